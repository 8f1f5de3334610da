#!/usr/bin/env python3
"""The same crowd run by cromosim (the public Python peer implementing Maury
and Venel's model), for scripts/bench-crowd.

    crowd_cromosim.py RUN.h5 --out RESULT.json [--steps K] [--pixel P] [--method cvxopt|uzawa]

reads a catchup-run crowd file (the scene text, the agents' start and radii,
T and n) and runs cromosim's micro model on the same scene: the room's
walls drawn on cromosim's pixel domain (pixel P, default 0.05 m), the doors
as its destination, cromosim's fast-marching desired velocity at the same
speed, its contacts within the same margin (dmax), its projection
(cvxopt's QP by default) with the same time step, and the same exit rule (an
agent leaves when its centre leaves the room). --steps K stops after K
steps (to time a few steps of a long run). Writes the exit times and the
seconds of every step (the projection's alone too) as JSON.
"""
import argparse
import json
import os
import time

import h5py
import numpy as np
import yaml
from matplotlib.lines import Line2D
from matplotlib.path import Path

from cromosim.domain import Destination, Domain
from cromosim.micro import compute_contacts, projection


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run")
    ap.add_argument("--out", required=True)
    ap.add_argument("--steps", type=int, default=0)
    ap.add_argument("--pixel", type=float, default=0.05)
    ap.add_argument("--method", default="cvxopt")
    ap.add_argument("--start", type=int, default=0, help="start from the J-th stored state (agents out of the room there have left)")
    a = ap.parse_args()
    with h5py.File(a.run, "r") as f:
        scene = yaml.safe_load(f.attrs["scene"])
        T, n = float(f.attrs["T"]), int(f.attrs["n"])
        q0 = f["x"][a.start].reshape(-1, 2)
        t_start = float(f["t"][a.start])
        radius = f["crowd/radius"][:]
        walls = f["crowd/walls"][:]
    crowd = scene["crowd"]
    dt, speed = T / n, float(crowd.get("speed", 1))
    room = np.array(crowd["room"], dtype=float)
    margin = float(crowd.get("margin", 0)) or max(4 * speed * dt, radius.mean())
    ps = a.pixel
    lo, hi = room.min(axis=0) - 1, room.max(axis=0) + 1
    width, height = int(np.ceil((hi[0] - lo[0]) / ps)), int(np.ceil((hi[1] - lo[1]) / ps))
    out_path = os.path.abspath(a.out)
    os.chdir(os.path.dirname(out_path))      # cromosim saves its domain's image in the working directory
    dom = Domain(name="catchup_scene", pixel_size=ps, xmin=lo[0], ymin=lo[1], width=width, height=height)
    black, red = [0, 0, 0], [255, 0, 0]
    # the domain draws in pixel units from its own origin: shift by (xmin, ymin)
    for w in walls:
        dom.add_shape(Line2D([w[0] - lo[0], w[2] - lo[0]], [w[1] - lo[1], w[3] - lo[1]], linewidth=2),
                      outline_color=black, fill_color=black)
    for d in crowd["doors"]:
        (x0, y0), (x1, y1) = d
        dom.add_shape(Line2D([x0 - lo[0], x1 - lo[0]], [y0 - lo[1], y1 - lo[1]], linewidth=2),
                      outline_color=red, fill_color=red)
    dom.build_domain()
    dom.add_destination(Destination(name="door", colors=[red], excluded_colors=[black]))
    inside_room = Path(room)
    N = len(radius)
    xyrv = np.column_stack([q0, radius, np.full(N, speed)])
    alive = np.arange(N)
    exit_time = np.full(N, np.nan)
    step_s, proj_s, contacts_n = [], [], []
    steps = a.steps if a.steps > 0 else n
    for k in range(steps):
        t = t_start + k * dt
        out = ~inside_room.contains_points(xyrv[:, :2])
        exit_time[alive[out]] = t
        xyrv, alive = xyrv[~out], alive[~out]
        if len(alive) == 0:
            break
        t0 = time.perf_counter()
        contacts = compute_contacts(dom, xyrv, margin)
        _, _, Vd = dom.people_desired_velocity(xyrv, ["door"] * len(alive))
        t1 = time.perf_counter()
        _, _, U, _, _ = projection(dt, xyrv, contacts, Vd, method=a.method)
        t2 = time.perf_counter()
        xyrv[:, :2] += dt * U
        step_s.append(time.perf_counter() - t0)
        proj_s.append(t2 - t1)
        contacts_n.append(int(contacts.shape[0]))
    res = {"N": N, "dt": dt, "steps": len(step_s), "pixel": ps, "method": a.method, "margin": margin,
           "exit_time": [None if np.isnan(e) else e for e in exit_time], "step_seconds": step_s,
           "projection_seconds": proj_s, "contacts": contacts_n}
    with open(out_path, "w") as f:
        json.dump(res, f)
    print(f"cromosim: {N} agents, {len(step_s)} steps, median {np.median(step_s):.4g} s a step "
          f"(projection {np.median(proj_s):.4g} s), {int(np.isfinite(exit_time).sum())} out")


if __name__ == "__main__":
    main()
