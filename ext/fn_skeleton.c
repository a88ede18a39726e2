/*
 * fn_skeleton.c — SQL wrappers of motion_to_bvh and motion_rigid, and the options shared with
 * motion_angles. Each wrapper only converts values and calls the core (affect/skeleton.h,
 * affect/io.h); see docs/reference.md for signatures, results and errors.
 */
#include "fn_skeleton.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "affect/quat.h"

static affect_status opt_whole(const affect_json_node *n, const char *key, double lo, double hi,
                               double *out, affect_error *err)
{
    if (n->type != AFFECT_JSON_NUMBER || n->num != floor(n->num) || n->num < lo || n->num > hi)
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "option \"%s\" must be a whole number from %g to %g", key, lo, hi);
    *out = n->num;
    return AFFECT_OK;
}

static affect_status opt_free(const affect_json_doc *doc, const affect_json_node *n,
                              const affect_motion *m, ax_skel_opts *so, affect_error *err)
{
    if (n->type != AFFECT_JSON_ARRAY)
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "option \"free\" must be an array of joint names");
    so->free_link = affect_calloc(m->n_joints, sizeof *so->free_link);
    if (!so->free_link)
        return affect_nomem(err);
    uint32_t i = 0;
    for (const affect_json_node *e = affect_json_first(doc, n); e;
         e = affect_json_next_sibling(doc, e), i++) {
        int32_t j = e->type == AFFECT_JSON_STRING ? affect_motion_find_joint(m, e->str) : -1;
        if (j < 0) {
            char shown[80];
            if (e->type == AFFECT_JSON_STRING)
                affect_json_quote(shown, sizeof shown, e->str, e->str_len);
            else
                snprintf(shown, sizeof shown, "a %s", affect_json_type_name(e->type));
            return affect_fail(err, AFFECT_ERR_INVALID,
                               "option \"free\": item %u is not a joint name of "
                               "the motion: %s",
                               i, shown);
        }
        so->free_link[j] = true;
    }
    so->ik.rigid.free_link = so->free_link;
    return AFFECT_OK;
}

static affect_status opt_choice(const affect_json_node *n, const char *key,
                                const char *const *choices, int *out, affect_error *err)
{
    for (int k = 0; choices[k] && n->type == AFFECT_JSON_STRING; k++)
        if (strcmp(n->str, choices[k]) == 0) {
            *out = k;
            return AFFECT_OK;
        }
    char list[96] = "";
    for (int k = 0; choices[k]; k++) {
        strncat(list, k ? ", \"" : "\"", sizeof list - strlen(list) - 1);
        strncat(list, choices[k], sizeof list - strlen(list) - 1);
        strncat(list, "\"", sizeof list - strlen(list) - 1);
    }
    return affect_fail(err, AFFECT_ERR_INVALID, "option \"%s\" must be one of %s", key, list);
}

/* One option of ax_skel_opts_parse. */
static affect_status skel_opt(const affect_json_doc *doc, const affect_json_node *n,
                              const affect_motion *m, ax_skel_opts *so, affect_error *err)
{
    static const char *const sources[] = {"auto", "stored", "ik", NULL};
    static const char *const lengths[] = {"median", "first", NULL};
    static const char *const siblings[] = {"auto", "rotate", "translate", NULL};
    const char *key = n->key;
    double v = 0;
    int k = 0;
    affect_status st = AFFECT_OK;
    if (strcmp(key, "rotations") == 0) {
        if (!(st = opt_choice(n, key, sources, &k, err)))
            so->rotations = (affect_rotation_source)k;
    } else if (strcmp(key, "lengths") == 0) {
        if (!(st = opt_choice(n, key, lengths, &k, err)))
            so->ik.rigid.lengths = k ? AFFECT_RIGID_FIRST : AFFECT_RIGID_MEDIAN;
    } else if (strcmp(key, "siblings") == 0) {
        if (!(st = opt_choice(n, key, siblings, &k, err)))
            so->ik.siblings = (affect_ik_siblings)k;
    } else if (strcmp(key, "rest_frame") == 0) {
        if (!(st = opt_whole(n, key, 0, (double)m->n_frames - 1, &v, err)))
            so->ik.rest_frame = (uint32_t)v;
    } else if (strcmp(key, "precision") == 0) {
        if (!(st = opt_whole(n, key, 1, 9, &v, err)))
            so->bvh.precision = (int)v;
    } else if (strcmp(key, "frame_time") == 0) {
        if (n->type != AFFECT_JSON_NUMBER || !(n->num > 0) ||
            !(1.0 / n->num <= AFFECT_MOTION_MAX_FPS))
            return affect_fail(
                err, AFFECT_ERR_INVALID,
                "option \"frame_time\" must be a positive number of seconds (at most "
                "%g frames per second)",
                AFFECT_MOTION_MAX_FPS);
        so->bvh.frame_time = n->num;
    } else if (strcmp(key, "order") == 0) {
        if (n->type != AFFECT_JSON_STRING || !affect_euler_order_parse(n->str, so->ik.order))
            return affect_fail(err, AFFECT_ERR_INVALID,
                               "option \"order\" must be a rotation order such as \"ZXY\" (three "
                               "distinct axes of X, Y, Z)");
        memcpy(so->bvh.order, so->ik.order, sizeof so->bvh.order);
        so->order_given = true;
    } else if (strcmp(key, "root") == 0) {
        if (n->type != AFFECT_JSON_STRING || n->str_len == 0 || n->str_len != strlen(n->str) ||
            n->str_len > AFFECT_MOTION_MAX_NAME)
            return affect_fail(err, AFFECT_ERR_INVALID,
                               "option \"root\" must be a joint name (1 .. %u bytes)",
                               AFFECT_MOTION_MAX_NAME);
        so->bvh.root_name = n->str;
    } else if (strcmp(key, "free") == 0) {
        st = opt_free(doc, n, m, so, err);
    }
    return st;
}

