/*
 * test_rmlr.c — elastic-net multinomial logistic regression: the KKT conditions of the
 * solution, the lasso path, recovery of the informative features, determinism (also across
 * thread counts), errors, the encoding (round trip, truncation, corruption), out-of-memory
 * handling (with 1 and 2 threads) and the column-mean imputation of missing values.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

#include "affect/hmm_blob.h" /* affect_fnv1a64 */
#include "affect/rmlr.h"
#include "util/rng.h"
#include "util/bytes.h"

#define P 27

/* n samples of P features, classes i mod K; features 0 .. n_inf−1 carry the label (class k
 * shifts feature k mod n_inf by sep), the others are noise; features get different scales and
 * offsets so that standardization matters. */
static void synth(size_t n, uint32_t K, size_t n_inf, double sep, uint64_t seed, double *x,
                  uint32_t *y)
{
    affect_rng r;
    affect_rng_seed(&r, seed);
    for (size_t i = 0; i < n; i++) {
        y[i] = (uint32_t)(i % K);
        for (size_t j = 0; j < P; j++) {
            double v = affect_rng_normal(&r);
            if (j < n_inf && y[i] % n_inf == j)
                v += sep;
            if (j < n_inf && y[i] == K - 1 && K > n_inf)
                v -= sep; /* the extra classes sit on the negative side of every feature */
            x[i * P + j] = 3.0 + (double)(j + 1) * v;
        }
    }
}

/* Standardized copy of x (n × P) as the library does (population sd). */
static void standardize(const double *x, size_t n, double *z)
{
    for (size_t j = 0; j < P; j++) {
        double m = 0, ss = 0;
        for (size_t i = 0; i < n; i++)
            m += x[i * P + j];
        m /= (double)n;
        for (size_t i = 0; i < n; i++)
            ss += (x[i * P + j] - m) * (x[i * P + j] - m);
        double sd = sqrt(ss / (double)n);
        for (size_t i = 0; i < n; i++)
            z[i * P + j] = (x[i * P + j] - m) / sd;
    }
}

static size_t nonzeros(const double *beta, uint32_t K)
{
    size_t c = 0;
    for (size_t i = 0; i < K * (size_t)P; i++)
        c += beta[i] != 0;
    return c;
}

/* KKT of the elastic net at every λ of a path, with gradients computed here from scratch. */
static void check_kkt(const double *x, size_t n, const uint32_t *y, uint32_t K, double alpha,
                      const double *lam, uint32_t L, const double *beta, const double *beta0,
                      double tol)
{
    double *z = malloc(n * P * sizeof *z), *pr = malloc(n * K * sizeof *pr);
    assert_non_null(z);
    assert_non_null(pr);
    standardize(x, n, z);
    for (uint32_t l = 0; l < L; l++) {
        const double *b = beta + (size_t)l * K * P, *b0 = beta0 + (size_t)l * K;
        for (size_t i = 0; i < n; i++) {
            double mx = -INFINITY, s = 0;
            for (uint32_t k = 0; k < K; k++) {
                double e = b0[k];
                for (size_t j = 0; j < P; j++)
                    e += b[k * P + j] * z[i * P + j];
                pr[i * K + k] = e;
                if (e > mx)
                    mx = e;
            }
            for (uint32_t k = 0; k < K; k++)
                s += pr[i * K + k] = exp(pr[i * K + k] - mx);
            for (uint32_t k = 0; k < K; k++)
                pr[i * K + k] /= s;
        }
        double s0 = 0;
        for (uint32_t k = 0; k < K; k++) {
            double gi = 0;
            for (size_t i = 0; i < n; i++)
                gi += (y[i] == k) - pr[i * K + k];
            tu_assert_near(gi / (double)n, 0, tol);
            s0 += b0[k];
            for (size_t j = 0; j < P; j++) {
                double g = 0, bk = b[k * P + j];
                for (size_t i = 0; i < n; i++)
                    g += z[i * P + j] * ((y[i] == k) - pr[i * K + k]);
                g /= (double)n;
                if (bk != 0) {
                    double s = bk > 0 ? 1 : -1;
                    tu_assert_near(g - lam[l] * (1 - alpha) * bk - lam[l] * alpha * s, 0, tol);
                } else {
                    assert_true(fabs(g) <= lam[l] * alpha + tol);
                }
            }
        }
        tu_assert_near(s0, 0, 1e-12);
    }
    free(z);
    free(pr);
}

static void test_kkt(void **state)
{
    (void)state;
    enum { N = 120, K = 3, L = 12 };
    static const double alphas[] = {0.05, 0.3, 0.7, 1.0};
    double *x = malloc(N * P * sizeof *x), *beta = malloc(L * K * P * sizeof *beta);
    double beta0[L * K], lam[L];
    uint32_t y[N];
    uint8_t conv[L];
    affect_error err;
    assert_non_null(x);
    assert_non_null(beta);
    synth(N, K, 3, 1.0, 11, x, y);
    for (size_t a = 0; a < sizeof alphas / sizeof *alphas; a++) {
        affect_rmlr_options o;
        affect_rmlr_options_default(&o);
        o.lambda_min_ratio = 0.01;
        o.tol = 1e-13; /* tight, so the KKT conditions hold to 1e-6 */
        assert_int_equal(affect_rmlr_fit_path(x, N, P, y, K, alphas[a], NULL, L, &o, lam, beta,
                                              beta0, conv, &err),
                         AFFECT_OK);
        for (uint32_t l = 0; l < L; l++)
            assert_int_equal(conv[l], 1);
        /* the path is log-spaced from λ_max down to λ_max / 100 */
        tu_assert_near(lam[L - 1] / lam[0], 0.01, 1e-12);
        tu_assert_near(lam[1] / lam[0], pow(0.01, 1.0 / (L - 1)), 1e-12);
        check_kkt(x, N, y, K, alphas[a], lam, L, beta, beta0, 2e-6);
        /* all zero at λ_max, and a little below it something enters */
        assert_int_equal(nonzeros(beta, K), 0);
        assert_true(nonzeros(beta + (size_t)(L - 1) * K * P, K) > 0);
    }
    /* given λ values (α = 0.5, one of them far from the path) */
    double given[3] = {0.2, 0.05, 0.003};
    affect_rmlr_options o;
    affect_rmlr_options_default(&o);
    o.tol = 1e-13;
    assert_int_equal(
        affect_rmlr_fit_path(x, N, P, y, K, 0.5, given, 3, &o, lam, beta, beta0, NULL, &err),
        AFFECT_OK);
    for (int l = 0; l < 3; l++)
        assert_true(lam[l] == given[l]);
    check_kkt(x, N, y, K, 0.5, lam, 3, beta, beta0, 2e-6);
    free(x);
    free(beta);
}

