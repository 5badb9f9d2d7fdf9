#!/usr/bin/env bats
# pd-lattice --inside MESH: the lattice filled inside a closed surface mesh
# (and mesh,MESH in --subtract, --set and --material-region).  Checked
# against the regions pd-lattice already has: a cube whose faces lie on
# lattice planes (so rows run through its vertices, edges and facets) is
# exactly --box, either way round; a triangulated sphere holds exactly the
# sites of --sphere but those between its facets and the sphere; a volume
# mesh fills as its own surface does; and open, non-manifold or badly
# oriented surfaces are refused in one line.

load test_helper
bats_require_minimum_version 1.5.0

setup() {
    cd "$BATS_TEST_TMPDIR"
}

GEO="$BATS_TEST_DIRNAME/fixtures/mesh"
# a spacing and a cube edge that are exact in binary: 8 spacings
H=0.0009765625
L=0.0078125

# CUBE: write cube.stl (each face fanned into 4 triangles around its centre,
# a lattice site), cubeinv.stl (turned inward) and the bad surfaces.
CUBE='
import meshio
L = float(sys.argv[1])
c = [(x, y, z) for z in (0, L) for y in (0, L) for x in (0, L)]
quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
pts, tri = list(c), []
for q in quads:
    pts.append(tuple(np.mean([c[k] for k in q], axis=0)))
    m = len(pts) - 1
    tri += [(q[k], q[(k + 1) % 4], m) for k in range(4)]
pts, tri = np.array(pts), np.array(tri)
meshio.Mesh(pts, [("triangle", tri)]).write("cube.stl")
meshio.Mesh(pts, [("triangle", tri[:, ::-1])]).write("cubeinv.stl")
meshio.Mesh(pts, [("triangle", tri[:-1])]).write("open.stl")
flip = tri.copy(); flip[0] = flip[0][::-1]
meshio.Mesh(pts, [("triangle", flip)]).write("turned.obj")
# two cubes that share an edge: closed, but the edge has four triangles
two = np.concatenate([pts, pts + [L, L, 0]])
meshio.Mesh(two, [("triangle", np.concatenate([tri, tri + len(pts)]))]).write("bowtie.obj")
'

