/*
 * fn_laban.c — SQL wrappers of the Laban Effort and Shape descriptors (core/laban/laban.c):
 * laban_weight, laban_time, laban_flow, laban_space, laban_shape_directional,
 * laban_shape_shaping, laban_shape_flow, laban, laban_names, laban_vector, and laban_zvector
 * (a motion's vector standardized with a laban index's statistics, for sqlite-vec's vec0).
 *
 * Options shared by all (a JSON object, last argument): cutoff_hz (low-pass cut-off, 6),
 * up ("y"), roles ({"left_hand": "LWrist", …}), missing ("error" | "null": a component that
 * needs an unresolved role or more frames gives NULL instead of an error). Each function adds
 * its own: method, per_second, hull, speed_floor, max_ratio. See docs/reference.md.
 */
#include <math.h>
#include <string.h>

#include "fn_laban.h"
#include "vt_laban.h"

#include "affect/laban.h"
#include "affect/summary.h"
#include "util/strbuf.h"

/* Parsed arguments common to every laban_* function. */
typedef struct laban_call {
    affect_motion *m;
    ax_opts opts;
    affect_roles roles;
    affect_laban_options lo;
    ax_monitor am; /* lo.monitor: the statement's interrupt (begun last in call_begin) */
} laban_call;

static void call_free(laban_call *c)
{
    if (c->lo.monitor)
        ax_monitor_end(&c->am);
    ax_opts_free(&c->opts);
    affect_motion_free(c->m);
}

/* Decodes the motion (argument 0) and the options (argument opt_index, if present), checks the
 * keys against allowed, and fills the common options. AX_NULL: the result is NULL. */
static ax_arg call_begin(sqlite3_context *ctx, int argc, sqlite3_value **argv, int opt_index,
                         const char *const *allowed, laban_call *c)
{
    static const char *const missing[] = {"error", "null", NULL};
    static const char *const hulls[] = {"convex", "box", NULL};
    memset(c, 0, sizeof *c);
    affect_laban_options_default(&c->lo);
    ax_arg r = ax_arg_motion(ctx, argv, 0, &c->m);
    if (r != AX_OK)
        return r;
    int miss = 0, hull = 0;
    if (ax_opts_parse(ctx, argc, argv, opt_index, allowed, &c->opts) ||
        ax_opt_number(ctx, &c->opts, "cutoff_hz", &c->lo.cutoff_hz) ||
        ax_opt_up(ctx, &c->opts, &c->lo.up_axis) ||
        ax_opt_enum(ctx, &c->opts, "missing", missing, &miss) ||
        ax_opt_enum(ctx, &c->opts, "hull", hulls, &hull) ||
        ax_opt_bool(ctx, &c->opts, "per_second", &c->lo.time_per_second) ||
        ax_opt_number(ctx, &c->opts, "speed_floor", &c->lo.speed_floor) ||
        ax_opt_number(ctx, &c->opts, "max_ratio", &c->lo.max_ratio) ||
        ax_opt_roles(ctx, &c->opts, c->m, &c->roles)) {
        call_free(c);
        return AX_ERROR;
    }
    c->lo.missing_null = miss == 1;
    c->lo.hull_box = hull == 1;
    if (ax_monitor_begin(&c->am, ctx, NULL) != AX_OK) {
        call_free(c);
        return AX_ERROR;
    }
    c->lo.monitor = &c->am.mon;
    return AX_OK;
}

/* Sets the error of a failed computation; a missing role or a short motion gives NULL when
 * the caller asked for {"missing": "null"}. */
static void laban_error(sqlite3_context *ctx, const laban_call *c, const affect_error *err)
{
    if (c->lo.missing_null &&
        (err->status == AFFECT_ERR_MISSING || err->status == AFFECT_ERR_RANGE)) {
        sqlite3_result_null(ctx);
        return;
    }
    if (err->status == AFFECT_ERR_MISSING) {
        ax_errorf(ctx, "%s (assign it with {\"roles\": {…}}, or use {\"missing\": \"null\"})",
                  err->msg);
        return;
    }
    ax_error(ctx, err);
}

static void result_value(sqlite3_context *ctx, const laban_call *c, affect_status st, double v,
                         const affect_error *err)
{
    if (st)
        laban_error(ctx, c, err);
    else if (isnan(v))
        sqlite3_result_null(ctx);
    else
        sqlite3_result_double(ctx, v);
}

