"""catchup-run's HDF5 files as post-processing tools read them: xarray with
engine="h5netcdf" opens each group with named dimensions (HDF5 dimension
scales; a phony dimension would be a warning, and warnings are errors here),
every dataset carries CF `units` and `long_name`, the state's columns are
labelled for every model, and a netlist run keeps its netlist. The values
that come through xarray are checked against h5py's reading of the same
datasets, and the labels against the dynamics they name (q(C4) is the
integral of i(L3) in the paper's circuit; v(out) is v(C1) in the rectifier).

    test_run_files.py CATCHUP_RUN SOURCE_DIR
"""
import os
import subprocess
import sys
import tempfile
import warnings

import h5py
import numpy as np
import xarray as xr

warnings.simplefilter("error")          # e.g. h5netcdf's phony_dims warning
RUN, SRC = sys.argv[1], sys.argv[2]
TMP = tempfile.mkdtemp(prefix="cup_pyfiles_")
NC_DIM_ONLY = b"This is a netCDF dimension but not a netCDF variable."


def run(scene, name, *args):
    out = os.path.join(TMP, name)
    subprocess.run([RUN, os.path.join(SRC, scene), "-o", out, "--quiet", *args], check=True)
    return out


def check_described(path):
    """Every dataset but netCDF's dimension-only scales has a long_name, and
    every numeric one its units, as str (variable-length UTF-8)."""
    bad = []

    def visit(name, obj):
        if not isinstance(obj, h5py.Dataset):
            return
        if obj.attrs.get("CLASS") == b"DIMENSION_SCALE" and \
                bytes(obj.attrs.get("NAME", b"")).startswith(NC_DIM_ONLY):
            return
        need = ["long_name"] + ([] if h5py.check_string_dtype(obj.dtype) else ["units"])
        if obj.dtype.names:                       # a compound table: its fields say it
            need = ["long_name"]
        for a in need:
            if not isinstance(obj.attrs.get(a), str):
                bad.append("%s: %s" % (name, a))
    with h5py.File(path, "r") as f:
        f.visititems(visit)
        for k, v in f.attrs.items():
            if isinstance(v, bytes):
                bad.append("root attribute %s is bytes" % k)
    assert not bad, "%s: missing or not str: %s" % (path, ", ".join(bad))


def test_paper_circuit():
    path = run("examples/paper-fig2.yaml", "fig2.h5")
    check_described(path)
    ds = xr.open_dataset(path, engine="h5netcdf")
    assert ds.x.dims == ("t", "state"), ds.x.dims
    assert list(ds.state.values) == ["q(C4)", "i(L3)", "i(L2)"], ds.state.values
    assert ds.t.attrs["units"] == "s" and ds.x.attrs["units"] == "C, A, A", (ds.t.attrs, ds.x.attrs)
    assert ds.attrs["state_names"] == "q(C4), i(L3), i(L2)"
    with h5py.File(path, "r") as f:
        assert np.array_equal(ds.x.values, f["x"][:]) and np.array_equal(ds.t.values, f["t"][:])
    # The explicit scheme's projection moves along B, whose first row is 0:
    # q_{k+1} = q_k + h i_k exactly, up to rounding.
    q, i = ds.x.sel(state="q(C4)").values, ds.x.sel(state="i(L3)").values
    h = float(ds.attrs["T"]) / int(ds.attrs["n"])
    assert np.max(np.abs(np.diff(q) - h * i[:-1])) < 1e-15 * max(1.0, np.max(np.abs(q))), "q(C4) is not the integral of i(L3)"
    ds.close()


def test_netlist():
    cir = "examples/circuits/halfwave-rc.cir"
    path = run(cir, "halfwave.h5", "--probe", "v(out)", "--probe", "i(D1)")
    check_described(path)
    ds = xr.open_dataset(path, engine="h5netcdf")
    sig = xr.open_dataset(path, engine="h5netcdf", group="signals")
    with open(os.path.join(SRC, cir), encoding="utf-8") as f:
        assert ds.attrs["netlist"] == f.read(), "the netlist's text is not the file's"
    assert list(ds.state.values) == ["v(C1)"] and ds.x.attrs["units"] == "V"
    assert sig["v(out)"].dims == ("t",) and sig["v(out)"].attrs["units"] == "V"
    assert sig["i(D1)"].attrs["units"] == "A" and sig["i(D1)"].attrs["long_name"] == "current i(D1)"
    assert sig["v(out)"].size == ds.t.size
    # C1 sits between out and ground: the probe is the state.
    assert np.array_equal(sig["v(out)"].values, ds.x.sel(state="v(C1)").values)
    ds.close()
    sig.close()


def test_crowd():
    path = run("examples/crowd-column.yaml", "crowd.h5", "--set", "T=2", "--set", "n=40",
               "--set", "output.every=10")
    check_described(path)
    ds = xr.open_dataset(path, engine="h5netcdf")
    crowd = xr.open_dataset(path, engine="h5netcdf", group="crowd")
    steps = xr.open_dataset(path, engine="h5netcdf", group="steps")
    n = int(ds.attrs["agents"])
    assert ds.x.dims == ("t", "state") and ds.x.attrs["units"] == "m"
    assert list(ds.state.values[:4]) == ["x0", "y0", "x1", "y1"] and ds.state.size == 2 * n
    assert crowd.walls.dims == ("wall", "wall_column") and crowd.walls.attrs["units"] == "m"
    assert list(crowd.wall_column.values) == ["x0", "y0", "x1", "y1"]
    assert crowd.radius.dims == ("agent",) and crowd.radius.size == n
    assert steps.gap.dims == ("t",) and steps.eta_cert.attrs["units"] == "m"
    assert np.allclose(steps.t.values, np.linspace(0, 2, 41), rtol=0, atol=1e-12)
    # x0, y0 of agent 0 at the start lie inside the room's box
    with h5py.File(path, "r") as f:
        assert np.array_equal(ds.x.values, f["x"][:])
        walls = f["crowd/walls"][:]
    x0, y0 = ds.x.isel(t=0).sel(state="x0").item(), ds.x.isel(t=0).sel(state="y0").item()
    assert walls[:, [0, 2]].min() < x0 < walls[:, [0, 2]].max() and walls[:, [1, 3]].min() < y0 < walls[:, [1, 3]].max()
    for d in (ds, crowd, steps):
        d.close()


def test_generic_lcs():
    path = run("examples/lcs-generic.yaml", "lcs.h5")
    check_described(path)
    ds = xr.open_dataset(path, engine="h5netcdf")
    assert list(ds.state.values) == ["x1", "x2", "x3"] and ds.x.attrs["units"] == "1"
    ds.close()


if __name__ == "__main__":
    from testmain import run_all
    run_all(globals())
