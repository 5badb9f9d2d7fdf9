"""cost.py -- accuracy against cost over the plate's resolutions.

usage: /usr/bin/python3 cost.py DX... > cost.txt
       /usr/bin/python3 cost.py --slice RUN.h5 > slice.txt

For each spacing DX (m) and each kind (mesh: gmsh's tetrahedra through
pd-mesh; lattice: pd-lattice --inside the same surface) it reads
run-KIND-DX.h5 (particles, bonds, the time series), run-KIND-DX.log (the
relaxation's iterations and bond updates per second) and run-KIND-DX.time
(/usr/bin/time: wall seconds, peak kB), and prints one row per run:

  kind dx_mm particles bonds volume_mm3 iterations wall_s updates_per_s
  peak_MiB force_N err_finest err_limit

force_N is the reaction of the pulled grip once relaxed (the series'
right.fx), the plate's stiffness times the pull.  err_finest is its
relative difference from the finest lattice run; err_limit from the limit
delta -> 0: each kind's force extrapolated by a straight line through its
two finest runs (the surface layer a horizon thick, where the bonds are
fewer, shrinks with delta), the two limits averaged.

--slice prints x_mm y_mm sigma_xx_MPa of the particles within 0.6 spacings
of the plate's mid-plane z = 1 mm (the last frame's stress field).
"""
import re
import sys

import h5py
import numpy as np

sys.path.insert(0, "../../share")
import pdh5  # noqa: E402  (the repository's own reader of the time series)

THICK = 0.002


def run(kind, dx):
    name = "run-%s-%s" % (kind, dx)
    with h5py.File(name + ".h5") as f:
        n = f["particles/id"].shape[0]
        volume = f["particles/volume"][:].sum()
        bonds = int(f["bonds"].attrs["count"]) // 2
    s = pdh5.series(name + ".h5")
    log = open(name + ".log").read()
    m = re.search(r"(\d+) iterations, in ([0-9.eE+-]+) s \(([0-9.eE+-]+) bond updates/s\)", log)
    wall, peak_kb = (float(v) for v in open(name + ".time").read().split()[-2:])
    return {"kind": kind, "dx": float(dx), "n": n, "bonds": bonds, "volume": volume,
            "it": int(m.group(1)) if m else -1, "wall": wall,
            "rate": float(m.group(3)) if m else float("nan"), "peak": peak_kb / 1024,
            "force": float(s["right.fx"][-1])}


def slice_of(path):
    with h5py.File(path) as f:
        x = f["particles/position"][:]
        h = f["particles"].attrs["spacing"]
        last = sorted(f["frames"])[-1]
        sxx = f["frames/%s/stress" % last][:, 0, 0]
    mid = np.abs(x[:, 2] - THICK / 2) < 0.6 * h
    for p, s in zip(x[mid], sxx[mid]):
        print("%.6g %.6g %.6g" % (1e3 * p[0], 1e3 * p[1], 1e-6 * s))


def limit(rows, kind):
    """The force of a kind extrapolated to delta -> 0 by a straight line
    through its two finest runs."""
    k = sorted((r for r in rows if r["kind"] == kind), key=lambda r: r["dx"])
    (d1, f1), (d2, f2) = (k[0]["dx"], k[0]["force"]), (k[1]["dx"], k[1]["force"])
    return f1 - d1 * (f2 - f1) / (d2 - d1)


def main(dxs):
    rows = [run(k, dx) for k in ("mesh", "lattice") for dx in dxs]
    finest = min(float(d) for d in dxs)
    ref = [r for r in rows if r["kind"] == "lattice" and r["dx"] == finest][0]["force"]
    lims = {k: limit(rows, k) for k in ("mesh", "lattice")}
    f0 = 0.5 * (lims["mesh"] + lims["lattice"])
    print("# kind dx_mm particles bonds volume_mm3 iterations wall_s updates_per_s peak_MiB "
          "force_N err_finest err_limit")
    for r in rows:
        print("%-7s %.4g %d %d %.5g %d %.2f %.3g %.0f %.4f %.4f %.4f" % (
            r["kind"], 1e3 * r["dx"], r["n"], r["bonds"], 1e9 * r["volume"], r["it"],
            r["wall"], r["rate"], r["peak"], r["force"], abs(r["force"] - ref) / ref,
            abs(r["force"] - f0) / f0))
    print("# err_finest: against the finest lattice run, %.4f N" % ref)
    print("# err_limit: against %.2f N, the mean of the two kinds' forces extrapolated to "
          "delta -> 0 (mesh %.2f N, lattice %.2f N; a line through each kind's two finest "
          "runs: the surface layer a horizon thick, where the bonds are fewer, shrinks with "
          "delta)" % (f0, lims["mesh"], lims["lattice"]))


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "--slice":
        slice_of(sys.argv[2])
    elif len(sys.argv) >= 3:
        main(sys.argv[1:])
    else:
        sys.exit("usage: cost.py DX... | cost.py --slice RUN.h5")
