/*
 * pd-bonds -- build the bond families within the horizon.
 *
 * Family of i: every j with |x_j - x_i| <= delta (seed 000 eq. 11), found
 * on the lattice's sites, or with cell lists of edge delta off a lattice
 * (linear in N either way, the same bonds).  Stored as CSR with reference
 * lengths, partial-volume factors (seed 000, "Modification to the Particle
 * Volume") and the bond state mu as one bit per bond.  Particles are first
 * sorted (pd_particles_sort_spatial: in lattice order on a lattice, else by
 * horizon-sized cells, row by row along the longest axis), so that families
 * sit close in memory; ids travel with them.
 *
 * Pre-cracks (--crack): every bond whose reference segment crosses a given
 * planar crack is created broken (mu = 0, seed 004) and marked in
 * /bonds/precrack; lib/bonds/crack.c holds the geometry and its conventions.
 *
 * A body whose families are a lattice stencil (the same offsets bonded at
 * every particle, found by pd_bonds_build_lattice) is written as the stencil: its
 * table of offsets and one state bit per bond, no per-bond arrays
 * (lib/bonds/stencil.c); --csr writes the lists anyway.
 */
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "pd.h"

#define PROG "pd-bonds"
#include "cli.h"
#define MAX_CRACKS 64

static int bonds_main(int argc, char **argv, const char *cmdline);

struct options {
    double horizon;
    int has_horizon;
    int no_sort;
    int csr;
    pd_crack cracks[MAX_CRACKS];
    const char *crack_specs[MAX_CRACKS];
    int ncracks;
    const char *input;
    const char *output;
    int quiet, debug;
};

static void usage(FILE *out)
{
    fprintf(out,
            "Usage: " PROG " --horizon DELTA [OPTION]... INPUT [-o FILE]\n"
            "Build bond families within the horizon (pd-h5 /bonds); INPUT '-' is stdin.\n"
            "\n"
            "Options:\n"
            "  --horizon DELTA   horizon, m (at least the spacing; give 3.0001 x spacing,\n"
            "                    not 3 x, so that pairs at exactly 3 spacings are bonded)\n"
            "  --no-sort         keep the particle order of INPUT\n"
            "  --csr             write the bond lists (CSR) even when the families are a\n"
            "                    lattice stencil (by default such a body gets the stencil)\n"
            "  --crack SPEC      pre-crack: make every bond that crosses the crack broken\n"
            "                    (and marked in /bonds/precrack); repeatable.  SPEC is\n"
            "                    rect,X,Y,Z,AX,AY,AZ,BX,BY,BZ  the parallelogram with\n"
            "                      corner X,Y,Z and edge vectors A and B, m; or\n"
            "                    segment,X1,Y1,X2,Y2  a segment in the x-y plane, m,\n"
            "                      through the whole thickness along z.\n"
            "                    An end of a bond exactly on the crack's plane counts on\n"
            "                    the side A x B points to (segment: (X2-X1,Y2-Y1,0) x z).\n"
            "  -o, --output FILE output file, '-' for stdout (default '-')\n"
            "  -q, --quiet       no summary on stderr\n"
            "      --debug       print HDF5's own error stack\n"
            "  -h, --help        show this help\n"
            "  -V, --version     show the version\n");
}

