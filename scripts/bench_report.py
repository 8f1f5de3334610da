#!/usr/bin/env python3
"""Turn benchmark JSON lines into plots and BENCHMARKS.md.

    python scripts/bench_report.py OUTDIR
    python scripts/bench_report.py OUTDIR --projector-only   (only that section, in place;
                                    $CATCHUP_BENCH_NOTE is added to its first line)

Reads whatever is in OUTDIR: catchup_circuit.jsonl + siconos.jsonl (from
scripts/bench-vs-siconos), catchup_projector.jsonl + peers.jsonl (from
scripts/bench-projector) and sweep.md (the table of scripts/bench-sweep,
kept as docs/bench/sweep.md). Writes docs/bench/*.png and BENCHMARKS.md,
replacing its header and its sections in place (a section whose data are
missing keeps its earlier figures: the circuit's as they were, the
projector's marked as from an earlier run, the sweep's from docs/bench/; with
no earlier figures it says which command produces them). Everything else
stays as it is, where it is: sections written by hand, such as the general
process's, those other scripts generate between markers, such as
scripts/bench-vs-ngspice's, and notes written by hand under a generated
table between "<!-- BEGIN notes: NAME -->" and "<!-- END notes: NAME -->",
such as the reading of the sweep table. A rerun with no new data changes
only the header's revision and date.
"""
import datetime
import json
import math
import os
import platform
import re
import subprocess
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
LEVELS = [1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10]


def load(path):
    rows = []
    if os.path.exists(path):
        for line in open(path):
            line = line.strip()
            if line.startswith("{"):
                rows.append(json.loads(line))
    return rows


def machine():
    model = platform.processor() or "unknown CPU"
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    try:
        rev = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"],
                             capture_output=True, text=True).stdout.strip()
    except OSError:
        rev = "unknown"
    return f"{model}, {os.cpu_count()} cores, {platform.system()} {platform.release()}", rev


# ---- work-precision ---------------------------------------------------------------

def curves(rows, key):
    """config -> sorted list of (n, error, seconds)."""
    out = {}
    for r in rows:
        if r.get("err_max") is None or r.get("median_s") is None:
            continue
        out.setdefault(key(r), []).append((r["n"], r["err_max"], r["median_s"]))
    for k in out:
        out[k].sort()
    return out


def time_to_reach(curve, level):
    """Wall time to reach error <= level along one configuration's curve
    (log-log interpolation between measured n), or None if never reached."""
    pts = [(e, t) for (_, e, t) in curve if e > 0 and t > 0]
    for (e0, t0), (e1, t1) in zip(pts, pts[1:]):
        if e0 > level >= e1:
            if e1 == e0:
                return t1
            f = (math.log(level) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(t0) + f * (math.log(t1) - math.log(t0)))
    if pts and pts[0][0] <= level:
        return pts[0][1]
    return None


def fastest(cvs, level):
    best = None
    for cfg, c in cvs.items():
        t = time_to_reach(c, level)
        if t is not None and (best is None or t < best[0]):
            best = (t, cfg)
    return best


