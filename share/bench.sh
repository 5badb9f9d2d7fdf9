#!/bin/sh
# bench.sh -- pd-run against LAMMPS on the seed impact, and how close pd-run
# is to what the machine allows (what `make bench` runs).
#
# The seed example (examples/lammps-impact: 103,110 particles, 5,004,900
# bonds, failure + contact + indenter, dt 1e-7) for BENCH_STEPS steps
# (default 300), in parts that BENCH_SKIP can leave out:
#   (a) PMB: pd-run --threads BENCH_THREADS (default 2) --every 0 --timing
#       (no frames but the last one, which pd-run always writes; a status
#       line every 200 steps, the script's thermo interval) against
#       the seed LAMMPS script (examples/lammps-impact/in.impact) without
#       its dump and with `run BENCH_STEPS`, through mpirun -np BENCH_NP (2)
#       lmp (peri/pmb);
#   (b) LPS ("lps"): the same with pd-run --model lps --bulk-modulus K
#       --shear-modulus G against the seed script with pair_style peri/lps
#       (K = 14.9 GPa, the seed's; G = 8 GPa, as tests/lammps-agree.bats:
#       3K - 5G is not 0, so the dilatation term does work);
#   (without "lammps" in BENCH_SKIP, LAMMPS runs beside both);
#   (c) the cost of each effect ("effects"): pd-run on the PMB model with
#       the effects added one by one: bonds only (the disk at rest),
#       + indenter, + failure, + contact (= the full scene of (a)).  The
#       indenter comes second: without it nothing moves, failure would
#       never break a bond and the contact list would never be rebuilt.
#       Each row is pd-run's own loop time per step (file I/O excluded);
#       the difference between two rows is what the effect added costs;
#   (d) the roofline ("roofline"): share/stream.c, built here with
#       -O3 -march=native and 512-bit vectors where the compiler takes
#       -mprefer-vector-width=512 (the tiles' width), measures the memory
#       bandwidth (a STREAM triad), the peak FMA rate and the divider's
#       rate of a square root and a division (the two a bond costs) on
#       BENCH_THREADS threads; the bond kernel's bytes, flops and divider
#       pairs per bond (counted in README.md, "Performance") times the
#       bonds of (a) over its "bonds" time are printed as fractions of
#       them, and so are those of the kernel alone (share/passes.c, built
#       by make bench: 200 bond passes of the seed in one process, the
#       best and the median pass); with LAMMPS beside it, the largest
#       LAMMPS/pd of the PMB loop the divider allows (every bond at the
#       divider's rate and the rest of the loop free);
#   (e) scaling with size ("scaling"): the impact scene on disks of about
#       BENCH_SIZES particles (default "25k 100k 400k 1.6M"; a larger disk
#       with the same spacing and thickness, radius 37 mm times the square
#       root of the factor; the seed disk itself stands for 100k), for
#       BENCH_STEPS x 103110 / N steps (at least 100, at most BENCH_STEPS;
#       one status line, at the end; twice, the better run kept):
#       time per bond (i < j) per step and peak memory per particle,
#       also less the peak of a 500-particle run (what pd-run takes
#       whatever the size: program, libraries, HDF5, OpenMP);
#   (f) threads ("threads"): the full PMB scene on 1 thread and on
#       BENCH_THREADS, alternately, twice each: the speed-up of the best
#       runs, and whether the last frames of 1 thread and of (a) are
#       identical (every dataset bit for bit, and every attribute but the
#       thread count and the command history; /usr/bin/python3 with h5py).
#   (g) kernels ("kernels"): the full PMB scene with --bond-list against
#       (a), which walks the bonds as a lattice stencil: the speed-up, the
#       largest position difference after BENCH_STEPS steps and the
#       damaged particles of each (the accuracy the faster mode costs);
#   (h) files and the pipe ("files"): pd-lattice and pd-bonds of the seed
#       disk (the best of two runs each), the sizes of the lattice, of the
#       model (a lattice stencil) and of the same model as lists (pd-bonds
#       --csr), the run file of (a) (its one frame) and the bytes of each
#       per particle; pd-run's time outside its loop in (a) (start-up and
#       the last frame); (a)'s peak memory per particle; and the whole
#       scene of (a) as one pipe, pd-lattice | pd-bonds | pd-run, against
#       LAMMPS's whole process of (a);
#   (i) a sweep ("sweep"): four pd-runs of the full scene (BENCH_SWEEP_STEPS
#       steps, default 100, four critical stretches) as a Makefile with no
#       thread option, made with make -j BENCH_THREADS and made one after
#       another (make -j1), twice each: the better wall times and their
#       ratio (runs sharing the cores, cmd/cli.h);
#   (j) a plate ("plate"): a pre-cracked 2-D plate of 97,969 particles
#       (dx 0.16 mm, delta 3 dx) under velocity pulses on two sets, PMB with
#       failure, BENCH_STEPS steps: its bond updates per second against
#       those of (a);
#   (k) frames ("frames"): the full scene of (a) with a frame every 5 steps:
#       what a frame costs (its loop time less (a)'s, per frame but the one
#       (a) writes too; and the same from the output rows of --timing) in
#       milliseconds and in steps of (a), the run file's size, and
#       pd-damage on that run, in place (its frames hold their damage: the
#       file is read, not copied) and into a new file (the better of two);
#       the bytes a frame adds to the run file (the run file less (a)'s, per
#       frame; the restart slots are rewritten in place, in pages the cache
#       holds already) and what writing them costs at the rate this
#       machine's page cache takes new pages now (dd of as many bytes as the run file into a new file,
#       after a pause of 15 s: a virtual machine whose freed pages go back
#       to its host takes new ones several times slower than reused ones)
#   (l) shattered ("shattered"; minutes): the whole demo, impact.scene as it
#       is (2000 steps, a frame every 100: the disk shatters, fragments fly
#       and the contact list is rebuilt hundreds of times) against the seed
#       script in.impact as it is (its dump every 100 steps);
#   (m) meshes ("mesh"): the seed disk meshed by gmsh in tetrahedra (about
#       10^5, share/bench-disk.geo), turned into particles by pd-mesh and
#       bonded by pd-bonds (the better of two each), and the full scene of
#       (a) on it for BENCH_STEPS steps (the bond lists: an irregular body):
#       ms per step and bond updates per second beside (a)'s; and the fill
#       of the same disk's surface by pd-lattice --inside at 0.14 mm (a box
#       of 10^7 sites) against --cylinder (the better of two each);
#   (n) an irregular body ("perturbed"): the seed disk with every site
#       moved by up to BENCH_PERTURB (5e-5 m, a tenth of the spacing) per
#       axis (pd-lattice --perturb): no lattice stencil, so pd-run walks
#       the bond list, as it does a meshed body; the full scene of (a)
#       against LAMMPS on the same particles (tests/lammps/pd2lmp.py writes
#       its data file, positions bit for bit, and the scene's input script,
#       without its dump and with the thermo interval of (a));
#   (o) MPI ranks ("mpi"; with the MPI build, mpi/bin/pd-run): the full
#       scene of (a) on BENCH_THREADS ranks of 1 thread (mpirun) against
#       (a)'s 1 rank of BENCH_THREADS threads, in BENCH_MPI_PAIRS (5) pairs
#       run one after the other: the median of the pairs' ratios of loop
#       times (steadier on a shared machine than the best of each), the
#       best loops, the halo a rank sends per step
#       (the log's), the share of the loop the ranks' exchanges took
#       (--timing's "MPI ranks"), and whether the two runs' files are the
#       same bit for bit (but the thread count);
# Wall time and peak RSS come from /usr/bin/time -f '%e %M' around pd-run,
# around mpirun (wall) and around each LAMMPS rank (peak RSS, summed).
#
# Environment: BENCH_STEPS (300), BENCH_THREADS (2), BENCH_NP (2),
# BENCH_SIZES ("25k 100k 400k 1.6M": particle counts, k = 1e3, M = 1e6;
# the 1.6M disk needs about 6 GB of memory and 3 GB in BENCH_DIR, and
# minutes to build), BENCH_SKIP (words among lammps, lps, effects,
# roofline, scaling, threads, kernels, files, sweep, plate, frames,
# shattered, mesh, perturbed, mpi: the parts left out), BENCH_PERTURB (5e-5),
# BENCH_MPI_PAIRS (5),
# BENCH_SWEEP_STEPS (100), BENCH_DIR (cache of the
# models and the runs, default $TMPDIR/pd-bench), PD_BIN (default: bin/ of
# this tree), LMP (lmp), MPIRUN (mpirun), CC (cc, for share/stream.c).
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
SIZES=${BENCH_SIZES-25k 100k 400k 1.6M}
SKIP=$(echo "${BENCH_SKIP:-}" | tr ',' ' ')
MPI_PAIRS=${BENCH_MPI_PAIRS:-5}
DIR=${BENCH_DIR:-${TMPDIR:-/tmp}/pd-bench}
LMP=${LMP:-lmp}
MPIRUN=${MPIRUN:-mpirun}
CC=${CC:-cc}
PY=/usr/bin/python3
# share/pdh5.py for the comparisons below: /bonds in either form
PYTHONPATH=$ROOT/share${PYTHONPATH:+:$PYTHONPATH}
export PYTHONPATH
EX=$ROOT/examples/lammps-impact
SCENE=$EX/impact.scene
TIME=/usr/bin/time
SEED_N=103110 # particles of the seed disk (radius 37 mm)
LPS_K=14.9e9
LPS_G=8e9

