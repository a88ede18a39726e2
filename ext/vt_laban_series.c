/*
 * vt_laban_series.c — laban_series, a table-valued function giving Weight, Time, Space and Flow
 * over a window sliding along a motion (core/laban/laban_series.c), to plot an Effort over a take:
 *
 *   SELECT frame, seconds, weight FROM laban_series(:motion) WHERE part = 'all';
 *   SELECT part, max(weight) FROM laban_series(:m, '{"window": 0.5, "hop": 0.1}') GROUP BY part;
 *   SELECT laban_plot(seconds, weight, part, '{"mode": "series"}')
 *     FROM laban_series(:m, '{"parts": ["left_hand", "right_hand"]}');
 *
 * Columns: frame (the window's centre frame, rounded down), seconds (its centre time, (first +
 * last) / 2 / fps), first_frame and last_frame (the frames it covers), part, and the four
 * Efforts over the window with the per-clip definitions (affect/laban.h): weight (peak kinetic
 * energy, or peak deceleration), time (peak acceleration, or accumulated velocity change),
 * space (path / net displacement, mean over the parts), flow (accumulated jerk). A window that
 * covers the whole motion gives laban_weight / laban_time / laban_space / laban_flow's values.
 * Rows run window by window, then part by part in the order of the "parts" option.
 *
 * Options (a JSON object, the second argument):
 *   window        window length in seconds (default 1), or window_frames (an integer ≥ 2)
 *   hop           seconds between window starts (default one frame), or hop_frames (≥ 1)
 *   parts         a name or an array of names (default all, torso, head, left_hand, right_hand,
 *                 left_foot, right_foot): "all" (the six together, laban_weight's default),
 *                 a part or a joint of the motion; at most six distinct parts ("all" counts as
 *                 its six)
 *   weight_method "peak" | "deceleration";  time_method "peak" | "accumulated";
 *   per_second (accumulated Time ÷ the window's duration), max_ratio (Space's cap, 100),
 *   cutoff_hz (6), up, roles, missing ("error" | "null": a part whose role is unresolved
 *   gives rows of NULL values, "all" too when one of its six is; a motion of fewer than four
 *   frames gives no rows) — as for laban_weight.
 * Windows start at frames 0, hop, 2·hop, … while they fit in the motion; a window longer than
 * the motion is cut to it (one window). A NULL motion gives no rows; bad arguments give
 * "laban_series: …" errors.
 *
 * How it works: an eponymous-only virtual table with the schema
 *   CREATE TABLE x(frame INTEGER, seconds REAL, first_frame INTEGER, last_frame INTEGER,
 *                  part TEXT, weight REAL, time REAL, space REAL, flow REAL,
 *                  motion HIDDEN, options HIDDEN)
 * xBestIndex needs an equality constraint on motion (idxNum bit 1) and takes one on options
 * (bit 2). xFilter decodes the motion and computes the parts' kinematics once; each window is
 * computed when the cursor reaches it (O(frames · parts) in all, a few windows' memory), so a
 * long motion with a one-frame hop streams rather than filling memory. The statement's
 * interrupt stops both (the cursor keeps the monitor). rowid = window × rows per window + row.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fn_laban.h"

#include "affect/laban.h"

enum {
    COL_FRAME,
    COL_SECONDS,
    COL_FIRST,
    COL_LAST,
    COL_PART,
    COL_WEIGHT,
    COL_TIME,
    COL_SPACE,
    COL_FLOW,
    COL_MOTION,
    COL_OPTIONS
};

#define MAX_SHOWN 16 /* rows per window the "parts" option may ask for */

static const char *const standard_parts[6] = {"torso",      "head",      "left_hand",
                                              "right_hand", "left_foot", "right_foot"};

typedef struct series_cursor {
    sqlite3_vtab_cursor base;
    affect_motion *m;
    affect_laban_options lo;
    ax_monitor am;
    bool monitoring;
    affect_laban_series *series; /* NULL when no part could be resolved (rows of NULL) */
    uint32_t window, hop, n_windows, n_frames;
    double fps;
    /* the rows of a window: their names (in the options' JSON document or static) and the
     * core row each shows (−1: NULL values) */
    uint32_t n_shown;
    char *names[MAX_SHOWN];
    int core_row[MAX_SHOWN];
    double *values; /* the current window's rows × AFFECT_SERIES_N */
    uint32_t win, row, first, last;
    bool eof;
} series_cursor;

