/*
 * fn_motion.c — SQL wrappers of the motion_* functions: import (BVH, CSV, JSON), export,
 * inspection, editing, roles, normalization and the synthetic generator (the previews,
 * motion_svg and motion_svg_group, are in fn_preview.c).
 * Each wrapper only converts values and calls the core; see docs/reference.md for the SQL
 * signatures, results and errors.
 */
#include "fn_motion.h"

#include <math.h>
#include <string.h>

#include "affect/io.h"
#include "affect/normalize.h"
#include "affect/skeleton.h"
#include "util/strbuf.h"
#include "affect/synth.h"

/* Sets the result from a core status: the motion on success, the error otherwise; frees it.
 * Pointers, not values, are passed so that a call such as finish_motion(ctx, f(&m), &m, …)
 * reads m after f has set it (argument evaluation order is unspecified in C). */
static void finish_motion(sqlite3_context *ctx, affect_status st, affect_motion **m,
                          const affect_error *err)
{
    if (st)
        ax_error(ctx, err);
    else
        ax_result_motion(ctx, *m);
    affect_motion_free(*m);
    *m = NULL;
}

/* Sets a text result produced by the core (or its error). */
static void finish_text(sqlite3_context *ctx, affect_status st, char **text, size_t *len,
                        const affect_error *err, bool json)
{
    if (st)
        ax_error(ctx, err);
    else if (json)
        ax_result_json(ctx, *text, *len);
    else
        ax_result_text(ctx, *text, *len);
    *text = NULL;
}

/* ---- import ---- */

/* motion_from_bvh's options; motion_bvh_error takes the same but "on_error" */
static const char *const bvh_keys[] = {"unit", "scale", "max_samples", "on_error", NULL};
static const char *const bvh_error_keys[] = {"unit", "scale", "max_samples", NULL};
static const char *const on_error_choices[] = {"raise", "null", NULL};

/* The option "max_samples" of the importers (frames × joints at most; absent: the core's
 * default, AFFECT_MOTION_MAX_SAMPLES): a whole number from 1 to the most a motion can hold. */
static ax_arg max_samples_option(sqlite3_context *ctx, const ax_opts *opts, uint64_t *out)
{
    double v = 0;
    if (!ax_opt(opts, "max_samples"))
        return AX_OK;
    if (ax_opt_number(ctx, opts, "max_samples", &v))
        return AX_ERROR;
    double top = (double)AFFECT_MOTION_MAX_FRAMES * AFFECT_MOTION_MAX_JOINTS;
    if (!(v >= 1 && v <= top) || v != floor(v)) {
        ax_errorf(ctx, "option \"max_samples\" must be a whole number from 1 to %.0f, got %g", top,
                  v);
        return AX_ERROR;
    }
    *out = (uint64_t)v;
    return AX_OK;
}

/* Reads the options "unit", "scale" and "max_samples" into *bo and checks the unit before any
 * text is read (the core checks it only after the hierarchy), so that a bad option is never
 * taken for a bad file: the unit is tried on a one-frame motion. */
static ax_arg bvh_options(sqlite3_context *ctx, const ax_opts *opts, affect_bvh_options *bo)
{
    if (ax_opt_string(ctx, opts, "unit", &bo->unit) ||
        ax_opt_number(ctx, opts, "scale", &bo->scale) ||
        max_samples_option(ctx, opts, &bo->max_samples))
        return AX_ERROR;
    if (!bo->unit)
        return AX_OK;
    affect_motion *probe = NULL;
    affect_error err;
    affect_status st = affect_motion_create(1, 1, 30.0, &probe, &err);
    if (!st)
        st = affect_motion_set_unit(probe, bo->unit, &err);
    affect_motion_free(probe);
    if (st) {
        ax_error(ctx, &err);
        return AX_ERROR;
    }
    return AX_OK;
}

/* Whether a failed import is the text's fault (malformed, or too large) rather than the
 * call's: the options are checked first (bvh_options; the core reports a bad scale as
 * AFFECT_ERR_INVALID before reading); running out of memory or an interrupt is never the
 * text's. */
static bool bvh_text_error(affect_status st)
{
    return st != AFFECT_OK && st != AFFECT_ERR_NOMEM && st != AFFECT_ERR_INVALID &&
           st != AFFECT_ERR_INTERRUPTED;
}

