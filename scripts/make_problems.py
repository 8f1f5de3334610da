#!/usr/bin/env python3
"""Generate test problem directories for bench_qp_peers.py.

Problem directory format (same as the catchup C benchmark writes):
  C.mtx       Matrix Market coordinate real general, m x dim
  P.mtx       Matrix Market coordinate real symmetric (lower triangle), dim x dim
  g.txt       m numbers, one per line
  points.txt  K lines of dim numbers (the drifting points x_1..x_K)
  ref.txt     (optional) K lines of dim numbers: exact reference projections
The k-th problem is  argmin_{y : C y + g >= 0} 1/2 (y - x_k)^T P (y - x_k).

Every set K below is nonempty by construction (a feasible point is named).

Problems
--------
circuit
    dim 3, m 2, P = diag(1, 2, 1), C = [[0, 1, -1], [0, 1, 0]], g = 0
    (constraints y2 - y3 >= 0 and y2 >= 0; y = 0 is feasible).
    x_k = (0.1, -0.15 + 0.004 k, 0.2 - 0.001 k), k = 0..99: the first points
    violate both constraints, then one, and the last ~25 are already in K.
    ref.txt is EXACT: every active set of the 2 constraints is enumerated and
    the KKT-consistent one (feasible, multipliers >= 0) is kept.

crowd_N  (N = 1000, 10000, 100000)
    N disks of diameter d = 1; positions q in R^{2N}, interleaved
    (x_1, y_1, x_2, y_2, ...).  q0 is a hexagonal lattice with spacing
    s = sqrt(pi / (2 sqrt(3) phi)) for packing fraction phi = 0.65
    (s ~= 1.181), laid out as nx = ceil(sqrt(N sqrt(3)/2)) columns so that the box is
    about square, each centre jittered uniformly in a disk of radius
    0.999 (s - 1)/2, so every pairwise distance in q0 is >= 1 (checked).
    Pairs i < j with |q0_j - q0_i| < 1.5 d are found with a cell list of cell
    size 1.5 (no O(N^2) loop).  For each pair one row
        n_ij . (y_j - y_i) - d >= 0,   n_ij = (q0_j - q0_i)/|q0_j - q0_i|
    i.e. -n_ij on i's two coordinates, +n_ij on j's, and g_ij = -d = -1.
    P = I.  q0 is feasible (n_ij . (q0_j - q0_i) = |q0_j - q0_i| >= 1).
    Points: with c the centroid of q0, v = c - q0 (drift towards the centre),
        x_k = q0 + (alpha0 + k delta) v + sigma xi,   k = 0..K-1,
    alpha0 = 0.08, delta = 0.0005, sigma = 0.02, xi ~ N(0, I) fixed.
    At alpha0 a good number of pairs already overlap; the compression grows
    slowly with k so more and more constraints become active.
    K defaults: 50 (N=1000), 20 (N=10000), 10 (N=100000).  No ref.txt.

ladder_N  (N = 100000, 1000000)
    A chain ("diode ladder") with n = N diodes and dim = n + 1 node
    potentials y_0..y_n.  Row i (i = 0..n-1):  y_{i+1} - y_i + g_i >= 0,
    i.e. the potential may drop by at most the diode's forward voltage
    g_i ~ U[0.002, 0.006] across diode i.  P = diag(p), p_i ~ U[1, 10].
    y = 0 is feasible (g > 0).  With G_0 = 0, G_{i+1} = G_i + g_i and
    z_i = y_i + G_i the set is {z nondecreasing}, so the P-projection is a
    weighted isotonic regression of x + G with weights p: ref.txt is EXACT
    (pool-adjacent-violators, scipy.optimize.isotonic_regression, then y = z - G).
    Points: x_{k,i} = sin(2 pi i / 1000 + 0.02 k) + 0.005 xi_i,
    xi ~ N(0,1) fixed, k = 0..K-1 (K = 10 by default, 5 for N = 10^6).  The mean drop allowed
    per diode (0.004) is smaller than the steepest descent of the sine
    (2 pi/1000), so every falling stretch pools: ~55-60 % of the constraints
    are active at the projections.

randsp_300  (extra, validates a NON-diagonal sparse P)
    dim 300, m 450, P = B B^T/10 + I restricted to a banded pattern (SPD,
    bandwidth 3), C sparse random with 3 nonzeros per row, g = 1 + |N(0,1)|
    (y = 0 strictly feasible); x_k = 3 w + 0.01 k u.  K = 30.  No ref.txt.

Usage: python make_problems.py OUTDIR [--only circuit,crowd_1000,...] [--seed S]
                                      [--K name=K ...]
"""
import argparse
import math
import os
import sys
import zlib

