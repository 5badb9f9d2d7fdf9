#!/usr/bin/env bats
# share/bench.sh (make bench) without running it: its argument checks, and
# share/stream.c, the roofline's bandwidth, flop-rate and divider program, built and
# run small, and share/passes (make check builds it), the timing of the
# bond kernel alone, on a small model.  The bench itself takes minutes and
# has no test.

load test_helper

BENCH="$BATS_TEST_DIRNAME/../share/bench.sh"
STREAM_C="$BATS_TEST_DIRNAME/../share/stream.c"
PASSES="$BATS_TEST_DIRNAME/../share/passes"

setup() {
    cd "$BATS_TEST_TMPDIR"
}

@test "share/stream.c builds without warnings and prints positive rates" {
    # the bench's flags (share/bench.sh; -mprefer-vector-width=512 where
    # the compiler takes it, as there)
    wide=-mprefer-vector-width=512
    cc -march=native "$wide" -x c - -o wide <<<'int main(void) { return 0; }' 2>/dev/null || wide=
    run cc -std=gnu11 -Wall -Wextra -O3 -march=native $wide -ffp-contract=fast -fno-math-errno \
        -fopenmp "$STREAM_C" -o stream -lm
    assert_success
    assert_output ""
    OMP_NUM_THREADS=1 run ./stream 8 2
    assert_success
    assert_line --index 3 "threads 1"
    # the three rates positive and finite, and below what no machine reaches
    # (1e13 B/s, 1e14 flop/s, 1e13 square roots and divisions a second: a
    # timer gone wrong), and the divider's well below the FMA rate (each
    # pair takes a core several cycles, an FMA a fraction of one); no lower
    # bound, a slow or busy machine is no failure (make bench measures
    # speed, the tests do not)
    echo "$output" | awk '
        $1 == "triad_bytes_per_s" { b = $2 } $1 == "fma_flops_per_s" { f = $2 }
        $1 == "sqrt_div_per_s" { d = $2 }
        END { exit !(b > 0 && b < 1e13 && f > 0 && f < 1e14 && d > 0 && d < 1e13 && d < f / 4) }'
}

@test "share/passes times the bond passes of a model: its counts, best <= median" {
    [ -x "$PASSES" ] || fail "share/passes is not built (make share/passes)"
    pd-lattice -q --spacing 0.001 --density 2200 --box 0,0.02,0,0.006,0,0.005 -o lattice.h5
    pd-bonds -q --horizon 0.0030001 lattice.h5 -o model.h5
    n=$(h5ls model.h5/particles/id | sed -n 's/.*Dataset {\([0-9]*\).*/\1/p')
    b=$(h5dump -a /bonds/count model.h5 | sed -n 's/^ *(0): \([0-9]*\) *$/\1/p')
    run "$PASSES" model.h5 2 5
    assert_success
    assert_output --regexp "^kernel stencil particles $n bonds $((b / 2)) best [0-9.]+ median [0-9.]+\$"
    echo "$output" | awk '{ exit !($8 > 0 && $8 <= $10 && $10 < 10) }'
    # a body off the lattice: the bond list
    pd-lattice -q --spacing 0.001 --density 2200 --box 0,0.02,0,0.006,0,0.005 --perturb 1e-4 \
        -o perturbed.h5
    pd-bonds -q --horizon 0.0030001 perturbed.h5 -o p-model.h5
    run "$PASSES" p-model.h5 1 3
    assert_success
    assert_output --regexp "^kernel list particles $n bonds [0-9]+ best "
}

@test "share/passes: bad arguments are usage errors, a missing model one line" {
    [ -x "$PASSES" ] || fail "share/passes is not built (make share/passes)"
    run "$PASSES" model.h5 2
    assert_failure 2
    assert_output --partial "usage: passes MODEL.h5 THREADS PASSES"
    run "$PASSES" model.h5 0 5
    assert_failure 2
    run --separate-stderr "$PASSES" nothing.h5 1 5
    assert_failure 1
    [ "${#stderr_lines[@]}" -eq 1 ]
    [[ "$stderr" == "passes: nothing.h5: "* ]]
}

@test "share/stream.c: bad arguments are usage errors" {
    cc -std=gnu11 -O2 -fopenmp "$STREAM_C" -o stream -lm
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
