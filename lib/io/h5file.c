/*
 * h5file.c -- opening and publishing pd-h5 files.
 *
 * Reading "-" takes the whole of stdin and opens it as an HDF5 file image
 * (core driver).  Writing "-" builds the file in memory (core driver, no
 * backing store) and streams its image to stdout at close.  Writing a path
 * goes to a temporary file beside it that is renamed over the path only once
 * the file is complete, so a failed or killed program never leaves a half
 * written file under the final name.  A path that exists and is neither a
 * regular file nor a directory (/dev/null, a FIFO, /dev/stdout) is written
 * like stdout: built in memory and streamed to it at close, never replaced.
 */

#include <errno.h>
#include <fcntl.h>
#include <libgen.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <hdf5.h>

#include "base/comm.h"
#include "io/h5util.h"
#include "pd.h"

/* Temporary files being written, for pd_remove_temps() in a signal
 * handler: plain slots, set and cleared by the one thread that opens and
 * closes files. */
#define MAX_TEMPS 16
static char *volatile temps[MAX_TEMPS];

static void temp_register(char *path)
{
    for (int k = 0; k < MAX_TEMPS; k++)
        if (temps[k] == NULL) {
            temps[k] = path;
            return;
        }
}

static void temp_forget(const char *path)
{
    for (int k = 0; k < MAX_TEMPS; k++)
        if (temps[k] == path)
            temps[k] = NULL;
}

void pd_remove_temps(void)
{
    for (int k = 0; k < MAX_TEMPS; k++)
        if (temps[k] != NULL)
            unlink(temps[k]); /* async-signal-safe */
}

static const unsigned char hdf5_signature[8] = {0x89, 'H', 'D', 'F', '\r', '\n', 0x1a, '\n'};

