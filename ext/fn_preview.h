/*
 * fn_preview.h — motion_svg, the motion_svg_group and affect_heatmap aggregates (SVG
 * previews; registered in affect.c).
 */
#ifndef AFFECT_EXT_FN_PREVIEW_H
#define AFFECT_EXT_FN_PREVIEW_H

#include "common.h"

void ax_motion_svg(sqlite3_context *ctx, int argc, sqlite3_value **argv);
void ax_motion_svg_group_step(sqlite3_context *ctx, int argc, sqlite3_value **argv);
void ax_motion_svg_group_final(sqlite3_context *ctx);
void ax_affect_heatmap_step(sqlite3_context *ctx, int argc, sqlite3_value **argv);
void ax_affect_heatmap_final(sqlite3_context *ctx);

#endif
