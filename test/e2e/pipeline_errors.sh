#!/bin/bash
# Bad inputs of the annual pipeline give clear errors, non-zero exits and no crash, before any
# long computation starts (no sun sources, photon map or coefficient pictures are made).
. test/e2e/lib.sh
ROOT=$(pwd)
T=$(cd "$T" && pwd)
O=$ROOT/scenes/office
izmir_wea "$T/day.wea" '3 21 10.5 820 110'
izmir_wea "$T/night.wea" '3 21 1.5 0 0' '3 21 23.5 0 0' '6 21 12.5 0 0'
echo "rview -vtv -vp 1 2.2 1.2 -vd 1 0 0 -vu 0 0 1 -vh 60 -vv 60" > "$T/persp.vf"

# missing BSDF file: the configuration check runs first
check_fails missing_bsdf "BSDF file .*cfs1_ttree.xml not found" \
    make -s -C "$O" WEATHER="$T/day.wea" CONFIG=fs1 CFSDIR="$T/nocfs" OUT="$T/r1"
if [ ! -e "$T/r1/suns.rad" ]; then pass missing_bsdf_early; else fail missing_bsdf_early "suns were made"; fi
# weather without daylight hours
check_fails night_weather "no daylight hours" \
    make -s -C "$O" WEATHER="$T/night.wea" CONFIG=glass OUT="$T/r2"
if [ ! -e "$T/r2/suns.rad" ]; then pass night_weather_early; else fail night_weather_early "suns were made"; fi
check_fails night_gensuns "night.wea: no daylight hours" gensuns -m 1 "$T/night.wea"
check_fails night_pmcompose "no daylight hours" pmcompose -P -w "$T/night.wea" -vf "$O/v1.vf"
# view that is not a fisheye
check_fails persp_view "fisheye|-vta|-vth" \
    make -s -C "$O" WEATHER="$T/day.wea" CONFIG=glass VIEW="$T/persp" OUT="$T/r3"
if [ ! -e "$T/r3/suns.rad" ]; then pass persp_view_early; else fail persp_view_early "suns were made"; fi
check_fails persp_pmcompose "fisheye|-vta|-vth" pmcompose -P -w "$T/day.wea" -vf "$T/persp.vf"
check_fails view_incomplete "must contain -vt" pmcompose -P -w "$T/day.wea" -vta
check_fails no_weather "weather file not found" make -s -C "$O" WEATHER="$T/none.wea" OUT="$T/r4"
check_fails bad_config "mat_nosuch.rad" make -s -C "$O" WEATHER="$T/day.wea" CONFIG=nosuch OUT="$T/r5"
# missing sun coefficient picture: named, with the sun patch, before the hourly loop
mkdir -p "$T/dc"
check_fails missing_dcsun "solar[0-9]+\.hdr: missing sun coefficient picture for sun patch [0-9]+" \
    pmcompose -w "$T/day.wea" -vf "$O/v1.vf" -s "$T/dc/solar%d.hdr" -o "$T/x.csv"
if [ ! -e "$T/x.csv" ]; then pass missing_dcsun_no_output; else fail missing_dcsun_no_output "CSV written"; fi
check_fails bad_pattern "exactly one %d" pmcompose -w "$T/day.wea" -vf "$O/v1.vf" -s "$T/dc/solar.hdr"
check_fails bad_mf "MF:0 out of range" gensuns -m 0 "$T/day.wea"
# sunlit ground fractions (-G): per sun patch, so only with -s; every bad line named
printf '3 0.5\n' > "$T/g_ok.txt"
check_fails ground_needs_sun "need the sun DC \(-s\)" pmcompose -w "$T/day.wea" -vf "$O/v1.vf" -k "$T/dc/%03d.hdr" -G "$T/g_ok.txt"
printf '# c\n3 0.5\n7 half\n' > "$T/g_bad.txt"
check_fails ground_bad_line "g_bad.txt: line 3: expected 'patch fraction'" \
    pmcompose -w "$T/day.wea" -vf "$O/v1.vf" -s "$T/dc/solar%d.hdr" -G "$T/g_bad.txt"
printf '146 0.5\n' > "$T/g_range.txt"
check_fails ground_bad_patch "g_range.txt: line 1: sun patch 146 outside 1..145" \
    pmcompose -w "$T/day.wea" -vf "$O/v1.vf" -s "$T/dc/solar%d.hdr" -G "$T/g_range.txt"
printf '3 1.5\n' > "$T/g_frac.txt"
check_fails ground_bad_fraction "g_frac.txt: line 1: fraction 1.5 outside 0..1" \
    pmcompose -w "$T/day.wea" -vf "$O/v1.vf" -s "$T/dc/solar%d.hdr" -G "$T/g_frac.txt"
check_fails ground_missing "nosuch.txt: cannot read" \
    pmcompose -w "$T/day.wea" -vf "$O/v1.vf" -s "$T/dc/solar%d.hdr" -G "$T/nosuch.txt"
# report inputs
printf 'hour,Ev,DGP,DGI,UGR,nsources,DGP_class,DGI_class,shade\n10.5,100,0.3\n' > "$T/bad.csv"
check_fails bad_csv "bad.csv: line 2" cbdmreport -c "$T/bad.csv" -o "$T/rep"
printf 'not a png' > "$T/x.png"
check_fails bad_png "not a PNG" cbdmreport -check "$T/x.png"
# pmmask: the ray stream must match the mask
printf '#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 2\n' > "$T/m.hdr"
printf '\200\200\200\201\200\200\200\201\0\0\0\0\0\0\0\0' >> "$T/m.hdr"
head -c 48 /dev/zero > "$T/short.ff"
check_fails pmmask_short "ended before the 4 rays" pmmask "$T/m.hdr" "$T/short.ff"
# two-pass shade run: both configurations are checked before either pass starts
check_fails twopass_missing_bsdf "BSDF file .*cfs3_ttree.xml not found" \
    make -s -C "$O" WEATHER="$T/day.wea" CONFIG=fs2 CFSDIR="$T/nocfs" OUT="$T/r6"
if [ ! -e "$T/r6/open/suns.rad" ]; then pass twopass_missing_bsdf_early; else fail twopass_missing_bsdf_early "open pass started"; fi
check_fails twopass_bad_closed "mat_nosuch.rad" \
    make -s -C "$O" WEATHER="$T/day.wea" CONFIG=fs2x SHADE_CLOSED=nosuch OUT="$T/r7"
if [ ! -e "$T/r7/open/suns.rad" ]; then pass twopass_bad_closed_early; else fail twopass_bad_closed_early "open pass started"; fi
check_fails twopass_night "no daylight hours" make -s -C "$O" WEATHER="$T/night.wea" CONFIG=fs2x OUT="$T/r8"
check_fails twopass_persp "fisheye|-vta|-vth" make -s -C "$O" WEATHER="$T/day.wea" CONFIG=fs2x VIEW="$T/persp" OUT="$T/r9"
if [ ! -e "$T/r9/open/suns.rad" ]; then pass twopass_persp_early; else fail twopass_persp_early "open pass started"; fi
