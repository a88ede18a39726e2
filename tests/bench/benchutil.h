/*
 * benchutil.h — the timing harness every benchmark of tests/bench shares: a monotonic clock,
 * and bench_measure, which runs a kernel (one pass over a data set) RUNS times in a row after
 * an untimed warm-up pass and reports the median, fastest and slowest run.
 *
 * With repeat 0 it calibrates: it doubles the passes until they take CALIBRATE_SECONDS, then
 * scales them so that one run takes about TARGET_RUN_SECONDS (at most MAX_REPEAT passes).
 *
 * For latency distributions (one time per request rather than per run), bench_summarize gives
 * the median, mean, fastest and slowest of n times. bench_read_file reads a whole file (the
 * corpus benchmarks' BVH files).
 */
#ifndef AFFECT_BENCHUTIL_H
#define AFFECT_BENCHUTIL_H

#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#define RUNS 5
#define TARGET_RUN_SECONDS 1.0
#define CALIBRATE_SECONDS 0.1
#define MAX_REPEAT 100000

typedef struct result {
    double median, min, max; /* seconds per run */
    unsigned repeat;         /* passes over the data set per run */
} result;

static inline double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static inline int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* pass(arg) runs one pass and returns non-zero on failure (which stops the measurement). */
static inline int bench_measure(int (*pass)(void *arg), void *arg, unsigned repeat, result *r)
{
    if (pass(arg))
        return 1;
    if (repeat == 0) {
        unsigned k = 1;
        double t;
        for (;;) {
            double t0 = now();
            for (unsigned i = 0; i < k; i++)
                if (pass(arg))
                    return 1;
            t = now() - t0;
            if (t >= CALIBRATE_SECONDS || k >= MAX_REPEAT)
                break;
            k *= 2;
        }
        double want = t > 0 ? k * TARGET_RUN_SECONDS / t : MAX_REPEAT;
        repeat = want < 1 ? 1 : want > MAX_REPEAT ? MAX_REPEAT : (unsigned)(want + 0.5);
    }
    double t[RUNS];
    for (int run = 0; run < RUNS; run++) {
        double t0 = now();
        for (unsigned k = 0; k < repeat; k++)
            if (pass(arg))
                return 1;
        t[run] = now() - t0;
    }
    qsort(t, RUNS, sizeof t[0], cmp_double);
    r->median = t[RUNS / 2];
    r->min = t[0];
    r->max = t[RUNS - 1];
    r->repeat = repeat;
    return 0;
}

/* The median (the mean of the two middle values when n is even), mean, fastest and slowest of
 * v[0..n-1], n >= 1; v is sorted in place. */
typedef struct bench_summary {
    double median, mean, min, max;
} bench_summary;

static inline bench_summary bench_summarize(double *v, size_t n)
{
    qsort(v, n, sizeof v[0], cmp_double);
    double sum = 0;
    for (size_t i = 0; i < n; i++)
        sum += v[i];
    bench_summary s = {n % 2 ? v[n / 2] : (v[n / 2 - 1] + v[n / 2]) / 2, sum / (double)n, v[0],
                       v[n - 1]};
    return s;
}

/* The bytes of the file at path plus a terminating NUL (*len: the file's size), or NULL when
 * it cannot be read (errno says why). Free with free(). */
static inline char *bench_read_file(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    char *buf = NULL;
    long size = -1;
    if (fseek(f, 0, SEEK_END) == 0)
        size = ftell(f);
    if (size >= 0 && fseek(f, 0, SEEK_SET) == 0) {
        buf = malloc((size_t)size + 1);
        if (buf && fread(buf, 1, (size_t)size, f) != (size_t)size) {
            free(buf);
            buf = NULL;
        }
    }
    fclose(f);
    if (buf) {
        buf[size] = '\0';
        *len = (size_t)size;
    }
    return buf;
}

#endif
