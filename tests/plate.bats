#!/usr/bin/env bats
# tests/plate.bats -- 2-D plates, which have no program of their own:
# pd-lattice --dimension 2 --thickness H, the file's /particles@thickness and
# its checks, pd-bonds on a plate (families in the plane, partial volumes,
# sorting, a pre-crack through the thickness), the plane-stress constants of
# pd-run (c = 9E/(pi H delta^3), s0 = sqrt(4 pi G0/(9 E delta))), a plate
# through the whole pipeline, and the energy balance of an elastic plate.
# The plate is 20 mm square, 0.5 mm spacing (1681 particles), 1 mm thick,
# steel-like (seed 004 section 5).

load test_helper

setup() {
    cd "$BATS_TEST_TMPDIR"
}

PLATE=(--dimension 2 --thickness 0.001 --spacing 0.0005 --density 8000
       --box -0.01,0.01,-0.01,0.01,0,0)
E=192e9
DELTA=0.0015001

make_plate() {
    pd-lattice -q "${PLATE[@]}" "$@" -o plate.h5
}

# ------------------------------------------------------------ pd-lattice

@test "a plate is the square lattice (i dx, j dx, 0) with volume dx^2 H and its thickness" {
    make_plate
    py "
with h5py.File(sys.argv[1]) as f:
    p = f['particles']
    x = p['position'][:]
    assert len(x) == 41 * 41, len(x)
    assert (x[:, 2] == 0).all()
    n = np.round(x[:, :2] / 0.0005)
    assert (x[:, :2] == n * 0.0005).all() and n.min() == -20 and n.max() == 20
    assert int(p.attrs['dimension']) == 2 and p.attrs['thickness'] == 0.001
    assert np.allclose(p['volume'][:], 0.0005 ** 2 * 0.001, rtol=1e-15)
    assert np.allclose(p['radius'][:], 0.00025, rtol=1e-15)
    assert len(set(map(tuple, n))) == len(n)" plate.h5
}

@test "regions are cut at z = 0: a box above the plane gives no plate; a sphere gives a disk" {
    expect_runtime_error "no lattice site at z = 0" \
        pd-lattice --dimension 2 --thickness 0.001 --spacing 0.001 --density 1 \
        --box 0,0.01,0,0.01,0.001,0.002 -o x.h5
    [ ! -e x.h5 ]
    # a sphere of radius 3.5 mm off the plane by 2 mm: a disk of radius
    # sqrt(3.5^2 - 2^2) mm at z = 0
    run -0 pd-lattice -q --dimension 2 --thickness 0.001 --spacing 0.001 --density 1 \
        --sphere 0,0,0.002,0.0035 -o disk.h5
    py "
with h5py.File(sys.argv[1]) as f:
    n = len(f['particles/position'])
want = sum(1 for i in range(-4, 5) for j in range(-4, 5) if i * i + j * j + 4 <= 3.5 ** 2)
assert n == want, (n, want)" disk.h5
}

@test "--perturb moves a plate's sites only in the plane" {
    make_plate --perturb 0.0001 --seed 3
    py "
with h5py.File(sys.argv[1]) as f:
    x = f['particles/position'][:]
assert (x[:, 2] == 0).all()
off = x[:, :2] - np.round(x[:, :2] / 0.0005) * 0.0005
assert np.abs(off).max() <= 0.0001 and np.abs(off).max() > 0.00005" plate.h5
}

@test "--dimension and --thickness: usage errors exit 2" {
    B=(--spacing 0.001 --density 1 --box 0,0.01,0,0.01,0,0)
    expect_usage_error "--dimension 2 needs --thickness" pd-lattice --dimension 2 "${B[@]}" -o x.h5
    expect_usage_error "--thickness is for a plate" pd-lattice --thickness 0.001 "${B[@]}" -o x.h5
    expect_usage_error "--thickness is for a plate" \
        pd-lattice --dimension 3 --thickness 0.001 "${B[@]}" -o x.h5
    for d in 1 4 0 2.5 x ""; do
        expect_usage_error "--dimension must be 2 or 3" \
            pd-lattice --dimension "$d" --thickness 0.001 "${B[@]}" -o x.h5
    done
    for h in 0 -1 nan inf x; do
        expect_usage_error "--thickness must be a positive number" \
            pd-lattice --dimension 2 --thickness "$h" "${B[@]}" -o x.h5
    done
    [ ! -e x.h5 ]
    run -0 pd-lattice --help
    assert_output --partial "--dimension D"
    assert_output --partial "--thickness H"
}

