#!/bin/sh
# bench.sh -- pd-run against LAMMPS on the seed impact (what `make bench` runs).
#
# The seed example (examples/lammps-impact: 103,110 particles, 5,004,900
# bonds, PMB + failure + contact + indenter, dt 1e-7) for BENCH_STEPS steps
# (default 300) through
#   (a) pd-run --threads BENCH_THREADS (default 2) --every 0 --timing
#       (no frames but the last one, which pd-run always writes);
#   (b) the seed LAMMPS script (examples/lammps-impact/in.impact) without its
#       dump and with `run BENCH_STEPS`, through mpirun -np BENCH_NP (2) lmp;
#   (c) pd-run on the same model with the effects added one by one, to show
#       what each costs: bonds only (PMB, the disk at rest), + indenter,
#       + failure, + contact (= the full scene of (a)).  The indenter comes
#       second: without it nothing moves, so failure would never break a
#       bond and the contact list would never be rebuilt, and their rows
#       would measure effects that do no work.  Each row is pd-run's own
#       loop time per step (file I/O excluded); the difference between two
#       rows is what the effect added costs.
# Wall time and peak RSS come from /usr/bin/time -f '%e %M' around pd-run,
# around mpirun (wall) and around each LAMMPS rank (peak RSS, summed).
#
# Environment: BENCH_STEPS (300), BENCH_THREADS (2), BENCH_NP (2),
# BENCH_DIR (cache of the model and the runs, default $TMPDIR/pd-bench),
# PD_BIN (default: bin/ of this tree), LMP (lmp), MPIRUN (mpirun).
# Run from anywhere; `make bench` builds the programs first.
set -eu

prog=bench.sh
die() {
    echo "$prog: error: $*" >&2
    exit 1
}

ROOT=$(cd "$(dirname "$0")/.." && pwd)
PD_BIN=${PD_BIN:-$ROOT/bin}
STEPS=${BENCH_STEPS:-300}
THREADS=${BENCH_THREADS:-2}
NP=${BENCH_NP:-2}
DIR=${BENCH_DIR:-${TMPDIR:-/tmp}/pd-bench}
LMP=${LMP:-lmp}
MPIRUN=${MPIRUN:-mpirun}
EX=$ROOT/examples/lammps-impact
SCENE=$EX/impact.scene
TIME=/usr/bin/time

case $STEPS in '' | *[!0-9]*) die "BENCH_STEPS must be a positive integer, not '$STEPS'" ;; esac
[ "$STEPS" -gt 0 ] || die "BENCH_STEPS must be a positive integer"
for p in pd-lattice pd-bonds pd-run; do
    [ -x "$PD_BIN/$p" ] || die "$PD_BIN/$p not found (run 'make all' first, or set PD_BIN)"
done
[ -r "$SCENE" ] || die "$SCENE not found"
[ -r "$EX/in.impact" ] || die "$EX/in.impact not found"
[ -x "$TIME" ] || die "$TIME not found (GNU time; Debian package 'time')"
command -v "$LMP" >/dev/null 2>&1 ||
    die "'$LMP' not found: LAMMPS with the PERI package is needed (Debian package 'lammps'; or set LMP)"
command -v "$MPIRUN" >/dev/null 2>&1 ||
    die "'$MPIRUN' not found (Debian package 'openmpi-bin'; or set MPIRUN)"
"$LMP" -h 2>/dev/null | grep -q 'peri/pmb' ||
    die "'$LMP' has no pair style peri/pmb (LAMMPS without the PERI package)"
command -v awk >/dev/null 2>&1 || die "awk not found"

# Open MPI refuses to run as root without these (containers, CI).
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1

mkdir -p "$DIR" || die "cannot create $DIR"
cd "$DIR"

