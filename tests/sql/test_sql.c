/*
 * test_sql.c — SQL-level tests: load build/affect.so into a real SQLite connection and run
 * spec files that read like specifications.
 *
 * Usage: test_sql MODULE SPEC.sql [SPEC.sql …]            normal run (one cmocka test per file)
 *        test_sql --oom MODULE SPEC.sql [SPEC.sql …]      the same under fault injection
 *
 * Spec format: plain SQL statements. After a statement, an annotation comment may say what
 * it must give:
 *     SELECT motion_frames(:walk);
 *     -- expect: 150                    first column of the first row, as text
 *     SELECT motion_info('x');
 *     -- error: motion_info: argument 1 must be a motion BLOB, got text
 * Without an annotation, every row whose second column exists must have it equal to 1, and
 * the first column names the check in a failure message:
 *     SELECT 'walk is long', motion_duration(:walk) > 3;
 * Statements may use the parameter :corpus (the real corpus's directory, or NULL). Whatever
 * the annotation, an error message that is not valid UTF-8 fails the statement.
 *
 * A statement annotated "-- heap-limit: N" runs with SQLite's hard heap limit set to N bytes
 * more than are in use when it starts (sqlite3_hard_heap_limit64; the limits are restored
 * after it): for what an allocation refused for its size reports.
 *
 * A statement annotated "-- oom: skip" runs once, normally, in that mode: for checks over a
 * whole table whose functions other, smaller statements already cover under fault injection
 * (each injected failure reruns the statement, so cost grows with its allocation count
 * squared).
 *
 * The --oom mode installs an allocator (SQLITE_CONFIG_MALLOC) that fails exactly the n-th
 * allocation; for every read-only statement it runs the statement with n = 1, 2, … until a
 * run completes without reaching the failure, requiring every failed run to end in
 * SQLITE_NOMEM (or the statement's own expected error) and never crash. Where an error is
 * expected, SQLite's generic "SQL logic error" is accepted too: it is what SQLite reports when
 * the allocation that fails is the one copying the error's text. Statements that
 * write run once, normally. At the end every allocation must have been freed (no leak),
 * checked after sqlite3_shutdown.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <cmocka.h>
#include <sqlite3.h>

static const char *module_path;
static const char *corpus_dir;

/* ---- a counting allocator with fault injection ---- */

static long long alloc_count, fail_at, outstanding;

static void *oom_malloc(int n)
{
    if (++alloc_count == fail_at)
        return NULL;
    void *p = malloc((size_t)n + 16);
    if (!p)
        return NULL;
    *(size_t *)p = (size_t)n;
    outstanding++;
    return (char *)p + 16;
}

static void oom_free(void *p)
{
    if (!p)
        return;
    outstanding--;
    free((char *)p - 16);
}

static void *oom_realloc(void *p, int n)
{
    if (++alloc_count == fail_at)
        return NULL;
    char *q = realloc((char *)p - 16, (size_t)n + 16);
    if (!q)
        return NULL;
    *(size_t *)q = (size_t)n;
    return q + 16;
}

static int oom_size(void *p)
{
    return (int)*(size_t *)((char *)p - 16);
}

static int oom_roundup(int n)
{
    return (n + 7) & ~7;
}

static int oom_init(void *x)
{
    return SQLITE_OK;
}

static void oom_shutdown(void *x) {}

static const sqlite3_mem_methods oom_methods = {oom_malloc,  oom_free, oom_realloc,  oom_size,
                                                oom_roundup, oom_init, oom_shutdown, NULL};

/* ---- spec files ---- */

typedef struct outcome {
    int rc;           /* SQLITE_OK or the error code */
    char *error;      /* error message (malloc'd) */
    char *first;      /* first column of first row as text (malloc'd), or NULL */
    char *failed_row; /* a row whose check column was not 1 (malloc'd), or NULL */
    int writes;       /* the statement is not read-only */
} outcome;

static void outcome_free(outcome *o)
{
    free(o->error);
    free(o->first);
    free(o->failed_row);
    memset(o, 0, sizeof *o);
}

