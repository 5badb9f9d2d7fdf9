#!/usr/bin/env bats
# Particle sets and boundary conditions: pd-lattice --set names the particles
# inside a region, by id, carried by pd-bonds (which reorders rows) and
# pd-run; pd-run --velocity-bc and --displacement-bc hold the motion of a
# set exactly, --body-force pushes it; the work they do keeps the energy
# balance; a restart goes on bit for bit; and every bad input is refused.

load test_helper

setup() {
    cd "$BATS_TEST_TMPDIR"
}

# A bar of 41 x 5 x 5 particles along x (40 mm), with the sets `left` and
# `right` (the three end layers, a horizon thick) and `all`.
_build_bar() {
    pd-lattice -q --spacing "$SPACING" --density "$DENSITY" --box 0,0.04,0,0.004,0,0.004 \
        --set left=box,-1,0.0025,-1,1,-1,1 --set right=box,0.0375,1,-1,1,-1,1 \
        --set all=box,-1,1,-1,1,-1,1 -o "$1/lattice.h5" &&
        pd-bonds -q --horizon "$HORIZON" "$1/lattice.h5" -o "$1/bar.h5"
}

make_bar() {
    _pd_cached bar _build_bar || return 1
    cp "$_PD_CACHE/lattice.h5" "$_PD_CACHE/bar.h5" .
}

K=(--bulk-modulus "$BULK")

# balance RUN.h5: the largest |balance - balance at step 0| over the frames,
# and the work at the last frame, "DRIFT WORK".
balance() {
    py "
f = h5py.File(sys.argv[1], 'r')
fr = [f['frames'][k].attrs for k in sorted(f['frames'], key=int)]
tot = [a['kinetic_energy'] + a['elastic_energy'] + a['contact_energy'] + a['released_energy']
       + a['lost_energy'] - a['external_work'] for a in fr]
print(max(abs(t - tot[0]) for t in tot), fr[-1]['external_work'])" "$1"
}

# ------------------------------------------------------------ sets

@test "--set: the particles inside the region, by id, through pd-bonds and pd-run" {
    make_bar
    pd-run "${K[@]}" --steps 2 -q bar.h5 -o run.h5
    py "
for fn in sys.argv[1:]:
    f = h5py.File(fn, 'r')
    x, ids = f['particles/position'][:], f['particles/id'][:]
    for name, inside in (('left', x[:, 0] <= 0.0025), ('right', x[:, 0] >= 0.0375),
                         ('all', np.ones(len(x), bool))):
        s = f['sets'][name]
        assert s.dtype == np.int64 and s.ndim == 1, (fn, name, s.dtype)
        assert np.array_equal(s[:], np.sort(ids[inside])), (fn, name)
    assert inside.sum() == 1025 and sorted(f['sets']) == ['all', 'left', 'right']
# pd-bonds reordered the rows: the ids are the same, the rows are not
a, b = h5py.File(sys.argv[1], 'r'), h5py.File(sys.argv[2], 'r')
assert not np.array_equal(a['particles/id'][:], b['particles/id'][:])" lattice.h5 bar.h5 run.h5
    py "
f = h5py.File(sys.argv[1], 'r')
assert len(f['sets/left']) == len(f['sets/right']) == 75" bar.h5
}

@test "--set: bad, duplicate and empty sets are refused" {
    L=(pd-lattice --spacing 0.001 --density 1000 --box 0,0.005,0,0.005,0,0.005 -o x.h5)
    expect_usage_error "--set NAME" "${L[@]}" --set 'a b=box,0,1,0,1,0,1'
    expect_usage_error "--set NAME" "${L[@]}" --set '=box,0,1,0,1,0,1'
    expect_usage_error "--set NAME" "${L[@]}" --set '..=box,0,1,0,1,0,1'
    expect_usage_error "--set needs NAME=KIND" "${L[@]}" --set top
    expect_usage_error "given twice: 'a'" "${L[@]}" --set a=box,0,1,0,1,0,1 --set a=sphere,0,0,0,1
    expect_usage_error "box" "${L[@]}" --set a=box,0,1
    expect_runtime_error "set 'far' holds no particle" "${L[@]}" --set far=sphere,1,1,1,0.001
    [ ! -e x.h5 ]
    assert_no_temp .
}

@test "hostile /sets are refused with one line by pd-bonds and pd-run" {
    make_bar
    for kind in noid float rank2 group order empty badname; do
        for f in lattice.h5 bar.h5; do cp $f h-$kind-$f; done
        py "
kind = sys.argv[1]
for fn in sys.argv[2:]:
    with h5py.File(fn, 'a') as f:
        g = f['sets']
        if kind == 'noid': del g['left']; g['left'] = np.array([1, 99999], np.int64)
        if kind == 'float': del g['left']; g['left'] = np.array([1.0, 2.0])
        if kind == 'rank2': del g['left']; g['left'] = np.ones((2, 2), np.int64)
        if kind == 'order': del g['left']; g['left'] = np.array([3, 2], np.int64)
        if kind == 'empty': del g['left']; g['left'] = np.zeros(0, np.int64)
        if kind == 'badname': g['a b'] = np.array([1], np.int64)
        if kind == 'group': del f['sets']; f['sets'] = np.array([1], np.int64)" \
            $kind h-$kind-lattice.h5 h-$kind-bar.h5
        expect_runtime_error "sets|left|a b" pd-bonds --horizon "$HORIZON" h-$kind-lattice.h5 -o o.h5
        expect_runtime_error "sets|left|a b" pd-run "${K[@]}" --steps 1 h-$kind-bar.h5 -o o.h5
    done
    [ ! -e o.h5 ]
}

