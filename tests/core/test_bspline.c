/*
 * test_bspline.c — B-spline bases (affect/bspline.h): Gauss–Legendre rules against known
 * integrals, partition of unity and non-negativity, derivatives against central finite
 * differences, the exact Gram matrix (Σ M_ij = ∫1 = 1) and penalty on polynomials (∫(t²)″² = 4,
 * ∫(t³)″² = 12), exact reproduction of cubics with λ = 0, straight lines kept whatever λ, the
 * band Cholesky against a dense product, GCV's minimum on a noisy sine, and the errors.
 */
#include <stdio.h>
#include <string.h>

#include "testutil.h"

#include "affect/bspline.h"
#include "util/rng.h"

static void test_gauss_legendre(void **state)
{
    (void)state;
    for (uint32_t n = 1; n <= 10; n++) {
        double x[16], w[16];
        affect_gauss_legendre(n, x, w);
        /* exact for polynomials of degree ≤ 2n − 1: ∫_{−1}^{1} x^d = 2/(d+1) for even d */
        for (uint32_t d = 0; d <= 2 * n - 1; d++) {
            double s = 0.0;
            for (uint32_t i = 0; i < n; i++)
                s += w[i] * pow(x[i], (double)d);
            double want = d % 2 ? 0.0 : 2.0 / (double)(d + 1);
            tu_assert_near(s, want, 1e-13);
        }
        for (uint32_t i = 1; i < n; i++)
            assert_true(x[i] > x[i - 1]);
    }
}

static void test_partition_of_unity(void **state)
{
    (void)state;
    for (uint32_t k = 2; k <= 6; k++) {
        affect_bspline b = {k, k + 7};
        assert_null(affect_bspline_check(&b));
        for (int s = 0; s <= 1000; s++) {
            double t = s / 1000.0, v[AFFECT_BSPLINE_MAX_ORDER], d[AFFECT_BSPLINE_MAX_ORDER];
            uint32_t first = affect_bspline_eval(&b, t, 0, v);
            assert_true(first + k <= b.n);
            double sum = 0.0, dsum = 0.0;
            for (uint32_t i = 0; i < k; i++) {
                assert_true(v[i] >= -1e-15);
                sum += v[i];
            }
            tu_assert_near(sum, 1.0, 1e-14);
            affect_bspline_eval(&b, t, 1, d); /* the derivative of a constant sum is 0 */
            for (uint32_t i = 0; i < k; i++)
                dsum += d[i];
            tu_assert_near(dsum, 0.0, 1e-9);
        }
    }
}

/* Value of basis function idx (any) at t, 0 outside its support. */
static double basis_at(const affect_bspline *b, uint32_t idx, double t, uint32_t deriv)
{
    double v[AFFECT_BSPLINE_MAX_ORDER];
    uint32_t first = affect_bspline_eval(b, t, deriv, v);
    return idx >= first && idx < first + b->order ? v[idx - first] : 0.0;
}

static void test_derivatives(void **state)
{
    (void)state;
    affect_bspline b = {4, 12};
    double h = 1e-6;
    for (uint32_t idx = 0; idx < b.n; idx++)
        for (int s = 1; s < 200; s++) {
            double t = (s + 0.37) / 200.0; /* avoid the knots, where B″ jumps */
            for (uint32_t d = 1; d <= 2; d++) {
                double fd =
                    (basis_at(&b, idx, t + h, d - 1) - basis_at(&b, idx, t - h, d - 1)) / (2 * h);
                double an = basis_at(&b, idx, t, d);
                if (!(fabs(fd - an) <= 1e-4 * (1.0 + fabs(an))))
                    fail_msg("basis %u at %g, derivative %u: %g, differences give %g", idx, t, d,
                             an, fd);
            }
        }
}

/* Coefficients reproducing f on the basis: a λ = 0 fit on many samples. */
static void fit_poly(const affect_bspline *b, const double *r, int degree, double *c)
{
    uint32_t T = 400;
    double *x = malloc(T * sizeof *x);
    double *work = malloc((2 * b->n * b->order + b->n) * sizeof(double));
    assert_non_null(x);
    assert_non_null(work);
    for (uint32_t s = 0; s < T; s++)
        x[s] = pow(s / (double)(T - 1), degree);
    affect_error err;
    assert_int_equal(affect_bspline_fit(b, r, NULL, x, T, 1, 0.0, c, work, &err), AFFECT_OK);
    double f[1];
    for (int s = 0; s <= 50; s++) {
        double t = s / 50.0;
        affect_bspline_values(b, c, 1, &t, 1, f);
        tu_assert_near(f[0], pow(t, degree), 1e-11);
    }
    free(x);
    free(work);
}

static double quad_form(const double *band, uint32_t g, uint32_t k, const double *c)
{
    double *y = malloc(g * sizeof *y), s = 0.0;
    assert_non_null(y);
    affect_band_mul(band, g, k, c, 1, y);
    for (uint32_t i = 0; i < g; i++)
        s += c[i] * y[i];
    free(y);
    return s;
}

