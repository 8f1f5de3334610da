#!/usr/bin/env bash
# Crash recovery: kill -9 the writer (rank 0) or a worker at random moments,
# KILLS times, each time resuming the file left behind; the file opens after
# every kill, and no task done before a resume is computed again (the
# workers abort if asked to: CATCHUP_SWEEP_DONE_LIST). The resumed file
# equals an uninterrupted run's, wall times aside. Kills land at a random
# moment after the first progress line (the file exists and is flushed by
# then: a kill during its creation is the one documented exception). When a
# sweep finishes before enough kills, a new round starts from scratch.
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
killed=0 round=0 cycle=0
while [ "$killed" -lt "$KILLS" ]; do
  round=$((round + 1))
  rm -f "$out"
  resume=()
  while :; do
    cycle=$((cycle + 1))
    victim=$(( cycle % 2 == 1 ? 0 : 1 + RANDOM % (NP - 1) ))
    delay=$(awk -v r=$RANDOM 'BEGIN { printf "%.2f", 0.05 + 0.6 * r / 32767 }')
    : > "$WORK/done.txt"
    if [ ${#resume[@]} -gt 0 ]; then "$CHECK" donelist "$out" "$WORK/done.txt" > /dev/null; fi
    log=$WORK/log$cycle.txt
    CATCHUP_SWEEP_DONE_LIST="$WORK/done.txt" "$MPIEXEC" -n "$NP" "$SWEEP" "$CRASH" -o "$out" \
      "${resume[@]}" > "$log" 2>&1 &
    mpirun_pid=$!
    for _ in $(seq 1 200); do      # until the first progress line (or the end)
      grep -q "done," "$log" 2> /dev/null && break
      kill -0 $mpirun_pid 2> /dev/null || break
      sleep 0.05
    done
    sleep "$delay"
    pid=$(rank_pid $mpirun_pid $victim)
    hit=0
    if [ -n "$pid" ] && kill -9 "$pid" 2> /dev/null; then hit=1; fi
    wait $mpirun_pid || true
    if grep -q "CATCHUP_SWEEP_DONE_LIST" "$log"; then
      cat "$log" >&2
      fail "a task done before the resume was computed again"
    fi
    "$CHECK" open "$out" || fail "the file does not open after cycle $cycle"
    if command -v h5dump > /dev/null; then
      h5dump -H "$out" > /dev/null || fail "h5dump cannot read the file after cycle $cycle"
    fi
    resume=(--resume)
    if [ $hit -eq 0 ]; then
      echo "round $round: the sweep finished before the kill"
      break
    fi
    killed=$((killed + 1))
    echo "round $round, kill $killed: rank $victim (pid $pid) $delay s after the first progress line;" \
         "$("$CHECK" donelist "$out" "$WORK/done.txt") tasks done"
    [ "$killed" -lt "$KILLS" ] || break
  done
  "$CHECK" donelist "$out" "$WORK/done.txt" > /dev/null
  CATCHUP_SWEEP_DONE_LIST="$WORK/done.txt" run "$NP" "$CRASH" -o "$out" --resume --quiet
  "$CHECK" complete "$out"
  "$CHECK" compare "$WORK/base.h5" "$out" || fail "round $round: the resumed file differs from an uninterrupted run's"
done
echo "crash: $killed kills (rank 0 and workers) in $round round(s), every file readable," \
     "nothing done was redone, resumed files equal to the uninterrupted one"
