#!/usr/bin/env bats
# pd-series: prints the rows pd-run --series records (/series), as a table,
# as CSV exact to the bit, some columns, the last row of each run, several
# runs with a 'run' column, standard input; draws curves with gnuplot into
# a PNG that appears only whole; bad input is one line and exit 1 or 2.
# The expectations are read from the file itself with h5py, never pasted.

load test_helper
bats_require_minimum_version 1.5.0

setup() {
    cd "$BATS_TEST_TMPDIR"
}

# The make_run scene (an indenter breaking bonds) with a row every 5 steps.
run_with_series() {
    make_run "$BATS_TEST_TMPDIR" --series 5 "$@"
}

# SERIES: the rows of a file as (columns, values) read with h5py.
SERIES='
def series(path):
    with h5py.File(path) as f:
        g = f["series"]
        return g.attrs["columns"].split(), g["values"][: g.attrs["rows"]]
'

@test "pd-series: the table holds every row and column of /series, counts as whole numbers" {
    run_with_series
    run -0 --separate-stderr pd-series run.h5
    [ -z "$stderr" ]
    printf '%s\n' "$output" >table.txt
    py "$SERIES
cols, v = series('run.h5')
lines = open('table.txt').read().splitlines()
assert lines[0].split() == cols, (lines[0], cols)
assert len(lines) == 1 + len(v) and len(v) == 11, len(lines)   # steps 0, 5, ..., 50
for line, row in zip(lines[1:], v):
    fields = line.split()
    assert len(fields) == len(cols)
    for name, text, x in zip(cols, fields, row):
        if name in ('step', 'broken_bonds', 'damaged_particles', 'lost_particles'):
            assert text == '%d' % x, (name, text, x)          # every digit, no exponent
        else:
            assert float(text) == float('%.6g' % x), (name, text, x)
assert [int(l.split()[0]) for l in lines[1:]] == list(range(0, 51, 5))
assert v[-1, cols.index('broken_bonds')] > 0      # the scene does break bonds
"
    # right-aligned columns: every line is as long as the header
    py "
lines = open('table.txt').read().splitlines()
assert len(set(len(l) for l in lines)) == 1, set(len(l) for l in lines)"
}

@test "pd-series --csv reads back to the same doubles, bit for bit" {
    run_with_series
    pd-series --csv run.h5 >s.csv
    py "$SERIES
cols, v = series('run.h5')
lines = open('s.csv').read().splitlines()
assert lines[0].split(',') == cols
got = np.array([[float(t) for t in l.split(',')] for l in lines[1:]])
assert got.shape == v.shape and got.tobytes() == v.tobytes()
"
}

@test "pd-series --columns prints those columns in that order; a typo gets the nearest name" {
    run_with_series
    pd-series --csv --columns balance,step,indenter.fz run.h5 >s.csv
    py "$SERIES
cols, v = series('run.h5')
lines = open('s.csv').read().splitlines()
assert lines[0] == 'balance,step,indenter.fz'
want = v[:, [cols.index('balance'), cols.index('step'), cols.index('indenter.fz')]]
got = np.array([[float(t) for t in l.split(',')] for l in lines[1:]])
assert got.tobytes() == want.tobytes()
assert (want[1:, 2] > 0).any()          # the body pushes the indenter up
"
    expect_runtime_error "'run.h5' has no column 'indentr.fz'; did you mean 'indenter.fz'\\?" \
        pd-series --columns step,indentr.fz run.h5
    expect_runtime_error "'run.h5' has no column 'elephant'$" pd-series --columns elephant run.h5
}

@test "pd-series: several runs get a 'run' column, --last one row each, '-' reads stdin" {
    run_with_series
    mv run.h5 a.h5
    pd-run -q "${RUN_OPTS[@]}" --steps 30 --series 10 model.h5 -o b.h5
    pd-series --csv a.h5 - <b.h5 >both.csv
    pd-series --csv --last --columns step,max_damage a.h5 b.h5 >last.csv
    pd-series --last b.h5 >last1.txt
    py "$SERIES
ca, va = series('a.h5')
cb, vb = series('b.h5')
lines = open('both.csv').read().splitlines()
assert lines[0] == 'run,' + ','.join(ca)
runs = [l.split(',')[0] for l in lines[1:]]
assert runs == ['a.h5'] * len(va) + ['-'] * len(vb), runs
got = np.array([[float(t) for t in l.split(',')[1:]] for l in lines[1:]])
assert got.tobytes() == np.vstack([va, vb]).tobytes()
last = open('last.csv').read().splitlines()
assert last[0] == 'run,step,max_damage'
for line, (c, v, name) in zip(last[1:], [(ca, va, 'a.h5'), (cb, vb, 'b.h5')]):
    r, step, d = line.split(',')
    assert r == name and float(step) == v[-1, c.index('step')] == (50 if name == 'a.h5' else 30)
    assert float(d) == v[-1, c.index('max_damage')]
assert len(last) == 3
one = open('last1.txt').read().splitlines()
assert len(one) == 2 and one[0].split()[0] == 'run' and one[1].split()[:2] == ['b.h5', '30']
"
}

