/*
 * test_json.c — the strict JSON reader (json.c) and the motion JSON format (motion_json.c):
 * grammar acceptance and rejection tables with exact messages and byte offsets, escapes and
 * surrogates, UTF-8 validation, the depth limit, duplicate keys, the accessors, motion round
 * trips (bit-identical floats), the exact writer output, every motion error path, and
 * out-of-memory at every allocation without leaks.
 */
#include "testutil.h"

#include "affect/io.h"
#include "util/json.h"
#include "util/strbuf.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- helpers ---- */

static affect_json_doc *parse_ok(const char *text, size_t len)
{
    affect_json_doc *doc = NULL;
    affect_error err;
    affect_error_clear(&err);
    affect_status st = affect_json_parse(text, len, &doc, NULL, &err);
    if (st != AFFECT_OK)
        fail_msg("parsing <%.60s> failed: %s", text, err.msg);
    assert_non_null(doc);
    assert_non_null(affect_json_root(doc));
    return doc;
}

static void expect_json_error(const char *text, size_t len, affect_status status, const char *msg)
{
    affect_json_doc *doc = (affect_json_doc *)&doc; /* must be reset to NULL */
    affect_error err;
    affect_error_clear(&err);
    affect_status st = affect_json_parse(text, len, &doc, NULL, &err);
    if (st == AFFECT_OK)
        fail_msg("<%.60s> was accepted, expected \"%s\"", text, msg);
    assert_null(doc);
    if (strcmp(err.msg, msg) != 0)
        fail_msg("<%.60s>: got \"%s\", expected \"%s\"", text, err.msg, msg);
    assert_int_equal(st, status);
    assert_int_equal(err.status, status);
}

/* ---- grammar: acceptance ---- */

typedef struct accept_case {
    const char *text;
    affect_json_type type;
    double num; /* NUMBER only */
} accept_case;

static void test_accept_table(void **state)
{
    (void)state;
    static const accept_case cases[] = {
        {"0", AFFECT_JSON_NUMBER, 0},
        {"-0", AFFECT_JSON_NUMBER, -0.0},
        {"1", AFFECT_JSON_NUMBER, 1},
        {"-1", AFFECT_JSON_NUMBER, -1},
        {"123", AFFECT_JSON_NUMBER, 123},
        {"1.5", AFFECT_JSON_NUMBER, 1.5},
        {"-1.5e10", AFFECT_JSON_NUMBER, -1.5e10},
        {"1E5", AFFECT_JSON_NUMBER, 1e5},
        {"1e+5", AFFECT_JSON_NUMBER, 1e5},
        {"1e-5", AFFECT_JSON_NUMBER, 1e-5},
        {"0.0", AFFECT_JSON_NUMBER, 0},
        {"0e0", AFFECT_JSON_NUMBER, 0},
        {"0.25E-2", AFFECT_JSON_NUMBER, 0.0025},
        {"-0.0e-0", AFFECT_JSON_NUMBER, -0.0},
        {"1e-400", AFFECT_JSON_NUMBER, 0}, /* underflow is not an error */
        {"1.7976931348623157e308", AFFECT_JSON_NUMBER, DBL_MAX},
        {"12345678901234567890", AFFECT_JSON_NUMBER, 12345678901234567890.0},
        {"true", AFFECT_JSON_TRUE, 0},
        {"false", AFFECT_JSON_FALSE, 0},
        {"null", AFFECT_JSON_NULL, 0},
        {"\"\"", AFFECT_JSON_STRING, 0},
        {"\"abc\"", AFFECT_JSON_STRING, 0},
        {"\"\\u00e9\\u00E9\"", AFFECT_JSON_STRING, 0},
        {"\"\\ud83d\\ude00\"", AFFECT_JSON_STRING, 0},
        {"\"\\\"\\\\\\/\\b\\f\\n\\r\\t\"", AFFECT_JSON_STRING, 0},
        {"\"caf\xc3\xa9 \xe2\x82\xac \xf0\x9f\x98\x80\"", AFFECT_JSON_STRING, 0},
        {"\"\xef\xbf\xbf\"", AFFECT_JSON_STRING, 0},     /* U+FFFF */
        {"\"\xf4\x8f\xbf\xbf\"", AFFECT_JSON_STRING, 0}, /* U+10FFFF */
        {"\"\xed\x9f\xbf\"", AFFECT_JSON_STRING, 0},     /* U+D7FF */
        {"\"\x7f\"", AFFECT_JSON_STRING, 0},             /* DEL is not a control char */
        {"\"\\u0000\"", AFFECT_JSON_STRING, 0},
        {"[]", AFFECT_JSON_ARRAY, 0},
        {"{}", AFFECT_JSON_OBJECT, 0},
        {" \t\n\r[ 1 , 2 ]\r\n\t ", AFFECT_JSON_ARRAY, 0},
        {"[[[]]]", AFFECT_JSON_ARRAY, 0},
        {"[1,\"a\",true,false,null,{},[]]", AFFECT_JSON_ARRAY, 0},
        {"{\"a\":{\"b\":[null]}}", AFFECT_JSON_OBJECT, 0},
        {"{\"a\":1,\"A\":1}", AFFECT_JSON_OBJECT, 0},
        {"{\"\":0}", AFFECT_JSON_OBJECT, 0},
        {"{\"a\":{\"a\":1},\"b\":{\"a\":2}}", AFFECT_JSON_OBJECT, 0},
        {"{ \"a\" : [ 1 , { } ] , \"b\" : \"\" }", AFFECT_JSON_OBJECT, 0},
    };
    size_t n = sizeof cases / sizeof cases[0];
    assert_true(n >= 30);
    for (size_t i = 0; i < n; i++) {
        affect_json_doc *doc = parse_ok(cases[i].text, strlen(cases[i].text));
        const affect_json_node *root = affect_json_root(doc);
        if (root->type != cases[i].type)
            fail_msg("<%s>: type %s", cases[i].text, affect_json_type_name(root->type));
        if (root->type == AFFECT_JSON_NUMBER) {
            if (root->num != cases[i].num || signbit(root->num) != signbit(cases[i].num))
                fail_msg("<%s>: read %.17g", cases[i].text, root->num);
        }
        assert_null(root->key);
        assert_int_equal(root->next, -1);
        affect_json_free(doc);
    }
}

static void test_len_is_respected(void **state)
{
    (void)state;
    /* only text[0..len) is read: no NUL terminator needed, trailing bytes ignored */
    affect_json_doc *doc = parse_ok("[1]xyz", 3);
    assert_int_equal(affect_json_root(doc)->count, 1);
    affect_json_free(doc);
    doc = parse_ok("12345", 2);
    assert_true(affect_json_root(doc)->num == 12);
    affect_json_free(doc);
    expect_json_error("\"abc\"", 4, AFFECT_ERR_FORMAT, "at byte 4: unexpected end of text");
    expect_json_error("tr", 2, AFFECT_ERR_FORMAT, "at byte 0: invalid literal");
    expect_json_error(NULL, 0, AFFECT_ERR_FORMAT, "at byte 0: unexpected end of text");
}

