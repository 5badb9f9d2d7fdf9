/*
 * sim.h -- internal: the state of a run and the effect table.  A run's step
 * is assembled from the effects its scene declares; an effect that is not
 * declared has no state and costs nothing.
 */
#ifndef PD_SIM_H
#define PD_SIM_H

#include "bonds/half.h"
#include "pd.h"

typedef struct pd_effect {
    const char *name;  /* as listed in the log and /scene/effects   */
    pd_timer timer;    /* where its time is booked                  */
    /* Allocate the effect's state (may stay NULL). */
    pd_status (*init)(pd_sim *sim, void **state);
    /* Add the effect's force density to sim->f (and the power it puts in
     * to sim->power). */
    pd_status (*force)(pd_sim *sim, void *state);
    void (*free)(void *state);
    /* Add each particle's share of the effect's potential energy, J, to
     * e[i]; NULL: none.  `kind` says where pd_energy books it. */
    void (*energy)(const pd_sim *sim, void *state, double *e);
    enum { PD_ENERGY_ELASTIC, PD_ENERGY_CONTACT } kind;
    /* Add each particle's peridynamic stress from the effect's bonds, Pa,
     * to s[9i + 3a + b] (pd_sim_stress); NULL: the effect adds none. */
    void (*stress)(const pd_sim *sim, void *state, double *s);
    /* Hold prescribed motion at a phase of the step (pd_phase); NULL:
     * none.  The work it does goes into sim->work. */
    pd_status (*constrain)(pd_sim *sim, void *state, int phase);
    /* Does the scene declare it?  (The effects of lib/effects/effects.c's
     * table; a model's force is chosen by its descriptor instead.) */
    int (*declared)(const pd_scene *s);
    /* Its own motion, in step with the particles': a half kick (`second`:
     * the one after the forces, which fails when its state is not finite)
     * and the drift; NULL: none. */
    pd_status (*kick)(pd_sim *sim, void *state, int second);
    void (*drift)(pd_sim *sim, void *state);
    /* What a restart needs of it beyond the particles' state: into the
     * restart data (pointing into the run), and back; NULL: nothing. */
    void (*save)(const pd_sim *sim, void *state, pd_restart *r);
    pd_status (*restore)(pd_sim *sim, void *state, const pd_restart *r);
    /* Add each particle's share of the force the effect applies to hold
     * or load it, N, to r[a][i]: the reaction of a boundary condition
     * (pd_sim_series_row sums it over each set); NULL: none. */
    void (*reaction)(const pd_sim *sim, void *state, double *const r[3]);
    /* On MPI ranks, after the drift: this rank's yes or no to the
     * effect's question of the new positions (contact: has one of its own
     * particles moved enough for the list to be rebuilt), or-ed over the
     * ranks in the step's one reduction with the lost particles' and kept
     * in sim->moved for the effect's force; NULL: none. */
    int (*moved)(const pd_sim *sim, void *state);
} pd_effect;

/* Where pd_effect.constrain is called: in pd_sim_setup before the first
 * forces, and in pd_sim_step after the first half kick, after the drift
 * (step and time already n+1, before the forces) and after the second
 * half kick. */
enum { PD_PHASE_SETUP, PD_PHASE_KICK1, PD_PHASE_DRIFT, PD_PHASE_KICK2 };

#define PD_MAX_EFFECTS 8

typedef struct pd_grid pd_grid; /* lib/stencil/ */

/* What a bond kernel does besides the forces (pd_grid_pmb, pd_grid_lps and
 * the bond lists' kernels of lib/models/). */
typedef enum {
    PD_BONDS_ELASTIC = 0,    /* forces only: no bond breaks               */
    PD_BONDS_FAILURE = 1,    /* and the breaking test against min(s0_i,
                                s0_j) and the new s0 (seed 000 eqs. 8-9) */
    PD_BONDS_FAILURE_LAWS = 2 /* the same, each bond's threshold times its
                                kfail (lib/models/materials.c; the bond
                                list of PMB only)                        */
} pd_bond_mode;

/* Hot loops are compiled for AVX-512, AVX2 and the baseline, picked at run
 * time (GCC function multiversioning), so one binary runs anywhere. */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(PD_NO_CLONES)
#define PD_VECTOR_CLONES \
    __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define PD_VECTOR_CLONES
#endif

