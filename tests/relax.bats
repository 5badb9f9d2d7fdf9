#!/usr/bin/env bats
# pd-run --relax: quasi-static loading by adaptive dynamic relaxation
# (Kilic & Madenci 2010).  A bar stretched along x in load steps must relax
# to the static state: in its interior a uniaxial stress with sigma_xx /
# eps_xx the modulus of the body as discretized, computed here from the
# model's own stencil (PMB: the bond-based lattice sum; LPS: the LPS energy
# of the lattice family), its reactions in balance, its elastic energy the
# loads' work, its kinetic energy decayed; the answer does not depend on
# the damping; the same bits at any thread count and through a restart.

load test_helper
bats_require_minimum_version 1.5.0

setup() {
    cd "$BATS_TEST_TMPDIR"
}

# _build_bar DIR NAME L W: DIR/NAME.h5, an L x W x W mm bar at 1 mm
# (horizon 3 spacings), the three planes at each end the sets left and
# right.
_build_bar() {
    local dir=$1 name=$2 l=$3 w=$4
    pd-lattice -q --spacing 0.001 --box "0,0.0$l,0,0.0$w,0,0.0$w" --density 2200 \
        --set left=box,-1,0.0025,-1,1,-1,1 --set "right=box,0.0$((l - 3))5,1,-1,1,-1,1" \
        -o "$dir/$name-l.h5" &&
        pd-bonds -q --horizon 0.0030001 "$dir/$name-l.h5" -o "$dir/$name.h5"
}
# The 40 x 12 x 12 mm bar (6929 particles) and a small 20 x 6 x 6 mm one,
# cached per file.
make_bar() {
    _pd_cached relax-bar _build_bar bar 40 12 || return 1
    cp "$_PD_CACHE/bar.h5" .
}
make_small() {
    _pd_cached relax-small _build_bar small 20 06 || return 1
    cp "$_PD_CACHE/small.h5" .
}

# STRETCH: the left end held, the right pulled 1 um per load step (1 s).
STRETCH=(--relax --dt 1 --velocity-bc left,x,0 --velocity-bc right,x,1e-6)

# CHECK MODEL RUN K [G]: the run's last frame against the lattice's modulus
# along x (uniaxial stress: E = (C11 - C12)(C11 + 2 C12)/(C11 + C12), the
# C of the model's energy under a uniform strain, summed over the stencil).
CHECK='
f = h5py.File(sys.argv[2]); model = sys.argv[1]; K = float(sys.argv[3])
st = f["bonds/stencil"][:].astype(float); beta = f["bonds/stencil_volume_factor"][:]
h = f["bonds"].attrs["spacing"]; delta = f["bonds"].attrs["horizon"]
xi = st * h; r = np.linalg.norm(xi, axis=1); V = h ** 3
def energy(e):                    # W of a uniform strain e, J/m^3
    ext = np.einsum("ja,ab,jb->j", xi, e, xi) / r          # extension
    if model == "pmb":            # 1/2 sum_j 1/2 c s^2 |xi| V beta
        c = f["scene"].attrs["c"]
        return 0.25 * c * np.sum((ext / r) ** 2 * r * V * beta)
    G = float(sys.argv[4]); w = 1 / r                         # influence 1/r
    m = np.sum(w * r * r * V * beta)
    th = 3 / m * np.sum(w * r * ext * V * beta)
    ed = ext - th * r / 3
    return K / 2 * th ** 2 + 15 * G / (2 * m) * np.sum(w * ed ** 2 * V * beta)
X, Y = np.diag([1.0, 0, 0]), np.diag([0, 1.0, 0])
C11 = 2 * energy(X); C12 = energy(X + Y) - energy(X) - energy(Y)
E = (C11 - C12) * (C11 + 2 * C12) / (C11 + C12)
x = f["particles/position"][:]
fr = f["frames"]; last = fr[sorted(fr)[-1]]
u, S = last["displacement"][:], last["stress"][:]
L, W = x[:, 0].max(), x[:, 1].max()
# the interior: the middle 40% of the length, farther than a horizon from the sides
inner = (x[:, 0] > 0.3 * L) & (x[:, 0] < 0.7 * L)
for a in (1, 2):
    inner &= abs(x[:, a] - W / 2) < W / 2 - delta - 0.5 * h
assert inner.sum() > 100, inner.sum()
eps = np.polyfit(x[inner, 0], u[inner, 0], 1)[0]
sxx = S[inner, 0, 0].mean()
assert abs(sxx / eps - E) < 5e-3 * E, (sxx / eps, E)
for a in (1, 2):                   # uniaxial stress: the sides are free
    assert abs(S[inner, a, a].mean()) < 1e-2 * sxx, S[inner, a, a].mean()
