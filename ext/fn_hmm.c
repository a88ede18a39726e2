/*
 * fn_hmm.c — SQL wrappers of the hidden Markov models (core: affect/hmm.h, affect/features.h,
 * affect/hmm_blob.h; SCIENCE.md §2):
 *
 *   hmm_train(motion [, options])        aggregate → model BLOB
 *   hmm_loglik(model, motion [, options]) → real: log P(x | Λ) ({"per_frame": true}: ÷ frames)
 *   hmm_viterbi(model, motion)           → JSON array of the most likely state per frame
 *   hmm_viterbi_loglik(model, motion)    → real: log-probability of that path
 *   hmm_info(model)                      → JSON: configuration, features, training report,
 *                                          start, transitions, weights, state durations
 *   hmm_postures(model)                  → motion: one frame per state (its mean posture)
 *
 * Maximum-likelihood recognition is plain SQL:
 *   CREATE TABLE class_models AS
 *     SELECT emotion AS label, hmm_train(motion, '{"states":7,"mixtures":4}') AS model
 *       FROM motions GROUP BY emotion;
 *   SELECT label FROM class_models ORDER BY hmm_loglik(model, :m) DESC LIMIT 1;
 *
 * hmm_train's options (the same text on every row): states, mixtures, covariance ("full" |
 * "diag"), topology ("ergodic" | "left-right"), max_jump, start ("first" | "learn"), max_iter,
 * tol, reg, seed — the affect_hmm_config fields — and the observation definition: joints (an
 * array of joint or role names; default every joint of the first motion), normalize (true),
 * scale ("arm" | "none"; default arm when the first motion's right arm roles resolve), up
 * ("y"), velocity (false).
 *
 * How hmm_train works: the aggregate context holds one pointer to a train_state, allocated on
 * the first row. That row's options are parsed and checked at once; the first non-NULL motion
 * fixes the feature definition (affect_features_create); every motion is turned into its
 * observation sequence on arrival and only the sequence is kept (not the motion). xFinal
 * trains, encodes the model BLOB and frees the state. SQLite calls xFinal for every context
 * that was created, also when the statement stops early, so the state is always freed there;
 * after an error the state is marked failed and xFinal only frees. NULL motions are skipped;
 * no motion at all gives NULL.
 *
 * The scalar functions decode the model on every call, unless the model argument is a
 * compile-time constant (a bound parameter or a literal; not a subquery): then the decoded
 * model is kept as the argument's auxiliary data (sqlite3_set_auxdata) and reused for the
 * next rows.
 *
 * Errors: "hmm_loglik: argument 1 must be a model BLOB (from hmm_train), got text",
 * "hmm_info: argument 1 is not a valid model: model checksum mismatch: the BLOB is corrupt",
 * "hmm_loglik: joint \"Hand_L\" of the model is not in the motion",
 * "hmm_train: row 3: the motion has 4 frames; 5 states need at least 5",
 * "hmm_train: row 2: the motion has 60 fps, the first one 30 (resample it with
 * motion_resample)", "hmm_train: options must be the same on every row",
 * "hmm_train: option \"states\" must be a whole number, got 2.5",
 * "hmm_train: states must be between 1 and 256" (the core's configuration check).
 */
#include "fn_hmm.h"

#include <inttypes.h>
#include <math.h>
#include <string.h>

#include "affect/features.h"
#include "affect/hmm.h"
#include "affect/hmm_blob.h"
#include "affect/strbuf.h"

/* ---- options ---- */

/* A whole-number option in [0, max] into *out (unchanged when absent). */
static ax_arg opt_whole(sqlite3_context *ctx, const ax_opts *opts, const char *key, double max,
                        double *out)
{
    double v = *out;
    if (ax_opt_number(ctx, opts, key, &v) != AX_OK)
        return AX_ERROR;
    if (v != floor(v) || v < 0 || v > max) {
        char num[32];
        affect_format_g(num, sizeof num, 17, v);
        ax_errorf(ctx, "option \"%s\" must be a whole number from 0 to %.0f, got %s", key, max,
                  num);
        return AX_ERROR;
    }
    *out = v;
    return AX_OK;
}

