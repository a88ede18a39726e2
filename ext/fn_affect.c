/*
 * fn_affect.c — SQL wrappers of the emotion recognizer (core: affect/classifier.h; SCIENCE.md
 * §3, thesis chapter 4):
 *
 *   affect_train(motion, label [, options])  aggregate → classifier BLOB
 *   affect_classify(classifier, motion [, method])   → label ('svm' default, 'knn', 'ml')
 *   affect_scores(classifier, motion)        → JSON: per class the HMM log-likelihood, SVM
 *                                               decision values and votes, kNN votes; the
 *                                               three labels; the sPCA coordinates
 *   fisher_score(classifier, motion)         → float32 vector BLOB: the normalized Fisher
 *                                               representation the SVM sees
 *   affect_embed(classifier, motion)         → float32 vector BLOB: sPCA coordinates
 *   affect_info(classifier)                  → JSON: classes, dimensions, configuration,
 *                                               training report
 *   affect_salience(classifier)              → JSON: per class HMM, state and mixture, the
 *                                               largest sPCA weight among its covariance
 *                                               scores and the top entries (thesis Fig. 4.6)
 *
 * affect_train's options (the same text on every row): hmm_train's (states, mixtures,
 * covariance, topology, max_jump, start, joints, normalize, scale, up, velocity, max_iter, tol,
 * reg, seed) and groups (an array of "start", "transitions", "weights", "means",
 * "covariances", or "all"), score_normalization ("zscore" | "none"), score_clip (z-scores
 * limited to ± this, default 5, 0 = no limit), svm_c (a positive number
 * or "auto"), svm_folds, spca_dims, spca_kernel ("linear" | "rbf"), spca_sigma, knn_k, and
 * grid: {"spca_dims": [...], "spca_sigma": [...], "knn_k": [...], "folds": n} to choose those
 * three by inner cross-validation on the training motions (see affect/classifier.h), and
 * storage ("auto" | "float32" | "compact": how the BLOB stores its long vectors, docs/FORMATS.md;
 * auto = compact from 65,536 dimensions). Rows
 * whose motion or label is NULL are skipped; labels are compared as text, and the classes are
 * ordered by their text (byte order), whatever the row order.
 *
 * Decoding a classifier BLOB (tens of MB for full-body models) is not free, so every function
 * keeps the last classifier it decoded on this connection, with a copy of its bytes: a call
 * whose BLOB is byte-identical (memcmp) reuses it. Joins such as
 *   SELECT affect_classify(c.model, m.motion) FROM classifiers c, motions m
 * therefore decode once.
 *
 * Errors: "affect_classify: argument 1 must be a classifier BLOB (from affect_train), got text",
 * "affect_info: argument 1 is not a valid classifier: classifier checksum mismatch: the BLOB is
 * corrupt", "affect_classify: method must be 'svm', 'knn' or 'ml', got 'x'",
 * "affect_train: row 3: label must be text or a number, got a BLOB",
 * "affect_train: need motions of at least 2 labels, got 1 (\"sad\")", and the core's messages.
 */
#include "fn_affect.h"

#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "affect/classifier.h"
#include "affect/crossval.h"
#include "fn_fda.h"
#include "util/strbuf.h"
#include "seqs.h"

/* ---- affect_train ---- */

static const char *const train_keys[] = {
    AX_SEQS_KEYS, "groups",      "score_normalization", "score_clip", "svm_c",
    "svm_folds",  "spca_dims",   "spca_kernel",         "spca_sigma", "knn_k",
    "grid",       "descriptors", "descriptor_weight",   "mirror",     "threads",
    "storage",    NULL};

typedef struct cls_train {
    ax_labelled l; /* first: the sequences and their labels (seqs.h) */
    affect_classifier_config cfg;
    double grid_dims[AFFECT_CLASSIFIER_GRID_MAX], grid_sigma[AFFECT_CLASSIFIER_GRID_MAX],
        grid_k[AFFECT_CLASSIFIER_GRID_MAX];
} cls_train;

static void cls_train_free(cls_train *t)
{
    ax_labelled_free(t ? &t->l : NULL); /* frees t itself */
}

/* The "groups" option into a mask. */
static ax_arg opt_groups(sqlite3_context *ctx, const ax_opts *opts, unsigned *groups)
{
    static const char *const names[] = {"start", "transitions", "weights", "means", "covariances"};
    const affect_json_node *n = ax_opt(opts, "groups");
    if (!n)
        return AX_OK;
    if (n->type == AFFECT_JSON_STRING && strcmp(n->str, "all") == 0) {
        *groups = AFFECT_FISHER_ALL;
        return AX_OK;
    }
    if (n->type != AFFECT_JSON_ARRAY || n->count == 0)
        goto bad;
    unsigned mask = 0;
    for (const affect_json_node *e = affect_json_first(opts->doc, n); e;
         e = affect_json_next_sibling(opts->doc, e)) {
        if (e->type != AFFECT_JSON_STRING)
            goto bad;
        unsigned bit = 0;
        for (unsigned g = 0; g < 5; g++)
            if (strcmp(e->str, names[g]) == 0)
                bit = 1u << g;
        if (!bit) {
            ax_errorf(ctx,
                      "option \"groups\": unknown group \"%s\" (start, transitions, "
                      "weights, means, covariances)",
                      e->str);
            return AX_ERROR;
        }
        mask |= bit;
    }
    *groups = mask;
    return AX_OK;
bad:
    ax_errorf(ctx, "option \"groups\" must be \"all\" or a non-empty array of group names "
                   "(start, transitions, weights, means, covariances)");
    return AX_ERROR;
}

