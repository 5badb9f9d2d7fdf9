/*
 * pd.h -- the one public header of libpd, the peridynamics core of the pd
 * toolkit.
 *
 * Units are SI throughout (m, kg, s, Pa, J).  Every function returns a
 * pd_status; on failure it leaves a one-line message that pd_errmsg() returns
 * and the caller prints.  The library never prints and never exits.
 *
 * Data are structures of arrays.  Particles carry a stable global id (1-based,
 * /particles/id) apart from their local row index, so that a later domain
 * decomposition can renumber rows without touching ids.
 */
#ifndef PD_H
#define PD_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#define PD_VERSION "0.1.0"
#define PD_FORMAT "pd-h5"
#define PD_FORMAT_VERSION 2 /* files of version 1 (no stencil form) still read */

/* ---------------------------------------------------------------- status */

typedef enum {
    PD_OK = 0,
    PD_ERR_IO,       /* cannot open, read or write a file */
    PD_ERR_FORMAT,   /* a file is not a pd-h5 file of the expected shape */
    PD_ERR_INVALID,  /* a parameter is out of its domain */
    PD_ERR_NOMEM,    /* an allocation failed or would be absurdly large */
    PD_ERR_UNSTABLE  /* a run produced NaN/Inf or exceeded a stability limit */
} pd_status;

/* The message of the last failure in this thread. */
const char *pd_errmsg(void);
/* Set the message (printf-style); returns `st` so one can `return
 * pd_fail(PD_ERR_IO, "...")`. */
pd_status pd_fail(pd_status st, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

/* Switch HDF5's own error printing on (debug) or off (default).  Call it
 * before any other pd function that touches files. */
void pd_h5_debug(int on);

/* ------------------------------------------------------ physics constants */

/* Every constant of the seeds lives here, with its source. */
#define PD_CONTACT_SCALE 15.0      /* c_S = 15 c (seed 000 eq. 14)              */
#define PD_CONTACT_REF_FRAC 0.9    /* d_ij <= 0.9 |x_i - x_j| (seed 000 eq. 15) */
#define PD_CONTACT_RADIUS_FAC 1.35 /* d_ij <= 1.35 (r_i + r_j) (seed 000 eq. 15)*/
#define PD_NEAR_ZERO 2.2204e-16    /* |dr| below this is 0 (seed 000, "A
                                      Numerical Example": eps_machine, as in
                                      LAMMPS)                                  */
#define PD_PMB_C_FACTOR 18.0       /* c = 18 K / (pi delta^4) (seed 000 eq. 6)  */
#define PD_PMB_C_FACTOR_2D 12.0    /* c = 12 K / (pi H delta^3), 2-D plane
                                      stress, K = E / (2 (1 - nu)) the 2-D
                                      bulk modulus: 9 E / (pi H delta^3) (Ha &
                                      Bobaru 2010; derivation in pd-run(1))   */
#define PD_PMB_NU_3D 0.25          /* PMB's Poisson ratio in 3-D (seed 000)     */
#define PD_PMB_NU_2D (1.0 / 3.0)   /* PMB's Poisson ratio in 2-D (seed 000)     */
#define PD_LPS_SHEAR_FACTOR 15.0   /* alpha = 15 G / m (seed 000 eq. 3)         */
#define PD_LPS_DILATATION 3.0      /* theta_i = (3 / m_i) sum_j omega |xi| e
                                      nu V_j (seed 000 Algorithm 4)            */
/* The factor (3K - 5G) of LPS's pair force t_ij, Pa (seed 000 Algorithm
 * 2), K the bulk and G the shear modulus: (3 K) - (5 G), in that order. */
#define PD_LPS_PAIR_FACTOR(K, G) ((3.0 * (K)) - (5.0 * (G)))
#define PD_DAMAGE_THRESHOLD 0.3    /* phi_0: a particle with damage above it
                                      is on the crack (seed 004, crack growth
                                      of Fig. 7: phi_0 = 0.3)                  */

/* Numerical guards of a run (not from the seeds: pd's own choices). */
#define PD_LOST_MARGIN_FAC 10.0 /* lost beyond 10 box edges outside the body */
#define PD_KE_GROWTH 100.0      /* kinetic energy above 100 times the energy
                                   put in: a runaway (unstable) run        */
#define PD_BALANCE_LIMIT 1.0    /* the energy alarm: the balance drifted from
                                   step 0 by more than the energy put in
                                   (pd-run --balance-limit; the evidence is
                                   in pd-run(1), ENERGY ALARM)              */
#define PD_PENALTY_STRAIN 1e-6  /* penalty energy at step 0 below that of a
                                   uniform strain of 1e-6 of the whole body
                                   is negligible (pd_sim_start_penalty)     */
#define PD_BALANCE_EVERY 8      /* steps between the alarm's cheap test of
                                   the kinetic energy (pd_sim_step)         */
#define PD_RELAX_TOLERANCE 1e-4 /* a load step of --relax is relaxed when the
                                   residual force is below 1e-4 of the load */
#define PD_RELAX_ITERATIONS 1000000 /* and gives up after this many
                                   iterations                               */

/* ---------------------------------------------------------------- particles */

typedef struct {
    int64_t n;         /* number of particles                              */
    double *x[3];      /* reference positions, m (x[d][i])                 */
    double *volume;    /* particle volume V_i, m^3                         */
    double *density;   /* mass density rho_i, kg/m^3                       */
    double *radius;    /* node radius r_i (half the spacing), m            */
    int32_t *material; /* material id                                      */
    int64_t *id;       /* global id, 1-based, stable across files          */
    double spacing;    /* lattice spacing Delta x, m                       */
    int dimension;     /* 3, or 2 for a plate: sites in the plane z = 0    */
    double thickness;  /* plate thickness H, m (dimension 2; 0 in 3-D):
                          volumes are spacing^2 H                          */
    /* A window of a body spread over MPI ranks (pd_read_body_ranks): rows
     * [first, first + n) of the body's `total`, of which this rank owns
     * [own_lo, own_hi) (local indices).  Its whole-body figures
     * (pd_body_bounds, ...) are taken over the ranks: collective.  A
     * whole body: window 0 (and the rest 0, n, 0, n). */
    int window;
    int64_t first, total, own_lo, own_hi;
} pd_particles;

pd_particles *pd_particles_new(int64_t n);
void pd_particles_free(pd_particles *p);
/* The bounding box of the reference positions (+inf, -inf when empty). */
void pd_particles_bounds(const pd_particles *p, double lo[3], double hi[3]);
/* The same of the whole body p is (a window: over the ranks, collective). */
void pd_body_bounds(const pd_particles *p, double lo[3], double hi[3]);
/* The whole body's count of particles (a window's total). */
int64_t pd_body_count(const pd_particles *p);
/* The largest of v over the ranks whose windows make the body (v itself
 * for a whole body; collective for a window). */
double pd_body_max(const pd_particles *p, double v);

/* ---------------------------------------------------------------- regions */

typedef enum {
    PD_REGION_BOX,
    PD_REGION_CYLINDER,
    PD_REGION_SPHERE,
    PD_REGION_SURFACE
} pd_region_kind;

/* A closed triangulated surface (surface.c; pd-lattice --inside): points
 * (np,3) and triangles (nt,3) of point indices, copied.  Refused unless
 * every edge is in exactly two triangles, once each way (closed, manifold,
 * oriented alike; either way round).  Inside means a winding number about
 * the point that is not zero, decided exactly on the points snapped to
 * 2^-30 of the surface's extent; a point on a facet is inside. */
typedef struct pd_surface pd_surface;
pd_status pd_surface_new(int64_t np, const double *points, int64_t nt, const int64_t *tri,
                         pd_surface **out);
void pd_surface_free(pd_surface *s);
int pd_surface_inside(const pd_surface *s, const double x[3]);
void pd_surface_bounds(const pd_surface *s, double lo[3], double hi[3]);
int64_t pd_surface_triangles(const pd_surface *s);
/* The enclosed volume, m^3: positive when the triangles turn outward. */
double pd_surface_volume(const pd_surface *s);

typedef struct {
    pd_region_kind kind;
    int axis;        /* cylinder: 0,1,2 for x,y,z                              */
    double p[6];     /* box: xlo,xhi,ylo,yhi,zlo,zhi
                        cylinder: c1,c2,R,lo,hi (LAMMPS region cylinder: c1,c2
                        are the axis coordinates in the other two dimensions,
                        in x,y,z order)
                        sphere: x,y,z,R                                       */
    int subtract;    /* 1: cut this region out of the union                  */
    const pd_surface *surface; /* PD_REGION_SURFACE: the surface (not owned) */
} pd_region;

/* Parse "XLO,XHI,..." style specs.  kind_spec is e.g. "box" and spec the
 * comma list; for --subtract the spec is "box,..." etc. */
pd_status pd_region_parse(pd_region_kind kind, const char *spec, pd_region *out);
pd_status pd_region_parse_tagged(const char *spec, pd_region *out);
int pd_region_inside(const pd_region *r, const double x[3]);
/* Axis-aligned bounding box of a region. */
void pd_region_bounds(const pd_region *r, double lo[3], double hi[3]);

typedef struct {
    double spacing;     /* m, > 0                          */
    double density;     /* kg/m^3, > 0                     */
    int32_t material;   /* material id                     */
    double perturb;     /* amplitude of uniform perturbation, m (0 = none) */
    unsigned long seed; /* GSL mt19937 seed                */
    double origin[3];   /* the sites are (n + origin) spacing, per axis,
                           origin in [0, 1) (LAMMPS lattice ... origin;
                           0: anchored at 0); a plate's z is 0        */
} pd_lattice_params;

/* Simple cubic lattice sites n*spacing (anchored at the origin, LAMMPS
 * `lattice sc`) inside the union of the non-subtract regions and outside
 * every subtract region; z outermost, x innermost, as LAMMPS create_atoms. */
pd_status pd_lattice_make(const pd_region *regions, int nregions,
                          const pd_lattice_params *lp, pd_particles **out);
/* Does a plane face of region r (a box's faces, a cylinder's ends) lie
 * within PD_LATTICE_ROUNDING spacings h of a lattice plane n h without
 * being on it, so that whether that plane's sites are in is decided by
 * rounding (--box 0,0.0045,... at 0.0005: 9 x 0.0005 is
 * 0.0045000000000000005, beyond the face)?  Then 1 and one line of text
 * (`what` names the region, e.g. "--box") on the first such face. */
#define PD_LATTICE_ROUNDING 1e-6
int pd_region_rounding(const pd_region *r, double h, const double origin[3], const char *what,
                       char *text, size_t len);
/* A 2-D plate of thickness H (m, > 0): the square lattice of sites
 * (i spacing, j spacing, 0), anchored at the origin, where the point
 * (x, y, 0) is in the body (the regions are cut at z = 0; none there is an
 * error), y outermost and x innermost; volume spacing^2 H, radius
 * spacing/2, dimension 2 and thickness H, and a perturbation only in x and
 * y. */
pd_status pd_plate_make(const pd_region *regions, int nregions, const pd_lattice_params *lp,
                        double thickness, pd_particles **out);

/* ---------------------------------------------------------------- cells */

/* Cell list over a set of points: cells of edge >= `cutoff`. */
typedef struct {
    double lo[3];      /* lower corner, m                            */
    double size;       /* cell edge, m                               */
    int64_t dim[3];    /* cells per axis                             */
    int64_t *start;    /* ncell+1 offsets into `index`               */
    int32_t *index;    /* particle indices sorted by cell            */
    int64_t *full;     /* the cells that hold points, ascending      */
    int64_t nfull;     /* how many                                   */
    int64_t *cellof;   /* each point's cell (the build's scratch)    */
    int64_t start_room, index_room, cellof_room, full_room; /* what the
                          arrays hold, kept by pd_cells_rebuild_except */
} pd_cells;

pd_status pd_cells_build(pd_cells *c, int64_t n, double *const x[3], double cutoff);
/* The same without the points whose skip[i] is set (skip may be NULL). */
pd_status pd_cells_build_except(pd_cells *c, int64_t n, double *const x[3], double cutoff,
                                const uint8_t *skip);
/* pd_cells_build_except into the arrays of c, a cell list built before (or
 * zeroed), grown where they are too small: a list rebuilt every few steps
 * allocates nothing once it has room.  The same cells and order. */
pd_status pd_cells_rebuild_except(pd_cells *c, int64_t n, double *const x[3], double cutoff,
                                  const uint8_t *skip);
/* Frees the arrays and zeroes c (NULL: nothing). */
void pd_cells_free(pd_cells *c);
/* The grid alone (lo, size, dim; no particles) that pd_cells_build_except
 * lays over n particles whose bounding box is [lo, hi] (lo > hi: none). */
void pd_cells_geometry(pd_cells *c, const double lo[3], const double hi[3], int64_t n,
                       double cutoff);
/* Cell coordinates of a point (clamped into the grid). */
void pd_cells_locate(const pd_cells *c, const double x[3], int64_t cell[3]);
/* The cell of x and its neighbours inside the grid (up to 27), in z, y, x
 * order; returns how many. */
int pd_cells_adjacent(const pd_cells *c, const double x[3], int64_t cells[27]);
/* The same cells as runs of `index`: the neighbours along x of one (z, y)
 * row are consecutive cells, so their points are index[lo[r] .. hi[r]),
 * rows in z, y order (pd_cells_adjacent's points in its order); returns
 * how many rows (up to 9). */
int pd_cells_adjacent_rows(const pd_cells *c, const double x[3], int64_t lo[9], int64_t hi[9]);
/* The same rows as cells: row r is the `width` cells first[r] ..
 * first[r] + width - 1 (width the same for every row), at z, y offset
 * around[r] = 3 (dz + 1) + (dy + 1) from x's cell, its first cell at x
 * offset *dx0 (-1, or 0 at the grid's edge); returns how many rows. */
