#!/usr/bin/env bats
# pd-run --damping C[,SET]: the viscous force density -C rho v (LAMMPS fix
# viscous per unit mass), on every particle or on a set.  A bar rung by a
# pulse loses its mechanical energy as exp(-C t) (dE/dt = -2 C KE, and KE
# is half of E on average); the balance books what the damping took
# (damped=), so it stays at its step-0 value; the same bits at any thread
# count and through a restart; bad values are usage errors.

load test_helper
bats_require_minimum_version 1.5.0

setup() {
    cd "$BATS_TEST_TMPDIR"
    # a 20 x 4 x 4 mm bar at 1 mm (525 particles), its right end a set
    pd-lattice -q --spacing 0.001 --box 0,0.02,0,0.004,0,0.004 --density 2200 \
        --set right=box,0.0195,1,-1,1,-1,1 -o lattice.h5
    pd-bonds -q --horizon 0.0030001 lattice.h5 -o model.h5
}

# a 2 us pull on the right end, then free ringing
RING=(--c 1.05e21 --body-force right,x,pulses:1e10,2e-6)

# The frames' energies: step, time, mechanical (kinetic + elastic),
# damped, balance, work.
energies() {
    py "
with h5py.File(sys.argv[1]) as f:
    for g in sorted(f['frames'].values(), key=lambda g: g.attrs['step']):
        a = g.attrs
        d = a['damped_energy'] if 'damped_energy' in a else 0.0
        e = a['kinetic_energy'] + a['elastic_energy']
        print(a['step'], repr(a['time']), repr(e), repr(d),
              repr(e + a['contact_energy'] + a['released_energy'] + a['lost_energy']
                   - a['external_work'] + d), repr(a['external_work']))" "$1"
}

@test "damping: the ringing decays as exp(-C t), and the balance books what it took" {
    pd-run -q "${RING[@]}" --damping 2e4 --steps 1000 --every 50 model.h5 -o damped.h5
    pd-run -q "${RING[@]}" --steps 1000 --every 50 model.h5 -o free.h5
    energies damped.h5 > d.txt
    energies free.h5 > f.txt
    run -0 py "
import math
d = [list(map(float, l.split())) for l in open(sys.argv[1])]
f = [list(map(float, l.split())) for l in open(sys.argv[2])]
C = 2e4
# after the pulse (step 100 on): E(t) / E(t0) against exp(-C (t - t0)),
# E averaged over two neighbouring frames to smooth the kinetic/elastic swap
def avg(rows, k):
    return 0.5 * (rows[k][2] + rows[k + 1][2])
t0 = 0.5 * (d[2][1] + d[3][1])
worst = 0
for k in range(2, 18):
    t = 0.5 * (d[k][1] + d[k + 1][1])
    ratio = avg(d, k) / avg(d, 2) / math.exp(-C * (t - t0))
    worst = max(worst, abs(ratio - 1))
assert worst < 0.15, worst
# the free bar keeps its energy; the damped one lost 95% or more of it
assert abs(f[-1][2] / f[3][2] - 1) < 0.01, (f[-1][2], f[3][2])
assert d[-1][2] < 0.05 * d[3][2], (d[-1][2], d[3][2])
# what the damping took is what the bar lost: the balance holds to 2% of
# the work done (measured 1.0%), against 0.3% without damping (first
# order in dt: the force is taken at the half-step velocities)
work = d[-1][5]
assert d[-1][3] > 0.9 * work, (d[-1][3], work)
assert max(abs(r[4]) for r in d) < 0.02 * work, max(abs(r[4]) for r in d)
assert max(abs(r[4]) for r in f) < 0.005 * work
print('ok', round(worst, 3))" d.txt f.txt
    assert_output --regexp '^ok '
    # the undamped run has no damped_energy: its file is what it was
    run -0 py "
with h5py.File(sys.argv[1]) as f:
    assert all('damped_energy' not in g.attrs for g in f['frames'].values())
    assert 'damping' not in f['restart/0'].attrs
print('ok')" free.h5
}

@test "damping on a set takes less than on the whole bar; the log and the scene say where" {
    run -0 --separate-stderr pd-run "${RING[@]}" --damping 2e4,right --steps 400 --every 400 \
        model.h5 -o set.h5
    [[ "$stderr" == *"pd-run: --damping 20000 1/s (-C rho v) on right"* ]]
    [[ "$stderr" == *"effects: pmb body-force damping"* ]]
    [[ "$stderr" == *"pd-run: damping took "*" J so far"* ]]
    pd-run -q "${RING[@]}" --damping 2e4 --steps 400 --every 400 model.h5 -o all.h5
    run -0 py "
import h5py
a = h5py.File(sys.argv[1])['frames/00000400'].attrs['damped_energy']
b = h5py.File(sys.argv[2])['frames/00000400'].attrs['damped_energy']
assert 0 < a < 0.5 * b, (a, b)
print('ok')" set.h5 all.h5
    run -0 h5dump -a /scene/options set.h5
    assert_output --partial "damping 20000,right"
}

@test "damping: the same bits at 1 and 2 threads and through a restart" {
    pd-run -q "${RING[@]}" --damping 2e4 --steps 200 --every 50 --threads 1 model.h5 -o one.h5
    pd-run -q "${RING[@]}" --damping 2e4 --steps 200 --every 50 --threads 2 model.h5 -o two.h5
    run -0 h5_same one.h5 two.h5 'history|threads'
    pd-run -q "${RING[@]}" --damping 2e4 --steps 100 --every 50 --threads 2 model.h5 -o half.h5
    run -0 pd-run -q --restart half.h5 --steps 100
    run -0 h5_same one.h5 half.h5 'history|threads|^/restart|^/series|@steps|options'
    # without the damping's sums the restart differs
    pd-run -q "${RING[@]}" --damping 2e4 --steps 100 --every 50 model.h5 -o cut.h5
    py "
with h5py.File(sys.argv[1], 'r+') as f:
    for k in (0, 1):
        f['restart/%d' % k].attrs['damping'] = [0.0, 0.0]" cut.h5
    run -0 pd-run -q --restart cut.h5 --steps 100
    run -1 h5_same one.h5 cut.h5 'history|threads|^/restart|^/series|@steps|options'
}

@test "damping: bad values are usage errors; an unknown set is a runtime error" {
    for bad in 0 -1 abc 1e4, 1e4,no/set ""; do
        expect_usage_error "--damping needs C\[,SET\], C > 0 in 1/s and SET a set name, not" \
            pd-run "${RING[@]}" --steps 5 --damping "$bad" model.h5 -o r.h5
    done
    expect_runtime_error "--damping: the model has no set 'left'" \
        pd-run "${RING[@]}" --steps 5 --damping 1e4,left model.h5 -o r.h5
    [ ! -e r.h5 ]
    assert_no_temp .
}
