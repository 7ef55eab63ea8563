#!/usr/bin/env bash
# Sun-path-only suns vs all sky patches (issue 10, "model no more than a scene
# needs"): the reference box (28 sensors, window "glazing" as photon port),
# the clear-sky sun of Jan 1 10:30 (radiance 5.181e6).  For Reinhart MF:1, 2,
# 4, 6 the contribution photon map is built with one source per sky patch
# (gensuns -a) or only for the patches the sun visits in a year of Chicago
# daylight records (gensuns on a synthetic genwea year), with the SAME total
# photon budget (PHOTONS, default 2m) and the same per-source bandwidth
# (BW = 20 x sources).  rcontrib -I -ab -1 -ap gathers the sun's patch, scaled
# by the sun radiance (hdcompare -s), compared with
#   * the sun at its patch centre (heliodon rtrace -ab 4 -ad 2048, converged):
#     the photon-map error alone, and
#   * the sun at its real position (Radiance's a1_sunonly_conv.dat): photon
#     map + sun discretisation, what a user gets.
# Also sources, map bytes and gather time.  Writes
# docs/benchmarks/sweep_sunpath.tsv / .svg.
. "$(dirname "$0")/sweep_lib.sh"
[ -f "$BOX/sun_clear_0101_1030.rad" ] || { echo "SKIP: $BOX not found"; exit 0; }
make -s BUILD="$BUILD" "$BUILD/bench/bench_sweep_patchsun" >/dev/null
PS=$ROOT/$BUILD/bench/bench_sweep_patchsun
W=$ROOT/$BUILD/bench/sweep_sunpath; mkdir -p "$W"
TSV=$DOCS/sweep_sunpath.tsv; : > "$TSV.new"
header
cd "$BOX"
ROOM="box_room.rad box_window.rad"
SUN="0.335220 -0.863972 0.375740"; SUNRAD=5.181e6
N=${PHOTONS:-2m}
"$BIN/genwea" -a 41.98 -o 87.92 -m 90 -n chicago_synthetic "$W/chicago.wea" 2>/dev/null
printf "%-4s %-8s %7s %6s %9s %8s %9s %10s %10s %10s\n" MF suns sources bw map_MB gather_s pm_rms pm_floor real_rms real_floor
fl() { paste <(awk 'b{print} /^$/{b=1}' "$1") <(awk 'b{print} /^$/{b=1}' "$2") | head -25 |
       awk -v s="$3" '{a+=s*(.265*$1+.670*$2+.065*$3); r+=.265*$4+.670*$5+.065*$6} END{printf "%.4f", a/r-1}'; }
for mf in ${MFS:-1 2 4 6}; do
    set -- $("$PS" $mf $SUN); bin=$1
    if [ ! -s "$W/centre$mf.dat" ]; then
        printf 'void light solar 0 0 3 %s %s %s\nsolar source sun 0 0 4 %s %s %s 0.533\n' $SUNRAD $SUNRAD $SUNRAD "$2" "$3" "$4" > "$W/centre$mf.rad"
        "$BIN/rtrace" -n 2 -I+ -ab 4 -ad 2048 -lw 2e-5 $ROOM "$W/centre$mf.rad" < sensors.pts > "$W/centre$mf.dat"
    fi
    for v in all path; do
        if [ $v = all ]; then A=-a; else A=; fi
        "$BIN/gensuns" -m $mf $A -M "$W/mods_$v$mf.txt" -o "$W/suns_$v$mf.rad" "$W/chicago.wea"
        grep -qx "solar$bin" "$W/mods_$v$mf.txt" || { echo "MF:$mf $v: the Jan 1 10:30 patch $bin is not among the suns"; continue; }
        ns=$(wc -l < "$W/mods_$v$mf.txt"); bw=$((20 * ns))
        "$BIN/oconv" $ROOM "$W/suns_$v$mf.rad" > "$W/$v$mf.oct"
        t=$(now)
        "$BIN/mkpmap" -fo -apC "$W/$v$mf.pm" $N -apo glazing -apr 1 -n 2 "$W/$v$mf.oct" >/dev/null 2>"$W/err" ||
            { echo "MF:$mf $v: mkpmap failed: $(head -2 "$W/err")"; continue; }
        b=$(elapsed "$t")
        t=$(now)
        "$BIN/rcontrib" -I+ -ab -1 -ap "$W/$v$mf.pm" $bw -n 2 -fa -y 28 -m solar$bin "$W/$v$mf.oct" < sensors.pts > "$W/$v$mf.dat" 2>"$W/err" ||
            { echo "MF:$mf $v: gather failed: $(head -2 "$W/err")"; continue; }
        g=$(elapsed "$t")
        "$BIN/hdcompare" -m -s $SUNRAD "$W/$v$mf.dat" "$W/centre$mf.dat" > "$W/cp"
        "$BIN/hdcompare" -m -s $SUNRAD "$W/$v$mf.dat" a1_sunonly_conv.dat > "$W/cr"
        mb=$(awk -v s="$(stat -c %s "$W/$v$mf.pm")" 'BEGIN{printf "%.1f", s/1e6}')
        printf "%-4s %-8s %7s %6s %9s %8.2f %9.4f %10s %10.4f %10s\n" $mf $v $ns $bw $mb "$g" "$(cmpval "$W/cp" rms_rel)" \
            "$(fl "$W/$v$mf.dat" "$W/centre$mf.dat" $SUNRAD)" "$(cmpval "$W/cr" rms_rel)" "$(fl "$W/$v$mf.dat" a1_sunonly_conv.dat $SUNRAD)"
        lab=$([ $v = all ] && echo "all patches" || echo "sun path only")
        printf "%s: PM error (vs patch centre)\t%s\t%s\n" "$lab" $mf "$(cmpval "$W/cp" rms_rel)" >> "$TSV.new"
        printf "%s: vs real sun\t%s\t%s\n" "$lab" $mf "$(cmpval "$W/cr" rms_rel)" >> "$TSV.new"
    done
done
mv "$TSV.new" "$TSV"
svgchart "$TSV" "$DOCS/sweep_sunpath.svg" "Box sensors, $N photons: all sky patches vs sun-path-only suns" "Reinhart MF" "RMS relative error"
echo "wrote $TSV and $DOCS/sweep_sunpath.svg"
