#!/usr/bin/python3
"""pd-mesh -- turn a mesh into particles: one particle per cell, at the
cell's centroid, with the cell's exact volume (pd-h5 /particles and /sets).

The mesh is read by meshio, so every format meshio reads works (Gmsh 2.2
and 4.x, Abaqus, Exodus, VTK/VTU, XDMF, MED, Nastran, ...).  Volume and
centroid are integrals over the cell's isoparametric map, by Gauss rules
that are exact for its polynomial degree: the volume enclosed by the
cell's faces (bilinear faces for linear cells, quadratic ones for
quadratic cells), to rounding.  With --surface it writes the boundary of
the mesh as triangles instead, for pd-lattice --inside.

The rules (materials, sets, spacing) are in pd-mesh(1).  Runs under
Debian's /usr/bin/python3 with python3-meshio, python3-numpy, python3-h5py.
"""

import contextlib
import getopt
import io
import os
import re
import signal
import sys
import tempfile

PROG = "pd-mesh"
VERSION = "@VERSION@"
FORMAT_VERSION = 2
NAME_RE = re.compile(r"^[A-Za-z0-9_.-]{1,63}$")


class UsageError(Exception):
    pass


class DataError(Exception):
    pass


USAGE = """\
Usage: pd-mesh --density RHO [OPTION]... MESH [-o FILE]
       pd-mesh --surface [OPTION]... MESH [-o FILE]
Turn a mesh into particles (pd-h5 /particles and /sets): one particle per
3-D cell (tetra, tetra10, pyramid, wedge, hexahedron, hexahedron20,
hexahedron27) at its centroid, with its exact volume; a 2-D mesh (triangle,
quad) in the plane z = 0 with --thickness becomes a plate.  The mesh is read
by meshio (Gmsh, Abaqus, Exodus, VTK/VTU, XDMF, MED, Nastran, ...).

Options:
  --density RHO        mass density, kg/m^3 (> 0)
  --thickness H        a 2-D mesh is a plate of thickness H, m (> 0):
                       volume = cell area x H
  --material NAME=ID   the cells of the named cell set (an Abaqus ELSET, a
                       Gmsh physical volume name, ...) get material ID;
                       repeatable, the last one given wins; by default a
                       cell's material is its Gmsh physical tag, or 1
  --format FMT         meshio's name of the file format, when the file's
                       extension does not tell it (gmsh, abaqus, exodus, ...)
  --surface            write the mesh's closed boundary surface as triangles
                       (/surface), for pd-lattice --inside
  -o, --output FILE    output file, '-' for stdout (default '-')
  -q, --quiet          no summary on stderr
  -h, --help           show this help
  -V, --version        show the version
"""


def warn(msg):
    sys.stderr.write(f"{PROG}: warning: {msg}\n")


def parse_number(opt, text):
    try:
        v = float(text)
    except ValueError:
        raise UsageError(f"{opt} must be a positive number, not '{text}'")
    if not (v > 0 and v < float("inf")):
        raise UsageError(f"{opt} must be a positive number, not '{text}'")
    return v


def parse_args(argv):
    longopts = ["density=", "thickness=", "material=", "format=", "surface", "output=",
                "quiet", "help", "version"]
    try:
        opts, args = getopt.gnu_getopt(argv, "o:qhV", longopts)
    except getopt.GetoptError as e:
        raise UsageError(str(e))
    o = {"density": None, "thickness": None, "materials": [], "format": None,
         "surface": False, "output": "-", "quiet": False}
    for k, v in opts:
        if k in ("-h", "--help"):
            sys.stdout.write(USAGE)
            sys.exit(0)
        if k in ("-V", "--version"):
            print(f"{PROG} (pd) {VERSION}")
            sys.exit(0)
        if k == "--density":
            o["density"] = parse_number(k, v)
        elif k == "--thickness":
            o["thickness"] = parse_number(k, v)
        elif k == "--material":
            name, eq, ident = v.partition("=")
            if not eq or not name:
                raise UsageError(f"--material needs NAME=ID, not '{v}'")
            if not re.fullmatch(r"[0-9]+", ident) or int(ident) > 2**31 - 1:
                raise UsageError(f"--material ID must be a non-negative integer, not '{v}'")
            o["materials"].append((name, int(ident)))
        elif k == "--format":
            o["format"] = v
        elif k == "--surface":
            o["surface"] = True
        elif k in ("-o", "--output"):
            o["output"] = v
        elif k in ("-q", "--quiet"):
            o["quiet"] = True
    if len(args) != 1:
        raise UsageError("give one mesh file" if not args else f"unexpected argument '{args[1]}'")
    o["mesh"] = args[0]
    if o["surface"]:
        if o["density"] is not None or o["thickness"] is not None or o["materials"]:
            raise UsageError("--surface takes no --density, --thickness or --material")
    elif o["density"] is None:
        raise UsageError("--density is required")
    return o


