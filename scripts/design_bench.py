"""Converters' steady states and a 10^4-variant design study (scripts/bench-design).

1. Per switched converter of examples/circuits: catchup-run --steady-state
   (the solve's wall time from its summary line, median of --reps runs; the
   residual target 1e-10 relative, pss's default), Newton's steps, period
   runs and the largest Floquet multiplier, beside catchup's brute force:
   the adaptive scheme at tol 1e-12 from rest until the change from one
   period's end to the next is below 1e-10 of the state (scripts/steady_bench.py
   runs both).
2. A design study of the buck (examples/circuits/buck-design.yaml) over a
   grid duty x L x C x load of --variants (10^4: 10 values each) by
   catchup-sweep on 1 rank (it computes everything) and on 3 ranks (rank 0
   dispatches, 2 workers: the machine's 2 cores), the wall time of each and
   the parallel efficiency T(1 rank) / (2 T(2 workers)), with catchup-sweep's
   own figures.

Prints the tables and writes the section of BENCHMARKS.md between its
design markers.

    python scripts/design_bench.py [--build build] [--reps 5] [--per-axis 10] [--no-write]
                                   [--study-only] [--compare OTHER_BUILD]

With --study-only the study alone (and MPI's own start-up: mpirun -n 3
true, catchup-sweep --version on 1 and 3 ranks) rewrites its part of the
section; --compare runs it with two builds in turn and prints both.
"""
import argparse
import json
import os
import re
import resource
import subprocess
import sys
import tempfile
import time

import h5py
import numpy as np

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
import steady_bench as sb  # noqa: E402
import converters_compare as cc  # noqa: E402

CONVERTERS = ["buck-ccm", "buck-dcm", "boost", "buckboost", "flyback", "fullbridge"]


def converters(build, reps, tmp):
    rows = []
    for name in CONVERTERS:
        r = sb.steady(build, name, reps, tmp)
        if "failed" not in r:
            r["brute"] = sb.catchup_brute(build, name, r["T"], sb.periods_needed(r["mu"]), reps, tmp)
        print(r, flush=True)
        rows.append(r)
    return rows


NGSPICE_CONVERTER = "buck-ccm"


def ngspice_brute(name, T, periods, tmp):
    """ngspice on the near-ideal copy of scripts/converters_compare.py (RON 1 mOhm,
    ROFF 1 GOhm, 1 ns edges, the steep diode) over `periods` periods at TSTEP =
    TMAX = T/200, its states at each period's end (interpolated between its
    time points, written at 15 digits), the first period whose change is below
    1e-10 of the state's largest entry and the transient time of the whole run."""
    cir = sb.cir(name)
    st = cc.states(cc.read_netlist(cir))
    vecs = list(dict.fromkeys(["i(%s)" % n.lower() if k == "i" else "v(%s)" % a for k, n, a, b in st]))
    rows = []
    for label, opts in cc.NGSPICE_SETTINGS:
        def run(k):
            text = cc.near_ideal(cir, None, opts)
            text = re.sub(r"(?m)^\.tran .*$", ".tran %.17g %.17g 0 %.17g uic" % (T / 200, k * T, T / 200), text)
            data, net = os.path.join(tmp, "ng.txt"), os.path.join(tmp, "ng.cir")
            open(net, "w").write(text + ".save %s\n.control\nset numdgt=15\nrun\nrusage trantime\nwrdata %s %s\n"
                                 ".endc\n.end\n" % (" ".join(vecs), data, " ".join(vecs)))
            if os.path.exists(data):
                os.remove(data)
            r = subprocess.run(["ngspice", "-b", net], capture_output=True, text=True, cwd=tmp)
            m = re.search(r"Transient analysis time = ([0-9.e+-]+)", r.stdout + r.stderr)
            if not m or not os.path.exists(data):
                return None, (r.stdout + r.stderr).strip().splitlines()[-1][:120]
            d = np.loadtxt(data, ndmin=2)
            t, cols = d[:, 0], [d[:, 2 * j + 1] for j in range(len(vecs))]
            return float(m.group(1)), np.array([[np.interp(j * T, t, c) for c in cols] for j in range(k + 1)])
        run_s, ends = run(periods)
        if run_s is None:
            rows.append({"setting": label, "failed": ends})
            continue
        ch = np.abs(np.diff(ends, axis=0)).max(axis=1) / (np.abs(ends).max() + 1e-9)
        k = next((i + 1 for i, v in enumerate(ch) if v < sb.TARGET), None)
        row = {"setting": label, "run_s": run_s, "periods": periods, "reached": k, "min_change": float(ch.min())}
        if k:                                   # the run to that period alone
            row["run_to_k_s"] = run(k)[0]
        rows.append(row)
        print(row, flush=True)
    return rows


