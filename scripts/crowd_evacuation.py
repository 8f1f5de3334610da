#!/usr/bin/env python3
"""Evacuation times of catchup and cromosim side by side (scripts/crowd-evacuation).

    crowd_evacuation.py OUTDIR [--tol T] SEED...

reads OUTDIR/room-SEED.h5 (catchup-run: /crowd/exit_time) and
OUTDIR/cromosim-SEED.json (scripts/crowd_cromosim.py: exit_time) for each
seed. Per seed: both evacuation times (the last agent out), their relative
difference, and the agents-left curves' largest gap in time (the k-th exit
of one against the k-th of the other, over all k). Over the seeds: the mean
and standard deviation of the relative difference, against the spread of
catchup's own evacuation time from seed to seed. Writes
OUTDIR/evacuation.{json,md,png}; exits 1 if a run left agents inside or the
mean relative difference exceeds T (default 0.05).
"""
import argparse
import json
import sys

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out")
    ap.add_argument("seeds", nargs="+", type=int)
    ap.add_argument("--tol", type=float, default=0.05)
    a = ap.parse_args()
    rows, ok = [], True
    fig, ax = plt.subplots(figsize=(6, 4))
    for s in a.seeds:
        with h5py.File(f"{a.out}/room-{s}.h5", "r") as f:
            ec = np.sort(f["crowd/exit_time"][:])
            h = float(f.attrs["T"]) / int(f.attrs["n"])
        c = json.load(open(f"{a.out}/cromosim-{s}.json"))
        er = np.sort(np.array([np.nan if e is None else e for e in c["exit_time"]], dtype=float))
        if not (np.isfinite(ec).all() and np.isfinite(er).all()):
            print(f"seed {s}: agents left inside (catchup {np.isnan(ec).sum()}, cromosim {np.isnan(er).sum()})")
            ok = False
            continue
        rows.append({"seed": s, "agents": len(ec), "h": h, "catchup": float(ec[-1]), "cromosim": float(er[-1]),
                     "rel": float((er[-1] - ec[-1]) / ec[-1]), "curve_max": float(np.max(np.abs(er - ec))),
                     "curve_mean": float(np.mean(er - ec)), "half_catchup": float(ec[len(ec) // 2]),
                     "half_cromosim": float(er[len(er) // 2])})
        n = np.arange(len(ec), 0, -1)
        ax.step(ec, n - 1, "k-", where="post", lw=0.8, label="catchup" if s == a.seeds[0] else None)
        ax.step(er, n - 1, "r--", where="post", lw=0.8, label="cromosim" if s == a.seeds[0] else None)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("agents in the room")
    ax.set_title(f"evacuation, {len(rows)} seeds: catchup and cromosim")
    ax.legend()
    fig.savefig(f"{a.out}/evacuation.png", dpi=120, bbox_inches="tight")
    if not rows:
        sys.exit("crowd_evacuation: no seed evacuated")
    rel = np.array([r["rel"] for r in rows])
    tc = np.array([r["catchup"] for r in rows])
    summ = {"seeds": len(rows), "rel_mean": float(rel.mean()), "rel_std": float(rel.std(ddof=1)) if len(rel) > 1 else 0.0,
            "catchup_mean": float(tc.mean()), "catchup_std": float(tc.std(ddof=1)) if len(tc) > 1 else 0.0,
            "cromosim_mean": float(np.mean([r["cromosim"] for r in rows])), "tol": a.tol,
            "curve_mean": float(np.mean([r["curve_mean"] for r in rows])),
            "curve_max": float(np.max([r["curve_max"] for r in rows]))}
    json.dump({"rows": rows, "summary": summ}, open(f"{a.out}/evacuation.json", "w"), indent=1)
    with open(f"{a.out}/evacuation.md", "w") as md:
        md.write("| seed | agents | catchup evacuation | cromosim evacuation | difference | half out (catchup, cromosim) "
                 "| agents-left curves: largest gap, mean |\n|---:|---:|---:|---:|---:|---:|---:|\n")
        for r in rows:
            md.write(f"| {r['seed']} | {r['agents']} | {r['catchup']:.2f} s | {r['cromosim']:.2f} s | {100 * r['rel']:+.1f} % "
                     f"| {r['half_catchup']:.2f}, {r['half_cromosim']:.2f} s | {r['curve_max']:.2f} s, {r['curve_mean']:+.2f} s |\n")
        md.write(f"\nOver {summ['seeds']} seeds: cromosim's evacuation time is catchup's {100 * summ['rel_mean']:+.1f} % "
                 f"(standard deviation {100 * summ['rel_std']:.1f} %); catchup's own evacuation time varies from seed to "
                 f"seed by {summ['catchup_std']:.2f} s (standard deviation) around {summ['catchup_mean']:.2f} s. "
                 f"The time of the k-th exit differs by {summ['curve_mean']:+.2f} s on average over k and the seeds "
                 f"(cromosim minus catchup), by {summ['curve_max']:.2f} s at most.\n")
    print(open(f"{a.out}/evacuation.md").read())
    if abs(summ["rel_mean"]) > a.tol or not ok:
        print(f"crowd_evacuation: mean relative difference {summ['rel_mean']:+.3f} beyond {a.tol} or agents left inside")
        sys.exit(1)


if __name__ == "__main__":
    main()
