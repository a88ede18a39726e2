/*
 * fn_hmm.h — the hmm_* SQL functions (registered in affect.c): the hmm_train aggregate and the
 * scalar functions that score, decode and describe a model BLOB.
 */
#ifndef AFFECT_EXT_FN_HMM_H
#define AFFECT_EXT_FN_HMM_H

#include "fn_motion.h"

void ax_hmm_train_step(sqlite3_context *ctx, int argc, sqlite3_value **argv);
void ax_hmm_train_final(sqlite3_context *ctx);
AX_FN(ax_hmm_loglik);
AX_FN(ax_hmm_viterbi);
AX_FN(ax_hmm_viterbi_loglik);
AX_FN(ax_hmm_info);
AX_FN(ax_hmm_postures);

#endif
