#!/usr/bin/env bash
# A crowd sweep (tests/sweeps/crowd.yaml, 20 agents): the same file at 1, 2
# and 3 ranks; each task's /crowd row (agents out, evacuation time,
# smallest gap), steps, certificates and positions equal to catchup-run's on
# the same scene with the variant's overrides; --resume recomputes exactly
# the tasks not done.
. "$(dirname "$0")/common.sh"
SW=$SRC/tests/sweeps/crowd.yaml
RUN=$(dirname "$SWEEP")/catchup-run
run 0 "$SW" -o "$WORK/np0.h5" --quiet
"$CHECK" complete "$WORK/np0.h5"
for np in 2 3; do
  run $np "$SW" -o "$WORK/np$np.h5" --quiet
  "$CHECK" compare "$WORK/np0.h5" "$WORK/np$np.h5" || fail "crowd sweep at $np ranks differs from 1 rank"
done
task=0
for set in "" "crowd.agents.seed=2" "crowd.agents.count=14" "crowd.doors.0.1.1=3.5" "crowd.speed=1.6"; do
  "$RUN" "$SRC/tests/sweeps/crowd-room.yaml" -o "$WORK/run$task.h5" --quiet ${set:+--set "$set"}
  "$CHECK" crowd-vs-run "$WORK/np2.h5" $task "$WORK/run$task.h5" || fail "task $task differs from catchup-run"
  task=$((task + 1))
done
cp "$WORK/np0.h5" "$WORK/resumed.h5"
"$CHECK" crowd-forget "$WORK/resumed.h5" 1
"$CHECK" crowd-forget "$WORK/resumed.h5" 3
"$CHECK" compare "$WORK/np0.h5" "$WORK/resumed.h5" > /dev/null && fail "crowd-forget changed nothing"
[ "$("$CHECK" donelist "$WORK/resumed.h5" "$WORK/done.txt")" = 3 ] || fail "not 3 tasks done after forgetting 2"
CATCHUP_SWEEP_DONE_LIST="$WORK/done.txt" run 2 "$SW" -o "$WORK/resumed.h5" --resume 2> "$WORK/resume.txt"
# the summary line: the sweep file's tasks (all done in np0.h5) and references (its variants);
# the references and the 3 tasks left done before, the 2 forgotten run now;
# the mean over the tasks alone (the references compute nothing)
T=$("$CHECK" donelist "$WORK/np0.h5" "$WORK/all.txt") V=$(grep -c '^  - name:' "$SW")
line="$T tasks + $V references (a crowd's: they compute nothing) = $((T + V)) jobs: $((V + 3)) done before"
grep -qF "$line, 2 run now (0 failed)" "$WORK/resume.txt" || fail "--resume summary line: $(cat "$WORK/resume.txt")"
grep -qF "; tasks of " "$WORK/resume.txt" || fail "--resume: the mean is not over the tasks: $(cat "$WORK/resume.txt")"
"$CHECK" compare "$WORK/np0.h5" "$WORK/resumed.h5" || fail "--resume did not restore the forgotten tasks"
echo "crowd: 1, 2, 3 ranks alike; 5 tasks equal to catchup-run; --resume redoes only the 2 tasks not done"
