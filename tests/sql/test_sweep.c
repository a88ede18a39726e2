/*
 * test_sweep.c — the adversarial sweep (issue 14): every SQL function and table the built module
 * registers, called with NULL, every SQL type, empty and huge values, NaN and ±inf, random,
 * truncated and bit-flipped BLOBs and BLOBs of the wrong kind. Each call must give a result or
 * an error whose message starts with the function's (or table's) name — "name: …" — or is
 * "out of memory" / "interrupted"; never a crash. Under the sanitizer build (AFFECT_SANITIZE=ON)
 * any ASan or UBSan report aborts the run, so the sweep also guarantees no memory error, leak
 * or undefined behaviour on those inputs.
 *
 * Usage: test_sweep MODULE [FIXTURES_DIR]           (ctest: sql/sweep)
 * Environment: AFFECT_SWEEP_SEED (default 14) seeds the random BLOBs and combinations;
 *   AFFECT_SWEEP_RANDOM (default 24) random combinations per function form;
 *   AFFECT_SWEEP_BUDGET (default 150) seconds after which the random phase stops (logged);
 *   AFFECT_SWEEP_VERBOSE=1 prints every call before it runs;
 *   AFFECT_SWEEP_ONLY=name,name… sweeps only those functions (and "laban": the virtual table).
 *
 * What it tries:
 *   1. The functions: every (name, argument count) of pragma_function_list that loading the
 *      module added (so a new function is swept without editing this file). Each has a
 *      baseline call of valid arguments (the table `baselines` below; a function missing there
 *      is swept around NULLs and logged). For each argument position, every value of the pool
 *      replaces the baseline's (one at a time); then AFFECT_SWEEP_RANDOM random combinations
 *      (each argument the baseline's or a random pool value). A position shared by several
 *      forms of a function is swept once (see sweep_form). Aggregates run over a small corpus
 *      table: the value replaces the argument in every row and, for per-row arguments, in the
 *      second row only.
 *   2. The pool: NULL; integers (0, ±1, 2, 9, 30, 60, 10^6, ±2^63); reals (0, −0, 0.5, NaN, ±inf,
 *      ±1e308, the least subnormal); texts (empty, 'x', 1 MB, invalid UTF-8, an embedded NUL,
 *      names, JSON options valid, unknown, malformed, deeply nested and extreme); BLOBs (empty,
 *      zeroblob(10^6), random, a motion header claiming the maximum sizes); valid BLOBs of every
 *      kind made by the module itself (motions of several versions, an HMM, a classifier, a
 *      Laban vector, a Fisher score, an embedding) and the fixtures of tests/fixtures; each of
 *      these truncated at several points, with a trailing byte, and bit-flipped at several
 *      positions (header and payload); BVH, CSV and JSON texts of a motion, whole and truncated,
 *      and hostile ones (2·10^9 frames declared, 5000 nested joints, names not UTF-8, NaN and
 *      1e999 values, lone surrogates, cycles); motions with hostile joint names (not UTF-8,
 *      quotes and braces, NUL, duplicates); Laban vectors of NaN, ±inf, 3e38, −0, subnormals.
 *   3. The table-valued functions (eponymous modules the load added): the same one-at-a-time
 *      and random sweep over their hidden arguments, every row and column read; and odd
 *      constraint shapes (none, >, IN, OR, IS, two equalities, a join).
 *   4. The laban virtual table: CREATE with bad arguments, over an empty content table and over
 *      one holding every pool value as motion and label; queries with every pool value as
 *      query, label, k, radius, components and rowid, and odd constraint shapes; the write
 *      commands with pool values; indexes of hostile labels and of every pool value that
 *      decodes as a motion; corrupt shadow tables (_data vectors and labels and _info values
 *      replaced by pool values) read by queries and by the generation functions.
 * Calls documented to be slow (training, cross-validation, generation) take the short pool
 * (about a third: one or two values of each class, no payload bit flips, each of which would
 * be a full training or generation run); the calls skipped so are counted. Text results and
 * error messages that are not UTF-8 are counted and shown (per function), not failed. A
 * progress handler interrupts a statement after CALL_SECONDS.
 *
 * On a crash, the call that was running is printed (a signal handler, or the sanitizer's
 * death callback) before the process dies.
 */
#define _POSIX_C_SOURCE 200809L /* clock_gettime, write */
#include <math.h>
#include <signal.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#include <sqlite3.h>

#if defined(__SANITIZE_ADDRESS__)
#define SWEEP_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define SWEEP_SANITIZED 1
#endif
#endif
#ifdef SWEEP_SANITIZED
#include <sanitizer/common_interface_defs.h>
#else
#include <execinfo.h>
#endif

#ifndef AFFECT_FIXTURES_DIR
#define AFFECT_FIXTURES_DIR "tests/fixtures"
#endif

#define MAX_POOL 512
#define MAX_ARGS 8
#define CALL_SECONDS 60.0 /* the progress handler interrupts a statement after this */
#define SLOW_CALL 2.0     /* a call longer than this is logged */
#define BIG 1000000       /* the huge text and zeroblob, bytes */

/* ---- the current call, printed if the process dies ---- */

static char current_call[8192];

static void print_current_call(void)
{
    static const char head[] = "\ntest_sweep: died during: ";
    ssize_t w = write(2, head, sizeof head - 1);
    w = write(2, current_call, strlen(current_call));
    w = write(2, "\n", 1);
    (void)w;
}

#ifndef SWEEP_SANITIZED
static void on_signal(int sig)
{
    print_current_call();
    void *frames[64];
    int n = backtrace(frames, 64);
    backtrace_symbols_fd(frames, n, 2);
    signal(sig, SIG_DFL);
    raise(sig);
}
#endif

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

/* ---- a seeded generator (splitmix64) ---- */

static uint64_t rng_state;

