#!/usr/bin/env bats
# pd-bonds: families within the horizon, checked against a brute-force
# all-pairs search, the lattice count of 122 partners for delta = 3.0001 dx,
# the partial-volume factors of seed 000, symmetry, the two forms of /bonds
# (a lattice body's stencil, read back through share/pdh5.py, equals the
# lists of --csr bit for bit), and the errors of a program that must never
# leave a half-written file.

load test_helper

setup() {
    cd "$BATS_TEST_TMPDIR"
}

# check_families MODEL.h5: every family (of either form of /bonds, through
# pdh5: a stencil is expanded) equals the brute-force set of particles
# within the horizon (|xi| <= delta), sorted, without self, and symmetric;
# lengths are the distances and volume factors follow seed 000:
# nu = 1 for |xi| <= delta - r_j, else (delta + r_j - |xi|) / (2 r_j).
# Prints "ok MIN MAX PAIRS".
check_families() {
    py "
f = h5py.File(sys.argv[1], 'r')
x = f['particles/position'][:]
r = f['particles/radius'][:]
b = f['bonds']
if pdh5.form(f) == 'csr':
    assert b['offset'].dtype == np.int64 and b['neighbor'].dtype == np.int32
    assert b['length'].dtype == np.float64 and b['volume_factor'].dtype == np.float64
off, nb, length, nu = pdh5.bonds(f)
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
f = h5py.File(sys.argv[1], 'r'); print(f['bonds'].attrs['count'] // 2)" model.h5)"
    # the sizes of the families the stencil expands to (make_block's model
    # is a stencil: pd-bonds' default on a lattice)
    run -0 py "
f = h5py.File(sys.argv[1], 'r')
assert pdh5.form(f) == 'stencil'
x = f['particles/position'][:]
sizes = np.diff(pdh5.bonds(f)[0])
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
    pairs=$(py "print(pdh5.bonds(h5py.File(sys.argv[1], 'r'))[1].size // 2)" m.h5)
    assert_equal "${#stderr_lines[@]}" 2
    assert_regex "${stderr_lines[0]}" "^pd-bonds: 1331 particles, $pairs bonds \([0-9.]+ per particle, 28 to 122\)$"
    assert_equal "${stderr_lines[1]}" "pd-bonds: stored as a lattice stencil of 122 offsets"
}

@test "a pair at exactly the horizon is bonded with volume factor 1/2" {
    # spacing 0.5 and horizon 1.5: |xi| = 1.5 exactly for (3,0,0) and (2,2,1)
    pd-lattice -q --spacing 0.5 --density 1 --box 0,3,0,3,0,3 -o l.h5
    pd-bonds -q --horizon 1.5 l.h5 -o m.h5
    run -0 check_families m.h5
    assert_output --regexp '^ok '
    run -0 py "
f = h5py.File(sys.argv[1], 'r')
length, nu = pdh5.bonds(f)[2:]
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

@test "a perturbed cloud is no lattice: its bonds stay lists (CSR), said by no stencil line" {
    pd-lattice -q --spacing 0.001 --density 2200 --box 0,0.006,0,0.006,0,0.006 \
        --perturb 0.0001 --seed 3 -o l.h5
    run -0 --separate-stderr pd-bonds --horizon 0.0030001 l.h5 -o m.h5
    assert_equal "${#stderr_lines[@]}" 1
    assert_regex "${stderr_lines[0]}" '^pd-bonds: 343 particles, '
    run -0 py "
b = h5py.File(sys.argv[1], 'r')['bonds']
assert b.attrs.get('form', 'csr') in ('csr', b'csr'), b.attrs['form']
assert sorted(b) == ['length', 'neighbor', 'offset', 'state', 'volume_factor'], sorted(b)
assert 'spacing' not in b.attrs and 'origin' not in b.attrs
assert int(b.attrs['count']) == b['neighbor'].size
print('ok')" m.h5
    assert_output ok
    run -0 check_families m.h5
    assert_output --regexp '^ok '
}

@test "every bond starts intact: one set bit per bond, padding bits clear" {
    make_block
    run -0 py "
b = h5py.File(sys.argv[1], 'r')['bonds']
count = int(b.attrs['count'])
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
    ids, (off, nb) = f['particles/id'][:], pdh5.bonds(f)[:2]
    rows = np.repeat(np.arange(ids.size), np.diff(off))
    return np.sort(ids[rows] * 10**7 + ids[nb])
assert np.array_equal(pairs(sys.argv[1]), pairs(sys.argv[2]))
print('ok')" model.h5 plain.h5
    assert_output ok
}

# ------------------------------------------------------------ pre-cracks

# The crack across the whole y-z section of the make_block cube (x, y, z in
# 0..10 mm): the plane x = 4.5 mm, between two lattice planes, corner
# (4.5, -1, -1) mm, edges 12 mm along y and z.
CRACK_FULL=rect,0.0045,-0.001,-0.001,0,0.012,0,0,0,0.012
# The same plane over y in [-1, 4.4] mm only: the edge y = 4.4 mm is 0.4
# spacing from a lattice line, off every point where a bond crosses.
CRACK_HALF=rect,0.0045,-0.001,-0.001,0,0.0054,0,0,0,0.012
# The half crack as a segment through the thickness.
CRACK_SEGMENT=segment,0.0045,-0.001,0.0045,0.0044

# check_precrack MODEL.h5 SPEC...: /bonds/precrack holds exactly the bonds
# that cross one of the cracks, computed here independently from all pairs
# within the horizon: the ends on different sides of the plane (s = n.(x-P)
# with n = A x B, s >= 0 the positive side), the crossing point inside the
# parallelogram; a segment is the parallelogram over the particles' z range
# and a horizon more.  The bits are symmetric, padding clear, and the broken
# bonds of /bonds/state are exactly the pre-cracked ones.  Prints
# "ok PAIRS" and a line "SPEC PAIRS" per crack.
check_precrack() {
    py "
f = h5py.File(sys.argv[1], 'r')
x = f['particles/position'][:]
ids = f['particles/id'][:]
b = f['bonds']
off, nb = pdh5.bonds(f)[:2]
delta = float(b.attrs['horizon'])
n, count = x.shape[0], nb.size
pre_bytes = b['precrack'][:]
assert pre_bytes.dtype == np.uint8 and pre_bytes.shape == ((count + 7) // 8,)
bits = np.unpackbits(pre_bytes, bitorder='little')
assert not bits[count:].any(), 'padding bits set'
pre = bits[:count].astype(bool)
intact = np.unpackbits(b['state'][:], bitorder='little')[:count].astype(bool)
assert np.array_equal(pre, ~intact), 'broken bonds other than the pre-cracked'
rows = np.repeat(np.arange(n), np.diff(off))
key = lambda i, j: np.minimum(ids[i], ids[j]) * 10**7 + np.maximum(ids[i], ids[j])
# symmetric: each pre-cracked pair twice, once from each end
got, times = np.unique(key(rows[pre], nb[pre]), return_counts=True)
assert np.all(times == 2), 'pre-crack bits not symmetric'
# all pairs within the horizon, i < j
d2 = ((x[:, None, :] - x[None, :, :])**2).sum(axis=2)
I, J = np.nonzero(np.triu(d2 <= delta * delta, 1))
want = np.zeros(I.size, bool)
for spec in sys.argv[2:]:
    kind, *v = spec.split(',')
    v = [float(t) for t in v]
    if kind == 'rect':
        P, A, B = np.array(v[0:3]), np.array(v[3:6]), np.array(v[6:9])
    else:
        lo, hi = x[:, 2].min(), x[:, 2].max()
        P = np.array([v[0], v[1], lo - delta])
        A = np.array([v[2] - v[0], v[3] - v[1], 0.0])
        B = np.array([0.0, 0.0, hi - lo + 2 * delta])
    nrm = np.cross(A, B)
    s = (x - P) @ nrm
    pos = s >= 0
    cand = pos[I] != pos[J]
    m = np.where(pos[I], J, I)[cand]          # the end on the negative side
    p = np.where(pos[I], I, J)[cand]
    t = s[m] / (s[m] - s[p])
    X = x[m] + t[:, None] * (x[p] - x[m]) - P
    G = np.array([[A @ A, A @ B], [A @ B, B @ B]])
    uv = np.linalg.solve(G, np.stack([X @ A, X @ B]))
    inside = np.all((uv >= 0) & (uv <= 1), axis=0)
    hit = np.zeros(I.size, bool)
    hit[np.nonzero(cand)[0][inside]] = True
    print(spec, int(hit.sum()))
    want |= hit
expect = np.sort(key(I[want], J[want]))
assert np.array_equal(got, expect), ('pre-cracked pairs differ', got.size, expect.size,
                                     np.setdiff1d(got, expect)[:5], np.setdiff1d(expect, got)[:5])
print('ok', got.size)
" "$@"
}

# bits MODEL.h5 NAME: the bytes of /bonds/NAME in hex.
bits() {
    py "print(h5py.File(sys.argv[1], 'r')['bonds/' + sys.argv[2]][:].tobytes().hex())" "$1" "$2"
}

@test "--crack across the whole section breaks exactly the bonds crossing it" {
    make_block
    run -0 --separate-stderr pd-bonds --horizon "$HORIZON" --crack "$CRACK_FULL" lattice.h5 -o m.h5
    run -0 check_precrack m.h5 "$CRACK_FULL"
    assert_line --index 1 --regexp '^ok [0-9]+$'
    pairs=${lines[1]#ok }
    assert_equal "${lines[0]}" "$CRACK_FULL $pairs"
    # a plane across the whole section cuts every pair with ends on both
    # sides of x = 4.5 mm
    run -0 py "
f = h5py.File(sys.argv[1], 'r')
x = f['particles/position'][:]
d2 = ((x[:, None, :] - x[None, :, :])**2).sum(axis=2)
I, J = np.nonzero(np.triu(d2 <= float(sys.argv[2])**2, 1))
print(np.count_nonzero((x[I, 0] < 0.0045) != (x[J, 0] < 0.0045)))" m.h5 "$HORIZON"
    assert_output "$pairs"
    # the families are those without a crack
    run -0 check_families m.h5
    assert_output --regexp '^ok 28 122 '
}

@test "the summary reports how many bonds each crack breaks" {
    make_block
    run -0 --separate-stderr pd-bonds --horizon "$HORIZON" --crack "$CRACK_FULL" \
        --crack "$CRACK_HALF" lattice.h5 -o m.h5
    run -0 check_precrack m.h5 "$CRACK_FULL" "$CRACK_HALF"
    full=${lines[0]##* } half=${lines[1]##* }
    [ "$half" -gt 0 ] && [ "$half" -lt "$full" ]
    run -0 --separate-stderr pd-bonds --horizon "$HORIZON" --crack "$CRACK_FULL" \
        --crack "$CRACK_HALF" lattice.h5 -o m.h5
    assert_equal "${#stderr_lines[@]}" 4
    assert_regex "${stderr_lines[0]}" '^pd-bonds: 1331 particles, '
    assert_equal "${stderr_lines[1]}" "pd-bonds: stored as a lattice stencil of 122 offsets"
    assert_equal "${stderr_lines[2]}" "pd-bonds: --crack $CRACK_FULL: $full bonds broken"
    assert_equal "${stderr_lines[3]}" "pd-bonds: --crack $CRACK_HALF: $half bonds broken"
    run -0 --separate-stderr pd-bonds -q --horizon "$HORIZON" --crack "$CRACK_FULL" lattice.h5 -o m.h5
    assert_equal "$stderr" ""
}

@test "a crack over half the section breaks only bonds crossing that half" {
    make_block
    pd-bonds -q --horizon "$HORIZON" --crack "$CRACK_FULL" lattice.h5 -o full.h5
    pd-bonds -q --horizon "$HORIZON" --crack "$CRACK_HALF" lattice.h5 -o half.h5
    run -0 check_precrack half.h5 "$CRACK_HALF"
    assert_line --index 1 --regexp '^ok [0-9]+$'
    # a subset of the full crack's bonds, each meeting x = 4.5 mm at y <= 4.4
    # mm, and all of those
    run -0 py "
def load(name):
    f = h5py.File(name, 'r')
    off, nb = pdh5.bonds(f)[:2]
    pre = np.unpackbits(f['bonds/precrack'][:], bitorder='little')[:nb.size].astype(bool)
    return f['particles/position'][:], np.repeat(np.arange(off.size - 1), np.diff(off)), nb, pre
x, rows, nb, full = load(sys.argv[1])
x2, rows2, nb2, half = load(sys.argv[2])
assert np.array_equal(x, x2) and np.array_equal(nb, nb2)
assert half.sum() > 0 and half.sum() < full.sum()
assert not np.any(half & ~full), 'a bond outside the full crack'
xi, xj = x[rows], x[nb]
t = (0.0045 - xi[:, 0]) / (xj[:, 0] - xi[:, 0] + (xj[:, 0] == xi[:, 0]))
y = xi[:, 1] + t * (xj[:, 1] - xi[:, 1])
assert np.array_equal(half, full & (y <= 0.0044)), 'not exactly the bonds across the half'
print('ok')" full.h5 half.h5
    assert_output ok
}

@test "segment through the thickness equals the equivalent rect" {
    make_block
    pd-bonds -q --horizon "$HORIZON" --crack "$CRACK_SEGMENT" lattice.h5 -o seg.h5
    pd-bonds -q --horizon "$HORIZON" --crack "$CRACK_HALF" lattice.h5 -o rect.h5
    run -0 check_precrack seg.h5 "$CRACK_SEGMENT"
    assert_line --index 1 --regexp '^ok [0-9]+$'
    assert_equal "$(bits seg.h5 precrack)" "$(bits rect.h5 precrack)"
    assert_equal "$(bits seg.h5 state)" "$(bits rect.h5 state)"
}

@test "a crack exactly on a lattice plane cuts on the side A x B points away from" {
    make_block
    at() { pd-bonds -q --horizon "$HORIZON" --crack "$1" lattice.h5 -o "$2"; }
    # normal +x: the plane x = 5 mm joins the + side, as the crack at 4.5 mm
    at rect,0.005,-0.001,-0.001,0,0.012,0,0,0,0.012 on-plus.h5
    at "$CRACK_FULL" at45.h5
    # normal -x (A and B swapped): as the crack at 5.5 mm
    at rect,0.005,-0.001,-0.001,0,0,0.012,0,0.012,0 on-minus.h5
    at rect,0.0055,-0.001,-0.001,0,0.012,0,0,0,0.012 at55.h5
    assert_equal "$(bits on-plus.h5 precrack)" "$(bits at45.h5 precrack)"
    assert_equal "$(bits on-minus.h5 precrack)" "$(bits at55.h5 precrack)"
    [ "$(bits at45.h5 precrack)" != "$(bits at55.h5 precrack)" ]
    run -0 check_precrack on-plus.h5 rect,0.005,-0.001,-0.001,0,0.012,0,0,0,0.012
    assert_line --index 1 --regexp '^ok [0-9]+$'
    run -0 check_precrack on-minus.h5 rect,0.005,-0.001,-0.001,0,0,0.012,0,0.012,0
    assert_line --index 1 --regexp '^ok [0-9]+$'
}

@test "an oblique crack: the bonds crossing it, computed independently" {
    make_block
    # a tilted parallelogram inside the cube, edges off the lattice
    spec=rect,0.0021,0.0017,0.0013,0.0043,0.0011,0.0029,-0.0012,0.0051,0.0007
    pd-bonds -q --horizon "$HORIZON" --crack "$spec" lattice.h5 -o m.h5
    run -0 check_precrack m.h5 "$spec"
    assert_line --index 1 --regexp '^ok [1-9][0-9]*$'
}

@test "a crack that crosses no bond breaks none and writes no /bonds/precrack" {
    make_block
    run -0 --separate-stderr pd-bonds --horizon "$HORIZON" --crack rect,0.5,0,0,0,1,0,0,0,1 \
        lattice.h5 -o m.h5
    assert_equal "${stderr_lines[2]}" "pd-bonds: --crack rect,0.5,0,0,0,1,0,0,0,1: 0 bonds broken"
    run -0 py "
b = h5py.File(sys.argv[1], 'r')['bonds']
assert 'precrack' not in b
count = int(b.attrs['count'])
assert np.all(np.unpackbits(b['state'][:], bitorder='little')[:count] == 1)
print('ok')" m.h5
    assert_output ok
}

bad_crack() {
    make_block
    expect_usage_error "$2" pd-bonds --horizon "$HORIZON" --crack "$1" lattice.h5 -o x.h5
    [ ! -e x.h5 ]
}
@test "--crack with a zero-length edge is a usage error" {
    bad_crack rect,0,0,0,0,0,0,0,0.01,0 "edge A has zero length"
    bad_crack rect,0,0,0,0.01,0,0,0,0,0 "edge B has zero length"
}
@test "--crack with parallel edges is a usage error" {
    bad_crack rect,0,0,0,0.001,0.002,0.003,0.002,0.004,0.006 "edges A and B are parallel"
}
@test "--crack segment of zero length is a usage error" {
    bad_crack segment,0.004,0.005,0.004,0.005 "segment has zero length"
}
@test "--crack with the wrong count of numbers, a bad number or kind is a usage error" {
    bad_crack rect,0,0,0,1,0,0,0,1 "expected rect,X,Y,Z,AX,AY,AZ,BX,BY,BZ"
    bad_crack rect,0,0,0,1,0,0,0,1,0,0 "expected rect,X,Y,Z"
    bad_crack rect,0,0,0,1,0,0,0,1,x "expected rect,X,Y,Z"
    bad_crack segment,0,0,1 "expected segment,X1,Y1,X2,Y2"
    bad_crack segment,0,0,1,inf "expected segment,X1,Y1,X2,Y2"
    bad_crack line,0,0,1,1 "expected rect,\.\.\. or segment,\.\.\."
    bad_crack "" "expected rect"
}

@test "the pre-crack survives pd-run into the run file and stays broken in every frame" {
    make_block
    pd-bonds -q --horizon "$HORIZON" --crack "$CRACK_HALF" lattice.h5 -o m.h5
    pd-run -q "${RUN_OPTS[@]}" --steps 20 --every 10 m.h5 -o run.h5
    run -0 py "
m, r = h5py.File(sys.argv[1], 'r'), h5py.File(sys.argv[2], 'r')
# /bonds as the model has it (a stencil here), every dataset and attribute
assert sorted(m['bonds']) == sorted(r['bonds']) and 'precrack' in m['bonds'], sorted(r['bonds'])
for k in m['bonds']:
    a, b = m['bonds/' + k], r['bonds/' + k]
    assert a.dtype == b.dtype and np.array_equal(a[:], b[:]), k
assert sorted(m['bonds'].attrs) == sorted(r['bonds'].attrs)
for k in m['bonds'].attrs:
    assert np.array_equal(m['bonds'].attrs[k], r['bonds'].attrs[k]), k
count = int(r['bonds'].attrs['count'])
pre = np.unpackbits(r['bonds/precrack'][:], bitorder='little')[:count].astype(bool)
assert pre.any()
frames = list(r['frames'].values())
assert len(frames) == 3
for g in frames:
    mu = np.unpackbits(g['state'][:], bitorder='little')[:count].astype(bool)
    assert not np.any(mu & pre), ('a pre-cracked bond intact in a frame', g.attrs['step'])
print('ok')" m.h5 run.h5
    assert_output ok
}

# ------------------------------------------------------------ the two forms

# same_bonds STENCIL.h5 CSR.h5 [DIM]: the first file's /bonds is a lattice
# stencil (form "stencil", spacing and origin, the table of offsets, no
# per-bond list), the second's the lists of --csr; the table is every
# nonzero lattice offset d of a DIM-D lattice (default 3) with |d| h <=
# delta, each with its opposite, stencil_length = |d| h, the factors in
# (0, 1]; pdh5.bonds expands the stencil to exactly the lists (dtype, shape
# and bits), and the state and pre-crack bits, the count, the horizon and
# /particles are the same in both.  Prints "ok K".
same_bonds() {
    py "
s, c = h5py.File(sys.argv[1], 'r'), h5py.File(sys.argv[2], 'r')
dim = int(sys.argv[3]) if len(sys.argv) > 3 else 3
bs, bc = s['bonds'], c['bonds']
assert pdh5.form(s) == 'stencil' and pdh5.form(c) == 'csr'
pre = ['precrack'] if 'precrack' in bc else []
assert sorted(bs) == sorted(['stencil', 'stencil_length', 'stencil_volume_factor', 'state'] + pre), sorted(bs)
assert sorted(bc) == sorted(['offset', 'neighbor', 'length', 'volume_factor', 'state'] + pre), sorted(bc)
assert 'form' not in bc.attrs or pdh5.form(c) == 'csr'
h, delta = float(bs.attrs['spacing']), float(bs.attrs['horizon'])
assert h == float(s['particles'].attrs['spacing']) and bs.attrs['origin'].shape == (3,)
assert delta == float(bc.attrs['horizon']) and int(bs.attrs['count']) == int(bc.attrs['count'])
# the table: the ball of lattice offsets within the horizon
d = bs['stencil'][:]
assert d.dtype == np.int32 and d.ndim == 2 and d.shape[1] == 3
m = int(delta / h) + 1
g = np.arange(-m, m + 1)
ball = np.stack(np.meshgrid(g, g, g if dim == 3 else [0], indexing='ij'), -1).reshape(-1, 3)
ball = ball[np.any(ball != 0, axis=1) & (((ball * h)**2).sum(1) <= delta * delta)]
key = lambda v: sorted(map(tuple, v.tolist()))
assert key(d) == key(ball), (len(d), len(ball))
assert key(-d) == key(d)
L, nu = bs['stencil_length'][:], bs['stencil_volume_factor'][:]
assert L.shape == nu.shape == (len(d),)
assert np.allclose(L, np.sqrt((d.astype(float)**2).sum(1)) * h, rtol=1e-12, atol=0)
assert np.all((nu > 0) & (nu <= 1))
# the expansion equals the lists bit for bit
for got, name in zip(pdh5.bonds(s), ('offset', 'neighbor', 'length', 'volume_factor')):
    want = bc[name][()]
    assert got.dtype == want.dtype and got.shape == want.shape, (name, got.dtype, want.dtype)
    assert got.tobytes() == want.tobytes(), (name, np.nonzero(got != want)[0][:5])
for name in ['state'] + pre:
    a, b = bs[name][()], bc[name][()]
    assert a.dtype == b.dtype == np.uint8 and a.tobytes() == b.tobytes(), name
assert not pre or pdh5.bits(bs['precrack'], int(bs.attrs['count'])).any()
for k in c['particles']:
    assert s['particles'][k][()].tobytes() == c['particles'][k][()].tobytes(), k
print('ok', len(d))
" "$@"
}

@test "a box lattice: the default writes the stencil of 122 offsets; pdh5 expands it to the --csr lists bit for bit" {
    make_block
    run -0 --separate-stderr pd-bonds --horizon "$HORIZON" lattice.h5 -o s.h5
    assert_equal "${stderr_lines[1]}" "pd-bonds: stored as a lattice stencil of 122 offsets"
    run -0 --separate-stderr pd-bonds --csr --horizon "$HORIZON" lattice.h5 -o c.h5
    assert_equal "${#stderr_lines[@]}" 1
    run -0 same_bonds s.h5 c.h5
    assert_output "ok 122"
    # the model of make_block, the suites' block, is that stencil
    py "
a, b = (h5py.File(n, 'r')['bonds'] for n in sys.argv[1:3])
assert sorted(a) == sorted(b) and all(np.array_equal(a[k][()], b[k][()]) for k in a)" model.h5 s.h5
    run -0 check_families s.h5
    assert_output --regexp '^ok 28 122 '
}

@test "a plate: the stencil of the 28 in-plane offsets, the same bonds as --csr" {
    pd-lattice -q --dimension 2 --thickness 0.001 --spacing 0.0005 --density 8000 \
        --box -0.003,0.003,-0.002,0.002,0,0 -o pl.h5
    run -0 --separate-stderr pd-bonds --horizon 0.0015001 pl.h5 -o s.h5
    assert_equal "${stderr_lines[1]}" "pd-bonds: stored as a lattice stencil of 28 offsets"
    pd-bonds -q --csr --horizon 0.0015001 pl.h5 -o c.h5
    run -0 same_bonds s.h5 c.h5 2
    assert_output "ok 28"
    run -0 check_families s.h5
    assert_output --regexp '^ok [0-9]+ 28 '
}

@test "a pre-cracked lattice: the stencil keeps the pre-crack bits, equal to those of --csr" {
    make_block
    pd-bonds -q --horizon "$HORIZON" --crack "$CRACK_HALF" lattice.h5 -o s.h5
    pd-bonds -q --csr --horizon "$HORIZON" --crack "$CRACK_HALF" lattice.h5 -o c.h5
    run -0 same_bonds s.h5 c.h5
    assert_output "ok 122"
    run -0 check_precrack s.h5 "$CRACK_HALF"
    assert_line --index 1 --regexp '^ok [1-9][0-9]*$'
}

@test "pd-run keeps either form: a run of the --csr model has the lists, of the default the stencil" {
    make_block
    pd-bonds -q --csr --horizon "$HORIZON" lattice.h5 -o c.h5
    pd-run -q --c 1e21 --steps 1 model.h5 -o rs.h5
    pd-run -q --c 1e21 --steps 1 c.h5 -o rc.h5
    run -0 same_bonds rs.h5 rc.h5
    assert_output "ok 122"
}
