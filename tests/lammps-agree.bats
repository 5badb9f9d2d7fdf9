#!/usr/bin/env bats
# pd-run against LAMMPS peri/pmb (`lmp`, Debian's lammps package): the same
# scene run by both codes must give positions that agree to 1e-9 relative
# and damage to 1e-12 (tests/lammps/compare.py defines the metrics; its
# displacement check, 1e-9 of the largest displacement, is the sharp one).
#
# The scene is a small version of seed 000's impact example: a disk of
# radius 6 mm and thickness 2.5 mm on the same 0.5 mm simple cubic lattice
# (2646 particles, horizon 0.0015001, c = 1.6863e22, s00 = 0.0005,
# alpha = 0.25, dt = 1e-7), hit by the seed's sphere (R = 5 mm, K = 1e17)
# that starts touching the top face y = 0 and moves down at 100 m/s.
# tests/lammps/pd2lmp.py writes the LAMMPS data file (bit-identical
# positions, ids = /particles/id) and input script from pd's model file,
# with the scene parameters given explicitly (not read from pd's /scene).
#
# Every comparison also asserts that both codes broke bonds: a comparison
# without damage would prove nothing about failure.

load test_helper
bats_require_minimum_version 1.5.0

LMPTOOLS=$BATS_TEST_DIRNAME/lammps
# shellcheck disable=SC2054 # the commas belong to the values
DISK=(--spacing 0.0005 --cylinder y,0,0,0.006,-0.0025,0 --density 2200)
DISK_HORIZON=0.0015001
# pd-run is given one thread: the results do not depend on it, and a busy
# two-core machine runs these small models faster that way.
C=1.6863e22
FAILURE=0.0005,0.25
DT=1e-7
PMB_NO_CONTACT=(--c "$C" --failure "$FAILURE" --dt "$DT" --threads 1)
PMB=("${PMB_NO_CONTACT[@]}" --contact)
IND_SEED=sphere,0,0.0050,0,0.005,1e17,0,-100,0

# make_disk DIR [pd-lattice option]...: DIR/model.h5
make_disk() {
    local dir=$1
    shift
    mkdir -p "$dir"
    pd-lattice "${DISK[@]}" "$@" -q -o "$dir/lattice.h5" &&
        pd-bonds --horizon "$DISK_HORIZON" -q "$dir/lattice.h5" -o "$dir/model.h5"
}

# run_pd DIR OUT STEPS EVERY [pd-run option]...: DIR/OUT from DIR/model.h5,
# with damage added by pd-damage.
run_pd() {
    local dir=$1 out=$2 steps=$3 every=$4
    shift 4
    pd-run "$dir/model.h5" "${PMB[@]}" --steps "$steps" --every "$every" "$@" -q \
        -o "$dir/$out" &&
        pd-damage "$dir/$out" >/dev/null
}

# run_lmp DIR STEPS EVERY INDENTER: the same scene run by LAMMPS from
# DIR/model.h5, its parameters given here rather than read from pd's /scene
# (so a parameter pd-run misreads is a disagreement too); DIR/dump.lmp.
run_lmp() {
    local dir=$1 steps=$2 every=$3 ind=$4
    "$PY" "$LMPTOOLS/pd2lmp.py" "$dir/model.h5" -d "$dir/data.lmp" -i "$dir/in.lmp" \
        --dump dump.lmp --c "$C" --horizon "$DISK_HORIZON" --failure "$FAILURE" \
        --dt "$DT" --steps "$steps" --every "$every" --indenter "$ind" || return 1
    (cd "$dir" && lmp -in in.lmp -log none >lmp.out 2>&1) || {
        cat "$dir/lmp.out"
        return 1
    }
}

# compare RUN DUMP [compare.py option]...: sets $output/$status.
compare() {
    run "$PY" "$LMPTOOLS/compare.py" "$@"
}

# count WHAT: from compare.py's $output, "pd N lammps M" of line WHAT.
count() {
    local line
    line=$(grep "^$1 " <<<"$output") || return 1
    read -r _ _ pd _ lmp <<<"$line"
    echo "$pd $lmp"
}

