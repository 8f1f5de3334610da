#!/usr/bin/env python3
"""catchup against ngspice and pulsim on the converters and rectifiers
(scripts/bench-converters).

    python scripts/converters_compare.py [--build build] [--out bench-out] [--reps 5] [--only NAME ...]

Each example of examples/circuits (below) runs, interleaved round by round
in this one process:
  * the exact reference: build/tests/pwl_ref_dump (tests/pwl_ref.h: the
    circuit's topologies written by hand, matrix exponentials between
    events bracketed to ulps), on the netlist's .tran grid;
  * catchup-run: the adaptive scheme at tol 1e-3 .. 1e-9 and theta at
    fixed steps, sampled on the .tran grid; and cheaper settings recorded
    at its own steps (--set output.every=1; a netlist catchup refuses is
    reported with its message);
  * ngspice (batch) on a near-ideal copy written here: switches RON = 1 mOhm,
    ROFF = 1 GOhm, `jump` edges 1 ns, every diode D(IS=1e-15 N=0.01),
    .options rshunt=1e12, TMAX = TSTEP, UIC; default and tight tolerances;
  * pulsim (PyPI, v2): the same circuit built with its CircuitBuilder, its
    switch and diode the conductance pair g_on = 1e3, g_off = 1e-9 (its
    switch's defaults in add_buck and the like; its diodes' there are
    g_off = 1e-6), gates as a NativeMultiMaskPwm schedule; the fixed-step
    engine (dt = Ts/100, Ts/1000) and the variable-step ones (trbdf2 with
    its step capped at TSTEP, dsed with its default cap, 10 us, sampled at
    its own steps) at rtol 1e-6 and 1e-9.
Errors: every tool's states (inductor currents, capacitor voltages: the
netlist formulation's x) at the points it reports, interpolated linearly
onto the .tran grid, against the reference there, max-norm of each
relative to its peak, the worst state; samples within two of a jump of the
reference (a step of more than 5 % of the peak) are left out (a sampled
waveform misplaces a jump by up to a sample). Times: each tool's own count
(catchup-run's time in the integrator, ngspice's transient analysis time,
pulsim's simulate() call) and the whole process for the command-line tools.
Writes OUTDIR/converters.jsonl, docs/figures/converter-NAME.png and the
section of BENCHMARKS.md between its converters markers.
"""
import json
import math
import os
import re
import statistics
import subprocess
import sys
import time
import warnings

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from ngspice_compare import bench_arguments, compare_all, ngspice_version, write_section  # noqa: E402

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
EXAMPLES = ["buck-ccm", "buck-dcm", "boost", "buckboost", "flyback", "fullbridge", "sixpulse", "precision-rectifier"]
TOLS = [1e-3, 1e-5, 1e-7, 1e-9]
THETA_FACTORS = [0.1, 1, 10]              # theta's n, times TSTOP / TSTEP
OWN_STEPS = ["--set", "output.every=1"]   # catchup-run at its own steps (docs/netlist.md)
OWN_TOLS = [1e-3, 1e-6]                   # the adaptive scheme's tol at its own steps
OWN_THETA_PER_PERIOD = [2, 4, 10, 30, 100]  # theta's n at its own steps, times the switching periods
OWN_HMAX = [3, 5, 10]                     # the adaptive scheme's hmax at its own steps: Ts / OWN_HMAX
                                          # (Ts/5: the full bridge's 24 us windows in two steps, just under
                                          # pulsim pwl Ts/100's error there: 9.9e-2 against 1.0e-1, measured)
OWN_SAMPLES_PER_PERIOD = [10, 30, 100]    # the adaptive scheme's dense output on a coarser uniform grid
OUTPUT_TOLS = [3e-2, 1e-2, 3e-3, 1e-3, 3e-4, 1e-4, 8e-5, 3e-5, 1e-5]  # its dense output where lines need points (output.tol);
# half decades, and 8e-5: just under pulsim pwl's 8.4e-5 on the precision rectifier (said in the text)
SWITCH = "RON=1m ROFF=1e9"
DIODE = "D(IS=1e-15 N=0.01)"
NGSPICE_SETTINGS = [("default", ""), ("tight", "reltol=1e-6 abstol=1e-12 vntol=1e-9")]
G_ON, G_OFF = 1e3, 1e-9


# ---- the netlists ------------------------------------------------------------------

