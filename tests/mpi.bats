#!/usr/bin/env bats
# pd-run on MPI ranks (the MPI build, mpi/bin/pd-run; lib/run/piece.c): the
# body is shared out among the ranks in whole blocks of its bond kernel, and
# every frame is bit for bit the one rank's, on 1 to 4 ranks, with any
# threads a rank, for the stencil and the bond list, the portable loops and
# the AVX-512 ones, fracture and lost particles.  Every rank writes its own
# rows of each frame and restart slot into the one run file (parallel
# HDF5), which is the one rank's, dataset for dataset.  Skipped where the MPI build cannot be made
# (no mpicc or no parallel HDF5); CI installs both (share/install-deps.sh).

load test_helper

MPI_RUN=$BATS_TEST_DIRNAME/../mpi/bin/pd-run
SAME=$BATS_TEST_DIRNAME/samebits/h5same.py

setup_file() {
    # mpirun refuses root without these (containers, CI)
    export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
}

setup() {
    if [ ! -x "$MPI_RUN" ]; then
        if command -v mpicc >/dev/null && pkg-config --exists hdf5-openmpi; then
            echo "mpicc and hdf5-openmpi are here but mpi/bin/pd-run is not built" >&2
            return 1
        fi
        skip "no MPI build (mpicc and libhdf5-openmpi-dev)"
    fi
    export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
    # built with the sanitizers (make check SANITIZE=1): Open MPI's own
    # allocations, held to the end, would be reported as leaks of every
    # rank (the serial suites check pd's code for leaks)
    if [ -n "${PD_SANITIZE:-}" ]; then
        export ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0"
    fi
    cd "$BATS_TEST_TMPDIR"
}

# mpi N ARG...: the MPI pd-run on N ranks (more ranks than cores allowed,
# unbound: this machine may have fewer cores than the test has ranks).
mpi() {
    local np=$1
    shift
    mpirun --oversubscribe --bind-to none ${ASAN_OPTIONS:+-x ASAN_OPTIONS} -np "$np" "$MPI_RUN" "$@"
}

# A disk hit hard enough by the indenter to break 70,000 of its bonds and
# throw fragments off (3771 particles on the lattice, 14 blocks of the
# stencil, 8 of the bond list), with contact (70 list builds); `perturbed`:
# its sites moved up to 0.1 spacing (a body of bond lists).
impact_body() {
    pd-lattice --spacing 0.001 --cylinder y,0,0,0.02,-0.0025,0 --density 2200 \
        ${1:+--perturb 1e-4} -o lat.h5 2>/dev/null
    pd-bonds --horizon 0.0030001 lat.h5 -o body.h5 2>/dev/null
    cat >impact.scene <<'EOF'
model pmb
c 1.6863e22
failure 0.0005,0.25
contact
indenter sphere,0,0.0051,0,0.005,1e17,0,-400,0
steps 400
every 50
EOF
}

# The disk of impact_body with two sets: `core` (a cylinder of 6 mm under
# the indenter) and `rim` (z > 12 mm), in bodys.h5; `perturbed` as there.
sets_body() {
    pd-lattice --spacing 0.001 --cylinder y,0,0,0.02,-0.0025,0 --density 2200 \
        ${1:+--perturb 1e-4} \
        --set core=cylinder,y,0,0,0.006,-1,1 --set rim=box,-1,1,-1,1,0.012,1 -q -o lats.h5
    pd-bonds --horizon 0.0030001 -q lats.h5 -o bodys.h5
}

# same_on_ranks RANKS THREADS ARG...: the run on one rank of the serial
# build, then on each count of RANKS with THREADS a rank: every dataset and
# attribute bit for bit the same.
same_on_ranks() {
    local ranks=$1 threads=$2
    shift 2
    pd-run --threads "$threads" -q "$@" -o one.h5
    for np in $ranks; do
        mpi "$np" --threads "$threads" -q "$@" -o "np$np.h5"
        run -0 "$PY" "$SAME" one.h5 "np$np.h5"
    done
}

@test "mpi: started without mpirun the MPI build is one rank, says so, and runs the serial bits" {
    impact_body
    run -0 "$MPI_RUN" --threads 1 --scene impact.scene body.h5 -o m.h5
    assert_line --partial "pd-run: 1 MPI rank x 1 thread"
    pd-run --threads 1 -q --scene impact.scene body.h5 -o one.h5
    run -0 "$PY" "$SAME" one.h5 m.h5
    # in a pipe, as the serial programs (MPI is not started without a launcher)
    pd-lattice --spacing 0.001 --cylinder y,0,0,0.02,-0.0025,0 --density 2200 -q -o - |
        "$BATS_TEST_DIRNAME/../mpi/bin/pd-bonds" --horizon 0.0030001 -q - |
        "$MPI_RUN" --threads 1 -q --scene impact.scene - -o pipe.h5
    run -0 "$PY" "$SAME" one.h5 pipe.h5
}

