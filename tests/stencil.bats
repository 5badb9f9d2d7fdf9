#!/usr/bin/env bats
# stencil.bats -- the PMB bonds of a body on a lattice walked as a stencil
# (lib/stencil/grid.c): when pd-run takes it, and that it gives the bond list's run
# (pd-run --bond-list) to rounding -- the same bonds broken, the same
# displacements to 1e-9 of the largest, the same energies -- with failure,
# contact (of the stencil pairs and of the list), the indenter, lost
# particles, a plate, and a file whose particles are not in lattice order.

load test_helper

setup() {
    cd "$BATS_TEST_TMPDIR"
}

# threads_and_restart MODEL: the RUN_OPTS scene on MODEL (80 steps, a frame
# every 20) gives the same bits on 1 and 2 threads, and through a restart
# at step 40.
threads_and_restart() {
    pd-run -q "${RUN_OPTS[@]}" --steps 80 --every 20 --threads 1 "$1" -o one.h5
    pd-run -q "${RUN_OPTS[@]}" --steps 80 --every 20 --threads 2 "$1" -o two.h5
    run -0 h5_same one.h5 two.h5 'history|threads'
    pd-run -q "${RUN_OPTS[@]}" --steps 40 --every 20 --threads 2 "$1" -o half.h5
    pd-run -q --restart half.h5 --steps 40 --threads 2 -o rest.h5
    run -0 h5_same two.h5 rest.h5 'history|threads|^/scene|^/series'
}

# agree A B [TOL]: the two runs have the same frames, the same bond states
# (by directed bond, or by the broken count when the particle orders
# differ), displacements and velocities within TOL (default 1e-9) of the
# largest, matched by particle id, and energies within TOL of the largest
# energy of the frame.
agree() {
    py "
a, b = h5py.File(sys.argv[1], 'r'), h5py.File(sys.argv[2], 'r')
tol = float(sys.argv[3])
ia, ib = a['particles/id'][:], b['particles/id'][:]
same_order = (ia == ib).all()
pa, pb = np.argsort(ia), np.argsort(ib)
assert sorted(a['frames']) == sorted(b['frames']) and len(a['frames']) > 1
for name in a['frames']:
    fa, fb = a['frames'][name], b['frames'][name]
    if same_order:
        assert (fa['state'][:] == fb['state'][:]).all(), (name, 'bond states differ')
    assert fa.attrs['broken_bonds'] == fb.attrs['broken_bonds'], name
    for k in ('displacement', 'velocity'):
        x, y = fa[k][:][pa], fb[k][:][pb]
        scale = max(np.abs(x).max(), 1e-30)
        assert np.abs(x - y).max() <= tol * scale, (name, k, np.abs(x - y).max(), scale)
    keys = [k for k in fa.attrs if k.endswith('_energy') or k == 'external_work']
    big = max(abs(fa.attrs[k]) for k in keys)
    for k in keys:
        assert abs(fa.attrs[k] - fb.attrs[k]) <= tol * max(big, 1e-30), (name, k)
    print(name, fa.attrs['broken_bonds'], fa.attrs['contact_energy'])
" "$1" "$2" "${3:-1e-9}"
}

