#!/usr/bin/env bash
# Office (case B, GLASS, Chicago March 12 11:30, view v1): fisheye rpict
# 128x128 -ab 6 -ad N vs Radiance's 256x256 -ad 512 reference image
# (b1_glass_v1_chicago_0312.hdr, box-filtered by 2): luminance RMS over lit
# pixels, E_v and DGP (hdcompare).  Radiance's rpict beside when RADIANCE_BIN
# is set (small N only: it is slow).  Writes docs/benchmarks/sweep_office.tsv/.svg.
. "$(dirname "$0")/sweep_lib.sh"
OFF=$REF/scenes/office
[ -f "$OFF/b1_glass_v1_chicago_0312.hdr" ] || { echo "SKIP: $OFF not found"; exit 0; }
W=$ROOT/$BUILD/bench/sweep_office; mkdir -p "$W"
TSV=$DOCS/sweep_office.tsv; : > "$TSV.new"
header
cd "$OFF"
VIEW=$(sed "s/^rview //; s/^rvu //" v1.vf)
SC="mat_glass.rad office.rad sky_chicago_0312_1130.rad skyglow.rad"
OPT="-ab 6 -as 0 -aa 0 -lw 1e-4 -dj 0 -st 0 -lr 12"
REFIMG=b1_glass_v1_chicago_0312.hdr
printf "%-16s %6s %8s %9s %9s %9s %9s\n" who ad wall_s lum_rms Ev_rel DGP DGP_ref
row() { # who ad secs img
    "$BIN/hdcompare" -R 2 -vf v1.vf "$4" "$REFIMG" > "$W/c"
    printf "%-16s %6s %8.2f %9.4f %9.4f %9.4f %9.4f\n" "$1" "$2" "$3" "$(cmpval "$W/c" rms_rel)" "$(cmpval "$W/c" ev_rel)" \
        "$(cmpval "$W/c" dgp_test)" "$(cmpval "$W/c" dgp_ref)"
    printf "%s lum RMS\t%s\t%s\n" "$1" "$3" "$(cmpval "$W/c" rms_rel)" >> "$TSV.new"
    printf "%s |E_v| rel\t%s\t%s\n" "$1" "$3" "$(cmpval "$W/c" ev_rel | tr -d -)" >> "$TSV.new"
}
for ad in ${ADS:-32 128 512}; do
    t=$(now)
    "$BIN/rpict" -n 2 $VIEW -x 128 -y 128 $OPT -ad $ad $SC > "$W/h$ad.hdr"
    row heliodon $ad "$(elapsed "$t")" "$W/h$ad.hdr"
done
if [ -n "$RB" ]; then
    for ad in ${RADS:-32 128}; do
        t=$(now)
        "$RB/rpict" $VIEW -x 128 -y 128 -ps 1 -pj 0 $OPT -ad $ad office_glass_chicago_0312.oct > "$W/r$ad.hdr"
        row Radiance $ad "$(elapsed "$t")" "$W/r$ad.hdr"
    done
fi
mv "$TSV.new" "$TSV"
slopes "$TSV"
svgchart "$TSV" "$DOCS/sweep_office.svg" "Office v1 fisheye 128x128 vs Radiance 256x256 reference" "wall time (s, 2 cores)" "relative error"
echo "wrote $TSV and $DOCS/sweep_office.svg"
