/*
 * fn_strength.h — the emotion-strength SQL functions (registered in affect.c): the
 * strength_train and rank_train aggregates, and the scalar functions that score, synthesize,
 * edit and describe with their models, and motion_keyframes.
 */
#ifndef AFFECT_EXT_FN_STRENGTH_H
#define AFFECT_EXT_FN_STRENGTH_H

#include "fn_motion.h"

void ax_strength_train_step(sqlite3_context *ctx, int argc, sqlite3_value **argv);
void ax_strength_train_final(sqlite3_context *ctx);
void ax_rank_train_step(sqlite3_context *ctx, int argc, sqlite3_value **argv);
void ax_rank_train_final(sqlite3_context *ctx);
/* affect_strength takes an ax_cached_fn (common.h) as user data (its name first, then a one-model
 * cache). */
AX_FN(ax_affect_strength);
AX_FN(ax_strength_synthesize);
AX_FN(ax_strength_edit);
AX_FN(ax_strength_info);
AX_FN(ax_motion_keyframes);
AX_FN(ax_rank_score);

#endif
