#!/usr/bin/env bash
# Runs a Python test with the interpreter that has the test's packages (the
# .venv that scripts/run-tests makes), or skips it with the reason: exit 77,
# which ctest reports as "Skipped" (SKIP_RETURN_CODE).
#
#   run.sh PYTHON SCRIPT [ARGS...]
py=$1; shift
if [ ! -x "$py" ]; then
  echo "SKIP: no Python at $py (scripts/run-tests makes .venv with h5py, numpy, xarray, h5netcdf, pandas, matplotlib; or configure with -DCATCHUP_PYTHON=...)"
  exit 77
fi
missing=$("$py" - <<'PY'
import importlib.util
print(" ".join(m for m in ("h5py", "numpy", "xarray", "h5netcdf", "pandas", "matplotlib")
               if importlib.util.find_spec(m) is None))
PY
)
if [ -n "$missing" ]; then
  echo "SKIP: $py lacks $missing (pip install $missing, or run scripts/run-tests)"
  exit 77
fi
exec "$py" "$@"