/* ---- grammar: rejection ---- */

typedef struct reject_case {
    const char *text;
    size_t len; /* 0: strlen(text) */
    affect_status status;
    const char *msg;
} reject_case;

#define F AFFECT_ERR_FORMAT
#define R AFFECT_ERR_RANGE

static void test_reject_table(void **state)
{
    (void)state;
    static const reject_case cases[] = {
        /* empty, white space, end of text */
        {"", 0, F, "at byte 0: unexpected end of text"},
        {"  \n\t", 0, F, "at byte 4: unexpected end of text"},
        {"[", 0, F, "at byte 1: unexpected end of text"},
        {"[1,", 0, F, "at byte 3: unexpected end of text"},
        {"{\"a\"", 0, F, "at byte 4: unexpected end of text"},
        {"{\"a\":", 0, F, "at byte 5: unexpected end of text"},
        {"\"abc", 0, F, "at byte 4: unexpected end of text"},
        {"\"\\", 0, F, "at byte 2: unexpected end of text"},
        {"\"\\u12", 0, F, "at byte 5: unexpected end of text"},
        {"\v1", 0, F, "at byte 0: expected a value"},
        {"\f1", 0, F, "at byte 0: expected a value"},
        {"\xef\xbb\xbf{}", 0, F, "at byte 0: expected a value"}, /* byte order mark */
        {"'a'", 0, F, "at byte 0: expected a value"},
        /* numbers */
        {"01", 0, F, "at byte 0: invalid number"},
        {"-01", 0, F, "at byte 0: invalid number"},
        {"[00]", 0, F, "at byte 1: invalid number"},
        {"+1", 0, F, "at byte 0: invalid number"},
        {".5", 0, F, "at byte 0: invalid number"},
        {"5.", 0, F, "at byte 0: invalid number"},
        {"-.5", 0, F, "at byte 0: invalid number"},
        {"1.e5", 0, F, "at byte 0: invalid number"},
        {"1e", 0, F, "at byte 0: invalid number"},
        {"1e+", 0, F, "at byte 0: invalid number"},
        {"[1E-]", 0, F, "at byte 1: invalid number"},
        {"-", 0, F, "at byte 0: invalid number"},
        {"0x1F", 0, F, "at byte 0: invalid number"},
        {"[1.5.2]", 0, F, "at byte 1: invalid number"},
        {"[1e5e5]", 0, F, "at byte 1: invalid number"},
        {"[1-2]", 0, F, "at byte 1: invalid number"},
        {"-Infinity", 0, F, "at byte 0: invalid number"},
        {"{\"a\": 1e999}", 0, R, "at byte 6: number out of range"},
        {"-1e400", 0, R, "at byte 0: number out of range"},
        /* literals */
        {"NaN", 0, F, "at byte 0: invalid literal"},
        {"Infinity", 0, F, "at byte 0: invalid literal"},
        {"True", 0, F, "at byte 0: invalid literal"},
        {"nul", 0, F, "at byte 0: invalid literal"},
        {"[truex]", 0, F, "at byte 1: invalid literal"},
        {"undefined", 0, F, "at byte 0: invalid literal"},
        /* structure */
        {"[1,]", 0, F, "at byte 3: expected a value"},
        {"[,1]", 0, F, "at byte 1: expected a value"},
        {"[1 2]", 0, F, "at byte 3: expected ',' or ']'"},
        {"[1;2]", 0, F, "at byte 2: expected ',' or ']'"},
        {"{\"a\":1 \"b\":2}", 0, F, "at byte 7: expected ',' or '}'"},
        {"{\"a\" 1}", 0, F, "at byte 5: expected ':'"},
        {"{a:1}", 0, F, "at byte 1: expected a key or '}'"},
        {"{\"a\":1,}", 0, F, "at byte 7: expected a key"},
        {"{\"a\":1, 2:3}", 0, F, "at byte 8: expected a key"},
        {"{\"a\"}", 0, F, "at byte 4: expected ':'"},
        {"[}", 0, F, "at byte 1: expected a value"},
        {"1 2", 0, F, "at byte 2: unexpected text after the value"},
        {"[1]]", 0, F, "at byte 3: unexpected text after the value"},
        {"{} x", 0, F, "at byte 3: unexpected text after the value"},
        {"1\0", 2, F, "at byte 1: unexpected text after the value"},
        {"{\"a\":1,\"b\":2,\"a\":3}", 0, F, "at byte 13: duplicate key \"a\""},
        /* strings */
        {"\"a\x01\"", 0, F, "at byte 2: control character in string"},
        {"\"a\nb\"", 0, F, "at byte 2: control character in string"},
        {"\"\tb\"", 0, F, "at byte 1: control character in string"},
        {"\"a\0b\"", 5, F, "at byte 2: control character in string"},
        {"\"\\x\"", 0, F, "at byte 1: invalid escape"},
        {"\"\\'\"", 0, F, "at byte 1: invalid escape"},
        {"\"\\U00e9\"", 0, F, "at byte 1: invalid escape"},
        {"[\"ok\", \"\\u12G4\"]", 0, F, "at byte 8: invalid escape"},
        {"\"\\ud800\"", 0, F, "at byte 1: unpaired surrogate \\uD800"},
        {"\"\\udc00\"", 0, F, "at byte 1: unpaired surrogate \\uDC00"},
        {"\"ab\\ud83d\\u0041\"", 0, F, "at byte 3: unpaired surrogate \\uD83D"},
        {"\"\\ud83d\\ud83d\"", 0, F, "at byte 1: unpaired surrogate \\uD83D"},
        {"\"\\ude00\\ud83d\"", 0, F, "at byte 1: unpaired surrogate \\uDE00"},
        {"\"\\ud83dx\"", 0, F, "at byte 1: unpaired surrogate \\uD83D"},
        /* UTF-8 */
        {"\"ab\xc0\x80\"", 0, F, "at byte 3: invalid UTF-8"},       /* overlong NUL */
        {"\"\xc1\xbf\"", 0, F, "at byte 1: invalid UTF-8"},         /* overlong 2-byte */
        {"\"\xe0\x80\xaf\"", 0, F, "at byte 1: invalid UTF-8"},     /* overlong 3-byte */
        {"\"\xf0\x8f\xbf\xbf\"", 0, F, "at byte 1: invalid UTF-8"}, /* overlong 4-byte */
        {"\"\xed\xa0\x80\"", 0, F, "at byte 1: invalid UTF-8"},     /* U+D800 encoded */
        {"\"\xed\xbf\xbf\"", 0, F, "at byte 1: invalid UTF-8"},     /* U+DFFF encoded */
        {"\"\xf4\x90\x80\x80\"", 0, F, "at byte 1: invalid UTF-8"}, /* U+110000 */
        {"\"\xf5\x80\x80\x80\"", 0, F, "at byte 1: invalid UTF-8"},
        {"\"x\x80\"", 0, F, "at byte 2: invalid UTF-8"}, /* lone continuation */
        {"\"\xc3\"", 0, F, "at byte 1: invalid UTF-8"},  /* truncated */
        {"\"\xe2\x82\"", 0, F, "at byte 1: invalid UTF-8"},
        {"\"\xe2\x28\xa1\"", 0, F, "at byte 1: invalid UTF-8"},
        {"\"\xff\"", 0, F, "at byte 1: invalid UTF-8"},
        {"\"\xc3", 0, F, "at byte 1: invalid UTF-8"},
    };
    size_t n = sizeof cases / sizeof cases[0];
    assert_true(n >= 30);
    for (size_t i = 0; i < n; i++)
        expect_json_error(cases[i].text, cases[i].len ? cases[i].len : strlen(cases[i].text),
                          cases[i].status, cases[i].msg);
}