def merge_rounds(rows, key):
    """One row per configuration: scripts/bench-vs-siconos measures each in rounds
    (tools interleaved against the machine's drift); keep the median over the
    rounds of each round's median, and how many rounds there were."""
    groups = {}
    for r in rows:
        groups.setdefault(key(r), []).append(r)
    out = []
    for g in groups.values():
        m = dict(g[0])
        if len(g) > 1:
            med = sorted(r["median_s"] for r in g)
            k = len(med)
            m["median_s"] = med[k // 2] if k % 2 else 0.5 * (med[k // 2 - 1] + med[k // 2])
            if "per_step_us" in m:
                m["per_step_us"] = m["median_s"] / m["n"] * 1e6
            if "ns_per_step" in m:
                m["ns_per_step"] = m["median_s"] / m["n"] * 1e9
            # the trajectory is the same in every round: so must be its error
            errs = [r["err_max"] for r in g]
            assert max(errs) - min(errs) <= 1e-12 * max(1.0, max(errs)), ("rounds disagree", key(g[0]), errs)
        m["rounds"] = len(g)
        out.append(m)
    return out


def adaptive_error(r):
    """The adaptive rows' error: against the adaptive reference (tol 1e-13); where
    that is this very computation (case 2: no event between breakpoints, the run
    is exact to rounding) against the Richardson limit, i.e. that limit's error."""
    return r["err_max"] if r["err_max"] > 0 else r["err_richardson"]


def adaptive_curve(rows):
    """tol from loose to tight, as (index, error, seconds)."""
    rows = sorted(rows, key=lambda r: -r["tol"])
    return [(k, adaptive_error(r), r["median_s"]) for k, r in enumerate(rows)]


def adaptive_table(rows, case, lines):
    rows = sorted((r for r in rows if r["case"] == case), key=lambda r: -r["tol"])
    if not rows:
        return
    lines.append(f"The adaptive scheme on case {case}, tol by tol (`catchup-bench adaptive`; error "
                 f"against `ref_case{case}_adaptive.csv`" + (", or where that is exact, against the "
                 "Richardson limit" if any(r["err_max"] == 0 for r in rows) else "") + "):\n")
    lines.append("| tol | time loop | steps | events | error | its estimate | estimate / error |")
    lines.append("|---:|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        e = adaptive_error(r)
        exact = r["err_max"] == 0
        # Where the run is exact, the error against Richardson is that limit's own error: no
        # ratio to state.
        lines.append(f"| {r['tol']:.0e} | {r['median_s'] * 1e6:.0f} µs | {r['n']} | {r['events']} | "
                     f"{e:.2e}{' (Richardson)' if exact else ''} | {r['err_est']:.2e} | "
                     f"{'—' if exact else format(r['err_est'] / e, '.2f')} |")
    lines.append("")


def circuit_section(outdir, lines):
    cat = merge_rounds(load(os.path.join(outdir, "catchup_circuit.jsonl")),
                       lambda r: (r["case"], r["config"], r["n"]))
    ada = merge_rounds(load(os.path.join(outdir, "catchup_adaptive.jsonl")),
                       lambda r: (r["case"], r["tol"]))
    sic = merge_rounds(load(os.path.join(outdir, "siconos.jsonl")),
                       lambda r: (r["case"], r.get("driver", "python"), r["theta"], r["solver"], r["n"]))
    if not cat or not sic:
        lines.append("_Not run here yet: `bash scripts/bench-vs-siconos`._\n")
        return False
    os.makedirs(os.path.join(ROOT, "docs", "bench"), exist_ok=True)
    # Rows without a "driver" field predate the C++ driver: they are the Python one's.
    sic_cpp = [r for r in sic if r.get("driver") == "c++" and r.get("theta", 0) > 0]
    sic_py = [r for r in sic if r.get("driver", "python") == "python" and r.get("theta", 0) > 0]
    if sic_cpp:
        sic_main, sic_label = sic_cpp, "Siconos C++"
    else:
        lines.append("_No rows from the Siconos C++ driver in this run: the Siconos figures below "
                     "are its Python driver's, which adds Python's cost to every step._\n")
        sic_main, sic_label = sic_py, "Siconos (Python)"
    for case in (1, 2):
        cc = curves([r for r in cat if r["case"] == case], lambda r: r["config"])
        if any(r["case"] == case for r in ada):
            cc["adaptive"] = adaptive_curve([r for r in ada if r["case"] == case])
        sc = curves([r for r in sic_main if r["case"] == case],
                    lambda r: f"theta{r['theta']:g}/{r['solver']}")
        fig, ax = plt.subplots(figsize=(9, 5))
        for cfg, c in sorted(cc.items()):
            style, lw = ("D-", 2.5) if cfg == "adaptive" else ("o-", 1.5)
            label = "catchup adaptive (tol 1e-3 .. 1e-10)" if cfg == "adaptive" else f"catchup {cfg}"
            ax.loglog([p[1] for p in c], [p[2] for p in c], style, lw=lw, label=label)
        for cfg, c in sorted(sc.items()):
            ax.loglog([p[1] for p in c], [p[2] for p in c], "s--", label=f"{sic_label} {cfg}")
        ax.set_xlabel("max-norm error against the reference limit")
        ax.set_ylabel("wall time of the time loop [s]")
        ax.set_title(f"paper circuit, case {case}: run time against error")
        ax.invert_xaxis()
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1))
        fig.tight_layout()
        png = os.path.join("docs", "bench", f"work_precision_case{case}.png")
        fig.savefig(os.path.join(ROOT, png), dpi=110)
        plt.close(fig)
        lines.append(f"### Case {case}\n")
        lines.append(f"![work-precision, case {case}]({png})\n")
        lines.append(f"| error level | catchup fastest | {sic_label} fastest | ratio |")
        lines.append("|---:|---|---|---:|")
        for lev in LEVELS:
            a, b = fastest(cc, lev), fastest(sc, lev)
            fa = f"{a[0]:.3g} s ({a[1]})" if a else "not reached"
            fb = f"{b[0]:.3g} s ({b[1]})" if b else "not reached (n <= 10^6)"
            ratio = f"{b[0] / a[0]:.0f}x" if a and b else "—"
            lines.append(f"| {lev:.0e} | {fa} | {fb} | {ratio} |")
        lines.append("")
        adaptive_table(ada, case, lines)
        lines.append("Per step at equal n (fastest configuration of each tool; "
                     f"{sic_label} is its time loop with no Python in it):\n")
        lines.append(f"| n | catchup ns/step | {sic_label} µs/step | ratio |")
        lines.append("|---:|---:|---:|---:|")
        ns = sorted({r["n"] for r in sic_main if r["case"] == case})
        for n in ns:
            a = [r["median_s"] / n for r in cat if r["case"] == case and r["n"] == n]
            b = [r["median_s"] / n for r in sic_main if r["case"] == case and r["n"] == n]
            if a and b:
                lines.append(f"| {n:.0e} | {min(a) * 1e9:.0f} | {min(b) * 1e6:.2f} | {min(b) / min(a):.0f}x |")
        lines.append("")
        if sic_cpp and sic_py:
            # the same kernel and model through python3-siconos: what Python adds per step,
            # and that both drivers compute the same trajectory
            pairs = []
            for q in sorted((r for r in sic_py if r["case"] == case), key=lambda r: r["n"]):
                c = [r for r in sic_cpp if r["case"] == case and r["n"] == q["n"]
                     and r["theta"] == q["theta"] and r["solver"] == q["solver"]]
                if c:
                    pairs.append((q, c[0]))
            if pairs:
                q0 = pairs[0][0]
                lines.append(f"For reference, the same Siconos model through its Python driver "
                             f"(θ = {q0['theta']:g}, {q0['solver']}; µs per step, C++ beside it):\n")
                lines.append("| n | Python | C++ | Python / C++ | errors differ by |")
                lines.append("|---:|---:|---:|---:|---:|")
                for q, c in pairs:
                    lines.append(f"| {q['n']:.0e} | {q['per_step_us']:.2f} | {c['per_step_us']:.2f} | "
                                 f"{q['per_step_us'] / c['per_step_us']:.1f}x | "
                                 f"{abs(q['err_max'] - c['err_max']):.1e} |")
                lines.append("")
    warned = [r for r in cat if r.get("status", "CUP_OK") != "CUP_OK"]
    if warned:
        lines.append("catchup runs with the default tolerances ε_n = n^-2.1, η_n = n^-1.05 that did "
                     "not end `CUP_OK` (their errors are measured like the others and used above):\n")
        lines.append("| case | configuration | n | status | ε_n | largest certified ε | error |")
        lines.append("|---:|---|---:|---|---:|---:|---:|")
        for r in warned:
            lines.append(f"| {r['case']} | {r['config']} | {r['n']:.0e} | `{r['status']}` | "
                         f"{r['n'] ** -2.1:.1e} | {r.get('max_eps_cert', float('nan')):.1e} | "
                         f"{r['err_max']:.3e} |")
        lines.append("\nAt n = 10^7, ε_n is about 2e-15, below what double precision can certify "
                     "on the steps where case 2's set jumps (the impulse is O(1) there and the "
                     "certified gap is a few ulps of the state times it): the run says so rather than "
                     "claim it.\n")
    cross = [r for r in sic if r.get("theta", 1) == 0]
    if cross:
        lines.append("Cross-check: Siconos with θ = 0 is the explicit catching-up step; its error "
                     "against the reference equals catchup's `explicit/auto` at n = 10^3 "
                     "(catchup-bench reports 7 digits):\n")
        for r in sorted(cross, key=lambda r: (r["case"], r.get("driver", "python"))):
            c = [q for q in cat if q["case"] == r["case"] and q["n"] == r["n"] and q["config"] == "explicit/auto"]
            if c:
                drv = "C++" if r.get("driver") == "c++" else "Python"
                lines.append(f"- case {r['case']}: Siconos ({drv} driver) θ = 0 {r['err_max']:.12e}, "
                             f"catchup {c[0]['err_max']:.6e}")
        lines.append("")
    return True