static int series_connect(sqlite3 *db, void *aux, int argc, const char *const *argv,
                          sqlite3_vtab **out, char **err)
{
    return ax_tvf_connect(db,
                          "CREATE TABLE x(frame INTEGER, seconds REAL, "
                          "first_frame INTEGER, last_frame INTEGER, part TEXT, "
                          "weight REAL, time REAL, space REAL, flow REAL, "
                          "motion HIDDEN, options HIDDEN)",
                          out);
}

static int series_open(sqlite3_vtab *vt, sqlite3_vtab_cursor **out)
{
    int rc = ax_tvf_open(sizeof(series_cursor), out);
    if (rc == SQLITE_OK)
        ((series_cursor *)*out)->eof = true;
    return rc;
}

static void series_reset(series_cursor *c)
{
    affect_laban_series_free(c->series);
    if (c->monitoring)
        ax_monitor_end(&c->am);
    affect_motion_free(c->m);
    sqlite3_free(c->values);
    for (uint32_t i = 0; i < c->n_shown; i++)
        sqlite3_free(c->names[i]);
    memset(c, 0, sizeof *c);
    c->eof = true;
}

static int series_close(sqlite3_vtab_cursor *cur)
{
    series_cursor *c = (series_cursor *)cur;
    sqlite3_vtab_cursor base = c->base;
    series_reset(c);
    c->base = base;
    sqlite3_free(cur);
    return SQLITE_OK;
}

/* "laban_series: …" as the table's error (ax_vtab_error); a missing role says how to assign it. */
static int series_error(sqlite3_vtab *vt, const affect_error *err)
{
    if (err->status == AFFECT_ERR_MISSING)
        return ax_vtab_error(vt, err,
                             "laban_series: %s (assign it with {\"roles\": {…}}, or use "
                             "{\"missing\": \"null\"})",
                             err->msg);
    return ax_vtab_error(vt, err, "laban_series: %s", err->msg);
}

/* ---- options ---- */

static const char *const series_keys[] = {"window",      "window_frames",
                                          "hop",         "hop_frames",
                                          "parts",       "weight_method",
                                          "time_method", "per_second",
                                          "max_ratio",   "cutoff_hz",
                                          "up",          "roles",
                                          "missing",     NULL};

typedef struct series_opts {
    affect_json_doc *doc;
    const affect_json_node *obj;
} series_opts;

static const affect_json_node *opt_get(const series_opts *o, const char *key)
{
    return o->obj ? affect_json_get(o->doc, o->obj, key) : NULL;
}

static affect_status wrong_type(const char *key, const char *want, const affect_json_node *n,
                                affect_error *err)
{
    return affect_fail(err, AFFECT_ERR_INVALID, "option \"%s\" must be %s, got %s", key, want,
                       affect_json_type_name(n->type));
}

static affect_status opt_number(const series_opts *o, const char *key, double *out, bool *given,
                                affect_error *err)
{
    const affect_json_node *n = opt_get(o, key);
    if (given)
        *given = n != NULL;
    if (!n)
        return AFFECT_OK;
    if (n->type != AFFECT_JSON_NUMBER)
        return wrong_type(key, "a number", n, err);
    *out = n->num;
    return AFFECT_OK;
}

static affect_status opt_bool(const series_opts *o, const char *key, bool *out, affect_error *err)
{
    const affect_json_node *n = opt_get(o, key);
    if (!n)
        return AFFECT_OK;
    if (n->type != AFFECT_JSON_TRUE && n->type != AFFECT_JSON_FALSE)
        return wrong_type(key, "true or false", n, err);
    *out = n->type == AFFECT_JSON_TRUE;
    return AFFECT_OK;
}

/* A string among choices (two or three, NULL-terminated): *out its index. */
static affect_status opt_enum(const series_opts *o, const char *key, const char *const *choices,
                              int *out, affect_error *err)
{
    const affect_json_node *n = opt_get(o, key);
    if (!n)
        return AFFECT_OK;
    if (n->type == AFFECT_JSON_STRING)
        for (int k = 0; choices[k]; k++)
            if (strcmp(choices[k], n->str) == 0) {
                *out = k;
                return AFFECT_OK;
            }
    char list[96] = "", got[80];
    size_t used = 0;
    for (int k = 0; choices[k]; k++) {
        int w = snprintf(list + used, sizeof list - used, "%s\"%s\"", k ? ", " : "", choices[k]);
        if (w > 0 && (size_t)w < sizeof list - used)
            used += (size_t)w;
    }
    if (n->type == AFFECT_JSON_STRING)
        affect_json_quote(got, sizeof got, n->str, n->str_len);
    return affect_fail(err, AFFECT_ERR_INVALID, "option \"%s\" must be one of %s, got %s", key,
                       list, n->type == AFFECT_JSON_STRING ? got : affect_json_type_name(n->type));
}

