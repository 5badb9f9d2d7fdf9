/* stream.c -- this machine's memory bandwidth, peak double-precision
 * flop rate and divider rate, the roofs of the roofline that
 * share/bench.sh puts pd-run's bond kernel under.  Built by the bench (not
 * part of the library):
 *
 *   cc -O3 -march=native -mprefer-vector-width=512 -ffp-contract=fast \
 *      -fno-math-errno -fopenmp share/stream.c -o stream
 *   ./stream [MIB [REPEATS]]
 *
 * (-mprefer-vector-width=512 where the compiler takes it: GCC's default
 * on Intel's AVX-512 processors is 256-bit vectors, which halves the FMA
 * peak against the 512-bit tiles of the bond kernel; -fno-math-errno lets
 * the square roots be vector instructions.)
 *
 * (1) Triad, after McCalpin's STREAM: a[i] = b[i] + q c[i] over three arrays
 *     of MIB MiB each (default 256: far larger than any cache), OpenMP
 *     static schedule, first touch by the same schedule; 24 bytes counted
 *     per element (two reads, one write; the write-allocate read of a is not
 *     counted, as in STREAM).  Best of REPEATS (default 10).
 * (2) FMA peak: each thread runs NACC independent accumulators x = x m + a
 *     (NACC doubles: eight vector registers' worth, enough to cover the FMA
 *     latency on two pipes), which the compiler turns into packed fused
 *     multiply-adds of the widest vectors -march=native allows; 2 flops per
 *     FMA.  Best of REPEATS.  This is the rate of dependent-free FMAs in
 *     registers only: divisions and square roots (which the bond kernel
 *     has) run far slower, so it is an upper bound no real kernel reaches.
 * (3) Divider: each thread runs NDIV independent chains x = m / sqrt(x)
 *     (m just above 1: x stays near 1, never subnormal), a square root
 *     and then a division of its result per element, as the bond kernel
 *     takes each bond (its length, then the force over the length), in
 *     vectors as (2) has them.  Both run on the one divider unit of a core
 *     (Intel, AMD), and the chains are enough to keep it busy, so this is
 *     the divider's rate of such pairs: a roof of its own for any kernel
 *     with a square root and a division per bond, whatever its FMA count.
 *     Best of REPEATS.
 *
 * Prints, on stdout:
 *   triad_bytes_per_s B
 *   fma_flops_per_s F
 *   sqrt_div_per_s D
 *   threads T
 * and exits 2 on a bad argument, 1 when out of memory. */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>

#if defined(__AVX512F__)
#define NACC 64 /* 8 zmm registers of 8 doubles */
#elif defined(__AVX__)
#define NACC 32 /* 8 ymm registers of 4 doubles */
#else
#define NACC 16 /* 8 xmm registers of 2 doubles */
#endif
#define FMA_ITER 20000000L
#define NDIV (2 * NACC) /* sixteen vector registers: covers the divider's latency */
#define DIV_ITER 1000000L

static double triad(double *a, const double *b, const double *c, long n, double q)
{
    double t0 = omp_get_wtime();
#pragma omp parallel for schedule(static)
    for (long i = 0; i < n; i++)
        a[i] = b[i] + q * c[i];
    return omp_get_wtime() - t0;
}

/* NACC independent chains per thread; returns the sum so nothing is
 * optimized away. */
static double fma_chains(long iter, double m, double s)
{
    double acc[NACC];
    for (int k = 0; k < NACC; k++)
        acc[k] = 1.0 + k * s;
    for (long it = 0; it < iter; it++)
        for (int k = 0; k < NACC; k++)
            acc[k] = acc[k] * m + s;
    double sum = 0;
    for (int k = 0; k < NACC; k++)
        sum += acc[k];
    return sum;
}

/* NDIV independent chains of a square root and a division per thread;
 * returns the sum. */
static double div_chains(long iter, double m, double s)
{
    double x[NDIV];
    for (int k = 0; k < NDIV; k++)
        x[k] = 1.0 + k * s;
    for (long it = 0; it < iter; it++)
        for (int k = 0; k < NDIV; k++)
            x[k] = m / sqrt(x[k]);
    double sum = 0;
    for (int k = 0; k < NDIV; k++)
        sum += x[k];
    return sum;
}

/* The best of `reps` runs of chain(iter, m, s) on every thread (s set
 * apart by thread), seconds; the chains' sums into *sink. */
static double best_time(double (*chain)(long, double, double), long iter, double m, int reps,
                        double *sink)
{
    double best = 1e300;
    for (int r = 0; r < reps; r++) {
        double t0 = omp_get_wtime(), s = 0;
#pragma omp parallel reduction(+ : s)
        s += chain(iter, m, 1e-9 * (1 + omp_get_thread_num()));
        double t = omp_get_wtime() - t0;
        best = t < best ? t : best;
        *sink += s;
    }
    return best;
}

static long arg(const char *s, long lo, long hi, const char *what)
{
    char *end;
    long v = strtol(s, &end, 10);
    if (*s == '\0' || *end != '\0' || v < lo || v > hi) {
        fprintf(stderr, "stream: error: %s must be an integer in [%ld, %ld], not '%s'\n", what,
                lo, hi, s);
        exit(2);
    }
    return v;
}

int main(int argc, char **argv)
{
    if (argc > 3) {
        fprintf(stderr, "usage: stream [MIB [REPEATS]]\n");
        return 2;
    }
    long mib = argc > 1 ? arg(argv[1], 1, 65536, "MIB") : 256;
    int reps = argc > 2 ? (int)arg(argv[2], 1, 1000, "REPEATS") : 10;
    long n = mib * 1048576L / (long)sizeof(double);
    double *a = malloc((size_t)n * sizeof(double));
    double *b = malloc((size_t)n * sizeof(double));
    double *c = malloc((size_t)n * sizeof(double));
    if (!a || !b || !c) {
        fprintf(stderr, "stream: error: out of memory for 3 x %ld MiB\n", mib);
        return 1;
    }
#pragma omp parallel for schedule(static)
    for (long i = 0; i < n; i++) {
        a[i] = 0;
        b[i] = 1;
        c[i] = 2;
    }
    double best = 1e300;
    for (int r = 0; r < reps; r++) {
        double t = triad(a, b, c, n, 3.0);
        best = t < best ? t : best;
    }
    double bw = 24.0 * (double)n / best;

    int threads = omp_get_max_threads();
    double sink = 0;
    long iter = FMA_ITER / (mib < 256 ? 256 / mib : 1); /* a quick check stays quick */
    double flops =
        2.0 * NACC * (double)iter * threads / best_time(fma_chains, iter, 0.9999999, reps, &sink);
    long diter = DIV_ITER / (mib < 256 ? 256 / mib : 1);
    double pairs =
        (double)NDIV * (double)diter * threads / best_time(div_chains, diter, 1.0000001, reps, &sink);

    printf("triad_bytes_per_s %.6g\n", bw);
    printf("fma_flops_per_s %.6g\n", flops);
    printf("sqrt_div_per_s %.6g\n", pairs);
    printf("threads %d\n", threads);
    if (sink != sink) /* never: keeps the chains' results live */
        printf("nan\n");
    free(a);
    free(b);
    free(c);
    return 0;
}
