/*
 * vt_laban_store.c — the laban index's storage (see the manual in vt_laban.c): its errors, the
 * SQL it runs on its shadow tables <name>_data and <name>_info, the Laban vector of a motion, the
 * per-connection cache of the indexed rows and their standardization, and the commands that
 * write the shadow tables (rebuild, refresh, delete) or verify them (check).
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "vt_laban_int.h"

#include "util/strbuf.h"

/* ---- errors: every message through ax_error_into (common.c), prefixed "laban: " ---- */

/* The error of a failed SQLite call on db (out of memory stays SQLITE_NOMEM). */
int lab_db_error(char **dst, sqlite3 *db, int rc)
{
    if ((rc & 0xff) == SQLITE_NOMEM)
        return SQLITE_NOMEM;
    int code = ax_error_into(dst, NULL, "laban: %s", sqlite3_errmsg(db));
    return code != SQLITE_NOMEM && (rc & 0xff) == SQLITE_INTERRUPT ? SQLITE_INTERRUPT : code;
}

/* "laban: interrupted" with SQLITE_INTERRUPT, as lab_db_error reports an interrupted statement
 * of the index. */
int lab_interrupted(char **dst)
{
    int code = ax_error_into(dst, NULL, "laban: interrupted");
    return code == SQLITE_NOMEM ? code : SQLITE_INTERRUPT;
}

/* A core error: out of memory becomes SQLITE_NOMEM, an interrupt lab_interrupted, anything else
 * "laban: <prefix><msg>". */
int lab_core_error(char **dst, const affect_error *err, const char *prefix)
{
    if (err->status == AFFECT_ERR_NOMEM)
        return SQLITE_NOMEM;
    if (err->status == AFFECT_ERR_INTERRUPTED)
        return lab_interrupted(dst);
    return ax_error_into(dst, NULL, "laban: %s%s", prefix, err->msg);
}

/* A value for a message: the number itself, or the name of its type. */
const char *lab_value_desc(sqlite3_value *v, char *buf, int size)
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

int lab_prepare(sqlite3 *db, char **err, sqlite3_stmt **st, const char *fmt, ...)
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
int lab_step_done(sqlite3 *db, char **err, sqlite3_stmt *st)
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
int lab_exec(sqlite3 *db, char **err, const char *fmt, ...)
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
bool lab_vector_corrupt(int type, const unsigned char *p, int n, char *why, int size)
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
char *lab_ident(const char *name)
{
    bool plain = (name[0] < '0' || name[0] > '9') &&
                 strspn(name, "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                              "0123456789_") == strlen(name);
    return sqlite3_mprintf(plain ? "%s" : "\"%w\"", name);
}

/* "stored vector of rowid 17 is corrupt (1 bytes, expected 108); run INSERT INTO g(g)
 * VALUES('rebuild')", with prefix in front (and ", and N more are" after the parenthesis when
 * more > 0); NULL when out of memory. */
char *lab_corrupt_message(const char *prefix, const char *name, sqlite3_int64 id, const char *why,
                          sqlite3_int64 more)
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
sqlite3_int64 lab_fnv1a(const unsigned char *p, size_t n)
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
affect_status lab_vector(const lab_vtab *vt, const unsigned char *data, size_t n, float out[LAB_N],
                         bool *bad_blob, affect_error *err)
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
int lab_value_equal(sqlite3_value *a, sqlite3_value *b, bool exact)
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

void lab_cache_unref(lab_cache *c)
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

void lab_cache_drop(lab_vtab *vt)
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

/* mean and sd per component over the rows (missing values skipped; affect_laban_stats, here in
 * parts of LAB_POLL_ROWS rows), then z, polling db's interrupt between the parts ("laban:
 * interrupted"): over millions of rows the three passes take about 0.1 s per million. */
static int lab_cache_standardize(sqlite3 *db, char **err, lab_cache *c)
{
    size_t bytes;
    if (!affect_mul_size(c->n ? c->n : 1, LAB_N * sizeof *c->z, &bytes))
        return SQLITE_NOMEM;
    c->z = sqlite3_malloc64(bytes);
    if (!c->z)
        return SQLITE_NOMEM;
    ax_monitor am;
    char *msg = NULL;
    if (c->n > LAB_POLL_ROWS && ax_monitor_begin_db(&am, db, NULL, &msg) != SQLITE_OK) {
        sqlite3_free(msg); /* no progress function: only out of memory */
        return SQLITE_NOMEM;
    }
    affect_laban_acc acc;
    affect_laban_acc_init(&acc);
    int rc = SQLITE_OK;
    /* pass 0: sums, pass 1: squares, pass 2: z */
    for (int pass = 0; pass < 3 && rc == SQLITE_OK; pass++) {
        if (pass == 1)
            affect_laban_acc_means(&acc);
        else if (pass == 2)
            affect_laban_acc_result(&acc, c->mean, c->sd);
        for (size_t at = 0; at < c->n; at += LAB_POLL_ROWS) {
            if (c->n > LAB_POLL_ROWS && (pass > 0 || at > 0) && ax_monitor_interrupted(&am)) {
                rc = lab_interrupted(err);
                break;
            }
            size_t part = c->n - at > LAB_POLL_ROWS ? LAB_POLL_ROWS : c->n - at;
            const float *x = c->raw + at * LAB_N;
            if (pass == 0)
                affect_laban_acc_sums(&acc, x, part);
            else if (pass == 1)
                affect_laban_acc_squares(&acc, x, part);
            else
                affect_laban_standardize(x, part, c->mean, c->sd, c->z + at * LAB_N);
        }
    }
    if (c->n > LAB_POLL_ROWS)
        ax_monitor_end(&am);
    return rc;
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
    rc = lab_cache_standardize(vt->db, err, c);
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
int lab_cache_current(lab_vtab *vt, char **err, lab_cache **out)
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
ptrdiff_t lab_cache_find(const lab_cache *c, sqlite3_int64 id)
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
int lab_flush_stats(lab_vtab *vt, char **err)
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
int lab_rebuild(lab_vtab *vt, char **err)
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
int lab_refresh(lab_vtab *vt, sqlite3_int64 id, bool remove, char **err)
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
int lab_check(lab_vtab *vt, char **err)
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
            rc = lab_rows_load(vt->db, vt->schema, vt->name, &rows, &msg);
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