# --- the seed model, built once --------------------------------------------
LATTICE="--spacing 0.0005 --cylinder y,0,0,0.037,-0.0025,0 --density 2200"
HORIZON=0.0015001
stamp="pd-lattice $LATTICE | pd-bonds --horizon $HORIZON"
if [ ! -s model.h5 ] || [ "$(cat model.stamp 2>/dev/null)" != "$stamp" ] ||
    [ -n "$(find "$PD_BIN/pd-lattice" "$PD_BIN/pd-bonds" -newer model.h5 2>/dev/null)" ]; then
    echo "$prog: building the seed model in $DIR" >&2
    # shellcheck disable=SC2086 # LATTICE is a list of options
    "$PD_BIN/pd-lattice" $LATTICE -q -o lattice.h5 || die "pd-lattice failed"
    "$PD_BIN/pd-bonds" --horizon "$HORIZON" -q lattice.h5 -o model.h5.tmp || die "pd-bonds failed"
    mv model.h5.tmp model.h5
    rm -f lattice.h5
    echo "$stamp" >model.stamp
fi

# --- helpers ----------------------------------------------------------------
# pd_loop LOG: "SECONDS BOND_UPDATES_PER_S" from pd-run's last log line
pd_loop() {
    sed -n 's/^pd-run: [0-9]* steps in \([0-9.eE+-]*\) s (\([0-9.eE+-]*\) bond updates\/s).*/\1 \2/p' "$1" |
        tail -n 1
}
# pd_bench NAME [pd-run option]...: pd-run on the model for STEPS steps;
# NAME.log (its log), NAME.time ("wall peak_kB").
pd_bench() {
    name=$1
    shift
    echo "$prog: pd-run $name ($STEPS steps)" >&2
    "$TIME" -f '%e %M' -o "$name.time" "$PD_BIN/pd-run" "$@" --threads "$THREADS" \
        --steps "$STEPS" --every 0 model.h5 -o "$name.h5" 2>"$name.log" || {
        cat "$name.log" >&2
        die "pd-run ($name) failed"
    }
    rm -f "$name.h5"
    [ -n "$(pd_loop "$name.log")" ] || die "no timing line in $DIR/$name.log"
}

