/*
 * sites.h -- internal (lib/bonds/): particles on their lattice sites, the
 * site map that finds the particle at a site, and the walk of a family
 * off a stencil (family.c); stencil.c builds on them.
 */
#ifndef PD_SITES_H
#define PD_SITES_H

#include <math.h>

#include "pd.h"

typedef struct {
    int32_t *c[3];   /* site of particle i along x, y, z                  */
    int32_t lo[3];   /* the bounding box's lowest site                    */
    int64_t dim[3];  /* its sites per axis                                */
    int32_t *map;    /* dim[0] dim[1] dim[2]: the particle at a site, or -1 */
    int ax[3];       /* outer, mid, inner axis of the particles' order, or
                        ax[0] = -1: the rows follow no lattice order      */
} site_map;

typedef enum { SITES_OK, SITES_OFF, SITES_SPARSE, SITES_SHARED, SITES_NOMEM } sites_result;

void pd_sites_free(site_map *m);
/* The sites of p's particles on the lattice (origin, h) and their map;
 * *shared gets a particle whose site another one holds (SITES_SHARED). */
sites_result pd_sites_build(const pd_particles *p, const double origin[3], double h, site_map *m,
                            int64_t *shared);
/* The offsets in the order that makes every family come out sorted by
 * partner when the rows are in lattice order (m->ax); the table's own
 * order otherwise.  NULL: out of memory. */
int32_t (*pd_sites_walk_order(const pd_stencil *st, const site_map *m))[3];
/* The length and partial-volume factor of bond i-j, as pd_bonds_build
 * computes them. */
static inline void pd_bond_geometry(const pd_particles *p, int64_t i, int64_t j, double horizon,
                                 double *len, double *nu)
{
    double dx = p->x[0][i] - p->x[0][j], dy = p->x[1][i] - p->x[1][j],
           dz = p->x[2][i] - p->x[2][j];
    *len = sqrt(dx * dx + dy * dy + dz * dz);
    *nu = pd_partial_volume(*len, horizon, p->radius[j]);
}

/* The particle at site c_i + d, or -1. */
static inline int32_t pd_site_partner(const site_map *m, int64_t i, const int32_t d[3])
{
    int64_t s[3];
    for (int a = 0; a < 3; a++) {
        s[a] = (int64_t)m->c[a][i] + d[a] - m->lo[a];
        if (s[a] < 0 || s[a] >= m->dim[a])
            return -1;
    }
    return m->map[(s[2] * m->dim[1] + s[1]) * m->dim[0] + s[0]];
}

/* What a compact family walks: the site map and the offsets in walk
 * order (sorted partners: the rows are in a lattice order). */
struct pd_bond_sites {
    site_map m;     /* the sites and their map: freed once padded      */
    int32_t (*d)[3];
    int nk;
    int64_t *delta; /* nk: each offset's step in `pad`'s index           */
    int32_t *pad;   /* the map with a margin of the offsets' reach on each
                       side (-1 there): particle i's partner at offset k
                       is pad[at[i] + delta[k]], never out of bounds    */
    int64_t *at;    /* n: each particle's index in `pad`                 */
    double dev;     /* the largest distance of a particle from its site, m */
    double xmax;    /* the largest |coordinate| of a particle, m         */
};

#endif