int pd_cells_adjacent_runs(const pd_cells *c, const double x[3], int64_t first[9], int *width,
                           int around[9], int *dx0);

/* ---------------------------------------------------------------- bonds */

typedef struct {
    int64_t n;          /* particles (rows)                                 */
    int64_t count;      /* directed bonds: each bond i-j is stored in the
                           families of i and of j                           */
    int64_t *offset;    /* n+1 CSR offsets                                  */
    int32_t *neighbor;  /* count: local row of the partner                  */
    double *length;     /* count: reference length |xi|, m                  */
    double *vfactor;    /* count: partial-volume factor nu in [1/2, 1]      */
    uint64_t *intact;   /* ceil(count/64) words: bit b = mu of bond b       */
    uint64_t *precrack; /* NULL, or ceil(count/64) words packed as intact:
                           bit b set = bond b was made broken before the run
                           by a pre-crack (pd_bonds_precrack)               */
    double horizon;     /* delta, m                                         */
    struct pd_stencil *stencil; /* NULL, or the lattice stencil these families
                           are, bit for bit (pd_bonds_build_lattice,
                           pd_bonds_find_stencil): files then store the
                           stencil instead of the lists                 */
    struct pd_bond_sites *sites; /* NULL, or the stencil's site map when
                           the families are compact: neighbor, length
                           and vfactor NULL, each family walked off the
                           stencil (pd_family_start; pd_read_bonds_compact) */
} pd_bonds;

/* One family walked bond by bond, in the order of the directed bonds
 * (b->offset[i] on), on bond lists and on compact families alike:
 *
 *     pd_bond_iter it;
 *     for (pd_family_start(b, p, i, &it); pd_family_next(&it);)
 *         ... it.q, it.j, it.length, it.vfactor ...
 *
 * A compact family computes each bond's length and factor from the
 * particles as pd_bonds_expand does: the same bits as the lists.
 * pd_family_start_partners walks the partners alone (length and vfactor
 * not set). */
typedef struct {
    int64_t q;      /* the directed bond                                */
    int32_t j;      /* its partner                                      */
    double length;  /* reference length |xi|, m                         */
    double vfactor; /* partial-volume factor nu                         */
    /* the walk's own */
    const pd_bonds *b_;
    const pd_particles *p_;
    const int32_t *pad_;   /* a compact family's site map and steps */
    const int64_t *delta_;
    int64_t i_, end_, s_;
    int k_, nk_, geometry_;
} pd_bond_iter;
void pd_family_start(const pd_bonds *b, const pd_particles *p, int64_t i, pd_bond_iter *it);
void pd_family_start_partners(const pd_bonds *b, const pd_particles *p, int64_t i,
                              pd_bond_iter *it);
int pd_family_next_site(pd_bond_iter *it); /* pd_family_next's compact case */
static inline int pd_family_next(pd_bond_iter *it)
{
    if (++it->q >= it->end_)
        return 0;
    const pd_bonds *b = it->b_;
    if (b->neighbor == NULL) {
        if (it->geometry_)
            return pd_family_next_site(it);
        while (it->k_ < it->nk_) { /* the partners alone, here inline */
            const int32_t j = it->pad_[it->s_ + it->delta_[it->k_++]];
            if (j >= 0) {
                it->j = j;
                return 1;
            }
        }
        it->q = it->end_; /* cannot be: the offsets counted these bonds */
        return 0;
    }
    it->j = b->neighbor[it->q];
    if (it->geometry_) {
        it->length = b->length[it->q];
        it->vfactor = b->vfactor[it->q];
    }
    return 1;
}
/* A family as arrays, for loops the compiler vectorizes (the same loop
 * over the same values gives the same bits in either form): the lists'
 * own arrays, or a compact family's partners, lengths and factors written
 * into buf (zeroed before the first use, grown as needed, freed by
 * pd_family_buf_free).  pd_family_get returns 0, or -1 when out of
 * memory for buf. */
typedef struct {
    int64_t n;              /* bonds                              */
    int64_t first;          /* the first's directed index          */
    const int32_t *j;       /* n partners                          */
    const double *length;   /* n reference lengths, m              */
    const double *vfactor;  /* n partial-volume factors            */
} pd_family;
typedef struct {
    int64_t cap;
    int32_t *j;
    double *length, *vfactor;
} pd_family_buf;
int pd_family_get(const pd_bonds *b, const pd_particles *p, int64_t i, pd_family_buf *buf,
                  pd_family *f);
void pd_family_buf_free(pd_family_buf *buf);
/* The offsets of compact families, each with its first bond (the lowest
 * row that has one): d (x, y, z, spacings), that bond's length and
 * factor (NaN: no bond at d) and how far any bond's length at d can lie
 * from it, m (twice each end's distance from its site, and rounding).
 * Returns the number of offsets (b->stencil->nk), or -1 for lists. */
int pd_family_offsets(const pd_bonds *b, const pd_particles *p, int32_t (*d)[3], double *len,
                      double *nu, double *spread);
/* Of compact families: the first directed bond i->j with j < i (rows
 * ascending, then bonds) whose bit in `bits` differs from that of its
 * mirror j->i; -1 when there is none, -2 when out of memory, -3 for lists. */
int64_t pd_family_asymmetric(const pd_bonds *b, const uint64_t *bits);
/* The same over rows [lo, hi) of b alone, whose partners' families are
 * whole. */
int64_t pd_family_asymmetric_rows(const pd_bonds *b, const uint64_t *bits, int64_t lo, int64_t hi);
/* pd_family_offsets of a body spread over MPI ranks as windows of compact
 * families (collective): each rank walks its own rows of p, b
 * ([p->own_lo, p->own_hi), whose families are whole); the offsets in the
 * table's order (b->stencil), the whole body's figures on every rank.
 * Returns the number of offsets, or -1 (on every rank) when a rank's b is
 * not compact, an array is NULL or memory ran out. */
int pd_family_offsets_ranks(const pd_bonds *b, const pd_particles *p, int32_t (*d)[3],
                            double *len, double *nu, double *spread);
/* Does b hold its families as lists (1), or compact (0)? */
static inline int pd_bonds_has_lists(const pd_bonds *b)
{
    return b->neighbor != NULL;
}

/* A body's families as a lattice stencil (lib/bonds/stencil.c): particle i
 * sits at the site c_i = round((x_i - origin) / spacing) (to
 * PD_LATTICE_TOL spacings), and its family is every particle j at a site
 * c_i + d over the offsets d of the table, sorted by j as the lists are.
 * Each bond's length |x_i - x_j| and partial-volume factor
 * (pd_partial_volume) come from the particles, so the families expand to
 * the very bits pd_bonds_build gives. */
typedef struct pd_stencil {
    int nk;             /* offsets (d and -d both)                          */
    int32_t (*d)[3];    /* nk lattice offsets (x, y, z), spacings, sorted by
                           (z, y, x)                                        */
    double *length;     /* nk: the reference length of the offset's first
                           bond (|d| spacing to rounding), m                */
    double *vfactor;    /* nk: its partial-volume factor                    */
    double origin[3];   /* the site (0, 0, 0), m                            */
    double spacing;     /* m                                                */
} pd_stencil;

pd_bonds *pd_bonds_alloc(int64_t n, int64_t count);
void pd_bonds_free(pd_bonds *b);
/* Families within the horizon (linear in N): on a lattice by its sites
 * (pd_bonds_build_lattice, which also finds their stencil), otherwise by
 * cell lists; the same bonds either way. */
pd_status pd_bonds_build(const pd_particles *p, double horizon, pd_bonds **out);
/* The families of rows [lo, hi) alone, by cell lists, as pd_bonds_build
 * finds them (a part of the body for one MPI rank): a pd_bonds of all
 * p->n rows whose rows outside [lo, hi) have none. */
pd_status pd_bonds_build_rows(const pd_particles *p, double horizon, int64_t lo, int64_t hi,
                              pd_bonds **out);
/* The families of particles on their lattice (spacing p->spacing, origin
 * their lowest corner), walked over the offsets that can hold a pair
 * within the horizon: pd_bonds_build's bonds bit for bit, with b->stencil
 * set when every offset holds all of its pairs or none.  With lists 0 and
 * a stencil found, b holds only the offsets, the state bits and the
 * stencil (neighbor, length and vfactor NULL): enough to write a model
 * file (pd-bonds), whose readers expand it.  *out stays NULL when the
 * particles are off a lattice, sparse on it (PD_STENCIL_SPARSE), share a
 * site, or the horizon reaches beyond PD_STENCIL_REACH spacings. */
pd_status pd_bonds_build_lattice(const pd_particles *p, double horizon, int lists,
                                 pd_bonds **out);
/* The partial-volume factor nu of a bond of length len to a node of radius
 * r (seed 000, "Modification to the Particle Volume"): 1 for len <=
 * horizon - r, (horizon + r - len) / (2 r) beyond. */
double pd_partial_volume(double len, double horizon, double r);
/* Are b's families a lattice stencil?  Sets b->stencil when they expand
 * from one to exactly their bits (offsets, partners, lengths, volume
 * factors); leaves it NULL when the particles are off a lattice, the body
 * is too sparse for a site map (more than PD_STENCIL_SPARSE sites of its
 * bounding box per particle), an offset reaches beyond PD_STENCIL_REACH
 * spacings or a family differs from the stencil's. */
pd_status pd_bonds_find_stencil(const pd_particles *p, pd_bonds *b);
/* The families of a stencil (all intact, no pre-crack; out->stencil is a
 * copy of st).  PD_ERR_FORMAT when a particle is off st's lattice, two
 * share a site, or the body is too sparse for the site map. */
pd_status pd_bonds_expand(const pd_particles *p, const pd_stencil *st, double horizon,
                          pd_bonds **out);
/* The families of a stencil kept compact: offsets, all intact, no
 * pre-crack, the site map (out->sites) and a copy of st, no lists.  When
 * the particles are not in a lattice order (the families would need a
 * sort), the lists instead, as pd_bonds_expand.  Its errors are
 * pd_bonds_expand's. */
pd_status pd_bonds_compact(const pd_particles *p, const pd_stencil *st, double horizon,
                           pd_bonds **out);
/* A copy of b with its families as lists (b compact or not): the state
 * and pre-crack bits b has. */
pd_status pd_bonds_with_lists(const pd_particles *p, const pd_bonds *b, pd_bonds **out);
void pd_bond_sites_free(struct pd_bond_sites *s);
/* An empty stencil of nk offsets (NULL: out of memory); and its release. */
pd_stencil *pd_stencil_alloc(int nk);
void pd_stencil_free(pd_stencil *st);
#define PD_STENCIL_REACH 16 /* spacings: offsets' components at most   */
#define PD_STENCIL_SPARSE 8 /* bounding-box sites per particle at most */

static inline int pd_bond_intact(const uint64_t *bits, int64_t b)
{
    return (int)((__atomic_load_n(&bits[b >> 6], __ATOMIC_RELAXED) >> (b & 63)) & 1u);
}
static inline void pd_bond_break(uint64_t *bits, int64_t b)
{
    __atomic_fetch_and(&bits[b >> 6], ~(UINT64_C(1) << (b & 63)), __ATOMIC_RELAXED);
}
int64_t pd_bits_words(int64_t count);
/* Number of cleared bits among the first `count`. */
int64_t pd_bits_count_broken(const uint64_t *bits, int64_t count);

/* Damage (seed 000 eq. 10, as LAMMPS compute damage/atom): 1 - sum of V_j
 * over intact bonds / sum of V_j over the reference family; 0 for a particle
 * without family.  Pre-cracked bonds are broken bonds like any other. */
void pd_damage(const pd_particles *p, const pd_bonds *b, const uint64_t *intact,
               double *damage);
/* Damage without the pre-crack: the same ratio with the pre-cracked bonds
 * (b->precrack) left out of both sums,
 *   phi_i = 1 - sum_{j intact, not pre-cracked} V_j
 *             / sum_{j in family, not pre-cracked} V_j,
 * so that it shows only what broke during the run; 0 for a particle whose
 * bonds are all pre-cracked.  Equals pd_damage when b->precrack is NULL. */
void pd_damage_no_precrack(const pd_particles *p, const pd_bonds *b, const uint64_t *intact,
                           double *damage);
/* Fragments: the pieces the intact bonds hold together, the connected
 * components of the bond graph (a particle without intact bond is a piece
 * of its own).  *pieces their number, *largest the volume of the largest,
 * m^3. */
pd_status pd_fragments(const pd_particles *p, const pd_bonds *b, const uint64_t *intact,
                       int64_t *pieces, double *largest);
/* Number of cleared bits of `bits` among the first `count` whose bit in
 * `skip` is clear (skip NULL: all of them), e.g. bonds broken during a run
 * but not pre-cracked. */
int64_t pd_bits_count_broken_except(const uint64_t *bits, const uint64_t *skip, int64_t count);

/* A planar pre-crack (lib/bonds/crack.c): the closed parallelogram
 *   C = { P + u A + v B : u, v in [0, 1] },  normal n = A x B,
 * or, with `through`, a segment in the x-y plane from (P_x, P_y) to
 * (P_x + A_x, P_y + A_y) extended through the whole thickness along z: when
 * applied it becomes the parallelogram with edges A and (0, 0, height) that
 * spans the particles' z range and a horizon more on each side.
 * The reference segment x_i -> x_j of a bond crosses C when its endpoints
 * are on different sides of the plane, with s(x) = n . (x - P) >= 0 the
 * positive side (a point exactly on the plane counts on the side n points
 * to), and the segment meets the plane at a point of C.  The test is
 * exactly symmetric in i and j. */
