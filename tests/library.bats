#!/usr/bin/env bats
# libpd as a user's own program sees it: examples/library/impact.c sets up
# and runs a scene through pd.h alone (pd_scene_spec, pd_scene_resolve,
# pd_sim_*, pd_run_file_*).  It builds with -Wall -Wextra
# -Werror against lib/libpd.a, writes the run file the pipeline
# pd-lattice | pd-bonds | pd-run writes for the same scene, bit for bit but
# for the history (so pd-run holds no physics of its own), keeps the energy
# balance, and its file reads in the post-processing programs.

load test_helper

setup() {
    cd "$BATS_TEST_TMPDIR"
    cp "$BATS_TEST_DIRNAME/../examples/library/impact.c" \
        "$BATS_TEST_DIRNAME/../examples/library/Makefile" .
}

# the example's own Makefile, on the tree under test (with the sanitizers
# when libpd.a was built with them)
example() {
    make -s PD_TOP="$BATS_TEST_DIRNAME/.." \
        EXTRA="${PD_SANITIZE:+-fsanitize=address,undefined -fno-omit-frame-pointer}" "$@"
}

@test "library: a program over pd.h alone writes the pipeline's run file, bit for bit" {
    run -0 example impact
    run -0 ./impact run.h5
    assert_line --partial "step 200"
    run -0 example pipeline.h5
    run -0 "$PY" "$BATS_TEST_DIRNAME/samebits/h5same.py" pipeline.h5 run.h5
    assert_output ""
    # the comparison sees a difference where there is one
    run -1 "$PY" "$BATS_TEST_DIRNAME/samebits/h5same.py" pipeline.h5 lattice.h5
}

@test "library: the example's run keeps the energy balance and reads in pd-damage" {
    run -0 example impact
    run -0 ./impact run.h5
    # balance at each frame against the 25 J the sphere brings (5 g at 100 m/s)
    printf '%s\n' "$output" | awk '{ for (k = 1; k < NF; k++) if ($k == "balance") b = $(k + 1);
        if (b < 0.99 * 25 || b > 1.01 * 25) { print "off balance:", $0; bad = 1 } }
        END { exit bad }'
    [ "$(printf '%s\n' "$output" | grep -c '^step')" -eq 5 ]
    # the bonds it says broke are those pd-damage counts in each frame
    printf '%s\n' "$output" | awk '/^step/ { print $2, $NF }' >said.txt
    run -0 pd-damage -n run.h5
    printf '%s\n' "$output" | awk '!/^#/ { print $1, $3 }' >counted.txt
    run -0 diff said.txt counted.txt
    [ "$(tail -n 1 counted.txt | cut -d' ' -f2)" -gt 0 ]
}
