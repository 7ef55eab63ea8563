#!/usr/bin/env bash
# BSDF library benchmark (make bench): load time and memory per file size
# (reference XMLs and synthetic 128x128 anisotropic / 512x512 isotropic
# tensor trees), sampling and evaluation rates per core.
set -u
BUILD=${BUILD:-build}
b=$BUILD/bench/bench_bsdf
[ -x "$b" ] || { echo "bench_bsdf not built ($b)"; exit 1; }
tmp=${HD_TEST_TMP:-$BUILD/tmp}
mkdir -p "$tmp"
"$b" "${HELIODON_REF:-../shared/ref}" "$tmp"
