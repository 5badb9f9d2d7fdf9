#!/usr/bin/env bats
# Scenes checked before step 1 (pd_scene_inspect, lib/run/scene.c): a
# projectile or indenter that starts inside the body is an error naming the
# depth and the particle (--allow-overlap lets it be); values no solid has,
# a run that ends before first contact, a sphere that never touches, a body
# nothing loads get one warning each, naming the likely mistake; --strict
# makes a warning an error; the log says when first contact comes and how
# many frames will be written.  The block is 21 x 21 x 9 sites at 0.5 mm
# (3,969 particles, 10 x 10 x 4 mm, top face z = 0.004).

load test_helper

setup() {
    cd "$BATS_TEST_TMPDIR"
    pd-lattice -q --box 0,0.01,0,0.01,0,0.004 --spacing 0.0005 --density 2200 -o lattice.h5
    pd-bonds -q --horizon 0.0015001 lattice.h5 -o model.h5
}

GLASS=(--bulk-modulus 14.9e9 --failure 0.0005,0.25 --contact)

@test "scene: a projectile 1.5 mm deep in the block is refused, naming the depth and the particle" {
    # a 2 mm sphere whose centre is 0.5 mm above the top face, at 5 m/s
    run -1 --separate-stderr pd-run "${GLASS[@]}" --steps 20 \
        --projectile sphere,0.005,0.005,0.0045,0.002,0.001,0,0,-5 model.h5 -o run.h5
    assert_one_error '^pd-run: error: the projectile overlaps the body at t = 0: particle [0-9]+ \(id [0-9]+\) is 0.0015 m inside it \(radius 0.002 m\); start it outside, or give --allow-overlap$'
    [ ! -e run.h5 ]
    assert_no_temp .
    # the particle named is the deepest: the centre of the top face
    id=$(printf '%s\n' "$stderr" | sed 's/.*(id \([0-9]*\)).*/\1/')
    run -0 py "
with h5py.File(sys.argv[1]) as f:
    x = f['particles/position'][:]
    i = np.nonzero(f['particles/id'][:] == int(sys.argv[2]))[0][0]
    print(' '.join('%.6f' % v for v in x[i]))" model.h5 "$id"
    assert_output "0.005000 0.005000 0.004000"
    # meant: it runs (the energy alarm off: see the next test), and the
    # scene keeps the choice for a rerun
    run -0 pd-run -q "${GLASS[@]}" --steps 5 --allow-overlap --balance-limit off \
        --projectile sphere,0.005,0.005,0.0045,0.002,0.001,0,0,-5 model.h5 -o run.h5
    run -0 h5dump -a /scene/options run.h5
    assert_output --partial "allow-overlap"
}

@test "scene: a start that is mostly penalty energy is said before step 1; the alarm stops its gain" {
    local deep=(--projectile sphere,0.005,0.005,0.0045,0.002,0.001,0,0,-5 --allow-overlap)
    # the overlap of the sphere 1.5 mm deep holds 1.19e3 J at step 0, the
    # sphere's motion 1.25e-2 J: the log says so before the first step
    run -0 --separate-stderr pd-run "${GLASS[@]}" --steps 20 --balance-limit off "${deep[@]}" \
        model.h5 -o run.h5
    [ "$(grep -c warning <<<"$stderr")" -eq 1 ]
    line=$(grep -n 'warning' <<<"$stderr" | cut -d: -f1)
    first=$(grep -n 'step 2/20' <<<"$stderr" | cut -d: -f1)
    [ "$line" -lt "$first" ]
    [[ "$stderr" =~ warning:\ 1.19e\+03\ J\ of\ the\ 1.19e\+03\ J\ at\ step\ 0\ \(100%\)\ is\ penalty\ energy\ of\ contact\ or\ of\ an\ overlap,\ not\ motion ]]
    # its explosive first steps make energy: the balance ends at 2.1 times
    # what it held at step 0, which the alarm (on by default) stops
    run -0 py "
with h5py.File(sys.argv[1]) as f:
    g = max(f['frames'].values(), key=lambda g: g.attrs['step'])
    a = g.attrs
    total = sum(a[k] for k in ('kinetic_energy', 'elastic_energy', 'contact_energy',
                               'released_energy', 'lost_energy', 'projectile_energy')) - a['external_work']
    print('%.1f' % (total / 1.19e3))" run.h5
    assert_output "2.1"
    run -1 --separate-stderr pd-run -q "${GLASS[@]}" --steps 20 "${deep[@]}" model.h5 -o run2.h5
    assert_one_error '^pd-run: error: at step [0-9]+ the energy balance gained 1.[0-9]+e\+03 J since step 0, 1.[0-9]+ times the energy put in \(1.19e\+03 J\), above --balance-limit 1: the run is unstable'
    # --strict refuses the start itself, leaving no file
    run -1 --separate-stderr pd-run -q --strict "${GLASS[@]}" --steps 20 "${deep[@]}" \
        model.h5 -o run3.h5
    assert_one_error '^pd-run: error: 1.19e\+03 J of the 1.19e\+03 J at step 0 \(100%\) is penalty energy .* \(--strict\)$'
    [ ! -e run3.h5 ]
    assert_no_temp .
    # a sphere that only touches the body holds no penalty worth a word
    run -0 --separate-stderr pd-run "${GLASS[@]}" --steps 5 \
        --projectile sphere,0.005,0.005,0.006,0.002,0.001,0,0,-5 model.h5 -o run4.h5
    [[ "$stderr" != *"warning"* ]]
}