# ------------------------------------------------------------ quadrature

def gauss(n):
    """Gauss-Legendre points and weights on [-1, 1]."""
    import numpy as np
    return np.polynomial.legendre.leggauss(n)


def cube_rule(n):
    import numpy as np
    x, w = gauss(n)
    X = np.array([(a, b, c) for c in x for b in x for a in x])
    W = np.array([wa * wb * wc for wc in w for wb in w for wa in w])
    return X, W


def square_rule(n):
    import numpy as np
    x, w = gauss(n)
    return np.array([(a, b) for b in x for a in x]), np.array([wa * wb for wb in w for wa in w])


# --------------------------------------------------- shape functions
# Node orderings are meshio's (VTK's): hexahedron corners (-1,-1,-1),
# (1,-1,-1), (1,1,-1), (-1,1,-1), then the same at z = +1; the quadratic
# hexahedra add the edge midpoints (0-1, 1-2, 2-3, 3-0, 4-5, 5-6, 6-7, 7-4,
# 0-4, 1-5, 2-6, 3-7), then (hexahedron27) the face centres -x, +x, -y,
# +y, -z, +z and the centre.

HEX_CORNERS = [(-1, -1, -1), (1, -1, -1), (1, 1, -1), (-1, 1, -1),
               (-1, -1, 1), (1, -1, 1), (1, 1, 1), (-1, 1, 1)]
HEX_EDGES = [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4),
             (0, 4), (1, 5), (2, 6), (3, 7)]
HEX_FACES = [(-1, 0, 0), (1, 0, 0), (0, -1, 0), (0, 1, 0), (0, 0, -1), (0, 0, 1)]


def hex_nodes(count):
    import numpy as np
    c = [np.array(p, float) for p in HEX_CORNERS]
    nodes = list(c)
    if count >= 20:
        nodes += [(c[a] + c[b]) / 2 for a, b in HEX_EDGES]
    if count == 27:
        nodes += [np.array(f, float) for f in HEX_FACES] + [np.zeros(3)]
    return np.array(nodes)


def trilinear(X):
    """Values (Q,8) and derivatives (Q,8,3) of the trilinear hexahedron."""
    import numpy as np
    R = hex_nodes(8)
    f = 1 + X[:, None, :] * R[None, :, :]              # (Q,8,3)
    N = f.prod(axis=2) / 8
    dN = np.empty(f.shape)
    for d in range(3):
        g = f.copy()
        g[:, :, d] = R[None, :, d]
        dN[:, :, d] = g.prod(axis=2) / 8
    return N, dN


def lagrange3(t, node):
    """The 1-D quadratic Lagrange polynomial on nodes -1, 0, 1 that is 1 at
    `node`, and its derivative, at points t."""
    import numpy as np
    if node == -1:
        return t * (t - 1) / 2, t - 0.5
    if node == 1:
        return t * (t + 1) / 2, t + 0.5
    return 1 - t * t, -2 * t


def triquadratic(X):
    import numpy as np
    R = hex_nodes(27)
    Q = len(X)
    N = np.ones((Q, 27))
    dN = np.ones((Q, 27, 3))
    for k, r in enumerate(R):
        vals = [lagrange3(X[:, d], r[d]) for d in range(3)]
        N[:, k] = vals[0][0] * vals[1][0] * vals[2][0]
        for d in range(3):
            prod = np.ones(Q)
            for e in range(3):
                prod = prod * (vals[e][1] if e == d else vals[e][0])
            dN[:, k, d] = prod
    return N, dN


