/*
 * affect/base.h — status codes, the error record, and the allocation hook shared by every
 * module of the core library.
 *
 * Every core function that can fail returns an affect_status and, when given a non-NULL
 * affect_error, writes a one-line message into it ("line 57: expected CHANNELS, found
 * CHANELS"). The SQLite glue prefixes the SQL function name.
 *
 * All memory is obtained through affect_malloc/affect_realloc/affect_free. By default they
 * call the C library; affect_set_allocator() reroutes them (the SQLite extension routes them
 * to the database engine's allocator, so that its memory accounting and fault injection see
 * every allocation).
 * The allocator is the one process-wide setting of the library: set it once, before use.
 */
#ifndef AFFECT_BASE_H
#define AFFECT_BASE_H

#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef enum affect_status {
    AFFECT_OK = 0,
    AFFECT_ERR_NOMEM = 1,   /* an allocation failed */
    AFFECT_ERR_INVALID = 2, /* a bad argument or option */
    AFFECT_ERR_FORMAT = 3,  /* malformed input data (text or BLOB) */
    AFFECT_ERR_RANGE = 4,   /* a size or index out of the supported range */
    AFFECT_ERR_MISSING = 5  /* a needed body-part role or joint is absent */
} affect_status;

#define AFFECT_ERROR_MSG_MAX 256

typedef struct affect_error {
    affect_status status;
    char msg[AFFECT_ERROR_MSG_MAX];
} affect_error;

/* Records a printf-style message (when err is not NULL) and returns status. The message is
 * kept on one line: control bytes (a newline in a quoted joint name, say) become \xNN. */
affect_status affect_fail(affect_error *err, affect_status status, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* Prefixes err's message with a printf-style context and ": " ("desired motion: …"), keeping
 * its status, which it returns; "out of memory" is left as it is. */
affect_status affect_prefix(affect_error *err, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* Records "out of memory" and returns AFFECT_ERR_NOMEM. */
affect_status affect_nomem(affect_error *err);

/* Clears an error record. */
void affect_error_clear(affect_error *err);

typedef struct affect_allocator {
    void *(*malloc_fn)(size_t n);
    void *(*realloc_fn)(void *p, size_t n);
    void (*free_fn)(void *p);
} affect_allocator;

/* Replaces the allocator; NULL restores the C library's. Not thread-safe: call it once,
 * before any other function of the library runs. */
void affect_set_allocator(const affect_allocator *allocator);

/* affect_malloc(0) returns a valid unique pointer (never NULL on success). */
void *affect_malloc(size_t n);
void *affect_realloc(void *p, size_t n);
void affect_free(void *p);

/* Zeroed array of n elements of size bytes; NULL on overflow or failure. */
void *affect_calloc(size_t n, size_t size);
/* Uninitialised array of n elements of size bytes; NULL on overflow or failure. */
void *affect_malloc_array(size_t n, size_t size);
/* Copy of the first n bytes of s with a terminating NUL; NULL on failure. */
char *affect_strndup(const char *s, size_t n);

/* a * b into *out; returns false (and leaves *out alone) on overflow. */
static inline bool affect_mul_size(size_t a, size_t b, size_t *out)
{
    if (a != 0 && b > SIZE_MAX / a)
        return false;
    *out = a * b;
    return true;
}

/* a + b into *out; returns false on overflow. */
static inline bool affect_add_size(size_t a, size_t b, size_t *out)
{
    if (b > SIZE_MAX - a)
        return false;
    *out = a + b;
    return true;
}

#ifdef __cplusplus
}
#endif
#endif