# ------------------------------------------------------------ options

@test "bad conditions: usage errors; unknown set, unreadable table, two holds of one axis: runtime" {
    make_bar
    R=(pd-run "${K[@]}" --steps 1 bar.h5 -o o.h5)
    expect_usage_error "SET,AXIS,PROFILE" "${R[@]}" --velocity-bc left,w,1
    expect_usage_error "SET,AXIS,PROFILE" "${R[@]}" --body-force left
    expect_usage_error "expected a number, points" "${R[@]}" --displacement-bc left,x,fast
    expect_usage_error "pulse durations must be positive" "${R[@]}" --velocity-bc left,x,pulses:1,0
    expect_usage_error "times must increase" "${R[@]}" --velocity-bc left,x,points:0,1,0,2
    printf '0 1\nzero 2\n' > bad.txt
    expect_usage_error "bad.txt.* line 2" "${R[@]}" --velocity-bc left,x,table:bad.txt
    expect_runtime_error "cannot read the profile table 'nope.txt'" "${R[@]}" --velocity-bc left,x,table:nope.txt
    expect_runtime_error "no set 'top'" "${R[@]}" --velocity-bc top,y,1
    expect_runtime_error "--velocity-bc all and --displacement-bc left both prescribe the x motion" \
        "${R[@]}" --velocity-bc all,x,1 --displacement-bc left,x,0
    # different axes of one particle may both be held
    run -0 "${R[@]}" -q --velocity-bc all,x,1 --displacement-bc left,y,0
    rm -f o.h5
    expect_usage_error "--restart goes on with the scene" pd-run --restart bar.h5 --steps 1 --body-force left,x,1
}

# ------------------------------------------------------------ physics

@test "--velocity-bc holds y = x + G(t), v = g(t) exactly; the rest of the bar moves" {
    make_bar
    run -0 --separate-stderr pd-run "${K[@]}" --steps 200 --every 20 --threads 2 \
        --velocity-bc right,x,pulses:20,5e-6,-20,5e-6 --velocity-bc left,y,points:0,0,1e-5,2 bar.h5 -o run.h5
    [[ "$stderr" =~ effects:\ pmb\ prescribed-motion ]]
    [[ "$stderr" =~ --velocity-bc\ right,x,pulses:20,5e-06,-20,5e-06\ on\ 75\ particles ]]
    py "
f = h5py.File(sys.argv[1], 'r')
ids, x = f['particles/id'][:], f['particles/position'][:]
row = {i: r for r, i in enumerate(ids)}
R = np.array([row[i] for i in f['sets/right'][:]]); L = np.array([row[i] for i in f['sets/left'][:]])
def G_pulse(t): return 20 * min(t, 5e-6) - 20 * min(max(t - 5e-6, 0), 5e-6)
def g_pulse(t): return 20.0 if t < 5e-6 else -20.0 if t < 1e-5 else 0.0
def g_ramp(t): return 2 * min(t, 1e-5) / 1e-5
def G_ramp(t): return t * t / 1e-5 if t < 1e-5 else 1e-5 + 2 * (t - 1e-5)
others = np.setdiff1d(np.arange(len(ids)), np.concatenate([R, L]))
moved = 0
for k in sorted(f['frames'], key=int):
    fr = f['frames'][k]; t = fr.attrs['time']
    y = x + fr['displacement'][:]; v = fr['velocity'][:]
    assert np.allclose(y[R, 0], x[R, 0] + G_pulse(t), rtol=1e-12, atol=0), k
    assert np.all(v[R, 0] == g_pulse(t)), (k, v[R, 0][:3], g_pulse(t))
    assert np.allclose(y[L, 1], x[L, 1] + G_ramp(t), rtol=1e-12, atol=1e-18), k
    assert np.allclose(v[L, 1], g_ramp(t), rtol=1e-12, atol=0), k
    moved = max(moved, np.abs(v[others, 0]).max())
# the pull sends a wave in: particles next to the held layer move
assert moved > 1, moved" run.h5
}

