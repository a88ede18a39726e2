/*
 * fn_strength.c — SQL wrappers of emotion strength by relative attributes (core:
 * affect/strength.h, affect/rank.h, affect/keyframes.h; SCIENCE.md §6):
 *
 *   strength_train(motion, label [, options])   aggregate → strength model BLOB (AFST)
 *   affect_strength(model, motion)              → real: the motion's strength r(x)
 *   strength_synthesize(model, s [, options])   → motion of strength s (s: a number, or a label
 *                                                 of the order: its training mean strength)
 *   strength_edit(model, motion, s [, options]) → the motion edited to strength s
 *   strength_info(model)                        → JSON: features, PCA, ranker, levels, regression
 *   motion_keyframes(motion [, q])              → JSON: the q keyframes and the error
 *   rank_train(vector, label [, options])       aggregate over float32 vector BLOBs → ranker (AFRK)
 *   rank_score(ranker, vector)                  → real
 *
 * Labels: a text or a number; or, for pairs within one content, a JSON object text such as
 * json_object('label', style, 'content', action) (the keys are the options "label" and
 * "content"). With the option "order" (an array of labels, weakest first) a row's level is its
 * label's position, and rows whose label is not in the order are left out; without it the
 * labels must be numbers, ordered by value.
 *
 * Training options (the same text on every row): order, pairs ("all" | "same_content"),
 * label, content, fraction (0 < f ≤ 1), similar (true), C (1), seed (0), progress; and for
 * strength_train keyframes (13), pca_dims (40; 0 = none), regression ("auto" | "kernel_ridge"
 * | "local_linear"), relative (false), standardize (true), features ("laban" | "keyframes" |
 * "both" | "fisher"), descriptors (with "fisher": "none" | "kinematics" | "laban" | "all",
 * default "kinematics"); for rank_train clusters (1).
 *
 * How the aggregates work: the state (one pointer in the aggregate context) keeps each row's
 * decoded motion (strength_train: every motion is checked against the first's skeleton and
 * length on arrival, with its row number) or vector, its label and content; xFinal assigns
 * levels, trains, encodes and frees. NULL motions, vectors or labels are skipped; no row gives
 * NULL.
 *
 * Models given as a constant argument are decoded once and kept as auxiliary data;
 * affect_strength keeps its last model per connection (decoded again only when the BLOB's
 * bytes change), so one call per statement does not decode it each time.
 *
 * Errors: "strength_train: row 3: 19 joints, the model has 22", "strength_train: option
 * \"order\" must be an array of at least 2 distinct labels", "strength_train: labels must be
 * numbers when no \"order\" is given (row 1: \"angry\")", "affect_strength: argument 1 is not a
 * valid strength model: …", "rank_train: row 2: the vector has 3 dimensions, the first 4".
 */
#include "fn_strength.h"

#include "seqs.h"

#include <inttypes.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "affect/keyframes.h"
#include "affect/rank.h"
#include "util/strbuf.h"
#include "affect/strength.h"

/* ---- the training state shared by both aggregates ---- */

typedef struct row_label {
    char *text; /* label text, or NULL when numeric */
    double num;
    uint32_t content; /* index in contents */
} row_label;

typedef struct train_state {
    bool failed, vectors;
    uint64_t rows;
    ax_opts_text opts_text; /* the first row's options text (NULL when none) */
    bool have_opts;
    /* options */
    affect_strength_options so;
    uint32_t clusters;
    char **order;
    uint32_t n_order;
    bool same_content;
    char *label_key, *content_key, *progress;
    /* rows kept */
    affect_motion **motions;
    double *vec;
    uint32_t dim;
    row_label *labels;
    uint32_t n, cap;
    char **contents;
    uint32_t n_contents;
} train_state;

static void state_free(train_state *ts)
{
    if (!ts)
        return;
    for (uint32_t i = 0; i < ts->n; i++) {
        if (ts->motions)
            affect_motion_free(ts->motions[i]);
        sqlite3_free(ts->labels[i].text);
    }
    sqlite3_free(ts->motions);
    sqlite3_free(ts->vec);
    sqlite3_free(ts->labels);
    for (uint32_t i = 0; i < ts->n_order; i++)
        sqlite3_free(ts->order[i]);
    sqlite3_free(ts->order);
    for (uint32_t i = 0; i < ts->n_contents; i++)
        sqlite3_free(ts->contents[i]);
    sqlite3_free(ts->contents);
    sqlite3_free(ts->label_key);
    sqlite3_free(ts->content_key);
    sqlite3_free(ts->progress);
    sqlite3_free(ts->opts_text.text);
    sqlite3_free(ts);
}

static char *dup_text(const char *s, size_t n)
{
    char *d = sqlite3_malloc64(n + 1);
    if (d) {
        memcpy(d, s, n);
        d[n] = '\0';
    }
    return d;
}

static const char *const strength_keys[] = {
    "order",    "pairs",       "label",    "content",     "fraction", "similar",
    "C",        "seed",        "progress", "keyframes",   "pca_dims", "regression",
    "relative", "standardize", "features", "descriptors", NULL};
static const char *const rank_keys[] = {"order",    "pairs",    "label", "content",
                                        "fraction", "similar",  "C",     "seed",
                                        "progress", "clusters", NULL};

