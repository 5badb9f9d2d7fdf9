#!/usr/bin/env bats
# The same bits: every output of this tree's programs is bit for bit that of
# the baseline commit (tests/samebits/BASELINE) on a matrix of small scenes
# (tests/samebits/matrix.sh), so a refactor of lib/ and cmd/ that should
# change nothing is shown to change nothing: the models of pd-lattice and
# pd-bonds, pd-run's runs (every dataset and attribute, bit for bit, but the
# command lines of the history), its log (but the wall-clock line),
# pd-damage's files and tables and pd-crack-tip's table.
#
# The baseline is built from git (tests/samebits/build-baseline.sh, once per
# commit and build setting, in tests/tmp/samebits/) rather than stored as
# checksums of its outputs: the bits of a floating-point result depend on
# the processor and the compiler.  The bond loops are compiled for AVX-512,
# AVX2 and the x86-64 baseline and pick one at run time, and on an AVX-512
# processor the stencil walks its rows in tiles, so two machines give runs
# that agree to rounding but not bit for bit.  Both builds run here, on the
# same processor with the same compiler and flags (SANITIZE, CC, CFLAGS),
# and only the source differs.  A clone without the baseline commit (a
# shallow one) fails here: fetch it.
#
# Moving the baseline: when a commit changes outputs on purpose, it puts
# its own hash (or a later one) in tests/samebits/BASELINE and says in its
# message which outputs changed and why.  A refactor never moves it.

load test_helper

LOG_SKIP=' steps in [0-9.]+ s '

setup_file() {
    SAMEBITS_OLD=$("$BATS_TEST_DIRNAME/samebits/build-baseline.sh")
    export SAMEBITS_OLD
}

setup() {
    cd "$BATS_TEST_TMPDIR"
    [ -n "${SAMEBITS_OLD:-}" ] || fail "the baseline was not built"
}

# _scene BIN DIR NAME: run scene_NAME of matrix.sh in the new folder DIR
# with the programs of BIN first on PATH; its messages go to DIR.out.
_scene() {
    local bin=$1 out=$2 scene=$3
    mkdir -p "$out"
    if ! PATH="$bin:$PATH" bash -e -c '. "$1"; cd "$2"; "scene_$3"' _ \
            "$BATS_TEST_DIRNAME/samebits/matrix.sh" "$out" "$scene" >"$out.out" 2>&1; then
        { echo "scene $scene failed with the programs of $bin:"; cat "$out.out"; } |
            batslib_decorate "scene $scene failed" | fail
        return 1
    fi
}

# same_bits NAME: scene NAME with the baseline's programs (old/) and this
# tree's (new/) leaves the same files with the same bits.  Prints every file
# that differs, and its first difference.
same_bits() {
    local scene=$1 f
    _scene "$SAMEBITS_OLD/bin" old "$scene" || return 1
    _scene "$BATS_TEST_DIRNAME/../bin" new "$scene" || return 1
    local diffs=() h5=()
    if [ "$(cd old && ls)" != "$(cd new && ls)" ]; then
        diffs+=("not the same files: old has $(cd old && echo *), new has $(cd new && echo *)")
    fi
    for f in $(cd old && ls); do
        [ -f "new/$f" ] || continue
        case $f in
        *.h5)
            h5+=("old/$f" "new/$f")
            ;;
        *.log)
            # all of the log but the wall-clock line (N steps in T s ...)
            if ! diff <(grep -Ev "$LOG_SKIP" "old/$f") <(grep -Ev "$LOG_SKIP" "new/$f") \
                    >"$f.diff"; then
                diffs+=("new/$f: the log differs:" "$(head -n 6 "$f.diff")")
            fi
            ;;
        *)
            cmp -s "old/$f" "new/$f" ||
                diffs+=("new/$f: differs:" "$(diff "old/$f" "new/$f" | head -n 6)")
            ;;
        esac
    done
    local out
    if ! out=$("$PY" "$BATS_TEST_DIRNAME/samebits/h5same.py" "${h5[@]}" 2>&1); then
        diffs+=("$out")
    fi
    if [ ${#diffs[@]} -gt 0 ]; then
        printf '%s\n' "${diffs[@]}" |
            batslib_decorate "scene $scene: this tree's outputs are not the baseline's" | fail
        return 1
    fi
}

@test "same bits: PMB as a bond list, with failure, contact and the indenter (1 thread)" {
    same_bits pmb_list
}

@test "same bits: PMB on the lattice stencil (1 and 2 threads)" {
    same_bits pmb_stencil
}

@test "same bits: PMB on the stencil without the AVX-512 tiles (PD_NO_AVX512=1)" {
    same_bits pmb_stencil_no_avx512
}

@test "same bits: LPS as a bond list" {
    same_bits lps_list
}

@test "same bits: LPS on the lattice stencil (1 and 2 threads)" {
    same_bits lps_stencil
}

@test "same bits: VES (1 and 2 threads)" {
    same_bits ves
}

@test "same bits: EPS, yielding" {
    same_bits eps
}

@test "same bits: the projectile, with and without the indenter" {
    same_bits projectile
}

@test "same bits: velocity, displacement and body-force conditions on sets (PMB 1 and 2 threads, LPS)" {
    same_bits bc
}

@test "same bits: material laws and an interface on --material-region" {
    same_bits materials
}

@test "same bits: fibres" {
    same_bits fibre
}

@test "same bits: a pre-cracked 2-D plate, energy and stress fields, pd-damage and pd-crack-tip" {
    same_bits plate
}

@test "same bits: a perturbed lattice (bond lists), energy and stress fields (1 and 2 threads, LPS)" {
    same_bits perturbed
}

@test "same bits: restarts of the stencil, the LPS list and the boundary conditions" {
    same_bits restart
}

@test "build-baseline.sh: a commit the repository does not hold is one error line, not a skip" {
    run -1 --separate-stderr "$BATS_TEST_DIRNAME/samebits/build-baseline.sh" \
        0123456789abcdef0123456789abcdef01234567
    assert_one_error "^build-baseline.sh: error: the baseline commit 0123456789abcdef0123456789abcdef01234567 is not in the repository"
}
