#!/usr/bin/env bats
# The corpus of broken pd-h5 files in tests/fixtures/broken (made by
# tests/fixtures/make-broken.py from a small valid run, one thing wrong in
# each): every reader refuses each file with exit 1 and exactly this one
# line, naming the file and what is wrong.  The same readers are fuzzed by
# `make fuzz`.

load test_helper

FIXTURES=$BATS_TEST_DIRNAME/fixtures/broken

setup() {
    cd "$FIXTURES"
}

# refused FILE MESSAGE [TIP_MESSAGE]: pd-damage, pd-dump2vtk and pd-crack-tip
# all exit 1 with "PROG: error: MESSAGE" (pd-crack-tip: TIP_MESSAGE when
# given) and nothing else on stderr; pd-dump2vtk writes
# no collection (.pvd), which it writes last, only for a complete export.
# (Rows or .vtu files of the frames before a bad frame may remain.)
refused() {
    local file=$1 out=$BATS_TEST_TMPDIR/out msg
    for prog in pd-damage pd-crack-tip pd-dump2vtk; do
        msg=$2
        [ "$prog" = pd-crack-tip ] && msg=${3:-$2}
        case $prog in
        pd-damage) run --separate-stderr pd-damage -n "$file" ;;
        pd-crack-tip) run --separate-stderr pd-crack-tip "$file" ;;
        pd-dump2vtk) run --separate-stderr pd-dump2vtk -q "$file" -o "$out/vtk" ;;
        esac
        [ "$status" -eq 1 ] && [ "$stderr" = "$prog: error: $msg" ] ||
            { echo "$prog: $status: $stderr"; return 1; }
    done
    ! compgen -G "$out/vtk/*.pvd" >/dev/null || { echo "a .pvd was written"; return 1; }
}

# refused_by_run FILE MESSAGE: pd-run too (for what a model carries).
refused_by_run() {
    refused "$@" || return 1
    run --separate-stderr pd-run --c 1e3 --steps 1 -q "$1" -o "$BATS_TEST_TMPDIR/r.h5"
    [ "$status" -eq 1 ] && [ "$stderr" = "pd-run: error: $2" ] &&
        [ ! -e "$BATS_TEST_TMPDIR/r.h5" ] || { echo "pd-run: $status: $stderr"; return 1; }
}

@test "unknown format version" {
    refused_by_run version-99.h5 "'version-99.h5': pd-h5 format version 99, this pd reads versions 1 to 2"
}

@test "HDF5 without pd_format" {
    refused_by_run no-format.h5 "'no-format.h5' is an HDF5 file but not a pd-h5 file (no pd_format)"
}

@test "volume stored as int32" {
    refused_by_run volume-int32.h5 "'volume-int32.h5': dataset '/particles/volume' is int32, expected float64"
}

@test "positions of shape (N,2)" {
    refused_by_run position-n2.h5 "'position-n2.h5': dataset '/particles/position' has 2 entries along axis 1, expected 3"
}

@test "density shorter than the positions" {
    refused_by_run density-short.h5 "'density-short.h5': dataset '/particles/density' has 26 entries along axis 0, expected 27"
}

@test "a volume that is NaN" {
    refused_by_run volume-nan.h5 "'volume-nan.h5': particle 0 has volume nan"
}

@test "two particles with the same id" {
    refused_by_run id-duplicate.h5 "'id-duplicate.h5': particle id 1 appears twice"
}

@test "an id of 0" {
    refused_by_run id-zero.h5 "'id-zero.h5': particle 0 has id 0 (ids start at 1)"
}

@test "CSR offsets that decrease" {
    refused_by_run offset-decreasing.h5 "'offset-decreasing.h5': /bonds/offset decreases at row 2"
}

@test "offsets declaring more bonds than memory holds" {
    refused_by_run offset-huge.h5 "'offset-huge.h5': /bonds/offset declares 1152921504606846976 bonds, more than memory"
}