typedef struct {
    double p[3];  /* corner P, m                                             */
    double a[3];  /* edge vector A, m                                        */
    double b[3];  /* edge vector B, m (unused with `through`)                */
    int through;  /* 1: segment through the thickness along z (see above)    */
} pd_crack;

/* Parse "rect,X,Y,Z,AX,AY,AZ,BX,BY,BZ" (corner and two edge vectors, m) or
 * "segment,X1,Y1,X2,Y2" (m); a degenerate crack (pd_crack_check) is
 * PD_ERR_INVALID. */
pd_status pd_crack_parse(const char *spec, pd_crack *out);
/* PD_ERR_INVALID for a zero-length edge, parallel edges (|A x B| below
 * 1e-9 |A| |B|) or a segment of zero length; `spec` (may be NULL) names the
 * crack in the message. */
pd_status pd_crack_check(const pd_crack *c, const char *spec);
/* Does the segment x -> y cross the crack (rules above)?  A `through`
 * crack must first be made a parallelogram: only pd_bonds_precrack does
 * that, this test takes c as it is. */
int pd_crack_crosses(const pd_crack *c, const double x[3], const double y[3]);
/* Pre-crack built bonds: every bond whose reference segment crosses one of
 * the cracks is broken on both directed copies (intact bit cleared) and
 * marked in b->precrack (allocated when some bond crosses; stays NULL when
 * none does).  counts[c] (counts may be NULL) gets the number of bonds
 * (pairs) crack c crosses; a bond crossing two cracks counts for both.
 * Families must be symmetric and sorted, as built; on failure b may be
 * partly cracked and is to be discarded. */
pd_status pd_bonds_precrack(const pd_particles *p, pd_bonds *b, const pd_crack *cracks,
                            int ncracks, int64_t *counts);
/* The same for the families of rows [lo, hi) alone (pd_bonds_build_rows):
 * each bond from its own row, a pair decided as pd_bonds_precrack decides
 * it; counts[c] are the pairs whose lower row is in [lo, hi), and
 * b->precrack is kept even when none of these is cut. */
pd_status pd_bonds_precrack_rows(const pd_particles *p, pd_bonds *b, const pd_crack *cracks,
                                 int ncracks, int64_t lo, int64_t hi, int64_t *counts);

/* Reorder particles so that families are close in memory and every bond
 * joins rows a bounded distance apart (the run's kernels cut rows into
 * blocks of that distance): on a lattice, in lattice order
 * (pd_lattice_order, what pd-run's stencil kernel walks), otherwise by
 * horizon-sized cells, row by row with the longest axis outermost.  Ids
 * travel with the particles. */
pd_status pd_particles_sort_spatial(pd_particles *p, double cell);

/* Are the particles on the lattice of their spacing (every site within
 * 1e-6 spacing of lo + spacing c, c integer)?  Then axis[] gets the axes in
 * the order inner (the longest extent), mid (the shortest), outer, and
 * lc[a][i] (when lc is not NULL) particle i's coordinate along axis[a].
 * Returns 1 or 0. */
int pd_lattice_coords(const pd_particles *p, int axis[3], int32_t *lc[3]);
/* Every particle's site round((x_i - origin) / h) along x, y, z into
 * c[d][i] (c may be NULL): 1, or 0 when a particle is farther than
 * PD_LATTICE_TOL spacings from its site. */
int pd_lattice_sites(const pd_particles *p, const double origin[3], double h, int32_t *c[3]);
/* Lattice order: sorted by (outer, mid, inner) coordinate.  *order gets
 * the old index of each new position (malloc'd), or NULL when the
 * particles are not on a lattice. */
pd_status pd_lattice_order(const pd_particles *p, int64_t **order);
/* The lattice order of n particles from their coordinates lc (as
 * pd_lattice_coords gives them): the old index of each new position
 * (malloc'd), or NULL when out of memory. */
int64_t *pd_lattice_sort(int64_t n, int32_t *const lc[3]);
/* The first row of each of nb blocks of `thick` outer planes from plane lo
 * (start[nb]: every row), were the rows in lattice order: the rows
 * [i0, i1) of outer coordinates `outer` counted under each block, the
 * counts summed over the MPI ranks (collective); start has nb + 1. */
void pd_lattice_block_starts(const int32_t *outer, int64_t i0, int64_t i1, int64_t lo, int thick,
                             int64_t nb, int64_t *start);
/* A site within PD_LATTICE_TOL spacings of the lattice is on it. */
#define PD_LATTICE_TOL 1e-6

/* ---------------------------------------------------------------- scene */

typedef enum { PD_MODEL_PMB = 0, PD_MODEL_LPS, PD_MODEL_VES, PD_MODEL_EPS } pd_model_kind;

/* The material models (lib/models/): one descriptor each, found by name or
 * by kind (NULL: none such). */
typedef struct pd_model pd_model;
const pd_model *pd_model_by_name(const char *name);
const pd_model *pd_model_of(pd_model_kind kind);
/* The k-th model of the table (NULL past the last). */
const pd_model *pd_model_at(int k);
const char *pd_model_name(const pd_model *m);
pd_model_kind pd_model_kind_of(const pd_model *m);
/* Does it take K, G and an influence function (LPS and its viscoelastic
 * and elastic-plastic variants VES and EPS, lib/models/lps.c), 3-D only? */
int pd_model_state_based(const pd_model *m);
/* The doubles per directed bond its restart data keep (0: none). */
int pd_model_history_width(const pd_model *m);

/* Influence functions omega(|xi|) of the LPS model (seed 000 eq. 4). */
typedef enum {
    PD_INFLUENCE_INV_R = 0, /* 1/|xi| (LAMMPS peri/lps, the default)       */
    PD_INFLUENCE_ONE,       /* 1                                           */
    PD_INFLUENCE_GAUSSIAN   /* exp(-|xi|^2/delta^2)                        */
} pd_influence;

/* An ellipsoid of the anisotropic influence function (seed 002, lib/
 * influence.c): major semi-axis 1 along the preferred direction u, the
 * others a and b along v and w, rolled about u by `roll`. */
#define PD_ELLIPSOID_MAX 8 /* --ellipsoid at most this many times         */
#define PD_NO_FAILURE_MAX 8 /* --no-failure at most this many times      */
typedef struct {
    double u[3];    /* preferred direction as given (nonzero, any length) */
    double a, b;    /* semi-axis ratios along v and w, in (0, 1]          */
    double roll;    /* rotation of v, w about u, rad                      */
    double rinv[9]; /* M^-1, row-major, M = M_Y M_P M_R (pd_ellipsoid_init) */
} pd_ellipsoid;

typedef struct {
    pd_model_kind model;
    double c;              /* PMB micromodulus, N/m^6                       */
    double bulk_modulus;   /* K, Pa (0 when c was given)                    */
    int has_failure;
    double s00;            /* critical stretch parameter s00               */
    double alpha;          /* s0 = s00 - alpha s_min (seed 000 eq. 9)       */
    int has_contact;
    int allow_overlap;     /* a projectile or indenter may start inside the
                              body (pd_scene_inspect; pd-run
                              --allow-overlap)                           */
    int bond_list;         /* walk the bond list even on a lattice (pd-run
                              --bond-list; lib/stencil/grid.c)                     */
    double contact_skin;   /* m                                            */
    int has_indenter;
    double ind_center[3];  /* centre at t = 0, m                            */
    double ind_radius;     /* m                                            */
    double ind_k;          /* K of F = K (R - r)^2, force density per m^2   */
    double ind_velocity[3];/* m/s                                           */
    double dt;             /* s                                            */
    double dt_stable;      /* eq. 46 estimate, s                           */
    double safety;         /* dt = safety * dt_stable when dt not given     */
    int64_t steps;
    int64_t every;         /* frame every N steps; 0 = last step only      */
    int64_t series;        /* a row of the time series (/series) every N
                              steps and at the last; 0: no series (pd-run
                              --series, by default its status interval;
                              not a line of the scene's text)             */
    unsigned fields;       /* optional frame fields, PD_FIELD_* bits       */
    double lost_margin;    /* a particle farther than this outside the
                              reference bounding box is lost, m (0: ten
                              times the box's largest edge)              */
    double damping;        /* C of the viscous damping -C rho v, 1/s (0:
                              none; pd-run --damping, lib/effects/damping.c) */
    char damping_set[64];  /* its set (PD_SET_NAME_MAX), or "": every
                              particle                                  */
    double balance_limit;  /* the energy alarm's limit, a fraction of the
                              energy put in (pd_sim_check_balance; 0:
                              PD_BALANCE_LIMIT, negative: no alarm)      */
    int relax;             /* quasi-static: each step a load step at time
                              n dt, relaxed (pd_sim_relax; pd-run --relax) */
    double relax_tolerance;/* its residual over the load (0: the default,
                              PD_RELAX_TOLERANCE)                        */
    int64_t relax_iterations; /* at most per load step (0: the default,
                              PD_RELAX_ITERATIONS)                       */
    double relax_dt;       /* the step of its iterations, s: safety x the
                              stable step (pd_scene_resolve)             */
    int threads;
    double youngs_modulus; /* E, Pa (0 unless --youngs-modulus gave K)   */
    int nbc;                     /* boundary conditions (pd_bc), in order   */
    const struct pd_bc *bc;
    const struct pd_sets *sets;  /* the model's particle sets (may be NULL
                                    when nbc is 0)                         */
    double shear_modulus;  /* G, Pa (LPS)                                   */
    pd_influence influence;/* LPS influence function                       */
    int has_projectile;    /* a rigid sphere moved by the contact force     */
    double proj_center[3]; /* its centre at t = 0, m                        */
    double proj_radius;    /* m                                             */
    double proj_mass;      /* kg                                            */
    double proj_velocity[3];/* at t = 0, m/s                                */
    double proj_k;         /* K of the force density K (R - r)^2, N/m^5 (0:
                              pd_projectile_default_k)                   */
    int nellipsoids;       /* anisotropic influence (state-based models);
                              0: isotropic                               */
    pd_ellipsoid ellipsoid[PD_ELLIPSOID_MAX];
    int nlaws;             /* PMB bond laws of materials and interfaces    */
    const struct pd_bond_law *laws; /* (lib/models/materials.c; may be NULL)     */
    int has_fibre;         /* seed 004 eq. 10 for the scene's own bonds    */
    double fibre_g[3];     /* fibre direction g (any length)               */
    double fibre_c[2];     /* c of the fibre and of the matrix, N/m^6      */
    double fibre_s00[2];   /* their s00 (0: the scene's s00)               */
    double ves_lambda;     /* VES: the viscous fraction lambda_i, 0..1     */
    double ves_tau;        /* VES: the relaxation time tau_i, s            */
    double yield_stress;   /* EPS: the yield stress Y, Pa                  */
    int nno_failure;       /* sets whose bonds never break (pd-run
                              --no-failure SET): a bond with an end in one
                              of them stays intact whatever its stretch   */
    char no_failure[PD_NO_FAILURE_MAX][64]; /* their names (PD_SET_NAME_MAX) */
} pd_scene;

/* A line on the model and the scene's constants of it for a run's log,
 * into text (len bytes); 0 when it has nothing to say. */
int pd_model_describe(const pd_model *m, const pd_scene *s, char *text, size_t len);

/* ---------------------------------------------------------------- run */

typedef struct pd_sim pd_sim;

/* Timers of the step (pd-run --timing). */
typedef enum {
    PD_T_BONDS, PD_T_CONTACT, PD_T_NEIGHBOR, PD_T_INDENTER, PD_T_INTEGRATE,
    PD_T_OUTPUT,
    PD_T_FAILURE, /* failure's bookkeeping outside the fused bond kernel */
    PD_T_RANKS,   /* on MPI ranks: the halo and the sums over the ranks */
    PD_T_COUNT
} pd_timer;

pd_status pd_sim_new(const pd_particles *p, const pd_bonds *b, const pd_scene *s,
                     pd_sim **out);
void pd_sim_free(pd_sim *sim);

/* ------------------------------------------------------- ranks (MPI) */

/* A run spread over MPI ranks (pd-run built with `make MPI=1`, started by
 * mpirun).  The body's blocks (the runs of rows its bond kernel cuts the
 * body into, each writing only to itself and the next: a rule of the body)
 * are shared out among the ranks, whole and in order.  Each rank steps a
 * piece: its own blocks, and as ghosts the block above them and the one
 * or two below (an even count of blocks below, so that each block keeps
 * its phase), whose bonds it walks again rather than receiving their
 * forces.  Every particle's force is then summed in the one rank's order:
 * the state is the same, bit for bit, on any number of ranks.  Before its
 * forces a step brings the ghosts' positions and s0 from their owners;
 * sums over the body (energies, the indenter's force, broken bonds'
 * energy) are taken in the one rank's order too.
 *
 * Without MPI there is one rank and these are the one-rank answers. */
int pd_comm_mpi(void);     /* 1: built with MPI                          */
pd_status pd_comm_init(int *argc, char ***argv); /* MPI_Init_thread, funneled */
void pd_comm_finalize(void);
int pd_comm_rank(void);
int pd_comm_size(void);
/* Abort every rank (MPI_Abort) when there are several; else nothing. */
void pd_comm_abort(int code);
/* The logical or, the smallest value, the largest and the sum over the
 * ranks (collective). */
