/*
 * vt_angles.c — motion_angles, a table-valued function listing every joint's local rotation:
 *
 *   SELECT frame, name, rx, ry, rz, speed FROM motion_angles(:motion);
 *   SELECT name, max(speed) FROM motion_angles(:motion, '{"order":"XYZ"}') GROUP BY name;
 *
 * Columns: frame, joint, name, the unit quaternion (qw, qx, qy, qz), the Euler order, the
 * angles about X, Y and Z in degrees (rx, ry, rz: R = product of the axis rotations in `order`,
 * continuous from frame to frame), and the angular speed in radians per second (central
 * difference of the rotations). Rotations are the stored ones (a motion imported from BVH) or
 * come from inverse kinematics (affect_motion_ik) for motions with positions only; the options
 * are motion_to_bvh's: order, rotations, rest_frame, lengths, free. The default order is each
 * joint's own BVH channel order when it has three rotation channels, else ZXY.
 *
 * How it works: an eponymous-only virtual table with the schema
 *   CREATE TABLE x(frame INTEGER, joint INTEGER, name TEXT, qw REAL, qx REAL, qy REAL, qz REAL,
 *                  "order" TEXT, rx REAL, ry REAL, rz REAL, speed REAL,
 *                  motion HIDDEN, options HIDDEN)
 * xBestIndex needs an equality constraint on motion (idxNum bit 1) and takes one on options
 * (bit 2); rows run frame-major, rowid = frame × joints + joint. A NULL motion gives no rows.
 */
#include <stdlib.h>
#include <string.h>

#include "fn_skeleton.h"
#include "affect/quat.h"

enum {
    COL_FRAME,
    COL_JOINT,
    COL_NAME,
    COL_QW,
    COL_QX,
    COL_QY,
    COL_QZ,
    COL_ORDER,
    COL_RX,
    COL_RY,
    COL_RZ,
    COL_SPEED,
    COL_MOTION,
    COL_OPTIONS
};

typedef struct angles_cursor {
    sqlite3_vtab_cursor base;
    affect_motion *m, *sk; /* the argument and its skeletal form (may be the same) */
    int *orders;           /* per joint, 3 axes */
    double *prev;          /* per joint, the Euler angles of the last frame computed */
    sqlite3_int64 row, n_rows;
    double q[4], deg[3], speed;
} angles_cursor;

static int angles_connect(sqlite3 *db, void *aux, int argc, const char *const *argv,
                          sqlite3_vtab **out, char **err)
{
    return ax_tvf_connect(db,
                          "CREATE TABLE x(frame INTEGER, joint INTEGER, name TEXT, "
                          "qw REAL, qx REAL, qy REAL, qz REAL, \"order\" TEXT, rx REAL, "
                          "ry REAL, rz REAL, speed REAL, motion HIDDEN, options HIDDEN)",
                          out);
}

static int angles_open(sqlite3_vtab *vt, sqlite3_vtab_cursor **out)
{
    return ax_tvf_open(sizeof(angles_cursor), out);
}

static void angles_reset(angles_cursor *c)
{
    if (c->sk != c->m)
        affect_motion_free(c->sk);
    affect_motion_free(c->m);
    sqlite3_free(c->orders);
    sqlite3_free(c->prev);
    c->m = c->sk = NULL;
    c->orders = NULL;
    c->prev = NULL;
    c->row = c->n_rows = 0;
}

static int angles_close(sqlite3_vtab_cursor *cur)
{
    angles_reset((angles_cursor *)cur);
    sqlite3_free(cur);
    return SQLITE_OK;
}

/* Computes the current row's values (rows are visited in order, so prev holds frame t − 1). */
static void angles_compute(angles_cursor *c)
{
    if (c->row >= c->n_rows)
        return;
    uint32_t nj = c->sk->n_joints, t = (uint32_t)(c->row / nj), j = (uint32_t)(c->row % nj);
    double *prev = c->prev + (size_t)j * 3;
    affect_motion_joint_angles(c->sk, t, j, c->orders + (size_t)j * 3, t ? prev : NULL, c->q,
                               c->deg, &c->speed);
    memcpy(prev, c->deg, sizeof c->deg);
}

/* Per joint: its own order when it has three rotation channels and no order was asked. */
static void joint_orders(const affect_motion *sk, const ax_skel_opts *so, int *orders)
{
    for (uint32_t j = 0; j < sk->n_joints; j++) {
        int *o = orders + (size_t)j * 3, k = 0;
        memcpy(o, so->ik.order, 3 * sizeof *o);
        if (so->order_given)
            continue;
        const affect_skel_joint *s = &sk->skel[j];
        int own[3];
        for (int ch = 0; ch < s->n_channels && k < 3; ch++)
            if (s->channel[ch] >= AFFECT_CH_XROT)
                own[k++] = s->channel[ch] - AFFECT_CH_XROT;
        if (k == 3)
            memcpy(o, own, sizeof own);
    }
}

static const char *const angle_keys[] = {"order", "rotations", "rest_frame", "lengths",
                                         "free",  "siblings",  NULL};

