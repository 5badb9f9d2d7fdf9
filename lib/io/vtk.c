/*
 * vtk.c -- frames as VTK XML files for ParaView.
 *
 * A frame is one UnstructuredGrid (.vtu): N points at the current positions
 * y = x + u, one vertex cell (VTK type 1) per particle (connectivity 0..N-1,
 * offsets 1..N), and point data displacement, velocity (3 components),
 * damage, damage_run (damage without the pre-crack, when given), material,
 * id, front (when given).  A subset of the particles (`select`, e.g. the
 * damaged zone of a crack path) gives a grid of only those points.  Data are binary and appended (encoding "raw"): each
 * array is a UInt64 byte count followed by its values, little-endian
 * whatever the host, so the XML header can state every array's offset before
 * any byte is written.  A time series is a ParaView collection (.pvd) that
 * names each .vtu with its time.
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

#include "pd.h"

#define VTK_VERTEX 1          /* VTK cell type of a single point         */
#define OUT_BUFFER (1 << 16)  /* bytes gathered before each fwrite        */

/* ------------------------------------------------------------ publishing */

/* An output being written: the stream, its temporary path and the target. */
typedef struct {
    FILE *fp;
    char *tmp;
    const char *path;
} pending;

/* Open a new temporary file beside `path`.  It is created with mode 0666 so
 * that the umask, not mkstemp's 0600, decides who may read the result. */
static pd_status pending_open(const char *path, pending *out)
{
    static _Atomic unsigned counter;
    memset(out, 0, sizeof *out);
    struct stat st;
    if (path == NULL || path[0] == '\0')
        return pd_fail(PD_ERR_INVALID, "empty output path");
    if (stat(path, &st) == 0 && S_ISDIR(st.st_mode))
        return pd_fail(PD_ERR_IO, "cannot write '%s': is a directory", path);
    char *copy = strdup(path), *base = strdup(path);
    size_t len = strlen(path) + 64;
    char *tmp = malloc(len);
    if (copy == NULL || base == NULL || tmp == NULL) {
        free(copy);
        free(base);
        free(tmp);
        return pd_fail(PD_ERR_NOMEM, "out of memory");
    }
    const char *dir = dirname(copy), *name = basename(base);
    int fd = -1;
    for (int attempt = 0; attempt < 100 && fd < 0; attempt++) {
        snprintf(tmp, len, "%s/.%s.tmp.%ld.%u", dir, name, (long)getpid(), counter++);
        fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL, 0666);
        if (fd < 0 && errno != EEXIST)
            break;
    }
    free(copy);
    free(base);
    if (fd < 0) {
        pd_status s = pd_fail(PD_ERR_IO, "cannot write '%s': %s", path, strerror(errno));
        free(tmp);
        return s;
    }
    out->fp = fdopen(fd, "wb");
    if (out->fp == NULL) {
        pd_status s = pd_fail(PD_ERR_IO, "cannot write '%s': %s", path, strerror(errno));
        close(fd);
        unlink(tmp);
        free(tmp);
        return s;
    }
    out->tmp = tmp;
    out->path = path;
    return PD_OK;
}

/* Finish: when `s` is PD_OK flush, sync and rename over the target;
 * otherwise (or when that fails) remove the temporary.  Returns the status. */
static pd_status pending_close(pending *w, pd_status s)
{
    if (w->fp == NULL)
        return s;
    if (s == PD_OK && (ferror(w->fp) || fflush(w->fp) != 0 || fsync(fileno(w->fp)) != 0))
        s = pd_fail(PD_ERR_IO, "cannot write '%s': %s", w->path,
                    errno ? strerror(errno) : "write error");
    if (fclose(w->fp) != 0 && s == PD_OK)
        s = pd_fail(PD_ERR_IO, "cannot write '%s': %s", w->path, strerror(errno));
    w->fp = NULL;
    if (s == PD_OK && rename(w->tmp, w->path) != 0)
        s = pd_fail(PD_ERR_IO, "cannot rename the output to '%s': %s", w->path, strerror(errno));
    if (s != PD_OK)
        unlink(w->tmp);
    free(w->tmp);
    w->tmp = NULL;
    return s;
}

/* ------------------------------------------------------------ binary data */

/* Where the values of one appended array come from. */
typedef enum {
    SRC_SOA,      /* double, 3 components from soa[0..2][i] */
    SRC_F64,      /* double, f64[i]                          */
    SRC_AOS,      /* double, ncomp interleaved: f64[ncomp i + c] */
    SRC_I32,      /* int32, i32[i]                           */
    SRC_I64,      /* int64, i64[i]                           */
    SRC_SEQUENCE, /* int64, i + start                        */
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
    int64_t start;
    uint64_t offset;   /* byte offset in the appended block  */
} varray;

