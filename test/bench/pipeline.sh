#!/bin/bash
# Benchmark of the annual PM-CBDM pipeline (scenes/office, a case of pipeline/heliodon.mk): the stage times of a run.
# Usage: test/bench/pipeline.sh [RES] [MF] [PHOTONS] with a synthetic Izmir year from genwea;
# prints "stage seconds" lines and the total.  Defaults: 128 1 1m (the demo's size, a few minutes,
# so that make bench stays short); PIPELINE_BENCH_FULL=1 gives the issue's MF:6 256^2 run
# (256 6 2m, about 20 minutes on 2 busy cores).
# Environment: BUILD (build), NPROC (2), OUT (build/bench/pipeline_RES_mfMF), FENSUN (0: no
# backward refined sun DC for the masked pixels; use it at MF:6).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BUILD=${BUILD:-build}
case "$BUILD" in /*) BIN=$BUILD/bin ;; *) BIN=$ROOT/$BUILD/bin ;; esac
export PATH="$BIN:$PATH"
if [ "${PIPELINE_BENCH_FULL:-0}" = 1 ]; then d=(256 6 2m); else d=(128 1 1m); fi
RES=${1:-${d[0]}}; MF=${2:-${d[1]}}; PHOTONS=${3:-${d[2]}}; NPROC=${NPROC:-2}
OUT=${OUT:-$ROOT/$BUILD/bench/pipeline_${RES}_mf$MF}
mkdir -p "$OUT"
genwea -a 38.4 -o -27.1 -m -30 -e 25 -n Izmir "$OUT/izmir.wea"
t0=$(date +%s.%N)
make -s -C "$ROOT/scenes/office" WEATHER="$OUT/izmir.wea" CONFIG=glass VIEW=v1 RES="$RES" MF="$MF" \
     PHOTONS="$PHOTONS" NPROC="$NPROC" OUT="$OUT/run" ${FENSUN:+FENSUN=$FENSUN} > "$OUT/make.log" 2>&1
t1=$(date +%s.%N)
echo "# pipeline benchmark: RES=$RES MF=$MF PHOTONS=$PHOTONS NPROC=$NPROC, $(date -u '+%Y-%m-%d %H:%M UTC')"
cat "$OUT/run/timings.txt"
grep -h "sun patches\|daylight hours" "$OUT/make.log" | sed 's/^/# /' || true
awk -v a="$t0" -v b="$t1" 'BEGIN{printf "total %.1f\n", b - a}'
