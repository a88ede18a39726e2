/*
 * affect/base.h — status codes, the error record, and the allocation hook shared by every
 * module of the core library.
 *
 * Usage:
 *     size_t n = ...;                                  // a count read from the input
 *     affect_error err;
 *     double *v = affect_malloc_array(n, sizeof *v);   // NULL on overflow or out of memory
 *     if (!v) {
 *         affect_nomem_of(&err, n, sizeof *v, "%zu values", n);   // "out of memory", or named
 *         puts(err.msg);
 *         return;
 *     }
 *     ...
 *     affect_free(v);
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
    AFFECT_ERR_NOMEM = 1,      /* an allocation failed */
    AFFECT_ERR_INVALID = 2,    /* a bad argument or option */
    AFFECT_ERR_FORMAT = 3,     /* malformed input data (text or BLOB) */
    AFFECT_ERR_RANGE = 4,      /* a size or index out of the supported range */
    AFFECT_ERR_MISSING = 5,    /* a needed body-part role or joint is absent */
    AFFECT_ERR_INTERRUPTED = 6 /* the caller asked the call to stop (affect/monitor.h) */
} affect_status;

#define AFFECT_ERROR_MSG_MAX 256

typedef struct affect_error {
    affect_status status;
    char msg[AFFECT_ERROR_MSG_MAX];
} affect_error;

/* Records a printf-style message (when err is not NULL) and returns status. The message is
 * kept on one line of valid UTF-8 whatever it quotes (affect_escape_text): control bytes (a
 * newline in a quoted joint name, say) and bytes that are not valid UTF-8 become \xNN. */
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

/* A failed request of at least this many bytes is reported by affect_nomem_of with what it was
 * for and how large it was; a smaller one is the plain "out of memory" (the process as a whole
 * is short of memory, as when SQLite fails its own allocations). 16 MiB is far above what an
 * ordinary call on a small input asks for in one block, and far below the sizes refused for
 * being large: SQLite refuses any single block of 2 GiB or more however much memory is free,
 * and a heap limit or a 32-bit address space refuse less. */
#define AFFECT_NOMEM_NAMED_MIN ((size_t)16 << 20)

/* Records the failure to allocate count elements of size bytes and returns AFFECT_ERR_NOMEM.
 * From AFFECT_NOMEM_NAMED_MIN bytes (or when count × size overflows) the message names the
 * request: "cannot allocate " + what (printf-style) + its size in binary units, as in "cannot
 * allocate the 560 x 95333 Fisher score block (407.3 MiB)"; below, it is affect_nomem's. The
 * SQLite glue raises a named failure as an error with its message and a plain one as
 * SQLITE_NOMEM. */
affect_status affect_nomem_of(affect_error *err, size_t count, size_t size, const char *what_fmt,
                              ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

/* Whether err records an allocation failure named by affect_nomem_of (AFFECT_ERR_NOMEM with a
 * message other than "out of memory"). */
bool affect_nomem_named(const affect_error *err);

/* Clears an error record. */
void affect_error_clear(affect_error *err);

/* ---- UTF-8 ----
 * Every name and label the library returns as text (joint names, class labels, feature
 * names) is valid UTF-8 without NUL bytes: the importers and BLOB decoders refuse anything
 * else, and every error message is valid UTF-8 (affect_fail escapes what is not). */

/* Length (1 to 4) of the valid UTF-8 sequence that starts at s[0], within the avail bytes
 * there, or 0 when none does: a NUL byte, a stray continuation byte, an overlong form, an
 * encoded surrogate (U+D800 .. U+DFFF), a code point above U+10FFFF, or a sequence cut short
 * (RFC 3629, table 3-7 of the Unicode standard). */
size_t affect_utf8_sequence(const unsigned char *s, size_t avail);

/* Offset of the first byte of s[0 .. n) that is not part of a valid sequence (see above), or n
 * when all of it is valid UTF-8 without NUL bytes. */
size_t affect_utf8_invalid_at(const char *s, size_t n);

/* Whether s[0 .. n) is valid UTF-8 without NUL bytes. */
bool affect_utf8_valid(const char *s, size_t n);

/* AFFECT_OK when s[0 .. n) is valid UTF-8 without NUL bytes; otherwise records "<what> is not
 * valid UTF-8 (byte 0xff at offset 2)", what being printf-style ("joint 3: name"), and returns
 * status. */
affect_status affect_utf8_check(affect_error *err, affect_status status, const char *s, size_t n,
                                const char *what_fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 5, 6)))
#endif
    ;

/* Copies the n bytes at src into dst (size ≥ 1 bytes, NUL-terminated) as one line of valid
 * UTF-8: a control byte, or a byte that is not part of a valid sequence, becomes the four
 * characters \xNN. The copy ends early rather than cut a sequence or an escape. Returns the
 * length written. Escaping escaped text changes nothing. */
size_t affect_escape_text(char *dst, size_t size, const char *src, size_t n);

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
