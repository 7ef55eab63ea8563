#!/usr/bin/env bash
# Benchmark: gendaymtx -m 6 (Reinhart MF:6, 5186 patches) for a full year
# (8760 steps) with binary float output, on 1 and 2 threads; prints the
# wall-clock and CPU (user+system) seconds, best of 3, and the load average
# (the machine is shared: compare CPU seconds when it is loaded).  Uses the
# Chicago EPW of the reference folder when present, else a genwea year.
# Radiance is not installed here: the comparison with Radiance's gendaymtx
# needs a Radiance build on the same machine (same command line).
set -u
BUILD=${BUILD:-build}
BIN=$BUILD/bin
REF=${HELIODON_REF:-../shared/ref}
TMP=${HD_TEST_TMP:-$BUILD/tmp}/bench_sky
mkdir -p "$TMP"
if [ -f "$REF/weather/chicago.epw" ]; then W=$REF/weather/chicago.epw
else "$BIN/genwea" -a 38.4 -o -27.1 -m -30 > "$TMP/year.wea"; W=$TMP/year.wea; fi
run() { # label args...
    label=$1; shift
    best=""; bestcpu=""
    for rep in 1 2 3; do
        /usr/bin/time -f "%e %U %S" -o "$TMP/time" "$BIN/gendaymtx" -w "$@" "$W" > "$TMP/out.mtx" 2>/dev/null ||
            { echo "gendaymtx $* failed"; return; }
        read -r e u s < "$TMP/time"
        cpu=$(awk -v u="$u" -v s="$s" 'BEGIN{printf "%.2f", u + s}')
        if [ -z "$best" ] || awk -v x="$e" -v y="$best" 'BEGIN{exit !(x < y)}'; then best=$e; fi
        if [ -z "$bestcpu" ] || awk -v x="$cpu" -v y="$bestcpu" 'BEGIN{exit !(x < y)}'; then bestcpu=$cpu; fi
    done
    echo "$label: wall $best s, cpu $bestcpu s (best of 3; $(wc -c < "$TMP/out.mtx") bytes; load $(cut -d' ' -f1 /proc/loadavg))"
}
run "gendaymtx -m 6 -of -nt 1 $(basename "$W")" -m 6 -of -nt 1
run "gendaymtx -m 6 -of -nt 2 $(basename "$W")" -m 6 -of -nt 2
run "gendaymtx -of -nt 1 (MF:1) $(basename "$W")" -of -nt 1
rm -f "$TMP/out.mtx"
