/*
 * common.c — argument checking, BLOB/JSON in and out, and error mapping for the SQL
 * functions (see common.h).
 */
#include "common.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "util/strbuf.h"

void ax_error(sqlite3_context *ctx, const affect_error *err)
{
    if (affect_nomem_named(err)) { /* a large request: say which, not a bare SQLITE_NOMEM */
        ax_errorf(ctx, "%s: out of memory", err->msg);
        return;
    }
    if (err->status == AFFECT_ERR_NOMEM) {
        sqlite3_result_error_nomem(ctx);
        return;
    }
    if (err->status == AFFECT_ERR_INTERRUPTED) { /* whatever context the core added */
        ax_interrupted(ctx);
        return;
    }
    ax_errorf(ctx, "%s", err->msg);
}

void ax_interrupted(sqlite3_context *ctx)
{
    ax_errorf(ctx, "interrupted");
    sqlite3_result_error_code(ctx, SQLITE_INTERRUPT);
}

void ax_errorf(sqlite3_context *ctx, const char *fmt, ...)
{
    char raw[AFFECT_ERROR_MSG_MAX + 512]; /* room for a list of the allowed option keys */
    char msg[sizeof raw];
    int n = snprintf(raw, sizeof raw, "%s: ", AX_NAME(ctx));
    if (n < 0)
        n = 0;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(raw + n, sizeof raw - (size_t)n, fmt, ap);
    va_end(ap);
    /* what the message quotes (a name, a text argument) may not be UTF-8: clients decode it */
    affect_escape_text(msg, sizeof msg, raw, strlen(raw));
    sqlite3_result_error(ctx, msg, -1);
}

/* raw (sqlite3_malloc'd, may be NULL) escaped into a new string; raw is freed. */
static char *escape_message(char *raw)
{
    if (!raw)
        return NULL;
    size_t len = strlen(raw);
    char *msg = sqlite3_malloc64(4 * (sqlite3_uint64)len + 1); /* every byte may become \xNN */
    if (msg)
        affect_escape_text(msg, 4 * len + 1, raw, len);
    sqlite3_free(raw);
    return msg;
}

char *ax_mprintf(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    char *raw = sqlite3_vmprintf(fmt, ap);
    va_end(ap);
    return escape_message(raw);
}

static int error_into(char **dst, const affect_error *err, const char *fmt, va_list ap)
{
    if (err && err->status == AFFECT_ERR_NOMEM)
        return SQLITE_NOMEM;
    if (err && err->status == AFFECT_ERR_INTERRUPTED)
        return SQLITE_INTERRUPT;
    char *raw = sqlite3_vmprintf(fmt, ap);
    sqlite3_free(*dst);
    *dst = escape_message(raw);
    return *dst ? SQLITE_ERROR : SQLITE_NOMEM;
}

int ax_vtab_error(sqlite3_vtab *vt, const affect_error *err, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int rc = error_into(&vt->zErrMsg, err, fmt, ap);
    va_end(ap);
    return rc;
}

int ax_error_into(char **dst, const affect_error *err, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int rc = error_into(dst, err, fmt, ap);
    va_end(ap);
    return rc;
}

const char *ax_type_name(sqlite3_value *v)
{
    switch (sqlite3_value_type(v)) {
    case SQLITE_INTEGER:
        return "integer";
    case SQLITE_FLOAT:
        return "real";
    case SQLITE_TEXT:
        return "text";
    case SQLITE_BLOB:
        return "blob";
    default:
        return "null";
    }
}

