/*
 * influence.c -- the influence functions of the state-based models: the
 * radial omega(|xi|) of seed 000 eq. 4 (1/|xi|, 1, a Gaussian; at the end
 * of this file), and the ellipsoidal (anisotropic) factor of seed 002.
 *
 * An ellipsoid centred at the origin has its major semi-axis, of length 1,
 * along the preferred direction u, and the semi-axes a and b (fractions of
 * it, in (0, 1]) along v and w.  In its own frame (u, v, w on x, y, z) a
 * point d e' of the surface satisfies eq. 12, so the distance from the
 * centre to the surface along a unit direction e' is (eq. 13)
 *   d = 1 / sqrt(e'_x^2 + e'_y^2/a^2 + e'_z^2/b^2),
 * 1 along u, a along v, b along w.  The frame is the rotation (eq. 7)
 *   M = M_Y M_P M_R,   e' = M^-1 e,
 * with the yaw Y about z, the pitch P about -y (positive P lifts x toward
 * +z) and the roll R about x (eqs. 8-10, with their signs chosen so that
 * each is a right-handed rotation and M e_x = u/|u|):
 *   M_Y = [cY -sY 0; sY cY 0; 0 0 1]
 *   M_P = [cP 0 -sP; 0 1 0; sP 0 cP]
 *   M_R = [1 0 0; 0 cR -sR; 0 sR cR]
 *   Y = atan2(u_y, u_x), P = atan2(u_z, hypot(u_x, u_y))
 * (eq. 6 writes Y and P as arcsines of u_y/|u| and u_z/|u|; the atan2 form
 * is the same in the x-y plane and right in every quadrant).  So v = M e_y
 * and w = M e_z: at R = 0, v is horizontal (u_z-free) and w = u x v;
 * R turns v toward w.  The seed builds M's LU factors once and solves
 * for e'; here GSL's LU inverts M once (pd_ellipsoid_init) and each bond
 * costs a 3x3 product.
 *
 * With several ellipsoids the largest d wins (seed 002: "running the
 * scaling routine on each one and then returning the largest value"); with
 * none the influence is isotropic (d = 1).  The bond's weight is the
 * radial influence times d: omega(xi) = omega_r(|xi|) d(xi/|xi|).
 */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_blas.h>
#include <gsl/gsl_linalg.h>
#include <gsl/gsl_matrix.h>
#include <gsl/gsl_permutation.h>

#include "pd.h"

pd_status pd_ellipsoid_parse(const char *text, pd_ellipsoid *e)
{
    double v[6];
    const char *s = text;
    for (int k = 0; k < 6; k++) {
        char *end;
        errno = 0;
        v[k] = strtod(s, &end);
        if (end == s || errno == ERANGE || !isfinite(v[k]) ||
            *end != (k < 5 ? ',' : '\0'))
            return pd_fail(PD_ERR_INVALID,
                           "an ellipsoid is UX,UY,UZ,A,B,ROLL (six numbers), not '%s'", text);
        s = end + 1;
    }
    e->u[0] = v[0];
    e->u[1] = v[1];
    e->u[2] = v[2];
    e->a = v[3];
    e->b = v[4];
    e->roll = v[5];
    return pd_ellipsoid_init(e);
}

/* dst = l r, 3x3 */
static void mul(gsl_matrix *dst, const gsl_matrix *l, const gsl_matrix *r)
{
    gsl_blas_dgemm(CblasNoTrans, CblasNoTrans, 1.0, l, r, 0.0, dst);
}

