/*
 * test_damage -- pd_damage (lib/bonds/bonds.c), seed 000 eq. 10 as LAMMPS compute
 * damage/atom: phi_i = 1 - sum_{j intact} V_j / sum_{j in family} V_j.
 *
 * Proves: damage is 0 with every bond intact and 1 with every bond broken;
 * a particle without family has damage 0; on a hand-built family with
 * unequal volumes the damage is the volume-weighted fraction of broken
 * bonds (the partial-volume factor nu does not enter); on a lattice cut by
 * a plane, damage is in [0,1], positive exactly for particles with a bond
 * across the plane, mirror-symmetric about it, and the broken bits are
 * twice the pairs across.  Without the pre-crack (pd_damage_no_precrack),
 * pre-cracked bonds leave both sums: a pre-crack alone gives damage 0, a
 * bond broken later weighs against the family less its pre-cracked
 * bonds, a family all pre-cracked gives 0, and with no pre-crack it equals
 * pd_damage.  On a lattice (equal volumes: the bits are counted) both are
 * bit for bit the sums over the partners in family order, with a
 * pseudo-random third of the bonds broken and a fifth pre-cracked.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "pd.h"


/*
 * Five particles with volumes 1, 2, 3, 4, 5 (x 1e-9 m^3); bonds 0-1, 0-2,
 * 0-3, 1-2, and particle 4 alone.  Families (sorted):
 *   0: 1 2 3    1: 0 2    2: 0 1    3: 0    4: -
 */
static void hand_built(pd_particles **pp, pd_bonds **bp)
{
    pd_particles *p = pd_particles_new(5);
    for (int i = 0; i < 5; i++) {
        p->x[0][i] = i;
        p->x[1][i] = p->x[2][i] = 0;
        p->volume[i] = (i + 1) * 1e-9;
        p->density[i] = 1000;
        p->radius[i] = 0.5;
        p->material[i] = 1;
        p->id[i] = i + 1;
    }
    p->spacing = 1;
    static const int64_t offset[6] = {0, 3, 5, 7, 8, 8};
    static const int32_t neighbor[8] = {1, 2, 3, 0, 2, 0, 1, 0};
    pd_bonds *b = pd_bonds_alloc(5, 8);
    if (b == NULL)
        die("alloc");
    memcpy(b->offset, offset, sizeof offset);
    memcpy(b->neighbor, neighbor, sizeof neighbor);
    for (int k = 0; k < 8; k++) {
        b->length[k] = 1;
        b->vfactor[k] = k % 2 ? 0.5 : 1.0; /* must not matter */
    }
    memset(b->intact, 0xff, (size_t)pd_bits_words(8) * sizeof(uint64_t));
    b->horizon = 3;
    *pp = p;
    *bp = b;
}

static void test_hand_built(void)
{
    int f0 = failures;
    pd_particles *p;
    pd_bonds *b;
    hand_built(&p, &b);
    double d[5];
    pd_damage(p, b, b->intact, d);
    for (int i = 0; i < 5; i++)
        CHECK(d[i] == 0, "intact: damage[%d] = %g", i, d[i]);

    /* break 0-2 in both families: bond 1 (0->2) and bond 5 (2->0) */
    pd_bond_break(b->intact, 1);
    pd_bond_break(b->intact, 5);
    pd_damage(p, b, b->intact, d);
    const double *V = p->volume;
    double want[5] = {V[2] / (V[1] + V[2] + V[3]), 0, V[0] / (V[0] + V[1]), 0, 0};
    for (int i = 0; i < 5; i++)
        CHECK(fabs(d[i] - want[i]) <= 1e-15, "one bond broken: damage[%d] = %.17g, expected %.17g",
              i, d[i], want[i]);
    CHECK(fabs(d[0] - 1.0 / 3.0) <= 1e-15 && fabs(d[2] - 1.0 / 3.0) <= 1e-15,
          "3/(2+3+4) and 1/(1+2)");

    /* break 0-3 too: particle 3 loses its only bond */
    pd_bond_break(b->intact, 2);
    pd_bond_break(b->intact, 7);
    pd_damage(p, b, b->intact, d);
    CHECK(fabs(d[0] - (V[2] + V[3]) / (V[1] + V[2] + V[3])) <= 1e-15, "damage[0] = 7/9");
    CHECK(d[3] == 1, "no intact bond: damage 1");
    CHECK(d[4] == 0, "no family: damage 0");

    /* everything broken */
    memset(b->intact, 0, (size_t)pd_bits_words(8) * sizeof(uint64_t));
    pd_damage(p, b, b->intact, d);
    for (int i = 0; i < 4; i++)
        CHECK(d[i] == 1, "all broken: damage[%d] = %g", i, d[i]);
    CHECK(d[4] == 0, "no family: damage 0 even when all is broken");
    pd_bonds_free(b);
    pd_particles_free(p);
    proved(f0, "damage: 0 intact, 1 all broken, 0 without family, volume-weighted fraction");
}