int pd_comm_or(int v);
int64_t pd_comm_min(int64_t v);
double pd_comm_max(double v);
int64_t pd_comm_total(int64_t v);
/* The sum of v over the ranks below this one (0 on rank 0; collective). */
int64_t pd_comm_below(int64_t v);
/* s, or a failure of this rank too when another rank's s failed
 * (collective): every rank then leaves a collective step together.  The
 * failure said for another rank is marked as such: pd_comm_echo() is 1
 * after it (and 0 once asked), so that the rank that failed tells why. */
pd_status pd_comm_agree(pd_status s);
int pd_comm_echo(void);
/* Rank `from`'s failure (its status s and message) on every rank
 * (collective): returns it, and pd_errmsg() says it. */
pd_status pd_comm_error_from(int from, pd_status s);
/* Every rank waits for every other (collective). */
void pd_comm_barrier(void);

/* This rank's piece of a run: pd_sim_piece_new (below, with pd_restart).
 * The rows [*g0, *g1) of this rank's piece of a body of n rows walked as a
 * bond list whose bonds span at most `span` rows (the body's, over every
 * rank: pd_read_bonds_span), as pd_sim_piece_new cuts it: the rows whose
 * bonds it reads (pd_read_bonds_rows); [*o0, *o1) those it owns. */
pd_status pd_piece_rows(int64_t n, int64_t span, int64_t *g0, int64_t *g1, int64_t *o0,
                        int64_t *o1);
/* The same of a body on a lattice whose bonds are the table st, from each
 * rank's share of its rows (collective): the blocks of outer planes the
 * stencil would cut it into, were its rows in lattice order; rows[0..1]
 * this rank's piece's rows, rows[2..3] its own, rows[4..5] the piece and a
 * block more on each side (the window whose compact families are whole in
 * the piece).  0 (on every rank) when the shares are off any lattice. */
int pd_piece_lattice_rows(const pd_particles *share, const pd_stencil *st, int64_t rows[6]);
/* Does the stencil plan of the windows p, b of a lattice body
 * (pd_grid_plan_window) find the stencil, and cut the body as p is cut
 * (pd_piece_lattice_rows)?  Collective; then pd_sim_piece_new cuts it so. */
int pd_piece_lattice_fits(const pd_particles *p, const pd_bonds *b, const pd_scene *sc);
/* On several ranks, is the body p walked as a bond list under the scene sc
 * whatever its bonds (off any lattice), so that each rank may read its own
 * rows' bonds alone? */
int pd_piece_reads_rows(const pd_particles *p, const pd_scene *sc);
/* The rows [*lo, *hi) of the whole body that this piece owns. */
void pd_sim_owned(const pd_sim *piece, int64_t *lo, int64_t *hi);
/* What one process writes of a run into its run file: its own rows of
 * particles and their bonds (a piece's on MPI ranks; every row on one).
 * Local rows [lo, lo + rows) of the run's arrays are the whole body's rows
 * [first, first + rows) of n; their bonds, [klo, klo + bonds) of the run's
 * bond list, are the body's [bond0, bond0 + bonds) of nbonds. */
typedef struct {
    int64_t lo, first, rows, n;
    int64_t klo, bond0, bonds, nbonds;
} pd_part;
/* The run's part (collective on MPI ranks). */
void pd_sim_part(const pd_sim *sim, pd_part *part);
/* The bytes this piece sends its neighbours at each step (the ghosts'
 * positions, and s0 with failure); 0 for a whole run. */
int64_t pd_sim_halo_bytes(const pd_sim *piece);

/* PMB micromodulus from the bulk modulus: c = 18 K / (pi delta^4) (seed 000
 * eq. 6, 3-D). */
double pd_pmb_c_from_bulk(double bulk_modulus, double horizon);

/* Critical stretch from the fracture energy G0 (J/m^2) for PMB:
 * s0 = sqrt(10 G0 / (pi c delta^5)) (seed 004 eqs. 26-27; with
 * c = 18 K / (pi delta^4) this is sqrt(5 G0 / (9 K delta))). */
double pd_pmb_s0_from_energy(double g0, double c, double horizon);

/* 2-D plates, plane stress (lib/models/plate.c; the derivations in pd-run(1)).
 * Matching the strain energy density of an isotropic in-plane stretch,
 * c pi H delta^3 eps^2 / 6 = 2 K eps^2, gives
 *   c = 12 K / (pi H delta^3) = 9 E / (pi H delta^3)    (nu = 1/3)
 * with K = E / (2 (1 - nu)) the 2-D (plane-stress) bulk modulus, and the
 * energy of the bonds across a unit area of crack, G0 = c s0^2 H delta^4 / 4,
 * gives s0 = sqrt(4 G0 / (c H delta^4)) = sqrt(4 pi G0 / (9 E delta)). */
double pd_pmb_c_from_bulk_2d(double bulk_modulus, double horizon, double thickness);
double pd_pmb_s0_from_energy_2d(double g0, double c, double horizon, double thickness);
/* The bulk modulus PMB has for Young's modulus E: with its fixed Poisson
 * ratio, K = E / (3 (1 - 2 nu)) = 2E/3 in 3-D (nu = 1/4) and
 * K = E / (2 (1 - nu)) = 3E/4 in 2-D plane stress (nu = 1/3). */
double pd_pmb_bulk_from_youngs(double youngs_modulus, int dimension);
/* c and s0 for the particles' dimension: the 3-D formulas above, or the
 * 2-D ones with p->thickness. */
double pd_pmb_c_for(const pd_particles *p, double bulk_modulus, double horizon);
double pd_pmb_s0_for(const pd_particles *p, double g0, double c, double horizon);

/* ---------------------------------------------------------------- materials */

/* A PMB bond law (lib/models/materials.c, pd-run --material and --interface): the
 * micromodulus and critical stretch parameter of the bonds between
 * particles of materials a and b (a == b: the bonds inside material a). */
typedef struct pd_bond_law {
    int32_t a, b;   /* material ids                                     */
    double c;       /* micromodulus, N/m^6 (> 0)                        */
    double s00;     /* s00 of the bonds (0: the scene's s00)            */
} pd_bond_law;

/* Whether a scene gives its bonds their own c or s00 (laws or a fibre). */
int pd_scene_has_laws(const pd_scene *s);
/* The c (N/m^6) and s00 of the bond from i to j (symmetric in i, j):
 *  - material m_i == m_j with a law (m, m): that law's;
 *  - else with a fibre (seed 004 eq. 10), beta = g.xi/(|g||xi|):
 *    c = beta^2 c_fibre + (1 - beta^2) c_matrix, s00 likewise;
 *  - else the scene's c and s00;
 * and between two materials, the law (m_i, m_j) when given, else each end
 * as above and c the harmonic mean 2 c_i c_j/(c_i + c_j) (the two half
 * bonds in series), s00 the smaller of the two. */
void pd_bond_law_of(const pd_particles *p, const pd_scene *s, int64_t i, int64_t j, double *c,
                    double *s00);
/* PD_ERR_INVALID naming the first law whose material is not in the body,
 * or whose c or s00 is out of its domain. */
pd_status pd_bond_laws_check(const pd_particles *p, const pd_scene *s);
/* Give the particles inside region r the material id (pd-lattice
 * --material-region); returns how many. */
int64_t pd_material_paint(pd_particles *p, const pd_region *r, int32_t id);

/* Stable step of seed 004 eq. 46 for the bonds of the scene's model (its
 * descriptor's, lib/models/). */
double pd_stable_dt(const pd_particles *p, const pd_bonds *b, const pd_scene *s);

/* LPS (lib/models/lps.c).  The influence function omega(|xi|) for a horizon. */
double pd_lps_influence(pd_influence w, double length, double horizon);
/* The weighted volume of every particle, m_i = sum_j omega |xi|^2 nu_ij V_j
 * over the reference family (seed 000 eq. 4, Algorithm 3), into m (n). */
void pd_lps_weighted_volume(const pd_particles *p, const pd_bonds *b, pd_influence w,
                            double *m);
/* The stable step of the state-based models LPS, VES and EPS (the analogue
 * of seed 004 eq. 46; see lib/models/lps.c), their descriptors' and so
 * pd_stable_dt's for them. */
double pd_lps_stable_dt(const pd_particles *p, const pd_bonds *b, const pd_scene *s);
/* Name of an influence function ("1/r", "1", "gaussian"), and back (-1:
 * unknown). */
const char *pd_influence_name(pd_influence w);
int pd_influence_parse(const char *name);
/* The dilatation theta of every particle at the run's current positions
 * and bond states (seed 000 Algorithm 4), into theta (n); LPS runs only
 * (PD_ERR_INVALID otherwise). */
pd_status pd_sim_dilatation(const pd_sim *sim, double *theta);
/* The run's bond history (VES: 2 values per directed bond, EPS: 1; see
 * lib/models/lps.c),
 * NULL and *width 0 when its model keeps none. */
double *pd_sim_bond_history(const pd_sim *sim, int *width);

/* The ellipsoidal influence function (lib/bonds/influence.c, seed 002 eqs. 6-13).
 * pd_ellipsoid_parse reads "UX,UY,UZ,A,B,ROLL" and calls pd_ellipsoid_init,
 * which checks u != 0, a, b in (0, 1] and builds M^-1 (PD_ERR_INVALID).
 * pd_ellipsoid_distance is eq. 13 for a direction of any nonzero length:
 * d = 1/sqrt(w_x^2 + w_y^2/a^2 + w_z^2/b^2), w = M^-1 e, e = dir/|dir|.
 * pd_ellipsoids_factor is the largest d over n ellipsoids (1 for n = 0),
 * pd_bond_influence the bond's weight omega(|xi|) d(xi/|xi|) in the scene. */
pd_status pd_ellipsoid_parse(const char *text, pd_ellipsoid *e);
pd_status pd_ellipsoid_init(pd_ellipsoid *e);
double pd_ellipsoid_distance(const pd_ellipsoid *e, const double dir[3]);
double pd_ellipsoids_factor(const pd_ellipsoid *e, int n, const double dir[3]);
double pd_bond_influence(const pd_scene *s, double length, double horizon, const double xi[3]);

/* What a user says of a scene (pd-run's options, lib/run/scene.c): the
 * scene as given, and which of its numbers were given. */
#define PD_LAWS_MAX 64 /* --material and --interface laws of a scene */
typedef struct {
    pd_scene sc;        /* as given; pd_scene_resolve completes it        */
    int has_c, has_k, has_e; /* the stiffness was given as c, K or E (the
                                last of them wins)                       */
    int has_g0;         /* --failure-energy: s00 from G0 once c is known  */
    double g0;          /* G0, J/m^2                                      */
    int has_g, has_influence, has_lambda, has_tau, has_yield; /* the
                           state-based models' --shear-modulus, --influence,
                           --ves-lambda, --ves-tau, --yield-stress          */
    int has_material, has_interface; /* some law of either kind           */
    int has_proj_k;     /* the projectile's K given (else its default)    */
    int has_dt;         /* dt given (else safety x the stable step)       */
    int has_time;       /* --time: sc.steps from end_time once dt is known */
    double end_time;    /* the run's end, s: the fewest steps of at most
                           dt that reach it, dt = end_time / steps        */
    int force_dt;       /* run a dt above the stable step anyway          */
    int nlaws;          /* laws[0..nlaws-1] (sc.laws points here once
                           resolved)                                     */
    pd_bond_law laws[PD_LAWS_MAX];
    double law_k[PD_LAWS_MAX]; /* laws[k]'s K=, Pa; 0: its c= was given  */
} pd_scene_spec;

/* Before the body is read: the options each model needs and takes (its
 * descriptor), the scene's c from laws and fibres, a stiffness given.
 * PD_ERR_INVALID (a usage error) names what is wrong. */
pd_status pd_scene_check(pd_scene_spec *spec);
/* Against the body p, b (`body` names it in messages), after
 * pd_scene_check (called again here, so that this one call resolves a
 * scene; a program calls pd_scene_check first to tell a usage error before
 * it reads the body): the laws' c, K from
 * E, c from K (3-D or plane stress), s00 from G0, the defaults (contact
 * skin, lost margin, the projectile's K), the stable step of seed 004 eq.
 * 46 and dt (safety x the stable step; a larger --dt without force_dt is
 * refused).  spec->sc is then the scene a run takes (pd_sim_new). */
pd_status pd_scene_resolve(pd_scene_spec *spec, const pd_particles *p, const pd_bonds *b,
                           const char *body);
/* The frames of a run (pd-run --every): step n gets one when it is a
 * multiple of sc->every (every > 0) or the last step, sc->steps.
 * pd_frame_steps lists those a run from step `first` writes (steps may be
 * NULL: only counted), step 0 included in a new run (`fresh`); returns how
 * many. */
int pd_frame_at(const pd_scene *sc, int64_t n);
int64_t pd_frame_steps(const pd_scene *sc, int64_t first, int fresh, int64_t *steps);
/* The same for the rows of the time series (pd-run --series): step n gets
 * one when it is a multiple of sc->series or the last step; none when
 * sc->series is 0. */
int pd_series_at(const pd_scene *sc, int64_t n);
int64_t pd_series_steps(const pd_scene *sc, int64_t first, int fresh, int64_t *steps);

/* What pd_scene_inspect finds in a resolved scene that is valid but
 * likely wrong, before step 1. */
#define PD_SCENE_WARNINGS 16 /* warnings kept, at most                     */
typedef struct {
    double contact_time; /* s from t = 0 until the projectile or indenter
                            first touches a particle: INFINITY when it
                            never does (moving away, or past the body),
                            NaN when the scene has neither              */
    int64_t frames;      /* frames the run will write                     */
    int nwarnings;
    char warning[PD_SCENE_WARNINGS][256]; /* one line each, no newline     */
} pd_scene_report;