/* The sequential strong rule is a heuristic: it may screen out a feature that the new λ needs,
 * which the KKT check must then find. A suppressor makes the rule fail: class = sign(e + noise),
 * feature 0 = s + e, feature 1 = s (s independent of the class): feature 1 alone is useless (its
 * gradient stays small while feature 0 is out), but once feature 0 is in, feature 1 cancels its
 * s and its gradient grows faster than the rule assumes (|dg/dλ| ≤ 1); with this seed and λ
 * steps of 0.63 the rule drops feature 1 (and another) where the KKT conditions need them
 * (twice: counted once by instrumenting the solver). And on correlated random data, the KKT
 * conditions hold along whole paths. */
static void test_strong_rule_kkt(void **state)
{
    (void)state;
    enum { N = 100, K = 2, L = 6 };
    double *x = malloc(N * P * sizeof *x), *beta = malloc(30 * 4 * P * sizeof *beta);
    double beta0[30 * 4], lam[30];
    uint32_t y[N];
    uint8_t conv[30];
    affect_error err;
    affect_rng r;
    assert_non_null(x);
    assert_non_null(beta);
    affect_rng_seed(&r, 2012);
    for (size_t i = 0; i < N; i++) {
        double s = 3 * affect_rng_normal(&r), e = affect_rng_normal(&r);
        y[i] = e + affect_rng_normal(&r) > 0;
        x[i * P] = s + e;
        x[i * P + 1] = s;
        for (size_t j = 2; j < P; j++)
            x[i * P + j] = affect_rng_normal(&r);
    }
    affect_rmlr_options o;
    affect_rmlr_options_default(&o);
    o.lambda_min_ratio = 0.1; /* steps of 0.63 */
    o.tol = 1e-13;
    assert_int_equal(
        affect_rmlr_fit_path(x, N, P, y, K, 1.0, NULL, L, &o, lam, beta, beta0, conv, &err),
        AFFECT_OK);
    for (uint32_t l = 0; l < L; l++)
        assert_int_equal(conv[l], 1);
    check_kkt(x, N, y, K, 1.0, lam, L, beta, beta0, 2e-6);
    /* both in at the end of the path, with opposite signs (feature 1 cancels s); with 2
     * classes and α = 1 only the differences β_1j − β_0j are identified (any split of one
     * between the two classes has the same penalty), so those are compared */
    const double *last = beta + (size_t)(L - 1) * K * P;
    double d0 = last[P] - last[0], d1 = last[P + 1] - last[1];
    assert_true(d0 != 0 && d1 != 0 && (d0 > 0) != (d1 > 0));
    /* correlated features (three latent factors, one carrying the class) along whole paths */
    enum { N2 = 100, K2 = 3, L2 = 30 };
    static const double alphas[] = {0.1, 0.5, 1.0};
    for (uint64_t seed = 1; seed <= 6; seed++) {
        affect_rng_seed(&r, seed);
        for (size_t i = 0; i < N2; i++) {
            double u[3];
            y[i] = (uint32_t)(i % K2);
            for (int q = 0; q < 3; q++)
                u[q] = affect_rng_normal(&r) + (q == 0 ? 0.8 * y[i] : 0);
            for (size_t j = 0; j < P; j++)
                x[i * P + j] = u[j % 3] * (1 + 0.1 * (double)j) + 0.5 * affect_rng_normal(&r) +
                               (j % 5 == 1 ? 0.4 * (y[i] == j % K2) : 0);
        }
        for (size_t a = 0; a < sizeof alphas / sizeof *alphas; a++) {
            affect_rmlr_options_default(&o);
            o.lambda_min_ratio = 0.1; /* far from separable, where tol 1e-13 takes too long */
            o.tol = 1e-13;
            assert_int_equal(affect_rmlr_fit_path(x, N2, P, y, K2, alphas[a], NULL, L2, &o, lam,
                                                  beta, beta0, conv, &err),
                             AFFECT_OK);
            for (uint32_t l = 0; l < L2; l++)
                assert_int_equal(conv[l], 1);
            check_kkt(x, N2, y, K2, alphas[a], lam, L2, beta, beta0, 2e-6);
        }
    }
    free(x);
    free(beta);
}

/* The penalised objective of one fit (β K × P, β0 K) on standardized z. */
static double objective(const double *z, size_t n, const uint32_t *y, uint32_t K, double alpha,
                        double lam, const double *b, const double *b0)
{
    double loss = 0, pen = 0;
    for (size_t i = 0; i < n; i++) {
        double e[8], mx = -INFINITY, s = 0;
        for (uint32_t k = 0; k < K; k++) {
            e[k] = b0[k];
            for (size_t j = 0; j < P; j++)
                e[k] += b[k * P + j] * z[i * P + j];
            if (e[k] > mx)
                mx = e[k];
        }
        for (uint32_t k = 0; k < K; k++)
            s += exp(e[k] - mx);
        loss += mx + log(s) - e[y[i]];
    }
    for (size_t q = 0; q < K * (size_t)P; q++)
        pen += alpha * fabs(b[q]) + 0.5 * (1 - alpha) * b[q] * b[q];
    return loss / (double)n + lam * pen;
}

/* The Newton solver (the default) against coordinate descent alone (options.solver CD, the
 * method before it) on random problems, some nearly separable (where Newton's steps take
 * over): both meet the KKT conditions, reach the same objective, and where the solution is
 * unique (α < 1: the ridge makes the objective strictly convex) the same coefficients. At
 * α = 1 the Newton solver leaves, in every feature, at least one class's coefficient at 0 (a
 * shift common to a feature's K coefficients changes only the penalty, and the sparsest point
 * of a flat stretch is chosen). Repeated fits give the same bytes. */
