#!/bin/sh
# A BSDF window seen from inside (issue 17): the office of scenes/office with
# all three window groups the CFS4 fabric tree of scenes/cfs (isotropic,
# 1.7 % directional transmission, room-side reflection 24 %), one ray from
# view v2's point (1.8 3.8 1.2) straight at the window (0 -1 0), mean
# luminance 179 (.265 R + .67 G + .065 B) over the rays, against Radiance
# 6.1 run side by side on the same files.
#
# What this checks: Radiance's specular threshold (m_bsdf.c sample_sdf):
# the transmission's directional-hemispherical value towards the viewer
# (0.015) is below -st (0.15), so Radiance does not follow the data's
# directions through the fabric but lights that value from the outside
# hemisphere like a diffuse transmitter (heliodon before: sky only 0.75
# cd/m2 instead of 19.5, everything -21 %; hd_scatter_bsdf_split now).
#
# Reference values: Radiance 6.1 (/work/rad/inst, build 6.1.bcffc2b52d),
# made 2026-12-07 in a scratch folder holding room.rad windows.rad
# skyglow.rad (scenes/office), cfs4_ttree.xml (scenes/cfs) and
#   mat.rad: void BSDF wg{1,2,3}_mat 6 0 cfs4_ttree.xml 0 0 1 . 0 0
#   sky.rad: gensky 3 21 10.5 +s -a 38.4 -o -27.1 -m -30
#   skyonly.rad: gensky 3 21 10.5 -s -a 38.4 -o -27.1 -m -30 + skyglow.rad
#   sunonly.rad: the 'solar' light and 'sun' source lines of sky.rad
#   oconv -f mat.rad room.rad windows.rad sky.rad skyglow.rad > r_skyall.oct
#   (same for skyonly.rad, sunonly.rad)
#   rtrace -h -ab N -ad 256 -aa 0 -ss 32 r_X.oct < 100 copies of the ray
#   | awk '{s+=179*(.265*$1+.67*$2+.065*$3)} END {print s/NR}'
# giving (sd of the mean in brackets):
#   sun only, -ab 0                 112.345
#   sky + sun + glows, -ab 1        153.607 (0.53)
#   sky only (+ glows), -ab 1        19.456 (0.27)
# heliodon (same rays, 300, 2026-12-07): 112.9, 159.2, 22.3 (1.4 for 100
# rays): the remaining +3.7 % / +14 % is the transmission's hemispherical
# value, 0.0150 against Radiance's 0.0136, which Radiance takes at a view
# vector jittered over the tree's widest cell (not done here).
. test/e2e/lib.sh

O=scenes/office C=scenes/cfs
if [ ! -f "$O/room.rad" ] || [ ! -f "$C/cfs4_ttree.xml" ]; then skip window_inside "no scenes/office"; exit 0; fi
cp "$O/room.rad" "$O/windows.rad" "$O/skyglow.rad" "$C/cfs4_ttree.xml" "$T/"
for g in 1 2 3; do echo "void BSDF wg${g}_mat 6 0 cfs4_ttree.xml 0 0 1 . 0 0"; done > "$T/mat.rad"
gensky 3 21 10.5 +s -a 38.4 -o -27.1 -m -30 > "$T/sky.rad"
gensky 3 21 10.5 -s -a 38.4 -o -27.1 -m -30 > "$T/skyonly.rad"
awk '/^void light solar/ {p=1} p {print} /^solar source sun/ {q=1} q && NF == 5 {exit}' "$T/sky.rad" > "$T/sunonly.rad"
awk 'BEGIN {for (i = 0; i < 300; i++) print "1.8 3.8 1.2 0 -1 0"}' > "$T/rays"
lum() { awk '{s += 179 * (.265 * $1 + .67 * $2 + .065 * $3); n++} END {if (n) printf "%.4f\n", s / n}'; }
run() {   # NAME SCENEFILES... -- OPTIONS
    name=$1; shift
    files=""
    while [ "$1" != -- ]; do files="$files $1"; shift; done
    shift
    (cd "$T" && oconv mat.rad room.rad windows.rad $files > "$name.oct" && \
        rtrace -h -n 2 -ad 256 -ss 32 "$@" "$name.oct" < rays) 2>"$T/err.$name" | lum
}
sun0=$(run sun sunonly.rad -- -ab 0)
all1=$(run all sky.rad skyglow.rad -- -ab 1)
sky1=$(run sky skyonly.rad skyglow.rad -- -ab 1)
echo "  window seen from v2 (cd/m2): sun -ab 0 $sun0 (Radiance 112.345), all -ab 1 $all1 (153.607)," \
     "sky -ab 1 $sky1 (19.456)"
if [ -n "$sun0" ] && close "$sun0" 112.345 0.03; then pass direct_sun_through_fabric
else fail direct_sun_through_fabric "$sun0 vs 112.345 (3 %) $(cat "$T/err.sun")"; fi
if [ -n "$all1" ] && close "$all1" 153.607 0.06; then pass window_luminance_ab1
else fail window_luminance_ab1 "$all1 vs 153.607 (6 %) $(cat "$T/err.all")"; fi
# the sky part alone is all threshold rule (0.75 without it); noisier
if [ -n "$sky1" ] && close "$sky1" 19.456 0.25; then pass sky_through_fabric_as_diffuse
else fail sky_through_fabric_as_diffuse "$sky1 vs 19.456 (25 %) $(cat "$T/err.sky")"; fi
# -st 1 lights both sides as diffuse: with -ab 0 -av 1 1 1 the window's
# value is the sum of the two hemispherical values, Radiance 0.2517
# (mean of 100 rays; its view vector is jittered per ray) against the
# data's 0.2550 at the unjittered vector
st1=$(cd "$T" && rtrace -h -ab 0 -av 1 1 1 -st 1 sky.oct < rays 2>/dev/null | awk '{s += $2; n++} END {if (n) printf "%.5f\n", s / n}')
if [ -n "$st1" ] && close "$st1" 0.2517 0.03; then pass threshold_hemispherical_sum
else fail threshold_hemispherical_sum "$st1 vs 0.2517 (3 %)"; fi
