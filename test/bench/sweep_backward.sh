#!/usr/bin/env bash
# Error vs wall time of the backward methods on the reference box (28
# sensors), against converged references:
#   rtrace  -ab 6 -ad N -lw 0.05/N (clear sky, Jan 1 10:30) vs heliodon's own
#           -ab 6 -ad 65536 render (-ab 8 is noisier: see accuracy.md) and vs Radiance's a1_clear_conv.dat;
#   3PM     V = rfluxmtx -ab 6 -ad N (sensors), T = glass_klems.xml,
#           D = a3_D.dmx, S = a3_skyonly_mf1_3h.smx (3 hours) vs the same with
#           V at -ad 131072;
#   Radiance rtrace and rfluxmtx (V) with the same options when RADIANCE_BIN is set.
# Then the parameter choice (issue 10 item 4): from a pilot at -ad 128 the
# 1/sqrt(N) law predicts the -ad for a target error; the run at that -ad
# reports the achieved error.  Writes docs/benchmarks/sweep_backward.tsv and
# docs/benchmarks/sweep_backward.svg.   Usage: BUILD=build bash test/bench/sweep_backward.sh
. "$(dirname "$0")/sweep_lib.sh"
[ -f "$BOX/sensors.pts" ] || { echo "SKIP: $BOX not found"; exit 0; }
W=$ROOT/$BUILD/bench/sweep_backward; mkdir -p "$W"
TSV=$DOCS/sweep_backward.tsv; : > "$TSV.new"
header
cd "$BOX"
SKY="sky_clear_0101_1030.rad skyglow.rad"
ROOM="box_room.rad box_window.rad"
lw() { awk -v a="$1" 'BEGIN{printf "%.3g", 0.05/a}'; }
t=$(now)
"$BIN/rtrace" -n 2 -I+ -ab 6 -ad 65536 -lw "$(lw 65536)" -dj 0 -st 0 -lr 12 $ROOM $SKY < sensors.pts > "$W/own_conv.dat"
echo "heliodon converged rtrace (-ab 6 -ad 65536 -lw 7.6e-7): $(elapsed "$t") s"
"$BIN/hdcompare" -m "$W/own_conv.dat" a1_clear_conv.dat > "$W/c"
echo "  vs Radiance a1_clear_conv: rms_rel $(cmpval "$W/c" rms_rel), max_rel $(cmpval "$W/c" max_rel), total_rel $(cmpval "$W/c" total_rel)"
printf "%-22s %8s %9s %7s %12s %12s\n" method N wall_s peakMB rms_vs_own rms_vs_radconv
for ad in 64 128 256 512 1024 2048 4096 8192; do
    tmem "$W/rt$ad.dat" "$BIN/rtrace" -n 2 -I+ -ab 6 -ad $ad -lw "$(lw $ad)" -dj 0 -st 0 -lr 12 $ROOM $SKY < sensors.pts
    e=$TM_WALL; m=$TM_RSS
    "$BIN/hdcompare" -m "$W/rt$ad.dat" "$W/own_conv.dat" > "$W/c1"
    "$BIN/hdcompare" -m "$W/rt$ad.dat" a1_clear_conv.dat > "$W/c2"
    printf "%-22s %8d %9.3f %7s %12.4f %12.4f\n" "heliodon rtrace" $ad "$e" "$m" "$(cmpval "$W/c1" rms_rel)" "$(cmpval "$W/c2" rms_rel)"
    printf "heliodon rtrace\t%s\t%s\n" "$e" "$(cmpval "$W/c2" rms_rel)" >> "$TSV.new"
    printf "heliodon rtrace (own ref)\t%s\t%s\n" "$e" "$(cmpval "$W/c1" rms_rel)" >> "$TSV.new"
    if [ -n "$RB" ] && [ $ad -le 4096 ]; then
        tmem "$W/rrt$ad.raw" "$RB/rtrace" -n 2 -h -I+ -ab 6 -ad $ad -as 0 -aa 0 -lw "$(lw $ad)" -dj 0 -dt 0 -dc 1 -st 0 -lr 12 box_clear.oct < sensors.pts
        e=$TM_WALL; m=$TM_RSS
        { printf '#?RADIANCE\nNCOMP=3\nFORMAT=ascii\n\n'; cat "$W/rrt$ad.raw"; } > "$W/rrt$ad.dat"
        "$BIN/hdcompare" -m "$W/rrt$ad.dat" a1_clear_conv.dat > "$W/c2"
        "$BIN/hdcompare" -m "$W/rrt$ad.dat" "$W/own_conv.dat" > "$W/c1"
        printf "%-22s %8d %9.3f %7s %12.4f %12.4f\n" "Radiance rtrace" $ad "$e" "$m" "$(cmpval "$W/c1" rms_rel)" "$(cmpval "$W/c2" rms_rel)"
        printf "Radiance rtrace\t%s\t%s\n" "$e" "$(cmpval "$W/c2" rms_rel)" >> "$TSV.new"
    fi