import numpy as np
import scipy.io
import scipy.sparse as sp


def log(*a):
    print(*a, file=sys.stderr, flush=True)


def write_problem(outdir, name, C, P, g, X, ref=None):
    d = os.path.join(outdir, name)
    os.makedirs(d, exist_ok=True)
    C = sp.coo_matrix(C)
    scipy.io.mmwrite(os.path.join(d, "C.mtx"), C, field="real", precision=17,
                     symmetry="general")
    Pl = sp.tril(sp.coo_matrix(P)).tocoo()
    scipy.io.mmwrite(os.path.join(d, "P.mtx"), Pl, field="real", precision=17,
                     symmetry="symmetric")
    # mmwrite with symmetry='symmetric' on a lower-triangular matrix keeps the
    # lower triangle as is; verify it reads back as the full symmetric P
    np.savetxt(os.path.join(d, "g.txt"), np.asarray(g, float), fmt="%.17g")
    np.savetxt(os.path.join(d, "points.txt"), np.atleast_2d(X), fmt="%.17g")
    if ref is not None:
        np.savetxt(os.path.join(d, "ref.txt"), np.atleast_2d(ref), fmt="%.17g")
    elif os.path.exists(os.path.join(d, "ref.txt")):
        os.remove(os.path.join(d, "ref.txt"))
    log(f"wrote {d}: dim={C.shape[1]} m={C.shape[0]} nnz(C)={C.nnz} "
        f"K={np.atleast_2d(X).shape[0]} ref={'yes' if ref is not None else 'no'}")


def active_stats(C, g, Y, tol=1e-9):
    """fraction of rows of C active at the reference solutions Y (K x dim)"""
    r = (C @ Y.T).T + g
    return float(np.mean(np.abs(r) <= tol * (1 + np.abs(g))))


# ----------------------------------------------------------------- circuit
def make_circuit(outdir, K=100):
    P = sp.diags([1.0, 2.0, 1.0])
    Cd = np.array([[0.0, 1.0, -1.0], [0.0, 1.0, 0.0]])
    g = np.zeros(2)
    k = np.arange(K)
    X = np.stack([0.1 + 0 * k, -0.15 + 0.004 * k, 0.2 - 0.001 * k], axis=1)
    Pd = np.diag([1.0, 2.0, 1.0])
    ref = np.empty_like(X)
    for kk in range(K):
        x = X[kk]
        best = None
        for S in ([], [0], [1], [0, 1]):
            if S:
                A = Cd[S]
                ns = len(S)
                KKT = np.block([[Pd, -A.T], [A, np.zeros((ns, ns))]])
                sol = np.linalg.solve(KKT, np.concatenate([Pd @ x, -g[S]]))
                y, lam = sol[:3], sol[3:]
            else:
                y, lam = x.copy(), np.zeros(0)
            if np.all(Cd @ y + g >= -1e-14) and np.all(lam >= -1e-14):
                best = y
                break
        assert best is not None
        ref[kk] = best
    write_problem(outdir, "circuit", sp.csr_matrix(Cd), P, g, X, ref)
    log(f"  circuit: active fraction at ref = {active_stats(Cd, g, ref):.3f}; "
        f"points already feasible: {int(np.sum(np.all(X @ Cd.T + g >= 0, axis=1)))}/{K}")


