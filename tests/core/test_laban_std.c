/*
 * test_laban_std.c — standardization of Laban vectors (core/laban/laban_std.c): the statistics on
 * a hand-made set (mean, sample sd with the n − 1 divisor, missing values skipped, sd 1 where it
 * is 0 or undefined), the same bits when computed in parts, their validation, and the L2 vector:
 * its z-scores, a component missing everywhere written as 0, a component missing in the vector
 * refused, chosen components, and the identity it exists for: the L2 distance of two such vectors
 * equals the index's distance (the Euclidean distance of the z-scores over the components present
 * in both).
 */
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "testutil.h"
#include "affect/laban.h"

#define N AFFECT_LABAN_N

/* Row i of a 4-row set: component j = (i + 1) · (j + 1), except: component 1 missing in row 0,
 * component 2 missing everywhere, component 3 constant (5), component 4 present only in row 3. */
static void make_rows(float x[4 * N])
{
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < N; j++)
            x[i * N + j] = (float)((i + 1) * (j + 1));
    x[0 * N + 1] = NAN;
    for (int i = 0; i < 4; i++) {
        x[i * N + 2] = NAN;
        x[i * N + 3] = 5;
        if (i != 3)
            x[i * N + 4] = NAN;
    }
}

/* In parts (the laban index's polled cache) the statistics have the same bits as in one call,
 * whatever the parts: 1,000 rows of values spread over six orders of magnitude with a third
 * missing, one component missing everywhere, one present in a single row; no rows at all. */
static void test_stats_parts(void **state)
{
    (void)state;
    enum { ROWS = 1000 };
    static float x[ROWS * N];
    uint64_t r = 12345;
    for (int i = 0; i < ROWS * N; i++) {
        r = r * 6364136223846793005ull + 1442695040888963407ull;
        double u = (double)(r >> 11) * 0x1p-53;
        x[i] = (r >> 7) % 3 == 0 ? NAN : (float)((u - 0.3) * pow(10.0, (double)(i % 7) - 3.0));
    }
    for (int i = 0; i < ROWS; i++) {
        x[i * N + 5] = NAN;
        x[i * N + 6] = i == 17 ? 2.5f : NAN;
    }
    double mean[N], sd[N], pm[N], ps[N];
    affect_laban_stats(x, ROWS, mean, sd);
    static const size_t parts[] = {1, 7, 333, 999, 1000, 4096};
    for (size_t k = 0; k < sizeof parts / sizeof parts[0]; k++) {
        affect_laban_acc a;
        affect_laban_acc_init(&a);
        for (size_t at = 0; at < ROWS; at += parts[k])
            affect_laban_acc_sums(&a, x + at * N, ROWS - at < parts[k] ? ROWS - at : parts[k]);
        affect_laban_acc_means(&a);
        for (size_t at = 0; at < ROWS; at += parts[k])
            affect_laban_acc_squares(&a, x + at * N, ROWS - at < parts[k] ? ROWS - at : parts[k]);
        affect_laban_acc_result(&a, pm, ps);
        assert_memory_equal(pm, mean, sizeof mean);
        assert_memory_equal(ps, sd, sizeof sd);
    }
    assert_true(isnan(mean[5]) && sd[5] == 1 && isfinite(mean[6]) && sd[6] == 1);
    affect_laban_acc a;
    affect_laban_acc_init(&a);
    affect_laban_acc_means(&a);
    affect_laban_acc_result(&a, pm, ps);
    for (int j = 0; j < N; j++)
        assert_true(isnan(pm[j]) && ps[j] == 1);
}

