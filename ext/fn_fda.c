/*
 * fn_fda.c — SQL wrappers of the functional analysis of movements (core: affect/fda.h;
 * SCIENCE.md §4, thesis chapter 3):
 *
 *   fda_train(motion, label [, options])  aggregate → functional model BLOB
 *   fda_embed(model, motion)              → float32 vector BLOB (the motion's coordinates)
 *   fda_classify(model, motion [, k])     → label by k-NN in the embedding (k default 1)
 *   fda_info(model)                       → JSON: method, basis, λ, dimensions, eigenvalues,
 *                                           explained shares, classes, feature definition
 *   fda_prototype(model, label)           → motion: the class prototype (rigid; exports with
 *                                           motion_to_bvh)
 *   fda_plot(model [, options])           → SVG scatter of the training embedding by label
 *
 * fda_train's options (the same text on every row):
 *   method      "ffda" (default: the measured best) | "fpca" | "fspca" | "fisomap"
 *   basis       B-spline count G (default 200), order (default 4), lambda (a number ≥ 0,
 *               default 1e-10, or "gcv"), dims (default 3)
 *   kernel      FSPCA label kernel "linear" (default) | "rbf", sigma (default 1)
 *   alignment   "linear" (default: t_j = j / (T − 1)) | "landmarks" (piecewise-linear
 *               registration to automatic landmarks, affect/fda.h)
 *   ffda_reg    FFDA regularization γ (default 1e-3); isomap_k (default 7); proto_dims
 *               (FPCA components of the prototypes, 1 .. 64, or "all" — the default, the
 *               measured best: the class's mean function; the thesis's is 3)
 *   observations: frame ("body", the default, or "first"), joints, normalize, scale, up,
 *               velocity, root (as hmm_train's); progress (an SQL function's name)
 * Rows whose motion or label is NULL are skipped; labels are compared as text and the classes
 * are ordered by their text (byte order) — the order the RBF label kernel sees.
 * fda_plot's options: x, y (1-based axes, default 1 and 2), title, width, height, radius,
 * means; with "coordinate" (1-based, the observation coordinate: joint entry by joint entry,
 * x y z, then the velocities) the perturbation plot of the axis "axis" (default 1) instead:
 * the mean function of that coordinate and the mean ± "alpha" (default 2) training standard
 * deviations along the axis (affect_fda_perturbation; linear methods), drawn as three dense
 * point series over normalized time.
 *
 * Every function on a model keeps the last model it decoded on this connection (a call with
 * byte-identical BLOB reuses it).
 *
 * Errors: "fda_embed: argument 1 must be a functional model BLOB (from fda_train), got text",
 * "fda_info: argument 1 is not a valid functional model: …", "fda_train: row 3: label must be
 * text or a number, got a BLOB", "fda_train: need motions of at least 2 labels, got 1
 * (\"sad\")", "fda_train: option \"method\" must be one of …", "fda_prototype: no class
 * \"joy\" in the model (angry, happy, normal, sad)", "fda_plot: option \"y\" must be from 1 to
 * 3 (the model's dimensions), got 4", and the core's messages.
 */
#include "fn_fda.h"

#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "affect/fda.h"
#include "affect/plot.h"
#include "util/strbuf.h"
#include "seqs.h"

/* ---- fda_train ---- */

static const char *const train_keys[] = {
    "joints",   "normalize", "scale",    "up",         "velocity",  "frame", "root",
    "progress", "method",    "basis",    "order",      "lambda",    "dims",  "kernel",
    "sigma",    "ffda_reg",  "isomap_k", "proto_dims", "alignment", NULL};

static const char *const method_names[] = {"fpca", "ffda", "fspca", "fisomap", NULL};

typedef struct fda_train {
    ax_labelled l; /* first: the sequences and their labels (seqs.h) */
    affect_fda_config cfg;
} fda_train;

