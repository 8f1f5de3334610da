#!/usr/bin/env python3
"""catchup against ngspice on the example circuits (scripts/bench-vs-ngspice).

    python scripts/ngspice_compare.py [--build build] [--out bench-out] [--reps 5]

For each circuit in examples/circuits: the ideal-diode reference (catchup's
adaptive scheme at tol 1e-12, checked against tol 1e-10), then ngspice
(batch mode) with a steep diode model, catchup's adaptive scheme at several
tolerances and its theta scheme at several step counts (theta = 1/2; on the
bridges --bridge-theta, 1/2 by default), every run timed side by
side in this one process, interleaved round by round; the errors are
max-norm against the reference on the .tran grid, relative to each signal's
peak. Writes OUTDIR/ngspice.jsonl, the figures docs/figures/circuit-*.png
(catchup's waveforms with ngspice's dashed over them) and the section of
BENCHMARKS.md between its ngspice markers.

The steep model, D(IS=1e-15 N=0.01): a forward drop N V_T ln(I/IS) of about
9 mV at 0.3 A, 1e-3 of a 10 V peak, which is how far ngspice's voltages sit
from the ideal diode's; its currents differ more near the switching instants,
where the exponential turns on over a few N V_T. `.options rshunt=1e12`
gives every node a 1 TOhm path to ground: without it ngspice stops on the
bridge ("timestep too small", the source's side floats while all four
diodes are off); its current is below 1e-11 A here.
"""
import argparse
import json
import math
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
CIRCUITS = ["halfwave-rc", "bridge", "bridge-lc", "bridge-cfilter", "resonant", "series-resonant", "clamp", "doubler",
            "rl-halfwave", "paper-fig2"]
BRIDGES = ("bridge", "bridge-lc", "bridge-cfilter", "resonant", "series-resonant")
MODEL = "D(IS=1e-15 N=0.01)"
# ngspice diverges on the paper's circuit with N = 0.01 (its two diodes in
# series with the inductors: the inductive kick when one turns off); a
# gentler exponential lets it run.
MODEL_FOR = {"paper-fig2": "D(IS=1e-15 N=0.05)"}
NGSPICE_SETTINGS = [("default", ""), ("tight", "reltol=1e-6 abstol=1e-12 vntol=1e-9")]
FACTORS = [1 / 8, 1 / 2, 2, 8, 32]       # theta's n, times TSTOP / TSTEP
TOLS = [1e-3, 1e-5, 1e-7, 1e-9]          # the adaptive scheme's
REF_TOL, REF_CHECK_TOL = 1e-12, 1e-10
VOLT_TOL = 2e-3      # ngspice against the ideal reference, voltages, relative to the peak, for N = 0.01
                     # (the forward drop, N V_T ln(I/IS), grows with N: so does the tolerance)


def tran_and_probes(path):
    tstep = tstop = None
    probes = []
    for line in open(path):
        w = line.split()
        if not w:
            continue
        if w[0].lower() == ".tran":
            tstep, tstop = spice_number(w[1]), spice_number(w[2])
        if w[0].lower() in (".probe", ".save", ".print"):
            probes += re.findall(r"[vViI]\([^)]*\)", line)
    return tstep, tstop, probes


def spice_number(s):
    m = re.match(r"([-+0-9.eE]+)(meg|[fpnumkgt])?", s.lower())
    scale = {"f": 1e-15, "p": 1e-12, "n": 1e-9, "u": 1e-6, "m": 1e-3, "k": 1e3, "meg": 1e6, "g": 1e9, "t": 1e12}
    return float(m.group(1)) * scale.get(m.group(2), 1)


def ngspice_vector(sig):
    """Our signal name as an ngspice vector."""
    kind, arg = sig[0].lower(), sig[2:-1]
    if kind == "v":
        return "v(%s)" % arg
    e = arg.lower()
    return {"d": "@%s[id]" % e, "r": "@%s[i]" % e, "c": "@%s[i]" % e, "l": "i(%s)" % e, "v": "i(%s)" % e,
            "i": "@%s[current]" % e}[e[0]]


