#!/usr/bin/env python3
"""Figures from a catchup-sweep results file (docs/sweep-format.md).

    python3 scripts/plot_sweep.py RESULTS.h5 -o PREFIX

writes
  PREFIX-work-precision.png  wall time against error, per variant and scheme
                             (marker: projector), log-log, with each scheme's
                             Pareto front;
  PREFIX-order.png           error against n per variant and scheme (median
                             over schedules and projectors at each n), with the
                             order fitted by least squares on log-log over the
                             n where the local slope has settled (the largest
                             n and the smaller ones whose segment slopes stay
                             within SETTLED of each other), that range in the
                             legend (the adaptive scheme has no n: it is in
                             the work-precision figure, one point per tol);
  PREFIX-certificates.png    the largest certified eps and eta of each run
                             against n, per tolerance schedule, with the
                             targets eps_n and eta_n as dashed lines.
The theta scheme is labelled with its theta ("theta 0.5"), read from each
variant's scene in /variants. Only rows with done = 1, no error status and
a finite error are drawn.

A crowd sweep (one with /crowd, docs/sweep-format.md "Crowd sweeps") has no
error: it writes instead
  PREFIX-evacuation.png      the evacuation time against the varied
                             parameter (the one with the most values; one
                             line per value of the others), mean and standard
                             deviation over the seeds (`crowd.agents.seed`)
                             with each seed's point, and, where some agents
                             never left, the agents out the same way;
  PREFIX-certificates.png    each task's largest certified eps and eta with
                             its targets eps_n and eta_n, and the smallest gap.
The parameters are the variants' overrides (/variants) and the grid axes
that differ between tasks; the door overrides (`crowd.doors...`) are shown
as the doors' total width, read from each variant's scene.
Needs h5py, numpy and matplotlib (scripts/setup --python makes .venv).
"""
import argparse
import math
import os
import re
import sys

import h5py
import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

MARKERS = {"auto": "o", "pg": "s", "fista": "^", "activeset": "D"}
SETTLED = 0.1     # local slopes within this of each other count as settled


def text(v):
    return v.decode() if isinstance(v, bytes) else str(v)


def theta_of(scene_text):
    """The scene's theta (the theta scheme's parameter; 0.5 when absent)."""
    m = re.search(r"^theta:\s*([-+0-9.eE]+)\s*$", scene_text, re.M)
    return float(m.group(1)) if m else 0.5


def reference_info(f):
    """What the errors are measured against, in words, for the figures."""
    method = text(f.attrs.get("reference_method", ""))
    cc = [float(c) for c in f["references/summary"]["cross_check"]] if "cross_check" in \
        (f["references/summary"].dtype.names or ()) else []
    cc = [c for c in cc if math.isfinite(c)]
    if "adaptive scheme at tol = 1e-13" in method:
        words = "reference: adaptive scheme at tol 1e-13"
        if cc:
            words += f" (Richardson limit within {max(cc):.2g})"
        return words
    return "reference: Richardson limit" if method else "reference"


def tally(s):
    """One line: how the tasks ended, every kind counted."""
    done = s[s["done"] == 1]
    names = [text(v) for v in done["status_name"]]
    kinds = {k: names.count(k) for k in ordered(names)}
    return f"{len(done)} of {len(s)} tasks done: " + ", ".join(f"{v} {k}" for k, v in kinds.items())


def load(path):
    with h5py.File(path, "r") as f:
        s = f["summary"][:]
        name = f.attrs.get("sweep_name", path)
        thetas = {text(v["name"]): theta_of(text(v["scene"])) for v in f["variants"][:]}
        global REFERENCE, UNITS
        REFERENCE = reference_info(f)
        UNITS = text(f["runs/x"].attrs.get("units", "")) if "runs/x" in f else ""
    print(f"plot_sweep: {path}: {tally(s)}; errors against the {REFERENCE}")
    rows = []
    for r in s:
        rows.append({
            "variant": text(r["variant_name"]), "n": int(r["n"]), "eps": text(r["eps"]),
            "eta": text(r["eta"]), "eps_value": float(r["eps_value"]), "eta_value": float(r["eta_value"]),
            "scheme": text(r["scheme"]), "projector": text(r["projector"]), "done": int(r["done"]),
            "error_code": int(r["error_code"]), "error": float(r["error"]), "wall": float(r["wall_time_s"]),
            "eps_cert": float(r["max_eps_cert"]), "eta_cert": float(r["max_eta_cert"]),
        })
        if rows[-1]["scheme"] == "theta":   # the legend says which theta ran
            rows[-1]["scheme"] = f"theta {thetas.get(rows[-1]['variant'], 0.5):g}"
    return text(name), rows