ax_arg ax_fda_read_options(sqlite3_context *ctx, const ax_opts *opts, affect_fda_config *cfg)
{
    static const char *const kernels[] = {"linear", "rbf", NULL};
    static const char *const alignments[] = {"linear", "landmarks", NULL};
    int method = (int)cfg->method, kernel = (int)cfg->kernel, align = (int)cfg->alignment;
    if (ax_opt_enum(ctx, opts, "method", method_names, &method) ||
        ax_opt_u32(ctx, opts, "basis", &cfg->n_basis) ||
        ax_opt_u32(ctx, opts, "order", &cfg->order) || ax_opt_u32(ctx, opts, "dims", &cfg->dims) ||
        ax_opt_enum(ctx, opts, "kernel", kernels, &kernel) ||
        ax_opt_number(ctx, opts, "sigma", &cfg->sigma) ||
        ax_opt_number(ctx, opts, "ffda_reg", &cfg->ffda_reg) ||
        ax_opt_u32(ctx, opts, "isomap_k", &cfg->isomap_k) ||
        ax_opt_enum(ctx, opts, "alignment", alignments, &align))
        return AX_ERROR;
    const affect_json_node *pd = ax_opt(opts, "proto_dims");
    if (pd && pd->type == AFFECT_JSON_STRING && strcmp(pd->str, "all") == 0) {
        cfg->proto_dims = 0;
    } else if (pd) {
        if (pd->type != AFFECT_JSON_NUMBER) {
            ax_errorf(ctx, "option \"proto_dims\" must be a number or \"all\"");
            return AX_ERROR;
        }
        if (ax_opt_u32(ctx, opts, "proto_dims", &cfg->proto_dims))
            return AX_ERROR;
        if (cfg->proto_dims == 0) {
            ax_errorf(ctx, "proto_dims must be from 1 to 64, or all");
            return AX_ERROR;
        }
    }
    cfg->alignment = (affect_fda_alignment)align;
    cfg->method = (affect_fda_method)method;
    cfg->kernel = (affect_spca_kernel)kernel;
    const affect_json_node *l = ax_opt(opts, "lambda");
    if (l) {
        if (l->type == AFFECT_JSON_STRING && strcmp(l->str, "gcv") == 0) {
            cfg->gcv = true;
        } else if (l->type == AFFECT_JSON_NUMBER) {
            if (ax_opt_number(ctx, opts, "lambda", &cfg->lambda))
                return AX_ERROR;
        } else {
            ax_errorf(ctx, "option \"lambda\" must be a number or \"gcv\"");
            return AX_ERROR;
        }
    }
    const char *msg = affect_fda_config_check(cfg);
    if (msg) {
        ax_errorf(ctx, "%s", msg);
        return AX_ERROR;
    }
    return AX_OK;
}

/* The first row: the defaults (observations as the recognizer's, no HMM) and the options. */
static ax_arg train_first(sqlite3_context *ctx, int argc, sqlite3_value **argv, ax_labelled *l)
{
    fda_train *t = (fda_train *)l;
    affect_fda_config_default(&t->cfg);
    affect_hmm_config_default(&t->l.s.cfg);
    t->l.s.cfg.n_states = 1; /* no HMM: a motion needs 1 frame */
    t->l.s.cfg.max_jump = 0;
    affect_features_options_default(&t->l.s.fo);
    t->l.s.fo.frame = AFFECT_FEATURES_FRAME_BODY; /* the recognizer's observations */
    t->l.s.preset = true;
    ax_opts opts;
    if (ax_seqs_options(ctx, argc, argv, 2, train_keys, &t->l.s, &opts) != AX_OK)
        return AX_ERROR;
    ax_arg r = ax_fda_read_options(ctx, &opts, &t->cfg);
    ax_opts_free(&opts);
    return r;
}