affect_status ax_skel_opts_parse(const char *text, size_t len, const char *const *allowed,
                                 const affect_motion *m, ax_skel_opts *so, affect_error *err)
{
    memset(so, 0, sizeof *so);
    affect_ik_options_default(&so->ik);
    affect_bvh_write_options_default(&so->bvh);
    if (!text)
        return AFFECT_OK;
    affect_json_doc *doc = NULL;
    if (affect_json_parse(text, len, &doc, NULL, err)) {
        if (err->status == AFFECT_ERR_NOMEM)
            return AFFECT_ERR_NOMEM;
        char msg[AFFECT_ERROR_MSG_MAX];
        memcpy(msg, err->msg, sizeof msg);
        return affect_fail(err, AFFECT_ERR_INVALID, "options are not valid JSON: %.200s", msg);
    }
    /* root_name points into the document until it is copied at the end */
    const affect_json_node *root = affect_json_root(doc);
    affect_status st = AFFECT_OK;
    if (root->type != AFFECT_JSON_OBJECT) {
        st = affect_fail(err, AFFECT_ERR_INVALID, "options must be a JSON object, got %s",
                         affect_json_type_name(root->type));
        goto done;
    }
    for (const affect_json_node *n = affect_json_first(doc, root); n && !st;
         n = affect_json_next_sibling(doc, n)) {
        bool known = false;
        for (int k = 0; allowed[k] && !known; k++)
            known = strcmp(allowed[k], n->key) == 0;
        if (!known) {
            char shown[80], list[256] = "";
            affect_json_quote(shown, sizeof shown, n->key, n->key_len);
            for (int k = 0; allowed[k]; k++) {
                strncat(list, k ? ", " : "", sizeof list - strlen(list) - 1);
                strncat(list, allowed[k], sizeof list - strlen(list) - 1);
            }
            st = affect_fail(err, AFFECT_ERR_INVALID, "unknown option %s (expected one of: %s)",
                             shown, list);
            break;
        }
        st = skel_opt(doc, n, m, so, err);
    }
    if (!st && so->bvh.root_name) { /* copy: the document is freed below */
        char *copy = affect_strndup(so->bvh.root_name, strlen(so->bvh.root_name));
        if (!copy)
            st = affect_nomem(err);
        so->bvh.root_name = copy;
    } else {
        so->bvh.root_name = NULL; /* on an error it still points into the document */
    }
done:
    affect_json_free(doc);
    if (st)
        ax_skel_opts_free(so);
    return st;
}

void ax_skel_opts_free(ax_skel_opts *so)
{
    affect_free(so->free_link);
    affect_free((char *)so->bvh.root_name);
    so->free_link = NULL;
    so->bvh.root_name = NULL;
}

affect_status ax_skeletal(affect_motion *m, const ax_skel_opts *so, affect_motion **out,
                          affect_error *err)
{
    affect_motion *made = NULL;
    affect_status st = affect_motion_skeletal(m, so->rotations, &so->ik, &made, err);
    if (!st)
        *out = made ? made : m;
    return st;
}

/* Options argument i as text, or NULL when absent or NULL. */
static ax_arg opts_text(sqlite3_context *ctx, int argc, sqlite3_value **argv, int i,
                        const char **text, size_t *len)
{
    *text = NULL;
    *len = 0;
    if (i >= argc || sqlite3_value_type(argv[i]) == SQLITE_NULL)
        return AX_OK;
    if (sqlite3_value_type(argv[i]) != SQLITE_TEXT) {
        ax_errorf(ctx, "options (argument %d) must be a JSON object as text, got %s", i + 1,
                  ax_type_name(argv[i]));
        return AX_ERROR;
    }
    return ax_arg_text(ctx, argv, i, text, len) == AX_ERROR ? AX_ERROR : AX_OK;
}

