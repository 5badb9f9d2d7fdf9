#!/usr/bin/env bats
# pd-lattice: sites of a simple cubic lattice inside closed regions, counted
# against an independent enumeration (and the LAMMPS count of the seed
# example), with the option errors of a command-line program.

load test_helper

setup() {
    cd "$BATS_TEST_TMPDIR"
}

BOX=(--box 0,0.01,0,0.01,0,0.01)

# ------------------------------------------------------------ the interface

@test "--help prints Usage on stdout and exits 0" {
    run -0 --separate-stderr pd-lattice --help
    assert_line --index 0 --regexp '^Usage: pd-lattice '
    assert_equal "$stderr" ""
}

@test "--version prints the program and version" {
    run -0 --separate-stderr pd-lattice --version
    assert_output --regexp '^pd-lattice \(pd\) [0-9]+\.[0-9]+'
    assert_equal "$stderr" ""
}

@test "an unknown option is a usage error naming the option" {
    run -2 --separate-stderr pd-lattice --bogus --spacing 0.001 --density 1 "${BOX[@]}" -o x.h5
    assert_one_error "^pd-lattice: error: .*--bogus"
    [ ! -e x.h5 ]
}

@test "a stray argument is a usage error" {
    expect_usage_error "stray" pd-lattice --spacing 0.001 --density 1 "${BOX[@]}" stray -o x.h5
    [ ! -e x.h5 ]
}

@test "--spacing is required" {
    expect_usage_error "--spacing" pd-lattice --density 1 "${BOX[@]}" -o x.h5
}

@test "--density is required" {
    expect_usage_error "--density" pd-lattice --spacing 0.001 "${BOX[@]}" -o x.h5
}

@test "a region is required; --subtract alone is not one" {
    expect_usage_error "region" pd-lattice --spacing 0.001 --density 1 -o x.h5
    expect_usage_error "region" pd-lattice --spacing 0.001 --density 1 \
        --subtract box,0,1,0,1,0,1 -o x.h5
    [ ! -e x.h5 ]
}

bad_spacing() {
    expect_usage_error "--spacing.*'$1'" pd-lattice --spacing "$1" --density 2200 "${BOX[@]}" -o x.h5
    [ ! -e x.h5 ]
}
@test "--spacing 0 is a usage error" { bad_spacing 0; }
@test "--spacing -0.001 is a usage error" { bad_spacing -0.001; }
@test "--spacing nan is a usage error" { bad_spacing nan; }
@test "--spacing abc is a usage error" { bad_spacing abc; }
@test "--spacing inf is a usage error" { bad_spacing inf; }

bad_density() {
    expect_usage_error "--density.*'$1'" pd-lattice --spacing 0.001 --density "$1" "${BOX[@]}" -o x.h5
    [ ! -e x.h5 ]
}
@test "--density 0 is a usage error" { bad_density 0; }
@test "--density -2200 is a usage error" { bad_density -2200; }
@test "--density nan is a usage error" { bad_density nan; }
@test "--density abc is a usage error" { bad_density abc; }

@test "--perturb and --seed refuse negative and non-numbers" {
    expect_usage_error "--perturb" pd-lattice --spacing 0.001 --density 1 "${BOX[@]}" --perturb -1e-5 -o x.h5
    expect_usage_error "--perturb" pd-lattice --spacing 0.001 --density 1 "${BOX[@]}" --perturb nan -o x.h5
    expect_usage_error "--seed" pd-lattice --spacing 0.001 --density 1 "${BOX[@]}" --seed -3 -o x.h5
    expect_usage_error "--seed" pd-lattice --spacing 0.001 --density 1 "${BOX[@]}" --seed 1.5 -o x.h5
}

@test "malformed regions are usage errors" {
    expect_usage_error "box" pd-lattice --spacing 0.001 --density 1 --box 0,1,0,1,0 -o x.h5
    expect_usage_error "box" pd-lattice --spacing 0.001 --density 1 --box 1,0,0,1,0,1 -o x.h5
    expect_usage_error "box" pd-lattice --spacing 0.001 --density 1 --box 0,1,,0,1,0,1 -o x.h5
    expect_usage_error "cylinder" pd-lattice --spacing 0.001 --density 1 --cylinder w,0,0,1,0,1 -o x.h5
    expect_usage_error "cylinder" pd-lattice --spacing 0.001 --density 1 --cylinder z,0,0,-1,0,1 -o x.h5
    expect_usage_error "sphere" pd-lattice --spacing 0.001 --density 1 --sphere 0,0,0,0 -o x.h5
    expect_usage_error "region" pd-lattice --spacing 0.001 --density 1 "${BOX[@]}" --subtract cone,1 -o x.h5
    [ ! -e x.h5 ]
}

