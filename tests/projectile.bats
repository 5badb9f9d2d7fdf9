#!/usr/bin/env bats
# pd-run --projectile: a rigid sphere that the body pushes back.  Momentum
# of particles and sphere together is conserved to rounding, a sphere on an
# elastic block stops and rebounds with the energy balance kept, a very
# heavy sphere is the constant-velocity indenter, a restart goes on bit for
# bit, the default K follows its stated rule, and bad specs are refused.

load test_helper

setup() {
    cd "$BATS_TEST_TMPDIR"
}

# a sphere of radius 3 mm above the top face (z = 10 mm) of make_block's
# cube, 0.1 mm away, moving down
SPHERE=0.005,0.005,0.0131,0.003

@test "--projectile in --help, and the run logs it and its K" {
    run -0 pd-run --help
    assert_output --partial "--projectile sphere,X,Y,Z,R,MASS,VX,VY,VZ[,K]"
    make_block
    run -0 --separate-stderr pd-run --bulk-modulus "$BULK" \
        --projectile "sphere,$SPHERE,0.001,0,0,-20" --steps 2 model.h5 -o r.h5
    [[ "$stderr" =~ effects:\ pmb\ projectile ]]
    [[ "$stderr" =~ projectile:\ mass\ 0.001\ kg,\ radius\ 0.003\ m,\ stiffness\ K\ [0-9.e+]+\ N/m\^5\ \(default ]]
}

@test "the default K: 2 K (spacing/4) = the largest bond stiffness sum of seed 004 eq. 46" {
    make_block
    pd-run -q --bulk-modulus "$BULK" --projectile "sphere,$SPHERE,0.001,0,0,-20" --steps 1 \
        model.h5 -o r.h5
    py "
import math
with h5py.File(sys.argv[1]) as f:
    p = f['particles']
    V = p['volume'][:]
    off, nb, length, nu = pdh5.bonds(f)
    w = V[nb] * nu / length
    c = f['scene'].attrs['c']
    smax = c * max(w[off[i]:off[i + 1]].sum() for i in range(len(off) - 1))
    K = f['scene'].attrs['projectile'][8]
    want = smax / (2 * 0.25 * p.attrs['spacing'])
    assert abs(K - want) <= 1e-12 * want, (K, want)
    o = f['scene'].attrs['options']
    assert 'projectile sphere,' in (o.decode() if isinstance(o, bytes) else o)" r.h5
}

@test "momentum of particles and sphere is conserved to rounding through contact and failure" {
    make_block
    # 60 m/s, 2 g: bonds break under the sphere, contact acts between particles
    run -0 --separate-stderr pd-run --bulk-modulus "$BULK" --failure 0.0005,0.25 --contact \
        --projectile "sphere,$SPHERE,0.002,0,0,-60" --steps 300 --every 20 --threads 2 \
        model.h5 -o r.h5
    py "
with h5py.File(sys.argv[1]) as f:
    m = f['particles/density'][:] * f['particles/volume'][:]
    M = 0.002
    p0 = M * np.array([0, 0, -60.0])
    fr = sorted(f['frames'].values(), key=lambda g: g.attrs['step'])
    worst = 0
    for g in fr:
        P = (m[:, None] * g['velocity'][:]).sum(axis=0) + M * g.attrs['projectile_velocity']
        worst = max(worst, np.abs(P - p0).max() / np.abs(p0).max())
    last = fr[-1].attrs
    assert last['broken_bonds'] > 0 and last['lost_particles'] == 0, dict(last)
    assert last['projectile_velocity'][2] > -60 + 1, last['projectile_velocity']
    assert worst < 1e-12, worst  # measured 1e-15
    print('relative momentum error', worst)" r.h5
}

@test "a sphere onto an elastic block slows, stops and rebounds; the energy balance holds" {
    make_block
    run -0 --separate-stderr pd-run --bulk-modulus "$BULK" --contact \
        --projectile "sphere,$SPHERE,0.001,0,0,-20" --steps 400 --every 10 --status 100 \
        model.h5 -o r.h5
    # the status line shows the sphere's velocity
    [[ "$stderr" =~ pd-run:\ projectile\ at\ \(.*\)\ m,\ velocity\ \(.*\)\ m/s ]]
    py "
with h5py.File(sys.argv[1]) as f:
    fr = sorted(f['frames'].values(), key=lambda g: g.attrs['step'])
    vz = np.array([g.attrs['projectile_velocity'][2] for g in fr])
    assert vz[0] == -20 and vz.min() >= -20 and vz[-1] > 0, vz
    # it slows monotonically while pressing in, then turns
    k = int(np.argmax(vz > 0))
    assert np.all(np.diff(vz[:k]) >= 0), vz[:k]
    names = ('kinetic_energy', 'elastic_energy', 'contact_energy', 'released_energy',
             'lost_energy', 'projectile_energy')
    tot = [sum(g.attrs[n] for n in names) - g.attrs['external_work'] for g in fr]
    e0 = 0.5 * 0.001 * 20**2
    assert abs(fr[0].attrs['projectile_energy'] - e0) <= 1e-15 * e0
    # the balance: within 5e-4 of the energy put in (measured 5e-5 at worst,
    # while the sphere presses in; the Verlet error of the stiff contact)
    drift = max(abs(t - e0) for t in tot) / e0
    assert drift < 5e-4, drift
    # the block got some of it, the sphere kept most of the rest
    last = fr[-1].attrs
    assert last['kinetic_energy'] > 0.1 * e0 and last['projectile_energy'] > 0.1 * e0, dict(last)
    print('energy drift', drift)" r.h5
}

@test "a very heavy sphere is the indenter at constant velocity" {
    make_block
    local K=1e19 dt=2e-7
    pd-run -q --bulk-modulus "$BULK" --contact --dt "$dt" --allow-overlap \
        --projectile "sphere,0.005,0.005,0.0125,0.003,1e9,0,0,-50,$K" --steps 150 model.h5 -o p.h5
    pd-run -q --bulk-modulus "$BULK" --contact --dt "$dt" --allow-overlap \
        --indenter "sphere,0.005,0.005,0.0125,0.003,$K,0,0,-50" --steps 150 model.h5 -o i.h5
    py "
with h5py.File(sys.argv[1]) as p, h5py.File(sys.argv[2]) as i:
    a, b = p['frames/00000150'], i['frames/00000150']
    up, ui = a['displacement'][:], b['displacement'][:]
    scale = np.abs(ui).max()
    assert scale > 1e-6, scale   # the indenter pushed the block in
    diff = np.abs(up - ui).max() / scale
    assert diff < 1e-6, diff  # measured 3e-12
    # the sphere kept its velocity, to 1e-6
    v = a.attrs['projectile_velocity']
    assert abs(v[2] + 50) < 50e-6 and a.attrs['external_work'] == 0, v
    print('relative difference', diff)" p.h5 i.h5
}

@test "--restart with a projectile goes on bit for bit" {
    make_block
    local opts=(--bulk-modulus "$BULK" --failure 0.0005,0.25 --contact
                --projectile "sphere,$SPHERE,0.002,0,0,-60" --every 20 --threads 2 -q)
    pd-run "${opts[@]}" --steps 120 model.h5 -o full.h5
    pd-run "${opts[@]}" --steps 60 model.h5 -o run.h5
    run -0 pd-run --restart run.h5 --steps 60 -q --threads 2
    py "
with h5py.File(sys.argv[1]) as a, h5py.File(sys.argv[2]) as b:
    for k in ('00000080', '00000100', '00000120'):
        x, y = a['frames'][k], b['frames'][k]
        for d in ('displacement', 'velocity', 'state'):
            assert np.array_equal(x[d][:].view(np.uint8), y[d][:].view(np.uint8)), (k, d)
        for n in ('projectile_position', 'projectile_velocity', 'projectile_energy',
                  'kinetic_energy', 'contact_energy', 'released_energy', 'broken_bonds'):
            assert np.array_equal(x.attrs[n], y.attrs[n]), (k, n, x.attrs[n], y.attrs[n])" \
        full.h5 run.h5
}

@test "--restart refuses --projectile" {
    make_block
    pd-run -q --bulk-modulus "$BULK" --projectile "sphere,$SPHERE,0.001,0,0,-20" --steps 4 \
        --every 2 model.h5 -o run.h5
    expect_usage_error "--restart goes on with the scene" pd-run --restart run.h5 --steps 2 \
        --projectile "sphere,$SPHERE,0.001,0,0,-30"
}

@test "bad --projectile specs are usage errors" {
    make_block
    for spec in "sphere,0,0,0,0.003,0.001,0,0" "sphere,0,0,0,0.003,0.001,0,0,-1,1e20,5" \
        "box,0,0,0,0.003,0.001,0,0,-1" "sphere,0,0,0,0,0.001,0,0,-1" \
        "sphere,0,0,0,-0.003,0.001,0,0,-1" "sphere,0,0,0,0.003,0,0,0,-1" \
        "sphere,0,0,0,0.003,-1,0,0,-1" "sphere,0,0,0,0.003,0.001,0,0,-1,0" \
        "sphere,0,0,0,0.003,0.001,0,0,-1,-1e20" "sphere,0,0,0,0.003,0.001,0,0,x" \
        "sphere,0,0,0,0.003,nan,0,0,-1"; do
        expect_usage_error "--projectile" pd-run --c 1e21 --steps 1 --projectile "$spec" \
            model.h5 -o r.h5
        [ ! -e r.h5 ]
    done
}
