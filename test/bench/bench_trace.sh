#!/bin/sh
# Full conformance of rtrace/rpict against the shared "box" references
# (Radiance 6.1), with the references' own settings.  Not part of
# `make check` (several CPU-minutes).  Usage, from the project root:
#   [RADIANCE_BIN=...] PATH=build/bin:$PATH sh test/bench/bench_trace.sh [outdir]
# Prints per-point relative differences, floor means and picture
# statistics; the figures are recorded in docs/benchmarks/trace.md.
set -u
REF=${HELIODON_REF:-../shared/ref}
B=$REF/scenes/box
O=${1:-build/bench-trace}
mkdir -p "$O"
ROOM="$B/box_room.rad $B/box_window.rad"
N=${NTHREADS:-2}
lux() { awk 'h==0 && /^$/ {h=1; next} h==1 && NF>=3 {print 179*(.265*$1+.670*$2+.065*$3)}' "$1"; }
compare() {   # ours ref label
    lux "$1" > "$O/a"; lux "$2" > "$O/b"
    paste "$O/a" "$O/b" | awk -v l="$3" '
        {r=($2>0)?($1-$2)/$2:0; a=r<0?-r:r; if(a>m)m=a; if(a<=0.03)k++; s+=a; if(NR<=25){fa+=$1; fb+=$2}}
        END{printf "%-28s floor mean %8.1f vs %8.1f lux (%+.3f)  mean|rel| %.3f  max|rel| %.3f  points within 3%%: %d/28\n",
            l, fa/25, fb/25, (fa-fb)/fb, s/NR, m, k}'
}
for sky in clear overcast sunonly; do
    case $sky in
    clear) S="$B/sky_clear_0101_1030.rad $B/skyglow.rad" ;;
    overcast) S="$B/sky_overcast_0103_1130.rad $B/skyglow.rad" ;;
    sunonly) S="$B/sun_clear_0101_1030.rad" ;;
    esac
    /usr/bin/time -f "%e s wall %U s CPU" -o "$O/$sky.time" \
        rtrace -n $N -I+ -ab 8 -ad 32768 -lw 1e-6 -dj 0 -st 0 -lr 12 $ROOM $S < $B/sensors.pts > "$O/$sky.conv"
    compare "$O/$sky.conv" "$B/a1_${sky}_conv.dat" "$sky conv settings (as 0)"
    echo "   time: $(cat "$O/$sky.time")"
    # average of 4 seeds (same expectation, half the noise)
    for s in 2 3 4; do
        rtrace -h -seed $s -n $N -I+ -ab 8 -ad 32768 -lw 1e-6 -dj 0 -st 0 -lr 12 $ROOM $S < $B/sensors.pts > "$O/$sky.s$s"
    done
    awk 'h==0 && /^$/ {h=1; next} h==1 && NF>=3' "$O/$sky.conv" | paste - "$O/$sky.s2" "$O/$sky.s3" "$O/$sky.s4" |
        awk 'BEGIN{print "#?RADIANCE\nFORMAT=ascii\n"} {for(c=1;c<=3;c++){v=0; for(k=0;k<4;k++) v+=$(c+3*k); printf "%e\t", v/4} print ""}' \
        > "$O/$sky.conv4"
    compare "$O/$sky.conv4" "$B/a1_${sky}_conv.dat" "$sky conv, mean of 4 seeds"
    /usr/bin/time -f "%e s wall %U s CPU" -o "$O/$sky.time" \
        rtrace -n $N -I+ -ab 6 -ad 4096 -lw 1e-5 -dj 0 -st 0 -lr 12 $ROOM $S < $B/sensors.pts > "$O/$sky.ab6"
    compare "$O/$sky.ab6" "$B/a1_${sky}_conv.dat" "$sky ab6 settings (as 0)"
    echo "   time: $(cat "$O/$sky.time")"
    compare "$B/a1_${sky}_ab6.dat" "$B/a1_${sky}_conv.dat" "  (Radiance ab6 vs conv)"
    # The A1 references used -as 16384 (super-sampling, biased low): with a
    # Radiance build (RADIANCE_BIN), the same conv settings with -as 0 are
    # run live; that is the quantity heliodon computes with -as 0 (it super-samples as Radiance otherwise).
    RB=${RADIANCE_BIN:-}
    if [ -n "$RB" ] && [ -x "$RB/rtrace" ]; then
        OA=$(cd "$O" && pwd)
        sfiles=$(for f in $S; do basename "$f"; done)
        (cd "$B" && RAYPATH=.:$RB/../lib "$RB/oconv" box_room.rad box_window.rad $sfiles > "$OA/$sky.oct" &&
         RAYPATH=.:$RB/../lib /usr/bin/time -f "%e s wall %U s CPU" -o "$OA/$sky.rtime" "$RB/rtrace" -n $N -I+ -ab 8 -ad 32768 -as 0 -aa 0 \
             -lw 1e-6 -dj 0 -dt 0 -dc 1 -st 0 -lr 12 "$OA/$sky.oct" < sensors.pts > "$OA/$sky.rad_as0")
        compare "$O/$sky.conv" "$O/$sky.rad_as0" "$sky conv vs live Radiance -as 0"
        compare "$O/$sky.conv4" "$O/$sky.rad_as0" "$sky conv 4 seeds vs Radiance -as 0"
        compare "$O/$sky.rad_as0" "$B/a1_${sky}_conv.dat" "  (Radiance -as 0 vs -as 16384 ref)"
        echo "   Radiance time: $(cat "$O/$sky.rtime")"
    fi