static ax_arg opt_u32(sqlite3_context *ctx, const ax_opts *opts, const char *key,
                      uint32_t *out)
{
    double v = *out;
    if (opt_whole(ctx, opts, key, 4294967295.0, &v) != AX_OK)
        return AX_ERROR;
    *out = (uint32_t)v;
    return AX_OK;
}

static const char *const train_keys[] = {"states",   "mixtures", "covariance", "topology",
                                         "max_jump", "start",    "joints",     "normalize",
                                         "scale",    "up",       "velocity",   "max_iter",
                                         "tol",      "reg",      "seed",       NULL};

typedef struct train_state {
    bool failed;             /* an error was reported: xFinal only frees */
    char *opts_text;         /* the first row's options text, NULL when none */
    size_t opts_len;
    affect_hmm_config cfg;
    affect_features_options fo;
    char **joints;           /* fo.joints storage: copies of the "joints" option's names */
    uint32_t n_joints;
    affect_features *feat;   /* fixed by the first non-NULL motion */
    affect_hmm_seq *seqs;    /* observation sequences (each x owned) */
    uint32_t n_seqs, cap;
    uint64_t rows;           /* rows seen, NULL motions included */
} train_state;

static void train_state_free(train_state *ts)
{
    if (!ts)
        return;
    for (uint32_t i = 0; i < ts->n_seqs; i++)
        affect_free((void *)ts->seqs[i].x);
    affect_free(ts->seqs);
    for (uint32_t i = 0; i < ts->n_joints; i++)
        affect_free(ts->joints[i]);
    affect_free(ts->joints);
    affect_features_free(ts->feat);
    sqlite3_free(ts->opts_text);
    sqlite3_free(ts);
}

/* The "joints" option: a non-empty array of names, copied into ts. */
static ax_arg read_joints(sqlite3_context *ctx, const ax_opts *opts, train_state *ts)
{
    const affect_json_node *n = ax_opt(opts, "joints");
    if (!n)
        return AX_OK;
    if (n->type != AFFECT_JSON_ARRAY || n->count == 0) {
        ax_errorf(ctx, "option \"joints\" must be a non-empty array of joint or role names, "
                       "got %s", n->type == AFFECT_JSON_ARRAY ? "an empty array"
                                                              : affect_json_type_name(n->type));
        return AX_ERROR;
    }
    ts->joints = affect_calloc(n->count, sizeof *ts->joints);
    if (!ts->joints) {
        sqlite3_result_error_nomem(ctx);
        return AX_ERROR;
    }
    uint32_t i = 0;
    for (const affect_json_node *e = affect_json_first(opts->doc, n); e;
         e = affect_json_next_sibling(opts->doc, e), i++) {
        if (e->type != AFFECT_JSON_STRING || e->str_len == 0 || strlen(e->str) != e->str_len) {
            ax_errorf(ctx, "option \"joints\": entry %u must be a joint or role name, got %s",
                      i + 1, e->type == AFFECT_JSON_STRING ? "a string that is empty or "
                                                             "contains NUL"
                                                           : affect_json_type_name(e->type));
            return AX_ERROR;
        }
        ts->joints[i] = affect_strndup(e->str, e->str_len);
        if (!ts->joints[i]) {
            sqlite3_result_error_nomem(ctx);
            return AX_ERROR;
        }
        ts->n_joints = i + 1;
    }
    ts->fo.joints = (const char *const *)ts->joints;
    ts->fo.n_joints = ts->n_joints;
    return AX_OK;
}

