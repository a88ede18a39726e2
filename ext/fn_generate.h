/*
 * fn_generate.h — affect generation's SQL functions (registered in affect.c): affect_generate,
 * affect_generate_explain and laban_salient. They take an ax_gen_fn as user data (their name
 * first, then the cached RMLR fit of the last index used). motion_dtw, the distance used to
 * judge generated motions, is a plain deterministic function (its name as user data).
 */
#ifndef AFFECT_EXT_FN_GENERATE_H
#define AFFECT_EXT_FN_GENERATE_H

#include "fn_motion.h"

typedef struct ax_gen_fn ax_gen_fn;
ax_gen_fn *ax_gen_fn_new(const char *name);
void ax_gen_fn_free(void *fn);

AX_FN(ax_affect_generate);
AX_FN(ax_affect_generate_explain);
AX_FN(ax_laban_salient);
AX_FN(ax_motion_dtw);

#endif