static void test_exact_penalty_and_gram(void **state)
{
    (void)state;
    affect_bspline b = {4, 20};
    double r[20 * 4], m[20 * 4], c[20];
    affect_bspline_gram(&b, 2, r);
    affect_bspline_gram(&b, 0, m);
    /* Σ_ij M_ij = ∫ (Σ B_i)² = 1 */
    double ones[20];
    for (int i = 0; i < 20; i++)
        ones[i] = 1.0;
    tu_assert_near(quad_form(m, 20, 4, ones), 1.0, 1e-14);
    tu_assert_near(quad_form(r, 20, 4, ones), 0.0, 1e-9);
    fit_poly(&b, r, 1, c);
    tu_assert_near(quad_form(r, 20, 4, c), 0.0, 1e-8);
    tu_assert_near(quad_form(m, 20, 4, c), 1.0 / 3.0, 1e-12); /* ∫ t² */
    fit_poly(&b, r, 2, c);
    tu_assert_near(quad_form(r, 20, 4, c), 4.0, 1e-8);        /* ∫ 2² */
    tu_assert_near(quad_form(m, 20, 4, c), 1.0 / 5.0, 1e-12); /* ∫ t⁴ */
    fit_poly(&b, r, 3, c);
    tu_assert_near(quad_form(r, 20, 4, c), 12.0, 1e-7); /* ∫ (6t)² */
    /* quintic splines: ∫ ((t⁵)″)² = 400/7 */
    affect_bspline b6 = {6, 15};
    double r6[15 * 6], c6[15];
    affect_bspline_gram(&b6, 2, r6);
    fit_poly(&b6, r6, 5, c6);
    tu_assert_near(quad_form(r6, 15, 6, c6), 400.0 / 7.0, 1e-6);
}

static void test_lines_survive_penalty(void **state)
{
    (void)state;
    affect_bspline b = {4, 30};
    double r[30 * 4], c[30 * 2], work[2 * 30 * 4 + 30];
    affect_bspline_gram(&b, 2, r);
    uint32_t T = 17;
    double x[17 * 2];
    for (uint32_t s = 0; s < T; s++) {
        double t = s / 16.0;
        x[s * 2] = 3.0 - 2.0 * t;
        x[s * 2 + 1] = 0.5 + t;
    }
    affect_error err;
    /* T < G: singular without a penalty, a straight line with one */
    assert_int_equal(affect_bspline_fit(&b, r, NULL, x, T, 2, 0.0, c, work, &err),
                     AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "the fit is singular: 17 samples cannot determine 30 "
                                 "coefficients with lambda = 0 (give a positive lambda or a "
                                 "smaller basis)");
    for (double lam = 1e-6; lam <= 1.0; lam *= 100) {
        assert_int_equal(affect_bspline_fit(&b, r, NULL, x, T, 2, lam, c, work, &err), AFFECT_OK);
        double f[2];
        for (int s = 0; s <= 20; s++) {
            double t = s / 20.0;
            affect_bspline_values(&b, c, 2, &t, 1, f);
            tu_assert_near(f[0], 3.0 - 2.0 * t, 1e-8);
            tu_assert_near(f[1], 0.5 + t, 1e-8);
        }
    }
    x[5] = NAN;
    assert_int_equal(affect_bspline_fit(&b, r, NULL, x, T, 2, 1.0, c, work, &err),
                     AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "sample 2, column 1: non-finite value");
    assert_int_equal(affect_bspline_fit(&b, r, NULL, x, 0, 2, 1.0, c, work, &err),
                     AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "need at least 1 sample");
}

static void test_band_cholesky(void **state)
{
    (void)state;
    affect_bspline b = {4, 25};
    double m[25 * 4], u[25 * 4], x[25 * 3], y[25 * 3];
    affect_bspline_gram(&b, 0, m);
    memcpy(u, m, sizeof m);
    assert_true(affect_band_cholesky(u, 25, 4));
    for (int i = 0; i < 75; i++)
        x[i] = sin(i * 0.7) + 0.1 * i;
    affect_band_mul(m, 25, 4, x, 3, y);
    affect_band_solve(u, 25, 4, y, 3);
    for (int i = 0; i < 75; i++)
        tu_assert_near(y[i], x[i], 1e-9);
    double bad[3 * 2] = {1, 2, 1, 0, 1, 0}; /* [[1,2,0],[2,1,0],[0,0,1]]: indefinite */
    assert_false(affect_band_cholesky(bad, 3, 2));
}

