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

struct pd_sim {
    const pd_particles *p;
    const pd_bonds *b;
    pd_scene sc;
    int64_t n;
    double *y[3];       /* current positions, m                          */
    double *v[3];       /* velocities, m/s                               */
    double *f[3];       /* force densities, N/m^3                        */
    uint64_t *intact;   /* bond state bits mu (1 = intact)               */
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