/* A fresh run's scene (spec resolved by pd_scene_resolve) against its body
 * at t = 0.  A projectile or indenter that overlaps the body (a particle
 * deeper than PD_OVERLAP_TOL spacings inside its sphere) is PD_ERR_INVALID,
 * naming the depth and the particle, unless spec->sc.allow_overlap.  Values
 * that are valid but implausible get one warning each, naming the likely
 * mistake (PD_PLAUSIBLE_*: densities and moduli of no solid, a critical
 * stretch above PD_PLAUSIBLE_S00_MAX, a horizon of fewer than
 * PD_PLAUSIBLE_M_MIN or more than PD_PLAUSIBLE_M_MAX spacings, a run that
 * ends before the first contact, a scene in which nothing loads the body). */
#define PD_OVERLAP_TOL 0.01           /* spacings: touching (to rounding, or a
                                         hair deeper) is not overlap        */
#define PD_PLAUSIBLE_DENSITY_MIN 100.0   /* kg/m^3: below any solid (foams
                                          aside): g/cm^3 meant?            */
#define PD_PLAUSIBLE_DENSITY_MAX 25000.0 /* kg/m^3: above any solid
                                          (osmium 22590)                  */
#define PD_PLAUSIBLE_MODULUS_MIN 1e5  /* Pa: softer than soft rubber's G    */
#define PD_PLAUSIBLE_MODULUS_MAX 2e12 /* Pa: stiffer than diamond's E      */
#define PD_PLAUSIBLE_S00_MAX 0.1      /* a bond stretched 10% before it breaks */
#define PD_PLAUSIBLE_M_MIN 2.0        /* horizon / spacing                   */
#define PD_PLAUSIBLE_M_MAX 6.0
pd_status pd_scene_inspect(const pd_scene_spec *spec, const pd_particles *p, const pd_bonds *b,
                           pd_scene_report *rep);

/* The resolved scene as scene-file lines ("option value"), enough to rerun
 * or restart (/scene/options); malloc'ed, NULL when out of memory. */
char *pd_scene_text(const pd_scene *s);

/* Compute the forces of the initial state (step 0). */
pd_status pd_sim_setup(pd_sim *sim);
/* One velocity-Verlet step (seed 000 Algorithm 1) with the declared effects. */
pd_status pd_sim_step(pd_sim *sim);

/* What one load step of the relaxation took (pd_sim_relax). */
typedef struct {
    int64_t iterations; /* the iterations it took                        */
    double residual;    /* the residual force at the end, N: the norm of
                           the net force on the free particles          */
    double load;        /* the norm of the load it is measured against, N */
    double kinetic_peak;/* the largest kinetic energy of the iterations, J */
    double kinetic;     /* the kinetic energy at the end, J              */
    int64_t rounds;     /* the relaxations again after bonds broke       */
} pd_relax_info;

/* One load step of a quasi-static scene (sc.relax; lib/run/relax.c): the
 * step and the time advance by one (the loads then are those of the new
 * time), and adaptive dynamic relaxation (Kilic & Madenci 2010) iterates
 * from rest until the residual force on the free particles falls below
 * sc.relax_tolerance times the load.  PD_ERR_UNSTABLE when it does not
 * within sc.relax_iterations, or the state turns non-finite. */
pd_status pd_sim_relax(pd_sim *sim, pd_relax_info *info);

/* Names of the active effects, e.g. "pmb+failure contact indenter". */
const char *pd_sim_effects(const pd_sim *sim);
/* The PMB bonds' kernel: the half-stencil offsets of the lattice kernel
 * (lib/stencil/grid.c), or 0 when the bond list is walked; whether the stencil
 * walks its rows in AVX-512 tiles; whether the PMB bond list is walked in
 * AVX-512 rows (lib/models/pmb.c), and whether 8 rows at a time, in lanes
 * (lib/models/pmb_lanes.c). */
int pd_sim_stencil(const pd_sim *sim);
int pd_sim_stencil_tiles(const pd_sim *sim);
int pd_sim_list_rows(const pd_sim *sim);
int pd_sim_list_lanes(const pd_sim *sim);
int64_t pd_sim_stepno(const pd_sim *sim);
double pd_sim_time(const pd_sim *sim);
double pd_sim_kinetic(const pd_sim *sim);

/* The energies of a run, J.  Up to the integrator's error,
 *   kinetic + elastic + contact + released + lost - work
 * stays at its value of step 0 (the energy balance). */
typedef struct {
    double kinetic;  /* sum of 1/2 rho_i V_i |v_i|^2                          */
    double elastic;  /* intact bonds: sum of 1/2 c s^2 |xi| nu V_i V_j (PMB)  */
    double contact;  /* contact pairs, 1/2 (c_S/delta) (d - r)^2 V_i V_j, and
                        the indenter's penalty, V_i K (R - r)^3 / 3          */
    double released; /* the elastic energy bonds held when they broke         */
    double lost;     /* the kinetic energy lost particles carried away        */
    double work;     /* work done on the body by the moving indenter          */
    double projectile; /* kinetic energy of the projectile, 1/2 M |V|^2     */
    double damped;   /* the energy --damping took (its power integrated)     */
} pd_energy;

/* The energies of the current state; with `density` (n values, may be
 * NULL), also the strain energy density of each particle, J/m^3 (half of
 * the energy of each of its bonds, per its volume).  Sums are taken in a
 * fixed order: the same figures at any thread count. */
pd_status pd_sim_energy(const pd_sim *sim, pd_energy *e, double *density);
/* The energies of the step pd_sim_step takes next will be asked for (a
 * frame, a status line): its pass over the bonds counts them on the way
 * (the lattice stencil's PMB kernel, but in AVX-512 tiles), so that
 * pd_sim_energy then walks no bond.  The same figures, bit for bit. */
void pd_sim_energy_next(pd_sim *sim);
/* The peridynamic stress of every particle (seed 003 eq. 7 read per
 * particle: the static virial of its bonds),
 *   sigma_i = 1/2 sum_j V_j f_ij (x) xi_ij,
 * with f_ij the force density the intact bond j puts on i per unit volume
 * of j (N/m^6) and xi_ij = x_j - x_i its reference vector: a first
 * Piola-Kirchhoff stress, Pa, 9 values per particle (stress[9i + 3a + b]).
 * Computed only when called. */
pd_status pd_sim_stress(const pd_sim *sim, double *stress);
/* The von Mises stress of a 3x3 tensor (of its symmetric part), Pa. */
double pd_von_mises(const double s[9]);
/* The balance kinetic + elastic + contact + released + lost - work
 * (+ projectile, the sphere's kinetic energy, with --projectile; + damped,
 * with --damping). */
double pd_energy_total(const pd_energy *e);
int64_t pd_sim_broken(const pd_sim *sim);      /* broken bonds (pairs) */
double pd_sim_max_damage(const pd_sim *sim);
/* The damage of every particle of the run (a piece's rows on MPI ranks)
 * of the current state, as pd_damage computes it from pd_sim_intact's
 * bits, bit for bit (on the stencil counted off its masks). */
void pd_sim_damage(const pd_sim *sim, double *damage);
/* The largest damage of the current state and the number of particles
 * whose damage is above `threshold` (pd_damage; on the stencil from its
 * masks, in parallel). */
pd_status pd_sim_damage_stats(const pd_sim *sim, double threshold, double *max_damage,
                              int64_t *above);
/* The same from the damage of the run's particles, already taken
 * (pd_damage of the current state; a piece's own rows' on MPI ranks). */
pd_status pd_sim_damage_stats_of(const pd_sim *sim, const double *damage, double threshold,
                                 double *max_damage, int64_t *above);

/* The time series of a run (lib/run/series.c; pd-run --series, /series of
 * the run file, man 5 pd-h5): one row per sampled step of
 *   step, time, kinetic_energy, elastic_energy, contact_energy,
 *   released_energy, lost_energy, external_work, [projectile_energy],
 *   [damped_energy], balance (pd_energy_total), broken_bonds,
 *   damaged_particles (damage above PD_DAMAGE_THRESHOLD), max_damage,
 *   lost_particles, px, py, pz (the body's momentum, kg m/s),
 * then for each named set S of the scene (sc.sets, in order)
 *   S.ux, S.uy, S.uz   the mean displacement y - x of its particles not
 *                      lost, m,
 *   S.fx, S.fy, S.fz   the force the boundary conditions apply to its
 *                      particles, N: on a held component V_i (rho_i a_i
 *                      - f_i), a_i the prescribed acceleration (the
 *                      reaction that holds it), under a body force V_i b,
 * and for the projectile and the indenter (projectile.*, indenter.*)
 *   x, y, z, vx, vy, vz, fx, fy, fz   centre (m), velocity (m/s) and the
 *                      force the body puts on it (N). */
#define PD_SERIES_NAME 72 /* bytes of a column name, NUL included: a set's
                             name (PD_SET_NAME_MAX) and ".ux"           */
/* The columns of a scene's series: their number, and their names into
 * names[0..] when names is not NULL. */
int pd_series_columns(const pd_scene *sc, char (*names)[PD_SERIES_NAME]);
/* The row of the current state, pd_series_columns(&scene) values; e: the
 * energies of the current state (pd_sim_energy). */
pd_status pd_sim_series_row(const pd_sim *sim, const pd_energy *e, double *row);
/* The same with the damage of the current state already taken (NULL: the
 * row takes it). */
pd_status pd_sim_series_row_damage(const pd_sim *sim, const pd_energy *e, const double *damage,
                                   double *row);
int64_t pd_sim_contact_builds(const pd_sim *sim);
/* A piece on MPI ranks: the most contact partners one of its list builds
 * took from beyond the piece (fragments that crossed to another rank's
 * particles); 0 for a whole run. */
int64_t pd_sim_contact_remote(const pd_sim *sim);
const double *pd_sim_timers(const pd_sim *sim); /* seconds per pd_timer */
/* What a run needs beyond a frame to go on bit for bit (pd-run --restart):
 * exact positions, the force densities of the last step, s0 (with failure)
 * and the positions at the contact list's last build (with contact). */
typedef struct {
    double *position[3];         /* current positions y, m            */
    double *force[3];            /* force densities, N/m^3            */
    double *s0;                  /* NULL without failure              */
    double *contact_position[3]; /* NULL without a contact list yet   */
    int64_t contact_builds;
    double work;                 /* pd_energy.work so far, J          */
    double released;             /* pd_energy.released so far, J      */
    double power;                /* the indenter's power at the last
                                    force evaluation, W (trapezoidal
                                    rule of the work)                 */
    double lost_energy;          /* pd_energy.lost so far, J          */
    double energy0;              /* kinetic + elastic + contact at
                                    step 0, J                         */
    int has_damping;
    double damping[2];           /* pd_energy.damped so far, J, and the
                                    damping's power at the last force
                                    evaluation, W                     */
    uint8_t *lost;               /* n flags: particle lost (NULL: none) */
    int has_projectile;
    double projectile[9];        /* the projectile's centre (m), velocity
                                    (m/s) and the force on it (N)     */
    int64_t history_bonds;       /* directed bonds of bond_history    */
    int history_width;           /* values per directed bond          */
    double *bond_history;        /* the model's state per directed bond
                                    (VES: the deviatoric extension of
                                    the last step and the back
                                    extension), row-major; NULL: none */
} pd_restart;
/* What a run's restart data hold (pd_restart: the state, the accumulated
 * energies and power, lost particles, and what its effects keep: contact
 * list positions, the projectile, bond history), pointing into the run. */
void pd_sim_accumulated(const pd_sim *sim, pd_restart *r);
/* Particles lost so far (see pd_scene.lost_margin). */
int64_t pd_sim_lost(const pd_sim *sim);
/* The default lost margin: PD_LOST_MARGIN_FAC times the largest edge of
 * the reference bounding box (at least the spacing). */
double pd_lost_margin_default(const pd_particles *p);
/* Has the kinetic energy grown past PD_KE_GROWTH times the energy put in
 * (that of step 0 plus the work done)?  Then *ratio says by how much. */
int pd_energy_runaway(const pd_sim *sim, const pd_energy *e, double *ratio);
/* The balance's drift from step 0, pd_energy_total(e) - (its value at step
 * 0), as a fraction of the energy put in (step 0's and the work done):
 * positive when the run made energy, negative when it lost some. */
double pd_energy_drift(const pd_sim *sim, const pd_energy *e);
/* The energy alarm on the energies e of the current step:
 * PD_ERR_UNSTABLE, naming the step and the drift, when the balance gained
 * more than sc.balance_limit times the energy put in, or lost as much with
 * a model that books all its energy (a dissipative one, VES or EPS, loses
 * what it does not book).  pd_sim_step itself tests every
 * PD_BALANCE_EVERY steps, on the kinetic energy alone, whether the alarm
 * must fire (kinetic > (1 + limit) x energy put in bounds the gain from
 * below), so that a run gone unstable stops before it turns NaN. */
pd_status pd_sim_check_balance(const pd_sim *sim, const pd_energy *e);
/* Is the energy of step 0 mostly penalty energy (the contact of pairs, a
 * projectile's or indenter's overlap) rather than motion?  Then 1 and one
 * line of text saying so; the scene then starts compressed, not loaded.
 * Less than the energy of a uniform strain of PD_PENALTY_STRAIN of the
 * whole body is no penalty (spheres that touch to rounding).
 * After pd_sim_setup of a fresh run. */
int pd_sim_start_penalty(const pd_sim *sim, char *text, size_t len);

double *const *pd_sim_forces(const pd_sim *sim);
const double *pd_sim_s0(const pd_sim *sim);
/* Put the run at `step` with the state of a restart slot, the frame's
 * velocities and bond states. */
pd_status pd_sim_restore(pd_sim *sim, int64_t step, const pd_restart *r, double *const v[3],
                         const uint64_t *intact);
