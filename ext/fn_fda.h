/*
 * fn_fda.h — the functional analysis's SQL functions (registered in affect.c): the fda_train
 * aggregate and the scalar functions on a functional model BLOB, which take an ax_cached_fn
 * (common.h) as user data (their name first, then a one-model cache).
 */
#ifndef AFFECT_EXT_FN_FDA_H
#define AFFECT_EXT_FN_FDA_H

#include "affect/fda.h"
#include "fn_motion.h"

/* fda_train's model options (method, basis, order, lambda, dims, kernel, sigma, ffda_reg,
 * isomap_k, proto_dims: those present in opts) into cfg, then affect_fda_config_check; also
 * affect_crossval's (which admits the keys but method and kernel). */
ax_arg ax_fda_read_options(sqlite3_context *ctx, const ax_opts *opts, affect_fda_config *cfg);

void ax_fda_train_step(sqlite3_context *ctx, int argc, sqlite3_value **argv);
void ax_fda_train_final(sqlite3_context *ctx);
AX_FN(ax_fda_embed);
AX_FN(ax_fda_classify);
AX_FN(ax_fda_info);
AX_FN(ax_fda_prototype);
AX_FN(ax_fda_plot);

#endif
