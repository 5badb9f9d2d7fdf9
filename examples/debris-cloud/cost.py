"""cost.py -- the debris cloud at 230 us against what a run costs.

usage: /usr/bin/python3 cost.py DX... > cost.txt

Reads conv/run-DX.{h5,log,time,frag} (spacing DX in m, m = 3, the fracture
energy held) and prints one row per run: share/pdcost.py's leading columns
(setting: dx in mm), then

  dx_mm horizon_mm lead_m_s spread_mm debris_fraction sphere_m_s
  largest_fraction err_lead err_spread err_debris err_sphere err_largest
  fragments broken

measured on the last frame.  The cloud is every particle whose current
position lies more than 2.5 mm below the disk's bottom face (z < -5 mm);
all particles of a grid have one volume, so shares of them are shares of
mass:

  lead_m_s         the cloud's leading velocity: the 99th percentile of
                   its particles' downward velocity
  spread_mm        its spread: the 90th percentile of their distance from
                   the axis
  debris_fraction  the share of the disk's volume outside its largest
                   fragment (pd-damage --fragments: the pieces the intact
                   bonds hold together), what the impact broke away
  sphere_m_s       the sphere's residual speed
  largest_fraction the largest fragment's share of the disk's volume (1 -
                   debris_fraction: where the disk shatters, its error is
                   the sharper measure)
  fragments        the number of fragments (single particles count: it
                   grows as the grid refines, and has no error here)

err_*: relative errors against the finest run (the smallest dx); the
comment lines at the end say which spacing is the cheapest within 5%.
"""
import math
import os
import sys

import h5py
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "share"))
import pdcost  # noqa: E402

CLOUD = -5e-3  # m: below this current z a particle is in the cloud
FIGURES = ["dx_mm", "horizon_mm", "lead_m_s", "spread_mm", "debris_fraction", "sphere_m_s",
           "largest_fraction", "err_lead", "err_spread", "err_debris", "err_sphere",
           "err_largest", "fragments", "broken"]
ERRS = (("lead_m_s", "err_lead"), ("spread_mm", "err_spread"),
        ("debris_fraction", "err_debris"), ("sphere_m_s", "err_sphere"),
        ("largest_fraction", "err_largest"))


def fragments(path):
    """(fragments, largest_fraction) of the last row of pd-damage's table."""
    with open(path) as f:
        head, *rows = [line.split() for line in f if line.strip()]
    last = dict(zip(head[1:], rows[-1]))
    return int(last["fragments"]), float(last["largest_fraction"])


def run(name):
    stem = "conv/run-" + name
    c = pdcost.run_cost(stem)
    with h5py.File(stem + ".h5", "r") as f:
        last = f["frames"][sorted(f["frames"])[-1]]
        x = f["particles/position"][()] + last["displacement"][()]
        v = last["velocity"][()]
        cloud = x[:, 2] < CLOUD
        c.update(particles=x.shape[0], bonds=int(f["bonds"].attrs["count"]) // 2,
                 horizon_mm=float(f["bonds"].attrs["horizon"]) * 1e3,
                 sphere_m_s=-float(last.attrs["projectile_velocity"][2]),
                 broken=int(last.attrs["broken_bonds"]))
    if cloud.sum() < 10:
        raise SystemExit("cost.py: %s: no debris cloud below z = %g m" % (stem, CLOUD))
    pieces, largest = fragments(stem + ".frag")
    c.update(sweep="spacing", setting="%g" % (float(name) * 1e3), dx_mm=float(name) * 1e3,
             lead_m_s=float(np.percentile(-v[cloud, 2], 99)),
             spread_mm=float(np.percentile(np.hypot(x[cloud, 0], x[cloud, 1]), 90)) * 1e3,
             debris_fraction=1.0 - largest, largest_fraction=largest, fragments=pieces)
    return c


def main():
    if len(sys.argv) < 3:
        raise SystemExit("usage: cost.py DX... (two or more spacings, m)")
    rows = sorted((run(n) for n in sys.argv[1:]), key=lambda r: -r["dx_mm"])
    ref = rows[-1]
    for r in rows:
        for k, e in ERRS:
            r[e] = pdcost.relerr(r[k], ref[k])
        r["err_all"] = max(r[e] for _, e in ERRS)
    pdcost.write(rows, FIGURES)
    print("# reference: the finest run, dx = %g mm (m = 3)" % ref["dx_mm"])
    pdcost.say_cheapest("spacing", rows, ref, (
        ("err_lead", "the leading velocity"), ("err_spread", "the spread"),
        ("err_debris", "the debris fraction"), ("err_sphere", "the sphere's speed"),
        ("err_largest", "the largest fragment's share"),
        ("err_all", "the five figures together")), unit=" mm")

if __name__ == "__main__":
    main()