static void test_newton_vs_cd(void **state)
{
    (void)state;
    enum { N = 90, L = 25 };
    static const uint32_t Ks[] = {2, 3, 5};
    static const double alphas[] = {0.3, 0.8, 1.0}, seps[] = {1.0, 4.0};
    double *x = malloc(N * P * sizeof *x), *z = malloc(N * P * sizeof *z);
    double *b1 = malloc(L * 5 * P * sizeof *b1), *b2 = malloc(L * 5 * P * sizeof *b2);
    double *b3 = malloc(L * 5 * P * sizeof *b3);
    double b01[L * 5], b02[L * 5], b03[L * 5], lam[L], lam2[L];
    uint32_t y[N];
    uint8_t c1[L], c2[L];
    affect_error err;
    assert_non_null(x);
    assert_non_null(z);
    assert_non_null(b1);
    assert_non_null(b2);
    assert_non_null(b3);
    for (size_t t = 0; t < sizeof Ks / sizeof *Ks; t++)
        for (size_t sp = 0; sp < 2; sp++) {
            uint32_t K = Ks[t];
            synth(N, K, 4, seps[sp], 100 + t * 2 + sp, x, y);
            standardize(x, N, z);
            for (size_t a = 0; a < sizeof alphas / sizeof *alphas; a++) {
                affect_rmlr_options o;
                affect_rmlr_options_default(&o);
                o.lambda_min_ratio = 0.02;
                o.tol = 1e-13;
                o.max_iter = 100000;
                assert_int_equal(affect_rmlr_fit_path(x, N, P, y, K, alphas[a], NULL, L, &o, lam,
                                                      b1, b01, c1, &err),
                                 AFFECT_OK);
                assert_int_equal(affect_rmlr_fit_path(x, N, P, y, K, alphas[a], NULL, L, &o, lam,
                                                      b3, b03, NULL, &err),
                                 AFFECT_OK);
                assert_memory_equal(b1, b3, L * K * P * sizeof *b1);
                assert_memory_equal(b01, b03, L * K * sizeof *b01);
                o.solver = AFFECT_RMLR_SOLVER_CD;
                assert_int_equal(affect_rmlr_fit_path(x, N, P, y, K, alphas[a], NULL, L, &o, lam2,
                                                      b2, b02, c2, &err),
                                 AFFECT_OK);
                assert_memory_equal(lam, lam2, sizeof lam);
                check_kkt(x, N, y, K, alphas[a], lam, L, b1, b01, 2e-6);
                check_kkt(x, N, y, K, alphas[a], lam, L, b2, b02, 2e-6);
                for (uint32_t l = 0; l < L; l++) {
                    const double *n1 = b1 + (size_t)l * K * P, *n2 = b2 + (size_t)l * K * P;
                    assert_int_equal(c1[l], 1);
                    assert_int_equal(c2[l], 1);
                    double f1 = objective(z, N, y, K, alphas[a], lam[l], n1, b01 + l * K);
                    double f2 = objective(z, N, y, K, alphas[a], lam[l], n2, b02 + l * K);
                    tu_assert_near(f1, f2, 1e-10 * f2);
                    if (alphas[a] < 1)
                        for (size_t q = 0; q < K * (size_t)P; q++)
                            tu_assert_near(n1[q], n2[q], 1e-5 * (1 + fabs(n2[q])));
                    else
                        for (size_t j = 0; j < P; j++) {
                            bool zero = false;
                            for (uint32_t k = 0; k < K; k++)
                                zero = zero || n1[k * P + j] == 0;
                            assert_true(zero);
                        }
                }
            }
        }
    free(x);
    free(z);
    free(b1);
    free(b2);
    free(b3);
}

static void test_lasso_path(void **state)
{
    (void)state;
    enum { N = 150, K = 4, L = 40 };
    double *x = malloc(N * P * sizeof *x), *beta = malloc(L * K * P * sizeof *beta);
    double lam[L];
    uint32_t y[N];
    affect_error err;
    assert_non_null(x);
    assert_non_null(beta);
    synth(N, K, 3, 1.5, 5, x, y);
    assert_int_equal(
        affect_rmlr_fit_path(x, N, P, y, K, 1.0, NULL, L, NULL, lam, beta, NULL, NULL, &err),
        AFFECT_OK);
    size_t prev = 0, drops = 0, nz[L];
    for (uint32_t l = 0; l < L; l++) {
        nz[l] = nonzeros(beta + (size_t)l * K * P, K);
        if (l > 0 && lam[l] >= lam[l - 1])
            fail_msg("path not decreasing at %u", l);
        if (nz[l] < prev)
            drops += prev - nz[l];
        prev = nz[l];
    }
    assert_int_equal(nz[0], 0);
    assert_true(nz[1] >= 1 && nz[1] <= 8); /* the first step adds a few */
    assert_true(nz[L / 2] > nz[L / 4]);
    assert_true(nz[L - 1] > nz[L / 2]);
    assert_true(nz[L - 1] >= 60);
    assert_true(drops <= 6); /* roughly monotone */
    /* λ_max is the smallest λ with all zero: a hair below it, something is non-zero */
    double below[2] = {lam[0] * (1 + 1e-9), lam[0] * (1 - 1e-3)};
    assert_int_equal(
        affect_rmlr_fit_path(x, N, P, y, K, 1.0, below, 2, NULL, NULL, beta, NULL, NULL, &err),
        AFFECT_OK);
    assert_int_equal(nonzeros(beta, K), 0);
    assert_int_equal(nonzeros(beta + K * P, K), 1);
    free(x);
    free(beta);
}

static void small_options(affect_rmlr_options *o, const double *alphas, uint32_t n_alpha)
{
    affect_rmlr_options_default(o);
    o->alphas = alphas;
    o->n_alpha = n_alpha;
    o->n_lambda = 15;
    o->lambda_min_ratio = 0.01;
    o->folds = 4;
    o->seed = 42;
}

static void test_recovery(void **state)
{
    (void)state;
    enum { N = 150, K = 3 };
    static const double alphas[] = {0.5, 1.0};
    double *x = malloc(N * P * sizeof *x);
    uint32_t y[N];
    affect_error err;
    affect_rmlr_options o;
    affect_rmlr *m;
    assert_non_null(x);
    synth(N, K, 3, 2.0, 99, x, y);
    small_options(&o, alphas, 2);
    assert_int_equal(affect_rmlr_cv(x, N, P, y, K, &o, &m, &err), AFFECT_OK);
    const double *beta = affect_rmlr_beta(m);
    size_t others = 0;
    for (size_t j = 0; j < P; j++) {
        bool any = false;
        for (uint32_t k = 0; k < K; k++)
            any = any || beta[k * P + j] != 0;
        if (j < 3)
            assert_true(any);
        else
            others += any;
    }
    assert_true(others <= 6);
    /* feature k carries class k: its coefficient for k is the largest positive one */
    for (uint32_t k = 0; k < K; k++) {
        for (size_t j = 0; j < P; j++)
            if (j != k)
                assert_true(beta[k * P + k] > beta[k * P + j]);
        assert_true(beta[k * P + k] > 0);
    }
    assert_true(affect_rmlr_cv_error(m) < 0.25);
    assert_true(affect_rmlr_converged(m));
    assert_int_equal(affect_rmlr_n_classes(m), K);
    assert_int_equal(affect_rmlr_n_features(m), P);
    assert_int_equal(affect_rmlr_n_train(m), N);
    uint32_t L;
    const double *lam = affect_rmlr_lambdas(m, &L);
    assert_int_equal(L, 15);
    assert_true(affect_rmlr_lambda(m) == lam[affect_rmlr_lambda_index(m)]);
    assert_true(affect_rmlr_cv_errors(m)[affect_rmlr_lambda_index(m)] == affect_rmlr_cv_error(m));
    /* the choice is the smallest error, the largest λ among ties (of the chosen α) */
    for (uint32_t l = 0; l < L; l++) {
        assert_true(affect_rmlr_cv_errors(m)[l] >= affect_rmlr_cv_error(m));
        if (l < affect_rmlr_lambda_index(m))
            assert_true(affect_rmlr_cv_errors(m)[l] > affect_rmlr_cv_error(m));
    }
    assert_true(affect_rmlr_alpha(m) == 0.5 || affect_rmlr_alpha(m) == 1.0);
    /* intercepts centred; means and sds of the training data */
    const double *b0 = affect_rmlr_intercepts(m);
    tu_assert_near(b0[0] + b0[1] + b0[2], 0, 1e-12);
    double mean0 = 0;
    for (size_t i = 0; i < N; i++)
        mean0 += x[i * P];
    tu_assert_near(affect_rmlr_means(m)[0], mean0 / N, 1e-12);
    assert_true(affect_rmlr_sds(m)[5] > 4 && affect_rmlr_sds(m)[5] < 8); /* scale 6 */
    /* prediction: training accuracy is high, probabilities sum to 1 */
    size_t right = 0;
    for (size_t i = 0; i < N; i++) {
        double pr[K];
        uint32_t c = affect_rmlr_predict(m, x + i * P, pr);
        right += c == y[i];
        tu_assert_near(pr[0] + pr[1] + pr[2], 1, 1e-12);
        assert_true(pr[c] >= pr[0] && pr[c] >= pr[1] && pr[c] >= pr[2]);
        assert_int_equal(affect_rmlr_predict(m, x + i * P, NULL), c);
    }
    assert_true(right >= 0.8 * N);
    affect_rmlr_free(m);
    free(x);
}

