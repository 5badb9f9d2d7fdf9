/*
 * surface_io.c -- a closed surface in a file: /surface/points (P,3)
 * float64 and /surface/triangles (T,3) int64, as pd-mesh --surface writes
 * it for pd-lattice --inside (man 5 pd-h5).
 */
#include <stdlib.h>

#include "io/h5util.h"

int pd_file_has_surface(const pd_file *f)
{
    return pd_h5_has_link(f->fid, "/surface");
}

pd_status pd_read_surface(const pd_file *f, pd_surface **out)
{
    *out = NULL;
    const char *fn = f->name;
    if (!pd_h5_has_link(f->fid, "/surface"))
        return pd_fail(PD_ERR_FORMAT, "'%s' holds no /surface (write one with pd-mesh --surface)",
                       fn);
    pd_h5_form pf = {H5T_FLOAT, 8, 2, {0, 3}}, tf = {H5T_INTEGER, 8, 2, {0, 3}};
    double *x = NULL;
    int64_t *tri = NULL;
    hsize_t pd[2] = {0, 0}, td[2] = {0, 0};
    pd_status s = pd_h5_read_data(f->fid, fn, "/surface/points", &pf, H5T_NATIVE_DOUBLE,
                                  sizeof *x, (void **)&x, pd);
    if (s == PD_OK)
        s = pd_h5_read_data(f->fid, fn, "/surface/triangles", &tf, H5T_NATIVE_INT64, sizeof *tri,
                            (void **)&tri, td);
    if (s == PD_OK && (s = pd_surface_new((int64_t)pd[0], x, (int64_t)td[0], tri, out)) != PD_OK)
        s = pd_fail(PD_ERR_FORMAT, "'%s': %s", fn, pd_errmsg());
    free(x);
    free(tri);
    return s;
}