static ax_arg read_options(sqlite3_context *ctx, int argc, sqlite3_value **argv, int opt_i,
                           train_state *ts)
{
    affect_strength_options_default(&ts->so);
    ts->clusters = 1;
    if (ax_opts_text_keep(ctx, argc, argv, opt_i, &ts->opts_text) != AX_OK)
        return AX_ERROR;
    ts->have_opts = true;
    ax_opts opts;
    if (ax_opts_parse(ctx, argc, argv, opt_i, ts->vectors ? rank_keys : strength_keys, &opts) !=
        AX_OK)
        return AX_ERROR;
    ax_arg r = AX_ERROR;
    double seed = 0;
    const char *lk = "label", *ck = "content";
    int pairs = 0, reg = 0, feat = (int)ts->so.features;
    static const char *const pair_choices[] = {"all", "same_content", NULL};
    static const char *const reg_choices[] = {"auto", "kernel_ridge", "local_linear", NULL};
    static const char *const feat_choices[] = {"keyframes", "laban", "both", "fisher", NULL};
    static const char *const desc_choices[] = {"none", "kinematics", "laban", "all", NULL};
    int desc = (int)ts->so.descriptors;
    if (ax_opt_enum(ctx, &opts, "pairs", pair_choices, &pairs) ||
        ax_opt_string(ctx, &opts, "label", &lk) || ax_opt_string(ctx, &opts, "content", &ck) ||
        ax_opt_number(ctx, &opts, "fraction", &ts->so.fraction) ||
        ax_opt_bool(ctx, &opts, "similar", &ts->so.similar) ||
        ax_opt_number(ctx, &opts, "C", &ts->so.C) ||
        ax_opt_whole(ctx, &opts, "seed", 9007199254740992.0, &seed))
        goto done;
    if (!ts->vectors && (ax_opt_u32(ctx, &opts, "keyframes", &ts->so.keyframes) ||
                         ax_opt_u32(ctx, &opts, "pca_dims", &ts->so.pca_dims) ||
                         ax_opt_enum(ctx, &opts, "regression", reg_choices, &reg) ||
                         ax_opt_bool(ctx, &opts, "relative", &ts->so.relative) ||
                         ax_opt_bool(ctx, &opts, "standardize", &ts->so.standardize) ||
                         ax_opt_enum(ctx, &opts, "features", feat_choices, &feat) ||
                         ax_opt_enum(ctx, &opts, "descriptors", desc_choices, &desc)))
        goto done;
    ts->so.features = (affect_strength_feature_kind)feat;
    ts->so.descriptors = (unsigned)desc; /* the list's order is the mask's */
    if (ax_opt(&opts, "descriptors") && ts->so.features != AFFECT_STRENGTH_FEAT_FISHER) {
        ax_errorf(ctx, "option \"descriptors\" needs \"features\": \"fisher\"");
        goto done;
    }
    if (!ts->vectors && ax_opt(&opts, "C"))
        ts->so.cv_C = false; /* a C given is used as it is */
    if (ts->vectors && ax_opt_u32(ctx, &opts, "clusters", &ts->clusters))
        goto done;
    ts->so.seed = (uint64_t)seed;
    ts->so.regression = (affect_strength_regression)reg;
    ts->same_content = pairs == 1;
    if (!(ts->so.fraction > 0 && ts->so.fraction <= 1)) {
        ax_errorf(ctx, "option \"fraction\" must be in (0, 1], got %g", ts->so.fraction);
        goto done;
    }
    if (!(ts->so.C > 0)) {
        ax_errorf(ctx, "option \"C\" must be > 0, got %g", ts->so.C);
        goto done;
    }
    if (!ts->vectors && (ts->so.keyframes < 2 || ts->so.keyframes > AFFECT_KEYFRAMES_MAX)) {
        ax_errorf(ctx, "option \"keyframes\" must be from 2 to %u, got %u", AFFECT_KEYFRAMES_MAX,
                  ts->so.keyframes);
        goto done;
    }
    if (!ts->vectors && ts->so.pca_dims > AFFECT_STRENGTH_MAX_PCA) {
        ax_errorf(ctx, "option \"pca_dims\" must be from 0 to %u, got %u", AFFECT_STRENGTH_MAX_PCA,
                  ts->so.pca_dims);
        goto done;
    }
    if (ts->vectors && (ts->clusters < 1 || ts->clusters > AFFECT_RANK_MAX_CLUSTERS)) {
        ax_errorf(ctx, "option \"clusters\" must be from 1 to %u, got %u", AFFECT_RANK_MAX_CLUSTERS,
                  ts->clusters);
        goto done;
    }
    ts->label_key = dup_text(lk, strlen(lk));
    ts->content_key = dup_text(ck, strlen(ck));
    const char *prog = NULL;
    if (ax_opt_string(ctx, &opts, "progress", &prog))
        goto done;
    if (prog && !(ts->progress = dup_text(prog, strlen(prog)))) {
        sqlite3_result_error_nomem(ctx);
        goto done;
    }
    if (!ts->label_key || !ts->content_key) {
        sqlite3_result_error_nomem(ctx);
        goto done;
    }
    const affect_json_node *order = ax_opt(&opts, "order");
    if (order) {
        bool ok = order->type == AFFECT_JSON_ARRAY && order->count >= 2 &&
                  order->count <= AFFECT_STRENGTH_MAX_LEVELS;
        for (const affect_json_node *e = ok ? affect_json_first(opts.doc, order) : NULL; e && ok;
             e = affect_json_next_sibling(opts.doc, e))
            ok = e->type == AFFECT_JSON_STRING && e->str_len > 0 && strlen(e->str) == e->str_len;
        if (ok) {
            ts->order = sqlite3_malloc64(sizeof(char *) * order->count);
            if (!ts->order) {
                sqlite3_result_error_nomem(ctx);
                goto done;
            }
            for (const affect_json_node *e = affect_json_first(opts.doc, order); e;
                 e = affect_json_next_sibling(opts.doc, e)) {
                for (uint32_t k = 0; k < ts->n_order; k++)
                    if (strcmp(ts->order[k], e->str) == 0)
                        ok = false;
                char *d = dup_text(e->str, e->str_len);
                if (!d) {
                    sqlite3_result_error_nomem(ctx);
                    goto done;
                }
                ts->order[ts->n_order++] = d;
            }
        }
        if (!ok) {
            ax_errorf(ctx,
                      "option \"order\" must be an array of 2 to %u distinct non-empty "
                      "labels",
                      AFFECT_STRENGTH_MAX_LEVELS);
            goto done;
        }
    }
    r = AX_OK;
done:
    ax_opts_free(&opts);
    return r;
}

