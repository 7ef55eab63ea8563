#!/usr/bin/env bash
# Sun-discretisation error (issue 10): the clear-sky sun of the reference box
# (Jan 1 10:30, sun-only light source, radiance 5.181e6) moved to the centre
# of its Reinhart MF:1, 2, 4, 6 patch (as a patch-centre sun DC does), vs the
# sun at its real position, same renderer and settings:
#   sensors  rtrace -ab 0 (direct only, exact) and -ab 4 -ad 2048 (all light)
#   fisheye  rpict 64x64 -ab 1 -ad 128, fish.vf: E_v and DGP (hdcompare)
# Radiance's own MF:1 figure (a4_res/patchsun_mf1_conv.dat vs
# a1_sunonly_conv.dat) is printed beside ours.  Writes
# docs/benchmarks/sweep_sun.tsv and docs/benchmarks/sweep_sun.svg.
. "$(dirname "$0")/sweep_lib.sh"
[ -f "$BOX/sun_clear_0101_1030.rad" ] || { echo "SKIP: $BOX not found"; exit 0; }
make -s BUILD="$BUILD" "$BUILD/bench/bench_sweep_patchsun" >/dev/null
PS=$ROOT/$BUILD/bench/bench_sweep_patchsun
W=$ROOT/$BUILD/bench/sweep_sun; mkdir -p "$W"
TSV=$DOCS/sweep_sun.tsv; : > "$TSV.new"
header
cd "$BOX"
ROOM="box_room.rad box_window.rad"
SUN="0.335220 -0.863972 0.375740"
VIEW=$(sed "s/^rview //; s/^rvu //" fish.vf)
run() { # name sunfile
    "$BIN/rtrace" -n 2 -I+ -ab 0 $ROOM "$2" < sensors.pts > "$W/$1.ab0"
    "$BIN/rtrace" -n 2 -I+ -ab 4 -ad 2048 -lw 2e-5 $ROOM "$2" < sensors.pts > "$W/$1.ab4"
    "$BIN/rpict" -n 2 $VIEW -x 64 -y 64 -ab 1 -ad 128 -lw 1e-3 $ROOM "$2" > "$W/$1.hdr"
}
sunfile() { printf 'void light solar 0 0 3 5.181e+06 5.181e+06 5.181e+06\nsolar source sun 0 0 4 %s %s %s 0.533\n' "$2" "$3" "$4" > "$1"; }
sunfile "$W/real.rad" $SUN
run real "$W/real.rad"
printf "%-4s %6s %9s %12s %12s %12s %12s %10s %10s\n" MF bin angle_deg ab0_rms ab0_floor ab4_rms ab4_floor Ev_rel dDGP
for mf in 1 2 4 6; do
    set -- $("$PS" $mf $SUN)
    bin=$1; ang=$5
    sunfile "$W/mf$mf.rad" "$2" "$3" "$4"
    run "mf$mf" "$W/mf$mf.rad"
    "$BIN/hdcompare" -m "$W/mf$mf.ab0" "$W/real.ab0" > "$W/c0"
    "$BIN/hdcompare" -m "$W/mf$mf.ab4" "$W/real.ab4" > "$W/c4"
    "$BIN/hdcompare" -vf fish.vf "$W/mf$mf.hdr" "$W/real.hdr" > "$W/ci"
    # floor mean (points 0-24) relative error
    fl() { paste <(awk 'b{print} /^$/{b=1}' "$1") <(awk 'b{print} /^$/{b=1}' "$2") | head -25 |
           awk '{a+=.265*$1+.670*$2+.065*$3; r+=.265*$4+.670*$5+.065*$6} END{printf "%.4f", a/r-1}'; }
    printf "%-4s %6s %9.3f %12.4f %12s %12.4f %12s %10.4f %10.4f\n" $mf $bin $ang "$(cmpval "$W/c0" rms_rel)" \
        "$(fl "$W/mf$mf.ab0" "$W/real.ab0")" "$(cmpval "$W/c4" rms_rel)" "$(fl "$W/mf$mf.ab4" "$W/real.ab4")" \
        "$(cmpval "$W/ci" ev_rel)" "$(cmpval "$W/ci" dgp_diff)"
    printf "sensors -ab 4 RMS\t%s\t%s\n" $mf "$(cmpval "$W/c4" rms_rel)" >> "$TSV.new"
    printf "sensors -ab 0 RMS\t%s\t%s\n" $mf "$(cmpval "$W/c0" rms_rel)" >> "$TSV.new"
    printf "fisheye |E_v| rel\t%s\t%s\n" $mf "$(cmpval "$W/ci" ev_rel | tr -d -)" >> "$TSV.new"
done
"$BIN/hdcompare" -m a4_res/patchsun_mf1_conv.dat a1_sunonly_conv.dat > "$W/cr"
echo "Radiance MF:1 (a4_res/patchsun_mf1_conv.dat vs a1_sunonly_conv.dat, converged rtrace): rms_rel $(cmpval "$W/cr" rms_rel), total_rel $(cmpval "$W/cr" total_rel)"
printf "Radiance sensors conv RMS\t1\t%s\n" "$(cmpval "$W/cr" rms_rel)" >> "$TSV.new"
if [ -f a4_res/patchsun_mf2_conv.dat ]; then
    "$BIN/hdcompare" -m a4_res/patchsun_mf2_conv.dat a1_sunonly_conv.dat > "$W/cr"
    echo "Radiance MF:2: rms_rel $(cmpval "$W/cr" rms_rel), total_rel $(cmpval "$W/cr" total_rel)"
    printf "Radiance sensors conv RMS\t2\t%s\n" "$(cmpval "$W/cr" rms_rel)" >> "$TSV.new"
fi
mv "$TSV.new" "$TSV"
svgchart "$TSV" "$DOCS/sweep_sun.svg" "Sun at its MF patch centre vs real position (box, Jan 1 10:30)" "Reinhart MF" "relative error"
echo "wrote $TSV and $DOCS/sweep_sun.svg"