def ngspice_netlist(src, tstep, tstop, vectors, options, out, model):
    """The netlist for ngspice: every diode gets the steep model, .tran gets
    TMAX = TSTEP, our .probe lines give way to .save and a .control block."""
    lines, models = [], set()
    for line in open(src):
        w = line.split()
        low = [x.lower() for x in w]
        if low and low[0] in (".probe", ".save", ".print", ".plot", ".end"):
            continue
        if low and low[0] == ".model" and len(w) >= 3 and low[2] == "d":
            models.add(low[1])
            line = ".model %s %s\n" % (w[1], model)
        elif low and low[0][0] == "d" and len(w) == 3:
            line = line.rstrip("\n") + " dsteep\n"
            models.add("dsteep-needed")
        elif low and low[0] == ".tran":
            line = ".tran %s %s 0 %s uic\n" % (w[1], w[2], w[1])   # x(0) from the ICs, as catchup
        lines.append(line)
    if "dsteep-needed" in models:
        lines.append(".model dsteep %s\n" % model)
    lines.append(".options rshunt=1e12 %s\n" % options)
    saves = []
    for v in vectors:                       # v(a,b) needs v(a) and v(b) saved
        saves += ["v(%s)" % n for n in v[2:-1].split(",")] if v.startswith("v(") else [v]
    lines.append(".save %s\n" % " ".join(dict.fromkeys(saves)))
    lines.append(".control\nrun\nrusage trantime\nwrdata %s %s\n.endc\n.end\n" % (out, " ".join(vectors)))
    return "".join(lines)


def read_h5(path, names):
    import h5py
    with h5py.File(path, "r") as f:
        n = f["t"].shape[0]
        return f["t"][:n], np.array([f["signals"][s][:n] for s in names])


def run_catchup(build, cir, args, probes, tmp):
    """catchup-run with args (["--tol", T] or ["--scheme", "theta", "--n", N, ...]);
    the samples are the netlist's, every TSTEP (interpolated)."""
    out = os.path.join(tmp, "c.h5")
    cmd = [os.path.join(build, "apps", "catchup-run"), cir, "-o", out] + [str(x) for x in args] + \
        sum([["--probe", p] for p in probes], [])
    t0 = time.perf_counter()
    r = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if r.returncode != 0:
        raise RuntimeError("catchup-run failed: %s" % r.stderr.strip())
    m = re.search(r", ([0-9.e+-]+) s: (CUP_\w+)", r.stderr)
    steps = re.search(r"adaptive, (\d+) steps", r.stderr)
    t, x = read_h5(out, probes)
    return {"run_s": float(m.group(1)), "wall_s": wall, "status": m.group(2), "t": t, "x": x,
            "steps": int(steps.group(1)) if steps else None}


def run_ngspice(src, tstep, tstop, probes, options, tmp, model):
    out = os.path.join(tmp, "ng.txt")
    vectors = [ngspice_vector(p) for p in probes]
    net = os.path.join(tmp, "ng.cir")
    open(net, "w").write(ngspice_netlist(src, tstep, tstop, vectors, options, out, model))
    t0 = time.perf_counter()
    r = subprocess.run(["ngspice", "-b", net], capture_output=True, text=True, cwd=tmp)
    wall = time.perf_counter() - t0
    m = re.search(r"Transient analysis time = ([0-9.e+-]+)", r.stdout + r.stderr)
    if not m or not os.path.exists(out):            # ngspice -b exits 1 even when it ran
        stop = re.search(r"Timestep too small; time = ([0-9.e+-]+)", r.stdout + r.stderr)
        why = "stopped at t = %.3g s (timestep too small)" % float(stop.group(1)) if stop else \
            "failed: %s" % (r.stdout + r.stderr).strip().splitlines()[-1][:120]
        return {"run_s": math.nan, "wall_s": wall, "t": None, "x": None, "failed": why}
    d = np.loadtxt(out, ndmin=2)
    os.remove(out)
    stop = re.search(r"Timestep too small; time = ([0-9.e+-]+)", r.stdout + r.stderr)
    failed = None
    if stop or "aborted" in r.stdout + r.stderr or d[-1, 0] < tstop * (1 - 1e-9):
        failed = "stopped at t = %.3g s (timestep too small)" % (float(stop.group(1)) if stop else d[-1, 0])
    return {"run_s": float(m.group(1)), "wall_s": wall, "t": d[:, 0], "x": d[:, 1::2].T, "failed": failed}


