#!/bin/bash
# The paper-scale annual run of issue 18 item 2: office FS1 data-driven (CFS1 tensor tree on wg1, CFS2
# on wg2 + wg3), views v1 and v2 in one run (one photon map, one set of suns), a whole year, Reinhart
# MF:6, 1024², 4·10⁹ contribution photons, 2 threads; the sky part by the three-phase split with the
# Klems XMLs of scenes/cfs (SKYMETHOD=3pm, as the estimate in docs/benchmarks/pipeline.md).  Records per stage wall, CPU, peak RSS, disk
# added and the run folder's peak (OUT/run/timings.txt, pipeline/stage.sh) and prints them as a table
# with the totals, the run's elapsed time, its largest RSS and its peak disk.
#   test/bench/paper_scale.sh                      the paper's run (hours: a quiet machine, ≥ 40 GB free)
#   RES=16 MF=1 PHOTONS=20k DAYS=3 test/bench/paper_scale.sh     a tiny check of the script
# Environment: BUILD (build), OUT (build/bench/paper_scale), RES (1024), MF (6), PHOTONS (4g), NPROC (2),
# WEATHER (an EPW or WEA; default a synthetic Izmir year from genwea), DAYS (keep only the first DAYS
# days of the weather: tiny checks), CFSDIR (where cfs1_ttree.xml and cfs2_ttree.xml are; default
# BUILD/tmp/cfs_trees, made there by scenes/cfs's Makefile when missing), MAKEFLAGS_EXTRA (more make
# variables, e.g. "FENSUN_OPTS=-ab 0"), SKYMETHOD (3pm; dc: the sky DC traced through the trees).  A killed run started again with the same settings continues
# from its finished stages (the pipeline is resumable); the table covers the stages of all attempts.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BUILD=${BUILD:-build}
case "$BUILD" in /*) BIN=$BUILD/bin; BD=$BUILD ;; *) BIN=$ROOT/$BUILD/bin; BD=$ROOT/$BUILD ;; esac
export PATH="$BIN:$PATH"
RES=${RES:-1024} MF=${MF:-6} PHOTONS=${PHOTONS:-4g} NPROC=${NPROC:-2}
OUT=${OUT:-$BD/bench/paper_scale}
CFSDIR=${CFSDIR:-$BD/tmp/cfs_trees}
mkdir -p "$OUT"
OUT=$(cd "$OUT" && pwd)
if [ ! -s "$CFSDIR/cfs1_ttree.xml" ] || [ ! -s "$CFSDIR/cfs2_ttree.xml" ]; then
    mkdir -p "$CFSDIR" && cp -n "$ROOT"/scenes/cfs/* "$CFSDIR"/
    t0=$(date +%s)
    nice make -s -C "$CFSDIR" GENBSDF="$BIN/genBSDF" NPROC="$NPROC" cfs1_ttree.xml cfs2_ttree.xml > "$OUT/trees.log" 2>&1
    echo "# tensor trees made in $CFSDIR: $(( $(date +%s) - t0 )) s (not part of the run)"
fi
if [ -z "${WEATHER:-}" ]; then
    WEATHER=$OUT/izmir.wea
    [ -s "$WEATHER" ] || genwea -a 38.4 -o -27.1 -m -30 -e 25 -n Izmir "$WEATHER"
fi
if [ -n "${DAYS:-}" ]; then   # the header and the records of the first DAYS days
    awk -v d="$DAYS" 'NF < 5 || $1 !~ /^[0-9]+$/ {print; next} {k = $1 * 100 + $2; if (!(k in s)) {s[k]; n++}
        if (n <= d) print}' "$WEATHER" > "$OUT/weather_${DAYS}d.wea"
    WEATHER=$OUT/weather_${DAYS}d.wea
fi
read -r -a extra <<< "${MAKEFLAGS_EXTRA:-}"
SKYMETHOD=${SKYMETHOD:-3pm}
sky=(SKYMETHOD="$SKYMETHOD")
[ "$SKYMETHOD" = 3pm ] && sky+=(KLEMS_WG1="$ROOT/scenes/cfs/cfs1_klems.xml" KLEMS_WG2="$ROOT/scenes/cfs/cfs2_klems.xml")
cmd=(make -C "$ROOT/scenes/office" CONFIG=fs1 CFSDIR="$CFSDIR" VIEWS="v1.vf v2.vf" WEATHER="$WEATHER"
     RES="$RES" MF="$MF" PHOTONS="$PHOTONS" NPROC="$NPROC" OUT="$OUT/run" "${sky[@]}" "${extra[@]}")
echo "# paper-scale run: $(date -u '+%Y-%m-%d %H:%M UTC'), load $(cut -d' ' -f1-3 /proc/loadavg), $(nproc) cores"
echo "# $(printf '%q ' "${cmd[@]}")"
l0=$(cut -d' ' -f1 /proc/loadavg)
t0=$(date +%s.%N)
if ! "${cmd[@]}" > "$OUT/make.log" 2>&1; then
    echo "paper_scale: the run failed; last lines of $OUT/make.log:" >&2
    tail -5 "$OUT/make.log" >&2
    exit 1
fi
t1=$(date +%s.%N)
echo "# finished $(date -u '+%Y-%m-%d %H:%M UTC'), load at start $l0, at end $(cut -d' ' -f1 /proc/loadavg)"
grep -h "sun patches" "$OUT/make.log" | sed 's/^/# /' | head -1 || true
# the table: every stage, then the stages summed by kind (the name up to the view or piece), totals
awk -v a="$t0" -v b="$t1" '
    function kind(n) { sub(/_(v1|v2|grid)(_.*)?$/, "", n); sub(/_h?[0-9]+$/, "", n); return n }
    NF >= 2 { printf "%-28s %9.1f %9.1f %9s %9s %9s\n", $1, $2, $4, $6, $8, $10
              k = kind($1); if (!(k in w)) ord[++nk] = k; w[k] += $2; c[k] += $4
              if ($6 != "-" && $6 + 0 > r[k]) r[k] = $6 + 0; d[k] += $8
              W += $2; C += $4; if ($6 != "-" && $6 + 0 > R) R = $6 + 0; if ($10 + 0 > P) P = $10 + 0 }
    BEGIN { printf "%-28s %9s %9s %9s %9s %9s\n", "stage", "wall s", "CPU s", "RSS MB", "disk MB", "peak MB" }
    END { print ""; printf "%-28s %9s %9s %9s %9s\n", "by kind", "wall s", "CPU s", "RSS MB", "disk MB"
          for (i = 1; i <= nk; i++) printf "%-28s %9.1f %9.1f %9.1f %9.1f\n", ord[i], w[ord[i]], c[ord[i]], r[ord[i]], d[ord[i]]
          print ""; printf "stages: wall %.1f s, CPU %.1f s (%.2f h on 2 cores if all parallel); largest RSS %.1f MB; peak disk %.1f MB\n", W, C, C / 7200, R, P
          printf "run elapsed (make): %.1f s = %.2f h\n", b - a, (b - a) / 3600 }' "$OUT/run/timings.txt"