def spice_number(s):
    """A SPICE value, correctly rounded: "10u" is float("10e-6") = 1e-05, not
    10 * 1e-6 = 9.999999999999999e-06 (pulsim's dsed engine ground on for
    minutes on a gate period one ulp off its own boundaries)."""
    m = re.match(r"([-+]?[0-9.]+)(e[-+]?[0-9]+)?(meg|[fpnumkgt])?", s.lower())
    exp = {"f": -15, "p": -12, "n": -9, "u": -6, "m": -3, "k": 3, "meg": 6, "g": 9, "t": 12}.get(m.group(3), 0)
    return float("%se%d" % (m.group(1), int((m.group(2) or "e0")[1:]) + exp))

def read_netlist(path):
    """Cards as (name, words) after the title, continuation lines joined, comments dropped."""
    lines = open(path).read().splitlines()[1:]
    cards = []
    for line in lines:
        line = line.split(";")[0]
        if not line.strip() or line.lstrip().startswith("*"):
            continue
        if line.startswith("+") and cards:
            cards[-1] += " " + line[1:]
        else:
            cards.append(line)
    out = []
    for c in cards:
        out.append(c.split())
    return out


def tran(cards):
    for w in cards:
        if w[0].lower() == ".tran":
            return spice_number(w[1]), spice_number(w[2])
    raise ValueError("no .tran")


def states(cards):
    """The netlist formulation's x: inductor currents, then capacitor voltages."""
    ls = [("i", w[0], w[1], w[2]) for w in cards if w[0][0].lower() == "l"]
    cs = [("v", w[0], w[1], w[2]) for w in cards if w[0][0].lower() == "c"]
    return ls + cs


def fn_args(card, fn):
    m = re.search(fn + r"\s*\(([^)]*)\)", card, re.I)
    return m.group(1).replace(",", " ").split() if m else None


def near_ideal(src, out, options):
    """The ngspice copy: SW models with RON/ROFF, 1 ns edges for `jump`,
    the steep diode, TMAX = TSTEP and UIC, rshunt, a .control block."""
    cards_text = open(src).read().splitlines()
    lines, saves = [], []
    for line in cards_text:
        w = line.split()
        low = [x.lower() for x in w]
        if low and low[0] in (".probe", ".save", ".print", ".plot", ".end"):
            continue
        if low and low[0] == ".model" and len(w) >= 3 and low[2].startswith("sw"):
            line = line.rstrip().rstrip(")") + " %s)" % SWITCH
        elif low and low[0] == ".model" and len(w) >= 3 and low[2] == "d":
            line = ".model %s %s" % (w[1], DIODE)
        elif low and low[0][0] == "d" and len(w) == 3:
            line = line.rstrip() + " dsteep"
        elif low and low[0] == ".tran":
            line = ".tran %s %s 0 %s uic" % (w[1], w[2], w[1])
        line = re.sub(r"\bjump\b", "1n", line)
        lines.append(line)
    lines.append(".model dsteep %s" % DIODE)
    lines.append(".options rshunt=1e12 %s" % options)
    return "\n".join(lines) + "\n"


# ---- runs ----------------------------------------------------------------------------

def reference(a, name, tstep, tstop):
    n = int(round(tstop / tstep)) + 1
    r = subprocess.run([os.path.join(a.build, "tests", "pwl_ref_dump"), name, repr(tstop), str(n)],
                       capture_output=True, text=True, check=True)
    d = np.loadtxt(r.stdout.splitlines())
    return {"t": d[:, 0], "x": d[:, 1:].T, "info": r.stderr.strip()}


def run_catchup(a, cir, args, tmp):
    out = os.path.join(tmp, "c.h5")
    cmd = [os.path.join(a.build, "apps", "catchup-run"), cir, "-o", out] + [str(x) for x in args]
    t0 = time.perf_counter()
    r = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if r.returncode != 0:
        return {"failed": r.stderr.strip().splitlines()[-1][:300], "run_s": math.nan, "wall_s": wall}
    import h5py
    m = re.search(r", ([0-9.e+-]+) s: (CUP_\w+)", r.stderr)
    steps = re.search(r"(\d+) steps", r.stderr)
    with h5py.File(out, "r") as f:
        t, x = f["t"][:], f["x"][:].T
    return {"run_s": float(m.group(1)), "wall_s": wall, "t": t, "x": x, "status": m.group(2),
            "steps": int(steps.group(1)) if steps else None, "summary": r.stderr.strip()}


