#!/usr/bin/env bash
# The smoke sweep at 1 (without mpirun and with), 2, 3, 4 and 5 ranks: /summary
# (all but wall_time_s), /runs, /references and /variants are identical; the
# case-1 reference agrees with the Richardson reference in tests/data.
. "$(dirname "$0")/common.sh"
run 0 "$SMOKE" -o "$WORK/np0.h5" --quiet
"$CHECK" complete "$WORK/np0.h5"
for np in 1 2 3 4 5; do
  run $np "$SMOKE" -o "$WORK/np$np.h5" --quiet
  "$CHECK" compare "$WORK/np0.h5" "$WORK/np$np.h5" || fail "results at $np ranks differ from 1 rank"
done
"$CHECK" refdiff "$WORK/np2.h5" 0 "$DATA/ref_case1_limit_richardson.csv" 1e-6 ||
  fail "case-1 reference differs from tests/data's by more than 1e-6"
echo "determinism: 1 (twice), 2, 3, 4, 5 ranks give the same file"
