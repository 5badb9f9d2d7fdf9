/*
 * series_io.c -- the time series of a run in its file (man 5 pd-h5):
 *
 *   /series          group; attributes columns (one string: the column
 *                    names, pd_series_columns, separated by single spaces)
 *                    and rows (int64: the complete rows)
 *   /series/values   float64 (capacity, ncols), laid out before the first
 *                    step for every row the run will write
 *
 * A row is written in place, the file flushed, and only then counted in
 * rows: a run killed at any moment leaves a file whose counted rows are
 * whole (as its frames, schema.c).  A restart keeps the rows of the steps
 * up to the frame it goes on from, lays the series out again for the rows
 * it will add, and writes them from there: the series of a restarted run
 * is that of the run never stopped, for the same --series.
 */
#include <stdlib.h>
#include <string.h>

#include "base/comm.h"
#include "io/h5util.h"

struct pd_series_plan {
    int64_t *steps; /* the steps of the rows still to write, ascending */
    int64_t nsteps;
    int64_t next;   /* of steps: the next to write                       */
    int64_t base;   /* rows kept before steps[0] (a restart's)           */
    int ncols;
};

void pd_series_plan_free(struct pd_series_plan *plan)
{
    if (plan)
        free(plan->steps);
    free(plan);
}

void pd_series_free(pd_series *s)
{
    free(s->name);
    free(s->value);
    memset(s, 0, sizeof *s);
}

int pd_series_column(const pd_series *s, const char *name)
{
    for (int k = 0; k < s->ncols; k++)
        if (strcmp(s->name[k], name) == 0)
            return k;
    return -1;
}

/* The names joined by spaces, malloc'ed (NULL when out of memory). */
static char *join(int ncols, const char (*names)[PD_SERIES_NAME])
{
    size_t len = 1;
    for (int k = 0; k < ncols; k++)
        len += strlen(names[k]) + 1;
    char *text = malloc(len);
    if (text == NULL)
        return NULL;
    char *p = text;
    *p = '\0';
    for (int k = 0; k < ncols; k++)
        p += sprintf(p, "%s%s", k ? " " : "", names[k]);
    return text;
}

/* The column names of a `columns` attribute's text, checked. */
static pd_status split(const char *file, const char *text, pd_series *s)
{
    int n = 0;
    for (const char *p = text; *p;) {
        size_t len = strcspn(p, " ");
        if (len == 0 || len >= PD_SERIES_NAME)
            return pd_fail(PD_ERR_FORMAT, "'%s': /series@columns is not a list of names", file);
        n++;
        p += len;
        p += *p == ' ';
    }
    if (n == 0 || (s->name = calloc((size_t)n, sizeof *s->name)) == NULL)
        return n == 0 ? pd_fail(PD_ERR_FORMAT, "'%s': /series has no columns", file)
                      : pd_fail(PD_ERR_NOMEM, "out of memory");
    s->ncols = n;
    int k = 0;
    for (const char *p = text; *p; k++) {
        size_t len = strcspn(p, " ");
        memcpy(s->name[k], p, len);
        p += len;
        p += *p == ' ';
    }
    if (strcmp(s->name[0], "step") != 0)
        return pd_fail(PD_ERR_FORMAT, "'%s': /series's first column is not the step", file);
    for (int a = 0; a < n; a++)
        for (int b = a + 1; b < n; b++)
            if (strcmp(s->name[a], s->name[b]) == 0)
                return pd_fail(PD_ERR_FORMAT, "'%s': /series has two columns '%s'", file,
                               s->name[a]);
    return PD_OK;
}

/* Read the group's columns and its first `rows` rows (all: -1). */
static pd_status read_series(hid_t fid, const char *file, int64_t rows, pd_series *s)
{
    memset(s, 0, sizeof *s);
    if (!pd_h5_has_link(fid, "/series"))
        return pd_fail(PD_ERR_FORMAT, "'%s' has no time series (/series): a run of pd-run "
                                      "before --series",
                       file);
    hid_t g = H5Gopen2(fid, "/series", H5P_DEFAULT);
    if (g < 0)
        return pd_fail(PD_ERR_FORMAT, "'%s': /series is not a group", file);
    char *text = NULL;
    int64_t count = 0;
    pd_status st = pd_h5_read_attr_string(g, "columns", &text);
    if (st == PD_OK)
        st = split(file, text, s);
    if (st == PD_OK)
        st = pd_h5_read_attr_int(g, "rows", &count);
    free(text);
    hsize_t dims[2] = {0, 0};
    if (st == PD_OK) {
        pd_h5_form form = {H5T_FLOAT, 8, 2, {0, (hsize_t)s->ncols}};
        st = pd_h5_read_data(g, file, "values", &form, H5T_NATIVE_DOUBLE, sizeof(double),
                             (void **)&s->value, dims);
    }
    H5Gclose(g);
    if (st == PD_OK && (count < 0 || (hsize_t)count > dims[0]))
        st = pd_fail(PD_ERR_FORMAT, "'%s': /series@rows is %lld, /series/values holds %llu",
                     file, (long long)count, (unsigned long long)dims[0]);
    if (st == PD_OK) {
        s->nrows = rows >= 0 && rows < count ? rows : count;
        for (int64_t r = 1; r < s->nrows && st == PD_OK; r++)
            if (!(s->value[r * s->ncols] > s->value[(r - 1) * s->ncols]))
                st = pd_fail(PD_ERR_FORMAT, "'%s': /series's steps are not ascending at row %lld",
                             file, (long long)r);
    }
    if (st != PD_OK)
        pd_series_free(s);
    return st;
}

pd_status pd_read_series(const pd_file *f, pd_series *out)
{
    return read_series(f->fid, f->name, -1, out);
}

