/*
 * cli.c -- pieces every program's command line shares: the command line as
 * one history line, and scene files (`--scene FILE`: one `option value` per
 * line, `#` comments) turned into long options.
 */
#include <ctype.h>
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "pd.h"

char *pd_join_argv(int argc, char **argv)
{
    size_t len = 1;
    for (int k = 0; k < argc; k++)
        len += strlen(argv[k]) + 3;
    char *s = malloc(len);
    if (s == NULL)
        return NULL;
    size_t used = 0;
    for (int k = 0; k < argc; k++) {
        int quote = argv[k][0] == '\0' || strpbrk(argv[k], " \t\n'\"") != NULL;
        used += (size_t)snprintf(s + used, len - used, "%s%s%s%s", k ? " " : "",
                                 quote ? "'" : "", argv[k], quote ? "'" : "");
    }
    return s;
}

static char *trim(char *s)
{
    while (isspace((unsigned char)*s))
        s++;
    char *e = s + strlen(s);
    while (e > s && isspace((unsigned char)e[-1]))
        *--e = '\0';
    return s;
}

static pd_status scene_stream(FILE *in, const char *path, int *argc, char ***argv,
                              int **lines);

pd_status pd_scene_args(const char *path, int *argc, char ***argv, int **lines)
{
    FILE *in = fopen(path, "r");
    if (in == NULL)
        return pd_fail(PD_ERR_IO, "cannot open scene '%s': %s", path, strerror(errno));
    return scene_stream(in, path, argc, argv, lines);
}

pd_status pd_scene_args_text(const char *text, const char *name, int *argc, char ***argv,
                             int **lines)
{
    FILE *in = fmemopen((void *)text, strlen(text), "r");
    if (in == NULL)
        return pd_fail(PD_ERR_NOMEM, "cannot read the scene of '%s'", name);
    return scene_stream(in, name, argc, argv, lines);
}

static pd_status scene_stream(FILE *in, const char *path, int *argc, char ***argv,
                              int **lines)
{
    int n = 0, cap = 16;
    char **v = malloc((size_t)cap * sizeof *v);
    int *at = malloc((size_t)cap * sizeof *at); /* each one's line */
    char line[4096];
    int lineno = 0;
    pd_status s = PD_OK;
    while (v && at && s == PD_OK && fgets(line, sizeof line, in)) {
        lineno++;
        if (strchr(line, '\n') == NULL && !feof(in)) {
            s = pd_fail(PD_ERR_INVALID, "scene '%s' line %d is too long", path, lineno);
            break;
        }
        char *hash = strchr(line, '#');
        if (hash)
            *hash = '\0';
        char *t = trim(line);
        if (*t == '\0')
            continue;
        char *val = t;
        while (*val && !isspace((unsigned char)*val))
            val++;
        if (*val)
            *val++ = '\0';
        val = trim(val);
        if (strncmp(t, "--", 2) == 0)
            t += 2;
        if (*t == '\0' || strcmp(t, "scene") == 0) {
            s = pd_fail(PD_ERR_INVALID, "scene '%s' line %d: bad option", path, lineno);
            break;
        }
        if (n + 2 >= cap) {
            cap *= 2;
            char **nv = realloc(v, (size_t)cap * sizeof *nv);
            if (nv != NULL)
                v = nv;
            int *na = nv ? realloc(at, (size_t)cap * sizeof *na) : NULL;
            if (na == NULL) {
                s = pd_fail(PD_ERR_NOMEM, "out of memory");
                break;
            }
            at = na;
        }
        size_t len = strlen(t) + 3;
        v[n] = malloc(len);
        if (v[n] == NULL) {
            s = pd_fail(PD_ERR_NOMEM, "out of memory");
            break;
        }
        at[n] = lineno;
        snprintf(v[n++], len, "--%s", t);
        if (*val) {
            at[n] = lineno;
            if ((v[n++] = strdup(val)) == NULL) {
                s = pd_fail(PD_ERR_NOMEM, "out of memory");
                break;
            }
        }
    }
    fclose(in);
    if ((v == NULL || at == NULL) && s == PD_OK)
        s = pd_fail(PD_ERR_NOMEM, "out of memory");
    if (s != PD_OK) {
        for (int k = 0; v && k < n; k++)
            free(v[k]);
        free(v);
        free(at);
        return s;
    }
    *argc = n;
    *argv = v;
    if (lines)
        *lines = at;
    else
        free(at);
    return PD_OK;
}

size_t pd_edit_distance(const char *a, size_t la, const char *b, size_t lb)
{
    enum { MAX = 63 };
    if (la > MAX || lb > MAX)
        return (size_t)-1;
    size_t row[MAX + 1]; /* the distances of a[0..i) to b[0..j), row by row */
    for (size_t j = 0; j <= lb; j++)
        row[j] = j;
    for (size_t i = 1; i <= la; i++) {
        size_t diag = row[0]; /* a[0..i-1) to b[0..j-1) */
        row[0] = i;
        for (size_t j = 1; j <= lb; j++) {
            size_t up = row[j], best = diag + (a[i - 1] != b[j - 1]);
            if (up + 1 < best)
                best = up + 1;
            if (row[j - 1] + 1 < best)
                best = row[j - 1] + 1;
            diag = up;
            row[j] = best;
        }
    }
    return row[lb];
}
