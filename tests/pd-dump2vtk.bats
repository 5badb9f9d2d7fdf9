#!/usr/bin/env bats
# pd-dump2vtk: every frame of a run as a .vtu readable by meshio, with points
# at reference + displacement, the frame's fields, damage equal to an
# independent recomputation from /bonds, and a .pvd listing every frame with
# its time.

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
sets = tree.getroot().findall("./Collection/DataSet")
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

@test "the .vtu files carry binary appended data, vertex cells, UInt64 headers" {
    pd-dump2vtk -q "$RUN" -o out
    run -0 "$PY" - out/run_00000100.vtu <<'EOF'
import sys, struct
import xml.etree.ElementTree as ET
raw = open(sys.argv[1], "rb").read()
# the XML before the binary block, closed, is the whole header
root = ET.fromstring(raw[:raw.index(b"<AppendedData")].decode() + "</VTKFile>")
assert root.get("type") == "UnstructuredGrid"
assert root.get("header_type") == "UInt64" and root.get("byte_order") == "LittleEndian"
app = raw.index(b"_", raw.index(b'<AppendedData encoding="raw">')) + 1
piece = root.find("./UnstructuredGrid/Piece")
n = int(piece.get("NumberOfPoints"))
assert int(piece.get("NumberOfCells")) == n
sizes = {"Float64": 8, "Int64": 8, "Int32": 4, "UInt8": 1}
for a in root.iter("DataArray"):
    assert a.get("format") == "appended"
    at = app + int(a.get("offset"))
    nbytes = struct.unpack("<Q", raw[at:at + 8])[0]
    comp = int(a.get("NumberOfComponents", "1"))
    assert nbytes == n * comp * sizes[a.get("type")], a.get("Name")
    body = raw[at + 8:at + 8 + nbytes]
    if a.get("Name") == "types":
        assert set(body) == {1}
    if a.get("Name") == "connectivity":
        assert list(struct.unpack("<%dq" % n, body)) == list(range(n))
    if a.get("Name") == "offsets":
        assert list(struct.unpack("<%dq" % n, body)) == list(range(1, n + 1))
print("ok")
EOF
    assert_output "ok"
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
    assert_output "$(printf 'run.pvd\n'; printf 'run_%08d.vtu\n' 0 25 50 75 100)"
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
