/*
 * vt_rows.h — table-valued functions whose rows are all computed at once (affect_salience,
 * affect_crossval): an eponymous-only virtual table whose last columns are HIDDEN arguments;
 * xFilter calls the function's fill callback with the argument values, which appends rows of
 * typed cells, and the cursor walks them.
 *
 * Usage:
 *     static int fill(sqlite3_vtab *vt, sqlite3 *db, int argc, sqlite3_value **argv,
 *                     ax_rows *rows)
 *     {   ... ax_rows_int(rows, 3); ax_rows_text(rows, "sad", 3); ...  }
 *     static const ax_rows_spec spec = {"affect_salience",
 *         "CREATE TABLE x(label TEXT, weight REAL, classifier HIDDEN)", 2, 1, 1, fill,
 *         "SELECT * FROM affect_salience(:classifier)"};
 *     ax_rows_register(db, &spec);
 * fill returns SQLITE_OK, SQLITE_NOMEM, or an error code with the whole error text set by
 * ax_vtab_error(vt, …) (common.h). The append functions record the first allocation failure in
 * rows->nomem; fill checks it (ax_rows_failed) or lets the caller do so after it returns.
 */
#ifndef AFFECT_EXT_VT_ROWS_H
#define AFFECT_EXT_VT_ROWS_H

#include "common.h"

typedef struct ax_cell {
    int type;  /* SQLITE_INTEGER, SQLITE_FLOAT, SQLITE_TEXT, SQLITE_BLOB, SQLITE_NULL */
    bool json; /* text with the JSON subtype */
    sqlite3_int64 i;
    double d;
    void *p; /* text or blob (sqlite3_malloc'd) */
    size_t len;
} ax_cell;

typedef struct ax_rows {
    int n_cols;     /* visible columns */
    ax_cell *cells; /* rows × n_cols */
    size_t n_cells, cap;
    bool nomem;
} ax_rows;

typedef int (*ax_rows_fill)(sqlite3_vtab *vt, sqlite3 *db, int argc, sqlite3_value **argv,
                            ax_rows *rows);

typedef struct ax_rows_spec {
    const char *name;
    const char *schema; /* CREATE TABLE x(visible columns…, arguments HIDDEN…) */
    int n_visible;      /* visible columns; the hidden ones follow */
    int n_args;         /* hidden argument columns */
    int min_args;       /* arguments that must be given */
    ax_rows_fill fill;
    const char *usage; /* shown when arguments are missing */
    bool direct_only;  /* SQLITE_VTAB_DIRECTONLY (reads other tables), else INNOCUOUS */
} ax_rows_spec;

int ax_rows_register(sqlite3 *db, const ax_rows_spec *spec);

void ax_rows_null(ax_rows *r);
void ax_rows_int(ax_rows *r, sqlite3_int64 v);
void ax_rows_double(ax_rows *r, double v); /* NaN → NULL */
void ax_rows_text(ax_rows *r, const char *s, size_t len);
/* Takes ownership of s (sqlite3_malloc'd, may be NULL = out of memory). */
void ax_rows_take_text(ax_rows *r, char *s, size_t len, bool json);
void ax_rows_take_blob(ax_rows *r, void *p, size_t len);
bool ax_rows_failed(const ax_rows *r);

#endif
