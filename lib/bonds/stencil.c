/*
 * stencil.c -- bond families as a lattice stencil, the compact form of a
 * lattice body's bonds in files (man/man5/pd-h5.5, "/bonds as a stencil").
 *
 * A body made by pd-lattice sits on a simple cubic (or square) lattice of
 * spacing h, and pd-bonds gives each particle a bond to every particle
 * within the horizon.  When the same lattice offsets d are bonds for every
 * particle that has a partner there, the families are the stencil: the
 * table of offsets names every bond, and a file needs no partner, length
 * or weight per bond, only its state bit.  The families come back from it
 * in their own order (each sorted by partner), each bond's length and
 * partial-volume factor computed from the particles by pd_bonds_build's
 * own arithmetic: expanding gives the bond lists bit for bit, and
 * pd_bonds_find_stencil proves it for a body before a file says so.
 *
 * Sites: c_i = round((x_i - origin) / h) (pd_lattice_sites), and a map
 * over the sites' bounding box gives the particle at a site.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bonds/sites.h"

static pd_stencil *stencil_copy(const pd_stencil *st)
{
    pd_stencil *c = pd_stencil_alloc(st->nk);
    if (c == NULL)
        return NULL;
    memcpy(c->d, st->d, (size_t)st->nk * sizeof *st->d);
    memcpy(c->length, st->length, (size_t)st->nk * sizeof(double));
    memcpy(c->vfactor, st->vfactor, (size_t)st->nk * sizeof(double));
    memcpy(c->origin, st->origin, sizeof c->origin);
    c->spacing = st->spacing;
    return c;
}

/* ---------------------------------------------------------- the families */

static inline int within(const pd_particles *p, int64_t i, int64_t j, double cut2);

/* The partners of i at the offsets d, sorted, into nb (with p, only those
 * within the horizon, cut2 its square); returns how many. */
static int64_t family_of(const site_map *m, int32_t (*d)[3], int nk, int64_t i, int32_t *nb,
                         const pd_particles *p, double cut2)
{
    int64_t c = 0;
    for (int k = 0; k < nk; k++) {
        int32_t j = pd_site_partner(m, i, d[k]);
        if (j >= 0 && (p == NULL || within(p, i, j, cut2)))
            nb[c++] = j;
    }
    if (m->ax[0] < 0) /* rows in no lattice order: sort (insertion, short) */
        for (int64_t a = 1; a < c; a++) {
            int32_t v = nb[a];
            int64_t q = a;
            for (; q > 0 && nb[q - 1] > v; q--)
                nb[q] = nb[q - 1];
            nb[q] = v;
        }
    return c;
}

static pd_status expand(const pd_particles *p, const pd_stencil *st, double horizon,
                        const site_map *m, pd_bonds **out)
{
    const int64_t n = p->n;
    int32_t(*d)[3] = pd_sites_walk_order(st, m);
    int64_t *count = malloc((size_t)(n + 1) * sizeof(int64_t));
    if (d == NULL || count == NULL) {
        free(d);
        free(count);
        return pd_fail(PD_ERR_NOMEM, "out of memory expanding the stencil");
    }
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < n; i++) {
        int64_t c = 0;
        for (int k = 0; k < st->nk; k++)
            c += pd_site_partner(m, i, d[k]) >= 0;
        count[i] = c;
    }
    int64_t total = 0;
    for (int64_t i = 0; i < n; i++)
        total += count[i];
    pd_bonds *b = pd_bonds_alloc(n, total);
    if (b == NULL || (b->stencil = stencil_copy(st)) == NULL) {
        free(d);
        free(count);
        pd_bonds_free(b);
        return pd_fail(PD_ERR_NOMEM, "out of memory for %lld bonds", (long long)total);
    }
    b->horizon = horizon;
    for (int64_t i = 0; i < n; i++)
        b->offset[i + 1] = b->offset[i] + count[i];
    free(count);
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < n; i++) {
        const int64_t o = b->offset[i];
        const int64_t c = family_of(m, d, st->nk, i, b->neighbor + o, NULL, 0);
        for (int64_t q = 0; q < c; q++)
            pd_bond_geometry(p, i, b->neighbor[o + q], horizon, &b->length[o + q], &b->vfactor[o + q]);
    }
    free(d);
    memset(b->intact, 0xff, (size_t)pd_bits_words(total) * sizeof(uint64_t));
    *out = b;
    return PD_OK;
}