/* Kernels written in AVX-512 intrinsics (the stencil's tiles, lib/stencil/;
 * the bond list's rows, lib/models/pmb.c) are built for x86-64 with GCC or
 * clang and taken at run time where the processor has the instructions;
 * any other build walks the portable loops alone. */
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__)) && !defined(PD_NO_CLONES)
#define PD_AVX512_KERNELS 1
#include <immintrin.h>
#else
#define PD_AVX512_KERNELS 0
#endif

#if PD_AVX512_KERNELS
/* Eight bonds from their ends (partners xj, yj, zj; own yi0, yi1, yi2):
 * the bond vectors d = y_j - y_i, the lengths r and the extensions
 * e = r - L, 0 below eps_machine of extension (seed 000).  Every AVX-512
 * bond kernel takes its bonds so (the stencil's tiles, the bond list's
 * rows and lanes), operation for operation as their scalar loops. */
__attribute__((target("avx512f"))) static inline __attribute__((always_inline)) void
pd_bonds8(__m512d xj, __m512d yj, __m512d zj, __m512d yi0, __m512d yi1, __m512d yi2, __m512d L,
          __m512d d[3], __m512d *r, __m512d *e)
{
    d[0] = _mm512_sub_pd(xj, yi0);
    d[1] = _mm512_sub_pd(yj, yi1);
    d[2] = _mm512_sub_pd(zj, yi2);
    *r = _mm512_sqrt_pd(_mm512_add_pd(
        _mm512_add_pd(_mm512_mul_pd(d[0], d[0]), _mm512_mul_pd(d[1], d[1])),
        _mm512_mul_pd(d[2], d[2])));
    const __m512d x = _mm512_sub_pd(*r, L);
    *e = _mm512_mask_mov_pd(x,
                            _mm512_cmp_pd_mask(_mm512_abs_pd(x), _mm512_set1_pd(PD_NEAR_ZERO),
                                               _CMP_LT_OQ),
                            _mm512_setzero_pd());
}
#endif

/* A run's piece of a body spread over ranks (lib/run/piece.c, pd.h's
 * pd_sim_piece): which of its rows it owns, where they sit in the whole
 * body, and its halo.  Rows [0, own_lo) are ghosts owned by the rank
 * below, [own_hi, n) by the rank above. */
typedef struct pd_piece {
    int rank, ranks;
    int64_t n_whole;        /* rows of the whole body                       */
    int64_t first;          /* the whole body's row of local row 0          */
    int64_t own_lo, own_hi; /* local rows owned                             */
    int64_t blk0;           /* the whole body's block of local block 0      */
    int64_t own_blk_lo, own_blk_hi; /* local blocks owned                   */
    int64_t *rows;          /* ranks: rows each rank owns                    */
    int64_t *own_at;        /* ranks + 1: the whole body's first row each
                               rank owns, and n_whole                        */
    int64_t *piece_at;      /* 2 ranks: the whole body's rows [piece_at[2r],
                               piece_at[2r + 1]) of rank r's piece           */
    int64_t *blocks;        /* ranks: blocks each rank owns                  */
    int64_t send_down;      /* rows [own_lo, own_lo + send_down) are the
                               ghosts of the rank below                      */
    int64_t send_up;        /* rows [own_hi - send_up, own_hi), those of the
                               rank above                                    */
    double *buf;            /* the halo's buffers, 4 doubles a row           */
    double *sum3;           /* 3 n scratch doubles (pd_sphere_push's sums)   */
    /* how the piece's kernel is cut, as the whole body's (pd_sim_new) */
    int grid;               /* 1: the lattice stencil, 0: the bond list     */
    int64_t half_block;     /* the bond list's rows per block               */
    int axis[3];            /* the stencil's axes (inner, mid, outer)       */
    double origin[3];       /* its lattice's origin, m                      */
    const struct pd_grid *table; /* the whole body's stencil, whose offsets'
                               lengths and partial volumes the piece's takes
                               (each the first bond's of its offset: the
                               whole body's first, not the piece's)          */
    pd_particles *p;        /* the piece's particles and bonds (owned)      */
    pd_bonds *b;
    uint64_t *keep;         /* a piece cut in place from a window of the body
                               (pd_sim_piece_take): which of the window's
                               keep_count bonds it kept, a bit each, for a
                               restart's bond history; NULL once restored  */
    int64_t keep_count;
} pd_piece;