static void test_constant_feature(void **state)
{
    (void)state;
    enum { N = 60, K = 2 };
    double *x = malloc(N * P * sizeof *x), beta[3 * K * P], lam[3];
    uint32_t y[N];
    affect_error err;
    assert_non_null(x);
    synth(N, K, 2, 2.0, 3, x, y);
    for (size_t i = 0; i < N; i++)
        x[i * P + 4] = 0.1; /* a constant that is not exactly representable */
    assert_int_equal(
        affect_rmlr_fit_path(x, N, P, y, K, 0.2, NULL, 3, NULL, lam, beta, NULL, NULL, &err),
        AFFECT_OK);
    for (int l = 0; l < 3; l++)
        for (uint32_t k = 0; k < K; k++)
            assert_true(beta[(l * K + k) * P + 4] == 0);
    assert_true(nonzeros(beta + 2 * K * P, K) > 10);
    free(x);
}

static void test_determinism(void **state)
{
    (void)state;
    enum { N = 60, K = 3 };
    static const double alphas[] = {0.3, 1.0};
    double *x = malloc(N * P * sizeof *x);
    uint32_t y[N];
    affect_error err;
    affect_rmlr_options o;
    affect_rmlr *m1, *m2, *m3;
    affect_bw w1, w2, w3;
    assert_non_null(x);
    synth(N, K, 3, 1.0, 8, x, y);
    small_options(&o, alphas, 2);
    assert_int_equal(affect_rmlr_cv(x, N, P, y, K, &o, &m1, &err), AFFECT_OK);
    assert_int_equal(affect_rmlr_cv(x, N, P, y, K, &o, &m2, &err), AFFECT_OK);
    o.seed = 43;
    assert_int_equal(affect_rmlr_cv(x, N, P, y, K, &o, &m3, &err), AFFECT_OK);
    affect_bw_init(&w1);
    affect_bw_init(&w2);
    affect_bw_init(&w3);
    affect_rmlr_encode(m1, &w1);
    affect_rmlr_encode(m2, &w2);
    affect_rmlr_encode(m3, &w3);
    assert_false(w1.failed || w2.failed || w3.failed);
    assert_int_equal(w1.len, w2.len);
    assert_memory_equal(w1.data, w2.data, w1.len);
    /* another seed, other folds: the cross-validated errors differ somewhere */
    assert_int_equal(w1.len, w3.len);
    assert_memory_not_equal(affect_rmlr_cv_errors(m1), affect_rmlr_cv_errors(m3),
                            15 * sizeof(double));
    affect_bw_free(&w1);
    affect_bw_free(&w2);
    affect_bw_free(&w3);
    affect_rmlr_free(m1);
    affect_rmlr_free(m2);
    affect_rmlr_free(m3);
    free(x);
}

/* affect_rmlr_cv's encoding into w (initialised here). */
static void cv_encode(const double *x, size_t n, const uint32_t *y, uint32_t K,
                      const affect_rmlr_options *o, affect_bw *w)
{
    affect_rmlr *m;
    affect_error err;
    assert_int_equal(affect_rmlr_cv(x, n, P, y, K, o, &m, &err), AFFECT_OK);
    affect_bw_init(w);
    affect_rmlr_encode(m, w);
    assert_false(w->failed);
    affect_rmlr_free(m);
}

static void test_threads(void **state)
{
    (void)state;
    enum { N = 45, K = 3 };
    /* α values of very different costs, so the workers finish them out of order */
    static const double alphas[] = {0.05, 1.0, 0.0, 0.6};
    double *x = malloc(N * P * sizeof *x);
    uint32_t y[N];
    affect_rmlr_options o;
    affect_bw w1, wt;
    assert_non_null(x);
    synth(N, K, 3, 1.0, 8, x, y);
    small_options(&o, alphas, 4);
    cv_encode(x, N, y, K, &o, &w1);
    static const uint32_t threads[] = {2, 3, 64}; /* 64: one thread per α */
    for (size_t t = 0; t < sizeof threads / sizeof *threads; t++) {
        o.threads = threads[t];
        cv_encode(x, N, y, K, &o, &wt);
        assert_int_equal(wt.len, w1.len);
        assert_memory_equal(wt.data, w1.data, w1.len);
        affect_bw_free(&wt);
    }
    affect_bw_free(&w1);
    /* one α: one worker whatever the option */
    small_options(&o, alphas + 3, 1);
    cv_encode(x, N, y, K, &o, &w1);
    o.threads = 2;
    cv_encode(x, N, y, K, &o, &wt);
    assert_int_equal(wt.len, w1.len);
    assert_memory_equal(wt.data, w1.data, w1.len);
    affect_bw_free(&w1);
    affect_bw_free(&wt);
    free(x);
}

#define EXPECT_ERR(call, status, message)                                                          \
    do {                                                                                           \
        affect_error_clear(&err);                                                                  \
        assert_int_equal((call), (status));                                                        \
        assert_string_equal(err.msg, (message));                                                   \
    } while (0)