@test "inside: a cube on lattice planes holds exactly the sites of --box, either way round" {
    py "$CUBE" "$L"
    local box="--box 0,$L,0,$L,0,$L"
    pd-lattice -q --spacing "$H" --density 1 $box -o box.h5
    run --separate-stderr pd-lattice --spacing "$H" --density 1 --inside cube.stl -o cube.h5
    assert_success
    [[ "$stderr" =~ mesh\ \'cube.stl\':\ a\ closed\ surface\ of\ 24\ triangles,\ volume\ 4.768371582e-07\ m\^3 ]]
    pd-lattice -q --spacing "$H" --density 1 --inside cubeinv.stl -o inv.h5
    # cut out of a larger box, and as a set and a material region
    local big="--box -0.002,0.01,-0.002,0.01,-0.002,0.01"
    pd-lattice -q --spacing "$H" --density 1 $big --subtract "box,0,$L,0,$L,0,$L" -o a.h5
    pd-lattice -q --spacing "$H" --density 1 $big --subtract mesh,cubeinv.stl -o b.h5
    pd-lattice -q --spacing "$H" --density 1 $big --set s=mesh,cube.stl \
        --material-region 4=mesh,cubeinv.stl -o c.h5
    pd-lattice -q --spacing "$H" --density 1 $big --set "s=box,0,$L,0,$L,0,$L" \
        --material-region "4=box,0,$L,0,$L,0,$L" -o d.h5
    py "
x = {n: h5py.File(n + '.h5')['particles/position'][:] for n in ('box', 'cube', 'inv', 'a', 'b')}
assert len(x['box']) == 9 ** 3
assert (x['cube'] == x['box']).all() and (x['inv'] == x['box']).all()
assert (x['a'] == x['b']).all()
c, d = h5py.File('c.h5'), h5py.File('d.h5')
assert (c['sets/s'][:] == d['sets/s'][:]).all() and len(c['sets/s']) == 9 ** 3
assert (c['particles/material'][:] == d['particles/material'][:]).all()
assert (c['particles/material'][:] == 4).sum() == 9 ** 3
"
}

@test "inside: a triangulated sphere holds the sites of --sphere but those between its facets and the sphere" {
    gmsh -v 0 -2 -format stl -o sphere.stl "$GEO/sphere.geo"
    gmsh -v 0 -3 -format msh41 -o sphere.msh "$GEO/sphere.geo"
    local h=0.0002
    pd-lattice -q --spacing $h --density 1 --sphere 0.0003,0.0002,0.0001,0.005 -o ball.h5
    pd-lattice -q --spacing $h --density 1 --inside sphere.stl -o stl.h5
    pd-lattice -q --spacing $h --density 1 --inside sphere.msh -o msh.h5
    pd-mesh -q --surface sphere.stl -o surface.h5
    pd-lattice -q --spacing $h --density 1 --inside surface.h5 -o h5.h5
    # a plate cut through it at z = 0
    pd-lattice -q --dimension 2 --thickness 1e-3 --spacing $h --density 1 --inside sphere.stl -o disk.h5
    pd-lattice -q --dimension 2 --thickness 1e-3 --spacing $h --density 1 \
        --sphere 0.0003,0.0002,0.0001,0.005 -o disk0.h5
    py "
import meshio
c, R, h = np.array([0.0003, 0.0002, 0.0001]), 0.005, 0.0002
m = meshio.read('sphere.stl')
t = np.concatenate([b.data for b in m.cells if b.type == 'triangle']); p = m.points
a, b, q = p[t[:, 0]], p[t[:, 1]], p[t[:, 2]]
n = np.cross(b - a, q - a); n /= np.linalg.norm(n, axis=1)[:, None]
inradius = np.abs(np.einsum('ij,ij->i', n, a - c)).min()   # nearest facet plane to the centre
Vpoly = abs(np.einsum('ij,ij->i', a - c, np.cross(b - c, q - c)).sum()) / 6
def sites(name):
    x = h5py.File(name + '.h5')['particles/position'][:]
    return {tuple(v) for v in np.round(x / h).astype(int)}, x
ball, xb = sites('ball')
for name in ('stl', 'msh', 'h5'):
    s, x = sites(name)
    assert s <= ball, name                       # the facets lie inside the sphere
    r = np.linalg.norm(xb - c, axis=1)
    held = np.array([tuple(v) in s for v in np.round(xb / h).astype(int)])
    assert held[r < inradius - 1e-9].all(), name  # all but the shell of the facets
    missing = len(ball) - len(s)
    expect = (4 / 3 * np.pi * R ** 3 - Vpoly) / h ** 3
    assert 0.6 * expect < missing < 1.4 * expect, (name, missing, expect)
assert sites('stl')[0] == sites('msh')[0] == sites('h5')[0]
d, x = sites('disk'); d0, _ = sites('disk0')
assert d <= d0 and len(d) > 0.98 * len(d0) and (x[:, 2] == 0).all()
"
}

@test "inside: a volume mesh with a hole fills as the box minus the sphere, but near the hole's facets" {
    cat >holed.geo <<'EOF'
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 0.008, 0.006, 0.004};
Sphere(2) = {0.004, 0.003, 0.002, 0.0015};
BooleanDifference(3) = { Volume{1}; Delete; }{ Volume{2}; Delete; };
Mesh.CharacteristicLengthMax = 0.0006;
EOF
    gmsh -v 0 -3 -format msh41 -o holed.msh holed.geo
    local h=0.0005
    pd-lattice -q --spacing $h --density 1 --inside holed.msh -o mesh.h5
    pd-lattice -q --spacing $h --density 1 --box 0,0.008,0,0.006,0,0.004 \
        --subtract sphere,0.004,0.003,0.002,0.0015 -o exact.h5
    py "
a = h5py.File('mesh.h5')['particles/position'][:]
b = h5py.File('exact.h5')['particles/position'][:]
A, B = {tuple(v) for v in np.round(a / 0.0005).astype(int)}, {tuple(v) for v in np.round(b / 0.0005).astype(int)}
# the box's faces are on lattice planes: only sites near the hole differ,
# and the facets lie inside the sphere, so the mesh holds more, never less
assert B <= A, len(B - A)
extra = np.array(sorted(A - B)) * 0.0005
r = np.linalg.norm(extra - [0.004, 0.003, 0.002], axis=1) if len(extra) else np.zeros(0)
assert ((r > 0.0015 * 0.95) & (r <= 0.0015)).all(), r
"
}

@test "inside: a row that crosses 1,200 facets (more than a row's crossings are kept) fills every cube" {
    # 600 cubes of 2 spacings, a spacing apart along x, on lattice planes
    py "
import meshio
h = float(sys.argv[1])
c = np.array([(x, y, z) for z in (0, 2) for y in (0, 2) for x in (0, 2)], float)
quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
tri = np.array([t for a, b, q, d in quads for t in ((a, b, q), (a, q, d))])
pts = np.concatenate([(c + [3 * k, 0, 0]) * h for k in range(600)])
cells = np.concatenate([tri + 8 * k for k in range(600)])
meshio.Mesh(pts, [('triangle', cells)]).write('row.stl')
" "$H"
    pd-lattice -q --spacing "$H" --density 1 --inside row.stl -o row.h5
    py "
h = float(sys.argv[1])
x = np.round(h5py.File('row.h5')['particles/position'][:] / h).astype(int)
want = {(3 * k + i, j, l) for k in range(600) for i in range(3) for j in range(3) for l in range(3)}
assert {tuple(v) for v in x} == want, len(x)
" "$H"
}

@test "inside: open, non-manifold and badly oriented surfaces are refused in one line, with no output" {
    py "$CUBE" "$L"
    local opts=(--spacing "$H" --density 1)
    expect_runtime_error "'open.stl': the surface is open: 1 boundary edges|the surface is open: 3 boundary edges" \
        pd-lattice "${opts[@]}" --inside open.stl -o out.h5
    expect_runtime_error "the surface is not manifold: 1 edges of more than two triangles" \
        pd-lattice "${opts[@]}" --inside bowtie.obj -o out.h5
    expect_runtime_error "the surface's triangles are not oriented alike: 3 edges" \
        pd-lattice "${opts[@]}" --inside turned.obj -o out.h5
    echo "solid nothing at all" >empty.stl
    expect_runtime_error "--inside 'empty.stl': the mesh has no cells" \
        pd-lattice "${opts[@]}" --inside empty.stl -o out.h5
    printf 'not a mesh' >junk.off
    expect_runtime_error "--inside 'junk.off': meshio cannot read 'junk.off'" \
        pd-lattice "${opts[@]}" --inside junk.off -o out.h5
    expect_runtime_error "--inside: cannot open 'nothere.stl'" \
        pd-lattice "${opts[@]}" --inside nothere.stl -o out.h5
    expect_runtime_error "cannot open 'nothere.stl'" \
        pd-lattice "${opts[@]}" --box 0,1e-3,0,1e-3,0,1e-3 --set s=mesh,nothere.stl -o out.h5
    make_block
    expect_runtime_error "holds no /surface \(write one with pd-mesh --surface\)" \
        pd-lattice "${opts[@]}" --inside model.h5 -o out.h5
    [ ! -e out.h5 ]
    assert_no_temp .
}
