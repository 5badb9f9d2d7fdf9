#!/usr/bin/env bats
# pd-run --no-failure SET: a bond with an end in SET never breaks.  A bar
# pulled apart by its grips, with failure: without the option the grips'
# bonds break as any; with it none does, on every kernel (the stencil with
# and without the AVX-512 tiles, the bond list, LPS on the stencil with
# and without them and on a perturbed lattice's list), while the bar still
# breaks between them.  The energy field of a frame counts a kept bond as
# intact (stencil and list agree), the option is recorded in /scene and
# kept through a restart, and bad uses are one-line errors.

load test_helper
bats_require_minimum_version 1.5.0

setup() {
    cd "$BATS_TEST_TMPDIR"
}

# _build_bar DIR: a 20 x 6 x 6 mm bar at 1 mm (horizon 3 spacings), its
# three planes at each end the sets left and right; and the same bar
# perturbed (its bonds as lists).
_build_bar() {
    local d=$1 grips=(--set left=box,-1,0.0025,-1,1,-1,1 --set right=box,0.0175,1,-1,1,-1,1)
    pd-lattice -q --spacing 0.001 --box 0,0.02,0,0.006,0,0.006 --density 2200 "${grips[@]}" \
        -o "$d/l.h5" &&
        pd-bonds -q --horizon 0.0030001 "$d/l.h5" -o "$d/bar.h5" &&
        pd-lattice -q --spacing 0.001 --box 0,0.02,0,0.006,0,0.006 --density 2200 "${grips[@]}" \
            --perturb 2e-5 -o "$d/p.h5" &&
        pd-bonds -q --horizon 0.0030001 "$d/p.h5" -o "$d/perturbed.h5"
}
make_bar() {
    _pd_cached no-failure-bar _build_bar || return 1
    cp "$_PD_CACHE/bar.h5" "$_PD_CACHE/perturbed.h5" .
}

PULL=(--failure 0.001,0 --velocity-bc left,x,-5 --velocity-bc right,x,5)
GRIPS=(--no-failure left --no-failure right)

# BROKEN RUN STEP: the broken bonds of frame STEP with an end in a grip, and
# the others
BROKEN='
f = h5py.File(sys.argv[1]); off, nb, _, _ = pdh5.bonds(f)
mu = pdh5.bits(f["frames/%08d/state" % int(sys.argv[2])], len(nb))
ids = f["particles/id"][:]
grip = np.isin(ids, np.concatenate([f["sets/left"][:], f["sets/right"][:]]))
rows = np.repeat(np.arange(len(ids)), np.diff(off))
touch = grip[rows] | grip[nb]
print((mu[touch] == 0).sum(), (mu[~touch] == 0).sum())
'

@test "no-failure: the grips' bonds never break on any kernel, and break without it" {
    make_bar
    local k=(--bulk-modulus 14e9) lps=(--model lps --bulk-modulus 14e9 --shear-modulus 9e9)
    pd-run -q "${k[@]}" "${PULL[@]}" --steps 300 --every 300 bar.h5 -o without.h5
    run py "$BROKEN" without.h5 300
    read -r touch other <<<"$output"
    [ "$touch" -gt 1000 ] && [ "$other" -gt 1000 ]
    for kernel in stencil tiles-off list lps lps-tiles-off lps-list; do
        case $kernel in
        stencil) pd-run -q "${k[@]}" "${PULL[@]}" "${GRIPS[@]}" --steps 300 --every 300 bar.h5 -o r.h5 ;;
        tiles-off) PD_NO_AVX512=1 pd-run -q "${k[@]}" "${PULL[@]}" "${GRIPS[@]}" --steps 300 \
            --every 300 bar.h5 -o r.h5 ;;
        list) pd-run -q "${k[@]}" "${PULL[@]}" "${GRIPS[@]}" --bond-list --steps 300 --every 300 \
            bar.h5 -o r.h5 ;;
        lps) pd-run -q "${lps[@]}" "${PULL[@]}" "${GRIPS[@]}" --steps 200 --every 200 bar.h5 -o r.h5 ;;
        lps-tiles-off) PD_NO_AVX512=1 pd-run -q "${lps[@]}" "${PULL[@]}" "${GRIPS[@]}" \
            --steps 200 --every 200 bar.h5 -o r.h5 ;;
        lps-list) pd-run -q "${lps[@]}" "${PULL[@]}" "${GRIPS[@]}" --steps 200 --every 200 \
            perturbed.h5 -o r.h5 ;;
        esac
        local last=300
        [[ $kernel == lps* ]] && last=200
        run py "$BROKEN" r.h5 $last
        read -r touch other <<<"$output"
        [ "$touch" -eq 0 ] || { echo "$kernel: $touch grip bonds broke"; false; }
        [ "$other" -gt 500 ] || { echo "$kernel: only $other bonds broke"; false; }
    done
}

