/*
 * json.c — a strict RFC 8259 JSON reader producing a read-only tree (see util/json.h).
 *
 * Usage:
 *     affect_json_doc *doc;
 *     if (affect_json_parse(text, len, &doc, NULL, &err) != AFFECT_OK) ... err.msg ...
 *     const affect_json_node *fps = affect_json_get(doc, affect_json_root(doc), "fps");
 *     affect_json_free(doc);
 *
 * What is accepted is exactly the RFC 8259 grammar: white space is space, tab, LF and CR only;
 * numbers are -?(0|[1-9][0-9]*)(.[0-9]+)?([eE][+-]?[0-9]+)? (no "+1", "01", ".5", "5.", "1e",
 * hex, NaN or Infinity); strings hold no raw control character, only the escapes \" \\ \/ \b
 * \f \n \r \t \uXXXX, surrogates only in valid \uD8xx\uDCxx pairs, and valid UTF-8 (no
 * overlong forms, no encoded surrogates, nothing above U+10FFFF). In addition, duplicate keys
 * in one object, nesting deeper than AFFECT_JSON_MAX_DEPTH and numbers beyond the double
 * range (1e999) are errors; a byte order mark is not skipped.
 *
 * Errors report the 0-based byte offset of the problem:
 *     at byte N: unexpected end of text          (N = the text's length)
 *     at byte N: expected a value
 *     at byte N: invalid literal                 (a word other than true, false, null)
 *     at byte N: invalid number                  (N = where the number starts)
 *     at byte N: number out of range             (overflows a double, e.g. 1e999)
 *     at byte N: control character in string
 *     at byte N: invalid escape                  (N = the backslash)
 *     at byte N: unpaired surrogate \uD800       (N = the backslash)
 *     at byte N: invalid UTF-8                   (N = the first byte of the bad sequence)
 *     at byte N: expected ',' or ']'   /  expected ',' or '}'
 *     at byte N: expected a key or '}' /  expected a key  /  expected ':'
 *     at byte N: duplicate key "k"               (N = the second key's opening quote)
 *     at byte N: nesting deeper than 64          (N = the opening bracket)
 *     at byte N: more than 2147483647 values
 *     at byte N: unexpected text after the value
 * Status: AFFECT_ERR_NOMEM, AFFECT_ERR_RANGE (depth, value count, number range) or
 * AFFECT_ERR_FORMAT (everything else).
 *
 * How it works: a recursive-descent parser (recursion is bounded by the depth limit) appends
 * nodes to one growable array owned by the document; containers link their children by index
 * (first, next), so pointers into the array are only handed out once parsing is over and stay
 * valid until affect_json_free. Decoded strings go to one arena allocated up front with
 * len + 1 bytes: a decoded string plus its NUL is never longer than its quoted source. Each
 * object being parsed keeps an open-addressing hash table of its keys (FNV-1a; inline for small
 * objects, on the heap beyond), so the duplicate check stays linear for big objects.
 */
#include "util/json.h"
#include "util/numparse.h"

#include <math.h>
#include <string.h>

/* Node indices are int32 (−1 = none), so at most INT32_MAX nodes (indices 0 .. INT32_MAX − 1). */
#define MAX_NODES ((size_t)INT32_MAX)
/* Hash slots kept in the parse_object frame before moving the table to the heap. */
#define INLINE_SLOTS 16u

struct affect_json_doc {
    affect_json_node *nodes;
    size_t n_nodes;
    size_t cap;
    char *arena; /* decoded strings, each NUL-terminated */
};

typedef struct parser {
    const char *text;
    size_t len;
    size_t pos;
    affect_json_doc *doc;
    size_t arena_used;
    affect_error *err;
    affect_monitor *mon; /* the caller's (may be NULL) */
} parser;

/* new_node polls the monitor every this many values */
#define POLL_NODES 16384

typedef struct key_slot {
    uint32_t hash;
    int32_t node; /* −1 when the slot is empty */
} key_slot;

static affect_status parse_value(parser *p, int depth, int32_t *out);

/* ---- helpers ---- */

static affect_status fail_at(parser *p, size_t pos, affect_status st, const char *what)
{
    return affect_fail(p->err, st, "at byte %zu: %s", pos, what);
}

static affect_status fail_eof(parser *p)
{
    return fail_at(p, p->len, AFFECT_ERR_FORMAT, "unexpected end of text");
}