@test "pd-series: a bar's sets give their displacement and reaction columns" {
    pd-lattice -q --spacing 0.001 --box 0,0.02,0,0.004,0,0.004 --density 2200 \
        --set left=box,-1,0.0025,-1,1,-1,1 --set right=box,0.0175,1,-1,1,-1,1 -o bar-l.h5
    pd-bonds -q --horizon 0.0030001 bar-l.h5 -o bar.h5
    pd-run -q --bulk-modulus 14e9 --steps 40 --series 20 --velocity-bc left,x,0 \
        --velocity-bc right,x,0.1 bar.h5 -o r.h5
    run -0 pd-series --columns step,right.ux,right.fx,left.fx r.h5
    assert_line --index 0 --regexp '^ +step +right.ux +right.fx +left.fx$'
    [ "${#lines[@]}" -eq 4 ]
    expect_runtime_error "'r.h5' has no column 'middle.fx'" pd-series --columns middle.fx r.h5
}

@test "pd-series --plot draws a PNG, whole or not at all" {
    command -v gnuplot >/dev/null || skip "gnuplot is not installed"
    run_with_series
    cp run.h5 two.h5
    run -0 --separate-stderr pd-series --plot e.png --y kinetic_energy,elastic_energy run.h5
    [ -z "$output" ] && [ -z "$stderr" ]
    run -0 pd-series --plot f.png --x step --y indenter.fz run.h5 two.h5
    for p in e.png f.png; do
        # a PNG's signature and an IHDR of 900 x 600
        py "
b = open(sys.argv[1], 'rb').read()
assert b[:8] == b'\x89PNG\r\n\x1a\n' and b[12:16] == b'IHDR', b[:16]
assert int.from_bytes(b[16:20], 'big') == 900 and int.from_bytes(b[20:24], 'big') == 600
assert len(b) > 2000" "$p"
    done
    assert_no_temp .
    # a failure leaves an existing picture as it was, and no temporary
    cp e.png keep.png
    cp e.png old.png
    expect_runtime_error "'run.h5' has no column 'kinetic'" \
        pd-series --plot old.png --y kinetic run.h5
    cmp old.png keep.png
    run -1 --separate-stderr env PATH=/nonexistent "$(command -v pd-series)" \
        --plot old.png --y balance run.h5
    assert_one_error "^pd-series: error: cannot draw 'old.png': gnuplot is not on PATH$"
    cmp old.png keep.png
    assert_no_temp .
    # a directory that cannot be written: one line, nothing left
    mkdir ro && chmod a-w ro
    if [ ! -w ro ]; then
        expect_runtime_error "cannot write 'ro/p.png'" pd-series --plot ro/p.png --y balance run.h5
        [ -z "$(ls -A ro)" ]
    fi
}

@test "pd-series: usage errors exit 2 with one line" {
    run_with_series
    expect_usage_error "missing RUN.h5" pd-series
    expect_usage_error "unrecognized option|unknown option" pd-series --bogus run.h5
    expect_usage_error "'-' is given more than once" pd-series - - <run.h5
    expect_usage_error "--x needs --plot" pd-series --x step run.h5
    expect_usage_error "--y needs --plot" pd-series --y balance run.h5
    expect_usage_error "--plot needs --y" pd-series --plot p.png run.h5
    expect_usage_error "--csv and --plot" pd-series --csv --plot p.png --y balance run.h5
    expect_usage_error "--last and --plot" pd-series --last --plot p.png --y balance run.h5
    expect_usage_error "--columns and --plot" pd-series --columns step --plot p.png --y balance run.h5
    expect_usage_error "--columns needs a comma list" pd-series --columns step,,balance run.h5
    expect_usage_error "--y needs a comma list" pd-series --plot p.png --y , run.h5
    expect_usage_error "--x needs one column name" pd-series --plot p.png --x a,b --y balance run.h5
    [ ! -e p.png ]
    run -0 pd-series --help
    assert_line --index 0 --regexp '^Usage: pd-series '
}

@test "pd-series: a file without a series, a bad file, a full disk exit 1 with one line" {
    run_with_series
    make_block
    make_bad_inputs
    expect_runtime_error "'model.h5'.*(no time series|series)" pd-series model.h5
    expect_runtime_error "nothere.h5" pd-series nothere.h5
    expect_runtime_error "text.h5" pd-series text.h5
    expect_runtime_error "plain.h5" pd-series plain.h5
    run -1 --separate-stderr bash -c 'pd-series run.h5 >/dev/full'
    [ "${#stderr_lines[@]}" -eq 1 ]
    [[ ${stderr_lines[0]} =~ ^pd-series:\ error:\ cannot\ write\ to\ standard\ output ]]
}