/* The group with a values dataset of `capacity` rows, its first `kept`
 * rows those of `old` (may be NULL). */
static pd_status lay_out(hid_t fid, const char *columns, int ncols, int64_t capacity,
                         const pd_series *old, int64_t kept)
{
    hid_t g = pd_h5_create_group(fid, "/series");
    if (g < 0)
        return pd_fail(PD_ERR_IO, "cannot create /series (disk full?)");
    hsize_t dims[2] = {(hsize_t)(capacity > 0 ? capacity : 1), (hsize_t)ncols};
    pd_status s = pd_h5_write_attr_string(g, "columns", columns);
    if (s == PD_OK)
        s = pd_h5_write_attr_int(g, "rows", kept);
    if (s == PD_OK)
        s = pd_h5_reserve_data(g, "values", H5T_IEEE_F64LE, 2, dims);
    if (s == PD_OK && kept > 0) /* one writer (rank 0 of a parallel file) */
        s = pd_h5_write_rows(g, "values", H5T_NATIVE_DOUBLE, old->value, 0,
                             pd_h5_writes_whole(g) ? kept : 0);
    H5Gclose(g);
    return s;
}

pd_status pd_plan_series(pd_file *f, const pd_scene *sc, int64_t first, int fresh)
{
    pd_series_plan_free(f->series);
    f->series = NULL;
    const int64_t m = pd_series_steps(sc, first, fresh, NULL);
    if (m == 0)
        return PD_OK;
    const int ncols = pd_series_columns(sc, NULL);
    char(*names)[PD_SERIES_NAME] = calloc((size_t)ncols, sizeof *names);
    struct pd_series_plan *plan = calloc(1, sizeof *plan);
    if (plan == NULL || names == NULL ||
        (plan->steps = malloc((size_t)m * sizeof *plan->steps)) == NULL) {
        free(names);
        pd_series_plan_free(plan);
        return pd_fail(PD_ERR_NOMEM, "out of memory for the time series");
    }
    pd_series_steps(sc, first, fresh, plan->steps);
    pd_series_columns(sc, names);
    plan->nsteps = m;
    plan->ncols = ncols;
    char *columns = join(ncols, (const char(*)[PD_SERIES_NAME])names);
    free(names);
    pd_series old;
    memset(&old, 0, sizeof old);
    pd_status s = columns ? PD_OK : pd_fail(PD_ERR_NOMEM, "out of memory");
    /* a restart keeps the rows up to its first step, of the same columns */
    if (s == PD_OK && !fresh && pd_h5_has_link(f->fid, "/series")) {
        s = read_series(f->fid, f->name, -1, &old);
        if (s == PD_OK) {
            char *had = join(old.ncols, (const char(*)[PD_SERIES_NAME])old.name);
            if (had == NULL)
                s = pd_fail(PD_ERR_NOMEM, "out of memory");
            else if (strcmp(had, columns) != 0)
                s = pd_fail(PD_ERR_FORMAT,
                            "'%s': the run's time series has other columns than this scene's",
                            f->name);
            free(had);
        }
        while (s == PD_OK && plan->base < old.nrows &&
               old.value[plan->base * old.ncols] <= (double)first)
            plan->base++;
        if (s == PD_OK && H5Ldelete(f->fid, "/series", H5P_DEFAULT) < 0)
            s = pd_fail(PD_ERR_IO, "cannot replace /series");
    }
    if (s == PD_OK)
        s = lay_out(f->fid, columns, ncols, plan->base + m, &old, plan->base);
    pd_series_free(&old);
    free(columns);
    if (s == PD_OK)
        f->series = plan;
    else
        pd_series_plan_free(plan);
    return s;
}

int pd_run_file_sample_due(const pd_file *out, int64_t step)
{
    const struct pd_series_plan *plan = out->series;
    return plan && plan->next < plan->nsteps && plan->steps[plan->next] == step;
}

pd_status pd_run_file_sample(pd_file *out, const pd_sim *sim, const pd_energy *e)
{
    return pd_run_file_sample_damage(out, sim, e, NULL);
}

pd_status pd_run_file_sample_damage(pd_file *out, const pd_sim *sim, const pd_energy *e,
                                    const double *damage)
{
    struct pd_series_plan *plan = out->series;
    if (!pd_run_file_sample_due(out, pd_sim_stepno(sim)))
        return PD_OK;
    double *row = malloc((size_t)plan->ncols * sizeof(double));
    if (row == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory for the time series");
    pd_status s = pd_sim_series_row_damage(sim, e, damage, row); /* collective on MPI ranks */
    if (out->ranks > 1)
        s = pd_comm_agree(s);
    const int64_t at = plan->base + plan->next;
    hid_t g = s == PD_OK ? H5Gopen2(out->fid, "/series", H5P_DEFAULT) : H5I_INVALID_HID;
    if (s == PD_OK && g < 0)
        s = pd_fail(PD_ERR_IO, "'%s': cannot open /series", out->name);
    if (s == PD_OK) /* one writer (rank 0 of a parallel file) */
        s = pd_h5_write_rows(g, "values", H5T_NATIVE_DOUBLE, row, at,
                             pd_h5_writes_whole(g) ? 1 : 0);
    /* the row on disk first, then counted */
    if (s == PD_OK && H5Fflush(out->fid, H5F_SCOPE_LOCAL) < 0)
        s = pd_fail(PD_ERR_IO, "cannot flush '%s' (disk full?)", out->name);
    const int64_t rows = at + 1;
    if (s == PD_OK)
        s = pd_h5_update_attr(g, "rows", H5T_NATIVE_INT64, &rows);
    if (g >= 0)
        H5Gclose(g);
    free(row);
    if (s == PD_OK)
        plan->next++;
    return s;
}