def run_ngspice(cir, st, options, tmp):
    vecs = []
    for kind, name, n1, n2 in st:
        vecs += ["i(%s)" % name.lower()] if kind == "i" else ["v(%s)" % n for n in (n1, n2) if n not in ("0", "gnd")]
    vecs = list(dict.fromkeys(vecs))
    data = os.path.join(tmp, "ng.txt")
    net = os.path.join(tmp, "ng.cir")
    text = near_ideal(cir, net, options)
    text += ".save %s\n.control\nrun\nrusage trantime\nwrdata %s %s\n.endc\n.end\n" % (" ".join(vecs), data,
                                                                                      " ".join(vecs))
    open(net, "w").write(text)
    if os.path.exists(data):
        os.remove(data)
    t0 = time.perf_counter()
    r = subprocess.run(["ngspice", "-b", net], capture_output=True, text=True, cwd=tmp)
    wall = time.perf_counter() - t0
    m = re.search(r"Transient analysis time = ([0-9.e+-]+)", r.stdout + r.stderr)
    stop = re.search(r"Timestep too small; time = ([0-9.e+-]+)", r.stdout + r.stderr)
    if not m or not os.path.exists(data):
        why = "stopped at t = %.3g s (timestep too small)" % float(stop.group(1)) if stop else \
            "failed: %s" % (r.stdout + r.stderr).strip().splitlines()[-1][:120]
        return {"failed": why, "run_s": math.nan, "wall_s": wall}
    d = np.loadtxt(data, ndmin=2)
    col = {v: d[:, 2 * k + 1] for k, v in enumerate(vecs)}
    t = d[:, 0]
    x = []
    for kind, name, n1, n2 in st:
        if kind == "i":
            x.append(col["i(%s)" % name.lower()])
        else:
            x.append(col.get("v(%s)" % n1, 0 * t) - col.get("v(%s)" % n2, 0 * t))
    failed = None
    if stop or t[-1] < tstop_of(cir) * (1 - 1e-9):
        failed = "stopped at t = %.3g s (timestep too small)" % (float(stop.group(1)) if stop else t[-1])
    return {"run_s": float(m.group(1)), "wall_s": wall, "t": t, "x": np.array(x), "failed": failed}


def tstop_of(cir):
    return tran(read_netlist(cir))[1]


def pulse_gate(args):
    """A PULSE(0 1 TD jump jump PW PER) as (td, pw, per)."""
    v = [spice_number(x) if x.lower() != "jump" else 0.0 for x in args]
    return v[2], v[5], v[6]


def pulsim_circuit(cards):
    """The netlist as a pulsim CircuitBuilder, with its gate schedule:
    (builder factory, [(switch name, (td, pw, per))], the states' readers)."""
    import pulsim as p
    sources = {}
    for w in cards:
        if w[0][0].lower() == "v":
            sources[(w[1].lower(), w[2].lower())] = " ".join(w[3:])

    def build():
        b = p.CircuitBuilder()
        gates = []
        for w in cards:
            kind, name = w[0][0].lower(), w[0]
            text = " ".join(w[3:])
            if kind == "r":
                b.add_resistor(name, w[1], w[2], spice_number(w[3]))
            elif kind == "l":
                b.add_inductor(name, w[1], w[2], spice_number(w[3]))
            elif kind == "c":
                b.add_capacitor(name, w[1], w[2], spice_number(w[3]))
            elif kind == "k":
                b.add_inductor_coupling(w[1], w[2], spice_number(w[3]))
            elif kind == "d":
                b.add_diode(name, w[1], w[2], G_ON, G_OFF)
            elif kind == "e":
                b.add_vcvs(name, w[3], w[4], w[1], w[2], spice_number(w[5]))
            elif kind == "s":
                b.add_switch(name, w[1], w[2], G_ON, G_OFF)
                gates.append((name, pulse_gate(fn_args(sources[(w[3].lower(), w[4].lower())], "PULSE"))))
            elif kind == "v":
                sin = fn_args(text, "SIN")
                if fn_args(text, "PULSE"):
                    continue                          # a gate: the schedule below
                if sin:
                    v = [spice_number(x) for x in sin] + [0] * 6
                    b.add_sine_voltage_source(name, w[1], w[2], v[0], v[1], v[2], math.radians(v[5]))
                else:
                    b.add_voltage_source(name, w[1], w[2], spice_number(w[-1]))
        return b, gates
    return build