def serendipity20(X):
    import numpy as np
    R = hex_nodes(20)
    Q = len(X)
    N = np.empty((Q, 20))
    dN = np.empty((Q, 20, 3))
    x = [X[:, 0], X[:, 1], X[:, 2]]
    for k, r in enumerate(R):
        if k < 8:
            f = [1 + x[d] * r[d] for d in range(3)]
            s = x[0] * r[0] + x[1] * r[1] + x[2] * r[2] - 2
            N[:, k] = f[0] * f[1] * f[2] * s / 8
            for d in range(3):
                o = [f[e] for e in range(3) if e != d]
                dN[:, k, d] = (r[d] * o[0] * o[1] * s + f[0] * f[1] * f[2] * r[d]) / 8
        else:
            z = [d for d in range(3) if r[d] == 0][0]
            f = [(1 - x[d] * x[d]) if d == z else (1 + x[d] * r[d]) for d in range(3)]
            df = [(-2 * x[d]) if d == z else r[d] * np.ones(Q) for d in range(3)]
            N[:, k] = f[0] * f[1] * f[2] / 4
            for d in range(3):
                prod = np.ones(Q)
                for e in range(3):
                    prod = prod * (df[e] if e == d else f[e])
                dN[:, k, d] = prod / 4
    return N, dN


def tetra10(X):
    """Quadratic tetrahedron on the reference tetrahedron r, s, t >= 0,
    r + s + t <= 1 (nodes 0-3 the corners, then the edge midpoints 0-1,
    1-2, 2-0, 0-3, 1-3, 2-3)."""
    import numpy as np
    r, s, t = X[:, 0], X[:, 1], X[:, 2]
    L = [1 - r - s - t, r, s, t]
    dL = [np.array([-1, -1, -1.0]), np.array([1, 0, 0.0]), np.array([0, 1, 0.0]),
          np.array([0, 0, 1.0])]
    edges = [(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)]
    Q = len(X)
    N = np.empty((Q, 10))
    dN = np.empty((Q, 10, 3))
    for k in range(4):
        N[:, k] = L[k] * (2 * L[k] - 1)
        dN[:, k, :] = (4 * L[k] - 1)[:, None] * dL[k][None, :]
    for e, (a, b) in enumerate(edges):
        N[:, 4 + e] = 4 * L[a] * L[b]
        dN[:, 4 + e, :] = 4 * (L[b][:, None] * dL[a][None, :] + L[a][:, None] * dL[b][None, :])
    return N, dN


def tet_rule(n):
    """A collapsed (Duffy) Gauss rule on the reference tetrahedron: n^3
    points, exact for polynomials of degree 2n - 3 and more."""
    import numpy as np
    x, w = gauss(n)
    u, wu = (x + 1) / 2, w / 2
    pts, wts = [], []
    for a, wa in zip(u, wu):
        for b, wb in zip(u, wu):
            for c, wc in zip(u, wu):
                pts.append((a * (1 - b) * (1 - c), b * (1 - c), c))
                wts.append(wa * wb * wc * (1 - b) * (1 - c) ** 2)
    return np.array(pts), np.array(wts)


# A linear cell is a hexahedron with corners repeated: the trilinear map of
# the repeated corners has the cell's own faces (flat triangles, bilinear
# quadrilaterals), so the volume and centroid it integrates are the cell's.
COLLAPSE = {"tetra": [0, 1, 2, 2, 3, 3, 3, 3], "pyramid": [0, 1, 2, 3, 4, 4, 4, 4],
            "wedge": [0, 1, 2, 2, 3, 4, 5, 5], "hexahedron": list(range(8))}
SOLIDS = {"tetra": 4, "tetra10": 10, "pyramid": 5, "wedge": 6, "hexahedron": 8,
          "hexahedron20": 20, "hexahedron27": 27}
PLANES = {"triangle": [0, 1, 2, 2], "quad": [0, 1, 2, 3]}
DIM = {"vertex": 0, "line": 1, "line3": 1, "triangle": 2, "triangle6": 2, "triangle7": 2,
       "quad": 2, "quad8": 2, "quad9": 2, "polygon": 2}


