#!/usr/bin/env bats
# The sweep pattern of pd(7) ("What accuracy costs: a convergence sweep"),
# as a user copies it: its Makefile and cost.py are taken from the man page
# itself and run, and share/pdcost.py, which every example's cost.py uses,
# is held to what it promises.

load test_helper

# the man page's two examples of the section (Makefile, cost.py) into the
# test's directory, cost.py reading this tree's share/
extract() {
    "$PY" - "$BATS_TEST_DIRNAME/../man/man7/pd.7" "$BATS_TEST_DIRNAME/../share" <<'PY'
import re, sys
s = open(sys.argv[1]).read()
s = s[s.index("A spacing sweep of the impact, in that pattern:"):]
blocks = re.findall(r"\.EX\n(.*?)\.EE", s, re.S)[:2]
def text(t):
    for a, b in (("\\-", "-"), ("\\e", "\\"), ("\\(aq", "'"), ("\\(dq", '"'), ("\\&", "")):
        t = t.replace(a, b)
    return t
open("Makefile", "w").write(text(blocks[0]))
open("cost.py", "w").write(text(blocks[1]).replace("/usr/local/share/pd/python", sys.argv[2]))
PY
}

@test "sweep: pd(7)'s Makefile and cost.py run as written, make -j safe, and collect the table" {
    cd "$BATS_TEST_TMPDIR"
    extract
    grep -q '^conv/run-%.h5: conv/model-%.h5$' Makefile
    # coarse spacings (the page's own take a minute), two at a time
    run -0 make -j2 DXS="0.002 0.0015 0.001"
    run -0 make -q DXS="0.002 0.0015 0.001"      # and then nothing left to make
    [ ! -e conv/run-0.001.h5.tmp ]
    run -0 "$PY" - <<'PY'
import h5py, math
rows = [l.split() for l in open("cost.txt") if not l.startswith("#")]
head = open("cost.txt").readline().split()[1:]
assert head[:10] == ["sweep", "setting", "particles", "bonds", "steps", "threads", "wall_s",
                     "loop_s", "peak_MiB", "updates_per_s"], head
assert [r[1] for r in rows] == ["0.002", "0.0015", "0.001"], rows
for r in rows:
    v = dict(zip(head, r))
    with h5py.File("conv/run-%s.h5" % v["setting"], "r") as f:
        assert int(v["particles"]) == f["particles/position"].shape[0]
        assert int(v["bonds"]) == int(f["bonds"].attrs["count"]) // 2
        steps = int(f["scene"].attrs["steps"])
        dt = float(f["scene"].attrs["dt"])
    assert int(v["steps"]) == steps and abs(steps * dt - 1e-4) < 1e-12, (steps, dt)
    log = open("conv/run-%s.log" % v["setting"]).read()
    assert ("pd-run: %s thread" % v["threads"]) in log
    assert 0 < float(v["loop_s"]) <= float(v["wall_s"]) + 0.01
    assert float(v["peak_MiB"]) > 1
    last = open("conv/run-%s.txt" % v["setting"]).read().split()[-6:]
    assert abs(float(v["mean_damage"]) / float(last[3]) - 1) < 1e-5 and 0 < float(last[3]) <= 1
ref = float(rows[-1][10])
for r in rows:
    assert abs(float(r[11]) - abs(float(r[10]) - ref) / ref) < 1e-5
assert float(rows[-1][11]) == 0
PY
    # share/cost.gp draws it, as the page says
    run -0 gnuplot -e "sweeps='spacing'; names='the spacing'; errs='12'; keys='mean damage'" \
        "$BATS_TEST_DIRNAME/../share/cost.gp"
    [ -s cost.png ]
}

@test "sweep: share/pdcost.py reads a run's cost, refuses a log without one, and picks the cheapest" {
    cd "$BATS_TEST_TMPDIR"
    printf '12.5 204800\n' > a.time
    printf 'pd-run: 3 threads, GOMP_SPINCOUNT=1000\npd-run: 10 steps in 9.5 s (1e+08 bond updates/s), contact list builds 0\n' > a.log
    printf '1 1024\n' > b.time
    printf 'impact: 2 threads\nimpact: 5 steps in 0.5 s (2e+08 bond updates/s)\n' > b.log
    printf '1 1024\n' > c.time
    printf 'pd-run: 2 threads\n' > c.log
    run -0 "$PY" - <<'PY'
import math, pdcost
a = pdcost.run_cost("a")
assert (a["wall"], a["peak"], a["loop"], a["steps"], a["rate"], a["threads"]) == \
    (12.5, 200.0, 9.5, 10, 1e8, 3), a
b = pdcost.run_cost("b")          # a program of one's own with pd-run's two lines
assert (b["threads"], b["steps"]) == (2, 5), b
assert math.isnan(pdcost.relerr(1.0, 0.0)) and math.isnan(pdcost.relerr(float("nan"), 1.0))
assert pdcost.relerr(0.9, 1.0) == abs(0.9 - 1.0)
rows = [{"wall": 3, "e": 0.01}, {"wall": 1, "e": 0.2}, {"wall": 2, "e": 0.05},
        {"wall": 0.5, "e": float("nan")}]
assert pdcost.cheapest(rows, "e") is rows[2]
assert pdcost.cheapest(rows, "e", limit=0.001) is None
PY
    run -1 "$PY" -c 'import pdcost; pdcost.run_cost("c")'
    assert_output --partial "c.log holds no pd-run loop or thread line"
}
