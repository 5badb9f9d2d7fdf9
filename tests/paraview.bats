#!/usr/bin/env bats
# ParaView's own reading of pd-dump2vtk's files: tests/paraview/check_dump.py
# runs under ParaView's pvbatch (Debian's paraview and python3-paraview),
# on an Xvfb server of its own for the rendering, and reads the compressed
# collection and a raw one (--compress 0) through ParaView's PVD reader: the
# frames' times, the named blocks (particles, indenter, projectile), the
# arrays bit for bit against the run file and tests/vtu.py, each sphere's
# radius, centre and area (ParaView's IntegrateVariables), and a picture of
# the last frame.  tests/paraview/check_xdmf.py opens a run file through
# pd-dump2vtk --xdmf's description with ParaView's XDMF Reader: every
# frame's time, points and arrays bit for bit against the run file.

load test_helper

# One X server for the file's tests, on a display it picks itself
# (-displayfd: it writes the number when it is ready to take clients).
# xvfb-run -a, started per check, lost the race for its server now and then
# (pvbatch: "bad X server connection", SIGABRT): measured 2 to 3 aborts in
# 6 tries on a 2-core Intel Xeon, against none in 8 on a server started once.
setup_file() {
    command -v pvbatch >/dev/null && command -v Xvfb >/dev/null || return 0
    local dfile="$BATS_FILE_TMPDIR/display"
    : >"$dfile"
    Xvfb -displayfd 9 -screen 0 1280x1024x24 -nolisten tcp 9>"$dfile" 3>&- \
        >"$BATS_FILE_TMPDIR/xvfb.log" 2>&1 &
    echo $! >"$BATS_FILE_TMPDIR/xvfb.pid"
    local _
    for _ in $(seq 100); do
        [ -s "$dfile" ] && break
        sleep 0.1
    done
}

teardown_file() {
    [ -s "$BATS_FILE_TMPDIR/xvfb.pid" ] && kill "$(cat "$BATS_FILE_TMPDIR/xvfb.pid")" 2>/dev/null
    return 0
}

setup() {
    command -v pvbatch >/dev/null && command -v Xvfb >/dev/null ||
        skip "pvbatch (paraview, python3-paraview) or Xvfb (xvfb) is not installed"
    [ -s "$BATS_FILE_TMPDIR/display" ] ||
        fail "Xvfb did not start: $(tail -n 3 "$BATS_FILE_TMPDIR/xvfb.log")"
    DISPLAY=":$(head -n 1 "$BATS_FILE_TMPDIR/display")"
    export DISPLAY
    cd "$BATS_TEST_TMPDIR"
}

# pv_check RUN.h5 KIND...: dump RUN.h5 compressed and raw, and check both in
# pvbatch; prints check_dump.py's "ok NFRAMES".
pv_check() {
    local run=$1 name
    shift
    name=$(basename "$run" .h5)
    pd-dump2vtk -q "$run" -o zlib && pd-dump2vtk -q --compress 0 "$run" -o raw || return 1
    grep -q 'compressor="vtkZLibDataCompressor"' "zlib/${name}_00000000.vtu" || return 1
    ! grep -q 'compressor=' "raw/${name}_00000000.vtu" || return 1
    pv_run "$BATS_TEST_DIRNAME/paraview/check_dump.py" "$run" "zlib/$name.pvd" "raw/$name.pvd" \
        last.png "$@"
}

# pv_run SCRIPT ARG...: pvbatch on a check script, its output in pv.out;
# prints the last line.  pvbatch's messages (its MPI start, Mesa) are not
# ours: only its last line counts.  Should pvbatch still abort (SIGABRT,
# "Aborted", before the script says anything), that crash, and only that
# one, gets one more try.  A check that fails exits 1 with its traceback
# and is not retried.
pv_run() {
    local try rc
    for try in 1 2; do
        rc=0
        pvbatch "$@" >pv.out 2>&1 || rc=$?
        [ "$rc" -eq 134 ] || [ "$(tail -n 1 pv.out)" = Aborted ] || break
        echo "pvbatch aborted (try $try)" >&2
    done
    tail -n 1 pv.out
    return "$rc"
}

@test "ParaView reads the compressed frames and the indenter's sphere of a run" {
    make_run "$BATS_TEST_TMPDIR" --steps 100 --every 25
    run -0 --separate-stderr pv_check run.h5 indenter
    assert_output "ok 5"
    [ -s last.png ]
}

@test "ParaView reads a run with a projectile and an indenter: both spheres, in order" {
    make_block
    pd-run -q --bulk-modulus "$BULK" --projectile sphere,0.005,0.005,0.0135,0.003,0.002,0,0,-60 \
        --indenter sphere,0.005,0.005,-0.0035,0.003,1e17,0,0,50 \
        --steps 100 --every 50 model.h5 -o both.h5
    run -0 --separate-stderr pv_check both.h5 indenter projectile
    assert_output "ok 3"
}

@test "ParaView reads a run without spheres: the particles alone" {
    # the make_block lattice with its top layer a set, pulled up at 1 m/s
    pd-lattice -q --spacing "$SPACING" --box -0.0005,0.0105,-0.0005,0.0105,-0.0005,0.0105 \
        --density "$DENSITY" --set top=box,-1,1,-1,1,0.0095,1 -o lattice.h5
    pd-bonds -q --horizon "$HORIZON" lattice.h5 -o model.h5
    pd-run -q --bulk-modulus "$BULK" --velocity-bc top,z,1 --steps 20 --every 10 model.h5 -o bare.h5
    run -0 --separate-stderr pv_check bare.h5
    assert_output "ok 3"
}

@test "ParaView's XDMF Reader opens a run in place (pd-dump2vtk --xdmf): every frame, bit for bit" {
    make_block
    pd-run -q "${RUN_OPTS[@]}" --steps 100 --every 25 --fields energy,stress model.h5 -o run.h5
    pd-dump2vtk -q --xdmf run.h5
    run -0 --separate-stderr pv_run "$BATS_TEST_DIRNAME/paraview/check_xdmf.py" run.h5 run.xdmf xdmf.png
    assert_output "ok 5"
    [ -s xdmf.png ]
    # from another folder, through the absolute path it names
    mkdir -p view
    pd-dump2vtk -q --xdmf run.h5 -o view/run.xdmf
    run -0 --separate-stderr pv_run "$BATS_TEST_DIRNAME/paraview/check_xdmf.py" run.h5 \
        view/run.xdmf xdmf.png
    assert_output "ok 5"
}

@test "ParaView's XDMF Reader opens the run of pd-run on 2 MPI ranks, in place" {
    local mpi_run=$BATS_TEST_DIRNAME/../mpi/bin/pd-run
    [ -x "$mpi_run" ] || skip "no MPI build (mpicc and libhdf5-openmpi-dev)"
    make_block
    OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 ASAN_OPTIONS=detect_leaks=0 \
        mpirun --oversubscribe --bind-to none -x ASAN_OPTIONS -np 2 "$mpi_run" -q \
        "${RUN_OPTS[@]}" --threads 1 --steps 100 --every 25 --fields energy,stress model.h5 \
        -o run.h5
    pd-dump2vtk -q --xdmf run.h5
    run -0 --separate-stderr pv_run "$BATS_TEST_DIRNAME/paraview/check_xdmf.py" run.h5 run.xdmf xdmf.png
    assert_output "ok 5"
    [ -s xdmf.png ]
}
