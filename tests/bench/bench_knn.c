/*
 * bench_knn.c — the laban virtual table (ext/vt_laban.c) over 10,000 motions: how fast the index
 * is built and how long a nearest-neighbour query takes, next to the same queries written as
 * brute-force SQL over the table's cached columns.
 *
 * Usage:
 *     bench_knn [module path] [--rounds N]
 *     bash tests/bench/run.sh            # Release build, pinned to one core, prints the results
 * The module defaults to AFFECT_BENCH_MODULE (the built affect.so, set by
 * tests/bench/CMakeLists.txt). When it cannot be loaded or has no laban module the program says
 * so and exits 0, so an incomplete build is not a failure.
 *
 * Set-up (in an in-memory database, so no disk in the numbers):
 *     motions   10,000 rows: motion_synth(action, emotion, seed, '{"fps":10}') for 4 actions ×
 *               4 emotions × seeds 1..625 (10 fps keeps the build short; the query cost does
 *               not depend on the motions' length, only on their number);
 *     queries   N_QUERIES fresh motions (seeds 626 on, not in the index) for the BLOB queries.
 * Index build: CREATE VIRTUAL TABLE motion_laban USING laban(content=motions, motion=motion,
 * label=emotion) — reading, decoding and describing every motion and writing the shadow
 * tables — timed like every benchmark here: one untimed warm-up build, then 5 timed builds
 * (each followed by an untimed DROP TABLE), the median reported as motions/s. Next to it, the
 * same way, the part of it that is Laban descriptors:
 *     SELECT sum(length(laban_vector(motion, '{"missing":"null"}'))) FROM motions
 * Queries, each a prepared statement with ?1 bound to one of N_QUERIES different query rows
 * (rowid 1 + 7919·i mod 10000, all distinct) or query motions:
 *     (a) rowid k=5    WHERE query = ?1 AND label = 'angry' AND k = 5    (?1 a rowid)
 *     (b) blob k=5     the same with ?1 a motion BLOB: decode + its Laban vector + the search;
 *                      laban_vector(?1, '{"missing":"null"}') alone is timed as (b0);
 *     (c) radius 0.1   WHERE query = ?1 AND label = 'angry' AND radius = 0.1
 *     (d) 2 comps k=5  WHERE query = ?1 AND label = 'angry' AND k = 5
 *                      AND components = '["TimeAll","FlowAll"]'
 *     (e) 1 candidate  WHERE query = ?1 AND rowid = ?1 % 10000 + 1 AND k = 1: (a) with the
 *                      search restricted to one row, i.e. the fixed cost of a query (statement,
 *                      the index's generation check, cursor) without the distance loop
 * and their peers in plain SQL: the standardized Euclidean distance computed per row from the
 * virtual table's 27 columns with mean and sd from motion_laban_info (JSON arrays: what the table
 * divides by), missing components skipped, ORDER BY distance, rowid LIMIT 5 (or the radius
 * ball). Before timing, every query runs once in both forms and the answers are compared:
 * rowids and distances must be identical (for (b) the table rounds the query's vector to float32
 * and laban() does not, so distances there may differ in the 7th digit; rowids must agree).
 * That pass is also the warm-up. A run is the N_QUERIES queries repeated `rounds` times (chosen
 * so that a run takes about a second, at least once); per run the median and 95th percentile of
 * the single-query latencies; 5 runs, the median run reported with the fastest and slowest
 * run's median. clock_gettime(CLOCK_MONOTONIC) around bind, every step and reset.
 * Output: tables for people, then one line per metric for scripts:
 *     BENCH <metric> <value> <unit>
 * Exit status 1 if a statement fails or the two forms disagree.
 */
#define _POSIX_C_SOURCE 200809L

#include <sqlite3.h>

#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define BENCH_NAME "bench_knn"
#include "benchutil.h"

#ifndef AFFECT_BENCH_MODULE
#define AFFECT_BENCH_MODULE "build-bench/affect.so"
#endif

#define MAX_ROUNDS 1000
#define N_MOTIONS 10000
#define N_SEEDS 625 /* × 4 actions × 4 emotions */
#define N_QUERIES 250
#define MAX_HITS 10000
#define TARGET_MS 2.0
#define N_COMP 27
#define STR(x) #x
#define XSTR(x) STR(x)