void ax_motion_from_bvh(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    const char *text;
    size_t len;
    if (ax_arg_document(ctx, argv, 0, &text, &len) != AX_OK)
        return;
    ax_opts opts;
    if (ax_opts_parse(ctx, argc, argv, 1, bvh_keys, &opts))
        return;
    affect_bvh_options bo = {1.0, NULL, 0, NULL};
    affect_motion *m = NULL;
    affect_error err;
    affect_status st;
    int on_error = 0; /* index in on_error_choices: 0 raise, 1 null */
    if (ax_opt_enum(ctx, &opts, "on_error", on_error_choices, &on_error) ||
        bvh_options(ctx, &opts, &bo))
        goto done;
    ax_monitor am;
    if (ax_monitor_begin(&am, ctx, NULL) != AX_OK)
        goto done;
    bo.monitor = &am.mon;
    st = affect_bvh_parse(text, len, &bo, &m, &err);
    ax_monitor_end(&am);
    if (on_error == 1 && bvh_text_error(st))
        sqlite3_result_null(ctx); /* m is NULL: the core sets it only on success */
    else
        finish_motion(ctx, st, &m, &err);
done:
    ax_opts_free(&opts);
}

/* motion_bvh_error(bvh [, options]): NULL when motion_from_bvh(bvh, options) imports the text,
 * else the message it would raise, without its "motion_from_bvh: " prefix ("line 57: …").
 * Bad options and out of memory are raised, as motion_from_bvh raises them. */
void ax_motion_bvh_error(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    const char *text;
    size_t len;
    if (ax_arg_document(ctx, argv, 0, &text, &len) != AX_OK)
        return;
    ax_opts opts;
    if (ax_opts_parse(ctx, argc, argv, 1, bvh_error_keys, &opts))
        return;
    affect_bvh_options bo = {1.0, NULL, 0, NULL};
    affect_motion *m = NULL;
    affect_error err;
    affect_status st;
    if (bvh_options(ctx, &opts, &bo))
        goto done;
    ax_monitor am;
    if (ax_monitor_begin(&am, ctx, NULL) != AX_OK)
        goto done;
    bo.monitor = &am.mon;
    st = affect_bvh_parse(text, len, &bo, &m, &err);
    ax_monitor_end(&am);
    affect_motion_free(m);
    if (st == AFFECT_OK)
        sqlite3_result_null(ctx);
    else if (bvh_text_error(st))
        sqlite3_result_text(ctx, err.msg, -1, SQLITE_TRANSIENT);
    else
        ax_error(ctx, &err);
done:
    ax_opts_free(&opts);
}

static const char *const csv_keys[] = {"header",  "delimiter",   "unit",
                                       "parents", "max_samples", NULL};

/* The "parents" option: one item per joint, a parent's index, its name, or null / −1 for a
 * root. */
static ax_arg set_parents(sqlite3_context *ctx, const ax_opts *opts, affect_motion *m)
{
    const affect_json_node *n = ax_opt(opts, "parents");
    if (!n)
        return AX_OK;
    if (n->type != AFFECT_JSON_ARRAY || n->count != m->n_joints) {
        ax_errorf(ctx,
                  "option \"parents\" must be an array of %u parents (an index, a joint name, or "
                  "null for a root)",
                  m->n_joints);
        return AX_ERROR;
    }
    int32_t *parents = sqlite3_malloc64((sqlite3_uint64)m->n_joints * sizeof *parents);
    if (!parents) {
        sqlite3_result_error_nomem(ctx);
        return AX_ERROR;
    }
    uint32_t i = 0;
    ax_arg rc = AX_OK;
    for (const affect_json_node *e = affect_json_first(opts->doc, n); e && !rc;
         e = affect_json_next_sibling(opts->doc, e), i++) {
        if (e->type == AFFECT_JSON_NULL)
            parents[i] = -1;
        else if (e->type == AFFECT_JSON_STRING)
            parents[i] = affect_motion_find_joint(m, e->str);
        else if (e->type == AFFECT_JSON_NUMBER && e->num == floor(e->num) && e->num >= -1 &&
                 e->num < m->n_joints)
            parents[i] = (int32_t)e->num;
        else
            parents[i] = -2;
        if (parents[i] == -2 || (e->type == AFFECT_JSON_STRING && parents[i] < 0)) {
            ax_errorf(ctx,
                      "option \"parents\": item %u is not a joint index (-1 .. %u), a joint name "
                      "or null",
                      i, m->n_joints - 1);
            rc = AX_ERROR;
        }
    }
    affect_error err;
    if (!rc && affect_motion_set_parents(m, parents, &err)) {
        ax_errorf(ctx, "option \"parents\": %s", err.msg);
        rc = AX_ERROR;
    }
    sqlite3_free(parents);
    return rc;
}