@test "a lattice body is walked as a stencil; --bond-list, a perturbed lattice and per-bond laws walk the list" {
    make_block
    run -0 --separate-stderr pd-run "${RUN_OPTS[@]}" --steps 1 model.h5 -o a.h5
    [[ "$stderr" =~ "bonds walked as a lattice stencil of 61 offsets"( in AVX-512 tiles)?", with the contact of its pairs" ]]
    # the tiles where the processor has AVX-512, unless PD_NO_AVX512 is set
    if grep -qw avx512f /proc/cpuinfo 2>/dev/null; then
        [[ "$stderr" == *" in AVX-512 tiles, "* ]]
    fi
    run -0 --separate-stderr env PD_NO_AVX512=1 pd-run "${RUN_OPTS[@]}" --steps 1 model.h5 -o c.h5
    [[ "$stderr" == *"lattice stencil of 61 offsets, with the contact"* ]]
    run -0 --separate-stderr pd-run "${RUN_OPTS[@]}" --bond-list --steps 1 model.h5 -o b.h5
    [[ "$stderr" != *stencil* ]]
    # the choice is part of the scene: a restart keeps it
    run -0 --separate-stderr pd-run --restart b.h5 --steps 1 -o c.h5
    [[ "$stderr" != *stencil* ]]
    pd-lattice -q --spacing "$SPACING" --density "$DENSITY" --perturb 1e-5 \
        --box 0,0.01,0,0.01,0,0.01 -o shaken.h5
    pd-bonds -q --horizon "$HORIZON" shaken.h5 -o shaken-model.h5
    run -0 --separate-stderr pd-run "${RUN_OPTS[@]}" --steps 1 shaken-model.h5 -o d.h5
    [[ "$stderr" != *stencil* ]]
    run -0 --separate-stderr pd-run "${RUN_OPTS[@]}" --fibre 1,0,0,2e22,1e22 --steps 1 model.h5 -o e.h5
    [[ "$stderr" != *stencil* ]]
    # LPS takes it too, but not with ellipsoids (omega then depends on the
    # direction), nor VES and EPS (their histories are per directed bond)
    run -0 --separate-stderr pd-run --model lps --bulk-modulus "$BULK" --shear-modulus 8e9 \
        --steps 1 model.h5 -o f.h5
    [[ "$stderr" == *"lattice stencil of 61 offsets"* ]]
    run -0 --separate-stderr pd-run --model lps --bulk-modulus "$BULK" --shear-modulus 8e9 \
        --ellipsoid 1,0,0,1,1,0 --steps 1 model.h5 -o g.h5
    [[ "$stderr" != *stencil* ]]
    for m in "ves --ves-lambda 0.5 --ves-tau 1e-6" "eps --yield-stress 1e8"; do
        # shellcheck disable=SC2086 # the model's options
        run -0 --separate-stderr pd-run --model $m --bulk-modulus "$BULK" --shear-modulus 8e9 \
            --steps 1 model.h5 -o h.h5
        [[ "$stderr" != *stencil* ]]
    done
    # LPS in another particle order keeps the list (its arrays are in the
    # file's order)
    pd-bonds -q --no-sort --horizon "$HORIZON" lattice.h5 -o unsorted.h5
    run -0 --separate-stderr pd-run --model lps --bulk-modulus "$BULK" --shear-modulus 8e9 \
        --steps 1 unsorted.h5 -o i.h5
    [[ "$stderr" != *stencil* ]]
}

@test "LPS on the stencil gives the bond list's run to rounding: failure, contact, indenter" {
    make_block
    opts=(--model lps --bulk-modulus "$BULK" --shear-modulus 8e9 --failure 0.0005,0.25 --contact
          --allow-overlap --indenter sphere,0.005,0.005,0.0125,0.003,1e17,0,0,-100 --every 20 -q --threads 2)
    pd-run "${opts[@]}" --steps 80 model.h5 -o grid.h5
    pd-run "${opts[@]}" --steps 80 --bond-list model.h5 -o list.h5
    run -0 agree grid.h5 list.h5
    [[ "${lines[-1]}" =~ ^00000080\ [1-9][0-9]+\  ]]
    # 1 and 2 threads, bit for bit; and a restart
    pd-run "${opts[@]}" --steps 80 --threads 1 model.h5 -o t1.h5
    run -0 h5_same grid.h5 t1.h5 'history|threads'
    pd-run "${opts[@]}" --steps 40 model.h5 -o half.h5
    pd-run -q --restart half.h5 --steps 40 --threads 2 -o rest.h5
    run -0 h5_same grid.h5 rest.h5 'history|threads|^/scene|^/series'
}

@test "the stencil gives the bond list's run to rounding: failure, contact, indenter" {
    make_block
    pd-run -q "${RUN_OPTS[@]}" --steps 80 --every 20 model.h5 -o grid.h5
    pd-run -q "${RUN_OPTS[@]}" --steps 80 --every 20 --bond-list model.h5 -o list.h5
    run -0 agree grid.h5 list.h5
    # bonds did break, and the sums are not bit for bit the same (so the
    # two kernels did run)
    [[ "${lines[-1]}" =~ ^00000080\ [1-9][0-9]+\  ]]
    run -1 h5_same grid.h5 list.h5 'history|bond_list|scene'
}