print(model, "E along x", E, "relaxed", sxx / eps)
'


@test "relax: a PMB bar stretched quasi-statically has the bond-based modulus in its interior" {
    make_bar
    pd-run -q --bulk-modulus 14e9 "${STRETCH[@]}" --steps 2 --fields stress bar.h5 -o r.h5
    py "$CHECK" pmb r.h5 14e9
    py "series = pdh5.series
s = series('r.h5')
F, Fl = s['right.fx'], s['left.fx']
assert list(s['step']) == [0, 1, 2] and list(s['time']) == [0.0, 1.0, 2.0]
assert abs(s['right.ux'][2] - 2e-6) < 1e-15
# at rest: the reactions balance, and grow linearly with the load
assert all(abs(F[1:] + Fl[1:]) < 1e-3 * F[1:]), (F, Fl)
assert abs(F[2] - 2 * F[1]) < 1e-3 * F[2], F
# Clapeyron: the elastic energy is the loads' work (the trapezoid of F du)
assert abs(s['elastic_energy'][2] - s['external_work'][2]) < 1e-3 * s['elastic_energy'][2]
# every load step relaxed to the tolerance, its kinetic energy decayed
it, res, load = s['relax_iterations'][1:], s['relax_residual'][1:], s['relax_load'][1:]
assert all(it > 20) and all(res <= 1e-4 * load), (it, res, load)
peak, ke = s['relax_peak_kinetic_energy'][1:], s['kinetic_energy'][1:]
assert all(ke < 1e-4 * peak), (ke, peak)
"
}

@test "relax: an LPS bar has the modulus of its LPS energy, and a tighter tolerance changes it less than the tolerance" {
    make_bar
    local lps=(--model lps --bulk-modulus 14e9 --shear-modulus 9e9)
    pd-run -q "${lps[@]}" "${STRETCH[@]}" --steps 2 --fields stress bar.h5 -o r.h5
    py "$CHECK" lps r.h5 14e9 9e9
    pd-run -q "${lps[@]}" "${STRETCH[@]}" --steps 2 --relax-tolerance 1e-7 bar.h5 -o tight.h5
    py "
a, b = h5py.File('r.h5'), h5py.File('tight.h5')
ua = a['frames/00000002/displacement'][:]; ub = b['frames/00000002/displacement'][:]
d = np.abs(ua - ub).max() / np.abs(ub).max()
assert 0 < d < 1e-3, d
ia = a['series/values'][2, list(a['series'].attrs['columns'].split()).index('relax_iterations')]
ib = b['series/values'][2, list(b['series'].attrs['columns'].split()).index('relax_iterations')]
assert ib > ia, (ia, ib)"
}

@test "relax: the relaxed answer does not depend on the damping, adaptive or fixed" {
    make_small
    local base=(-q --bulk-modulus 14e9 "${STRETCH[@]}" --steps 1 --relax-tolerance 1e-7)
    pd-run "${base[@]}" small.h5 -o adaptive.h5
    pd-run "${base[@]}" --damping 1e5 small.h5 -o c1.h5
    pd-run "${base[@]}" --damping 1e6 small.h5 -o c2.h5
    py "series = pdh5.series
u = {}
for name in ('adaptive', 'c1', 'c2'):
    with h5py.File(name + '.h5') as f:
        u[name] = f['frames/00000001/displacement'][:]
        assert 'damped_energy' not in f['series'].attrs['columns'].split()
scale = np.abs(u['adaptive']).max()
for name in ('c1', 'c2'):
    d = np.abs(u[name] - u['adaptive']).max()
    assert d < 1e-5 * scale, (name, d / scale)
it = {n: series(n + '.h5')['relax_iterations'][1] for n in u}
assert len(set(it.values())) == 3, it    # three different paths to one state
assert it['adaptive'] < it['c2'], it     # a heavy fixed damping crawls
"
}

@test "relax: a body force is held by the reaction of the held end" {
    make_small
    # the right end pulled by a body force density b along x
    pd-run -q --bulk-modulus 14e9 --relax --dt 1 --steps 2 --velocity-bc left,x,0 \
        --body-force right,x,points:0,0,2,2e9 small.h5 -o r.h5
    py "series = pdh5.series
s = series('r.h5')
with h5py.File('r.h5') as f:
    ids = f['sets/right'][:]
    V = f['particles/volume'][:][np.isin(f['particles/id'][:], ids)]
for n, b in ((1, 1e9), (2, 2e9)):
    F = V.sum() * b
    assert abs(s['right.fx'][n] - F) < 1e-12 * F
    assert abs(s['left.fx'][n] + F) < 1e-3 * F, (s['left.fx'][n], F)
    assert s['right.ux'][n] > 0
assert abs(s['elastic_energy'][2] - s['external_work'][2]) < 1e-3 * s['elastic_energy'][2]
"
}