static void skip_ws(parser *p)
{
    while (p->pos < p->len) {
        char c = p->text[p->pos];
        if (c != ' ' && c != '\t' && c != '\n' && c != '\r')
            break;
        p->pos++;
    }
}

static bool is_digit(char c)
{
    return c >= '0' && c <= '9';
}

static bool is_alpha(char c)
{
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z');
}

static int hex_value(char c)
{
    if (c >= '0' && c <= '9')
        return c - '0';
    if (c >= 'a' && c <= 'f')
        return c - 'a' + 10;
    if (c >= 'A' && c <= 'F')
        return c - 'A' + 10;
    return -1;
}

/* Appends a node of the given type and returns its index in *out. */
static affect_status new_node(parser *p, affect_json_type type, int32_t *out)
{
    affect_json_doc *d = p->doc;
    if (d->n_nodes % POLL_NODES == 0 && p->mon) {
        affect_status st = affect_monitor_check(p->mon, p->err);
        if (st)
            return st;
    }
    if (d->n_nodes >= MAX_NODES)
        return affect_fail(p->err, AFFECT_ERR_RANGE, "at byte %zu: more than %zu values", p->pos,
                           MAX_NODES);
    if (d->n_nodes == d->cap) {
        size_t cap = d->cap ? d->cap * 2 : 16, bytes;
        if (cap > MAX_NODES)
            cap = MAX_NODES;
        if (!affect_mul_size(cap, sizeof *d->nodes, &bytes))
            return affect_nomem(p->err);
        affect_json_node *nodes = affect_realloc(d->nodes, bytes);
        if (!nodes)
            return affect_nomem(p->err);
        d->nodes = nodes;
        d->cap = cap;
    }
    affect_json_node *n = &d->nodes[d->n_nodes];
    memset(n, 0, sizeof *n);
    n->type = type;
    n->first = -1;
    n->next = -1;
    *out = (int32_t)d->n_nodes++;
    return AFFECT_OK;
}

/* ---- strings ---- */

static size_t utf8_encode(uint32_t cp, char *out)
{
    if (cp < 0x80) {
        out[0] = (char)cp;
        return 1;
    }
    if (cp < 0x800) {
        out[0] = (char)(0xC0 | (cp >> 6));
        out[1] = (char)(0x80 | (cp & 0x3F));
        return 2;
    }
    if (cp < 0x10000) {
        out[0] = (char)(0xE0 | (cp >> 12));
        out[1] = (char)(0x80 | ((cp >> 6) & 0x3F));
        out[2] = (char)(0x80 | (cp & 0x3F));
        return 3;
    }
    out[0] = (char)(0xF0 | (cp >> 18));
    out[1] = (char)(0x80 | ((cp >> 12) & 0x3F));
    out[2] = (char)(0x80 | ((cp >> 6) & 0x3F));
    out[3] = (char)(0x80 | (cp & 0x3F));
    return 4;
}

/* Reads the 4 hex digits of a \u escape starting at text[at] (just after "\u"); −1 when they
 * are not 4 hex digits, −2 when the text ends first. */
static int32_t read_hex4(const parser *p, size_t at)
{
    int32_t v = 0;
    for (size_t i = 0; i < 4; i++) {
        if (at + i >= p->len)
            return -2;
        int h = hex_value(p->text[at + i]);
        if (h < 0)
            return -1;
        v = v * 16 + h;
    }
    return v;
}