static affect_status opts_parse(const char *text, size_t len, series_opts *o, affect_error *err)
{
    o->doc = NULL;
    o->obj = NULL;
    if (!text)
        return AFFECT_OK;
    affect_status st = affect_json_parse(text, len, &o->doc, NULL, err);
    if (st) {
        if (st == AFFECT_ERR_NOMEM)
            return st;
        char msg[AFFECT_ERROR_MSG_MAX];
        memcpy(msg, err->msg, sizeof msg);
        return affect_fail(err, AFFECT_ERR_INVALID, "options are not valid JSON: %.200s", msg);
    }
    const affect_json_node *root = affect_json_root(o->doc);
    if (root->type != AFFECT_JSON_OBJECT)
        return affect_fail(err, AFFECT_ERR_INVALID, "options must be a JSON object, got %s",
                           affect_json_type_name(root->type));
    for (const affect_json_node *m = affect_json_first(o->doc, root); m;
         m = affect_json_next_sibling(o->doc, m)) {
        bool known = false;
        for (int k = 0; series_keys[k] && !known; k++)
            known = strcmp(series_keys[k], m->key) == 0;
        if (!known) {
            char q[80];
            affect_json_quote(q, sizeof q, m->key, m->key_len);
            return affect_fail(err, AFFECT_ERR_INVALID,
                               "unknown option %s (expected window, window_frames, hop, "
                               "hop_frames, parts, weight_method, time_method, per_second, "
                               "max_ratio, cutoff_hz, up, roles, missing)",
                               q);
        }
    }
    o->obj = root;
    return AFFECT_OK;
}

/* Frames of the "window"/"window_frames" (or "hop"/"hop_frames") options; *out unchanged when
 * neither is given. */
static affect_status opt_frames(const series_opts *o, const char *sec_key, const char *frames_key,
                                uint32_t min, double fps, uint32_t *out, affect_error *err)
{
    double sec = 0, frames = 0;
    bool has_sec, has_frames;
    affect_status st = opt_number(o, sec_key, &sec, &has_sec, err);
    if (!st)
        st = opt_number(o, frames_key, &frames, &has_frames, err);
    if (st)
        return st;
    if (has_sec && has_frames)
        return affect_fail(err, AFFECT_ERR_INVALID, "give \"%s\" or \"%s\", not both", sec_key,
                           frames_key);
    if (has_frames) {
        if (!(frames >= min) || !isfinite(frames) || frames != floor(frames))
            return affect_fail(err, AFFECT_ERR_INVALID,
                               "option \"%s\" must be an integer of at least %u, got %.15g",
                               frames_key, min, frames);
        *out = frames >= 4294967295.0 ? UINT32_MAX : (uint32_t)frames; /* longer than any take */
    } else if (has_sec) {
        uint32_t f = affect_laban_series_frames(sec, fps);
        if (!(sec > 0) || f < min)
            return affect_fail(err, AFFECT_ERR_INVALID,
                               "option \"%s\" must be at least %u frame%s (%.15g s at %.15g fps), "
                               "got %.15g s",
                               sec_key, min, min > 1 ? "s" : "", (min - 0.5) / fps, fps, sec);
        *out = f;
    }
    return AFFECT_OK;
}