/* The content index of text s (added when new). */
static ax_arg content_index(sqlite3_context *ctx, train_state *ts, const char *s, size_t n,
                            uint32_t *out)
{
    for (uint32_t k = 0; k < ts->n_contents; k++)
        if (strlen(ts->contents[k]) == n && memcmp(ts->contents[k], s, n) == 0) {
            *out = k;
            return AX_OK;
        }
    char **c = sqlite3_realloc64(ts->contents, sizeof(char *) * ((uint64_t)ts->n_contents + 1));
    if (!c) {
        sqlite3_result_error_nomem(ctx);
        return AX_ERROR;
    }
    ts->contents = c;
    if (!(c[ts->n_contents] = dup_text(s, n))) {
        sqlite3_result_error_nomem(ctx);
        return AX_ERROR;
    }
    *out = ts->n_contents++;
    return AX_OK;
}

/* Reads the label argument: AX_NULL for a NULL label (row skipped). */
static ax_arg read_label(sqlite3_context *ctx, sqlite3_value *v, train_state *ts, row_label *lb)
{
    memset(lb, 0, sizeof *lb);
    int type = sqlite3_value_type(v);
    if (type == SQLITE_NULL)
        return AX_NULL;
    if (type == SQLITE_INTEGER || type == SQLITE_FLOAT) {
        lb->num = sqlite3_value_double(v);
        if (!isfinite(lb->num)) {
            ax_errorf(ctx, "row %" PRIu64 ": the label must be finite", ts->rows);
            return AX_ERROR;
        }
    } else if (type == SQLITE_TEXT) {
        const char *t = (const char *)sqlite3_value_text(v);
        size_t len = (size_t)sqlite3_value_bytes(v);
        if (!t) {
            sqlite3_result_error_nomem(ctx);
            return AX_ERROR;
        }
        if (len > 0 && t[0] == '{') {
            affect_json_doc *doc;
            affect_error err;
            if (affect_json_parse(t, len, &doc, NULL, &err)) {
                if (err.status == AFFECT_ERR_NOMEM)
                    sqlite3_result_error_nomem(ctx);
                else
                    ax_errorf(ctx, "row %" PRIu64 ": the label is not valid JSON: %s", ts->rows,
                              err.msg);
                return AX_ERROR;
            }
            const affect_json_node *root = affect_json_root(doc);
            const affect_json_node *l =
                root->type == AFFECT_JSON_OBJECT ? affect_json_get(doc, root, ts->label_key) : NULL;
            const affect_json_node *c = root->type == AFFECT_JSON_OBJECT
                                            ? affect_json_get(doc, root, ts->content_key)
                                            : NULL;
            ax_arg r = AX_OK;
            if (!l || l->type == AFFECT_JSON_NULL) {
                r = AX_NULL;
            } else if (l->type == AFFECT_JSON_NUMBER) {
                lb->num = l->num;
            } else if (l->type == AFFECT_JSON_STRING) {
                if (!(lb->text = dup_text(l->str, l->str_len))) {
                    sqlite3_result_error_nomem(ctx);
                    r = AX_ERROR;
                }
            } else {
                ax_errorf(ctx, "row %" PRIu64 ": the label's \"%s\" must be a string or a number",
                          ts->rows, ts->label_key);
                r = AX_ERROR;
            }
            if (r == AX_OK && ts->same_content) {
                char num[32];
                const char *cs = NULL;
                size_t cn = 0;
                if (c && c->type == AFFECT_JSON_STRING) {
                    cs = c->str;
                    cn = c->str_len;
                } else if (c && c->type == AFFECT_JSON_NUMBER) {
                    cn = (size_t)affect_format_g(num, sizeof num, 17, c->num);
                    cs = num;
                }
                if (!cs) {
                    ax_errorf(ctx,
                              "row %" PRIu64 ": \"pairs\": \"same_content\" needs the "
                              "label's \"%s\" (a string or a number)",
                              ts->rows, ts->content_key);
                    r = AX_ERROR;
                } else {
                    r = content_index(ctx, ts, cs, cn, &lb->content);
                }
            }
            affect_json_free(doc);
            if (r != AX_OK) {
                sqlite3_free(lb->text);
                lb->text = NULL;
            }
            return r;
        }
        if (!(lb->text = dup_text(t, len))) {
            sqlite3_result_error_nomem(ctx);
            return AX_ERROR;
        }
    } else {
        ax_errorf(ctx, "argument 2 (the label) must be text or a number, got %s", ax_type_name(v));
        return AX_ERROR;
    }
    if (ts->same_content) {
        ax_errorf(ctx,
                  "row %" PRIu64 ": \"pairs\": \"same_content\" needs labels as JSON "
                  "objects with a \"%s\"",
                  ts->rows, ts->content_key);
        sqlite3_free(lb->text);
        lb->text = NULL;
        return AX_ERROR;
    }
    return AX_OK;
}