/* Parses and checks the first row's options (argument 2) into ts. */
static ax_arg read_train_options(sqlite3_context *ctx, int argc, sqlite3_value **argv,
                                 train_state *ts)
{
    static const char *const covs[] = {"full", "diag", NULL};
    static const char *const topologies[] = {"ergodic", "left-right", NULL};
    static const char *const starts[] = {"first", "learn", NULL};
    static const char *const scales[] = {"arm", "none", NULL};
    affect_hmm_config_default(&ts->cfg);
    affect_features_options_default(&ts->fo);
    ax_opts opts;
    if (ax_opts_parse(ctx, argc, argv, 1, train_keys, &opts) != AX_OK)
        return AX_ERROR;
    int cov = (int)ts->cfg.cov, topology = (int)ts->cfg.topology, start = ts->cfg.learn_start,
        scale = -1;
    double seed = (double)ts->cfg.seed;
    ax_arg r = AX_ERROR;
    if (opt_u32(ctx, &opts, "states", &ts->cfg.n_states) ||
        opt_u32(ctx, &opts, "mixtures", &ts->cfg.n_mix) ||
        ax_opt_enum(ctx, &opts, "covariance", covs, &cov) ||
        ax_opt_enum(ctx, &opts, "topology", topologies, &topology) ||
        opt_u32(ctx, &opts, "max_jump", &ts->cfg.max_jump) ||
        ax_opt_enum(ctx, &opts, "start", starts, &start) ||
        opt_u32(ctx, &opts, "max_iter", &ts->cfg.max_iter) ||
        ax_opt_number(ctx, &opts, "tol", &ts->cfg.tol) ||
        ax_opt_number(ctx, &opts, "reg", &ts->cfg.reg) ||
        opt_whole(ctx, &opts, "seed", 9007199254740992.0, &seed) ||
        read_joints(ctx, &opts, ts) ||
        ax_opt_bool(ctx, &opts, "normalize", &ts->fo.normalize) ||
        ax_opt_enum(ctx, &opts, "scale", scales, &scale) ||
        ax_opt_up(ctx, &opts, &ts->fo.up_axis) ||
        ax_opt_bool(ctx, &opts, "velocity", &ts->fo.velocity))
        goto done;
    ts->cfg.cov = cov ? AFFECT_HMM_DIAG : AFFECT_HMM_FULL;
    ts->cfg.topology = topology ? AFFECT_HMM_LEFT_RIGHT : AFFECT_HMM_ERGODIC;
    ts->cfg.learn_start = start == 1;
    ts->cfg.seed = (uint64_t)seed;
    ts->fo.scale = scale == 0   ? AFFECT_FEATURES_SCALE_ARM
                   : scale == 1 ? AFFECT_FEATURES_SCALE_NONE
                                : AFFECT_FEATURES_SCALE_AUTO;
    /* the configuration is checked now (with a stand-in dimension; the real one is known
     * with the first motion), so bad options fail on the first row */
    ts->cfg.dim = 3;
    const char *msg = affect_hmm_config_check(&ts->cfg);
    if (msg) {
        ax_errorf(ctx, "%s", msg);
        goto done;
    }
    if (argc > 1 && sqlite3_value_type(argv[1]) == SQLITE_TEXT) {
        const unsigned char *text = sqlite3_value_text(argv[1]);
        int n = sqlite3_value_bytes(argv[1]);
        ts->opts_text = sqlite3_malloc64((sqlite3_uint64)n + 1);
        if (!text || !ts->opts_text) {
            sqlite3_result_error_nomem(ctx);
            goto done;
        }
        memcpy(ts->opts_text, text, (size_t)n);
        ts->opts_text[n] = '\0';
        ts->opts_len = (size_t)n;
    }
    r = AX_OK;
done:
    ax_opts_free(&opts);
    return r;
}

