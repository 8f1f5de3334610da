# Shared by the chaos scripts (chaos.sh, disk.sh): arguments and helpers.
#   SCRIPT CATCHUP-RUN CATCHUP-SWEEP MPIEXEC SOURCE-DIR WORK-DIR [CASE...]
set -uo pipefail
RUN=$1 SWEEP=$2 MPIEXEC=$3 SRC=$4 WORK=$5
shift 5
. "$SRC/scripts/mpi-env"
mkdir -p "$WORK"
cd "$WORK" || exit 1
EX=$SRC/examples
failures=0
fail() { echo "FAIL [$case]: $*" >&2; failures=$((failures + 1)); }
ok() { echo "ok   [$case]: $*"; }

# expect CODE TEXT cmd...: the exit status, one stderr line, holding TEXT
expect() {
  local code=$1 text=$2
  shift 2
  "$@" > out.txt 2> err.txt
  local rc=$? lines
  lines=$(grep -c '' err.txt)
  if [ "$rc" -ne "$code" ]; then fail "exit $rc, expected $code: $* ($(cat err.txt))"; return 1; fi
  if [ "$lines" -ne 1 ]; then fail "$lines stderr lines, expected 1: $* ($(cat err.txt))"; return 1; fi
  if ! grep -qF -- "$text" err.txt; then fail "stderr lacks '$text': $(cat err.txt)"; return 1; fi
  return 0
}
# keep FILE...: remember the bytes; kept FILE...: they are the same, and no
# staged sibling (FILE.part*) is left beside them
keep() { sha256sum "$@" > "keep.$case.sum"; }
kept() {
  if ! sha256sum --quiet -c "keep.$case.sum" > /dev/null 2>&1; then fail "bytes changed: $(sha256sum -c "keep.$case.sum" 2>&1 | grep -v ': OK')"; return 1; fi
  local f
  for f in "$@"; do
    if compgen -G "$f.part*" > /dev/null; then fail "a staged file is left: $(ls "$f".part*)"; return 1; fi
  done
  return 0
}
# attr FILE NAME: a root attribute's value, as h5dump prints it
attr() { h5dump -a "$2" "$1" 2>/dev/null | sed -n 's/^ *(0): //p' | head -1; }

# run_cases DEFAULT...: the cases named on the command line, or the defaults
run_cases() {
  local cases=("${ARGS[@]}") t0=$SECONDS
  [ ${#cases[@]} -gt 0 ] || cases=("$@")
  for case in "${cases[@]}"; do "case_$case"; done
  echo "$(basename "$0" .sh): ${#cases[@]} cases, $failures failures, $((SECONDS - t0)) s"
  [ "$failures" -eq 0 ]
}
ARGS=("$@")
