/*
 * vt_laban.c — laban, a virtual table that keeps the 27 Laban descriptors of every motion of a
 * table and finds the motions nearest to a query (the neighbourhoods of SCIENCE.md §5 step 4).
 *
 *   CREATE VIRTUAL TABLE motion_laban USING laban(content=motions, motion=motion, label=emotion);
 *   SELECT rowid, label, WeightAll, TimeAll FROM motion_laban;             -- cached descriptors
 *   SELECT rowid, label, distance FROM motion_laban
 *    WHERE query = :m AND label = 'angry' AND k = 5;                       -- 5 nearest angry
 *   SELECT rowid, distance FROM motion_laban
 *    WHERE query = 12 AND label = 'sad' AND radius = 0.1;                  -- ε-ball around row 12
 *   SELECT rowid, distance FROM motion_laban
 *    WHERE query = :m AND k = 3 AND components = '["TimeAll","FlowAll"]';
 *   INSERT INTO motion_laban(motion_laban) VALUES('rebuild');              -- after content changes
 *
 * Arguments, key=value, each at most once; a value is a bare word or '…' / "…" quoted:
 *   content   the table holding the motions, in the same database as the index (required)
 *   motion    its column of motion BLOBs (default motion)
 *   label     its column of labels (default label)
 *   options   a JSON object of Laban options (see affect/laban.h): cutoff_hz (6),
 *             hull ("convex" | "box"), speed_floor (0.05), max_ratio (100), up ("x"|"y"|"z"),
 *             per_second (false); a component that cannot be computed (a role the skeleton lacks,
 *             too few frames) is missing (NULL) rather than an error.
 * CREATE checks that the content table and both columns exist, then indexes every row.
 *
 * The equivalent schema (rowid = the content row's rowid):
 *   CREATE TABLE motion_laban(label, WeightAll REAL, WeightTorso REAL, …, ShapeDirRHand REAL,
 *       distance REAL HIDDEN, query HIDDEN, k HIDDEN, radius HIDDEN, components HIDDEN,
 *       motion_laban HIDDEN);
 * The 27 components are in laban_names() order; the last hidden column carries the table's
 * own name and is only written, to give commands (as in FTS5).
 *
 * How it works. External content, like FTS5: the index reads
 *   SELECT rowid, <label>, <motion> FROM <content>
 * computes each motion's Laban vector once (roles resolved from the joint names) and keeps it in
 * two shadow tables:
 *   <name>_data(id INTEGER PRIMARY KEY, label, vector BLOB, msize INTEGER, mhash INTEGER)
 *       vector: 27 little-endian float32, the sqlite-vec convention (a missing component is NaN,
 *       bits 0x7fc00000); msize: the motion BLOB's length; mhash: 64-bit FNV-1a of its bytes
 *       (as a signed integer), for the stale check. A row whose motion is NULL is not indexed.
 *   <name>_info(key TEXT PRIMARY KEY, value)
 *       format ('1'), content, motion, label, options (normalized JSON: every option with its
 *       value), generation (bumped by every write), rows (indexed rows), mean and sd (JSON arrays
 *       of 27 numbers in component order: sd is the divisor used, see below; a mean is null
 *       where the component is missing in every row), stats_generation (the generation that
 *       mean and sd describe: it lags behind generation while a transaction that changed the
 *       index has not committed; ax_laban_stats_read, behind laban_zvector, refuses them then).
 * Standardization: z = (x − mean) / sd per component over the indexed rows, skipping missing
 * values; sd is the sample standard deviation (n − 1), and 1 where it is 0 or undefined (fewer
 * than two values) (affect_laban_stats, core/laban/laban_std.c, which also gives laban_zvector
 * the vectors whose plain L2 distances are these distances, for sqlite-vec's vec0). mean and sd are
 * recomputed when a transaction that changed the index commits (xSync), so a transaction of many
 * per-row 'refresh' commands pays for them once; queries always standardize with the statistics of
 * the rows they see. Distance: Euclidean over the chosen components (default all 27) of the
 * standardized vectors; a component missing in either vector is skipped, and a row that shares no
 * component with the query is not a candidate. Ties are broken by rowid ascending, so results are
 * deterministic. The arithmetic is the core's (affect_laban_standardize, affect_laban_search_run
 * in core/laban/laban_search.c: the distance, the k-nearest heap, the ε-ball, the tie rule); this
 * file feeds it the cached rows and the constraints. Each connection caches the vectors (raw and
 * standardized) in memory, keyed by the generation in _info: a query re-reads one _info row and
 * reloads the cache only when the index changed (here or in another connection); a rollback drops
 * the cache. Cursors hold a reference to the cache they started with, so a write during a scan
 * cannot pull it from under them. sqlite3_interrupt stops a query: the cache is read by SQL
 * (which SQLite interrupts), its standardization and a search poll between parts of
 * LAB_POLL_ROWS rows ("laban: interrupted"), and a query motion's vector is computed under the
 * monitor.
 *
 * Queries. xBestIndex uses these equality constraints; idxNum says which are present, and they
 * are passed to xFilter in this order:
 *   bit  1  query = ?        a motion BLOB (its vector is computed with the index's options), or
 *                            an INTEGER rowid of an indexed row (its cached vector; that row is
 *                            left out of the results). NULL gives no rows.
 *   bit  2  label = ?        only rows whose label equals it: numbers numerically, text and BLOBs
 *                            byte for byte, never across types; NULL labels never match.
 *   bit  4  k = ?            the k nearest (an integer ≥ 1); fewer when there are fewer rows
 *   bit  8  radius = ?       r in (0, 1]: every candidate within r × the distance from the query
 *                            to the furthest candidate (ε = 10 % in the thesis is r = 0.1); at
 *                            least the nearest one even when that ball is empty. Over all 27
 *                            components distances crowd together (the sad motions of the test
 *                            corpus lie 4.2 to 5.0 from an angry one), so the thesis's small
 *                            radii are meant for its component subsets: use components.
 *   bit 16  components = ?   a JSON array of component names (default: all 27)
 *   bit 32  rowid = ?        only that row ('7' and 7.0 name row 7, as for any rowid)
 * With bit 1 exactly one of bits 4 and 8 is required; bits 4, 8 and 16 need bit 1. Rows come
 * by distance ascending (then rowid), and ORDER BY distance [, rowid] is consumed. Without bit 1
 * the cached rows come in rowid order (ORDER BY rowid is consumed) and distance is NULL.
 * A constraint on query, k, radius or components that is not usable gives SQLITE_CONSTRAINT so
 * SQLite tries another plan; a usable but incomplete combination is an error naming what is
 * missing.
 *
 * Writes are commands only, as in FTS5:
 *   INSERT INTO motion_laban(motion_laban) VALUES('rebuild');              -- everything again
 *   INSERT INTO motion_laban(motion_laban, rowid) VALUES('refresh', 12);   -- one row (removed
 *                                  -- when the content row is gone or its motion is NULL; a row
 *                                  -- whose motion is byte-identical only gets its label updated)
 *   INSERT INTO motion_laban(motion_laban, rowid) VALUES('delete', 12);
 *   INSERT INTO motion_laban(motion_laban) VALUES('check');  -- fails if anything is wrong
 * Stale handling: the index does not watch the content table. 'check' compares every indexed
 * row with it (rows present, motion length and FNV-1a hash, label) and names the first stale
 * rowid; 'rebuild' fixes everything; sql/laban_triggers.sql installs triggers that issue
 * 'refresh' and 'delete' so the index follows each change.
 * Corruption: a stored vector is sound when it is a BLOB of 27 × 4 bytes whose every component
 * is a finite number >= 0 (every Laban component is a magnitude) or the missing marker (NaN,
 * bits 0x7fc00000 exactly). 'check' validates every stored vector first, then the staleness,
 * then every cache entry of _info (ax_laban_cache_put; each kind checked by the validator
 * registered with the module, e.g. the RMLR fit must decode and fit the index's shape), and
 * names the first rowid or entry that is wrong. Every reader of the vectors (queries, scans,
 * ax_laban_read) refuses a corrupt one: "stored vector of rowid 17 is corrupt (1 bytes,
 * expected 108); run INSERT INTO …('rebuild')".
 *
 * Which tables are indexes. Other files read an index only through vt_laban.h (ax_laban_read,
 * ax_laban_stats_read, ax_laban_label_of, ax_laban_cache_get/put). Those that take an index by
 * name recognize one by its module: sqlite_schema's statement read token by token
 * (lab_is_laban_def: CREATE VIRTUAL TABLE <name> USING laban), then _info's format, which must
 * be '1' ("g_info has format "2"; this version reads format 1 (index "g")").
 *
 * Trust. The table reads another table (of its own database only, so a schema cannot use it
 * to reach an attached database) and writes only its shadow tables. It is not marked
 * SQLITE_VTAB_DIRECTONLY, although reading other tables makes it direct-only in spirit: that
 * flag forbids any use from triggers, and the 'refresh'/'delete' triggers are how an index stays
 * current. It is not SQLITE_VTAB_INNOCUOUS either: with the hardened PRAGMA trusted_schema=OFF
 * SQLite refuses it in triggers and views (DIRECTONLY would refuse it there always).
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "vt_laban_int.h"

#include "affect/laban.h"
#include "util/strbuf.h"

enum {
    COL_LABEL = 0,
    COL_COMP0 = 1, /* the 27 components */
    COL_DISTANCE = COL_COMP0 + LAB_N,
    COL_QUERY,
    COL_K,
    COL_RADIUS,
    COL_COMPONENTS,
    COL_COMMAND /* named after the table */
};

