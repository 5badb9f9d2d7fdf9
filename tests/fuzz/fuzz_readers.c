/*
 * fuzz_readers -- a libFuzzer target for the pd-h5 readers of libpd.
 *
 * Fuzzing raw HDF5 bytes would mostly exercise HDF5's own parser; what pd
 * must get right is what it does with a well-formed HDF5 file whose
 * contents are wrong.  So the input is a recipe of edits to a small valid
 * run file (a 4x4x4 block with bonds, a pre-crack, two /sets, one frame with
 * stress, von Mises and projectile attributes, a restart slot with the
 * projectile's state, a plate thickness): each edit picks a dataset or
 * attribute and overwrites an element with raw bytes (NaN, Inf, huge,
 * negative), truncates, extends or multiplies it, changes its type or rank,
 * swaps two elements (unsorted sets), drops it, or turns the body into a
 * plate (dimension 2, with or without z = 0).  The edited file is built in
 * memory and handed to every reader (particles, bonds, sets, frames, stress,
 * von Mises, damage, restart data, history); the bytes past the edits are a
 * scene text for pd_scene_args_text.  A reader may
 * refuse the file -- that is the point -- but must never crash, hang or
 * read out of bounds (AddressSanitizer and UndefinedBehaviorSanitizer
 * watch).
 *
 * Build and run: make fuzz [FUZZ_SECONDS=60]  (clang with libFuzzer).
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <hdf5.h>

#include "pd.h"

enum { T_F64, T_F32, T_I64, T_I32, T_U8, T_COUNT };

static const size_t type_size[T_COUNT] = {8, 4, 8, 4, 1};

typedef struct {
    const char *path; /* dataset path, or "group@attribute" */
    int type;
    int rank;
    hsize_t dims[3];
    unsigned char *data;
    int present;
} field;

#define MAX_FIELDS 48
static field base[MAX_FIELDS];
static int nbase;

static double get(const field *f, size_t k)
{
    const unsigned char *p = f->data + k * type_size[f->type];
    switch (f->type) {
    case T_F64: { double v; memcpy(&v, p, 8); return v; }
    case T_F32: { float v; memcpy(&v, p, 4); return v; }
    case T_I64: { int64_t v; memcpy(&v, p, 8); return (double)v; }
    case T_I32: { int32_t v; memcpy(&v, p, 4); return v; }
    default: return *p;
    }
}

static void put(field *f, size_t k, double v)
{
    unsigned char *p = f->data + k * type_size[f->type];
    switch (f->type) {
    case T_F64: memcpy(p, &v, 8); break;
    case T_F32: { float x = (float)v; memcpy(p, &x, 4); break; }
    case T_I64: { int64_t x = (v > -9e18 && v < 9e18) ? (int64_t)v : 0; memcpy(p, &x, 8); break; }
    case T_I32: { int32_t x = (v > -2e9 && v < 2e9) ? (int32_t)v : 0; memcpy(p, &x, 4); break; }
    default: *p = (unsigned char)(v >= 0 && v < 256 ? v : 0);
    }
}

static size_t count(const field *f)
{
    size_t m = 1;
    for (int k = 0; k < f->rank; k++)
        m *= f->dims[k];
    return m;
}

static void add3(const char *path, int type, int rank, hsize_t d0, hsize_t d1, hsize_t d2,
                 const void *src)
{
    field *f = &base[nbase++];
    f->path = path;
    f->type = type;
    f->rank = rank;
    f->dims[0] = d0;
    f->dims[1] = d1;
    f->dims[2] = d2;
    f->present = 1;
    size_t bytes = count(f) * type_size[type];
    f->data = malloc(bytes ? bytes : 1);
    memcpy(f->data, src, bytes);
}

static void add(const char *path, int type, int rank, hsize_t d0, hsize_t d1, const void *src)
{
    add3(path, type, rank, d0, d1, 0, src);
}

static field *find(field *w, int nw, const char *path)
{
    for (int k = 0; k < nw; k++)
        if (strcmp(w[k].path, path) == 0)
            return &w[k];
    return NULL;
}

static int cmp_i64(const void *a, const void *b)
{
    int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
    return (x > y) - (x < y);
}

