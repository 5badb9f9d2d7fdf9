"""cost.py -- the library example's block against what a run costs.

usage: /usr/bin/python3 cost.py DX... > cost.txt

Reads conv/run-DX.{h5,txt,log,time} (`impact RUN.h5 DX`: the block at
spacing DX in m, m = 3, the fracture energy held, to 23 us) and prints one
row per run: share/pdcost.py's leading columns (setting: dx in mm), then

  dx_mm sphere_m_s released_J balance_J err_sphere err_released
  err_balance broken

from the last frame's line of the program:

  sphere_m_s       the sphere's residual speed, sqrt(2 E / M) of its
                   kinetic energy E (M = 5 g; it comes at 100 m/s)
  released_J       the energy the broken bonds held when they broke: with
                   G0 held, about G0 times the area of the cracks made, a
                   figure that converges (the share of the bonds broken
                   does not: at a fixed crack area it falls as dx)
  balance_J        the energy balance (kinetic + elastic + contact +
                   released - work + the sphere's kinetic energy)
  err_sphere, err_released
                   relative errors against the finest run
  err_balance      against the 25 J the sphere brings: what the balance
                   lost, which is no grid error but the integrator's (and
                   that of bonds that break within a step)
  broken           the broken bonds

The comment lines at the end say which spacing is the cheapest within 5%.
"""
import os
import sys

import h5py

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "share"))
import pdcost  # noqa: E402

MASS = 0.005  # kg
BROUGHT = 0.5 * MASS * 100.0 ** 2  # J
FIGURES = ["dx_mm", "sphere_m_s", "released_J", "balance_J", "err_sphere", "err_released",
           "err_balance", "broken"]


def last_frame(path):
    """The program's last frame line, as {word: the number after it}."""
    with open(path) as f:
        lines = [ln.split() for ln in f if ln.startswith("step ")]
    if not lines:
        raise SystemExit("cost.py: %s holds no frame line" % path)
    w, out = lines[-1], {}
    for k in range(len(w) - 1):
        try:
            out[w[k]] = float(w[k + 1])
        except ValueError:
            pass
    return out


def run(dx):
    stem = "conv/run-" + dx
    c = pdcost.run_cost(stem)
    line = last_frame(stem + ".txt")
    with h5py.File(stem + ".h5", "r") as f:
        bonds = int(f["bonds"].attrs["count"]) // 2
        c.update(particles=f["particles/position"].shape[0], bonds=bonds)
    c.update(sweep="spacing", setting="%g" % (float(dx) * 1e3), dx_mm=float(dx) * 1e3,
             sphere_m_s=(2 * line["projectile"] / MASS) ** 0.5,
             released_J=line["released"], balance_J=line["balance"],
             broken=int(line["broken"]),
             err_balance=pdcost.relerr(line["balance"], BROUGHT))
    return c


def main():
    if len(sys.argv) < 2:
        raise SystemExit("usage: cost.py DX...")
    rows = sorted((run(dx) for dx in sys.argv[1:]), key=lambda r: -r["dx_mm"])
    ref = rows[-1]
    for r in rows:
        r["err_sphere"] = pdcost.relerr(r["sphere_m_s"], ref["sphere_m_s"])
        r["err_released"] = pdcost.relerr(r["released_J"], ref["released_J"])
        r["err_both"] = max(r["err_sphere"], r["err_released"])
    pdcost.write(rows, FIGURES)
    print("# reference: the finest run, dx = %g mm (the balance: the 25 J the sphere brings)"
          % ref["dx_mm"])
    pdcost.say_cheapest("spacing", rows, ref, (
        ("err_sphere", "the sphere's residual speed"), ("err_released", "the energy released"),
        ("err_both", "both")), unit=" mm")

if __name__ == "__main__":
    main()