@test "mpi: the stencil on 1 to 4 ranks and on one block a rank, bit for bit the serial run's, fracture and all" {
    impact_body
    # 14 ranks: each owns one block of the 14 (odd and even ones first)
    same_on_ranks "1 2 3 4 14" 1 --scene impact.scene body.h5
    # the disk did break: the check saw fracture, not an elastic run
    run -0 "$PY" -c "
import h5py
with h5py.File('np4.h5') as f:
    last = f['frames'][sorted(f['frames'])[-1]]
    assert last.attrs['broken_bonds'] > 50000, last.attrs['broken_bonds']"
    run -0 mpi 2 --threads 1 --timing --scene impact.scene body.h5 -o log.h5
    assert_line --partial "pd-run: 2 MPI ranks x 1 thread"
    assert_line --partial "lattice stencil"
    assert_line --partial "every rank writes its rows of 'log.h5' (parallel HDF5)"
    # --timing: the ranks' least and most bonds' and ranks' time, rank 0's
    # among them
    local over bonds0
    over=$(printf '%s\n' "${lines[@]}" | grep "over the ranks: bonds")
    bonds0=$(printf '%s\n' "${lines[@]}" | awk '$1 == "bonds" { print $2 }')
    [ -n "$over" ] && [ -n "$bonds0" ]
    echo "$over" | awk -v b="$bonds0" '{ lo = $5; hi = $7; mlo = $11; mhi = $13 }
        END { exit !(lo > 0 && lo <= b + 0.0005 && b <= hi + 0.0005 && mlo > 0 && mlo <= mhi) }'
    # the frames' energy density and stress, each rank its own rows'
    same_on_ranks "3" 1 --scene impact.scene --fields energy,stress body.h5
}

@test "mpi: the bond list's AVX-512 rows and its portable loop, two threads a rank, one block a rank, material laws" {
    impact_body perturbed
    # 8 ranks: each owns one block of the bond list's 8
    same_on_ranks "2 3 4 8" 1 --scene impact.scene body.h5
    PD_NO_AVX512=1 same_on_ranks "3" 2 --scene impact.scene body.h5
    impact_body
    same_on_ranks "2" 2 --scene impact.scene --bond-list body.h5
    # material laws and an interface (their own c and s00 a bond: the list)
    pd-lattice --spacing 0.001 --cylinder y,0,0,0.02,-0.0025,0 --density 2200 \
        --material-region 2=box,0.005,1,-1,1,-1,1 -o latm.h5 2>/dev/null
    pd-bonds --horizon 0.0030001 latm.h5 -o bodym.h5 2>/dev/null
    same_on_ranks "2 3" 1 --scene impact.scene --material 1,K=2e10,s00=0.003 \
        --interface 1,2,K=14.9e9,s00=0.0002 bodym.h5
}