/* idxNum bits, in argv order (see the header). */
enum {
    IDX_QUERY = 1,
    IDX_LABEL = 2,
    IDX_K = 4,
    IDX_RADIUS = 8,
    IDX_COMPONENTS = 16,
    IDX_ROWID = 32
};
#define IDX_BITS 6

typedef struct lab_cursor {
    sqlite3_vtab_cursor base;
    lab_cache *cache;
    bool knn;
    /* scan: rows [pos, end) whose label passes */
    size_t pos, end;
    unsigned char *label_ok; /* per distinct label; NULL = no label filter */
    /* KNN */
    affect_laban_hit *hits;
    size_t n_hits, hit;
    sqlite3_value *args[4]; /* query, k, radius, components, for their hidden columns */
} lab_cursor;

static int lab_create(sqlite3 *db, void *aux, int argc, const char *const *argv, sqlite3_vtab **out,
                      char **err)
{
    lab_vtab *vt = NULL;
    sqlite3_stmt *st = NULL;
    int rc = lab_init(db, aux, argc, argv, &vt, err);
    if (rc)
        return rc;
    if ((rc = lab_check_content(vt, err)) != SQLITE_OK)
        goto done;
    rc = lab_exec(db, err,
                  "CREATE TABLE \"%w\".\"%w_data\"(id INTEGER PRIMARY KEY, label, "
                  "vector BLOB, msize INTEGER, mhash INTEGER)",
                  vt->schema, vt->name);
    if (rc || (rc = lab_exec(db, err,
                             "CREATE TABLE \"%w\".\"%w_info\"(key TEXT PRIMARY KEY, "
                             "value) WITHOUT ROWID",
                             vt->schema, vt->name)) != SQLITE_OK)
        goto done;
    rc = lab_prepare(db, err, &st,
                     "INSERT INTO \"%w\".\"%w_info\"(key, value) VALUES"
                     "('format', '" LAB_FORMAT "'), ('content', ?1), "
                     "('motion', ?2), ('label', ?3), ('options', ?4), "
                     "('generation', 0)",
                     vt->schema, vt->name);
    if (rc)
        goto done;
    if ((rc = sqlite3_bind_text(st, 1, vt->content, -1, SQLITE_STATIC)) != SQLITE_OK ||
        (rc = sqlite3_bind_text(st, 2, vt->motion, -1, SQLITE_STATIC)) != SQLITE_OK ||
        (rc = sqlite3_bind_text(st, 3, vt->label, -1, SQLITE_STATIC)) != SQLITE_OK ||
        (rc = sqlite3_bind_text(st, 4, vt->options_json, -1, SQLITE_STATIC)) != SQLITE_OK) {
        rc = lab_db_error(err, db, rc);
        goto done;
    }
    if ((rc = lab_step_done(db, err, st)) != SQLITE_OK || (rc = lab_rebuild(vt, err)) != SQLITE_OK)
        goto done;
    rc = lab_flush_stats(vt, err);
done:
    sqlite3_finalize(st);
    if (rc) {
        lab_free(vt);
        return rc;
    }
    *out = &vt->base;
    return SQLITE_OK;
}

