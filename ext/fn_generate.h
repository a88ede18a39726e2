/*
 * fn_generate.h — affect generation's SQL functions (registered in affect.c): affect_generate,
 * affect_generate_explain and laban_salient. They take an ax_gen_fn as user data (their name
 * first, then the cached RMLR fit of the last index used). motion_dtw, the distance used to
 * judge generated motions, is a plain deterministic function (its name as user data).
 */
#ifndef AFFECT_EXT_FN_GENERATE_H
#define AFFECT_EXT_FN_GENERATE_H

#include "fn_motion.h"
#include "vt_laban.h"

typedef struct ax_gen_fn ax_gen_fn;
ax_gen_fn *ax_gen_fn_new(const char *name);
void ax_gen_fn_free(void *fn);

AX_FN(ax_affect_generate);
AX_FN(ax_affect_generate_explain);
AX_FN(ax_laban_salient);
AX_FN(ax_motion_dtw);

/* The 'check' of a laban index's cache entry "rmlr" (ax_laban_cache_kind, vt_laban.h): the
 * stored RMLR fit must decode exactly, with the 27 components and the row count of its key;
 * a fit whose key names the index's current rows must also have its classes. */
int ax_gen_check_fit(const ax_laban_rows *rows, const char *tag, const void *blob, int size,
                     char **why);

#endif