/* The valid run file the edits start from. */
static void build_base(void)
{
    pd_region box;
    pd_region_parse(PD_REGION_BOX, "0,3,0,3,0,3", &box);
    pd_lattice_params lp = {1.0, 1000.0, 1, 0.0, 1};
    pd_particles *p;
    pd_bonds *b;
    pd_crack crack = {{1.5, -1, -1}, {0, 5, 0}, {0, 0, 5}, 0};
    if (pd_lattice_make(&box, 1, &lp, &p) != PD_OK || pd_bonds_build(p, 2.0001, &b) != PD_OK ||
        pd_bonds_precrack(p, b, &crack, 1, NULL) != PD_OK || b->precrack == NULL)
        abort();
    size_t n = (size_t)p->n, nb = (size_t)b->count, ns = (nb + 7) / 8;
    double *pos = malloc(n * 3 * sizeof(double)), *vel = malloc(n * 3 * sizeof(double));
    unsigned char *bits = malloc(ns), *pre = malloc(ns);
    for (size_t i = 0; i < n; i++)
        for (int d = 0; d < 3; d++) {
            pos[3 * i + d] = p->x[d][i];
            vel[3 * i + d] = 0.1 * (double)d;
        }
    for (size_t k = 0; k < ns; k++) {
        bits[k] = (unsigned char)(b->intact[k / 8] >> (8 * (k % 8)));
        pre[k] = (unsigned char)(b->precrack[k / 8] >> (8 * (k % 8)));
    }
    double spacing = 1.0, horizon = 2.0001, t = 0.5;
    int64_t version = PD_FORMAT_VERSION, dim = 3, step = 7, one = 1;
    add("/particles/position", T_F64, 2, n, 3, pos);
    add("/particles/volume", T_F64, 1, n, 0, p->volume);
    add("/particles/density", T_F64, 1, n, 0, p->density);
    add("/particles/radius", T_F64, 1, n, 0, p->radius);
    add("/particles/material", T_I32, 1, n, 0, p->material);
    add("/particles/id", T_I64, 1, n, 0, p->id);
    add("/bonds/offset", T_I64, 1, n + 1, 0, b->offset);
    add("/bonds/neighbor", T_I32, 1, nb, 0, b->neighbor);
    add("/bonds/length", T_F64, 1, nb, 0, b->length);
    add("/bonds/volume_factor", T_F64, 1, nb, 0, b->vfactor);
    add("/bonds/state", T_U8, 1, ns, 0, bits);
    add("/bonds/precrack", T_U8, 1, ns, 0, pre);
    add("/frames/00000007/displacement", T_F64, 2, n, 3, vel);
    add("/frames/00000007/velocity", T_F64, 2, n, 3, vel);
    add("/frames/00000007/state", T_U8, 1, ns, 0, bits);
    add("/frames/00000007/damage", T_F64, 1, n, 0, p->volume);
    add("/restart/0/position", T_F64, 2, n, 3, pos);
    add("/restart/0/force", T_F64, 2, n, 3, vel);
    add("/restart/0/s0", T_F64, 1, n, 0, p->volume);
    add("/restart/0/contact_position", T_F64, 2, n, 3, pos);
    /* the parts added with pd issues 3 and 4: sets, stress, projectile, plate */
    int64_t left[16], right[4];
    for (int k = 0; k < 16; k++)
        left[k] = p->id[k];
    for (int k = 0; k < 4; k++)
        right[k] = p->id[n - 4 + (size_t)k];
    qsort(left, 16, sizeof left[0], cmp_i64);
    qsort(right, 4, sizeof right[0], cmp_i64);
    double *stress = malloc(n * 9 * sizeof(double)), proj[9], ppos[3] = {1.5, 1.5, 5},
           pvel[3] = {0, 0, -10}, penergy = 2.5, thickness = 0.25;
    for (size_t k = 0; k < 9 * n; k++)
        stress[k] = (double)(k % 9) - 4.0;
    for (int k = 0; k < 9; k++)
        proj[k] = k < 3 ? ppos[k] : k < 6 ? pvel[k - 3] : 0.0;
    add("/sets/left", T_I64, 1, 16, 0, left);
    add("/sets/right", T_I64, 1, 4, 0, right);
    add3("/frames/00000007/stress", T_F64, 3, n, 3, 3, stress);
    add("/frames/00000007/von_mises", T_F64, 1, n, 0, p->density);
    add("/frames/00000007@projectile_position", T_F64, 1, 3, 0, ppos);
    add("/frames/00000007@projectile_velocity", T_F64, 1, 3, 0, pvel);
    add("/frames/00000007@projectile_energy", T_F64, 1, 1, 0, &penergy);
    add("/restart/0@projectile", T_F64, 1, 9, 0, proj);
    add("/particles@thickness", T_F64, 1, 1, 0, &thickness);
    free(stress);
    add("/@pd_format_version", T_I64, 1, 1, 0, &version);
    add("/particles@spacing", T_F64, 1, 1, 0, &spacing);
    add("/particles@dimension", T_I64, 1, 1, 0, &dim);
    add("/bonds@horizon", T_F64, 1, 1, 0, &horizon);
    add("/frames/00000007@step", T_I64, 1, 1, 0, &step);
    add("/frames/00000007@time", T_F64, 1, 1, 0, &t);
    add("/restart/0@step", T_I64, 1, 1, 0, &step);
    add("/restart/0@complete", T_I64, 1, 1, 0, &one);
    add("/restart/0@contact_builds", T_I64, 1, 1, 0, &one);
    free(pos);
    free(vel);
    free(bits);
    free(pre);
    pd_bonds_free(b);
    pd_particles_free(p);
}