/* Whether a later row's options are the first row's (the same text, or both absent). */
static ax_arg same_options(sqlite3_context *ctx, int argc, sqlite3_value **argv,
                           const train_state *ts)
{
    if (argc <= 1)
        return AX_OK;
    int type = sqlite3_value_type(argv[1]);
    bool same;
    if (type == SQLITE_NULL) {
        same = ts->opts_text == NULL;
    } else if (type != SQLITE_TEXT || ts->opts_text == NULL) {
        same = false;
    } else {
        const unsigned char *text = sqlite3_value_text(argv[1]);
        if (!text) {
            sqlite3_result_error_nomem(ctx);
            return AX_ERROR;
        }
        same = (size_t)sqlite3_value_bytes(argv[1]) == ts->opts_len &&
               memcmp(text, ts->opts_text, ts->opts_len) == 0;
    }
    if (!same) {
        ax_errorf(ctx, "options must be the same on every row");
        return AX_ERROR;
    }
    return AX_OK;
}

/* Reports a core error met on a row: "row 3: …" (out of memory as SQLITE_NOMEM). */
static void row_error(sqlite3_context *ctx, const train_state *ts, const affect_error *err)
{
    if (err->status == AFFECT_ERR_NOMEM)
        sqlite3_result_error_nomem(ctx);
    else
        ax_errorf(ctx, "row %" PRIu64 ": %s", ts->rows, err->msg);
}

/* Fixes the feature definition on the first motion and completes the configuration. */
static ax_arg first_motion(sqlite3_context *ctx, train_state *ts, const affect_motion *m)
{
    affect_error err;
    if (affect_features_create(&ts->fo, m, &ts->feat, &err)) {
        row_error(ctx, ts, &err);
        return AX_ERROR;
    }
    uint32_t dim = affect_features_dim(ts->feat);
    if (dim > AFFECT_HMM_MAX_DIM) {
        ax_errorf(ctx, "the observations would have %u dimensions (%u joints x 3%s); at most %u: "
                       "choose fewer joints with \"joints\"", dim, ts->feat->n_joints,
                  ts->feat->velocity ? " x 2 with velocity" : "", AFFECT_HMM_MAX_DIM);
        return AX_ERROR;
    }
    ts->cfg.dim = dim;
    const char *msg = affect_hmm_config_check(&ts->cfg);
    if (msg) {
        ax_errorf(ctx, "%s", msg);
        return AX_ERROR;
    }
    return AX_OK;
}

/* Checks one row and keeps its observation sequence; AX_ERROR when an error was reported. */
static ax_arg add_row(sqlite3_context *ctx, int argc, sqlite3_value **argv, train_state *ts)
{
    if (same_options(ctx, argc, argv, ts) != AX_OK)
        return AX_ERROR;
    affect_motion *m = NULL;
    ax_arg r = ax_arg_motion(ctx, argv, 0, &m);
    if (r != AX_OK)
        return r == AX_NULL ? AX_OK : AX_ERROR;
    affect_error err;
    double *x = NULL;
    uint32_t n_frames = 0;
    r = AX_ERROR;
    if (!ts->feat && first_motion(ctx, ts, m) != AX_OK)
        goto done;
    if (m->fps != ts->feat->fps) {
        char a[32], b[32];
        affect_format_g(a, sizeof a, 10, m->fps);
        affect_format_g(b, sizeof b, 10, ts->feat->fps);
        ax_errorf(ctx, "row %" PRIu64 ": the motion has %s fps, the first one %s (resample it "
                       "with motion_resample)", ts->rows, a, b);
        goto done;
    }
    if (m->n_frames < ts->cfg.n_states) {
        ax_errorf(ctx, "row %" PRIu64 ": the motion has %u frames; %u states need at least %u",
                  ts->rows, m->n_frames, ts->cfg.n_states, ts->cfg.n_states);
        goto done;
    }
    if (ts->n_seqs == UINT32_MAX) {
        ax_errorf(ctx, "row %" PRIu64 ": too many motions", ts->rows);
        goto done;
    }
    if (ts->n_seqs == ts->cap) {
        uint32_t cap = ts->cap ? (ts->cap > UINT32_MAX / 2 ? UINT32_MAX : ts->cap * 2) : 16;
        size_t bytes;
        affect_hmm_seq *seqs = NULL;
        if (affect_mul_size(cap, sizeof *seqs, &bytes))
            seqs = affect_realloc(ts->seqs, bytes);
        if (!seqs) {
            sqlite3_result_error_nomem(ctx);
            goto done;
        }
        ts->seqs = seqs;
        ts->cap = cap;
    }
    if (affect_features_extract(ts->feat, m, &x, &n_frames, &err)) {
        row_error(ctx, ts, &err);
        goto done;
    }
    ts->seqs[ts->n_seqs].x = x;
    ts->seqs[ts->n_seqs].n_frames = n_frames;
    ts->n_seqs++;
    r = AX_OK;
done:
    affect_motion_free(m);
    return r;
}

