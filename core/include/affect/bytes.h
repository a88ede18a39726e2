/*
 * affect/bytes.h — little-endian binary encoding for the BLOB formats: a growable writer and a
 * bounds-checked reader. Values are written byte by byte, so the encoding does not depend on the
 * host's byte order or alignment.
 *
 * Writer: every put appends; the first allocation failure sets `failed` and later puts do
 * nothing, so a caller checks once at the end:
 *     affect_bw w;
 *     affect_bw_init(&w);
 *     affect_bw_u32(&w, 7);
 *     affect_bw_f64s(&w, values, n);
 *     if (w.failed) { affect_bw_free(&w); return affect_nomem(err); }
 *     ... w.data, w.len (free with affect_bw_free, or take w.data and free it with affect_free)
 *
 * Reader: every get returns false, reading nothing, when fewer bytes are left than it needs;
 * r.off is then the offset of the field that did not fit, for the caller's message.
 */
#ifndef AFFECT_BYTES_H
#define AFFECT_BYTES_H

#include "affect/base.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct affect_bw {
    unsigned char *data;
    size_t len, cap;
    bool failed;
} affect_bw;

void affect_bw_init(affect_bw *w);
void affect_bw_free(affect_bw *w);
void affect_bw_bytes(affect_bw *w, const void *p, size_t n);
void affect_bw_u8(affect_bw *w, uint8_t v);
void affect_bw_u32(affect_bw *w, uint32_t v);
void affect_bw_u64(affect_bw *w, uint64_t v);
void affect_bw_f64(affect_bw *w, double v);
void affect_bw_f64s(affect_bw *w, const double *v, size_t n);
void affect_bw_f32s(affect_bw *w, const float *v, size_t n);
/* n doubles written as float32 (each rounded to nearest; exact for float32 values). */
void affect_bw_f64s_as_f32(affect_bw *w, const double *v, size_t n);
void affect_bw_u32s(affect_bw *w, const uint32_t *v, size_t n);

typedef struct affect_br {
    const unsigned char *data;
    size_t size, off;
} affect_br;

void affect_br_init(affect_br *r, const unsigned char *data, size_t size);
/* Whether n more bytes are left (n counts elements of elem bytes each; overflow-safe). */
bool affect_br_has(const affect_br *r, size_t n, size_t elem);
/* A pointer to the next n bytes (borrowed from the input), advancing past them. */
bool affect_br_bytes(affect_br *r, const unsigned char **p, size_t n);
bool affect_br_u8(affect_br *r, uint8_t *v);
bool affect_br_u32(affect_br *r, uint32_t *v);
bool affect_br_u64(affect_br *r, uint64_t *v);
bool affect_br_f64(affect_br *r, double *v);
bool affect_br_f64s(affect_br *r, double *v, size_t n);
bool affect_br_f32s(affect_br *r, float *v, size_t n);
bool affect_br_u32s(affect_br *r, uint32_t *v, size_t n);

#ifdef __cplusplus
}
#endif

#endif