@test "an empty region (a box between lattice sites) is a runtime error" {
    # the box holds no site n*spacing: nothing to write, and that is a data
    # problem (exit 1), not a malformed command line
    expect_runtime_error "no lattice site" pd-lattice --spacing 0.001 --density 2200 \
        --box 0.0002,0.0008,0.0002,0.0008,0.0002,0.0008 -o x.h5
    [ ! -e x.h5 ]
    assert_no_temp .
}

@test "subtracting everything leaves an empty body: runtime error" {
    expect_runtime_error "no lattice site" pd-lattice --spacing 0.001 --density 2200 "${BOX[@]}" \
        --subtract sphere,0.005,0.005,0.005,1 -o x.h5
    [ ! -e x.h5 ]
}

@test "-o naming a directory fails with one error and leaves nothing in it" {
    mkdir out
    expect_runtime_error "out" pd-lattice --spacing 0.001 --density 2200 "${BOX[@]}" -o out
    run -0 ls -A out
    assert_output ""
    assert_no_temp .
}

@test "-o into a missing directory fails with one error" {
    expect_runtime_error "nodir/x.h5" pd-lattice --spacing 0.001 --density 2200 "${BOX[@]}" -o nodir/x.h5
    assert_no_temp .
}

# ------------------------------------------------------------ the lattice

@test "the seed cylinder has exactly 103110 particles (the LAMMPS count)" {
    run -0 --separate-stderr pd-lattice --spacing 0.0005 --cylinder y,0,0,0.037,-0.0025,0 \
        --density 2200 -o cyl.h5
    assert_equal "$stderr" "pd-lattice: 103110 particles, spacing 0.0005 m"
    run -0 py "
f = h5py.File(sys.argv[1], 'r')
print(f['particles/position'].shape, f['particles/id'].shape)" cyl.h5
    assert_output "(103110, 3) (103110,)"
}

@test "the cylinder count equals an independent enumeration of lattice sites" {
    # LAMMPS region cylinder: closed, radius compared after a square root
    pd-lattice -q --spacing 0.0005 --cylinder y,0,0,0.037,-0.0025,0 --density 2200 -o cyl.h5
    pd-lattice -q --spacing 0.001 --cylinder z,0.002,-0.001,0.0042,0.0005,0.004 --density 1 -o cz.h5
    run -0 py "
def count(h, axis, c1, c2, R, lo, hi):
    m = int(np.ceil((max(abs(c1), abs(c2), abs(lo), abs(hi)) + R) / h)) + 2
    n = np.arange(-m, m + 1)
    a = n[(n * h >= lo) & (n * h <= hi)].size        # sites along the axis
    u, w = np.meshgrid(n * h, n * h, indexing='ij')
    return a * int(np.count_nonzero(np.sqrt((u - c1)**2 + (w - c2)**2) <= R))
for name, args in [(sys.argv[1], (0.0005, 1, 0, 0, 0.037, -0.0025, 0)),
                   (sys.argv[2], (0.001, 2, 0.002, -0.001, 0.0042, 0.0005, 0.004))]:
    got = h5py.File(name, 'r')['particles/position'].shape[0]
    want = count(*args)
    assert got == want, (name, got, want)
print('ok')" cyl.h5 cz.h5
    assert_output ok
}

@test "a closed box holds both of its faces: 11x11x11 sites for 0..10 spacings" {
    pd-lattice -q --spacing 0.001 --density 2200 "${BOX[@]}" -o b.h5
    run -0 py "
x = h5py.File(sys.argv[1], 'r')['particles/position'][:]
assert x.shape == (1331, 3), x.shape
for d in range(3):
    assert np.allclose(np.unique(np.round(x[:, d] / 1e-3)), np.arange(11)), d
print('ok')" b.h5
    assert_output ok
}

