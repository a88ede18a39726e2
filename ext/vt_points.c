/*
 * vt_points.c — motion_points, a table-valued function listing every position of a motion:
 *
 *   SELECT frame, joint, name, x, y, z FROM motion_points(:motion);
 *   SELECT name, max(y) FROM motion_points((SELECT motion FROM motions WHERE id = 3))
 *    GROUP BY name;
 *
 * How it works: an eponymous-only virtual table with the schema
 *   CREATE TABLE x(frame INTEGER, joint INTEGER, name TEXT, x REAL, y REAL, z REAL,
 *                  motion HIDDEN)
 * The hidden column is the function's argument. xBestIndex (ax_motion_tvf_best_index, common.h)
 * accepts only an equality constraint on it:
 *   idxNum 1   motion = ? is usable and passed as argv[0] to xFilter
 * A plan where the constraint exists but is unusable gets SQLITE_CONSTRAINT so SQLite picks
 * another; no constraint at all is an error with the usage in the message. The motion is
 * decoded once per xFilter; rows run frame-major, rowid = frame × joints + joint. A NULL motion
 * gives no rows; an invalid one is an error naming the problem.
 */
#include <stdlib.h>
#include <string.h>

#include "fn_motion.h"

enum { COL_FRAME, COL_JOINT, COL_NAME, COL_X, COL_Y, COL_Z, COL_MOTION };

typedef struct points_cursor {
    sqlite3_vtab_cursor base;
    affect_motion *m;
    sqlite3_int64 row, n_rows;
} points_cursor;

static int points_connect(sqlite3 *db, void *aux, int argc, const char *const *argv,
                          sqlite3_vtab **out, char **err)
{
    return ax_tvf_connect(db,
                          "CREATE TABLE x(frame INTEGER, joint INTEGER, name TEXT, "
                          "x REAL, y REAL, z REAL, motion HIDDEN)",
                          out);
}

static int points_open(sqlite3_vtab *vt, sqlite3_vtab_cursor **out)
{
    return ax_tvf_open(sizeof(points_cursor), out);
}

static int points_close(sqlite3_vtab_cursor *cur)
{
    points_cursor *c = (points_cursor *)cur;
    affect_motion_free(c->m);
    sqlite3_free(c);
    return SQLITE_OK;
}

static int points_filter(sqlite3_vtab_cursor *cur, int idx_num, const char *idx_str, int argc,
                         sqlite3_value **argv)
{
    points_cursor *c = (points_cursor *)cur;
    affect_motion_free(c->m);
    c->m = NULL;
    c->row = c->n_rows = 0;
    if (argc < 1 || sqlite3_value_type(argv[0]) == SQLITE_NULL)
        return SQLITE_OK;
    if (sqlite3_value_type(argv[0]) != SQLITE_BLOB)
        return ax_vtab_error(cur->pVtab, NULL,
                             "motion_points: the argument must be a motion BLOB, got %s",
                             ax_type_name(argv[0]));
    const unsigned char *data = sqlite3_value_blob(argv[0]);
    int n = sqlite3_value_bytes(argv[0]);
    if (!data && n > 0)
        return SQLITE_NOMEM;
    affect_error err;
    if (affect_motion_decode(data, (size_t)n, &c->m, &err))
        return ax_vtab_error(cur->pVtab, &err,
                             "motion_points: the argument is not a valid motion: %s", err.msg);
    c->n_rows = (sqlite3_int64)c->m->n_frames * c->m->n_joints;
    return SQLITE_OK;
}

static int points_next(sqlite3_vtab_cursor *cur)
{
    ((points_cursor *)cur)->row++;
    return SQLITE_OK;
}

static int points_eof(sqlite3_vtab_cursor *cur)
{
    points_cursor *c = (points_cursor *)cur;
    return c->row >= c->n_rows;
}

static int points_column(sqlite3_vtab_cursor *cur, sqlite3_context *ctx, int col)
{
    points_cursor *c = (points_cursor *)cur;
    uint32_t nj = c->m->n_joints;
    uint32_t frame = (uint32_t)(c->row / nj), joint = (uint32_t)(c->row % nj);
    const float *p = affect_motion_at(c->m, frame, joint);
    switch (col) {
    case COL_FRAME:
        sqlite3_result_int64(ctx, frame);
        break;
    case COL_JOINT:
        sqlite3_result_int64(ctx, joint);
        break;
    case COL_NAME:
        sqlite3_result_text(ctx, c->m->names[joint], -1, SQLITE_TRANSIENT);
        break;
    case COL_X:
        sqlite3_result_double(ctx, p[0]);
        break;
    case COL_Y:
        sqlite3_result_double(ctx, p[1]);
        break;
    case COL_Z:
        sqlite3_result_double(ctx, p[2]);
        break;
    default:
        sqlite3_result_null(ctx);
        break; /* the hidden argument column */
    }
    return SQLITE_OK;
}

static int points_rowid(sqlite3_vtab_cursor *cur, sqlite3_int64 *rowid)
{
    *rowid = ((points_cursor *)cur)->row;
    return SQLITE_OK;
}

static int points_best_index(sqlite3_vtab *vt, sqlite3_index_info *info)
{
    return ax_motion_tvf_best_index(vt, info, COL_MOTION, -1, "motion_points");
}

static sqlite3_module points_module = {
    .iVersion = 0,
    .xConnect = points_connect,
    .xBestIndex = points_best_index,
    .xDisconnect = ax_tvf_disconnect,
    .xOpen = points_open,
    .xClose = points_close,
    .xFilter = points_filter,
    .xNext = points_next,
    .xEof = points_eof,
    .xColumn = points_column,
    .xRowid = points_rowid,
};

int ax_register_points(sqlite3 *db)
{
    return sqlite3_create_module(db, "motion_points", &points_module, NULL);
}
