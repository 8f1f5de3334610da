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
# The summary line counts the jobs that ran, against the sweep file's own
# counts: the smoke's tasks (the rows done in its file) and references (its
# variants); a steady-state sweep (3 x 2 buck designs) has no reference job
# at all, on a fresh run or a --resume with nothing left; no ETA before a
# job is done ("?", not "0 s").
tasks=$("$CHECK" donelist "$WORK/c.h5" "$WORK/done.txt")
refs=$(grep -c '^  - name:' "$SMOKE")
jobs=$((tasks + refs))
grep -qF "$tasks tasks + $refs references = $jobs jobs: 0 done before, $jobs run now (0 failed)" \
  "$WORK/progress.txt" || fail "smoke: summary line not '$tasks tasks + $refs references': $(cat "$WORK/progress.txt")"
grep -qE "^catchup-sweep: $jobs/$jobs done" "$WORK/progress.txt" || fail "smoke: progress does not count $jobs jobs"
D=(0.3 0.5 0.7) L=(10u 50u)
printf 'name: steady\nbase: %s\nvariants:\n  - name: buck\n    grid: {netlist.D: [%s], netlist.L: [%s]}\n' \
  "$SRC/examples/circuits/buck-design.yaml" "$(IFS=,; echo "${D[*]}")" "$(IFS=,; echo "${L[*]}")" > "$WORK/steady.yaml"
n=$((${#D[@]} * ${#L[@]}))
run 2 "$WORK/steady.yaml" -o "$WORK/s.h5" --log-progress 2> "$WORK/steady.txt" > /dev/null
[ "$("$CHECK" donelist "$WORK/s.h5" "$WORK/done.txt")" = $n ] || fail "steady: not $n tasks done"
grep -qF "$n tasks: $n ok, 0 failed, 0 not certified, no tolerance check (no reference)," "$WORK/steady.txt" ||
  fail "steady: first summary line: $(cat "$WORK/steady.txt")"
grep -qF "$n tasks (steady states; no reference jobs) = $n jobs: 0 done before, $n run now (0 failed)" \
  "$WORK/steady.txt" || fail "steady: summary line: $(cat "$WORK/steady.txt")"
grep -qE "^catchup-sweep: $n/$n done" "$WORK/steady.txt" || fail "steady: progress not out of $n jobs"
if grep -hE '^catchup-sweep: 0/' "$WORK/progress.txt" "$WORK/steady.txt" | grep -qv 'ETA ?$'; then
  fail "an ETA before any job was done: $(grep -h '^catchup-sweep: 0/' "$WORK/progress.txt" "$WORK/steady.txt")"
fi
run 2 "$WORK/steady.yaml" -o "$WORK/s.h5" --resume 2> "$WORK/steady.txt" > /dev/null
grep -qF "$n tasks (steady states; no reference jobs) = $n jobs: $n done before, none run now" "$WORK/steady.txt" ||
  fail "steady --resume: summary line: $(cat "$WORK/steady.txt")"
# A singleton (no launcher) runs in a session directory of its own under
# TMPDIR and removes it at the end: after a run, after a one-line error, and
# after a worker's abort (the done-list hook: a task it says was done).
mkdir -p "$WORK/tmp"
TMPDIR="$WORK/tmp" run 0 "$SMOKE" -o "$WORK/t.h5" --quiet
TMPDIR="$WORK/tmp" expect 1 "/no/such.yaml: cannot open" run 0 /no/such.yaml -o "$WORK/x.h5"
"$CHECK" donelist "$WORK/t.h5" "$WORK/done.txt" > /dev/null
set +e
TMPDIR="$WORK/tmp" CATCHUP_SWEEP_DONE_LIST="$WORK/done.txt" run 0 "$SMOKE" -o "$WORK/u.h5" 2> "$WORK/err.txt" > /dev/null
rc=$?
set -e
[ "$rc" -eq 3 ] || fail "singleton abort: exit $rc, expected 3: $(cat "$WORK/err.txt")"
grep -qF "CATCHUP_SWEEP_DONE_LIST" "$WORK/err.txt" || fail "singleton abort: no message: $(cat "$WORK/err.txt")"
left=$(ls -A "$WORK/tmp")
[ -z "$left" ] || fail "a singleton left its directory behind in TMPDIR: $left"
echo "cli: one-line errors, hash check, idle resume, log progress, summary lines ($tasks + $refs jobs; $n steady), singleton directories removed"