/* ---- strings ---- */

static void test_string_decoding(void **state)
{
    (void)state;
    const char *text = "[\"a\\\"b\\\\c\\/d\\be\\ff\\ng\\rh\\ti\", \"\\u00e9\\u20AC\\ud83d\\ude00\","
                       " \"x\\u0000y\", \"\", \"caf\xc3\xa9\", \"\\uDBFF\\uDFFF\"]";
    affect_json_doc *doc = parse_ok(text, strlen(text));
    const affect_json_node *root = affect_json_root(doc);
    assert_int_equal(root->count, 6);

    const affect_json_node *s = affect_json_child(doc, root, 0);
    assert_int_equal(s->type, AFFECT_JSON_STRING);
    assert_string_equal(s->str, "a\"b\\c/d\be\ff\ng\rh\ti");
    assert_int_equal(s->str_len, 17);

    s = affect_json_child(doc, root, 1);
    assert_string_equal(s->str, "\xc3\xa9\xe2\x82\xac\xf0\x9f\x98\x80");
    assert_int_equal(s->str_len, 9);

    s = affect_json_child(doc, root, 2); /* \u0000 is kept and counted */
    assert_int_equal(s->str_len, 3);
    assert_memory_equal(s->str, "x\0y", 4);

    s = affect_json_child(doc, root, 3);
    assert_int_equal(s->str_len, 0);
    assert_string_equal(s->str, "");

    s = affect_json_child(doc, root, 4);
    assert_string_equal(s->str, "caf\xc3\xa9");

    s = affect_json_child(doc, root, 5); /* U+10FFFF, the highest pair */
    assert_string_equal(s->str, "\xf4\x8f\xbf\xbf");
    affect_json_free(doc);

    /* a string of only escapes fills the arena: decoded text never outgrows the input */
    doc = parse_ok("\"\\n\"", 4);
    assert_string_equal(affect_json_root(doc)->str, "\n");
    affect_json_free(doc);
}

/* ---- depth ---- */

static char *nested(int depth, const char *open, const char *inner, const char *close)
{
    size_t lo = strlen(open), li = strlen(inner), lc = strlen(close);
    char *s = malloc((size_t)depth * (lo + lc) + li + 1), *w = s;
    assert_non_null(s);
    for (int i = 0; i < depth; i++, w += lo)
        memcpy(w, open, lo);
    memcpy(w, inner, li);
    w += li;
    for (int i = 0; i < depth; i++, w += lc)
        memcpy(w, close, lc);
    *w = '\0';
    return s;
}

static void test_depth_limit(void **state)
{
    (void)state;
    char *s = nested(AFFECT_JSON_MAX_DEPTH, "[", "1", "]");
    affect_json_doc *doc = parse_ok(s, strlen(s));
    const affect_json_node *n = affect_json_root(doc);
    for (int i = 0; i < AFFECT_JSON_MAX_DEPTH; i++) {
        assert_int_equal(n->type, AFFECT_JSON_ARRAY);
        n = affect_json_first(doc, n);
    }
    assert_int_equal(n->type, AFFECT_JSON_NUMBER);
    affect_json_free(doc);
    free(s);

    s = nested(AFFECT_JSON_MAX_DEPTH + 1, "[", "1", "]");
    expect_json_error(s, strlen(s), AFFECT_ERR_RANGE, "at byte 64: nesting deeper than 64");
    free(s);

    /* objects count too: 64 levels of {"a": is fine, 65 is not */
    s = nested(AFFECT_JSON_MAX_DEPTH, "{\"a\":", "{}", "}");
    expect_json_error(s, strlen(s), AFFECT_ERR_RANGE, "at byte 320: nesting deeper than 64");
    free(s);
    s = nested(AFFECT_JSON_MAX_DEPTH - 1, "{\"a\":", "[]", "}");
    doc = parse_ok(s, strlen(s));
    affect_json_free(doc);
    free(s);

    /* very deep input fails at the limit instead of overflowing the stack */
    s = nested(1000000, "[", "", "]");
    expect_json_error(s, strlen(s), AFFECT_ERR_RANGE, "at byte 64: nesting deeper than 64");
    free(s);
}

/* ---- duplicate keys ---- */

static void test_duplicate_keys(void **state)
{
    (void)state;
    expect_json_error("{\"a\":1,\"a\":1}", 13, F, "at byte 7: duplicate key \"a\"");
    expect_json_error("{\"x\":{\"k\":1, \"k\":[]}}", 21, F, "at byte 13: duplicate key \"k\"");
    /* the same key after decoding is the same key */
    expect_json_error("{\"\\u0061\":1,\"a\":2}", 18, F, "at byte 12: duplicate key \"a\"");
    expect_json_error("{\"\":1,\"\":2}", 11, F, "at byte 6: duplicate key \"\"");
    /* keys differing after \u0000 are distinct; the message escapes what it quotes */
    affect_json_doc *doc = parse_ok("{\"a\\u0000b\":1,\"a\\u0000c\":2}", 27);
    affect_json_free(doc);
    expect_json_error("{\"a\\u0000\\\"\":1,\"a\\u0000\\\"\":2}", 29, F,
                      "at byte 15: duplicate key \"a\\u0000\\\"\"");
    /* a long key is shortened in the message */
    char text[480], key[201];
    memset(key, 'k', 200);
    key[200] = '\0';
    snprintf(text, sizeof text, "{\"%s\":1,\"%s\":2}", key, key);
    char want[128];
    snprintf(want, sizeof want, "at byte 206: duplicate key \"%.65s...\"", key);
    expect_json_error(text, strlen(text), F, want);

    /* many keys: the check must stay fast (a quadratic one would take minutes here) */
    enum { N = 100000 };
    size_t cap = (size_t)N * 24 + 32, o = 0;
    char *big = malloc(cap);
    assert_non_null(big);
    big[o++] = '{';
    for (int i = 0; i < N; i++)
        o += (size_t)snprintf(big + o, cap - o, "%s\"key%d\":%d", i ? "," : "", i, i);
    size_t closed = o;
    big[o++] = '}';
    doc = parse_ok(big, o);
    const affect_json_node *root = affect_json_root(doc);
    assert_int_equal(root->count, N);
    assert_true(affect_json_get(doc, root, "key99999")->num == 99999);
    assert_true(affect_json_get(doc, root, "key0")->num == 0);
    affect_json_free(doc);
    o = closed + (size_t)snprintf(big + closed, cap - closed, ",\"key77777\":0}");
    char msg[64];
    snprintf(msg, sizeof msg, "at byte %zu: duplicate key \"key77777\"", closed + 1);
    expect_json_error(big, o, F, msg);
    free(big);
}

