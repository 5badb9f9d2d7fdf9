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
    printf '%s\n' "$output" | awk '/^step/ { for (k = 1; k < NF; k++) if ($k == "balance") b = $(k + 1);
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

@test "library: the example at a spacing of its own: m = 3, G0 held, to 23 us, and its log" {
    run -0 example impact
    run -0 --separate-stderr ./impact run.h5 0.001
    # the last frame is at the end time, the balance within 1% of 25 J
    last=$(printf '%s\n' "$output" | grep '^step' | tail -n 1)
    [ "$(printf '%s\n' "$last" | awk '{ print $4 }')" = "2.3000e-05" ]
    printf '%s\n' "$last" | awk '{ for (k = 1; k < NF; k++) if ($k == "balance") b = $(k + 1);
        exit !(b > 0.99 * 25 && b < 1.01 * 25) }'
    # its log: the threads and what the steps cost, as pd-run's (share/pdcost.py reads it)
    printf '%s\n' "$stderr" | grep -Eq '^impact: [0-9]+ threads$'
    printf '%s\n' "$stderr" | grep -Eq '^impact: [0-9]+ steps in [0-9.]+ s \([0-9.e+]+ bond updates/s\)$'
    # the body and the scene the spacing says: 11 x 11 x 5 sites, horizon
    # 3.0002 dx, s00 from G0 = 9 K (1.5 mm) 0.0005^2 / 5
    "$PY" - <<'PY'
import h5py, math
with h5py.File("run.h5", "r") as f:
    assert f["particles/position"].shape[0] == 11 * 11 * 5
    h = f["bonds"].attrs["horizon"]
    assert abs(h - 0.0030002) < 1e-12, h
    s00 = float(f["scene"].attrs["s00"])
    want = math.sqrt(5 * (9 * 14.9e9 * 0.0015 * 0.0005 ** 2 / 5) / (9 * 14.9e9 * h))
    assert abs(s00 / want - 1) < 1e-9, (s00, want)
PY
    # a spacing that is none, or a word too many: usage, exit 2
    run -2 ./impact run.h5 0.001x
    assert_output --partial "usage: impact"
    run -2 ./impact run.h5 -1
    run -2 ./impact run.h5 0.001 extra
}
