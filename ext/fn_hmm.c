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
 * How hmm_train works: the aggregate context holds one pointer to a ax_seqs, allocated on
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

#include "seqs.h"

#include <inttypes.h>
#include <math.h>
#include <string.h>

#include "affect/features.h"
#include "affect/hmm.h"
#include "affect/hmm_blob.h"
#include "util/strbuf.h"

static const char *const train_keys[] = {AX_SEQS_KEYS, NULL};

void ax_hmm_train_step(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    ax_seqs **slot = sqlite3_aggregate_context(ctx, (int)sizeof *slot);
    if (!slot) {
        sqlite3_result_error_nomem(ctx);
        return;
    }
    ax_seqs *ts = *slot;
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
        ax_opts opts;
        if (ax_seqs_options(ctx, argc, argv, 1, train_keys, ts, &opts) != AX_OK) {
            ts->failed = true;
            return;
        }
        ax_opts_free(&opts);
    } else {
        ts->rows++;
    }
    if (ax_seqs_add(ctx, argc, argv, ts) != AX_OK)
        ts->failed = true;
}

void ax_hmm_train_final(sqlite3_context *ctx)
{
    ax_seqs **slot = sqlite3_aggregate_context(ctx, 0);
    ax_seqs *ts = slot ? *slot : NULL;
    affect_hmm *h = NULL;
    affect_error err;
    if (!ts || ts->failed || ts->n_seqs == 0) {
        if (!ts || !ts->failed)
            sqlite3_result_null(ctx);
        goto done;
    }
    ax_monitor am;
    if (ax_monitor_begin(&am, ctx, ts->progress) != AX_OK)
        goto done;
    ts->cfg.monitor = &am.mon;
    affect_status st = affect_hmm_train(&ts->cfg, ts->seqs, ts->n_seqs, &h, &err);
    ax_monitor_end(&am);
    if (st) {
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
    ax_seqs_free(ts);
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
        ax_errorf(ctx, "argument 1 must be a model BLOB (from hmm_train), got %s", ax_type_name(v));
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
            ax_error(ctx, &err); /* SQLITE_NOMEM, or the large block it could not allocate */
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
    ax_monitor am;
    if ((r = ax_monitor_begin(&am, ctx, NULL)) == AX_OK) {
        if (affect_features_extract(ref->f, m, x, n_frames, &am.mon, &err)) {
            ax_error(ctx, &err);
            r = AX_ERROR;
        }
        ax_monitor_end(&am);
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
    ax_monitor am;
    if (ax_monitor_begin(&am, ctx, NULL) != AX_OK)
        goto done;
    affect_status st = affect_hmm_loglik(ma.ref->h, x, n_frames, &ll, &am.mon, &err);
    ax_monitor_end(&am);
    if (st)
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
    ax_monitor am;
    if (ax_monitor_begin(&am, ctx, NULL) != AX_OK)
        goto done;
    affect_status st = affect_hmm_viterbi(ma.ref->h, x, n_frames, path, &lp, &am.mon, &err);
    ax_monitor_end(&am);
    if (st) {
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
    ax_json_hmm_config(&sb, c);
    affect_strbuf_puts(&sb, ",\"features\":");
    ax_json_features(&sb, f);
    affect_strbuf_printf(&sb, ",\"training\":{\"iterations\":%u,\"converged\":%s,\"loglik\":",
                         rep.iterations, rep.converged ? "true" : "false");
    ax_json_doubles(&sb, rep.loglik, (size_t)rep.iterations + 1);
    affect_strbuf_printf(&sb, ",\"reseeded\":%u,\"sequences\":%u,\"frames\":%" PRIu64 "}",
                         rep.reseeded, rep.n_sequences, rep.n_frames);
    affect_strbuf_puts(&sb, ",\"start_probabilities\":");
    ax_json_doubles(&sb, affect_hmm_start(h), n);
    affect_strbuf_puts(&sb, ",\"transitions\":");
    ax_json_matrix(&sb, affect_hmm_transitions(h), n, n);
    affect_strbuf_puts(&sb, ",\"weights\":");
    ax_json_matrix(&sb, affect_hmm_weights(h), n, c->n_mix);
    affect_strbuf_puts(&sb, ",\"durations\":{\"mean_frames\":");
    affect_strbuf_double(&sb, mean);
    affect_strbuf_puts(&sb, ",\"mean_seconds\":");
    affect_strbuf_double(&sb, mean / f->fps);
    affect_strbuf_puts(&sb, ",\"frames\":");
    ax_json_doubles(&sb, dur, n);
    for (uint32_t i = 0; i < n; i++)
        dur[i] /= f->fps;
    affect_strbuf_puts(&sb, ",\"seconds\":");
    ax_json_doubles(&sb, dur, n);
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