/* An array of numbers (at most AFFECT_CLASSIFIER_GRID_MAX) of the grid object. */
static ax_arg grid_list(sqlite3_context *ctx, const ax_opts *opts, const affect_json_node *grid,
                        const char *key, double *v, uint32_t *n)
{
    const affect_json_node *a = NULL;
    for (const affect_json_node *e = affect_json_first(opts->doc, grid); e;
         e = affect_json_next_sibling(opts->doc, e))
        if (strcmp(e->key, key) == 0)
            a = e;
    if (!a)
        return AX_OK;
    if (a->type != AFFECT_JSON_ARRAY || a->count == 0 || a->count > AFFECT_CLASSIFIER_GRID_MAX) {
        ax_errorf(ctx, "option \"grid\": \"%s\" must be an array of 1 to %u numbers", key,
                  AFFECT_CLASSIFIER_GRID_MAX);
        return AX_ERROR;
    }
    uint32_t i = 0;
    for (const affect_json_node *e = affect_json_first(opts->doc, a); e;
         e = affect_json_next_sibling(opts->doc, e)) {
        if (e->type != AFFECT_JSON_NUMBER) {
            ax_errorf(ctx, "option \"grid\": \"%s\" must be an array of 1 to %u numbers", key,
                      AFFECT_CLASSIFIER_GRID_MAX);
            return AX_ERROR;
        }
        v[i++] = e->num;
    }
    *n = i;
    return AX_OK;
}

static ax_arg opt_grid(sqlite3_context *ctx, const ax_opts *opts, cls_train *t)
{
    static const char *const keys[] = {"spca_dims", "spca_sigma", "knn_k", "folds", NULL};
    const affect_json_node *g = ax_opt(opts, "grid");
    if (!g)
        return AX_OK;
    if (g->type != AFFECT_JSON_OBJECT) {
        ax_errorf(ctx, "option \"grid\" must be an object, got %s", affect_json_type_name(g->type));
        return AX_ERROR;
    }
    for (const affect_json_node *e = affect_json_first(opts->doc, g); e;
         e = affect_json_next_sibling(opts->doc, e)) {
        bool known = false;
        for (int k = 0; keys[k]; k++)
            known = known || strcmp(e->key, keys[k]) == 0;
        if (!known) {
            ax_errorf(ctx,
                      "option \"grid\": unknown key \"%s\" (spca_dims, spca_sigma, knn_k, "
                      "folds)",
                      e->key);
            return AX_ERROR;
        }
        if (strcmp(e->key, "folds") == 0) {
            if (e->type != AFFECT_JSON_NUMBER || e->num != floor(e->num) || e->num < 2 ||
                e->num > 1000) {
                ax_errorf(ctx, "option \"grid\": \"folds\" must be a whole number from 2 to 1000");
                return AX_ERROR;
            }
            t->cfg.grid.folds = (uint32_t)e->num;
        }
    }
    affect_classifier_grid *gr = &t->cfg.grid;
    if (grid_list(ctx, opts, g, "spca_dims", t->grid_dims, &gr->n_dims) ||
        grid_list(ctx, opts, g, "spca_sigma", t->grid_sigma, &gr->n_sigma) ||
        grid_list(ctx, opts, g, "knn_k", t->grid_k, &gr->n_k))
        return AX_ERROR;
    /* a value that is not a whole number in range becomes 0, which the configuration check
     * refuses ("grid knn_k must be whole numbers of at least 1") */
    for (uint32_t i = 0; i < gr->n_dims; i++) {
        double v = t->grid_dims[i];
        gr->dims[i] = v >= 1 && v <= 1000 && v == floor(v) ? (uint32_t)v : 0;
    }
    for (uint32_t i = 0; i < gr->n_k; i++) {
        double v = t->grid_k[i];
        gr->k[i] = v >= 1 && v <= 100000 && v == floor(v) ? (uint32_t)v : 0;
    }
    for (uint32_t i = 0; i < gr->n_sigma; i++)
        gr->sigma[i] = t->grid_sigma[i];
    return AX_OK;
}

/* The "mirror" option: true, false or "auto". */
static ax_arg opt_mirror(sqlite3_context *ctx, const ax_opts *opts, affect_classifier_mirror *m)
{
    const affect_json_node *n = ax_opt(opts, "mirror");
    if (!n)
        return AX_OK;
    if (n->type == AFFECT_JSON_TRUE || n->type == AFFECT_JSON_FALSE) {
        *m = n->type == AFFECT_JSON_TRUE ? AFFECT_MIRROR_ON : AFFECT_MIRROR_OFF;
        return AX_OK;
    }
    if (n->type == AFFECT_JSON_STRING && strcmp(n->str, "auto") == 0) {
        *m = AFFECT_MIRROR_AUTO;
        return AX_OK;
    }
    ax_errorf(ctx, "option \"mirror\" must be true, false or \"auto\"");
    return AX_ERROR;
}

