#!/usr/bin/env bash
# The paper's §3.3.5 setting (issue 19; docs/benchmarks/accuracy.md §6e): the office in FS2 (wg1 the
# CFS3 prismatic film, wg2 + wg3 the CFS4 fabric, static: mat_fs2_closed.rad, the tensor trees of
# scenes/cfs made by heliodon's genBSDF; the 3PM and 5PM with the Klems XMLs of scenes/cfs), view v2,
# a full year of weather, PM-CBDM, the 5PM and the plain 3PM in one run folder, suns on Reinhart MF:6
# patches for PM-CBDM and the 5PM alike; then "make compare" (p95 DGP of each, the hour-by-hour
# differences with their percentiles, the heat map of OUT/compare/index.html).
# The 5PM's sun part against the exact sun (PART sun, after PART year): three sunny hours of the
# run, one per season (the record of largest sun radiance times its incidence on the facade among
# the 5PM's hours of Dec-Feb, Mar-May, Jun-Aug), the 5PM's term pmcompose -m 6 -s cds/solar%d.hdr
# alone against the same definition rendered backward with gendaylit's exact sun direction (the
# radiance of the hour's sun vector from the 5PM's hour log): rtrace -i -ab 1 on the black scene with
# the window groups' BSDFs (the irradiance of the surfaces seen, the sun through the film and the
# fabric) times the reflectance map, plus rpict -ab 0 (the sun seen through the windows), at
# OS x RES (pixel centres of the finer grid) box-filtered to RES (pfilt -1); OS 4 with -ad 128 and
# four seeds (their standard error: the reference's own noise), OS 2 with -ad 512, OS 1 with -ad 256.  E_v by evalglare -d.
# Usage (from the worktree, after make):
#   test/bench/methods_fs2.sh [year|sun] [RES [WEATHER [OUT]]]   (year, 64, the Mannheim EPW of the
#   reference data)
# Each method's make is timed (wall) with the load average; OUT/timings.txt has wall and CPU per stage.
set -eu
ROOT=$(pwd)
export PATH=$ROOT/${BUILD:-build}/bin:$PATH
PART=${1:-year}
RES=${2:-64}
W=${3:-${HELIODON_REF:-$ROOT/../shared/ref}/weather/mannheim.epw}
R=$(mkdir -p "${4:-$ROOT/build/bench/methods_fs2_$RES}" && cd "${4:-$ROOT/build/bench/methods_fs2_$RES}" && pwd)
[ -r "$W" ] || { echo "methods_fs2: no weather file $W"; exit 1; }
C=$ROOT/scenes/cfs
# the film's tensor tree is not committed (6 MB): made here by heliodon's genBSDF (about 100 s CPU)
[ -s "$C/cfs3_ttree.xml" ] || nice make -s -C "$C" GENBSDF="$ROOT/${BUILD:-build}/bin/genBSDF" NPROC=2 cfs3_ttree.xml
A="WEATHER=$W OUT=$R CONFIG=fs2_closed VIEW=v2 RES=$RES MF=6 NPROC=2 CFSDIR=$C KLEMS_WG1=$C/cfs3_klems.xml KLEMS_WG2=$C/cfs4_klems.xml"
cd "$ROOT/scenes/office"
case $PART in
year)
for m in pm 3pm 5pm; do
    l0=$(cut -d' ' -f1-3 /proc/loadavg); t0=$(date +%s.%N)
    nice make -s $A METHOD=$m > "$R/make_$m.log" 2>&1 || { tail -5 "$R/make_$m.log"; exit 1; }
    echo "METHOD=$m: $(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN{printf "%.0f", b - a}') s wall, load $l0 -> $(cut -d' ' -f1-3 /proc/loadavg); $(tail -2 "$R/make_$m.log" | head -1)"
done
nice make -s $A compare
echo "stages (wall s, CPU s):"
awk '{w += $2; c += $4; printf "  %s\n", $0} END {printf "  total %.0f s wall, %.0f s CPU\n", w, c}' "$R/timings.txt"
    ;;
