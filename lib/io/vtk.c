/*
 * vtk.c -- frames as VTK XML files for ParaView.
 *
 * A frame is one UnstructuredGrid (.vtu): N points at the current positions
 * y = x + u, one vertex cell (VTK type 1) per particle (connectivity 0..N-1,
 * offsets 1..N), and point data displacement, velocity (3 components),
 * damage, damage_run (damage without the pre-crack, when given), material,
 * id, front (when given).  A subset of the particles (`select`, e.g. the
 * damaged zone of a crack path) gives a grid of only those points.  Data
 * are binary and appended (encoding "raw"), little-endian whatever the
 * host.  Uncompressed (zlib level 0), each array is a UInt64 byte count
 * followed by its values, so the XML header can state every array's offset
 * before any byte is written.  Compressed (levels 1-9, the attribute
 * compressor="vtkZLibDataCompressor"), each array is VTK's compressed block:
 * a header of UInt64 sizes and the array's bytes in 64 KiB pieces, each
 * compressed alone by zlib; all are compressed before the header is
 * written, since their offsets depend on their sizes.
 *
 * A rigid sphere (the indenter, the projectile) is a grid of triangles on
 * its surface.  A time series is a ParaView collection (.pvd) that names
 * each .vtu with its time and its part: ParaView shows the parts of one
 * time together, as the blocks of one dataset.
 *
 * Both writers go to a temporary file beside the target and rename it over
 * the target only when it is complete and synced, so a reader never sees a
 * half-written file under the final name.
 */
#include <errno.h>
#include <fcntl.h>
#include <libgen.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include "io/pending.h"
#include "pd.h"

#define VTK_VERTEX 1          /* VTK cell type of a single point         */
#define VTK_TRIANGLE 5        /* VTK cell type of a triangle             */
#define OUT_BUFFER (1 << 16)  /* bytes gathered before each fwrite        */
#define ZBLOCK (1u << 16)     /* bytes of each block zlib compresses     */

/* ------------------------------------------------------------ binary data */

/* Where the values of one appended array come from. */
typedef enum {
    SRC_SOA,      /* double, 3 components from soa[0..2][i] */
    SRC_F64,      /* double, f64[i]                          */
    SRC_AOS,      /* double, ncomp interleaved: f64[ncomp i + c] */
    SRC_I32,      /* int32, i32[i]                           */
    SRC_I64,      /* int64, i64[i]                           */
    SRC_SEQUENCE, /* int64, start + i stride                 */
    SRC_CONSTANT, /* uint8, the value `start`                */
    SRC_U8        /* uint8, u8[i]                            */
} source;

typedef struct {
    const char *name;
    const char *type;  /* VTK type name                      */
    int ncomp;         /* components per tuple               */
    int width;         /* bytes per value                    */
    source src;
    double *const *soa;
    const double *f64;
    const int32_t *i32;
    const int64_t *i64;
    const uint8_t *u8;
    const int64_t *select; /* row of tuple i: select[i] (NULL: i) */
    int64_t start, stride;
    int64_t count;     /* tuples                             */
    uint64_t offset;   /* byte offset in the appended block  */
    unsigned char *z;  /* compressed: its whole block (header and data) */
    uint64_t zbytes;
} varray;

/* Bytes of the values of one array. */
static uint64_t value_bytes(const varray *a)
{
    return (uint64_t)a->count * (uint64_t)a->ncomp * (uint64_t)a->width;
}

/* Bytes of one array in the appended block: a UInt64 count and the values,
 * or its compressed block. */
static uint64_t block_size(const varray *a)
{
    return a->z ? a->zbytes : 8 + value_bytes(a);
}

