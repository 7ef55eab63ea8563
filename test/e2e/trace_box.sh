#!/bin/sh
# rtrace / rpict on the shared "box" reference scene (Radiance 6.1 outputs).
# Quick versions of the conformance checks; the full ones are in
# test/bench/trace_conformance.sh (see docs/benchmarks/trace.md).
. test/e2e/lib.sh
B=$REF/scenes/box
if ! have_ref scenes/box; then skip box "no reference folder $REF"; exit 0; fi
ROOM="$B/box_room.rad $B/box_window.rad"

# luminance-weighted values (lux) of an rtrace -I output
lux() { data_values "$1" | awk '{v[n++]=$1} n==3 {print 179*(.265*v[0]+.670*v[1]+.065*v[2]); n=0}'; }

# 1. -ab 0: direct sun through the glass, exact (Radiance prints 7 digits)
for sky in clear overcast sunonly; do
    case $sky in
    clear) S="$B/sky_clear_0101_1030.rad $B/skyglow.rad" ;;
    overcast) S="$B/sky_overcast_0103_1130.rad $B/skyglow.rad" ;;
    sunonly) S="$B/sun_clear_0101_1030.rad" ;;
    esac
    if rtrace -I+ -ab 0 -dj 0 -dt 0 -dc 1 -st 0 -lr 12 -lw 1e-6 $ROOM $S < $B/sensors.pts > "$T/$sky.ab0" 2>"$T/err"; then
        lux "$T/$sky.ab0" > "$T/a"; lux "$B/a1_${sky}_ab0.dat" > "$T/b"
        bad=$(paste "$T/a" "$T/b" | awk '{d=$1-$2; if(d<0)d=-d; if ($2==0 ? $1!=0 : d>1e-5*$2) n++} END{print n+0}')
        n=$(wc -l < "$T/a")
        if [ "$n" -eq 28 ] && [ "$bad" -eq 0 ]; then pass "ab0_$sky"; else fail "ab0_$sky" "$bad of $n points differ"; fi
    else fail "ab0_$sky" "$(cat "$T/err")"; fi
done