pd_status pd_ellipsoid_init(pd_ellipsoid *e)
{
    const double *u = e->u;
    if (!(u[0] != 0.0 || u[1] != 0.0 || u[2] != 0.0) || !isfinite(u[0]) || !isfinite(u[1]) ||
        !isfinite(u[2]))
        return pd_fail(PD_ERR_INVALID, "an ellipsoid's preferred direction must be nonzero");
    if (!(e->a > 0.0 && e->a <= 1.0 && e->b > 0.0 && e->b <= 1.0))
        return pd_fail(PD_ERR_INVALID,
                       "an ellipsoid's semi-axis ratios A, B must be in (0, 1], not %g, %g", e->a,
                       e->b);
    if (!isfinite(e->roll))
        return pd_fail(PD_ERR_INVALID, "an ellipsoid's roll must be finite");
    const double Y = atan2(u[1], u[0]), P = atan2(u[2], hypot(u[0], u[1])), R = e->roll;
    const double cy = cos(Y), sy = sin(Y), cp = cos(P), sp = sin(P), cr = cos(R), sr = sin(R);
    double my[9] = {cy, -sy, 0, sy, cy, 0, 0, 0, 1};
    double mp[9] = {cp, 0, -sp, 0, 1, 0, sp, 0, cp};
    double mr[9] = {1, 0, 0, 0, cr, -sr, 0, sr, cr};
    double yp[9], m[9];
    gsl_matrix_view Vy = gsl_matrix_view_array(my, 3, 3), Vp = gsl_matrix_view_array(mp, 3, 3),
                    Vr = gsl_matrix_view_array(mr, 3, 3), Vyp = gsl_matrix_view_array(yp, 3, 3),
                    Vm = gsl_matrix_view_array(m, 3, 3),
                    Vinv = gsl_matrix_view_array(e->rinv, 3, 3);
    mul(&Vyp.matrix, &Vy.matrix, &Vp.matrix);
    mul(&Vm.matrix, &Vyp.matrix, &Vr.matrix);
    /* M^-1 from M's LU factors (seed 002: the LU factorization of M) */
    gsl_permutation *perm = gsl_permutation_alloc(3);
    if (perm == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for an ellipsoid");
    int sign;
    gsl_error_handler_t *old = gsl_set_error_handler_off();
    int rc = gsl_linalg_LU_decomp(&Vm.matrix, perm, &sign);
    if (rc == 0)
        rc = gsl_linalg_LU_invert(&Vm.matrix, perm, &Vinv.matrix);
    gsl_set_error_handler(old);
    gsl_permutation_free(perm);
    if (rc != 0) /* a rotation is never singular */
        return pd_fail(PD_ERR_INVALID, "an ellipsoid's rotation is singular");
    return PD_OK;
}

double pd_ellipsoid_distance(const pd_ellipsoid *e, const double dir[3])
{
    const double n = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    const double ex = dir[0] / n, ey = dir[1] / n, ez = dir[2] / n;
    const double *r = e->rinv;
    const double wx = r[0] * ex + r[1] * ey + r[2] * ez;
    const double wy = r[3] * ex + r[4] * ey + r[5] * ez;
    const double wz = r[6] * ex + r[7] * ey + r[8] * ez;
    return 1.0 / sqrt(wx * wx + (wy * wy) / (e->a * e->a) + (wz * wz) / (e->b * e->b));
}

double pd_ellipsoids_factor(const pd_ellipsoid *e, int n, const double dir[3])
{
    if (n <= 0)
        return 1.0;
    double best = 0;
    for (int k = 0; k < n; k++)
        best = fmax(best, pd_ellipsoid_distance(&e[k], dir));
    return best;
}

double pd_bond_influence(const pd_scene *s, double length, double horizon, const double xi[3])
{
    const double w = pd_lps_influence(s->influence, length, horizon);
    if (s->nellipsoids <= 0)
        return w; /* isotropic: omega_r itself, bit for bit */
    return w * pd_ellipsoids_factor(s->ellipsoid, s->nellipsoids, xi);
}

/* ------------------------------------------------ omega(|xi|), seed 000 eq. 4 */

const char *pd_influence_name(pd_influence w)
{
    return w == PD_INFLUENCE_ONE ? "1" : w == PD_INFLUENCE_GAUSSIAN ? "gaussian" : "1/r";
}

int pd_influence_parse(const char *name)
{
    if (strcmp(name, "1/r") == 0)
        return PD_INFLUENCE_INV_R;
    if (strcmp(name, "1") == 0)
        return PD_INFLUENCE_ONE;
    if (strcmp(name, "gaussian") == 0)
        return PD_INFLUENCE_GAUSSIAN;
    return -1;
}

double pd_lps_influence(pd_influence w, double length, double horizon)
{
    switch (w) {
    case PD_INFLUENCE_ONE:
        return 1.0;
    case PD_INFLUENCE_GAUSSIAN:
        return exp(-(length * length) / (horizon * horizon));
    default:
        return 1.0 / length; /* LAMMPS peri/lps (seed 000, the note on omega) */
    }
}
