#!/bin/bash
# The second shipped case of the annual pipeline (scenes/corner: a corner room facing east and north
# with a skylight; four window groups -- clear glass, a Klems BSDF XML, a diffusing 'trans' glazing,
# a skylight glass --, a fisheye glare view, a perspective view, a 12-point sensor grid) run through
# the INSTALLED pipeline (make install PREFIX=tmp; the case's Makefile includes
# $PREFIX/share/heliodon/heliodon.mk) at tiny settings: two days of a synthetic Berlin-like year,
# 64x64, MF:1.  For two hours the composite of the glare view is compared with heliodon's own
# converged backward rendering (rpict) with the sun at its patch centre: mean luminance within 10 %,
# DGP within 0.03; the sensor illuminances with rtrace -I at the same sky and sun: the grid mean
# within 10 % and every point in the sun within 10 %.  Also: the image-only view, the metrics (DA, UDI, ASE hours recomputed here from the
# hourly CSVs), and the report's sections.
. test/e2e/lib.sh
ROOT=$(pwd)
T=$(cd "$T" && pwd)
INST=$T/inst
if ! make -s install PREFIX="$INST" BUILD="${BUILD:-build}" > "$T/install.log" 2>&1; then
    fail install "$(tail -3 "$T/install.log" | tr '\n' ' ')"; exit 0
fi
MK=$INST/share/heliodon/heliodon.mk
if [ -r "$MK" ] && [ -x "$INST/share/heliodon/preflight.sh" ] && [ -r "$INST/share/man/man7/heliodon-pipeline.7" ]; then
    pass install
else
    fail install "no $MK, preflight.sh or man7 page"; exit 0
fi
export PATH="$INST/bin:$PATH"
cp -r "$ROOT/scenes/corner" "$T/case"
C=$T/case
genwea -a 52.5 -o -13.4 -m -15 -e 40 -n Berlin_synth "$T/year.wea"
{ head -6 "$T/year.wea"; awk 'NR > 6 && (($1 == 3 && $2 == 21) || ($1 == 10 && $2 == 15))' "$T/year.wea"; } > "$T/w.wea"
RUN=$T/run
if ! make -s -C "$C" HELIODON_MK="$MK" WEATHER="$T/w.wea" OUT="$RUN" RES=64 MF=1 PHOTONS=200k NPROC=2 \
        MAT_east_high="$ROOT/scenes/cfs/cfs1_klems.xml" FEN_OPTS="-ab 3 -ad 512 -lw 1e-4" \
        FENSUN_OPTS="-ab 1 -ad 64 -lw 1e-3" SENSOR_SUN_OPTS="-ab 3 -ad 512 -lw 1e-4" SENSOR_SKY_OPTS="-ab 3 -ad 512 -lw 1e-4" \
        > "$T/make.log" 2>&1; then
    fail run "$(grep -v 'no emission\|no photons stored' "$T/make.log" | tail -5 | tr '\n' ' ')"; exit 0
fi
pass run
nd=$(grep -vc '^#' "$RUN/desk/hours.log")
if [ "$nd" -ge 15 ] && [ "$(wc -l < "$RUN/desk/annual.csv")" = $((nd + 1)) ]; then pass glare_view_hours
else fail glare_view_hours "desk: $nd hours in the log, $(wc -l < "$RUN/desk/annual.csv") CSV lines"; fi
# the perspective view: images of the selected hours, no glare CSV
ni=$(ls "$RUN"/corner/selected/h*.hdr 2>/dev/null | wc -l)
if [ "$ni" = 3 ] && [ ! -e "$RUN/corner/annual.csv" ] && [ "$(grep -vc '^#' "$RUN/corner/hours.log")" = "$nd" ]; then pass image_view
else fail image_view "corner: $ni selected images, annual.csv $( [ -e "$RUN/corner/annual.csv" ] && echo present || echo absent)"; fi
# the groups are all photon ports and all in the mask
if grep -q 'mkpmap -apC .*-apo east_glass -apo blinds -apo diffusing -apo roof_glass' "$T/make.log" ||
   [ "$(grep -c 'glow' "$RUN/scene/mask.rad")" = 4 ]; then pass four_groups; else fail four_groups "mask.rad: $(cat "$RUN/scene/mask.rad")"; fi