typedef struct knn_result {
    double median, p95;      /* of the median run: seconds per query */
    double run_min, run_max; /* fastest and slowest run's median */
    unsigned per_run;        /* queries per run */
    double rows;             /* mean rows returned per query */
} knn_result;

typedef struct hit {
    sqlite3_int64 id;
    double d;
} hit;

/* The query inputs: rowids and motion BLOBs. */
typedef struct inputs {
    sqlite3_int64 rowid[N_QUERIES];
    void *blob[N_QUERIES];
    int blob_len[N_QUERIES];
} inputs;

/* A growing string for the generated SQL. */
typedef struct sbuf {
    char *s;
    size_t n, cap;
    bool failed;
} sbuf;

static volatile double g_sink;

static void sb_add(sbuf *b, const char *fmt, ...)
{
    if (b->failed)
        return;
    for (;;) {
        va_list ap;
        va_start(ap, fmt);
        int k = vsnprintf(b->s ? b->s + b->n : NULL, b->s ? b->cap - b->n : 0, fmt, ap);
        va_end(ap);
        if (k < 0) {
            b->failed = true;
            return;
        }
        if (b->s && b->n + (size_t)k < b->cap) {
            b->n += (size_t)k;
            return;
        }
        size_t cap = (b->cap ? 2 * b->cap : 4096) + (size_t)k;
        char *grown = realloc(b->s, cap);
        if (!grown) {
            b->failed = true;
            return;
        }
        b->s = grown;
        b->cap = cap;
    }
}

/* Runs st with ?1 bound to query i (a rowid, or a BLOB when blob); collects up to MAX_HITS
 * (rowid, distance) rows into out (NULL: only count). Returns the row count, −1 on error. */
static long run_one(sqlite3 *db, sqlite3_stmt *st, const inputs *in, int i, bool blob, hit *out)
{
    int rc = blob ? sqlite3_bind_blob(st, 1, in->blob[i], in->blob_len[i], SQLITE_STATIC)
                  : sqlite3_bind_int64(st, 1, in->rowid[i]);
    long n = 0;
    if (rc == SQLITE_OK) {
        while ((rc = sqlite3_step(st)) == SQLITE_ROW) {
            if (out && n < MAX_HITS) {
                out[n].id = sqlite3_column_int64(st, 0);
                out[n].d = sqlite3_column_double(st, 1);
            } else {
                g_sink += sqlite3_column_double(st, 1);
            }
            n++;
        }
    }
    if (rc != SQLITE_DONE) {
        fprintf(stderr, "query %d: %s\n", i, sqlite3_errmsg(db));
        n = -1;
    }
    sqlite3_reset(st);
    return n;
}

/* Times the N_QUERIES queries, `rounds` at a time per run (0: calibrate from one pass). */
static int measure(sqlite3 *db, sqlite3_stmt *st, const inputs *in, bool blob, unsigned rounds,
                   knn_result *r)
{
    if (rounds == 0) {
        double t0 = now();
        for (int i = 0; i < N_QUERIES; i++)
            if (run_one(db, st, in, i, blob, NULL) < 0)
                return 1;
        double t = now() - t0;
        double want = t > 0 ? TARGET_RUN_SECONDS / t : MAX_ROUNDS;
        rounds = want < 1 ? 1 : want > MAX_ROUNDS ? MAX_ROUNDS : (unsigned)(want + 0.5);
    }
    size_t per_run = (size_t)rounds * N_QUERIES;
    double *lat = malloc(per_run * sizeof *lat);
    if (!lat) {
        fprintf(stderr, "out of memory\n");
        return 1;
    }
    double med[RUNS], p95[RUNS];
    long rows = 0;
    int rc = 0;
    for (int run = 0; run < RUNS && !rc; run++) {
        for (size_t q = 0; q < per_run; q++) {
            double t0 = now();
            long n = run_one(db, st, in, (int)(q % N_QUERIES), blob, NULL);
            lat[q] = now() - t0;
            if (n < 0) {
                rc = 1;
                break;
            }
            if (run == 0)
                rows += n;
        }
        qsort(lat, per_run, sizeof *lat, cmp_double);
        med[run] = per_run % 2 ? lat[per_run / 2] : (lat[per_run / 2 - 1] + lat[per_run / 2]) / 2;
        p95[run] = lat[(size_t)ceil(0.95 * (double)per_run) - 1];
    }
    free(lat);
    if (rc)
        return 1;
    /* the median run by its median latency; its p95 goes with it */
    int order[RUNS];
    for (int i = 0; i < RUNS; i++)
        order[i] = i;
    for (int i = 1; i < RUNS; i++)
        for (int j = i; j > 0 && med[order[j]] < med[order[j - 1]]; j--) {
            int t = order[j];
            order[j] = order[j - 1];
            order[j - 1] = t;
        }
    r->median = med[order[RUNS / 2]];
    r->p95 = p95[order[RUNS / 2]];
    r->run_min = med[order[0]];
    r->run_max = med[order[RUNS - 1]];
    r->per_run = (unsigned)per_run;
    r->rows = (double)rows / (double)per_run;
    return 0;
}

