/*
 * bench_generate.c — the latency of affective motion generation (affect_generate, SCIENCE.md §5)
 * on the real corpus, on one core, split into its stages: neighbour search, reading the
 * neighbours, observations, HMM training, Viterbi and rendering; and the time of the RMLR fit
 * (laban_salient) that chooses the search's components.
 *
 * Usage:
 *     bench_generate [corpus directory] [--module PATH] [--reps N] [--rmlr-runs N] [--quick]
 *     bench_generate --rmlr-only [--threads N] [corpus directory]
 *     bench_generate --transfer-only [--reps N] [corpus directory]   (section 3 alone)
 *     AFFECT_BENCH_ONLY=bench_generate bash tests/bench/run.sh   # Release, one core
 * The directory defaults to AFFECT_BENCH_CORPUS and the module to AFFECT_BENCH_MODULE (the
 * built affect.so), both set by tests/bench/CMakeLists.txt. When the corpus is absent, or the
 * module cannot be loaded or has no affect_generate, the program says so and exits 0. Run it
 * with OPENBLAS_NUM_THREADS=1 (run.sh does): it prints OpenBLAS's thread count and warns when
 * it is not 1. --reps N: repetitions of every generation (default 5); --rmlr-runs N: timed RMLR
 * fits (default 3); --quick (for valgrind): one path, one target, one repetition, the RMLR fit
 * once with laban_salient('ix22', '{"folds":3}') (stored under the same key as a 10-fold fit,
 * which affect_generate then uses), the 27-joint workloads left out. --rmlr-only builds ix22
 * and times only its RMLR fit; with --threads N > 1 it passes {"threads":N} to laban_salient
 * (run.sh runs it so, unpinned), or says that laban_salient has no such option and exits 0.
 * The load average is printed at the start and the end, and each fit's CPU time next to its
 * wall time (less when another process shared the core).
 *
 * Set-up, in an in-memory database with the module loaded as a user loads it:
 *   corpus27  the corpus's 44 recordings of emotion angry, happy, normal or sad whose content is
 *             one of the contents recorded in all four (bow, bye, byebye, dash, guide, run, walk
 *             (2 takes), walk-back, walk-left, walk-right): motion_from_bvh(text, {"unit":"cm"})
 *             of every such file, the content and emotion parsed from the file name by the
 *             expressions of sql/import_bvh.sql, rows in name order; 27 joints (the BVH's 22
 *             and its 5 End Sites, named Head_end, Hand_L_end, Hand_R_end, Toes_L_end,
 *             Toes_R_end);
 *   corpus22  the same rows through motion_select without those 5 End Site joints: the BVH's
 *             22 joints, the 22-joint skeleton (every role still resolves);
 *   ix27, ix22  CREATE VIRTUAL TABLE ixNN USING laban(content=corpusNN, motion=motion,
 *             label=emotion).
 *
 * 1. RMLR fit: the first laban_salient('ix22') call (the fit), then --rmlr-runs − 1 forced
 *    refits, each after an untimed DELETE of the keys 'rmlr' and 'rmlr_key' from ix22_info and
 *    a reload of the extension (new registrations: the in-memory cache, kept per registration
 *    and keyed by the index's content, is gone with the old ones); every run is checked to have
 *    stored a new fit (the keys are back) and to return the first run's JSON.
 *    Then a cached call (the same registration: memory) and one through another registration
 *    (laban_salient('ix22', '{"seed":1}'): the stored fit decoded from ix22_info), and the
 *    first fit of ix27. Whether laban_salient accepts {"threads":2} is asked without any work:
 *    laban_salient('bench_no_such_index', '{"threads":2}') fails with "unknown option" when it
 *    does not (the options are read before the index), with another message when it does.
 * 2. Generation latency. Workloads (the paths in name order, the targets in byte order):
 *      (i)   22 joints: every recording with at least 300 frames, motion_slice(motion, 0, 299),
 *            converted to each of the three other emotions, copies 0 and copies 2;
 *      (ii)  the same at the corpus's 27 joints;
 *      (iii) 27 joints, all 44 recordings at their natural length, to the 3 other emotions,
 *            copies 0.
 *    Every call names its source: options {"source_label": <the recording's emotion>,
 *    "copies": n}, so the components are L \ (L'_source ∩ L'_target) for every path (a slice's
 *    bytes are not in the index, so without the option its source would be unknown); the index
 *    holds the path's whole recording too. Before timing, affect_generate_explain gives each
 *    generation's components (components.used) and neighbours; then the first generation once,
 *    untimed (the warm-up). A generation is measured --reps times (the generations in turn,
 *    then again), each time
 *      (a) neighbour search  the statement affect_generate prepares and runs (fn_generate.c,
 *                            find_neighbours): SELECT rowid, distance FROM ixNN WHERE query =
 *                            ?desired AND label = ?target AND components = ?used AND radius =
 *                            0.1 ORDER BY distance, rowid (then k = 1 if that were empty),
 *                            prepared, run and finalized (the BLOB query computes the
 *                            path's Laban vector: most of this stage);
 *      (b) read + decode     the neighbours' motions: SELECT motion FROM corpusNN WHERE rowid =
 *                            ?1 per neighbour, affect_motion_decode (load_neighbours);
 *      (c) affect_generate   the core call with the function's options (defaults: 12 states,
 *                            cut-off 3 Hz, covariance scale 1, seed 1; copies) and opt.clock =
 *                            CLOCK_MONOTONIC, whose report splits it into features (observations
 *                            of the path and the neighbours), HMM training (Baum-Welch), Viterbi
 *                            and render (state means, low-pass filter, de-normalization);
 *    and then the whole SQL call SELECT affect_generate(?index, ?desired, ?target, ?options)
 *    (one prepared statement; bind, step, reset). Its rest (SQL − (a+b+c)) is what the split
 *    leaves out: decoding the path's BLOB, loading and imputing the index's 44 vectors, the
 *    source and RMLR look-ups, encoding the result. Checked on the first repetition: (a) returns
 *    the rowids and distances of the explanation, and (c)'s motion, encoded, has exactly the
 *    bytes of the SQL call's result (else exit status 1: the split would not be the call).
 *    Per generation the median of its repetitions; per workload the median, mean and worst
 *    generation of each stage, in ms. The goal (issue 6): a median SQL call of at most 100 ms
 *    on workload (i), copies 0: MET or NOT MET, with the ratio.
 * Output: tables for people, then one line per metric for scripts:
 *     BENCH <metric> <value> <unit>
 * Exit status 1 if a statement fails or a check does not hold.
 */
#define _DEFAULT_SOURCE /* getloadavg */
#define _POSIX_C_SOURCE 200809L

#include <sqlite3.h>

#include "affect/generate.h"
#include "affect/motion.h"

#include <cblas.h>
#include <errno.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define BENCH_NAME "bench_generate"
#include "benchutil.h"

#ifndef AFFECT_BENCH_MODULE
#define AFFECT_BENCH_MODULE "build-bench/affect.so"
#endif
#ifndef AFFECT_BENCH_CORPUS
#define AFFECT_BENCH_CORPUS "../shared/corpora/bandai-namco-1/data"
#endif

#define N_EMOTIONS 4
#define EXPECTED_MOTIONS 44
#define EXPECTED_PER_EMOTION 11
#define EXPECTED_CONTENTS 10
#define PATH_FRAMES 300
#define FEW_PATHS 5
#define COPIES_MORE 2u
/* The split below reproduces HMM_NN as the core's defaults run it: the thesis's step
 * rendering, the ε-ball alone (the SQL defaults add at least 3 neighbours ranked by DTW). */
#define HMM_NN_OPTIONS                                                                             \
    "\"method\":\"hmm_nn\",\"render\":\"steps\",\"min_neighbours\":1,\"prefer_action\":false"
/* The default method's goal (issue 13): a median 300-frame, 22-joint generation in 30 ms. */
#define TRANSFER_GOAL_MS 30.0
#define EPSILON 0.1 /* affect_generate's default radius */
#define GOAL_MS 100.0
#define DEFAULT_REPS 5u
#define MAX_REPS 25u
#define RMLR_RUNS 3u
#define MAX_RMLR_RUNS 10u
#define MAX_NB 64u
#define N_WORKLOADS 5