/* ---- accessors ---- */

static void test_accessors(void **state)
{
    (void)state;
    const char *text = "{\"name\":\"Hips\",\"list\":[10,20,30],\"empty\":[],\"obj\":{},"
                       "\"flag\":true,\"off\":false,\"none\":null,\"n\\u0000ul\":1}";
    affect_json_doc *doc = parse_ok(text, strlen(text));
    const affect_json_node *root = affect_json_root(doc);
    assert_int_equal(root->type, AFFECT_JSON_OBJECT);
    assert_int_equal(root->count, 8);

    const affect_json_node *name = affect_json_get(doc, root, "name");
    assert_non_null(name);
    assert_string_equal(name->key, "name");
    assert_int_equal(name->key_len, 4);
    assert_string_equal(name->str, "Hips");
    assert_ptr_equal(affect_json_first(doc, root), name);
    assert_ptr_equal(affect_json_child(doc, root, 0), name);

    const affect_json_node *list = affect_json_get(doc, root, "list");
    assert_ptr_equal(affect_json_next_sibling(doc, name), list);
    assert_ptr_equal(affect_json_child(doc, root, 1), list);
    assert_int_equal(list->type, AFFECT_JSON_ARRAY);
    assert_int_equal(list->count, 3);
    for (uint32_t i = 0; i < 3; i++) {
        const affect_json_node *c = affect_json_child(doc, list, i);
        assert_non_null(c);
        assert_true(c->num == 10.0 * (i + 1));
        assert_null(c->key);
        assert_int_equal(c->key_len, 0);
    }
    assert_null(affect_json_child(doc, list, 3));
    const affect_json_node *last = affect_json_child(doc, list, 2);
    assert_null(affect_json_next_sibling(doc, last));
    assert_int_equal(last->next, -1);

    const affect_json_node *empty = affect_json_get(doc, root, "empty");
    assert_int_equal(empty->count, 0);
    assert_int_equal(empty->first, -1);
    assert_null(affect_json_first(doc, empty));
    assert_null(affect_json_child(doc, empty, 0));
    assert_null(affect_json_get(doc, affect_json_get(doc, root, "obj"), "x"));

    assert_int_equal(affect_json_get(doc, root, "flag")->type, AFFECT_JSON_TRUE);
    assert_int_equal(affect_json_get(doc, root, "off")->type, AFFECT_JSON_FALSE);
    assert_int_equal(affect_json_get(doc, root, "none")->type, AFFECT_JSON_NULL);
    /* a key with \u0000 inside is not found by its prefix */
    assert_null(affect_json_get(doc, root, "n"));
    const affect_json_node *nul = affect_json_child(doc, root, 7);
    assert_int_equal(nul->key_len, 4);
    assert_memory_equal(nul->key, "n\0ul", 5); /* with its terminating NUL */

    assert_null(affect_json_get(doc, root, "missing"));
    assert_null(affect_json_get(doc, root, "nam"));
    assert_null(affect_json_get(doc, list, "name")); /* not an object */
    assert_null(affect_json_first(doc, name));       /* not a container */
    assert_null(affect_json_get(doc, NULL, "name"));
    assert_null(affect_json_child(doc, NULL, 0));

    assert_string_equal(affect_json_type_name(AFFECT_JSON_NULL), "null");
    assert_string_equal(affect_json_type_name(AFFECT_JSON_FALSE), "boolean");
    assert_string_equal(affect_json_type_name(AFFECT_JSON_TRUE), "boolean");
    assert_string_equal(affect_json_type_name(AFFECT_JSON_NUMBER), "number");
    assert_string_equal(affect_json_type_name(AFFECT_JSON_STRING), "string");
    assert_string_equal(affect_json_type_name(AFFECT_JSON_ARRAY), "array");
    assert_string_equal(affect_json_type_name(AFFECT_JSON_OBJECT), "object");
    affect_json_free(doc);

    assert_null(affect_json_root(NULL));
    affect_json_free(NULL);
}

/* Node pointers taken early stay valid while the node array grows (it is complete before any
 * pointer is handed out) and strings live until the document is freed. */
static void test_many_nodes(void **state)
{
    (void)state;
    enum { N = 50000 };
    size_t cap = (size_t)N * 12 + 8, o = 0;
    char *text = malloc(cap);
    assert_non_null(text);
    text[o++] = '[';
    for (int i = 0; i < N; i++)
        o += (size_t)snprintf(text + o, cap - o, "%s[\"%d\"]", i ? "," : "", i);
    text[o++] = ']';
    affect_json_doc *doc = parse_ok(text, o);
    free(text);
    const affect_json_node *root = affect_json_root(doc);
    assert_int_equal(root->count, N);
    int i = 0;
    for (const affect_json_node *c = affect_json_first(doc, root); c;
         c = affect_json_next_sibling(doc, c), i++) {
        const affect_json_node *s = affect_json_first(doc, c);
        char want[16];
        snprintf(want, sizeof want, "%d", i);
        assert_string_equal(s->str, want);
    }
    assert_int_equal(i, N);
    affect_json_free(doc);
}

/* ---- motion JSON ---- */

static affect_motion *make_motion(uint32_t frames, uint32_t joints, double fps, const char *unit,
                                  const char *const *names, const int32_t *parents)
{
    affect_motion *m = NULL;
    assert_int_equal(affect_motion_create(frames, joints, fps, &m, NULL), AFFECT_OK);
    assert_int_equal(affect_motion_set_unit(m, unit, NULL), AFFECT_OK);
    for (uint32_t j = 0; j < joints; j++) {
        assert_int_equal(affect_motion_set_name(m, j, names[j], strlen(names[j]), NULL), AFFECT_OK);
        m->parents[j] = parents[j];
    }
    return m;
}

static affect_motion *from_json_ok(const char *text)
{
    affect_motion *m = NULL;
    affect_error err;
    affect_error_clear(&err);
    if (affect_motion_from_json(text, strlen(text), &m, NULL, &err) != AFFECT_OK)
        fail_msg("from_json <%.80s>: %s", text, err.msg);
    assert_non_null(m);
    return m;
}