@test "scene: an indenter inside the body is refused; one touching the face is not" {
    run -1 --separate-stderr pd-run "${GLASS[@]}" --steps 5 \
        --indenter sphere,0.005,0.005,0.0045,0.001,1e17,0,0,-10 model.h5 -o run.h5
    assert_one_error '^pd-run: error: the indenter overlaps the body at t = 0: .* is 0.0005 m inside it'
    # its lowest point on the top face's sites: touching, not inside
    run -0 --separate-stderr pd-run "${GLASS[@]}" --steps 5 \
        --indenter sphere,0.005,0.005,0.005,0.001,1e17,0,0,-10 model.h5 -o run.h5
    [[ "$stderr" != *"warning"* ]]
    [[ "$stderr" == *"pd-run: first contact at t = 0 s (step 0); 1 frame to write"* ]]
}

@test "scene: the log says when first contact comes and how many frames it writes" {
    # 1 mm above the top face at 100 m/s: contact after 10 us
    run -0 --separate-stderr pd-run "${GLASS[@]}" --steps 100 --every 30 \
        --projectile sphere,0.005,0.005,0.0065,0.0015,0.005,0,0,-100 model.h5 -o run.h5
    [[ "$stderr" == *"pd-run: first contact at t = 1e-05 s (step "*"); 5 frames to write"* ]]
    [[ "$stderr" != *"warning"* ]]
    # frames at 0, 30, 60, 90 and the last step
    run -0 py "
with h5py.File(sys.argv[1]) as f:
    print(len(f['frames']))" run.h5
    assert_output 5
}

@test "scene: implausible values get one warning each, naming the likely mistake" {
    pd-lattice -q --box 0,0.01,0,0.01,0,0.004 --spacing 0.0005 --density 2.44 -o light.h5
    pd-bonds -q --horizon 0.0015001 light.h5 -o light-model.h5
    ABOVE=(--projectile sphere,0.005,0.005,0.0065,0.0015,0.005,0,0,-100)
    run -0 --separate-stderr pd-run "${GLASS[@]}" "${ABOVE[@]}" --steps 200 light-model.h5 -o r.h5
    [[ "$stderr" == *"pd-run: warning: density 2.44 kg/m^3 is far below any solid's; g/cm^3 meant?"* ]]
    run -0 --separate-stderr pd-run --youngs-modulus 70 --contact "${ABOVE[@]}" --steps 5 \
        --force-dt --dt 1e-7 model.h5 -o r.h5
    [[ "$stderr" == *"pd-run: warning: Young's modulus 70 Pa is far below any solid's; GPa or MPa meant?"* ]]
    run -0 --separate-stderr pd-run --bulk-modulus 14.9e9 --failure 0.5,0.25 "${ABOVE[@]}" \
        --steps 200 model.h5 -o r.h5
    [[ "$stderr" == *"pd-run: warning: critical stretch s00 0.5: bonds stretch 50% before they break"* ]]
    pd-bonds -q --horizon 0.00075 lattice.h5 -o thin.h5
    run -0 --separate-stderr pd-run --bulk-modulus 14.9e9 "${ABOVE[@]}" --steps 200 thin.h5 -o r.h5
    [[ "$stderr" == *"pd-run: warning: the horizon is 1.5 spacings"* ]]
    # each warning is one line of its own, and a sound scene has none
    run -0 --separate-stderr pd-run "${GLASS[@]}" "${ABOVE[@]}" --steps 200 model.h5 -o r.h5
    [[ "$stderr" != *"warning"* ]]
}

@test "scene: a run that ends before first contact, a sphere that misses, a body nothing loads" {
    run -0 --separate-stderr pd-run "${GLASS[@]}" --steps 10 \
        --projectile sphere,0.005,0.005,0.0065,0.0015,0.005,0,0,-100 model.h5 -o r.h5
    [[ "$stderr" == *"pd-run: warning: the projectile first touches the body at t = 1e-05 s, after the run ends ("*"10 steps): more --steps?"* ]]
    run -0 --separate-stderr pd-run "${GLASS[@]}" --steps 10 \
        --projectile sphere,0.005,0.005,0.0065,0.0015,0.005,0,0,100 model.h5 -o r.h5
    [[ "$stderr" == *"pd-run: warning: the projectile never touches the body (it moves away from it or past it)"* ]]
    run -0 --separate-stderr pd-run "${GLASS[@]}" --steps 10 \
        --indenter sphere,0.02,0.005,0.0065,0.0015,1e17,0,0,-100 model.h5 -o r.h5
    [[ "$stderr" == *"pd-run: warning: the indenter never touches the body"* ]]
    run -0 --separate-stderr pd-run "${GLASS[@]}" --steps 10 model.h5 -o r.h5
    [[ "$stderr" == *"pd-run: warning: nothing loads the body"* ]]
}

@test "scene: --strict makes a warning an error; -q keeps warnings quiet; a restart does not check again" {
    run -1 --separate-stderr pd-run --strict "${GLASS[@]}" --steps 10 model.h5 -o r.h5
    assert_one_error '^pd-run: error: nothing loads the body .* \(--strict\)$'
    [ ! -e r.h5 ]
    assert_no_temp .
    run -0 --separate-stderr pd-run -q "${GLASS[@]}" --steps 10 model.h5 -o r.h5
    [ -z "$stderr" ]
    # the projectile is inside the body by step 20; going on is no overlap
    run -0 pd-run -q --strict "${GLASS[@]}" --steps 20 --every 10 \
        --projectile sphere,0.005,0.005,0.0056,0.0015,0.005,0,0,-100 model.h5 -o r.h5
    run -0 --separate-stderr pd-run --restart r.h5 --steps 5 --strict
    [[ "$stderr" != *"warning"* && "$stderr" != *"error"* ]]
}
