/*
 * sim.h -- internal: the state of a run and the effect table.  A run's step
 * is assembled from the effects its scene declares; an effect that is not
 * declared has no state and costs nothing.
 */
#ifndef PD_SIM_H
#define PD_SIM_H

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
} pd_effect;

/* Where pd_effect.constrain is called: in pd_sim_setup before the first
 * forces, and in pd_sim_step after the first half kick, after the drift
 * (step and time already n+1, before the forces) and after the second
 * half kick. */
enum { PD_PHASE_SETUP, PD_PHASE_KICK1, PD_PHASE_DRIFT, PD_PHASE_KICK2 };

/* Deterministic parallel sums: fixed chunks, summed in order. */
#define PD_SUM_CHUNK 4096
double pd_sum_fixed(const double *x, int64_t n);

#define PD_MAX_EFFECTS 8

typedef struct pd_grid pd_grid; /* lib/grid.c */

/* The bonds of a run, each stored once (i < j), as the PMB kernel walks
 * them; the directed bonds of the file are expanded from it on demand. */
typedef struct {
    int64_t n;         /* particles                                      */
    int64_t count;     /* bonds                                          */
    int64_t *offset;   /* n+1 CSR offsets                                */
    int32_t *neighbor; /* j > i, ascending                               */
    double *length;    /* |xi|, m                                        */
    double *w_ij;      /* c V_j nu_ij: force density on i per stretch    */
    double *w_ji;      /* c V_i nu_ji: force density on j per stretch
                          (the same array as w_ij when they are equal)   */
    uint64_t *intact;  /* mu per bond                                    */
    int64_t block;     /* rows per block (>= the largest j - i)          */
    int64_t nblocks;
    double *released;  /* nblocks: energy of the bonds broken in a block
                          in this step, J (summed in block order)        */
    int64_t *cursor;   /* scratch of pd_half_expand                      */
    double *kfail;     /* per bond s00_bond / s00: the bond breaks at
                          kfail min(s0_i, s0_j) (lib/materials.c); NULL:
                          all 1, the kernel of old                       */
    uint64_t epoch;    /* bumped when `intact` is changed from outside the
                          kernels (a restart, a lost particle)           */
} pd_half_bonds;

/* The half bonds of b: rows, partners and state (what every kernel needs);
 * pd_half_weights adds the lengths and the weights c V nu that the bond
 * list of PMB walks (not needed by the lattice stencil nor by LPS). */
pd_status pd_half_build(const pd_bonds *b, pd_half_bonds *h);
pd_status pd_half_weights(const pd_particles *p, const pd_bonds *b, double c, pd_half_bonds *h);
void pd_half_free(pd_half_bonds *h);
/* The half bonds' bits from directed state bits (the file's), and back. */
void pd_half_set_state(pd_half_bonds *h, const pd_bonds *b, const uint64_t *intact);
void pd_half_expand(pd_half_bonds *h, const pd_bonds *b, uint64_t *intact);

/* Hot loops are compiled for AVX-512, AVX2 and the baseline, picked at run
 * time (GCC function multiversioning), so one binary runs anywhere. */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(PD_NO_CLONES)
#define PD_VECTOR_CLONES \
    __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define PD_VECTOR_CLONES
#endif

struct pd_sim {
    const pd_particles *p;
    const pd_bonds *b;
    pd_scene sc;
    int64_t n;
    double *y[3];       /* current positions, m                          */
    double *v[3];       /* velocities, m/s                               */
    double *f[3];       /* force densities, N/m^3                        */
    pd_half_bonds half; /* the bonds as the kernel walks them             */
    pd_grid *grid;      /* the same as a lattice stencil, or NULL         */
    uint64_t *intact;   /* directed bond state bits mu (1 = intact), kept
                           up to date from `half` on demand              */
    int intact_stale;   /* `intact` lags behind half.intact              */
    double *s0;         /* critical stretch of the previous step (eq. 9) */
    double *s0_new;     /* being computed in this step                   */
    int64_t step;
    double time;        /* s                                             */
    double power;       /* power put in by the effects at this step's
                           force evaluation, W                           */
    double work;        /* its time integral (trapezoidal), J            */
    double released;    /* energy of the bonds broken so far, J          */
    double energy0;     /* kinetic + elastic + contact at step 0, J      */
    double box_lo[3];   /* a particle outside [box_lo, box_hi] is lost, m */
    double box_hi[3];
    uint8_t *lost;      /* n flags, NULL until the first loss            */
    int64_t nlost;
    double lost_energy; /* kinetic energy of the lost particles, J       */
    int setup;          /* 1 while computing the forces of the initial state */
    const pd_effect *effects[PD_MAX_EFFECTS];
    void *state[PD_MAX_EFFECTS];
    int neffects;
    char names[256];
    double timers[PD_T_COUNT];
    int64_t contact_builds;
    int constrained;    /* some effect has a constrain hook              */
    int f_zeroed;       /* the drift pass has zeroed f for the next forces */
    /* the projectile (lib/projectile.c), a rigid sphere of mass
     * sc.proj_mass, integrated with the particles                     */
    int has_projectile;
    double proj_x[3];   /* centre, m                                     */
    double proj_v[3];   /* velocity, m/s                                 */
    double proj_f[3];   /* force on it at the last force evaluation, N   */
};