void ax_motion_from_csv(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    const char *text;
    size_t len;
    double fps;
    if (ax_arg_document(ctx, argv, 0, &text, &len) != AX_OK ||
        ax_arg_double(ctx, argv, 1, &fps) != AX_OK)
        return;
    ax_opts opts;
    if (ax_opts_parse(ctx, argc, argv, 2, csv_keys, &opts))
        return;
    affect_csv_options co;
    affect_csv_options_default(&co);
    const char *delim = NULL;
    const affect_json_node *h = ax_opt(&opts, "header");
    affect_motion *m = NULL;
    affect_error err;
    if (h && h->type == AFFECT_JSON_TRUE)
        co.header = 1;
    else if (h && h->type == AFFECT_JSON_FALSE)
        co.header = 0;
    else if (h && !(h->type == AFFECT_JSON_STRING && strcmp(h->str, "auto") == 0)) {
        ax_errorf(ctx, "option \"header\" must be true, false or \"auto\"");
        goto done;
    }
    if (ax_opt_string(ctx, &opts, "delimiter", &delim) ||
        ax_opt_string(ctx, &opts, "unit", &co.unit) ||
        max_samples_option(ctx, &opts, &co.max_samples))
        goto done;
    if (delim) {
        if (strlen(delim) != 1) {
            ax_errorf(ctx,
                      "option \"delimiter\" must be one character: \",\", \";\", \"\\t\" or \" \"");
            goto done;
        }
        co.delimiter = delim[0];
    }
    ax_monitor am;
    if (ax_monitor_begin(&am, ctx, NULL) != AX_OK)
        goto done;
    co.monitor = &am.mon;
    affect_status st = affect_csv_parse(text, len, fps, &co, &m, &err);
    ax_monitor_end(&am);
    if (st) {
        ax_error(ctx, &err);
        goto done;
    }
    if (set_parents(ctx, &opts, m) == AX_OK)
        ax_result_motion(ctx, m);
done:
    affect_motion_free(m);
    ax_opts_free(&opts);
}

void ax_motion_from_json(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    const char *text;
    size_t len;
    if (ax_arg_document(ctx, argv, 0, &text, &len) != AX_OK)
        return;
    affect_motion *m = NULL;
    affect_error err;
    ax_monitor am;
    if (ax_monitor_begin(&am, ctx, NULL) != AX_OK)
        return;
    affect_status st = affect_motion_from_json(text, len, &m, &am.mon, &err);
    ax_monitor_end(&am);
    finish_motion(ctx, st, &m, &err);
}

/* ---- export and inspection ---- */

typedef affect_status (*motion_writer)(const affect_motion *, char **, size_t *, affect_monitor *,
                                       affect_error *);

/* Writes the motion argument as text with a core writer. */
static void write_motion(sqlite3_context *ctx, sqlite3_value **argv, motion_writer writer,
                         bool json)
{
    affect_motion *m;
    if (ax_arg_motion(ctx, argv, 0, &m) != AX_OK)
        return;
    char *text = NULL;
    size_t len = 0;
    affect_error err;
    ax_monitor am;
    if (ax_monitor_begin(&am, ctx, NULL) == AX_OK) {
        affect_status st = writer(m, &text, &len, &am.mon, &err);
        ax_monitor_end(&am);
        finish_text(ctx, st, &text, &len, &err, json);
    }
    affect_motion_free(m);
}

void ax_motion_to_json(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    write_motion(ctx, argv, affect_motion_to_json, true);
}

void ax_motion_to_csv(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    write_motion(ctx, argv, affect_csv_write, false);
}

static void put_floats(affect_strbuf *sb, const float *v, int n)
{
    affect_strbuf_putc(sb, '[');
    for (int i = 0; i < n; i++) {
        if (i)
            affect_strbuf_putc(sb, ',');
        affect_strbuf_float(sb, v[i]);
    }
    affect_strbuf_putc(sb, ']');
}

