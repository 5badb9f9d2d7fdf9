#!/usr/bin/env bats
# pd-crack-tip: the tips of seed 004 §5 (smallest and largest current
# coordinate along an axis among particles with damage > threshold) per
# frame, their extension and speed, the crack front (--front), the plot
# (--plot) and the crack path (--path); checked on hand-made damage with
# known answers, against numpy on a real run and on a pre-cracked plate.

load test_helper

# One run for the whole file: the make_run block (a sphere pressed into a
# 10 mm cube, sites at whole mm from 0 to 10 mm) over 100 steps, frames at
# 0, 25, 50, 75, 100, some particles above damage 0.3 at the end.
setup_file() {
    make_run "$BATS_FILE_TMPDIR" --steps 100 --every 25
}

HEADER="# step time_s lower_m upper_m da_lower_m da_upper_m speed_lower_m_s speed_upper_m_s n_damaged"
FRONT_HEADER="# step time_s n_damaged n_front r_max_m r_mean_m lo_m hi_m da_m speed_m_s"

setup() {
    RUN=$BATS_FILE_TMPDIR/run.h5
    MODEL=$BATS_FILE_TMPDIR/model.h5
    LATTICE=$BATS_FILE_TMPDIR/lattice.h5
    cd "$BATS_TEST_TMPDIR"
}

# check_tip RUN TABLE AXIS THRESHOLD: TABLE (the program's stdout) has the
# header, one row per frame in step order with the frame's step and time,
# and lower / upper tips and count equal to numpy's over damage recomputed
# from /bonds.  Prints "ok NFRAMES NFRAMES_WITH_A_TIP".
check_tip() {
    "$PY" - "$HEADER" "$@" <<'EOF'
import sys, math
import h5py, numpy as np, pdh5

header, run, table = sys.argv[1], sys.argv[2], sys.argv[3]
axis, thr = "xyz".index(sys.argv[4]), float(sys.argv[5])
lines = open(table).read().splitlines()
assert lines[0] == header, lines[0]
rows = [l.split() for l in lines[1:]]
f = h5py.File(run, "r")
x = f["particles/position"][:]
n = x.shape[0]
(off, nb), vol = pdh5.bonds(f)[:2], f["particles/volume"][:]
row = np.repeat(np.arange(n), np.diff(off))
b = np.arange(nb.size)
keys = sorted(f["frames"], key=lambda k: int(f["frames"][k].attrs["step"]))
assert len(rows) == len(keys), (len(rows), len(keys))
found = 0
for r, k in zip(rows, keys):
    g = f["frames"][k]
    assert len(r) == 9, r
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
    assert int(r[8]) == hit.sum(), (k, r[8], hit.sum())
    if hit.sum() == 0:
        assert r[2] == "nan" and r[3] == "nan", r
    else:
        assert math.isclose(float(r[2]), y[hit].min(), rel_tol=1e-9, abs_tol=1e-15), r
        assert math.isclose(float(r[3]), y[hit].max(), rel_tol=1e-9, abs_tol=1e-15), r
        found += 1
print("ok", len(rows), found)
EOF
}