def pulsim_schedule(b, gates):
    import pulsim as p
    ns = b.graph.num_switches
    if not gates:
        m = p.SwitchStateMask(ns)
        return p.NativeMultiMaskPwm(1.0, [1.0], [m])
    per = gates[0][1][2]
    assert all(abs(g[1][2] - per) < 1e-15 for g in gates), "one period for every gate"
    edges = sorted({0.0, per} | {e % per for _, (td, pw, _) in gates for e in (td, td + pw)})
    bounds, masks = [], []
    for lo, hi in zip(edges[:-1], edges[1:]):
        mid = 0.5 * (lo + hi)
        m = p.SwitchStateMask(ns)
        for name, (td, pw, _) in gates:
            if (mid - td) % per < pw:
                m.set(b.switch_index_of(name), True)
        bounds.append(hi / per)
        masks.append(m)
    return p.NativeMultiMaskPwm(per, bounds, masks)


PULSIM_TIMEOUT = 60                      # s; a run beyond it is reported as stopped


def run_pulsim(cir, kw, tmp):
    """One pulsim run in a child process (a variable-step run may grind on
    for millions of steps): its simulate() time and the states."""
    out = os.path.join(tmp, "p.npz")
    if os.path.exists(out):
        os.remove(out)
    cmd = [sys.executable, os.path.abspath(__file__), "--pulsim-one", cir, json.dumps(kw), out]
    try:
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=PULSIM_TIMEOUT)
    except subprocess.TimeoutExpired:
        return {"failed": "not done in %d s" % PULSIM_TIMEOUT, "run_s": math.nan, "wall_s": math.nan}
    if r.returncode != 0 or not os.path.exists(out):
        return {"failed": (r.stderr.strip().splitlines() or ["exit %d" % r.returncode])[-1][:240],
                "run_s": math.nan, "wall_s": math.nan}
    d = np.load(out, allow_pickle=False)
    res = {"run_s": float(d["run_s"]), "wall_s": float(d["run_s"]), "t": d["t"], "x": d["x"], "failed": None,
           "warnings": [str(w) for w in d["warnings"]]}
    if str(d["failed"]):
        res["failed"] = str(d["failed"])
    return res


def pulsim_one(cir, kw, out):
    import pulsim as p
    cards = read_netlist(cir)
    st = states(cards)
    tstop = tran(cards)[1]
    b, gates = pulsim_circuit(cards)()
    fn = pulsim_schedule(b, gates)
    failed = ""
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        t0 = time.perf_counter()
        try:
            r = p.simulate(b, t_end=tstop, switch_fn=fn, **kw)
        except Exception as e:                      # noqa: BLE001 (reported as the run's failure)
            failed = "%s: %s" % (type(e).__name__, str(e)[:200])
        run = time.perf_counter() - t0
    if failed:
        np.savez(out, run_s=run, t=np.zeros(0), x=np.zeros((0, 0)), failed=failed, warnings=np.array([""]))
        return
    t = np.asarray(r.times)
    x = []
    for kind, name, n1, n2 in st:
        if kind == "i":
            x.append(np.asarray(r.i(name)))
        else:
            v = lambda n: 0 * t if n in ("0", "gnd") else np.asarray(r.v(n))
            x.append(v(n1) - v(n2))
    msgs = sorted({str(m.message)[:160] for m in w}) or [""]
    np.savez(out, run_s=run, t=t, x=np.array(x), failed="", warnings=np.array(msgs))


def errors(ref, run):
    """The worst state's max-norm error relative to its peak, away from the reference's jumps."""
    worst, where = 0.0, None
    for k in range(ref["x"].shape[0]):
        r = ref["x"][k]
        peak = max(np.max(np.abs(r)), 1e-300)
        near = np.zeros(len(r), bool)
        for j in np.nonzero(np.abs(np.diff(r)) > 0.05 * peak)[0]:
            near[max(0, j - 1):j + 3] = True
        d = np.abs(np.interp(ref["t"], run["t"], run["x"][k]) - r)[~near]
        e = np.max(d) / peak if np.all(np.isfinite(d)) else math.inf
        if e > worst:
            worst, where = e, (k, float(ref["t"][~near][np.argmax(d)]))
    return worst, where


# ---- one example ---------------------------------------------------------------------