case $STEPS in '' | *[!0-9]*) die "BENCH_STEPS must be a positive integer, not '$STEPS'" ;; esac
[ "$STEPS" -gt 0 ] || die "BENCH_STEPS must be a positive integer"
case $THREADS in '' | *[!0-9]*) die "BENCH_THREADS must be a positive integer, not '$THREADS'" ;; esac
[ "$THREADS" -gt 0 ] || die "BENCH_THREADS must be a positive integer"
case $MPI_PAIRS in '' | *[!0-9]*) die "BENCH_MPI_PAIRS must be a positive integer, not '$MPI_PAIRS'" ;; esac
[ "$MPI_PAIRS" -gt 0 ] || die "BENCH_MPI_PAIRS must be a positive integer"
for w in $SKIP; do
    case $w in
    lammps | lps | effects | roofline | scaling | threads | kernels | files | sweep | plate | frames | shattered | mesh | perturbed | mpi) ;;
    *) die "BENCH_SKIP: unknown part '$w' (lammps, lps, effects, roofline, scaling, threads, kernels, files, sweep, plate, frames, shattered, mesh, perturbed, mpi)" ;;
    esac
done
# skip PART: is PART left out?
skip() {
    case " $SKIP " in *" $1 "*) return 0 ;; esac
    return 1
}
# particles N: the particle count of a BENCH_SIZES word (25k, 1.6M, 40000)
particles() {
    echo "$1" | awk '/^[0-9]+(\.[0-9]+)?[kKmM]?$/ {
        v = $0 + 0; u = substr($0, length($0))
        if (u == "k" || u == "K") v *= 1e3
        if (u == "m" || u == "M") v *= 1e6
        printf "%d\n", v; ok = 1 } END { exit !ok }'
}
NSIZES=
for w in $SIZES; do
    n=$(particles "$w") || die "BENCH_SIZES: '$w' is not a particle count (25k, 1.6M, 40000)"
    [ "$n" -ge 2000 ] || die "BENCH_SIZES: '$w' is too small (at least 2000 particles)"
    NSIZES="$NSIZES $n"
done
skip scaling || [ -n "$NSIZES" ] || die "BENCH_SIZES is empty (add 'scaling' to BENCH_SKIP instead)"
for p in pd-lattice pd-bonds pd-run; do
    [ -x "$PD_BIN/$p" ] || die "$PD_BIN/$p not found (run 'make all' first, or set PD_BIN)"
done
[ -r "$SCENE" ] || die "$SCENE not found"
[ -r "$EX/in.impact" ] || die "$EX/in.impact not found"
[ -x "$TIME" ] || die "$TIME not found (GNU time; Debian package 'time')"
command -v awk >/dev/null 2>&1 || die "awk not found"
command -v h5ls >/dev/null 2>&1 || die "h5ls not found (Debian package 'hdf5-tools')"
if ! skip lammps; then
    command -v "$LMP" >/dev/null 2>&1 ||
        die "'$LMP' not found: LAMMPS with the PERI package is needed (Debian package 'lammps'; or set LMP, or BENCH_SKIP=lammps)"
    command -v "$MPIRUN" >/dev/null 2>&1 ||
        die "'$MPIRUN' not found (Debian package 'openmpi-bin'; or set MPIRUN)"
    "$LMP" -h 2>/dev/null | grep -q 'peri/pmb' ||
        die "'$LMP' has no pair style peri/pmb (LAMMPS without the PERI package)"
    skip lps || "$LMP" -h 2>/dev/null | grep -q 'peri/lps' ||
        die "'$LMP' has no pair style peri/lps"
fi
if ! skip roofline; then
    command -v "$CC" >/dev/null 2>&1 || die "'$CC' not found (a C compiler for share/stream.c; or set CC)"
    [ -r "$ROOT/share/stream.c" ] || die "$ROOT/share/stream.c not found"
fi
if ! skip threads; then
    "$PY" -c 'import h5py, numpy' 2>/dev/null ||
        die "$PY with h5py and numpy is needed to compare the thread counts' outputs (or BENCH_SKIP=threads)"
fi

# Open MPI refuses to run as root without these (containers, CI).
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1

mkdir -p "$DIR" || die "cannot create $DIR"
cd "$DIR"

# --- the models ----------------------------------------------------------------
HORIZON=0.0015001
# build_model FILE RADIUS: the seed disk (spacing, thickness, density,
# horizon) with the given radius, built once and kept in FILE
build_model() {
    lattice="--spacing 0.0005 --cylinder y,0,0,$2,-0.0025,0 --density 2200"
    stamp="pd-lattice $lattice | pd-bonds --horizon $HORIZON"
    if [ ! -s "$1" ] || [ "$(cat "$1.stamp" 2>/dev/null)" != "$stamp" ] ||
        [ -n "$(find "$PD_BIN/pd-lattice" "$PD_BIN/pd-bonds" -newer "$1" 2>/dev/null)" ]; then
        echo "$prog: building $1 (disk of radius $2 m) in $DIR" >&2
        # shellcheck disable=SC2086 # lattice is a list of options
        "$PD_BIN/pd-lattice" $lattice -q -o lattice.h5 || die "pd-lattice failed"
        "$PD_BIN/pd-bonds" --horizon "$HORIZON" -q lattice.h5 -o "$1.tmp" || die "pd-bonds failed"
        mv "$1.tmp" "$1"
        rm -f lattice.h5
        echo "$stamp" >"$1.stamp"
    fi
}
# counts FILE: "PARTICLES BONDS" (bonds i < j) of a model file: the length
# of /particles/id and /bonds@count (the directed bonds, in either form of
# /bonds: a lattice stencil has no per-bond dataset)
counts() {
    c_n=$(h5ls "$1/particles/id" 2>/dev/null | sed -n 's/.*Dataset {\([0-9]*\).*/\1/p')
    c_b=$(h5dump -a /bonds/count "$1" 2>/dev/null | sed -n 's/^ *(0): \([0-9]*\) *$/\1/p')
    case $c_n in '' | *[!0-9]*) return 1 ;; esac
    case $c_b in '' | *[!0-9]*) return 1 ;; esac
    [ "$c_n" -gt 0 ] && [ "$c_b" -gt 0 ] || return 1
    echo "$c_n $((c_b / 2))"
}
build_model model.h5 0.037
read -r N0 B0 <<EOF
$(counts model.h5 || echo)
EOF
[ -n "$N0" ] || die "cannot read the particle and bond counts of $DIR/model.h5"