def cell_dim(ctype):
    if ctype in SOLIDS or ctype.startswith(("tetra", "hexahedron", "wedge", "pyramid")):
        return 3
    if ctype in DIM:
        return DIM[ctype]
    if ctype.startswith(("triangle", "quad")):
        return 2
    if ctype.startswith("line"):
        return 1
    return 3


def integrate_solids(ctype, points, cells):
    """Signed volumes (C) and centroids (C,3) of the cells, and the smallest
    and largest Jacobian determinant of each cell at the rule's points."""
    import numpy as np
    if ctype in COLLAPSE:
        X, W = cube_rule(2)          # exact: det J is of degree 2 per axis
        N, dN = trilinear(X)
        nodes = cells[:, COLLAPSE[ctype]]
    elif ctype == "tetra10":
        X, W = tet_rule(4)
        N, dN = tetra10(X)
        nodes = cells
    else:
        X, W = cube_rule(4)          # exact: x det J is of degree 7 per axis
        N, dN = serendipity20(X) if ctype == "hexahedron20" else triquadratic(X)
        nodes = cells
    x = points[nodes]                                   # (C,n,3)
    J = np.einsum("qnd,cnk->cqkd", dN, x)               # (C,Q,3,3)
    det = np.linalg.det(J)                              # (C,Q)
    vol = det @ W
    xq = np.einsum("qn,cnk->cqk", N, x)
    cen = np.einsum("cq,q,cqk->ck", det, W, xq) / vol[:, None]
    return vol, cen, det.min(axis=1), det.max(axis=1)


def integrate_planes(ctype, points, cells):
    import numpy as np
    X, W = square_rule(2)
    R = np.array([(-1, -1), (1, -1), (1, 1), (-1, 1)], float)
    f = 1 + X[:, None, :] * R[None, :, :]
    N = f.prod(axis=2) / 4
    dN = np.stack([R[None, :, 0] * f[:, :, 1], f[:, :, 0] * R[None, :, 1]], axis=2) / 4
    x = points[cells[:, PLANES[ctype]]][:, :, :2]
    J = np.einsum("qnd,cnk->cqkd", dN, x)
    det = J[:, :, 0, 0] * J[:, :, 1, 1] - J[:, :, 0, 1] * J[:, :, 1, 0]
    area = det @ W
    xq = np.einsum("qn,cnk->cqk", N, x)
    cen = np.einsum("cq,q,cqk->ck", det, W, xq) / area[:, None]
    cen = np.concatenate([cen, np.zeros((len(cen), 1))], axis=1)
    return area, cen, det.min(axis=1), det.max(axis=1)


# ------------------------------------------------------------ the mesh

def read_mesh(path, fmt):
    import meshio
    if path == "-":
        raise DataError("the mesh must be a file (meshio reads files, not a pipe)")
    if not os.path.exists(path):
        raise DataError(f"cannot open '{path}': no such file")
    if os.path.isdir(path):
        raise DataError(f"'{path}' is a directory, not a mesh")
    said = io.StringIO()
    try:
        # meshio prints progress and warnings on stdout, which carries the
        # output file, and its own error lines on stderr (then exits): keep
        # them off both, the one line of an error is pd-mesh's
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(said):
            return meshio.read(path, file_format=fmt)
    except (Exception, SystemExit) as e:  # meshio raises many kinds, or exits
        text = " ".join((str(e) if isinstance(e, Exception) else said.getvalue()).split())
        text = re.sub(r"^Error:\s*", "", text) or type(e).__name__
        raise DataError(f"meshio cannot read '{path}': {text[:300]}")


def particle_blocks(mesh, thickness):
    """The indices of the cell blocks that become particles, and the
    dimension of the body."""
    if not any(len(c.data) for c in mesh.cells):
        raise DataError("the mesh has no cells")
    solids = [k for k, c in enumerate(mesh.cells) if cell_dim(c.type) == 3 and len(c.data)]
    if solids:
        if thickness is not None:
            raise DataError("--thickness is for a 2-D mesh, and this mesh has 3-D cells")
        return supported(mesh, solids, SOLIDS, ""), 3
    planes = [k for k, c in enumerate(mesh.cells) if cell_dim(c.type) == 2 and len(c.data)]
    if thickness is None:
        raise DataError("the mesh has no 3-D cells (for a 2-D mesh give --thickness H)")
    if not planes:
        raise DataError("the mesh has no 3-D or 2-D cells")
    return supported(mesh, planes, PLANES, " for a plate"), 2