/* The roles option (ax_opt_roles' rules, without a context). */
static affect_status opt_roles(const series_opts *o, const affect_motion *m, affect_roles *roles,
                               affect_error *err)
{
    affect_roles_resolve(m, roles);
    const affect_json_node *n = opt_get(o, "roles");
    if (!n)
        return AFFECT_OK;
    if (n->type != AFFECT_JSON_OBJECT)
        return wrong_type("roles", "an object of role names to joint names", n, err);
    for (const affect_json_node *r = affect_json_first(o->doc, n); r;
         r = affect_json_next_sibling(o->doc, r)) {
        if (r->type != AFFECT_JSON_STRING && r->type != AFFECT_JSON_NULL)
            return affect_fail(err, AFFECT_ERR_INVALID,
                               "option \"roles\": \"%.64s\" must map to a joint name or null, "
                               "got %s",
                               r->key, affect_json_type_name(r->type));
        affect_error e;
        if (affect_roles_set(m, roles, r->key, r->type == AFFECT_JSON_STRING ? r->str : NULL, &e)) {
            if (e.status == AFFECT_ERR_NOMEM)
                return affect_nomem(err);
            return affect_fail(err, AFFECT_ERR_INVALID, "option \"roles\": %s", e.msg);
        }
    }
    return AFFECT_OK;
}

/* The names of the "parts" option into c->names (copies). */
static affect_status opt_parts(const series_opts *o, series_cursor *c, affect_error *err)
{
    const affect_json_node *n = opt_get(o, "parts");
    if (!n) {
        static const char *const defaults[7] = {"all",        "torso",     "head",      "left_hand",
                                                "right_hand", "left_foot", "right_foot"};
        for (int i = 0; i < 7; i++)
            if (!(c->names[c->n_shown++] = sqlite3_mprintf("%s", defaults[i])))
                return affect_nomem(err);
        return AFFECT_OK;
    }
    if (n->type != AFFECT_JSON_STRING && n->type != AFFECT_JSON_ARRAY)
        return wrong_type("parts", "a part name or an array of them", n, err);
    if (n->type == AFFECT_JSON_ARRAY && (n->count < 1 || n->count > MAX_SHOWN))
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "option \"parts\" must name 1 to %d parts, got %u", MAX_SHOWN, n->count);
    const affect_json_node *e = n->type == AFFECT_JSON_STRING ? n : affect_json_first(o->doc, n);
    for (; e; e = n->type == AFFECT_JSON_STRING ? NULL : affect_json_next_sibling(o->doc, e)) {
        if (e->type != AFFECT_JSON_STRING)
            return affect_fail(err, AFFECT_ERR_INVALID,
                               "option \"parts\": every element must be a part name, got %s",
                               affect_json_type_name(e->type));
        if (strlen(e->str) != e->str_len || e->str_len == 0)
            return affect_fail(err, AFFECT_ERR_INVALID,
                               "option \"parts\": a part name must be non-empty text without "
                               "NUL characters");
        for (uint32_t i = 0; i < c->n_shown; i++)
            if (strcmp(c->names[i], e->str) == 0) {
                char q[80];
                affect_json_quote(q, sizeof q, e->str, e->str_len);
                return affect_fail(err, AFFECT_ERR_INVALID, "option \"parts\" names %s twice", q);
            }
        if (!(c->names[c->n_shown++] = sqlite3_mprintf("%s", e->str)))
            return affect_nomem(err);
    }
    return AFFECT_OK;
}

/* Resolves the shown rows to the core's parts and starts the series. */
static affect_status start_series(series_cursor *c, const affect_roles *roles,
                                  const affect_laban_series_options *so_in, affect_error *err)
{
    affect_part parts[6];
    const char *part_names[6];
    uint32_t n = 0;
    bool all = false, all_ok = true;
    int part_of[MAX_SHOWN]; /* index in parts, or −1 (unresolved), −2 ("all") */
    for (uint32_t i = 0; i < c->n_shown; i++)
        if (strcmp(c->names[i], "all") == 0)
            all = true;
    if (all) { /* the six first, in their order, so the combined row is theirs */
        for (int k = 0; k < 6; k++) {
            affect_part p;
            affect_status st = affect_part_resolve(c->m, roles, standard_parts[k], &p, err);
            if (st == AFFECT_ERR_MISSING && c->lo.missing_null) {
                all_ok = false;
                continue;
            }
            if (st)
                return st;
            part_names[n] = standard_parts[k];
            parts[n++] = p;
        }
    }
    for (uint32_t i = 0; i < c->n_shown; i++) {
        const char *name = c->names[i];
        part_of[i] = -1;
        if (strcmp(name, "all") == 0) {
            part_of[i] = -2;
            continue;
        }
        for (uint32_t k = 0; k < n; k++)
            if (strcmp(part_names[k], name) == 0)
                part_of[i] = (int)k;
        if (part_of[i] >= 0)
            continue;
        affect_part p;
        affect_status st = affect_part_resolve(c->m, roles, name, &p, err);
        if (st == AFFECT_ERR_MISSING && c->lo.missing_null)
            continue;
        if (st)
            return st;
        if (n == 6)
            return affect_fail(err, AFFECT_ERR_INVALID,
                               "option \"parts\": at most 6 distinct parts (\"all\" counts as "
                               "its six), and \"%.64s\" is a seventh",
                               name);
        part_names[n] = name;
        parts[n] = p;
        part_of[i] = (int)n++;
    }
    affect_laban_series_options so = *so_in;
    so.combined = all && all_ok && n > 0;
    if (n > 0) {
        for (uint32_t k = 0; k < n; k++)
            parts[k].name = part_names[k];
        affect_status st = affect_laban_series_new(c->m, parts, n, &c->lo, &so, &c->series, err);
        if (st)
            return st;
    }
    for (uint32_t i = 0; i < c->n_shown; i++)
        c->core_row[i] = part_of[i] == -2  ? (so.combined ? 0 : -1)
                         : part_of[i] >= 0 ? part_of[i] + (so.combined ? 1 : 0)
                                           : -1;
    uint32_t rows = n + (so.combined ? 1 : 0);
    c->values =
        sqlite3_malloc64((sqlite3_uint64)(rows ? rows : 1) * AFFECT_SERIES_N * sizeof *c->values);
    return c->values ? AFFECT_OK : affect_nomem(err);
}

