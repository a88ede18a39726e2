/*
 * bytes.c — little-endian writer and bounds-checked reader for the BLOB formats (see
 * util/bytes.h). The writer doubles its buffer (at least 256 bytes) and records the first
 * allocation failure; the reader checks the remaining length before every read.
 */
#include "util/bytes.h"

#include "affect/hmm_blob.h" /* affect_fnv1a64 */

#include <string.h>

void affect_bw_init(affect_bw *w)
{
    memset(w, 0, sizeof *w);
}

void affect_bw_free(affect_bw *w)
{
    affect_free(w->data);
    affect_bw_init(w);
}

/* Room for n more bytes; false (and failed) when it cannot be made. */
static bool reserve(affect_bw *w, size_t n)
{
    if (w->failed)
        return false;
    size_t need;
    if (!affect_add_size(w->len, n, &need)) {
        w->failed = true;
        return false;
    }
    if (need <= w->cap)
        return true;
    size_t cap = w->cap < 128 ? 256 : w->cap;
    while (cap < need)
        if (!affect_mul_size(cap, 2, &cap)) {
            cap = need;
            break;
        }
    unsigned char *p = affect_realloc(w->data, cap);
    if (!p) {
        w->failed = true;
        return false;
    }
    w->data = p;
    w->cap = cap;
    return true;
}

void affect_bw_bytes(affect_bw *w, const void *p, size_t n)
{
    if (n == 0 || !reserve(w, n))
        return;
    memcpy(w->data + w->len, p, n);
    w->len += n;
}

static void put_le(affect_bw *w, uint64_t v, unsigned bytes)
{
    if (!reserve(w, bytes))
        return;
    for (unsigned i = 0; i < bytes; i++)
        w->data[w->len++] = (unsigned char)(v >> (8 * i));
}

void affect_bw_u8(affect_bw *w, uint8_t v)
{
    put_le(w, v, 1);
}

void affect_bw_u16(affect_bw *w, uint16_t v)
{
    put_le(w, v, 2);
}

void affect_bw_u32(affect_bw *w, uint32_t v)
{
    put_le(w, v, 4);
}

void affect_bw_u64(affect_bw *w, uint64_t v)
{
    put_le(w, v, 8);
}

void affect_bw_f64(affect_bw *w, double v)
{
    uint64_t u;
    memcpy(&u, &v, sizeof u);
    put_le(w, u, 8);
}

void affect_bw_f64s(affect_bw *w, const double *v, size_t n)
{
    size_t bytes;
    if (!affect_mul_size(n, 8, &bytes)) {
        w->failed = true;
        return;
    }
    if (!reserve(w, bytes))
        return;
    for (size_t i = 0; i < n; i++)
        affect_bw_f64(w, v[i]);
}

void affect_bw_f32s(affect_bw *w, const float *v, size_t n)
{
    size_t bytes;
    if (!affect_mul_size(n, 4, &bytes)) {
        w->failed = true;
        return;
    }
    if (!reserve(w, bytes))
        return;
    for (size_t i = 0; i < n; i++) {
        uint32_t u;
        memcpy(&u, &v[i], sizeof u);
        put_le(w, u, 4);
    }
}

void affect_bw_f64s_as_f32(affect_bw *w, const double *v, size_t n)
{
    size_t bytes;
    if (!affect_mul_size(n, 4, &bytes)) {
        w->failed = true;
        return;
    }
    if (!reserve(w, bytes))
        return;
    for (size_t i = 0; i < n; i++) {
        float f = (float)v[i];
        uint32_t u;
        memcpy(&u, &f, sizeof u);
        put_le(w, u, 4);
    }
}

void affect_bw_u32s(affect_bw *w, const uint32_t *v, size_t n)
{
    size_t bytes;
    if (!affect_mul_size(n, 4, &bytes)) {
        w->failed = true;
        return;
    }
    if (!reserve(w, bytes))
        return;
    for (size_t i = 0; i < n; i++)
        put_le(w, v[i], 4);
}

void affect_br_init(affect_br *r, const unsigned char *data, size_t size)
{
    r->data = data;
    r->size = size;
    r->off = 0;
}

bool affect_br_has(const affect_br *r, size_t n, size_t elem)
{
    size_t bytes;
    return affect_mul_size(n, elem, &bytes) && bytes <= r->size - r->off;
}

bool affect_br_bytes(affect_br *r, const unsigned char **p, size_t n)
{
    if (!affect_br_has(r, n, 1))
        return false;
    *p = r->data + r->off;
    r->off += n;
    return true;
}

static uint64_t get_le(affect_br *r, unsigned bytes)
{
    uint64_t v = 0;
    for (unsigned i = 0; i < bytes; i++)
        v |= (uint64_t)r->data[r->off + i] << (8 * i);
    r->off += bytes;
    return v;
}

bool affect_br_u8(affect_br *r, uint8_t *v)
{
    if (!affect_br_has(r, 1, 1))
        return false;
    *v = (uint8_t)get_le(r, 1);
    return true;
}

