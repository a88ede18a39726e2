/*
 * interrupt_run.h — the long SQL calls of issue 14 (item 3) and one interrupted run of a call,
 * measured; shared by tests/sql/test_interrupt.c (which asserts) and
 * tests/bench/bench_interrupt.c (which reports medians). Static definitions: include it once
 * per program.
 *
 *     ir_open(module);                      the connection, the module, note(), the corpus
 *     ir_run(&IR_CASES[i], &r);             one run: r.rc, r.msg, r.latency, r.cpu, …
 *
 * The corpus (IR_CORPUS): sql/synth_corpus.sql's 80 motion_synth motions (4 actions × 4
 * emotions × performers 1-5) in `motions`, their laban index `motion_laban`, and 8 walks at 1000
 * fps (3000-6200 frames) in `long` with their index `long_laban`.
 * How a run is stopped (ir_how):
 *   IR_THREAD   a second thread calls sqlite3_interrupt(db) `delay` seconds after the step
 *               starts; the latency counts from that call;
 *   IR_HANDLER  sqlite3_progress_handler(db, 1000, h) with h returning 1 from `delay` seconds
 *               after the start on; the latency counts from that moment (SQLite calls h every
 *               1000 VM steps, so its first call that says stop may come later);
 *   IR_STAGE    the SQL function note(stage, done, total), named by the call's option
 *               "progress", calls sqlite3_interrupt as the call shows `stage` ("<stage> (end)":
 *               as it shows that stage with done == total); the latency counts from then;
 *   IR_ROW      the SQL function interrupt_if(x), in the statement's WHERE clause, calls
 *               sqlite3_interrupt at the first row where x is true (an aggregate is interrupted
 *               while it reads its rows, a scalar function just before it starts); the latency
 *               counts from then.
 * r.cpu is the process's CPU time over the same span (all threads): on a shared machine the
 * wall time also measures the other processes.
 */
#ifndef AFFECT_INTERRUPT_RUN_H
#define AFFECT_INTERRUPT_RUN_H

#include <sqlite3.h>

#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <threads.h>
#include <time.h>

typedef enum ir_how { IR_THREAD, IR_HANDLER, IR_STAGE, IR_ROW } ir_how;

typedef struct ir_case {
    const char *name, *sql;
    const char *fn;  /* the expected message is "<fn>: interrupted" */
    const char *alt; /* another accepted message, or NULL */
    ir_how how;
    double delay;      /* IR_THREAD, IR_HANDLER: seconds after the start */
    const char *stage; /* IR_STAGE */
} ir_case;

#define IR_INTERRUPT_AFTER 0.3
/* the name of the cases on the large motions ends in this (IR_BIG_CORPUS) */
#define IR_BIG "615,701 frames"
#define IR_BIG_HMM "\"states\":7,\"mixtures\":4,\"covariance\":\"full\""
/* hmm_train alone converges in about 2 s (Release): every iteration instead */
#define IR_LONG_HMM IR_BIG_HMM ",\"max_iter\":200,\"tol\":0"
#define IR_FISHER_TRAIN                                                                            \
    "SELECT affect_train(motion, emotion, '{\"states\":5,\"mixtures\":2,"                          \
    "\"covariance\":\"full\",\"max_iter\":10,\"progress\":\"note\"}') FROM motions"
#define IR_DTW                                                                                     \
    "SELECT motion_dtw(a.motion, b.motion) FROM long a, long b WHERE a.id = 1 AND b.id = 2"

/* Each runs for seconds uninterrupted (most for tens of seconds), except the rebuild (about
 * 0.2 s: interrupted earlier). */