/* Decodes the string whose opening quote is at p->pos into the arena. */
static affect_status parse_string(parser *p, const char **out, size_t *out_len)
{
    const unsigned char *t = (const unsigned char *)p->text;
    char *start = p->doc->arena + p->arena_used, *w = start;
    size_t i = p->pos + 1;
    for (;;) {
        size_t run = i;
        while (i < p->len && t[i] >= 0x20 && t[i] < 0x80 && t[i] != '"' && t[i] != '\\')
            i++;
        if (i > run) {
            memcpy(w, t + run, i - run);
            w += i - run;
        }
        if (i >= p->len) {
            p->pos = i;
            return fail_eof(p);
        }
        unsigned char c = t[i];
        if (c == '"')
            break;
        if (c < 0x20) {
            return fail_at(p, i, AFFECT_ERR_FORMAT, "control character in string");
        } else if (c >= 0x80) {
            size_t n = affect_utf8_sequence(t + i, p->len - i); /* base.h */
            if (n == 0)
                return fail_at(p, i, AFFECT_ERR_FORMAT, "invalid UTF-8");
            memcpy(w, t + i, n);
            w += n;
            i += n;
            continue;
        }
        /* a backslash */
        if (i + 1 >= p->len)
            return fail_eof(p);
        char e = (char)t[i + 1], simple = 0;
        switch (e) {
        case '"':
            simple = '"';
            break;
        case '\\':
            simple = '\\';
            break;
        case '/':
            simple = '/';
            break;
        case 'b':
            simple = '\b';
            break;
        case 'f':
            simple = '\f';
            break;
        case 'n':
            simple = '\n';
            break;
        case 'r':
            simple = '\r';
            break;
        case 't':
            simple = '\t';
            break;
        case 'u':
            break;
        default:
            return fail_at(p, i, AFFECT_ERR_FORMAT, "invalid escape");
        }
        if (simple) {
            *w++ = simple;
            i += 2;
            continue;
        }
        int32_t cp = read_hex4(p, i + 2);
        if (cp == -2)
            return fail_eof(p);
        if (cp < 0)
            return fail_at(p, i, AFFECT_ERR_FORMAT, "invalid escape");
        size_t esc = i;
        i += 6;
        if (cp >= 0xD800 && cp <= 0xDFFF) {
            int32_t lo = -1;
            if (cp <= 0xDBFF && i + 1 < p->len && t[i] == '\\' && t[i + 1] == 'u')
                lo = read_hex4(p, i + 2);
            if (lo < 0xDC00 || lo > 0xDFFF)
                return affect_fail(p->err, AFFECT_ERR_FORMAT,
                                   "at byte %zu: unpaired surrogate \\u%04X", esc, (unsigned)cp);
            cp = 0x10000 + ((cp - 0xD800) << 10) + (lo - 0xDC00);
            i += 6;
        }
        w += utf8_encode((uint32_t)cp, w);
    }
    *w = '\0';
    *out = start;
    *out_len = (size_t)(w - start);
    p->arena_used += *out_len + 1;
    p->pos = i + 1;
    return AFFECT_OK;
}

/* ---- numbers and literals ---- */

/* Length of the JSON number at the start of s[0..n), or 0 if s does not start with one. */
static size_t number_length(const char *s, size_t n)
{
    size_t i = 0;
    if (i < n && s[i] == '-')
        i++;
    if (i >= n || !is_digit(s[i]))
        return 0;
    if (s[i] == '0')
        i++;
    else
        while (i < n && is_digit(s[i]))
            i++;
    if (i < n && s[i] == '.') {
        i++;
        if (i >= n || !is_digit(s[i]))
            return 0;
        while (i < n && is_digit(s[i]))
            i++;
    }
    if (i < n && (s[i] == 'e' || s[i] == 'E')) {
        i++;
        if (i < n && (s[i] == '+' || s[i] == '-'))
            i++;
        if (i >= n || !is_digit(s[i]))
            return 0;
        while (i < n && is_digit(s[i]))
            i++;
    }
    return i;
}

/* A number token runs over every character that could continue a number or a word, so that
 * "01", "1.5.2" and "0x1F" are reported as one invalid number rather than as a number followed
 * by unexpected text. */
static affect_status parse_number(parser *p, affect_json_node *n)
{
    const char *s = p->text + p->pos;
    size_t tok = 0, avail = p->len - p->pos;
    while (tok < avail && (is_digit(s[tok]) || is_alpha(s[tok]) || s[tok] == '.' || s[tok] == '+' ||
                           s[tok] == '-'))
        tok++;
    if (number_length(s, tok) != tok)
        return fail_at(p, p->pos, AFFECT_ERR_FORMAT, "invalid number");
    double v;
    const char *end = affect_parse_double(s, s + tok, &v);
    if (!end || !isfinite(v))
        return fail_at(p, p->pos, AFFECT_ERR_RANGE, "number out of range");
    if (end != s + tok)
        return fail_at(p, p->pos, AFFECT_ERR_FORMAT, "invalid number");
    n->num = v;
    p->pos += tok;
    return AFFECT_OK;
}

static affect_status parse_literal(parser *p, affect_json_type *type)
{
    const char *s = p->text + p->pos;
    size_t tok = 0, avail = p->len - p->pos;
    while (tok < avail && (is_alpha(s[tok]) || is_digit(s[tok]) || s[tok] == '_'))
        tok++;
    if (tok == 4 && memcmp(s, "true", 4) == 0)
        *type = AFFECT_JSON_TRUE;
    else if (tok == 5 && memcmp(s, "false", 5) == 0)
        *type = AFFECT_JSON_FALSE;
    else if (tok == 4 && memcmp(s, "null", 4) == 0)
        *type = AFFECT_JSON_NULL;
    else
        return fail_at(p, p->pos, AFFECT_ERR_FORMAT, "invalid literal");
    p->pos += tok;
    return AFFECT_OK;
}

