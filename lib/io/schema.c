/*
 * schema.c -- the pd-h5 layout (schema v1, man/man5/pd-h5.5): root
 * attributes and history, /particles, /bonds, /scene and /frames.  Readers
 * validate everything before use: dtypes, shapes, sizes consistent across
 * datasets, values in their domain, CSR offsets and neighbours in range,
 * families symmetric.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/comm.h"
#include "io/h5util.h"
#include "models/model.h"

/* ------------------------------------------------------------ header */

pd_status pd_read_history(const pd_file *f, char **out)
{
    if (!pd_h5_has_attr(f->fid, "history")) {
        *out = strdup("");
        return *out ? PD_OK : pd_fail(PD_ERR_NOMEM, "out of memory");
    }
    return pd_h5_read_attr_string(f->fid, "history", out);
}

static pd_status write_history(pd_file *f, const char *old, const char *cmdline)
{
    size_t len = strlen(old) + strlen(cmdline) + 2;
    char *h = malloc(len);
    if (h == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory");
    snprintf(h, len, "%s%s%s", old, (old[0] && old[strlen(old) - 1] != '\n') ? "\n" : "",
             cmdline);
    pd_status s = pd_h5_write_attr_string(f->fid, "history", h);
    free(h);
    return s;
}

pd_status pd_write_header(pd_file *f, const pd_file *from, const char *cmdline)
{
    pd_status s;
    if ((s = pd_h5_write_attr_string(f->fid, "pd_format", PD_FORMAT)) != PD_OK ||
        (s = pd_h5_write_attr_int(f->fid, "pd_format_version", PD_FORMAT_VERSION)) != PD_OK ||
        (s = pd_h5_write_attr_string(f->fid, "units", "SI")) != PD_OK)
        return s;
    char *old = NULL;
    if (from != NULL && (s = pd_read_history(from, &old)) != PD_OK)
        return s;
    s = write_history(f, old ? old : "", cmdline);
    free(old);
    return s;
}

pd_status pd_append_history(pd_file *f, const char *cmdline)
{
    char *old = NULL;
    pd_status s = pd_read_history(f, &old);
    if (s != PD_OK)
        return s;
    s = write_history(f, old, cmdline);
    free(old);
    return s;
}

/* ------------------------------------------------------------ particles */

/* (n,3) into SoA arrays, and back. */
static void deinterleave(double *const x[3], const double *buf, int64_t n)
{
    for (int64_t i = 0; i < n; i++)
        for (int d = 0; d < 3; d++)
            x[d][i] = buf[3 * i + d];
}

/* Interleave SoA arrays into (n,3). */
static void interleave(double *buf, double *const x[3], int64_t n)
{
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < n; i++)
        for (int d = 0; d < 3; d++)
            buf[3 * i + d] = x[d][i];
}

static const pd_h5_form F64_N3 = {H5T_FLOAT, 8, 2, {0, 3}};

static int cmp_int64(const void *a, const void *b)
{
    int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
    return (x > y) - (x < y);
}