def configs(name, cards, tstep, tstop, period):
    base = int(round(tstop / tstep))
    periods = int(round(tstop / period))
    out = [("catchup", "adaptive tol=%g" % tol, ["--tol", tol]) for tol in TOLS]
    out += [("catchup", "theta n=%d" % int(f * base), ["--scheme", "theta", "--n", int(f * base)])
            for f in THETA_FACTORS]
    # the same tool recording at its own steps instead of the .tran grid
    # (OWN_STEPS), as ngspice and pulsim do: cheaper settings only
    out += [("catchup", "adaptive tol=%g, own steps" % tol, ["--tol", tol] + OWN_STEPS) for tol in OWN_TOLS]
    out += [("catchup", "adaptive tol=%g hmax=Ts/%d, own steps" % (OWN_TOLS[-1], h),
             ["--tol", OWN_TOLS[-1], "--set", "hmax=%r" % (period / h)] + OWN_STEPS) for h in OWN_HMAX]
    out += [("catchup", "adaptive tol=%g, %d samples" % (OWN_TOLS[-1], k * periods + 1),
             ["--tol", OWN_TOLS[-1], "--set", "output.samples=%d" % (k * periods + 1)])
            for k in OWN_SAMPLES_PER_PERIOD if k * periods < base]
    out += [("catchup", "adaptive tol=%g, output tol=%g" % (OWN_TOLS[-1], x),
             ["--tol", OWN_TOLS[-1], "--set", "output.tol=%g" % x]) for x in OUTPUT_TOLS]
    out += [("catchup", "theta n=%d, own steps" % (f * periods), ["--scheme", "theta", "--n", f * periods] + OWN_STEPS)
            for f in OWN_THETA_PER_PERIOD]
    out += [("ngspice", label, opts) for label, opts in NGSPICE_SETTINGS]
    out += [("pulsim", "pwl dt=%g" % (period / k), {"dt": period / k}) for k in (100, 1000)]
    # trbdf2: dt is its step cap, TSTEP, so that it samples every TSTEP;
    # dsed ground on for over a minute on the buck with any cap (1 us, 0.1 us),
    # so it runs with its default (10 us) and is sampled at its own steps.
    out += [("pulsim", "trbdf2 rtol=%g" % rt, {"engine": "trbdf2", "rtol": rt, "atol": rt * 1e-3, "dt": tstep})
            for rt in (1e-6, 1e-9)]
    out += [("pulsim", "dsed rtol=%g" % rt, {"engine": "dsed", "rtol": rt, "atol": rt * 1e-3}) for rt in (1e-6, 1e-9)]
    return out


def switching_period(cards, tstop):
    for w in cards:
        if w[0][0].lower() == "v":
            g = fn_args(" ".join(w[3:]), "PULSE")
            if g:
                return pulse_gate(g)[2]
            s = fn_args(" ".join(w[3:]), "SIN")
            if s:
                return 1 / spice_number(s[2]) / 6
    return tstop / 100


def compare(a, name, tmp, log):
    cir = os.path.join(ROOT, "examples", "circuits", name + ".cir")
    cards = read_netlist(cir)
    tstep, tstop = tran(cards)
    st = states(cards)
    period = switching_period(cards, tstop)
    ref = reference(a, name, tstep, tstop)
    print("%s: reference %s" % (name, ref["info"]), file=sys.stderr)
    runs, failed = [], set()
    for rep in range(a.reps):
        for tool, label, opts in configs(name, cards, tstep, tstop, period):
            if (tool, label) in failed:                # once is enough to know
                continue
            if tool == "catchup":
                r = run_catchup(a, cir, opts, tmp)
            elif tool == "ngspice":
                r = run_ngspice(cir, st, opts, tmp)
            else:
                r = run_pulsim(cir, opts, tmp)
            runs.append((tool, label, r))
            if r.get("failed"):
                failed.add((tool, label))
    rows = []
    for tool, label in dict.fromkeys((t, l) for t, l, _ in runs):
        rs = [r for t, l, r in runs if t == tool and l == label]
        r0 = rs[0]
        err, where = (math.inf, None) if r0.get("failed") else errors(ref, r0)
        row = {"example": name, "tool": tool, "config": label, "failed": r0.get("failed"),
               "err": err, "worst_at": where, "reps": len(rs), "periods": tstop / period,
               "run_s": statistics.median(r["run_s"] for r in rs),
               "wall_s": statistics.median(r["wall_s"] for r in rs),
               "steps": r0.get("steps"), "points": len(r0["t"]) if "t" in r0 else None,
               "warnings": r0.get("warnings")}
        rows.append(row)
        log.write(json.dumps(row) + "\n")
        log.flush()
    plot(name, st, ref, runs, rows)
    return rows