static int lab_connect(sqlite3 *db, void *aux, int argc, const char *const *argv,
                       sqlite3_vtab **out, char **err)
{
    lab_vtab *vt = NULL;
    int rc = lab_init(db, aux, argc, argv, &vt, err);
    if (rc == SQLITE_OK)
        *out = &vt->base;
    return rc;
}

static int lab_disconnect(sqlite3_vtab *tab)
{
    lab_free((lab_vtab *)tab);
    return SQLITE_OK;
}

static int lab_destroy(sqlite3_vtab *tab)
{
    lab_vtab *vt = (lab_vtab *)tab;
    int rc = lab_exec(vt->db, &tab->zErrMsg, "DROP TABLE IF EXISTS \"%w\".\"%w_data\"", vt->schema,
                      vt->name);
    if (rc == SQLITE_OK)
        rc = lab_exec(vt->db, &tab->zErrMsg, "DROP TABLE IF EXISTS \"%w\".\"%w_info\"", vt->schema,
                      vt->name);
    if (rc == SQLITE_OK)
        lab_free(vt);
    return rc;
}

static int lab_rename(sqlite3_vtab *tab, const char *name)
{
    lab_vtab *vt = (lab_vtab *)tab;
    static const char *const suffix[] = {"_data", "_info"};
    if (lab_is_column_name(name)) /* it would not reconnect */
        return ax_vtab_error(tab, NULL,
                             "laban: a laban table cannot be named \"%s\": that is one of "
                             "its columns",
                             name);
    char *copy = sqlite3_mprintf("%s", name);
    if (!copy)
        return SQLITE_NOMEM;
    for (int i = 0; i < 2; i++) {
        int rc = lab_exec(vt->db, &tab->zErrMsg, "ALTER TABLE \"%w\".\"%w%s\" RENAME TO \"%w%s\"",
                          vt->schema, vt->name, suffix[i], name, suffix[i]);
        if (rc) {
            sqlite3_free(copy);
            return rc;
        }
    }
    sqlite3_free(vt->name);
    vt->name = copy;
    return SQLITE_OK;
}

static int lab_shadow_name(const char *suffix)
{
    return !sqlite3_stricmp(suffix, "data") || !sqlite3_stricmp(suffix, "info");
}

/* ---- transactions: statistics at commit, the cache dropped on rollback ---- */

static int lab_begin(sqlite3_vtab *tab)
{
    return SQLITE_OK;
}