static uint64_t rng_next(void)
{
    uint64_t z = (rng_state += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

static int rng_below(int n)
{
    return (int)(rng_next() % (uint64_t)n);
}

/* ---- the value pool ---- */

typedef struct value {
    char *label; /* how the value reads in a call's description */
    int type;    /* SQLITE_NULL, _INTEGER, _FLOAT, _TEXT, _BLOB; zeroblob: _BLOB with zero */
    sqlite3_int64 i;
    double d;
    unsigned char *bytes;
    int n;
    int zero;  /* a zeroblob of this size (no bytes) */
    bool lite; /* in the short pool of the slow functions: one or two of each class of value */
} value;

static value pool[MAX_POOL];
static int n_pool;

static void die(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fprintf(stderr, "test_sweep: ");
    vfprintf(stderr, fmt, ap);
    fprintf(stderr, "\n");
    va_end(ap);
    exit(2);
}

static char *dup_printf(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(NULL, 0, fmt, ap);
    va_end(ap);
    char *s = malloc((size_t)n + 1);
    if (!s)
        die("out of memory");
    va_start(ap, fmt);
    vsnprintf(s, (size_t)n + 1, fmt, ap);
    va_end(ap);
    return s;
}

static value *add_value(int type, const char *fmt, ...)
{
    if (n_pool == MAX_POOL)
        die("the pool is full (MAX_POOL %d)", MAX_POOL);
    value *v = &pool[n_pool++];
    memset(v, 0, sizeof *v);
    va_list ap;
    va_start(ap, fmt);
    char buf[512];
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    v->label = dup_printf("%s", buf);
    v->type = type;
    return v;
}

static void set_bytes(value *v, const void *bytes, int n)
{
    v->bytes = malloc(n > 0 ? (size_t)n : 1);
    if (!v->bytes)
        die("out of memory");
    if (n > 0)
        memcpy(v->bytes, bytes, (size_t)n);
    v->n = n;
}

static void add_int(sqlite3_int64 i, const char *label)
{
    value *v = add_value(SQLITE_INTEGER, "%s", label);
    v->i = i;
}

static void add_real(double d, const char *label)
{
    value *v = add_value(SQLITE_FLOAT, "%s", label);
    v->d = d;
}

static value *add_text(const char *label, const char *text, int n)
{
    if (!text)
        die("no text for %s", label);
    value *v = add_value(SQLITE_TEXT, "%s", label);
    set_bytes(v, text, n < 0 ? (int)strlen(text) : n);
    return v;
}

/* A text labelled as an SQL literal. */
static void add_quoted(const char *text)
{
    char label[256];
    snprintf(label, sizeof label, "'%s'", text);
    add_text(label, text, -1);
}

static value *add_blob(const char *label, const void *bytes, int n)
{
    value *v = add_value(SQLITE_BLOB, "%s", label);
    set_bytes(v, bytes, n);
    v->lite = true;
    return v;
}

static const value *find_value(const char *label)
{
    for (int i = 0; i < n_pool; i++)
        if (strcmp(pool[i].label, label) == 0)
            return &pool[i];
    die("no pool value %s", label);
    return NULL;
}

static void bind_value(sqlite3_stmt *st, int idx, const value *v)
{
    int rc = SQLITE_OK;
    switch (v->type) {
    case SQLITE_NULL:
        rc = sqlite3_bind_null(st, idx);
        break;
    case SQLITE_INTEGER:
        rc = sqlite3_bind_int64(st, idx, v->i);
        break;
    case SQLITE_FLOAT:
        rc = sqlite3_bind_double(st, idx, v->d);
        break;
    case SQLITE_TEXT:
        rc = sqlite3_bind_text(st, idx, (const char *)v->bytes, v->n, SQLITE_STATIC);
        break;
    default:
        if (v->zero)
            rc = sqlite3_bind_zeroblob(st, idx, v->zero);
        else
            rc = sqlite3_bind_blob(st, idx, v->bytes, v->n, SQLITE_STATIC);
    }
    if (rc != SQLITE_OK)
        die("cannot bind %s: %d", v->label, rc);
}

/* ---- running statements ---- */

static sqlite3 *db;
static const char *module_path;
static double call_deadline;

static int progress(void *unused)
{
    return call_deadline > 0 && now() > call_deadline;
}

static void exec_or_die(const char *sql)
{
    char *err = NULL;
    if (sqlite3_exec(db, sql, NULL, NULL, &err) != SQLITE_OK)
        die("setup failed: %s\n  in: %.300s", err ? err : "?", sql);
}

static sqlite3_stmt *prepare_or_die(const char *sql)
{
    sqlite3_stmt *st = NULL;
    if (sqlite3_prepare_v2(db, sql, -1, &st, NULL) != SQLITE_OK)
        die("cannot prepare %s: %s", sql, sqlite3_errmsg(db));
    return st;
}

/* The first column of a one-row query, added to the pool. */
static value *add_from_sql(const char *label, const char *sql)
{
    sqlite3_stmt *st = prepare_or_die(sql);
    if (sqlite3_step(st) != SQLITE_ROW)
        die("setup query gave no row: %s: %s", sql, sqlite3_errmsg(db));
    int type = sqlite3_column_type(st, 0);
    value *v = add_value(type, "%s", label);
    v->lite = true;
    if (type == SQLITE_TEXT || type == SQLITE_BLOB) {
        const void *p = type == SQLITE_TEXT ? (const void *)sqlite3_column_text(st, 0)
                                            : sqlite3_column_blob(st, 0);
        set_bytes(v, p, sqlite3_column_bytes(st, 0));
    } else if (type == SQLITE_INTEGER) {
        v->i = sqlite3_column_int64(st, 0);
    } else if (type == SQLITE_FLOAT) {
        v->d = sqlite3_column_double(st, 0);
    } else {
        die("setup query gave NULL: %s", sql);
    }
    sqlite3_finalize(st);
    return v;
}

static bool valid_utf8(const unsigned char *s, int n)
{
    int i = 0;
    while (i < n) {
        unsigned c = s[i];
        int len;
        unsigned min;
        if (c < 0x80) {
            i++;
            continue;
        } else if ((c & 0xe0) == 0xc0) {
            len = 2, min = 0x80, c &= 0x1f;
        } else if ((c & 0xf0) == 0xe0) {
            len = 3, min = 0x800, c &= 0x0f;
        } else if ((c & 0xf8) == 0xf0) {
            len = 4, min = 0x10000, c &= 0x07;
        } else {
            return false;
        }
        if (i + len > n)
            return false;
        for (int k = 1; k < len; k++) {
            if ((s[i + k] & 0xc0) != 0x80)
                return false;
            c = (c << 6) | (s[i + k] & 0x3f);
        }
        if (c < min || c > 0x10ffff || (c >= 0xd800 && c <= 0xdfff))
            return false;
        i += len;
    }
    return true;
}

/* ---- tallies and judgement ---- */

typedef struct tally {
    long calls, results, errors, skipped, failures;
    long bad_utf8_messages, bad_utf8_results;
} tally;

static tally total;
static int verbose;
static int n_fail_shown;
static double slowest;
static char slowest_call[512];

static void note_failure(const char *what, const char *message)
{
    total.failures++;
    if (n_fail_shown++ < 200)
        fprintf(stderr, "FAIL: %s\n  → %.500s\n", what, message);
}

/* Text that is not UTF-8 (results and messages) is noted, not failed: per function, a count
 * and the first two calls. */
static struct {
    char name[64];
    long n;
} utf8_notes[64];

static void note_utf8(const char *what, const char *name_list)
{
    size_t len = strcspn(name_list, "|");
    int i = 0;
    while (i < 64 && utf8_notes[i].n &&
           !(strlen(utf8_notes[i].name) == len && strncmp(utf8_notes[i].name, name_list, len) == 0))
        i++;
    if (i == 64)
        return;
    snprintf(utf8_notes[i].name, sizeof utf8_notes[i].name, "%.*s", (int)len, name_list);
    if (utf8_notes[i].n++ < 2)
        fprintf(stderr, "note: %s that is not UTF-8: %.500s\n", what, current_call);
}

/* The message names `name` ("name: …"), or is one every statement may give. */
static bool names(const char *message, const char *name)
{
    size_t n = strlen(name);
    if (strncmp(message, name, n) == 0 && message[n] == ':')
        return true;
    return strcmp(message, "out of memory") == 0 || strcmp(message, "interrupted") == 0;
}

/* Steps st to the end, reading every column of every row, and judges the outcome: a result, or
 * an error whose message names one of the names (a |-separated list; an item "=text" accepts
 * exactly that message, one of SQLite's own). Returns true for a result. */
static bool run_call(sqlite3_stmt *st, const char *name_list)
{
    if (verbose) {
        fprintf(stderr, "call: %s\n", current_call);
        fflush(stderr);
    }
    total.calls++;
    double t0 = now();
    call_deadline = t0 + CALL_SECONDS;
    int rc;
    while ((rc = sqlite3_step(st)) == SQLITE_ROW) {
        int nc = sqlite3_column_count(st);
        for (int c = 0; c < nc; c++) {
            int type = sqlite3_column_type(st, c);
            if (type == SQLITE_TEXT) {
                const unsigned char *t = sqlite3_column_text(st, c);
                int n = sqlite3_column_bytes(st, c);
                if (t && !valid_utf8(t, n)) {
                    total.bad_utf8_results++;
                    note_utf8("text result", name_list);
                }
            } else if (type == SQLITE_BLOB) {
                (void)sqlite3_column_blob(st, c);
            }
        }
    }
    call_deadline = 0;
    double dt = now() - t0;
    if (dt > slowest) {
        slowest = dt;
        snprintf(slowest_call, sizeof slowest_call, "%.500s", current_call);
    }
    if (dt > SLOW_CALL)
        fprintf(stderr, "slow (%.1f s): %.300s\n", dt, current_call);
    bool ok = rc == SQLITE_DONE;
    if (ok) {
        total.results++;
    } else {
        total.errors++;
        const char *msg = sqlite3_errmsg(db);
        if (!valid_utf8((const unsigned char *)msg, (int)strlen(msg))) {
            total.bad_utf8_messages++;
            note_utf8("error message", name_list);
        }
        bool named = false;
        char buf[256];
        const char *p = name_list;
        while (*p && !named) {
            const char *bar = strchr(p, '|');
            size_t len = bar ? (size_t)(bar - p) : strlen(p);
            snprintf(buf, sizeof buf, "%.*s", (int)len, p);
            named = buf[0] == '=' ? strcmp(msg, buf + 1) == 0 : names(msg, buf);
            p += len + (bar ? 1 : 0);
        }
        if (!named) {
            char what[9000];
            snprintf(what, sizeof what, "%s (rc %d)", current_call, rc);
            note_failure(what, msg);
        }
    }
    sqlite3_reset(st);
    return ok;
}

/* ---- what every function is called with when valid ---- */

/* Arguments of the longest form; shorter forms take a prefix. A label names a pool value;
 * "@col" (aggregates) a column of the table agg_rows. */
typedef struct baseline {
    const char *name;
    const char *args[MAX_ARGS];
    bool slow; /* documented to be slow: swept with the short pool (see sweep_form) */
} baseline;

#define M "<motion: synth wave sad 1>"
#define M2 "<motion: synth knock angry 2>"
#define OPT "'{}'"
#define HMM "<hmm model>"
#define CLS "<classifier>"
#define STR "<strength model>"
#define RNK "<ranker>"
#define FDA "<functional model>"

static const baseline baselines[] = {
    {"affect_version", {NULL}, false},
    {"affect_build_info", {NULL}, false},
    {"motion_from_bvh", {"<bvh text>", OPT}, false},
    {"motion_bvh_error", {"<bvh text>", OPT}, false},
    {"motion_from_csv", {"<csv text>", "30", OPT}, false},
    {"motion_from_json", {"<json text>"}, false},
    {"motion_to_json", {M}, false},
    {"motion_to_csv", {M}, false},
    {"motion_to_bvh", {M, OPT}, false},
    {"motion_rigid", {M, OPT, M2}, false},
    {"motion_info", {M}, false},
    {"motion_frames", {M}, false},
    {"motion_joints", {M}, false},
    {"motion_fps", {M}, false},
    {"motion_duration", {M}, false},
    {"motion_slice", {M, "2", "9"}, false},
    {"motion_resample", {M, "60"}, false},
    {"motion_select", {M, "'[\"Hips\",\"Head\"]'"}, false},
    {"motion_dtw", {M, M2}, false},
    {"motion_roles", {M, OPT}, false},
    {"motion_normalize", {M, OPT}, false},
    {"motion_svg", {M, OPT}, false},
    {"motion_synth", {"'wave'", "'angry'", "1", OPT}, false},
    {"laban_weight", {M, "'all'", OPT}, false},
    {"laban_time", {M, "'all'", OPT}, false},
    {"laban_flow", {M, "'all'", OPT}, false},
    {"laban_space", {M, "'all'", OPT}, false},
    {"laban_shape_directional", {M, "'left'", OPT}, false},
    {"laban_shape_shaping", {M, OPT}, false},
    {"laban_shape_flow", {M, OPT}, false},
    {"laban", {M, OPT}, false},
    {"motion_kinematics", {M, OPT}, false},
    {"laban_vector", {M, OPT}, false},
    {"laban_zvector", {M, "'idx'", OPT}, false},
    {"laban_names", {NULL}, false},
    {"hmm_loglik", {HMM, M, OPT}, false},
    {"hmm_viterbi", {HMM, M}, false},
    {"hmm_viterbi_loglik", {HMM, M}, false},
    {"hmm_info", {HMM}, false},
    {"hmm_postures", {HMM}, false},
    {"affect_classify", {CLS, M, "'svm'"}, false},
    {"affect_scores", {CLS, M}, false},
    {"fisher_score", {CLS, M}, false},
    {"affect_embed", {CLS, M}, false},
    {"affect_info", {CLS}, false},
    {"fda_embed", {FDA, M}, false},
    {"fda_classify", {FDA, M, "1"}, false},
    {"fda_info", {FDA}, false},
    {"fda_prototype", {FDA, "'sad'"}, false},
    {"fda_plot", {FDA, OPT}, false},
    {"affect_generate", {"'idx'", M, "'angry'", OPT}, true},
    {"affect_generate_explain", {"'idx'", M, "'angry'", OPT}, true},
    {"laban_salient", {"'idx'", OPT}, true},
    {"affect_strength", {STR, M}, false},
    {"strength_synthesize", {STR, "0.5", OPT}, true},
    {"strength_edit", {STR, M, "0.5", OPT}, true},
    {"strength_info", {STR}, false},
    {"motion_keyframes", {M, "9"}, false},
    {"rank_score", {RNK, "<laban vector>"}, false},
    /* aggregates, over agg_rows */
    {"laban_plot", {"@x", "@y", "@label", OPT}, false},
    {"motion_svg_group", {"@m", "@label", OPT}, false},
    {"affect_heatmap", {"@label", "@label", "@x", OPT}, false},
    {"hmm_train", {"@m", "@hmm_opt"}, true},
    {"affect_train", {"@m", "@label", "@cls_opt"}, true},
    {"affect_crossval_json", {"@m", "@label", "@grp", "@cv_opt"}, true},
    {"strength_train", {"@m", "@label", "@str_opt"}, true},
    {"rank_train", {"@vec", "@label", "@rank_opt"}, false},
    {"fda_train", {"@m", "@label", "@fda_opt"}, true},
    /* table-valued functions: their hidden arguments */
    {"motion_points", {M}, false},
    {"motion_angles", {M, OPT}, false},
    {"laban_series", {M, OPT}, false},
    {"affect_salience", {CLS, "2"}, false},
    {"affect_crossval", {"'agg_rows'", "'m'", "'label'", "<crossval options>"}, true},
};

#define HMM_OPT "{\"states\":2,\"mixtures\":1,\"joints\":[\"right_hand\",\"head\"],\"max_iter\":2}"
#define CLS_OPT                                                                                    \
    "{\"states\":2,\"mixtures\":1,\"joints\":[\"right_hand\"],\"max_iter\":2,\"svm_c\":1,"         \
    "\"spca_dims\":1,\"knn_k\":1,\"covariance\":\"full\",\"frame\":\"first\",\"velocity\":false,"  \
    "\"descriptors\":\"all\",\"mirror\":false}"
#define STR_OPT "{\"order\":[\"sad\",\"angry\"],\"keyframes\":4,\"pca_dims\":3}"
#define FDA_OPT "{\"basis\":8,\"dims\":2,\"joints\":[\"right_hand\",\"head\"]}"
#define CV_OPT                                                                                     \
    "{\"folds\":2,\"states\":1,\"mixtures\":1,\"joints\":[\"right_hand\"],\"max_iter\":1,"         \
    "\"svm_c\":1,\"spca_dims\":1,\"knn_k\":1,\"descriptors\":\"none\",\"mirror\":false}"

static const baseline *find_baseline(const char *name)
{
    for (size_t i = 0; i < sizeof baselines / sizeof baselines[0]; i++)
        if (strcmp(baselines[i].name, name) == 0)
            return &baselines[i];
    return NULL;
}

/* ---- building the pool ---- */

static unsigned char *read_file(const char *path, int *n)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        die("cannot open %s", path);
    fseek(f, 0, SEEK_END);
    long len = ftell(f);
    rewind(f);
    unsigned char *p = malloc((size_t)len + 1);
    if (!p || fread(p, 1, (size_t)len, f) != (size_t)len)
        die("cannot read %s", path);
    fclose(f);
    *n = (int)len;
    return p;
}

static void add_fixture(const char *dir, const char *file)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, file);
    int n;
    unsigned char *p = read_file(path, &n);
    char label[256];
    snprintf(label, sizeof label, "<fixture %s>", file);
    add_blob(label, p, n);
    free(p);
}

