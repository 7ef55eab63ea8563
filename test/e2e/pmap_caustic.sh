#!/bin/sh
# rcontrib -ap with -ab 1 (final gather) must count the sun light that
# reaches a diffuse surface after a data-driven BSDF or a specular slat, as
# -ab -1 (density estimate at the hit) does.  The photons of that light are
# flagged "caustic" by mkpmap (only glass / specular / BSDF events since the
# port); the final gather adds them at the gather point (its rays see only
# the diffuse reflection of what they hit, its shadow ray only glass).
. test/e2e/lib.sh

box() {   # $1 = port material line, $2 = extra scene lines
    printf 'void plastic black 0 0 5 0 0 0 0 0\nvoid plastic floormat 0 0 5 .5 .5 .5 0 0\n%s\n' "$1"
    printf 'void light solar1 0 0 3 1 1 1\nsolar1 source sun1 0 0 4 0 0 1 0.533\n%s\n' "$2"
    cat test/e2e/roofbox.rad
}
om=$(awk 'BEGIN { printf "%.9e", 2 * 3.14159265358979 * (1 - cos(0.533 / 2 * 3.14159265358979 / 180)) }')

# ---- (a) a Lambertian Klems diffuser (tau = 0.5) as the roof opening of
# the black 1 m box, sun overhead: floor coefficient tau * Omega * F(x, y),
# F = view factor to the opening (parallel rectangle).  -ab -1 and -ab 1
# within 6 % of it at 4 points.
lambert_xml 0.5 "$T/lam.xml"
box "void BSDF port_m 6 0 $T/lam.xml 0 1 0 . 0 0" "" > "$T/lam.rad"
printf '0.5 0.5 0.001 0 0 1\n0.3 0.4 0.001 0 0 1\n0.5 0.2 0.001 0 0 1\n0.15 0.15 0.001 0 0 1\n' > "$T/pts.txt"
awk -v om="$om" 'function fc(a, b,   s, X, Y) { s = (a < 0 ? -1 : 1) * (b < 0 ? -1 : 1); X = a < 0 ? -a : a; Y = b < 0 ? -b : b
        return s / (2 * 3.14159265358979) * (X / sqrt(1 + X*X) * atan2(Y, sqrt(1 + X*X)) + Y / sqrt(1 + Y*Y) * atan2(X, sqrt(1 + Y*Y))) }
    { x = $1; y = $2; h = 1 - $3
      F = fc((.75-x)/h, (.75-y)/h) - fc((.25-x)/h, (.75-y)/h) - fc((.75-x)/h, (.25-y)/h) + fc((.25-x)/h, (.25-y)/h)
      printf "%.6e\n", 0.5 * om * F }' "$T/pts.txt" > "$T/exact.txt"
if mkpmap -apC "$T/lam.pm" 400k -apo port_m -apr 5 -n 2 "$T/lam.rad" 2>"$T/err"; then
    for ab in -1 1; do
        if rcontrib -h -I+ -ab $ab -ad 64 -ap "$T/lam.pm" 2000 -am 0.2 -fa -m solar1 "$T/lam.rad" < "$T/pts.txt" \
               > "$T/lam_$ab.txt" 2>>"$T/err"; then
            r=$(paste "$T/lam_$ab.txt" "$T/exact.txt" | awk '{ d = $2 / $4 - 1; if (d < 0) d = -d; if (d > m) m = d; printf "%.4g/%.4g ", $2, $4 } END { printf "max %.4f", m }')
            echo "  BSDF diffuser, -ab $ab photon / exact floor coefficients: $r"
            if [ "$(echo "$r" | awk '{print ($NF < 0.06)}')" = 1 ]; then pass "bsdf_ab$ab"
            else fail "bsdf_ab$ab" "$r (6 %)"; fi
        else fail "bsdf_ab$ab" "$(cat "$T/err")"; fi
    done
else fail bsdf_build "$(cat "$T/err")"; fi

# ---- (b) a clear glass roof opening and a metal slat (specularity 1,
# roughness 0) tilted 60 degrees under it: the beam reflected towards +x
# lands on the floor at x in [.66, .90], beyond the direct patch (x <= .75).
# Floor coefficient there: Omega * T_glass * slat specular colour (with
# Fresnel at 60 degrees) * cos 60.  -ab -1 and -ab 1 within 6 % of each
# other on the mean of 6 points, and the -ab 1 mean is not below 90 % of
# Omega * 0.85 (glass T > .85) * 0.9 (slat colour) * 0.5.
slat='void metal slatmat 0 0 5 .9 .9 .9 1 0
slatmat polygon slat 0 0 12 .41 .3 .146 .29 .3 .354 .29 .7 .354 .41 .7 .146'
box 'void glass port_m 0 0 3 .96 .96 .96' "$slat" > "$T/slat.rad"
awk 'BEGIN { for (i = 0; i < 3; i++) for (j = 0; j < 2; j++) printf "%g %g 0.001 0 0 1\n", 0.79 + 0.04 * i, 0.45 + 0.1 * j }' > "$T/spts.txt"
if mkpmap -apC "$T/slat.pm" 300k -apo port_m -apr 3 -n 2 "$T/slat.rad" 2>"$T/err" &&
   rcontrib -h -I+ -ab -1 -ap "$T/slat.pm" 400 -am 0.2 -fa -m solar1 "$T/slat.rad" < "$T/spts.txt" > "$T/s_m1.txt" 2>>"$T/err" &&
   rcontrib -h -I+ -ab 1 -ad 64 -ap "$T/slat.pm" 400 -am 0.2 -fa -m solar1 "$T/slat.rad" < "$T/spts.txt" > "$T/s_1.txt" 2>>"$T/err"; then
    a=$(awk '{ s += $2 } END { printf "%.6e", s / NR }' "$T/s_m1.txt")
    b=$(awk '{ s += $2 } END { printf "%.6e", s / NR }' "$T/s_1.txt")
    lo=$(awk -v om="$om" 'BEGIN { printf "%.6e", 0.9 * om * 0.85 * 0.9 * 0.5 }')
    echo "  slat-reflected sun on the floor: -ab -1 $a, -ab 1 $b (lower bound $lo)"
    if close "$b" "$a" 0.06 && le "$lo" "$b"; then pass slat_ab1
    else fail slat_ab1 "-ab 1 $b vs -ab -1 $a (6 %), lower bound $lo"; fi
else fail slat_ab1 "$(cat "$T/err")"; fi