@test "a face on a lattice plane only to rounding is warned about, with the exact remedy" {
    # 9 x 0.0005 = 0.0045000000000000005 > 0.0045: 9 planes in y and z, not 10
    run -0 --separate-stderr pd-lattice --spacing 0.0005 --density 1 \
        --box 0,0.0195,0,0.0045,0,0.0045 -o a.h5
    [ "$(grep -c warning <<<"$stderr")" -eq 1 ]
    [[ "$stderr" == *"warning: --box: its face y = 0.0045 lies 1.7e-15 spacings from the lattice plane y = 9 x 0.0005 = 0.0045000000000000005, whose sites rounding puts outside; to say which you mean, give the face half a spacing away (0.00475 keeps them, 0.00425 leaves them out); 1 more face like it"* ]]
    [[ "$stderr" == *"3240 particles"* ]]
    # the remedy: faces half a spacing beyond the planes meant, no warning
    run -0 --separate-stderr pd-lattice --spacing 0.0005 --density 1 \
        --box -0.00025,0.01975,-0.00025,0.00475,-0.00025,0.00475 -o b.h5
    [[ "$stderr" != *warning* && "$stderr" == *"4000 particles"* ]]
    # a face exactly on its plane (10 x 0.001 is 0.01) is not warned about
    run -0 --separate-stderr pd-lattice --spacing 0.001 --density 1 "${BOX[@]}" -o c.h5
    [[ "$stderr" != *warning* ]]
    # sets, material regions and cylinder ends are checked too; -q is quiet
    run -0 --separate-stderr pd-lattice --spacing 0.0001 --density 1 \
        --cylinder z,0,0,0.0005,0,0.0003 --set low=box,-1,1,-1,1,-1,0.0003 \
        --material-region 2=box,-1,1,-1,1,-1,0.0003 -o d.h5
    [ "$(grep -c warning <<<"$stderr")" -eq 3 ]
    [[ "$stderr" == *"warning: --cylinder: its face z = 0.0003 "*"puts outside"* ]]
    [[ "$stderr" == *"warning: --set low: its face z = 0.0003 "*"puts outside"* ]]
    [[ "$stderr" == *"warning: --material-region 2: its face z = 0.0003 "*"puts outside"* ]]
    run -0 --separate-stderr pd-lattice -q --spacing 0.0005 --density 1 \
        --box 0,0.0195,0,0.0045,0,0.0045 -o e.h5
    [ -z "$stderr" ]
}

@test "a sphere holds exactly the sites within its radius, surface included" {
    # radius 3 spacings around a site: the 123 integer points with
    # i^2 + j^2 + k^2 <= 9 (spacing 0.5 so that every value is exact)
    pd-lattice -q --spacing 0.5 --density 1 --sphere 1,1,1,1.5 -o s.h5
    run -0 py "
x = h5py.File(sys.argv[1], 'r')['particles/position'][:]
k = (x - 1) / 0.5
assert x.shape[0] == 123, x.shape
assert np.all((k**2).sum(axis=1) <= 9 + 1e-12)
print('ok')" s.h5
    assert_output ok
}

@test "every particle has volume spacing^3, radius spacing/2, the density and material given" {
    pd-lattice -q --spacing 0.0007 --density 2500 --material 3 --sphere 0,0,0,0.003 -o s.h5
    run -0 py "
f = h5py.File(sys.argv[1], 'r')
p = f['particles']
h = 0.0007
assert p.attrs['spacing'] == h
assert int(p.attrs['dimension']) == 3
assert p['position'].dtype == np.float64 and p['volume'].dtype == np.float64
assert p['material'].dtype == np.int32 and p['id'].dtype == np.int64
assert np.all(p['volume'][:] == h * h * h), p['volume'][:5]
assert np.all(p['radius'][:] == h / 2)
assert np.all(p['density'][:] == 2500.0)
assert np.all(p['material'][:] == 3)
print('ok')" s.h5
    assert_output ok
}

@test "sites are multiples of the spacing inside the region" {
    pd-lattice -q --spacing 0.0007 --density 1 --box -0.002,0.0031,0.0001,0.004,-0.003,-0.001 -o b.h5
    run -0 py "
x = h5py.File(sys.argv[1], 'r')['particles/position'][:]
h = 0.0007
k = np.round(x / h)
assert np.all(np.abs(x - k * h) <= 1e-15), 'not on the lattice'
lo, hi = np.array([-0.002, 0.0001, -0.003]), np.array([0.0031, 0.004, -0.001])
assert np.all(x >= lo) and np.all(x <= hi)
# and every lattice site of the box is there
n = [np.arange(np.ceil(lo[d] / h), np.floor(hi[d] / h) + 1) for d in range(3)]
assert x.shape[0] == n[0].size * n[1].size * n[2].size, x.shape
print('ok')" b.h5
    assert_output ok
}

