"""cost.py -- the anisotropic beam's axial stress and onset of yield
against what a run costs.

usage: /usr/bin/python3 cost.py --spacing "DX-A..." --aspect "DX-A..." > cost.txt

Reads, for each run DX-A (spacing DX in m, A the aspect a = b of the
ellipsoid along x, or iso), conv/eps-DX-A.{dat,h5,log,time} (the eps run;
.dat the table of `beam.py stress`) and conv/lps-DX-A.{dat,time} (its
elastic twin, lps), and prints one row per run of each sweep:
share/pdcost.py's leading columns (the eps run's cost; setting: dx in mm
for the spacing sweep, A for the aspect sweep), then

  dx_mm aspect horizon_mm peak_MPa peak_ms onset_MPa onset_ms err_peak
  err_onset shift_peak shift_onset twin_wall_s broken

from the mean axial stress over the middle third of the beam, -sigma_xx
(compression positive):

  peak_MPa, peak_ms    its largest value, and when
  onset_MPa, onset_ms  the onset of yield: where eps first falls 1% below
                       its elastic twin (the two agree to rounding until
                       eps yields), linear between frames (a frame every
                       5 us or so); nan if it never does
  err_*                relative errors against the finest run of the
                       spacing sweep (nan in the aspect sweep)
  shift_*              the aspect sweep: the relative change against the
                       sweep's a = 1 run (an ellipsoid that is a sphere,
                       the isotropic beam), what the anisotropy does, not
                       an error (nan in the spacing sweep)
  twin_wall_s          the wall time of the twin, which only measures
  broken               broken bonds at the end of the eps run

The comment lines at the end say which spacing is the cheapest within 5%.
"""
import argparse
import os
import sys

import h5py
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "share"))
import pdcost  # noqa: E402

ONSET = 0.99  # eps / lps below this: yielded
FLOOR = 1.0  # MPa: the twin's stress below which the ratio is not read
FIGURES = ["dx_mm", "aspect", "horizon_mm", "peak_MPa", "peak_ms", "onset_MPa", "onset_ms",
           "err_peak", "err_onset", "shift_peak", "shift_onset", "twin_wall_s", "broken"]
NAN = float("nan")


def onset(eps, lps):
    """(MPa, ms) where -sigma of eps first falls below ONSET x the twin's."""
    if eps.shape != lps.shape or not np.allclose(eps[:, 0], lps[:, 0], rtol=1e-9, atol=0):
        raise SystemExit("cost.py: eps and its twin have different frames")
    t, se, sl = eps[:, 0], -eps[:, 1], -lps[:, 1]
    prev = None
    for k in range(len(t)):
        if sl[k] < FLOOR:
            continue
        r = se[k] / sl[k]
        if r < ONSET:
            if prev is None:
                return se[k], t[k]
            j, rj = prev
            w = (rj - ONSET) / (rj - r)
            return se[j] + w * (se[k] - se[j]), t[j] + w * (t[k] - t[j])
        prev = (k, r)
    return NAN, NAN


def run(name, sweep):
    dx, a = name.split("-")
    c = pdcost.run_cost("conv/eps-" + name)
    twin = pdcost.run_cost("conv/lps-" + name)
    eps = np.loadtxt("conv/eps-%s.dat" % name, ndmin=2)
    lps = np.loadtxt("conv/lps-%s.dat" % name, ndmin=2)
    k = int(np.argmin(eps[:, 1]))
    o_mpa, o_ms = onset(eps, lps)
    with h5py.File("conv/eps-%s.h5" % name, "r") as f:
        last = f["frames"][sorted(f["frames"])[-1]]
        c.update(particles=f["particles/position"].shape[0],
                 bonds=int(f["bonds"].attrs["count"]) // 2,
                 horizon_mm=float(f["bonds"].attrs["horizon"]) * 1e3,
                 broken=int(last.attrs["broken_bonds"]))
    aspect = 1.0 if a == "iso" else float(a)
    c.update(sweep=sweep, setting="%g" % (float(dx) * 1e3 if sweep == "spacing" else aspect),
             dx_mm=float(dx) * 1e3, aspect=aspect, peak_MPa=-eps[k, 1], peak_ms=eps[k, 0],
             onset_MPa=o_mpa, onset_ms=o_ms, twin_wall_s=twin["wall"], err_peak=NAN,
             err_onset=NAN, shift_peak=NAN, shift_onset=NAN)
    return c


def main():
    ap = argparse.ArgumentParser(prog="cost.py")
    ap.add_argument("--spacing", required=True)
    ap.add_argument("--aspect", required=True)
    a = ap.parse_args()
    by_dx = sorted((run(n, "spacing") for n in a.spacing.split()), key=lambda r: -r["dx_mm"])
    by_a = sorted((run(n, "aspect") for n in a.aspect.split()), key=lambda r: -r["aspect"])
    ref = by_dx[-1]
    for r in by_dx:
        r["err_peak"] = pdcost.relerr(r["peak_MPa"], ref["peak_MPa"])
        r["err_onset"] = pdcost.relerr(r["onset_MPa"], ref["onset_MPa"])
        r["err_all"] = max(r["err_peak"], r["err_onset"])
    sphere = [r for r in by_a if r["aspect"] == 1.0]
    for r in by_a:
        if sphere:
            r["shift_peak"] = (r["peak_MPa"] - sphere[0]["peak_MPa"]) / sphere[0]["peak_MPa"]
            r["shift_onset"] = (r["onset_MPa"] - sphere[0]["onset_MPa"]) / sphere[0]["onset_MPa"]
    pdcost.write(by_dx + by_a, FIGURES)
    print("# reference of the spacing sweep: its finest run, dx = %g mm" % ref["dx_mm"])
    pdcost.say_cheapest("spacing", by_dx, ref, (
        ("err_peak", "the peak axial stress"), ("err_onset", "the onset of yield"),
        ("err_all", "both")), unit=" mm")

if __name__ == "__main__":
    main()