def errors(ref_t, ref_x, t, x, probes):
    """The max-norm difference on the reference grid relative to each
    signal's peak, the worst voltage and the worst current, away from the
    jumps of the reference (a step of more than 5 % of the peak and its two
    neighbours on each side): ideal diodes put jumps in voltages and
    currents, and a sampled waveform misplaces a jump by up to a sample,
    an O(1) difference whatever the step."""
    ev = ei = 0.0
    where = None                                    # (signal, time) of the worst voltage
    for k, p in enumerate(probes):
        peak = max(np.max(np.abs(ref_x[k])), 1e-300)
        jump = np.abs(np.diff(ref_x[k])) > 0.05 * peak
        near = np.zeros(len(ref_t), bool)
        for j in np.nonzero(jump)[0]:
            near[max(0, j - 1):j + 3] = True
        d = np.abs(np.interp(ref_t, t, x[k]) - ref_x[k])[~near]
        e = np.max(d) / peak if np.all(np.isfinite(d)) else math.inf
        if p[0].lower() == "v":
            if e > ev and np.isfinite(e):
                where = (p, float(ref_t[~near][np.argmax(d)]))
            ev = max(ev, e)
        else:
            ei = max(ei, e)
    return ev, ei, where


def compare_circuit(name, a, tmp, log):
    cir = os.path.join(ROOT, "examples", "circuits", name + ".cir")
    tstep, tstop, probes = tran_and_probes(cir)
    base = int(round(tstop / tstep))
    ref = run_catchup(a.build, cir, ["--tol", REF_TOL], probes, tmp)
    check = run_catchup(a.build, cir, ["--tol", REF_CHECK_TOL], probes, tmp)
    ref_err = errors(ref["t"], ref["x"], check["t"], check["x"], probes)[:2]
    print("%s: reference adaptive tol %g (against tol %g: %.1e V, %.1e A of the peaks)" % (
        name, REF_TOL, REF_CHECK_TOL, *ref_err), file=sys.stderr)
    theta = a.bridge_theta if name in BRIDGES else 0.5
    runs = []
    for rep in range(a.reps):                       # interleaved: every configuration once per round
        for label, opts in NGSPICE_SETTINGS:
            r = run_ngspice(cir, tstep, tstop, probes, opts, tmp, MODEL_FOR.get(name, MODEL))
            runs.append(("ngspice", label, r))
        for tol in TOLS:
            runs.append(("catchup", "adaptive tol=%g" % tol, run_catchup(a.build, cir, ["--tol", tol], probes, tmp)))
        for f in FACTORS:
            n = max(1, int(round(f * base)))
            runs.append(("catchup", "theta(%g) n=%d" % (theta, n), run_catchup(
                a.build, cir, ["--scheme", "theta", "--n", n, "--set", "theta=%g" % theta], probes, tmp)))
    rows = []
    for tool, label in dict.fromkeys((t, l) for t, l, _ in runs):
        rs = [r for t, l, r in runs if t == tool and l == label]
        failed = rs[0].get("failed")
        ev, ei, where = (math.inf, math.inf, None) if failed else errors(ref["t"], ref["x"], rs[0]["t"],
                                                                          rs[0]["x"], probes)
        rows.append({"circuit": name, "tool": tool, "config": label, "model": MODEL_FOR.get(name, MODEL),
                     "failed": failed, "worst_v_at": where, "run_s": statistics.median(r["run_s"] for r in rs),
                     "wall_s": statistics.median(r["wall_s"] for r in rs), "err_v": ev, "err_i": ei,
                     "ref_err_v": ref_err[0], "ref_err_i": ref_err[1], "reps": len(rs),
                     "steps": rs[0].get("steps"), "theta": theta})
        log.write(json.dumps(rows[-1]) + "\n")
    ng_best = min((r for r in rows if r["tool"] == "ngspice"), key=lambda r: r["err_v"])
    ng_plot = [r for t, l, r in runs if t == "ngspice" and l == ng_best["config"]][0]
    plot(name, probes, ref, ng_plot if not ng_best["failed"] else None, MODEL_FOR.get(name, MODEL),
         ng_best["config"])
    return rows