static ax_arg grow(sqlite3_context *ctx, train_state *ts)
{
    if (ts->n < ts->cap)
        return AX_OK;
    if (ts->cap >= UINT32_MAX / 2) {
        ax_errorf(ctx, "row %" PRIu64 ": too many rows", ts->rows);
        return AX_ERROR;
    }
    uint32_t cap = ts->cap ? ts->cap * 2 : 16;
    row_label *l = sqlite3_realloc64(ts->labels, sizeof *l * (uint64_t)cap);
    if (!l) {
        sqlite3_result_error_nomem(ctx);
        return AX_ERROR;
    }
    ts->labels = l;
    if (ts->vectors) {
        double *v = sqlite3_realloc64(ts->vec, sizeof(double) * (uint64_t)cap * ts->dim);
        if (!v) {
            sqlite3_result_error_nomem(ctx);
            return AX_ERROR;
        }
        ts->vec = v;
    } else {
        affect_motion **m = sqlite3_realloc64(ts->motions, sizeof *m * (uint64_t)cap);
        if (!m) {
            sqlite3_result_error_nomem(ctx);
            return AX_ERROR;
        }
        ts->motions = m;
    }
    ts->cap = cap;
    return AX_OK;
}

/* A float32 vector argument (little-endian, the sqlite-vec convention) into doubles. */
static ax_arg arg_vector(sqlite3_context *ctx, sqlite3_value **argv, int i, const char *what,
                         const unsigned char **data, uint32_t *dim)
{
    sqlite3_value *v = argv[i];
    if (sqlite3_value_type(v) == SQLITE_NULL)
        return AX_NULL;
    if (sqlite3_value_type(v) != SQLITE_BLOB) {
        ax_errorf(ctx, "argument %d must be a float32 vector BLOB, got %s", i + 1, ax_type_name(v));
        return AX_ERROR;
    }
    int n = sqlite3_value_bytes(v);
    *data = sqlite3_value_blob(v);
    if (n == 0 || n % 4 != 0 || (uint32_t)n / 4 > AFFECT_RANK_MAX_DIM) {
        ax_errorf(ctx, "argument %d must be a float32 vector BLOB (%s), got %d bytes", i + 1, what,
                  n);
        return AX_ERROR;
    }
    if (!*data) {
        sqlite3_result_error_nomem(ctx);
        return AX_ERROR;
    }
    *dim = (uint32_t)n / 4;
    return AX_OK;
}

