#!/usr/bin/env bats
# pd-run's time series (/series, --series N): a row of the energies, the
# damage, the body's momentum, each set's mean displacement and reaction
# force, and the projectile's and indenter's motion and force, every N
# steps.  Checked against a hand calculation (the reaction of a chain of
# bonds held stretched: c s V^2), Clapeyron's theorem on a bar at rest,
# Newton's third law (the reactions of a body at rest cancel), the momentum
# the indenter and the projectile exchange with the body, and the frames'
# own figures; its rows are the same at any thread count and through a
# restart, also from a frame of a killed run.

load test_helper
bats_require_minimum_version 1.5.0

setup() {
    cd "$BATS_TEST_TMPDIR"
}


# A chain of 11 particles along y at 1 mm (horizon 1.6 mm: each bonded to
# its neighbours only), its end particles the sets bottom and top.
make_chain() {
    pd-lattice -q --spacing 1e-3 --density 2000 --box -5e-4,5e-4,-5e-4,10.5e-3,-5e-4,5e-4 \
        --set bottom=box,-1,1,-1,5e-4,-1,1 --set top=box,-1,1,9.5e-3,1,-1,1 -o chain-l.h5
    pd-bonds -q --horizon 1.6e-3 chain-l.h5 -o chain.h5
}

# A 20 x 4 x 4 mm bar at 1 mm (525 particles), three planes at each end
# the sets left and right.
make_bar() {
    pd-lattice -q --spacing 0.001 --box 0,0.02,0,0.004,0,0.004 --density 2200 \
        --set left=box,-1,0.0025,-1,1,-1,1 --set right=box,0.0175,1,-1,1,-1,1 -o bar-l.h5
    pd-bonds -q --horizon 0.0030001 bar-l.h5 -o bar.h5
}

@test "series: the reaction of a chain held stretched is the hand calculation c s V^2" {
    make_chain
    # bottom held, top pulled 10 um in 0.2 ms and held; damped to rest
    pd-run -q --c 1e20 --steps 4000 --series 400 --damping 3e4 --velocity-bc bottom,y,0 \
        --displacement-bc top,y,points:0,0,2e-4,1e-5 chain.h5 -o r.h5
    py "series = pdh5.series
s = series('r.h5')
c, V, dx, u = 1e20, 1e-9, 1e-3, 1e-5
F = c * (u / (10 * dx)) * V * V      # every bond stretched u / L; 0.1 N
last = -1
assert abs(s['top.uy'][last] - u) < 1e-9 * u and s['bottom.uy'][last] == 0
assert abs(s['top.fy'][last] - F) < 1e-9 * F, (s['top.fy'][last], F)
assert abs(s['bottom.fy'][last] + F) < 1e-9 * F, s['bottom.fy'][last]
for a in 'xz':       # no force across the chain
    assert s['top.f' + a][last] == 0 and s['bottom.f' + a][last] == 0
assert s['kinetic_energy'][last] < 1e-20 * s['elastic_energy'][last]
# the elastic energy of 10 bonds, 1/2 c s^2 |xi| V V each (both directions)
E = 10 * 0.5 * c * (u / (10 * dx)) ** 2 * dx * V * V
assert abs(s['elastic_energy'][last] - E) < 1e-6 * E, (s['elastic_energy'][last], E)
assert list(s['step']) == list(range(0, 4001, 400)), s['step']
"
}

@test "series: a bar pulled slowly comes to rest with reactions that cancel and Clapeyron's energy" {
    make_bar
    pd-run -q --bulk-modulus 14e9 --steps 3000 --series 300 --damping 2e5 \
        --velocity-bc left,x,0 --displacement-bc right,x,points:0,0,5e-5,1e-5 bar.h5 -o r.h5
    py "series = pdh5.series
s = series('r.h5')
F, Fl, u = s['right.fx'][-1], s['left.fx'][-1], s['right.ux'][-1]
assert abs(u - 1e-5) < 1e-9 * u and s['left.ux'][-1] == 0
assert F > 0 and abs(F + Fl) < 1e-9 * F, (F, Fl)        # Newton's third law at rest
# Clapeyron: a linear body at rest holds half the work of its loads
E = s['elastic_energy'][-1]
assert abs(E - 0.5 * F * u) < 5e-3 * E, (E, 0.5 * F * u)
# the loads' work went into the bond energy and what the damping took:
# the balance (kinetic + elastic + damped - work) stays at its step-0 value
W, D, B = s['external_work'][-1], s['damped_energy'][-1], s['balance']
assert D > 0.1 * W and abs(B[-1] - B[0]) < 1e-3 * W, (W, E, D, B[0], B[-1])
# the transverse reactions of the held faces vanish (nothing holds them)
for a in 'yz':
    assert s['right.f' + a][-1] == 0 and s['left.f' + a][-1] == 0
"
}

