/*
 * strbuf.c — growable text buffer and locale-independent number formatting
 * (see util/strbuf.h).
 */
#include "util/strbuf.h"
#include "util/numparse.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

void affect_strbuf_init(affect_strbuf *sb)
{
    sb->data = NULL;
    sb->len = 0;
    sb->cap = 0;
    sb->failed = false;
}

void affect_strbuf_free(affect_strbuf *sb)
{
    affect_free(sb->data);
    affect_strbuf_init(sb);
}

static bool reserve(affect_strbuf *sb, size_t extra)
{
    size_t need;
    if (sb->failed)
        return false;
    if (!affect_add_size(sb->len, extra, &need) || !affect_add_size(need, 1, &need)) {
        sb->failed = true;
        return false;
    }
    if (need <= sb->cap)
        return true;
    size_t cap = sb->cap ? sb->cap : 256;
    while (cap < need) {
        if (cap > SIZE_MAX / 2) {
            cap = need;
            break;
        }
        cap *= 2;
    }
    char *p = affect_realloc(sb->data, cap);
    if (!p) {
        sb->failed = true;
        return false;
    }
    sb->data = p;
    sb->cap = cap;
    return true;
}

void affect_strbuf_append(affect_strbuf *sb, const char *s, size_t n)
{
    if (!reserve(sb, n))
        return;
    if (n)
        memcpy(sb->data + sb->len, s, n);
    sb->len += n;
    sb->data[sb->len] = '\0';
}

void affect_strbuf_puts(affect_strbuf *sb, const char *s)
{
    affect_strbuf_append(sb, s, strlen(s));
}

void affect_strbuf_putc(affect_strbuf *sb, char c)
{
    affect_strbuf_append(sb, &c, 1);
}

void affect_strbuf_printf(affect_strbuf *sb, const char *fmt, ...)
{
    char small[256];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(small, sizeof small, fmt, ap);
    va_end(ap);
    if (n < 0) {
        sb->failed = true;
        return;
    }
    if ((size_t)n < sizeof small) {
        affect_strbuf_append(sb, small, (size_t)n);
        return;
    }
    if (!reserve(sb, (size_t)n))
        return;
    va_start(ap, fmt);
    vsnprintf(sb->data + sb->len, (size_t)n + 1, fmt, ap);
    va_end(ap);
    sb->len += (size_t)n;
}

/* snprintf writes the locale's decimal point; rewrite whatever sits between the digits of the
 * integer and fraction parts as '.', so output never depends on LC_NUMERIC. */
int affect_format_g(char *buf, size_t size, int precision, double v)
{
    char raw[64];
    int n = snprintf(raw, sizeof raw, "%.*g", precision, v);
    if (n < 0 || (size_t)n >= sizeof raw) {
        if (size)
            buf[0] = '\0';
        return 0;
    }
    size_t o = 0;
    bool in_point = false;
    for (int i = 0; i < n && o + 1 < size; i++) {
        char c = raw[i];
        bool plain = (c >= '0' && c <= '9') || c == '-' || c == '+' || c == 'e' || c == 'E' ||
                     c == '.' || (c >= 'a' && c <= 'z');
        if (plain) {
            buf[o++] = c;
            in_point = false;
        } else if (!in_point) {
            buf[o++] = '.';
            in_point = true;
        }
    }
    buf[o] = '\0';
    return (int)o;
}

void affect_strbuf_float(affect_strbuf *sb, float v)
{
    char buf[64];
    if (!isfinite(v)) {
        affect_strbuf_puts(sb, "null");
        return;
    }
    int n = 0;
    for (int prec = 6; prec <= 9; prec++) {
        n = affect_format_g(buf, sizeof buf, prec, (double)v);
        double back = 0;
        if (affect_parse_double(buf, buf + n, &back) && (float)back == v)
            break;
    }
    affect_strbuf_append(sb, buf, (size_t)n);
}

void affect_strbuf_double(affect_strbuf *sb, double v)
{
    char buf[64];
    if (!isfinite(v)) {
        affect_strbuf_puts(sb, "null");
        return;
    }
    int n = 0;
    for (int prec = 15; prec <= 17; prec++) {
        n = affect_format_g(buf, sizeof buf, prec, v);
        double back = 0;
        if (affect_parse_double(buf, buf + n, &back) && back == v)
            break;
    }
    affect_strbuf_append(sb, buf, (size_t)n);
}

