"""pdcost.py -- what a pd-run cost, and how far a figure lies from its
reference: the common part of the examples' `make convergence` sweeps
(examples/*/cost.py).

A sweep's rule runs

    /usr/bin/time -f '%e %M' -o STEM.time pd-run ... -o STEM.h5.tmp 2> STEM.log

so that STEM.time holds pd-run's wall seconds and peak resident kB, and
STEM.log its log: the threads it ran on ("pd-run: N threads") and its last
line, "N steps in T s (R bond updates/s)".  run_cost(STEM) reads both; a
program of one's own over libpd that logs the same two lines under its
own name (examples/library/impact.c) is read the same way.

Every example's cost.txt has the same leading columns,

    sweep setting particles bonds steps threads wall_s loop_s peak_MiB
    updates_per_s

then its figures and their errors, so that share/cost.gp draws any of them.
"""
import math
import re
import sys

LOOP = re.compile(r"(\d+) steps in ([0-9.eE+-]+) s \(([0-9.eE+-]+) bond updates/s\)")
THREADS = re.compile(r"^[\w.-]+: (\d+) threads?\b", re.M)

LEAD = ["sweep", "setting", "particles", "bonds", "steps", "threads", "wall_s", "loop_s",
        "peak_MiB", "updates_per_s"]


def run_cost(stem):
    """What the run STEM cost: {'wall', 'peak' (MiB), 'loop' (s), 'steps',
    'rate' (bond updates/s), 'threads', 'log' (the log's text)}."""
    with open(stem + ".time") as f:
        wall, peak_kb = (float(v) for v in f.read().split()[-2:])
    with open(stem + ".log") as f:
        log = f.read()
    loop = LOOP.findall(log)
    threads = THREADS.search(log)
    if not loop or not threads:
        raise SystemExit("pdcost: %s.log holds no pd-run loop or thread line" % stem)
    steps, seconds, rate = loop[-1]
    return {"wall": wall, "peak": peak_kb / 1024.0, "loop": float(seconds), "steps": int(steps),
            "rate": float(rate), "threads": int(threads.group(1)), "log": log}


def relerr(value, ref):
    """|value - ref| / |ref| (nan where ref is 0 or either is nan)."""
    if ref == 0 or math.isnan(value) or math.isnan(ref):
        return float("nan")
    return abs(value - ref) / abs(ref)


def cheapest(rows, err, limit=0.05):
    """The row of least wall time whose error err is within limit (None if
    none is)."""
    ok = [r for r in rows if not math.isnan(r[err]) and r[err] <= limit]
    return min(ok, key=lambda r: r["wall"]) if ok else None


def say_cheapest(kind, rows, ref, checks, unit="", out=sys.stdout):
    """A comment line for each (err, what) of checks that some row meets:
    the cheapest setting of kind (its unit after it) within 5% of the
    finest, ref, on what (the figure, with its article), and its wall time
    against ref's."""
    for err, what in checks:
        best = cheapest(rows, err)
        if best:
            print("# cheapest %s within 5%% of the finest on %s: %s%s, wall %.2f s against "
                  "%.2f s (%.3f)" % (kind, what, best["setting"], unit, best["wall"], ref["wall"],
                                     best["wall"] / ref["wall"]), file=out)


def _fmt(v):
    if isinstance(v, str):
        return v
    if isinstance(v, int):
        return "%d" % v
    if math.isnan(v):
        return "nan"
    return "%.6g" % v


def write(rows, figures, out=sys.stdout):
    """One line per row: the LEAD columns, then each of figures (the keys of
    the row's figures, then of their errors, as the caller lists them)."""
    print("# " + " ".join(LEAD + figures), file=out)
    for r in rows:
        lead = [r["sweep"], r["setting"], r["particles"], r["bonds"], r["steps"], r["threads"],
                r["wall"], r["loop"], r["peak"], r["rate"]]
        print(" ".join(_fmt(v) for v in lead + [r[k] for k in figures]), file=out)


def column(figures, key):
    """The 1-based column of cost.txt that holds figure key (for gnuplot)."""
    return len(LEAD) + figures.index(key) + 1