/* Truncations, a trailing byte and bit flips of a valid BLOB or text (texts: truncations only).
 * The short pool takes the cut at half the length, the trailing byte and the flips of bytes 4
 * (the version) and 8 (a size). */
static void add_corruptions(const value *base, bool texts_too)
{
    char *name = dup_printf("%s", base->label);
    int n = base->n;
    unsigned char *b = malloc((size_t)n + 1);
    memcpy(b, base->bytes, (size_t)n);
    int type = base->type;
    const int cuts[] = {1, 4, 8, 16, 31, 32, 33, n / 4, n / 2, n - 1};
    for (size_t i = 0; i < sizeof cuts / sizeof cuts[0]; i++)
        if (cuts[i] > 0 && cuts[i] < n && (i == 0 || cuts[i] != cuts[i - 1])) {
            value *v = add_value(type, "%s truncated to %d bytes", name, cuts[i]);
            set_bytes(v, b, cuts[i]);
            v->lite = cuts[i] == n / 2;
        }
    if (texts_too) {
        free(b);
        free(name);
        return;
    }
    b[n] = 0x5a;
    value *v = add_value(type, "%s + 1 trailing byte", name);
    set_bytes(v, b, n + 1);
    v->lite = true;
    const int at[] = {0, 4, 6, 8, 12, 16, 20, 24, 28, 36, 44, n / 3, n / 2, n - 3, n - 1};
    for (size_t i = 0; i < sizeof at / sizeof at[0]; i++) {
        int pos = at[i];
        if (pos < 0 || pos >= n)
            continue;
        int bit = (int)(i * 3 % 8);
        if (pos >= 28 && bit < 4)
            bit = 7 - bit; /* reach the exponent of little-endian numbers too */
        b[pos] ^= (unsigned char)(1u << bit);
        v = add_value(type, "%s with bit %d of byte %d flipped", name, bit, pos);
        set_bytes(v, b, n);
        v->lite = pos == 4 || pos == 8;
        b[pos] ^= (unsigned char)(1u << bit);
    }
    free(b);
    free(name);
}

/* A copy of base with the first occurrence of `find` replaced by `with` (same length). */
static void add_patched(const char *base_label, const char *find, const char *with, int n,
                        const char *label)
{
    const value *base = find_value(base_label);
    for (int i = 0; i + n <= base->n; i++)
        if (memcmp(base->bytes + i, find, (size_t)n) == 0) {
            value *v = add_value(base->type, "%s", label);
            set_bytes(v, base->bytes, base->n);
            memcpy(v->bytes + i, with, (size_t)n);
            v->lite = true;
            return;
        }
    die("%s: no %s in %s", label, find, base_label);
}

/* A text grown by printf pieces. */
typedef struct text {
    char *p;
    size_t n, cap;
} text;

static void tx(text *t, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(NULL, 0, fmt, ap);
    va_end(ap);
    if (t->n + (size_t)n + 1 > t->cap) {
        t->cap = 2 * (t->n + (size_t)n + 1);
        t->p = realloc(t->p, t->cap);
        if (!t->p)
            die("out of memory");
    }
    va_start(ap, fmt);
    vsnprintf(t->p + t->n, (size_t)n + 1, fmt, ap);
    va_end(ap);
    t->n += (size_t)n;
}

static void add_tx(text *t, const char *label)
{
    add_text(label, t->p, (int)t->n)->lite = true;
    free(t->p);
    memset(t, 0, sizeof *t);
}

/* Hostile BVH, CSV and JSON motion texts, and motions with hostile joint names. */
static void add_crafted(void)
{
    static const char bvh_head[] = "HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n CHANNELS 6 "
                                   "Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
                                   " End Site\n {\n  OFFSET 0 1 0\n }\n}\nMOTION\n";
    text t = {0};
    tx(&t, "%sFrames: 2000000000\nFrame Time: 0.0333333\n0 0 0 0 0 0\n", bvh_head);
    add_tx(&t, "<bvh: Frames 2000000000, one frame line>");
    tx(&t, "%sFrames: 1\nFrame Time: 1e-320\n0 0 0 0 0 0\n", bvh_head);
    add_tx(&t, "<bvh: Frame Time 1e-320>");
    tx(&t, "%sFrames: 1\nFrame Time: nan\n0 0 0 0 0 0\n", bvh_head);
    add_tx(&t, "<bvh: Frame Time nan>");
    tx(&t, "%sFrames: 2\nFrame Time: 0.0333333\n1e999 nan inf -inf 0 0\n0 0 0 1e308 1e308 1e308\n",
       bvh_head);
    add_tx(&t, "<bvh: values 1e999 nan inf and 1e308 degrees>");
    tx(&t, "HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n CHANNELS 99999999 Xposition\n}\n"
           "MOTION\nFrames: 1\nFrame Time: 0.03\n0\n");
    add_tx(&t, "<bvh: CHANNELS 99999999>");
    tx(&t, "HIERARCHY\nROOT H\xffps\n{\n OFFSET 0 0 0\n CHANNELS 3 Xposition Yposition "
           "Zposition\n}\nMOTION\nFrames: 1\nFrame Time: 0.03\n0 0 0\n");
    add_tx(&t, "<bvh: a joint name not UTF-8>");
    /* 5000 joints nested: more than a motion may have, deeper than any skeleton */
    tx(&t, "HIERARCHY\nROOT j0\n{\n OFFSET 0 0 0\n CHANNELS 3 Xposition Yposition Zposition\n");
    for (int i = 1; i < 5000; i++)
        tx(&t, "JOINT j%d\n{\nOFFSET 0 1 0\nCHANNELS 1 Zrotation\n", i);
    for (int i = 0; i < 5000; i++)
        tx(&t, "}\n");
    tx(&t, "MOTION\nFrames: 1\nFrame Time: 0.03\n0 0 0");
    for (int i = 1; i < 5000; i++)
        tx(&t, " 0");
    tx(&t, "\n");
    add_tx(&t, "<bvh: 5000 joints nested>");
    for (int i = 0; i < 20000; i++)
        tx(&t, "{\n");
    add_tx(&t, "<bvh-like: '{' × 20000>");

    tx(&t, "a.x,a.y,a.z\n1,2,nan\n1e999,0,0\n");
    add_tx(&t, "<csv: nan and 1e999>");
    tx(&t, "\xff.x,\xff.y,\xff.z\n0,0,0\n");
    add_tx(&t, "<csv: a joint name not UTF-8>");
    for (int i = 0; i < 5000; i++)
        tx(&t, "%sj%d.x,j%d.y,j%d.z", i ? "," : "", i, i, i);
    tx(&t, "\n");
    for (int i = 0; i < 5000; i++)
        tx(&t, "%s0,0,0", i ? "," : "");
    tx(&t, "\n");
    add_tx(&t, "<csv: 5000 joints>");
    tx(&t, "\"a.x\",\"a.y\",\"a.z\"\n\"1\",\"2\",\"3");
    add_tx(&t, "<csv: an unterminated quoted field>");

    static const char *const json[] = {
        "{\"fps\":30,\"joints\":[\"\\ud800\"],\"parents\":[-1],\"frames\":[[[0,0,0]]]}",
        "{\"fps\":30,\"joints\":[\"a\\u0000b\"],\"frames\":[[[0,0,0]]]}",
        "{\"fps\":30,\"joints\":[\"a\",\"a\"],\"frames\":[[[0,0,0],[1,1,1]]]}",
        "{\"fps\":30,\"joints\":[\"a\",\"b\"],\"parents\":[1,0],\"frames\":[[[0,0,0],[1,1,1]]]}",
        "{\"fps\":30,\"joints\":[\"a\"],\"frames\":[[[1e999,0,0]]]}",
        "{\"fps\":1e308,\"joints\":[\"a\"],\"frames\":[[[0,0,0]]]}",
        "{\"fps\":30,\"joints\":[\"a\"],\"frames\":[]}",
        "{\"fps\":30,\"joints\":[],\"frames\":[[]]}",
        "{\"fps\":30,\"unit\":\"\\\"\",\"joints\":[\"a\"],\"frames\":[[[0,0,0]]]}",
    };
    for (size_t i = 0; i < sizeof json / sizeof json[0]; i++) {
        char label[64];
        snprintf(label, sizeof label, "<json motion %zu: %.30s…>", i + 1, json[i] + 10);
        add_text(label, json[i], -1)->lite = true;
    }

    /* motions whose joint names are hostile: the decoder's name checks and every writer's
     * escaping (JSON, BVH, SVG, CSV) */
    const char *three = "<motion: 3 joints>";
    add_patched(three, "\x04\x00Hips", "\x04\x00H\xffps", 6, "<motion: a joint name not UTF-8>");
    add_patched(three, "\x04\x00Hips", "\x04\x00H\"<\\", 6, "<motion: a joint named H\"<\\>");
    add_patched(three, "\x04\x00Hips", "\x04\x00H\n{}", 6, "<motion: a joint named H\\n{}>");
    add_patched(three, "\x04\x00Hips", "\x04\x00H\0ps", 6, "<motion: a joint name with NUL>");
    add_patched(three, "\x04\x00Head", "\x04\x00Hips", 6, "<motion: two joints named Hips>");
    add_patched(three, "m\x04\x00Hips", "\xff\x04\x00Hips", 7, "<motion: unit not ASCII>");

    /* Laban vectors (27 float32) of extreme values, as the index stores them */
    static const struct {
        float f;
        const char *what;
    } fill[] = {
        {NAN, "NaN"}, {INFINITY, "+Inf"}, {3e38f, "3e38"}, {-0.0f, "-0"}, {1e-45f, "1e-45"}};
    for (size_t i = 0; i < sizeof fill / sizeof fill[0]; i++) {
        unsigned char b[108];
        for (int c = 0; c < 27; c++)
            memcpy(b + 4 * c, &fill[i].f, 4); /* little-endian hosts */
        char label[64];
        snprintf(label, sizeof label, "<laban vector: all %s>", fill[i].what);
        add_blob(label, b, 108);
    }
}