@test "a neighbour index out of range" {
    refused_by_run neighbor-out-of-range.h5 "'neighbor-out-of-range.h5': bond 0 points to particle 1000000 of 27"
}

@test "a particle bonded to itself" {
    refused_by_run neighbor-self.h5 "'neighbor-self.h5': particle 0 is bonded to itself"
}

@test "a bond broken on one side only" {
    refused_by_run state-one-side.h5 "'state-one-side.h5': bond 0-1 is broken on one side only (state bits differ)"
}

@test "a negative bond length" {
    refused_by_run length-negative.h5 "'length-negative.h5': bond 0 has length -1"
}

@test "a partial-volume factor of 2" {
    refused_by_run vfactor-two.h5 "'vfactor-two.h5': bond 0 has volume factor 2"
}

@test "a pre-cracked bond that is intact in /bonds/state" {
    refused_by_run precrack-intact.h5 "'precrack-intact.h5': bond 0-3 is pre-cracked (/bonds/precrack) but intact in /bonds/state"
}

@test "a bond pre-cracked on one side only" {
    refused_by_run precrack-one-side.h5 "'precrack-one-side.h5': bond 0-1 is pre-cracked on one side only (precrack bits differ)"
}

@test "a /bonds/precrack too short" {
    refused_by_run precrack-short.h5 "'precrack-short.h5': dataset '/bonds/precrack' has 31 entries along axis 0, expected 32"
}

@test "a run without bonds (the wrong stage)" {
    refused_by_run no-bonds.h5 "'no-bonds.h5' has no /bonds (run pd-bonds first)" \
        "'no-bonds.h5' has no damage data: no /bonds (run pd-bonds first)"
}

# refused_with_restart FILE MESSAGE: pd-run --restart too, on a copy,
# with -o and in place: exit 1 with exactly this line, no output written
# and the run left as it was.
refused_with_restart() {
    refused "$@" || return 1
    local dir=$BATS_TEST_TMPDIR/restart
    mkdir -p "$dir" && cp "$1" "$dir/" || return 1
    (
        cd "$dir" || exit 1
        run --separate-stderr pd-run --restart "$1" --steps 1 -q -o r.h5
        [ "$status" -eq 1 ] && [ "$stderr" = "pd-run: error: $2" ] && [ ! -e r.h5 ] ||
            { echo "pd-run --restart -o: $status: $stderr"; exit 1; }
        cmp "$1" "$FIXTURES/$1" || exit 1
        run --separate-stderr pd-run --restart "$1" --steps 1 -q
        [ "$status" -eq 1 ] && [ "$stderr" = "pd-run: error: $2" ] ||
            { echo "pd-run --restart: $status: $stderr"; exit 1; }
        cmp "$1" "$FIXTURES/$1" || exit 1
        assert_no_temp .
        [ "$(ls -A)" = "$1" ] || { echo "left behind: $(ls -A)"; exit 1; }
    )
}

@test "a frame without its step" {
    refused_with_restart frame-no-step.h5 "'frame-no-step.h5': frame '00000001' has no step attribute"
}

# Frame attributes: for the complete frames in step order, steps are
# non-negative and strictly increasing, times finite, non-decreasing and
# step x dt (/scene dt) to 1e-9 relative.

@test "a frame without its time" {
    refused_with_restart frame-no-time.h5 "'frame-no-time.h5': frame '00000001' has no time attribute"
}

@test "a frame whose time is a string" {
    refused_with_restart frame-time-string.h5 "'frame-time-string.h5': frame '00000001': attribute 'time' has the wrong type or shape"
}

@test "a frame whose time is NaN" {
    refused_with_restart frame-time-nan.h5 "'frame-time-nan.h5': frame '00000001' has time nan; times must be finite"
}

@test "a frame whose time is +inf" {
    refused_with_restart frame-time-inf.h5 "'frame-time-inf.h5': frame '00000001' has time inf; times must be finite"
}

@test "a frame with a negative step" {
    refused_with_restart frame-step-negative.h5 "'frame-step-negative.h5': frame '00000001' has step -5; steps must be non-negative"
}

