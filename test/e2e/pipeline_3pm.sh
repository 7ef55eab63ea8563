#!/bin/bash
# Three-phase sky part of the annual pipeline (SKYMETHOD=3pm: V per window group by rfluxmtx,
# D per group, T = Klems BSDF, folded by pmcompose) against Radiance: the shared reference
# b1_fs1s_v1_chicago_1221_1230 (CFS1 on all groups, December 21 12:30 Chicago, an overcast hour:
# DNI 7, DHI 170 W/m2).  The sun is left out (SUN=0; the weak sun's share of E_v is small), the
# composite must match Radiance's E_v within 5 % and DGP within 0.01.
. test/e2e/lib.sh
ROOT=$(pwd)
T=$(cd "$T" && pwd)
R=$REF/scenes/office/b1_fs1s_v1_chicago_1221_1230.evalglare.txt
X=$REF/bsdf/cfs1/cfs1_klems.xml
if [ ! -r "$R" ] || [ ! -r "$X" ]; then skip fs1s_chicago "no shared reference ($R, $X)"; exit 0; fi
R=$(cd "$(dirname "$R")" && pwd)/$(basename "$R"); X=$(cd "$(dirname "$X")" && pwd)/$(basename "$X")
cat > "$T/c.wea" <<'W'
place Chicago
latitude 41.98
longitude 87.92
time_zone 90
site_elevation 190
weather_data_file_units 1
12 21 2.5 0 0
12 21 12.5 7 170
W
if ! make -s -C "$ROOT/scenes/office" WEATHER="$T/c.wea" OUT="$T/run" CONFIG=fs1s CFSDIR="$(dirname "$X")" \
        SKYMETHOD=3pm KLEMS_WG1="$X" SUN=0 FEN=0 RES=64 NPROC=2 > "$T/make.log" 2>&1; then
    fail run "$(tail -5 "$T/make.log" | tr '\n' ' ')"; exit 0
fi
pass run
read -r rdgp rev <<< "$(awk -F': ' '/^dgp,/ {split($2, v, " "); print v[1], v[3]}' "$R")"
read -r ev dgp <<< "$(tail -1 "$T/run/v1/annual.csv" | awk -F, '{print $2, $3}')"
echo "3pm composite: Ev $ev DGP $dgp; Radiance: Ev $rev DGP $rdgp" >&2
if close "$ev" "$rev" 0.05; then pass ev; else fail ev "Ev $ev vs Radiance $rev"; fi
if awk -v a="$dgp" -v b="$rdgp" 'BEGIN{d=a-b; if(d<0)d=-d; exit !(d<=0.01)}'; then pass dgp; else fail dgp "DGP $dgp vs Radiance $rdgp"; fi
n=$(ls "$T/run/v1/v/wg2" | wc -l)
if [ "$n" = 145 ]; then pass v_pictures; else fail v_pictures "expected 145 Klems V pictures for wg2, got $n"; fi
check_fails missing_klems "Klems BSDF for wg1 not found" make -s -C "$ROOT/scenes/office" WEATHER="$T/c.wea" \
    OUT="$T/run2" CONFIG=fs1s CFSDIR="$(dirname "$X")" SKYMETHOD=3pm KLEMS_WG1="$T/none.xml" SUN=0 FEN=0 RES=16
if [ ! -e "$T/run2/v1/v" ] && [ ! -e "$T/run2/d_wg1.mtx" ]; then pass missing_klems_early; else fail missing_klems_early "V/D matrices were computed"; fi