# assert_damage_in_both: both codes have damaged particles and broken bonds,
# the same numbers.
assert_damage_in_both() {
    local pd lmp
    read -r pd lmp < <(count damaged)
    [ "$pd" -gt 0 ] && [ "$lmp" -gt 0 ] && [ "$pd" -eq "$lmp" ] ||
        fail "damaged particles: pd $pd, LAMMPS $lmp"
    read -r pd lmp < <(count broken)
    [ "$pd" -gt 0 ] && [ "$lmp" -gt 0 ] && [ "$pd" -eq "$lmp" ] ||
        fail "broken bonds: pd $pd, LAMMPS $lmp"
}

setup_file() {
    PATH="$BATS_TEST_DIRNAME/../bin:$PATH"
    command -v lmp >/dev/null || return 0
    # the main scene, shared by the agreement test and the negative control
    local d=$BATS_FILE_TMPDIR/seed
    make_disk "$d" &&
        run_pd "$d" run.h5 100 50 --indenter "$IND_SEED" &&
        run_lmp "$d" 100 50 "$IND_SEED"
}

setup() {
    command -v lmp >/dev/null || skip "lmp (LAMMPS with the PERI package) is not installed"
}

@test "pd-run agrees with LAMMPS peri/pmb: disk, failure + contact + indenter, 100 steps" {
    local d=$BATS_FILE_TMPDIR/seed
    for step in 50 100; do
        compare "$d/run.h5" "$d/dump.lmp" --step "$step"
        assert_success
        assert_line --partial "OK"
    done
    # by step 100 the sphere is 1 mm deep: a few hundred damaged particles
    compare "$d/run.h5" "$d/dump.lmp" --step 100 --min-damaged 100
    assert_success
    assert_damage_in_both
}

@test "pd-run agrees with LAMMPS peri/pmb on a perturbed lattice" {
    # nodes off the lattice sites: bond lengths and partial-volume factors
    # differ bond by bond, and some 3-spacing bonds fall outside the horizon
    local d=$BATS_TEST_TMPDIR/perturbed
    make_disk "$d" --perturb 1e-5 --seed 3
    run_pd "$d" run.h5 100 100 --indenter "$IND_SEED"
    run_lmp "$d" 100 100 "$IND_SEED"
    compare "$d/run.h5" "$d/dump.lmp" --step 100 --min-damaged 100
    assert_success
    assert_damage_in_both
}

@test "pd-run agrees with LAMMPS peri/pmb when contact forces act" {
    # a stiffer, faster sphere crushes the disk: particles come closer than
    # the short-range distance d_ij (seed 000 eq. 15)
    local d=$BATS_TEST_TMPDIR/crush ind=sphere,0,0.0050,0,0.005,1e18,0,-200,0
    make_disk "$d"
    run_pd "$d" run.h5 100 100 --indenter "$ind"
    run_lmp "$d" 100 100 "$ind"
    compare "$d/run.h5" "$d/dump.lmp" --step 100 --min-damaged 100
    assert_success
    assert_damage_in_both
    # contact is really exercised: without it pd no longer agrees
    pd-run "$d/model.h5" "${PMB_NO_CONTACT[@]}" --indenter "$ind" --steps 100 -q \
        -o "$d/nocontact.h5"
    compare "$d/nocontact.h5" "$d/dump.lmp" --step 100
    assert_failure 1
    assert_line --partial "FAIL: positions"
}

@test "no bond breaks in the first step, in pd as in LAMMPS (s0 starts at +inf)" {
    # the sphere starts 0.5 mm deep and pushes hard: bonds are stretched
    # beyond s00 already at step 1, yet neither code breaks them before
    # step 2, when s0 of step 1 is known
    local d=$BATS_TEST_TMPDIR/first ind=sphere,0,0.0045,0,0.005,1e19,0,0,0
    make_disk "$d"
    run_pd "$d" run.h5 2 1 --indenter "$ind" --allow-overlap
    run_lmp "$d" 2 1 "$ind"
    run -0 py "
with h5py.File(sys.argv[1]) as h:
    x = h['particles/position'][...]
    off, nb, L, _ = pdh5.bonds(h)
    i = np.repeat(np.arange(len(x)), np.diff(off))
    y = x + h['frames/00000001/displacement'][...]
    s = (np.linalg.norm(y[nb] - y[i], axis=1) - L) / L
    print(int((s > 0.0005).sum()))" "$d/run.h5"
    [ "$output" -gt 0 ] || fail "no bond is stretched beyond s00 at step 1"
    compare "$d/run.h5" "$d/dump.lmp" --step 1
    assert_success
    assert_line --regexp "^broken +pd 0  lammps 0$"
    compare "$d/run.h5" "$d/dump.lmp" --step 2
    assert_success
    assert_damage_in_both
}