def plot(name, probes, ref, ng, model, setting):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    volts = [k for k, p in enumerate(probes) if p[0].lower() == "v"]
    amps = [k for k, p in enumerate(probes) if p[0].lower() == "i"]
    panels = [p for p in (volts, amps) if p]
    fig, axes = plt.subplots(len(panels), 1, sharex=True, figsize=(8, 2.6 * len(panels) + 0.6), squeeze=False)
    scale, unit = (1e3, "ms") if ref["t"][-1] < 1 else (1, "s")
    for ax, ks, ylabel in zip(axes[:, 0], panels, ["V" if volts else "A", "A"]):
        for k in ks:
            line, = ax.plot(ref["t"] * scale, ref["x"][k], lw=1.3, label=probes[k] + " catchup")
            if ng:
                ax.plot(ng["t"] * scale, ng["x"][k], "--", lw=0.9, color="k", alpha=0.6,
                        label=probes[k] + " ngspice" if k == ks[0] else None)
        ax.set_ylabel(ylabel)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, ncol=2, loc="upper right")
    axes[-1, 0].set_xlabel("t (%s)" % unit)
    axes[0, 0].set_title("%s: catchup (ideal diodes) and ngspice (%s, %s, dashed)" % (name, model, setting)
                         if ng else "%s: catchup (ideal diodes); ngspice (%s) failed" % (name, model), fontsize=10)
    fig.tight_layout()
    os.makedirs(os.path.join(ROOT, "docs", "figures"), exist_ok=True)
    fig.savefig(os.path.join(ROOT, "docs", "figures", "circuit-%s.png" % name), dpi=110)
    plt.close(fig)


def adaptive_cost(a, tmp):
    """The adaptive scheme's time loop on 5 periods of the 50 Hz bridge at
    tol 1e-8 (final state only), and its steps against the samples asked."""
    cir = os.path.join(ROOT, "examples", "circuits", "bridge.cir")
    base = ["--tol", 1e-8, "--set", "T=0.1"]
    loop = [run_catchup(a.build, cir, base + ["--set", "output=final"], ["v(out)"], tmp) for _ in range(max(a.reps, 5))]
    out = {"loop_s": statistics.median(r["run_s"] for r in loop), "loop_steps": loop[0]["steps"], "samples": []}
    for S in (2, 1001, 100001):
        rs = [run_catchup(a.build, cir, base + ["--set", "output.samples=%d" % S], ["v(out)"], tmp)
              for _ in range(max(a.reps, 3))]
        out["samples"].append((S, rs[0]["steps"], statistics.median(r["run_s"] for r in rs),
                               statistics.median(r["wall_s"] for r in rs)))
    return out


def cost_text(c):
    rows = "; ".join("%d samples: %d steps, %.3g s in the integrator (%.3g s the process)" % s for s in c["samples"])
    return ["### The adaptive scheme's cost on the bridge", "",
            "Five periods of `bridge.cir`'s 50 Hz line (T = 100 ms) at tol 1e-8, final state only: the time loop "
            "takes %.3g ms (%d steps; catchup-run's time in the integrator, median). Samples are interpolated "
            "from the exact flow, not stepped to: %s." % (1e3 * c["loop_s"], c["loop_steps"], rows), ""]