static void expect_motion_error(const char *text, affect_status status, const char *msg)
{
    affect_motion *m = (affect_motion *)&m;
    affect_error err;
    affect_error_clear(&err);
    affect_status st = affect_motion_from_json(text, strlen(text), &m, NULL, &err);
    if (st == AFFECT_OK)
        fail_msg("<%.80s> was accepted, expected \"%s\"", text, msg);
    assert_null(m);
    if (strcmp(err.msg, msg) != 0)
        fail_msg("<%.80s>: got \"%s\", expected \"%s\"", text, err.msg, msg);
    assert_int_equal(st, status);
}

static void test_motion_round_trip(void **state)
{
    (void)state;
    static const char *const names[] = {"Hips", "Spine", "Le\"ft\\Arm", "\xc3\xa9paule"};
    static const int32_t parents[] = {-1, 0, 1, 1};
    static const float values[] = {0.1f,
                                   1e-7f,
                                   -0.0f,
                                   0.0f,
                                   FLT_MAX,
                                   -FLT_MAX,
                                   FLT_MIN,
                                   FLT_TRUE_MIN,
                                   0x1p-140f,
                                   -1.17549421e-38f /* largest denormal */,
                                   1.0f / 3.0f,
                                   123456.789f,
                                   16777216.0f,
                                   -2.5f,
                                   3.14159274f,
                                   1e10f,
                                   9.99999944e-11f,
                                   0.3f,
                                   100.0f,
                                   -7e-45f,
                                   33554436.0f,
                                   1.00000012f,
                                   0.99999994f,
                                   6.02214076e23f};
    size_t nv = sizeof values / sizeof values[0];
    affect_motion *m = make_motion(3, 4, 1000.0 / 33.0, "cm", names, parents);
    size_t n = (size_t)m->n_frames * m->n_joints * 3;
    for (size_t i = 0; i < n; i++)
        m->pos[i] = values[i % nv] * (i / nv % 2 ? -1.0f : 1.0f);

    char *text = NULL;
    size_t len = 0;
    assert_int_equal(affect_motion_to_json(m, &text, &len, NULL, NULL), AFFECT_OK);
    assert_int_equal(len, strlen(text));
    affect_motion *back = NULL;
    affect_error err;
    if (affect_motion_from_json(text, len, &back, NULL, &err) != AFFECT_OK)
        fail_msg("%s\n%s", err.msg, text);

    assert_int_equal(back->n_frames, 3);
    assert_int_equal(back->n_joints, 4);
    assert_memory_equal(&back->fps, &m->fps, sizeof m->fps);
    assert_string_equal(back->unit, "cm");
    for (uint32_t j = 0; j < 4; j++) {
        assert_string_equal(back->names[j], names[j]);
        assert_int_equal(back->parents[j], parents[j]);
    }
    assert_memory_equal(back->pos, m->pos, n * sizeof *m->pos); /* bit-identical */
    assert_true(signbit(back->pos[2]));                         /* -0.0f survives */

    /* writing the result again gives the same text */
    char *again = NULL;
    assert_int_equal(affect_motion_to_json(back, &again, NULL, NULL, NULL), AFFECT_OK);
    assert_string_equal(again, text);
    affect_free(again);
    affect_free(text);
    affect_motion_free(back);
    affect_motion_free(m);
}

static void test_motion_exact_output(void **state)
{
    (void)state;
    static const char *const names[] = {"Hips", "Left\"Foot"};
    static const int32_t parents[] = {-1, 0};
    affect_motion *m = make_motion(2, 2, 30, "cm", names, parents);
    static const float pos[] = {0,     1.5f,  -2,    0.1f, 100,      1e-7f,
                                -0.0f, 3.25f, 1e20f, -1,   16777216, 0.3f};
    memcpy(m->pos, pos, sizeof pos);
    char *text = NULL;
    size_t len = 0;
    assert_int_equal(affect_motion_to_json(m, &text, &len, NULL, NULL), AFFECT_OK);
    const char *want = "{\"fps\":30,\"unit\":\"cm\",\"joints\":[\"Hips\",\"Left\\\"Foot\"],"
                       "\"parents\":[-1,0],\"frames\":[[[0,1.5,-2],[0.1,100,1e-07]],"
                       "[[-0,3.25,1e+20],[-1,16777216,0.3]]]}";
    assert_string_equal(text, want);
    assert_int_equal(len, strlen(want));
    affect_free(text);

    /* no unit: the key is left out; fractional fps keeps its digits */
    m->unit[0] = '\0';
    m->fps = 29.97;
    m->parents[1] = -1;
    assert_int_equal(affect_motion_to_json(m, &text, NULL, NULL, NULL), AFFECT_OK);
    assert_string_equal(text, "{\"fps\":29.97,\"joints\":[\"Hips\",\"Left\\\"Foot\"],"
                              "\"parents\":[-1,-1],\"frames\":[[[0,1.5,-2],[0.1,100,1e-07]],"
                              "[[-0,3.25,1e+20],[-1,16777216,0.3]]]}");
    affect_free(text);
    affect_motion_free(m);
}

static void test_motion_defaults(void **state)
{
    (void)state;
    /* parents and unit are optional; white space and key order are free */
    affect_motion *m = from_json_ok(" { \"frames\" : [ [[1,2,3],[4,5,6]] ] , \"joints\":[\"a\","
                                    "\"b\"], \"fps\": 120.5 } ");
    assert_int_equal(m->n_frames, 1);
    assert_int_equal(m->n_joints, 2);
    assert_true(m->fps == 120.5);
    assert_string_equal(m->unit, "");
    assert_int_equal(m->parents[0], -1);
    assert_int_equal(m->parents[1], -1);
    assert_string_equal(m->names[1], "b");
    for (int i = 0; i < 6; i++)
        assert_true(m->pos[i] == (float)(i + 1));
    affect_motion_free(m);

    /* integers written as 1.0 or -0 are integers; an empty unit is unknown */
    m = from_json_ok("{\"fps\":30,\"unit\":\"\",\"joints\":[\"a\",\"b\",\"c\"],"
                     "\"parents\":[-1,0.0,1e0],\"frames\":[[[0,0,0],[0,0,0],[0,0,0]]]}");
    assert_int_equal(m->parents[1], 0);
    assert_int_equal(m->parents[2], 1);
    assert_string_equal(m->unit, "");
    affect_motion_free(m);

    /* the largest float32 is accepted; values just below the overflow threshold round to it */
    m = from_json_ok("{\"fps\":30,\"joints\":[\"a\"],\"frames\":[[[3.4028235e38,-3.40282356e38,"
                     "1e-50]]]}");
    assert_true(m->pos[0] == FLT_MAX);
    assert_true(m->pos[1] == -FLT_MAX);
    assert_true(m->pos[2] == 0.0f);
    affect_motion_free(m);
}