void ax_hmm_train_step(sqlite3_context *ctx, int argc, sqlite3_value **argv)
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
        *slot = ts;
        ts->rows++;
        if (read_train_options(ctx, argc, argv, ts) != AX_OK) {
            ts->failed = true;
            return;
        }
    } else {
        ts->rows++;
    }
    if (add_row(ctx, argc, argv, ts) != AX_OK)
        ts->failed = true;
}

void ax_hmm_train_final(sqlite3_context *ctx)
{
    train_state **slot = sqlite3_aggregate_context(ctx, 0);
    train_state *ts = slot ? *slot : NULL;
    affect_hmm *h = NULL;
    affect_error err;
    if (!ts || ts->failed || ts->n_seqs == 0) {
        if (!ts || !ts->failed)
            sqlite3_result_null(ctx);
        goto done;
    }
    if (affect_hmm_train(&ts->cfg, ts->seqs, ts->n_seqs, &h, &err)) {
        ax_error(ctx, &err);
        goto done;
    }
    unsigned char *blob;
    size_t size;
    if (affect_hmm_blob_encode(h, ts->feat, &blob, &size, &err))
        ax_error(ctx, &err);
    else
        sqlite3_result_blob64(ctx, blob, size, sqlite3_free);
done:
    affect_hmm_free(h);
    train_state_free(ts);
    if (slot)
        *slot = NULL;
}

/* ---- the scalar functions ---- */

/* A decoded model BLOB (kept as auxiliary data of a constant argument). */
typedef struct model_ref {
    affect_hmm *h;
    affect_features *f;
} model_ref;

static void model_ref_free(void *p)
{
    model_ref *ref = p;
    if (!ref)
        return;
    affect_hmm_free(ref->h);
    affect_features_free(ref->f);
    sqlite3_free(ref);
}

/* A call's model: decoded from argument 0, or reused from its auxiliary data. */
typedef struct model_arg {
    model_ref *ref;
    bool cached; /* ref belongs to SQLite's auxiliary data */
} model_arg;

static ax_arg arg_model(sqlite3_context *ctx, sqlite3_value **argv, model_arg *ma)
{
    ma->ref = NULL;
    ma->cached = false;
    sqlite3_value *v = argv[0];
    int type = sqlite3_value_type(v);
    if (type == SQLITE_NULL)
        return AX_NULL;
    if (type != SQLITE_BLOB) {
        ax_errorf(ctx, "argument 1 must be a model BLOB (from hmm_train), got %s",
                  ax_type_name(v));
        return AX_ERROR;
    }
    ma->ref = sqlite3_get_auxdata(ctx, 0);
    if (ma->ref) {
        ma->cached = true;
        return AX_OK;
    }
    const unsigned char *data = sqlite3_value_blob(v);
    int n = sqlite3_value_bytes(v);
    if (!data && n > 0) {
        sqlite3_result_error_nomem(ctx);
        return AX_ERROR;
    }
    model_ref *ref = sqlite3_malloc64(sizeof *ref);
    if (!ref) {
        sqlite3_result_error_nomem(ctx);
        return AX_ERROR;
    }
    affect_error err;
    if (affect_hmm_blob_decode(data, (size_t)n, &ref->h, &ref->f, &err)) {
        sqlite3_free(ref);
        if (err.status == AFFECT_ERR_NOMEM)
            sqlite3_result_error_nomem(ctx);
        else
            ax_errorf(ctx, "argument 1 is not a valid model: %s", err.msg);
        return AX_ERROR;
    }
    ma->ref = ref;
    return AX_OK;
}