static hid_t h5type(int t)
{
    static const hid_t *types[T_COUNT] = {&H5T_NATIVE_DOUBLE_g, &H5T_NATIVE_FLOAT_g,
                                          &H5T_NATIVE_INT64_g, &H5T_NATIVE_INT32_g,
                                          &H5T_NATIVE_UCHAR_g};
    return *types[t];
}

/* Apply one 12-byte edit to the working copy. */
static void edit(field *w, int nw, const uint8_t *op)
{
    field *f = &w[op[0] % nw];
    uint32_t index;
    memcpy(&index, op + 2, 4);
    size_t m = count(f);
    switch (op[1] % 8) {
    case 0: /* overwrite an element with raw bytes (NaN, Inf, huge, negative) */
        if (m > 0) {
            size_t es = type_size[f->type], k = index % m;
            unsigned char raw[8] = {0};
            memcpy(raw, op + 6, 6);
            raw[6] = op[6] ^ op[7];
            raw[7] = op[7] | (op[11] & 0xf0);
            memcpy(f->data + k * es, raw + (8 - es), es);
        }
        break;
    case 1: { /* resize the first dimension; a high bit: multiply it (a huge set) */
        size_t old = count(f), es = type_size[f->type];
        hsize_t d0 = index % (f->dims[0] + 3);
        if ((op[7] & 0x80) && old * (1 + index % 16) <= (1u << 16)) /* at most 64 Ki elements */
            d0 = f->dims[0] * (1 + index % 16);
        f->dims[0] = d0;
        size_t now = count(f);
        unsigned char *nd = calloc(now ? now : 1, es);
        memcpy(nd, f->data, (now < old ? now : old) * es);
        free(f->data);
        f->data = nd;
        break;
    }
    case 2: { /* change the type, keeping the values where they fit */
        int t = op[6] % T_COUNT;
        size_t m2 = count(f);
        unsigned char *nd = calloc(m2 ? m2 : 1, type_size[t]);
        field g = *f;
        g.type = t;
        g.data = nd;
        for (size_t k = 0; k < m2; k++)
            put(&g, k, get(f, k));
        free(f->data);
        *f = g;
        break;
    }
    case 3: /* drop it */
        f->present = 0;
        break;
    case 4: /* change the rank (same elements) */
        if (f->rank == 3) {
            f->dims[1] *= f->dims[2];
            f->rank = 2;
        } else if (f->rank == 2 && f->dims[1] > 3 && f->dims[1] % 3 == 0 && (op[6] & 1)) {
            f->dims[2] = 3;
            f->dims[1] /= 3;
            f->rank = 3;
        } else if (f->rank == 2) {
            f->dims[0] *= f->dims[1];
            f->rank = 1;
        } else if (f->dims[0] % 3 == 0) {
            f->dims[0] /= 3;
            f->dims[1] = 3;
            f->rank = 2;
        } else if (f->dims[0] % 2 == 0) {
            f->dims[0] /= 2;
            f->dims[1] = 2;
            f->rank = 2;
        }
        break;
    case 6: { /* a plate: dimension 2, and (op[6] odd) every z set to 0 */
        field *dim = find(w, nw, "/particles@dimension"), *pos = find(w, nw, "/particles/position");
        if (dim && count(dim) > 0)
            put(dim, 0, 2.0);
        if (pos && (op[6] & 1) && pos->rank == 2 && pos->dims[1] == 3)
            for (size_t i = 0; i < pos->dims[0]; i++)
                put(pos, 3 * i + 2, 0.0);
        break;
    }
    case 7: /* swap two elements (ids out of order, offsets that decrease) */
        if (m > 1) {
            size_t es = type_size[f->type], a = index % m, c = (index / 7 + op[6]) % m;
            unsigned char t[8];
            memcpy(t, f->data + a * es, es);
            memcpy(f->data + a * es, f->data + c * es, es);
            memcpy(f->data + c * es, t, es);
        }
        break;
    default: /* a typed value: index-th element set to a small signed number */
        if (m > 0)
            put(f, index % m, (double)(int16_t)(op[6] | op[7] << 8) * 0.5);
    }
}

