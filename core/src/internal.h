/*
 * internal.h — small helpers shared by the core's .c files (not part of the public API).
 */
#ifndef AFFECT_INTERNAL_H
#define AFFECT_INTERNAL_H

#include <stdint.h>

/* FNV-1a hash of a NUL-terminated string (joint-name sets). */
static inline uint32_t affect_hash_name(const char *s)
{
    uint32_t h = 2166136261u;
    for (; *s; s++)
        h = (h ^ (unsigned char)*s) * 16777619u;
    return h;
}

#endif