/* The site map of p on st's lattice, or the error that says why not (m
 * is freed by the caller either way). */
static pd_status stencil_sites(const pd_particles *p, const pd_stencil *st, site_map *m)
{
    if (p->n >= INT32_MAX) {
        memset(m, 0, sizeof *m);
        return pd_fail(PD_ERR_INVALID, "too many particles for one process (%lld)",
                       (long long)p->n);
    }
    int64_t shared = 0;
    sites_result r = pd_sites_build(p, st->origin, st->spacing, m, &shared);
    if (r == SITES_NOMEM)
        return pd_fail(PD_ERR_NOMEM, "out of memory for the lattice sites");
    if (r == SITES_OFF)
        return pd_fail(PD_ERR_FORMAT, "a particle is off the lattice of the bonds' stencil "
                                      "(spacing %g m)", st->spacing);
    if (r == SITES_SPARSE)
        return pd_fail(PD_ERR_FORMAT, "the particles are too sparse on the stencil's lattice "
                                      "(more than %d sites per particle)", PD_STENCIL_SPARSE);
    if (r == SITES_SHARED)
        return pd_fail(PD_ERR_FORMAT, "particle %lld (id %lld) shares its lattice site with "
                                      "another", (long long)shared, (long long)p->id[shared]);
    return PD_OK;
}

pd_status pd_bonds_expand(const pd_particles *p, const pd_stencil *st, double horizon,
                          pd_bonds **out)
{
    *out = NULL;
    site_map m;
    pd_status s = stencil_sites(p, st, &m);
    if (s == PD_OK)
        s = expand(p, st, horizon, &m, out);
    pd_sites_free(&m);
    return s;
}

/* ------------------------------------------------------ compact families */

/* The padded map of a compact body's sites (struct pd_bond_sites), its
 * offsets' steps in it, and each particle's distance from its site. */
static pd_status pad_sites(const pd_particles *p, const pd_stencil *st, struct pd_bond_sites *bs)
{
    const site_map *m = &bs->m;
    int64_t R[3] = {0, 0, 0}, D[3];
    for (int k = 0; k < st->nk; k++)
        for (int a = 0; a < 3; a++)
            R[a] = abs(st->d[k][a]) > R[a] ? abs(st->d[k][a]) : R[a];
    for (int a = 0; a < 3; a++)
        D[a] = m->dim[a] + 2 * R[a];
    const int64_t n = p->n, ns = D[0] * D[1] * D[2];
    bs->delta = malloc((size_t)(st->nk > 0 ? st->nk : 1) * sizeof(int64_t));
    bs->pad = malloc((size_t)ns * sizeof(int32_t));
    bs->at = malloc((size_t)(n > 0 ? n : 1) * sizeof(int64_t));
    if (!bs->delta || !bs->pad || !bs->at)
        return pd_fail(PD_ERR_NOMEM, "out of memory for the lattice sites");
    for (int k = 0; k < bs->nk; k++) {
        const int32_t *d = bs->d[k];
        bs->delta[k] = ((int64_t)d[2] * D[1] + d[1]) * D[0] + d[0];
    }
    memset(bs->pad, 0xff, (size_t)ns * sizeof(int32_t));
    double dev = 0, xmax = 0;
#pragma omp parallel for schedule(static) reduction(max : dev, xmax)
    for (int64_t i = 0; i < n; i++) {
        int64_t c[3];
        double e2 = 0;
        for (int a = 0; a < 3; a++) {
            c[a] = (int64_t)m->c[a][i] - m->lo[a] + R[a];
            const double e = p->x[a][i] - (st->origin[a] + (double)m->c[a][i] * st->spacing);
            e2 += e * e;
            xmax = fabs(p->x[a][i]) > xmax ? fabs(p->x[a][i]) : xmax;
        }
        bs->at[i] = (c[2] * D[1] + c[1]) * D[0] + c[0];
        bs->pad[bs->at[i]] = (int32_t)i;
        dev = sqrt(e2) > dev ? sqrt(e2) : dev;
    }
    bs->dev = dev;
    bs->xmax = xmax;
    /* the unpadded map and the sites are not needed again */
    pd_sites_free(&bs->m);
    memset(&bs->m, 0, sizeof bs->m);
    return PD_OK;
}