def best_run(runs, rows, tool):
    ok = [r for r in rows if r["tool"] == tool and not r["failed"]]
    if not ok:
        return None
    best = min(ok, key=lambda r: r["err"])
    return best, [r for t, l, r in runs if t == tool and l == best["config"]][0]


def plot(name, st, ref, runs, rows):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(len(st), 2, figsize=(11, 2.3 * len(st) + 0.8), squeeze=False,
                             gridspec_kw={"width_ratios": [2, 1]})
    t = ref["t"]
    scale, unit = (1e3, "ms") if t[-1] >= 1e-3 else (1e6, "us")
    zoom = t >= t[-1] - 0.05 * t[-1]
    others = [(tool, best_run(runs, rows, tool)) for tool in ("catchup", "ngspice", "pulsim")]
    styles = {"catchup": dict(ls="-", lw=0.9, color="C1"), "ngspice": dict(ls="--", lw=0.9, color="k", alpha=0.7),
              "pulsim": dict(ls=":", lw=1.1, color="C2")}
    for k, (kind, el, n1, n2) in enumerate(st):
        label = "i(%s) (A)" % el if kind == "i" else "v(%s,%s) (V)" % (n1, n2) if n2 != "0" else "v(%s) (V)" % n1
        for col, sel in ((0, slice(None)), (1, zoom)):
            ax = axes[k, col]
            ax.plot(t[sel] * scale, ref["x"][k][sel], lw=2.2, color="C0", alpha=0.5, label="exact")
            for tool, br in others:
                if not br:
                    continue
                row, run = br
                m = (run["t"] >= t[sel][0]) & (run["t"] <= t[sel][-1])
                ax.plot(run["t"][m] * scale, run["x"][k][m], label="%s %s" % (tool, row["config"]), **styles[tool])
            ax.grid(alpha=0.3)
            if col == 0:
                ax.set_ylabel(label, fontsize=8)
        if k == 0:
            axes[0, 0].legend(fontsize=6, loc="best")
    for col in (0, 1):
        axes[-1, col].set_xlabel("t (%s)%s" % (unit, "" if col == 0 else ", the last 5 %"))
    failed = [tool for tool, br in others if not br]
    fig.suptitle("%s: the exact solution, catchup, ngspice (near-ideal), pulsim (g_on = 1e3)%s" % (
        name, "; no run of %s" % ", ".join(failed) if failed else ""), fontsize=9)
    fig.tight_layout()
    os.makedirs(os.path.join(ROOT, "docs", "figures"), exist_ok=True)
    fig.savefig(os.path.join(ROOT, "docs", "figures", "converter-%s.png" % name), dpi=100)
    plt.close(fig)


# ---- the report ------------------------------------------------------------------------

