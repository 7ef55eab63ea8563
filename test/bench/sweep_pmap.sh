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
# run.  Writes docs/benchmarks/sweep_pmap.tsv / sweep_pmap.svg, and the storage
# chart (stored photons per file byte vs map size, both programs; Radiance's
# count from the NumPhotons header line) sweep_pmap_bytes.tsv / .svg.
. "$(dirname "$0")/sweep_lib.sh"
[ -f "$BOX/box_suns_mf1.oct" ] || { echo "SKIP: $BOX not found"; exit 0; }
{ [ -f tools/mkpmap.c ] && [ -x "$BIN/mkpmap" ]; } || { echo "SKIP: photon maps (tools/mkpmap.c) not in this tree"; exit 0; }
W=$ROOT/$BUILD/bench/sweep_pmap; mkdir -p "$W"
TSV=$DOCS/sweep_pmap.tsv; : > "$TSV.new"
BTSV=$DOCS/sweep_pmap_bytes.tsv; : > "$BTSV.new"
# bytes: label stored_photons file_bytes
bytes() { if [ -z "$2" ] || [ "$2" -le 0 ]; then echo "$1: no photon count"; return 0; fi; printf "%s\t%s\t%s\n" "$1" "$2" "$(awk -v n="$2" -v b="$3" 'BEGIN{print n/b}')" >> "$BTSV.new"
          echo "$1: $2 stored photons, $3 bytes = $(awk -v n="$2" -v b="$3" 'BEGIN{printf "%.2f", b/n}') bytes/photon"; }
header
cd "$BOX"
VEC=a4_sunvec_mf1_0101_1030_noground.vec
gather() { # bin map bw out
    rss "$1/rcontrib" -I+ -ab -1 -ap "$2" "$3" -fa -y 28 -M mods_mf1.txt box_suns_mf1.oct < sensors.pts > "$4.dc" 2>"$W/err" || return 1
    "$BIN/dctimestep" "$4.dc" "$VEC" > "$4.dat"
}
point() { # label N BW build_s bin map   ($BRSS: the build's peak MB)
    local t; t=$(now)
    gather "$5" "$6" "$3" "$W/g" || { echo "$1 $2 $3: gather failed: $(head -2 "$W/err")"; return; }
    local g; g=$(elapsed "$t")
    "$BIN/hdcompare" -m "$W/g.dat" a4_res/patchsun_mf1_conv.dat > "$W/c"
    printf "%-10s %9s %6s %9.2f %9.2f %9.4f %9.4f %9s\n" "$1" "$2" "$3" "$4" "$g" "$(cmpval "$W/c" rms_rel)" "$(cmpval "$W/c" total_rel)" \
        "$BRSS/$(rssmb)"
    printf "%s bw %s\t%s\t%s\n" "$1" "$3" "$(awk -v a="$4" -v b="$g" 'BEGIN{print a+b}')" "$(cmpval "$W/c" rms_rel)" >> "$TSV.new"
}
printf "%-10s %9s %6s %9s %9s %9s %9s %9s\n" who photons bw build_s gather_s rms_rel total_rel peak_MB
# peak_MB: peak resident memory of the build / of the gather
for n in ${SWEEP_N-100k 300k 1m 3m}; do
    t=$(now)
    rss "$BIN/mkpmap" -fo -apC "$W/h$n.pm" $n -apo glazing -apr 1 -n 2 box_suns_mf1.oct 2>"$W/err" >/dev/null || { echo "mkpmap $n failed: $(head -2 "$W/err")"; continue; }
    b=$(elapsed "$t"); BRSS=$(rssmb)
    bytes heliodon "$("$BIN/pmapdump" "$W/h$n.pm" | awk '$1=="photons"{print $2}')" "$(stat -c %s "$W/h$n.pm")"
    for bw in 145 1450; do point heliodon $n $bw "$b" "$BIN" "$W/h$n.pm"; done
    if [ -n "$RB" ] && [ -x "$RB/mkpmap" ] && [ $n != 3m ]; then
        rm -rf "$W/r$n.pm" "$W/r$n.leaf"
        t=$(now)
        if rss "$RB/mkpmap" -fo -apC "$W/r$n.pm" $n -apo glazing -apr 1 -n 2 box_suns_mf1.oct >/dev/null 2>"$W/err"; then
            b=$(elapsed "$t"); BRSS=$(rssmb)
            bytes Radiance "$(head -c 4096 "$W/r$n.pm" | tr -d '\0' | awk -F'=' '/^NumPhotons/{gsub(/[ \t]/, "", $2); print $2; exit}')" \
                "$(cat "$W/r$n.pm"* | wc -c)"
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
# parameter choice without a reference (bias-variance pilot, hd_compare_pm_fit):
# two pilots of N0 photons with different seeds, gathered at k = 5..160 photons
# per lookup and source; the seed difference gives the noise variance, the
# drift of the seed-averaged estimate with k the kernel bias (noise removed:
# nested k-nearest sums, so the difference to k0 carries var(k0) - var(k)); the model
# e^2 = C/k + (B k/N)^2 then gives N and k for the target, which are run and
# compared with the reference.
make -s -C "$ROOT" BUILD="$BUILD" "$BUILD/bench/bench_pmpilot" >/dev/null
N0=${PILOT:-300000}; PT=${PILOT_TARGET:-0.10}
for sd in 11 12; do "$BIN/mkpmap" -fo -apC "$W/pp$sd.pm" $N0 -apo glazing -apr $sd -n 2 box_suns_mf1.oct >/dev/null 2>&1; done
act=$("$BIN/pmapdump" "$W/pp11.pm" | awk '$1=="sources"{gsub(/\(/, "", $3); print $3}')
vals() { awk 'b{print .265*$1+.670*$2+.065*$3} /^$/{b=1}' "$1"; }
: > "$W/pilot.tab"
for k in 5 10 20 40 80 160; do
    gather "$BIN" "$W/pp11.pm" $((k * act)) "$W/pa$k"; gather "$BIN" "$W/pp12.pm" $((k * act)) "$W/pb$k"
    vals "$W/pa$k.dat" > "$W/va$k"; vals "$W/pb$k.dat" > "$W/vb$k"
