#!/bin/sh
# The layer check of `make check`: lib/ is split into folders, one a layer,
# listed bottom to top in lib/LAYERS.  A file may call (or read the data
# of) files of its own layer or of a lower one, never of a higher one, and
# the files' calls form no circle: read from the object files' symbols
# (nm), what each defines and what each leaves undefined.  Its #include
# "LAYER/x.h" lines name only its own layer or lower ones.
# Usage: sh share/layers.sh [LIBDIR]   (default lib; after `make all`)
set -eu
lib=${1:-lib}
layers=$(cat "$lib/LAYERS")
fail=0
for c in "$lib"/*.c; do
    [ -e "$c" ] || continue
    echo "layers: $c is in no layer: move it into one of the folders of $lib/LAYERS" >&2
    fail=1
done
for d in "$lib"/*/; do
    d=$(basename "$d")
    echo "$layers" | grep -qx "$d" ||
        { echo "layers: $lib/$d/ is not listed in $lib/LAYERS" >&2; fail=1; }
done
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
rank=0
for l in $layers; do
    rank=$((rank + 1))
    for c in "$lib/$l"/*.c; do
        [ -e "$c" ] || continue
        o=${c%.c}.o
        [ -e "$o" ] || { echo "layers: $o is not built (run make all first)" >&2; exit 1; }
        nm -g --defined-only "$o" | awk -v f="$c" -v r="$rank" -v l="$l" \
            'NF == 3 { print $3, f, r, l }' >>"$tmp/defined"
        nm -u "$o" | awk -v f="$c" -v r="$rank" -v l="$l" \
            '$1 == "U" { print $2, f, r, l }' >>"$tmp/used"
    done
done
# for each use of a symbol another lib file defines: caller and callee
awk 'NR == FNR { def[$1] = $2 " " $3 " " $4; next }
     ($1 in def) { split(def[$1], d, " ");
                   if (d[1] != $2) print $2, $3, $4, d[1], d[2], d[3], $1 }' \
    "$tmp/defined" "$tmp/used" >"$tmp/calls"
up=$(awk '$5 > $2 { printf "layers: %s (%s) uses %s of %s (%s), a higher layer\n", $1, $3, $7, $4, $6 }' "$tmp/calls")
if [ -n "$up" ]; then
    echo "$up" >&2
    fail=1
fi
# the headers too: a file includes only headers of its own layer or a
# lower one (#include "LAYER/x.h")
rank_of() { echo "$layers" | awk -v l="$1" '$0 == l { print NR }'; }
for l in $layers; do
    r=$(rank_of "$l")
    for f in "$lib/$l"/*.[ch]; do
        [ -e "$f" ] || continue
        for inc in $(sed -n 's/^#include "\([a-z_]*\)\/[^"]*"/\1/p' "$f"); do
            ri=$(rank_of "$inc")
            if [ -z "$ri" ] || [ "$ri" -gt "$r" ]; then
                echo "layers: $f ($l) includes a header of $inc, a higher layer" >&2
                fail=1
            fi
        done
    done
done
# no circle among the files (tsort names one when there is)
awk '{ print $1, $4 }' "$tmp/calls" | sort -u >"$tmp/edges"
if ! tsort "$tmp/edges" >/dev/null 2>"$tmp/loop"; then
    echo "layers: the files' calls form a circle:" >&2
    grep -v '^tsort: -\?: input contains a loop' "$tmp/loop" | sed 's/^tsort: /  /' >&2
    fail=1
fi
[ "$fail" -eq 0 ] && echo "layers: $(wc -l <"$tmp/edges") calls between $(cut -d' ' -f2 "$tmp/defined" | sort -u | wc -l) files, none upward, no circle"
exit "$fail"