@test "two frames with the same step" {
    refused_with_restart frame-step-duplicate.h5 "'frame-step-duplicate.h5': frame '00000001' has step 0, as frame '00000000' does; steps must be strictly increasing"
}

@test "a frame whose time is before the previous frame's" {
    refused_with_restart frame-time-decreasing.h5 "'frame-time-decreasing.h5': frame '00000001' has time -0.001, before frame '00000000' (time 0); times must not decrease"
}

@test "a frame whose time is not step x dt" {
    refused_with_restart frame-time-dt.h5 "'frame-time-dt.h5': frame '00000001' has time 0.0015, not step x dt = 1 x 0.001 = 0.001 (/scene dt)"
}

@test "a run whose /scene dt is NaN" {
    refused_with_restart scene-dt-nan.h5 "'scene-dt-nan.h5': /scene has dt nan; dt must be positive and finite"
}

@test "frame times within the tolerance of step x dt are read; beyond it refused" {
    cd "$BATS_TEST_TMPDIR"
    # the valid run of the corpus: frame-time-dt.h5 with its time put back
    for rel in 5e-10 -5e-10 2e-9; do
        cp "$FIXTURES/frame-time-dt.h5" t.h5
        py "
with h5py.File(sys.argv[1], 'a') as f:
    dt = f['scene'].attrs['dt']
    f['frames/00000001'].attrs['time'] = dt * (1 + float(sys.argv[2]))" t.h5 $rel
        if [ $rel = 2e-9 ]; then
            run --separate-stderr pd-damage -n t.h5
            [ "$status" -eq 1 ]
            [[ "$stderr" == "pd-damage: error: 't.h5': frame '00000001' has time 0.001000000002, not step x dt = 1 x 0.001 = 0.001 (/scene dt)" ]]
        else
            run -0 pd-damage -n t.h5
            run -0 pd-crack-tip t.h5
        fi
    done
}

@test "a frame whose state is too short" {
    refused frame-state-short.h5 "'frame-state-short.h5': dataset '/frames/00000001/state' has 31 entries along axis 0, expected 32"
}

# ------------------------------------------------------------ newer parts:
# /sets, frame stress, plates, the projectile's restart state

# refused_by_model_readers FILE MESSAGE: the programs that read /sets
# (pd-bonds, pd-run) exit 1 with exactly this line and write no output.
refused_by_model_readers() {
    local out=$BATS_TEST_TMPDIR/o.h5
    run --separate-stderr pd-bonds --horizon 1.5 -q "$1" -o "$out"
    [ "$status" -eq 1 ] && [ "$stderr" = "pd-bonds: error: $2" ] && [ ! -e "$out" ] ||
        { echo "pd-bonds: $status: $stderr"; return 1; }
    run --separate-stderr pd-run --c 1e3 --steps 1 -q "$1" -o "$out"
    [ "$status" -eq 1 ] && [ "$stderr" = "pd-run: error: $2" ] && [ ! -e "$out" ] ||
        { echo "pd-run: $status: $stderr"; return 1; }
}

@test "a /sets member with an id that is no particle's" {
    refused_by_model_readers set-unknown-id.h5 "'set-unknown-id.h5': set 'right': id 1000 is no particle's"
}

@test "a /sets member stored as float64" {
    refused_by_model_readers set-float.h5 "'set-float.h5': dataset '/sets/left' is float64, expected int64"
}

@test "a /sets member whose ids descend" {
    refused_by_model_readers set-unsorted.h5 "'set-unsorted.h5': set 'left': ids are not strictly ascending"
}

@test "a frame stress of shape (N,3,2) (pd-dump2vtk reads it)" {
    local out=$BATS_TEST_TMPDIR/out
    run --separate-stderr pd-dump2vtk -q stress-shape.h5 -o "$out/vtk"
    [ "$status" -eq 1 ]
    [ "$stderr" = "pd-dump2vtk: error: 'stress-shape.h5': dataset '/frames/00000000/stress' is not a (27,3,3) float dataset" ]
    ! compgen -G "$out/vtk/*.pvd" >/dev/null
    # the readers that do not look at the stress read the file
    run -0 pd-damage -n stress-shape.h5
}