/* ---- containers ---- */

static affect_status check_depth(parser *p, int depth)
{
    if (depth > AFFECT_JSON_MAX_DEPTH)
        return affect_fail(p->err, AFFECT_ERR_RANGE, "at byte %zu: nesting deeper than %d", p->pos,
                           AFFECT_JSON_MAX_DEPTH);
    return AFFECT_OK;
}

/* Links child after prev (or as the first child of the container at index parent). */
static void link_child(parser *p, int32_t parent, int32_t *prev, int32_t child)
{
    affect_json_node *nodes = p->doc->nodes;
    if (*prev < 0)
        nodes[parent].first = child;
    else
        nodes[*prev].next = child;
    *prev = child;
    nodes[parent].count++;
}

/* Parses the array whose '[' is at p->pos into node self; depth is its nesting level (1 for a
 * root array). */
static affect_status parse_array(parser *p, int depth, int32_t self)
{
    affect_status st;
    int32_t prev = -1;
    p->pos++;
    skip_ws(p);
    if (p->pos < p->len && p->text[p->pos] == ']') {
        p->pos++;
        return AFFECT_OK;
    }
    for (;;) {
        int32_t child;
        st = parse_value(p, depth, &child);
        if (st)
            return st;
        link_child(p, self, &prev, child);
        skip_ws(p);
        if (p->pos >= p->len)
            return fail_eof(p);
        char c = p->text[p->pos];
        if (c == ']') {
            p->pos++;
            return AFFECT_OK;
        }
        if (c != ',')
            return fail_at(p, p->pos, AFFECT_ERR_FORMAT, "expected ',' or ']'");
        p->pos++;
    }
}

static uint32_t key_hash(const char *s, size_t n)
{
    uint32_t h = 2166136261u;
    for (size_t i = 0; i < n; i++)
        h = (h ^ (unsigned char)s[i]) * 16777619u;
    return h;
}

/* Writes key as a quoted, escaped, possibly shortened string for an error message. */
void affect_json_quote(char *buf, size_t size, const char *key, size_t len)
{
    static const char hex[] = "0123456789ABCDEF";
    size_t o = 0, limit = size - 6; /* room for "...\"" and the NUL */
    buf[o++] = '"';
    for (size_t i = 0; i < len; i++) {
        unsigned char c = (unsigned char)key[i];
        size_t need = c < 0x20 ? 6 : (c == '"' || c == '\\') ? 2 : 1;
        if (o + need > limit) {
            while (o > 1 && ((unsigned char)buf[o - 1] & 0xC0) == 0x80)
                o--; /* do not end in the middle of a UTF-8 sequence */
            if (o > 1 && (unsigned char)buf[o - 1] >= 0xC0)
                o--;
            memcpy(buf + o, "...", 3);
            o += 3;
            break;
        }
        if (c < 0x20) {
            char e[6] = {'\\', 'u', '0', '0', hex[c >> 4], hex[c & 15]};
            memcpy(buf + o, e, 6);
        } else if (need == 2) {
            buf[o] = '\\';
            buf[o + 1] = (char)c;
        } else
            buf[o] = (char)c;
        o += need;
    }
    buf[o++] = '"';
    buf[o] = '\0';
}

typedef struct key_table {
    key_slot inline_slots[INLINE_SLOTS];
    key_slot *slots;
    size_t cap; /* a power of two */
    size_t used;
} key_table;

static void table_init(key_table *kt)
{
    kt->slots = kt->inline_slots;
    kt->cap = INLINE_SLOTS;
    kt->used = 0;
    for (size_t i = 0; i < INLINE_SLOTS; i++)
        kt->slots[i].node = -1;
}

static void table_free(key_table *kt)
{
    if (kt->slots != kt->inline_slots)
        affect_free(kt->slots);
}

