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

static pd_status scene_stream(FILE *in, const char *path, int *argc, char ***argv);

pd_status pd_scene_args(const char *path, int *argc, char ***argv)
{
    FILE *in = fopen(path, "r");
    if (in == NULL)
        return pd_fail(PD_ERR_IO, "cannot open scene '%s': %s", path, strerror(errno));
    return scene_stream(in, path, argc, argv);
}

pd_status pd_scene_args_text(const char *text, const char *name, int *argc, char ***argv)
{
    FILE *in = fmemopen((void *)text, strlen(text), "r");
    if (in == NULL)
        return pd_fail(PD_ERR_NOMEM, "cannot read the scene of '%s'", name);
    return scene_stream(in, name, argc, argv);
}

static pd_status scene_stream(FILE *in, const char *path, int *argc, char ***argv)
{
    int n = 0, cap = 16;
    char **v = malloc((size_t)cap * sizeof *v);
    char line[4096];
    int lineno = 0;
    pd_status s = PD_OK;
    while (v && s == PD_OK && fgets(line, sizeof line, in)) {
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
            if (nv == NULL) {
                s = pd_fail(PD_ERR_NOMEM, "out of memory");
                break;
            }
            v = nv;
        }
        size_t len = strlen(t) + 3;
        v[n] = malloc(len);
        if (v[n] == NULL) {
            s = pd_fail(PD_ERR_NOMEM, "out of memory");
            break;
        }
        snprintf(v[n++], len, "--%s", t);
        if (*val)
            v[n++] = strdup(val);
    }
    fclose(in);
    if (v == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory");
    if (s != PD_OK) {
        for (int k = 0; k < n; k++)
            free(v[k]);
        free(v);
        return s;
    }
    *argc = n;
    *argv = v;
    return PD_OK;
}