/* The part argument (index i, default "all"): all six parts, or one. */
static ax_arg parts_arg(sqlite3_context *ctx, int argc, sqlite3_value **argv, int i,
                        const laban_call *c, affect_part parts[6], uint32_t *n, affect_error *err,
                        affect_status *st)
{
    const char *name = "all";
    size_t len;
    if (i < argc) {
        ax_arg r = ax_arg_text(ctx, argv, i, &name, &len);
        if (r != AX_OK)
            return r;
    }
    if (strcmp(name, "all") == 0) {
        *n = 6;
        *st = affect_parts_all(c->m, &c->roles, parts, err);
    } else {
        *n = 1;
        *st = affect_part_resolve(c->m, &c->roles, name, &parts[0], err);
    }
    return AX_OK;
}

static const char *const weight_keys[] = {"method", "cutoff_hz", "up", "roles", "missing", NULL};
static const char *const time_keys[] = {"method", "per_second", "cutoff_hz", "up",
                                        "roles",  "missing",    NULL};
static const char *const flow_keys[] = {"cutoff_hz", "up", "roles", "missing", NULL};
static const char *const space_keys[] = {"method", "max_ratio", "cutoff_hz", "up",
                                         "roles",  "missing",   NULL};

typedef enum effort { EFFORT_WEIGHT, EFFORT_TIME, EFFORT_FLOW, EFFORT_SPACE } effort;

/* laban_weight / laban_time / laban_flow / laban_space (motion [, part [, options]]). */
static void effort_fn(sqlite3_context *ctx, int argc, sqlite3_value **argv, effort which)
{
    static const char *const weight_methods[] = {"peak", "deceleration", NULL};
    static const char *const time_methods[] = {"peak", "accumulated", NULL};
    static const char *const space_methods[] = {"ratio", "peaks", NULL};
    const char *const *keys = which == EFFORT_WEIGHT ? weight_keys
                              : which == EFFORT_TIME ? time_keys
                              : which == EFFORT_FLOW ? flow_keys
                                                     : space_keys;
    laban_call c;
    if (call_begin(ctx, argc, argv, 2, keys, &c) != AX_OK)
        return;
    int method = 0;
    const char *const *methods = which == EFFORT_WEIGHT ? weight_methods
                                 : which == EFFORT_TIME ? time_methods
                                                        : space_methods;
    affect_part parts[6];
    uint32_t n = 0;
    affect_error err;
    affect_status st = AFFECT_OK;
    double v = NAN;
    if ((which != EFFORT_FLOW && ax_opt_enum(ctx, &c.opts, "method", methods, &method)) ||
        parts_arg(ctx, argc, argv, 1, &c, parts, &n, &err, &st) != AX_OK)
        goto done;
    affect_laban_method q = method == 1 ? AFFECT_LABAN_Q2 : AFFECT_LABAN_Q1;
    if (!st) {
        switch (which) {
        case EFFORT_WEIGHT:
            st = affect_laban_weight(c.m, parts, n, q, &c.lo, &v, &err);
            break;
        case EFFORT_TIME:
            st = affect_laban_time(c.m, parts, n, q, &c.lo, &v, &err);
            break;
        case EFFORT_FLOW:
            st = affect_laban_flow(c.m, parts, n, &c.lo, &v, &err);
            break;
        case EFFORT_SPACE:
            if (method == 1) { /* peaks of v_hand · v_torso: the part is the hand */
                if (n != 1) {
                    ax_errorf(ctx, "method \"peaks\" needs one hand part (left_hand, right_hand "
                                   "or a joint), not \"all\"");
                    goto done;
                }
                st = affect_part_resolve(c.m, &c.roles, "torso", &parts[1], &err);
                if (!st)
                    st = affect_laban_space(c.m, parts, 2, AFFECT_LABAN_Q1, &c.lo, &v, &err);
            } else {
                st = affect_laban_space(c.m, parts, n, AFFECT_LABAN_Q2, &c.lo, &v, &err);
            }
            break;
        }
    }
    result_value(ctx, &c, st, v, &err);
done:
    call_free(&c);
}