ax_arg ax_arg_motion(sqlite3_context *ctx, sqlite3_value **argv, int i, affect_motion **out)
{
    sqlite3_value *v = argv[i];
    int type = sqlite3_value_type(v);
    if (type == SQLITE_NULL)
        return AX_NULL;
    if (type != SQLITE_BLOB) {
        ax_errorf(ctx, "argument %d must be a motion BLOB, got %s", i + 1, ax_type_name(v));
        return AX_ERROR;
    }
    const unsigned char *data = sqlite3_value_blob(v);
    int n = sqlite3_value_bytes(v);
    if (!data && n > 0) {
        sqlite3_result_error_nomem(ctx);
        return AX_ERROR;
    }
    affect_error err;
    ax_monitor am; /* a motion at the size limit takes tenths of a second to decode */
    if (ax_monitor_begin(&am, ctx, NULL) != AX_OK)
        return AX_ERROR;
    affect_status st = affect_motion_decode_monitored(data, (size_t)n, &am.mon, out, &err);
    ax_monitor_end(&am);
    if (st) {
        if (err.status == AFFECT_ERR_NOMEM || err.status == AFFECT_ERR_INTERRUPTED)
            ax_error(ctx, &err);
        else
            ax_errorf(ctx, "argument %d is not a valid motion: %s", i + 1, err.msg);
        return AX_ERROR;
    }
    return AX_OK;
}

ax_arg ax_arg_text(sqlite3_context *ctx, sqlite3_value **argv, int i, const char **text,
                   size_t *len)
{
    sqlite3_value *v = argv[i];
    int type = sqlite3_value_type(v);
    if (type == SQLITE_NULL)
        return AX_NULL;
    if (type == SQLITE_BLOB) {
        ax_errorf(ctx, "argument %d must be text, got blob", i + 1);
        return AX_ERROR;
    }
    const unsigned char *t = sqlite3_value_text(v);
    if (!t) {
        sqlite3_result_error_nomem(ctx);
        return AX_ERROR;
    }
    *text = (const char *)t;
    *len = (size_t)sqlite3_value_bytes(v);
    return AX_OK;
}

ax_arg ax_arg_document(sqlite3_context *ctx, sqlite3_value **argv, int i, const char **text,
                       size_t *len)
{
    if (sqlite3_value_type(argv[i]) != SQLITE_BLOB)
        return ax_arg_text(ctx, argv, i, text, len);
    int n = sqlite3_value_bytes(argv[i]);
    const void *b = sqlite3_value_blob(argv[i]);
    if (!b && n > 0) {
        sqlite3_result_error_nomem(ctx);
        return AX_ERROR;
    }
    *text = b ? (const char *)b : "";
    *len = (size_t)n;
    return AX_OK;
}

void ax_blob_cache_clear(ax_blob_cache *c)
{
    if (c->obj)
        c->free_obj(c->obj);
    sqlite3_free(c->bytes);
    c->obj = NULL;
    c->bytes = NULL;
    c->size = 0;
}

ax_cached_fn *ax_cached_fn_new(const char *name)
{
    ax_cached_fn *fn = sqlite3_malloc64(sizeof *fn);
    if (!fn)
        return NULL;
    memset(fn, 0, sizeof *fn);
    ax_copy_name(fn->name, sizeof fn->name, name);
    return fn;
}

void ax_cached_fn_free(void *p)
{
    ax_cached_fn *fn = p;
    if (fn) {
        ax_blob_cache_clear(&fn->cache);
        sqlite3_free(fn);
    }
}