/* Trains on the rows and sets the encoded model as the result. */
static void train_model(sqlite3_context *ctx, ax_labelled *l, char *const *classes,
                        uint32_t n_classes, const uint32_t *y)
{
    fda_train *t = (fda_train *)l;
    affect_fda *f = NULL;
    affect_error err;
    ax_monitor am;
    if (ax_monitor_begin(&am, ctx, t->l.s.progress) != AX_OK)
        return;
    t->cfg.monitor = &am.mon;
    affect_status st = affect_fda_train(&t->cfg, t->l.s.feat, t->l.s.seqs, t->l.s.n_seqs,
                                        affect_features_dim(t->l.s.feat), y,
                                        (const char *const *)classes, n_classes, &f, &err);
    ax_monitor_end(&am);
    unsigned char *blob;
    size_t size;
    if (st || affect_fda_encode(f, &blob, &size, &err))
        ax_error(ctx, &err);
    else
        sqlite3_result_blob64(ctx, blob, size, sqlite3_free);
    affect_fda_free(f);
}

static const ax_labelled_kind train_kind = {sizeof(fda_train), train_first, train_model};

void ax_fda_train_step(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    ax_labelled_step(ctx, argc, argv, &train_kind);
}

void ax_fda_train_final(sqlite3_context *ctx)
{
    ax_labelled_final(ctx, &train_kind);
}

/* ---- the model argument, with the per-function cache ---- */

static affect_status decode_model(const unsigned char *data, size_t size, void **out,
                                  affect_error *err)
{
    affect_fda *m = NULL;
    affect_status st = affect_fda_decode(data, size, &m, err);
    *out = m;
    return st;
}

static void free_model(void *m)
{
    affect_fda_free(m);
}

static ax_arg arg_model(sqlite3_context *ctx, sqlite3_value **argv, const affect_fda **out)
{
    ax_cached_fn *fn = sqlite3_user_data(ctx);
    const void *m;
    ax_arg r = ax_arg_cached_blob(ctx, argv, &fn->cache, decode_model, free_model,
                                  "functional model", "fda_train", &m);
    *out = m;
    return r;
}

/* The model (argument 0) and the observations of the motion (argument 1) under its feature
 * definition. */
static ax_arg arg_model_motion(sqlite3_context *ctx, sqlite3_value **argv, const affect_fda **f,
                               double **x, uint32_t *T)
{
    *x = NULL;
    ax_arg r = arg_model(ctx, argv, f);
    if (r != AX_OK)
        return r;
    affect_motion *m = NULL;
    if ((r = ax_arg_motion(ctx, argv, 1, &m)) != AX_OK)
        return r;
    const affect_features *feat = affect_fda_features(*f);
    affect_error err;
    if (!feat) {
        ax_errorf(ctx, "the model was trained on plain data, not motions");
        r = AX_ERROR;
    } else if (affect_features_extract(feat, m, x, T, NULL, &err)) {
        ax_error(ctx, &err);
        r = AX_ERROR;
    }
    affect_motion_free(m);
    return r;
}

void ax_fda_embed(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    (void)argc;
    const affect_fda *f;
    double *x, z[AFFECT_FDA_MAX_DIMS];
    uint32_t T;
    if (arg_model_motion(ctx, argv, &f, &x, &T) != AX_OK)
        return;
    affect_error err;
    if (affect_fda_embed(f, x, T, z, &err))
        ax_error(ctx, &err);
    else
        ax_result_f32(ctx, z, affect_fda_dims(f));
    affect_free(x);
}

void ax_fda_classify(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    int64_t k = 1;
    if (argc > 2) {
        ax_arg r = ax_arg_int(ctx, argv, 2, &k);
        if (r != AX_OK)
            return;
        if (k < 1 || k > 100000) {
            ax_errorf(ctx, "k must be from 1 to 100000, got %" PRId64, k);
            return;
        }
    }
    const affect_fda *f;
    double *x;
    uint32_t T, label;
    if (arg_model_motion(ctx, argv, &f, &x, &T) != AX_OK)
        return;
    affect_error err;
    if (affect_fda_classify(f, x, T, (uint32_t)k, &label, NULL, &err))
        ax_error(ctx, &err);
    else
        sqlite3_result_text(ctx, affect_fda_class_name(f, label), -1, SQLITE_TRANSIENT);
    affect_free(x);
}