def ordered(values):
    seen = []
    for v in values:
        if v not in seen:
            seen.append(v)
    return seen


def grid(n):
    cols = min(n, 3)
    return (n + cols - 1) // cols, cols


def finish(fig, suptitle, out, bottom=0.0):
    fig.suptitle(suptitle)
    fig.tight_layout(rect=(0, bottom, 1, 1))
    fig.savefig(out, dpi=110)
    plt.close(fig)


def pareto(points):
    """Lower-left front of (time, error) points."""
    front, best = [], math.inf
    for t, e in sorted(points):
        if e < best:
            front.append((t, e))
            best = e
    return front


REFERENCE, UNITS = "reference", ""


def error_label():
    return "max-norm error" + (f" [{UNITS}]" if UNITS else "")


def one_legend(fig, axes, **kw):
    """A single legend for the figure: every label once, from all panels."""
    seen = {}
    for ax in axes:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            seen.setdefault(lab, h)
    fig.legend(list(seen.values()), list(seen.keys()), **kw)


def panels(variants, schemes):
    """A panel per variant on a grid, and a colour per scheme."""
    nr, nc = grid(len(variants))
    fig, axes = plt.subplots(nr, nc, figsize=(5 * nc, 4 * nr), squeeze=False)
    return fig, axes, {s: plt.cm.tab10(i) for i, s in enumerate(schemes)}


def work_precision(rows, variants, schemes, title, out):
    fig, axes, colors = panels(variants, schemes)
    for ax, v in zip(axes.flat, variants):
        for s in schemes:
            pts = [r for r in rows if r["variant"] == v and r["scheme"] == s and r["wall"] > 0 and r["error"] > 0]
            for p in ordered(r["projector"] for r in pts):
                q = [r for r in pts if r["projector"] == p]
                ax.scatter([r["wall"] for r in q], [r["error"] for r in q], s=14, alpha=0.6, color=colors[s],
                           marker=MARKERS.get(p, "x"), label=f"{s}, {p}")
            front = pareto([(r["wall"], r["error"]) for r in pts])
            if len(front) > 1:
                ax.plot(*zip(*front), color=colors[s], lw=1)
        ax.set(xscale="log", yscale="log", title=v, xlabel="wall time per task [s]", ylabel=error_label())
        ax.grid(True, which="major", alpha=0.3)
    spare = list(axes.flat)[len(variants):]
    for ax in spare:
        ax.axis("off")
    if spare:           # the legend in the empty panel
        one_legend(fig, axes.flat, loc="center", bbox_to_anchor=spare[0].get_position(), fontsize=8)
    else:
        one_legend(fig, axes.flat, loc="lower center", ncol=4, fontsize=8)
    finish(fig, f"{title}: work-precision (lines: Pareto front per scheme; {REFERENCE})", out,
           bottom=0 if spare else 0.12)


def fitted_order(ns, errs):
    """The order fitted where the local slope has settled: from the largest n
    down, the segments whose slopes stay within SETTLED of each other (at least
    the last one); least squares on log-log over their points. Returns the
    order and the first index of the points used."""
    x, y = np.log(np.asarray(ns, float)), np.log(np.asarray(errs, float))
    if len(x) < 2 or np.ptp(x) == 0:
        return float("nan"), 0
    slopes = np.diff(y) / np.diff(x)
    first = len(slopes) - 1
    while first > 0 and np.ptp(slopes[first - 1:]) <= SETTLED:
        first -= 1
    return -np.polyfit(x[first:], y[first:], 1)[0], first


def power10(n):
    e = math.log10(n)
    return f"10^{e:.0f}" if abs(e - round(e)) < 1e-9 else f"{n:g}"


def error_order(rows, variants, schemes, title, out):
    fig, axes, colors = panels(variants, schemes)
    for ax, v in zip(axes.flat, variants):
        for s in schemes:
            if s == "adaptive":
                continue
            pts = [r for r in rows if r["variant"] == v and r["scheme"] == s and r["error"] > 0]
            ns = sorted(set(r["n"] for r in pts))
            med = [float(np.median([r["error"] for r in pts if r["n"] == n])) for n in ns]
            if not ns:
                continue
            p, first = fitted_order(ns, med)
            ax.loglog(ns, med, "o-", color=colors[s],
                      label=f"{s}: order {p:.2f} (n = {power10(ns[first])}..{power10(ns[-1])})")
            lo = [min(r["error"] for r in pts if r["n"] == n) for n in ns]
            hi = [max(r["error"] for r in pts if r["n"] == n) for n in ns]
            ax.fill_between(ns, lo, hi, color=colors[s], alpha=0.12)
        ax.set(title=v, xlabel="n (steps)", ylabel=error_label())
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize=7)
    for ax in list(axes.flat)[len(variants):]:
        ax.axis("off")
    finish(fig, f"{title}: error against n (median over schedules and projectors; band: min-max;\n"
           f"order fitted where the slope has settled; {REFERENCE})", out)


