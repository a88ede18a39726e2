/*
 * base.c — error records, the allocation hook and the UTF-8 checks (see affect/base.h).
 */
#include "affect/base.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void *libc_malloc(size_t n)
{
    return malloc(n);
}

static void *libc_realloc(void *p, size_t n)
{
    return realloc(p, n);
}

static void libc_free(void *p)
{
    free(p);
}

static affect_allocator current_allocator = {libc_malloc, libc_realloc, libc_free};

void affect_set_allocator(const affect_allocator *allocator)
{
    if (allocator && allocator->malloc_fn && allocator->realloc_fn && allocator->free_fn)
        current_allocator = *allocator;
    else {
        current_allocator.malloc_fn = libc_malloc;
        current_allocator.realloc_fn = libc_realloc;
        current_allocator.free_fn = libc_free;
    }
}

void *affect_malloc(size_t n)
{
    return current_allocator.malloc_fn(n ? n : 1);
}

void *affect_realloc(void *p, size_t n)
{
    if (!p)
        return affect_malloc(n);
    return current_allocator.realloc_fn(p, n ? n : 1);
}

void affect_free(void *p)
{
    if (p)
        current_allocator.free_fn(p);
}

void *affect_malloc_array(size_t n, size_t size)
{
    size_t total;
    if (!affect_mul_size(n, size, &total))
        return NULL;
    return affect_malloc(total);
}

void *affect_calloc(size_t n, size_t size)
{
    size_t total;
    if (!affect_mul_size(n, size, &total))
        return NULL;
    void *p = affect_malloc(total);
    if (p)
        memset(p, 0, total);
    return p;
}

char *affect_strndup(const char *s, size_t n)
{
    if (n == SIZE_MAX)
        return NULL;
    char *d = affect_malloc(n + 1);
    if (!d)
        return NULL;
    if (n)
        memcpy(d, s, n);
    d[n] = '\0';
    return d;
}

affect_status affect_prefix(affect_error *err, const char *fmt, ...)
{
    if (!err || err->status == AFFECT_ERR_NOMEM)
        return err ? err->status : AFFECT_ERR_INVALID;
    char msg[AFFECT_ERROR_MSG_MAX], head[AFFECT_ERROR_MSG_MAX];
    memcpy(msg, err->msg, sizeof msg);
    msg[sizeof msg - 1] = '\0';
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(head, sizeof head, fmt, ap);
    va_end(ap);
    return affect_fail(err, err->status, "%s: %s", head, msg);
}

affect_status affect_fail(affect_error *err, affect_status status, const char *fmt, ...)
{
    if (err) {
        char raw[AFFECT_ERROR_MSG_MAX];
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(raw, sizeof raw, fmt, ap);
        va_end(ap);
        /* one line of valid UTF-8 whatever the message quotes */
        affect_escape_text(err->msg, sizeof err->msg, raw, strlen(raw));
        err->status = status;
    }
    return status;
}

size_t affect_utf8_sequence(const unsigned char *s, size_t avail)
{
    if (avail == 0)
        return 0;
    unsigned char c = s[0];
    if (c < 0x80)
        return c != 0;
    size_t n;
    unsigned char lo = 0x80, hi = 0xBF; /* range of the second byte */
    if (c >= 0xC2 && c <= 0xDF) {
        n = 2;
    } else if (c >= 0xE0 && c <= 0xEF) {
        n = 3;
        if (c == 0xE0)
            lo = 0xA0; /* overlong below U+0800 */
        else if (c == 0xED)
            hi = 0x9F; /* surrogates */
    } else if (c >= 0xF0 && c <= 0xF4) {
        n = 4;
        if (c == 0xF0)
            lo = 0x90; /* overlong below U+10000 */
        else if (c == 0xF4)
            hi = 0x8F; /* above U+10FFFF */
    } else {
        return 0; /* a continuation byte, C0/C1 (overlong) or F5..FF */
    }
    if (avail < n || s[1] < lo || s[1] > hi)
        return 0;
    for (size_t i = 2; i < n; i++)
        if (s[i] < 0x80 || s[i] > 0xBF)
            return 0;
    return n;
}

size_t affect_utf8_invalid_at(const char *s, size_t n)
{
    const unsigned char *u = (const unsigned char *)s;
    size_t i = 0;
    while (i < n) {
        if (u[i] >= 0x01 && u[i] < 0x80) { /* the common case */
            i++;
            continue;
        }
        size_t k = affect_utf8_sequence(u + i, n - i);
        if (k == 0)
            return i;
        i += k;
    }
    return n;
}

bool affect_utf8_valid(const char *s, size_t n)
{
    return affect_utf8_invalid_at(s, n) == n;
}

affect_status affect_utf8_check(affect_error *err, affect_status status, const char *s, size_t n,
                                const char *what_fmt, ...)
{
    size_t at = affect_utf8_invalid_at(s, n);
    if (at == n)
        return AFFECT_OK;
    if (!err)
        return status;
    char what[AFFECT_ERROR_MSG_MAX];
    va_list ap;
    va_start(ap, what_fmt);
    vsnprintf(what, sizeof what, what_fmt, ap);
    va_end(ap);
    return affect_fail(err, status, "%s is not valid UTF-8 (byte 0x%02x at offset %zu)", what,
                       (unsigned char)s[at], at);
}

size_t affect_escape_text(char *dst, size_t size, const char *src, size_t n)
{
    static const char hex[] = "0123456789abcdef";
    const unsigned char *s = (const unsigned char *)src;
    size_t o = 0, i = 0;
    while (i < n) {
        unsigned char c = s[i];
        size_t k = c >= 0x20 && c != 0x7f ? affect_utf8_sequence(s + i, n - i) : 0;
        if (k) {
            if (o + k >= size)
                break;
            memcpy(dst + o, s + i, k);
            o += k;
            i += k;
        } else {
            if (o + 4 >= size)
                break;
            dst[o++] = '\\';
            dst[o++] = 'x';
            dst[o++] = hex[c >> 4];
            dst[o++] = hex[c & 15];
            i++;
        }
    }
    dst[o] = '\0';
    return o;
}

affect_status affect_nomem(affect_error *err)
{
    return affect_fail(err, AFFECT_ERR_NOMEM, "out of memory");
}

affect_status affect_nomem_of(affect_error *err, size_t count, size_t size, const char *what_fmt,
                              ...)
{
    size_t bytes;
    bool overflow = !affect_mul_size(count, size, &bytes);
    if (!overflow && bytes < AFFECT_NOMEM_NAMED_MIN)
        return affect_nomem(err);
    if (!err)
        return AFFECT_ERR_NOMEM;
    char what[AFFECT_ERROR_MSG_MAX];
    va_list ap;
    va_start(ap, what_fmt);
    vsnprintf(what, sizeof what, what_fmt, ap);
    va_end(ap);
    double b = (double)count * (double)size; /* exact enough for a message, even on overflow */
    static const char *const units[] = {"MiB", "GiB", "TiB", "PiB", "EiB"};
    int u = 0;
    b /= 1048576.0;
    while (b >= 1024.0 && u < 4) {
        b /= 1024.0;
        u++;
    }
    return affect_fail(err, AFFECT_ERR_NOMEM, "cannot allocate %s (%.1f %s)", what, b, units[u]);
}

bool affect_nomem_named(const affect_error *err)
{
    return err && err->status == AFFECT_ERR_NOMEM && err->msg[0] &&
           strcmp(err->msg, "out of memory") != 0;
}

void affect_error_clear(affect_error *err)
{
    if (err) {
        err->status = AFFECT_OK;
        err->msg[0] = '\0';
    }
}
