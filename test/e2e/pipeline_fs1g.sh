#!/bin/bash
# Geometric FS1 (scenes/office/mat_fs1g.rad: the CFS1 / CFS2 slat arrays of scenes/cfs placed in
# the windows behind clear glazing) through the annual pipeline on a tiny configuration: one
# daylight hour (+1 night record), 32x32, MF:1, default DC_sun (-ab -1 photon lookup).  The
# composite must agree with heliodon's converged backward rendering (rpict) of the same hour with
# the sun at its patch centre: mean luminance within 10 %, DGP within 0.03.  Also checks that
# the slat geometry is really in the scene (the windows' transmitted view is darker than clear
# glass and the run's octree holds the slats).
. test/e2e/lib.sh
ROOT=$(pwd)
T=$(cd "$T" && pwd)
O=$ROOT/scenes/office
izmir_wea "$T/w.wea" '3 21 1.5 0 0' '3 21 10.5 820 110'
RUN=$T/run
if ! make -s -C "$O" WEATHER="$T/w.wea" OUT="$RUN" CONFIG=fs1g VIEW=v1 RES=32 MF=1 PHOTONS=200k BANDWIDTH=50 \
        SKY_OPTS="-ab 3 -ad 256 -lw 1e-4" FEN_OPTS="-ab 3 -ad 512 -lw 1e-4" NPROC=2 IMAGES=1 > "$T/make.log" 2>&1; then
    fail run "$(grep -v 'no emission' "$T/make.log" | tail -5 | tr '\n' ' ')"
    exit 0
fi
pass run
# the slats are in the scene: 4 x (77 + 125 + 67) slat polygons... counted through oconv's input
n=$(cd "$O" && sh -c "$(grep '^!' mat_fs1g.rad | sed 's/^!//' | tr '\n' ';')" | grep -c ' polygon ')
if [ "$n" = $(( 16 * (77 + 125 + 67) )) ]; then pass slat_geometry; else fail slat_geometry "expected 4304 slat polygons, got $n"; fi
read -r rec mo da hr bin dx dy dz sr sg sb ml dgp <<< "$(grep -v '^#' "$RUN/v1/hours.log" | head -1)"
izmir_sky "$T/sky.rad" "$mo" "$da" "$hr" $(wea_record "$T/w.wea" "$mo" "$da" "$hr")
patchsun_rad "$T/sun.rad" "$sr" "$sg" "$sb" "$dx" "$dy" "$dz"
(cd "$O" && oconv mat_fs1g.rad room.rad windows.rad "$T/sky.rad" skyglow.rad "$T/sun.rad" > "$T/ref.oct" &&
    rpict -vf v1.vf -x 32 -y 32 -ps 1 -pj 0 -dj 0 -ab 4 -ad 1024 -as 0 -aa 0 -lw 1e-5 "$T/ref.oct" > "$T/ref.hdr")
rdgp=$(evalglare -vta -vh 180 -vv 180 "$T/ref.hdr" | awk '{print $2}')
rml=$(meanlum "$T/ref.hdr")
echo "fs1g hour $rec ($mo/$da $hr): composite mean $ml DGP $dgp; reference mean $rml DGP $rdgp" >&2
if close "$ml" "$rml" 0.10; then pass mean_lum; else fail mean_lum "composite $ml vs reference $rml cd/m2"; fi
if awk -v a="$dgp" -v b="$rdgp" 'BEGIN{d=a-b; if(d<0)d=-d; exit !(d<=0.03)}'; then pass dgp; else fail dgp "composite $dgp vs reference $rdgp"; fi