void affect_strbuf_fixed(affect_strbuf *sb, double v, int decimals)
{
    char raw[64], buf[64];
    if (!isfinite(v))
        v = 0;
    int n = snprintf(raw, sizeof raw, "%.*f", decimals, v);
    if (n < 0 || (size_t)n >= sizeof raw)
        return;
    size_t o = 0;
    for (int i = 0; i < n; i++) {
        char c = raw[i];
        buf[o++] = (c >= '0' && c <= '9') || c == '-' ? c : '.';
    }
    /* trim trailing zeros of the fraction and a dangling point */
    bool has_point = memchr(buf, '.', o) != NULL;
    while (has_point && o > 1 && buf[o - 1] == '0')
        o--;
    if (o > 1 && buf[o - 1] == '.')
        o--;
    if (o == 2 && buf[0] == '-' && buf[1] == '0')
        o = 1, buf[0] = '0';
    affect_strbuf_append(sb, buf, o);
}

void affect_strbuf_int(affect_strbuf *sb, long long v)
{
    affect_strbuf_printf(sb, "%lld", v);
}

void affect_strbuf_json_string(affect_strbuf *sb, const char *s)
{
    static const char hex[] = "0123456789abcdef";
    affect_strbuf_putc(sb, '"');
    const char *run = s;
    size_t left = strlen(s);
    for (const char *p = s; *p; p++, left--) {
        unsigned char c = (unsigned char)*p;
        if (c >= 0x80) { /* a valid sequence as it is; a byte that is not UTF-8 as U+FFFD */
            size_t k = affect_utf8_sequence((const unsigned char *)p, left);
            if (k > 0) {
                p += k - 1;
                left -= k - 1;
                continue;
            }
            affect_strbuf_append(sb, run, (size_t)(p - run));
            run = p + 1;
            affect_strbuf_puts(sb, "\\ufffd");
            continue;
        }
        if (c >= 0x20 && c != '"' && c != '\\')
            continue;
        affect_strbuf_append(sb, run, (size_t)(p - run));
        run = p + 1;
        switch (c) {
        case '"':
            affect_strbuf_puts(sb, "\\\"");
            break;
        case '\\':
            affect_strbuf_puts(sb, "\\\\");
            break;
        case '\n':
            affect_strbuf_puts(sb, "\\n");
            break;
        case '\r':
            affect_strbuf_puts(sb, "\\r");
            break;
        case '\t':
            affect_strbuf_puts(sb, "\\t");
            break;
        default: {
            char e[6] = {'\\', 'u', '0', '0', hex[c >> 4], hex[c & 15]};
            affect_strbuf_append(sb, e, 6);
        }
        }
    }
    affect_strbuf_puts(sb, run);
    affect_strbuf_putc(sb, '"');
}

void affect_strbuf_xml(affect_strbuf *sb, const char *s)
{
    const char *run = s;
    for (const char *p = s; *p; p++) {
        const char *rep = NULL;
        switch (*p) {
        case '&':
            rep = "&amp;";
            break;
        case '<':
            rep = "&lt;";
            break;
        case '>':
            rep = "&gt;";
            break;
        case '"':
            rep = "&quot;";
            break;
        case '\'':
            rep = "&#39;";
            break;
        default:
            if ((unsigned char)*p < 0x20 && *p != '\t' && *p != '\n')
                rep = "?";
        }
        if (!rep)
            continue;
        affect_strbuf_append(sb, run, (size_t)(p - run));
        affect_strbuf_puts(sb, rep);
        run = p + 1;
    }
    affect_strbuf_puts(sb, run);
}

affect_status affect_strbuf_finish(affect_strbuf *sb, char **out, size_t *len, affect_error *err)
{
    if (!sb->failed && !sb->data)
        reserve(sb, 0);
    if (sb->failed) {
        affect_strbuf_free(sb);
        return affect_nomem(err);
    }
    sb->data[sb->len] = '\0';
    *out = sb->data;
    if (len)
        *len = sb->len;
    affect_strbuf_init(sb);
    return AFFECT_OK;
}