def supported(mesh, blocks, types, what):
    """The blocks, when each is of one of the types pd-mesh takes."""
    for k in blocks:
        if mesh.cells[k].type not in types:
            raise DataError(f"unsupported cell type '{mesh.cells[k].type}'{what} "
                            f"(pd-mesh takes {', '.join(types)})")
    return blocks


def cells_of(mesh, blocks, dim):
    """Volumes, centroids and a check of every particle cell."""
    import numpy as np
    pts = np.asarray(mesh.points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] < 2:
        raise DataError("the mesh's points are not 2-D or 3-D")
    if pts.shape[1] == 2:
        pts = np.concatenate([pts, np.zeros((len(pts), 1))], axis=1)
    if not np.isfinite(pts).all():
        raise DataError("the mesh has a point that is not finite")
    if dim == 2:
        used = np.unique(np.concatenate([mesh.cells[k].data.ravel() for k in blocks]))
        ext = np.ptp(pts[used, :2], axis=0).max()
        if np.abs(pts[used, 2]).max() > 1e-9 * ext:
            raise DataError("a 2-D mesh for a plate must lie in the plane z = 0")
    vols, cens, kinds = [], [], []
    for k in blocks:
        c = mesh.cells[k]
        data = np.asarray(c.data, dtype=np.int64)
        f = integrate_solids if dim == 3 else integrate_planes
        v, x, dmin, dmax = f(c.type, pts, data)
        vols.append(v)
        cens.append(x)
        kinds.append((c.type, v, dmin, dmax))
    v = np.concatenate(vols)
    # every cell of a type turns the same way (meshio keeps each format's
    # node order, whose handedness differs between formats for wedges): a
    # cell turning against the others of its type is inverted
    scale = np.abs(v).mean()
    for ctype in sorted(set(t for t, *_ in kinds)):
        vt = np.concatenate([vv for t, vv, *_ in kinds if t == ctype])
        lo = np.concatenate([a for t, _, a, _ in kinds if t == ctype])
        hi = np.concatenate([b for t, _, _, b in kinds if t == ctype])
        zero = np.abs(vt) <= 1e-12 * scale
        if zero.any():
            raise DataError(f"{zero.sum()} {ctype} cell(s) of zero volume "
                            f"(the first is {ctype} cell {np.flatnonzero(zero)[0]})")
        sign = 1.0 if (vt > 0).sum() >= (vt < 0).sum() else -1.0
        bad = (sign * lo <= 0) | (sign * hi <= 0)
        if bad.any():
            raise DataError(f"{bad.sum()} inverted or tangled {ctype} cell(s) of "
                            f"{len(vt)} (the first is {ctype} cell {np.flatnonzero(bad)[0]})")
    return pts, np.abs(v), np.concatenate(cens)


def gmsh_tags(mesh, k):
    tags = mesh.cell_data.get("gmsh:physical")
    if tags is None:
        return None
    return tags[k]


def sanitize(name):
    clean = re.sub(r"[^A-Za-z0-9_.-]", "_", name)[:63]
    if clean in (".", "..") or not clean:
        clean = "set_" + clean.strip(".")
    return clean


