/*
 * fn_fda.h — the functional analysis's SQL functions (registered in affect.c): the fda_train
 * aggregate and the scalar functions on a functional model BLOB, which take an ax_fda_fn as
 * user data (their name first, then a one-model cache).
 */
#ifndef AFFECT_EXT_FN_FDA_H
#define AFFECT_EXT_FN_FDA_H

#include "fn_motion.h"

typedef struct ax_fda_fn ax_fda_fn;
ax_fda_fn *ax_fda_fn_new(const char *name);
void ax_fda_fn_free(void *fn);

void ax_fda_train_step(sqlite3_context *ctx, int argc, sqlite3_value **argv);
void ax_fda_train_final(sqlite3_context *ctx);
AX_FN(ax_fda_embed);
AX_FN(ax_fda_classify);
AX_FN(ax_fda_info);
AX_FN(ax_fda_prototype);
AX_FN(ax_fda_plot);

#endif
