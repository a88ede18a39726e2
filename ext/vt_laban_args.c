/*
 * vt_laban_args.c — the laban index's constructor (see the manual in vt_laban.c): its key=value
 * arguments (each at most once, bare or quoted), the JSON of Laban options normalized for _info,
 * the table's own fields, and the check that the content table and its columns exist.
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "vt_laban_int.h"

#include "util/strbuf.h"

/* ---- constructor arguments ---- */

typedef struct lab_args {
    char *value[4]; /* content, motion, label, options; NULL when not given */
} lab_args;

static const char *const lab_keys[4] = {"content", "motion", "label", "options"};
enum { ARG_CONTENT, ARG_MOTION, ARG_LABEL, ARG_OPTIONS };

static void lab_args_free(lab_args *a)
{
    for (int i = 0; i < 4; i++)
        sqlite3_free(a->value[i]);
}

static bool lab_space(char c)
{
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v';
}

/* One "key=value" argument. */
static int lab_parse_arg(const char *arg, lab_args *a, char **err)
{
    const char *eq = strchr(arg, '=');
    if (!eq)
        return ax_error_into(err, NULL, "laban: expected key=value, got \"%s\"", arg);
    const char *k0 = arg, *k1 = eq;
    while (k0 < k1 && lab_space(*k0))
        k0++;
    while (k1 > k0 && lab_space(k1[-1]))
        k1--;
    int key = -1;
    for (int i = 0; i < 4 && key < 0; i++)
        if (strlen(lab_keys[i]) == (size_t)(k1 - k0) &&
            sqlite3_strnicmp(lab_keys[i], k0, (int)(k1 - k0)) == 0)
            key = i;
    if (key < 0)
        return ax_error_into(err, NULL,
                             "laban: unknown argument \"%.*s\" (expected content, motion, label, "
                             "options)",
                             (int)(k1 - k0), k0);
    if (a->value[key])
        return ax_error_into(err, NULL, "laban: duplicate argument \"%s\"", lab_keys[key]);
    const char *v0 = eq + 1, *v1 = eq + strlen(eq);
    while (v0 < v1 && lab_space(*v0))
        v0++;
    while (v1 > v0 && lab_space(v1[-1]))
        v1--;
    if (v0 == v1)
        return ax_error_into(err, NULL, "laban: argument \"%s\" needs a value", lab_keys[key]);
    char *out = sqlite3_malloc64((sqlite3_uint64)(v1 - v0) + 1);
    if (!out)
        return SQLITE_NOMEM;
    size_t n = 0;
    if (*v0 == '\'' || *v0 == '"') {
        char q = *v0;
        const char *p = v0 + 1;
        for (;;) {
            if (p >= v1) {
                sqlite3_free(out);
                return ax_error_into(err, NULL, "laban: argument \"%s\": unterminated quote",
                                     lab_keys[key]);
            }
            if (*p == q) {
                if (p + 1 < v1 && p[1] == q) {
                    out[n++] = q;
                    p += 2;
                    continue;
                }
                break;
            }
            out[n++] = *p++;
        }
        if (p + 1 != v1) {
            sqlite3_free(out);
            return ax_error_into(err, NULL,
                                 "laban: argument \"%s\": unexpected text after the closing quote",
                                 lab_keys[key]);
        }
    } else {
        memcpy(out, v0, (size_t)(v1 - v0));
        n = (size_t)(v1 - v0);
    }
    out[n] = '\0';
    if (n == 0 || (key != ARG_OPTIONS && strlen(out) != n)) {
        sqlite3_free(out);
        return ax_error_into(err, NULL, "laban: argument \"%s\" needs a value", lab_keys[key]);
    }
    a->value[key] = out;
    return SQLITE_OK;
}

/* A JSON member's key, quoted for a message. */
static const char *lab_quote_key(const affect_json_node *m, char *buf, size_t size)
{
    affect_json_quote(buf, size, m->key, m->key_len);
    return buf;
}

