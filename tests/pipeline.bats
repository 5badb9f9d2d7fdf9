#!/usr/bin/env bats
# The programs together: pipes through stdin and stdout give the same
# results as files, ids survive every stage, the history records every
# command, a failing stage leaves no half file, and a Makefile sweep works.

load test_helper

setup() {
    cd "$BATS_TEST_TMPDIR"
}

LATTICE=(--spacing 0.001 --density 2200 --box 0,0.01,0,0.01,0,0.01)

@test "lattice | bonds | run | damage through pipes equals the same through files" {
    pd-lattice -q "${LATTICE[@]}" -o - |
        pd-bonds -q --horizon "$HORIZON" - -o - |
        pd-run -q "${RUN_OPTS[@]}" --steps 50 --every 10 - -o - |
        pd-damage - > piped.h5 2> piped.table
    make_run
    pd-damage run.h5 -o files.h5 > files.table
    run -0 h5_same files.h5 piped.h5 history
    cmp files.table piped.table
    run -0 py "
f = h5py.File(sys.argv[1], 'r')
assert all('damage' in g for g in f['frames'].values())
assert f['frames/00000050/damage'][:].max() > 0
print('ok')" piped.h5
    assert_output ok
}

@test "the history lists every program in order" {
    make_run
    pd-damage run.h5 -o out.h5 > /dev/null
    run -0 py "
h = h5py.File(sys.argv[1], 'r').attrs['history']
print(h.decode() if isinstance(h, bytes) else h)" out.h5
    assert_equal "${#lines[@]}" 4
    assert_line --index 0 --regexp '^pd-lattice '
    assert_line --index 1 --regexp '^pd-bonds '
    assert_line --index 2 --regexp '^pd-run '
    assert_line --index 3 --regexp '^pd-damage '
}

@test "ids stay with their particles from the lattice to the damage" {
    make_run
    pd-damage run.h5 > /dev/null
    run -0 py "
a, b = h5py.File(sys.argv[1], 'r'), h5py.File(sys.argv[2], 'r')
ida, idb = a['particles/id'][:], b['particles/id'][:]
assert np.array_equal(np.sort(idb), ida)
xa = a['particles/position'][:]
xb = b['particles/position'][:]
assert np.array_equal(xb, xa[idb - 1]), 'an id changed particle'
print('ok')" lattice.h5 run.h5
    assert_output ok
}

@test "a failing stage stops the pipe with one error and no output file" {
    run -1 --separate-stderr bash -o pipefail -c "
        pd-lattice -q ${LATTICE[*]} -o - |
        pd-bonds -q --horizon 0.0005 - -o - |
        pd-run -q --bulk-modulus $BULK --steps 5 - -o run.h5"
    # pd-bonds says why; pd-run then finds nothing on stdin
    assert_regex "${stderr_lines[0]}" '^pd-bonds: error: horizon .* below the lattice spacing'
    assert_regex "${stderr_lines[1]}" "^pd-run: error: .*stdin.*empty"
    assert_equal "${#stderr_lines[@]}" 2
    [ ! -e run.h5 ]
    assert_no_temp .
}

@test "a Makefile sweep: scene file plus command-line override, make -j2" {
    command -v make || skip "make is not installed"
    cat > impact.scene <<EOF
bulk-modulus $BULK
failure 0.0005,0.25
contact
indenter sphere,0.005,0.005,0.0125,0.003,1e17,0,0,-100
allow-overlap
steps 20
every 0
EOF
    cat > Makefile <<'EOF'
DTS = 5e-8 1e-7
all: $(DTS:%=run-%.h5)
lattice.h5:
	pd-lattice -q --spacing 0.001 --density 2200 --box 0,0.01,0,0.01,0,0.01 -o $@
model.h5: lattice.h5
	pd-bonds -q --horizon 0.0030001 $< -o $@
run-%.h5: model.h5 impact.scene
	pd-run -q --scene impact.scene --dt $* $< -o $@
	pd-damage $@ > $*.table
EOF
    run -0 make -j2
    run -0 py "
for name in ('5e-8', '1e-7'):
    dt = float(name)
    f = h5py.File('run-' + name + '.h5', 'r')
    s = f['scene'].attrs
    assert s['dt'] == dt, (s['dt'], dt)
    assert int(s['steps']) == 20
    e = s['effects']
    assert 'contact' in (e.decode() if isinstance(e, bytes) else e)
    g = f['frames/00000020']
    assert g.attrs['time'] == 20 * dt
    assert 'damage' in g
print('ok')"
    assert_output ok
    # nothing left to do, and no temporaries
    run -0 make -q
    assert_no_temp .
}

@test "the seed cylinder lattice pipes into pd-bonds with 3.0001 spacings" {
    # a thin slice of the seed target keeps the test quick
    pd-lattice -q --spacing 0.0005 --cylinder y,0,0,0.005,-0.003,0 --density 2200 -o - |
        pd-bonds --horizon 0.0015001 - -o m.h5 2> log
    run -0 cat log
    assert_equal "${#lines[@]}" 2
    assert_line --index 0 --regexp '^pd-bonds: [0-9]+ particles, [0-9]+ bonds \([0-9.]+ per particle, [0-9]+ to 122\)$'
    # a cylinder cut from the lattice: its families are the lattice stencil
    assert_line --index 1 "pd-bonds: stored as a lattice stencil of 122 offsets"
    run -0 py "
f = h5py.File(sys.argv[1], 'r')
assert pdh5.form(f) == 'stencil'
print(np.diff(pdh5.bonds(f)[0]).max())" m.h5
    assert_output 122
}
