#!/bin/bash
# MF sweep of the annual pipeline (issue 18 item 3): the office (view v1) for a synthetic Izmir year at
# sun MF 1, 2, 4, 6; per MF the stage times and, for four hours, E_v and DGP against heliodon's backward
# rendering with the EXACT sun position (gendaylit with its sun, rpict -aa 0).
#   test/bench/pipeline_mf.sh [RES] [PHOTONS] [FENSUN]  (defaults 64 1m 1)
# Environment:
#   CONFIG   glass (default: the window groups glass) or fs1 (FS1 data-driven: the CFS1 / CFS2 tensor
#            trees of CFSDIR, default BUILD/tmp/cfs_trees, made there by scenes/cfs's Makefile when
#            missing); every other pipeline variable at its default (sky DC, refined sun DC FENSUN_OPTS)
#   MFS      the MFs to run ("1 2 4 6")
#   SHARE_MF 1: the stages that do not depend on MF (preflight, scene, sky and fenestration sky DCs,
#            mask, ground points) are made by the first MF's run and hard-linked into the later runs'
#            folders with their times, so make does not run them again; their timings lines are
#            copied too (marked "=shared"), so each MF's CPU total still counts them; SHARE_MF_FROM=MF
#            takes them from that MF's finished run of an earlier invocation
#   MAPS_FROM another sweep's OUT (e.g. the same case at another RES): its weather, preflight, scene,
#            suns and photon map of each MF (none depends on RES) are hard-linked with their times
#            instead of made again; their gensuns and mkpmap timings lines are copied (marked "=linked").
#            Do not start a second invocation on the same OUT before the first has made its weather file.
#   REF_OPTS rpict options of the reference (-ab 4 -ad 1024 -as 0 -aa 0 -lw 1e-5)
#   REF_RES  the references' resolution (RES; a smaller one when CPU is short: E_v and DGP of the runs'
#            RES pictures are then compared with a reference of REF_RES x REF_RES rays)
#   REF_SEEDS seeds of the reference renderings (1, rpict's default); with two or more, the reference is their mean
#            picture's E_v and DGP and the spread over seeds is printed (the reference's noise)
#   REUSE    1: evaluate the runs already in OUT again
#   STEP     refs: the references only; runs: the runs only (hours without a reference not compared)
#   CHART    1: write docs/benchmarks/sweep_mf_CONFIG_RES.tsv/.svg (svgchart of sweep_lib.sh)
# Prints "MF total_s sun_patches stage=wall/cpu... | hour: dEv% dDGP ..." lines (CPU seconds per
# stage from pipeline/stage.sh: the figure to compare on a loaded machine).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BUILD=${BUILD:-build}
case "$BUILD" in /*) BIN=$BUILD/bin; BD=$BUILD ;; *) BIN=$ROOT/$BUILD/bin; BD=$ROOT/$BUILD ;; esac
export PATH="$BIN:$PATH"
RES=${1:-64}; PHOTONS=${2:-1m}; FENSUN=${3:-1}; NPROC=${NPROC:-2}
CONFIG=${CONFIG:-glass}; MFS=${MFS:-1 2 4 6}
REF_OPTS=${REF_OPTS:--ab 4 -ad 1024 -as 0 -aa 0 -lw 1e-5}; REF_SEEDS=${REF_SEEDS:-1}; REF_RES=${REF_RES:-$RES}
OUT=${OUT:-$BD/bench/pipeline_mf_$([ "$CONFIG" = glass ] || echo "${CONFIG}_")$RES}
mkdir -p "$OUT"
OUT=$(cd "$OUT" && pwd)
O=$ROOT/scenes/office
case $CONFIG in
glass) cfg=(CONFIG=glass) ;;
fs1)
    CFSDIR=${CFSDIR:-$BD/tmp/cfs_trees}
    if [ ! -s "$CFSDIR/cfs1_ttree.xml" ] || [ ! -s "$CFSDIR/cfs2_ttree.xml" ]; then
        mkdir -p "$CFSDIR" && cp -n "$ROOT"/scenes/cfs/* "$CFSDIR"/
        nice make -s -C "$CFSDIR" GENBSDF="$BIN/genBSDF" NPROC="$NPROC" cfs1_ttree.xml cfs2_ttree.xml > "$OUT/trees.log" 2>&1
    fi
    CFSDIR=$(cd "$CFSDIR" && pwd)
    export RAYPATH=".:$CFSDIR"
    cfg=(CONFIG=fs1 CFSDIR="$CFSDIR") ;;
*) echo "pipeline_mf.sh: CONFIG='$CONFIG': expected glass or fs1" >&2; exit 1 ;;
esac
# with MAPS_FROM the weather is the other sweep's, with its time (older than the linked preflight)
if [ -n "${MAPS_FROM:-}" ]; then cp -p "$MAPS_FROM/izmir.wea" "$OUT/izmir.wea.tmp" && mv -f "$OUT/izmir.wea.tmp" "$OUT/izmir.wea"; fi
[ -s "$OUT/izmir.wea" ] || genwea -a 38.4 -o -27.1 -m -30 -e 25 -n Izmir "$OUT/izmir.wea"
# hours: Mar 21 10:30, Jun 21 15:30, Sep 21 9:30, Dec 21 12:30 (hour of year = 24 (day - 1) + hour)
HOURS="3 21 10.5;6 21 15.5;9 21 9.5;12 21 12.5"
echo "# pipeline MF sweep: office $CONFIG v1, ${RES}x$RES (references ${REF_RES}x$REF_RES, $REF_OPTS, seeds $REF_SEEDS), $PHOTONS photons, FENSUN=$FENSUN, NPROC=$NPROC, $(date -u '+%Y-%m-%d %H:%M UTC'), load $(cut -d' ' -f1-3 /proc/loadavg)"
# references with the exact sun: one rendering per seed; E_v and DGP of their mean picture
IFS=';' read -ra HS <<< "$HOURS"
for h in "${HS[@]}"; do
    [ "${STEP:-}" = runs ] && break
    set -- $h
    read -r dni dhi <<< "$(awk -v m="$1" -v d="$2" -v h="$3" 'NR > 6 && $1 == m && $2 == d && $3 + 0 == h + 0 {print $4, $5}' "$OUT/izmir.wea")"
    tag=$1_$2_$3
    pics=(); rs=$([ "$REF_RES" = "$RES" ] || echo "_r$REF_RES")
    for s in $REF_SEEDS; do
        p=$OUT/ref_$tag$rs$([ "$s" = 1 ] || echo "_s$s").hdr
        pics+=("$p")
        [ -s "$p" ] && continue
        [ -s "$OUT/sky_$tag.rad" ] || gendaylit "$1" "$2" "$3" -a 38.4 -o -27.1 -m -30 -W "$dni" "$dhi" > "$OUT/sky_$tag.rad"
        (cd "$O" && oconv "mat_$CONFIG.rad" room.rad windows.rad "$OUT/sky_$tag.rad" skyglow.rad > "$OUT/ref_$tag.oct" &&
            /usr/bin/time -f "%U %S" -o "$p.cpu" rpict -vf v1.vf -x "$REF_RES" -y "$REF_RES" -ps 1 -pj 0 -dj 0 $REF_OPTS -seed "$s" -n "$NPROC" \
            "$OUT/ref_$tag.oct" > "$p.tmp" && mv -f "$p.tmp" "$p")
    done
    vals=""
    for p in "${pics[@]}"; do vals="$vals $(evalglare -vta -vh 180 -vv 180 "$p" | awk '{print $2}') $(evalglare -V -vta -vh 180 -vv 180 "$p")"; done
    if [ ${#pics[@]} -gt 1 ]; then
        pcomb $(for p in "${pics[@]}"; do printf -- '-s %s %s ' "$(awk -v n=${#pics[@]} 'BEGIN {print 1 / n}')" "$p"; done) > "$OUT/refmean_$tag$rs.hdr.tmp" && mv -f "$OUT/refmean_$tag$rs.hdr.tmp" "$OUT/refmean_$tag$rs.hdr"
        p=$OUT/refmean_$tag$rs.hdr
    fi
    echo "$tag $(evalglare -vta -vh 180 -vv 180 "$p" | awk '{print $2}') $(evalglare -V -vta -vh 180 -vv 180 "$p") |$vals" > "$OUT/refval_$tag.txt"
    awk '{n = 0; for (i = 5; i < NF; i += 2) {g[++n] = $i; e[n] = $(i + 1)}
        if (n > 1) {for (i = 1; i <= n; i++) {sg += g[i]; se += e[i]} mg = sg / n; me = se / n
            for (i = 1; i <= n; i++) {vg += (g[i] - mg) ^ 2; ve += (e[i] - me) ^ 2}
            printf "# reference %s: DGP %.3f E_v %.0f lx over %d seeds: SD of one seed DGP %.4f, E_v %.2f %%\n", $1, mg, me, n, sqrt(vg / (n - 1)), 100 * sqrt(ve / (n - 1)) / me}
        else printf "# reference %s: DGP %.3f E_v %.0f lx\n", $1, $2, $3}' "$OUT/refval_$tag.txt"
done
[ "${STEP:-}" = refs ] && exit 0
# the stages that do not depend on MF (SHARE=1): files and folders linked from the first run
SHARED="preflight.ok mat.rad scene sky.oct skyg.oct mask.oct groundpts.txt v1/mask.hdr v1/dcsky v1/dcfen"
SHARED_T="mask_v1 rcontrib_sky_v1 rcontrib_fen_v1"
first=${SHARE_MF_FROM:+$OUT/run_mf$SHARE_MF_FROM}
TSV=$OUT/sweep.tsv; : > "$TSV"
for MF in $MFS; do
    R=$OUT/run_mf$MF
    [ "${REUSE:-0}" = 1 ] && [ -s "$R/v1/annual.csv" ] && [ -s "$R.t" ] || {
    rm -rf "$R"; mkdir -p "$R/v1"; : > "$R/timings.txt"
    if [ "${SHARE_MF:-0}" = 1 ] && [ -n "$first" ]; then
        for f in $SHARED; do [ -e "$first/$f" ] && cp -al "$first/$f" "$R/$f"; done
        for s in $SHARED_T; do awk -v s="$s" '$1 == s {$1 = $1 "=shared"; print}' "$first/timings.txt"; done >> "$R/timings.txt"
    fi
    M=${MAPS_FROM:-}/run_mf$MF
    if [ -n "${MAPS_FROM:-}" ] && [ -s "$M/sun.cpm" ]; then
        for f in preflight.ok mat.rad scene suns.rad mods.txt sun.oct sun.cpm; do [ -e "$R/$f" ] || cp -al "$M/$f" "$R/$f"; done
        awk '$1 == "gensuns" || $1 == "mkpmap" {$1 = $1 "=linked"; print}' "$M/timings.txt" >> "$R/timings.txt"
    fi
    t0=$(date +%s.%N)
    make -s -C "$O" WEATHER="$OUT/izmir.wea" "${cfg[@]}" VIEW=v1 RES="$RES" MF="$MF" PHOTONS="$PHOTONS" NPROC="$NPROC" \
        FENSUN="$FENSUN" OUT="$R" > "$R.log" 2>&1
    t1=$(date +%s.%N)
    echo "$t0 $t1 $(cut -d' ' -f1 /proc/loadavg)" > "$R.t"; }
    [ -n "$first" ] || first=$R
    read -r t0 t1 HD_LOAD < "$R.t"
    export HD_LOAD
    ns=$(wc -l < "$R/mods.txt")   # the visited sun patches (gensuns -M)
    # stage lines "name wall cpu cpu_seconds" (pipeline/stage.sh): wall and CPU per stage and in all
    # (a stage made again although shared counts once, as made: "NAME=shared" is skipped when NAME is there)
    line=$(awk 'NR == FNR {ran[$1]; next} {n = $1; sub(/=shared$/, "", n)} $1 != n && (n in ran) {next} 1' "$R/timings.txt" "$R/timings.txt" |
        awk -v mf="$MF" -v a="$t0" -v b="$t1" -v ns="$ns" '{s = s " " $1 "=" $2 "/" $4; c += $4}
        END {printf "MF:%s total %.1f s (stages wall/CPU s; CPU %.1f s, load %s), %s suns;%s", mf, b - a, c, ENVIRON["HD_LOAD"], ns, s}')
    errs=""; se=0; sg=0; me=0; mg=0
    for h in "${HS[@]}"; do
        set -- $h
        tag=$1_$2_$3
        [ -s "$OUT/refval_$tag.txt" ] || continue
        read -r _ rdgp rev _ < "$OUT/refval_$tag.txt"
        jd=$(awk -v m="$1" -v d="$2" 'BEGIN {split("31 28 31 30 31 30 31 31 30 31 30 31", n, " "); for (i = 1; i < m; i++) d += n[i]; print d}')
        hoy=$(awk -v j="$jd" -v h="$3" 'BEGIN {printf "%.1f", 24 * (j - 1) + h}')
        read -r ev dgp <<< "$(awk -F, -v t="$hoy" 'NR > 1 && $1 + 0 == t + 0 {print $2, $3}' "$R/v1/annual.csv")"
        errs="$errs $(awk -v t="$tag" -v a="$ev" -v b="$rev" -v c="$dgp" -v d="$rdgp" 'BEGIN {printf "%s:Ev%+.1f%%,DGP%+.3f", t, 100 * (a - b) / b, c - d}')"
        read -r se sg me mg <<< "$(awk -v a="$ev" -v b="$rev" -v c="$dgp" -v d="$rdgp" -v se="$se" -v sg="$sg" -v me="$me" -v mg="$mg" 'BEGIN {
            e = 100 * (a - b) / b; e = e < 0 ? -e : e; g = 100 * (c - d); g = g < 0 ? -g : g
            print se + e, sg + g, (e > me ? e : me), (g > mg ? g : mg)}')"
    done
    printf 'mean |dE_v| %%\t%s\t%.2f\nmax |dE_v| %%\t%s\t%.2f\nmean |dDGP| x100\t%s\t%.3f\nmax |dDGP| x100\t%s\t%.3f\n' \
        "$MF" "$(awk -v s="$se" -v n=${#HS[@]} 'BEGIN {print s / n}')" "$MF" "$me" "$MF" "$(awk -v s="$sg" -v n=${#HS[@]} 'BEGIN {print s / n}')" "$MF" "$mg" >> "$TSV"
    echo "$line |$errs"
done
if [ "${CHART:-0}" = 1 ]; then
    cd "$ROOT" && . test/bench/sweep_lib.sh
    name=sweep_mf_${CONFIG}_$RES
    sort "$TSV" > "$DOCS/$name.tsv"
    svgchart "$DOCS/$name.tsv" "$DOCS/$name.svg" "Office $CONFIG v1 ${RES}², $PHOTONS photons: error vs backward (exact sun), ${#HS[@]} hours" "sun MF" "error (E_v %, DGP x 100)"
    echo "wrote $DOCS/$name.tsv and $DOCS/$name.svg"
fi
