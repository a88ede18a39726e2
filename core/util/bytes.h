/*
 * util/bytes.h — little-endian binary encoding for the BLOB formats: a growable writer and a
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
 *
 * Headers and checksums: every format starts with 4 magic bytes and a version, and the
 * self-contained ones end with a checksum, the 64-bit FNV-1a hash of every byte before it
 * (docs/FORMATS.md). affect_check_magic and affect_check_version word their errors the same way
 * for every format, so that a user meets one message whatever BLOB is wrong:
 *     not a model (bad magic bytes at offset 0)
 *     unknown format version 3 (this build reads 1 .. 2)
 * (a record embedded in another BLOB puts its name in front: "sPCA: unknown format version …").
 * affect_bw_header / affect_br_header write and read the common layout of the newer formats:
 * magic, uint32 version, uint32 flags.
 */
#ifndef AFFECT_BYTES_H
#define AFFECT_BYTES_H

#include "affect/base.h"

#include <string.h>

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
void affect_bw_u16(affect_bw *w, uint16_t v);
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
bool affect_br_u16(affect_br *r, uint16_t *v);
bool affect_br_u32(affect_br *r, uint32_t *v);
bool affect_br_u64(affect_br *r, uint64_t *v);
bool affect_br_f64(affect_br *r, double *v);
bool affect_br_f64s(affect_br *r, double *v, size_t n);
bool affect_br_f32s(affect_br *r, float *v, size_t n);
bool affect_br_u32s(affect_br *r, uint32_t *v, size_t n);

/* Little-endian loads and stores at a pointer the caller has bounds-checked (fixed-size headers
 * and pre-sized buffers; inline: the motion decoder calls them per coordinate). */
static inline void affect_put_u16(unsigned char *p, uint16_t v)
{
    p[0] = (unsigned char)v;
    p[1] = (unsigned char)(v >> 8);
}

static inline void affect_put_u32(unsigned char *p, uint32_t v)
{
    for (int i = 0; i < 4; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}

static inline void affect_put_u64(unsigned char *p, uint64_t v)
{
    for (int i = 0; i < 8; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}

static inline void affect_put_f64(unsigned char *p, double d)
{
    uint64_t u;
    memcpy(&u, &d, sizeof u);
    affect_put_u64(p, u);
}

static inline uint16_t affect_get_u16(const unsigned char *p)
{
    return (uint16_t)(p[0] | (p[1] << 8));
}

static inline uint32_t affect_get_u32(const unsigned char *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

static inline uint64_t affect_get_u64(const unsigned char *p)
{
    uint64_t v = 0;
    for (int i = 7; i >= 0; i--)
        v = (v << 8) | p[i];
    return v;
}

static inline double affect_get_f64(const unsigned char *p)
{
    uint64_t u = affect_get_u64(p);
    double d;
    memcpy(&d, &u, sizeof d);
    return d;
}

/* ---- headers and checksums ---- */

/* AFFECT_ERR_FORMAT "<prefix>not <what> (bad magic bytes at offset <off>)" unless the 4 bytes
 * at p are magic; what has its article ("a model"), prefix may be NULL (""), off is where p is
 * in the caller's BLOB. */
affect_status affect_check_magic(const unsigned char *p, const char magic[4], const char *prefix,
                                 const char *what, size_t off, affect_error *err);

/* AFFECT_ERR_FORMAT "<prefix>unknown format version <v> (this build reads 1 .. <newest>)" unless
 * 1 ≤ version ≤ newest; prefix may be NULL. The one wording of every format's version error. */
affect_status affect_check_version(uint32_t version, uint32_t newest, const char *prefix,
                                   affect_error *err);

/* Named fields of the records that report where they are truncated (SVM, RMLR):
 * AFFECT_ERR_FORMAT "<prefix>truncated in <field> (offset <off>)". affect_br_need fails so
 * unless n elements of elem bytes are left (at r's offset); the reads fail so, reading
 * nothing, when their value is not all there. */
affect_status affect_fail_truncated(affect_error *err, const char *prefix, const char *field,
                                    size_t off);
affect_status affect_br_need(const affect_br *r, size_t n, size_t elem, const char *prefix,
                             const char *field, affect_error *err);
affect_status affect_br_u32_field(affect_br *r, uint32_t *v, const char *prefix, const char *field,
                                  affect_error *err);
affect_status affect_br_f64_field(affect_br *r, double *v, const char *prefix, const char *field,
                                  affect_error *err);

/* Appends magic, version (uint32) and flags (uint32). */
void affect_bw_header(affect_bw *w, const char magic[4], uint32_t version, uint32_t flags);

/* Reads what affect_bw_header wrote and checks the magic and 1 ≤ version ≤ newest, with the
 * messages above ("<prefix>truncated: <n> bytes is shorter than the 12-byte header" when fewer
 * than 12 bytes are left); the flags are returned unchecked. Nothing is consumed on failure. */
affect_status affect_br_header(affect_br *r, const char magic[4], uint32_t newest,
                               const char *prefix, const char *what, uint32_t *version,
                               uint32_t *flags, affect_error *err);

/* Appends the checksum of the bytes written since offset start (FNV-1a 64 of w->data[start ..
 * w->len)). */
void affect_bw_checksum(affect_bw *w, size_t start);

/* Whether the 8 bytes at data + n hold the FNV-1a 64 hash of data[0 .. n). */
bool affect_checksum_ok(const unsigned char *data, size_t n);

#ifdef __cplusplus
}
#endif

#endif