void ax_fda_info(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    (void)argc;
    const affect_fda *f;
    if (arg_model(ctx, argv, &f) != AX_OK)
        return;
    const affect_fda_config *cfg = affect_fda_get_config(f);
    uint32_t p = affect_fda_dims(f), c = affect_fda_classes(f);
    affect_strbuf sb;
    affect_strbuf_init(&sb);
    affect_strbuf_printf(&sb, "{\"method\":\"%s\",\"order\":%u,\"basis\":%u,\"lambda\":",
                         method_names[cfg->method], cfg->order, cfg->n_basis);
    affect_strbuf_double(&sb, cfg->lambda);
    affect_strbuf_printf(&sb,
                         ",\"lambda_from\":\"%s\",\"dims\":%u,\"dims_requested\":%u,"
                         "\"coordinates\":%u,\"motions\":%u,\"classes\":[",
                         cfg->gcv ? "gcv" : "option", p, cfg->dims, affect_fda_coords(f),
                         affect_fda_train_size(f));
    for (uint32_t k = 0; k < c; k++) {
        if (k)
            affect_strbuf_putc(&sb, ',');
        affect_strbuf_json_string(&sb, affect_fda_class_name(f, k));
    }
    affect_strbuf_puts(&sb, "],\"class_frames\":[");
    for (uint32_t k = 0; k < c; k++) {
        if (k)
            affect_strbuf_putc(&sb, ',');
        affect_strbuf_double(&sb, affect_fda_class_frames(f, k));
    }
    affect_strbuf_puts(&sb, "],\"eigenvalues\":");
    ax_json_doubles(&sb, affect_fda_eigenvalues(f), p);
    affect_strbuf_puts(&sb, ",\"explained\":");
    ax_json_doubles(&sb, affect_fda_explained(f), p);
    affect_strbuf_puts(&sb, ",\"fpca_eigenvalues\":");
    ax_json_doubles(&sb, affect_fda_fpca_eigenvalues(f), affect_fda_fpca_rank(f));
    affect_strbuf_puts(&sb, ",\"total_variance\":");
    affect_strbuf_double(&sb, affect_fda_total_variance(f));
    affect_strbuf_printf(
        &sb, ",\"kernel\":\"%s\",\"sigma\":", cfg->kernel == AFFECT_SPCA_RBF ? "rbf" : "linear");
    affect_strbuf_double(&sb, cfg->sigma);
    affect_strbuf_puts(&sb, ",\"ffda_reg\":");
    affect_strbuf_double(&sb, cfg->ffda_reg);
    affect_strbuf_printf(&sb, ",\"isomap_k\":%u", cfg->isomap_k);
    if (affect_fda_proto_dims(f) == 0)
        affect_strbuf_puts(&sb, ",\"proto_dims\":\"all\"");
    else
        affect_strbuf_printf(&sb, ",\"proto_dims\":%u", affect_fda_proto_dims(f));
    uint32_t n_lm;
    const affect_fda_landmark *lm = affect_fda_template(f, &n_lm);
    affect_strbuf_printf(&sb, ",\"alignment\":\"%s\",\"landmarks\":[",
                         cfg->alignment == AFFECT_FDA_ALIGN_LANDMARKS ? "landmarks" : "linear");
    for (uint32_t k = 0; k < n_lm; k++) {
        affect_strbuf_puts(&sb, k ? ",{\"t\":" : "{\"t\":");
        affect_strbuf_double(&sb, lm[k].t);
        affect_strbuf_printf(&sb, ",\"type\":\"%s\"}", lm[k].type > 0 ? "peak" : "rest");
    }
    affect_strbuf_putc(&sb, ']');
    affect_strbuf_puts(&sb, ",\"train_labels\":[");
    for (uint32_t i = 0; i < affect_fda_train_size(f); i++)
        affect_strbuf_printf(&sb, i ? ",%u" : "%u", affect_fda_train_labels(f)[i]);
    affect_strbuf_puts(&sb, "],\"train_embedding\":");
    ax_json_matrix(&sb, affect_fda_train_embedding(f), affect_fda_train_size(f), p);
    if (affect_fda_features(f)) {
        affect_strbuf_puts(&sb, ",\"observations\":");
        ax_json_features(&sb, affect_fda_features(f));
    }
    affect_strbuf_putc(&sb, '}');
    ax_result_json_buffer(ctx, &sb);
}