static int lab_sync(sqlite3_vtab *tab)
{
    lab_vtab *vt = (lab_vtab *)tab;
    return vt->dirty ? lab_flush_stats(vt, &tab->zErrMsg) : SQLITE_OK;
}

static int lab_commit(sqlite3_vtab *tab)
{
    return SQLITE_OK;
}

static int lab_rollback(sqlite3_vtab *tab)
{
    lab_vtab *vt = (lab_vtab *)tab;
    vt->dirty = false;
    lab_cache_drop(vt);
    return SQLITE_OK;
}

static int lab_savepoint(sqlite3_vtab *tab, int i)
{
    return SQLITE_OK;
}

static int lab_rollback_to(sqlite3_vtab *tab, int i)
{
    lab_cache_drop((lab_vtab *)tab); /* generations may repeat after a rollback */
    return SQLITE_OK;
}

/* ---- writes: commands ---- */

static int lab_update(sqlite3_vtab *tab, int argc, sqlite3_value **argv, sqlite3_int64 *rowid)
{
    lab_vtab *vt = (lab_vtab *)tab;
    char **err = &tab->zErrMsg;
    if (argc == 1 || sqlite3_value_type(argv[0]) != SQLITE_NULL ||
        sqlite3_value_type(argv[2 + COL_COMMAND]) == SQLITE_NULL)
        return ax_error_into(err, NULL,
                             "laban: the index is read-only: change the content table and run "
                             "'rebuild', or install the triggers of sql/laban_triggers.sql");
    const char *cmd = (const char *)sqlite3_value_text(argv[2 + COL_COMMAND]);
    if (!cmd)
        return SQLITE_NOMEM;
    if (!strcmp(cmd, "rebuild"))
        return lab_rebuild(vt, err);
    if (!strcmp(cmd, "check"))
        return lab_check(vt, err);
    bool refresh = !strcmp(cmd, "refresh");
    if (refresh || !strcmp(cmd, "delete")) {
        sqlite3_value *id = argv[1];
        if (sqlite3_value_type(id) == SQLITE_NULL)
            return ax_error_into(err, NULL,
                                 "laban: '%s' needs a rowid, as in INSERT INTO %s(%s, rowid) "
                                 "VALUES('%s', 12)",
                                 cmd, vt->name, vt->name, cmd);
        if (sqlite3_value_type(id) != SQLITE_INTEGER) {
            char buf[40];
            return ax_error_into(err, NULL, "laban: the rowid of '%s' must be an integer, got %s",
                                 cmd, lab_value_desc(id, buf, sizeof buf));
        }
        return lab_refresh(vt, sqlite3_value_int64(id), !refresh, err);
    }
    return ax_error_into(
        err, NULL, "laban: unknown command \"%.40s\" (expected rebuild, refresh, delete, check)",
        cmd);
}

/* ---- planning ---- */

static int lab_best_index(sqlite3_vtab *tab, sqlite3_index_info *info)
{
    static const int cols[IDX_BITS] = {COL_QUERY, COL_LABEL, COL_K, COL_RADIUS, COL_COMPONENTS, -1};
    int use[IDX_BITS];
    bool seen[IDX_BITS];
    for (int b = 0; b < IDX_BITS; b++) {
        use[b] = -1;
        seen[b] = false;
    }
    for (int i = 0; i < info->nConstraint; i++) {
        const struct sqlite3_index_constraint *c = &info->aConstraint[i];
        if (c->op != SQLITE_INDEX_CONSTRAINT_EQ)
            continue;
        for (int b = 0; b < IDX_BITS; b++)
            if (c->iColumn == cols[b]) {
                seen[b] = true;
                if (c->usable && use[b] < 0)
                    use[b] = i;
            }
    }
    /* query, k, radius, components: present but not usable in this plan → another plan */
    static const int needed[] = {0, 2, 3, 4};
    for (int i = 0; i < 4; i++)
        if (seen[needed[i]] && use[needed[i]] < 0)
            return SQLITE_CONSTRAINT;
    bool q = use[0] >= 0, k = use[2] >= 0, r = use[3] >= 0, comp = use[4] >= 0;
    if (!q && (k || r || comp))
        return ax_vtab_error(tab, NULL, "laban: k, radius and components need a query constraint");
    if (q && k && r)
        return ax_vtab_error(tab, NULL, "laban: use either k or radius, not both");
    if (q && !k && !r)
        return ax_vtab_error(tab, NULL, "laban: a k or radius constraint is required for a query");
    int idx = 0, argi = 0;
    for (int b = 0; b < IDX_BITS; b++)
        if (use[b] >= 0) {
            idx |= 1 << b;
            info->aConstraintUsage[use[b]].argvIndex = ++argi;
            info->aConstraintUsage[use[b]].omit = 1;
        }
    info->idxNum = idx;
    const struct sqlite3_index_orderby *o = info->aOrderBy;
    if (q) {
        info->estimatedCost = 100.0;
        info->estimatedRows = 10;
        if ((info->nOrderBy == 1 || (info->nOrderBy == 2 && o[1].iColumn == -1 && !o[1].desc)) &&
            o[0].iColumn == COL_DISTANCE && !o[0].desc)
            info->orderByConsumed = 1;
    } else {
        if (idx & IDX_ROWID) {
            info->estimatedCost = 1.0;
            info->estimatedRows = 1;
            info->idxFlags = SQLITE_INDEX_SCAN_UNIQUE;
        } else {
            info->estimatedCost = idx & IDX_LABEL ? 2500.0 : 10000.0;
            info->estimatedRows = idx & IDX_LABEL ? 2500 : 10000;
        }
        if (info->nOrderBy == 1 && o[0].iColumn == -1 && !o[0].desc)
            info->orderByConsumed = 1;
    }
    return SQLITE_OK;
}