@test "ids are 1..N in LAMMPS create_atoms order (z outermost, x innermost)" {
    pd-lattice -q --spacing 0.001 --density 1 --sphere 0.001,0.002,0.003,0.0035 -o s.h5
    run -0 py "
f = h5py.File(sys.argv[1], 'r')
ids = f['particles/id'][:]
x = f['particles/position'][:]
assert np.array_equal(ids, np.arange(1, ids.size + 1)), ids[:10]
key = np.lexsort((x[:, 0], x[:, 1], x[:, 2]))
assert np.array_equal(key, np.arange(ids.size)), 'not in z, y, x order'
print('ok')" s.h5
    assert_output ok
}

@test "--subtract removes exactly the sites inside the subtracted region" {
    pd-lattice -q --spacing 0.001 --density 1 "${BOX[@]}" -o full.h5
    pd-lattice -q --spacing 0.001 --density 1 "${BOX[@]}" \
        --subtract sphere,0.005,0.005,0.005,0.003 --subtract box,0,0.002,0,0.01,0,0.01 -o cut.h5
    run -0 py "
full = h5py.File(sys.argv[1], 'r')['particles/position'][:]
cut = h5py.File(sys.argv[2], 'r')['particles/position'][:]
c = np.array([0.005] * 3)
inside = (np.sqrt(((full - c)**2).sum(axis=1)) <= 0.003) | (full[:, 0] <= 0.002)
keep = full[~inside]
assert cut.shape == keep.shape, (cut.shape, keep.shape)
assert np.array_equal(cut, keep)
assert not np.any(np.sqrt(((cut - c)**2).sum(axis=1)) <= 0.003)
print('ok')" full.h5 cut.h5
    assert_output ok
}

@test "the union of two overlapping boxes holds every site once" {
    # spacing 0.5: every bound is an exact multiple, no rounding at the faces
    pd-lattice -q --spacing 0.5 --density 1 --box 0,3,0,2,0,2 --box 1.5,4.5,1,4,0,2 -o u.h5
    run -0 py "
x = h5py.File(sys.argv[1], 'r')['particles/position'][:]
k = np.round(x / 0.5).astype(int)
assert np.array_equal(k * 0.5, x), 'not on the lattice'
assert np.unique(k, axis=0).shape[0] == k.shape[0], 'duplicate sites'
a = 7 * 5 * 5        # 0..6 x 0..4 x 0..4
b = 7 * 7 * 5        # 3..9 x 2..8 x 0..4
both = 4 * 3 * 5     # 3..6 x 2..4 x 0..4
assert k.shape[0] == a + b - both, (k.shape[0], a + b - both)
print('ok')" u.h5
    assert_output ok
}

@test "--perturb moves every site by at most A per axis, reproducibly by seed" {
    A=0.0001
    pd-lattice -q --spacing 0.001 --density 1 "${BOX[@]}" -o p0.h5
    pd-lattice -q --spacing 0.001 --density 1 "${BOX[@]}" --perturb $A --seed 7 -o p7.h5
    pd-lattice -q --spacing 0.001 --density 1 "${BOX[@]}" --perturb $A --seed 7 -o p7b.h5
    pd-lattice -q --spacing 0.001 --density 1 "${BOX[@]}" --perturb $A --seed 8 -o p8.h5
    run -0 py "
r = lambda n: h5py.File(n, 'r')['particles/position'][:]
x0, x7, x7b, x8 = (r(n) for n in sys.argv[1:5])
A = float(sys.argv[5])
d = np.abs(x7 - x0)
assert d.max() <= A, d.max()
assert d.max() > 0.5 * A, 'hardly perturbed'
assert np.all(d.max(axis=0) > 0.5 * A), 'some axis not perturbed'
assert np.array_equal(x7, x7b), 'same seed, different positions'
assert np.count_nonzero(np.any(x7 != x8, axis=1)) > 0.99 * x7.shape[0], 'different seeds, same positions'
print('ok')" p0.h5 p7.h5 p7b.h5 p8.h5 $A
    assert_output ok
    # the same command line makes the same file: every dataset and attribute
    # (the bytes differ only by HDF5's object modification times)
    pd-lattice -q --spacing 0.001 --density 1 "${BOX[@]}" --perturb $A --seed 7 -o - > s1.h5
    pd-lattice -q --spacing 0.001 --density 1 "${BOX[@]}" --perturb $A --seed 7 -o - > s2.h5
    run -0 h5_same s1.h5 s2.h5
}