void ax_fda_prototype(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    (void)argc;
    const affect_fda *f;
    if (arg_model(ctx, argv, &f) != AX_OK)
        return;
    const char *label;
    size_t len;
    if (ax_arg_text(ctx, argv, 1, &label, &len) != AX_OK)
        return;
    uint32_t c = affect_fda_classes(f), k = 0;
    while (k < c && !(strlen(affect_fda_class_name(f, k)) == len &&
                      memcmp(affect_fda_class_name(f, k), label, len) == 0))
        k++;
    if (k == c) {
        affect_strbuf sb;
        affect_strbuf_init(&sb);
        for (uint32_t j = 0; j < c; j++) {
            if (j)
                affect_strbuf_puts(&sb, ", ");
            affect_strbuf_puts(&sb, affect_fda_class_name(f, j));
        }
        char *names;
        size_t nlen;
        affect_error err;
        if (affect_strbuf_finish(&sb, &names, &nlen, &err)) {
            sqlite3_result_error_nomem(ctx);
            return;
        }
        ax_errorf(ctx, "no class \"%.*s\" in the model (%s)", (int)(len > 200 ? 200 : len), label,
                  names);
        affect_free(names);
        return;
    }
    affect_motion *m = NULL;
    affect_error err;
    if (affect_fda_prototype(f, k, &m, &err))
        ax_error(ctx, &err);
    else
        ax_result_motion(ctx, m);
    affect_motion_free(m);
}

/* "right_hand y", "right_hand y velocity", "root 2" for coordinate j of the observations. */
static void coordinate_name(const affect_fda *f, uint32_t j, char *out, size_t size)
{
    static const char *const xyz[] = {"x", "y", "z"};
    const affect_features *feat = affect_fda_features(f);
    if (!feat) {
        snprintf(out, size, "coordinate %u", j + 1);
        return;
    }
    uint32_t J3 = 3 * feat->n_joints;
    if (j < J3)
        snprintf(out, size, "%s %s", feat->joints[j / 3], xyz[j % 3]);
    else if (feat->velocity && j < 2 * J3)
        snprintf(out, size, "%s %s velocity", feat->joints[(j - J3) / 3], xyz[(j - J3) % 3]);
    else
        snprintf(out, size, "root %u", j - (feat->velocity ? 2 * J3 : J3) + 1);
}

#define PERTURB_SAMPLES 201

/* The perturbation plot of fda_plot's "coordinate" option: μ and μ ± α σ w of one axis. */
static void perturbation_plot(sqlite3_context *ctx, const affect_fda *f, uint32_t axis,
                              uint32_t coord, double alpha, affect_plot_options *po,
                              affect_scatter *sc)
{
    double mean[PERTURB_SAMPLES], plus[PERTURB_SAMPLES], minus[PERTURB_SAMPLES];
    char title[160], yl[128], lp[64], lm[64];
    char *svg = NULL;
    size_t len;
    affect_error err;
    if (affect_fda_perturbation(f, axis - 1, coord - 1, alpha, PERTURB_SAMPLES, mean, plus, minus,
                                &err)) {
        ax_error(ctx, &err);
        return;
    }
    coordinate_name(f, coord - 1, yl, sizeof yl);
    snprintf(title, sizeof title, "%s %u: mean and mean ± %g sd along the axis",
             method_names[affect_fda_get_config(f)->method], axis, alpha);
    snprintf(lp, sizeof lp, "mean + %g sd", alpha);
    snprintf(lm, sizeof lm, "mean - %g sd", alpha);
    if (!po->title)
        po->title = title;
    po->x_label = "normalized time";
    po->y_label = yl;
    for (uint32_t t = 0; t < PERTURB_SAMPLES; t++) {
        double x = (double)t / (PERTURB_SAMPLES - 1);
        if (affect_scatter_add(sc, x, mean[t], "mean", &err) ||
            affect_scatter_add(sc, x, plus[t], lp, &err) ||
            affect_scatter_add(sc, x, minus[t], lm, &err)) {
            ax_error(ctx, &err);
            return;
        }
    }
    if (affect_scatter_render(sc, po, &svg, &len, &err)) {
        ax_error(ctx, &err);
        return;
    }
    ax_result_text(ctx, svg, len);
}

