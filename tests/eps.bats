#!/usr/bin/env bats
# pd-run --model eps: the options and their errors, the scene, thread-count
# independence and restart bit for bit with the plastic extensions (the
# comparison with LAMMPS peri/eps is in lammps-agree.bats, the plasticity
# in tests/unit/test_eps.c).

load test_helper
bats_require_minimum_version 1.5.0

setup() {
    cd "$BATS_TEST_TMPDIR"
}

EPS=(--model eps --bulk-modulus "$BULK" --shear-modulus 6e9 --yield-stress 5e7)
EPS_RUN=("${EPS[@]}" --failure 0.0005,0.25 --contact --allow-overlap
         --indenter sphere,0.005,0.005,0.0125,0.003,1e17,0,0,-100)

@test "eps: option errors are usage errors with one clear line" {
    make_block
    run -2 --separate-stderr pd-run --model eps --bulk-modulus "$BULK" --shear-modulus 6e9 \
        --steps 1 model.h5
    [[ "$stderr" =~ ^pd-run:\ error:\ --model\ eps\ needs\ .*--yield-stress ]]
    [ "$(printf '%s\n' "$stderr" | wc -l)" -eq 1 ]
    run -2 --separate-stderr pd-run "${EPS[@]}" --yield-stress -3 --steps 1 model.h5
    [[ "$stderr" =~ --yield-stress\ must\ be\ a\ positive\ number ]]
    run -2 --separate-stderr pd-run --model lps --bulk-modulus "$BULK" --shear-modulus 6e9 \
        --yield-stress 5e7 --steps 1 model.h5
    [[ "$stderr" =~ --yield-stress\ is\ for\ --model\ eps ]]
    run -2 --separate-stderr pd-run "${EPS[@]}" --ves-tau 1 --steps 1 model.h5
    [[ "$stderr" =~ --ves-tau\ is\ for\ --model\ ves ]]
    run -2 --separate-stderr pd-run --model eps --bulk-modulus "$BULK" --yield-stress 5e7 \
        --steps 1 model.h5
    [[ "$stderr" =~ needs\ --bulk-modulus,\ --shear-modulus ]]
    run -0 pd-run --help
    assert_line --partial "--yield-stress Y"
    assert_line --partial "--model pmb|lps|ves|eps"
}

@test "eps: /scene and the log name the model and the yield stress" {
    make_block
    run -0 --separate-stderr pd-run "${EPS[@]}" --steps 2 model.h5 -o r.h5
    [[ "$stderr" =~ effects:\ eps ]]
    [[ "$stderr" =~ model\ eps.*yield\ stress\ 5e\+07\ Pa ]]
    py "
with h5py.File(sys.argv[1]) as f:
    a = f['scene'].attrs
    s = lambda v: v.decode() if isinstance(v, bytes) else v
    assert s(a['model']) == 'eps' and a['yield_stress'] == 5e7
    o = s(a['options'])
    assert 'model eps' in o and 'yield-stress 50000000' in o, o
    assert f['restart/0/bond_history'].shape == (f['bonds'].attrs['count'], 1)" r.h5
}

@test "eps: --threads 1 and --threads 2 give bit-identical frames (failure, contact, sphere)" {
    make_block
    pd-run "${EPS_RUN[@]}" --steps 50 --every 25 --threads 1 -q model.h5 -o t1.h5
    pd-run "${EPS_RUN[@]}" --steps 50 --every 25 --threads 2 -q model.h5 -o t2.h5
    run -0 h5_same t1.h5 t2.h5 'history|threads'
    py "
with h5py.File(sys.argv[1]) as f:
    a = f['frames/00000050'].attrs
    assert a['broken_bonds'] > 0, a['broken_bonds']" t1.h5
}

@test "eps: --restart goes on bit for bit (the plastic extensions travel in the restart slots)" {
    make_block
    pd-run "${EPS_RUN[@]}" --steps 60 --every 30 --threads 2 -q model.h5 -o full.h5
    pd-run "${EPS_RUN[@]}" --steps 30 --every 30 --threads 1 -q model.h5 -o run.h5
    run -0 pd-run --restart run.h5 --steps 30 --threads 2 -q
    run -0 h5_same full.h5 run.h5 'history|threads|^/restart|^/series|@steps|options'
    py "
with h5py.File(sys.argv[1]) as f:
    assert f['frames/00000060'].attrs['broken_bonds'] > 0
    h = [f['restart/%d/bond_history' % k][...] for k in (0, 1)]
    assert max(abs(x).max() for x in h) > 0, 'no plastic flow'" run.h5
    # without the plastic extensions the restart differs
    pd-run "${EPS_RUN[@]}" --steps 30 --every 30 --threads 1 -q model.h5 -o cut.h5
    py "
with h5py.File(sys.argv[1], 'r+') as f:
    for k in (0, 1):
        f['restart/%d/bond_history' % k][...] = 0" cut.h5
    run -0 pd-run --restart cut.h5 --steps 30 --threads 2 -q
    run -1 h5_same full.h5 cut.h5 'history|threads|^/restart|^/series|@steps|options'
}
