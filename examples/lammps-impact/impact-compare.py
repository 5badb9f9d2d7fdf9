#!/usr/bin/python3
"""impact-compare.py -- pd against LAMMPS on the seed impact, step by step.

Usage:
  /usr/bin/python3 impact-compare.py RUN.h5 DUMP [--steps 100,300,2000] [-o DIR]

RUN.h5 is pd-run's output of impact.scene (frames every 100 steps, damage
added by pd-damage or not: it is recomputed from the bond state when a
frame has none); DUMP is the LAMMPS text dump of in.impact (`dump custom
... id type x y z c_C1`, sorted by id, with its step-0 frame).

The seed script makes its atoms with create_atoms, so LAMMPS's atom IDs
are not pd's /particles/id (they even depend on the number of MPI ranks).
Particles are matched by their reference lattice site instead: the step-0
frame's x/spacing, y/spacing, z/spacing rounded to integers, the same for
pd's /particles/position.

For every step it writes
  DIR/pd-stepNNNNN.txt      pd's broken bonds and damage histogram
  DIR/lammps-stepNNNNN.txt  the same for LAMMPS
and, to stdout and DIR/compare.txt, one side-by-side table of all steps.

Broken bonds: pd's from the frame's bond state bits; LAMMPS's reconstructed
as sum_i k_i / 2 with k_i = round(damage_i n_i) the broken bonds of
particle i and n_i its family size from pd's /bonds (exact for equal
particle volumes, which is what compute damage/atom weights by).  The
histogram bins the damage k_i/n_i of each particle (counted in both codes
from k_i, so a damage of exactly 0.1 falls in (0,0.1] in both codes
whatever its last bit): 0, (0,0.1], (0.1,0.2], ..., (0.9,1].

Also reported: particles whose damage differs between the codes, and the
largest difference of current positions, max |y_pd - y_lmp| (m; in.impact
prints them with %.17g, so one ulp, ~7e-18 m at 0.037 m, is resolved).
"""
import argparse
import os
import sys

import h5py
import numpy as np

# share/pdh5.py of this source tree (installed: $(PREFIX)/share/pd/python):
# the bonds of /bonds in either form (lists or a lattice stencil)
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "share"))
import pdh5  # noqa: E402

BINS = ["0"] + ["(%.1f,%.1f]" % (k / 10, (k + 1) / 10) for k in range(10)]


def read_dump(path, want):
    """{step: (columns, array)} of a LAMMPS text dump, only the steps in want."""
    frames = {}
    with open(path) as f:
        lines = iter(f)
        for line in lines:
            if not line.startswith("ITEM: TIMESTEP"):
                continue
            step = int(next(lines))
            next(lines)
            n = int(next(lines))
            for _ in range(4):
                next(lines)
            item = next(lines)
            if not item.startswith("ITEM: ATOMS"):
                raise SystemExit("impact-compare.py: error: %s: no ITEM: ATOMS at step %d"
                                 % (path, step))
            cols = item.split()[2:]
            if step in want:
                a = np.loadtxt((next(lines) for _ in range(n)), dtype=np.float64, ndmin=2)
                frames[step] = (cols, a)
            else:
                for _ in range(n):
                    next(lines)
    return frames


def site_keys(x, spacing):
    """One int64 per lattice site of reference positions x (N,3)."""
    i = np.rint(x / spacing).astype(np.int64) + (1 << 20)
    return (i[:, 0] << 42) | (i[:, 1] << 21) | i[:, 2]