def build(mesh, o):
    import numpy as np
    blocks, dim = particle_blocks(mesh, o["thickness"])
    pts, vol, cen = cells_of(mesh, blocks, dim)
    n = len(vol)
    start = {}
    at = 0
    for k in blocks:
        start[k] = at
        at += len(mesh.cells[k].data)
    if dim == 2:
        vol = vol * o["thickness"]
    # materials: Gmsh physical tag, then --material NAME=ID in order
    material = np.ones(n, dtype=np.int32)
    source = {1: "default"}
    for k in blocks:
        tags = gmsh_tags(mesh, k)
        if tags is not None:
            t = np.asarray(tags, dtype=np.int64)
            if (t < 0).any() or (t > 2**31 - 1).any():
                raise DataError("a Gmsh physical tag outside 0 to 2^31 - 1")
            material[start[k]:start[k] + len(t)] = t
            for tag in np.unique(t):
                source[int(tag)] = "Gmsh physical tag"
    cell_sets = {k: v for k, v in mesh.cell_sets.items() if not k.startswith("gmsh:")}

    def set_rows(name):
        """Rows of the particle cells in cell set `name`, and the nodes of
        its other cells."""
        rows, nodes = [], []
        for k, idx in enumerate(cell_sets[name]):
            if idx is None or len(idx) == 0 or k >= len(mesh.cells):
                continue
            idx = np.asarray(idx, dtype=np.int64)
            if k in start:
                rows.append(start[k] + idx)
            else:
                nodes.append(np.asarray(mesh.cells[k].data, dtype=np.int64)[idx].ravel())
        cat = lambda a: np.concatenate(a) if a else np.zeros(0, dtype=np.int64)
        return cat(rows), cat(nodes)

    for name, ident in o["materials"]:
        if name not in cell_sets:
            names = ", ".join(sorted(cell_sets)) or "none"
            raise DataError(f"--material {name}={ident}: the mesh has no cell set '{name}' "
                            f"(its cell sets: {names})")
        rows, _ = set_rows(name)
        if len(rows) == 0:
            raise DataError(f"--material {name}={ident}: cell set '{name}' holds no cell of "
                            f"the body")
        material[rows] = ident
        source[ident] = f"cell set '{name}'"
    # Peridigm's rule: a node set holds the particles of the cells with at
    # least one node in it
    cellnodes = [(start[k], np.asarray(mesh.cells[k].data, dtype=np.int64)) for k in blocks]

    def node_rule(nodes):
        mark = np.zeros(len(pts), dtype=bool)
        mark[nodes] = True
        return np.concatenate([s + np.flatnonzero(mark[c].any(axis=1)) for s, c in cellnodes])

    sets = []
    for name in cell_sets:
        rows, nodes = set_rows(name)
        if len(nodes):
            rows = np.concatenate([rows, node_rule(nodes)])
        sets.append((name, rows, "cell set" if not len(nodes) else "cells touching its nodes"))
    for name, nodes in mesh.point_sets.items():
        sets.append((name, node_rule(np.asarray(nodes, dtype=np.int64)), "node set"))
    out, seen = [], set()
    for name, rows, kind in sets:
        clean = sanitize(name)
        if clean in seen:
            raise DataError(f"two sets are named '{clean}'")
        seen.add(clean)
        if clean != name:
            warn(f"set '{name}' is written as '{clean}' (names are A-Z a-z 0-9 _ . -)")
        ids = np.unique(rows) + 1
        if len(ids) == 0:
            warn(f"set '{clean}' holds no particle; left out")
            continue
        out.append((clean, ids, kind))
    mean = vol.mean() if dim == 3 else (vol / o["thickness"]).mean()
    spacing = mean ** (1 / 3) if dim == 3 else mean ** 0.5
    cell_size = vol ** (1 / 3) if dim == 3 else (vol / o["thickness"]) ** 0.5
    counts = {}
    for k in blocks:
        counts[mesh.cells[k].type] = counts.get(mesh.cells[k].type, 0) + len(mesh.cells[k].data)
    return {"position": cen, "volume": vol, "radius": cell_size / 2,
            "density": np.full(n, o["density"]), "material": material,
            "id": np.arange(1, n + 1, dtype=np.int64), "spacing": spacing, "dimension": dim,
            "sets": out, "counts": counts, "source": source}


# ------------------------------------------------------------ surfaces

FACES = {  # corner faces of each solid, turning outward for a positive cell
    "tetra": [(0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2)],
    "pyramid": [(0, 3, 2, 1), (0, 1, 4), (1, 2, 4), (2, 3, 4), (3, 0, 4)],
    "wedge": [(0, 2, 1), (3, 4, 5), (0, 1, 4, 3), (1, 2, 5, 4), (2, 0, 3, 5)],
    "hexahedron": [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6),
                   (3, 0, 4, 7)],
}
CORNERS = {"tetra": 4, "pyramid": 5, "wedge": 6, "hexahedron": 8}
LINEAR = {"tetra10": "tetra", "hexahedron20": "hexahedron", "hexahedron27": "hexahedron",
          "triangle6": "triangle", "triangle7": "triangle", "quad8": "quad", "quad9": "quad"}


