/*
 * model.h -- internal (lib/models/): what the models share with the
 * effects and the run.
 */
#ifndef PD_MODEL_H
#define PD_MODEL_H

#include <stddef.h>

#include "state/sim.h"
#include "stencil/grid.h"

/* A number of the scene that only some models take: its option (pd-run
 * --OPTION, and the line of the resolved scene), its /scene attribute,
 * and where pd_scene holds it. */
typedef struct {
    const char *option, *attr;
    size_t offset; /* offsetof(pd_scene, ...), a double */
} pd_model_param;

/* A material model: one descriptor per model, in the model's own file, and
 * one entry in the table of lib/models/model.c.  Nothing outside the
 * model's file asks which model a scene has: it asks the descriptor. */
struct pd_model {
    const char *name;        /* --model NAME, /scene@model                  */
    pd_model_kind kind;
    int state_based;         /* takes K, G and an influence function (seed
                                000 eqs. 3-4), 3-D only                      */
    /* Its force in the step's effect table, without and with failure. */
    const pd_effect *force, *force_failure;
    /* The stable step of seed 004 eq. 46 (or its analogue), s. */
    double (*stable_dt)(const pd_particles *p, const pd_bonds *b, const pd_scene *s);
    /* The stencil that can walk the scene's bonds (any body; lib/stencil/
     * checks the body). */
    pd_stencil_kind (*stencil)(const pd_scene *s);
    int dissipative;         /* 1: it dissipates energy the balance does not
                                book (a dashpot, plastic flow), so the energy
                                alarm watches gains only                    */
    int history_width;       /* doubles per directed bond it keeps from step
                                to step (a restart's bond history); 0: none */
    /* Its own long options (NULL-terminated): those it needs, those it
     * takes besides (any other model refuses them). */
    const char *const *needs;
    const char *const *takes;
    unsigned fields;         /* the PD_FIELD_* it can write into frames      */
    const pd_model_param *params; /* its own numbers (option, attribute),
                                     ended by a NULL option; NULL: none    */
    /* One line on the model and its constants for a run's log (NULL:
     * nothing to say beyond the moduli). */
    void (*describe)(const pd_scene *s, char *text, size_t len);
};

/* The models' descriptors (their files) and the table over them. */
extern const pd_model pd_model_pmb, pd_model_lps, pd_model_ves, pd_model_eps;

/* The PMB bond stiffness sum of seed 004 eq. 46 of particle i,
 * sum_p V_p nu c / |xi| over its family, N/m^4 per unit volume (lib/models/pmb.c). */
double pd_bond_stiffness(const pd_particles *p, const pd_bonds *b, double c, int64_t i);

/* Per-bond laws (lib/models/materials.c): w_ij and w_ji with each bond's own c,
 * and kfail when the scene has failure; for pd_scene_has_laws only. */
pd_status pd_half_laws(const pd_particles *p, const pd_bonds *b, const pd_scene *s,
                       pd_half_bonds *h);
/* pd_bond_stiffness with each bond's own c. */
double pd_bond_stiffness_laws(const pd_particles *p, const pd_bonds *b, const pd_scene *s,
                              int64_t i);
/* The lengths and the weights c V nu of the half bonds that PMB's bond list
 * walks (not needed by the lattice stencil nor by LPS). */
pd_status pd_half_weights(const pd_particles *p, const pd_bonds *b, double c, pd_half_bonds *h);

/* The contact energy of the pairs the AVX-512 rows take (sim->half.contact;
 * nothing otherwise), half of each pair to each end, as lib/effects/contact.c
 * counts its list's: e_i += sum_j 1/4 (c_S/delta) (d_ij - r)^2 V_i V_j over
 * i's family (lib/models/pmb.c). */
void pd_half_contact_energy(const pd_sim *sim, double *e);

/* The AVX-512 rows' contact cap over the particles p (the whole body's,
 * also for a piece of it): 1.35 (r_i + r_j) when every node radius is the
 * same, else +inf, m. */
double pd_half_contact_cap(const pd_particles *p);

/* The models' forces in the step's effect table. */
extern const pd_effect pd_effect_pmb;
extern const pd_effect pd_effect_pmb_failure;
extern const pd_effect pd_effect_lps;
extern const pd_effect pd_effect_lps_failure;
extern const pd_effect pd_effect_ves;
extern const pd_effect pd_effect_ves_failure;
extern const pd_effect pd_effect_eps;
extern const pd_effect pd_effect_eps_failure;

#endif