/* Value c of tuple i as raw bits (doubles by their IEEE 754 image). */
static uint64_t value_bits(const varray *a, int64_t i, int c)
{
    uint64_t bits = 0;
    double v;
    int64_t row = a->select ? a->select[i] : i;
    switch (a->src) {
    case SRC_SOA:
        v = a->soa[c][row];
        memcpy(&bits, &v, sizeof bits);
        break;
    case SRC_F64:
        v = a->f64[row];
        memcpy(&bits, &v, sizeof bits);
        break;
    case SRC_AOS:
        v = a->f64[(int64_t)a->ncomp * row + c];
        memcpy(&bits, &v, sizeof bits);
        break;
    case SRC_I32:
        bits = (uint32_t)a->i32[row];
        break;
    case SRC_I64:
        bits = (uint64_t)a->i64[row];
        break;
    case SRC_SEQUENCE:
        bits = (uint64_t)(a->start + i * a->stride);
        break;
    case SRC_CONSTANT:
        bits = (uint64_t)a->start;
        break;
    case SRC_U8:
        bits = a->u8[row];
        break;
    }
    return bits;
}

/* The low `width` bytes of bits, little-endian, at out; returns the end. */
static unsigned char *le_bytes(unsigned char *out, uint64_t bits, int width)
{
    for (int k = 0; k < width; k++)
        *out++ = (unsigned char)(bits >> (8 * k));
    return out;
}

/* The little-endian bytes of tuple i of an array at out. */
static void put_tuple(const varray *a, int64_t i, unsigned char *out)
{
    for (int c = 0; c < a->ncomp; c++)
        out = le_bytes(out, value_bits(a, i, c), a->width);
}

/* Little-endian bytes gathered in a buffer and written in large pieces. */
typedef struct {
    FILE *fp;
    size_t len;
    int failed;
    unsigned char buf[OUT_BUFFER];
} le_writer;

static void le_flush(le_writer *w)
{
    if (w->len && !w->failed && fwrite(w->buf, 1, w->len, w->fp) != w->len)
        w->failed = 1;
    w->len = 0;
}

static void le_put(le_writer *w, uint64_t bits, int width)
{
    if (w->len + (size_t)width > sizeof w->buf)
        le_flush(w);
    le_bytes(w->buf + w->len, bits, width);
    w->len += (size_t)width;
}

static void write_block(le_writer *w, const varray *a)
{
    if (a->z) {
        le_flush(w);
        if (!w->failed && fwrite(a->z, 1, a->zbytes, w->fp) != a->zbytes)
            w->failed = 1;
        return;
    }
    le_put(w, value_bytes(a), 8);
    for (int64_t i = 0; i < a->count; i++)
        for (int c = 0; c < a->ncomp; c++)
            le_put(w, value_bits(a, i, c), a->width);
}

/* ------------------------------------------------------------ compression */

/* Compress an array as VTK's vtkZLibDataCompressor does: its bytes cut in
 * ZBLOCK-byte blocks, each compressed alone (zlib compress2 at `level`),
 * after a header of UInt64s: the number of blocks, the block size, the
 * size of a partial last block (0 when the last is full) and the
 * compressed size of every block.  Blocks are compressed in parallel; each
 * depends on its own bytes only, so the file does not depend on the thread
 * count.  Fills a->z and a->zbytes. */
static pd_status compress_array(varray *a, int level)
{
    const uint64_t nbytes = value_bytes(a);
    const int64_t tuple = (int64_t)a->ncomp * a->width;
    const int64_t nblocks = (int64_t)((nbytes + ZBLOCK - 1) / ZBLOCK);
    const uLong bound = compressBound(ZBLOCK);
    unsigned char *raw = malloc(nbytes ? nbytes : 1);
    unsigned char *packed = malloc(nblocks ? (size_t)nblocks * bound : 1);
    uint64_t *zlen = malloc((size_t)(nblocks ? nblocks : 1) * sizeof *zlen);
    if (raw == NULL || packed == NULL || zlen == NULL) {
        free(raw);
        free(packed);
        free(zlen);
        return pd_fail(PD_ERR_NOMEM, "out of memory compressing '%s'", a->name);
    }
    /* each tuple's bytes at its own place, then each block on its own */
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < a->count; i++)
        put_tuple(a, i, raw + (uint64_t)i * (uint64_t)tuple);
    int failed = 0;
