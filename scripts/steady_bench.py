"""The periodic steady state's cost (scripts/bench-steady): per example
circuit, catchup-run --steady-state (the solve's wall time from its summary,
median of --reps runs), Newton's steps and period runs, the largest Floquet
multiplier; beside it the brute force: the periods a transient needs until
the period-to-period change is below 1e-10 of the state's scale (our
Newton target), run by catchup's adaptive scheme at tol 1e-12 and, on the
voltage doubler, by ngspice (Debian's, batch mode, the steep diode model
of scripts/ngspice_compare.py, default and tight tolerances, its output at
15 digits). Prints the
table and writes the section of BENCHMARKS.md between its steady markers.

    python scripts/steady_bench.py [--build build] [--reps 5] [--no-write]
"""
import argparse
import math
import os
import re
import statistics
import subprocess
import sys
import tempfile

import numpy as np

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
import ngspice_compare as ngc  # noqa: E402

_netlist = ngc.ngspice_netlist


def _netlist_15_digits(*args):
    """ngspice_compare's netlist, its wrdata at 15 digits: the default 9
    cannot show a change below 1e-9 (the periods would seem to repeat)."""
    return _netlist(*args).replace("\nwrdata ", "\nset numdgt=15\nwrdata ", 1)


ngc.ngspice_netlist = _netlist_15_digits

CIRCUITS = ["halfwave-rc", "bridge", "bridge-lc", "bridge-cfilter", "resonant", "series-resonant", "clamp", "doubler",
            "rl-halfwave", "ladder", "paper-fig2"]
TARGET = 1e-10            # the period-to-period change, relative to the state's largest entry
NGSPICE_CIRCUIT = "doubler"


def cir(name):
    return os.path.join(ROOT, "examples", "circuits", name + ".cir")


def steady(build, name, reps, tmp):
    """catchup-run --steady-state: median solve time and the summary's figures."""
    out = os.path.join(tmp, "s.h5")
    times, line = [], None
    for _ in range(reps):
        r = subprocess.run([os.path.join(build, "apps", "catchup-run"), cir(name), "-o", out, "--steady-state"],
                           capture_output=True, text=True)
        line = [s for s in r.stderr.splitlines() if ": steady state: " in s][-1]
        m = re.search(r"period runs, ([0-9.e+-]+) s;", line)
        if not m:
            return {"name": name, "failed": line.split("steady state: ", 1)[1][:160]}
        times.append(float(m.group(1)))
    import h5py
    with h5py.File(out, "r") as f:
        g = f["steady_state"]
        res = g["residuals"][:]
        x0 = g["x0"][:]
        mu = np.hypot(g["multipliers_re"][:], g["multipliers_im"][:])
        T = float(g["period"][0])
    return {"name": name, "seconds": statistics.median(times), "iterations": len(res) - 1,
            "runs": int(re.search(r"(\d+) period runs", line).group(1)), "mu": float(mu.max()), "T": T,
            "residual": float(res[-1]), "scale": float(np.abs(x0).max())}


def periods_needed(mu):
    """Periods for a change of 1 (the first period's) to shrink below TARGET at |mu| a period."""
    if mu < 1e-300:
        return 2
    return max(2, math.ceil(math.log(TARGET) / math.log(mu)) + 1)


