#!/usr/bin/python3
"""Siconos side of the catchup benchmark: the paper's 3-state diode circuit (LCS).

    x' = A x + B z + E u(t),   0 <= z  _|_  C x + G u(t) >= 0,   x(0) = 0,  T = 1.

Case 1: G = 0,      u(t) = 16 sin(6 pi t) - 0.5
Case 2: G = (0,1)^T, u(t) = sign(sin(4 pi t)), sign(0) = 0

Schemes (--scheme):
  siconos           Siconos kernel: FirstOrderLinearTIDS(A, b) + FirstOrderLinearTIR(C, B)
                    + ComplementarityConditionNSL(2) + EulerMoreauOSI(theta) + LCP(lemke|enum)
                    + TimeStepping.  Per step k -> k+1 the DS's b is set (in place) to
                    (1/h) E int_{t_k}^{t_{k+1}} u, and for case 2 the relation's e to
                    G u(t_{k+1}).  EulerMoreauOSI adds h*b to the free state whatever theta
                    is (b is not theta-split for time-invariant DS), and treats the
                    reaction r = B lambda fully implicitly, so theta = 0 gives
                        x_{k+1} = x_k + h A x_k + E int u + h B lambda,
                        0 <= lambda _|_ C x_{k+1} + e >= 0,
                    which with P B = C^T is the KKT system of the P-projection below.
  catchup-explicit  Independent numpy reference of the explicit catching-up scheme:
                    x_free = x_k + h A x_k + E int u;
                    x_{k+1} = argmin_{C y + G u(t_{k+1}) >= 0} (y - x_free)^T P (y - x_free),
                    solved exactly by enumerating the 4 active sets.

Only the time loop is timed (time.perf_counter).  The same model driven from C++, with
no Python in the loop, is siconos_circuit.cpp; this driver cross-checks it.  The input averages and e values are
tabulated with numpy before the loop (closed forms; see input_tables).  The state is
stored only at times common to the grid k/n and the reference grid j/1000.

Usage: /usr/bin/python3 siconos_circuit.py --case {1,2} --n N [--theta TH]
       [--solver {lemke,enum}] [--scheme {siconos,catchup-explicit}] [--reps R]
       [--ref PATH] [--out-traj FILE]
Prints ONE JSON line on stdout; diagnostics go to stderr.
"""
import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import time

# Siconos calls BLAS on 2x2 and 3x3 blocks; a threaded OpenBLAS wakes its pool on
# every call and doubles the cost of a step on a 2-core machine. OpenBLAS reads
# this when it loads (numpy's import loads it), hence before the import; a value
# the caller chose is kept. The C++ driver (siconos_circuit.cpp) does the same.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

R1, R2, R3, L2, L3, C4 = 1.0, 2.0, 1.0, 1.0, 2.0, 1.0
A = np.array([[0.0, 1.0, 0.0],
              [-1.0 / (L3 * C4), -(R1 + R3) / L3, R1 / L3],
              [0.0, R1 / L2, -(R1 + R2) / L2]])
B = np.array([[0.0, 0.0], [1.0 / L3, 1.0 / L3], [-1.0 / L2, 0.0]])
C = np.array([[0.0, 1.0, -1.0], [0.0, 1.0, 0.0]])
E = np.array([0.0, 1.0 / L3, 1.0 / L2])
P = np.diag([1.0, L3, L2])
assert np.allclose(P @ B, C.T)
G = {1: np.zeros(2), 2: np.array([0.0, 1.0])}
# the reference limits of the paper's cases ship in the repository (tests/data/README.md)
REF_DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "data")


def input_tables(case, n):
    """Return (ubar, ue): ubar[k] = (1/h) int_{t_k}^{t_{k+1}} u, ue[k] = u(t_{k+1}), k < n."""
    h = 1.0 / n
    k = np.arange(n + 1, dtype=np.float64)
    t = k * h                                       # t_k = k*h, never accumulated
    if case == 1:
        a, b = 6 * np.pi * t[:-1], 6 * np.pi * t[1:]
        # 16 (cos a - cos b)/(6 pi) written as a product to avoid cancellation for small h
        integ = 16.0 * 2.0 * np.sin(0.5 * (a + b)) * np.sin(0.5 * (b - a)) / (6 * np.pi) - 0.5 * h
        ue = 16.0 * np.sin(6 * np.pi * t[1:]) - 0.5
    else:
        # U(t) = int_0^t sign(sin(4 pi s)) ds is the triangle wave: tau = t mod 1/2,
        # U = tau on [0,1/4], 1/2 - tau on [1/4,1/2]; U is continuous so U(t_{k+1}) - U(t_k)
        # is exact also for steps straddling a jump at a multiple of 1/4.
        tau = np.mod(t, 0.5)
        U = np.where(tau <= 0.25, tau, 0.5 - tau)
        integ = np.diff(U)
        # u(t_{k+1}) with exact integer arithmetic: 4 t = 4(k+1)/n; jumps where n | 4(k+1)
        m = 4 * np.arange(1, n + 1, dtype=np.int64)
        q, r = np.divmod(m, n)
        ue = np.where(r == 0, 0.0, np.where(q % 2 == 0, 1.0, -1.0))
    return integ / h, ue


def sample_plan(n):
    """Common times of grids k/n and j/1000: store every s_sim steps, ref row every s_ref."""
    g = math.gcd(n, 1000)
    return n // g, 1000 // g