# --- helpers ----------------------------------------------------------------
# pd_loop LOG: "SECONDS BOND_UPDATES_PER_S" from pd-run's last log line
pd_loop() {
    sed -n 's/^pd-run: [0-9]* steps in \([0-9.eE+-]*\) s (\([0-9.eE+-]*\) bond updates\/s).*/\1 \2/p' "$1" |
        tail -n 1
}
# pd_row LOG ROW: the seconds of a row of pd-run --timing
pd_row() {
    awk -v r="$2" '/^pd-run: timing/ { t = 1; next }
        t { s = $0; sub(/^ */, "", s); if (index(s, r " ") == 1) { n = split(s, w, " ");
            print w[n - 2]; exit } }' "$1"
}
# steps_less_output LOG: the loop time of a pd-run log less its output row
steps_less_output() {
    read -r t _ <<EOF
$(pd_loop "$1")
EOF
    awk -v t="$t" -v o="$(pd_row "$1" output)" 'BEGIN { print t - (o == "" ? 0 : o) }'
}
# pd_bench NAME MODEL NSTEPS [pd-run option]...: pd-run on MODEL for NSTEPS
# steps on $nth threads (default THREADS); NAME.log (its log), NAME.time
# ("wall peak_kB"), NAME.h5 (its output, removed unless keep=1).
nth=
keep=''
pd_bench() {
    name=$1 model=$2 ns=$3
    shift 3
    echo "$prog: pd-run $name ($ns steps)" >&2
    "$TIME" -f '%e %M' -o "$name.time" "$PD_BIN/pd-run" "$@" --threads "${nth:-$THREADS}" \
        --steps "$ns" --every 0 --timing "$model" -o "$name.h5" 2>"$name.log" || {
        cat "$name.log" >&2
        die "pd-run ($name) failed"
    }
    [ -n "$keep" ] || rm -f "$name.h5"
    [ -n "$(pd_loop "$name.log")" ] || die "no timing line in $DIR/$name.log"
}
# lmp_bench NAME SCRIPT [STEPS]: mpirun -np NP lmp on SCRIPT (of STEPS
# steps, default BENCH_STEPS: for the message); NAME.time (wall),
# NAME.ranks (wall, peak kB of each rank), NAME.lammps (its log)
lmp_bench() {
    rm -f "$1.ranks"
    echo "$prog: $MPIRUN -np $NP $LMP, $1 (${3:-$STEPS} steps)" >&2
    # one OpenMP thread per rank (LAMMPS's default, said so when unset)
    OMP_NUM_THREADS=1 "$TIME" -f '%e %M' -o "$1.time" "$MPIRUN" -np "$NP" \
        "$TIME" -a -o "$1.ranks" -f '%e %M' "$LMP" -in "$2" -log "$1.lammps" -screen none \
        >"$1.out" 2>&1 || {
        cat "$1.out" >&2
        die "LAMMPS failed (see $DIR/$1.out, $DIR/$1.lammps)"
    }
    [ -n "$(lmp_loop "$1")" ] || die "no 'Loop time' in $DIR/$1.lammps"
}
lmp_loop() {
    sed -n 's/^Loop time of \([0-9.eE+-]*\) on .*/\1/p' "$1.lammps" | tail -n 1
}
# versus TITLE PD LMP [STEPS]: the table of pd-run (PD.log, PD.time)
# against LAMMPS (LMP.lammps, LMP.time, LMP.ranks; LMP empty: pd-run
# alone), runs of STEPS steps (default BENCH_STEPS)
versus() {
    read -r pw pk <"$2.time"
    read -r pl pr <<EOF
$(pd_loop "$2.log")
EOF
    lw='' ll='' lk='' lr=0
    if [ -n "$3" ]; then
        read -r lw _ <"$3.time"
        ll=$(lmp_loop "$3")
        lk=$(awk '{ s += $2 } END { print s + 0 }' "$3.ranks")
        lr=$(wc -l <"$3.ranks" | tr -d ' ')
    fi
    echo "$1"
    awk -v pw="$pw" -v pl="$pl" -v pk="$pk" -v pr="$pr" -v lw="$lw" -v ll="$ll" -v lk="$lk" \
        -v lr="$lr" -v n="${4:-$STEPS}" -v th="$THREADS" -v np="$NP" -v b="$B0" 'BEGIN {
        if (ll == "") {
            printf "  %-34s %12s\n", "", "pd-run"
            printf "  %-34s %12.2f\n", "wall time, whole process (s)", pw
            printf "  %-34s %12.2f\n", "time stepping loop (s)", pl
            printf "  %-34s %12.2f\n", "per step (ms)", 1000 * pl / n
            printf "  %-34s %12.0f\n", "peak memory (MiB)", pk / 1024
        } else {
            printf "  %-34s %12s %12s %9s\n", "", "pd-run", "LAMMPS", "LAMMPS/pd"
            printf "  %-34s %12.2f %12.2f %9.2f\n", "wall time, whole process (s)", pw, lw, lw / pw
            printf "  %-34s %12.2f %12.2f %9.2f\n", "time stepping loop (s)", pl, ll, ll / pl
            printf "  %-34s %12.2f %12.2f %9.2f\n", "per step (ms)", 1000 * pl / n, 1000 * ll / n, ll / pl
            printf "  %-34s %12.0f %12.0f %9.2f\n", "peak memory (MiB)", pk / 1024, lk / 1024, lk / pk
        }
        printf "  %-34s %12.3g  (%.3g bonds i < j)\n", "pd-run bond updates per second", pr, pr / 2
        if (ll == "") printf "  (%d threads)\n", th
        else printf "  (%d threads; LAMMPS: %d ranks, memory summed over %d ranks)\n", th, np, lr
    }'
}

