#!/usr/bin/python3
"""damage-xz.py -- the top monolayer of a run as a table for gnuplot.

Usage: /usr/bin/python3 damage-xz.py RUN.h5 [STEP] > damage.dat
       /usr/bin/python3 damage-xz.py --lammps DUMP [STEP] > damage.dat

Prints 'x z damage' (m, m, 1) of the particles of the top monolayer (the
largest reference y, the face the sphere hits) at their current positions
at step STEP (default: the last frame), sorted by damage so that the most
damaged particles are drawn last.

RUN.h5 is a pd-run output: the damage is the frame's 'damage' (pd-damage)
or, without it, the broken fraction of each bond family.  With --lammps,
DUMP is the LAMMPS dump of in.impact (id x y z c_C1; its step-0 frame gives
the reference positions).  The step and the number of particles go into
'#' comment lines.
"""
import os
import sys

import h5py
import numpy as np

# share/pdh5.py of this source tree (installed: $(PREFIX)/share/pd/python):
# the bonds of /bonds in either form (lists or a lattice stencil)
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "share"))
import pdh5  # noqa: E402


def pd_frame(path, step):
    with h5py.File(path, "r") as h:
        steps = sorted(int(k) for k in h["frames"])
        step = steps[-1] if step is None else step
        if "frames/%08d" % step not in h:
            raise SystemExit("damage-xz.py: error: %s has no frame %d" % (path, step))
        g = h["frames/%08d" % step]
        x0 = np.asarray(h["particles/position"][...], dtype=np.float64)
        y = x0 + np.asarray(g["displacement"][...], dtype=np.float64)
        if "damage" in g:
            dmg = np.asarray(g["damage"][...], dtype=np.float64)
        else:
            off = pdh5.bonds(h)[0]
            fam = np.diff(off)
            bits = np.unpackbits(np.asarray(g["state"][...], dtype=np.uint8),
                                 bitorder="little")[:off[-1]]
            kept = np.add.reduceat(bits.astype(np.int64), off[:-1])
            dmg = np.where(fam > 0, 1.0 - np.where(fam > 0, kept, 0) / np.maximum(fam, 1), 0.0)
        spacing = float(h["particles"].attrs["spacing"])
    return step, x0, y, dmg, spacing


def lammps_frame(path, step):
    """Step-0 positions, positions and damage at STEP (default last), by id."""
    frames = {}
    last = None
    with open(path) as f:
        lines = iter(f)
        for line in lines:
            if not line.startswith("ITEM: TIMESTEP"):
                continue
            s = int(next(lines))
            next(lines)
            n = int(next(lines))
            for _ in range(4):
                next(lines)
            cols = next(lines).split()[2:]
            rows = [next(lines) for _ in range(n)]
            last = s
            if s == 0 or s == step or step is None:
                frames[s] = (cols, rows)
                if step is None:  # keep step 0 and the latest only
                    for k in [k for k in frames if k not in (0, s)]:
                        del frames[k]
    step = last if step is None else step
    if 0 not in frames or step not in frames:
        raise SystemExit("damage-xz.py: error: %s has no step 0 or no step %s" % (path, step))

    def table(cols, rows):
        a = np.loadtxt(rows, dtype=np.float64, ndmin=2)
        a = a[np.argsort(a[:, cols.index("id")], kind="stable")]
        dcol = [c for c in cols if c.startswith("c_")]
        return (a[:, [cols.index(c) for c in ("x", "y", "z")]],
                a[:, cols.index(dcol[0])] if dcol else np.zeros(len(a)))

    x0, _ = table(*frames[0])
    y, dmg = table(*frames[step])
    zs = np.unique(np.round(x0[:, 1], 12))
    spacing = float(np.min(np.diff(zs))) if len(zs) > 1 else 1.0
    return step, x0, y, dmg, spacing


def main(argv):
    if not argv or argv[0] in ("-h", "--help"):
        sys.stderr.write(__doc__)
        return 2
    lammps = argv[0] == "--lammps"
    if lammps:
        argv = argv[1:]
    if len(argv) not in (1, 2):
        sys.stderr.write(__doc__)
        return 2
    step = int(argv[1]) if len(argv) == 2 else None
    step, x0, y, dmg, spacing = (lammps_frame if lammps else pd_frame)(argv[0], step)
    top = x0[:, 1] > x0[:, 1].max() - 0.5 * spacing
    idx = np.nonzero(top)[0]
    idx = idx[np.argsort(dmg[idx], kind="stable")]
    out = sys.stdout
    out.write("# %s step %d, top monolayer (reference y = %g m), %d particles\n"
              % ("LAMMPS" if lammps else "pd", step, x0[:, 1].max(), len(idx)))
    out.write("# x z damage\n")
    np.savetxt(out, np.column_stack([y[idx, 0], y[idx, 2], dmg[idx]]), fmt="%.6e %.6e %.4f")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
