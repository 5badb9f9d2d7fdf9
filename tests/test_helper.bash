# tests/test_helper.bash -- loaded by every tests/*.bats (`load test_helper`).
#
# Loads bats-support and bats-assert (Debian packages), puts the programs
# built in bin/ first on PATH, and gives the suites small models to work on.
# Scratch files go to $BATS_TEST_TMPDIR, which bats removes after each test.

bats_require_minimum_version 1.5.0

for _lib in bats-support bats-assert; do
    for _dir in /usr/lib/bats /usr/lib/bats-core /usr/share/bats /usr/local/lib/bats; do
        if [ -f "$_dir/$_lib/load.bash" ]; then
            load "$_dir/$_lib/load.bash"
            break
        fi
    done
done
unset _lib _dir

PATH="$BATS_TEST_DIRNAME/../bin:$PATH"
export PATH

# Idle OpenMP threads sleep rather than spin: the suites run many small
# programs side by side, and spinning threads only steal their cores.
: "${OMP_WAIT_POLICY:=passive}"
export OMP_WAIT_POLICY

# Debian's python, the one with h5py and numpy; another python3 may come
# first on PATH.  share/ comes first on its path, for pdh5 (the bonds of
# either form of /bonds, pd-h5(5)), then tests/, for vtu (the suites' own
# reader of .vtu files, raw or compressed): every $PY the suites run finds
# them.
PY=/usr/bin/python3
PYTHONPATH="$(cd "$BATS_TEST_DIRNAME/../share" && pwd):$BATS_TEST_DIRNAME${PYTHONPATH:+:$PYTHONPATH}"
export PYTHONPATH

# The small block of make_block: an 11x11x11 simple cubic lattice (1331
# particles) with horizon 3.0001 spacings.
SPACING=0.001
DENSITY=2200
HORIZON=0.0030001
BULK=14.9e9

# _pd_cached KEY BUILD [ARG]...: a directory filled once per test file by
# `BUILD DIR ARG...`, in $_PD_CACHE.  Models are reused across the tests of a
# file (they only read them: the helpers below hand out copies).
_pd_cached() {
    local key=$1 build=$2
    shift 2
    if [ -z "${BATS_FILE_TMPDIR:-}" ]; then
        _PD_CACHE=$(mktemp -d) && "$build" "$_PD_CACHE" "$@"
        return
    fi
    _PD_CACHE=$BATS_FILE_TMPDIR/pd-cache-$key
    [ -d "$_PD_CACHE" ] && return 0
    local tmp
    tmp=$(mktemp -d "$BATS_FILE_TMPDIR/pd-build.XXXXXX") || return 1
    if ! "$build" "$tmp" "$@"; then
        rm -rf "$tmp"
        return 1
    fi
    # another test may have won the race: keep its copy
    mv -T "$tmp" "$_PD_CACHE" 2>/dev/null || rm -rf "$tmp"
}

# _pd_build_block DIR [PD-BONDS OPTION]...
_pd_build_block() {
    local dir=$1
    shift
    pd-lattice -q --spacing "$SPACING" --density "$DENSITY" \
        --box 0,0.01,0,0.01,0,0.01 -o "$dir/lattice.h5" &&
        pd-bonds -q --horizon "$HORIZON" "$@" "$dir/lattice.h5" -o "$dir/model.h5"
}

# make_block [DIR]: DIR/lattice.h5 (/particles only) and DIR/model.h5 (with
# /bonds, a lattice stencil: pd-bonds' default on a lattice) of a 10 mm cube
# of glass-like material.  DIR defaults to $BATS_TEST_TMPDIR.
make_block() {
    local dir=${1:-$BATS_TEST_TMPDIR}
    _pd_cached block _pd_build_block || return 1
    cp "$_PD_CACHE/lattice.h5" "$_PD_CACHE/model.h5" "$dir/"
}

# make_csr_block [DIR]: make_block's files, /bonds of DIR/model.h5 stored as
# lists (pd-bonds --csr: /bonds/offset, neighbor, length, volume_factor), for
# tests that change those lists.
make_csr_block() {
    local dir=${1:-$BATS_TEST_TMPDIR}
    _pd_cached block-csr _pd_build_block --csr || return 1
    cp "$_PD_CACHE/lattice.h5" "$_PD_CACHE/model.h5" "$dir/"
}

# The pd-run options of make_run: PMB with failure, contact, and a sphere
# that starts 0.5 mm deep in the top face and moves down at 100 m/s, which
# breaks bonds within 50 steps (--allow-overlap: it means to start inside).
RUN_OPTS=(--bulk-modulus "$BULK" --failure 0.0005,0.25 --contact --allow-overlap
          --indenter sphere,0.005,0.005,0.0125,0.003,1e17,0,0,-100)

_pd_build_run() {
    local out=$1 model=$2
    shift 2
    pd-run -q "${RUN_OPTS[@]}" --steps 50 --every 10 "$@" "$model" -o "$out/run.h5"
}

