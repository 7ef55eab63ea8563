#!/bin/bash
# Time against task count on a one-machine SLURM cluster (issue 20 item 4): the office (glass,
# view v1) for a synthetic Izmir year, submitted with make SUBMIT=slurm at 1, 2, 4 and 8 tasks per
# split stage (photon shards, DC record pieces, hour pieces; DC_sun in pieces), beside the
# one-machine run.  The cluster (test/slurm/cluster.sh) has CPUS CPUs configured on this machine
# and every task asks for one, so up to CPUS tasks run at once.  Needs root, slurm-wlm and munge
# (tools/setup-deps --slurm).  Usage: test/bench/slurm_tasks.sh [RES] [PHOTONS] [CPUS]
# (defaults 128 4m 8).  Prints "tasks wall_s slurm_tasks stage_sum_s" lines; every run's
# timings.txt stays under OUT.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BUILD=${BUILD:-build}
case "$BUILD" in /*) BIN=$BUILD/bin ;; *) BIN=$ROOT/$BUILD/bin ;; esac
export PATH="$BIN:$PATH"
RES=${1:-128}; PHOTONS=${2:-4m}; CPUS=${3:-8}
OUT=${OUT:-$ROOT/$BUILD/bench/slurm_tasks}
if ! command -v sbatch >/dev/null || [ "$(id -u)" -ne 0 ]; then echo "SKIP: needs root and SLURM"; exit 0; fi
unset MAKEFLAGS MFLAGS MAKELEVEL
rm -rf "$OUT"; mkdir -p "$OUT"
CL=$(mktemp -d /tmp/hdslurm-bench.XXXXXX)
trap '"$ROOT/test/slurm/cluster.sh" stop "$CL" >/dev/null 2>&1 || true' EXIT
eval "$("$ROOT/test/slurm/cluster.sh" start "$CL" "$CPUS")"
export SLURM_CONF
O=$ROOT/scenes/office
genwea -a 38.4 -o -27.1 -m -30 -e 25 -n Izmir "$OUT/izmir.wea"
ARGS=(WEATHER="$OUT/izmir.wea" CONFIG=glass VIEW=v1 RES="$RES" MF=1 PHOTONS="$PHOTONS" BANDWIDTH=50 NPROC=1 FENSUN=0
      SKY_OPTS="-ab 2 -ad 256 -lw 1e-4" FEN_OPTS="-ab 2 -ad 256 -lw 1e-4")
echo "# SLURM task-count sweep: office glass v1, ${RES}x$RES, MF:1, $PHOTONS photons, NPROC=1 per task, $CPUS CPUs configured," \
     "$(nproc) cores, $(date -u '+%Y-%m-%d %H:%M UTC'), load $(cut -d' ' -f1-3 /proc/loadavg)"
t0=$(date +%s.%N)
make -s -C "$O" "${ARGS[@]}" OUT="$OUT/local" > "$OUT/local.log" 2>&1
t1=$(date +%s.%N)
echo "one-machine $(awk -v a="$t0" -v b="$t1" 'BEGIN{printf "%.1f", b-a}') - $(awk '{s+=$2} END{printf "%.1f", s}' "$OUT/local/timings.txt")"
for k in 1 2 4 8; do
    R=$OUT/slurm$k
    t0=$(date +%s.%N)
    make -s -C "$O" "${ARGS[@]}" OUT="$R" SUBMIT=slurm SLURM_CPUS=1 SLURM_MEM=1G SLURM_PM_SHARDS=$k DC_PIECES=$k \
        HOUR_PIECES=$k > "$R.log" 2>&1
    "$ROOT/scripts/hdslurm" wait "$R" 7200 > "$R.wait" 2>&1
    t1=$(date +%s.%N)
    ntask=$(awk '!/^#/ && NF {n += $2} END {print n}' "$R/slurm.plan")
    echo "$k $(awk -v a="$t0" -v b="$t1" 'BEGIN{printf "%.1f", b-a}') $ntask $(awk '{s+=$2} END{printf "%.1f", s}' "$R/timings.txt")"
done