static void test_motion_errors(void **state)
{
    (void)state;
#define HEAD "{\"fps\":30,\"joints\":[\"a\",\"b\"],"
#define ONE_FRAME "\"frames\":[[[0,0,0],[0,0,0]]]}"
    /* JSON syntax errors pass through with their byte offset */
    expect_motion_error("{\"fps\": 30,}", F, "at byte 11: expected a key");
    expect_motion_error("", F, "at byte 0: unexpected end of text");
    expect_motion_error("{\"fps\":1e999}", R, "at byte 7: number out of range");
    expect_motion_error("{\"fps\":30,\"fps\":30}", F, "at byte 10: duplicate key \"fps\"");
    /* top level */
    expect_motion_error("[1]", F, "expected an object at the top level, found array");
    expect_motion_error("\"x\"", F, "expected an object at the top level, found string");
    expect_motion_error("{\"fps\":30,\"joints\":[\"a\"],\"frams\":[]}", F,
                        "\"frams\": unknown key (expected fps, unit, joints, parents, frames)");
    expect_motion_error("{\"FPS\":30}", F,
                        "\"FPS\": unknown key (expected fps, unit, joints, parents, frames)");
    expect_motion_error("{\"fps\\u0000\":30}", F,
                        "\"fps\\u0000\": unknown key "
                        "(expected fps, unit, joints, parents, frames)");
    expect_motion_error("{\"joints\":[\"a\"],\"frames\":[]}", F,
                        "\"fps\": missing key (required: fps, joints, frames)");
    expect_motion_error("{\"fps\":30,\"frames\":[]}", F,
                        "\"joints\": missing key (required: fps, joints, frames)");
    expect_motion_error("{\"fps\":30,\"joints\":[\"a\"]}", F,
                        "\"frames\": missing key (required: fps, joints, frames)");
    /* fps */
    expect_motion_error("{\"fps\":0,\"joints\":[\"a\"],\"frames\":[[[0,0,0]]]}", F,
                        "fps: expected a positive number");
    expect_motion_error("{\"fps\":-30,\"joints\":[\"a\"],\"frames\":[[[0,0,0]]]}", F,
                        "fps: expected a positive number");
    expect_motion_error("{\"fps\":\"30\",\"joints\":[\"a\"],\"frames\":[[[0,0,0]]]}", F,
                        "fps: expected a positive number");
    expect_motion_error("{\"fps\":null,\"joints\":[\"a\"],\"frames\":[[[0,0,0]]]}", F,
                        "fps: expected a positive number");
    expect_motion_error("{\"fps\":200000,\"joints\":[\"a\"],\"frames\":[[[0,0,0]]]}", R,
                        "fps: 200000 is above the limit of 100000");
    /* unit */
    expect_motion_error(HEAD "\"unit\":5," ONE_FRAME, F, "unit: expected a string");
    expect_motion_error(HEAD "\"unit\":\"c m\"," ONE_FRAME, F,
                        "unit has a character other than letters, digits, '_', '.', '-' (byte 1)");
    expect_motion_error(HEAD "\"unit\":\"cm\\u0000\"," ONE_FRAME, F,
                        "unit: contains a NUL character");
    expect_motion_error(HEAD "\"unit\":\"centimetres-ish-x\"," ONE_FRAME, F,
                        "unit is 17 bytes long (at most 15)");
    /* joints */
    expect_motion_error("{\"fps\":30,\"joints\":[],\"frames\":[[]]}", F,
                        "joints: expected a non-empty array");
    expect_motion_error("{\"fps\":30,\"joints\":\"a\",\"frames\":[[]]}", F,
                        "joints: expected a non-empty array");
    expect_motion_error("{\"fps\":30,\"joints\":[\"a\",\"b\",\"\"],\"frames\":[[]]}", F,
                        "joints[2]: expected a non-empty string");
    expect_motion_error("{\"fps\":30,\"joints\":[\"a\",7],\"frames\":[[]]}", F,
                        "joints[1]: expected a non-empty string");
    expect_motion_error("{\"fps\":30,\"joints\":[\"a\\u0000b\"],\"frames\":[[[0,0,0]]]}", F,
                        "joints[0]: contains a NUL character");
    expect_motion_error("{\"fps\":30,\"joints\":[\"a\",\"a\"]," ONE_FRAME, F,
                        "joints 0 and 1 have the same name \"a\"");
    /* parents */
    expect_motion_error(HEAD "\"parents\":{}," ONE_FRAME, F,
                        "parents: expected an array of 2 integers, found object");
    expect_motion_error(HEAD "\"parents\":[-1]," ONE_FRAME, F,
                        "parents: expected 2 integers, found 1");
    expect_motion_error(HEAD "\"parents\":[-1,2]," ONE_FRAME, F,
                        "parents[1]: expected an integer from -1 to 1");
    expect_motion_error(HEAD "\"parents\":[-2,0]," ONE_FRAME, F,
                        "parents[0]: expected an integer from -1 to 1");
    expect_motion_error(HEAD "\"parents\":[-1,0.5]," ONE_FRAME, F,
                        "parents[1]: expected an integer from -1 to 1");
    expect_motion_error(HEAD "\"parents\":[-1,\"0\"]," ONE_FRAME, F,
                        "parents[1]: expected an integer from -1 to 1");
    expect_motion_error(HEAD "\"parents\":[null,0]," ONE_FRAME, F,
                        "parents[0]: expected an integer from -1 to 1");
    expect_motion_error(HEAD "\"parents\":[1,0]," ONE_FRAME, F,
                        "joint 0: parent indices form a cycle");
    expect_motion_error(HEAD "\"parents\":[0,-1]," ONE_FRAME, F, "joint 0: is its own parent");
    /* frames */
    expect_motion_error(HEAD "\"frames\":[]}", F, "frames: expected a non-empty array");
    expect_motion_error(HEAD "\"frames\":{}}", F, "frames: expected a non-empty array");
    expect_motion_error(HEAD "\"frames\":[[[0,0,0],[0,0,0]],5]}", F,
                        "frames[1]: expected an array of 2 joints, found number");
    expect_motion_error(HEAD "\"frames\":[[[0,0,0],[0,0,0]],[[0,0,0]]]}", F,
                        "frames[1]: expected 2 joints, found 1");
    expect_motion_error(HEAD "\"frames\":[[[0,0],[0,0,0]]]}", F,
                        "frames[0][0]: expected an array of 3 numbers");
    expect_motion_error(HEAD "\"frames\":[[[0,0,0],[0,0,0,0]]]}", F,
                        "frames[0][1]: expected an array of 3 numbers");
    expect_motion_error(HEAD "\"frames\":[[[0,0,0],[0,0,null]]]}", F,
                        "frames[0][1]: expected an array of 3 numbers");
    expect_motion_error(HEAD "\"frames\":[[[0,0,0],[0,\"1\",0]]]}", F,
                        "frames[0][1]: expected an array of 3 numbers");
    expect_motion_error(HEAD "\"frames\":[[[0,0,0],7]]}", F,
                        "frames[0][1]: expected an array of 3 numbers");
    expect_motion_error(HEAD "\"frames\":[[[0,0,0],[0,0,1e300]]]}", R,
                        "frames[0][1][2]: 1e+300 does not fit a 32-bit float");
    expect_motion_error(HEAD "\"frames\":[[[0,0,0],[0,0,0]],[[-3.5e38,0,0],[0,0,0]]]}", R,
                        "frames[1][0][0]: -3.5e+38 does not fit a 32-bit float");
    /* exactly half an ulp above FLT_MAX rounds (to even) to infinity; only the start of the
     * message is checked, as the long-double scaling of numparse differs under valgrind */
    const char *tie = HEAD "\"frames\":[[[0,0,0],[3.4028235677973366e38,0,0]]]}";
    affect_motion *m = NULL;
    affect_error err;
    assert_int_equal(affect_motion_from_json(tie, strlen(tie), &m, NULL, &err), R);
    assert_null(m);
    assert_true(strncmp(err.msg, "frames[0][1][0]: 3.40282356779733", 33) == 0);
#undef HEAD
#undef ONE_FRAME
}