/* ---- cursors ---- */

static int lab_open(sqlite3_vtab *tab, sqlite3_vtab_cursor **out)
{
    return ax_tvf_open(sizeof(lab_cursor), out);
}

static void lab_cursor_reset(lab_cursor *c)
{
    lab_cache_unref(c->cache);
    c->cache = NULL;
    sqlite3_free(c->label_ok);
    sqlite3_free(c->hits);
    for (int i = 0; i < 4; i++)
        sqlite3_value_free(c->args[i]);
    memset((char *)c + sizeof c->base, 0, sizeof *c - sizeof c->base);
}

static int lab_close(sqlite3_vtab_cursor *cur)
{
    lab_cursor_reset((lab_cursor *)cur);
    sqlite3_free(cur);
    return SQLITE_OK;
}

/* k: an integer ≥ 1 (an integral REAL is accepted). */
static int lab_arg_k(sqlite3_value *v, sqlite3_int64 *k, char **err)
{
    int t = sqlite3_value_type(v);
    double d = sqlite3_value_double(v);
    if (t == SQLITE_INTEGER)
        *k = sqlite3_value_int64(v);
    else if (t == SQLITE_FLOAT && d == floor(d) && fabs(d) < 9e15)
        *k = (sqlite3_int64)d;
    else
        *k = 0;
    if (*k >= 1)
        return SQLITE_OK;
    char buf[40];
    return ax_error_into(err, NULL, "laban: k must be a positive integer, got %s",
                         lab_value_desc(v, buf, sizeof buf));
}

static int lab_arg_radius(sqlite3_value *v, double *r, char **err)
{
    int t = sqlite3_value_type(v);
    *r = sqlite3_value_double(v);
    if ((t == SQLITE_INTEGER || t == SQLITE_FLOAT) && *r > 0 && *r <= 1)
        return SQLITE_OK;
    char buf[40];
    return ax_error_into(err, NULL, "laban: radius must be in (0, 1], got %s",
                         lab_value_desc(v, buf, sizeof buf));
}

/* components: a JSON array of distinct component names, or NULL (or absent) for all; out in
 * component order. */
static int lab_arg_components(sqlite3_value *v, int out[LAB_N], int *n, char **err)
{
    bool on[LAB_N] = {false};
    *n = 0;
    if (!v || sqlite3_value_type(v) == SQLITE_NULL) {
        for (int j = 0; j < LAB_N; j++)
            out[(*n)++] = j;
        return SQLITE_OK;
    }
    if (sqlite3_value_type(v) != SQLITE_TEXT)
        return ax_error_into(err, NULL,
                             "laban: components must be a JSON array of component names, got %s",
                             ax_type_name(v));
    const char *text = (const char *)sqlite3_value_text(v);
    if (!text)
        return SQLITE_NOMEM;
    affect_json_doc *doc = NULL;
    affect_error e;
    if (affect_json_parse(text, (size_t)sqlite3_value_bytes(v), &doc, NULL, &e))
        return e.status == AFFECT_ERR_NOMEM
                   ? SQLITE_NOMEM
                   : ax_error_into(err, NULL,
                                   "laban: components must be a JSON array of component names: %s",
                                   e.msg);
    int rc = SQLITE_OK;
    char q[80];
    const affect_json_node *root = affect_json_root(doc);
    if (root->type != AFFECT_JSON_ARRAY) {
        rc = ax_error_into(err, NULL,
                           "laban: components must be a JSON array of component names, got %s",
                           affect_json_type_name(root->type));
        goto done;
    }
    if (root->count == 0) {
        rc = ax_error_into(err, NULL, "laban: components must name at least one component");
        goto done;
    }
    for (const affect_json_node *m = affect_json_first(doc, root); m;
         m = affect_json_next_sibling(doc, m)) {
        if (m->type != AFFECT_JSON_STRING) {
            rc = ax_error_into(err, NULL,
                               "laban: components must be a JSON array of component names, got %s "
                               "in it",
                               affect_json_type_name(m->type));
            goto done;
        }
        int j = strlen(m->str) == m->str_len ? affect_laban_index(m->str) : -1;
        affect_json_quote(q, sizeof q, m->str, m->str_len);
        if (j < 0) {
            rc = ax_error_into(err, NULL, "laban: unknown component %s (see laban_names())", q);
            goto done;
        }
        if (on[j]) {
            rc = ax_error_into(err, NULL, "laban: component %s is listed twice", q);
            goto done;
        }
        on[j] = true;
    }
    for (int j = 0; j < LAB_N; j++)
        if (on[j])
            out[(*n)++] = j;
done:
    affect_json_free(doc);
    return rc;
}

