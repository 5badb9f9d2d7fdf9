"""convergence.py -- accuracy against cost over the grids of the sweep.

usage: /usr/bin/python3 convergence.py DX... > cost.txt

For each grid spacing DX (m) it reads tip-DX.txt (pd-crack-tip's table),
run-DX.h5 (particles, bonds, steps), run-DX.log (pd-run's loop time and bond
updates per second) and run-DX.time (/usr/bin/time: wall seconds, peak kB),
and prints one row per grid:

  dx_mm particles bonds steps wall_s updates_per_s peak_MiB arrest_mm
  speed_m_s err_arrest_mm err_speed_m_s

The crack extension of a frame is the mean of its two tips (the plate is
symmetric); the arrest length is its mean over the frames from 20 us on
(the crack has stopped by 10 us; the mean takes out the ringing of the
plate, +-0.05 mm), the
largest crack speed the largest over the frames of the mean of the two tips'
smoothed speeds (pd-crack-tip: a least-squares line over +-2 frames).
Errors are against the finest grid.  The comment lines at the end give the
convergence order p of each error, err ~ dx^p (least squares in log-log
over the grids but the finest), and the Rayleigh speed of the plate.
"""
import math
import re
import sys

import h5py
import numpy as np

ARREST_FROM = 20e-6  # s: the crack has stopped; the tips only ring with the plate


def table(path):
    rows = [l.split() for l in open(path) if l.strip() and not l.startswith("#")]
    return np.array([[float(v) for v in r] for r in rows])


def grid(dx):
    t = table("tip-%s.txt" % dx)
    # step time lower upper da_lower da_upper speed_lower speed_upper n
    da = 0.5 * (t[:, 4] + t[:, 5])
    speed = 0.5 * (t[:, 6] + t[:, 7])
    with h5py.File("run-%s.h5" % dx) as f:
        n = f["particles/id"].shape[0]
        bonds = int(f["bonds"].attrs["count"]) // 2
        steps = int(f["scene"].attrs["steps"])
    log = open("run-%s.log" % dx).read()
    m = re.search(r"(\d+) steps in ([0-9.eE+-]+) s \(([0-9.eE+-]+) bond updates/s\)", log)
    wall, peak_kb = (float(v) for v in open("run-%s.time" % dx).read().split()[-2:])
    return {
        "dx": float(dx), "n": n, "bonds": bonds, "steps": steps, "wall": wall,
        "rate": float(m.group(3)) if m else float("nan"), "peak": peak_kb / 1024,
        "arrest": float(np.mean(da[t[:, 1] >= ARREST_FROM])), "speed": np.nanmax(speed),
    }


def order(rows, key):
    pts = [(math.log(r["dx"]), math.log(r[key])) for r in rows if r[key] > 0]
    if len(pts) < 2:
        return float("nan")
    x, y = np.array(pts).T
    return np.polyfit(x, y, 1)[0]


def main():
    rows = [grid(dx) for dx in sys.argv[1:]]
    ref = min(rows, key=lambda r: r["dx"])
    print("# dx_mm particles bonds steps wall_s updates_per_s peak_MiB arrest_mm speed_m_s "
          "err_arrest_mm err_speed_m_s")
    for r in sorted(rows, key=lambda r: -r["dx"]):
        r["err_arrest"] = abs(r["arrest"] - ref["arrest"])
        r["err_speed"] = abs(r["speed"] - ref["speed"])
        print("%g %d %d %d %.2f %.3g %.0f %.4f %.0f %.4f %.0f" % (
            r["dx"] * 1e3, r["n"], r["bonds"], r["steps"], r["wall"], r["rate"], r["peak"],
            r["arrest"] * 1e3, r["speed"], r["err_arrest"] * 1e3, r["err_speed"]))
    coarse = [r for r in rows if r is not ref]
    print("# reference: the finest grid, dx = %g mm" % (ref["dx"] * 1e3))
    print("# convergence order of the arrest length: %.2f" % order(coarse, "err_arrest"))
    print("# convergence order of the largest crack speed: %.2f" % order(coarse, "err_speed"))
    E, rho, nu = 192e9, 8000.0, 1.0 / 3.0  # plane stress, PMB's Poisson ratio in 2-D
    cs = math.sqrt(E / (2 * (1 + nu)) / rho)
    print("# Rayleigh speed (plane stress, nu = 1/3): %.0f m/s; largest crack speed on the "
          "finest grid %.0f m/s = %.2f of it" % (cs * (0.862 + 1.14 * nu) / (1 + nu),
                                                  ref["speed"], ref["speed"] / (cs * (0.862 + 1.14 * nu) / (1 + nu))))


if __name__ == "__main__":
    main()