# --- machine -----------------------------------------------------------------
cpu=$(lscpu 2>/dev/null | sed -n 's/^Model name: *//p' | head -n 1)
ncpu=$(getconf _NPROCESSORS_ONLN 2>/dev/null || echo '?')
cores=$(lscpu 2>/dev/null | awk -F: '/^Core\(s\) per socket/ { c = $2 } /^Socket\(s\)/ { s = $2 }
    END { if (c && s) printf "%d", c * s }')
mem=$(awk '/^MemTotal/ { printf "%.1f GiB", $2 / 1048576 }' /proc/meminfo 2>/dev/null || true)
load0=$(cut -d' ' -f1-3 /proc/loadavg 2>/dev/null || echo '?')
lmpver=
skip lammps || lmpver=$("$LMP" -h 2>/dev/null | sed -n 's/^Large-scale.*Simulator - //p' | head -n 1)
pdver=$("$PD_BIN/pd-run" --version 2>/dev/null | head -n 1)

# --- (a) PMB: pd-run, the full scene; LAMMPS, the seed script without its dump --
# pd-run's status lines (each an energy balance over the bonds) at the
# script's thermo interval, as LAMMPS prints its thermo lines
THERMO=$(sed -n 's/^thermo  *\([0-9][0-9]*\) *$/\1/p' "$EX/in.impact")
[ -n "$THERMO" ] || die "cannot read the thermo interval of $EX/in.impact"
keep=1 pd_bench full model.h5 "$STEPS" --scene "$SCENE" --status "$THERMO"
keep=''
if ! skip lammps; then
    sed -e '/^dump/d' -e "s/^run .*/run             $STEPS/" "$EX/in.impact" >in.bench
    grep -q "^run  *$STEPS\$" in.bench || die "cannot set 'run $STEPS' in in.bench"
    lmp_bench lmp in.bench
fi

# --- (b) LPS ------------------------------------------------------------------
if ! skip lps; then
    pd_bench lps model.h5 "$STEPS" --scene "$SCENE" --model lps --bulk-modulus "$LPS_K" \
        --shear-modulus "$LPS_G" --status "$THERMO"
    if ! skip lammps; then
        # pair_coeff * * K G horizon s00 alpha, from the seed's * * c horizon s00 alpha
        sed -e 's|^pair_style .*|pair_style      peri/lps|' \
            -e "s|^\(pair_coeff  *\* *\* *\)[^ ]*|\1$LPS_K $LPS_G|" in.bench >in.lps
        grep -q "^pair_coeff .*$LPS_K $LPS_G $HORIZON" in.lps ||
            die "cannot write pair_coeff for peri/lps in in.lps"
        lmp_bench lmp-lps in.lps
    fi
fi

# --- (c) the cost of each effect ----------------------------------------------
if ! skip effects; then
    # the same numbers as the scene (c, failure, indenter, dt), stated here once
    C=$(sed -n 's/^c  *//p' "$SCENE")
    FAILURE=$(sed -n 's/^failure  *//p' "$SCENE")
    INDENTER=$(sed -n 's/^indenter  *//p' "$SCENE")
    DT=$(sed -n 's/^dt  *//p' "$SCENE")
    if [ -z "$C" ] || [ -z "$FAILURE" ] || [ -z "$INDENTER" ] || [ -z "$DT" ]; then
        die "cannot read c, failure, indenter and dt from $SCENE"
    fi
    pd_bench bonds model.h5 "$STEPS" --c "$C" --dt "$DT"
    pd_bench indenter model.h5 "$STEPS" --c "$C" --dt "$DT" --indenter "$INDENTER"
    pd_bench failure model.h5 "$STEPS" --c "$C" --dt "$DT" --indenter "$INDENTER" --failure "$FAILURE"
    # + contact is the full scene of (a)
fi

# --- (d) the roofline -----------------------------------------------------------
if ! skip roofline; then
    echo "$prog: building and running share/stream.c ($THREADS threads)" >&2
    # the widest vectors: GCC's default on Intel's AVX-512 processors is
    # 256 bits, half the FMA peak of the tiles' 512-bit vectors
    wide=-mprefer-vector-width=512
    echo 'int main(void) { return 0; }' >wide.c
    "$CC" -march=native "$wide" wide.c -o wide 2>/dev/null || wide=
    rm -f wide.c wide
    "$CC" -std=gnu11 -O3 -march=native $wide -ffp-contract=fast -fno-math-errno -fopenmp \
        "$ROOT/share/stream.c" -o stream -lm 2>stream.err || {
        cat stream.err >&2
        die "cannot build share/stream.c with $CC"
    }
    OMP_NUM_THREADS=$THREADS OMP_PROC_BIND=close ./stream >stream.out || die "stream failed"
    # the bond kernel alone, best and median of 200 passes (share/passes.c)
    [ -x "$ROOT/share/passes" ] || die "$ROOT/share/passes not built (make share/passes; make bench builds it)"
    echo "$prog: timing 200 bond passes of model.h5 alone (share/passes, $THREADS threads)" >&2
    "$ROOT/share/passes" model.h5 "$THREADS" 200 >passes.out || die "share/passes failed"
fi

# --- (e) scaling with size ----------------------------------------------------
if ! skip scaling; then
    for n in $NSIZES; do
        if awk -v n="$n" -v s="$SEED_N" 'BEGIN { exit !(n > 0.9 * s && n < 1.1 * s) }'; then
            m=model.h5 # about 100k: the seed disk
        else
            m=disk-$n.h5
            build_model "$m" "$(awk -v n="$n" -v s="$SEED_N" 'BEGIN { printf "%.6g", 0.037 * sqrt(n / s) }')"
        fi
        ns=$(awk -v n="$n" -v s="$SEED_N" -v st="$STEPS" 'BEGIN {
            k = int(st * s / n + 0.5); if (k < 100) k = 100; if (k > st) k = st; print k }')
        # one status line (at the end): each costs an energy pass over the
        # bonds, and the default, every steps/10, would charge the short
        # runs of the large disks more of them per step
        # twice, the better run kept (one run of a large disk can meet a
        # slow minute of this shared machine: the page cache writing back
        # a model just built, another tenant)
        pd_bench "size-$n" "$m" "$ns" --scene "$SCENE" --status "$ns"
        pd_bench "size-$n-again" "$m" "$ns" --scene "$SCENE" --status "$ns"
        if awk -v a="$(steps_less_output "size-$n.log")" \
            -v b="$(steps_less_output "size-$n-again.log")" 'BEGIN { exit !(b < a) }'; then
            mv "size-$n-again.log" "size-$n.log"
            mv "size-$n-again.time" "size-$n.time"
        fi
        rm -f "size-$n-again.log" "size-$n-again.time"
        echo "$n $m $ns" >"size-$n.run"
    done
    # what pd-run takes whatever the size (program, libraries, HDF5 and
    # OpenMP): the peak of a 500-particle block under the same scene
    "$PD_BIN/pd-lattice" --spacing 0.0005 --box -0.0025,0.0025,-0.0025,0,-0.0025,0.0025 \
        --density 2200 -q -o base-lattice.h5 &&
        "$PD_BIN/pd-bonds" --horizon "$HORIZON" -q base-lattice.h5 -o base.h5 ||
        die "cannot build the 500-particle block"
    pd_bench size-base base.h5 10 --scene "$SCENE" --status 10
    rm -f base-lattice.h5 base.h5
fi

# --- (f) threads ------------------------------------------------------------------
if ! skip threads; then
    # 1 and THREADS threads alternately, twice each, back to back: the best
    # of each is the figure (the machine's noise comes and goes on a scale
    # of seconds to minutes, so runs far apart in time do not compare)
    keep=1 nth=1 pd_bench t1 model.h5 "$STEPS" --scene "$SCENE" --status "$THERMO"
    keep='' nth=''
    pd_bench t2 model.h5 "$STEPS" --scene "$SCENE" --status "$THERMO"
    nth=1 pd_bench t1b model.h5 "$STEPS" --scene "$SCENE" --status "$THERMO"
    nth=''
    pd_bench t2b model.h5 "$STEPS" --scene "$SCENE" --status "$THERMO"
    # every dataset bit for bit; every attribute but threads and history
    "$PY" - t1.h5 full.h5 >same.out <<'EOF' || die "cannot compare t1.h5 and full.h5"
import sys
import h5py
import numpy as np

def items(name):
    out = {}
    with h5py.File(name, "r") as f:
        def visit(path, obj):
            for k, v in obj.attrs.items():
                if k not in ("threads", "history"):
                    out["%s@%s" % (path, k)] = np.asarray(v)
            if isinstance(obj, h5py.Dataset):
                out[path] = np.asarray(obj[()])
        visit("/", f)
        f.visititems(visit)
    return out

a, b = items(sys.argv[1]), items(sys.argv[2])
diff = sorted(set(a) ^ set(b))
worst = 0.0
for k in sorted(set(a) & set(b)):
    x, y = a[k], b[k]
    if x.shape != y.shape or x.dtype != y.dtype or x.tobytes() != y.tobytes():
        diff.append(k)
        if x.shape == y.shape and x.dtype.kind == "f":
            worst = max(worst, float(np.nanmax(np.abs(x.astype(float) - y.astype(float)))))
if not diff:
    print("identical (%d datasets and attributes, bit for bit)" % len(a))
else:
    print("DIFFERENT: %d items (%s%s), largest difference %.3g"
          % (len(diff), ", ".join(diff[:4]), ", ..." if len(diff) > 4 else "", worst))
EOF
    rm -f t1.h5
fi

# --- (o) MPI ranks: THREADS ranks of 1 thread against 1 rank of THREADS --------
MPI_PD=${PD_MPI_BIN:-$ROOT/mpi/bin/pd-run}
if ! skip mpi && [ -x "$MPI_PD" ]; then
    # mpi_bench NAME: the full scene on THREADS ranks of 1 thread
    mpi_bench() {
        echo "$prog: $MPIRUN -np $THREADS pd-run (MPI) $1 ($STEPS steps)" >&2
        OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 "$TIME" -f '%e %M' -o "$1.time" \
            "$MPIRUN" --bind-to none -np "$THREADS" "$MPI_PD" --scene "$SCENE" --status "$THERMO" \
            --threads 1 --steps "$STEPS" --every 0 --timing model.h5 -o "$1.h5" 2>"$1.log" || {
            cat "$1.log" >&2
            die "mpirun pd-run ($1) failed"
        }
        [ -n "$(pd_loop "$1.log")" ] || die "no timing line in $DIR/$1.log"
    }
    # MPI_PAIRS pairs, one rank then the ranks, one after the other: on a
    # shared machine the ratio of a pair's loops is steadier than either
    k=1
    while [ "$k" -le "$MPI_PAIRS" ]; do
        keep=1 pd_bench "m1-$k" model.h5 "$STEPS" --scene "$SCENE" --status "$THERMO"
        keep=''
        mpi_bench "mr-$k"
        k=$((k + 1))
    done
    "$PY" "$ROOT/tests/samebits/h5same.py" m1-1.h5 mr-1.h5 >mpi-same.out 2>&1 || true
    rm -f m1-*.h5 mr-*.h5
fi

# --- (g) kernels: the bond list against the lattice stencil -----------------------
if ! skip kernels; then
    keep=1 pd_bench list model.h5 "$STEPS" --scene "$SCENE" --status "$THERMO" --bond-list
    keep=''
    # the largest position difference, the damaged particles of each, the
    # particles damaged in one run only, the difference of broken bonds
    "$PY" - full.h5 list.h5 >kernels.out <<'EOF' || die "cannot compare list.h5 and full.h5"
import sys
import h5py
import numpy as np
import pdh5

def last(name):
    f = h5py.File(name, "r")
    g = max(f["frames"].values(), key=lambda g: g.attrs["step"])
    # damaged: a particle with a broken bond (directed bond states, by row)
    off, count = pdh5.bonds(f)[0], int(f["bonds"].attrs["count"])
    state = np.unpackbits(g["state"][:], bitorder="little")[:count].astype(np.int64)
    broken = np.add.reduceat(1 - state, off[:-1]) if count else np.zeros(len(off) - 1)
    broken[off[:-1] == off[1:]] = 0  # reduceat of an empty row
    order = np.argsort(f["particles/id"][:])
    return g["displacement"][:][order], broken[order] > 0, int(g.attrs["broken_bonds"])

(ua, da, ba), (ub, db, bb) = last(sys.argv[1]), last(sys.argv[2])
print("%.3g %.3g %d %d %d %d" % (np.abs(ua - ub).max(), np.abs(ua).max(), da.sum(), db.sum(),
                                 (da != db).sum(), ba - bb))
EOF
    rm -f list.h5
fi
# --- (h) files and the pipe ---------------------------------------------------------
# size FILE: its bytes
size() { wc -c <"$1" | tr -d ' '; }
# best2 NAME CMD...: CMD twice under /usr/bin/time; NAME.time gets the
# better "wall peak_kB"
best2() {
    name=$1
    shift
    "$TIME" -f '%e %M' -o "$name.t1" "$@" || die "$name failed"
    "$TIME" -f '%e %M' -o "$name.t2" "$@" || die "$name failed"
    sort -n "$name.t1" "$name.t2" | head -n 1 >"$name.time"
}
if ! skip files; then
    echo "$prog: files and the pipe" >&2
    lat="--spacing 0.0005 --cylinder y,0,0,0.037,-0.0025,0 --density 2200"
    # shellcheck disable=SC2086 # lat is a list of options
    best2 lattice "$PD_BIN/pd-lattice" $lat -q -o f-lattice.h5
    best2 bonds "$PD_BIN/pd-bonds" --horizon "$HORIZON" -q f-lattice.h5 -o f-model.h5
    "$PD_BIN/pd-bonds" --horizon "$HORIZON" --csr -q f-lattice.h5 -o f-csr.h5 ||
        die "pd-bonds --csr failed"
    keep=1 pd_bench files f-model.h5 "$STEPS" --scene "$SCENE" --status "$THERMO"
    keep=''
    echo "$(size f-lattice.h5) $(size f-model.h5) $(size f-csr.h5) $(size files.h5)" >files.sizes
    rm -f f-csr.h5 files.h5
    # the pipe: the whole scene of (a) from nothing
    echo "$prog: pd-lattice | pd-bonds | pd-run ($STEPS steps)" >&2
    "$TIME" -f '%e %M' -o pipe.time sh -c '"$1"/pd-lattice $2 -q -o - |
        "$1"/pd-bonds --horizon "$3" -q - -o - |
        "$1"/pd-run --scene "$4" --status "$5" --threads "$6" --steps "$7" --every 0 - -o pipe.h5' \
        _ "$PD_BIN" "$lat" "$HORIZON" "$SCENE" "$THERMO" "$THREADS" "$STEPS" 2>pipe.log ||
        { cat pipe.log >&2; die "the pipe failed"; }
    rm -f pipe.h5
fi

# --- (i) a sweep: make -j against one run after another ------------------------
SWEEP_STEPS=${BENCH_SWEEP_STEPS:-100}
if ! skip sweep; then
    echo "$prog: a sweep of four runs, make -j$THREADS and make -j1, twice each" >&2
    {
        echo "S = 0.0004 0.0005 0.0006 0.0007"
        echo 'all: $(S:%=sweep-%.h5)'
        echo "sweep-%.h5: model.h5"
        printf '\t"%s" -q --scene "%s" --failure $*,0.25 --steps %s --every 0 model.h5 -o $@\n' \
            "$PD_BIN/pd-run" "$SCENE" "$SWEEP_STEPS"
    } >sweep.mk
    rm -f "sweep-$THREADS.times" sweep-1.times
    for j in "$THREADS" 1 "$THREADS" 1; do
        rm -f sweep-*.h5
        # a make of its own, not a part of `make bench`'s jobserver
        "$TIME" -f '%e' -a -o "sweep-$j.times" env -u MAKEFLAGS -u MFLAGS -u MAKELEVEL \
            make -s -f sweep.mk -j "$j" all ||
            die "the sweep failed (make -j$j)"
    done
    rm -f sweep-*.h5
fi
# --- (j) a plate: the 2-D stencil against the 3-D seed -------------------------
if ! skip plate; then
    echo "$prog: a pre-cracked 2-D plate ($STEPS steps)" >&2
    "$PD_BIN/pd-lattice" -q --dimension 2 --thickness 0.001 --spacing 0.00016 --density 8000 \
        --box -0.025,0.025,-0.025,0.025,-1,1 --set top=box,-1,1,0.0245,1,-1,1 \
        --set bottom=box,-1,1,-1,-0.0245,-1,1 -o plate-lattice.h5 || die "pd-lattice (plate) failed"
    "$PD_BIN/pd-bonds" -q --horizon 0.00048005 --crack segment,-0.005,0,0.005,0 \
        plate-lattice.h5 -o plate-model.h5 || die "pd-bonds (plate) failed"
    pd_bench plate plate-model.h5 "$STEPS" --youngs-modulus 192e9 --failure 0.02,0 \
        --velocity-bc top,y,pulses:20,5e-6,-20,5e-6 --velocity-bc bottom,y,pulses:-20,5e-6,20,5e-6
    rm -f plate-lattice.h5
fi
# --- (k) frames: a frame every 5 steps against the one of (a) ------------------
FRAME_EVERY=5
if ! skip frames; then
    echo "$prog: pd-run with a frame every $FRAME_EVERY steps ($STEPS steps)" >&2
    "$TIME" -f '%e %M' -o frames.time "$PD_BIN/pd-run" --scene "$SCENE" --status "$THERMO" \
        --threads "$THREADS" --steps "$STEPS" --every "$FRAME_EVERY" --timing model.h5 \
        -o frames.h5 2>frames.log || { cat frames.log >&2; die "pd-run (frames) failed"; }
    [ -n "$(pd_loop frames.log)" ] || die "no timing line in $DIR/frames.log"
    # pd-damage on the run: in place (its frames hold their damage: read,
    # not copied) and into a new file
    best2 damage-in-place "$PD_BIN/pd-damage" -q frames.h5
    best2 damage-copy "$PD_BIN/pd-damage" -q frames.h5 -o frames-damage.h5
    echo "$(size frames.h5) $(size full.h5)" >frames.sizes
    mb=$(($(size frames.h5) / 1048576 + 1))
    rm -f frames.h5 frames-damage.h5
    sleep 15
    "$TIME" -f '%e' -o page-cache.time dd if=/dev/zero of=page-cache.tmp bs=1M count="$mb" \
        2>/dev/null || die "dd failed"
    rm -f page-cache.tmp
    echo "$mb" >page-cache.mb
fi
# --- (l) shattered: the whole 2000-step demo against in.impact as it is -------
if ! skip shattered; then
    echo "$prog: pd-run, the whole demo (impact.scene, 2000 steps, a frame every 100)" >&2
    "$TIME" -f '%e %M' -o shattered.time "$PD_BIN/pd-run" --scene "$SCENE" --threads "$THREADS" \
        --timing model.h5 -o shattered.h5 2>shattered.log ||
        { cat shattered.log >&2; die "pd-run (shattered) failed"; }
    [ -n "$(pd_loop shattered.log)" ] || die "no timing line in $DIR/shattered.log"
    rm -f shattered.h5
    if ! skip lammps; then
        # the seed script verbatim: its dump every 100 steps, into this folder
        cp "$EX/in.impact" in.shattered
        lmp_bench lmp-shattered in.shattered 2000
        rm -f dump.peri
    fi
fi
# --- (m) meshes: the seed disk meshed, and a surface filled ----------------------
if ! skip mesh; then
    echo "$prog: the seed disk meshed by gmsh, pd-mesh, pd-bonds, pd-run ($STEPS steps)" >&2
    gmsh -v 0 -3 -format msh41 -o disk.msh "$ROOT/share/bench-disk.geo" || die "gmsh failed"
    best2 mesh-pd-mesh "$PD_BIN/pd-mesh" -q --density 2200 disk.msh -o mesh-particles.h5
    best2 mesh-pd-bonds "$PD_BIN/pd-bonds" -q --horizon "$HORIZON" mesh-particles.h5 -o mesh-model.h5
    pd_bench mesh mesh-model.h5 "$STEPS" --scene "$SCENE" --status "$THERMO"
    "$PD_BIN/pd-mesh" -q --surface disk.msh -o disk-surface.h5 || die "pd-mesh --surface failed"
    best2 fill-inside "$PD_BIN/pd-lattice" -q --spacing 0.00014 --density 2200 \
        --inside disk-surface.h5 -o /dev/null
    best2 fill-cylinder "$PD_BIN/pd-lattice" -q --spacing 0.00014 --density 2200 \
        --cylinder y,0,0,0.037,-0.0025,0 -o /dev/null
    "$PD_BIN/pd-lattice" --spacing 0.00014 --density 2200 --inside disk-surface.h5 -o /dev/null \
        2>fill.log || die "pd-lattice --inside failed"
    rm -f mesh-particles.h5 mesh-model.h5 disk-surface.h5
fi
# --- (n) an irregular body: the seed perturbed, its bond list against LAMMPS ----
PERTURB=${BENCH_PERTURB:-5e-5}
if ! skip perturbed; then
    echo "$prog: the seed disk perturbed by $PERTURB m (the bond list; $STEPS steps)" >&2
    # shellcheck disable=SC2086 # a list of options
    "$PD_BIN/pd-lattice" --spacing 0.0005 --cylinder y,0,0,0.037,-0.0025,0 --density 2200 \
        --perturb "$PERTURB" -q -o p-lattice.h5 &&
        "$PD_BIN/pd-bonds" --horizon "$HORIZON" -q p-lattice.h5 -o p-model.h5 ||
        die "cannot build the perturbed disk"
    rm -f p-lattice.h5
    pd_bench perturbed p-model.h5 "$STEPS" --scene "$SCENE" --status "$THERMO"
    if ! skip lammps; then
        C=$(sed -n 's/^c  *//p' "$SCENE")
        FAILURE=$(sed -n 's/^failure  *//p' "$SCENE")
        INDENTER=$(sed -n 's/^indenter  *//p' "$SCENE")
        DT=$(sed -n 's/^dt  *//p' "$SCENE")
        "$PY" "$ROOT/tests/lammps/pd2lmp.py" p-model.h5 -d perturbed.data -i in.perturbed.tmp \
            --c "$C" --horizon "$HORIZON" --failure "$FAILURE" --dt "$DT" --indenter "$INDENTER" \
            --steps "$STEPS" --every "$STEPS" || die "pd2lmp.py failed on the perturbed disk"
        sed -e '/^dump/d' -e "s/^thermo .*/thermo          $THERMO/" in.perturbed.tmp >in.perturbed
        grep -q "^thermo  *$THERMO\$" in.perturbed || die "cannot set the thermo interval in in.perturbed"
        lmp_bench lmp-perturbed in.perturbed
        rm -f in.perturbed.tmp perturbed.data
    fi
    rm -f p-model.h5
fi
rm -f full.h5

# --- report ---------------------------------------------------------------------
# body LOG: "N particles, B bonds" of a pd-run log
body() {
    sed -n 's/^pd-run: \([0-9]*\) particles, \([0-9]*\) bonds.*/\1 particles, \2 bonds/p' "$1" |
        head -n 1
}
echo
echo "pd bench: seed impact (examples/lammps-impact), $N0 particles, $B0 bonds, $STEPS steps"
echo "machine:  ${cpu:-unknown CPU}, $ncpu CPUs (${cores:-?} cores), ${mem:-? memory}"
echo "load:     $load0 (1/5/15 min, at the start)"
echo "pd:       ${pdver:-?}, pd-run --threads $THREADS"
skip lammps || echo "LAMMPS:   ${lmpver:-?}, $MPIRUN -np $NP $LMP"
echo
lmp=lmp
skip lammps && lmp=
versus "PMB (LAMMPS peri/pmb):" full "$lmp"
if ! skip lps; then
    echo
    lmp='lmp-lps'
    skip lammps && lmp=
    versus "LPS, K = $LPS_K Pa, G = $LPS_G Pa (LAMMPS peri/lps):" lps "$lmp"
fi

if ! skip effects; then
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
fi
echo
echo "pd-run --timing of the full PMB scene:"
sed -n '/^pd-run: timing/,$p' full.log | sed 's/^/  /'

if ! skip roofline; then
    bw=$(sed -n 's/^triad_bytes_per_s //p' stream.out)
    fl=$(sed -n 's/^fma_flops_per_s //p' stream.out)
    dv=$(sed -n 's/^sqrt_div_per_s //p' stream.out)
    tb=$(pd_row full.log bonds)
    { [ -n "$bw" ] && [ -n "$fl" ] && [ -n "$dv" ] && [ -n "$tb" ]; } ||
        die "cannot read stream.out or the bonds row of full.log"
    ll=
    skip lammps || ll=$(lmp_loop lmp)
    echo
    # which kernel ran: the lattice stencil (lib/stencil/grid.c) or the bond list
    stencil=0
    grep -q 'bonds walked as a lattice stencil' full.log && stencil=1
    echo "roofline of the PMB bond kernel (with failure$([ $stencil = 1 ] && echo ', the lattice stencil with the contact of its pairs'), $THREADS threads:"
    # bytes and flops per bond i < j: see README.md, "Performance"
    awk -v bw="$bw" -v fl="$fl" -v dv="$dv" -v tb="$tb" -v n="$N0" -v b="$B0" -v st="$STEPS" \
        -v stencil="$stencil" -v ll="$ll" 'BEGIN {
        per = b / n                        # bonds i < j per particle
        if (stencil) {                     # per particle only: positions, forces,
            bb = 112 / per                 # s0, s0_new, the two mask words
            ff = 29; nd = 1
        } else {
            bb = 4 + 8 + 8 + 1 / 8 + 104 / per # streamed per bond + per particle / per
            ff = 31; nd = 3
        }
        rate = b * (st + 1) / tb           # bonds per second in the kernel
                                           # (setup evaluates the forces once more)
        ai = ff / bb
        printf "  machine: triad %.1f GB/s, FMA peak %.1f GFLOP/s (share/stream.c; balance %.2f flop/B)\n",
            bw / 1e9, fl / 1e9, fl / bw
        printf "  kernel:  %.1f bytes and %d flops per bond (%.2f flop/B; %d division%s and 1 sqrt among the flops)\n",
            bb, ff, ai, nd, nd > 1 ? "s" : ""
        printf "  bonds row %.3f s for %d x %d bonds: %.3g bonds/s, %.2f ns per bond\n",
            tb, st + 1, b, rate, 1e9 / rate
        printf "  achieved %.2f GB/s = %.0f%% of the triad, %.2f GFLOP/s = %.0f%% of the FMA peak\n",
            rate * bb / 1e9, 100 * rate * bb / bw, rate * ff / 1e9, 100 * rate * ff / fl
        roof = ai * bw < fl ? ai * bw : fl
        printf "  roofline bound %.3g bonds/s (%s-bound): achieved %.0f%% of it\n",
            roof / ff, ai * bw < fl ? "memory" : "compute", 100 * rate * ff / roof
        # the divider: a square root and nd divisions a bond, (1 + nd) / 2
        # of share/stream.c'"'"'s pairs (a square root and a division)
        dr = dv / ((1 + nd) / 2)
        printf "  divider: %.3g square roots and divisions (pairs) a second; the kernel'"'"'s %s\n",
            dv, nd == 1 ? "1 pair a bond" : sprintf("%.0f pairs a bond", (1 + nd) / 2)
        printf "  divider bound %.3g bonds/s: achieved %.0f%% of it\n", dr, 100 * rate / dr
        if (ll != "")
            printf "  LAMMPS/pd of the PMB loop with every bond at the divider bound and the rest free: %.1f\n",
                ll / (b * (st + 1) / dr)
    }'
    # the kernel alone: its best pass against the roofs' best (both the
    # best of their repetitions), its median pass the hour the bench ran
    read -r _ kind _ _ _ pb _ best _ median <passes.out || die "cannot read passes.out"
    awk -v bw="$bw" -v fl="$fl" -v dv="$dv" -v b="$pb" -v best="$best" -v med="$median" \
        -v kind="$kind" 'BEGIN {
        ff = kind == "stencil" ? 29 : 31
        dr = kind == "stencil" ? dv : dv / 2
        printf "  the kernel alone (share/passes: the bond pass of model.h5 with failure and contact,\n"
        printf "  every bond stretched, no break; 200 passes): best %.2f ms a pass, %.3f ns per bond,\n",
            1e3 * best, 1e9 * best / b
        printf "  %.1f GFLOP/s = %.0f%% of the FMA peak; median %.2f ms, %.0f%%;\n",
            ff * b / best / 1e9, 100 * ff * b / best / fl, 1e3 * med, 100 * ff * b / med / fl
        printf "  %.0f%% of the divider bound (median %.0f%%)\n", 100 * b / best / dr, 100 * b / med / dr
    }'
