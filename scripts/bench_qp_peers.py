#!/usr/bin/env python3
"""Peer side of the catchup projector benchmark: QP solvers via Python wrappers.

For a problem directory (C.mtx, P.mtx, g.txt, points.txt, optional ref.txt) the
k-th QP is
    minimize 1/2 y^T P y - (P x_k)^T y   subject to  C y >= -g   (no upper bound),
i.e. the P-metric projection of x_k onto K = {y : C y + g >= 0}.

For every (problem, solver, mode) ONE JSON line is printed on stdout; all
diagnostics go to stderr.

Modes
  cold  every point from scratch: a fresh solver object + setup per point, no
        warm start.  Timed = setup + solve per point.
  warm  the sequence in order with ONE setup (done with q_0, timed separately as
        setup_s); for k >= 1 only the linear term is updated and the solver is
        warm-started from the previous primal/dual solution where the API allows:
          OSQP    warm_starting=True (default): solve() restarts from the
                  previous (x, y) kept in the workspace after update(q=...).
          DAQP    Model.update(f=...) then Model.solve(): the workspace keeps the
                  previous working (active) set, i.e. a hot start.
          ProxQP  settings.initial_guess = WARM_START_WITH_PREVIOUS_RESULT,
                  update(g=...) then solve() (previous x, y, z are reused).
          PIQP    interior point: no primal/dual warm start exists in the API;
                  "warm" = setup once + update(c=...) (reuses the symbolic
                  factorisation/allocations), noted in the output.
        Timed = update + solve per point (setup excluded; time_per_proj_incl_setup_s
        adds setup_s/K).

Timing: time.perf_counter around the solver calls only (no file reading, no
result copying beyond what the wrapper's solve() itself does).
time_per_proj_s = median over reps of (total timed sequence time / K).

Memory: the first --memory-points points of every reported sequence run
again in a fresh (spawned) interpreter which, once the problem is loaded,
gives the C heap's free memory back (malloc_trim) and restarts the kernel's
peak-RSS record (/proc/self/clear_refs) and reports the
peak resident set after the run (VmHWM): peak_rss_kb, and solver_rss_kb = that
peak minus its resident size after loading and minus the library code paged
in on first use (the growth of RssFile), i.e. the solver's own data. (A
forked child would reuse the parent's freed heap and hide the solver's
allocations.) The resident figures come from one read of /proc/self/status
each. With --heapcount SO (bench/heap.c, preloaded) it also reports
solver_heap_bytes: the most bytes malloc held at once during the run above
what it held before (catchup-bench reports the same with the same shim);
pages are too coarse for sets of a few rows. --memory-only PEERS.jsonl does
this alone for an earlier run.

Accuracy: rel_err = max_k ||y_k - ref_k||_P / max(||ref_k||_P, ||x_k||_P, 1e-300).
"At equal accuracy": the solver's tolerances walk down a ladder (default
eps = 1e-7 ... 1e-13, eps_abs = eps_rel = eps; OSQP: each eps without then with
polishing; DAQP: primal_tol = eps) and the loosest level whose rel_err <= --acc
is reported (its time).  If none meets it, the level with the best rel_err is
reported with met=false.  The ladder is walked with a single rep per level; the
remaining reps are only spent on the reported level.

Budget: --max-seconds S per (problem, solver): warm mode must finish its ladder
by start + S/2, cold mode by start + S; a level is not started after its
deadline, a sequence that runs past it is cut (points_done < K, truncated=true)
and the accuracy is computed over the points done.  OSQP and DAQP get the
remaining time as their own time_limit; ProxQP and PIQP have none, so on
problems with dim + m >= 1e4 every sequence runs in a forked child that is
killed --grace-seconds after the deadline (the points already finished are
streamed back and kept).

Reference: ref.txt if present (unless --recompute-ref).  Otherwise
(--ref-method auto): if dim + m <= 1e5, PIQP at eps = 1e-12 (looser if it
does not converge) followed by an active-set polish (method of multipliers on
the equality-constrained QP of the active rows, with primal-dual active-set
correction rounds); for larger problems the same active-set/KKT machinery
started from the rows violated at x_k (no QP solver involved; PIQP guess as
fallback).  Either way the result is checked by its KKT residuals (ref_kkt).
Validated against the exact references of circuit (enumeration) and
ladder_100000 (PAVA): relative differences ~1e-13.

Usage:
  python bench_qp_peers.py PROBLEM_DIR [PROBLEM_DIR...] [--solvers osqp,daqp,proxqp,piqp]
      [--acc 1e-8] [--reps 5] [--max-seconds 300] [--max-points K]
      [--ladder 1e-7,1e-8,...] [--modes warm,cold] [--recompute-ref]
      [--ref-method auto|piqp|pdas|daqp] [--fork auto|always|never] [--grace-seconds 10]
"""
import os

# single-threaded by default, like the C projector (set before numpy import)
for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse
import collections
import importlib
import json
import math
import sys
import time
import warnings
from importlib import metadata

import numpy as np
import scipy.io
import scipy.sparse as sp
import scipy.sparse.linalg as spla

BIG = 1e30          # "infinite" upper bound for solvers that want a number
TINY = 1e-300


def log(*a):
    print(*a, file=sys.stderr, flush=True)


# Some solver C libraries printf() to fd 1 even with verbose off (OSQP prints
# "Polishing not needed ..."), which would corrupt the JSON stream.  Keep a
# private duplicate of the real stdout for the JSON lines and point fd 1 (and
# sys.stdout) at stderr.
JSON_OUT = None


def protect_stdout():
    global JSON_OUT
    sys.stdout.flush()
    JSON_OUT = os.fdopen(os.dup(1), "w", buffering=1)
    os.dup2(2, 1)
    sys.stdout = sys.stderr