void ax_laban_weight(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    effort_fn(ctx, argc, argv, EFFORT_WEIGHT);
}

void ax_laban_time(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    effort_fn(ctx, argc, argv, EFFORT_TIME);
}

void ax_laban_flow(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    effort_fn(ctx, argc, argv, EFFORT_FLOW);
}

void ax_laban_space(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    effort_fn(ctx, argc, argv, EFFORT_SPACE);
}

static const char *const directional_keys[] = {"speed_floor", "cutoff_hz", "up",
                                               "roles",       "missing",   NULL};

/* laban_shape_directional(motion, hand [, options]): hand is 'left', 'right' or a joint. */
void ax_laban_shape_directional(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    laban_call c;
    const char *hand;
    size_t len;
    if (ax_arg_text(ctx, argv, 1, &hand, &len) != AX_OK ||
        call_begin(ctx, argc, argv, 2, directional_keys, &c) != AX_OK)
        return;
    const char *part_name = strcmp(hand, "left") == 0    ? "left_hand"
                            : strcmp(hand, "right") == 0 ? "right_hand"
                                                         : hand;
    affect_part part;
    affect_error err;
    double v = NAN;
    affect_status st = affect_part_resolve(c.m, &c.roles, part_name, &part, &err);
    if (!st)
        st = affect_laban_shape_directional(c.m, &part, &c.lo, &v, &err);
    result_value(ctx, &c, st, v, &err);
    call_free(&c);
}

static const char *const shaping_keys[] = {"up", "roles", "missing", NULL};

void ax_laban_shape_shaping(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    laban_call c;
    if (call_begin(ctx, argc, argv, 1, shaping_keys, &c) != AX_OK)
        return;
    double v[3];
    affect_error err;
    affect_status st = affect_laban_shape_shaping(c.m, &c.roles, &c.lo, v, &err);
    if (st) {
        laban_error(ctx, &c, &err);
    } else {
        affect_strbuf sb;
        affect_strbuf_init(&sb);
        affect_strbuf_puts(&sb, "{\"vertical\":");
        affect_strbuf_double(&sb, v[0]);
        affect_strbuf_puts(&sb, ",\"sagittal\":");
        affect_strbuf_double(&sb, v[1]);
        affect_strbuf_puts(&sb, ",\"horizontal\":");
        affect_strbuf_double(&sb, v[2]);
        affect_strbuf_putc(&sb, '}');
        ax_result_json_buffer(ctx, &sb);
    }
    call_free(&c);
}

static const char *const shape_flow_keys[] = {"hull", "roles", NULL};

void ax_laban_shape_flow(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    laban_call c;
    if (call_begin(ctx, argc, argv, 1, shape_flow_keys, &c) != AX_OK)
        return;
    double v = NAN;
    affect_error err;
    affect_status st = affect_laban_shape_flow(c.m, &c.lo, &v, &err);
    result_value(ctx, &c, st, v, &err);
    call_free(&c);
}

static const char *const vector_keys[] = {"cutoff_hz",   "up",         "roles",       "missing",
                                          "hull",        "per_second", "speed_floor", "max_ratio",
                                          "standardize", NULL};

/* The 27 components of a motion, or an error already set on ctx (returns false). */
static bool all_components(sqlite3_context *ctx, int argc, sqlite3_value **argv, laban_call *c,
                           double out[AFFECT_LABAN_N])
{
    if (call_begin(ctx, argc, argv, 1, vector_keys, c) != AX_OK)
        return false;
    if (ax_opt(&c->opts, "standardize")) {
        /* laban_vector is pure (usable in indexes, views and generated columns); a vector that
         * depends on an index's rows is not */
        ax_errorf(ctx, "option \"standardize\" is laban_zvector's: laban_zvector(motion, "
                       "'index_name') gives the vector standardized with that laban index's "
                       "statistics (laban_vector is pure and reads no table)");
        call_free(c);
        return false;
    }
    affect_error err;
    if (affect_laban_vector(c->m, &c->roles, &c->lo, out, &err)) {
        if (err.status == AFFECT_ERR_MISSING)
            ax_errorf(ctx, "%s (assign it with {\"roles\": {…}}, or use {\"missing\": \"null\"})",
                      err.msg);
        else
            ax_error(ctx, &err);
        call_free(c);
        return false;
    }
    return true;
}