@test "the file carries the pd-h5 header and the command line in its history" {
    pd-lattice -q --spacing 0.001 --density 2200 "${BOX[@]}" -o b.h5
    run -0 py "
f = h5py.File(sys.argv[1], 'r')
a = f.attrs
h = a['history']
h = h.decode() if isinstance(h, bytes) else h
print(a['pd_format'], int(a['pd_format_version']), a['units'])
print(h)" b.h5
    assert_line --index 0 "pd-h5 2 SI"
    assert_line --index 1 "pd-lattice -q --spacing 0.001 --density 2200 --box 0,0.01,0,0.01,0,0.01 -o b.h5"
    assert_equal "${#lines[@]}" 2
}

@test "-o - writes the HDF5 file to stdout (default output)" {
    pd-lattice -q --spacing 0.001 --density 2200 "${BOX[@]}" > out.h5
    run -0 py "print(h5py.File(sys.argv[1], 'r')['particles/id'].shape[0])" out.h5
    assert_output 1331
    pd-lattice -q --spacing 0.001 --density 2200 "${BOX[@]}" -o - > out2.h5
    run -0 py "print(h5py.File(sys.argv[1], 'r')['particles/id'].shape[0])" out2.h5
    assert_output 1331
}

@test "the summary goes to stderr, -q silences it" {
    run -0 --separate-stderr pd-lattice --spacing 0.001 --density 2200 "${BOX[@]}" -o b.h5
    assert_equal "$stderr" "pd-lattice: 1331 particles, spacing 0.001 m"
    assert_output ""
    run -0 --separate-stderr pd-lattice -q --spacing 0.001 --density 2200 "${BOX[@]}" -o b.h5
    assert_equal "$stderr" ""
}

@test "the same command gives the same bytes, whenever it runs" {
    mkdir a b
    (cd a && pd-lattice -q --spacing 0.001 --box 0,0.004,0,0.004,0,0.004 --density 1 -o l.h5)
    sleep 1.1 # HDF5 would record a different modification time
    (cd b && pd-lattice -q --spacing 0.001 --box 0,0.004,0,0.004,0,0.004 --density 1 -o l.h5)
    cmp a/l.h5 b/l.h5
}

@test "--origin shifts the sites by fractions of the spacing (LAMMPS lattice ... origin)" {
    # a cube of 8 spacings (exact in binary): 9^3 sites on its faces at the
    # default origin, 8^3 half a spacing in with --origin 0.5,0.5,0.5
    local h=0.0009765625 L=0.0078125
    pd-lattice -q --spacing $h --density 1 --box 0,$L,0,$L,0,$L -o a.h5
    pd-lattice -q --spacing $h --density 1 --box 0,$L,0,$L,0,$L --origin 0.5,0.5,0.5 -o b.h5
    pd-lattice -q --spacing $h --density 1 --box 0,$L,0,$L,-1,1 --origin 0.25,0.5,0 \
        --dimension 2 --thickness 1e-3 -o p.h5
    py "
h = float(sys.argv[1])
a = h5py.File('a.h5')['particles/position'][:]
b = h5py.File('b.h5')['particles/position'][:]
p = h5py.File('p.h5')['particles/position'][:]
assert len(a) == 9 ** 3 and len(b) == 8 ** 3
want = np.array([((i + .5) * h, (j + .5) * h, (k + .5) * h)
                 for k in range(8) for j in range(8) for i in range(8)])
assert (b == want).all()     # (n + 0.5) h, in LAMMPS create_atoms' order
assert len(p) == 8 * 8 and (p[:, 2] == 0).all() and (p[:8, 0] == (np.arange(8) + .25) * h).all()
" "$h"
    # the shifted lattice is still a stencil for pd-bonds
    run --separate-stderr pd-bonds --horizon 0.0030001 b.h5 -o bb.h5
    [[ "$stderr" =~ stored\ as\ a\ lattice\ stencil ]]
    expect_usage_error "--origin needs FX,FY,FZ, fractions of the spacing in \[0, 1\), not '1,0,0'" \
        pd-lattice --spacing $h --density 1 --box 0,$L,0,$L,0,$L --origin 1,0,0
    expect_usage_error "--origin needs FX,FY,FZ" \
        pd-lattice --spacing $h --density 1 --box 0,$L,0,$L,0,$L --origin 0.5,0.5
    expect_usage_error "a plate's sites are at z = 0: give --origin FX,FY,0" \
        pd-lattice --spacing $h --density 1 --box 0,$L,0,$L,-1,1 --origin 0,0,0.5 \
        --dimension 2 --thickness 1e-3
}
