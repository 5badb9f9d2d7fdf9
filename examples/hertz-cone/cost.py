"""cost.py -- the Hertzian cone at 80 us against what a run costs.

usage: /usr/bin/python3 cost.py --spacing "DX-M..." --m "DX-M..." --s0 "DX-M..."
       > cost.txt

Reads conv/run-DX-M.{h5,log,time} (spacing DX, m = delta / DX, the
fracture energy held) for the spacing and m sweeps, conv/s0-DX-M.* (the
critical stretch held) for the s0 sweep, and prints one row per run of each
sweep: share/pdcost.py's leading columns (setting: dx in mm for the spacing
sweeps, m for the m sweep), then

  dx_mm m horizon_mm angle_deg depth_mm rebound_m_s err_angle err_depth
  err_rebound broken

measured on the last frame, at reference positions, on the particles with
damage > 0.3 (r the distance from the axis, z the depth below the top
face):

  angle_deg   the cone's half-angle from the axis: a least-squares line
              through the median r of each lattice layer between z = -2.5
              and -7.5 mm (below the crushed zone under the sphere, above
              the turn of the crack), atan of its slope dr/d(-z); nan where
              fewer than 3 layers hold 3 such particles (no cone)
  depth_mm    how deep the damage reaches: the 98th percentile of -z
  rebound_m_s the sphere's velocity along z once it has left

err_*: relative errors against the sweep's finest run (the smallest dx of
the spacing sweeps, the largest m of the m sweep).  The depth is read off
lattice layers, so its error is of the order of the spacing; the comment
lines at the end say which setting is the cheapest within 5%.
"""
import argparse
import math
import os
import sys

import h5py
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "share"))
import pdcost  # noqa: E402

DAMAGED = 0.3
BAND = (-7.5e-3, -2.5e-3)  # m: the layers of the cone's fit
FIGURES = ["dx_mm", "m", "horizon_mm", "angle_deg", "depth_mm", "rebound_m_s", "err_angle",
           "err_depth", "err_rebound", "broken"]


def cone(x0, dmg, dx):
    """(angle_deg, depth_mm) of the damage of the last frame."""
    hit = dmg > DAMAGED
    r, z = np.hypot(x0[hit, 0], x0[hit, 1]), x0[hit, 2]
    depth = float(np.percentile(-z, 98)) * 1e3 if hit.any() else 0.0
    layer = np.round(z / dx).astype(np.int64)
    pts = []
    for k in np.unique(layer):
        zk = k * dx
        on = layer == k
        if BAND[0] - 1e-9 <= zk <= BAND[1] + 1e-9 and on.sum() >= 3:
            pts.append((-zk, float(np.median(r[on]))))
    if len(pts) < 3:
        return float("nan"), depth
    slope = np.polyfit(*np.array(pts).T, 1)[0]
    return math.degrees(math.atan(slope)), depth


def run(name, sweep):
    stem = ("conv/s0-" if sweep == "s0" else "conv/run-") + name
    c = pdcost.run_cost(stem)
    dx, m = (float(v) for v in name.split("-"))
    with h5py.File(stem + ".h5", "r") as f:
        last = f["frames"][sorted(f["frames"])[-1]]
        x0 = f["particles/position"][()]
        angle, depth = cone(x0, last["damage"][()], dx)
        c.update(particles=x0.shape[0], bonds=int(f["bonds"].attrs["count"]) // 2,
                 horizon_mm=float(f["bonds"].attrs["horizon"]) * 1e3,
                 rebound_m_s=float(last.attrs["projectile_velocity"][2]),
                 broken=int(last.attrs["broken_bonds"]))
    c.update(sweep=sweep, setting="%g" % (m if sweep == "m" else dx * 1e3), dx_mm=dx * 1e3,
             m=m, angle_deg=angle, depth_mm=depth)
    return c


def sweep(names, kind, finest):
    rows = [run(n, kind) for n in names]
    ref = finest(rows)
    for r in rows:
        for k, e in (("angle_deg", "err_angle"), ("depth_mm", "err_depth"),
                     ("rebound_m_s", "err_rebound")):
            r[e] = pdcost.relerr(r[k], ref[k])
        errs = [r["err_angle"], r["err_depth"], r["err_rebound"]]
        r["err_all"] = float("nan") if any(math.isnan(e) for e in errs) else max(errs)
    return rows, ref


def main():
    ap = argparse.ArgumentParser(prog="cost.py")
    ap.add_argument("--spacing", required=True)
    ap.add_argument("--m", required=True)
    ap.add_argument("--s0", required=True)
    a = ap.parse_args()
    finest = lambda rows: min(rows, key=lambda r: r["dx_mm"])  # noqa: E731
    by_dx, ref_dx = sweep(a.spacing.split(), "spacing", finest)
    by_m, ref_m = sweep(a.m.split(), "m", lambda rows: max(rows, key=lambda r: r["m"]))
    by_s0, ref_s0 = sweep(a.s0.split(), "s0", finest)
    rows = (sorted(by_dx, key=lambda r: -r["dx_mm"]) + sorted(by_m, key=lambda r: r["m"]) +
            sorted(by_s0, key=lambda r: -r["dx_mm"]))
    pdcost.write(rows, FIGURES)
    print("# reference of the spacing sweeps: dx = %g mm (m = %g); of the m sweep: m = %g "
          "(dx = %g mm)" % (ref_dx["dx_mm"], ref_dx["m"], ref_m["m"], ref_m["dx_mm"]))
    for kind, rs, ref in (("spacing", by_dx, ref_dx), ("m", by_m, ref_m), ("s0", by_s0, ref_s0)):
        pdcost.say_cheapest(kind, rs, ref, (
            ("err_angle", "the cone angle"), ("err_rebound", "the rebound velocity"),
            ("err_all", "the cone angle, its depth and the rebound together")))


if __name__ == "__main__":
    main()
