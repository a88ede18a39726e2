/*
 * fn_skeleton.h — skeletal-motion SQL functions: motion_to_bvh, motion_rigid, and the
 * motion_angles table-valued function (vt_angles.c); the option parsing they share.
 */
#ifndef AFFECT_EXT_FN_SKELETON_H
#define AFFECT_EXT_FN_SKELETON_H

#include "common.h"
#include "affect/io.h"
#include "affect/skeleton.h"

/* Options of the functions that need a skeletal motion. */
typedef struct ax_skel_opts {
    affect_rotation_source rotations;
    affect_ik_options ik;
    bool order_given;             /* "order" was set */
    affect_bvh_write_options bvh; /* motion_to_bvh's own keys */
    bool *free_link;              /* from "free" (n_joints flags), or NULL */
} ax_skel_opts;

/* Parses a JSON options object (text may be NULL: defaults) whose keys must be in allowed.
 * Keys: rotations ("auto" | "stored" | "ik"), rest_frame, lengths ("median" | "first"),
 * siblings ("auto" | "rotate" | "translate"),
 * free (joint names), order ("ZXY", …), frame_time, precision, root. */
affect_status ax_skel_opts_parse(const char *text, size_t len, const char *const *allowed,
                                 const affect_motion *m, ax_skel_opts *so, affect_error *err);
void ax_skel_opts_free(ax_skel_opts *so);

/* The skeletal form of m under the options (affect_motion_skeletal): m itself (*out = m) or a
 * new motion. */
affect_status ax_skeletal(affect_motion *m, const ax_skel_opts *so, affect_motion **out,
                          affect_error *err);

#define AX_FN(name) void name(sqlite3_context *ctx, int argc, sqlite3_value **argv)
AX_FN(ax_motion_to_bvh);
AX_FN(ax_motion_rigid);

/* The motion_angles table-valued function (vt_angles.c). */
int ax_register_angles(sqlite3 *db);

#endif