def section(rows, cost=None):
    thetas = sorted({r["theta"] for r in rows if r["circuit"] in BRIDGES})
    out = ["<!-- BEGIN ngspice: generated by scripts/bench-vs-ngspice; do not edit -->",
           "## Circuits: catchup against ngspice", "",
           "Command: `bash scripts/bench-vs-ngspice` (ngspice %s from Debian's `ngspice`, batch mode; "
           "every diode `%s` unless said otherwise; `.tran` with TMAX = TSTEP and UIC (the initial state from the "
           "ICs, 0 by default, as in catchup); `.options rshunt=1e12`, without which ngspice stops on the bridge). "
           "catchup runs each netlist as `catchup-run` does by default, the adaptive scheme (`--tol`, every "
           "`.tran` TSTEP sampled from its exact flow), and the θ scheme at a fixed step (`--scheme theta --n N`, "
           "%s). Errors are max-norm differences on the "
           "`.tran` grid from catchup's adaptive scheme at tol %g (checked against tol %g), relative to "
           "each signal's peak: the worst voltage and the worst current of the netlist's `.probe` signals, "
           "away from the reference's jumps (two samples on each side of a step of more than 5 %% of the "
           "peak: a sampled waveform misplaces a jump by up to a sample, an O(1) difference whatever the "
           "step). "
           "Times are medians of interleaved rounds "
           "in one run: `run` is each tool's own count (ngspice's transient analysis time, 1 ms "
           "resolution; catchup-run's time in the integrator, with the signals and HDF5 writes), `process` "
           "the whole command (on circuits this small mostly each program's start-up: loading its libraries, "
           "for catchup-run creating the HDF5 file)." % (
               ngspice_version(), MODEL, "θ = ½, through the bridges too (issue 30's fix)" if thetas in ([], [0.5])
               else "θ = ½; on the bridges θ = %s" % ", ".join("%g" % t for t in thetas), REF_TOL, REF_CHECK_TOL), ""]
    for name in CIRCUITS:
        rs = [r for r in rows if r["circuit"] == name]
        if not rs:
            continue
        model = "" if rs[0]["model"] == MODEL else " (ngspice's diode: `%s`)" % rs[0]["model"]
        out += ["### %s%s" % (name, model), "", "![%s](docs/figures/circuit-%s.png)" % (name, name), "",
                "Reference against tol %g: %.1e of the peak voltage, %.1e of the peak current." % (
                    REF_CHECK_TOL, rs[0]["ref_err_v"], rs[0]["ref_err_i"]), "",
                "| tool | setting | voltage error | current error | run | process |",
                "|---|---|---:|---:|---:|---:|"]
        for r in rs:
            label = r["config"] + (" (%d steps)" % r["steps"] if r.get("steps") else "")
            if r.get("failed"):
                out.append("| %s | %s | %s | | %s | %.3g s |" % (r["tool"], label, r["failed"],
                                                                 "" if math.isnan(r["run_s"]) else
                                                                 "%.3g s" % r["run_s"], r["wall_s"]))
            else:
                out.append("| %s | %s | %.1e | %.1e | %.3g s | %.3g s |" % (
                    r["tool"], label, r["err_v"], r["err_i"], r["run_s"], r["wall_s"]))
        for r in rs:
            if r["tool"] == "ngspice" and r.get("worst_v_at") and r["err_v"] >= 0.1:
                out += ["", "ngspice %s: its worst voltage difference, %.2g times the peak, is in %s at t = "
                        "%.4g s." % (
                            r["config"], r["err_v"], r["worst_v_at"][0], r["worst_v_at"][1])]
        out += equal_error(rs)
        ng = min((r for r in rs if r["tool"] == "ngspice"), key=lambda r: r["err_v"])
        if ng.get("failed"):
            out += ["", "ngspice does not finish this circuit (%s)." % ng["failed"], ""]
            continue
        target = ng["err_v"]
        tol = VOLT_TOL * float(re.search(r"N=([0-9.e-]+)", ng["model"]).group(1)) / 0.01
        ok = [r for r in rs if r["tool"] == "catchup" and r["err_v"] <= target]
        verdict = "ngspice and the ideal circuit agree to %.1e of the peak voltage (tolerance %.0e): %s." % (
            target, tol, "PASS" if target <= tol else "FAIL")
        if ok:
            c = min(ok, key=lambda r: r["run_s"])
            out += ["", "At ngspice's accuracy (voltage error %.1e): ngspice %s %.3g s, catchup %s %.3g s "
                    "(%.0fx; process %.3g s against %.3g s, %.1fx). %s" % (
                        target, ng["config"], ng["run_s"], c["config"], c["run_s"],
                        ng["run_s"] / max(c["run_s"], 1e-9), ng["wall_s"], c["wall_s"],
                        ng["wall_s"] / c["wall_s"], verdict)]
        else:
            out += ["", verdict]
        out.append("")
    if cost:
        out += cost_text(cost)
    out.append("<!-- END ngspice -->")
    return "\n".join(out)


