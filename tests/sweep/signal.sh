#!/usr/bin/env bash
# A stop in the middle of a sweep of tiny tasks, whose batches are hundreds
# of job ids (rendezvous sends, which stay open until the worker receives
# them): the workers are frozen (SIGSTOP) once the dispatch has started, so
# that batches sent ahead wait for them; then SIGTERM goes to rank 0 alone,
# or to every rank (what mpirun does with its own SIGTERM), and the workers
# go on (SIGCONT). catchup-sweep ends within seconds with the line saying
# what is saved; the file opens; --resume computes nothing done before and
# finishes a file equal to an uninterrupted run's.
. "$(dirname "$0")/common.sh"
NP=3
{
  echo "name: tiny"
  echo "base: $SRC/examples/paper-fig2.yaml"
  echo 'grid: {n: [20, 30, 40, 50, 60, 70, 80, 90], eps: ["n^-2.1", 0], scheme: [explicit, implicit, exponential, theta], projector: [auto, activeset]}'
  echo "variants:"
  for k in $(seq 1 1000); do echo "  - {name: v$k, set: {circuit.R1: $k}}"; done
  echo "reference: {samples: 11, n: 200}"
} > "$WORK/tiny.yaml"                         # 128,000 tasks of ~10 us (about 0.7 s on 2 workers: a loaded machine still stops them mid-way)
run "$NP" "$WORK/tiny.yaml" -o "$WORK/base.h5" --quiet
"$CHECK" complete "$WORK/base.h5"

rank_pid() {   # rank_pid MPIRUN_PID RANK
  local p
  for p in $(pgrep -P "$1" || true); do
    if tr '\0' '\n' < "/proc/$p/environ" 2> /dev/null | grep -qx "OMPI_COMM_WORLD_RANK=$2"; then
      echo "$p"
      return
    fi
  done
}

for who in rank0 all; do
  out=$WORK/$who.h5 log=$WORK/$who.txt
  "$MPIEXEC" -n "$NP" "$SWEEP" "$WORK/tiny.yaml" -o "$out" --log-progress > "$log" 2>&1 &
  mpirun_pid=$!
  for _ in $(seq 1 1000); do                  # the dispatch has started: first progress line
    grep -q "done," "$log" 2> /dev/null && break
    kill -0 $mpirun_pid 2> /dev/null || break
    sleep 0.01
  done
  pids=()
  for r in $(seq 0 $((NP - 1))); do pids+=("$(rank_pid $mpirun_pid "$r")"); done
  for p in "${pids[@]:1}"; do kill -STOP "$p" 2> /dev/null || fail "$who: the sweep ended before the stop: $(cat "$log")"; done
  if [ "$who" = rank0 ]; then kill -TERM "${pids[0]}"; else kill -TERM "${pids[@]}"; fi
  sleep 0.2
  kill -CONT "${pids[@]:1}"
  for _ in $(seq 1 300); do                   # 30 s at most
    kill -0 $mpirun_pid 2> /dev/null || break
    sleep 0.1
  done
  if kill -0 $mpirun_pid 2> /dev/null; then
    kill -9 "${pids[@]}" 2> /dev/null || true
    fail "$who: still running 30 s after SIGTERM: $(tr '\r' '\n' < "$log" | tail -3)"
  fi
  wait $mpirun_pid || true
  grep -q "catchup-sweep: stopped by SIGTERM: [0-9]* of 129000 jobs are done and saved in $out; continue with --resume" "$log" ||
    fail "$who: no line saying what is saved: $(tr '\r' '\n' < "$log" | tail -5)"
  "$CHECK" open "$out" || fail "$who: the file does not open after the stop"
  "$CHECK" donelist "$out" "$WORK/done.txt" > /dev/null
  CATCHUP_SWEEP_DONE_LIST="$WORK/done.txt" run "$NP" "$WORK/tiny.yaml" -o "$out" --resume --quiet
  "$CHECK" complete "$out"
  "$CHECK" compare "$WORK/base.h5" "$out" || fail "$who: the resumed file differs from an uninterrupted run's"
  echo "signal: SIGTERM to $who: stopped with $(grep -o '[0-9]* of 129000 jobs are done' "$log"), resumed to the same file"
done
