#!/usr/bin/env bats
# pd-damage: damage per particle (seed 000 eq. 10) checked against an
# independent numpy computation from /bonds and the frames' state bits, the
# table on stdout, and files left unchanged unless they are the output.

load test_helper

setup() {
    cd "$BATS_TEST_TMPDIR"
}

# check_damage RUN.h5 [TABLE]: every frame's stored damage equals
#   damage_i = 1 - sum_{j intact} V_j / sum_{j in family} V_j
# with bond b intact when bit b%8 of byte b//8 of the frame's state is set;
# with TABLE, one row per frame with step, time, broken pairs (cleared bits
# / 2), mean, max and the count above the threshold in the header.
check_damage() {
    py "
f = h5py.File(sys.argv[1], 'r')
V = f['particles/volume'][:]
off, nb = pdh5.bonds(f)[:2]
n, count = V.size, nb.size
rows = np.repeat(np.arange(n), np.diff(off))
total = np.bincount(rows, V[nb], minlength=n)
frames = sorted(f['frames'].values(), key=lambda g: g.attrs['step'])
table = None
if len(sys.argv) > 2:
    text = open(sys.argv[2]).read().splitlines()
    head = text[0].split()
    assert head[:6] == ['#', 'step', 'time_s', 'broken_bonds', 'mean_damage', 'max_damage'], head
    threshold = float(head[6].replace('n_damage_gt_', ''))
    table = [l.split() for l in text[1:]]
    assert len(table) == len(frames), (len(table), len(frames))
for k, g in enumerate(frames):
    b = np.arange(count)
    intact = (g['state'][:][b // 8] >> (b % 8)) & 1
    kept = np.bincount(rows, V[nb] * intact, minlength=n)
    want = np.where(total > 0, 1 - kept / np.where(total > 0, total, 1), 0)
    d = g['damage'][:]
    assert d.dtype == np.float64 and d.shape == (n,)
    assert np.all((d >= 0) & (d <= 1)), (d.min(), d.max())
    assert np.allclose(d, want, rtol=0, atol=1e-14), abs(d - want).max()
    if table is not None:
        row = table[k]
        assert int(row[0]) == g.attrs['step'], row
        assert abs(float(row[1]) - g.attrs['time']) <= 1e-8 * max(g.attrs['time'], 1e-300), row
        cleared = count - int(intact.sum())
        assert int(row[2]) * 2 == cleared, (row, cleared)
        assert abs(float(row[3]) - want.mean()) <= 1e-8, (row, want.mean())
        assert abs(float(row[4]) - want.max()) <= 1e-8, (row, want.max())
        assert int(row[5]) == np.count_nonzero(want > threshold), (row, threshold)
print('ok', len(frames), repr(frames[-1]['damage'][:].max() > 0))
" "$@"
}

# digest FILE: its SHA-256.
digest() {
    sha256sum "$1" | cut -d' ' -f1
}

# history FILE: the history attribute, one command per line.
history() {
    py "
h = h5py.File(sys.argv[1], 'r').attrs['history']
print(h.decode() if isinstance(h, bytes) else h)" "$1"
}

# ------------------------------------------------------------ the interface

@test "--help prints Usage on stdout and exits 0" {
    run -0 --separate-stderr pd-damage --help
    assert_line --index 0 --regexp '^Usage: pd-damage '
    assert_equal "$stderr" ""
}

@test "--version prints the program and version" {
    run -0 --separate-stderr pd-damage --version
    assert_output --regexp '^pd-damage \(pd\) [0-9]+\.[0-9]+'
}

@test "an unknown option is a usage error naming the option" {
    run -2 --separate-stderr pd-damage --bogus run.h5
    assert_one_error "^pd-damage: error: .*--bogus"
}

@test "RUN.h5 is required, and only one" {
    expect_usage_error "RUN\.h5" pd-damage
    expect_usage_error "RUN\.h5" pd-damage a.h5 b.h5
}

@test "--no-write and -o exclude each other" {
    expect_usage_error "--no-write" pd-damage -n -o out.h5 run.h5
}

@test "--threshold outside [0,1] or not a number is a usage error" {
    expect_usage_error "--threshold.*'1.5'" pd-damage --threshold 1.5 run.h5
    expect_usage_error "--threshold.*'-0.1'" pd-damage --threshold -0.1 run.h5
    expect_usage_error "--threshold.*'nan'" pd-damage --threshold nan run.h5
    expect_usage_error "--threshold.*'abc'" pd-damage --threshold abc run.h5
}

# ------------------------------------------------------------ bad inputs

@test "a missing file is a runtime error naming it" {
    expect_runtime_error "nosuch\.h5" pd-damage nosuch.h5
    expect_runtime_error "nosuch\.h5" pd-damage -n nosuch.h5
    [ ! -e nosuch.h5 ]
    assert_no_temp .
}

@test "an empty file is a runtime error, and it stays as it was" {
    make_bad_inputs
    expect_runtime_error "empty\.h5.*empty" pd-damage empty.h5
    [ ! -s empty.h5 ]
    assert_no_temp .
}

@test "a text file is a runtime error: not HDF5" {
    make_bad_inputs
    expect_runtime_error "text\.h5.*not an HDF5 file" pd-damage text.h5
    assert_equal "$(cat text.h5)" "this is not HDF5"
    assert_no_temp .
}

@test "a directory as input is a runtime error" {
    make_bad_inputs
    expect_runtime_error "adir.*directory" pd-damage adir
    expect_runtime_error "adir.*directory" pd-damage -n adir
}

@test "an HDF5 file that is not pd-h5 is a runtime error, left unchanged" {
    make_bad_inputs
    before=$(digest plain.h5)
    expect_runtime_error "plain\.h5.*not a pd-h5 file" pd-damage plain.h5
    assert_equal "$(digest plain.h5)" "$before"
    assert_no_temp .
}

@test "an unknown pd_format_version is a runtime error naming the version" {
    make_run
    with_version run.h5 v99.h5 99
    expect_runtime_error "v99\.h5.*version 99" pd-damage v99.h5 -o out.h5
    [ ! -e out.h5 ]
    assert_no_temp .
}

@test "a model without frames (the wrong stage) is a runtime error, left unchanged" {
    make_block
    before=$(digest model.h5)
    expect_runtime_error "model\.h5.*frames" pd-damage model.h5
    assert_equal "$(digest model.h5)" "$before"
    assert_no_temp .
}

@test "a lattice without bonds is a runtime error" {
    make_block
    expect_runtime_error "lattice\.h5.*/bonds" pd-damage -n lattice.h5
}

@test "a frame whose state has the wrong size is a runtime error" {
    make_run
    py "
with h5py.File(sys.argv[1], 'a') as f:
    s = f['frames/00000020/state'][:]
    del f['frames/00000020/state']
    f['frames/00000020/state'] = s[:-1]" run.h5
    run -1 --separate-stderr pd-damage run.h5 -o out.h5
    # the rows of the frames before the bad one are already out
    assert_line --index 2 --regexp '^10 '
    output=""
    assert_one_error "^pd-damage: error: .*00000020/state"
    [ ! -e out.h5 ]
    assert_no_temp .
}

@test "-o naming a directory fails with one error and leaves no temp file" {
    make_run
    mkdir out
    expect_runtime_error "out.*directory" pd-damage run.h5 -o out
    run -0 ls -A out
    assert_output ""
    assert_no_temp .
}

# ------------------------------------------------------------ damage

@test "damage is in [0,1] and equals the volume-weighted fraction of broken bonds" {
    make_run
    pd-damage run.h5 -o out.h5 > table
    run -0 check_damage out.h5 table
    assert_output "ok 6 True"
}

@test "the damage weights partners by their volume V_j" {
    make_run
    # give the particles unequal volumes: damage must follow them
    py "
with h5py.File(sys.argv[1], 'a') as f:
    v = f['particles/volume']
    v[...] = v[:] * (1 + 0.5 * np.sin(np.arange(v.size)))" run.h5
    pd-damage run.h5 -o out.h5 > table
    run -0 check_damage out.h5 table
    assert_output "ok 6 True"
}

@test "the table has one row per frame under a header; frame 0 is undamaged" {
    make_run
    run -0 --separate-stderr pd-damage -n run.h5
    assert_equal "$stderr" ""
    assert_line --index 0 "# step time_s broken_bonds mean_damage max_damage n_damage_gt_0.3"
    assert_equal "${#lines[@]}" 7
    assert_line --index 1 --regexp '^0 0\.0+e\+00 0 0\.0+ 0\.0+ 0$'
    assert_line --index 6 --regexp '^50 '
}

@test "--threshold sets the counted damage level" {
    make_run
    pd-damage --threshold 0.05 run.h5 -o out.h5 > table
    run -0 head -1 table
    assert_output "# step time_s broken_bonds mean_damage max_damage n_damage_gt_0.05"
    run -0 check_damage out.h5 table
    assert_output "ok 6 True"
}

@test "pd-run writes each frame's damage: on the stencil, the bond list, LPS, an irregular body" {
    make_block
    pd-run -q "${RUN_OPTS[@]}" --steps 50 --every 10 model.h5 -o stencil.h5
    pd-run -q "${RUN_OPTS[@]}" --steps 50 --every 10 --bond-list model.h5 -o list.h5
    # LPS breaks its first bonds later
    pd-run -q "${RUN_OPTS[@]}" --steps 100 --every 20 --model lps --shear-modulus 1e10 \
        model.h5 -o lps.h5
    pd-lattice -q --spacing "$SPACING" --density "$DENSITY" --box 0,0.01,0,0.01,0,0.01 \
        --perturb 5e-5 --seed 3 -o irregular-lattice.h5
    pd-bonds -q --horizon "$HORIZON" irregular-lattice.h5 -o irregular.h5
    pd-run -q "${RUN_OPTS[@]}" --steps 50 --every 10 irregular.h5 -o irregular-run.h5
    for r in stencil list lps irregular-run; do
        run -0 check_damage "$r.h5"
        assert_output "ok 6 True"
        # and pd-damage finds nothing to change
        pd-damage "$r.h5" -o "$r-again.h5" > /dev/null
        run -0 h5_same "$r.h5" "$r-again.h5" 'history'
    done
}

@test "-o OUT.h5 leaves RUN.h5 unchanged; OUT's history gains a line" {
    make_run
    before=$(digest run.h5)
    pd-damage run.h5 -o out.h5 > /dev/null
    assert_equal "$(digest run.h5)" "$before"
    run -0 history out.h5
    assert_equal "${#lines[@]}" 4
    assert_line --index 2 --regexp '^pd-run '
    assert_line --index 3 "pd-damage run.h5 -o out.h5"
    # everything else travels unchanged, and the damage is pd-run's own
    run -0 h5_same run.h5 out.h5 'history'
    assert_no_temp .
}

@test "pd-run's frames hold the damage pd-damage computes: RUN.h5 is read, not copied" {
    make_run
    run -0 check_damage run.h5
    assert_output "ok 6 True"
    before=$(digest run.h5)
    pd-damage run.h5 > table
    run -0 check_damage run.h5 table
    assert_output "ok 6 True"
    assert_equal "$(digest run.h5)" "$before"
    run -0 history run.h5
    assert_equal "${#lines[@]}" 3
    run -0 pd-damage -n run.h5
    assert_equal "$output" "$(cat table)"
    assert_no_temp .
}

@test "without -o, a RUN.h5 whose damage differs is updated in place through a complete copy" {
    make_run
    py "
with h5py.File(sys.argv[1], 'a') as f:
    f['frames/00000030/damage'][5] = 0.5" run.h5
    pd-damage run.h5 > table
    run -0 check_damage run.h5 table
    assert_output "ok 6 True"
    run -0 history run.h5
    assert_equal "${#lines[@]}" 4
    assert_line --index 3 "pd-damage run.h5"
    # a frame without the field is one to write too
    py "
with h5py.File(sys.argv[1], 'a') as f:
    del f['frames/00000040/damage']" run.h5
    pd-damage -q run.h5
    run -0 check_damage run.h5
    assert_output "ok 6 True"
    run -0 history run.h5
    assert_equal "${#lines[@]}" 5
    assert_no_temp .
}

@test "a second pass replaces the damage field and adds another history line" {
    make_run
    pd-damage run.h5 -o once.h5 > /dev/null
    pd-damage once.h5 -o twice.h5 > /dev/null
    run -0 h5_same once.h5 twice.h5 'history'
    run -0 history twice.h5
    assert_equal "${#lines[@]}" 5
}

@test "--no-write only prints the table; the file is untouched" {
    make_run
    before=$(digest run.h5)
    run -0 pd-damage --no-write run.h5
    assert_equal "${#lines[@]}" 7
    assert_equal "$(digest run.h5)" "$before"
    assert_no_temp .
}

@test "stdin to stdout: the file on stdout, the table on stderr" {
    make_run
    pd-damage - < run.h5 > out.h5 2> table
    run -0 check_damage out.h5 table
    assert_output "ok 6 True"
}

@test "an undamaged run has zero damage everywhere" {
    make_block
    pd-run -q --bulk-modulus "$BULK" --steps 10 --every 5 model.h5 -o r.h5
    run -0 pd-damage r.h5
    assert_equal "${#lines[@]}" 4
    for k in 1 2 3; do
        assert_line --index $k --regexp '^[0-9]+ [0-9.e+-]+ 0 0\.0+ 0\.0+ 0$'
    done
    run -0 check_damage r.h5
    assert_output "ok 3 False"
}

@test "-q prints no table but still stores the damage" {
    make_run
    run -0 --separate-stderr pd-damage -q run.h5 -o out.h5
    assert_output ""
    assert_equal "$stderr" ""
    run -0 check_damage out.h5
    assert_output "ok 6 True"
}

# ------------------------------------------------------------ pre-cracks

# The plane x = 4.5 mm over y in [-1, 4.4] mm, through the make_block cube.
CRACK=rect,0.0045,-0.001,-0.001,0,0.0054,0,0,0,0.012

# make_cracked_model: lattice.h5 and model.h5 of make_block, the model with
# the pre-crack CRACK.
make_cracked_model() {
    make_block || return 1
    pd-bonds -q --horizon "$HORIZON" --crack "$CRACK" lattice.h5 -o model.h5
}

# check_damage_run RUN.h5 [TABLE]: every frame's damage_run equals
#   1 - sum_{j intact, not pre-cracked} V_j / sum_{j not pre-cracked} V_j
# (0 without such partners), computed here from /bonds/precrack and the
# frame's state; with TABLE, its rows count the broken bonds that are not
# pre-cracked and give the mean and max of that damage.  Prints
# "ok NFRAMES MAX>0".
check_damage_run() {
    py "
f = h5py.File(sys.argv[1], 'r')
V = f['particles/volume'][:]
off, nb = pdh5.bonds(f)[:2]
n, count = V.size, nb.size
pre = np.unpackbits(f['bonds/precrack'][:], bitorder='little')[:count].astype(bool)
assert pre.any()
rows = np.repeat(np.arange(n), np.diff(off))
total = np.bincount(rows, V[nb] * ~pre, minlength=n)
frames = sorted(f['frames'].values(), key=lambda g: g.attrs['step'])
table = None
if len(sys.argv) > 2:
    text = open(sys.argv[2]).read().splitlines()
    table = [l.split() for l in text[1:]]
    assert len(table) == len(frames)
for k, g in enumerate(frames):
    mu = np.unpackbits(g['state'][:], bitorder='little')[:count].astype(bool)
    assert not np.any(mu & pre), 'a pre-cracked bond is intact'
    kept = np.bincount(rows, V[nb] * (mu & ~pre), minlength=n)
    want = np.where(total > 0, 1 - kept / np.where(total > 0, total, 1), 0)
    d = g['damage_run'][:]
    assert np.allclose(d, want, rtol=0, atol=1e-14), abs(d - want).max()
    if table is not None:
        row = table[k]
        assert int(row[0]) == g.attrs['step']
        assert int(row[2]) * 2 == np.count_nonzero(~mu & ~pre), row
        assert abs(float(row[3]) - want.mean()) <= 1e-8 and abs(float(row[4]) - want.max()) <= 1e-8, row
print('ok', len(frames), repr(frames[-1]['damage_run'][:].max() > 0))
" "$@"
}

@test "with a pre-crack, step 0: damage > 0 next to the crack, 0 with --no-precrack" {
    make_cracked_model
    pd-run -q --bulk-modulus "$BULK" --steps 0 model.h5 -o run.h5
    run -0 pd-damage -n run.h5
    assert_line --index 1 --regexp '^0 0\.0+e\+00 [1-9][0-9]* 0\.[0-9]*[1-9][0-9]* 0\.[0-9]*[1-9][0-9]* [0-9]+$'
    run -0 pd-damage -n --no-precrack run.h5
    assert_equal "${#lines[@]}" 2
    assert_line --index 1 --regexp '^0 0\.0+e\+00 0 0\.0+ 0\.0+ 0$'
    # stored: damage is positive exactly for particles with a bond across
    # the crack, damage_run is 0 everywhere
    pd-damage -q run.h5
    pd-damage -q --no-precrack run.h5
    run -0 py "
f = h5py.File(sys.argv[1], 'r')
off, nb = pdh5.bonds(f)[:2]
pre = np.unpackbits(f['bonds/precrack'][:], bitorder='little')[:nb.size].astype(bool)
rows = np.repeat(np.arange(off.size - 1), np.diff(off))
next_to = np.bincount(rows, pre, minlength=off.size - 1) > 0
g = f['frames/00000000']
d, r = g['damage'][:], g['damage_run'][:]
assert np.array_equal(d > 0, next_to) and next_to.any()
x = f['particles/position'][:]
assert np.all(np.abs(x[next_to, 0] - 0.0045) < 0.003), 'damage away from the crack'
assert np.all(r == 0)
print('ok')" run.h5
    assert_output ok
}

@test "--no-precrack: damage_run and the table leave the pre-crack out; damage keeps it" {
    make_cracked_model
    make_run
    pd-damage --no-precrack run.h5 -o out.h5 > table
    run -0 check_damage_run out.h5 table
    assert_output "ok 6 True"
    # damage_run written; damage is pd-run's, with the pre-crack
    run -0 h5_same run.h5 out.h5 'history|/damage_run$'
    run -0 check_damage out.h5
    assert_output "ok 6 True"
    # the default counts the pre-cracked bonds as broken
    pd-damage out.h5 > table2
    run -0 check_damage out.h5 table2
    assert_output "ok 6 True"
    run -0 check_damage_run out.h5
    assert_output "ok 6 True"
}

@test "--no-precrack without a pre-crack equals the default" {
    make_run
    diff <(pd-damage -n run.h5) <(pd-damage -n --no-precrack run.h5)
}

# precrack_edit EDIT: model.h5 of make_cracked_model (a stencil: the bits
# follow its expanded families), its /bonds/precrack changed by EDIT
# (python, with f open and count, pre (bits), state (bits), off, nb), into
# bad.h5.
precrack_edit() {
    make_cracked_model
    cp model.h5 bad.h5
    py "
f = h5py.File(sys.argv[1], 'a')
b = f['bonds']
count = int(b.attrs['count'])
off, nb = pdh5.bonds(f)[:2]
pre = np.unpackbits(b['precrack'][:], bitorder='little')[:count]
state = np.unpackbits(b['state'][:], bitorder='little')[:count]
$1
f.close()" bad.h5
}

@test "a pre-cracked bond intact in /bonds/state is refused naming the bond" {
    # mark the intact bond 0 -> nb[0] and its mirror as pre-cracked
    precrack_edit "
j = nb[0]
m = off[j] + np.searchsorted(nb[off[j]:off[j + 1]], 0)
assert state[0] == 1 and state[m] == 1
pre[0] = pre[m] = 1
b['precrack'][...] = np.packbits(pre, bitorder='little')"
    j=$(py "print(pdh5.bonds(h5py.File(sys.argv[1], 'r'))[1][0])" bad.h5)
    msg="'bad\.h5': bond 0-$j is pre-cracked \(/bonds/precrack\) but intact in /bonds/state$"
    expect_runtime_error "$msg" pd-damage -n bad.h5
    expect_runtime_error "$msg" pd-run -q --bulk-modulus "$BULK" --steps 0 bad.h5 -o r.h5
    [ ! -e r.h5 ]
}

@test "pre-crack bits on one side of a bond only are refused" {
    # clear one of the two copies of the first pre-cracked bond
    precrack_edit "
k = int(np.nonzero(pre)[0][0])
pre[k] = 0
b['precrack'][...] = np.packbits(pre, bitorder='little')"
    expect_runtime_error "'bad.h5': bond [0-9]+-[0-9]+ is pre-cracked on one side only \(precrack bits differ\)" \
        pd-damage -n bad.h5
}

# same_refusal FILE: pd-damage (which reads a stencil model's bonds as
# lists) and pd-run (which keeps them compact, walking each family off the
# stencil) refuse FILE with the same line, and pd-run leaves no output
same_refusal() {
    run -1 --separate-stderr pd-damage -n "$1"
    local line=${stderr#pd-damage: error: }
    [ -n "$line" ] && [ "$line" != "$stderr" ]
    run -1 --separate-stderr pd-run -q --bulk-modulus "$BULK" --steps 0 "$1" -o r.h5
    [ "$stderr" = "pd-run: error: $line" ]
    [ ! -e r.h5 ]
}

@test "a stencil model's bits on one side of a bond only: pd-run (compact families) refuses as pd-damage (lists) does" {
    # the state bit of the first bond that has a mirror below it, cleared
    # on one side; then the pre-crack bit of one side of a bond
    precrack_edit "
assert b.attrs['form'] == 'stencil'
i = int(np.nonzero(np.diff(off) > 0)[0][-1])
k = off[i]
state[k] = 1 - state[k]
b['state'][...] = np.packbits(state, bitorder='little')"
    same_refusal bad.h5
    [[ $stderr == *"is broken on one side only (state bits differ)" ]]
    precrack_edit "
k = int(np.nonzero(pre)[0][-1])
pre[k] = 0
b['precrack'][...] = np.packbits(pre, bitorder='little')"
    same_refusal bad.h5
    [[ $stderr == *"is pre-cracked on one side only (precrack bits differ)" ]]
    # both at once: the first one in the rows' order is named, as the lists do
    precrack_edit "
k = int(np.nonzero(pre)[0][0])
pre[k] = 0
b['precrack'][...] = np.packbits(pre, bitorder='little')
state[count - 1] = 1 - state[count - 1]
b['state'][...] = np.packbits(state, bitorder='little')"
    same_refusal bad.h5
}

@test "/bonds/precrack of the wrong size or type is refused naming the dataset" {
    precrack_edit "
p = b['precrack'][:]
del b['precrack']
b['precrack'] = p[:-1]"
    expect_runtime_error "'bad.h5': dataset '/bonds/precrack' has [0-9]+ entries along axis 0, expected [0-9]+" \
        pd-damage -n bad.h5
    precrack_edit "
p = b['precrack'][:]
del b['precrack']
b['precrack'] = p.astype(np.float64)"
    expect_runtime_error "'bad.h5': dataset '/bonds/precrack' is float64, expected uint8" pd-damage -n bad.h5
}

@test "--fragments: a cube cut through by a pre-crack is two fragments, 5 and 6 of its 11 layers" {
    make_block
    pd-bonds -q --horizon "$HORIZON" --crack rect,0.005,-1,-1,0,2,0,0,0,2 lattice.h5 -o cut.h5
    pd-run -q --bulk-modulus "$BULK" --steps 1 cut.h5 -o run.h5
    run pd-damage -n --fragments run.h5
    [ "$status" -eq 0 ]
    [[ "${lines[0]}" == *" fragments largest_fraction" ]]
    read -r -a row <<< "${lines[1]}"
    [ "${row[6]}" = 2 ]
    [ "${row[7]}" = 0.545454545 ] # 6/11: the plane's layer is on the +x side
    # the table without --fragments is the same, less the two columns
    diff <(pd-damage -n run.h5 | sed 's/ fragments largest_fraction$//') \
        <(pd-damage -n --fragments run.h5 | sed 's/ fragments largest_fraction$//; /^[0-9]/s/ [^ ]* [^ ]*$//')
}

@test "--fragments equals a union-find over the bond lists, bonds broken at random" {
    make_run
    # each frame: pairs broken at random (both of their bonds), more each frame
    py "
f = h5py.File(sys.argv[1], 'a')
off, nb = pdh5.bonds(f)[:2]
n, count = off.size - 1, nb.size
rng = np.random.default_rng(17)
frames = sorted(f['frames'].values(), key=lambda g: g.attrs['step'])
for k, g in enumerate(frames):
    bits = np.unpackbits(g['state'][:], bitorder='little')
    p = [0.3, 0.5, 0.8, 0.9, 0.95, 0.99][k]
    for i in range(n):
        for q in range(off[i], off[i + 1]):
            j = nb[q]
            if j > i and rng.random() < p:
                m = off[j] + np.searchsorted(nb[off[j]:off[j + 1]], i)
                assert nb[m] == i
                bits[q] = bits[m] = 0
    g['state'][...] = np.packbits(bits, bitorder='little')[:g['state'].shape[0]]
f.close()" run.h5
    pd-damage -n --fragments run.h5 > table
    py "
f = h5py.File(sys.argv[1], 'r')
V = f['particles/volume'][:]
off, nb = pdh5.bonds(f)[:2]
n, count = V.size, nb.size
rows = np.repeat(np.arange(n), np.diff(off))
frames = sorted(f['frames'].values(), key=lambda g: g.attrs['step'])
table = [l.split() for l in open(sys.argv[2]) if not l.startswith('#')]
assert len(table) == len(frames) == 6, (len(table), len(frames))
seen = set()
for g, row in zip(frames, table):
    b = np.arange(count)
    intact = (g['state'][:][b // 8] >> (b % 8)) & 1
    parent = list(range(n))
    def root(x):
        while parent[x] != x:
            x = parent[x]
        return x
    for i, j in zip(rows[intact == 1], nb[intact == 1]):
        a, c = root(i), root(j)
        if a != c:
            parent[max(a, c)] = min(a, c)
    roots = np.array([root(i) for i in range(n)])
    vol = np.bincount(roots, V, minlength=n)
    pieces = np.unique(roots).size
    assert int(row[6]) == pieces, (row, pieces)
    assert abs(float(row[7]) - vol.max() / V.sum()) <= 1e-9, (row, vol.max() / V.sum())
    seen.add(pieces)
assert len(seen) >= 3 and max(seen) > 50, seen
print('ok', sorted(seen))
" run.h5 table
}