/* The options argument: fills vt->opt and the normalized JSON. */
int lab_parse_options(lab_vtab *vt, const char *text, char **err)
{
    affect_laban_options *o = &vt->opt;
    affect_laban_options_default(o);
    o->missing_null = true;
    affect_json_doc *doc = NULL;
    int rc = SQLITE_OK;
    char q[80];
    if (text) {
        affect_error e;
        if (affect_json_parse(text, strlen(text), &doc, NULL, &e))
            return e.status == AFFECT_ERR_NOMEM
                       ? SQLITE_NOMEM
                       : ax_error_into(err, NULL, "laban: options are not valid JSON: %s", e.msg);
        const affect_json_node *root = affect_json_root(doc);
        if (root->type != AFFECT_JSON_OBJECT) {
            rc = ax_error_into(err, NULL, "laban: options must be a JSON object, got %s",
                               affect_json_type_name(root->type));
            goto done;
        }
        for (const affect_json_node *m = affect_json_first(doc, root); m;
             m = affect_json_next_sibling(doc, m)) {
            const char *k = m->key;
            bool number = m->type == AFFECT_JSON_NUMBER;
            if (!strcmp(k, "cutoff_hz") || !strcmp(k, "speed_floor") || !strcmp(k, "max_ratio")) {
                if (!number) {
                    rc = ax_error_into(err, NULL, "laban: option \"%s\" must be a number, got %s",
                                       k, affect_json_type_name(m->type));
                    goto done;
                }
                double v = m->num;
                if (!strcmp(k, "cutoff_hz") && !(v > 0 && isfinite(v)))
                    rc = ax_error_into(
                        err, NULL,
                        "laban: option \"cutoff_hz\" must be a positive number, got %.15g", v);
                else if (!strcmp(k, "speed_floor") && !(v >= 0 && v < 1))
                    rc = ax_error_into(
                        err, NULL, "laban: option \"speed_floor\" must be in [0, 1), got %.15g", v);
                else if (!strcmp(k, "max_ratio") && !(v >= 1 && isfinite(v)))
                    rc = ax_error_into(
                        err, NULL, "laban: option \"max_ratio\" must be at least 1, got %.15g", v);
                if (rc)
                    goto done;
                *(!strcmp(k, "cutoff_hz")     ? &o->cutoff_hz
                  : !strcmp(k, "speed_floor") ? &o->speed_floor
                                              : &o->max_ratio) = v;
            } else if (!strcmp(k, "hull")) {
                if (m->type == AFFECT_JSON_STRING && !strcmp(m->str, "convex"))
                    o->hull_box = false;
                else if (m->type == AFFECT_JSON_STRING && !strcmp(m->str, "box"))
                    o->hull_box = true;
                else {
                    if (m->type == AFFECT_JSON_STRING)
                        affect_json_quote(q, sizeof q, m->str, m->str_len);
                    rc = ax_error_into(
                        err, NULL, "laban: option \"hull\" must be \"convex\" or \"box\", got %s",
                        m->type == AFFECT_JSON_STRING ? q : affect_json_type_name(m->type));
                    goto done;
                }
            } else if (!strcmp(k, "up")) {
                static const char *const axes[] = {"x", "y", "z"};
                int axis = -1;
                for (int i = 0; i < 3 && m->type == AFFECT_JSON_STRING; i++)
                    if (!strcmp(m->str, axes[i]))
                        axis = i;
                if (axis < 0) {
                    if (m->type == AFFECT_JSON_STRING)
                        affect_json_quote(q, sizeof q, m->str, m->str_len);
                    rc = ax_error_into(
                        err, NULL, "laban: option \"up\" must be \"x\", \"y\" or \"z\", got %s",
                        m->type == AFFECT_JSON_STRING ? q : affect_json_type_name(m->type));
                    goto done;
                }
                o->up_axis = axis;
            } else if (!strcmp(k, "per_second")) {
                if (m->type != AFFECT_JSON_TRUE && m->type != AFFECT_JSON_FALSE) {
                    rc = ax_error_into(err, NULL,
                                       "laban: option \"per_second\" must be true or false, got %s",
                                       affect_json_type_name(m->type));
                    goto done;
                }
                o->time_per_second = m->type == AFFECT_JSON_TRUE;
            } else {
                rc = ax_error_into(
                    err, NULL,
                    "laban: unknown option %s (expected cutoff_hz, hull, speed_floor, "
                    "max_ratio, up, per_second)",
                    lab_quote_key(m, q, sizeof q));
                goto done;
            }
        }
    }
    affect_strbuf sb;
    affect_strbuf_init(&sb);
    affect_strbuf_puts(&sb, "{\"cutoff_hz\":");
    affect_strbuf_double(&sb, o->cutoff_hz);
    affect_strbuf_puts(&sb, o->hull_box ? ",\"hull\":\"box\"" : ",\"hull\":\"convex\"");
    affect_strbuf_puts(&sb, ",\"speed_floor\":");
    affect_strbuf_double(&sb, o->speed_floor);
    affect_strbuf_puts(&sb, ",\"max_ratio\":");
    affect_strbuf_double(&sb, o->max_ratio);
    affect_strbuf_printf(&sb, ",\"up\":\"%c\"", "xyz"[o->up_axis]);
    affect_strbuf_puts(&sb,
                       o->time_per_second ? ",\"per_second\":true}" : ",\"per_second\":false}");
    size_t len;
    affect_error e;
    if (affect_strbuf_finish(&sb, &vt->options_json, &len, &e))
        rc = SQLITE_NOMEM;
done:
    affect_json_free(doc);
    return rc;
}