static void build_pool(const char *fixtures)
{
    add_value(SQLITE_NULL, "NULL");
    add_int(0, "0");
    add_int(1, "1");
    add_int(-1, "-1");
    add_int(2, "2");
    add_int(9, "9");
    add_int(30, "30");
    add_int(60, "60");
    add_int(1000000, "1000000");
    add_int(INT64_MAX, "9223372036854775807");
    add_int(INT64_MIN, "-9223372036854775808");
    add_real(0.0, "0.0");
    add_real(-0.0, "-0.0");
    add_real(0.5, "0.5");
    add_real(2.5, "2.5");
    add_real(NAN, "NaN");
    add_real(INFINITY, "+Inf");
    add_real(-INFINITY, "-Inf");
    add_real(1e308, "1e308");
    add_real(-1e308, "-1e308");
    add_real(4.9406564584124654e-324, "4.9e-324");

    add_text("''", "", 0);
    add_quoted("x");
    char *big = malloc(BIG + 1);
    memset(big, 'a', BIG);
    big[BIG] = 0;
    add_text("'a' × 1000000", big, BIG);
    free(big);
    add_text("invalid UTF-8 \\xff\\xfe", "\xff\xfe", 2);
    add_text("invalid UTF-8 overlong NUL \\xc0\\x80", "x\xc0\x80y", 4);
    add_text("invalid UTF-8 surrogate \\xed\\xa0\\x80", "\xed\xa0\x80", 3);
    add_text("invalid UTF-8 truncated \\xe2\\x82", "wave\xe2\x82", 6);
    add_text("'a' NUL 'b'", "a\0b", 3);
    /* clang-format off */
    static const char *const words[] = {
        "wave", "angry", "sad", "knock", "right_hand", "Hips", "all", "left", "svm", "knn", "ml",
        "idx", "agg_rows", "m", "label", "corpus", "[\"Hips\",\"Head\"]",
        "[\"TimeAll\",\"FlowAll\"]", "[\"Nope\"]", "[]", "{}", "{\"bogus\":1}", "[1,2]", "null",
        "{\"a\":", "{\"states\":1,\"max_iter\":1}",
        "{\"states\":2,\"states\":3}", "{\"states\":1e999}", "{\"states\":-1}", "{\"fps\":1e308}",
        "{\"fps\":1e-300}", "{\"frames\":100000}", "{\"cutoff_hz\":0}", "{\"cutoff_hz\":1e300}",
        "{\"missing\":\"null\"}", "{\"joints\":[]}", "{\"roles\":{\"left_hand\":\"nope\"}}",
        "{\"x\":\"\\u0000\"}", "{\"method\":\"hmm_nn\"}",
        "{\"order\":\"XYZ\",\"rotations\":\"ik\"}",
        "{\"unit\":\"cm\",\"header\":false}", "{\"intensity\":2,\"noise\":1e300}",
        "{\"components\":[\"TimeAll\"]}", "{\"k\":1000000}", "{\"width\":4000,\"height\":4000}",
        "{\"per_frame\":true}", "{\"scale\":\"arm\"}", "{\"seed\":-1,\"folds\":1}",
        "{\"group\":\"grp\"}", "{\"frame\":\"body\",\"root\":true}", "1e999", "\"str\"",
        "{\"precision\":9,\"frame_time\":1e-300}", "{\"rest_frame\":-1}",
        "{\"rest_frame\":1000000}", "{\"top\":32}", "{\"width\":100,\"height\":100,\"frames\":1}",
        "{\"hull\":\"box\",\"speed_floor\":0,\"max_ratio\":1e308}",
        "{\"per_second\":true,\"cutoff_hz\":1e-300}", "{\"up\":\"z\"}", "{\"parents\":[0]}",
        "{\"parents\":[-1,0,1]}", "{\"delimiter\":\"\\t\"}", "{\"order\":\"QQQ\"}",
        "{\"siblings\":\"translate\",\"free\":[\"Hips\"]}", "{\"lengths\":\"first\"}",
        "{\"rotations\":\"stored\"}", "{\"scale\":\"none\",\"normalize\":false}",
        "{\"mirror\":true}", "{\"roles\":{\"right_hand\":\"Hips\",\"left_hand\":\"Hips\"}}",
        "{\"roles\":{\"right_hand\":\"Head_end\"}}", "{\"model\":\"skeleton\"}",
        "{\"strength\":2,\"pairs\":64}", "{\"source_label\":\"sad\",\"pair_by\":\"action\"}",
        "{\"method\":\"hmm_nn\",\"k\":1,\"render\":\"steps\"}",
        "{\"log_x\":true,\"log_y\":true,\"means\":true}",
        "{\"title\":\"<&\\\"'>\"}", "{\"fps\":100000}", "{\"fps\":1,\"intensity\":0}",
        "{\"components\":[]}", "{\"on_error\":\"null\"}", "{\"scale\":1e308}"};
    /* clang-format on */
    for (size_t i = 0; i < sizeof words / sizeof words[0]; i++)
        add_quoted(words[i]);
    {
        enum { DEPTH = 20000 };
        char *deep = malloc(2 * DEPTH + 1);
        memset(deep, '[', DEPTH);
        memset(deep + DEPTH, ']', DEPTH);
        add_text("'[' × 20000 ']' × 20000", deep, 2 * DEPTH);
        add_text("'[' × 20000", deep, DEPTH);
        memset(deep, '{', DEPTH);
        add_text("'{' × 20000", deep, DEPTH);
        free(deep);
    }

    add_blob("x''", "", 0);
    value *z = add_value(SQLITE_BLOB, "zeroblob(1000000)");
    z->zero = BIG;
    unsigned char rnd[4096];
    for (int i = 0; i < 4096; i++)
        rnd[i] = (unsigned char)rng_next();
    add_blob("<random 16 bytes>", rnd, 16);
    add_blob("<random 4096 bytes>", rnd, 4096);
    for (int k = 0; k < 5; k++) {
        static const char *const magic[] = {"AFMO", "AFHM", "AFCL", "AFxx", "AFFD"};
        memcpy(rnd, magic[k], 4);
        rnd[4] = 1 + (unsigned char)(k & 1);
        rnd[5] = 0;
        char label[64];
        snprintf(label, sizeof label, "<%s, version %d, then 594 random bytes>", magic[k], rnd[4]);
        add_blob(label, rnd, 600);
    }
    {
        /* a motion header claiming the largest sizes, and nothing after */
        unsigned char h[32] = {'A', 'F', 'M', 'O', 1, 0, 0, 0, 0, 0, 0, 1, 0, 0x10, 0, 0};
        double fps = 30;
        memcpy(h + 16, &fps, 8); /* little-endian hosts only; the sweep does not need others */
        add_blob("<motion header: 16777216 frames × 4096 joints, no payload>", h, 32);
        h[8] = 0xff, h[9] = 0xff, h[10] = 0xff, h[11] = 0xff, h[12] = 0xff, h[13] = 0xff;
        h[14] = 0xff, h[15] = 0xff;
        add_blob("<motion header: 2^32-1 frames × 2^32-1 joints>", h, 32);
    }

    add_from_sql(M, "SELECT m FROM corpus WHERE action = 'wave' AND emotion = 'sad' AND seed = 1");
    add_from_sql(M2,
                 "SELECT m FROM corpus WHERE action = 'knock' AND emotion = 'angry' AND seed = 2");
    add_from_sql("<motion: 1 frame>", "SELECT motion_slice(m, 0, 0) FROM corpus WHERE id = 1");
    add_from_sql(
        "<motion: 3 joints>",
        "SELECT motion_select(m, '[\"Hips\",\"Head\",\"Hand_R\"]') FROM corpus WHERE id = 1");
    add_from_sql("<motion: skeletal, from BVH>",
                 "SELECT motion_from_bvh(motion_to_bvh(m)) FROM corpus WHERE id = 1");
    add_from_sql("<bvh text>",
                 "SELECT motion_to_bvh(motion_slice(m, 0, 4)) FROM corpus WHERE id = 1");
    add_from_sql("<csv text>",
                 "SELECT motion_to_csv(motion_slice(m, 0, 4)) FROM corpus WHERE id = 1");
    add_from_sql("<json text>",
                 "SELECT motion_to_json(motion_slice(m, 0, 4)) FROM corpus WHERE id = 1");
    add_from_sql(HMM, "SELECT hmm_train(m, hmm_opt) FROM agg_rows WHERE label = 'sad'");
    add_from_sql(CLS, "SELECT affect_train(m, label, cls_opt) FROM agg_rows");
    add_from_sql(FDA, "SELECT fda_train(m, label, fda_opt) FROM agg_rows");
    add_from_sql("<laban vector>", "SELECT laban_vector(m) FROM corpus WHERE id = 1");
    add_from_sql(STR, "SELECT strength_train(m, label, str_opt) FROM agg_rows");
    add_from_sql(RNK, "SELECT rank_train(vec, label, rank_opt) FROM agg_rows");
    add_from_sql("<fisher score>", "SELECT fisher_score((SELECT affect_train(m, label, cls_opt) "
                                   "FROM agg_rows), m) FROM corpus WHERE id = 1");
    add_from_sql("<embedding>", "SELECT affect_embed((SELECT affect_train(m, label, cls_opt) "
                                "FROM agg_rows), m) FROM corpus WHERE id = 1");
    add_text("<crossval options>", CV_OPT, -1);
    add_crafted();
    add_fixture(fixtures, "motion-v1.bin");
    add_fixture(fixtures, "motion-v2.bin");
    add_fixture(fixtures, "hmm-v1.bin");
    add_fixture(fixtures, "classifier-v1.bin");
    add_fixture(fixtures, "strength-v1.bin");
    add_fixture(fixtures, "strength-v2.bin");
    add_fixture(fixtures, "strength-v3.bin");
    add_fixture(fixtures, "ranker-v1.bin");
    add_fixture(fixtures, "fda-v1.bin");

    /* the short pool: these, every BLOB made above, and some corruptions of each kind */
    /* clang-format off */
    static const char *const lite[] = {
        "NULL", "0", "-1", "9223372036854775807", "NaN", "+Inf", "1e308", "0.5", "''", "'x'",
        "'a' × 1000000", "invalid UTF-8 \\xff\\xfe", "'a' NUL 'b'", "'wave'", "'angry'", "'{}'",
        "'{\"bogus\":1}'", "'[1,2]'", "'{\"a\":'", "'[' × 20000", "<bvh text>", "<csv text>",
        "<json text>", "<crossval options>"};
    /* clang-format on */
    for (size_t i = 0; i < sizeof lite / sizeof lite[0]; i++)
        ((value *)find_value(lite[i]))->lite = true;

    static const struct {
        const char *label;
        bool text;
    } kinds[] = {
        {M, false},
        {"<motion: skeletal, from BVH>", false},
        {"<fixture motion-v2.bin>", false},
        {HMM, false},
        {CLS, false},
        {"<laban vector>", false},
        {"<fisher score>", false},
        {STR, false},
        {RNK, false},
        {"<bvh text>", true},
        {"<csv text>", true},
        {"<json text>", true},
    };
    for (size_t k = 0; k < sizeof kinds / sizeof kinds[0]; k++)
        add_corruptions(find_value(kinds[k].label), kinds[k].text);
}