# --- machine -----------------------------------------------------------------
cpu=$(lscpu 2>/dev/null | sed -n 's/^Model name: *//p' | head -n 1)
ncpu=$(getconf _NPROCESSORS_ONLN 2>/dev/null || echo '?')
cores=$(lscpu 2>/dev/null | awk -F: '/^Core\(s\) per socket/ { c = $2 } /^Socket\(s\)/ { s = $2 }
    END { if (c && s) printf "%d", c * s }')
mem=$(awk '/^MemTotal/ { printf "%.1f GiB", $2 / 1048576 }' /proc/meminfo 2>/dev/null || true)
load0=$(cut -d' ' -f1-3 /proc/loadavg 2>/dev/null || echo '?')
lmpver=$("$LMP" -h 2>/dev/null | sed -n 's/^Large-scale.*Simulator - //p' | head -n 1)
pdver=$("$PD_BIN/pd-run" --version 2>/dev/null | head -n 1)

# --- (a) pd-run, the full scene ------------------------------------------
pd_bench full --scene "$SCENE" --timing

# --- (b) LAMMPS, the seed script without its dump ------------------------------
sed -e '/^dump/d' -e "s/^run .*/run             $STEPS/" "$EX/in.impact" >in.bench
grep -q "^run  *$STEPS\$" in.bench || die "cannot set 'run $STEPS' in in.bench"
rm -f lmp.ranks
echo "$prog: $MPIRUN -np $NP $LMP ($STEPS steps)" >&2
# one OpenMP thread per rank (LAMMPS's default, said so when unset)
OMP_NUM_THREADS=1 "$TIME" -f '%e %M' -o lmp.time "$MPIRUN" -np "$NP" \
    "$TIME" -a -o lmp.ranks -f '%e %M' "$LMP" -in in.bench -log log.lammps -screen none \
    >lmp.out 2>&1 || {
    cat lmp.out >&2
    die "LAMMPS failed (see $DIR/lmp.out, $DIR/log.lammps)"
}
lmp_loop=$(sed -n 's/^Loop time of \([0-9.eE+-]*\) on .*/\1/p' log.lammps | tail -n 1)
[ -n "$lmp_loop" ] || die "no 'Loop time' in $DIR/log.lammps"

# --- (c) the cost of each effect ----------------------------------------------
# the same numbers as the scene (c, failure, indenter, dt), stated here once
C=$(sed -n 's/^c  *//p' "$SCENE")
FAILURE=$(sed -n 's/^failure  *//p' "$SCENE")
INDENTER=$(sed -n 's/^indenter  *//p' "$SCENE")
DT=$(sed -n 's/^dt  *//p' "$SCENE")
if [ -z "$C" ] || [ -z "$FAILURE" ] || [ -z "$INDENTER" ] || [ -z "$DT" ]; then
    die "cannot read c, failure, indenter and dt from $SCENE"
fi
pd_bench bonds --c "$C" --dt "$DT"
pd_bench indenter --c "$C" --dt "$DT" --indenter "$INDENTER"
pd_bench failure --c "$C" --dt "$DT" --indenter "$INDENTER" --failure "$FAILURE"
# + contact is the full scene of (a)

# --- report ---------------------------------------------------------------------
read -r pd_wall pd_kb <full.time
read -r pd_lt pd_rate <<EOF
$(pd_loop full.log)
EOF
read -r lmp_wall _ <lmp.time
lmp_kb=$(awk '{ s += $2 } END { print s + 0 }' lmp.ranks)
lmp_ranks=$(wc -l <lmp.ranks | tr -d ' ')

echo
echo "pd bench: seed impact (examples/lammps-impact), 103110 particles, $STEPS steps"
echo "machine:  ${cpu:-unknown CPU}, $ncpu CPUs (${cores:-?} cores), ${mem:-? memory}"
echo "load:     $load0 (1/5/15 min, at the start)"
echo "pd:       ${pdver:-?}, pd-run --threads $THREADS"
echo "LAMMPS:   ${lmpver:-?}, $MPIRUN -np $NP $LMP (peri/pmb)"
echo
awk -v pw="$pd_wall" -v pl="$pd_lt" -v pk="$pd_kb" -v pr="$pd_rate" \
    -v lw="$lmp_wall" -v ll="$lmp_loop" -v lk="$lmp_kb" -v lr="$lmp_ranks" \
    -v n="$STEPS" -v th="$THREADS" -v np="$NP" 'BEGIN {
    printf "%-34s %12s %12s %9s\n", "", "pd-run", "LAMMPS", "LAMMPS/pd"
    printf "%-34s %12.2f %12.2f %9.2f\n", "wall time, whole process (s)", pw, lw, lw / pw
    printf "%-34s %12.2f %12.2f %9.2f\n", "time stepping loop (s)", pl, ll, ll / pl
    printf "%-34s %12.2f %12.2f %9.2f\n", "per step (ms)", 1000 * pl / n, 1000 * ll / n, ll / pl
    printf "%-34s %12.0f %12.0f %9.2f\n", "peak memory (MiB)", pk / 1024, lk / 1024, lk / pk
    printf "%-34s %12.3g\n", "pd-run bond updates per second", pr
    printf "(%d threads; LAMMPS: %d ranks, memory summed over %d ranks)\n", th, np, lr
}'
echo
echo "pd-run: cost of each effect ($STEPS steps, --threads $THREADS, loop time per step)"
prev=
for row in bonds indenter failure full; do
    read -r t _ <<EOF
$(pd_loop "$row.log")
EOF
    case $row in
    bonds) label="bonds only (PMB, disk at rest)" ;;
    indenter) label="+ indenter" ;;
    failure) label="+ failure" ;;
    full) label="+ contact (= full scene)" ;;
    esac
    awk -v l="$label" -v t="$t" -v p="$prev" -v n="$STEPS" 'BEGIN {
        if (p == "") printf "  %-32s %9.2f ms/step\n", l, 1000 * t / n
        else printf "  %-32s %9.2f ms/step  (%+.2f ms/step)\n", l, 1000 * t / n, 1000 * (t - p) / n
    }'
    prev=$t
done
echo
echo "pd-run --timing of the full scene:"
sed -n '/^pd-run: timing/,$p' full.log | sed 's/^/  /'
echo
echo "(runs and logs in $DIR; the model is kept there for the next run)"