# check_growth TABLE WINDOW: the extension and speed columns of TABLE follow
# from its own tip and time columns by the definitions of pd-crack-tip(1):
# Delta a counted from the first frame with a tip (0 before it; the upper
# tip grows up, the lower down) and the speed the slope of a least-squares
# line (numpy's polyfit) through the frames within WINDOW.  Prints "ok".
check_growth() {
    "$PY" - "$@" <<'EOF'
import sys, math
import numpy as np
lines = open(sys.argv[1]).read().splitlines()
w = int(sys.argv[2])
rows = np.array([[float(v) for v in l.split()] for l in lines[1:]])
t = rows[:, 1]
for tip, da, sp, sign in ((2, 4, 6, -1), (3, 5, 7, 1)):
    fin = np.flatnonzero(np.isfinite(rows[:, tip]))
    want = np.zeros(len(rows))
    if fin.size:
        f = fin[0]
        want[f:] = sign * (rows[f:, tip] - rows[f, tip])
    assert np.allclose(rows[:, da], want, rtol=0, atol=2e-11, equal_nan=True), (rows[:, da], want)
    for k in range(len(rows)):
        lo, hi = max(0, k - w), min(len(rows) - 1, k + w)
        tt, aa = t[lo:hi + 1], want[lo:hi + 1]
        ok = np.isfinite(aa)
        if ok.sum() < 2 or not math.isfinite(want[k]):
            assert math.isnan(rows[k, sp]), rows[k]
            continue
        v = np.polyfit(tt[ok], aa[ok], 1)[0]
        assert math.isclose(rows[k, sp], v, rel_tol=1e-6, abs_tol=1e-3), (k, rows[k, sp], v)
print("ok")
EOF
}

# check_table TABLE 'STEP LOWER UPPER N'...: each row's step, tips (or nan)
# to 1e-12 m and count.
check_table() {
    "$PY" - "$HEADER" "$@" <<'EOF'
import sys, math
lines = open(sys.argv[2]).read().splitlines()
assert lines[0] == sys.argv[1], lines[0]
got = [l.split() for l in lines[1:]]
want = [w.split() for w in sys.argv[3:]]
assert len(got) == len(want), (got, want)
for g, w in zip(got, want):
    assert g[0] == w[0], (g, w)
    for col, v in ((2, w[1]), (3, w[2])):
        if v == "nan":
            assert g[col] == "nan", (g, w)
        else:
            assert math.isclose(float(g[col]), float(v), rel_tol=0, abs_tol=1e-12), (g, w)
    assert g[8] == w[3], (g, w)
print("ok")
EOF
}

# read_vtu FILE: the points and point data of a .vtu of pd as "NPOINTS
# NAME..." after reading it whole (tests/vtu.py checks that the XML header
# parses and every array has the size its header says).
read_vtu() {
    "$PY" - "$@" <<'EOF'
import sys, vtu
g = vtu.read(sys.argv[1])
assert g.compressed
names = list(g.point_data) + ["Points", "connectivity", "offsets", "types"]
print(len(g.points), *names)
EOF
}

@test "--help prints the usage on stdout and exits 0" {
    run -0 pd-crack-tip --help
    assert_line --index 0 "Usage: pd-crack-tip [OPTION]... RUN.h5"
    for opt in --axis --threshold --window --front --center --distance --plot --path; do
        assert_output --partial -- "$opt"
    done
    run -0 pd-crack-tip --version
    assert_output --regexp '^pd-crack-tip \(pd\) [0-9]'
}

@test "usage errors exit 2 with one error line" {
    expect_usage_error "missing RUN.h5" pd-crack-tip
    expect_usage_error "--axis .*'w'" pd-crack-tip --axis w "$RUN"
    expect_usage_error "--threshold" pd-crack-tip --threshold 1.5 "$RUN"
    expect_usage_error "--threshold" pd-crack-tip --threshold abc "$RUN"
    expect_usage_error "exactly one RUN.h5" pd-crack-tip "$RUN" "$RUN"
    expect_usage_error "--window .*'0'" pd-crack-tip --window 0 "$RUN"
    expect_usage_error "--window .*'1.5'" pd-crack-tip -w 1.5 "$RUN"
    expect_usage_error "--center .*'1,2'" pd-crack-tip --front --center 1,2 "$RUN"
    expect_usage_error "--center needs --front" pd-crack-tip --center 1,2,3 "$RUN"
    expect_usage_error "--distance .*'line'" pd-crack-tip --front --distance line "$RUN"
    expect_usage_error "--distance needs --front" pd-crack-tip --distance point "$RUN"
    expect_usage_error "--plot" pd-crack-tip --plot '' "$RUN"
    expect_usage_error "--path" pd-crack-tip --path out/ "$RUN"
    run -2 pd-crack-tip --bogus "$RUN"
}