#pragma omp parallel for schedule(dynamic, 1) reduction(| : failed)
    for (int64_t k = 0; k < nblocks; k++) {
        const uint64_t lo = (uint64_t)k * ZBLOCK;
        const uint64_t len = nbytes - lo < ZBLOCK ? nbytes - lo : ZBLOCK;
        uLongf out = bound;
        if (compress2(packed + (size_t)k * bound, &out, raw + lo, (uLong)len, level) != Z_OK)
            failed = 1;
        zlen[k] = out;
    }
    free(raw);
    uint64_t total = 8 * (3 + (uint64_t)nblocks);
    for (int64_t k = 0; k < nblocks; k++)
        total += zlen[k];
    unsigned char *z = failed ? NULL : malloc(total);
    if (z == NULL) {
        free(packed);
        free(zlen);
        return failed ? pd_fail(PD_ERR_IO, "zlib cannot compress '%s'", a->name)
                      : pd_fail(PD_ERR_NOMEM, "out of memory compressing '%s'", a->name);
    }
    uint64_t header[3] = {(uint64_t)nblocks, ZBLOCK, nbytes % ZBLOCK};
    unsigned char *at = z;
    for (int64_t h = 0; h < 3 + nblocks; h++)
        at = le_bytes(at, h < 3 ? header[h] : zlen[h - 3], 8);
    for (int64_t k = 0; k < nblocks; k++) {
        memcpy(at, packed + (size_t)k * bound, zlen[k]);
        at += zlen[k];
    }
    free(packed);
    free(zlen);
    a->z = z;
    a->zbytes = total;
    return PD_OK;
}

/* ------------------------------------------------------------ .vtu */

static void xml_array(FILE *fp, const varray *a)
{
    fprintf(fp, "        <DataArray type=\"%s\" Name=\"%s\"", a->type, a->name);
    if (a->ncomp > 1)
        fprintf(fp, " NumberOfComponents=\"%d\"", a->ncomp);
    fprintf(fp, " format=\"appended\" offset=\"%llu\"/>\n", (unsigned long long)a->offset);
}

/* The cells of a grid and the names ParaView shows first. */
typedef struct {
    int64_t npoints, ncells;
    const char *scalars, *vectors; /* PointData attributes; NULL: none */
    int level;                     /* zlib level 1-9; 0: raw          */
} grid_shape;

/* One UnstructuredGrid of arrays a[0..na): point data a[0..npoint), the
 * points a[npoint], then connectivity, offsets and types of the cells.
 * The order of the XML is that of the appended block. */