/* The labels in byte order, as the index orders its classes. */
static const char *const emotions[N_EMOTIONS] = {"angry", "happy", "normal", "sad"};
/* The BVH's End Sites, which motion_from_bvh makes joints: left out of the 22-joint skeleton. */
static const char *const end_sites[] = {"Head_end", "Hand_L_end", "Hand_R_end", "Toes_L_end",
                                        "Toes_R_end"};

enum {
    S_SEARCH,
    S_READ,
    S_CORE,
    S_FEATURES,
    S_TRAIN,
    S_VITERBI,
    S_RENDER,
    S_CORE_OTHER,
    S_SUM,
    S_SQL,
    S_REST,
    S_COUNT
};
static const char *const stage_names[S_COUNT] = {"(a) neighbour search (SQL)",
                                                 "(b) read + decode neighbours",
                                                 "(c) affect_generate (core)",
                                                 "      features",
                                                 "      HMM training",
                                                 "      Viterbi",
                                                 "      render",
                                                 "      other (in the core)",
                                                 "(a) + (b) + (c)",
                                                 "SQL affect_generate(...)",
                                                 "  rest: SQL - (a+b+c)"};
static const char *const stage_keys[S_COUNT] = {"search",    "read",    "core",    "features",
                                                "train",     "viterbi", "render",  "core_other",
                                                "split_sum", "sql",     "sql_rest"};

/* A desired path: a recording (or its first PATH_FRAMES frames) of one content table. */
typedef struct path {
    char *name;
    int source;                /* index into emotions */
    uint32_t frames;           /* of the path */
    uint32_t recording_frames; /* of its recording */
    unsigned char *blob;
    int len;
    affect_motion *m; /* decoded, for the core call */
} path;

typedef struct job {
    const path *p;
    int target;
    char opts[192]; /* the SQL call's options */
    char *comps;    /* components.used of the explanation */
    uint32_t n_nb;  /* neighbours of the explanation */
    sqlite3_int64 nb_id[MAX_NB];
    double nb_dist[MAX_NB];
    uint32_t iterations, used;
    uint64_t train_frames;
    double t[MAX_REPS][S_COUNT]; /* seconds */
} job;

typedef struct workload {
    const char *key, *title, *index, *content;
    uint32_t copies;
    const path *paths;
    uint32_t n_paths;
    job *jobs;
    uint32_t n_jobs;
    bench_summary s[S_COUNT]; /* over the generations' medians, seconds */
    const job *worst;         /* the slowest SQL call */
} workload;

typedef struct rmlr_result {
    double fit[MAX_RMLR_RUNS];
    uint32_t runs;
    double cached_memory, cached_info, fit27;
    bool same27;
    char *json;
    char *summary, *summary27; /* alpha, lambda, cv_error, salient components per label */
    char *threads_note;
} rmlr_result;

static void print_load(const char *when)
{
    double la[3];
    if (getloadavg(la, 3) == 3)
        printf("load average %s: %.2f %.2f %.2f\n", when, la[0], la[1], la[2]);
}

/* ---- SQL helpers ---- */

/* ---- the corpus ---- */

/* The file stems of dir into table files(stem); 1 when dir cannot be opened, 2 on error. */
static int list_files(sqlite3 *db, const char *dir)
{
    char **names;
    size_t n;
    int rc = bench_list_files(dir, ".bvh", &names, &n);
    sqlite3_stmt *st = NULL;
    if (rc) {
        if (rc == 2)
            fprintf(stderr, "bench_generate: out of memory\n");
        goto done;
    }
    rc = 2;
    if (bench_exec(db, "CREATE TABLE files(stem TEXT PRIMARY KEY)") ||
        bench_prepare(db, "INSERT INTO files(stem) VALUES (?1)", &st))
        goto done;
    for (size_t i = 0; i < n; i++) {
        sqlite3_bind_text(st, 1, names[i], (int)strlen(names[i]) - 4, SQLITE_TRANSIENT);
        if (sqlite3_step(st) != SQLITE_DONE) {
            fprintf(stderr, "bench_generate: %s\n", sqlite3_errmsg(db));
            goto done;
        }
        sqlite3_reset(st);
    }
    rc = 0;
done:
    sqlite3_finalize(st);
    for (size_t i = 0; i < n; i++)
        free(names[i]);
    free(names);
    return rc;
}

/* The selection, parsed as sql/import_bvh.sql parses file names. */
#define SELECTED                                                                                   \
    "WITH parts AS (SELECT stem, CASE WHEN stem LIKE 'dataset-%\\_%\\_%\\_%' ESCAPE '\\' "         \
    "THEN substr(stem, instr(stem, '_') + 1) END AS rest1 FROM files), "                           \
    "labels AS (SELECT stem, substr(rest1, 1, instr(rest1, '_') - 1) AS content, "                 \
    "substr(rest1, instr(rest1, '_') + 1) AS rest2 FROM parts WHERE rest1 IS NOT NULL), "          \
    "parsed AS (SELECT stem, content, substr(rest2, 1, instr(rest2, '_') - 1) AS emotion "         \
    "FROM labels WHERE emotion IN ('angry', 'happy', 'normal', 'sad')) "                           \
    "SELECT stem, content, emotion FROM parsed WHERE content IN (SELECT content FROM parsed "      \
    "GROUP BY content HAVING count(DISTINCT emotion) = 4) ORDER BY stem"

/* corpus27 from the selected files of dir; *secs: the time of motion_from_bvh and the
 * inserts (the files read beforehand). 1 when dir cannot be opened, 2 on error. */
static int import_corpus(sqlite3 *db, const char *dir, double *secs, sqlite3_int64 *frames)
{
    int rc = list_files(db, dir);
    if (rc)
        return rc;
    rc = 2;
    sqlite3_stmt *sel = NULL, *ins = NULL;
    char *text = NULL;
    *secs = 0;
    if (bench_exec(db, "CREATE TABLE corpus27(id INTEGER PRIMARY KEY, name TEXT, content TEXT, "
                       "emotion TEXT, frames INTEGER, motion BLOB)") ||
        bench_prepare(db, SELECTED, &sel) ||
        bench_prepare(db,
                      "INSERT INTO corpus27(name, content, emotion, motion) "
                      "VALUES (?1, ?2, ?3, motion_from_bvh(?4, '{\"unit\":\"cm\"}'))",
                      &ins))
        goto done;
    int step;
    while ((step = sqlite3_step(sel)) == SQLITE_ROW) {
        const char *stem = (const char *)sqlite3_column_text(sel, 0);
        char file[4096];
        snprintf(file, sizeof file, "%s/%s.bvh", dir, stem);
        size_t len = 0;
        free(text);
        text = bench_read_file(file, &len);
        if (!text) {
            fprintf(stderr, "bench_generate: cannot read %s: %s\n", file, strerror(errno));
            goto done;
        }
        for (int k = 0; k < 3; k++)
            sqlite3_bind_value(ins, k + 1, sqlite3_column_value(sel, k));
        sqlite3_bind_text(ins, 4, text, (int)len, SQLITE_STATIC);
        double t0 = now();
        int r = sqlite3_step(ins);
        *secs += now() - t0;
        if (r != SQLITE_DONE) {
            fprintf(stderr, "bench_generate: %s.bvh: %s\n", stem, sqlite3_errmsg(db));
            goto done;
        }
        sqlite3_reset(ins);
    }
    if (step != SQLITE_DONE) {
        fprintf(stderr, "bench_generate: %s\n", sqlite3_errmsg(db));
        goto done;
    }
    if (bench_exec(db, "UPDATE corpus27 SET frames = motion_frames(motion)") ||
        bench_query_int(db, "SELECT sum(frames) FROM corpus27", frames))
        goto done;
    rc = 0;
done:
    free(text);
    sqlite3_finalize(sel);
    sqlite3_finalize(ins);
    return rc;
}