# ------------------------------------------------------------------- crowd
def hex_jitter_packing(N, phi, rng):
    s = math.sqrt(math.pi / (2 * math.sqrt(3) * phi))
    nx = int(math.ceil(math.sqrt(N * math.sqrt(3) / 2)))
    idx = np.arange(N)
    row, col = idx // nx, idx % nx
    px = col * s + 0.5 * s * (row % 2)
    py = row * s * math.sqrt(3) / 2
    r = 0.999 * (s - 1) / 2
    rad = r * np.sqrt(rng.random(N))
    ang = 2 * math.pi * rng.random(N)
    px = px + rad * np.cos(ang)
    py = py + rad * np.sin(ang)
    return np.stack([px, py], axis=1), s


def cell_list_pairs(pos, cutoff):
    """all pairs i<j with |pos_i - pos_j| < cutoff, via a uniform cell grid."""
    N = pos.shape[0]
    lo = pos.min(axis=0)
    cell = np.floor((pos - lo) / cutoff).astype(np.int64)
    ncx, ncy = cell.max(axis=0) + 1
    cid = cell[:, 0] * ncy + cell[:, 1]
    order = np.argsort(cid, kind="stable")
    counts = np.bincount(cid, minlength=ncx * ncy)
    maxocc = int(counts.max())
    start = np.concatenate([[0], np.cumsum(counts)[:-1]])
    slot = np.empty(N, np.int64)
    slot[order] = np.arange(N) - start[cid[order]]
    grid = -np.ones((ncx + 2, ncy + 2, maxocc), np.int64)   # padded by one cell
    grid[cell[:, 0] + 1, cell[:, 1] + 1, slot] = np.arange(N)
    I_all, J_all = [], []
    # half stencil: each neighbouring cell pair visited once
    for dx, dy in ((0, 0), (1, -1), (1, 0), (1, 1), (0, 1)):
        A = grid[1:ncx + 1, 1:ncy + 1, :]
        B = grid[1 + dx:ncx + 1 + dx, 1 + dy:ncy + 1 + dy, :]
        for a in range(maxocc):
            for b in range(maxocc):
                i = A[:, :, a].ravel()
                j = B[:, :, b].ravel()
                ok = (i >= 0) & (j >= 0)
                if dx == 0 and dy == 0:
                    ok &= j > i
                i, j = i[ok], j[ok]
                dist2 = np.sum((pos[i] - pos[j]) ** 2, axis=1)
                ok = dist2 < cutoff * cutoff
                I_all.append(i[ok])
                J_all.append(j[ok])
    I = np.concatenate(I_all)
    J = np.concatenate(J_all)
    lo_, hi_ = np.minimum(I, J), np.maximum(I, J)
    key = np.unique(lo_ * N + hi_)
    return key // N, key % N


def make_crowd(outdir, N, K, rng, phi=0.65, alpha0=0.08, delta=0.0005, sigma=0.02):
    pos, s = hex_jitter_packing(N, phi, rng)
    I, J = cell_list_pairs(pos, 1.5)
    diff = pos[J] - pos[I]
    dist = np.sqrt(np.sum(diff ** 2, axis=1))
    assert dist.min() >= 1.0, dist.min()
    n = diff / dist[:, None]
    m = len(I)
    rows = np.repeat(np.arange(m), 4)
    cols = np.stack([2 * I, 2 * I + 1, 2 * J, 2 * J + 1], axis=1).ravel()
    vals = np.stack([-n[:, 0], -n[:, 1], n[:, 0], n[:, 1]], axis=1).ravel()
    C = sp.coo_matrix((vals, (rows, cols)), shape=(m, 2 * N))
    g = -np.ones(m)
    q0 = pos.ravel()
    assert np.all(C @ q0 + g >= -1e-12)
    c = pos.mean(axis=0)
    v = (c[None, :] - pos).ravel()
    xi = rng.standard_normal(2 * N)
    X = np.stack([q0 + (alpha0 + k * delta) * v + sigma * xi for k in range(K)])
    viol = [(np.mean(C @ X[k] + g < 0)) for k in (0, K - 1)]
    box = pos.max(axis=0) - pos.min(axis=0) + 1
    log(f"  crowd_{N}: lattice spacing {s:.4f}, box {box[0]:.1f} x {box[1]:.1f}, "
        f"packing fraction {N * math.pi / 4 / (box[0] * box[1]):.3f}, m={m} "
        f"(cell-list pairs < 1.5), min dist {dist.min():.4f}; violated rows "
        f"x_0: {viol[0]:.3f}, x_K-1: {viol[1]:.3f}")
    write_problem(outdir, f"crowd_{N}", C, sp.identity(2 * N), g, X, None)