/* Keeps the load factor at most 1/2 for one more insertion. */
static affect_status table_reserve(parser *p, key_table *kt)
{
    if ((kt->used + 1) * 2 <= kt->cap)
        return AFFECT_OK;
    size_t cap;
    if (!affect_mul_size(kt->cap, 2, &cap))
        return affect_nomem(p->err);
    key_slot *slots = affect_malloc_array(cap, sizeof *slots);
    if (!slots)
        return affect_nomem(p->err);
    for (size_t i = 0; i < cap; i++)
        slots[i].node = -1;
    for (size_t i = 0; i < kt->cap; i++) {
        if (kt->slots[i].node < 0)
            continue;
        size_t h = kt->slots[i].hash & (cap - 1);
        while (slots[h].node >= 0)
            h = (h + 1) & (cap - 1);
        slots[h] = kt->slots[i];
    }
    table_free(kt);
    kt->slots = slots;
    kt->cap = cap;
    return AFFECT_OK;
}

/* Finds key in the table: returns the node holding it, or −1 with *slot set to the empty slot
 * where it belongs. */
static int32_t table_find(const parser *p, const key_table *kt, const char *key, size_t len,
                          uint32_t hash, size_t *slot)
{
    const affect_json_node *nodes = p->doc->nodes;
    size_t h = hash & (kt->cap - 1);
    while (kt->slots[h].node >= 0) {
        const affect_json_node *n = &nodes[kt->slots[h].node];
        if (kt->slots[h].hash == hash && n->key_len == len && memcmp(n->key, key, len) == 0)
            return kt->slots[h].node;
        h = (h + 1) & (kt->cap - 1);
    }
    *slot = h;
    return -1;
}

/* Parses the object whose '{' is at p->pos into node self, like parse_array. */
static affect_status parse_object(parser *p, int depth, int32_t self)
{
    affect_status st = AFFECT_OK;
    key_table kt;
    table_init(&kt);
    int32_t prev = -1;
    p->pos++;
    skip_ws(p);
    if (p->pos < p->len && p->text[p->pos] == '}') {
        p->pos++;
        goto done;
    }
    for (;;) {
        if (p->pos >= p->len) {
            st = fail_eof(p);
            goto done;
        }
        if (p->text[p->pos] != '"') {
            st = fail_at(p, p->pos, AFFECT_ERR_FORMAT,
                         prev < 0 ? "expected a key or '}'" : "expected a key");
            goto done;
        }
        size_t key_pos = p->pos, key_len;
        const char *key;
        st = parse_string(p, &key, &key_len);
        if (st)
            goto done;
        st = table_reserve(p, &kt);
        if (st)
            goto done;
        uint32_t hash = key_hash(key, key_len);
        size_t slot = 0;
        if (table_find(p, &kt, key, key_len, hash, &slot) >= 0) {
            char quoted[72];
            affect_json_quote(quoted, sizeof quoted, key, key_len);
            st = affect_fail(p->err, AFFECT_ERR_FORMAT, "at byte %zu: duplicate key %s", key_pos,
                             quoted);
            goto done;
        }
        skip_ws(p);
        if (p->pos >= p->len) {
            st = fail_eof(p);
            goto done;
        }
        if (p->text[p->pos] != ':') {
            st = fail_at(p, p->pos, AFFECT_ERR_FORMAT, "expected ':'");
            goto done;
        }
        p->pos++;
        int32_t child;
        st = parse_value(p, depth, &child);
        if (st)
            goto done;
        p->doc->nodes[child].key = key;
        p->doc->nodes[child].key_len = key_len;
        kt.slots[slot].hash = hash;
        kt.slots[slot].node = child;
        kt.used++;
        link_child(p, self, &prev, child);
        skip_ws(p);
        if (p->pos >= p->len) {
            st = fail_eof(p);
            goto done;
        }
        char c = p->text[p->pos];
        if (c == '}') {
            p->pos++;
            goto done;
        }
        if (c != ',') {
            st = fail_at(p, p->pos, AFFECT_ERR_FORMAT, "expected ',' or '}'");
            goto done;
        }
        p->pos++;
        skip_ws(p);
    }
done:
    table_free(&kt);
    return st;
}