# make_run [DIR [PD-RUN OPTION]...]: DIR/run.h5, 50 steps with a frame every
# 10 of the make_block model (DIR/model.h5, made first when missing).  Extra
# options go after the defaults, so they override them.
make_run() {
    local dir=${1:-$BATS_TEST_TMPDIR}
    shift || true
    [ -f "$dir/model.h5" ] || make_block "$dir" || return 1
    _pd_cached block _pd_build_block || return 1
    if ! cmp -s "$dir/model.h5" "$_PD_CACHE/model.h5"; then
        # a model of the test's own
        _pd_build_run "$dir" "$dir/model.h5" "$@"
        return
    fi
    local key
    key=run-$(printf '%s\n' "$@" | cksum | cut -d' ' -f1)
    _pd_cached "$key" _pd_build_run "$_PD_CACHE/model.h5" "$@" || return 1
    cp "$_PD_CACHE/run.h5" "$dir/run.h5"
}

# py CODE [ARG]...: run CODE with Debian's python; numpy is np, h5py is h5py,
# pdh5 (share/pdh5.py) is pdh5, the arguments are sys.argv[1:].  The bonds
# of a model in either form: `off, nb, length, nu = pdh5.bonds(f)`.
py() {
    local code=$1
    shift
    "$PY" -c "import sys, h5py, numpy as np, pdh5
$code" "$@"
}

# assert_one_error REGEX: after `run --separate-stderr`, stdout is empty and
# stderr is exactly one line, matching REGEX (an extended regular
# expression).
assert_one_error() {
    local regex=$1
    if [ "${#stderr_lines[@]}" -ne 1 ]; then
        batslib_print_kv_single_or_multi 8 stderr "$stderr" |
            batslib_decorate "expected one error line on stderr" | fail
        return 1
    fi
    if ! [[ ${stderr_lines[0]} =~ $regex ]]; then
        batslib_print_kv_single_or_multi 8 regex "$regex" stderr "$stderr" |
            batslib_decorate "the error line does not match" | fail
        return 1
    fi
    if [ -n "$output" ]; then
        batslib_print_kv_single_or_multi 8 stdout "$output" |
            batslib_decorate "expected nothing on stdout with an error" | fail
        return 1
    fi
}

# expect_usage_error REGEX COMMAND...: COMMAND exits 2 with one error line
# "PROG: error: ..." matching REGEX.
expect_usage_error() {
    local regex=$1
    shift
    run -2 --separate-stderr "$@"
    assert_one_error "^$1: error: .*$regex"
}

# expect_runtime_error REGEX COMMAND...: COMMAND exits 1 with one error line
# "PROG: error: ..." matching REGEX.
expect_runtime_error() {
    local regex=$1
    shift
    run -1 --separate-stderr "$@"
    assert_one_error "^$1: error: .*$regex"
}

# assert_no_temp DIR: no temporary file (.NAME.tmp.XXXXXX) is left in DIR.
assert_no_temp() {
    local left
    left=$(ls -A "$1" | grep '\.tmp\.' || true)
    if [ -n "$left" ]; then
        batslib_print_kv_single_or_multi 8 left "$left" |
            batslib_decorate "temporary files left in $1" | fail
        return 1
    fi
}

# Inputs that are not pd-h5 files, in $BATS_TEST_TMPDIR:
#   empty.h5 (0 bytes), text.h5 (a line of text), adir/ (a directory),
#   plain.h5 (valid HDF5 without pd_format).
make_bad_inputs() {
    local dir=$BATS_TEST_TMPDIR
    : >"$dir/empty.h5"
    echo "this is not HDF5" >"$dir/text.h5"
    mkdir -p "$dir/adir"
    py "with h5py.File(sys.argv[1], 'w') as f: f['x'] = np.arange(3.0)" "$dir/plain.h5"
}

# with_version SRC DST V: copy SRC to DST with pd_format_version = V.
with_version() {
    cp "$1" "$2"
    py "
with h5py.File(sys.argv[1], 'a') as f: f.attrs['pd_format_version'] = int(sys.argv[2])" "$2" "$3"
}

# h5_same A B [SKIP]: the two HDF5 files hold the same groups, datasets
# (dtype, shape and bits) and attributes; paths matching the regular
# expression SKIP (e.g. 'history') are not compared.  Prints the first
# difference and fails.
h5_same() {
    py "
import re
a, b = h5py.File(sys.argv[1], 'r'), h5py.File(sys.argv[2], 'r')
skip = re.compile(sys.argv[3]) if len(sys.argv) > 3 and sys.argv[3] else None
def same(x, y):
    x, y = np.asarray(x), np.asarray(y)
    return x.dtype == y.dtype and x.shape == y.shape and x.tobytes() == y.tobytes()
def attrs(path, x, y):
    keys = sorted(k for k in set(x.attrs) | set(y.attrs) if not (skip and skip.search(path + '@' + k)))
    for k in keys:
        assert k in x.attrs and k in y.attrs, ('attribute only in one file', path, k)
        assert same(x.attrs[k], y.attrs[k]), ('attribute differs', path, k)
def walk(path, x, y):
    attrs(path, x, y)
    if isinstance(x, h5py.Dataset):
        assert isinstance(y, h5py.Dataset), ('not both datasets', path)
        assert same(x[()], y[()]), ('dataset differs', path)
        return
    names = sorted(k for k in set(x) | set(y) if not (skip and skip.search(path + '/' + k)))
    for k in names:
        assert k in x and k in y, ('only in one file', path + '/' + k)
        walk(path + '/' + k, x[k], y[k])
walk('', a, b)
" "$@"
}