static pd_status write_grid(const char *path, varray *a, int na, int npoint, const grid_shape *g)
{
    if (g->level < 0 || g->level > 9)
        return pd_fail(PD_ERR_INVALID, "zlib level %d; levels are 0 (none) to 9", g->level);
    pd_status s = PD_OK;
    for (int k = 0; k < na; k++)
        a[k].z = NULL;
    for (int k = 0; k < na && s == PD_OK && g->level > 0; k++)
        s = compress_array(&a[k], g->level);
    uint64_t offset = 0;
    for (int k = 0; k < na; k++) {
        a[k].offset = offset;
        offset += block_size(&a[k]);
    }
    pd_pending out = {0};
    le_writer *w = NULL;
    if (s == PD_OK)
        s = pd_pending_open(path, &out);
    if (s == PD_OK && (w = malloc(sizeof *w)) == NULL)
        s = pd_fail(PD_ERR_NOMEM, "out of memory");
    if (s == PD_OK) {
        FILE *fp = out.fp;
        fprintf(fp, "<?xml version=\"1.0\"?>\n"
                    "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\""
                    " byte_order=\"LittleEndian\" header_type=\"UInt64\"%s>\n"
                    "  <UnstructuredGrid>\n"
                    "    <Piece NumberOfPoints=\"%lld\" NumberOfCells=\"%lld\">\n",
                g->level > 0 ? " compressor=\"vtkZLibDataCompressor\"" : "",
                (long long)g->npoints, (long long)g->ncells);
        fprintf(fp, "      <PointData");
        if (g->scalars)
            fprintf(fp, " Scalars=\"%s\"", g->scalars);
        if (g->vectors)
            fprintf(fp, " Vectors=\"%s\"", g->vectors);
        fprintf(fp, ">\n");
        for (int k = 0; k < npoint; k++)
            xml_array(fp, &a[k]);
        fprintf(fp, "      </PointData>\n      <Points>\n");
        xml_array(fp, &a[npoint]);
        fprintf(fp, "      </Points>\n      <Cells>\n");
        for (int k = npoint + 1; k < na; k++)
            xml_array(fp, &a[k]);
        fprintf(fp, "      </Cells>\n"
                    "    </Piece>\n"
                    "  </UnstructuredGrid>\n"
                    "  <AppendedData encoding=\"raw\">\n"
                    "   _");
        w->fp = fp;
        w->len = 0;
        w->failed = 0;
        for (int k = 0; k < na; k++)
            write_block(w, &a[k]);
        le_flush(w);
        if (w->failed)
            s = pd_fail(PD_ERR_IO, "cannot write '%s': %s", path, strerror(errno));
        fprintf(fp, "\n  </AppendedData>\n</VTKFile>\n");
    }
    free(w);
    for (int k = 0; k < na; k++)
        free(a[k].z);
    return pd_pending_close(&out, s);
}

pd_status pd_vtk_write(const char *path, const pd_vtk_frame *fr)
{
    if (fr == NULL || fr->position == NULL)
        return pd_fail(PD_ERR_INVALID, "VTK frame without positions");
    int64_t n = fr->n;
    if (n < 0 || n > INT64_MAX / 64)
        return pd_fail(PD_ERR_INVALID, "VTK frame with %lld points", (long long)n);
    if (fr->select) {
        if (fr->nselect < 0 || fr->nselect > n)
            return pd_fail(PD_ERR_INVALID, "VTK frame with %lld of %lld points selected",
                           (long long)fr->nselect, (long long)n);
        for (int64_t k = 0; k < fr->nselect; k++)
            if (fr->select[k] < 0 || fr->select[k] >= n)
                return pd_fail(PD_ERR_INVALID, "VTK frame selects row %lld of %lld",
                               (long long)fr->select[k], (long long)n);
        n = fr->nselect;
    }

    /* Point data first, then Points, then Cells: one vertex per point. */
    if (fr->nextra < 0 || fr->nextra > 64 || (fr->nextra > 0 && fr->extra == NULL))
        return pd_fail(PD_ERR_INVALID, "VTK frame with %d extra fields", fr->nextra);
    for (int k = 0; k < fr->nextra; k++)
        if (fr->extra[k].name == NULL || fr->extra[k].values == NULL ||
            fr->extra[k].ncomp < 1 || fr->extra[k].ncomp > 9)
            return pd_fail(PD_ERR_INVALID, "VTK frame field %d is incomplete", k);
    varray a[11 + 64];
    int na = 0;
    if (fr->displacement)
        a[na++] = (varray){"displacement", "Float64", 3, 8, SRC_SOA, .soa = fr->displacement};
    if (fr->velocity)
        a[na++] = (varray){"velocity", "Float64", 3, 8, SRC_SOA, .soa = fr->velocity};
    if (fr->damage)
        a[na++] = (varray){"damage", "Float64", 1, 8, SRC_F64, .f64 = fr->damage};
    if (fr->damage_run)
        a[na++] = (varray){"damage_run", "Float64", 1, 8, SRC_F64, .f64 = fr->damage_run};
    if (fr->material)
        a[na++] = (varray){"material", "Int32", 1, 4, SRC_I32, .i32 = fr->material};
    if (fr->id)
        a[na++] = (varray){"id", "Int64", 1, 8, SRC_I64, .i64 = fr->id};
    if (fr->front)
        a[na++] = (varray){"front", "UInt8", 1, 1, SRC_U8, .u8 = fr->front};
    for (int k = 0; k < fr->nextra; k++)
        a[na++] = (varray){fr->extra[k].name, "Float64", fr->extra[k].ncomp, 8, SRC_AOS,
                           .f64 = fr->extra[k].values};
    a[na++] = (varray){"Points", "Float64", 3, 8, SRC_SOA, .soa = fr->position};
    const int npoint = na - 1;
    for (int k = 0; k < na; k++)
        a[k].select = fr->select;
    a[na++] = (varray){"connectivity", "Int64", 1, 8, SRC_SEQUENCE, .start = 0, .stride = 1};
    a[na++] = (varray){"offsets", "Int64", 1, 8, SRC_SEQUENCE, .start = 1, .stride = 1};
    a[na++] = (varray){"types", "UInt8", 1, 1, SRC_CONSTANT, .start = VTK_VERTEX};
    for (int k = 0; k < na; k++)
        a[k].count = n;
    grid_shape g = {n, n, fr->damage ? "damage" : NULL,
                    fr->displacement ? "displacement" : NULL, fr->zlib_level};
    return write_grid(path, a, na, npoint, &g);
}

