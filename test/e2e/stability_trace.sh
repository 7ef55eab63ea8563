#!/bin/sh
# Stability suite (issue 10): cases where lighting methods are known to fail.
# Each case asserts a value or a bound; see docs/design/bench.md.
. test/e2e/lib.sh

# all numbers of an rtrace/rcontrib output finite (no nan/inf)
finite() { data_values "$1" | awk '{v=tolower($1); if (v ~ /nan|inf/ || v+0 != v+0) bad++} END{exit bad>0}'; }
allzero() { data_values "$1" | awk '$1+0 != 0 {bad++} END{exit bad>0}'; }

# 1. empty scene: rtrace, rcontrib and rpict give exact zeros, no NaN
: > "$T/empty.rad"
printf '0 0 1 0 0 1\n1 2 3 0 1 0\n' > "$T/two.pts"
if rtrace -I+ -ab 2 -ad 64 "$T/empty.rad" < "$T/two.pts" > "$T/e1" 2>"$T/err" && finite "$T/e1" && allzero "$T/e1" &&
   [ "$(data_values "$T/e1" | wc -l)" -eq 6 ]; then pass empty_rtrace_zero; else fail empty_rtrace_zero "$(cat "$T/err")"; fi
printf 'void glow g 0 0 4 1 1 1 0\n' > "$T/glowonly.rad"     # modifier that nothing uses
# a modifier no surface uses: a clear error naming it (not silent zeros)
check_fails empty_rcontrib_unused_modifier "modifier .g." rcontrib -I+ -ab 1 -ad 64 -m g "$T/empty.rad" "$T/glowonly.rad"
if rpict -vta -vp 0 0 0 -vd 0 1 0 -vh 180 -vv 180 -x 16 -y 16 -ab 1 "$T/empty.rad" > "$T/e.hdr" 2>"$T/err" &&
   hdcompare "$T/e.hdr" "$T/e.hdr" > "$T/e.cmp" && grep -q '^lit 0$' "$T/e.cmp" && grep -q '^ev_test 0$' "$T/e.cmp"
then pass empty_rpict_black; else fail empty_rpict_black "$(cat "$T/err" "$T/e.cmp" 2>/dev/null | head -5)"; fi

# 2. black closed box under a bright sky: every interior value exactly 0
{ printf 'void plastic black 0 0 5 0 0 0 0 0\nvoid glow sky 0 0 4 1000 1000 1000 0\nsky source s 0 0 4 0 0 1 180\n'
  genbox black room 3 4 3 -i; } > "$T/black.rad"
printf '1.5 2 1.5 0 0 1\n0.5 0.5 0.01 0 0 1\n2.9 3.9 2.9 -1 0 0\n' > "$T/in.pts"
if rtrace -I+ -ab 4 -ad 128 "$T/black.rad" < "$T/in.pts" > "$T/b1" 2>"$T/err" && finite "$T/b1" && allzero "$T/b1"
then pass black_box_zero; else fail black_box_zero "$(cat "$T/err"; data_values "$T/b1" | head -3 | tr '\n' ' ')"; fi
if rcontrib -I+ -ab 4 -ad 128 -m sky "$T/black.rad" < "$T/in.pts" > "$T/b2" 2>"$T/err" && finite "$T/b2" && allzero "$T/b2"
then pass black_box_rcontrib_zero; else fail black_box_rcontrib_zero "$(cat "$T/err")"; fi

# 3. sun at and below the horizon of a horizontal sensor (grazing incidence).
#    Analytic: E = L * Omega * sin(altitude) for the disk centre; a disk of
#    radius r sampled anywhere gives L*Omega*sin(alt +- r): the result must lie
#    in [L Omega max(0, sin(alt-r)), L Omega sin(alt+r)], finite, never
#    negative; a sun entirely below the horizon gives exactly 0.
L=1000000; D=0.533
for alt in 5 0.5 0.2 -0.1 -1; do
    dir=$(awk -v a="$alt" 'BEGIN{r=a*atan2(0,-1)/180; printf "0 %.9f %.9f", -cos(r), sin(r)}')
    printf 'void light solar 0 0 3 %s %s %s\nsolar source sun 0 0 4 %s %s\n' $L $L $L "$dir" $D > "$T/sun.rad"
    printf '0 0 0 0 0 1\n' > "$T/up.pts"
    bounds=$(awk -v a="$alt" -v d=$D -v L=$L 'BEGIN{pi=atan2(0,-1); r=d/2; om=2*pi*(1-cos(r*pi/180));
        lo=sin((a-r)*pi/180); hi=sin((a+r)*pi/180); if(lo<0)lo=0; if(hi<0)hi=0; printf "%.9g %.9g", L*om*lo, L*om*hi}')
    set -- $bounds; lo=$1; hi=$2
    for prog in rtrace rcontrib; do
        if [ $prog = rtrace ]; then rtrace -I+ -ab 0 "$T/sun.rad" < "$T/up.pts" > "$T/g" 2>"$T/err"
        else rcontrib -V+ -I+ -ab 0 -m solar "$T/sun.rad" < "$T/up.pts" > "$T/g" 2>"$T/err"; fi
        v=$(data_values "$T/g" | head -1)
        if [ -n "$v" ] && finite "$T/g" && awk -v v="$v" -v lo="$lo" -v hi="$hi" 'BEGIN{exit !(v >= lo*(1-1e-4) && v <= hi*(1+1e-4) && v >= 0)}'
        then pass "grazing_${prog}_alt$alt"; else fail "grazing_${prog}_alt$alt" "value '$v' outside [$lo, $hi] $(head -2 "$T/err")"; fi
    done