@test "a hand-made damage field gives the tips one can work out by hand" {
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
    run -0 check_table x.txt "0 nan nan 0" "25 nan nan 0" "50 0.0001 0.0041 $n50" \
        "75 0 0.007 $n75" "100 0.002 0.002 1"
    pd-crack-tip --axis y hand.h5 > y.txt
    run -0 check_table y.txt "0 nan nan 0" "25 nan nan 0" "50 0 0.01 $n50" \
        "75 0.0052 0.0052 $n75" "100 0.003 0.003 1"
    pd-crack-tip --axis z --threshold 0.5 hand.h5 > z.txt
    run -0 check_table z.txt "0 nan nan 0" "25 nan nan 0" "50 nan nan 0" \
        "75 -0.0001 0.0099 $n75" "100 0.004 0.004 1"
    # a threshold just below 0.3 takes in the whole block of frame 25
    pd-crack-tip -a x -t 0.2999 hand.h5 > all.txt
    run -0 check_table all.txt "0 nan nan 0" "25 0 0.01 $n" "50 0.0001 0.0041 $n50" \
        "75 0 0.007 $n75" "100 0.002 0.002 1"
    # Delta a counted from the first frame with a tip (50), 0 before it:
    # upper 0.0041 -> 0.007 -> 0.002, lower 0.0001 -> 0 -> 0.002
    run -0 "$PY" - x.txt <<'EOF'
import sys, math
rows = [l.split() for l in open(sys.argv[1]).read().splitlines()[1:]]
want = [(0, 0), (0, 0), (0, 0), (0.0001, 0.0029), (-0.0019, -0.0021)]
for r, (lo, up) in zip(rows, want):
    assert math.isclose(float(r[4]), lo, abs_tol=1e-12), (r, lo)
    assert math.isclose(float(r[5]), up, abs_tol=1e-12), (r, up)
print("ok")
EOF
    for t in x y z all; do
        run -0 check_growth $t.txt 2
    done
    pd-crack-tip --window 1 hand.h5 > w1.txt
    run -0 check_growth w1.txt 1
}

@test "tips moving apart at a constant speed give that speed in every frame" {
    cp "$RUN" moving.h5
    # damage 1 on the plane y = 5 mm for 3 <= x <= 7 mm in every frame; the
    # half x > 5 mm moves by +c t along x, the other half by -c t: both tips
    # grow at c (the seed's 1300 m/s)
    run -0 "$PY" - moving.h5 <<'EOF'
import sys, h5py, numpy as np
c = 1300.0
with h5py.File(sys.argv[1], "r+") as f:
    x = f["particles/position"][:]
    crack = (np.abs(x[:, 1] - 0.005) < 1e-9) & (x[:, 0] > 0.0029) & (x[:, 0] < 0.0071)
    side = np.where(x[:, 0] > 0.005, 1.0, -1.0)
    for g in f["frames"].values():
        t = float(g.attrs["time"])
        if "damage" in g:
            del g["damage"]
        g["damage"] = np.where(crack, 1.0, 0.0)
        u = np.zeros_like(x)
        u[:, 0] = side * c * t
        g["displacement"][...] = u
print(crack.sum())
EOF
    ncrack=$output
    for w in 1 2 3 10; do
        pd-crack-tip --window "$w" moving.h5 > m.txt
        run -0 check_growth m.txt "$w"
        run -0 "$PY" - m.txt "$ncrack" <<'EOF'
import sys, math
lines = open(sys.argv[1]).read().splitlines()
c, n = 1300.0, sys.argv[2]
assert len(lines) == 6
for l in lines[1:]:
    r = l.split()
    t = float(r[1])
    assert math.isclose(float(r[2]), 0.003 - c * t, rel_tol=0, abs_tol=2e-11), r
    assert math.isclose(float(r[3]), 0.007 + c * t, rel_tol=0, abs_tol=2e-11), r
    assert math.isclose(float(r[4]), c * t, rel_tol=0, abs_tol=2e-11), r
    assert math.isclose(float(r[5]), c * t, rel_tol=0, abs_tol=2e-11), r
    for v in (float(r[6]), float(r[7])):
        assert math.isclose(v, c, rel_tol=1e-9), (r, v)
    assert r[8] == n, r
print("ok")
EOF
        assert_output "ok"
    done
}