ax_arg ax_arg_cached_blob(sqlite3_context *ctx, sqlite3_value **argv, ax_blob_cache *c,
                          ax_decode_fn decode, void (*free_obj)(void *), const char *what,
                          const char *from, const void **out)
{
    sqlite3_value *v = argv[0];
    int type = sqlite3_value_type(v);
    *out = NULL;
    if (type == SQLITE_NULL)
        return AX_NULL;
    if (type != SQLITE_BLOB) {
        ax_errorf(ctx, "argument 1 must be a %s BLOB (from %s), got %s", what, from,
                  ax_type_name(v));
        return AX_ERROR;
    }
    const unsigned char *data = sqlite3_value_blob(v);
    size_t n = (size_t)sqlite3_value_bytes(v);
    if (!data && n > 0) {
        sqlite3_result_error_nomem(ctx);
        return AX_ERROR;
    }
    if (c->obj && c->size == n && memcmp(c->bytes, data, n) == 0) {
        *out = c->obj;
        return AX_OK;
    }
    ax_blob_cache_clear(c);
    void *obj = NULL;
    affect_error err;
    if (decode(data ? data : (const unsigned char *)"", n, &obj, &err)) {
        if (err.status == AFFECT_ERR_NOMEM)
            ax_error(ctx, &err); /* SQLITE_NOMEM, or the large block it could not allocate */
        else
            ax_errorf(ctx, "argument 1 is not a valid %s: %s", what, err.msg);
        return AX_ERROR;
    }
    c->bytes = sqlite3_malloc64(n ? n : 1);
    if (!c->bytes) {
        free_obj(obj);
        sqlite3_result_error_nomem(ctx);
        return AX_ERROR;
    }
    memcpy(c->bytes, data, n);
    c->size = n;
    c->obj = obj;
    c->free_obj = free_obj;
    *out = obj;
    return AX_OK;
}