/* ---- construction ---- */

void lab_free(lab_vtab *vt)
{
    if (!vt)
        return;
    lab_cache_drop(vt);
    sqlite3_free(vt->schema);
    sqlite3_free(vt->name);
    sqlite3_free(vt->content);
    sqlite3_free(vt->motion);
    sqlite3_free(vt->label);
    affect_free(vt->options_json);
    sqlite3_free(vt->base.zErrMsg);
    sqlite3_free(vt);
}

/* Every column name of the declared schema, for the name check. */
bool lab_is_column_name(const char *name)
{
    static const char *const hidden[] = {"label",      "distance", "query", "k",      "radius",
                                         "components", "rowid",    "oid",   "_rowid_"};
    for (size_t i = 0; i < sizeof hidden / sizeof hidden[0]; i++)
        if (!sqlite3_stricmp(name, hidden[i]))
            return true;
    for (int i = 0; i < LAB_N; i++)
        if (!sqlite3_stricmp(name, affect_laban_names[i]))
            return true;
    return false;
}

/* Parses the arguments and declares the schema (shared by xCreate and xConnect). */
int lab_init(sqlite3 *db, void *aux, int argc, const char *const *argv, lab_vtab **out, char **err)
{
    lab_args a;
    memset(&a, 0, sizeof a);
    sqlite3_str *decl = NULL;
    int rc = SQLITE_NOMEM;
    lab_vtab *vt = sqlite3_malloc(sizeof *vt);
    *out = NULL;
    if (!vt)
        return SQLITE_NOMEM;
    memset(vt, 0, sizeof *vt);
    vt->db = db;
    vt->caches = aux;
    for (int i = 3; i < argc; i++)
        if ((rc = lab_parse_arg(argv[i], &a, err)) != SQLITE_OK)
            goto done;
    if (!a.value[ARG_CONTENT]) {
        rc = ax_error_into(err, NULL,
                           "laban: the content argument is required, as in CREATE VIRTUAL TABLE %s "
                           "USING laban(content=motions, motion=motion, label=emotion)",
                           argv[2]);
        goto done;
    }
    if (lab_is_column_name(argv[2])) {
        rc = ax_error_into(
            err, NULL, "laban: a laban table cannot be named \"%s\": that is one of its columns",
            argv[2]);
        goto done;
    }
    rc = SQLITE_NOMEM;
    vt->schema = sqlite3_mprintf("%s", argv[1]);
    vt->name = sqlite3_mprintf("%s", argv[2]);
    vt->content = sqlite3_mprintf("%s", a.value[ARG_CONTENT]);
    vt->motion = sqlite3_mprintf("%s", a.value[ARG_MOTION] ? a.value[ARG_MOTION] : "motion");
    vt->label = sqlite3_mprintf("%s", a.value[ARG_LABEL] ? a.value[ARG_LABEL] : "label");
    if (!vt->schema || !vt->name || !vt->content || !vt->motion || !vt->label)
        goto done;
    if ((rc = lab_parse_options(vt, a.value[ARG_OPTIONS], err)) != SQLITE_OK)
        goto done;

    decl = sqlite3_str_new(db);
    sqlite3_str_appendall(decl, "CREATE TABLE x(label");
    for (int i = 0; i < LAB_N; i++)
        sqlite3_str_appendf(decl, ", %s REAL", affect_laban_names[i]);
    sqlite3_str_appendf(decl,
                        ", distance REAL HIDDEN, query HIDDEN, k HIDDEN, radius HIDDEN, "
                        "components HIDDEN, \"%w\" HIDDEN)",
                        argv[2]);
    char *sql = sqlite3_str_finish(decl);
    decl = NULL;
    if (!sql) {
        rc = SQLITE_NOMEM;
        goto done;
    }
    rc = sqlite3_declare_vtab(db, sql);
    sqlite3_free(sql);
    if (rc != SQLITE_OK) {
        rc = lab_db_error(err, db, rc);
        goto done;
    }
    *out = vt;
    vt = NULL;
done:
    lab_args_free(&a);
    lab_free(vt);
    return rc;
}