@test "on a real run the tips are numpy's min and max over damage recomputed from /bonds" {
    for axis in x y z; do
        for thr in 0.3 0.1 0; do
            pd-crack-tip --axis "$axis" --threshold "$thr" "$RUN" > t.txt
            run -0 check_tip "$RUN" t.txt "$axis" "$thr"
            assert_output --regexp '^ok 5 [1-9]'
            run -0 check_growth t.txt 2
        done
    done
    # the default is x, 0.3 and a window of 2
    pd-crack-tip "$RUN" > d.txt
    pd-crack-tip --axis x --threshold 0.3 --window 2 "$RUN" > e.txt
    cmp d.txt e.txt
}

@test "a pre-crack counts: its ends are the tips of the first frame, Delta a 0" {
    # a 20 x 10 x 2 mm plate with a centre crack from x = 6.5 to 13.5 mm on
    # y = 5.5 mm, through the thickness, and no load: nothing grows
    pd-lattice -q --spacing 0.001 --density 2200 --box 0,0.02,0,0.01,0,0.002 -o plate.h5
    pd-bonds -q --horizon 0.0030001 --crack segment,0.0065,0.0055,0.0135,0.0055 plate.h5 \
        -o cracked.h5
    pd-run -q --bulk-modulus 14.9e9 --steps 4 --every 2 cracked.h5 -o still.h5
    pd-crack-tip still.h5 > t.txt
    run -0 check_tip still.h5 t.txt x 0.3
    assert_output "ok 3 3"
    # the lattice columns nearest inside the crack's ends, 7 and 13 mm
    run -0 check_table t.txt "0 0.007 0.013 39" "2 0.007 0.013 39" "4 0.007 0.013 39"
    run -0 awk 'NR > 1 { print $5, $6, $7, $8 }' t.txt
    assert_output "$(printf '0.000000000e+00 %.0s0.000000000e+00 0.000000000e+00 0.000000000e+00\n' 1 2 3)"
}