static void test_errors(void **state)
{
    (void)state;
    enum { N = 20, K = 2 };
    double x[N * P], lam[2] = {0.1, -1}, beta[K * P];
    uint32_t y[N];
    affect_error err;
    affect_rmlr_options o;
    affect_rmlr *m = (affect_rmlr *)&err;
    synth(N, K, 2, 1.0, 1, x, y);

#define FIT(n_, p_, y_, K_, a_, l_, L_, o_)                                                        \
    affect_rmlr_fit_path(x, n_, p_, y_, K_, a_, l_, L_, o_, NULL, beta, NULL, NULL, &err)
    EXPECT_ERR(FIT(0, P, y, K, 1, NULL, 2, NULL), AFFECT_ERR_INVALID, "need at least 1 sample");
    EXPECT_ERR(FIT(N, 0, y, K, 1, NULL, 2, NULL), AFFECT_ERR_INVALID, "need at least 1 feature");
    EXPECT_ERR(FIT(N, 2000000, y, K, 1, NULL, 2, NULL), AFFECT_ERR_RANGE,
               "too many features: 2000000 (at most 1048576)");
    EXPECT_ERR(FIT((size_t)1 << 40, P, y, K, 1, NULL, 2, NULL), AFFECT_ERR_RANGE,
               "too many samples: 1099511627776");
    EXPECT_ERR(FIT(N, P, y, 1, 1, NULL, 2, NULL), AFFECT_ERR_INVALID,
               "need at least 2 classes, got 1");
    EXPECT_ERR(FIT(N, P, y, 300, 1, NULL, 2, NULL), AFFECT_ERR_INVALID,
               "at most 256 classes, got 300");
    EXPECT_ERR(FIT(N, P, y, K, 1.5, NULL, 2, NULL), AFFECT_ERR_INVALID,
               "alpha must be in [0, 1], got 1.5");
    EXPECT_ERR(FIT(N, P, y, K, NAN, NULL, 2, NULL), AFFECT_ERR_INVALID,
               "alpha must be in [0, 1], got nan");
    EXPECT_ERR(FIT(N, P, y, K, 1, NULL, 0, NULL), AFFECT_ERR_INVALID, "need at least 1 lambda");
    EXPECT_ERR(FIT(N, P, y, K, 1, NULL, 2000000, NULL), AFFECT_ERR_RANGE,
               "too many lambdas: 2000000 (at most 1048576)");
    EXPECT_ERR(FIT(N, P, y, K, 1, lam, 2, NULL), AFFECT_ERR_INVALID,
               "lambda 1 = -1 is not a positive finite number");
    affect_rmlr_options_default(&o);
    o.lambda_min_ratio = 2;
    EXPECT_ERR(FIT(N, P, y, K, 1, NULL, 2, &o), AFFECT_ERR_INVALID,
               "lambda_min_ratio must be in (0, 1), or 0 for automatic, got 2");
    affect_rmlr_options_default(&o);
    o.max_iter = 0;
    EXPECT_ERR(FIT(N, P, y, K, 1, NULL, 2, &o), AFFECT_ERR_INVALID, "max_iter must be at least 1");
    affect_rmlr_options_default(&o);
    o.tol = 0;
    EXPECT_ERR(FIT(N, P, y, K, 1, NULL, 2, &o), AFFECT_ERR_INVALID,
               "tol must be a positive finite number, got 0");
    y[5] = 7;
    EXPECT_ERR(FIT(N, P, y, 3, 1, NULL, 2, NULL), AFFECT_ERR_INVALID,
               "sample 5: class 7 out of range 0 .. 2");
    y[5] = 1;
    x[3 * P + 17] = INFINITY;
    EXPECT_ERR(FIT(N, P, y, K, 1, NULL, 2, NULL), AFFECT_ERR_INVALID,
               "sample 3, feature 17 is not finite");
    x[3 * P + 17] = 0;
    EXPECT_ERR(FIT(N, P, y, 3, 1, NULL, 2, NULL), AFFECT_ERR_INVALID, "class 2 has no sample");

    /* cross-validation */
    EXPECT_ERR(affect_rmlr_cv(x, N, P, y, 1, NULL, &m, &err), AFFECT_ERR_INVALID,
               "need at least 2 classes, got 1");
    assert_null(m);
    static const double bad_alphas[] = {0.5, 1, 0.2, 1.5};
    affect_rmlr_options_default(&o);
    o.n_lambda = 0;
    EXPECT_ERR(affect_rmlr_cv(x, N, P, y, K, &o, &m, &err), AFFECT_ERR_INVALID,
               "n_lambda must be at least 1");
    o.n_lambda = 2000000;
    EXPECT_ERR(affect_rmlr_cv(x, N, P, y, K, &o, &m, &err), AFFECT_ERR_RANGE,
               "too many lambdas: 2000000 (at most 1048576)");
    affect_rmlr_options_default(&o);
    o.alphas = bad_alphas;
    o.n_alpha = 0;
    EXPECT_ERR(affect_rmlr_cv(x, N, P, y, K, &o, &m, &err), AFFECT_ERR_INVALID,
               "need at least 1 alpha");
    o.n_alpha = 4;
    EXPECT_ERR(affect_rmlr_cv(x, N, P, y, K, &o, &m, &err), AFFECT_ERR_INVALID,
               "alpha 3 = 1.5 is not in [0, 1]");
    affect_rmlr_options_default(&o);
    o.folds = 1;
    EXPECT_ERR(affect_rmlr_cv(x, N, P, y, K, &o, &m, &err), AFFECT_ERR_INVALID,
               "need at least 2 folds, got 1");
    affect_rmlr_options_default(&o);
    o.threads = 0;
    EXPECT_ERR(affect_rmlr_cv(x, N, P, y, K, &o, &m, &err), AFFECT_ERR_INVALID,
               "threads must be from 1 to 64, got 0");
    o.threads = 65;
    EXPECT_ERR(affect_rmlr_cv(x, N, P, y, K, &o, &m, &err), AFFECT_ERR_INVALID,
               "threads must be from 1 to 64, got 65");
    assert_null(m);
    affect_rmlr_options_default(&o);
    o.solver = 2;
    EXPECT_ERR(affect_rmlr_cv(x, N, P, y, K, &o, &m, &err), AFFECT_ERR_INVALID,
               "solver must be 0 (Newton) or 1 (CD), got 2");
    EXPECT_ERR(FIT(N, P, y, K, 1, NULL, 1, &o), AFFECT_ERR_INVALID,
               "solver must be 0 (Newton) or 1 (CD), got 2");
    affect_rmlr_options_default(&o);
    o.threads = 0; /* not an option of the path: ignored there */
    assert_int_equal(FIT(N, P, y, K, 1, NULL, 1, &o), AFFECT_OK); /* beta holds one λ */
    y[0] = 2;
    EXPECT_ERR(affect_rmlr_cv(x, N, P, y, 3, NULL, &m, &err), AFFECT_ERR_INVALID,
               "class 2 has 1 sample (cross-validation needs at least 2)");
    assert_null(m);
#undef FIT
}

/* A small model for the encoding tests. */
static affect_rmlr *small_model(void)
{
    enum { N = 40, K = 3 };
    static const double alphas[] = {0.5};
    double x[N * P];
    uint32_t y[N];
    affect_error err;
    affect_rmlr_options o;
    affect_rmlr *m;
    synth(N, K, 3, 2.0, 21, x, y);
    affect_rmlr_options_default(&o);
    o.alphas = alphas;
    o.n_alpha = 1;
    o.n_lambda = 5;
    o.folds = 3;
    assert_int_equal(affect_rmlr_cv(x, N, P, y, K, &o, &m, &err), AFFECT_OK);
    return m;
}