void ax_fda_plot(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    static const char *const keys[] = {"x",     "y",    "title",      "width", "height", "radius",
                                       "means", "axis", "coordinate", "alpha", NULL};
    const affect_fda *f;
    if (arg_model(ctx, argv, &f) != AX_OK)
        return;
    ax_opts opts;
    if (ax_opts_parse(ctx, argc, argv, 1, keys, &opts) != AX_OK)
        return;
    uint32_t p = affect_fda_dims(f), ax = 1, ay = p >= 2 ? 2 : 1;
    affect_plot_options po;
    affect_plot_options_default(&po);
    affect_scatter *sc = NULL;
    char *svg = NULL, xl[32], yl[32];
    size_t len;
    affect_error err;
    uint32_t axis = 1, coord = 0;
    double alpha = 2.0;
    if (ax_opt_u32(ctx, &opts, "x", &ax) || ax_opt_u32(ctx, &opts, "y", &ay) ||
        ax_opt_string(ctx, &opts, "title", &po.title) ||
        ax_opt_number(ctx, &opts, "width", &po.width) ||
        ax_opt_number(ctx, &opts, "height", &po.height) ||
        ax_opt_number(ctx, &opts, "radius", &po.radius) ||
        ax_opt_bool(ctx, &opts, "means", &po.means) || ax_opt_u32(ctx, &opts, "axis", &axis) ||
        ax_opt_u32(ctx, &opts, "coordinate", &coord) || ax_opt_number(ctx, &opts, "alpha", &alpha))
        goto done;
    if (ax_opt(&opts, "coordinate")) {
        if (coord < 1 || axis < 1) {
            ax_errorf(ctx, "option \"%s\" must be at least 1", coord < 1 ? "coordinate" : "axis");
            goto done;
        }
        if (ax_opt(&opts, "radius") == NULL)
            po.radius = 1.0;
        if (affect_scatter_create(&sc, &err)) {
            ax_error(ctx, &err);
            goto done;
        }
        perturbation_plot(ctx, f, axis, coord, alpha, &po, sc);
        goto done;
    }
    if (ax < 1 || ax > p || ay < 1 || ay > p) {
        ax_errorf(ctx, "option \"%s\" must be from 1 to %u (the model's dimensions), got %u",
                  ax < 1 || ax > p ? "x" : "y", p, ax < 1 || ax > p ? ax : ay);
        goto done;
    }
    snprintf(xl, sizeof xl, "%s %u", method_names[affect_fda_get_config(f)->method], ax);
    snprintf(yl, sizeof yl, "%s %u", method_names[affect_fda_get_config(f)->method], ay);
    po.x_label = xl;
    po.y_label = yl;
    if (affect_scatter_create(&sc, &err)) {
        ax_error(ctx, &err);
        goto done;
    }
    const double *z = affect_fda_train_embedding(f);
    const uint32_t *y = affect_fda_train_labels(f);
    for (uint32_t i = 0; i < affect_fda_train_size(f); i++)
        if (affect_scatter_add(sc, z[(size_t)i * p + ax - 1], z[(size_t)i * p + ay - 1],
                               affect_fda_class_name(f, y[i]), &err)) {
            ax_error(ctx, &err);
            goto done;
        }
    if (affect_scatter_render(sc, &po, &svg, &len, &err)) {
        ax_error(ctx, &err);
        goto done;
    }
    ax_result_text(ctx, svg, len);
    svg = NULL;
done:
    affect_free(svg);
    affect_scatter_free(sc);
    ax_opts_free(&opts);
}
