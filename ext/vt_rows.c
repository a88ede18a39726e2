/*
 * vt_rows.c — materialized table-valued functions (see vt_rows.h).
 *
 * How it works: each spec is registered as an eponymous-only module whose aux pointer is the
 * spec. xBestIndex passes every usable equality constraint on a hidden argument column to
 * xFilter, in column order, and records which ones in idxNum (bit i = argument i); an
 * argument whose constraint exists but is unusable in this plan (its value comes from a table
 * joined later) gets SQLITE_CONSTRAINT, so SQLite picks a plan that knows it. A plan without
 * a required argument (SQLite asks for such plans when it splits an OR of constraints) gets a
 * huge cost and, should it still be chosen, fails in xFilter with the usage. xFilter rebuilds the
 * argument list (NULL for the ones not given), clears the previous rows, and calls fill (which
 * sets its errors with ax_vtab_error). Cells are returned as stored (text and BLOBs copied by
 * SQLite, SQLITE_TRANSIENT).
 */
#include "vt_rows.h"

#include <math.h>
#include <string.h>

#define MAX_ARGS 8
#define MISSING_SHIFT 16 /* idxNum bits 16..: 1 + the first missing required argument */

typedef struct rows_vtab {
    sqlite3_vtab base;
    sqlite3 *db;
    const ax_rows_spec *spec;
} rows_vtab;

typedef struct rows_cursor {
    sqlite3_vtab_cursor base;
    ax_rows rows;
    size_t row, n_rows;
} rows_cursor;

static void rows_clear(ax_rows *r)
{
    for (size_t i = 0; i < r->n_cells; i++)
        sqlite3_free(r->cells[i].p);
    sqlite3_free(r->cells);
    int n_cols = r->n_cols;
    memset(r, 0, sizeof *r);
    r->n_cols = n_cols;
}

static ax_cell *next_cell(ax_rows *r)
{
    if (r->nomem)
        return NULL;
    if (r->n_cells == r->cap) {
        size_t cap = r->cap ? 2 * r->cap : 64;
        ax_cell *cells = sqlite3_realloc64(r->cells, cap * sizeof *cells);
        if (!cells) {
            r->nomem = true;
            return NULL;
        }
        r->cells = cells;
        r->cap = cap;
    }
    ax_cell *c = &r->cells[r->n_cells++];
    memset(c, 0, sizeof *c);
    c->type = SQLITE_NULL;
    return c;
}

void ax_rows_null(ax_rows *r)
{
    next_cell(r);
}

void ax_rows_int(ax_rows *r, sqlite3_int64 v)
{
    ax_cell *c = next_cell(r);
    if (c) {
        c->type = SQLITE_INTEGER;
        c->i = v;
    }
}

void ax_rows_double(ax_rows *r, double v)
{
    ax_cell *c = next_cell(r);
    if (c && !isnan(v)) {
        c->type = SQLITE_FLOAT;
        c->d = v;
    }
}

void ax_rows_take_text(ax_rows *r, char *s, size_t len, bool json)
{
    if (!s) {
        r->nomem = true;
        return;
    }
    ax_cell *c = next_cell(r);
    if (!c) {
        sqlite3_free(s);
        return;
    }
    c->type = SQLITE_TEXT;
    c->p = s;
    c->len = len;
    c->json = json;
}

void ax_rows_text(ax_rows *r, const char *s, size_t len)
{
    char *copy = sqlite3_malloc64(len + 1);
    if (copy) {
        memcpy(copy, s, len);
        copy[len] = '\0';
    }
    ax_rows_take_text(r, copy, len, false);
}

void ax_rows_take_blob(ax_rows *r, void *p, size_t len)
{
    if (!p) {
        r->nomem = true;
        return;
    }
    ax_cell *c = next_cell(r);
    if (!c) {
        sqlite3_free(p);
        return;
    }
    c->type = SQLITE_BLOB;
    c->p = p;
    c->len = len;
}

bool ax_rows_failed(const ax_rows *r)
{
    return r->nomem;
}

static int rows_connect(sqlite3 *db, void *aux, int argc, const char *const *argv,
                        sqlite3_vtab **out, char **err)
{
    (void)argc;
    (void)argv;
    (void)err;
    const ax_rows_spec *spec = aux;
    int rc = sqlite3_declare_vtab(db, spec->schema);
    if (rc != SQLITE_OK)
        return rc;
    rows_vtab *vt = sqlite3_malloc(sizeof *vt);
    if (!vt)
        return SQLITE_NOMEM;
    memset(vt, 0, sizeof *vt);
    vt->db = db;
    vt->spec = spec;
    sqlite3_vtab_config(db, spec->direct_only ? SQLITE_VTAB_DIRECTONLY : SQLITE_VTAB_INNOCUOUS);
    *out = &vt->base;
    return SQLITE_OK;
}

static int rows_disconnect(sqlite3_vtab *vt)
{
    sqlite3_free(vt);
    return SQLITE_OK;
}

static int rows_open(sqlite3_vtab *vtab, sqlite3_vtab_cursor **out)
{
    int rc = ax_tvf_open(sizeof(rows_cursor), out);
    if (rc == SQLITE_OK)
        ((rows_cursor *)*out)->rows.n_cols = ((rows_vtab *)vtab)->spec->n_visible;
    return rc;
}

static int rows_close(sqlite3_vtab_cursor *cur)
{
    rows_cursor *c = (rows_cursor *)cur;
    rows_clear(&c->rows);
    sqlite3_free(c);
    return SQLITE_OK;
}