static void test_plane_cut(void)
{
    int f0 = failures;
    const double h = 1e-3;
    pd_region r;
    if (pd_region_parse(PD_REGION_BOX, "0,0.0091,0,0.0061,0,0.0061", &r) != PD_OK)
        die("region");
    pd_lattice_params lp = {h, 2200, 1, 0, 1};
    pd_particles *p = NULL;
    pd_bonds *b = NULL;
    if (pd_lattice_make(&r, 1, &lp, &p) != PD_OK || pd_bonds_build(p, 3.0001 * h, &b) != PD_OK)
        die("model");
    /* cut every bond crossing the plane x = 4.5 h */
    const double cut = 4.5 * h;
    int64_t across = 0;
    char *has_cut = calloc((size_t)p->n, 1);
    for (int64_t i = 0; i < p->n; i++)
        for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++) {
            int64_t j = b->neighbor[k];
            if ((p->x[0][i] < cut) != (p->x[0][j] < cut)) {
                pd_bond_break(b->intact, k);
                has_cut[i] = 1;
                across++;
            }
        }
    CHECK(pd_bits_count_broken(b->intact, b->count) == across && across % 2 == 0,
          "broken bits are both copies of each pair");
    double *d = malloc((size_t)p->n * sizeof(double));
    pd_damage(p, b, b->intact, d);
    for (int64_t i = 0; i < p->n; i++) {
        CHECK(d[i] >= 0 && d[i] <= 1, "damage out of [0,1]");
        CHECK((d[i] > 0) == has_cut[i], "particle %lld: damage %g", (long long)i, d[i]);
        /* the mirror image about the plane: x -> 9h - x */
        for (int64_t j = 0; j < p->n; j++)
            if (fabs(p->x[0][j] - (9 * h - p->x[0][i])) < 1e-9 && p->x[1][j] == p->x[1][i] &&
                p->x[2][j] == p->x[2][i])
                CHECK(fabs(d[j] - d[i]) <= 1e-15, "damage not mirror-symmetric");
    }
    free(d);
    free(has_cut);
    pd_bonds_free(b);
    pd_particles_free(p);
    proved(f0, "a plane cut: damage in [0,1], positive exactly next to the cut, symmetric");
}

static void test_no_precrack(void)
{
    int f0 = failures;
    pd_particles *p;
    pd_bonds *b;
    hand_built(&p, &b);
    const double *V = p->volume;
    double d[5], e[5];
    /* no pre-crack: the same as pd_damage */
    pd_bond_break(b->intact, 1);
    pd_bond_break(b->intact, 5);
    pd_damage(p, b, b->intact, d);
    pd_damage_no_precrack(p, b, b->intact, e);
    for (int i = 0; i < 5; i++)
        CHECK(d[i] == e[i], "no pre-crack: damage[%d] %g != %g", i, e[i], d[i]);
    /* 0-2 (bonds 1, 5) pre-cracked: damage 0 without it, the same with */
    b->precrack = calloc((size_t)pd_bits_words(8) + 1, sizeof(uint64_t));
    if (b->precrack == NULL)
        die("alloc");
    b->precrack[0] = (UINT64_C(1) << 1) | (UINT64_C(1) << 5);
    pd_damage_no_precrack(p, b, b->intact, e);
    for (int i = 0; i < 5; i++)
        CHECK(e[i] == 0, "pre-crack only: damage[%d] = %g", i, e[i]);
    pd_damage(p, b, b->intact, e);
    for (int i = 0; i < 5; i++)
        CHECK(e[i] == d[i], "pd_damage counts the pre-crack: damage[%d] = %g", i, e[i]);
    CHECK(pd_bits_count_broken_except(b->intact, b->precrack, 8) == 0, "no bond broken later");
    /* then 0-1 (bonds 0, 3) breaks in the run */
    pd_bond_break(b->intact, 0);
    pd_bond_break(b->intact, 3);
    pd_damage_no_precrack(p, b, b->intact, e);
    CHECK(fabs(e[0] - V[1] / (V[1] + V[3])) <= 1e-15, "damage[0] = V1/(V1+V3): %g", e[0]);
    CHECK(fabs(e[1] - V[0] / (V[0] + V[2])) <= 1e-15, "damage[1] = V0/(V0+V2): %g", e[1]);
    CHECK(e[2] == 0, "damage[2]: its only other bond 2-1 is intact (%g)", e[2]);
    CHECK(e[3] == 0 && e[4] == 0, "untouched particles");
    CHECK(pd_bits_count_broken_except(b->intact, b->precrack, 8) == 2, "one pair broken later");
    /* 0-3 (bonds 2, 7) pre-cracked too: particle 3 has no bond left to
     * count, damage 0 */
    b->precrack[0] |= (UINT64_C(1) << 2) | (UINT64_C(1) << 7);
    pd_bond_break(b->intact, 2);
    pd_bond_break(b->intact, 7);
    pd_damage_no_precrack(p, b, b->intact, e);
    CHECK(e[3] == 0, "all bonds pre-cracked: damage 0 (%g)", e[3]);
    CHECK(e[0] == 1, "particle 0: its only bond outside the pre-crack broke (%g)", e[0]);
    pd_bonds_free(b);
    pd_particles_free(p);
    proved(f0, "damage without the pre-crack: pre-cracked bonds out of both sums");
}

