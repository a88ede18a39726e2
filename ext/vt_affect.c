/*
 * vt_affect.c — the recognizer's table-valued functions (materialized, see vt_rows.h):
 *
 *   affect_crossval(table, motion_column, label_column [, options])
 *       one row per method × fold and a summary row per method (fold NULL):
 *       method, fold, held_out, n_train, n_test, accuracy, balanced_accuracy, macro_f1,
 *       accuracy_sd, balanced_accuracy_sd, macro_f1_sd, pooled_accuracy, confusion (JSON:
 *       {"labels": [...], "matrix": [[...]]}, rows = true class), params (JSON: what the fold's
 *       classifier used)
 *   affect_salience(classifier [, options])
 *       one row per class HMM, state and mixture: label, state, mixture, weight, top (JSON:
 *       [{"coordinates": ["Hand_L.y", "Hand_L.y"], "weight": w}, ...]), posture (a one-frame
 *       motion: the component's mean pose on the training skeleton, for motion_svg)
 *
 * affect_crossval runs, on the same connection,
 *   SELECT affect_crossval_json(t."motion_column", t."label_column", <t."group" or NULL>,
 *                               :options) FROM "table" AS t
 * (identifiers quoted and qualified, so that a misspelt column is "no such column: t.x", not
 * a string; options {"group": "content"} selects leave-one-group-out over that column,
 * otherwise stratified k-fold with "folds" (10) and "seed"), then turns the JSON's rows
 * into table rows; its errors are that statement's (for instance "affect_crossval_json: row 3:
 * …"), prefixed with "affect_crossval: ", except an interrupt: "affect_crossval: interrupted".
 * The options are affect_train's plus folds, group,
 * methods (["ml", "svm", "knn"]; also "fpca", "ffda", "fspca", "fspca_rbf", "fisomap", the
 * functional methods with fda_train's dims, basis, order, lambda, sigma, ffda_reg and isomap_k)
 * and verbose (progress lines on stderr).
 */
#include "fn_affect.h"

#include <string.h>

#include "affect/classifier.h"
#include "util/strbuf.h"
#include "vt_rows.h"

/* ---- affect_crossval ---- */

#define CV_COLUMNS 14

/* The "group" option of an options text into *out (NULL when absent or not a string, or when
 * the text is not a JSON object: affect_crossval_json reports that itself). SQLITE_NOMEM when
 * memory ran out (never a silent "no group", which would change the protocol). */
static int group_column(const char *options, size_t len, char **out)
{
    affect_json_doc *doc = NULL;
    affect_error err;
    *out = NULL;
    if (!options)
        return SQLITE_OK;
    if (affect_json_parse(options, len, &doc, NULL, &err))
        return err.status == AFFECT_ERR_NOMEM ? SQLITE_NOMEM : SQLITE_OK;
    const affect_json_node *root = affect_json_root(doc);
    int rc = SQLITE_OK;
    if (root->type == AFFECT_JSON_OBJECT)
        for (const affect_json_node *e = affect_json_first(doc, root); e;
             e = affect_json_next_sibling(doc, e))
            if (strcmp(e->key, "group") == 0 && e->type == AFFECT_JSON_STRING) {
                sqlite3_free(*out);
                *out = sqlite3_mprintf("%s", e->str);
                if (!*out)
                    rc = SQLITE_NOMEM;
            }
    affect_json_free(doc);
    return rc;
}