/* The expected counts: 44 motions, 11 per emotion, 10 contents, one 27-joint skeleton. */
static int check_corpus(sqlite3 *db)
{
    sqlite3_int64 n = 0, contents = 0, skeletons = 0, joints = 0, bad = 0;
    if (bench_query_int(db, "SELECT count(*) FROM corpus27", &n) ||
        bench_query_int(db, "SELECT count(DISTINCT content) FROM corpus27", &contents) ||
        bench_query_int(db,
                        "SELECT count(DISTINCT json_extract(motion_info(motion), '$.names')) "
                        "FROM corpus27",
                        &skeletons) ||
        bench_query_int(db, "SELECT min(motion_joints(motion)) FROM corpus27", &joints) ||
        bench_query_int(db,
                        "SELECT count(*) FROM (SELECT emotion FROM corpus27 GROUP BY emotion "
                        "HAVING count(*) <> 11)",
                        &bad))
        return 1;
    if (n != EXPECTED_MOTIONS || contents != EXPECTED_CONTENTS || bad || skeletons != 1 ||
        joints != 27) {
        fprintf(stderr,
                "bench_generate: expected %d motions (%d per emotion, %d contents) of one "
                "27-joint skeleton; found %lld motions, %lld contents, %lld emotions with "
                "another count, %lld skeletons, %lld joints\n",
                EXPECTED_MOTIONS, EXPECTED_PER_EMOTION, EXPECTED_CONTENTS, (long long)n,
                (long long)contents, (long long)bad, (long long)skeletons, (long long)joints);
        return 1;
    }
    return 0;
}

/* corpus22: corpus27 without the End Site joints. */
static int make_corpus22(sqlite3 *db)
{
    char sql[1024];
    int k = snprintf(sql, sizeof sql,
                     "CREATE TABLE keep22 AS SELECT json_group_array(value) AS names FROM "
                     "(SELECT value FROM json_each(motion_info((SELECT motion FROM corpus27 "
                     "WHERE id = 1)), '$.names') WHERE value NOT IN (");
    for (size_t i = 0; i < sizeof end_sites / sizeof end_sites[0]; i++)
        k += snprintf(sql + k, sizeof sql - (size_t)k, "%s'%s'", i ? ", " : "", end_sites[i]);
    snprintf(sql + k, sizeof sql - (size_t)k, ") ORDER BY key)");
    sqlite3_int64 n = 0, joints = 0;
    if (bench_exec(db, sql) ||
        bench_query_int(db, "SELECT json_array_length(names) FROM keep22", &n))
        return 1;
    if (n != 22) {
        fprintf(stderr, "bench_generate: the 22-joint selection has %lld joints\n", (long long)n);
        return 1;
    }
    if (bench_exec(db,
                   "CREATE TABLE corpus22(id INTEGER PRIMARY KEY, name TEXT, content TEXT, "
                   "emotion TEXT, frames INTEGER, motion BLOB);"
                   "INSERT INTO corpus22 SELECT id, name, content, emotion, frames, "
                   "motion_select(motion, (SELECT names FROM keep22)) FROM corpus27 ORDER BY id") ||
        bench_query_int(db, "SELECT max(motion_joints(motion)) FROM corpus22", &joints))
        return 1;
    return joints != 22;
}

/* ---- 1. the RMLR fit ---- */

/* Runs a laban_salient call; *secs its time, *json a copy of its result (if json). A failure
 * is printed unless quiet; its message is returned in *msg (if msg; free()). */
static int salient(sqlite3 *db, const char *sql, double *secs, char **json, bool quiet, char **msg)
{
    sqlite3_stmt *st = NULL;
    double t0 = now();
    if (bench_prepare(db, sql, &st))
        return 1;
    int rc = sqlite3_step(st);
    if (rc == SQLITE_ROW && json) {
        free(*json);
        *json = strdup((const char *)sqlite3_column_text(st, 0));
    }
    if (rc != SQLITE_ROW) {
        if (!quiet)
            fprintf(stderr, "bench_generate: %s\n  in: %s\n", sqlite3_errmsg(db), sql);
        if (msg)
            *msg = strdup(sqlite3_errmsg(db));
    }
    sqlite3_finalize(st);
    *secs = now() - t0;
    return rc != SQLITE_ROW;
}

/* Whether laban_salient accepts {"threads":2}, asked without any work: the options are read
 * before the index, so a call on no index fails with "unknown option" or with another message.
 * *msg: the message (free()). */
static int threads_option(sqlite3 *db, bool *accepted, char **msg)
{
    double t;
    *msg = NULL;
    if (!salient(db, "SELECT laban_salient('bench_no_such_index', '{\"threads\":2}')", &t, NULL,
                 true, msg)) {
        fprintf(stderr, "bench_generate: laban_salient succeeded on no index\n");
        return 1;
    }
    if (!*msg)
        return 1;
    *accepted = strstr(*msg, "unknown option") == NULL;
    return 0;
}

/* The extension's path, for force_refit. */
static const char *bench_module;

/* Forces the next laban_salient on ix to fit: the stored fit deleted from the index's cache
 * and the extension loaded again, which registers its functions anew with empty in-memory
 * caches (the fits are keyed by the index's content, so a rebuild that changes nothing keeps
 * them). */
static int force_refit(sqlite3 *db, const char *ix)
{
    char sql[256];
    snprintf(sql, sizeof sql, "DELETE FROM \"%s_info\" WHERE key IN ('rmlr', 'rmlr_key')", ix);
    if (bench_exec(db, sql))
        return 1;
    char *err = NULL;
    if (sqlite3_load_extension(db, bench_module, "sqlite3_affect_init", &err) != SQLITE_OK) {
        fprintf(stderr, "bench_generate: reloading %s: %s\n", bench_module, err ? err : "?");
        sqlite3_free(err);
        return 1;
    }
    return 0;
}

/* Whether a fit of ix is stored. */
static int stored_now(sqlite3 *db, const char *ix, bool *yes)
{
    char sql[512];
    snprintf(sql, sizeof sql,
             "SELECT (SELECT value FROM \"%s_info\" WHERE key = 'rmlr_key') IS NOT NULL AND "
             "(SELECT typeof(value) FROM \"%s_info\" WHERE key = 'rmlr') = 'blob'",
             ix, ix);
    sqlite3_int64 v = 0;
    if (bench_query_int(db, sql, &v))
        return 1;
    *yes = v == 1;
    return 0;
}

/* Timed fits of ix with the call sql, the first on a fresh index, then forced refits. */
static int time_fits(sqlite3 *db, const char *ix, const char *sql, uint32_t runs, double *t,
                     char **json)
{
    char *first = NULL;
    for (uint32_t r = 0; r < runs; r++) {
        bool stored = true;
        if ((r > 0 && force_refit(db, ix)) || stored_now(db, ix, &stored))
            goto fail;
        if (stored) {
            fprintf(stderr, "bench_generate: %s: the fit is still stored before run %u\n", ix,
                    r + 1);
            goto fail;
        }
        double c0 = cpu_now();
        if (salient(db, sql, &t[r], json, false, NULL) || stored_now(db, ix, &stored))
            goto fail;
        double cpu = cpu_now() - c0;
        if (!stored) {
            fprintf(stderr, "bench_generate: %s: run %u did not store a new fit\n", ix, r + 1);
            goto fail;
        }
        if (r == 0) {
            first = strdup(*json);
        } else if (!first || strcmp(first, *json) != 0) {
            fprintf(stderr, "bench_generate: %s: run %u gave another fit:\n%s\n%s\n", ix, r + 1,
                    first ? first : "?", *json);
            goto fail;
        }
        printf("  %s run %u (%s): %.2f s (CPU %.2f s)\n", ix, r + 1, r ? "refit" : "first call",
               t[r], cpu);
        fflush(stdout);
    }
    free(first);
    return 0;
fail:
    free(first);
    return 1;
}

/* "alpha …, lambda …, cv_error …; salient components per label: angry 18, …" of a
 * laban_salient JSON. */
