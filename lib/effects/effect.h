/*
 * effect.h -- internal (lib/effects/): the effects' tables and what the
 * run calls of them.
 */
#ifndef PD_EFFECT_H
#define PD_EFFECT_H

#include "state/sim.h"

/* A rigid sphere (centre c, radius R, m) pushing the particles inside it,
 * r = |y_i - c| < R, with the force density K (R - r)^2 (y_i - c)/r (LAMMPS
 * fix indent; K in N/m^5), lost particles left out: adds to sim->f and
 * returns in F the sum of V_i f_i, N, summed in fixed chunks (the same at
 * any thread count).  The indenter and the projectile (lib/effects/indenter.c). */
void pd_sphere_push(pd_sim *sim, const double c[3], double R, double K, double F[3]);
/* Its penalty energy V_i K (R - r)^3 / 3, J, added to e[i]. */
void pd_sphere_energy(const pd_sim *sim, const double c[3], double R, double K, double *e);
extern const pd_effect pd_effect_contact;
extern const pd_effect pd_effect_indenter;
extern const pd_effect pd_effect_body_force;
extern const pd_effect pd_effect_prescribed;
extern const pd_effect pd_effect_projectile;
extern const pd_effect pd_effect_damping;

/* The declarable effects in step order, NULL-terminated (effects.c). */
extern const pd_effect *const pd_effects[];

#endif