done
for k in 5 10 20 40 80 160; do
    paste "$W/va$k" "$W/vb$k" "$W/va5" "$W/vb5" | awk -v k=$k '
        { a[NR]=$1; b[NR]=$2; a0[NR]=$3; b0[NR]=$4; m[NR]=($3+$4)/2; tot+=m[NR] }
        END { lim = 0.01 * tot / NR
              for (i = 1; i <= NR; i++) if (m[i] > lim) {
                  n++; da=(a[i]-b[i])/m[i]; v+=da*da/2; d0=(a0[i]-b0[i])/m[i]; v0+=d0*d0/2
                  dd=((a[i]+b[i])/2-m[i])/m[i]; D+=dd*dd }
              v/=n; v0/=n; D=D/n-(v0-v)/2; if (k==5) D=0
              printf "%d %.6g %.6g\n", k, v, D }' >> "$W/pilot.tab"
done
set -- $("$ROOT/$BUILD/bench/bench_pmpilot" $N0 $PT < "$W/pilot.tab")
echo "bias-variance pilot ($N0 photons x 2 seeds, $act sources with photons): C=$1 B=$2 -> N=$3 photons, k=$4 per source (bw $(awk -v k="$4" -v a="$act" 'BEGIN{printf "%d", k*a+0.5}')), predicted rms $5 for target $PT"
np=$3; bw=$(awk -v k="$4" -v a="$act" 'BEGIN{b=int(k*a+0.5); print (b<a?a:b)}')
if [ "$np" -lt 1000 ]; then np=1000; fi
if [ "$np" -gt 30000000 ]; then echo "(capped at 30M photons)"; np=30000000; fi
t=$(now); "$BIN/mkpmap" -fo -apC "$W/pc.pm" "$np" -apo glazing -apr 13 -n 2 box_suns_mf1.oct >/dev/null 2>&1; b=$(elapsed "$t")
gather "$BIN" "$W/pc.pm" "$bw" "$W/pc"; "$BIN/hdcompare" -m "$W/pc.dat" a4_res/patchsun_mf1_conv.dat > "$W/c"
echo "bias-variance choice: $np photons, bw $bw: achieved rms $(cmpval "$W/c" rms_rel) vs the converged reference, total_rel $(cmpval "$W/c" total_rel) (build $b s)"
mv "$TSV.new" "$TSV"
mv "$BTSV.new" "$BTSV"
svgchart "$BTSV" "$DOCS/sweep_pmap_bytes.svg" "Contribution photon maps on disk (box, 145 suns)" "stored photons" "photons per file byte"
slopes "$TSV"
svgchart "$TSV" "$DOCS/sweep_pmap.svg" "Box PM-CBDM sensors (145 MF:1 suns): RMS rel. error vs build+gather time" "wall time (s, 2 cores)" "RMS relative error"
echo "wrote $TSV and $DOCS/sweep_pmap.svg"