# ---- references for two hours: Mar 21 10:30 (sun through the east windows), Oct 15 13:30 ----
cat > "$T/skyglow.rad" <<'EOF'
skyfunc glow sky_glow 0 0 4 1 1 1 0
sky_glow source sky 0 0 4 0 0 1 180
skyfunc glow ground_glow 0 0 4 1 1 1 0
ground_glow source ground 0 0 4 0 0 -1 180
EOF
export RAYPATH=".:$ROOT/scenes/cfs"
sel=$(grep -v '^#' "$RUN/desk/hours.log" | awk '($2 == 3 && $4 + 0 == 10.5) || ($2 == 10 && $4 + 0 == 13.5) {print $1}' | tr '\n' ' ')
set -- $sel
if [ $# != 2 ]; then fail hours "expected Mar 21 10:30 and Oct 15 13:30 in the run, got '$sel'"; exit 0; fi
for rec in $sel; do
    read -r _ mo da hr bin dx dy dz sr sg sb ml dgp <<< "$(grep -v '^#' "$RUN/desk/hours.log" | awk -v r="$rec" '$1 == r')"
    gendaylit "$mo" "$da" "$hr" -a 52.5 -o -13.4 -m -15 -W $(wea_record "$T/w.wea" "$mo" "$da" "$hr") -s > "$T/sky_$rec.rad"
    patchsun_rad "$T/sun_$rec.rad" "$sr" "$sg" "$sb" "$dx" "$dy" "$dz"
    (cd "$C" && oconv "$RUN/mat.rad" room.rad site.rad windows.rad "$T/sky_$rec.rad" "$T/skyglow.rad" "$T/sun_$rec.rad" > "$T/ref_$rec.oct")
done
{ for rec in $sel; do
    (cd "$C" && rpict -vf desk.vf -x 64 -y 64 -ps 1 -pj 0 -dj 0 -ab 4 -ad 1024 -as 0 -aa 0 -lw 1e-5 "$T/ref_$rec.oct" > "$T/ref_$rec.hdr") &
  done; wait; }
for rec in $sel; do
    read -r _ mo da hr bin dx dy dz sr sg sb ml dgp <<< "$(grep -v '^#' "$RUN/desk/hours.log" | awk -v r="$rec" '$1 == r')"
    rml=$(meanlum "$T/ref_$rec.hdr")
    rdgp=$(evalglare -vta -vh 180 -vv 180 "$T/ref_$rec.hdr" | awk '{print $2}')
    echo "corner desk view, record $rec ($mo/$da $hr): composite mean $ml DGP $dgp; reference mean $rml DGP $rdgp" >&2
    if close "$ml" "$rml" 0.10; then pass "mean_lum_$rec"; else fail "mean_lum_$rec" "composite $ml vs reference $rml cd/m2"; fi
    if awk -v a="$dgp" -v b="$rdgp" 'BEGIN{d=a-b; if(d<0)d=-d; exit !(d<=0.03)}'; then pass "dgp_$rec"
    else fail "dgp_$rec" "composite $dgp vs reference $rdgp"; fi
    # sensors: rtrace -I at the same sky and patch-centre sun
    (cd "$C" && rtrace -h -I -ab 4 -ad 2048 -as 0 -aa 0 -lw 1e-5 -dj 0 "$T/ref_$rec.oct" < grid.pts) |
        awk '{printf "%.6g\n", 179 * (.265 * $1 + .670 * $2 + .065 * $3)}' > "$T/refE_$rec.txt"
    awk -F, -v r="$rec" '$1 == r {for (i = 5; i <= NF; i++) print $i}' "$RUN/grid/illuminance.csv" > "$T/E_$rec.txt"
    echo "  sensors (lux, pipeline / rtrace -I): $(paste -d/ "$T/E_$rec.txt" "$T/refE_$rec.txt" | tr '\n' ' ')" >&2
    # the grid mean within 10 %; the points in the sun patch (direct sun through the east glass, exact
    # in both) each within 10 %.  The other points are not asserted one by one: the backward
    # references through the Klems blinds are not converged (rtrace -I at point 5, Mar 21 10:30:
    # 1877..3612 lx between -ab 2..6 / -ad 2048..8192), and the ground glow has one sunlit fraction
    # for the ground all the facades see (docs/design/pipeline.md)
    read -r pm rm nsun worst <<< "$(paste "$T/E_$rec.txt" "$T/refE_$rec.txt" | awk '{a += $1; b += $2; n++
        if ($2 > 20000) {k++; d = ($1 - $2) / $2; if (d < 0) d = -d; if (d > w) w = d}}
        END {printf "%.6g %.6g %d %.4f\n", a / n, b / n, k, w}')"
    echo "  grid mean $pm vs $rm lux; $nsun points in the sun, largest difference there $worst" >&2
    if [ "$(wc -l < "$T/E_$rec.txt")" = 12 ] && close "$pm" "$rm" 0.10; then pass "sensors_mean_$rec"
    else fail "sensors_mean_$rec" "grid mean $pm vs rtrace -I $rm lux ($(wc -l < "$T/E_$rec.txt") points)"; fi
    if le "$worst" 0.10; then pass "sensors_sunlit_$rec"; else fail "sensors_sunlit_$rec" "sunlit points differ by up to $worst"; fi
