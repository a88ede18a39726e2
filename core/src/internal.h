/*
 * internal.h — small helpers shared by the core's .c files (not part of the public API).
 */
#ifndef AFFECT_INTERNAL_H
#define AFFECT_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

/* FNV-1a hash of a NUL-terminated string (joint-name sets). */
static inline uint32_t affect_hash_name(const char *s)
{
    uint32_t h = 2166136261u;
    for (; *s; s++)
        h = (h ^ (unsigned char)*s) * 16777619u;
    return h;
}

/* One allocation for a workspace of several arrays: each part receives a pointer into one block
 * (count elements of elem bytes, each part 64-byte aligned within it). Returns the block (free
 * it with affect_free) or NULL on overflow or allocation failure (the slots are then unset). */
typedef struct affect_ws_part {
    void **slot;
    size_t count;
    size_t elem;
} affect_ws_part;

void *affect_ws_alloc(const affect_ws_part *parts, size_t n);

#endif