static const ir_case IR_CASES[] = {
    {"hmm_train 7x4 full", "SELECT hmm_train(motion, '{" IR_LONG_HMM "}') FROM motions",
     "hmm_train", NULL, IR_THREAD, IR_INTERRUPT_AFTER, NULL},
    {"affect_train 7x4 full",
     "SELECT affect_train(motion, emotion, '{" IR_BIG_HMM "}') FROM motions", "affect_train", NULL,
     IR_THREAD, IR_INTERRUPT_AFTER, NULL},
    {"affect_train 7x4 full, threads 2",
     "SELECT affect_train(motion, emotion, '{" IR_BIG_HMM ",\"threads\":2}') FROM motions",
     "affect_train", NULL, IR_THREAD, IR_INTERRUPT_AFTER, NULL},
    /* the table-valued function runs affect_crossval_json and prefixes its errors */
    {"affect_crossval 7x4 full",
     "SELECT * FROM affect_crossval('motions', 'motion', 'emotion', '{" IR_BIG_HMM
     ",\"folds\":4}')",
     "affect_crossval", NULL, IR_THREAD, IR_INTERRUPT_AFTER, NULL},
    {"affect_crossval 7x4 full, threads 2",
     "SELECT * FROM affect_crossval('motions', 'motion', 'emotion', '{" IR_BIG_HMM
     ",\"folds\":4,\"threads\":2}')",
     "affect_crossval", NULL, IR_THREAD, IR_INTERRUPT_AFTER, NULL},
    {"motion_dtw 6158 x 6000 frames", IR_DTW, "motion_dtw", NULL, IR_THREAD, IR_INTERRUPT_AFTER,
     NULL},
    {"laban_salient (RMLR fit)", "SELECT laban_salient('motion_laban')", "laban_salient", NULL,
     IR_THREAD, IR_INTERRUPT_AFTER, NULL},
    /* 20 folds: with two threads the default fit ends in about 0.3 s (Release), and a fit that
     * ends before the interrupt would also be cached for the calls below */
    {"laban_salient (RMLR fit, 20 folds), threads 2",
     "SELECT laban_salient('motion_laban', '{\"threads\":2,\"folds\":20}')", "laban_salient", NULL,
     IR_THREAD, IR_INTERRUPT_AFTER, NULL},
    {"affect_generate transfer (RMLR fit)",
     "SELECT affect_generate('motion_laban', motion, 'angry') FROM motions WHERE id = 1",
     "affect_generate", NULL, IR_THREAD, IR_INTERRUPT_AFTER, NULL},
    {"affect_generate_explain (RMLR fit)",
     "SELECT affect_generate_explain('motion_laban', motion, 'angry') FROM motions WHERE id = 1",
     "affect_generate_explain", NULL, IR_THREAD, IR_INTERRUPT_AFTER, NULL},
    /* the exact keyframe selection of a 6,158-frame walk (a 6,158² cost table), and for the edit
     * the rigid projection and the corrections after it */
    {"affect_strength, 6158 frames",
     "SELECT affect_strength(r, motion) FROM strength, long WHERE long.id = 1", "affect_strength",
     NULL, IR_THREAD, IR_INTERRUPT_AFTER, NULL},
    {"strength_edit, 6158 frames",
     "SELECT strength_edit(r, motion, 0.5) FROM strength, long WHERE long.id = 1", "strength_edit",
     NULL, IR_THREAD, IR_INTERRUPT_AFTER, NULL},
    /* a Fisher model's edit: gradient steps, each with the recognizer's posteriors and a rigid
     * projection of the 6,158 frames */
    {"strength_edit (Fisher model), 6158 frames",
     "SELECT strength_edit(r, motion, 0.5) FROM strength_fisher, long WHERE long.id = 1",
     "strength_edit", NULL, IR_THREAD, IR_INTERRUPT_AFTER, NULL},
    /* the default (Fisher) features: the recognizer's class HMMs and Fisher scores of six
     * 6,158-frame walks (2 keyframes, so that the keyframe selection takes no time; 1 s) */
    {"strength_train, Fisher features",
     "SELECT strength_train(motion, emotion, '{\"order\":[\"sad\",\"neutral\",\"happy\"],"
     "\"keyframes\":2}') FROM long",
     "strength_train", NULL, IR_THREAD, IR_INTERRUPT_AFTER, NULL},
    {"affect_generate hmm_nn (HMM training)",
     "SELECT affect_generate('motion_laban', motion, 'angry', '{\"method\":\"hmm_nn\","
     "\"components\":[\"WeightAll\",\"TimeAll\"],\"k\":20,\"min_neighbours\":20,"
     "\"states\":80,\"copies\":40,\"prefer_action\":false}') FROM motions WHERE id = 1",
     "affect_generate", NULL, IR_THREAD, IR_INTERRUPT_AFTER, NULL},
    /* single calls on one motion at the size limit (`big`: 615,701 frames x 26 joints,
     * 16,008,226 samples, positions only; `bigsk`: the same with joint rotations; `bigbvh`:
     * its BVH text), each seconds to minutes of work uninterrupted */
    {"laban_vector, " IR_BIG, "SELECT laban_vector(m) FROM big", "laban_vector", NULL, IR_THREAD,
     IR_INTERRUPT_AFTER, NULL},
    {"laban_shape_flow, " IR_BIG, "SELECT laban_shape_flow(m) FROM big", "laban_shape_flow", NULL,
     IR_THREAD, IR_INTERRUPT_AFTER, NULL},
    {"motion_kinematics, " IR_BIG, "SELECT motion_kinematics(m) FROM big", "motion_kinematics",
     NULL, IR_THREAD, 0.1, NULL},
    {"motion_rigid, " IR_BIG, "SELECT motion_rigid(m) FROM big", "motion_rigid", NULL, IR_THREAD,
     IR_INTERRUPT_AFTER, NULL},
    {"motion_to_bvh by inverse kinematics, " IR_BIG, "SELECT motion_to_bvh(m) FROM big",
     "motion_to_bvh", NULL, IR_THREAD, IR_INTERRUPT_AFTER, NULL},
    {"motion_to_bvh of stored rotations, " IR_BIG, "SELECT motion_to_bvh(m) FROM bigsk",
     "motion_to_bvh", NULL, IR_THREAD, IR_INTERRUPT_AFTER, NULL},
    {"motion_angles by inverse kinematics, " IR_BIG,
     "SELECT count(*) FROM motion_angles((SELECT m FROM big))", "motion_angles", NULL, IR_THREAD,
     IR_INTERRUPT_AFTER, NULL},
    {"laban_series, " IR_BIG, "SELECT count(*), max(weight) FROM big, laban_series(big.m)",
     "laban_series", NULL, IR_THREAD, IR_INTERRUPT_AFTER, NULL},
    {"laban_series, one window, " IR_BIG,
     "SELECT count(*) FROM big, laban_series(big.m, '{\"window_frames\":615701,"
     "\"parts\":\"all\",\"time_method\":\"accumulated\"}')",
     "laban_series", NULL, IR_THREAD, IR_INTERRUPT_AFTER, NULL},
    {"motion_from_bvh, " IR_BIG, "SELECT motion_from_bvh(t) FROM bigbvh", "motion_from_bvh", NULL,
     IR_THREAD, IR_INTERRUPT_AFTER, NULL},
    {"motion_bvh_error, " IR_BIG, "SELECT motion_bvh_error(t) FROM bigbvh", "motion_bvh_error",
     NULL, IR_THREAD, IR_INTERRUPT_AFTER, NULL},
    {"motion_to_json, " IR_BIG, "SELECT motion_to_json(m) FROM big", "motion_to_json", NULL,
     IR_THREAD, IR_INTERRUPT_AFTER, NULL},
    {"motion_to_csv, " IR_BIG, "SELECT motion_to_csv(m) FROM big", "motion_to_csv", NULL, IR_THREAD,
     IR_INTERRUPT_AFTER, NULL},
    {"hmm_loglik 7x4 full, " IR_BIG, "SELECT hmm_loglik(h, m) FROM bigmodel, big", "hmm_loglik",
     NULL, IR_THREAD, IR_INTERRUPT_AFTER, NULL},
    {"hmm_viterbi 7x4 full, " IR_BIG, "SELECT hmm_viterbi(h, m) FROM bigmodel, big", "hmm_viterbi",
     NULL, IR_THREAD, IR_INTERRUPT_AFTER, NULL},
    {"affect_classify, " IR_BIG, "SELECT affect_classify(c, m) FROM bigmodel, big",
     "affect_classify", NULL, IR_THREAD, IR_INTERRUPT_AFTER, NULL},
    {"affect_classify ml, " IR_BIG, "SELECT affect_classify(c, m, 'ml') FROM bigmodel, big",
     "affect_classify", NULL, IR_THREAD, IR_INTERRUPT_AFTER, NULL},
    {"fisher_score, " IR_BIG, "SELECT length(fisher_score(c, m)) FROM bigmodel, big",
     "fisher_score", NULL, IR_THREAD, IR_INTERRUPT_AFTER, NULL},
    {"affect_generate onto " IR_BIG,
     "SELECT affect_generate('motion_laban', m, 'angry', '{\"source_label\":\"neutral\"}') "
     "FROM big",
     "affect_generate", NULL, IR_THREAD, IR_INTERRUPT_AFTER, NULL},
    /* SQLite's own statements run it: it stops between rows */
    {"laban rebuild (8 walks at 1000 fps)", "INSERT INTO long_laban(long_laban) VALUES('rebuild')",
     "laban", NULL, IR_THREAD, 0.05, NULL},
    /* affect_train's later stages (5 x 2 full, 80 motions); "(end)": the work between the two
     * passes of the Fisher scores (normalization, SVM, grid, sPCA), which polls nothing */
    {"affect_train: Fisher scores, first pass", IR_FISHER_TRAIN, "affect_train", NULL, IR_STAGE, 0,
     "Fisher scores, first pass"},
    {"affect_train: Fisher scores, first pass (end)", IR_FISHER_TRAIN, "affect_train", NULL,
     IR_STAGE, 0, "Fisher scores, first pass (end)"},
    {"affect_train: Fisher scores, second pass", IR_FISHER_TRAIN, "affect_train", NULL, IR_STAGE, 0,
     "Fisher scores, second pass"},
    /* interrupted while the aggregate reads its rows: at row 40 of 80 (SQLite stops reading and
     * finalizes the aggregate as it cleans up), and at the last row (the aggregate's final step
     * then runs as usual, with the interrupt pending) */
    {"hmm_train, interrupted at row 40 of 80",
     "SELECT hmm_train(motion, '{" IR_BIG_HMM "}') FROM motions WHERE interrupt_if(id = 40)",
     "hmm_train", NULL, IR_ROW, 0, NULL},
    {"hmm_train, interrupted at the last row",
     "SELECT hmm_train(motion, '{" IR_BIG_HMM "}') FROM motions WHERE interrupt_if(id = 80)",
     "hmm_train", NULL, IR_ROW, 0, NULL},
    {"affect_train, interrupted at the last row",
     "SELECT affect_train(motion, emotion, '{" IR_BIG_HMM "}') FROM motions "
     "WHERE interrupt_if(id = 80)",
     "affect_train", NULL, IR_ROW, 0, NULL},
    /* interrupted just before the call starts (interrupt_if in its own statement's WHERE):
     * the interrupt is pending at the call's first poll */
    {"motion_dtw, interrupted just before it starts", IR_DTW " AND interrupt_if(1)", "motion_dtw",
     NULL, IR_ROW, 0, NULL},
    {"laban_salient, interrupted just before it starts",
     "SELECT laban_salient('motion_laban') WHERE interrupt_if(1)", "laban_salient", NULL, IR_ROW, 0,
     NULL},
    /* a progress handler instead of sqlite3_interrupt */
    {"hmm_train, progress handler (1000 steps)",
     "SELECT hmm_train(motion, '{" IR_LONG_HMM "}') FROM motions", "hmm_train", NULL, IR_HANDLER,
     IR_INTERRUPT_AFTER, NULL},
    {"motion_dtw, progress handler (1000 steps)", IR_DTW, "motion_dtw", NULL, IR_HANDLER,
     IR_INTERRUPT_AFTER, NULL},
};
#define IR_N_CASES (sizeof IR_CASES / sizeof IR_CASES[0])