static int parse_options(int argc, char **argv, struct options *o)
{
    enum { OPT_HORIZON = 256, OPT_NOSORT, OPT_CRACK, OPT_CSR };
    static const struct option longopts[] = {
        {"horizon", required_argument, 0, OPT_HORIZON},
        {"no-sort", no_argument, 0, OPT_NOSORT},
        {"csr", no_argument, 0, OPT_CSR},
        {"crack", required_argument, 0, OPT_CRACK},
        {"output", required_argument, 0, 'o'},
        {"quiet", no_argument, 0, 'q'},
        COMMON_LONGOPTS,
        {0, 0, 0, 0}};
    memset(o, 0, sizeof *o);
    o->output = "-";
    int c, status = 0;
    while ((c = next_option(argc, argv, "o:qhV", longopts, usage, &o->debug, &status)) != -1) {
        switch (c) {
        case OPT_HORIZON:
            if (!pd_parse_double(optarg, &o->horizon) || !(o->horizon > 0))
                return usage_error("--horizon must be a positive number, not", optarg);
            o->has_horizon = 1;
            break;
        case OPT_NOSORT:
            o->no_sort = 1;
            break;
        case OPT_CSR:
            o->csr = 1;
            break;
        case OPT_CRACK:
            if (o->ncracks == MAX_CRACKS)
                return usage_error("too many --crack options", NULL);
            if (pd_crack_parse(optarg, &o->cracks[o->ncracks]) != PD_OK)
                return usage_error(pd_errmsg(), NULL);
            o->crack_specs[o->ncracks++] = optarg;
            break;
        case 'o':
            o->output = optarg;
            break;
        case 'q':
            o->quiet = 1;
            break;
        default:
            return option_error(argv, longopts);
        }
    }
    if (status)
        return status;
    if (!o->has_horizon)
        return usage_error("--horizon is required", NULL);
    if (optind != argc - 1)
        return usage_error(optind < argc ? "give exactly one INPUT" : "missing INPUT (a file or '-')",
                           NULL);
    o->input = argv[optind];
    return 0;
}

/* The families of the sorted body: a lattice's stencil (or its lists) as
 * one rank makes them on every rank; otherwise, on MPI ranks, each rank
 * the families of its share of the rows [*lo, *hi) (pd_bonds_build_rows),
 * pre-cracked; on one rank all of them. */
static pd_status families(const struct options *o, const pd_particles *p, pd_bonds **b,
                          int64_t *lo, int64_t *hi, int64_t *cut)
{
    const int64_t P = pd_comm_size(), r = pd_comm_rank();
    *lo = 0;
    *hi = p->n;
    /* on a lattice whose families are a stencil, the file needs only that
     * (unless the lists are asked for, or pre-cracks cut them) */
    pd_status s = pd_bonds_build_lattice(p, o->horizon, o->csr || o->ncracks > 0, b);
    if (s == PD_OK && *b == NULL && P == 1)
        s = pd_bonds_build(p, o->horizon, b);
    else if (s == PD_OK && *b == NULL) { /* rows in equal shares, in order */
        *lo = p->n * r / P;
        *hi = p->n * (r + 1) / P;
        s = pd_bonds_build_rows(p, o->horizon, *lo, *hi, b);
    }
    if (s == PD_OK && o->ncracks > 0 && (*lo > 0 || *hi < p->n)) /* a part */
        s = pd_bonds_precrack_rows(p, *b, o->cracks, o->ncracks, *lo, *hi, cut);
    else if (s == PD_OK && o->ncracks > 0)
        s = pd_bonds_precrack(p, *b, o->cracks, o->ncracks, cut);
    if (s == PD_OK && o->csr) { /* the lists, though the families are a stencil */
        pd_stencil_free((*b)->stencil);
        (*b)->stencil = NULL;
    }
    return s;
}

/* The model file: every MPI rank writes it, its own rows' bonds. */
static pd_status write_output(const struct options *o, pd_file *in, const char *cmdline,
                              const pd_particles *p, const pd_bonds *b, const pd_sets *sets,
                              int64_t lo, int64_t hi)
{
    pd_file *out = NULL;
    pd_status s = pd_file_create_ranks(o->output, &out);
    if (s == PD_OK && lo == 0 && hi == p->n)
        s = pd_write_model(out, in, cmdline ? cmdline : PROG, p, b, sets);
    else if (s == PD_OK) { /* a part of the bond lists */
        const int64_t klo = b->offset[lo], bonds = b->offset[hi] - klo;
        const pd_part pt = {lo, lo, hi - lo, p->n, klo, pd_comm_below(bonds), bonds,
                            pd_comm_total(bonds)};
        if ((s = pd_write_header(out, in, cmdline ? cmdline : PROG)) == PD_OK &&
            (s = pd_write_particles(out, p)) == PD_OK &&
            (s = pd_write_bonds_part(out, &pt, b)) == PD_OK)
            s = pd_write_sets(out, sets);
    }
    s = cli_agreed(s);
    if (s == PD_OK)
        return cli_agreed(pd_file_close(out));
    pd_file_abort(out);
    return s;
}