# ---- projector -----------------------------------------------------------------------

def earlier_projector(old):
    """The projector section's results in the BENCHMARKS.md being replaced, with a note naming
    the run they came from (a run of bench-vs-siconos alone must not drop them); None when it
    has none."""
    head = "## The projector against QP solvers"
    if head not in old:
        return None
    body = old.split(head, 1)[1].split("\n## ", 1)[0]
    for mark in ("\n_From an earlier run", "\nMeasured on "):   # it says which run it is from
        at = body.find(mark)
        if at >= 0:
            return body[at + 1:].rstrip("\n") + "\n"
    at = body.find("\n| problem |")
    if at < 0:
        return None
    body = body[at + 1:].rstrip("\n")
    rev = next((l.split(": ", 1)[1] for l in old.splitlines() if l.startswith("- catchup revision: ")), "?")
    when = next((l.split(": ", 1)[1] for l in old.splitlines() if l.startswith("- Generated: ")), "?")
    return (f"_From an earlier run (catchup revision {rev}, {when}, same machine); "
            f"`bash scripts/bench-projector` was not rerun with this one._\n\n" + body + "\n")


def splice(old, lines):
    """The old BENCHMARKS.md with its header and the sections in `lines` replaced in place,
    each from its heading to the next level-2 heading or marked block ("<!-- BEGIN ..."):
    hand-written sections, other scripts' marked blocks and notes kept in a marked block
    under a generated table ("<!-- BEGIN notes: ...") stay verbatim, in their order."""
    parts = re.split(r"^(?=## )", "\n".join(lines), flags=re.M)
    first = re.search(r"^## ", old, re.M)
    if not first:
        return "".join(parts)
    text = parts[0] + old[first.start():]
    boundary = re.compile(r"^(## |<!-- BEGIN )", re.M)
    for sec in parts[1:]:
        m = re.search("^" + re.escape(sec.split("\n", 1)[0]) + "$", text, re.M)
        if not m:
            text = text.rstrip("\n") + "\n\n" + sec
            continue
        end = boundary.search(text, m.end())
        text = text[:m.start()] + sec.rstrip("\n") + "\n\n" + (text[end.start():] if end else "")
    return text