static int cv_fill(sqlite3_vtab *vt, sqlite3 *db, int argc, sqlite3_value **argv, ax_rows *rows)
{
    for (int i = 0; i < 3; i++)
        if (argc <= i || sqlite3_value_type(argv[i]) != SQLITE_TEXT)
            return ax_vtab_error(vt, NULL,
                                 "affect_crossval: argument %d (%s) must be a name, as in "
                                 "SELECT * FROM affect_crossval('motions', 'motion', "
                                 "'emotion', '{\"folds\":10}')",
                                 i + 1,
                                 i == 0   ? "table"
                                 : i == 1 ? "motion column"
                                          : "label column");
    const char *table = (const char *)sqlite3_value_text(argv[0]);
    const char *motion = (const char *)sqlite3_value_text(argv[1]);
    const char *label = (const char *)sqlite3_value_text(argv[2]);
    const char *options = argc > 3 ? (const char *)sqlite3_value_text(argv[3]) : NULL;
    size_t options_len = argc > 3 ? (size_t)sqlite3_value_bytes(argv[3]) : 0;
    if (!table || !motion || !label)
        return SQLITE_NOMEM;
    if (argc > 3 && sqlite3_value_type(argv[3]) != SQLITE_NULL && !options)
        return SQLITE_NOMEM;
    char *group = NULL;
    if (group_column(options, options_len, &group) != SQLITE_OK)
        return SQLITE_NOMEM;
    /* columns qualified by the table's alias: an unknown one is "no such column", never the
     * string literal SQLite makes of an unresolved double-quoted name */
    char *inner = group ? sqlite3_mprintf("t.\"%w\"", group) : sqlite3_mprintf("NULL");
    char *sql =
        inner ? sqlite3_mprintf(
                    "SELECT json_extract(r.value, '$.method'), json_extract(r.value, '$.fold'), "
                    "json_extract(r.value, '$.held_out'), json_extract(r.value, '$.n_train'), "
                    "json_extract(r.value, '$.n_test'), json_extract(r.value, '$.accuracy'), "
                    "json_extract(r.value, '$.balanced_accuracy'), "
                    "json_extract(r.value, '$.macro_f1'), "
                    "json_extract(r.value, '$.accuracy_sd'), "
                    "json_extract(r.value, '$.balanced_accuracy_sd'), "
                    "json_extract(r.value, '$.macro_f1_sd'), "
                    "json_extract(r.value, '$.pooled_accuracy'), "
                    "json_object('labels', json_extract(j.v, '$.labels'), "
                    "'matrix', json_extract(r.value, '$.confusion')), "
                    "json_extract(r.value, '$.params') "
                    "FROM (SELECT affect_crossval_json(t.\"%w\", t.\"%w\", %s, ?1) AS v "
                    "FROM \"%w\" AS t) "
                    "AS j, json_each(j.v, '$.rows') AS r",
                    motion, label, inner, table)
              : NULL;
    sqlite3_free(group);
    sqlite3_free(inner);
    if (!sql)
        return SQLITE_NOMEM;
    sqlite3_stmt *st = NULL;
    int rc = sqlite3_prepare_v2(db, sql, -1, &st, NULL);
    sqlite3_free(sql);
    if (rc == SQLITE_OK)
        rc = argc > 3 ? sqlite3_bind_value(st, 1, argv[3]) : sqlite3_bind_null(st, 1);
    while (rc == SQLITE_OK && (rc = sqlite3_step(st)) == SQLITE_ROW) {
        for (int c = 0; c < CV_COLUMNS; c++) {
            int type = sqlite3_column_type(st, c);
            if (type == SQLITE_INTEGER)
                ax_rows_int(rows, sqlite3_column_int64(st, c));
            else if (type == SQLITE_FLOAT)
                ax_rows_double(rows, sqlite3_column_double(st, c));
            else if (type == SQLITE_TEXT) {
                const char *t = (const char *)sqlite3_column_text(st, c);
                size_t n = (size_t)sqlite3_column_bytes(st, c);
                char *copy = t ? sqlite3_malloc64(n + 1) : NULL;
                if (copy) {
                    memcpy(copy, t, n);
                    copy[n] = '\0';
                }
                ax_rows_take_text(rows, copy, n, c >= CV_COLUMNS - 2);
            } else
                ax_rows_null(rows);
        }
        rc = SQLITE_OK;
    }
    if (rc == SQLITE_DONE) {
        rc = SQLITE_OK;
    } else if (rc != SQLITE_NOMEM) { /* an interrupt: "affect_crossval: interrupted" */
        const char *why = rc == SQLITE_INTERRUPT ? "interrupted" : sqlite3_errmsg(db);
        if (ax_vtab_error(vt, NULL, "affect_crossval: %s", why) == SQLITE_NOMEM)
            rc = SQLITE_NOMEM;
    }
    sqlite3_finalize(st);
    return rc;
}

static const ax_rows_spec cv_spec = {
    "affect_crossval",
    "CREATE TABLE x(method TEXT, fold INTEGER, held_out TEXT, n_train INTEGER, n_test INTEGER, "
    "accuracy REAL, balanced_accuracy REAL, macro_f1 REAL, accuracy_sd REAL, "
    "balanced_accuracy_sd REAL, macro_f1_sd REAL, pooled_accuracy REAL, confusion TEXT, "
    "params TEXT, content_table HIDDEN, motion_column HIDDEN, label_column HIDDEN, "
    "options HIDDEN)",
    CV_COLUMNS,
    4,
    3,
    cv_fill,
    "SELECT * FROM affect_crossval('motions', 'motion', 'emotion', '{\"folds\":10}')",
    true};

/* ---- affect_salience ---- */

/* "Hand_L.y" (or "v.Hand_L.y" for a velocity coordinate) of observation coordinate r. */
static void coordinate_name(affect_strbuf *sb, const affect_features *f, uint32_t r)
{
    static const char axes[] = "xyz";
    uint32_t J = f->n_joints;
    bool vel = r >= 3 * J;
    uint32_t q = vel ? r - 3 * J : r;
    affect_strbuf_puts(sb, vel ? "v." : "");
    affect_strbuf_puts(sb, f->joints[q / 3]);
    affect_strbuf_putc(sb, '.');
    affect_strbuf_putc(sb, axes[q % 3]);
}