static int fit_summary(sqlite3 *db, const char *json, char **out)
{
    sqlite3_stmt *st = NULL;
    if (bench_prepare(
            db,
            "SELECT printf('alpha %g, lambda %.4g, cv_error %.4f; salient components per "
            "label: ', json_extract(?1, '$.alpha'), json_extract(?1, '$.lambda'), "
            "json_extract(?1, '$.cv_error')) || (SELECT group_concat(key || ' ' || "
            "json_array_length(value), ', ') FROM json_each(?1, '$.salient')) || '; per "
            "pair: ' || (SELECT group_concat(key || ' ' || json_array_length(value), ', ') "
            "FROM json_each(?1, '$.pairs'))",
            &st))
        return 1;
    sqlite3_bind_text(st, 1, json, -1, SQLITE_STATIC);
    int rc = sqlite3_step(st);
    if (rc == SQLITE_ROW)
        *out = strdup((const char *)sqlite3_column_text(st, 0));
    else
        fprintf(stderr, "bench_generate: %s\n", sqlite3_errmsg(db));
    sqlite3_finalize(st);
    return rc != SQLITE_ROW || !*out;
}

static int bench_rmlr(sqlite3 *db, uint32_t runs, bool quick, bool with27, rmlr_result *res)
{
    const char *call =
        quick ? "SELECT laban_salient('ix22', '{\"folds\":3}')" : "SELECT laban_salient('ix22')";
    printf("== 1. RMLR fit: %s, %u run%s (the first call, then refits forced by "
           "deleting the stored fit and reloading the extension)\n",
           call + 7, runs, runs == 1 ? "" : "s");
    res->runs = runs;
    if (time_fits(db, "ix22", call, runs, res->fit, &res->json))
        return 1;
    char *again = NULL;
    bool same = !salient(db, call, &res->cached_memory, &again, false, NULL) &&
                strcmp(again, res->json) == 0;
    if (same && !quick &&
        (salient(db, "SELECT laban_salient('ix22', '{\"seed\":1}')", &res->cached_info, &again,
                 false, NULL) ||
         strcmp(again, res->json) != 0))
        same = false;
    free(again);
    if (fit_summary(db, res->json, &res->summary))
        return 1;
    if (!same) {
        fprintf(stderr, "bench_generate: a cached laban_salient gave another answer\n");
        return 1;
    }
    char *msg = NULL;
    bool accepted = false;
    if (threads_option(db, &accepted, &msg))
        return 1;
    if (accepted) {
        res->threads_note = strdup("accepted: see bench_generate --rmlr-only --threads 2 "
                                   "(run.sh runs it unpinned)");
    } else {
        size_t n = strlen("not available: laban_salient said \"\"") + strlen(msg) + 1;
        res->threads_note = malloc(n);
        if (res->threads_note)
            snprintf(res->threads_note, n, "not available: laban_salient said \"%s\"", msg);
    }
    free(msg);
    if (!res->threads_note)
        return 1;
    if (with27) {
        char *json27 = NULL;
        double c0 = cpu_now();
        if (salient(db, "SELECT laban_salient('ix27')", &res->fit27, &json27, false, NULL)) {
            free(json27);
            return 1;
        }
        double cpu = cpu_now() - c0;
        res->same27 = strcmp(strstr(json27, "\"rows\""), strstr(res->json, "\"rows\"")) == 0;
        int bad = fit_summary(db, json27, &res->summary27);
        free(json27);
        if (bad)
            return 1;
        printf("  ix27 run 1 (first call): %.2f s (CPU %.2f s)\n", res->fit27, cpu);
    }
    return 0;
}

static void print_rmlr(const rmlr_result *res, bool quick, bool with27)
{
    double v[MAX_RMLR_RUNS];
    memcpy(v, res->fit, res->runs * sizeof *v);
    bench_summary s = bench_summarize(v, res->runs);
    printf("\nfit of the 22-joint index (44 rows x 27 components, 4 labels%s): median %.2f s "
           "(fastest %.2f, slowest %.2f, mean %.2f)\n",
           quick ? ", 3 folds (--quick)" : ", 10 folds", s.median, s.min, s.max, s.mean);
    printf("cached: the same registration (in memory) %.3f ms", res->cached_memory * 1e3);
    if (!quick)
        printf("; another registration (the fit stored in ix22_info, decoded) %.3f ms",
               res->cached_info * 1e3);
    printf("\n");
    if (with27)
        printf("fit of the 27-joint index: %.2f s (one run); the same alpha, lambda and salient "
               "sets as the 22-joint index: %s\n",
               res->fit27, res->same27 ? "yes" : "no");
    printf("threads option ({\"threads\":2}): %s\n", res->threads_note);
    printf("the fit (22 joints): %s\n", res->summary);
    if (with27)
        printf("the fit (27 joints): %s\n", res->summary27);
    printf("\n");
}

/* ---- 2. generation ---- */

static void free_paths(path *p, uint32_t n)
{
    for (uint32_t i = 0; p && i < n; i++) {
        free(p[i].name);
        free(p[i].blob);
        affect_motion_free(p[i].m);
    }
    free(p);
}

/* The paths of a workload: the first PATH_FRAMES frames of the recordings that have them
 * (sliced) or every recording, in name order. */
static int load_paths(sqlite3 *db, const char *content, bool sliced, path **out, uint32_t *n)
{
    char sql[512];
    if (sliced)
        snprintf(sql, sizeof sql,
                 "SELECT name, emotion, frames, motion_slice(motion, 0, %d) FROM \"%s\" "
                 "WHERE frames >= %d ORDER BY name",
                 PATH_FRAMES - 1, content, PATH_FRAMES);
    else
        snprintf(sql, sizeof sql, "SELECT name, emotion, frames, motion FROM \"%s\" ORDER BY name",
                 content);
    sqlite3_stmt *st = NULL;
    path *p = NULL;
    uint32_t k = 0;
    if (bench_prepare(db, sql, &st))
        return 1;
    p = calloc(EXPECTED_MOTIONS, sizeof *p);
    if (!p)
        goto fail;
    int rc;
    while ((rc = sqlite3_step(st)) == SQLITE_ROW && k < EXPECTED_MOTIONS) {
        path *q = &p[k++];
        const char *emo = (const char *)sqlite3_column_text(st, 1);
        q->source = -1;
        for (int e = 0; e < N_EMOTIONS; e++)
            if (strcmp(emo, emotions[e]) == 0)
                q->source = e;
        q->name = strdup((const char *)sqlite3_column_text(st, 0));
        q->recording_frames = (uint32_t)sqlite3_column_int(st, 2);
        q->len = sqlite3_column_bytes(st, 3);
        q->blob = malloc((size_t)q->len);
        if (!q->name || !q->blob || q->source < 0)
            goto fail;
        memcpy(q->blob, sqlite3_column_blob(st, 3), (size_t)q->len);
        affect_error err;
        if (affect_motion_decode(q->blob, (size_t)q->len, &q->m, &err)) {
            fprintf(stderr, "bench_generate: %s: %s\n", q->name, err.msg);
            goto fail;
        }
        q->frames = q->m->n_frames;
    }
    if (rc != SQLITE_DONE) {
        fprintf(stderr, "bench_generate: reading the paths: %s\n", sqlite3_errmsg(db));
        goto fail;
    }
    sqlite3_finalize(st);
    *out = p;
    *n = k;
    return 0;
fail:
    sqlite3_finalize(st);
    free_paths(p, k);
    return 1;
}

/* Every path to every other emotion (at most max_paths paths and max_targets targets each). */
static int make_jobs(workload *w, uint32_t max_paths, uint32_t max_targets)
{
    w->jobs = calloc((size_t)w->n_paths * (N_EMOTIONS - 1), sizeof *w->jobs);
    if (!w->jobs)
        return 1;
    w->n_jobs = 0;
    for (uint32_t i = 0; i < w->n_paths && i < max_paths; i++) {
        uint32_t made = 0;
        for (int e = 0; e < N_EMOTIONS && made < max_targets; e++) {
            if (e == w->paths[i].source)
                continue;
            job *j = &w->jobs[w->n_jobs++];
            j->p = &w->paths[i];
            j->target = e;
            snprintf(j->opts, sizeof j->opts, "{%s,\"source_label\":\"%s\",\"copies\":%u}",
                     HMM_NN_OPTIONS, emotions[w->paths[i].source], w->copies);
            made++;
        }
    }
    return 0;
}

