/*
 * fn_plot.h — the laban_plot aggregate (an SVG scatter plot; registered in affect.c).
 */
#ifndef AFFECT_EXT_FN_PLOT_H
#define AFFECT_EXT_FN_PLOT_H

#include "common.h"

void ax_laban_plot_step(sqlite3_context *ctx, int argc, sqlite3_value **argv);
void ax_laban_plot_final(sqlite3_context *ctx);

#endif
