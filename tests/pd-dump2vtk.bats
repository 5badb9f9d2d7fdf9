#!/usr/bin/env bats
# pd-dump2vtk: every frame of a run as a .vtu readable by meshio and by
# tests/vtu.py (zlib-compressed unless --compress 0), with points at
# reference + displacement, the frame's fields, damage equal to an
# independent recomputation from /bonds, the indenter's and the projectile's
# spheres, and a .pvd listing every frame with its time.  ParaView's own
# reading of them is in paraview.bats.

load test_helper

# One run for the whole file: the make_run block (a sphere pressed into a
# 10 mm cube) over 100 steps, frames at 0, 25, 50, 75, 100, bonds broken in
# the last ones.
setup_file() {
    make_run "$BATS_FILE_TMPDIR" --steps 100 --every 25
}

setup() {
    RUN=$BATS_FILE_TMPDIR/run.h5
    MODEL=$BATS_FILE_TMPDIR/model.h5
    cd "$BATS_TEST_TMPDIR"
}

# check_vtk RUN DIR NAME [field]: the properties every dump must have.
# With `field`, damage must equal the frames' stored `damage` field;
# otherwise it must equal a recomputation from /bonds and the frame state.
# Prints "ok NFRAMES".
check_vtk() {
    "$PY" - "$@" <<'EOF'
import os, sys
import xml.etree.ElementTree as ET
import h5py, meshio, numpy as np, pdh5

run, out, name = sys.argv[1:4]
use_field = len(sys.argv) > 4 and sys.argv[4] == "field"
f = h5py.File(run, "r")
x = f["particles/position"][:]
n = x.shape[0]
off, nb = pdh5.bonds(f)[:2]
vol = f["particles/volume"][:]
row = np.repeat(np.arange(n), np.diff(off))

def damage_from_bonds(state):
    # bond b is intact when bit b%8 of byte b//8 is set (seed 004's mu);
    # damage = 1 - sum V_j intact / sum V_j of the family (seed 000 eq. 10)
    b = np.arange(nb.size)
    intact = (state[b // 8] >> (b % 8)) & 1
    tot = np.bincount(row, vol[nb], minlength=n)
    kept = np.bincount(row, vol[nb] * intact, minlength=n)
    return np.where(tot > 0, 1.0 - kept / np.where(tot > 0, tot, 1.0), 0.0)

frames = f["frames"]
assert len(frames) >= 2, "fixture should have several frames"
tree = ET.parse(os.path.join(out, name + ".pvd"))
assert tree.getroot().get("type") == "Collection"
sets = [s for s in tree.getroot().findall("./Collection/DataSet") if s.get("part") == "0"]
assert len(sets) == len(frames), (len(sets), len(frames))
listed = {s.get("file"): float(s.get("timestep")) for s in sets}
broken_seen = False
for key in frames:
    g = frames[key]
    step, time = int(g.attrs["step"]), float(g.attrs["time"])
    file = "%s_%08d.vtu" % (name, step)
    assert file in listed, (file, listed)
    assert listed[file] == time, (file, listed[file], time)
    m = meshio.read(os.path.join(out, file))
    assert m.points.shape == (n, 3), m.points.shape
    assert sum(len(c.data) for c in m.cells if c.type == "vertex") == n
    u = g["displacement"][:]
    assert np.abs(m.points - (x + u)).max() <= 1e-12
    pdata = m.point_data
    assert np.array_equal(pdata["displacement"], u)
    assert np.array_equal(pdata["velocity"], g["velocity"][:])
    assert np.array_equal(pdata["material"].ravel(), f["particles/material"][:])
    assert np.array_equal(pdata["id"].ravel(), f["particles/id"][:])
    d = pdata["damage"].ravel()
    assert d.shape == (n,)
    assert np.all(d >= 0) and np.all(d <= 1), (d.min(), d.max())
    want = g["damage"][:] if use_field else damage_from_bonds(g["state"][:])
    assert np.abs(d - want).max() <= 1e-12, np.abs(d - want).max()
    broken_seen |= d.max() > 0
assert use_field or broken_seen, "fixture should break bonds"
print("ok", len(frames))
EOF
}

@test "--help prints the usage on stdout and exits 0" {
    run -0 pd-dump2vtk --help
    assert_line --index 0 "Usage: pd-dump2vtk [OPTION]... RUN.h5 -o DIR"
    run -0 pd-dump2vtk --version
    assert_output --regexp '^pd-dump2vtk \(pd\) [0-9]'
}

@test "usage errors exit 2 with one error line" {
    expect_usage_error "missing -o DIR" pd-dump2vtk "$RUN"
    expect_usage_error "missing RUN.h5" pd-dump2vtk -o out
    expect_usage_error "exactly one RUN.h5" pd-dump2vtk "$RUN" "$RUN" -o out
    expect_usage_error "--name" pd-dump2vtk --name a/b "$RUN" -o out
    expect_usage_error "--name" pd-dump2vtk --name "" "$RUN" -o out
    run -2 pd-dump2vtk --bogus "$RUN" -o out
    [ ! -e out ]
}

@test "every frame becomes a .vtu with current positions, fields and recomputed damage" {
    run -0 --separate-stderr pd-dump2vtk "$RUN" -o out
    assert_equal "${#stderr_lines[@]}" 1
    assert_regex "${stderr_lines[0]}" '^pd-dump2vtk: 5 frames of [0-9]+ particles'
    assert_output ""
    run -0 check_vtk "$RUN" out run
    assert_output "ok 5"
}

@test "the .vtu files carry zlib-compressed appended data, vertex cells, UInt64 headers" {
    # 32 x 16 x 16 = 8192 particles: Points fill three 64 KiB blocks
    # exactly, damage one; material and types end in a partial block
    pd-lattice -q --spacing 0.001 --box 0,0.0315,0,0.0155,0,0.0155 --density 2200 -o big.h5
    pd-bonds -q --horizon "$HORIZON" big.h5 -o bigm.h5
    pd-run -q "${RUN_OPTS[@]}" --steps 20 --every 20 bigm.h5 -o big.h5
    pd-dump2vtk -q big.h5 -o out
    pd-dump2vtk -q --compress 0 big.h5 -o raw
    pd-dump2vtk -q --compress 9 big.h5 -o best
    run -0 "$PY" - out/big_00000020.vtu raw/big_00000020.vtu best/big_00000020.vtu <<'EOF'
import sys, numpy as np, vtu
z, r, b = (vtu.read(p) for p in sys.argv[1:4])
assert z.compressed and b.compressed and not r.compressed
n = len(r.points)
assert n == 8192, n
# the arrays in 64 KiB blocks, each compressed alone
for name, blocks in (("Points", 3), ("damage", 1), ("material", 1), ("types", 1)):
    assert z.blocks[name] == blocks, (name, z.blocks[name])
assert r.point_data["damage"].max() > 0
conn, off, types = z.cells
assert np.array_equal(conn, np.arange(n)) and np.array_equal(off, np.arange(1, n + 1))
assert np.all(types == 1)
# compressed at any level, every array is the raw one, bit for bit
for g in (z, b):
    assert np.array_equal(g.points, r.points)
    assert list(g.point_data) == list(r.point_data)
    for k in r.point_data:
        assert np.array_equal(g.point_data[k], r.point_data[k]), k
    for c, d in zip(g.cells, r.cells):
        assert np.array_equal(c, d)
print("ok")
EOF
    assert_output "ok"
    # smaller files; a higher level, no larger ones
    z=$(stat -c %s out/big_00000020.vtu) r=$(stat -c %s raw/big_00000020.vtu)
    b=$(stat -c %s best/big_00000020.vtu)
    (( z < r * 3 / 4 && b <= z )) || fail "sizes: level 1 $z, raw $r, level 9 $b"
}

@test "--compress takes a zlib level 0 to 9; anything else is a usage error" {
    for bad in -1 10 1.5 x ""; do
        expect_usage_error "--compress needs a zlib level 0 to 9" pd-dump2vtk --compress "$bad" "$RUN" -o out
    done
    [ ! -e out ]
}

@test "the compressed files do not depend on the thread count" {
    OMP_NUM_THREADS=1 pd-dump2vtk -q "$RUN" -o one
    OMP_NUM_THREADS=2 pd-dump2vtk -q "$RUN" -o two
    for f in one/*; do
        cmp "$f" "two/${f#one/}"
    done
    [ "$(ls one | wc -l)" -eq 11 ]
}

# check_spheres RUN DIR NAME KIND...: the .pvd lists, at every frame's time,
# the particles as part 0 and then one sphere a KIND (indenter, projectile)
# as parts 1, 2, named; each sphere's .vtu is a closed surface of triangles
# with outward normals around the centre the run puts it at (the indenter
# at its /scene centre + step dt v, the projectile at the frame's
# projectile_position), its radius, and its velocity as point data.
check_spheres() {
    "$PY" - "$@" <<'EOF'
import os, sys
import xml.etree.ElementTree as ET
import h5py, numpy as np, vtu
run, out, name, kinds = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]
f = h5py.File(run, "r")
sc = f["scene"].attrs
entries = ET.parse(os.path.join(out, name + ".pvd")).getroot().findall("./Collection/DataSet")
assert len(entries) == len(f["frames"]) * (1 + len(kinds)), len(entries)
for g in f["frames"].values():
    step, t = int(g.attrs["step"]), float(g.attrs["time"])
    mine = [e for e in entries if float(e.get("timestep")) == t]
    assert [int(e.get("part")) for e in mine] == list(range(1 + len(kinds))), mine
    assert [e.get("name") for e in mine] == ["particles"] + kinds
    assert mine[0].get("file") == "%s_%08d.vtu" % (name, step)
    for e, kind in zip(mine[1:], kinds):
        assert e.get("file") == "%s_%s_%08d.vtu" % (name, kind, step), e.get("file")
        s = vtu.read(os.path.join(out, e.get("file")))
        assert s.compressed
        if kind == "indenter":
            row = sc["indenter"]
            c = row[:3] + (step * sc["dt"]) * row[5:8]
            R, v = row[3], row[5:8]
        else:
            c, R = g.attrs["projectile_position"], sc["projectile"][3]
            v = g.attrs["projectile_velocity"]
        conn, off, types = s.cells
        assert np.all(types == 5) and np.array_equal(off, 3 * np.arange(1, len(types) + 1))
        tri = s.points[conn.reshape(-1, 3)]
        r = np.linalg.norm(s.points - c, axis=1)
        assert np.allclose(r, R, rtol=1e-12), (r.min(), r.max(), R)
        # closed: every edge in exactly two triangles, once each way
        t3 = conn.reshape(-1, 3)
        edges = np.concatenate([t3[:, [0, 1]], t3[:, [1, 2]], t3[:, [2, 0]]])
        fwd = {tuple(x) for x in edges}
        assert len(fwd) == len(edges) and all((b, a) in fwd for a, b in fwd)
        # outward: the enclosed volume (divergence theorem) is positive and
        # near 4/3 pi R^3 (a polyhedron inscribed in the sphere)
        vol = np.einsum("ij,ij->i", tri[:, 0] - c, np.cross(tri[:, 1] - c, tri[:, 2] - c)).sum() / 6
        assert 0.97 < vol / (4 / 3 * np.pi * R**3) < 1.0, vol / (4 / 3 * np.pi * R**3)
        assert np.array_equal(s.point_data["velocity"], np.tile(v, (len(s.points), 1)))
print("ok", len(f["frames"]))
EOF
}

@test "a run with an indenter gets the indenter's sphere at every frame, part 1 of the .pvd" {
    run -0 --separate-stderr pd-dump2vtk "$RUN" -o out
    assert_regex "${stderr_lines[0]}" '^pd-dump2vtk: 5 frames of [0-9]+ particles, 5 indenter spheres'
    run -0 check_spheres "$RUN" out run indenter
    assert_output "ok 5"
    run -0 check_vtk "$RUN" out run
}

@test "a run with a projectile gets its sphere where each frame puts it" {
    make_block
    pd-run -q --bulk-modulus "$BULK" --projectile sphere,0.005,0.005,0.0135,0.003,0.002,0,0,-60 \
        --steps 200 --every 50 model.h5 -o p.h5
    pd-dump2vtk -q p.h5 -o out
    run -0 check_spheres p.h5 out p projectile
    assert_output "ok 5"
    # it moved: down, then pushed back by the body
    run -0 py "
z = [g.attrs['projectile_position'][2] for g in h5py.File(sys.argv[1])['frames'].values()]
assert z[1] < z[0] and len(set(z)) == len(z), z
print('ok')" p.h5
}

@test "a run with both gets both, indenter first" {
    make_block
    pd-run -q --bulk-modulus "$BULK" --projectile sphere,0.005,0.005,0.0135,0.003,0.002,0,0,-60 \
        --indenter sphere,0.005,0.005,-0.0035,0.003,1e17,0,0,50 \
        --steps 100 --every 50 model.h5 -o both.h5
    pd-dump2vtk -q both.h5 -o out
    run -0 check_spheres both.h5 out both indenter projectile
    assert_output "ok 3"
}

@test "damage comes from the frame's damage field when pd-damage stored one" {
    pd-damage "$RUN" -o with.h5 >/dev/null
    # replace the stored field by values no bond state gives: the dump must
    # show them, which proves it read the field rather than recomputing
    "$PY" - with.h5 <<'EOF'
import sys, h5py, numpy as np
with h5py.File(sys.argv[1], "r+") as f:
    for k, g in f["frames"].items():
        n = g["damage"].shape[0]
        g["damage"][...] = (np.arange(n) % 7) / 7.0 * 0.999 + int(k) * 1e-6
EOF
    run -0 pd-dump2vtk -q with.h5 -o out
    assert_output ""
    run -0 check_vtk with.h5 out with field
    assert_output "ok 5"
}

@test "stdin is read with '-' and named run; --name renames; DIR is created with parents" {
    run -0 --separate-stderr pd-dump2vtk -q - -o a/b/c < "$RUN"
    assert_equal "${#stderr_lines[@]}" 0
    [ -f a/b/c/run.pvd ]
    run -0 check_vtk "$RUN" a/b/c run
    cp "$RUN" impact.h5
    run -0 pd-dump2vtk -q impact.h5 -o d
    [ -f d/impact.pvd ] && [ -f d/impact_00000000.vtu ]
    run -0 pd-dump2vtk -q impact.h5 --name seed -o d
    [ -f d/seed.pvd ] && [ -f d/seed_00000100.vtu ]
    run -0 check_vtk "$RUN" d seed
}

@test "a rerun into an existing directory replaces the files and leaves no temporaries" {
    pd-dump2vtk -q "$RUN" -o out
    pd-dump2vtk -q "$RUN" -o out
    run -0 check_vtk "$RUN" out run
    assert_no_temp out
    run ls -A out
    assert_output "$(printf 'run.pvd\n'; printf 'run_%08d.vtu\n' 0 25 50 75 100
                     printf 'run_indenter_%08d.vtu\n' 0 25 50 75 100)"
}

@test "a missing input is a runtime error: exit 1, one line, no directory made" {
    expect_runtime_error "nosuch\.h5" pd-dump2vtk nosuch.h5 -o out
    [ ! -e out ]
}

@test "inputs that are not pd-h5 runs are runtime errors with one line" {
    make_bad_inputs
    for bad in empty.h5 text.h5 adir plain.h5; do
        expect_runtime_error "$bad" pd-dump2vtk "$bad" -o out
    done
    run -1 --separate-stderr pd-dump2vtk - -o out < text.h5
    assert_one_error '^pd-dump2vtk: error: '
    [ ! -e out ]
}

@test "a model without frames is a runtime error with one line" {
    expect_runtime_error "frames" pd-dump2vtk "$MODEL" -o out
    [ ! -e out ]
}

@test "-o naming a regular file is a runtime error with one line, the file untouched" {
    printf 'keep\n' > plain
    expect_runtime_error "plain" pd-dump2vtk "$RUN" -o plain
    assert_equal "$(cat plain)" "keep"
    expect_runtime_error "plain" pd-dump2vtk "$RUN" -o plain/sub
}

@test "a frame without bond state nor damage field is an error, not a silent zero" {
    cp "$RUN" broken.h5
    "$PY" - broken.h5 <<'EOF'
import sys, h5py
with h5py.File(sys.argv[1], "r+") as f:
    del f["frames/00000050/state"]
    del f["frames/00000050/damage"]
EOF
    expect_runtime_error "state" pd-dump2vtk broken.h5 -o out
    [ ! -e out/broken.pvd ]
}

# ------------------------------------------------------------ pre-cracks

@test "a run without a pre-crack has no damage_run field" {
    pd-dump2vtk -q "$RUN" -o out
    run -0 "$PY" -c "
import sys, meshio
m = meshio.read(sys.argv[1])
assert 'damage' in m.point_data and 'damage_run' not in m.point_data, list(m.point_data)
print('ok')" out/run_00000100.vtu
    assert_output ok
}

# The pre-cracked run: the make_block lattice with the plane x = 4.5 mm over
# y in [-1, 4.4] mm, pressed by the make_run sphere for 50 steps.
make_cracked_run() {
    make_block || return 1
    pd-bonds -q --horizon "$HORIZON" --crack rect,0.0045,-0.001,-0.001,0,0.0054,0,0,0,0.012 \
        lattice.h5 -o model.h5 && make_run
}

# check_damage_run RUN DIR NAME: every .vtu has damage (pre-crack counted)
# and damage_run (pre-cracked bonds out of both sums), both equal to a
# recomputation here; damage_run is 0 at step 0 where damage is not.
check_damage_run() {
    "$PY" - "$@" <<'EOF2'
import os, sys
import h5py, meshio, numpy as np, pdh5
run, out, name = sys.argv[1:4]
f = h5py.File(run, "r")
vol = f["particles/volume"][:]
off, nb = pdh5.bonds(f)[:2]
n, count = vol.size, nb.size
row = np.repeat(np.arange(n), np.diff(off))
pre = np.unpackbits(f["bonds/precrack"][:], bitorder="little")[:count].astype(bool)
def damage(mu, use):
    tot = np.bincount(row, vol[nb] * use, minlength=n)
    kept = np.bincount(row, vol[nb] * (mu & use), minlength=n)
    return np.where(tot > 0, 1.0 - kept / np.where(tot > 0, tot, 1.0), 0.0)
for g in f["frames"].values():
    step = int(g.attrs["step"])
    m = meshio.read(os.path.join(out, "%s_%08d.vtu" % (name, step)))
    mu = np.unpackbits(g["state"][:], bitorder="little")[:count].astype(bool)
    d, r = m.point_data["damage"].ravel(), m.point_data["damage_run"].ravel()
    assert np.abs(d - damage(mu, np.ones(count, bool))).max() <= 1e-12
    assert np.abs(r - damage(mu, ~pre)).max() <= 1e-12
    if step == 0:
        assert d.max() > 0 and np.all(r == 0), (d.max(), r.max())
    assert np.all(r <= 1) and np.all(r >= 0)
print("ok", len(f["frames"]))
EOF2
}

@test "a pre-cracked run gets damage_run, the damage without the pre-crack" {
    make_cracked_run
    run -0 pd-dump2vtk -q run.h5 -o out
    run -0 check_damage_run run.h5 out run
    assert_output "ok 6"
    run -0 check_vtk run.h5 out run
    assert_output "ok 6"
}

@test "damage_run comes from the frame's damage_run field when pd-damage stored one" {
    make_cracked_run
    pd-damage -q --no-precrack run.h5
    run -0 pd-dump2vtk -q run.h5 -o out
    run -0 check_damage_run run.h5 out run
    assert_output "ok 6"
    # values no bond state gives: the dump shows them
    "$PY" - run.h5 <<'EOF2'
import sys, h5py, numpy as np
with h5py.File(sys.argv[1], "r+") as f:
    for k, g in f["frames"].items():
        g["damage_run"][...] = 0.5 + int(k) * 1e-6
EOF2
    pd-dump2vtk -q run.h5 -o out2
    run -0 "$PY" -c "
import sys, h5py, meshio, numpy as np
f = h5py.File(sys.argv[1], 'r')
for k, g in f['frames'].items():
    m = meshio.read('%s/run_%08d.vtu' % (sys.argv[2], g.attrs['step']))
    assert np.all(m.point_data['damage_run'].ravel() == 0.5 + int(k) * 1e-6)
print('ok')" run.h5 out2
    assert_output ok
}

# check_xdmf RUN XDMF H5REF: the XDMF file describes RUN's complete frames
# in step order with their times, each DataItem naming a dataset H5REF:PATH
# that RUN has, with its shape and number type; the geometry the sum of the
# reference positions and the frame's displacement.  Prints "ok NFRAMES".
check_xdmf() {
    "$PY" - "$@" <<'EOF2'
import sys
import xml.etree.ElementTree as ET
import h5py

run, xdmf, ref = sys.argv[1:4]
f = h5py.File(run, "r")
n = len(f["particles/id"])
frames = sorted((g for g in f["frames"].values() if g.attrs["complete"] == 1),
                key=lambda g: g.attrs["step"])
root = ET.parse(xdmf).getroot()
assert root.tag == "Xdmf" and root.get("Version") == "2.0", root.attrib
coll = root.find("./Domain/Grid")
assert coll.get("GridType") == "Collection" and coll.get("CollectionType") == "Temporal"
grids = coll.findall("./Grid")
assert len(grids) == len(frames), (len(grids), len(frames))
kinds = {"f": "Float", "i": "Int", "u": "UInt"}
for g, grid in zip(frames, grids):
    assert float(grid.find("Time").get("Value")) == float(g.attrs["time"]), g.name
    top = grid.find("Topology")
    assert top.get("TopologyType") == "Polyvertex" and int(top.get("NumberOfElements")) == n
    fn = grid.find("./Geometry/DataItem")
    assert fn.get("ItemType") == "Function" and fn.get("Function") == "$0 + $1"
    items = grid.findall(".//DataItem[@Format='HDF']")
    paths = []
    for it in items:
        file, path = it.text.split(":")
        assert file == ref, (file, ref)
        d = f[path]
        assert tuple(int(v) for v in it.get("Dimensions").split()) == d.shape, (path, d.shape)
        assert it.get("NumberType") == kinds[d.dtype.kind] and int(it.get("Precision")) == d.dtype.itemsize, path
        paths.append(path)
    assert paths[:2] == ["/particles/position", g.name + "/displacement"], paths[:2]
    names = [a.get("Name") for a in grid.findall("Attribute")]
    want = [k for k in ("displacement", "velocity", "damage", "damage_run",
                        "strain_energy_density", "von_mises", "stress") if k in g]
    assert names == want + ["material", "id"], names
    for a in grid.findall("Attribute"):
        p = a.find("DataItem").text.split(":")[1]
        assert p.rsplit("/", 1)[1] == a.get("Name"), (p, a.get("Name"))
print("ok", len(frames))
EOF2
}

@test "--xdmf describes every frame in place: no copy, each array a dataset of the run file" {
    cp "$RUN" run.h5
    run -0 --separate-stderr pd-dump2vtk --xdmf run.h5
    assert_equal "${stderr_lines[0]}" "pd-dump2vtk: 5 frames of $(h5ls run.h5/particles/id | sed -n 's/.*{\([0-9]*\)}.*/\1/p') particles described in place, run.xdmf (ParaView: XDMF Reader)"
    run -0 check_xdmf run.h5 run.xdmf run.h5
    assert_output "ok 5"
    # the run file is only read
    cmp run.h5 "$RUN"
    # elsewhere, the XDMF names the run file by its absolute path
    mkdir -p sub
    pd-dump2vtk -q --xdmf run.h5 -o sub/r.xdmf
    run -0 check_xdmf run.h5 sub/r.xdmf "$PWD/run.h5"
    assert_output "ok 5"
    # the optional fields go along
    pd-run -q "${RUN_OPTS[@]}" --steps 20 --every 10 --fields energy,stress "$MODEL" -o fields.h5
    pd-dump2vtk -q --xdmf fields.h5
    run -0 check_xdmf fields.h5 fields.xdmf fields.h5
    assert_output "ok 3"
    grep -q 'Name="stress" AttributeType="Tensor"' fields.xdmf
}

@test "--xdmf of a pre-cracked run takes its damage_run where pd-damage stored it" {
    make_cracked_run
    pd-damage -q --no-precrack run.h5
    pd-dump2vtk -q --xdmf run.h5
    run -0 check_xdmf run.h5 run.xdmf run.h5
    assert_output "ok 6"
    grep -q 'Name="damage_run"' run.xdmf
}

@test "--xdmf: usage errors exit 2; a missing folder or a run without frames is one error line and no file" {
    expect_usage_error "give its name" pd-dump2vtk --xdmf - -o x.xdmf
    expect_usage_error "no --name or --compress" pd-dump2vtk --xdmf --compress 3 "$RUN"
    expect_usage_error "no --name or --compress" pd-dump2vtk --xdmf --name a "$RUN"
    expect_usage_error "-o needs a file name" pd-dump2vtk --xdmf "$RUN" -o ""
    cp "$RUN" run.h5
    run -1 --separate-stderr pd-dump2vtk --xdmf run.h5 -o nowhere/r.xdmf
    assert_equal "${#stderr_lines[@]}" 1
    assert_regex "${stderr_lines[0]}" "^pd-dump2vtk: error: cannot write 'nowhere/r.xdmf'"
    [ ! -e nowhere ]
    run -1 --separate-stderr pd-dump2vtk --xdmf "$MODEL" -o m.xdmf
    assert_equal "${#stderr_lines[@]}" 1
    assert_regex "${stderr_lines[0]}" "^pd-dump2vtk: error: .*has no /frames"
    [ ! -e m.xdmf ]
    [ -z "$(find . -name '.*.tmp.*')" ]
}