/* The particles and bonds the run steps (a piece's own on MPI ranks). */
const pd_particles *pd_sim_particles(const pd_sim *sim);
const pd_bonds *pd_sim_bonds(const pd_sim *sim);
/* Views of the state (current positions y, velocities v), SoA. */
double *const *pd_sim_positions(const pd_sim *sim);
double *const *pd_sim_velocities(const pd_sim *sim);
const uint64_t *pd_sim_intact(const pd_sim *sim);

/* ---------------------------------------------------------------- sets */

/* Named particle sets (lib/base/sets.c), stored by global id so that they
 * survive the reordering of rows (pd-bonds' spatial sort): /sets/NAME, an
 * int64 dataset of ascending ids (man 5 pd-h5). */
#define PD_SET_NAME_MAX 64 /* bytes of a set name, with the NUL */

typedef struct pd_file pd_file; /* (repeated under files below) */

typedef struct {
    char name[PD_SET_NAME_MAX]; /* [A-Za-z0-9_.-]+, not "." or ".."        */
    int64_t n;                  /* particles in the set, >= 1              */
    int64_t *id;                /* n global ids, strictly ascending        */
} pd_set;

typedef struct pd_sets {
    int count;
    pd_set *set;
} pd_sets;

pd_sets *pd_sets_new(void);
void pd_sets_free(pd_sets *s);
/* Is `name` a valid set name? */
int pd_set_name_ok(const char *name);
/* Add the set `name` of the particles of p inside region r (its subtract
 * flag is ignored).  PD_ERR_INVALID for a bad or taken name and for a set
 * that holds no particle. */
pd_status pd_sets_add_region(pd_sets *s, const char *name, const pd_region *r,
                             const pd_particles *p);
/* The set called `name`, or NULL. */
const pd_set *pd_sets_find(const pd_sets *s, const char *name);
/* The local rows of a set's particles (ascending ids order), malloc'ed;
 * PD_ERR_INVALID when an id is not one of p's. */
pd_status pd_set_rows(const pd_set *set, const pd_particles *p, int64_t **rows);
/* The same, -1 for a member that is not among p (a piece of a body on MPI
 * ranks holds some of a set). */
pd_status pd_set_rows_present(const pd_set *set, const pd_particles *p, int64_t **rows);
/* Read /sets (an empty pd_sets when the file has none), checking every set
 * against the particles p: names, type, rank, order, ids that exist. */
pd_status pd_read_sets(const pd_file *f, const pd_particles *p, pd_sets **out);
/* The closed surface of /surface (pd-mesh --surface), checked as
 * pd_surface_new() checks it; pd_file_has_surface() says whether there is
 * one. */
int pd_file_has_surface(const pd_file *f);
pd_status pd_read_surface(const pd_file *f, pd_surface **out);
/* Write /sets (nothing when there is no set). */
pd_status pd_write_sets(pd_file *f, const pd_sets *s);

/* ---------------------------------------------------------------- profiles */

/* A function of time g(t) (lib/base/profile.c) with its exact integral
 * G(t) = int_0^t g and its derivative g'(t) where g is smooth (the right
 * derivative at a corner; 0 at a jump).  Forms:
 *   V                        constant V
 *   points:T0,V0,T1,V1,...   piecewise linear through (T_k, V_k), times
 *                            strictly increasing, held at V0 before T0 and
 *                            at the last value after the last time
 *   table:FILE               the same from a file of `time value` lines
 *                            (`#` starts a comment)
 *   pulses:V1,D1,V2,D2,...   V1 for 0 <= t < D1, V2 for the next D2, ...,
 *                            0 before 0 and after the last (D_k > 0) */
typedef enum { PD_PROFILE_CONSTANT, PD_PROFILE_POINTS, PD_PROFILE_PULSES } pd_profile_kind;

typedef struct {
    pd_profile_kind kind;
    int64_t n;  /* points, or pulses                                        */
    double *t;  /* n: points: times, s; pulses: start times (0, D1, ...), s */
    double *v;  /* n: values (constant: one)                                */
    double *G;  /* n+1: int_0^{t_k} g (pulses: G[n] at the last end)        */
    double *d;  /* n: pulses: durations D_k, s                              */
    double end; /* pulses: end of the last pulse, s                         */
} pd_profile;

/* Parse a profile; PD_ERR_INVALID for a malformed one, PD_ERR_IO for a
 * table file that cannot be read.  Free with pd_profile_free. */
pd_status pd_profile_parse(const char *spec, pd_profile *g);
void pd_profile_free(pd_profile *g);
double pd_profile_value(const pd_profile *g, double t);
double pd_profile_integral(const pd_profile *g, double t);
double pd_profile_rate(const pd_profile *g, double t);
/* The profile in a form pd_profile_parse reads back to the same numbers
 * (a table as points:..., each number in the shortest form that reads back
 * to it); malloc'ed, NULL when out of memory. */
char *pd_profile_text(const pd_profile *g);

/* ---------------------------------------------------------------- boundary conditions */

/* A boundary condition on a particle set (lib/effects/bc.c), given to a run in
 * pd_scene.bc.  For the particles of the set, along `axis`:
 *   PD_BC_VELOCITY      y = x + G(t) and v = g(t), held exactly
 *   PD_BC_DISPLACEMENT  y = x + g(t) and v = g'(t), held exactly
 *   PD_BC_BODY_FORCE    a force density b = g(t), N/m^3, added to f
 * Two prescribed motions of the same particle and axis are refused. */
typedef enum { PD_BC_VELOCITY, PD_BC_DISPLACEMENT, PD_BC_BODY_FORCE } pd_bc_kind;

typedef struct pd_bc {
    pd_bc_kind kind;
    char set[PD_SET_NAME_MAX];
    int axis;            /* 0, 1, 2 for x, y, z */
    pd_profile profile;
} pd_bc;

/* Parse "SET,AXIS,PROFILE" (AXIS x|y|z); the status of pd_profile_parse
 * for the profile. */
pd_status pd_bc_parse(pd_bc_kind kind, const char *spec, pd_bc *bc);
/* The option that gives a condition, e.g. "velocity-bc". */
const char *pd_bc_option(pd_bc_kind kind);
/* The projectile (pd_scene.has_projectile, lib/effects/projectile.c): a rigid
 * sphere of mass M that pushes the particles inside it with the indenter's
 * force density K (R - r)^2 and feels the reaction F = -sum V_i f_i.
 * The default K makes the penalty's tangent stiffness 2 K p at a
 * penetration p = PD_PROJECTILE_DEPTH x spacing equal the largest bond
 * stiffness sum of seed 004 eq. 46, max_i sum_p V_p nu c/|xi|. */
#define PD_PROJECTILE_DEPTH 0.25
double pd_projectile_default_k(const pd_particles *p, const pd_bonds *b, const pd_scene *s);
/* The projectile's centre (m) and velocity (m/s) now; 0 when there is none. */
int pd_sim_projectile(const pd_sim *sim, double x[3], double v[3]);
/* The scene's --damping C, 1/s (0: none). */
double pd_sim_damping(const pd_sim *sim);
/* The particles of the scene's --no-failure sets, none of whose bonds
 * breaks (0: no such set). */
int64_t pd_sim_no_failure(const pd_sim *sim);

/* ---------------------------------------------------------------- files */

typedef struct pd_file pd_file;

/* Open for reading; path "-" reads the whole of stdin as an HDF5 image. */
pd_status pd_file_open(const char *path, pd_file **out);
/* Open an HDF5 file image held in memory (copied), e.g. for a fuzzer;
 * `name` is used in messages. */
pd_status pd_file_open_memory(const void *buf, size_t len, const char *name, pd_file **out);
/* Open the whole of a stream (a pipe from another program) as an HDF5
 * image, as "-" opens stdin; `name` is used in messages. */
pd_status pd_file_open_stream(FILE *in, const char *name, pd_file **out);
/* Does the file at `path` begin with HDF5's signature?  1 or 0, or -1
 * with pd_errmsg() set when it cannot be read. */
int pd_file_is_hdf5(const char *path);
/* Create for writing; "-" builds the file in memory and streams it to stdout
 * at close.  Otherwise the file is written under a temporary name beside
 * `path` and renamed when pd_file_close() succeeds. */
pd_status pd_file_create(const char *path, pd_file **out);
/* Open an existing file for update through a copy: the original is copied to
 * a temporary beside `outpath` ("-" for stdout), modified, and renamed to
 * `outpath` on close. */
pd_status pd_file_update(const char *inpath, const char *outpath, pd_file **out);
/* pd_file_create and pd_file_update for every MPI rank at once
 * (collective): rank 0 makes the temporary (and the copy), every rank
 * opens it with parallel HDF5, and from then on every rank takes part in
 * each call on the file (the frames: each rank its own rows; metadata and
 * whole datasets: the same call on every rank, rank 0's data written);
 * pd_file_publish and pd_file_close flush it together and rank 0 renames
 * it.  The output must be a regular file.  On one rank, and in a build
 * without MPI, they are pd_file_create and pd_file_update. */
pd_status pd_file_create_ranks(const char *path, pd_file **out);
pd_status pd_file_update_ranks(const char *inpath, const char *outpath, pd_file **out);
/* Close: flush, publish (rename or stream), free.  On failure the temporary
 * file is removed. */
pd_status pd_file_close(pd_file *f);
/* Put a file being written under its final name now, while it stays open
 * (after flushing it): for a run whose frames are laid out in advance and
 * then only filled in (pd_plan_frames), so that a killed run leaves a
 * readable file.  No-op for stdout. */
pd_status pd_file_publish(pd_file *f);
/* Abandon a file being written: remove the temporary (a published file
 * stays, with what it holds), free. */
void pd_file_abort(pd_file *f);

/* Remove the temporary files of outputs still being written: for a signal
 * handler (async-signal-safe), so that a killed program leaves nothing. */
void pd_remove_temps(void);

/* Root attributes: format, version, units, history.  `history` of a new
 * file starts from `from` (may be NULL) and gets `cmdline` appended. */
pd_status pd_write_header(pd_file *f, const pd_file *from, const char *cmdline);
pd_status pd_append_history(pd_file *f, const char *cmdline);
/* The history text (lines); caller frees. */
pd_status pd_read_history(const pd_file *f, char **out);

pd_status pd_read_particles(const pd_file *f, pd_particles **out);
pd_status pd_write_particles(pd_file *f, const pd_particles *p);
/* The body's count of particles, checked as pd_read_particles checks it. */
pd_status pd_file_particles(const pd_file *f, int64_t *n);
/* Rows [g0, g1) of the file's n particles as a window of the body
 * (pd_particles: window, first g0, total n, owning every row read), each
 * row checked as pd_read_particles checks it (the ids' uniqueness below). */
pd_status pd_read_particles_rows(const pd_file *f, int64_t n, int64_t g0, int64_t g1,
                                 pd_particles **out);
/* No two particles of the body have the same id, the ranks' windows of it
 * p together holding every row once (collective; pd_read_particles' error). */
pd_status pd_check_ids_ranks(const pd_file *f, const pd_particles *p);
/* /particles of a part of the body (pd_part: its rows [lo, lo + rows) of
 * p are the body's [first, first + rows) of n): on MPI ranks every rank
 * writes its own, at once, into a file of pd_file_create_ranks. */
pd_status pd_write_particles_part(pd_file *f, const pd_part *pt, const pd_particles *p);
int pd_file_has_bonds(const pd_file *f);
/* Whether the file has a /frames group (a run of pd-run), complete frames
 * or not. */
int pd_file_has_frames(const pd_file *f);
pd_status pd_read_bonds(const pd_file *f, const pd_particles *p, pd_bonds **out);
/* The same, a stencil's families kept compact (pd_bonds_compact): no
 * per-bond arrays but the bits.  A file of lists reads as lists. */
pd_status pd_read_bonds_compact(const pd_file *f, const pd_particles *p, pd_bonds **out);
/* A piece of a body on MPI ranks reads the lists of its own rows alone
 * (lib/run/piece.c).  pd_file_bonds_listed: 1 when the file's /bonds are
 * lists (CSR), 0 for a stencil or none.  pd_read_bonds_span: the largest
 * span j - i of a bond of rows [r0, r1) (at least 1), the partners read a
 * million at a time.  pd_read_bonds_rows: the bonds of the body's rows
 * [g0, g1) as a pd_bonds of the rows of the window p (pd_read_particles_rows,
 * which reaches a span beyond them: partners are rows of p), in which only
 * those rows have their families (the others none), checked as
 * pd_read_bonds checks a body: each bond, and the symmetry of the bonds
 * between two of these rows (a piece's rows hold both ends of each bond of
 * the rows it owns); *first_bond, the whole body's index of their first
 * bond. */
int pd_file_bonds_listed(const pd_file *f);
pd_status pd_read_bonds_span(const pd_file *f, int64_t n, int64_t r0, int64_t r1, int64_t *span);
pd_status pd_read_bonds_rows(const pd_file *f, const pd_particles *p, int64_t g0, int64_t g1,
                             pd_bonds **out, int64_t *first_bond);
/* A lattice body's /bonds as a stencil: pd_read_stencil, its table (NULL
 * when the file has none, or one pd_read_bonds_compact would refuse).
 * pd_read_bonds_window (collective): the compact families of the window p
 * (pd_read_particles_rows) of a body on MPI ranks, whose rows [r0, r1) are
 * a piece's (their families whole in p: pd_piece_lattice_rows), their
 * state and pre-crack bits from the file (the other rows' bits set);
 * *first_bond the body's index of row r0's first bond.  Each rank checks
 * its own rows' bonds as pd_read_bonds_compact checks the body's, and the
 * ranks the body's count; *out NULL (on every rank) where that does not
 * show the file to be as pd_read_bonds_compact wants it (the caller then
 * reads it whole, which says why). */