pd_status pd_bonds_compact(const pd_particles *p, const pd_stencil *st, double horizon,
                           pd_bonds **out)
{
    *out = NULL;
    struct pd_bond_sites *bs = calloc(1, sizeof *bs);
    if (bs == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for the lattice sites");
    pd_status s = stencil_sites(p, st, &bs->m);
    if (s == PD_OK && bs->m.ax[0] < 0) { /* no lattice order: the lists */
        s = expand(p, st, horizon, &bs->m, out);
        pd_bond_sites_free(bs);
        return s;
    }
    if (s == PD_OK && (bs->d = pd_sites_walk_order(st, &bs->m)) == NULL)
        s = pd_fail(PD_ERR_NOMEM, "out of memory for the stencil");
    bs->nk = st->nk;
    if (s == PD_OK)
        s = pad_sites(p, st, bs);
    const int64_t n = p->n;
    pd_bonds *b = s == PD_OK ? calloc(1, sizeof *b) : NULL;
    if (s == PD_OK && (b == NULL || (b->offset = calloc((size_t)n + 1, sizeof(int64_t))) == NULL ||
                       (b->stencil = stencil_copy(st)) == NULL))
        s = pd_fail(PD_ERR_NOMEM, "out of memory for the bonds");
    if (s != PD_OK) {
        pd_bonds_free(b);
        pd_bond_sites_free(bs);
        return s;
    }
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < n; i++) {
        int64_t c = 0;
        for (int k = 0; k < bs->nk; k++)
            c += bs->pad[bs->at[i] + bs->delta[k]] >= 0;
        b->offset[i + 1] = c;
    }
    for (int64_t i = 0; i < n; i++)
        b->offset[i + 1] += b->offset[i];
    b->n = n;
    b->count = b->offset[n];
    b->horizon = horizon;
    b->sites = bs;
    /* one word more, clear, as pd_bonds_alloc's */
    if ((b->intact = calloc((size_t)pd_bits_words(b->count) + 1, sizeof(uint64_t))) == NULL) {
        pd_bonds_free(b);
        return pd_fail(PD_ERR_NOMEM, "out of memory for %lld bonds", (long long)b->count);
    }
    memset(b->intact, 0xff, (size_t)pd_bits_words(b->count) * sizeof(uint64_t));
    *out = b;
    return PD_OK;
}

pd_status pd_bonds_with_lists(const pd_particles *p, const pd_bonds *b, pd_bonds **out)
{
    *out = NULL;
    if (b->sites == NULL || b->stencil == NULL)
        return pd_fail(PD_ERR_INVALID, "the bonds are not compact");
    pd_bonds *c = NULL;
    pd_status s = pd_bonds_expand(p, b->stencil, b->horizon, &c);
    if (s != PD_OK)
        return s;
    if (c->count != b->count) {
        pd_bonds_free(c);
        return pd_fail(PD_ERR_INVALID, "the stencil expands to %lld bonds, not %lld",
                       (long long)c->count, (long long)b->count);
    }
    const size_t words = (size_t)pd_bits_words(b->count);
    memcpy(c->intact, b->intact, words * sizeof(uint64_t));
    if (b->precrack) {
        if ((c->precrack = calloc(words + 1, sizeof(uint64_t))) == NULL) {
            pd_bonds_free(c);
            return pd_fail(PD_ERR_NOMEM, "out of memory for the pre-crack");
        }
        memcpy(c->precrack, b->precrack, words * sizeof(uint64_t));
    }
    *out = c;
    return PD_OK;
}