/* seed 000 eq. 10 summed over the partners, in family order */
static double walked(const pd_particles *p, const pd_bonds *b, const uint64_t *intact,
                     const uint64_t *skip, int64_t i)
{
    double all = 0, kept = 0;
    for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++) {
        if (skip && pd_bond_intact(skip, k))
            continue;
        all += p->volume[b->neighbor[k]];
        if (pd_bond_intact(intact, k))
            kept += p->volume[b->neighbor[k]];
    }
    return all > 0 ? 1.0 - kept / all : 0.0;
}

static void test_counted(void)
{
    int f0 = failures;
    pd_region r;
    if (pd_region_parse(PD_REGION_BOX, "0,0.0071,0,0.0051,0,0.0041", &r) != PD_OK)
        die("region");
    pd_lattice_params lp = {0.001, 2200.0, 1, 0.0, 1};
    pd_particles *p = NULL;
    pd_bonds *b = NULL;
    if (pd_lattice_make(&r, 1, &lp, &p) != PD_OK || pd_bonds_build(p, 3.0001e-3, &b) != PD_OK)
        die("model");
    const size_t words = (size_t)pd_bits_words(b->count);
    uint64_t *intact = calloc(words, sizeof(uint64_t)), *pre = calloc(words, sizeof(uint64_t));
    double *d = malloc((size_t)p->n * sizeof(double)), *dn = malloc((size_t)p->n * sizeof(double));
    if (!intact || !pre || !d || !dn)
        die("memory");
    for (int64_t k = 0; k < b->count; k++) {
        uint64_t h = (uint64_t)k * 2654435761u;
        if (h % 3 != 0)
            intact[k >> 6] |= UINT64_C(1) << (k & 63);
        if (h % 5 == 1) {
            pre[k >> 6] |= UINT64_C(1) << (k & 63);
            intact[k >> 6] &= ~(UINT64_C(1) << (k & 63));
        }
    }
    b->precrack = pre;
    pd_damage(p, b, intact, d);
    pd_damage_no_precrack(p, b, intact, dn);
    int64_t differ = 0, between = 0;
    for (int64_t i = 0; i < p->n; i++) {
        differ += memcmp(&d[i], &(double){walked(p, b, intact, NULL, i)}, sizeof(double)) != 0;
        differ += memcmp(&dn[i], &(double){walked(p, b, intact, pre, i)}, sizeof(double)) != 0;
        between += d[i] > 0 && d[i] < 1;
    }
    CHECK(differ == 0, "%lld damages differ from the sums over the partners", (long long)differ);
    CHECK(between > p->n / 2, "the damage should lie strictly between 0 and 1 for most particles");
    b->precrack = NULL;
    free(pre);
    free(intact);
    free(d);
    free(dn);
    pd_bonds_free(b);
    pd_particles_free(p);
    proved(f0, "equal volumes: the counted damage is the partners' sums bit for bit (with and "
               "without the pre-crack)");
}

int main(void)
{
    test_hand_built();
    test_plane_cut();
    test_no_precrack();
    test_counted();
    if (failures)
        fprintf(stderr, "test_damage: %d failures\n", failures);
    return failures != 0;
}
