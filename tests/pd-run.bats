#!/usr/bin/env bats
# pd-run: frames when asked for, the resolved scene in /scene, effects that
# exist only when declared, the stable step of seed 004 eq. 46, bonds that
# break only with --failure and never heal, results independent of the
# thread count, and the errors of every bad input.

load test_helper

setup() {
    cd "$BATS_TEST_TMPDIR"
}

# frames RUN.h5: "NAME STEP TIME" per frame, in step order, the time to 6
# digits.
frames() {
    py "
f = h5py.File(sys.argv[1], 'r')
for k in sorted(f['frames'], key=lambda k: int(f['frames'][k].attrs['step'])):
    a = f['frames'][k].attrs
    print(k, int(a['step']), '%.6g' % a['time'])" "$1"
}

# scene_attr RUN.h5 NAME: an attribute of /scene.
scene_attr() {
    py "
v = h5py.File(sys.argv[1], 'r')['scene'].attrs[sys.argv[2]]
print(v.decode() if isinstance(v, bytes) else repr(v) if isinstance(v, float) else v)" "$1" "$2"
}

# ------------------------------------------------------------ the interface

@test "--help prints Usage on stdout and exits 0" {
    run -0 --separate-stderr pd-run --help
    assert_line --index 0 --regexp '^Usage: pd-run '
    assert_equal "$stderr" ""
}

@test "--version prints the program and version" {
    run -0 --separate-stderr pd-run --version
    assert_output --regexp '^pd-run \(pd\) [0-9]+\.[0-9]+'
}

@test "an unknown option is a usage error naming the option" {
    make_block
    run -2 --separate-stderr pd-run --bogus --c 1e21 --steps 1 model.h5 -o r.h5
    assert_one_error "^pd-run: error: .*--bogus"
    [ ! -e r.h5 ]
}

@test "--steps or --time is required" {
    make_block
    expect_usage_error "--steps or --time" pd-run --c 1e21 model.h5 -o r.h5
}

@test "the stiffness is required: --c or --bulk-modulus" {
    make_block
    expect_usage_error "--c or --bulk-modulus" pd-run --steps 1 model.h5 -o r.h5
    [ ! -e r.h5 ]
}

@test "of --c and --bulk-modulus the last one wins" {
    make_block
    pd-run -q --c 1e21 --bulk-modulus "$BULK" --steps 0 model.h5 -o k.h5
    pd-run -q --bulk-modulus "$BULK" --c 1e21 --steps 0 model.h5 -o c.h5
    run -0 py "
f = h5py.File(sys.argv[1], 'r')
K, delta = float(sys.argv[3]), float(f['bonds'].attrs['horizon'])
ck = float(f['scene'].attrs['c'])
assert abs(ck - 18 * K / (np.pi * delta**4)) <= 1e-14 * ck, ck
assert float(h5py.File(sys.argv[2], 'r')['scene'].attrs['c']) == 1e21
print('ok')" k.h5 c.h5 "$BULK"
    assert_output ok
}

@test "INPUT is required, and only one" {
    make_block
    expect_usage_error "INPUT" pd-run --c 1e21 --steps 1 -o r.h5
    expect_usage_error "INPUT" pd-run --c 1e21 --steps 1 model.h5 model.h5 -o r.h5
}

@test "an unknown --model is a usage error" {
    make_block
    expect_usage_error "model.*lps" pd-run --model lps --c 1e21 --steps 1 model.h5 -o r.h5
}

bad_dt() {
    make_block
    expect_usage_error "--dt.*'$1'" pd-run --c 1e21 --dt "$1" --steps 1 model.h5 -o r.h5
    [ ! -e r.h5 ]
}
@test "--dt 0 is a usage error" { bad_dt 0; }
@test "--dt -1e-8 is a usage error" { bad_dt -1e-8; }
@test "--dt nan is a usage error" { bad_dt nan; }
@test "--dt abc is a usage error" { bad_dt abc; }

bad_steps() {
    make_block
    expect_usage_error "--steps.*'$1'" pd-run --c 1e21 --steps "$1" model.h5 -o r.h5
    [ ! -e r.h5 ]
}
@test "--steps -1 is a usage error" { bad_steps -1; }
@test "--steps nan is a usage error" { bad_steps nan; }
@test "--steps abc is a usage error" { bad_steps abc; }
@test "--steps 2.5 is a usage error" { bad_steps 2.5; }

@test "--steps 0 is accepted: the file holds the initial state as frame 0" {
    make_block
    run -0 pd-run -q --c 1e21 --steps 0 model.h5 -o r.h5
    run -0 frames r.h5
    assert_output "00000000 0 0"
}

@test "other bad numbers are usage errors" {
    make_block
    expect_usage_error "--c" pd-run --c 0 --steps 1 model.h5 -o r.h5
    expect_usage_error "--bulk-modulus" pd-run --bulk-modulus -1 --steps 1 model.h5 -o r.h5
    expect_usage_error "--every" pd-run --c 1e21 --steps 1 --every -1 model.h5 -o r.h5
    expect_usage_error "--threads" pd-run --c 1e21 --steps 1 --threads 0 model.h5 -o r.h5
    expect_usage_error "--safety" pd-run --c 1e21 --steps 1 --safety 1.5 model.h5 -o r.h5
    expect_usage_error "--failure" pd-run --c 1e21 --steps 1 --failure 0.001 model.h5 -o r.h5
    expect_usage_error "--failure" pd-run --c 1e21 --steps 1 --failure -0.001,0.25 model.h5 -o r.h5
    expect_usage_error "--indenter" pd-run --c 1e21 --steps 1 --indenter box,0,0,0,1,1,0,0,0 model.h5 -o r.h5
    expect_usage_error "--indenter" pd-run --c 1e21 --steps 1 --indenter sphere,0,0,0,0,1,0,0,0 model.h5 -o r.h5
    expect_usage_error "--contact-skin" pd-run --c 1e21 --steps 1 --contact --contact-skin abc model.h5 -o r.h5
    [ ! -e r.h5 ]
}

# ------------------------------------------------------------ bad inputs

@test "a missing file is a runtime error naming it" {
    expect_runtime_error "nosuch\.h5" pd-run --c 1e21 --steps 1 nosuch.h5 -o r.h5
    [ ! -e r.h5 ]
}

@test "an empty file is a runtime error" {
    make_bad_inputs
    expect_runtime_error "empty\.h5.*empty" pd-run --c 1e21 --steps 1 empty.h5 -o r.h5
}

@test "a text file is a runtime error: not HDF5" {
    make_bad_inputs
    expect_runtime_error "text\.h5.*not an HDF5 file" pd-run --c 1e21 --steps 1 text.h5 -o r.h5
}

@test "a directory as input is a runtime error" {
    make_bad_inputs
    expect_runtime_error "adir.*directory" pd-run --c 1e21 --steps 1 adir -o r.h5
}

@test "an HDF5 file that is not pd-h5 is a runtime error" {
    make_bad_inputs
    expect_runtime_error "plain\.h5.*not a pd-h5 file" pd-run --c 1e21 --steps 1 plain.h5 -o r.h5
}

@test "an unknown pd_format_version is a runtime error naming the version" {
    make_block
    with_version model.h5 v99.h5 99
    expect_runtime_error "v99\.h5.*version 99" pd-run --c 1e21 --steps 1 v99.h5 -o r.h5
}

