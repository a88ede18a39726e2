/*
 * test_bytes.c — the little-endian writer and bounds-checked reader (util/bytes.h): exact
 * byte layout, round trips, every truncation refused without reading past the end, and the
 * writer's sticky failure under out-of-memory; the header and checksum helpers with their one
 * wording of magic, version and truncation errors.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>

#include <cmocka.h>
#include <math.h>
#include <string.h>

#include "util/bytes.h"
#include "affect/hmm_blob.h" /* affect_fnv1a64 */
#include "testutil.h"

static void write_all(affect_bw *w)
{
    static const double d[2] = {1.5, -0.0};
    static const float f[2] = {0.25f, -3.0f};
    static const uint32_t u[2] = {7u, 0xdeadbeefu};
    affect_bw_u8(w, 0xab);
    affect_bw_u32(w, 0x01020304u);
    affect_bw_u64(w, 0x1122334455667788ull);
    affect_bw_f64(w, 1.0);
    affect_bw_f64s(w, d, 2);
    affect_bw_f32s(w, f, 2);
    affect_bw_u32s(w, u, 2);
    affect_bw_bytes(w, "xyz", 3);
}

#define TOTAL (1 + 4 + 8 + 8 + 16 + 8 + 8 + 3)

static void test_layout(void **state)
{
    (void)state;
    affect_bw w;
    affect_bw_init(&w);
    write_all(&w);
    assert_false(w.failed);
    assert_int_equal(w.len, TOTAL);
    static const unsigned char head[] = {0xab, 0x04, 0x03, 0x02, 0x01, 0x88, 0x77,
                                         0x66, 0x55, 0x44, 0x33, 0x22, 0x11, 0,
                                         0,    0,    0,    0,    0,    0xf0, 0x3f};
    assert_memory_equal(w.data, head, sizeof head);
    assert_memory_equal(w.data + TOTAL - 3, "xyz", 3);
    affect_bw_free(&w);
    assert_null(w.data);
}

/* Reads everything back; returns false at the first field that does not fit. */
static bool read_all(affect_br *r)
{
    uint8_t b;
    uint32_t u32, u[2];
    uint64_t u64;
    double x, d[2];
    float f[2];
    const unsigned char *p;
    if (!affect_br_u8(r, &b) || !affect_br_u32(r, &u32) || !affect_br_u64(r, &u64) ||
        !affect_br_f64(r, &x) || !affect_br_f64s(r, d, 2) || !affect_br_f32s(r, f, 2) ||
        !affect_br_u32s(r, u, 2) || !affect_br_bytes(r, &p, 3))
        return false;
    assert_int_equal(b, 0xab);
    assert_int_equal(u32, 0x01020304u);
    assert_true(u64 == 0x1122334455667788ull);
    assert_true(x == 1.0 && d[0] == 1.5 && d[1] == 0.0 && signbit(d[1]));
    assert_true(f[0] == 0.25f && f[1] == -3.0f);
    assert_int_equal(u[0], 7u);
    assert_int_equal(u[1], 0xdeadbeefu);
    assert_memory_equal(p, "xyz", 3);
    return true;
}

static void test_round_trip_and_truncation(void **state)
{
    (void)state;
    affect_bw w;
    affect_bw_init(&w);
    write_all(&w);
    affect_br r;
    affect_br_init(&r, w.data, w.len);
    assert_true(read_all(&r));
    assert_int_equal(r.off, w.len);
    assert_false(affect_br_has(&r, 1, 1));
    for (size_t cut = 0; cut < w.len;
         cut++) { /* a copy of exactly cut bytes: ASan sees overreads */
        unsigned char *copy = cut ? affect_malloc(cut) : NULL;
        if (cut)
            memcpy(copy, w.data, cut);
        affect_br_init(&r, copy, cut);
        assert_false(read_all(&r));
        assert_true(r.off <= cut);
        affect_free(copy);
    }
    affect_br_init(&r, w.data, w.len);
    assert_false(affect_br_has(&r, SIZE_MAX / 2, 8)); /* overflow-safe */
    affect_bw_free(&w);
}

static affect_status oom_op(void *ctx, affect_error *err)
{
    (void)ctx;
    affect_bw w;
    affect_bw_init(&w);
    for (int i = 0; i < 100; i++)
        write_all(&w);
    bool failed = w.failed;
    size_t len = w.len;
    affect_bw_free(&w);
    if (failed)
        return affect_nomem(err);
    assert_int_equal(len, 100 * TOTAL);
    return AFFECT_OK;
}