pd_stencil *pd_read_stencil(const pd_file *f);
pd_status pd_read_bonds_window(const pd_file *f, const pd_particles *p, int64_t r0, int64_t r1,
                               pd_bonds **out, int64_t *first_bond);
/* What a rank of a run on several MPI ranks read of the body
 * (pd_read_body_ranks). */
typedef struct {
    int rows;           /* 0: the whole body; 1: a window of bond lists (its
                           piece's rows' bonds alone); 2: a window of a
                           lattice body's compact families                */
    int64_t first_bond; /* the body's index of the first bond whose state
                           was read,                                       */
    int64_t bond_at;    /* its index among the window's bonds,             */
    int64_t bonds;      /* and the bonds read from it on                   */
} pd_body_read;
/* The body a run of the scene o on several MPI ranks reads
 * (lib/io/runfile.c; collective): each rank checks its share of the
 * particles' rows (and the ids over the ranks); where the body's bonds are
 * lists walked as a bond list (pd_piece_reads_rows), each reads its
 * piece's rows alone (pd_piece_rows): the particles they reach as a window
 * (pd_read_particles_rows, owning its own rows) and their bonds
 * (pd_read_bonds_rows); where they are a lattice's stencil, each reads
 * the window of its piece and a block more on each side
 * (pd_piece_lattice_rows, pd_read_bonds_window), when the windows show
 * the file to be as the whole body's reader wants it and the stencil to
 * cut it as the windows are cut (pd_piece_lattice_fits); else the whole
 * body (pd_read_particles, pd_read_bonds_compact). */
pd_status pd_read_body_ranks(const pd_file *f, const pd_scene_spec *o, pd_particles **p,
                             pd_bonds **b, pd_body_read *w);
pd_status pd_write_bonds(pd_file *f, const pd_bonds *b);
/* The bond lists of a part of the body (pd_part: rows [first, first +
 * rows), whose bonds are the body's [bond0, bond0 + bonds)) from b, a
 * pd_bonds of every row (pd_bonds_build_rows) or of a window's (its rows
 * and partners the body's less first - lo) whose rows outside the part
 * may have none: on MPI ranks every rank writes its own, at once, into a
 * file of pd_file_create_ranks. */
pd_status pd_write_bonds_part(pd_file *f, const pd_part *pt, const pd_bonds *b);
pd_status pd_write_scene(pd_file *f, const pd_scene *s, const char *effects,
                         const char *options_text);
/* The resolved options of a run (/scene/options); caller frees. */
pd_status pd_read_scene_options(const pd_file *f, char **text);

/* Frames. */
typedef struct {
    int64_t step;
    double time;       /* s */
    int64_t broken;    /* broken bonds (pairs) */
    int64_t lost;      /* lost particles */
    pd_energy energy;  /* J; attributes kinetic_energy, elastic_energy,
                          contact_energy, released_energy, lost_energy,
                          external_work (and projectile_energy)      */
    int has_projectile;             /* attributes projectile_position, */
    double projectile_position[3];  /* m, and projectile_velocity, m/s */
    double projectile_velocity[3];
    int has_damping;                /* attribute damped_energy          */
} pd_frame_info;

/* Optional per-particle fields of frames, asked for with pd-run --fields. */
enum {
    PD_FIELD_ENERGY = 1, /* strain_energy_density (N), J/m^3                 */
    PD_FIELD_STRESS = 2  /* stress (N,3,3) and von_mises (N), Pa             */
};

/* The fields of one frame besides the motion and the bond states: the
 * damage (every frame has it; NULL: zeros) and the optional ones (each
 * NULL when not asked for). */
typedef struct {
    const double *damage;         /* N values, seed 000 eq. 10 (pd_damage)  */
    const double *energy_density; /* N values, J/m^3                        */
    const double *stress;         /* 9 N values, Pa: particle i's tensor at
                                     stress[9i + 3a + b], row a, column b  */
    const double *von_mises;      /* N values, Pa                           */
} pd_frame_fields;
/* Not a field: frames laid out with the projectile's attributes. */
enum { PD_FRAME_PROJECTILE = 1u << 16, PD_FRAME_DAMPING = 1u << 17 };

/* Lay out every frame a run will write (steps[k] at times[k]) before the
 * first step, so that writing them later changes no structure of the file;
 * see schema.c on crash safety. */
pd_status pd_plan_frames(pd_file *f, int64_t n, int64_t nbonds, int64_t nframes,
                         const int64_t *steps, const double *times, unsigned fields);
/* Lay out the time series (lib/io/series_io.c) for the rows of
 * pd_series_steps(sc, first, fresh): a fresh run's, or a restart's after
 * step `first` (the rows of the file's series up to `first` are kept; its
 * columns must be the scene's); nothing when there are none. */
pd_status pd_plan_series(pd_file *f, const pd_scene *sc, int64_t first, int fresh);
/* Restart slots (see schema.c): lay out `slots` of them (1: a run that
 * writes one frame needs no second; 2 else; those there already stay),
 * write (in turn), read the one of `step` (arrays allocated;
 * pd_restart_free). */
pd_status pd_plan_restart(pd_file *f, int64_t n, int has_s0, int has_contact, int slots);
pd_status pd_write_restart(pd_file *f, int64_t n, int64_t step, const pd_restart *r);
/* The same for a part of the run (pd_sim_part): r's arrays are the run's,
 * local rows, of which the part's go into the slot (on MPI ranks, every
 * rank its own, at once, into a file of pd_file_create_ranks). */
pd_status pd_write_restart_part(pd_file *f, const pd_part *pt, int64_t step, const pd_restart *r);
pd_status pd_read_restart(const pd_file *f, int64_t n, int64_t step, pd_restart *r);
/* The same of the particles' rows [g0, g0 + m) alone, and the bond
 * history's rows [k0, k0 + nb) (a piece's bonds, pd_read_bonds_rows). */
pd_status pd_read_restart_rows(const pd_file *f, int64_t n, int64_t g0, int64_t m, int64_t step,
                               int64_t k0, int64_t nb, pd_restart *r);
/* Lay out the projectile's state in the restart slots (after
 * pd_plan_restart; nothing when it is there already). */
pd_status pd_plan_restart_projectile(pd_file *f);
/* Lay out the damping's sums (pd_restart.damping) in the restart slots. */
pd_status pd_plan_restart_damping(pd_file *f);
/* Lay out the model's bond history, `width` doubles for each of `nbonds`
 * directed bonds, in the restart slots (nothing when it is there). */
pd_status pd_plan_restart_history(pd_file *f, int64_t nbonds, int width);
void pd_restart_free(pd_restart *r);

/* This rank's piece of a run of the scene sc on the body p, b, for
 * pd_comm_size() ranks (collective), cut as pd_sim_new would cut the whole
 * body's kernel but without building the whole body's run: *piece is a run
 * of its own (its own particles and bonds, freed with it), at rest, not yet
 * set up, stepped with pd_sim_setup, pd_sim_step or pd_sim_relax by every
 * rank together.  Its bonds take the directed states intact (NULL: b's).
 * A body the rank count cannot share (fewer than two blocks a rank) is
 * refused with PD_ERR_INVALID. */
pd_status pd_sim_piece_new(const pd_particles *p, const pd_bonds *b, const pd_scene *sc,
                           const uint64_t *intact, pd_sim **piece);
/* The same for a window of the body (pd_read_body_ranks): the piece
 * takes *p and *b over, and sets them NULL: a window of bond lists cut to
 * its rows in place (no second copy of its bonds), a lattice's window
 * freed once the piece's rows are sliced from it, before the piece's run
 * is built; a restart's pd_sim_piece_restore then takes them NULL. */
pd_status pd_sim_piece_take(pd_particles **p, pd_bonds **b, const pd_scene *sc,
                            const uint64_t *intact, pd_sim **piece);
/* The body's rows [*g0, *g1) the piece holds (its own and its ghosts). */
void pd_sim_piece_rows(const pd_sim *piece, int64_t *g0, int64_t *g1);
/* The piece of the body p, b goes on at `step` from restart data r and
 * velocities v of the body's rows from r_first on (the piece's rows at
 * least: pd_run_file_load_rows), with the bond history of b's bonds
 * (collective). */
pd_status pd_sim_piece_restore(pd_sim *piece, const pd_particles *p, const pd_bonds *b,
                               int64_t step, const pd_restart *r, int64_t r_first,
                               double *const v[3]);
/* A model file: the header (history from `from`, may be NULL, and
 * `cmdline`), the particles, the bonds (b may be NULL: a lattice before
 * pd-bonds) and the sets (may be NULL). */
pd_status pd_write_model(pd_file *out, const pd_file *from, const char *cmdline,
                         const pd_particles *p, const pd_bonds *b, const pd_sets *sets);
/* A run's file (lib/io/runfile.c).  Start it: a new run gets the header
 * (its history from `from`, the model file it read, or none when NULL),
 * the particles, bonds and sets, the scene (`effects`, the scene's text)
 * and every frame and restart slot laid out (frames from step 0); a
 * `restart` (`out` is the run file itself, updated through a copy) drops
 * unfinished frames, appends `cmdline` to the history and lays out the
 * frames after step `first`.  Then the file is published. */
pd_status pd_run_file_start(pd_file *out, int restart, const pd_file *from,
                            const pd_particles *p, const pd_bonds *b, const pd_sets *sets,
                            const pd_scene *sc, const char *effects, const char *cmdline,
                            const char *text, int64_t first);
/* The same on MPI ranks whose p is a window of the body and b holds the
 * families of their own rows alone (pd_read_body_ranks): each writes its
 * part's particles and bonds (pd_part: its own rows; collective). */
pd_status pd_run_file_start_part(pd_file *out, int restart, const pd_file *from,
                                 const pd_particles *p, const pd_bonds *b, const pd_part *part,
                                 const pd_sets *sets, const pd_scene *sc, const char *effects,
                                 const char *cmdline, const char *text, int64_t first);
/* The state at the last complete frame of a run: its step, the restart
 * slot (pd_restart_free), the frame's velocities and bond states
 * (malloc'ed), for pd_sim_restore. */
pd_status pd_run_file_load(pd_file *f, const pd_particles *p, const pd_bonds *b, int64_t *step,
                           pd_restart *r, double *v[3], uint64_t **bits);
/* The same in two parts, for a piece on MPI ranks: the step and the bond
 * states of b's bonds (of a window, w: the body's bonds [w->first_bond,
 * w->first_bond + w->bonds) into b's from w->bond_at on; w NULL or whole:
 * every bond), before the piece is cut; then the rows [g0, g0 + m) of
 * the body's n of the frame's velocities and of the restart slot, with
 * the bond history of bonds [k0, k0 + nb) (every bond's where nb < 0). */
pd_status pd_run_file_load_state(pd_file *f, const pd_bonds *b, const pd_body_read *w,
                                 int64_t *step, uint64_t **bits);
pd_status pd_run_file_load_rows(pd_file *f, int64_t n, int64_t g0, int64_t m, int64_t k0,
                                int64_t nb, pd_restart *r, double *v[3]);
/* The frame of the run's current step (energies, the optional `fields`)
 * and its restart data; the energies also go to *energy (may be NULL). */
pd_status pd_run_file_frame(pd_file *out, const pd_sim *sim, unsigned fields, pd_energy *energy);
/* The row of the time series (/series, laid out by pd_run_file_start when
 * sc->series > 0) of the run's current step, when it is one of the
 * series' steps (pd_series_at; else nothing is written): computed from the
 * energies e of the current state, written, flushed, then counted in
 * /series@rows.  pd_run_file_frame writes the row of its step itself,
 * before the frame, so that a restart from a frame finds the row of its
 * step.  pd_run_file_sample_due: is step one of those still to write? */
pd_status pd_run_file_sample(pd_file *out, const pd_sim *sim, const pd_energy *e);
/* The same with the damage of the step already taken (a frame's; NULL: the
 * row takes it). */
pd_status pd_run_file_sample_damage(pd_file *out, const pd_sim *sim, const pd_energy *e,
                                    const double *damage);
int pd_run_file_sample_due(const pd_file *out, int64_t step);
/* A run's time series as read (pd_read_series; pd_series_free). */
typedef struct {
    int ncols;
    char (*name)[PD_SERIES_NAME]; /* ncols column names                 */
    int64_t nrows;                /* complete rows                      */
    double *value;                /* nrows x ncols, row-major           */
} pd_series;
/* Read /series: its complete rows (/series@rows of them), checked: the
 * columns' names, a step column first, steps ascending.  PD_ERR_FORMAT
 * when the file has none (a run of a pd before the series). */
pd_status pd_read_series(const pd_file *f, pd_series *out);
void pd_series_free(pd_series *s);
/* The index of the column called `name`, or -1. */
int pd_series_column(const pd_series *s, const char *name);
/* Remove frames laid out but never completed. */
pd_status pd_drop_incomplete_frames(pd_file *f);
/* Write a frame (into its place when planned), then mark it complete;
 * the optional fields `ff` (may be NULL) go into strain_energy_density,
 * stress and von_mises. */
pd_status pd_write_frame(pd_file *f, const pd_particles *p, const pd_frame_info *fi,
                         double *const y[3], double *const v[3],
                         const uint64_t *intact, int64_t nbonds, const pd_frame_fields *ff);
/* The same for a part of the run (pd_sim_part): x, y, v, the bits and the
 * fields are the run's, local rows and bonds, of which the part's go into
 * the frame (on MPI ranks, every rank its own, at once). */