@test "a model of format version 1 (bond lists) runs as the stencil model of version 2 does" {
    make_block
    mkdir csr && make_csr_block csr
    with_version csr/model.h5 v1.h5 1
    pd-run -q "${RUN_OPTS[@]}" --steps 20 --every 10 v1.h5 -o r1.h5
    pd-run -q "${RUN_OPTS[@]}" --steps 20 --every 10 model.h5 -o r2.h5
    # the same frames bit for bit, and each run keeps its model's form
    run -0 py "
a, b = h5py.File(sys.argv[1], 'r'), h5py.File(sys.argv[2], 'r')
assert pdh5.form(a) == 'csr' and pdh5.form(b) == 'stencil'
assert sorted(a['frames']) == sorted(b['frames']) and len(a['frames']) == 3
for k in a['frames']:
    for name in ('displacement', 'velocity', 'state'):
        x, y = a['frames'][k][name][()], b['frames'][k][name][()]
        assert x.dtype == y.dtype and x.tobytes() == y.tobytes(), (k, name)
assert a['frames/00000020'].attrs['broken_bonds'] > 0
print('ok')" r1.h5 r2.h5
    assert_output ok
}

@test "a lattice without /bonds (the wrong stage) is a runtime error" {
    make_block
    expect_runtime_error "lattice\.h5.*/bonds.*pd-bonds" pd-run --c 1e21 --steps 1 lattice.h5 -o r.h5
    [ ! -e r.h5 ]
}

@test "/bonds/neighbor out of range is a runtime error" {
    make_csr_block
    py "
with h5py.File(sys.argv[1], 'a') as f: f['bonds/neighbor'][5] = 1331" model.h5
    expect_runtime_error "bond 5 points to particle 1331" pd-run --c 1e21 --steps 1 model.h5 -o r.h5
}

@test "/bonds/offset not monotone is a runtime error" {
    make_csr_block
    py "
with h5py.File(sys.argv[1], 'a') as f:
    o = f['bonds/offset'][:]
    o[10], o[11] = o[11], o[10]
    f['bonds/offset'][...] = o" model.h5
    expect_runtime_error "/bonds/offset" pd-run --c 1e21 --steps 1 model.h5 -o r.h5
}

@test "/bonds/neighbor of the wrong type or length is a runtime error" {
    make_csr_block
    cp model.h5 short.h5
    py "
with h5py.File(sys.argv[1], 'a') as f:
    v = f['bonds/neighbor'][:]
    del f['bonds/neighbor']
    f['bonds/neighbor'] = v.astype(np.float64)
with h5py.File(sys.argv[2], 'a') as f:
    v = f['bonds/neighbor'][:]
    del f['bonds/neighbor']
    f['bonds/neighbor'] = v[:-1]" model.h5 short.h5
    expect_runtime_error "/bonds/neighbor.*float64" pd-run --c 1e21 --steps 1 model.h5 -o r.h5
    expect_runtime_error "/bonds/neighbor" pd-run --c 1e21 --steps 1 short.h5 -o r.h5
}

@test "an asymmetric bond state is a runtime error" {
    make_block
    py "
with h5py.File(sys.argv[1], 'a') as f:
    s = f['bonds/state'][:]
    s[0] &= 0xfe              # break bond 0 on one side only
    f['bonds/state'][...] = s" model.h5
    # the check runs on every thread; the message must still reach stderr
    for t in 1 2; do
        expect_runtime_error "bond 0-[0-9]+ is broken on one side only" \
            pd-run --threads $t --c 1e21 --steps 1 model.h5 -o r.h5
    done
}

@test "a family missing its mirror bond is a runtime error" {
    make_csr_block
    # drop the partner of particle 0's first bond from that partner's family
    py "
import numpy as np
with h5py.File(sys.argv[1], 'a') as f:
    off = f['bonds/offset'][:]; nb = f['bonds/neighbor'][:]
    j = nb[off[0]]
    k = off[j] + int(np.nonzero(nb[off[j]:off[j + 1]] == 0)[0][0])
    nb[k] = nb[k - 1] if k > off[j] else nb[k + 1]
    f['bonds/neighbor'][...] = nb" model.h5
    expect_runtime_error "not (symmetric|sorted)|itself" pd-run --threads 2 --c 1e21 --steps 1 model.h5 -o r.h5
}

@test "two particles with the same id are refused" {
    make_block
    py "
with h5py.File(sys.argv[1], 'a') as f:
    ids = f['particles/id'][:]
    ids[1] = ids[0]
    f['particles/id'][...] = ids" model.h5
    expect_runtime_error "id [0-9]+ appears twice" pd-run --c 1e21 --steps 1 model.h5 -o r.h5
}

@test "a typo suggests the nearest option; a missing or stray value is named" {
    make_block
    expect_usage_error "unknown option '--stps'; did you mean '--steps'\?" \
        pd-run --c 1e21 --stps 1 model.h5 -o r.h5
    expect_usage_error "unknown option '--balnce-limit'; did you mean '--balance-limit'\?" \
        pd-run --c 1e21 --steps 1 --balnce-limit=2 model.h5 -o r.h5
    # far from every option: no guess
    expect_usage_error "unknown option '--frobnicate' \(see" pd-run --frobnicate model.h5
    expect_usage_error "missing value for '--dt'" pd-run --c 1e21 --steps 1 model.h5 --dt
    expect_usage_error "--contact takes no value, not '--contact=yes'" \
        pd-run --c 1e21 --steps 1 --contact=yes model.h5
    # the other programs share it
    expect_usage_error "unknown option '--spcing'; did you mean '--spacing'\?" \
        pd-lattice --spcing 0.001 -o x.h5
    expect_usage_error "unknown option '--horizn'; did you mean '--horizon'\?" \
        pd-bonds --horizn 0.0015 lattice.h5 -o x.h5
    [ ! -e r.h5 ] && [ ! -e x.h5 ]
}

@test "an error from a scene file names FILE:LINE" {
    make_block
    printf 'c 1e21\n# a comment\n\ndt abc\nsteps 5\n' > a.scene
    expect_usage_error "a.scene:4: --dt must be a positive number, not 'abc'" \
        pd-run --scene a.scene model.h5 -o r.h5
    printf 'c 1e21\nstrcit\nsteps 5\n' > b.scene
    expect_usage_error "b.scene:2: unknown option '--strcit'; did you mean '--strict'\?" \
        pd-run --scene b.scene model.h5 -o r.h5
    # an option without its value does not take the command line's next word
    printf 'c 1e21\nsteps\n' > c.scene
    expect_usage_error "c.scene:2: missing value for '--steps'" pd-run --scene c.scene model.h5 -o r.h5
    # the command line's own errors name no line, wherever --scene stands
    printf 'c 1e21\nsteps 5\n' > good.scene
    run -2 --separate-stderr pd-run --dt abc --scene good.scene model.h5 -o r.h5
    assert_one_error "^pd-run: error: --dt must be a positive number, not 'abc'"
    [ ! -e r.h5 ]
}

@test "a missing --scene file is a runtime error naming it" {
    make_block
    expect_runtime_error "nosuch\.scene" pd-run --scene nosuch.scene --c 1e21 --steps 1 model.h5 -o r.h5
    [ ! -e r.h5 ]
}

@test "-o naming a directory fails with one error and leaves no temp file" {
    make_block
    mkdir out
    expect_runtime_error "out.*directory" pd-run --c 1e21 --steps 2 model.h5 -o out
    run -0 ls -A out
    assert_output ""
    assert_no_temp .
}

# ------------------------------------------------------------ time step