/* The components and neighbours of every generation, from affect_generate_explain. */
static int explain_jobs(sqlite3 *db, workload *w)
{
    sqlite3_stmt *st = NULL;
    int rc = 1;
    if (bench_prepare(
            db,
            "WITH e AS (SELECT affect_generate_explain(?1, ?2, ?3, ?4) AS e) "
            "SELECT json_extract(e, '$.components.used'), json_extract(r.value, '$.rowid'), "
            "json_extract(r.value, '$.distance') FROM e, json_each(e, '$.neighbours.rows') "
            "AS r ORDER BY r.key",
            &st))
        return 1;
    for (uint32_t i = 0; i < w->n_jobs; i++) {
        job *j = &w->jobs[i];
        sqlite3_bind_text(st, 1, w->index, -1, SQLITE_STATIC);
        sqlite3_bind_blob(st, 2, j->p->blob, j->p->len, SQLITE_STATIC);
        sqlite3_bind_text(st, 3, emotions[j->target], -1, SQLITE_STATIC);
        sqlite3_bind_text(st, 4, j->opts, -1, SQLITE_STATIC);
        int r;
        j->n_nb = 0;
        while ((r = sqlite3_step(st)) == SQLITE_ROW) {
            if (!j->comps && !(j->comps = strdup((const char *)sqlite3_column_text(st, 0))))
                goto done;
            if (j->n_nb == MAX_NB) {
                fprintf(stderr, "bench_generate: more than %u neighbours\n", MAX_NB);
                goto done;
            }
            j->nb_id[j->n_nb] = sqlite3_column_int64(st, 1);
            j->nb_dist[j->n_nb++] = sqlite3_column_double(st, 2);
        }
        if (r != SQLITE_DONE || j->n_nb == 0) {
            fprintf(stderr, "bench_generate: explaining %s -> %s: %s\n", j->p->name,
                    emotions[j->target], r != SQLITE_DONE ? sqlite3_errmsg(db) : "no neighbours");
            goto done;
        }
        sqlite3_reset(st);
    }
    rc = 0;
done:
    sqlite3_finalize(st);
    return rc;
}

/* (a) the neighbour search as fn_generate.c's find_neighbours runs it: ids and distances. */
static int search(sqlite3 *db, const workload *w, const job *j, sqlite3_int64 *ids, double *dist,
                  uint32_t *n)
{
    *n = 0;
    for (int pass = 0; pass < 2 && *n == 0; pass++) {
        char sql[256];
        snprintf(sql, sizeof sql,
                 "SELECT rowid, distance FROM \"%s\" WHERE query = ?1 AND label = ?2 AND "
                 "components = ?3 AND %s = ?4 ORDER BY distance, rowid",
                 w->index, pass ? "k" : "radius");
        sqlite3_stmt *st = NULL;
        if (bench_prepare(db, sql, &st))
            return 1;
        sqlite3_bind_blob(st, 1, j->p->blob, j->p->len, SQLITE_STATIC);
        sqlite3_bind_text(st, 2, emotions[j->target], -1, SQLITE_STATIC);
        sqlite3_bind_text(st, 3, j->comps, -1, SQLITE_STATIC);
        if (pass)
            sqlite3_bind_int64(st, 4, 1);
        else
            sqlite3_bind_double(st, 4, EPSILON);
        int rc;
        while ((rc = sqlite3_step(st)) == SQLITE_ROW && *n < MAX_NB) {
            ids[*n] = sqlite3_column_int64(st, 0);
            dist[(*n)++] = sqlite3_column_double(st, 1);
        }
        sqlite3_finalize(st);
        if (rc != SQLITE_ROW && rc != SQLITE_DONE) {
            fprintf(stderr, "bench_generate: the neighbour search: %s\n", sqlite3_errmsg(db));
            return 1;
        }
    }
    return 0;
}

/* (b) the neighbours' motions, read and decoded as load_neighbours does. */
static int read_neighbours(sqlite3 *db, const workload *w, const sqlite3_int64 *ids, uint32_t n,
                           affect_motion **out)
{
    char sql[128];
    snprintf(sql, sizeof sql, "SELECT motion FROM \"%s\" WHERE rowid = ?1", w->content);
    sqlite3_stmt *st = NULL;
    if (bench_prepare(db, sql, &st))
        return 1;
    int rc = 0;
    for (uint32_t i = 0; i < n && !rc; i++) {
        sqlite3_reset(st);
        sqlite3_bind_int64(st, 1, ids[i]);
        affect_error err;
        if (sqlite3_step(st) != SQLITE_ROW || sqlite3_column_type(st, 0) != SQLITE_BLOB) {
            fprintf(stderr, "bench_generate: content row %lld has no motion\n", (long long)ids[i]);
            rc = 1;
        } else if (affect_motion_decode(sqlite3_column_blob(st, 0),
                                        (size_t)sqlite3_column_bytes(st, 0), &out[i], &err)) {
            fprintf(stderr, "bench_generate: content row %lld: %s\n", (long long)ids[i], err.msg);
            rc = 1;
        }
    }
    sqlite3_finalize(st);
    return rc;
}

/* One generation split into (a), (b), (c); t gets the stage times. With check, (a) must give
 * the explanation's neighbours and *enc gets (c)'s motion encoded (affect_free). */
static int run_split(sqlite3 *db, const workload *w, job *j, double *t, bool check,
                     unsigned char **enc, size_t *enc_len)
{
    sqlite3_int64 ids[MAX_NB];
    double dist[MAX_NB];
    affect_motion *nb[MAX_NB] = {NULL}, *out = NULL;
    affect_generate_report rep;
    memset(&rep, 0, sizeof rep);
    uint32_t n = 0;
    int rc = 1;

    double t0 = now();
    if (search(db, w, j, ids, dist, &n))
        goto done;
    double t1 = now();
    if (read_neighbours(db, w, ids, n, nb))
        goto done;
    double t2 = now();
    affect_generate_options opt;
    affect_generate_options_default(&opt);
    opt.copies = w->copies;
    opt.clock = now;
    affect_error err;
    if (affect_generate(j->p->m, (const affect_motion *const *)nb, n, &opt, &out, &rep, &err)) {
        fprintf(stderr, "bench_generate: affect_generate %s -> %s: %s\n", j->p->name,
                emotions[j->target], err.msg);
        goto done;
    }
    double t3 = now();

    t[S_SEARCH] = t1 - t0;
    t[S_READ] = t2 - t1;
    t[S_CORE] = t3 - t2;
    t[S_FEATURES] = rep.t_features;
    t[S_TRAIN] = rep.t_train;
    t[S_VITERBI] = rep.t_viterbi;
    t[S_RENDER] = rep.t_render;
    t[S_CORE_OTHER] = t[S_CORE] - (rep.t_features + rep.t_train + rep.t_viterbi + rep.t_render);
    t[S_SUM] = t3 - t0;
    if (check) {
        bool same = n == j->n_nb;
        for (uint32_t i = 0; same && i < n; i++)
            same = ids[i] == j->nb_id[i] && dist[i] == j->nb_dist[i];
        if (!same) {
            fprintf(stderr,
                    "bench_generate: %s -> %s: the neighbour search gave %u rows, not "
                    "the %u of affect_generate_explain (or other ones)\n",
                    j->p->name, emotions[j->target], n, j->n_nb);
            goto done;
        }
        if (affect_motion_encode(out, enc, enc_len, &err)) {
            fprintf(stderr, "bench_generate: encoding: %s\n", err.msg);
            goto done;
        }
        j->iterations = rep.iterations;
        j->used = rep.neighbours_used;
        j->train_frames = (uint64_t)w->copies * j->p->frames;
        for (uint32_t i = 0; i < n; i++)
            j->train_frames += nb[i]->n_frames;
    }
    rc = 0;
done:
    for (uint32_t i = 0; i < n; i++)
        affect_motion_free(nb[i]);
    affect_motion_free(out);
    affect_free(rep.path);
    return rc;
}

