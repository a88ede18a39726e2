/*
 * fuzz_sql.c — the connection, fixtures and outcome checks shared by the SQL-driven fuzz
 * targets (see fuzz_sql.h for what they hold and how a target uses them). Linked into each
 * of those targets with the extension's sources (tests/fuzz/CMakeLists.txt).
 */
#include "fuzz_sql.h"

#include "affect/classifier.h"
#include "affect/hmm.h"
#include "affect/hmm_blob.h"
#include "affect/motion.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

int sqlite3_affect_init(sqlite3 *db, char **err, const sqlite3_api_routines *api);
void openblas_set_num_threads(int n);

#define FZ_HEAP_LIMIT ((sqlite3_int64)512 << 20)
/* Seconds a connection may run statements before its progress handler interrupts them. */
#define FZ_SECONDS 2.0

static const char fixture_sql[] =
    "CREATE TABLE motions(id INTEGER PRIMARY KEY, motion BLOB, label TEXT, action TEXT, "
    "grp TEXT);"
    "WITH e(label) AS (VALUES('angry'),('sad'),('happy')),"
    "     a(action) AS (VALUES('wave'),('knock')), s(seed) AS (VALUES(1),(2))"
    "INSERT INTO motions(motion, label, action, grp)"
    "  SELECT motion_synth(action, label, seed, '{\"fps\":10}'), label, action, 'g' || seed"
    "  FROM a, e, s ORDER BY action, label, seed;"
    "CREATE TABLE extra(name TEXT PRIMARY KEY, motion BLOB);"
    "INSERT INTO extra VALUES('skeletal', motion_from_bvh(motion_to_bvh("
    "  (SELECT motion FROM motions WHERE id = 1))));"
    "CREATE TABLE docs(name TEXT PRIMARY KEY, body);"
    "INSERT INTO docs VALUES('bvh', motion_to_bvh((SELECT motion FROM motions WHERE id = 1),"
    "  '{\"precision\":3}'));"
    "INSERT INTO docs VALUES('csv', motion_to_csv((SELECT motion FROM motions WHERE id = 1)));"
    "CREATE TABLE models(name TEXT PRIMARY KEY, model BLOB);"
    "INSERT INTO models SELECT 'hmm', hmm_train(motion, '{\"states\":2,\"mixtures\":1,"
    "  \"joints\":[\"right_hand\"],\"max_iter\":2}') FROM motions WHERE label = 'angry';"
    "INSERT INTO models SELECT 'classifier', affect_train(motion, label, '{\"states\":2,"
    "  \"mixtures\":1,\"joints\":[\"right_hand\"],\"max_iter\":2,\"svm_c\":1,\"spca_dims\":1,"
    "  \"knn_k\":1}') FROM motions;"
    "CREATE TABLE points(x, y, label);"
    "INSERT INTO points SELECT laban_weight(motion), laban_time(motion), label FROM motions;"
    "CREATE VIRTUAL TABLE ix USING laban(content=motions, motion=motion, label=label);"
    /* The fit laban_salient and affect_generate look for by default is seed 1, 10 folds; it
     * takes ~8 s of CPU instrumented, so the fixture fits 2 folds (~5 times cheaper) and files
     * that fit under the 10-fold key (content:rows:seed:folds, ext/fn_generate.c fit_key). */
    "SELECT laban_salient('ix', '{\"folds\":2,\"threads\":2}');"
    "UPDATE ix_info SET value = substr(value, 1, length(value) - 2) || ':10'"
    "  WHERE key = 'rmlr_key' AND value LIKE '%:1:2';";

static unsigned char *image;
static bool verbose; /* AFFECT_FUZZ_VERBOSE set: each statement's outcome on stderr */
static sqlite3_int64 image_size;