pd_status pd_write_frame_part(pd_file *f, const pd_part *pt, const pd_frame_info *fi,
                              double *const x[3], double *const y[3], double *const v[3],
                              const uint64_t *intact, const pd_frame_fields *ff);
/* Number of complete frames and their names in step order (none, from a
 * run killed before its first frame, is not an error; no /frames is);
 * caller frees with pd_frames_free_list.  Every reader of frames goes
 * through it, so it checks them (PD_ERR_FORMAT, one line naming the file
 * and the frame): in that order steps are non-negative and strictly
 * increasing, times finite and non-decreasing, and each time is
 * step x dt (the /scene dt, positive and finite) to 1e-9 relative:
 * |time - step dt| <= 1e-9 max(step, 1) dt (pd-run writes step * dt). */
pd_status pd_list_frames(const pd_file *f, int64_t *nframes, char ***names);
void pd_frames_free_list(int64_t nframes, char **names);
pd_status pd_read_frame_info(const pd_file *f, const char *name, pd_frame_info *fi);
/* A rigid sphere of a run at one frame, for drawing it. */
typedef struct {
    const char *name;   /* "indenter" or "projectile" */
    double centre[3];   /* m   */
    double radius;      /* m   */
    double velocity[3]; /* m/s */
} pd_frame_sphere;
/* The rigid spheres of a run at frame fi, into out[0..*n): the indenter
 * where pd-run puts it at the frame's step (pd_indenter_centre of its
 * /scene row), then the projectile where the frame's attributes say. */
pd_status pd_frame_spheres(const pd_file *f, const pd_frame_info *fi, pd_frame_sphere out[2],
                           int *n);
/* Per-particle fields of a frame: displacement and velocity (N,3) into SoA
 * arrays d[3] (any may be NULL to skip). */
pd_status pd_read_frame_vectors(const pd_file *f, const char *name, int64_t n,
                                double *disp[3], double *vel[3]);
/* The same of rows [g0, g0 + m) of the n alone. */
pd_status pd_read_frame_vectors_rows(const pd_file *f, const char *name, int64_t n, int64_t g0,
                                     int64_t m, double *disp[3], double *vel[3]);
/* Bond state bits of a frame (count bonds) into a words array. */
pd_status pd_read_frame_state(const pd_file *f, const char *name, int64_t count,
                              uint64_t *intact);
/* Bits [k0, k0 + count) of them into bits [at, at + count) of intact
 * (with at 0, intact cleared first; else its other bits left). */
pd_status pd_read_frame_state_rows(const pd_file *f, const char *name, int64_t k0, int64_t count,
                                   uint64_t *intact, int64_t at);
/* Optional scalar field (N) of a frame, e.g. "damage"; *present = 0 when
 * absent (not an error). */
pd_status pd_read_frame_scalar(const pd_file *f, const char *name, const char *field,
                               int64_t n, double *out, int *present);
/* Damage of a frame: its stored `damage` field, or else computed from its
 * bond state (pd_damage).  *b and *intact are read on first need and reused
 * for later frames; the caller frees them (pd_bonds_free, free). */
pd_status pd_read_frame_damage(const pd_file *f, const pd_particles *p, const char *frame,
                               pd_bonds **b, uint64_t **intact, double *damage);
/* Damage of a frame without the pre-crack: its stored `damage_run` field
 * (pd-damage --no-precrack), or else computed from its bond state
 * (pd_damage_no_precrack); *b and *intact as for pd_read_frame_damage.
 * When the file has no /bonds/precrack, *present = 0 and nothing is read. */
pd_status pd_read_frame_damage_run(const pd_file *f, const pd_particles *p, const char *frame,
                                   pd_bonds **b, uint64_t **intact, double *damage,
                                   int *present);
pd_status pd_write_frame_scalar(pd_file *f, const char *name, const char *field,
                                int64_t n, const double *values);
/* The stress field of a frame (9 n values, as pd_frame_fields.stress);
 * *present = 0 when absent. */
pd_status pd_read_frame_stress(const pd_file *f, const char *name, int64_t n, double *out,
                               int *present);

/* ---------------------------------------------------------------- VTK */

/* One VTK XML UnstructuredGrid (binary appended data, vertex cells) of a
 * frame: points at current positions, point data as given (NULL skips). */
typedef struct {
    int64_t n;
    double *const *position;      /* current positions, SoA          */
    double *const *displacement;  /* SoA                             */
    double *const *velocity;      /* SoA                             */
    const double *damage;
    const int32_t *material;
    const int64_t *id;
    const double *damage_run;     /* damage without the pre-crack    */
    const int64_t *select;        /* NULL: all n points; else only the
                                     nselect rows select[0..nselect-1]
                                     of the arrays above, in that order
                                     (e.g. a crack path)               */
    int64_t nselect;
    const uint8_t *front;         /* point data "front" (0/1), e.g.
                                     pd_crack_front; NULL skips        */
    int nextra;                   /* more point data:                */
    const struct pd_vtk_field *extra;
    int zlib_level;               /* 1-9: arrays compressed by zlib at
                                     that level (VTK's
                                     vtkZLibDataCompressor); 0: raw    */
} pd_vtk_frame;

/* The zlib level pd's programs write at unless told: on the seed disk
 * level 1 makes a frame 54% of its raw size at about 70 MB/s a core,
 * level 6 53% at a third of the speed. */
#define PD_VTK_ZLIB_LEVEL 1

/* A named point-data array of `ncomp` components per point, interleaved
 * (values[ncomp i + c]); 9 components is a tensor to ParaView. */
typedef struct pd_vtk_field {
    const char *name;
    int ncomp;
    const double *values;
} pd_vtk_field;

pd_status pd_vtk_write(const char *path, const pd_vtk_frame *fr);

/* A rigid sphere (pd_frame_sphere) as a VTK UnstructuredGrid of triangles
 * on its surface (482 points on 15 circles of latitude and the poles, 960
 * triangles, normals outward), with point data velocity, the sphere's own;
 * zlib_level as pd_vtk_frame's. */
pd_status pd_vtk_write_sphere(const char *path, const pd_frame_sphere *sphere, int zlib_level);

/* The complete frames of run file f described in XDMF at `path` (written
 * whole or not at all), for ParaView's XDMF Reader to read them from the
 * run file in place (lib/io/xdmf.c): the run file named `h5ref` in it, a
 * path relative to the folder of `path` or absolute, without ':'.
 * *nframes gets the frames described. */
pd_status pd_xdmf_write(const pd_file *f, const char *h5ref, const char *path,
                        int64_t *nframes);

/* A ParaView collection listing files (relative names) with their times,
 * parts (NULL: all part 0) and names of the parts (NULL, or a NULL entry:
 * none).  ParaView reads the files of one time as the blocks of one
 * dataset, block k holding part k under its name. */
pd_status pd_pvd_write(const char *path, int64_t nfiles, char *const *files, const double *times,
                       const int *parts, const char *const *names);

/* ---------------------------------------------------------------- crack tips */

/* Crack tip (seed 004 §5): the largest coordinate along `axis` (0, 1, 2 for
 * x, y, z) of the current positions x + u among particles whose damage
 * exceeds `threshold` (the seed's phi_0 = 0.3).  u may be NULL (reference
 * positions).  *ndamaged gets the number of such particles and *tip, in m,
 * NaN when there is none. */
pd_status pd_crack_tip(const pd_particles *p, double *const u[3], const double *damage, int axis,
                       double threshold, double *tip, int64_t *ndamaged);

/* Both tips of a crack along `axis` (a centre crack grows both ways): among
 * the particles with damage > threshold, *lower is the smallest and *upper
 * the largest current coordinate x + u along the axis (u NULL: reference
 * positions), in m, both NaN when there is none; *ndamaged counts them.
 * *upper is pd_crack_tip's tip.  A pre-crack counts like any other damage
 * when `damage` includes it (pd_damage): its ends are where growth starts. */
pd_status pd_crack_tips(const pd_particles *p, double *const u[3], const double *damage, int axis,
                        double threshold, double *lower, double *upper, int64_t *ndamaged);
/* Crack extension Delta a (seed 004 Fig. 7) of a tip series tip[0..n-1]
 * (frames in time order, NaN where no particle was damaged): with f the
 * first frame with a finite tip,
 *   da[k] = sign (tip[k] - tip[f])   for k >= f (NaN where tip[k] is NaN),
 *   da[k] = 0                         for k < f (no crack yet),
 * sign = +1 for an upper tip, -1 for a lower one, so that both grow
 * positive.  All zero when no frame has a tip. */
void pd_crack_extension(int64_t n, const double *tip, int sign, double *da);
/* Crack speed, m/s: speed[k] is the slope of the least-squares line
 * da = c0 + c1 t (gsl_fit_linear) through the frames j with |j - k| <=
 * window and finite time[j] and da[j] (fewer at the ends of the series);
 * NaN when da[k] is NaN, when fewer than two frames remain or when their
 * times are all equal.  A tip moving at a constant speed gets that speed
 * exactly (to rounding); on a lattice the window smooths the steps of one
 * spacing.  window >= 1. */
pd_status pd_crack_speed(int64_t n, const double *time, const double *da, int window,
                         double *speed);
/* The crack front of a 3-D body, the outline of the damaged zone:
 * front[i] = 1 when damage_i > threshold and at least one particle j of
 * i's reference family (every bond of b, intact or not) has damage_j <=
 * threshold; else 0.  *nfront counts the front. */
pd_status pd_crack_front(const pd_particles *p, const pd_bonds *b, const double *damage,
                         double threshold, uint8_t *front, int64_t *nfront);
/* The damaged cluster of the pre-crack (pd-crack-tip --connected): on
 * entry keep[i] = 1 where particle i may belong (all, or those inside a
 * region), on return keep[i] = 1 for the particles with damage > threshold,
 * allowed by keep, that are reached from a pre-cracked particle (one with a
 * bond of b->precrack; itself damaged and allowed) through such particles
 * in each other's reference families (every bond of b, intact or not, so
 * within the horizon); 0 elsewhere.  *nkept counts them.  PD_ERR_INVALID
 * when b has no pre-crack. */
pd_status pd_crack_connected(const pd_particles *p, const pd_bonds *b, const double *damage,
                             double threshold, uint8_t *keep, int64_t *nkept);
/* Measures of a front at the current positions y = x + u (u NULL:
 * reference positions).  With from_axis, r is the distance of y from the
 * line through `center` along `axis` (the radius of a ring or penny crack
 * around that axis); otherwise its distance from the point `center`. */
typedef struct {
    int64_t n;     /* particles on the front                               */
    double r_max;  /* largest r over the front, m (NaN when n = 0)          */
    double r_mean; /* mean r over the front, m (NaN when n = 0)             */
    double lo, hi; /* smallest and largest y along `axis`, m (NaN: n = 0)   */
} pd_crack_front_info;
pd_status pd_crack_front_stats(const pd_particles *p, double *const u[3], const uint8_t *front,
                               const double center[3], int axis, int from_axis,
                               pd_crack_front_info *fi);

/* ---------------------------------------------------------------- utilities */

/* Checked number parsing: whole string, finite. */
int pd_parse_double(const char *s, double *out);
int pd_parse_int64(const char *s, int64_t *out);
/* Comma list of exactly n doubles. */
int pd_parse_doubles(const char *s, double *out, int n);
/* The command line as one line of history (quoted where needed); free it. */
char *pd_join_argv(int argc, char **argv);
/* A scene file as long options: "option value" lines become "--option",
 * "value"; `#` starts a comment.  *argv and its strings are malloc'ed;
 * with `lines`, so is *lines, the line of the file each of them came from. */
pd_status pd_scene_args(const char *path, int *argc, char ***argv, int **lines);
/* Physical memory of this machine, bytes (a large guess if unknown). */
double pd_memory_bytes(void);
/* The same from a scene's text (the /scene/options of a run). */
pd_status pd_scene_args_text(const char *text, const char *name, int *argc, char ***argv,
                             int **lines);
/* Wall clock, s. */
double pd_wtime(void);
/* The sum of x[0..n-1] in fixed chunks of PD_SUM_CHUNK, summed in order
 * (the chunks in parallel): the same bits at any thread count. */
#define PD_SUM_CHUNK 4096
double pd_sum_fixed(const double *x, int64_t n);
/* The calling thread's share [*lo, *hi) of n items in a parallel region:
 * equal contiguous parts, as OpenMP's static schedule cuts a loop (all of
 * them outside one). */
void pd_thread_share(int64_t n, int64_t *lo, int64_t *hi);
/* Room for `need` elements of `size` bytes in *a, which holds *room of
 * them: grown by realloc (to a quarter more than asked) when short.
 * Returns 1, or 0 out of memory (*a and *room as they were). */
int pd_grow(void **a, int64_t *room, int64_t need, size_t size);
/* The Levenshtein distance between a[0..la) and b[0..lb): the fewest
 * insertions, deletions and substitutions that turn one into the other
 * (the nearest option to a typo); lengths up to 63, longer ones are far. */
size_t pd_edit_distance(const char *a, size_t la, const char *b, size_t lb);
/* mkdir -p: create `dir` and its missing parents (mode 0777 less the
 * umask); an existing path must be a directory.  PD_ERR_IO naming it. */
pd_status pd_make_dirs(const char *dir);
/* The indenter's centre at step n, m: c0 + (n dt) v, as pd-run moves it
 * (the evaluation order of the LAMMPS example, fix indent with
 * y0 + (step dt) v). */
void pd_indenter_centre(const double c0[3], const double v[3], int64_t step, double dt,
                        double c[3]);
/* Peak resident memory of this process, bytes (0 if unknown). */
int64_t pd_peak_rss(void);

#endif