/* Ends a call: hands a freshly decoded model to SQLite as auxiliary data of argument 0 (it
 * frees it when the argument changes, or at once if it is not a constant). */
static void model_done(sqlite3_context *ctx, model_arg *ma)
{
    if (ma->ref && !ma->cached)
        sqlite3_set_auxdata(ctx, 0, ma->ref, model_ref_free);
    ma->ref = NULL;
}

/* The observations of argument 1 under the model's feature definition. */
static ax_arg arg_observations(sqlite3_context *ctx, sqlite3_value **argv, const model_ref *ref,
                               double **x, uint32_t *n_frames)
{
    affect_motion *m = NULL;
    ax_arg r = ax_arg_motion(ctx, argv, 1, &m);
    if (r != AX_OK)
        return r;
    affect_error err;
    if (affect_features_extract(ref->f, m, x, n_frames, &err)) {
        ax_error(ctx, &err);
        r = AX_ERROR;
    }
    affect_motion_free(m);
    return r;
}

static void result_real(sqlite3_context *ctx, double v)
{
    if (isnan(v))
        sqlite3_result_null(ctx);
    else
        sqlite3_result_double(ctx, v);
}

static const char *const loglik_keys[] = {"per_frame", NULL};

void ax_hmm_loglik(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    model_arg ma;
    ax_opts opts = {NULL, NULL};
    double *x = NULL;
    uint32_t n_frames = 0;
    bool per_frame = false;
    if (arg_model(ctx, argv, &ma) != AX_OK ||
        ax_opts_parse(ctx, argc, argv, 2, loglik_keys, &opts) != AX_OK ||
        ax_opt_bool(ctx, &opts, "per_frame", &per_frame) != AX_OK ||
        arg_observations(ctx, argv, ma.ref, &x, &n_frames) != AX_OK)
        goto done;
    double ll;
    affect_error err;
    if (affect_hmm_loglik(ma.ref->h, x, n_frames, &ll, &err))
        ax_error(ctx, &err);
    else
        result_real(ctx, per_frame ? ll / n_frames : ll);
done:
    affect_free(x);
    ax_opts_free(&opts);
    model_done(ctx, &ma);
}

/* hmm_viterbi and hmm_viterbi_loglik: the registered name says which result. */
static void viterbi(sqlite3_context *ctx, sqlite3_value **argv, bool want_path)
{
    model_arg ma;
    double *x = NULL;
    int32_t *path = NULL;
    uint32_t n_frames = 0;
    if (arg_model(ctx, argv, &ma) != AX_OK ||
        arg_observations(ctx, argv, ma.ref, &x, &n_frames) != AX_OK)
        goto done;
    path = affect_malloc_array(n_frames, sizeof *path);
    if (!path) {
        sqlite3_result_error_nomem(ctx);
        goto done;
    }
    double lp;
    affect_error err;
    if (affect_hmm_viterbi(ma.ref->h, x, n_frames, path, &lp, &err)) {
        ax_error(ctx, &err);
    } else if (!want_path) {
        result_real(ctx, lp);
    } else {
        affect_strbuf sb;
        affect_strbuf_init(&sb);
        affect_strbuf_putc(&sb, '[');
        for (uint32_t t = 0; t < n_frames; t++) {
            if (t)
                affect_strbuf_putc(&sb, ',');
            affect_strbuf_int(&sb, path[t]);
        }
        affect_strbuf_putc(&sb, ']');
        ax_result_json_buffer(ctx, &sb);
    }
done:
    affect_free(path);
    affect_free(x);
    model_done(ctx, &ma);
}

