/*
 * test_quant.c — the compact storage of long vectors (util/quant.h).
 *
 * Checked: 24-bit floats round to 12 mantissa bits to nearest, ties to even, carry into the
 * exponent, keep the sign and every exponent (1e-300 .. 1e300, subnormals), give a non-finite
 * value only next to DBL_MAX, and read back to the bit; the 4-bit form's sizes, its rounding
 * (scale = max / 7 as float32, codes −7 .. 7, the largest magnitude exactly 7 × scale, an error
 * of at most half a step per value), the factors, idempotence, bytes that read back to the same
 * values and re-encode to the same bytes, blocks of zeros and of values too small for a
 * normal float32 scale, the short last block and the odd nibble; affect_q4_fits refuses
 * non-finite products and scales beyond float32; every non-canonical input is refused at its
 * byte (code −8, a non-zero code under a zero scale, a negative, subnormal, infinite or NaN
 * scale, a scale whose block has no code of magnitude 7, a non-zero padding nibble).
 */
#include <float.h>
#include <stdint.h>
#include <string.h>

#include "testutil.h"

#include "util/quant.h"

static uint64_t bits_of(double v)
{
    uint64_t u;
    memcpy(&u, &v, sizeof u);
    return u;
}

static double of_bits(uint64_t u)
{
    double v;
    memcpy(&v, &u, sizeof v);
    return v;
}

static void test_f24(void **state)
{
    (void)state;
    const uint64_t one = bits_of(1.0), ulp = (uint64_t)1 << 40;
    assert_true(affect_f24_round(1.0) == 1.0);
    /* below, at and above half a step; ties to even */
    assert_true(affect_f24_round(of_bits(one + (ulp / 2 - 1))) == 1.0);
    assert_true(affect_f24_round(of_bits(one + ulp / 2)) == 1.0); /* tie, 1.0 is even */
    assert_true(affect_f24_round(of_bits(one + ulp + ulp / 2)) == of_bits(one + 2 * ulp));
    assert_true(affect_f24_round(of_bits(one + ulp / 2 + 1)) == of_bits(one + ulp));
    /* the carry into the exponent: just under 2 rounds to 2 */
    assert_true(affect_f24_round(nextafter(2.0, 0.0)) == 2.0);
    assert_true(affect_f24_round(-3.0) == -3.0);
    /* relative error ≤ 2^-13 over the whole range, and the bytes read back */
    const double values[] = {1e-300, -2.5e-310,   0.1,    -0.333, 7.0,
                             1e10,   3.14159e200, -1e300, 0.0,    1234.5678};
    for (size_t i = 0; i < sizeof values / sizeof values[0]; i++) {
        double v = values[i], r = affect_f24_round(v);
        assert_true(isfinite(r));
        if (fabs(v) >= DBL_MIN)
            assert_true(fabs(r - v) <= ldexp(fabs(v), -13));
        assert_true(affect_f24_round(r) == r);
        affect_bw w;
        affect_bw_init(&w);
        affect_f24_write(&w, v);
        assert_false(w.failed);
        assert_int_equal(w.len, 3);
        affect_br rd;
        affect_br_init(&rd, w.data, w.len);
        double back = affect_f24_read(&rd);
        assert_int_equal(bits_of(back), bits_of(r));
        assert_int_equal(rd.off, 3);
        affect_bw_free(&w);
    }
    assert_false(isfinite(affect_f24_round(DBL_MAX)));
}

static void test_q4_sizes(void **state)
{
    (void)state;
    size_t b;
    assert_true(affect_q4_size(0, &b) && b == 0);
    assert_true(affect_q4_size(1, &b) && b == 4 + 1);
    assert_true(affect_q4_size(64, &b) && b == 4 + 32);
    assert_true(affect_q4_size(65, &b) && b == 8 + 33);
    assert_true(affect_q4_size(667331, &b) && b == 4 * 10428 + 333666);
}

/* Writes v (n values) and reads it back: the same doubles; the bytes again the same. */
static void round_trip(const double *v, size_t n, affect_bw *w)
{
    affect_bw_init(w);
    affect_q4_write(w, v, n);
    assert_false(w->failed);
    size_t bytes;
    assert_true(affect_q4_size(n, &bytes));
    assert_int_equal(w->len, bytes);
    double *back = malloc((n ? n : 1) * sizeof *back);
    assert_non_null(back);
    affect_br r;
    affect_br_init(&r, w->data, w->len);
    size_t bad = 0;
    assert_true(affect_q4_read(&r, back, n, &bad));
    assert_int_equal(r.off, bytes);
    for (size_t i = 0; i < n; i++)
        assert_int_equal(bits_of(back[i]), bits_of(v[i]));
    affect_bw again;
    affect_bw_init(&again);
    affect_q4_write(&again, back, n);
    assert_int_equal(again.len, w->len);
    assert_memory_equal(again.data, w->data, w->len);
    affect_bw_free(&again);
    free(back);
}

