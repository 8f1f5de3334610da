#!/usr/bin/env python3
"""Draw the closed-loop buck of examples/c/buck_pi.c from its per-period CSV.

    build/examples/c/example_buck_pi examples/circuits/buck-pi.cir 5 periods.csv
    python3 scripts/plot_buck_pi.py periods.csv -o docs/figures/buck-pi.png [--vref 5 --vin 12]

Three panels sharing the time axis, one point a switching period: the mean
of v(out) over the controller's samples against Vref, the duty against the
lossless closed form Vref / Vin, and the mean inductor current (the load
steps from 1 A to 2 A at 2 ms). Needs matplotlib and numpy
(scripts/setup --python)."""

import argparse


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("csv")
    ap.add_argument("-o", "--output", required=True)
    ap.add_argument("--vref", type=float, default=5.0)
    ap.add_argument("--vin", type=float, default=12.0)
    a = ap.parse_args()
    import numpy as np
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    d = np.genfromtxt(a.csv, delimiter=",", names=True)
    t = d["t_end"] * 1e3
    fig, ax = plt.subplots(3, 1, sharex=True, figsize=(7, 6.5))
    ax[0].plot(t, d["vout_mean"], lw=1, label="mean v(out) over the period")
    ax[0].axhline(a.vref, color="k", ls="--", lw=0.8, label="Vref")
    ax[0].set_ylabel("V")
    ax[0].legend(loc="lower right", fontsize=8)
    ax[1].plot(t, d["duty"], lw=1, label="duty")
    ax[1].axhline(a.vref / a.vin, color="k", ls="--", lw=0.8, label="Vref / Vin")
    ax[1].legend(loc="lower right", fontsize=8)
    ax[2].plot(t, d["iL_mean"], lw=1, label="mean i(L1)")
    ax[2].set_ylabel("A")
    ax[2].set_xlabel("t [ms]")
    ax[2].legend(loc="lower right", fontsize=8)
    ax[0].set_title("ideal buck, digital PI every 10 ns, PWM at 100 kHz, 1 A load step at 2 ms", fontsize=9)
    fig.tight_layout()
    fig.savefig(a.output, dpi=110)


if __name__ == "__main__":
    main()