@test "the comparison fails when pd and LAMMPS disagree (negative control)" {
    # a micromodulus 6e-5 off: pd and LAMMPS then differ by ~7e-8 relative
    local d=$BATS_FILE_TMPDIR/seed
    pd-run "$d/model.h5" "${PMB[@]}" --c 1.6864e22 --indenter "$IND_SEED" --steps 100 -q \
        -o "$BATS_TEST_TMPDIR/off.h5"
    compare "$BATS_TEST_TMPDIR/off.h5" "$d/dump.lmp" --step 100
    assert_failure 1
    assert_line --partial "FAIL: positions"
}

# ---------------------------------------------------------------- LPS
# The same disk with pair_style peri/lps (K, G; LAMMPS's influence function
# 1/r, pd's default).  3K - 5G is far from 0 in both scenes, so the
# dilatation term of the force (seed 000 Algorithm 2) is exercised.
K=14.9e9

# run_lps DIR G STEPS EVERY IND FAILURE: pd and LAMMPS on DIR/model.h5
# (FAILURE "none": no bond breaks; LAMMPS gets s00 = 1e300), both with
# contact (LAMMPS's peri styles always have it).
run_lps() {
    local dir=$1 g=$2 steps=$3 every=$4 ind=$5 failure=$6 pdfail=() lmpfail=()
    if [ "$failure" = none ]; then
        lmpfail=(--no-failure)
    else
        pdfail=(--failure "$failure")
        lmpfail=(--failure "$failure")
    fi
    pd-run "$dir/model.h5" --model lps --bulk-modulus "$K" --shear-modulus "$g" "${pdfail[@]}" \
        --contact --dt "$DT" --threads 1 --indenter "$ind" --steps "$steps" --every "$every" -q \
        -o "$dir/run.h5" && pd-damage "$dir/run.h5" >/dev/null || return 1
    "$PY" "$LMPTOOLS/pd2lmp.py" "$dir/model.h5" -d "$dir/data.lmp" -i "$dir/in.lmp" \
        --dump dump.lmp --model lps --bulk-modulus "$K" --shear-modulus "$g" \
        --horizon "$DISK_HORIZON" "${lmpfail[@]}" --dt "$DT" --steps "$steps" --every "$every" \
        --indenter "$ind" || return 1
    grep -q "^pair_style *peri/lps" "$dir/in.lmp" || return 1
    (cd "$dir" && lmp -in in.lmp -log none >lmp.out 2>&1) || {
        cat "$dir/lmp.out"
        return 1
    }
}

@test "pd-run --model lps agrees with LAMMPS peri/lps: elastic disk pressed by the sphere" {
    local d=$BATS_TEST_TMPDIR/lps-elastic
    make_disk "$d"
    run_lps "$d" 5e9 100 50 sphere,0,0.0050,0,0.005,1e17,0,-20,0 none
    for step in 50 100; do
        compare "$d/run.h5" "$d/dump.lmp" --step "$step"
        assert_success
        assert_line --partial "OK"
        assert_line --regexp "^broken +pd 0  lammps 0$"
    done
    # a shear modulus 1e-5 off is seen (negative control of this scene)
    pd-run "$d/model.h5" --model lps --bulk-modulus "$K" --shear-modulus 5.00005e9 --contact \
        --dt "$DT" --threads 1 --indenter sphere,0,0.0050,0,0.005,1e17,0,-20,0 --steps 100 -q \
        -o "$d/off.h5"
    compare "$d/off.h5" "$d/dump.lmp" --step 100
    assert_failure 1
    assert_line --partial "FAIL: displacements"
}

@test "pd-run --model lps agrees with LAMMPS peri/lps: failure, contact and the indenter" {
    local d=$BATS_TEST_TMPDIR/lps-failure
    make_disk "$d"
    run_lps "$d" 8e9 100 50 "$IND_SEED" "$FAILURE"
    compare "$d/run.h5" "$d/dump.lmp" --step 50
    assert_success
    compare "$d/run.h5" "$d/dump.lmp" --step 100 --min-damaged 100
    assert_success
    assert_damage_in_both
}

