/*
 * vt_laban.h — the laban virtual table module (vt_laban.c): an external-content index of the
 * Laban descriptors of a table of motions, with k-nearest and radius queries.
 */
#ifndef AFFECT_EXT_VT_LABAN_H
#define AFFECT_EXT_VT_LABAN_H

#include "common.h"

/* Registers the module "laban" on db. */
int ax_register_laban(sqlite3 *db);

#endif
