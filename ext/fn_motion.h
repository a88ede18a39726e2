/*
 * fn_motion.h — the motion_* SQL function implementations (registered in affect.c).
 */
#ifndef AFFECT_EXT_FN_MOTION_H
#define AFFECT_EXT_FN_MOTION_H

#include "common.h"

#define AX_FN(name) void name(sqlite3_context *ctx, int argc, sqlite3_value **argv)
AX_FN(ax_motion_from_bvh);
AX_FN(ax_motion_bvh_error);
AX_FN(ax_motion_from_csv);
AX_FN(ax_motion_from_json);
AX_FN(ax_motion_to_json);
AX_FN(ax_motion_to_csv);
AX_FN(ax_motion_info);
AX_FN(ax_motion_scalar); /* motion_frames, motion_joints, motion_fps, motion_duration */
AX_FN(ax_motion_slice);
AX_FN(ax_motion_resample);
AX_FN(ax_motion_select);
AX_FN(ax_motion_roles);
AX_FN(ax_motion_normalize);
AX_FN(ax_motion_synth);

/* The motion_points table-valued function (vt_points.c). */
int ax_register_points(sqlite3 *db);

#endif