int main(int argc, char **argv)
{
    /* before getopt_long permutes argv */
    char *cmdline = pd_join_argv(argc, argv);
    if (cli_ranks_start(&argc, &argv) != 0) {
        free(cmdline);
        return 1;
    }
    int rc = bonds_main(argc, argv, cmdline);
    free(cmdline);
    return cli_ranks_end(rc);
}

static int bonds_main(int argc, char **argv, const char *cmdline)
{
    struct options o;
    int rc = parse_options(argc, argv, &o);
    if (rc == 0)
        rc = cli_ranks_files(o.input, "the input", o.output, "the output");
    if (rc)
        return rc;
    pd_h5_debug(o.debug);
    remove_temps_on_signal();

    pd_file *in = NULL;
    pd_particles *p = NULL;
    pd_status s = pd_file_open(o.input, &in);
    if (s == PD_OK)
        s = pd_read_particles(in, &p);
    if (cli_agreed(s) != PD_OK) {
        pd_file_close(in);
        return cli_failed();
    }
    if (o.horizon < p->spacing) { /* the same on every rank */
        fprintf(stderr, PROG ": error: horizon %g m is below the lattice spacing %g m\n",
                o.horizon, p->spacing);
        pd_particles_free(p);
        pd_file_close(in);
        return 1;
    }
    pd_bonds *b = NULL;
    pd_sets *sets = NULL; /* carried through: by id, they survive the sort */
    s = pd_read_sets(in, p, &sets);
    if (s == PD_OK && !o.no_sort)
        s = pd_particles_sort_spatial(p, o.horizon);
    int64_t cut[MAX_CRACKS], lo = 0, hi = 0;
    if (s == PD_OK)
        s = families(&o, p, &b, &lo, &hi, cut);
    s = cli_agreed(s);
    if (s == PD_OK)
        s = write_output(&o, in, cmdline, p, b, sets, lo, hi);
    pd_file_close(in);
    /* the families' sizes and the pre-cracks' pairs, over the ranks */
    const int part = s == PD_OK && (lo > 0 || hi < p->n);
    int64_t least = INT64_MAX, most = 0;
    for (int64_t i = lo; s == PD_OK && i < hi; i++) {
        int64_t m = b->offset[i + 1] - b->offset[i];
        least = m < least ? m : least;
        most = m > most ? m : most;
    }
    const int64_t count = part ? pd_comm_total(b->count) : b ? b->count : 0;
    if (part) {
        least = pd_comm_min(least);
        most = -pd_comm_min(-most);
        for (int c = 0; c < o.ncracks; c++)
            cut[c] = pd_comm_total(cut[c]);
    }
    if (s == PD_OK && !o.quiet) {
        fprintf(stderr, PROG ": %lld particles, %lld bonds (%.2f per particle, %lld to %lld)\n",
                (long long)p->n, (long long)(count / 2), (double)count / (double)p->n,
                (long long)least, (long long)most);
        if (b->stencil)
            fprintf(stderr, PROG ": stored as a lattice stencil of %d offsets\n",
                    b->stencil->nk);
        if (part)
            fprintf(stderr, PROG ": families built by %d MPI ranks, each writing its rows' "
                                 "(parallel HDF5)\n",
                    pd_comm_size());
        for (int c = 0; c < o.ncracks; c++)
            fprintf(stderr, PROG ": --crack %s: %lld bonds broken\n", o.crack_specs[c],
                    (long long)cut[c]);
    }
    pd_sets_free(sets);
    pd_bonds_free(b);
    pd_particles_free(p);
    return s == PD_OK ? 0 : cli_failed();
}
