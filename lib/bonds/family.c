/*
 * family.c -- particles on their lattice sites (the site map), and the
 * walk of a family in either form of the bonds: the lists, or compact
 * families walked off their stencil (pd_bonds_compact), each bond's length
 * and partial-volume factor computed from the particles as pd_bonds_build
 * computes them (man/man5/pd-h5.5, "/bonds as a stencil").
 */
#include <stdlib.h>
#include <string.h>
#include <float.h>
#include <math.h>

#include "base/comm.h"
#include "bonds/sites.h"

double pd_partial_volume(double len, double horizon, double r)
{
    if (len <= horizon - r)
        return 1.0;
    return (horizon + r - len) / (2.0 * r);
}

/* ------------------------------------------------------------- site map */

void pd_sites_free(site_map *m)
{
    for (int d = 0; d < 3; d++)
        free(m->c[d]);
    free(m->map);
}

/* Is row order the lexicographic order of the sites in (ax[0], ax[1],
 * ax[2])? */
static int sorted_by(const site_map *m, int64_t n, const int ax[3])
{
    for (int64_t i = 1; i < n; i++) {
        int a = 0;
        while (a < 3 && m->c[ax[a]][i] == m->c[ax[a]][i - 1])
            a++;
        if (a == 3 || m->c[ax[a]][i] < m->c[ax[a]][i - 1])
            return 0;
    }
    return 1;
}

/* The sites of p's particles on the lattice (origin, h) and their map;
 * *shared gets a particle whose site another one holds (SITES_SHARED). */
sites_result pd_sites_build(const pd_particles *p, const double origin[3], double h,
                                site_map *m, int64_t *shared)
{
    const int64_t n = p->n;
    memset(m, 0, sizeof *m);
    for (int d = 0; d < 3; d++)
        if ((m->c[d] = malloc((size_t)(n > 0 ? n : 1) * sizeof(int32_t))) == NULL)
            return SITES_NOMEM;
    if (!pd_lattice_sites(p, origin, h, m->c))
        return SITES_OFF;
    double sites = 1;
    for (int d = 0; d < 3; d++) {
        int32_t lo = INT32_MAX, hi = INT32_MIN;
        for (int64_t i = 0; i < n; i++) {
            lo = m->c[d][i] < lo ? m->c[d][i] : lo;
            hi = m->c[d][i] > hi ? m->c[d][i] : hi;
        }
        m->lo[d] = lo;
        m->dim[d] = (int64_t)hi - lo + 1;
        sites *= (double)m->dim[d];
    }
    if (sites > (double)PD_STENCIL_SPARSE * (double)n + 4096)
        return SITES_SPARSE;
    const int64_t ns = m->dim[0] * m->dim[1] * m->dim[2];
    if ((m->map = malloc((size_t)ns * sizeof(int32_t))) == NULL)
        return SITES_NOMEM;
    memset(m->map, 0xff, (size_t)ns * sizeof(int32_t));
    for (int64_t i = 0; i < n; i++) {
        int64_t s = ((int64_t)(m->c[2][i] - m->lo[2]) * m->dim[1] + (m->c[1][i] - m->lo[1])) *
                        m->dim[0] +
                    (m->c[0][i] - m->lo[0]);
        if (m->map[s] >= 0) {
            *shared = i;
            return SITES_SHARED;
        }
        m->map[s] = (int32_t)i;
    }
    static const int perms[6][3] = {{2, 1, 0}, {2, 0, 1}, {1, 2, 0},
                                    {1, 0, 2}, {0, 2, 1}, {0, 1, 2}};
    m->ax[0] = -1;
    for (int q = 0; q < 6 && m->ax[0] < 0; q++)
        if (sorted_by(m, n, perms[q]))
            memcpy(m->ax, perms[q], sizeof m->ax);
    return SITES_OK;
}

typedef struct {
    int64_t key;
    int k;
} key_item;

static int cmp_key(const void *a, const void *b)
{
    const key_item *x = a, *y = b;
    return (x->key > y->key) - (x->key < y->key);
}

/* The offsets in the order that makes every family come out sorted by
 * partner when the rows are in lattice order (m->ax); the table's own
 * order otherwise.  NULL: out of memory. */