# 2. -ab > 0 against the converged references, made by Radiance 6.1 with
#    ambient super-sampling (-as 16384 / 2048; -as 16384 here for every
#    sky).  heliodon super-samples as Radiance does (walk.c), so it must
#    equal the reference: floor mean (25 points) within 1.5 %, every point
#    within 12 % (ours at the conv settings: about 1 s CPU per sky).
#    Super-sampling biases low (Radiance's ambcomp.c says so): Radiance's
#    own -as 0 floor means are higher by +1.0 % (clear), +3.4 % (overcast),
#    +0.4 % (sun only), up to +9 % at the back of the room for the overcast
#    sky (docs/benchmarks/trace.md), so the overcast case fails if -as is
#    ignored (measured after the change: overcast +0.2 %).
for sky in clear overcast sunonly; do
    case $sky in
    clear) S="$B/sky_clear_0101_1030.rad $B/skyglow.rad" ;;
    overcast) S="$B/sky_overcast_0103_1130.rad $B/skyglow.rad" ;;
    sunonly) S="$B/sun_clear_0101_1030.rad" ;;
    esac
    if rtrace -n 2 -I+ -ab 8 -ad 32768 -as 16384 -aa 0 -lw 1e-6 -dj 0 -st 0 -lr 12 $ROOM $S < $B/sensors.pts > "$T/$sky.conv" 2>"$T/err"; then
        lux "$T/$sky.conv" > "$T/a"; lux "$B/a1_${sky}_conv.dat" > "$T/b"
        res=$(paste "$T/a" "$T/b" | awk 'NR<=25 {sa+=$1; sb+=$2} {r=($1-$2)/$2; if(r<0)r=-r; if(r>m)m=r}
              END{printf "%.4f %.4f", (sa-sb)/sb, m}')
        set -- $res
        if le "$(echo "$1" | tr -d -)" 0.015 && le "$2" 0.12; then pass "conv_${sky}_vs_ref"
        else fail "conv_${sky}_vs_ref" "floor mean vs reference: rel $1; max per-point |rel| $2"; fi
    else fail "conv_${sky}_vs_ref" "$(cat "$T/err")"; fi
done

# 2b. With a Radiance build (RADIANCE_BIN): the overcast sky, the hardest
#     case (light from low sky through several interreflections), with -as 0
#     in both programs against a live Radiance rtrace at the conv settings
#     (~20 s CPU): every one of the 28 points within 3 %.
RB=${RADIANCE_BIN:-}
if [ -n "$RB" ] && [ -x "$RB/rtrace" ] && [ -x "$RB/oconv" ]; then
    TA=$(cd "$T" && pwd)
    S="$B/sky_overcast_0103_1130.rad $B/skyglow.rad"
    if rtrace -n 2 -I+ -ab 8 -ad 32768 -as 0 -aa 0 -lw 1e-6 -dj 0 -st 0 -lr 12 $ROOM $S < $B/sensors.pts > "$T/overcast.as0" 2>"$T/err" &&
       (cd $B && RAYPATH=.:$RB/../lib "$RB/oconv" box_room.rad box_window.rad sky_overcast_0103_1130.rad skyglow.rad) > "$T/ov.oct" &&
       (cd $B && RAYPATH=.:$RB/../lib "$RB/rtrace" -n 2 -I+ -ab 8 -ad 32768 -as 0 -aa 0 -lw 1e-6 -dj 0 -dt 0 -dc 1 -st 0 -lr 12 \
            "$TA/ov.oct" < sensors.pts) > "$T/rad.conv" 2>"$T/err"; then
        lux "$T/overcast.as0" > "$T/a"; lux "$T/rad.conv" > "$T/b"
        res=$(paste "$T/a" "$T/b" | awk '{r=($1-$2)/$2; if(r<0)r=-r; if(r>m)m=r; if(r<=0.03)k++} END{printf "%d %.4f", k, m}')
        set -- $res
        if [ "$1" -eq 28 ]; then pass overcast_conv_vs_live_radiance_as0
        else fail overcast_conv_vs_live_radiance_as0 "$1/28 points within 3 %, max |rel| $2"; fi
    else fail overcast_conv_vs_live_radiance_as0 "run failed: $(cat "$T/err")"; fi
else
    skip overcast_conv_vs_live_radiance_as0 "RADIANCE_BIN not set"
fi

# 3. same seed, 1 or 2 threads: identical output
S="$B/sky_overcast_0103_1130.rad $B/skyglow.rad"
head -6 $B/sensors.pts > "$T/six.pts"
rtrace -h -n 1 -I+ -ab 2 -ad 64 $ROOM $S < "$T/six.pts" > "$T/n1" 2>&1
rtrace -h -n 2 -I+ -ab 2 -ad 64 $ROOM $S < "$T/six.pts" > "$T/n2" 2>&1
check threads_deterministic cmp "$T/n1" "$T/n2"

# 4. header as Radiance's rtrace writes it
S="$B/sky_clear_0101_1030.rad $B/skyglow.rad"
rtrace -I+ -ab 0 $ROOM $S < "$T/six.pts" > "$T/hdr.dat" 2>"$T/err"
if head -1 "$T/hdr.dat" | grep -q '^#?RADIANCE$' && grep -q '^rtrace -I+ -ab 0' "$T/hdr.dat" &&
   grep -q '^SOFTWARE= heliodon' "$T/hdr.dat" && grep -q '^NCOMP=3$' "$T/hdr.dat" &&
   grep -q '^FORMAT=ascii$' "$T/hdr.dat" && [ "$(data_values "$T/hdr.dat" | wc -l)" -eq 18 ]; then
    pass rtrace_header
else fail rtrace_header "$(head -8 "$T/hdr.dat" | tr '\n' '|')"; fi

# 5. rpict fisheye, 64 x 64 jittered pixels with the reference settings:
#    mean luminance within 6 % of the 256 x 256 Radiance picture (the
#    window covers few pixels at this size; the 256 x 256 run is in test/bench)
meanlum() { pvalue -h -H -d "$1" | awk '{s+=179*(.265*$1+.670*$2+.065*$3); n++} END{printf "%.6g", s/n}'; }
if rpict -n 2 -vf $B/fish.vf -x 64 -y 64 -pj 1 -ab 6 -ad 1024 -as 0 -aa 0 -lw 1e-4 -dj 0 -st 0 -lr 12 \
        $ROOM $B/sky_overcast_0103_1130.rad $B/skyglow.rad > "$T/fish.hdr" 2>"$T/err"; then
    a=$(meanlum "$T/fish.hdr"); b=$(meanlum $B/a2_overcast_fish.hdr)
    if close "$a" "$b" 0.06; then pass rpict_fish_mean; else fail rpict_fish_mean "mean luminance $a vs $b"; fi
    if getinfo "$T/fish.hdr" | grep -q 'VIEW= -vta -vp 1.5 3.5 1.2 -vd 0 -1 0 -vu 0 0 1 -vh 180 -vv 180 -vo 0 -va 0 -vs 0 -vl 0' &&
       getinfo -d "$T/fish.hdr" | grep -Eq -- '-Y +64 \+X +64'; then pass rpict_header
    else fail rpict_header "$(getinfo "$T/fish.hdr" | tr '\n' '|')"; fi
else fail rpict_fish_mean "$(cat "$T/err")"; skip rpict_header "no picture"; fi

# 6. rpict per-pixel agreement with the 256 x 256 clear-sky reference picture
#    (A2 settings), on the central band of 32 rows (rows 112-143: window,
#    sun patch, walls): -vv 22.5 with -x 256 -y 32 traces exactly the rays of
#    those rows of the full picture (same pixel centres; checked against
#    vwrays).  Must show: mean luminance within 3 %, median per-pixel
#    |relative difference| over lit pixels (> 0.179 cd/m2) below 10 %.
#    Measured: mean -0.4 %, median 4.5 %; the reference's own pixel noise is
#    about 3.5 % (docs/benchmarks/trace.md).  ~15 s CPU.
if rpict -n 2 -vf $B/fish.vf -vv 22.5 -x 256 -y 32 -pj 0 -ab 6 -ad 1024 -as 0 -aa 0 -lw 1e-4 -dj 0 -st 0 -lr 12 \
        $ROOM $B/sky_clear_0101_1030.rad $B/skyglow.rad > "$T/band.hdr" 2>"$T/err"; then
    pvalue -h -H -d "$T/band.hdr" | awk '{print 179*(.265*$1+.670*$2+.065*$3)}' > "$T/pa"
    pvalue -h -H -d $B/a2_clear_fish.hdr | sed -n "$((112 * 256 + 1)),$((144 * 256))p" |
        awk '{print 179*(.265*$1+.670*$2+.065*$3)}' > "$T/pb"
    res=$(paste "$T/pa" "$T/pb" | awk '$2>0.179 {sa+=$1; sb+=$2; r=($1-$2)/$2; print (r<0?-r:r)} END{printf "%.6g\n", (sa-sb)/sb > "/dev/stderr"}' \
          2> "$T/meanrel" | sort -g | awk '{v[NR]=$1} END{printf "%.4f %d", v[int(NR/2)+1], NR}')
    set -- $res $(cat "$T/meanrel")
    if [ "$(wc -l < "$T/pa")" -eq 8192 ] && [ "$2" -gt 4000 ] && le "$1" 0.10 && le "$(echo "$3" | tr -d -)" 0.03; then
        pass rpict_band_vs_reference_pixels
    else fail rpict_band_vs_reference_pixels "median |rel| $1 over $2 lit pixels, mean rel $3"; fi
else fail rpict_band_vs_reference_pixels "$(cat "$T/err")"; fi
