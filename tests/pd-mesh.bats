#!/usr/bin/env bats
# pd-mesh: meshes to particles.  The meshes are made here by Debian's gmsh
# from the .geo files of tests/fixtures/mesh (and a few by meshio itself),
# and every check is against the mesh as meshio reads it, computed here
# independently: one particle per cell at its centroid with its exact
# volume (tetrahedra by their determinant, boxes and layers by their
# measures), the materials and sets by the rules of pd-mesh(1), a plate's
# area, the closed outward surface of --surface; then the physics on a
# meshed bar, and every kind of bad input.

load test_helper
bats_require_minimum_version 1.5.0

setup() {
    cd "$BATS_TEST_TMPDIR"
}

GEO="$BATS_TEST_DIRNAME/fixtures/mesh"

# _build_meshes DIR: the fixtures meshed, as Gmsh 4.1 files.
_build_meshes() {
    local d=$1
    gmsh -v 0 -3 -format msh41 -o "$d/box.msh" "$GEO/box.geo" &&
        gmsh -v 0 -3 -order 2 -format msh41 -o "$d/box10.msh" "$GEO/box.geo" &&
        gmsh -v 0 -3 -format msh41 -o "$d/two.msh" "$GEO/two.geo" &&
        gmsh -v 0 -3 -format msh41 -o "$d/hex8.msh" "$GEO/hexbox.geo" &&
        gmsh -v 0 -3 -order 2 -format msh41 -o "$d/hex27.msh" "$GEO/hexbox.geo" &&
        gmsh -v 0 -3 -order 2 -string 'Mesh.SecondOrderIncomplete = 1;' -format msh41 \
            -o "$d/hex20.msh" "$GEO/hexbox.geo" &&
        gmsh -v 0 -3 -format msh41 -o "$d/prism.msh" "$GEO/prism.geo" &&
        gmsh -v 0 -3 -format msh41 -o "$d/cyl1.msh" "$GEO/cylinder.geo" &&
        gmsh -v 0 -3 -order 2 -format msh41 -o "$d/cyl2.msh" "$GEO/cylinder.geo" &&
        gmsh -v 0 -2 -format msh41 -o "$d/plate.msh" "$GEO/plate.geo" &&
        gmsh -v 0 -2 -string 'Mesh.RecombineAll = 1;' -format msh41 -o "$d/plateq.msh" \
            "$GEO/plate.geo"
}
make_meshes() {
    _pd_cached meshes _build_meshes || return 1
    cp "$_PD_CACHE"/*.msh .
}

# CELLS: meshio's cells of a mesh, for the checks (tetrahedra only).
CELLS='
import meshio
def tets(path):
    m = meshio.read(path)
    t = np.concatenate([c.data for c in m.cells if c.type == "tetra"])
    return m, t
'

@test "pd-mesh: --help and --version; usage errors are one line and exit 2" {
    run pd-mesh --help
    assert_success
    assert_output --partial "Usage: pd-mesh --density RHO"
    run pd-mesh --version
    assert_output --regexp '^pd-mesh \(pd\) [0-9]+\.[0-9]+\.[0-9]+$'
    expect_usage_error "--density is required" pd-mesh box.msh
    expect_usage_error "give one mesh file" pd-mesh --density 1
    expect_usage_error "unexpected argument 'b.msh'" pd-mesh --density 1 a.msh b.msh
    expect_usage_error "--density must be a positive number, not '-1'" pd-mesh --density -1 a.msh
    expect_usage_error "--thickness must be a positive number" pd-mesh --density 1 --thickness 0 a.msh
    expect_usage_error "--material needs NAME=ID" pd-mesh --density 1 --material top a.msh
    expect_usage_error "--material ID must be a non-negative integer" pd-mesh --density 1 \
        --material top=-2 a.msh
    expect_usage_error "option --frobnicate not recognized" pd-mesh --frobnicate a.msh
    expect_usage_error "--surface takes no --density" pd-mesh --surface --density 1 a.msh
}

@test "pd-mesh: a block of tetrahedra: a particle per cell at its centroid, with its volume" {
    make_meshes
    run --separate-stderr pd-mesh --density 2200 box.msh -o m.h5
    assert_success
    [[ "$stderr" =~ particles\ from\ [0-9]+\ tetra ]]
    py "$CELLS
m, t = tets('box.msh')
p = m.points
f = h5py.File('m.h5'); g = f['particles']
x, V, rho = g['position'][:], g['volume'][:], g['density'][:]
a, b, c, d = (p[t[:, k]] for k in range(4))
vol = np.einsum('ij,ij->i', np.cross(b - a, c - a), d - a) / 6
assert (vol > 0).all()
assert len(V) == len(t) and np.allclose(V, vol, rtol=1e-12, atol=0)
assert np.allclose(x, p[t].mean(axis=1), rtol=0, atol=1e-15)
# the volumes sum to the block's, and the mass follows from them
assert abs(V.sum() - 0.01 * 0.004 * 0.002) < 1e-12 * 8e-8, V.sum()
assert abs((rho * V).sum() - 2200 * 8e-8) < 1e-12 * 2200 * 8e-8
assert (rho == 2200).all()
# spacing: the cube root of the mean cell volume; radius: each cell's half
assert abs(g.attrs['spacing'] - V.mean() ** (1 / 3)) < 1e-15
assert np.allclose(g['radius'][:], V ** (1 / 3) / 2, rtol=1e-15)
assert g.attrs['dimension'] == 3 and 'thickness' not in g.attrs
assert (g['id'][:] == np.arange(1, len(V) + 1)).all()
assert f.attrs['pd_format'] == 'pd-h5' and f.attrs['pd_format_version'] == 2
assert f.attrs['history'] == 'pd-mesh --density 2200 box.msh -o m.h5'
"
}

@test "pd-mesh: quadratic tetrahedra and hexahedra, wedges and pyramids have their exact volumes" {
    make_meshes
    for m in hex8 hex20 hex27 prism cyl1 cyl2 box10; do
        pd-mesh -q --density 1 "$m.msh" -o "$m.h5"
    done
    py "
import meshio
V = {n: h5py.File(n + '.h5')['particles/volume'][:] for n in
     ('hex8', 'hex20', 'hex27', 'prism', 'cyl1', 'cyl2', 'box10')}
X = {n: h5py.File(n + '.h5')['particles/position'][:] for n in V}
box = 0.004 * 0.003 * 0.002
# 27 equal bricks, each at its own centre, at every order
for n in ('hex8', 'hex20', 'hex27'):
    m = meshio.read(n + '.msh')
    assert [c.type for c in m.cells if c.type.startswith('hexa')] == \
        [{'hex8': 'hexahedron', 'hex20': 'hexahedron20', 'hex27': 'hexahedron27'}[n]]
    assert len(V[n]) == 27 and np.allclose(V[n], box / 27, rtol=1e-12), n
    centres = np.array([(0.004 / 3 * (i + .5), 0.001 * (j + .5), 0.002 / 3 * (k + .5))
                        for i in range(3) for j in range(3) for k in range(3)])
    d = np.abs(X[n][:, None, :] - centres[None, :, :]).max(axis=2).min(axis=1)
    assert d.max() < 1e-15, (n, d.max())
# wedges: the triangle's area times the layer
m = meshio.read('prism.msh')
w = np.concatenate([c.data for c in m.cells if c.type == 'wedge'])
p = m.points
area = np.abs(np.cross(p[w[:, 1]] - p[w[:, 0]], p[w[:, 2]] - p[w[:, 0]])[:, 2]) / 2
assert np.allclose(V['prism'], area * 0.001, rtol=1e-12)
assert abs(V['prism'].sum() - box) < 1e-12 * box
# a quadratic tetrahedron's curved faces follow the cylinder: 50 times closer
exact = np.pi * 0.002 ** 2 * 0.004
e1, e2 = abs(V['cyl1'].sum() - exact) / exact, abs(V['cyl2'].sum() - exact) / exact
assert e2 < 1e-4 and e2 < e1 / 50, (e1, e2)
# and straight tetra10 are their tetrahedra
assert abs(V['box10'].sum() - 8e-8) < 1e-12 * 8e-8
# pyramids: a cube cut into six from its centre
q = np.array([(x, y, z) for z in (0, 1e-3) for y in (0, 1e-3) for x in (0, 1e-3)] + [(5e-4,) * 3])
faces = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
cells = np.array([f[::-1] + (8,) for f in faces])   # base turning towards the apex
meshio.Mesh(q, [('pyramid', cells)]).write('pyr.vtu')
" 
    pd-mesh -q --density 1 pyr.vtu -o pyr.h5
    py "
f = h5py.File('pyr.h5'); V = f['particles/volume'][:]; x = f['particles/position'][:]
assert np.allclose(V, 1e-9 / 6, rtol=1e-12), V
# the centroid of a pyramid: a quarter of the way from its base to its apex
q = np.array([(x, y, z) for z in (0, 1e-3) for y in (0, 1e-3) for x in (0, 1e-3)])
faces = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
want = np.array([q[list(f)].mean(axis=0) * 0.75 + 0.25 * 5e-4 for f in faces])
assert np.abs(x - want).max() < 1e-18, np.abs(x - want).max()
"
}

@test "pd-mesh: materials are Gmsh physical tags or --material NAME=ID, the last one winning" {
    make_meshes
    run --separate-stderr pd-mesh --density 1 two.msh -o two.h5
    assert_success
    [[ "$stderr" =~ material\ 1:\ [0-9]+\ particles\ \(Gmsh\ physical\ tag\) ]]
    pd-mesh -q --density 1 --material hard=5 --material soft=9 --material hard=6 two.msh -o m.h5
    py "
import meshio
m = meshio.read('two.msh')
tags = np.concatenate([t for c, t in zip(m.cells, m.cell_data['gmsh:physical'])
                       if c.type == 'tetra'])
a = h5py.File('two.h5')['particles/material'][:]
b = h5py.File('m.h5')['particles/material'][:]
x = h5py.File('two.h5')['particles/position'][:]
assert (a == tags).all() and set(a) == {1, 2}
# physical volume 1 is x < 5 mm, 2 beyond
assert (x[a == 1, 0] < 0.005).all() and (x[a == 2, 0] > 0.005).all()
assert (b[a == 2] == 6).all() and (b[a == 1] == 9).all()
# the named volumes are sets too
s = h5py.File('two.h5')['sets']
ids = h5py.File('two.h5')['particles/id'][:]
assert (s['soft'][:] == ids[a == 1]).all() and (s['hard'][:] == ids[a == 2]).all()
"
}

@test "pd-mesh: sets: a cell set is its cells; a node set, or a physical surface, the cells touching it" {
    make_meshes
    pd-mesh -q --density 1 box.msh -o box.h5
    py "$CELLS
m, t = tets('box.msh')
p = m.points
f = h5py.File('box.h5'); s = f['sets']
ids = f['particles/id'][:]
# the physical surfaces x = 0 and x = 10 mm: every cell with a node on them
for name, x0 in (('left', 0.0), ('right', 0.01)):
    want = ids[(np.abs(p[t][:, :, 0] - x0) < 1e-12).any(axis=1)]
    assert (s[name][:] == want).all() and len(want) > 0, name
assert (s['body'][:] == ids).all()
# an Abaqus file of 4 x 3 x 2 hexahedra with an ELSET and an NSET, written by meshio
nx, ny, nz, h = 4, 3, 2, 1e-3
q = np.array([(i * h, j * h, k * h) for k in range(nz + 1) for j in range(ny + 1)
              for i in range(nx + 1)])
n = lambda i, j, k: i + (nx + 1) * (j + (ny + 1) * k)
cells = np.array([[n(i, j, k), n(i + 1, j, k), n(i + 1, j + 1, k), n(i, j + 1, k),
                   n(i, j, k + 1), n(i + 1, j, k + 1), n(i + 1, j + 1, k + 1), n(i, j + 1, k + 1)]
                  for k in range(nz) for j in range(ny) for i in range(nx)])
left = np.array([n(0, j, k) for k in range(nz + 1) for j in range(ny + 1)])
corner = np.array([n(nx, ny, nz)])
top = np.arange(12, 24)
meshio.Mesh(q, [('hexahedron', cells)], point_sets={'LEFT': left, 'CORNER': corner},
            cell_sets={'TOP': [top]}).write('grid.inp')
"
    run --separate-stderr pd-mesh --density 1000 --material TOP=3 grid.inp -o grid.h5
    assert_success
    [[ "$stderr" =~ set\ \'LEFT\':\ 6\ particles\ \(node\ set\) ]]
    py "
f = h5py.File('grid.h5'); s = f['sets']
assert sorted(s) == ['CORNER', 'LEFT', 'TOP']
assert len(s['TOP']) == 12 and len(s['LEFT']) == 6 and list(s['CORNER']) == [24]
assert (s['TOP'][:] == np.arange(13, 25)).all()
assert (s['LEFT'][:] == np.arange(1, 25, 4)).all()
mat = f['particles/material'][:]
assert (mat[12:] == 3).all() and (mat[:12] == 1).all()
assert np.allclose(f['particles/volume'][:], 1e-9, rtol=1e-12)
"
}

@test "pd-mesh: a 2-D mesh with --thickness is a plate: area times thickness, at z = 0" {
    make_meshes
    for m in plate plateq; do
        run --separate-stderr pd-mesh --density 2200 --thickness 0.001 "$m.msh" -o "$m.h5"
        assert_success
        [[ "$stderr" =~ a\ 2-D\ plate ]]
    done
    py "
import meshio
for name, kind in (('plate', 'triangle'), ('plateq', 'quad')):
    m = meshio.read(name + '.msh')
    c = np.concatenate([b.data for b in m.cells if b.type == kind])
    p = m.points[:, :2]
    k = c.shape[1]
    # the shoelace area of each cell
    area = sum(p[c[:, i], 0] * p[c[:, (i + 1) % k], 1] - p[c[:, (i + 1) % k], 0] * p[c[:, i], 1]
               for i in range(k)) / 2
    f = h5py.File(name + '.h5'); g = f['particles']
    V = g['volume'][:]
    assert len(V) == len(c) and np.allclose(V, np.abs(area) * 0.001, rtol=1e-12), name
    assert g.attrs['dimension'] == 2 and g.attrs['thickness'] == 0.001
    assert (g['position'][:, 2] == 0).all()
    assert abs(g.attrs['spacing'] - (V / 0.001).mean() ** 0.5) < 1e-15
    # the physical curves left and right: the cells touching them
    for s, x0 in (('left', 0), ('right', 0.02)):
        want = g['id'][:][(np.abs(m.points[c][:, :, 0] - x0) < 1e-12).any(axis=1)]
        assert (f['sets/' + s][:] == want).all() and len(want) > 5, (name, s)
"
    # and it runs as a plate
    pd-bonds -q --horizon 0.0015 plate.h5 -o pb.h5
    run --separate-stderr pd-run --youngs-modulus 7e10 --steps 20 --velocity-bc left,x,-1 \
        --velocity-bc right,x,1 pb.h5 -o run.h5
    assert_success
    [[ "$stderr" =~ 2-D ]] || [[ "$stderr" =~ plate ]]
}

@test "pd-mesh: it pipes: pd-mesh -o - | pd-bonds - | pd-run -, with the history of every stage" {
    make_meshes
    pd-mesh -q --density 2200 box.msh -o - | pd-bonds -q --horizon 0.0016 - -o - |
        pd-run -q --youngs-modulus 7e10 --steps 10 --velocity-bc left,x,-1 - -o run.h5
    py "
f = h5py.File('run.h5')
h = f.attrs['history'].split('\n')
assert h[0] == 'pd-mesh -q --density 2200 box.msh -o -' and h[1].startswith('pd-bonds')
assert h[2].startswith('pd-run')
assert f['particles/volume'].shape[0] == f['frames/00000010/displacement'].shape[0]
"
}

@test "pd-mesh --surface: the closed boundary of a volume mesh, outward, enclosing the cells' volume" {
    make_meshes
    run --separate-stderr pd-mesh --surface box.msh -o s.h5
    assert_success
    [[ "$stderr" =~ surface\ of\ [0-9]+\ triangles ]]
    pd-mesh -q --density 1 box.msh -o m.h5
    py "
f = h5py.File('s.h5'); p = f['surface/points'][:]; t = f['surface/triangles'][:]
assert 'particles' not in f
a, b, c = p[t[:, 0]], p[t[:, 1]], p[t[:, 2]]
vol = np.einsum('ij,ij->i', a, np.cross(b, c)).sum() / 6
V = h5py.File('m.h5')['particles/volume'][:].sum()
assert abs(vol - V) < 1e-12 * V, (vol, V)       # outward: a positive volume
# closed: every edge twice, once each way
e = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
fw = {tuple(x) for x in e}
assert len(fw) == len(e) and all((y, x) in fw for x, y in fw)
# every point on the block's faces
on = np.isclose(p, 0).any(axis=1) | np.isclose(p, [0.01, 0.004, 0.002]).any(axis=1)
assert on.all()
"
}

@test "pd-mesh: a meshed bar stretched quasi-statically has the strain energy of its stress" {
    # PMB with K = 14 GPa (nu = 1/4, E = 3K/2 = 21 GPa); a 24 x 8 x 8 mm bar
    # of tetrahedra (spacing about 0.47 mm), horizon 2 mm, the ends 1.5 mm
    # held and pulled 1 um along x.  Away from the surfaces the strain
    # energy density W is sigma eps / 2 (to 1%), and within 15% of the
    # continuum's E eps^2 / 2: a bond family of m = delta / spacing ~ 4 on
    # an irregular mesh gives 0.89 E (the lattice bar of relax.bats, at
    # m = 3, 0.83 E).
    cat >bar.geo <<'EOF'
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 0.024, 0.008, 0.008};
Mesh.CharacteristicLengthMax = 0.0008;
EOF
    gmsh -v 0 -3 -format msh41 -o bar.msh bar.geo
    pd-mesh -q --density 2200 bar.msh -o bar.h5
    py "
f = h5py.File('bar.h5', 'a'); x = f['particles/position'][:]; ids = f['particles/id'][:]
f['sets/left'] = ids[x[:, 0] < 0.0015]
f['sets/right'] = ids[x[:, 0] > 0.0225]
"
    pd-bonds -q --horizon 0.0020001 bar.h5 -o barb.h5
    pd-run -q --bulk-modulus 14e9 --relax --dt 1 --velocity-bc left,x,0 --velocity-bc right,x,1e-6 \
        --steps 1 --fields stress,energy barb.h5 -o r.h5
    py "
f = h5py.File('r.h5'); x = f['particles/position'][:]
fr = f['frames/00000001']; u = fr['displacement'][:]
S, W = fr['stress'][:], fr['strain_energy_density'][:]
inner = (x[:, 0] > 0.008) & (x[:, 0] < 0.016)
for a in (1, 2):
    inner &= np.abs(x[:, a] - 0.004) < 0.0015
assert inner.sum() > 300, inner.sum()
eps = np.polyfit(x[inner, 0], u[inner, 0], 1)[0]
sxx, w = S[inner, 0, 0].mean(), W[inner].mean()
assert abs(sxx * eps / 2 - w) < 0.01 * w, (sxx * eps / 2, w)
ratio = w / (0.5 * 21e9 * eps ** 2)
assert 0.85 < ratio < 1.0, ratio
print('W / (E eps^2 / 2) =', ratio)
"
}

@test "pd-mesh: bad meshes get one line and exit 1, and leave no output" {
    make_meshes
    echo "this is not a mesh" >junk.msh
    expect_runtime_error "meshio cannot read 'junk.msh'" pd-mesh --density 1 junk.msh -o out.h5
    expect_runtime_error "cannot open 'nothere.msh': no such file" pd-mesh --density 1 nothere.msh -o out.h5
    expect_runtime_error "no 3-D cells \(for a 2-D mesh give --thickness H\)" \
        pd-mesh --density 1 plate.msh -o out.h5
    expect_runtime_error "--thickness is for a 2-D mesh" \
        pd-mesh --density 1 --thickness 0.001 box.msh -o out.h5
    expect_runtime_error "--material nothere=3: the mesh has no cell set 'nothere' \(its cell sets: body, left, right\)" \
        pd-mesh --density 1 --material nothere=3 box.msh -o out.h5
    expect_runtime_error "--material left=3: cell set 'left' holds no cell of the body" \
        pd-mesh --density 1 --material left=3 box.msh -o out.h5
    py "$CELLS
m, t = tets('box.msh')
p = m.points
bad = t.copy(); bad[5] = bad[5][[1, 0, 2, 3]]               # one cell turned inside out
meshio.Mesh(p, [('tetra', bad)]).write('inverted.vtu')
flat = t.copy(); flat[3, 3] = flat[3, 2]                     # one cell with no volume
meshio.Mesh(p, [('tetra', flat)]).write('flat.vtu')
meshio.Mesh(p, [('wedge18', np.arange(18)[None, :])]).write('w18.vtu')
q = np.array([(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (.5, 0, 0), (1, .5, 0), (.5, 1, 0),
              (0, .5, 0)], float) * 1e-3
meshio.Mesh(q, [('quad8', np.arange(8)[None, :])]).write('q8.vtu')
meshio.Mesh(q + [0, 0, 1e-3], [('quad', np.arange(4)[None, :])]).write('lifted.vtu')
"
    expect_runtime_error "1 inverted or tangled tetra cell\(s\) of [0-9]+ \(the first is tetra cell 5\)" \
        pd-mesh --density 1 inverted.vtu -o out.h5
    expect_runtime_error "1 tetra cell\(s\) of zero volume \(the first is tetra cell 3\)" \
        pd-mesh --density 1 flat.vtu -o out.h5
    expect_runtime_error "unsupported cell type 'wedge18'" pd-mesh --density 1 w18.vtu -o out.h5
    expect_runtime_error "unsupported cell type 'quad8' for a plate" \
        pd-mesh --density 1 --thickness 1e-3 q8.vtu -o out.h5
    expect_runtime_error "must lie in the plane z = 0" \
        pd-mesh --density 1 --thickness 1e-3 lifted.vtu -o out.h5
    expect_runtime_error "refusing to write binary|the mesh must be a file" pd-mesh --density 1 - -o out.h5
    [ ! -e out.h5 ]
    assert_no_temp .
    mkdir adir
    expect_runtime_error "cannot write 'adir': it is a directory" pd-mesh --density 1 box.msh -o adir
}

@test "pd-mesh: a meshed plate and the lattice plate of the same scene store the same elastic energy, within 3%" {
    # a 20 x 10 mm plate, 1 mm thick, PMB with E = 70 GPa, horizon 1.5 mm:
    # gmsh's triangles (about 0.33 mm) and the square lattice at 0.5 mm,
    # the ends 1.5 mm held and pulled 1 um quasi-statically.  Measured:
    # 1.790e-5 J and 1.801e-5 J (0.6% apart), reactions 35.80 N and 36.03 N.
    cat >rect.geo <<'GEO'
SetFactory("OpenCASCADE");
Rectangle(1) = {0, 0, 0, 0.02, 0.01};
Mesh.CharacteristicLengthMax = 0.0005;
GEO
    gmsh -v 0 -2 -format msh41 -o rect.msh rect.geo
    pd-mesh -q --density 2200 --thickness 0.001 rect.msh -o mesh.h5
    py "
f = h5py.File('mesh.h5', 'a'); x = f['particles/position'][:]; ids = f['particles/id'][:]
f['sets/left'] = ids[x[:, 0] < 0.0015]
f['sets/right'] = ids[x[:, 0] > 0.0185]
"
    pd-lattice -q --dimension 2 --thickness 0.001 --spacing 0.0005 --density 2200 \
        --box -0.00025,0.02025,-0.00025,0.01025,0,0 --set left=box,-1,0.0015,-1,1,-1,1 \
        --set right=box,0.0185,1,-1,1,-1,1 -o lattice.h5
    local stretch=(--youngs-modulus 7e10 --relax --dt 1 --velocity-bc left,x,0
        --velocity-bc right,x,1e-6 --steps 1)
    for m in mesh lattice; do
        pd-bonds -q --horizon 0.0015001 "$m.h5" -o "$m-b.h5"
        pd-run -q "${stretch[@]}" "$m-b.h5" -o "$m-r.h5"
    done
    py "
a, b = pdh5.series('mesh-r.h5'), pdh5.series('lattice-r.h5')
ea, eb = a['elastic_energy'][1], b['elastic_energy'][1]
assert ea > 0 and abs(ea - eb) < 0.03 * eb, (ea, eb)
fa, fb = a['right.fx'][1], b['right.fx'][1]
assert abs(fa - fb) < 0.03 * fb, (fa, fb)
with h5py.File('mesh-b.h5') as f:
    assert f['particles'].attrs['dimension'] == 2
"
}
