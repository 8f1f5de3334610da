#!/usr/bin/env python3
"""The same crowd run by cromosim (the public Python peer implementing Maury
and Venel's model), for scripts/bench-crowd.

    crowd_cromosim.py RUN.h5 --out RESULT.json [--steps K] [--pixel P] [--method cvxopt|uzawa]
                      [--start J] [--accuracy]

reads a catchup-run crowd file (the scene text, the agents' start and radii,
T and n) and runs cromosim's micro model on the same scene: the room's
walls drawn on cromosim's pixel domain (pixel P, default 0.05 m), the doors
as its destination, cromosim's fast-marching desired velocity at the same
speed, its contacts within the same margin (dmax), its projection
(cvxopt's QP by default) with the same time step, and the same exit rule (an
agent leaves when its centre leaves the room). --steps K stops after K
steps (to time a few steps of a long run). Writes the exit times and the
seconds of every step (the projection's alone too) as JSON; --accuracy
also how far each answer is from the exact projection of the same QP.
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


def answer_error(dt, xyrv, contacts, Vd, U):
    """How far cromosim's velocities U are from the exact projection of the
    same QP (its own construction: min |U - V|^2 / 2 s.t. B U <= Z), solved
    again by cvxopt at 1e-13 (its solver options restored after), in
    positions (y = q + dt U): the largest and the 2-norm distance, the
    excess |x - y|^2 - |x - y*|^2 (what an eps certificate bounds) and the
    largest violation of a row (m)."""
    import cvxopt
    N = xyrv.shape[0]
    II, JJ = contacts[:, 0].astype(int), contacts[:, 1].astype(int)
    pos, neg = np.where(JJ >= 0)[0], np.where(JJ < 0)[0]
    row = np.concatenate([pos, pos, pos, pos, neg, neg])
    col = np.concatenate([2 * II[pos], 2 * II[pos] + 1, 2 * JJ[pos], 2 * JJ[pos] + 1, 2 * II[neg], 2 * II[neg] + 1])
    data = np.concatenate([contacts[pos, 3], contacts[pos, 4], -contacts[pos, 3], -contacts[pos, 4],
                           -contacts[neg, 3], -contacts[neg, 4]])
    B = cvxopt.spmatrix(data, row, col, size=(contacts.shape[0], 2 * N))
    Z = contacts[:, 2] / dt
    V = np.empty(2 * N)
    V[::2], V[1::2] = Vd[:, 0], Vd[:, 1]
    saved = dict(cvxopt.solvers.options)
    cvxopt.solvers.options.update({"show_progress": False, "abstol": 1e-13, "reltol": 1e-13,
                                   "feastol": 1e-13, "maxiters": 200})
    try:
        sol = cvxopt.solvers.qp(cvxopt.spdiag([1.0] * (2 * N)), cvxopt.matrix(-V), B, cvxopt.matrix(Z))
    finally:
        cvxopt.solvers.options.clear()
        cvxopt.solvers.options.update(saved)
    Ustar = np.array(sol["x"]).ravel()
    BU = np.array(B * cvxopt.matrix(U)).ravel()
    return {"status": sol["status"], "max_m": float(dt * np.abs(U - Ustar).max()),
            "norm_m": float(dt * np.linalg.norm(U - Ustar)),
            "excess_m2": float(dt * dt * (np.sum((V - U) ** 2) - np.sum((V - Ustar) ** 2))),
            "violation_m": float(dt * max(0.0, (BU - Z).max()))}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run")
    ap.add_argument("--out", required=True)
    ap.add_argument("--steps", type=int, default=0)
    ap.add_argument("--pixel", type=float, default=0.05)
    ap.add_argument("--method", default="cvxopt")
    ap.add_argument("--start", type=int, default=0, help="start from the J-th stored state (agents out of the room there have left)")
    ap.add_argument("--accuracy", action="store_true",
                    help="also solve each step's QP to 1e-13 and record how far cromosim's answer is from it")
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
    step_s, proj_s, contacts_n, accuracy = [], [], [], []
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
        if a.accuracy and contacts.shape[0] > 0:      # untimed: the QP as it was posed
            accuracy.append(answer_error(dt, xyrv, contacts, Vd, np.asarray(U).ravel()))
    res = {"N": N, "dt": dt, "steps": len(step_s), "pixel": ps, "method": a.method, "margin": margin,
           "exit_time": [None if np.isnan(e) else e for e in exit_time], "step_seconds": step_s,
           "projection_seconds": proj_s, "contacts": contacts_n}
    if a.accuracy:
        res["accuracy"] = accuracy
    with open(out_path, "w") as f:
        json.dump(res, f)
    print(f"cromosim: {N} agents, {len(step_s)} steps, median {np.median(step_s):.4g} s a step "
          f"(projection {np.median(proj_s):.4g} s), {int(np.isfinite(exit_time).sum())} out")
    if accuracy:
        print("cromosim's answers against the exact projection: largest distance "
              f"{max(e['max_m'] for e in accuracy):.3g} m, excess |x - y|^2 - d^2 up to "
              f"{max(e['excess_m2'] for e in accuracy):.3g} m^2, violation up to "
              f"{max(e['violation_m'] for e in accuracy):.3g} m")


if __name__ == "__main__":
    main()