static void write_field(hid_t fid, const field *f)
{
    char path[128];
    snprintf(path, sizeof path, "%s", f->path);
    char *at = strchr(path, '@');
    hsize_t dims[3] = {f->dims[0], f->dims[1], f->dims[2]};
    hid_t sp = (at && count(f) == 1) ? H5Screate(H5S_SCALAR) : H5Screate_simple(f->rank, dims, NULL);
    if (at) {
        *at = '\0';
        hid_t loc = H5Oopen(fid, path, H5P_DEFAULT);
        if (loc >= 0) {
            hid_t a = H5Acreate2(loc, at + 1, h5type(f->type), sp, H5P_DEFAULT, H5P_DEFAULT);
            if (a >= 0) {
                H5Awrite(a, h5type(f->type), f->data);
                H5Aclose(a);
            }
            H5Oclose(loc);
        }
    } else {
        hid_t lcpl = H5Pcreate(H5P_LINK_CREATE);
        H5Pset_create_intermediate_group(lcpl, 1);
        hid_t d = H5Dcreate2(fid, path, h5type(f->type), sp, lcpl, H5P_DEFAULT, H5P_DEFAULT);
        if (d >= 0) {
            if (count(f) > 0)
                H5Dwrite(d, h5type(f->type), H5S_ALL, H5S_ALL, H5P_DEFAULT, f->data);
            H5Dclose(d);
        }
        H5Pclose(lcpl);
    }
    H5Sclose(sp);
}

/* The edited file as an HDF5 image; *len its size. */
static void *image_of(const field *w, int nw, size_t *len)
{
    hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
    H5Pset_fapl_core(fapl, 1 << 16, 0);
    hid_t fid = H5Fcreate("fuzz", H5F_ACC_TRUNC, H5P_DEFAULT, fapl);
    H5Pclose(fapl);
    hid_t t = H5Tcopy(H5T_C_S1);
    H5Tset_size(t, H5T_VARIABLE);
    hid_t sp = H5Screate(H5S_SCALAR);
    const char *fmt = PD_FORMAT;
    hid_t a = H5Acreate2(fid, "pd_format", t, sp, H5P_DEFAULT, H5P_DEFAULT);
    H5Awrite(a, t, &fmt);
    H5Aclose(a);
    H5Sclose(sp);
    H5Tclose(t);
    for (int pass = 0; pass < 2; pass++) /* datasets (and groups) first, then attributes */
        for (int k = 0; k < nw; k++)
            if (w[k].present && (strchr(w[k].path, '@') != NULL) == pass)
                write_field(fid, &w[k]);
    H5Fflush(fid, H5F_SCOPE_GLOBAL);
    ssize_t size = H5Fget_file_image(fid, NULL, 0);
    void *img = size > 0 ? malloc((size_t)size) : NULL;
    if (img)
        H5Fget_file_image(fid, img, (size_t)size);
    H5Fclose(fid);
    *len = size > 0 ? (size_t)size : 0;
    return img;
}

/* A refusal is one printable line; a format error names the file, once (a
 * message wrapped in another must not have been overwritten by it). */
static pd_status checked(pd_status st)
{
    if (st == PD_OK)
        return st;
    const char *m = pd_errmsg();
    const char *name = strstr(m, "fuzz.h5");
    int bad = m[0] == '\0' || strlen(m) >= 511 || (st == PD_ERR_FORMAT && !name) ||
              (name && strstr(name + 1, "fuzz.h5"));
    for (const char *c = m; *c && !bad; c++)
        bad = (unsigned char)*c < 0x20 || *c == 0x7f;
    if (bad) {
        fprintf(stderr, "fuzz_readers: a bad error message: \"%s\"\n", m);
        abort();
    }
    return st;
}
#define pd_read_history(...) checked(pd_read_history(__VA_ARGS__))
#define pd_read_particles(...) checked(pd_read_particles(__VA_ARGS__))
#define pd_read_bonds(...) checked(pd_read_bonds(__VA_ARGS__))
#define pd_read_sets(...) checked(pd_read_sets(__VA_ARGS__))
#define pd_list_frames(...) checked(pd_list_frames(__VA_ARGS__))
#define pd_read_frame_info(...) checked(pd_read_frame_info(__VA_ARGS__))
#define pd_read_frame_vectors(...) checked(pd_read_frame_vectors(__VA_ARGS__))
#define pd_read_frame_stress(...) checked(pd_read_frame_stress(__VA_ARGS__))
#define pd_read_frame_scalar(...) checked(pd_read_frame_scalar(__VA_ARGS__))
#define pd_read_frame_damage(...) checked(pd_read_frame_damage(__VA_ARGS__))
#define pd_read_frame_damage_run(...) checked(pd_read_frame_damage_run(__VA_ARGS__))
#define pd_read_restart(...) checked(pd_read_restart(__VA_ARGS__))

