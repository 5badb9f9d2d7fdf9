/*
 * plate.c -- 2-D plates: the plane-stress constants of PMB.
 *
 * A plate is a square lattice in the plane z = 0 whose particles have volume
 * V = dx^2 H (H the thickness); the bond force is the 3-D one (seed 000 eqs.
 * 5-7), only the family is a disk of radius delta in the plane.  The
 * micromodulus follows by matching the strain energy density of a uniform
 * isotropic in-plane stretch eps (every bond has stretch s = eps): with the
 * pair energy 1/2 c s^2 |xi| per volume^2 (seed 004 eq. 22) and half of each
 * bond's energy booked to each end,
 *   W = 1/4 int_0^delta c eps^2 xi (2 pi xi H) dxi = c pi H delta^3 eps^2 / 6,
 * and plane stress with sigma_xx = sigma_yy = E eps / (1 - nu) gives
 *   W = E eps^2 / (1 - nu) = 2 K eps^2,   K = E / (2 (1 - nu)),
 * so c = 12 K / (pi H delta^3); PMB in 2-D has nu = 1/3 (seed 000), K = 3E/4
 * and c = 9 E / (pi H delta^3), the value of Ha & Bobaru 2010 (Emmrich &
 * Weckner 2007 derive the bond-based constants in 1-D, 2-D and 3-D).
 *
 * Critical stretch (seed 004 eqs. 26-27 in the plane): the work to break
 * every bond across a unit length of a straight crack, per unit thickness.
 * A particle at distance z below the line (volume H dz per unit length)
 * bonds across it with the partners at xi in (z, delta) within the angle
 * |phi| < acos(z / xi) of the normal (volume H xi dxi dphi):
 *   G0 = (1/H) int_0^delta H dz int_z^delta (1/2 c s0^2 xi) 2 acos(z/xi) H xi dxi
 *      = c s0^2 H int_0^delta xi^2 int_0^xi acos(z/xi) dz dxi
 *      = c s0^2 H int_0^delta xi^3 dxi = c s0^2 H delta^4 / 4,
 * as int_0^1 acos(u) du = 1; so s0 = sqrt(4 G0 / (c H delta^4)), which with
 * c = 9 E / (pi H delta^3) is sqrt(4 pi G0 / (9 E delta)) (Ha & Bobaru 2010).
 */
#include <math.h>

#include "pd.h"

double pd_pmb_c_from_bulk_2d(double bulk_modulus, double horizon, double thickness)
{
    const double pi = 3.14159265358979323846;
    return PD_PMB_C_FACTOR_2D * bulk_modulus / (pi * thickness * pow(horizon, 3));
}

double pd_pmb_s0_from_energy_2d(double g0, double c, double horizon, double thickness)
{
    return sqrt(4.0 * g0 / (c * thickness * pow(horizon, 4)));
}

double pd_pmb_bulk_from_youngs(double youngs_modulus, int dimension)
{
    if (dimension == 2)
        return youngs_modulus / (2.0 * (1.0 - PD_PMB_NU_2D));
    return youngs_modulus / (3.0 * (1.0 - 2.0 * PD_PMB_NU_3D));
}

double pd_pmb_c_for(const pd_particles *p, double bulk_modulus, double horizon)
{
    if (p->dimension == 2)
        return pd_pmb_c_from_bulk_2d(bulk_modulus, horizon, p->thickness);
    return pd_pmb_c_from_bulk(bulk_modulus, horizon);
}

double pd_pmb_s0_for(const pd_particles *p, double g0, double c, double horizon)
{
    if (p->dimension == 2)
        return pd_pmb_s0_from_energy_2d(g0, c, horizon, p->thickness);
    return pd_pmb_s0_from_energy(g0, c, horizon);
}