def _clean(o):
    """strict JSON: numpy scalars -> Python, non-finite floats -> "inf"/"nan"."""
    if isinstance(o, dict):
        return {str(k): _clean(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [_clean(v) for v in o]
    if isinstance(o, (np.integer,)):
        return int(o)
    if isinstance(o, (float, np.floating)):
        f = float(o)
        return f if math.isfinite(f) else str(f)
    if isinstance(o, np.bool_):
        return bool(o)
    return o


def emit(d):
    # the machine may be shared: record the 1/5/15-min load averages so noisy
    # timings can be recognised
    try:
        d = dict(d, loadavg=[round(v, 2) for v in os.getloadavg()], ncpu=os.cpu_count())
    except OSError:
        pass
    JSON_OUT.write(json.dumps(_clean(d), allow_nan=False) + "\n")
    JSON_OUT.flush()


def pkg_version(name):
    try:
        return metadata.version(name)
    except Exception:
        return None


# ---------------------------------------------------------------- problem
class Problem:
    def __init__(self, path, max_points=None):
        self.path = os.path.abspath(path)
        self.name = os.path.basename(self.path.rstrip("/"))
        self.C = sp.csc_matrix(scipy.io.mmread(os.path.join(path, "C.mtx")), dtype=float)
        # mmread expands 'symmetric' storage into the full matrix
        P = sp.csc_matrix(scipy.io.mmread(os.path.join(path, "P.mtx")), dtype=float)
        P.sum_duplicates()
        self.P = P
        self.Ptriu = sp.triu(P, format="csc")
        self.m, self.dim = self.C.shape
        assert P.shape == (self.dim, self.dim), "P/C dimension mismatch"
        self.g = np.loadtxt(os.path.join(path, "g.txt"), ndmin=1).astype(float)
        assert self.g.shape == (self.m,), "g has wrong length"
        X = np.loadtxt(os.path.join(path, "points.txt"), ndmin=2)
        if self.dim == 1 and X.shape[0] == 1 and X.shape[1] != 1:
            X = X.T
        self.K_file = X.shape[0]
        if max_points:
            X = X[:max_points]
        self.X = np.ascontiguousarray(X, dtype=float)
        assert self.X.shape[1] == self.dim, "points have wrong dimension"
        self.K = self.X.shape[0]
        self.Q = np.ascontiguousarray(-(self.P @ self.X.T).T)   # linear terms
        rp = os.path.join(path, "ref.txt")
        self.ref_file = None
        if os.path.exists(rp):
            R = np.loadtxt(rp, ndmin=2)
            self.ref_file = np.ascontiguousarray(R[: self.K], dtype=float)
            assert self.ref_file.shape == self.X.shape, "ref.txt has wrong shape"
        self.is_diag_P = (P - sp.diags(P.diagonal())).count_nonzero() == 0
        self.xnorm = np.array([self.pnorm(x) for x in self.X])

    def pnorm(self, v):
        return math.sqrt(max(float(v @ (self.P @ v)), 0.0))

    def accuracy(self, Y, ref, npts=None):
        """(max relative P-error, max absolute P-error, max constraint violation)"""
        n = self.K if npts is None else npts
        rel, ab, viol = 0.0, 0.0, 0.0
        for k in range(n):
            e = self.pnorm(Y[k] - ref[k])
            den = max(self.pnorm(ref[k]), self.xnorm[k], TINY)
            rel = max(rel, e / den)
            ab = max(ab, e)
            r = self.C @ Y[k] + self.g
            viol = max(viol, float(max(0.0, -r.min())) if self.m else 0.0)
        if not np.all(np.isfinite(Y[:n])):
            rel = ab = float("inf")
        return rel, ab, viol


# ---------------------------------------------------------------- solvers
class SolverBase:
    name = "?"
    pkg = "?"
    note = ""
    module = None     # "osqp", or "proxsuite.proxqp" (from proxsuite import proxqp): self.osqp, self.proxqp
    _cache = None     # a dense solver's copy of the problem's data, (prob, ...), made once a problem

    def __init__(self, args):
        self.args = args
        self.version = pkg_version(self.pkg)
        if self.module:
            top, _, sub = self.module.partition(".")
            mod = importlib.import_module(top)
            if sub:
                mod = getattr(mod, sub, None) or importlib.import_module(self.module)
            setattr(self, sub or top, mod)

    def applicable(self, prob):
        return True, ""

    def prepare(self, prob):
        """untimed data preparation (e.g. densification)"""
        pass

    def levels(self, ladder):
        # for each eps: relative+absolute test, then absolute-only (eps_rel=0):
        # with large ||P x|| (crowd: positions ~ box size) eps_rel*||.|| makes
        # the stopping test far looser than eps_abs (PIQP crowd_1000: eps=1e-12
        # gives rel_err 1.8e-8, eps_abs=1e-10/eps_rel=0 gives 3.8e-9).
        out = []
        for e in ladder:
            out.append({"eps_abs": e, "eps_rel": e})
            out.append({"eps_abs": e, "eps_rel": 0.0})
        return out

    # returns (timed_seconds, state)
    def setup(self, prob, q, level, warm, time_left):
        raise NotImplementedError

    def update_solve(self, state, q, time_left):
        """warm mode, k >= 1: returns timed seconds"""
        raise NotImplementedError

    def solve(self, state, time_left):
        """first solve after setup: returns timed seconds"""
        raise NotImplementedError

    def result(self, state):
        """(y copy, iterations, status string)"""
        raise NotImplementedError


OSQP_POLISH = {1: "ok", 0: "not_performed", -1: "failed", -2: "linsys_error",
               2: "no_active_set"}


class OSQPSolver(SolverBase):
    name, pkg = "osqp", "osqp"
    note = "warm: warm_starting=True, update(q=) keeps previous (x,y); osqp>=1 setting names (polishing, warm_starting)"
    module = "osqp"

    def levels(self, ladder):
        out = []
        for e in ladder:
            out.append({"eps_abs": e, "eps_rel": e, "polishing": False})
            out.append({"eps_abs": e, "eps_rel": e, "polishing": True})
        return out

    def setup(self, prob, q, level, warm, time_left):
        s = self.osqp.OSQP()
        u = np.full(prob.m, np.inf)
        l = -prob.g
        kw = dict(verbose=False, eps_abs=level["eps_abs"], eps_rel=level["eps_rel"],
                  polishing=level["polishing"], max_iter=self.args.max_iter,
                  warm_starting=warm, time_limit=max(time_left, 1e-3))
        t0 = time.perf_counter()
        s.setup(prob.Ptriu, q, prob.C, l, u, **kw)
        t = time.perf_counter() - t0
        return t, {"s": s, "r": None}

    def solve(self, st, time_left):
        st["s"].update_settings(time_limit=max(time_left, 1e-3))
        t0 = time.perf_counter()
        st["r"] = st["s"].solve(raise_error=False)
        return time.perf_counter() - t0

    def update_solve(self, st, q, time_left):
        st["s"].update_settings(time_limit=max(time_left, 1e-3))
        t0 = time.perf_counter()
        st["s"].update(q=q)
        st["r"] = st["s"].solve(raise_error=False)
        return time.perf_counter() - t0

    def result(self, st):
        r = st["r"]
        stat = str(r.info.status)
        if st["s"].settings.polishing:
            ps = int(r.info.status_polish)
            stat += "/polish_" + OSQP_POLISH.get(ps, str(ps))
        return np.array(r.x, dtype=float, copy=True), int(r.info.iter), stat


DAQP_FLAGS = {1: "optimal", 2: "soft_optimal", 3: "?3", -1: "infeasible",
              -2: "cycling", -3: "unbounded", -4: "iter_limit", -5: "nonconvex",
              -6: "overdetermined_initial", -7: "time_limit"}


class DAQPSolver(SolverBase):
    name, pkg = "daqp", "daqp"
    note = "dense active set; warm: Model.update(f=) keeps the working set (hot start); level eps -> primal_tol"
    module = "daqp"

    def applicable(self, prob):
        if prob.dim > self.args.daqp_max_dim:
            return False, f"skipped: dense solver, dim {prob.dim} > --daqp-max-dim {self.args.daqp_max_dim}"
        return True, ""

    def levels(self, ladder):
        return [{"primal_tol": e} for e in ladder]

    def prepare(self, prob):
        self._dense(prob)

    def _dense(self, prob):
        if self._cache is None or self._cache[0] is not prob:
            H = np.ascontiguousarray(prob.P.toarray())
            A = np.ascontiguousarray(prob.C.toarray())
            self._cache = (prob, H, A, np.full(prob.m, BIG), np.ascontiguousarray(-prob.g))
        return self._cache[1:]

    def setup(self, prob, q, level, warm, time_left):
        H, A, bu, bl = self._dense(prob)   # densification not timed (data prep)
        sense = np.zeros(prob.m, dtype=np.int32)
        d = self.daqp.Model()
        t0 = time.perf_counter()
        d.setup(H, np.ascontiguousarray(q), A, bu, bl, sense)
        d.settings = {"primal_tol": level["primal_tol"],
                      "iter_limit": self.args.daqp_iter_limit,
                      "time_limit": max(time_left, 1e-3)}
        t = time.perf_counter() - t0
        return t, {"d": d, "out": None}

    def solve(self, st, time_left):
        st["d"].settings = {"time_limit": max(time_left, 1e-3)}
        t0 = time.perf_counter()
        st["out"] = st["d"].solve()
        return time.perf_counter() - t0

    def update_solve(self, st, q, time_left):
        st["d"].settings = {"time_limit": max(time_left, 1e-3)}
        t0 = time.perf_counter()
        st["d"].update(f=np.ascontiguousarray(q))
        st["out"] = st["d"].solve()
        return time.perf_counter() - t0

    def result(self, st):
        x, f, ef, info = st["out"]
        return np.array(x, dtype=float, copy=True), int(info["iterations"]), DAQP_FLAGS.get(int(ef), f"exitflag={ef}")


class ProxQPSolver(SolverBase):
    name, pkg = "proxqp", "proxsuite"
    note = "warm: update(g=) + initial_guess=WARM_START, solve(x_prev, y_prev, z_prev); cold and first solve: EQUALITY_CONSTRAINED_INITIAL_GUESS (default); check_duality_gap=True"
    module = "proxsuite.proxqp"

    def prepare(self, prob):
        if self.backend(prob) == "dense" and (self._cache is None or self._cache[0] is not prob):
            self._cache = (prob, prob.P.toarray(), prob.C.toarray())

    def backend(self, prob):
        b = self.args.proxqp_backend
        if b == "auto":
            b = "dense" if prob.dim * (prob.dim + prob.m) <= 4e6 else "sparse"
        return b

    def setup(self, prob, q, level, warm, time_left):
        pq = self.proxqp
        b = self.backend(prob)
        if b == "dense":
            if self._cache is None or self._cache[0] is not prob:
                self._cache = (prob, prob.P.toarray(), prob.C.toarray())
            H, C = self._cache[1], self._cache[2]
        else:
            H, C = prob.P, prob.C
        l = -prob.g
        u = np.full(prob.m, np.inf)
        t0 = time.perf_counter()
        if b == "dense":
            qp = pq.dense.QP(prob.dim, 0, prob.m)
        else:
            qp = pq.sparse.QP(prob.dim, 0, prob.m)
        st = qp.settings
        st.eps_abs = level["eps_abs"]
        st.eps_rel = level["eps_rel"]
        # without the duality-gap test ProxQP may stop with primal and dual
        # residuals below eps but complementarity violated (stale multipliers
        # on constraints that are no longer active): seen with
        # NO_INITIAL_GUESS and WARM_START_WITH_PREVIOUS_RESULT, errors ~1e-3.
        st.check_duality_gap = True
        st.eps_duality_gap_abs = level["eps_abs"]
        st.eps_duality_gap_rel = level["eps_rel"]
        st.verbose = False
        st.max_iter = self.args.max_iter
        st.compute_timings = False
        # first solve (and every cold solve): ProxQP's default
        # EQUALITY_CONSTRAINED_INITIAL_GUESS, with no equalities the
        # unconstrained minimiser x_k.  NO_INITIAL_GUESS (zeros) was markedly
        # less accurate at equal eps on 'circuit' and ~50x slower per solve on
        # crowd_1000 (sparse).
        st.initial_guess = pq.InitialGuess.EQUALITY_CONSTRAINED_INITIAL_GUESS
        qp.init(H, q, None, None, C, l, u)
        t = time.perf_counter() - t0
        return t, {"qp": qp, "prev": None}

    def solve(self, st, time_left):
        t0 = time.perf_counter()
        st["qp"].solve()
        return time.perf_counter() - t0

    def update_solve(self, st, q, time_left):
        # warm start: initial_guess = WARM_START and solve(x, y, z) with the
        # previous result.  WARM_START_WITH_PREVIOUS_RESULT + solve() gives the
        # same iterates but cost ~0.29 s per solve instead of ~4 ms on
        # crowd_1000 (sparse backend, proxsuite 0.8.0).
        qp = st["qp"]
        x, y, z = st["prev"]
        t0 = time.perf_counter()
        qp.settings.initial_guess = self.proxqp.InitialGuess.WARM_START
        qp.update(g=q)
        qp.solve(x, y, z)
        return time.perf_counter() - t0

    def result(self, st):
        r = st["qp"].results
        st["prev"] = (np.array(r.x, copy=True), np.array(r.y, copy=True), np.array(r.z, copy=True))
        s = str(r.info.status).split(".")[-1]
        return st["prev"][0].copy(), int(r.info.iter), s


class PIQPSolver(SolverBase):
    name, pkg = "piqp", "piqp"
    note = "interior point, SparseSolver; no primal/dual warm start in the API: warm = setup once + update(c=)"
    module = "piqp"

    def _settings(self, s, eps_abs, eps_rel, max_iter):
        st = s.settings
        st.eps_abs = eps_abs
        st.eps_rel = eps_rel
        st.eps_duality_gap_abs = eps_abs
        st.eps_duality_gap_rel = eps_rel
        st.verbose = False
        st.max_iter = max_iter
        st.compute_timings = False

    def setup(self, prob, q, level, warm, time_left):
        t0 = time.perf_counter()
        s = self.piqp.SparseSolver()
        self._settings(s, level["eps_abs"], level["eps_rel"], self.args.piqp_max_iter)
        s.setup(prob.Ptriu, q, None, None, prob.C, -prob.g, None)
        t = time.perf_counter() - t0
        return t, {"s": s, "status": None}

    def solve(self, st, time_left):
        t0 = time.perf_counter()
        st["status"] = st["s"].solve()
        return time.perf_counter() - t0

    def update_solve(self, st, q, time_left):
        t0 = time.perf_counter()
        st["s"].update(c=q)
        st["status"] = st["s"].solve()
        return time.perf_counter() - t0

    def result(self, st):
        r = st["s"].result
        return (np.array(r.x, dtype=float, copy=True), int(r.info.iter),
                str(st["status"]).split(".")[-1])


SOLVERS = {"osqp": OSQPSolver, "daqp": DAQPSolver, "proxqp": ProxQPSolver, "piqp": PIQPSolver}


# ---------------------------------------------------------------- runner
def iter_sequence(prob, solver, level, mode, deadline):
    """Solve the K points in the given mode; yields one record per point."""
    st = None
    for k in range(prob.K):
        left = deadline - time.perf_counter()
        if k > 0 and left <= 0:
            return
        if mode == "cold" or k == 0:
            ts, st = solver.setup(prob, prob.Q[k], level, mode == "warm", left)
            t = solver.solve(st, deadline - time.perf_counter())
            rec = {"k": k, "setup": ts, "timed": ts + t if mode == "cold" else t}
        else:
            rec = {"k": k, "setup": 0.0, "timed": solver.update_solve(st, prob.Q[k], left)}
        rec["y"], rec["it"], rec["status"] = solver.result(st)
        yield rec


def reset_peak():
    """restart the kernel's peak-RSS record (VmHWM) at the current size, so that
    the peak measured later is the solver's, not the file loading's; the C
    heap's free memory is given back first (malloc_trim), so that memory the
    loading freed and the solver reuses counts (catchup-bench does the same)"""
    try:
        import ctypes
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):
        pass
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
        return True
    except OSError:
        return False


def rss_now():
    """(VmHWM, VmRSS, RssFile) in kB from one read of /proc/self/status: the
    peak resident set since reset_peak(), the resident set now and its part
    mapped from files (the libraries' code among them). One read, so that code
    paged in by the reading falls on one side of it, not between two figures
    (catchup-bench does the same)."""
    fig = {}
    with open("/proc/self/status") as f:
        text = f.read()
    for line in text.splitlines():
        key, _, val = line.partition(":")
        if key in ("VmHWM", "VmRSS", "RssFile"):
            fig[key] = int(val.split()[0])
    if "VmHWM" not in fig:
        import resource
        fig["VmHWM"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return fig["VmHWM"], fig.get("VmRSS", 0), fig.get("RssFile", 0)


def heapcount(name):
    """the heapcount shim's function `name` (bench/heap.c, preloaded by
    --heapcount), or None"""
    import ctypes
    try:
        fn = getattr(ctypes.CDLL(None), name)
    except (OSError, AttributeError):
        return None
    fn.restype = ctypes.c_long
    return fn


def _memory_main(conn, path, solver_name, args, level, mode, npts):
    """A fresh interpreter (spawned, not forked: a forked child reuses the
    parent's freed heap and hides the solver's allocations): load the problem,
    note the resident size, run the first npts points of the sequence, report
    (resident before, peak, heap bytes held at most or None)."""
    import gc
    try:
        prob = Problem(path, npts)
        solver = SOLVERS[solver_name](args)
        solver.prepare(prob)
        gc.collect()
        heap_reset, heap_peak = heapcount("cup_heapcount_reset"), heapcount("cup_heapcount_peak")
        reset_peak()
        _, base, code = rss_now()
        if heap_reset:   # after the last file read before the run (its 8 kB buffer)
            heap_reset()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            for _ in iter_sequence(prob, solver, level, mode,
                                   time.perf_counter() + args.memory_seconds):
                pass
        heap = heap_peak() if heap_peak else None
        peak, _, code_after = rss_now()
        # library code paged in on first use is not the solver's data
        conn.send(("rss", (base + code_after - code, peak, heap)))
    except BaseException as e:
        conn.send(("error", f"{type(e).__name__}: {e}"))
    finally:
        conn.close()


def measure_memory(prob, solver_name, args, level, mode):
    """(resident kB before the solver, peak kB, heap bytes or None) of one
    sequence in a fresh process, on the first --memory-points points, or None;
    with --heapcount, that process has the shim preloaded."""
    import multiprocessing as mp
    ctx = mp.get_context("spawn")
    rd, wr = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_memory_main, args=(wr, prob.path, solver_name, args, level, mode,
                                                  min(prob.K, args.memory_points)))
    preload = os.environ.get("LD_PRELOAD")
    if args.heapcount:
        os.environ["LD_PRELOAD"] = os.path.abspath(args.heapcount)
    try:
        proc.start()
    finally:
        if args.heapcount:
            if preload is None:
                del os.environ["LD_PRELOAD"]
            else:
                os.environ["LD_PRELOAD"] = preload
    wr.close()
    kind, val = "error", "no answer within --memory-seconds + 60 s: killed"
    try:
        if rd.poll(args.memory_seconds + 60):
            kind, val = rd.recv()
    except EOFError:
        kind, val = "error", "child died"
    if proc.is_alive():
        proc.kill()
    proc.join()
    if kind != "rss":
        log(f"[{prob.name}/{solver_name}/{mode}] memory probe failed: {val}")
        return None
    return val


def _child_main(conn, prob, solver, level, mode, deadline):
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            # batch the records (flush at most every 0.25 s): a pipe write +
            # parent wake-up between two microsecond solves measurably slowed
            # the next solve (circuit: DAQP warm 2.5 -> 5 us per projection)
            buf, last = [], time.perf_counter()
            for rec in iter_sequence(prob, solver, level, mode, deadline):
                buf.append(rec)
                now = time.perf_counter()
                if now - last > 0.25:
                    conn.send(("points", buf))
                    buf, last = [], time.perf_counter()
            if buf:
                conn.send(("points", buf))
        conn.send(("end", None))
    except BaseException as e:  # report, never hang the parent
        try:
            conn.send(("error", f"{type(e).__name__}: {e}"))
        except Exception:
            pass
    finally:
        conn.close()


def _records(prob, solver, level, mode, deadline, hard_deadline, use_fork):
    """yields ('points', [rec, ...]) ... then ('end'|'error'|'killed', info)."""
    if not use_fork:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                for rec in iter_sequence(prob, solver, level, mode, deadline):
                    yield "points", [rec]
            yield "end", None
        except Exception as e:
            yield "error", f"{type(e).__name__}: {e}"
        return
    # Run in a forked child so that solvers without a time limit (ProxQP,
    # PIQP) can be stopped at the hard deadline; the per-point results stream
    # back through a pipe so the points done survive a kill.  Timing is done
    # inside the child around the solver calls only.
    import multiprocessing as mp
    ctx = mp.get_context("fork")
    rd, wr = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_child_main, args=(wr, prob, solver, level, mode, deadline),
                       daemon=True)
    proc.start()
    wr.close()
    try:
        while True:
            remaining = hard_deadline - time.perf_counter()
            if remaining <= 0 or not rd.poll(remaining):
                proc.kill()
                yield "killed", "hard deadline (budget + grace) reached: child process killed"
                return
            try:
                kind, val = rd.recv()
            except EOFError:
                yield "error", f"child died (exit code {proc.exitcode})"
                return
            yield kind, val
            if kind != "points":
                return
    finally:
        proc.join(5)
        if proc.is_alive():
            proc.kill()
            proc.join()
        rd.close()