static void test_out_of_memory(void **state)
{
    (void)state;
    assert_true(tu_oom_sweep(oom_op, NULL, NULL, NULL) > 1);
}

static void test_header_and_checksum(void **state)
{
    (void)state;
    affect_bw w;
    affect_bw_init(&w);
    affect_bw_u8(&w, 0xee); /* a record after other bytes */
    affect_bw_header(&w, "ABCD", 2, 0x0301);
    affect_bw_u16(&w, 0xbeef);
    affect_bw_checksum(&w, 1);
    assert_false(w.failed);
    static const unsigned char want[] = {0xee, 'A', 'B', 'C', 'D', 2,    0,   0,
                                         0,    1,   3,   0,   0,   0xef, 0xbe};
    assert_int_equal(w.len, sizeof want + 8);
    assert_memory_equal(w.data, want, sizeof want);
    assert_true(affect_checksum_ok(w.data + 1, sizeof want - 1));
    assert_int_equal(affect_get_u64(w.data + sizeof want),
                     affect_fnv1a64(w.data + 1, sizeof want - 1));
    /* the pointer loads and stores agree with the writer */
    unsigned char b[8];
    affect_put_u16(b, 0xbeef);
    assert_int_equal(affect_get_u16(b), 0xbeef);
    affect_put_u32(b, 0x01020304u);
    assert_int_equal(b[0], 4);
    assert_int_equal(affect_get_u32(b), 0x01020304u);
    affect_put_f64(b, -2.5);
    assert_true(affect_get_f64(b) == -2.5);
    w.data[sizeof want] ^= 1;
    assert_false(affect_checksum_ok(w.data + 1, sizeof want - 1));

    affect_br r;
    affect_error err;
    uint32_t version, flags;
    uint16_t u16;
    affect_br_init(&r, w.data, w.len);
    r.off = 1;
    assert_int_equal(affect_br_header(&r, "ABCD", 2, NULL, "an abcd", &version, &flags, &err),
                     AFFECT_OK);
    assert_int_equal(version, 2);
    assert_int_equal(flags, 0x0301);
    assert_int_equal(r.off, 13);
    assert_true(affect_br_u16(&r, &u16) && u16 == 0xbeef);
    /* errors: one wording, nothing consumed */
    r.off = 1;
    assert_int_equal(affect_br_header(&r, "ABCD", 1, "X: ", "an abcd", &version, &flags, &err),
                     AFFECT_ERR_FORMAT);
    assert_string_equal(err.msg, "X: unknown format version 2 (this build reads 1 .. 1)");
    assert_int_equal(r.off, 1);
    assert_int_equal(affect_br_header(&r, "ABCE", 2, NULL, "an abce", &version, &flags, &err),
                     AFFECT_ERR_FORMAT);
    assert_string_equal(err.msg, "not an abce (bad magic bytes at offset 1)");
    affect_br_init(&r, w.data, 12);
    r.off = 1;
    assert_int_equal(affect_br_header(&r, "ABCD", 2, NULL, "an abcd", &version, &flags, &err),
                     AFFECT_ERR_FORMAT);
    assert_string_equal(err.msg, "truncated: 11 bytes is shorter than the 12-byte header");
    assert_int_equal(affect_check_version(0, 3, NULL, &err), AFFECT_ERR_FORMAT);
    assert_string_equal(err.msg, "unknown format version 0 (this build reads 1 .. 3)");
    assert_int_equal(affect_check_version(3, 3, NULL, &err), AFFECT_OK);
    /* named fields */
    uint32_t u32;
    double d;
    affect_br_init(&r, w.data, 3);
    assert_int_equal(affect_br_u32_field(&r, &u32, "R: ", "the count", &err), AFFECT_ERR_FORMAT);
    assert_string_equal(err.msg, "R: truncated in the count (offset 0)");
    assert_int_equal(affect_br_need(&r, 2, 1, NULL, "x", &err), AFFECT_OK);
    assert_int_equal(affect_br_need(&r, 2, 2, NULL, "the pairs", &err), AFFECT_ERR_FORMAT);
    assert_string_equal(err.msg, "truncated in the pairs (offset 0)");
    affect_br_init(&r, w.data, w.len);
    assert_int_equal(affect_br_f64_field(&r, &d, NULL, "x", &err), AFFECT_OK);
    assert_int_equal(r.off, 8);
    affect_bw_free(&w);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_layout),
        cmocka_unit_test(test_round_trip_and_truncation),
        cmocka_unit_test(test_out_of_memory),
        cmocka_unit_test(test_header_and_checksum),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
