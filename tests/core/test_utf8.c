/*
 * test_utf8.c — names are UTF-8 and messages are UTF-8 (issue 14, item 6): the validator of
 * base.h (overlongs, surrogates, code points above U+10FFFF, NUL, cut sequences), the escaping
 * of every error message, and each place a name enters the library — the motion BLOB decoder,
 * affect_motion_set_name, the BVH, CSV and JSON importers, the feature definition inside a
 * model BLOB, the classifier's labels — refusing one that is not UTF-8, with the encoder
 * refusing to write one.
 */
#include <stdio.h>
#include <string.h>

#include "testutil.h"

#include "affect/classifier.h"
#include "affect/features.h"
#include "affect/hmm.h"
#include "affect/hmm_blob.h"
#include "affect/io.h"

/* Whether s (NUL-terminated) is valid UTF-8, by an independent decoder: code point by code
 * point, comparing with the shortest form. */
static bool reference_valid(const unsigned char *s, size_t n)
{
    size_t i = 0;
    while (i < n) {
        unsigned c = s[i];
        uint32_t cp;
        size_t k;
        if (c == 0)
            return false;
        if (c < 0x80)
            k = 1, cp = c;
        else if ((c & 0xE0) == 0xC0)
            k = 2, cp = c & 0x1F;
        else if ((c & 0xF0) == 0xE0)
            k = 3, cp = c & 0x0F;
        else if ((c & 0xF8) == 0xF0)
            k = 4, cp = c & 0x07;
        else
            return false;
        if (n - i < k)
            return false;
        for (size_t j = 1; j < k; j++) {
            if ((s[i + j] & 0xC0) != 0x80)
                return false;
            cp = (cp << 6) | (s[i + j] & 0x3F);
        }
        uint32_t min = k == 1 ? 0 : k == 2 ? 0x80 : k == 3 ? 0x800 : 0x10000;
        if (cp < min || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF))
            return false;
        i += k;
    }
    return true;
}

static void test_validator(void **state)
{
    (void)state;
    struct {
        const char *s;
        size_t n;
        size_t bad; /* offset of the first invalid byte, n when valid */
    } cases[] = {
        {"Hips", 4, 4},
        {"", 0, 0},
        {"h\xC3\xA9", 3, 3},        /* é */
        {"\xE2\x82\xAC", 3, 3},     /* € */
        {"\xF0\x9F\x98\x80", 4, 4}, /* U+1F600 */
        {"\xF4\x8F\xBF\xBF", 4, 4}, /* U+10FFFF, the last code point */
        {"\xEF\xBF\xBF", 3, 3},     /* U+FFFF: a noncharacter, but valid UTF-8 */
        {"ab\xFF", 3, 2},           /* never in UTF-8 */
        {"\x80", 1, 0},             /* stray continuation byte */
        {"\xC0\xAF", 2, 0},         /* overlong '/' */
        {"\xC1\xBF", 2, 0},         /* overlong */
        {"\xE0\x80\xAF", 3, 0},     /* overlong '/' in 3 bytes */
        {"\xE0\x9F\xBF", 3, 0},     /* overlong U+07FF */
        {"\xF0\x8F\xBF\xBF", 4, 0}, /* overlong U+FFFF */
        {"x\xED\xA0\x80", 4, 1},    /* U+D800, a surrogate */
        {"\xED\xBF\xBF", 3, 0},     /* U+DFFF */
        {"\xED\x9F\xBF", 3, 3},     /* U+D7FF, just below */
        {"\xF4\x90\x80\x80", 4, 0}, /* U+110000 */
        {"\xF5\x80\x80\x80", 4, 0}, /* lead byte past U+10FFFF */
        {"a\xC3", 2, 1},            /* cut short */
        {"\xE2\x82", 2, 0},         /* cut short */
        {"\xE2\x82x", 3, 0},        /* continuation missing */
        {"a\0b", 3, 1},             /* NUL inside */
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        size_t got = affect_utf8_invalid_at(cases[i].s, cases[i].n);
        if (got != cases[i].bad)
            fail_msg("case %zu: invalid at %zu, expected %zu", i, got, cases[i].bad);
        assert_int_equal(affect_utf8_valid(cases[i].s, cases[i].n), cases[i].bad == cases[i].n);
    }
    /* every 1-, 2- and 3-byte string, and 4-byte strings around every lead byte, against the
     * reference decoder */
    unsigned char b[4];
    for (unsigned x = 0; x < 256; x++) {
        b[0] = (unsigned char)x;
        assert_int_equal(affect_utf8_valid((char *)b, 1), reference_valid(b, 1));
        for (unsigned y = 0; y < 256; y++) {
            b[1] = (unsigned char)y;
            assert_int_equal(affect_utf8_valid((char *)b, 2), reference_valid(b, 2));
            for (unsigned z = 0x70; z < 0xC8; z++) {
                b[2] = (unsigned char)z;
                if (affect_utf8_valid((char *)b, 3) != reference_valid(b, 3))
                    fail_msg("%02x %02x %02x", x, y, z);
                b[3] = 0x80;
                if (affect_utf8_valid((char *)b, 4) != reference_valid(b, 4))
                    fail_msg("%02x %02x %02x 80", x, y, z);
            }
        }
    }
    affect_error err;
    assert_int_equal(affect_utf8_check(&err, AFFECT_ERR_FORMAT, "ok", 2, "name"), AFFECT_OK);
    assert_int_equal(affect_utf8_check(&err, AFFECT_ERR_FORMAT, "ab\xFF", 3, "joint %d: name", 3),
                     AFFECT_ERR_FORMAT);
    assert_string_equal(err.msg, "joint 3: name is not valid UTF-8 (byte 0xff at offset 2)");
    assert_int_equal(affect_utf8_check(NULL, AFFECT_ERR_INVALID, "\xC0\x80", 2, "x"),
                     AFFECT_ERR_INVALID);
}

