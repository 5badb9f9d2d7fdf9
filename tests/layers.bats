#!/usr/bin/env bats
# share/layers.sh, the layer check of `make check`: lib/ calls only
# downward (lib/LAYERS, bottom first) and its files' calls form no circle.
# It passes on libpd, and fails, naming the culprit, on a tree of its own
# with an upward call, a circle of calls, an upward include, or a file
# outside the layers.

load test_helper

CHECK="$BATS_TEST_DIRNAME/../share/layers.sh"

setup() {
    cd "$BATS_TEST_TMPDIR"
    mkdir -p t/low t/high
    printf 'low\nhigh\n' >t/LAYERS
}

# obj FILE.c CODE: a source file and its object
obj() {
    printf '%s\n' "$2" >"$1"
    cc -c -o "${1%.c}.o" "$1"
}

@test "layers: libpd calls only downward, with no circle" {
    run -0 sh "$CHECK" "$BATS_TEST_DIRNAME/../lib"
    assert_output --partial "none upward, no circle"
}

@test "layers: a call into a higher layer is named" {
    obj t/high/up.c 'int up(void) { return 1; }'
    obj t/low/down.c 'int up(void); int down(void) { return up(); }'
    run -1 --separate-stderr sh "$CHECK" t
    [[ "$stderr" == *"t/low/down.c (low) uses up of t/high/up.c (high), a higher layer"* ]]
}

@test "layers: calls downward pass, a circle of calls within a layer does not" {
    obj t/low/a.c 'int a(void) { return 1; }'
    obj t/high/b.c 'int a(void); int b(void) { return a(); }'
    run -0 sh "$CHECK" t
    obj t/low/a.c 'int c(void); int a(void) { return c(); }'
    obj t/low/c.c 'int a(void); int c(void) { return a(); }'
    run -1 --separate-stderr sh "$CHECK" t
    [[ "$stderr" == *"circle"* ]]
    [[ "$stderr" == *"t/low/a.c"* && "$stderr" == *"t/low/c.c"* ]]
}

@test "layers: an include of a higher layer's header, and a file in no layer" {
    obj t/low/a.c 'int a(void) { return 1; }'
    printf '#include "high/x.h"\n' >t/low/a.h
    run -1 --separate-stderr sh "$CHECK" t
    [[ "$stderr" == *"t/low/a.h (low) includes a header of high, a higher layer"* ]]
    rm t/low/a.h
    printf 'int z;\n' >t/z.c
    run -1 --separate-stderr sh "$CHECK" t
    [[ "$stderr" == *"t/z.c is in no layer"* ]]
}