static const char IR_CORPUS[] =
    "CREATE TABLE motions(id INTEGER PRIMARY KEY, content TEXT, emotion TEXT, performer INT,"
    "                     motion BLOB);"
    "WITH actions(action) AS (VALUES ('knock'), ('wave'), ('walk'), ('bow')),"
    "     emotions(emotion) AS (VALUES ('neutral'), ('happy'), ('sad'), ('angry')),"
    "     seeds(seed) AS (SELECT 1 UNION ALL SELECT seed + 1 FROM seeds WHERE seed < 5)"
    "INSERT INTO motions(content, emotion, performer, motion)"
    "  SELECT action, emotion, seed, motion_synth(action, emotion, seed)"
    "    FROM actions, emotions, seeds ORDER BY action, emotion, seed;"
    "CREATE VIRTUAL TABLE motion_laban USING laban(content=motions, motion=motion,"
    "                                              label=emotion);"
    "CREATE TABLE strength AS SELECT strength_train(motion, emotion,"
    "  '{\"order\":[\"sad\",\"neutral\",\"happy\"],\"features\":\"keyframes\"}') AS r"
    "  FROM motions"
    " WHERE emotion IN ('sad', 'neutral', 'happy');"
    "CREATE TABLE strength_fisher AS SELECT strength_train(motion, emotion,"
    "  '{\"order\":[\"sad\",\"neutral\",\"happy\"]}') AS r"
    "  FROM motions"
    " WHERE emotion IN ('sad', 'neutral', 'happy');"
    "CREATE TABLE long(id INTEGER PRIMARY KEY, emotion TEXT, motion BLOB);"
    "INSERT INTO long(emotion, motion) VALUES"
    "  ('sad', motion_synth('walk', 'sad', 1, '{\"fps\":1000}')),"
    "  ('sad', motion_synth('walk', 'sad', 2, '{\"fps\":1000}')),"
    "  ('angry', motion_synth('walk', 'angry', 3, '{\"fps\":1000}')),"
    "  ('angry', motion_synth('walk', 'angry', 4, '{\"fps\":1000}')),"
    "  ('happy', motion_synth('walk', 'happy', 5, '{\"fps\":1000}')),"
    "  ('happy', motion_synth('walk', 'happy', 6, '{\"fps\":1000}')),"
    "  ('neutral', motion_synth('walk', 'neutral', 7, '{\"fps\":1000}')),"
    "  ('neutral', motion_synth('walk', 'neutral', 8, '{\"fps\":1000}'));"
    "CREATE VIRTUAL TABLE long_laban USING laban(content=long, motion=motion, label=emotion);";