static void test_escape(void **state)
{
    (void)state;
    char out[64];
    /* valid UTF-8 is kept, control bytes and invalid bytes escaped */
    const char in[] = "a\n\xC3\xA9\xFF\xED\xA0\x80\x7F\xE2\x82";
    assert_int_equal(affect_escape_text(out, sizeof out, in, sizeof in - 1), 35);
    assert_string_equal(out, "a\\x0a\xC3\xA9\\xff\\xed\\xa0\\x80\\x7f\\xe2\\x82");
    /* escaping escaped text changes nothing */
    char again[64];
    affect_escape_text(again, sizeof again, out, strlen(out));
    assert_string_equal(again, out);
    /* the copy ends before a sequence or an escape that does not fit */
    assert_int_equal(affect_escape_text(out, 3, "a\xC3\xA9", 3), 1);
    assert_string_equal(out, "a");
    assert_int_equal(affect_escape_text(out, 5, "ab\xFF", 3), 2);
    assert_string_equal(out, "ab");
    assert_int_equal(affect_escape_text(out, 1, "abc", 3), 0);
    assert_string_equal(out, "");
    /* every byte value, alone and after a valid prefix: always valid UTF-8 out */
    for (unsigned c = 1; c < 256; c++) {
        char s[3] = {'x', (char)c, (char)0xA9};
        for (size_t n = 1; n <= 3; n++) {
            size_t len = affect_escape_text(out, sizeof out, s, n);
            assert_int_equal(len, strlen(out));
            assert_true(affect_utf8_valid(out, len));
        }
    }
}

static void test_fail_escapes(void **state)
{
    (void)state;
    affect_error err;
    /* a quoted name with a byte that is not UTF-8 */
    assert_int_equal(affect_fail(&err, AFFECT_ERR_FORMAT, "no joint named \"%s\"", "Hi\xFFps"),
                     AFFECT_ERR_FORMAT);
    assert_string_equal(err.msg, "no joint named \"Hi\\xffps\"");
    /* valid multi-byte text is kept as it is, control bytes escaped as before */
    affect_fail(&err, AFFECT_ERR_FORMAT, "\"%s\" \"%s\"", "T\xC3\xAAte", "a\tb");
    assert_string_equal(err.msg, "\"T\xC3\xAAte\" \"a\\x09b\"");
    /* a sequence cut by the message's length limit becomes an escape, not half a character */
    char longname[AFFECT_ERROR_MSG_MAX + 8];
    memset(longname, 'a', sizeof longname);
    for (size_t i = 250; i + 2 < sizeof longname; i += 2)
        longname[i] = (char)0xC3, longname[i + 1] = (char)0xA9;
    longname[sizeof longname - 1] = '\0';
    affect_fail(&err, AFFECT_ERR_FORMAT, "%s", longname);
    assert_true(affect_utf8_valid(err.msg, strlen(err.msg)));
    assert_true(strlen(err.msg) < AFFECT_ERROR_MSG_MAX);
    /* a prefix keeps the message valid */
    affect_fail(&err, AFFECT_ERR_FORMAT, "bad \xE2\x82");
    affect_prefix(&err, "motion \"%s\"", "\xF0\x9F");
    assert_string_equal(err.msg, "motion \"\\xf0\\x9f\": bad \\xe2\\x82");
}

