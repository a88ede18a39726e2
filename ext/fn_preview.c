/*
 * fn_preview.c — motion previews as SVG (core: affect/svg.h):
 *
 *   motion_svg(motion [, options])                  → SVG text: a film strip, or with
 *                                                     {"animate":true} an animated figure
 *   motion_svg_group(motion, caption [, options])   aggregate → SVG text: its rows' motions
 *                                                     at one scale, animated side by side or
 *                                                     as one strip per row
 *
 *   SELECT motion_svg(motion, '{"animate":true,"view":"side"}') FROM motions WHERE id = 3;
 *   SELECT motion_svg_group(motion, caption, '{"animate":true}')
 *     FROM (SELECT 'source' AS caption, motion FROM src
 *           UNION ALL SELECT 'generated', motion FROM gen
 *           UNION ALL SELECT 'real', motion FROM truth);
 *
 * Options (a JSON object; motion_svg_group reads them from its first row, and they must be the
 * same text on every row): view ("front" | "side" | "top"), frames (the strip's panels, 1..64),
 * size (panel pixels, 32..1024), up ("x" | "y" | "z"), trajectories, labels (true, false,
 * "frame" = true, or "state": "state N" under panel N, for hmm_postures), title, animate,
 * keyframes (with animate: 2..1000; absent = 15 per second of motion, at most 150), roles
 * (applied to each motion). "frames" belongs to the strip and "keyframes" to the animation: a
 * call that gives one with the other kind of preview is an error, not silently ignored.
 *
 * motion_svg_group: the rows' motions in the order the rows arrive (use a subquery's ORDER BY
 * or, from SQLite 3.44, motion_svg_group(motion, caption ORDER BY …)); a row with a NULL motion
 * is skipped; caption is text, a number (as text) or NULL (no caption). Over no motion at all
 * the result is NULL. At most 64 motions (AFFECT_SVG_MAX_GROUP); every one is decoded and kept
 * until the end, so memory grows with their sizes.
 *
 * How the aggregate works: its context holds one pointer to a group_state, allocated on the
 * first row, which owns the decoded motions, their roles, the captions, the parsed options and
 * a copy of the options text. xFinal renders and frees it (SQLite calls xFinal for every
 * context created, also when a statement stops early); after an error the state is marked
 * failed and xFinal only frees.
 *
 * Errors: "motion_svg: options \"frames\" and \"size\" must be whole numbers",
 * "motion_svg: option \"frames\" is for the film strip (an animation takes \"keyframes\")",
 * "motion_svg: option \"keyframes\" needs \"animate\":true",
 * "motion_svg: option \"labels\" must be true, false, \"frame\" or \"state\", got number",
 * "motion_svg_group: caption (argument 2) must be text, a number or NULL, got blob",
 * "motion_svg_group: options must be the same on every row",
 * "motion_svg_group: at most 64 motions in a group",
 * and the core's ("motion_svg: keyframes must be 0 (automatic) or between 2 and 1000, got 1").
 */
#include "fn_preview.h"

#include <math.h>
#include <string.h>

#include "affect/heatmap.h"
#include "affect/svg.h"

static const char *const svg_keys[] = {"view",         "frames", "size",  "up",
                                       "trajectories", "labels", "title", "animate",
                                       "keyframes",    "roles",  NULL};

/* A whole number option in [0, 1e6] into *out (unchanged when absent). */
static ax_arg whole(sqlite3_context *ctx, const ax_opts *opts, const char *key, uint32_t *out,
                    bool *given)
{
    double v = *out;
    *given = ax_opt(opts, key) != NULL;
    if (ax_opt_number(ctx, opts, key, &v) != AX_OK)
        return AX_ERROR;
    if (v != floor(v) || v < 0 || v > 1e6) {
        ax_errorf(ctx, "options \"frames\", \"size\" and \"keyframes\" must be whole numbers");
        return AX_ERROR;
    }
    *out = (uint32_t)v;
    return AX_OK;
}