/* The cases on one motion at the size limit (their names end in IR_BIG) and what they read
 * (ir_open_big; about 10 s to build): `big`, 615,701 frames x 26 joints = 16,008,226 samples,
 * positions only (a 192 MB BLOB); `bigsk`, the same with joint rotations (450 MB); `bigbvh`,
 * its BVH text (443 MB); `bigmodel`, a 7 x 4 full HMM and a classifier. SQLite's own reading
 * of such a value and its decoding take 0.2-0.4 s of CPU before the call can poll (measured:
 * docs/BENCHMARKS.md), so these cases have their own bound. */
static const char IR_BIG_CORPUS[] =
    "CREATE TABLE big AS SELECT motion_resample(motion_synth('walk', 'sad', 1,"
    "                                                     '{\"fps\":1000}'), 100000) AS m;"
    "CREATE TABLE bigsk AS SELECT motion_resample(motion_from_bvh(motion_to_bvh("
    "  motion_synth('walk', 'sad', 1, '{\"fps\":1000}'))), 100000) AS m;"
    "CREATE TABLE bigbvh AS SELECT motion_to_bvh(m) AS t FROM bigsk;"
    "CREATE TABLE bigmodel AS SELECT"
    "  (SELECT hmm_train(motion, '{" IR_BIG_HMM ",\"max_iter\":2}') FROM motions) AS h,"
    "  (SELECT affect_train(motion, emotion, '{\"states\":3,\"mixtures\":1,"
    "                       \"max_iter\":2}') FROM motions) AS c;";