/* Every reader on the file; errors are expected, crashes are not. */
static void read_all(const void *img, size_t len)
{
    pd_file *f = NULL;
    if (pd_file_open_memory(img, len, "fuzz.h5", &f) != PD_OK)
        return;
    char *hist = NULL;
    if (pd_read_history(f, &hist) == PD_OK)
        free(hist);
    pd_particles *p = NULL;
    pd_bonds *b = NULL;
    uint64_t *intact = NULL;
    if (pd_read_particles(f, &p) == PD_OK) {
        pd_sets *sets = NULL;
        if (pd_read_sets(f, p, &sets) == PD_OK) {
            /* a set read is a set whose every id is a particle's */
            for (int k = 0; k < sets->count; k++) {
                int64_t *rows = NULL;
                if (pd_set_rows(&sets->set[k], p, &rows) != PD_OK ||
                    pd_sets_find(sets, sets->set[k].name) == NULL)
                    abort();
                for (int64_t q = 0; q < sets->set[k].n; q++)
                    if (rows[q] < 0 || rows[q] >= p->n || p->id[rows[q]] != sets->set[k].id[q])
                        abort();
                free(rows);
            }
            pd_sets_free(sets);
        }
        int64_t nf = 0;
        char **names = NULL;
        if (pd_read_bonds(f, p, &b) == PD_OK) {
            double *dmg = malloc((size_t)p->n * sizeof(double));
            pd_damage(p, b, b->intact, dmg);
            pd_damage_no_precrack(p, b, b->intact, dmg);
            free(dmg);
            pd_bonds_free(b);
            b = NULL;
        }
        if (pd_list_frames(f, &nf, &names) == PD_OK) {
            double *d[3], *v[3], *dmg = malloc((size_t)p->n * sizeof(double)),
                   *stress = malloc((size_t)p->n * 9 * sizeof(double));
            for (int k = 0; k < 3; k++) {
                d[k] = malloc((size_t)p->n * sizeof(double));
                v[k] = malloc((size_t)p->n * sizeof(double));
            }
            for (int64_t k = 0; k < nf; k++) {
                pd_frame_info fi = {0, 0, 0, 0};
                pd_read_frame_info(f, names[k], &fi);
                pd_read_frame_vectors(f, names[k], p->n, d, v);
                int present = 0;
                pd_read_frame_stress(f, names[k], p->n, stress, &present);
                pd_read_frame_scalar(f, names[k], "von_mises", p->n, dmg, &present);
                pd_read_frame_damage(f, p, names[k], &b, &intact, dmg);
                int has_run = 0;
                pd_read_frame_damage_run(f, p, names[k], &b, &intact, dmg, &has_run);
                pd_restart r;
                if (pd_read_restart(f, p->n, fi.step, &r) == PD_OK)
                    pd_restart_free(&r);
            }
            for (int k = 0; k < 3; k++) {
                free(d[k]);
                free(v[k]);
            }
            free(dmg);
            free(stress);
            pd_frames_free_list(nf, names);
        }
    }
    free(intact);
    pd_bonds_free(b);
    pd_particles_free(p);
    pd_file_close(f);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (nbase == 0) {
        pd_h5_debug(0);
        build_base();
    }
    field w[MAX_FIELDS];
    for (int k = 0; k < nbase; k++) {
        w[k] = base[k];
        size_t bytes = count(&base[k]) * type_size[base[k].type];
        w[k].data = malloc(bytes ? bytes : 1);
        memcpy(w[k].data, base[k].data, bytes);
    }
    size_t at = 0;
    for (; at + 12 <= size && at < 12 * 16; at += 12)
        edit(w, nbase, data + at);
    if (at < size) { /* the rest: a scene text (/scene options) */
        char *text = malloc(size - at + 1);
        memcpy(text, data + at, size - at);
        text[size - at] = '\0';
        int argc = 0;
        char **argv = NULL;
        if (pd_scene_args_text(text, "fuzz.h5", &argc, &argv, NULL) == PD_OK) {
            for (int k = 0; k < argc; k++)
                free(argv[k]);
            free(argv);
        }
        free(text);
    }
    size_t len = 0;
    void *img = image_of(w, nbase, &len);
    if (img)
        read_all(img, len);
    free(img);
    for (int k = 0; k < nbase; k++)
        free(w[k].data);
    return 0;
}