static void test_gcv_minimum(void **state)
{
    (void)state;
    /* a sine plus noise: GCV is large for tiny λ (interpolating noise, df → T) and for huge λ
     * (a straight line), with its minimum in between, where the fit is closest to the truth */
    affect_bspline b = {4, 40};
    double r[40 * 4];
    affect_bspline_gram(&b, 2, r);
    uint32_t T = 120;
    double x[120], truth[120], c[40];
    affect_rng rng;
    affect_rng_seed(&rng, 7);
    for (uint32_t s = 0; s < T; s++) {
        double t = s / (double)(T - 1);
        truth[s] = sin(2 * 3.14159265358979 * t);
        x[s] = truth[s] + 0.2 * affect_rng_normal(&rng);
    }
    double *work = malloc(affect_bspline_gcv_work(&b, T, 1) * sizeof(double));
    assert_non_null(work);
    double best = INFINITY, best_lam = 0, lo = 0, hi = 0, df_lo = 0, df_hi = 0;
    for (int e = -40; e <= 4; e++) {
        double lam = pow(10.0, e / 4.0), df;
        double g = affect_bspline_gcv(&b, r, NULL, x, T, 1, lam, &df, work);
        if (e == -40)
            lo = g, df_lo = df;
        if (e == 4)
            hi = g, df_hi = df;
        if (g < best)
            best = g, best_lam = lam;
    }
    assert_true(best < lo && best < hi);
    assert_true(df_lo > df_hi && df_hi < 3.0 && df_lo > 30.0);
    assert_true(best_lam > 1e-10 && best_lam < 1.0);
    /* the GCV fit is nearer the truth than the roughest and the smoothest */
    double ework[2 * 40 * 4 + 40], errs[3], lams[3] = {1e-10, best_lam, 1e1};
    for (int i = 0; i < 3; i++) {
        affect_error err;
        assert_int_equal(affect_bspline_fit(&b, r, NULL, x, T, 1, lams[i], c, ework, &err),
                         AFFECT_OK);
        double f[120], s = 0;
        affect_bspline_values(&b, c, 1, NULL, T, f);
        for (uint32_t j = 0; j < T; j++)
            s += (f[j] - truth[j]) * (f[j] - truth[j]);
        errs[i] = s;
    }
    assert_true(errs[1] < errs[0] && errs[1] < errs[2]);
    free(work);
}

/* df from the band recursion against tr((A + λR)⁻¹ A) by G full solves. */
static void test_gcv_df(void **state)
{
    (void)state;
    affect_bspline b = {4, 30};
    double r[30 * 4], a[30 * 4], u[30 * 4], rhs[30], col[30];
    affect_bspline_gram(&b, 2, r);
    uint32_t T = 50;
    double x[50], tt[50];
    for (uint32_t s = 0; s < T; s++) {
        tt[s] = (s * 0.37 + 0.1 * (s % 3)) / (T * 0.37); /* uneven times */
        if (tt[s] > 1)
            tt[s] = 1;
        x[s] = cos(7.0 * tt[s]);
    }
    double *work = malloc(affect_bspline_gcv_work(&b, T, 1) * sizeof(double));
    assert_non_null(work);
    for (double lam = 1e-9; lam < 10; lam *= 31.6) {
        double df;
        affect_bspline_gcv(&b, r, tt, x, T, 1, lam, &df, work);
        affect_bspline_normal(&b, tt, x, T, 1, a, rhs);
        for (int i = 0; i < 120; i++)
            u[i] = a[i] + lam * r[i];
        assert_true(affect_band_cholesky(u, 30, 4));
        double tr = 0;
        for (uint32_t j = 0; j < 30; j++) {
            memset(col, 0, sizeof col);
            for (uint32_t i = 0; i < 30; i++) {
                uint32_t lo = i < j ? i : j, d = i < j ? j - i : i - j;
                if (d < 4)
                    col[i] = a[lo * 4 + d];
            }
            affect_band_solve(u, 30, 4, col, 1);
            tr += col[j];
        }
        tu_assert_near(df, tr, 1e-9 * (1 + tr));
        assert_true(df > 0 && df <= 30 + 1e-9);
    }
    free(work);
}

static void test_check(void **state)
{
    (void)state;
    affect_bspline b = {1, 10};
    assert_string_equal(affect_bspline_check(&b), "order must be from 2 to 10");
    b.order = 4;
    b.n = 3;
    assert_string_equal(affect_bspline_check(&b), "the basis size must be from the order to 4096");
    b.n = 4; /* one interval: a single cubic */
    assert_null(affect_bspline_check(&b));
    double v[4];
    assert_int_equal(affect_bspline_eval(&b, 1.0, 0, v), 0);
    tu_assert_near(v[3], 1.0, 1e-15);
    assert_int_equal(affect_bspline_eval(&b, -3.0, 0, v), 0);
    tu_assert_near(v[0], 1.0, 1e-15);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_gauss_legendre),
        cmocka_unit_test(test_partition_of_unity),
        cmocka_unit_test(test_derivatives),
        cmocka_unit_test(test_exact_penalty_and_gram),
        cmocka_unit_test(test_lines_survive_penalty),
        cmocka_unit_test(test_band_cholesky),
        cmocka_unit_test(test_gcv_minimum),
        cmocka_unit_test(test_gcv_df),
        cmocka_unit_test(test_check),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
