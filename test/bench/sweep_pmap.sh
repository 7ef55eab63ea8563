#!/usr/bin/env bash
# Photon-map DC sweep (issue 10): photon count x bandwidth for the reference
# box with the 145 MF:1 suns (mkpmap -apC N -apo glazing -apr 1 -n 2,
# rcontrib -ab -1 -ap map BW on the 28 sensors, folded with the Jan 1 10:30
# sun vector) against the converged rtrace with the sun at its patch centre
# (a4_res/patchsun_mf1_conv.dat).  Error: RMS relative over lit sensors
# (hdcompare -m).  Time: build + gather wall seconds.  Radiance's mkpmap /
# rcontrib at the same settings when RADIANCE_BIN is set.
# Parameter choice: the bandwidth is kept proportional to the photon count
# (BW = N/690, Radiance-style density; 10M -> 1450) so that the noise follows
# 1/sqrt(N): a pilot at 300k predicts N for a target error, then that N is
# run.  Writes docs/benchmarks/sweep_pmap.tsv / sweep_pmap.svg.
. "$(dirname "$0")/sweep_lib.sh"
[ -f "$BOX/box_suns_mf1.oct" ] || { echo "SKIP: $BOX not found"; exit 0; }
{ [ -f tools/mkpmap.c ] && [ -x "$BIN/mkpmap" ]; } || { echo "SKIP: photon maps (tools/mkpmap.c) not in this tree"; exit 0; }
W=$ROOT/$BUILD/bench/sweep_pmap; mkdir -p "$W"
TSV=$DOCS/sweep_pmap.tsv; : > "$TSV.new"
header
cd "$BOX"
VEC=a4_sunvec_mf1_0101_1030_noground.vec
gather() { # bin map bw out
    "$1/rcontrib" -I+ -ab -1 -ap "$2" "$3" -fa -y 28 -M mods_mf1.txt box_suns_mf1.oct < sensors.pts > "$4.dc" 2>"$W/err" || return 1
    "$BIN/dctimestep" "$4.dc" "$VEC" > "$4.dat"
}
point() { # label N BW build_s bin map
    local t; t=$(now)
    gather "$5" "$6" "$3" "$W/g" || { echo "$1 $2 $3: gather failed: $(head -2 "$W/err")"; return; }
    local g; g=$(elapsed "$t")
    "$BIN/hdcompare" -m "$W/g.dat" a4_res/patchsun_mf1_conv.dat > "$W/c"
    printf "%-10s %9s %6s %9.2f %9.2f %9.4f %9.4f\n" "$1" "$2" "$3" "$4" "$g" "$(cmpval "$W/c" rms_rel)" "$(cmpval "$W/c" total_rel)"
    printf "%s bw %s\t%s\t%s\n" "$1" "$3" "$(awk -v a="$4" -v b="$g" 'BEGIN{print a+b}')" "$(cmpval "$W/c" rms_rel)" >> "$TSV.new"
}
printf "%-10s %9s %6s %9s %9s %9s %9s\n" who photons bw build_s gather_s rms_rel total_rel
for n in 100k 300k 1m 3m; do
    t=$(now)
    "$BIN/mkpmap" -fo -apC "$W/h$n.pm" $n -apo glazing -apr 1 -n 2 box_suns_mf1.oct 2>"$W/err" >/dev/null || { echo "mkpmap $n failed: $(head -2 "$W/err")"; continue; }
    b=$(elapsed "$t")
    for bw in 145 1450; do point heliodon $n $bw "$b" "$BIN" "$W/h$n.pm"; done
    if [ -n "$RB" ] && [ -x "$RB/mkpmap" ] && [ $n != 3m ]; then
        rm -rf "$W/r$n.pm" "$W/r$n.leaf"
        t=$(now)
        if "$RB/mkpmap" -fo -apC "$W/r$n.pm" $n -apo glazing -apr 1 -n 2 box_suns_mf1.oct >/dev/null 2>"$W/err"; then
            b=$(elapsed "$t")
            for bw in 145 1450; do point Radiance $n $bw "$b" "$RB" "$W/r$n.pm"; done
        else echo "Radiance mkpmap $n failed: $(head -2 "$W/err")"; fi
    fi
done
# parameter choice with BW = N/690
target=${TARGET:-0.15}
t=$(now); "$BIN/mkpmap" -fo -apC "$W/pilot.pm" 300000 -apo glazing -apr 2 -n 2 box_suns_mf1.oct >/dev/null 2>&1; b=$(elapsed "$t")
gather "$BIN" "$W/pilot.pm" 435 "$W/p"; "$BIN/hdcompare" -m "$W/p.dat" a4_res/patchsun_mf1_conv.dat > "$W/c"
e0=$(cmpval "$W/c" rms_rel)
np=$(awk -v e="$e0" -v t="$target" 'BEGIN{n=300000*(e/t)^2; if(n<1000)n=1000; if(n>20000000)n=20000000; printf "%d", n}')
bw=$(awk -v n="$np" 'BEGIN{b=int(n/690+0.5); print (b<1?1:b)}')
t=$(now); "$BIN/mkpmap" -fo -apC "$W/pred.pm" "$np" -apo glazing -apr 3 -n 2 box_suns_mf1.oct >/dev/null 2>&1; b=$(elapsed "$t")
gather "$BIN" "$W/pred.pm" "$bw" "$W/q"; "$BIN/hdcompare" -m "$W/q.dat" a4_res/patchsun_mf1_conv.dat > "$W/c"
echo "parameter choice: pilot 300k photons bw 435 rms $e0 -> predicted $np photons (bw $bw) for target $target; achieved rms $(cmpval "$W/c" rms_rel) (build $b s)"
mv "$TSV.new" "$TSV"
slopes "$TSV"
svgchart "$TSV" "$DOCS/sweep_pmap.svg" "Box PM-CBDM sensors (145 MF:1 suns): RMS rel. error vs build+gather time" "wall time (s, 2 cores)" "RMS relative error"
echo "wrote $TSV and $DOCS/sweep_pmap.svg"