static int angles_filter(sqlite3_vtab_cursor *cur, int idx_num, const char *idx_str, int argc,
                         sqlite3_value **argv)
{
    angles_cursor *c = (angles_cursor *)cur;
    angles_reset(c);
    affect_error err;
    const char *text;
    size_t len;
    ax_monitor am; /* the decoding and inverse kinematics of a long motion stop when asked */
    char *msg = NULL;
    if (ax_monitor_begin_db(&am, ((ax_tvf_vtab *)cur->pVtab)->db, NULL, &msg) != SQLITE_OK) {
        sqlite3_free(msg); /* no progress function: cannot fail */
        return SQLITE_NOMEM;
    }
    affect_status st = ax_motion_tvf_args(idx_num, argc, argv, &am.mon, &c->m, &text, &len, &err);
    if (st || !c->m) { /* an error, or a NULL motion: no rows */
        ax_monitor_end(&am);
        return st ? ax_vtab_error(cur->pVtab, &err, "motion_angles: %s", err.msg) : SQLITE_OK;
    }
    ax_skel_opts so;
    if (ax_skel_opts_parse(text, len, angle_keys, c->m, &so, &err)) {
        ax_monitor_end(&am);
        return ax_vtab_error(cur->pVtab, &err, "motion_angles: %s", err.msg);
    }
    so.ik.rigid.monitor = &am.mon; /* inverse kinematics of a long motion */
    st = ax_skeletal(c->m, &so, &c->sk, &err);
    ax_monitor_end(&am);
    if (!st) {
        size_t nj = c->sk->n_joints;
        c->orders = sqlite3_malloc64(nj * 3 * sizeof *c->orders);
        c->prev = sqlite3_malloc64(nj * 3 * sizeof *c->prev);
        if (!c->orders || !c->prev)
            st = affect_nomem(&err);
        else
            joint_orders(c->sk, &so, c->orders);
    }
    ax_skel_opts_free(&so);
    if (st)
        return ax_vtab_error(cur->pVtab, &err, "motion_angles: %s", err.msg);
    c->n_rows = (sqlite3_int64)c->sk->n_frames * c->sk->n_joints;
    angles_compute(c);
    return SQLITE_OK;
}

static int angles_next(sqlite3_vtab_cursor *cur)
{
    angles_cursor *c = (angles_cursor *)cur;
    c->row++;
    angles_compute(c);
    return SQLITE_OK;
}

static int angles_eof(sqlite3_vtab_cursor *cur)
{
    angles_cursor *c = (angles_cursor *)cur;
    return c->row >= c->n_rows;
}

static int angles_column(sqlite3_vtab_cursor *cur, sqlite3_context *ctx, int col)
{
    angles_cursor *c = (angles_cursor *)cur;
    uint32_t nj = c->sk->n_joints;
    uint32_t frame = (uint32_t)(c->row / nj), joint = (uint32_t)(c->row % nj);
    char order[4];
    switch (col) {
    case COL_FRAME:
        sqlite3_result_int64(ctx, frame);
        break;
    case COL_JOINT:
        sqlite3_result_int64(ctx, joint);
        break;
    case COL_NAME:
        sqlite3_result_text(ctx, c->sk->names[joint], -1, SQLITE_TRANSIENT);
        break;
    case COL_QW:
    case COL_QX:
    case COL_QY:
    case COL_QZ:
        sqlite3_result_double(ctx, c->q[col - COL_QW]);
        break;
    case COL_ORDER:
        affect_euler_order_name(c->orders + (size_t)joint * 3, order);
        sqlite3_result_text(ctx, order, 3, SQLITE_TRANSIENT);
        break;
    case COL_RX:
    case COL_RY:
    case COL_RZ: { /* deg[k] is about axis orders[k] */
        const int *o = c->orders + (size_t)joint * 3;
        int axis = col - COL_RX;
        for (int k = 0; k < 3; k++)
            if (o[k] == axis)
                sqlite3_result_double(ctx, c->deg[k]);
        break;
    }
    case COL_SPEED:
        sqlite3_result_double(ctx, c->speed);
        break;
    default:
        sqlite3_result_null(ctx);
        break; /* the hidden argument columns */
    }
    return SQLITE_OK;
}

static int angles_rowid(sqlite3_vtab_cursor *cur, sqlite3_int64 *rowid)
{
    *rowid = ((angles_cursor *)cur)->row;
    return SQLITE_OK;
}

static int angles_best_index(sqlite3_vtab *vt, sqlite3_index_info *info)
{
    return ax_motion_tvf_best_index(vt, info, COL_MOTION, COL_OPTIONS, "motion_angles");
}

static sqlite3_module angles_module = {
    .iVersion = 0,
    .xConnect = angles_connect,
    .xBestIndex = angles_best_index,
    .xDisconnect = ax_tvf_disconnect,
    .xOpen = angles_open,
    .xClose = angles_close,
    .xFilter = angles_filter,
    .xNext = angles_next,
    .xEof = angles_eof,
    .xColumn = angles_column,
    .xRowid = angles_rowid,
};

int ax_register_angles(sqlite3 *db)
{
    return sqlite3_create_module(db, "motion_angles", &angles_module, NULL);
}