static const char *const bvh_keys[] = {"order",     "frame_time", "precision", "root",
                                       "rotations", "rest_frame", "lengths",   "free",
                                       "siblings",  NULL};

void ax_motion_to_bvh(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    affect_motion *m = NULL, *sk = NULL;
    const char *text;
    size_t len;
    if (opts_text(ctx, argc, argv, 1, &text, &len) || ax_arg_motion(ctx, argv, 0, &m) != AX_OK)
        return;
    ax_skel_opts so;
    affect_error err;
    char *bvh = NULL;
    size_t n = 0;
    ax_monitor am;
    if (ax_monitor_begin(&am, ctx, NULL) != AX_OK) {
        affect_motion_free(m);
        return;
    }
    affect_status st = ax_skel_opts_parse(text, len, bvh_keys, m, &so, &err);
    if (!st) {
        so.ik.rigid.monitor = so.bvh.monitor = &am.mon; /* inverse kinematics and the text */
        st = ax_skeletal(m, &so, &sk, &err);
        if (!st)
            st = affect_bvh_write(sk, &so.bvh, &bvh, &n, &err);
        ax_skel_opts_free(&so);
    }
    ax_monitor_end(&am);
    if (st)
        ax_error(ctx, &err);
    else
        ax_result_text(ctx, bvh, n);
    if (sk != m)
        affect_motion_free(sk);
    affect_motion_free(m);
}

static const char *const rigid_keys[] = {"model", "lengths", "free", "sweeps", "tolerance", NULL};

void ax_motion_rigid(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    static const char *const lengths[] = {"median", "first", "reference", NULL};
    static const char *const models[] = {"bones", "skeleton", NULL};
    affect_motion *m = NULL, *ref = NULL, *out = NULL;
    if (ax_arg_motion(ctx, argv, 0, &m) != AX_OK)
        return;
    ax_opts opts;
    if (ax_opts_parse(ctx, argc, argv, 1, rigid_keys, &opts)) {
        affect_motion_free(m);
        return;
    }
    affect_rigid_options ro;
    affect_rigid_options_default(&ro);
    int which = 0, model = 0;
    double sweeps = ro.max_sweeps, tol = ro.tolerance;
    bool *free_link = NULL;
    affect_error err;
    if (ax_opt_enum(ctx, &opts, "lengths", lengths, &which) ||
        ax_opt_enum(ctx, &opts, "model", models, &model) ||
        ax_opt_number(ctx, &opts, "sweeps", &sweeps) ||
        ax_opt_number(ctx, &opts, "tolerance", &tol))
        goto done;
    if (sweeps != floor(sweeps) || sweeps < 1 || sweeps > 100000) {
        ax_errorf(ctx, "option \"sweeps\" must be a whole number from 1 to 100000");
        goto done;
    }
    if (!(tol > 0) || !(tol < 1)) {
        ax_errorf(ctx, "option \"tolerance\" must be a number between 0 and 1");
        goto done;
    }
    ro.max_sweeps = (uint32_t)sweeps;
    ro.tolerance = tol;
    ro.lengths = (affect_rigid_lengths)which;
    ro.model = (affect_rigid_model)model;
    if (argc > 2) {
        ax_arg a = ax_arg_motion(ctx, argv, 2, &ref);
        if (a == AX_ERROR)
            goto done;
        if (a == AX_NULL && which == AFFECT_RIGID_REFERENCE) {
            ax_errorf(ctx, "\"lengths\": \"reference\" needs a reference motion (argument 3)");
            goto done;
        }
        if (ref && !ax_opt(&opts, "lengths"))
            ro.lengths = AFFECT_RIGID_REFERENCE;
        ro.reference = ref;
    } else if (which == AFFECT_RIGID_REFERENCE) {
        ax_errorf(ctx, "\"lengths\": \"reference\" needs a reference motion (argument 3)");
        goto done;
    }
    const affect_json_node *fl = ax_opt(&opts, "free");
    if (fl) {
        ax_skel_opts so;
        memset(&so, 0, sizeof so);
        if (opt_free(opts.doc, fl, m, &so, &err)) {
            ax_error(ctx, &err);
            affect_free(so.free_link);
            goto done;
        }
        free_link = so.free_link;
        ro.free_link = free_link;
    }
    ax_monitor am;
    if (ax_monitor_begin(&am, ctx, NULL) != AX_OK)
        goto done;
    ro.monitor = &am.mon;
    affect_status st = affect_motion_rigid(m, &ro, &out, &err);
    ax_monitor_end(&am);
    if (st)
        ax_error(ctx, &err);
    else
        ax_result_motion(ctx, out);
done:
    affect_free(free_link);
    affect_motion_free(out);
    affect_motion_free(ref);
    affect_motion_free(m);
    ax_opts_free(&opts);
}
