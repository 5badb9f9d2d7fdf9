#!/usr/bin/env bats
# pd-run --ellipsoid: the ellipsoidal influence function of seed 002 in the
# LPS model -- its errors, /scene, the seed's two consistency tests (equal
# axes reproduce the isotropic run to six digits; ellipsoids of the same
# proportions give the same run) and restart bit for bit.  The distance
# function and the stiffness along u are in tests/unit/test_influence.c.

load test_helper
bats_require_minimum_version 1.5.0

setup() {
    cd "$BATS_TEST_TMPDIR"
}

G=6e9
LPS=(--model lps --bulk-modulus "$BULK" --shear-modulus "$G")
LPS_RUN=("${LPS[@]}" --failure 0.0005,0.25 --contact --allow-overlap
         --indenter sphere,0.005,0.005,0.0125,0.003,1e17,0,0,-100)

# close A.h5 B.h5 RTOL: every frame dataset and frame attribute of A equals
# B's within RTOL of the dataset's largest magnitude; prints the largest
# relative difference.
close() {
    py "
a, b, rtol = h5py.File(sys.argv[1], 'r'), h5py.File(sys.argv[2], 'r'), float(sys.argv[3])
worst = 0.0
assert sorted(a['frames']) == sorted(b['frames'])
for fr in a['frames']:
    x, y = a['frames'][fr], b['frames'][fr]
    for k in x.attrs:
        u, v = np.asarray(x.attrs[k], dtype=float), np.asarray(y.attrs[k], dtype=float)
        scale = max(np.abs(u).max(initial=0), 1e-300)
        worst = max(worst, np.abs(u - v).max(initial=0) / scale)
    def walk(name, obj):
        global worst
        if isinstance(obj, h5py.Dataset):
            u, v = obj[()].astype(float), y[name][()].astype(float)
            scale = max(np.abs(u).max(initial=0), 1e-300)
            worst = max(worst, np.abs(u - v).max(initial=0) / scale)
    x.visititems(walk)
print(worst)
assert worst <= rtol, worst" "$@"
}

@test "ellipsoid: option errors are usage errors with one clear line" {
    make_block
    run -2 --separate-stderr pd-run --bulk-modulus "$BULK" --ellipsoid 1,0,0,0.5,0.5,0 --steps 1 model.h5
    [[ "$stderr" =~ ^pd-run:\ error:\ --ellipsoid\ is\ for\ --model\ lps\|ves\|eps,\ not\ pmb ]]
    [ "$(printf '%s\n' "$stderr" | wc -l)" -eq 1 ]
    for bad in 0,0,0,0.5,0.5,0 1,0,0,0,0.5,0 1,0,0,1.5,0.5,0 1,0,0,0.5,0.5 1,0,0,0.5,0.5,0,1 x; do
        run -2 --separate-stderr pd-run "${LPS[@]}" --ellipsoid "$bad" --steps 1 model.h5
        [[ "$stderr" =~ ^pd-run:\ error:\ --ellipsoid\ needs\ UX,UY,UZ,A,B,ROLL ]]
        [ "$(printf '%s\n' "$stderr" | wc -l)" -eq 1 ]
    done
    many=()
    for k in 1 2 3 4 5 6 7 8 9; do many+=(--ellipsoid 1,0,0,0.5,0.5,0); done
    run -2 --separate-stderr pd-run "${LPS[@]}" "${many[@]}" --steps 1 model.h5
    [[ "$stderr" =~ at\ most\ 8\ times ]]
    run -0 pd-run --help
    assert_line --partial "--ellipsoid UX,UY,UZ,A,B,ROLL"
}

@test "ellipsoid: /scene keeps them, the options text reruns them, the log says so" {
    make_block
    run -0 --separate-stderr pd-run "${LPS[@]}" --ellipsoid 1,1,0,0.5,0.25,0.3 \
        --ellipsoid 0,0,2,1,0.5,0 --steps 2 model.h5 -o r.h5
    [[ "$stderr" =~ anisotropic\ influence.*2\ ellipsoids ]]
    py "
with h5py.File(sys.argv[1]) as f:
    a = f['scene'].attrs
    s = lambda v: v.decode() if isinstance(v, bytes) else v
    assert list(a['ellipsoids']) == [1, 1, 0, 0.5, 0.25, 0.3, 0, 0, 2, 1, 0.5, 0], a['ellipsoids']
    o = s(a['options'])
    assert 'ellipsoid 1,1,0,0.5,0.25,0.29999999999999999' in o and 'ellipsoid 0,0,2,1,0.5,0' in o, o" r.h5
    pd-run "${LPS[@]}" --steps 2 -q model.h5 -o iso.h5
    py "
with h5py.File(sys.argv[1]) as f:
    assert 'ellipsoids' not in f['scene'].attrs" iso.h5
}

@test "ellipsoid: equal axes reproduce the isotropic run to six digits (failure, contact, sphere)" {
    make_block
    pd-run "${LPS_RUN[@]}" --steps 50 --every 25 -q model.h5 -o iso.h5
    pd-run "${LPS_RUN[@]}" --ellipsoid 0.3,-1,2,1,1,0.4 --steps 50 --every 25 -q model.h5 -o sph.h5
    run -0 close iso.h5 sph.h5 1e-6
    echo "# a = b = 1 against isotropic: largest relative difference $output" >&3
    py "
with h5py.File(sys.argv[1]) as f:
    assert f['frames/00000050'].attrs['broken_bonds'] > 0" sph.h5
}

@test "ellipsoid: the same proportions with a scaled U give the same run bit for bit" {
    make_block
    pd-run "${LPS_RUN[@]}" --ellipsoid 1,1,0,0.5,0.7,0.3 --steps 40 --every 20 -q model.h5 -o u1.h5
    pd-run "${LPS_RUN[@]}" --ellipsoid 4,4,0,0.5,0.7,0.3 --steps 40 --every 20 -q model.h5 -o u4.h5
    run -0 h5_same u1.h5 u4.h5 '^/scene|history'
    # and the ellipsoid changes the run
    pd-run "${LPS_RUN[@]}" --steps 40 --every 20 -q model.h5 -o iso.h5
    run -1 close u1.h5 iso.h5 1e-3
}

@test "ellipsoid: --restart goes on bit for bit" {
    make_block
    E=(--ellipsoid 1,1,0,0.5,0.7,0.3 --ellipsoid 0,0,1,0.4,0.4,0)
    pd-run "${LPS_RUN[@]}" "${E[@]}" --steps 60 --every 30 --threads 2 -q model.h5 -o full.h5
    pd-run "${LPS_RUN[@]}" "${E[@]}" --steps 30 --every 30 --threads 1 -q model.h5 -o run.h5
    run -0 pd-run --restart run.h5 --steps 30 --threads 2 -q
    run -0 h5_same full.h5 run.h5 'history|threads|^/restart|^/series|@steps|options'
    run -2 --separate-stderr pd-run --restart run.h5 --steps 30 --ellipsoid 1,0,0,1,1,0
    [[ "$stderr" =~ would\ change\ it ]]
}