static int cmp_text(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

ax_arg ax_label_classes(sqlite3_context *ctx, char *const *labels, uint32_t n, char **classes,
                        uint32_t *n_classes, uint32_t *y)
{
    uint32_t k = 0;
    memcpy(classes, labels, n * sizeof *classes);
    qsort(classes, n, sizeof *classes, cmp_text);
    for (uint32_t i = 0; i < n; i++)
        if (k == 0 || strcmp(classes[i], classes[k - 1]) != 0)
            classes[k++] = classes[i];
    *n_classes = k;
    if (k < 2) {
        ax_errorf(ctx, "need motions of at least 2 labels, got 1 (\"%s\")", classes[0]);
        return AX_ERROR;
    }
    for (uint32_t i = 0; i < n; i++) {
        char **hit = bsearch(&labels[i], classes, k, sizeof *classes, cmp_text);
        y[i] = (uint32_t)(hit - classes);
    }
    return AX_OK;
}

ax_arg ax_arg_int(sqlite3_context *ctx, sqlite3_value **argv, int i, int64_t *out)
{
    sqlite3_value *v = argv[i];
    switch (sqlite3_value_type(v)) {
    case SQLITE_NULL:
        return AX_NULL;
    case SQLITE_INTEGER:
        *out = sqlite3_value_int64(v);
        return AX_OK;
    case SQLITE_FLOAT: {
        double d = sqlite3_value_double(v);
        if (d == floor(d) && fabs(d) < 9e15) {
            *out = (int64_t)d;
            return AX_OK;
        }
        break;
    }
    default:
        break;
    }
    ax_errorf(ctx, "argument %d must be an integer, got %s", i + 1, ax_type_name(v));
    return AX_ERROR;
}

ax_arg ax_arg_double(sqlite3_context *ctx, sqlite3_value **argv, int i, double *out)
{
    sqlite3_value *v = argv[i];
    int type = sqlite3_value_type(v);
    if (type == SQLITE_NULL)
        return AX_NULL;
    if (type == SQLITE_INTEGER || type == SQLITE_FLOAT) {
        *out = sqlite3_value_double(v);
        if (isfinite(*out))
            return AX_OK;
    }
    ax_errorf(ctx, "argument %d must be a finite number, got %s", i + 1, ax_type_name(v));
    return AX_ERROR;
}

void ax_result_motion(sqlite3_context *ctx, const affect_motion *m)
{
    size_t n;
    if (!affect_motion_encoded_size(m, &n)) {
        /* a name the decoder would refuse (affect_motion_encode says which), or too large */
        unsigned char *buf = NULL;
        affect_error err;
        if (affect_motion_encode(m, &buf, &n, &err) == AFFECT_ERR_INVALID) {
            ax_error(ctx, &err);
            return;
        }
        affect_free(buf);
        sqlite3_result_error_toobig(ctx);
        return;
    }
    if (n > 0x7fffffff) {
        sqlite3_result_error_toobig(ctx);
        return;
    }
    unsigned char *buf = sqlite3_malloc64(n);
    if (!buf) {
        sqlite3_result_error_nomem(ctx);
        return;
    }
    affect_motion_encode_into(m, buf);
    sqlite3_result_blob64(ctx, buf, n, sqlite3_free);
}

void ax_result_text(sqlite3_context *ctx, char *text, size_t len)
{
    sqlite3_result_text64(ctx, text, len, sqlite3_free, SQLITE_UTF8);
}

void ax_copy_name(char *dst, size_t size, const char *name)
{
    size_t len = strlen(name);
    if (len >= size)
        len = size - 1;
    memcpy(dst, name, len);
    dst[len] = '\0';
}

void ax_put_f32(unsigned char *p, float f)
{
    uint32_t u = 0x7fc00000u;
    if (!isnan(f))
        memcpy(&u, &f, 4);
    for (int b = 0; b < 4; b++)
        p[b] = (unsigned char)(u >> (8 * b));
}

float ax_get_f32(const unsigned char *p)
{
    uint32_t u = (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
    float f;
    memcpy(&f, &u, 4);
    return f;
}

void ax_result_f32(sqlite3_context *ctx, const double *v, size_t n)
{
    unsigned char *out = sqlite3_malloc64(n ? 4 * (sqlite3_uint64)n : 1);
    if (!out) {
        sqlite3_result_error_nomem(ctx);
        return;
    }
    for (size_t i = 0; i < n; i++)
        ax_put_f32(out + 4 * i, (float)v[i]);
    sqlite3_result_blob64(ctx, out, 4 * (sqlite3_uint64)n, sqlite3_free);
}

void ax_result_json(sqlite3_context *ctx, char *text, size_t len)
{
    sqlite3_result_text64(ctx, text, len, sqlite3_free, SQLITE_UTF8);
    sqlite3_result_subtype(ctx, AX_JSON_SUBTYPE);
}

void ax_result_json_buffer(sqlite3_context *ctx, affect_strbuf *sb)
{
    char *text;
    size_t len;
    affect_error err;
    if (affect_strbuf_finish(sb, &text, &len, &err))
        sqlite3_result_error_nomem(ctx);
    else
        ax_result_json(ctx, text, len);
}

/* ---- options ---- */

ax_arg ax_opts_parse(sqlite3_context *ctx, int argc, sqlite3_value **argv, int i,
                     const char *const *allowed, ax_opts *opts)
{
    opts->doc = NULL;
    opts->obj = NULL;
    if (i >= argc || sqlite3_value_type(argv[i]) == SQLITE_NULL)
        return AX_OK;
    if (sqlite3_value_type(argv[i]) != SQLITE_TEXT) {
        ax_errorf(ctx, "options (argument %d) must be a JSON object as text, got %s", i + 1,
                  ax_type_name(argv[i]));
        return AX_ERROR;
    }
    const char *text = (const char *)sqlite3_value_text(argv[i]);
    if (!text) {
        sqlite3_result_error_nomem(ctx);
        return AX_ERROR;
    }
    affect_error err;
    if (affect_json_parse(text, (size_t)sqlite3_value_bytes(argv[i]), &opts->doc, NULL, &err)) {
        if (err.status == AFFECT_ERR_NOMEM)
            sqlite3_result_error_nomem(ctx);
        else
            ax_errorf(ctx, "options (argument %d) are not valid JSON: %s", i + 1, err.msg);
        return AX_ERROR;
    }
    const affect_json_node *root = affect_json_root(opts->doc);
    if (root->type != AFFECT_JSON_OBJECT) {
        ax_errorf(ctx, "options (argument %d) must be a JSON object, got %s", i + 1,
                  affect_json_type_name(root->type));
        ax_opts_free(opts);
        return AX_ERROR;
    }
    for (const affect_json_node *m = affect_json_first(opts->doc, root); m;
         m = affect_json_next_sibling(opts->doc, m)) {
        bool known = false;
        for (int k = 0; allowed[k] && !known; k++)
            known = strcmp(allowed[k], m->key) == 0;
        if (!known) {
            char list[640] = ""; /* affect_crossval's 45 keys take 408 bytes */
            size_t used = 0;
            for (int k = 0; allowed[k]; k++) {
                int w =
                    snprintf(list + used, sizeof list - used, "%s%s", k ? ", " : "", allowed[k]);
                if (w < 0 || (size_t)w >= sizeof list - used) {
                    list[used] = '\0'; /* never a key cut in the middle */
                    break;
                }
                used += (size_t)w;
            }
            ax_errorf(ctx, "unknown option \"%.64s\" (expected %s)", m->key,
                      allowed[0] ? list : "no options");
            ax_opts_free(opts);
            return AX_ERROR;
        }
    }
    opts->obj = root;
    return AX_OK;
}

void ax_opts_free(ax_opts *opts)
{
    affect_json_free(opts->doc);
    opts->doc = NULL;
    opts->obj = NULL;
}

const affect_json_node *ax_opt(const ax_opts *opts, const char *key)
{
    return opts->obj ? affect_json_get(opts->doc, opts->obj, key) : NULL;
}

static ax_arg wrong_type(sqlite3_context *ctx, const char *key, const char *want,
                         const affect_json_node *n)
{
    ax_errorf(ctx, "option \"%s\" must be %s, got %s", key, want, affect_json_type_name(n->type));
    return AX_ERROR;
}

ax_arg ax_opt_bool(sqlite3_context *ctx, const ax_opts *opts, const char *key, bool *out)
{
    const affect_json_node *n = ax_opt(opts, key);
    if (!n)
        return AX_OK;
    if (n->type != AFFECT_JSON_TRUE && n->type != AFFECT_JSON_FALSE)
        return wrong_type(ctx, key, "true or false", n);
    *out = n->type == AFFECT_JSON_TRUE;
    return AX_OK;
}

ax_arg ax_opt_number(sqlite3_context *ctx, const ax_opts *opts, const char *key, double *out)
{
    const affect_json_node *n = ax_opt(opts, key);
    if (!n)
        return AX_OK;
    if (n->type != AFFECT_JSON_NUMBER)
        return wrong_type(ctx, key, "a number", n);
    *out = n->num;
    return AX_OK;
}

ax_arg ax_opt_string(sqlite3_context *ctx, const ax_opts *opts, const char *key, const char **out)
{
    const affect_json_node *n = ax_opt(opts, key);
    if (!n)
        return AX_OK;
    if (n->type != AFFECT_JSON_STRING)
        return wrong_type(ctx, key, "a string", n);
    *out = n->str;
    return AX_OK;
}

ax_arg ax_opt_enum(sqlite3_context *ctx, const ax_opts *opts, const char *key,
                   const char *const *choices, int *out)
{
    const affect_json_node *n = ax_opt(opts, key);
    if (!n)
        return AX_OK;
    if (n->type == AFFECT_JSON_STRING)
        for (int k = 0; choices[k]; k++)
            if (strcmp(choices[k], n->str) == 0) {
                *out = k;
                return AX_OK;
            }
    affect_strbuf sb;
    affect_strbuf_init(&sb);
    for (int k = 0; choices[k]; k++) {
        affect_strbuf_puts(&sb, k ? ", " : "");
        affect_strbuf_json_string(&sb, choices[k]);
    }
    if (sb.failed) {
        affect_strbuf_free(&sb);
        sqlite3_result_error_nomem(ctx);
        return AX_ERROR;
    }
    if (n->type == AFFECT_JSON_STRING)
        ax_errorf(ctx, "option \"%s\" must be one of %s, got \"%.64s\"", key, sb.data, n->str);
    else
        ax_errorf(ctx, "option \"%s\" must be one of %s, got %s", key, sb.data,
                  affect_json_type_name(n->type));
    affect_strbuf_free(&sb);
    return AX_ERROR;
}

ax_arg ax_opt_up(sqlite3_context *ctx, const ax_opts *opts, int *up)
{
    static const char *const axes[] = {"x", "y", "z", NULL};
    return ax_opt_enum(ctx, opts, "up", axes, up);
}

ax_arg ax_opt_roles(sqlite3_context *ctx, const ax_opts *opts, const affect_motion *m,
                    affect_roles *roles)
{
    affect_roles_resolve(m, roles);
    const affect_json_node *n = ax_opt(opts, "roles");
    if (!n)
        return AX_OK;
    if (n->type != AFFECT_JSON_OBJECT)
        return wrong_type(ctx, "roles", "an object of role names to joint names", n);
    for (const affect_json_node *r = affect_json_first(opts->doc, n); r;
         r = affect_json_next_sibling(opts->doc, r)) {
        if (r->type != AFFECT_JSON_STRING && r->type != AFFECT_JSON_NULL) {
            ax_errorf(ctx, "option \"roles\": \"%.64s\" must map to a joint name or null, got %s",
                      r->key, affect_json_type_name(r->type));
            return AX_ERROR;
        }
        affect_error err;
        if (affect_roles_set(m, roles, r->key, r->type == AFFECT_JSON_STRING ? r->str : NULL,
                             &err)) {
            ax_errorf(ctx, "option \"roles\": %s", err.msg);
            return AX_ERROR;
        }
    }
    return AX_OK;
}

/* ---- ax_monitor ---- */

/* The probe counts to 100 so that it also runs about 1,000 VM steps: a progress handler
 * installed with N ≤ 1,000 is asked at every poll, one with N = 10,000 every tenth (20–50 µs
 * per poll, every 10 ms at most). */
#define AX_PROBE_SQL                                                                               \
    "WITH RECURSIVE c(i) AS (SELECT 1 UNION ALL SELECT i + 1 FROM c WHERE i < 100) "               \
    "SELECT count(*) FROM c"

static bool monitor_stop(void *arg)
{
    ax_monitor *am = arg;
    if (!am->probe) {
        int rc = sqlite3_prepare_v2(am->db, AX_PROBE_SQL, -1, &am->probe, NULL);
        if ((rc & 0xff) == SQLITE_INTERRUPT) /* the parser refuses while one is pending */
            return true;
        if (rc != SQLITE_OK)
            return false; /* out of memory: carry on rather than fail the call */
    }
    int rc = sqlite3_step(am->probe);
    sqlite3_reset(am->probe);
    return rc == SQLITE_INTERRUPT;
}

static void monitor_progress(void *arg, const char *stage, uint64_t done, uint64_t total)
{
    ax_monitor *am = arg;
    if (!am->report)
        return;
    sqlite3_bind_text(am->report, 1, stage, -1, SQLITE_STATIC);
    sqlite3_bind_int64(am->report, 2, (sqlite3_int64)done);
    sqlite3_bind_int64(am->report, 3, (sqlite3_int64)total);
    while (sqlite3_step(am->report) == SQLITE_ROW) {
    }
    sqlite3_reset(am->report);
}

int ax_monitor_begin_db(ax_monitor *am, sqlite3 *db, const char *progress_fn, char **errmsg)
{
    am->db = db;
    am->probe = NULL;
    am->report = NULL;
    affect_monitor_init(&am->mon, monitor_stop, monitor_progress, am);
    if (!progress_fn)
        return SQLITE_OK;
    char *sql = sqlite3_mprintf("SELECT \"%w\"(?1, ?2, ?3)", progress_fn);
    if (!sql)
        return SQLITE_NOMEM;
    int rc = sqlite3_prepare_v2(db, sql, -1, &am->report, NULL);
    sqlite3_free(sql);
    if ((rc & 0xff) == SQLITE_NOMEM || (rc & 0xff) == SQLITE_INTERRUPT)
        return rc & 0xff;
    if (rc != SQLITE_OK) {
        *errmsg = ax_mprintf("option \"progress\": %s", sqlite3_errmsg(db));
        return *errmsg ? SQLITE_ERROR : SQLITE_NOMEM;
    }
    return SQLITE_OK;
}

ax_arg ax_monitor_begin(ax_monitor *am, sqlite3_context *ctx, const char *progress_fn)
{
    char *msg = NULL;
    int rc = ax_monitor_begin_db(am, sqlite3_context_db_handle(ctx), progress_fn, &msg);
    if (rc == SQLITE_OK)
        return AX_OK;
    if (rc == SQLITE_NOMEM)
        sqlite3_result_error_nomem(ctx);
    else if (rc == SQLITE_INTERRUPT)
        ax_interrupted(ctx);
    else
        ax_errorf(ctx, "%s", msg);
    sqlite3_free(msg);
    ax_monitor_end(am);
    return AX_ERROR;
}

bool ax_monitor_interrupted(ax_monitor *am)
{
    return monitor_stop(am);
}

void ax_monitor_end(ax_monitor *am)
{
    sqlite3_finalize(am->probe);
    sqlite3_finalize(am->report);
    am->probe = am->report = NULL;
}

/* ---- table-valued functions of a motion ---- */

int ax_motion_tvf_best_index(sqlite3_vtab *vt, sqlite3_index_info *info, int col_motion,
                             int col_options, const char *name)
{
    int motion = -1, options = -1, seen = 0;
    for (int i = 0; i < info->nConstraint; i++) {
        const struct sqlite3_index_constraint *k = &info->aConstraint[i];
        if (k->iColumn != col_motion && (col_options < 0 || k->iColumn != col_options))
            continue;
        if (k->iColumn == col_motion)
            seen = 1;
        if (!k->usable || k->op != SQLITE_INDEX_CONSTRAINT_EQ) {
            if (k->iColumn != col_motion)
                return SQLITE_CONSTRAINT;
            continue;
        }
        if (k->iColumn == col_motion)
            motion = i;
        else
            options = i;
    }
    if (motion < 0) {
        if (seen)
            return SQLITE_CONSTRAINT;
        return ax_vtab_error(vt, NULL,
                             "%s: a motion argument is required, as in SELECT * FROM %s(:motion)",
                             name, name);
    }
    info->aConstraintUsage[motion].argvIndex = 1;
    info->aConstraintUsage[motion].omit = 1;
    info->idxNum = 1;
    if (options >= 0) {
        info->aConstraintUsage[options].argvIndex = 2;
        info->aConstraintUsage[options].omit = 1;
        info->idxNum |= 2;
    }
    info->estimatedCost = 1000.0;
    info->estimatedRows = 10000;
    return SQLITE_OK;
}

int ax_tvf_connect(sqlite3 *db, const char *schema, sqlite3_vtab **out)
{
    int rc = sqlite3_declare_vtab(db, schema);
    if (rc != SQLITE_OK)
        return rc;
    ax_tvf_vtab *vt = sqlite3_malloc(sizeof *vt);
    if (!vt)
        return SQLITE_NOMEM;
    memset(vt, 0, sizeof *vt);
    vt->db = db;
    sqlite3_vtab_config(db, SQLITE_VTAB_INNOCUOUS);
    *out = &vt->base;
    return SQLITE_OK;
}

int ax_tvf_disconnect(sqlite3_vtab *vt)
{
    sqlite3_free(vt);
    return SQLITE_OK;
}

int ax_tvf_open(size_t size, sqlite3_vtab_cursor **out)
{
    sqlite3_vtab_cursor *c = sqlite3_malloc64(size);
    if (!c)
        return SQLITE_NOMEM;
    memset(c, 0, size);
    *out = c;
    return SQLITE_OK;
}

affect_status ax_motion_tvf_args(int idx_num, int argc, sqlite3_value **argv, affect_monitor *mon,
                                 affect_motion **m, const char **text, size_t *len,
                                 affect_error *err)
{
    *m = NULL;
    *text = NULL;
    *len = 0;
    if (argc < 1 || sqlite3_value_type(argv[0]) == SQLITE_NULL)
        return AFFECT_OK;
    if (sqlite3_value_type(argv[0]) != SQLITE_BLOB)
        return affect_fail(err, AFFECT_ERR_INVALID, "the argument must be a motion BLOB, got %s",
                           ax_type_name(argv[0]));
    if ((idx_num & 2) && argc > 1 && sqlite3_value_type(argv[1]) != SQLITE_NULL) {
        if (sqlite3_value_type(argv[1]) != SQLITE_TEXT)
            return affect_fail(err, AFFECT_ERR_INVALID,
                               "options must be a JSON object as text, got %s",
                               ax_type_name(argv[1]));
        *text = (const char *)sqlite3_value_text(argv[1]);
        if (!*text)
            return affect_nomem(err);
        *len = (size_t)sqlite3_value_bytes(argv[1]);
    }
    const unsigned char *data = sqlite3_value_blob(argv[0]);
    int n = sqlite3_value_bytes(argv[0]);
    if (!data && n > 0)
        return affect_nomem(err);
    affect_status st = affect_motion_decode_monitored(data, (size_t)n, mon, m, err);
    if (st && st != AFFECT_ERR_NOMEM && st != AFFECT_ERR_INTERRUPTED) {
        char emsg[AFFECT_ERROR_MSG_MAX];
        memcpy(emsg, err->msg, sizeof emsg);
        st =
            affect_fail(err, AFFECT_ERR_FORMAT, "the argument is not a valid motion: %.200s", emsg);
    }
    return st;
}

/* ---- an aggregate's options: read on the first row, the same text on every row ---- */

/* Keeps a copy of argument i's text (nothing when it is absent or not text). */
ax_arg ax_opts_text_keep(sqlite3_context *ctx, int argc, sqlite3_value **argv, int i,
                         ax_opts_text *oc)
{
    if (argc <= i || sqlite3_value_type(argv[i]) != SQLITE_TEXT)
        return AX_OK;
    const unsigned char *text = sqlite3_value_text(argv[i]);
    int n = sqlite3_value_bytes(argv[i]);
    oc->text = text ? sqlite3_malloc64((sqlite3_uint64)n + 1) : NULL;
    if (!oc->text) {
        sqlite3_result_error_nomem(ctx);
        return AX_ERROR;
    }
    memcpy(oc->text, text, (size_t)n);
    oc->text[n] = '\0';
    oc->len = (size_t)n;
    return AX_OK;
}

/* AX_OK when argument i is the first row's options (the same text, or both absent). */
ax_arg ax_opts_text_same(sqlite3_context *ctx, int argc, sqlite3_value **argv, int i,
                         const ax_opts_text *oc)
{
    if (argc <= i)
        return AX_OK;
    int type = sqlite3_value_type(argv[i]);
    bool same;
    if (type == SQLITE_NULL) {
        same = oc->text == NULL;
    } else if (type != SQLITE_TEXT || oc->text == NULL) {
        same = false;
    } else {
        const unsigned char *text = sqlite3_value_text(argv[i]);
        if (!text) {
            sqlite3_result_error_nomem(ctx);
            return AX_ERROR;
        }
        same =
            (size_t)sqlite3_value_bytes(argv[i]) == oc->len && memcmp(text, oc->text, oc->len) == 0;
    }
    if (!same) {
        ax_errorf(ctx, "options must be the same on every row");
        return AX_ERROR;
    }
    return AX_OK;
}