PULSIM_CONVERTERS = ["buck-ccm", "boost", "buck-dcm"]
PULSIM_STEPS = [100, 1000, 10000]          # its fixed step dt = T / N


def pulsim_version():
    import pulsim
    return getattr(pulsim, "__version__", "?")


def x0_of(build, name, tmp):
    """catchup's steady state x0 and the state's names (tests/test_pss_converters.c:
    the exact period map's fixed point to 2e-11 .. 6e-10)."""
    out = os.path.join(tmp, "x0.h5")
    subprocess.run([os.path.join(build, "apps", "catchup-run"), sb.cir(name), "-o", out, "--steady-state"],
                   capture_output=True, check=True)
    with h5py.File(out, "r") as f:
        return f["steady_state"]["x0"][:], [s.decode() if isinstance(s, bytes) else s for s in f["state"][:]]


def pulsim_one(name, n):
    """Child: pulsim's run_periodic_shooting on the converter (scripts/converters_compare.py's
    builder: g_on 1e3, g_off 1e-9, the gates as a schedule), dt = T / n; prints JSON."""
    import pulsim as p
    cards = cc.read_netlist(sb.cir(name))
    times = []
    for _ in range(3):
        b, gates = cc.pulsim_circuit(cards)()
        fn = cc.pulsim_schedule(b, gates)
        t0 = time.perf_counter()
        r = p.run_periodic_shooting(b, t_period=1e-5, dt=1e-5 / n, switch_fn=fn, tol=1e-10, max_iterations=50)
        times.append(time.perf_counter() - t0)
    names = b.state_var_names()
    x = {}
    for kind, el, a, c in cc.states(cards):       # catchup's states: inductor currents, capacitor voltages
        if kind == "i":
            x["i(%s)" % el] = float(r.x_steady_state[names.index("I(%s)" % el)])
        else:
            v = lambda nd: 0.0 if nd in ("0", "gnd") else float(r.x_steady_state[names.index("V(%s)" % nd)])
            x["v(%s)" % el] = v(a) - v(c)
    print(json.dumps({"seconds": sorted(times)[1], "converged": bool(r.converged), "iterations": int(r.n_iterations),
                      "runs": int(r.n_simulations), "residual": float(r.final_residual), "x": x}))


def pulsim_shooting(build, tmp):
    """Per converter and step: pulsim's steady state, its time and its error against catchup's x0."""
    rows = []
    for name in PULSIM_CONVERTERS:
        ref, labels = x0_of(build, name, tmp)
        for n in PULSIM_STEPS:
            try:
                r = subprocess.run([sys.executable, os.path.abspath(__file__), "--pulsim-one", name, str(n)],
                                   capture_output=True, text=True, timeout=120)
                d = json.loads(r.stdout.strip().splitlines()[-1]) if r.returncode == 0 else None
            except subprocess.TimeoutExpired:
                d = None
            if not d:
                rows.append({"name": name, "n": n, "failed": "no result in 120 s" if r is None else r.stderr[-200:]})
                continue
            err = max(abs(d["x"][lab] - ref[k]) for k, lab in enumerate(labels)) / np.abs(ref).max()
            rows.append(dict(d, name=name, n=n, error=err))
            print(rows[-1], flush=True)
    return rows