/* Error messages that need long inputs: frame and joint indices in the tens, name lengths and
 * joint counts beyond the limits. */
/* The largest single request made while it is installed (issue 14: sizes from the input are
 * checked against what the input can hold before anything is allocated for them). */
static size_t largest_request;

static void *largest_malloc(size_t n)
{
    if (n > largest_request)
        largest_request = n;
    return malloc(n);
}

static void *largest_realloc(void *p, size_t n)
{
    if (n > largest_request)
        largest_request = n;
    return realloc(p, n);
}

static const affect_allocator largest_allocator = {largest_malloc, largest_realloc, free};

static void test_motion_sizes(void **state)
{
    (void)state;
    affect_strbuf sb;
    char *text;
    size_t len;

    /* 4096 joints and 4000 empty frames: 16,384,000 joint entries in 52 kB of text. The first
     * frame's joint count is the error, found before the 196 MB motion is allocated. */
    affect_strbuf_init(&sb);
    affect_strbuf_puts(&sb, "{\"fps\":30,\"joints\":[");
    for (int j = 0; j < 4096; j++)
        affect_strbuf_printf(&sb, "%s\"j%d\"", j ? "," : "", j);
    affect_strbuf_puts(&sb, "],\"frames\":[");
    for (int t = 0; t < 4000; t++)
        affect_strbuf_puts(&sb, t ? ",[]" : "[]");
    affect_strbuf_puts(&sb, "]}");
    assert_int_equal(affect_strbuf_finish(&sb, &text, &len, NULL), AFFECT_OK);
    largest_request = 0;
    affect_set_allocator(&largest_allocator);
    affect_motion *m = (affect_motion *)&m;
    affect_error err;
    affect_status st = affect_motion_from_json(text, len, &m, NULL, &err);
    affect_set_allocator(NULL);
    assert_int_equal(st, F);
    assert_null(m);
    assert_string_equal(err.msg, "frames[0]: expected 4096 joints, found 0");
    if (largest_request > 32 * len) /* the document's nodes take about 10 bytes per byte */
        fail_msg("a %zu-byte document made a request of %zu bytes", len, largest_request);
    affect_free(text);

    /* frames × joints above AFFECT_MOTION_MAX_SAMPLES (no option raises it here) */
    affect_strbuf_init(&sb);
    affect_strbuf_puts(&sb, "{\"fps\":30,\"joints\":[");
    for (int j = 0; j < 4096; j++)
        affect_strbuf_printf(&sb, "%s\"j%d\"", j ? "," : "", j);
    affect_strbuf_puts(&sb, "],\"frames\":[");
    for (int t = 0; t < 4097; t++)
        affect_strbuf_puts(&sb, t ? ",[]" : "[]");
    affect_strbuf_puts(&sb, "]}");
    assert_int_equal(affect_strbuf_finish(&sb, &text, NULL, NULL), AFFECT_OK);
    expect_motion_error(text, R,
                        "frames: 4097 frames x 4096 joints is 16781312 samples, above the limit "
                        "of 16777216");
    affect_free(text);
}

static void test_motion_errors_large(void **state)
{
    (void)state;
    affect_strbuf sb;
    char *text;

    /* 22 joints, 13 frames; frame 12 joint 3 is broken */
    affect_strbuf_init(&sb);
    affect_strbuf_puts(&sb, "{\"fps\":30,\"joints\":[");
    for (int j = 0; j < 22; j++)
        affect_strbuf_printf(&sb, "%s\"j%d\"", j ? "," : "", j);
    affect_strbuf_puts(&sb, "],\"frames\":[");
    for (int t = 0; t < 13; t++) {
        affect_strbuf_puts(&sb, t ? ",[" : "[");
        for (int j = 0; j < 22; j++)
            affect_strbuf_puts(&sb, t == 12 && j == 3 ? ",[1,2]" : j ? ",[1,2,3]" : "[1,2,3]");
        affect_strbuf_putc(&sb, ']');
    }
    affect_strbuf_puts(&sb, "]}");
    assert_int_equal(affect_strbuf_finish(&sb, &text, NULL, NULL), AFFECT_OK);
    expect_motion_error(text, F, "frames[12][3]: expected an array of 3 numbers");
    affect_free(text);

    /* 22 joints, frame 4 has 21 */
    affect_strbuf_init(&sb);
    affect_strbuf_puts(&sb, "{\"fps\":30,\"joints\":[");
    for (int j = 0; j < 22; j++)
        affect_strbuf_printf(&sb, "%s\"j%d\"", j ? "," : "", j);
    affect_strbuf_puts(&sb, "],\"parents\":[-1,0,1,2,3,99],\"frames\":[]}");
    assert_int_equal(affect_strbuf_finish(&sb, &text, NULL, NULL), AFFECT_OK);
    /* frames are checked for emptiness before parents */
    expect_motion_error(text, F, "frames: expected a non-empty array");
    affect_free(text);

    affect_strbuf_init(&sb);
    affect_strbuf_puts(&sb, "{\"fps\":30,\"joints\":[");
    for (int j = 0; j < 22; j++)
        affect_strbuf_printf(&sb, "%s\"j%d\"", j ? "," : "", j);
    affect_strbuf_puts(&sb, "],\"parents\":[");
    for (int j = 0; j < 22; j++)
        affect_strbuf_printf(&sb, "%s%d", j ? "," : "", j == 5 ? 22 : j - 1);
    affect_strbuf_puts(&sb, "],\"frames\":[");
    for (int t = 0; t < 5; t++) {
        affect_strbuf_puts(&sb, t ? ",[" : "[");
        for (int j = 0; j < (t == 4 ? 21 : 22); j++)
            affect_strbuf_puts(&sb, j ? ",[0,0,0]" : "[0,0,0]");
        affect_strbuf_putc(&sb, ']');
    }
    affect_strbuf_puts(&sb, "]}");
    assert_int_equal(affect_strbuf_finish(&sb, &text, NULL, NULL), AFFECT_OK);
    expect_motion_error(text, F, "parents[5]: expected an integer from -1 to 21");
    char *p = strstr(text, ",22,");
    assert_non_null(p);
    p[1] = '4';
    p[2] = ' '; /* parents[5] = 4, now valid */
    expect_motion_error(text, F, "frames[4]: expected 22 joints, found 21");
    affect_free(text);

    /* a name of 1025 bytes */
    affect_strbuf_init(&sb);
    affect_strbuf_puts(&sb, "{\"fps\":30,\"joints\":[\"a\",\"");
    for (int i = 0; i < 1025; i++)
        affect_strbuf_putc(&sb, 'n');
    affect_strbuf_puts(&sb, "\"],\"frames\":[[[0,0,0],[0,0,0]]]}");
    assert_int_equal(affect_strbuf_finish(&sb, &text, NULL, NULL), AFFECT_OK);
    expect_motion_error(text, R, "joints[1]: 1025 bytes long (at most 1024)");
    affect_free(text);

    /* 4097 joints */
    affect_strbuf_init(&sb);
    affect_strbuf_puts(&sb, "{\"fps\":30,\"joints\":[");
    for (int j = 0; j < 4097; j++)
        affect_strbuf_printf(&sb, "%s\"j%d\"", j ? "," : "", j);
    affect_strbuf_puts(&sb, "],\"frames\":[[]]}");
    assert_int_equal(affect_strbuf_finish(&sb, &text, NULL, NULL), AFFECT_OK);
    expect_motion_error(text, R, "joints: 4097 joints (at most 4096)");
    affect_free(text);
}