void ax_hmm_viterbi(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    viterbi(ctx, argv, true);
}

void ax_hmm_viterbi_loglik(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    viterbi(ctx, argv, false);
}

/* ---- hmm_info ---- */

static void put_doubles(affect_strbuf *sb, const double *v, size_t n)
{
    affect_strbuf_putc(sb, '[');
    for (size_t i = 0; i < n; i++) {
        if (i)
            affect_strbuf_putc(sb, ',');
        affect_strbuf_double(sb, v[i]);
    }
    affect_strbuf_putc(sb, ']');
}

/* A rows × cols row-major matrix as an array of arrays. */
static void put_matrix(affect_strbuf *sb, const double *v, size_t rows, size_t cols)
{
    affect_strbuf_putc(sb, '[');
    for (size_t i = 0; i < rows; i++) {
        if (i)
            affect_strbuf_putc(sb, ',');
        put_doubles(sb, v + i * cols, cols);
    }
    affect_strbuf_putc(sb, ']');
}

static void put_names(affect_strbuf *sb, char *const *names, uint32_t n)
{
    affect_strbuf_putc(sb, '[');
    for (uint32_t i = 0; i < n; i++) {
        if (i)
            affect_strbuf_putc(sb, ',');
        affect_strbuf_json_string(sb, names[i]);
    }
    affect_strbuf_putc(sb, ']');
}

static void put_config(affect_strbuf *sb, const affect_hmm_config *c)
{
    affect_strbuf_printf(sb, "{\"states\":%u,\"mixtures\":%u,\"dim\":%u,\"covariance\":\"%s\","
                             "\"topology\":\"%s\",\"max_jump\":%u,\"start\":\"%s\","
                             "\"max_iter\":%u,\"tol\":",
                         c->n_states, c->n_mix, c->dim,
                         c->cov == AFFECT_HMM_DIAG ? "diag" : "full",
                         c->topology == AFFECT_HMM_LEFT_RIGHT ? "left-right" : "ergodic",
                         c->max_jump, c->learn_start ? "learn" : "first", c->max_iter);
    affect_strbuf_double(sb, c->tol);
    affect_strbuf_puts(sb, ",\"reg\":");
    affect_strbuf_double(sb, c->reg);
    affect_strbuf_printf(sb, ",\"seed\":%" PRIu64 "}", c->seed);
}

static void put_features(affect_strbuf *sb, const affect_features *f)
{
    static const char *const axes[] = {"x", "y", "z"};
    affect_strbuf_puts(sb, "{\"joints\":");
    put_names(sb, f->joints, f->n_joints);
    affect_strbuf_puts(sb, ",\"skeleton\":");
    put_names(sb, f->skeleton, f->n_joints);
    affect_strbuf_puts(sb, ",\"parents\":[");
    for (uint32_t j = 0; j < f->n_joints; j++)
        affect_strbuf_printf(sb, "%s%d", j ? "," : "", (int)f->parents[j]);
    affect_strbuf_printf(sb, "],\"normalize\":%s,\"scale\":\"%s\",\"up\":\"%s\",\"velocity\":%s,"
                             "\"fps\":",
                         f->normalize ? "true" : "false", f->scale_arm ? "arm" : "none",
                         axes[f->up_axis], f->velocity ? "true" : "false");
    affect_strbuf_double(sb, f->fps);
    affect_strbuf_puts(sb, ",\"unit\":");
    if (f->unit[0])
        affect_strbuf_json_string(sb, f->unit);
    else
        affect_strbuf_puts(sb, "null");
    affect_strbuf_printf(sb, ",\"dim\":%u}", affect_features_dim(f));
}

