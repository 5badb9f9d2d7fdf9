#!/usr/bin/python3
"""frames.py -- tables for gnuplot from a pd-run with --projectile.

Usage: /usr/bin/python3 frames.py slice RUN.h5 [STEP] > slice.dat
       /usr/bin/python3 frames.py top RUN.h5 [STEP] > top.dat
       /usr/bin/python3 frames.py side RUN.h5 [STEP] > side.dat
       /usr/bin/python3 frames.py velocity RUN.h5 > velocity.dat

slice     'x z damage' of the lattice plane of reference y nearest 0 (the
          x-z plane through the axis), at their reference positions (the
          body as a whole moves after the impact), at STEP (default: the
          last frame);
top       'x y damage' of the top monolayer (largest reference z);
side      'x z damage' of every particle (the side view, all of y);
velocity  'time_us vx vy vz z_mm' of the projectile, one line per frame,
          from the frames' projectile_velocity and projectile_position.

Damage is the frame's 'damage' (pd-damage) or, without it, the broken
fraction of each bond family.  Rows are sorted by damage so that the most
damaged particles are drawn last.  '#' lines say the step and the counts.
"""
import os
import sys

import h5py
import numpy as np

# share/pdh5.py of this source tree (installed: $(PREFIX)/share/pd/python):
# the bonds of /bonds in either form (lists or a lattice stencil)
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "share"))
import pdh5  # noqa: E402


def frame(h, step):
    steps = sorted(int(k) for k in h["frames"] if h["frames"][k].attrs.get("complete", 1) == 1)
    step = steps[-1] if step is None else step
    if "frames/%08d" % step not in h:
        raise SystemExit("frames.py: error: no frame %d" % step)
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
        kept = np.add.reduceat(bits.astype(np.int64), off[:-1]) if off[-1] else 0 * fam
        dmg = np.where(fam > 0, 1.0 - kept / np.maximum(fam, 1), 0.0)
    spacing = float(h["particles"].attrs["spacing"])
    return step, x0, y, dmg, spacing


def table(out, what, step, idx, cols, dmg, header):
    idx = idx[np.argsort(dmg[idx], kind="stable")]
    out.write("# %s, step %d, %d particles\n" % (what, step, len(idx)))
    out.write("# %s damage\n" % header)
    np.savetxt(out, np.column_stack([c[idx] for c in cols] + [dmg[idx]]),
               fmt="%.6e %.6e %.4f")


def main(argv):
    if len(argv) < 2 or argv[0] not in ("slice", "top", "side", "velocity"):
        sys.stderr.write(__doc__)
        return 2
    mode, path = argv[0], argv[1]
    step = int(argv[2]) if len(argv) > 2 else None
    out = sys.stdout
    with h5py.File(path, "r") as h:
        if mode == "velocity":
            out.write("# time_us vx vy vz (m/s) z_mm of the projectile\n")
            for k in sorted(h["frames"], key=lambda k: int(h["frames"][k].attrs["step"])):
                a = h["frames"][k].attrs
                if a.get("complete", 1) != 1 or "projectile_velocity" not in a:
                    continue
                v, x = a["projectile_velocity"], a["projectile_position"]
                out.write("%.6f %.6e %.6e %.6e %.6f\n"
                          % (a["time"] * 1e6, v[0], v[1], v[2], x[2] * 1e3))
            return 0
        step, x0, y, dmg, spacing = frame(h, step)
    if mode == "slice":
        y0 = x0[np.argmin(np.abs(x0[:, 1])), 1]  # the lattice plane nearest y = 0
        idx = np.nonzero(np.abs(x0[:, 1] - y0) < 0.5 * spacing)[0]
        table(out, "x-z slice through the axis (reference y = %g m), reference positions" % y0,
              step, idx, [x0[:, 0], x0[:, 2]], dmg, "x z")
    elif mode == "top":
        idx = np.nonzero(x0[:, 2] > x0[:, 2].max() - 0.5 * spacing)[0]
        table(out, "top monolayer (reference z = %g m)" % x0[:, 2].max(), step, idx,
              [y[:, 0], y[:, 1]], dmg, "x y")
    else:
        idx = np.arange(len(dmg))
        table(out, "side view, all particles", step, idx, [y[:, 0], y[:, 2]], dmg, "x z")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
