#!/usr/bin/env python3
"""Draw the paper's figures from a catchup-run file.

    python3 scripts/plot_run.py OUT.h5 -o FIG.png [--title TEXT]

Two panels side by side: left x1 against t; right x2 (black) and x3 (blue)
against t, as in the paper's Figs. 2 and 3. For a state of another dimension
the right panel shows every component with a legend. A caption line gives n,
eps, eta and the scheme from the file's attributes.

Needs h5py, matplotlib and numpy (scripts/run-main puts them in .venv).
Long runs are drawn from a min/max envelope per pixel column, read in blocks,
so a 10^8-row file neither fills memory nor loses its spikes. A file whose
writer was killed is drawn from the rows it holds (min(len(t), len(x)))."""

import argparse
import os
import sys

try:
    import numpy as np
except ImportError:       # reported by main() with the install hint
    np = None

ENVELOPE_ABOVE = 20000   # rows; beyond this, draw a min/max envelope
BUCKETS = 4000           # envelope columns (a few per pixel at 150 dpi)
BLOCK_ROWS = 1 << 20     # rows read at a time


def text_attr(attrs, name, default=""):
    """An attribute as str, whether h5py gives str, bytes or a numpy scalar."""
    if name not in attrs:
        return default
    v = attrs[name]
    if isinstance(v, bytes):
        return v.decode("utf-8", "replace")
    if isinstance(v, np.ndarray) and v.shape == ():
        v = v[()]
    return v.decode("utf-8", "replace") if isinstance(v, bytes) else str(v)


def number_attr(attrs, name):
    try:
        return float(attrs[name])
    except (KeyError, TypeError, ValueError):
        return None


def envelope(t_ds, x_ds, n):
    """Per bucket of consecutive rows, the rows holding each component's min
    and max, in time order: plotting them as a line draws the envelope."""
    size = -(-n // BUCKETS)                      # rows per bucket, rounded up
    block = max(size, (BLOCK_ROWS // size) * size)
    ts, xs = [], []
    for start in range(0, n, block):
        stop = min(n, start + block)
        t = t_ds[start:stop]
        x = x_ds[start:stop, :]
        for b0 in range(0, stop - start, size):
            tb, xb = t[b0:b0 + size], x[b0:b0 + size]
            rows = np.unique(np.concatenate([np.argmin(xb, axis=0), np.argmax(xb, axis=0)]))
            ts.append(tb[rows])
            xs.append(xb[rows, :])
    # Each component keeps its own min/max rows; the union keeps all of them.
    return np.concatenate(ts), np.concatenate(xs)


def read_run(path):
    import h5py
    with h5py.File(path, "r") as f:
        if "t" not in f or "x" not in f:
            raise ValueError("no /t and /x datasets (not a catchup-run file?)")
        t_ds, x_ds = f["t"], f["x"]
        if x_ds.ndim != 2:
            raise ValueError("/x has %d dimensions, expected 2" % x_ds.ndim)
        n = min(t_ds.shape[0], x_ds.shape[0])
        if n == 0:
            raise ValueError("no samples (output: %s)" % text_attr(f.attrs, "output", "?"))
        if n > ENVELOPE_ABOVE:
            t, x = envelope(t_ds, x_ds, n)
        else:
            t, x = t_ds[:n], x_ds[:n, :]
        attrs = {k: f.attrs[k] for k in f.attrs}
        # the axes' names and units, as the file states them (docs/run-output.md)
        dim = x_ds.shape[1]
        names = [text_attr({"v": v}, "v") for v in f["state"][:]] if "state" in f else []
        units = [u.strip() for u in text_attr(x_ds.attrs, "units").split(",")] if "units" in x_ds.attrs else []
        if len(units) == 1:
            units = units * dim
        attrs["_names"] = names if len(names) == dim else ["" for _ in range(dim)]
        attrs["_units"] = units if len(units) == dim else ["" for _ in range(dim)]
        attrs["_t_unit"] = text_attr(t_ds.attrs, "units")
    return t, x, n, attrs


def axis_label(symbol, name, unit):
    """"$x_1$ = q(C4) [C]" from what the file says; the bare symbol without it."""
    return symbol + (f" = {name}" if name else "") + (f" [{unit}]" if unit and unit != "1" else "")


def caption(attrs, n_rows):
    parts = []
    if "n" in attrs:
        parts.append("n = %d" % int(attrs["n"]))
    for key, sym in (("eps", "\u03b5"), ("eta", "\u03b7")):
        spec, value = text_attr(attrs, key), number_attr(attrs, key + "_value")
        if spec:
            parts.append("%s = %s%s" % (sym, spec, "" if value is None else " (%.3g)" % value))
    for key in ("scheme", "projector"):
        if key in attrs:
            parts.append("%s %s" % (key, text_attr(attrs, key)))
    parts.append("%d samples" % n_rows)
    status = text_attr(attrs, "status_name")
    if status and status != "CUP_OK":
        parts.append("status %s" % status)
    return ",  ".join(parts)


def plot(t, x, n_rows, attrs, out, title):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    dim = x.shape[1]
    names, units = attrs.get("_names", [""] * dim), attrs.get("_units", [""] * dim)
    tlabel = axis_label("t", "", attrs.get("_t_unit", ""))
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2))
    left.plot(t, x[:, 0], color="black", linewidth=1)
    left.set_xlabel(tlabel)
    left.set_ylabel(axis_label("$x_1$", names[0], units[0]))
    if dim == 3:
        right.plot(t, x[:, 1], color="black", linewidth=1, label="$x_2$")
        right.plot(t, x[:, 2], color="blue", linewidth=1, label="$x_3$")
        if units[1] == units[2]:
            right.set_ylabel(axis_label("$x_2$ (black), $x_3$ (blue)", "", units[1]))
            if names[1]:
                right.set_title(f"$x_2$ = {names[1]}, $x_3$ = {names[2]}", fontsize=9)
        else:
            right.set_ylabel("%s (black), %s (blue)" % (axis_label("$x_2$", names[1], units[1]),
                                                        axis_label("$x_3$", names[2], units[2])))
    else:
        for j in range(dim):
            right.plot(t, x[:, j], linewidth=1, label=axis_label("$x_{%d}$" % (j + 1), names[j], units[j]))
        right.set_ylabel("x")
        right.legend(fontsize="small", ncol=max(1, dim // 8))
    right.set_xlabel(tlabel)
    for ax in (left, right):
        ax.grid(True, linewidth=0.3, alpha=0.5)
    fig.suptitle(title)
    fig.text(0.5, 0.01, caption(attrs, n_rows), ha="center", va="bottom", fontsize=8)
    fig.tight_layout(rect=(0, 0.05, 1, 0.95))
    fig.savefig(out, dpi=150)
    plt.close(fig)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("run", metavar="OUT.h5", help="a file written by catchup-run")
    p.add_argument("-o", "--output", metavar="FIG.png", required=True,
                   help="figure to write (format from the extension: png, pdf, svg)")
    p.add_argument("--title", help="figure title (default: the scene name)")
    a = p.parse_args(argv)
    try:
        if np is None:
            raise ImportError("No module named 'numpy'")
        t, x, n_rows, attrs = read_run(a.run)
        title = a.title or text_attr(attrs, "scene_name") or os.path.basename(a.run)
        plot(t, x, n_rows, attrs, a.output, title)
    except ImportError as e:
        print("plot_run.py: %s (pip install h5py matplotlib numpy)" % e, file=sys.stderr)
        return 1
    except (OSError, ValueError, KeyError) as e:
        print("plot_run.py: %s: %s" % (a.run, e), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