def surface(mesh):
    """The mesh's boundary as triangles (points, triangles), outward for
    volume meshes; a surface mesh keeps its own orientation."""
    import numpy as np
    if not any(len(c.data) for c in mesh.cells):
        raise DataError("the mesh has no cells")
    pts = np.asarray(mesh.points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise DataError("a surface for --inside needs 3-D points")
    solids = [c for c in mesh.cells if cell_dim(c.type) == 3 and len(c.data)]
    tris = []
    if solids:
        faces, owner_centre = [], []
        for c in solids:
            base = LINEAR.get(c.type, c.type)
            if base not in FACES:
                raise DataError(f"unsupported cell type '{c.type}'")
            data = np.asarray(c.data, dtype=np.int64)
            centre = pts[data[:, :CORNERS[base]]].mean(axis=1)
            for f in FACES[base]:
                faces.append((len(f), data[:, list(f)], centre))
        # a boundary face belongs to one cell only
        keys, allf = [], []
        for m, fd, centre in faces:
            keys.append(np.sort(np.pad(fd, ((0, 0), (0, 4 - m)), constant_values=-1), axis=1))
            allf.append((m, fd, centre))
        key = np.concatenate(keys)
        _, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
        once = cnt[inv.ravel()] == 1
        at = 0
        for m, fd, centre in allf:
            sel = once[at:at + len(fd)]
            at += len(fd)
            fd, centre = fd[sel], centre[sel]
            # outward: away from the cell's centre
            a, b, c = pts[fd[:, 0]], pts[fd[:, 1]], pts[fd[:, 2]]
            nrm = np.cross(b - a, c - a)
            if m == 4:
                nrm += np.cross(c - a, pts[fd[:, 3]] - a)
            flip = np.einsum("ij,ij->i", nrm, pts[fd].mean(axis=1) - centre) < 0
            fd = np.where(flip[:, None], fd[:, ::-1], fd)
            tris.append(fd[:, :3])
            if m == 4:
                tris.append(fd[:, [0, 2, 3]])
    else:
        for c in mesh.cells:
            base = LINEAR.get(c.type, c.type)
            data = np.asarray(c.data, dtype=np.int64)
            if base == "triangle":
                tris.append(data[:, :3])
            elif base == "quad":
                tris += [data[:, [0, 1, 2]], data[:, [0, 2, 3]]]
    if not tris:
        raise DataError("the mesh has no triangles, quadrilaterals or 3-D cells")
    tri = np.concatenate(tris)
    # points that coincide are one point (an STL file repeats them)
    used, inv = np.unique(tri.ravel(), return_inverse=True)
    upts, uinv = np.unique(pts[used], axis=0, return_inverse=True)
    return upts, uinv.ravel()[inv.ravel()].reshape(-1, 3).astype(np.int64)


# ------------------------------------------------------------ output

def history():
    def q(a):
        return f"'{a}'" if a == "" or re.search(r"[ \t\n'\"]", a) else a
    return " ".join([PROG] + [q(a) for a in sys.argv[1:]])


def write_file(h5, o, fill):
    import h5py
    import numpy as np
    out = o["output"]
    stream = out == "-" or (os.path.exists(out) and not os.path.isfile(out)
                            and not os.path.isdir(out))
    if out == "-" and sys.stdout.isatty():
        raise DataError("refusing to write binary HDF5 to a terminal (give -o FILE)")
    if os.path.isdir(out):
        raise DataError(f"cannot write '{out}': it is a directory")

    def content(f):
        f.attrs["pd_format"] = "pd-h5"
        f.attrs["pd_format_version"] = np.int64(FORMAT_VERSION)
        f.attrs["units"] = "SI"
        f.attrs["history"] = history()
        fill(f)

    if stream:
        buf = io.BytesIO()
        with h5.File(buf, "w") as f:
            content(f)
        target = sys.stdout.buffer if out == "-" else open(out, "wb")
        try:
            target.write(buf.getvalue())
            target.flush()
        except OSError as e:
            raise DataError(f"cannot write '{out}': {e.strerror}")
        return
    d = os.path.dirname(out) or "."
    try:
        fd, tmp = tempfile.mkstemp(dir=d, prefix="." + os.path.basename(out) + ".tmp.")
    except OSError as e:
        raise DataError(f"cannot write '{out}': {e.strerror}")
    os.close(fd)
    TEMPS.append(tmp)
    try:
        with h5.File(tmp, "w") as f:
            content(f)
        os.chmod(tmp, 0o666 & ~current_umask())
        os.replace(tmp, out)
    except OSError as e:
        raise DataError(f"cannot write '{out}': {e.strerror or e}")
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
        TEMPS.remove(tmp)


def current_umask():
    m = os.umask(0)
    os.umask(m)
    return m


TEMPS = []


def die_of(sig, frame):
    for t in TEMPS:
        try:
            os.unlink(t)
        except OSError:
            pass
    signal.signal(sig, signal.SIG_DFL)
    os.kill(os.getpid(), sig)


def write_particles(f, b):
    import numpy as np
    g = f.create_group("particles")
    g.create_dataset("position", data=np.ascontiguousarray(b["position"], dtype="<f8"))
    g.create_dataset("volume", data=b["volume"].astype("<f8"))
    g.create_dataset("density", data=b["density"].astype("<f8"))
    g.create_dataset("radius", data=b["radius"].astype("<f8"))
    g.create_dataset("material", data=b["material"].astype("<i4"))
    g.create_dataset("id", data=b["id"].astype("<i8"))
    g.attrs["spacing"] = np.float64(b["spacing"])
    g.attrs["dimension"] = np.int64(b["dimension"])
    if b["dimension"] == 2:
        g.attrs["thickness"] = np.float64(b["thickness"])
    g.attrs["spacing_rule"] = ("mesh: the cube root of the mean cell volume" if
                               b["dimension"] == 3 else "mesh: the square root of the mean "
                               "cell area")
    if b["sets"]:
        s = f.create_group("sets")
        for name, ids, _ in b["sets"]:
            s.create_dataset(name, data=ids.astype("<i8"))


def main():
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        if signal.getsignal(sig) is not signal.SIG_IGN:
            signal.signal(sig, die_of)
    try:
        o = parse_args(sys.argv[1:])
    except UsageError as e:
        sys.stderr.write(f"{PROG}: error: {e} (see '{PROG} --help')\n")
        return 2
    try:
        import h5py
        import numpy as np
        import warnings
        warnings.simplefilter("ignore")
        mesh = read_mesh(o["mesh"], o["format"])
        if o["surface"]:
            pts, tri = surface(mesh)

            def fill(f):
                g = f.create_group("surface")
                g.create_dataset("points", data=pts.astype("<f8"))
                g.create_dataset("triangles", data=tri.astype("<i8"))
            write_file(h5py, o, fill)
            if not o["quiet"]:
                sys.stderr.write(f"{PROG}: surface of {len(tri)} triangles, {len(pts)} points\n")
            return 0
        b = build(mesh, o)
        b["thickness"] = o["thickness"]
        write_file(h5py, o, lambda f: write_particles(f, b))
    except DataError as e:
        sys.stderr.write(f"{PROG}: error: {e}\n")
        return 1
    except MemoryError:
        sys.stderr.write(f"{PROG}: error: out of memory\n")
        return 1
    if not o["quiet"]:
        cells = ", ".join(f"{n} {t}" for t, n in b["counts"].items())
        kind = ", a 2-D plate" if b["dimension"] == 2 else ""
        sys.stderr.write(f"{PROG}: {len(b['volume'])} particles from {cells}; volume "
                         f"{b['volume'].sum():.10g} m^3, spacing {b['spacing']:.6g} m{kind}\n")
        for m in np.unique(b["material"]):
            n = int((b["material"] == m).sum())
            sys.stderr.write(f"{PROG}: material {m}: {n} particles "
                             f"({b['source'].get(int(m), 'default')})\n")
        for name, ids, kind in b["sets"]:
            sys.stderr.write(f"{PROG}: set '{name}': {len(ids)} particles ({kind})\n")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except BrokenPipeError:
        sys.exit(1)
