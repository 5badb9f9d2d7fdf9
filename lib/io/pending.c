/*
 * pending.c -- text and binary outputs published whole: written to a
 * temporary file beside the target, flushed and synced, then renamed over
 * it, so that a reader never sees a half-written file under the final name
 * (the VTK files, the .pvd and the XDMF description of a run).
 */
#include <errno.h>
#include <fcntl.h>
#include <libgen.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "io/pending.h"

/* Open a new temporary file beside `path`.  It is created with mode 0666 so
 * that the umask, not mkstemp's 0600, decides who may read the result. */
pd_status pd_pending_open(const char *path, pd_pending *out)
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
pd_status pd_pending_close(pd_pending *w, pd_status s)
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

/* A string as the text of an XML attribute value. */
void pd_xml_escaped(FILE *fp, const char *s)
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