/* Parses the value at p->pos (after white space) inside `depth` enclosing containers. */
static affect_status parse_value(parser *p, int depth, int32_t *out)
{
    skip_ws(p);
    if (p->pos >= p->len)
        return fail_eof(p);
    char c = p->text[p->pos];
    affect_json_type type = AFFECT_JSON_NULL;
    if (c == '{')
        type = AFFECT_JSON_OBJECT;
    else if (c == '[')
        type = AFFECT_JSON_ARRAY;
    else if (c == '"')
        type = AFFECT_JSON_STRING;
    else if (is_digit(c) || c == '-' || c == '+' || c == '.')
        type = AFFECT_JSON_NUMBER;
    else if (is_alpha(c)) {
        affect_status st = parse_literal(p, &type);
        if (st)
            return st;
        return new_node(p, type, out);
    } else
        return fail_at(p, p->pos, AFFECT_ERR_FORMAT, "expected a value");

    affect_status st;
    if (type == AFFECT_JSON_ARRAY || type == AFFECT_JSON_OBJECT) {
        st = check_depth(p, depth + 1);
        if (st)
            return st;
    }
    int32_t self;
    st = new_node(p, type, &self);
    if (st)
        return st;
    *out = self;
    switch (type) {
    case AFFECT_JSON_OBJECT:
        return parse_object(p, depth + 1, self);
    case AFFECT_JSON_ARRAY:
        return parse_array(p, depth + 1, self);
    case AFFECT_JSON_NUMBER:
        return parse_number(p, &p->doc->nodes[self]);
    default: {
        const char *s;
        size_t len;
        st = parse_string(p, &s, &len);
        if (st)
            return st;
        p->doc->nodes[self].str = s;
        p->doc->nodes[self].str_len = len;
        return AFFECT_OK;
    }
    }
}

/* ---- public API ---- */

affect_status affect_json_parse(const char *text, size_t len, affect_json_doc **out,
                                affect_monitor *mon, affect_error *err)
{
    *out = NULL;
    if (!text)
        len = 0;
    parser p = {text, len, 0, NULL, 0, err, mon};
    skip_ws(&p);
    if (p.pos >= len)
        return fail_eof(&p);
    size_t arena_size;
    if (!affect_add_size(len, 1, &arena_size))
        return affect_nomem(err);
    affect_json_doc *doc = affect_calloc(1, sizeof *doc);
    if (!doc)
        return affect_nomem(err);
    p.doc = doc;
    affect_status st;
    doc->arena = affect_malloc(arena_size);
    if (!doc->arena) {
        st = affect_nomem(err);
        goto fail;
    }
    int32_t root;
    st = parse_value(&p, 0, &root);
    if (st)
        goto fail;
    skip_ws(&p);
    if (p.pos < len) {
        st = fail_at(&p, p.pos, AFFECT_ERR_FORMAT, "unexpected text after the value");
        goto fail;
    }
    *out = doc;
    return AFFECT_OK;
fail:
    affect_json_free(doc);
    return st;
}

void affect_json_free(affect_json_doc *doc)
{
    if (!doc)
        return;
    affect_free(doc->nodes);
    affect_free(doc->arena);
    affect_free(doc);
}

const affect_json_node *affect_json_root(const affect_json_doc *doc)
{
    return doc && doc->n_nodes ? &doc->nodes[0] : NULL;
}

const affect_json_node *affect_json_first(const affect_json_doc *doc, const affect_json_node *n)
{
    if (!doc || !n || (n->type != AFFECT_JSON_ARRAY && n->type != AFFECT_JSON_OBJECT) ||
        n->first < 0)
        return NULL;
    return &doc->nodes[n->first];
}

const affect_json_node *affect_json_next_sibling(const affect_json_doc *doc,
                                                 const affect_json_node *n)
{
    if (!doc || !n || n->next < 0)
        return NULL;
    return &doc->nodes[n->next];
}

const affect_json_node *affect_json_child(const affect_json_doc *doc, const affect_json_node *n,
                                          uint32_t i)
{
    if (!n || i >= n->count)
        return NULL;
    const affect_json_node *c = affect_json_first(doc, n);
    while (c && i--)
        c = affect_json_next_sibling(doc, c);
    return c;
}

const affect_json_node *affect_json_get(const affect_json_doc *doc, const affect_json_node *obj,
                                        const char *key)
{
    if (!obj || obj->type != AFFECT_JSON_OBJECT || !key)
        return NULL;
    size_t len = strlen(key);
    for (const affect_json_node *c = affect_json_first(doc, obj); c;
         c = affect_json_next_sibling(doc, c))
        if (c->key_len == len && memcmp(c->key, key, len) == 0)
            return c;
    return NULL;
}

const char *affect_json_type_name(affect_json_type t)
{
    switch (t) {
    case AFFECT_JSON_NULL:
        return "null";
    case AFFECT_JSON_FALSE:
    case AFFECT_JSON_TRUE:
        return "boolean";
    case AFFECT_JSON_NUMBER:
        return "number";
    case AFFECT_JSON_STRING:
        return "string";
    case AFFECT_JSON_ARRAY:
        return "array";
    case AFFECT_JSON_OBJECT:
        return "object";
    }
    return "unknown";
}
