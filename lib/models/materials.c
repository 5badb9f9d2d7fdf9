/*
 * materials.c -- bonds with their own PMB constants: several materials with
 * interfaces between them, and fibre-reinforced bonds (seed 004 eq. 10).
 *
 * Each particle carries a material id (pd-lattice --material and
 * --material-region).  A bond between particles of materials m_i and m_j
 * takes (pd_bond_law_of):
 *   m_i == m_j: the law (m, m) (pd-run --material) when given, else the
 *     scene's constants, or with a fibre direction g (pd-run --fibre)
 *       beta = g . xi / (|g| |xi|)                          (seed 004 eq. 10)
 *       c    = beta^2 c_fibre   + (1 - beta^2) c_matrix
 *       s00  = beta^2 s00_fibre + (1 - beta^2) s00_matrix
 *     (eq. 10 mixes the micropotentials; for PMB's w = c s^2 |xi| / 2 that is
 *     mixing c; the critical stretch is mixed the same way);
 *   m_i != m_j: the law (m_i, m_j) (pd-run --interface) when given, else
 *     each end's constants as above, and
 *       c   = 2 c_i c_j / (c_i + c_j)   (the halves of the bond, one in each
 *             material, as two springs in series)
 *       s00 = min(s00_i, s00_j)         (it breaks no later than its weaker
 *             half would).
 *
 * (The mix is computed as x_m + beta^2 (x_f - x_m): exactly x_m when the two
 * are equal.)
 *
 * The run keeps c in the half bonds' weights w = c V nu (lib/models/pmb.c), so a
 * bond's own c costs the force kernel nothing: pd_half_laws scales the
 * weights of pd_half_weights by c_bond / c, so that a bond whose c is the
 * scene's keeps its weight bit for bit.  Its own s00 enters the
 * failure test of seed 000 eqs. 8-9 as a factor k = s00_bond / s00 (s00 the
 * scene's): the bond breaks when
 *   s > k min(s0_i, s0_j),   s0 = s00 - alpha s_min  (per particle, eq. 9)
 * so with alpha = 0 it breaks at exactly s00_bond, and with alpha > 0 the
 * compressive raise of eq. 9 is scaled in the same proportion.  A scene
 * without laws keeps kfail NULL and the kernel of old.
 */
#include <math.h>
#include <stdlib.h>

#include "models/model.h"

int pd_scene_has_laws(const pd_scene *s)
{
    return s->model == PD_MODEL_PMB && (s->nlaws > 0 || s->has_fibre);
}

static const pd_bond_law *find_law(const pd_scene *s, int32_t a, int32_t b)
{
    for (int k = 0; k < s->nlaws; k++)
        if ((s->laws[k].a == a && s->laws[k].b == b) || (s->laws[k].a == b && s->laws[k].b == a))
            return &s->laws[k];
    return NULL;
}

/* The constants of one end: its material's law, the fibre mix or the
 * scene's; beta2 is beta^2 of the bond. */
static void end_law(const pd_scene *s, int32_t m, double beta2, double *c, double *s00)
{
    const pd_bond_law *law = find_law(s, m, m);
    if (law) {
        *c = law->c;
        *s00 = law->s00 > 0 ? law->s00 : s->s00;
    } else if (s->has_fibre) {
        double sf = s->fibre_s00[0] > 0 ? s->fibre_s00[0] : s->s00;
        double sm = s->fibre_s00[1] > 0 ? s->fibre_s00[1] : s->s00;
        /* beta^2 x_f + (1 - beta^2) x_m, as x_m + beta^2 (x_f - x_m):
         * exactly x_m when the two are equal */
        *c = s->fibre_c[1] + beta2 * (s->fibre_c[0] - s->fibre_c[1]);
        *s00 = sm + beta2 * (sf - sm);
    } else {
        *c = s->c;
        *s00 = s->s00;
    }
}