@test "pd-run --model lps agrees with LAMMPS peri/lps on a perturbed lattice, crushed" {
    # unequal bond lengths and partial volumes; a stiff fast sphere brings
    # particles within the contact distance.  It starts 30 um above the top
    # face: LAMMPS peri/lps breaks every bond stretched at all in the first
    # step (its s0 is not +inf there, unlike peri/pmb and seed 000
    # Algorithm 2, which pd follows), so nothing may stretch in step 1.
    local d=$BATS_TEST_TMPDIR/lps-perturbed
    make_disk "$d" --perturb 1e-5 --seed 3
    run_lps "$d" 8e9 100 100 sphere,0,0.00503,0,0.005,1e18,0,-200,0 "$FAILURE"
    compare "$d/run.h5" "$d/dump.lmp" --step 100 --min-damaged 100
    assert_success
    assert_damage_in_both
}

# ---------------------------------------------------------------- VES
# pair_style peri/ves (Mitchell SAND2011-8064): K, G as LPS plus the
# viscous fraction lambda and the relaxation time tau.  tau = 40 steps, so
# the back extension moves a lot within the run (decay exp(-1/40) per
# step), and lambda = 0.5 weighs both branches alike.  VES's stable step
# is smaller than LPS's (see lib/models/lps.c), hence dt = 5e-8 s; the sphere
# goes twice as fast to reach the same depth as the LPS scenes.
VES_DT=5e-8
VES=(--ves-lambda 0.5 --ves-tau 2e-6)

# run_ves DIR STEPS EVERY IND [pd-run option]...: pd and LAMMPS on
# DIR/model.h5, failure, contact and the indenter.
run_ves() {
    local dir=$1 steps=$2 every=$3 ind=$4
    shift 4
    pd-run "$dir/model.h5" --model ves --bulk-modulus "$K" --shear-modulus 8e9 "${VES[@]}" \
        --failure "$FAILURE" --contact --dt "$VES_DT" --threads 1 --indenter "$ind" \
        --steps "$steps" --every "$every" -q -o "$dir/run.h5" "$@" &&
        pd-damage "$dir/run.h5" >/dev/null || return 1
    "$PY" "$LMPTOOLS/pd2lmp.py" "$dir/model.h5" -d "$dir/data.lmp" -i "$dir/in.lmp" \
        --dump dump.lmp --model ves --bulk-modulus "$K" --shear-modulus 8e9 "${VES[@]}" \
        --horizon "$DISK_HORIZON" --failure "$FAILURE" --dt "$VES_DT" --steps "$steps" \
        --every "$every" --indenter "$ind" || return 1
    grep -q "^pair_style *peri/ves" "$dir/in.lmp" || return 1
    (cd "$dir" && lmp -in in.lmp -log none >lmp.out 2>&1) || {
        cat "$dir/lmp.out"
        return 1
    }
}

@test "pd-run --model ves agrees with LAMMPS peri/ves: failure, contact and the indenter" {
    local d=$BATS_TEST_TMPDIR/ves ind=sphere,0,0.0050,0,0.005,1e17,0,-200,0
    make_disk "$d"
    run_ves "$d" 100 50 "$ind"
    compare "$d/run.h5" "$d/dump.lmp" --step 50
    assert_success
    compare "$d/run.h5" "$d/dump.lmp" --step 100 --min-damaged 100
    assert_success
    assert_damage_in_both
    # negative controls: lambda 2e-4 or tau 1e-4 off is seen, so both
    # parameters are in play
    for off in "--ves-lambda 0.5001" "--ves-tau 2.0002e-6"; do
        # shellcheck disable=SC2086 # two words
        pd-run "$d/model.h5" --model ves --bulk-modulus "$K" --shear-modulus 8e9 "${VES[@]}" \
            $off --failure "$FAILURE" --contact --dt "$VES_DT" --threads 1 --indenter "$ind" \
            --steps 100 -q -o "$d/off.h5"
        compare "$d/off.h5" "$d/dump.lmp" --step 100
        assert_failure 1
        assert_line --regexp "^FAIL:.*displacements"
    done
}

@test "pd-run --model ves agrees with LAMMPS peri/ves on a perturbed lattice, crushed" {
    # as the LPS scene: unequal bonds, a stiff fast sphere (contact forces
    # act) that starts above the top face
    local d=$BATS_TEST_TMPDIR/ves-perturbed
    make_disk "$d" --perturb 1e-5 --seed 3
    run_ves "$d" 100 100 sphere,0,0.00503,0,0.005,1e18,0,-400,0
    compare "$d/run.h5" "$d/dump.lmp" --step 100 --min-damaged 100
    assert_success
    assert_damage_in_both
}