@test "--displacement-bc holds y = x + g(t) and v = g'(t) exactly" {
    make_bar
    pd-run "${K[@]}" --steps 100 --every 10 --threads 2 -q \
        --displacement-bc left,x,0 --displacement-bc right,z,points:0,0,1e-5,1e-5 bar.h5 -o run.h5
    py "
f = h5py.File(sys.argv[1], 'r')
ids, x = f['particles/id'][:], f['particles/position'][:]
row = {i: r for r, i in enumerate(ids)}
R = np.array([row[i] for i in f['sets/right'][:]]); L = np.array([row[i] for i in f['sets/left'][:]])
for k in sorted(f['frames'], key=int):
    fr = f['frames'][k]; t = fr.attrs['time']
    u, v = fr['displacement'][:], fr['velocity'][:]
    assert np.all(u[L, 0] == 0) and np.all(v[L, 0] == 0), k
    assert np.allclose(u[R, 2], min(t, 1e-5), rtol=1e-12, atol=1e-20), (k, u[R, 2][0], t)
    assert np.all(v[R, 2] == (1.0 if t < 1e-5 else 0.0)), k
assert np.abs(f['frames'][k]['velocity'][:, 2]).max() > 0" run.h5
}

@test "--body-force: the momentum grows as sum V_i b t; the work keeps the balance" {
    make_bar
    pd-run "${K[@]}" --steps 400 --every 40 --threads 2 -q --body-force right,y,2e8 \
        --body-force all,x,-1e7 bar.h5 -o run.h5
    py "
f = h5py.File(sys.argv[1], 'r')
ids, V, rho = f['particles/id'][:], f['particles/volume'][:], f['particles/density'][:]
row = {i: r for r, i in enumerate(ids)}
R = np.array([row[i] for i in f['sets/right'][:]])
for k in sorted(f['frames'], key=int):
    fr = f['frames'][k]; t = fr.attrs['time']
    assert fr.attrs['broken_bonds'] == 0
    p = (rho * V)[:, None] * fr['velocity'][:]
    py, px = p[:, 1].sum(), p[:, 0].sum()
    assert abs(py - V[R].sum() * 2e8 * t) <= 1e-9 * V[R].sum() * 2e8 * max(t, 1e-30), (k, py)
    assert abs(px + V.sum() * 1e7 * t) <= 1e-9 * V.sum() * 1e7 * max(t, 1e-30), (k, px)" run.h5
    read -r drift work < <(balance run.h5)
    echo "drift $drift work $work" >&3
    py "assert $work > 0 and $drift < 1e-5 * $work, ($drift, $work)"
}

@test "energy balance: a velocity pull on an elastic bar over 4000 steps" {
    make_bar
    pd-run "${K[@]}" --steps 4000 --every 400 --threads 2 -q --displacement-bc left,x,0 \
        --velocity-bc right,x,points:0,0,2e-6,1 bar.h5 -o run.h5
    read -r drift work < <(balance run.h5)
    echo "drift $drift work $work" >&3
    py "assert $work > 1 and $drift < 1e-5 * $work, ($drift, $work)"
}

@test "energy balance: square velocity pulses, the drift bounded and O(dt^2)" {
    make_bar
    P=(--velocity-bc left,x,pulses:-20,5e-6,20,5e-6 --velocity-bc right,x,pulses:20,5e-6,-20,5e-6)
    pd-run "${K[@]}" --steps 600 --dt 2.3e-7 --every 60 --threads 2 -q "${P[@]}" bar.h5 -o a.h5
    pd-run "${K[@]}" --steps 1200 --dt 1.15e-7 --every 120 --threads 2 -q "${P[@]}" bar.h5 -o b.h5
    read -r da wa < <(balance a.h5)
    read -r db wb < <(balance b.h5)
    echo "dt 2.3e-7: drift $da work $wa; dt 1.15e-7: drift $db work $wb" >&3
    py "assert $da < 0.01 * $wa and 3 < $da / $db < 5, ($da, $db)"
}

@test "--restart with conditions: 2N steps equal N and N more, bit for bit, without the table file" {
    make_bar
    printf '# t v\n0 0\n2e-6 3\n' > ramp.txt
    C=(--velocity-bc right,x,table:ramp.txt --displacement-bc left,x,0 --body-force all,y,1e7
       --velocity-bc left,z,pulses:5,3e-6,-5,3e-6)
    pd-run "${K[@]}" "${C[@]}" --steps 60 --every 20 --threads 2 -q bar.h5 -o full.h5
    pd-run "${K[@]}" "${C[@]}" --steps 40 --every 20 --threads 2 -q bar.h5 -o run.h5
    rm ramp.txt
    run -0 --separate-stderr pd-run --restart run.h5 --steps 20 --threads 2
    [[ "$stderr" =~ --velocity-bc\ right,x,points:0,0,2e-06,3 ]]
    py "
a, b = h5py.File(sys.argv[1], 'r'), h5py.File(sys.argv[2], 'r')
assert sorted(a['frames']) == sorted(b['frames'])
for k in a['frames']:
    for d in a['frames'][k]:
        x, y = a['frames'][k][d][:], b['frames'][k][d][:]
        assert x.dtype == y.dtype and np.array_equal(x.view(np.uint8), y.view(np.uint8)), (k, d)
    for n in a['frames'][k].attrs:
        assert a['frames'][k].attrs[n] == b['frames'][k].attrs[n], (k, n)
assert sorted(b['sets']) == ['all', 'left', 'right']
assert 'velocity-bc right,x,points:0,0,' in a['scene'].attrs['options']" full.h5 run.h5
    assert_no_temp .
}