bool affect_br_u16(affect_br *r, uint16_t *v)
{
    if (!affect_br_has(r, 1, 2))
        return false;
    *v = (uint16_t)get_le(r, 2);
    return true;
}

bool affect_br_u32(affect_br *r, uint32_t *v)
{
    if (!affect_br_has(r, 1, 4))
        return false;
    *v = (uint32_t)get_le(r, 4);
    return true;
}

bool affect_br_u64(affect_br *r, uint64_t *v)
{
    if (!affect_br_has(r, 1, 8))
        return false;
    *v = get_le(r, 8);
    return true;
}

bool affect_br_f64(affect_br *r, double *v)
{
    if (!affect_br_has(r, 1, 8))
        return false;
    uint64_t u = get_le(r, 8);
    memcpy(v, &u, sizeof *v);
    return true;
}

bool affect_br_f64s(affect_br *r, double *v, size_t n)
{
    if (!affect_br_has(r, n, 8))
        return false;
    for (size_t i = 0; i < n; i++) {
        uint64_t u = get_le(r, 8);
        memcpy(&v[i], &u, sizeof u);
    }
    return true;
}

bool affect_br_f32s(affect_br *r, float *v, size_t n)
{
    if (!affect_br_has(r, n, 4))
        return false;
    for (size_t i = 0; i < n; i++) {
        uint32_t u = (uint32_t)get_le(r, 4);
        memcpy(&v[i], &u, sizeof u);
    }
    return true;
}

bool affect_br_u32s(affect_br *r, uint32_t *v, size_t n)
{
    if (!affect_br_has(r, n, 4))
        return false;
    for (size_t i = 0; i < n; i++)
        v[i] = (uint32_t)get_le(r, 4);
    return true;
}

/* ---- headers and checksums ---- */

affect_status affect_check_magic(const unsigned char *p, const char magic[4], const char *prefix,
                                 const char *what, size_t off, affect_error *err)
{
    if (memcmp(p, magic, 4) == 0)
        return AFFECT_OK;
    return affect_fail(err, AFFECT_ERR_FORMAT, "%snot %s (bad magic bytes at offset %zu)",
                       prefix ? prefix : "", what, off);
}

affect_status affect_check_version(uint32_t version, uint32_t newest, const char *prefix,
                                   affect_error *err)
{
    if (version >= 1 && version <= newest)
        return AFFECT_OK;
    return affect_fail(err, AFFECT_ERR_FORMAT,
                       "%sunknown format version %u (this build reads 1 .. %u)",
                       prefix ? prefix : "", (unsigned)version, (unsigned)newest);
}

affect_status affect_fail_truncated(affect_error *err, const char *prefix, const char *field,
                                    size_t off)
{
    return affect_fail(err, AFFECT_ERR_FORMAT, "%struncated in %s (offset %zu)",
                       prefix ? prefix : "", field, off);
}

affect_status affect_br_need(const affect_br *r, size_t n, size_t elem, const char *prefix,
                             const char *field, affect_error *err)
{
    return affect_br_has(r, n, elem) ? AFFECT_OK
                                     : affect_fail_truncated(err, prefix, field, r->off);
}

affect_status affect_br_u32_field(affect_br *r, uint32_t *v, const char *prefix, const char *field,
                                  affect_error *err)
{
    return affect_br_u32(r, v) ? AFFECT_OK : affect_fail_truncated(err, prefix, field, r->off);
}

affect_status affect_br_f64_field(affect_br *r, double *v, const char *prefix, const char *field,
                                  affect_error *err)
{
    return affect_br_f64(r, v) ? AFFECT_OK : affect_fail_truncated(err, prefix, field, r->off);
}

void affect_bw_header(affect_bw *w, const char magic[4], uint32_t version, uint32_t flags)
{
    affect_bw_bytes(w, magic, 4);
    affect_bw_u32(w, version);
    affect_bw_u32(w, flags);
}

affect_status affect_br_header(affect_br *r, const char magic[4], uint32_t newest,
                               const char *prefix, const char *what, uint32_t *version,
                               uint32_t *flags, affect_error *err)
{
    affect_status st;
    if (!affect_br_has(r, 12, 1))
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "%struncated: %zu bytes is shorter than the 12-byte header",
                           prefix ? prefix : "", r->size - r->off);
    const unsigned char *p = r->data + r->off;
    if ((st = affect_check_magic(p, magic, prefix, what, r->off, err)) != AFFECT_OK)
        return st;
    uint32_t v = affect_get_u32(p + 4);
    if ((st = affect_check_version(v, newest, prefix, err)) != AFFECT_OK)
        return st;
    *version = v;
    *flags = affect_get_u32(p + 8);
    r->off += 12;
    return AFFECT_OK;
}

void affect_bw_checksum(affect_bw *w, size_t start)
{
    if (w->failed || start > w->len)
        return;
    affect_bw_u64(w, affect_fnv1a64(w->data + start, w->len - start));
}

bool affect_checksum_ok(const unsigned char *data, size_t n)
{
    return affect_get_u64(data + n) == affect_fnv1a64(data, n);
}
