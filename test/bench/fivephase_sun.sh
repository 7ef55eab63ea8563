#!/usr/bin/env bash
# The five-phase method's sun part (step 4 of pipeline/fivephase.mk: MF:6 direct-sun coefficients
# times the reflectance map plus the sun seen through the windows) against the exact sun rendered
# backward by Radiance: the office with clear glass, view v2, 64x64, four sunny hours of the
# Izmir-like e2e site (DNI 800, DHI 100 W/m2).
#   The 5PM sun part of an hour: pmcompose -m 6 -s OUT/5pm/v2/cds/solar%d.hdr (that term alone).
#   The reference: gendaylit's sun direction for the hour (Radiance's), with the radiance of the
#   hour's sun vector (the 5PM's hour log), rpict -ab 0 (the direct sun and its one reflection, the
#   sun seen through the glass) at 512x512 box-filtered to 64x64 (pfilt -1), and the same at 64x64;
#   the exterior surfaces (ground, building opposite) are black in the reference: the sunlight they
#   reflect, seen through the glass, is in the 5PM's three-phase part.
# E_v by evalglare -d on the images.  Usage (from the worktree, after make):
#   RADBIN=/path/to/radiance/bin test/bench/fivephase_sun.sh [FIVE_OS] [OUT]
set -eu
ROOT=$(pwd)
export PATH=$ROOT/${BUILD:-build}/bin:$PATH
RADBIN=${RADBIN:-$ROOT/../rad/inst/bin}
[ -x "$RADBIN/rpict" ] || { echo "fivephase_sun: no Radiance rpict in RADBIN=$RADBIN"; exit 0; }
RADLIB=${RADLIB:-$RADBIN/../lib}
OS=${1:-1}
R=$(mkdir -p "${2:-$ROOT/build/bench/fivephase_sun}" && cd "${2:-$ROOT/build/bench/fivephase_sun}" && pwd)
W=$R/w.wea
printf '%s\n' "place Izmir_bench" "latitude 38.4" "longitude -27.1" "time_zone -30" "site_elevation 25" \
    "weather_data_file_units 1" "3 21 10.5 800 100" "3 21 14.5 800 100" "6 21 9.5 800 100" "12 21 12.5 800 100" > "$W.new"
cmp -s "$W.new" "$W" 2>/dev/null && rm "$W.new" || mv "$W.new" "$W"
cd scenes/office
echo "load before: $(cat /proc/loadavg)"
rm -rf "$R/5pm/v2/cdsi" "$R/5pm/v2/cdsl" "$R/5pm/v2/cds"   # step 4 again for this FIVE_OS
t0=$(date +%s.%N)
make -s WEATHER="$W" OUT="$R" CONFIG=glass VIEW=v2 RES=64 NPROC=2 MF=6 METHOD=5pm KLEMS_WG1=glass FIVE_OS="$OS" > "$R/make.log" 2>&1 ||
    { tail -5 "$R/make.log"; exit 1; }
t1=$(date +%s.%N)
echo "METHOD=5pm FIVE_OS=$OS: $(awk -v a="$t0" -v b="$t1" 'BEGIN{printf "%.1f", b - a}') s (make, this run); step 4: $(grep -E '^5pm_(rcontrib_sun|rcontrib_fen|pcomb_sun)_v2' "$R/timings.txt" | tail -3 | tr '\n' ' ')"
ev() { evalglare -d -vf v2.vf "$1" 2>/dev/null | awk -F: '/^dgp,av_lum,E_v/ {split($2, v, " "); print v[3]}'; }
sed -e 's/^void plastic ground_mat .*/void plastic ground_mat 0 0 5 0 0 0 0 0/' \
    -e 's/^void plastic building_mat .*/void plastic building_mat 0 0 5 0 0 0 0 0/' room.rad > "$R/ref_room.rad"
echo "| hour | exact sun (gendaylit) | MF:6 patch | reference 512² → 64² E_v (lx) | 5PM sun part | reference at 64² | rpict 512² (s) |"
echo "|---|---|---|---|---|---|---|"
grep -v '^#' "$R/5pm/v2/hours.log" | while read -r rec mo da hr sb dx dy dz sr sg sbb ml dgp; do
    pmcompose -n 2 -w "$W" -vf v2.vf -m 6 -s "$R/5pm/v2/cds/solar%d.hdr" -noglare -r "$rec" -I "$R/sun5_%d.hdr" 2>/dev/null
    d=$("$RADBIN/gendaylit" "$mo" "$da" "$hr" -a 38.4 -o -27.1 -m -30 -W 800 100 |
        awk '$2 == "source" && $3 == "sun" {getline; getline; getline; print $2, $3, $4}')
    printf 'void light xsun 0 0 3 %s %s %s\nxsun source sun 0 0 4 %s 0.533\n' "$sr" "$sg" "$sbb" "$d" > "$R/xsun_$rec.rad"
    RAYPATH=.:$RADLIB "$RADBIN/oconv" mat_glass.rad "$R/ref_room.rad" windows.rad "$R/xsun_$rec.rad" > "$R/xsun_$rec.oct"
    r0=$(date +%s.%N)
    RAYPATH=.:$RADLIB "$RADBIN/rpict" -vf v2.vf -x 512 -y 512 -ps 1 -pj 0 -dj 0 -ab 0 -av 0 0 0 "$R/xsun_$rec.oct" > "$R/xref512_$rec.hdr"
    r1=$(date +%s.%N)
    "$RADBIN/pfilt" -1 -x 64 -y 64 "$R/xref512_$rec.hdr" > "$R/xref8_$rec.hdr"
    RAYPATH=.:$RADLIB "$RADBIN/rpict" -vf v2.vf -x 64 -y 64 -ps 1 -pj 0 -dj 0 -ab 0 -av 0 0 0 "$R/xsun_$rec.oct" > "$R/xref_$rec.hdr"
    a=$(ev "$R/sun5_$rec.hdr"); b=$(ev "$R/xref8_$rec.hdr"); c=$(ev "$R/xref_$rec.hdr")
    awk -v m="$mo" -v d="$da" -v h="$hr" -v a="$a" -v b="$b" -v c="$c" -v dir="$d" -v s="$dx $dy $dz" -v t="$(awk -v a="$r0" -v b="$r1" 'BEGIN{print b - a}')" \
        'BEGIN {printf "| %d/%d %.2f h | %s | %s | %.1f | %.1f (%+.1f %%) | %.1f (%+.1f %%) | %.1f |\n", m, d, h, dir, s, b, a, 100 * (a / b - 1), c, 100 * (c / b - 1), t}'
done
echo "load after: $(cat /proc/loadavg)"