def run_sequence(prob, solver, level, mode, deadline, args):
    """Solve the K points in the given mode. Returns a dict."""
    K = prob.K
    Y = np.full((K, prob.dim), np.nan)
    iters = np.zeros(K, dtype=np.int64)
    statuses = collections.Counter()
    timed = 0.0
    setup_total = 0.0
    setup_warm = None
    done = 0
    end = None
    t_start = time.perf_counter()
    hard = deadline + max(args.grace_seconds, 0.0)
    use_fork = args.fork == "always" or (args.fork == "auto"
                                         and prob.dim + prob.m >= args.fork_min_size)
    for kind, val in _records(prob, solver, level, mode, deadline, hard, use_fork):
        if kind != "points":
            end = None if kind == "end" else f"{kind}: {val}"
            break
        for rec in val:
            k = rec["k"]
            Y[k] = rec["y"]
            iters[k] = rec["it"]
            statuses[rec["status"]] += 1
            timed += rec["timed"]
            if mode == "cold":
                setup_total += rec["setup"]
            elif k == 0:
                setup_warm = rec["setup"]
            done = k + 1
    return {"Y": Y, "iters": iters[:done], "statuses": dict(statuses), "timed": timed,
            "setup_total": setup_total, "setup_warm": setup_warm, "done": done,
            "wall": time.perf_counter() - t_start, "end": end}