/* The options of motion_svg and motion_svg_group (all but roles) into so. */
static ax_arg svg_options(sqlite3_context *ctx, const ax_opts *opts, affect_svg_options *so)
{
    static const char *const views[] = {"front", "side", "top", NULL};
    static const char *const label_kinds[] = {"frame", "state", NULL};
    affect_svg_options_default(so);
    int view = (int)so->view;
    bool has_frames, has_size, has_keys;
    if (ax_opt_enum(ctx, opts, "view", views, &view) != AX_OK ||
        whole(ctx, opts, "frames", &so->frames, &has_frames) != AX_OK ||
        whole(ctx, opts, "size", &so->panel_size, &has_size) != AX_OK ||
        whole(ctx, opts, "keyframes", &so->keyframes, &has_keys) != AX_OK ||
        ax_opt_up(ctx, opts, &so->up_axis) != AX_OK ||
        ax_opt_bool(ctx, opts, "trajectories", &so->trajectories) != AX_OK ||
        ax_opt_string(ctx, opts, "title", &so->title) != AX_OK ||
        ax_opt_bool(ctx, opts, "animate", &so->animate) != AX_OK)
        return AX_ERROR;
    so->view = (affect_svg_view)view;
    const affect_json_node *labels = ax_opt(opts, "labels");
    if (labels && labels->type == AFFECT_JSON_STRING) {
        int kind = 0;
        if (ax_opt_enum(ctx, opts, "labels", label_kinds, &kind) != AX_OK)
            return AX_ERROR;
        so->labels = true;
        so->state_labels = kind == 1;
    } else if (labels && labels->type != AFFECT_JSON_TRUE && labels->type != AFFECT_JSON_FALSE) {
        ax_errorf(ctx, "option \"labels\" must be true, false, \"frame\" or \"state\", got %s",
                  affect_json_type_name(labels->type));
        return AX_ERROR;
    } else if (ax_opt_bool(ctx, opts, "labels", &so->labels) != AX_OK) {
        return AX_ERROR;
    }
    if (so->animate && has_frames) {
        ax_errorf(ctx, "option \"frames\" is for the film strip (an animation takes "
                       "\"keyframes\")");
        return AX_ERROR;
    }
    if (!so->animate && has_keys) {
        ax_errorf(ctx, "option \"keyframes\" needs \"animate\":true");
        return AX_ERROR;
    }
    return AX_OK;
}

void ax_motion_svg(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    affect_motion *m;
    if (ax_arg_motion(ctx, argv, 0, &m) != AX_OK)
        return;
    ax_opts opts;
    affect_roles roles;
    affect_svg_options so;
    if (ax_opts_parse(ctx, argc, argv, 1, svg_keys, &opts) == AX_OK &&
        svg_options(ctx, &opts, &so) == AX_OK && ax_opt_roles(ctx, &opts, m, &roles) == AX_OK) {
        char *text = NULL;
        size_t len = 0;
        affect_error err;
        if (affect_motion_svg(m, &roles, &so, &text, &len, &err))
            ax_error(ctx, &err);
        else
            ax_result_text(ctx, text, len);
    }
    ax_opts_free(&opts);
    affect_motion_free(m);
}

/* ---- motion_svg_group ---- */

typedef struct group_state {
    affect_motion *m[AFFECT_SVG_MAX_GROUP];
    affect_roles roles[AFFECT_SVG_MAX_GROUP];
    char *caption[AFFECT_SVG_MAX_GROUP]; /* sqlite3_malloc'd, NULL for none */
    size_t n;
    ax_opts opts; /* the first row's options; owns the strings in so */
    affect_svg_options so;
    ax_opts_text oc;
    bool failed; /* an error was reported: xFinal only frees */
} group_state;

static void group_free(group_state *gs)
{
    if (!gs)
        return;
    for (size_t i = 0; i < gs->n; i++) {
        affect_motion_free(gs->m[i]);
        sqlite3_free(gs->caption[i]);
    }
    ax_opts_free(&gs->opts);
    sqlite3_free(gs->oc.text);
    sqlite3_free(gs);
}

/* The first row's options (argument 3), parsed and kept with a copy of their text. */
static ax_arg group_options(sqlite3_context *ctx, int argc, sqlite3_value **argv, group_state *gs)
{
    if (ax_opts_parse(ctx, argc, argv, 2, svg_keys, &gs->opts) != AX_OK ||
        svg_options(ctx, &gs->opts, &gs->so) != AX_OK)
        return AX_ERROR;
    return ax_opts_text_keep(ctx, argc, argv, 2, &gs->oc);
}

