#!/usr/bin/env bash
# Errors of tasks that finished before their reference: --resume computes
# the missing reference and fills the errors from /runs/x; without stored
# trajectories (output.samples: 0) tasks wait in memory for their
# reference. Either way the file equals a plain run's.
. "$(dirname "$0")/common.sh"
run 2 "$SMOKE" -o "$WORK/plain.h5" --quiet
cp "$WORK/plain.h5" "$WORK/forgot.h5"
"$CHECK" forget-reference "$WORK/forgot.h5" 1
"$CHECK" compare "$WORK/plain.h5" "$WORK/forgot.h5" > /dev/null && fail "forget-reference changed nothing"
"$CHECK" donelist "$WORK/forgot.h5" "$WORK/done.txt" > /dev/null
CATCHUP_SWEEP_DONE_LIST="$WORK/done.txt" run 2 "$SMOKE" -o "$WORK/forgot.h5" --resume --quiet
"$CHECK" compare "$WORK/plain.h5" "$WORK/forgot.h5" || fail "errors not filled from /runs/x after resume"
# the same sweep storing no trajectories: the same /summary and references
sed "s#base: paper-fig2.yaml#base: $SRC/examples/paper-fig2.yaml#; s#scene: paper-fig3.yaml#scene: $SRC/examples/paper-fig3.yaml#; /^output:/,\$ s#samples: 101#samples: 0#" \
  "$SMOKE" > "$WORK/nox.yaml"
grep -q "samples: 0" "$WORK/nox.yaml" || fail "could not make the output.samples: 0 sweep"
for np in 0 3; do
  run $np "$WORK/nox.yaml" -o "$WORK/nox$np.h5" --quiet
  "$CHECK" compare "$WORK/plain.h5" "$WORK/nox$np.h5" nox || fail "output.samples: 0 at $np ranks differs"
done
echo "resume: errors filled after the reference, with and without stored trajectories"