/* 1 frame × 2 joints named "H\xC3\xA9" (Hé) and "b". */
static affect_motion *make_named(void)
{
    affect_motion *m = NULL;
    affect_error err;
    assert_int_equal(affect_motion_create(1, 2, 30.0, &m, &err), AFFECT_OK);
    assert_int_equal(affect_motion_set_name(m, 0, "H\xC3\xA9", 3, &err), AFFECT_OK);
    assert_int_equal(affect_motion_set_name(m, 1, "b", 1, &err), AFFECT_OK);
    return m;
}

static void test_motion_decode(void **state)
{
    (void)state;
    affect_motion *m = make_named(), *out = NULL;
    affect_error err;
    unsigned char *blob;
    size_t size;
    assert_int_equal(affect_motion_encode(m, &blob, &size, &err), AFFECT_OK);
    assert_int_equal(affect_motion_decode(blob, size, &out, &err), AFFECT_OK);
    assert_string_equal(out->names[0], "H\xC3\xA9");
    affect_motion_free(out);
    /* the name of joint 0 starts at 32 + 2 (no unit, 2-byte length) */
    const size_t at = 34;
    assert_memory_equal(blob + at, "H\xC3\xA9", 3);
    struct {
        unsigned char b1, b2; /* the bytes of "é" replaced */
        const char *message;
    } cases[] = {
        {0xFF, 0xA9, "joint 0: name is not valid UTF-8 (byte 0xff at offset 1)"},
        {0xC1, 0xA9, "joint 0: name is not valid UTF-8 (byte 0xc1 at offset 1)"}, /* overlong */
        {0xC3, 0x41, "joint 0: name is not valid UTF-8 (byte 0xc3 at offset 1)"}, /* cut */
        {0xA9, 0xA9, "joint 0: name is not valid UTF-8 (byte 0xa9 at offset 1)"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        blob[at + 1] = cases[i].b1;
        blob[at + 2] = cases[i].b2;
        out = NULL;
        assert_int_equal(affect_motion_decode(blob, size, &out, &err), AFFECT_ERR_FORMAT);
        assert_string_equal(err.msg, cases[i].message);
        assert_null(out);
    }
    affect_free(blob);
    affect_motion_free(m);

    /* a 3-byte name: an encoded surrogate; a 4-byte name: above U+10FFFF */
    assert_int_equal(affect_motion_create(1, 2, 30.0, &m, &err), AFFECT_OK);
    assert_int_equal(affect_motion_set_name(m, 0, "\xE2\x82\xAC", 3, &err), AFFECT_OK);
    assert_int_equal(affect_motion_set_name(m, 1, "\xF0\x9F\x98\x80", 4, &err), AFFECT_OK);
    assert_int_equal(affect_motion_encode(m, &blob, &size, &err), AFFECT_OK);
    memcpy(blob + 34, "\xED\xA0\x80", 3);
    assert_int_equal(affect_motion_decode(blob, size, &out, &err), AFFECT_ERR_FORMAT);
    assert_string_equal(err.msg, "joint 0: name is not valid UTF-8 (byte 0xed at offset 0)");
    memcpy(blob + 34, "\xE2\x82\xAC", 3);
    memcpy(blob + 39, "\xF4\x90\x80\x80", 4);
    assert_int_equal(affect_motion_decode(blob, size, &out, &err), AFFECT_ERR_FORMAT);
    assert_string_equal(err.msg, "joint 1: name is not valid UTF-8 (byte 0xf4 at offset 0)");
    affect_free(blob);
    affect_motion_free(m);
}

static void test_motion_api(void **state)
{
    (void)state;
    affect_motion *m = make_named();
    affect_error err;
    /* set_name refuses the name and keeps the old one */
    assert_int_equal(affect_motion_set_name(m, 1, "x\xFF", 2, &err), AFFECT_ERR_FORMAT);
    assert_string_equal(err.msg, "joint 1: name is not valid UTF-8 (byte 0xff at offset 1)");
    assert_string_equal(m->names[1], "b");
    /* a name written into the struct directly: validate says so, and nothing encodes it */
    m->names[1][0] = (char)0xFF;
    assert_int_equal(affect_motion_validate(m, &err), AFFECT_ERR_FORMAT);
    assert_string_equal(err.msg, "joint 1: name is not valid UTF-8 (byte 0xff at offset 0)");
    size_t size = 0;
    assert_false(affect_motion_encoded_size(m, &size));
    unsigned char *blob = NULL;
    assert_int_equal(affect_motion_encode(m, &blob, &size, &err), AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "cannot encode the motion: joint 1: name is not valid UTF-8 "
                                 "(byte 0xff at offset 0)");
    assert_null(blob);
    /* clone copies through set_name, so it refuses too */
    affect_motion *c = NULL;
    assert_int_equal(affect_motion_clone(m, &c, &err), AFFECT_ERR_FORMAT);
    assert_null(c);
    affect_motion_free(m);
}

static void test_bvh(void **state)
{
    (void)state;
    char text[512];
    const char *fmt = "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 3 Xposition "
                      "Yposition Zposition\n  JOINT %s\n  {\n    OFFSET 0 1 0\n    CHANNELS 0\n"
                      "  }\n}\nMOTION\nFrames: 1\nFrame Time: 0.04\n0 0 0\n";
    affect_motion *m = NULL;
    affect_error err;
    snprintf(text, sizeof text, fmt, "T\xC3\xAAte");
    assert_int_equal(affect_bvh_parse(text, strlen(text), NULL, &m, &err), AFFECT_OK);
    assert_string_equal(m->names[1], "T\xC3\xAAte");
    affect_motion_free(m);
    m = NULL;
    snprintf(text, sizeof text, fmt,
             "Ch\xFF"
             "est");
    assert_int_equal(affect_bvh_parse(text, strlen(text), NULL, &m, &err), AFFECT_ERR_FORMAT);
    assert_string_equal(err.msg, "line 6: joint name is not valid UTF-8 (byte 0xff at offset 2)");
    assert_null(m);
    /* Latin-1 text (é as the single byte 0xe9), the common case of a file not in UTF-8 */
    snprintf(text, sizeof text, fmt, "T\xE9te");
    assert_int_equal(affect_bvh_parse(text, strlen(text), NULL, &m, &err), AFFECT_ERR_FORMAT);
    assert_string_equal(err.msg, "line 6: joint name is not valid UTF-8 (byte 0xe9 at offset 1)");
    /* the longest names, suffixed when they repeat, are cut between characters: a name of
     * 1016 bytes ("a", 507 × "é", "b") twice, so the second gets "_2" after 1012 bytes at
     * most, and byte 1012 is the middle of an "é" */
    char name[1017];
    name[0] = 'a';
    for (size_t i = 1; i < 1015; i += 2)
        name[i] = (char)0xC3, name[i + 1] = (char)0xA9;
    name[1015] = 'b';
    name[1016] = '\0';
    char *big = malloc(4096);
    snprintf(big, 4096,
             "HIERARCHY\nROOT %s\n{\n  OFFSET 0 0 0\n  CHANNELS 0\n  JOINT %s\n  {\n"
             "    OFFSET 0 1 0\n    CHANNELS 0\n    End Site\n    {\n      OFFSET 0 1 0\n    }\n"
             "  }\n}\nMOTION\nFrames: 1\nFrame Time: 0.04\n\n",
             name, name);
    assert_int_equal(affect_bvh_parse(big, strlen(big), NULL, &m, &err), AFFECT_OK);
    assert_int_equal(m->n_joints, 3);
    for (uint32_t j = 0; j < 3; j++)
        assert_true(affect_utf8_valid(m->names[j], strlen(m->names[j])));
    assert_int_equal(strlen(m->names[1]), 1011 + 2); /* 1012 would cut an "é" */
    assert_string_equal(m->names[1] + 1011, "_2");
    assert_memory_equal(m->names[1], name, 1011);
    assert_int_equal(strlen(m->names[2]), 1013 + 4); /* "<parent>_end" */
    affect_motion_free(m);
    free(big);
}

static void test_csv_json(void **state)
{
    (void)state;
    affect_motion *m = NULL;
    affect_error err;
    const char good[] = "H\xC3\xA9.x,H\xC3\xA9.y,H\xC3\xA9.z\n1,2,3\n";
    assert_int_equal(affect_csv_parse(good, sizeof good - 1, 30, NULL, &m, &err), AFFECT_OK);
    assert_string_equal(m->names[0], "H\xC3\xA9");
    affect_motion_free(m);
    m = NULL;
    const char bad[] = "a.x,a.y,a.z,b\xFF.x,b\xFF.y,b\xFF.z\n1,2,3,4,5,6\n";
    assert_int_equal(affect_csv_parse(bad, sizeof bad - 1, 30, NULL, &m, &err), AFFECT_ERR_FORMAT);
    assert_string_equal(err.msg, "row 1, column 4: the joint name is not valid UTF-8 "
                                 "(byte 0xff at offset 1)");
    assert_null(m);
    /* a message quoting a CSV field with such a byte stays valid UTF-8 */
    const char field[] = "a.x,a.y,a.z\n1,\xFF,3\n";
    assert_int_equal(affect_csv_parse(field, sizeof field - 1, 30, NULL, &m, &err),
                     AFFECT_ERR_FORMAT);
    assert_true(affect_utf8_valid(err.msg, strlen(err.msg)));
    assert_non_null(strstr(err.msg, "\\xff"));
    /* JSON refuses such text already (the parser checks UTF-8) */
    const char json[] = "{\"fps\":30,\"joints\":[\"a\xFF\"],\"frames\":[[[1,2,3]]]}";
    assert_int_equal(affect_motion_from_json(json, sizeof json - 1, &m, NULL, &err),
                     AFFECT_ERR_FORMAT);
    assert_string_equal(err.msg, "at byte 22: invalid UTF-8");
}

/* Replaces the first occurrence of what in blob with a 0xff byte first, and recomputes the
 * trailing checksum (the last 8 bytes, FNV-1a 64 of the rest). */
static void spoil(unsigned char *blob, size_t size, const char *what)
{
    size_t n = strlen(what);
    for (size_t i = 0; i + n <= size; i++)
        if (memcmp(blob + i, what, n) == 0) {
            blob[i] = 0xFF;
            uint64_t h = affect_fnv1a64(blob, size - 8);
            for (int b = 0; b < 8; b++)
                blob[size - 8 + (size_t)b] = (unsigned char)(h >> (8 * b));
            return;
        }
    fail_msg("\"%s\" not found in the BLOB", what);
}

static void test_model_blobs(void **state)
{
    (void)state;
    size_t len;
    affect_error err;
    /* a feature name inside a model BLOB */
    unsigned char *data = (unsigned char *)tu_read_file(AFFECT_FIXTURES_DIR "/hmm-v1.bin", &len);
    assert_non_null(data);
    spoil(data, len, "Hips");
    affect_hmm *h = NULL;
    affect_features *f = NULL;
    assert_int_equal(affect_hmm_blob_decode(data, len, &h, &f, &err), AFFECT_ERR_FORMAT);
    assert_string_equal(err.msg, "feature definition at offset 80: joint entry 1 is not valid "
                                 "UTF-8 (byte 0xff at offset 0)");
    assert_null(h);
    free(data);
    /* a class label of a classifier BLOB */
    data = (unsigned char *)tu_read_file(AFFECT_FIXTURES_DIR "/classifier-v1.bin", &len);
    assert_non_null(data);
    spoil(data, len, "angry");
    affect_classifier *c = NULL;
    assert_int_equal(affect_classifier_decode(data, len, &c, &err), AFFECT_ERR_FORMAT);
    assert_string_equal(err.msg, "label 0 (offset 20) is not valid UTF-8 (byte 0xff at offset 0)");
    assert_null(c);
    free(data);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_validator),    cmocka_unit_test(test_escape),
        cmocka_unit_test(test_fail_escapes), cmocka_unit_test(test_motion_decode),
        cmocka_unit_test(test_motion_api),   cmocka_unit_test(test_bvh),
        cmocka_unit_test(test_csv_json),     cmocka_unit_test(test_model_blobs),
    };
    return cmocka_run_group_tests_name("utf8", tests, NULL, NULL);
}
