/*
 * util.c -- checked number parsing, clocks and memory figures shared by the
 * programs.
 */

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "pd.h"

int pd_parse_double(const char *s, double *out)
{
    char *end;
    if (s == NULL || *s == '\0')
        return 0;
    errno = 0;
    double v = strtod(s, &end);
    if (errno != 0 || *end != '\0' || !isfinite(v))
        return 0;
    *out = v;
    return 1;
}

int pd_parse_int64(const char *s, int64_t *out)
{
    char *end;
    if (s == NULL || *s == '\0')
        return 0;
    errno = 0;
    long long v = strtoll(s, &end, 10);
    if (errno != 0 || *end != '\0')
        return 0;
    *out = (int64_t)v;
    return 1;
}

int pd_parse_doubles(const char *s, double *out, int n)
{
    char buf[1024];
    if (s == NULL || strlen(s) >= sizeof buf)
        return 0;
    strcpy(buf, s);
    int k = 0;
    char *save = NULL;
    /* strtok_r skips empty fields, so count commas to catch "1,,2". */
    int commas = 0;
    for (const char *c = s; *c; c++)
        commas += (*c == ',');
    if (commas != n - 1)
        return 0;
    for (char *tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
        if (k >= n || !pd_parse_double(tok, &out[k]))
            return 0;
        k++;
    }
    return k == n;
}

double pd_memory_bytes(void)
{
    long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGE_SIZE);
    if (pages <= 0 || size <= 0)
        return 1e12;
    return (double)pages * (double)size;
}

double pd_wtime(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int64_t pd_peak_rss(void)
{
    struct rusage ru;
    if (getrusage(RUSAGE_SELF, &ru) != 0)
        return 0;
    return (int64_t)ru.ru_maxrss * 1024;
}

void pd_thread_share(int64_t n, int64_t *lo, int64_t *hi)
{
#ifdef _OPENMP
    const int64_t T = omp_get_num_threads(), t = omp_get_thread_num();
#else
    const int64_t T = 1, t = 0;
#endif
    *lo = n * t / T;
    *hi = n * (t + 1) / T;
}

int pd_grow(void **a, int64_t *room, int64_t need, size_t size)
{
    if (need <= *room)
        return 1;
    const int64_t r = need + need / 4 + 64;
    void *p = realloc(*a, (size_t)r * size);
    if (p == NULL)
        return 0;
    *a = p;
    *room = r;
    return 1;
}

double pd_sum_fixed(const double *x, int64_t n)
{
    int64_t nchunks = (n + PD_SUM_CHUNK - 1) / PD_SUM_CHUNK;
    double part[64], total = 0;
    /* groups of 64 chunks: a stack array, the same order at any thread count */
    for (int64_t g = 0; g < nchunks; g += 64) {
        int64_t m = nchunks - g < 64 ? nchunks - g : 64;
#pragma omp parallel for schedule(static)
        for (int64_t c = 0; c < m; c++) {
            int64_t lo = (g + c) * PD_SUM_CHUNK, hi = lo + PD_SUM_CHUNK < n ? lo + PD_SUM_CHUNK : n;
            double sum = 0;
            for (int64_t i = lo; i < hi; i++)
                sum += x[i];
            part[c] = sum;
        }
        for (int64_t c = 0; c < m; c++)
            total += part[c];
    }
    return total;
}

pd_status pd_make_dirs(const char *dir)
{
    char *path = strdup(dir);
    if (path == NULL)
        return pd_fail(PD_ERR_NOMEM, "out of memory");
    pd_status s = PD_OK;
    size_t len = strlen(path);
    for (size_t k = 1; k <= len && s == PD_OK; k++) {
        if (path[k] != '/' && path[k] != '\0')
            continue;
        char keep = path[k];
        path[k] = '\0';
        struct stat st;
        if (stat(path, &st) == 0) {
            if (!S_ISDIR(st.st_mode))
                s = pd_fail(PD_ERR_IO, "cannot make directory '%s': '%s' is not a directory",
                            dir, path);
        } else if (mkdir(path, 0777) != 0 && errno != EEXIST) {
            s = pd_fail(PD_ERR_IO, "cannot make directory '%s': %s", path, strerror(errno));
        }
        path[k] = keep;
    }
    free(path);
    return s;
}

void pd_indenter_centre(const double c0[3], const double v[3], int64_t step, double dt,
                        double c[3])
{
    const double t = (double)step * dt;
    for (int d = 0; d < 3; d++)
        c[d] = c0[d] + t * v[d];
}