def peer_cell(p):
    """one peer's figure: its time at 1e-8, or how close it came"""
    if p is None:
        return "not run"
    if p.get("skipped"):
        return "skipped"
    if p.get("met"):
        return f"{p['time_per_proj_s']:.3g} s"
    e = p.get("rel_err")
    return f"not reached (best {e:.0e})" if isinstance(e, (int, float)) else "not reached"


def mb(kb):
    return f"{kb / 1024:.0f} MB" if kb >= 10240 else f"{kb / 1024:.1f} MB"


def heap(b):
    """bytes in kB below 1 MB (the circuit's sets hold a few kB), else in MB"""
    if b < 1 << 20:
        return f"{b / 1024:.1f} kB" if b < 10240 else f"{b / 1024:.0f} kB"
    return f"{b / 1048576:.1f} MB" if b < 10 << 20 else f"{b / 1048576:.0f} MB"


def peer_row(peers, r, names, cell, key=None, missing="—"):
    """one cell per peer name for catchup's row r: cell(record), or `missing`
    when that peer has no record for the row (or none with `key`)"""
    cells = []
    for n in names:
        q = [p for p in peers if p["problem"] == r["problem"] and p.get("mode") == r["mode"]
             and p["solver"] == n and (key is None or p.get(key) is not None)]
        cells.append(cell(q[0]) if q else missing)
    return " | ".join(cells)


def peer_table(lines, auto, peers, names, own, cell, **kw):
    """A table of catchup's rows (auto) against each peer in names, then a blank
    line: catchup's own columns first (own: (heading, text of a row) pairs), then
    peer_row's cell for each peer (kw: its key and missing)."""
    lines.append("| problem | mode | " + "".join(h + " | " for h, _ in own) + " | ".join(names) + " |")
    lines.append("|---|---|" + "---:|" * (len(own) + len(names)))
    for r in auto:
        mine = "".join(text(r) + " | " for _, text in own)
        lines.append(f"| {r['problem']} | {r['mode']} | {mine}{peer_row(peers, r, names, cell, **kw)} |")
    lines.append("")