# ---------------------------------------------------------------- EPS
# pair_style peri/eps (Mitchell SAND2011-3166) is compared, not matched:
# pd follows a corrected form (pd-run(1), MODELS), and the test shows where
# the two differ and why.  LAMMPS 20220106 (Debian's) peri/eps
#  - has as elastic part the pair form of peri/ves with lambda = 0: the
#    deviatoric extension of bond i-j with theta_i for both ends.  pd's
#    --model ves --ves-lambda 0 reproduces it to 1e-13 (checked here), and
#    on this scene it differs from LPS (and so from pd's EPS below yield,
#    which is LPS to rounding) by 0.31 of the largest displacement, with 113
#    damaged particles where LPS has none;
#  - weighs its yield norm by theta ((omega theta_i/m_i + omega theta_j/m_j)
#    where the trial state has omega/m_i), so the norm is ~theta ~1e-4 of the
#    force state's: at Y = 5e6 Pa it never yields (its dump equals that of
#    Y = 1e30 byte for byte), while pd's plastic extensions reach ~9e-6 m;
#  - adds Delta-lambda t^d to the plastic extension with t^d the pair sum of
#    both ends: the increment carries omega (1 + m_i/m_j) ~ 2/|xi| (1/m) too
#    many, so where it yields (Y = 5e3 Pa here) its positions go NaN within
#    100 steps.
# Measured, step 100, Y = 5e6 Pa: pd EPS against LAMMPS peri/eps 0.45 of
# the largest displacement, damaged particles pd 171, LAMMPS 113.
@test "pd-run --model eps against LAMMPS peri/eps: the difference, and where it comes from" {
    local d=$BATS_TEST_TMPDIR/eps ind=sphere,0,0.0050,0,0.005,1e17,0,-200,0 y
    make_disk "$d"
    for y in 5e6 1e30; do
        "$PY" "$LMPTOOLS/pd2lmp.py" "$d/model.h5" -d "$d/data.lmp" -i "$d/in.lmp" \
            --dump "dump-$y.lmp" --model eps --bulk-modulus "$K" --shear-modulus 8e9 \
            --yield-stress "$y" --horizon "$DISK_HORIZON" --failure "$FAILURE" --dt "$VES_DT" \
            --steps 100 --every 100 --indenter "$ind"
        grep -q "^pair_style *peri/eps" "$d/in.lmp"
        (cd "$d" && lmp -in in.lmp -log none >lmp.out 2>&1) || fail "$(cat "$d/lmp.out")"
        pd-run "$d/model.h5" --model eps --bulk-modulus "$K" --shear-modulus 8e9 \
            --yield-stress "$y" --failure "$FAILURE" --contact --dt "$VES_DT" --threads 1 \
            --indenter "$ind" --steps 100 --every 100 -q -o "$d/eps-$y.h5"
        pd-damage "$d/eps-$y.h5" >/dev/null
    done
    # LAMMPS peri/eps does not yield at 5e6 Pa; pd does
    cmp "$d/dump-5e6.lmp" "$d/dump-1e30.lmp"
    run -0 py "
with h5py.File(sys.argv[1]) as f:
    e = abs(f['restart/0/bond_history'][...]).max(), abs(f['restart/1/bond_history'][...]).max()
    print(max(e))
    assert max(e) > 1e-6, e" "$d/eps-5e6.h5"
    # the elastic part of peri/eps is pd's VES at lambda = 0
    pd-run "$d/model.h5" --model ves --ves-lambda 0 --ves-tau 1 --bulk-modulus "$K" \
        --shear-modulus 8e9 --failure "$FAILURE" --contact --dt "$VES_DT" --threads 1 \
        --indenter "$ind" --steps 100 --every 100 -q -o "$d/ves0.h5"
    pd-damage "$d/ves0.h5" >/dev/null
    compare "$d/ves0.h5" "$d/dump-1e30.lmp" --step 100 --min-damaged 100
    assert_success
    # pd's EPS: the difference (stated above)
    compare "$d/eps-5e6.h5" "$d/dump-5e6.lmp" --step 100
    assert_failure 1
    assert_line --regexp "^FAIL:.*displacements"
}