/* ------------------------------------------------------------ spheres */

/* A sphere's surface: its points on SPHERE_RINGS - 1 circles of latitude
 * (SPHERE_SEGMENTS points each) and the two poles, joined by triangles. */
#define SPHERE_RINGS 16
#define SPHERE_SEGMENTS 32
#define SPHERE_POINTS (2 + (SPHERE_RINGS - 1) * SPHERE_SEGMENTS)
#define SPHERE_TRIANGLES (2 * SPHERE_SEGMENTS * (SPHERE_RINGS - 1))

/* Point j of circle r (1..RINGS-1), row 1 + (r - 1) SEGMENTS + j; the
 * poles are rows 0 (+z) and POINTS - 1 (-z). */
static int64_t sphere_row(int r, int j)
{
    if (r == 0)
        return 0;
    if (r == SPHERE_RINGS)
        return SPHERE_POINTS - 1;
    return 1 + (int64_t)(r - 1) * SPHERE_SEGMENTS + (j % SPHERE_SEGMENTS);
}

pd_status pd_vtk_write_sphere(const char *path, const pd_frame_sphere *sp, int zlib_level)
{
    if (sp == NULL || !(isfinite(sp->radius) && sp->radius > 0))
        return pd_fail(PD_ERR_INVALID, "VTK sphere of radius %g", sp ? sp->radius : NAN);
    double *xyz = malloc(3 * SPHERE_POINTS * sizeof *xyz);
    double *vel = malloc(3 * SPHERE_POINTS * sizeof *vel);
    int64_t *conn = malloc(3 * SPHERE_TRIANGLES * sizeof *conn);
    if (xyz == NULL || vel == NULL || conn == NULL) {
        free(xyz);
        free(vel);
        free(conn);
        return pd_fail(PD_ERR_NOMEM, "out of memory");
    }
    const double pi = 3.14159265358979323846;
    for (int r = 0; r <= SPHERE_RINGS; r++) {
        const double theta = pi * r / SPHERE_RINGS;
        for (int j = 0; j < ((r == 0 || r == SPHERE_RINGS) ? 1 : SPHERE_SEGMENTS); j++) {
            const double phi = 2.0 * pi * j / SPHERE_SEGMENTS;
            const double dir[3] = {sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta)};
            const int64_t row = sphere_row(r, j);
            for (int d = 0; d < 3; d++) {
                xyz[3 * row + d] = sp->centre[d] + sp->radius * dir[d];
                vel[3 * row + d] = sp->velocity[d];
            }
        }
    }
    /* triangles wound counter-clockwise seen from outside (normals out) */
    int64_t t = 0;
    for (int r = 0; r < SPHERE_RINGS; r++)
        for (int j = 0; j < SPHERE_SEGMENTS; j++) {
            const int64_t a = sphere_row(r, j), b = sphere_row(r, j + 1);
            const int64_t c = sphere_row(r + 1, j), d = sphere_row(r + 1, j + 1);
            if (r > 0) { /* a b above, c d below: the upper triangle */
                conn[t++] = a;
                conn[t++] = c;
                conn[t++] = b;
            }
            if (r < SPHERE_RINGS - 1) { /* the lower triangle */
                conn[t++] = (r == 0) ? a : b;
                conn[t++] = c;
                conn[t++] = d;
            }
        }
    varray a[] = {
        {"velocity", "Float64", 3, 8, SRC_AOS, .f64 = vel, .count = SPHERE_POINTS},
        {"Points", "Float64", 3, 8, SRC_AOS, .f64 = xyz, .count = SPHERE_POINTS},
        {"connectivity", "Int64", 1, 8, SRC_I64, .i64 = conn, .count = t},
        {"offsets", "Int64", 1, 8, SRC_SEQUENCE, .start = 3, .stride = 3,
         .count = SPHERE_TRIANGLES},
        {"types", "UInt8", 1, 1, SRC_CONSTANT, .start = VTK_TRIANGLE, .count = SPHERE_TRIANGLES},
    };
    grid_shape g = {SPHERE_POINTS, SPHERE_TRIANGLES, NULL, "velocity", zlib_level};
    pd_status s = write_grid(path, a, (int)(sizeof a / sizeof a[0]), 1, &g);
    free(xyz);
    free(vel);
    free(conn);
    return s;
}