def certified_bounds(r):
    """The largest certified eps/S^2 and eta/S of a row; JSON has no inf, so a
    bound some point never certified is null: said in words."""
    if "max_eps_cert_rel" not in r:
        return "—"
    return ", ".join("not certified" if r[k] is None else f"{r[k]:.1e}"
                     for k in ("max_eps_cert_rel", "max_eta_cert_rel"))


def projector_section(outdir, lines, old=""):
    cat = load(os.path.join(outdir, "catchup_projector.jsonl"))
    peers = [p for p in load(os.path.join(outdir, "peers.jsonl")) if p.get("problem")]
    if not cat:
        kept = earlier_projector(old)
        lines.append(kept if kept else "_Not run here yet: `bash scripts/bench-projector`._\n")
        return
    auto = [r for r in cat if r.get("solver") == "catchup-auto"]
    lines.append("| problem | mode | catchup auto | certified | largest ε/S², η/S certified | its error "
                 "| fastest peer at 1e-8 | ratio |")
    lines.append("|---|---|---:|---:|---:|---:|---|---:|")
    for r in auto:
        prob, mode = r["problem"], r["mode"]
        met = [p for p in peers if p["problem"] == prob and p.get("mode") == mode and p.get("met")]
        best = min(met, key=lambda p: p["time_per_proj_s"]) if met else None
        t = r["median_s_per_projection"]
        peer = (f"{best['solver']} {best['time_per_proj_s']:.3g} s (err {best['rel_err']:.1e})"
                if best else "none reached 1e-8" if peers else "not run")
        ratio = f"{best['time_per_proj_s'] / t:.1f}x" if best else "—"
        err = r.get("max_rel_err")
        err = -1 if err is None else err          # null: no reference, or never certified
        cert = certified_bounds(r)
        lines.append(f"| {prob} | {mode} | {t:.3g} s | {r['certified']}/{r['K']} | {cert} | "
                     f"{err:.1e} | {peer} | {ratio} |" if err >= 0 else
                     f"| {prob} | {mode} | {t:.3g} s | {r['certified']}/{r['K']} | {cert} | — "
                     f"| {peer} | {ratio} |")
    lines.append("")
    names = [n for n in ("osqp", "daqp", "proxqp", "piqp") if any(p["solver"] == n for p in peers)]
    if names:
        lines.append("Every peer, at the loosest tolerance that reached 1e-8 (else the best error it "
                     "reached within its budget of the run):\n")
        peer_table(lines, auto, peers, names, [], peer_cell, missing="not run")
        lines.append("Peak memory, each (problem, solver, mode) in its own process: the process's "
                     "peak resident set less its size before the solver's set-up (the problem data "
                     "and, for the peers, the Python interpreter), i.e. the solver's own memory; "
                     "catchup's set-up (polyset and projector) beside it:\n")
        own = [("catchup set-up", lambda r: f"{r.get('setup_s', 0) + r.get('polyset_setup_s', 0):.3g} s"),
               ("catchup", lambda r: mb(r["solver_rss_kb"]) if "solver_rss_kb" in r else "—")]
        peer_table(lines, auto, peers, names, own, key="solver_rss_kb",
                   cell=lambda p: mb(p["solver_rss_kb"]) + ("" if p.get("met") else " (not at 1e-8)"))
        if any(r.get("solver_heap_bytes") is not None for r in auto):
            lines.append("Heap held at most, bytes by the heapcount shim (`bench/heap.c`, preloaded "
                         "into both harnesses): the most bytes malloc held at once during the run above "
                         "what it held before the set-up, resident pages being too coarse for a set of "
                         "a few rows; the peers' include what their Python wrappers allocate through "
                         "malloc (numpy's buffers), not Python's own small objects:\n")
            own = [("catchup", lambda r: heap(r["solver_heap_bytes"]) if r.get("solver_heap_bytes") is not None
                    else "—")]
            peer_table(lines, auto, peers, names, own, key="solver_heap_bytes",
                       cell=lambda p: heap(p["solver_heap_bytes"]))
    others = [r for r in cat if r.get("solver") in ("catchup-pg", "catchup-fista")]
    if others:
        lines.append("catchup's first-order methods on the small sets:\n")
        lines.append("| problem | method | mode | per projection | iterations | certified "
                     "| largest ε/S², η/S certified | its error |")
        lines.append("|---|---|---|---:|---:|---:|---:|---:|")
        for r in others:
            err = r.get("max_rel_err")
            lines.append(f"| {r['problem']} | {r['solver'][8:]} | {r['mode']} | "
                         f"{r['median_s_per_projection']:.3g} s | {r['iterations_mean']:.1f} | "
                         f"{r['certified']}/{r['K']} | {certified_bounds(r)} | "
                         + ("—" if err is None or err < 0 else f"{err:.1e}") + " |")
        lines.append("")
    vers = sorted({f"{p['solver']} {p.get('version', '?')}" for p in peers if p.get("version")})
    if vers:
        lines.append("Peers (pip, Python wrappers): " + ", ".join(vers) + ".\n")


