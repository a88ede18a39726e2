/*
 * util/strbuf.h — a growable text buffer for the writers (JSON, CSV, SVG).
 *
 * Appends never fail visibly: the first allocation failure sets sb->failed and later appends
 * do nothing, so a writer appends freely and checks once at the end (affect_strbuf_finish).
 * Numbers are formatted independently of the process locale ('.' is always the decimal point).
 */
#ifndef AFFECT_STRBUF_H
#define AFFECT_STRBUF_H

#include "affect/base.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct affect_strbuf {
    char *data; /* NUL-terminated when len > 0 or after finish */
    size_t len;
    size_t cap;
    bool failed; /* an allocation failed; the content is incomplete */
} affect_strbuf;

void affect_strbuf_init(affect_strbuf *sb);
void affect_strbuf_free(affect_strbuf *sb);
void affect_strbuf_append(affect_strbuf *sb, const char *s, size_t n);
void affect_strbuf_puts(affect_strbuf *sb, const char *s);
void affect_strbuf_putc(affect_strbuf *sb, char c);
void affect_strbuf_printf(affect_strbuf *sb, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
/* Shortest decimal that reads back as the same float (at most 9 significant digits). */
void affect_strbuf_float(affect_strbuf *sb, float v);
/* Shortest decimal that reads back as the same double (at most 17 significant digits).
 * Non-finite values are written as null (JSON has no inf or nan). */
void affect_strbuf_double(affect_strbuf *sb, double v);
/* Fixed-point with `decimals` digits after the point (SVG coordinates). */
void affect_strbuf_fixed(affect_strbuf *sb, double v, int decimals);
void affect_strbuf_int(affect_strbuf *sb, long long v);
/* A JSON string literal with quotes and escapes; a byte that is not part of valid UTF-8 becomes
 * \ufffd (labels read from tables may be any bytes; JSON text must be Unicode). */
void affect_strbuf_json_string(affect_strbuf *sb, const char *s);
/* Text escaped for XML content and attribute values (& < > " '). */
void affect_strbuf_xml(affect_strbuf *sb, const char *s);

/* Hands over the NUL-terminated text (free with affect_free) and its length, resetting sb;
 * returns AFFECT_ERR_NOMEM (and frees) if any append failed. */
affect_status affect_strbuf_finish(affect_strbuf *sb, char **out, size_t *len, affect_error *err);

/* Formats a double like "%.*g" into buf (size ≥ 32) with '.' as decimal point whatever the
 * locale; returns the length. */
int affect_format_g(char *buf, size_t size, int precision, double v);

#ifdef __cplusplus
}
#endif
#endif