/* Read all of a stream into memory. */
static pd_status slurp(FILE *in, const char *what, unsigned char **buf, size_t *len)
{
    size_t cap = 1 << 20, n = 0;
    unsigned char *b = malloc(cap);
    if (b == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory reading %s", what);
    for (;;) {
        if (n == cap) {
            unsigned char *nb = realloc(b, cap * 2);
            if (nb == NULL) {
                free(b);
                return pd_fail(PD_ERR_NOMEM, "out of memory reading %s", what);
            }
            b = nb;
            cap *= 2;
        }
        size_t got = fread(b + n, 1, cap - n, in);
        n += got;
        if (got == 0) {
            if (ferror(in)) {
                free(b);
                return pd_fail(PD_ERR_IO, "cannot read %s: %s", what, strerror(errno));
            }
            break;
        }
    }
    *buf = b;
    *len = n;
    return PD_OK;
}

/* Open an in-memory image (read-only or writable, never backed by a file). */
static hid_t open_image(const void *buf, size_t len, unsigned flags)
{
    hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
    H5Pset_fapl_core(fapl, 1 << 20, 0);
    H5Pset_file_image(fapl, (void *)buf, len);
    hid_t fid = H5Fopen("pd-input-image", flags, fapl);
    H5Pclose(fapl);
    return fid;
}

static pd_status check_header(pd_file *f)
{
    char *format = NULL;
    if (!pd_h5_has_attr(f->fid, "pd_format") ||
        pd_h5_read_attr_string(f->fid, "pd_format", &format) != PD_OK ||
        strcmp(format, PD_FORMAT) != 0) {
        free(format);
        return pd_fail(PD_ERR_FORMAT, "'%s' is an HDF5 file but not a pd-h5 file (no pd_format)",
                       f->name);
    }
    free(format);
    int64_t version = 0;
    if (pd_h5_read_attr_int(f->fid, "pd_format_version", &version) != PD_OK)
        return pd_fail(PD_ERR_FORMAT, "'%s': no pd_format_version", f->name);
    if (version < 1 || version > PD_FORMAT_VERSION)
        return pd_fail(PD_ERR_FORMAT,
                       "'%s': pd-h5 format version %lld, this pd reads versions 1 to %d",
                       f->name, (long long)version, PD_FORMAT_VERSION);
    f->version = (int)version;
    return PD_OK;
}

static pd_file *file_new(const char *path)
{
    pd_file *f = calloc(1, sizeof *f);
    if (f == NULL)
        return NULL;
    f->fid = H5I_INVALID_HID;
    f->version = PD_FORMAT_VERSION; /* an opened file's is read by check_header */
    f->name = strdup(strcmp(path, "-") == 0 ? "<stdin>" : path);
    return f;
}

static void file_free(pd_file *f)
{
    if (f == NULL)
        return;
    temp_forget(f->tmp);
    pd_series_plan_free(f->series);
    free(f->name);
    free(f->path);
    free(f->tmp);
    free(f->image);
    free(f);
}

/* A path (not a directory) opened to read. */
static pd_status open_path(const char *path, FILE **in)
{
    struct stat st;
    if (stat(path, &st) != 0)
        return pd_fail(PD_ERR_IO, "cannot open '%s': %s", path, strerror(errno));
    if (S_ISDIR(st.st_mode))
        return pd_fail(PD_ERR_IO, "cannot open '%s': is a directory", path);
    if ((*in = fopen(path, "rb")) == NULL)
        return pd_fail(PD_ERR_IO, "cannot open '%s': %s", path, strerror(errno));
    return PD_OK;
}

static pd_status load_bytes(const char *path, unsigned char **buf, size_t *len)
{
    if (strcmp(path, "-") == 0) {
        if (isatty(STDIN_FILENO))
            return pd_fail(PD_ERR_IO, "refusing to read an HDF5 file from a terminal (give a file "
                                      "or a pipe)");
        return slurp(stdin, "stdin", buf, len);
    }
    FILE *in = NULL;
    pd_status s = open_path(path, &in);
    if (s != PD_OK)
        return s;
    s = slurp(in, path, buf, len);
    fclose(in);
    return s;
}

static pd_status check_signature(const char *name, const unsigned char *buf, size_t len)
{
    if (len == 0)
        return pd_fail(PD_ERR_FORMAT, "'%s' is empty", name);
    if (len < 8 || memcmp(buf, hdf5_signature, 8) != 0)
        return pd_fail(PD_ERR_FORMAT, "'%s' is not an HDF5 file", name);
    return PD_OK;
}

/* Open an image read-only, taking ownership of `buf` (freed with the file,
 * or here on failure); `name` ("-" for stdin) is used in messages. */
static pd_status open_owned_image(unsigned char *buf, size_t len, const char *name,
                                  pd_file **out)
{
    pd_file *f = file_new(name);
    if (f == NULL) {
        free(buf);
        return pd_fail(PD_ERR_NOMEM, "out of memory");
    }
    f->image = buf;
    f->readonly = 1;
    pd_status s = check_signature(f->name, buf, len);
    if (s == PD_OK && (f->fid = open_image(buf, len, H5F_ACC_RDONLY)) < 0)
        s = pd_fail(PD_ERR_FORMAT, "cannot open '%s' as HDF5 (damaged or truncated?)", f->name);
    if (s == PD_OK)
        s = check_header(f);
    if (s != PD_OK) {
        if (f->fid >= 0)
            H5Fclose(f->fid);
        file_free(f);
        return s;
    }
    *out = f;
    return PD_OK;
}

pd_status pd_file_open_stream(FILE *in, const char *name, pd_file **out)
{
    unsigned char *buf;
    size_t len;
    pd_status s = slurp(in, name, &buf, &len);
    return s == PD_OK ? open_owned_image(buf, len, name, out) : s;
}

int pd_file_is_hdf5(const char *path)
{
    unsigned char head[sizeof hdf5_signature];
    FILE *in = fopen(path, "rb");
    if (in == NULL) {
        pd_fail(PD_ERR_IO, "cannot open '%s': %s", path, strerror(errno));
        return -1;
    }
    size_t got = fread(head, 1, sizeof head, in);
    fclose(in);
    return got == sizeof head && memcmp(head, hdf5_signature, sizeof head) == 0;
}

pd_status pd_file_open_memory(const void *buf, size_t len, const char *name, pd_file **out)
{
    unsigned char *copy = malloc(len ? len : 1);
    if (copy == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory");
    memcpy(copy, buf, len);
    return open_owned_image(copy, len, name, out);
}

pd_status pd_file_open(const char *path, pd_file **out)
{
    if (strcmp(path, "-") == 0) {
        unsigned char *buf;
        size_t len;
        pd_status s = load_bytes(path, &buf, &len);
        return s == PD_OK ? open_owned_image(buf, len, path, out) : s;
    }
    pd_file *f = file_new(path);
    if (f == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory");
    pd_status s;
    struct stat st;
    if (stat(path, &st) != 0) {
        s = pd_fail(PD_ERR_IO, "cannot open '%s': %s", path, strerror(errno));
        file_free(f);
        return s;
    }
    if (S_ISDIR(st.st_mode)) {
        file_free(f);
        return pd_fail(PD_ERR_IO, "cannot open '%s': is a directory", path);
    }
    if (st.st_size == 0) {
        file_free(f);
        return pd_fail(PD_ERR_FORMAT, "'%s' is empty", path);
    }
    if (access(path, R_OK) != 0) {
        s = pd_fail(PD_ERR_IO, "cannot open '%s': %s", path, strerror(errno));
        file_free(f);
        return s;
    }
    if (H5Fis_hdf5(path) <= 0) {
        file_free(f);
        return pd_fail(PD_ERR_FORMAT, "'%s' is not an HDF5 file", path);
    }
    f->fid = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    if (f->fid < 0) {
        s = pd_fail(PD_ERR_FORMAT, "cannot open '%s' as HDF5 (damaged or truncated?)", f->name);
        file_free(f);
        return s;
    }
    f->readonly = 1;
    if ((s = check_header(f)) != PD_OK) {
        H5Fclose(f->fid);
        file_free(f);
        return s;
    }
    *out = f;
    return PD_OK;
}

/* A temporary path beside `path`; the file is created (empty) by mkstemp. */
static pd_status make_temp(const char *path, char **tmp)
{
    char *copy = strdup(path);
    char *base = strdup(path);
    if (copy == NULL || base == NULL) {
        free(copy);
        free(base);
        return pd_fail(PD_ERR_NOMEM, "out of memory");
    }
    const char *dir = dirname(copy);
    const char *name = basename(base);
    size_t len = strlen(dir) + strlen(name) + 32;
    char *t = malloc(len);
    if (t == NULL) {
        free(copy);
        free(base);
        return pd_fail(PD_ERR_NOMEM, "out of memory");
    }
    snprintf(t, len, "%s/.%s.tmp.XXXXXX", dir, name);
    struct stat st;
    if (stat(path, &st) == 0 && S_ISDIR(st.st_mode)) {
        free(copy);
        free(base);
        free(t);
        return pd_fail(PD_ERR_IO, "cannot write '%s': is a directory", path);
    }
    /* registered before it exists: mkstemp writes the name before it
     * creates the file, so a signal at any moment removes whatever exists */
    temp_register(t);
    int fd = mkstemp(t);
    if (fd >= 0) {
        /* mkstemp makes 0600; a published file gets 0666 less the umask */
        mode_t mask = umask(0);
        umask(mask);
        if (fchmod(fd, 0666 & ~mask) != 0) {
            close(fd);
            unlink(t);
            fd = -1;
        }
    }
    if (fd < 0) {
        pd_status s = pd_fail(PD_ERR_IO, "cannot write '%s': %s", path, strerror(errno));
        temp_forget(t);
        free(copy);
        free(base);
        free(t);
        return s;
    }
    close(fd);
    free(copy);
    free(base);
    *tmp = t;
    return PD_OK;
}

/* Is `path` an existing special file (device, FIFO, socket)? */
static int is_special(const char *path)
{
    struct stat st;
    return strcmp(path, "-") != 0 && stat(path, &st) == 0 && !S_ISREG(st.st_mode) &&
           !S_ISDIR(st.st_mode);
}

/* A writable in-memory file (core driver, no backing store). */
static hid_t create_image(void)
{
    hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
    H5Pset_fapl_core(fapl, 1 << 22, 0);
    hid_t fid = H5Fcreate("pd-output-image", H5F_ACC_TRUNC, H5P_DEFAULT, fapl);
    H5Pclose(fapl);
    return fid;
}

pd_status pd_file_create(const char *path, pd_file **out)
{
    pd_file *f = file_new(path);
    if (f == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory");
    free(f->name);
    f->name = strdup(strcmp(path, "-") == 0 ? "<stdout>" : path);
    pd_status s;
    if (strcmp(path, "-") == 0) {
        if (isatty(STDOUT_FILENO)) {
            file_free(f);
            return pd_fail(PD_ERR_IO, "refusing to write an HDF5 file to a terminal (use -o FILE "
                                      "or a pipe)");
        }
        f->to_stdout = 1;
        f->fid = create_image();
    } else if (is_special(path)) {
        f->to_stdout = 1;
        f->path = strdup(path);
        f->fid = create_image();
    } else {
        if ((s = make_temp(path, &f->tmp)) != PD_OK) {
            file_free(f);
            return s;
        }
        f->path = strdup(path);
        f->fid = H5Fcreate(f->tmp, H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    }
    if (f->fid < 0) {
        s = pd_fail(PD_ERR_IO, "cannot create '%s'", f->name);
        if (f->tmp)
            unlink(f->tmp);
        file_free(f);
        return s;
    }
    *out = f;
    return PD_OK;
}

/* len bytes at buf into a new temporary beside outpath (*tmp). */
static pd_status copy_to_temp(const char *outpath, const unsigned char *buf, size_t len,
                              char **tmp)
{
    pd_status s = make_temp(outpath, tmp);
    if (s != PD_OK)
        return s;
    FILE *o = fopen(*tmp, "wb");
    int ok = o != NULL && fwrite(buf, 1, len, o) == len;
    if (o != NULL && fclose(o) != 0)
        ok = 0;
    if (!ok) {
        s = pd_fail(PD_ERR_IO, "cannot write '%s': %s", outpath, strerror(errno));
        unlink(*tmp);
        temp_forget(*tmp);
        free(*tmp);
        *tmp = NULL;
    }
    return s;
}

/* The file at inpath (an HDF5 file: its signature checked first) copied
 * into a new temporary beside outpath (*tmp), a buffer at a time: a run of
 * any size goes on without being held in memory. */
static pd_status copy_file_to_temp(const char *inpath, const char *outpath, char **tmp)
{
    FILE *in = NULL;
    pd_status s = open_path(inpath, &in);
    if (s != PD_OK)
        return s;
    enum { CHUNK = 8 << 20 };
    unsigned char *buf = malloc(CHUNK);
    size_t got = buf ? fread(buf, 1, CHUNK, in) : 0;
    s = buf == NULL              ? pd_fail(PD_ERR_NOMEM, "out of memory")
                  : ferror(in) ? pd_fail(PD_ERR_IO, "cannot read '%s': %s", inpath, strerror(errno))
                               : check_signature(inpath, buf, got);
    if (s == PD_OK)
        s = make_temp(outpath, tmp);
    FILE *o = s == PD_OK ? fopen(*tmp, "wb") : NULL;
    int ok = o != NULL;
    while (ok && got > 0) {
        ok = fwrite(buf, 1, got, o) == got;
        got = ok ? fread(buf, 1, CHUNK, in) : 0;
    }
    if (s == PD_OK && ferror(in))
        s = pd_fail(PD_ERR_IO, "cannot read '%s': %s", inpath, strerror(errno));
    if (o != NULL && fclose(o) != 0)
        ok = 0;
    if (s == PD_OK && !ok)
        s = pd_fail(PD_ERR_IO, "cannot write '%s': %s", outpath, strerror(errno));
    if (s != PD_OK && *tmp) {
        unlink(*tmp);
        temp_forget(*tmp);
        free(*tmp);
        *tmp = NULL;
    }
    free(buf);
    fclose(in);
    return s;
}

pd_status pd_file_update(const char *inpath, const char *outpath, pd_file **out)
{
    unsigned char *buf = NULL;
    size_t len = 0;
    const char *inname = strcmp(inpath, "-") == 0 ? "<stdin>" : inpath;
    /* a file into a file: copied a buffer at a time; else through memory */
    const int streamed = strcmp(inpath, "-") != 0 && strcmp(outpath, "-") != 0 &&
                         !is_special(outpath);
    pd_status s = streamed ? PD_OK : load_bytes(inpath, &buf, &len);
    if (s != PD_OK)
        return s;
    if (!streamed && (s = check_signature(inname, buf, len)) != PD_OK) {
        free(buf);
        return s;
    }
    pd_file *f = file_new(outpath);
    if (f == NULL) {
        free(buf);
        return pd_fail(PD_ERR_NOMEM, "out of memory");
    }
    free(f->name);
    f->name = strdup(inname);
    if (strcmp(outpath, "-") == 0 || is_special(outpath)) {
        if (strcmp(outpath, "-") == 0 && isatty(STDOUT_FILENO)) {
            free(buf);
            file_free(f);
            return pd_fail(PD_ERR_IO, "refusing to write an HDF5 file to a terminal (use -o FILE "
                                      "or a pipe)");
        }
        f->to_stdout = 1;
        if (strcmp(outpath, "-") != 0)
            f->path = strdup(outpath);
        f->image = buf;
        f->fid = open_image(buf, len, H5F_ACC_RDWR);
    } else {
        s = streamed ? copy_file_to_temp(inpath, outpath, &f->tmp)
                     : copy_to_temp(outpath, buf, len, &f->tmp);
        free(buf);
        if (s != PD_OK) {
            file_free(f);
            return s;
        }
        f->path = strdup(outpath);
        f->fid = H5Fopen(f->tmp, H5F_ACC_RDWR, H5P_DEFAULT);
    }
    if (f->fid < 0) {
        s = pd_fail(PD_ERR_FORMAT, "cannot open '%s' as HDF5 (damaged or truncated?)", inname);
        if (f->tmp)
            unlink(f->tmp);
        file_free(f);
        return s;
    }
    if ((s = check_header(f)) != PD_OK) {
        pd_file_abort(f);
        return s;
    }
    *out = f;
    return PD_OK;
}

#ifdef H5_HAVE_PARALLEL
/* Rank 0's temporary path, made beside the output, on every rank too;
 * then the file opened there by every rank (parallel HDF5): created, or
 * opened for update.  Collective; s is rank 0's making of the temporary. */
static pd_status open_on_ranks(pd_file *f, pd_status s, int create)
{
    int64_t len = f->tmp ? (int64_t)strlen(f->tmp) + 1 : 0;
    if ((s = pd_comm_agree(s)) != PD_OK)
        return s;
    pd_comm_bcast(&len, sizeof len);
    char *name = malloc((size_t)len);
    if (name && pd_comm_rank() == 0)
        memcpy(name, f->tmp, (size_t)len);
    if (pd_comm_or(name == NULL)) {
        free(name);
        return pd_fail(PD_ERR_NOMEM, "out of memory");
    }
    pd_comm_bcast(name, len);
    if (pd_comm_rank() > 0)
        f->tmp = name;
    else
        free(name);
    hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
    H5Pset_fapl_mpio(fapl, MPI_COMM_WORLD, MPI_INFO_NULL);
    f->fid = create ? H5Fcreate(f->tmp, H5F_ACC_TRUNC, H5P_DEFAULT, fapl)
                    : H5Fopen(f->tmp, H5F_ACC_RDWR, fapl);
    H5Pclose(fapl);
    f->ranks = pd_comm_size();
    return pd_comm_agree(f->fid < 0 ? pd_fail(PD_ERR_IO, "cannot open '%s' on every MPI rank "
                                                         "(parallel HDF5)",
                                              f->name)
                                    : PD_OK);
}

/* A regular file is what MPI ranks write together. */
static pd_status ranks_output(const char *path)
{
    if (strcmp(path, "-") == 0 || is_special(path))
        return pd_fail(PD_ERR_INVALID, "on several MPI ranks the run file must be a regular file "
                                       "(the ranks write it with parallel HDF5), not '%s'",
                       path);
    return PD_OK;
}

/* A file of every rank named `name`, to go under `path` (collective). */
static pd_status new_on_ranks(const char *name, const char *path, pd_file **out)
{
    pd_status s = PD_OK;
    pd_file *f = file_new(name);
    if (f == NULL || (f->path = strdup(path)) == NULL)
        s = pd_fail(PD_ERR_NOMEM, "out of memory");
    if (pd_comm_or(s != PD_OK)) {
        file_free(f);
        return s != PD_OK ? s : pd_comm_agree(s);
    }
    *out = f;
    return PD_OK;
}

/* Undo a parallel open that failed: every rank. */
static pd_status undo_ranks(pd_file *f, pd_status s)
{
    if (f->fid >= 0)
        H5Fclose(f->fid);
    if (pd_comm_rank() == 0 && f->tmp)
        unlink(f->tmp);
    file_free(f);
    return s;
}
#endif

pd_status pd_file_create_ranks(const char *path, pd_file **out)
{
#ifdef H5_HAVE_PARALLEL
    if (pd_comm_size() == 1)
        return pd_file_create(path, out);
    pd_status s = ranks_output(path);
    if (s != PD_OK)
        return s;
    pd_file *f = NULL;
    if ((s = new_on_ranks(path, path, &f)) != PD_OK)
        return s;
    if (pd_comm_rank() == 0)
        s = make_temp(path, &f->tmp);
    if ((s = open_on_ranks(f, s, 1)) != PD_OK)
        return undo_ranks(f, s);
    *out = f;
    return PD_OK;
#else
    return pd_file_create(path, out);
#endif
}

pd_status pd_file_update_ranks(const char *inpath, const char *outpath, pd_file **out)
{
#ifdef H5_HAVE_PARALLEL
    if (pd_comm_size() == 1)
        return pd_file_update(inpath, outpath, out);
    pd_status s = ranks_output(outpath);
    if (s == PD_OK && strcmp(inpath, "-") == 0)
        s = pd_fail(PD_ERR_INVALID, "on several MPI ranks the run to go on from must be a file");
    if (s != PD_OK)
        return s;
    pd_file *f = NULL;
    if ((s = new_on_ranks(inpath, outpath, &f)) != PD_OK)
        return s;
    if (pd_comm_rank() == 0) /* the copy, rank 0's */
        s = copy_file_to_temp(inpath, outpath, &f->tmp);
    if ((s = open_on_ranks(f, s, 0)) == PD_OK)
        s = pd_comm_agree(check_header(f));
    if (s != PD_OK)
        return undo_ranks(f, s);
    *out = f;
    return PD_OK;
#else
    return pd_file_update(inpath, outpath, out);
#endif
}

/* Rank 0's end of a parallel file (its fsync and rename, published or
 * not), agreed by every rank after the collective close. */
static pd_status close_ranks(pd_file *f, pd_status s)
{
    s = pd_comm_agree(s);
    if (pd_comm_rank() == 0) {
        const char *at = f->published ? f->path : f->tmp;
        int fd = s == PD_OK ? open(at, O_RDONLY) : -1;
        if (fd >= 0 && fsync(fd) != 0)
            s = pd_fail(PD_ERR_IO, "cannot write '%s': %s", f->path, strerror(errno));
        if (fd >= 0)
            close(fd);
        if (s == PD_OK && !f->published && rename(f->tmp, f->path) != 0)
            s = pd_fail(PD_ERR_IO, "cannot rename the output to '%s': %s", f->path,
                        strerror(errno));
        if (s != PD_OK && !f->published)
            unlink(f->tmp);
    }
    s = pd_comm_agree(s);
    file_free(f);
    return s;
}

pd_status pd_file_close(pd_file *f)
{
    if (f == NULL)
        return PD_OK;
    pd_status s = PD_OK;
    if (f->readonly) {
        H5Fclose(f->fid);
        file_free(f);
        return PD_OK;
    }
    if (f->to_stdout) {
        if (H5Fflush(f->fid, H5F_SCOPE_GLOBAL) < 0)
            s = pd_fail(PD_ERR_IO, "cannot finish the output file");
        ssize_t size = s == PD_OK ? H5Fget_file_image(f->fid, NULL, 0) : -1;
        unsigned char *img = size > 0 ? malloc((size_t)size) : NULL;
        if (s == PD_OK && (img == NULL || H5Fget_file_image(f->fid, img, (size_t)size) != size))
            s = pd_fail(PD_ERR_IO, "cannot build the output image");
        H5Fclose(f->fid);
        if (s == PD_OK) {
            /* stdout, or a special file given as the output path */
            FILE *o = f->path ? fopen(f->path, "wb") : stdout;
            const char *where = f->path ? f->path : "stdout";
            if (o == NULL)
                s = pd_fail(PD_ERR_IO, "cannot write to '%s': %s", where, strerror(errno));
            else {
                if (fwrite(img, 1, (size_t)size, o) != (size_t)size || fflush(o) != 0)
                    s = pd_fail(PD_ERR_IO, "cannot write to %s: %s", where, strerror(errno));
                if (f->path && fclose(o) != 0 && s == PD_OK)
                    s = pd_fail(PD_ERR_IO, "cannot write to %s: %s", where, strerror(errno));
            }
        }
        free(img);
        file_free(f);
        return s;
    }
    if (H5Fclose(f->fid) < 0)
        s = pd_fail(PD_ERR_IO, "cannot write '%s' (disk full?)", f->path);
    if (f->ranks > 1)
        return close_ranks(f, s);
    if (f->published) { /* already under its final name: make it durable */
        int fd = open(f->path, O_RDONLY);
        if (s == PD_OK && fd >= 0 && fsync(fd) != 0)
            s = pd_fail(PD_ERR_IO, "cannot write '%s': %s", f->path, strerror(errno));
        if (fd >= 0)
            close(fd);
        file_free(f);
        return s;
    }
    if (s == PD_OK) {
        int fd = open(f->tmp, O_RDONLY);
        if (fd >= 0) {
            if (fsync(fd) != 0)
                s = pd_fail(PD_ERR_IO, "cannot write '%s': %s", f->path, strerror(errno));
            close(fd);
        }
    }
    if (s == PD_OK && rename(f->tmp, f->path) != 0)
        s = pd_fail(PD_ERR_IO, "cannot rename the output to '%s': %s", f->path, strerror(errno));
    if (s != PD_OK)
        unlink(f->tmp);
    file_free(f);
    return s;
}

void pd_file_abort(pd_file *f)
{
    if (f == NULL)
        return;
    if (f->fid >= 0)
        H5Fclose(f->fid); /* collective on a parallel file: every rank aborts it */
    if (f->tmp && !f->published && (f->ranks <= 1 || pd_comm_rank() == 0))
        unlink(f->tmp);
    file_free(f);
}

static pd_status publish_ranks(pd_file *f)
{
    pd_status s = PD_OK;
    if (H5Fflush(f->fid, H5F_SCOPE_GLOBAL) < 0)
        s = pd_fail(PD_ERR_IO, "cannot write '%s' (disk full?)", f->path);
    if ((s = pd_comm_agree(s)) == PD_OK && pd_comm_rank() == 0) {
        int fd = open(f->tmp, O_RDONLY);
        if (fd < 0 || fsync(fd) != 0)
            s = pd_fail(PD_ERR_IO, "cannot write '%s': %s", f->path, strerror(errno));
        if (fd >= 0)
            close(fd);
        if (s == PD_OK && rename(f->tmp, f->path) != 0)
            s = pd_fail(PD_ERR_IO, "cannot rename the output to '%s': %s", f->path,
                        strerror(errno));
    }
    if ((s = pd_comm_agree(s)) == PD_OK) {
        temp_forget(f->tmp);
        f->published = 1;
    }
    return s;
}

pd_status pd_file_publish(pd_file *f)
{
    if (f->to_stdout || f->published || f->tmp == NULL)
        return PD_OK;
    if (f->ranks > 1) /* every rank flushes; rank 0 renames */
        return publish_ranks(f);
    if (H5Fflush(f->fid, H5F_SCOPE_GLOBAL) < 0)
        return pd_fail(PD_ERR_IO, "cannot write '%s' (disk full?)", f->path);
    int fd = open(f->tmp, O_RDONLY);
    int ok = fd >= 0 && fsync(fd) == 0;
    if (fd >= 0)
        close(fd);
    if (!ok)
        return pd_fail(PD_ERR_IO, "cannot write '%s': %s", f->path, strerror(errno));
    if (rename(f->tmp, f->path) != 0)
        return pd_fail(PD_ERR_IO, "cannot rename the output to '%s': %s", f->path,
                       strerror(errno));
    temp_forget(f->tmp);
    f->published = 1;
    return PD_OK;
}