done

# ---- metrics: recomputed from the hourly CSVs (occupied 8-18 h; the weather's occupied hours) ----
nocc=$(awk 'NR > 6 && $3 >= 8 && $3 < 18' "$T/w.wea" | wc -l)
awk -F, -v nocc="$nocc" 'FNR == 1 {f++; next} $4 >= 8 && $4 < 18 {
        for (i = 5; i <= NF; i++) { if (f == 1 && $i >= 300) da[i]++; if (f == 1 && $i >= 300 && $i <= 3000) ua[i]++; if (f == 2 && $i >= 1000) as[i]++ } n = NF }
    END {for (i = 5; i <= n; i++) printf "%d,%.4f,%.4f,%d\n", i - 4, da[i] / nocc, ua[i] / nocc, as[i]}' \
    "$RUN/grid/illuminance.csv" "$RUN/grid/direct.csv" > "$T/metrics_here.csv"
if [ "$(awk -F, 'NR > 1 {print $1 "," $5 "," $8 "," $10}' "$RUN/grid/metrics.csv")" = "$(cat "$T/metrics_here.csv")" ] &&
   [ "$(wc -l < "$T/metrics_here.csv")" = 12 ]; then pass metrics
else fail metrics "metrics.csv (DA, UDI-a, ASE hours) differ from the recomputation: $(head -2 "$T/metrics_here.csv" | tr '\n' ' ')"; fi
# direct-sun-only ASE input: the points in the sun patch see the sun, the others get less than the total
if awk -F, 'FNR == 1 {f++; next} f == 1 {for (i = 5; i <= NF; i++) t[FNR, i] = $i} f == 2 {for (i = 5; i <= NF; i++) if ($i > t[FNR, i] * 1.001 + 1) bad = 1}
        END {exit bad}' "$RUN/grid/illuminance.csv" "$RUN/grid/direct.csv"; then pass direct_below_total
else fail direct_below_total "direct-sun illuminance above the total"; fi
if grep -q '^sDA_300_50%: ' "$RUN/grid/metrics_summary.txt" && grep -q '^ASE_1000_250h: ' "$RUN/grid/metrics_summary.txt"; then pass metrics_summary
else fail metrics_summary "$(head -3 "$RUN/grid/metrics_summary.txt" | tr '\n' ' ')"; fi
# ---- report: a section per view and per sensor grid; the glare view's page and figures ----
R=$RUN/report
if grep -q 'id="view-desk"' "$R/index.html" && grep -q 'id="view-corner"' "$R/index.html" && grep -q 'id="sensors-grid"' "$R/index.html" &&
   [ -s "$R/desk/index.html" ] && [ "$(ls "$R"/desk/fc_*.png | wc -l)" = 3 ] && [ "$(ls "$R"/corner/h*.hdr | wc -l)" = 3 ]; then pass report
else fail report "sections or files missing in $R"; fi
missing=""
for f in $(grep -o 'src="[^"]*"\|href="[^"#]*"' "$R/index.html" | sed 's/^[a-z]*="//; s/"$//'); do [ -s "$R/$f" ] || missing="$missing $f"; done
if [ -z "$missing" ]; then pass report_refs; else fail report_refs "missing:$missing"; fi