@test "--connected and --region: the notch crack's tip and speed come out alone" {
    # the pre-cracked plate of the test above (crack ends at 7 and 13 mm
    # on y = 5.5 mm); by hand, in the frames of step 2 and 4: damage at a
    # loaded point (a blob at x <= 1 mm, y >= 9 mm, more than a horizon from
    # the crack), a damaged bottom face (y = 0) that moves down 0.1 mm a
    # frame, and in frame 4 the crack grown to x = 15 mm
    pd-lattice -q --spacing 0.001 --density 2200 --box 0,0.02,0,0.01,0,0.002 -o plate.h5
    pd-bonds -q --horizon 0.0030001 --crack segment,0.0065,0.0055,0.0135,0.0055 plate.h5 \
        -o cracked.h5
    pd-run -q --bulk-modulus 14.9e9 --steps 4 --every 2 cracked.h5 -o beam.h5
    run -0 "$PY" - beam.h5 <<'EOF'
import sys, h5py, numpy as np
with h5py.File(sys.argv[1], "r+") as f:
    x = f["particles/position"][:]
    n = x.shape[0]
    fr = f["frames"]
    blob = (x[:, 0] <= 0.0010001) & (x[:, 1] >= 0.0089999)
    face = x[:, 1] <= 1e-9
    grown = (x[:, 0] >= 0.0139999) & (x[:, 0] <= 0.0150001) & (np.abs(x[:, 1] - 0.0055) < 0.0006)
    for key, k in (("00000002", 1), ("00000004", 2)):
        d = fr[key]["damage"][:]
        d[blob | face] = 0.8
        if k == 2:
            d[grown] = 0.5
        del fr[key]["damage"]
        fr[key]["damage"] = d
        u = np.zeros((n, 3))
        u[face, 1] = -1e-4 * k
        fr[key]["displacement"][...] = u
    print(blob.sum(), face.sum(), grown.sum())
EOF
    read -r nblob nface ngrown <<<"$output"
    [ "$nblob" -eq 12 ] && [ "$nface" -eq 63 ] && [ "$ngrown" -eq 12 ]
    # all the damage: the blob and the face pull the lower tips away
    pd-crack-tip beam.h5 > all.txt
    run -0 check_table all.txt "0 0.007 0.013 39" "2 0 0.02 $((39 + nblob + nface))" \
        "4 0 0.02 $((39 + nblob + nface + ngrown))"
    # the pre-crack's cluster: its ends, and the growth to 15 mm
    pd-crack-tip --connected beam.h5 > one.txt
    run -0 check_table one.txt "0 0.007 0.013 39" "2 0.007 0.013 39" "4 0.007 0.015 $((39 + ngrown))"
    # along y the face moving down at 0.1 mm a frame is a "speed" of the
    # lower tip; the crack's own lower tip stands still
    pd-crack-tip --axis y beam.h5 > ya.txt
    run -0 awk 'NR == 4 { print $3, $7 }' ya.txt
    [[ "$output" == "-2.000000000e-04 "* && "$output" != *" 0.000000000e+00" ]]
    pd-crack-tip --axis y --connected beam.h5 > yc.txt
    run -0 awk 'NR > 1 { print $3, $4, $7, $8 }' yc.txt
    assert_output "$(printf '5.000000000e-03 6.000000000e-03 0.000000000e+00 0.000000000e+00\n%.0s' 1 2 3)"
    # a region keeps only what is inside it (reference positions)
    pd-crack-tip --region box,0.004,0.02,0.002,0.01,-1,1 beam.h5 > r.txt
    run -0 check_table r.txt "0 0.007 0.013 39" "2 0.007 0.013 39" "4 0.007 0.015 $((39 + ngrown))"
    # a body without a pre-crack has no cluster to follow
    expect_runtime_error "has no pre-crack" pd-crack-tip --connected "$RUN"
    expect_usage_error "--region needs box" pd-crack-tip --region cube,1 beam.h5
}

@test "a stored damage field and a recomputed one give the same table; stdin works" {
    pd-crack-tip --threshold 0.1 "$RUN" > computed.txt
    pd-damage "$RUN" -o with.h5 > /dev/null
    pd-crack-tip --threshold 0.1 with.h5 > stored.txt
    cmp computed.txt stored.txt
    pd-crack-tip --threshold 0.1 - < "$RUN" > piped.txt
    cmp computed.txt piped.txt
}

