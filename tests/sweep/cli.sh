#!/usr/bin/env bash
# Usage and sweep-file errors are one stderr line with the right exit code;
# --resume refuses a file made from another sweep file, naming both hashes.
. "$(dirname "$0")/common.sh"
expect() {   # expect CODE TEXT cmd...
  local code=$1 text=$2
  shift 2
  set +e
  "$@" > "$WORK/out.txt" 2> "$WORK/err.txt"
  local rc=$?
  set -e
  local lines
  lines=$(grep -c '' "$WORK/err.txt" || true)
  [ "$rc" -eq "$code" ] || fail "exit $rc, expected $code: $* ($(cat "$WORK/err.txt"))"
  [ "$lines" -eq 1 ] || fail "$lines stderr lines, expected 1: $* ($(cat "$WORK/err.txt"))"
  grep -qF -- "$text" "$WORK/err.txt" || fail "stderr lacks '$text': $(cat "$WORK/err.txt")"
}
expect 2 "no output file" run 0 "$SMOKE"
expect 2 "--frob" run 0 "$SMOKE" -o "$WORK/x.h5" --frob
expect 2 "--task-time-limit 'abc'" run 0 "$SMOKE" -o "$WORK/x.h5" --task-time-limit abc
expect 1 "/no/such.yaml: cannot open" run 0 /no/such.yaml -o "$WORK/x.h5"
for bad in "$SRC"/tests/sweeps/bad/*.yaml; do
  want=$(head -1 "$bad" | sed 's/^# expect: //')
  expect 1 "$want" run 0 "$bad" -o "$WORK/x.h5"
done
expect 1 "cannot resume: no such file" run 0 "$SMOKE" -o "$WORK/none.h5" --resume
run 0 "$SMOKE" -o "$WORK/a.h5" --quiet
sed 's/name: smoke/name: smoke2/' "$SMOKE" > "$WORK/other.yaml"
sed -i "s#base: paper-fig2.yaml#base: $SRC/examples/paper-fig2.yaml#; s#scene: paper-fig3.yaml#scene: $SRC/examples/paper-fig3.yaml#" "$WORK/other.yaml"
expect 1 "made from a different sweep file (stored SHA-256" run 0 "$WORK/other.yaml" -o "$WORK/a.h5" --resume
# a finished file resumes to itself: nothing runs (every task is in the done list)
"$CHECK" donelist "$WORK/a.h5" "$WORK/done.txt" > /dev/null
cp "$WORK/a.h5" "$WORK/b.h5"
CATCHUP_SWEEP_DONE_LIST="$WORK/done.txt" run 2 "$SMOKE" -o "$WORK/b.h5" --resume --quiet
"$CHECK" compare "$WORK/a.h5" "$WORK/b.h5" > /dev/null
# --log-progress: whole lines, no carriage returns, even under mpirun (whose
# stdout is a pseudo-terminal)
run 2 "$SMOKE" -o "$WORK/c.h5" --log-progress 2> "$WORK/progress.txt" > /dev/null
if grep -q $'\r' "$WORK/progress.txt"; then fail "--log-progress wrote a carriage return"; fi
grep -qE '^catchup-sweep: ([0-9]+)/\1 done, 0 failed' "$WORK/progress.txt" ||
  fail "--log-progress: no final progress line: $(cat "$WORK/progress.txt")"
echo "cli: one-line errors, hash check, idle resume, log progress"
