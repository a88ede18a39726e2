/*
 * fuzz_sql_laban.c — libFuzzer target for the laban virtual table (ext/vt_laban.c): its
 * constructor arguments (key=value parsing, quoting, the options JSON, the content checks),
 * its query constraints (xBestIndex / xFilter: query, label, k, radius, components, rowid),
 * its commands, and DROP.
 *
 * Usage (see tests/fuzz/run.sh, or build with -DAFFECT_FUZZ=ON and clang):
 *     build-fuzz/tests/fuzz/fuzz_sql_laban -max_total_time=60 -dict=tests/fuzz/fuzz_sql_laban.dict
 * <a copy of tests/fuzz/corpus/fuzz_sql_laban>
 *
 * Input, line by line (on a fresh copy of fuzz_sql.h's fixtures):
 *   1  the constructor arguments:  CREATE VIRTUAL TABLE t USING laban(<line 1>)
 *   2  a query tail (optional):    SELECT rowid, label, distance, WeightAll, TimeAll,
 *                                  ShapeDirRHand FROM t <line 2>
 *      e.g. WHERE query = (SELECT motion FROM motions WHERE id = 3) AND label = 'sad' AND k = 2
 *   3  a command (optional):       INSERT INTO t(t, rowid) VALUES(<line 3>), e.g. 'refresh', 3;
 *      then the query of line 2 runs again
 * and finally DROP TABLE t. Lines are SQL text, so the fuzzer can also write constraints the
 * planner passes in other shapes (IN, >, a column compared with a column); only the first
 * statement of each is prepared. The dictionary fuzz_sql_laban.dict holds the hidden columns,
 * the argument keys and the commands (SQLite's parser is not instrumented, so comparison
 * tracing cannot find them).
 * Checks beyond "no crash, no leak, no undefined behaviour": a failed CREATE says "laban: …";
 * every error has a message and none is SQLITE_INTERNAL, SQLITE_MISUSE or SQLITE_CORRUPT;
 * distance is NULL or a finite value ≥ 0 and the component columns are NULL or finite (not
 * checked when line 2 holds UNION, INTERSECT or EXCEPT: those rows need not come from t);
 * DROP TABLE succeeds and leaves no shadow table. (The order of the rows is not checked: the
 * free-form tail can make SQLite call xFilter several times — IN, OR, joins — and concatenate.)
 */
#include "fuzz_sql.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

typedef struct line {
    const char *p;
    size_t n;
    bool present;
} line;

/* Line i (0-based) of the input; a NUL byte ends the input. */
static line get_line(const char *text, int i)
{
    line l = {NULL, 0, false};
    const char *p = text;
    for (int k = 0; k < i; k++) {
        p = strchr(p, '\n');
        if (!p)
            return l;
        p++;
    }
    const char *e = strchr(p, '\n');
    l.p = p;
    l.n = e ? (size_t)(e - p) : strlen(p);
    l.present = true;
    return l;
}

/* Runs one statement of the target's making (its first statement only); returns the step
 * result, or -1 when it does not prepare. */
static int run(sqlite3 *db, const char *sql, const char *prefix,
               void (*row)(sqlite3_stmt *, void *), void *arg)
{
    sqlite3_stmt *st = NULL;
    if (sqlite3_prepare_v2(db, sql, -1, &st, NULL) != SQLITE_OK || !st) {
        sqlite3_finalize(st);
        return -1;
    }
    int rc = fz_step_all(db, st, prefix, row, arg);
    sqlite3_finalize(st);
    return rc;
}

/* Values read from t: distance ≥ 0 and finite or NULL, components finite or NULL. */
static void check_row(sqlite3_stmt *st, void *arg)
{
    if (sqlite3_column_type(st, 2) != SQLITE_NULL) {
        double d = sqlite3_column_double(st, 2);
        if (!(d >= 0) || !isfinite(d))
            fz_fail("distance %g", d);
    }
    for (int c = 3; c < 6; c++)
        if (sqlite3_column_type(st, c) != SQLITE_NULL && !isfinite(sqlite3_column_double(st, c)))
            fz_fail("component column %d is %g", c, sqlite3_column_double(st, c));
}

/* Whether l holds word (ASCII, any case). */
static bool contains(const line *l, const char *word)
{
    size_t n = strlen(word);
    for (size_t i = 0; i + n <= l->n; i++)
        if (sqlite3_strnicmp(l->p + i, word, (int)n) == 0)
            return true;
    return false;
}

static void query(sqlite3 *db, const line *tail)
{
    if (!tail->present)
        return;
    char *sql = sqlite3_mprintf("SELECT rowid, label, distance, WeightAll, TimeAll, "
                                "ShapeDirRHand FROM t %.*s",
                                (int)tail->n, tail->p);
    if (!sql)
        return;
    bool compound =
        contains(tail, "union") || contains(tail, "intersect") || contains(tail, "except");
    run(db, sql, NULL, compound ? NULL : check_row, NULL);
    sqlite3_free(sql);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char *text = malloc(size + 1);
    if (!text)
        return 0;
    memcpy(text, data, size);
    text[size] = '\0';
    line args = get_line(text, 0), tail = get_line(text, 1), cmd = get_line(text, 2);
    sqlite3 *db = fz_open();
    char *sql = sqlite3_mprintf("CREATE VIRTUAL TABLE t USING laban(%.*s)", (int)args.n, args.p);
    int rc = sql ? run(db, sql, "laban", NULL, NULL) : -1;
    sqlite3_free(sql);
    if (rc == SQLITE_DONE) {
        query(db, &tail);
        if (cmd.present) {
            sql = sqlite3_mprintf("INSERT INTO t(t, rowid) VALUES(%.*s)", (int)cmd.n, cmd.p);
            if (sql)
                run(db, sql, "laban", NULL, NULL);
            sqlite3_free(sql);
            query(db, &tail);
        }
        rc = run(db, "DROP TABLE t", NULL, NULL, NULL);
        if (rc != SQLITE_DONE)
            fz_fail("DROP TABLE t failed (%d): %s", rc, sqlite3_errmsg(db));
        sqlite3_stmt *st = fz_prepare(db, "SELECT count(*) FROM sqlite_schema WHERE name IN "
                                          "('t', 't_data', 't_info')");
        if (sqlite3_step(st) != SQLITE_ROW || sqlite3_column_int(st, 0) != 0)
            fz_fail("DROP TABLE t left t, t_data or t_info behind");
        sqlite3_finalize(st);
    }
    fz_close(db);
    free(text);
    return 0;
}