fi

if ! skip scaling; then
    echo
    echo "scaling with size (the impact scene on larger disks, --threads $THREADS;"
    echo "  per step: the loop time less output, over the steps + the setup's forces):"
    read -r _ kb0 <size-base.time
    printf "  %10s %11s %6s %14s %14s %14s %14s\n" particles bonds steps "ms/step" "ns/bond/step" \
        "peak B/particle" "above base"
    for n in $NSIZES; do
        read -r _ m ns <"size-$n.run"
        read -r np nb <<EOF
$(counts "$m")
EOF
        read -r t _ <<EOF
$(pd_loop "size-$n.log")
EOF
        read -r _ kb <"size-$n.time"
        # the loop less its output (the last frame), over the steps and the
        # setup's force evaluation, which the loop time also holds
        to=$(pd_row "size-$n.log" output)
        awk -v np="$np" -v nb="$nb" -v ns="$ns" -v t="$t" -v to="${to:-0}" -v kb="$kb" \
            -v kb0="$kb0" 'BEGIN {
            t = (t - to) / (ns + 1)
            printf "  %10d %11d %6d %14.2f %14.3f %14.0f %14.0f\n", np, nb, ns, 1000 * t,
                1e9 * t / nb, 1024 * kb / np, 1024 * (kb - kb0) / np }'
    done | tee scaling.out
    awk -v kb0="$kb0" '{ t = $5; m = $6; a = $7; if (NR == 1 || t < t0) t0 = t; if (t > t1) t1 = t
           if (NR == 1 || m < m0) m0 = m; if (m > m1) m1 = m
           if (NR == 1 || a < a0) a0 = a; if (a > a1) a1 = a }
        END { if (NR > 1) {
            printf "  spread: time per bond %.0f%% (max/min - 1; target <= 30%%), memory per particle %.0f%%\n",
                100 * (t1 / t0 - 1), 100 * (m1 / m0 - 1)
            printf "  memory above the base (%.0f MiB, the peak of a 500-particle run): %.0f%% per particle\n",
                kb0 / 1024, 100 * (a1 / a0 - 1) } }' scaling.out