def section(rows, a, cost):
    out = ["<!-- BEGIN converters: generated by scripts/bench-converters; do not edit -->",
           "## Converters: catchup against ngspice and pulsim", "",
           "Command: `bash scripts/bench-converters` (%d interleaved rounds, medians; the 1-minute load "
           "average %.1f at the start and %.1f at the end, on %d cores). Each example of "
           "examples/circuits against its exact solution (`build/tests/pwl_ref_dump`, tests/pwl_ref.h: "
           "topologies written by hand, matrix exponentials between events bisected to ulps), on the "
           "netlist's `.tran` grid: the worst state (inductor currents, capacitor voltages), max-norm relative "
           "to its peak, away from the reference's jumps." % (a.reps, a.load[0], a.load[1], os.cpu_count()), "",
           "**One rule for every tool.** Each tool reports at the points it chooses, and its error is measured "
           "on the `.tran` grid by linear interpolation between them (the *points* column counts them): "
           "ngspice at its own time points (`wrdata`, no `.options interp`), pulsim at its own steps, catchup "
           "either on the `.tran` grid from its dense output (`catchup-run`'s default for a netlist: the rows "
           "without *own steps*) or at its own steps (`--set output.every=1`: each step's end, the input's "
           "breakpoints and the events' switch points among them; the rows marked *own steps*) or from its dense "
           "output on a coarser uniform grid of its choosing (`--set output.samples=K`, K - 1 = %s times the "
           "switching periods, below the `.tran` grid's size: the rows marked *K samples*) or from its dense "
           "output where straight lines need points (`--set output.tol=X`: each step's end and the points "
           "inside steps that keep the lines within X of each state's peak, docs/run-output.md; the rows marked "
           "*output tol*; X in half decades, and 8e-5, just under pulsim's error on the precision rectifier, to "
           "time catchup at that error). Each *at equal "
           "error* row pairs a run of ngspice or pulsim with the cheapest catchup run, of either kind, at "
           "least as accurate. No peer setting was dropped or loosened: ngspice and pulsim run exactly as "
           "before catchup got its own-step rows." % ", ".join(map(str, OWN_SAMPLES_PER_PERIOD)), "",
           "catchup: `catchup-run` (adaptive `--tol`, θ = ½ `--scheme theta --n N`; at its own steps the "
           "adaptive scheme, also with its step capped at Ts/%s, `--set hmax=` (Ts/5 splits the full bridge's 24 us "
           "windows in two: its error, 9.9e-2, is just under pulsim's there, to time catchup at that error), and θ "
           "at %s steps per switching "
           "period Ts), its time in the integrator (sampling and HDF5 writes included; the process grows its heap 4 MiB "
           "at a time, apps/heap_pad.h). ngspice %s: a "
           "near-ideal copy (switches `%s`, "
           "`jump` edges 1 ns, diodes `%s`, TMAX = TSTEP, UIC, rshunt = 1e12), its transient analysis time "
           "(1 ms resolution). pulsim %s (PyPI): the same circuit through its CircuitBuilder, switches and "
           "diodes the conductance pair g_on = 1e3 S, g_off = 1e-9 S, gates as a NativeMultiMaskPwm "
           "schedule; its fixed-step engine `pwl` (dt = Ts/100, Ts/1000), `trbdf2` with its step capped at "
           "TSTEP, `dsed` with its default cap (10 us; it ground on for over a minute on the buck with a cap of "
           "1 us or 0.1 us); each run in a child process, stopped at %d s; the time of its `simulate()` "
           "call." % (
               ", Ts/".join(map(str, OWN_HMAX)), ", ".join(map(str, OWN_THETA_PER_PERIOD)), ngspice_version(), SWITCH, DIODE,
               pulsim_version(), PULSIM_TIMEOUT), ""]
    out += summary(rows) + [""]
    for name in EXAMPLES:
        rs = [r for r in rows if r["example"] == name]
        if not rs:
            continue
        out += ["### %s" % name, "", "![%s](docs/figures/converter-%s.png)" % (name, name), "",
                "| tool | setting | error | run | process | steps | points |", "|---|---|---:|---:|---:|---:|---:|"]
        for r in rs:
            if r["failed"]:
                out.append("| %s | %s | %s | | | | |" % (r["tool"], r["config"], r["failed"].replace("|", "/")))
            else:
                out.append("| %s | %s | %.1e | %.3g s | %s | %s | %s |" % (
                    r["tool"], r["config"], r["err"], r["run_s"],
                    "%.3g s" % r["wall_s"] if r["tool"] != "pulsim" else "",
                    r["steps"] if r["steps"] else "", r.get("points") or ""))
        out += equal_error(rs) + [""]
    out += cost_text(cost)
    out.append("<!-- END converters -->")
    return "\n".join(out)


def smallest_speedup(rs):
    """(ratio, other run, catchup run): over the runs of ngspice and pulsim,
    the smallest ratio of its time to the cheapest catchup run at least as
    accurate; None if no pair."""
    cu = [r for r in rs if r["tool"] == "catchup" and not r["failed"]]
    worst = None
    for o in (r for r in rs if r["tool"] != "catchup" and not r["failed"]):
        ok = [c for c in cu if c["err"] <= o["err"]]
        if ok:
            c = min(ok, key=lambda r: r["run_s"])
            ratio = o["run_s"] / max(c["run_s"], 1e-9)
            if worst is None or ratio < worst[0]:
                worst = (ratio, o, c)
    return worst


def summary(rows):
    """One line per example: each tool's most accurate run, and the smallest speed-up at equal error."""
    out = ["| example | catchup, most accurate | ngspice, most accurate | pulsim, most accurate | "
           "smallest speed-up at equal error | >= 10x |", "|---|---|---|---|---|---|"]
    for name in EXAMPLES:
        rs = [r for r in rows if r["example"] == name]
        if not rs:
            continue
        cells = []
        for tool in ("catchup", "ngspice", "pulsim"):
            ok = [r for r in rs if r["tool"] == tool and not r["failed"]]
            if not ok:
                cells.append("no run finished")
                continue
            b = min(ok, key=lambda r: r["err"])
            cells.append("%.1e in %.3g s (%s)" % (b["err"], b["run_s"], b["config"]))
        w = smallest_speedup(rs)
        cells.append("%.1fx (%s %s)" % (w[0], w[1]["tool"], w[1]["config"]) if w else "")
        cells.append(("yes" if w[0] >= 10 else "no") if w else "")
        out.append("| %s | %s |" % (name, " | ".join(cells)))
    return out