/* Rows whose label passes the label = ? constraint (NULL: every row). */
static int lab_label_filter(const lab_cache *ca, sqlite3_value *want, unsigned char **out)
{
    *out = sqlite3_malloc64(ca->n_labels ? ca->n_labels : 1);
    if (!*out)
        return SQLITE_NOMEM;
    for (size_t j = 0; j < ca->n_labels; j++) {
        int eq = 0;
        if (ca->labels[j] && sqlite3_value_type(want) != SQLITE_NULL &&
            (eq = lab_value_equal(ca->labels[j], want, false)) < 0)
            return SQLITE_NOMEM;
        (*out)[j] = (unsigned char)eq;
    }
    return SQLITE_OK;
}

/* The standardized query vector: a motion BLOB or the rowid of an indexed row (*self). */
static int lab_query_vector(lab_vtab *vt, const lab_cache *ca, sqlite3_value *q, double zq[LAB_N],
                            ptrdiff_t *self, char **err)
{
    int t = sqlite3_value_type(q);
    *self = -1;
    double d = sqlite3_value_double(q);
    if (t == SQLITE_INTEGER || (t == SQLITE_FLOAT && d == floor(d) && fabs(d) < 9e15)) {
        sqlite3_int64 id = t == SQLITE_INTEGER ? sqlite3_value_int64(q) : (sqlite3_int64)d;
        *self = lab_cache_find(ca, id);
        if (*self < 0)
            return ax_error_into(err, NULL, "laban: no row %lld in the index", id);
        memcpy(zq, ca->z + (size_t)*self * LAB_N, sizeof(double) * LAB_N);
        return SQLITE_OK;
    }
    if (t != SQLITE_BLOB)
        return ax_error_into(err, NULL,
                             "laban: query must be a motion BLOB or a rowid of the content table, "
                             "got %s",
                             ax_type_name(q));
    const unsigned char *data = sqlite3_value_blob(q);
    int n = sqlite3_value_bytes(q);
    if (!data && n > 0)
        return SQLITE_NOMEM;
    float v[LAB_N];
    bool bad;
    affect_error e;
    if (lab_vector(vt, data, (size_t)n, v, &bad, &e))
        return lab_core_error(err, &e, bad ? "query is not a valid motion: " : "query: ");
    affect_laban_standardize(v, 1, ca->mean, ca->sd, zq);
    return SQLITE_OK;
}

static int hit_order(const void *a, const void *b)
{
    return affect_laban_hit_cmp(a, b);
}

/* The radius ball from the candidates of every part, hits[run[i] .. run[i + 1]) sorted for
 * each part i < n_runs: those within limit, or the nearest alone when there is none, as
 * affect_laban_search_run selects them, sorted by merging the parts' runs. */
static int lab_ball(lab_cursor *c, size_t *run, size_t n_runs, double limit, size_t *n)
{
    affect_laban_hit *a = c->hits, nearest = {INFINITY, 0, 0};
    size_t kept = 0;
    bool any = false;
    for (size_t r = 0; r < n_runs; r++) {
        size_t from = run[r];
        run[r] = kept;
        if (from < run[r + 1] && (!any || affect_laban_hit_cmp(&a[from], &nearest) < 0))
            nearest = a[from]; /* a run's first is its nearest */
        any = any || from < run[r + 1];
        for (size_t i = from; i < run[r + 1]; i++)
            if (a[i].d <= limit)
                a[kept++] = a[i];
    }
    run[n_runs] = kept;
    if (kept == 0 && any)
        a[kept++] = nearest;
    *n = kept;
    if (kept <= 1)
        return SQLITE_OK;
    affect_laban_hit *b = sqlite3_malloc64(kept * sizeof *b);
    if (!b)
        return SQLITE_NOMEM;
    while (n_runs > 1) { /* merge neighbouring runs, a into b, until one is left */
        size_t out = 0;
        for (size_t r = 0; r < n_runs; r += 2) {
            size_t p = run[r], pe = run[r + 1], q = pe, qe = r + 1 < n_runs ? run[r + 2] : pe;
            size_t o = p;
            while (p < pe && q < qe)
                b[o++] = affect_laban_hit_cmp(&a[q], &a[p]) < 0 ? a[q++] : a[p++];
            while (p < pe)
                b[o++] = a[p++];
            while (q < qe)
                b[o++] = a[q++];
            run[out++] = run[r];
        }
        run[out] = kept;
        n_runs = out;
        affect_laban_hit *t = a;
        a = b;
        b = t;
    }
    sqlite3_free(b);
    c->hits = a;
    return SQLITE_OK;
}

