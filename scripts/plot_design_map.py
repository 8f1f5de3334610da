#!/usr/bin/env python3
"""Design maps of a steady-state sweep (docs/sweep-format.md, "Steady-state sweeps").

    python3 scripts/plot_design_map.py RESULTS.h5 --x netlist.D --y netlist.L -o map.png
                                      [--signal v(out)] [--current i(L1)]

Two panels over two of the variants' overridden keys (their values read from
/variants' overrides, SPICE suffixes understood): the signal's peak-to-peak
ripple over the steady state's period and the efficiency. Variants whose
largest Floquet multiplier modulus is >= 1 (no attracting orbit) are marked
with a red x, those with no steady state in grey; with --current, the line
where that current's minimum over the period reaches 0 (the boundary between
continuous and discontinuous conduction) is drawn. Scattered points (a Latin
hypercube) are drawn as dots, a grid as cells."""
import argparse
import os
import re
import sys

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

SUFFIX = {"meg": 1e6, "t": 1e12, "g": 1e9, "k": 1e3, "m": 1e-3, "u": 1e-6, "n": 1e-9, "p": 1e-12, "f": 1e-15}


def spice_value(text):
    m = re.fullmatch(r"\s*([-+]?[0-9.]+(?:[eE][-+]?[0-9]+)?)\s*([A-Za-z]*)\s*", text)
    if not m:
        raise ValueError(f"not a number: {text!r}")
    mul = SUFFIX.get(m.group(2).lower(), None) if m.group(2) else 1.0
    if mul is None:
        raise ValueError(f"unknown suffix in {text!r}")
    return float(m.group(1)) * mul


def overrides(text):
    out = {}
    for part in text.split("; "):
        if "=" in part:
            k, v = part.split("=", 1)
            out[k] = v                      # the last one wins, as the scene loader applies them
    return out


def load(path, xkey, ykey):
    with h5py.File(path, "r") as f:
        if "steady_state" not in f:
            sys.exit(f"{path}: no /steady_state: not a steady-state sweep")
        ss = f["steady_state"][:]
        var = f["variants"][:]
        summ = f["summary"][:]
    ov = [overrides(v["overrides"].decode() if isinstance(v["overrides"], bytes) else v["overrides"]) for v in var]
    for key in (xkey, ykey):
        if not all(key in o for o in ov):
            sys.exit(f"{path}: not every variant sets {key}")
    x = np.array([spice_value(ov[v][xkey]) for v in ss["variant"]])
    y = np.array([spice_value(ov[v][ykey]) for v in ss["variant"]])
    return ss, summ, x, y


def panel(ax, x, y, z, title, cmap, log_color, grid):
    ok = np.isfinite(z)
    if grid:
        xs, ys = np.unique(x), np.unique(y)
        Z = np.full((len(ys), len(xs)), np.nan)
        Z[np.searchsorted(ys, y), np.searchsorted(xs, x)] = z
        norm = matplotlib.colors.LogNorm() if log_color else None
        im = ax.pcolormesh(xs, ys, np.ma.masked_invalid(Z), shading="nearest", cmap=cmap, norm=norm)
    else:
        norm = matplotlib.colors.LogNorm() if log_color else None
        im = ax.scatter(x[ok], y[ok], c=z[ok], s=18, cmap=cmap, norm=norm)
    plt.colorbar(im, ax=ax)
    ax.set_title(title)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("results")
    ap.add_argument("--x", required=True, help="the override key on the x axis, e.g. netlist.D")
    ap.add_argument("--y", required=True, help="the override key on the y axis, e.g. netlist.L")
    ap.add_argument("--signal", default="v(out)", help="the measured signal whose ripple is drawn")
    ap.add_argument("--current", default=None, help="a measured current: draw where its minimum reaches 0")
    ap.add_argument("-o", "--output", required=True)
    a = ap.parse_args()
    ss, summ, x, y = load(a.results, a.x, a.y)
    col = f"{a.signal}_peak_to_peak"
    if col not in ss.dtype.names:
        sys.exit(f"{a.results}: {a.signal} is not measured (columns: {', '.join(ss.dtype.names)})")
    solved = (ss["solved"] == 1) & (ss["done"] == 1)
    ripple = np.where(solved, ss[col], np.nan)
    eff = np.where(solved, ss["efficiency"], np.nan)
    grid = len(np.unique(x)) * len(np.unique(y)) == len(x)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.4), constrained_layout=True)
    panel(axes[0], x, y, ripple, f"{a.signal} peak-to-peak ripple", "viridis", True, grid)
    panel(axes[1], x, y, eff, "efficiency", "magma", False, grid)
    unstable = solved & (ss["max_multiplier"] >= 1)
    failed = ~solved
    for ax in axes:
        ax.set_xlabel(a.x)
        ax.set_ylabel(a.y)
        if y.max() / max(y.min(), 1e-300) > 20 and y.min() > 0:
            ax.set_yscale("log")
        if x.max() / max(x.min(), 1e-300) > 20 and x.min() > 0:
            ax.set_xscale("log")
        ax.scatter(x[unstable], y[unstable], marker="x", c="red", s=40,
                   label=f"max |Floquet multiplier| >= 1 ({unstable.sum()})")
        ax.scatter(x[failed], y[failed], marker="s", c="0.6", s=30, label=f"no steady state ({failed.sum()})")
        if a.current and grid:
            imin = np.where(solved, ss[f"{a.current}_min"], np.nan)
            xs, ys = np.unique(x), np.unique(y)
            Z = np.full((len(ys), len(xs)), np.nan)
            Z[np.searchsorted(ys, y), np.searchsorted(xs, x)] = imin
            scale = np.nanmax(np.abs(Z)) or 1
            ax.contour(xs, ys, Z, levels=[1e-9 * scale], colors="white", linewidths=1.5)
            ax.plot([], [], c="white", label=f"{a.current} reaches 0 (CCM above, DCM below)")
        ax.legend(loc="lower right", fontsize=7, facecolor="0.85")
    mu = ss["max_multiplier"][solved]
    fig.suptitle(f"{os.path.basename(a.results)}: {solved.sum()} of {len(ss)} steady states, largest |multiplier| "
                 f"{np.nanmax(mu) if mu.size else float('nan'):.4g}, Newton steps "
                 f"{ss['newton_iterations'][solved].min() if mu.size else 0}-"
                 f"{ss['newton_iterations'][solved].max() if mu.size else 0}", fontsize=9)
    fig.savefig(a.output, dpi=110)
    print(f"{a.output}: {len(ss)} variants, {unstable.sum()} unstable, {failed.sum()} without a steady state")


if __name__ == "__main__":
    main()
