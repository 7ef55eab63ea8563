#!/usr/bin/env bash
# HDR picture read/write throughput (make bench): runs build/bench/bench_hdr
# on a synthetic 2048x2048 picture and on the reference rendering.
set -u
BUILD=${BUILD:-build}
b=$BUILD/bench/bench_hdr
[ -x "$b" ] || { echo "bench_hdr not built ($b)"; exit 1; }
HELIODON_REF=${HELIODON_REF:-../shared/ref} HD_TEST_TMP=${HD_TEST_TMP:-/tmp} "$b" 2048