@test "mpi: a body of bond lists off any lattice: each rank reads its own rows' bonds alone, checked as one rank checks them" {
    impact_body perturbed
    run -0 mpi 3 --threads 1 --scene impact.scene --steps 60 body.h5 -o rows.h5
    assert_line --partial "each read with its own rows' particles and bonds alone"
    pd-run --threads 1 -q --scene impact.scene --steps 60 body.h5 -o one.h5
    run -0 "$PY" "$SAME" one.h5 rows.h5
    # a pre-crack in some ranks' rows alone: the model's /bonds/precrack
    # written again, each rank its rows'
    pd-bonds -q --horizon 0.0030001 --crack rect,0.015,-1,-0.0001,0,2,0,0.01,0,0 lat.h5 -o cr.h5
    same_on_ranks "3" 1 --scene impact.scene --steps 60 cr.h5
    run -0 "$PY" -c "
import h5py
with h5py.File('np3.h5') as f:
    assert f['bonds/precrack'][:].any()"
    # a restart of VES (its bond history) from 2 ranks on 3, each reading its
    # rows' bonds, their states and their history alone
    sed -i 's/^steps 400/steps 120/' impact.scene
    local ves="--model ves --bulk-modulus 14.9e9 --shear-modulus 11.2e9 --ves-lambda 0.5 --ves-tau 1e-6"
    # shellcheck disable=SC2086
    mpi 2 --threads 1 -q --scene impact.scene $ves body.h5 -o r.h5
    cp r.h5 r1.h5
    pd-run --threads 1 -q --restart r1.h5 --steps 100 -o one.h5
    run -0 mpi 3 --threads 1 --restart r.h5 --steps 100 -o np3.h5
    assert_line --partial "each read with its own rows' particles and bonds alone"
    run -0 "$PY" "$SAME" one.h5 np3.h5
    # a lattice's stencil is read whole (small), as the serial program does
    impact_body
    run -0 mpi 2 --threads 1 --scene impact.scene --steps 1 body.h5 -o grid.h5
    refute_line --partial "own rows' particles and bonds alone"
    # a bond broken on one side only, in the rows of the middle rank: the
    # serial program's one error line, exit 1 and no run file
    impact_body perturbed
    "$PY" -c "
import h5py
with h5py.File('body.h5', 'r+') as f:
    off = f['bonds/offset'][:]
    k = int(off[len(off) // 2])
    s = f['bonds/state']
    b = s[k // 8]
    s[k // 8] = b ^ (1 << (k % 8))"
    run -1 pd-run --threads 1 -q --scene impact.scene --steps 1 body.h5 -o bad.h5
    local line=${lines[0]}
    [[ "$line" == *"broken on one side only"* ]]
    run -1 mpi 3 --threads 1 -q --scene impact.scene --steps 1 body.h5 -o bad.h5
    assert_line "$line"
    [ ! -e bad.h5 ]
}

# refused_alike FILE ARG...: the serial program and 3 ranks refuse the run
# of FILE with the same one line, exit 1, and no run file.
refused_alike() {
    local file=$1
    shift
    run -1 pd-run --threads 1 -q --steps 1 "$@" "$file" -o bad.h5
    local line=${lines[0]}
    [ "${#lines[@]}" -eq 1 ] && [[ "$line" == "pd-run: error: "* ]]
    run -1 mpi 3 --threads 1 -q --steps 1 "$@" "$file" -o bad.h5
    assert_line "$line"
    [ ! -e bad.h5 ]
}

@test "mpi: a body of bond lists, each rank holding the window of particles its rows reach: sets, boundary conditions, the projectile, and bad input refused as one rank refuses it" {
    impact_body perturbed
    sets_body perturbed
    run -0 mpi 3 --threads 1 --scene impact.scene --steps 1 bodys.h5 -o w.h5
    assert_line --partial "each read with its own rows' particles and bonds alone"
    # sets' members on the ranks that hold them, each counted once
    same_on_ranks "2 3" 1 --scene impact.scene --no-failure rim --damping 1e4,core bodys.h5
    run -0 pd-run --threads 1 --scene impact.scene --no-failure rim --steps 1 bodys.h5 -o l1.h5
    local line
    line=$(printf '%s\n' "${lines[@]}" | grep -- "--no-failure rim: no bond of their")
    run -0 mpi 3 --threads 1 --scene impact.scene --no-failure rim --steps 1 bodys.h5 -o l3.h5
    assert_line "$line"
    sed '/^indenter/d' impact.scene >bc.scene
    same_on_ranks "3" 1 --scene bc.scene --displacement-bc core,y,-1e-5 --velocity-bc rim,z,5 \
        bodys.h5
    # the projectile: its default stiffness and first contact over the ranks
    local proj=--projectile=sphere,0,0.0051,0,0.005,0.01,0,-300,0
    same_on_ranks "3" 1 --scene bc.scene "$proj" --steps 200 bodys.h5
    run -0 pd-run --threads 1 --scene bc.scene "$proj" --steps 1 bodys.h5 -o l1.h5
    line=$(printf '%s\n' "${lines[@]}" | grep "first contact at")
    [ -n "$line" ]
    run -0 mpi 3 --threads 1 --scene bc.scene "$proj" --steps 1 bodys.h5 -o l3.h5
    assert_line "$line"
    # a restart from 2 ranks on 3: each its rows of the frame and the slot
    mpi 2 --threads 1 -q --scene impact.scene --steps 100 bodys.h5 -o r.h5
    cp r.h5 r1.h5
    pd-run --threads 1 -q --restart r1.h5 --steps 60 -o one.h5
    mpi 3 --threads 1 -q --restart r.h5 --steps 60 -o np3.h5
    run -0 "$PY" "$SAME" one.h5 np3.h5
    # bad input found in some rank's rows alone: the serial line
    refused_alike bodys.h5 --scene impact.scene \
        --projectile=sphere,0,0.004,0,0.005,0.01,0,-300,0
    refused_alike bodys.h5 --scene impact.scene --material 3,c=1e22
    "$PY" -c "
import h5py, numpy
with h5py.File('bodys.h5') as f, h5py.File('badset.h5', 'w') as g:
    for k in f: f.copy(k, g)
    for a, v in f.attrs.items(): g.attrs[a] = v
    n = len(g['particles/id'])
    del g['sets/rim']
    g['sets/rim'] = [n // 2, n + 7]
with h5py.File('bodys.h5') as f, h5py.File('dupid.h5', 'w') as g:
    for k in f: f.copy(k, g)
    for a, v in f.attrs.items(): g.attrs[a] = v
    ids = g['particles/id']
    ids[len(ids) - 3] = ids[len(ids) // 2]
with h5py.File('bodys.h5') as f, h5py.File('badvol.h5', 'w') as g:
    for k in f: f.copy(k, g)
    for a, v in f.attrs.items(): g.attrs[a] = v
    g['particles/volume'][len(g['particles/volume']) * 5 // 6] = -1
for name, ds, extra in (('longstate.h5', 'state', 255), ('longlen.h5', 'length', 1e-3)):
    with h5py.File('bodys.h5') as f, h5py.File(name, 'w') as g:
        for k in f: f.copy(k, g)
        for a, v in f.attrs.items(): g.attrs[a] = v
        v = g['bonds'][ds][()]
        del g['bonds'][ds]
        g['bonds'][ds] = numpy.append(v, numpy.array([extra], dtype=v.dtype))"
    refused_alike badset.h5 --scene impact.scene --damping 1e4,rim
    # a dataset of the bonds longer than /bonds/offset says, though no
    # rank's rows reach its end
    refused_alike longstate.h5 --scene impact.scene
    refused_alike longlen.h5 --scene impact.scene
    refused_alike dupid.h5 --scene impact.scene
    refused_alike badvol.h5 --scene impact.scene
}

@test "mpi: a lattice body, each rank reading its own window of the stencil: sets, a pre-crack, the projectile, and a file the windows cannot vouch for read whole, refused as one rank refuses it" {
    impact_body
    sets_body
    run -0 mpi 3 --threads 1 --scene impact.scene --steps 1 bodys.h5 -o w.h5
    assert_line --partial "each read as its own window of the lattice"
    assert_line --partial "lattice stencil"
    same_on_ranks "2 3" 1 --scene impact.scene --no-failure rim --damping 1e4,core bodys.h5
    sed '/^indenter/d' impact.scene >bc.scene
    local proj=--projectile=sphere,0,0.0051,0,0.005,0.01,0,-300,0
    same_on_ranks "3" 1 --scene bc.scene "$proj" --displacement-bc core,y,-1e-5 --steps 200 \
        bodys.h5
    run -0 pd-run --threads 1 --scene bc.scene "$proj" --steps 1 bodys.h5 -o l1.h5
    local line
    line=$(printf '%s\n' "${lines[@]}" | grep "first contact at")
    [ -n "$line" ]
    run -0 mpi 3 --threads 1 --scene bc.scene "$proj" --steps 1 bodys.h5 -o l3.h5
    assert_line "$line"
    # a pre-crack across the planes where the pieces meet: /bonds/precrack
    # written by every rank's rows
    pd-bonds --horizon 0.0030001 -q --crack rect,-0.01,-0.003,0.0005,0.02,0,0,0,0.004,0 \
        lat.h5 -o crack.h5
    same_on_ranks "2 3" 1 --scene impact.scene crack.h5
    run -0 "$PY" -c "
import h5py
with h5py.File('np3.h5') as f:
    assert f['bonds'].attrs['form'] == 'stencil' and 'precrack' in f['bonds']"
    # files the windows cannot vouch for: read whole, the serial line
    "$PY" -c "
import h5py
def copy(name):
    f = h5py.File('body.h5'); g = h5py.File(name, 'w')
    for k in f: f.copy(k, g)
    for a, v in f.attrs.items(): g.attrs[a] = v
    return g
with copy('asym.h5') as g: # a bond broken on one side only
    s = g['bonds/state']; k = len(s) * 2 // 3; s[k] = s[k] & 0xf7
with copy('count.h5') as g:
    g['bonds'].attrs['count'] = g['bonds'].attrs['count'] + 2
with copy('off.h5') as g: # a particle a third of a spacing off its site
    x = g['particles/position']; k = len(x) * 5 // 6; x[k, 0] = x[k, 0] + 3e-4
with copy('badcrack.h5') as g: # pre-cracked but intact
    n = g['bonds'].attrs['count']
    g['bonds/precrack'] = bytearray((n + 7) // 8); g['bonds/precrack'][len(g['bonds/state']) // 3] = 1
with copy('order.h5') as g: # two rows' sites swapped: off the stencil's lattice order
    x = g['particles/position']; n = len(x); a, b = x[10], x[n - 10]; x[10] = b; x[n - 10] = a"
    refused_alike asym.h5 --scene impact.scene
    refused_alike count.h5 --scene impact.scene
    refused_alike off.h5 --scene impact.scene
    refused_alike badcrack.h5 --scene impact.scene
    # the serial program walks the rows out of order as lists; MPI ranks
    # need them in lattice order, and say so
    run -1 mpi 3 --threads 1 -q --steps 1 --scene impact.scene order.h5 -o bad.h5
    assert_line "pd-run: error: on MPI ranks the particles must be in lattice order, as pd-bonds writes them"
}

@test "mpi: lost particles, taken on whichever rank owns them, the same bits" {
    impact_body
    same_on_ranks "2 4" 1 --scene impact.scene --lost-margin 0.002 body.h5
    # particles were lost, with their kinetic energy
    run -0 "$PY" -c "
import h5py
with h5py.File('np4.h5') as f:
    last = f['frames'][sorted(f['frames'])[-1]]
    assert last.attrs['lost_particles'] > 50 and last.attrs['lost_energy'] > 0, dict(last.attrs)"
}

@test "mpi: more ranks than the body has blocks is one line and exit 1; a model on stdin or a run file to stdout is a usage error" {
    impact_body
    run -2 mpi 2 --scene impact.scene - -o c.h5 <body.h5
    assert_output --partial "the model must be a file"
    # the ranks write the run file together: a regular file, not stdout
    run -2 mpi 2 --scene impact.scene body.h5 -o /dev/null
    assert_output --partial "the run file must be a regular file, which the ranks write together (parallel HDF5), not '/dev/null'"
    run -2 mpi 2 --scene impact.scene body.h5
    assert_output --partial "not '-'"
    [ ! -e c.h5 ]
    # more ranks than the body has blocks
    run -1 mpi 15 --scene impact.scene body.h5 -o c.h5
    assert_output --partial "cut into 14 blocks and each of the 15 MPI ranks needs one: run it on at most 14 ranks"
    [ "$(grep -c 'pd-run: error' <<<"$output")" -eq 1 ]
    [ ! -e c.h5 ]
}

@test "mpi: --restart goes on from a run of N ranks on M ranks (M = 1 too), bit for bit" {
    impact_body
    sed -i 's/^steps 400/steps 200/' impact.scene
    # 200 steps with fracture and lost particles on 2 ranks, then 200 more
    mpi 2 --threads 1 -q --scene impact.scene --lost-margin 0.002 body.h5 -o r.h5
    cp r.h5 r1.h5
    cp r.h5 r3.h5
    pd-run --threads 1 -q --restart r1.h5 --steps 200 -o one.h5
    mpi 3 --threads 1 -q --restart r3.h5 --steps 200 -o np3.h5
    run -0 "$PY" "$SAME" one.h5 np3.h5
    # in place, on 4 ranks: the run file goes on
    mpi 4 --threads 1 -q --restart r.h5 --steps 200
    run -0 "$PY" "$SAME" one.h5 r.h5
    run -0 "$PY" -c "
import h5py
with h5py.File('r.h5') as f:
    steps = sorted(int(g.attrs['step']) for g in f['frames'].values())
    assert steps[-1] == 400 and f['frames'][sorted(f['frames'])[-1]].attrs['lost_particles'] > 0, steps"
}

@test "mpi: contact across the ranks: a plate thrown into another meets particles of other ranks' pieces, the same bits" {
    # two plates 9 mm apart along the axis the ranks cut; the indenter
    # throws the first (rank 0's) into the second at 400 m/s, shattering
    # both: on 6 ranks the lists of a rank take partners from beyond its
    # piece, whose positions come from their owners at every step
    pd-lattice --spacing 0.001 --box 0,0.045,0,0.003,0,0.005 --box 0,0.045,0,0.003,0.014,0.040 \
        --density 2200 -o lat.h5 2>/dev/null
    pd-bonds --horizon 0.0030001 lat.h5 -o two.h5 2>/dev/null
    local scene=(--model pmb --c 1.6863e22 --failure 0.0005,0.25 --contact
        --indenter sphere,0.0225,0.0015,-0.0205,0.02,1e17,0,0,400 --steps 600 --every 100)
    pd-run --threads 1 -q "${scene[@]}" two.h5 -o one.h5
    run -0 mpi 6 --threads 1 "${scene[@]}" two.h5 -o np6.h5
    assert_line --regexp "contact across the ranks: at most [1-9][0-9]* partners of a rank's list from beyond its piece"
    run -0 "$PY" "$SAME" one.h5 np6.h5
}

@test "mpi: contact and restart: a run with contact goes on from 2 ranks on 4, bit for bit" {
    impact_body
    sed -i 's/^steps 400/steps 200/' impact.scene
    mpi 2 --threads 1 -q --scene impact.scene body.h5 -o r.h5
    cp r.h5 r1.h5
    pd-run --threads 1 -q --restart r1.h5 --steps 200 -o one.h5
    mpi 4 --threads 1 -q --restart r.h5 --steps 200 -o np4.h5
    run -0 "$PY" "$SAME" one.h5 np4.h5
}

@test "mpi: LPS on the stencil and the list, VES and EPS (ghost dilatations, plastic history), with contact, the same bits" {
    local K=14.9e9 G=11.2e9
    impact_body
    sed -i 's/^steps 400/steps 300/' impact.scene
    same_on_ranks "2 3" 1 --scene impact.scene --model lps --bulk-modulus $K --shear-modulus $G body.h5
    run -0 mpi 2 --threads 1 --scene impact.scene --model lps --bulk-modulus $K --shear-modulus $G \
        --steps 2 body.h5 -o log.h5
    assert_line --partial "lattice stencil"
    same_on_ranks "2" 1 --scene impact.scene --model ves --bulk-modulus $K --shear-modulus $G \
        --ves-lambda 0.5 --ves-tau 1e-6 body.h5
    # EPS yields under the indenter, where the ranks' pieces meet, and its
    # portable list takes the contact of bonded pairs too: lists of many
    # pairs in contact at once, in the one rank's order
    same_on_ranks "2 3" 1 --scene impact.scene --model eps --bulk-modulus $K --shear-modulus $G \
        --yield-stress 5e6 body.h5
    impact_body perturbed
    sed -i 's/^steps 400/steps 300/' impact.scene
    # the stress of a piece's rows takes its ghosts' dilatations from their owners
    same_on_ranks "3" 2 --scene impact.scene --model lps --bulk-modulus $K --shear-modulus $G \
        --fields energy,stress body.h5
}

@test "mpi: VES and EPS go on from a restart on other ranks, their bond history and all" {
    local K=14.9e9 G=11.2e9
    impact_body
    sed -i 's/^steps 400/steps 150/' impact.scene
    for model in "ves --ves-lambda 0.5 --ves-tau 1e-6" "eps --yield-stress 5e6"; do
        # shellcheck disable=SC2086
        mpi 2 --threads 1 -q --scene impact.scene --model $model --bulk-modulus $K \
            --shear-modulus $G body.h5 -o r.h5
        cp r.h5 r1.h5
        pd-run --threads 1 -q --restart r1.h5 --steps 150 -o one.h5
        mpi 3 --threads 1 -q --restart r.h5 --steps 150 -o np3.h5
        run -0 "$PY" "$SAME" one.h5 np3.h5
    done
}

@test "mpi: the projectile, pushed back by the particles of every rank, the same bits (restart too)" {
    impact_body
    sed -i '/^indenter/d; s/^steps 400/steps 200/' impact.scene
    local proj=--projectile=sphere,0,0.0051,0,0.005,0.01,0,-300,0
    same_on_ranks "2 3" 1 --scene impact.scene "$proj" body.h5
    mv np2.h5 r.h5
    cp one.h5 r1.h5
    pd-run --threads 1 -q --restart r1.h5 --steps 100 -o a.h5
    mpi 3 --threads 1 -q --restart r.h5 --steps 100 -o b.h5
    run -0 "$PY" "$SAME" a.h5 b.h5
}

# rank_pid R: the pid of MPI rank R of this test's pd-run job (Open MPI puts
# each rank's number into its environment; PD_TEST_JOB, this test's own
# folder, tells this job from any other on the machine)
rank_pid() {
    local p env
    for p in $(pgrep -f "$MPI_RUN"); do
        env=$(tr '\0' '\n' <"/proc/$p/environ" 2>/dev/null) || continue
        if grep -qx "OMPI_COMM_WORLD_RANK=$1" <<<"$env" &&
            grep -qxF "PD_TEST_JOB=$BATS_TEST_TMPDIR" <<<"$env"; then
            echo "$p"
            return 0
        fi
    done
    return 1
}

@test "mpi: a rank killed mid-run (SIGKILL) leaves a run file of whole frames that every reader takes" {
    impact_body
    sed -i "s/^steps 400/steps 40000/; s/^every 50/every 20/" impact.scene
    PD_TEST_JOB=$BATS_TEST_TMPDIR mpirun --oversubscribe --bind-to none -x PD_TEST_JOB \
        ${ASAN_OPTIONS:+-x ASAN_OPTIONS} -np 2 "$MPI_RUN" --threads 1 -q --scene impact.scene \
        body.h5 -o k.h5 &
    local job=$! pid=''
    # the run file published (pd-run lays out its frames first), then a
    # few seconds of steps and frames (the file is locked while it is
    # written: nothing reads it before the kill)
    for _ in $(seq 1200); do
        [ -e k.h5 ] && pid=$(rank_pid 1) && break
        sleep 0.1
    done
    [ -n "$pid" ] || { kill -9 "$job" 2>/dev/null; false; }
    sleep 3
    kill -9 "$pid"
    run wait "$job"
    [ "$status" -ne 0 ] # the job ended with its rank
    for _ in $(seq 300); do # and mpirun takes the other rank down
        rank_pid 0 >/dev/null || break
        sleep 0.1
    done
    ! rank_pid 0
    rm -f .k.h5.tmp.*
    run -0 pd-damage -n k.h5
    run -0 pd-dump2vtk -q --xdmf k.h5 -o k.xdmf
    run -0 "$PY" -c "
import h5py
with h5py.File('k.h5') as f:
    frames = [g for g in f['frames'].values() if g.attrs['complete'] == 1]
    steps = sorted(int(g.attrs['step']) for g in frames)
    assert len(steps) >= 3 and steps == list(range(0, 20 * len(steps), 20)), steps"
}

@test "mpi: damping (every particle, and a set's) and --no-failure sets, the same bits" {
    impact_body
    sets_body
    same_on_ranks "2 3" 1 --scene impact.scene --damping 3e4 bodys.h5
    same_on_ranks "3" 1 --scene impact.scene --damping 3e4,rim bodys.h5
    same_on_ranks "2 3" 1 --scene impact.scene --no-failure rim --damping 1e4,core bodys.h5
    # the log counts the set's particles over the pieces, each once
    run -0 pd-run --threads 1 --scene impact.scene --no-failure rim --steps 1 bodys.h5 -o l1.h5
    local line
    line=$(printf '%s\n' "${lines[@]}" | grep -- "--no-failure rim: no bond of their")
    [ -n "$line" ]
    run -0 mpi 3 --threads 1 --scene impact.scene --no-failure rim --steps 1 bodys.h5 -o l3.h5
    assert_line "$line"
    run -0 "$PY" -c "
import h5py
with h5py.File('np3.h5') as f:
    last = f['frames'][sorted(f['frames'])[-1]]
    assert last.attrs['damped_energy'] > 0, dict(last.attrs)"
}

@test "mpi: boundary conditions on sets (held velocity and displacement, body forces) and --relax, the same bits, series and all" {
    impact_body
    sets_body
    sed -i '/^indenter/d' impact.scene
    same_on_ranks "2 3" 1 --scene impact.scene --displacement-bc core,y,-1e-5 \
        --velocity-bc rim,z,5 bodys.h5
    same_on_ranks "3" 1 --scene impact.scene --body-force core,y,-1e12 bodys.h5
    # a plate pulled apart by load steps, relaxed, breaking (the ranks cut
    # it across the pull)
    pd-lattice --spacing 0.001 --box 0,0.03,0,0.003,0,0.035 --density 2200 \
        --set left=box,-1,0.0025,-1,1,-1,1 --set right=box,0.0275,1,-1,1,-1,1 -q -o barl.h5
    pd-bonds --horizon 0.0030001 -q barl.h5 -o bar.h5
    same_on_ranks "2 3" 1 --bulk-modulus 14e9 --relax --dt 1 --velocity-bc left,x,0 \
        --velocity-bc right,x,2e-6 --steps 4 --every 1 --failure 0.0003,0 bar.h5
    run -0 "$PY" -c "
import h5py
with h5py.File('np3.h5') as f:
    last = f['frames'][sorted(f['frames'])[-1]]
    assert last.attrs['broken_bonds'] > 0, dict(last.attrs)"
}

@test "mpi: on 2 and 3 ranks pd-run agrees with LAMMPS peri/pmb (the agreement test's disk, failure + contact + indenter)" {
    command -v lmp >/dev/null || skip "lmp (LAMMPS with the PERI package) is not installed"
    local tools=$BATS_TEST_DIRNAME/lammps c=1.6863e22 fail=0.0005,0.25 ind=sphere,0,0.0050,0,0.005,1e17,0,-100,0
    pd-lattice --spacing 0.0005 --cylinder y,0,0,0.006,-0.0025,0 --density 2200 -q -o lat.h5
    pd-bonds --horizon 0.0015001 -q lat.h5 -o model.h5
    "$PY" "$tools/pd2lmp.py" model.h5 -d data.lmp -i in.lmp --dump dump.lmp --c "$c" \
        --horizon 0.0015001 --failure "$fail" --dt 1e-7 --steps 100 --every 50 --indenter "$ind"
    lmp -in in.lmp -log none >lmp.out 2>&1
    for np in 2 3; do
        mpi "$np" --threads 1 -q --c "$c" --failure "$fail" --dt 1e-7 --contact --indenter "$ind" \
            --steps 100 --every 50 model.h5 -o "np$np.h5"
        pd-damage "np$np.h5" >/dev/null
        for step in 50 100; do
            run -0 "$PY" "$tools/compare.py" "np$np.h5" dump.lmp --step "$step"
            assert_line --partial "OK"
        done
        run -0 "$PY" "$tools/compare.py" "np$np.h5" dump.lmp --step 100 --min-damaged 100
    done
}

@test "mpi: mpirun pd-bonds builds an irregular body's families on 1 to 4 ranks, each writing its rows: the serial file, pre-cracks and all" {
    local MPI_BONDS=$BATS_TEST_DIRNAME/../mpi/bin/pd-bonds
    pd-lattice --spacing 0.001 --cylinder y,0,0,0.02,-0.0025,0 --density 2200 \
        --perturb 1e-4 --set core=cylinder,y,0,0,0.006,-1,1 -q -o plat.h5
    # two pre-cracks: one across the rows of every rank, one along them
    local cracks=(--crack rect,0.0005,-0.003,-0.021,0,0.004,0,0,0,0.021
        --crack rect,-0.021,-0.003,0.0052,0.01,0,0,0,0.004,0)
    pd-bonds --horizon 0.0030001 "${cracks[@]}" plat.h5 -o one.h5 2>one.log
    for np in 1 2 3 4; do
        run -0 mpirun --oversubscribe --bind-to none ${ASAN_OPTIONS:+-x ASAN_OPTIONS} -np "$np" \
            "$MPI_BONDS" --horizon 0.0030001 "${cracks[@]}" plat.h5 -o "np$np.h5"
        run -0 "$PY" "$SAME" one.h5 "np$np.h5"
    done
    # the log's figures are the body's, summed over the ranks
    run -0 mpirun --oversubscribe --bind-to none ${ASAN_OPTIONS:+-x ASAN_OPTIONS} -np 3 \
        "$MPI_BONDS" --horizon 0.0030001 "${cracks[@]}" plat.h5 -o np3.h5
    assert_line --partial "families built by 3 MPI ranks, each writing its rows' (parallel HDF5)"
    [ "$(grep -v 'MPI ranks' <<<"$output")" = "$(cat one.log)" ]
    # the pre-cracks did cut bonds of several ranks' rows
    run -0 "$PY" -c "
import h5py, numpy as np
with h5py.File('np3.h5') as f:
    bits = np.unpackbits(f['bonds/precrack'][:], bitorder='little')[:f['bonds'].attrs['count']]
    off = f['bonds/offset'][:]
    rows = np.searchsorted(off, np.nonzero(bits)[0], side='right') - 1
    n = len(off) - 1
    assert bits.sum() > 1000 and len(set(rows * 3 // n)) >= 2, (bits.sum(), set(rows * 3 // n))"
    # a lattice body: its stencil, as one rank finds it
    impact_body
    run -0 mpirun --oversubscribe --bind-to none ${ASAN_OPTIONS:+-x ASAN_OPTIONS} -np 2 \
        "$MPI_BONDS" --horizon 0.0030001 lat.h5 -o s2.h5
    run -0 "$PY" "$SAME" body.h5 s2.h5
    # two particles at one place: the serial program's one line, no file
    "$PY" -c "
import h5py
with h5py.File('plat.h5', 'r+') as f:
    x = f['particles/position']; x[1000] = x[3000]"
    run -1 --separate-stderr pd-bonds --horizon 0.0030001 plat.h5 -o dup.h5
    local line=$stderr
    for np in 2 3; do
        run -1 --separate-stderr mpirun --oversubscribe --bind-to none \
            ${ASAN_OPTIONS:+-x ASAN_OPTIONS} -np "$np" "$MPI_BONDS" --horizon 0.0030001 plat.h5 -o dup.h5
        [ "$(grep -c 'pd-bonds: error' <<<"$stderr")" -eq 1 ]
        grep -qxF "$line" <<<"$stderr"
    done
    [ ! -e dup.h5 ] && ! ls .dup.h5.* 2>/dev/null
    # files, not pipes, on several ranks
    run -2 mpirun --oversubscribe --bind-to none -np 2 "$MPI_BONDS" --horizon 0.003 plat.h5
    assert_output --partial "on several MPI ranks the output must be a regular file"
    run -2 mpirun --oversubscribe --bind-to none -np 2 "$MPI_BONDS" --horizon 0.003 - -o x.h5 <plat.h5
    assert_output --partial "on several MPI ranks the input must be a file, not '-'"
    [ ! -e x.h5 ]
}