int32_t (*pd_sites_walk_order(const pd_stencil *st, const site_map *m))[3]
{
    int32_t(*d)[3] = malloc((size_t)(st->nk > 0 ? st->nk : 1) * sizeof *d);
    key_item *it = malloc((size_t)(st->nk > 0 ? st->nk : 1) * sizeof *it);
    if (d == NULL || it == NULL) {
        free(d);
        free(it);
        return NULL;
    }
    const int64_t w = 4 * (int64_t)PD_STENCIL_REACH + 1; /* wider than any |d| */
    for (int k = 0; k < st->nk; k++) {
        it[k].k = k;
        it[k].key = k;
        if (m->ax[0] >= 0) {
            it[k].key = 0;
            for (int a = 0; a < 3; a++)
                it[k].key = it[k].key * w + (st->d[k][m->ax[a]] + 2 * PD_STENCIL_REACH);
        }
    }
    qsort(it, (size_t)st->nk, sizeof *it, cmp_key);
    for (int k = 0; k < st->nk; k++)
        memcpy(d[k], st->d[it[k].k], sizeof d[k]);
    free(it);
    return d;
}

/* ------------------------------------------------------ compact families */

void pd_bond_sites_free(struct pd_bond_sites *bs)
{
    if (bs == NULL)
        return;
    pd_sites_free(&bs->m);
    free(bs->d);
    free(bs->delta);
    free(bs->pad);
    free(bs->at);
    free(bs);
}

static void family_start(const pd_bonds *b, const pd_particles *p, int64_t i, pd_bond_iter *it,
                         int geometry)
{
    it->b_ = b;
    it->p_ = p;
    it->i_ = i;
    it->q = b->offset[i] - 1;
    it->end_ = b->offset[i + 1];
    it->k_ = 0;
    it->geometry_ = geometry;
    it->pad_ = NULL;
    it->delta_ = NULL;
    it->nk_ = 0;
    if (!pd_bonds_has_lists(b)) {
        it->s_ = b->sites->at[i];
        it->pad_ = b->sites->pad;
        it->delta_ = b->sites->delta;
        it->nk_ = b->sites->nk;
    }
}

void pd_family_start(const pd_bonds *b, const pd_particles *p, int64_t i, pd_bond_iter *it)
{
    family_start(b, p, i, it, 1);
}

void pd_family_start_partners(const pd_bonds *b, const pd_particles *p, int64_t i,
                              pd_bond_iter *it)
{
    family_start(b, p, i, it, 0);
}

int pd_family_next_site(pd_bond_iter *it)
{
    const struct pd_bond_sites *bs = it->b_->sites;
    while (it->k_ < bs->nk) {
        const int32_t j = bs->pad[it->s_ + bs->delta[it->k_++]];
        if (j < 0)
            continue;
        it->j = j;
        if (it->geometry_)
            pd_bond_geometry(it->p_, it->i_, j, it->b_->horizon, &it->length, &it->vfactor);
        return 1;
    }
    it->q = it->end_; /* cannot be: the offsets counted these bonds */
    return 0;
}

int pd_family_get(const pd_bonds *b, const pd_particles *p, int64_t i, pd_family_buf *buf,
                  pd_family *f)
{
    f->first = b->offset[i];
    f->n = b->offset[i + 1] - b->offset[i];
    if (pd_bonds_has_lists(b)) {
        f->j = b->neighbor + f->first;
        f->length = b->length + f->first;
        f->vfactor = b->vfactor + f->first;
        return 0;
    }
    if (f->n > buf->cap) {
        pd_family_buf_free(buf);
        buf->j = malloc((size_t)f->n * sizeof(int32_t));
        buf->length = malloc((size_t)f->n * sizeof(double));
        buf->vfactor = malloc((size_t)f->n * sizeof(double));
        if (!buf->j || !buf->length || !buf->vfactor) {
            pd_family_buf_free(buf);
            f->n = 0;
            return -1;
        }
        buf->cap = f->n;
    }
    /* pd_family_next's walk, without its calls */
    const struct pd_bond_sites *bs = b->sites;
    const int64_t s = bs->at[i];
    int64_t t = 0;
    for (int k = 0; k < bs->nk && t < f->n; k++) {
        const int32_t j = bs->pad[s + bs->delta[k]];
        if (j < 0)
            continue;
        buf->j[t] = j;
        pd_bond_geometry(p, i, j, b->horizon, &buf->length[t], &buf->vfactor[t]);
        t++;
    }
    f->n = t; /* = f->n: the offsets counted these bonds */
    f->j = buf->j;
    f->length = buf->length;
    f->vfactor = buf->vfactor;
    return 0;
}