/* ---- the sweep of one function or table-valued function ---- */

typedef enum kind { SCALAR, AGGREGATE, TABLE } kind;

typedef struct form {
    char *name;
    int n_arg;
    kind kind;
} form;

static int n_forms;
static long n_random_skipped;
static int n_random = 24; /* random combinations per form */
static double budget_end;

/* One argument of a call: a pool value, or a column of agg_rows (aggregates). */
typedef struct arg {
    const value *v;
    const char *column;
    bool first_row_only; /* aggregates: the value in row 2 only, the column elsewhere */
} arg;

static void describe(const form *f, const arg *args)
{
    size_t off = 0;
    off += (size_t)snprintf(current_call + off, sizeof current_call - off, "%s%s(", f->name,
                            f->kind == TABLE ? " table" : "");
    for (int i = 0; i < f->n_arg && off < sizeof current_call; i++) {
        const char *sep = i ? ", " : "";
        if (args[i].column)
            off += (size_t)snprintf(current_call + off, sizeof current_call - off, "%s%s", sep,
                                    args[i].column);
        else if (args[i].first_row_only)
            off += (size_t)snprintf(current_call + off, sizeof current_call - off, "%s%s in row 2",
                                    sep, args[i].v->label);
        else
            off += (size_t)snprintf(current_call + off, sizeof current_call - off, "%s%s", sep,
                                    args[i].v->label);
    }
    if (off < sizeof current_call)
        snprintf(current_call + off, sizeof current_call - off, ")%s",
                 f->kind == AGGREGATE ? " over agg_rows" : "");
}

/* The SQL of a call with these argument shapes; ?i is argument i's value. */
static char *call_sql(const form *f, const arg *args, const baseline *b)
{
    char buf[2048];
    size_t off = 0;
    if (f->kind == TABLE)
        off += (size_t)snprintf(buf + off, sizeof buf - off, "SELECT * FROM \"%s\"(", f->name);
    else
        off += (size_t)snprintf(buf + off, sizeof buf - off, "SELECT \"%s\"(", f->name);
    for (int i = 0; i < f->n_arg; i++) {
        const char *sep = i ? ", " : "";
        if (args[i].column)
            off += (size_t)snprintf(buf + off, sizeof buf - off, "%s%s", sep, args[i].column);
        else if (args[i].first_row_only)
            off += (size_t)snprintf(buf + off, sizeof buf - off,
                                    "%sCASE WHEN rowid = 2 THEN ?%d ELSE %s END", sep, i + 1,
                                    b->args[i] + 1);
        else
            off += (size_t)snprintf(buf + off, sizeof buf - off, "%s?%d", sep, i + 1);
    }
    snprintf(buf + off, sizeof buf - off, ")%s", f->kind == AGGREGATE ? " FROM agg_rows" : "");
    return dup_printf("%s", buf);
}

static void bind_args(sqlite3_stmt *st, const form *f, const arg *args)
{
    for (int i = 0; i < f->n_arg; i++)
        if (!args[i].column)
            bind_value(st, i + 1, args[i].v);
}

/* The baseline arguments of a form. */
static void baseline_args(const form *f, const baseline *b, arg *args)
{
    static const value null_value = {"NULL", SQLITE_NULL, 0, 0, NULL, 0, 0, false};
    for (int i = 0; i < f->n_arg; i++) {
        memset(&args[i], 0, sizeof args[i]);
        const char *a = b && i < MAX_ARGS ? b->args[i] : NULL;
        if (a && a[0] == '@')
            args[i].column = a + 1;
        else if (a)
            args[i].v = find_value(a);
        else
            args[i].v = &null_value;
    }
}

/* The shortest and longest registered argument counts of a function or table. */
static void form_range(const form *forms, const form *f, int *shortest, int *longest)
{
    *shortest = 1 << 30;
    *longest = -1;
    for (int i = 0; i < n_forms; i++)
        if (strcmp(forms[i].name, f->name) == 0 && forms[i].kind == f->kind) {
            if (forms[i].n_arg < *shortest)
                *shortest = forms[i].n_arg;
            if (forms[i].n_arg > *longest)
                *longest = forms[i].n_arg;
        }
}

/* Which positions of form f are swept with every pool value, and with which part of it:
 * a position shared by several forms is swept once — at the shortest form for a function; at
 * the longest for a slow function (its baseline options keep training small; the shorter forms
 * mean the expensive defaults) and for a table-valued function (a shorter call lacks required
 * arguments). Slow functions take the short pool. */
static void sweep_form(const form *forms, const form *f)
{
    const baseline *b = find_baseline(f->name);
    if (!b)
        fprintf(stderr, "note: %s/%d has no baseline in test_sweep.c: swept around NULLs\n",
                f->name, f->n_arg);
    bool slow = b && b->slow;
    int shortest, longest;
    form_range(forms, f, &shortest, &longest);
    bool at_longest = slow || f->kind == TABLE;
    int from, to;
    if (at_longest)
        from = 0, to = f->n_arg == longest ? f->n_arg : 0;
    else
        from = f->n_arg > shortest ? shortest : 0, to = f->n_arg;
    arg args[MAX_ARGS];

    /* the baseline itself */
    baseline_args(f, b, args);
    char *sql = call_sql(f, args, b);
    sqlite3_stmt *st = prepare_or_die(sql);
    free(sql);
    bind_args(st, f, args);
    describe(f, args);
    if (!run_call(st, f->name) && b && (f->n_arg == longest || verbose))
        fprintf(stderr, "note: the baseline %s fails: %s\n", current_call, sqlite3_errmsg(db));
    sqlite3_finalize(st);

    /* one position at a time, every pool value */
    for (int pos = from; pos < to; pos++) {
        for (int mode = 0; mode < 2; mode++) {
            baseline_args(f, b, args);
            if (mode == 1) {
                /* aggregates: the value in one row only, for per-row arguments */
                if (!args[pos].column || strstr(args[pos].column, "_opt"))
                    continue;
                args[pos].first_row_only = true;
            }
            args[pos].column = NULL;
            args[pos].v = &pool[0];
            sql = call_sql(f, args, b);
            st = prepare_or_die(sql);
            free(sql);
            for (int k = 0; k < n_pool; k++) {
                if (slow && !pool[k].lite) {
                    total.skipped++;
                    continue;
                }
                args[pos].v = &pool[k];
                bind_args(st, f, args);
                describe(f, args);
                run_call(st, f->name);
            }
            sqlite3_finalize(st);
        }
    }

    /* random combinations (slow functions: at their longest form, from the short pool) */
    if (f->n_arg == 0 || (at_longest && f->n_arg != longest))
        return;
    for (int r = 0; r < n_random; r++) {
        baseline_args(f, b, args);
        for (int i = 0; i < f->n_arg; i++)
            if (rng_below(2)) {
                int k = rng_below(n_pool);
                while (slow && !pool[k].lite)
                    k = rng_below(n_pool);
                args[i].column = NULL;
                args[i].v = &pool[k];
            }
        if (now() > budget_end) {
            n_random_skipped++;
            continue;
        }
        sql = call_sql(f, args, b);
        st = prepare_or_die(sql);
        free(sql);
        bind_args(st, f, args);
        describe(f, args);
        run_call(st, f->name);
        sqlite3_finalize(st);
    }
}

/* ---- odd constraint shapes on the table-valued functions ---- */

