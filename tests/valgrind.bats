#!/usr/bin/env bats
# The whole pipeline under valgrind's memcheck: no invalid access, no
# uninitialised value used, no leak (definite or indirect), in every
# program.  Skipped in a sanitizer build (SANITIZE=1 exports PD_SANITIZE:
# AddressSanitizer and valgrind do not run together) and where valgrind is
# not installed.

load test_helper

setup() {
    [ -z "${PD_SANITIZE:-}" ] || skip "sanitizer build"
    command -v valgrind >/dev/null || skip "valgrind is not installed"
    cd "$BATS_TEST_TMPDIR"
}

# vg PROGRAM ARG...: PROGRAM under memcheck; fails on any error or leak.
vg() {
    valgrind --quiet --error-exitcode=99 --leak-check=full \
        --errors-for-leak-kinds=definite,indirect --show-leak-kinds=definite,indirect "$@"
}

@test "lattice, bonds, run (failure, contact, indenter), damage, crack tip, VTK: memcheck clean" {
    run -0 vg pd-lattice -q --spacing 0.0005 --cylinder y,0,0,0.003,-0.0015,0 --density 2200 \
        -o lattice.h5
    run -0 vg pd-bonds -q --horizon 0.0015001 lattice.h5 -o model.h5
    run -0 vg pd-run -q --c 1.6863e22 --failure 0.0005,0.25 --contact \
        --allow-overlap --indenter sphere,0,0.0049,0,0.005,1e17,0,-100,0 --dt 1e-7 --steps 20 --every 10 \
        --threads 1 model.h5 -o run.h5
    run -0 vg pd-damage -q run.h5
    run -0 vg pd-crack-tip run.h5
    run -0 vg pd-dump2vtk -q run.h5 -o vtk
    # and the error paths: a bad input, a usage error
    run -1 vg pd-run -q --c 1 --steps 1 lattice.h5 -o x.h5
    run -2 vg pd-bonds --horizon -1 lattice.h5
}