def histogram(k, n):
    """Particles per damage bin; k broken of n bonds (integers)."""
    h = np.zeros(11, dtype=np.int64)
    has = n > 0
    kk, nn = k[has], n[has]
    b = np.where(kk == 0, 0, (10 * kk + nn - 1) // nn)  # ceil(10 k/n), 0 for k=0
    np.add.at(h, b, 1)
    h[0] += int((~has).sum())
    return h


def describe(code, step, k, n, dmg):
    broken = int(k.sum())
    lines = ["# %s, step %d: broken bonds and damage histogram" % (code, step),
             "broken_bonds %d" % (broken // 2),
             "damaged_particles %d" % int((k > 0).sum()),
             "max_damage %.6f" % float(dmg.max()),
             "mean_damage %.6f" % float(dmg.mean()),
             "# bin particles"]
    lines += ["%-10s %d" % (b, c) for b, c in zip(BINS, histogram(k, n))]
    return "\n".join(lines) + "\n"


def main(argv):
    ap = argparse.ArgumentParser(prog="impact-compare.py",
                                 description="Compare pd and LAMMPS on the seed impact.")
    ap.add_argument("run", help="pd-run output of impact.scene")
    ap.add_argument("dump", help="LAMMPS dump of in.impact")
    ap.add_argument("--steps", default="100,300,2000", help="steps (default 100,300,2000)")
    ap.add_argument("-o", "--outdir", default="results", help="output directory (results)")
    a = ap.parse_args(argv)
    steps = [int(s) for s in a.steps.split(",")]

    frames = read_dump(a.dump, set([0] + steps))
    missing = [s for s in [0] + steps if s not in frames]
    if missing:
        raise SystemExit("impact-compare.py: error: %s has no step %s"
                         % (a.dump, ",".join(map(str, missing))))

    with h5py.File(a.run, "r") as h:
        x0 = np.asarray(h["particles/position"][...], dtype=np.float64)
        spacing = float(h["particles"].attrs["spacing"])
        off = pdh5.bonds(h)[0]
        fam = np.diff(off)
        nbond = int(off[-1])
        pd = {}
        for s in steps:
            name = "frames/%08d" % s
            if name not in h:
                raise SystemExit("impact-compare.py: error: %s has no frame %d" % (a.run, s))
            g = h[name]
            intact = np.unpackbits(np.asarray(g["state"][...], dtype=np.uint8),
                                   bitorder="little")[:nbond]
            kept = np.add.reduceat(intact.astype(np.int64), off[:-1]) if nbond else 0
            kept = np.where(fam > 0, kept, 0)
            y = x0 + np.asarray(g["displacement"][...], dtype=np.float64)
            pd[s] = (fam - kept, y)

    # LAMMPS rows -> pd particles, through the step-0 lattice sites
    cols0, d0 = frames[0]
    xyz = [cols0.index(c) for c in ("x", "y", "z")]
    kl = site_keys(d0[:, xyz], spacing)
    kp = site_keys(x0, spacing)
    ol, op = np.argsort(kl), np.argsort(kp)
    if len(kl) != len(kp) or not np.array_equal(kl[ol], kp[op]):
        raise SystemExit("impact-compare.py: error: the lattices differ (pd %d, LAMMPS %d "
                         "particles, or other sites)" % (len(kp), len(kl)))
    row_of_pd = np.empty(len(kp), dtype=np.int64)
    row_of_pd[op] = ol                      # pd particle i is LAMMPS row row_of_pd[i] at step 0
    lid0 = d0[:, cols0.index("id")].astype(np.int64)
    id_of_pd = lid0[row_of_pd]
    ref_dx = np.abs(d0[row_of_pd][:, xyz] - x0).max()

    os.makedirs(a.outdir, exist_ok=True)
    rows = []
    for s in steps:
        cols, d = frames[s]
        lid = d[:, cols.index("id")].astype(np.int64)
        at = {int(i): r for r, i in enumerate(lid)}
        perm = np.array([at[int(i)] for i in id_of_pd])
        d = d[perm]
        dcol = [c for c in cols if c.startswith("c_")][0]
        dl = d[:, cols.index(dcol)]
        kl_ = np.rint(dl * fam).astype(np.int64)
        kp_, yp = pd[s]
        dp = np.where(fam > 0, kp_ / np.maximum(fam, 1), 0.0)
        yl = d[:, [cols.index(c) for c in ("x", "y", "z")]]
        with open(os.path.join(a.outdir, "pd-step%05d.txt" % s), "w") as f:
            f.write(describe("pd", s, kp_, fam, dp))
        with open(os.path.join(a.outdir, "lammps-step%05d.txt" % s), "w") as f:
            f.write(describe("LAMMPS", s, kl_, fam, dl))
        rows.append((s, int(kp_.sum()) // 2, int(kl_.sum()) // 2, histogram(kp_, fam),
                     histogram(kl_, fam), int((kp_ != kl_).sum()),
                     float(np.abs(yp - yl).max())))

    out = ["pd (%s) against LAMMPS (%s), %d particles, %d bonds"
           % (a.run, a.dump, len(x0), nbond // 2),
           "reference positions: max |x_pd - x_lmp| = %.3g m at step 0" % ref_dx, ""]
    out.append("%-22s" % "" + "".join("%-22s" % ("step %d" % s) for s in steps))
    out.append("%-22s" % "" + "".join("%10s %10s  " % ("pd", "LAMMPS") for _ in steps))
    out.append("%-22s" % "broken bonds" + "".join("%10d %10d  " % (r[1], r[2]) for r in rows))
    out.append("%-22s" % "damaged particles"
               + "".join("%10d %10d  " % (len(x0) - r[3][0], len(x0) - r[4][0]) for r in rows))
    for b in range(11):
        out.append("%-22s" % ("damage " + BINS[b])
                   + "".join("%10d %10d  " % (r[3][b], r[4][b]) for r in rows))
    out.append("%-22s" % "damage differs" + "".join("%21d  " % r[5] for r in rows))
    out.append("%-22s" % "max |y_pd - y_lmp| m" + "".join("%21.3g  " % r[6] for r in rows))
    text = "\n".join(out) + "\n"
    with open(os.path.join(a.outdir, "compare.txt"), "w") as f:
        f.write(text)
    sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