/* The whole SQL call; with want, *blob gets a copy of the result (free()). */
static int run_sql(sqlite3 *db, sqlite3_stmt *st, const workload *w, const job *j, double *t,
                   unsigned char **blob, size_t *len)
{
    double t0 = now();
    sqlite3_bind_text(st, 1, w->index, -1, SQLITE_STATIC);
    sqlite3_bind_blob(st, 2, j->p->blob, j->p->len, SQLITE_STATIC);
    sqlite3_bind_text(st, 3, emotions[j->target], -1, SQLITE_STATIC);
    sqlite3_bind_text(st, 4, j->opts, -1, SQLITE_STATIC);
    int rc = sqlite3_step(st);
    if (rc == SQLITE_ROW && blob) {
        *len = (size_t)sqlite3_column_bytes(st, 0);
        *blob = malloc(*len ? *len : 1);
        if (*blob)
            memcpy(*blob, sqlite3_column_blob(st, 0), *len);
    }
    sqlite3_reset(st);
    *t = now() - t0;
    if (rc != SQLITE_ROW) {
        fprintf(stderr, "bench_generate: affect_generate %s -> %s: %s\n", j->p->name,
                emotions[j->target], sqlite3_errmsg(db));
        return 1;
    }
    return 0;
}

static int bench_workload(sqlite3 *db, workload *w, uint32_t reps)
{
    sqlite3_stmt *st = NULL;
    unsigned char *a = NULL, *b = NULL;
    int rc = 1;
    double t0 = now(), c0 = cpu_now();
    if (explain_jobs(db, w) || bench_prepare(db, "SELECT affect_generate(?1, ?2, ?3, ?4)", &st))
        goto done;
    double warm[S_COUNT]; /* an untimed generation first */
    if (run_split(db, w, &w->jobs[0], warm, false, NULL, NULL) ||
        run_sql(db, st, w, &w->jobs[0], &warm[S_SQL], NULL, NULL))
        goto done;
    for (uint32_t r = 0; r < reps; r++) {
        for (uint32_t i = 0; i < w->n_jobs; i++) {
            job *j = &w->jobs[i];
            size_t na = 0, nb = 0;
            bool check = r == 0;
            if (run_split(db, w, j, j->t[r], check, check ? &a : NULL, &na) ||
                run_sql(db, st, w, j, &j->t[r][S_SQL], check ? &b : NULL, &nb))
                goto done;
            j->t[r][S_REST] = j->t[r][S_SQL] - j->t[r][S_SUM];
            if (check && (!a || !b || na != nb || memcmp(a, b, na) != 0)) {
                fprintf(stderr,
                        "bench_generate: %s -> %s: the core's motion (%zu bytes) is "
                        "not the SQL call's (%zu bytes)\n",
                        j->p->name, emotions[j->target], na, nb);
                goto done;
            }
            affect_free(a);
            free(b);
            a = NULL;
            b = NULL;
        }
    }
    /* per generation the median of its repetitions; per stage over the generations */
    double *v = malloc((size_t)w->n_jobs * sizeof *v), rv[MAX_REPS];
    if (!v)
        goto done;
    double worst_sql = -1;
    for (int s = 0; s < S_COUNT; s++) {
        for (uint32_t i = 0; i < w->n_jobs; i++) {
            for (uint32_t r = 0; r < reps; r++)
                rv[r] = w->jobs[i].t[r][s];
            v[i] = bench_summarize(rv, reps).median;
            if (s == S_SQL && v[i] > worst_sql) {
                worst_sql = v[i];
                w->worst = &w->jobs[i];
            }
        }
        w->s[s] = bench_summarize(v, w->n_jobs);
    }
    free(v);
    printf("  %-42s %3u generations x %u repetitions in %.1f s (CPU %.1f s)\n", w->title, w->n_jobs,
           reps, now() - t0, cpu_now() - c0);
    fflush(stdout);
    rc = 0;
done:
    affect_free(a);
    free(b);
    sqlite3_finalize(st);
    return rc;
}

/* 3. The default method (transfer): the SQL call on the 300-frame 22-joint paths to every
 * other emotion, with its defaults and the source label; per generation the median of reps
 * calls, then the median, mean and worst over the generations. */
static int bench_transfer(sqlite3 *db, const char *index, const path *paths, uint32_t n_paths,
                          uint32_t reps, bool quick)
{
    sqlite3_stmt *st = NULL;
    char sql[128];
    snprintf(sql, sizeof sql,
             "SELECT affect_generate('%s', ?1, ?2, json_object('source_label', ?3))", index);
    if (bench_prepare(db, sql, &st))
        return 1;
    double *med = calloc((size_t)n_paths * N_EMOTIONS + 1, sizeof *med), rv[MAX_REPS];
    uint32_t n = 0;
    int rc = 1;
    double c0 = cpu_now(), t0 = now();
    if (!med)
        goto done;
    for (uint32_t i = 0; i < n_paths && (!quick || i < 1); i++)
        for (int e = 0; e < N_EMOTIONS; e++) {
            if (e == paths[i].source)
                continue;
            for (uint32_t r = 0; r <= reps; r++) { /* the first call is the warm-up */
                double a = now();
                sqlite3_bind_blob(st, 1, paths[i].blob, paths[i].len, SQLITE_STATIC);
                sqlite3_bind_text(st, 2, emotions[e], -1, SQLITE_STATIC);
                sqlite3_bind_text(st, 3, emotions[paths[i].source], -1, SQLITE_STATIC);
                int step = sqlite3_step(st);
                sqlite3_reset(st);
                if (step != SQLITE_ROW) {
                    fprintf(stderr, "bench_generate: transfer %s -> %s: %s\n", paths[i].name,
                            emotions[e], sqlite3_errmsg(db));
                    goto done;
                }
                if (r > 0)
                    rv[r - 1] = now() - a;
            }
            med[n++] = bench_summarize(rv, reps).median;
        }
    bench_summary s = bench_summarize(med, n);
    printf("== 3. the default method (transfer): SQL affect_generate('%s', path, target, "
           "{\"source_label\"}), %u generations x %u repetitions in %.1f s (CPU %.1f s)\n",
           index, n, reps, now() - t0, cpu_now() - c0);
    printf("  per generation, ms: median %.3f, mean %.3f, worst %.3f; goal <= %.0f ms: %s "
           "(%.2fx)\n",
           s.median * 1e3, s.mean * 1e3, s.max * 1e3, TRANSFER_GOAL_MS,
           s.median * 1e3 <= TRANSFER_GOAL_MS ? "MET" : "NOT MET",
           TRANSFER_GOAL_MS / (s.median * 1e3));
    printf("BENCH transfer_%s_300_median %.3f ms\n", index, s.median * 1e3);
    printf("BENCH transfer_%s_300_worst %.3f ms\n", index, s.max * 1e3);
    rc = 0;
done:
    free(med);
    sqlite3_finalize(st);
    return rc;
}

/* The names in a JSON array of component names. */
static double count_components(const char *json)
{
    double quotes = 0;
    for (const char *c = json; c && *c; c++)
        quotes += *c == '"';
    return quotes / 2;
}

static void minmax_mean(const workload *w, int what, double *lo, double *hi, double *mean)
{
    *lo = 1e300;
    *hi = 0;
    double sum = 0;
    for (uint32_t i = 0; i < w->n_jobs; i++) {
        const job *j = &w->jobs[i];
        double x = what == 0   ? j->n_nb
                   : what == 1 ? j->iterations
                   : what == 2 ? (double)j->train_frames
                   : what == 3 ? j->p->frames
                               : count_components(j->comps);
        *lo = x < *lo ? x : *lo;
        *hi = x > *hi ? x : *hi;
        sum += x;
    }
    *mean = sum / w->n_jobs;
}