/* ------------------------------------------------------------ the finding */

/* Do the families of b equal the stencil's, bit for bit? */
static int same_families(const pd_particles *p, const pd_bonds *b, const pd_stencil *st,
                         const site_map *m)
{
    int32_t(*d)[3] = pd_sites_walk_order(st, m);
    int same = d != NULL;
#pragma omp parallel reduction(&& : same)
    {
        int32_t *nb = d ? malloc((size_t)(st->nk > 0 ? st->nk : 1) * sizeof(int32_t)) : NULL;
        same = nb != NULL; /* out of memory: the bond lists stay */
#pragma omp for schedule(static)
        for (int64_t i = 0; i < b->n; i++) {
            if (!same)
                continue;
            const int64_t o = b->offset[i], c = family_of(m, d, st->nk, i, nb, NULL, 0);
            same = c == b->offset[i + 1] - o;
            for (int64_t q = 0; q < c && same; q++) {
                double len, nu;
                pd_bond_geometry(p, i, nb[q], b->horizon, &len, &nu);
                same = nb[q] == b->neighbor[o + q] &&
                       memcmp(&len, &b->length[o + q], sizeof len) == 0 &&
                       memcmp(&nu, &b->vfactor[o + q], sizeof nu) == 0;
            }
        }
        free(nb);
    }
    free(d);
    return same;
}

pd_status pd_bonds_find_stencil(const pd_particles *p, pd_bonds *b)
{
    pd_stencil_free(b->stencil);
    b->stencil = NULL;
    if (b->count == 0 || p->n < 2 || p->n >= INT32_MAX)
        return PD_OK;
    double origin[3], hi[3];
    pd_particles_bounds(p, origin, hi);
    site_map m;
    int64_t shared = 0;
    sites_result r = pd_sites_build(p, origin, p->spacing, &m, &shared);
    if (r != SITES_OK) {
        pd_sites_free(&m);
        return r == SITES_NOMEM ? pd_fail(PD_ERR_NOMEM, "out of memory for the lattice sites")
                                : PD_OK;
    }
    /* every offset a bond has, with its first bond (lowest row) */
    const int R = PD_STENCIL_REACH, w = 2 * R + 1;
    int64_t *first = malloc((size_t)w * w * w * sizeof(int64_t));
    if (first == NULL) {
        pd_sites_free(&m);
        return pd_fail(PD_ERR_NOMEM, "out of memory for the stencil");
    }
    for (int q = 0; q < w * w * w; q++)
        first[q] = -1;
    int ok = 1, nk = 0;
    for (int64_t i = 0; i < b->n && ok; i++)
        for (int64_t q = b->offset[i]; q < b->offset[i + 1] && ok; q++) {
            const int32_t j = b->neighbor[q];
            int at = 0;
            for (int a = 2; a >= 0; a--) {
                const int64_t dd = (int64_t)m.c[a][j] - m.c[a][i];
                ok = ok && dd >= -R && dd <= R;
                at = at * w + (int)(dd + R);
            }
            if (ok && first[at] < 0) {
                first[at] = q;
                nk++;
            }
        }
    pd_stencil *st = ok ? pd_stencil_alloc(nk) : NULL;
    pd_status s = ok && st == NULL ? pd_fail(PD_ERR_NOMEM, "out of memory for the stencil") : PD_OK;
    if (st) {
        int k = 0;
        for (int q = 0; q < w * w * w; q++) /* (z, y, x) ascending */
            if (first[q] >= 0) {
                st->d[k][0] = q % w - R;
                st->d[k][1] = (q / w) % w - R;
                st->d[k][2] = q / (w * w) - R;
                st->length[k] = b->length[first[q]];
                st->vfactor[k] = b->vfactor[first[q]];
                k++;
            }
        memcpy(st->origin, origin, sizeof origin);
        st->spacing = p->spacing;
        if (same_families(p, b, st, &m))
            b->stencil = st;
        else
            pd_stencil_free(st);
    }
    free(first);
    pd_sites_free(&m);
    return s;
}