def catchup_brute(build, name, T, periods, reps, tmp):
    """The transient over `periods` periods at tol 1e-12 (1e-10 where that run
    fails), the states at each period's end."""
    out = os.path.join(tmp, "b.h5")
    for tol in ("1e-12", "1e-10"):
        args = [os.path.join(build, "apps", "catchup-run"), cir(name), "-o", out, "--tol", tol,
                "--set", "T=%.17g" % (periods * T), "--set", "output={samples: %d}" % (periods + 1)]
        times = []
        for _ in range(reps):
            r = subprocess.run(args, capture_output=True, text=True)
            m = re.search(r", ([0-9.e+-]+) s: (CUP_\w+)", r.stderr)
            if not m:
                break
            times.append(float(m.group(1)))
        if len(times) == reps:
            break
    else:
        m = re.search(r"(CUP_\w+): step \d+ \(t = ([0-9.e+-]+)\)", r.stderr)
        return {"failed": "%s at t = %.3g s" % (m.group(1), float(m.group(2))) if m else "failed"}
    import h5py
    with h5py.File(out, "r") as f:
        x = f["x"][:]
    scale = np.abs(x).max() + 1e-9
    d = np.abs(np.diff(x, axis=0)).max(axis=1) / scale
    k = next((i + 1 for i, v in enumerate(d) if v < TARGET), None)
    return {"seconds": statistics.median(times), "periods": periods, "reached": k, "last_change": float(d[-1]),
            "tol": tol, "scale": float(scale)}


def ngspice_brute(name, T, periods, tmp):
    """ngspice over `periods` periods; its probed voltages at each period's end
    (interpolated between its time points), the first period whose change is
    below TARGET, and the transient time of a run to that period."""
    _, _, probes = ngc.tran_and_probes(cir(name))
    volts = [p for p in probes if p.lower().startswith("v(")]
    step = T / 200

    def netlist(k):                          # the example with .tran over k periods
        path = os.path.join(tmp, "%s-%d.cir" % (name, k))
        with open(path, "w") as f:
            for line in open(cir(name)):
                f.write(".tran %.17g %.17g\n" % (step, k * T) if line.lower().startswith(".tran") else line)
        return path
    rows = []
    for label, opts in ngc.NGSPICE_SETTINGS:
        r = ngc.run_ngspice(netlist(periods), step, periods * T, volts, opts, tmp, ngc.MODEL)
        if r.get("failed") or r["t"] is None:
            rows.append({"setting": label, "failed": r.get("failed")})
            continue
        ends = np.array([[np.interp(k * T, r["t"], v) for v in r["x"]] for k in range(periods + 1)])
        d = np.abs(np.diff(ends, axis=0)).max(axis=1) / (np.abs(ends).max() + 1e-9)
        k = next((i + 1 for i, v in enumerate(d) if v < TARGET), None)
        row = {"setting": label, "run_s": r["run_s"], "periods": periods, "reached": k, "min_change": float(d.min())}
        if k:                                   # the run to that period alone
            r2 = ngc.run_ngspice(netlist(k), step, k * T, volts, opts, tmp, ngc.MODEL)
            row["run_to_k_s"] = r2["run_s"]
        rows.append(row)
    return rows


