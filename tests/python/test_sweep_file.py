"""catchup-sweep's results file as post-processing tools read it: /summary
into pandas in the one line docs/sweep-format.md gives (strings as str),
every dataset with CF `units`/`long_name`, /runs/x with named dimensions
(task, t, state). The pandas frame is checked against h5py's reading of the
same rows, and each task's `error` against max |/runs/x - /references/x|
recomputed here.

A netlist sweep keeps its probes: /runs/signals equals, sample for sample,
what catchup-run writes to /signals for the same variant and n.

    test_sweep_file.py CATCHUP_SWEEP SOURCE_DIR CATCHUP_RUN
"""
import os
import subprocess
import sys
import tempfile
import warnings

import h5py
import numpy as np
import pandas as pd

warnings.simplefilter("error")
SWEEP, SRC, RUN = sys.argv[1], sys.argv[2], sys.argv[3]
TMP = tempfile.mkdtemp(prefix="cup_pysweep_")

SWEEP_FILE = """name: small
base: {src}/examples/paper-fig2.yaml
grid:
  n: [100, 1000]
  eps: ["n^-2.1", 0]
  eta: ["n^-1.05", 0]
  zip: [eps, eta]
  scheme: [explicit, theta]
variants:
  - name: case1
  - name: case2
    scene: {src}/examples/paper-fig3.yaml
reference: {{samples: 101, n: 20000}}
"""


def test_summary_in_pandas():
    yaml = os.path.join(TMP, "small.yaml")
    with open(yaml, "w") as f:
        f.write(SWEEP_FILE.format(src=os.path.abspath(SRC)))
    out = os.path.join(TMP, "small.h5")
    subprocess.run([SWEEP, yaml, "-o", out, "--quiet"], check=True)
    # the line of docs/sweep-format.md:
    df = pd.DataFrame(h5py.File(out, "r")["summary"][:]).apply(lambda c: c.str.decode("utf-8") if c.dtype == object else c)
    assert len(df) == 16, len(df)
    assert set(df["variant_name"]) == {"case1", "case2"} and set(df["scheme"]) == {"explicit", "theta"}
    assert (df["status_name"] == "CUP_OK").all(), df["status_name"].tolist()
    with h5py.File(out, "r") as f:
        s = f["summary"][:]
        assert np.array_equal(df["n"].values, s["n"]) and np.array_equal(df["wall_time_s"].values, s["wall_time_s"])
        x, ref = f["runs/x"][:], f["references/x"][:]
        for i, row in df.iterrows():
            e = np.max(np.abs(x[i] - ref[row["variant"]]))
            assert e == row["error"], (i, e, row["error"])
        # CF attributes, str, on every dataset; dimensions of the trajectories
        for name in ("summary", "variants", "runs/t", "runs/x", "runs/state", "references/x", "references/summary"):
            assert isinstance(f[name].attrs.get("long_name"), str), name
        assert f["runs/x"].attrs["units"] == "C, A, A" and f["runs/t"].attrs["units"] == "s"
        assert [d.label or list(d.keys())[0] for d in f["runs/x"].dims][1:] == ["t", "state"]
        assert [n.decode() if isinstance(n, bytes) else n for n in f["runs/state"][:]] == ["q(C4)", "i(L3)", "i(L2)"]
        for k, v in f.attrs.items():
            assert not isinstance(v, bytes), "root attribute %s is bytes" % k


def test_netlist_sweep_keeps_probes():
    out = os.path.join(TMP, "rect.h5")
    subprocess.run([SWEEP, os.path.join(SRC, "examples/circuits/rectifier-sweep.yaml"), "-o", out, "--quiet"],
                   check=True)
    run = os.path.join(TMP, "rect250.h5")
    subprocess.run([RUN, os.path.join(SRC, "examples/circuits/halfwave-rc.yaml"), "-o", run, "--quiet",
                    "--set", "netlist.RL=250", "--n", "3000", "--eps", "0", "--eta", "0"], check=True)
    with h5py.File(out, "r") as f, h5py.File(run, "r") as g:
        names = [n.decode() if isinstance(n, bytes) else n for n in f["runs/signal"][:]]
        assert names == list(g["signals"].attrs["names"]), (names, g["signals"].attrs["names"])
        assert f["runs/signals"].attrs["units"] == ", ".join(g["signals"][n].attrs["units"] for n in names)
        s = f["summary"][:]
        i = int(np.flatnonzero((s["variant_name"] == b"RL-250") & (s["n"] == 3000))[0])
        every = 3000 // (f["runs/t"].size - 1)            # samples fall on every 10th step
        for k, n in enumerate(names):
            assert np.array_equal(f["runs/signals"][i, :, k], g["signals"][n][::every]), n
        assert np.isfinite(f["references/signals"][:]).all()


if __name__ == "__main__":
    from testmain import run_all
    run_all(globals())
