#!/bin/bash
# Equal-error speed comparison of heliodon's backward renderer with
# Radiance 6.1, 512 x 512 angular fisheye pictures of the box and office
# scenes (issue #3).  Not part of `make check` (CPU-minutes).  Usage, from
# the project root:
#   RADIANCE_BIN=/path/to/radiance/bin PATH=build/bin:$PATH \
#       bash test/bench/bench_trace_speed.sh [outdir]
#
# Method (docs/benchmarks/trace.md):
#  * The pixels: the 512 x 512 fisheye's view rays (vwrays), every ROWSTEP-th
#    row (default 16: 32 rows = 16384 pixels, an even sample of the picture);
#    rpict -ps 1 -aa 0 computes exactly these rays per pixel, so the time per
#    512² picture is the time for the sample × ROWSTEP (both programs are
#    driven by rtrace on the same rays: no picture-file overhead counted).
#  * The truth: heliodon at the sample pixels with many samples and no
#    ray-weight truncation (-ab 10 -ad $REFAD -lw 1e-5 -lr -20: Russian
#    roulette, unbiased), checked on every 8th sample pixel against Radiance
#    rtrace with the same settings and -as 0 (the means over lit pixels must
#    agree within their noise).
#  * Radiance at the settings of the shared references (box A2: -ab 6
#    -ad 1024 -lw 1e-4 -lr 12 -as 0 -aa 0; office B1: -ad 512) -> its error.
#    Also Radiance with -lr -12 (Russian roulette instead of the hard -lw
#    cut-off: unbiased, its best option at these settings).
#  * heliodon at -ab 8 -lw 1e-4 -lr -12 (Russian roulette, unbiased) with
#    -ad in ADS: error and time of each; the first -ad whose error does not
#    exceed Radiance's is "equal error".
#  * Error = median over lit pixels (truth > 1 cd/m²) of |pixel/truth - 1|,
#    and the bias of the mean over lit pixels.  Times are CPU (user+sys)
#    seconds of all threads / processes, and wall seconds (-n $N).
set -u
REF=${HELIODON_REF:-../shared/ref}
O=${1:-build/bench-trace-speed}
mkdir -p "$O"
O=$(cd "$O" && pwd)
REF=$(cd "$REF" && pwd)
N=${NTHREADS:-2}
ROWSTEP=${ROWSTEP:-32}
REFAD=${REFAD:-2048}
ADS=${ADS:-"64 96 121 144 169 196 256 384 512"}   # -ad n² levels: a fine ladder near equal error
RB=${RADIANCE_BIN:-}
if [ -z "$RB" ] || [ ! -x "$RB/rtrace" ]; then echo "bench_trace_speed: RADIANCE_BIN not set: skipped"; exit 0; fi
export RAYPATH=.:$RB/../lib
export LC_ALL=C

cpu() { awk '{print $1+$2, $3}' "$1"; }   # user+sys, wall from time -f "%U %S %e"
lum() { awk '{print 179*(.265*$1+.670*$2+.065*$3)}' "$1"; }
# err truth.lum test.lum -> "median|rel| meanbias nlit"
err() {
    paste "$1" "$2" | awk '$1>1 {r=$2/$1-1; a+=$1; b+=$2; n++; print (r<0?-r:r)} END{printf "%.6g %d\n", (b-a)/a, n > "/dev/stderr"}' \
        2> "$O/err.tmp" | sort -g | awk '{v[NR]=$1} END{printf "%.4f ", v[int(NR/2)+1]}'
    cat "$O/err.tmp"
}