/* Runs every query in both forms and compares the answers (exact unless tolerant). Also the
 * warm-up. */
static int verify(sqlite3 *db, sqlite3_stmt *vt, sqlite3_stmt *bf, const inputs *in, bool blob,
                  bool tolerant, const char *what)
{
    static hit a[MAX_HITS], b[MAX_HITS];
    double worst = 0;
    for (int i = 0; i < N_QUERIES; i++) {
        long na = run_one(db, vt, in, i, blob, a), nb = run_one(db, bf, in, i, blob, b);
        if (na < 0 || nb < 0)
            return 1;
        if (na != nb || na == 0) {
            fprintf(stderr, "%s, query %d: the table gave %ld rows, the SQL %ld\n", what, i, na,
                    nb);
            return 1;
        }
        for (long j = 0; j < na && j < MAX_HITS; j++) {
            double rel = fabs(a[j].d - b[j].d) / fmax(fabs(b[j].d), 1e-300);
            if (a[j].id != b[j].id || (tolerant ? rel > 1e-5 : a[j].d != b[j].d)) {
                fprintf(stderr,
                        "%s, query %d, row %ld: the table gave %lld at %.17g, the SQL "
                        "%lld at %.17g\n",
                        what, i, j, (long long)a[j].id, a[j].d, (long long)b[j].id, b[j].d);
                return 1;
            }
            worst = fmax(worst, rel);
        }
    }
    printf("  %-16s table and SQL agree on all %d queries (%s; largest relative distance "
           "difference %.1e)\n",
           what, N_QUERIES, tolerant ? "same rowids" : "same rowids, same distances", worst);
    return 0;
}

/* The brute-force peer. query: "rowid" (the vtab's cached row, left out of the results) or
 * "blob" (laban(?1) of a motion); comps: component indices; radius 0 means k nearest. */
static char *brute_sql(char names[N_COMP][32], const char *query, const int *comps, int nc, int k,
                       double radius)
{
    sbuf b = {0};
    sb_add(&b, "WITH st AS MATERIALIZED (SELECT ");
    for (int t = 0; t < nc; t++)
        sb_add(&b, "%sjson_extract(m.value, '$[%d]') AS m%d, json_extract(s.value, '$[%d]') AS s%d",
               t ? ", " : "", comps[t], comps[t], comps[t], comps[t]);
    sb_add(&b, " FROM motion_laban_info m, motion_laban_info s "
               "WHERE m.key = 'mean' AND s.key = 'sd'), q AS MATERIALIZED (SELECT ");
    for (int t = 0; t < nc; t++) {
        int c = comps[t];
        if (strcmp(query, "rowid") == 0)
            sb_add(&b, "%s(%s - m%d) / s%d AS z%d", t ? ", " : "", names[c], c, c, c);
        else
            sb_add(&b, "%s(json_extract(j, '$.%s') - m%d) / s%d AS z%d", t ? ", " : "", names[c], c,
                   c, c);
    }
    if (strcmp(query, "rowid") == 0)
        sb_add(&b, " FROM motion_laban, st WHERE rowid = ?1)");
    else
        sb_add(&b, " FROM (SELECT laban(?1, '{\"missing\":\"null\"}') AS j), st)");
    sb_add(&b, ", dist AS %s(SELECT d.rowid AS id, sqrt(", radius > 0 ? "MATERIALIZED " : "");
    for (int t = 0; t < nc; t++) {
        int c = comps[t];
        sb_add(&b, "%scoalesce((z%d - (d.%s - m%d) / s%d) * (z%d - (d.%s - m%d) / s%d), 0)",
               t ? " + " : "", c, names[c], c, c, c, names[c], c, c);
    }
    sb_add(&b, ") AS distance FROM motion_laban d, st, q WHERE d.label = 'angry'%s) ",
           strcmp(query, "rowid") == 0 ? " AND d.rowid <> ?1" : "");
    if (radius > 0)
        sb_add(&b,
               "SELECT id, distance FROM dist WHERE distance <= %.17g * (SELECT max(distance) "
               "FROM dist) OR id = (SELECT id FROM dist ORDER BY distance, id LIMIT 1) "
               "ORDER BY distance, id",
               radius);
    else
        sb_add(&b, "SELECT id, distance FROM dist ORDER BY distance, id LIMIT %d", k);
    if (b.failed) {
        free(b.s);
        return NULL;
    }
    return b.s;
}