def build_siconos(case, n, theta, solver):
    import siconos.kernel as sk
    import siconos.numerics as sn
    ds = sk.FirstOrderLinearTIDS(np.zeros(3), A, np.zeros(3))
    rel = sk.FirstOrderLinearTIR(C, B)
    if case == 2:
        rel.setePtr(np.zeros(2))                    # e is None until set once
    nslaw = sk.ComplementarityConditionNSL(2)
    inter = sk.Interaction(nslaw, rel)
    nsds = sk.NonSmoothDynamicalSystem(0.0, 1.0)
    nsds.insertDynamicalSystem(ds)
    nsds.link(inter, ds)
    osi = sk.EulerMoreauOSI(theta)
    td = sk.TimeDiscretisation(0.0, 1.0 / n)
    sid = {"lemke": sn.SICONOS_LCP_LEMKE, "enum": sn.SICONOS_LCP_ENUM}[solver]
    osnspb = sk.LCP(sid)
    sim = sk.TimeStepping(nsds, td, osi, osnspb)
    return sim, ds, rel


def run_siconos(case, n, theta, solver):
    sim, ds, rel = build_siconos(case, n, theta, solver)
    ubar, ue = input_tables(case, n)
    bview = ds.b()                                  # numpy view on the DS's b (in place)
    eview = rel.e() if case == 2 else None          # numpy view on the relation's e
    xview = ds.x()
    s_sim, _ = sample_plan(n)
    nstore = n // s_sim + 1
    X = np.empty((nstore, 3))
    X[0] = xview
    j = 1
    t0 = time.perf_counter()
    for k in range(n):
        bview[:] = E * ubar[k]
        if eview is not None:
            eview[1] = ue[k]
        sim.computeOneStep()
        sim.nextStep()
        if (k + 1) % s_sim == 0:
            X[j] = xview
            j += 1
    t1 = time.perf_counter()
    return t1 - t0, X


def project(xf, g):
    """argmin_{C y + g >= 0} (y - xf)^T P (y - xf), exact, by enumerating active sets."""
    best, bestval = None, np.inf
    Pinv = np.diag(1.0 / np.diag(P))
    for I in ([], [0], [1], [0, 1]):
        if I:
            CI = C[I]
            mu = np.linalg.solve(CI @ Pinv @ CI.T, -(CI @ xf + g[I]))
            if np.any(mu < -1e-14):
                continue
            y = xf + Pinv @ CI.T @ mu
        else:
            y = xf
        if np.all(C @ y + g >= -1e-12 * (1 + np.abs(g).max())):
            val = (y - xf) @ P @ (y - xf)
            if val < bestval:
                best, bestval = y, val
    assert best is not None
    return best


def run_explicit(case, n):
    h = 1.0 / n
    ubar, ue = input_tables(case, n)
    Gc = G[case]
    s_sim, _ = sample_plan(n)
    X = np.empty((n // s_sim + 1, 3))
    x = np.zeros(3)
    X[0] = x
    j = 1
    Ah = np.eye(3) + h * A
    t0 = time.perf_counter()
    for k in range(n):
        x = project(Ah @ x + h * ubar[k] * E, Gc * ue[k])
        if (k + 1) % s_sim == 0:
            X[j] = x
            j += 1
    t1 = time.perf_counter()
    return t1 - t0, X


def siconos_version():
    try:
        out = subprocess.run(["dpkg-query", "-W", "-f=${Version}", "python3-siconos"],
                             capture_output=True, text=True, timeout=10).stdout.strip()
    except Exception:
        out = ""
    try:
        import siconos
        mod = getattr(siconos, "version", "?")
    except Exception:
        mod = "?"
    return {"debian": out or "?", "module": mod}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", type=int, choices=(1, 2), required=True)
    ap.add_argument("--n", type=int, required=True)
    ap.add_argument("--theta", type=float, default=0.5)
    ap.add_argument("--solver", choices=("lemke", "enum"), default="lemke")
    ap.add_argument("--scheme", choices=("siconos", "catchup-explicit"), default="siconos")
    ap.add_argument("--reps", type=int, default=1)
    ap.add_argument("--ref", default=None)
    ap.add_argument("--out-traj", default=None)
    a = ap.parse_args()

    ref_path = a.ref or os.path.join(REF_DIR, f"ref_case{a.case}_limit_richardson.csv")
    ref = np.loadtxt(ref_path, delimiter=",", skiprows=1)

    times, X = [], None
    for _ in range(a.reps):
        if a.scheme == "siconos":
            dt, X = run_siconos(a.case, a.n, a.theta, a.solver)
        else:
            dt, X = run_explicit(a.case, a.n)
        times.append(dt)

    s_sim, s_ref = sample_plan(a.n)
    tt = np.arange(X.shape[0]) * s_sim / a.n
    R = ref[::s_ref]
    assert R.shape[0] == X.shape[0] and np.allclose(R[:, 0], tt, atol=1e-12), "grid mismatch"
    err = float(np.max(np.abs(X - R[:, 1:4])))
    if a.out_traj:
        np.savetxt(a.out_traj, np.column_stack([tt, X]), delimiter=",",
                   header="t,x1,x2,x3", comments="", fmt="%.17g")
    med = statistics.median(times)
    res = {"case": a.case, "n": a.n, "scheme": a.scheme, "driver": "python",
           "theta": a.theta if a.scheme == "siconos" else 0.0,
           "solver": a.solver if a.scheme == "siconos" else "active-set-enum",
           "reps": a.reps, "median_s": med, "times": times,
           "per_step_us": med / a.n * 1e6, "err_max": err, "n_compared": int(X.shape[0]),
           "openblas_num_threads": os.environ["OPENBLAS_NUM_THREADS"],
           "siconos_version": siconos_version()}
    print(json.dumps(res))


if __name__ == "__main__":
    main()