@test "the default dt is 0.8 of the stable step of seed 004 eq. 46" {
    make_block
    pd-run -q --bulk-modulus "$BULK" --steps 1 model.h5 -o r.h5
    run -0 py "
f = h5py.File(sys.argv[1], 'r')
p, s = f['particles'], f['scene'].attrs
off, nb, length, nu = pdh5.bonds(f)
rows = np.repeat(np.arange(off.size - 1), np.diff(off))
c = float(s['c'])
# dt < sqrt(2 rho_i / sum_j V_j nu_ij C_ij), C_ij = c / |xi_ij| for PMB
sums = np.bincount(rows, p['volume'][:][nb] * nu * c / length)
stable = np.min(np.sqrt(2 * p['density'][:] / sums))
assert abs(s['dt_stable'] - stable) <= 1e-12 * stable, (s['dt_stable'], stable)
assert abs(s['dt'] - 0.8 * stable) <= 1e-12 * stable, (s['dt'], stable)
assert float(s['safety']) == 0.8
print('ok')" r.h5
    assert_output ok
}

@test "--safety scales the default step" {
    make_block
    pd-run -q --bulk-modulus "$BULK" --steps 1 --safety 0.5 model.h5 -o r.h5
    run -0 py "
s = h5py.File(sys.argv[1], 'r')['scene'].attrs
assert s['dt'] == 0.5 * s['dt_stable'], (s['dt'], s['dt_stable'])
print('ok')" r.h5
    assert_output ok
}

@test "--time T runs the fewest equal steps of at most the time step that reach T" {
    make_block
    pd-run -q --bulk-modulus "$BULK" --steps 0 model.h5 -o ref.h5
    stable=$(scene_attr ref.h5 dt_stable)
    # 10.3 default steps (safety 0.8): 11 steps of T / 11; 13 steps of a
    # given dt = T / 13: 13 steps, whichever way T / dt rounds
    T=$(py "print(repr(10.3 * 0.8 * float(sys.argv[1])))" "$stable")
    pd-run -q --bulk-modulus "$BULK" --time "$T" --every 5 model.h5 -o r.h5
    dt=$(py "print(repr(float(sys.argv[1]) / 13))" "$T")
    pd-run -q --bulk-modulus "$BULK" --time "$T" --dt "$dt" model.h5 -o d.h5
    run -0 py "
T = float(sys.argv[3])
for path, steps, dt_max in ((sys.argv[1], 11, 0.8 * float(sys.argv[4])), (sys.argv[2], 13, float(sys.argv[5]))):
    f = h5py.File(path, 'r')
    s = f['scene'].attrs
    assert int(s['steps']) == steps, (path, s['steps'])
    assert s['dt'] == T / steps and s['dt'] <= dt_max * (1 + 1e-15), (path, s['dt'], dt_max)
    last = f['frames/%08d' % steps].attrs
    assert abs(last['time'] - T) <= 1e-14 * T, (path, last['time'], T)
    opts = s['options'].decode() if isinstance(s['options'], bytes) else s['options']
    assert 'steps %d\\n' % steps in opts and 'time' not in opts, opts
print('ok')" r.h5 d.h5 "$T" "$stable" "$dt"
    assert_output ok
    run -0 frames r.h5
    assert_equal "$(echo "$output" | awk '{print $2}' | tr '\n' ' ')" "0 5 10 11 "
}

@test "of --steps and --time the later wins, and a restart goes on by --steps" {
    make_block
    pd-run -q --bulk-modulus "$BULK" --steps 0 model.h5 -o ref.h5
    T=$(py "print(repr(4.5 * float(sys.argv[1])))" "$(scene_attr ref.h5 dt_stable)")
    pd-run -q --bulk-modulus "$BULK" --time "$T" --steps 3 model.h5 -o s.h5
    pd-run -q --bulk-modulus "$BULK" --steps 3 --time "$T" model.h5 -o t.h5
    assert_equal "$(scene_attr s.h5 steps)" 3
    assert_equal "$(scene_attr t.h5 steps)" 6
    # the run file holds the resolved dt and steps: a restart goes on with
    # that dt, to the bit of a run of 8 steps of it
    pd-run -q --restart t.h5 --steps 2 -o more.h5
    pd-run -q --bulk-modulus "$BULK" --dt "$(scene_attr t.h5 dt)" --steps 8 model.h5 -o all.h5
    run -0 py "
a, b = h5py.File(sys.argv[1], 'r'), h5py.File(sys.argv[2], 'r')
for k in ('displacement', 'velocity'):
    assert np.array_equal(a['frames/00000008'][k][()], b['frames/00000008'][k][()]), k
print('ok')" more.h5 all.h5
    assert_output ok
    expect_usage_error "--restart goes on" pd-run --restart t.h5 --time "$T" -o x.h5
}

@test "bad --time is a usage error, and --relax takes --steps" {
    make_block
    for t in 0 -1e-6 nan abc; do
        expect_usage_error "--time" pd-run --c 1e21 --time "$t" model.h5 -o r.h5
    done
    expect_usage_error "--relax takes --steps" \
        pd-run --c 1e21 --relax --dt 1 --time 1e-6 model.h5 -o r.h5
}

@test "--dt above the stable step is refused with a message naming the limit" {
    make_block
    pd-run -q --bulk-modulus "$BULK" --steps 0 model.h5 -o ref.h5
    stable=$(scene_attr ref.h5 dt_stable)
    dt=$(py "print(1.5 * float(sys.argv[1]))" "$stable")
    expect_runtime_error "exceeds the stable time step [0-9.e+-]+ s.*--force-dt" \
        pd-run --bulk-modulus "$BULK" --dt "$dt" --steps 2 model.h5 -o r.h5
    [ ! -e r.h5 ]
    assert_no_temp .
    # the limit in the message is the stable step, to the digits printed
    limit=$(sed -E 's/.*stable time step ([^ ]+) s.*/\1/' <<<"${stderr_lines[0]}")
    run -0 py "
a, b = float(sys.argv[1]), float(sys.argv[2])
assert abs(a - b) <= 1e-5 * b, (a, b)
print('ok')" "$limit" "$stable"
    assert_output ok
}

@test "--force-dt runs a --dt above the stable step" {
    make_block
    pd-run -q --bulk-modulus "$BULK" --steps 0 model.h5 -o ref.h5
    dt=$(py "print(1.5 * float(sys.argv[1]))" "$(scene_attr ref.h5 dt_stable)")
    run -0 --separate-stderr pd-run --bulk-modulus "$BULK" --dt "$dt" --force-dt --steps 2 model.h5 -o r.h5
    run -0 py "
s = h5py.File(sys.argv[1], 'r')['scene'].attrs
assert s['dt'] == float(sys.argv[2]) and s['dt'] > s['dt_stable']
print('ok')" r.h5 "$dt"
    assert_output ok
}

@test "a --dt below the stable step is used as given" {
    make_block
    pd-run -q --bulk-modulus "$BULK" --dt 1e-8 --steps 3 --every 1 model.h5 -o r.h5
    run -0 frames r.h5
    assert_output "$(printf '00000000 0 0\n00000001 1 1e-08\n00000002 2 2e-08\n00000003 3 3e-08')"
}

# ------------------------------------------------------------ frames

@test "frames at step 0, every N steps and the last step" {
    make_block
    pd-run -q --bulk-modulus "$BULK" --steps 25 --every 10 model.h5 -o r.h5
    run -0 frames r.h5
    assert_equal "${#lines[@]}" 4
    assert_line --index 0 --regexp '^00000000 0 '
    assert_line --index 1 --regexp '^00000010 10 '
    assert_line --index 2 --regexp '^00000020 20 '
    assert_line --index 3 --regexp '^00000025 25 '
}