def add_memory(out, prob, solver_name, args, level, mode):
    rss = measure_memory(prob, solver_name, args, level, mode)
    if rss is not None:
        out["peak_rss_kb"] = int(rss[1])
        out["solver_rss_kb"] = int(max(rss[1] - rss[0], 0))
        if rss[2] is not None:
            out["solver_heap_bytes"] = int(rss[2])
        out["rss_meaning"] = (f"a fresh process ran the first {min(prob.K, args.memory_points)} "
                              "points at this setting: its peak resident set (peak_rss_kb) and "
                              "that minus its size after loading the problem (solver_rss_kb)")


def memory_only(path, args):
    """--memory-only PEERS.jsonl: measure (again) the memory of every reported
    sequence of an earlier run, timings untouched; the lines go to stdout."""
    probs = {}
    for line in open(path):
        d = json.loads(line)
        if d.get("problem") and not d.get("skipped") and d.get("setting") is not None:
            key = d["problem"]
            if key not in probs:
                dirs = [p for p in args.problems if os.path.basename(p.rstrip("/")) == key]
                probs[key] = Problem(dirs[0]) if dirs else None
            if probs[key] is not None:
                for k in ("peak_rss_kb", "solver_rss_kb", "solver_heap_bytes", "rss_meaning"):
                    d.pop(k, None)
                add_memory(d, probs[key], d["solver"], args, d["setting"], d["mode"])
                log(f"[{key}/{d['solver']}/{d['mode']}] memory {d.get('solver_rss_kb')} kB")
        JSON_OUT.write(json.dumps(_clean(d), allow_nan=False) + "\n")
        JSON_OUT.flush()