/* Nearest rows: the k smallest distances (k > 0) or the radius ball (k = 0), by
 * affect_laban_search_run (core/laban/laban_search.c: the distance, the heap and the tie rule).
 * More than LAB_POLL_ROWS rows are searched LAB_POLL_ROWS at a time, polling the interrupt
 * between two ("laban: interrupted"), with the same result: the k nearest are the k first, by
 * the tie rule's total order, of each part's k nearest; the radius ball is taken from all the
 * candidates, each part giving them all (radius 1), by the core's rule: those within radius ×
 * the largest distance, or the nearest alone when there is none. */
static int lab_knn(lab_cursor *c, sqlite3 *db, const double zq[LAB_N], ptrdiff_t self, size_t lo,
                   size_t hi, sqlite3_int64 k, double radius, const int *comp, int nc, char **err)
{
    const lab_cache *ca = c->cache;
    affect_laban_search s = {
        .z = ca->z,
        .ids = ca->ids,
        .lo = lo,
        .hi = hi,
        .self = self < 0 ? SIZE_MAX : (size_t)self,
        .label = ca->label,
        .label_ok = c->label_ok,
        .comp = comp,
        .n_comp = nc,
        .k = (uint64_t)k,
        .radius = radius,
    };
    bool parts = hi - lo > LAB_POLL_ROWS;
    size_t cap = affect_laban_search_capacity(&s), bytes;
    if (parts && k > 0) /* room for one part's hits after the best so far */
        cap += (uint64_t)k < LAB_POLL_ROWS ? (size_t)k : LAB_POLL_ROWS;
    if (!affect_mul_size(cap ? cap : 1, sizeof *c->hits, &bytes) ||
        !(c->hits = sqlite3_malloc64(bytes)))
        return SQLITE_NOMEM;
    if (!parts) {
        affect_laban_search_run(&s, zq, c->hits, &c->n_hits);
        return SQLITE_OK;
    }
    ax_monitor am;
    char *msg = NULL;
    if (ax_monitor_begin_db(&am, db, NULL, &msg) != SQLITE_OK) { /* no progress function */
        sqlite3_free(msg);
        return SQLITE_NOMEM;
    }
    int rc = SQLITE_OK;
    size_t n = 0, n_runs = 0, *run = NULL; /* the radius: where each part's hits start */
    double dmax = 0;
    if (k == 0) {
        s.radius = 1; /* every candidate of the part */
        if (!(run = sqlite3_malloc64(((hi - lo) / LAB_POLL_ROWS + 2) * sizeof *run))) {
            ax_monitor_end(&am);
            return SQLITE_NOMEM;
        }
    }
    for (size_t at = lo; at < hi; at += LAB_POLL_ROWS) {
        if (at > lo && ax_monitor_interrupted(&am)) {
            rc = lab_interrupted(err);
            break;
        }
        size_t got;
        s.lo = at;
        s.hi = hi - at > LAB_POLL_ROWS ? at + LAB_POLL_ROWS : hi;
        affect_laban_search_run(&s, zq, c->hits + n, &got);
        if (run)
            run[n_runs++] = n;
        if (k == 0 && got > 0 && c->hits[n + got - 1].d > dmax)
            dmax = c->hits[n + got - 1].d; /* sorted: the part's largest is its last */
        n += got;
        if (k > 0) {
            qsort(c->hits, n, sizeof *c->hits, hit_order);
            n = n > (uint64_t)k ? (size_t)k : n;
        }
    }
    ax_monitor_end(&am);
    if (rc == SQLITE_OK && run) {
        run[n_runs] = n;
        rc = lab_ball(c, run, n_runs, radius * dmax, &n);
    }
    sqlite3_free(run);
    c->n_hits = rc == SQLITE_OK ? n : 0;
    return rc;
}

static void lab_scan_skip(lab_cursor *c)
{
    const lab_cache *ca = c->cache;
    while (c->pos < c->end && c->label_ok &&
           (ca->label[c->pos] < 0 || !c->label_ok[ca->label[c->pos]]))
        c->pos++;
}