/* One row: its caption checked, its motion decoded and kept with its roles. */
static ax_arg group_add(sqlite3_context *ctx, int argc, sqlite3_value **argv, group_state *gs)
{
    if (ax_opts_text_same(ctx, argc, argv, 2, &gs->oc) != AX_OK)
        return AX_ERROR;
    int ctype = sqlite3_value_type(argv[1]);
    if (ctype == SQLITE_BLOB) {
        ax_errorf(ctx, "caption (argument 2) must be text, a number or NULL, got blob");
        return AX_ERROR;
    }
    affect_motion *m = NULL;
    ax_arg a = ax_arg_motion(ctx, argv, 0, &m);
    if (a != AX_OK)
        return a == AX_NULL ? AX_OK : AX_ERROR;
    if (gs->n == AFFECT_SVG_MAX_GROUP) {
        affect_motion_free(m);
        ax_errorf(ctx, "at most %u motions in a group", AFFECT_SVG_MAX_GROUP);
        return AX_ERROR;
    }
    char *caption = NULL;
    if (ctype != SQLITE_NULL) {
        const unsigned char *text = sqlite3_value_text(argv[1]);
        int n = sqlite3_value_bytes(argv[1]);
        caption = text ? sqlite3_malloc64((sqlite3_uint64)n + 1) : NULL;
        if (!caption) {
            affect_motion_free(m);
            sqlite3_result_error_nomem(ctx);
            return AX_ERROR;
        }
        memcpy(caption, text, (size_t)n);
        caption[n] = '\0';
    }
    gs->m[gs->n] = m;
    gs->caption[gs->n] = caption;
    gs->n++;
    return ax_opt_roles(ctx, &gs->opts, m, &gs->roles[gs->n - 1]);
}

void ax_motion_svg_group_step(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    group_state **slot = sqlite3_aggregate_context(ctx, (int)sizeof *slot);
    if (!slot) {
        sqlite3_result_error_nomem(ctx);
        return;
    }
    group_state *gs = *slot;
    if (gs && gs->failed)
        return;
    if (!gs) {
        gs = sqlite3_malloc64(sizeof *gs);
        if (!gs) {
            sqlite3_result_error_nomem(ctx);
            return;
        }
        memset(gs, 0, sizeof *gs);
        *slot = gs;
        if (group_options(ctx, argc, argv, gs) != AX_OK) {
            gs->failed = true;
            return;
        }
    }
    if (group_add(ctx, argc, argv, gs) != AX_OK)
        gs->failed = true;
}

void ax_motion_svg_group_final(sqlite3_context *ctx)
{
    group_state **slot = sqlite3_aggregate_context(ctx, 0);
    group_state *gs = slot ? *slot : NULL;
    if (gs && !gs->failed && gs->n > 0) {
        char *text = NULL;
        size_t len = 0;
        affect_error err;
        if (affect_motion_svg_group((const affect_motion *const *)gs->m, gs->roles,
                                    (const char *const *)gs->caption, gs->n, &gs->so, &text, &len,
                                    &err))
            ax_error(ctx, &err);
        else
            ax_result_text(ctx, text, len);
    } else if (!gs || !gs->failed) {
        sqlite3_result_null(ctx);
    }
    group_free(gs);
    if (slot)
        *slot = NULL;
}

/* ---- affect_heatmap ---- */

static const char *const heatmap_keys[] = {"title",        "x_label", "y_label", "cell",
                                           "values",       "min",     "max",     "sort_rows",
                                           "sort_columns", NULL};

typedef struct heat_state {
    affect_heatmap *hm;
    ax_opts opts; /* the first row's options; owns the strings in ho */
    affect_heatmap_options ho;
    ax_opts_text oc;
    bool failed;
} heat_state;

static void heat_free(heat_state *hs)
{
    if (!hs)
        return;
    affect_heatmap_free(hs->hm);
    ax_opts_free(&hs->opts);
    sqlite3_free(hs->oc.text);
    sqlite3_free(hs);
}

/* The first row's options (argument 4) into hs, checked, with a copy of their text. */
static ax_arg heat_options(sqlite3_context *ctx, int argc, sqlite3_value **argv, heat_state *hs)
{
    affect_heatmap_options_default(&hs->ho);
    bool values = false;
    if (ax_opts_parse(ctx, argc, argv, 3, heatmap_keys, &hs->opts) != AX_OK ||
        ax_opt_string(ctx, &hs->opts, "title", &hs->ho.title) != AX_OK ||
        ax_opt_string(ctx, &hs->opts, "x_label", &hs->ho.x_label) != AX_OK ||
        ax_opt_string(ctx, &hs->opts, "y_label", &hs->ho.y_label) != AX_OK ||
        ax_opt_number(ctx, &hs->opts, "cell", &hs->ho.cell) != AX_OK ||
        ax_opt_bool(ctx, &hs->opts, "values", &values) != AX_OK ||
        ax_opt_number(ctx, &hs->opts, "min", &hs->ho.min) != AX_OK ||
        ax_opt_number(ctx, &hs->opts, "max", &hs->ho.max) != AX_OK ||
        ax_opt_bool(ctx, &hs->opts, "sort_rows", &hs->ho.sort_rows) != AX_OK ||
        ax_opt_bool(ctx, &hs->opts, "sort_columns", &hs->ho.sort_columns) != AX_OK)
        return AX_ERROR;
    if (ax_opt(&hs->opts, "values"))
        hs->ho.values = values ? 1 : 0;
    hs->ho.has_min = ax_opt(&hs->opts, "min") != NULL;
    hs->ho.has_max = ax_opt(&hs->opts, "max") != NULL;
    affect_error err;
    if (affect_heatmap_options_check(&hs->ho, &err)) {
        ax_error(ctx, &err);
        return AX_ERROR;
    }
    return ax_opts_text_keep(ctx, argc, argv, 3, &hs->oc);
}