/* Computes the window c->win (rows in order: windows are computed once each, in order). */
static affect_status load_window(series_cursor *c, affect_error *err)
{
    if (c->win >= c->n_windows) {
        c->eof = true;
        return AFFECT_OK;
    }
    if (c->series)
        return affect_laban_series_next(c->series, &c->first, &c->last, c->values, err);
    c->first = c->win * c->hop;
    c->last = c->first + (c->window < c->n_frames ? c->window : c->n_frames) - 1;
    return AFFECT_OK;
}

static int series_filter(sqlite3_vtab_cursor *cur, int idx_num, const char *idx_str, int argc,
                         sqlite3_value **argv)
{
    series_cursor *c = (series_cursor *)cur;
    sqlite3_vtab_cursor base = c->base;
    series_reset(c);
    c->base = base;
    affect_error err;
    const char *text;
    size_t len;
    char *msg = NULL;
    if (ax_monitor_begin_db(&c->am, ((ax_tvf_vtab *)cur->pVtab)->db, NULL, &msg) != SQLITE_OK) {
        sqlite3_free(msg); /* no progress function: cannot fail */
        return SQLITE_NOMEM;
    }
    c->monitoring = true;
    if (ax_motion_tvf_args(idx_num, argc, argv, &c->am.mon, &c->m, &text, &len, &err))
        return series_error(cur->pVtab, &err);
    if (!c->m)
        return SQLITE_OK; /* a NULL motion: no rows */
    static const char *const missing[] = {"error", "null", NULL};
    static const char *const weights[] = {"peak", "deceleration", NULL};
    static const char *const times[] = {"peak", "accumulated", NULL};
    static const char *const axes[] = {"x", "y", "z", NULL};
    series_opts o;
    affect_roles roles;
    affect_laban_series_options so;
    affect_laban_series_options_default(&so);
    affect_laban_options_default(&c->lo);
    c->fps = c->m->fps;
    c->n_frames = c->m->n_frames;
    c->window = affect_laban_series_frames(1.0, c->fps);
    if (c->window < 2)
        c->window = 2;
    c->hop = 1;
    int miss = 0, wm = 0, tm = 0;
    affect_status st = opts_parse(text, len, &o, &err);
    if (!st)
        st = opt_frames(&o, "window", "window_frames", 2, c->fps, &c->window, &err);
    if (!st)
        st = opt_frames(&o, "hop", "hop_frames", 1, c->fps, &c->hop, &err);
    if (!st)
        st = opt_number(&o, "cutoff_hz", &c->lo.cutoff_hz, NULL, &err);
    if (!st)
        st = opt_number(&o, "max_ratio", &c->lo.max_ratio, NULL, &err);
    if (!st)
        st = opt_bool(&o, "per_second", &c->lo.time_per_second, &err);
    if (!st)
        st = opt_enum(&o, "up", axes, &c->lo.up_axis, &err);
    if (!st)
        st = opt_enum(&o, "missing", missing, &miss, &err);
    if (!st)
        st = opt_enum(&o, "weight_method", weights, &wm, &err);
    if (!st)
        st = opt_enum(&o, "time_method", times, &tm, &err);
    if (!st)
        st = opt_roles(&o, c->m, &roles, &err);
    if (!st)
        st = opt_parts(&o, c, &err);
    affect_json_free(o.doc);
    if (st)
        return series_error(cur->pVtab, &err);
    c->lo.missing_null = miss == 1;
    c->lo.monitor = &c->am.mon;
    so.window = c->window;
    so.hop = c->hop;
    so.weight = wm == 1 ? AFFECT_LABAN_Q2 : AFFECT_LABAN_Q1;
    so.time = tm == 1 ? AFFECT_LABAN_Q2 : AFFECT_LABAN_Q1;
    if (c->n_frames < 4 && c->lo.missing_null)
        return SQLITE_OK; /* no rows */
    st = start_series(c, &roles, &so, &err);
    if (st)
        return series_error(cur->pVtab, &err);
    c->n_windows = c->series                 ? affect_laban_series_windows(c->series)
                   : c->window < c->n_frames ? (c->n_frames - c->window) / c->hop + 1
                                             : 1;
    c->eof = false;
    if ((st = load_window(c, &err)))
        return series_error(cur->pVtab, &err);
    return SQLITE_OK;
}