def certificates(rows, title, out):
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    specs = ordered((r["eps"], r["eta"]) for r in rows)
    tiny = 1e-30
    for i, (se, st) in enumerate(specs):
        c = plt.cm.tab10(i)
        q = [r for r in rows if (r["eps"], r["eta"]) == (se, st)]
        ns = sorted(set(r["n"] for r in q))
        for ax, key, target, spec in ((axes[0], "eps_cert", "eps_value", se), (axes[1], "eta_cert", "eta_value", st)):
            worst = [max(max(r[key] for r in q if r["n"] == n), tiny) for n in ns]
            ax.loglog(ns, worst, "o", color=c, label=f"certified, {spec}")
            tv = [max(r[target] for r in q if r["n"] == n) for n in ns]
            if all(t > 0 for t in tv):
                ax.loglog(ns, tv, "--", color=c, label=f"target {spec}")
    axes[0].set(title="largest certified eps over a run (max over tasks)", xlabel="n", ylabel="eps")
    axes[1].set(title="largest certified eta over a run (max over tasks)", xlabel="n", ylabel="eta")
    for ax in axes:
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize=7)
    finish(fig, f"{title}: certified bounds and their targets (schedule 0: exact projection, no target line)", out)


# ---- crowd sweeps ----------------------------------------------------------------------

SEED = "crowd.agents.seed"
LABELS = {"door width": "door width [m]", "crowd.speed": "desired speed [m/s]",
          "crowd.agents.count": "agents", "crowd.agents.radius": "radius [m]"}


def number(v):
    try:
        return float(v)
    except ValueError:
        return v


def door_width(scene):
    """Total width of the scene's doors: the pairs of points listed under `crowd.doors`
    (block or flow YAML, as cup_scene_text writes it), two points a door."""
    m = re.search(r"^( *)doors:(.*?)(?=^\1[\w.]+:|^\S|\Z)", scene, re.M | re.S)
    if not m:
        return float("nan")
    pts = [(float(x), float(y)) for x, y in
           re.findall(r"\[\s*([-+0-9.eE]+)\s*,\s*([-+0-9.eE]+)\s*\]", m.group(2))]
    return sum(math.dist(pts[i], pts[i + 1]) for i in range(0, len(pts) - 1, 2))


def scene_value(scene, key):
    """The scalar at a dotted key of a scene as cup_scene_text writes it (block mappings
    indented by two), or None."""
    at, indent = 0, ""
    for part in key.split("."):
        m = re.compile(f"^{indent}{re.escape(part)}:[ ]*(.*)$", re.M).search(scene, at)
        if not m:
            return None
        at, indent = m.end(), indent + "  "
    return number(m.group(1).strip()) if m.group(1).strip() else None


def variant_params(variants):
    """Each variant's parameters: its overrides, with the keys that another variant overrides
    read from its own scene, and the door overrides replaced by the doors' total width."""
    over = {}
    for v in variants:
        p = dict(kv.strip().split("=", 1) for kv in text(v["overrides"]).split(";") if "=" in kv)
        over[int(v["variant"])] = {k.strip(): number(x.strip()) for k, x in p.items()}
    keys = ordered(k for p in over.values() for k in p if not k.startswith("crowd.doors"))
    doors = any(k.startswith("crowd.doors") for p in over.values() for k in p)
    params = {}
    for v in variants:
        i, scene = int(v["variant"]), text(v["scene"])
        p = {k: over[i][k] if k in over[i] else scene_value(scene, k) for k in keys}
        if doors:
            p["door width"] = round(door_width(scene), 9)
        params[i] = p
    # variants that differ by their scene file alone would otherwise be taken for one
    if len({tuple(sorted(p.items(), key=str)) for p in params.values()}) < len(params):
        for v in variants:
            params[int(v["variant"])]["scene"] = os.path.basename(text(v["scene_file"]))
    return params


