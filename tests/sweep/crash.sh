#!/usr/bin/env bash
# Crash recovery: kill -9 the writer (rank 0) or a worker at random moments,
# KILLS times, each time resuming the file left behind; the file opens after
# every kill, and no task done before a resume is computed again (the
# workers abort if asked to: CATCHUP_SWEEP_DONE_LIST). The final file equals
# an uninterrupted run's, wall times aside.
#   extra arguments: KILLS (default 6) NP (default 3)
. "$(dirname "$0")/common.sh"
KILLS=${1:-6}
NP=${2:-3}
CRASH=$SRC/tests/sweeps/crash.yaml
run "$NP" "$CRASH" -o "$WORK/base.h5" --quiet
"$CHECK" complete "$WORK/base.h5"

# the pid of rank R among mpirun's children
rank_pid() {
  local mpirun=$1 want=$2 p
  for p in $(pgrep -P "$mpirun" || true); do
    if tr '\0' '\n' < "/proc/$p/environ" 2>/dev/null | grep -qx "OMPI_COMM_WORLD_RANK=$want"; then
      echo "$p"
      return
    fi
  done
}

out=$WORK/crash.h5
resume=()
finished=0 killed=0
for i in $(seq 1 "$KILLS"); do
  victim=$(( i % 2 == 1 ? 0 : 1 + RANDOM % (NP - 1) ))
  delay=$(awk -v r=$RANDOM 'BEGIN { printf "%.2f", 0.6 + 0.8 * r / 32767 }')
  : > "$WORK/done.txt"
  if [ ${#resume[@]} -gt 0 ]; then "$CHECK" donelist "$out" "$WORK/done.txt" > "$WORK/ndone.txt"; fi
  CATCHUP_SWEEP_DONE_LIST="$WORK/done.txt" "$MPIEXEC" -n "$NP" "$SWEEP" "$CRASH" -o "$out" \
    "${resume[@]}" --quiet > "$WORK/log$i.txt" 2>&1 &
  mpirun_pid=$!
  sleep "$delay"
  pid=$(rank_pid $mpirun_pid $victim)
  if [ -n "$pid" ] && kill -9 "$pid" 2> /dev/null; then
    killed=$((killed + 1))
    echo "kill $i: rank $victim (pid $pid) after $delay s"
  else
    finished=$((finished + 1))
    echo "kill $i: the run had finished before $delay s"
  fi
  wait $mpirun_pid || true
  if grep -q "CATCHUP_SWEEP_DONE_LIST" "$WORK/log$i.txt"; then
    cat "$WORK/log$i.txt" >&2
    fail "a task done before the resume was computed again"
  fi
  "$CHECK" open "$out" || fail "the file does not open after kill $i"
  resume=(--resume)
done
"$CHECK" donelist "$out" "$WORK/done.txt" > "$WORK/ndone.txt"
echo "after $killed kills: $(cat "$WORK/ndone.txt") tasks done; resuming to the end"
CATCHUP_SWEEP_DONE_LIST="$WORK/done.txt" run "$NP" "$CRASH" -o "$out" --resume --quiet
"$CHECK" complete "$out"
"$CHECK" compare "$WORK/base.h5" "$out" || fail "the resumed file differs from an uninterrupted run's"
[ "$killed" -ge $((KILLS / 2)) ] || fail "only $killed of $KILLS kills hit a running sweep"
echo "crash: $killed kills (rank 0 and workers), every file readable, resumed file equal to the uninterrupted one"
