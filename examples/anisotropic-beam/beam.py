#!/usr/bin/python3
"""beam.py -- tables for gnuplot from a pd-run of the anisotropic beam.

Usage: /usr/bin/python3 beam.py stress RUN.h5 > stress.dat
       /usr/bin/python3 beam.py slice RUN.h5 > slice.dat

stress  'time_ms sigma_xx_MPa' per complete frame: the mean axial
        peridynamic stress (the frames' 'stress', pd-run --fields stress)
        over the middle third of the beam (100 mm < x < 200 mm); negative
        is compression;
slice   'x_mm y_mm damage' at the last frame, of the lattice plane of
        reference z nearest the beam's mid-height, at the deformed x and
        y, sorted by damage (the most damaged drawn last).
"""
import sys

import h5py
import numpy as np


def frames(h):
    return sorted((g for g in h["frames"].values() if g.attrs.get("complete", 1) == 1),
                  key=lambda g: g.attrs["step"])


def main():
    if len(sys.argv) != 3 or sys.argv[1] not in ("stress", "slice"):
        raise SystemExit(__doc__.split("\n\n")[1])
    with h5py.File(sys.argv[2], "r") as h:
        x0 = np.asarray(h["particles/position"][...], dtype=np.float64)
        if sys.argv[1] == "stress":
            mid = (x0[:, 0] > 0.1) & (x0[:, 0] < 0.2)
            print("# time_ms mean_sigma_xx_MPa over 100 < x < 200 mm (%d particles)" % mid.sum())
            for g in frames(h):
                s = np.asarray(g["stress"][...], dtype=np.float64)
                print("%.6g %.6g" % (1e3 * g.attrs["time"], 1e-6 * s[mid, 0, 0].mean()))
        else:
            g = frames(h)[-1]
            y = x0 + np.asarray(g["displacement"][...], dtype=np.float64)
            zs = np.unique(np.round(x0[:, 2], 9))
            zmid = zs[np.argmin(np.abs(zs - 0.5 * (zs[0] + zs[-1])))]
            sel = np.abs(x0[:, 2] - zmid) < 1e-9
            dmg = np.asarray(g["damage"][...], dtype=np.float64)[sel]
            order = np.argsort(dmg, kind="stable")
            print("# step %d, plane z = %.4g mm, %d particles" % (g.attrs["step"], 1e3 * zmid, sel.sum()))
            for i in order:
                print("%.6g %.6g %.6g" % (1e3 * y[sel][i, 0], 1e3 * y[sel][i, 1], dmg[i]))


main()