static void row(const char *name, const knn_result *r, const knn_result *base)
{
    printf("%-26s %8u %10.3f %10.3f %10.3f %10.3f %8.1f", name, r->per_run, r->median * 1e3,
           r->p95 * 1e3, r->run_min * 1e3, r->run_max * 1e3, r->rows);
    if (base)
        printf(" %9.1fx", r->median / base->median);
    printf("\n");
}

/* Creates the content and query tables; reads the component names and the query BLOBs. */
static int setup(sqlite3 *db, char names[N_COMP][32], inputs *in, double *gen_s,
                 sqlite3_int64 *frames)
{
    double t0 = now();
    if (bench_exec(
            db,
            "CREATE TABLE motions(id INTEGER PRIMARY KEY, action TEXT, emotion TEXT, "
            "seed INTEGER, motion BLOB);"
            "WITH RECURSIVE seeds(seed) AS (SELECT 1 UNION ALL SELECT seed + 1 FROM seeds "
            "WHERE seed < " XSTR(
                N_SEEDS) "), "
                         "actions(action) AS (VALUES ('knock'), ('wave'), ('walk'), ('bow')), "
                         "emotions(emotion) AS (VALUES ('neutral'), ('happy'), ('sad'), ('angry')) "
                         "INSERT INTO motions(action, emotion, seed, motion) "
                         "SELECT action, emotion, seed, motion_synth(action, emotion, seed, "
                         "'{\"fps\":10}') FROM seeds, actions, emotions ORDER BY seed, action, "
                         "emotion;"))
        return 1;
    *gen_s = now() - t0;
    if (bench_exec(db,
                   "CREATE TABLE queries(id INTEGER PRIMARY KEY, motion BLOB);"
                   "WITH RECURSIVE seeds(seed) AS (SELECT 626 UNION ALL SELECT seed + 1 FROM seeds "
                   "WHERE seed < 641), "
                   "actions(action) AS (VALUES ('knock'), ('wave'), ('walk'), ('bow')), "
                   "emotions(emotion) AS (VALUES ('neutral'), ('happy'), ('sad'), ('angry')) "
                   "INSERT INTO queries(motion) "
                   "SELECT motion_synth(action, emotion, seed, '{\"fps\":10}') "
                   "FROM seeds, actions, emotions ORDER BY seed, action, emotion;"))
        return 1;
    sqlite3_int64 n = 0;
    if (bench_query_int(db, "SELECT count(*) FROM motions", &n))
        return 1;
    if (n != N_MOTIONS) {
        fprintf(stderr, "expected %d motions, made %lld\n", N_MOTIONS, (long long)n);
        return 1;
    }
    if (bench_query_int(db, "SELECT sum(motion_frames(motion)) FROM motions", frames))
        return 1;

    sqlite3_stmt *st = NULL;
    int i = 0;
    if (bench_prepare(db, "SELECT value FROM json_each(laban_names())", &st))
        return 1;
    while (sqlite3_step(st) == SQLITE_ROW && i < N_COMP)
        snprintf(names[i++], 32, "%s", (const char *)sqlite3_column_text(st, 0));
    sqlite3_finalize(st);
    if (i != N_COMP) {
        fprintf(stderr, "laban_names() has %d names, expected %d\n", i, N_COMP);
        return 1;
    }
    if (bench_prepare(db, "SELECT motion FROM queries ORDER BY id LIMIT 250", &st))
        return 1;
    for (i = 0; i < N_QUERIES && sqlite3_step(st) == SQLITE_ROW; i++) {
        int len = sqlite3_column_bytes(st, 0);
        in->blob[i] = malloc((size_t)len);
        if (!in->blob[i])
            break;
        memcpy(in->blob[i], sqlite3_column_blob(st, 0), (size_t)len);
        in->blob_len[i] = len;
        in->rowid[i] = 1 + ((sqlite3_int64)i * 7919) % N_MOTIONS;
    }
    sqlite3_finalize(st);
    if (i != N_QUERIES) {
        fprintf(stderr, "could not read %d query motions\n", N_QUERIES);
        return 1;
    }
    return 0;
}