/* The content table and both columns exist (and are not the index itself). */
int lab_check_content(lab_vtab *vt, char **err)
{
    static const char *const suffixes[] = {"", "_data", "_info"};
    size_t n = strlen(vt->name);
    for (int i = 0; i < 3; i++)
        if (strlen(vt->content) == n + strlen(suffixes[i]) &&
            !sqlite3_strnicmp(vt->content, vt->name, (int)n) &&
            !sqlite3_stricmp(vt->content + n, suffixes[i]))
            return ax_error_into(
                err, NULL, "laban: the content table cannot be %s itself or its shadow tables",
                vt->name);
    sqlite3_stmt *st = NULL;
    int rc =
        lab_prepare(vt->db, err, &st, "PRAGMA \"%w\".table_xinfo(%Q)", vt->schema, vt->content);
    if (rc)
        return rc;
    bool any = false, motion = false, label = false;
    while ((rc = sqlite3_step(st)) == SQLITE_ROW) {
        const char *col = (const char *)sqlite3_column_text(st, 1);
        if (!col) {
            rc = SQLITE_NOMEM;
            goto done;
        }
        any = true;
        motion = motion || !sqlite3_stricmp(col, vt->motion);
        label = label || !sqlite3_stricmp(col, vt->label);
    }
    if (rc != SQLITE_DONE) {
        rc = lab_db_error(err, vt->db, rc);
        goto done;
    }
    if (!any)
        rc = ax_error_into(err, NULL, "laban: no such table: %s", vt->content);
    else if (!motion || !label)
        rc = ax_error_into(err, NULL, "laban: no column \"%s\" in table %s",
                           motion ? vt->label : vt->motion, vt->content);
    else
        rc = SQLITE_OK;
done:
    sqlite3_finalize(st);
    return rc;
}

/* Marks the index changed: a new generation, statistics due at commit, the cache dropped. */