void ax_motion_info(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    affect_motion *m;
    if (ax_arg_motion(ctx, argv, 0, &m) != AX_OK)
        return;
    affect_strbuf sb;
    affect_strbuf_init(&sb);
    affect_strbuf_printf(&sb, "{\"frames\":%u,\"joints\":%u,\"fps\":", m->n_frames, m->n_joints);
    affect_strbuf_double(&sb, m->fps);
    affect_strbuf_puts(&sb, ",\"duration\":");
    affect_strbuf_double(&sb, affect_motion_duration(m));
    affect_strbuf_puts(&sb, ",\"unit\":");
    if (m->unit[0])
        affect_strbuf_json_string(&sb, m->unit);
    else
        affect_strbuf_puts(&sb, "null");
    affect_strbuf_puts(&sb, ",\"names\":[");
    for (uint32_t j = 0; j < m->n_joints; j++) {
        if (j)
            affect_strbuf_putc(&sb, ',');
        affect_strbuf_json_string(&sb, m->names[j]);
    }
    affect_strbuf_puts(&sb, "],\"parents\":[");
    for (uint32_t j = 0; j < m->n_joints; j++)
        affect_strbuf_printf(&sb, "%s%d", j ? "," : "", m->parents[j]);
    float lo[3], hi[3];
    affect_motion_bbox(m, lo, hi);
    affect_strbuf_puts(&sb, "],\"bbox\":{\"min\":");
    put_floats(&sb, lo, 3);
    affect_strbuf_puts(&sb, ",\"max\":");
    put_floats(&sb, hi, 3);
    affect_strbuf_puts(&sb, "}");
    affect_strbuf_printf(&sb, ",\"skeleton\":%s,\"rotations\":%s", m->skel ? "true" : "false",
                         m->rot ? "true" : "false");
    double variation;
    int32_t worst;
    affect_error err;
    affect_status st = affect_motion_bone_variation(m, &variation, &worst, &err);
    if (!st && worst >= 0) {
        affect_strbuf_puts(&sb, ",\"bone_variation\":");
        affect_strbuf_double(&sb, variation);
        affect_strbuf_puts(&sb, ",\"bone_variation_joint\":");
        affect_strbuf_json_string(&sb, m->names[worst]);
    } else if (!st) {
        affect_strbuf_puts(&sb, ",\"bone_variation\":null,\"bone_variation_joint\":null");
    }
    affect_strbuf_putc(&sb, '}');
    char *text = NULL;
    size_t len = 0;
    if (!st)
        st = affect_strbuf_finish(&sb, &text, &len, &err);
    else
        affect_strbuf_free(&sb);
    finish_text(ctx, st, &text, &len, &err, true);
    affect_motion_free(m);
}

/* motion_frames, motion_joints, motion_fps and motion_duration share this wrapper; the
 * registered name says which field to return. */
void ax_motion_scalar(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    affect_motion *m;
    if (ax_arg_motion(ctx, argv, 0, &m) != AX_OK)
        return;
    const char *name = AX_NAME(ctx);
    if (strcmp(name, "motion_frames") == 0)
        sqlite3_result_int64(ctx, m->n_frames);
    else if (strcmp(name, "motion_joints") == 0)
        sqlite3_result_int64(ctx, m->n_joints);
    else if (strcmp(name, "motion_fps") == 0)
        sqlite3_result_double(ctx, m->fps);
    else
        sqlite3_result_double(ctx, affect_motion_duration(m));
    affect_motion_free(m);
}

/* ---- editing ---- */

void ax_motion_slice(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    int64_t first, last;
    affect_motion *m, *out = NULL;
    if (ax_arg_int(ctx, argv, 1, &first) != AX_OK || ax_arg_int(ctx, argv, 2, &last) != AX_OK ||
        ax_arg_motion(ctx, argv, 0, &m) != AX_OK)
        return;
    affect_error err;
    finish_motion(ctx, affect_motion_slice(m, first, last, &out, &err), &out, &err);
    affect_motion_free(m);
}

void ax_motion_resample(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    double fps;
    affect_motion *m, *out = NULL;
    if (ax_arg_double(ctx, argv, 1, &fps) != AX_OK || ax_arg_motion(ctx, argv, 0, &m) != AX_OK)
        return;
    affect_error err;
    finish_motion(ctx, affect_motion_resample(m, fps, &out, &err), &out, &err);
    affect_motion_free(m);
}

void ax_motion_select(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    const char *text;
    size_t len;
    affect_motion *m = NULL, *out = NULL;
    affect_json_doc *doc = NULL;
    const char **names = NULL;
    affect_error err;
    if (ax_arg_text(ctx, argv, 1, &text, &len) != AX_OK || ax_arg_motion(ctx, argv, 0, &m) != AX_OK)
        return;
    if (affect_json_parse(text, len, &doc, NULL, &err)) {
        if (err.status == AFFECT_ERR_NOMEM)
            sqlite3_result_error_nomem(ctx);
        else
            ax_errorf(ctx, "argument 2 is not valid JSON: %s", err.msg);
        goto done;
    }
    const affect_json_node *root = affect_json_root(doc);
    if (root->type != AFFECT_JSON_ARRAY || root->count == 0) {
        ax_errorf(ctx, "argument 2 must be a non-empty JSON array of joint names");
        goto done;
    }
    names = sqlite3_malloc64((sqlite3_uint64)root->count * sizeof *names);
    if (!names) {
        sqlite3_result_error_nomem(ctx);
        goto done;
    }
    uint32_t i = 0;
    for (const affect_json_node *n = affect_json_first(doc, root); n;
         n = affect_json_next_sibling(doc, n), i++) {
        if (n->type != AFFECT_JSON_STRING) {
            ax_errorf(ctx, "argument 2: item %u must be a joint name, got %s", i,
                      affect_json_type_name(n->type));
            goto done;
        }
        names[i] = n->str;
    }
    finish_motion(ctx, affect_motion_select(m, names, root->count, &out, &err), &out, &err);
done:
    sqlite3_free(names);
    affect_json_free(doc);
    affect_motion_free(m);
}