void fz_fail(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fputs("fuzz_sql: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
    abort();
}

static double now(void)
{
    struct timespec ts;
    timespec_get(&ts, TIME_UTC);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double deadline; /* set by open_registered (one connection at a time) */

static int progress(void *arg)
{
    return now() > deadline;
}

static sqlite3 *open_registered(void)
{
    sqlite3 *db = NULL;
    if (sqlite3_open_v2(":memory:", &db, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, NULL) !=
        SQLITE_OK)
        fz_fail("cannot open a connection: %s", db ? sqlite3_errmsg(db) : "out of memory");
    char *err = NULL;
    if (sqlite3_affect_init(db, &err, NULL) != SQLITE_OK)
        fz_fail("sqlite3_affect_init: %s", err ? err : "failed");
    deadline = now() + FZ_SECONDS;
    sqlite3_progress_handler(db, 100, progress, NULL);
    return db;
}

static void build_fixtures(void)
{
    openblas_set_num_threads(1);
    verbose = getenv("AFFECT_FUZZ_VERBOSE") != NULL;
    double t0 = now();
    sqlite3_hard_heap_limit64(FZ_HEAP_LIMIT);
    sqlite3 *db = open_registered();
    sqlite3_progress_handler(db, 0, NULL, NULL);
    for (const char *sql = fixture_sql; *sql;) {
        sqlite3_stmt *st = NULL;
        double t1 = now();
        if (sqlite3_prepare_v2(db, sql, -1, &st, &sql) != SQLITE_OK)
            fz_fail("building the fixtures: %s", sqlite3_errmsg(db));
        if (!st)
            continue;
        int rc;
        while ((rc = sqlite3_step(st)) == SQLITE_ROW) {
        }
        if (rc != SQLITE_DONE)
            fz_fail("building the fixtures: %s: %s", sqlite3_sql(st), sqlite3_errmsg(db));
        if (verbose)
            fprintf(stderr, "fuzz_sql: %.2f s  %.70s\n", now() - t1, sqlite3_sql(st));
        sqlite3_finalize(st);
    }
    sqlite3_stmt *st = fz_prepare(db, "SELECT value LIKE '%:1:10' FROM ix_info "
                                      "WHERE key = 'rmlr_key'");
    if (sqlite3_step(st) != SQLITE_ROW || sqlite3_column_int(st, 0) != 1)
        fz_fail("the fixture's RMLR fit is not filed under seed 1, 10 folds: has the key "
                "format of ext/fn_generate.c fit_key changed?");
    sqlite3_finalize(st);
    unsigned char *img = sqlite3_serialize(db, "main", &image_size, 0);
    if (!img)
        fz_fail("sqlite3_serialize failed");
    image = malloc((size_t)image_size);
    if (!image)
        fz_fail("out of memory");
    memcpy(image, img, (size_t)image_size);
    sqlite3_free(img);
    sqlite3_close(db);
    const char *path = getenv("AFFECT_FUZZ_WRITE_FIXTURES");
    if (path) {
        FILE *f = fopen(path, "wb");
        if (!f || fwrite(image, 1, (size_t)image_size, f) != (size_t)image_size || fclose(f))
            fz_fail("cannot write the fixtures to %s", path);
    }
    if (verbose)
        fprintf(stderr, "fuzz_sql: fixtures built in %.2f s (%lld bytes)\n", now() - t0,
                (long long)image_size);
}

sqlite3 *fz_open(void)
{
    if (!image)
        build_fixtures();
    sqlite3 *db = open_registered();
    unsigned char *copy = sqlite3_malloc64((sqlite3_uint64)image_size);
    if (!copy)
        fz_fail("out of memory for the fixture image");
    memcpy(copy, image, (size_t)image_size);
    if (sqlite3_deserialize(db, "main", copy, image_size, image_size,
                            SQLITE_DESERIALIZE_FREEONCLOSE | SQLITE_DESERIALIZE_RESIZEABLE) !=
        SQLITE_OK)
        fz_fail("sqlite3_deserialize: %s", sqlite3_errmsg(db));
    return db;
}

void fz_close(sqlite3 *db)
{
    if (sqlite3_close(db) != SQLITE_OK)
        fz_fail("sqlite3_close: %s (a statement left unfinalized?)", sqlite3_errmsg(db));
}

sqlite3_stmt *fz_prepare(sqlite3 *db, const char *sql)
{
    sqlite3_stmt *st = NULL;
    if (sqlite3_prepare_v2(db, sql, -1, &st, NULL) != SQLITE_OK)
        fz_fail("cannot prepare %s: %s", sql, sqlite3_errmsg(db));
    return st;
}

int fz_step_all(sqlite3 *db, sqlite3_stmt *st, const char *prefix,
                void (*row)(sqlite3_stmt *st, void *arg), void *arg)
{
    int rc;
    while ((rc = sqlite3_step(st)) == SQLITE_ROW)
        if (row)
            row(st, arg);
    const char *msg = rc == SQLITE_DONE ? "" : sqlite3_errmsg(db);
    if (verbose)
        fprintf(stderr, "fuzz_sql: %.300s -> %d %.500s\n", sqlite3_sql(st), rc, msg);
    if (rc == SQLITE_DONE)
        return rc;
    switch (rc) {
    case SQLITE_OK:
    case SQLITE_INTERNAL:
    case SQLITE_CORRUPT:
    case SQLITE_MISUSE:
    case SQLITE_NOTADB:
        fz_fail("result code %d (%s): %s", rc, sqlite3_errstr(rc), msg);
    default:
        break;
    }
    if (!msg || !msg[0])
        fz_fail("error %d without a message", rc);
    size_t n = prefix ? strlen(prefix) : 0;
    if (rc == SQLITE_ERROR && prefix &&
        (strncmp(msg, prefix, n) != 0 || msg[n] != ':' || msg[n + 1] != ' '))
        fz_fail("error message does not start with \"%s: \": %s", prefix, msg);
    return rc;
}

void fz_check_motion(sqlite3_stmt *st, int col)
{
    if (sqlite3_column_type(st, col) == SQLITE_NULL)
        return;
    if (sqlite3_column_type(st, col) != SQLITE_BLOB)
        fz_fail("a motion result is not a BLOB");
    affect_motion *m = NULL;
    affect_error err;
    affect_status s = affect_motion_decode(sqlite3_column_blob(st, col),
                                           (size_t)sqlite3_column_bytes(st, col), &m, &err);
    if (s == AFFECT_ERR_NOMEM)
        return;
    if (s != AFFECT_OK)
        fz_fail("a motion result does not decode: %s", err.msg);
    s = affect_motion_validate(m, &err);
    affect_motion_free(m);
    if (s != AFFECT_OK && s != AFFECT_ERR_NOMEM)
        fz_fail("a motion result does not validate: %s", err.msg);
}

void fz_check_json(sqlite3 *db, sqlite3_stmt *st, int col)
{
    if (sqlite3_column_type(st, col) == SQLITE_NULL)
        return;
    if (sqlite3_column_type(st, col) != SQLITE_TEXT)
        fz_fail("a JSON result is not text");
    sqlite3_stmt *v = fz_prepare(db, "SELECT json_valid(?1)");
    sqlite3_bind_text(v, 1, (const char *)sqlite3_column_text(st, col),
                      sqlite3_column_bytes(st, col), SQLITE_TRANSIENT);
    int rc = sqlite3_step(v);
    if (rc == SQLITE_ROW && sqlite3_column_int(v, 0) != 1)
        fz_fail("a JSON result is not valid JSON: %.2000s", sqlite3_column_text(st, col));
    sqlite3_finalize(v);
}

void fz_check_hmm(sqlite3_stmt *st, int col)
{
    if (sqlite3_column_type(st, col) == SQLITE_NULL)
        return;
    const unsigned char *data = sqlite3_column_blob(st, col);
    size_t size = (size_t)sqlite3_column_bytes(st, col);
    affect_hmm *h = NULL;
    affect_features *f = NULL;
    affect_error err;
    affect_status s = affect_hmm_blob_decode(data, size, &h, &f, &err);
    if (s == AFFECT_ERR_NOMEM)
        return;
    if (s != AFFECT_OK)
        fz_fail("a trained model does not decode: %s", err.msg);
    unsigned char *buf = NULL;
    size_t n = 0;
    s = affect_hmm_blob_encode(h, f, &buf, &n, &err);
    if (s == AFFECT_OK && (n != size || memcmp(buf, data, size) != 0))
        fz_fail("a trained model does not re-encode to the same bytes");
    affect_free(buf);
    affect_hmm_free(h);
    affect_features_free(f);
}

void fz_check_classifier(sqlite3_stmt *st, int col)
{
    if (sqlite3_column_type(st, col) == SQLITE_NULL)
        return;
    const unsigned char *data = sqlite3_column_blob(st, col);
    size_t size = (size_t)sqlite3_column_bytes(st, col);
    affect_classifier *c = NULL;
    affect_error err;
    affect_status s = affect_classifier_decode(data, size, &c, &err);
    if (s == AFFECT_ERR_NOMEM)
        return;
    if (s != AFFECT_OK)
        fz_fail("a trained classifier does not decode: %s", err.msg);
    unsigned char *buf = NULL;
    size_t n = 0;
    s = affect_classifier_encode(c, &buf, &n, &err);
    if (s == AFFECT_OK && (n != size || memcmp(buf, data, size) != 0))
        fz_fail("a trained classifier does not re-encode to the same bytes");
    affect_free(buf);
    affect_classifier_free(c);
}

/* libFuzzer calls this once before the first input: the fixtures are built outside the
 * per-input timeout. */
int LLVMFuzzerInitialize(int *argc, char ***argv);

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    if (!image)
        build_fixtures();
    return 0;
}
