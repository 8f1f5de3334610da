#!/usr/bin/env python3
"""Pictures of a crowd run (catchup-run on a crowd: scene, docs/crowd.md).

    plot_crowd.py RUN.h5 -o PREFIX [--frames K] [--gif] [--fps F] [--window S]

writes PREFIX-snapshot-NNN.png (K snapshots evenly spread over the run,
default 4; agents inside drawn as disks, coloured by their exit time),
PREFIX-left.png (agents left in the room against time), PREFIX-flow.png (the
flow through the doors, agents per second over a moving window of S
seconds, default 5), PREFIX-certificates.png (per step: certified eta and
the smallest gap, which stays above -sqrt(2) eta), and with --gif
PREFIX.gif, an animation of every stored state (matplotlib's Pillow
writer: no ffmpeg needed).
"""
import argparse
import sys

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import LineCollection, PatchCollection  # noqa: E402
from matplotlib.patches import Circle  # noqa: E402


def load(path):
    with h5py.File(path, "r") as f:
        if "crowd" not in f:
            sys.exit(f"plot_crowd: {path}: no /crowd group (not a crowd scene's run)")
        run = {
            "t": f["t"][:],
            "x": f["x"][:],
            "radius": f["crowd/radius"][:],
            "exit": f["crowd/exit_time"][:],
            "walls": f["crowd/walls"][:],
            "steps": {k: f["steps"][k][:] for k in f["steps"]},
            "name": f.attrs.get("scene_name", path),
        }
    return run


def draw_room(ax, run):
    w = run["walls"]
    ax.add_collection(LineCollection(w.reshape(-1, 2, 2), colors="k", linewidths=2))
    lo, hi = w.reshape(-1, 2).min(axis=0), w.reshape(-1, 2).max(axis=0)
    pad = 0.04 * (hi - lo).max()
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal")


def agents(ax, run, j, cmap, norm):
    t, q = run["t"][j], run["x"][j].reshape(-1, 2)
    inside = ~(run["exit"] <= t)
    colours = cmap(norm(np.where(np.isnan(run["exit"]), norm.vmax, run["exit"])))
    patches = [Circle(q[i], run["radius"][i]) for i in np.flatnonzero(inside)]
    pc = PatchCollection(patches, facecolors=colours[inside], edgecolors="k", linewidths=0.2)
    ax.add_collection(pc)
    ax.set_title(f"{run['name']}: t = {t:.1f} s, {inside.sum()} agents inside")
    return pc


def snapshots(run, prefix, frames):
    cmap, exit_t = plt.get_cmap("viridis"), run["exit"]
    norm = plt.Normalize(0, np.nanmax(exit_t) if np.isfinite(exit_t).any() else run["t"][-1])
    files = []
    for k, j in enumerate(np.linspace(0, len(run["t"]) - 1, frames).round().astype(int)):
        fig, ax = plt.subplots(figsize=(8, 6))
        draw_room(ax, run)
        agents(ax, run, j, cmap, norm)
        fig.colorbar(plt.cm.ScalarMappable(norm=norm, cmap=cmap), ax=ax, label="exit time (s)")
        name = f"{prefix}-snapshot-{k:03d}.png"
        fig.savefig(name, dpi=120, bbox_inches="tight")
        plt.close(fig)
        files.append(name)
    return files


def animation(run, prefix, fps):
    from matplotlib.animation import FuncAnimation, PillowWriter

    cmap, exit_t = plt.get_cmap("viridis"), run["exit"]
    norm = plt.Normalize(0, np.nanmax(exit_t) if np.isfinite(exit_t).any() else run["t"][-1])
    fig, ax = plt.subplots(figsize=(6, 4.5))
    draw_room(ax, run)
    state = {"pc": agents(ax, run, 0, cmap, norm)}

    def frame(j):
        state["pc"].remove()
        state["pc"] = agents(ax, run, j, cmap, norm)
        return (state["pc"],)

    anim = FuncAnimation(fig, frame, frames=len(run["t"]), blit=False)
    name = f"{prefix}.gif"
    anim.save(name, writer=PillowWriter(fps=fps), dpi=80)
    plt.close(fig)
    return name


