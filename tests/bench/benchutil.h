/*
 * benchutil.h — the timing harness every benchmark of tests/bench shares: a monotonic clock,
 * and bench_measure, which runs a kernel (one pass over a data set) RUNS times in a row after
 * an untimed warm-up pass and reports the median, fastest and slowest run.
 *
 * With repeat 0 it calibrates: it doubles the passes until they take CALIBRATE_SECONDS, then
 * scales them so that one run takes about TARGET_RUN_SECONDS (at most MAX_REPEAT passes).
 *
 * For latency distributions (one time per request rather than per run), bench_summarize gives
 * the median, mean, fastest and slowest of n times. bench_read_file reads a whole file and
 * bench_list_files lists a folder's files by suffix, sorted, and bench_load_texts reads them all
 * (the corpus benchmarks' BVH files); bench_load_items reads them into a benchmark's own items.
 * Each run's process CPU time is read too (a shared machine slows a run without it waiting).
 *
 * Command lines: bench_parse_count reads a count option (--repeat N and the like),
 * bench_dir_args the plain "[corpus directory] [--repeat N]" of several benchmarks. Messages
 * start with BENCH_NAME (define it before including this header; default "bench").
 *
 * SQL (only when <sqlite3.h> is included before this header): bench_exec, bench_prepare and
 * bench_query_int run a statement and print SQLite's message with the SQL on failure.
 */
#ifndef AFFECT_BENCHUTIL_H
#define AFFECT_BENCHUTIL_H

#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#ifndef BENCH_NAME
#define BENCH_NAME "bench"
#endif

#define RUNS 5
#define TARGET_RUN_SECONDS 1.0
#define CALIBRATE_SECONDS 0.1
#define MAX_REPEAT 100000

typedef struct result {
    double median, min, max; /* seconds per run (wall clock) */
    unsigned repeat;         /* passes over the data set per run */
    double cpu_median;       /* the median run's process CPU time, seconds */
    double busy;             /* CPU time over wall time summed over the runs: below 1 when the
                                process waited (other jobs on its core) */
} result;

static inline double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static inline double cpu_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
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
    double t[RUNS], cpu[RUNS], sum_wall = 0, sum_cpu = 0;
    for (int run = 0; run < RUNS; run++) {
        double t0 = now(), c0 = cpu_now();
        for (unsigned k = 0; k < repeat; k++)
            if (pass(arg))
                return 1;
        cpu[run] = cpu_now() - c0;
        t[run] = now() - t0;
        sum_wall += t[run];
        sum_cpu += cpu[run];
    }
    qsort(t, RUNS, sizeof t[0], cmp_double);
    qsort(cpu, RUNS, sizeof cpu[0], cmp_double);
    r->median = t[RUNS / 2];
    r->min = t[0];
    r->max = t[RUNS - 1];
    r->cpu_median = cpu[RUNS / 2];
    r->busy = sum_wall > 0 ? sum_cpu / sum_wall : 1;
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