def bench(prob, solver, ref, ref_info, args):
    ok, why = solver.applicable(prob)
    base = {"problem": prob.name, "dim": prob.dim, "m": prob.m, "nnz_C": int(prob.C.nnz),
            "K": prob.K, "K_file": prob.K_file, "solver": solver.name,
            "version": solver.version, "target_acc": args.acc}
    if isinstance(solver, ProxQPSolver):
        base["backend"] = solver.backend(prob)
    elif isinstance(solver, DAQPSolver):
        base["backend"] = "dense"
    else:
        base["backend"] = "sparse"
    base.update(ref_info)
    if not ok:
        for mode in args.modes:
            emit(dict(base, mode=mode, skipped=True, met=False, rel_err=None, note=why))
        return
    solver.prepare(prob)   # untimed data preparation, done before forking
    t0 = time.perf_counter()
    S = args.max_seconds
    for mode in args.modes:
        deadline = t0 + (S / 2 if (mode == "warm" and "cold" in args.modes
                                  and args.modes.index("warm") < args.modes.index("cold")) else S)
        tried = []
        chosen = None
        best = None
        notes = []
        for level in solver.levels(args.ladder):
            if time.perf_counter() >= deadline:
                notes.append("budget exhausted before level " + json.dumps(level))
                break
            res = run_sequence(prob, solver, level, mode, deadline, args)
            if res["end"]:
                notes.append(f"{res['end']} (level {json.dumps(level)}, {res['done']} points done)")
                log(f"[{prob.name}/{solver.name}/{mode}] {res['end']} at {level}")
            if res["done"] == 0:
                break
            rel, ab, viol = prob.accuracy(res["Y"], ref, res["done"])
            ent = {"level": level, "res": res, "rel": rel, "abs": ab, "viol": viol,
                   "complete": res["done"] == prob.K}
            tried.append(ent)
            log(f"[{prob.name}/{solver.name}/{mode}] {level} rel_err={rel:.3e} "
                f"iters={res['iters'].mean() if res['done'] else float('nan'):.1f} "
                f"t/proj={res['timed'] / max(res['done'], 1):.3e}s done={res['done']}/{prob.K} "
                f"{res['statuses']}")
            # best = most accurate COMPLETE sequence (a run cut by the budget
            # is only used if nothing completed)
            complete = res["done"] == prob.K
            if (best is None or (complete and not best["complete"])
                    or (complete == best["complete"] and rel < best["rel"])):
                best = ent
            ent["complete"] = complete
            if res["done"] < prob.K:
                if not res["end"]:
                    notes.append(f"sequence cut by the time budget at level {json.dumps(level)}")
                break
            if rel <= args.acc:
                chosen = ent
                break
        rep = chosen or best
        out = dict(base, mode=mode)
        if rep is None:
            out.update(skipped=True, met=False, rel_err=None, note="; ".join(notes) or "nothing run")
            emit(out)
            continue
        res = rep["res"]
        n = res["done"]
        times = [res["timed"] / n]
        setups = [res["setup_warm"] if mode == "warm" else res["setup_total"] / n]
        if n == prob.K:
            for r in range(args.reps - 1):
                if time.perf_counter() >= deadline:
                    notes.append(f"budget: only {len(times)} of {args.reps} reps")
                    break
                rr = run_sequence(prob, solver, rep["level"], mode, deadline, args)
                if rr["done"] < prob.K:
                    notes.append("a timing rep was cut by the budget (ignored)"
                                 + (f" [{rr['end']}]" if rr["end"] else ""))
                    break
                times.append(rr["timed"] / prob.K)
                setups.append(rr["setup_warm"] if mode == "warm" else rr["setup_total"] / prob.K)
        tpp = float(np.median(times))
        # peak memory: from the timed runs if they ran in a child process,
        # else from one more (untimed) run of the sequence in a child
        add_memory(out, prob, solver.name, args, rep["level"], mode)
        out.update({
            "setting": rep["level"],
            "time_per_proj_s": tpp,
            "time_stat": "median over reps of (timed sequence time / K); cold = setup+solve per point, warm = update+solve (setup once, excluded)",
            "time_reps_s": [float(t) for t in times],
            "reps_done": len(times),
            "setup_s": float(np.median([s for s in setups if s is not None])) if any(s is not None for s in setups) else None,
            "setup_meaning": "one setup for the whole sequence" if mode == "warm" else "mean setup per point (included in time_per_proj_s)",
            "iters_mean": float(res["iters"].mean()),
            "iters_max": int(res["iters"].max()),
            "rel_err": rep["rel"],
            "abs_err_P": rep["abs"],
            "max_violation": rep["viol"],
            "met": bool(rep["rel"] <= args.acc and n == prob.K),
            "status": res["statuses"],
            "points_done": n,
            "truncated": n < prob.K,
            "levels_tried": [{"level": e["level"], "rel_err": e["rel"],
                              "time_per_proj_s": e["res"]["timed"] / max(e["res"]["done"], 1),
                              "iters_mean": float(e["res"]["iters"].mean()) if e["res"]["done"] else None,
                              "points_done": e["res"]["done"], "status": e["res"]["statuses"]}
                             for e in tried],
            "note": "; ".join([solver.note] + notes),
        })
        if mode == "warm" and out["setup_s"] is not None:
            out["time_per_proj_incl_setup_s"] = tpp + out["setup_s"] / prob.K
        if chosen is None:
            out["note"] += "; target not met: reporting the best accuracy reached"
        emit(out)