static void test_stats(void **state)
{
    (void)state;
    float x[4 * N];
    double mean[N], sd[N];
    make_rows(x);
    affect_laban_stats(x, 4, mean, sd);
    /* component 0: 1, 2, 3, 4 → mean 2.5, sample sd sqrt(5/3) */
    assert_true(fabs(mean[0] - 2.5) < 1e-15);
    assert_true(fabs(sd[0] - sqrt(5.0 / 3.0)) < 1e-15);
    /* component 1 without row 0: 4, 6, 8 → mean 6, sd 2 */
    assert_true(fabs(mean[1] - 6) < 1e-15 && fabs(sd[1] - 2) < 1e-15);
    assert_true(isnan(mean[2]) && sd[2] == 1); /* missing everywhere */
    assert_true(mean[3] == 5 && sd[3] == 1);   /* constant: sd 0 → 1 */
    assert_true(mean[4] == 20 && sd[4] == 1);  /* one value: undefined → 1 */
    assert_int_equal(affect_laban_stats_check(mean, sd, NULL), AFFECT_OK);
    affect_laban_stats(x, 0, mean, sd); /* no rows */
    for (int j = 0; j < N; j++)
        assert_true(isnan(mean[j]) && sd[j] == 1);
    assert_int_equal(affect_laban_stats_check(mean, sd, NULL), AFFECT_OK);
}

static void test_standardize(void **state)
{
    (void)state;
    float x[4 * N];
    double mean[N], sd[N], z[4 * N];
    make_rows(x);
    affect_laban_stats(x, 4, mean, sd);
    affect_laban_standardize(x, 4, mean, sd, z);
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < N; j++) {
            double want = ((double)x[i * N + j] - mean[j]) / sd[j];
            if (isnan(want))
                assert_true(isnan(z[i * N + j]));
            else
                assert_true(z[i * N + j] == want);
        }
    /* by hand: component 0 of row 3 is (4 − 2.5) / sqrt(5/3) */
    assert_true(fabs(z[3 * N] - 1.5 / sqrt(5.0 / 3.0)) < 1e-15);
    assert_true(isnan(z[0 * N + 1]));                      /* missing in the row */
    assert_true(isnan(z[1 * N + 2]));                      /* missing everywhere */
    assert_true(z[2 * N + 3] == 0);                        /* constant: sd 1 */
    assert_true(isnan(z[0 * N + 4]) && z[3 * N + 4] == 0); /* one value: its own mean */
    /* zero rows write nothing */
    z[0] = 7;
    affect_laban_standardize(x, 0, mean, sd, z);
    assert_true(z[0] == 7);
}

static void test_stats_check(void **state)
{
    (void)state;
    double mean[N], sd[N];
    affect_error err;
    for (int j = 0; j < N; j++) {
        mean[j] = j;
        sd[j] = 1;
    }
    sd[3] = -1;
    assert_int_equal(affect_laban_stats_check(mean, sd, &err), AFFECT_ERR_FORMAT);
    assert_string_equal(err.msg, "sd[3] (WeightLHand) is -1, expected a finite number > 0");
    sd[3] = 0;
    assert_int_equal(affect_laban_stats_check(mean, sd, &err), AFFECT_ERR_FORMAT);
    sd[3] = NAN;
    assert_int_equal(affect_laban_stats_check(mean, sd, &err), AFFECT_ERR_FORMAT);
    sd[3] = INFINITY;
    assert_int_equal(affect_laban_stats_check(mean, sd, &err), AFFECT_ERR_FORMAT);
    sd[3] = 1;
    mean[26] = -INFINITY;
    assert_int_equal(affect_laban_stats_check(mean, sd, &err), AFFECT_ERR_FORMAT);
    assert_string_equal(err.msg, "mean[26] (ShapeDirRHand) is -inf, expected a finite number or "
                                 "null");
    mean[26] = NAN; /* missing everywhere: allowed */
    assert_int_equal(affect_laban_stats_check(mean, sd, &err), AFFECT_OK);
}

static void test_f32(void **state)
{
    (void)state;
    assert_true(affect_laban_f32(1.5) == 1.5f);
    assert_true(isnan(affect_laban_f32(INFINITY)) && isnan(affect_laban_f32(-INFINITY)));
    assert_true(isnan(affect_laban_f32(NAN)) && isnan(affect_laban_f32(1e39)));
    assert_true(affect_laban_f32(FLT_MAX) == FLT_MAX);
}