@test "the AVX-512 tiles and the portable segment walk (PD_NO_AVX512) give the same run" {
    # rows of 24 particles: a full tile and a last one moved back over it
    # (the block's rows of 10 are shorter than a tile).  Where the processor
    # has no AVX-512 both runs walk the segments and agree trivially.
    pd-lattice -q --spacing "$SPACING" --density "$DENSITY" --box 0,0.024,0,0.01,0,0.01 \
        -o long.h5
    pd-bonds -q --horizon "$HORIZON" long.h5 -o model.h5
    pd-run -q "${RUN_OPTS[@]}" --steps 80 --every 20 model.h5 -o tile.h5
    PD_NO_AVX512=1 pd-run -q "${RUN_OPTS[@]}" --steps 80 --every 20 model.h5 -o seg.h5
    run -0 agree tile.h5 seg.h5
    [[ "${lines[-1]}" =~ ^00000080\ [1-9][0-9]+\  ]]
    # 1 and 2 threads bit for bit, and a restart
    threads_and_restart model.h5
}

@test "LPS: the AVX-512 tiles and the portable segment walk (PD_NO_AVX512) give the same run" {
    # rows of 24 particles, as above: the dilatation and the forces in
    # tiles, and the rows' last tile moved back over the one before
    pd-lattice -q --spacing "$SPACING" --density "$DENSITY" --box 0,0.024,0,0.01,0,0.01 \
        -o long.h5
    pd-bonds -q --horizon "$HORIZON" long.h5 -o model.h5
    opts=(--model lps --bulk-modulus "$BULK" --shear-modulus 8e9 --failure 0.0005,0.25 --contact
          --allow-overlap --indenter sphere,0.012,0.005,0.0125,0.003,1e17,0,0,-100 --every 20 -q)
    pd-run "${opts[@]}" --steps 80 model.h5 -o tile.h5
    PD_NO_AVX512=1 pd-run "${opts[@]}" --steps 80 model.h5 -o seg.h5
    run -0 agree tile.h5 seg.h5
    [[ "${lines[-1]}" =~ ^00000080\ [1-9][0-9]+\  ]]
    # the tiles did run where the processor has AVX-512: their sums are
    # rounded in another order
    if grep -qw avx512f /proc/cpuinfo 2>/dev/null; then
        run -1 h5_same tile.h5 seg.h5 'history'
    fi
    # 1 and 2 threads, bit for bit; and a restart
    pd-run "${opts[@]}" --steps 80 --threads 1 model.h5 -o t1.h5
    pd-run "${opts[@]}" --steps 80 --threads 2 model.h5 -o t2.h5
    run -0 h5_same t1.h5 t2.h5 'history|threads'
    pd-run "${opts[@]}" --steps 40 --threads 2 model.h5 -o half.h5
    pd-run -q --restart half.h5 --steps 40 --threads 2 -o rest.h5
    run -0 h5_same t2.h5 rest.h5 'history|threads|^/scene|^/series'
}

