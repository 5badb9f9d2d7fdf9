#!/usr/bin/env bats
# pd-run's threads when runs share the cores (cmd/cli.h, settle_threads):
# with neither OMP_WAIT_POLICY nor GOMP_SPINCOUNT in its environment,
# pd-run runs itself again with GOMP_SPINCOUNT=1000, so that idle threads
# sleep soon instead of spinning on cores another run needs; the user's
# own setting wins; the bits do not depend on it.  (The speed of runs
# sharing the cores is make bench's, not a test's.)

load test_helper

setup() {
    cd "$BATS_TEST_TMPDIR"
    make_block
}

# run_env ENV... -- PD-RUN OPTION...: pd-run on model.h5 under exactly the
# OpenMP variables given (the others unset), its log in log.txt.
run_env() {
    local vars=()
    while [ "$1" != -- ]; do
        vars+=("$1")
        shift
    done
    shift
    env -u OMP_WAIT_POLICY -u GOMP_SPINCOUNT "${vars[@]}" \
        pd-run --bulk-modulus "$BULK" --steps 20 --every 10 --threads 2 "$@" 2>log.txt
}

@test "without a setting pd-run runs with GOMP_SPINCOUNT=1000 and says so" {
    run_env -- model.h5 -o a.h5
    run grep -x 'pd-run: 2 threads, GOMP_SPINCOUNT=1000' log.txt
    assert_success
}

@test "the user's GOMP_SPINCOUNT or OMP_WAIT_POLICY wins" {
    run_env GOMP_SPINCOUNT=77 -- model.h5 -o a.h5
    run grep -x 'pd-run: 2 threads, GOMP_SPINCOUNT=77' log.txt
    assert_success
    run_env OMP_WAIT_POLICY=active -- model.h5 -o b.h5
    run grep -x 'pd-run: 2 threads, OMP_WAIT_POLICY=active' log.txt
    assert_success
}

@test "the run's bits do not depend on the wait setting" {
    run_env -- model.h5 -o a.h5
    run_env OMP_WAIT_POLICY=passive -- model.h5 -o b.h5
    run_env GOMP_SPINCOUNT=0 -- model.h5 -o c.h5
    run "$PY" "$BATS_TEST_DIRNAME/samebits/h5same.py" a.h5 b.h5 a.h5 c.h5
    assert_success
    assert_output ''
}

@test "the program libgomp loads has GOMP_SPINCOUNT in its own environment" {
    # pd-run reads the model from a pipe that stays empty until its
    # process image (/proc/PID/environ: the environment it was started
    # with, not one changed later by setenv) is seen to hold the setting;
    # the test holds the pipe open on fd 8 (bats has 3), pd-run neither
    mkfifo in.pipe
    exec 8<>in.pipe
    env -u OMP_WAIT_POLICY -u GOMP_SPINCOUNT \
        pd-run --bulk-modulus "$BULK" --steps 2 - -o r.h5 <in.pipe 2>log.txt 3>&- 8>&- &
    local pid=$! seen=0
    for _ in $(seq 100); do
        if tr '\0' '\n' <"/proc/$pid/environ" 2>/dev/null | grep -qx 'GOMP_SPINCOUNT=1000'; then
            seen=1
            break
        fi
        sleep 0.05
    done
    cat model.h5 >&8
    exec 8>&-
    wait "$pid"
    [ "$seen" = 1 ] || fail "pd-run's process image never held GOMP_SPINCOUNT=1000"
    [ -s r.h5 ]
}