fi

if ! skip threads; then
    echo
    read -r t1 _ <<EOF
$(pd_loop t1.log)
EOF
    read -r t1b _ <<EOF
$(pd_loop t1b.log)
EOF
    read -r t2 _ <<EOF
$(pd_loop t2.log)
EOF
    read -r t2b _ <<EOF
$(pd_loop t2b.log)
EOF
    awk -v a="$t1" -v a2="$t1b" -v b="$t2" -v b2="$t2b" -v th="$THREADS" -v n="$STEPS" 'BEGIN {
        if (a2 < a) a = a2
        if (b2 < b) b = b2
        printf "threads: 1 thread %.2f ms/step, %d threads %.2f ms/step: speed-up %.2fx\n",
            1000 * a / n, th, 1000 * b / n, a / b
        printf "  (the best of two runs of each, 1 and %d threads alternately)\n", th }'
    echo "  outputs of 1 and $THREADS threads: $(cat same.out)"
fi

if ! skip mpi && [ -x "$MPI_PD" ]; then
    echo
    # each pair's loops (one rank, the ranks) and the ranks' exchanges
    pairs=$(k=1
        while [ "$k" -le "$MPI_PAIRS" ]; do
            echo "$(pd_loop "m1-$k.log" | cut -d' ' -f1) $(pd_loop "mr-$k.log" | cut -d' ' -f1) $(pd_row "mr-$k.log" 'MPI ranks')"
            k=$((k + 1))
        done)
    halo=$(sed -n 's/.*halo of at most \([0-9.eE+-]*\) MB a rank a step.*/\1/p' mr-1.log)
    echo "$pairs" | sort -t' ' -k1,1 | awk -v th="$THREADS" -v n="$STEPS" -v h="$halo" '
        { a[NR] = $1; b[NR] = $2; c[NR] = $3; r[NR] = $2 / $1 }
        END {
            ba = a[1]; bb = b[1]; cs = 0
            for (k = 1; k <= NR; k++) {
                if (a[k] < ba) ba = a[k]
                if (b[k] < bb) bb = b[k]
                cs += c[k] / b[k]
            }
            # the median of the pairs'"'"' ratios
            for (k = 1; k <= NR; k++)
                for (m = k + 1; m <= NR; m++)
                    if (r[m] < r[k]) { t = r[k]; r[k] = r[m]; r[m] = t }
            med = NR % 2 ? r[(NR + 1) / 2] : (r[NR / 2] + r[NR / 2 + 1]) / 2
            printf "MPI ranks: %d ranks x 1 thread against 1 rank x %d threads: %.2fx the time (median of %d pairs, %.2f to %.2f)\n",
                th, th, med, NR, r[1], r[NR]
            printf "  best loops: 1 rank x %d threads %.2f ms/step, %d ranks x 1 thread %.2f ms/step\n",
                th, 1000 * ba / n, th, 1000 * bb / n
            printf "  halo %s MB a rank a step; the ranks'"'"' exchanges %.1f%% of the loop (--timing, MPI ranks, mean)\n",
                h, 100 * cs / NR
            printf "  (pairs run one after the other; target: within 10%%)\n" }'
    ndiff=$(grep -v 'threads' mpi-same.out | grep -c . || true)
    if [ "$ndiff" -gt 0 ]; then
        echo "  outputs of 1 rank and $THREADS ranks: differ in $ndiff items (see $DIR/mpi-same.out)"
    else
        echo "  outputs of 1 rank and $THREADS ranks: identical, bit for bit (but /scene@threads)"
    fi