def equal_error(rs):
    """The adaptive scheme against theta at equal error: for each tol, the
    cheapest theta run whose worse error (voltage or current) is no larger;
    where none is, theta's steps and time extrapolated from its two finest
    runs at their observed order (marked ~)."""
    worse = lambda r: max(r["err_v"], r["err_i"])
    steps = lambda r: int(r["config"].split("n=")[1])
    thetas = sorted((r for r in rs if r["config"].startswith("theta") and not r.get("failed")), key=steps)
    ratio = lambda a, b: "%.2gx" % (a / max(b, 1e-9))
    lines = []
    for a in (r for r in rs if r["config"].startswith("adaptive") and not r.get("failed")):
        e = worse(a)
        ok = [t for t in thetas if worse(t) <= e]
        if ok:
            t = min(ok, key=lambda r: r["run_s"])
            lines.append("| %s | %.1e | %.3g s | %s | %.1e | %.3g s | %s |" % (
                a["config"], e, a["run_s"], t["config"], worse(t), t["run_s"], ratio(t["run_s"], a["run_s"])))
            continue
        t1, t2 = thetas[-2:] if len(thetas) >= 2 else (None, None)
        p = math.log(worse(t1) / worse(t2)) / math.log(steps(t2) / steps(t1)) \
            if t1 and worse(t1) > 0 and worse(t2) > 0 and worse(t1) > worse(t2) else 0
        if e > 0 and p > 0.3:
            n = steps(t2) * (worse(t2) / e) ** (1 / p)
            if n > 100 * steps(t2):               # too far to extrapolate: a bound
                n = 100 * steps(t2)
                secs = t2["run_s"] * 100
                lines.append("| %s | %.1e | %.3g s | more than 100 times its finest n (order %.1f from n = %d, %d) "
                             "| | > %.2g s | > %s |" % (a["config"], e, a["run_s"], p, steps(t1), steps(t2), secs,
                                                     ratio(secs, a["run_s"])))
                continue
            secs = t2["run_s"] * n / steps(t2)
            lines.append("| %s | %.1e | %.3g s | ~n = %.2g (order %.1f from n = %d, %d) | | ~%.2g s | ~%s |" % (
                a["config"], e, a["run_s"], n, p, steps(t1), steps(t2), secs, ratio(secs, a["run_s"])))
        else:
            lines.append("| %s | %.1e | %.3g s | none of the θ runs%s | | | |" % (
                a["config"], e, a["run_s"], " (the adaptive run is exact here)" if e == 0 else ""))
    if not lines:
        return []
    return ["", "At equal error, the adaptive scheme against θ (the worse of the voltage and the current "
            "error; the cheapest θ run above at least as accurate, or, marked ~, θ's steps and time extrapolated "
            "from its two finest runs at their observed order, up to 100 times the finest n):", "",
            "| adaptive | error | run | θ | error | run | θ / adaptive |", "|---|---:|---:|---|---:|---:|---:|"] + lines


def ngspice_version():
    r = subprocess.run(["ngspice", "-v"], capture_output=True, text=True)
    m = re.search(r"ngspice-(\S+)", r.stdout + r.stderr)
    return m.group(1) if m else "?"


def write_section(name, text):
    """BENCHMARKS.md with its block from "<!-- BEGIN NAME" to "<!-- END NAME -->" replaced
    by text (which carries both markers), or text appended when there is no such block;
    every generated section of the bench scripts is written so."""
    path = os.path.join(ROOT, "BENCHMARKS.md")
    doc = open(path).read() if os.path.exists(path) else "# Benchmarks\n"
    m = re.search(r"<!-- BEGIN %s.*?<!-- END %s -->" % (re.escape(name), re.escape(name)), doc, re.S)
    doc = doc[:m.start()] + text + doc[m.end():] if m else doc.rstrip("\n") + "\n\n" + text + "\n"
    with open(path, "w") as f:
        f.write(doc)


def bench_arguments(circuits):
    """The options of a comparison over circuits (converters_compare.py's too): the
    build, where its records go, the repetitions, the circuits (all by default)."""
    ap = argparse.ArgumentParser()
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--out", default="bench-out")
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--only", nargs="*", default=circuits)
    return ap


def compare_all(a, log_name, compare_one, cost_name, cost_of):
    """compare_one(name, tmp, log) for each circuit of a.only, then cost_of(a, tmp):
    their rows and the cost, each logged (JSON lines) into a.out/log_name."""
    os.makedirs(a.out, exist_ok=True)
    rows = []
    with tempfile.TemporaryDirectory() as tmp, open(os.path.join(a.out, log_name), "w") as log:
        for name in a.only:
            rows += compare_one(name, tmp, log)
        cost = cost_of(a, tmp)
        log.write(json.dumps({cost_name: cost}) + "\n")
    return rows, cost


def main():
    ap = bench_arguments(CIRCUITS)
    ap.add_argument("--bridge-theta", type=float, default=0.5,
                    help="theta of the theta scheme on the bridges (1: implicit Euler, first order)")
    a = ap.parse_args()
    rows, cost = compare_all(a, "ngspice.jsonl", lambda name, tmp, log: compare_circuit(name, a, tmp, log),
                             "adaptive_cost", adaptive_cost)
    text = section(rows, cost)
    write_section("ngspice", text)
    print(text)


if __name__ == "__main__":
    main()