static int lab_filter(sqlite3_vtab_cursor *cur, int idx_num, const char *idx_str, int argc,
                      sqlite3_value **argv)
{
    lab_cursor *c = (lab_cursor *)cur;
    lab_vtab *vt = (lab_vtab *)cur->pVtab;
    char **err = &vt->base.zErrMsg;
    lab_cursor_reset(c);
    sqlite3_value *arg[IDX_BITS] = {NULL};
    for (int b = 0, a = 0; b < IDX_BITS; b++)
        if (idx_num & (1 << b) && a < argc)
            arg[b] = argv[a++];
    sqlite3_value *query = arg[0], *label = arg[1], *kv = arg[2], *rv = arg[3], *cv = arg[4],
                  *idv = arg[5];

    sqlite3_int64 k = 0;
    double radius = 0;
    int comp[LAB_N], nc = 0;
    int rc = SQLITE_OK;
    if ((kv && (rc = lab_arg_k(kv, &k, err))) || (rv && (rc = lab_arg_radius(rv, &radius, err))) ||
        (rc = lab_arg_components(cv, comp, &nc, err)) != SQLITE_OK)
        return rc;
    lab_cache *ca;
    if ((rc = lab_cache_current(vt, err, &ca)) != SQLITE_OK)
        return rc;
    c->cache = ca;
    ca->refs++;
    c->knn = query != NULL;
    sqlite3_value *keep[4] = {query, kv, rv, cv};
    for (int i = 0; i < 4; i++)
        if (keep[i] && !(c->args[i] = sqlite3_value_dup(keep[i])))
            return SQLITE_NOMEM;

    /* the rows [lo, hi) that the rowid constraint allows */
    size_t lo = 0, hi = ca->n;
    if (idv) {
        /* INTEGER affinity, as for any rowid: '7' and 7.0 name row 7 */
        sqlite3_value *id = sqlite3_value_dup(idv);
        if (!id)
            return SQLITE_NOMEM;
        int t = sqlite3_value_numeric_type(id);
        double d = sqlite3_value_double(id);
        ptrdiff_t at = -1;
        if (t == SQLITE_INTEGER)
            at = lab_cache_find(ca, sqlite3_value_int64(id));
        else if (t == SQLITE_FLOAT && d == floor(d) && fabs(d) < 9e15)
            at = lab_cache_find(ca, (sqlite3_int64)d);
        sqlite3_value_free(id);
        lo = at < 0 ? 0 : (size_t)at;
        hi = at < 0 ? 0 : lo + 1;
    }
    if (label && (rc = lab_label_filter(ca, label, &c->label_ok)) != SQLITE_OK)
        return rc;
    if (!c->knn) {
        c->pos = lo;
        c->end = hi;
        lab_scan_skip(c);
        return SQLITE_OK;
    }
    if (sqlite3_value_type(query) == SQLITE_NULL)
        return SQLITE_OK; /* query = NULL matches nothing */
    double zq[LAB_N];
    ptrdiff_t self;
    if ((rc = lab_query_vector(vt, ca, query, zq, &self, err)) != SQLITE_OK)
        return rc;
    return lab_knn(c, vt->db, zq, self, lo, hi, kv ? k : 0, radius, comp, nc, err);
}

static int lab_next(sqlite3_vtab_cursor *cur)
{
    lab_cursor *c = (lab_cursor *)cur;
    if (c->knn) {
        c->hit++;
    } else {
        c->pos++;
        lab_scan_skip(c);
    }
    return SQLITE_OK;
}

static int lab_eof(sqlite3_vtab_cursor *cur)
{
    lab_cursor *c = (lab_cursor *)cur;
    return c->knn ? c->hit >= c->n_hits : c->pos >= c->end;
}

static size_t lab_row(const lab_cursor *c)
{
    return c->knn ? c->hits[c->hit].row : c->pos;
}

static int lab_column(sqlite3_vtab_cursor *cur, sqlite3_context *ctx, int col)
{
    lab_cursor *c = (lab_cursor *)cur;
    const lab_cache *ca = c->cache;
    size_t row = lab_row(c);
    if (col == COL_LABEL) {
        if (ca->label[row] >= 0)
            sqlite3_result_value(ctx, ca->labels[ca->label[row]]);
    } else if (col >= COL_COMP0 && col < COL_COMP0 + LAB_N) {
        float f = ca->raw[row * LAB_N + (col - COL_COMP0)];
        if (!isnan(f))
            sqlite3_result_double(ctx, f);
    } else if (col == COL_DISTANCE) {
        if (c->knn)
            sqlite3_result_double(ctx, c->hits[c->hit].d);
    } else if (col >= COL_QUERY && col <= COL_COMPONENTS) {
        if (c->args[col - COL_QUERY])
            sqlite3_result_value(ctx, c->args[col - COL_QUERY]);
    }
    return SQLITE_OK; /* anything else (the command column) is NULL */
}

static int lab_rowid(sqlite3_vtab_cursor *cur, sqlite3_int64 *rowid)
{
    lab_cursor *c = (lab_cursor *)cur;
    *rowid = c->cache->ids[lab_row(c)];
    return SQLITE_OK;
}

static sqlite3_module lab_module = {
    .iVersion = 3,
    .xCreate = lab_create,
    .xConnect = lab_connect,
    .xBestIndex = lab_best_index,
    .xDisconnect = lab_disconnect,
    .xDestroy = lab_destroy,
    .xOpen = lab_open,
    .xClose = lab_close,
    .xFilter = lab_filter,
    .xNext = lab_next,
    .xEof = lab_eof,
    .xColumn = lab_column,
    .xRowid = lab_rowid,
    .xUpdate = lab_update,
    .xBegin = lab_begin,
    .xSync = lab_sync,
    .xCommit = lab_commit,
    .xRollback = lab_rollback,
    .xRename = lab_rename,
    .xSavepoint = lab_savepoint,
    .xRelease = lab_savepoint,
    .xRollbackTo = lab_rollback_to,
    .xShadowName = lab_shadow_name,
};

int ax_register_laban(sqlite3 *db, const ax_laban_cache_kind *caches)
{
    return sqlite3_create_module(db, "laban", &lab_module, (void *)caches);
}