done
# 3PM: V sampling error (T, D, S fixed)
"$BIN/rfluxmtx" -n 2 -faf -y 28 -I+ -ab 6 -ad 131072 -lw 1e-7 - window_rx_pts.rad box_room.rad < sensors.pts > "$W/Vconv.vmx"
"$BIN/dctimestep" "$W/Vconv.vmx" glass_klems.xml a3_D.dmx a3_skyonly_mf1_3h.smx > "$W/res_conv.mtx"
for ad in 256 1024 4096 16384; do
    tmem "$W/V$ad.vmx" "$BIN/rfluxmtx" -n 2 -faf -y 28 -I+ -ab 6 -ad $ad -lw "$(lw $ad)" - window_rx_pts.rad box_room.rad < sensors.pts
    e=$TM_WALL; m=$TM_RSS
    "$BIN/dctimestep" "$W/V$ad.vmx" glass_klems.xml a3_D.dmx a3_skyonly_mf1_3h.smx > "$W/res$ad.mtx"
    "$BIN/hdcompare" -m "$W/res$ad.mtx" "$W/res_conv.mtx" > "$W/c1"
    printf "%-22s %8d %9.3f %7s %12.4f %12s\n" "heliodon 3PM (V)" $ad "$e" "$m" "$(cmpval "$W/c1" rms_rel)" -
    printf "heliodon 3PM V (own ref)\t%s\t%s\n" "$e" "$(cmpval "$W/c1" rms_rel)" >> "$TSV.new"
    if [ -n "$RB" ] && [ -x "$RB/rfluxmtx" ] && [ $ad -le 4096 ]; then
        # Radiance's rfluxmtx runs its own rcontrib/oconv: its bin first on PATH
        tmem "$W/rV$ad.vmx" env PATH="$RB:$PATH" "$RB/rfluxmtx" -n 2 -faf -y 28 -I+ -ab 6 -ad $ad -lw "$(lw $ad)" - window_rx_pts.rad box_room.rad < sensors.pts
        e=$TM_WALL; m=$TM_RSS
        "$BIN/dctimestep" "$W/rV$ad.vmx" glass_klems.xml a3_D.dmx a3_skyonly_mf1_3h.smx > "$W/rres$ad.mtx"
        "$BIN/hdcompare" -m "$W/rres$ad.mtx" "$W/res_conv.mtx" > "$W/c1"
        printf "%-22s %8d %9.3f %7s %12.4f %12s\n" "Radiance 3PM (V)" $ad "$e" "$m" "$(cmpval "$W/c1" rms_rel)" -
        printf "Radiance 3PM V (own ref)\t%s\t%s\n" "$e" "$(cmpval "$W/c1" rms_rel)" >> "$TSV.new"
    fi
done
# parameter choice: pilot at -ad 128, target 2 % RMS against the own reference
target=${TARGET:-0.02}
"$BIN/hdcompare" -m "$W/rt128.dat" "$W/own_conv.dat" > "$W/c1"
e0=$(cmpval "$W/c1" rms_rel)
np=$(awk -v e="$e0" -v t="$target" 'BEGIN{n=128*(e/t)^2; n=int(n)+(n>int(n)); print (n<1?1:n)}')
t=$(now)
"$BIN/rtrace" -n 2 -I+ -ab 6 -ad "$np" -lw "$(lw "$np")" -dj 0 -st 0 -lr 12 $ROOM $SKY < sensors.pts > "$W/rtp.dat"
e=$(elapsed "$t")
"$BIN/hdcompare" -m "$W/rtp.dat" "$W/own_conv.dat" > "$W/c1"
echo "parameter choice: pilot -ad 128 rms $e0 -> predicted -ad $np for target $target; achieved rms $(cmpval "$W/c1" rms_rel) in $e s"
mv "$TSV.new" "$TSV"
slopes "$TSV"
svgchart "$TSV" "$DOCS/sweep_backward.svg" "Box, 28 sensors: RMS relative error vs wall time" "wall time (s, 2 cores)" "RMS relative error"
echo "wrote $TSV and $DOCS/sweep_backward.svg"