static void test_q4_round(void **state)
{
    (void)state;
    enum { N = 64 * 3 + 7 }; /* three full blocks and a short, odd one */
    double v[N], orig[N], factor[N];
    for (size_t i = 0; i < N; i++) {
        orig[i] = sin(0.37 * (double)i + 0.1) * (1.0 + (double)(i % 5)) * 1e-3;
        factor[i] = 1.0 + 1e-4 * (double)(i % 3);
    }
    orig[10] = 0.0;
    for (size_t i = 64; i < 128; i++) /* a block of zeros */
        orig[i] = 0.0;
    memcpy(v, orig, sizeof v);
    assert_true(affect_q4_fits(v, N, factor));
    affect_q4_round(v, N, factor);
    for (size_t b = 0; b < N; b += 64) {
        size_t len = N - b < 64 ? N - b : 64;
        double a = 0.0;
        for (size_t i = 0; i < len; i++)
            if (fabs(orig[b + i] * factor[b + i]) > a)
                a = fabs(orig[b + i] * factor[b + i]);
        float s = (float)(a / 7);
        double top = 0.0;
        for (size_t i = 0; i < len; i++) {
            double x = orig[b + i] * factor[b + i], q = v[b + i] / s;
            if (a == 0.0) {
                assert_true(v[b + i] == 0.0);
                continue;
            }
            assert_true(q == nearbyint(q) && fabs(q) <= 7); /* a code times the scale */
            assert_true(fabs(v[b + i] - x) <= 0.5 * s * (1 + 1e-6));
            if (fabs(v[b + i]) > top)
                top = fabs(v[b + i]);
        }
        if (a > 0.0)
            assert_true(top == 7.0 * (double)s);
    }
    double again[N];
    memcpy(again, v, sizeof v);
    affect_q4_round(again, N, NULL); /* idempotent */
    assert_memory_equal(again, v, sizeof v);
    affect_bw w;
    round_trip(v, N, &w);
    affect_bw_free(&w);
    /* values below FLT_MIN × 7: the block is stored as zeros */
    double tiny[3] = {1e-39, -2e-39, 5e-40};
    affect_q4_round(tiny, 3, NULL);
    assert_true(tiny[0] == 0.0 && tiny[1] == 0.0 && tiny[2] == 0.0);
    round_trip(tiny, 3, &w);
    assert_memory_equal(w.data, "\0\0\0\0\0\0", 6);
    affect_bw_free(&w);
    /* fits: a non-finite product, a scale beyond float32 */
    double big[2] = {1.0, 7.0 * 3.5e38};
    assert_false(affect_q4_fits(big, 2, NULL));
    double inf_factor[2] = {INFINITY, 1.0};
    assert_false(affect_q4_fits(tiny, 2, inf_factor));
    big[1] = 7.0 * 3.0e38;
    assert_true(affect_q4_fits(big, 2, NULL));
}

/* The bytes of the 4-bit form of 3 values {7, -3, 1} × 0.5: scale 0.5, codes 7, -3 (0xd), 1. */
static void test_q4_canonical(void **state)
{
    (void)state;
    double v[3] = {3.5, -1.5, 0.5};
    affect_bw w;
    round_trip(v, 3, &w);
    static const unsigned char expect[] = {0x00, 0x00, 0x00, 0x3f, 0xd7, 0x01};
    assert_int_equal(w.len, sizeof expect);
    assert_memory_equal(w.data, expect, sizeof expect);
    static const struct {
        size_t at;
        unsigned char value;
        bool ok;
        size_t bad;
    } cases[] = {
        {4, 0xd8, false, 4}, /* code −8 */
        {4, 0xd6, false, 0}, /* codes 6, −3, 1: no magnitude 7, the scale is too large */
        {5, 0x11, false, 5}, /* the padding nibble of an odd count */
        {3, 0xbf, false, 0}, /* a negative scale */
        {3, 0x00, false, 4}, /* a zero scale under non-zero codes */
        {3, 0x7f, true, 0},  /* 0x7f000000, a normal scale (1.7e38) with a code 7: canonical */
        {4, 0xd9, true, 0},  /* codes −7, −3, 1: canonical */
    };
    double out[3];
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        unsigned char b[sizeof expect];
        memcpy(b, expect, sizeof b);
        b[cases[k].at] = cases[k].value;
        affect_br r;
        affect_br_init(&r, b, sizeof b);
        size_t bad = 99;
        bool ok = affect_q4_read(&r, out, 3, &bad);
        assert_int_equal(ok, cases[k].ok);
        if (!ok)
            assert_int_equal(bad, cases[k].bad);
    }
    /* infinite, NaN and subnormal scales */
    static const uint32_t scales[] = {0x7f800000u, 0x7fc00000u, 0x00400000u};
    for (size_t k = 0; k < 3; k++) {
        unsigned char b[sizeof expect];
        memcpy(b, expect, sizeof b);
        for (int i = 0; i < 4; i++)
            b[i] = (unsigned char)(scales[k] >> (8 * i));
        affect_br r;
        affect_br_init(&r, b, sizeof b);
        size_t bad = 99;
        assert_false(affect_q4_read(&r, out, 3, &bad));
        assert_int_equal(bad, 0);
    }
    affect_bw_free(&w);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_f24),
        cmocka_unit_test(test_q4_sizes),
        cmocka_unit_test(test_q4_round),
        cmocka_unit_test(test_q4_canonical),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
