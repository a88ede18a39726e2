/*
 * fuzz_json.c — libFuzzer target for the JSON reader (affect_json_parse, util/json.h) and
 * the JSON motion importer built on it (affect_motion_from_json, affect/io.h).
 *
 * Usage (see tests/fuzz/run.sh, or build with -DAFFECT_FUZZ=ON and clang):
 *     build-fuzz/tests/fuzz/fuzz_json -max_total_time=60 <a copy of tests/fuzz/corpus/fuzz_json>
 *
 * Every input (not NUL-terminated) goes to both functions. Checks beyond "no crash, no leak,
 * no undefined behaviour":
 *   - on failure: a status other than AFFECT_OK, recorded in the error with a non-empty
 *     message, and nothing handed out;
 *   - a parsed document is walked completely: each container's count matches its children,
 *     affect_json_child agrees with the sibling links, each object member is found again by
 *     affect_json_get under its key, and every decoded string and key is NUL-terminated at
 *     its length and is valid UTF-8 (the reader decodes escapes into UTF-8 and refuses
 *     invalid input, so it can never produce an invalid sequence);
 *   - a motion read from JSON validates, and to_json → from_json gives back a motion whose
 *     BLOB is byte-identical (the writer's shortest round-trip numbers promise exactness).
 * A broken invariant calls abort(), which libFuzzer reports as a crash with the input saved.
 */
#include "affect/io.h"
#include "util/json.h"

#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* children checked by index and members looked up by key, per container (both are O(n)) */
#define CHECK_FIRST 16u

/* A failure is recorded with its status and a non-empty, NUL-terminated message. (Messages
 * may quote input text, joint names included, verbatim, so a line break in one is not an
 * error here.) */
static void check_error(affect_status st, const affect_error *err)
{
    if (st == AFFECT_OK || err->status != st || err->msg[0] == '\0' ||
        !memchr(err->msg, '\0', sizeof err->msg))
        abort();
}

/* Valid UTF-8 (U+0000 allowed, no overlongs, no surrogates, nothing above U+10FFFF) with a
 * NUL right after the len bytes. */
static void check_text(const char *s, size_t len)
{
    if (!s || s[len] != '\0')
        abort();
    const unsigned char *p = (const unsigned char *)s, *end = p + len;
    while (p < end) {
        unsigned c = *p++;
        int more;
        unsigned min, cp;
        if (c < 0x80)
            continue;
        if (c >= 0xC2 && c <= 0xDF)
            more = 1, min = 0x80, cp = c & 0x1F;
        else if (c >= 0xE0 && c <= 0xEF)
            more = 2, min = 0x800, cp = c & 0x0F;
        else if (c >= 0xF0 && c <= 0xF4)
            more = 3, min = 0x10000, cp = c & 0x07;
        else
            abort();
        for (int i = 0; i < more; i++) {
            if (p >= end || (*p & 0xC0) != 0x80)
                abort();
            cp = (cp << 6) | (*p++ & 0x3Fu);
        }
        if (cp < min || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF))
            abort();
    }
}

static void walk(const affect_json_doc *doc, const affect_json_node *n, int depth)
{
    if (depth > AFFECT_JSON_MAX_DEPTH + 1 || !affect_json_type_name(n->type))
        abort();
    if (n->type == AFFECT_JSON_STRING)
        check_text(n->str, n->str_len);
    if (n->type != AFFECT_JSON_ARRAY && n->type != AFFECT_JSON_OBJECT)
        return;
    uint32_t count = 0;
    for (const affect_json_node *c = affect_json_first(doc, n); c;
         c = affect_json_next_sibling(doc, c), count++) {
        if (count == UINT32_MAX)
            abort();
        if (count < CHECK_FIRST && affect_json_child(doc, n, count) != c)
            abort();
        if (n->type == AFFECT_JSON_OBJECT) {
            check_text(c->key, c->key_len);
            /* keys are unique; one holding \u0000 cannot be named by a C string */
            if (count < CHECK_FIRST && strlen(c->key) == c->key_len &&
                affect_json_get(doc, n, c->key) != c)
                abort();
        } else if (c->key) {
            abort();
        }
        walk(doc, c, depth + 1);
    }
    if (count != n->count || affect_json_child(doc, n, count) != NULL)
        abort();
}

static void fuzz_json_parse(const char *text, size_t len)
{
    affect_json_doc *doc = NULL;
    affect_error err;
    affect_error_clear(&err);
    affect_status st = affect_json_parse(text, len, &doc, NULL, &err);
    if (st != AFFECT_OK) {
        if (doc)
            abort();
        check_error(st, &err);
        return;
    }
    const affect_json_node *root = affect_json_root(doc);
    if (!root || root->key)
        abort();
    walk(doc, root, 0);
    affect_json_free(doc);
}

/* True when both motions encode to the same bytes; allocation failure counts as equal. */
static bool same_blob(const affect_motion *a, const affect_motion *b)
{
    affect_error err;
    unsigned char *ea = NULL, *eb = NULL;
    size_t na = 0, nb = 0;
    bool same = true;
    if (affect_motion_encode(a, &ea, &na, &err) == AFFECT_OK &&
        affect_motion_encode(b, &eb, &nb, &err) == AFFECT_OK)
        same = na == nb && memcmp(ea, eb, na) == 0;
    affect_free(ea);
    affect_free(eb);
    return same;
}

static void fuzz_motion_from_json(const char *text, size_t len)
{
    affect_motion *m = NULL, *back = NULL;
    affect_error err;
    affect_error_clear(&err);
    char *json = NULL;
    size_t json_len = 0;
    affect_status st = affect_motion_from_json(text, len, &m, NULL, &err);
    if (st != AFFECT_OK) {
        if (m)
            abort();
        check_error(st, &err);
        return;
    }
    if (affect_motion_validate(m, &err) != AFFECT_OK)
        abort();
    st = affect_motion_to_json(m, &json, &json_len, NULL, &err);
    if (st == AFFECT_OK) {
        st = affect_motion_from_json(json, json_len, &back, NULL, &err);
        if (st == AFFECT_OK && !same_blob(m, back))
            abort();
    }
    if (st != AFFECT_OK && st != AFFECT_ERR_NOMEM)
        abort();
    affect_motion_free(back);
    affect_free(json);
    affect_motion_free(m);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_json_parse((const char *)data, size);
    fuzz_motion_from_json((const char *)data, size);
    return 0;
}