int pd_family_offsets(const pd_bonds *b, const pd_particles *p, int32_t (*d)[3], double *len,
                      double *nu, double *spread)
{
    if (pd_bonds_has_lists(b) || b->sites == NULL)
        return -1;
    const struct pd_bond_sites *bs = b->sites;
#pragma omp parallel for schedule(dynamic, 1)
    for (int k = 0; k < bs->nk; k++) {
        memcpy(d[k], bs->d[k], sizeof d[k]);
        len[k] = nu[k] = spread[k] = NAN;
        for (int64_t i = 0; i < b->n; i++) {
            const int32_t j = bs->pad[bs->at[i] + bs->delta[k]];
            if (j < 0)
                continue;
            pd_bond_geometry(p, i, j, b->horizon, &len[k], &nu[k]);
            spread[k] = 4 * bs->dev + 32 * DBL_EPSILON * (len[k] + bs->xmax);
            break;
        }
    }
    return bs->nk;
}

int pd_family_offsets_ranks(const pd_bonds *b, const pd_particles *p, int32_t (*d)[3],
                            double *len, double *nu, double *spread)
{
    const struct pd_bond_sites *bs = b->sites;
    const pd_stencil *st = b->stencil;
    const int nk = st ? st->nk : 0;
    int64_t *first = malloc((size_t)(nk > 0 ? nk : 1) * sizeof(int64_t));
    double *v = malloc((size_t)(nk > 0 ? 2 * nk : 1) * sizeof(double));
    int *walk = malloc((size_t)(nk > 0 ? nk : 1) * sizeof(int));
    int ok = first && v && walk && bs && !pd_bonds_has_lists(b) && d && len && nu && spread;
    for (int t = 0; t < nk && ok; t++) { /* the table's offset t in the walk */
        walk[t] = -1;
        for (int k = 0; k < bs->nk && walk[t] < 0; k++)
            if (memcmp(bs->d[k], st->d[t], sizeof st->d[t]) == 0)
                walk[t] = k;
        ok = walk[t] >= 0;
    }
    if (pd_comm_min(ok) == 0) { /* every rank, or none, goes on */
        free(first);
        free(v);
        free(walk);
        return -1;
    }
    /* each offset's first row over the ranks' own rows, which are whole */
    for (int t = 0; t < nk; t++) {
        first[t] = INT64_MAX;
        for (int64_t i = p->own_lo; i < p->own_hi && first[t] == INT64_MAX; i++)
            if (bs->pad[bs->at[i] + bs->delta[walk[t]]] >= 0)
                first[t] = p->first + i;
    }
    pd_comm_min_int(first, nk);
    /* its bond's length and factor from the rank that owns it (the
     * others' zeros add nothing) */
    for (int t = 0; t < nk; t++) {
        const int64_t i = first[t] - p->first;
        v[2 * t] = v[2 * t + 1] = 0;
        if (i >= p->own_lo && i < p->own_hi)
            pd_bond_geometry(p, i, bs->pad[bs->at[i] + bs->delta[walk[t]]], b->horizon,
                             &v[2 * t], &v[2 * t + 1]);
    }
    pd_comm_add(v, 2 * nk);
    const double dev = pd_comm_max(bs->dev), xmax = pd_comm_max(bs->xmax);
    for (int t = 0; t < nk; t++) {
        memcpy(d[t], st->d[t], sizeof d[t]);
        const int none = first[t] == INT64_MAX;
        len[t] = none ? NAN : v[2 * t];
        nu[t] = none ? NAN : v[2 * t + 1];
        spread[t] = none ? NAN : 4 * dev + 32 * DBL_EPSILON * (len[t] + xmax);
    }
    free(first);
    free(v);
    free(walk);
    return nk;
}

/* The first directed bond of rows [i0, i1) whose bit differs from its
 * reverse's (INT64_MAX: none), the partner's rank in its family a
 * popcount of its offsets' mask (mask, W words a particle; neg: each
 * offset's reverse, -1 for none). */