/* ------------------------------------------------- building on a lattice */

/* Is bond i-j within the horizon?  pd_bonds_build's test (lib/bonds/bonds.c,
 * family()), the same arithmetic. */
static inline int within(const pd_particles *p, int64_t i, int64_t j, double cut2)
{
    double dx = p->x[0][i] - p->x[0][j], dy = p->x[1][i] - p->x[1][j],
           dz = p->x[2][i] - p->x[2][j];
    return dx * dx + dy * dy + dz * dz <= cut2;
}

/* Every offset that can hold a pair within the horizon: |d| h <= delta +
 * 1e-5 h covers the sites' tolerance of PD_LATTICE_TOL at both ends. */
static pd_stencil *candidates(double horizon, double h)
{
    const int R = (int)floor(horizon / h + 1e-5);
    const double lim = (horizon / h + 1e-5) * (horizon / h + 1e-5);
    int nk = 0;
    for (int pass = 0; pass < 2; pass++) {
        pd_stencil *st = pass ? pd_stencil_alloc(nk) : NULL;
        if (pass && st == NULL)
            return NULL;
        int k = 0;
        for (int z = -R; z <= R; z++)
            for (int y = -R; y <= R; y++)
                for (int x = -R; x <= R; x++)
                    if ((x || y || z) && (double)(x * x + y * y + z * z) <= lim) {
                        if (pass) {
                            st->d[k][0] = x;
                            st->d[k][1] = y;
                            st->d[k][2] = z;
                        }
                        k++;
                    }
        if (pass)
            return st;
        nk = k;
    }
    return NULL;
}