@test "readers check a plate: a thickness, positive and finite, and z = 0" {
    make_plate
    bad() { # bad NAME CODE: a copy of plate.h5 changed by CODE (f is the file)
        cp plate.h5 "$1.h5"
        py "
with h5py.File(sys.argv[1], 'a') as f:
    $2" "$1.h5"
    }
    bad nothick "del f['particles'].attrs['thickness']"
    bad negthick "f['particles'].attrs['thickness'] = -0.001"
    bad nanthick "f['particles'].attrs['thickness'] = float('nan')"
    bad offplane "f['particles/position'][5, 2] = 1e-6"
    bad dim4 "f['particles'].attrs['dimension'] = np.int64(4)"
    expect_runtime_error "dimension 2 without a thickness" pd-bonds --horizon $DELTA nothick.h5 -o x.h5
    expect_runtime_error "thickness must be positive" pd-bonds --horizon $DELTA negthick.h5 -o x.h5
    expect_runtime_error "thickness must be positive" pd-bonds --horizon $DELTA nanthick.h5 -o x.h5
    expect_runtime_error "has z = 1e-06, not 0" pd-bonds --horizon $DELTA offplane.h5 -o x.h5
    expect_runtime_error "dimension 4" pd-bonds --horizon $DELTA dim4.h5 -o x.h5
    [ ! -e x.h5 ]
}

# ------------------------------------------------------------ pd-bonds

@test "pd-bonds on a plate: sorted families in the plane, 28 inside, partial volumes, thickness kept" {
    make_plate
    run -0 pd-bonds -q --horizon $DELTA plate.h5 -o model.h5
    py "
with h5py.File(sys.argv[1]) as f:
    p = f['particles']
    assert int(p.attrs['dimension']) == 2 and p.attrs['thickness'] == 0.001
    x = p['position'][:]
    ids = p['id'][:]
    assert sorted(ids) == list(range(1, len(x) + 1))
    off, nb, _, vf = pdh5.bonds(f)
    for i in range(len(x)):
        fam = nb[off[i]:off[i + 1]]
        d = np.round((x[fam, :2] - x[i, :2]) / 0.0005).astype(int)
        assert ((d ** 2).sum(1) <= 9).all()
        if np.abs(x[i, :2]).max() <= 0.0085:
            assert len(fam) == 28, (i, len(fam))
            # nu = (delta + r - |xi|)/(2r) beyond delta - r = 2.5002 dx (delta = 3.0002 dx)
            # (sqrt 8 and 3 spacings away), 1 within
            v = vf[off[i]:off[i + 1]]
            r = np.sqrt((d ** 2).sum(1))
            want = np.where(r <= 2.5002, 1, 3.0002 + 0.5 - r)
            assert np.allclose(v, want, rtol=1e-9, atol=0), (v, want)
            assert np.allclose(v[r == 3], 0.5002, rtol=1e-9)
" model.h5
}

