/*
 * test_interrupt.c — long SQL calls stop when asked (issue 14, item 3: "every call returns
 * `interrupted` within 0.2 s of the interrupt, with no leak; and a progress report a user can
 * watch"), through a real connection with the built module loaded.
 *
 * Usage: test_interrupt MODULE [CASE]             (ctest: sql/interrupt)
 *   CASE: run only the cases whose name contains it. The latencies' medians over several runs:
 *   tests/bench/bench_interrupt.c.
 *
 * The calls, the corpus and how each run is stopped: interrupt_run.h (hmm_train, affect_train,
 * affect_crossval, motion_dtw, laban_salient, affect_generate, affect_generate_explain,
 * affect_strength, strength_edit and the laban index's 'rebuild', each running for seconds
 * uninterrupted; an interrupt from a second thread 0.3 s after the step starts, from the progress
 * function as affect_train reaches a stage, from a function in the statement's WHERE clause (while
 * an aggregate reads its rows, or just before a scalar call starts: the interrupt is then pending
 * at the call's first poll), or a progress handler that says stop from 0.3 s on). Checked for each,
 * twice: sqlite3_step returns SQLITE_INTERRUPT (also the extended code) with the message
 * "<fn>: interrupted" (or SQLite's own "interrupted"), within LATENCY_MAX of the
 * interrupt (printed: the goal is 0.2 s; the bound leaves room for the sanitizer build and a
 * loaded 2-core machine); the connection works afterwards; and the second run leaves the memory
 * SQLite reports in use as the first left it (no leak; the sanitizer build checks the whole
 * process too).
 * Progress: hmm_train, affect_train and affect_crossval with {"progress":"note"} call the
 * registered function note(stage, done, total) with done ≤ total, done never decreasing within
 * a stage, and end on done == total; a name that is not a function is
 * 'hmm_train: option "progress": no such function: nope' (and the same for the other two).
 */
#define _POSIX_C_SOURCE 200809L /* clock_gettime */
#include "interrupt_run.h"

#include <stdarg.h>

/* Seconds from the interrupt to the return of sqlite3_step, at most. */
#define LATENCY_MAX 1.0
/* The same for the calls on the large motions (IR_BIG_CORPUS), whose value SQLite reads and we
 * decode before the first poll: wall seconds, and process CPU seconds (a loaded machine
 * stretches the wall time, not the CPU time). */
#define LATENCY_MAX_BIG 8.0
#define CPU_MAX_BIG 1.2
/* Whether the cases on the large motions run: not in the sanitizer build, whose decoding of
 * hundreds of megabytes takes seconds (the latency there measures the instrumentation). */
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_UNDEFINED__)
#define RUN_BIG false
#else
#define RUN_BIG true
#endif
/* Runs of each case: the second checks the memory in use against the first's. */
#define RUNS 2

static int failures, checks;
static const char *only; /* run only the cases whose name contains this */

static void fail(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    printf("FAIL: ");
    vprintf(fmt, ap);
    printf("\n");
    va_end(ap);
    fflush(stdout);
    failures++;
}

static bool selected(const char *name)
{
    return !only || strstr(name, only) != NULL;
}

/* One interrupted run of c, checked; false on a failure. */
static bool check_run(const ir_case *c)
{
    ir_result r;
    checks++;
    if (!ir_run(c, &r)) {
        fail("%s: cannot prepare: %s", c->name, r.msg);
        return false;
    }
    if (!r.fired) {
        fail("%s: returned after %.2f s (rc %d: %s) before the interrupt came%s", c->name,
             r.elapsed, r.rc, r.msg,
             c->how == IR_HANDLER ? " (the progress handler never stopped it)" : "");
        return false;
    }
    char want[128];
    snprintf(want, sizeof want, "%s: interrupted", c->fn);
    if (c->how == IR_HANDLER)
        printf("  %-48s %7.1f ms (CPU %6.1f ms)  %s; the handler ran %ld times, said stop "
               "first %.1f ms late\n",
               c->name, r.latency * 1e3, r.cpu * 1e3, r.msg, r.handler_calls, r.handler_late * 1e3);
    else
        printf("  %-48s %7.1f ms (CPU %6.1f ms)  %s\n", c->name, r.latency * 1e3, r.cpu * 1e3,
               r.msg);
    fflush(stdout);
    bool ok = false;
    if (r.rc != SQLITE_INTERRUPT || r.xrc != SQLITE_INTERRUPT)
        fail("%s: rc %d (extended %d), message \"%s\"; expected SQLITE_INTERRUPT", c->name, r.rc,
             r.xrc, r.msg);
    else if (strcmp(r.msg, want) != 0 && strcmp(r.msg, "interrupted") != 0 &&
             !(c->alt && strcmp(r.msg, c->alt) == 0))
        fail("%s: message \"%s\", expected \"%s\"", c->name, r.msg, want);
    else if (r.latency > (ir_is_big(c) ? LATENCY_MAX_BIG : LATENCY_MAX))
        fail("%s: returned %.3f s after the interrupt (at most %.1f s)", c->name, r.latency,
             ir_is_big(c) ? LATENCY_MAX_BIG : LATENCY_MAX);
    else if (ir_is_big(c) && r.cpu > CPU_MAX_BIG)
        fail("%s: %.3f s of CPU after the interrupt (at most %.1f s)", c->name, r.cpu, CPU_MAX_BIG);
    else
        ok = true;
    /* the connection works again */
    sqlite3_stmt *probe = NULL;
    if (sqlite3_prepare_v2(ir_db, "SELECT 1", -1, &probe, NULL) != SQLITE_OK ||
        sqlite3_step(probe) != SQLITE_ROW || sqlite3_column_int(probe, 0) != 1) {
        fail("%s: the connection does not work after the interrupt: %s", c->name,
             sqlite3_errmsg(ir_db));
        ok = false;
    }
    sqlite3_finalize(probe);
    return ok;
}

