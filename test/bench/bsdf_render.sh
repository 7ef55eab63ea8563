#!/usr/bin/env bash
# Rendering through large tensor trees, heliodon against Radiance 6.1 in the
# same run (issue 17; docs/benchmarks/bsdf.md).  Not part of make check.
#
#   test/bench/bsdf_render.sh [PAIRS]
#   env: RADBIN (Radiance's bin, default /work/rad/inst/bin), RADLIB (its
#        lib), OUT (scratch folder, default build/tmp/bsdf_render), BUILD,
#        HELIODON_REF (for the measured fabric), CASES (default "fab iso fs2";
#        also "aniso": all three window groups the 128² tree),
#        RUNS (default "pict24 pict8ref trace"; also "pict8": pict24 at 8×8)
#
# Trees (made here, never committed: 50-90 MB each):
#   iso512r.xml   bench_bsdf -write 3 9 iso512r.xml R   (512² isotropic stand-in, 90 MB)
#   aniso128r.xml bench_bsdf -write 4 7 aniso128r.xml R (128² anisotropic stand-in, 31 MB)
#   fab512.xml    the measured route: heliodon's bsdf2ttree -p -g 9 -t 98 of the synthetic
#                 fabric's PAB-Opto interpolants ($HELIODON_REF/bsdf/measured/fabric_tb.sir
#                 and fabric_rf.sir, made by pabopto2bsdf): 512² isotropic, 50 MB, two blocks
#                 (Transmission Front, Reflection Back); about 100 s CPU and 1.4 GB to make
# Scenes: scenes/office (room.rad, windows.rad, skyglow.rad) with all three window
# groups one tree ("fab", "iso"), or the FS2 stand-in ("fs2": wg1 the 128²
# tree, wg2 + wg3 the 512² one); gensky 3 21 12 +s -a 51.5 -o 0 -m 0; view v2.
# Each run is made A (heliodon) B (Radiance) A B ...; user and system CPU,
# wall and peak RSS of the whole process (tree loading included) go to
# $OUT/times.txt with the load average at the start of each pair.
set -u
PAIRS=${1:-2}
BUILD=${BUILD:-build}
RADBIN=${RADBIN:-/work/rad/inst/bin}
RADLIB=${RADLIB:-$(dirname "$RADBIN")/lib}
REF=${HELIODON_REF:-../shared/ref}
OUT=${OUT:-$BUILD/tmp/bsdf_render}
CASES=${CASES:-fab iso fs2}
RUNS=${RUNS:-pict24 pict8ref trace}
HB=$(cd "$BUILD/bin" && pwd)
[ -x "$RADBIN/rpict" ] || { echo "no Radiance at $RADBIN"; exit 1; }
mkdir -p "$OUT"
cp scenes/office/room.rad scenes/office/windows.rad scenes/office/skyglow.rad "$OUT/"
S=$(cd "$OUT" && pwd)
M=$(cd "$REF/bsdf/measured" 2>/dev/null && pwd)
cd "$S" || exit 1
[ -f iso512r.xml ] || "$HB/../bench/bench_bsdf" -write 3 9 iso512r.xml R
[ -f aniso128r.xml ] || "$HB/../bench/bench_bsdf" -write 4 7 aniso128r.xml R
if [ ! -f fab512.xml ] && [ -n "$M" ]; then
    "$HB/bsdf2ttree" -p -g 9 -t 98 "$M/fabric_tb.sir" "$M/fabric_rf.sir" > fab512.xml.tmp 2>fab512.log &&
        mv fab512.xml.tmp fab512.xml
fi
"$RADBIN/gensky" 3 21 12 +s -a 51.5 -o 0 -m 0 > sky.rad
mat() {   # CASE -> materials of wg1..wg3
    case $1 in
    fs2) t1=aniso128r.xml t2=iso512r.xml ;;
    iso) t1=iso512r.xml t2=iso512r.xml ;;
    aniso) t1=aniso128r.xml t2=aniso128r.xml ;;
    fab) t1=fab512.xml t2=fab512.xml ;;
    esac
    printf 'void BSDF wg1_mat 6 0 %s 0 0 1 . 0 0\nvoid BSDF wg2_mat 6 0 %s 0 0 1 . 0 0\nvoid BSDF wg3_mat 6 0 %s 0 0 1 . 0 0\n' \
        "$t1" "$t2" "$t2"
}
V="-vta -vp 1.8 3.8 1.2 -vd 0 -1 0 -vu 0 0 1 -vh 180 -vv 180"
# ten rays from v2's point to points of wg2 (the view window)
awk 'BEGIN {srand(7); for (i = 0; i < 10; i++) {x = .2 + 3.2 * rand(); z = .9 + 1.1 * rand();
     dx = x - 1.8; dy = -3.8; dz = z - 1.2; l = sqrt(dx*dx + dy*dy + dz*dz);
     printf "1.8 3.8 1.2 %.6f %.6f %.6f\n", dx/l, dy/l, dz/l}}' > wg2.rays
cmd() {   # WHO RUN OCT -> command line
    local who=$1 run=$2 oct=$3 bin n=""
    if [ "$who" = A ]; then bin=$HB; n="-n ${NPROC:-1}"; else bin=$RADBIN; fi
    case $run in
    pict24) echo "$bin/rpict $n $V -x 24 -y 24 -ab 3 -ad 256 -ss 32 $oct" ;;
    pict8) echo "$bin/rpict $n $V -x 8 -y 8 -ab 3 -ad 256 -ss 32 $oct" ;;
    pict8ref) echo "$bin/rpict $n $V -x 8 -y 8 -ab 6 -ad 512 -ss 32 $oct" ;;
    trace) echo "$bin/rtrace $n -h -ab 2 -ad 256 -ss 32 $oct" ;;
    esac
}
echo "# $(date -u '+%F %T') heliodon $(cd "$OLDPWD" && git rev-parse --short HEAD 2>/dev/null) NPROC=${NPROC:-1}" >> times.txt
for c in $CASES; do
    [ "$c" = fab ] && [ ! -f fab512.xml ] && { echo "no fab512.xml (no $REF/bsdf/measured)"; continue; }
    mat "$c" > "mat_$c.rad"
    PATH=$RADBIN:$PATH RAYPATH=.:$RADLIB "$RADBIN/oconv" -f "mat_$c.rad" room.rad windows.rad sky.rad skyglow.rad > "r_$c.oct"
    PATH=$HB:$PATH "$HB/oconv" "mat_$c.rad" room.rad windows.rad sky.rad skyglow.rad > "h_$c.oct"
    for run in $RUNS; do
        for p in $(seq "$PAIRS"); do
            la=$(cut -d' ' -f1-3 /proc/loadavg)
            for who in A B; do
                oct=h_$c.oct; [ $who = B ] && oct=r_$c.oct
                in=/dev/null; [ $run = trace ] && in=wg2.rays
                RAYPATH=.:$RADLIB /usr/bin/time -f "%U %S %e %M" -o t.one $(cmd $who $run $oct) < $in > "out_${c}_${run}_$who.txt" 2>/dev/null
                echo "$c $run pair $p $who $(cat t.one) load $la" | tee -a times.txt
            done
        done
    done
done
# ratios A/B of CPU (user + system) per pair
awk '!/^#/ && NF >= 9 {k = $1 " " $2 " " $4; cpu = $6 + $7; if ($5 == "A") a[k] = cpu; else b[k] = cpu}
     END {for (k in a) if (b[k] > 0) printf "%s A/B cpu %.3f (%.1fx)\n", k, a[k] / b[k], b[k] / a[k]}' times.txt | sort
