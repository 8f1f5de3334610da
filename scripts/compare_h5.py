#!/usr/bin/env python3
"""Two HDF5 files' results, bit for bit (scripts/compare-builds).

    compare_h5.py A.h5 B.h5 GROUP...

Every dataset under the given groups (or the dataset itself) must be in both
files with the same shape, type and bytes (NaN equal to NaN when its bits
are); fields and datasets that measure wall time (a name with 'seconds',
'wall' or 'eta_s') are left out, as are attributes (a dimension scale's
references differ between files that hold the same data). Prints one line
per difference; exit 1 if any."""
import sys
import h5py
import numpy as np

SKIP = ("seconds", "wall", "eta_s")


def skipped(name):
    return any(s in name for s in SKIP)


def datasets(f, root):
    if root not in f:
        return {}
    obj = f[root]
    if isinstance(obj, h5py.Dataset):
        return {root: obj}
    out = {}
    obj.visititems(lambda n, o: out.__setitem__(f"{root}/{n}", o) if isinstance(o, h5py.Dataset) else None)
    return out


def equal(x, y):
    x, y = np.asarray(x), np.asarray(y)
    if x.dtype.kind == "O":                 # variable-length strings: by value, not by pointer
        return x.shape == y.shape and x.tolist() == y.tolist()
    return x.tobytes() == y.tobytes()


def same(a, b):
    if a.shape != b.shape or a.dtype != b.dtype:
        return False
    x, y = a[()], b[()]
    if a.dtype.names:
        return all(equal(x[k], y[k]) for k in a.dtype.names if not skipped(k))
    return equal(x, y)


def main():
    pa, pb, roots = sys.argv[1], sys.argv[2], sys.argv[3:]
    bad = 0
    with h5py.File(pa, "r") as fa, h5py.File(pb, "r") as fb:
        for root in roots:
            da, db = datasets(fa, root), datasets(fb, root)
            for name in sorted(set(da) | set(db)):
                if skipped(name.rsplit("/", 1)[-1]):
                    continue
                if name not in da or name not in db:
                    print(f"{name}: only in {'the first' if name in da else 'the second'} file")
                    bad += 1
                elif not same(da[name], db[name]):
                    print(f"{name}: differs")
                    bad += 1
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