static sqlite3 *ir_db;

static double ir_clock(clockid_t id)
{
    struct timespec ts;
    clock_gettime(id, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static double ir_now(void)
{
    return ir_clock(CLOCK_MONOTONIC);
}

/* CPU time of the whole process (every thread). */
static double ir_cpu(void)
{
    return ir_clock(CLOCK_PROCESS_CPUTIME_ID);
}

/* ---- note(stage, done, total): the progress function ---- */

typedef struct ir_progress {
    long calls;
    char stage[64]; /* the last call's */
    long long done, total;
    char bad[256];            /* the first inconsistent call: done > total, or done going back */
    char stages[512];         /* the stages in order (a stage again after another: again) */
    const char *interrupt_at; /* IR_STAGE's stage (NULL: never) */
    double interrupted_at, cpu_at;
} ir_progress;

static ir_progress ir_plog;

static void ir_note(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    (void)argc;
    const char *stage = (const char *)sqlite3_value_text(argv[0]);
    long long done = sqlite3_value_int64(argv[1]), total = sqlite3_value_int64(argv[2]);
    ir_progress *p = &ir_plog;
    if (!stage)
        stage = "(null)";
    if (!p->bad[0] && (done > total || done < 0))
        snprintf(p->bad, sizeof p->bad, "call %ld: stage \"%s\", done %lld of %lld", p->calls + 1,
                 stage, done, total);
    bool same = p->calls > 0 && strcmp(stage, p->stage) == 0;
    if (!p->bad[0] && same && done < p->done && total == p->total)
        snprintf(p->bad, sizeof p->bad, "call %ld: stage \"%s\" went back from %lld to %lld",
                 p->calls + 1, stage, p->done, done);
    if (!same) {
        size_t len = strlen(p->stages);
        snprintf(p->stages + len, sizeof p->stages - len, "%s%s", len ? " | " : "", stage);
    }
    p->calls++;
    snprintf(p->stage, sizeof p->stage, "%s", stage);
    p->done = done;
    p->total = total;
    size_t len = p->interrupt_at ? strlen(p->interrupt_at) : 0;
    bool at_end = len > 6 && strcmp(p->interrupt_at + len - 6, " (end)") == 0;
    if (at_end)
        len -= 6;
    if (p->interrupt_at && p->interrupted_at == 0 && strncmp(stage, p->interrupt_at, len) == 0 &&
        stage[len] == '\0' && (!at_end || done == total)) {
        p->interrupted_at = ir_now();
        p->cpu_at = ir_cpu();
        sqlite3_interrupt(sqlite3_context_db_handle(ctx));
    }
    sqlite3_result_null(ctx);
}

/* interrupt_if(x): sqlite3_interrupt at the first row where x is true; returns 1. */
static double ir_row_fired, ir_row_cpu;

static void ir_interrupt_if(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    (void)argc;
    if (sqlite3_value_int(argv[0]) && ir_row_fired == 0) {
        ir_row_fired = ir_now();
        ir_row_cpu = ir_cpu();
        sqlite3_interrupt(sqlite3_context_db_handle(ctx));
    }
    sqlite3_result_int(ctx, 1);
}

/* ---- the interrupter thread and the progress handler ---- */

typedef struct ir_interrupter {
    double delay, start;
    double fired_at, cpu_at; /* fired_at 0: not fired */
    mtx_t lock;
    cnd_t cond;
    bool cancel;
} ir_interrupter;

static int ir_interrupter_main(void *arg)
{
    ir_interrupter *it = arg;
    struct timespec until;
    clock_gettime(CLOCK_REALTIME, &until); /* cnd_timedwait's clock */
    double d = it->delay - (ir_now() - it->start);
    if (d < 0)
        d = 0;
    until.tv_sec += (time_t)d;
    until.tv_nsec += (long)((d - (double)(time_t)d) * 1e9);
    if (until.tv_nsec >= 1000000000L) {
        until.tv_sec++;
        until.tv_nsec -= 1000000000L;
    }
    mtx_lock(&it->lock);
    while (!it->cancel && cnd_timedwait(&it->cond, &it->lock, &until) != thrd_timedout) {
    }
    if (!it->cancel) {
        it->fired_at = ir_now();
        it->cpu_at = ir_cpu();
        sqlite3_interrupt(ir_db);
    }
    mtx_unlock(&it->lock);
    return 0;
}

typedef struct ir_handler {
    double stop_at;   /* says stop from then on */
    double first_yes; /* its first call at or after stop_at (0: none) */
    double cpu_first_yes;
    long calls;
} ir_handler;

static ir_handler ir_hstate;

static int ir_handler_fn(void *arg)
{
    (void)arg;
    ir_hstate.calls++;
    double t = ir_now();
    if (t < ir_hstate.stop_at)
        return 0;
    if (ir_hstate.first_yes == 0) {
        ir_hstate.first_yes = t;
        ir_hstate.cpu_first_yes = ir_cpu();
    }
    return 1;
}

/* ---- one run ---- */

typedef struct ir_result {
    int rc, xrc;    /* sqlite3_step's result and the extended error code */
    char msg[512];  /* sqlite3_errmsg after the step */
    double elapsed; /* seconds from the start of the step to its return */
    bool fired;     /* the interrupt came (or the handler said stop) before the return */
    double latency; /* seconds from the interrupt to the return */
    double cpu;     /* process CPU seconds over that span (handler: from its first yes) */
    long handler_calls;
    double handler_late; /* seconds from stop_at to the handler's first yes */
} ir_result;

/* Runs c once (its first step); false when the statement cannot be prepared (r->msg says). */
static bool ir_run(const ir_case *c, ir_result *r)
{
    memset(r, 0, sizeof *r);
    sqlite3_stmt *st = NULL;
    if (sqlite3_prepare_v2(ir_db, c->sql, -1, &st, NULL) != SQLITE_OK) {
        snprintf(r->msg, sizeof r->msg, "%s", sqlite3_errmsg(ir_db));
        return false;
    }
    ir_interrupter it = {.delay = c->delay};
    thrd_t th;
    memset(&ir_plog, 0, sizeof ir_plog);
    memset(&ir_hstate, 0, sizeof ir_hstate);
    ir_row_fired = ir_row_cpu = 0;
    double start = ir_now();
    if (c->how == IR_THREAD) {
        it.start = start;
        if (mtx_init(&it.lock, mtx_plain) != thrd_success || cnd_init(&it.cond) != thrd_success ||
            thrd_create(&th, ir_interrupter_main, &it) != thrd_success) {
            fprintf(stderr, "cannot start the interrupter thread\n");
            exit(1);
        }
    } else if (c->how == IR_HANDLER) {
        ir_hstate.stop_at = start + c->delay;
        sqlite3_progress_handler(ir_db, 1000, ir_handler_fn, NULL);
    } else if (c->how == IR_STAGE) {
        ir_plog.interrupt_at = c->stage;
    }
    r->rc = sqlite3_step(st);
    double end = ir_now(), cpu_end = ir_cpu();
    r->elapsed = end - start;
    double fired = 0, cpu_fired = 0;
    if (c->how == IR_THREAD) {
        mtx_lock(&it.lock);
        it.cancel = true;
        cnd_signal(&it.cond);
        mtx_unlock(&it.lock);
        thrd_join(th, NULL);
        mtx_destroy(&it.lock);
        cnd_destroy(&it.cond);
        fired = it.fired_at;
        cpu_fired = it.cpu_at;
    } else if (c->how == IR_HANDLER) {
        sqlite3_progress_handler(ir_db, 0, NULL, NULL);
        if (ir_hstate.first_yes != 0) {
            fired = ir_hstate.stop_at; /* when the handler would have said stop */
            cpu_fired = ir_hstate.cpu_first_yes;
            r->handler_late = ir_hstate.first_yes - ir_hstate.stop_at;
        }
        r->handler_calls = ir_hstate.calls;
    } else if (c->how == IR_STAGE) {
        fired = ir_plog.interrupted_at;
        cpu_fired = ir_plog.cpu_at;
    } else {
        fired = ir_row_fired;
        cpu_fired = ir_row_cpu;
    }
    snprintf(r->msg, sizeof r->msg, "%s", sqlite3_errmsg(ir_db));
    r->xrc = sqlite3_extended_errcode(ir_db);
    sqlite3_finalize(st);
    r->fired = fired != 0 && fired <= end;
    if (r->fired) {
        r->latency = end - fired;
        r->cpu = cpu_end - cpu_fired;
    }
    return true;
}

/* Opens ir_db in memory, loads the module, registers note and builds the corpus; exits with a
 * message on failure. */
static void ir_open(const char *module)
{
    char *err = NULL;
    if (sqlite3_open(":memory:", &ir_db) != SQLITE_OK) {
        fprintf(stderr, "cannot open a database\n");
        exit(1);
    }
    sqlite3_enable_load_extension(ir_db, 1);
    if (sqlite3_load_extension(ir_db, module, "sqlite3_affect_init", &err) != SQLITE_OK) {
        fprintf(stderr, "cannot load %s: %s\n", module, err ? err : "?");
        exit(1);
    }
    if (sqlite3_create_function(ir_db, "note", 3, SQLITE_UTF8, NULL, ir_note, NULL, NULL) !=
            SQLITE_OK ||
        sqlite3_create_function(ir_db, "interrupt_if", 1, SQLITE_UTF8, NULL, ir_interrupt_if, NULL,
                                NULL) != SQLITE_OK ||
        sqlite3_exec(ir_db, IR_CORPUS, NULL, NULL, &err) != SQLITE_OK) {
        fprintf(stderr, "cannot build the corpus: %s\n", err ? err : sqlite3_errmsg(ir_db));
        exit(1);
    }
}

/* Adds IR_BIG_CORPUS to the connection of ir_open. */
static void ir_open_big(void)
{
    char *err = NULL;
    if (sqlite3_exec(ir_db, IR_BIG_CORPUS, NULL, NULL, &err) != SQLITE_OK) {
        fprintf(stderr, "cannot build the large motions: %s\n", err ? err : sqlite3_errmsg(ir_db));
        exit(1);
    }
}

/* Whether c is one of the cases on the large motions. */
static inline bool ir_is_big(const ir_case *c)
{
    size_t n = strlen(c->name), b = strlen(IR_BIG);
    return n >= b && strcmp(c->name + n - b, IR_BIG) == 0;
}

#endif
