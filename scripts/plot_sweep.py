#!/usr/bin/env python3
"""Figures from a catchup-sweep results file (docs/sweep-format.md).

    python3 scripts/plot_sweep.py RESULTS.h5 -o PREFIX

writes
  PREFIX-work-precision.png  wall time against error, per variant and scheme
                             (marker: projector), log-log, with each scheme's
                             Pareto front;
  PREFIX-order.png           error against n per variant and scheme (median
                             over schedules and projectors at each n), with the
                             order fitted by least squares on log-log in the
                             legend (the adaptive scheme has no n: it is in
                             the work-precision figure, one point per tol);
  PREFIX-certificates.png    the largest certified eps and eta of each run
                             against n, per tolerance schedule, with the
                             targets eps_n and eta_n as dashed lines.
The theta scheme is labelled with its theta ("theta 0.5"), read from each
variant's scene in /variants. Only rows with done = 1, no error status and
a finite error are drawn.
Needs h5py, numpy and matplotlib (scripts/setup --python makes .venv).
"""
import argparse
import math
import re
import sys

import h5py
import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

MARKERS = {"auto": "o", "pg": "s", "fista": "^", "activeset": "D"}


def text(v):
    return v.decode() if isinstance(v, bytes) else str(v)


def theta_of(scene_text):
    """The scene's theta (the theta scheme's parameter; 0.5 when absent)."""
    m = re.search(r"^theta:\s*([-+0-9.eE]+)\s*$", scene_text, re.M)
    return float(m.group(1)) if m else 0.5


def load(path):
    with h5py.File(path, "r") as f:
        s = f["summary"][:]
        name = f.attrs.get("sweep_name", path)
        thetas = {text(v["name"]): theta_of(text(v["scene"])) for v in f["variants"][:]}
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


def pareto(points):
    """Lower-left front of (time, error) points."""
    front, best = [], math.inf
    for t, e in sorted(points):
        if e < best:
            front.append((t, e))
            best = e
    return front


def work_precision(rows, variants, schemes, title, out):
    nr, nc = grid(len(variants))
    fig, axes = plt.subplots(nr, nc, figsize=(5 * nc, 4 * nr), squeeze=False)
    colors = {s: plt.cm.tab10(i) for i, s in enumerate(schemes)}
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
        ax.set(xscale="log", yscale="log", title=v, xlabel="wall time per task [s]", ylabel="max-norm error")
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize=7)
    for ax in list(axes.flat)[len(variants):]:
        ax.axis("off")
    fig.suptitle(f"{title}: work-precision (lines: Pareto front per scheme)")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def fitted_order(ns, errs):
    x, y = np.log(np.asarray(ns, float)), np.log(np.asarray(errs, float))
    if len(x) < 2 or np.ptp(x) == 0:
        return float("nan")
    slope = np.polyfit(x, y, 1)[0]
    return -slope


def error_order(rows, variants, schemes, title, out):
    nr, nc = grid(len(variants))
    fig, axes = plt.subplots(nr, nc, figsize=(5 * nc, 4 * nr), squeeze=False)
    colors = {s: plt.cm.tab10(i) for i, s in enumerate(schemes)}
    for ax, v in zip(axes.flat, variants):
        for s in schemes:
            if s == "adaptive":
                continue
            pts = [r for r in rows if r["variant"] == v and r["scheme"] == s and r["error"] > 0]
            ns = sorted(set(r["n"] for r in pts))
            med = [float(np.median([r["error"] for r in pts if r["n"] == n])) for n in ns]
            if not ns:
                continue
            p = fitted_order(ns, med)
            ax.loglog(ns, med, "o-", color=colors[s], label=f"{s}: order {p:.2f}")
            lo = [min(r["error"] for r in pts if r["n"] == n) for n in ns]
            hi = [max(r["error"] for r in pts if r["n"] == n) for n in ns]
            ax.fill_between(ns, lo, hi, color=colors[s], alpha=0.12)
        ax.set(title=v, xlabel="n (steps)", ylabel="max-norm error vs reference")
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize=8)
    for ax in list(axes.flat)[len(variants):]:
        ax.axis("off")
    fig.suptitle(f"{title}: error against n (median over schedules and projectors; band: min-max)")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


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
    fig.suptitle(f"{title}: certified bounds and their targets (schedule 0: exact projection, no target line)")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("results")
    ap.add_argument("-o", "--output", required=True, help="prefix of the PNG files")
    a = ap.parse_args()
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