/* Ids are the particles' stable names: no two of the n may be equal. */
static pd_status check_unique_ids(const char *fn, const int64_t *id, int64_t n)
{
    int64_t *ids = malloc((size_t)(n > 0 ? n : 1) * sizeof(int64_t));
    if (ids == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory checking ids");
    memcpy(ids, id, (size_t)n * sizeof(int64_t));
    qsort(ids, (size_t)n, sizeof *ids, cmp_int64);
    pd_status s = PD_OK;
    for (int64_t i = 1; i < n; i++)
        if (ids[i] == ids[i - 1]) {
            s = pd_fail(PD_ERR_FORMAT, "'%s': particle id %lld appears twice", fn,
                        (long long)ids[i]);
            break;
        }
    free(ids);
    return s;
}

/* The attributes of /particles into p, checked. */
static pd_status read_particle_attrs(const pd_file *f, pd_particles *p)
{
    const char *fn = f->name;
    hid_t g = H5Gopen2(f->fid, "/particles", H5P_DEFAULT);
    int64_t dim = 3;
    pd_status s = pd_h5_read_attr_double(g, "spacing", &p->spacing);
    if (s == PD_OK && pd_h5_has_attr(g, "dimension"))
        s = pd_h5_read_attr_int(g, "dimension", &dim);
    /* a plate (dimension 2) says its thickness */
    int has_thickness = pd_h5_has_attr(g, "thickness");
    if (s == PD_OK && dim == 2 && has_thickness)
        s = pd_h5_read_attr_double(g, "thickness", &p->thickness);
    H5Gclose(g);
    if (s != PD_OK)
        return pd_fail(PD_ERR_FORMAT, "'%s': /particles: %s", fn, pd_errmsg());
    p->dimension = (int)dim;
    if (!(p->spacing > 0) || !isfinite(p->spacing))
        return pd_fail(PD_ERR_FORMAT, "'%s': /particles spacing must be positive", fn);
    if (dim != 3 && dim != 2)
        return pd_fail(PD_ERR_FORMAT, "'%s': /particles dimension %lld (this pd runs 3-D bodies "
                       "and 2-D plates)", fn, (long long)dim);
    if (dim == 2 && !has_thickness)
        return pd_fail(PD_ERR_FORMAT, "'%s': /particles of dimension 2 without a thickness", fn);
    if (dim == 2 && (!(p->thickness > 0) || !isfinite(p->thickness)))
        return pd_fail(PD_ERR_FORMAT, "'%s': /particles thickness must be positive, not %g", fn,
                       p->thickness);
    return PD_OK;
}

/* Each of p's rows checked: row i is the body's particle first + i. */
static pd_status check_particle_rows(const char *fn, const pd_particles *p, int64_t first)
{
    const int dim = p->dimension;
    for (int64_t i = 0; i < p->n; i++) {
        const long long g = (long long)(first + i);
        if (!isfinite(p->x[0][i]) || !isfinite(p->x[1][i]) || !isfinite(p->x[2][i]))
            return pd_fail(PD_ERR_FORMAT, "'%s': particle %lld has a non-finite position", fn,
                           g);
        if (dim == 2 && p->x[2][i] != 0)
            return pd_fail(PD_ERR_FORMAT, "'%s': particle %lld of a plate (dimension 2) has "
                           "z = %g, not 0", fn, g, p->x[2][i]);
        if (!(p->volume[i] > 0) || !isfinite(p->volume[i]))
            return pd_fail(PD_ERR_FORMAT, "'%s': particle %lld has volume %g", fn, g,
                           p->volume[i]);
        if (!(p->density[i] > 0) || !isfinite(p->density[i]))
            return pd_fail(PD_ERR_FORMAT, "'%s': particle %lld has density %g", fn, g,
                           p->density[i]);
        if (!(p->radius[i] > 0) || !isfinite(p->radius[i]))
            return pd_fail(PD_ERR_FORMAT, "'%s': particle %lld has radius %g", fn, g,
                           p->radius[i]);
        if (p->id[i] < 1)
            return pd_fail(PD_ERR_FORMAT, "'%s': particle %lld has id %lld (ids start at 1)", fn,
                           g, (long long)p->id[i]);
    }
    return PD_OK;
}

pd_status pd_file_particles(const pd_file *f, int64_t *n)
{
    const char *fn = f->name;
    *n = 0;
    if (!pd_h5_has_link(f->fid, "/particles"))
        return pd_fail(PD_ERR_FORMAT, "'%s' has no /particles (not made by pd-lattice?)", fn);
    pd_status s = pd_h5_rows(f->fid, fn, "/particles/position", &F64_N3, n);
    if (s == PD_OK && *n == 0)
        s = pd_fail(PD_ERR_FORMAT, "'%s' holds no particles", fn);
    else if (s == PD_OK && *n >= INT32_MAX)
        s = pd_fail(PD_ERR_FORMAT, "'%s' holds too many particles for one process", fn);
    return s;
}

/* Rows [g0, g1) of the n particles of f, checked row by row. */
static pd_status read_particle_rows(const pd_file *f, int64_t n, int64_t g0, int64_t g1,
                                    pd_particles **out)
{
    const char *fn = f->name;
    *out = NULL;
    const int64_t m = g1 - g0;
    pd_particles *p = pd_particles_new(m);
    double *pos = malloc((size_t)(m > 0 ? m : 1) * 3 * sizeof(double));
    pd_status s = p && pos ? PD_OK
                           : pd_fail(PD_ERR_NOMEM, "out of memory for %lld particles",
                                     (long long)m);
    const pd_h5_form pf = {H5T_FLOAT, 8, 2, {(hsize_t)n, 3}};
    if (s == PD_OK)
        s = pd_h5_read_rows(f->fid, fn, "/particles/position", &pf, H5T_NATIVE_DOUBLE, pos, g0,
                            m);
    if (s == PD_OK)
        deinterleave(p->x, pos, m);
    free(pos);
    struct {
        const char *name;
        H5T_class_t cls;
        size_t size;
        hid_t mt;
        void *dst;
    } fields[] = {
        {"/particles/volume", H5T_FLOAT, 8, H5T_NATIVE_DOUBLE, p ? p->volume : NULL},
        {"/particles/density", H5T_FLOAT, 8, H5T_NATIVE_DOUBLE, p ? p->density : NULL},
        {"/particles/radius", H5T_FLOAT, 8, H5T_NATIVE_DOUBLE, p ? p->radius : NULL},
        {"/particles/material", H5T_INTEGER, 4, H5T_NATIVE_INT32, p ? p->material : NULL},
        {"/particles/id", H5T_INTEGER, 8, H5T_NATIVE_INT64, p ? p->id : NULL},
    };
    for (size_t k = 0; k < sizeof fields / sizeof fields[0] && s == PD_OK; k++) {
        const pd_h5_form form = {fields[k].cls, fields[k].size, 1, {(hsize_t)n, 0}};
        s = pd_h5_read_rows(f->fid, fn, fields[k].name, &form, fields[k].mt, fields[k].dst, g0,
                            m);
    }
    if (s == PD_OK)
        s = read_particle_attrs(f, p);
    if (s == PD_OK)
        s = check_particle_rows(fn, p, g0);
    if (s != PD_OK) {
        pd_particles_free(p);
        return s;
    }
    *out = p;
    return PD_OK;
}

pd_status pd_read_particles(const pd_file *f, pd_particles **out)
{
    *out = NULL;
    int64_t n = 0;
    pd_particles *p = NULL;
    pd_status s = pd_file_particles(f, &n);
    if (s == PD_OK)
        s = read_particle_rows(f, n, 0, n, &p);
    if (s == PD_OK)
        s = check_unique_ids(f->name, p->id, n);
    if (s != PD_OK) {
        pd_particles_free(p);
        return s;
    }
    *out = p;
    return PD_OK;
}

pd_status pd_read_particles_rows(const pd_file *f, int64_t n, int64_t g0, int64_t g1,
                                 pd_particles **out)
{
    pd_status s = read_particle_rows(f, n, g0, g1, out);
    if (s == PD_OK) {
        pd_particles *p = *out;
        p->window = 1;
        p->first = g0;
        p->total = n;
        p->own_lo = 0;
        p->own_hi = p->n;
    }
    return s;
}

pd_status pd_check_ids_ranks(const pd_file *f, const pd_particles *p)
{
    /* each id to the rank of its range of ids, which sorts what it gets:
     * the smallest id that appears twice over the ranks (collective) */
    const int P = pd_comm_size();
    const int64_t m = p->n;
    int64_t lo = INT64_MAX, hi = INT64_MIN;
    for (int64_t i = 0; i < m; i++) {
        lo = p->id[i] < lo ? p->id[i] : lo;
        hi = p->id[i] > hi ? p->id[i] : hi;
    }
    lo = pd_comm_min(lo);
    hi = -pd_comm_min(-hi); /* ids are at least 1: no overflow */
    const int64_t width = hi >= lo ? (hi - lo) / P + 1 : 1;
    int64_t *count = calloc((size_t)P * 2, sizeof(int64_t));
    int64_t *at = malloc((size_t)P * sizeof(int64_t));
    int64_t *sent = malloc((size_t)(m > 0 ? m : 1) * sizeof(int64_t)), *got = NULL;
    pd_status s = count && at && sent ? PD_OK : pd_fail(PD_ERR_NOMEM, "out of memory checking ids");
    s = pd_comm_agree(s);
    int64_t nget = 0, twice = INT64_MAX;
    if (s == PD_OK) {
        for (int64_t i = 0; i < m; i++)
            count[(p->id[i] - lo) / width]++;
        for (int r = 0, k = 0; r < P; k += count[r], r++)
            at[r] = k;
        for (int64_t i = 0; i < m; i++)
            sent[at[(p->id[i] - lo) / width]++] = p->id[i];
        pd_comm_counts_to(count, count + P);
        for (int r = 0; r < P; r++)
            nget += count[P + r];
        got = malloc((size_t)(nget > 0 ? nget : 1) * sizeof(int64_t));
        s = pd_comm_agree(got ? PD_OK : pd_fail(PD_ERR_NOMEM, "out of memory checking ids"));
    }
    if (s == PD_OK) {
        pd_comm_alltoall_int(sent, count, got, count + P);
        qsort(got, (size_t)nget, sizeof *got, cmp_int64);
        for (int64_t i = 1; i < nget && twice == INT64_MAX; i++)
            if (got[i] == got[i - 1])
                twice = got[i];
        twice = pd_comm_min(twice);
        if (twice != INT64_MAX)
            s = pd_fail(PD_ERR_FORMAT, "'%s': particle id %lld appears twice", f->name,
                        (long long)twice);
    }
    free(count);
    free(at);
    free(sent);
    free(got);
    return s;
}

/* The attributes of /particles (g). */
static pd_status write_particle_attrs(hid_t g, const pd_particles *p)
{
    pd_status s = pd_h5_write_attr_doubles(g, "spacing", &p->spacing, 1);
    if (s == PD_OK)
        s = pd_h5_write_attr_int(g, "dimension", p->dimension);
    if (s == PD_OK && p->dimension == 2)
        s = pd_h5_write_attr_doubles(g, "thickness", &p->thickness, 1);
    return s;
}

pd_status pd_write_particles(pd_file *f, const pd_particles *p)
{
    hid_t g = pd_h5_create_group(f->fid, "/particles");
    if (g < 0)
        return pd_fail(PD_ERR_IO, "cannot create /particles");
    size_t n = (size_t)p->n;
    double *pos = malloc((n ? n : 1) * 3 * sizeof(double));
    if (pos == NULL) {
        H5Gclose(g);
        return pd_fail(PD_ERR_NOMEM, "out of memory");
    }
    interleave(pos, p->x, p->n);
    hsize_t d2[2] = {n, 3}, d1[1] = {n};
    pd_status s;
    if ((s = pd_h5_write_data(g, "position", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 2, d2, pos)) ==
            PD_OK &&
        (s = pd_h5_write_data(g, "volume", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 1, d1,
                              p->volume)) == PD_OK &&
        (s = pd_h5_write_data(g, "density", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 1, d1,
                              p->density)) == PD_OK &&
        (s = pd_h5_write_data(g, "radius", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 1, d1,
                              p->radius)) == PD_OK &&
        (s = pd_h5_write_data(g, "material", H5T_STD_I32LE, H5T_NATIVE_INT32, 1, d1,
                              p->material)) == PD_OK &&
        (s = pd_h5_write_data(g, "id", H5T_STD_I64LE, H5T_NATIVE_INT64, 1, d1, p->id)) ==
            PD_OK)
        s = write_particle_attrs(g, p);
    free(pos);
    H5Gclose(g);
    return s;
}

pd_status pd_write_particles_part(pd_file *f, const pd_part *pt, const pd_particles *p)
{
    hid_t g = pd_h5_create_group(f->fid, "/particles");
    if (g < 0)
        return pd_fail(PD_ERR_IO, "cannot create /particles");
    const int64_t lo = pt->lo, m = pt->rows;
    double *pos = malloc((size_t)(m > 0 ? m : 1) * 3 * sizeof(double));
    pd_status s = pos ? PD_OK : pd_fail(PD_ERR_NOMEM, "out of memory");
    if (f->ranks > 1)
        s = pd_comm_agree(s);
    if (pos) {
        double *const x[3] = {p->x[0] + lo, p->x[1] + lo, p->x[2] + lo};
        interleave(pos, x, m);
    }
    hsize_t d2[2] = {(hsize_t)pt->n, 3}, d1[1] = {(hsize_t)pt->n};
    if (s == PD_OK &&
        (s = pd_h5_reserve_data(g, "position", H5T_IEEE_F64LE, 2, d2)) == PD_OK &&
        (s = pd_h5_reserve_data(g, "volume", H5T_IEEE_F64LE, 1, d1)) == PD_OK &&
        (s = pd_h5_reserve_data(g, "density", H5T_IEEE_F64LE, 1, d1)) == PD_OK &&
        (s = pd_h5_reserve_data(g, "radius", H5T_IEEE_F64LE, 1, d1)) == PD_OK &&
        (s = pd_h5_reserve_data(g, "material", H5T_STD_I32LE, 1, d1)) == PD_OK &&
        (s = pd_h5_reserve_data(g, "id", H5T_STD_I64LE, 1, d1)) == PD_OK &&
        (s = pd_h5_write_rows(g, "position", H5T_NATIVE_DOUBLE, pos, pt->first, m)) == PD_OK &&
        (s = pd_h5_write_rows(g, "volume", H5T_NATIVE_DOUBLE, p->volume + lo, pt->first, m)) ==
            PD_OK &&
        (s = pd_h5_write_rows(g, "density", H5T_NATIVE_DOUBLE, p->density + lo, pt->first, m)) ==
            PD_OK &&
        (s = pd_h5_write_rows(g, "radius", H5T_NATIVE_DOUBLE, p->radius + lo, pt->first, m)) ==
            PD_OK &&
        (s = pd_h5_write_rows(g, "material", H5T_NATIVE_INT32, p->material + lo, pt->first,
                              m)) == PD_OK &&
        (s = pd_h5_write_rows(g, "id", H5T_NATIVE_INT64, p->id + lo, pt->first, m)) == PD_OK)
        s = write_particle_attrs(g, p);
    free(pos);
    H5Gclose(g);
    return s;
}

/* ------------------------------------------------------------ bonds */

int pd_file_has_bonds(const pd_file *f)
{
    return pd_h5_has_link(f->fid, "/bonds");
}

int pd_file_has_frames(const pd_file *f)
{
    return pd_h5_has_link(f->fid, "/frames");
}

/* Packed little-endian bits (bond b = bit b%8 of byte b/8) <-> words. */
static void bytes_to_words(const uint8_t *bytes, int64_t count, uint64_t *words)
{
    int64_t nb = (count + 7) / 8;
    memset(words, 0, (size_t)pd_bits_words(count) * sizeof(uint64_t));
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
    memcpy(words, bytes, (size_t)nb); /* the words' own bytes, in their order */
#else
    for (int64_t k = 0; k < nb; k++)
        words[k / 8] |= (uint64_t)bytes[k] << (8 * (k % 8));
#endif
    /* bits past `count` stay clear */
    if (count % 64)
        words[count / 64] &= (UINT64_C(1) << (count % 64)) - 1;
}

static uint8_t *words_to_bytes(const uint64_t *words, int64_t count)
{
    int64_t nb = (count + 7) / 8;
    uint8_t *bytes = malloc((size_t)(nb ? nb : 1));
    if (bytes == NULL)
        return NULL;
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
    memcpy(bytes, words, (size_t)nb);
#else
    for (int64_t k = 0; k < nb; k++)
        bytes[k] = (uint8_t)(words[k / 8] >> (8 * (k % 8)));
#endif
    if (count % 8)
        bytes[nb - 1] &= (uint8_t)((1u << (count % 8)) - 1);
    return bytes;
}

/* 8 bond bits from bit k of words (k + 7 within them). */
static uint8_t bits8(const uint64_t *words, int64_t k)
{
    const int64_t w = k >> 6;
    const int o = (int)(k & 63);
    uint64_t v = words[w] >> o;
    if (o > 56)
        v |= words[w + 1] << (64 - o);
    return (uint8_t)v;
}

/* The bytes of a frame's bond states that a part writes: the body's bits
 * [bond0, bond0 + bonds), the part's local bits from klo, as bytes
 * [*at, *at + *count) of the body's.  On MPI ranks a byte the part shares
 * with the part below gets that part's bits (a chain over the ranks, which
 * every rank joins), and a byte it shares with the part above is left to
 * that part. */
static uint8_t *state_bytes(const pd_file *f, const pd_part *pt, const uint64_t *intact,
                            int64_t *at, int64_t *count)
{
    const int64_t g0 = pt->bond0, g1 = pt->bond0 + pt->bonds, B0 = g0 / 8, B1 = (g1 + 7) / 8;
    uint8_t *bytes = NULL;
    if (f->ranks <= 1 && g0 == 0 && pt->klo == 0) { /* the whole body's, as they lie */
        bytes = words_to_bytes(intact, pt->bonds);
        *at = 0;
        *count = B1;
        return bytes;
    }
    bytes = calloc((size_t)(B1 > B0 ? B1 - B0 : 1), 1);
    if (bytes) {
        const int64_t shift = pt->klo - g0; /* local bit of body bit g */
        for (int64_t B = B0; B < B1; B++) {
            const int64_t lo = B * 8 > g0 ? B * 8 : g0, hi = B * 8 + 8 < g1 ? B * 8 + 8 : g1;
            if (lo == B * 8 && hi == B * 8 + 8)
                bytes[B - B0] = bits8(intact, B * 8 + shift);
            else
                for (int64_t g = lo; g < hi; g++)
                    bytes[B - B0] |= (uint8_t)(pd_bond_intact(intact, g + shift) << (g % 8));
        }
    }
    int64_t end = B1;
    if (f->ranks > 1) {
        const int carry = (int)pd_comm_chain_in();
        int out = 0;
        if (bytes && B1 > B0)
            bytes[0] |= (uint8_t)carry;
        if (pd_comm_rank() + 1 < f->ranks && g1 % 8) { /* the next part's first byte */
            out = B1 > B0 ? (bytes ? bytes[B1 - 1 - B0] : 0) : carry;
            end = B1 - 1;
        }
        pd_comm_chain_out((double)out);
    }
    *at = B0;
    *count = end > B0 ? end - B0 : 0;
    return bytes;
}

/* Check the CSR structure; families must be sorted and symmetric with equal
 * state (and pre-crack bits) on both sides. */
static pd_status check_compact(const char *fn, const pd_particles *p, const pd_bonds *b);
static int64_t row_of(const pd_bonds *b, int64_t k);

static pd_status check_bond_rows(const char *fn, const pd_bonds *b, int64_t g0, int64_t g1,
                                 int64_t k0, int64_t first)
{
    for (int64_t i = g0; i < g1; i++)
        for (int64_t k = b->offset[i]; k < b->offset[i + 1]; k++) {
            const int32_t j = b->neighbor[k];
            if (j == i)
                return pd_fail(PD_ERR_FORMAT, "'%s': particle %lld is bonded to itself", fn,
                               (long long)(first + i));
            if (k > b->offset[i] && b->neighbor[k - 1] >= j)
                return pd_fail(PD_ERR_FORMAT, "'%s': family of particle %lld is not sorted", fn,
                               (long long)(first + i));
            if (!(b->length[k] > 0) || !isfinite(b->length[k]))
                return pd_fail(PD_ERR_FORMAT, "'%s': bond %lld has length %g", fn,
                               (long long)(k0 + k), b->length[k]);
            if (b->length[k] > b->horizon * (1 + 1e-9))
                return pd_fail(PD_ERR_FORMAT, "'%s': bond %lld is %g m long, beyond the horizon "
                                              "%g m", fn, (long long)(k0 + k), b->length[k],
                               b->horizon);
            if (!(b->vfactor[k] > 0 && b->vfactor[k] <= 1))
                return pd_fail(PD_ERR_FORMAT, "'%s': bond %lld has volume factor %g", fn,
                               (long long)(k0 + k), b->vfactor[k]);
        }
    /* as check_bonds: the mirror of i-j (j < i) is the next unmatched entry
     * above the diagonal in j's row */
    int64_t *next = malloc((size_t)(g1 > g0 ? g1 - g0 : 1) * sizeof(int64_t));
    if (next == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory checking bonds");
    for (int64_t j = g0; j < g1; j++) {
        int64_t q = b->offset[j];
        while (q < b->offset[j + 1] && b->neighbor[q] < j)
            q++;
        next[j - g0] = q;
    }
    pd_status s = PD_OK;
    for (int64_t i = g0; i < g1 && s == PD_OK; i++)
        for (int64_t k = b->offset[i]; k < b->offset[i + 1] && b->neighbor[k] < i && s == PD_OK;
             k++) {
            const int64_t j = b->neighbor[k];
            if (j < g0)
                continue;
            const int64_t q = next[j - g0]++;
            if (q >= b->offset[j + 1] || b->neighbor[q] != i)
                s = pd_fail(PD_ERR_FORMAT,
                            "'%s': bonds are not symmetric (%lld-%lld has no %lld-%lld)", fn,
                            (long long)(first + i), (long long)(first + j),
                            (long long)(first + j), (long long)(first + i));
            else if (pd_bond_intact(b->intact, k) != pd_bond_intact(b->intact, q))
                s = pd_fail(PD_ERR_FORMAT,
                            "'%s': bond %lld-%lld is broken on one side only (state bits differ)",
                            fn, (long long)(first + j), (long long)(first + i));
            else if (b->precrack &&
                     pd_bond_intact(b->precrack, k) != pd_bond_intact(b->precrack, q))
                s = pd_fail(PD_ERR_FORMAT,
                            "'%s': bond %lld-%lld is pre-cracked on one side only (precrack bits "
                            "differ)",
                            fn, (long long)(first + j), (long long)(first + i));
        }
    for (int64_t j = g0; j < g1 && s == PD_OK; j++) {
        const int64_t q = next[j - g0];
        if (q < b->offset[j + 1] && b->neighbor[q] < g1)
            s = pd_fail(PD_ERR_FORMAT, "'%s': bonds are not symmetric (%lld-%lld has no %lld-%lld)",
                        fn, (long long)(first + j), (long long)(first + b->neighbor[q]),
                        (long long)(first + b->neighbor[q]), (long long)(first + j));
    }
    free(next);
    return s;
}

static pd_status check_bonds(const char *fn, const pd_particles *p, const pd_bonds *b)
{
    if (!pd_bonds_has_lists(b))
        return check_compact(fn, p, b);
    if (b->offset[0] != 0)
        return pd_fail(PD_ERR_FORMAT, "'%s': /bonds/offset must start at 0", fn);
    for (int64_t i = 0; i < b->n; i++)
        if (b->offset[i + 1] < b->offset[i])
            return pd_fail(PD_ERR_FORMAT, "'%s': /bonds/offset decreases at row %lld", fn,
                           (long long)i);
    if (b->offset[b->n] != b->count)
        return pd_fail(PD_ERR_FORMAT, "'%s': /bonds/offset ends at %lld but there are %lld bonds",
                       fn, (long long)b->offset[b->n], (long long)b->count);
    return check_bond_rows(fn, b, 0, b->n, 0, 0);
}

/* Are the nk offsets' bonds of lengths len (their first bonds', NaN: none)
 * within `spread` of them bound to be as check_bonds wants them (length
 * positive, finite and within the horizon, volume factor in (0, 1]), the
 * smallest radius rmin? */
static int lengths_bound(int nk, const double *len, const double *spread, double horizon,
                         double rmin)
{
    int ok = rmin > 0 && isfinite(rmin);
    for (int k = 0; k < nk && ok; k++) /* nu in (0, 1] while len < horizon + r */
        ok = isnan(len[k]) || (len[k] - spread[k] > 0 &&
                               len[k] + spread[k] <= horizon * (1 + 1e-9) &&
                               len[k] + spread[k] < horizon + 0.5 * rmin);
    return ok;
}

/* Is every bond of compact families as check_bonds wants it?  Each
 * offset's bonds are bound to its first one's length within its spread
 * (pd_family_offsets): 1 when the bounds settle it for all, else 0.  A
 * window of the body (pd_read_bonds_window): over the ranks (collective). */
static int compact_lengths_bound(const pd_particles *p, const pd_bonds *b)
{
    const int nk = b->stencil ? b->stencil->nk : 0;
    int32_t(*d)[3] = malloc((size_t)(nk > 0 ? nk : 1) * sizeof *d);
    double *len = malloc((size_t)(nk > 0 ? nk : 1) * sizeof(double));
    double *nu = malloc((size_t)(nk > 0 ? nk : 1) * sizeof(double));
    double *spread = malloc((size_t)(nk > 0 ? nk : 1) * sizeof(double));
    int ok = d && len && nu && spread;
    if (p->window) /* every rank takes part */
        ok = pd_family_offsets_ranks(b, p, d, len, nu, spread) == nk;
    else
        ok = ok && pd_family_offsets(b, p, d, len, nu, spread) == nk;
    double rmin = INFINITY;
    for (int64_t i = p->window ? p->own_lo : 0; i < (p->window ? p->own_hi : p->n); i++)
        rmin = fmin(rmin, p->radius[i]);
    rmin = -pd_body_max(p, -rmin);
    ok = ok && lengths_bound(nk, len, spread, b->horizon, rmin);
    free(d);
    free(len);
    free(nu);
    free(spread);
    return ok;
}

/* The partner of directed bond k. */
static int32_t partner_of(const pd_particles *p, const pd_bonds *b, int64_t k)
{
    pd_bond_iter it;
    for (pd_family_start_partners(b, p, row_of(b, k), &it); pd_family_next(&it) && it.q < k;)
        ;
    return it.j;
}

/* The same checks of compact families (pd_bonds_compact): partners,
 * order and symmetry hold by the stencil's making; each bond's length and
 * factor, and the state (and pre-crack) bits of both sides. */
static pd_status check_compact(const char *fn, const pd_particles *p, const pd_bonds *b)
{
    int64_t bad = INT64_MAX; /* the first bad bond, as check_bonds finds it */
    if (!compact_lengths_bound(p, b)) {
#pragma omp parallel for schedule(static) reduction(min : bad)
        for (int64_t i = 0; i < b->n; i++) {
            pd_bond_iter it;
            for (pd_family_start(b, p, i, &it); pd_family_next(&it);)
                if (!(it.length > 0) || !isfinite(it.length) ||
                    it.length > b->horizon * (1 + 1e-9) || !(it.vfactor > 0 && it.vfactor <= 1)) {
                    bad = it.q < bad ? it.q : bad;
                    break;
                }
        }
    }
    if (bad < INT64_MAX) {
        pd_bond_iter it;
        for (pd_family_start(b, p, row_of(b, bad), &it); pd_family_next(&it) && it.q < bad;)
            ;
        const long long k = (long long)bad;
        if (!(it.length > 0) || !isfinite(it.length))
            return pd_fail(PD_ERR_FORMAT, "'%s': bond %lld has length %g", fn, k, it.length);
        if (it.length > b->horizon * (1 + 1e-9))
            return pd_fail(PD_ERR_FORMAT, "'%s': bond %lld is %g m long, beyond the horizon %g m",
                           fn, k, it.length, b->horizon);
        return pd_fail(PD_ERR_FORMAT, "'%s': bond %lld has volume factor %g", fn, k, it.vfactor);
    }
    /* both sides' bits, the first difference as check_bonds meets it (the
     * state's before the pre-crack's at one bond) */
    const int64_t ks = pd_family_asymmetric(b, b->intact),
                  kp = b->precrack ? pd_family_asymmetric(b, b->precrack) : -1;
    if (ks == -2 || kp == -2)
        return pd_fail(PD_ERR_NOMEM, "out of memory checking bonds");
    if (ks >= 0 && (kp < 0 || ks <= kp))
        return pd_fail(PD_ERR_FORMAT,
                       "'%s': bond %lld-%lld is broken on one side only (state bits differ)", fn,
                       (long long)partner_of(p, b, ks), (long long)row_of(b, ks));
    if (kp >= 0)
        return pd_fail(PD_ERR_FORMAT,
                       "'%s': bond %lld-%lld is pre-cracked on one side only (precrack bits "
                       "differ)",
                       fn, (long long)partner_of(p, b, kp), (long long)row_of(b, kp));
    return PD_OK;
}

/* The row whose family holds directed bond k (offsets checked). */
static int64_t row_of(const pd_bonds *b, int64_t k)
{
    int64_t lo = 0, hi = b->n; /* offset[lo] <= k < offset[hi] */
    while (hi - lo > 1) {
        int64_t mid = lo + (hi - lo) / 2;
        if (b->offset[mid] <= k)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

/* /bonds/precrack, when present: the bonds broken before the run, packed as
 * /bonds/state.  Every pre-cracked bond must be broken in /bonds/state (the
 * symmetry of the bits is checked with the families).  All clear is the
 * same as absent: b->precrack stays NULL. */
static pd_status read_precrack(const pd_file *f, pd_bonds *b)
{
    const char *fn = f->name;
    if (b->count == 0 || !pd_h5_has_link(f->fid, "/bonds/precrack"))
        return PD_OK;
    pd_h5_form bf = {H5T_INTEGER, 1, 1, {(hsize_t)((b->count + 7) / 8), 0}};
    uint8_t *bytes = NULL;
    pd_status s = pd_h5_read_data(f->fid, fn, "/bonds/precrack", &bf, H5T_NATIVE_UINT8, 1,
                                  (void **)&bytes, NULL);
    if (s != PD_OK)
        return s;
    int64_t words = pd_bits_words(b->count);
    b->precrack = calloc((size_t)words + 1, sizeof(uint64_t));
    if (b->precrack == NULL) {
        free(bytes);
        return pd_fail(PD_ERR_NOMEM, "out of memory for the pre-crack");
    }
    bytes_to_words(bytes, b->count, b->precrack);
    free(bytes);
    if (pd_bits_count_broken(b->precrack, b->count) == b->count) {
        free(b->precrack);
        b->precrack = NULL;
    }
    return PD_OK;
}

static pd_status check_precrack(const char *fn, const pd_particles *p, const pd_bonds *b)
{
    if (b->precrack == NULL)
        return PD_OK;
    for (int64_t w = 0; w < pd_bits_words(b->count); w++) {
        uint64_t both = b->precrack[w] & b->intact[w];
        if (both) {
            const int64_t k = w * 64 + __builtin_ctzll(both);
            return pd_fail(PD_ERR_FORMAT,
                           "'%s': bond %lld-%lld is pre-cracked (/bonds/precrack) but intact in "
                           "/bonds/state",
                           fn, (long long)(p->first + row_of(b, k)),
                           (long long)(p->first + partner_of(p, b, k)));
        }
    }
    return PD_OK;
}

/* /bonds as lists (CSR): offsets, partners, lengths, volume factors. */
static pd_status read_list_bonds(const pd_file *f, const pd_particles *p, pd_bonds **out)
{
    const char *fn = f->name;
    int64_t n = p->n;
    pd_h5_form of = {H5T_INTEGER, 8, 1, {(hsize_t)n + 1, 0}};
    int64_t *offset = NULL;
    pd_status s = pd_h5_read_data(f->fid, fn, "/bonds/offset", &of, H5T_NATIVE_INT64,
                                  sizeof(int64_t), (void **)&offset, NULL);
    if (s != PD_OK)
        return s;
    int64_t count = offset[n];
    if (count < 0) {
        free(offset);
        return pd_fail(PD_ERR_FORMAT, "'%s': /bonds/offset ends negative", fn);
    }
    /* neighbour (int32 in memory), length, volume factor, state bits */
    if ((double)count * 24 > pd_memory_bytes()) {
        free(offset);
        return pd_fail(PD_ERR_NOMEM, "'%s': /bonds/offset declares %lld bonds, more than memory",
                       fn, (long long)count);
    }
    pd_bonds *b = pd_bonds_alloc(n, count);
    if (b == NULL) {
        free(offset);
        return pd_fail(PD_ERR_NOMEM, "out of memory for %lld bonds", (long long)count);
    }
    memcpy(b->offset, offset, (size_t)(n + 1) * sizeof(int64_t));
    free(offset);
    const char *names[3] = {"/bonds/neighbor", "/bonds/length", "/bonds/volume_factor"};
    pd_h5_form forms[3] = {{H5T_INTEGER, 4, 1, {(hsize_t)count, 0}},
                           {H5T_FLOAT, 8, 1, {(hsize_t)count, 0}},
                           {H5T_FLOAT, 8, 1, {(hsize_t)count, 0}}};
    hid_t types[3] = {H5T_NATIVE_INT32, H5T_NATIVE_DOUBLE, H5T_NATIVE_DOUBLE};
    void *dst[3] = {b->neighbor, b->length, b->vfactor};
    size_t sizes[3] = {sizeof(int32_t), sizeof(double), sizeof(double)};
    for (int k = 0; k < 3 && s == PD_OK; k++) {
        if (count == 0) { /* "any" length: then it must be empty */
            void *tmp = NULL;
            hsize_t dims[1] = {0};
            forms[k].dims[0] = 0;
            s = pd_h5_read_data(f->fid, fn, names[k], &forms[k], types[k], sizes[k], &tmp, dims);
            free(tmp);
            if (s == PD_OK && dims[0] != 0)
                s = pd_fail(PD_ERR_FORMAT, "'%s': %s has %llu entries, offsets say 0", fn,
                            names[k], (unsigned long long)dims[0]);
        } else
            s = pd_h5_read_data(f->fid, fn, names[k], &forms[k], types[k], sizes[k], &dst[k],
                                NULL);
    }
    for (int64_t k = 0; k < count && s == PD_OK; k++)
        if (b->neighbor[k] < 0 || b->neighbor[k] >= n)
            s = pd_fail(PD_ERR_FORMAT, "'%s': bond %lld points to particle %lld of %lld", fn,
                        (long long)k, (long long)b->neighbor[k], (long long)n);
    if (s != PD_OK) {
        pd_bonds_free(b);
        return s;
    }
    *out = b;
    return PD_OK;
}

/* The table of /bonds as a stencil (pd_stencil, lib/bonds/stencil.c): its
 * offsets and its lattice, checked. */
static pd_status read_stencil_table(const pd_file *f, hid_t g, double horizon, pd_stencil **out)
{
    *out = NULL;
    const char *fn = f->name;
    const int R = PD_STENCIL_REACH, w = 2 * R + 1;
    pd_h5_form df = {H5T_INTEGER, 4, 2, {0, 3}};
    hsize_t dims[2] = {0, 0};
    int32_t *d = NULL;
    pd_status s = pd_h5_read_data(f->fid, fn, "/bonds/stencil", &df, H5T_NATIVE_INT32,
                                  sizeof(int32_t), (void **)&d, dims);
    if (s != PD_OK)
        return s;
    const hsize_t nk = dims[0];
    pd_stencil *st = nk >= 1 && nk < (hsize_t)w * w * w ? pd_stencil_alloc((int)nk) : NULL;
    uint8_t *seen = calloc((size_t)w * w * w, 1);
    if (nk < 1 || nk >= (hsize_t)w * w * w)
        s = pd_fail(PD_ERR_FORMAT, "'%s': /bonds/stencil has %llu offsets", fn,
                    (unsigned long long)nk);
    else if (st == NULL || seen == NULL)
        s = pd_fail(PD_ERR_NOMEM, "out of memory for the stencil");
    pd_h5_form lf = {H5T_FLOAT, 8, 1, {nk, 0}};
    if (s == PD_OK) {
        memcpy(st->d, d, (size_t)nk * sizeof *st->d);
        void *len = st->length, *nu = st->vfactor;
        s = pd_h5_read_data(f->fid, fn, "/bonds/stencil_length", &lf, H5T_NATIVE_DOUBLE,
                            sizeof(double), &len, NULL);
        if (s == PD_OK)
            s = pd_h5_read_data(f->fid, fn, "/bonds/stencil_volume_factor", &lf,
                                H5T_NATIVE_DOUBLE, sizeof(double), &nu, NULL);
    }
    free(d);
    if (s == PD_OK && (pd_h5_read_attr_doubles(g, "origin", st->origin, 3) != PD_OK ||
                       pd_h5_read_attr_double(g, "spacing", &st->spacing) != PD_OK))
        s = pd_fail(PD_ERR_FORMAT, "'%s': /bonds as a stencil needs the attributes origin (3) "
                                   "and spacing", fn);
    if (s == PD_OK && (!(st->spacing > 0) || !isfinite(st->spacing) || !isfinite(st->origin[0]) ||
                       !isfinite(st->origin[1]) || !isfinite(st->origin[2])))
        s = pd_fail(PD_ERR_FORMAT, "'%s': /bonds has spacing %g and origin (%g, %g, %g)", fn,
                    st->spacing, st->origin[0], st->origin[1], st->origin[2]);
    /* offsets: within reach, not zero, each once, with their opposites */
    for (int k = 0; k < (int)nk && s == PD_OK; k++) {
        const int32_t *dk = st->d[k];
        if (abs(dk[0]) > R || abs(dk[1]) > R || abs(dk[2]) > R || !(dk[0] || dk[1] || dk[2]))
            s = pd_fail(PD_ERR_FORMAT, "'%s': /bonds/stencil offset %d is (%d, %d, %d)", fn, k,
                        dk[0], dk[1], dk[2]);
        else if (seen[((dk[2] + R) * w + dk[1] + R) * w + dk[0] + R]++)
            s = pd_fail(PD_ERR_FORMAT, "'%s': /bonds/stencil has offset (%d, %d, %d) twice", fn,
                        dk[0], dk[1], dk[2]);
        else if (!(st->length[k] > 0) || !isfinite(st->length[k]) ||
                 !(st->vfactor[k] > 0 && st->vfactor[k] <= 1))
            s = pd_fail(PD_ERR_FORMAT, "'%s': /bonds/stencil offset %d has length %g and volume "
                                       "factor %g", fn, k, st->length[k], st->vfactor[k]);
    }
    /* within the horizon, and each length that of its offset (to the
     * sites' tolerance at both ends, as pd_bonds_build_lattice's reach) */
    for (int k = 0; k < (int)nk && s == PD_OK; k++) {
        const int32_t *dk = st->d[k];
        const double h = st->spacing,
                     len = h * sqrt((double)dk[0] * dk[0] + (double)dk[1] * dk[1] +
                                    (double)dk[2] * dk[2]);
        if (len > horizon + 1e-5 * h)
            s = pd_fail(PD_ERR_FORMAT, "'%s': /bonds/stencil offset (%d, %d, %d) is %g m long, "
                                       "beyond the horizon %g m", fn, dk[0], dk[1], dk[2], len,
                        horizon);
        else if (fabs(st->length[k] - len) > 1e-5 * h)
            s = pd_fail(PD_ERR_FORMAT, "'%s': /bonds/stencil_length of offset (%d, %d, %d) is %g m, "
                                       "not %g m", fn, dk[0], dk[1], dk[2], st->length[k], len);
    }
    for (int k = 0; k < (int)nk && s == PD_OK; k++) {
        const int32_t *dk = st->d[k];
        if (!seen[((R - dk[2]) * w + R - dk[1]) * w + R - dk[0]])
            s = pd_fail(PD_ERR_FORMAT, "'%s': /bonds/stencil has offset (%d, %d, %d) but not its "
                                       "opposite", fn, dk[0], dk[1], dk[2]);
    }
    free(seen);
    if (s == PD_OK)
        *out = st;
    else
        pd_stencil_free(st);
    return s;
}

/* /bonds as a stencil (the table checked, read_stencil_table), expanded to
 * lists or kept compact. */
static pd_status read_stencil_bonds(const pd_file *f, hid_t g, const pd_particles *p,
                                    double horizon, int lists, pd_bonds **out)
{
    pd_stencil *st = NULL;
    pd_status s = read_stencil_table(f, g, horizon, &st);
    if (s == PD_OK && (s = lists ? pd_bonds_expand(p, st, horizon, out)
                                 : pd_bonds_compact(p, st, horizon, out)) != PD_OK)
        s = pd_fail(s, "'%s': %s", f->name, pd_errmsg());
    pd_stencil_free(st);
    return s;
}

static pd_status read_bonds(const pd_file *f, const pd_particles *p, int lists, pd_bonds **out)
{
    const char *fn = f->name;
    if (!pd_file_has_bonds(f))
        return pd_fail(PD_ERR_FORMAT, "'%s' has no /bonds (run pd-bonds first)", fn);
    hid_t g = H5Gopen2(f->fid, "/bonds", H5P_DEFAULT);
    double horizon = 0;
    char *form = NULL;
    int64_t declared = -1;
    pd_status s = PD_OK;
    if (pd_h5_read_attr_double(g, "horizon", &horizon) != PD_OK)
        s = pd_fail(PD_ERR_FORMAT, "'%s': /bonds has no horizon attribute", fn);
    else if (!(horizon > 0) || !isfinite(horizon))
        s = pd_fail(PD_ERR_FORMAT, "'%s': /bonds horizon must be positive", fn);
    else if (pd_h5_has_attr(g, "form") && pd_h5_read_attr_string(g, "form", &form) != PD_OK)
        s = pd_fail(PD_ERR_FORMAT, "'%s': /bonds attribute form is not a string", fn);
    else if (form && strcmp(form, "stencil") != 0 && strcmp(form, "csr") != 0)
        s = pd_fail(PD_ERR_FORMAT, "'%s': /bonds form '%s' is neither 'csr' nor 'stencil'", fn,
                    form);
    pd_bonds *b = NULL;
    const int stencil = form && strcmp(form, "stencil") == 0;
    if (s == PD_OK && stencil && f->version < 2)
        s = pd_fail(PD_ERR_FORMAT, "'%s': /bonds as a stencil needs pd-h5 format version 2, "
                    "the file says %d", fn, f->version);
    if (s == PD_OK && stencil && pd_h5_read_attr_int(g, "count", &declared) != PD_OK)
        s = pd_fail(PD_ERR_FORMAT, "'%s': /bonds as a stencil has no count attribute", fn);
    if (s == PD_OK)
        s = stencil ? read_stencil_bonds(f, g, p, horizon, lists, &b) : read_list_bonds(f, p, &b);
    H5Gclose(g);
    free(form);
    if (s == PD_OK && stencil && b->count != declared)
        s = pd_fail(PD_ERR_FORMAT, "'%s': the stencil gives %lld bonds, /bonds@count says %lld",
                    fn, (long long)b->count, (long long)declared);
    const int64_t count = b ? b->count : 0;
    pd_h5_form bf = {H5T_INTEGER, 1, 1, {(hsize_t)((count + 7) / 8), 0}};
    uint8_t *state = NULL;
    if (s == PD_OK && count > 0)
        s = pd_h5_read_data(f->fid, fn, "/bonds/state", &bf, H5T_NATIVE_UINT8, 1,
                            (void **)&state, NULL);
    if (s == PD_OK && count > 0)
        bytes_to_words(state, count, b->intact);
    free(state);
    if (s == PD_OK) {
        b->horizon = horizon;
        s = read_precrack(f, b);
    }
    if (s == PD_OK)
        s = check_bonds(fn, p, b);
    if (s == PD_OK)
        s = check_precrack(fn, p, b);
    if (s != PD_OK) {
        pd_bonds_free(b);
        return s;
    }
    *out = b;
    return PD_OK;
}

pd_status pd_read_bonds(const pd_file *f, const pd_particles *p, pd_bonds **out)
{
    return read_bonds(f, p, 1, out);
}

pd_status pd_read_bonds_compact(const pd_file *f, const pd_particles *p, pd_bonds **out)
{
    return read_bonds(f, p, 0, out);
}

/* ------------------------------------------- a piece's rows of /bonds */

int pd_file_bonds_listed(const pd_file *f)
{
    if (!pd_file_has_bonds(f))
        return 0;
    hid_t g = H5Gopen2(f->fid, "/bonds", H5P_DEFAULT);
    char *form = NULL;
    int lists = 1; /* no form: lists, as files before the stencil */
    if (pd_h5_has_attr(g, "form"))
        lists = pd_h5_read_attr_string(g, "form", &form) == PD_OK && strcmp(form, "csr") == 0;
    free(form);
    H5Gclose(g);
    return lists;
}

/* Rows [r0, r1] of /bonds/offset (n + 1 rows) into off (r1 - r0 + 1
 * entries), checked to rise (and to start at 0). */
static pd_status read_offset_rows(const pd_file *f, int64_t n, int64_t r0, int64_t r1,
                                  int64_t *off)
{
    const pd_h5_form of = {H5T_INTEGER, 8, 1, {(hsize_t)n + 1, 0}};
    pd_status s = pd_h5_read_rows(f->fid, f->name, "/bonds/offset", &of, H5T_NATIVE_INT64, off,
                                  r0, r1 - r0 + 1);
    if (s == PD_OK && r0 == 0 && off[0] != 0)
        s = pd_fail(PD_ERR_FORMAT, "'%s': /bonds/offset must start at 0", f->name);
    for (int64_t i = r0; i < r1 && s == PD_OK; i++)
        if (off[i + 1 - r0] < off[i - r0])
            s = pd_fail(PD_ERR_FORMAT, "'%s': /bonds/offset decreases at row %lld", f->name,
                        (long long)i);
    return s;
}

#define SPAN_CHUNK (1 << 20) /* bonds read at a time */

pd_status pd_read_bonds_span(const pd_file *f, int64_t n, int64_t r0, int64_t r1, int64_t *span)
{
    *span = 1;
    int64_t *off = malloc((size_t)(r1 - r0 + 1) * sizeof(int64_t));
    int32_t *nb = NULL;
    int64_t cap = 0;
    pd_status s = off ? read_offset_rows(f, n, r0, r1, off)
                      : pd_fail(PD_ERR_NOMEM, "out of memory for the bonds' offsets");
    const pd_h5_form nf = {H5T_INTEGER, 4, 1, {0, 0}};
    for (int64_t i = r0; i < r1 && s == PD_OK;) { /* whole rows, about SPAN_CHUNK bonds */
        int64_t e = i + 1;
        while (e < r1 && off[e + 1 - r0] - off[i - r0] <= SPAN_CHUNK)
            e++;
        const int64_t k0 = off[i - r0], m = off[e - r0] - k0;
        if (m > cap) {
            free(nb);
            cap = m > SPAN_CHUNK ? m : SPAN_CHUNK;
            if ((nb = malloc((size_t)cap * sizeof(int32_t))) == NULL) {
                s = pd_fail(PD_ERR_NOMEM, "out of memory for the bonds' partners");
                break;
            }
        }
        s = pd_h5_read_rows(f->fid, f->name, "/bonds/neighbor", &nf, H5T_NATIVE_INT32, nb, k0, m);
        for (int64_t r = i; r < e && s == PD_OK; r++)
            for (int64_t k = off[r - r0]; k < off[r + 1 - r0] && s == PD_OK; k++) {
                const int64_t j = nb[k - k0];
                if (j < 0 || j >= n)
                    s = pd_fail(PD_ERR_FORMAT, "'%s': bond %lld points to particle %lld of %lld",
                                f->name, (long long)k, (long long)j, (long long)n);
                *span = j - r > *span ? j - r : *span;
            }
        i = e;
    }
    free(off);
    free(nb);
    return s;
}

/* Bits [k0, k1) of a dataset of bits packed as /bonds/state (of `total`
 * bits, 0: not checked) into bits [at, at + k1 - k0) of words: with at 0,
 * words cleared first; else the other bits left as they are. */
static pd_status read_bit_rows(const pd_file *f, const char *name, int64_t k0, int64_t k1,
                               int64_t total, uint64_t *words, int64_t at)
{
    if (at == 0)
        memset(words, 0, (size_t)(pd_bits_words(k1 - k0) + 1) * sizeof(uint64_t));
    if (k1 <= k0)
        return PD_OK;
    const int64_t b0 = k0 / 8, nbytes = (k1 + 7) / 8 - b0;
    uint8_t *bytes = malloc((size_t)nbytes);
    const pd_h5_form bf = {H5T_INTEGER, 1, 1, {(hsize_t)((total + 7) / 8), 0}};
    pd_status s = bytes ? pd_h5_read_rows(f->fid, f->name, name, &bf, H5T_NATIVE_UINT8, bytes, b0,
                                          nbytes)
                        : pd_fail(PD_ERR_NOMEM, "out of memory for the bonds' states");
    for (int64_t k = k0; k < k1 && s == PD_OK; k++) {
        const int64_t q = at + k - k0;
        const uint64_t bit = UINT64_C(1) << (q & 63);
        words[q >> 6] = (bytes[k / 8 - b0] >> (k % 8)) & 1 ? words[q >> 6] | bit
                                                          : words[q >> 6] & ~bit;
    }
    free(bytes);
    return s;
}

/* check_bonds of rows [g0, g1) of b alone: each bond as check_bonds wants
 * it, and the symmetry of the bonds between two of the rows (a bond to a
 * row beyond them is checked by a piece that holds both). */

pd_status pd_read_bonds_rows(const pd_file *f, const pd_particles *p, int64_t g0, int64_t g1,
                             pd_bonds **out, int64_t *first_bond)
{
    *out = NULL;
    *first_bond = 0;
    const char *fn = f->name;
    const int64_t n = pd_body_count(p), e0 = p->first, e1 = p->first + p->n;
    double horizon = 0;
    hid_t g = H5Gopen2(f->fid, "/bonds", H5P_DEFAULT);
    pd_status s = PD_OK;
    if (g0 < e0 || g1 > e1 || g0 > g1)
        s = pd_fail(PD_ERR_INVALID, "rows %lld to %lld are not in the particles read",
                    (long long)g0, (long long)g1);
    else if (g < 0 || pd_h5_read_attr_double(g, "horizon", &horizon) != PD_OK)
        s = pd_fail(PD_ERR_FORMAT, "'%s': /bonds has no horizon attribute", fn);
    else if (!(horizon > 0) || !isfinite(horizon))
        s = pd_fail(PD_ERR_FORMAT, "'%s': /bonds horizon must be positive", fn);
    if (g >= 0)
        H5Gclose(g);
    /* the rows' offsets alone, then their bonds */
    int64_t *off = malloc((size_t)(g1 - g0 + 1) * sizeof(int64_t));
    if (s == PD_OK && off == NULL)
        s = pd_fail(PD_ERR_NOMEM, "out of memory for the bonds' offsets");
    int64_t total = 0; /* the body's bonds: every dataset's length, as read_bonds wants it */
    if (s == PD_OK)
        s = read_offset_rows(f, n, g0, g1, off);
    if (s == PD_OK)
        s = read_offset_rows(f, n, n, n, &total);
    const int64_t k0 = s == PD_OK ? off[0] : 0, k1 = s == PD_OK ? off[g1 - g0] : 0;
    pd_bonds *b = s == PD_OK ? pd_bonds_alloc(p->n, k1 - k0) : NULL;
    if (s == PD_OK && b == NULL)
        s = pd_fail(PD_ERR_NOMEM, "out of memory for %lld bonds", (long long)(k1 - k0));
    for (int64_t i = 0; b && i <= p->n; i++) { /* rows of p: those of [g0, g1) have bonds */
        const int64_t r = e0 + i;
        b->offset[i] = (r <= g0 ? k0 : r >= g1 ? k1 : off[r - g0]) - k0;
    }
    free(off);
    const char *names[3] = {"/bonds/neighbor", "/bonds/length", "/bonds/volume_factor"};
    const hsize_t len = total > 0 ? (hsize_t)total : 0; /* none: any (then empty) */
    const pd_h5_form forms[3] = {{H5T_INTEGER, 4, 1, {len, 0}},
                                 {H5T_FLOAT, 8, 1, {len, 0}},
                                 {H5T_FLOAT, 8, 1, {len, 0}}};
    const hid_t types[3] = {H5T_NATIVE_INT32, H5T_NATIVE_DOUBLE, H5T_NATIVE_DOUBLE};
    for (int a = 0; a < 3 && s == PD_OK; a++)
        s = pd_h5_read_rows(f->fid, fn, names[a], &forms[a], types[a],
                            a == 0 ? (void *)b->neighbor : a == 1 ? (void *)b->length
                                                                  : (void *)b->vfactor,
                            k0, k1 - k0);
    /* partners as rows of p: a bond's span is at most the body's largest,
     * which p's rows reach beyond [g0, g1) (pd_read_body_ranks); one
     * farther has no mirror */
    for (int64_t i = g0; i < g1 && s == PD_OK; i++)
        for (int64_t k = b->offset[i - e0]; k < b->offset[i - e0 + 1] && s == PD_OK; k++) {
            const int64_t j = b->neighbor[k];
            if (j < 0 || j >= n)
                s = pd_fail(PD_ERR_FORMAT, "'%s': bond %lld points to particle %lld of %lld", fn,
                            (long long)(k0 + k), (long long)j, (long long)n);
            else if (j < e0 || j >= e1)
                s = pd_fail(PD_ERR_FORMAT,
                            "'%s': bonds are not symmetric (%lld-%lld has no %lld-%lld)", fn,
                            (long long)i, (long long)j, (long long)j, (long long)i);
            else
                b->neighbor[k] = (int32_t)(j - e0);
        }
    if (s == PD_OK)
        s = read_bit_rows(f, "/bonds/state", k0, k1, total, b->intact, 0);
    if (s == PD_OK && k1 > k0 && pd_h5_has_link(f->fid, "/bonds/precrack")) {
        if ((b->precrack = malloc((size_t)(pd_bits_words(k1 - k0) + 1) * sizeof(uint64_t))) ==
            NULL)
            s = pd_fail(PD_ERR_NOMEM, "out of memory for the pre-crack");
        else /* kept when none of these rows' is: the file's /bonds/precrack
                is written again by every rank's rows */
            s = read_bit_rows(f, "/bonds/precrack", k0, k1, total, b->precrack, 0);
    }
    if (b)
        b->horizon = horizon;
    if (s == PD_OK)
        s = check_bond_rows(fn, b, g0 - e0, g1 - e0, k0, e0);
    if (s == PD_OK)
        s = check_precrack(fn, p, b);
    if (s != PD_OK) {
        pd_bonds_free(b);
        return s;
    }
    *out = b;
    *first_bond = k0;
    return PD_OK;
}

/* /bonds's horizon, declared count and table when they are a stencil, as
 * read_bonds checks them (NULL *st: they are not, or not as it wants). */
static void stencil_header(const pd_file *f, double *horizon, int64_t *declared,
                           pd_stencil **st)
{
    *st = NULL;
    hid_t g = pd_file_has_bonds(f) ? H5Gopen2(f->fid, "/bonds", H5P_DEFAULT) : -1;
    char *form = NULL;
    const int ok = g >= 0 && f->version >= 2 &&
                   pd_h5_read_attr_double(g, "horizon", horizon) == PD_OK && *horizon > 0 &&
                   isfinite(*horizon) && pd_h5_has_attr(g, "form") &&
                   pd_h5_read_attr_string(g, "form", &form) == PD_OK &&
                   strcmp(form, "stencil") == 0 &&
                   pd_h5_read_attr_int(g, "count", declared) == PD_OK;
    if (ok && read_stencil_table(f, g, *horizon, st) != PD_OK)
        *st = NULL;
    free(form);
    if (g >= 0)
        H5Gclose(g);
}

pd_stencil *pd_read_stencil(const pd_file *f)
{
    double horizon = 0;
    int64_t declared = 0;
    pd_stencil *st = NULL;
    stencil_header(f, &horizon, &declared, &st);
    return st;
}

/* Are the window's own rows' bonds as check_bonds and check_precrack want
 * them (their lengths over the ranks, both sides' bits), its pre-crack
 * none on any rank?  (collective) */
static int window_checked(const pd_particles *p, const pd_bonds *b, int *cracked)
{
    const int64_t lo = p->own_lo, hi = p->own_hi, k0 = b->offset[lo], k1 = b->offset[hi];
    int ok = compact_lengths_bound(p, b);
    ok = ok && pd_family_asymmetric_rows(b, b->intact, lo, hi) == -1 &&
         (!b->precrack || pd_family_asymmetric_rows(b, b->precrack, lo, hi) == -1);
    *cracked = 0;
    for (int64_t k = k0; b->precrack && k < k1; k++) { /* pre-cracked and intact */
        *cracked |= pd_bond_intact(b->precrack, k);
        ok = ok && !(pd_bond_intact(b->precrack, k) && pd_bond_intact(b->intact, k));
    }
    *cracked = pd_comm_or(*cracked);
    return pd_comm_min(ok) == 1;
}

pd_status pd_read_bonds_window(const pd_file *f, const pd_particles *p, int64_t r0, int64_t r1,
                               pd_bonds **out, int64_t *first_bond)
{
    *out = NULL;
    *first_bond = 0;
    double horizon = 0;
    int64_t declared = -1;
    pd_stencil *st = NULL;
    pd_bonds *b = NULL;
    stencil_header(f, &horizon, &declared, &st);
    int ok = st && pd_bonds_compact(p, st, horizon, &b) == PD_OK && !pd_bonds_has_lists(b);
    pd_stencil_free(st);
    ok = pd_comm_min(ok) == 1; /* every rank, or none, goes on */
    /* the body's count, from the own rows' whole families; row r0's first
     * bond's index in the body */
    const int64_t *off = ok ? b->offset : NULL;
    const int64_t own = ok ? off[p->own_hi] - off[p->own_lo] : 0, total = pd_comm_total(own);
    const int64_t k0 = ok ? pd_comm_below(own) - (off[p->own_lo] - off[r0]) : 0,
                  k1 = ok ? k0 + off[r1] - off[r0] : 0;
    ok = ok && total == declared && total > 0;
    /* the bits of rows [r0, r1) */
    if (ok)
        ok = read_bit_rows(f, "/bonds/state", k0, k1, total, b->intact, off[r0]) == PD_OK;
    if (ok && pd_h5_has_link(f->fid, "/bonds/precrack"))
        ok = (b->precrack = calloc((size_t)pd_bits_words(b->count) + 1, sizeof(uint64_t))) &&
             read_bit_rows(f, "/bonds/precrack", k0, k1, total, b->precrack, off[r0]) == PD_OK;
    int cracked = 0;
    ok = pd_comm_min(ok) == 1 && window_checked(p, b, &cracked);
    if (ok && !cracked) { /* all clear is the same as absent (read_precrack) */
        free(b->precrack);
        b->precrack = NULL;
    }
    if (!ok) {
        pd_bonds_free(b);
        return PD_OK;
    }
    *out = b;
    *first_bond = k0;
    return PD_OK;
}

/* The families as lists (CSR) or, when b->stencil says they are one, as the
 * stencil's table and its lattice (no per-bond arrays). */
static pd_status write_families(hid_t g, const pd_bonds *b)
{
    hsize_t dn[1] = {(hsize_t)b->n + 1}, db[1] = {(hsize_t)b->count};
    const pd_stencil *st = b->stencil;
    pd_status s;
    if (st == NULL) {
        if ((s = pd_h5_write_data(g, "offset", H5T_STD_I64LE, H5T_NATIVE_INT64, 1, dn,
                                  b->offset)) == PD_OK &&
            (s = pd_h5_write_data(g, "neighbor", H5T_STD_I32LE, H5T_NATIVE_INT32, 1, db,
                                  b->neighbor)) == PD_OK &&
            (s = pd_h5_write_data(g, "length", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 1, db,
                                  b->length)) == PD_OK)
            s = pd_h5_write_data(g, "volume_factor", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 1, db,
                                 b->vfactor);
        return s;
    }
    hsize_t dd[2] = {(hsize_t)st->nk, 3}, dk[1] = {(hsize_t)st->nk};
    if ((s = pd_h5_write_attr_string(g, "form", "stencil")) == PD_OK &&
        (s = pd_h5_write_data(g, "stencil", H5T_STD_I32LE, H5T_NATIVE_INT32, 2, dd, st->d)) ==
            PD_OK &&
        (s = pd_h5_write_data(g, "stencil_length", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 1, dk,
                              st->length)) == PD_OK &&
        (s = pd_h5_write_data(g, "stencil_volume_factor", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 1,
                              dk, st->vfactor)) == PD_OK &&
        (s = pd_h5_write_attr_doubles(g, "origin", st->origin, 3)) == PD_OK)
        s = pd_h5_write_attr_doubles(g, "spacing", &st->spacing, 1);
    return s;
}

pd_status pd_write_bonds(pd_file *f, const pd_bonds *b)
{
    hid_t g = pd_h5_create_group(f->fid, "/bonds");
    if (g < 0)
        return pd_fail(PD_ERR_IO, "cannot create /bonds");
    uint8_t *bytes = words_to_bytes(b->intact, b->count);
    if (bytes == NULL) {
        H5Gclose(g);
        return pd_fail(PD_ERR_NOMEM, "out of memory");
    }
    hsize_t ds[1] = {(hsize_t)((b->count + 7) / 8)};
    pd_status s;
    if ((s = write_families(g, b)) == PD_OK &&
        (s = pd_h5_write_data(g, "state", H5T_STD_U8LE, H5T_NATIVE_UINT8, 1, ds, bytes)) ==
            PD_OK &&
        (s = pd_h5_write_attr_doubles(g, "horizon", &b->horizon, 1)) == PD_OK)
        s = pd_h5_write_attr_int(g, "count", b->count);
    free(bytes);
    /* the pre-crack only when some bond is pre-cracked */
    if (s == PD_OK && b->precrack && pd_bits_count_broken(b->precrack, b->count) < b->count) {
        bytes = words_to_bytes(b->precrack, b->count);
        s = bytes ? pd_h5_write_data(g, "precrack", H5T_STD_U8LE, H5T_NATIVE_UINT8, 1, ds, bytes)
                  : pd_fail(PD_ERR_NOMEM, "out of memory");
        free(bytes);
    }
    H5Gclose(g);
    return s;
}

pd_status pd_write_bonds_part(pd_file *f, const pd_part *pt, const pd_bonds *b)
{
    hid_t g = pd_h5_create_group(f->fid, "/bonds");
    if (g < 0)
        return pd_fail(PD_ERR_IO, "cannot create /bonds");
    const int last = pt->first + pt->rows == pt->n; /* writes offset[n] too */
    const int lists = b->stencil == NULL; /* else the stencil, as write_families */
    const int64_t k0 = pt->klo, shift = pt->bond0 - pt->klo;
    hsize_t dn[1] = {(hsize_t)pt->n + 1}, db[1] = {(hsize_t)pt->nbonds},
            ds[1] = {(hsize_t)((pt->nbonds + 7) / 8)};
    int64_t *off = malloc((size_t)(pt->rows + 1) * sizeof(int64_t));
    /* b's rows are the body's shifted as the part's (a window's) */
    const int64_t row0 = pt->first - pt->lo;
    int32_t *nb = lists && row0 != 0
                      ? malloc((size_t)(pt->bonds > 0 ? pt->bonds : 1) * sizeof(int32_t))
                      : NULL;
    for (int64_t k = 0; nb && k < pt->bonds; k++)
        nb[k] = (int32_t)(b->neighbor[k0 + k] + row0);
    int64_t at = 0, count = 0, pat = 0, pcount = 0;
    uint8_t *bytes = pt->nbonds > 0 ? state_bytes(f, pt, b->intact, &at, &count) : NULL;
    /* the pre-crack only when some bond is pre-cracked */
    int cracked = 0;
    for (int64_t k = k0; b->precrack && k < k0 + pt->bonds && !cracked; k++)
        cracked = pd_bond_intact(b->precrack, k); /* a set bit: pre-cracked */
    if (f->ranks > 1)
        cracked = pd_comm_or(cracked);
    uint8_t *pbytes = cracked ? state_bytes(f, pt, b->precrack, &pat, &pcount) : NULL;
    pd_status s = off && (bytes || pt->nbonds == 0) && (pbytes || !cracked) &&
                          (nb || !row0 || !lists)
                      ? PD_OK
                      : pd_fail(PD_ERR_NOMEM, "out of memory");
    if (f->ranks > 1)
        s = pd_comm_agree(s);
    for (int64_t i = 0; off && i <= pt->rows; i++)
        off[i] = b->offset[pt->lo + i] + shift;
    if (s == PD_OK && !lists) /* the table, as pd_write_bonds writes it */
        s = write_families(g, b);
    if (s == PD_OK && lists &&
        (s = pd_h5_reserve_data(g, "offset", H5T_STD_I64LE, 1, dn)) == PD_OK &&
        (s = pd_h5_reserve_data(g, "neighbor", H5T_STD_I32LE, 1, db)) == PD_OK &&
        (s = pd_h5_reserve_data(g, "length", H5T_IEEE_F64LE, 1, db)) == PD_OK &&
        (s = pd_h5_reserve_data(g, "volume_factor", H5T_IEEE_F64LE, 1, db)) == PD_OK &&
        (s = pd_h5_write_rows(g, "offset", H5T_NATIVE_INT64, off, pt->first,
                              pt->rows + last)) == PD_OK &&
        (s = pd_h5_write_rows(g, "neighbor", H5T_NATIVE_INT32, nb ? nb : b->neighbor + k0,
                              pt->bond0, pt->bonds)) == PD_OK &&
        (s = pd_h5_write_rows(g, "length", H5T_NATIVE_DOUBLE, b->length + k0, pt->bond0,
                              pt->bonds)) == PD_OK)
        s = pd_h5_write_rows(g, "volume_factor", H5T_NATIVE_DOUBLE, b->vfactor + k0, pt->bond0,
                             pt->bonds);
    if (s == PD_OK && (s = pd_h5_reserve_data(g, "state", H5T_STD_U8LE, 1, ds)) == PD_OK &&
        (!cracked || (s = pd_h5_reserve_data(g, "precrack", H5T_STD_U8LE, 1, ds)) == PD_OK) &&
        (s = pd_h5_write_rows(g, "state", H5T_NATIVE_UINT8, bytes, at, count)) == PD_OK &&
        (!cracked ||
         (s = pd_h5_write_rows(g, "precrack", H5T_NATIVE_UINT8, pbytes, pat, pcount)) == PD_OK) &&
        (s = pd_h5_write_attr_doubles(g, "horizon", &b->horizon, 1)) == PD_OK)
        s = pd_h5_write_attr_int(g, "count", pt->nbonds);
    free(off);
    free(nb);
    free(bytes);
    free(pbytes);
    H5Gclose(g);
    return s;
}

/* ------------------------------------------------------------ scene */

pd_status pd_write_scene(pd_file *f, const pd_scene *sc, const char *effects,
                         const char *options_text)
{
    if (pd_h5_has_link(f->fid, "/scene"))
        H5Ldelete(f->fid, "/scene", H5P_DEFAULT);
    hid_t g = pd_h5_create_group(f->fid, "/scene");
    if (g < 0)
        return pd_fail(PD_ERR_IO, "cannot create /scene");
    pd_status s = PD_OK;
#define TRY(call)                                                                                  \
    do {                                                                                           \
        if (s == PD_OK)                                                                            \
            s = (call);                                                                            \
    } while (0)
    const pd_model *model = pd_model_of(sc->model);
    if (model == NULL)
        s = pd_fail(PD_ERR_INVALID, "unknown model %d", (int)sc->model);
    TRY(pd_h5_write_attr_string(g, "model", model->name));
    TRY(pd_h5_write_attr_string(g, "effects", effects));
    TRY(pd_h5_write_attr_string(g, "options", options_text));
    TRY(pd_h5_write_attr_doubles(g, "c", &sc->c, 1));
    if (sc->bulk_modulus > 0)
        TRY(pd_h5_write_attr_doubles(g, "bulk_modulus", &sc->bulk_modulus, 1));
    if (sc->youngs_modulus > 0)
        TRY(pd_h5_write_attr_doubles(g, "youngs_modulus", &sc->youngs_modulus, 1));
    if (sc->has_failure) {
        TRY(pd_h5_write_attr_doubles(g, "s00", &sc->s00, 1));
        TRY(pd_h5_write_attr_doubles(g, "alpha", &sc->alpha, 1));
    }
    if (sc->nno_failure > 0) { /* the sets' names, space-separated */
        char names[PD_NO_FAILURE_MAX * PD_SET_NAME_MAX] = "";
        for (int k = 0; k < sc->nno_failure; k++)
            snprintf(names + strlen(names), sizeof names - strlen(names), "%s%s", k ? " " : "",
                     sc->no_failure[k]);
        TRY(pd_h5_write_attr_string(g, "no_failure", names));
    }
    if (sc->has_contact)
        TRY(pd_h5_write_attr_doubles(g, "contact_skin", &sc->contact_skin, 1));
    if (sc->has_indenter) {
        double ind[8] = {sc->ind_center[0], sc->ind_center[1],   sc->ind_center[2],
                         sc->ind_radius,    sc->ind_k,           sc->ind_velocity[0],
                         sc->ind_velocity[1], sc->ind_velocity[2]};
        TRY(pd_h5_write_attr_doubles(g, "indenter", ind, 8));
    }
    if (sc->has_projectile) {
        double pr[9] = {sc->proj_center[0],   sc->proj_center[1],   sc->proj_center[2],
                         sc->proj_radius,      sc->proj_mass,        sc->proj_velocity[0],
                         sc->proj_velocity[1], sc->proj_velocity[2], sc->proj_k};
        TRY(pd_h5_write_attr_doubles(g, "projectile", pr, 9));
    }
    TRY(pd_h5_write_attr_doubles(g, "dt", &sc->dt, 1));
    TRY(pd_h5_write_attr_doubles(g, "dt_stable", &sc->dt_stable, 1));
    TRY(pd_h5_write_attr_doubles(g, "safety", &sc->safety, 1));
    TRY(pd_h5_write_attr_int(g, "steps", sc->steps));
    TRY(pd_h5_write_attr_int(g, "every", sc->every));
    TRY(pd_h5_write_attr_int(g, "threads", sc->threads));
    if (model && model->state_based) {
        TRY(pd_h5_write_attr_doubles(g, "shear_modulus", &sc->shear_modulus, 1));
        TRY(pd_h5_write_attr_string(g, "influence", pd_influence_name(sc->influence)));
    }
    if (sc->relax) { /* quasi-static: tolerance, iterations, their step */
        const double rx[3] = {sc->relax_tolerance, (double)sc->relax_iterations, sc->relax_dt};
        TRY(pd_h5_write_attr_doubles(g, "relax", rx, 3));
    }
    if (sc->nellipsoids > 0) { /* UX,UY,UZ,A,B,ROLL per ellipsoid */
        double el[6 * PD_ELLIPSOID_MAX];
        for (int k = 0; k < sc->nellipsoids; k++) {
            const pd_ellipsoid *e = &sc->ellipsoid[k];
            const double row[6] = {e->u[0], e->u[1], e->u[2], e->a, e->b, e->roll};
            for (int q = 0; q < 6; q++)
                el[6 * k + q] = row[q];
        }
        TRY(pd_h5_write_attr_doubles(g, "ellipsoids", el, 6 * sc->nellipsoids));
    }
    if (sc->has_fibre) { /* PMB only (pd_scene_check) */
        double fb[7] = {sc->fibre_g[0], sc->fibre_g[1], sc->fibre_g[2],  sc->fibre_c[0],
                        sc->fibre_c[1], sc->fibre_s00[0], sc->fibre_s00[1]};
        TRY(pd_h5_write_attr_doubles(g, "fibre", fb, 7));
    }
    if (sc->nlaws > 0) { /* PMB only */
        /* rows (a, b, c, s00) of the bond laws, a == b for a material */
        double *rows = malloc((size_t)sc->nlaws * 4 * sizeof(double));
        if (rows == NULL && s == PD_OK)
            s = pd_fail(PD_ERR_NOMEM, "out of memory");
        for (int k = 0; rows && k < sc->nlaws; k++) {
            rows[4 * k] = sc->laws[k].a;
            rows[4 * k + 1] = sc->laws[k].b;
            rows[4 * k + 2] = sc->laws[k].c;
            rows[4 * k + 3] = sc->laws[k].s00 > 0 ? sc->laws[k].s00 : sc->s00;
        }
        if (rows)
            TRY(pd_h5_write_attr_doubles(g, "bond_laws", rows, 4 * sc->nlaws));
        free(rows);
    }
    for (const pd_model_param *q = model ? model->params : NULL; q && q->option; q++)
        TRY(pd_h5_write_attr_doubles(g, q->attr,
                                     (const double *)((const char *)sc + q->offset), 1));
#undef TRY
    H5Gclose(g);
    return s;
}

/* ------------------------------------------------------------ frames */

static pd_status frame_path(const char *name, const char *field, char *buf, size_t len)
{
    if (snprintf(buf, len, "/frames/%s%s%s", name, field ? "/" : "", field ? field : "") >=
        (int)len)
        return pd_fail(PD_ERR_INVALID, "frame name too long");
    return PD_OK;
}

/* Crash safety.  A run lays out all its frames at the start
 * (pd_plan_frames): groups, datasets with their storage allocated, and
 * attributes, each frame marked complete = 0.  Writing a frame then changes
 * no structure of the file: it writes the datasets and attributes in place,
 * flushes, and only then sets complete = 1 and flushes again.  A run killed
 * at any moment (SIGKILL included) leaves a file whose structure was
 * complete before the first step, and whose complete frames are whole;
 * readers list only complete frames. */

/* The energies of a frame as attributes, in pd_energy's order. */
#define NENERGY 6
static const char *energy_attrs[NENERGY] = {"kinetic_energy",  "elastic_energy", "contact_energy",
                                            "released_energy", "lost_energy",    "external_work"};

static double *energy_field(pd_energy *e, int k)
{
    double *v[NENERGY] = {&e->kinetic, &e->elastic, &e->contact, &e->released, &e->lost, &e->work};
    return v[k];
}

static void frame_name(int64_t step, char *buf, size_t len)
{
    snprintf(buf, len, "/frames/%08lld", (long long)step);
}

/* One frame's group, datasets (storage allocated) and attributes, not yet
 * complete. */
static pd_status lay_out_frame(pd_file *f, int64_t n, int64_t nbonds, int64_t step, double time,
                               unsigned fields)
{
    if (!pd_h5_has_link(f->fid, "/frames")) {
        hid_t root = pd_h5_create_group(f->fid, "/frames");
        if (root < 0)
            return pd_fail(PD_ERR_IO, "cannot create /frames");
        H5Gclose(root);
    }
    char path[64];
    frame_name(step, path, sizeof path);
    hid_t g = pd_h5_create_group(f->fid, path);
    if (g < 0)
        return pd_fail(PD_ERR_IO, "cannot create frame %s (disk full?)", path);
    hsize_t d2[2] = {(hsize_t)n, 3}, d1[1] = {(hsize_t)n}, ds[1] = {(hsize_t)((nbonds + 7) / 8)};
    double zero = 0;
    pd_status s;
    if ((s = pd_h5_reserve_data(g, "displacement", H5T_IEEE_F64LE, 2, d2)) == PD_OK &&
        (s = pd_h5_reserve_data(g, "velocity", H5T_IEEE_F64LE, 2, d2)) == PD_OK &&
        (s = pd_h5_reserve_data(g, "state", H5T_STD_U8LE, 1, ds)) == PD_OK &&
        (s = pd_h5_reserve_data(g, "damage", H5T_IEEE_F64LE, 1, d1)) == PD_OK &&
        (s = pd_h5_write_attr_int(g, "step", step)) == PD_OK &&
        (s = pd_h5_write_attr_doubles(g, "time", &time, 1)) == PD_OK &&
        (s = pd_h5_write_attr_int(g, "broken_bonds", 0)) == PD_OK &&
        (s = pd_h5_write_attr_int(g, "lost_particles", 0)) == PD_OK)
        s = pd_h5_write_attr_int(g, "complete", 0);
    for (int k = 0; k < NENERGY && s == PD_OK; k++)
        s = pd_h5_write_attr_doubles(g, energy_attrs[k], &zero, 1);
    if (s == PD_OK && (fields & PD_FIELD_ENERGY))
        s = pd_h5_reserve_data(g, "strain_energy_density", H5T_IEEE_F64LE, 1, d1);
    hsize_t d3[3] = {(hsize_t)n, 3, 3};
    if (s == PD_OK && (fields & PD_FIELD_STRESS) &&
        (s = pd_h5_reserve_data(g, "stress", H5T_IEEE_F64LE, 3, d3)) == PD_OK)
        s = pd_h5_reserve_data(g, "von_mises", H5T_IEEE_F64LE, 1, d1);
    double zeros[3] = {0, 0, 0};
    if (s == PD_OK && (fields & PD_FRAME_PROJECTILE) &&
        (s = pd_h5_write_attr_doubles(g, "projectile_position", zeros, 3)) == PD_OK &&
        (s = pd_h5_write_attr_doubles(g, "projectile_velocity", zeros, 3)) == PD_OK)
        s = pd_h5_write_attr_doubles(g, "projectile_energy", zeros, 1);
    if (s == PD_OK && (fields & PD_FRAME_DAMPING))
        s = pd_h5_write_attr_doubles(g, "damped_energy", zeros, 1);
    H5Gclose(g);
    return s;
}

pd_status pd_plan_frames(pd_file *f, int64_t n, int64_t nbonds, int64_t nframes,
                         const int64_t *steps, const double *times, unsigned fields)
{
    pd_status s = PD_OK;
    for (int64_t k = 0; k < nframes && s == PD_OK; k++)
        s = lay_out_frame(f, n, nbonds, steps[k], times[k], fields);
    return s;
}

/* A part's rows of the first index of an array of `width` values a row
 * (local rows from pt->lo) into dataset `name` of g. */
static pd_status write_part(hid_t g, const char *name, hid_t memtype, const double *a, int width,
                            const pd_part *pt)
{
    return pd_h5_write_rows(g, name, memtype, a ? a + pt->lo * width : NULL, pt->first,
                            pt->rows);
}

pd_status pd_write_frame_part(pd_file *f, const pd_part *pt, const pd_frame_info *fi,
                              double *const x[3], double *const y[3], double *const v[3],
                              const uint64_t *intact, const pd_frame_fields *ff)
{
    static const pd_frame_fields none;
    if (ff == NULL)
        ff = &none;
    char path[64];
    frame_name(fi->step, path, sizeof path);
    if (!pd_h5_has_link(f->fid, path)) { /* not laid out: lay out this one */
        unsigned fields = (ff->energy_density ? PD_FIELD_ENERGY : 0) |
                          (ff->stress && ff->von_mises ? PD_FIELD_STRESS : 0) |
                          (fi->has_projectile ? PD_FRAME_PROJECTILE : 0) |
                          (fi->has_damping ? PD_FRAME_DAMPING : 0);
        pd_status s = lay_out_frame(f, pt->n, pt->nbonds, fi->step, fi->time, fields);
        if (s != PD_OK)
            return s;
    }
    hid_t g = H5Gopen2(f->fid, path, H5P_DEFAULT);
    if (g < 0)
        return pd_fail(PD_ERR_IO, "cannot open frame %s", path);
    const size_t n = (size_t)pt->rows, lo = (size_t)pt->lo;
    double *buf = malloc((n ? n : 1) * 3 * sizeof(double));
    int64_t at = 0, count = 0;
    uint8_t *bytes = pt->nbonds > 0 ? state_bytes(f, pt, intact, &at, &count) : NULL;
    pd_status s = PD_OK;
    if (buf == NULL || (pt->nbonds > 0 && bytes == NULL))
        s = pd_fail(PD_ERR_NOMEM, "out of memory writing a frame");
    if (f->ranks > 1)
        s = pd_comm_agree(s);
    if (s == PD_OK) {
#pragma omp parallel for schedule(static)
        for (size_t i = 0; i < n; i++)
            for (int d = 0; d < 3; d++)
                buf[3 * i + d] = y[d][lo + i] - x[d][lo + i];
        s = pd_h5_write_rows(g, "displacement", H5T_NATIVE_DOUBLE, buf, pt->first, pt->rows);
    }
    if (s == PD_OK) {
        const double *vv[3] = {v[0] + lo, v[1] + lo, v[2] + lo};
        interleave(buf, (double *const *)vv, pt->rows);
        s = pd_h5_write_rows(g, "velocity", H5T_NATIVE_DOUBLE, buf, pt->first, pt->rows);
    }
    if (s == PD_OK && pt->nbonds > 0)
        s = pd_h5_write_rows(g, "state", H5T_NATIVE_UINT8, bytes, at, count);
    if (s == PD_OK && ff->damage)
        s = write_part(g, "damage", H5T_NATIVE_DOUBLE, ff->damage, 1, pt);
    else if (s == PD_OK) {
        memset(buf, 0, n * sizeof(double));
        s = pd_h5_write_rows(g, "damage", H5T_NATIVE_DOUBLE, buf, pt->first, pt->rows);
    }
    if (s == PD_OK && ff->energy_density)
        s = write_part(g, "strain_energy_density", H5T_NATIVE_DOUBLE, ff->energy_density, 1, pt);
    if (s == PD_OK && ff->stress && ff->von_mises &&
        (s = write_part(g, "stress", H5T_NATIVE_DOUBLE, ff->stress, 9, pt)) == PD_OK)
        s = write_part(g, "von_mises", H5T_NATIVE_DOUBLE, ff->von_mises, 1, pt);
    pd_energy e = fi->energy;
    for (int k = 0; k < NENERGY && s == PD_OK; k++)
        s = pd_h5_update_attr(g, energy_attrs[k], H5T_NATIVE_DOUBLE, energy_field(&e, k));
    if (s == PD_OK)
        s = pd_h5_update_attr(g, "broken_bonds", H5T_NATIVE_INT64, &fi->broken);
    if (s == PD_OK)
        s = pd_h5_update_attr(g, "lost_particles", H5T_NATIVE_INT64, &fi->lost);
    if (s == PD_OK && fi->has_projectile) {
        pd_frame_info pf = *fi;
        if ((s = pd_h5_update_attr(g, "projectile_position", H5T_NATIVE_DOUBLE,
                                   pf.projectile_position)) == PD_OK &&
            (s = pd_h5_update_attr(g, "projectile_velocity", H5T_NATIVE_DOUBLE,
                                   pf.projectile_velocity)) == PD_OK)
            s = pd_h5_update_attr(g, "projectile_energy", H5T_NATIVE_DOUBLE,
                                  &pf.energy.projectile);
    }
    if (s == PD_OK && fi->has_damping)
        s = pd_h5_update_attr(g, "damped_energy", H5T_NATIVE_DOUBLE, &e.damped);
    /* the frame whole on disk first, then marked complete */
    if (s == PD_OK && H5Fflush(f->fid, H5F_SCOPE_LOCAL) < 0)
        s = pd_fail(PD_ERR_IO, "cannot write frame %s (disk full?)", path);
    int64_t one = 1;
    if (s == PD_OK)
        s = pd_h5_update_attr(g, "complete", H5T_NATIVE_INT64, &one);
    if (s == PD_OK && H5Fflush(f->fid, H5F_SCOPE_LOCAL) < 0)
        s = pd_fail(PD_ERR_IO, "cannot write frame %s (disk full?)", path);
    free(buf);
    free(bytes);
    H5Gclose(g);
    return s;
}

pd_status pd_write_frame(pd_file *f, const pd_particles *p, const pd_frame_info *fi,
                         double *const y[3], double *const v[3], const uint64_t *intact,
                         int64_t nbonds, const pd_frame_fields *ff)
{
    const pd_part whole = {0, 0, p->n, p->n, 0, 0, nbonds, nbonds};
    return pd_write_frame_part(f, &whole, fi, p->x, y, v, intact, ff);
}

typedef struct {
    int64_t step;
    double time; /* s */
    char *name;
} frame_entry;

typedef struct {
    frame_entry *v;
    int64_t n, cap;
    pd_status st;
    const char *file;
} frame_list;

static herr_t collect_frame(hid_t g, const char *name, const H5L_info_t *info, void *data)
{
    (void)info;
    frame_list *fl = data;
    hid_t fg = H5Gopen2(g, name, H5P_DEFAULT);
    if (fg < 0) {
        fl->st = pd_fail(PD_ERR_FORMAT, "'%s': /frames/%s is not a group", fl->file, name);
        return 1;
    }
    /* step, complete (when there), and of a complete frame its time; attr
     * names the one that failed */
    int64_t step, complete = 1;
    double time = 0;
    const char *attr = "step";
    pd_status s = pd_h5_read_attr_int(fg, attr, &step);
    if (s == PD_OK && pd_h5_has_attr(fg, "complete")) {
        attr = "complete";
        s = pd_h5_read_attr_int(fg, attr, &complete);
    }
    if (s == PD_OK && complete == 1) {
        attr = "time";
        s = pd_h5_read_attr_double(fg, attr, &time);
    }
    const int missing = s != PD_OK && !pd_h5_has_attr(fg, attr);
    H5Gclose(fg);
    if (s == PD_OK && complete != 1)
        return 0; /* laid out, not (yet) written: not a frame */
    if (s != PD_OK) {
        fl->st = missing ? pd_fail(PD_ERR_FORMAT, "'%s': frame '%s' has no %s attribute", fl->file,
                                   name, attr)
                         : pd_fail(PD_ERR_FORMAT, "'%s': frame '%s': %s", fl->file, name,
                                   pd_errmsg());
        return 1;
    }
    if (fl->n == fl->cap) {
        int64_t cap = fl->cap ? 2 * fl->cap : 64;
        frame_entry *nv = realloc(fl->v, (size_t)cap * sizeof *nv);
        if (nv == NULL) {
            fl->st = pd_fail(PD_ERR_NOMEM, "out of memory listing frames");
            return 1;
        }
        fl->v = nv;
        fl->cap = cap;
    }
    fl->v[fl->n].step = step;
    fl->v[fl->n].time = time;
    if ((fl->v[fl->n].name = strdup(name)) == NULL) {
        fl->st = pd_fail(PD_ERR_NOMEM, "out of memory listing frames");
        return 1;
    }
    fl->n++;
    return 0;
}

/* By step, then by name (so that of two frames with one step the same
 * one is reported, whatever qsort does). */
static int cmp_frame(const void *a, const void *b)
{
    const frame_entry *x = a, *y = b;
    if (x->step != y->step)
        return (x->step > y->step) - (x->step < y->step);
    return strcmp(x->name, y->name);
}

/* How far a frame's time may lie from step x dt, relative to step x dt
 * (to dt at step 0): pd-run writes (double)step * dt exactly; this leaves
 * room for a time summed step by step over some 10^6 steps. */
#define FRAME_TIME_RTOL 1e-9

/* The rule of complete frames, in step order v[0..n): steps non-negative
 * and strictly increasing, times finite, non-decreasing and step x dt
 * (the /scene dt) to FRAME_TIME_RTOL. */
static pd_status check_frames(const pd_file *f, const frame_entry *v, int64_t n)
{
    double dt;
    if (!pd_h5_has_link(f->fid, "/scene"))
        return pd_fail(PD_ERR_FORMAT, "'%s' has frames but no /scene (its dt)", f->name);
    hid_t g = H5Gopen2(f->fid, "/scene", H5P_DEFAULT);
    if (g < 0)
        return pd_fail(PD_ERR_FORMAT, "'%s': /scene is not a group", f->name);
    pd_status s = pd_h5_read_attr_double(g, "dt", &dt);
    H5Gclose(g);
    if (s != PD_OK)
        return pd_fail(PD_ERR_FORMAT, "'%s': /scene: %s", f->name, pd_errmsg());
    if (!(isfinite(dt) && dt > 0))
        return pd_fail(PD_ERR_FORMAT, "'%s': /scene has dt %.10g; dt must be positive and finite",
                       f->name, dt);
    for (int64_t k = 0; k < n; k++) {
        const frame_entry *e = &v[k], *prev = k ? &v[k - 1] : NULL;
        const double want = (double)e->step * dt;
        if (e->step < 0)
            return pd_fail(PD_ERR_FORMAT, "'%s': frame '%s' has step %lld; steps must be "
                           "non-negative", f->name, e->name, (long long)e->step);
        if (prev && e->step <= prev->step)
            return pd_fail(PD_ERR_FORMAT, "'%s': frame '%s' has step %lld, as frame '%s' does; "
                           "steps must be strictly increasing", f->name, e->name,
                           (long long)e->step, prev->name);
        if (!isfinite(e->time))
            return pd_fail(PD_ERR_FORMAT, "'%s': frame '%s' has time %g; times must be finite",
                           f->name, e->name, e->time);
        if (prev && e->time < prev->time)
            return pd_fail(PD_ERR_FORMAT, "'%s': frame '%s' has time %.10g, before frame '%s' "
                           "(time %.10g); times must not decrease", f->name, e->name, e->time,
                           prev->name, prev->time);
        if (!(fabs(e->time - want) <= FRAME_TIME_RTOL * (e->step > 0 ? want : dt)))
            return pd_fail(PD_ERR_FORMAT, "'%s': frame '%s' has time %.10g, not step x dt = "
                           "%lld x %.10g = %.10g (/scene dt)", f->name, e->name, e->time,
                           (long long)e->step, dt, want);
    }
    return PD_OK;
}

pd_status pd_list_frames(const pd_file *f, int64_t *nframes, char ***names)
{
    *nframes = 0;
    *names = NULL;
    if (!pd_h5_has_link(f->fid, "/frames"))
        return pd_fail(PD_ERR_FORMAT, "'%s' has no /frames (not made by pd-run?)", f->name);
    hid_t g = H5Gopen2(f->fid, "/frames", H5P_DEFAULT);
    frame_list fl = {NULL, 0, 0, PD_OK, f->name};
    hsize_t idx = 0;
    H5Literate(g, H5_INDEX_NAME, H5_ITER_INC, &idx, collect_frame, &fl);
    H5Gclose(g);
    if (fl.st != PD_OK) {
        for (int64_t k = 0; k < fl.n; k++)
            free(fl.v[k].name);
        free(fl.v);
        return fl.st;
    }
    if (fl.n == 0) { /* a run killed before its first frame: none yet */
        free(fl.v);
        return PD_OK;
    }
    qsort(fl.v, (size_t)fl.n, sizeof *fl.v, cmp_frame);
    pd_status s = check_frames(f, fl.v, fl.n);
    char **out = s == PD_OK ? malloc((size_t)fl.n * sizeof *out) : NULL;
    if (out == NULL) {
        for (int64_t k = 0; k < fl.n; k++)
            free(fl.v[k].name);
        free(fl.v);
        return s == PD_OK ? pd_fail(PD_ERR_NOMEM, "out of memory") : s;
    }
    for (int64_t k = 0; k < fl.n; k++)
        out[k] = fl.v[k].name;
    free(fl.v);
    *nframes = fl.n;
    *names = out;
    return PD_OK;
}

void pd_frames_free_list(int64_t nframes, char **names)
{
    if (names == NULL)
        return;
    for (int64_t k = 0; k < nframes; k++)
        free(names[k]);
    free(names);
}

pd_status pd_read_frame_info(const pd_file *f, const char *name, pd_frame_info *fi)
{
    char path[256];
    pd_status s = frame_path(name, NULL, path, sizeof path);
    if (s != PD_OK)
        return s;
    hid_t g = H5Gopen2(f->fid, path, H5P_DEFAULT);
    if (g < 0)
        return pd_fail(PD_ERR_FORMAT, "'%s' has no frame '%s'", f->name, name);
    memset(fi, 0, sizeof *fi);
    s = pd_h5_read_attr_int(g, "step", &fi->step);
    if (s == PD_OK)
        s = pd_h5_read_attr_double(g, "time", &fi->time);
    for (int k = 0; k < NENERGY && s == PD_OK; k++)
        if (pd_h5_has_attr(g, energy_attrs[k]))
            s = pd_h5_read_attr_double(g, energy_attrs[k], energy_field(&fi->energy, k));
    if (s == PD_OK && pd_h5_has_attr(g, "broken_bonds"))
        s = pd_h5_read_attr_int(g, "broken_bonds", &fi->broken);
    if (s == PD_OK && pd_h5_has_attr(g, "lost_particles"))
        s = pd_h5_read_attr_int(g, "lost_particles", &fi->lost);
    if (s == PD_OK && pd_h5_has_attr(g, "projectile_position")) {
        fi->has_projectile = 1;
        if ((s = pd_h5_read_attr_doubles(g, "projectile_position", fi->projectile_position, 3)) ==
                PD_OK &&
            (s = pd_h5_read_attr_doubles(g, "projectile_velocity", fi->projectile_velocity, 3)) ==
                PD_OK)
            s = pd_h5_read_attr_double(g, "projectile_energy", &fi->energy.projectile);
    }
    if (s == PD_OK && pd_h5_has_attr(g, "damped_energy")) {
        fi->has_damping = 1;
        s = pd_h5_read_attr_double(g, "damped_energy", &fi->energy.damped);
    }
    H5Gclose(g);
    if (s != PD_OK)
        return pd_fail(PD_ERR_FORMAT, "'%s': frame '%s': %s", f->name, name, pd_errmsg());
    return PD_OK;
}

pd_status pd_frame_spheres(const pd_file *f, const pd_frame_info *fi, pd_frame_sphere out[2],
                           int *n)
{
    *n = 0;
    if (!pd_h5_has_link(f->fid, "/scene"))
        return PD_OK;
    hid_t g = H5Gopen2(f->fid, "/scene", H5P_DEFAULT);
    if (g < 0)
        return pd_fail(PD_ERR_FORMAT, "'%s': /scene is not a group", f->name);
    double ind[8], pr[9], dt = 0.0;
    pd_status s = PD_OK;
    if (pd_h5_has_attr(g, "indenter") &&
        (s = pd_h5_read_attr_doubles(g, "indenter", ind, 8)) == PD_OK &&
        (s = pd_h5_read_attr_double(g, "dt", &dt)) == PD_OK) {
        pd_frame_sphere *sp = &out[(*n)++];
        sp->name = "indenter";
        pd_indenter_centre(ind, ind + 5, fi->step, dt, sp->centre);
        sp->radius = ind[3];
        memcpy(sp->velocity, ind + 5, sizeof sp->velocity);
    }
    /* the projectile as the frame has it (files before those attributes:
     * none drawn) */
    if (s == PD_OK && fi->has_projectile && pd_h5_has_attr(g, "projectile") &&
        (s = pd_h5_read_attr_doubles(g, "projectile", pr, 9)) == PD_OK) {
        pd_frame_sphere *sp = &out[(*n)++];
        sp->name = "projectile";
        memcpy(sp->centre, fi->projectile_position, sizeof sp->centre);
        sp->radius = pr[3];
        memcpy(sp->velocity, fi->projectile_velocity, sizeof sp->velocity);
    }
    H5Gclose(g);
    for (int k = 0; k < *n && s == PD_OK; k++)
        if (!(isfinite(out[k].radius) && out[k].radius > 0))
            s = pd_fail(PD_ERR_FORMAT, "/scene gives the %s radius %g", out[k].name,
                        out[k].radius);
    if (s != PD_OK) {
        *n = 0;
        return pd_fail(PD_ERR_FORMAT, "'%s': %s", f->name, pd_errmsg());
    }
    return PD_OK;
}

pd_status pd_read_frame_vectors(const pd_file *f, const char *name, int64_t n, double *disp[3],
                                double *vel[3])
{
    return pd_read_frame_vectors_rows(f, name, n, 0, n, disp, vel);
}

pd_status pd_read_frame_vectors_rows(const pd_file *f, const char *name, int64_t n, int64_t g0,
                                     int64_t m, double *disp[3], double *vel[3])
{
    const char *fields[2] = {"displacement", "velocity"};
    double **dst[2] = {disp, vel};
    for (int k = 0; k < 2; k++) {
        if (dst[k] == NULL)
            continue;
        char path[256];
        pd_status s = frame_path(name, fields[k], path, sizeof path);
        if (s != PD_OK)
            return s;
        pd_h5_form form = {H5T_FLOAT, 8, 2, {(hsize_t)n, 3}};
        double *buf = malloc((size_t)(m > 0 ? m : 1) * 3 * sizeof(double));
        s = buf ? pd_h5_read_rows(f->fid, f->name, path, &form, H5T_NATIVE_DOUBLE, buf, g0, m)
                : pd_fail(PD_ERR_NOMEM, "out of memory reading a frame");
        if (s == PD_OK)
            deinterleave(dst[k], buf, m);
        free(buf);
        if (s != PD_OK)
            return s;
    }
    return PD_OK;
}

pd_status pd_read_frame_state_rows(const pd_file *f, const char *name, int64_t k0, int64_t count,
                                   uint64_t *intact, int64_t at)
{
    char path[256];
    pd_status s = frame_path(name, "state", path, sizeof path);
    return s == PD_OK ? read_bit_rows(f, path, k0, k0 + count, 0, intact, at) : s;
}

pd_status pd_read_frame_state(const pd_file *f, const char *name, int64_t count, uint64_t *intact)
{
    char path[256];
    pd_status s = frame_path(name, "state", path, sizeof path);
    if (s != PD_OK)
        return s;
    pd_h5_form form = {H5T_INTEGER, 1, 1, {(hsize_t)((count + 7) / 8), 0}};
    if (count == 0)
        return PD_OK;
    uint8_t *bytes = NULL;
    s = pd_h5_read_data(f->fid, f->name, path, &form, H5T_NATIVE_UINT8, 1, (void **)&bytes, NULL);
    if (s != PD_OK)
        return s;
    bytes_to_words(bytes, count, intact);
    free(bytes);
    return PD_OK;
}

pd_status pd_read_frame_scalar(const pd_file *f, const char *name, const char *field, int64_t n,
                               double *out, int *present)
{
    char path[256];
    pd_status s = frame_path(name, field, path, sizeof path);
    if (s != PD_OK)
        return s;
    *present = pd_h5_has_link(f->fid, path);
    if (!*present)
        return PD_OK;
    pd_h5_form form = {H5T_FLOAT, 8, 1, {(hsize_t)n, 0}};
    double *buf = NULL;
    s = pd_h5_read_data(f->fid, f->name, path, &form, H5T_NATIVE_DOUBLE, sizeof(double),
                        (void **)&buf, NULL);
    if (s != PD_OK)
        return s;
    memcpy(out, buf, (size_t)n * sizeof(double));
    free(buf);
    return PD_OK;
}

pd_status pd_read_frame_stress(const pd_file *f, const char *name, int64_t n, double *out,
                               int *present)
{
    char path[256];
    pd_status s = frame_path(name, "stress", path, sizeof path);
    if (s != PD_OK)
        return s;
    *present = pd_h5_has_link(f->fid, path);
    if (!*present)
        return PD_OK;
    /* (N,3,3) read as (N,9): the form checks rank 2, so look at rank 3 here */
    hid_t ds = H5Dopen2(f->fid, path, H5P_DEFAULT);
    if (ds < 0)
        return pd_fail(PD_ERR_FORMAT, "'%s': cannot open '%s'", f->name, path);
    hid_t sp = H5Dget_space(ds);
    hsize_t dims[3] = {0, 0, 0};
    int rank = sp < 0 ? -1 : H5Sget_simple_extent_ndims(sp);
    if (rank == 3)
        H5Sget_simple_extent_dims(sp, dims, NULL);
    hid_t ft = H5Dget_type(ds);
    int isfloat = ft >= 0 && H5Tget_class(ft) == H5T_FLOAT;
    if (ft >= 0)
        H5Tclose(ft);
    if (sp >= 0)
        H5Sclose(sp);
    if (rank != 3 || dims[0] != (hsize_t)n || dims[1] != 3 || dims[2] != 3 || !isfloat) {
        H5Dclose(ds);
        return pd_fail(PD_ERR_FORMAT, "'%s': dataset '%s' is not a (%lld,3,3) float dataset",
                       f->name, path, (long long)n);
    }
    herr_t rc = H5Dread(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, out);
    H5Dclose(ds);
    return rc < 0 ? pd_fail(PD_ERR_FORMAT, "'%s': cannot read '%s'", f->name, path) : PD_OK;
}

pd_status pd_write_frame_scalar(pd_file *f, const char *name, const char *field, int64_t n,
                                const double *values)
{
    char path[256];
    pd_status s = frame_path(name, field, path, sizeof path);
    if (s != PD_OK)
        return s;
    if (pd_h5_has_link(f->fid, path))
        H5Ldelete(f->fid, path, H5P_DEFAULT);
    hsize_t d1[1] = {(hsize_t)n};
    return pd_h5_write_data(f->fid, path, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 1, d1, values);
}

/* The bonds and the frame's state bits, the bonds read on first need. */
static pd_status frame_bonds(const pd_file *f, const pd_particles *p, const char *frame,
                             pd_bonds **b, uint64_t **intact)
{
    pd_status s;
    if (*b == NULL && (s = pd_read_bonds(f, p, b)) != PD_OK)
        return s;
    if (*intact == NULL) {
        *intact = calloc((size_t)pd_bits_words((*b)->count) + 1, sizeof(uint64_t));
        if (*intact == NULL)
            return pd_fail(PD_ERR_NOMEM, "out of memory");
    }
    return pd_read_frame_state(f, frame, (*b)->count, *intact);
}

pd_status pd_read_frame_damage(const pd_file *f, const pd_particles *p, const char *frame,
                               pd_bonds **b, uint64_t **intact, double *damage)
{
    int present = 0;
    pd_status s = pd_read_frame_scalar(f, frame, "damage", p->n, damage, &present);
    if (s != PD_OK || present)
        return s;
    if ((s = frame_bonds(f, p, frame, b, intact)) != PD_OK)
        return s;
    pd_damage(p, *b, *intact, damage);
    return PD_OK;
}

pd_status pd_read_frame_damage_run(const pd_file *f, const pd_particles *p, const char *frame,
                                   pd_bonds **b, uint64_t **intact, double *damage,
                                   int *present)
{
    *present = pd_h5_has_link(f->fid, "/bonds/precrack");
    if (!*present)
        return PD_OK;
    int stored = 0;
    pd_status s = pd_read_frame_scalar(f, frame, "damage_run", p->n, damage, &stored);
    if (s != PD_OK || stored)
        return s;
    if ((s = frame_bonds(f, p, frame, b, intact)) != PD_OK)
        return s;
    pd_damage_no_precrack(p, *b, *intact, damage);
    return PD_OK;
}

/* ------------------------------------------------------------ restart */

/* Two restart slots, /restart/0 and /restart/1, laid out with the frames
 * and written in turn, each after its frame's data and before the frame is
 * marked complete: the slot of the last complete frame is always whole (the
 * other slot may be half written when a run is killed).  A fresh run of
 * one frame lays out the first only: killed before that frame is complete
 * it leaves nothing to go on from. */

static const char *restart_fields[4] = {"position", "force", "s0", "contact_position"};
/* the run's accumulated energies and the last power (pd_restart) */
#define NSUMS 5
static const char *restart_sums[NSUMS] = {"external_work", "released_energy", "external_power",
                                          "lost_energy", "initial_energy"};

static double *restart_sum(pd_restart *r, int a)
{
    double *v[NSUMS] = {&r->work, &r->released, &r->power, &r->lost_energy, &r->energy0};
    return v[a];
}

pd_status pd_plan_restart(pd_file *f, int64_t n, int has_s0, int has_contact, int slots)
{
    if (!pd_h5_has_link(f->fid, "/restart")) {
        hid_t root = pd_h5_create_group(f->fid, "/restart");
        if (root < 0)
            return pd_fail(PD_ERR_IO, "cannot create /restart");
        H5Gclose(root);
    }
    hsize_t d2[2] = {(hsize_t)n, 3}, d1[1] = {(hsize_t)n};
    pd_status s = PD_OK;
    for (int k = 0; k < slots && k < 2 && s == PD_OK; k++) {
        char path[32];
        snprintf(path, sizeof path, "/restart/%d", k);
        if (pd_h5_has_link(f->fid, path))
            continue;
        hid_t g = pd_h5_create_group(f->fid, path);
        if (g < 0)
            return pd_fail(PD_ERR_IO, "cannot create %s", path);
        if ((s = pd_h5_reserve_data(g, "position", H5T_IEEE_F64LE, 2, d2)) == PD_OK)
            s = pd_h5_reserve_data(g, "force", H5T_IEEE_F64LE, 2, d2);
        if (s == PD_OK && has_s0)
            s = pd_h5_reserve_data(g, "s0", H5T_IEEE_F64LE, 1, d1);
        if (s == PD_OK && has_contact)
            s = pd_h5_reserve_data(g, "contact_position", H5T_IEEE_F64LE, 2, d2);
        if (s == PD_OK && (s = pd_h5_write_attr_int(g, "step", -1)) == PD_OK &&
            (s = pd_h5_write_attr_int(g, "contact_builds", 0)) == PD_OK)
            s = pd_h5_write_attr_int(g, "complete", 0);
        double zero = 0;
        for (int a = 0; a < NSUMS && s == PD_OK; a++)
            s = pd_h5_write_attr_doubles(g, restart_sums[a], &zero, 1);
        /* lost particles: flags, written once some are */
        if (s == PD_OK && (s = pd_h5_reserve_data(g, "lost", H5T_STD_U8LE, 1, d1)) == PD_OK)
            s = pd_h5_write_attr_int(g, "lost_particles", 0);
        H5Gclose(g);
    }
    return s;
}

static void slot_info(hid_t fid, int k, int64_t *step, int64_t *complete)
{
    char path[32];
    snprintf(path, sizeof path, "/restart/%d", k);
    *step = -1;
    *complete = 0;
    hid_t g = pd_h5_has_link(fid, path) ? H5Gopen2(fid, path, H5P_DEFAULT) : -1;
    if (g < 0)
        return;
    if (pd_h5_read_attr_int(g, "step", step) != PD_OK ||
        pd_h5_read_attr_int(g, "complete", complete) != PD_OK)
        *complete = 0;
    H5Gclose(g);
}

pd_status pd_write_restart_part(pd_file *f, const pd_part *pt, int64_t step, const pd_restart *r)
{
    int64_t st[2], done[2];
    slot_info(f->fid, 0, &st[0], &done[0]);
    slot_info(f->fid, 1, &st[1], &done[1]);
    int k = !pd_h5_has_link(f->fid, "/restart/1") ? 0 /* a run of one frame */
            : !done[0]                            ? 0
            : !done[1]                            ? 1
                                                  : (st[0] <= st[1] ? 0 : 1);
    char path[32];
    snprintf(path, sizeof path, "/restart/%d", k);
    hid_t g = H5Gopen2(f->fid, path, H5P_DEFAULT);
    if (g < 0)
        return pd_fail(PD_ERR_IO, "'%s' has no %s", f->name, path);
    /* the contact list's positions change only when it is built: a
     * complete slot of the same build holds them already */
    int64_t builds = -1;
    const int same_list = done[k] && r->contact_position[0] &&
                          pd_h5_has_attr(g, "contact_builds") &&
                          pd_h5_read_attr_int(g, "contact_builds", &builds) == PD_OK &&
                          builds == r->contact_builds && pd_h5_has_link(g, "contact_position");
    const int64_t n = pt->rows, lo = pt->lo;
    double *buf = malloc((size_t)(n > 0 ? n : 1) * 3 * sizeof(double));
    int64_t zero = 0, one = 1;
    pd_status s = buf ? PD_OK : pd_fail(PD_ERR_NOMEM, "out of memory writing restart data");
    if (f->ranks > 1)
        s = pd_comm_agree(s);
    if (s == PD_OK)
        s = pd_h5_update_attr(g, "complete", H5T_NATIVE_INT64, &zero);
    if (s == PD_OK && H5Fflush(f->fid, H5F_SCOPE_LOCAL) < 0)
        s = pd_fail(PD_ERR_IO, "cannot write restart data (disk full?)");
    /* the part's rows of an array of three */
#define ROWS3(name, a)                                                                          \
    do {                                                                                       \
        const double *own[3] = {(a)[0] + lo, (a)[1] + lo, (a)[2] + lo};                        \
        interleave(buf, (double *const *)own, n);                                              \
        s = pd_h5_write_rows(g, name, H5T_NATIVE_DOUBLE, buf, pt->first, n);                   \
    } while (0)
    if (s == PD_OK)
        ROWS3("position", r->position);
    if (s == PD_OK)
        ROWS3("force", r->force);
    if (s == PD_OK && r->s0)
        s = pd_h5_write_rows(g, "s0", H5T_NATIVE_DOUBLE, r->s0 + lo, pt->first, n);
    if (s == PD_OK && r->contact_position[0] && !same_list)
        ROWS3("contact_position", r->contact_position);
#undef ROWS3
    if (s == PD_OK)
        s = pd_h5_update_attr(g, "step", H5T_NATIVE_INT64, &step);
    if (s == PD_OK)
        s = pd_h5_update_attr(g, "contact_builds", H5T_NATIVE_INT64, &r->contact_builds);
    pd_restart sums = *r;
    for (int a = 0; a < NSUMS && s == PD_OK; a++)
        s = pd_h5_update_attr(g, restart_sums[a], H5T_NATIVE_DOUBLE, restart_sum(&sums, a));
    int64_t nlost = 0;
    for (int64_t i = lo; r->lost && i < lo + n; i++)
        nlost += r->lost[i] != 0;
    if (f->ranks > 1)
        nlost = pd_comm_total(nlost);
    if (s == PD_OK && nlost > 0)
        s = pd_h5_write_rows(g, "lost", H5T_NATIVE_UINT8, r->lost ? r->lost + lo : NULL, pt->first,
                             r->lost ? n : 0);
    if (s == PD_OK)
        s = pd_h5_update_attr(g, "lost_particles", H5T_NATIVE_INT64, &nlost);
    if (s == PD_OK && r->has_projectile)
        s = pd_h5_update_attr(g, "projectile", H5T_NATIVE_DOUBLE, sums.projectile);
    if (s == PD_OK && r->has_damping)
        s = pd_h5_update_attr(g, "damping", H5T_NATIVE_DOUBLE, sums.damping);
    const int w = r->history_width;
    if (s == PD_OK && r->bond_history)
        s = pd_h5_write_rows(g, "bond_history", H5T_NATIVE_DOUBLE, r->bond_history + pt->klo * w,
                             pt->bond0, pt->bonds);
    if (s == PD_OK && H5Fflush(f->fid, H5F_SCOPE_LOCAL) < 0)
        s = pd_fail(PD_ERR_IO, "cannot write restart data (disk full?)");
    if (s == PD_OK)
        s = pd_h5_update_attr(g, "complete", H5T_NATIVE_INT64, &one);
    free(buf);
    H5Gclose(g);
    return s;
}

pd_status pd_write_restart(pd_file *f, int64_t n, int64_t step, const pd_restart *r)
{
    const int64_t nb = r->bond_history ? r->history_bonds : 0;
    const pd_part whole = {0, 0, n, n, 0, 0, nb, nb};
    return pd_write_restart_part(f, &whole, step, r);
}

void pd_restart_free(pd_restart *r)
{
    for (int d = 0; d < 3; d++) {
        free(r->position[d]);
        free(r->force[d]);
        free(r->contact_position[d]);
    }
    free(r->s0);
    free(r->lost);
    free(r->bond_history);
    memset(r, 0, sizeof *r);
}

/* The bond history's rows [k0, k0 + nb) of the restart slot's dataset
 * `path` (width values a row) into r. */
static pd_status read_history_rows(const pd_file *f, const char *path, int64_t k0, int64_t nb,
                                   pd_restart *r)
{
    hid_t d = H5Dopen2(f->fid, path, H5P_DEFAULT);
    hsize_t dims[2] = {0, 0};
    if (d < 0)
        return pd_fail(PD_ERR_FORMAT, "'%s': '%s' is not a dataset", f->name, path);
    hid_t sp = H5Dget_space(d);
    const int rank = H5Sget_simple_extent_ndims(sp);
    if (rank == 2)
        H5Sget_simple_extent_dims(sp, dims, NULL);
    H5Sclose(sp);
    H5Dclose(d);
    if (rank != 2 || dims[1] < 1 || dims[1] > 16)
        return pd_fail(PD_ERR_FORMAT, "'%s': %s is not a table of a few values a bond", f->name,
                       path);
    const int w = (int)dims[1];
    r->bond_history = malloc((size_t)(nb > 0 ? nb : 1) * (size_t)w * sizeof(double));
    if (r->bond_history == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for the bond history");
    const pd_h5_form form = {H5T_FLOAT, 8, 2, {0, (hsize_t)w}};
    r->history_bonds = nb;
    r->history_width = w;
    return pd_h5_read_rows(f->fid, f->name, path, &form, H5T_NATIVE_DOUBLE, r->bond_history, k0,
                           nb);
}

static pd_status read_restart(const pd_file *f, int64_t n, int64_t g0, int64_t m, int64_t step,
                              int64_t k0, int64_t nb, pd_restart *r);

pd_status pd_read_restart(const pd_file *f, int64_t n, int64_t step, pd_restart *r)
{
    return read_restart(f, n, 0, n, step, 0, -1, r);
}

pd_status pd_read_restart_rows(const pd_file *f, int64_t n, int64_t g0, int64_t m, int64_t step,
                               int64_t k0, int64_t nb, pd_restart *r)
{
    return read_restart(f, n, g0, m, step, k0, nb, r);
}

/* pd_read_restart, of the particles' rows [g0, g0 + m) of n alone, and the
 * bond history's rows [k0, k0 + nb) alone when nb >= 0. */
static pd_status read_restart(const pd_file *f, int64_t n, int64_t g0, int64_t m, int64_t step,
                              int64_t k0, int64_t nb, pd_restart *r)
{
    memset(r, 0, sizeof *r);
    int k = -1;
    for (int q = 0; q < 2; q++) {
        int64_t st, done;
        slot_info(f->fid, q, &st, &done);
        if (done == 1 && st == step)
            k = q;
    }
    if (k < 0)
        return pd_fail(PD_ERR_FORMAT, "'%s' has no restart data for step %lld", f->name,
                       (long long)step);
    char group[32];
    snprintf(group, sizeof group, "/restart/%d", k);
    pd_status s = PD_OK;
    for (int fld = 0; fld < 4 && s == PD_OK; fld++) {
        char path[64];
        snprintf(path, sizeof path, "%s/%s", group, restart_fields[fld]);
        if (!pd_h5_has_link(f->fid, path)) {
            if (fld < 2)
                s = pd_fail(PD_ERR_FORMAT, "'%s' has no %s", f->name, path);
            continue;
        }
        int vec = fld != 2;
        pd_h5_form form = {H5T_FLOAT, 8, vec ? 2 : 1, {(hsize_t)n, vec ? 3 : 0}};
        double *buf = malloc((size_t)(m > 0 ? m : 1) * (vec ? 3 : 1) * sizeof(double));
        s = buf ? pd_h5_read_rows(f->fid, f->name, path, &form, H5T_NATIVE_DOUBLE, buf, g0, m)
                : pd_fail(PD_ERR_NOMEM, "out of memory reading restart data");
        if (s != PD_OK) {
            free(buf);
            break;
        }
        if (!vec) {
            r->s0 = buf;
            continue;
        }
        double **dst = fld == 0 ? r->position : fld == 1 ? r->force : r->contact_position;
        for (int d = 0; d < 3 && s == PD_OK; d++)
            if ((dst[d] = malloc((size_t)(m > 0 ? m : 1) * sizeof(double))) == NULL)
                s = pd_fail(PD_ERR_NOMEM, "out of memory reading restart data");
        if (s == PD_OK)
            deinterleave(dst, buf, m);
        free(buf);
    }
    if (s == PD_OK) {
        hid_t g = H5Gopen2(f->fid, group, H5P_DEFAULT);
        s = pd_h5_read_attr_int(g, "contact_builds", &r->contact_builds);
        for (int a = 0; a < NSUMS && s == PD_OK; a++)
            if (pd_h5_has_attr(g, restart_sums[a]))
                s = pd_h5_read_attr_double(g, restart_sums[a], restart_sum(r, a));
        int64_t nlost = 0;
        if (s == PD_OK && pd_h5_has_attr(g, "lost_particles"))
            s = pd_h5_read_attr_int(g, "lost_particles", &nlost);
        if (s == PD_OK && pd_h5_has_attr(g, "damping")) {
            r->has_damping = 1;
            s = pd_h5_read_attr_doubles(g, "damping", r->damping, 2);
        }
        if (s == PD_OK && pd_h5_has_attr(g, "projectile")) {
            r->has_projectile = 1;
            s = pd_h5_read_attr_doubles(g, "projectile", r->projectile, 9);
            /* the projectile's x, v, f go on as the run's state */
            for (int q = 0; q < 9 && s == PD_OK; q++)
                if (!isfinite(r->projectile[q]))
                    s = pd_fail(PD_ERR_FORMAT, "the projectile state holds %g", r->projectile[q]);
        }
        H5Gclose(g);
        if (s != PD_OK)
            s = pd_fail(PD_ERR_FORMAT, "'%s': %s: %s", f->name, group, pd_errmsg());
        if (s == PD_OK && nlost > 0) {
            char path[64];
            snprintf(path, sizeof path, "%s/lost", group);
            pd_h5_form form = {H5T_INTEGER, 1, 1, {(hsize_t)n, 0}};
            r->lost = malloc((size_t)(m > 0 ? m : 1));
            s = r->lost ? pd_h5_read_rows(f->fid, f->name, path, &form, H5T_NATIVE_UINT8,
                                          r->lost, g0, m)
                        : pd_fail(PD_ERR_NOMEM, "out of memory reading restart data");
        }
        char hpath[64];
        snprintf(hpath, sizeof hpath, "%s/bond_history", group);
        if (s == PD_OK && nb >= 0 && pd_h5_has_link(f->fid, hpath))
            s = read_history_rows(f, hpath, k0, nb, r);
        else if (s == PD_OK && pd_h5_has_link(f->fid, hpath)) {
            pd_h5_form form = {H5T_FLOAT, 8, 2, {0, 0}};
            hsize_t dims[8] = {0};
            s = pd_h5_read_data(f->fid, f->name, hpath, &form, H5T_NATIVE_DOUBLE, sizeof(double),
                                (void **)&r->bond_history, dims);
            r->history_bonds = (int64_t)dims[0];
            r->history_width = (int)dims[1];
        }
    }
    if (s != PD_OK)
        pd_restart_free(r);
    return s;
}

/* Restart attribute `name` of `count` zeros in each slot that lacks it. */
static pd_status plan_restart_attr(pd_file *f, const char *name, int count)
{
    double zeros[9] = {0};
    pd_status s = PD_OK;
    for (int k = 0; k < 2 && s == PD_OK; k++) {
        char path[32];
        snprintf(path, sizeof path, "/restart/%d", k);
        if (!pd_h5_has_link(f->fid, path))
            continue; /* a run of one frame has one slot */
        hid_t g = H5Gopen2(f->fid, path, H5P_DEFAULT);
        if (g < 0)
            return pd_fail(PD_ERR_IO, "'%s': cannot open %s", f->name, path);
        if (!pd_h5_has_attr(g, name))
            s = pd_h5_write_attr_doubles(g, name, zeros, count);
        H5Gclose(g);
    }
    return s;
}

pd_status pd_plan_restart_damping(pd_file *f)
{
    return plan_restart_attr(f, "damping", 2);
}

pd_status pd_plan_restart_projectile(pd_file *f)
{
    return plan_restart_attr(f, "projectile", 9);
}

pd_status pd_plan_restart_history(pd_file *f, int64_t nbonds, int width)
{
    hsize_t d2[2] = {(hsize_t)nbonds, (hsize_t)width};
    pd_status s = PD_OK;
    for (int k = 0; k < 2 && s == PD_OK; k++) {
        char path[32];
        snprintf(path, sizeof path, "/restart/%d", k);
        if (!pd_h5_has_link(f->fid, path))
            continue; /* a run of one frame has one slot */
        hid_t g = H5Gopen2(f->fid, path, H5P_DEFAULT);
        if (g < 0)
            return pd_fail(PD_ERR_IO, "'%s': cannot open %s", f->name, path);
        if (!pd_h5_has_link(g, "bond_history"))
            s = pd_h5_reserve_data(g, "bond_history", H5T_IEEE_F64LE, 2, d2);
        H5Gclose(g);
    }
    return s;
}

/* Frames laid out but never completed (by a run that was killed or ended
 * early) go, so that a restart can lay out its own. */
pd_status pd_drop_incomplete_frames(pd_file *f)
{
    if (!pd_h5_has_link(f->fid, "/frames"))
        return PD_OK;
    hid_t g = H5Gopen2(f->fid, "/frames", H5P_DEFAULT);
    H5G_info_t info;
    H5Gget_info(g, &info);
    pd_status s = PD_OK;
    for (hsize_t k = info.nlinks; k-- > 0 && s == PD_OK;) {
        char name[64];
        if (H5Lget_name_by_idx(g, ".", H5_INDEX_NAME, H5_ITER_INC, k, name, sizeof name,
                               H5P_DEFAULT) < 0)
            continue;
        hid_t fg = H5Gopen2(g, name, H5P_DEFAULT);
        int64_t complete = 1;
        if (fg >= 0 && pd_h5_has_attr(fg, "complete"))
            pd_h5_read_attr_int(fg, "complete", &complete);
        if (fg >= 0)
            H5Gclose(fg);
        if (complete != 1 && H5Ldelete(g, name, H5P_DEFAULT) < 0)
            s = pd_fail(PD_ERR_IO, "cannot remove the unfinished frame %s", name);
    }
    H5Gclose(g);
    return s;
}

pd_status pd_read_scene_options(const pd_file *f, char **text)
{
    if (!pd_h5_has_link(f->fid, "/scene"))
        return pd_fail(PD_ERR_FORMAT, "'%s' has no /scene (not made by pd-run?)", f->name);
    hid_t g = H5Gopen2(f->fid, "/scene", H5P_DEFAULT);
    pd_status s = pd_h5_read_attr_string(g, "options", text);
    H5Gclose(g);
    if (s != PD_OK)
        return pd_fail(PD_ERR_FORMAT, "'%s': /scene has no options", f->name);
    return PD_OK;
}