run_scene() {   # name dir view "scene files (relative to dir)" "radiance settings"
    local name=$1 dir=$2 vf=$3 files=$4 rset=$5
    local P="$O/$name"
    (cd "$dir" && "$RB/oconv" $files > "$P.oct") || { echo "$name: oconv failed"; return; }
    "$RB/vwrays" -fa -x 512 -y 512 -vf "$dir/$vf" |
        awk -v s="$ROWSTEP" 'int((NR-1)/512) % s == int(s/2)' > "$P.rays"
    local npx; npx=$(wc -l < "$P.rays")
    awk 'NR % 8 == 1' "$P.rays" > "$P.rays8"
    echo "== $name: $npx pixels of 512x512 (every ${ROWSTEP}th row), $N threads"
    # truth (heliodon, converged) and its check against Radiance; with
    # REUSE=1 the truth and Radiance results of an earlier run in $O are kept
    [ "${REUSE:-0}" = 1 ] && [ -s "$P.rtruth" ] && [ -s "$P.rad" ] || {
    (cd "$dir" && /usr/bin/time -f "%U %S %e" -o "$P.t_truth" rtrace -h -n $N -ab 10 -ad $REFAD -lw 1e-5 -lr -20 -dj 0 -st 0 \
        $files < "$P.rays" > "$P.truth")
    (cd "$dir" && /usr/bin/time -f "%U %S %e" -o "$P.t_rtruth" "$RB/rtrace" -h -n $N -ab 10 -ad $REFAD -as 0 -aa 0 -lw 1e-5 -lr -20 \
        -dj 0 -st 0 "$P.oct" < "$P.rays8" > "$P.rtruth")
    (cd "$dir" && /usr/bin/time -f "%U %S %e" -o "$P.t_rad" "$RB/rtrace" -h -n $N $rset "$P.oct" < "$P.rays" > "$P.rad")
    (cd "$dir" && /usr/bin/time -f "%U %S %e" -o "$P.t_radrr" "$RB/rtrace" -h -n $N ${rset/-lr 12/-lr -12} "$P.oct" < "$P.rays" > "$P.radrr")
    }
    lum "$P.truth" > "$P.truth.l"
    lum "$P.rtruth" > "$P.rtruth.l"
    awk 'NR % 8 == 1' "$P.truth.l" > "$P.truth8.l"
    echo "truth: heliodon -ab 10 -ad $REFAD -lw 1e-5 -lr -20 ($(cpu "$P.t_truth") s CPU/wall);" \
         "vs Radiance -ab 10 -ad $REFAD -lw 1e-5 -lr -20 -as 0 on every 8th pixel: median|rel| mean-bias nlit = $(err "$P.truth8.l" "$P.rtruth.l")"
    # Radiance at the reference settings
    lum "$P.rad" > "$P.rad.l"
    set -- $(cpu "$P.t_rad")
    local rcpu=$1 rwall=$2
    local rerr; rerr=$(err "$P.truth.l" "$P.rad.l")
    printf "Radiance  %-34s error(median|rel| bias nlit) %s  CPU %.1f s wall %.1f s -> per 512^2 picture CPU %.0f s\n" \
        "$rset" "$rerr" "$rcpu" "$rwall" "$(echo "$rcpu * $ROWSTEP" | bc -l)"
    lum "$P.radrr" > "$P.radrr.l"
    set -- $(cpu "$P.t_radrr")
    local rrerr; rrerr=$(err "$P.truth.l" "$P.radrr.l")
    printf "Radiance  %-34s error(median|rel| bias nlit) %s  CPU %.1f s wall %.1f s -> per 512^2 picture CPU %.0f s\n" \
        "${rset/-lr 12/-lr -12}" "$rrerr" "$1" "$2" "$(echo "$1 * $ROWSTEP" | bc -l)"
    # heliodon at exactly Radiance's reference settings (same -lw cut-off)
    (cd "$dir" && /usr/bin/time -f "%U %S %e" -o "$P.t_hsame" rtrace -h -n $N $rset $files < "$P.rays" > "$P.hsame")
    lum "$P.hsame" > "$P.hsame.l"
    local rr1=$1 rr2=$2
    set -- $(cpu "$P.t_hsame")
    local se; se=$(err "$P.truth.l" "$P.hsame.l")
    local se2; se2=$(err "$P.rad.l" "$P.hsame.l")
    printf "heliodon  %-34s error(median|rel| bias nlit) %s  CPU %.1f s wall %.1f s -> per 512^2 picture CPU %.0f s\n" \
        "$rset" "$se" "$1" "$2" "$(echo "$1 * $ROWSTEP" | bc -l)"
    printf "SAME SETTINGS %s: heliodon vs Radiance pixels (median|rel| mean-bias): %s; CPU time ratio %.2f\n" \
        "$name" "$se2" "$(echo "$rcpu / $1" | bc -l)"
    set -- $rr1 $rr2
    local rmed=${rerr%% *} rrmed=${rrerr%% *} rrcpu=$1 rrwall=$2 found="" found2=""
    for ad in $ADS; do
        (cd "$dir" && /usr/bin/time -f "%U %S %e" -o "$P.t_h$ad" rtrace -h -n $N -ab 8 -ad $ad -lw 1e-4 -lr -12 -dj 0 -st 0 \
            $files < "$P.rays" > "$P.h$ad")
        lum "$P.h$ad" > "$P.h$ad.l"
        set -- $(cpu "$P.t_h$ad")
        local e; e=$(err "$P.truth.l" "$P.h$ad.l")
        printf "heliodon  -ab 8 -ad %-5s -lw 1e-4 -lr -12       error(median|rel| bias nlit) %s  CPU %.1f s wall %.1f s -> per 512^2 picture CPU %.0f s\n" \
            "$ad" "$e" "$1" "$2" "$(echo "$1 * $ROWSTEP" | bc -l)"
        if [ -z "$found" ] && awk -v a="${e%% *}" -v b="$rmed" 'BEGIN{exit !(a <= b)}'; then
            found=$ad
            printf "EQUAL ERROR %s vs Radiance reference settings (-lr 12): heliodon -ad %s (error %s) vs Radiance (error %s): CPU time ratio %.2f, wall ratio %.2f\n" \
                "$name" "$ad" "${e%% *}" "$rmed" "$(echo "$rcpu / $1" | bc -l)" "$(echo "$rwall / $2" | bc -l)"
        fi
        if [ -z "$found2" ] && awk -v a="${e%% *}" -v b="$rrmed" 'BEGIN{exit !(a <= b)}'; then
            found2=$ad
            printf "EQUAL ERROR %s vs Radiance with Russian roulette (-lr -12): heliodon -ad %s (error %s) vs Radiance (error %s): CPU time ratio %.2f, wall ratio %.2f\n" \
                "$name" "$ad" "${e%% *}" "$rrmed" "$(echo "$rrcpu / $1" | bc -l)" "$(echo "$rrwall / $2" | bc -l)"
        fi
    done
    [ -n "$found2" ] || echo "EQUAL ERROR $name: no heliodon setting in ADS reached the error $rrmed of Radiance -lr -12"
    [ -n "$found" ] || echo "EQUAL ERROR $name: no heliodon setting in ADS reached Radiance's error $rmed"
}

run_scene box "$REF/scenes/box" fish.vf \
    "box_room.rad box_window.rad sky_overcast_0103_1130.rad skyglow.rad" \
    "-ab 6 -ad 1024 -as 0 -aa 0 -lw 1e-4 -dj 0 -st 0 -lr 12"
run_scene office "$REF/scenes/office" v1.vf \
    "mat_glass.rad office.rad sky_chicago_1221_1230.rad skyglow.rad" \
    "-ab 6 -ad 512 -as 0 -aa 0 -lw 1e-4 -dj 0 -st 0 -lr 12"