static int rows_best_index(sqlite3_vtab *vtab, sqlite3_index_info *info)
{
    const ax_rows_spec *spec = ((rows_vtab *)vtab)->spec;
    int usable[MAX_ARGS], seen[MAX_ARGS];
    for (int a = 0; a < spec->n_args; a++)
        usable[a] = -1, seen[a] = 0;
    for (int i = 0; i < info->nConstraint; i++) {
        const struct sqlite3_index_constraint *k = &info->aConstraint[i];
        int a = k->iColumn - spec->n_visible;
        if (a < 0 || a >= spec->n_args)
            continue;
        seen[a] = 1;
        if (k->usable && k->op == SQLITE_INDEX_CONSTRAINT_EQ)
            usable[a] = i;
    }
    int mask = 0, next = 1;
    bool missing = false;
    for (int a = 0; a < spec->n_args; a++) {
        if (usable[a] < 0) {
            if (seen[a]) /* a plan where the argument's value is known exists: use that one */
                return SQLITE_CONSTRAINT;
            if (a < spec->min_args && !missing) { /* reported by xFilter if no plan is better */
                missing = true;
                mask |= (a + 1) << MISSING_SHIFT;
            }
            continue;
        }
        info->aConstraintUsage[usable[a]].argvIndex = next++;
        info->aConstraintUsage[usable[a]].omit = 1;
        mask |= 1 << a;
    }
    info->idxNum = mask;
    info->estimatedCost = missing ? 1e300 : 1e6;
    info->estimatedRows = 100;
    return SQLITE_OK;
}

static int rows_filter(sqlite3_vtab_cursor *cur, int idx_num, const char *idx_str, int argc,
                       sqlite3_value **argv)
{
    (void)idx_str;
    rows_cursor *c = (rows_cursor *)cur;
    rows_vtab *vt = (rows_vtab *)cur->pVtab;
    const ax_rows_spec *spec = vt->spec;
    if (idx_num >> MISSING_SHIFT)
        return ax_vtab_error(&vt->base, NULL, "%s: argument %d is required, as in %s", spec->name,
                             idx_num >> MISSING_SHIFT, spec->usage);
    sqlite3_value *args[MAX_ARGS];
    int given = 0;
    for (int a = 0; a < spec->n_args; a++)
        args[a] = (idx_num & (1 << a)) && given < argc ? argv[given++] : NULL;
    int n = spec->n_args; /* trailing arguments not given count as absent */
    while (n > 0 && args[n - 1] == NULL)
        n--;
    rows_clear(&c->rows);
    c->row = c->n_rows = 0;
    int rc = spec->fill(&vt->base, vt->db, n, args, &c->rows);
    if (rc == SQLITE_OK && c->rows.nomem)
        rc = SQLITE_NOMEM;
    if (rc != SQLITE_OK) {
        rows_clear(&c->rows);
        return rc;
    }
    c->n_rows = spec->n_visible ? c->rows.n_cells / (size_t)spec->n_visible : 0;
    return SQLITE_OK;
}

static int rows_next(sqlite3_vtab_cursor *cur)
{
    ((rows_cursor *)cur)->row++;
    return SQLITE_OK;
}

static int rows_eof(sqlite3_vtab_cursor *cur)
{
    rows_cursor *c = (rows_cursor *)cur;
    return c->row >= c->n_rows;
}

static int rows_column(sqlite3_vtab_cursor *cur, sqlite3_context *ctx, int col)
{
    rows_cursor *c = (rows_cursor *)cur;
    if (col >= c->rows.n_cols) { /* a hidden argument column */
        sqlite3_result_null(ctx);
        return SQLITE_OK;
    }
    const ax_cell *cell = &c->rows.cells[c->row * (size_t)c->rows.n_cols + (size_t)col];
    switch (cell->type) {
    case SQLITE_INTEGER:
        sqlite3_result_int64(ctx, cell->i);
        break;
    case SQLITE_FLOAT:
        sqlite3_result_double(ctx, cell->d);
        break;
    case SQLITE_TEXT:
        sqlite3_result_text64(ctx, cell->p, cell->len, SQLITE_TRANSIENT, SQLITE_UTF8);
        if (cell->json)
            sqlite3_result_subtype(ctx, AX_JSON_SUBTYPE);
        break;
    case SQLITE_BLOB:
        sqlite3_result_blob64(ctx, cell->p, cell->len, SQLITE_TRANSIENT);
        break;
    default:
        sqlite3_result_null(ctx);
        break;
    }
    return SQLITE_OK;
}

static int rows_rowid(sqlite3_vtab_cursor *cur, sqlite3_int64 *rowid)
{
    *rowid = (sqlite3_int64)((rows_cursor *)cur)->row + 1;
    return SQLITE_OK;
}

static const sqlite3_module rows_module = {
    .iVersion = 0,
    .xConnect = rows_connect,
    .xBestIndex = rows_best_index,
    .xDisconnect = rows_disconnect,
    .xOpen = rows_open,
    .xClose = rows_close,
    .xFilter = rows_filter,
    .xNext = rows_next,
    .xEof = rows_eof,
    .xColumn = rows_column,
    .xRowid = rows_rowid,
};

int ax_rows_register(sqlite3 *db, const ax_rows_spec *spec)
{
    if (spec->n_args > MAX_ARGS)
        return SQLITE_MISUSE;
    return sqlite3_create_module(db, spec->name, &rows_module, (void *)spec);
}
