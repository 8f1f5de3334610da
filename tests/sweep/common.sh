# Shared by the catchup-sweep tests: arguments and helpers.
#   $1 catchup-sweep  $2 sweep_check  $3 mpiexec  $4 source dir  $5 work dir
set -euo pipefail
SWEEP=$1 CHECK=$2 MPIEXEC=$3 SRC=$4 WORK=$5
shift 5
. "$SRC/scripts/mpi-env"
rm -rf "$WORK"
mkdir -p "$WORK"
SMOKE=$SRC/examples/sweep-smoke.yaml
DATA=$SRC/tests/data

fail() { echo "FAIL: $*" >&2; exit 1; }

# run NP ARGS...: catchup-sweep on NP ranks (the program itself for NP = 0)
run() {
  local np=$1
  shift
  if [ "$np" -eq 0 ]; then "$SWEEP" "$@"; else "$MPIEXEC" -n "$np" "$SWEEP" "$@"; fi
}