fi

if ! skip kernels; then
    echo
    read -r tl _ <<EOF
$(pd_loop list.log)
EOF
    read -r ts _ <<EOF
$(pd_loop full.log)
EOF
    read -r du umax dmg_s dmg_l ddiff bdiff <kernels.out
    echo "kernels: the lattice stencil (default) against the bond list (--bond-list), full scene:"
    awk -v a="$tl" -v b="$ts" -v n="$STEPS" 'BEGIN {
        printf "  bond list %.2f ms/step, stencil %.2f ms/step: the stencil is %.2fx faster\n",
            1000 * a / n, 1000 * b / n, a / b }'
    echo "  after $STEPS steps: largest position difference $du m (largest displacement $umax m);"
    echo "  damaged particles $dmg_s (stencil) and $dmg_l (list), $ddiff damaged in one run only;"
    echo "  broken bonds differ by $bdiff (the two sum in another order: they agree to rounding)"
fi
if ! skip files; then
    echo
    read -r s_lat s_model s_csr s_run <files.sizes
    read -r t_lat _ <lattice.time
    read -r t_bonds _ <bonds.time
    read -r fw fk <files.time
    read -r fl _ <<EOF
$(pd_loop files.log)
EOF
    read -r pw _ <pipe.time
    lw=
    skip lammps || read -r lw _ <lmp.time
    echo "files: the seed disk, $N0 particles, $B0 bonds"
    awk -v n="$N0" -v sl="$s_lat" -v sm="$s_model" -v sc="$s_csr" -v sr="$s_run" \
        -v tl="$t_lat" -v tb="$t_bonds" -v fw="$fw" -v fl="$fl" -v fk="$fk" -v pw="$pw" \
        -v lw="$lw" -v st="$STEPS" 'BEGIN {
        printf "  %-46s %8.3f s\n", "pd-lattice (the better of two)", tl
        printf "  %-46s %8.3f s\n", "pd-bonds (the better of two)", tb
        printf "  %-46s %8.1f MB %6.0f B/particle\n", "lattice.h5", sl / 1e6, sl / n
        printf "  %-46s %8.1f MB %6.0f B/particle\n", "model.h5 (a lattice stencil)", sm / 1e6, sm / n
        printf "  %-46s %8.1f MB %6.0f B/particle\n", "the same as lists (pd-bonds --csr)", sc / 1e6, sc / n
        printf "  %-46s %8.1f MB %6.0f B/particle\n", "run file of (a): the model and one frame", sr / 1e6, sr / n
        printf "  %-46s %8.3f s\n", "pd-run outside its loop (start-up, last frame)", fw - fl
        printf "  %-46s %8.0f B/particle\n", "pd-run peak memory", fk * 1024 / n
        printf "  %-46s %8.2f s\n", "pd-lattice | pd-bonds | pd-run, " st " steps", pw
        if (lw != "") printf "  %-46s %8.2f s: LAMMPS/pipe %.2fx\n", "LAMMPS, whole process", lw, lw / pw }'