static void interrupt_case(const ir_case *c)
{
    if (!selected(c->name) || (ir_is_big(c) && !RUN_BIG))
        return;
    sqlite3_int64 used_first = 0;
    for (int r = 0; r < RUNS; r++) {
        if (!check_run(c))
            return;
        sqlite3_int64 used = sqlite3_memory_used();
        if (r == 0)
            used_first = used;
        else if (used > used_first) { /* less is no leak: SQLite may release a cache lazily */
            checks++;
            fail("%s: %lld bytes in use after run %d, %lld after the first (a leak?)", c->name,
                 (long long)used, r + 1, (long long)used_first);
        }
    }
}

/* Runs sql to completion (it names note as its progress function); checks the calls. */
static void progress_case(const char *name, const char *sql)
{
    if (!selected(name))
        return;
    memset(&ir_plog, 0, sizeof ir_plog);
    checks++;
    double t0 = ir_now();
    char *err = NULL;
    if (sqlite3_exec(ir_db, sql, NULL, NULL, &err) != SQLITE_OK) {
        fail("%s: %s", name, err ? err : "?");
        sqlite3_free(err);
        return;
    }
    printf("  %-48s %ld calls in %.1f s; stages: %s\n", name, ir_plog.calls, ir_now() - t0,
           ir_plog.stages);
    if (ir_plog.calls == 0)
        fail("%s: note was never called", name);
    else if (ir_plog.bad[0])
        fail("%s: %s", name, ir_plog.bad);
    else if (ir_plog.done != ir_plog.total)
        fail("%s: the last call is stage \"%s\", %lld of %lld", name, ir_plog.stage, ir_plog.done,
             ir_plog.total);
}

/* sql must fail with exactly want. */
static void error_case(const char *name, const char *sql, const char *want)
{
    if (!selected(name))
        return;
    checks++;
    char *err = NULL;
    int rc = sqlite3_exec(ir_db, sql, NULL, NULL, &err);
    if (rc == SQLITE_OK)
        fail("%s: succeeded, expected the error \"%s\"", name, want);
    else if (!err || strcmp(err, want) != 0)
        fail("%s: error \"%s\", expected \"%s\"", name, err ? err : "(none)", want);
    else
        printf("  %-48s %s\n", name, err);
    sqlite3_free(err);
}

/* ---- the laban index's search polls (ext/vt_laban.c, LAB_POLL_ROWS) ----
 * A k-nearest search over a few hundred thousand rows takes milliseconds, too short for an
 * interrupt from a clock; its polls are seen instead: each steps the monitor's probe, a statement
 * whose start SQLITE_TRACE_STMT reports. The index gets 300,000 copies of its 3 vectors written
 * straight into its _data table. A search of one row (rowid = 2) starts the statements a search
 * without polls starts; the whole search starts more (its polls); an interrupt at its first poll
 * stops it with "laban: interrupted", and the connection then answers again. The nearest row
 * to row 1 is its first copy, row 12 (distance 0; row 1 itself is left out). */
static struct {
    int events;    /* statements started */
    int interrupt; /* call sqlite3_interrupt at this event (0: never) */
} poll_trace;

static int poll_trace_fn(unsigned type, void *ctx, void *p, void *x)
{
    (void)type;
    (void)ctx;
    (void)p;
    (void)x;
    if (++poll_trace.events == poll_trace.interrupt)
        sqlite3_interrupt(ir_db);
    return 0;
}

