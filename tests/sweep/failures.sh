#!/usr/bin/env bash
# Injected failures: exactly the listed tasks fail, with their status and
# message in /summary, and the study completes; a time limit fails tasks
# with CUP_ERR_TIME_LIMIT the same way.
. "$(dirname "$0")/common.sh"
CATCHUP_SWEEP_INJECT_FAIL=3,7,11 run 3 "$SMOKE" -o "$WORK/inject.h5" --quiet
"$CHECK" complete "$WORK/inject.h5"
got=$("$CHECK" failed "$WORK/inject.h5")
want="3:CUP_ERR_CALLBACK,7:CUP_ERR_CALLBACK,11:CUP_ERR_CALLBACK"
[ "$got" = "$want" ] || fail "failed rows '$got', expected '$want'"
# the same at 1 rank, through the same code path as the workers'
CATCHUP_SWEEP_INJECT_FAIL=0,47 run 0 "$SMOKE" -o "$WORK/inject1.h5" --quiet
got=$("$CHECK" failed "$WORK/inject1.h5")
[ "$got" = "0:CUP_ERR_CALLBACK,47:CUP_ERR_CALLBACK" ] || fail "1 rank: failed rows '$got'"
echo "failures: injected tasks fail alone, the study completes"

# --task-time-limit: the long task fails with CUP_ERR_TIME_LIMIT, the short
# one and the reference (never limited) finish
cat > "$WORK/limit.yaml" <<YAML
base: $SRC/examples/paper-fig2.yaml
grid: {n: [10, 4000000]}
variants: [{name: case1}]
reference: {samples: 11, n: 100}
YAML
run 0 "$WORK/limit.yaml" -o "$WORK/limit.h5" --task-time-limit 0.02 --quiet
got=$("$CHECK" failed "$WORK/limit.h5")
[ "$got" = "1:CUP_ERR_TIME_LIMIT" ] || fail "time limit: failed rows '$got'"
echo "failures: --task-time-limit fails the long task only"

# ... and of a switched circuit, whose run goes window by window (one per
# switch configuration in force): the limit is the task's, not a window's
# (each window restarted the clock, and a 20 s buck ran to its end with
# CUP_OK), for the adaptive scheme and for theta
sed 's/^\.tran .*/.tran 1u 20/' "$SRC/examples/circuits/buck-ccm.cir" > "$WORK/buck-long.cir"
printf 'netlist:\n  file: buck-long.cir\n' > "$WORK/buck-long.yaml"
for grid in "{tol: [1e-6]}" "{scheme: theta, n: [20000000], eps: 0, eta: 0}"; do
  cat > "$WORK/switched-limit.yaml" <<YAML
base: buck-long.yaml
grid: $grid
variants: [{name: buck}]
reference: {samples: 11, n: 100}
YAML
  rm -f "$WORK/switched-limit.h5"
  run 0 "$WORK/switched-limit.yaml" -o "$WORK/switched-limit.h5" --task-time-limit 0.05 --quiet
  got=$("$CHECK" failed "$WORK/switched-limit.h5")
  [ "$got" = "0:CUP_ERR_TIME_LIMIT" ] || fail "switched circuit, grid $grid: failed rows '$got'"
done
echo "failures: --task-time-limit stops a switched circuit's task too"