def load_crowd(path):
    """One dict a finished task: its /crowd row, its certificates and targets, its seed and
    its parameters (what may differ between tasks besides the seed), in task order."""
    with h5py.File(path, "r") as f:
        name = text(f.attrs.get("sweep_name", path))
        crowd, summ = f["crowd"][:], f["summary"][:]
        params = variant_params(f["variants"][:])
    tasks = []
    for c, r in zip(crowd, summ):
        if not (c["done"] == 1 and r["done"] == 1 and int(r["error_code"]) == 0):
            continue
        p = dict(params[int(r["variant"])])
        for axis in ("n", "eps", "eta", "scheme", "projector"):
            p[axis] = int(r[axis]) if axis == "n" else text(r[axis])
        tasks.append({"params": p, "seed": p.pop(SEED, None), "agents": int(c["agents"]),
                      "out": int(c["agents_out"]), "evac": float(c["evacuation_time"]),
                      "gap": float(c["min_gap"]), "eps_cert": float(r["max_eps_cert"]),
                      "eta_cert": float(r["max_eta_cert"]), "eps_value": float(r["eps_value"]),
                      "eta_value": float(r["eta_value"]), "task": int(c["task_id"])})
    return name, tasks


def varied(tasks):
    """The parameters that take more than one value, the one with the most values first."""
    keys = ordered(k for t in tasks for k in t["params"])
    vals = {k: ordered(t["params"].get(k) for t in tasks) for k in keys}
    keys = [k for k in keys if len(vals[k]) > 1]
    return sorted(keys, key=lambda k: -len(vals[k])), vals


def x_axis(tasks, key, vals):
    """positions and tick labels along the x parameter (numbers where they all are)"""
    if key is None:
        return (lambda t: 0.0), None, ""
    v = vals[key]
    if all(isinstance(x, float) or isinstance(x, int) for x in v):
        return (lambda t: float(t["params"][key])), None, LABELS.get(key, key)
    return (lambda t: float(v.index(t["params"][key]))), [str(x) for x in v], LABELS.get(key, key)


def spread_plot(ax, tasks, xkey, others, vals, value, keep):
    """value(t) against the x parameter, one line per combination of the other parameters:
    each seed's point, the mean over the seeds and its standard deviation as error bars."""
    xof, ticks, xlabel = x_axis(tasks, xkey, vals)
    groups = ordered(tuple(t["params"].get(k) for k in others) for t in tasks)
    for i, g in enumerate(groups):
        c = plt.cm.tab10(i % 10)
        mine = [t for t in tasks if tuple(t["params"].get(k) for k in others) == g and keep(t)]
        xs = sorted(set(xof(t) for t in mine))
        if not xs:
            continue
        ax.plot([xof(t) for t in mine], [value(t) for t in mine], ".", color=c, alpha=0.35, ms=5)
        ys = [[value(t) for t in mine if xof(t) == x] for x in xs]
        label = ", ".join(f"{LABELS.get(k, k).split(' [')[0]} {x}" for k, x in zip(others, g)) or None
        ax.errorbar(xs, [np.mean(y) for y in ys], yerr=[np.std(y) for y in ys], fmt="o-", color=c,
                    capsize=3, label=label)
    if ticks:
        ax.set_xticks(range(len(ticks)), ticks, rotation=30, fontsize=7)
    ax.set_xlabel(xlabel)
    ax.grid(True, alpha=0.3)
    if groups != [()]:
        ax.legend(fontsize=7)


def evacuation(tasks, title, out):
    keys, vals = varied(tasks)
    xkey, others = (keys[0] if keys else None), keys[1:]
    seeds = len(ordered(t["seed"] for t in tasks))
    stuck = [t for t in tasks if t["out"] < t["agents"]]
    fig, axes = plt.subplots(1, 2 if stuck else 1, figsize=(11 if stuck else 6, 4.3), squeeze=False)
    ax = axes[0][0]
    spread_plot(ax, tasks, xkey, others, vals, lambda t: t["evac"], lambda t: math.isfinite(t["evac"]))
    ax.set(ylabel="evacuation time [s]",
           title="evacuation time (tasks where all left)" + (f"; mean, sd over {seeds} seeds" if seeds > 1 else ""))
    if stuck:
        ax = axes[0][1]
        spread_plot(ax, tasks, xkey, others, vals, lambda t: t["out"], lambda t: True)
        n = max(t["agents"] for t in tasks)
        ax.axhline(n, color="k", lw=0.8, ls="--")
        ax.set(ylabel="agents out by the end", ylim=(0, 1.05 * n),
               title=f"agents out ({len(stuck)} of {len(tasks)} tasks kept some inside)")
    finish(fig, f"{title}: evacuation against the parameters", out)