@test "a last step that is a multiple of --every is written once" {
    make_block
    pd-run -q --bulk-modulus "$BULK" --steps 20 --every 5 model.h5 -o r.h5
    run -0 frames r.h5
    assert_equal "$(cut -d' ' -f2 <<<"$output" | tr '\n' ' ')" "0 5 10 15 20 "
}

@test "--every 0 writes only the last step" {
    make_block
    pd-run -q --bulk-modulus "$BULK" --steps 12 --every 0 model.h5 -o r.h5
    run -0 frames r.h5
    assert_equal "${#lines[@]}" 1
    assert_line --index 0 --regexp '^00000012 12 '
}

@test "each frame: time = step dt, fields of the documented shapes, kinetic energy and broken bonds agree" {
    make_run
    run -0 py "
f = h5py.File(sys.argv[1], 'r')
n = f['particles/id'].size
count = int(f['bonds'].attrs['count'])
m = f['particles/density'][:] * f['particles/volume'][:]
dt = f['scene'].attrs['dt']
steps = []
for k, g in f['frames'].items():
    a = g.attrs
    steps.append(int(a['step']))
    assert k == '%08d' % a['step']
    assert a['time'] == a['step'] * dt, (a['time'], a['step'] * dt)
    u, v, s = g['displacement'], g['velocity'], g['state']
    assert u.shape == (n, 3) and u.dtype == np.float64
    assert v.shape == (n, 3) and v.dtype == np.float64
    assert s.shape == ((count + 7) // 8,) and s.dtype == np.uint8
    v = v[:]
    ke = 0.5 * (m * (v * v).sum(axis=1)).sum()
    assert abs(a['kinetic_energy'] - ke) <= 1e-12 * max(ke, 1e-300), (a['kinetic_energy'], ke)
    bits = np.unpackbits(s[:], bitorder='little')
    assert np.all(bits[count:] == 0), 'padding bits set'
    broken = count - int(bits[:count].sum())
    assert broken % 2 == 0 and a['broken_bonds'] == broken // 2, (a['broken_bonds'], broken)
assert sorted(steps) == [0, 10, 20, 30, 40, 50], steps
print('ok')" run.h5
    assert_output ok
}

# ------------------------------------------------------------ scene

@test "/scene holds the resolved parameters and only the declared effects" {
    make_block
    pd-run -q --bulk-modulus "$BULK" --steps 4 model.h5 -o plain.h5
    run -0 scene_attr plain.h5 effects
    assert_output "pmb"
    make_run
    run -0 py "
f = h5py.File(sys.argv[1], 'r')
s = f['scene'].attrs
e = s['effects']
e = (e.decode() if isinstance(e, bytes) else e).split()
assert 'contact' in e and 'indenter' in e and any('failure' in w for w in e), e
assert s['s00'] == 0.0005 and s['alpha'] == 0.25
assert s['contact_skin'] > 0
assert list(s['indenter']) == [0.005, 0.005, 0.0125, 0.003, 1e17, 0, 0, -100]
assert int(s['steps']) == 50 and int(s['every']) == 10
assert s['dt'] > 0 and s['dt'] <= s['dt_stable']
print('ok')" run.h5
    assert_output ok
    run -0 py "
s = h5py.File(sys.argv[1], 'r')['scene'].attrs
for k in ('s00', 'alpha', 'contact_skin', 'indenter'):
    assert k not in s, k
print('ok')" plain.h5
    assert_output ok
}

@test "the default contact skin: half the room between the contact's reach and the lattice gap, within 0.5 and 1 spacings" {
    # g: the nearest lattice distance beyond the horizon (a sum of three
    # squares in 3-D, of two on a plate), max d_ij = 1.35 (r_i + r_j) =
    # 1.35 spacings on a lattice: skin = (g - 1.35 dx) / 2, clamped
    dx=0.001
    pd-lattice -q --spacing "$dx" --density 2200 --box 0,0.008,0,0.008,0,0.006 -o box.h5
    pd-lattice -q --spacing "$dx" --density 2200 --dimension 2 --thickness 0.001 \
        --box 0,0.008,0,0.008,-1,1 -o plate.h5
    check() { # LATTICE M EXPECTED_SPACINGS
        pd-bonds -q --horizon "$(awk -v m="$2" -v dx="$dx" 'BEGIN { printf "%.10g", m * dx }')" \
            "$1" -o m.h5
        pd-run -q --c 1e21 --contact --steps 1 m.h5 -o r.h5
        run -0 py "
s = float(h5py.File(sys.argv[1], 'r')['scene'].attrs['contact_skin'])
want = float(sys.argv[2]) * float(sys.argv[3])
assert abs(s - want) <= 1e-12 * want, (s, want)
print('ok')" r.h5 "$3" "$dx"
        assert_output ok
    }
    # delta = 3 dx: g = sqrt(10) dx, in 3-D and on a plate (0.906 spacings)
    check box.h5 3.0002 "$(awk 'BEGIN { printf "%.15g", (sqrt(10) - 1.35) / 2 }')"
    check plate.h5 3.0002 "$(awk 'BEGIN { printf "%.15g", (sqrt(10) - 1.35) / 2 }')"
    # delta = 2.3 dx: g = sqrt(6) dx in 3-D (0.55), sqrt(8) dx on a plate (0.739)
    check box.h5 2.3 "$(awk 'BEGIN { printf "%.15g", (sqrt(6) - 1.35) / 2 }')"
    check plate.h5 2.3 "$(awk 'BEGIN { printf "%.15g", (sqrt(8) - 1.35) / 2 }')"
    # delta = 2 dx: g = sqrt(5) dx, (g - 1.35 dx) / 2 = 0.443: half a spacing
    check box.h5 2.0001 0.5
    # delta = 4 dx: g = sqrt(17) dx, 1.39: one spacing
    check box.h5 4.0001 1
    # a skin given is kept
    pd-run -q --c 1e21 --contact --contact-skin 0.00017 --steps 1 m.h5 -o r.h5
    run -0 scene_attr r.h5 contact_skin
    assert_output 0.00017
}

@test "the contact skin changes no bit: stencil and bond list, PMB and LPS, a run and its restart" {
    # the bar of tests/samebits/matrix.sh pressed by a sphere until its
    # broken bonds' particles are in contact; each row of the list sums its
    # pairs in ascending partner, whatever the cells of its build (before,
    # in the cells' order, whose edge is the reach: the LPS list's restart
    # at 0.5 and 0.906 spacings differed in a velocity at step 80).  Skins
    # of 0.05 spacings (a build almost every step) to 2.  The run files
    # the same but for the skin, the list's builds and their positions
    # (the restart slots') and the history.
    pd-lattice -q --spacing 0.001 --density 2200 --box 0,0.024,0,0.006,0,0.006 -o lattice.h5
    pd-bonds -q --horizon 0.0030001 lattice.h5 -o model.h5
    local scene=(--failure 0.0005,0.25 --contact --indenter sphere,0.012,0.003,0.009,0.003,1e18,0,0,-200
                 --steps 40 --every 20 --threads 1)
    local pmb=(--bulk-modulus 14.9e9) lps=(--model lps --bulk-modulus 14.9e9 --shear-modulus 6e9)
    local skins=(0.0005 0.00005 0.000906 0.002)
    for skin in "${skins[@]}"; do
        pd-run -q "${pmb[@]}" "${scene[@]}" --contact-skin "$skin" model.h5 -o "pmb-$skin.h5"
        pd-run -q "${lps[@]}" "${scene[@]}" --bond-list --contact-skin "$skin" model.h5 \
            -o "lps-$skin.h5"
        pd-run -q --restart "lps-$skin.h5" --steps 40 --every 20 -o "cont-$skin.h5"
    done
    run -0 py "
def same(a, b):
    def walk(name, x):
        y = b[name]
        for k in x.attrs:
            if k not in ('contact_builds', 'contact_skin', 'options', 'history'):
                assert np.array_equal(np.asarray(x.attrs[k]), np.asarray(y.attrs[k])), (name, k)
        if isinstance(x, h5py.Dataset) and not name.endswith('contact_position'):
            assert x.dtype == y.dtype and x[()].tobytes() == y[()].tobytes(), name
    a.visititems(walk)
n = 0
for run in ('pmb', 'lps', 'cont'):
    a = h5py.File(run + '-' + sys.argv[1] + '.h5', 'r')
    for skin in sys.argv[2:]:
        b = h5py.File(run + '-' + skin + '.h5', 'r')
        same(a, b)
        assert float(a['scene'].attrs['contact_skin']) != float(b['scene'].attrs['contact_skin'])
        n += len(b['frames'])
print('ok', n)" "${skins[@]}"
    assert_output "ok 33"
    # the runs were in contact: more builds with the smaller skin
    run -0 py "
b = [int(h5py.File(f, 'r')['restart/0'].attrs['contact_builds']) for f in sys.argv[1:]]
assert b[0] > b[1] > 0, b
print('ok')" pmb-0.00005.h5 pmb-0.002.h5
    assert_output ok
}

@test "--bulk-modulus gives c = 18 K / (pi delta^4) in /scene/c" {
    make_block
    pd-run -q --bulk-modulus "$BULK" --steps 1 model.h5 -o r.h5
    run -0 py "
f = h5py.File(sys.argv[1], 'r')
delta = float(f['bonds'].attrs['horizon'])
K = float(sys.argv[2])
c = 18 * K / (np.pi * delta**4)
got = float(f['scene'].attrs['c'])
assert abs(got - c) <= 1e-14 * c, (got, c)
assert float(f['scene'].attrs['bulk_modulus']) == K
print('ok')" r.h5 "$BULK"
    assert_output ok
}

@test "--c is stored as given" {
    make_block
    pd-run -q --c 1.6863e22 --steps 1 model.h5 -o r.h5
    run -0 scene_attr r.h5 c
    assert_output "1.6863e+22"
}

@test "without --contact the log lacks contact and reports 0 contact list builds" {
    make_block
    run -0 --separate-stderr pd-run --bulk-modulus "$BULK" --steps 5 model.h5 -o r.h5
    assert_regex "${stderr_lines[0]}" '; effects: pmb$'
    refute_regex "${stderr_lines[0]}" 'contact'
    assert_regex "${stderr_lines[${#stderr_lines[@]}-1]}" 'contact list builds 0$'
}

@test "with --contact the log names it and the contact list is built" {
    make_block
    run -0 --separate-stderr pd-run --bulk-modulus "$BULK" --contact --steps 5 model.h5 -o r.h5
    assert_regex "${stderr_lines[0]}" '; effects: .*contact'
    assert_regex "${stderr_lines[${#stderr_lines[@]}-1]}" 'contact list builds [1-9][0-9]*$'
}

@test "--scene FILE: 'option value' lines with comments, the command line overrides" {
    make_block
    cat > impact.scene <<EOF
# a scene file holds the long options, one per line
bulk-modulus $BULK
dt 1e-8          # a comment after a value
steps 7
every 0

contact
EOF
    pd-run -q --scene impact.scene --steps 3 model.h5 -o r.h5
    run -0 frames r.h5
    assert_output "00000003 3 3e-08"
    run -0 scene_attr r.h5 effects
    assert_output "pmb contact"
    # a --scene given after the options changes nothing: the command line wins
    pd-run -q --steps 2 --scene impact.scene model.h5 -o r2.h5
    run -0 frames r2.h5
    assert_output "00000002 2 2e-08"
    # the scene's bulk modulus gives way to a --c on the command line
    pd-run -q --scene impact.scene --c 1e21 model.h5 -o r3.h5
    run -0 scene_attr r3.h5 c
    assert_output "1e+21"
}

@test "a run repeated from /scene/options gives the same frames" {
    make_run
    py "
o = h5py.File(sys.argv[1], 'r')['scene'].attrs['options']
sys.stdout.write(o.decode() if isinstance(o, bytes) else o)" run.h5 > again.scene
    pd-run -q --scene again.scene model.h5 -o again.h5
    # the options give c itself, so only bulk_modulus is missing from /scene
    run -0 h5_same run.h5 again.h5 'history|threads|bulk_modulus'
}

@test "the history gains the pd-run command line" {
    make_block
    pd-run -q --bulk-modulus "$BULK" --steps 1 model.h5 -o r.h5
    run -0 py "
h = h5py.File(sys.argv[1], 'r').attrs['history']
print(h.decode() if isinstance(h, bytes) else h)" r.h5
    assert_equal "${#lines[@]}" 3
    assert_line --index 2 "pd-run -q --bulk-modulus $BULK --steps 1 model.h5 -o r.h5"
}

@test "the model travels unchanged into the run file" {
    make_run
    run -0 h5_same model.h5 run.h5 'history|^/frames|^/scene|^/restart|^/series'
}

# ------------------------------------------------------------ physics

@test "a body at rest without effects stays exactly at rest" {
    make_block
    pd-run -q --bulk-modulus "$BULK" --steps 20 --every 10 model.h5 -o r.h5
    run -0 py "
f = h5py.File(sys.argv[1], 'r')
for k, g in f['frames'].items():
    assert not np.any(g['displacement'][:]), k
    assert not np.any(g['velocity'][:]), k
    assert g.attrs['kinetic_energy'] == 0
print('ok')" r.h5
    assert_output ok
}

@test "an elastic run (no --failure) breaks no bond, even under the indenter" {
    make_block
    pd-run -q --bulk-modulus "$BULK" --contact --allow-overlap \
        --indenter sphere,0.005,0.005,0.0125,0.003,1e17,0,0,-100 \
        --steps 50 --every 10 model.h5 -o r.h5
    run -0 py "
f = h5py.File(sys.argv[1], 'r')
count = int(f['bonds'].attrs['count'])
moved = False
for k, g in f['frames'].items():
    assert g.attrs['broken_bonds'] == 0, k
    bits = np.unpackbits(g['state'][:], bitorder='little')[:count]
    assert np.all(bits == 1), k
    moved |= np.abs(g['displacement'][:]).max() > 1e-6
assert moved, 'the indenter did not deform the block'
print('ok')" r.h5
    assert_output ok
}

@test "with --failure the indenter breaks bonds; they break in pairs and never heal" {
    make_run
    run -0 py "
f = h5py.File(sys.argv[1], 'r')
off, nb = pdh5.bonds(f)[:2]
count = nb.size
rows = np.repeat(np.arange(off.size - 1), np.diff(off))
# the position of the reverse copy j->i of every bond i->j
key = rows.astype(np.int64) * (off.size) + nb
rev = np.searchsorted(key, nb.astype(np.int64) * (off.size) + rows)
assert np.array_equal(key[rev], nb.astype(np.int64) * off.size + rows)
prev = np.ones(count, dtype=np.uint8)
frames = sorted(f['frames'].values(), key=lambda g: g.attrs['step'])
for g in frames:
    bits = np.unpackbits(g['state'][:], bitorder='little')[:count]
    assert np.all(bits <= prev), ('a bond healed at step', g.attrs['step'])
    assert np.array_equal(bits, bits[rev]), 'a bond broke on one side only'
    prev = bits
assert frames[0].attrs['broken_bonds'] == 0
assert frames[-1].attrs['broken_bonds'] > 0, 'no bond broke'
print('ok')" run.h5
    assert_output ok
}

@test "--threads 1 and --threads 2 give bit-identical frames" {
    make_block
    make_run "$BATS_TEST_TMPDIR" --threads 1
    mv run.h5 t1.h5
    make_run "$BATS_TEST_TMPDIR" --threads 2
    mv run.h5 t2.h5
    run -0 scene_attr t2.h5 threads
    assert_output 2
    run -0 h5_same t1.h5 t2.h5 'history|threads'
    run -0 py "
f = h5py.File(sys.argv[1], 'r')
assert f['frames/00000050'].attrs['broken_bonds'] > 0
print('ok')" t1.h5
    assert_output ok
}

# ------------------------------------------------------------ pipes

@test "pd-lattice -o - | pd-bonds - -o - | pd-run - -o run.h5 works" {
    pd-lattice -q --spacing "$SPACING" --density "$DENSITY" --box 0,0.01,0,0.01,0,0.01 -o - |
        pd-bonds -q --horizon "$HORIZON" - -o - |
        pd-run -q "${RUN_OPTS[@]}" --steps 50 --every 10 - -o piped.h5
    make_run
    run -0 h5_same run.h5 piped.h5 'history'
}

@test "-o - streams the run to stdout, the log stays on stderr" {
    make_block
    pd-run --bulk-modulus "$BULK" --steps 3 model.h5 -o - > r.h5 2> log
    run -0 frames r.h5
    assert_output --regexp '^00000003 3 '
    run grep -c '^pd-run: ' log
    [ "$output" -ge 3 ]
}

@test "-q silences the log" {
    make_block
    run -0 --separate-stderr pd-run -q --bulk-modulus "$BULK" --steps 3 model.h5 -o r.h5
    assert_equal "$stderr" ""
    assert_output ""
}

@test "a run killed by SIGTERM or SIGHUP before its first step leaves nothing behind" {
    make_block
    # under nohup SIGHUP comes in ignored, and pd-run leaves it so
    local ignored
    ignored=$(awk '/^SigIgn:/ { print $2 }' /proc/$$/status)
    for sig in TERM HUP; do
        [ "$sig" = HUP ] && (( 0x$ignored & 1 )) && continue
        # a long run on a slow pipe: killed while the model is being written
        pd-run --c 1e21 --steps 100000000 --every 1 -q model.h5 -o "killed.h5" &
        pid=$!
        for _ in $(seq 100); do
            compgen -G ".killed.h5.tmp.*" >/dev/null && break
            sleep 0.05
        done
        kill -s "$sig" "$pid"
        run wait "$pid"
        kill -s KILL "$pid" 2>/dev/null || true # should it live on, it must not run on
        [ "$status" -gt 128 ]
        [ ! -e killed.h5 ]
        assert_no_temp .
    done
}

# The SIGKILL tests kill pd-run at moments drawn from a fixed seed, so that a
# failure can be repeated: PD_KILL_SEED=N draws others.  A moment is a
# fraction of the time the uninterrupted run took after publishing its file,
# counted from the moment the killed run's file appears under its final name
# (pd-run publishes it once its frames are laid out): a slow machine or
# AddressSanitizer (SANITIZE=1) stretches the moments with the run.
KILL_SEED=${PD_KILL_SEED:-42}
KILLS=5 # kills per test, at least KILLS_LANDED of them before the run ends
KILLS_LANDED=3
PUBLISH_TIMEOUT=120 # s

# kill_fractions SEED N: N fractions of the run in [0.05, 0.7), one a line,
# the same for a SEED on every machine (Python's Mersenne Twister).
kill_fractions() {
    "$PY" -c "import random, sys
r = random.Random(int(sys.argv[1]))
for _ in range(int(sys.argv[2])):
    print('%.3f' % r.uniform(0.05, 0.7))" "$1" "$2"
}

# await_publish PID FILE: wait until FILE exists, at most PUBLISH_TIMEOUT
# seconds; fail naming it when the process PID ends first or time runs out.
await_publish() {
    local pid=$1 file=$2 deadline=$((SECONDS + PUBLISH_TIMEOUT))
    until [ -e "$file" ]; do
        if ! kill -0 "$pid" 2>/dev/null && [ ! -e "$file" ]; then
            echo "pd-run (pid $pid) ended without publishing $file" >&2
            return 1
        fi
        if [ "$SECONDS" -ge "$deadline" ]; then
            echo "$file did not appear within $PUBLISH_TIMEOUT s" >&2
            return 1
        fi
        sleep 0.01
    done
}

# run_after_publish FILE PD-RUN-ARG...: run pd-run writing FILE and print the
# seconds it ran after publishing FILE; fail when it fails.
run_after_publish() {
    local file=$1 pid t0
    shift
    pd-run "$@" &
    pid=$!
    await_publish "$pid" "$file" || return 1
    t0=$EPOCHREALTIME
    wait "$pid" || { echo "the uninterrupted pd-run $* failed" >&2; return 1; }
    awk -v a="$t0" -v b="$EPOCHREALTIME" 'BEGIN { printf "%.3f\n", b - a }'
}

# kill_after_publish FILE DELAY PD-RUN-ARG...: start pd-run writing FILE,
# SIGKILL it DELAY seconds after FILE appears, and set KILL_STATUS to its exit
# status (137 when the kill landed before the run ended, 0 when it did not).
kill_after_publish() {
    local file=$1 delay=$2 pid
    shift 2
    pd-run "$@" &
    pid=$!
    if ! await_publish "$pid" "$file"; then
        kill -9 "$pid" 2>/dev/null || true
        wait "$pid" || true
        return 1
    fi
    sleep "$delay"
    kill -9 "$pid" 2>/dev/null || true
    KILL_STATUS=0
    wait "$pid" || KILL_STATUS=$?
    if [ "$KILL_STATUS" -ne 0 ] && [ "$KILL_STATUS" -ne 137 ]; then
        echo "pd-run $* failed before the kill (exit $KILL_STATUS)" >&2
        return 1
    fi
}

# kill_delays SECONDS: the delays of the seeded fractions of a run of SECONDS
# after publishing, into DELAYS, printed (shown on failure) with the seed.
kill_delays() {
    local fractions
    mapfile -t fractions < <(kill_fractions "$KILL_SEED" "$KILLS")
    mapfile -t DELAYS < <(printf '%s\n' "${fractions[@]}" | awk -v t="$1" '{ printf "%.3f\n", $1 * t }')
    [ "${#DELAYS[@]}" -eq "$KILLS" ]
    echo "kill seed $KILL_SEED (PD_KILL_SEED): the run took $1 s after publishing;" \
        "kills at ${fractions[*]} of it: ${DELAYS[*]} s after publishing"
}

# assert_kills_landed N: at least KILLS_LANDED of the kills came before the
# run ended (a kill after it checked nothing).
assert_kills_landed() {
    echo "$1 of $KILLS kills landed before the run ended"
    if [ "$1" -lt "$KILLS_LANDED" ]; then
        echo "only $1 of $KILLS kills landed before the run ended (at least $KILLS_LANDED wanted)" >&2
        return 1
    fi
}

@test "a run killed by SIGKILL at 5 seeded moments after it is published reads with whole frames and series rows" {
    make_block
    py "
import numpy as np
with h5py.File('model.h5') as f:
    print(len(f['particles/id']))" >/dev/null
    local opts=("${RUN_OPTS[@]}" --steps 3000 --every 20 --series 10 --threads 1 -q model.h5 -o k.h5)
    took=$(run_after_publish k.h5 "${opts[@]}")
    kill_delays "$took"
    landed=0
    for k in $(seq "$KILLS"); do
        rm -f k.h5 .k.h5.tmp.*
        kill_after_publish k.h5 "${DELAYS[k - 1]}" "${opts[@]}"
        echo "kill $k, ${DELAYS[k - 1]} s after publishing: pd-run exit $KILL_STATUS"
        rm -f .k.h5.tmp.* # the published file has no temporary left
        [ -e k.h5 ]
        # every pd reader takes it, and lists only whole frames
        run -0 pd-damage -n k.h5
        run -0 pd-crack-tip k.h5
        run -0 pd-dump2vtk -q k.h5 -o "vtk$k"
        # the XDMF description lists the complete frames, at their times
        run -0 pd-dump2vtk -q --xdmf k.h5 -o "k$k.xdmf"
        py "
import xml.etree.ElementTree as ET
with h5py.File(sys.argv[1]) as f:
    times = sorted(float(g.attrs['time']) for g in f['frames'].values() if g.attrs['complete'] == 1)
grids = ET.parse(sys.argv[2]).getroot().find('./Domain/Grid').findall('Grid')
assert [float(g.find('Time').get('Value')) for g in grids] == times, times" k.h5 "k$k.xdmf"
        py "
import numpy as np
with h5py.File(sys.argv[1]) as f:
    frames = [g for g in f['frames'].values() if g.attrs['complete'] == 1]
    steps = sorted(g.attrs['step'] for g in frames)
    assert steps == list(range(0, 20 * len(steps), 20)), steps   # a prefix of the plan
    for g in frames:
        assert np.isfinite(g['displacement'][:]).all() and np.isfinite(g['velocity'][:]).all()
    d = f['frames'][max(f['frames'], key=lambda n: f['frames'][n].attrs['step'])]
    # the counted rows of the series are whole, a prefix of its plan, and
    # the row of each complete frame's step was written before the frame
    g = f['series']
    rows = g.attrs['rows']
    v = g['values'][:rows]
    assert list(v[:, 0]) == list(range(0, 10 * rows, 10)), v[:, 0]
    assert np.isfinite(v).all()
    assert rows > 0 and v[-1, 0] >= max(steps), (rows, steps)
    print(len(steps), 'frames,', rows, 'rows')" k.h5
        if [ "$KILL_STATUS" -eq 137 ]; then landed=$((landed + 1)); fi
    done
    assert_kills_landed "$landed"
}

@test "a run that goes non-finite stops naming the step, keeps the frames before" {
    make_block
    # no failure (bonds that break would free the particles) and twenty times
    # the stable step: the indented lattice blows up within a hundred steps
    run --separate-stderr pd-run --bulk-modulus "$BULK" --allow-overlap \
        --indenter sphere,0.005,0.005,0.0125,0.003,1e17,0,0,-100 --dt 5e-6 --force-dt \
        --steps 2000 --every 5 -q model.h5 -o r.h5
    [ "$status" -eq 1 ]
    [ "$(printf '%s\n' "$stderr" | wc -l)" -eq 1 ]
    # caught as not finite, or as a particle flying off while the kinetic
    # energy runs away (not taken for a lost particle)
    [[ "$stderr" =~ ^pd-run:\ error:\ (the\ (force|position|velocity)\ of\ )?particle\ [0-9]+\ \(id\ [0-9]+\)\ (is\ not\ finite|flew\ off)\ at\ step\ ([0-9]+)[:\ ].*time\ step ]]
    bad=${BASH_REMATCH[4]}
    # every complete frame in the file is finite and comes before the bad step
    py "
import numpy as np
with h5py.File(sys.argv[1]) as f:
    done = [g for g in f['frames'].values() if g.attrs['complete'] == 1]
    steps = [g.attrs['step'] for g in done]
    assert steps and max(steps) < int(sys.argv[2]), (steps, sys.argv[2])
    for g in done:
        assert np.isfinite(g['displacement'][:]).all()
        assert np.isfinite(g['velocity'][:]).all()" r.h5 "$bad"
    run -0 pd-damage -n r.h5
    assert_no_temp .
}

@test "a full disk (a file-size limit) is one error, no output and no temporary file" {
    make_block
    run --separate-stderr bash -c 'ulimit -f 200; exec pd-run --c 1e21 --steps 1 -q model.h5 -o full.h5'
    [ "$status" -eq 1 ]
    [ "$(printf '%s\n' "$stderr" | wc -l)" -eq 1 ]
    [[ "$stderr" =~ ^pd-run:\ error:.*(disk\ full|cannot\ write) ]]
    [ ! -e full.h5 ]
    assert_no_temp .
}

# same_frame A B STEP: the frame STEP of A and of B bit for bit
same_frame() {
    py "
import numpy as np
with h5py.File(sys.argv[1]) as a, h5py.File(sys.argv[2]) as b:
    k = '%08d' % int(sys.argv[3])
    for d in ('displacement', 'velocity', 'state'):
        x, y = a['frames'][k][d][:], b['frames'][k][d][:]
        assert x.dtype == y.dtype and np.array_equal(x.view(np.uint8), y.view(np.uint8)), (k, d)
    assert a['frames'][k].attrs['complete'] == b['frames'][k].attrs['complete'] == 1
    # the energies too: the work and released energy go on from the restart data
    for n in ('kinetic_energy', 'elastic_energy', 'contact_energy', 'released_energy',
              'lost_energy', 'external_work', 'broken_bonds', 'lost_particles'):
        x, y = a['frames'][k].attrs[n], b['frames'][k].attrs[n]
        assert x == y, (k, n, x, y)" "$@"
}

@test "--restart: 2N steps in one run equal N steps and N more, bit for bit" {
    make_block
    pd-run "${RUN_OPTS[@]}" --steps 120 --every 30 --threads 2 -q model.h5 -o full.h5
    pd-run "${RUN_OPTS[@]}" --steps 60 --every 30 --threads 2 -q model.h5 -o run.h5
    run --separate-stderr pd-run --restart run.h5 --steps 60 --threads 2
    [ "$status" -eq 0 ]
    [[ "$stderr" =~ going\ on\ from\ step\ 60 ]]
    for step in 90 120; do same_frame full.h5 run.h5 "$step"; done
    py "
with h5py.File(sys.argv[1]) as f:
    assert f['scene'].attrs['steps'] == 120, f['scene'].attrs['steps']
    assert '--restart run.h5 --steps 60' in f.attrs['history'].splitlines()[-1]
    assert sorted(f['frames']) == ['%08d' % s for s in (0, 30, 60, 90, 120)], sorted(f['frames'])" run.h5
    assert_no_temp .
}

@test "--restart of a run killed by SIGKILL goes on from the last complete frame to the uninterrupted result" {
    make_block
    took=$(run_after_publish full.h5 "${RUN_OPTS[@]}" --steps 3000 --every 100 --series 50 \
        --threads 2 -q model.h5 -o full.h5)
    kill_delays "$took"
    landed=0
    for k in $(seq "$KILLS"); do
        rm -f k.h5 .k.h5.tmp.*
        kill_after_publish k.h5 "${DELAYS[k - 1]}" "${RUN_OPTS[@]}" --steps 3000 --every 100 \
            --series 50 --threads 2 -q model.h5 -o k.h5
        rm -f .k.h5.tmp.*
        [ -e k.h5 ]
        last=$(py "
with h5py.File(sys.argv[1]) as f:
    done = [g.attrs['step'] for g in f['frames'].values() if g.attrs['complete'] == 1]
    print(max(done) if done else -1)" k.h5)
        echo "kill $k, ${DELAYS[k - 1]} s after publishing: pd-run exit $KILL_STATUS, last complete frame $last"
        [ "$last" -ge 0 ] || continue # killed before its first frame: nothing to go on from
        run -0 pd-run --restart k.h5 --steps $((3000 - last)) --series 50 --threads 1 -q
        same_frame full.h5 k.h5 3000
        # and the time series, its rows after the frame written again
        py "
import numpy as np
with h5py.File(sys.argv[1]) as a, h5py.File(sys.argv[2]) as b:
    x = a['series/values'][: a['series'].attrs['rows']]
    y = b['series/values'][: b['series'].attrs['rows']]
    assert x.shape == y.shape == (61, x.shape[1]), (x.shape, y.shape)
    assert np.array_equal(x.view(np.uint8), y.view(np.uint8))" full.h5 k.h5
        if [ "$KILL_STATUS" -eq 137 ]; then landed=$((landed + 1)); fi
    done
    assert_kills_landed "$landed"
}

@test "--restart refuses what would change the scene, and needs --steps" {
    make_block
    pd-run "${RUN_OPTS[@]}" --steps 20 --every 10 -q model.h5 -o run.h5
    cp run.h5 before.h5
    for opt in "--dt 1e-8" "--c 1e21" "--contact" "--failure 0.001,0.25" "--safety 0.5" \
        "--indenter sphere,0,0,0,1,1,0,0,0" "--scene x.scene"; do
        # shellcheck disable=SC2086 # opt holds an option and its value
        expect_usage_error "--restart goes on with the scene" pd-run --restart run.h5 --steps 5 $opt
    done
    expect_usage_error "--restart needs --steps" pd-run --restart run.h5
    cmp run.h5 before.h5
    # -o: the continued run goes elsewhere, RUN.h5 stays as it was
    run -0 pd-run --restart run.h5 --steps 10 -q -o more.h5
    cmp run.h5 before.h5
    run -0 pd-damage -n more.h5
    assert_line --partial "30 "
}

@test "--restart from step 0 (a run killed after its first frame)" {
    make_block
    pd-run "${RUN_OPTS[@]}" --steps 40 --every 20 --threads 2 -q model.h5 -o full.h5
    pd-run "${RUN_OPTS[@]}" --steps 0 --every 20 --threads 2 -q model.h5 -o run.h5
    # one frame, one restart slot; the restart adds the second
    run -0 py "print(sorted(h5py.File(sys.argv[1])['restart']))" run.h5
    assert_output "['0']"
    run -0 pd-run --restart run.h5 --steps 40 --threads 2 -q
    for step in 20 40; do same_frame full.h5 run.h5 "$step"; done
    run -0 py "print(sorted(h5py.File(sys.argv[1])['restart']))" run.h5
    assert_output "['0', '1']"
    run -0 py "print(sorted(h5py.File(sys.argv[1])['restart']))" full.h5
    assert_output "['0', '1']"
}

@test "--restart goes on bit for bit after particles were lost" {
    pd-lattice -q --spacing 0.0005 --density "$DENSITY" --box 0,0.02,0,0.02,0,0.0025 -o plate.h5
    pd-bonds -q --horizon 0.0015001 plate.h5 -o model.h5
    local opts=(--bulk-modulus "$BULK" --failure 0.0005,0.25 --contact --lost-margin 0.005
                --indenter sphere,0.01,0.01,0.0055,0.0025,1e18,0,0,-1000 --every 100 -q)
    pd-run "${opts[@]}" --steps 300 model.h5 -o full.h5
    pd-run "${opts[@]}" --steps 200 model.h5 -o run.h5
    py "
with h5py.File(sys.argv[1]) as f:
    assert f['frames/00000200'].attrs['lost_particles'] > 0" run.h5
    run -0 pd-run --restart run.h5 --steps 100 -q
    same_frame full.h5 run.h5 300
}

@test "--failure-energy G0 gives s00 = sqrt(5 G0 / (9 K delta)) (seed 004 eq. 27)" {
    make_block
    run --separate-stderr pd-run --bulk-modulus "$BULK" --failure-energy 3.8 --steps 1 \
        model.h5 -o g.h5
    [ "$status" -eq 0 ]
    [[ "$stderr" =~ critical\ stretch\ s00\ [0-9.e-]+\ from\ the\ fracture\ energy\ G0\ 3.8 ]]
    py "
import math
with h5py.File(sys.argv[1]) as f:
    a = f['scene'].attrs
    want = math.sqrt(5 * 3.8 / (9 * $BULK * $HORIZON))
    assert abs(a['s00'] - want) <= 1e-12 * want and a['alpha'] == 0, (a['s00'], want)" g.h5
    # with --c and ALPHA: sqrt(10 G0 / (pi c delta^5))
    run -0 pd-run --c 1e21 --failure-energy 3.8,0.25 --steps 1 -q model.h5 -o c.h5
    py "
import math
with h5py.File(sys.argv[1]) as f:
    a = f['scene'].attrs
    want = math.sqrt(10 * 3.8 / (math.pi * 1e21 * $HORIZON ** 5))
    assert abs(a['s00'] - want) <= 1e-12 * want and a['alpha'] == 0.25, (a['s00'], want)" c.h5
    # the last of --failure and --failure-energy wins
    run -0 pd-run --c 1e21 --failure-energy 3.8 --failure 0.001,0.5 --steps 1 -q model.h5 -o l.h5
    [ "$(scene_attr l.h5 s00)" = 0.001 ]
    for bad in 0 -1 abc 3.8,-1 3.8,1,2; do
        expect_usage_error "--failure-energy needs G0" pd-run --c 1e21 --failure-energy "$bad" \
            --steps 1 model.h5 -o x.h5
    done
}

@test "an unwritable directory is one error naming the file and its cause, and leaves nothing" {
    make_block
    # a directory without write permission; root ignores permission bits,
    # so as root take sysfs, which refuses new files to everyone
    local dir=ro
    mkdir ro && chmod 555 ro
    if [ "$(id -u)" -eq 0 ]; then
        dir=/sys
        if touch /sys/pd-probe 2>/dev/null; then
            rm -f /sys/pd-probe
            skip "no unwritable directory here"
        fi
    fi
    run --separate-stderr pd-run --c 1e21 --steps 1 -q model.h5 -o "$dir/run.h5"
    [ "$status" -eq 1 ]
    [ "$(printf '%s\n' "$stderr" | wc -l)" -eq 1 ]
    [[ "$stderr" =~ ^pd-run:\ error:\ cannot\ write\ \'$dir/run.h5\':\ (Permission\ denied|Read-only\ file\ system) ]]
    [ ! -e "$dir/run.h5" ]
    [ -z "$(ls -A ro)" ]
}
