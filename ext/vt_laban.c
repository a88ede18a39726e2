/*
 * vt_laban.c — laban, a virtual table that keeps the 27 Laban descriptors of every motion of a
 * table and finds the motions nearest to a query (the neighbourhoods of SCIENCE.md §5 step 4).
 *
 *   CREATE VIRTUAL TABLE motion_laban USING laban(content=motions, motion=motion, label=emotion);
 *   SELECT rowid, label, WeightAll, TimeAll FROM motion_laban;             -- cached descriptors
 *   SELECT rowid, label, distance FROM motion_laban
 *    WHERE query = :m AND label = 'angry' AND k = 5;                       -- 5 nearest angry
 *   SELECT rowid, distance FROM motion_laban
 *    WHERE query = 12 AND label = 'sad' AND radius = 0.1;                  -- ε-ball around row 12
 *   SELECT rowid, distance FROM motion_laban
 *    WHERE query = :m AND k = 3 AND components = '["TimeAll","FlowAll"]';
 *   INSERT INTO motion_laban(motion_laban) VALUES('rebuild');              -- after content changes
 *
 * Arguments, key=value, each at most once; a value is a bare word or '…' / "…" quoted:
 *   content   the table holding the motions, in the same database as the index (required)
 *   motion    its column of motion BLOBs (default motion)
 *   label     its column of labels (default label)
 *   options   a JSON object of Laban options (see affect/laban.h): cutoff_hz (6),
 *             hull ("convex" | "box"), speed_floor (0.05), max_ratio (100), up ("x"|"y"|"z"),
 *             per_second (false); a component that cannot be computed (a role the skeleton lacks,
 *             too few frames) is missing (NULL) rather than an error.
 * CREATE checks that the content table and both columns exist, then indexes every row.
 *
 * The equivalent schema (rowid = the content row's rowid):
 *   CREATE TABLE motion_laban(label, WeightAll REAL, WeightTorso REAL, …, ShapeDirRHand REAL,
 *       distance REAL HIDDEN, query HIDDEN, k HIDDEN, radius HIDDEN, components HIDDEN,
 *       motion_laban HIDDEN);
 * The 27 components are in laban_names() order; the last hidden column carries the table's
 * own name and is only written, to give commands (as in FTS5).
 *
 * How it works. External content, like FTS5: the index reads
 *   SELECT rowid, <label>, <motion> FROM <content>
 * computes each motion's Laban vector once (roles resolved from the joint names) and keeps it in
 * two shadow tables:
 *   <name>_data(id INTEGER PRIMARY KEY, label, vector BLOB, msize INTEGER, mhash INTEGER)
 *       vector: 27 little-endian float32, the sqlite-vec convention (a missing component is NaN,
 *       bits 0x7fc00000); msize: the motion BLOB's length; mhash: 64-bit FNV-1a of its bytes
 *       (as a signed integer), for the stale check. A row whose motion is NULL is not indexed.
 *   <name>_info(key TEXT PRIMARY KEY, value)
 *       format ('1'), content, motion, label, options (normalized JSON: every option with its
 *       value), generation (bumped by every write), rows (indexed rows), mean and sd (JSON arrays
 *       of 27 numbers in component order: sd is the divisor used, see below; a mean is null
 *       where the component is missing in every row), stats_generation (the generation that
 *       mean and sd describe: it lags behind generation while a transaction that changed the
 *       index has not committed; ax_laban_stats_read, behind laban_zvector, refuses them then).
 * Standardization: z = (x − mean) / sd per component over the indexed rows, skipping missing
 * values; sd is the sample standard deviation (n − 1), and 1 where it is 0 or undefined (fewer
 * than two values) (affect_laban_stats, core/src/laban_std.c, which also gives laban_zvector
 * the vectors whose plain L2 distances are these distances, for sqlite-vec's vec0). mean and sd are
 * recomputed when a transaction that changed the index commits (xSync), so a transaction of many
 * per-row 'refresh' commands pays for them once; queries always standardize with the statistics of
 * the rows they see. Distance: Euclidean over the chosen components (default all 27) of the
 * standardized vectors; a component missing in either vector is skipped, and a row that shares no
 * component with the query is not a candidate. Ties are broken by rowid ascending, so results are
 * deterministic. The arithmetic is the core's (affect_laban_standardize, affect_laban_search_run
 * in core/src/laban_search.c: the distance, the k-nearest heap, the ε-ball, the tie rule); this
 * file feeds it the cached rows and the constraints. Each connection caches the vectors (raw and
 * standardized) in memory, keyed by the generation in _info: a query re-reads one _info row and
 * reloads the cache only when the index changed (here or in another connection); a rollback drops
 * the cache. Cursors hold a reference to the cache they started with, so a write during a scan
 * cannot pull it from under them.
 *
 * Queries. xBestIndex uses these equality constraints; idxNum says which are present, and they
 * are passed to xFilter in this order:
 *   bit  1  query = ?        a motion BLOB (its vector is computed with the index's options), or
 *                            an INTEGER rowid of an indexed row (its cached vector; that row is
 *                            left out of the results). NULL gives no rows.
 *   bit  2  label = ?        only rows whose label equals it: numbers numerically, text and BLOBs
 *                            byte for byte, never across types; NULL labels never match.
 *   bit  4  k = ?            the k nearest (an integer ≥ 1); fewer when there are fewer rows
 *   bit  8  radius = ?       r in (0, 1]: every candidate within r × the distance from the query
 *                            to the furthest candidate (ε = 10 % in the thesis is r = 0.1); at
 *                            least the nearest one even when that ball is empty. Over all 27
 *                            components distances crowd together (the sad motions of the test
 *                            corpus lie 4.2 to 5.0 from an angry one), so the thesis's small
 *                            radii are meant for its component subsets: use components.
 *   bit 16  components = ?   a JSON array of component names (default: all 27)
 *   bit 32  rowid = ?        only that row ('7' and 7.0 name row 7, as for any rowid)
 * With bit 1 exactly one of bits 4 and 8 is required; bits 4, 8 and 16 need bit 1. Rows come
 * by distance ascending (then rowid), and ORDER BY distance [, rowid] is consumed. Without bit 1
 * the cached rows come in rowid order (ORDER BY rowid is consumed) and distance is NULL.
 * A constraint on query, k, radius or components that is not usable gives SQLITE_CONSTRAINT so
 * SQLite tries another plan; a usable but incomplete combination is an error naming what is
 * missing.
 *
 * Writes are commands only, as in FTS5:
 *   INSERT INTO motion_laban(motion_laban) VALUES('rebuild');              -- everything again
 *   INSERT INTO motion_laban(motion_laban, rowid) VALUES('refresh', 12);   -- one row (removed
 *                                  -- when the content row is gone or its motion is NULL; a row
 *                                  -- whose motion is byte-identical only gets its label updated)
 *   INSERT INTO motion_laban(motion_laban, rowid) VALUES('delete', 12);
 *   INSERT INTO motion_laban(motion_laban) VALUES('check');  -- fails if anything is wrong
 * Stale handling: the index does not watch the content table. 'check' compares every indexed
 * row with it (rows present, motion length and FNV-1a hash, label) and names the first stale
 * rowid; 'rebuild' fixes everything; sql/laban_triggers.sql installs triggers that issue
 * 'refresh' and 'delete' so the index follows each change.
 * Corruption: a stored vector is sound when it is a BLOB of 27 × 4 bytes whose every component
 * is a finite number >= 0 (every Laban component is a magnitude) or the missing marker (NaN,
 * bits 0x7fc00000 exactly). 'check' validates every stored vector first, then the staleness,
 * then every cache entry of _info (ax_laban_cache_put; each kind checked by the validator
 * registered with the module, e.g. the RMLR fit must decode and fit the index's shape), and
 * names the first rowid or entry that is wrong. Every reader of the vectors (queries, scans,
 * ax_laban_read) refuses a corrupt one: "stored vector of rowid 17 is corrupt (1 bytes,
 * expected 108); run INSERT INTO …('rebuild')".
 *
 * Which tables are indexes. Other files read an index only through vt_laban.h (ax_laban_read,
 * ax_laban_stats_read, ax_laban_label_of, ax_laban_cache_get/put). Those that take an index by
 * name recognize one by its module: sqlite_schema's statement read token by token
 * (lab_is_laban_def: CREATE VIRTUAL TABLE <name> USING laban), then _info's format, which must
 * be '1' ("g_info has format "2"; this version reads format 1 (index "g")").
 *
 * Trust. The table reads another table (of its own database only, so a schema cannot use it
 * to reach an attached database) and writes only its shadow tables. It is not marked
 * SQLITE_VTAB_DIRECTONLY, although reading other tables makes it direct-only in spirit: that
 * flag forbids any use from triggers, and the 'refresh'/'delete' triggers are how an index stays
 * current. It is not SQLITE_VTAB_INNOCUOUS either: with the hardened PRAGMA trusted_schema=OFF
 * SQLite refuses it in triggers and views (DIRECTONLY would refuse it there always).
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "vt_laban.h"

#include "affect/laban.h"
#include "affect/strbuf.h"

#define LAB_N AFFECT_LABAN_N
#define LAB_VECTOR_BYTES (LAB_N * 4)
#define LAB_FORMAT "1"

enum {
    COL_LABEL = 0,
    COL_COMP0 = 1, /* the 27 components */
    COL_DISTANCE = COL_COMP0 + LAB_N,
    COL_QUERY,
    COL_K,
    COL_RADIUS,
    COL_COMPONENTS,
    COL_COMMAND /* named after the table */
};

/* idxNum bits, in argv order (see the header). */
enum {
    IDX_QUERY = 1,
    IDX_LABEL = 2,
    IDX_K = 4,
    IDX_RADIUS = 8,
    IDX_COMPONENTS = 16,
    IDX_ROWID = 32
};
#define IDX_BITS 6

/* The cached rows of one generation of the index; shared by the table and its cursors. */
typedef struct lab_cache {
    int refs;
    sqlite3_int64 generation;
    size_t n, cap;
    int64_t *ids;           /* ascending */
    int32_t *label;         /* per row: index into labels, −1 for a NULL label */
    float *raw;             /* n × LAB_N, NaN where missing */
    double *z;              /* n × LAB_N standardized */
    sqlite3_value **labels; /* distinct labels (slots may be NULL) */
    size_t n_labels;
    double mean[LAB_N], sd[LAB_N];
} lab_cache;

typedef struct lab_vtab {
    sqlite3_vtab base;
    sqlite3 *db;
    char *schema, *name; /* where the index lives */
    char *content, *motion, *label;
    char *options_json; /* normalized */
    affect_laban_options opt;
    lab_cache *cache;
    bool dirty;                        /* _info statistics are out of date until xSync */
    const ax_laban_cache_kind *caches; /* the module's aux: what 'check' validates in _info */
} lab_vtab;

typedef struct lab_cursor {
    sqlite3_vtab_cursor base;
    lab_cache *cache;
    bool knn;
    /* scan: rows [pos, end) whose label passes */
    size_t pos, end;
    unsigned char *label_ok; /* per distinct label; NULL = no label filter */
    /* KNN */
    affect_laban_hit *hits;
    size_t n_hits, hit;
    sqlite3_value *args[4]; /* query, k, radius, components, for their hidden columns */
} lab_cursor;

/* ---- errors: every message through ax_error_into (common.c), prefixed "laban: " ---- */

/* The error of a failed SQLite call on db (out of memory stays SQLITE_NOMEM). */
static int lab_db_error(char **dst, sqlite3 *db, int rc)
{
    if ((rc & 0xff) == SQLITE_NOMEM)
        return SQLITE_NOMEM;
    int code = ax_error_into(dst, NULL, "laban: %s", sqlite3_errmsg(db));
    return code != SQLITE_NOMEM && (rc & 0xff) == SQLITE_INTERRUPT ? SQLITE_INTERRUPT : code;
}

/* "laban: interrupted" with SQLITE_INTERRUPT, as lab_db_error reports an interrupted statement
 * of the index. */
static int lab_interrupted(char **dst)
{
    int code = ax_error_into(dst, NULL, "laban: interrupted");
    return code == SQLITE_NOMEM ? code : SQLITE_INTERRUPT;
}

/* A core error: out of memory becomes SQLITE_NOMEM, an interrupt lab_interrupted, anything else
 * "laban: <prefix><msg>". */
static int lab_core_error(char **dst, const affect_error *err, const char *prefix)
{
    if (err->status == AFFECT_ERR_NOMEM)
        return SQLITE_NOMEM;
    if (err->status == AFFECT_ERR_INTERRUPTED)
        return lab_interrupted(dst);
    return ax_error_into(dst, NULL, "laban: %s%s", prefix, err->msg);
}

/* A value for a message: the number itself, or the name of its type. */
static const char *lab_value_desc(sqlite3_value *v, char *buf, int size)
{
    switch (sqlite3_value_type(v)) {
    case SQLITE_INTEGER:
        return sqlite3_snprintf(size, buf, "%lld", sqlite3_value_int64(v));
    case SQLITE_FLOAT:
        return sqlite3_snprintf(size, buf, "%.15g", sqlite3_value_double(v));
    default:
        return ax_type_name(v);
    }
}

/* ---- SQL helpers ---- */

static int lab_prepare(sqlite3 *db, char **err, sqlite3_stmt **st, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    char *sql = sqlite3_vmprintf(fmt, ap);
    va_end(ap);
    *st = NULL;
    if (!sql)
        return SQLITE_NOMEM;
    int rc = sqlite3_prepare_v2(db, sql, -1, st, NULL);
    sqlite3_free(sql);
    if (rc != SQLITE_OK) {
        sqlite3_finalize(*st);
        *st = NULL;
        return lab_db_error(err, db, rc);
    }
    return SQLITE_OK;
}

/* Steps a statement to its end and resets it. */
static int lab_step_done(sqlite3 *db, char **err, sqlite3_stmt *st)
{
    int rc = sqlite3_step(st);
    if (rc == SQLITE_DONE || rc == SQLITE_ROW)
        rc = SQLITE_OK;
    else
        rc = lab_db_error(err, db, rc);
    sqlite3_reset(st);
    return rc;
}