def crowd_certificates(tasks, title, out):
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    ids = [t["task"] for t in tasks]
    for ax, key, target, name in ((axes[0], "eps_cert", "eps_value", "eps"), (axes[1], "eta_cert", "eta_value", "eta")):
        pos = [t[key] for t in tasks if t[key] > 0] + [t[target] for t in tasks if t[target] > 0]
        floor = min(pos) / 100 if pos else 1e-16   # where a bound certified 0 is drawn
        nz = [t for t in tasks if t[key] > 0]
        ax.semilogy([t["task"] for t in nz], [t[key] for t in nz], "o", ms=4, label=f"largest certified {name} of the run")
        zeros = [t["task"] for t in tasks if t[key] == 0]
        if zeros:
            ax.semilogy(zeros, [floor] * len(zeros), "v", ms=4, color="gray",
                        label=f"certified 0 ({len(zeros)} tasks; drawn at {floor:.0e})")
        if any(t[target] > 0 for t in tasks):
            ax.semilogy(ids, [t[target] if t[target] > 0 else np.nan for t in tasks], "_", ms=10, color="k",
                        label=f"target {name}_n")
        ax.set(xlabel="task", ylabel=name, title=f"{name}: certified bound and target")
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize=7)
    gap = min(t["gap"] for t in tasks)
    finish(fig, f"{title}: certified bounds per task; smallest gap between agents over all tasks {gap:.2g} m", out)


def crowd_table(tasks):
    """The evacuation over the seeds, one Markdown row per combination of the
    other parameters: agents out per seed, and the evacuation time's median,
    range, mean and standard deviation over the seeds where all left (the
    table docs/crowd.md quotes; a chaotic result is a distribution)."""
    keys, vals = varied(tasks)
    heads = [LABELS.get(k, k) for k in keys]
    print("| " + " | ".join(heads + ["agents out (per seed)", "evacuation time [s]: median, range; mean ± sd"]) + " |")
    print("|" + "---:|" * len(heads) + "---|---|")
    for g in ordered(tuple(t["params"].get(k) for k in keys) for t in tasks):
        mine = sorted((t for t in tasks if tuple(t["params"].get(k) for k in keys) == g),
                      key=lambda t: (t["seed"] is None, t["seed"]))
        n = mine[0]["agents"]
        outs = [t["out"] for t in mine]
        out = "all" if all(o == n for o in outs) else ", ".join(str(o) for o in outs)
        ev = [t["evac"] for t in mine if math.isfinite(t["evac"])]
        if ev:
            sd = f" ± {np.std(ev):.2f}" if len(ev) > 1 else ""
            time = (f"{np.median(ev):.2f}, {min(ev):.2f}–{max(ev):.2f}; {np.mean(ev):.2f}{sd} "
                    f"({len(ev)} of {len(mine)} seeds)")
        else:
            time = f"– (no seed of {len(mine)} got all out)"
        print("| " + " | ".join([str(x) for x in g] + [out, time]) + " |")


def crowd_main(path, prefix, table=False):
    title, tasks = load_crowd(path)
    if not tasks:
        sys.exit(f"plot_sweep: {path}: no finished crowd task yet")
    if table:
        crowd_table(tasks)
    outs = [f"{prefix}-evacuation.png", f"{prefix}-certificates.png"]
    evacuation(tasks, title, outs[0])
    crowd_certificates(tasks, title, outs[1])
    for o in outs:
        print(o)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("results")
    ap.add_argument("-o", "--output", required=True, help="prefix of the PNG files")
    ap.add_argument("--table", action="store_true",
                    help="crowd sweeps: also print the evacuation over the seeds as a Markdown table")
    a = ap.parse_args()
    with h5py.File(a.results, "r") as f:
        is_crowd = "crowd" in f
    if is_crowd:
        crowd_main(a.results, a.output, a.table)
        return
    title, rows = load(a.results)
    rows = [r for r in rows if r["done"] == 1 and r["error_code"] == 0 and math.isfinite(r["error"])]
    if not rows:
        sys.exit(f"plot_sweep: {a.results}: no finished task with an error yet")
    variants = ordered(r["variant"] for r in rows)
    schemes = ordered(r["scheme"] for r in rows)
    outs = [f"{a.output}-work-precision.png", f"{a.output}-order.png", f"{a.output}-certificates.png"]
    work_precision(rows, variants, schemes, title, outs[0])
    error_order(rows, variants, schemes, title, outs[1])
    certificates(rows, title, outs[2])
    for o in outs:
        print(o)


if __name__ == "__main__":
    main()
