#!/usr/bin/python3
"""tests/samebits/h5same.py -- are two HDF5 files the same, bit for bit?

    /usr/bin/python3 h5same.py A.h5 B.h5 [A2.h5 B2.h5]...

The same tree of groups and datasets, the same attributes on every object,
and for each dataset the same dtype, shape and raw bytes (so NaN and -0.0
count); for each attribute the same dtype, shape and bytes (numbers and
arrays of them) or the same value (strings).  The root attribute `history`
(the command lines, which name the programs' paths) is not compared.
Prints the first difference of each pair that differs, naming the second
file, the object and what differs, and exits 1; prints nothing and exits 0
when every pair is the same.  Exit 2 when a file cannot be read.
"""

import sys

import h5py
import numpy as np

SKIP_ROOT_ATTRS = {"history"}


class Differ(Exception):
    pass


def kind(obj):
    if isinstance(obj, h5py.Group):
        return "group"
    if isinstance(obj, h5py.Dataset):
        return "dataset"
    return type(obj).__name__


def values_differ(path, a, b):
    """Raise Differ naming PATH when the arrays A and B differ in any bit."""
    if a.dtype != b.dtype:
        raise Differ(f"{path}: dtype {a.dtype} against {b.dtype}")
    if a.shape != b.shape:
        raise Differ(f"{path}: shape {a.shape} against {b.shape}")
    if a.dtype.kind == "O":  # variable-length strings: compare the values
        fa, fb = a.ravel(), b.ravel()
        bad = [i for i in range(fa.size) if fa[i] != fb[i]]
        if bad:
            i = bad[0]
            raise Differ(f"{path}: {len(bad)} of {fa.size} values differ, "
                         f"the first {fa[i]!r} against {fb[i]!r}")
        return
    if a.tobytes() == b.tobytes():
        return
    n = max(a.size, 1)
    ra = np.frombuffer(a.tobytes(), dtype=np.uint8).reshape(n, -1)
    rb = np.frombuffer(b.tobytes(), dtype=np.uint8).reshape(n, -1)
    bad = (ra != rb).any(axis=1)
    what = f"{path}: {int(bad.sum())} of {a.size} values differ"
    if a.dtype.kind in "fiu":
        with np.errstate(all="ignore"):
            d = np.abs(a.ravel()[bad].astype(np.float64) - b.ravel()[bad].astype(np.float64))
        if np.isnan(d).all():
            what += ", largest nan"
        else:
            what += f", largest {np.nanmax(d):.3g}"
    raise Differ(what)


def as_array(value):
    if isinstance(value, (str, bytes)):
        return None
    return np.asarray(value)


def compare_attrs(path, x, y):
    skip = SKIP_ROOT_ATTRS if path == "/" else set()
    ka, kb = set(x.attrs) - skip, set(y.attrs) - skip
    for k in sorted(ka ^ kb):
        where = "the first" if k in ka else "the second"
        raise Differ(f"{path}: attribute {k} only in {where} file")
    for k in sorted(ka):
        name = f"{path} attribute {k}"
        va, vb = x.attrs[k], y.attrs[k]
        ta, tb = x.attrs.get_id(k).dtype, y.attrs.get_id(k).dtype
        if ta != tb:
            raise Differ(f"{name}: dtype {ta} against {tb}")
        aa, ab = as_array(va), as_array(vb)
        if aa is None or ab is None:
            if type(va) is not type(vb) or va != vb:
                raise Differ(f"{name}: {va!r} against {vb!r}")
        else:
            values_differ(name, aa, ab)


def compare(path, x, y):
    if kind(x) != kind(y):
        raise Differ(f"{path}: a {kind(x)} against a {kind(y)}")
    compare_attrs(path, x, y)
    if isinstance(x, h5py.Dataset):
        values_differ(path, x[()] if x.shape != () else np.asarray(x[()]),
                      y[()] if y.shape != () else np.asarray(y[()]))
        return
    if not isinstance(x, h5py.Group):
        return
    ka, kb = set(x), set(y)
    for k in sorted(ka ^ kb):
        where = "the first" if k in ka else "the second"
        raise Differ(f"{path.rstrip('/')}/{k}: only in {where} file")
    for k in sorted(ka):
        compare(f"{path.rstrip('/')}/{k}", x[k], y[k])


def main(argv):
    files = argv[1:]
    if not files or len(files) % 2:
        print("usage: h5same.py A.h5 B.h5 [A2.h5 B2.h5]...", file=sys.stderr)
        return 2
    status = 0
    for first, second in zip(files[0::2], files[1::2]):
        try:
            a, b = h5py.File(first, "r"), h5py.File(second, "r")
        except OSError as e:
            print(f"h5same.py: error: {e}", file=sys.stderr)
            return 2
        with a, b:
            try:
                compare("/", a, b)
            except Differ as d:
                print(f"{second}: {d}")
                status = 1
    return status


if __name__ == "__main__":
    sys.exit(main(sys.argv))
