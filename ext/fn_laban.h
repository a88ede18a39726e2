/*
 * fn_laban.h — the laban_* SQL function implementations (registered in affect.c).
 */
#ifndef AFFECT_EXT_FN_LABAN_H
#define AFFECT_EXT_FN_LABAN_H

#include "fn_motion.h"

AX_FN(ax_laban_weight);
AX_FN(ax_laban_time);
AX_FN(ax_laban_flow);
AX_FN(ax_laban_space);
AX_FN(ax_laban_shape_directional);
AX_FN(ax_laban_shape_shaping);
AX_FN(ax_laban_shape_flow);
AX_FN(ax_laban);
AX_FN(ax_laban_vector);
AX_FN(ax_laban_zvector);
AX_FN(ax_motion_kinematics);
AX_FN(ax_laban_names);

/* laban_series, the windowed Effort series (vt_laban_series.c). */
int ax_register_laban_series(sqlite3 *db);

#endif