done

# 4. sun near the horizon through the whole chain: gendaylit at 0.5 deg, the
#    box scene at -ab 2: finite, non-negative, and below the value at 10 deg.
B=$REF/scenes/box
if have_ref scenes/box; then
    for alt in 0.5 10; do
        gendaylit -ang "$alt" 0 -W 600 100 > "$T/sky$alt.rad" 2>"$T/err" || { fail gendaylit_low_sun "$(cat "$T/err")"; continue; }
        rtrace -I+ -ab 2 -ad 256 -lw 1e-3 "$B/box_room.rad" "$B/box_window.rad" "$T/sky$alt.rad" "$B/skyglow.rad" \
            < "$B/sensors.pts" > "$T/low$alt" 2>"$T/err"
    done
    m1=$(data_values "$T/low0.5" | awk '{s+=$1} END{print s/NR}'); m2=$(data_values "$T/low10" | awk '{s+=$1} END{print s/NR}')
    if finite "$T/low0.5" && [ "$(data_values "$T/low0.5" | wc -l)" -eq 84 ] && le 0 "$m1" && le "$m1" "$m2"
    then pass low_sun_box_finite; else fail low_sun_box_finite "mean 0.5deg $m1, 10deg $m2"; fi
else skip low_sun_box_finite "no reference folder $REF"; fi

# 5. geometric slats with the sun in view (pixel-sampling artefact of the
#    geometric model: the paper's DGP 0.869 vs 0.447).  A sub-pixel bright
#    source seen through slat gaps is hit or missed by single pixel samples:
#    at 1 sample per pixel the DGP error against a converged render is large,
#    and k*k samples per pixel (a k-times larger picture box-filtered,
#    hdcompare -r k) must reduce the mean |dDGP| over several sun positions.
#    The "sun" is a 3-degree disk so that the reference (64 jittered samples
#    per 5.6-degree pixel) converges at a test-suite size.
{ cat <<'R'
void plastic wall 0 0 5 .5 .5 .5 0 0
void metal slatmat 0 0 5 .8 .8 .8 0 0
void light solar 0 0 3 3000 3000 3000
solar source sun 0 0 4 SUNDIR 3
void glow skyglow 0 0 4 20 20 20 0
skyglow source sky 0 0 4 0 0 1 180
wall polygon floor 0 0 12 0 0 0 2 0 0 2 3 0 0 3 0
wall polygon ceil 0 0 12 0 0 2.5 0 3 2.5 2 3 2.5 2 0 2.5
wall polygon back 0 0 12 0 3 0 2 3 0 2 3 2.5 0 3 2.5
wall polygon east 0 0 12 2 0 0 2 3 0 2 3 2.5 2 0 2.5
wall polygon west 0 0 12 0 0 0 0 0 2.5 0 3 2.5 0 3 0
wall polygon s1 0 0 12 0 0 0 2 0 0 2 0 0.5 0 0 0.5
wall polygon s2 0 0 12 0 0 2.0 2 0 2.0 2 0 2.5 0 0 2.5
wall polygon s3 0 0 12 0 0 0.5 0.2 0 0.5 0.2 0 2.0 0 0 2.0
wall polygon s4 0 0 12 1.8 0 0.5 2 0 0.5 2 0 2.0 1.8 0 2.0
R
  awk 'BEGIN{for(i=0;i<13;i++){z=0.5+i*0.12; printf "slatmat polygon slat%d 0 0 12 0 -0.02 %g 2 -0.02 %g 2 -0.12 %g 0 -0.12 %g\n",i,z,z,z,z}}'
} > "$T/slats.tpl"
V="-vta -vp 1 2.5 1.2 -vd 0 -1 0 -vu 0 0 1 -vh 180 -vv 180"
: > "$T/slat.res"
ok=1
for az in 0 0.15 0.3; do
    sed "s/SUNDIR/$az -0.9781 0.2079/" "$T/slats.tpl" > "$T/s.rad"
    rpict $V -x 256 -y 256 -pj 1 -ab 1 -ad 16 -lw 1e-3 "$T/s.rad" > "$T/ref.hdr" 2>"$T/err" || ok=0
    for k in 1 4; do
        r=$((32 * k))
        rpict $V -x $r -y $r -pj 1 -ab 1 -ad 16 -lw 1e-3 "$T/s.rad" > "$T/t.hdr" 2>>"$T/err" || ok=0
        hdcompare -r $k -R 8 "$T/t.hdr" "$T/ref.hdr" > "$T/c" 2>>"$T/err" || ok=0
        echo "$k $(awk '$1=="dgp_diff"{print ($2<0?-$2:$2)}' "$T/c")" >> "$T/slat.res"
    done
done
res=$(awk '{s[$1]+=$2; n[$1]++} END{printf "%.4f %.4f", s[1]/n[1], s[4]/n[4]}' "$T/slat.res")
set -- $res
if [ $ok = 1 ] && le 0.05 "$1" && awk -v a="$1" -v b="$2" 'BEGIN{exit !(b < 0.6*a)}'
then pass "slats_sun_in_view_dgp (mean |dDGP| 1 spp $1, 16 spp $2)"
else fail slats_sun_in_view_dgp "mean |dDGP| 1 spp $1, 16 spp $2 $(head -3 "$T/err")"; fi