static inline int bench_cmp_string(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

/* The names of the files in dir ending with suffix, sorted (bytewise), in *names (*n of them;
 * free each and the array). Returns 0, 1 when dir cannot be opened, 2 when out of memory. */
static inline int bench_list_files(const char *dir, const char *suffix, char ***names, size_t *n)
{
    *names = NULL;
    *n = 0;
    DIR *d = opendir(dir);
    if (!d)
        return 1;
    size_t cap = 0, k = strlen(suffix);
    int rc = 0;
    struct dirent *e;
    while (!rc && (e = readdir(d)) != NULL) {
        size_t len = strlen(e->d_name);
        if (len < k || strcmp(e->d_name + len - k, suffix) != 0)
            continue;
        if (*n == cap) {
            cap = cap ? 2 * cap : 256;
            char **grown = realloc(*names, cap * sizeof *grown);
            if (!grown) {
                rc = 2;
                break;
            }
            *names = grown;
        }
        (*names)[*n] = malloc(len + 1);
        if (!(*names)[*n]) {
            rc = 2;
            break;
        }
        memcpy((*names)[*n], e->d_name, len + 1);
        (*n)++;
    }
    closedir(d);
    if (!rc)
        qsort(*names, *n, sizeof **names, bench_cmp_string);
    return rc;
}

/* One file of bench_load_texts: its name (not the path), its bytes NUL-terminated, their count. */
typedef struct bench_text {
    char *name;
    char *text;
    size_t len;
} bench_text;

/* Reads every file of dir ending with suffix, sorted by name, into *out (*n of them; free each
 * name and text, then the array); *bytes receives the total size. Returns 0, 1 when dir cannot
 * be opened, 2 on any other error (a file that cannot be read is named on stderr). */
static inline int bench_load_texts(const char *dir, const char *suffix, bench_text **out, size_t *n,
                                   size_t *bytes)
{
    char **names;
    size_t count;
    *out = NULL;
    *n = *bytes = 0;
    int rc = bench_list_files(dir, suffix, &names, &count);
    if (rc)
        return rc;
    bench_text *t = calloc(count ? count : 1, sizeof *t);
    char path[4096];
    for (size_t i = 0; i < count; i++) {
        if (!rc && !t)
            rc = 2;
        if (rc) {
            free(names[i]);
            continue;
        }
        snprintf(path, sizeof path, "%s/%s", dir, names[i]);
        t[*n].name = names[i];
        t[*n].text = bench_read_file(path, &t[*n].len);
        if (!t[*n].text) {
            fprintf(stderr, "cannot read %s: %s\n", path, strerror(errno));
            free(names[i]);
            rc = 2;
            continue;
        }
        *bytes += t[*n].len;
        (*n)++;
    }
    free(names);
    *out = t;
    return rc;
}

static inline void bench_free_text(bench_text *t)
{
    free(t->name);
    free(t->text);
}

/* bench_load_texts into *items: n items of item_size bytes each (calloc'ed; free each item's
 * text with bench_free_text, then the array), an item being a struct whose first member is the
 * bench_text of its file. Returns as bench_load_texts (2 also when out of memory); the items
 * read are there (*n of them) even on failure. */
static inline int bench_load_items(const char *dir, const char *suffix, size_t item_size,
                                   void **items, size_t *n, size_t *bytes)
{
    bench_text *t;
    size_t count;
    int rc = bench_load_texts(dir, suffix, &t, &count, bytes);
    unsigned char *it = t ? calloc(count ? count : 1, item_size) : NULL;
    if (!rc && !it)
        rc = 2;
    for (size_t i = 0; i < count; i++) {
        if (it)
            memcpy(it + i * item_size, &t[i], sizeof t[i]);
        else
            bench_free_text(&t[i]);
    }
    *items = it;
    *n = it ? count : 0;
    free(t);
    return rc;
}

/* ---- command lines ---- */

/* *out = the count v (a whole number from 1 to max), or 1 with a message. */
static inline int bench_parse_count(const char *flag, const char *v, unsigned max, unsigned *out)
{
    char *end;
    long n = strtol(v, &end, 10);
    if (*end != '\0' || n < 1 || n > (long)max) {
        fprintf(stderr, BENCH_NAME ": %s must be from 1 to %u\n", flag, max);
        return 1;
    }
    *out = (unsigned)n;
    return 0;
}

/* "[corpus directory] [--repeat N]": *dir (unchanged when not given) and *repeat (0 when not
 * given: calibrate). 0, or 2 with a message (the exit status of a bad command line). */
static inline int bench_dir_args(int argc, char **argv, const char **dir, unsigned *repeat)
{
    *repeat = 0;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--repeat") == 0 && i + 1 < argc) {
            if (bench_parse_count("--repeat", argv[++i], MAX_REPEAT, repeat))
                return 2;
        } else if (argv[i][0] == '-') {
            fprintf(stderr, "usage: %s [corpus directory] [--repeat N]\n", argv[0]);
            return 2;
        } else {
            *dir = argv[i];
        }
    }
    return 0;
}

/* ---- SQL ---- */
#ifdef SQLITE_VERSION

/* Runs sql (any number of statements); 0, or 1 with SQLite's message and the SQL. */
static inline int bench_exec(sqlite3 *db, const char *sql)
{
    char *err = NULL;
    if (sqlite3_exec(db, sql, NULL, NULL, &err) != SQLITE_OK) {
        fprintf(stderr, BENCH_NAME ": %s\n  in: %.300s\n", err ? err : sqlite3_errmsg(db), sql);
        sqlite3_free(err);
        return 1;
    }
    return 0;
}

/* Prepares one statement; 0, or 1 with SQLite's message and the SQL. */
static inline int bench_prepare(sqlite3 *db, const char *sql, sqlite3_stmt **st)
{
    if (sqlite3_prepare_v2(db, sql, -1, st, NULL) != SQLITE_OK) {
        fprintf(stderr, BENCH_NAME ": %s\n  in: %.300s\n", sqlite3_errmsg(db), sql);
        return 1;
    }
    return 0;
}

/* One integer from a query of one row; 0, or 1 with a message. */
static inline int bench_query_int(sqlite3 *db, const char *sql, sqlite3_int64 *out)
{
    sqlite3_stmt *st = NULL;
    if (bench_prepare(db, sql, &st))
        return 1;
    int rc = sqlite3_step(st);
    if (rc == SQLITE_ROW)
        *out = sqlite3_column_int64(st, 0);
    else
        fprintf(stderr, BENCH_NAME ": %s\n  in: %.300s\n", sqlite3_errmsg(db), sql);
    sqlite3_finalize(st);
    return rc != SQLITE_ROW;
}

#endif
#endif