LOOSE_MAP_TOL = 1e-6


def catchup_loose(build, name, reps, tmp):
    """catchup-run --steady-state with the period map at tol 1e-6 (the default
    1e-12): its median solve time, Newton steps, period runs and the max-norm
    distance of its x0 from the default's over the state's largest entry."""
    ref, _ = x0_of(build, name, tmp)
    out = os.path.join(tmp, "loose.h5")
    args = [os.path.join(build, "apps", "catchup-run"), sb.cir(name), "-o", out, "--steady-state",
            "--set", "steady_state.map_tol=%g" % LOOSE_MAP_TOL]
    times, line = [], ""
    for _ in range(reps):
        r = subprocess.run(args, capture_output=True, text=True)
        line = [x for x in r.stderr.splitlines() if ": steady state: " in x][-1]
        times.append(float(re.search(r"period runs, ([0-9.e+-]+) s;", line).group(1)))
    with h5py.File(out, "r") as f:
        x0 = f["steady_state"]["x0"][:]
        it = len(f["steady_state"]["residuals"][:]) - 1
    return {"name": name, "seconds": float(np.median(times)), "iterations": it,
            "runs": int(re.search(r"(\d+) period runs", line).group(1)),
            "error": float(np.abs(x0 - ref).max() / np.abs(ref).max())}


def values(lo, hi, k, log):
    v = np.geomspace(lo, hi, k) if log else np.linspace(lo, hi, k)
    return "[" + ", ".join("%.6g" % x for x in v) + "]"


def study_file(tmp, k):
    path = os.path.join(tmp, "buck-study.yaml")
    base = os.path.join(ROOT, "examples", "circuits", "buck-design.yaml")
    with open(path, "w") as f:
        f.write("name: buck-study\nbase: %s\nvariants:\n  - name: buck\n    grid:\n" % base)
        f.write("      netlist.D: %s\n" % values(0.1, 0.9, k, False))
        f.write("      netlist.L: %s\n" % values(5e-6, 200e-6, k, True))
        f.write("      netlist.C: %s\n" % values(2e-6, 100e-6, k, True))
        f.write("      netlist.R: %s\n" % values(1, 50, k, True))
    return path


def sweep(build, path, ranks, tmp):
    out = os.path.join(tmp, "study-%d.h5" % ranks)
    cmd = [os.path.join(build, "apps", "catchup-sweep"), path, "-o", out, "--log-progress"]
    if ranks > 1:
        cmd = ["mpirun", "-n", str(ranks)] + cmd
    ru0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    r = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    ru1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (ru1.ru_utime - ru0.ru_utime) + (ru1.ru_stime - ru0.ru_stime)
    if r.returncode:
        sys.exit("catchup-sweep failed: " + r.stderr[-2000:])
    line = [s for s in r.stderr.splitlines() if "parallel efficiency" in s][-1]
    with h5py.File(out, "r") as f:
        ss = f["steady_state"][:]
        summ = f["summary"][:]
    eff = re.search(r"parallel efficiency ([0-9.]+)", line).group(1)
    inner = re.search(r", ([0-9.e+-]+) s on (\d+) rank", line)
    return {"ranks": ranks, "wall": wall, "cpu": cpu, "sweep_s": float(inner.group(1)), "own_eff": float(eff), "line": line,
            "tasks": len(ss), "ok": int((summ["status"] == 0).sum()), "solved": int((ss["solved"] == 1).sum()),
            "iters": (int(ss["newton_iterations"].min()), float(np.median(ss["newton_iterations"])),
                      int(ss["newton_iterations"].max())),
            "mu": float(np.nanmax(ss["max_multiplier"])), "task_ms": 1e3 * float(np.median(summ["wall_time_s"])),
            "statuses": dict(zip(*[list(map(lambda b: b.decode(), u)) if i == 0 else list(map(int, u))
                                  for i, u in enumerate(np.unique(summ["status_name"], return_counts=True))]))}


