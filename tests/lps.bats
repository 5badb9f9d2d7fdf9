#!/usr/bin/env bats
# pd-run --model lps: the options and their errors, the scene, thread-count
# independence, restart bit for bit, the energy balance and the stable step
# (agreement with LAMMPS peri/lps is in lammps-agree.bats, the formulas in
# tests/unit/test_lps.c).

load test_helper
bats_require_minimum_version 1.5.0

setup() {
    cd "$BATS_TEST_TMPDIR"
}

G=6e9
LPS=(--model lps --bulk-modulus "$BULK" --shear-modulus "$G")
LPS_RUN=("${LPS[@]}" --failure 0.0005,0.25 --contact --allow-overlap
         --indenter sphere,0.005,0.005,0.0125,0.003,1e17,0,0,-100)

# balance FILE: per complete frame "step total motion", total being
# kinetic + elastic + contact + released + lost - work and motion
# kinetic + elastic + contact.
balance() {
    py "
with h5py.File(sys.argv[1]) as f:
    for g in sorted(f['frames'].values(), key=lambda g: g.attrs['step']):
        a = g.attrs
        motion = a['kinetic_energy'] + a['elastic_energy'] + a['contact_energy']
        print(a['step'], motion + a['released_energy'] + a['lost_energy'] - a['external_work'],
              motion, a['external_work'])" "$1"
}

@test "lps: option errors are usage errors with one clear line" {
    make_block
    run -2 --separate-stderr pd-run --model lps --bulk-modulus "$BULK" --steps 1 model.h5
    [[ "$stderr" =~ ^pd-run:\ error:\ --model\ lps\ needs\ --bulk-modulus\ and\ --shear-modulus ]]
    run -2 --separate-stderr pd-run "${LPS[@]}" --c 1e22 --steps 1 model.h5
    [[ "$stderr" =~ ^pd-run:\ error:\ --c\ is\ for\ --model\ pmb,\ not\ lps ]]
    run -2 --separate-stderr pd-run --bulk-modulus "$BULK" --shear-modulus "$G" --steps 1 model.h5
    [[ "$stderr" =~ ^pd-run:\ error:\ --shear-modulus\ is\ for\ --model\ lps ]]
    run -2 --separate-stderr pd-run --bulk-modulus "$BULK" --influence 1 --steps 1 model.h5
    [[ "$stderr" =~ --influence\ is\ for\ --model\ lps ]]
    run -2 --separate-stderr pd-run "${LPS[@]}" --influence 1/r2 --steps 1 model.h5
    [[ "$stderr" =~ --influence\ takes\ 1/r,\ 1\ or\ gaussian ]]
    run -2 --separate-stderr pd-run "${LPS[@]}" --failure-energy 8 --steps 1 model.h5
    [[ "$stderr" =~ --failure-energy ]]
    run -2 --separate-stderr pd-run "${LPS[@]}" --shear-modulus -1 --steps 1 model.h5
    run -2 --separate-stderr pd-run --model xyz --bulk-modulus "$BULK" --steps 1 model.h5
    [[ "$stderr" =~ pmb,\ lps ]]
    [ "$(printf '%s\n' "$stderr" | wc -l)" -eq 1 ]
    run -0 pd-run --help
    assert_line --partial "--shear-modulus G"
    assert_line --partial "--influence W"
}

@test "lps: /scene and the log name the model, its moduli and influence function" {
    make_block
    run -0 --separate-stderr pd-run "${LPS[@]}" --influence gaussian --steps 2 model.h5 -o r.h5
    [[ "$stderr" =~ effects:\ lps ]]
    [[ "$stderr" =~ model\ lps.*G\ 6e\+09\ Pa,\ influence\ gaussian ]]
    py "
with h5py.File(sys.argv[1]) as f:
    a = f['scene'].attrs
    s = lambda v: v.decode() if isinstance(v, bytes) else v
    assert s(a['model']) == 'lps' and a['shear_modulus'] == 6e9 and s(a['influence']) == 'gaussian'
    assert a['bulk_modulus'] == 14.9e9
    assert 'model lps' in s(a['options']) and 'influence gaussian' in s(a['options'])
    assert 'shear-modulus 6000000000' in s(a['options'])" r.h5
}

@test "lps: --threads 1 and --threads 2 give bit-identical frames (failure, contact, sphere)" {
    make_block
    pd-run "${LPS_RUN[@]}" --steps 50 --every 25 --threads 1 -q model.h5 -o t1.h5
    pd-run "${LPS_RUN[@]}" --steps 50 --every 25 --threads 2 -q model.h5 -o t2.h5
    run -0 h5_same t1.h5 t2.h5 'history|threads'
    py "
with h5py.File(sys.argv[1]) as f:
    a = f['frames/00000050'].attrs
    assert a['broken_bonds'] > 0 and a['released_energy'] > 0, (a['broken_bonds'], a['released_energy'])" t1.h5
}

@test "lps: --restart goes on bit for bit" {
    make_block
    pd-run "${LPS_RUN[@]}" --influence 1 --steps 60 --every 30 --threads 2 -q model.h5 -o full.h5
    pd-run "${LPS_RUN[@]}" --influence 1 --steps 30 --every 30 --threads 1 -q model.h5 -o run.h5
    run -0 pd-run --restart run.h5 --steps 30 --threads 2 -q
    run -0 h5_same full.h5 run.h5 'history|threads|^/restart|^/series|@steps|options'
    py "
with h5py.File(sys.argv[1]) as f:
    assert f['frames/00000060'].attrs['broken_bonds'] > 0" run.h5
}

@test "lps: an elastic run keeps its energy balance within 0.1% over 2000 steps" {
    make_block
    # the sphere presses in at 10 m/s and throws the block, dt at 0.9 of
    # the stable step
    run -0 pd-run "${LPS[@]}" --safety 0.9 -q \
        --indenter sphere,0.005,0.005,0.0131,0.003,1e17,0,0,-10 \
        --steps 2000 --every 100 model.h5 -o el.h5
    run -0 balance el.h5
    printf '%s\n' "$output" | "$PY" -c "
import sys
rows = [list(map(float, l.split())) for l in sys.stdin]
assert len(rows) == 21 and rows[-1][3] > 0.1, rows[-1]
worst = max(abs(r[1]) / r[2] for r in rows[1:])
print('balance / energy', worst)
assert worst <= 1e-3, worst"
}

@test "lps: the stable step: 0.9 of it runs, --dt above it is refused, 4 times it blows up" {
    make_block
    ind=sphere,0.005,0.005,0.0125,0.003,1e17,0,0,-10
    pd-run "${LPS[@]}" -q --steps 0 model.h5 -o ref.h5
    dts=$(py "
with h5py.File(sys.argv[1]) as f:
    print(repr(f['scene'].attrs['dt_stable']))" ref.h5)
    run -0 pd-run "${LPS[@]}" -q --indenter "$ind" --allow-overlap --dt "$("$PY" -c "print(0.9 * $dts)")" \
        --steps 1000 --every 1000 model.h5 -o ok.h5
    big=$("$PY" -c "print(1.01 * $dts)")
    run -1 --separate-stderr pd-run "${LPS[@]}" --indenter "$ind" --dt "$big" --steps 10 \
        model.h5 -o no.h5
    [[ "$stderr" =~ exceeds\ the\ stable\ time\ step ]]
    run -1 --separate-stderr pd-run "${LPS[@]}" -q --indenter "$ind" --allow-overlap --force-dt \
        --dt "$("$PY" -c "print(4 * $dts)")" --steps 1000 model.h5 -o blow.h5
    [[ "$stderr" =~ unstable ]]
}