/* A rigid sphere (centre c, radius R, m) pushing the particles inside it,
 * r = |y_i - c| < R, with the force density K (R - r)^2 (y_i - c)/r (LAMMPS
 * fix indent; K in N/m^5), lost particles left out: adds to sim->f and
 * returns in F the sum of V_i f_i, N, summed in fixed chunks (the same at
 * any thread count).  The indenter and the projectile (lib/indenter.c). */
void pd_sphere_push(pd_sim *sim, const double c[3], double R, double K, double F[3]);
/* Its penalty energy V_i K (R - r)^3 / 3, J, added to e[i]. */
void pd_sphere_energy(const pd_sim *sim, const double c[3], double R, double K, double *e);
/* The PMB bond stiffness sum of seed 004 eq. 46 of particle i,
 * sum_p V_p nu c / |xi| over its family, N/m^4 per unit volume (lib/pmb.c). */
double pd_bond_stiffness(const pd_particles *p, const pd_bonds *b, double c, int64_t i);

/* Per-bond laws (lib/materials.c): w_ij and w_ji with each bond's own c,
 * and kfail when the scene has failure; for pd_scene_has_laws only. */
pd_status pd_half_laws(const pd_particles *p, const pd_bonds *b, const pd_scene *s,
                       pd_half_bonds *h);
/* pd_bond_stiffness with each bond's own c. */
double pd_bond_stiffness_laws(const pd_particles *p, const pd_bonds *b, const pd_scene *s,
                              int64_t i);

/* Break every bond of particle i (both halves). */
void pd_half_break_all(pd_half_bonds *h, const pd_bonds *b, int64_t i);
/* The half bond i-j (i < j): its index, or -1 when there is none. */
int64_t pd_half_find(const pd_half_bonds *h, int64_t i, int64_t j);

/* The PMB bonds of a body on a lattice, walked as a stencil (lib/grid.c).
 * pd_grid_new leaves *out NULL when the scene or the body does not allow
 * it (then lib/pmb.c's bond list serves). */
pd_status pd_grid_new(pd_sim *sim, pd_grid **out);
void pd_grid_free(pd_grid *g);
/* The PMB forces (and with `failure` the breaking test and s0), and the
 * contact forces of the stencil pairs when the scene has contact. */
pd_status pd_grid_pmb(pd_sim *sim, int failure);
/* Half-stencil offsets (0: no grid); are its rows walked in AVX-512
 * tiles; does the kernel take the contact of the stencil pairs; is i-j a
 * stencil pair. */
int pd_grid_offsets(const pd_grid *g);
int pd_grid_tiles(const pd_grid *g);
/* The shortest reference distance of a pair that is not a stencil pair,
 * m (lib/contact.c searches only particles that moved enough to close
 * it). */
double pd_grid_gap(const pd_grid *g);
/* The largest damage of a particle (seed 000 eq. 10), counted on the
 * stencil's masks in parallel: 1 when *max_damage is set, 0 when the grid
 * cannot tell (none, or its masks lag behind the half bonds). */
int pd_grid_max_damage(const pd_sim *sim, double *max_damage);
int pd_grid_contact(const pd_grid *g);
int pd_grid_pair(const pd_grid *g, int64_t i, int64_t j);
/* LPS on the stencil (lib/lps.c without ellipsoids, particles in lattice
 * order): theta of Algorithm 4 into theta (m: the weighted volumes), the
 * forces of Algorithm 2 and with failure the test and s0_new; each broken
 * bond i-j (i < j) goes to mark(ctx, i, j), its stencil bit already
 * cleared. */
pd_status pd_grid_lps(pd_sim *sim, const double *m, double *theta, int failure,
                      void (*mark)(void *ctx, int64_t i, int64_t j), void *ctx);
/* The bonds' elastic energy, J, added to e[i]. */
void pd_grid_pmb_energy(const pd_sim *sim, double *e);
/* The contact energy of the stencil pairs, J, added to e[i]. */
void pd_grid_contact_energy(const pd_sim *sim, double *e);

pd_status pd_contact_restore(pd_sim *sim, void *state, double *const yb[3], int64_t builds);
double *const *pd_contact_positions(void *state);

extern const pd_effect pd_effect_pmb;
extern const pd_effect pd_effect_pmb_failure;
extern const pd_effect pd_effect_contact;
extern const pd_effect pd_effect_indenter;
extern const pd_effect pd_effect_body_force;
extern const pd_effect pd_effect_prescribed;
extern const pd_effect pd_effect_lps;
extern const pd_effect pd_effect_lps_failure;
extern const pd_effect pd_effect_projectile;
extern const pd_effect pd_effect_ves;
extern const pd_effect pd_effect_ves_failure;
extern const pd_effect pd_effect_eps;
extern const pd_effect pd_effect_eps_failure;

/* The projectile's half kick V += dt/(2M) F (1 when V is not finite) and
 * its drift X += dt V, in step with the particles'. */
int pd_projectile_kick(pd_sim *sim);
void pd_projectile_drift(pd_sim *sim);

#endif