/* ------------------------------------------------------------ .pvd */


pd_status pd_pvd_write(const char *path, int64_t nfiles, char *const *files, const double *times,
                       const int *parts, const char *const *names)
{
    if (nfiles < 0 || (nfiles > 0 && (files == NULL || times == NULL)))
        return pd_fail(PD_ERR_INVALID, "ParaView collection without files or times");
    for (int64_t k = 0; k < nfiles; k++) {
        if (files[k] == NULL || files[k][0] == '\0')
            return pd_fail(PD_ERR_INVALID, "ParaView collection entry %lld has no file name",
                           (long long)k);
        if (!isfinite(times[k]))
            return pd_fail(PD_ERR_INVALID, "ParaView collection entry '%s' has time %g",
                           files[k], times[k]);
        if (parts && parts[k] < 0)
            return pd_fail(PD_ERR_INVALID, "ParaView collection entry '%s' has part %d",
                           files[k], parts[k]);
    }
    pd_pending out;
    pd_status s = pd_pending_open(path, &out);
    if (s != PD_OK)
        return s;
    FILE *fp = out.fp;
    fprintf(fp, "<?xml version=\"1.0\"?>\n"
                "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
                "  <Collection>\n");
    for (int64_t k = 0; k < nfiles; k++) {
        fprintf(fp, "    <DataSet timestep=\"%.17g\" group=\"\" part=\"%d\"", times[k],
                parts ? parts[k] : 0);
        if (names && names[k]) {
            fprintf(fp, " name=\"");
            pd_xml_escaped(fp, names[k]);
            fprintf(fp, "\"");
        }
        fprintf(fp, " file=\"");
        pd_xml_escaped(fp, files[k]);
        fprintf(fp, "\"/>\n");
    }
    fprintf(fp, "  </Collection>\n</VTKFile>\n");
    return pd_pending_close(&out, s);
}