void pd_bond_law_of(const pd_particles *p, const pd_scene *s, int64_t i, int64_t j, double *c,
                    double *s00)
{
    const int32_t mi = p->material[i], mj = p->material[j];
    if (mi != mj) {
        const pd_bond_law *law = find_law(s, mi, mj);
        if (law) {
            *c = law->c;
            *s00 = law->s00 > 0 ? law->s00 : s->s00;
            return;
        }
    }
    double beta2 = 0;
    if (s->has_fibre) {
        const double *g = s->fibre_g;
        double xi[3], gx = 0, gg = 0, xx = 0;
        for (int d = 0; d < 3; d++) {
            xi[d] = p->x[d][j] - p->x[d][i];
            gx += g[d] * xi[d];
            gg += g[d] * g[d];
            xx += xi[d] * xi[d];
        }
        beta2 = gg > 0 && xx > 0 ? gx * gx / (gg * xx) : 0.0;
    }
    double ci, si;
    end_law(s, mi, beta2, &ci, &si);
    if (mi == mj) {
        *c = ci;
        *s00 = si;
        return;
    }
    double cj, sj;
    end_law(s, mj, beta2, &cj, &sj);
    *c = 2.0 * ci * cj / (ci + cj);
    *s00 = si < sj ? si : sj;
}

pd_status pd_bond_laws_check(const pd_particles *p, const pd_scene *s)
{
    for (int k = 0; k < s->nlaws; k++) {
        const pd_bond_law *law = &s->laws[k];
        if (!(law->c > 0) || !isfinite(law->c) || !(law->s00 >= 0) || !isfinite(law->s00))
            return pd_fail(PD_ERR_INVALID, "the bond law of materials %d,%d needs c > 0 and "
                                           "s00 >= 0", (int)law->a, (int)law->b);
        for (int e = 0; e < 2; e++) {
            int32_t m = e ? law->b : law->a;
            int64_t i = 0;
            while (i < p->n && p->material[i] != m)
                i++;
            if (pd_body_max(p, i < p->n) == 0) /* a window: on no rank */
                return pd_fail(PD_ERR_INVALID, "the body has no particle of material %d (%s)",
                               (int)m, law->a == law->b ? "--material" : "--interface");
        }
    }
    if (s->has_fibre && (!(s->fibre_c[0] > 0) || !(s->fibre_c[1] > 0)))
        return pd_fail(PD_ERR_INVALID, "--fibre needs positive micromoduli");
    return PD_OK;
}

int64_t pd_material_paint(pd_particles *p, const pd_region *r, int32_t id)
{
    int64_t count = 0;
    for (int64_t i = 0; i < p->n; i++) {
        const double x[3] = {p->x[0][i], p->x[1][i], p->x[2][i]};
        if (pd_region_inside(r, x)) {
            p->material[i] = id;
            count++;
        }
    }
    return count;
}

pd_status pd_half_laws(const pd_particles *p, const pd_bonds *b, const pd_scene *s,
                       pd_half_bonds *h)
{
    (void)b; /* the weights of pd_half_weights hold V nu already */
    if (!(s->c > 0))
        return pd_fail(PD_ERR_INVALID, "the scene's micromodulus must be positive");
    size_t m = (size_t)(h->count > 0 ? h->count : 1);
    const int failure = s->has_failure && s->s00 > 0;
    if (failure && (h->kfail = malloc(m * sizeof(double))) == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for the bond laws");
    const int shared = h->w_ji == h->w_ij;
    int bad = 0;
    /* w = c V nu of pd_half_weights times c_bond / c: a bond whose c is the
     * scene's keeps its weight bit for bit */
#pragma omp parallel for schedule(static) reduction(| : bad)
    for (int64_t i = 0; i < h->n; i++)
        for (int64_t q = h->offset[i]; q < h->offset[i + 1]; q++) {
            double c, s00;
            pd_bond_law_of(p, s, i, h->neighbor[q], &c, &s00);
            bad |= !(c > 0) || !isfinite(c);
            const double scale = c / s->c;
            h->w_ij[q] *= scale;
            if (!shared)
                h->w_ji[q] *= scale;
            if (failure)
                h->kfail[q] = s00 / s->s00;
        }
    if (bad)
        return pd_fail(PD_ERR_INVALID, "a bond's micromodulus is not positive");
    return PD_OK;
}

double pd_bond_stiffness_laws(const pd_particles *p, const pd_bonds *b, const pd_scene *s,
                              int64_t i)
{
    double sum = 0;
    pd_bond_iter it;
    for (pd_family_start(b, p, i, &it); pd_family_next(&it);) {
        double c, s00;
        pd_bond_law_of(p, s, i, it.j, &c, &s00);
        sum += p->volume[it.j] * it.vfactor * c / it.length;
    }
    return sum;
}