static void test_round_trip(void **state)
{
    (void)state;
    affect_rmlr *m = small_model(), *m2;
    affect_bw w, w2;
    affect_br r;
    affect_error err;
    affect_bw_init(&w);
    affect_bw_init(&w2);
    affect_rmlr_encode(m, &w);
    assert_int_equal(w.len, 20 + 37 + 8 * (2 * 5 + 2 * P + 3 + 3 * P) + 8);
    assert_memory_equal(w.data, "AFRL\x02\0\0\0\0\0\0\0", 12);
    affect_br_init(&r, w.data, w.len);
    assert_int_equal(affect_rmlr_decode(&r, &m2, &err), AFFECT_OK);
    assert_int_equal(r.off, w.len);
    affect_rmlr_encode(m2, &w2);
    assert_int_equal(w2.len, w.len);
    assert_memory_equal(w.data, w2.data, w.len);
    assert_memory_equal(affect_rmlr_beta(m), affect_rmlr_beta(m2), 3 * P * sizeof(double));
    assert_true(affect_rmlr_alpha(m2) == 0.5);
    assert_true(affect_rmlr_lambda(m2) == affect_rmlr_lambda(m));
    double xs[P];
    for (size_t j = 0; j < P; j++)
        xs[j] = (double)j;
    double p1[3], p2[3];
    assert_int_equal(affect_rmlr_predict(m, xs, p1), affect_rmlr_predict(m2, xs, p2));
    assert_memory_equal(p1, p2, sizeof p1);
    affect_bw_free(&w);
    affect_bw_free(&w2);
    affect_rmlr_free(m);
    affect_rmlr_free(m2);
}