static char *dup_text(const char *s)
{
    if (!s)
        return NULL;
    size_t n = strlen(s);
    char *d = malloc(n + 1);
    memcpy(d, s, n + 1);
    return d;
}

/* Runs one prepared statement to the end. */
static void run_stmt(sqlite3 *db, sqlite3_stmt *st, outcome *o)
{
    memset(o, 0, sizeof *o);
    o->writes = !sqlite3_stmt_readonly(st);
    int idx = sqlite3_bind_parameter_index(st, ":corpus");
    if (idx > 0) {
        if (corpus_dir)
            sqlite3_bind_text(st, idx, corpus_dir, -1, SQLITE_STATIC);
        else
            sqlite3_bind_null(st, idx);
    }
    int rc, row = 0;
    while ((rc = sqlite3_step(st)) == SQLITE_ROW) {
        if (row == 0) {
            const unsigned char *t = sqlite3_column_text(st, 0);
            o->first = dup_text(t ? (const char *)t : "NULL");
        }
        if (sqlite3_column_count(st) >= 2 && !o->failed_row &&
            !(sqlite3_column_type(st, 1) == SQLITE_INTEGER && sqlite3_column_int64(st, 1) == 1)) {
            const unsigned char *name = sqlite3_column_text(st, 0);
            const unsigned char *val = sqlite3_column_text(st, 1);
            char buf[512];
            snprintf(buf, sizeof buf, "%s → %s", name ? (const char *)name : "NULL",
                     val ? (const char *)val : "NULL");
            o->failed_row = dup_text(buf);
        }
        row++;
    }
    o->rc = rc == SQLITE_DONE ? SQLITE_OK : rc;
    if (o->rc != SQLITE_OK)
        o->error = dup_text(sqlite3_errmsg(db));
}

/* The annotation right after a statement: "-- expect: …", "-- error: …", "-- oom: skip" and
 * "-- heap-limit: N" (*heap_limit: N, else 0). */
static void read_annotation(const char *tail, char **expect, char **error, bool *oom_skip,
                            long long *heap_limit)
{
    *expect = *error = NULL;
    *oom_skip = false;
    *heap_limit = 0;
    const char *p = tail;
    while (*p == ' ' || *p == '\t' || *p == '\r' || *p == '\n')
        p++;
    while (strncmp(p, "--", 2) == 0) {
        const char *eol = strchr(p, '\n');
        size_t len = eol ? (size_t)(eol - p) : strlen(p);
        char line[4096];
        if (len >= sizeof line)
            len = sizeof line - 1;
        memcpy(line, p, len);
        line[len] = '\0';
        if (len > 0 && line[len - 1] == '\r')
            line[len - 1] = '\0';
        if (strncmp(line, "-- expect: ", 11) == 0)
            *expect = dup_text(line + 11);
        else if (strncmp(line, "-- error: ", 10) == 0)
            *error = dup_text(line + 10);
        else if (strcmp(line, "-- oom: skip") == 0)
            *oom_skip = true;
        else if (strncmp(line, "-- heap-limit: ", 15) == 0)
            *heap_limit = atoll(line + 15);
        if (!eol)
            break;
        p = eol + 1;
        while (*p == ' ' || *p == '\t')
            p++;
        if (*p == '\n' || *p == '\r')
            break; /* a blank line ends the annotation */
    }
}

static int line_of(const char *text, const char *at)
{
    int line = 1;
    for (const char *p = text; p < at; p++)
        line += *p == '\n';
    return line;
}

/* Whether s is valid UTF-8 (no overlongs, surrogates or code points above U+10FFFF): every
 * error message must be, since clients decode it (Python's sqlite3 raises UnicodeDecodeError
 * instead of showing a message that is not). */
