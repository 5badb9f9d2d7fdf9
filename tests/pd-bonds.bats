#!/usr/bin/env bats
# pd-bonds: families within the horizon, checked against a brute-force
# all-pairs search, the lattice count of 122 partners for delta = 3.0001 dx,
# the partial-volume factors of seed 000, symmetry, and the errors of a
# program that must never leave a half-written file.

load test_helper

setup() {
    cd "$BATS_TEST_TMPDIR"
}

# check_families MODEL.h5: every family equals the brute-force set of
# particles within the horizon (|xi| <= delta), sorted, without self, and
# symmetric; lengths are the distances and volume factors follow seed 000:
# nu = 1 for |xi| <= delta - r_j, else (delta + r_j - |xi|) / (2 r_j).
# Prints "ok MIN MAX PAIRS".
check_families() {
    py "
f = h5py.File(sys.argv[1], 'r')
x = f['particles/position'][:]
r = f['particles/radius'][:]
b = f['bonds']
off, nb = b['offset'][:], b['neighbor'][:]
length, nu = b['length'][:], b['volume_factor'][:]
delta = float(b.attrs['horizon'])
n = x.shape[0]
assert off.dtype == np.int64 and nb.dtype == np.int32
assert off.shape == (n + 1,) and off[0] == 0 and off[-1] == nb.size
assert np.all(np.diff(off) >= 0)
assert length.shape == nb.shape and nu.shape == nb.shape
assert int(b.attrs['count']) == nb.size
d2 = ((x[:, None, :] - x[None, :, :])**2).sum(axis=2)
np.fill_diagonal(d2, np.inf)
for i in range(n):
    fam = nb[off[i]:off[i + 1]]
    want = np.nonzero(d2[i] <= delta * delta)[0]
    assert np.array_equal(fam, want), ('family', i, fam, want)
rows = np.repeat(np.arange(n), np.diff(off))
dist = np.sqrt(((x[rows] - x[nb])**2).sum(axis=1))
assert np.allclose(length, dist, rtol=1e-15, atol=0), abs(length - dist).max()
rj = r[nb]
want = np.where(length <= delta - rj, 1.0, (delta + rj - length) / (2 * rj))
assert np.allclose(nu, want, rtol=1e-14, atol=0), abs(nu - want).max()
assert np.all(nu >= 0.5) and np.all(nu <= 1)
# symmetric: the pair set equals its transpose
fwd = rows.astype(np.int64) * n + nb
back = nb.astype(np.int64) * n + rows
assert np.array_equal(np.sort(fwd), np.sort(back)), 'not symmetric'
sizes = np.diff(off)
print('ok', sizes.min(), sizes.max(), nb.size // 2)
" "$1"
}

# ------------------------------------------------------------ the interface

@test "--help prints Usage on stdout and exits 0" {
    run -0 --separate-stderr pd-bonds --help
    assert_line --index 0 --regexp '^Usage: pd-bonds '
    assert_equal "$stderr" ""
}

@test "--version prints the program and version" {
    run -0 --separate-stderr pd-bonds --version
    assert_output --regexp '^pd-bonds \(pd\) [0-9]+\.[0-9]+'
}

@test "an unknown option is a usage error naming the option" {
    make_block
    run -2 --separate-stderr pd-bonds --bogus --horizon 0.003 "$BATS_TEST_TMPDIR/lattice.h5" -o x.h5
    assert_one_error "^pd-bonds: error: .*--bogus"
    [ ! -e x.h5 ]
}

@test "--horizon is required" {
    make_block
    expect_usage_error "--horizon" pd-bonds lattice.h5 -o x.h5
}

@test "INPUT is required, and only one" {
    make_block
    expect_usage_error "INPUT" pd-bonds --horizon 0.003 -o x.h5
    expect_usage_error "INPUT" pd-bonds --horizon 0.003 lattice.h5 lattice.h5 -o x.h5
    [ ! -e x.h5 ]
}

bad_horizon() {
    make_block
    expect_usage_error "--horizon.*'$1'" pd-bonds --horizon "$1" lattice.h5 -o x.h5
    [ ! -e x.h5 ]
}
@test "--horizon 0 is a usage error" { bad_horizon 0; }
@test "--horizon -0.003 is a usage error" { bad_horizon -0.003; }
@test "--horizon nan is a usage error" { bad_horizon nan; }
@test "--horizon abc is a usage error" { bad_horizon abc; }

@test "a horizon below the spacing is a runtime error naming both" {
    make_block
    expect_runtime_error "horizon 0.0009 m is below the lattice spacing 0.001 m" \
        pd-bonds --horizon 0.0009 lattice.h5 -o x.h5
    [ ! -e x.h5 ]
    assert_no_temp .
}

# ------------------------------------------------------------ bad inputs

@test "a missing file is a runtime error naming it" {
    expect_runtime_error "nosuch\.h5" pd-bonds --horizon 0.003 nosuch.h5 -o x.h5
    [ ! -e x.h5 ]
}

@test "an empty file is a runtime error" {
    make_bad_inputs
    expect_runtime_error "empty\.h5.*empty" pd-bonds --horizon 0.003 empty.h5 -o x.h5
    [ ! -e x.h5 ]
}

@test "a text file is a runtime error: not HDF5" {
    make_bad_inputs
    expect_runtime_error "text\.h5.*not an HDF5 file" pd-bonds --horizon 0.003 text.h5 -o x.h5
    [ ! -e x.h5 ]
}

@test "a directory as input is a runtime error" {
    make_bad_inputs
    expect_runtime_error "adir.*directory" pd-bonds --horizon 0.003 adir -o x.h5
    [ ! -e x.h5 ]
}

@test "an HDF5 file that is not pd-h5 is a runtime error" {
    make_bad_inputs
    expect_runtime_error "plain\.h5.*not a pd-h5 file" pd-bonds --horizon 0.003 plain.h5 -o x.h5
    [ ! -e x.h5 ]
}

@test "an unknown pd_format_version is a runtime error naming the version" {
    make_block
    with_version lattice.h5 v99.h5 99
    expect_runtime_error "v99\.h5.*version 99" pd-bonds --horizon 0.003 v99.h5 -o x.h5
    [ ! -e x.h5 ]
}

@test "empty or non-HDF5 stdin is a runtime error" {
    make_bad_inputs
    run -1 --separate-stderr pd-bonds --horizon 0.003 - -o x.h5 < /dev/null
    assert_one_error "^pd-bonds: error: .*stdin.*empty"
    run -1 --separate-stderr pd-bonds --horizon 0.003 - -o x.h5 < text.h5
    assert_one_error "^pd-bonds: error: .*stdin.*not an HDF5 file"
    [ ! -e x.h5 ]
}

@test "/particles/volume stored as int32 is a runtime error naming the dataset" {
    make_block
    py "
with h5py.File(sys.argv[1], 'a') as f:
    v = f['particles/volume'][:]
    del f['particles/volume']
    f['particles/volume'] = v.astype(np.int32)" lattice.h5
    expect_runtime_error "/particles/volume.*int32" pd-bonds --horizon 0.003 lattice.h5 -o x.h5
    [ ! -e x.h5 ]
}

@test "/particles/position of shape (N,2) is a runtime error naming the dataset" {
    make_block
    py "
with h5py.File(sys.argv[1], 'a') as f:
    v = f['particles/position'][:]
    del f['particles/position']
    f['particles/position'] = v[:, :2]" lattice.h5
    expect_runtime_error "/particles/position" pd-bonds --horizon 0.003 lattice.h5 -o x.h5
    [ ! -e x.h5 ]
}

@test "a /particles dataset shorter than position is a runtime error" {
    make_block
    py "
with h5py.File(sys.argv[1], 'a') as f:
    v = f['particles/density'][:]
    del f['particles/density']
    f['particles/density'] = v[:-1]" lattice.h5
    expect_runtime_error "/particles/density" pd-bonds --horizon 0.003 lattice.h5 -o x.h5
}

@test "a file without /particles is a runtime error" {
    make_block
    py "
with h5py.File(sys.argv[1], 'a') as f:
    del f['particles']" lattice.h5
    expect_runtime_error "/particles" pd-bonds --horizon 0.003 lattice.h5 -o x.h5
}

@test "a negative volume or NaN position is a runtime error" {
    make_block
    cp lattice.h5 neg.h5
    py "
with h5py.File(sys.argv[1], 'a') as f: f['particles/volume'][7] = -1.0
with h5py.File(sys.argv[2], 'a') as f: f['particles/position'][3, 1] = np.nan" neg.h5 lattice.h5
    expect_runtime_error "particle 7 .*volume" pd-bonds --horizon 0.003 neg.h5 -o x.h5
    expect_runtime_error "particle 3 .*position" pd-bonds --horizon 0.003 lattice.h5 -o x.h5
}

# ------------------------------------------------------------ output

@test "-o naming a directory fails with one error and leaves no temp file" {
    make_block
    mkdir out
    expect_runtime_error "out.*directory" pd-bonds --horizon 0.0030001 lattice.h5 -o out
    run -0 ls -A out
    assert_output ""
    assert_no_temp .
}

@test "-o into a missing directory fails with one error" {
    make_block
    expect_runtime_error "nodir/x\.h5" pd-bonds --horizon 0.0030001 lattice.h5 -o nodir/x.h5
    assert_no_temp .
}

@test "an existing output is replaced only by a complete file" {
    make_block
    echo "old" > m.h5
    # failing run: the old file stays as it was
    run -1 pd-bonds --horizon 0.0009 lattice.h5 -o m.h5
    assert_equal "$(cat m.h5)" "old"
    pd-bonds -q --horizon 0.0030001 lattice.h5 -o m.h5
    run -0 py "print(h5py.File(sys.argv[1], 'r')['bonds'].attrs['horizon'])" m.h5
    assert_output 0.0030001
    assert_no_temp .
}

@test "stdin and stdout: pd-bonds - -o - inside a pipe" {
    pd-lattice -q --spacing 0.001 --density 2200 --box 0,0.004,0,0.004,0,0.004 -o - |
        pd-bonds -q --horizon 0.0030001 - -o - > m.h5
    run -0 check_families m.h5
    assert_output --regexp '^ok '
}

@test "the history gains the pd-bonds command line" {
    make_block
    run -0 py "
h = h5py.File(sys.argv[1], 'r').attrs['history']
print(h.decode() if isinstance(h, bytes) else h)" model.h5
    assert_equal "${#lines[@]}" 2
    assert_line --index 0 --regexp '^pd-lattice '
    assert_line --index 1 --regexp "^pd-bonds -q --horizon $HORIZON .*lattice\.h5 -o .*model\.h5$"
}

# ------------------------------------------------------------ the families

@test "families equal a brute-force search; interior particles have 122 partners" {
    make_block
    run -0 check_families model.h5
    # 122 = integer points with i^2+j^2+k^2 <= 9, less the origin; a corner
    # keeps the 28 of them with i, j, k >= 0 (less the origin)
    assert_output "ok 28 122 $(py "
f = h5py.File(sys.argv[1], 'r'); print(f['bonds/neighbor'].size // 2)" model.h5)"
    run -0 py "
f = h5py.File(sys.argv[1], 'r')
x = f['particles/position'][:]
sizes = np.diff(f['bonds/offset'][:])
k = np.round(x / 0.001).astype(int)
interior = np.all((k >= 3) & (k <= 7), axis=1)
assert interior.sum() == 125
assert np.all(sizes[interior] == 122), sizes[interior]
# every other family is the same ball clipped by the faces
g = np.arange(-3, 4)
I, J, K = np.meshgrid(g, g, g, indexing='ij')
ball = np.stack([I.ravel(), J.ravel(), K.ravel()], 1)
ball = ball[((ball**2).sum(1) <= 9) & np.any(ball != 0, axis=1)]
assert ball.shape[0] == 122
want = [np.count_nonzero(np.all((p + ball >= 0) & (p + ball <= 10), axis=1)) for p in k]
assert np.array_equal(sizes, want)
print('ok')" model.h5
    assert_output ok
}

@test "the summary line reports particles, pairs and the family range" {
    make_block
    run -0 --separate-stderr pd-bonds --horizon "$HORIZON" lattice.h5 -o m.h5
    pairs=$(py "print(h5py.File(sys.argv[1], 'r')['bonds/neighbor'].size // 2)" m.h5)
    assert_regex "$stderr" "^pd-bonds: 1331 particles, $pairs bonds \([0-9.]+ per particle, 28 to 122\)$"
}

@test "a pair at exactly the horizon is bonded with volume factor 1/2" {
    # spacing 0.5 and horizon 1.5: |xi| = 1.5 exactly for (3,0,0) and (2,2,1)
    pd-lattice -q --spacing 0.5 --density 1 --box 0,3,0,3,0,3 -o l.h5
    pd-bonds -q --horizon 1.5 l.h5 -o m.h5
    run -0 check_families m.h5
    assert_output --regexp '^ok '
    run -0 py "
f = h5py.File(sys.argv[1], 'r')
length, nu = f['bonds/length'][:], f['bonds/volume_factor'][:]
at = length == 1.5
inner = length <= 1.5 - 0.25
assert at.sum() > 0
assert np.all(nu[at] == 0.5), nu[at]
assert np.all(nu[inner] == 1.0)
assert np.all((nu[~inner] < 1) & (nu[~inner] >= 0.5))
print('ok')" m.h5
    assert_output ok
}

@test "a perturbed cloud: cell-list families equal brute force" {
    pd-lattice -q --spacing 0.001 --density 2200 --box 0,0.008,0,0.008,0,0.008 \
        --perturb 0.0003 --seed 5 -o l.h5
    pd-bonds -q --horizon 0.0025 l.h5 -o m.h5
    run -0 check_families m.h5
    assert_output --regexp '^ok '
}

@test "every bond starts intact: one set bit per bond, padding bits clear" {
    make_block
    run -0 py "
b = h5py.File(sys.argv[1], 'r')['bonds']
count = b['neighbor'].size
s = b['state'][:]
assert s.dtype == np.uint8 and s.size == (count + 7) // 8
bits = np.unpackbits(s, bitorder='little')
assert np.all(bits[:count] == 1) and np.all(bits[count:] == 0)
print('ok')" model.h5
    assert_output ok
}

@test "sorting keeps each id with its particle; --no-sort keeps the order" {
    make_block
    pd-bonds -q --no-sort --horizon "$HORIZON" lattice.h5 -o plain.h5
    run -0 py "
a, b, c = (h5py.File(n, 'r')['particles'] for n in sys.argv[1:4])
ida, idb = a['id'][:], b['id'][:]
assert sorted(idb) == list(ida), 'ids lost or duplicated'
assert not np.array_equal(ida, idb), 'the sort did nothing'
order = np.argsort(idb)            # rows of b in id order
for k in ('position', 'volume', 'density', 'radius', 'material'):
    assert np.array_equal(b[k][:][order], a[k][:]), k
    assert np.array_equal(c[k][:], a[k][:]), k
assert np.array_equal(c['id'][:], ida)
assert a.attrs['spacing'] == b.attrs['spacing'] == c.attrs['spacing']
print('ok')" lattice.h5 model.h5 plain.h5
    assert_output ok
    run -0 check_families plain.h5
    assert_output --regexp '^ok 28 122 '
}

@test "bonds do not depend on the particle order (same pairs by id)" {
    make_block
    pd-bonds -q --no-sort --horizon "$HORIZON" lattice.h5 -o plain.h5
    run -0 py "
def pairs(name):
    f = h5py.File(name, 'r')
    ids, off, nb = f['particles/id'][:], f['bonds/offset'][:], f['bonds/neighbor'][:]
    rows = np.repeat(np.arange(ids.size), np.diff(off))
    return np.sort(ids[rows] * 10**7 + ids[nb])
assert np.array_equal(pairs(sys.argv[1]), pairs(sys.argv[2]))
print('ok')" model.h5 plain.h5
    assert_output ok
}