#define CREATE_INDEX                                                                               \
    "CREATE VIRTUAL TABLE motion_laban USING laban(content=motions, motion=motion, label=emotion)"

#define VECTOR_SCAN                                                                                \
    "SELECT sum(length(laban_vector(motion, '{\"missing\":\"null\"}'))) FROM motions"

/* Warm-up build, then RUNS timed builds (each dropped untimed); leaves the index in place.
 * Then the same for the descriptors alone (vec). */
static int measure_build(sqlite3 *db, double t[RUNS], double vec[RUNS])
{
    if (bench_exec(db, CREATE_INDEX) || bench_exec(db, "DROP TABLE motion_laban"))
        return 1;
    for (int run = 0; run < RUNS; run++) {
        double t0 = now();
        if (bench_exec(db, CREATE_INDEX))
            return 1;
        t[run] = now() - t0;
        if (bench_exec(db, "DROP TABLE motion_laban"))
            return 1;
    }
    qsort(t, RUNS, sizeof t[0], cmp_double);
    sqlite3_int64 bytes = 0;
    if (bench_query_int(db, VECTOR_SCAN, &bytes))
        return 1;
    for (int run = 0; run < RUNS; run++) {
        double t0 = now();
        if (bench_query_int(db, VECTOR_SCAN, &bytes))
            return 1;
        vec[run] = now() - t0;
    }
    qsort(vec, RUNS, sizeof vec[0], cmp_double);
    return bench_exec(db, CREATE_INDEX);
}

enum { Q_ROWID, Q_BLOB, Q_VECTOR, Q_RADIUS, Q_COMPS, Q_FIXED, Q_COUNT };