pd_status pd_bonds_build_lattice(const pd_particles *p, double horizon, int lists,
                                 pd_bonds **out)
{
    *out = NULL;
    const double h = p->spacing;
    if (p->n < 2 || p->n >= INT32_MAX || !(h > 0) || !isfinite(h) ||
        !(horizon / h + 1e-5 < PD_STENCIL_REACH + 1))
        return PD_OK;
    double origin[3], hi[3];
    pd_particles_bounds(p, origin, hi);
    site_map m;
    int64_t shared = 0;
    sites_result r = pd_sites_build(p, origin, h, &m, &shared);
    if (r != SITES_OK) { /* off the lattice, sparse, two at one site: cell lists */
        pd_sites_free(&m);
        return r == SITES_NOMEM ? pd_fail(PD_ERR_NOMEM, "out of memory for the lattice sites")
                                : PD_OK;
    }
    const int64_t n = p->n;
    const double cut2 = horizon * horizon;
    pd_stencil *cand = candidates(horizon, h);
    int32_t(*d)[3] = cand ? pd_sites_walk_order(cand, &m) : NULL;
    const int nk = cand ? cand->nk : 0;
    /* per walked offset: pairs within the horizon, pairs there at all, and
     * the first row with a bond there */
    int64_t *in = calloc((size_t)nk + 1, sizeof(int64_t)), *there = calloc((size_t)nk + 1, 8);
    int64_t *first = malloc(((size_t)nk + 1) * sizeof(int64_t));
    int64_t *count = malloc((size_t)(n + 1) * sizeof(int64_t));
    pd_bonds *b = NULL;
    pd_status s = PD_OK;
    if (!d || !in || !there || !first || !count)
        s = pd_fail(PD_ERR_NOMEM, "out of memory for the bonds");
    for (int k = 0; k < nk && s == PD_OK; k++)
        first[k] = INT64_MAX;
    if (s == PD_OK) {
#pragma omp parallel
        {
            int64_t *my_in = calloc(2 * (size_t)nk + 1, sizeof(int64_t)), *my_there = my_in + nk;
            int64_t *my_first = malloc(((size_t)nk + 1) * sizeof(int64_t));
            for (int k = 0; my_first && k < nk; k++)
                my_first[k] = INT64_MAX;
#pragma omp for schedule(static)
            for (int64_t i = 0; i < n; i++) {
                int64_t c = 0;
                for (int k = 0; k < nk; k++) {
                    const int32_t j = pd_site_partner(&m, i, d[k]);
                    if (j < 0)
                        continue;
                    const int w = within(p, i, j, cut2);
                    c += w;
                    if (my_in && my_first) {
                        my_there[k]++;
                        my_in[k] += w;
                        if (w && i < my_first[k])
                            my_first[k] = i;
                    }
                }
                count[i] = c;
            }
#pragma omp critical
            {
                if (my_in == NULL || my_first == NULL)
                    in[nk] = 1; /* a thread without its tallies: no stencil */
                for (int k = 0; my_in && my_first && k < nk; k++) {
                    in[k] += my_in[k];
                    there[k] += my_there[k];
                    first[k] = my_first[k] < first[k] ? my_first[k] : first[k];
                }
            }
            free(my_in);
            free(my_first);
        }
        int64_t total = 0;
        for (int64_t i = 0; i < n; i++)
            total += count[i];
        if ((b = pd_bonds_alloc(n, total)) == NULL)
            s = pd_fail(PD_ERR_NOMEM, "out of memory for %lld bonds", (long long)total);
        for (int64_t i = 0; i < n && b; i++)
            b->offset[i + 1] = b->offset[i] + count[i];
    }
    /* a stencil when every offset holds all of its pairs or none */
    int uniform = s == PD_OK && b->count > 0 && in[nk] == 0, used = 0;
    for (int k = 0; k < nk && s == PD_OK; k++) {
        uniform = uniform && (in[k] == 0 || in[k] == there[k]);
        used += in[k] > 0;
    }
    if (s == PD_OK && uniform && !lists) { /* the stencil stands for the lists */
        free(b->neighbor);
        free(b->length);
        free(b->vfactor);
        b->neighbor = NULL;
        b->length = b->vfactor = NULL;
    }
    if (s == PD_OK) {
        b->horizon = horizon;
#pragma omp parallel for schedule(static) if (b->neighbor)
        for (int64_t i = 0; i < n; i++) {
            if (b->neighbor == NULL)
                continue;
            int32_t *nb = b->neighbor + b->offset[i];
            const int64_t c = family_of(&m, d, nk, i, nb, p, cut2);
            for (int64_t q = 0; q < c; q++)
                pd_bond_geometry(p, i, nb[q], horizon, &b->length[b->offset[i] + q],
                              &b->vfactor[b->offset[i] + q]);
        }
        memset(b->intact, 0xff, (size_t)pd_bits_words(b->count) * sizeof(uint64_t));
        pd_stencil *st = uniform ? pd_stencil_alloc(used) : NULL;
        if (st) { /* in (z, y, x) order: the candidates' own */
            int q = 0;
            for (int c = 0; c < cand->nk; c++)
                for (int k = 0; k < nk; k++)
                    if (in[k] > 0 && memcmp(d[k], cand->d[c], sizeof d[k]) == 0) {
                        memcpy(st->d[q], d[k], sizeof d[k]);
                        const int32_t j = pd_site_partner(&m, first[k], d[k]);
                        pd_bond_geometry(p, first[k], j, horizon, &st->length[q], &st->vfactor[q]);
                        q++;
                    }
            memcpy(st->origin, origin, sizeof origin);
            st->spacing = h;
            b->stencil = st;
        }
    }
    free(d);
    free(in);
    free(there);
    free(first);
    free(count);
    pd_stencil_free(cand);
    pd_sites_free(&m);
    if (s != PD_OK) {
        pd_bonds_free(b);
        return s;
    }
    *out = b;
    return PD_OK;
}