static void put_u32(unsigned char *p, uint32_t v)
{
    for (int i = 0; i < 4; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}

static void put_u64_at(unsigned char *p, uint64_t v)
{
    for (int i = 0; i < 8; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}

static void put_f64(unsigned char *p, double d)
{
    uint64_t u;
    memcpy(&u, &d, sizeof u);
    for (int i = 0; i < 8; i++)
        p[i] = (unsigned char)(u >> (8 * i));
}

/* Decodes a copy of w's bytes (size bytes of it) and expects the message. */
static void expect_decode(const affect_bw *w, size_t size, void (*edit)(unsigned char *),
                          const char *message)
{
    unsigned char *b = malloc(w->len);
    affect_rmlr *m = (affect_rmlr *)b;
    affect_br r;
    affect_error err;
    assert_non_null(b);
    memcpy(b, w->data, w->len);
    if (edit)
        edit(b);
    affect_br_init(&r, b, size);
    affect_error_clear(&err);
    assert_int_equal(affect_rmlr_decode(&r, &m, &err), AFFECT_ERR_FORMAT);
    assert_null(m);
    if (message)
        assert_string_equal(err.msg, message);
    free(b);
}

static void e_version(unsigned char *b)
{
    b[0] = 2;
}
static void e_classes(unsigned char *b)
{
    put_u32(b + 1, 1);
}
static void e_features(unsigned char *b)
{
    put_u32(b + 5, 0);
}
static void e_samples(unsigned char *b)
{
    put_u32(b + 9, 1);
}
static void e_lcount(unsigned char *b)
{
    put_u32(b + 13, 0);
}
static void e_lindex(unsigned char *b)
{
    put_u32(b + 17, 5);
}
static void e_conv(unsigned char *b)
{
    b[21] = 2;
}
static void e_alpha(unsigned char *b)
{
    put_f64(b + 22, 2);
}
static void e_cverr(unsigned char *b)
{
    put_f64(b + 30, NAN);
}
static void e_lambda(unsigned char *b)
{
    put_f64(b + 38 + 8 * 3, -1);
}
static void e_cverrs(unsigned char *b)
{
    put_f64(b + 78 + 8 * 4, 2);
}
static void e_mean(unsigned char *b)
{
    put_f64(b + 118 + 8 * 2, INFINITY);
}
static void e_sd(unsigned char *b)
{
    put_f64(b + 118 + 8 * P + 8, -1);
}
static void e_b0(unsigned char *b)
{
    put_f64(b + 118 + 16 * P + 16, NAN);
}
static void e_beta(unsigned char *b)
{
    put_f64(b + 118 + 16 * P + 24 + 8 * 50, NAN);
}

/* Version 1 of a fit: its version byte, then version 2's body (affect/rmlr.h). */
static void encode_v1(const affect_rmlr *m, affect_bw *w)
{
    affect_bw v2;
    affect_bw_init(&v2);
    affect_rmlr_encode(m, &v2);
    assert_false(v2.failed);
    affect_bw_u8(w, 1);
    affect_bw_bytes(w, v2.data + 20, v2.len - 28);
    assert_false(w->failed);
    affect_bw_free(&v2);
}

static void test_corrupt(void **state)
{
    (void)state;
    affect_rmlr *m = small_model();
    affect_bw w;
    affect_bw_init(&w);
    encode_v1(m, &w);
    /* version 1 is still read, and every truncation of it fails */
    affect_br r0;
    affect_rmlr *m0;
    affect_error err0;
    affect_br_init(&r0, w.data, w.len);
    assert_int_equal(affect_rmlr_decode(&r0, &m0, &err0), AFFECT_OK);
    assert_int_equal(r0.off, w.len);
    affect_rmlr_free(m0);
    for (size_t s = 0; s < w.len; s++)
        expect_decode(&w, s, NULL, NULL);
    expect_decode(&w, 0, NULL, "RMLR: truncated: 0 bytes is shorter than the 12-byte header");
    expect_decode(&w, 3, NULL, "RMLR: truncated in the class count (offset 1)");
    expect_decode(&w, 21, NULL, "RMLR: truncated in the converged flag (offset 21)");
    expect_decode(&w, 29, NULL, "RMLR: truncated in alpha (offset 22)");
    expect_decode(&w, 40, NULL, "RMLR: truncated in the lambdas (offset 38)");
    expect_decode(&w, 80, NULL, "RMLR: truncated in the cross-validation errors (offset 78)");
    expect_decode(&w, 118 + 8 * P, NULL, "RMLR: truncated in the standard deviations (offset 334)");
    expect_decode(&w, 118 + 16 * P + 8, NULL, "RMLR: truncated in the intercepts (offset 550)");
    expect_decode(&w, w.len - 1, NULL, "RMLR: truncated in the coefficients (offset 574)");
    expect_decode(&w, w.len, e_version, "RMLR: not an RMLR fit (bad magic bytes at offset 0)");
    expect_decode(&w, w.len, e_classes, "RMLR: class count 1 out of range 2 .. 256 (offset 1)");
    expect_decode(&w, w.len, e_features,
                  "RMLR: feature count 0 out of range 1 .. 1048576 (offset 5)");
    expect_decode(&w, w.len, e_samples, "RMLR: sample count 1 below the class count 3 (offset 9)");
    expect_decode(&w, w.len, e_lcount,
                  "RMLR: lambda count 0 out of range 1 .. 1048576 (offset 13)");
    expect_decode(&w, w.len, e_lindex,
                  "RMLR: lambda index 5 not below the lambda count 5 (offset 17)");
    expect_decode(&w, w.len, e_conv, "RMLR: converged flag 2 is not 0 or 1 (offset 21)");
    expect_decode(&w, w.len, e_alpha, "RMLR: alpha = 2 is not in [0, 1] (offset 22)");
    expect_decode(&w, w.len, e_cverr,
                  "RMLR: cross-validation error nan is not in [0, 1] (offset 30)");
    expect_decode(&w, w.len, e_lambda,
                  "RMLR: lambda 3 = -1 is not a positive finite number (offset 62)");
    expect_decode(&w, w.len, e_cverrs,
                  "RMLR: cross-validation error 2 is not in [0, 1] (offset 110)");
    expect_decode(&w, w.len, e_mean, "RMLR: non-finite value in the means (offset 134)");
    expect_decode(&w, w.len, e_sd,
                  "RMLR: standard deviation -1 is not a non-negative finite number (offset 342)");
    expect_decode(&w, w.len, e_b0, "RMLR: non-finite value in the intercepts (offset 566)");
    expect_decode(&w, w.len, e_beta, "RMLR: non-finite value in the coefficients (offset 974)");
    affect_bw_free(&w);
    affect_rmlr_free(m);
}

/* Version 2 with one edit, its checksum recomputed unless keep_sum. */
static void expect_v2(const affect_bw *w, size_t size, size_t at, const void *bytes, size_t n,
                      bool keep_sum, const char *message)
{
    affect_bw c;
    affect_bw_init(&c);
    affect_bw_bytes(&c, w->data, w->len);
    assert_false(c.failed);
    if (n)
        memcpy(c.data + at, bytes, n);
    if (!keep_sum)
        put_u64_at(c.data + w->len - 8, affect_fnv1a64(c.data, w->len - 8));
    expect_decode(&c, size, NULL, message);
    affect_bw_free(&c);
}

static void test_corrupt_v2(void **state)
{
    (void)state;
    affect_rmlr *m = small_model();
    affect_bw w;
    affect_bw_init(&w);
    affect_rmlr_encode(m, &w);
    size_t len = w.len;
    for (size_t s = 0; s < len; s++)
        expect_decode(&w, s, NULL, NULL);
    expect_decode(&w, 3, NULL, "RMLR: truncated: 3 bytes is shorter than the 12-byte header");
    expect_decode(&w, 19, NULL, "RMLR: truncated in the length (offset 12)");
    char msg[160];
    snprintf(msg, sizeof msg, "RMLR: truncated: %zu bytes, the header says %zu (offset 12)",
             len - 1, len);
    expect_decode(&w, len - 1, NULL, msg);
    expect_v2(&w, len, 0, "AFRM", 4, false, "RMLR: not an RMLR fit (bad magic bytes at offset 0)");
    expect_v2(&w, len, 4, "\3", 1, false,
              "RMLR: unknown format version 3 (this build reads 1 .. 2)");
    expect_v2(&w, len, 4, "\0", 1, false,
              "RMLR: unknown format version 0 (this build reads 1 .. 2)");
    expect_v2(&w, len, 4, "\1", 1, false, "RMLR: version 1 is stored without a header (offset 4)");
    expect_v2(&w, len, 8, "\1", 1, false, "RMLR: flags 0x1 are not 0 (offset 8)");
    unsigned char seven[8];
    put_u64_at(seven, 7);
    snprintf(msg, sizeof msg, "RMLR: truncated: %zu bytes, the header says 7 (offset 12)", len);
    expect_v2(&w, len, 12, seven, 8, false, msg);
    snprintf(msg, sizeof msg, "RMLR: checksum mismatch: the fit is corrupt (offset %zu)", len - 8);
    expect_v2(&w, len, 100, "\xff", 1, true, msg);
    /* the body's errors, 19 bytes further than version 1's */
    expect_v2(&w, len, 20, "\1\0\0\0", 4, false,
              "RMLR: class count 1 out of range 2 .. 256 (offset 20)");
    uint64_t nan_bits = 0x7ff8000000000000ull;
    unsigned char nanb[8];
    put_u64_at(nanb, nan_bits);
    expect_v2(&w, len, 118 + 16 * P + 24 + 8 * 50 + 19, nanb, 8, false,
              "RMLR: non-finite value in the coefficients (offset 993)");
    /* a record two bytes shorter than its length says: bytes follow the coefficients; a
     * record followed by other bytes is read up to its end */
    {
        affect_bw c;
        affect_bw_init(&c);
        affect_bw_bytes(&c, w.data, len - 8);
        affect_bw_u64(&c, 0);
        affect_bw_u64(&c, 0);
        put_u64_at(c.data + 12, len + 8);
        put_u64_at(c.data + len, affect_fnv1a64(c.data, len));
        snprintf(msg, sizeof msg, "RMLR: 8 bytes follow the coefficients (offset %zu)", len - 8);
        expect_decode(&c, c.len, NULL, msg);
        affect_bw_free(&c);
        affect_bw_init(&c);
        affect_bw_bytes(&c, w.data, len);
        affect_bw_bytes(&c, "xyz", 3);
        affect_br r;
        affect_rmlr *m2;
        affect_error err;
        affect_br_init(&r, c.data, c.len);
        assert_int_equal(affect_rmlr_decode(&r, &m2, &err), AFFECT_OK);
        assert_int_equal(r.off, len);
        affect_rmlr_free(m2);
        affect_bw_free(&c);
    }
    affect_bw_free(&w);
    affect_rmlr_free(m);
}

/* tests/fixtures/rmlr-v1.bin: the fit laban_salient cached for the fuzz fixtures' index before
 * the header existed (3 classes, 27 Laban components, 12 rows); rmlr-v2.bin: the same fit as
 * today's encoder writes it. */
static void test_fixtures(void **state)
{
    (void)state;
    size_t n1, n2;
    unsigned char *v1 = (unsigned char *)tu_read_file(AFFECT_FIXTURES_DIR "/rmlr-v1.bin", &n1);
    assert_non_null(v1);
    affect_rmlr *m1, *m2;
    affect_br r;
    affect_error err;
    affect_br_init(&r, v1, n1);
    assert_int_equal(affect_rmlr_decode(&r, &m1, &err), AFFECT_OK);
    assert_int_equal(r.off, n1);
    assert_int_equal(affect_rmlr_n_classes(m1), 3);
    assert_int_equal(affect_rmlr_n_features(m1), 27);
    assert_int_equal(affect_rmlr_n_train(m1), 12);
    affect_bw w;
    affect_bw_init(&w);
    affect_rmlr_encode(m1, &w);
    assert_false(w.failed);
    /* version 2 is version 1's body between the header and the checksum */
    assert_int_equal(w.len, n1 - 1 + 28);
    assert_memory_equal(w.data + 20, v1 + 1, n1 - 1);
    if (getenv("AFFECT_WRITE_FIXTURES")) { /* regenerate: AFFECT_WRITE_FIXTURES=1 test_rmlr */
        FILE *out = fopen(AFFECT_FIXTURES_DIR "/rmlr-v2.bin", "wb");
        assert_non_null(out);
        assert_int_equal(fwrite(w.data, 1, w.len, out), w.len);
        fclose(out);
    }
    unsigned char *v2 = (unsigned char *)tu_read_file(AFFECT_FIXTURES_DIR "/rmlr-v2.bin", &n2);
    assert_non_null(v2);
    assert_int_equal(n2, w.len);
    assert_memory_equal(v2, w.data, n2);
    affect_br_init(&r, v2, n2);
    assert_int_equal(affect_rmlr_decode(&r, &m2, &err), AFFECT_OK);
    assert_int_equal(r.off, n2);
    affect_bw w2;
    affect_bw_init(&w2);
    affect_rmlr_encode(m2, &w2);
    assert_int_equal(w2.len, n2);
    assert_memory_equal(w2.data, v2, n2);
    assert_true(affect_rmlr_alpha(m1) == affect_rmlr_alpha(m2));
    assert_memory_equal(affect_rmlr_beta(m1), affect_rmlr_beta(m2), 3 * 27 * sizeof(double));
    affect_bw_free(&w);
    affect_bw_free(&w2);
    affect_rmlr_free(m1);
    affect_rmlr_free(m2);
    free(v1);
    free(v2);
}

/* ---- out of memory ---- */

typedef struct oom_ctx {
    double x[30 * 5];
    uint32_t y[30];
    affect_rmlr *m;
    affect_bw w;
    double beta[4 * 3 * 5];
    uint32_t threads;
} oom_ctx;

static affect_status oom_cv(void *ctx, affect_error *err)
{
    oom_ctx *c = ctx;
    static const double alphas[] = {0.5, 1.0};
    affect_rmlr_options o;
    affect_rmlr_options_default(&o);
    o.alphas = alphas;
    o.n_alpha = 2;
    o.n_lambda = 4;
    o.folds = 3;
    o.threads = c->threads;
    return affect_rmlr_cv(c->x, 30, 5, c->y, 3, &o, &c->m, err);
}

static void oom_model_finish(void *ctx, affect_status st)
{
    oom_ctx *c = ctx;
    if (st == AFFECT_OK)
        assert_non_null(c->m);
    else
        assert_null(c->m);
    affect_rmlr_free(c->m);
    c->m = NULL;
}

static affect_status oom_path(void *ctx, affect_error *err)
{
    oom_ctx *c = ctx;
    return affect_rmlr_fit_path(c->x, 30, 5, c->y, 3, 0.5, NULL, 4, NULL, NULL, c->beta, NULL, NULL,
                                err);
}

static affect_status oom_encode(void *ctx, affect_error *err)
{
    oom_ctx *c = ctx;
    affect_bw_init(&c->w);
    affect_rmlr_encode(c->m, &c->w);
    return c->w.failed ? affect_nomem(err) : AFFECT_OK;
}

static void oom_encode_finish(void *ctx, affect_status st)
{
    oom_ctx *c = ctx;
    (void)st;
    affect_bw_free(&c->w);
}

static affect_status oom_decode(void *ctx, affect_error *err)
{
    oom_ctx *c = ctx;
    affect_br r;
    affect_br_init(&r, c->w.data, c->w.len);
    return affect_rmlr_decode(&r, &c->m, err);
}

static void test_out_of_memory(void **state)
{
    (void)state;
    oom_ctx c;
    affect_error err;
    memset(&c, 0, sizeof c);
    affect_rng r;
    affect_rng_seed(&r, 77);
    for (size_t i = 0; i < 30; i++) {
        c.y[i] = (uint32_t)(i % 3);
        for (size_t j = 0; j < 5; j++)
            c.x[i * 5 + j] = affect_rng_normal(&r) + (j == c.y[i] ? 1.5 : 0);
    }
    c.threads = 1;
    long allocs1 = tu_oom_sweep(oom_cv, &c, oom_model_finish, NULL);
    /* with 2 threads every allocation still happens on the calling thread, before the other
     * starts: one more fitter (2 blocks) and the thread handles */
    c.threads = 2;
    long allocs2 = tu_oom_sweep(oom_cv, &c, oom_model_finish, NULL);
    assert_true(allocs1 >= 10);
    assert_int_equal(allocs2, allocs1 + 3);
    c.threads = 1;
    assert_true(tu_oom_sweep(oom_path, &c, NULL, NULL) >= 4);
    assert_int_equal(oom_cv(&c, &err), AFFECT_OK);
    affect_rmlr *m = c.m;
    assert_true(tu_oom_sweep(oom_encode, &c, oom_encode_finish, NULL) >= 1);
    affect_bw_init(&c.w);
    affect_rmlr_encode(m, &c.w);
    c.m = NULL;
    assert_true(tu_oom_sweep(oom_decode, &c, oom_model_finish, NULL) == 2);
    affect_bw_free(&c.w);
    affect_rmlr_free(m);
}

static void test_impute(void **state)
{
    (void)state;
    /* 4 × 4: missing values in rows 1 and 3 of column 0, everywhere in column 1, infinities in
     * column 2, none in column 3 */
    double x[4 * 4] = {0.1, NAN, INFINITY,  -0.0, NAN, NAN, 0.5,  2.0,
                       0.2, NAN, -INFINITY, 3.0,  NAN, NAN, 0.25, 4.5};
    const double mean0 = (0.1 + 0.2) / 2, mean2 = (0.5 + 0.25) / 2;
    const double want[4 * 4] = {0.1, 0, mean2, -0.0, mean0, 0, 0.5,  2.0,
                                0.2, 0, mean2, 3.0,  mean0, 0, 0.25, 4.5};
    affect_impute_column_means(x, 4, 4);
    assert_memory_equal(x, want, sizeof x); /* exact bits: -0.0 kept, the means in row order */
    /* the sum in row order, divided by the count */
    double y[5] = {0.1, 0.2, NAN, 0.3, NAN};
    affect_impute_column_means(y, 5, 1);
    assert_true(y[2] == (0.1 + 0.2 + 0.3) / 3 && y[4] == y[2] && y[0] == 0.1);
    /* nothing to do */
    affect_impute_column_means(NULL, 0, 3);
    affect_impute_column_means(x, 4, 0);
    assert_memory_equal(x, want, sizeof x);
    /* one row: its missing values become 0 */
    double z[3] = {NAN, 7, -INFINITY};
    affect_impute_column_means(z, 1, 3);
    assert_true(z[0] == 0 && z[1] == 7 && z[2] == 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_kkt),           cmocka_unit_test(test_lasso_path),
        cmocka_unit_test(test_recovery),      cmocka_unit_test(test_constant_feature),
        cmocka_unit_test(test_determinism),   cmocka_unit_test(test_errors),
        cmocka_unit_test(test_round_trip),    cmocka_unit_test(test_corrupt),
        cmocka_unit_test(test_corrupt_v2),    cmocka_unit_test(test_fixtures),
        cmocka_unit_test(test_out_of_memory), cmocka_unit_test(test_threads),
        cmocka_unit_test(test_impute),        cmocka_unit_test(test_strong_rule_kkt),
        cmocka_unit_test(test_newton_vs_cd),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
