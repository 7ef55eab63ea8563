#!/usr/bin/env bash
# genBSDF benchmark: generation time of the CFS1 slat system (the paper's
# deflecting blinds, scenes/cfs) as an anisotropic tensor tree at
# -t4 6 -c 10000 on 2 threads (backward side, genBSDF's default), plus a
# Klems run at -c 2000 from both sides.  Radiance genBSDF is timed in the
# same run when it is on PATH or in /work/radiance-build/bin.
# Usage: BUILD=build test/bench/bench_genbsdf.sh [C] [TREE]
set -u
BUILD=${BUILD:-build}
GB=$BUILD/bin/genBSDF
C=${1:-10000}
TREE=${2:-6}
D=$(mktemp -d)
trap 'rm -rf "$D"' EXIT
[ -x "$GB" ] || { echo "bench_genbsdf: $GB not built"; exit 1; }
cd scenes/cfs || exit 1
G=../../$GB
TM="/usr/bin/time -f %e_s_wall_%U_s_user_%S_s_sys_%MkB_maxrss -o $D/time"
$TM $G -n 2 -c "$C" -t4 "$TREE" -geom millimeter -dim -50 50 -50 50 -12.01 0 slat.mat cfs1.rad > "$D/t.xml" || exit 1
rays=$(( (1 << (2 * TREE)) * C ))
echo "genBSDF CFS1 -t4 $TREE -c $C -n 2 (backward): $(tr _ ' ' < "$D/time"), $rays incident rays, tree file $(wc -c < "$D/t.xml") bytes"
$TM $G -n 2 -c 2000 +f +b -geom millimeter -dim -50 50 -50 50 -12.01 0 slat.mat cfs1.rad > "$D/k.xml" || exit 1
echo "genBSDF CFS1 Klems -c 2000 +f +b -n 2: $(tr _ ' ' < "$D/time")"
echo "load average: $(cut -d' ' -f1-3 /proc/loadavg)"
RG=$(command -v genBSDF 2>/dev/null | grep -v "$BUILD" || true)
[ -z "$RG" ] && [ -x /work/radiance-build/bin/genBSDF ] && RG=/work/radiance-build/bin/genBSDF
if [ -n "$RG" ]; then
    t0=$(date +%s.%N)
    "$RG" -n 2 -c "$C" -t4 "$TREE" -geom millimeter -dim -50 50 -50 50 -12.01 0 slat.mat cfs1.rad > "$D/r.xml"
    t1=$(date +%s.%N)
    echo "Radiance genBSDF ($RG) same options: $(echo "$t1 - $t0" | bc) s wall"
else
    echo "Radiance genBSDF: not available (not on PATH, not in /work/radiance-build/bin)"
fi
