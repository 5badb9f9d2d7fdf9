#!/usr/bin/python3
"""compare.py -- compare a pd run with a LAMMPS peri run of the same scene.

Usage:
  /usr/bin/python3 tests/lammps/compare.py [options] RUN.h5 DUMP [--step N]

RUN.h5 is pd-run's output (after pd-damage, or not: damage is computed here
from the bond state when /frames/<step>/damage is missing); DUMP is the
LAMMPS text dump written by the script of pd2lmp.py (`dump custom ... id x
y z vx vy vz c_damage`, any column order, with %.17g numbers).  The frame
compared is --step (default: the last step the dump and the run both have).
Particles are matched by id (/particles/id = LAMMPS atom-ID).

Metrics (each a maximum over all particles and components):
  pos_rel   max |y_pd - y_lmp| / max |y_lmp|
            y = current position (pd: /particles/position + displacement);
            the scale max|y_lmp| is the body's size (its largest
            coordinate), so this is "positions agree to pos_rel relative".
            Checked against --pos-tol (default 1e-9).
  pos_sp    max |y_pd - y_lmp| / spacing: the same difference in lattice
            spacings (reported only).
  disp_rel  max |y_pd - y_lmp| / max |u_lmp|, u = y - reference position:
            the difference relative to the largest displacement, i.e. how
            well the *motion* agrees.  pos_rel alone is weak: positions are
            mostly the reference lattice (a 1e-7 relative change of dt
            moves pos_rel by only ~8e-10 in the 100-step disk, but disp_rel
            by ~4e-7).  Checked against --disp-tol (default 1e-9; 'inf'
            turns it off).  Its floor is one ulp of the coordinates over
            max |u| (~1e-18 m / max |u|), so it needs a scene that moves
            by more than ~1e-9 m, as any impact does.
  vel_rel   max |v_pd - v_lmp| / max |v_lmp| (reported; --vel-tol).
  dmg_abs   max |damage_pd - damage_lmp| (absolute; damage is a fraction
            in [0, 1]).  Checked against --damage-tol (default 1e-12).
Also printed: the number of particles with damage > 0 in each code, and
the number of broken bonds: pd's from its bond state bits, LAMMPS's
reconstructed as sum_i round(damage_i * n_i) / 2 with n_i the family
size of i from pd's /bonds (exact for equal particle volumes, which is what
compute damage/atom weights by).

Exit status: 0 if within tolerances, 1 if not (or ids do not match),
2 for a usage error.  With --min-damaged N, also 1 unless both codes have
at least N damaged particles (a comparison without damage proves little).
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


def read_dump(path, want=None):
    """Frames of a LAMMPS text dump: {step: (columns, array)}; only `want`
    (a step, or None for all) is parsed."""
    frames = {}
    with open(path) as f:
        lines = iter(f)
        for line in lines:
            if not line.startswith("ITEM: TIMESTEP"):
                continue
            step = int(next(lines))
            item = next(lines)
            assert item.startswith("ITEM: NUMBER OF ATOMS"), item
            n = int(next(lines))
            item = next(lines)
            assert item.startswith("ITEM: BOX BOUNDS"), item
            for _ in range(3):
                next(lines)
            item = next(lines)
            assert item.startswith("ITEM: ATOMS"), item
            cols = item.split()[2:]
            rows = [next(lines) for _ in range(n)]
            if want is None or step == want:
                # %.17g text: numpy's float parser is correctly rounded
                a = np.array([r.split() for r in rows], dtype=np.float64).reshape(n, len(cols))
                frames[step] = (cols, a)
    return frames


def main(argv):
    ap = argparse.ArgumentParser(prog="compare.py",
                                 description="Compare pd-run output with a LAMMPS peri dump.")
    ap.add_argument("run", help="pd-run output (pd-h5)")
    ap.add_argument("dump", help="LAMMPS dump (custom: id x y z vx vy vz c_damage)")
    ap.add_argument("--step", type=int, help="step to compare (default: last common)")
    ap.add_argument("--pos-tol", type=float, default=1e-9, help="tolerance on pos_rel (1e-9)")
    ap.add_argument("--damage-tol", type=float, default=1e-12, help="tolerance on dmg_abs (1e-12)")
    ap.add_argument("--disp-tol", type=float, default=1e-9,
                    help="tolerance on disp_rel (1e-9; inf: no check)")
    ap.add_argument("--vel-tol", type=float, help="tolerance on vel_rel (none)")
    ap.add_argument("--min-damaged", type=int, default=0,
                    help="fail unless both codes have at least N damaged particles")
    a = ap.parse_args(argv)

    with h5py.File(a.run, "r") as h:
        steps = sorted(int(k) for k in h["frames"].keys())
        ids = np.asarray(h["particles/id"][...], dtype=np.int64)
        x0 = np.asarray(h["particles/position"][...], dtype=np.float64)
        spacing = float(h["particles"].attrs.get("spacing", np.nan))
        off = pdh5.bonds(h)[0]
        nbond = off[-1]
        fam = np.diff(off)
        want = a.step
        dump = read_dump(a.dump, want)
        if want is None:
            common = sorted(set(steps) & set(dump))
            if not common:
                print("compare.py: error: no step in both %s and %s" % (a.run, a.dump),
                      file=sys.stderr)
                return 1
            want = common[-1]
        if want not in steps or want not in dump:
            print("compare.py: error: step %d is not in both files" % want, file=sys.stderr)
            return 1
        g = h["frames/%08d" % want]
        u = np.asarray(g["displacement"][...], dtype=np.float64)
        v = np.asarray(g["velocity"][...], dtype=np.float64)
        state = np.asarray(g["state"][...], dtype=np.uint8) if "state" in g else None
        if "damage" in g:
            dmg = np.asarray(g["damage"][...], dtype=np.float64)
        else:
            dmg = None

    intact = None
    if state is not None:
        intact = np.unpackbits(state, bitorder="little")[:nbond].astype(bool)
    if dmg is None:
        if intact is None:
            print("compare.py: error: frame %d has neither damage nor state" % want,
                  file=sys.stderr)
            return 1
        # equal-volume damage: broken fraction of each family
        kept = np.add.reduceat(intact.astype(np.float64), off[:-1]) if nbond else np.zeros(len(ids))
        kept[fam == 0] = 0
        dmg = np.where(fam > 0, 1.0 - kept / np.maximum(fam, 1), 0.0)

    cols, d = dump[want]
    need = ["id", "x", "y", "z", "vx", "vy", "vz"]
    for c in need:
        if c not in cols:
            print("compare.py: error: dump has no column %s" % c, file=sys.stderr)
            return 1
    dcol = [c for c in cols if c.startswith("c_")]
    if not dcol:
        print("compare.py: error: dump has no damage column (c_...)", file=sys.stderr)
        return 1
    lid = d[:, cols.index("id")].astype(np.int64)
    if len(lid) != len(ids) or not np.array_equal(np.sort(lid), np.sort(ids)):
        print("compare.py: error: the particle ids differ (pd %d, LAMMPS %d particles)"
              % (len(ids), len(lid)), file=sys.stderr)
        return 1
    # LAMMPS rows in pd's particle order
    pos_of = {int(i): k for k, i in enumerate(lid)}
    perm = np.array([pos_of[int(i)] for i in ids])
    d = d[perm]
    yl = d[:, [cols.index("x"), cols.index("y"), cols.index("z")]]
    vl = d[:, [cols.index("vx"), cols.index("vy"), cols.index("vz")]]
    dl = d[:, cols.index(dcol[0])]

    yp = x0 + u
    dy = np.abs(yp - yl).max()
    scale_y = np.abs(yl).max()
    scale_u = np.abs(yl - x0).max()
    scale_v = np.abs(vl).max()
    pos_rel = dy / scale_y if scale_y > 0 else dy
    pos_sp = dy / spacing
    disp_rel = dy / scale_u if scale_u > 0 else dy
    dv = np.abs(v - vl).max()
    vel_rel = dv / scale_v if scale_v > 0 else dv
    dmg_abs = np.abs(dmg - dl).max()
    n_pd = int((dmg > 0).sum())
    n_lmp = int((dl > 0).sum())
    n_diff = int((np.abs(dmg - dl) > a.damage_tol).sum())
    broken_pd = (int(nbond - intact.sum()) // 2) if intact is not None else -1
    broken_lmp = int(np.rint(dl * fam).sum()) // 2

    print("step %d  particles %d  bonds %d" % (want, len(ids), nbond // 2))
    print("pos_rel   %.3e   (max |dy| %.3e m / max |y| %.3e m; tol %.0e)"
          % (pos_rel, dy, scale_y, a.pos_tol))
    print("pos_sp    %.3e   (max |dy| / spacing %.3e m)" % (pos_sp, spacing))
    print("disp_rel  %.3e   (max |dy| / max |u| %.3e m; tol %.0e)"
          % (disp_rel, scale_u, a.disp_tol))
    print("vel_rel   %.3e   (max |dv| %.3e m/s / max |v| %.3e m/s)" % (vel_rel, dv, scale_v))
    print("dmg_abs   %.3e   (tol %.0e; %d particles differ)" % (dmg_abs, a.damage_tol, n_diff))
    print("damaged   pd %d  lammps %d" % (n_pd, n_lmp))
    print("broken    pd %d  lammps %d" % (broken_pd, broken_lmp))
    print("max_dmg   pd %.9f  lammps %.9f" % (dmg.max(), dl.max()))

    bad = []
    if not pos_rel <= a.pos_tol:
        bad.append("positions")
    if not dmg_abs <= a.damage_tol:
        bad.append("damage")
    if not disp_rel <= a.disp_tol:
        bad.append("displacements")
    if a.vel_tol is not None and not vel_rel <= a.vel_tol:
        bad.append("velocities")
    if min(n_pd, n_lmp) < a.min_damaged:
        bad.append("too few damaged particles")
    if bad:
        print("FAIL: %s" % ", ".join(bad))
        return 1
    print("OK")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
