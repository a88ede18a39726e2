/*
 * seqs.c — observation sequences collected by the training aggregates (see seqs.h): option
 * parsing shared by hmm_train and affect_train, the first motion fixing the feature definition
 * (affect_features_create), and per row the checks (same options, same fps, enough frames) and
 * the observation sequence (affect_features_extract). Only the sequences are kept, not the
 * motions.
 */
#include "seqs.h"

#include "affect/summary.h"

#include <inttypes.h>
#include <math.h>
#include <string.h>

#include "util/strbuf.h"

/* A whole-number option in [0, max] into *out (unchanged when absent). */
ax_arg ax_opt_whole(sqlite3_context *ctx, const ax_opts *opts, const char *key, double max,
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

ax_arg ax_opt_u32(sqlite3_context *ctx, const ax_opts *opts, const char *key, uint32_t *out)
{
    double v = *out;
    if (ax_opt_whole(ctx, opts, key, 4294967295.0, &v) != AX_OK)
        return AX_ERROR;
    *out = (uint32_t)v;
    return AX_OK;
}

void ax_seqs_free(ax_seqs *ts)
{
    if (!ts)
        return;
    for (uint32_t i = 0; i < ts->n_seqs; i++)
        affect_free((void *)ts->seqs[i].x);
    affect_free(ts->seqs);
    affect_free(ts->desc);
    for (uint32_t i = 0; i < ts->n_joints; i++)
        affect_free(ts->joints[i]);
    affect_free(ts->joints);
    affect_features_free(ts->feat);
    sqlite3_free(ts->opts_text.text);
    sqlite3_free(ts->progress);
    if (ts->probing)
        ax_monitor_end(&ts->probe);
    sqlite3_free(ts);
}

/* The "joints" option: a non-empty array of names, copied into ts. */
static ax_arg read_joints(sqlite3_context *ctx, const ax_opts *opts, ax_seqs *ts)
{
    const affect_json_node *n = ax_opt(opts, "joints");
    if (!n)
        return AX_OK;
    if (n->type != AFFECT_JSON_ARRAY || n->count == 0) {
        ax_errorf(ctx,
                  "option \"joints\" must be a non-empty array of joint or role names, "
                  "got %s",
                  n->type == AFFECT_JSON_ARRAY ? "an empty array" : affect_json_type_name(n->type));
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
                      i + 1,
                      e->type == AFFECT_JSON_STRING ? "a string that is empty or "
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

ax_arg ax_seqs_options(sqlite3_context *ctx, int argc, sqlite3_value **argv, int opt_i,
                       const char *const *allowed, ax_seqs *ts, ax_opts *opts)
{
    static const char *const covs[] = {"full", "diag", NULL};
    static const char *const topologies[] = {"ergodic", "left-right", NULL};
    static const char *const starts[] = {"first", "learn", NULL};
    static const char *const scales[] = {"arm", "none", NULL};
    static const char *const frames[] = {"first", "body", NULL};
    if (!ts->preset) { /* the caller's defaults (affect_train's) are already in place */
        affect_hmm_config_default(&ts->cfg);
        affect_features_options_default(&ts->fo);
    }
    ts->opt_i = opt_i;
    if (ax_opts_parse(ctx, argc, argv, opt_i, allowed, opts) != AX_OK)
        return AX_ERROR;
    int cov = (int)ts->cfg.cov, topology = (int)ts->cfg.topology, start = ts->cfg.learn_start,
        scale = -1, frame = (int)ts->fo.frame;
    double seed = (double)ts->cfg.seed;
    ax_arg r = AX_ERROR;
    if (ax_opt_u32(ctx, opts, "states", &ts->cfg.n_states) ||
        ax_opt_u32(ctx, opts, "mixtures", &ts->cfg.n_mix) ||
        ax_opt_enum(ctx, opts, "covariance", covs, &cov) ||
        ax_opt_enum(ctx, opts, "topology", topologies, &topology) ||
        ax_opt_u32(ctx, opts, "max_jump", &ts->cfg.max_jump) ||
        ax_opt_enum(ctx, opts, "start", starts, &start) ||
        ax_opt_u32(ctx, opts, "max_iter", &ts->cfg.max_iter) ||
        ax_opt_number(ctx, opts, "tol", &ts->cfg.tol) ||
        ax_opt_number(ctx, opts, "reg", &ts->cfg.reg) ||
        ax_opt_whole(ctx, opts, "seed", 9007199254740992.0, &seed) || read_joints(ctx, opts, ts) ||
        ax_opt_bool(ctx, opts, "normalize", &ts->fo.normalize) ||
        ax_opt_enum(ctx, opts, "scale", scales, &scale) || ax_opt_up(ctx, opts, &ts->fo.up_axis) ||
        ax_opt_bool(ctx, opts, "velocity", &ts->fo.velocity) ||
        ax_opt_enum(ctx, opts, "frame", frames, &frame) ||
        ax_opt_bool(ctx, opts, "root", &ts->fo.root))
        goto done;
    const char *progress = NULL;
    if (ax_opt_string(ctx, opts, "progress", &progress))
        goto done;
    if (progress && !(ts->progress = sqlite3_mprintf("%s", progress))) {
        sqlite3_result_error_nomem(ctx);
        goto done;
    }
    ts->fo.frame = frame ? AFFECT_FEATURES_FRAME_BODY : AFFECT_FEATURES_FRAME_FIRST;
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
    if (ax_opts_text_keep(ctx, argc, argv, opt_i, &ts->opts_text) != AX_OK)
        goto done;
    r = AX_OK;
done:
    if (r != AX_OK)
        ax_opts_free(opts);
    return r;
}

/* Reports a core error met on a row: "row 3: …" (out of memory as SQLITE_NOMEM). */
void ax_seqs_row_error(sqlite3_context *ctx, const ax_seqs *ts, const affect_error *err)
{
    if (err->status == AFFECT_ERR_NOMEM)
        ax_error(ctx, err); /* SQLITE_NOMEM, or the large block it could not allocate */
    else
        ax_errorf(ctx, "row %" PRIu64 ": %s", ts->rows, err->msg);
}

/* Fixes the feature definition on the first motion and completes the configuration. */
static ax_arg first_motion(sqlite3_context *ctx, ax_seqs *ts, const affect_motion *m)
{
    affect_error err;
    if (affect_features_create(&ts->fo, m, &ts->feat, &err)) {
        ax_seqs_row_error(ctx, ts, &err);
        return AX_ERROR;
    }
    uint32_t dim = affect_features_dim(ts->feat);
    if (dim > AFFECT_HMM_MAX_DIM) {
        ax_errorf(ctx,
                  "the observations would have %u dimensions (%u joints x 3%s%s); at most "
                  "%u: choose fewer joints with \"joints\"",
                  dim, ts->feat->n_joints, ts->feat->velocity ? " x 2 with velocity" : "",
                  ts->feat->root ? " + 4" : "", AFFECT_HMM_MAX_DIM);
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

ax_arg ax_seqs_add(sqlite3_context *ctx, int argc, sqlite3_value **argv, ax_seqs *ts)
{
    if (ax_opts_text_same(ctx, argc, argv, ts->opt_i, &ts->opts_text) != AX_OK)
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
        ax_errorf(ctx,
                  "row %" PRIu64 ": the motion has %s fps, the first one %s (resample it "
                  "with motion_resample)",
                  ts->rows, a, b);
        goto done;
    }
    if (!ts->any_length && m->n_frames < ts->cfg.n_states) {
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
        uint32_t dd = affect_descriptors_dim(ts->desc_mask);
        if (dd) {
            double *desc = NULL;
            if (affect_mul_size((size_t)cap * dd, sizeof *desc, &bytes))
                desc = affect_realloc(ts->desc, bytes);
            if (!desc) {
                sqlite3_result_error_nomem(ctx);
                goto done;
            }
            ts->desc = desc;
        }
        ts->cap = cap;
    }
    uint32_t dd = affect_descriptors_dim(ts->desc_mask);
    if (dd && affect_descriptors(ts->desc_mask, m, ts->feat->up_axis,
                                 ts->desc + (size_t)ts->n_seqs * dd, NULL, &err)) {
        ax_seqs_row_error(ctx, ts, &err);
        goto done;
    }
    if (affect_features_extract(ts->feat, m, &x, &n_frames, NULL, &err)) {
        ax_seqs_row_error(ctx, ts, &err);
        goto done;
    }
    /* An interrupt that SQLite notices between rows ends the scan, and SQLite 3.40 then runs
     * xFinal while resetting the statement, when the interrupt is no longer visible: the
     * training would run whole for nothing. So every row asks too, and a stopped aggregate
     * only frees in xFinal (what is left: an interrupt in the microseconds between this
     * question and SQLite's own). */
    if (!ts->probing) {
        char *msg = NULL;
        if (ax_monitor_begin_db(&ts->probe, sqlite3_context_db_handle(ctx), NULL, &msg) !=
            SQLITE_OK) {
            sqlite3_free(msg);
            affect_free(x);
            sqlite3_result_error_nomem(ctx);
            goto done;
        }
        ts->probing = true;
    }
    if (ax_monitor_interrupted(&ts->probe)) {
        affect_free(x);
        ax_interrupted(ctx);
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

/* ---- JSON pieces shared by hmm_info and affect_info ---- */

void ax_json_doubles(affect_strbuf *sb, const double *v, size_t n)
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
void ax_json_matrix(affect_strbuf *sb, const double *v, size_t rows, size_t cols)
{
    affect_strbuf_putc(sb, '[');
    for (size_t i = 0; i < rows; i++) {
        if (i)
            affect_strbuf_putc(sb, ',');
        ax_json_doubles(sb, v + i * cols, cols);
    }
    affect_strbuf_putc(sb, ']');
}

void ax_json_names(affect_strbuf *sb, char *const *names, uint32_t n)
{
    affect_strbuf_putc(sb, '[');
    for (uint32_t i = 0; i < n; i++) {
        if (i)
            affect_strbuf_putc(sb, ',');
        affect_strbuf_json_string(sb, names[i]);
    }
    affect_strbuf_putc(sb, ']');
}

void ax_json_hmm_config(affect_strbuf *sb, const affect_hmm_config *c)
{
    affect_strbuf_printf(sb,
                         "{\"states\":%u,\"mixtures\":%u,\"dim\":%u,\"covariance\":\"%s\","
                         "\"topology\":\"%s\",\"max_jump\":%u,\"start\":\"%s\","
                         "\"max_iter\":%u,\"tol\":",
                         c->n_states, c->n_mix, c->dim, c->cov == AFFECT_HMM_DIAG ? "diag" : "full",
                         c->topology == AFFECT_HMM_LEFT_RIGHT ? "left-right" : "ergodic",
                         c->max_jump, c->learn_start ? "learn" : "first", c->max_iter);
    affect_strbuf_double(sb, c->tol);
    affect_strbuf_puts(sb, ",\"reg\":");
    affect_strbuf_double(sb, c->reg);
    affect_strbuf_printf(sb, ",\"seed\":%" PRIu64 "}", c->seed);
}

void ax_json_features(affect_strbuf *sb, const affect_features *f)
{
    static const char *const axes[] = {"x", "y", "z"};
    affect_strbuf_puts(sb, "{\"joints\":");
    ax_json_names(sb, f->joints, f->n_joints);
    affect_strbuf_puts(sb, ",\"skeleton\":");
    ax_json_names(sb, f->skeleton, f->n_joints);
    affect_strbuf_puts(sb, ",\"parents\":[");
    for (uint32_t j = 0; j < f->n_joints; j++)
        affect_strbuf_printf(sb, "%s%d", j ? "," : "", (int)f->parents[j]);
    affect_strbuf_printf(sb,
                         "],\"frame\":\"%s\",\"normalize\":%s,\"scale\":\"%s\",\"up\":\"%s\","
                         "\"velocity\":%s,\"root\":%s,\"fps\":",
                         f->frame == AFFECT_FEATURES_FRAME_BODY ? "body" : "first",
                         f->normalize ? "true" : "false", f->scale_arm ? "arm" : "none",
                         axes[f->up_axis], f->velocity ? "true" : "false",
                         f->root ? "true" : "false");
    affect_strbuf_double(sb, f->fps);
    affect_strbuf_puts(sb, ",\"unit\":");
    if (f->unit[0])
        affect_strbuf_json_string(sb, f->unit);
    else
        affect_strbuf_puts(sb, "null");
    affect_strbuf_printf(sb, ",\"dim\":%u}", affect_features_dim(f));
}

/* ---- labelled training aggregates ---- */

/* The label of the current row (argument 1): its text, or AX_NULL for SQL NULL. */
static ax_arg row_label(sqlite3_context *ctx, sqlite3_value **argv, const ax_seqs *ts,
                        const char **text)
{
    int type = sqlite3_value_type(argv[1]);
    *text = NULL;
    if (type == SQLITE_NULL)
        return AX_NULL;
    if (type == SQLITE_BLOB) {
        ax_errorf(ctx, "row %" PRIu64 ": label must be text or a number, got a BLOB", ts->rows);
        return AX_ERROR;
    }
    *text = (const char *)sqlite3_value_text(argv[1]);
    if (!*text) {
        sqlite3_result_error_nomem(ctx);
        return AX_ERROR;
    }
    if (**text == '\0' || strlen(*text) != (size_t)sqlite3_value_bytes(argv[1])) {
        ax_errorf(ctx, "row %" PRIu64 ": label must not be empty or contain NUL", ts->rows);
        return AX_ERROR;
    }
    size_t len = strlen(*text), bad = affect_utf8_invalid_at(*text, len);
    if (bad < len) { /* the model BLOBs keep labels as UTF-8 */
        ax_errorf(ctx, "row %" PRIu64 ": label is not valid UTF-8 (byte 0x%02x at offset %zu)",
                  ts->rows, (unsigned char)(*text)[bad], bad);
        return AX_ERROR;
    }
    return AX_OK;
}

ax_arg ax_labelled_add(sqlite3_context *ctx, int argc, sqlite3_value **argv, ax_labelled *t)
{
    const char *label;
    ax_arg r = row_label(ctx, argv, &t->s, &label);
    if (r != AX_OK)
        return r == AX_NULL ? AX_OK : AX_ERROR;
    uint32_t before = t->s.n_seqs;
    if (ax_seqs_add(ctx, argc, argv, &t->s) != AX_OK)
        return AX_ERROR;
    if (t->s.n_seqs == before)
        return AX_OK;
    /* labels grow with the sequences (their capacity) */
    char **labels = affect_realloc(t->labels, (size_t)t->s.cap * sizeof *labels);
    if (labels) {
        t->labels = labels;
        t->labels[before] = affect_strndup(label, strlen(label));
    }
    if (!labels || !t->labels[before]) {
        affect_free((void *)t->s.seqs[before].x); /* keep labels and sequences paired */
        t->s.n_seqs = before;
        sqlite3_result_error_nomem(ctx);
        return AX_ERROR;
    }
    return AX_OK;
}

void ax_labelled_free(ax_labelled *t)
{
    if (!t)
        return;
    for (uint32_t i = 0; i < t->s.n_seqs; i++)
        affect_free(t->labels[i]);
    affect_free(t->labels);
    ax_seqs_free(&t->s); /* frees t itself (s is its first member) */
}

void ax_labelled_step(sqlite3_context *ctx, int argc, sqlite3_value **argv,
                      const ax_labelled_kind *kind)
{
    ax_labelled **slot = sqlite3_aggregate_context(ctx, (int)sizeof *slot);
    if (!slot) {
        sqlite3_result_error_nomem(ctx);
        return;
    }
    ax_labelled *t = *slot;
    if (t && t->s.failed)
        return;
    if (!t) {
        t = sqlite3_malloc64(kind->size);
        if (!t) {
            sqlite3_result_error_nomem(ctx);
            return;
        }
        memset(t, 0, kind->size);
        *slot = t;
        t->s.rows++;
        if (kind->first(ctx, argc, argv, t) != AX_OK) {
            t->s.failed = true;
            return;
        }
    } else {
        t->s.rows++;
    }
    if (ax_labelled_add(ctx, argc, argv, t) != AX_OK)
        t->s.failed = true;
}

void ax_labelled_final(sqlite3_context *ctx, const ax_labelled_kind *kind)
{
    ax_labelled **slot = sqlite3_aggregate_context(ctx, 0);
    ax_labelled *t = slot ? *slot : NULL;
    if (!t || t->s.failed || t->s.n_seqs == 0) {
        if (!t || !t->s.failed)
            sqlite3_result_null(ctx);
        goto done;
    }
    uint32_t n = t->s.n_seqs, n_classes = 0;
    char **classes = affect_malloc_array(n, sizeof *classes);
    uint32_t *y = affect_malloc_array(n, sizeof *y);
    if (!classes || !y)
        sqlite3_result_error_nomem(ctx);
    else if (ax_label_classes(ctx, t->labels, n, classes, &n_classes, y) == AX_OK)
        kind->train(ctx, t, classes, n_classes, y);
    affect_free(classes);
    affect_free(y);
done:
    ax_labelled_free(t);
    if (slot)
        *slot = NULL;
}