PROJECTOR_INTRO = (
    "Command: `bash scripts/bench-projector` (OSQP, DAQP, ProxQP, PIQP through their "
    "Python wrappers, each tightened until its answers reach 1e-8 relative error in the "
    "P-norm against the reference; catchup's `auto` method certifies (ε, η) = "
    "(1e-12·S², 1e-8·S), S the scale of the point and the offset, and its certified bounds "
    "and measured error are shown). Times per projection: `cold` without warm start (the "
    "peers' cold times include their set-up for each point, catchup's do not: its set-up "
    "for the set is in the memory table), `warm` along a sequence of slowly drifting points.")


def replace_projector(outdir, note):
    """--projector-only: rewrite the projector section of BENCHMARKS.md in place
    (everything from its heading to the next level-2 heading), the rest kept."""
    path = os.path.join(ROOT, "BENCHMARKS.md")
    text = open(path).read()
    head = "## The projector against QP solvers"
    a = text.index(head)
    b = text.find("\n## ", a + len(head))
    desc, rev = machine()
    lines = [head, "", PROJECTOR_INTRO, "",
             f"Measured on {desc}, catchup revision {rev}, "
             f"{datetime.datetime.now().strftime('%Y-%m-%d %H:%M')}." + (f" {note}" if note else ""), ""]
    projector_section(outdir, lines)
    text = text[:a] + "\n".join(lines) + ("\n" + text[b:] if b >= 0 else "")
    with open(path, "w") as f:
        f.write(text if text.endswith("\n") else text + "\n")
    print(f"bench_report: rewrote the projector section of BENCHMARKS.md from {outdir}", file=sys.stderr)


def sweep_section(outdir, lines, old=""):
    """scripts/bench-sweep's table: from OUTDIR when it has one, else the last one kept. The
    reading of it written under it by hand, in a marked block, stays (splice)."""
    kept = os.path.join(ROOT, "docs", "bench", "sweep.md")
    fresh = os.path.join(outdir, "sweep.md")
    if os.path.exists(fresh):
        if "<!-- BEGIN notes: sweep" in old:
            print("bench_report: new sweep figures: the notes under their table in BENCHMARKS.md "
                  "describe the previous run; read them again", file=sys.stderr)
        with open(fresh) as src, open(kept, "w") as dst:
            dst.write(src.read())
    lines += ["## Sweeps of tiny tasks: `catchup-sweep` against task size", "",
              "Command: `bash scripts/bench-sweep build 3 1 3 5 > OUTDIR/sweep.md`, then this script; "
              "`BENCH_SWEEP_BASELINE=OTHER/apps/catchup-sweep` adds the rows of another build "
              "(`baseline`) side by side. Grids on the paper's case 1 with tasks of about 10 µs "
              "(5 x 10^4 of them), 100 µs (10^4), 1 ms (10^3) and 10 ms (200): four schemes, two "
              "projectors and five tolerance schedules spread each grid's task sizes by about 2x; "
              "every task stores its trajectory at 101 sample times. `spread` is 84 tasks of "
              "n = 10^3..10^6. Every grid runs at 1, 3 and 5 ranks, three times, interleaved with the "
              "other grids and builds; the table has the medians.", "",
              "- *parallel efficiency* is what `catchup-sweep` prints: the jobs' wall times over "
              "(workers x the wall time of the dispatch), the share of the workers' time spent in "
              "jobs. *by job CPU* uses the CPU time the workers spent on their batches instead.",
              "- *CPU in jobs* is that CPU time over the CPU time of all ranks during the dispatch "
              "(rank 0's and the workers' own: messages, waiting, writing the file), and *rank 0's "
              "CPU* is rank 0's part of the latter: what the sweep costs beyond its jobs, whatever "
              "else runs on the machine.",
              "- *speedup* is the 1-rank dispatch wall over this one (one rank computes and writes "
              "by itself, no MPI): at most 2 on 2 cores, whatever the number of ranks.",
              "- With 3 ranks on 2 cores, rank 0 mostly sleeps and the two workers have a core each. "
              "With 5 ranks the four workers share 2 cores: a job's wall time then includes the "
              "time its worker waits for a core, and the parallel efficiency says only that no "
              "worker waits for work (how the scheduler slices the jobs moves it too: with Open "
              "MPI's `mpi_yield_when_idle=0`, its workers no longer yield at each test inside a "
              "job, and on tasks of ~10 ms it read 0.90 instead of 0.98 while the sweep took 2.8 s "
              "instead of 3.6 s); the CPU shares and the speedup say what oversubscription costs.",
              "- This machine is shared with other sessions: wall times and the CPU time one "
              "process gets per second vary by 2-4x within minutes (the `by job CPU` column shows "
              "the share of its wall time a worker actually ran). The CPU shares hold best under "
              "that noise.", ""]
    if os.path.exists(kept):
        lines += [open(kept).read().strip(), ""]
    else:
        lines += ["(no figures yet: run the command above)", ""]