def equal_error(rs):
    """For each run of ngspice and pulsim, the cheapest catchup run at
    least as accurate, and the ratio of their times."""
    cu = [r for r in rs if r["tool"] == "catchup" and not r["failed"]]
    lines = []
    for o in (r for r in rs if r["tool"] != "catchup" and not r["failed"]):
        ok = [c for c in cu if c["err"] <= o["err"]]
        if not ok:
            lines.append("| %s %s | %.1e | %.3g s | no catchup run as accurate | | | |" % (
                o["tool"], o["config"], o["err"], o["run_s"]))
            continue
        c = min(ok, key=lambda r: r["run_s"])
        lines.append("| %s %s | %.1e | %.3g s | %s | %.1e | %.3g s | %.1fx |" % (
            o["tool"], o["config"], o["err"], o["run_s"], c["config"], c["err"], c["run_s"],
            o["run_s"] / max(c["run_s"], 1e-9)))
    if not lines:
        return []
    worst = smallest_speedup(rs)
    verdict = [] if worst is None else [
        "", "The smallest speed-up at equal error: %.1fx (%s %s, %.1e, against catchup %s); the target, >= 10x "
        "against the faster of ngspice and pulsim at every error, is %s here." % (
            worst[0], worst[1]["tool"], worst[1]["config"], worst[1]["err"], worst[2]["config"],
            "met" if worst[0] >= 10 else "missed")]
    return verdict + ["", "At equal error: each run of ngspice and pulsim beside the cheapest catchup run at least as "
                      "accurate.", "", "| run | error | time | catchup | error | time | speed-up |",
                      "|---|---:|---:|---|---:|---:|---:|"] + lines


def loop_cost(a, tmp):
    """catchup's time loop on buck-ccm.cir's 100 periods at tol 1e-6, final
    state only (no samples): the median of max(reps, 9) runs, per period."""
    cir = os.path.join(ROOT, "examples", "circuits", "buck-ccm.cir")
    rs = [run_catchup(a, cir, ["--tol", 1e-6, "--set", "output=final"], tmp) for _ in range(max(a.reps, 9))]
    if rs[0].get("failed"):
        return {"failed": rs[0]["failed"]}
    run = statistics.median(r["run_s"] for r in rs)
    return {"run_s": run, "per_period_s": run / 100, "steps": rs[0]["steps"], "summary": rs[0]["summary"]}


def cost_text(c):
    if c.get("failed"):
        return ["### catchup's time loop on the buck", "", "Not measured: %s" % c["failed"], ""]
    return ["### catchup's time loop on the buck", "",
            "`catchup-run examples/circuits/buck-ccm.cir --tol 1e-6 --set output=final` (100 switching periods, "
            "final state only): %.3g ms in the integrator (median), %.3g us per switching period (target: <= 2 us: "
            "%s); %s steps." % (1e3 * c["run_s"], 1e6 * c["per_period_s"],
                                "met" if c["per_period_s"] <= 2e-6 else "missed", c["steps"]), ""]


def pulsim_version():
    try:
        import pulsim
        return getattr(pulsim, "__version__", "?")
    except ImportError:
        return "(not installed)"


def main():
    if len(sys.argv) == 5 and sys.argv[1] == "--pulsim-one":
        return pulsim_one(sys.argv[2], json.loads(sys.argv[3]), sys.argv[4])
    ap = bench_arguments(EXAMPLES)
    ap.add_argument("--no-doc", action="store_true", help="do not rewrite BENCHMARKS.md")
    a = ap.parse_args()
    load0 = os.getloadavg()[0]                 # the machine may be shared: timings depend on it
    rows, cost = compare_all(a, "converters.jsonl", lambda name, tmp, log: compare(a, name, tmp, log),
                             "loop_cost", loop_cost)
    a.load = (load0, os.getloadavg()[0])
    text = section(rows, a, cost)
    print(text)
    if a.no_doc:
        return
    write_section("converters", text)


if __name__ == "__main__":
    main()