static void print_workload(const workload *w, uint32_t reps)
{
    double lo, hi, mean;
    printf("== %s\n", w->title);
    minmax_mean(w, 3, &lo, &hi, &mean);
    uint32_t n_paths = 0;
    for (uint32_t i = 0; i < w->n_jobs; i++)
        n_paths += i == 0 || w->jobs[i].p != w->jobs[i - 1].p;
    printf("%u generations (%u paths of %.0f", w->n_jobs, n_paths, lo);
    if (hi > lo)
        printf("-%.0f (mean %.0f)", hi, mean);
    printf(" frames x the other emotions), copies %u, %u repetitions each; ms, over the "
           "generations' medians\n",
           w->copies, reps);
    printf("%-30s %9s %9s %9s %9s\n", "stage", "median", "mean", "worst", "% of SQL");
    for (int s = 0; s < S_COUNT; s++)
        printf("%-30s %9.3f %9.3f %9.3f %8.1f%%\n", stage_names[s], w->s[s].median * 1e3,
               w->s[s].mean * 1e3, w->s[s].max * 1e3, 100.0 * w->s[s].median / w->s[S_SQL].median);
    minmax_mean(w, 4, &lo, &hi, &mean);
    printf("components searched: mean %.1f (%.0f-%.0f) of 27; ", mean, lo, hi);
    minmax_mean(w, 0, &lo, &hi, &mean);
    printf("neighbours: mean %.2f (%.0f-%.0f);\n", mean, lo, hi);
    minmax_mean(w, 1, &lo, &hi, &mean);
    printf("Baum-Welch iterations: mean %.1f (%.0f-%.0f); ", mean, lo, hi);
    minmax_mean(w, 2, &lo, &hi, &mean);
    printf("training frames (neighbours + copies x path): mean %.0f (%.0f-%.0f)\n", mean, lo, hi);
    if (w->worst)
        printf("slowest SQL call: %s -> %s, %.3f ms (%u neighbours, %u iterations)\n",
               w->worst->p->name, emotions[w->worst->target], w->s[S_SQL].max * 1e3, w->worst->n_nb,
               w->worst->iterations);
    printf("\n");
}

/* ---- main ---- */

/* Times the RMLR fit with {"threads":N} (or without options for N = 1) on ix22. */
static int rmlr_only(sqlite3 *db, uint32_t threads, uint32_t runs)
{
    char call[128], *json = NULL, *msg = NULL;
    double t[MAX_RMLR_RUNS];
    if (threads > 1)
        snprintf(call, sizeof call, "SELECT laban_salient('ix22', '{\"threads\":%u}')", threads);
    else
        snprintf(call, sizeof call, "SELECT laban_salient('ix22')");
    printf("== RMLR fit: %s, %u runs (the first call, then refits forced by "
           "deleting the stored fit and reloading the extension)\n",
           call + 7, runs);
    if (threads > 1) {
        bool accepted = false;
        if (threads_option(db, &accepted, &msg))
            return 1;
        if (!accepted) {
            printf("laban_salient has no threads option (it said \"%s\"): nothing measured\n", msg);
            free(msg);
            return 0;
        }
        free(msg);
    }
    /* the first run must fit: nothing stored for this generation */
    int rc = time_fits(db, "ix22", call, runs, t, &json);
    if (!rc) {
        bench_summary s = bench_summarize(t, runs);
        printf("median %.2f s (fastest %.2f, slowest %.2f)\n\n", s.median, s.min, s.max);
        printf("BENCH rmlr_fit_threads%u %.3f s\n", threads, s.median);
    }
    free(json);
    return rc;
}