@test "no-failure: a meshed bar's grips (Gmsh physical surfaces) hold as a lattice bar's do" {
    gmsh -v 0 -3 -format msh41 -o box.msh "$BATS_TEST_DIRNAME/fixtures/mesh/box.geo"
    pd-mesh -q --density 2200 box.msh -o m.h5
    pd-bonds -q --horizon 0.0016 m.h5 -o mb.h5
    pd-run -q --bulk-modulus 14e9 "${PULL[@]}" "${GRIPS[@]}" --steps 200 --every 200 mb.h5 -o r.h5
    run py "$BROKEN" r.h5 200
    read -r touch other <<<"$output"
    [ "$touch" -eq 0 ] && [ "$other" -gt 100 ]
    pd-run -q --bulk-modulus 14e9 "${PULL[@]}" --steps 200 --every 200 mb.h5 -o w.h5
    run py "$BROKEN" w.h5 200
    read -r touch other <<<"$output"
    [ "$touch" -gt 100 ]
}

@test "no-failure: a kept bond counts as intact in the energy field (stencil, with and without tiles, against the list)" {
    make_bar
    local base=(-q --bulk-modulus 14e9 "${PULL[@]}" "${GRIPS[@]}" --steps 80 --every 40 --fields energy)
    pd-run "${base[@]}" bar.h5 -o tiles.h5
    PD_NO_AVX512=1 pd-run "${base[@]}" bar.h5 -o plain.h5
    pd-run "${base[@]}" --bond-list bar.h5 -o list.h5
    py "
def W(name, fr):
    f = h5py.File(name + '.h5')
    return f['frames/%s/strain_energy_density' % fr][:][np.argsort(f['particles/id'][:])], \
        f['frames/%s' % fr].attrs['broken_bonds']
for fr in ('00000040', '00000080'):
    wl, bl = W('list', fr)
    assert bl > 1000, bl           # the bar is breaking, and its grips hold
    for name in ('tiles', 'plain'):
        w, b = W(name, fr)
        assert b == bl and np.abs(w - wl).max() < 1e-9 * np.abs(wl).max(), (name, fr)
"
}

@test "no-failure: recorded in /scene and the log, kept through a restart, the same bits at 1 and 2 threads" {
    make_bar
    run --separate-stderr pd-run --bulk-modulus 14e9 "${PULL[@]}" "${GRIPS[@]}" --steps 100 \
        --every 50 --threads 1 bar.h5 -o a.h5
    assert_success
    [[ "$stderr" =~ --no-failure\ left\ right:\ no\ bond\ of\ their\ 294\ particles\ breaks ]]  # 2 x 3 planes of 7 x 7
    pd-run -q --bulk-modulus 14e9 "${PULL[@]}" "${GRIPS[@]}" --steps 100 --every 50 --threads 2 \
        bar.h5 -o b.h5
    pd-run -q --restart a.h5 --steps 100 --every 50 -o c.h5
    py "
a, b, c = h5py.File('a.h5'), h5py.File('b.h5'), h5py.File('c.h5')
assert a['scene'].attrs['no_failure'] == 'left right' == c['scene'].attrs['no_failure']
opts = a['scene'].attrs['options'].split('\n')
assert 'no-failure left' in opts and 'no-failure right' in opts
for d in ('displacement', 'velocity', 'state'):
    assert (a['frames/00000100/' + d][:] == b['frames/00000100/' + d][:]).all(), d
"
    run py "$BROKEN" c.h5 200
    read -r touch other <<<"$output"
    [ "$touch" -eq 0 ] && [ "$other" -gt 500 ]
}

@test "no-failure: without failure, an unknown set or a bad name, one line" {
    make_bar
    expect_usage_error "--no-failure left keeps bonds from breaking: it needs --failure" \
        pd-run --bulk-modulus 14e9 --steps 5 --no-failure left bar.h5 -o out.h5
    expect_runtime_error "--no-failure: the model has no set 'nothere'" \
        pd-run --bulk-modulus 14e9 --failure 0.001,0 --steps 5 --no-failure nothere bar.h5 -o out.h5
    expect_usage_error "--no-failure needs a set name, not 'a b'" \
        pd-run --bulk-modulus 14e9 --failure 0.001,0 --steps 5 --no-failure 'a b' bar.h5 -o out.h5
    [ ! -e out.h5 ]
    assert_no_temp .
}