static char *top_json(const affect_features *f, const affect_salience_row *row, size_t *len)
{
    affect_strbuf sb;
    affect_strbuf_init(&sb);
    affect_strbuf_putc(&sb, '[');
    for (uint32_t t = 0; t < row->n_top; t++) {
        affect_strbuf_puts(&sb, t ? ",{\"coordinates\":[\"" : "{\"coordinates\":[\"");
        coordinate_name(&sb, f, row->top[t].r);
        affect_strbuf_puts(&sb, "\",\"");
        coordinate_name(&sb, f, row->top[t].s);
        affect_strbuf_puts(&sb, "\"],\"weight\":");
        affect_strbuf_double(&sb, row->top[t].weight);
        affect_strbuf_putc(&sb, '}');
    }
    affect_strbuf_putc(&sb, ']');
    char *text;
    affect_error err;
    if (affect_strbuf_finish(&sb, &text, len, &err))
        return NULL;
    return text;
}

static int salience_rows(sqlite3_vtab *vt, const affect_classifier *c, uint32_t top, ax_rows *rows)
{
    affect_salience_row *sr = NULL;
    size_t n = 0;
    affect_error err;
    if (affect_classifier_salience(c, top, &sr, &n, &err))
        return ax_vtab_error(vt, &err, "affect_salience: %s", err.msg);
    const affect_features *f = affect_classifier_features(c);
    int rc = SQLITE_OK;
    for (size_t i = 0; i < n && rc == SQLITE_OK; i++) {
        const affect_hmm *h = affect_classifier_hmm(c, sr[i].cls);
        const affect_hmm_config *hc = affect_hmm_get_config(h);
        const double *mean =
            affect_hmm_means(h) + ((size_t)sr[i].state * hc->n_mix + sr[i].mix) * hc->dim;
        const char *label = affect_classifier_label(c, sr[i].cls);
        ax_rows_text(rows, label, strlen(label));
        ax_rows_int(rows, sr[i].state);
        ax_rows_int(rows, sr[i].mix);
        ax_rows_double(rows, sr[i].weight);
        size_t len;
        char *json = top_json(f, &sr[i], &len);
        ax_rows_take_text(rows, json, len, true);
        affect_motion *m = NULL;
        unsigned char *blob = NULL;
        size_t size = 0;
        if (affect_features_posture_motion(f, mean, 1, &m, &err) ||
            affect_motion_encode(m, &blob, &size, &err))
            rc = ax_vtab_error(vt, &err, "affect_salience: posture: %s", err.msg);
        else
            ax_rows_take_blob(rows, blob, size);
        affect_motion_free(m);
    }
    affect_free(sr);
    return rc;
}

static int salience_fill(sqlite3_vtab *vt, sqlite3 *db, int argc, sqlite3_value **argv,
                         ax_rows *rows)
{
    (void)db;
    if (argc < 1 || sqlite3_value_type(argv[0]) == SQLITE_NULL)
        return SQLITE_OK;
    if (sqlite3_value_type(argv[0]) != SQLITE_BLOB)
        return ax_vtab_error(vt, NULL,
                             "affect_salience: argument 1 must be a classifier BLOB "
                             "(from affect_train), got %s",
                             ax_type_name(argv[0]));
    uint32_t top = 5;
    if (argc > 1 && sqlite3_value_type(argv[1]) != SQLITE_NULL) {
        if (sqlite3_value_type(argv[1]) != SQLITE_INTEGER)
            return ax_vtab_error(vt, NULL,
                                 "affect_salience: argument 2 (top) must be an integer "
                                 "from 1 to 32, got %s",
                                 ax_type_name(argv[1]));
        if (sqlite3_value_int64(argv[1]) < 1 ||
            sqlite3_value_int64(argv[1]) > AFFECT_SALIENCE_TOP_MAX)
            return ax_vtab_error(vt, NULL,
                                 "affect_salience: argument 2 (top) must be an integer from 1 "
                                 "to 32, got %lld",
                                 sqlite3_value_int64(argv[1]));
        top = (uint32_t)sqlite3_value_int64(argv[1]);
    }
    const unsigned char *data = sqlite3_value_blob(argv[0]);
    int n = sqlite3_value_bytes(argv[0]);
    if (!data && n > 0)
        return SQLITE_NOMEM;
    affect_classifier *c;
    affect_error err;
    if (affect_classifier_decode(data, (size_t)n, &c, &err))
        return ax_vtab_error(vt, &err, "affect_salience: argument 1 is not a valid classifier: %s",
                             err.msg);
    int rc = salience_rows(vt, c, top, rows);
    affect_classifier_free(c);
    return rc;
}

static const ax_rows_spec salience_spec = {
    "affect_salience",
    "CREATE TABLE x(label TEXT, state INTEGER, mixture INTEGER, weight REAL, top TEXT, "
    "posture BLOB, classifier HIDDEN, top_n HIDDEN)",
    6,
    2,
    1,
    salience_fill,
    "SELECT * FROM affect_salience(:classifier [, top])",
    false};

int ax_register_affect_salience(sqlite3 *db)
{
    return ax_rows_register(db, &salience_spec);
}

int ax_register_affect_crossval(sqlite3 *db)
{
    return ax_rows_register(db, &cv_spec);
}