@test "relax: a bar pulled past its critical stretch breaks in a relaxed state and carries nothing" {
    make_small
    # s0 = 5e-4: 2 um a load step over the 15 mm between the grips
    pd-run -q --bulk-modulus 14e9 --failure 5e-4,0 --relax --dt 1 --steps 5 \
        --velocity-bc left,x,0 --velocity-bc right,x,2e-6 small.h5 -o r.h5
    py "series = pdh5.series
s = series('r.h5')
F, Fl, broken = s['right.fx'], s['left.fx'], s['broken_bonds']
assert broken[1] == broken[2] == 0 and abs(F[2] - 2 * F[1]) < 1e-3 * F[2], (broken, F)
assert all(np.diff(broken) >= 0) and broken[4] > 0, broken
# cut through: the grips carry nothing but the tolerance's rounding
assert abs(F[5]) < 1e-4 * F[4] and abs(Fl[5]) < 1e-4 * F[4], (F, Fl)
assert all(abs(F[1:5] + Fl[1:5]) < 1e-3 * F[1:5]), (F, Fl)
assert s['elastic_energy'][5] < 1e-4 * s['elastic_energy'][4]
with h5py.File('r.h5') as f:      # a plane of particles lost half its bonds
    d = f['frames/00000005/damage'][:]
    x = f['particles/position'][:, 0]
assert max(d[np.isclose(x, xp)].min() for xp in np.unique(x)) > 0.3
"
}

@test "relax: the same bits at 1 and 2 threads, and through a restart" {
    make_small
    local opts=(-q --bulk-modulus 14e9 --failure 0.0005,0.25 "${STRETCH[@]}" --every 2)
    pd-run "${opts[@]}" --steps 4 --threads 1 small.h5 -o one.h5
    pd-run "${opts[@]}" --steps 4 --threads 2 small.h5 -o two.h5
    h5_same one.h5 two.h5 '@history$|@threads$|/scene@options$'
    pd-run "${opts[@]}" --steps 2 small.h5 -o half.h5
    pd-run -q --restart half.h5 --steps 2
    # a restart takes the scene's c, not the K it came from (/scene@bulk_modulus)
    h5_same one.h5 half.h5 '@history$|@threads$|/scene@(options|steps|bulk_modulus)$|/restart'
}

@test "relax: scenes it cannot relax are usage errors, a load step that does not relax stops the run" {
    make_small
    expect_usage_error "--relax needs --dt" pd-run --bulk-modulus 14e9 --relax --steps 1 \
        --velocity-bc left,x,0 small.h5 -o r.h5
    expect_usage_error "--relax is quasi-static: a projectile" pd-run --bulk-modulus 14e9 \
        --relax --dt 1 --steps 1 --projectile sphere,0,0,0.02,0.001,0.01,0,0,-1 small.h5 -o r.h5
    expect_usage_error "--relax is quasi-static: --model ves" pd-run --model ves \
        --bulk-modulus 14e9 --shear-modulus 9e9 --ves-lambda 0.5 --ves-tau 1e-5 --relax --dt 1 \
        --steps 1 small.h5 -o r.h5
    expect_usage_error "--relax takes --damping C" pd-run --bulk-modulus 14e9 --relax --dt 1 \
        --steps 1 --damping 1e5,left small.h5 -o r.h5
    expect_usage_error "--relax-tolerance must be below 1" pd-run --bulk-modulus 14e9 --relax \
        --dt 1 --steps 1 --relax-tolerance 1 small.h5 -o r.h5
    expect_usage_error "--relax-tolerance" pd-run --bulk-modulus 14e9 --relax \
        --dt 1 --steps 1 --relax-tolerance 0 small.h5 -o r.h5
    expect_usage_error "--relax-iterations must be a positive integer" pd-run --bulk-modulus 14e9 \
        --relax --dt 1 --steps 1 --relax-iterations 0 small.h5 -o r.h5
    [ ! -e r.h5 ]
    # 30 iterations are not enough: load step 1 of 2 stops the run, step 0 kept
    run -1 --separate-stderr pd-run -q --bulk-modulus 14e9 "${STRETCH[@]}" --steps 2 --every 1 \
        --relax-iterations 30 small.h5 -o r.h5
    assert_one_error "^pd-run: error: load step 1 is not relaxed after 30 iterations: the residual force .* above --relax-tolerance 0.0001"
    py "
with h5py.File('r.h5') as f:
    done = [k for k in f['frames'] if f['frames'][k].attrs['complete']]
    assert done == ['00000000'], done"
}
