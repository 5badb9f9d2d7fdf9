/*
 * particles.c -- the particle arrays (structure of arrays) and their
 * lifecycle.
 */
#include <math.h>
#include <stdlib.h>

#include "base/comm.h"

pd_particles *pd_particles_new(int64_t n)
{
    pd_particles *p = calloc(1, sizeof *p);
    if (p == NULL)
        return NULL;
    p->n = n;
    size_t m = n > 0 ? (size_t)n : 1;
    for (int d = 0; d < 3; d++)
        p->x[d] = malloc(m * sizeof(double));
    p->volume = malloc(m * sizeof(double));
    p->density = malloc(m * sizeof(double));
    p->radius = malloc(m * sizeof(double));
    p->material = malloc(m * sizeof(int32_t));
    p->id = malloc(m * sizeof(int64_t));
    p->dimension = 3;
    p->total = p->own_hi = n;
    if (!p->x[0] || !p->x[1] || !p->x[2] || !p->volume || !p->density ||
        !p->radius || !p->material || !p->id) {
        pd_particles_free(p);
        return NULL;
    }
    return p;
}

void pd_particles_free(pd_particles *p)
{
    if (p == NULL)
        return;
    for (int d = 0; d < 3; d++)
        free(p->x[d]);
    free(p->volume);
    free(p->density);
    free(p->radius);
    free(p->material);
    free(p->id);
    free(p);
}

void pd_particles_bounds(const pd_particles *p, double lo[3], double hi[3])
{
    for (int d = 0; d < 3; d++) {
        lo[d] = INFINITY;
        hi[d] = -INFINITY;
        for (int64_t i = 0; i < p->n; i++) {
            lo[d] = fmin(lo[d], p->x[d][i]);
            hi[d] = fmax(hi[d], p->x[d][i]);
        }
    }
}

void pd_body_bounds(const pd_particles *p, double lo[3], double hi[3])
{
    pd_particles_bounds(p, lo, hi);
    if (p->window)
        pd_comm_box(lo, hi);
}

int64_t pd_body_count(const pd_particles *p)
{
    return p->window ? p->total : p->n;
}

double pd_body_max(const pd_particles *p, double v)
{
    return p->window ? pd_comm_max(v) : v;
}