/* The state of a run.  Every per-particle array has n entries in the
 * rows of p (local indices; p->id holds the global ids). */
struct pd_sim;
/* May the bond i-j break, or is an end of it in a --no-failure set?
 * Asked only of a bond whose stretch breaks it. */
static inline int pd_sim_may_break(const struct pd_sim *sim, int64_t i, int64_t j);

struct pd_sim {
    const pd_particles *p;        /* the body (reference configuration), not owned */
    const pd_bonds *b;            /* its directed families: the caller's, or
                                     `own` when the kernels need the lists of
                                     compact families                          */
    pd_bonds *own;                /* NULL, or those lists (owned)               */
    pd_scene sc;                  /* the resolved scene, SI units (pd.h)        */
    const struct pd_model *model; /* the scene's model (lib/models/)            */
    int64_t n;                    /* particles, = p->n                          */
    double *y[3];       /* current positions, m                          */
    double *v[3];       /* velocities, m/s                               */
    double *f[3];       /* force densities, N/m^3                        */
    pd_half_bonds half; /* the bonds as the kernels walk them: each once,
                           with its state bit (lib/bonds/half.c)         */
    pd_grid *grid;      /* the same bonds as a lattice stencil
                           (lib/stencil/), or NULL                       */
    uint64_t *intact;   /* directed bond state bits mu (1 = intact), in
                           the order of b; kept up to date from `half`
                           on demand (pd_sim_intact)                     */
    int intact_stale;   /* 1: `intact` lags behind half.intact           */
    int (*directed_bits)(const pd_sim *sim, uint64_t *intact); /* writes
                           `intact` from a faster copy of the state than
                           the half bonds (the stencil's masks): 1, or 0
                           when it cannot; NULL: none                    */
    double *s0;         /* critical stretch of the previous step (seed
                           000 eq. 9), dimensionless; NULL without
                           failure                                       */
    double *s0_new;     /* the same, being computed in this step         */
    uint8_t *nofail;    /* n flags, 1: the particle is in a --no-failure
                           set and no bond of it breaks; NULL: no such
                           set (the kernels veto a break only where they
                           apply it, the rare path)                      */
    int64_t step;       /* steps taken                                   */
    double time;        /* step * sc.dt, s                               */
    double power;       /* power put in by the effects at this step's
                           force evaluation, W                           */
    double work;        /* its time integral (trapezoidal), J            */
    double released;    /* energy of the bonds broken so far, J (a piece:
                           but for rel_held's steps, pd_sim_released)    */
    double *rel_held;   /* a piece: its own blocks' energies of the bonds
                           broken in each of rel_steps steps (at most
                           PD_RELEASED_STEPS), not yet in `released`     */
    int64_t rel_steps;
    double energy0;     /* kinetic + elastic + contact at step 0, J      */
    double penalty0;    /* its contact share (pairs, overlaps), J        */
    double damped;      /* the energy --damping took so far, J           */
    double damp_power;  /* its power at this step's forces, W            */
    double box_lo[3];   /* a particle outside [box_lo, box_hi] is lost, m */
    double box_hi[3];   /* m                                             */
    uint8_t *lost;      /* n flags (1: lost), NULL until the first loss  */
    int64_t nlost;      /* lost particles so far                         */
    double lost_energy; /* kinetic energy of the lost particles, J       */
    int setup;          /* 1 while computing the forces of the initial state */
    int energy_next;    /* 1: the energies of the next force evaluation
                           are wanted (pd_sim_energy_next)               */
    const pd_effect *effects[PD_MAX_EFFECTS]; /* the step's table: the
                           model's force first, then the declared
                           effects (lib/effects/effects.c's order)       */
    void *state[PD_MAX_EFFECTS]; /* each effect's own state, or NULL     */
    int neffects;       /* entries of effects[] and state[]              */
    char names[256];    /* the effects' names, space-separated (the log,
                           /scene@effects)                               */
    double timers[PD_T_COUNT]; /* wall time per pd_timer, s               */
    int64_t contact_builds;    /* contact list builds so far             */
    int moved;          /* a piece: 0, or 1 + the ranks' answer to the
                           step's pd_effect.moved, for this step's forces */
    int64_t contact_remote;    /* a piece: the most contact partners one
                                  of its lists took from beyond it        */
    int constrained;    /* 1: some effect has a constrain hook           */
    int f_zeroed;       /* 1: the drift pass has zeroed f for the next
                           forces                                        */
    /* the projectile (lib/effects/projectile.c), a rigid sphere of mass
     * sc.proj_mass, integrated with the particles                     */
    int has_projectile; /* 1: the scene has one                          */
    double proj_x[3];   /* centre, m                                     */
    double proj_v[3];   /* velocity, m/s                                 */
    double proj_f[3];   /* force on it at the last force evaluation, N   */
    double ind_f[3];    /* the force on the indenter at the last force
                           evaluation, N (the body's push back)          */
    int nsets;          /* the scene's named sets (sc.sets), and the     */
    int64_t **set_rows; /* rows of each, for the time series             */
    uint8_t *held;      /* n flags, bit a: component a of the particle's
                           motion is prescribed (lib/effects/bc.c); NULL
                           when nothing is                               */
    struct pd_relax *relax; /* the relaxation's work arrays (lib/run/
                           relax.c), NULL until its first load step      */
    void (*relax_free)(struct pd_relax *r); /* and what frees them       */
    pd_relax_info relaxed;  /* what the last load step took              */
    pd_piece *piece;    /* NULL: the whole body on one rank; else this
                           rank's piece of it (lib/run/piece.c)          */
    int piece_owned;    /* 1: freed with the run                         */
};
static inline int pd_sim_may_break(const struct pd_sim *sim, int64_t i, int64_t j)
{
    return sim->nofail == NULL || !(sim->nofail[i] | sim->nofail[j]);
}