def fixed_costs(build, reps):
    """MPI's own start-up, no sweep: medians of the wall times of `mpirun -n 3
    true` (the launcher alone) and of `catchup-sweep --version` on 1 rank and
    under `mpirun -n 3` (the program's libraries loaded, MPI_Init and
    MPI_Finalize, nothing else)."""
    prog = os.path.join(build, "apps", "catchup-sweep")
    cmds = {"mpirun_true": ["mpirun", "-n", "3", "true"], "version_1": [prog, "--version"],
            "version_3": ["mpirun", "-n", "3", prog, "--version"]}
    out = {k: [] for k in cmds}
    for _ in range(reps):
        for k, c in cmds.items():
            t0 = time.perf_counter()
            subprocess.run(c, capture_output=True, check=True)
            out[k].append(time.perf_counter() - t0)
    return {k: float(np.median(v)) for k, v in out.items()}


def median_run(xs):
    """The run of median wall time, with the medians of the wall, CPU and
    dispatch times over all runs (the study's figures are the same in each)."""
    out = dict(sorted(xs, key=lambda x: x["wall"])[len(xs) // 2])
    for key in ("wall", "cpu", "sweep_s", "own_eff", "task_ms"):
        out[key] = float(np.median([x[key] for x in xs]))
    out["n_runs"] = len(xs)
    return out


def study_text(runs, k, fixed):
    one = next(x for x in runs if x["ranks"] == 1)
    three = next(x for x in runs if x["ranks"] == 3)
    out = ["**A design study of %d buck variants** (examples/circuits/buck-design.yaml, a grid of %d duties "
           "0.1-0.9 x %d inductances 5-200 uH x %d capacitances 2-100 uF x %d loads 1-50 ohm, generated by the "
           "sweep file's `grid:`; each task a steady state and its period measured, its variant's scene loaded by "
           "the task itself): `catchup-sweep` on 1 rank and under `mpirun -n 3` (rank 0 dispatches, 2 workers on "
           "the 2 cores), %d runs of each in turn, medians. Target: <= 60 s on 2 cores at a parallel efficiency "
           ">= 0.9. The efficiency is T(1 rank) / (2 T(3 ranks)) of the whole process (mpirun's start included) "
           "and of the dispatch (from the first job sent to the last row written; catchup-sweep's summary line), "
           "and catchup-sweep's own figure: the jobs' wall time over 2 x its own time." % (
               one["tasks"], k, k, k, k, one["n_runs"]), "",
           "| ranks | wall time (process) | CPU time (all processes) | sweep's own time (dispatch) | "
           "T(1 rank) / (workers x T), process | the same, dispatch | catchup-sweep's efficiency figure | "
           "CPU(1 rank) / CPU | tasks ok | steady states | Newton steps min/median/max | task median | "
           "largest multiplier |",
           "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for x in runs:
        workers = max(1, x["ranks"] - 1)
        out.append("| %d | %.2f s | %.1f s | %.2f s | %.2f | %.2f | %.2f | %.2f | %d of %d | %d | %d / %g / %d | "
                   "%.2f ms | %.4g |" % (x["ranks"], x["wall"], x["cpu"], x["sweep_s"], one["wall"] / (workers * x["wall"]),
                                         one["sweep_s"] / (workers * x["sweep_s"]), x["own_eff"], one["cpu"] / x["cpu"],
                                         x["ok"], x["tasks"], x["solved"], *x["iters"], x["task_ms"], x["mu"]))
    f1, f3 = fixed["version_1"], fixed["version_3"]
    eff, eff_d = one["wall"] / (2 * three["wall"]), one["sweep_s"] / (2 * three["sweep_s"])
    eff_nompi = (one["wall"] - f1) / (2 * (three["wall"] - f3))
    out += ["", "**MPI's own start-up**, measured in the same run (%d times each, medians): `mpirun -n 3 true` "
            "(the launcher alone) %.2f s; `catchup-sweep --version` (its libraries loaded, MPI_Init and "
            "MPI_Finalize, no sweep) %.2f s on 1 rank (Open MPI's singleton start) and %.2f s under `mpirun -n 3`. "
            "The study's time beyond its dispatch (process minus dispatch) is %.2f s on 1 rank and %.2f s on 3 "
            "ranks (there the dispatch's clock starts when the workers get their first batches, before rank 0 "
            "makes the variants' texts and the results file). Parallel efficiency of the whole process %.2f, of "
            "the dispatch %.2f, of the process less MPI's start-up, (T(1) - %.2f) / (2 (T(3) - %.2f)), %.2f: the "
            "target 0.9 is %s by the whole process%s." % (
                fixed["n"], fixed["mpirun_true"], f1, f3, one["wall"] - one["sweep_s"], three["wall"] - three["sweep_s"],
                eff, eff_d, f1, f3, eff_nompi, "met" if eff >= 0.9 else "missed",
                "" if eff >= 0.9 else (" and met without MPI's start-up" if eff_nompi >= 0.9 else
                                       " and by the dispatch too" if eff_d < 0.9 else ""))]
    out += ["", "Load average (1, 5, 15 min) at the end: %s. With other sessions on the 2 cores the wall times "
            "measure their load: a run gets the cores' share the scheduler leaves it, whatever its ranks (the "
            "process's CPU time over its wall time says how much). What the sweep itself costs in parallel is the "
            "CPU column: CPU(1 rank) / CPU(3 ranks) is the share of the 3-rank run's work that the 1-rank run also "
            "does, the efficiency's bound on an idle machine (the 3-rank run adds mpirun, rank 0's dispatch and "
            "MPI's polling). On 3 ranks the workers start on their first batches before rank 0 makes the "
            "variants' scene texts (for /variants) and the results file (docs/sweep-format.md); before (28c84f3, "
            "same script at load 0.8) 1 rank 3.9 s, 3 ranks 2.2 s, 0.86 by the process, 0.97 by the dispatch." % (
                ", ".join("%.1f" % v for v in os.getloadavg())),
            "", "Statuses (1 rank): %s." % ", ".join("%s %d" % kv for kv in one["statuses"].items()), ""]
    return out


def section(rows, runs, reps, k, ng, pul, loose=None, fixed=None):
    out = ["<!-- BEGIN design: generated by scripts/bench-design; do not edit -->",
           "## Switched converters' steady states and a design study", "",
           "Command: `bash scripts/bench-design` (%d runs each, medians; this machine's 2 cores shared with other "
           "sessions: times are noisy). `catchup-run CONVERTER.cir --steady-state`: the solve's wall time (the "
           "switched integrator's adaptive map at tol 1e-12, Newton to a residual of 1e-10 relative, the monodromy "
           "by finite differences). Brute force: catchup's adaptive scheme at tol 1e-12 from rest until the change "
           "from one period's end to the next is below 1e-10 of the state's largest entry." % reps, "",
           "| converter | Newton steps | period runs | final residual | largest multiplier | steady state "
           "(target 5 ms) | brute force: periods | brute force: time | ratio |", "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if "failed" in r:
            out.append("| %s | | | | | none: %s | | | |" % (r["name"], r["failed"].replace("|", "/")[:150]))
            continue
        b = r["brute"]
        if "failed" in b:
            bf, bt, ratio = "failed: " + b["failed"], "", ""
        else:
            bf = str(b["reached"] or ">%d (last change %.1e)" % (b["periods"], b["last_change"]))
            bt, ratio = "%.3g ms" % (1e3 * b["seconds"]), "%.2g" % (b["seconds"] / r["seconds"])
        out.append("| %s | %d | %d | %.1e | %.4g | %.3g ms | %s | %s | %s |" % (
            r["name"], r["iterations"], r["runs"], r["residual"], r["mu"], 1e3 * r["seconds"], bf, bt, ratio))
    ours = next(r for r in rows if r["name"] == NGSPICE_CONVERTER)
    out += ["", "**ngspice's brute force** on `%s` (the near-ideal copy of scripts/converters_compare.py: RON 1 mOhm, "
            "ROFF 1 GOhm, 1 ns edges, `%s`; TSTEP = TMAX = T/200, its states at each period's end interpolated "
            "between its time points, written at 15 digits), over 4x the periods catchup's brute force needs:" % (
                NGSPICE_CONVERTER, cc.DIODE), "",
            "| ngspice setting | periods run | first period below %g | transient time to it | smallest "
            "change seen | catchup steady state | ratio |" % sb.TARGET, "|---|---|---|---|---|---|---|"]
    for g in ng:
        if g.get("failed"):
            out.append("| %s | | failed: %s | | | | |" % (g["setting"], g["failed"]))
            continue
        t = g.get("run_to_k_s") or g["run_s"]
        ratio = t / ours["seconds"]
        out.append("| %s | %d | %s | %.3g ms | %.1e | %.3g ms | %s%.0fx |" % (
            g["setting"], g["periods"], g["reached"] or "never", 1e3 * t, g["min_change"],
            1e3 * ours["seconds"], "" if g["reached"] else ">", ratio))
    if pul is not None:
        out += ["", "**pulsim's `run_periodic_shooting`** (pulsim %s from PyPI; the circuit as scripts/converters_compare.py "
                "builds it: switches g_on 1e3 S, g_off 1e-9 S, the gates as a schedule; a fixed step dt = T/N, Newton "
                "to 1e-10, 3 runs each, median); error: the max-norm distance of its steady state from catchup's "
                "(the exact map's fixed point to 6e-10) over the state's largest entry:" % pulsim_version(), "",
                "| converter | N (dt = T/N) | pulsim: time | converged | Newton steps | simulations | error | catchup "
                "steady state (error <= 1e-9) | ratio |", "|---|---|---|---|---|---|---|---|---|"]
        for q in pul:
            ours_q = next(r for r in rows if r["name"] == q["name"])
            if "failed" in q:
                out.append("| %s | %d | failed: %s | | | | | | |" % (q["name"], q["n"], q["failed"].replace("|", "/")))
                continue
            out.append("| %s | %d | %.3g ms | %s | %d | %d | %.1e | %.3g ms | %.0fx |" % (
                q["name"], q["n"], 1e3 * q["seconds"], "yes" if q["converged"] else "no (residual %.1e)" % q["residual"],
                q["iterations"], q["runs"], q["error"],
                1e3 * ours_q["seconds"], q["seconds"] / ours_q["seconds"]))
        if loose:
            best = {}
            for q in pul:
                if "failed" not in q and q["converged"] and (q["name"] not in best or q["error"] < best[q["name"]]["error"]):
                    best[q["name"]] = q
            out += ["", "**At matched accuracy.** pulsim's best (its smallest error above, which its step sets) beside "
                    "catchup with the period map at tol %g instead of 1e-12 (%d runs, median); error as above, "
                    "against catchup's default steady state:" % (LOOSE_MAP_TOL, reps), "",
                    "| converter | pulsim's best: N, error, time | catchup at map tol %g: Newton steps, period runs, "
                    "error, time | catchup default: error <= 1e-9, time | ratio, matched | ratio, default |" % LOOSE_MAP_TOL,
                    "|---|---|---|---|---|---|"]
            for c in loose:
                q, d = best.get(c["name"]), next(r for r in rows if r["name"] == c["name"])
                if not q:
                    out.append("| %s | did not converge | | | | |" % c["name"])
                    continue
                out.append("| %s | %d, %.1e, %.3g ms | %d, %d, %.1e, %.3g ms | %.3g ms | %.0fx | %.0fx |" % (
                    c["name"], q["n"], q["error"], 1e3 * q["seconds"], c["iterations"], c["runs"], c["error"],
                    1e3 * c["seconds"], 1e3 * d["seconds"], q["seconds"] / c["seconds"], q["seconds"] / d["seconds"]))
            out += ["", "The buck's and the boost's period maps are exact between the gate edges (matrix "
                    "exponentials, no events inside the period), so a looser tol changes neither their Newton steps "
                    "nor their runs: catchup's time does not fall with the accuracy asked, and at pulsim's accuracy "
                    "it is what it is at 1e-9. The DCM buck's map has a diode event inside the period, located to the "
                    "looser tol: its steady state moves by the error shown, its steps and runs stay."]
    out += [""] + study_text(runs, k, fixed) + ["<!-- END design -->"]
    return "\n".join(out)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--per-axis", type=int, default=10)
    ap.add_argument("--no-write", action="store_true")
    ap.add_argument("--sweep-reps", type=int, default=3, help="runs of the study at each rank count, in turn")
    ap.add_argument("--study-only", action="store_true",
                    help="the design study alone: its part of the section is rewritten, the rest kept")
    ap.add_argument("--compare", metavar="BUILD",
                    help="the study alone, with this build and --build in turn, side by side (nothing written)")
    ap.add_argument("--pulsim-one", nargs=2, metavar=("NAME", "N"), help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.pulsim_one:
        return pulsim_one(a.pulsim_one[0], int(a.pulsim_one[1]))
    if a.study_only or a.compare:
        return study_only(a)
    with tempfile.TemporaryDirectory() as tmp:
        rows = converters(a.build, a.reps, tmp)
        ours = next(r for r in rows if r["name"] == NGSPICE_CONVERTER)
        ng = ngspice_brute(NGSPICE_CONVERTER, ours["T"], 4 * sb.periods_needed(ours["mu"]), tmp)
        try:
            import pulsim  # noqa: F401
            pul = pulsim_shooting(a.build, tmp)
            loose = [catchup_loose(a.build, name, a.reps, tmp) for name in PULSIM_CONVERTERS]
            print(loose, flush=True)
        except ImportError:
            print("pulsim not installed (.venv/bin/pip install pulsim): its rows are left out", flush=True)
            pul = loose = None
        path = study_file(tmp, a.per_axis)
        raw = {1: [], 3: []}
        for _ in range(a.sweep_reps):       # 1 rank and 3 ranks in turn: the load they meet is alike
            for ranks in (1, 3):
                raw[ranks].append(sweep(a.build, path, ranks, tmp))
                print({k: v for k, v in raw[ranks][-1].items() if k != "line"}, raw[ranks][-1]["line"], flush=True)
        runs = [median_run(raw[1]), median_run(raw[3])]
        fixed = dict(fixed_costs(a.build, a.reps), n=a.reps)
    text = section(rows, runs, a.reps, a.per_axis, ng, pul, loose, fixed)
    print(text)
    if not a.no_write:
        sb.ngc.write_section("design", text)


def study_only(a):
    """The study (and MPI's fixed costs) alone; with --compare, two builds in
    turn, each run of one beside the same run of the other."""
    builds = [a.compare, a.build] if a.compare else [a.build]
    with tempfile.TemporaryDirectory() as tmp:
        path = study_file(tmp, a.per_axis)
        raw = {(b, r): [] for b in builds for r in (1, 3)}
        for _ in range(a.sweep_reps):
            for ranks in (1, 3):
                for b in builds:
                    raw[(b, ranks)].append(sweep(b, path, ranks, tmp))
                    x = raw[(b, ranks)][-1]
                    print(b, ranks, "wall %.3f dispatch %.3f cpu %.3f" % (x["wall"], x["sweep_s"], x["cpu"]), flush=True)
        fixed = {b: dict(fixed_costs(b, a.reps), n=a.reps) for b in builds}
    for b in builds:
        runs = [median_run(raw[(b, 1)]), median_run(raw[(b, 3)])]
        text = study_text(runs, a.per_axis, fixed[b])
        print("\n## %s\n" % b + "\n".join(text))
        if not a.compare and not a.no_write:
            path = os.path.join(ROOT, "BENCHMARKS.md")
            doc = open(path).read()
            i, j = doc.index("**A design study of"), doc.index("<!-- END design -->")
            open(path, "w").write(doc[:i] + "\n".join(text) + doc[j:])


if __name__ == "__main__":
    main()
