#!/bin/bash
# compare.sh VIEW.csv > VIEW.txt: hour-by-hour agreement of the methods of a run (methods.mk).
# Input: "record,month,day,hour,pm,3pm,imageless,5pm" (empty field: no result of that method for the hour).
# Output, per pair of methods with hours in common: the hours, mean and largest |dDGP| (with the
# record, date and signed difference), each method's 95th percentile over the common hours
# (linear interpolation between order statistics, as pmcompose and glarestats compute it), the 50th,
# 90th, 95th and 99th percentiles of |dDGP| and the hours with |dDGP| > 0.05 and <= 0.02.
set -eu
csv=$1
p95() { sort -g | awk '{d[NR] = $1} END {if (!NR) {print "nan"; exit} k = 0.95 * (NR - 1) + 1; i = int(k); f = k - i; printf "%.4f\n", (i < NR ? d[i] + f * (d[i+1] - d[i]) : d[NR])}'; }
names=(pm 3pm imageless 5pm)
for a in 5 6 7 8; do
    for b in $(seq $((a + 1)) 8); do
        common=$(awk -F, -v a=$a -v b=$b 'NR > 1 && $a != "" && $b != ""' "$csv")
        [ -n "$common" ] || continue
        stats=$(awk -F, -v a=$a -v b=$b '{d = $a - $b; ad = d < 0 ? -d : d; n++; s += ad; if (ad > mx || n == 1) {mx = ad; r = $1; md = d; dt = $2 "/" $3 " " $4 " h"}}
            END {printf "%d hours, mean |dDGP| %.4f, max |dDGP| %.4f (record %d, %s: %+.4f)", n, s / n, mx, r, dt, md}' <<< "$common")
        pa=$(cut -d, -f$a <<< "$common" | p95); pb=$(cut -d, -f$b <<< "$common" | p95)
        # the distribution of |dDGP| over the common hours: percentiles (as p95 above) and counts
        dist=$(awk -F, -v a=$a -v b=$b '{d = $a - $b; print d < 0 ? -d : d}' <<< "$common" | sort -g | awk '{d[NR] = $1; if ($1 > 0.05) g++; if ($1 <= 0.02) l++}
            function q(p,  k, i, f) {k = p * (NR - 1) + 1; i = int(k); f = k - i; return i < NR ? d[i] + f * (d[i+1] - d[i]) : d[NR]}
            END {printf "|dDGP| p50 %.4f, p90 %.4f, p95 %.4f, p99 %.4f; hours > 0.05: %d, <= 0.02: %d", q(0.5), q(0.9), q(0.95), q(0.99), g, l}')
        echo "${names[a-5]} vs ${names[b-5]}: $stats; DGP p95 ${names[a-5]} $pa, ${names[b-5]} $pb; $dist"
    done
done