static bool valid_utf8(const unsigned char *s)
{
    while (*s) {
        unsigned c = *s, n; /* continuation bytes */
        if (c < 0x80)
            n = 0;
        else if (c >= 0xC2 && c <= 0xDF)
            n = 1;
        else if (c >= 0xE0 && c <= 0xEF)
            n = 2;
        else if (c >= 0xF0 && c <= 0xF4)
            n = 3;
        else
            return false;
        unsigned long cp = n == 0 ? c : c & (0x3Fu >> n);
        for (unsigned i = 1; i <= n; i++) {
            if ((s[i] & 0xC0) != 0x80)
                return false;
            cp = (cp << 6) | (s[i] & 0x3Fu);
        }
        if ((n == 2 && cp < 0x800) || (n == 3 && (cp < 0x10000 || cp > 0x10FFFF)) ||
            (cp >= 0xD800 && cp <= 0xDFFF))
            return false;
        s += n + 1;
    }
    return true;
}

/* Checks an outcome against the annotation; returns a malloc'd failure text or NULL. */
static char *judge(const outcome *o, const char *expect, const char *error)
{
    char buf[8192];
    if (o->error && !valid_utf8((const unsigned char *)o->error)) {
        snprintf(buf, sizeof buf, "the error message is not valid UTF-8: %s", o->error);
        return dup_text(buf);
    }
    if (error) {
        if (o->rc == SQLITE_OK)
            snprintf(buf, sizeof buf, "expected error \"%s\", got success", error);
        else if (strcmp(o->error, error) != 0)
            snprintf(buf, sizeof buf, "expected error\n      \"%s\"\n  got \"%s\"", error,
                     o->error);
        else
            return NULL;
        return dup_text(buf);
    }
    if (o->rc != SQLITE_OK) {
        snprintf(buf, sizeof buf, "unexpected error: %s", o->error);
        return dup_text(buf);
    }
    if (expect) {
        if (!o->first || strcmp(o->first, expect) != 0) {
            snprintf(buf, sizeof buf, "expected\n      %s\n  got %s", expect,
                     o->first ? o->first : "(no row)");
            return dup_text(buf);
        }
        return NULL;
    }
    if (o->failed_row) {
        snprintf(buf, sizeof buf, "check failed: %s", o->failed_row);
        return dup_text(buf);
    }
    return NULL;
}

static sqlite3 *open_db(void)
{
    sqlite3 *db = NULL;
    assert_int_equal(sqlite3_open(":memory:", &db), SQLITE_OK);
    sqlite3_enable_load_extension(db, 1);
    char *err = NULL;
    if (sqlite3_load_extension(db, module_path, "sqlite3_affect_init", &err) != SQLITE_OK)
        fail_msg("cannot load %s: %s", module_path, err ? err : "?");
    return db;
}

