#!/bin/bash
# MF sweep of the annual pipeline (issue 18 item 3, small size): the office (glass, view v1) for a
# synthetic Izmir year at sun MF 1, 2, 4, 6; per MF the stage times and, for a few hours, E_v and
# DGP against heliodon's backward rendering with the EXACT sun position (gendaylit with its sun,
# rpict -ab 4).  Usage: test/bench/pipeline_mf.sh [RES] [PHOTONS] [FENSUN]  (defaults 64 1m 1).
# REUSE=1 evaluates the runs already in OUT again.
# Prints "MF total_s sun_patches stage=wall/cpu... | hour: dEv% dDGP ..." lines (CPU seconds per
# stage from pipeline/stage.sh: the figure to compare on a loaded machine).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BUILD=${BUILD:-build}
case "$BUILD" in /*) BIN=$BUILD/bin ;; *) BIN=$ROOT/$BUILD/bin ;; esac
export PATH="$BIN:$PATH"
RES=${1:-64}; PHOTONS=${2:-1m}; FENSUN=${3:-1}; NPROC=${NPROC:-2}
OUT=${OUT:-$ROOT/$BUILD/bench/pipeline_mf_$RES}
mkdir -p "$OUT"
O=$ROOT/scenes/office
genwea -a 38.4 -o -27.1 -m -30 -e 25 -n Izmir "$OUT/izmir.wea"
# hours: Mar 21 10:30, Jun 21 15:30, Sep 21 9:30, Dec 21 12:30 (hour of year = 24 (day - 1) + hour)
HOURS="3 21 10.5;6 21 15.5;9 21 9.5;12 21 12.5"
echo "# pipeline MF sweep: office glass v1, ${RES}x$RES, $PHOTONS photons, FENSUN=$FENSUN, NPROC=$NPROC, $(date -u '+%Y-%m-%d %H:%M UTC'), load $(cut -d' ' -f1-3 /proc/loadavg)"
# references with the exact sun
IFS=';' read -ra HS <<< "$HOURS"
for h in "${HS[@]}"; do
    set -- $h
    read -r dni dhi <<< "$(awk -v m="$1" -v d="$2" -v h="$3" 'NR > 6 && $1 == m && $2 == d && $3 + 0 == h + 0 {print $4, $5}' "$OUT/izmir.wea")"
    tag=$1_$2_$3
    if [ ! -s "$OUT/ref_$tag.hdr" ]; then
        gendaylit "$1" "$2" "$3" -a 38.4 -o -27.1 -m -30 -W "$dni" "$dhi" > "$OUT/sky_$tag.rad"
        (cd "$O" && oconv mat_glass.rad room.rad windows.rad "$OUT/sky_$tag.rad" skyglow.rad > "$OUT/ref_$tag.oct" &&
            rpict -vf v1.vf -x "$RES" -y "$RES" -ps 1 -pj 0 -dj 0 -ab 4 -ad 1024 -as 0 -aa 0 -lw 1e-5 -n "$NPROC" \
            "$OUT/ref_$tag.oct" > "$OUT/ref_$tag.hdr")
    fi
    echo "$tag $(evalglare -vta -vh 180 -vv 180 "$OUT/ref_$tag.hdr" | awk '{print $2}') $(evalglare -V -vta -vh 180 -vv 180 "$OUT/ref_$tag.hdr")" > "$OUT/refval_$tag.txt"
done
for MF in 1 2 4 6; do
    R=$OUT/run_mf$MF
    [ "${REUSE:-0}" = 1 ] && [ -s "$R/v1/annual.csv" ] && [ -s "$R.t" ] || {
    rm -rf "$R"
    t0=$(date +%s.%N)
    make -s -C "$O" WEATHER="$OUT/izmir.wea" CONFIG=glass VIEW=v1 RES="$RES" MF="$MF" PHOTONS="$PHOTONS" NPROC="$NPROC" \
        FENSUN="$FENSUN" OUT="$R" > "$R.log" 2>&1
    t1=$(date +%s.%N)
    echo "$t0 $t1 $(cut -d' ' -f1 /proc/loadavg)" > "$R.t"; }
    read -r t0 t1 HD_LOAD < "$R.t"
    export HD_LOAD
    ns=$(grep -o '[0-9]* sun patches of' "$R.log" | head -1 | awk '{print $1}')
    # stage lines "name wall cpu cpu_seconds" (pipeline/stage.sh): wall and CPU per stage and in all
    line=$(awk -v mf="$MF" -v a="$t0" -v b="$t1" -v ns="$ns" '{s = s " " $1 "=" $2 "/" $4; c += $4}
        END {printf "MF:%s total %.1f s (stages wall/CPU s; CPU %.1f s, load %s), %s suns;%s", mf, b - a, c, ENVIRON["HD_LOAD"], ns, s}' "$R/timings.txt")
    errs=""
    for h in "${HS[@]}"; do
        set -- $h
        tag=$1_$2_$3
        read -r _ rdgp rev < "$OUT/refval_$tag.txt"
        jd=$(awk -v m="$1" -v d="$2" 'BEGIN {split("31 28 31 30 31 30 31 31 30 31 30 31", n, " "); for (i = 1; i < m; i++) d += n[i]; print d}')
        hoy=$(awk -v j="$jd" -v h="$3" 'BEGIN {printf "%.1f", 24 * (j - 1) + h}')
        read -r ev dgp <<< "$(awk -F, -v t="$hoy" 'NR > 1 && $1 + 0 == t + 0 {print $2, $3}' "$R/v1/annual.csv")"
        errs="$errs $(awk -v t="$tag" -v a="$ev" -v b="$rev" -v c="$dgp" -v d="$rdgp" 'BEGIN {printf "%s:Ev%+.1f%%,DGP%+.3f", t, 100 * (a - b) / b, c - d}')"
    done
    echo "$line |$errs"
done