# list_kernels VAR SAYS: the bond list's kernel as pd-run takes it and the
# one it takes with VAR=1 give the same run (agree: the same bonds broken,
# the rest to rounding) on a perturbed body (no stencil: the bond list;
# rows of 25 particles with 40 to 60 half bonds: full vectors of 8 and a
# masked last one, groups of lanes that end at different columns) with
# failure, contact and the indenter; with per-bond laws (each bond's own
# kfail) and --no-failure; and on a meshed block (unequal volumes: two
# weights a bond; node radii of their own, so the pairs closer than 0.9
# |xi| are flagged and the contact pass takes each pair's d_ij).  Each
# kernel gives the same bits on 1 and 2 threads and through a restart.
# Where the processor has AVX-512 the log says SAYS and the two runs'
# sums differ; with VAR=1 it does not say it.  (Without AVX-512 both runs
# take the portable loop and agree trivially.)
list_kernels() {
    local var=$1 says=$2
    pd-lattice -q --spacing "$SPACING" --density "$DENSITY" --perturb 1e-4 --seed 5 \
        --box 0,0.024,0,0.01,0,0.01 --set bottom=box,-1,1,-1,1,-1,0.0015 -o shaken.h5
    pd-bonds -q --horizon "$HORIZON" shaken.h5 -o model.h5
    pd-run -q "${RUN_OPTS[@]}" --steps 80 --every 20 model.h5 -o one.h5
    env "$var=1" pd-run -q "${RUN_OPTS[@]}" --steps 80 --every 20 model.h5 -o other.h5
    run -0 agree one.h5 other.h5
    [[ "${lines[-1]}" =~ ^00000080\ [1-9][0-9]+\  ]]
    if grep -qw avx512f /proc/cpuinfo 2>/dev/null; then
        run -0 --separate-stderr pd-run "${RUN_OPTS[@]}" --steps 1 model.h5 -o log.h5
        [[ "$stderr" == *"$says"* ]]
        run -1 h5_same one.h5 other.h5 'history'
    fi
    run -0 --separate-stderr env "$var=1" pd-run "${RUN_OPTS[@]}" --steps 1 model.h5 -o log.h5
    [[ "$stderr" != *"$says"* ]]
    laws=(--material 1,c=1.2e21,s00=0.0004 --no-failure bottom)
    pd-run -q "${RUN_OPTS[@]}" "${laws[@]}" --steps 80 --every 20 model.h5 -o one-laws.h5
    env "$var=1" pd-run -q "${RUN_OPTS[@]}" "${laws[@]}" --steps 80 --every 20 model.h5 \
        -o other-laws.h5
    run -0 agree one-laws.h5 other-laws.h5
    [[ "${lines[-1]}" =~ ^00000080\ [1-9][0-9]+\  ]]
    threads_and_restart model.h5
    export "$var=1"
    threads_and_restart model.h5
    unset "$var"
    gmsh -v 0 -3 -format msh41 -o box.msh "$BATS_TEST_DIRNAME/fixtures/mesh/box.geo"
    pd-mesh -q --density "$DENSITY" box.msh -o mesh.h5
    pd-bonds -q --horizon 0.0016 mesh.h5 -o mesh-model.h5
    mesh=(--bulk-modulus "$BULK" --failure 0.0005,0.25 --contact --allow-overlap
          --indenter sphere,0.005,0.002,0.0045,0.003,1e17,0,0,-100 --steps 80 --every 20 -q)
    pd-run "${mesh[@]}" mesh-model.h5 -o mesh-one.h5
    env "$var=1" pd-run "${mesh[@]}" mesh-model.h5 -o mesh-other.h5
    run -0 agree mesh-one.h5 mesh-other.h5
    [[ "${lines[-1]}" =~ ^00000080\ [1-9][0-9]+\ [0-9.e-]+$ ]]
}

@test "the bond list in AVX-512 and its portable loop (PD_NO_AVX512) give the same run" {
    list_kernels PD_NO_AVX512 "bonds walked as a bond list in AVX-512 rows"
}

@test "the bond list's lanes and its rows (PD_NO_LANES) give the same run, each on any threads" {
    # the lanes (lib/models/pmb_lanes.c) walk 8 rows at a time
    list_kernels PD_NO_LANES "bonds walked as a bond list in AVX-512 rows, 8 at a time in lanes"
}

@test "the status line's largest damage (counted on the stencil) is pd-damage's, and the list's" {
    pd-lattice -q --spacing "$SPACING" --density "$DENSITY" --box 0,0.024,0,0.01,0,0.01 \
        -o long.h5
    pd-bonds -q --horizon "$HORIZON" long.h5 -o model.h5
    for k in grid list; do
        extra=()
        [ $k = list ] && extra=(--bond-list)
        pd-run "${RUN_OPTS[@]}" "${extra[@]}" --steps 80 --every 20 --status 20 model.h5 \
            -o $k.h5 2>$k.log
        # "step S/80 ... max_damage=D" against pd-damage's table (step ... max_damage ...)
        sed -n 's|^pd-run: step \([0-9]*\)/80 .* max_damage=\([0-9.]*\)$|\1 \2|p' $k.log >$k.status
        pd-damage -n $k.h5 | awk '!/^#/ && $1 > 0 { printf "%d %.4f\n", $1, $5 }' >$k.table
        [ "$(wc -l <$k.status)" -eq 4 ]
        run diff $k.status $k.table
        assert_success
    done
    # bonds did break, and the damage is not all 0 or 1
    run awk '$2 > 0 && $2 < 1' grid.status
    [ "${#lines[@]}" -ge 2 ]
}