int main(int argc, char **argv)
{
    const char *dir = AFFECT_BENCH_CORPUS, *module = AFFECT_BENCH_MODULE;
    uint32_t reps = DEFAULT_REPS, rmlr_runs = RMLR_RUNS, threads = 1;
    bool quick = false, only_rmlr = false, only_transfer = false;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--module") == 0 && i + 1 < argc) {
            module = argv[++i];
        } else if (strcmp(argv[i], "--reps") == 0 && i + 1 < argc) {
            if (bench_parse_count("--reps", argv[++i], MAX_REPS, &reps))
                return 2;
        } else if (strcmp(argv[i], "--rmlr-runs") == 0 && i + 1 < argc) {
            if (bench_parse_count("--rmlr-runs", argv[++i], MAX_RMLR_RUNS, &rmlr_runs))
                return 2;
        } else if (strcmp(argv[i], "--threads") == 0 && i + 1 < argc) {
            if (bench_parse_count("--threads", argv[++i], 64, &threads))
                return 2;
        } else if (strcmp(argv[i], "--quick") == 0) {
            quick = true;
        } else if (strcmp(argv[i], "--rmlr-only") == 0) {
            only_rmlr = true;
        } else if (strcmp(argv[i], "--transfer-only") == 0) {
            only_transfer = true;
        } else if (argv[i][0] == '-') {
            fprintf(stderr,
                    "usage: %s [corpus directory] [--module PATH] [--reps N] [--rmlr-runs N] "
                    "[--quick] [--rmlr-only [--threads N]] [--transfer-only]\n",
                    argv[0]);
            return 2;
        } else {
            dir = argv[i];
        }
    }
    if (quick) {
        reps = 1;
        rmlr_runs = 1;
    }

    sqlite3 *db = NULL;
    char *err = NULL;
    path *p22 = NULL, *p27 = NULL, *pnat = NULL;
    uint32_t n22 = 0, n27 = 0, nnat = 0;
    workload w[N_WORKLOADS];
    memset(w, 0, sizeof w);
    rmlr_result rr;
    memset(&rr, 0, sizeof rr);
    int rc = 1;
    if (sqlite3_open(":memory:", &db) != SQLITE_OK) {
        fprintf(stderr, "bench_generate: cannot open an in-memory database\n");
        goto done;
    }
    sqlite3_enable_load_extension(db, 1);
    bench_module = module;
    if (sqlite3_load_extension(db, module, "sqlite3_affect_init", &err) != SQLITE_OK) {
        printf("bench_generate: cannot load %s (%s): nothing to measure\n", module,
               err ? err : "?");
        sqlite3_free(err);
        rc = 0;
        goto done;
    }
    sqlite3_int64 have = 0;
    if (bench_query_int(db,
                        "SELECT count(*) FROM pragma_function_list WHERE name IN "
                        "('affect_generate', 'affect_generate_explain', 'laban_salient')",
                        &have))
        goto done;
    if (have < 3) {
        printf("bench_generate: %s has no affect_generate: nothing to measure\n", module);
        rc = 0;
        goto done;
    }

    print_load("at start");
    int blas_threads = openblas_get_num_threads();
    printf("openblas: %s; %d thread%s%s\n", openblas_get_config(), blas_threads,
           blas_threads == 1 ? "" : "s",
           blas_threads == 1 ? ""
                             : " (WARNING: set OPENBLAS_NUM_THREADS=1 for single-core numbers)");
    double import_s = 0, t0;
    sqlite3_int64 frames = 0;
    int lc = import_corpus(db, dir, &import_s, &frames);
    if (lc == 1) {
        printf("bench_generate: corpus directory %s not found: skipped (nothing measured)\n", dir);
        rc = 0;
        goto done;
    }
    if (lc || check_corpus(db) || make_corpus22(db))
        goto done;
    t0 = now();
    if (bench_exec(db, "CREATE VIRTUAL TABLE ix22 USING laban(content=corpus22, motion=motion, "
                       "label=emotion)"))
        goto done;
    double build22 = now() - t0, build27 = 0;
    bool with27 = !quick && !only_rmlr;
    if (with27) {
        t0 = now();
        if (bench_exec(db, "CREATE VIRTUAL TABLE ix27 USING laban(content=corpus27, motion=motion, "
                           "label=emotion)"))
            goto done;
        build27 = now() - t0;
    }
    printf("corpus: %s\n  %d recordings (angry, happy, normal, sad x bow, bye, byebye, dash, "
           "guide, run, walk (2 takes), walk-back, walk-left, walk-right), %lld frames at 30 "
           "fps;\n  motion_from_bvh of the 44 files %.2f s\n",
           dir, EXPECTED_MOTIONS, (long long)frames, import_s);
    printf("  corpus27: 27 joints (22 BVH joints + 5 End Sites); corpus22: motion_select "
           "without Head_end, Hand_L_end, Hand_R_end, Toes_L_end, Toes_R_end\n");
    printf("  laban index build: ix22 %.3f s", build22);
    if (with27)
        printf(", ix27 %.3f s", build27);
    printf("\n\n");
    fflush(stdout);

    if (only_rmlr) {
        rc = rmlr_only(db, threads, rmlr_runs);
        goto done;
    }
    if (only_transfer) {
        rc = load_paths(db, "corpus22", true, &p22, &n22) ||
             bench_transfer(db, "ix22", p22, n22, reps, quick) ||
             (with27 && (load_paths(db, "corpus27", true, &p27, &n27) ||
                         bench_transfer(db, "ix27", p27, n27, reps, quick)));
        goto done;
    }
    if (bench_rmlr(db, rmlr_runs, quick, with27, &rr))
        goto done;
    print_rmlr(&rr, quick, with27);
    fflush(stdout);

    if (load_paths(db, "corpus22", true, &p22, &n22))
        goto done;
    if (with27 && (load_paths(db, "corpus27", true, &p27, &n27) ||
                   load_paths(db, "corpus27", false, &pnat, &nnat)))
        goto done;
    printf("== 2. generation latency (SQL affect_generate and its stages, one generation at a "
           "time)\n");
    printf("paths of %d frames: the %u recordings with at least %d frames (motion_slice(motion, "
           "0, %d)):",
           PATH_FRAMES, n22, PATH_FRAMES, PATH_FRAMES - 1);
    for (uint32_t i = 0; i < n22; i++)
        printf("%s %s (%u)", i ? "," : "", p22[i].name, p22[i].recording_frames);
    printf("\n");
    if (n22 < FEW_PATHS)
        printf("  only %u recordings are that long (fewer than %d): all of them are used; each "
               "goes to the %d other emotions\n",
               n22, FEW_PATHS, N_EMOTIONS - 1);
    if (n22 == 0) {
        fprintf(stderr, "bench_generate: no recording has %d frames\n", PATH_FRAMES);
        goto done;
    }
    printf("options of every call: {%s, \"source_label\": <the recording's emotion>, "
           "\"copies\": n}; the rest the defaults (12 states, epsilon 0.1, cut-off 3 Hz, seed 1)\n",
           HMM_NN_OPTIONS);
    static const struct {
        const char *key, *title, *index, *content;
        uint32_t copies;
        int paths; /* 0: p22, 1: p27, 2: pnat */
    } spec[N_WORKLOADS] = {
        {"gen22_300_c0", "(i) 22 joints, 300 frames, copies 0", "ix22", "corpus22", 0, 0},
        {"gen22_300_c2", "(i) 22 joints, 300 frames, copies 2", "ix22", "corpus22", COPIES_MORE, 0},
        {"gen27_300_c0", "(ii) 27 joints, 300 frames, copies 0", "ix27", "corpus27", 0, 1},
        {"gen27_300_c2", "(ii) 27 joints, 300 frames, copies 2", "ix27", "corpus27", COPIES_MORE,
         1},
        {"gen27_natural_c0", "(iii) 27 joints, natural length, copies 0", "ix27", "corpus27", 0,
         2}};
    for (int k = 0; k < N_WORKLOADS; k++) {
        w[k].key = spec[k].key;
        w[k].title = spec[k].title;
        w[k].index = spec[k].index;
        w[k].content = spec[k].content;
        w[k].copies = spec[k].copies;
        w[k].paths = spec[k].paths == 0 ? p22 : spec[k].paths == 1 ? p27 : pnat;
        w[k].n_paths = spec[k].paths == 0 ? n22 : spec[k].paths == 1 ? n27 : nnat;
    }
    int n_work = with27 ? N_WORKLOADS : 2;
    for (int k = 0; k < n_work; k++)
        if (make_jobs(&w[k], quick ? 1 : EXPECTED_MOTIONS, quick ? 1 : N_EMOTIONS) ||
            bench_workload(db, &w[k], reps))
            goto done;
    if (bench_transfer(db, "ix22", p22, n22, reps, quick) ||
        (with27 && bench_transfer(db, "ix27", p27, n27, reps, quick)))
        goto done;
    printf("check: for every generation the neighbour search returned the rowids and distances "
           "of affect_generate_explain, and the core's motion had exactly the bytes of the SQL "
           "call's result\n");
    printf("rows: (a), (b) and (c) run in turn, then the SQL call; per generation the median of "
           "its repetitions, then over the generations the median, mean and worst; features, "
           "HMM training, Viterbi and render are (c)'s report (opt.clock); rest: what the SQL "
           "call does besides (a)-(c) (the path's decode, the index's vectors, the source and "
           "RMLR look-ups, the result's encoding)\n\n");
    for (int k = 0; k < n_work; k++)
        print_workload(&w[k], reps);

    printf("== summary: SQL affect_generate per generation, ms (over the generations' "
           "medians)\n");
    printf("%-42s %5s %9s %9s %9s  %s\n", "workload", "gens", "median", "mean", "worst",
           "largest stage (share of the SQL median)");
    for (int k = 0; k < n_work; k++) {
        static const int parts[] = {S_SEARCH,  S_READ,   S_FEATURES, S_TRAIN,
                                    S_VITERBI, S_RENDER, S_REST};
        int big = parts[0];
        for (size_t i = 1; i < sizeof parts / sizeof parts[0]; i++)
            if (w[k].s[parts[i]].median > w[k].s[big].median)
                big = parts[i];
        const char *name = stage_names[big];
        while (*name == ' ')
            name++;
        printf("%-42s %5u %9.3f %9.3f %9.3f  %s (%.1f%%)\n", w[k].title, w[k].n_jobs,
               w[k].s[S_SQL].median * 1e3, w[k].s[S_SQL].mean * 1e3, w[k].s[S_SQL].max * 1e3, name,
               100.0 * w[k].s[big].median / w[k].s[S_SQL].median);
    }
    double goal_ratio = w[0].s[S_SQL].median * 1e3 / GOAL_MS;
    printf("\ngoal (issue 6): median latency <= %.0f ms per generated motion, %d frames, 22 "
           "joints, one core (workload (i), copies 0): median %.3f ms = %.3f x the goal: %s\n\n",
           GOAL_MS, PATH_FRAMES, w[0].s[S_SQL].median * 1e3, goal_ratio,
           goal_ratio <= 1.0 ? "MET" : "NOT MET");

    double v[MAX_RMLR_RUNS];
    memcpy(v, rr.fit, rr.runs * sizeof *v);
    printf("BENCH rmlr_fit %.3f s\n", bench_summarize(v, rr.runs).median);
    if (with27)
        printf("BENCH rmlr_fit_27 %.3f s\n", rr.fit27);
    printf("BENCH rmlr_cached %.4f ms\n", rr.cached_memory * 1e3);
    for (int k = 0; k < n_work; k++) {
        printf("BENCH %s_sql_median %.3f ms\n", w[k].key, w[k].s[S_SQL].median * 1e3);
        printf("BENCH %s_sql_mean %.3f ms\n", w[k].key, w[k].s[S_SQL].mean * 1e3);
        printf("BENCH %s_sql_worst %.3f ms\n", w[k].key, w[k].s[S_SQL].max * 1e3);
        for (int s = 0; s < S_COUNT; s++)
            if (s != S_SQL && s != S_CORE_OTHER && s != S_SUM)
                printf("BENCH %s_%s_median %.3f ms\n", w[k].key, stage_keys[s],
                       w[k].s[s].median * 1e3);
    }
    printf("BENCH goal_ratio %.4f ratio\n", goal_ratio);
    print_load("at end");
    rc = 0;
done:
    free_paths(p22, n22);
    free_paths(p27, n27);
    free_paths(pnat, nnat);
    for (int k = 0; k < N_WORKLOADS; k++) {
        for (uint32_t i = 0; w[k].jobs && i < w[k].n_jobs; i++)
            free(w[k].jobs[i].comps);
        free(w[k].jobs);
    }
    free(rr.json);
    free(rr.summary);
    free(rr.summary27);
    free(rr.threads_note);
    sqlite3_close(db);
    return rc;
}