@test "a --crack segment through a plate breaks exactly the bonds that cross it" {
    make_plate
    # the segment y = 0.25 mm (between two rows) from x = -11 mm to x = 0
    run -0 --separate-stderr pd-bonds --horizon $DELTA --crack segment,-0.011,0.00025,0,0.00025 \
        plate.h5 -o model.h5
    py "
with h5py.File(sys.argv[1]) as f:
    x = f['particles/position'][:]
    off, nb = pdh5.bonds(f)[:2]
    pre = np.unpackbits(f['bonds/precrack'][:], bitorder='little')[:len(nb)]
i = np.repeat(np.arange(len(x)), np.diff(off))
j = nb
yc = 0.00025
cross = (x[i, 1] - yc) * (x[j, 1] - yc) < 0
t = (yc - x[i, 1]) / np.where(cross, x[j, 1] - x[i, 1], 1)
xc = x[i, 0] + t * (x[j, 0] - x[i, 0])
want = cross & (xc >= -0.011) & (xc <= 0)
assert (pre == want).all(), (pre.sum(), want.sum())
print(want.sum() // 2)" model.h5
    [[ "$stderr" =~ ${output}\ bonds\ broken ]]
}

# ------------------------------------------------------------ pd-run

@test "pd-run on a plate: plane-stress c = 9E/(pi H delta^3), s0 = sqrt(4 pi G0/(9 E delta)), logged" {
    make_plate
    pd-bonds -q --horizon $DELTA plate.h5 -o model.h5
    run -0 --separate-stderr pd-run --youngs-modulus $E --failure-energy 250 --steps 0 \
        model.h5 -o run.h5
    [[ "$stderr" =~ "a 2-D plate of thickness 0.001 m: plane-stress PMB" ]]
    [[ "$stderr" =~ "K = 3E/4, plane stress" ]]
    [[ "$stderr" =~ "2-D: sqrt(4 G0/(c H delta^4))" ]]
    py "
import math
with h5py.File(sys.argv[1]) as f:
    s = f['scene'].attrs
    E, H, d = $E, 0.001, $DELTA
    c = 9 * E / (math.pi * H * d ** 3)
    assert abs(s['c'] / c - 1) < 1e-14, (s['c'], c)
    s0 = math.sqrt(4 * math.pi * 250 / (9 * E * d))
    assert abs(s['s00'] / s0 - 1) < 1e-14, (s['s00'], s0)
    assert s['youngs_modulus'] == E and abs(s['bulk_modulus'] / (0.75 * E) - 1) < 1e-15" run.h5
    # --bulk-modulus is the 2-D bulk modulus: K = 3E/4 gives the same c (and,
    # given last, it wins over --youngs-modulus)
    run -0 pd-run -q --youngs-modulus 1e9 --bulk-modulus 144e9 --steps 0 model.h5 -o runk.h5
    py "
with h5py.File(sys.argv[1]) as a, h5py.File(sys.argv[2]) as b:
    assert abs(a['scene'].attrs['c'] / b['scene'].attrs['c'] - 1) < 1e-14
    assert 'youngs_modulus' not in b['scene'].attrs" run.h5 runk.h5
}

@test "pd-run --youngs-modulus in 3-D: K = 2E/3 (nu = 1/4), c = 18K/(pi delta^4)" {
    make_block
    run -0 --separate-stderr pd-run --youngs-modulus 72e9 --steps 0 model.h5 -o run.h5
    [[ "$stderr" =~ "K = 2E/3, nu = 1/4" ]]
    [[ ! "$stderr" =~ plane-stress ]]
    py "
import math
with h5py.File(sys.argv[1]) as f:
    c, d = f['scene'].attrs['c'], $HORIZON
    want = 18 * (2 * 72e9 / 3) / (math.pi * d ** 4)
    assert abs(c / want - 1) < 1e-14, (c, want)" run.h5
    expect_usage_error "--youngs-modulus must be a positive number" \
        pd-run --youngs-modulus -1 --steps 1 model.h5 -o x.h5
    expect_usage_error "--c or --bulk-modulus \(or --youngs-modulus\)" pd-run --steps 1 model.h5 -o x.h5
    [ ! -e x.h5 ]
}

@test "a wedge opens a pre-cracked plate: pd-run, pd-damage, pd-crack-tip, pd-dump2vtk" {
    make_plate
    pd-bonds -q --horizon $DELTA --crack segment,-0.011,0,0,0 plate.h5 -o model.h5
    # a sphere of radius 2 mm driven at 50 m/s into the crack's mouth
    run -0 pd-run -q --youngs-modulus $E --failure-energy 50 \
        --indenter sphere,-0.012,0,0,0.002,1e17,50,0,0 --steps 400 --every 100 \
        model.h5 -o run.h5
    run -0 pd-damage -q run.h5
    py "
with h5py.File(sys.argv[1]) as f:
    fr = sorted(f['frames'].values(), key=lambda g: g.attrs['step'])
    assert len(fr) == 5
    broken = [g.attrs['broken_bonds'] for g in fr]
    assert broken == sorted(broken) and broken[-1] > broken[0] > 0, broken
    for g in fr:
        dmg = g['damage'][:]
        assert (dmg >= 0).all() and (dmg <= 1).all()
        assert (g['displacement'][:, 2] == 0).all(), 'out of the plane'" run.h5
    run -0 pd-crack-tip run.h5
    # the pre-crack ends at x = 0; the crack runs from there along +x
    py "
rows = [l.split() for l in sys.stdin.read().splitlines() if not l.startswith('#')]
tips = [float(r[3]) for r in rows]  # upper_m: the tip that runs along +x
assert abs(tips[0]) <= $DELTA, tips
assert tips[-1] > tips[0] + 0.0005, tips" <<<"$output"
    run -0 pd-dump2vtk -q run.h5 -o vtk
    # five frames of the plate and of the wedge (an indenter)
    [ "$(ls vtk/run_0*.vtu | wc -l)" -eq 5 ] && [ "$(ls vtk/run_indenter_*.vtu | wc -l)" -eq 5 ]
    [ -s vtk/run.pvd ]
}

@test "an elastic plate keeps its total energy within 0.1% over 2000 steps, in the plane" {
    make_plate
    pd-bonds -q --horizon $DELTA plate.h5 -o model.h5
    # a sphere 0.1 mm deep in the top edge pushes at 10 m/s and throws the plate
    run -0 pd-run -q --youngs-modulus $E --indenter sphere,0,0.012,0,0.002,1e19,0,-10,0 \
        --steps 2000 --every 100 model.h5 -o el.h5
    py "
with h5py.File(sys.argv[1]) as f:
    fr = sorted(f['frames'].values(), key=lambda g: g.attrs['step'])
    assert len(fr) == 21
    rho, V = f['particles/density'][:], f['particles/volume'][:]
    emax = 0
    for g in fr[1:]:
        a = g.attrs
        motion = a['kinetic_energy'] + a['elastic_energy'] + a['contact_energy']
        total = motion + a['released_energy'] + a['lost_energy'] - a['external_work']
        assert abs(total) <= 1e-3 * motion, (a['step'], total, motion)
        assert (g['displacement'][:, 2] == 0).all() and (g['velocity'][:, 2] == 0).all()
        emax = max(emax, a['elastic_energy'])
    a = fr[-1].attrs
    assert a['contact_energy'] == 0 and emax > 1e-3 * a['external_work'], emax
    # free flight: the momentum is that of the kinetic energy, along -y
    v = fr[-1]['velocity'][:]
    p = (rho * V)[:, None] * v
    m = (rho * V).sum()
    assert abs(p[:, 0].sum()) <= 1e-9 * abs(p[:, 1].sum()) and p[:, 1].sum() < 0
    assert abs(p[:, 1].sum() ** 2 / (2 * m) / a['kinetic_energy'] - 1) < 0.01" el.h5
}

@test "plane stress: a plate twice as thick moves the same (H enters c and the volumes only)" {
    for h in 0.001 0.002; do
        pd-lattice -q --dimension 2 --thickness $h --spacing 0.0005 --density 8000 \
            --box -0.005,0.005,-0.005,0.005,0,0 -o p$h.h5
        pd-bonds -q --horizon $DELTA p$h.h5 -o m$h.h5
        pd-run -q --youngs-modulus $E --allow-overlap \
            --indenter sphere,0,0.0069,0,0.002,1e19,0,-10,0 \
            --steps 300 m$h.h5 -o r$h.h5
    done
    py "
with h5py.File(sys.argv[1]) as a, h5py.File(sys.argv[2]) as b:
    ga, gb = list(a['frames'].values())[-1], list(b['frames'].values())[-1]
    ua, ub = ga['displacement'][:], gb['displacement'][:]
    assert np.abs(ua).max() > 0
    assert np.abs(ua - ub).max() <= 1e-9 * np.abs(ua).max()
    for k in ('kinetic_energy', 'elastic_energy', 'external_work'):
        assert abs(gb.attrs[k] / ga.attrs[k] - 2) < 1e-9, k
    assert a['scene'].attrs['dt'] == b['scene'].attrs['dt'] or \
        abs(a['scene'].attrs['dt'] / b['scene'].attrs['dt'] - 1) < 1e-12" r0.001.h5 r0.002.h5
}