/* laban(motion [, options]) → JSON object of the 27 components (null where missing). */
void ax_laban(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    laban_call c;
    double v[AFFECT_LABAN_N];
    if (!all_components(ctx, argc, argv, &c, v))
        return;
    affect_strbuf sb;
    affect_strbuf_init(&sb);
    for (int i = 0; i < AFFECT_LABAN_N; i++) {
        affect_strbuf_putc(&sb, i ? ',' : '{');
        affect_strbuf_json_string(&sb, affect_laban_names[i]);
        affect_strbuf_putc(&sb, ':');
        affect_strbuf_double(&sb, v[i]); /* NaN is written as null */
    }
    affect_strbuf_putc(&sb, '}');
    ax_result_json_buffer(ctx, &sb);
    call_free(&c);
}

/* laban_vector(motion [, options]) → 27 little-endian float32 (the sqlite-vec convention);
 * a missing component is NaN. */
void ax_laban_vector(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    laban_call c;
    double v[AFFECT_LABAN_N];
    if (!all_components(ctx, argc, argv, &c, v))
        return;
    ax_result_f32(ctx, v, AFFECT_LABAN_N);
    call_free(&c);
}

/* The "components" option of laban_zvector: out gets the chosen component indices in
 * laban_names() order (*n of them; all 27 when absent), as the index's components = ? does. */
static ax_arg zvector_components(sqlite3_context *ctx, const ax_opts *opts, int out[AFFECT_LABAN_N],
                                 int *n)
{
    const affect_json_node *arr = ax_opt(opts, "components");
    bool on[AFFECT_LABAN_N] = {false};
    char q[80];
    *n = 0;
    if (!arr) {
        for (int j = 0; j < AFFECT_LABAN_N; j++)
            out[(*n)++] = j;
        return AX_OK;
    }
    if (arr->type != AFFECT_JSON_ARRAY || arr->count == 0) {
        ax_errorf(ctx,
                  "option \"components\" must be a non-empty array of component names "
                  "(see laban_names()), got %s%s",
                  arr->type == AFFECT_JSON_ARRAY ? "an empty " : "",
                  affect_json_type_name(arr->type));
        return AX_ERROR;
    }
    for (const affect_json_node *m = affect_json_first(opts->doc, arr); m;
         m = affect_json_next_sibling(opts->doc, m)) {
        if (m->type != AFFECT_JSON_STRING) {
            ax_errorf(ctx,
                      "option \"components\" must be an array of component names, got %s "
                      "in it",
                      affect_json_type_name(m->type));
            return AX_ERROR;
        }
        int j = strlen(m->str) == m->str_len ? affect_laban_index(m->str) : -1;
        affect_json_quote(q, sizeof q, m->str, m->str_len);
        if (j < 0 || on[j]) {
            ax_errorf(ctx,
                      j < 0 ? "option \"components\": unknown component %s (see "
                              "laban_names())"
                            : "option \"components\": component %s is listed twice",
                      q);
            return AX_ERROR;
        }
        on[j] = true;
    }
    for (int j = 0; j < AFFECT_LABAN_N; j++)
        if (on[j])
            out[(*n)++] = j;
    return AX_OK;
}

/* laban_zvector(motion, index_name [, options]) → float32 BLOB: the motion's Laban vector
 * computed with the index's options and standardized with its statistics, so that L2 distances
 * between such vectors are the index's distances (affect_laban_l2_vector). Option components:
 * the index's components = ? (default all 27). Reads the index: registered DIRECTONLY. */
