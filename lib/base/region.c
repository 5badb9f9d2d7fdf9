/*
 * region.c -- geometric regions that pd-lattice fills: box, cylinder,
 * sphere, and a closed surface (surface.c).  The inside tests follow LAMMPS `region` (closed sets; the cylinder
 * and sphere compare a square root with the radius), so a lattice made here
 * holds exactly the sites LAMMPS `create_atoms` makes.
 */
#include <math.h>
#include <string.h>

#include "pd.h"

static pd_status parse_cylinder(const char *spec, pd_region *r)
{
    /* AXIS,C1,C2,R,LO,HI */
    const char *comma = strchr(spec, ',');
    if (comma == NULL || comma - spec != 1 || !strchr("xyz", spec[0]))
        return pd_fail(PD_ERR_INVALID,
                       "cylinder '%s': expected AXIS,C1,C2,R,LO,HI with AXIS x, y or z", spec);
    r->axis = spec[0] - 'x';
    if (!pd_parse_doubles(comma + 1, r->p, 5))
        return pd_fail(PD_ERR_INVALID, "cylinder '%s': expected AXIS,C1,C2,R,LO,HI", spec);
    if (!(r->p[2] > 0))
        return pd_fail(PD_ERR_INVALID, "cylinder '%s': radius must be positive", spec);
    if (!(r->p[4] >= r->p[3]))
        return pd_fail(PD_ERR_INVALID, "cylinder '%s': LO must not exceed HI", spec);
    return PD_OK;
}

pd_status pd_region_parse(pd_region_kind kind, const char *spec, pd_region *r)
{
    memset(r, 0, sizeof *r);
    r->kind = kind;
    switch (kind) {
    case PD_REGION_BOX:
        if (!pd_parse_doubles(spec, r->p, 6))
            return pd_fail(PD_ERR_INVALID, "box '%s': expected XLO,XHI,YLO,YHI,ZLO,ZHI", spec);
        for (int d = 0; d < 3; d++)
            if (!(r->p[2 * d + 1] >= r->p[2 * d]))
                return pd_fail(PD_ERR_INVALID, "box '%s': a lower bound exceeds its upper bound",
                               spec);
        return PD_OK;
    case PD_REGION_CYLINDER:
        return parse_cylinder(spec, r);
    case PD_REGION_SURFACE:
        return pd_fail(PD_ERR_INVALID, "a surface region is read from its file, not parsed");
    case PD_REGION_SPHERE:
        if (!pd_parse_doubles(spec, r->p, 4))
            return pd_fail(PD_ERR_INVALID, "sphere '%s': expected X,Y,Z,R", spec);
        if (!(r->p[3] > 0))
            return pd_fail(PD_ERR_INVALID, "sphere '%s': radius must be positive", spec);
        return PD_OK;
    }
    return pd_fail(PD_ERR_INVALID, "unknown region kind");
}

pd_status pd_region_parse_tagged(const char *spec, pd_region *r)
{
    static const struct { const char *name; pd_region_kind kind; } kinds[] = {
        {"box,", PD_REGION_BOX}, {"cylinder,", PD_REGION_CYLINDER}, {"sphere,", PD_REGION_SPHERE}};
    for (size_t k = 0; k < sizeof kinds / sizeof kinds[0]; k++) {
        size_t len = strlen(kinds[k].name);
        if (strncmp(spec, kinds[k].name, len) == 0)
            return pd_region_parse(kinds[k].kind, spec + len, r);
    }
    return pd_fail(PD_ERR_INVALID, "region '%s': expected box,..., cylinder,... or sphere,...",
                   spec);
}

int pd_region_inside(const pd_region *r, const double x[3])
{
    switch (r->kind) {
    case PD_REGION_BOX:
        return x[0] >= r->p[0] && x[0] <= r->p[1] && x[1] >= r->p[2] && x[1] <= r->p[3] &&
               x[2] >= r->p[4] && x[2] <= r->p[5];
    case PD_REGION_CYLINDER: {
        /* c1, c2 are the axis position in the other two dimensions, in
         * x, y, z order (LAMMPS region cylinder). */
        int a = r->axis, u = (a == 0) ? 1 : 0, w = (a == 2) ? 1 : 2;
        double d1 = x[u] - r->p[0], d2 = x[w] - r->p[1];
        double dist = sqrt(d1 * d1 + d2 * d2);
        return dist <= r->p[2] && x[a] >= r->p[3] && x[a] <= r->p[4];
    }
    case PD_REGION_SPHERE: {
        double dx = x[0] - r->p[0], dy = x[1] - r->p[1], dz = x[2] - r->p[2];
        return sqrt(dx * dx + dy * dy + dz * dz) <= r->p[3];
    }
    case PD_REGION_SURFACE:
        return pd_surface_inside(r->surface, x);
    }
    return 0;
}

void pd_region_bounds(const pd_region *r, double lo[3], double hi[3])
{
    switch (r->kind) {
    case PD_REGION_BOX:
        for (int d = 0; d < 3; d++) {
            lo[d] = r->p[2 * d];
            hi[d] = r->p[2 * d + 1];
        }
        break;
    case PD_REGION_CYLINDER: {
        int a = r->axis, u = (a == 0) ? 1 : 0, w = (a == 2) ? 1 : 2;
        lo[a] = r->p[3];
        hi[a] = r->p[4];
        lo[u] = r->p[0] - r->p[2];
        hi[u] = r->p[0] + r->p[2];
        lo[w] = r->p[1] - r->p[2];
        hi[w] = r->p[1] + r->p[2];
        break;
    }
    case PD_REGION_SPHERE:
        for (int d = 0; d < 3; d++) {
            lo[d] = r->p[d] - r->p[3];
            hi[d] = r->p[d] + r->p[3];
        }
        break;
    case PD_REGION_SURFACE:
        pd_surface_bounds(r->surface, lo, hi);
        break;
    }
}