@test "a plate (dimension 2) without its thickness" {
    refused_by_run plate-no-thickness.h5 "'plate-no-thickness.h5': /particles of dimension 2 without a thickness"
}

@test "a plate (dimension 2) with a particle off the plane z = 0" {
    refused_by_run plate-z.h5 "'plate-z.h5': particle 0 of a plate (dimension 2) has z = 0.5, not 0"
}

@test "a restart slot whose projectile state is one value short (pd-run --restart)" {
    # on a copy: a restart updates its run in place unless -o is given
    cp restart-projectile-short.h5 "$BATS_TEST_TMPDIR/"
    cd "$BATS_TEST_TMPDIR"
    run --separate-stderr pd-run --restart restart-projectile-short.h5 --steps 1 -q -o r.h5
    [ "$status" -eq 1 ]
    [ "$stderr" = "pd-run: error: 'restart-projectile-short.h5': /restart/1: attribute 'projectile' has the wrong type or shape" ]
    [ ! -e r.h5 ]
    cmp restart-projectile-short.h5 "$FIXTURES/restart-projectile-short.h5"
    run --separate-stderr pd-run --restart restart-projectile-short.h5 --steps 1 -q
    [ "$status" -eq 1 ]
    cmp restart-projectile-short.h5 "$FIXTURES/restart-projectile-short.h5"
    assert_no_temp .
}

@test "a restart slot whose projectile velocity is NaN (pd-run --restart)" {
    cp restart-projectile-nan.h5 "$BATS_TEST_TMPDIR/"
    cd "$BATS_TEST_TMPDIR"
    run --separate-stderr pd-run --restart restart-projectile-nan.h5 --steps 1 -q -o r.h5
    [ "$status" -eq 1 ]
    [ "$stderr" = "pd-run: error: 'restart-projectile-nan.h5': /restart/1: the projectile state holds nan" ]
    [ ! -e r.h5 ]
    cmp restart-projectile-nan.h5 "$FIXTURES/restart-projectile-nan.h5"
}

@test "hostile but valid /sets go through pd-bonds and pd-run unchanged; an unknown one is refused" {
    cd "$BATS_TEST_TMPDIR"
    pd-lattice -q --spacing 1 --density 1000 --box 0,3,0,3,0,3 --set left=box,0,0,0,3,0,3 -o l.h5
    # names at the edge of what is allowed, one id, every id, the largest id
    py "
with h5py.File(sys.argv[1], 'a') as f:
    ids = np.sort(f['particles/id'][:])
    f['sets/' + 'x' * 63] = ids[:1]
    f['sets/.-_9'] = ids
    f['sets/...'] = ids[-1:]
    f['sets/A'] = ids[::7]
" l.h5
    run -0 pd-bonds -q --horizon 1.5 l.h5 -o m.h5
    run -0 pd-run -q --c 1e3 --steps 2 --velocity-bc ...,z,-1 --velocity-bc .-_9,x,0 m.h5 -o r.h5
    py "
files = [h5py.File(a) for a in sys.argv[1:]]
want = {k: v[:] for k, v in files[0]['sets'].items()}
assert len(want) == 5, sorted(want)
for f in files[1:]:
    got = {k: v[:] for k, v in f['sets'].items()}
    assert sorted(got) == sorted(want), (sorted(got), sorted(want))
    for k in want:
        assert got[k].dtype == np.int64 and np.array_equal(got[k], want[k]), k
" l.h5 m.h5 r.h5
    expect_runtime_error "the model has no set 'top'" pd-run --c 1e3 --steps 1 --velocity-bc top,y,1 \
        m.h5 -o r2.h5
    [ ! -e r2.h5 ]
}

# ------------------------------------------------------------ /bonds as a
# stencil (pd-h5 format version 2): the corpus's block has the stencil of
# 18 offsets; its table, its lattice and its count are checked before the
# families it expands to are used

