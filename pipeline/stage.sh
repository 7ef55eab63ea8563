#!/bin/sh
# stage.sh TIMINGS NAME command...: run a pipeline stage and append one line to TIMINGS:
#   NAME WALL cpu CPU rss_mb RSS disk_mb DISK peak_mb PEAK
# WALL: elapsed seconds; CPU: user + system seconds of the stage's processes; RSS: the peak
# resident set of the largest of them (MB = 10^6 bytes; "-" without GNU time); DISK: what the run
# folder (the folder of TIMINGS) grew by during the stage (MB, negative if it shrank; under make -j
# it includes the stages running beside it); PEAK: the largest size of the run folder seen during
# the stage (MB; sampled every STAGE_DU_EVERY seconds, default 2, and at its start and end).
# The line is written only when the command succeeds (a failed stage is run again on resume).
set -e
tf=$1; name=$2; shift 2
dir=$(dirname "$tf")
tmp=$(mktemp -d "${TMPDIR:-/tmp}/stage.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
trap 'rm -rf "$tmp"; exit 143' TERM INT HUP
du_k() { du -sk "$dir" 2> /dev/null | awk '{print $1; exit}'; }
d0=$(du_k); d0=${d0:-0}
echo "$d0" > "$tmp/peak"
# the run folder's size, sampled while the stage runs (its largest value kept in $tmp/peak)
(
    p=$d0
    while sleep "${STAGE_DU_EVERY:-2}" && kill -0 $$ 2> /dev/null; do
        s=$(du_k) || s=0
        [ "${s:-0}" -gt "$p" ] && p=$s && echo "$p" > "$tmp/peak.new" && mv -f "$tmp/peak.new" "$tmp/peak"
    done
) > /dev/null 2>&1 &
poll=$!
# GNU time, when there, for the largest resident set (its %M: ru_maxrss of the waited-for
# processes, KiB)
timed=
if /usr/bin/time -o /dev/null -f %M true > /dev/null 2>&1; then timed=1; fi
t0=$(date +%s.%N)
st=0
if [ -n "$timed" ]; then /usr/bin/time -o "$tmp/rss" -f %M "$@" || st=$?
else "$@" || st=$?; fi
t1=$(date +%s.%N)
kill "$poll" 2> /dev/null || :
wait "$poll" 2> /dev/null || :
[ "$st" = 0 ] || exit "$st"
d1=$(du_k); d1=${d1:-0}
p=$(cat "$tmp/peak")
[ "$d1" -gt "$p" ] && p=$d1
rss=-
[ -n "$timed" ] && rss=$(tail -1 "$tmp/rss" | awk '$1 ~ /^[0-9]+$/ {printf "%.1f", $1 * 1024 / 1e6; exit}')
# the shell's `times`: its own user/system times, then its children's (the stage's processes,
# all waited for); written to a file, not a pipe, so that this shell runs it
times > "$tmp/times"
awk -v n="$name" -v a="$t0" -v b="$t1" -v r="${rss:--}" -v d0="$d0" -v d1="$d1" -v p="$p" \
    'function s(x) {split(x, q, "m"); return q[1] * 60 + q[2]}
     NR == 2 {c = s($1) + s($2)}
     END {printf "%s %.2f cpu %.2f rss_mb %s disk_mb %.1f peak_mb %.1f\n", n, b - a, c, r, (d1 - d0) * 1024 / 1e6, p * 1024 / 1e6}' \
    "$tmp/times" >> "$tf"
