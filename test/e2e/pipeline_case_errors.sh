#!/bin/bash
# Bad case inputs of the reusable pipeline (pipeline/heliodon.mk, run on scenes/corner) are answered
# by the preflight, before any long stage: a clear message naming the make variable or the file,
# a non-zero exit, and no sun sources, octree or photon map made.
. test/e2e/lib.sh
ROOT=$(pwd)
T=$(cd "$T" && pwd)
C=$ROOT/scenes/corner
printf '%s\n' "place Berlin_e2e" "latitude 52.5" "longitude -13.4" "time_zone -15" "site_elevation 40" \
    "weather_data_file_units 1" "3 21 10.5 745 124" "3 21 11.5 772 128" > "$T/w.wea"
printf '%s\n' "3 21 10.5 745 124" "3 21 11.5 772 128" > "$T/noloc.wea"
printf '%s\n' "place Nowhere" "3 21 10.5 745 124" > "$T/noloc2.wea"
k=0
case_fails() {  # NAME PATTERN make-arguments...
    local name=$1 pat=$2; shift 2
    k=$((k + 1))
    check_fails "$name" "$pat" make -s -C "$C" WEATHER="$T/w.wea" OUT="$T/r$k" RES=16 "$@"
    if [ ! -e "$T/r$k/suns.rad" ] && [ ! -e "$T/r$k/sun.oct" ] && [ ! -e "$T/r$k/scene/all.rad" ]; then pass "${name}_early"
    else fail "${name}_early" "a stage ran before the check: $(ls "$T/r$k" | tr '\n' ' ')"; fi
}
case_fails no_material "group 'north': MAT_north is not set" MAT_north=
case_fails missing_bsdf "group 'east_high': MAT_east_high=$T/none.xml: BSDF file not found" MAT_east_high="$T/none.xml"
printf 'void BSDF diffusing 6 0 nosuch_ttree.xml 0 0 1 . 0 0\n' > "$T/north_bsdf.rad"
case_fails missing_bsdf_in_rad "BSDF file nosuch_ttree.xml not found in RAYPATH" MAT_north="$T/north_bsdf.rad"
case_fails glare_not_fisheye "GLARE_VIEWS: corner.vf: .*fisheye" GLARE_VIEWS="desk.vf corner.vf"
case_fails weather_no_location "WEATHER: .*noloc.wea: line 1" WEATHER="$T/noloc.wea"
case_fails weather_no_location2 "WEATHER: .*noloc2.wea: line 2: .*latitude" WEATHER="$T/noloc2.wea"
case_fails same_group_twice "GROUPS: group 'north' is named twice" GROUPS="east_view east_high north north"
case_fails group_no_surface "group 'north': no surface with modifier 'frosted' \(MOD_north\) in GEOM_north=windows.rad" MOD_north=frosted MAT_north=glass
case_fails missing_geom "group 'skylight': GEOM_skylight=nosuch.rad: file not found" GEOM_skylight=nosuch.rad
case_fails no_weather "WEATHER is not set" WEATHER=
case_fails bad_group_name "GROUPS: 'east-view' is not a valid group name" GROUPS="east-view north"
printf '1 2 3 0 0\n' > "$T/bad.pts"
case_fails bad_sensors "SENSORS: .*bad.pts: line 1: expected x y z dx dy dz" SENSORS="$T/bad.pts"
case_fails bad_ground "GROUND_MOD=lawn: no surface with this modifier in SCENE" GROUND_MOD=lawn
# a good case passes the preflight alone
check preflight_ok make -s -C "$C" WEATHER="$T/w.wea" OUT="$T/ok" preflight