@test "--front of a damaged ball inside the block is exactly its outline" {
    cp "$RUN" ball.h5
    # frame k: damage 0.5 in the ball of radius (1.5 + k/2) mm about
    # (5, 5, 5) mm, 0.1 elsewhere; no displacement.  The front, worked out
    # here from all pairs within the horizon: ball particles with a
    # neighbour outside the ball; r from the point (5,5,5) mm and from the
    # z axis through it, and the extent along z.
    run -0 "$PY" - ball.h5 <<'EOF'
import sys, h5py, numpy as np
with h5py.File(sys.argv[1], "r+") as f:
    x = f["particles/position"][:]
    delta = float(f["bonds"].attrs["horizon"])
    c = np.array([0.005, 0.005, 0.005])
    keys = sorted(f["frames"], key=lambda k: int(f["frames"][k].attrs["step"]))
    dist = np.linalg.norm(x[:, None, :] - x[None, :, :], axis=2)
    near = (dist <= delta) & (dist > 0)
    for k, key in enumerate(keys):
        g = f["frames"][key]
        R = 0.0015 + 0.0005 * k
        ball = np.linalg.norm(x - c, axis=1) <= R + 1e-12
        if "damage" in g:
            del g["damage"]
        g["damage"] = np.where(ball, 0.5, 0.1)
        g["displacement"][...] = 0
        front = ball & (near & ~ball[None, :]).any(axis=1)
        rp = np.linalg.norm(x[front] - c, axis=1)
        ra = np.linalg.norm(x[front][:, :2] - c[:2], axis=1)
        z = x[front][:, 2]
        print(g.attrs["step"], ball.sum(), front.sum(), rp.max(), rp.mean(), ra.max(),
              ra.mean(), z.min(), z.max())
EOF
    echo "$output" > want.txt
    pd-crack-tip --front --axis z --center 0.005,0.005,0.005 --distance point ball.h5 > p.txt
    pd-crack-tip --front --axis z ball.h5 > a.txt
    run -0 "$PY" - want.txt p.txt a.txt "$FRONT_HEADER" <<'EOF'
import sys, math
want = [l.split() for l in open(sys.argv[1]).read().splitlines()]
for table, cols in ((sys.argv[2], (3, 4)), (sys.argv[3], (5, 6))):
    lines = open(table).read().splitlines()
    assert lines[0] == sys.argv[4], lines[0]
    rows = [l.split() for l in lines[1:]]
    assert len(rows) == len(want) == 5
    for r, w in zip(rows, want):
        assert r[0] == w[0] and r[2] == w[1] and r[3] == w[2], (r, w)
        # to the 9 digits of the table
        assert math.isclose(float(r[4]), float(w[cols[0]]), rel_tol=1e-8), (r, w)
        assert math.isclose(float(r[5]), float(w[cols[1]]), rel_tol=1e-8), (r, w)
        assert math.isclose(float(r[6]), float(w[7]), abs_tol=1e-11), (r, w)
        assert math.isclose(float(r[7]), float(w[8]), abs_tol=1e-11), (r, w)
    # Delta a is r_max less that of the first frame; it grows by about the
    # half millimetre a frame the ball does
    r0 = float(rows[0][4])
    for r in rows:
        assert math.isclose(float(r[8]), float(r[4]) - r0, abs_tol=2e-11), r
    assert float(rows[-1][8]) > 0.0015 and float(rows[-1][9]) > 0, rows[-1]
print("ok")
EOF
    assert_output "ok"
    # the default centre is the centroid of the block, (5, 5, 5) mm
    pd-crack-tip --front --axis z --center 0.005,0.005,0.005 ball.h5 > c.txt
    cmp a.txt c.txt
}

@test "--plot draws Delta a(t) as a PNG; without gnuplot one error line and no file" {
    run -0 --separate-stderr pd-crack-tip --plot da.png "$RUN"
    assert_equal "${#stderr_lines[@]}" 0
    assert_line --index 0 "$HEADER"
    run -0 "$PY" -c 'import sys; print(open(sys.argv[1], "rb").read(8) == b"\x89PNG\r\n\x1a\n")' da.png
    assert_output "True"
    pd-crack-tip --front --axis z --plot front.png "$RUN" > /dev/null
    [ -s front.png ]
    # no gnuplot on PATH: only pd-crack-tip itself
    mkdir onlypd
    ln -s "$(command -v pd-crack-tip)" onlypd/pd-crack-tip
    run -1 --separate-stderr env PATH="$PWD/onlypd" pd-crack-tip --plot none.png "$RUN"
    assert_one_error "^pd-crack-tip: error: cannot draw 'none.png': gnuplot is not on PATH$"
    run ls -A
    refute_output --partial "none.png"
    # a gnuplot that fails: no PNG, no temporary left
    mkdir badgp
    printf '#!/bin/sh\ncat > /dev/null\nexit 3\n' > badgp/gnuplot
    chmod +x badgp/gnuplot
    PATH=$PWD/badgp:$PATH expect_runtime_error "gnuplot failed" pd-crack-tip --plot bad.png "$RUN"
    run ls -A
    refute_output --partial "bad.png"
    refute_output --partial ".tmp"
}