void ax_hmm_info(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    model_arg ma;
    double *dur = NULL;
    if (arg_model(ctx, argv, &ma) != AX_OK)
        goto done;
    const affect_hmm *h = ma.ref->h;
    const affect_features *f = ma.ref->f;
    const affect_hmm_config *c = affect_hmm_get_config(h);
    uint32_t n = c->n_states;
    affect_hmm_report rep;
    affect_hmm_get_report(h, &rep);
    dur = affect_malloc_array(n, sizeof *dur);
    if (!dur) {
        sqlite3_result_error_nomem(ctx);
        goto done;
    }
    double mean = affect_hmm_mean_duration(h, dur);
    affect_strbuf sb;
    affect_strbuf_init(&sb);
    affect_strbuf_puts(&sb, "{\"config\":");
    put_config(&sb, c);
    affect_strbuf_puts(&sb, ",\"features\":");
    put_features(&sb, f);
    affect_strbuf_printf(&sb, ",\"training\":{\"iterations\":%u,\"converged\":%s,\"loglik\":",
                         rep.iterations, rep.converged ? "true" : "false");
    put_doubles(&sb, rep.loglik, (size_t)rep.iterations + 1);
    affect_strbuf_printf(&sb, ",\"reseeded\":%u,\"sequences\":%u,\"frames\":%" PRIu64 "}",
                         rep.reseeded, rep.n_sequences, rep.n_frames);
    affect_strbuf_puts(&sb, ",\"start_probabilities\":");
    put_doubles(&sb, affect_hmm_start(h), n);
    affect_strbuf_puts(&sb, ",\"transitions\":");
    put_matrix(&sb, affect_hmm_transitions(h), n, n);
    affect_strbuf_puts(&sb, ",\"weights\":");
    put_matrix(&sb, affect_hmm_weights(h), n, c->n_mix);
    affect_strbuf_puts(&sb, ",\"durations\":{\"mean_frames\":");
    affect_strbuf_double(&sb, mean);
    affect_strbuf_puts(&sb, ",\"mean_seconds\":");
    affect_strbuf_double(&sb, mean / f->fps);
    affect_strbuf_puts(&sb, ",\"frames\":");
    put_doubles(&sb, dur, n);
    for (uint32_t i = 0; i < n; i++)
        dur[i] /= f->fps;
    affect_strbuf_puts(&sb, ",\"seconds\":");
    put_doubles(&sb, dur, n);
    affect_strbuf_puts(&sb, "}}");
    ax_result_json_buffer(ctx, &sb);
done:
    affect_free(dur);
    model_done(ctx, &ma);
}

/* ---- hmm_postures ---- */

void ax_hmm_postures(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    model_arg ma;
    double *post = NULL;
    affect_motion *m = NULL;
    if (arg_model(ctx, argv, &ma) != AX_OK)
        goto done;
    const affect_hmm *h = ma.ref->h;
    const affect_hmm_config *c = affect_hmm_get_config(h);
    size_t n_vals;
    if (!affect_mul_size(c->n_states, c->dim, &n_vals) ||
        !(post = affect_calloc(n_vals, sizeof *post))) {
        sqlite3_result_error_nomem(ctx);
        goto done;
    }
    /* state i's posture: Σ_j w_ij μ_ij */
    const double *w = affect_hmm_weights(h), *mu = affect_hmm_means(h);
    for (uint32_t i = 0; i < c->n_states; i++)
        for (uint32_t j = 0; j < c->n_mix; j++) {
            double wij = w[(size_t)i * c->n_mix + j];
            const double *mij = mu + ((size_t)i * c->n_mix + j) * c->dim;
            for (uint32_t d = 0; d < c->dim; d++)
                post[(size_t)i * c->dim + d] += wij * mij[d];
        }
    affect_error err;
    if (affect_features_posture_motion(ma.ref->f, post, c->n_states, &m, &err))
        ax_error(ctx, &err);
    else
        ax_result_motion(ctx, m);
done:
    affect_motion_free(m);
    affect_free(post);
    model_done(ctx, &ma);
}