int main(int argc, char **argv)
{
    const char *module = AFFECT_BENCH_MODULE;
    unsigned rounds = 0;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--rounds") == 0 && i + 1 < argc) {
            long v = strtol(argv[++i], NULL, 10);
            if (v < 1 || v > MAX_ROUNDS) {
                fprintf(stderr, "--rounds must be from 1 to %d\n", MAX_ROUNDS);
                return 2;
            }
            rounds = (unsigned)v;
        } else if (argv[i][0] == '-') {
            fprintf(stderr, "usage: %s [module path] [--rounds N]\n", argv[0]);
            return 2;
        } else {
            module = argv[i];
        }
    }

    sqlite3 *db = NULL;
    char *err = NULL;
    inputs *in = calloc(1, sizeof *in);
    sqlite3_stmt *vt[Q_COUNT] = {NULL}, *bf[Q_COUNT] = {NULL};
    char *sql[Q_COUNT] = {NULL};
    int rc = 1;
    if (!in || sqlite3_open(":memory:", &db) != SQLITE_OK) {
        fprintf(stderr, "cannot open an in-memory database\n");
        goto done;
    }
    sqlite3_enable_load_extension(db, 1);
    if (sqlite3_load_extension(db, module, "sqlite3_affect_init", &err) != SQLITE_OK) {
        printf("bench_knn: cannot load %s (%s): nothing to measure\n", module, err ? err : "?");
        sqlite3_free(err);
        rc = 0;
        goto done;
    }
    sqlite3_int64 have = 0;
    if (bench_query_int(db, "SELECT count(*) FROM pragma_module_list WHERE name = 'laban'", &have))
        goto done;
    if (!have) {
        printf("bench_knn: %s has no laban virtual table: nothing to measure\n", module);
        rc = 0;
        goto done;
    }

    char names[N_COMP][32];
    double gen_s = 0, build[RUNS], vscan[RUNS];
    sqlite3_int64 frames = 0;
    if (setup(db, names, in, &gen_s, &frames) || measure_build(db, build, vscan))
        goto done;

    int all[N_COMP], two[2] = {-1, -1};
    for (int c = 0; c < N_COMP; c++) {
        all[c] = c;
        if (strcmp(names[c], "TimeAll") == 0)
            two[0] = c;
        if (strcmp(names[c], "FlowAll") == 0)
            two[1] = c;
    }
    static const char *const vt_sql[Q_COUNT] = {
        "SELECT rowid, distance FROM motion_laban WHERE query = ?1 AND label = 'angry' AND k = 5",
        "SELECT rowid, distance FROM motion_laban WHERE query = ?1 AND label = 'angry' AND k = 5",
        "SELECT 0, length(laban_vector(?1, '{\"missing\":\"null\"}'))",
        "SELECT rowid, distance FROM motion_laban WHERE query = ?1 AND label = 'angry' "
        "AND radius = 0.1",
        "SELECT rowid, distance FROM motion_laban WHERE query = ?1 AND label = 'angry' AND k = 5 "
        "AND components = '[\"TimeAll\",\"FlowAll\"]'",
        "SELECT rowid, distance FROM motion_laban WHERE query = ?1 AND rowid = ?1 % 10000 + 1 "
        "AND k = 1"};
    sql[Q_ROWID] = brute_sql(names, "rowid", all, N_COMP, 5, 0);
    sql[Q_BLOB] = brute_sql(names, "blob", all, N_COMP, 5, 0);
    sql[Q_RADIUS] = brute_sql(names, "rowid", all, N_COMP, 0, 0.1);
    sql[Q_COMPS] = brute_sql(names, "rowid", two, 2, 5, 0);
    for (int q = 0; q < Q_COUNT; q++) {
        if (bench_prepare(db, vt_sql[q], &vt[q]))
            goto done;
        if (q != Q_VECTOR && q != Q_FIXED && (!sql[q] || bench_prepare(db, sql[q], &bf[q])))
            goto done;
    }

    printf("content: %d motions (motion_synth, 4 actions x 4 emotions x seeds 1..%d, 10 fps), "
           "%lld frames; made in %.2f s\n",
           N_MOTIONS, N_SEEDS, (long long)frames, gen_s);
    printf("queries: %d different query rows or motions per kind, label 'angry' (%d candidate "
           "rows)\n\n",
           N_QUERIES, N_MOTIONS / 4);
    printf("checking every query against the brute-force SQL (also the warm-up):\n");
    if (verify(db, vt[Q_ROWID], bf[Q_ROWID], in, false, false, "(a) rowid k=5") ||
        verify(db, vt[Q_BLOB], bf[Q_BLOB], in, true, true, "(b) blob k=5") ||
        verify(db, vt[Q_RADIUS], bf[Q_RADIUS], in, false, false, "(c) radius 0.1") ||
        verify(db, vt[Q_COMPS], bf[Q_COMPS], in, false, false, "(d) 2 comps k=5"))
        goto done;
    for (int i = 0; i < N_QUERIES; i++) {
        if (run_one(db, vt[Q_VECTOR], in, i, true, NULL) < 0)
            goto done;
        if (run_one(db, vt[Q_FIXED], in, i, false, NULL) != 1) {
            fprintf(stderr, "(e) 1 candidate, query %d: expected one row\n", i);
            goto done;
        }
    }

    knn_result rv[Q_COUNT], rb[Q_COUNT];
    for (int q = 0; q < Q_COUNT; q++) {
        bool blob = q == Q_BLOB || q == Q_VECTOR;
        if (measure(db, vt[q], in, blob, rounds, &rv[q]) ||
            (bf[q] && measure(db, bf[q], in, blob, rounds, &rb[q])))
            goto done;
    }

    double build_s = build[RUNS / 2];
    printf("\nindex build (CREATE VIRTUAL TABLE over the %d motions), %d runs:\n", N_MOTIONS, RUNS);
    printf("  median %.3f s (fastest %.3f, slowest %.3f): %.0f motions/s, %.0f frames/s\n", build_s,
           build[0], build[RUNS - 1], N_MOTIONS / build_s, (double)frames / build_s);
    double vscan_s = vscan[RUNS / 2];
    printf("  of which Laban descriptors (laban_vector over the same motions): median %.3f s "
           "(fastest %.3f, slowest %.3f), %.1f%% of the build\n\n",
           vscan_s, vscan[0], vscan[RUNS - 1], 100.0 * vscan_s / build_s);
    printf("query latency, %d runs of 'per run' queries; ms per query: median and p95 of the "
           "median run,\nfastest and slowest run's median; rows = mean rows returned; "
           "x = brute-force SQL / table\n\n",
           RUNS);
    printf("%-26s %8s %10s %10s %10s %10s %8s %10s\n", "query", "per run", "median", "p95",
           "fastest", "slowest", "rows", "vs table");
    static const char *const label[Q_COUNT] = {"(a) rowid k=5",           "(b) blob k=5",
                                               "(b0) laban_vector(blob)", "(c) radius 0.1",
                                               "(d) 2 comps k=5",         "(e) 1 candidate"};
    for (int q = 0; q < Q_COUNT; q++) {
        char name[64];
        snprintf(name, sizeof name, "%s table", label[q]);
        row(q == Q_VECTOR || q == Q_FIXED ? label[q] : name, &rv[q], NULL);
        if (bf[q]) {
            snprintf(name, sizeof name, "%s SQL", label[q]);
            row(name, &rb[q], &rv[q]);
        }
    }
    printf("\n(b) minus (b0): %.3f ms per query for the search once the vector is known\n",
           (rv[Q_BLOB].median - rv[Q_VECTOR].median) * 1e3);
    printf("(a) minus (e): %.3f ms per query for the distances to the 2,500 candidates and the "
           "top 5\n",
           (rv[Q_ROWID].median - rv[Q_FIXED].median) * 1e3);
    bool met = true;
    for (int q = 0; q <= Q_COMPS; q++)
        if (q != Q_VECTOR && rv[q].median * 1e3 > TARGET_MS)
            met = false;
    printf("target: KNN query <= %.0f ms over %d motions (median of each table query): %s\n\n",
           TARGET_MS, N_MOTIONS, met ? "met" : "NOT met");

    static const char *const key[Q_COUNT] = {"knn_rowid_k5",      "knn_blob_k5",
                                             "laban_vector_blob", "knn_radius",
                                             "knn_components_k5", "knn_one_candidate"};
    printf("BENCH knn_index_build %.1f motions/s\n", N_MOTIONS / build_s);
    printf("BENCH knn_index_build_descriptor_share %.4f ratio\n", vscan_s / build_s);
    printf("BENCH knn_index_build_frames %.0f frames/s\n", (double)frames / build_s);
    for (int q = 0; q < Q_COUNT; q++) {
        printf("BENCH %s_median %.4f ms\n", key[q], rv[q].median * 1e3);
        printf("BENCH %s_p95 %.4f ms\n", key[q], rv[q].p95 * 1e3);
        if (bf[q]) {
            printf("BENCH %s_sql_median %.4f ms\n", key[q], rb[q].median * 1e3);
            printf("BENCH %s_sql_p95 %.4f ms\n", key[q], rb[q].p95 * 1e3);
            printf("BENCH %s_sql_vs_table %.2f ratio\n", key[q], rb[q].median / rv[q].median);
        }
    }
    rc = 0;
done:
    for (int q = 0; q < Q_COUNT; q++) {
        sqlite3_finalize(vt[q]);
        sqlite3_finalize(bf[q]);
        free(sql[q]);
    }
    if (in)
        for (int i = 0; i < N_QUERIES; i++)
            free(in->blob[i]);
    free(in);
    sqlite3_close(db);
    return rc;
}