@test "contact between the stencil pairs of a loose block: the same as the list's" {
    make_block
    # every bond breaks at the first stretch: contact alone holds the
    # particles apart, and every pair within 1.35 spacings is a stencil pair.
    # A loose heap is chaotic: rounding differences grow about tenfold every
    # 30 steps (1e-16 of the largest displacement at step 300, 1e-8 at 600,
    # 1e-3 at 900), so the runs are compared up to step 600.
    opts=(--bulk-modulus "$BULK" --failure 1e-9,0 --contact -q
          --indenter sphere,0.005,0.005,0.0131,0.003,1e17,0,0,-10 --steps 600 --every 300)
    pd-run "${opts[@]}" model.h5 -o grid.h5
    pd-run "${opts[@]}" --bond-list model.h5 -o list.h5
    run -0 agree grid.h5 list.h5 1e-6
    py "
with h5py.File(sys.argv[1]) as f:
    a = f['frames/00000300'].attrs
    assert a['contact_energy'] > 0 and a['broken_bonds'] > 0.99 * f['bonds'].attrs['count'] / 2, \\
        dict(a)" grid.h5
}

@test "a file in another particle order goes through a permutation, with the same run" {
    make_block
    pd-bonds -q --no-sort --horizon "$HORIZON" lattice.h5 -o unsorted.h5
    # the unsorted file is in pd-lattice's order (z, y, x), not lattice
    # order (the inner axis is x, the outer y): a permutation is needed
    run -0 py "
with h5py.File(sys.argv[1]) as a, h5py.File(sys.argv[2]) as b:
    assert not (a['particles/id'][:] == b['particles/id'][:]).all()" unsorted.h5 model.h5
    run -0 --separate-stderr pd-run "${RUN_OPTS[@]}" --steps 80 --every 20 unsorted.h5 -o perm.h5
    [[ "$stderr" == *"lattice stencil of 61"* ]]
    pd-run -q "${RUN_OPTS[@]}" --steps 80 --every 20 --bond-list unsorted.h5 -o list.h5
    pd-run -q "${RUN_OPTS[@]}" --steps 80 --every 20 model.h5 -o sorted.h5
    run -0 agree perm.h5 list.h5
    run -0 agree perm.h5 sorted.h5
    # the permutation and the lattice order give the same sums: bit for bit
    run -0 py "
with h5py.File(sys.argv[1]) as a, h5py.File(sys.argv[2]) as b:
    pa, pb = np.argsort(a['particles/id'][:]), np.argsort(b['particles/id'][:])
    for k in ('displacement', 'velocity'):
        assert (a['frames/00000080'][k][:][pa] == b['frames/00000080'][k][:][pb]).all(), k" perm.h5 sorted.h5
}

@test "the stencil is identical at 1 and 2 threads and restarts bit for bit, with a permutation too" {
    make_block
    pd-bonds -q --no-sort --horizon "$HORIZON" lattice.h5 -o unsorted.h5
    for m in model unsorted; do
        pd-run -q "${RUN_OPTS[@]}" --steps 60 --every 30 --threads 1 $m.h5 -o t1.h5
        pd-run -q "${RUN_OPTS[@]}" --steps 60 --every 30 --threads 2 $m.h5 -o t2.h5
        run -0 h5_same t1.h5 t2.h5 'history|threads'
        pd-run -q "${RUN_OPTS[@]}" --steps 30 --every 30 --threads 2 $m.h5 -o half.h5
        pd-run -q --restart half.h5 --steps 30 --threads 2 -o rest.h5
        run -0 h5_same t2.h5 rest.h5 'history|threads|^/scene|^/series'
    done
}

