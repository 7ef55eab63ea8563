#!/usr/bin/env bash
# Benchmark: gendaymtx -m 6 (Reinhart MF:6, 5186 patches) for a full year
# (8760 steps), binary float (-of) and ascii (-oa) output, ours on 1 and 2
# threads against Radiance's gendaymtx ($RADIANCE_BIN/gendaymtx) in the
# same run, runs interleaved, 3 repetitions each.  Prints wall-clock and
# CPU (user+system) seconds of every run with the 1-minute load average, the
# medians, and the ratios Radiance/ours.  The output goes to a file (on the
# build machine /dev/null is a regular file, so it is no cheaper).
# Uses the Chicago EPW of the reference folder when present, else a genwea
# year.  Without RADIANCE_BIN (or without a gendaymtx there) only our times
# are printed.  BENCH_SKY_ASCII=0 skips the (slow for Radiance) ascii runs.
set -u
BUILD=${BUILD:-build}
BIN=$BUILD/bin
REF=${HELIODON_REF:-../shared/ref}
TMP=${HD_TEST_TMP:-$BUILD/tmp}/bench_sky
REPS=${BENCH_SKY_REPS:-3}
RAD=""
if [ -n "${RADIANCE_BIN:-}" ] && [ -x "$RADIANCE_BIN/gendaymtx" ]; then RAD=$RADIANCE_BIN/gendaymtx; fi
mkdir -p "$TMP"
if [ -f "$REF/weather/chicago.epw" ]; then W=$REF/weather/chicago.epw
else "$BIN/genwea" -a 38.4 -o -27.1 -m -30 > "$TMP/year.wea"; W=$TMP/year.wea; fi
echo "bench_sky: $(date -u '+%Y-%m-%d %H:%M UTC'), $(nproc) processors, weather $(basename "$W")"
[ -n "$RAD" ] || echo "bench_sky: RADIANCE_BIN not set (or no gendaymtx there): no comparison"

# one timed run: label prog args... -> appends "wall cpu load" to $TMP/t.<label>
one() {
    label=$1; shift
    load=$(cut -d' ' -f1 /proc/loadavg)
    if ! /usr/bin/time -f "%e %U %S" -o "$TMP/time" "$@" "$W" > "$TMP/out.mtx" 2>/dev/null; then
        echo "  $label: FAILED ($*)"; return 1; fi
    read -r e u s < "$TMP/time"
    cpu=$(awk -v u="$u" -v s="$s" 'BEGIN{printf "%.2f", u + s}')
    echo "$e $cpu $load" >> "$TMP/t.$label"
    printf '  %-22s wall %6.2f s  cpu %6.2f s  (load %s, %s bytes)\n' "$label" "$e" "$cpu" "$load" "$(wc -c < "$TMP/out.mtx")"
}
median() { sort -n | awk '{v[NR]=$1} END{print (NR%2) ? v[(NR+1)/2] : (v[NR/2]+v[NR/2+1])/2}'; }
summary() { # label -> "median wall, median cpu"
    w=$(cut -d' ' -f1 "$TMP/t.$1" | median); c=$(cut -d' ' -f2 "$TMP/t.$1" | median)
    echo "$w $c"
}
rm -f "$TMP"/t.*
fmts="of"
[ "${BENCH_SKY_ASCII:-1}" = 0 ] || fmts="of oa"
for f in $fmts; do
    for rep in $(seq "$REPS"); do
        one "ours_nt1_$f" "$BIN/gendaymtx" -w -m 6 -$f -nt 1
        one "ours_nt2_$f" "$BIN/gendaymtx" -w -m 6 -$f -nt 2
        [ -z "$RAD" ] || one "radiance_$f" "$RAD" -m 6 -$f
    done
done
echo "medians of $REPS runs (wall, cpu seconds):"
for f in $fmts; do
    set -- $(summary "ours_nt1_$f"); w1=$1; c1=$2
    set -- $(summary "ours_nt2_$f"); w2=$1; c2=$2
    line="gendaymtx -m 6 -$f: ours nt1 wall $w1 cpu $c1; nt2 wall $w2 cpu $c2"
    if [ -n "$RAD" ]; then
        set -- $(summary "radiance_$f"); wr=$1; cr=$2
        line="$line; radiance wall $wr cpu $cr; ratio cpu $(awk -v a="$cr" -v b="$c1" 'BEGIN{printf "%.1f", a/b}')x (nt1),"
        line="$line wall $(awk -v a="$wr" -v b="$w2" 'BEGIN{printf "%.1f", a/b}')x (nt2)"
    fi
    echo "$line"
done
# determinism: the thread count must not change a byte (-h: the header
# holds the command line)
"$BIN/gendaymtx" -w -h -m 6 -of -nt 1 "$W" | cksum > "$TMP/c1"
"$BIN/gendaymtx" -w -h -m 6 -of -nt 2 "$W" | cksum > "$TMP/c2"
if cmp -s "$TMP/c1" "$TMP/c2"; then echo "nt1 and nt2 outputs identical"; else echo "nt1 and nt2 outputs DIFFER"; fi
rm -f "$TMP/out.mtx" "$TMP"/t.* "$TMP/c1" "$TMP/c2"