/* The classifier keys of the first row's options. */
static ax_arg read_classifier_options(sqlite3_context *ctx, const ax_opts *opts, cls_train *t)
{
    static const char *const norms[] = {"zscore", "none", NULL};
    static const char *const kernels[] = {"linear", "rbf", NULL};
    static const char *const descs[] = {"none", "kinematics", "laban", "all", NULL};
    static const char *const storages[] = {"auto", "float32", "compact", NULL};
    affect_classifier_config *cfg = &t->cfg;
    int desc = (int)cfg->descriptors, storage = (int)cfg->storage;
    int norm = cfg->zscore ? 0 : 1, kernel = cfg->spca_kernel == AFFECT_SPCA_RBF;
    const affect_json_node *c = ax_opt(opts, "svm_c");
    if (c) {
        if (c->type == AFFECT_JSON_STRING && strcmp(c->str, "auto") == 0) {
            cfg->svm_c = 0;
        } else if (c->type == AFFECT_JSON_NUMBER && c->num > 0 && isfinite(c->num)) {
            cfg->svm_c = c->num;
        } else {
            ax_errorf(ctx, "option \"svm_c\" must be a positive number or \"auto\"");
            return AX_ERROR;
        }
    }
    if (opt_groups(ctx, opts, &cfg->groups) ||
        ax_opt_enum(ctx, opts, "score_normalization", norms, &norm) ||
        ax_opt_number(ctx, opts, "score_clip", &cfg->score_clip) ||
        ax_opt_u32(ctx, opts, "svm_folds", &cfg->svm_folds) ||
        ax_opt_u32(ctx, opts, "spca_dims", &cfg->spca_dims) ||
        ax_opt_enum(ctx, opts, "spca_kernel", kernels, &kernel) ||
        ax_opt_number(ctx, opts, "spca_sigma", &cfg->spca_sigma) ||
        ax_opt_u32(ctx, opts, "knn_k", &cfg->knn_k) || opt_grid(ctx, opts, t) ||
        ax_opt_enum(ctx, opts, "descriptors", descs, &desc) ||
        ax_opt_number(ctx, opts, "descriptor_weight", &cfg->descriptor_weight) ||
        opt_mirror(ctx, opts, &cfg->mirror) ||
        ax_opt_enum(ctx, opts, "storage", storages, &storage))
        return AX_ERROR;
    cfg->storage = (affect_classifier_storage)storage; /* the list's order is the enum's */
    cfg->descriptors = (unsigned)desc;                 /* the list's order is the mask's */
    t->l.s.desc_mask = cfg->descriptors;
    cfg->zscore = norm == 0;
    cfg->spca_kernel = kernel ? AFFECT_SPCA_RBF : AFFECT_SPCA_LINEAR;
    cfg->hmm = t->l.s.cfg;
    const char *msg = affect_classifier_config_check(cfg);
    if (msg) {
        ax_errorf(ctx, "%s", msg);
        return AX_ERROR;
    }
    return AX_OK;
}

/* The first row: the recognizer's defaults and the options. */
static ax_arg train_first(sqlite3_context *ctx, int argc, sqlite3_value **argv, ax_labelled *l)
{
    cls_train *t = (cls_train *)l;
    affect_classifier_config_default(&t->cfg);
    t->l.s.cfg = t->cfg.hmm; /* the recognizer's defaults, not the HMM's own */
    affect_classifier_features_default(&t->l.s.fo);
    t->l.s.preset = true;
    ax_opts opts;
    if (ax_seqs_options(ctx, argc, argv, 2, train_keys, &t->l.s, &opts) != AX_OK)
        return AX_ERROR;
    ax_arg r = read_classifier_options(ctx, &opts, t);
    if (r == AX_OK) /* affect_train's own: affect_crossval's threads run folds */
        r = ax_opt_u32(ctx, &opts, "threads", &t->cfg.threads);
    if (r == AX_OK && (t->cfg.threads < 1 || t->cfg.threads > 64)) {
        ax_errorf(ctx, "option \"threads\" must be from 1 to 64, got %u", t->cfg.threads);
        r = AX_ERROR;
    }
    ax_opts_free(&opts);
    return r;
}