CIRCUIT_HEAD = "## Run time against error: catchup and Siconos on the paper's circuit"


def main():
    if "--projector-only" in sys.argv:
        args = [a for a in sys.argv[1:] if a != "--projector-only"]
        note = os.environ.get("CATCHUP_BENCH_NOTE", "")
        replace_projector(args[0] if args else "bench-out", note)
        return
    outdir = sys.argv[1] if len(sys.argv) > 1 else "bench-out"
    desc, rev = machine()
    path = os.path.join(ROOT, "BENCHMARKS.md")
    old = open(path).read() if os.path.exists(path) else ""
    lines = ["# Benchmarks", "",
             "Figures, not tests: produced by the commands below on the machine named here, "
             "in one run, medians of repeated timings. This machine is shared and noisy "
             "(2 cores); ratios measured side by side are more reliable than absolute times.", "",
             f"- Machine: {desc}", f"- catchup revision: {rev}",
             f"- Generated: {datetime.datetime.now().strftime('%Y-%m-%d %H:%M')}", "",
             CIRCUIT_HEAD, "",
             "Command: `bash scripts/bench-vs-siconos` (Siconos 4.4 through its C++ time loop, "
             "`scripts/siconos_circuit.cpp` built against Debian's `libsiconos-kernel-dev`, with no "
             "Python in the loop; Moreau–Jean `EulerMoreauOSI` with θ = ½ and 1, LCP by Lemke and "
             "by enumeration; the input enters each step as its exact average; only the time loop "
             "is timed on both sides, one BLAS thread on both; the tools alternate n by n in five "
             "rounds of the same run, and each figure is the median over the rounds of each "
             "round's median). The same model through Siconos's Python driver "
             "(`scripts/siconos_circuit.py`, Debian's `python3-siconos`) is a cross-check: same "
             "trajectory, Python's cost per step added. Errors are max-norm against "
             "`tests/data/ref_case{1,2}_limit_richardson.csv` at t = j/1000 (Richardson limits, "
             "accurate to about 1e-10: `tests/data/README.md`); the adaptive scheme's "
             "(`catchup-bench adaptive`, tol = 1e-3 .. 1e-10, in the same rounds, its dense "
             "output at the same times) against `ref_case{1,2}_adaptive.csv` (its own run at "
             "tol = 1e-13, which agrees with the Richardson limits to their accuracy), since "
             "its errors go below theirs.", ""]
    if not circuit_section(outdir, lines) and CIRCUIT_HEAD in old:
        del lines[lines.index(CIRCUIT_HEAD):]    # no new figures: the old section stays as it is
    lines += ["## The projector against QP solvers", "", PROJECTOR_INTRO, ""]
    projector_section(outdir, lines, old)
    sweep_section(outdir, lines, old)
    text = splice(old, lines)
    with open(path, "w") as f:
        f.write(text.rstrip("\n") + "\n")
    print(f"bench_report: wrote BENCHMARKS.md and docs/bench/*.png from {outdir}", file=sys.stderr)


if __name__ == "__main__":
    main()