@test "series: under a body force a set's force is its particles' volume times b" {
    make_bar
    pd-run -q --c 1e21 --steps 20 --series 5 --body-force right,x,points:0,0,1e-5,1e9 \
        bar.h5 -o r.h5
    py "series = pdh5.series
s = series('r.h5')
with h5py.File('bar.h5') as f:
    n = len(f['sets/right'])
dt = s['time'][1] / s['step'][1]
for k, t in enumerate(s['time']):
    b = 1e9 * min(t / 1e-5, 1.0)
    assert abs(s['right.fx'][k] - n * 1e-9 * b) <= 1e-12 * n * 1e-9 * 1e9, (k, s['right.fx'][k])
    assert s['left.fx'][k] == 0 and s['right.fy'][k] == 0
# the body's momentum grows by the force's impulse (trapezoidal, as the step)
imp = np.concatenate([[0], np.cumsum(0.5 * (s['right.fx'][1:] + s['right.fx'][:-1]) * np.diff(s['time']))])
assert np.allclose(s['px'], imp, rtol=1e-9, atol=1e-12 * abs(imp).max()), (s['px'], imp)
"
}

@test "series: the indenter's force is the momentum it gives the body, step by step" {
    make_block
    pd-run -q --bulk-modulus "$BULK" --allow-overlap --steps 60 --series 1 \
        --indenter sphere,0.005,0.005,0.0125,0.003,1e17,0,0,-100 model.h5 -o r.h5
    py "series = pdh5.series
s = series('r.h5')
dt = s['time'][1]
# the indenter moves as given
assert np.allclose(s['indenter.z'], 0.0125 - 100 * s['time'], rtol=0, atol=1e-15)
assert (s['indenter.vz'] == -100).all() and (s['indenter.vx'] == 0).all()
# it pushes the body down: the body pushes it up
assert s['indenter.fz'][-1] > 0
# velocity Verlet: P(n+1) - P(n) = dt/2 (F(n) + F(n+1)), F = -(force on the sphere)
scale = dt * abs(s['indenter.fz']).max()
for a in 'xyz':
    P, F = s['p' + a], -s['indenter.f' + a]
    dP = np.diff(P)
    want = 0.5 * dt * (F[1:] + F[:-1])
    assert np.allclose(dP, want, rtol=0, atol=1e-9 * scale), (a, abs(dP - want).max(), scale)
"
}

@test "series: the projectile and the body exchange momentum and keep its total" {
    make_block
    pd-run -q --bulk-modulus "$BULK" --steps 120 --series 1 \
        --projectile sphere,0.005,0.005,0.0131,0.003,0.002,0,0,-50 model.h5 -o r.h5
    py "series = pdh5.series
s = series('r.h5')
m, dt = 0.002, s['time'][1]
assert s['projectile.fz'].max() > 0, 'no contact'
for a in 'xyz':
    v, F = s['projectile.v' + a], s['projectile.f' + a]
    # its own Verlet step: m (v(n+1) - v(n)) = dt/2 (F(n) + F(n+1))
    assert np.allclose(m * np.diff(v), 0.5 * dt * (F[1:] + F[:-1]), rtol=0,
                       atol=1e-9 * (abs(F).max() * dt + 1e-30)), a
    # the total momentum stays that of the start
    total = s['p' + a] + m * v
    assert abs(total - total[0]).max() <= 1e-9 * m * 50, (a, abs(total - total[0]).max())
assert s['projectile.z'][0] == 0.0131
assert s['projectile_energy'][0] == 0.5 * m * 50 ** 2
"
}