/* The index's distance: Euclidean over the z-scores of the components present in both. */
static double index_distance(const float *a, const float *b, const double *mean, const double *sd,
                             const int *comp, int nc)
{
    double s = 0;
    for (int t = 0; t < nc; t++) {
        int c = comp[t];
        double d = ((double)a[c] - mean[c]) / sd[c] - ((double)b[c] - mean[c]) / sd[c];
        if (!isnan(d))
            s += d * d;
    }
    return sqrt(s);
}

static void test_l2_vector(void **state)
{
    (void)state;
    float x[4 * N], z[N], w[N];
    double mean[N], sd[N];
    affect_error err;
    make_rows(x);
    affect_laban_stats(x, 4, mean, sd);
    /* row 1 has every component but 2 (missing everywhere) and 4 (present in row 3 only) */
    assert_int_equal(affect_laban_l2_vector(x + N, mean, sd, NULL, N, z, &err), AFFECT_ERR_MISSING);
    assert_string_equal(err.msg, "component WeightRHand is missing in this motion but present in "
                                 "the index, so no L2 vector gives the index's distances");
    int comp[N], nc = 0;
    for (int j = 0; j < N; j++)
        if (j != 4)
            comp[nc++] = j;
    assert_int_equal(affect_laban_l2_vector(x + N, mean, sd, comp, nc, z, &err), AFFECT_OK);
    assert_true(z[0] == (float)((2 - 2.5) / sqrt(5.0 / 3.0)));
    assert_true(z[2] == 0); /* component 2: missing everywhere */
    assert_true(z[3] == 0); /* constant 5 with mean 5 */
    /* rows 1, 2, 3 over those components: L2 = the index's distance */
    for (int a = 1; a < 4; a++)
        for (int b = 1; b < 4; b++) {
            assert_int_equal(affect_laban_l2_vector(x + a * N, mean, sd, comp, nc, z, &err),
                             AFFECT_OK);
            assert_int_equal(affect_laban_l2_vector(x + b * N, mean, sd, comp, nc, w, &err),
                             AFFECT_OK);
            double s = 0;
            for (int t = 0; t < nc; t++)
                s += ((double)z[t] - w[t]) * ((double)z[t] - w[t]);
            double want = index_distance(x + a * N, x + b * N, mean, sd, comp, nc);
            assert_true(fabs(sqrt(s) - want) <= 1e-6 * (1 + want));
        }
    /* chosen components come out in the order given */
    int two[2] = {7, 0};
    assert_int_equal(affect_laban_l2_vector(x + N, mean, sd, two, 2, z, &err), AFFECT_OK);
    assert_true(z[0] == (float)((16 - mean[7]) / sd[7]) && z[1] == (float)((2 - 2.5) / sd[0]));
    /* bad arguments */
    assert_int_equal(affect_laban_l2_vector(x + N, mean, sd, two, 0, z, &err), AFFECT_ERR_INVALID);
    assert_int_equal(affect_laban_l2_vector(x + N, mean, sd, NULL, 2, z, &err), AFFECT_ERR_INVALID);
    two[1] = N;
    assert_int_equal(affect_laban_l2_vector(x + N, mean, sd, two, 2, z, &err), AFFECT_ERR_INVALID);
    /* a tiny sd sends a z-score beyond float32 */
    sd[0] = 1e-300;
    two[1] = 0;
    assert_int_equal(affect_laban_l2_vector(x + N, mean, sd, two, 2, z, &err), AFFECT_ERR_RANGE);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_stats),       cmocka_unit_test(test_standardize),
        cmocka_unit_test(test_stats_check), cmocka_unit_test(test_f32),
        cmocka_unit_test(test_l2_vector),   cmocka_unit_test(test_stats_parts),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
