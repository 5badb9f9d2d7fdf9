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
    /* Add the effect's force density to sim->f. */
    pd_status (*force)(pd_sim *sim, void *state);
    void (*free)(void *state);
} pd_effect;

#define PD_MAX_EFFECTS 8

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
    uint64_t *intact;   /* bond state bits mu (1 = intact)               */
    double *bond_w;     /* per bond c V_j nu, N/m^3 (the force density of
                           a bond is bond_w * stretch)                    */
    double *s0;         /* critical stretch of the previous step (eq. 9) */
    double *s0_new;     /* being computed in this step                   */
    int64_t step;
    double time;        /* s                                             */
    int setup;          /* 1 while computing the forces of the initial state */
    const pd_effect *effects[PD_MAX_EFFECTS];
    void *state[PD_MAX_EFFECTS];
    int neffects;
    char names[256];
    double timers[PD_T_COUNT];
    int64_t contact_builds;
};

extern const pd_effect pd_effect_pmb;
extern const pd_effect pd_effect_pmb_failure;
extern const pd_effect pd_effect_contact;
extern const pd_effect pd_effect_indenter;

#endif