def section(rows, brutes, ng, reps):
    out = ["<!-- BEGIN steady: generated by scripts/bench-steady; do not edit -->",
           "## The periodic steady state: Newton on the period map against brute force", "",
           "Command: `bash scripts/bench-steady` (%d runs each, medians; this machine, 2 cores shared with "
           "other work: times are noisy, ratios within one run). `catchup-run CIRCUIT.cir --steady-state`: the "
           "solve's wall time (the period map by the adaptive scheme at tol 1e-12, the monodromy exact with D = 0 "
           "(clamp, doubler, rl-halfwave, ladder, paper-fig2), else by finite differences; docs/steady-state.md). Brute force: the transient from the same x0 until the change "
           "from one period's end to the next is below %g of the state's largest entry (Newton's target), by "
           "catchup's adaptive scheme at tol 1e-12 (`--set T=K*T --set 'output={samples: K+1}'`), K from the "
           "largest multiplier (the periods a change of 1 needs to fall below the target)." % (reps, TARGET), "",
           "| circuit | T | Newton steps | period runs | final residual | largest multiplier | steady state | "
           "brute force: periods | brute force: time | ratio |",
           "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if "failed" in r:
            why = re.search(r"\((CUP_\w+)\)", r["failed"])
            out.append("| %s | | | | | | none (%s: [steady-state.md](docs/steady-state.md#known-limits)) | | | |" % (
                r["name"], why.group(1) if why else "failed"))
            continue
        b = brutes.get(r["name"])
        if not b:
            bf, bt, ratio = "none: the orbit does not attract (a multiplier at 1)", "", ""
        elif "failed" in b:
            bf, bt, ratio = "failed: " + b["failed"].replace("|", "/"), "", ""
        else:
            bf = "%s%s" % (b["reached"] or ("x0 is the orbit" if b["last_change"] * b["scale"] < 1e-15 else
                                            ">%d (last change %.1e)" % (b["periods"], b["last_change"])),
                           "" if b["tol"] == "1e-12" else " (tol %s)" % b["tol"])
            bt = "%.3g ms" % (1e3 * b["seconds"])
            ratio = "%.2g" % (b["seconds"] / r["seconds"])
        out.append("| %s | %.3g s | %d | %d | %.1e | %.3g | %.3g ms | %s | %s | %s |" % (
            r["name"], r["T"], r["iterations"], r["runs"], r["residual"], r["mu"], 1e3 * r["seconds"], bf, bt,
            ratio))
    out += ["", "**ngspice's brute force** on `%s` (the steep diode model `%s`, `.options rshunt=1e12`, TSTEP = "
            "TMAX = T/200, output at 15 digits (`set numdgt=15`); its voltages %s at each period's end, interpolated between its time points):" % (
                NGSPICE_CIRCUIT, ngc.MODEL, ", ".join("`%s`" % p for p in ng["probes"])), "",
            "| ngspice setting | periods run | first period below %g | transient time to it | smallest change "
            "seen | catchup steady state | ratio |" % TARGET, "|---|---|---|---|---|---|---|"]
    ours = next(r for r in rows if r["name"] == NGSPICE_CIRCUIT)["seconds"]
    for g in ng["rows"]:
        if g.get("failed"):
            out.append("| %s | | %s | | | %.3g ms | |" % (g["setting"], g["failed"], 1e3 * ours))
            continue
        t = g.get("run_to_k_s", g["run_s"])
        out.append("| %s | %d | %s | %.3g ms%s | %.1e | %.3g ms | %s |" % (
            g["setting"], g["periods"], g["reached"] or "never", 1e3 * t, "" if g["reached"] else " (all periods)",
            g["min_change"], 1e3 * ours, ("%.0fx" % (t / ours)) if g["reached"] else ">%.0fx" % (t / ours)))
    out += ["", "The period ends fall between ngspice's time points and are interpolated linearly; with the "
            "default setting its time points repeat from period to period (the interpolation's error then cancels "
            "in the change), with the tight one they do not: its plateau may be the interpolation's rather than "
            "its solution's. Its steady state is the steep diode's, not the ideal one (about 1e-3 of the peak "
            "apart: the ngspice section above).", "", "<!-- END steady -->"]
    return "\n".join(out)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--no-write", action="store_true")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        rows, brutes = [], {}
        for name in CIRCUITS:
            r = steady(a.build, name, a.reps, tmp)
            rows.append(r)
            if "failed" not in r and r["mu"] < 0.999:   # an orbit that does not attract has no brute force
                brutes[name] = catchup_brute(a.build, name, r["T"], min(periods_needed(r["mu"]), 2000), a.reps, tmp)
            print(r, brutes.get(name), flush=True)
        ng_r = next(r for r in rows if r["name"] == NGSPICE_CIRCUIT)
        probes = [p for p in ngc.tran_and_probes(cir(NGSPICE_CIRCUIT))[2] if p.lower().startswith("v(")]
        ng = {"probes": probes, "rows": ngspice_brute(NGSPICE_CIRCUIT, ng_r["T"], 4 * periods_needed(ng_r["mu"]), tmp)}
        print(ng, flush=True)
    text = section(rows, brutes, ng, a.reps)
    print(text)
    if not a.no_write:
        ngc.write_section("steady", text)


if __name__ == "__main__":
    main()