@test "series: at a frame its row holds the frame's energies, broken bonds and damage" {
    make_block
    pd-run -q "${RUN_OPTS[@]}" --steps 120 --every 20 --series 10 model.h5 -o r.h5
    py "series = pdh5.series
s = series('r.h5')
assert list(s['step']) == list(range(0, 121, 10))
with h5py.File('r.h5') as f:
    for g in f['frames'].values():
        a = g.attrs
        k = list(s['step']).index(a['step'])
        for n in ('kinetic_energy', 'elastic_energy', 'contact_energy', 'released_energy',
                  'lost_energy', 'external_work'):
            assert s[n][k] == a[n], (a['step'], n, s[n][k], a[n])
        assert s['broken_bonds'][k] == a['broken_bonds'] and s['lost_particles'][k] == a['lost_particles']
        d = g['damage'][:]
        assert s['max_damage'][k] == d.max(), (s['max_damage'][k], d.max())
        assert s['damaged_particles'][k] == (d > 0.3).sum()
        bal = sum(a[n] for n in ('kinetic_energy', 'elastic_energy', 'contact_energy',
                                 'released_energy', 'lost_energy')) - a['external_work']
        assert abs(s['balance'][k] - bal) <= 1e-12 * abs(bal)
    assert s['broken_bonds'][-1] > 0 and s['damaged_particles'][-1] > 100
"
}

@test "series: its rows fall on multiples of --series and the last step, by default the status interval" {
    make_block
    pd-run -q --c 1e21 --steps 100 model.h5 -o a.h5
    pd-run -q --c 1e21 --steps 100 --status 25 model.h5 -o b.h5
    pd-run -q --c 1e21 --steps 100 --series 7 model.h5 -o c.h5
    py "series = pdh5.series
assert list(series('a.h5')['step']) == list(range(0, 101, 10))
assert list(series('b.h5')['step']) == [0, 25, 50, 75, 100]
assert list(series('c.h5')['step']) == list(range(0, 99, 7)) + [100]
with h5py.File('c.h5') as f:   # laid out for exactly its rows
    assert f['series/values'].shape[0] == f['series'].attrs['rows'] == 16
"
    run -2 --separate-stderr pd-run --c 1e21 --steps 10 --series 0 model.h5 -o d.h5
    assert_one_error "--series must be a positive integer"
}

# same_series A B: /series of A and B bit for bit
same_series() {
    py "
import numpy as np
with h5py.File(sys.argv[1]) as a, h5py.File(sys.argv[2]) as b:
    ga, gb = a['series'], b['series']
    assert ga.attrs['columns'] == gb.attrs['columns']
    assert ga.attrs['rows'] == gb.attrs['rows'], (ga.attrs['rows'], gb.attrs['rows'])
    x, y = ga['values'][: ga.attrs['rows']], gb['values'][: gb.attrs['rows']]
    assert np.array_equal(x.view(np.uint8), y.view(np.uint8)), np.argwhere(x != y)[:3]" "$@"
}

@test "series: the same bits at 1 and 2 threads, and through a restart" {
    local opts=("${RUN_OPTS[@]}" --velocity-bc top,x,1 --steps 120 --every 30 --series 10 -q)
    pd-lattice -q --spacing "$SPACING" --box 0,0.01,0,0.01,0,0.01 --density "$DENSITY" \
        --set top=box,-1,1,-1,1,0.0095,1 -o sets-l.h5
    pd-bonds -q --horizon "$HORIZON" sets-l.h5 -o sets.h5
    pd-run "${opts[@]}" --threads 1 sets.h5 -o one.h5
    pd-run "${opts[@]}" --threads 2 sets.h5 -o two.h5
    same_series one.h5 two.h5
    # 60 steps, then 60 more
    pd-run "${RUN_OPTS[@]}" --velocity-bc top,x,1 --steps 60 --every 30 --series 10 -q \
        sets.h5 -o half.h5
    pd-run -q --restart half.h5 --steps 60 --series 10
    same_series one.h5 half.h5
    # a run killed after its frame of step 90 wrote the rows of 100 and 110:
    # its restart from step 90 writes them again, as the run never stopped
    cp one.h5 killed.h5
    py "
with h5py.File('killed.h5', 'r+') as f:
    f['frames']['%08d' % 120].attrs['complete'] = 0
    f['series'].attrs['rows'] = 12        # rows 0..110 counted
    f['series/values'][10:12, 2:] = 0.0    # what the restart must rewrite" 
    pd-run -q --restart killed.h5 --steps 30 --series 10
    same_series one.h5 killed.h5
}
