#!/usr/bin/env bash
# A results file that another catchup-sweep still holds open: --resume and a
# fresh start on it both stop with one stderr line saying that the file is
# in use by another process and what to do; the running sweep is not
# disturbed: it finishes, and its file equals an undisturbed run's.
. "$(dirname "$0")/common.sh"
CRASH=$SRC/tests/sweeps/crash.yaml            # 324 tasks, a few seconds on one core
run 0 "$CRASH" -o "$WORK/base.h5" --quiet
out=$WORK/held.h5
"$SWEEP" "$CRASH" -o "$out" --log-progress > "$WORK/log.txt" 2>&1 &
pid=$!
for _ in $(seq 1 3000); do                    # until the file exists (first progress line; 60 s at most: a loaded machine)
  grep -q "done," "$WORK/log.txt" 2> /dev/null && break
  sleep 0.02
done
kill -STOP "$pid" 2> /dev/null || fail "the sweep ended before it could be held: $(cat "$WORK/log.txt")"
held() {   # held ARGS...: one line, exit 1, the file named, in use, what to do
  set +e
  run 0 "$CRASH" -o "$out" "$@" --quiet > /dev/null 2> "$WORK/err.txt"
  local rc=$?
  set -e
  [ "$rc" -eq 1 ] || fail "exit $rc, expected 1 ($*): $(cat "$WORK/err.txt")"
  [ "$(grep -c '' "$WORK/err.txt")" -eq 1 ] || fail "more than one stderr line ($*): $(cat "$WORK/err.txt")"
  for want in "$out" "in use by another process" "HDF5 file locking" "wait for that run to end, or stop it"; do
    grep -qF -- "$want" "$WORK/err.txt" || fail "stderr lacks '$want' ($*): $(cat "$WORK/err.txt")"
  done
}
held --resume
held
# On 2 ranks the worker starts on its first batch before rank 0 makes the
# file: the same one line, and the worker stopped, not aborted.
set +e
run 2 "$CRASH" -o "$out" --log-progress > /dev/null 2> "$WORK/err.txt"
rc=$?
set -e
[ "$rc" -eq 1 ] || fail "2 ranks: exit $rc, expected 1: $(cat "$WORK/err.txt")"
[ "$(grep -c '^catchup-sweep:' "$WORK/err.txt")" -eq 1 ] || fail "2 ranks: not one line: $(cat "$WORK/err.txt")"
grep -qF "in use by another process" "$WORK/err.txt" || fail "2 ranks: the file in use not said: $(cat "$WORK/err.txt")"
kill -CONT "$pid"
wait "$pid" || fail "the held sweep failed: $(cat "$WORK/log.txt")"
"$CHECK" complete "$out"
"$CHECK" compare "$WORK/base.h5" "$out" || fail "the held sweep's file differs from an undisturbed run's"
echo "held: --resume and a fresh start (1 and 2 ranks) on a file in use say so; the running sweep finished unharmed"
