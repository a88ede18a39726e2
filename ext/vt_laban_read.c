/*
 * vt_laban_read.c — what the rest of the extension reads of a laban index (vt_laban.h): which
 * tables are indexes (by their CREATE statement, then _info's format), the labelled rows and
 * their vectors, the label of a motion, the cache entries of other functions kept in _info, and
 * the statistics that laban_zvector standardizes with.
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "vt_laban_int.h"

#include "util/strbuf.h"

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
 * format 1", followed by " (index "g")" when name_it (NULL when the row is missing). The reader
 * of rows leaves the index's name to its caller, as for its other messages. */
static int rows_check_format(sqlite3_stmt *st, int col, const char *name, bool name_it, char **err)
{
    const char *format = (const char *)sqlite3_column_text(st, col);
    if (sqlite3_column_type(st, col) == SQLITE_TEXT && format && !strcmp(format, LAB_FORMAT))
        return SQLITE_OK;
    if (!format && sqlite3_column_type(st, col) != SQLITE_NULL)
        return SQLITE_NOMEM;
    return ax_error_into(
        err, NULL, "%s_info has format %s%s%s; this version reads format " LAB_FORMAT "%s%w%s",
        name, format ? "\"" : "", format ? format : "NULL", format ? "\"" : "",
        name_it ? " (index \"" : "", name_it ? name : "", name_it ? "\")" : "");
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
    rc = is_laban ? rows_check_format(st, 3, name, false, err) : SQLITE_NOTFOUND;
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
int lab_rows_load(sqlite3 *db, const char *schema, const char *name, ax_laban_rows *out, char **err)
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
        rc = lab_rows_load(db, NULL, name, out, err);
    if (rc != SQLITE_OK)
        ax_laban_rows_free(out);
    return rc;
}

/* The cache entries of _info that the module knows (vt->caches) against the index's rows:
 * an entry is its value (a BLOB) and its tag (TEXT, under "<key>_key"), both or neither. */
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
    if ((rc = rows_check_format(st, 0, name, true, err)) != SQLITE_OK)
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
