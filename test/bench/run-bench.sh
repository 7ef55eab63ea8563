#!/usr/bin/env bash
# Run every benchmark script in test/bench (make bench). Each prints its
# figures; record them in docs/benchmarks.md with the date and machine.
set -u
BUILD=${BUILD:-build}
export BUILD
for s in test/bench/*.sh; do
    case $(basename "$s") in run-bench.sh|compare_builds.sh) continue ;; esac   # compare_builds: make compare-builds
    echo "=== $s"
    bash "$s" || echo "(benchmark $s failed)"
done
