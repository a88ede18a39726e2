/*
 * base.c — error records and the allocation hook (see affect/base.h).
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
        /* one line whatever the message quotes: control bytes become \xNN */
        static const char hex[] = "0123456789abcdef";
        size_t o = 0;
        for (const char *p = raw; *p && o + 1 < sizeof err->msg; p++) {
            unsigned char c = (unsigned char)*p;
            if (c >= 0x20 && c != 0x7f) {
                err->msg[o++] = (char)c;
            } else if (o + 5 < sizeof err->msg) {
                err->msg[o++] = '\\';
                err->msg[o++] = 'x';
                err->msg[o++] = hex[c >> 4];
                err->msg[o++] = hex[c & 15];
            } else {
                break;
            }
        }
        err->msg[o] = '\0';
        err->status = status;
    }
    return status;
}

affect_status affect_nomem(affect_error *err)
{
    return affect_fail(err, AFFECT_ERR_NOMEM, "out of memory");
}

void affect_error_clear(affect_error *err)
{
    if (err) {
        err->status = AFFECT_OK;
        err->msg[0] = '\0';
    }
}