@test "--path writes the damaged zone of every frame as .vtu files and a .pvd" {
    mkdir out
    pd-crack-tip --path out/crack "$RUN" > t.txt
    # the .pvd parses as XML and names one file per frame, relative to it,
    # with the frame's time
    "$PY" - out/crack.pvd <<'EOF' > pvd.txt
import sys
import xml.etree.ElementTree as ET
root = ET.parse(sys.argv[1]).getroot()
assert root.get("type") == "Collection"
for d in root.iter("DataSet"):
    print(d.get("file"), d.get("timestep"))
EOF
    awk 'NR > 1 { print $1, $2, $9 }' t.txt | paste -d' ' - pvd.txt > both.txt
    [ "$(wc -l < both.txt)" -eq 5 ]
    # each .vtu holds the frame's damaged particles (the table's count)
    while read -r step time count file ts; do
        assert_equal "$file" "$(printf 'crack_%08d.vtu' "$step")"
        "$PY" -c 'import sys, math; assert math.isclose(float(sys.argv[1]), float(sys.argv[2]), rel_tol=1e-8, abs_tol=1e-300)' "$ts" "$time"
        run -0 read_vtu "out/$file"
        assert_output "$count displacement damage material id Points connectivity offsets types"
    done < both.txt
    # with --front a front flag
    pd-crack-tip --front --path out/front "$RUN" > /dev/null
    run -0 read_vtu out/front_00000100.vtu
    assert_output --regexp '^[1-9][0-9]* displacement damage material id front Points'
    # PREFIX's folder is made, with its parents, as pd-dump2vtk -o does
    pd-crack-tip --path new/deeper/crack "$RUN" > /dev/null
    [ -d new/deeper ] && [ -s new/deeper/crack.pvd ]
    run -0 read_vtu new/deeper/crack_00000100.vtu
    # a part of it that is a file is one error line
    touch plain
    expect_runtime_error "cannot make directory 'plain/sub': 'plain' is not a directory" \
        pd-crack-tip --path plain/sub/crack "$RUN"
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

@test "a file without frames or without bonds has no damage data: one line, exit 1" {
    expect_runtime_error "'.*model.h5' has no damage data: no /frames" pd-crack-tip "$MODEL"
    expect_runtime_error "'.*lattice.h5' has no damage data: no /frames" pd-crack-tip "$LATTICE"
    cp "$RUN" nobonds.h5
    py 'del h5py.File(sys.argv[1], "r+")["bonds"]' nobonds.h5
    expect_runtime_error "has no damage data: no /bonds" pd-crack-tip nobonds.h5
    cp "$RUN" noframes.h5
    py '
f = h5py.File(sys.argv[1], "r+")
for k in list(f["frames"]):
    del f["frames"][k]' noframes.h5
    # a run killed before its first frame: no rows yet, not an error
    run -0 --separate-stderr pd-crack-tip noframes.h5
    assert_output "$HEADER"
    run -0 pd-crack-tip --front noframes.h5
    assert_output "$FRONT_HEADER"
    expect_runtime_error "no complete frame" pd-crack-tip --plot n.png noframes.h5
    [ ! -e n.png ]
    expect_runtime_error "no damage data" pd-crack-tip --front --plot x.png --path p "$LATTICE"
    [ ! -e x.png ] && [ ! -e p.pvd ]
}
