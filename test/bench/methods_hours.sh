#!/usr/bin/env bash
# PM-CBDM, plain 3PM and 5PM on the hours of fivephase_sun.sh's run (office, clear glass, view v2,
# 64x64, MF:6 suns for PM-CBDM and the 5PM) against heliodon's converged backward rendering with the
# exact sun (gendaylit's sun and sky, rpict -ab 4 -ad 2048 -as 0 -aa 0 -lw 1e-5 at 64x64, as in
# docs/benchmarks/accuracy.md §6): E_v and DGP (evalglare -d), and each method's whole make time.
# Usage (after test/bench/fivephase_sun.sh): test/bench/methods_hours.sh [OUT]
set -eu
ROOT=$(pwd)
export PATH=$ROOT/${BUILD:-build}/bin:$PATH
R=$(cd "${1:-$ROOT/build/bench/fivephase_sun}" && pwd)
W=$R/w.wea
[ -s "$R/5pm/v2/annual.csv" ] || { echo "methods_hours: run test/bench/fivephase_sun.sh first ($R/5pm/v2/annual.csv)"; exit 1; }
cd scenes/office
A="WEATHER=$W OUT=$R CONFIG=glass VIEW=v2 RES=64 NPROC=2 MF=6"
echo "load before: $(cat /proc/loadavg)"
for m in pm 3pm; do
    t0=$(date +%s.%N)
    make -s $A METHOD=$m KLEMS_WG1=glass > "$R/make_$m.log" 2>&1 || { tail -5 "$R/make_$m.log"; exit 1; }
    echo "METHOD=$m: $(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN{printf "%.1f", b - a}') s (make)"
done
ev() { evalglare -d -vf v2.vf "$1" 2>/dev/null | awk -F: '/^dgp,av_lum,E_v/ {split($2, v, " "); printf "%.1f %.3f", v[3], v[1]}'; }
row() { sed -n "$(($1 + 2))p" "$2" | awk -F, '{printf "%.1f %.3f", $2, $3}'; }
echo "| hour | reference E_v / DGP | PM-CBDM | 3PM | 5PM | rpict (s) |"
echo "|---|---|---|---|---|---|"
grep -v '^#' "$R/5pm/v2/hours.log" | while read -r rec mo da hr rest; do
    gendaylit "$mo" "$da" "$hr" -a 38.4 -o -27.1 -m -30 -W 800 100 > "$R/fsky_$rec.rad"
    oconv mat_glass.rad room.rad windows.rad "$R/fsky_$rec.rad" skyglow.rad > "$R/fref_$rec.oct"
    t0=$(date +%s.%N)
    rpict -vf v2.vf -x 64 -y 64 -ps 1 -pj 0 -dj 0 -ab 4 -ad 2048 -as 0 -aa 0 -lw 1e-5 "$R/fref_$rec.oct" > "$R/fref_$rec.hdr"
    t=$(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN{printf "%.0f", b - a}')
    set -- $(ev "$R/fref_$rec.hdr") $(row "$rec" "$R/v2/annual.csv") $(row "$rec" "$R/3pm/v2/annual.csv") $(row "$rec" "$R/5pm/v2/annual.csv")
    awk -v m="$mo" -v d="$da" -v h="$hr" -v t="$t" -v e="$1" -v g="$2" -v pe="$3" -v pg="$4" -v te="$5" -v tg="$6" -v fe="$7" -v fg="$8" \
        'function c(x, y) { return sprintf("%.0f (%+.0f %%) / %.3f", x, 100 * (x / e - 1), y) }
         BEGIN {printf "| %d/%d %.2f h | %.0f / %.3f | %s | %s | %s | %s |\n", m, d, h, e, g, c(pe, pg), c(te, tg), c(fe, fg), t}'
done
echo "load after: $(cat /proc/loadavg)"