/* Runs sql (one row of one integer) counting the statements it starts; rc and *value. */
static int poll_run(const char *sql, int interrupt_at, sqlite3_int64 *value, char **err)
{
    poll_trace.events = 0;
    poll_trace.interrupt = interrupt_at;
    sqlite3_trace_v2(ir_db, SQLITE_TRACE_STMT, poll_trace_fn, NULL);
    sqlite3_stmt *st = NULL;
    int rc = sqlite3_prepare_v2(ir_db, sql, -1, &st, NULL);
    if (rc == SQLITE_OK && (rc = sqlite3_step(st)) == SQLITE_ROW) {
        *value = sqlite3_column_int64(st, 0);
        rc = SQLITE_OK;
    }
    *err = rc == SQLITE_OK ? NULL : sqlite3_mprintf("%s", sqlite3_errmsg(ir_db));
    sqlite3_finalize(st);
    sqlite3_trace_v2(ir_db, 0, NULL, NULL);
    return rc;
}

static void search_poll_case(void)
{
    const char *name = "laban search polls";
    if (!selected(name))
        return;
    char *err = NULL;
    if (sqlite3_exec(ir_db,
                     "CREATE TABLE pm(id INTEGER PRIMARY KEY, emotion TEXT, motion BLOB);"
                     "INSERT INTO pm VALUES (1, 'sad', motion_synth('walk', 'sad', 1)),"
                     " (2, 'angry', motion_synth('walk', 'angry', 1)),"
                     " (3, 'happy', motion_synth('knock', 'happy', 2));"
                     "CREATE VIRTUAL TABLE pm_laban USING laban(content=pm, label=emotion);"
                     "WITH RECURSIVE n(i) AS (SELECT 10 UNION ALL SELECT i + 1 FROM n"
                     " WHERE i < 300009)"
                     " INSERT INTO pm_laban_data(id, label, vector, msize, mhash)"
                     " SELECT n.i, d.label, d.vector, 0, 0 FROM n JOIN pm_laban_data d"
                     " ON d.id = 1 + n.i % 3;"
                     "UPDATE pm_laban_info SET value = value + 1 WHERE key = 'generation';"
                     "SELECT count(*) FROM pm_laban WHERE query = 1 AND k = 1;", /* the cache */
                     NULL, NULL, &err) != SQLITE_OK) {
        fail("%s: cannot build the index: %s", name, err ? err : "?");
        sqlite3_free(err);
        return;
    }
    static const char whole[] = "SELECT rowid FROM pm_laban WHERE query = 1 AND k = 1";
    static const char one[] = "SELECT rowid FROM pm_laban WHERE query = 1 AND k = 1 AND rowid = 2";
    sqlite3_int64 v = 0, v1 = 0;
    int rc = poll_run(one, 0, &v1, &err);
    int base = poll_trace.events;
    checks++;
    if (rc != SQLITE_OK || v1 != 2) {
        fail("%s: the search of one row: %s, row %lld", name, err ? err : "ok", v1);
        goto done;
    }
    sqlite3_free(err);
    rc = poll_run(whole, 0, &v, &err);
    int polls = poll_trace.events - base;
    checks++;
    if (rc != SQLITE_OK || v != 12 || polls < 2) {
        fail("%s: the whole search: %s, row %lld, %d polls (expected 2 or more)", name,
             err ? err : "ok", v, polls);
        goto done;
    }
    sqlite3_free(err);
    rc = poll_run(whole, base + 1, &v, &err);
    checks++;
    if (rc != SQLITE_INTERRUPT || !err || strcmp(err, "laban: interrupted") != 0) {
        fail("%s: interrupted at the first poll: rc %d, \"%s\"", name, rc, err ? err : "");
        goto done;
    }
    sqlite3_free(err);
    rc = poll_run(whole, 0, &v, &err);
    checks++;
    if (rc != SQLITE_OK || v != 12) {
        fail("%s: after the interrupt: %s", name, err ? err : "ok");
        goto done;
    }
    printf("  %-48s %d polls over 300,003 rows; interrupted at the first: laban: interrupted\n",
           name, polls);
    /* the cache's standardization polls too (3 passes over 3 parts of LAB_POLL_ROWS rows: 8
     * polls, the first part of the first pass unpolled): after a change of generation the same
     * search starts at least 8 more statements, and an interrupt at any of the rebuild's polls
     * stops it with "laban: interrupted" */
    static const char bump[] = "UPDATE pm_laban_info SET value = value + 1 WHERE key = "
                               "'generation'";
    if (sqlite3_exec(ir_db, bump, NULL, NULL, NULL) != SQLITE_OK)
        goto done;
    rc = poll_run(whole, 0, &v, &err);
    int rebuild = poll_trace.events;
    checks++;
    if (rc != SQLITE_OK || v != 12 || rebuild < base + polls + 8) {
        fail("%s: the search with the cache rebuilt: %s, %d statements (expected %d or more)", name,
             err ? err : "ok", rebuild, base + polls + 8);
        goto done;
    }
    sqlite3_free(err);
    err = NULL;
    int ours = 0; /* interrupts answered by our polls */
    for (int at = 1; at <= rebuild; at++) {
        if (sqlite3_exec(ir_db, bump, NULL, NULL, NULL) != SQLITE_OK)
            goto done;
        rc = poll_run(whole, at, &v, &err);
        if (rc == SQLITE_INTERRUPT && err && strcmp(err, "laban: interrupted") == 0)
            ours++;
        sqlite3_free(err);
        err = NULL;
    }
    checks++;
    if (ours < polls + 8) {
        fail("%s: %d of the %d statements of a rebuilding search were polls that stopped it "
             "(expected %d or more)",
             name, ours, rebuild, polls + 8);
        goto done;
    }
    rc = poll_run(whole, 0, &v, &err);
    checks++;
    if (rc != SQLITE_OK || v != 12) {
        fail("%s: after the interrupts of the rebuild: %s", name, err ? err : "ok");
        goto done;
    }
    printf("  %-48s %d statements with the cache rebuilt, %d polls stopped it\n",
           "laban cache standardization polls", rebuild, ours);
done:
    sqlite3_free(err);
    sqlite3_exec(ir_db, "DROP TABLE pm_laban; DROP TABLE pm", NULL, NULL, NULL);
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: %s MODULE [CASE]\n", argv[0]);
        return 2;
    }
    only = argc > 2 ? argv[2] : NULL;
    double t0 = ir_now();
    ir_open(argv[1]);
    printf("corpus: 80 motions, 8 walks at 1000 fps and their laban indexes in %.1f s\n",
           ir_now() - t0);
    if (RUN_BIG) {
        t0 = ir_now();
        ir_open_big();
        printf("large motions (" IR_BIG "): %.1f s\n", ir_now() - t0);
    } else {
        printf("skipped in the sanitizer build: the cases on the large motions (" IR_BIG ")\n");
    }
    printf("latency from the interrupt to the return (goal 0.2 s, bound %.1f s), process CPU "
           "over it, message:\n",
           LATENCY_MAX);
    for (size_t i = 0; i < IR_N_CASES; i++)
        interrupt_case(&IR_CASES[i]);
    search_poll_case();

    printf("progress (option \"progress\": note(stage, done, total)):\n");
    progress_case("hmm_train progress",
                  "SELECT hmm_train(motion, '{\"states\":4,\"mixtures\":2,\"max_iter\":20,"
                  "\"progress\":\"note\"}') FROM motions WHERE performer <= 2");
    progress_case("affect_train progress",
                  "SELECT affect_train(motion, emotion, '{\"states\":4,\"max_iter\":6,"
                  "\"progress\":\"note\"}') FROM motions WHERE performer <= 2");
    progress_case("affect_train progress, threads 2",
                  "SELECT affect_train(motion, emotion, '{\"states\":4,\"max_iter\":6,"
                  "\"threads\":2,\"progress\":\"note\"}') FROM motions WHERE performer <= 2");
    progress_case("affect_crossval progress",
                  "SELECT count(*) FROM affect_crossval('motions', 'motion', 'emotion', "
                  "'{\"states\":4,\"max_iter\":6,\"folds\":3,\"progress\":\"note\"}')");
    error_case("hmm_train progress: unknown function",
               "SELECT hmm_train(motion, '{\"progress\":\"nope\"}') FROM motions",
               "hmm_train: option \"progress\": no such function: nope");
    error_case("affect_train progress: unknown function",
               "SELECT affect_train(motion, emotion, '{\"progress\":\"nope\"}') FROM motions",
               "affect_train: option \"progress\": no such function: nope");
    error_case("affect_crossval progress: unknown function",
               "SELECT * FROM affect_crossval('motions', 'motion', 'emotion', "
               "'{\"progress\":\"nope\"}')",
               "affect_crossval: affect_crossval_json: option \"progress\": no such function: "
               "nope");

    sqlite3_close(ir_db);
    printf("interrupt: %d checks, %d failed (%.1f s)\n", checks, failures, ir_now() - t0);
    return failures ? 1 : 0;
}