static void train_step(sqlite3_context *ctx, int argc, sqlite3_value **argv, bool vectors)
{
    train_state **slot = sqlite3_aggregate_context(ctx, (int)sizeof *slot);
    if (!slot) {
        sqlite3_result_error_nomem(ctx);
        return;
    }
    train_state *ts = *slot;
    if (ts && ts->failed)
        return;
    if (!ts) {
        ts = sqlite3_malloc64(sizeof *ts);
        if (!ts) {
            sqlite3_result_error_nomem(ctx);
            return;
        }
        memset(ts, 0, sizeof *ts);
        ts->vectors = vectors;
        *slot = ts;
        if (read_options(ctx, argc, argv, 2, ts) != AX_OK) {
            ts->failed = true;
            return;
        }
    } else if (ax_opts_text_same(ctx, argc, argv, 2, &ts->opts_text) != AX_OK) {
        ts->failed = true;
        return;
    }
    ts->rows++;
    affect_motion *m = NULL;
    const unsigned char *vd = NULL;
    uint32_t dim = 0;
    ax_arg r = vectors ? arg_vector(ctx, argv, 0, "4 bytes per value", &vd, &dim)
                       : ax_arg_motion(ctx, argv, 0, &m);
    if (r == AX_ERROR) {
        ts->failed = true;
        return;
    }
    if (r == AX_NULL)
        return;
    row_label lb;
    r = read_label(ctx, argv[1], ts, &lb);
    if (r != AX_OK) {
        affect_motion_free(m);
        if (r == AX_ERROR)
            ts->failed = true;
        return;
    }
    if (vectors) {
        if (ts->n == 0 && ts->cap == 0)
            ts->dim = dim;
        if (dim != ts->dim) {
            ax_errorf(ctx, "row %" PRIu64 ": the vector has %u dimensions, the first %u", ts->rows,
                      dim, ts->dim);
            goto fail;
        }
    } else {
        uint32_t q = ts->so.keyframes;
        if (m->n_frames < q) {
            ax_errorf(ctx,
                      "row %" PRIu64 ": the motion has %u frames, fewer than the %u "
                      "keyframes",
                      ts->rows, m->n_frames, q);
            goto fail;
        }
        if (ts->n > 0) {
            const affect_motion *f = ts->motions[0];
            bool same = m->n_joints == f->n_joints;
            for (uint32_t j = 0; same && j < m->n_joints; j++)
                same = strcmp(m->names[j], f->names[j]) == 0;
            if (!same) {
                ax_errorf(ctx,
                          "row %" PRIu64 ": the motion's joints differ from the first "
                          "motion's (%u joints, the first has %u)",
                          ts->rows, m->n_joints, f->n_joints);
                goto fail;
            }
        }
    }
    if (grow(ctx, ts) != AX_OK)
        goto fail;
    if (vectors) {
        double *x = ts->vec + (size_t)ts->n * ts->dim;
        for (uint32_t k = 0; k < dim; k++) {
            x[k] = ax_get_f32(vd + 4 * (size_t)k);
            if (!isfinite(x[k])) {
                ax_errorf(ctx, "row %" PRIu64 ": value %u of the vector is not finite", ts->rows,
                          k);
                goto fail;
            }
        }
    } else {
        ts->motions[ts->n] = m;
        m = NULL;
    }
    ts->labels[ts->n++] = lb;
    return;
fail:
    affect_motion_free(m);
    sqlite3_free(lb.text);
    ts->failed = true;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* Levels of the rows and the level names (pointers into ts or into numbuf). */
static ax_arg assign_levels(sqlite3_context *ctx, train_state *ts, int32_t *level,
                            const char **names, char (*numbuf)[32], uint32_t *n_levels)
{
    if (ts->n_order > 0) {
        for (uint32_t i = 0; i < ts->n; i++) {
            char num[32];
            const char *t = ts->labels[i].text;
            if (!t) { /* a number matches its shortest text form ("0.2") */
                affect_format_g(num, sizeof num, 15, ts->labels[i].num);
                t = num;
            }
            level[i] = -1;
            for (uint32_t k = 0; k < ts->n_order; k++)
                if (strcmp(t, ts->order[k]) == 0)
                    level[i] = (int32_t)k;
        }
        for (uint32_t k = 0; k < ts->n_order; k++)
            names[k] = ts->order[k];
        *n_levels = ts->n_order;
        return AX_OK;
    }
    double *vals = sqlite3_malloc64(sizeof(double) * (uint64_t)ts->n);
    if (!vals) {
        sqlite3_result_error_nomem(ctx);
        return AX_ERROR;
    }
    for (uint32_t i = 0; i < ts->n; i++) {
        if (ts->labels[i].text) {
            ax_errorf(ctx, "labels must be numbers when no \"order\" is given (got \"%s\")",
                      ts->labels[i].text);
            sqlite3_free(vals);
            return AX_ERROR;
        }
        vals[i] = ts->labels[i].num;
    }
    qsort(vals, ts->n, sizeof(double), cmp_double);
    uint32_t d = 0;
    for (uint32_t i = 0; i < ts->n; i++)
        if (d == 0 || vals[i] != vals[d - 1])
            vals[d++] = vals[i];
    if (d > AFFECT_STRENGTH_MAX_LEVELS) {
        ax_errorf(ctx, "at most %u distinct label values (got %u)", AFFECT_STRENGTH_MAX_LEVELS, d);
        sqlite3_free(vals);
        return AX_ERROR;
    }
    for (uint32_t i = 0; i < ts->n; i++)
        for (uint32_t k = 0; k < d; k++)
            if (ts->labels[i].num == vals[k])
                level[i] = (int32_t)k;
    for (uint32_t k = 0; k < d; k++) {
        affect_format_g(numbuf[k], sizeof numbuf[k], 15, vals[k]);
        names[k] = numbuf[k];
    }
    *n_levels = d;
    sqlite3_free(vals);
    return AX_OK;
}

static void train_final(sqlite3_context *ctx, bool vectors)
{
    train_state **slot = sqlite3_aggregate_context(ctx, 0);
    train_state *ts = slot ? *slot : NULL;
    int32_t *level = NULL;
    uint32_t *group = NULL;
    const char **names = NULL;
    char(*numbuf)[32] = NULL;
    affect_rank_pair *pairs = NULL;
    if (!ts || ts->failed || ts->n == 0) {
        if (!ts || !ts->failed)
            sqlite3_result_null(ctx);
        goto done;
    }
    level = sqlite3_malloc64(sizeof *level * (uint64_t)ts->n);
    group = sqlite3_malloc64(sizeof *group * (uint64_t)ts->n);
    names = sqlite3_malloc64(sizeof *names * AFFECT_STRENGTH_MAX_LEVELS);
    numbuf = sqlite3_malloc64(sizeof *numbuf * AFFECT_STRENGTH_MAX_LEVELS);
    if (!level || !group || !names || !numbuf) {
        sqlite3_result_error_nomem(ctx);
        goto done;
    }
    uint32_t n_levels;
    if (assign_levels(ctx, ts, level, names, numbuf, &n_levels) != AX_OK)
        goto done;
    if (n_levels < 2) {
        ax_errorf(ctx, "the rows need at least 2 different labels (got %u)", n_levels);
        goto done;
    }
    for (uint32_t i = 0; i < ts->n; i++)
        group[i] = ts->labels[i].content;
    ax_monitor am;
    if (ax_monitor_begin(&am, ctx, ts->progress) != AX_OK)
        goto done;
    affect_error err;
    affect_status st;
    unsigned char *blob = NULL;
    size_t size = 0;
    if (vectors) {
        size_t n_pairs;
        affect_ranker *rk = NULL;
        st = affect_rank_pairs(level, ts->same_content ? group : NULL, ts->n, ts->so.similar,
                               ts->so.fraction, ts->so.seed, &pairs, &n_pairs, &err);
        if (st == AFFECT_OK) {
            affect_rank_options ro;
            affect_rank_options_default(&ro);
            ro.C = ts->so.C;
            ro.clusters = ts->clusters;
            ro.seed = ts->so.seed;
            ro.monitor = &am.mon;
            st = affect_ranker_train(ts->vec, ts->n, ts->dim, pairs, n_pairs, &ro, &rk, &err);
        }
        if (st == AFFECT_OK)
            st = affect_ranker_encode(rk, &blob, &size, &err);
        affect_ranker_free(rk);
    } else {
        affect_strength *s = NULL;
        ts->so.monitor = &am.mon;
        st = affect_strength_train((const affect_motion *const *)ts->motions, level,
                                   ts->same_content ? group : NULL, ts->n, names, n_levels, &ts->so,
                                   &s, &err);
        if (st == AFFECT_OK)
            st = affect_strength_encode(s, &blob, &size, &err);
        affect_strength_free(s);
    }
    ax_monitor_end(&am);
    if (st != AFFECT_OK)
        ax_error(ctx, &err);
    else
        sqlite3_result_blob64(ctx, blob, size, sqlite3_free);
done:
    affect_free(pairs);
    sqlite3_free(level);
    sqlite3_free(group);
    sqlite3_free(names);
    sqlite3_free(numbuf);
    state_free(ts);
    if (slot)
        *slot = NULL;
}

void ax_strength_train_step(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    train_step(ctx, argc, argv, false);
}

void ax_strength_train_final(sqlite3_context *ctx)
{
    train_final(ctx, false);
}

void ax_rank_train_step(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    train_step(ctx, argc, argv, true);
}

void ax_rank_train_final(sqlite3_context *ctx)
{
    train_final(ctx, true);
}

/* ---- models as arguments (decoded once for a constant argument) ---- */

static void strength_aux_free(void *p)
{
    affect_strength_free(p);
}

static void ranker_aux_free(void *p)
{
    affect_ranker_free(p);
}

/* Argument 0 as a strength model (or ranker): *cached tells whether SQLite owns it. */
static ax_arg arg_model(sqlite3_context *ctx, sqlite3_value **argv, bool ranker, void **out,
                        bool *cached)
{
    *out = NULL;
    *cached = false;
    sqlite3_value *v = argv[0];
    int type = sqlite3_value_type(v);
    if (type == SQLITE_NULL)
        return AX_NULL;
    const char *kind =
        ranker ? "ranker BLOB (from rank_train)" : "strength model BLOB (from strength_train)";
    if (type != SQLITE_BLOB) {
        ax_errorf(ctx, "argument 1 must be a %s, got %s", kind, ax_type_name(v));
        return AX_ERROR;
    }
    void *aux = sqlite3_get_auxdata(ctx, 0);
    if (aux) {
        *out = aux;
        *cached = true;
        return AX_OK;
    }
    const unsigned char *data = sqlite3_value_blob(v);
    int n = sqlite3_value_bytes(v);
    if (!data && n > 0) {
        sqlite3_result_error_nomem(ctx);
        return AX_ERROR;
    }
    affect_error err;
    affect_status st = ranker
                           ? affect_ranker_decode(data, (size_t)n, (affect_ranker **)out, &err)
                           : affect_strength_decode(data, (size_t)n, (affect_strength **)out, &err);
    if (st != AFFECT_OK) {
        if (err.status == AFFECT_ERR_NOMEM)
            ax_error(ctx, &err);
        else
            ax_errorf(ctx, "argument 1 is not a valid %s: %s", ranker ? "ranker" : "strength model",
                      err.msg);
        return AX_ERROR;
    }
    return AX_OK;
}

static void model_done(sqlite3_context *ctx, void *model, bool cached, bool ranker)
{
    if (model && !cached)
        sqlite3_set_auxdata(ctx, 0, model, ranker ? ranker_aux_free : strength_aux_free);
}

/* ---- affect_strength: the model kept per function and connection ---- */

static affect_status decode_strength(const unsigned char *data, size_t size, void **out,
                                     affect_error *err)
{
    affect_strength *s = NULL;
    affect_status st = affect_strength_decode(data, size, &s, err);
    *out = s;
    return st;
}

/* The model is decoded again only when the argument's bytes change, so one call per statement
 * (an application scoring motions one at a time) does not decode and checksum it each time. */
AX_FN(ax_affect_strength)
{
    (void)argc;
    ax_cached_fn *fn = sqlite3_user_data(ctx);
    const void *mv;
    if (ax_arg_cached_blob(ctx, argv, &fn->cache, decode_strength, strength_aux_free,
                           "strength model", "strength_train", &mv) != AX_OK)
        return;
    const affect_strength *s = mv;
    affect_motion *m = NULL;
    ax_monitor am;
    if (ax_arg_motion(ctx, argv, 1, &m) == AX_OK && ax_monitor_begin(&am, ctx, NULL) == AX_OK) {
        affect_error err;
        double v;
        affect_status st = affect_strength_score(s, m, &v, &am.mon, &err);
        ax_monitor_end(&am);
        if (st)
            ax_error(ctx, &err);
        else
            sqlite3_result_double(ctx, v);
    }
    affect_motion_free(m);
}

/* A strength argument: a number, or a label of the model's order (its mean strength). */
static ax_arg arg_strength(sqlite3_context *ctx, sqlite3_value **argv, int i,
                           const affect_strength *s, double *out)
{
    sqlite3_value *v = argv[i];
    int type = sqlite3_value_type(v);
    if (type == SQLITE_NULL)
        return AX_NULL;
    if (type == SQLITE_TEXT) {
        const char *t = (const char *)sqlite3_value_text(v);
        if (!t) {
            sqlite3_result_error_nomem(ctx);
            return AX_ERROR;
        }
        for (uint32_t l = 0; l < s->n_levels; l++)
            if (strcmp(t, s->level_names[l]) == 0 && s->level_count[l] > 0) {
                *out = s->level_strength[l];
                return AX_OK;
            }
        char q[64];
        affect_json_quote(q, sizeof q, t, strlen(t));
        ax_errorf(ctx, "argument %d: %s is not a trained label of the model", i + 1, q);
        return AX_ERROR;
    }
    return ax_arg_double(ctx, argv, i, out);
}

static const char *const synth_keys[] = {"rigid", NULL};

static void synth_or_edit(sqlite3_context *ctx, int argc, sqlite3_value **argv, bool edit)
{
    void *mv;
    bool cached;
    if (arg_model(ctx, argv, false, &mv, &cached) != AX_OK)
        return;
    affect_strength *s = mv;
    affect_motion *m = NULL, *out = NULL;
    ax_opts opts = {0};
    double target;
    int si = edit ? 2 : 1;
    if (edit && ax_arg_motion(ctx, argv, 1, &m) != AX_OK)
        goto done;
    if (arg_strength(ctx, argv, si, s, &target) != AX_OK)
        goto done;
    bool rigid = true;
    if (ax_opts_parse(ctx, argc, argv, si + 1, synth_keys, &opts) != AX_OK ||
        ax_opt_bool(ctx, &opts, "rigid", &rigid) != AX_OK)
        goto done;
    ax_monitor am;
    if (ax_monitor_begin(&am, ctx, NULL) != AX_OK)
        goto done;
    affect_error err;
    affect_status st = edit ? affect_strength_edit(s, m, target, rigid, &out, &am.mon, &err)
                            : affect_strength_synthesize(s, target, rigid, &out, &am.mon, &err);
    ax_monitor_end(&am);
    if (st)
        ax_error(ctx, &err);
    else
        ax_result_motion(ctx, out);
done:
    ax_opts_free(&opts);
    affect_motion_free(m);
    affect_motion_free(out);
    model_done(ctx, s, cached, false);
}

AX_FN(ax_strength_synthesize)
{
    synth_or_edit(ctx, argc, argv, false);
}

AX_FN(ax_strength_edit)
{
    synth_or_edit(ctx, argc, argv, true);
}

static void json_num(affect_strbuf *sb, const char *key, double v, bool comma)
{
    affect_strbuf_printf(sb, "%s\"%s\":", comma ? "," : "", key);
    if (isfinite(v))
        affect_strbuf_double(sb, v);
    else
        affect_strbuf_puts(sb, "null");
}

AX_FN(ax_strength_info)
{
    (void)argc;
    void *mv;
    bool cached;
    if (arg_model(ctx, argv, false, &mv, &cached) != AX_OK)
        return;
    affect_strength *s = mv;
    static const char *const reg_names[] = {"auto", "kernel_ridge", "local_linear"};
    static const char *const feat_names[] = {"keyframes", "laban", "both", "fisher"};
    affect_strbuf sb;
    affect_strbuf_init(&sb);
    affect_strbuf_printf(&sb, "{\"version\":%u,\"motions\":%u,\"joints\":%u,\"keyframes\":%u",
                         s->features == AFFECT_STRENGTH_FEAT_KEYFRAMES ? 1u
                         : s->features == AFFECT_STRENGTH_FEAT_FISHER  ? 3u
                                                                       : 2u,
                         s->n_train, s->n_joints, s->keyframes);
    json_num(&sb, "fps", s->fps, true);
    affect_strbuf_printf(&sb, ",\"features\":%u,\"pca\":", s->dim);
    if (s->pca) {
        affect_strbuf_printf(&sb, "{\"dims\":%u", s->pdim);
        json_num(&sb, "variance", s->pca_variance, true);
        affect_strbuf_putc(&sb, '}');
    } else {
        affect_strbuf_puts(&sb, "null");
    }
    affect_strbuf_printf(&sb, ",\"ranker\":{\"features\":\"%s\",\"dims\":%u",
                         feat_names[s->features], affect_strength_rank_dim(s));
    if (s->features == AFFECT_STRENGTH_FEAT_BOTH)
        json_num(&sb, "keyframe_weight", s->kf_weight, true);
    if (s->fisher) {
        static const char *const desc_names[] = {"none", "kinematics", "laban", "all"};
        affect_strbuf_printf(&sb, ",\"descriptors\":\"%s\"",
                             desc_names[affect_classifier_get_config(s->fisher)->descriptors & 3u]);
    }
    json_num(&sb, "C", s->C, true);
    affect_strbuf_printf(
        &sb, ",\"C_cross_validated\":%s,\"loss\":\"%s\"", s->cv_C ? "true" : "false",
        s->features == AFFECT_STRENGTH_FEAT_KEYFRAMES || s->features == AFFECT_STRENGTH_FEAT_FISHER
            ? "sum"
            : "mean");
    affect_strbuf_printf(&sb, ",\"ordered_pairs\":%" PRIu64 ",\"similar_pairs\":%" PRIu64,
                         s->stats.ordered, s->stats.similar);
    json_num(&sb, "training_accuracy",
             s->stats.ordered ? (double)s->stats.correct / (double)s->stats.ordered : NAN, true);
    affect_strbuf_printf(&sb, ",\"newton_iterations\":%u,\"converged\":%s", s->stats.iterations,
                         s->stats.converged ? "true" : "false");
    json_num(&sb, "objective", s->stats.objective, true);
    double ww = 0;
    for (uint32_t c = 0; c < affect_strength_rank_dim(s); c++)
        ww += s->w[c] * s->w[c];
    json_num(&sb, "w_norm", sqrt(ww), true);
    affect_strbuf_puts(&sb, "},\"levels\":[");
    for (uint32_t l = 0; l < s->n_levels; l++) {
        affect_strbuf_puts(&sb, l ? ",{\"label\":" : "{\"label\":");
        affect_strbuf_json_string(&sb, s->level_names[l]);
        affect_strbuf_printf(&sb, ",\"motions\":%u", s->level_count[l]);
        json_num(&sb, "strength", s->level_count[l] ? s->level_strength[l] : NAN, true);
        affect_strbuf_putc(&sb, '}');
    }
    double lo = INFINITY, hi = -INFINITY;
    for (uint32_t i = 0; i < s->n_train; i++) {
        lo = fmin(lo, s->train_r[i]);
        hi = fmax(hi, s->train_r[i]);
    }
    affect_strbuf_puts(&sb, "],\"strength_range\":[");
    affect_strbuf_double(&sb, lo);
    affect_strbuf_putc(&sb, ',');
    affect_strbuf_double(&sb, hi);
    affect_strbuf_printf(&sb, "],\"regression\":{\"method\":\"%s\"", reg_names[s->regression]);
    json_num(&sb, "bandwidth", s->reg_h, true);
    if (s->regression == AFFECT_STRENGTH_REG_KERNEL_RIDGE)
        json_num(&sb, "ridge", s->reg_lambda, true);
    affect_strbuf_puts(&sb, ",\"cv_error\":{");
    json_num(&sb, "kernel_ridge", s->cv_kernel_ridge, false);
    json_num(&sb, "local_linear", s->cv_local_linear, true);
    json_num(&sb, "constant", s->cv_constant, true);
    affect_strbuf_puts(&sb, "}}}");
    ax_result_json_buffer(ctx, &sb);
    model_done(ctx, s, cached, false);
}

AX_FN(ax_motion_keyframes)
{
    affect_motion *m = NULL;
    if (ax_arg_motion(ctx, argv, 0, &m) != AX_OK)
        return;
    int64_t q = AFFECT_KEYFRAMES_DEFAULT;
    uint32_t *frames = NULL;
    if (argc > 1) {
        ax_arg r = ax_arg_int(ctx, argv, 1, &q);
        if (r != AX_OK)
            goto done;
        if (q < 2 || q > AFFECT_KEYFRAMES_MAX) {
            ax_errorf(ctx, "argument 2 (keyframes) must be from 2 to %u, got %" PRId64,
                      AFFECT_KEYFRAMES_MAX, q);
            goto done;
        }
    }
    uint32_t nk = (uint32_t)q < m->n_frames ? (uint32_t)q : m->n_frames;
    frames = sqlite3_malloc64(sizeof *frames * (uint64_t)(nk ? nk : 1));
    if (!frames) {
        sqlite3_result_error_nomem(ctx);
        goto done;
    }
    ax_monitor am;
    if (ax_monitor_begin(&am, ctx, NULL) != AX_OK)
        goto done;
    affect_error err;
    double rms = 0;
    uint32_t n = 0;
    affect_status st = affect_motion_keyframes(m, (uint32_t)q, frames, &n, &rms, &am.mon, &err);
    ax_monitor_end(&am);
    if (st) {
        ax_error(ctx, &err);
        goto done;
    }
    affect_strbuf sb;
    affect_strbuf_init(&sb);
    affect_strbuf_printf(&sb, "{\"frames\":%u,\"keyframes\":[", m->n_frames);
    for (uint32_t k = 0; k < n; k++)
        affect_strbuf_printf(&sb, k ? ",%u" : "%u", frames[k]);
    affect_strbuf_puts(&sb, "],\"times\":[");
    for (uint32_t k = 0; k < n; k++) {
        if (k)
            affect_strbuf_putc(&sb, ',');
        affect_strbuf_double(&sb, frames[k] / m->fps);
    }
    affect_strbuf_puts(&sb, "],\"interpolation\":\"linear\"");
    json_num(&sb, "rms_error", rms, true);
    affect_strbuf_puts(&sb, ",\"unit\":");
    affect_strbuf_json_string(&sb, m->unit);
    affect_strbuf_putc(&sb, '}');
    ax_result_json_buffer(ctx, &sb);
done:
    sqlite3_free(frames);
    affect_motion_free(m);
}

AX_FN(ax_rank_score)
{
    (void)argc;
    void *mv;
    bool cached;
    if (arg_model(ctx, argv, true, &mv, &cached) != AX_OK)
        return;
    affect_ranker *r = mv;
    const unsigned char *vd;
    uint32_t dim;
    double *x = NULL;
    if (arg_vector(ctx, argv, 1, "4 bytes per value", &vd, &dim) != AX_OK)
        goto done;
    if (dim != r->dim) {
        ax_errorf(ctx, "the vector has %u dimensions, the ranker %u", dim, r->dim);
        goto done;
    }
    x = sqlite3_malloc64(sizeof(double) * (uint64_t)dim);
    if (!x) {
        sqlite3_result_error_nomem(ctx);
        goto done;
    }
    for (uint32_t k = 0; k < dim; k++) {
        x[k] = ax_get_f32(vd + 4 * (size_t)k);
        if (!isfinite(x[k])) {
            ax_errorf(ctx, "value %u of the vector is not finite", k);
            goto done;
        }
    }
    sqlite3_result_double(ctx, affect_ranker_score(r, x));
done:
    sqlite3_free(x);
    model_done(ctx, r, cached, true);
}