/* lib/run/sim.c, for relax.c: all force densities at the current
 * positions, and the effects' constrain hooks at a phase. */
pd_status pd_sim_compute_forces(pd_sim *sim);
pd_status pd_sim_constrain(pd_sim *sim, int phase);
/* lib/run/series.c, for relax.c too: the force each particle's boundary
 * conditions apply to it, N, into r (zeroed first); the indenter's centre
 * at the current time, m (as lib/effects/indenter.c places it; 0 without
 * one). */
void pd_sim_reactions(const pd_sim *sim, double *const r[3]);
/* lib/state/state.c: the energy of the bonds broken in a step, per block
 * of the kernel (nblocks, in block order), added to sim->released in the
 * whole body's block order (over the ranks, a piece's own blocks). */
void pd_sim_add_released(pd_sim *sim, const double *released, int64_t nblocks);
/* A piece keeps its own blocks' energies of PD_RELEASED_STEPS steps at
 * most and adds the ranks' together, in the order one rank adds them,
 * when sim->released is read (collective): pd_sim_released, before every
 * read of it.  One meeting point a step fewer. */
#define PD_RELEASED_STEPS 64
void pd_sim_released(const pd_sim *sim);
/* The sums of m per-row arrays of the run (x[c][0..n)) as pd_sum_fixed
 * takes them over the whole body: over the ranks, of the rows each piece
 * owns.  Every rank calls it and gets the same sums. */
void pd_sim_sum(const pd_sim *sim, const double *const *x, int m, double *sums);
/* lib/state/halo.c: a piece freed; for the step: the ghosts' positions (and s0, with
 * failure) from their owners; the ghosts' forces and velocities zeroed; n
 * values of each rank's (its own rows', in row order) added to *sum in
 * rank order, as one rank adds them in row order. */
pd_status pd_piece_halo(pd_sim *sim);
/* The ghosts' rows of m (at most 4) per-row arrays from their owners
 * (collective; a model's per-particle values mid-step: LPS's theta). */
void pd_piece_exchange(pd_sim *sim, double *const *a, int m);
void pd_piece_ghosts_rest(pd_sim *sim);
pd_status pd_piece_add_in_order(const pd_sim *sim, const double *v, int64_t n, double *sum);
void pd_piece_free(pd_piece *pc);
/* lib/run/sim.c, for lib/run/piece.c: pd_sim_new with the cut of a piece's
 * kernel taken from `piece` (NULL: its own); the box outside which a
 * particle of the body p is lost (its bounding box grown by lost_margin,
 * or when 0 by pd_lost_margin_default, on every side). */
pd_status pd_sim_new_cut(const pd_particles *p, const pd_bonds *b, const pd_scene *s,
                         pd_piece *piece, pd_sim **out);
void pd_lost_box(const pd_particles *p, double lost_margin, double lo[3], double hi[3]);
void pd_sim_indenter_centre(const pd_sim *sim, double c[3]);


#endif