/* Runs one statement with no parameters. */
static int lab_exec(sqlite3 *db, char **err, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    char *sql = sqlite3_vmprintf(fmt, ap);
    va_end(ap);
    if (!sql)
        return SQLITE_NOMEM;
    sqlite3_stmt *st = NULL;
    int rc = sqlite3_prepare_v2(db, sql, -1, &st, NULL);
    sqlite3_free(sql);
    if (rc != SQLITE_OK)
        rc = lab_db_error(err, db, rc);
    else
        rc = lab_step_done(db, err, st);
    sqlite3_finalize(st);
    return rc;
}

/* ---- vectors and hashes ---- */

/* The bits of the missing marker, a quiet NaN. */
#define LAB_MISSING_BITS 0x7fc00000u

/* Whether a stored vector (a value of _data's vector column: its type, bytes and length) is
 * corrupt, and then what is wrong in why: not a BLOB, not LAB_VECTOR_BYTES long, or a
 * component that is neither a finite number >= 0 (every component is a magnitude; -0 is
 * accepted) nor the missing marker. p may be NULL only when n is 0. */
static bool lab_vector_corrupt(int type, const unsigned char *p, int n, char *why, int size)
{
    static const char *const types[] = {"", "integer", "real", "text", "blob", "null"};
    if (type != SQLITE_BLOB) {
        sqlite3_snprintf(size, why, "%s, expected a BLOB of %d bytes",
                         types[type >= 1 && type <= 5 ? type : 5], LAB_VECTOR_BYTES);
        return true;
    }
    if (n != LAB_VECTOR_BYTES) {
        sqlite3_snprintf(size, why, "%d bytes, expected %d", n, LAB_VECTOR_BYTES);
        return true;
    }
    for (int j = 0; j < LAB_N; j++) {
        const unsigned char *b = p + 4 * j;
        uint32_t bits =
            (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
        float f = ax_get_f32(b);
        if (bits == LAB_MISSING_BITS || (isfinite(f) && f >= 0))
            continue;
        char what[40];
        if (isnan(f))
            sqlite3_snprintf(sizeof what, what, "NaN 0x%08x", bits);
        else if (isinf(f))
            sqlite3_snprintf(sizeof what, what, "%s", f > 0 ? "inf" : "-inf");
        else
            sqlite3_snprintf(sizeof what, what, "%.9g", (double)f);
        sqlite3_snprintf(size, why,
                         "%s is %s, expected a finite number >= 0 or NaN 0x%08x for "
                         "missing",
                         affect_laban_names[j], what, LAB_MISSING_BITS);
        return true;
    }
    return false;
}

/* An index name for a message: as is when it is a plain identifier, else quoted;
 * sqlite3_free it (NULL: out of memory). */
static char *lab_ident(const char *name)
{
    bool plain = (name[0] < '0' || name[0] > '9') &&
                 strspn(name, "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                              "0123456789_") == strlen(name);
    return sqlite3_mprintf(plain ? "%s" : "\"%w\"", name);
}

/* "stored vector of rowid 17 is corrupt (1 bytes, expected 108); run INSERT INTO g(g)
 * VALUES('rebuild')", with prefix in front (and ", and N more are" after the parenthesis when
 * more > 0); NULL when out of memory. */
static char *lab_corrupt_message(const char *prefix, const char *name, sqlite3_int64 id,
                                 const char *why, sqlite3_int64 more)
{
    char *ident = lab_ident(name);
    char others[48] = "";
    if (more > 0)
        sqlite3_snprintf(sizeof others, others, ", and %lld more %s", more,
                         more == 1 ? "is" : "are");
    char *msg = ident ? sqlite3_mprintf("%sstored vector of rowid %lld is corrupt (%s)%s; run "
                                        "INSERT INTO %s(%s) VALUES('rebuild')",
                                        prefix, id, why, others, ident, ident)
                      : NULL;
    sqlite3_free(ident);
    return msg;
}

/* 64-bit FNV-1a, stored as the signed integer with the same bits. */
static sqlite3_int64 lab_fnv1a(const unsigned char *p, size_t n)
{
    uint64_t h = 14695981039346656037u;
    for (size_t i = 0; i < n; i++) {
        h ^= p[i];
        h *= 1099511628211u;
    }
    return h <= (uint64_t)INT64_MAX ? (sqlite3_int64)h : -(sqlite3_int64)(UINT64_MAX - h) - 1;
}

/* The Laban vector of a motion BLOB with the index's options, rounded to float32. *bad_blob
 * says the BLOB itself is invalid. */
static affect_status lab_vector(const lab_vtab *vt, const unsigned char *data, size_t n,
                                float out[LAB_N], bool *bad_blob, affect_error *err)
{
    affect_motion *m = NULL;
    *bad_blob = false;
    ax_monitor am; /* a long motion stops on the statement's interrupt */
    char *msg = NULL;
    if (ax_monitor_begin_db(&am, vt->db, NULL, &msg) != SQLITE_OK) { /* no progress function */
        sqlite3_free(msg);
        return affect_nomem(err);
    }
    affect_status st = affect_motion_decode_monitored(data, n, &am.mon, &m, err);
    if (st) {
        ax_monitor_end(&am);
        *bad_blob = st != AFFECT_ERR_NOMEM && st != AFFECT_ERR_INTERRUPTED;
        return st;
    }
    affect_roles roles;
    affect_roles_resolve(m, &roles);
    double v[LAB_N];
    affect_laban_options opt = vt->opt;
    opt.monitor = &am.mon;
    st = affect_laban_vector(m, &roles, &opt, v, err);
    ax_monitor_end(&am);
    affect_motion_free(m);
    if (!st)
        for (int i = 0; i < LAB_N; i++)
            out[i] = affect_laban_f32(v[i]);
    return st;
}

/* ---- label comparison ---- */

/* Bytes of a text or BLOB value; NULL with *n > 0 when out of memory. */
static const void *lab_bytes(sqlite3_value *v, int *n)
{
    const void *p = sqlite3_value_type(v) == SQLITE_TEXT ? (const void *)sqlite3_value_text(v)
                                                         : sqlite3_value_blob(v);
    *n = sqlite3_value_bytes(v);
    return p;
}

/* 1 if two non-NULL values are equal for label = ? (numbers numerically, text and BLOBs byte
 * for byte, never across types), 0 if not, −1 when out of memory. With exact, numbers must
 * also have the same type (the stale check). */
static int lab_value_equal(sqlite3_value *a, sqlite3_value *b, bool exact)
{
    int ta = sqlite3_value_type(a), tb = sqlite3_value_type(b);
    bool na = ta == SQLITE_INTEGER || ta == SQLITE_FLOAT;
    bool nb = tb == SQLITE_INTEGER || tb == SQLITE_FLOAT;
    if (na && nb && (ta == tb || !exact)) {
        if (ta == SQLITE_INTEGER && tb == SQLITE_INTEGER)
            return sqlite3_value_int64(a) == sqlite3_value_int64(b);
        if (ta == SQLITE_FLOAT && tb == SQLITE_FLOAT)
            return sqlite3_value_double(a) == sqlite3_value_double(b);
        sqlite3_int64 i = sqlite3_value_int64(ta == SQLITE_INTEGER ? a : b);
        double r = sqlite3_value_double(ta == SQLITE_FLOAT ? a : b);
        return r >= -9223372036854775808.0 && r < 9223372036854775808.0 &&
               (double)(sqlite3_int64)r == r && (sqlite3_int64)r == i;
    }
    if (ta != tb || ta == SQLITE_NULL)
        return 0;
    int la, lb;
    const void *pa = lab_bytes(a, &la), *pb = lab_bytes(b, &lb);
    if ((!pa && la > 0) || (!pb && lb > 0))
        return -1;
    return la == lb && (la == 0 || memcmp(pa, pb, (size_t)la) == 0);
}

/* ---- the cache ---- */

static void lab_cache_unref(lab_cache *c)
{
    if (!c || --c->refs > 0)
        return;
    for (size_t i = 0; i < c->n_labels; i++)
        sqlite3_value_free(c->labels[i]);
    sqlite3_free(c->labels);
    sqlite3_free(c->ids);
    sqlite3_free(c->label);
    sqlite3_free(c->raw);
    sqlite3_free(c->z);
    sqlite3_free(c);
}

static void lab_cache_drop(lab_vtab *vt)
{
    lab_cache_unref(vt->cache);
    vt->cache = NULL;
}

/* Room for one more row. */
static int lab_cache_grow(lab_cache *c)
{
    if (c->n < c->cap)
        return SQLITE_OK;
    size_t cap = c->cap ? 2 * c->cap : 64, b_ids, b_raw;
    if (!affect_mul_size(cap, sizeof *c->ids, &b_ids) ||
        !affect_mul_size(cap, LAB_N * sizeof *c->raw, &b_raw))
        return SQLITE_NOMEM;
    int64_t *ids = sqlite3_realloc64(c->ids, b_ids);
    if (!ids)
        return SQLITE_NOMEM;
    c->ids = ids;
    int32_t *label = sqlite3_realloc64(c->label, cap * sizeof *c->label);
    if (!label)
        return SQLITE_NOMEM;
    c->label = label;
    float *raw = sqlite3_realloc64(c->raw, b_raw);
    if (!raw)
        return SQLITE_NOMEM;
    c->raw = raw;
    c->cap = cap;
    return SQLITE_OK;
}

/* Keeps label value v as distinct label number rank − 1. */
static int lab_cache_label(lab_cache *c, sqlite3_int64 rank, sqlite3_value *v, int32_t *out)
{
    if (sqlite3_value_type(v) == SQLITE_NULL) {
        *out = -1;
        return SQLITE_OK;
    }
    if (rank < 1 || rank > INT32_MAX)
        return SQLITE_INTERNAL;
    size_t slot = (size_t)rank - 1;
    if (slot >= c->n_labels) {
        size_t n = slot + 1 > 2 * c->n_labels ? slot + 1 : 2 * c->n_labels, bytes;
        if (!affect_mul_size(n, sizeof *c->labels, &bytes))
            return SQLITE_NOMEM;
        sqlite3_value **labels = sqlite3_realloc64(c->labels, bytes);
        if (!labels)
            return SQLITE_NOMEM;
        memset(labels + c->n_labels, 0, (n - c->n_labels) * sizeof *labels);
        c->labels = labels;
        c->n_labels = n;
    }
    if (!c->labels[slot] && !(c->labels[slot] = sqlite3_value_dup(v)))
        return SQLITE_NOMEM;
    *out = (int32_t)slot;
    return SQLITE_OK;
}

/* mean and sd per component over the rows (missing values skipped; affect_laban_stats), then
 * z. */
static int lab_cache_standardize(lab_cache *c)
{
    affect_laban_stats(c->raw, c->n, c->mean, c->sd);
    size_t bytes;
    if (!affect_mul_size(c->n ? c->n : 1, LAB_N * sizeof *c->z, &bytes))
        return SQLITE_NOMEM;
    c->z = sqlite3_malloc64(bytes);
    if (!c->z)
        return SQLITE_NOMEM;
    affect_laban_standardize(c->raw, c->n, c->mean, c->sd, c->z);
    return SQLITE_OK;
}

/* Reads every indexed row of the given generation. */
static int lab_cache_load(lab_vtab *vt, sqlite3_int64 generation, char **err, lab_cache **out)
{
    sqlite3_stmt *st = NULL;
    lab_cache *c = sqlite3_malloc(sizeof *c);
    *out = NULL;
    if (!c)
        return SQLITE_NOMEM;
    memset(c, 0, sizeof *c);
    c->refs = 1;
    c->generation = generation;
    /* dense_rank numbers the distinct labels (by type, then value) */
    int rc = lab_prepare(vt->db, err, &st,
                         "SELECT id, label, vector, dense_rank() OVER (ORDER BY typeof(label), "
                         "label) FROM \"%w\".\"%w_data\" ORDER BY id",
                         vt->schema, vt->name);
    if (rc)
        goto done;
    while ((rc = sqlite3_step(st)) == SQLITE_ROW) {
        if ((rc = lab_cache_grow(c)) != SQLITE_OK)
            goto done;
        sqlite3_int64 id = sqlite3_column_int64(st, 0);
        int type = sqlite3_column_type(st, 2); /* before the conversions of column_blob */
        const unsigned char *vec = sqlite3_column_blob(st, 2);
        int bytes = sqlite3_column_bytes(st, 2);
        if (!vec && bytes > 0) {
            rc = SQLITE_NOMEM;
            goto done;
        }
        char why[160];
        if (lab_vector_corrupt(type, vec, bytes, why, sizeof why)) {
            char *msg = lab_corrupt_message("", vt->name, id, why, 0);
            rc = msg ? ax_error_into(err, NULL, "laban: %s", msg) : SQLITE_NOMEM;
            sqlite3_free(msg);
            goto done;
        }
        size_t i = c->n;
        rc = lab_cache_label(c, sqlite3_column_int64(st, 3), sqlite3_column_value(st, 1),
                             &c->label[i]);
        if (rc)
            goto done;
        c->ids[i] = id;
        for (int j = 0; j < LAB_N; j++)
            c->raw[i * LAB_N + j] = ax_get_f32(vec + 4 * j);
        c->n++;
    }
    if (rc != SQLITE_DONE) {
        rc = lab_db_error(err, vt->db, rc);
        goto done;
    }
    rc = lab_cache_standardize(c);
done:
    sqlite3_finalize(st);
    if (rc == SQLITE_OK)
        *out = c;
    else
        lab_cache_unref(c);
    return rc;
}

/* The index's generation; checks the format. */
static int lab_generation(lab_vtab *vt, char **err, sqlite3_int64 *out)
{
    sqlite3_stmt *st = NULL;
    int rc = lab_prepare(vt->db, err, &st,
                         "SELECT (SELECT value FROM \"%w\".\"%w_info\" WHERE key = 'format'), "
                         "(SELECT value FROM \"%w\".\"%w_info\" WHERE key = 'generation')",
                         vt->schema, vt->name, vt->schema, vt->name);
    if (rc)
        return rc;
    rc = sqlite3_step(st);
    if (rc != SQLITE_ROW) {
        rc = lab_db_error(err, vt->db, rc);
    } else {
        const unsigned char *format = sqlite3_column_text(st, 0);
        if (!format && sqlite3_column_type(st, 0) != SQLITE_NULL)
            rc = SQLITE_NOMEM;
        else if (!format || strcmp((const char *)format, LAB_FORMAT) != 0)
            rc = ax_error_into(
                err, NULL,
                "laban: %s_info has format %s%s%s; this version reads format " LAB_FORMAT, vt->name,
                format ? "\"" : "", format ? (const char *)format : "NULL", format ? "\"" : "");
        else {
            *out = sqlite3_column_int64(st, 1);
            rc = SQLITE_OK;
        }
    }
    sqlite3_finalize(st);
    return rc;
}

/* The cache of the current generation, loaded if needed (owned by vt). */
static int lab_cache_current(lab_vtab *vt, char **err, lab_cache **out)
{
    sqlite3_int64 gen = 0;
    int rc = lab_generation(vt, err, &gen);
    if (rc)
        return rc;
    if (!vt->cache || vt->cache->generation != gen) {
        lab_cache_drop(vt);
        rc = lab_cache_load(vt, gen, err, &vt->cache);
        if (rc)
            return rc;
    }
    *out = vt->cache;
    return SQLITE_OK;
}

/* Index of the row with that id, or −1. */
static ptrdiff_t lab_cache_find(const lab_cache *c, sqlite3_int64 id)
{
    size_t lo = 0, hi = c->n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (c->ids[mid] < id)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < c->n && c->ids[lo] == id ? (ptrdiff_t)lo : -1;
}

/* ---- constructor arguments ---- */

typedef struct lab_args {
    char *value[4]; /* content, motion, label, options; NULL when not given */
} lab_args;

static const char *const lab_keys[4] = {"content", "motion", "label", "options"};
enum { ARG_CONTENT, ARG_MOTION, ARG_LABEL, ARG_OPTIONS };

static void lab_args_free(lab_args *a)
{
    for (int i = 0; i < 4; i++)
        sqlite3_free(a->value[i]);
}

static bool lab_space(char c)
{
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v';
}

/* One "key=value" argument. */
static int lab_parse_arg(const char *arg, lab_args *a, char **err)
{
    const char *eq = strchr(arg, '=');
    if (!eq)
        return ax_error_into(err, NULL, "laban: expected key=value, got \"%s\"", arg);
    const char *k0 = arg, *k1 = eq;
    while (k0 < k1 && lab_space(*k0))
        k0++;
    while (k1 > k0 && lab_space(k1[-1]))
        k1--;
    int key = -1;
    for (int i = 0; i < 4 && key < 0; i++)
        if (strlen(lab_keys[i]) == (size_t)(k1 - k0) &&
            sqlite3_strnicmp(lab_keys[i], k0, (int)(k1 - k0)) == 0)
            key = i;
    if (key < 0)
        return ax_error_into(err, NULL,
                             "laban: unknown argument \"%.*s\" (expected content, motion, label, "
                             "options)",
                             (int)(k1 - k0), k0);
    if (a->value[key])
        return ax_error_into(err, NULL, "laban: duplicate argument \"%s\"", lab_keys[key]);
    const char *v0 = eq + 1, *v1 = eq + strlen(eq);
    while (v0 < v1 && lab_space(*v0))
        v0++;
    while (v1 > v0 && lab_space(v1[-1]))
        v1--;
    if (v0 == v1)
        return ax_error_into(err, NULL, "laban: argument \"%s\" needs a value", lab_keys[key]);
    char *out = sqlite3_malloc64((sqlite3_uint64)(v1 - v0) + 1);
    if (!out)
        return SQLITE_NOMEM;
    size_t n = 0;
    if (*v0 == '\'' || *v0 == '"') {
        char q = *v0;
        const char *p = v0 + 1;
        for (;;) {
            if (p >= v1) {
                sqlite3_free(out);
                return ax_error_into(err, NULL, "laban: argument \"%s\": unterminated quote",
                                     lab_keys[key]);
            }
            if (*p == q) {
                if (p + 1 < v1 && p[1] == q) {
                    out[n++] = q;
                    p += 2;
                    continue;
                }
                break;
            }
            out[n++] = *p++;
        }
        if (p + 1 != v1) {
            sqlite3_free(out);
            return ax_error_into(err, NULL,
                                 "laban: argument \"%s\": unexpected text after the closing quote",
                                 lab_keys[key]);
        }
    } else {
        memcpy(out, v0, (size_t)(v1 - v0));
        n = (size_t)(v1 - v0);
    }
    out[n] = '\0';
    if (n == 0 || (key != ARG_OPTIONS && strlen(out) != n)) {
        sqlite3_free(out);
        return ax_error_into(err, NULL, "laban: argument \"%s\" needs a value", lab_keys[key]);
    }
    a->value[key] = out;
    return SQLITE_OK;
}

/* A JSON member's key, quoted for a message. */
static const char *lab_quote_key(const affect_json_node *m, char *buf, size_t size)
{
    affect_json_quote(buf, size, m->key, m->key_len);
    return buf;
}

/* The options argument: fills vt->opt and the normalized JSON. */
static int lab_parse_options(lab_vtab *vt, const char *text, char **err)
{
    affect_laban_options *o = &vt->opt;
    affect_laban_options_default(o);
    o->missing_null = true;
    affect_json_doc *doc = NULL;
    int rc = SQLITE_OK;
    char q[80];
    if (text) {
        affect_error e;
        if (affect_json_parse(text, strlen(text), &doc, NULL, &e))
            return e.status == AFFECT_ERR_NOMEM
                       ? SQLITE_NOMEM
                       : ax_error_into(err, NULL, "laban: options are not valid JSON: %s", e.msg);
        const affect_json_node *root = affect_json_root(doc);
        if (root->type != AFFECT_JSON_OBJECT) {
            rc = ax_error_into(err, NULL, "laban: options must be a JSON object, got %s",
                               affect_json_type_name(root->type));
            goto done;
        }
        for (const affect_json_node *m = affect_json_first(doc, root); m;
             m = affect_json_next_sibling(doc, m)) {
            const char *k = m->key;
            bool number = m->type == AFFECT_JSON_NUMBER;
            if (!strcmp(k, "cutoff_hz") || !strcmp(k, "speed_floor") || !strcmp(k, "max_ratio")) {
                if (!number) {
                    rc = ax_error_into(err, NULL, "laban: option \"%s\" must be a number, got %s",
                                       k, affect_json_type_name(m->type));
                    goto done;
                }
                double v = m->num;
                if (!strcmp(k, "cutoff_hz") && !(v > 0 && isfinite(v)))
                    rc = ax_error_into(
                        err, NULL,
                        "laban: option \"cutoff_hz\" must be a positive number, got %.15g", v);
                else if (!strcmp(k, "speed_floor") && !(v >= 0 && v < 1))
                    rc = ax_error_into(
                        err, NULL, "laban: option \"speed_floor\" must be in [0, 1), got %.15g", v);
                else if (!strcmp(k, "max_ratio") && !(v >= 1 && isfinite(v)))
                    rc = ax_error_into(
                        err, NULL, "laban: option \"max_ratio\" must be at least 1, got %.15g", v);
                if (rc)
                    goto done;
                *(!strcmp(k, "cutoff_hz")     ? &o->cutoff_hz
                  : !strcmp(k, "speed_floor") ? &o->speed_floor
                                              : &o->max_ratio) = v;
            } else if (!strcmp(k, "hull")) {
                if (m->type == AFFECT_JSON_STRING && !strcmp(m->str, "convex"))
                    o->hull_box = false;
                else if (m->type == AFFECT_JSON_STRING && !strcmp(m->str, "box"))
                    o->hull_box = true;
                else {
                    if (m->type == AFFECT_JSON_STRING)
                        affect_json_quote(q, sizeof q, m->str, m->str_len);
                    rc = ax_error_into(
                        err, NULL, "laban: option \"hull\" must be \"convex\" or \"box\", got %s",
                        m->type == AFFECT_JSON_STRING ? q : affect_json_type_name(m->type));
                    goto done;
                }
            } else if (!strcmp(k, "up")) {
                static const char *const axes[] = {"x", "y", "z"};
                int axis = -1;
                for (int i = 0; i < 3 && m->type == AFFECT_JSON_STRING; i++)
                    if (!strcmp(m->str, axes[i]))
                        axis = i;
                if (axis < 0) {
                    if (m->type == AFFECT_JSON_STRING)
                        affect_json_quote(q, sizeof q, m->str, m->str_len);
                    rc = ax_error_into(
                        err, NULL, "laban: option \"up\" must be \"x\", \"y\" or \"z\", got %s",
                        m->type == AFFECT_JSON_STRING ? q : affect_json_type_name(m->type));
                    goto done;
                }
                o->up_axis = axis;
            } else if (!strcmp(k, "per_second")) {
                if (m->type != AFFECT_JSON_TRUE && m->type != AFFECT_JSON_FALSE) {
                    rc = ax_error_into(err, NULL,
                                       "laban: option \"per_second\" must be true or false, got %s",
                                       affect_json_type_name(m->type));
                    goto done;
                }
                o->time_per_second = m->type == AFFECT_JSON_TRUE;
            } else {
                rc = ax_error_into(
                    err, NULL,
                    "laban: unknown option %s (expected cutoff_hz, hull, speed_floor, "
                    "max_ratio, up, per_second)",
                    lab_quote_key(m, q, sizeof q));
                goto done;
            }
        }
    }
    affect_strbuf sb;
    affect_strbuf_init(&sb);
    affect_strbuf_puts(&sb, "{\"cutoff_hz\":");
    affect_strbuf_double(&sb, o->cutoff_hz);
    affect_strbuf_puts(&sb, o->hull_box ? ",\"hull\":\"box\"" : ",\"hull\":\"convex\"");
    affect_strbuf_puts(&sb, ",\"speed_floor\":");
    affect_strbuf_double(&sb, o->speed_floor);
    affect_strbuf_puts(&sb, ",\"max_ratio\":");
    affect_strbuf_double(&sb, o->max_ratio);
    affect_strbuf_printf(&sb, ",\"up\":\"%c\"", "xyz"[o->up_axis]);
    affect_strbuf_puts(&sb,
                       o->time_per_second ? ",\"per_second\":true}" : ",\"per_second\":false}");
    size_t len;
    affect_error e;
    if (affect_strbuf_finish(&sb, &vt->options_json, &len, &e))
        rc = SQLITE_NOMEM;
done:
    affect_json_free(doc);
    return rc;
}

/* ---- construction ---- */

static void lab_free(lab_vtab *vt)
{
    if (!vt)
        return;
    lab_cache_drop(vt);
    sqlite3_free(vt->schema);
    sqlite3_free(vt->name);
    sqlite3_free(vt->content);
    sqlite3_free(vt->motion);
    sqlite3_free(vt->label);
    affect_free(vt->options_json);
    sqlite3_free(vt->base.zErrMsg);
    sqlite3_free(vt);
}

/* Every column name of the declared schema, for the name check. */
static bool lab_is_column_name(const char *name)
{
    static const char *const hidden[] = {"label",      "distance", "query", "k",      "radius",
                                         "components", "rowid",    "oid",   "_rowid_"};
    for (size_t i = 0; i < sizeof hidden / sizeof hidden[0]; i++)
        if (!sqlite3_stricmp(name, hidden[i]))
            return true;
    for (int i = 0; i < LAB_N; i++)
        if (!sqlite3_stricmp(name, affect_laban_names[i]))
            return true;
    return false;
}

/* Parses the arguments and declares the schema (shared by xCreate and xConnect). */
static int lab_init(sqlite3 *db, void *aux, int argc, const char *const *argv, lab_vtab **out,
                    char **err)
{
    lab_args a;
    memset(&a, 0, sizeof a);
    sqlite3_str *decl = NULL;
    int rc = SQLITE_NOMEM;
    lab_vtab *vt = sqlite3_malloc(sizeof *vt);
    *out = NULL;
    if (!vt)
        return SQLITE_NOMEM;
    memset(vt, 0, sizeof *vt);
    vt->db = db;
    vt->caches = aux;
    for (int i = 3; i < argc; i++)
        if ((rc = lab_parse_arg(argv[i], &a, err)) != SQLITE_OK)
            goto done;
    if (!a.value[ARG_CONTENT]) {
        rc = ax_error_into(err, NULL,
                           "laban: the content argument is required, as in CREATE VIRTUAL TABLE %s "
                           "USING laban(content=motions, motion=motion, label=emotion)",
                           argv[2]);
        goto done;
    }
    if (lab_is_column_name(argv[2])) {
        rc = ax_error_into(
            err, NULL, "laban: a laban table cannot be named \"%s\": that is one of its columns",
            argv[2]);
        goto done;
    }
    rc = SQLITE_NOMEM;
    vt->schema = sqlite3_mprintf("%s", argv[1]);
    vt->name = sqlite3_mprintf("%s", argv[2]);
    vt->content = sqlite3_mprintf("%s", a.value[ARG_CONTENT]);
    vt->motion = sqlite3_mprintf("%s", a.value[ARG_MOTION] ? a.value[ARG_MOTION] : "motion");
    vt->label = sqlite3_mprintf("%s", a.value[ARG_LABEL] ? a.value[ARG_LABEL] : "label");
    if (!vt->schema || !vt->name || !vt->content || !vt->motion || !vt->label)
        goto done;
    if ((rc = lab_parse_options(vt, a.value[ARG_OPTIONS], err)) != SQLITE_OK)
        goto done;

    decl = sqlite3_str_new(db);
    sqlite3_str_appendall(decl, "CREATE TABLE x(label");
    for (int i = 0; i < LAB_N; i++)
        sqlite3_str_appendf(decl, ", %s REAL", affect_laban_names[i]);
    sqlite3_str_appendf(decl,
                        ", distance REAL HIDDEN, query HIDDEN, k HIDDEN, radius HIDDEN, "
                        "components HIDDEN, \"%w\" HIDDEN)",
                        argv[2]);
    char *sql = sqlite3_str_finish(decl);
    decl = NULL;
    if (!sql) {
        rc = SQLITE_NOMEM;
        goto done;
    }
    rc = sqlite3_declare_vtab(db, sql);
    sqlite3_free(sql);
    if (rc != SQLITE_OK) {
        rc = lab_db_error(err, db, rc);
        goto done;
    }
    *out = vt;
    vt = NULL;
done:
    lab_args_free(&a);
    lab_free(vt);
    return rc;
}

/* The content table and both columns exist (and are not the index itself). */
static int lab_check_content(lab_vtab *vt, char **err)
{
    static const char *const suffixes[] = {"", "_data", "_info"};
    size_t n = strlen(vt->name);
    for (int i = 0; i < 3; i++)
        if (strlen(vt->content) == n + strlen(suffixes[i]) &&
            !sqlite3_strnicmp(vt->content, vt->name, (int)n) &&
            !sqlite3_stricmp(vt->content + n, suffixes[i]))
            return ax_error_into(
                err, NULL, "laban: the content table cannot be %s itself or its shadow tables",
                vt->name);
    sqlite3_stmt *st = NULL;
    int rc =
        lab_prepare(vt->db, err, &st, "PRAGMA \"%w\".table_xinfo(%Q)", vt->schema, vt->content);
    if (rc)
        return rc;
    bool any = false, motion = false, label = false;
    while ((rc = sqlite3_step(st)) == SQLITE_ROW) {
        const char *col = (const char *)sqlite3_column_text(st, 1);
        if (!col) {
            rc = SQLITE_NOMEM;
            goto done;
        }
        any = true;
        motion = motion || !sqlite3_stricmp(col, vt->motion);
        label = label || !sqlite3_stricmp(col, vt->label);
    }
    if (rc != SQLITE_DONE) {
        rc = lab_db_error(err, vt->db, rc);
        goto done;
    }
    if (!any)
        rc = ax_error_into(err, NULL, "laban: no such table: %s", vt->content);
    else if (!motion || !label)
        rc = ax_error_into(err, NULL, "laban: no column \"%s\" in table %s",
                           motion ? vt->label : vt->motion, vt->content);
    else
        rc = SQLITE_OK;
done:
    sqlite3_finalize(st);
    return rc;
}

/* Marks the index changed: a new generation, statistics due at commit, the cache dropped. */
static int lab_touch(lab_vtab *vt, char **err)
{
    lab_cache_drop(vt);
    vt->dirty = true;
    return lab_exec(vt->db, err,
                    "UPDATE \"%w\".\"%w_info\" SET value = value + 1 WHERE key = 'generation'",
                    vt->schema, vt->name);
}

/* Writes rows, mean and sd of the current rows into _info, with the generation they describe
 * (stats_generation: readers of the statistics, ax_laban_stats_read, refuse them while a
 * transaction has changed the index and not yet committed). */
static int lab_flush_stats(lab_vtab *vt, char **err)
{
    lab_cache *c = NULL;
    sqlite3_stmt *st = NULL;
    char *mean = NULL, *sd = NULL;
    int rc = lab_cache_current(vt, err, &c);
    if (rc)
        return rc;
    affect_strbuf a, b;
    affect_strbuf_init(&a);
    affect_strbuf_init(&b);
    for (int j = 0; j < LAB_N; j++) {
        affect_strbuf_putc(&a, j ? ',' : '[');
        affect_strbuf_double(&a, c->mean[j]); /* NaN → null */
        affect_strbuf_putc(&b, j ? ',' : '[');
        affect_strbuf_double(&b, c->sd[j]);
    }
    affect_strbuf_putc(&a, ']');
    affect_strbuf_putc(&b, ']');
    size_t la, lb;
    affect_error e;
    bool fa = affect_strbuf_finish(&a, &mean, &la, &e) != AFFECT_OK;
    bool fb = affect_strbuf_finish(&b, &sd, &lb, &e) != AFFECT_OK;
    if (fa || fb) {
        rc = SQLITE_NOMEM;
        goto done;
    }
    rc = lab_prepare(vt->db, err, &st,
                     "INSERT OR REPLACE INTO \"%w\".\"%w_info\"(key, value) "
                     "VALUES('rows', ?1), ('mean', ?2), ('sd', ?3), ('stats_generation', ?4)",
                     vt->schema, vt->name);
    if (rc)
        goto done;
    if ((rc = sqlite3_bind_int64(st, 1, (sqlite3_int64)c->n)) != SQLITE_OK ||
        (rc = sqlite3_bind_text(st, 2, mean, (int)la, SQLITE_STATIC)) != SQLITE_OK ||
        (rc = sqlite3_bind_text(st, 3, sd, (int)lb, SQLITE_STATIC)) != SQLITE_OK ||
        (rc = sqlite3_bind_int64(st, 4, c->generation)) != SQLITE_OK) {
        rc = lab_db_error(err, vt->db, rc);
        goto done;
    }
    rc = lab_step_done(vt->db, err, st);
    if (rc == SQLITE_OK)
        vt->dirty = false;
done:
    sqlite3_finalize(st);
    affect_free(mean);
    affect_free(sd);
    return rc;
}

/* Computes and stores one content row (ins: INSERT OR REPLACE into _data). A NULL motion is not
 * indexed. */
static int lab_store_row(lab_vtab *vt, sqlite3_stmt *ins, sqlite3_int64 id, sqlite3_value *label,
                         sqlite3_value *motion, char **err)
{
    int type = sqlite3_value_type(motion);
    if (type == SQLITE_NULL)
        return SQLITE_OK;
    if (type != SQLITE_BLOB)
        return ax_error_into(err, NULL, "laban: row %lld of %s: the motion must be a BLOB, got %s",
                             id, vt->content, ax_type_name(motion));
    const unsigned char *data = sqlite3_value_blob(motion);
    int n = sqlite3_value_bytes(motion);
    if (!data && n > 0)
        return SQLITE_NOMEM;
    float v[LAB_N];
    bool bad;
    affect_error e;
    if (lab_vector(vt, data, (size_t)n, v, &bad, &e)) {
        if (e.status == AFFECT_ERR_NOMEM)
            return SQLITE_NOMEM;
        if (e.status == AFFECT_ERR_INTERRUPTED)
            return lab_interrupted(err);
        return ax_error_into(err, NULL, "laban: row %lld of %s: %s%s", id, vt->content,
                             bad ? "not a valid motion: " : "", e.msg);
    }
    unsigned char blob[LAB_VECTOR_BYTES];
    for (int j = 0; j < LAB_N; j++)
        ax_put_f32(blob + 4 * j, v[j]);
    int rc;
    if ((rc = sqlite3_bind_int64(ins, 1, id)) != SQLITE_OK ||
        (rc = sqlite3_bind_value(ins, 2, label)) != SQLITE_OK ||
        (rc = sqlite3_bind_blob(ins, 3, blob, LAB_VECTOR_BYTES, SQLITE_STATIC)) != SQLITE_OK ||
        (rc = sqlite3_bind_int64(ins, 4, n)) != SQLITE_OK ||
        (rc = sqlite3_bind_int64(ins, 5, lab_fnv1a(data, (size_t)n))) != SQLITE_OK)
        return lab_db_error(err, vt->db, rc);
    return lab_step_done(vt->db, err, ins);
}

static int lab_prepare_insert(lab_vtab *vt, char **err, sqlite3_stmt **ins)
{
    return lab_prepare(vt->db, err, ins,
                       "INSERT OR REPLACE INTO \"%w\".\"%w_data\"(id, label, vector, msize, "
                       "mhash) VALUES(?1, ?2, ?3, ?4, ?5)",
                       vt->schema, vt->name);
}

/* 'rebuild': every content row again. */
static int lab_rebuild(lab_vtab *vt, char **err)
{
    sqlite3_stmt *sel = NULL, *ins = NULL;
    int rc = lab_exec(vt->db, err, "DELETE FROM \"%w\".\"%w_data\"", vt->schema, vt->name);
    if (rc)
        return rc;
    rc = lab_prepare(vt->db, err, &sel,
                     "SELECT rowid, \"%w\", \"%w\" FROM \"%w\".\"%w\" "
                     "ORDER BY rowid",
                     vt->label, vt->motion, vt->schema, vt->content);
    if (rc || (rc = lab_prepare_insert(vt, err, &ins)) != SQLITE_OK)
        goto done;
    while ((rc = sqlite3_step(sel)) == SQLITE_ROW) {
        rc = lab_store_row(vt, ins, sqlite3_column_int64(sel, 0), sqlite3_column_value(sel, 1),
                           sqlite3_column_value(sel, 2), err);
        if (rc)
            goto done;
    }
    rc = rc == SQLITE_DONE ? lab_touch(vt, err) : lab_db_error(err, vt->db, rc);
done:
    sqlite3_finalize(sel);
    sqlite3_finalize(ins);
    return rc;
}

/* 'refresh' (one row from the content table) and 'delete'. */
static int lab_refresh(lab_vtab *vt, sqlite3_int64 id, bool remove, char **err)
{
    sqlite3_stmt *sel = NULL, *old = NULL, *st = NULL;
    int rc = SQLITE_OK;
    if (!remove) {
        rc = lab_prepare(vt->db, err, &sel,
                         "SELECT \"%w\", \"%w\" FROM \"%w\".\"%w\" "
                         "WHERE rowid = ?1",
                         vt->label, vt->motion, vt->schema, vt->content);
        if (rc)
            goto done;
        if ((rc = sqlite3_bind_int64(sel, 1, id)) != SQLITE_OK) {
            rc = lab_db_error(err, vt->db, rc);
            goto done;
        }
        rc = sqlite3_step(sel);
        if (rc != SQLITE_ROW && rc != SQLITE_DONE) {
            rc = lab_db_error(err, vt->db, rc);
            goto done;
        }
        remove = rc == SQLITE_DONE || sqlite3_column_type(sel, 1) == SQLITE_NULL;
        rc = SQLITE_OK;
    }
    if (remove) {
        rc = lab_prepare(vt->db, err, &st, "DELETE FROM \"%w\".\"%w_data\" WHERE id = ?1",
                         vt->schema, vt->name);
        if (rc)
            goto done;
        if ((rc = sqlite3_bind_int64(st, 1, id)) != SQLITE_OK) {
            rc = lab_db_error(err, vt->db, rc);
            goto done;
        }
        if ((rc = lab_step_done(vt->db, err, st)) != SQLITE_OK)
            goto done;
        rc = sqlite3_changes(vt->db) ? lab_touch(vt, err) : SQLITE_OK;
        goto done;
    }
    /* the same motion bytes: only the label may have changed */
    sqlite3_value *motion = sqlite3_column_value(sel, 1);
    const unsigned char *data = sqlite3_value_blob(motion);
    int n = sqlite3_value_bytes(motion);
    if (!data && n > 0) {
        rc = SQLITE_NOMEM;
        goto done;
    }
    rc = lab_prepare(vt->db, err, &old,
                     "SELECT msize, mhash FROM \"%w\".\"%w_data\" "
                     "WHERE id = ?1",
                     vt->schema, vt->name);
    if (rc)
        goto done;
    if ((rc = sqlite3_bind_int64(old, 1, id)) != SQLITE_OK) {
        rc = lab_db_error(err, vt->db, rc);
        goto done;
    }
    rc = sqlite3_step(old);
    if (rc != SQLITE_ROW && rc != SQLITE_DONE) {
        rc = lab_db_error(err, vt->db, rc);
        goto done;
    }
    if (rc == SQLITE_ROW && sqlite3_value_type(motion) == SQLITE_BLOB &&
        sqlite3_column_int64(old, 0) == n &&
        sqlite3_column_int64(old, 1) == lab_fnv1a(data, (size_t)n)) {
        rc = lab_prepare(vt->db, err, &st,
                         "UPDATE \"%w\".\"%w_data\" SET label = ?2 "
                         "WHERE id = ?1",
                         vt->schema, vt->name);
        if (rc)
            goto done;
        if ((rc = sqlite3_bind_int64(st, 1, id)) != SQLITE_OK ||
            (rc = sqlite3_bind_value(st, 2, sqlite3_column_value(sel, 0))) != SQLITE_OK) {
            rc = lab_db_error(err, vt->db, rc);
            goto done;
        }
    } else {
        rc = lab_prepare_insert(vt, err, &st);
        if (rc || (rc = lab_store_row(vt, st, id, sqlite3_column_value(sel, 0), motion, err)))
            goto done;
        sqlite3_finalize(st);
        st = NULL;
    }
    if (st && (rc = lab_step_done(vt->db, err, st)) != SQLITE_OK)
        goto done;
    rc = lab_touch(vt, err);
done:
    sqlite3_finalize(sel);
    sqlite3_finalize(old);
    sqlite3_finalize(st);
    return rc;
}

static int lab_check_caches(lab_vtab *vt, char **err);

/* 'check': every stored vector sound, every indexed row current with the content table, every
 * cache entry sound (lab_check_caches), in that order; the first problem is the error. */
static int lab_check(lab_vtab *vt, char **err)
{
    sqlite3_stmt *cs = NULL, *is = NULL;
    int rc = lab_prepare(vt->db, err, &cs,
                         "SELECT rowid, \"%w\", \"%w\" FROM \"%w\".\"%w\" "
                         "WHERE \"%w\" IS NOT NULL ORDER BY rowid",
                         vt->label, vt->motion, vt->schema, vt->content, vt->motion);
    if (rc || (rc = lab_prepare(vt->db, err, &is,
                                "SELECT id, label, msize, mhash, vector FROM "
                                "\"%w\".\"%w_data\" ORDER BY id",
                                vt->schema, vt->name)) != SQLITE_OK)
        goto done;
    sqlite3_int64 stale = 0, first = 0, corrupt = 0, first_corrupt = 0;
    char why[160];
    int rc_c = sqlite3_step(cs), rc_i = sqlite3_step(is);
    while (rc_c == SQLITE_ROW || rc_i == SQLITE_ROW) {
        sqlite3_int64 cid = rc_c == SQLITE_ROW ? sqlite3_column_int64(cs, 0) : INT64_MAX;
        sqlite3_int64 iid = rc_i == SQLITE_ROW ? sqlite3_column_int64(is, 0) : INT64_MAX;
        bool ok = false;
        if (rc_c == SQLITE_ROW && rc_i == SQLITE_ROW && cid == iid) {
            sqlite3_value *motion = sqlite3_column_value(cs, 2);
            const unsigned char *data = sqlite3_value_blob(motion);
            int n = sqlite3_value_bytes(motion);
            if (!data && n > 0) {
                rc = SQLITE_NOMEM;
                goto done;
            }
            int same =
                lab_value_equal(sqlite3_column_value(cs, 1), sqlite3_column_value(is, 1), true);
            if (same < 0) {
                rc = SQLITE_NOMEM;
                goto done;
            }
            bool both_null = sqlite3_column_type(cs, 1) == SQLITE_NULL &&
                             sqlite3_column_type(is, 1) == SQLITE_NULL;
            ok = sqlite3_value_type(motion) == SQLITE_BLOB && sqlite3_column_int64(is, 2) == n &&
                 sqlite3_column_int64(is, 3) == lab_fnv1a(data, (size_t)n) && (same || both_null);
        }
        sqlite3_int64 id = cid < iid ? cid : iid;
        if (!ok && stale++ == 0)
            first = id;
        if (rc_i == SQLITE_ROW && iid == id) {
            int type = sqlite3_column_type(is, 4); /* before the conversions of column_blob */
            const unsigned char *vec = sqlite3_column_blob(is, 4);
            int bytes = sqlite3_column_bytes(is, 4);
            if (!vec && bytes > 0) {
                rc = SQLITE_NOMEM;
                goto done;
            }
            char w[sizeof why];
            if (lab_vector_corrupt(type, vec, bytes, w, sizeof w) && corrupt++ == 0) {
                first_corrupt = id;
                memcpy(why, w, sizeof why);
            }
        }
        if (rc_c == SQLITE_ROW && cid == id)
            rc_c = sqlite3_step(cs);
        if (rc_i == SQLITE_ROW && iid == id)
            rc_i = sqlite3_step(is);
    }
    if (rc_c != SQLITE_DONE || rc_i != SQLITE_DONE) {
        rc = lab_db_error(err, vt->db, rc_c != SQLITE_DONE ? rc_c : rc_i);
        goto done;
    }
    if (corrupt) {
        char *msg = lab_corrupt_message("", vt->name, first_corrupt, why, corrupt - 1);
        rc = msg ? ax_error_into(err, NULL, "laban: %s", msg) : SQLITE_NOMEM;
        sqlite3_free(msg);
    } else if (stale) {
        char *ident = lab_ident(vt->name);
        if (!ident) {
            rc = SQLITE_NOMEM;
            goto done;
        }
        rc = ax_error_into(err, NULL,
                           "laban: %lld %s stale (first: rowid %lld); run INSERT INTO %s(%s) "
                           "VALUES('rebuild')",
                           stale, stale == 1 ? "row is" : "rows are", first, ident, ident);
        sqlite3_free(ident);
    } else {
        rc = lab_check_caches(vt, err);
    }
done:
    sqlite3_finalize(cs);
    sqlite3_finalize(is);
    return rc;
}

static int lab_create(sqlite3 *db, void *aux, int argc, const char *const *argv, sqlite3_vtab **out,
                      char **err)
{
    lab_vtab *vt = NULL;
    sqlite3_stmt *st = NULL;
    int rc = lab_init(db, aux, argc, argv, &vt, err);
    if (rc)
        return rc;
    if ((rc = lab_check_content(vt, err)) != SQLITE_OK)
        goto done;
    rc = lab_exec(db, err,
                  "CREATE TABLE \"%w\".\"%w_data\"(id INTEGER PRIMARY KEY, label, "
                  "vector BLOB, msize INTEGER, mhash INTEGER)",
                  vt->schema, vt->name);
    if (rc || (rc = lab_exec(db, err,
                             "CREATE TABLE \"%w\".\"%w_info\"(key TEXT PRIMARY KEY, "
                             "value) WITHOUT ROWID",
                             vt->schema, vt->name)) != SQLITE_OK)
        goto done;
    rc = lab_prepare(db, err, &st,
                     "INSERT INTO \"%w\".\"%w_info\"(key, value) VALUES"
                     "('format', '" LAB_FORMAT "'), ('content', ?1), "
                     "('motion', ?2), ('label', ?3), ('options', ?4), "
                     "('generation', 0)",
                     vt->schema, vt->name);
    if (rc)
        goto done;
    if ((rc = sqlite3_bind_text(st, 1, vt->content, -1, SQLITE_STATIC)) != SQLITE_OK ||
        (rc = sqlite3_bind_text(st, 2, vt->motion, -1, SQLITE_STATIC)) != SQLITE_OK ||
        (rc = sqlite3_bind_text(st, 3, vt->label, -1, SQLITE_STATIC)) != SQLITE_OK ||
        (rc = sqlite3_bind_text(st, 4, vt->options_json, -1, SQLITE_STATIC)) != SQLITE_OK) {
        rc = lab_db_error(err, db, rc);
        goto done;
    }
    if ((rc = lab_step_done(db, err, st)) != SQLITE_OK || (rc = lab_rebuild(vt, err)) != SQLITE_OK)
        goto done;
    rc = lab_flush_stats(vt, err);
done:
    sqlite3_finalize(st);
    if (rc) {
        lab_free(vt);
        return rc;
    }
    *out = &vt->base;
    return SQLITE_OK;
}

static int lab_connect(sqlite3 *db, void *aux, int argc, const char *const *argv,
                       sqlite3_vtab **out, char **err)
{
    lab_vtab *vt = NULL;
    int rc = lab_init(db, aux, argc, argv, &vt, err);
    if (rc == SQLITE_OK)
        *out = &vt->base;
    return rc;
}

static int lab_disconnect(sqlite3_vtab *tab)
{
    lab_free((lab_vtab *)tab);
    return SQLITE_OK;
}

static int lab_destroy(sqlite3_vtab *tab)
{
    lab_vtab *vt = (lab_vtab *)tab;
    int rc = lab_exec(vt->db, &tab->zErrMsg, "DROP TABLE IF EXISTS \"%w\".\"%w_data\"", vt->schema,
                      vt->name);
    if (rc == SQLITE_OK)
        rc = lab_exec(vt->db, &tab->zErrMsg, "DROP TABLE IF EXISTS \"%w\".\"%w_info\"", vt->schema,
                      vt->name);
    if (rc == SQLITE_OK)
        lab_free(vt);
    return rc;
}

static int lab_rename(sqlite3_vtab *tab, const char *name)
{
    lab_vtab *vt = (lab_vtab *)tab;
    static const char *const suffix[] = {"_data", "_info"};
    if (lab_is_column_name(name)) /* it would not reconnect */
        return ax_vtab_error(tab, NULL,
                             "laban: a laban table cannot be named \"%s\": that is one of "
                             "its columns",
                             name);
    char *copy = sqlite3_mprintf("%s", name);
    if (!copy)
        return SQLITE_NOMEM;
    for (int i = 0; i < 2; i++) {
        int rc = lab_exec(vt->db, &tab->zErrMsg, "ALTER TABLE \"%w\".\"%w%s\" RENAME TO \"%w%s\"",
                          vt->schema, vt->name, suffix[i], name, suffix[i]);
        if (rc) {
            sqlite3_free(copy);
            return rc;
        }
    }
    sqlite3_free(vt->name);
    vt->name = copy;
    return SQLITE_OK;
}

static int lab_shadow_name(const char *suffix)
{
    return !sqlite3_stricmp(suffix, "data") || !sqlite3_stricmp(suffix, "info");
}

/* ---- transactions: statistics at commit, the cache dropped on rollback ---- */

static int lab_begin(sqlite3_vtab *tab)
{
    return SQLITE_OK;
}

static int lab_sync(sqlite3_vtab *tab)
{
    lab_vtab *vt = (lab_vtab *)tab;
    return vt->dirty ? lab_flush_stats(vt, &tab->zErrMsg) : SQLITE_OK;
}

static int lab_commit(sqlite3_vtab *tab)
{
    return SQLITE_OK;
}

static int lab_rollback(sqlite3_vtab *tab)
{
    lab_vtab *vt = (lab_vtab *)tab;
    vt->dirty = false;
    lab_cache_drop(vt);
    return SQLITE_OK;
}

static int lab_savepoint(sqlite3_vtab *tab, int i)
{
    return SQLITE_OK;
}

static int lab_rollback_to(sqlite3_vtab *tab, int i)
{
    lab_cache_drop((lab_vtab *)tab); /* generations may repeat after a rollback */
    return SQLITE_OK;
}

/* ---- writes: commands ---- */

static int lab_update(sqlite3_vtab *tab, int argc, sqlite3_value **argv, sqlite3_int64 *rowid)
{
    lab_vtab *vt = (lab_vtab *)tab;
    char **err = &tab->zErrMsg;
    if (argc == 1 || sqlite3_value_type(argv[0]) != SQLITE_NULL ||
        sqlite3_value_type(argv[2 + COL_COMMAND]) == SQLITE_NULL)
        return ax_error_into(err, NULL,
                             "laban: the index is read-only: change the content table and run "
                             "'rebuild', or install the triggers of sql/laban_triggers.sql");
    const char *cmd = (const char *)sqlite3_value_text(argv[2 + COL_COMMAND]);
    if (!cmd)
        return SQLITE_NOMEM;
    if (!strcmp(cmd, "rebuild"))
        return lab_rebuild(vt, err);
    if (!strcmp(cmd, "check"))
        return lab_check(vt, err);
    bool refresh = !strcmp(cmd, "refresh");
    if (refresh || !strcmp(cmd, "delete")) {
        sqlite3_value *id = argv[1];
        if (sqlite3_value_type(id) == SQLITE_NULL)
            return ax_error_into(err, NULL,
                                 "laban: '%s' needs a rowid, as in INSERT INTO %s(%s, rowid) "
                                 "VALUES('%s', 12)",
                                 cmd, vt->name, vt->name, cmd);
        if (sqlite3_value_type(id) != SQLITE_INTEGER) {
            char buf[40];
            return ax_error_into(err, NULL, "laban: the rowid of '%s' must be an integer, got %s",
                                 cmd, lab_value_desc(id, buf, sizeof buf));
        }
        return lab_refresh(vt, sqlite3_value_int64(id), !refresh, err);
    }
    return ax_error_into(
        err, NULL, "laban: unknown command \"%.40s\" (expected rebuild, refresh, delete, check)",
        cmd);
}

/* ---- planning ---- */

static int lab_best_index(sqlite3_vtab *tab, sqlite3_index_info *info)
{
    static const int cols[IDX_BITS] = {COL_QUERY, COL_LABEL, COL_K, COL_RADIUS, COL_COMPONENTS, -1};
    int use[IDX_BITS];
    bool seen[IDX_BITS];
    for (int b = 0; b < IDX_BITS; b++) {
        use[b] = -1;
        seen[b] = false;
    }
    for (int i = 0; i < info->nConstraint; i++) {
        const struct sqlite3_index_constraint *c = &info->aConstraint[i];
        if (c->op != SQLITE_INDEX_CONSTRAINT_EQ)
            continue;
        for (int b = 0; b < IDX_BITS; b++)
            if (c->iColumn == cols[b]) {
                seen[b] = true;
                if (c->usable && use[b] < 0)
                    use[b] = i;
            }
    }
    /* query, k, radius, components: present but not usable in this plan → another plan */
    static const int needed[] = {0, 2, 3, 4};
    for (int i = 0; i < 4; i++)
        if (seen[needed[i]] && use[needed[i]] < 0)
            return SQLITE_CONSTRAINT;
    bool q = use[0] >= 0, k = use[2] >= 0, r = use[3] >= 0, comp = use[4] >= 0;
    if (!q && (k || r || comp))
        return ax_vtab_error(tab, NULL, "laban: k, radius and components need a query constraint");
    if (q && k && r)
        return ax_vtab_error(tab, NULL, "laban: use either k or radius, not both");
    if (q && !k && !r)
        return ax_vtab_error(tab, NULL, "laban: a k or radius constraint is required for a query");
    int idx = 0, argi = 0;
    for (int b = 0; b < IDX_BITS; b++)
        if (use[b] >= 0) {
            idx |= 1 << b;
            info->aConstraintUsage[use[b]].argvIndex = ++argi;
            info->aConstraintUsage[use[b]].omit = 1;
        }
    info->idxNum = idx;
    const struct sqlite3_index_orderby *o = info->aOrderBy;
    if (q) {
        info->estimatedCost = 100.0;
        info->estimatedRows = 10;
        if ((info->nOrderBy == 1 || (info->nOrderBy == 2 && o[1].iColumn == -1 && !o[1].desc)) &&
            o[0].iColumn == COL_DISTANCE && !o[0].desc)
            info->orderByConsumed = 1;
    } else {
        if (idx & IDX_ROWID) {
            info->estimatedCost = 1.0;
            info->estimatedRows = 1;
            info->idxFlags = SQLITE_INDEX_SCAN_UNIQUE;
        } else {
            info->estimatedCost = idx & IDX_LABEL ? 2500.0 : 10000.0;
            info->estimatedRows = idx & IDX_LABEL ? 2500 : 10000;
        }
        if (info->nOrderBy == 1 && o[0].iColumn == -1 && !o[0].desc)
            info->orderByConsumed = 1;
    }
    return SQLITE_OK;
}

/* ---- cursors ---- */

static int lab_open(sqlite3_vtab *tab, sqlite3_vtab_cursor **out)
{
    lab_cursor *c = sqlite3_malloc(sizeof *c);
    if (!c)
        return SQLITE_NOMEM;
    memset(c, 0, sizeof *c);
    *out = &c->base;
    return SQLITE_OK;
}

static void lab_cursor_reset(lab_cursor *c)
{
    lab_cache_unref(c->cache);
    c->cache = NULL;
    sqlite3_free(c->label_ok);
    sqlite3_free(c->hits);
    for (int i = 0; i < 4; i++)
        sqlite3_value_free(c->args[i]);
    memset((char *)c + sizeof c->base, 0, sizeof *c - sizeof c->base);
}

static int lab_close(sqlite3_vtab_cursor *cur)
{
    lab_cursor_reset((lab_cursor *)cur);
    sqlite3_free(cur);
    return SQLITE_OK;
}

/* k: an integer ≥ 1 (an integral REAL is accepted). */
static int lab_arg_k(sqlite3_value *v, sqlite3_int64 *k, char **err)
{
    int t = sqlite3_value_type(v);
    double d = sqlite3_value_double(v);
    if (t == SQLITE_INTEGER)
        *k = sqlite3_value_int64(v);
    else if (t == SQLITE_FLOAT && d == floor(d) && fabs(d) < 9e15)
        *k = (sqlite3_int64)d;
    else
        *k = 0;
    if (*k >= 1)
        return SQLITE_OK;
    char buf[40];
    return ax_error_into(err, NULL, "laban: k must be a positive integer, got %s",
                         lab_value_desc(v, buf, sizeof buf));
}

static int lab_arg_radius(sqlite3_value *v, double *r, char **err)
{
    int t = sqlite3_value_type(v);
    *r = sqlite3_value_double(v);
    if ((t == SQLITE_INTEGER || t == SQLITE_FLOAT) && *r > 0 && *r <= 1)
        return SQLITE_OK;
    char buf[40];
    return ax_error_into(err, NULL, "laban: radius must be in (0, 1], got %s",
                         lab_value_desc(v, buf, sizeof buf));
}

/* components: a JSON array of distinct component names, or NULL (or absent) for all; out in
 * component order. */
static int lab_arg_components(sqlite3_value *v, int out[LAB_N], int *n, char **err)
{
    bool on[LAB_N] = {false};
    *n = 0;
    if (!v || sqlite3_value_type(v) == SQLITE_NULL) {
        for (int j = 0; j < LAB_N; j++)
            out[(*n)++] = j;
        return SQLITE_OK;
    }
    if (sqlite3_value_type(v) != SQLITE_TEXT)
        return ax_error_into(err, NULL,
                             "laban: components must be a JSON array of component names, got %s",
                             ax_type_name(v));
    const char *text = (const char *)sqlite3_value_text(v);
    if (!text)
        return SQLITE_NOMEM;
    affect_json_doc *doc = NULL;
    affect_error e;
    if (affect_json_parse(text, (size_t)sqlite3_value_bytes(v), &doc, NULL, &e))
        return e.status == AFFECT_ERR_NOMEM
                   ? SQLITE_NOMEM
                   : ax_error_into(err, NULL,
                                   "laban: components must be a JSON array of component names: %s",
                                   e.msg);
    int rc = SQLITE_OK;
    char q[80];
    const affect_json_node *root = affect_json_root(doc);
    if (root->type != AFFECT_JSON_ARRAY) {
        rc = ax_error_into(err, NULL,
                           "laban: components must be a JSON array of component names, got %s",
                           affect_json_type_name(root->type));
        goto done;
    }
    if (root->count == 0) {
        rc = ax_error_into(err, NULL, "laban: components must name at least one component");
        goto done;
    }
    for (const affect_json_node *m = affect_json_first(doc, root); m;
         m = affect_json_next_sibling(doc, m)) {
        if (m->type != AFFECT_JSON_STRING) {
            rc = ax_error_into(err, NULL,
                               "laban: components must be a JSON array of component names, got %s "
                               "in it",
                               affect_json_type_name(m->type));
            goto done;
        }
        int j = strlen(m->str) == m->str_len ? affect_laban_index(m->str) : -1;
        affect_json_quote(q, sizeof q, m->str, m->str_len);
        if (j < 0) {
            rc = ax_error_into(err, NULL, "laban: unknown component %s (see laban_names())", q);
            goto done;
        }
        if (on[j]) {
            rc = ax_error_into(err, NULL, "laban: component %s is listed twice", q);
            goto done;
        }
        on[j] = true;
    }
    for (int j = 0; j < LAB_N; j++)
        if (on[j])
            out[(*n)++] = j;
done:
    affect_json_free(doc);
    return rc;
}

/* Rows whose label passes the label = ? constraint (NULL: every row). */
static int lab_label_filter(const lab_cache *ca, sqlite3_value *want, unsigned char **out)
{
    *out = sqlite3_malloc64(ca->n_labels ? ca->n_labels : 1);
    if (!*out)
        return SQLITE_NOMEM;
    for (size_t j = 0; j < ca->n_labels; j++) {
        int eq = 0;
        if (ca->labels[j] && sqlite3_value_type(want) != SQLITE_NULL &&
            (eq = lab_value_equal(ca->labels[j], want, false)) < 0)
            return SQLITE_NOMEM;
        (*out)[j] = (unsigned char)eq;
    }
    return SQLITE_OK;
}

/* The standardized query vector: a motion BLOB or the rowid of an indexed row (*self). */
static int lab_query_vector(lab_vtab *vt, const lab_cache *ca, sqlite3_value *q, double zq[LAB_N],
                            ptrdiff_t *self, char **err)
{
    int t = sqlite3_value_type(q);
    *self = -1;
    double d = sqlite3_value_double(q);
    if (t == SQLITE_INTEGER || (t == SQLITE_FLOAT && d == floor(d) && fabs(d) < 9e15)) {
        sqlite3_int64 id = t == SQLITE_INTEGER ? sqlite3_value_int64(q) : (sqlite3_int64)d;
        *self = lab_cache_find(ca, id);
        if (*self < 0)
            return ax_error_into(err, NULL, "laban: no row %lld in the index", id);
        memcpy(zq, ca->z + (size_t)*self * LAB_N, sizeof(double) * LAB_N);
        return SQLITE_OK;
    }
    if (t != SQLITE_BLOB)
        return ax_error_into(err, NULL,
                             "laban: query must be a motion BLOB or a rowid of the content table, "
                             "got %s",
                             ax_type_name(q));
    const unsigned char *data = sqlite3_value_blob(q);
    int n = sqlite3_value_bytes(q);
    if (!data && n > 0)
        return SQLITE_NOMEM;
    float v[LAB_N];
    bool bad;
    affect_error e;
    if (lab_vector(vt, data, (size_t)n, v, &bad, &e))
        return lab_core_error(err, &e, bad ? "query is not a valid motion: " : "query: ");
    affect_laban_standardize(v, 1, ca->mean, ca->sd, zq);
    return SQLITE_OK;
}

/* Nearest rows: the k smallest distances (k > 0) or the radius ball (k = 0), by
 * affect_laban_search_run (core/src/laban_search.c: the distance, the heap and the tie rule). */
static int lab_knn(lab_cursor *c, const double zq[LAB_N], ptrdiff_t self, size_t lo, size_t hi,
                   sqlite3_int64 k, double radius, const int *comp, int nc)
{
    const lab_cache *ca = c->cache;
    affect_laban_search s = {
        .z = ca->z,
        .ids = ca->ids,
        .lo = lo,
        .hi = hi,
        .self = self < 0 ? SIZE_MAX : (size_t)self,
        .label = ca->label,
        .label_ok = c->label_ok,
        .comp = comp,
        .n_comp = nc,
        .k = (uint64_t)k,
        .radius = radius,
    };
    size_t cap = affect_laban_search_capacity(&s), bytes;
    if (!affect_mul_size(cap ? cap : 1, sizeof *c->hits, &bytes) ||
        !(c->hits = sqlite3_malloc64(bytes)))
        return SQLITE_NOMEM;
    affect_laban_search_run(&s, zq, c->hits, &c->n_hits);
    return SQLITE_OK;
}

static void lab_scan_skip(lab_cursor *c)
{
    const lab_cache *ca = c->cache;
    while (c->pos < c->end && c->label_ok &&
           (ca->label[c->pos] < 0 || !c->label_ok[ca->label[c->pos]]))
        c->pos++;
}

static int lab_filter(sqlite3_vtab_cursor *cur, int idx_num, const char *idx_str, int argc,
                      sqlite3_value **argv)
{
    lab_cursor *c = (lab_cursor *)cur;
    lab_vtab *vt = (lab_vtab *)cur->pVtab;
    char **err = &vt->base.zErrMsg;
    lab_cursor_reset(c);
    sqlite3_value *arg[IDX_BITS] = {NULL};
    for (int b = 0, a = 0; b < IDX_BITS; b++)
        if (idx_num & (1 << b) && a < argc)
            arg[b] = argv[a++];
    sqlite3_value *query = arg[0], *label = arg[1], *kv = arg[2], *rv = arg[3], *cv = arg[4],
                  *idv = arg[5];

    sqlite3_int64 k = 0;
    double radius = 0;
    int comp[LAB_N], nc = 0;
    int rc = SQLITE_OK;
    if ((kv && (rc = lab_arg_k(kv, &k, err))) || (rv && (rc = lab_arg_radius(rv, &radius, err))) ||
        (rc = lab_arg_components(cv, comp, &nc, err)) != SQLITE_OK)
        return rc;
    lab_cache *ca;
    if ((rc = lab_cache_current(vt, err, &ca)) != SQLITE_OK)
        return rc;
    c->cache = ca;
    ca->refs++;
    c->knn = query != NULL;
    sqlite3_value *keep[4] = {query, kv, rv, cv};
    for (int i = 0; i < 4; i++)
        if (keep[i] && !(c->args[i] = sqlite3_value_dup(keep[i])))
            return SQLITE_NOMEM;

    /* the rows [lo, hi) that the rowid constraint allows */
    size_t lo = 0, hi = ca->n;
    if (idv) {
        /* INTEGER affinity, as for any rowid: '7' and 7.0 name row 7 */
        sqlite3_value *id = sqlite3_value_dup(idv);
        if (!id)
            return SQLITE_NOMEM;
        int t = sqlite3_value_numeric_type(id);
        double d = sqlite3_value_double(id);
        ptrdiff_t at = -1;
        if (t == SQLITE_INTEGER)
            at = lab_cache_find(ca, sqlite3_value_int64(id));
        else if (t == SQLITE_FLOAT && d == floor(d) && fabs(d) < 9e15)
            at = lab_cache_find(ca, (sqlite3_int64)d);
        sqlite3_value_free(id);
        lo = at < 0 ? 0 : (size_t)at;
        hi = at < 0 ? 0 : lo + 1;
    }
    if (label && (rc = lab_label_filter(ca, label, &c->label_ok)) != SQLITE_OK)
        return rc;
    if (!c->knn) {
        c->pos = lo;
        c->end = hi;
        lab_scan_skip(c);
        return SQLITE_OK;
    }
    if (sqlite3_value_type(query) == SQLITE_NULL)
        return SQLITE_OK; /* query = NULL matches nothing */
    double zq[LAB_N];
    ptrdiff_t self;
    if ((rc = lab_query_vector(vt, ca, query, zq, &self, err)) != SQLITE_OK)
        return rc;
    return lab_knn(c, zq, self, lo, hi, kv ? k : 0, radius, comp, nc);
}

static int lab_next(sqlite3_vtab_cursor *cur)
{
    lab_cursor *c = (lab_cursor *)cur;
    if (c->knn) {
        c->hit++;
    } else {
        c->pos++;
        lab_scan_skip(c);
    }
    return SQLITE_OK;
}

static int lab_eof(sqlite3_vtab_cursor *cur)
{
    lab_cursor *c = (lab_cursor *)cur;
    return c->knn ? c->hit >= c->n_hits : c->pos >= c->end;
}

static size_t lab_row(const lab_cursor *c)
{
    return c->knn ? c->hits[c->hit].row : c->pos;
}

static int lab_column(sqlite3_vtab_cursor *cur, sqlite3_context *ctx, int col)
{
    lab_cursor *c = (lab_cursor *)cur;
    const lab_cache *ca = c->cache;
    size_t row = lab_row(c);
    if (col == COL_LABEL) {
        if (ca->label[row] >= 0)
            sqlite3_result_value(ctx, ca->labels[ca->label[row]]);
    } else if (col >= COL_COMP0 && col < COL_COMP0 + LAB_N) {
        float f = ca->raw[row * LAB_N + (col - COL_COMP0)];
        if (!isnan(f))
            sqlite3_result_double(ctx, f);
    } else if (col == COL_DISTANCE) {
        if (c->knn)
            sqlite3_result_double(ctx, c->hits[c->hit].d);
    } else if (col >= COL_QUERY && col <= COL_COMPONENTS) {
        if (c->args[col - COL_QUERY])
            sqlite3_result_value(ctx, c->args[col - COL_QUERY]);
    }
    return SQLITE_OK; /* anything else (the command column) is NULL */
}

static int lab_rowid(sqlite3_vtab_cursor *cur, sqlite3_int64 *rowid)
{
    lab_cursor *c = (lab_cursor *)cur;
    *rowid = c->cache->ids[lab_row(c)];
    return SQLITE_OK;
}

static sqlite3_module lab_module = {
    .iVersion = 3,
    .xCreate = lab_create,
    .xConnect = lab_connect,
    .xBestIndex = lab_best_index,
    .xDisconnect = lab_disconnect,
    .xDestroy = lab_destroy,
    .xOpen = lab_open,
    .xClose = lab_close,
    .xFilter = lab_filter,
    .xNext = lab_next,
    .xEof = lab_eof,
    .xColumn = lab_column,
    .xRowid = lab_rowid,
    .xUpdate = lab_update,
    .xBegin = lab_begin,
    .xSync = lab_sync,
    .xCommit = lab_commit,
    .xRollback = lab_rollback,
    .xRename = lab_rename,
    .xSavepoint = lab_savepoint,
    .xRelease = lab_savepoint,
    .xRollbackTo = lab_rollback_to,
    .xShadowName = lab_shadow_name,
};

int ax_register_laban(sqlite3 *db, const ax_laban_cache_kind *caches)
{
    return sqlite3_create_module(db, "laban", &lab_module, (void *)caches);
}

/* ---- what the rest of the extension reads of an index (vt_laban.h) ---- */

static int rows_db_error(char **err, sqlite3 *db, int rc)
{
    if ((rc & 0xff) == SQLITE_NOMEM)
        return SQLITE_NOMEM;
    return ax_error_into(err, NULL, "%s", sqlite3_errmsg(db));
}

void ax_laban_rows_free(ax_laban_rows *r)
{
    sqlite3_free(r->content);
    sqlite3_free(r->motion);
    sqlite3_free(r->ids);
    for (uint32_t i = 0; r->labels && i < r->n; i++)
        sqlite3_free(r->labels[i]);
    sqlite3_free(r->labels);
    sqlite3_free(r->vectors);
    memset(r, 0, sizeof *r);
}

/* ---- which tables are laban indexes ---- */

/* p past blanks and SQL comments. */
static const char *def_skip_blank(const char *p)
{
    for (;;) {
        while (*p == ' ' || *p == '\t' || *p == '\n' || *p == '\r' || *p == '\f')
            p++;
        if (p[0] == '-' && p[1] == '-') {
            while (*p && *p != '\n')
                p++;
        } else if (p[0] == '/' && p[1] == '*') {
            const char *end = strstr(p + 2, "*/");
            p = end ? end + 2 : p + strlen(p);
        } else {
            return p;
        }
    }
}

static bool def_ident_char(char c)
{
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
           c == '$' || (unsigned char)c >= 0x80;
}

/* p past one name ("…", `…`, '…' with doubled quotes, […], or a bare identifier), with its text
 * (quotes excluded, doubled quotes as they are) in *text and *len; NULL when there is none. */
static const char *def_name(const char *p, const char **text, size_t *len)
{
    char close = *p == '"' ? '"' : *p == '`' ? '`' : *p == '\'' ? '\'' : *p == '[' ? ']' : 0;
    if (close) {
        *text = p + 1;
        for (p++; *p; p++) {
            if (*p != close)
                continue;
            if (close != ']' && p[1] == close) {
                p++;
                continue;
            }
            *len = (size_t)(p - *text);
            return p + 1;
        }
        return NULL;
    }
    *text = p;
    while (def_ident_char(*p))
        p++;
    *len = (size_t)(p - *text);
    return *len ? p : NULL;
}

/* Whether def, the sql of a table in sqlite_schema, creates a table of the module "laban". SQLite
 * stores a virtual table's statement as "CREATE VIRTUAL TABLE " and then its text from the
 * table's name on: the name (quoted or bare), USING, the module's name (case-insensitive, quoted
 * or not) and its arguments, with blanks and comments allowed between them. Read token by token,
 * so that a table whose quoted name contains "USING laban(" is not taken for one. */
static bool lab_is_laban_def(const char *def)
{
    static const char prefix[] = "CREATE VIRTUAL TABLE";
    const char *text;
    size_t len;
    if (!def || sqlite3_strnicmp(def, prefix, (int)sizeof prefix - 1) != 0)
        return false;
    const char *p = def_skip_blank(def + sizeof prefix - 1);
    if (p == def + sizeof prefix - 1 || !(p = def_name(p, &text, &len)))
        return false;
    p = def_skip_blank(p);
    if (sqlite3_strnicmp(p, "USING", 5) != 0 || def_ident_char(p[5]))
        return false;
    p = def_name(def_skip_blank(p + 5), &text, &len);
    return p && len == 5 && sqlite3_strnicmp(text, "laban", 5) == 0 && !def_ident_char(*p);
}

/* The format of _info (column col of st) as this version reads it: SQLITE_OK for text '1';
 * SQLITE_NOMEM; else SQLITE_ERROR with *err: "g_info has format "2"; this version reads
 * format 1 (index "g")" (NULL when the row is missing). */
static int rows_check_format(sqlite3_stmt *st, int col, const char *name, char **err)
{
    const char *format = (const char *)sqlite3_column_text(st, col);
    if (sqlite3_column_type(st, col) == SQLITE_TEXT && format && !strcmp(format, LAB_FORMAT))
        return SQLITE_OK;
    if (!format && sqlite3_column_type(st, col) != SQLITE_NULL)
        return SQLITE_NOMEM;
    return ax_error_into(
        err, NULL,
        "%s_info has format %s%s%s; this version reads format " LAB_FORMAT " (index \"%w\")", name,
        format ? "\"" : "", format ? format : "NULL", format ? "\"" : "", name);
}

/* The content table and motion column of a laban table; SQLITE_NOTFOUND if it is not one
 * (lab_is_laban_def), SQLITE_ERROR with *err if its _info has another format. */
static int rows_info(sqlite3 *db, const char *name, ax_laban_rows *r, char **err)
{
    sqlite3_stmt *st = NULL;
    char *sql = sqlite3_mprintf(
        "SELECT (SELECT sql FROM sqlite_schema WHERE type = 'table' AND name = %Q), "
        "(SELECT value FROM \"%w_info\" WHERE key = 'content'), "
        "(SELECT value FROM \"%w_info\" WHERE key = 'motion'), "
        "(SELECT value FROM \"%w_info\" WHERE key = 'format')",
        name, name, name, name);
    if (!sql)
        return SQLITE_NOMEM;
    int rc = sqlite3_prepare_v2(db, sql, -1, &st, NULL);
    sqlite3_free(sql);
    if (rc == SQLITE_OK)
        rc = sqlite3_step(st);
    if (rc != SQLITE_ROW) {
        sqlite3_finalize(st);
        int code = sqlite3_errcode(db) & 0xff;
        return code == SQLITE_NOMEM || code == SQLITE_INTERRUPT ? code : SQLITE_NOTFOUND;
    }
    const char *def = (const char *)sqlite3_column_text(st, 0);
    if (!def && sqlite3_column_type(st, 0) != SQLITE_NULL) {
        sqlite3_finalize(st);
        return SQLITE_NOMEM;
    }
    bool is_laban = lab_is_laban_def(def);
    rc = is_laban ? rows_check_format(st, 3, name, err) : SQLITE_NOTFOUND;
    if (rc == SQLITE_OK &&
        (sqlite3_column_type(st, 1) != SQLITE_TEXT || sqlite3_column_type(st, 2) != SQLITE_TEXT))
        rc = SQLITE_NOTFOUND;
    if (rc == SQLITE_OK) {
        const char *content = (const char *)sqlite3_column_text(st, 1);
        const char *motion = (const char *)sqlite3_column_text(st, 2);
        r->content = content ? sqlite3_mprintf("%s", content) : NULL;
        r->motion = motion ? sqlite3_mprintf("%s", motion) : NULL;
        rc = r->content && r->motion ? SQLITE_OK : SQLITE_NOMEM;
    }
    sqlite3_finalize(st);
    return rc;
}

/* The labelled rows of _data of index `name` (in schema, or unqualified when schema is NULL)
 * into out (its ids, labels, vectors and n; out zeroed by the caller), validating every stored
 * vector, those of unlabelled rows too. On failure out keeps what was read: the caller frees
 * it. */
static int rows_load(sqlite3 *db, const char *schema, const char *name, ax_laban_rows *out,
                     char **err)
{
    sqlite3_stmt *st = NULL;
    char *sql = schema ? sqlite3_mprintf("SELECT id, label IS NULL, CAST(label AS TEXT), vector "
                                         "FROM \"%w\".\"%w_data\" ORDER BY id",
                                         schema, name)
                       : sqlite3_mprintf("SELECT id, label IS NULL, CAST(label AS TEXT), vector "
                                         "FROM \"%w_data\" ORDER BY id",
                                         name);
    if (!sql)
        return SQLITE_NOMEM;
    int rc = sqlite3_prepare_v2(db, sql, -1, &st, NULL);
    sqlite3_free(sql);
    if (rc != SQLITE_OK) {
        sqlite3_finalize(st);
        return rows_db_error(err, db, rc);
    }
    uint32_t cap = 0;
    while ((rc = sqlite3_step(st)) == SQLITE_ROW) {
        sqlite3_int64 id = sqlite3_column_int64(st, 0);
        int type = sqlite3_column_type(st, 3); /* before the conversions of column_blob */
        const unsigned char *v = sqlite3_column_blob(st, 3);
        int bytes = sqlite3_column_bytes(st, 3);
        char why[160];
        if (!v && bytes > 0) {
            rc = SQLITE_NOMEM;
            goto done;
        }
        if (lab_vector_corrupt(type, v, bytes, why, sizeof why)) {
            char *msg = lab_corrupt_message("", name, id, why, 0);
            rc = msg ? ax_error_into(err, NULL, "%s", msg) : SQLITE_NOMEM;
            sqlite3_free(msg);
            goto done;
        }
        if (sqlite3_column_int(st, 1))
            continue; /* no label */
        if (out->n == UINT32_MAX / 2) {
            rc = ax_error_into(err, NULL, "the index has too many rows");
            goto done;
        }
        if (out->n == cap) {
            cap = cap ? 2 * cap : 64;
            sqlite3_int64 *ids = sqlite3_realloc64(out->ids, cap * sizeof *ids);
            if (ids)
                out->ids = ids;
            char **l = sqlite3_realloc64(out->labels, cap * sizeof *l);
            if (l)
                out->labels = l;
            unsigned char *vv =
                sqlite3_realloc64(out->vectors, (sqlite3_uint64)cap * LAB_VECTOR_BYTES);
            if (vv)
                out->vectors = vv;
            if (!ids || !l || !vv) {
                rc = SQLITE_NOMEM;
                goto done;
            }
        }
        const char *label = (const char *)sqlite3_column_text(st, 2);
        if (!label) { /* a label that is not NULL has a text */
            rc = SQLITE_NOMEM;
            goto done;
        }
        out->labels[out->n] = sqlite3_mprintf("%s", label);
        if (!out->labels[out->n]) {
            rc = SQLITE_NOMEM;
            goto done;
        }
        out->ids[out->n] = id;
        memcpy(out->vectors + (size_t)out->n * LAB_VECTOR_BYTES, v, LAB_VECTOR_BYTES);
        out->n++;
    }
    rc = rc == SQLITE_DONE ? SQLITE_OK : rows_db_error(err, db, rc);
done:
    sqlite3_finalize(st);
    return rc;
}

int ax_laban_read(sqlite3 *db, const char *name, ax_laban_rows *out, char **err)
{
    memset(out, 0, sizeof *out);
    int rc = rows_info(db, name, out, err);
    if (rc == SQLITE_OK)
        rc = rows_load(db, NULL, name, out, err);
    if (rc != SQLITE_OK)
        ax_laban_rows_free(out);
    return rc;
}

/* The cache entries of _info that the module knows (vt->caches) against the index's rows:
 * an entry is its value (a BLOB) and its tag (TEXT, under "<key>_key"), both or neither. */
static int lab_check_caches(lab_vtab *vt, char **err)
{
    if (!vt->caches || !vt->caches[0].key)
        return SQLITE_OK;
    ax_laban_rows rows;
    memset(&rows, 0, sizeof rows);
    bool loaded = false;
    char *why = NULL;
    sqlite3_stmt *st = NULL;
    int rc = lab_prepare(vt->db, err, &st,
                         "SELECT (SELECT value FROM \"%w\".\"%w_info\" WHERE key = ?1), "
                         "(SELECT value FROM \"%w\".\"%w_info\" WHERE key = ?1 || '_key'), "
                         "EXISTS (SELECT 1 FROM \"%w\".\"%w_info\" WHERE key = ?1), "
                         "EXISTS (SELECT 1 FROM \"%w\".\"%w_info\" WHERE key = ?1 || '_key')",
                         vt->schema, vt->name, vt->schema, vt->name, vt->schema, vt->name,
                         vt->schema, vt->name);
    for (const ax_laban_cache_kind *k = vt->caches; rc == SQLITE_OK && k->key; k++) {
        sqlite3_reset(st);
        if ((rc = sqlite3_bind_text(st, 1, k->key, -1, SQLITE_STATIC)) != SQLITE_OK ||
            (rc = sqlite3_step(st)) != SQLITE_ROW) {
            rc = lab_db_error(err, vt->db, rc);
            break;
        }
        rc = SQLITE_OK;
        bool has_value = sqlite3_column_int(st, 2), has_tag = sqlite3_column_int(st, 3);
        if (!has_value && !has_tag)
            continue;
        if (!has_value || !has_tag) {
            rc = ax_error_into(err, NULL,
                               "laban: cache entry '%s' is corrupt: %s_info has its row '%s%s' but "
                               "not '%s%s'",
                               k->key, vt->name, k->key, has_value ? "" : "_key", k->key,
                               has_value ? "_key" : "");
            break;
        }
        int vtype = sqlite3_column_type(st, 0), ttype = sqlite3_column_type(st, 1);
        if (vtype != SQLITE_BLOB || ttype != SQLITE_TEXT) {
            rc =
                ax_error_into(err, NULL,
                              "laban: cache entry '%s' is corrupt: its value is %s and its key %s, "
                              "expected a blob and text",
                              k->key, ax_type_name(sqlite3_column_value(st, 0)),
                              ax_type_name(sqlite3_column_value(st, 1)));
            break;
        }
        const void *blob = sqlite3_column_blob(st, 0);
        int size = sqlite3_column_bytes(st, 0);
        const char *tag = (const char *)sqlite3_column_text(st, 1);
        if ((!blob && size > 0) || !tag) {
            rc = SQLITE_NOMEM;
            break;
        }
        if (!loaded) {
            char *msg = NULL;
            rc = rows_load(vt->db, vt->schema, vt->name, &rows, &msg);
            if (rc == SQLITE_ERROR)
                rc = ax_error_into(err, NULL, "laban: %s", msg);
            sqlite3_free(msg);
            if (rc)
                break;
            loaded = true;
        }
        rc = k->check(&rows, tag, blob, size, &why);
        if (rc == SQLITE_ERROR)
            rc = why ? ax_error_into(err, NULL, "laban: cache entry '%s' is corrupt: %s", k->key,
                                     why)
                     : SQLITE_NOMEM;
    }
    sqlite3_finalize(st);
    sqlite3_free(why);
    ax_laban_rows_free(&rows);
    return rc;
}

int ax_laban_label_of(sqlite3 *db, const char *name, const void *blob, int size, char **label,
                      char **err)
{
    *label = NULL;
    sqlite3_stmt *st = NULL;
    char *sql = sqlite3_mprintf("SELECT CAST(label AS TEXT) FROM \"%w_data\" WHERE msize = ?1 "
                                "AND mhash = ?2 AND label IS NOT NULL ORDER BY id LIMIT 1",
                                name);
    if (!sql)
        return SQLITE_NOMEM;
    int rc = sqlite3_prepare_v2(db, sql, -1, &st, NULL);
    sqlite3_free(sql);
    if (rc != SQLITE_OK) {
        sqlite3_finalize(st);
        return rows_db_error(err, db, rc);
    }
    sqlite3_bind_int64(st, 1, size);
    sqlite3_bind_int64(st, 2, lab_fnv1a(blob, (size_t)size));
    rc = sqlite3_step(st);
    const char *text = rc == SQLITE_ROW ? (const char *)sqlite3_column_text(st, 0) : NULL;
    if (text) {
        *label = sqlite3_mprintf("%s", text);
        rc = *label ? SQLITE_OK : SQLITE_NOMEM;
    } else if (rc == SQLITE_ROW && (sqlite3_errcode(db) & 0xff) == SQLITE_NOMEM) {
        rc = SQLITE_NOMEM;
    } else {
        rc = rc == SQLITE_ROW || rc == SQLITE_DONE ? SQLITE_OK : rows_db_error(err, db, rc);
    }
    sqlite3_finalize(st);
    return rc;
}

int ax_laban_cache_get(sqlite3 *db, const char *name, const char *key, const char *tag, void **blob,
                       int *size)
{
    *blob = NULL;
    *size = 0;
    char *sql = sqlite3_mprintf("SELECT (SELECT value FROM \"%w_info\" WHERE key = %Q), "
                                "(SELECT value FROM \"%w_info\" WHERE key = %Q || '_key')",
                                name, key, name, key);
    if (!sql)
        return SQLITE_NOMEM;
    sqlite3_stmt *st = NULL;
    int rc = sqlite3_prepare_v2(db, sql, -1, &st, NULL);
    sqlite3_free(sql);
    if (rc == SQLITE_OK && sqlite3_step(st) == SQLITE_ROW &&
        sqlite3_column_type(st, 0) == SQLITE_BLOB) {
        const char *got = (const char *)sqlite3_column_text(st, 1);
        int n = sqlite3_column_bytes(st, 0);
        if (got && strcmp(got, tag) == 0 && n > 0) {
            *blob = sqlite3_malloc(n);
            if (*blob) {
                memcpy(*blob, sqlite3_column_blob(st, 0), (size_t)n);
                *size = n;
            }
        }
    }
    rc = (sqlite3_errcode(db) & 0xff) == SQLITE_NOMEM ? SQLITE_NOMEM : SQLITE_OK;
    sqlite3_finalize(st);
    return rc;
}

int ax_laban_cache_put(sqlite3 *db, const char *name, const char *key, const char *tag,
                       const void *blob, int size)
{
    char *sql = sqlite3_mprintf("INSERT OR REPLACE INTO \"%w_info\"(key, value) "
                                "VALUES (%Q, ?1), (%Q || '_key', ?2)",
                                name, key, key);
    if (!sql)
        return SQLITE_NOMEM;
    sqlite3_stmt *st = NULL;
    int rc = sqlite3_prepare_v2(db, sql, -1, &st, NULL);
    sqlite3_free(sql);
    if (rc == SQLITE_OK) {
        sqlite3_bind_blob(st, 1, blob, size, SQLITE_STATIC);
        sqlite3_bind_text(st, 2, tag, -1, SQLITE_STATIC);
        rc = sqlite3_step(st);
        rc = rc == SQLITE_DONE ? SQLITE_OK : rc;
    }
    sqlite3_finalize(st);
    return rc;
}

/* ---- the statistics, for vectors that other L2 searches compare as the index does ---- */

/* One JSON array of AFFECT_LABAN_N statistics from _info row `key` (text) into v; a null entry
 * is NaN where nulls are allowed. NULL when sound, else what is wrong (static or in why). */
static const char *stats_array(const char *text, int type, const char *key, bool nulls,
                               double v[LAB_N], char *why, int size, bool *nomem)
{
    *nomem = false;
    if (type != SQLITE_TEXT) {
        sqlite3_snprintf(size, why, "%s is %s, expected a JSON array of %d numbers", key,
                         type == SQLITE_NULL ? "missing or NULL" : "not text", LAB_N);
        return why;
    }
    affect_json_doc *doc = NULL;
    affect_error e;
    const char *bad = NULL;
    if (affect_json_parse(text, strlen(text), &doc, NULL, &e)) {
        *nomem = e.status == AFFECT_ERR_NOMEM;
        sqlite3_snprintf(size, why, "%s is not valid JSON (%s)", key, e.msg);
        return why;
    }
    const affect_json_node *root = affect_json_root(doc);
    if (root->type != AFFECT_JSON_ARRAY || root->count != LAB_N) {
        if (root->type == AFFECT_JSON_ARRAY)
            sqlite3_snprintf(size, why, "%s is a JSON array of %u values, expected %d", key,
                             root->count, LAB_N);
        else
            sqlite3_snprintf(size, why, "%s is a JSON %s, expected an array of %d numbers", key,
                             affect_json_type_name(root->type), LAB_N);
        bad = why;
        goto done;
    }
    int j = 0;
    for (const affect_json_node *m = affect_json_first(doc, root); m;
         m = affect_json_next_sibling(doc, m), j++) {
        if (m->type == AFFECT_JSON_NUMBER) {
            v[j] = m->num;
        } else if (m->type == AFFECT_JSON_NULL && nulls) {
            v[j] = NAN;
        } else {
            sqlite3_snprintf(size, why, "%s[%d] (%s) is %s, expected a number%s", key, j,
                             affect_laban_names[j], affect_json_type_name(m->type),
                             nulls ? " or null" : "");
            bad = why;
            goto done;
        }
    }
done:
    affect_json_free(doc);
    return bad;
}

int ax_laban_stats_read(sqlite3 *db, const char *name, ax_laban_stats *out, char **err)
{
    memset(out, 0, sizeof *out);
    sqlite3_stmt *st = NULL;
    lab_vtab tmp;
    memset(&tmp, 0, sizeof tmp);
    char *ident = lab_ident(name);
    if (!ident)
        return SQLITE_NOMEM;
    int rc = SQLITE_OK;
    char *sql = sqlite3_mprintf("SELECT sql FROM sqlite_schema WHERE type = 'table' AND "
                                "name = %Q",
                                name);
    if (!sql) {
        rc = SQLITE_NOMEM;
        goto done;
    }
    rc = sqlite3_prepare_v2(db, sql, -1, &st, NULL);
    sqlite3_free(sql);
    if (rc != SQLITE_OK) {
        rc = rows_db_error(err, db, rc);
        goto done;
    }
    rc = sqlite3_step(st);
    const char *def = rc == SQLITE_ROW ? (const char *)sqlite3_column_text(st, 0) : NULL;
    if (rc != SQLITE_ROW && rc != SQLITE_DONE) {
        rc = rows_db_error(err, db, rc);
        goto done;
    }
    if (!def && rc == SQLITE_ROW && sqlite3_column_type(st, 0) != SQLITE_NULL) {
        rc = SQLITE_NOMEM;
        goto done;
    }
    if (!lab_is_laban_def(def)) {
        rc = SQLITE_NOTFOUND;
        goto done;
    }
    sqlite3_finalize(st);
    st = NULL;
    /* the seven keys in one row; absent keys are NULL, told apart by the EXISTS columns */
    sql = sqlite3_mprintf("SELECT (SELECT value FROM \"%w_info\" WHERE key = 'format'), "
                          "(SELECT value FROM \"%w_info\" WHERE key = 'options'), "
                          "(SELECT value FROM \"%w_info\" WHERE key = 'mean'), "
                          "(SELECT value FROM \"%w_info\" WHERE key = 'sd'), "
                          "(SELECT value FROM \"%w_info\" WHERE key = 'generation'), "
                          "(SELECT value FROM \"%w_info\" WHERE key = 'stats_generation'), "
                          "(SELECT value FROM \"%w_info\" WHERE key = 'rows')",
                          name, name, name, name, name, name, name);
    if (!sql) {
        rc = SQLITE_NOMEM;
        goto done;
    }
    rc = sqlite3_prepare_v2(db, sql, -1, &st, NULL);
    sqlite3_free(sql);
    if (rc == SQLITE_OK && (rc = sqlite3_step(st)) == SQLITE_ROW)
        rc = SQLITE_OK;
    if (rc != SQLITE_OK) {
        rc = (rc & 0xff) == SQLITE_NOMEM
                 ? SQLITE_NOMEM
                 : ax_error_into(err, NULL, "cannot read the statistics of index \"%w\": %s", name,
                                 sqlite3_errmsg(db));
        goto done;
    }
    if ((rc = rows_check_format(st, 0, name, err)) != SQLITE_OK)
        goto done;
    char why[200];
    const char *bad = NULL;
    bool nomem = false;
    /* the options with which the index computes a query motion's vector */
    const char *options = (const char *)sqlite3_column_text(st, 1);
    if (sqlite3_column_type(st, 1) != SQLITE_TEXT) {
        sqlite3_snprintf(sizeof why, why, "options is %s, expected a JSON object",
                         sqlite3_column_type(st, 1) == SQLITE_NULL ? "missing or NULL"
                                                                   : "not text");
        bad = why;
    } else if (!options) {
        rc = SQLITE_NOMEM;
        goto done;
    } else {
        char *msg = NULL;
        rc = lab_parse_options(&tmp, options, &msg);
        if (rc == SQLITE_NOMEM) {
            sqlite3_free(msg);
            goto done;
        }
        if (rc != SQLITE_OK) {
            /* "laban: option …" without the module's prefix */
            const char *text = msg ? msg : "";
            if (!strncmp(text, "laban: ", 7))
                text += 7;
            sqlite3_snprintf(sizeof why, why, "options: %s", text);
            sqlite3_free(msg);
            bad = why;
        }
        rc = SQLITE_OK;
    }
    const char *row = bad ? "options" : NULL;
    if (!bad &&
        (bad = stats_array((const char *)sqlite3_column_text(st, 2), sqlite3_column_type(st, 2),
                           "mean", true, out->mean, why, (int)sizeof why, &nomem)) != NULL)
        row = "mean";
    if (!bad && !nomem &&
        (bad = stats_array((const char *)sqlite3_column_text(st, 3), sqlite3_column_type(st, 3),
                           "sd", false, out->sd, why, (int)sizeof why, &nomem)) != NULL)
        row = "sd";
    if (nomem) {
        rc = SQLITE_NOMEM;
        goto done;
    }
    affect_error e;
    if (!bad && affect_laban_stats_check(out->mean, out->sd, &e)) {
        sqlite3_snprintf(sizeof why, why, "%s", e.msg);
        bad = why;
        row = strncmp(e.msg, "mean", 4) ? "sd" : "mean";
    }
    if (!bad && (sqlite3_column_type(st, 4) != SQLITE_INTEGER ||
                 (sqlite3_column_type(st, 5) != SQLITE_INTEGER &&
                  sqlite3_column_type(st, 5) != SQLITE_NULL) ||
                 sqlite3_column_type(st, 6) != SQLITE_INTEGER || sqlite3_column_int64(st, 6) < 0)) {
        int c = sqlite3_column_type(st, 4) != SQLITE_INTEGER   ? 4
                : sqlite3_column_type(st, 6) != SQLITE_INTEGER ? 6
                : sqlite3_column_int64(st, 6) < 0              ? 6
                                                               : 5;
        row = c == 4 ? "generation" : c == 5 ? "stats_generation" : "rows";
        sqlite3_snprintf(sizeof why, why, "%s is %s, expected %s", row,
                         ax_type_name(sqlite3_column_value(st, c)),
                         c == 6 ? "an integer >= 0" : "an integer");
        bad = why;
    }
    if (bad) {
        rc = ax_error_into(err, NULL,
                           "corrupt statistics: %s (index \"%w\", %s_info row '%s'); run "
                           "INSERT INTO %s(%s) VALUES('rebuild')",
                           bad, name, name, row, ident, ident);
        goto done;
    }
    out->generation = sqlite3_column_int64(st, 4);
    out->rows = sqlite3_column_int64(st, 6);
    if (sqlite3_column_type(st, 5) == SQLITE_INTEGER &&
        sqlite3_column_int64(st, 5) != out->generation) {
        rc = ax_error_into(err, NULL,
                           "the statistics of index \"%w\" are out of date until the "
                           "transaction that changed it commits (generation %lld, statistics of "
                           "generation %lld)",
                           name, out->generation, sqlite3_column_int64(st, 5));
        goto done;
    }
    out->opt = tmp.opt;
    rc = SQLITE_OK;
done:
    sqlite3_finalize(st);
    affect_free(tmp.options_json);
    sqlite3_free(ident);
    return rc;
}