static int series_next(sqlite3_vtab_cursor *cur)
{
    series_cursor *c = (series_cursor *)cur;
    if (++c->row < c->n_shown)
        return SQLITE_OK;
    c->row = 0;
    c->win++;
    affect_error err;
    affect_status st = load_window(c, &err);
    return st ? series_error(cur->pVtab, &err) : SQLITE_OK;
}

static int series_eof(sqlite3_vtab_cursor *cur)
{
    return ((series_cursor *)cur)->eof;
}

static int series_column(sqlite3_vtab_cursor *cur, sqlite3_context *ctx, int col)
{
    series_cursor *c = (series_cursor *)cur;
    int r = c->core_row[c->row];
    switch (col) {
    case COL_FRAME:
        sqlite3_result_int64(ctx, c->first + (c->last - c->first) / 2);
        break;
    case COL_SECONDS:
        sqlite3_result_double(ctx, ((double)c->first + c->last) / 2.0 / c->fps);
        break;
    case COL_FIRST:
        sqlite3_result_int64(ctx, c->first);
        break;
    case COL_LAST:
        sqlite3_result_int64(ctx, c->last);
        break;
    case COL_PART:
        sqlite3_result_text(ctx, c->names[c->row], -1, SQLITE_TRANSIENT);
        break;
    case COL_WEIGHT:
    case COL_TIME:
    case COL_SPACE:
    case COL_FLOW: {
        static const int q[4] = {AFFECT_SERIES_WEIGHT, AFFECT_SERIES_TIME, AFFECT_SERIES_SPACE,
                                 AFFECT_SERIES_FLOW};
        double v = r < 0 ? NAN : c->values[(size_t)r * AFFECT_SERIES_N + q[col - COL_WEIGHT]];
        if (isnan(v))
            sqlite3_result_null(ctx);
        else
            sqlite3_result_double(ctx, v);
        break;
    }
    default:
        sqlite3_result_null(ctx);
        break; /* the hidden argument columns */
    }
    return SQLITE_OK;
}

static int series_rowid(sqlite3_vtab_cursor *cur, sqlite3_int64 *rowid)
{
    series_cursor *c = (series_cursor *)cur;
    *rowid = (sqlite3_int64)c->win * c->n_shown + c->row;
    return SQLITE_OK;
}

static int series_best_index(sqlite3_vtab *vt, sqlite3_index_info *info)
{
    return ax_motion_tvf_best_index(vt, info, COL_MOTION, COL_OPTIONS, "laban_series");
}

static sqlite3_module series_module = {
    .iVersion = 0,
    .xConnect = series_connect,
    .xBestIndex = series_best_index,
    .xDisconnect = ax_tvf_disconnect,
    .xOpen = series_open,
    .xClose = series_close,
    .xFilter = series_filter,
    .xNext = series_next,
    .xEof = series_eof,
    .xColumn = series_column,
    .xRowid = series_rowid,
};

int ax_register_laban_series(sqlite3 *db)
{
    return sqlite3_create_module(db, "laban_series", &series_module, NULL);
}