static int cmp_text(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

/* Trains on the rows and sets the encoded classifier as the result. */
static void train_model(sqlite3_context *ctx, ax_labelled *l, char *const *classes,
                        uint32_t n_classes, const uint32_t *y)
{
    cls_train *t = (cls_train *)l;
    affect_classifier *c = NULL;
    affect_error err;
    t->cfg.hmm = t->l.s.cfg;
    ax_monitor am;
    if (ax_monitor_begin(&am, ctx, t->l.s.progress) != AX_OK)
        return;
    t->cfg.hmm.monitor = &am.mon;
    affect_status st =
        affect_classifier_train(&t->cfg, t->l.s.feat, t->l.s.seqs, t->l.s.desc, y, t->l.s.n_seqs,
                                (const char *const *)classes, n_classes, &c, &err);
    ax_monitor_end(&am);
    unsigned char *blob;
    size_t size;
    if (st || affect_classifier_encode(c, &blob, &size, &err))
        ax_error(ctx, &err);
    else
        sqlite3_result_blob64(ctx, blob, size, sqlite3_free);
    affect_classifier_free(c);
}

static const ax_labelled_kind train_kind = {sizeof(cls_train), train_first, train_model};

void ax_affect_train_step(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    ax_labelled_step(ctx, argc, argv, &train_kind);
}

void ax_affect_train_final(sqlite3_context *ctx)
{
    ax_labelled_final(ctx, &train_kind);
}

/* ---- the classifier argument, with the per-function cache ---- */

static affect_status decode_model(const unsigned char *data, size_t size, void **out,
                                  affect_error *err)
{
    affect_classifier *m = NULL;
    affect_status st = affect_classifier_decode(data, size, &m, err);
    *out = m;
    return st;
}

static void free_model(void *m)
{
    affect_classifier_free(m);
}

/* The classifier of argument 0: the cached one when the bytes are the same, else decoded
 * (and cached). */
static ax_arg arg_classifier(sqlite3_context *ctx, sqlite3_value **argv,
                             const affect_classifier **out)
{
    ax_cached_fn *fn = sqlite3_user_data(ctx);
    const void *m;
    ax_arg r = ax_arg_cached_blob(ctx, argv, &fn->cache, decode_model, free_model, "classifier",
                                  "affect_train", &m);
    *out = m;
    return r;
}

/* The observations of the motion in argument 1 under the classifier's definition. */
static ax_arg arg_observations(sqlite3_context *ctx, sqlite3_value **argv,
                               const affect_classifier *c, double **x, uint32_t *n_frames,
                               double **desc)
{
    affect_motion *m = NULL;
    ax_arg r = ax_arg_motion(ctx, argv, 1, &m);
    if (r != AX_OK)
        return r;
    affect_error err;
    ax_monitor am;
    if ((r = ax_monitor_begin(&am, ctx, NULL)) == AX_OK) {
        if (affect_classifier_observe(c, m, x, n_frames, desc, &am.mon, &err)) {
            ax_error(ctx, &err);
            r = AX_ERROR;
        }
        ax_monitor_end(&am);
    }
    affect_motion_free(m);
    return r;
}

/* Buffers for everything affect_classifier_eval gives. */
typedef struct eval_buf {
    affect_classifier_out o;
    void *block;
} eval_buf;

static affect_status eval_all(const affect_classifier *c, const double *x, uint32_t T,
                              const double *desc, bool ml_only, bool want_fisher, eval_buf *b,
                              affect_monitor *mon, affect_error *err)
{
    uint32_t C = affect_classifier_n_classes(c), p = affect_spca_dims(affect_classifier_spca(c));
    size_t D = want_fisher ? affect_classifier_dim(c) : 0, pairs = (size_t)C * (C - 1) / 2;
    size_t doubles = C + D + pairs + p;
    memset(b, 0, sizeof *b);
    b->block = affect_malloc_array(doubles + C, sizeof(double));
    if (!b->block)
        return affect_nomem(err);
    double *d = b->block;
    b->o.loglik = d;
    b->o.fisher = want_fisher ? d + C : NULL;
    b->o.decision = d + C + D;
    b->o.embed = d + C + D + pairs;
    b->o.votes = (uint32_t *)(void *)(d + doubles);
    return affect_classifier_eval(c, x, T, desc, ml_only, &b->o, mon, err);
}

static ax_arg evaluate(sqlite3_context *ctx, sqlite3_value **argv, bool ml_only, bool want_fisher,
                       const affect_classifier **c, eval_buf *b)
{
    double *x = NULL, *desc = NULL;
    uint32_t T = 0;
    memset(b, 0, sizeof *b);
    ax_arg r = arg_classifier(ctx, argv, c);
    if (r == AX_OK)
        r = arg_observations(ctx, argv, *c, &x, &T, &desc);
    ax_monitor am;
    if (r == AX_OK)
        r = ax_monitor_begin(&am, ctx, NULL);
    if (r == AX_OK) {
        affect_error err;
        if (eval_all(*c, x, T, desc, ml_only, want_fisher, b, &am.mon, &err)) {
            ax_error(ctx, &err);
            r = AX_ERROR;
        }
        ax_monitor_end(&am);
    }
    affect_free(x);
    affect_free(desc);
    return r;
}

void ax_affect_classify(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    static const char *const methods[] = {"svm", "knn", "ml", NULL};
    int method = 0;
    if (argc > 2 && sqlite3_value_type(argv[2]) != SQLITE_NULL) {
        const char *m = (const char *)sqlite3_value_text(argv[2]);
        method = -1;
        for (int i = 0; m && methods[i]; i++)
            if (strcmp(m, methods[i]) == 0)
                method = i;
        if (method < 0) {
            if (!m && sqlite3_value_type(argv[2]) == SQLITE_TEXT)
                sqlite3_result_error_nomem(ctx);
            else
                ax_errorf(ctx, "method must be 'svm', 'knn' or 'ml', got '%s'", m ? m : "");
            return;
        }
    }
    const affect_classifier *c;
    eval_buf b;
    if (evaluate(ctx, argv, method == 2, false, &c, &b) == AX_OK) {
        uint32_t k = method == 0 ? b.o.svm : method == 1 ? b.o.knn : b.o.ml;
        sqlite3_result_text(ctx, affect_classifier_label(c, k), -1, SQLITE_TRANSIENT);
    }
    affect_free(b.block);
}

void ax_affect_scores(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    (void)argc;
    const affect_classifier *c;
    eval_buf b;
    if (evaluate(ctx, argv, false, false, &c, &b) == AX_OK) {
        uint32_t C = affect_classifier_n_classes(c);
        uint32_t p = affect_spca_dims(affect_classifier_spca(c));
        affect_strbuf sb;
        affect_strbuf_init(&sb);
        affect_strbuf_puts(&sb, "{\"label\":{\"svm\":");
        affect_strbuf_json_string(&sb, affect_classifier_label(c, b.o.svm));
        affect_strbuf_puts(&sb, ",\"knn\":");
        affect_strbuf_json_string(&sb, affect_classifier_label(c, b.o.knn));
        affect_strbuf_puts(&sb, ",\"ml\":");
        affect_strbuf_json_string(&sb, affect_classifier_label(c, b.o.ml));
        affect_strbuf_puts(&sb, "},\"classes\":{");
        uint32_t svm_votes[AFFECT_SVM_MAX_CLASSES];
        affect_svm_vote(b.o.decision, C, svm_votes);
        for (uint32_t k = 0; k < C; k++) {
            if (k)
                affect_strbuf_putc(&sb, ',');
            affect_strbuf_json_string(&sb, affect_classifier_label(c, k));
            affect_strbuf_puts(&sb, ":{\"loglik\":");
            affect_strbuf_double(&sb, b.o.loglik[k]);
            affect_strbuf_puts(&sb, ",\"decision\":{");
            bool first = true;
            for (uint32_t q = 0; q < C; q++) {
                if (q == k)
                    continue;
                uint32_t lo = k < q ? k : q, hi = k < q ? q : k;
                double v = b.o.decision[affect_svm_pair_index(affect_classifier_svm(c), lo, hi)];
                double mine = k == lo ? v : -v; /* positive: k wins against q */
                if (!first)
                    affect_strbuf_putc(&sb, ',');
                first = false;
                affect_strbuf_json_string(&sb, affect_classifier_label(c, q));
                affect_strbuf_putc(&sb, ':');
                affect_strbuf_double(&sb, mine);
            }
            affect_strbuf_printf(&sb, "},\"svm_votes\":%u,\"knn_votes\":%u}", svm_votes[k],
                                 b.o.votes[k]);
        }
        affect_strbuf_puts(&sb, "},\"embedding\":");
        ax_json_doubles(&sb, b.o.embed, p);
        affect_strbuf_putc(&sb, '}');
        ax_result_json_buffer(ctx, &sb);
    }
    affect_free(b.block);
}

void ax_fisher_score(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    (void)argc;
    const affect_classifier *c;
    eval_buf b;
    if (evaluate(ctx, argv, false, true, &c, &b) == AX_OK)
        ax_result_f32(ctx, b.o.fisher, affect_classifier_dim(c));
    affect_free(b.block);
}

void ax_affect_embed(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    (void)argc;
    const affect_classifier *c;
    eval_buf b;
    if (evaluate(ctx, argv, false, false, &c, &b) == AX_OK)
        ax_result_f32(ctx, b.o.embed, affect_spca_dims(affect_classifier_spca(c)));
    affect_free(b.block);
}

/* ---- affect_info ---- */

static void put_groups(affect_strbuf *sb, unsigned groups)
{
    affect_strbuf_putc(sb, '[');
    bool first = true;
    for (unsigned g = 1; g <= AFFECT_FISHER_COVS; g <<= 1)
        if (groups & g) {
            affect_strbuf_puts(sb, first ? "" : ",");
            affect_strbuf_json_string(sb, affect_fisher_group_name(g));
            first = false;
        }
    affect_strbuf_putc(sb, ']');
}

static void put_number_or_null(affect_strbuf *sb, double v)
{
    if (isfinite(v))
        affect_strbuf_double(sb, v);
    else
        affect_strbuf_puts(sb, "null");
}

void ax_affect_info(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    (void)argc;
    const affect_classifier *c;
    if (arg_classifier(ctx, argv, &c) != AX_OK)
        return;
    const affect_classifier_config *cfg = affect_classifier_get_config(c);
    const affect_svm *svm = affect_classifier_svm(c);
    const affect_spca *sp = affect_classifier_spca(c);
    uint32_t C = affect_classifier_n_classes(c), n = affect_classifier_n_train(c);
    const uint32_t *ty = affect_classifier_train_labels(c);
    affect_classifier_report rep;
    affect_classifier_get_report(c, &rep);
    affect_strbuf sb;
    affect_strbuf_init(&sb);
    /* the version the classifier encodes as: 3 for the compact storage, else 2 */
    affect_strbuf_printf(&sb, "{\"format\":%u,\"classes\":[",
                         affect_classifier_get_config(c)->storage == AFFECT_STORAGE_COMPACT
                             ? AFFECT_CLASSIFIER_VERSION
                             : 2u);
    for (uint32_t k = 0; k < C; k++) {
        affect_strbuf_puts(&sb, k ? "," : "");
        affect_strbuf_json_string(&sb, affect_classifier_label(c, k));
    }
    affect_strbuf_printf(&sb, "],\"training_motions\":%u,\"per_class\":{", n);
    for (uint32_t k = 0; k < C; k++) {
        uint32_t count = 0;
        for (uint32_t i = 0; i < n; i++)
            count += ty[i] == k;
        affect_strbuf_puts(&sb, k ? "," : "");
        affect_strbuf_json_string(&sb, affect_classifier_label(c, k));
        affect_strbuf_printf(&sb, ":%u", count);
    }
    static const char *const descs[] = {"none", "kinematics", "laban", "all"};
    uint32_t dd = affect_descriptors_dim(cfg->descriptors);
    affect_strbuf_printf(&sb,
                         "},\"mirror\":%s,\"dimensions\":{\"observation\":%u,"
                         "\"per_hmm\":%zu,\"fisher\":%zu,\"descriptors\":%u,"
                         "\"representation\":%zu,\"spca\":%u},\"descriptors\":\"%s\","
                         "\"descriptor_weight\":",
                         cfg->mirror == AFFECT_MIRROR_ON ? "true" : "false", cfg->hmm.dim,
                         affect_classifier_part_dim(c), affect_classifier_dim(c) - dd, dd,
                         affect_classifier_dim(c), affect_spca_dims(sp),
                         descs[cfg->descriptors & 3u]);
    affect_strbuf_double(&sb, cfg->descriptor_weight);
    affect_strbuf_puts(&sb, ",\"hmm\":");
    ax_json_hmm_config(&sb, &cfg->hmm);
    affect_strbuf_puts(&sb, ",\"features\":");
    ax_json_features(&sb, affect_classifier_features(c));
    affect_strbuf_puts(&sb, ",\"groups\":");
    put_groups(&sb, cfg->groups);
    affect_strbuf_printf(
        &sb, ",\"score_normalization\":\"%s\",\"score_clip\":", cfg->zscore ? "zscore" : "none");
    affect_strbuf_double(&sb, cfg->score_clip);
    affect_strbuf_puts(&sb, ",\"svm\":{\"C\":");
    affect_strbuf_double(&sb, rep.svm_c);
    affect_strbuf_printf(&sb, ",\"C_chosen_by\":\"%s\",\"cv_accuracy\":",
                         cfg->svm_c > 0 ? "option" : "cross-validation");
    put_number_or_null(&sb, rep.svm_cv_acc);
    affect_strbuf_printf(&sb, ",\"support_vectors\":%u},\"spca\":{\"kernel\":\"%s\",\"sigma\":",
                         affect_svm_total_sv(svm),
                         affect_spca_get_kernel(sp) == AFFECT_SPCA_RBF ? "rbf" : "linear");
    affect_strbuf_double(&sb, affect_spca_sigma(sp));
    affect_strbuf_printf(&sb, ",\"dims\":%u,\"eigenvalues\":", affect_spca_dims(sp));
    ax_json_doubles(&sb, affect_spca_eigenvalues(sp), affect_spca_dims(sp));
    affect_strbuf_printf(&sb, "},\"knn_k\":%u,\"training_accuracy\":{\"ml\":", cfg->knn_k);
    put_number_or_null(&sb, rep.train_acc_ml);
    affect_strbuf_puts(&sb, ",\"svm\":");
    put_number_or_null(&sb, rep.train_acc_svm);
    affect_strbuf_puts(&sb, ",\"knn_leave_one_out\":");
    put_number_or_null(&sb, rep.train_acc_knn);
    affect_strbuf_puts(&sb, "}}");
    ax_result_json_buffer(ctx, &sb);
}

/* ---- affect_crossval_json (the engine of the affect_crossval table) ---- */

static const char *const cv_keys[] = {AX_SEQS_KEYS,
                                      "groups",
                                      "score_normalization",
                                      "score_clip",
                                      "svm_c",
                                      "svm_folds",
                                      "spca_dims",
                                      "spca_kernel",
                                      "spca_sigma",
                                      "knn_k",
                                      "grid",
                                      "folds",
                                      "descriptors",
                                      "descriptor_weight",
                                      "mirror",
                                      "group",
                                      "methods",
                                      "verbose",
                                      "threads",
                                      "storage",
                                      "dims",
                                      "basis",
                                      "order",
                                      "lambda",
                                      "sigma",
                                      "ffda_reg",
                                      "isomap_k",
                                      "alignment",
                                      NULL};

typedef struct cv_state {
    cls_train t;   /* first (freed through cls_train_free) */
    char **groups; /* one per sequence, or NULL entries (k-fold) */
    uint32_t folds;
    unsigned methods;      /* bit m = AFFECT_CV_* */
    affect_fda_config fda; /* the functional methods' options */
    bool verbose;
    uint32_t threads;
} cv_state;

static void cv_state_free(cv_state *s)
{
    if (!s)
        return;
    for (uint32_t i = 0; s->groups && i < s->t.l.s.n_seqs; i++)
        affect_free(s->groups[i]);
    affect_free(s->groups);
    cls_train_free(&s->t); /* frees s */
}

static ax_arg read_cv_options(sqlite3_context *ctx, const ax_opts *opts, cv_state *s)
{
    s->folds = 10;
    s->methods = AFFECT_CV_RECOGNIZER_MASK;
    s->threads = 1;
    affect_fda_config_default(&s->fda);
    if (ax_fda_read_options(ctx, opts, &s->fda) != AX_OK)
        return AX_ERROR;
    if (ax_opt_u32(ctx, opts, "folds", &s->folds) ||
        ax_opt_bool(ctx, opts, "verbose", &s->verbose) ||
        ax_opt_u32(ctx, opts, "threads", &s->threads))
        return AX_ERROR;
    if (s->threads < 1 || s->threads > 64) {
        ax_errorf(ctx, "option \"threads\" must be from 1 to 64, got %u", s->threads);
        return AX_ERROR;
    }
    if (s->threads > 1 && !sqlite3_threadsafe()) {
        ax_errorf(ctx, "option \"threads\" needs SQLite built thread-safe (this one is "
                       "SQLITE_THREADSAFE=0)");
        return AX_ERROR;
    }
    if (s->folds < 2 || s->folds > 1024) {
        ax_errorf(ctx, "option \"folds\" must be from 2 to 1024, got %u", s->folds);
        return AX_ERROR;
    }
    const affect_json_node *g = ax_opt(opts, "group");
    if (g && g->type != AFFECT_JSON_STRING) {
        ax_errorf(ctx, "option \"group\" must be a column name");
        return AX_ERROR;
    }
    const affect_json_node *m = ax_opt(opts, "methods");
    if (!m)
        return AX_OK;
    if (m->type != AFFECT_JSON_ARRAY || m->count == 0)
        goto bad;
    s->methods = 0;
    for (const affect_json_node *e = affect_json_first(opts->doc, m); e;
         e = affect_json_next_sibling(opts->doc, e)) {
        unsigned bit = 0;
        for (unsigned k = 0; k < AFFECT_CV_METHODS; k++)
            if (e->type == AFFECT_JSON_STRING && strcmp(e->str, affect_cv_method_name(k)) == 0)
                bit = 1u << k;
        if (!bit)
            goto bad;
        s->methods |= bit;
    }
    return AX_OK;
bad:
    ax_errorf(ctx, "option \"methods\" must be a non-empty array of \"ml\", \"svm\", \"knn\", "
                   "\"fpca\", \"ffda\", \"fspca\", \"fspca_rbf\", \"fisomap\"");
    return AX_ERROR;
}

void ax_affect_crossval_step(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    cv_state **slot = sqlite3_aggregate_context(ctx, (int)sizeof *slot);
    if (!slot) {
        sqlite3_result_error_nomem(ctx);
        return;
    }
    cv_state *s = *slot;
    if (s && s->t.l.s.failed)
        return;
    if (!s) {
        s = sqlite3_malloc64(sizeof *s);
        if (!s) {
            sqlite3_result_error_nomem(ctx);
            return;
        }
        memset(s, 0, sizeof *s);
        *slot = s;
        s->t.l.s.rows++;
        affect_classifier_config_default(&s->t.cfg);
        s->t.l.s.cfg = s->t.cfg.hmm; /* the recognizer's defaults, not the HMM's own */
        affect_classifier_features_default(&s->t.l.s.fo);
        s->t.l.s.preset = true;
        ax_opts opts;
        if (ax_seqs_options(ctx, argc, argv, 3, cv_keys, &s->t.l.s, &opts) != AX_OK) {
            s->t.l.s.failed = true;
            return;
        }
        ax_arg r = read_classifier_options(ctx, &opts, &s->t);
        if (r == AX_OK)
            r = read_cv_options(ctx, &opts, s);
        /* the functional methods alone train no HMM: any motion length is theirs to judge */
        s->t.l.s.any_length = !(s->methods & AFFECT_CV_RECOGNIZER_MASK);
        ax_opts_free(&opts);
        if (r != AX_OK) {
            s->t.l.s.failed = true;
            return;
        }
    } else {
        s->t.l.s.rows++;
    }
    uint32_t before = s->t.l.s.n_seqs;
    if (ax_labelled_add(ctx, argc, argv, &s->t.l) != AX_OK) {
        s->t.l.s.failed = true;
        return;
    }
    if (s->t.l.s.n_seqs == before)
        return;
    char **groups = affect_realloc(s->groups, (size_t)s->t.l.s.cap * sizeof *groups);
    if (!groups) { /* keep groups, labels and sequences paired */
        affect_free(s->t.l.labels[before]);
        affect_free((void *)s->t.l.s.seqs[before].x);
        s->t.l.s.n_seqs = before;
        sqlite3_result_error_nomem(ctx);
        s->t.l.s.failed = true;
        return;
    }
    s->groups = groups;
    s->groups[before] = NULL;
    if (sqlite3_value_type(argv[2]) == SQLITE_BLOB) { /* the group names go into the JSON */
        ax_errorf(ctx, "row %" PRIu64 ": group must be text or a number, got a BLOB",
                  s->t.l.s.rows);
        s->t.l.s.failed = true;
        return;
    }
    if (sqlite3_value_type(argv[2]) != SQLITE_NULL) {
        const char *g = (const char *)sqlite3_value_text(argv[2]);
        size_t len = g ? strlen(g) : 0, bad = g ? affect_utf8_invalid_at(g, len) : 0;
        if (g && (len != (size_t)sqlite3_value_bytes(argv[2]) || bad < len)) {
            if (bad < len)
                ax_errorf(ctx,
                          "row %" PRIu64 ": group is not valid UTF-8 (byte 0x%02x at offset %zu)",
                          s->t.l.s.rows, (unsigned char)g[bad], bad);
            else
                ax_errorf(ctx, "row %" PRIu64 ": group must not contain NUL", s->t.l.s.rows);
            s->t.l.s.failed = true;
            return;
        }
        s->groups[before] = g ? affect_strndup(g, len) : NULL;
        if (!s->groups[before]) {
            sqlite3_result_error_nomem(ctx);
            s->t.l.s.failed = true;
        }
    }
}

/* Distinct names of v[0 .. n) in byte order into names (*count), and each entry's index into
 * idx. */
static void distinct(char **v, uint32_t n, char **names, uint32_t *count, uint32_t *idx)
{
    memcpy(names, v, n * sizeof *names);
    qsort(names, n, sizeof *names, cmp_text);
    uint32_t k = 0;
    for (uint32_t i = 0; i < n; i++)
        if (k == 0 || strcmp(names[i], names[k - 1]) != 0)
            names[k++] = names[i];
    *count = k;
    for (uint32_t i = 0; i < n; i++)
        idx[i] = (uint32_t)((char **)bsearch(&v[i], names, k, sizeof *names, cmp_text) - names);
}

static void cv_progress(void *ctx, const char *line)
{
    (void)ctx;
    fprintf(stderr, "affect_crossval: %s\n", line);
}

static void put_matrix_u32(affect_strbuf *sb, const uint32_t *m, uint32_t C)
{
    affect_strbuf_putc(sb, '[');
    for (uint32_t r = 0; r < C; r++) {
        affect_strbuf_puts(sb, r ? ",[" : "[");
        for (uint32_t c = 0; c < C; c++)
            affect_strbuf_printf(sb, "%s%u", c ? "," : "", m[(size_t)r * C + c]);
        affect_strbuf_putc(sb, ']');
    }
    affect_strbuf_putc(sb, ']');
}

static void put_metric(affect_strbuf *sb, const char *key, double v)
{
    affect_strbuf_printf(sb, ",\"%s\":", key);
    put_number_or_null(sb, v);
}

static void cv_json(affect_strbuf *sb, const cv_state *s, const affect_cv_result *r, char **classes,
                    char **group_names, bool by_group)
{
    uint32_t C = r->n_classes;
    affect_strbuf_puts(sb, "{\"labels\":");
    ax_json_names(sb, classes, C);
    affect_strbuf_printf(sb, ",\"protocol\":\"%s\",\"rows\":[",
                         by_group ? "leave-one-group-out" : "stratified k-fold");
    bool first = true;
    for (int m = 0; m < AFFECT_CV_METHODS; m++) {
        if (!(s->methods & (1u << m)))
            continue;
        for (uint32_t f = 0; f <= r->n_folds; f++) {
            bool summary = f == r->n_folds;
            const affect_cv_fold *fd = summary ? NULL : &r->folds[f];
            affect_strbuf_puts(sb, first ? "{" : ",{");
            first = false;
            affect_strbuf_printf(sb, "\"method\":\"%s\"", affect_cv_method_name((unsigned)m));
            if (summary) {
                uint32_t n = 0;
                for (uint32_t k = 0; k < r->n_folds; k++)
                    n += r->folds[k].n_test;
                affect_strbuf_printf(sb,
                                     ",\"fold\":null,\"held_out\":null,\"n_train\":null,"
                                     "\"n_test\":%u",
                                     n);
                put_metric(sb, "accuracy", r->mean_accuracy[m]);
                put_metric(sb, "balanced_accuracy", r->mean_balanced[m]);
                put_metric(sb, "macro_f1", r->mean_f1[m]);
                put_metric(sb, "accuracy_sd", r->sd_accuracy[m]);
                put_metric(sb, "balanced_accuracy_sd", r->sd_balanced[m]);
                put_metric(sb, "macro_f1_sd", r->sd_f1[m]);
                put_metric(sb, "pooled_accuracy", r->pooled_accuracy[m]);
                affect_strbuf_puts(sb, ",\"confusion\":");
                put_matrix_u32(sb, r->pooled[m], C);
                affect_strbuf_puts(sb, ",\"params\":null}");
                continue;
            }
            affect_strbuf_printf(sb, ",\"fold\":%u,\"held_out\":", fd->fold + 1);
            if (by_group)
                affect_strbuf_json_string(sb, group_names[fd->group]);
            else
                affect_strbuf_puts(sb, "null");
            affect_strbuf_printf(sb, ",\"n_train\":%u,\"n_test\":%u", fd->n_train, fd->n_test);
            put_metric(sb, "accuracy", fd->accuracy[m]);
            put_metric(sb, "balanced_accuracy", fd->balanced[m]);
            put_metric(sb, "macro_f1", fd->f1[m]);
            affect_strbuf_puts(sb, ",\"accuracy_sd\":null,\"balanced_accuracy_sd\":null,"
                                   "\"macro_f1_sd\":null,\"pooled_accuracy\":null,\"confusion\":");
            put_matrix_u32(sb, fd->confusion[m], C);
            affect_strbuf_puts(sb, ",\"params\":");
            if (m == AFFECT_CV_SVM) {
                affect_strbuf_puts(sb, "{\"svm_c\":");
                affect_strbuf_double(sb, fd->svm_c);
                affect_strbuf_putc(sb, '}');
            } else if (m == AFFECT_CV_KNN) {
                affect_strbuf_printf(sb, "{\"spca_dims\":%u,\"spca_sigma\":", fd->spca_dims);
                affect_strbuf_double(sb, fd->spca_sigma);
                affect_strbuf_printf(sb, ",\"knn_k\":%u}", fd->knn_k);
            } else if (m >= AFFECT_CV_FPCA) {
                affect_strbuf_printf(sb, "{\"dims\":%u,\"lambda\":", fd->fda_dims[m]);
                affect_strbuf_double(sb, fd->fda_lambda);
                affect_strbuf_putc(sb, '}');
            } else {
                affect_strbuf_puts(sb, "null");
            }
            affect_strbuf_putc(sb, '}');
        }
    }
    affect_strbuf_puts(sb, "]}");
}

static void cv_final(sqlite3_context *ctx, cv_state *s)
{
    uint32_t n = s->t.l.s.n_seqs, n_classes = 0, n_groups = 0, with_group = 0;
    char **classes = affect_malloc_array(n, sizeof *classes);
    char **gnames = affect_malloc_array(n, sizeof *gnames);
    uint32_t *y = affect_malloc_array(n, sizeof *y), *g = affect_malloc_array(n, sizeof *g);
    affect_cv_result *r = NULL;
    affect_error err;
    if (!classes || !gnames || !y || !g) {
        sqlite3_result_error_nomem(ctx);
        goto done;
    }
    for (uint32_t i = 0; i < n; i++)
        with_group += s->groups[i] != NULL;
    if (with_group != 0 && with_group != n) {
        ax_errorf(ctx, "the group is NULL for %u of %u motions", n - with_group, n);
        goto done;
    }
    distinct(s->t.l.labels, n, classes, &n_classes, y);
    if (n_classes < 2) {
        ax_errorf(ctx, "need motions of at least 2 labels, got 1 (\"%s\")", classes[0]);
        goto done;
    }
    if (with_group)
        distinct(s->groups, n, gnames, &n_groups, g);
    affect_cv_config cfg;
    affect_cv_config_default(&cfg);
    s->t.cfg.hmm = s->t.l.s.cfg;
    cfg.cls = s->t.cfg;
    cfg.folds = s->folds;
    cfg.seed = s->t.l.s.cfg.seed;
    cfg.threads = s->threads;
    cfg.methods = s->methods;
    cfg.fda = s->fda;
    if (s->verbose)
        cfg.progress = cv_progress;
    ax_monitor am;
    if (ax_monitor_begin(&am, ctx, s->t.l.s.progress) != AX_OK)
        goto done;
    cfg.cls.hmm.monitor = &am.mon;
    affect_status st = affect_crossval(&cfg, s->t.l.s.feat, s->t.l.s.seqs, s->t.l.s.desc, y, n,
                                       (const char *const *)classes, n_classes,
                                       with_group ? g : NULL, n_groups, &r, &err);
    ax_monitor_end(&am);
    if (st) {
        ax_error(ctx, &err);
        goto done;
    }
    affect_strbuf sb;
    affect_strbuf_init(&sb);
    cv_json(&sb, s, r, classes, gnames, with_group != 0);
    ax_result_json_buffer(ctx, &sb);
done:
    affect_cv_result_free(r);
    affect_free(classes);
    affect_free(gnames);
    affect_free(y);
    affect_free(g);
}

void ax_affect_crossval_final(sqlite3_context *ctx)
{
    cv_state **slot = sqlite3_aggregate_context(ctx, 0);
    cv_state *s = slot ? *slot : NULL;
    if (!s || s->t.l.s.failed || s->t.l.s.n_seqs == 0) {
        if (!s || !s->t.l.s.failed)
            sqlite3_result_null(ctx);
    } else {
        cv_final(ctx, s);
    }
    cv_state_free(s);
    if (slot)
        *slot = NULL;
}