static int run_spec(const char *path, int oom)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        fail_msg("cannot open %s", path);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    rewind(f);
    char *text = malloc((size_t)n + 1);
    if (fread(text, 1, (size_t)n, f) != (size_t)n)
        fail_msg("cannot read %s", path);
    text[n] = '\0';
    fclose(f);

    int failures = 0, statements = 0;
    long long oom_runs = 0;
    sqlite3 *db = open_db();
    const char *sql = text;
    while (*sql) {
        sqlite3_stmt *st = NULL;
        const char *tail = NULL;
        int rc = sqlite3_prepare_v2(db, sql, -1, &st, &tail);
        const char *start = sql;
        while (*start == ' ' || *start == '\n' || *start == '\r' || *start == '\t')
            start++;
        char *expect, *error;
        bool oom_skip;
        long long heap_limit;
        read_annotation(tail ? tail : "", &expect, &error, &oom_skip, &heap_limit);
        sqlite3_int64 old_hard = sqlite3_hard_heap_limit64(-1),
                      old_soft = sqlite3_soft_heap_limit64(-1);
        if (heap_limit > 0)
            sqlite3_hard_heap_limit64(sqlite3_memory_used() + heap_limit);
        outcome o;
        memset(&o, 0, sizeof o);
        if (rc != SQLITE_OK) {
            o.rc = rc;
            o.error = dup_text(sqlite3_errmsg(db));
        } else if (!st) { /* only comments or white space left */
            sqlite3_hard_heap_limit64(old_hard);
            sqlite3_soft_heap_limit64(old_soft);
            free(expect);
            free(error);
            sql = tail;
            continue;
        } else if (oom && sqlite3_stmt_readonly(st) && !oom_skip) {
            /* fail the n-th allocation for n = 1, 2, … until a run does not reach it */
            clock_t t0 = clock();
            long long k = 1;
            for (;; k++) {
                sqlite3_reset(st);
                alloc_count = 0;
                fail_at = k;
                outcome_free(&o);
                run_stmt(db, st, &o);
                int reached = alloc_count >= k;
                fail_at = 0;
                oom_runs++;
                if (!reached)
                    break;
                /* SQLite reports SQLITE_ERROR "SQL logic error" when it cannot allocate the
                 * text of an error a function set: allowed where an error is expected */
                bool generic = error && o.rc == SQLITE_ERROR && o.error &&
                               strcmp(o.error, "SQL logic error") == 0;
                if (o.rc != SQLITE_OK && o.rc != SQLITE_NOMEM && !generic &&
                    !(error && o.error && strcmp(o.error, error) == 0)) {
                    print_error("%s:%d: under allocation failure %lld: %s (rc %d)\n", path,
                                line_of(text, start), k, o.error ? o.error : "?", o.rc);
                    failures++;
                    break;
                }
            }
            /* AFFECT_OOM_PROFILE=1 names the statements that keep fault injection long */
            if (getenv("AFFECT_OOM_PROFILE"))
                fprintf(stderr, "%s:%d: %lld runs, %.2f s\n", path, line_of(text, start), k,
                        (double)(clock() - t0) / CLOCKS_PER_SEC);
        } else {
            run_stmt(db, st, &o);
        }
        if (heap_limit > 0) {
            sqlite3_hard_heap_limit64(old_hard);
            sqlite3_soft_heap_limit64(old_soft);
        }
        statements++;
        char *why = judge(&o, expect, error);
        if (why) {
            int len = (int)(tail - start);
            print_error("%s:%d: %.*s\n  %s\n", path, line_of(text, start), len > 300 ? 300 : len,
                        start, why);
            failures++;
            free(why);
        }
        outcome_free(&o);
        free(expect);
        free(error);
        sqlite3_finalize(st);
        if (!tail)
            break;
        sql = tail;
    }
    sqlite3_close(db);
    free(text);
    print_message("%s: %d statements%s, %d failed\n", path, statements,
                  oom ? " under fault injection" : "", failures);
    if (oom)
        print_message("%s: %lld runs with an injected allocation failure\n", path, oom_runs);
    return failures;
}

static int oom_mode;

static void test_spec(void **state)
{
    const char *path = *state;
    if (oom_mode) {
        sqlite3_shutdown();
        assert_int_equal(sqlite3_config(SQLITE_CONFIG_MALLOC, &oom_methods), SQLITE_OK);
        assert_int_equal(sqlite3_config(SQLITE_CONFIG_LOOKASIDE, 0, 0), SQLITE_OK);
        assert_int_equal(sqlite3_initialize(), SQLITE_OK);
        outstanding = 0;
    }
    int failures = run_spec(path, oom_mode);
    if (oom_mode) {
        sqlite3_shutdown();
        if (outstanding != 0)
            fail_msg("%s: %lld allocations were not freed", path, outstanding);
    }
    if (failures)
        fail_msg("%s: %d statement(s) failed", path, failures);
}

int main(int argc, char **argv)
{
    int a = 1;
    if (a < argc && strcmp(argv[a], "--oom") == 0) {
        oom_mode = 1;
        a++;
    }
    if (argc - a < 2) {
        fprintf(stderr, "usage: %s [--oom] MODULE SPEC.sql [SPEC.sql ...]\n", argv[0]);
        return 2;
    }
    module_path = argv[a++];
    corpus_dir = getenv("AFFECT_CORPUS_DIR");
    if (corpus_dir && !*corpus_dir)
        corpus_dir = NULL;
    int n = argc - a;
    struct CMUnitTest *tests = calloc((size_t)n, sizeof *tests);
    for (int i = 0; i < n; i++) {
        tests[i].name = argv[a + i];
        tests[i].test_func = test_spec;
        tests[i].initial_state = argv[a + i];
    }
    int rc = _cmocka_run_group_tests(oom_mode ? "sql-oom" : "sql", tests, (size_t)n, NULL, NULL);
    free(tests);
    return rc;
}