@test "a stencil offset of zero" {
    refused_by_run stencil-offset-zero.h5 "'stencil-offset-zero.h5': /bonds/stencil offset 2 is (0, 0, 0)"
}

@test "a stencil offset beyond the reach of 16 sites" {
    refused_by_run stencil-offset-far.h5 "'stencil-offset-far.h5': /bonds/stencil offset 9 is (17, 0, 0)"
}

@test "a stencil offset twice" {
    refused_by_run stencil-offset-twice.h5 "'stencil-offset-twice.h5': /bonds/stencil has offset (-1, 0, 0) twice"
}

@test "a stencil offset without its opposite" {
    refused_by_run stencil-no-opposite.h5 "'stencil-no-opposite.h5': /bonds/stencil has offset (-1, 0, 0) but not its opposite"
}

@test "a stencil length of zero" {
    refused_by_run stencil-length-zero.h5 "'stencil-length-zero.h5': /bonds/stencil offset 2 has length 0 and volume factor 1"
}

@test "a stencil offset beyond the horizon" {
    refused_by_run stencil-beyond-horizon.h5 "'stencil-beyond-horizon.h5': /bonds/stencil offset (2, 0, 0) is 2 m long, beyond the horizon 1.5 m"
}

@test "a stencil length that is not its offset's" {
    refused_by_run stencil-length-wrong.h5 "'stencil-length-wrong.h5': /bonds/stencil_length of offset (0, 0, -1) is 5 m, not 1 m"
}

@test "a stencil volume factor of 1.5" {
    refused_by_run stencil-vfactor.h5 "'stencil-vfactor.h5': /bonds/stencil offset 0 has length 1.41421 and volume factor 1.5"
}

@test "a stencil without its spacing" {
    refused_by_run stencil-no-spacing.h5 "'stencil-no-spacing.h5': /bonds as a stencil needs the attributes origin (3) and spacing"
}

@test "a stencil whose origin has two values" {
    refused_by_run stencil-origin-2.h5 "'stencil-origin-2.h5': /bonds as a stencil needs the attributes origin (3) and spacing"
}

@test "a stencil whose /bonds@count is not the bonds it gives" {
    refused_by_run stencil-count.h5 "'stencil-count.h5': the stencil gives 252 bonds, /bonds@count says 254"
}

@test "a stencil in a file of format version 1, which had no stencil form" {
    refused_by_run stencil-version-1.h5 "'stencil-version-1.h5': /bonds as a stencil needs pd-h5 format version 2, the file says 1"
}

@test "a /bonds form that is neither csr nor stencil" {
    refused_by_run bonds-form-foo.h5 "'bonds-form-foo.h5': /bonds form 'foo' is neither 'csr' nor 'stencil'"
}

@test "a particle off the lattice of the stencil" {
    refused_by_run stencil-off-lattice.h5 "'stencil-off-lattice.h5': a particle is off the lattice of the bonds' stencil (spacing 1 m)"
}

@test "the corpus: the list fixtures are CSR, the others the stencil of pd-bonds' default" {
    py "
import glob
lists = ('offset-decreasing', 'offset-huge', 'neighbor-out-of-range', 'neighbor-self',
         'length-negative', 'vfactor-two')
for name in sorted(glob.glob('*.h5')):
    with h5py.File(name, 'r') as f:
        if 'bonds' not in f or name == 'bonds-form-foo.h5':
            continue
        b = f['bonds']
        form = b.attrs.get('form', 'csr')
        form = form.decode() if isinstance(form, bytes) else form
        want = 'csr' if name[:-3] in lists else 'stencil'
        assert form == want, (name, form)
        assert ('neighbor' in b) == (want == 'csr') and ('stencil' in b) == (want == 'stencil'), name
"
}

@test "every file of the corpus has a test here" {
    for f in *.h5; do
        grep -q "${f%.h5}.h5" "$BATS_TEST_FILENAME" || { echo "no test for $f"; return 1; }
    done
}
