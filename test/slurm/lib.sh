# Shared start of the SLURM tests (sourced after test/e2e/lib.sh): skips when SLURM is not
# installed or not root, else starts a one-machine cluster (cluster.sh) in a temporary folder,
# stops it at exit, and exports SLURM_CONF.  Sets SLURM_TEST_DIR to this folder.
SLURM_TEST_DIR=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
if ! command -v sbatch >/dev/null || ! [ -x /usr/sbin/slurmctld ] || ! [ -x /usr/sbin/munged ]; then
    skip cluster "SLURM not installed (tools/setup-deps --slurm)"; exit 0
fi
if [ "$(id -u)" -ne 0 ]; then skip cluster "needs root to start slurmd"; exit 0; fi
CL=$(mktemp -d /tmp/hdslurm-cluster.XXXXXX)
trap '"$SLURM_TEST_DIR/cluster.sh" stop "$CL" >/dev/null 2>&1 || true' EXIT
if out=$("$SLURM_TEST_DIR/cluster.sh" start "$CL" 4 2>&1); then pass cluster_start
else fail cluster_start "$out"; exit 1; fi
eval "$out"
export SLURM_CONF