def left_and_flow(run, prefix, window):
    s = run["steps"]
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.plot(s["t"], s["inside"], "k-")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("agents in the room")
    ax.set_title(f"{run['name']}: agents left")
    fig.savefig(f"{prefix}-left.png", dpi=120, bbox_inches="tight")
    plt.close(fig)
    exits = np.sort(run["exit"][np.isfinite(run["exit"])])
    t = s["t"]
    flow = (np.searchsorted(exits, t, side="right") - np.searchsorted(exits, t - window, side="right")) / window
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.plot(t, flow, "b-")
    ax.set_xlabel("t [s]")
    ax.set_ylabel(f"agents per second [1/s] ({window:g} s window)")
    ax.set_title(f"{run['name']}: flow through the door")
    fig.savefig(f"{prefix}-flow.png", dpi=120, bbox_inches="tight")
    plt.close(fig)
    certificates(run, t, s, prefix)
    return [f"{prefix}-left.png", f"{prefix}-flow.png", f"{prefix}-certificates.png"]


def certificates(run, t, s, prefix):
    """Per step, the smallest gap of the state where it is > 0, the overlap
    (-gap) only on the states that overlap, and the certified eta where it is
    > 0: nothing is clamped to a floor, so a run without overlaps shows none
    (and says so with its smallest gap), and eta certified 0 is counted."""
    fig, ax = plt.subplots(figsize=(6, 4))
    k = np.arange(1, len(t))
    eta, gap = s["eta_cert"][k], s["gap"]
    pos = eta > 0
    apart = np.flatnonzero(gap > 0)
    if apart.size:
        ax.semilogy(t[apart], gap[apart], "k-", lw=0.8, label="smallest gap of the state")
    if pos.any():
        ax.semilogy(t[k][pos], eta[pos], "r-", lw=1, label="certified \u03b7 of the step")
        ax.semilogy(t[k][pos], np.sqrt(2) * eta[pos], "r:", lw=1, label="\u221a2 \u03b7: the overlap it allows")
    zero = int((eta == 0).sum())
    if zero:
        ax.plot([], [], " ", label=f"\u03b7 certified 0 (exact) on {zero} of {len(k)} steps")
    over = np.flatnonzero(gap < 0)
    if over.size:
        ax.semilogy(t[over], -gap[over], "rx", ms=4,
                    label=f"overlap (\u2212gap) on {over.size} states, largest {-gap[over].min():.2g} m")
    finite = gap[np.isfinite(gap)]
    smallest = f"smallest gap {finite.min():+.2g} m" if finite.size else "no gap recorded"
    ax.set_title(f"{run['name']}: gaps, overlaps and certified \u03b7\n"
                 f"{'no state overlaps; ' if not over.size else ''}{smallest}", fontsize=10)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("[m]")
    if pos.any() or over.size:
        ax.set_yscale("log")
    ax.legend(fontsize=8)
    fig.savefig(f"{prefix}-certificates.png", dpi=120, bbox_inches="tight")
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run")
    ap.add_argument("-o", "--output", required=True, help="prefix of the files written")
    ap.add_argument("--frames", type=int, default=4)
    ap.add_argument("--gif", action="store_true")
    ap.add_argument("--fps", type=float, default=10)
    ap.add_argument("--window", type=float, default=5.0)
    a = ap.parse_args()
    run = load(a.run)
    files = snapshots(run, a.output, max(1, a.frames)) + left_and_flow(run, a.output, a.window)
    if a.gif:
        files.append(animation(run, a.output, a.fps))
    print("\n".join(files))


if __name__ == "__main__":
    main()
