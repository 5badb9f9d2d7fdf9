#!/usr/bin/env bats
# pd-crack-tip: the tip of seed 004 §5 (largest current coordinate along an
# axis among particles with damage > threshold) per frame, checked on a hand
# made case with a known answer and against numpy on a real run.

load test_helper

# One run for the whole file: the make_run block (a sphere pressed into a
# 10 mm cube, sites at whole mm from 0 to 10 mm) over 100 steps, frames at
# 0, 25, 50, 75, 100, some particles above damage 0.3 at the end.
setup_file() {
    make_run "$BATS_FILE_TMPDIR" --steps 100 --every 25
}

setup() {
    RUN=$BATS_FILE_TMPDIR/run.h5
    MODEL=$BATS_FILE_TMPDIR/model.h5
    LATTICE=$BATS_FILE_TMPDIR/lattice.h5
    cd "$BATS_TEST_TMPDIR"
}

# check_tip RUN TABLE AXIS THRESHOLD: TABLE (the program's stdout) has the
# header, one row per frame in step order with the frame's step and time,
# and tip / count equal to numpy's over damage recomputed from /bonds.
# Prints "ok NFRAMES NFRAMES_WITH_A_TIP".
check_tip() {
    "$PY" - "$@" <<'EOF'
import sys, math
import h5py, numpy as np

run, table, axis, thr = sys.argv[1], sys.argv[2], "xyz".index(sys.argv[3]), float(sys.argv[4])
lines = open(table).read().splitlines()
assert lines[0] == "# step time_s tip_m n_damaged", lines[0]
rows = [l.split() for l in lines[1:]]
f = h5py.File(run, "r")
x = f["particles/position"][:]
n = x.shape[0]
off, nb, vol = f["bonds/offset"][:], f["bonds/neighbor"][:], f["particles/volume"][:]
row = np.repeat(np.arange(n), np.diff(off))
b = np.arange(nb.size)
keys = sorted(f["frames"], key=lambda k: int(f["frames"][k].attrs["step"]))
assert len(rows) == len(keys), (len(rows), len(keys))
found = 0
for r, k in zip(rows, keys):
    g = f["frames"][k]
    assert len(r) == 4, r
    assert int(r[0]) == int(g.attrs["step"])
    assert math.isclose(float(r[1]), float(g.attrs["time"]), rel_tol=1e-8, abs_tol=1e-300)
    # bond b intact when bit b%8 of byte b//8 of the frame state is set;
    # damage = 1 - sum V_j intact / sum V_j of the family (seed 000 eq. 10)
    st = g["state"][:]
    intact = (st[b // 8] >> (b % 8)) & 1
    tot = np.bincount(row, vol[nb], minlength=n)
    kept = np.bincount(row, vol[nb] * intact, minlength=n)
    d = np.where(tot > 0, 1.0 - kept / np.where(tot > 0, tot, 1.0), 0.0)
    y = x[:, axis] + g["displacement"][:, axis]
    hit = d > thr
    assert int(r[3]) == hit.sum(), (k, r[3], hit.sum())
    if hit.sum() == 0:
        assert r[2] == "nan", r
    else:
        assert math.isclose(float(r[2]), y[hit].max(), rel_tol=1e-9), (r[2], y[hit].max())
        found += 1
print("ok", len(rows), found)
EOF
}

# check_table TABLE 'STEP TIP N'...: each row's step, tip (or nan) to 1e-12 m
# and count.
check_table() {
    "$PY" - "$@" <<'EOF'
import sys, math
lines = open(sys.argv[1]).read().splitlines()
assert lines[0] == "# step time_s tip_m n_damaged", lines[0]
got = [l.split() for l in lines[1:]]
want = [w.split() for w in sys.argv[2:]]
assert len(got) == len(want), (got, want)
for g, w in zip(got, want):
    assert g[0] == w[0], (g, w)
    if w[1] == "nan":
        assert g[2] == "nan", (g, w)
    else:
        assert math.isclose(float(g[2]), float(w[1]), rel_tol=0, abs_tol=1e-12), (g, w)
    assert g[3] == w[2], (g, w)
print("ok")
EOF
}

@test "--help prints the usage on stdout and exits 0" {
    run -0 pd-crack-tip --help
    assert_line --index 0 "Usage: pd-crack-tip [OPTION]... RUN.h5"
    run -0 pd-crack-tip --version
    assert_output --regexp '^pd-crack-tip \(pd\) [0-9]'
}

@test "usage errors exit 2 with one error line" {
    expect_usage_error "missing RUN.h5" pd-crack-tip
    expect_usage_error "--axis .*'w'" pd-crack-tip --axis w "$RUN"
    expect_usage_error "--threshold" pd-crack-tip --threshold 1.5 "$RUN"
    expect_usage_error "--threshold" pd-crack-tip --threshold abc "$RUN"
    expect_usage_error "exactly one RUN.h5" pd-crack-tip "$RUN" "$RUN"
    run -2 pd-crack-tip --bogus "$RUN"
}

@test "a hand-made damage field gives the tip one can work out by hand" {
    cp "$RUN" hand.h5
    # frame 0: no damage; 25: damage exactly 0.3 everywhere (not above);
    # 50: damage 0.4 where x <= 4.5 mm, every particle moved by +0.1 mm in x;
    # 75: damage 0.9 on the plane y = 5 mm where x <= 7.5 mm, all moved by
    # (0, +0.2, -0.1) mm; 100: damage 1 on the one site (2, 3, 4) mm.
    run -0 "$PY" - hand.h5 <<'EOF'
import sys, h5py, numpy as np
with h5py.File(sys.argv[1], "r+") as f:
    x = f["particles/position"][:]
    n = x.shape[0]
    assert np.allclose(x.min(0), 0) and np.allclose(x.max(0), 0.01)
    fr = f["frames"]
    def put(key, damage, u):
        if "damage" in fr[key]:
            del fr[key]["damage"]
        fr[key]["damage"] = damage
        fr[key]["displacement"][...] = np.tile(u, (n, 1))
    put("00000000", np.zeros(n), [0, 0, 0])
    put("00000025", np.full(n, 0.3), [0, 0, 0])
    put("00000050", np.where(x[:, 0] <= 0.0045, 0.4, 0.0), [1e-4, 0, 0])
    plane = (np.abs(x[:, 1] - 0.005) < 1e-9) & (x[:, 0] <= 0.0075)
    put("00000075", np.where(plane, 0.9, 0.0), [0, 2e-4, -1e-4])
    site = np.all(np.abs(x - [0.002, 0.003, 0.004]) < 1e-9, axis=1)
    assert site.sum() == 1
    put("00000100", np.where(site, 1.0, 0.0), [0, 0, 0])
    print((x[:, 0] <= 0.0045).sum(), plane.sum(), n)
EOF
    read -r n50 n75 n <<<"$output"
    [ "$n50" -gt 0 ] && [ "$n75" -gt 0 ]
    pd-crack-tip hand.h5 > x.txt
    run -0 check_table x.txt "0 nan 0" "25 nan 0" "50 0.0041 $n50" "75 0.007 $n75" "100 0.002 1"
    pd-crack-tip --axis y hand.h5 > y.txt
    run -0 check_table y.txt "0 nan 0" "25 nan 0" "50 0.01 $n50" "75 0.0052 $n75" "100 0.003 1"
    pd-crack-tip --axis z --threshold 0.5 hand.h5 > z.txt
    run -0 check_table z.txt "0 nan 0" "25 nan 0" "50 nan 0" "75 0.0099 $n75" "100 0.004 1"
    # a threshold just below 0.3 takes in the whole block of frame 25
    pd-crack-tip -a x -t 0.2999 hand.h5 > all.txt
    run -0 check_table all.txt "0 nan 0" "25 0.01 $n" "50 0.0041 $n50" "75 0.007 $n75" \
        "100 0.002 1"
}

@test "on a real run the tip is numpy's max over damage recomputed from /bonds" {
    for axis in x y z; do
        for thr in 0.3 0.1 0; do
            pd-crack-tip --axis "$axis" --threshold "$thr" "$RUN" > t.txt
            run -0 check_tip "$RUN" t.txt "$axis" "$thr"
            assert_output --regexp '^ok 5 [1-9]'
        done
    done
    # the default is x and 0.3
    pd-crack-tip "$RUN" > d.txt
    pd-crack-tip --axis x --threshold 0.3 "$RUN" > e.txt
    cmp d.txt e.txt
}

@test "a stored damage field and a recomputed one give the same table; stdin works" {
    pd-crack-tip --threshold 0.1 "$RUN" > computed.txt
    pd-damage "$RUN" -o with.h5 > /dev/null
    pd-crack-tip --threshold 0.1 with.h5 > stored.txt
    cmp computed.txt stored.txt
    pd-crack-tip --threshold 0.1 - < "$RUN" > piped.txt
    cmp computed.txt piped.txt
}

@test "a missing input or one that is not a pd-h5 run is a runtime error with one line" {
    expect_runtime_error "nosuch\.h5" pd-crack-tip nosuch.h5
    make_bad_inputs
    for bad in empty.h5 text.h5 adir plain.h5; do
        expect_runtime_error "$bad" pd-crack-tip "$bad"
    done
    run -1 --separate-stderr pd-crack-tip - < text.h5
    assert_one_error '^pd-crack-tip: error: '
}

@test "a file without frames or without bonds is a runtime error with one line" {
    expect_runtime_error "frames" pd-crack-tip "$MODEL"
    expect_runtime_error "frames" pd-crack-tip "$LATTICE"
    cp "$RUN" nobonds.h5
    py 'del h5py.File(sys.argv[1], "r+")["bonds"]' nobonds.h5
    expect_runtime_error "bonds" pd-crack-tip nobonds.h5
}