/* Bytes of one array in the appended block: its UInt64 count + values. */
static uint64_t block_size(const varray *a, int64_t n)
{
    return 8 + (uint64_t)n * (uint64_t)a->ncomp * (uint64_t)a->width;
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
        bits = (uint64_t)(i + a->start);
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
    for (int k = 0; k < width; k++)
        w->buf[w->len++] = (unsigned char)(bits >> (8 * k));
}

static void write_block(le_writer *w, const varray *a, int64_t n)
{
    le_put(w, block_size(a, n) - 8, 8);
    for (int64_t i = 0; i < n; i++)
        for (int c = 0; c < a->ncomp; c++)
            le_put(w, value_bits(a, i, c), a->width);
}

/* ------------------------------------------------------------ .vtu */

static void xml_array(FILE *fp, const varray *a)
{
    fprintf(fp, "        <DataArray type=\"%s\" Name=\"%s\"", a->type, a->name);
    if (a->ncomp > 1)
        fprintf(fp, " NumberOfComponents=\"%d\"", a->ncomp);
    fprintf(fp, " format=\"appended\" offset=\"%llu\"/>\n", (unsigned long long)a->offset);
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

    /* Point data first, then Points, then Cells: the order of the XML and
     * of the appended block. */
    if (fr->nextra < 0 || fr->nextra > 64 || (fr->nextra > 0 && fr->extra == NULL))
        return pd_fail(PD_ERR_INVALID, "VTK frame with %d extra fields", fr->nextra);
    for (int k = 0; k < fr->nextra; k++)
        if (fr->extra[k].name == NULL || fr->extra[k].values == NULL ||
            fr->extra[k].ncomp < 1 || fr->extra[k].ncomp > 9)
            return pd_fail(PD_ERR_INVALID, "VTK frame field %d is incomplete", k);
    varray a[11 + 64];
    int na = 0, npoint = 0;
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
    npoint = na - 1;
    for (int k = 0; k < na; k++)
        a[k].select = fr->select;
    a[na++] = (varray){"connectivity", "Int64", 1, 8, SRC_SEQUENCE, .start = 0};
    a[na++] = (varray){"offsets", "Int64", 1, 8, SRC_SEQUENCE, .start = 1};
    a[na++] = (varray){"types", "UInt8", 1, 1, SRC_CONSTANT, .start = VTK_VERTEX};
    uint64_t offset = 0;
    for (int k = 0; k < na; k++) {
        a[k].offset = offset;
        offset += block_size(&a[k], n);
    }

    pending out;
    pd_status s = pending_open(path, &out);
    if (s != PD_OK)
        return s;
    FILE *fp = out.fp;
    fprintf(fp, "<?xml version=\"1.0\"?>\n"
                "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\""
                " header_type=\"UInt64\">\n"
                "  <UnstructuredGrid>\n"
                "    <Piece NumberOfPoints=\"%lld\" NumberOfCells=\"%lld\">\n",
            (long long)n, (long long)n);
    fprintf(fp, "      <PointData%s%s>\n", fr->damage ? " Scalars=\"damage\"" : "",
            fr->displacement ? " Vectors=\"displacement\"" : "");
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
    le_writer *w = malloc(sizeof *w);
    if (w == NULL)
        return pending_close(&out, pd_fail(PD_ERR_NOMEM, "out of memory"));
    w->fp = fp;
    w->len = 0;
    w->failed = 0;
    for (int k = 0; k < na; k++)
        write_block(w, &a[k], n);
    le_flush(w);
    if (w->failed)
        s = pd_fail(PD_ERR_IO, "cannot write '%s': %s", path, strerror(errno));
    free(w);
    fprintf(fp, "\n  </AppendedData>\n</VTKFile>\n");
    return pending_close(&out, s);
}

/* ------------------------------------------------------------ .pvd */

/* A string as the text of an XML attribute value. */
static void xml_escaped(FILE *fp, const char *s)
{
    for (; *s; s++) {
        switch (*s) {
        case '&':
            fputs("&amp;", fp);
            break;
        case '<':
            fputs("&lt;", fp);
            break;
        case '>':
            fputs("&gt;", fp);
            break;
        case '"':
            fputs("&quot;", fp);
            break;
        case '\'':
            fputs("&apos;", fp);
            break;
        default:
            fputc(*s, fp);
        }
    }
}

pd_status pd_pvd_write(const char *path, int64_t nfiles, char *const *files, const double *times)
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
    }
    pending out;
    pd_status s = pending_open(path, &out);
    if (s != PD_OK)
        return s;
    FILE *fp = out.fp;
    fprintf(fp, "<?xml version=\"1.0\"?>\n"
                "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
                "  <Collection>\n");
    for (int64_t k = 0; k < nfiles; k++) {
        fprintf(fp, "    <DataSet timestep=\"%.17g\" group=\"\" part=\"0\" file=\"", times[k]);
        xml_escaped(fp, files[k]);
        fprintf(fp, "\"/>\n");
    }
    fprintf(fp, "  </Collection>\n</VTKFile>\n");
    return pending_close(&out, s);
}
