#!/usr/bin/env bats
# pd-run --model ves: the options and their errors, the scene, thread-count
# independence and restart bit for bit with the bond history (agreement
# with LAMMPS peri/ves is in lammps-agree.bats, the relaxation in
# tests/unit/test_ves.c).

load test_helper
bats_require_minimum_version 1.5.0

setup() {
    cd "$BATS_TEST_TMPDIR"
}

VES=(--model ves --bulk-modulus "$BULK" --shear-modulus 6e9 --ves-lambda 0.5 --ves-tau 1e-6)
VES_RUN=("${VES[@]}" --failure 0.0005,0.25 --contact
         --allow-overlap --indenter sphere,0.005,0.005,0.0125,0.003,1e17,0,0,-100)

@test "ves: option errors are usage errors with one clear line" {
    make_block
    run -2 --separate-stderr pd-run --model ves --bulk-modulus "$BULK" --shear-modulus 6e9 \
        --ves-tau 1e-6 --steps 1 model.h5
    [[ "$stderr" =~ ^pd-run:\ error:\ --model\ ves\ needs\ .*--ves-lambda\ and\ --ves-tau ]]
    [ "$(printf '%s\n' "$stderr" | wc -l)" -eq 1 ]
    run -2 --separate-stderr pd-run --model ves --bulk-modulus "$BULK" --shear-modulus 6e9 \
        --ves-lambda 0.5 --steps 1 model.h5
    [[ "$stderr" =~ --model\ ves\ needs ]]
    run -2 --separate-stderr pd-run "${VES[@]}" --ves-lambda 1.5 --steps 1 model.h5
    [[ "$stderr" =~ --ves-lambda\ must\ be\ a\ number\ in\ \[0,\ 1\] ]]
    run -2 --separate-stderr pd-run "${VES[@]}" --ves-tau 0 --steps 1 model.h5
    [[ "$stderr" =~ --ves-tau\ must\ be\ a\ positive\ number ]]
    run -2 --separate-stderr pd-run --model lps --bulk-modulus "$BULK" --shear-modulus 6e9 \
        --ves-tau 1e-6 --steps 1 model.h5
    [[ "$stderr" =~ --ves-tau\ is\ for\ --model\ ves ]]
    run -2 --separate-stderr pd-run --model ves --bulk-modulus "$BULK" --ves-lambda 0.5 \
        --ves-tau 1e-6 --steps 1 model.h5
    [[ "$stderr" =~ needs\ --bulk-modulus,\ --shear-modulus ]]
    run -0 pd-run --help
    assert_line --partial "--ves-lambda L"
    assert_line --partial "--ves-tau T"
}

@test "ves: /scene and the log name the model and its parameters" {
    make_block
    run -0 --separate-stderr pd-run "${VES[@]}" --steps 2 model.h5 -o r.h5
    [[ "$stderr" =~ effects:\ ves ]]
    [[ "$stderr" =~ model\ ves.*lambda\ 0.5,\ tau\ 1e-06\ s ]]
    py "
with h5py.File(sys.argv[1]) as f:
    a = f['scene'].attrs
    s = lambda v: v.decode() if isinstance(v, bytes) else v
    assert s(a['model']) == 'ves' and a['shear_modulus'] == 6e9, a['model']
    assert a['ves_lambda'] == 0.5 and a['ves_tau'] == 1e-6
    o = s(a['options'])
    assert 'model ves' in o and 'ves-lambda 0.5' in o and 'ves-tau 9.9999999999999995e-07' in o, o
    assert f['restart/0/bond_history'].shape == (f['bonds'].attrs['count'], 2)" r.h5
}

@test "ves: --threads 1 and --threads 2 give bit-identical frames (failure, contact, sphere)" {
    make_block
    pd-run "${VES_RUN[@]}" --steps 50 --every 25 --threads 1 -q model.h5 -o t1.h5
    pd-run "${VES_RUN[@]}" --steps 50 --every 25 --threads 2 -q model.h5 -o t2.h5
    run -0 h5_same t1.h5 t2.h5 'history|threads'
    py "
with h5py.File(sys.argv[1]) as f:
    a = f['frames/00000050'].attrs
    assert a['broken_bonds'] > 0, a['broken_bonds']" t1.h5
}

@test "ves: --restart goes on bit for bit (the bond history travels in the restart slots)" {
    make_block
    pd-run "${VES_RUN[@]}" --steps 60 --every 30 --threads 2 -q model.h5 -o full.h5
    pd-run "${VES_RUN[@]}" --steps 30 --every 30 --threads 1 -q model.h5 -o run.h5
    run -0 pd-run --restart run.h5 --steps 30 --threads 2 -q
    run -0 h5_same full.h5 run.h5 'history|threads|^/restart|^/series|@steps|options'
    py "
with h5py.File(sys.argv[1]) as f:
    assert f['frames/00000060'].attrs['broken_bonds'] > 0
    h = [f['restart/%d/bond_history' % k][...] for k in (0, 1)]
    assert max(abs(x).max() for x in h) > 0" run.h5
    # without the history the restart differs: zero it and go on again
    pd-run "${VES_RUN[@]}" --steps 30 --every 30 --threads 1 -q model.h5 -o cut.h5
    py "
with h5py.File(sys.argv[1], 'r+') as f:
    for k in (0, 1):
        f['restart/%d/bond_history' % k][...] = 0" cut.h5
    run -0 pd-run --restart cut.h5 --steps 30 --threads 2 -q
    run -1 h5_same full.h5 cut.h5 'history|threads|^/restart|^/series|@steps|options'
}