static void sweep_table_shapes(const form *f)
{
    static const char *const shapes[] = {
        "SELECT * FROM \"%s\"",
        "SELECT * FROM \"%s\" WHERE \"%s\" > ?1",
        "SELECT * FROM \"%s\" WHERE \"%s\" IS ?1",
        "SELECT * FROM \"%s\" WHERE \"%s\" IN (?1, ?2)",
        "SELECT * FROM \"%s\" WHERE \"%s\" = ?1 OR \"%s\" = ?2",
        "SELECT * FROM \"%s\"(?1) WHERE \"%s\" = ?2",
        "SELECT * FROM \"%s\" WHERE \"%s\" = ?1 AND \"%s\" = ?2",
        "SELECT count(*) FROM pool_t LEFT JOIN \"%s\"(pool_t.v)",
        "SELECT count(*) FROM pool_t, \"%s\" AS t WHERE t.\"%s\" = pool_t.v",
        "SELECT * FROM \"%s\" WHERE \"%s\" = ?1 ORDER BY 1 DESC LIMIT 2 OFFSET 1",
    };
    /* the first hidden column */
    char q[512], col[256] = "";
    snprintf(q, sizeof q, "SELECT name FROM pragma_table_xinfo('%s') WHERE hidden <> 0 LIMIT 1",
             f->name);
    sqlite3_stmt *st = prepare_or_die(q);
    if (sqlite3_step(st) == SQLITE_ROW)
        snprintf(col, sizeof col, "%s", (const char *)sqlite3_column_text(st, 0));
    sqlite3_finalize(st);
    const baseline *b = find_baseline(f->name);
    const value *good = b && b->args[0] ? find_value(b->args[0]) : &pool[0];
    const value *odd[] = {good, find_value("x''"), find_value("<random 4096 bytes>"),
                          find_value("'a' × 1000000"), find_value("NaN")};
    for (size_t s = 0; s < sizeof shapes / sizeof shapes[0]; s++) {
        char sql[1024];
        snprintf(sql, sizeof sql, shapes[s], f->name, col, col);
        st = NULL;
        if (sqlite3_prepare_v2(db, sql, -1, &st, NULL) != SQLITE_OK) {
            snprintf(current_call, sizeof current_call, "prepare %s", sql);
            total.calls++;
            total.errors++;
            const char *msg = sqlite3_errmsg(db);
            /* SQLite's own answer when every plan was refused as unusable */
            if (!names(msg, f->name) && strcmp(msg, "no query solution") != 0)
                note_failure(current_call, msg);
            continue;
        }
        for (size_t i = 0; i < sizeof odd / sizeof odd[0]; i++) {
            for (int p = 1; p <= sqlite3_bind_parameter_count(st); p++)
                bind_value(st, p, odd[(i + (size_t)p - 1) % (sizeof odd / sizeof odd[0])]);
            snprintf(current_call, sizeof current_call, "%s with ?1 = %s", sql, odd[i]->label);
            run_call(st, f->name);
        }
        sqlite3_finalize(st);
    }
}

/* ---- the laban virtual table ---- */

/* Runs sql (parameters ?1, ?2 bound to a and b when present) and judges it against `names`. */
static bool run_sql(const char *sql, const value *a, const value *b, const char *name_list)
{
    sqlite3_stmt *st = NULL;
    snprintf(current_call, sizeof current_call, "%s", sql);
    if (a)
        snprintf(current_call + strlen(current_call), sizeof current_call - strlen(current_call),
                 " with ?1 = %s", a->label);
    if (b)
        snprintf(current_call + strlen(current_call), sizeof current_call - strlen(current_call),
                 ", ?2 = %s", b->label);
    if (sqlite3_prepare_v2(db, sql, -1, &st, NULL) != SQLITE_OK) {
        total.calls++;
        total.errors++;
        const char *msg = sqlite3_errmsg(db);
        if (!names(msg, "laban") && strcmp(msg, "no query solution") != 0)
            note_failure(current_call, msg);
        return false;
    }
    int np = sqlite3_bind_parameter_count(st);
    if (np >= 1 && a)
        bind_value(st, 1, a);
    if (np >= 2 && b)
        bind_value(st, 2, b);
    bool ok = run_call(st, name_list);
    sqlite3_finalize(st);
    return ok;
}

static double cpu(void)
{
    return (double)clock() / CLOCKS_PER_SEC;
}

static void phase_done(const char *what, double *t, long *calls)
{
    if (verbose || cpu() - *t > 2)
        fprintf(stderr, "  laban table, %s: %ld calls, %.1f s of CPU\n", what, total.calls - *calls,
                cpu() - *t);
    *t = cpu();
    *calls = total.calls;
}

/* The functions that read an index: laban_salient's fit with 2 folds, generation with the
 * components given (no fit), both methods, and laban_zvector; target_sql is the target
 * label's SQL. */
static void generation(const char *index, const char *target_sql)
{
    static const char *const calls[][2] = {
        {"SELECT laban_salient('%s', '{\"folds\":2}')", "laban_salient"},
        {"SELECT affect_generate('%s', ?1, %s, '{\"components\":[\"WeightAll\",\"TimeAll\","
         "\"FlowAll\"]}')",
         "affect_generate"},
        {"SELECT affect_generate_explain('%s', ?1, %s, '{\"method\":\"hmm_nn\",\"components\":"
         "[\"WeightAll\",\"TimeAll\",\"FlowAll\"]}')",
         "affect_generate_explain"},
        /* the index's statistics and options (_info), read back as untrusted input */
        {"SELECT laban_zvector(?1, '%s', '{\"components\":[\"TimeAll\",\"FlowAll\"]}')",
         "laban_zvector"},
    };
    for (size_t i = 0; i < sizeof calls / sizeof calls[0]; i++) {
        char q[512];
        snprintf(q, sizeof q, calls[i][0], index, target_sql);
        run_sql(q, i ? find_value(M) : NULL, NULL, calls[i][1]);
    }
}

