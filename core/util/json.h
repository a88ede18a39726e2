/*
 * util/json.h — a small, strict JSON (RFC 8259) reader producing a read-only tree.
 *
 * All nodes live in one array owned by the document; strings are decoded (escapes and \u
 * surrogate pairs resolved) and NUL-terminated. Nesting is limited to AFFECT_JSON_MAX_DEPTH.
 * Errors give the byte offset and what was expected: "at byte 17: expected ',' or '}'".
 * Duplicate object keys are an error (they are always a mistake in our options and motions).
 */
#ifndef AFFECT_JSON_H
#define AFFECT_JSON_H

#include "affect/base.h"
#include "affect/monitor.h"

#ifdef __cplusplus
extern "C" {
#endif

#define AFFECT_JSON_MAX_DEPTH 64

typedef enum affect_json_type {
    AFFECT_JSON_NULL,
    AFFECT_JSON_FALSE,
    AFFECT_JSON_TRUE,
    AFFECT_JSON_NUMBER,
    AFFECT_JSON_STRING,
    AFFECT_JSON_ARRAY,
    AFFECT_JSON_OBJECT
} affect_json_type;

typedef struct affect_json_node {
    affect_json_type type;
    uint32_t count;  /* ARRAY, OBJECT: number of children (members) */
    int32_t first;   /* ARRAY, OBJECT: index of first child, −1 if none */
    int32_t next;    /* index of next sibling, −1 at the end */
    const char *key; /* member of an OBJECT: its key (decoded), else NULL */
    size_t key_len;  /* member of an OBJECT: bytes of key (it may contain \u0000) */
    const char *str; /* STRING: decoded text */
    size_t str_len;  /* STRING: bytes (the text may contain \u0000) */
    double num;      /* NUMBER */
} affect_json_node;

typedef struct affect_json_doc affect_json_doc;

/* Parses text[0..len). The root is node 0. mon (may be NULL) is polled every few thousand
 * values: AFFECT_ERR_INTERRUPTED once it says stop (long documents such as a motion's). */
affect_status affect_json_parse(const char *text, size_t len, affect_json_doc **out,
                                affect_monitor *mon, affect_error *err);
void affect_json_free(affect_json_doc *doc);

const affect_json_node *affect_json_root(const affect_json_doc *doc);
/* Child i (0-based) of an array or object, or NULL. O(i). */
const affect_json_node *affect_json_child(const affect_json_doc *doc, const affect_json_node *n,
                                          uint32_t i);
/* First child of a container, or NULL; then affect_json_next_sibling. */
const affect_json_node *affect_json_first(const affect_json_doc *doc, const affect_json_node *n);
const affect_json_node *affect_json_next_sibling(const affect_json_doc *doc,
                                                 const affect_json_node *n);
/* Member of an object whose key is exactly the C string key (key_len bytes), or NULL. */
const affect_json_node *affect_json_get(const affect_json_doc *doc, const affect_json_node *obj,
                                        const char *key);
/* Writes s[0..len) into buf (size ≥ 16) as a JSON string literal for a one-line message:
 * quoted, escaped, and shortened with "..." (never inside a UTF-8 sequence) to fit. */
void affect_json_quote(char *buf, size_t size, const char *s, size_t len);
/* "null", "boolean", "number", "string", "array", "object". */
const char *affect_json_type_name(affect_json_type t);

#ifdef __cplusplus
}
#endif
#endif
