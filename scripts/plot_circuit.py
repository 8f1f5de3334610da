#!/usr/bin/env python3
"""Draw a circuit's waveforms from a catchup-run file of a netlist.

    python3 scripts/plot_circuit.py OUT.h5 -o FIG.png [--title TEXT]
            [--signals v(out) i(D1) ...] [--ngspice FILE.txt]

Two panels sharing the time axis: the node voltages v(...) on top, the
branch currents i(...) below, from /signals in the order of its `names`
attribute (docs/netlist.md); a file without /signals is drawn from /x with
its `state_names`. A caption gives the scheme, n and the run's status.
--ngspice draws an ngspice `wrdata` file (time/value column pairs in the
same order as --signals) dashed over the curves, as scripts/bench-vs-ngspice
does. Needs h5py, matplotlib and numpy (scripts/setup --python)."""

import argparse
import sys


def text_attr(attrs, name, default=""):
    if name not in attrs:
        return default
    v = attrs[name]
    if hasattr(v, "shape") and v.shape == ():
        v = v[()]
    return v.decode("utf-8", "replace") if isinstance(v, bytes) else str(v)


def read(path, wanted):
    import h5py
    import numpy as np
    with h5py.File(path, "r") as f:
        n = f["t"].shape[0]
        series = []
        if "signals" in f:
            g = f["signals"]
            names = [s.decode() if isinstance(s, bytes) else str(s) for s in g.attrs.get("names", sorted(g))]
            n = min([n] + [g[s].shape[0] for s in names])
            series = [(s, g[s][:n]) for s in names]
        else:
            names = [s.strip() for s in text_attr(f.attrs, "state_names").split(",") if s.strip()]
            x = f["x"][:n, :]
            if len(names) != x.shape[1]:
                names = ["x%d" % (j + 1) for j in range(x.shape[1])]
            series = [(names[j], x[:, j]) for j in range(x.shape[1])]
        if wanted:
            have = {s.lower(): (s, v) for s, v in series}
            missing = [w for w in wanted if w.lower() not in have]
            if missing:
                raise ValueError("no signal %s in the file (it has %s)" % (", ".join(missing),
                                 ", ".join(s for s, _ in series)))
            series = [have[w.lower()] for w in wanted]
        caption = "%s, n = %s, %s" % (text_attr(f.attrs, "scheme", "?"), text_attr(f.attrs, "n", "?"),
                                      text_attr(f.attrs, "status_name", "?"))
        return np.asarray(f["t"][:n]), series, caption, text_attr(f.attrs, "scene_name", path)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("file")
    ap.add_argument("-o", "--output", required=True)
    ap.add_argument("--title")
    ap.add_argument("--signals", nargs="+")
    ap.add_argument("--ngspice", help="ngspice wrdata output for the same --signals, drawn dashed")
    a = ap.parse_args()
    try:
        import numpy as np
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError as e:
        sys.exit("plot_circuit: %s (scripts/setup --python makes .venv with h5py, matplotlib, numpy)" % e)
    try:
        t, series, caption, name = read(a.file, a.signals)
    except (OSError, KeyError, ValueError) as e:
        sys.exit("plot_circuit: %s: %s" % (a.file, e))
    spice = None
    if a.ngspice:
        d = np.loadtxt(a.ngspice, ndmin=2)
        spice = [(d[:, 2 * k], d[:, 2 * k + 1]) for k in range(d.shape[1] // 2)]
    scale, unit = (1e3, "ms") if t[-1] < 1 else (1, "s")
    volts = [(k, s, v) for k, (s, v) in enumerate(series) if not s.lower().startswith("i(")]
    amps = [(k, s, v) for k, (s, v) in enumerate(series) if s.lower().startswith("i(")]
    panels = [p for p in (volts, amps) if p]
    fig, axes = plt.subplots(len(panels), 1, sharex=True, figsize=(8, 2.6 * len(panels) + 0.6), squeeze=False)
    for ax, panel, ylabel in zip(axes[:, 0], panels, ["V" if volts else "A", "A"]):
        for k, s, v in panel:
            line, = ax.plot(t * scale, v, lw=1.2, label=s)
            if spice and k < len(spice):
                ax.plot(spice[k][0] * scale, spice[k][1], "--", lw=0.9, color=line.get_color(),
                        label=s + " (ngspice)")
        ax.set_ylabel(ylabel)
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right", fontsize=8, ncol=2)
    axes[-1, 0].set_xlabel("t (%s)" % unit)
    axes[0, 0].set_title(a.title or name)
    fig.text(0.01, 0.005, caption, fontsize=7, color="0.4")
    fig.tight_layout(rect=(0, 0.02, 1, 1))
    fig.savefig(a.output, dpi=120)
    print("plot_circuit: wrote %s" % a.output, file=sys.stderr)


if __name__ == "__main__":
    main()