static void sweep_laban(void)
{
    double t = cpu();
    long calls = total.calls;
    /* CREATE with bad arguments */
    static const char *const creates[] = {
        "",
        "()",
        "(content=nosuch)",
        "(content=corpus, motion=nosuch)",
        "(content=corpus, label=nosuch)",
        "(content=corpus, motion=m, motion=m)",
        "(contnet=corpus)",
        "(content=corpus, motion=m, label=emotion, options='{bogus}')",
        "(content=corpus, motion=m, label=emotion, options='[1,2]')",
        "(content=corpus, motion=m, label=emotion, options='{\"cutoff_hz\":0}')",
        "(content=corpus, motion=m, label=emotion, options='{\"hull\":\"sphere\"}')",
        "(content=corpus, motion=m, label=emotion, options='{\"up\":\"w\"}')",
        "(content=\"corpus\", motion=\"m\", label=\"emotion\", extra)",
        "(content=corpus, motion=m, label=emotion, options=)",
        "(content=, motion=m)",
        "(=corpus)",
        "(content=corpus, motion=action, label=emotion)",
        "(content=corpus, motion=seed, label=m)",
        "(content=corpus, motion=m, label=m)",
        "(content=pool_t, motion=v, label=v)",
        "(content=empty_t, motion=m, label=label)",
        "(content=junk, motion=motion, label=label)",
        "(content=sqlite_master, motion=sql, label=name)",
        "(content=idx, motion=WeightAll, label=label)",
        "(content=\"x\xff\xfey\", motion=m)",
    };
    for (size_t i = 0; i < sizeof creates / sizeof creates[0]; i++) {
        char sql[1024];
        snprintf(sql, sizeof sql, "CREATE VIRTUAL TABLE t%zu USING laban%s", i, creates[i]);
        if (run_sql(sql, NULL, NULL, "laban")) {
            /* created: read it, query it, drop it */
            char q[256];
            snprintf(q, sizeof q, "SELECT * FROM t%zu", i);
            run_sql(q, NULL, NULL, "laban");
            snprintf(q, sizeof q, "SELECT rowid, distance FROM t%zu WHERE query = ?1 AND k = 3", i);
            run_sql(q, find_value(M), NULL, "laban");
            snprintf(q, sizeof q,
                     "SELECT rowid, distance FROM t%zu WHERE query = 1 AND radius = 0.5", i);
            run_sql(q, NULL, NULL, "laban");
            snprintf(q, sizeof q, "SELECT laban_salient('t%zu')", i);
            run_sql(q, NULL, NULL, "laban_salient");
            snprintf(q, sizeof q, "SELECT affect_generate('t%zu', ?1, 'angry')", i);
            run_sql(q, find_value(M), NULL, "affect_generate");
            snprintf(q, sizeof q, "SELECT affect_generate_explain('t%zu', ?1, 'sad', ?2)", i);
            run_sql(q, find_value(M), find_value("'{\"method\":\"hmm_nn\"}'"),
                    "affect_generate_explain");
            snprintf(q, sizeof q, "INSERT INTO t%zu(t%zu) VALUES('check')", i, i);
            run_sql(q, NULL, NULL, "laban");
            snprintf(q, sizeof q, "DROP TABLE t%zu", i);
            run_sql(q, NULL, NULL, "laban");
        }
    }

    phase_done("CREATE with bad arguments", &t, &calls);

    /* every pool value as a constraint, the others valid */
    static const char *const queries[] = {
        "SELECT rowid, label, distance FROM idx WHERE query = ?1 AND k = ?2",
        "SELECT rowid, label, distance FROM idx WHERE query = ?1 AND radius = ?2",
        "SELECT rowid, label, distance FROM idx WHERE query = ?1 AND k = 3 AND label = ?2",
        "SELECT rowid, label, distance FROM idx WHERE query = ?1 AND k = 3 AND components = ?2",
        "SELECT rowid, label, distance FROM idx WHERE query = ?1 AND radius = 0.5 AND rowid = ?2",
        "SELECT * FROM idx WHERE rowid = ?1 OR label = ?2",
    };
    const value *good_a[] = {find_value(M), find_value(M),   find_value(M),
                             find_value(M), find_value("2"), find_value("2")};
    const value *good_b[] = {find_value("2"),     find_value("0.5"),
                             find_value("'sad'"), find_value("'[\"TimeAll\",\"FlowAll\"]'"),
                             find_value("2"),     find_value("'sad'")};
    for (size_t q = 0; q < sizeof queries / sizeof queries[0]; q++)
        for (int pos = 0; pos < 2; pos++)
            for (int k = 0; k < n_pool; k++)
                run_sql(queries[q], pos == 0 ? &pool[k] : good_a[q],
                        pos == 1 ? &pool[k] : good_b[q], "laban");

    phase_done("constraints", &t, &calls);

    /* odd shapes */
    static const char *const shapes[] = {
        "SELECT * FROM idx WHERE k = 3",
        "SELECT * FROM idx WHERE radius = 0.5 AND components = '[\"TimeAll\"]'",
        "SELECT * FROM idx WHERE query = ?1",
        "SELECT * FROM idx WHERE query = ?1 AND k = 3 AND radius = 0.5",
        "SELECT * FROM idx WHERE query > ?1 AND k = 3",
        "SELECT * FROM idx WHERE query = ?1 AND k > 3",
        "SELECT * FROM idx WHERE query = ?1 AND k = 3 AND k = 4",
        "SELECT * FROM idx WHERE query = ?1 OR k = 3",
        "SELECT * FROM idx WHERE query IN (?1, 2) AND k = 3",
        "SELECT * FROM idx WHERE query = ?1 AND k IN (1, 2)",
        "SELECT * FROM idx WHERE query IS ?1 AND k IS 3",
        "SELECT * FROM idx WHERE query = ?1 AND k = 3 ORDER BY distance DESC, rowid DESC",
        "SELECT * FROM idx WHERE query = ?1 AND k = 3 ORDER BY label LIMIT 1 OFFSET 2",
        "SELECT * FROM idx WHERE distance < 1 AND query = ?1 AND k = 3",
        "SELECT count(*) FROM pool_t, idx WHERE idx.query = pool_t.v AND idx.k = 2",
        "SELECT count(*) FROM pool_t, idx WHERE idx.query = ?1 AND idx.k = pool_t.v",
        "SELECT count(*) FROM pool_t, idx WHERE idx.query = ?1 AND idx.radius = pool_t.v",
        "SELECT count(*) FROM pool_t, idx WHERE idx.query = ?1 AND idx.k = 1 AND "
        "idx.components = pool_t.v",
        "SELECT count(*) FROM pool_t LEFT JOIN idx ON idx.query = pool_t.v AND idx.k = 1",
        "SELECT * FROM idx WHERE idx = ?1",
        "SELECT * FROM idx WHERE query = (SELECT m FROM corpus WHERE id = 3) AND k = 2 AND "
        "label = (SELECT emotion FROM corpus WHERE id = 3)",
    };
    const value *odd[] = {find_value(M),     find_value("2"),
                          find_value("x''"), find_value("<random 4096 bytes>"),
                          find_value("NaN"), find_value("'a' × 1000000")};
    for (size_t s = 0; s < sizeof shapes / sizeof shapes[0]; s++)
        for (size_t i = 0; i < sizeof odd / sizeof odd[0]; i++)
            run_sql(shapes[s], odd[i], NULL, "laban");

    phase_done("constraint shapes", &t, &calls);

    /* the write commands, on a second index of the same content */
    exec_or_die("CREATE TABLE corpus2 AS SELECT * FROM corpus;"
                "CREATE VIRTUAL TABLE idx2 USING laban(content=corpus2, motion=m, label=emotion)");
    static const char *const writes[] = {
        "INSERT INTO idx2(idx2) VALUES(?1)",
        "INSERT INTO idx2(idx2, rowid) VALUES('refresh', ?1)",
        "INSERT INTO idx2(idx2, rowid) VALUES('delete', ?1)",
        "INSERT INTO idx2(idx2, rowid) VALUES(?1, 3)",
        "INSERT INTO idx2(rowid, label) VALUES(99, ?1)",
        "UPDATE idx2 SET label = ?1 WHERE rowid = 1",
        "DELETE FROM idx2 WHERE rowid = ?1",
        "UPDATE corpus2 SET m = ?1 WHERE rowid = 2",
    };
    for (size_t w = 0; w < sizeof writes / sizeof writes[0]; w++)
        for (int k = 0; k < n_pool; k++) {
            /* SQLite itself requires an integer rowid for an INSERT */
            run_sql(writes[w], &pool[k], NULL,
                    w == 1 || w == 2 ? "laban|=datatype mismatch" : "laban");
            if (w == 7) {
                /* the changed content: stale check, refresh of that row, a query */
                run_sql("INSERT INTO idx2(idx2) VALUES('check')", NULL, NULL, "laban");
                run_sql("INSERT INTO idx2(idx2, rowid) VALUES('refresh', 2)", NULL, NULL, "laban");
                run_sql("SELECT rowid, distance FROM idx2 WHERE query = 1 AND k = 7", NULL, NULL,
                        "laban");
            }
        }

    phase_done("write commands", &t, &calls);

    /* indexes of odd content: hostile labels on valid motions (junk_labels), and every pool
     * value that decodes as a motion — other skeletons, units, hostile joint names, payload bit
     * flips — under two labels (junk_motions); each read, queried and used by generation */
    exec_or_die("CREATE TABLE junk_labels(id INTEGER PRIMARY KEY, motion, label);"
                "CREATE TABLE junk_motions(id INTEGER PRIMARY KEY, motion, label);");
    {
        /* four labels (a fit's cost grows with their number), two rows each */
        const value *labels[] = {find_value("invalid UTF-8 \\xff\\xfe"), find_value("x''"),
                                 find_value("'a' NUL 'b'"), find_value("9223372036854775807")};
        sqlite3_stmt *ins = prepare_or_die(
            "INSERT INTO junk_labels(motion, label) SELECT m, ?1 FROM corpus WHERE id IN (?2, ?3)");
        for (int i = 0; i < 4; i++) {
            bind_value(ins, 1, labels[i]);
            sqlite3_bind_int(ins, 2, 1 + i * 2);
            sqlite3_bind_int(ins, 3, 2 + i * 2);
            if (sqlite3_step(ins) != SQLITE_DONE)
                die("cannot fill junk_labels: %s", sqlite3_errmsg(db));
            sqlite3_reset(ins);
        }
        sqlite3_finalize(ins);
        sqlite3_stmt *probe = prepare_or_die("SELECT motion_frames(?1)");
        ins = prepare_or_die("INSERT INTO junk_motions(motion, label) VALUES(?1, ?2)");
        int n = 0;
        for (int k = 0; k < n_pool; k++) {
            bind_value(probe, 1, &pool[k]);
            bool motion = sqlite3_step(probe) == SQLITE_ROW &&
                          sqlite3_column_type(probe, 0) == SQLITE_INTEGER;
            sqlite3_reset(probe);
            if (!motion)
                continue;
            bind_value(ins, 1, &pool[k]);
            sqlite3_bind_text(ins, 2, n++ % 2 ? "angry" : "sad", -1, SQLITE_STATIC);
            if (sqlite3_step(ins) != SQLITE_DONE)
                die("cannot fill junk_motions: %s", sqlite3_errmsg(db));
            sqlite3_reset(ins);
        }
        sqlite3_finalize(probe);
        sqlite3_finalize(ins);
    }
    static const char *const junk[] = {"junk_labels", "junk_motions"};
    for (int j = 0; j < 2; j++) {
        char q[512];
        snprintf(q, sizeof q, "CREATE VIRTUAL TABLE %s_idx USING laban(content=%s, motion=motion)",
                 junk[j], junk[j]);
        if (!run_sql(q, NULL, NULL, "laban"))
            continue;
        static const char *const reads[] = {
            "SELECT * FROM %s_idx",
            "SELECT rowid, label, distance FROM %s_idx WHERE query = ?1 AND k = 4",
            "SELECT rowid, label, distance FROM %s_idx WHERE query = 2 AND radius = 0.2",
            "SELECT count(*) FROM %s_idx AS i, %s AS c WHERE i.query = ?1 AND i.k = 2 "
            "AND i.label = c.label",
            "INSERT INTO %s_idx(%s_idx) VALUES('check')",
        };
        for (size_t r = 0; r < sizeof reads / sizeof reads[0]; r++) {
            snprintf(q, sizeof q, reads[r], junk[j], junk[j]);
            run_sql(q, find_value(M), NULL, "laban");
        }
        char index[64], target[128];
        snprintf(index, sizeof index, "%s_idx", junk[j]);
        snprintf(target, sizeof target, "(SELECT label FROM %s WHERE id = 3)", junk[j]);
        generation(index, target);
    }
    phase_done("odd content", &t, &calls);

    /* corrupt shadow tables: each trial restores the saved tables, bumps the generation so that
     * the cached vectors are reloaded, then replaces one stored value by a pool value */
    exec_or_die("CREATE TABLE corpus3 AS SELECT * FROM corpus;"
                "CREATE VIRTUAL TABLE idx3 USING laban(content=corpus3, motion=m, label=emotion);"
                "CREATE TABLE data_bak AS SELECT * FROM idx3_data;"
                "CREATE TABLE info_bak AS SELECT * FROM idx3_info;");
    static const char *const corruptions[] = {
        "UPDATE idx3_data SET vector = ?1 WHERE id = 2",
        "UPDATE idx3_data SET label = ?1 WHERE id = 3",
        "UPDATE idx3_data SET msize = ?1 WHERE id = 4",
        "UPDATE idx3_data SET id = ?1 WHERE id = 5",
        "UPDATE idx3_info SET value = ?1 WHERE key = 'format'",
        "UPDATE idx3_info SET value = ?1 WHERE key = 'rows'",
        "UPDATE idx3_info SET value = ?1 WHERE key = 'mean'",
        "UPDATE idx3_info SET value = ?1 WHERE key = 'sd'",
        "UPDATE idx3_info SET value = ?1 WHERE key = 'generation'",
        "UPDATE idx3_info SET value = ?1 WHERE key = 'options'",
        "UPDATE idx3_info SET value = ?1 WHERE key = 'content'",
    };
    static const char *const readers[] = {
        "SELECT * FROM idx3",
        "SELECT rowid, distance FROM idx3 WHERE query = 1 AND k = 3",
        "SELECT rowid, distance FROM idx3 WHERE query = ?1 AND radius = 0.3 AND label = 'sad'",
        "INSERT INTO idx3(idx3) VALUES('check')",
    };
    long counter = 1000; /* the generation stored in idx3_info */
    for (size_t c = 0; c < sizeof corruptions / sizeof corruptions[0]; c++)
        for (int k = 0; k < n_pool; k++) {
            if (!pool[k].lite)
                continue;
            char reset[512];
            snprintf(reset, sizeof reset,
                     "DELETE FROM idx3_data; INSERT INTO idx3_data SELECT * FROM data_bak;"
                     "DELETE FROM idx3_info; INSERT INTO idx3_info SELECT * FROM info_bak;"
                     "UPDATE idx3_info SET value = '%ld' WHERE key = 'generation'",
                     ++counter);
            exec_or_die(reset);
            /* a plain write to an ordinary table (SQLite may refuse it: an id must be an
             * integer): not a call of the module */
            sqlite3_stmt *st = prepare_or_die(corruptions[c]);
            bind_value(st, 1, &pool[k]);
            int rc = sqlite3_step(st);
            sqlite3_finalize(st);
            if (rc != SQLITE_DONE)
                continue;
            for (size_t r = 0; r < sizeof readers / sizeof readers[0]; r++)
                run_sql(readers[r], find_value(M), NULL, "laban");
            /* the generation functions read the index through its API: the vectors, labels and
             * statistics replaced by a few values */
            const char *l = pool[k].label;
            bool few = strcmp(l, "NULL") == 0 || strcmp(l, "x''") == 0 || strcmp(l, "'x'") == 0 ||
                       strcmp(l, "<laban vector: all NaN>") == 0;
            if ((c == 0 && (few || strncmp(l, "<laban vector:", 14) == 0)) ||
                ((c == 1 || c == 6 || c == 7) && few))
                generation("idx3", "'angry'");
        }
    phase_done("corrupt shadow tables", &t, &calls);
}

