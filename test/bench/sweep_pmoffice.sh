#!/usr/bin/env bash
# Office photon-map DC sweep (issue 10): the reference office of
# ../shared/ref/scenes/office (GLASS, view v1, 64x64 fisheye), lit by the
# Chicago March 12 11:30 sun (sky_chicago_0312_1130.rad: radiance 7.241e6)
# moved to the centre of its Reinhart MF:1 patch, as a sun daylight
# coefficient sees it.  Contribution photon maps for all 145 MF:1 suns
# (gensuns -a: one unit-radiance source per patch, the per-source photon
# budget of a real annual run), photon ports on the three window groups,
# then rcontrib -ab -1 -ap for the sun's bin, scaled by the sun radiance
# (hdcompare -s) and compared with heliodon's converged backward rendering of
# the same patch-centre sun (rpict -ab 6 -ad 2048, 64x64) with the exterior
# ground and building black: photons enter through the ports in the sun's
# direction only, so sunlight reflected by the exterior is not part of a sun
# DC (the method leaves it to the sky part's ground).  Luminance RMS over
# lit pixels (reference above 10 % of its mean: the black exterior seen
# through the glass is left out), E_v and DGP.  Photon count x bandwidth; Radiance's
# mkpmap/rcontrib at the same settings when RADIANCE_BIN is set.
# Writes docs/benchmarks/sweep_pmoffice.tsv / .svg.
. "$(dirname "$0")/sweep_lib.sh"
OFF=$REF/scenes/office
[ -f "$OFF/office.rad" ] || { echo "SKIP: $OFF not found"; exit 0; }
make -s BUILD="$BUILD" "$BUILD/bench/bench_sweep_patchsun" >/dev/null
PS=$ROOT/$BUILD/bench/bench_sweep_patchsun
W=$ROOT/$BUILD/bench/sweep_pmoffice; mkdir -p "$W"
TSV=$DOCS/sweep_pmoffice.tsv; : > "$TSV.new"
header
RES=${RES:-64}
cd "$OFF"
SUN="0.137433 -0.712941 0.687624"; SUNRAD=7.241e6
set -- $("$PS" 1 $SUN); BIN_=$1
echo "sun Mar 12 11:30 -> MF:1 patch $BIN_ (centre $2 $3 $4, $5 deg off)"
printf 'void light solar 0 0 3 %s %s %s\nsolar source sun 0 0 4 %s %s %s 0.533\n' $SUNRAD $SUNRAD $SUNRAD "$2" "$3" "$4" > "$W/patchsun.rad"
VIEW=$(sed "s/^rview //; s/^rvu //" v1.vf)
VW="$VIEW -x $RES -y $RES"
REFH=$W/ref_${RES}_${REFAD:-2048}.hdr
if [ ! -s "$REFH" ]; then
    t=$(now)
    sed 's/^void plastic \(ground_mat\|building_mat\) .*/void plastic \1 0 0 5 0 0 0 0 0/' office.rad > "$W/office_blackext.rad"
    "$BIN/rpict" -n 2 $VW -ps 1 -pj 0 -ab 6 -ad ${REFAD:-2048} -as 0 -aa 0 -lw 1e-5 -dj 0 -st 0 -lr 12 mat_glass.rad "$W/office_blackext.rad" "$W/patchsun.rad" > "$REFH"
    echo "reference: rpict -ab 6 -ad ${REFAD:-2048} ${RES}x$RES, $(elapsed "$t") s"
fi
"$BIN/genwea" -a 41.98 -o 87.92 -m 90 -n chicago "$W/chicago.wea" 2>/dev/null
"$BIN/gensuns" -m 1 -a -M "$W/mods.txt" -o "$W/suns.rad" "$W/chicago.wea"
PORTS="-apo wg1_mat -apo wg2_mat -apo wg3_mat"
NS=$(wc -l < "$W/mods.txt")
printf "%-10s %8s %6s %8s %8s %9s %9s %9s %9s\n" who photons bw build_s gather_s lum_rms Ev_rel dDGP peak_MB
point() { # who N BW build_s bin map
    local t g; t=$(now)
    "$BIN/vwrays" -ff $VW | rss "$5/rcontrib" -ffc $("$BIN/vwrays" -d $VW) -n 2 -ab -1 -ap "$6" "$3" -fo \
        -o "$W/g_%s.hdr" -m solar$BIN_ "$7" 2>"$W/err" || { echo "$1 $2 $3: gather failed: $(head -2 "$W/err")"; return; }
    g=$(elapsed "$t")
    "$BIN/hdcompare" -f -0.1 -s $SUNRAD -vf v1.vf "$W/g_solar$BIN_.hdr" "$REFH" > "$W/c"
    printf "%-10s %8s %6s %8.2f %8.2f %9.4f %9.4f %9.4f %9s\n" "$1" "$2" "$3" "$4" "$g" "$(cmpval "$W/c" rms_rel)" \
        "$(cmpval "$W/c" ev_rel)" "$(cmpval "$W/c" dgp_diff)" "$BRSS/$(rssmb)"
    local tot; tot=$(awk -v a="$4" -v b="$g" 'BEGIN{print a+b}')
    printf "%s bw %s lum RMS\t%s\t%s\n" "$1" "$3" "$tot" "$(cmpval "$W/c" rms_rel)" >> "$TSV.new"
    printf "%s bw %s |E_v| rel\t%s\t%s\n" "$1" "$3" "$tot" "$(cmpval "$W/c" ev_rel | tr -d -)" >> "$TSV.new"
}
"$BIN/oconv" mat_glass.rad office.rad "$W/suns.rad" > "$W/h.oct"
if [ -n "$RB" ]; then "$RB/oconv" mat_glass.rad office.rad "$W/suns.rad" > "$W/r.oct"; fi
for n in ${PHOTONS:-300k 1m 3m}; do
    t=$(now)
    rss "$BIN/mkpmap" -fo -apC "$W/h$n.pm" $n $PORTS -apr 1 -n 2 "$W/h.oct" 2>"$W/err" >/dev/null ||
        { echo "mkpmap $n failed: $(head -2 "$W/err")"; continue; }
    b=$(elapsed "$t"); BRSS=$(rssmb)
    for bw in ${BWS:-$NS $((NS * 10))}; do point heliodon $n $bw "$b" "$BIN" "$W/h$n.pm" "$W/h.oct"; done
    if [ -n "$RB" ] && [ -x "$RB/mkpmap" ]; then
        rm -rf "$W/r$n.pm" "$W/r$n.leaf"
        t=$(now)
        if rss "$RB/mkpmap" -fo -apC "$W/r$n.pm" $n $PORTS -apr 1 -n 2 "$W/r.oct" >/dev/null 2>"$W/err"; then
            b=$(elapsed "$t"); BRSS=$(rssmb)
            for bw in ${BWS:-$NS $((NS * 10))}; do point Radiance $n $bw "$b" "$RB" "$W/r$n.pm" "$W/r.oct"; done
        else echo "Radiance mkpmap $n failed: $(head -2 "$W/err")"; fi
    fi
done
mv "$TSV.new" "$TSV"
slopes "$TSV"
svgchart "$TSV" "$DOCS/sweep_pmoffice.svg" "Office v1 PM-CBDM sun DC (145 MF:1 suns, ${RES}x$RES) vs converged backward" "wall time (s, 2 cores)" "relative error"
echo "wrote $TSV and $DOCS/sweep_pmoffice.svg"
