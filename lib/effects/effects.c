/*
 * effects.c -- the table of the effects a scene may declare, in the order
 * a run's step takes them (after the model's force): a new effect is its
 * file and an entry here.
 */
#include "effects/effect.h"

const pd_effect *const pd_effects[] = {&pd_effect_contact,    &pd_effect_indenter,
                                       &pd_effect_body_force, &pd_effect_prescribed,
                                       &pd_effect_projectile, &pd_effect_damping, NULL};