fi

if ! skip sweep; then
    echo
    echo "sweep: four pd-runs of the full scene ($SWEEP_STEPS steps each, no thread option)"
    awk -v j="$THREADS" 'FNR == 1 { k++ } { t[k, FNR] = $1 }
        END { a = t[1, 1] < t[1, 2] ? t[1, 1] : t[1, 2]; b = t[2, 1] < t[2, 2] ? t[2, 1] : t[2, 2]
            printf "  make -j%d %.2f s, make -j1 %.2f s: -j%d/-j1 %.2f (the better of two each)\n",
                j, a, b, j, a / b }' "sweep-$THREADS.times" sweep-1.times
fi
if ! skip plate; then
    echo
    read -r _ r3 <<EOF
$(pd_loop full.log)
EOF
    read -r t2 r2 <<EOF
$(pd_loop plate.log)
EOF
    n2=$(body plate.log)
    echo "plate: a 2-D plate, 50 mm square, dx 0.16 mm, delta 3 dx, a 10 mm centre pre-crack,"
    echo "  velocity pulses on its top and bottom sets, PMB with failure ($n2)"
    awk -v r2="$r2" -v r3="$r3" -v t="$t2" -v n="$STEPS" 'BEGIN {
        printf "  %.2f ms/step, %.3g bond updates/s: %.0f%% of the 3-D seed'"'"'s %.3g (a)\n",
            1000 * t / n, r2, 100 * r2 / r3, r3 }'
fi
if ! skip frames; then
    echo
    read -r t1 _ <<EOF2
$(pd_loop full.log)
EOF2
    read -r tf _ <<EOF2
$(pd_loop frames.log)
EOF2
    nf=$(sed -n 's/^pd-run: .*[^0-9]\([0-9][0-9]*\) frames to write$/\1/p' frames.log | head -n 1)
    read -r di _ <damage-in-place.time
    read -r dc _ <damage-copy.time
    read -r fs f1 <frames.sizes
    read -r pc <page-cache.time
    read -r pcmb <page-cache.mb
    echo "frames: (a) with a frame every $FRAME_EVERY steps, ${nf:-?} frames against (a)'s one"
    awk -v t1="$t1" -v tf="$tf" -v nf="$nf" -v n="$STEPS" -v of="$(pd_row frames.log output)" \
        -v o1="$(pd_row full.log output)" -v di="$di" -v dc="$dc" -v fs="$fs" \
        -v f1="$f1" -v pc="$pc" -v pcmb="$pcmb" 'BEGIN {
        step = t1 / n; f = (tf - t1) / (nf - 1); g = (of - o1) / (nf - 1)
        printf "  %-46s %8.2f ms = %.2f steps of %.2f ms\n", "a frame, by the loop times", 1000 * f,
            f / step, 1000 * step
        printf "  %-46s %8.2f ms = %.2f steps\n", "a frame, by the output rows (--timing)", 1000 * g,
            g / step
        printf "  %-46s %8.1f MB\n", "the run file", fs / 1e6
        bf = (fs - f1) / (nf - 1); rate = pc > 0 ? pcmb * 1048576 / pc : 0
        printf "  %-46s %8.2f MB\n", "bytes a frame adds to the run file", bf / 1e6
        if (rate > 0)
            printf "  %-46s %8.0f MB/s: %.2f ms a frame = %.2f steps\n",
                "new page-cache pages (dd, after 15 s idle)", rate / 1e6, 1000 * bf / rate,
                bf / rate / step
        printf "  %-46s %8.3f s\n", "pd-damage RUN.h5 (in place: read, not copied)", di
        printf "  %-46s %8.3f s\n", "pd-damage RUN.h5 -o OUT.h5", dc }'
fi
if ! skip shattered; then
    echo
    lmp='lmp-shattered'
    skip lammps && lmp=
    versus "shattered: the whole demo, 2000 steps, the disk shattered (pd: a frame every 100 steps; LAMMPS: in.impact, its dump every 100):" shattered "$lmp" 2000
    sed -n 's/^pd-run: .*contact list builds \([0-9]*\)$/  pd-run contact list builds: \1/p' shattered.log
fi
if ! skip mesh; then
    echo
    read -r _ r3 <<EOF
$(pd_loop full.log)
EOF
    read -r tm rmesh <<EOF
$(pd_loop mesh.log)
EOF
    nm=$(body mesh.log)
    read -r a _ <mesh-pd-mesh.time
    read -r b _ <mesh-pd-bonds.time
    read -r fin _ <fill-inside.time
    read -r fcy _ <fill-cylinder.time
    tri=$(sed -n "s/^pd-lattice: mesh .*: a closed surface of \([0-9]*\) triangles.*/\1/p" fill.log)
    nfill=$(sed -n 's/^pd-lattice: \([0-9]*\) particles.*/\1/p' fill.log)
    echo "mesh: the seed disk in gmsh's tetrahedra ($nm), the full scene of (a)"
    awk -v a="$a" -v b="$b" -v t="$tm" -v r="$rmesh" -v r3="$r3" -v n="$STEPS" 'BEGIN {
        printf "  pd-mesh %.2f s, pd-bonds %.2f s\n", a, b
        printf "  %.2f ms/step, %.3g bond updates/s: %.0f%% of the lattice seed'"'"'s %.3g (a)\n",
            1000 * t / n, r, 100 * r / r3, r3 }'
    awk -v fin="$fin" -v fcy="$fcy" -v tri="$tri" -v n="$nfill" 'BEGIN {
        printf "  fill: pd-lattice --inside the disk'"'"'s %s triangles at 0.14 mm (%s particles, 1.0e7 sites)\n", tri, n
        printf "        %.2f s, against %.2f s for --cylinder (the whole program, the better of two)\n", fin, fcy }'
fi
if ! skip perturbed; then
    echo
    lmp=lmp-perturbed
    skip lammps && lmp=
    versus "perturbed: the seed disk with its sites moved by up to $PERTURB m ($(body perturbed.log); the bond list; LAMMPS peri/pmb on the same particles):" perturbed "$lmp"
    sed -n 's/^pd-run: \(bonds walked as a bond list.*\)$/  pd-run: \1/p' perturbed.log
fi
echo
echo "(runs and logs in $DIR; the models are kept there for the next run)"
