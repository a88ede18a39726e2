/*
 * fn_affect.h — the emotion recognizer's SQL functions (registered in affect.c): the
 * affect_train aggregate and the scalar functions on a classifier BLOB. The scalar functions
 * take an ax_cached_fn (common.h) as user data (their name first, then a one-classifier cache).
 */
#ifndef AFFECT_EXT_FN_AFFECT_H
#define AFFECT_EXT_FN_AFFECT_H

#include "fn_motion.h"

void ax_affect_train_step(sqlite3_context *ctx, int argc, sqlite3_value **argv);
void ax_affect_train_final(sqlite3_context *ctx);
AX_FN(ax_affect_classify);
AX_FN(ax_affect_scores);
AX_FN(ax_fisher_score);
AX_FN(ax_affect_embed);
AX_FN(ax_affect_info);
void ax_affect_crossval_step(sqlite3_context *ctx, int argc, sqlite3_value **argv);
void ax_affect_crossval_final(sqlite3_context *ctx);
/* The table-valued functions affect_salience and affect_crossval (vt_affect.c). */
int ax_register_affect_salience(sqlite3 *db);
int ax_register_affect_crossval(sqlite3 *db);

#endif