static inline __attribute__((always_inline)) int64_t
asym_rows(const pd_bonds *b, const uint64_t *bits, const uint64_t *mask, const int *neg, int W,
          int64_t i0, int64_t i1)
{
    const struct pd_bond_sites *bs = b->sites;
    const int nk = bs->nk;
    for (int64_t i = i0; i < i1; i++) {
        int64_t q = b->offset[i];
        for (int k = 0; k < nk; k++) {
            const int32_t j = bs->pad[bs->at[i] + bs->delta[k]];
            if (j < 0)
                continue;
            const int64_t me = q++;
            if (j > i || neg[k] < 0)
                continue;
            const int m = neg[k];
            int64_t rank = 0;
            for (int w = 0; w < (m >> 6); w++)
                rank += __builtin_popcountll(mask[(int64_t)j * W + w]);
            rank += __builtin_popcountll(mask[(int64_t)j * W + (m >> 6)] &
                                         ((UINT64_C(1) << (m & 63)) - 1));
            if (pd_bond_intact(bits, me) != pd_bond_intact(bits, b->offset[j] + rank))
                return me; /* the rows' first */
        }
    }
    return INT64_MAX;
}

#if defined(__x86_64__) && defined(__GNUC__)
/* with the processor's popcnt instruction (the baseline's is a call) */
__attribute__((target("popcnt"))) static int64_t
asym_rows_popcnt(const pd_bonds *b, const uint64_t *bits, const uint64_t *mask, const int *neg,
                 int W, int64_t i0, int64_t i1)
{
    return asym_rows(b, bits, mask, neg, W, i0, i1);
}
#endif

int64_t pd_family_asymmetric(const pd_bonds *b, const uint64_t *bits)
{
    return pd_family_asymmetric_rows(b, bits, 0, b->n);
}

int64_t pd_family_asymmetric_rows(const pd_bonds *b, const uint64_t *bits, int64_t lo, int64_t hi)
{
    if (pd_bonds_has_lists(b) || b->sites == NULL)
        return -3;
    const struct pd_bond_sites *bs = b->sites;
    const int nk = bs->nk, W = (nk + 63) / 64;
    /* each particle's partners as a mask over the walk's offsets, so that
     * the rank of a partner in its family is a popcount */
    uint64_t *mask = calloc((size_t)(b->n > 0 ? b->n : 1) * W, sizeof(uint64_t));
    int *neg = malloc((size_t)(nk > 0 ? nk : 1) * sizeof(int));
    if (mask == NULL || neg == NULL) {
        free(mask);
        free(neg);
        return -2;
    }
    for (int k = 0; k < nk; k++) {
        neg[k] = -1;
        for (int m = 0; m < nk && neg[k] < 0; m++)
            if (bs->d[m][0] == -bs->d[k][0] && bs->d[m][1] == -bs->d[k][1] &&
                bs->d[m][2] == -bs->d[k][2])
                neg[k] = m;
    }
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < b->n; i++)
        for (int k = 0; k < nk; k++)
            if (bs->pad[bs->at[i] + bs->delta[k]] >= 0)
                mask[i * W + (k >> 6)] |= UINT64_C(1) << (k & 63);
    int popcnt = 0;
#if defined(__x86_64__) && defined(__GNUC__)
    popcnt = __builtin_cpu_supports("popcnt");
#endif
    /* rows in chunks: each chunk's first, the smallest of them */
    const int64_t chunk = 4096;
    int64_t first = INT64_MAX;
#pragma omp parallel for schedule(static) reduction(min : first)
    for (int64_t c = 0; c < (hi - lo + chunk - 1) / chunk; c++) {
        const int64_t i0 = lo + c * chunk, i1 = i0 + chunk < hi ? i0 + chunk : hi;
        int64_t f;
#if defined(__x86_64__) && defined(__GNUC__)
        if (popcnt)
            f = asym_rows_popcnt(b, bits, mask, neg, W, i0, i1);
        else
#endif
            f = asym_rows(b, bits, mask, neg, W, i0, i1);
        first = f < first ? f : first;
    }
    free(mask);
    free(neg);
    return first == INT64_MAX ? -1 : first;
}

void pd_family_buf_free(pd_family_buf *buf)
{
    free(buf->j);
    free(buf->length);
    free(buf->vfactor);
    memset(buf, 0, sizeof *buf);
}
