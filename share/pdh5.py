"""pdh5 -- read pd-h5 files' bonds from Python, in either form (pd-h5(5)),
and a run's time series.

    import h5py, pdh5
    with h5py.File("model.h5", "r") as f:
        offset, neighbor, length, vfactor = pdh5.bonds(f)
        mu = pdh5.bits(f["bonds/state"], len(neighbor))

A lattice body's /bonds is stored as a stencil (form "stencil": a table of
lattice offsets, no per-bond arrays); any other body's as lists (CSR).
bonds() gives the lists for both: for a stencil, particle i sits at the
site c_i = round((x_i - origin) / spacing), its family is every particle at
a site c_i + d over the table's offsets d, sorted by row, and each bond's
length and partial-volume factor come from the positions and radii by the
arithmetic of pd-bonds, so the arrays equal those of `pd-bonds --csr` bit
for bit.  series(path) gives a run's /series (pd-run --series) as a dict
of its columns by name, the rows counted only.  Needs numpy and h5py
(python3-numpy, python3-h5py).
"""

import numpy as np

__all__ = ["bonds", "bits", "form", "series", "FormatError"]


class FormatError(ValueError):
    """The file's /bonds is not of either form."""


def form(f):
    """'stencil' or 'csr': the form of f's /bonds."""
    v = f["bonds"].attrs.get("form", "csr")
    v = v.decode() if isinstance(v, bytes) else str(v)
    if v not in ("csr", "stencil"):
        raise FormatError(f"/bonds form {v!r} is neither 'csr' nor 'stencil'")
    return v


def bits(data, count):
    """The first COUNT bits of a packed state (a dataset or bytes), 0 or 1
    (uint8), bit b being bit b % 8 of byte b // 8."""
    return np.unpackbits(np.asarray(data[()] if hasattr(data, "shape") else data,
                                    dtype=np.uint8), bitorder="little")[:count]


def _partial_volume(length, horizon, r):
    # seed 000, "Modification to the Particle Volume" (pd_partial_volume)
    return np.where(length <= horizon - r, 1.0, (horizon + r - length) / (2.0 * r))


def _expand(f):
    g = f["bonds"]
    x = np.asarray(f["particles/position"][()], dtype=np.float64)
    radius = np.asarray(f["particles/radius"][()], dtype=np.float64)
    try:
        d = np.asarray(g["stencil"][()], dtype=np.int64).reshape(-1, 3)
        h = float(g.attrs["spacing"])
        origin = np.asarray(g.attrs["origin"], dtype=np.float64).reshape(3)
        horizon = float(g.attrs["horizon"])
        count = int(g.attrs["count"])
    except (KeyError, ValueError) as e:
        raise FormatError(f"/bonds as a stencil: {e}") from None
    if not (h > 0 and np.isfinite(h) and np.isfinite(origin).all()):
        raise FormatError(f"/bonds has spacing {h} and origin {origin}")
    n = len(x)
    u = (x - origin) / h
    c = np.rint(u).astype(np.int64)
    if n and np.abs(u - c).max() > 1e-6:
        raise FormatError("a particle is off the lattice of the bonds' stencil")
    lo = c.min(axis=0) if n else np.zeros(3, np.int64)
    dim = (c.max(axis=0) - lo + 1) if n else np.ones(3, np.int64)
    site = np.full(int(np.prod(dim)), -1, dtype=np.int64)
    key = ((c[:, 2] - lo[2]) * dim[1] + (c[:, 1] - lo[1])) * dim[0] + (c[:, 0] - lo[0])
    site[key] = np.arange(n)
    if n and np.unique(key).size != n:
        raise FormatError("two particles share a lattice site")
    rows, partners = [], []
    for dk in d:
        s = c + dk
        inside = np.all((s >= lo) & (s < lo + dim), axis=1)
        i = np.nonzero(inside)[0]
        sk = ((s[i, 2] - lo[2]) * dim[1] + (s[i, 1] - lo[1])) * dim[0] + (s[i, 0] - lo[0])
        j = site[sk]
        keep = j >= 0
        rows.append(i[keep])
        partners.append(j[keep])
    i = np.concatenate(rows) if rows else np.zeros(0, np.int64)
    j = np.concatenate(partners) if partners else np.zeros(0, np.int64)
    order = np.lexsort((j, i))
    i, j = i[order], j[order]
    offset = np.zeros(n + 1, dtype=np.int64)
    offset[1:] = np.cumsum(np.bincount(i, minlength=n))
    dx = x[i, 0] - x[j, 0]
    dy = x[i, 1] - x[j, 1]
    dz = x[i, 2] - x[j, 2]
    length = np.sqrt(dx * dx + dy * dy + dz * dz)
    if count != len(j):
        raise FormatError(f"the stencil gives {len(j)} bonds, /bonds@count says {count}")
    return offset, j.astype(np.int32), length, _partial_volume(length, horizon, radius[j])


def bonds(f):
    """(offset (N+1) int64, neighbor (B) int32, length (B) float64,
    volume_factor (B) float64) of an open h5py.File, for either form."""
    if form(f) == "stencil":
        return _expand(f)
    g = f["bonds"]
    return (np.asarray(g["offset"][()], dtype=np.int64), np.asarray(g["neighbor"][()]),
            np.asarray(g["length"][()]), np.asarray(g["volume_factor"][()]))


def series(path):
    """The time series of the run file at path: {column name: its values}."""
    import h5py
    with h5py.File(path, "r") as f:
        g = f["series"]
        columns = g.attrs["columns"]
        columns = (columns.decode() if isinstance(columns, bytes) else columns).split()
        values = g["values"][: g.attrs["rows"]]
    return {c: values[:, k] for k, c in enumerate(columns)}