void ax_laban_zvector(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    static const char *const keys[] = {"components", NULL};
    affect_motion *m = NULL;
    ax_opts opts = {0};
    ax_monitor am;
    bool monitored = false;
    const char *name;
    size_t name_len;
    char *msg = NULL;
    ax_laban_stats stats;
    int comp[AFFECT_LABAN_N], nc = 0;
    if (ax_arg_motion(ctx, argv, 0, &m) != AX_OK ||
        ax_arg_text(ctx, argv, 1, &name, &name_len) != AX_OK ||
        ax_opts_parse(ctx, argc, argv, 2, keys, &opts) != AX_OK ||
        zvector_components(ctx, &opts, comp, &nc) != AX_OK)
        goto done;
    if (strlen(name) != name_len) {
        ax_errorf(ctx, "argument 2 must name a laban index, got text with a NUL byte");
        goto done;
    }
    int rc = ax_laban_stats_read(sqlite3_context_db_handle(ctx), name, &stats, &msg);
    if (rc != SQLITE_OK) {
        if (rc == SQLITE_NOMEM)
            sqlite3_result_error_nomem(ctx);
        else if (rc == SQLITE_NOTFOUND)
            ax_errorf(ctx,
                      "\"%s\" is not a laban table (CREATE VIRTUAL TABLE %s USING "
                      "laban(…))",
                      name, name);
        else
            ax_errorf(ctx, "%s", msg);
        goto done;
    }
    if (ax_monitor_begin(&am, ctx, NULL) != AX_OK)
        goto done;
    monitored = true;
    affect_roles roles;
    affect_roles_resolve(m, &roles); /* as the index resolves them */
    affect_laban_options lo = stats.opt;
    lo.monitor = &am.mon;
    double v[AFFECT_LABAN_N];
    float x[AFFECT_LABAN_N], z[AFFECT_LABAN_N];
    affect_error err;
    affect_status st = affect_laban_vector(m, &roles, &lo, v, &err);
    if (!st) {
        for (int j = 0; j < AFFECT_LABAN_N; j++)
            x[j] = affect_laban_f32(v[j]); /* as the index stores it */
        st = affect_laban_l2_vector(x, stats.mean, stats.sd, comp, nc, z, &err);
    }
    if (st == AFFECT_ERR_MISSING || st == AFFECT_ERR_RANGE) {
        ax_errorf(ctx, "%s (index \"%s\"%s)", err.msg, name,
                  st == AFFECT_ERR_MISSING ? "; leave it out with {\"components\": […]}" : "");
    } else if (st) {
        ax_error(ctx, &err);
    } else {
        double d[AFFECT_LABAN_N];
        for (int t = 0; t < nc; t++)
            d[t] = z[t];
        ax_result_f32(ctx, d, (size_t)nc);
    }
done:
    if (monitored)
        ax_monitor_end(&am);
    sqlite3_free(msg);
    ax_opts_free(&opts);
    affect_motion_free(m);
}

/* motion_kinematics(motion [, options]) → JSON object of the kinematic summary
 * (affect/summary.h), names in affect_summary_names order; option "up". */
void ax_motion_kinematics(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    static const char *const keys[] = {"up", NULL};
    affect_motion *m = NULL;
    ax_arg r = ax_arg_motion(ctx, argv, 0, &m);
    if (r != AX_OK)
        return;
    ax_opts opts;
    int up = 1;
    if (ax_opts_parse(ctx, argc, argv, 1, keys, &opts) == AX_OK) {
        ax_monitor am;
        if (ax_opt_up(ctx, &opts, &up) == AX_OK && ax_monitor_begin(&am, ctx, NULL) == AX_OK) {
            double v[AFFECT_SUMMARY_N];
            affect_error err;
            affect_status st = affect_motion_summary(m, up, v, &am.mon, &err);
            ax_monitor_end(&am);
            if (st) {
                ax_error(ctx, &err);
            } else {
                affect_strbuf sb;
                affect_strbuf_init(&sb);
                for (int i = 0; i < AFFECT_SUMMARY_N; i++) {
                    affect_strbuf_putc(&sb, i ? ',' : '{');
                    affect_strbuf_json_string(&sb, affect_summary_names[i]);
                    affect_strbuf_putc(&sb, ':');
                    affect_strbuf_double(&sb, v[i]);
                }
                affect_strbuf_putc(&sb, '}');
                ax_result_json_buffer(ctx, &sb);
            }
        }
        ax_opts_free(&opts);
    }
    affect_motion_free(m);
}

void ax_laban_names(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    affect_strbuf sb;
    affect_strbuf_init(&sb);
    for (int i = 0; i < AFFECT_LABAN_N; i++) {
        affect_strbuf_putc(&sb, i ? ',' : '[');
        affect_strbuf_json_string(&sb, affect_laban_names[i]);
    }
    affect_strbuf_putc(&sb, ']');
    ax_result_json_buffer(ctx, &sb);
}
