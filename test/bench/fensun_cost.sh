#!/bin/bash
# Cost and accuracy of the pipeline's refined sun DC of the window pixels (dcfensun, heliodon.mk
# $(1)_CMD_fensun) on the office, FS1 data-driven, view v1, a synthetic Izmir year:
#   test/bench/fensun_cost.sh RES MF "NAME:rcontrib options" ...
# e.g. test/bench/fensun_cost.sh 64 6 "dn4:-ab 2 -ad 128 -lw 1e-4 -dn 4" "ab0:-ab 0"
# Per variant: the stage over all visited suns (FENSUN_C 4), CPU seconds and rcontrib -stats; then
# against a converged reference of the old rule (every sun at every vertex, -ab 2 -ad 128, 32
# estimates per pixel, only the sun patches of four hours tracked, seed 7): per patch the sum over
# the window pixels (%) and the pixel RMS / mean.  The tensor trees come from CFSDIR (default the
# e2e tests' build/tmp/cfs_trees: make -C scenes/cfs trees, or run test/e2e/pipeline_office.sh).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BUILD=${BUILD:-build}
case "$BUILD" in /*) BIN=$BUILD/bin ;; *) BIN=$ROOT/$BUILD/bin ;; esac
export PATH="$BIN:$PATH"
RES=$1 MF=$2; shift 2
CFSDIR=${CFSDIR:-$ROOT/$BUILD/tmp/cfs_trees}
OUT=${OUT:-$ROOT/$BUILD/bench/fensun_cost}
B=$OUT/base_${RES}_mf$MF
O=$ROOT/scenes/office
export RAYPATH=.:$CFSDIR
mkdir -p "$OUT"
[ -s "$OUT/izmir.wea" ] || genwea -a 38.4 -o -27.1 -m -30 -e 25 -n Izmir "$OUT/izmir.wea"
make -s -C "$O" WEATHER="$OUT/izmir.wea" CONFIG=fs1 CFSDIR="$CFSDIR" VIEW=v1 RES="$RES" MF="$MF" OUT="$B" \
    "$B/v1/mask.hdr" "$B/fensun.oct" "$B/mods.txt"
# the sun patches of Mar 21 10:30, Jun 21 15:30, Sep 21 9:30, Dec 21 12:30 (nearest patch centre)
for h in "3 21 10.5" "6 21 15.5" "9 21 9.5" "12 21 12.5"; do
    d=$(gendaylit $h -a 38.4 -o -27.1 -m -30 -W 800 100 | awk '$0 ~ /source/ {getline; getline; getline; print $2, $3, $4}')
    awk -v d="$d" 'BEGIN {split(d, s, " ")} /^void light/ {m = $3}
        $1 == "4" && NF == 5 {c = $2 * s[1] + $3 * s[2] + $4 * s[3]; if (c > best) {best = c; bm = m}} END {print bm}' "$B/suns.rad"
done | sort -u > "$B/sub.txt"
VW="-vf $O/v1.vf -x $RES -y $RES"
# stage DIR C MODS options... : the pipeline's command (CPU user+sys s and -stats to DIR.txt)
stage() {
    local d=$1 c=$2 mods=$3; shift 3
    rm -rf "$d" && mkdir -p "$d"
    ( cd "$O" && TIMEFORMAT='%U %S' && time (vwrays -ff $VW | pmmask -c "$c" "$B/v1/mask.hdr" |
        rcontrib -ffc $(vwrays -d $VW) -n 2 -c "$c" "$@" -stats -o "$d/%s.hdr" -M "$mods" "$B/fensun.oct") ) > "$d.txt" 2>&1
}
[ -s "$B/ref.txt" ] || stage "$B/ref" 32 "$B/sub.txt" -ab 2 -ad 128 -lw 1e-4 -seed 7
echo "# fensun cost: office FS1 v1 ${RES}², MF:$MF ($(wc -l < "$B/mods.txt") suns), $(date -u '+%Y-%m-%d %H:%M UTC'), load $(cut -d' ' -f1-3 /proc/loadavg)"
for v in "$@"; do
    name=${v%%:*} opts=${v#*:}
    # shellcheck disable=SC2086
    stage "$OUT/${name}_${RES}_mf$MF" 4 "$B/mods.txt" $opts
    cpu=$(tail -1 "$OUT/${name}_${RES}_mf$MF.txt" | awk '{print $1 + $2}')
    echo "$name [$opts]: CPU $cpu s; $(grep stats: "$OUT/${name}_${RES}_mf$MF.txt" | sed 's/.*stats: //')"
    for p in $(cat "$B/sub.txt"); do
        paste <(pvalue -h -H -b -d "$B/v1/mask.hdr") <(pvalue -h -H -b -d "$B/ref/$p.hdr") \
              <(pvalue -h -H -b -d "$OUT/${name}_${RES}_mf$MF/$p.hdr") |
            awk -v p="$p" '$1 > 0 {n++; r += $2; c += $3; e += ($3 - $2) ^ 2}
                END {printf "  %s: window sum %+.2f %%, pixel RMS / mean %.3f\n", p, 100 * (c - r) / r, sqrt(e / n) / (r / n)}'
    done
done