# ------------------------------------------------------------------ ladder
def make_ladder(outdir, n, K, rng):
    from scipy.optimize import isotonic_regression
    dim = n + 1
    gi = rng.uniform(0.002, 0.006, n)
    p = rng.uniform(1.0, 10.0, dim)
    rows = np.repeat(np.arange(n), 2)
    cols = np.stack([np.arange(n), np.arange(1, n + 1)], axis=1).ravel()
    vals = np.tile([-1.0, 1.0], n)
    C = sp.coo_matrix((vals, (rows, cols)), shape=(n, dim))
    G = np.concatenate([[0.0], np.cumsum(gi)])
    assert np.all(C @ np.zeros(dim) + gi >= 0)
    xi = rng.standard_normal(dim)
    i = np.arange(dim)
    X = np.stack([np.sin(2 * math.pi * i / 1000 + 0.02 * k) + 0.005 * xi
                  for k in range(K)])
    ref = np.empty_like(X)
    for k in range(K):
        z = isotonic_regression(X[k] + G, weights=p, increasing=True).x
        ref[k] = z - G
    r = (C @ ref.T).T + gi
    assert r.min() >= -1e-10, r.min()
    act = float(np.mean(np.abs(r) <= 1e-12 * (1 + G[-1])))
    log(f"  ladder_{n}: active fraction at ref = {act:.3f}; min slack {r.min():.2e}")
    write_problem(outdir, f"ladder_{n}", C, sp.diags(p), gi, X, ref)


# ------------------------------------------------------------------ randsp
def make_randsp(outdir, n, K, rng):
    m = int(1.5 * n)
    B = sp.diags([rng.uniform(0.5, 1.5, n - k) for k in range(3)],
                 offsets=[0, 1, 2], shape=(n, n))
    P = (B @ B.T) / 10 + sp.identity(n)
    rows = np.repeat(np.arange(m), 3)
    cols = np.concatenate([rng.choice(n, 3, replace=False) for _ in range(m)])
    C = sp.coo_matrix((rng.standard_normal(3 * m), (rows, cols)), shape=(m, n))
    g = 1.0 + np.abs(rng.standard_normal(m))
    w, u = rng.standard_normal(n), rng.standard_normal(n)
    X = np.stack([3 * w + 0.01 * k * u for k in range(K)])
    write_problem(outdir, f"randsp_{n}", C, P, g, X, None)


ALL = ["circuit", "crowd_1000", "crowd_10000", "crowd_100000", "ladder_100000",
       "ladder_1000000", "randsp_300"]
DEFAULT_K = {"circuit": 100, "crowd_1000": 50, "crowd_10000": 20,
             "crowd_100000": 10, "ladder_100000": 10, "ladder_1000000": 5, "randsp_300": 30}


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("outdir")
    ap.add_argument("--only", default=",".join(ALL))
    ap.add_argument("--seed", type=int, default=12345)
    ap.add_argument("--K", action="append", default=[],
                    help="override number of points, e.g. --K crowd_100000=20")
    a = ap.parse_args()
    Ks = dict(DEFAULT_K)
    for kv in a.K:
        k, v = kv.split("=")
        Ks[k] = int(v)
    os.makedirs(a.outdir, exist_ok=True)
    for name in a.only.split(","):
        rng = np.random.default_rng([a.seed, zlib.crc32(name.encode())])
        if name == "circuit":
            make_circuit(a.outdir, Ks[name])
        elif name.startswith("crowd_"):
            make_crowd(a.outdir, int(name.split("_")[1]), Ks[name], rng)
        elif name.startswith("ladder_"):
            make_ladder(a.outdir, int(name.split("_")[1]), Ks[name], rng)
        elif name.startswith("randsp_"):
            make_randsp(a.outdir, int(name.split("_")[1]), Ks[name], rng)
        else:
            sys.exit(f"unknown problem {name}")


if __name__ == "__main__":
    main()
