#!/usr/bin/python3
"""beam.py -- tables for gnuplot from a pd-run of the anisotropic beam.

Usage: /usr/bin/python3 beam.py stress RUN.h5 > stress.dat
       /usr/bin/python3 beam.py slice RUN.h5 > slice.dat
       /usr/bin/python3 beam.py compare CASE... > static.txt

stress  'time_ms sigma_xx_MPa' per complete frame: the mean axial
        peridynamic stress (the frames' 'stress', pd-run --fields stress)
        over the middle third of the beam (100 mm < x < 200 mm); negative
        is compression;
slice   'x_mm y_mm damage' at the last frame, of the lattice plane of
        reference z nearest the beam's mid-height, at the deformed x and
        y, sorted by damage (the most damaged drawn last);
compare per CASE, from stress-dynamic-CASE.dat, stress-static-CASE.dat and
        the logs dynamic-CASE.log, static-CASE.log (make static): the peak
        compression of the dynamic and of the quasi-static run and when,
        their largest difference at the quasi-static run's times (up to
        its peak), and the wall time of each (the relaxation's iterations
        too).
"""
import re
import sys

import h5py
import numpy as np


def frames(h):
    return sorted((g for g in h["frames"].values() if g.attrs.get("complete", 1) == 1),
                  key=lambda g: g.attrs["step"])


def wall(log):
    """The wall time of a pd-run log, s, and its iterations (0: dynamic)."""
    text = open(log).read()
    m = re.search(r"load steps, (\d+) iterations, in ([0-9.]+) s", text)
    if m:
        return float(m.group(2)), int(m.group(1))
    return float(re.search(r"steps in ([0-9.]+) s", text).group(1)), 0


def compare(cases):
    print("# case  dynamic: peak -sigma_xx MPa, at ms, wall s   "
          "static: peak MPa, at ms, wall s, iterations   "
          "largest |dynamic - static| up to the static peak, MPa")
    for c in cases:
        d = np.loadtxt("stress-dynamic-%s.dat" % c, ndmin=2)
        q = np.loadtxt("stress-static-%s.dat" % c, ndmin=2)
        kd, kq = np.argmin(d[:, 1]), np.argmin(q[:, 1])
        common = [(t, s) for t, s in q[: kq + 1] if np.isclose(d[:, 0], t, rtol=1e-6).any()]
        diff = max(abs(s - d[np.isclose(d[:, 0], t, rtol=1e-6), 1][0]) for t, s in common)
        wd, _ = wall("dynamic-%s.log" % c)
        wq, it = wall("static-%s.log" % c)
        print("%-8s %6.1f %6.3f %7.1f   %6.1f %6.3f %7.1f %7d   %6.1f" %
              (c, -d[kd, 1], d[kd, 0], wd, -q[kq, 1], q[kq, 0], wq, it, diff))


def main():
    if len(sys.argv) > 2 and sys.argv[1] == "compare":
        compare(sys.argv[2:])
        return
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
