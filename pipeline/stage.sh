#!/bin/sh
# stage.sh TIMINGS NAME command...: run a pipeline stage, append "NAME seconds cpu seconds" to
# TIMINGS: elapsed time, then the CPU time (user + system) of the stage's processes.
set -e
tf=$1; name=$2; shift 2
t0=$(date +%s.%N)
"$@"
t1=$(date +%s.%N)
# the shell's `times`: its own user/system times, then its children's (the stage's processes,
# all waited for); written to a file, not a pipe, so that this shell runs it
tt=$(mktemp "${TMPDIR:-/tmp}/stage.XXXXXX")
times > "$tt"
awk -v n="$name" -v a="$t0" -v b="$t1" 'function s(x) {split(x, p, "m"); return p[1] * 60 + p[2]}
  NR == 2 {c = s($1) + s($2)} END {printf "%s %.2f cpu %.2f\n", n, b - a, c}' "$tt" >> "$tf"
rm -f "$tt"
