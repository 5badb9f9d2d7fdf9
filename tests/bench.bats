#!/usr/bin/env bats
# share/bench.sh (make bench) without running it: its argument checks, and
# share/stream.c, the roofline's bandwidth and flop-rate program, built and
# run small.  The bench itself takes minutes and has no test.

load test_helper

BENCH="$BATS_TEST_DIRNAME/../share/bench.sh"
STREAM_C="$BATS_TEST_DIRNAME/../share/stream.c"

setup() {
    cd "$BATS_TEST_TMPDIR"
}

@test "share/stream.c builds without warnings and prints positive rates" {
    run cc -std=gnu11 -Wall -Wextra -O3 -march=native -ffp-contract=fast -fopenmp "$STREAM_C" -o stream
    assert_success
    assert_output ""
    OMP_NUM_THREADS=1 run ./stream 8 2
    assert_success
    assert_line --index 2 "threads 1"
    # both rates positive and finite, and below what no machine reaches (1e13
    # B/s, 1e14 flop/s: a timer gone wrong); no lower bound, a slow or busy
    # machine is no failure (make bench measures speed, the tests do not)
    echo "$output" | awk '
        $1 == "triad_bytes_per_s" { b = $2 } $1 == "fma_flops_per_s" { f = $2 }
        END { exit !(b > 0 && b < 1e13 && f > 0 && f < 1e14) }'
}

@test "share/stream.c: bad arguments are usage errors" {
    cc -std=gnu11 -O2 -fopenmp "$STREAM_C" -o stream
    run ./stream 0
    assert_failure 2
    assert_output --partial "stream: error: MIB must be an integer"
    run ./stream 8 x
    assert_failure 2
    assert_output --partial "REPEATS"
    run ./stream 1 2 3
    assert_failure 2
    assert_output --partial "usage"
}

@test "bench.sh: bad BENCH_SKIP, BENCH_SIZES, BENCH_STEPS, BENCH_THREADS and BENCH_MPI_PAIRS are one-line errors" {
    BENCH_SKIP=lammps,foo run sh "$BENCH"
    assert_failure 1
    assert_output "bench.sh: error: BENCH_SKIP: unknown part 'foo' (lammps, lps, effects, roofline, scaling, threads, kernels, files, sweep, plate, frames, shattered, mesh, perturbed, mpi)"
    BENCH_SIZES="25k 1.6Q" run sh "$BENCH"
    assert_failure 1
    assert_output "bench.sh: error: BENCH_SIZES: '1.6Q' is not a particle count (25k, 1.6M, 40000)"
    BENCH_SIZES=500 run sh "$BENCH"
    assert_failure 1
    assert_output --partial "too small"
    BENCH_SIZES="" run sh "$BENCH"
    assert_failure 1
    assert_output --partial "BENCH_SIZES is empty"
    BENCH_STEPS=0 run sh "$BENCH"
    assert_failure 1
    assert_output --partial "BENCH_STEPS must be a positive integer"
    BENCH_THREADS=two run sh "$BENCH"
    assert_failure 1
    assert_output --partial "BENCH_THREADS must be a positive integer"
    BENCH_MPI_PAIRS=0 run sh "$BENCH"
    assert_failure 1
    assert_output --partial "BENCH_MPI_PAIRS must be a positive integer"
}

@test "pd-run --timing: a failure row, and the rows' shares add up to at most the wall time" {
    make_block
    run pd-run model.h5 "${RUN_OPTS[@]}" --dt 1e-7 --steps 20 --every 0 --timing -o run.h5
    assert_success
    assert_line --regexp '^  failure +[0-9.]+ s +[0-9.]+%$'
    for row in bonds contact "neighbour lists" indenter integration output; do
        assert_line --regexp "^  $row +[0-9.]+ s +[0-9.]+%\$"
    done
    # no row negative (failure's time is moved out of bonds', not copied)
    echo "$output" | awk '/^pd-run: timing/ { t = 1; next }
        t && / s +[0-9.-]+%$/ { n++; p = $NF; sub(/%/, "", p); s += p; if ($(NF - 2) < 0) bad = 1 }
        END { exit !(n == 7 && !bad && s <= 100.5) }' || {
        echo "$output" | sed -n '/timing/,$p'
        false
    }
}