# ---------------------------------------------------------------- reference
def kkt_report(prob, Y, LAM=None):
    """relative KKT residuals over the sequence (LAM: multipliers, K x m)."""
    pv = dv = sr = cp = 0.0
    for k in range(prob.K):
        y, x = Y[k], prob.X[k]
        r = prob.C @ y + prob.g
        scale = max(1.0, float(np.abs(prob.g).max()) if prob.m else 1.0,
                    float(np.abs(prob.C).max() * np.abs(y).max()) if prob.m else 1.0)
        pv = max(pv, float(max(0.0, -r.min())) / scale if prob.m else 0.0)
        if LAM is not None:
            lam = LAM[k]
            grad = prob.P @ (y - x)
            st = grad - prob.C.T @ lam
            sr = max(sr, float(np.abs(st).max()) / max(1.0, float(np.abs(prob.P @ x).max())))
            dv = max(dv, float(max(0.0, -lam.min())) / max(1.0, float(np.abs(lam).max())))
            cp = max(cp, float(np.abs(lam * r).max()) / (scale * max(1.0, float(np.abs(lam).max()))))
    d = {"prim_viol": pv}
    if LAM is not None:
        d.update(dual_viol=dv, stationarity=sr, complementarity=cp)
    return d


class Polisher:
    """Exact-ish projection given an active-set guess: method of multipliers on
    min 1/2||y-x||_P^2 s.t. C_A y + g_A = 0 (y is unique even if C_A is rank
    deficient), followed by active-set correction rounds."""

    def __init__(self, prob, rho_rel=1e4):
        self.prob = prob
        self.pmax = float(np.abs(prob.P.diagonal()).max())
        self.rho = rho_rel * self.pmax
        self.fact = {}

    def _factor(self, A_idx):
        key = A_idx.tobytes()
        if key not in self.fact:
            if len(self.fact) > 4:
                self.fact.clear()
            CA = self.prob.C[A_idx]
            M = (self.prob.P + self.rho * (CA.T @ CA)).tocsc()
            self.fact[key] = (CA, spla.splu(M, permc_spec="MMD_AT_PLUS_A"))
        return self.fact[key]

    def polish(self, x, lam0, active, max_rounds=8, max_iter=200):
        prob = self.prob
        act = active.copy()
        lam = np.where(act, np.maximum(lam0, 0.0), 0.0)
        scale = max(1.0, float(np.abs(prob.g).max()) if prob.m else 1.0)
        Px = prob.P @ x
        y = x.copy()
        for rnd in range(max_rounds):
            A_idx = np.flatnonzero(act)
            if len(A_idx) == 0:
                y = x.copy()
                lam = np.zeros(prob.m)
            else:
                CA, lu = self._factor(A_idx)
                gA = prob.g[A_idx]
                l = lam[A_idx]
                for it in range(max_iter):
                    y = lu.solve(Px + CA.T @ (l - self.rho * gA))
                    r = CA @ y + gA
                    l = l - self.rho * r
                    tol = 1e-15 * max(scale, float(np.abs(CA).max() * np.abs(y).max()))
                    if np.abs(r).max() <= tol:
                        break
                lam = np.zeros(prob.m)
                lam[A_idx] = l
            res = prob.C @ y + prob.g
            tol = 1e-13 * max(scale, float(np.abs(prob.C).max() * np.abs(y).max())) if prob.m else 0
            lt = 1e-13 * max(1.0, float(np.abs(lam).max()))
            add = (~act) & (res < -tol)
            drop = act & (lam < -lt)
            if not add.any() and not drop.any():
                return y, lam, True, rnd
            act = (act | add) & ~drop
        return y, lam, False, max_rounds


