/*
 * workspace.c — one allocation for a routine's scratch arrays (see internal.h): the HMM engine
 * and the Fisher scores size their parts from the problem, allocate once, and free once.
 *
 * Usage:
 *     double *a, *b;
 *     affect_ws_part parts[] = {{(void **)&a, n, sizeof *a}, {(void **)&b, m, sizeof *b}};
 *     void *block = affect_ws_alloc(parts, 2);
 *     if (!block) return affect_nomem(err);
 *     ...
 *     affect_free(block);
 */
#include "util/internal.h"

#include "affect/base.h"

void *affect_ws_alloc(const affect_ws_part *parts, size_t n)
{
    size_t total = 0;
    for (size_t i = 0; i < n; i++) {
        size_t bytes;
        if (!affect_mul_size(parts[i].count, parts[i].elem, &bytes) ||
            !affect_add_size(bytes, 63, &bytes))
            return NULL;
        bytes &= ~(size_t)63;
        if (!affect_add_size(total, bytes, &total))
            return NULL;
    }
    char *block = affect_malloc(total);
    if (!block)
        return NULL;
    size_t off = 0;
    for (size_t i = 0; i < n; i++) {
        *parts[i].slot = block + off;
        off += (parts[i].count * parts[i].elem + 63) & ~(size_t)63;
    }
    return block;
}
