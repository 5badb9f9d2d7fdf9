#!/bin/sh
# tests/samebits/build-baseline.sh -- build the programs of the baseline
# commit (tests/samebits/BASELINE) for tests/samebits.bats, and print the
# folder that holds them (its bin/ has pd-lattice, pd-bonds, pd-run, ...).
#
#   build-baseline.sh [COMMIT]
#
# The tree of COMMIT comes from git (git archive), so the baseline is built
# by the compiler and on the processor of the build it is compared with.
# It is built once per commit and build setting, in
# tests/tmp/samebits/COMMIT-SETTING (git-ignored): the sanitizers when
# PD_SANITIZE=1 (what the Makefile exports with SANITIZE=1), and CC and
# CFLAGS when they are set.  A build goes to a temporary folder renamed at
# the end, so a folder under the final name is a complete build, reused by
# the next call, and a killed build is never reused.  A commit that the
# repository does not hold (a shallow clone) is an error, not a skip.
set -eu

me=build-baseline.sh
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)

fail() {
    echo "$me: error: $*" >&2
    exit 1
}

if [ $# -ge 1 ]; then
    want=$1
else
    want=$(grep -v '^#' "$here/BASELINE" | head -n 1)
fi
[ -n "$want" ] || fail "no commit in $here/BASELINE"
git -C "$root" rev-parse --git-dir >/dev/null 2>&1 ||
    fail "$root is not a git repository: the baseline $want is built from git"
commit=$(git -C "$root" rev-parse --verify --quiet "$want^{commit}") ||
    fail "the baseline commit $want is not in the repository (a shallow clone? git fetch --unshallow)"

setting=plain
[ "${PD_SANITIZE:-}" = 1 ] && setting=sanitize
if [ -n "${CC+set}${CFLAGS+set}" ]; then
    setting=$setting-$(printf 'CC=%s\nCFLAGS=%s\n' "${CC-}" "${CFLAGS-}" | cksum | cut -d' ' -f1)
fi
cache=$root/tests/tmp/samebits
dir=$cache/$commit-$setting
if [ -x "$dir/bin/pd-run" ]; then
    echo "$dir"
    exit 0
fi

mkdir -p "$cache"
tmp=$(mktemp -d "$cache/.build.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
trap 'exit 1' HUP INT TERM
git -C "$root" archive "$commit" | tar -x -C "$tmp" ||
    fail "cannot extract $commit into $tmp"

# The outer make's flags (its job server, its command-line variables) are
# not this build's: it takes only the settings above.
set -- all
[ "${PD_SANITIZE:-}" = 1 ] && set -- "$@" SANITIZE=1
[ -n "${CC+set}" ] && set -- "$@" "CC=$CC"
[ -n "${CFLAGS+set}" ] && set -- "$@" "CFLAGS=$CFLAGS"
if ! env -u MAKEFLAGS -u MFLAGS -u MAKELEVEL -u MAKEOVERRIDES \
        make -C "$tmp" -j2 "$@" >"$tmp/build.log" 2>&1; then
    tail -n 20 "$tmp/build.log" >&2
    fail "the baseline $commit does not build (make $*)"
fi
[ -x "$tmp/bin/pd-run" ] || fail "the baseline $commit built no bin/pd-run"

# Another build may have finished first: keep the one under the final name.
if mv -T "$tmp" "$dir" 2>/dev/null; then
    trap - EXIT
fi
[ -x "$dir/bin/pd-run" ] || fail "no complete baseline build in $dir"
echo "$dir"