sun)
    S=$R/sun; mkdir -p "$S"; export RAYPATH=".:$C"
    [ -s "$R/v2/hours.log" ] && [ -s "$R/5pm/black.rad" ] && [ -s "$R/5pm/mapb.oct" ] || { echo "methods_fs2 sun: run the year part first ($R)"; exit 1; }
    nice make -s $A "$R/records.txt" "$R/site.txt"
    read -r lat lon mer < "$R/site.txt"
    ev() { evalglare -d -vf v2.vf "$1" 2>/dev/null | awk -F: '/^dgp,av_lum,E_v/ {split($2, v, " "); print v[3]}'; }
    # the three hours: per season the largest sun radiance x incidence on the facade (-dy: the facade
    # faces -y) among hours with a sun patch; PM-CBDM's hour log (the same MF:6 suns and sun vectors
    # as the 5PM's), so that the references can start before the 5PM's step 4 is done
    recs=$(grep -v '^#' "$R/v2/hours.log" | awk '$5 > 0 && $7 < 0 {s = ($2 == 12 || $2 <= 2) ? 1 : ($2 <= 5 ? 2 : ($2 <= 8 ? 3 : 0))
        if (!s) next; v = -$7 * $9; if (v > b[s]) {b[s] = v; r[s] = $1}} END {print r[1], r[2], r[3]}')
    echo "load before: $(cat /proc/loadavg); records $recs"
    mk_map() {   # reflectance map at $1 x $1 (the 5PM's step 2)
        [ -s "$S/map_$1.hdr" ] && return
        rpict -vf v2.vf -x "$1" -y "$1" -ps 1 -pj 0 -dj 0 -ab 0 -av 0.3183099 0.3183099 0.3183099 "$R/mask.oct" > "$S/ma_$1.hdr"
        rpict -vf v2.vf -x "$1" -y "$1" -ps 1 -pj 0 -dj 0 -ab 0 -av 0.3183099 0.3183099 0.3183099 "$R/5pm/mapb.oct" > "$S/mb_$1.hdr"
        pcomb -e 'ro=ri(1)-ri(2);go=gi(1)-gi(2);bo=bi(1)-bi(2)' -o "$S/ma_$1.hdr" -o "$S/mb_$1.hdr" > "$S/map_$1.hdr"
    }
    ref() {   # ref REC OS AD SEED -> $S/ref_REC_OS_AD_SEED.hdr; its CPU seconds in $S/ref_REC_OS_AD_SEED.cpu
        local n=$((RES * $2)) f=$S/ref_$1_$2_$3_$4
        [ -s "$f.hdr" ] && return
        mk_map "$n"
        /usr/bin/time -f "%U %S" -o "$f.cpu" sh -c "vwrays -ff -vf v2.vf -x $n -y $n | nice rtrace -h -ff -i -ab 1 -ad $3 -lw 1e-4 -dj 0 -av 0 0 0 -seed $4 -n 2 $S/xsun_$1.oct |
            pvalue -r -h -df -y $n +x $n > $f.ri.hdr && nice rpict -vf v2.vf -x $n -y $n -ps 1 -pj 0 -dj 0 -ab 0 -av 0 0 0 $S/xsun_$1.oct > $f.rl.hdr"
        pcomb -e 'ro=ri(1)*ri(2)+ri(3);go=gi(1)*gi(2)+gi(3);bo=bi(1)*bi(2)+bi(3)' -o "$S/map_$n.hdr" -o "$f.ri.hdr" -o "$f.rl.hdr" |
            pfilt -1 -x "$RES" -y "$RES" > "$f.hdr"
        rm -f "$f.ri.hdr" "$f.rl.hdr"
    }
    for r in $recs; do
        read -r mo da hr sr sg sb < <(awk -v r="$r" '$1 == r {print $2, $3, $4, $9, $10, $11}' "$R/v2/hours.log")
        read -r dni dhi < <(awk -v r="$r" '$1 == r {print $5, $6}' "$R/records.txt")
        d=$(gendaylit "$mo" "$da" "$hr" -a "$lat" -o "$lon" -m "$mer" -W "$dni" "$dhi" | awk '$2 == "source" && $3 == "sun" {getline; getline; getline; print $2, $3, $4}')
        printf 'void light xsun 0 0 3 %s %s %s\nxsun source sun 0 0 4 %s 0.533\n' "$sr" "$sg" "$sb" "$d" > "$S/xsun_$r.rad"
        oconv "$R/mat.rad" "$R/5pm/black.rad" "$R/scene/win.rad" "$S/xsun_$r.rad" > "$S/xsun_$r.oct"
        echo "$r $mo $da $hr $d" > "$S/hour_$r.txt"
        for sd in 1 2 3 4; do ref "$r" 4 128 "$sd"; done; ref "$r" 2 512 1; ref "$r" 1 256 1
        echo "record $r: references done, load $(cut -d' ' -f1-3 /proc/loadavg)"
    done
    while [ ! -e "$R/5pm/v2/annual.done" ]; do sleep 20; done
    echo "| hour | exact sun (gendaylit) | 5PM sun part E_v (lx) | reference OS 4, -ad 128: mean of 4 seeds ± standard error (min–max) | OS 2, -ad 512 | one ray per pixel | 5PM vs reference mean | reference CPU s |"
    echo "|---|---|---|---|---|---|---|---|"
    for r in $recs; do
        read -r _ mo da hr d < "$S/hour_$r.txt"
        pmcompose -n 2 -w "$W" -vf v2.vf -m 6 -s "$R/5pm/v2/cds/solar%d.hdr" -noglare -r "$r" -I "$S/sun5_%d.hdr"
        a=$(ev "$S/sun5_$r.hdr"); b3=$(ev "$S/ref_${r}_2_512_1.hdr"); b1=$(ev "$S/ref_${r}_1_256_1.hdr")
        bs=$(for sd in 1 2 3 4; do ev "$S/ref_${r}_4_128_$sd.hdr"; done | tr '\n' ' ')
        t=$(cat "$S/ref_${r}_"*.cpu | awk '{s += $1 + $2} END {printf "%.0f", s}')
        awk -v m="$mo" -v d="$da" -v h="$hr" -v dir="$d" -v a="$a" -v bs="$bs" -v b3="$b3" -v b1="$b1" -v t="$t" 'BEGIN {
            n = split(bs, x, " "); lo = hi = x[1]; for (i = 1; i <= n; i++) {s += x[i]; if (x[i] < lo) lo = x[i]; if (x[i] > hi) hi = x[i]}
            b = s / n; for (i = 1; i <= n; i++) v += (x[i] - b) ^ 2; se = sqrt(v / (n - 1) / n)
            printf "| %d/%d %.2f h | %s | %.1f | %.1f ± %.1f (%.1f %%; %.0f–%.0f) | %.1f (%+.1f %%) | %.1f (%+.1f %%) | %+.1f %% | %s |\n", m, d, h, dir, a, b, se, 100 * se / b, lo, hi, b3, 100 * (b3 / b - 1), b1, 100 * (b1 / b - 1), 100 * (a / b - 1), t}'
    done
    echo "load after: $(cat /proc/loadavg)"
    ;;
*) echo "usage: test/bench/methods_fs2.sh [year|sun] [RES [WEATHER [OUT]]]"; exit 1 ;;
esac