/* ---- main ---- */

/* name is an item of the comma-separated list */
static bool listed(const char *list, const char *name)
{
    size_t n = strlen(name);
    for (const char *p = list; p; p = strchr(p, ',') ? strchr(p, ',') + 1 : NULL)
        if (strncmp(p, name, n) == 0 && (p[n] == ',' || p[n] == '\0'))
            return true;
    return false;
}

static void push_form(form **forms, const char *name, int n_arg, kind k)
{
    *forms = realloc(*forms, (size_t)(n_forms + 1) * sizeof **forms);
    if (!*forms)
        die("out of memory");
    (*forms)[n_forms].name = dup_printf("%s", name);
    (*forms)[n_forms].n_arg = n_arg;
    (*forms)[n_forms].kind = k;
    n_forms++;
}

/* Every (name, argument count) the module adds: functions from pragma_function_list, then the
 * table-valued functions (eponymous modules, whose hidden columns are the arguments) with 1 up
 * to all of their arguments. */
static form *load_forms(int *n_names, int *n_tables)
{
    /* what a fresh connection has before the module, to subtract */
    exec_or_die(
        "CREATE TEMP TABLE before_f AS SELECT DISTINCT name, narg FROM pragma_function_list;"
        "CREATE TEMP TABLE before_m AS SELECT name FROM pragma_module_list;");
    char *err = NULL;
    if (sqlite3_load_extension(db, module_path, "sqlite3_affect_init", &err) != SQLITE_OK)
        die("cannot load %s: %s", module_path, err ? err : "?");
    sqlite3_stmt *st = prepare_or_die(
        "SELECT DISTINCT name, narg, type FROM pragma_function_list AS f WHERE NOT EXISTS "
        "(SELECT 1 FROM before_f AS b WHERE b.name = f.name AND b.narg = f.narg) "
        "ORDER BY name, narg");
    form *forms = NULL;
    n_forms = 0;
    *n_names = 0;
    char last[256] = "";
    while (sqlite3_step(st) == SQLITE_ROW) {
        const char *name = (const char *)sqlite3_column_text(st, 0);
        int narg = sqlite3_column_int(st, 1);
        const char *type = (const char *)sqlite3_column_text(st, 2);
        if (strcmp(name, last) != 0)
            ++*n_names;
        snprintf(last, sizeof last, "%s", name);
        int lo = narg, hi = narg;
        if (narg < 0)
            lo = 0, hi = 4; /* variadic: 0 to 4 arguments */
        for (int n = lo; n <= hi; n++)
            push_form(&forms, name, n, strcmp(type, "a") == 0 ? AGGREGATE : SCALAR);
    }
    sqlite3_finalize(st);
    st = prepare_or_die("SELECT name, (SELECT count(*) FROM pragma_table_xinfo(m.name) "
                        "WHERE hidden <> 0) FROM pragma_module_list AS m "
                        "WHERE name NOT IN (SELECT name FROM before_m) "
                        "AND name NOT LIKE 'pragma\\_%' ESCAPE '\\' ORDER BY name");
    *n_tables = 0;
    int rc;
    while ((rc = sqlite3_step(st)) == SQLITE_ROW) {
        int hidden = sqlite3_column_int(st, 1);
        if (hidden == 0)
            continue; /* not eponymous (laban): swept by sweep_laban */
        ++*n_tables;
        for (int n = 1; n <= hidden; n++)
            push_form(&forms, (const char *)sqlite3_column_text(st, 0), n, TABLE);
    }
    if (rc != SQLITE_DONE)
        die("cannot list the modules: %s", sqlite3_errmsg(db));
    sqlite3_finalize(st);
    return forms;
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: %s MODULE [FIXTURES_DIR]\n", argv[0]);
        return 2;
    }
    module_path = argv[1];
    const char *fixtures = argc > 2 ? argv[2] : AFFECT_FIXTURES_DIR;
    const char *env = getenv("AFFECT_SWEEP_SEED");
    unsigned long long seed = env ? strtoull(env, NULL, 10) : 14;
    rng_state = seed;
    verbose = getenv("AFFECT_SWEEP_VERBOSE") && atoi(getenv("AFFECT_SWEEP_VERBOSE"));
    env = getenv("AFFECT_SWEEP_RANDOM");
    if (env)
        n_random = atoi(env);
    env = getenv("AFFECT_SWEEP_BUDGET");
    double start = now();
    budget_end = start + (env ? atof(env) : 150.0);
    snprintf(current_call, sizeof current_call, "(setup)");
#ifdef SWEEP_SANITIZED
    __sanitizer_set_death_callback(print_current_call);
#else
    signal(SIGSEGV, on_signal);
    signal(SIGBUS, on_signal);
    signal(SIGFPE, on_signal);
    signal(SIGILL, on_signal);
    signal(SIGABRT, on_signal);
#endif

    if (sqlite3_open(":memory:", &db) != SQLITE_OK)
        die("cannot open a database");
    sqlite3_enable_load_extension(db, 1);
    sqlite3_progress_handler(db, 10000, progress, NULL);
    int n_names, n_tables;
    form *forms = load_forms(&n_names, &n_tables);

    /* the corpus: 8 short synthetic motions, an index of them, the aggregates' rows */
    exec_or_die(
        "CREATE TABLE corpus(id INTEGER PRIMARY KEY, action TEXT, emotion TEXT, seed INTEGER, m);"
        "INSERT INTO corpus(action, emotion, seed, m) SELECT a.value, e.value, k.value,"
        "       motion_slice(motion_synth(a.value, e.value, k.value), 0, 29)"
        "  FROM json_each('[\"wave\",\"knock\"]') AS a, json_each('[\"sad\",\"angry\"]') AS e,"
        "       json_each('[1,2]') AS k;"
        "CREATE VIRTUAL TABLE idx USING laban(content=corpus, motion=m, label=emotion);"
        "CREATE TABLE agg_rows AS SELECT id, m, emotion AS label, action AS grp,"
        "       laban_weight(m) AS x, laban_time(m) AS y, '" HMM_OPT "' AS hmm_opt,"
        "       '" CLS_OPT "' AS cls_opt, '" CV_OPT "' AS cv_opt, laban_vector(m) AS vec,"
        "       '" STR_OPT "' AS str_opt, '{\"order\":[\"sad\",\"angry\"]}' AS rank_opt,"
        "       '" FDA_OPT "' AS fda_opt FROM corpus ORDER BY id;"
        "CREATE TABLE empty_t(m, label);");
    build_pool(fixtures);
    /* every pool value as a row (for joins), and as the content of an index */
    exec_or_die("CREATE TABLE pool_t(v); CREATE TABLE junk(id INTEGER PRIMARY KEY, motion, label)");
    {
        sqlite3_stmt *a = prepare_or_die("INSERT INTO pool_t(v) VALUES(?1)");
        sqlite3_stmt *j = prepare_or_die("INSERT INTO junk(motion, label) VALUES(?1, ?2)");
        for (int k = 0; k < n_pool; k++) {
            if (pool[k].zero || pool[k].n > 100000)
                continue;
            bind_value(a, 1, &pool[k]);
            bind_value(j, 1, &pool[k]);
            bind_value(j, 2, &pool[(k * 7 + 3) % n_pool]);
            if (sqlite3_step(a) != SQLITE_DONE || sqlite3_step(j) != SQLITE_DONE)
                die("cannot fill pool_t: %s", sqlite3_errmsg(db));
            sqlite3_reset(a);
            sqlite3_reset(j);
        }
        sqlite3_finalize(a);
        sqlite3_finalize(j);
    }
    int n_lite = 0;
    for (int k = 0; k < n_pool; k++)
        n_lite += pool[k].lite;
    printf("test_sweep: %d functions in %d forms, %d table-valued functions, the laban virtual "
           "table; a pool of %d values (short pool %d); seed %llu\n",
           n_names, n_forms, n_tables, n_pool, n_lite, seed);
    fflush(stdout);
    double t_setup = now();

    const char *only = getenv("AFFECT_SWEEP_ONLY");
    long calls[3] = {0, 0, 0};
    for (int i = 0; i < n_forms; i++) {
        if (only && !listed(only, forms[i].name))
            continue;
        double t0 = cpu();
        long c0 = total.calls;
        sweep_form(forms, &forms[i]);
        if (forms[i].kind == TABLE && forms[i].n_arg == 1)
            sweep_table_shapes(&forms[i]);
        calls[forms[i].kind == TABLE] += total.calls - c0;
        if (verbose || cpu() - t0 > 2)
            fprintf(stderr, "  %s/%d: %ld calls, %.1f s of CPU\n", forms[i].name, forms[i].n_arg,
                    total.calls - c0, cpu() - t0);
    }
    double t_functions = now();
    long c0 = total.calls;
    if (!only || listed(only, "laban"))
        sweep_laban();
    calls[2] = total.calls - c0;
    double t_laban = now();

    printf("test_sweep: %ld calls (%ld of functions, %ld of table-valued functions, %ld on the "
           "laban table): %ld results, %ld errors naming the function, %ld failures\n",
           total.calls, calls[0], calls[1], calls[2], total.results, total.errors - total.failures,
           total.failures);
    printf(
        "test_sweep: %ld calls skipped by slow functions (short pool), %ld random calls skipped by "
        "the time budget; %ld error messages and %ld text results not valid UTF-8\n",
        total.skipped, n_random_skipped, total.bad_utf8_messages, total.bad_utf8_results);
    for (int i = 0; i < 64 && utf8_notes[i].n; i++)
        printf("test_sweep: not UTF-8: %ld texts from %s\n", utf8_notes[i].n, utf8_notes[i].name);
    printf("test_sweep: setup %.1f s, functions %.1f s, laban table %.1f s (%.1f s of CPU in "
           "all); slowest call %.2f s: %.300s\n",
           t_setup - start, t_functions - t_setup, t_laban - t_functions, cpu(), slowest,
           slowest_call);

    for (int i = 0; i < n_forms; i++)
        free(forms[i].name);
    free(forms);
    for (int k = 0; k < n_pool; k++) {
        free(pool[k].label);
        free(pool[k].bytes);
    }
    snprintf(current_call, sizeof current_call, "(closing the connection)");
    if (sqlite3_close(db) != SQLITE_OK)
        die("cannot close the connection: %s", sqlite3_errmsg(db));
    return total.failures ? 1 : 0;
}
