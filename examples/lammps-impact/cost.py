"""cost.py -- the seed impact's damage at t = 30 us against what a run costs.

usage: /usr/bin/python3 cost.py --nsteps "N..." --skins "S..." > cost.txt

Reads conv/dt-N.{h5,log,time} (the run to 30 us in N steps),
conv/skin-S.{h5,log,time} (the seed's step, --contact-skin S) and
conv/lammps/lammps-step00300.txt (impact-compare.py's count of LAMMPS's
in.impact at step 300), and prints one row per run: share/pdcost.py's
leading columns (setting: dt / dt_stable for the time step, skin / spacing
for the skin), then

  dt_s skin_m builds broken damaged err_broken err_damaged
  err_broken_lammps err_damaged_lammps

broken: the broken bonds of the last frame (its broken_bonds), damaged: the
particles with a broken bond (damage > 0).  err_*: relative errors against
the sweep's reference, the smallest step of the time-step sweep and the
skin of half a spacing (the default until 2026-12-08) of the skin sweep; err_*_lammps against
LAMMPS at its step of 0.1 us.  The comment lines at the end give the
cheapest setting within 5% of the reference, and LAMMPS's own figures.
"""
import argparse
import os
import re
import sys

import h5py
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "share"))
import pdcost  # noqa: E402

BUILDS = re.compile(r"contact list builds (\d+)")
FIGURES = ["dt_s", "skin_m", "builds", "broken", "damaged", "err_broken", "err_damaged",
           "err_broken_lammps", "err_damaged_lammps"]


def run(stem, sweep):
    c = pdcost.run_cost(stem)
    with h5py.File(stem + ".h5", "r") as f:
        last = f["frames"][sorted(f["frames"])[-1]]
        broken = int(last.attrs["broken_bonds"])
        damaged = int(np.count_nonzero(last["damage"][()] > 0))
        n = f["particles/id"].shape[0]
        bonds = int(f["bonds"].attrs["count"]) // 2
        spacing = float(f["particles/radius"][0]) * 2
        scene = f["scene"].attrs
        dt, stable, skin = (float(scene[k]) for k in ("dt", "dt_stable", "contact_skin"))
    builds = BUILDS.search(c["log"])
    setting = dt / stable if sweep == "safety" else skin / spacing
    c.update(sweep=sweep, setting="%.3g" % setting, particles=n, bonds=bonds, dt_s=dt,
             skin_m=skin, builds=int(builds.group(1)) if builds else -1, broken=broken,
             damaged=damaged)
    return c


def lammps(path):
    text = open(path).read()
    return {k: int(re.search(r"^%s (\d+)$" % k, text, re.M).group(1))
            for k in ("broken_bonds", "damaged_particles")}


def errors(rows, ref, lmp):
    for r in rows:
        r["err_broken"] = pdcost.relerr(r["broken"], ref["broken"])
        r["err_damaged"] = pdcost.relerr(r["damaged"], ref["damaged"])
        r["err_broken_lammps"] = pdcost.relerr(r["broken"], lmp["broken_bonds"])
        r["err_damaged_lammps"] = pdcost.relerr(r["damaged"], lmp["damaged_particles"])


def main():
    ap = argparse.ArgumentParser(prog="cost.py")
    ap.add_argument("--nsteps", required=True)
    ap.add_argument("--skins", required=True)
    a = ap.parse_args()
    lmp = lammps("conv/lammps/lammps-step00300.txt")
    steps = [run("conv/dt-%s" % n, "safety") for n in a.nsteps.split()]
    skins = [run("conv/skin-%s" % s, "skin") for s in a.skins.split()]
    errors(steps, min(steps, key=lambda r: r["dt_s"]), lmp)
    default = [r for r in skins if abs(float(r["setting"]) - 0.5) < 1e-9]
    if not default:
        raise SystemExit("cost.py: the skins hold no run at half a spacing")
    errors(skins, default[0], lmp)
    rows = sorted(steps, key=lambda r: -r["dt_s"]) + sorted(skins, key=lambda r: r["skin_m"])
    pdcost.write(rows, FIGURES)
    finest = min(steps, key=lambda r: r["dt_s"])
    best = pdcost.cheapest(steps, "err_broken")
    print("# reference of the time step: the smallest, dt = %.4g s (safety %s); of the skin: "
          "half a spacing" % (finest["dt_s"], finest["setting"]))
    wall, peak_kb = (float(v) for v in open("conv/lammps/lammps.time").read().split()[-2:])
    print("# LAMMPS (mpirun -np 2, dt 1e-7 s) at step 300: broken %d damaged %d, wall %.2f s, "
          "peak %.0f MiB (the largest of its processes)" % (lmp["broken_bonds"], lmp["damaged_particles"],
                                                   wall, peak_kb / 1024))
    if best:
        print("# cheapest time step within 5%% of the smallest on the broken bonds: safety %s, "
              "wall %.2f s against %.2f s (%.2f)" % (best["setting"], best["wall"],
                                                    finest["wall"], best["wall"] / finest["wall"]))


if __name__ == "__main__":
    main()