done
for sky in overcast clear; do
    case $sky in
    clear) S="$B/sky_clear_0101_1030.rad $B/skyglow.rad" ;;
    overcast) S="$B/sky_overcast_0103_1130.rad $B/skyglow.rad" ;;
    esac
    /usr/bin/time -f "%e s wall %U s CPU" -o "$O/fish_$sky.time" \
        rpict -n $N -spp ${SPP:-1} -vf $B/fish.vf -x 256 -y 256 -ps 1 -pj 0 -ab 6 -ad 1024 -as 0 -aa 0 -lw 1e-4 -dj 0 -st 0 -lr 12 \
        $ROOM $S > "$O/fish_$sky.hdr"
    pvalue -h -H -d "$O/fish_$sky.hdr" | awk '{print 179*(.265*$1+.670*$2+.065*$3)}' > "$O/pa"
    pvalue -h -H -d "$B/a2_${sky}_fish.hdr" | awk '{print 179*(.265*$1+.670*$2+.065*$3)}' > "$O/pb"
    paste "$O/pa" "$O/pb" | awk '{sa+=$1; sb+=$2; if($2>0.179){r=($1-$2)/$2; print (r<0?-r:r)}}
        END{printf "%.6g %.6g\n", sa/NR, sb/NR > "/dev/stderr"}' 2> "$O/means" | sort -g > "$O/rel"
    n=$(wc -l < "$O/rel")
    med=$(awk -v n="$n" 'NR==int(n/2)+1{print; exit}' "$O/rel")
    # the reference's own pixel noise: |pixel - mean of its 4 neighbours|,
    # median over lit pixels, scaled by 1/sqrt(1 + 1/4) (an upper bound:
    # true gradients count as noise)
    refnoise=$(awk '{v[NR-1]=$1} END{for(y=1;y<255;y++)for(x=1;x<255;x++){i=y*256+x; c=v[i]; if(c<=0.179)continue;
        m=(v[i-1]+v[i+1]+v[i-256]+v[i+256])/4; r=(c-m)/c; if(r<0)r=-r; print r/sqrt(1.25)}}' "$O/pb" | sort -g |
        awk '{a[NR]=$1} END{print a[int(NR/2)+1]}')
    set -- $(cat "$O/means")
    printf "rpict fish %-9s mean luminance %.2f vs %.2f cd/m2 (%+.4f); per-pixel median |rel| %.4f over %d lit pixels; reference noise ~%.4f\n" \
        "$sky" "$1" "$2" "$(awk -v a="$1" -v b="$2" 'BEGIN{print (a-b)/b}')" "$med" "$n" "$refnoise"
    echo "   time: $(cat "$O/fish_$sky.time")"
done