@test "lost particles: the stencil drops their contact as the list does" {
    pd-lattice -q --spacing 0.0005 --density "$DENSITY" --box 0,0.01,0,0.01,0,0.0025 -o plate.h5
    pd-bonds -q --horizon 0.0015001 plate.h5 -o model.h5
    opts=(--bulk-modulus "$BULK" --failure 0.0005,0.25 --contact -q
          --allow-overlap --indenter sphere,0.005,0.005,0.0055,0.0025,1e18,0,0,-1000 --lost-margin 0.002
          --steps 150 --every 50)
    pd-run "${opts[@]}" model.h5 -o grid.h5
    pd-run "${opts[@]}" --bond-list model.h5 -o list.h5
    py "
with h5py.File(sys.argv[1]) as f:
    assert f['frames/00000150'].attrs['lost_particles'] > 100" grid.h5
    # (later a particle may cross the margin a step earlier in one run than
    # in the other, and is then held one step's travel, 5e-5 m, apart)
    run -0 agree grid.h5 list.h5
}

@test "a 2-D plate is walked as a stencil and agrees with the list" {
    pd-lattice -q --dimension 2 --thickness 0.001 --spacing 0.0005 --density "$DENSITY" \
        --box 0,0.02,0,0.01,-1,1 -o plate.h5
    pd-bonds -q --horizon 0.0015001 plate.h5 -o model.h5
    opts=(--youngs-modulus 72e9 --failure 0.002,0 --contact
          --allow-overlap --indenter sphere,0.01,0.0128,0,0.003,1e18,0,-50,0 --steps 200 --every 50)
    run -0 --separate-stderr pd-run "${opts[@]}" model.h5 -o grid.h5
    [[ "$stderr" == *"lattice stencil of 14 offsets"* ]]
    pd-run -q "${opts[@]}" --bond-list model.h5 -o list.h5
    run -0 agree grid.h5 list.h5
}

@test "two bodies meeting: their contact goes through the list, found as the bond list finds it" {
    # two blocks 4 spacings apart (farther than the horizon: no stencil
    # pair joins them); the right one is driven into the left one, so
    # their contact pairs are the contact list's, not the stencil's.  The
    # right block moves as one: its cells are passed over by its own
    # particles' searches (lib/effects/contact.c), not those of the left
    # block's cells it meets.  The reference: the portable bond list
    # (PD_NO_AVX512), whose contact list every particle searches for
    # itself, with nothing passed over.
    pd-lattice -q --spacing "$SPACING" --density "$DENSITY" --box 0,0.005,0,0.005,0,0.005 \
        --box 0.009,0.014,0,0.005,0,0.005 --set push=box,0.0085,0.0145,0,0.005,0,0.005 -o two.h5
    pd-bonds -q --horizon "$HORIZON" two.h5 -o model.h5
    opts=(--bulk-modulus "$BULK" --contact --velocity-bc push,x,-20 --steps 800 --every 100 -q)
    pd-run "${opts[@]}" model.h5 -o grid.h5
    pd-run "${opts[@]}" --bond-list model.h5 -o list.h5
    PD_NO_AVX512=1 pd-run "${opts[@]}" --bond-list model.h5 -o ref.h5
    run -0 agree grid.h5 list.h5
    run -0 agree grid.h5 ref.h5
    run -0 agree list.h5 ref.h5
    # some frame has pairs from the two blocks in contact
    py "
with h5py.File(sys.argv[1]) as f:
    x = f['particles/position'][:]
    r2 = ((x[:, None, :] - x[None, :, :]) ** 2).sum(-1)
    hits = 0
    for g in f['frames'].values():
        y = x + g['displacement'][:]
        d2 = ((y[:, None, :] - y[None, :, :]) ** 2).sum(-1)
        near = (d2 < (1.35 * $SPACING) ** 2) & (r2 > $HORIZON ** 2)
        hits += near.sum() > 0 and g.attrs['contact_energy'] > 0
    assert hits > 0, 'the blocks never met'" grid.h5
}