/* A row or column label (argument i) as text; AX_NULL for NULL. */
static ax_arg heat_label(sqlite3_context *ctx, sqlite3_value **argv, int i, const char *what,
                         const char **out)
{
    int type = sqlite3_value_type(argv[i]);
    if (type == SQLITE_NULL)
        return AX_NULL;
    if (type == SQLITE_BLOB) {
        ax_errorf(ctx, "%s (argument %d) must be text or a number, got blob", what, i + 1);
        return AX_ERROR;
    }
    *out = (const char *)sqlite3_value_text(argv[i]);
    if (!*out) {
        sqlite3_result_error_nomem(ctx);
        return AX_ERROR;
    }
    return AX_OK;
}

static ax_arg heat_add(sqlite3_context *ctx, int argc, sqlite3_value **argv, heat_state *hs)
{
    if (ax_opts_text_same(ctx, argc, argv, 3, &hs->oc) != AX_OK)
        return AX_ERROR;
    const char *row = NULL, *col = NULL;
    ax_arg ar = heat_label(ctx, argv, 0, "row", &row);
    if (ar == AX_ERROR)
        return AX_ERROR;
    ax_arg ac = heat_label(ctx, argv, 1, "column", &col);
    if (ac == AX_ERROR)
        return AX_ERROR;
    int vtype = sqlite3_value_type(argv[2]);
    if (vtype != SQLITE_NULL && vtype != SQLITE_INTEGER && vtype != SQLITE_FLOAT) {
        ax_errorf(ctx, "value (argument 3) must be a number, got %s", ax_type_name(argv[2]));
        return AX_ERROR;
    }
    if (ar == AX_NULL || ac == AX_NULL || vtype == SQLITE_NULL)
        return AX_OK;
    affect_error err;
    if (affect_heatmap_add(hs->hm, row, col, sqlite3_value_double(argv[2]), &err)) {
        ax_error(ctx, &err);
        return AX_ERROR;
    }
    return AX_OK;
}

void ax_affect_heatmap_step(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    heat_state **slot = sqlite3_aggregate_context(ctx, (int)sizeof *slot);
    if (!slot) {
        sqlite3_result_error_nomem(ctx);
        return;
    }
    heat_state *hs = *slot;
    if (hs && hs->failed)
        return;
    if (!hs) {
        hs = sqlite3_malloc64(sizeof *hs);
        if (!hs) {
            sqlite3_result_error_nomem(ctx);
            return;
        }
        memset(hs, 0, sizeof *hs);
        *slot = hs;
        affect_error err;
        if (heat_options(ctx, argc, argv, hs) != AX_OK) {
            hs->failed = true;
            return;
        }
        if (affect_heatmap_create(&hs->hm, &err)) {
            ax_error(ctx, &err);
            hs->failed = true;
            return;
        }
    }
    if (heat_add(ctx, argc, argv, hs) != AX_OK)
        hs->failed = true;
}

void ax_affect_heatmap_final(sqlite3_context *ctx)
{
    heat_state **slot = sqlite3_aggregate_context(ctx, 0);
    heat_state *hs = slot ? *slot : NULL;
    affect_heatmap *empty = NULL;
    char *svg = NULL;
    size_t len = 0;
    affect_error err;
    if (hs && hs->failed)
        goto done;
    if (!hs && affect_heatmap_create(&empty, &err)) { /* no rows: the empty map */
        ax_error(ctx, &err);
        goto done;
    }
    if (affect_heatmap_render(hs ? hs->hm : empty, hs ? &hs->ho : NULL, &svg, &len, &err))
        ax_error(ctx, &err);
    else
        ax_result_text(ctx, svg, len);
done:
    affect_heatmap_free(empty);
    heat_free(hs);
    if (slot)
        *slot = NULL;
}