/* ---- out of memory ----
 * Every allocation fails in turn (tu_oom_sweep): each failure must report "out of memory",
 * produce nothing and leak nothing. */

static const char oom_motion[] =
    "{\"fps\":30,\"unit\":\"cm\",\"joints\":[\"Hips\",\"Spine\",\"Head\",\"LeftHand\"],"
    "\"parents\":[-1,0,1,1],\"frames\":["
    "[[0,90,0],[0,100,0],[0,160,0],[-40,120,5]],"
    "[[0.5,90.25,0],[0.5,100.25,0],[0.5,160.25,0],[-39.5,121,5]],"
    "[[1,90.5,0],[1,100.5,0],[1,160.5,1e-3],[-39,122,5]]]}";

static affect_status oom_from_json(void *ctx, affect_error *err)
{
    affect_motion **m = ctx;
    *m = NULL;
    return affect_motion_from_json(oom_motion, strlen(oom_motion), m, NULL, err);
}

static void oom_from_json_finish(void *ctx, affect_status st)
{
    affect_motion **m = ctx;
    if (st != AFFECT_OK) {
        assert_null(*m);
        return;
    }
    assert_int_equal((*m)->n_frames, 3);
    affect_motion_free(*m);
}

static void test_oom_motion_from_json(void **state)
{
    (void)state;
    affect_motion *m;
    /* the parse really allocates: doc, nodes, arena, motion, names */
    assert_true(tu_oom_sweep(oom_from_json, &m, oom_from_json_finish, NULL) >= 5);
}

typedef struct json_oom {
    const char *text;
    size_t len;
    affect_json_doc *doc;
} json_oom;

static affect_status oom_parse(void *ctx, affect_error *err)
{
    json_oom *j = ctx;
    j->doc = NULL;
    return affect_json_parse(j->text, j->len, &j->doc, NULL, err);
}

static void oom_parse_finish(void *ctx, affect_status st)
{
    json_oom *j = ctx;
    if (st != AFFECT_OK) {
        assert_null(j->doc);
        return;
    }
    assert_int_equal(affect_json_child(j->doc, affect_json_root(j->doc), 1)->count, 40);
    affect_json_free(j->doc);
}

static void test_oom_json_parse(void **state)
{
    (void)state;
    /* a big object (its key table moves to the heap) inside nested containers */
    affect_strbuf sb;
    affect_strbuf_init(&sb);
    affect_strbuf_puts(&sb, "[{\"a\":[1,{\"b\":2}]},{");
    for (int i = 0; i < 40; i++)
        affect_strbuf_printf(&sb, "%s\"key%d\":{\"x\":[%d,\"s\\u00e9\"]}", i ? "," : "", i, i);
    affect_strbuf_puts(&sb, "}]");
    json_oom j = {0};
    char *text;
    assert_int_equal(affect_strbuf_finish(&sb, &text, &j.len, NULL), AFFECT_OK);
    j.text = text;
    assert_true(tu_oom_sweep(oom_parse, &j, oom_parse_finish, NULL) >= 4);
    affect_free(text);
}

typedef struct json_write_oom {
    const affect_motion *m;
    char *text;
} json_write_oom;

static affect_status oom_to_json(void *ctx, affect_error *err)
{
    json_write_oom *w = ctx;
    w->text = NULL;
    return affect_motion_to_json(w->m, &w->text, NULL, NULL, err);
}

static void oom_to_json_finish(void *ctx, affect_status st)
{
    json_write_oom *w = ctx;
    if (st != AFFECT_OK)
        assert_null(w->text);
    affect_free(w->text);
}

static void test_oom_motion_to_json(void **state)
{
    (void)state;
    affect_motion *m = from_json_ok(oom_motion);
    json_write_oom w = {m, NULL};
    assert_true(tu_oom_sweep(oom_to_json, &w, oom_to_json_finish, NULL) >= 1);
    affect_motion_free(m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_accept_table),
        cmocka_unit_test(test_len_is_respected),
        cmocka_unit_test(test_reject_table),
        cmocka_unit_test(test_string_decoding),
        cmocka_unit_test(test_depth_limit),
        cmocka_unit_test(test_duplicate_keys),
        cmocka_unit_test(test_accessors),
        cmocka_unit_test(test_many_nodes),
        cmocka_unit_test(test_motion_round_trip),
        cmocka_unit_test(test_motion_exact_output),
        cmocka_unit_test(test_motion_defaults),
        cmocka_unit_test(test_motion_errors),
        cmocka_unit_test(test_motion_errors_large),
        cmocka_unit_test(test_motion_sizes),
        cmocka_unit_test(test_oom_motion_from_json),
        cmocka_unit_test(test_oom_json_parse),
        cmocka_unit_test(test_oom_motion_to_json),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