/* ---- roles and normalization ---- */

static const char *const roles_keys[] = {"roles", NULL};

void ax_motion_roles(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    affect_motion *m;
    if (ax_arg_motion(ctx, argv, 0, &m) != AX_OK)
        return;
    ax_opts opts;
    affect_roles roles;
    if (ax_opts_parse(ctx, argc, argv, 1, roles_keys, &opts) == AX_OK &&
        ax_opt_roles(ctx, &opts, m, &roles) == AX_OK) {
        affect_strbuf sb;
        affect_strbuf_init(&sb);
        affect_strbuf_putc(&sb, '{');
        for (int r = 0; r < AFFECT_ROLE_COUNT; r++) {
            affect_strbuf_puts(&sb, r ? "," : "");
            affect_strbuf_json_string(&sb, affect_role_name((affect_role)r));
            affect_strbuf_putc(&sb, ':');
            if (roles.joint[r] >= 0)
                affect_strbuf_json_string(&sb, m->names[roles.joint[r]]);
            else
                affect_strbuf_puts(&sb, "null");
        }
        affect_strbuf_putc(&sb, '}');
        char *text = NULL;
        size_t len = 0;
        affect_error err;
        finish_text(ctx, affect_strbuf_finish(&sb, &text, &len, &err), &text, &len, &err, true);
    }
    ax_opts_free(&opts);
    affect_motion_free(m);
}

static const char *const normalize_keys[] = {"up",    "translation", "vertical", "heading",
                                             "scale", "roles",       NULL};

void ax_motion_normalize(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    static const char *const scales[] = {"none", "arm", NULL};
    affect_motion *m, *out = NULL;
    if (ax_arg_motion(ctx, argv, 0, &m) != AX_OK)
        return;
    ax_opts opts;
    affect_roles roles;
    affect_normalize_options no;
    affect_normalize_options_default(&no);
    int scale = 0;
    if (ax_opts_parse(ctx, argc, argv, 1, normalize_keys, &opts) == AX_OK &&
        ax_opt_up(ctx, &opts, &no.up_axis) == AX_OK &&
        ax_opt_bool(ctx, &opts, "translation", &no.translation) == AX_OK &&
        ax_opt_bool(ctx, &opts, "vertical", &no.vertical) == AX_OK &&
        ax_opt_bool(ctx, &opts, "heading", &no.heading) == AX_OK &&
        ax_opt_enum(ctx, &opts, "scale", scales, &scale) == AX_OK &&
        ax_opt_roles(ctx, &opts, m, &roles) == AX_OK) {
        no.scale_arm = scale == 1;
        affect_error err;
        finish_motion(ctx, affect_motion_normalize(m, &roles, &no, &out, &err), &out, &err);
    }
    ax_opts_free(&opts);
    affect_motion_free(m);
}

/* ---- synthetic movements ---- */

static const char *const synth_keys[] = {"fps", "intensity", "noise", NULL};

void ax_motion_synth(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    const char *action, *emotion;
    size_t alen, elen;
    int64_t seed;
    if (ax_arg_text(ctx, argv, 0, &action, &alen) != AX_OK ||
        ax_arg_text(ctx, argv, 1, &emotion, &elen) != AX_OK ||
        ax_arg_int(ctx, argv, 2, &seed) != AX_OK)
        return;
    ax_opts opts;
    affect_synth_options so;
    affect_synth_options_default(&so);
    if (ax_opts_parse(ctx, argc, argv, 3, synth_keys, &opts) == AX_OK &&
        ax_opt_number(ctx, &opts, "fps", &so.fps) == AX_OK &&
        ax_opt_number(ctx, &opts, "intensity", &so.intensity) == AX_OK &&
        ax_opt_number(ctx, &opts, "noise", &so.noise) == AX_OK) {
        affect_motion *m = NULL;
        affect_error err;
        finish_motion(ctx, affect_motion_synth(action, emotion, (uint64_t)seed, &so, &m, &err), &m,
                      &err);
    }
    ax_opts_free(&opts);
}