def reference_piqp(prob, log_prefix=""):
    import piqp
    Y = np.empty_like(prob.X)
    LAM = np.zeros((prob.K, prob.m))
    Yraw = np.empty_like(prob.X)
    s = piqp.SparseSolver()
    used = []
    pol = Polisher(prob)
    polished_ok = 0
    for k in range(prob.K):
        for eps in (1e-12, 1e-11, 1e-10, 1e-9):
            s = piqp.SparseSolver()
            st = s.settings
            st.eps_abs = st.eps_rel = eps
            st.eps_duality_gap_abs = st.eps_duality_gap_rel = eps
            st.max_iter = 100
            st.verbose = False
            s.setup(prob.Ptriu, prob.Q[k], None, None, prob.C, -prob.g, None)
            status = s.solve()
            if str(status).endswith("PIQP_SOLVED"):
                break
        used.append(eps)
        r = s.result
        x = np.array(r.x, copy=True)
        z = np.array(r.z_l, copy=True)
        sl = np.array(r.s_l, copy=True)
        Yraw[k] = x
        act = z > sl
        y, lam, ok, rounds = pol.polish(prob.X[k], z, act)
        if ok:
            Y[k], LAM[k] = y, lam
            polished_ok += 1
        else:
            Y[k], LAM[k] = x, z
            log(f"{log_prefix}ref polish failed at k={k}; keeping raw PIQP")
    diff = max(prob.pnorm(Y[k] - Yraw[k]) / max(prob.pnorm(Y[k]), prob.xnorm[k], TINY)
               for k in range(prob.K))
    meth = (f"piqp {pkg_version('piqp')} eps={max(used):g}"
            + (f" (looser on {sum(e > 1e-12 for e in used)} pts)" if max(used) > 1e-12 else "")
            + f" + active-set polish ({polished_ok}/{prob.K} points polished)")
    return Y, LAM, meth, diff


def reference_pdas(prob, log_prefix=""):
    """Solver-free reference for large problems: primal-dual active-set
    iterations (Polisher) started from the rows violated at x_k; each
    equality-constrained QP is solved by the method of multipliers with one
    sparse LU.  Converges in 2-3 rounds on the crowd problems; certified by
    the KKT residuals.  Points where it does not converge fall back to a PIQP
    (eps 1e-9) active-set guess."""
    Y = np.empty_like(prob.X)
    LAM = np.zeros((prob.K, prob.m))
    pol = Polisher(prob)
    rounds_used, fallback = [], 0
    for k in range(prob.K):
        x = prob.X[k]
        act = (prob.C @ x + prob.g) < 0
        y, lam, ok, rounds = pol.polish(x, np.zeros(prob.m), act, max_rounds=15)
        if not ok:
            import piqp
            s = piqp.SparseSolver()
            st = s.settings
            st.eps_abs = st.eps_duality_gap_abs = 1e-9
            st.eps_rel = st.eps_duality_gap_rel = 0.0
            st.max_iter = 100
            s.setup(prob.Ptriu, prob.Q[k], None, None, prob.C, -prob.g, None)
            s.solve()
            z, sl = np.array(s.result.z_l), np.array(s.result.s_l)
            y, lam, ok, rounds = pol.polish(x, z, z > sl, max_rounds=50)
            fallback += 1
            if not ok:
                log(f"{log_prefix}PDAS reference did not converge at k={k}")
        Y[k], LAM[k] = y, lam
        rounds_used.append(rounds)
    meth = (f"primal-dual active set from the rows violated at x_k + exact KKT solves "
            f"(rounds max {max(rounds_used)}, PIQP-guess fallback on {fallback} points)")
    return Y, LAM, meth


def reference_daqp(prob):
    import daqp
    H, A = prob.P.toarray(), prob.C.toarray()
    Y = np.empty_like(prob.X)
    LAM = np.zeros((prob.K, prob.m))
    for k in range(prob.K):
        x, f, ef, info = daqp.solve(H, prob.Q[k], A, np.full(prob.m, BIG), -prob.g,
                                    np.zeros(prob.m, dtype=np.int32), primal_tol=1e-12,
                                    iter_limit=100000)
        Y[k] = x
        LAM[k] = -np.asarray(info["lam"])   # daqp: lam<0 on active lower bounds
    return Y, LAM, f"daqp {pkg_version('daqp')} primal_tol=1e-12"


