#!/bin/sh
# stage.sh TIMINGS NAME command...: run a pipeline stage, append "NAME seconds" to TIMINGS.
set -e
tf=$1; name=$2; shift 2
t0=$(date +%s.%N)
"$@"
t1=$(date +%s.%N)
awk -v n="$name" -v a="$t0" -v b="$t1" 'BEGIN{printf "%s %.2f\n", n, b-a}' >> "$tf"