def get_reference(prob, args):
    info = {}
    t0 = time.perf_counter()
    if prob.ref_file is not None and not args.recompute_ref:
        ref = prob.ref_file
        info["ref_method"] = "ref.txt"
        info["ref_kkt"] = kkt_report(prob, ref)
        return ref, info
    ref = None
    LAM = None
    how = args.ref_method
    if how == "auto":
        # PIQP (the brief's choice) where it is affordable: on crowd_100000
        # (dim+m = 5e5) one PIQP KKT factorisation takes ~10 s and eps 1e-12
        # never converges; ProxQP took > 10 min for one solve there.
        how = "piqp" if prob.dim + prob.m <= args.ref_piqp_max_size else "pdas"
    if how == "piqp":
        try:
            ref, LAM, meth, diff = reference_piqp(prob, f"[{prob.name}] ")
            info["ref_method"] = meth
            info["ref_polish_change_rel"] = diff
        except ImportError:
            how = "pdas"
    if how == "pdas":
        ref, LAM, meth = reference_pdas(prob, f"[{prob.name}] ")
        info["ref_method"] = meth
    if ref is None and how == "daqp" and prob.dim <= args.daqp_max_dim:
        try:
            ref, LAM, meth = reference_daqp(prob)
            info["ref_method"] = meth
        except ImportError:
            pass
    if ref is None:
        raise SystemExit("no solver available to compute the reference")
    info["ref_kkt"] = kkt_report(prob, ref, LAM)
    info["ref_time_s"] = time.perf_counter() - t0
    if prob.ref_file is not None:
        info["ref_vs_ref_txt_rel"] = prob.accuracy(ref, prob.ref_file)[0]
        info["ref_method"] += " (recomputed; ref.txt ignored)"
    log(f"[{prob.name}] reference: {info}")
    return ref, info


# ---------------------------------------------------------------- main
def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("problems", nargs="+")
    ap.add_argument("--solvers", default="osqp,daqp,proxqp,piqp")
    ap.add_argument("--acc", type=float, default=1e-8)
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--max-seconds", type=float, default=300.0,
                    help="budget per (problem, solver); warm gets up to half when both modes run")
    ap.add_argument("--max-points", type=int, default=None, help="use only the first K points")
    ap.add_argument("--ladder", default="1e-7,1e-8,1e-9,1e-10,1e-11,1e-12,1e-13")
    ap.add_argument("--modes", default="warm,cold")
    ap.add_argument("--max-iter", type=int, default=200000, help="OSQP/ProxQP max_iter")
    ap.add_argument("--piqp-max-iter", type=int, default=100,
                    help="PIQP max_iter (an IPM needing more is stalled at roundoff)")
    ap.add_argument("--daqp-max-dim", type=int, default=2000)
    ap.add_argument("--daqp-iter-limit", type=int, default=100000)
    ap.add_argument("--proxqp-backend", choices=["auto", "dense", "sparse"], default="auto")
    ap.add_argument("--grace-seconds", type=float, default=10.0,
                    help="a sequence still running this long after its deadline is killed")
    ap.add_argument("--fork", choices=["auto", "always", "never"], default="auto",
                    help="run each sequence in a forked child that is killed at the hard "
                         "deadline (needed for solvers without a time limit: ProxQP, PIQP). "
                         "auto = only when dim + m >= --fork-min-size: on tiny problems the "
                         "fresh child's copy-on-write page faults add ~1 us per solve")
    ap.add_argument("--fork-min-size", type=int, default=10000)
    ap.add_argument("--ref-method", choices=["auto", "piqp", "pdas", "daqp"], default="auto",
                    help="reference when ref.txt is absent: piqp = PIQP eps 1e-12 + active-set "
                         "polish; pdas = solver-free primal-dual active set + KKT solves; "
                         "auto = piqp if dim+m <= --ref-piqp-max-size else pdas")
    ap.add_argument("--ref-piqp-max-size", type=int, default=100000)
    ap.add_argument("--save-ref", action="store_true",
                    help="write a computed reference as ref.txt in the problem directory "
                         "(so that other tools are measured against the same one)")
    ap.add_argument("--recompute-ref", action="store_true",
                    help="ignore ref.txt, compute the reference (reports the difference to ref.txt)")
    ap.add_argument("--memory-points", type=int, default=2,
                    help="points of the sequence run again in a fresh process for its memory")
    ap.add_argument("--memory-seconds", type=float, default=120.0,
                    help="time limit of that run (solvers with a time limit get it; "
                         "the others are killed a minute after it)")
    ap.add_argument("--heapcount", metavar="SO",
                    help="preload this heapcount shim (build/bench/libcatchup_heapcount.so) into "
                         "the memory probe: solver_heap_bytes, the most heap bytes held at once")
    ap.add_argument("--memory-only", metavar="PEERS_JSONL",
                    help="measure only the memory of the sequences an earlier run reported "
                         "(the problem directories are the positional arguments)")
    args = ap.parse_args()
    protect_stdout()
    if args.memory_only:
        args.ladder = []
        memory_only(args.memory_only, args)
        return
    args.ladder = [float(e) for e in args.ladder.split(",")]
    args.modes = args.modes.split(",")

    solvers = []
    for nm in args.solvers.split(","):
        nm = nm.strip()
        try:
            solvers.append(SOLVERS[nm](args))
        except ImportError as e:
            log(f"solver {nm} not available: {e}")
            emit({"solver": nm, "skipped": True, "note": f"import failed: {e}"})
        except KeyError:
            sys.exit(f"unknown solver {nm}; known: {','.join(SOLVERS)}")

    for path in args.problems:
        t0 = time.perf_counter()
        prob = Problem(path, args.max_points)
        log(f"[{prob.name}] loaded dim={prob.dim} m={prob.m} nnz(C)={prob.C.nnz} K={prob.K} "
            f"(file {prob.K_file}) diagP={prob.is_diag_P} in {time.perf_counter() - t0:.1f}s")
        ref, ref_info = get_reference(prob, args)
        if args.save_ref and prob.ref_file is None and prob.K == prob.K_file:
            np.savetxt(os.path.join(path, "ref.txt"), ref, fmt="%.17g")
            log(f"[{prob.name}] saved the reference as ref.txt")
        for s in solvers:
            bench(prob, s, ref, ref_info, args)


if __name__ == "__main__":
    main()
