/*
 * test_spca.c — supervised PCA (HSIC) in the dual and k-NN classification (affect/spca.h):
 * the HSIC on a hand-computed example, the dual against the primal d × d eigenproblem solved
 * here by Jacobi rotations (independent of LAPACK), the Gram-matrix variant, orthonormal axes
 * over several column blocks and far from the origin, separation of well-separated classes,
 * rbf with a small σ against linear, the rank cap, Σλ against the HSIC, the k-NN tie rules,
 * determinism, bit-identical round trips, every truncation and corruption of the record, every
 * error message, and allocation failure.
 */
#include <stdio.h>
#include <string.h>

#include "testutil.h"

#include "affect/hmm_blob.h" /* affect_fnv1a64 */
#include "util/rng.h"
#include "affect/spca.h"
#include "util/bytes.h"

/* ---- helpers ---- */

/* n × d data, labels y_i = i mod c; row i = offset + sep × centre(y_i) + N(0, 1) noise, the
 * class centres themselves N(0, 1) per coordinate. Caller frees x and y with free(). */
static void make_data(size_t n, size_t d, uint32_t c, double sep, double offset, uint64_t seed,
                      double **x_out, uint32_t **y_out)
{
    affect_rng r;
    affect_rng_seed(&r, seed);
    double *centre = malloc(c * d * sizeof *centre);
    double *x = malloc(n * d * sizeof *x);
    uint32_t *y = malloc(n * sizeof *y);
    assert_non_null(centre);
    assert_non_null(x);
    assert_non_null(y);
    for (size_t i = 0; i < c * d; i++)
        centre[i] = affect_rng_normal(&r);
    for (size_t i = 0; i < n; i++) {
        y[i] = (uint32_t)(i % c);
        for (size_t j = 0; j < d; j++)
            x[i * d + j] = offset + sep * centre[y[i] * d + j] + affect_rng_normal(&r);
    }
    free(centre);
    *x_out = x;
    *y_out = y;
}

static affect_spca *fit_ok(const double *x, size_t n, size_t d, const uint32_t *y, uint32_t c,
                           affect_spca_kernel kernel, double sigma, uint32_t dims)
{
    affect_spca *s = NULL;
    affect_error err;
    affect_status st = affect_spca_fit(x, n, d, y, c, kernel, sigma, dims, &s, &err);
    if (st != AFFECT_OK)
        fail_msg("fit: %s", err.msg);
    return s;
}

/* Asserts that fit fails with status st and exactly message msg. */
static void fit_fails(const double *x, size_t n, size_t d, const uint32_t *y, uint32_t c,
                      affect_spca_kernel kernel, double sigma, uint32_t dims, affect_status st,
                      const char *msg)
{
    affect_spca *s = (affect_spca *)&s; /* must be reset to NULL */
    affect_error err;
    assert_int_equal(affect_spca_fit(x, n, d, y, c, kernel, sigma, dims, &s, &err), st);
    assert_null(s);
    assert_int_equal(err.status, st);
    assert_string_equal(err.msg, msg);
}

/* The Gram matrix X Xᵀ by plain loops. Caller frees. */
static double *gram(const double *x, size_t n, size_t d)
{
    double *k = malloc(n * n * sizeof *k);
    assert_non_null(k);
    for (size_t i = 0; i < n; i++)
        for (size_t j = 0; j < n; j++) {
            double s = 0;
            for (size_t l = 0; l < d; l++)
                s += x[i * d + l] * x[j * d + l];
            k[i * n + j] = s;
        }
    return k;
}

/* The label kernel written out independently of spca.c. */
static double label_b(uint32_t a, uint32_t b, affect_spca_kernel kernel, double sigma)
{
    if (kernel == AFFECT_SPCA_LINEAR)
        return a == b ? 1.0 : 0.0;
    double t = (double)a - (double)b;
    return exp(-t * t / (2 * sigma * sigma));
}

/* Eigen-decomposition of the symmetric m × m matrix a (destroyed) by cyclic Jacobi rotations:
 * w gets the eigenvalues in descending order, row r of v the eigenvector of w[r]. */
static void jacobi(double *a, int m, double *w, double *v)
{
    double *q = calloc((size_t)m * m, sizeof *q);
    assert_non_null(q);
    for (int i = 0; i < m; i++)
        q[i * m + i] = 1;
    for (int sweep = 0; sweep < 100; sweep++) {
        double off = 0, total = 0;
        for (int i = 0; i < m; i++)
            for (int j = 0; j < m; j++) {
                total += a[i * m + j] * a[i * m + j];
                if (i != j)
                    off += a[i * m + j] * a[i * m + j];
            }
        if (off <= 1e-32 * total)
            break;
        for (int p = 0; p < m; p++)
            for (int r = p + 1; r < m; r++) {
                double apr = a[p * m + r];
                if (apr == 0)
                    continue;
                double theta = (a[r * m + r] - a[p * m + p]) / (2 * apr);
                double t = (theta >= 0 ? 1 : -1) / (fabs(theta) + sqrt(theta * theta + 1));
                double cs = 1 / sqrt(t * t + 1), sn = t * cs;
                for (int k = 0; k < m; k++) { /* columns p, r of a */
                    double akp = a[k * m + p], akr = a[k * m + r];
                    a[k * m + p] = cs * akp - sn * akr;
                    a[k * m + r] = sn * akp + cs * akr;
                }
                for (int k = 0; k < m; k++) { /* rows p, r of a */
                    double apk = a[p * m + k], ark = a[r * m + k];
                    a[p * m + k] = cs * apk - sn * ark;
                    a[r * m + k] = sn * apk + cs * ark;
                }
                for (int k = 0; k < m; k++) { /* columns p, r of q */
                    double qkp = q[k * m + p], qkr = q[k * m + r];
                    q[k * m + p] = cs * qkp - sn * qkr;
                    q[k * m + r] = sn * qkp + cs * qkr;
                }
            }
    }
    int *order = malloc((size_t)m * sizeof *order);
    assert_non_null(order);
    for (int i = 0; i < m; i++)
        order[i] = i;
    for (int i = 0; i < m; i++) /* selection sort, descending */
        for (int j = i + 1; j < m; j++)
            if (a[order[j] * m + order[j]] > a[order[i] * m + order[i]]) {
                int t = order[i];
                order[i] = order[j];
                order[j] = t;
            }
    for (int r = 0; r < m; r++) {
        w[r] = a[order[r] * m + order[r]];
        for (int k = 0; k < m; k++)
            v[r * m + k] = q[k * m + order[r]];
    }
    free(order);
    free(q);
}

/* Asserts that row q of axes (d values) equals ±v within tol. */
static void assert_same_axis(const double *u, const double *v, size_t d, double tol)
{
    double dot = 0;
    for (size_t j = 0; j < d; j++)
        dot += u[j] * v[j];
    double sign = dot < 0 ? -1 : 1;
    for (size_t j = 0; j < d; j++)
        tu_assert_near(u[j], sign * v[j], tol);
}

/* Asserts the sign convention: the first largest-magnitude component of every axis is > 0. */
static void assert_sign_convention(const affect_spca *s)
{
    size_t d = affect_spca_input_dim(s);
    const double *u = affect_spca_axes(s);
    for (uint32_t q = 0; q < affect_spca_dims(s); q++) {
        const double *row = u + q * d;
        size_t best = 0;
        for (size_t j = 1; j < d; j++)
            if (fabs(row[j]) > fabs(row[best]))
                best = j;
        assert_true(row[best] > 0);
    }
}

static void assert_orthonormal(const affect_spca *s, double tol)
{
    size_t d = affect_spca_input_dim(s);
    uint32_t p = affect_spca_dims(s);
    const double *u = affect_spca_axes(s);
    for (uint32_t a = 0; a < p; a++)
        for (uint32_t b = 0; b < p; b++) {
            double dot = 0;
            for (size_t j = 0; j < d; j++)
                dot += u[a * d + j] * u[b * d + j];
            tu_assert_near(dot, a == b ? 1.0 : 0.0, tol);
        }
}

static unsigned char *encode(const affect_spca *s, size_t *len)
{
    affect_bw w;
    affect_bw_init(&w);
    affect_spca_encode(s, &w);
    assert_false(w.failed);
    *len = w.len;
    return w.data; /* free with affect_free */
}

/* ---- the HSIC by hand ---- */

/* n = 4 one-dimensional samples x = (10, 11, 12, 13), K = x xᵀ, labels y = (0, 0, 1, 1).
 * tr(K H B H) = tr(H K H B) (H² = H, the trace is cyclic) and H K H = x̃ x̃ᵀ with the centred
 * x̃ = x − 11.5 = (−1.5, −0.5, 0.5, 1.5), so tr(K H B H) = Σ_ij x̃_i x̃_j B_ij.
 *   linear: B_ij = [y_i = y_j]: (x̃_1 + x̃_2)² + (x̃_3 + x̃_4)² = (−2)² + 2² = 8,
 *           HSIC = 8 / (4 − 1)² = 8/9.
 *   rbf σ = 1: B_ij = 1 within a class and e^{−1/2} across, which adds
 *           2 e^{−1/2} (x̃_1 + x̃_2)(x̃_3 + x̃_4) = −8 e^{−1/2}: HSIC = (8 − 8 e^{−1/2}) / 9.
 * Adding 100 to every entry of K (or of B) changes nothing, since H e = 0. */
static void test_hsic_by_hand(void **state)
{
    (void)state;
    const double x[4] = {10, 11, 12, 13};
    const uint32_t y[4] = {0, 0, 1, 1};
    double k[16], b[16], k2[16];
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            k[i * 4 + j] = x[i] * x[j];
            k2[i * 4 + j] = k[i * 4 + j] + 100;
        }
    affect_error err;
    assert_int_equal(affect_spca_label_kernel(y, 4, 2, AFFECT_SPCA_LINEAR, 0, b, &err), AFFECT_OK);
    const double lin[16] = {1, 1, 0, 0, 1, 1, 0, 0, 0, 0, 1, 1, 0, 0, 1, 1};
    assert_memory_equal(b, lin, sizeof lin);
    tu_assert_near(affect_hsic(k, b, 4), 8.0 / 9.0, 1e-12);
    tu_assert_near(affect_hsic(k2, b, 4), 8.0 / 9.0, 1e-12);
    assert_int_equal(affect_spca_label_kernel(y, 4, 2, AFFECT_SPCA_RBF, 1.0, b, &err), AFFECT_OK);
    tu_assert_near(b[2], exp(-0.5), 1e-16);
    tu_assert_near(b[5], 1.0, 0);
    tu_assert_near(affect_hsic(k, b, 4), (8 - 8 * exp(-0.5)) / 9, 1e-12);
    for (int i = 0; i < 16; i++)
        b[i] += 100;
    tu_assert_near(affect_hsic(k, b, 4), (8 - 8 * exp(-0.5)) / 9, 1e-10);
    /* independent labels: y = (0, 1, 0, 1) → (x̃1 + x̃3)² + (x̃2 + x̃4)² = 1 + 1 = 2 */
    const uint32_t y2[4] = {0, 1, 0, 1};
    assert_int_equal(affect_spca_label_kernel(y2, 4, 2, AFFECT_SPCA_LINEAR, 0, b, &err), AFFECT_OK);
    tu_assert_near(affect_hsic(k, b, 4), 2.0 / 9.0, 1e-12);
    assert_true(affect_hsic(k, b, 1) == 0.0);
    /* label kernel errors */
    assert_int_equal(affect_spca_label_kernel(y, 4, 2, (affect_spca_kernel)5, 1, b, &err),
                     AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "unknown label kernel 5 (0 = linear, 1 = rbf)");
    assert_int_equal(affect_spca_label_kernel(y, 4, 2, AFFECT_SPCA_RBF, 0, b, &err),
                     AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "sigma must be a positive finite number");
    assert_int_equal(affect_spca_label_kernel(y, 4, 1, AFFECT_SPCA_LINEAR, 0, b, &err),
                     AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "row 2: label 1 is out of range (1 classes: 0 .. 0)");
    assert_int_equal(affect_spca_label_kernel(y, 4, 0, AFFECT_SPCA_LINEAR, 0, b, &err),
                     AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "need at least 1 class");
}

/* ---- dual against primal ---- */

/* Forms S = Xᵀ H B H X (d × d) directly and compares its top eigenpairs with the model. */
static void check_primal(const double *x, size_t n, size_t d, const uint32_t *y,
                         affect_spca_kernel kernel, double sigma, const affect_spca *s)
{
    double *xc = malloc(n * d * sizeof *xc); /* H X */
    double *bx = malloc(n * d * sizeof *bx); /* B H X */
    double *sm = malloc(d * d * sizeof *sm), *w = malloc(d * sizeof *w),
           *v = malloc(d * d * sizeof *v);
    assert_true(xc && bx && sm && w && v);
    for (size_t j = 0; j < d; j++) {
        double mean = 0;
        for (size_t i = 0; i < n; i++)
            mean += x[i * d + j];
        mean /= (double)n;
        for (size_t i = 0; i < n; i++)
            xc[i * d + j] = x[i * d + j] - mean;
    }
    for (size_t i = 0; i < n; i++)
        for (size_t j = 0; j < d; j++) {
            double acc = 0;
            for (size_t l = 0; l < n; l++)
                acc += label_b(y[i], y[l], kernel, sigma) * xc[l * d + j];
            bx[i * d + j] = acc;
        }
    for (size_t a = 0; a < d; a++) /* (H X)ᵀ B (H X) = Xᵀ H B H X */
        for (size_t b = 0; b < d; b++) {
            double acc = 0;
            for (size_t i = 0; i < n; i++)
                acc += xc[i * d + a] * bx[i * d + b];
            sm[a * d + b] = acc;
        }
    jacobi(sm, (int)d, w, v);
    uint32_t p = affect_spca_dims(s);
    for (uint32_t q = 0; q < p; q++) {
        tu_assert_near(affect_spca_eigenvalues(s)[q] / w[0], w[q] / w[0], 1e-9);
        assert_same_axis(affect_spca_axes(s) + q * d, v + q * d, d, 1e-9);
    }
    /* the eigenvalues the model dropped are zero in the primal too */
    for (size_t q = p; q < d; q++)
        assert_true(fabs(w[q]) <= 1e-9 * w[0]);
    free(xc);
    free(bx);
    free(sm);
    free(w);
    free(v);
}

static void test_dual_equals_primal(void **state)
{
    (void)state;
    enum { N = 30, D = 5, C = 3 };
    double *x;
    uint32_t *y;
    make_data(N, D, C, 1.5, 3.0, 11, &x, &y);
    const affect_spca_kernel kernels[] = {AFFECT_SPCA_LINEAR, AFFECT_SPCA_RBF, AFFECT_SPCA_RBF};
    const double sigmas[] = {0, 0.7, 4.0};
    for (int t = 0; t < 3; t++) {
        affect_spca *s = fit_ok(x, N, D, y, C, kernels[t], sigmas[t], 5);
        assert_int_equal(affect_spca_dims(s), C - 1);
        assert_int_equal(affect_spca_input_dim(s), D);
        assert_int_equal(affect_spca_classes(s), C);
        assert_int_equal(affect_spca_train_size(s), N);
        assert_int_equal(affect_spca_get_kernel(s), kernels[t]);
        assert_true(affect_spca_sigma(s) == sigmas[t]);
        check_primal(x, N, D, y, kernels[t], sigmas[t], s);
        assert_sign_convention(s);
        assert_orthonormal(s, 1e-12);

        /* the Gram-matrix variant gives the same model */
        double *k = gram(x, N, D);
        affect_spca *g = NULL;
        affect_error err;
        assert_int_equal(affect_spca_fit_gram(x, k, N, D, y, C, kernels[t], sigmas[t], 5, &g, &err),
                         AFFECT_OK);
        assert_int_equal(affect_spca_dims(g), C - 1);
        for (uint32_t q = 0; q < C - 1; q++) {
            tu_assert_near(affect_spca_eigenvalues(g)[q], affect_spca_eigenvalues(s)[q],
                           1e-9 * affect_spca_eigenvalues(s)[0]);
            for (size_t j = 0; j < D; j++)
                tu_assert_near(affect_spca_axes(g)[q * D + j], affect_spca_axes(s)[q * D + j],
                               1e-9);
        }
        /* only the upper triangle is read */
        for (size_t i = 0; i < N; i++)
            for (size_t j = 0; j < i; j++)
                k[i * N + j] = NAN;
        affect_spca *g2 = NULL;
        assert_int_equal(
            affect_spca_fit_gram(x, k, N, D, y, C, kernels[t], sigmas[t], 5, &g2, &err), AFFECT_OK);
        assert_memory_equal(affect_spca_axes(g2), affect_spca_axes(g),
                            (C - 1) * D * sizeof(double));
        affect_spca_free(g2);
        affect_spca_free(g);
        free(k);
        affect_spca_free(s);
    }
    free(x);
    free(y);
}

/* ---- orthonormality, blocks, offsets ---- */

static void test_orthonormal_blocks_and_offset(void **state)
{
    (void)state;
    /* n = 60: column blocks of 262144 / 60 = 4369 columns, so d = 10000 takes three */
    enum { N = 60, D = 10000, C = 4 };
    double *x, *x2;
    uint32_t *y, *y2;
    make_data(N, D, C, 0.3, 0.0, 5, &x, &y);
    make_data(N, D, C, 0.3, 1000.0, 5, &x2, &y2); /* the same data, 1000 away from the origin */
    affect_spca *s = fit_ok(x, N, D, y, C, AFFECT_SPCA_RBF, 0.5, 3);
    affect_spca *s2 = fit_ok(x2, N, D, y2, C, AFFECT_SPCA_RBF, 0.5, 3);
    assert_int_equal(affect_spca_dims(s), 3);
    assert_orthonormal(s, 1e-10);
    assert_orthonormal(s2, 1e-10);
    assert_sign_convention(s);
    /* centring happens before any product: the offset costs almost no precision */
    for (uint32_t q = 0; q < 3; q++) {
        tu_assert_near(affect_spca_eigenvalues(s2)[q] / affect_spca_eigenvalues(s)[q], 1.0, 1e-9);
        for (size_t j = 0; j < D; j++)
            tu_assert_near(affect_spca_axes(s2)[q * D + j], affect_spca_axes(s)[q * D + j], 1e-9);
    }
    /* the embedding is not centred: the offset moves every point by the same vector */
    double z[3], z2[3], shift[3];
    affect_spca_embed(s, x, z);
    affect_spca_embed(s, x2, z2);
    for (uint32_t q = 0; q < 3; q++)
        shift[q] = z2[q] - z[q];
    affect_spca_embed(s, x + 7 * D, z);
    affect_spca_embed(s, x2 + 7 * D, z2);
    for (uint32_t q = 0; q < 3; q++)
        tu_assert_near(z2[q] - z[q], shift[q], 1e-8);
    /* fit_gram on the same data, K also of the data far from the origin */
    double *k = gram(x2, N, D);
    affect_spca *g = NULL;
    affect_error err;
    assert_int_equal(affect_spca_fit_gram(x2, k, N, D, y2, C, AFFECT_SPCA_RBF, 0.5, 3, &g, &err),
                     AFFECT_OK);
    for (size_t j = 0; j < 3 * (size_t)D; j++)
        tu_assert_near(affect_spca_axes(g)[j], affect_spca_axes(s)[j], 1e-6);
    affect_spca_free(g);
    free(k);
    affect_spca_free(s);
    affect_spca_free(s2);
    free(x);
    free(y);
    free(x2);
    free(y2);
}

/* ---- separation and k-NN in the projection ---- */

static void test_separation(void **state)
{
    (void)state;
    enum { N = 80, D = 300, C = 4, Q = 40 };
    double *x;
    uint32_t *y;
    /* class centres 1.2 σ apart per coordinate: noise dominates any single feature, the
     * projection should still gather the classes */
    make_data(N + Q, D, C, 1.2, 0.0, 21, &x, &y);
    affect_spca *s = fit_ok(x, N, D, y, C, AFFECT_SPCA_LINEAR, 0, 3);
    uint32_t p = affect_spca_dims(s);
    assert_int_equal(p, 3);
    double *z = malloc((N + Q) * p * sizeof *z);
    assert_non_null(z);
    affect_spca_embed_rows(s, x, N + Q, z);
    double one[3];
    affect_spca_embed(s, x + 5 * D, one);
    assert_memory_equal(one, z + 5 * p, sizeof one); /* embed_rows = embed row by row */
    /* training points: mean within-class distance far below the between-class one */
    double within = 0, between = 0;
    size_t nw = 0, nb = 0;
    for (size_t i = 0; i < N; i++)
        for (size_t j = i + 1; j < N; j++) {
            double d2 = 0;
            for (uint32_t q = 0; q < p; q++)
                d2 += (z[i * p + q] - z[j * p + q]) * (z[i * p + q] - z[j * p + q]);
            if (y[i] == y[j]) {
                within += sqrt(d2);
                nw++;
            } else {
                between += sqrt(d2);
                nb++;
            }
        }
    assert_true(between / (double)nb > 3 * within / (double)nw);
    /* held-out points (same class centres) classified by 5-NN among the training points */
    unsigned right = 0;
    for (size_t i = N; i < N + Q; i++) {
        uint32_t label = 99, votes[C];
        affect_error err;
        assert_int_equal(affect_knn_classify(z, y, N, p, C, z + i * p, 5, &label, votes, &err),
                         AFFECT_OK);
        assert_int_equal(votes[0] + votes[1] + votes[2] + votes[3], 5);
        right += label == y[i];
    }
    assert_true(right >= Q - 1);
    free(z);
    affect_spca_free(s);
    free(x);
    free(y);
}

/* ---- rbf with a small σ is the linear kernel ---- */

/* Why: labels are integers, so two samples of different classes have |y_i − y_j| ≥ 1 and
 * B_ij = exp(−(y_i − y_j)²/(2σ²)) ≤ exp(−1/(2σ²)), while samples of one class have B_ij = 1.
 * At σ = 0.02 that bound is exp(−1250), which is 0 in double precision, so B is exactly the
 * one-hot kernel E Eᵀ; at σ = 0.1 it is exp(−50) ≈ 2e-22, below rounding. The same B gives
 * the same matrix Xᵀ H B H X, hence the same axes (equal, not just up to sign, given the sign
 * convention) and the same eigenvalues, although the dual goes through G^{1/2} from LAPACK. */
static void test_rbf_small_sigma_is_linear(void **state)
{
    (void)state;
    enum { N = 40, D = 50, C = 5 };
    double *x;
    uint32_t *y;
    make_data(N, D, C, 0.8, 0.0, 3, &x, &y);
    affect_spca *lin = fit_ok(x, N, D, y, C, AFFECT_SPCA_LINEAR, 0, 4);
    const double sigmas[] = {0.02, 0.1};
    for (int t = 0; t < 2; t++) {
        affect_spca *rbf = fit_ok(x, N, D, y, C, AFFECT_SPCA_RBF, sigmas[t], 4);
        assert_int_equal(affect_spca_dims(rbf), affect_spca_dims(lin));
        for (uint32_t q = 0; q < 4; q++) {
            tu_assert_near(affect_spca_eigenvalues(rbf)[q] / affect_spca_eigenvalues(lin)[q], 1.0,
                           1e-12);
            for (size_t j = 0; j < D; j++)
                tu_assert_near(affect_spca_axes(rbf)[q * D + j], affect_spca_axes(lin)[q * D + j],
                               1e-10);
        }
        affect_spca_free(rbf);
    }
    /* a large σ does differ: the classes are then ordered along the index */
    affect_spca *wide = fit_ok(x, N, D, y, C, AFFECT_SPCA_RBF, 3.0, 4);
    double dot = 0;
    for (size_t j = 0; j < D; j++)
        dot += affect_spca_axes(wide)[j] * affect_spca_axes(lin)[j];
    assert_true(fabs(dot) < 0.999);
    affect_spca_free(wide);
    affect_spca_free(lin);
    free(x);
    free(y);
}

/* ---- the number of axes ---- */

static void test_rank_cap(void **state)
{
    (void)state;
    enum { N = 36, D = 20 };
    double *x;
    uint32_t *y;
    make_data(N, D, 3, 1.0, 0.0, 8, &x, &y);
    affect_spca *s = fit_ok(x, N, D, y, 3, AFFECT_SPCA_LINEAR, 0, 10);
    assert_int_equal(affect_spca_dims(s), 2); /* c − 1 */
    affect_spca_free(s);
    s = fit_ok(x, N, D, y, 3, AFFECT_SPCA_RBF, 1.0, 10);
    assert_int_equal(affect_spca_dims(s), 2);
    affect_spca_free(s);
    s = fit_ok(x, N, D, y, 3, AFFECT_SPCA_LINEAR, 0, 1);
    assert_int_equal(affect_spca_dims(s), 1); /* as asked */
    affect_spca_free(s);
    free(x);
    free(y);
    /* d = 1 caps it at 1 whatever c */
    make_data(N, 1, 4, 2.0, 0.0, 9, &x, &y);
    s = fit_ok(x, N, 1, y, 4, AFFECT_SPCA_LINEAR, 0, 3);
    assert_int_equal(affect_spca_dims(s), 1);
    tu_assert_near(affect_spca_axes(s)[0], 1.0, 1e-12); /* the only unit vector, sign + */
    affect_spca_free(s);
    free(x);
    free(y);
    /* 6 classes, d = 2: at most 2 */
    make_data(N, 2, 6, 2.0, 0.0, 10, &x, &y);
    s = fit_ok(x, N, 2, y, 6, AFFECT_SPCA_RBF, 0.5, 5);
    assert_int_equal(affect_spca_dims(s), 2);
    affect_spca_free(s);
    free(x);
    free(y);
}

/* Σ λ_r = tr(U Xᵀ H B H X Uᵀ) = (n − 1)² HSIC(Z Zᵀ, B) for the embedded training data Z, and
 * with every nonzero eigenvalue kept it is also (n − 1)² HSIC(X Xᵀ, B). */
static void test_eigenvalues_are_hsic(void **state)
{
    (void)state;
    enum { N = 45, D = 30, C = 3 };
    double *x;
    uint32_t *y;
    make_data(N, D, C, 0.7, 2.0, 17, &x, &y);
    affect_spca *s = fit_ok(x, N, D, y, C, AFFECT_SPCA_RBF, 1.5, 2);
    double z[N * 2], kz[N * N], b[N * N];
    affect_spca_embed_rows(s, x, N, z);
    for (size_t i = 0; i < N; i++)
        for (size_t j = 0; j < N; j++)
            kz[i * N + j] = z[i * 2] * z[j * 2] + z[i * 2 + 1] * z[j * 2 + 1];
    affect_error err;
    assert_int_equal(affect_spca_label_kernel(y, N, C, AFFECT_SPCA_RBF, 1.5, b, &err), AFFECT_OK);
    double sum = affect_spca_eigenvalues(s)[0] + affect_spca_eigenvalues(s)[1];
    double scale = (N - 1.0) * (N - 1.0);
    tu_assert_near(affect_hsic(kz, b, N) * scale / sum, 1.0, 1e-9);
    double *k = gram(x, N, D);
    tu_assert_near(affect_hsic(k, b, N) * scale / sum, 1.0, 1e-9);
    /* keeping one axis captures less */
    affect_spca *s1 = fit_ok(x, N, D, y, C, AFFECT_SPCA_RBF, 1.5, 1);
    assert_true(affect_spca_eigenvalues(s1)[0] == affect_spca_eigenvalues(s)[0]);
    assert_true(affect_spca_eigenvalues(s)[1] < affect_spca_eigenvalues(s)[0]);
    affect_spca_free(s1);
    free(k);
    affect_spca_free(s);
    free(x);
    free(y);
}

/* ---- k-NN ---- */

static uint32_t knn(const double *tz, const uint32_t *ty, size_t n, uint32_t c, double q,
                    uint32_t k, uint32_t *votes)
{
    uint32_t label = 99;
    affect_error err;
    affect_status st = affect_knn_classify(tz, ty, n, 1, c, &q, k, &label, votes, &err);
    if (st != AFFECT_OK)
        fail_msg("knn: %s", err.msg);
    return label;
}

static void test_knn_rules(void **state)
{
    (void)state;
    /* equal distances: the lower training index wins, whatever its class */
    const double a[] = {-1, 1};
    const uint32_t ya[] = {1, 0}, yb[] = {0, 1};
    assert_int_equal(knn(a, ya, 2, 2, 0.0, 1, NULL), 1);
    assert_int_equal(knn(a, yb, 2, 2, 0.0, 1, NULL), 0);
    /* one vote each, equal summed distances: the lower class */
    uint32_t votes[3] = {7, 7, 7};
    assert_int_equal(knn(a, ya, 2, 2, 0.0, 2, votes), 0);
    assert_int_equal(votes[0], 1);
    assert_int_equal(votes[1], 1);
    /* one vote each: the smaller summed distance beats the lower class */
    const double b[] = {-1, 3};
    assert_int_equal(knn(b, ya, 2, 2, 0.0, 2, NULL), 1);
    /* majority beats proximity */
    const double c3[] = {-1, 2, 2.5};
    const uint32_t yc[] = {1, 0, 0};
    assert_int_equal(knn(c3, yc, 3, 2, 0.0, 3, NULL), 0);
    assert_int_equal(knn(c3, yc, 3, 2, 0.0, 1, NULL), 1);
    /* k is clamped to n; a class without votes is reported with 0 */
    assert_int_equal(knn(c3, yc, 3, 3, 0.0, 100, votes), 0);
    assert_int_equal(votes[0], 2);
    assert_int_equal(votes[1], 1);
    assert_int_equal(votes[2], 0);
    /* a distance tie at the k-th place: the lower index gets in. Rows 1 (class 2) and 2
     * (class 1) are both 2 from the query; with k = 2, row 1 joins row 0 (class 1). */
    const double d4[] = {0.5, 2, -2, 10};
    const uint32_t yd[] = {1, 2, 1, 2};
    assert_int_equal(knn(d4, yd, 4, 3, 0.0, 2, votes), 1); /* 1 : 1, sums 0.5 < 2 */
    assert_int_equal(votes[2], 1);
    const uint32_t ye[] = {1, 1, 2, 2}; /* now row 1 is class 1: two votes */
    assert_int_equal(knn(d4, ye, 4, 3, 0.0, 2, votes), 1);
    assert_int_equal(votes[1], 2);
    const double d5[] = {0.5, -2, 2, 10}; /* swap rows 1 and 2: row 1 is class 1 */
    const uint32_t yf[] = {2, 1, 1, 1};
    assert_int_equal(knn(d5, yf, 4, 3, 0.0, 2, votes), 2); /* 1 : 1, sums 0.5 < 2 */
    /* equal distances that both got in keep their order when a nearer point arrives: rows
     * 0 and 1 are both 2 away, row 2 pushes the later of them (row 1) out */
    const double e3[] = {2, -2, 0.5};
    const uint32_t ye3[] = {0, 1, 2};
    assert_int_equal(knn(e3, ye3, 3, 3, 0.0, 2, votes), 2); /* 1 : 1, sums 0.5 < 2 */
    assert_int_equal(votes[0], 1);
    assert_int_equal(votes[1], 0);
    /* several dimensions */
    const double t2[] = {0, 0, 3, 4, 1, 1};
    const uint32_t y2[] = {0, 1, 1};
    const double q2[] = {2.5, 3.5};
    uint32_t label;
    affect_error err;
    assert_int_equal(affect_knn_classify(t2, y2, 3, 2, 2, q2, 1, &label, NULL, &err), AFFECT_OK);
    assert_int_equal(label, 1);
    /* deterministic */
    for (int i = 0; i < 3; i++)
        assert_int_equal(knn(d4, yd, 4, 3, 0.0, 2, NULL), 1);
    /* errors */
    const double bad[] = {0, NAN};
    const uint32_t ybad[] = {0, 3};
    struct {
        const double *z;
        const uint32_t *y;
        size_t n;
        uint32_t p, c, k;
        const double *q;
        const char *msg;
    } cases[] = {
        {a, ya, 0, 1, 2, 1, q2, "no training points"},
        {a, ya, 2, 0, 2, 1, q2, "the embedding has no dimensions"},
        {a, ya, 2, 1, 0, 1, q2, "need at least 1 class"},
        {a, ya, 2, 1, 2, 0, q2, "k must be at least 1"},
        {a, ybad, 2, 1, 2, 1, q2, "training row 1: label 3 is out of range (2 classes: 0 .. 1)"},
        {bad, ya, 2, 1, 2, 1, q2, "training row 1, coordinate 0: non-finite value"},
        {t2, y2, 3, 2, 2, 1, bad, "query coordinate 1: non-finite value"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        assert_int_equal(affect_knn_classify(cases[i].z, cases[i].y, cases[i].n, cases[i].p,
                                             cases[i].c, cases[i].q, cases[i].k, &label, NULL,
                                             &err),
                         AFFECT_ERR_INVALID);
        assert_string_equal(err.msg, cases[i].msg);
    }
}

/* ---- determinism and serialisation ---- */

static void test_determinism_and_round_trip(void **state)
{
    (void)state;
    enum { N = 50, D = 40, C = 4 };
    double *x;
    uint32_t *y;
    make_data(N, D, C, 0.9, 1.0, 77, &x, &y);
    affect_spca *s = fit_ok(x, N, D, y, C, AFFECT_SPCA_RBF, 0.75, 3);
    affect_spca *s2 = fit_ok(x, N, D, y, C, AFFECT_SPCA_RBF, 0.75, 3);
    size_t len, len2;
    unsigned char *blob = encode(s, &len), *blob2 = encode(s2, &len2);
    assert_int_equal(len, AFFECT_SPCA_HEADER_SIZE + 3 * 8 + 3 * D * 8 + 8);
    assert_int_equal(len2, len);
    assert_memory_equal(blob, blob2, len); /* same inputs, same bytes */
    assert_memory_equal(blob, "AFSP\1\0\0\0\0\0\0\0\1\0\0\0\4\0\0\0\3\0\0\0", 24);

    /* decode, re-encode: bit-identical; every accessor and embedding equal */
    affect_br r;
    affect_br_init(&r, blob, len);
    affect_spca *t = NULL;
    affect_error err;
    assert_int_equal(affect_spca_decode(&r, &t, &err), AFFECT_OK);
    assert_int_equal(r.off, len);
    size_t len3;
    unsigned char *blob3 = encode(t, &len3);
    assert_int_equal(len3, len);
    assert_memory_equal(blob3, blob, len);
    assert_int_equal(affect_spca_dims(t), 3);
    assert_int_equal(affect_spca_input_dim(t), D);
    assert_int_equal(affect_spca_classes(t), C);
    assert_int_equal(affect_spca_train_size(t), N);
    assert_int_equal(affect_spca_get_kernel(t), AFFECT_SPCA_RBF);
    assert_true(affect_spca_sigma(t) == 0.75);
    assert_memory_equal(affect_spca_eigenvalues(t), affect_spca_eigenvalues(s), 3 * sizeof(double));
    double z[3], zt[3];
    affect_spca_embed(s, x + 3 * D, z);
    affect_spca_embed(t, x + 3 * D, zt);
    assert_memory_equal(z, zt, sizeof z);

    /* inside a larger buffer: offsets count from the buffer, r stops after the record */
    unsigned char *big = malloc(len + 13);
    assert_non_null(big);
    memset(big, 0xAB, len + 13);
    memcpy(big + 8, blob, len);
    affect_spca *u = NULL;
    affect_br_init(&r, big, len + 13);
    r.off = 8;
    assert_int_equal(affect_spca_decode(&r, &u, &err), AFFECT_OK);
    assert_int_equal(r.off, 8 + len);
    affect_spca_free(u);
    affect_br_init(&r, big, 8 + 60);
    r.off = 8;
    assert_int_equal(affect_spca_decode(&r, &u, &err), AFFECT_ERR_FORMAT);
    assert_string_equal(err.msg, "sPCA: truncated in the eigenvalues (offset 56)");
    free(big);

    /* a linear model too */
    affect_spca *l = fit_ok(x, N, D, y, C, AFFECT_SPCA_LINEAR, 0.75, 2);
    assert_true(affect_spca_sigma(l) == 0.0);
    size_t ll;
    unsigned char *lb = encode(l, &ll);
    affect_br_init(&r, lb, ll);
    assert_int_equal(affect_spca_decode(&r, &u, &err), AFFECT_OK);
    size_t ll2;
    unsigned char *lb2 = encode(u, &ll2);
    assert_int_equal(ll2, ll);
    assert_memory_equal(lb2, lb, ll);
    affect_free(lb2);
    affect_free(lb);
    affect_spca_free(u);
    affect_spca_free(l);

    affect_free(blob);
    affect_free(blob2);
    affect_free(blob3);
    affect_spca_free(t);
    affect_spca_free(s);
    affect_spca_free(s2);
    free(x);
    free(y);
}

/* Decodes buf[0 .. len) and asserts the error message. */
static void decode_fails(const unsigned char *buf, size_t len, const char *msg)
{
    affect_br r;
    affect_br_init(&r, buf, len);
    affect_spca *s = (affect_spca *)&s;
    affect_error err;
    assert_int_equal(affect_spca_decode(&r, &s, &err), AFFECT_ERR_FORMAT);
    assert_null(s);
    assert_string_equal(err.msg, msg);
}

static void put32(unsigned char *p, uint32_t v)
{
    for (int i = 0; i < 4; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}

static void put64(unsigned char *p, uint64_t v)
{
    for (int i = 0; i < 8; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}

static void put_f64(unsigned char *p, double d)
{
    uint64_t u;
    memcpy(&u, &d, sizeof u);
    put64(p, u);
}

/* Rewrites the checksum of a record changed on purpose. */
static void reseal(unsigned char *rec, size_t len)
{
    put64(rec + len - 8, affect_fnv1a64(rec, len - 8));
}

static void test_truncations_and_corruptions(void **state)
{
    (void)state;
    enum { N = 24, D = 6, C = 3 };
    double *x;
    uint32_t *y;
    make_data(N, D, C, 1.0, 0.0, 4, &x, &y);
    affect_spca *s = fit_ok(x, N, D, y, C, AFFECT_SPCA_RBF, 0.5, 2);
    size_t len;
    unsigned char *blob = encode(s, &len);
    assert_int_equal(len, 48 + 16 + 96 + 8); /* 168 */

    /* every cut: an error, never a crash (valgrind watches the reads) */
    for (size_t cut = 0; cut < len; cut++) {
        unsigned char *part = malloc(cut ? cut : 1);
        assert_non_null(part);
        memcpy(part, blob, cut);
        affect_br r;
        affect_br_init(&r, part, cut);
        affect_spca *t = NULL;
        affect_error err;
        assert_int_equal(affect_spca_decode(&r, &t, &err), AFFECT_ERR_FORMAT);
        assert_null(t);
        const char *want = cut < 48    ? "sPCA: truncated in the header (offset 0)"
                           : cut < 64  ? "sPCA: truncated in the eigenvalues (offset 48)"
                           : cut < 160 ? "sPCA: truncated in the axes (offset 64)"
                                       : "sPCA: truncated in the checksum (offset 160)";
        assert_string_equal(err.msg, want);
        free(part);
    }

    unsigned char *c = malloc(len);
    assert_non_null(c);
    /* header fields, each behind a valid checksum so the field check itself is reached */
    struct {
        size_t off;
        int width; /* 4, 8 or -8 (double) */
        double value;
        const char *msg;
    } cases[] = {
        {0, 4, 0x50534641 + 1, "sPCA: not an sPCA record (bad magic bytes at offset 0)"},
        {4, 4, 2, "sPCA: unknown format version 2 (this build reads 1 .. 1)"},
        {8, 4, 3, "sPCA: unknown flags 0x3 (offset 8)"},
        {8, 4, 4, "sPCA: unknown flags 0x4 (offset 8)"},
        {12, 4, 2, "sPCA: unknown label kernel 2 (offset 12)"},
        {16, 4, 1, "sPCA: 1 class, need at least 2 (offset 16)"},
        {16, 4, 0, "sPCA: 0 classes, need at least 2 (offset 16)"},
        {20, 4, 3, "sPCA: 3 axes, expected 1 .. 2 for 3 classes (offset 20)"},
        {20, 4, 0, "sPCA: 0 axes, expected 1 .. 2 for 3 classes (offset 20)"},
        {24, 8, 2, "sPCA: 2 training samples for 3 classes (offset 24)"},
        {32, 8, 0, "sPCA: input dimension 0 is not in 1 .. 2147483647 (offset 32)"},
        {32, 8, 2147483648.0,
         "sPCA: input dimension 2147483648 is not in 1 .. 2147483647 "
         "(offset 32)"},
        {40, -8, -1, "sPCA: sigma -1 is not a positive finite number (offset 40)"},
        {40, -8, INFINITY, "sPCA: sigma inf is not a positive finite number (offset 40)"},
        {48, -8, NAN, "sPCA: eigenvalue 0 is not a positive finite number (offset 48)"},
        {56, -8, 0, "sPCA: eigenvalue 1 is not a positive finite number (offset 56)"},
        {56, -8, 1e300, "sPCA: eigenvalue 1 exceeds eigenvalue 0 (offset 56)"},
        {64 + 8 * 7, -8, INFINITY, "sPCA: non-finite value in the axes (offset 120)"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        memcpy(c, blob, len);
        if (cases[i].width == 4)
            put32(c + cases[i].off, (uint32_t)cases[i].value);
        else if (cases[i].width == 8)
            put64(c + cases[i].off, (uint64_t)cases[i].value);
        else
            put_f64(c + cases[i].off, cases[i].value);
        reseal(c, len);
        decode_fails(c, len, cases[i].msg);
    }
    /* more axes than the record holds (the size is checked before any allocation) */
    memcpy(c, blob, len);
    put64(c + 32, 2147483647u);
    decode_fails(c, len, "sPCA: truncated in the axes (offset 64)");
    /* a flipped bit anywhere after the header fields: the checksum */
    const size_t flips[] = {48, 63, 64, 100, 159, 160, 167};
    for (size_t i = 0; i < sizeof flips / sizeof flips[0]; i++) {
        memcpy(c, blob, len);
        c[flips[i]] ^= 0x10;
        decode_fails(c, len, "sPCA: checksum mismatch, the record is corrupt (offset 160)");
    }
    /* a linear record must carry σ = 0 */
    memcpy(c, blob, len);
    put32(c + 12, 0);
    reseal(c, len);
    decode_fails(c, len, "sPCA: sigma 0.5 with the linear kernel, expected 0 (offset 40)");
    put_f64(c + 40, -0.0);
    reseal(c, len);
    decode_fails(c, len, "sPCA: sigma -0 with the linear kernel, expected 0 (offset 40)");
    put_f64(c + 40, 0.0);
    reseal(c, len);
    affect_br r;
    affect_br_init(&r, c, len);
    affect_spca *t = NULL;
    affect_error err;
    assert_int_equal(affect_spca_decode(&r, &t, &err), AFFECT_OK);
    assert_int_equal(affect_spca_get_kernel(t), AFFECT_SPCA_LINEAR);
    affect_spca_free(t);

    free(c);
    affect_free(blob);
    affect_spca_free(s);
    free(x);
    free(y);
}

/* ---- fit errors ---- */

/* The dual fit with the axes given block by block gives affect_spca_fit's model: the same
 * eigenvalues, the same axes and training coordinates up to rounding (Aᵀ X against Aᵀ H X),
 * the same signs after affect_spca_finish. */
static void test_dual_blocks(void **state)
{
    (void)state;
    enum { N = 40, DD = 23, C4 = 4 };
    double *x;
    uint32_t *y;
    make_data(N, DD, C4, 2.0, 3.0, 91, &x, &y);
    double *k = gram(x, N, DD), *B = malloc(sizeof(double) * N * DD);
    double *z = malloc(sizeof(double) * N * C4), *zr = malloc(sizeof(double) * N * C4);
    affect_spca *ref = fit_ok(x, N, DD, y, C4, AFFECT_SPCA_RBF, 0.5, 3), *s = NULL;
    affect_error err;
    assert_int_equal(affect_spca_fit_dual(k, N, DD, y, C4, AFFECT_SPCA_RBF, 0.5, 3, &s, &err),
                     AFFECT_OK);
    uint32_t p = affect_spca_dims(s);
    assert_int_equal(p, affect_spca_dims(ref));
    affect_spca_dual_embed(s, k, N, z);
    static const size_t cuts[] = {0, 7, 8, DD};
    for (size_t c = 0; c + 1 < sizeof cuts / sizeof cuts[0]; c++) {
        size_t w = cuts[c + 1] - cuts[c];
        for (size_t i = 0; i < N; i++)
            memcpy(B + i * w, x + i * DD + cuts[c], w * sizeof *B);
        affect_spca_add_rows(s, B, w, cuts[c]);
    }
    affect_spca_finish(s, z, N);
    affect_spca_embed_rows(ref, x, N, zr);
    for (uint32_t q = 0; q < p; q++)
        tu_assert_near(affect_spca_eigenvalues(s)[q], affect_spca_eigenvalues(ref)[q],
                       1e-9 * affect_spca_eigenvalues(ref)[0]);
    for (size_t e = 0; e < (size_t)p * DD; e++)
        tu_assert_near(affect_spca_axes(s)[e], affect_spca_axes(ref)[e], 1e-9);
    for (size_t e = 0; e < (size_t)N * p; e++)
        tu_assert_near(z[e], zr[e], 1e-8 * (1 + fabs(zr[e])));
    assert_sign_convention(s);
    /* float32 axes: flag 1, 4 bytes a component, the same axes and bytes after a round trip */
    size_t len64, len32, len2;
    unsigned char *b64 = encode(s, &len64);
    assert_true(affect_spca_round_axes(s));
    unsigned char *b32 = encode(s, &len32);
    assert_int_equal(b32[8], 1);
    assert_int_equal(len64 - len32, (size_t)4 * p * DD);
    affect_br rd;
    affect_br_init(&rd, b32, len32);
    affect_spca *back = NULL;
    assert_int_equal(affect_spca_decode(&rd, &back, &err), AFFECT_OK);
    assert_memory_equal(affect_spca_axes(back), affect_spca_axes(s), sizeof(double) * p * DD);
    for (size_t e = 0; e < (size_t)p * DD; e++)
        assert_true(affect_spca_axes(s)[e] == (float)affect_spca_axes(s)[e]);
    unsigned char *b2 = encode(back, &len2);
    assert_int_equal(len2, len32);
    assert_memory_equal(b2, b32, len32);
    affect_free(b64);
    affect_free(b32);
    affect_free(b2);
    affect_spca_free(back);
    affect_spca_free(ref);
    affect_spca_free(s);
    free(k);
    free(B);
    free(z);
    free(zr);
    free(x);
    free(y);
}

static void test_fit_errors(void **state)
{
    (void)state;
    enum { N = 12, D = 3 };
    double *x;
    uint32_t *y;
    make_data(N, D, 3, 1.0, 0.0, 2, &x, &y);
    const affect_status inv = AFFECT_ERR_INVALID;
    fit_fails(x, N, D, y, 1, AFFECT_SPCA_LINEAR, 0, 2, inv, "need at least 2 classes");
    fit_fails(x, N, 0, y, 3, AFFECT_SPCA_LINEAR, 0, 2, inv, "d must be at least 1");
    fit_fails(x, N, D, y, 3, (affect_spca_kernel)7, 0, 2, inv,
              "unknown label kernel 7 (0 = linear, 1 = rbf)");
    fit_fails(x, N, D, y, 3, AFFECT_SPCA_RBF, 0, 2, inv, "sigma must be a positive finite number");
    fit_fails(x, N, D, y, 3, AFFECT_SPCA_RBF, -1, 2, inv, "sigma must be a positive finite number");
    fit_fails(x, N, D, y, 3, AFFECT_SPCA_RBF, NAN, 2, inv,
              "sigma must be a positive finite number");
    fit_fails(x, N, D, y, 3, AFFECT_SPCA_RBF, INFINITY, 2, inv,
              "sigma must be a positive finite number");
    fit_fails(x, N, D, y, 3, AFFECT_SPCA_LINEAR, NAN, 0, inv, "dims must be at least 1");
    y[4] = 9;
    fit_fails(x, N, D, y, 3, AFFECT_SPCA_LINEAR, 0, 2, inv,
              "row 4: label 9 is out of range (3 classes: 0 .. 2)");
    y[4] = 1;
    fit_fails(x, N, D, y, 4, AFFECT_SPCA_LINEAR, 0, 2, inv, "class 3 has no training sample");
    for (size_t i = 0; i < N; i++)
        if (y[i] == 1)
            y[i] = 0;
    fit_fails(x, N, D, y, 3, AFFECT_SPCA_LINEAR, 0, 2, inv, "class 1 has no training sample");
    for (size_t i = 0; i < N; i++)
        y[i] = (uint32_t)(i % 3);
    x[5 * D + 2] = NAN;
    fit_fails(x, N, D, y, 3, AFFECT_SPCA_LINEAR, 0, 2, inv, "row 5, column 2: non-finite value");
    x[5 * D + 2] = -INFINITY;
    fit_fails(x, N, D, y, 3, AFFECT_SPCA_LINEAR, 0, 2, inv, "row 5, column 2: non-finite value");
    x[5 * D + 2] = 1e200; /* finite, but its square overflows */
    fit_fails(x, N, D, y, 3, AFFECT_SPCA_LINEAR, 0, 2, AFFECT_ERR_RANGE,
              "the data are too large: the centred Gram matrix overflows");
    fit_fails(x, N, 3000000000u, y, 3, AFFECT_SPCA_LINEAR, 0, 2, AFFECT_ERR_RANGE,
              "d = 3000000000 exceeds the BLAS limit of 2147483647");
    x[5 * D + 2] = 0;

    /* no label information: every sample equal */
    double same[N * D];
    for (size_t i = 0; i < N * D; i++)
        same[i] = 2.5;
    fit_fails(same, N, D, y, 3, AFFECT_SPCA_LINEAR, 0, 2, inv,
              "the data carry no label information (all projections are 0)");
    /* ... or every class with the same mean (±v around one point), with the linear kernel */
    for (size_t i = 0; i < N; i++)
        for (size_t j = 0; j < D; j++)
            same[i * D + j] = 1.0 + ((i / 3) % 2 ? 1.0 : -1.0) * (double)(j + 1 + (i / 6));
    fit_fails(same, N, D, y, 3, AFFECT_SPCA_LINEAR, 0, 2, inv,
              "the data carry no label information (all projections are 0)");

    /* ... and with values that do not add up exactly: rounding leaves M tiny but nonzero,
     * far below the AFFECT_SPCA_INFO_TOL bound */
    affect_rng r;
    affect_rng_seed(&r, 99);
    double centre[D], v[N / 2][D];
    for (size_t j = 0; j < D; j++)
        centre[j] = affect_rng_normal(&r) * 10;
    for (size_t i = 0; i < N / 2; i++)
        for (size_t j = 0; j < D; j++)
            v[i][j] = affect_rng_normal(&r);
    for (size_t i = 0; i < N; i++) /* rows i and i + 3 mirror each other, same class */
        for (size_t j = 0; j < D; j++)
            same[i * D + j] =
                centre[j] + ((i / 3) % 2 ? v[(i / 6) * 3 + i % 3][j] : -v[(i / 6) * 3 + i % 3][j]);
    fit_fails(same, N, D, y, 3, AFFECT_SPCA_LINEAR, 0, 2, inv,
              "the data carry no label information (all projections are 0)");

    /* the Gram-matrix variant */
    double *k = gram(x, N, D);
    affect_spca *s = (affect_spca *)&s;
    affect_error err;
    k[2 * N + 7] = INFINITY;
    assert_int_equal(affect_spca_fit_gram(x, k, N, D, y, 3, AFFECT_SPCA_LINEAR, 0, 2, &s, &err),
                     inv);
    assert_null(s);
    assert_string_equal(err.msg, "K row 2, column 7: non-finite value");
    free(k);
    k = gram(x, N, D); /* twice the Gram matrix of the data */
    for (size_t i = 0; i < N * N; i++)
        k[i] *= 2;
    assert_int_equal(affect_spca_fit_gram(x, k, N, D, y, 3, AFFECT_SPCA_LINEAR, 0, 2, &s, &err),
                     inv);
    assert_null(s);
    assert_int_equal(
        strncmp(err.msg, "the Gram matrix does not match the data (trace of H K H ", 56), 0);
    /* K of the data shifted by a constant vector is fine */
    double shifted[N * D];
    for (size_t i = 0; i < N * D; i++)
        shifted[i] = x[i] + (double)(i % D);
    free(k);
    k = gram(shifted, N, D);
    assert_int_equal(affect_spca_fit_gram(x, k, N, D, y, 3, AFFECT_SPCA_LINEAR, 0, 2, &s, &err),
                     AFFECT_OK);
    affect_spca *ref = fit_ok(x, N, D, y, 3, AFFECT_SPCA_LINEAR, 0, 2);
    for (size_t j = 0; j < 2 * D; j++)
        tu_assert_near(affect_spca_axes(s)[j], affect_spca_axes(ref)[j], 1e-9);
    affect_spca_free(ref);
    affect_spca_free(s);
    free(k);
    free(x);
    free(y);
}

/* ---- out of memory ---- */

typedef struct oom_ctx {
    const double *x, *k;
    const uint32_t *y;
    size_t n, d;
    affect_spca *s;
    const unsigned char *blob;
    size_t len;
    const double *tz;
    uint32_t label;
} oom_ctx;

static affect_status oom_fit(void *ctx, affect_error *err)
{
    oom_ctx *c = ctx;
    return affect_spca_fit(c->x, c->n, c->d, c->y, 3, AFFECT_SPCA_RBF, 0.5, 2, &c->s, err);
}

static affect_status oom_fit_gram(void *ctx, affect_error *err)
{
    oom_ctx *c = ctx;
    return affect_spca_fit_gram(c->x, c->k, c->n, c->d, c->y, 3, AFFECT_SPCA_LINEAR, 0, 2, &c->s,
                                err);
}

static affect_status oom_decode(void *ctx, affect_error *err)
{
    oom_ctx *c = ctx;
    affect_br r;
    affect_br_init(&r, c->blob, c->len);
    return affect_spca_decode(&r, &c->s, err);
}

static void oom_finish(void *ctx, affect_status st)
{
    oom_ctx *c = ctx;
    if (st != AFFECT_OK)
        assert_null(c->s);
    affect_spca_free(c->s);
    c->s = NULL;
}

static affect_status oom_knn(void *ctx, affect_error *err)
{
    oom_ctx *c = ctx;
    return affect_knn_classify(c->tz, c->y, c->n, 2, 3, c->tz + 2, 4, &c->label, NULL, err);
}

static affect_status oom_encode(void *ctx, affect_error *err)
{
    oom_ctx *c = ctx;
    affect_bw w;
    affect_bw_init(&w);
    affect_spca_encode(c->s, &w);
    bool failed = w.failed;
    affect_bw_free(&w);
    return failed ? affect_nomem(err) : AFFECT_OK;
}

static void test_out_of_memory(void **state)
{
    (void)state;
    enum { N = 30, D = 8 };
    double *x;
    uint32_t *y;
    make_data(N, D, 3, 1.0, 0.0, 6, &x, &y);
    double *k = gram(x, N, D);
    oom_ctx c = {x, k, y, N, D, NULL, NULL, 0, NULL, 0};
    assert_int_equal(tu_oom_sweep(oom_fit, &c, oom_finish, NULL), 2);
    assert_int_equal(tu_oom_sweep(oom_fit_gram, &c, oom_finish, NULL), 2);

    affect_spca *s = fit_ok(x, N, D, y, 3, AFFECT_SPCA_RBF, 0.5, 2);
    c.blob = encode(s, &c.len);
    assert_int_equal(tu_oom_sweep(oom_decode, &c, oom_finish, NULL), 1);
    c.s = s;
    assert_true(tu_oom_sweep(oom_encode, &c, NULL, NULL) >= 1);
    c.s = NULL;
    double z[N * 2];
    affect_spca_embed_rows(s, x, N, z);
    c.tz = z;
    assert_int_equal(tu_oom_sweep(oom_knn, &c, NULL, NULL), 1);
    affect_free((void *)c.blob);
    affect_spca_free(s);
    free(k);
    free(x);
    free(y);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hsic_by_hand),
        cmocka_unit_test(test_dual_equals_primal),
        cmocka_unit_test(test_orthonormal_blocks_and_offset),
        cmocka_unit_test(test_separation),
        cmocka_unit_test(test_rbf_small_sigma_is_linear),
        cmocka_unit_test(test_rank_cap),
        cmocka_unit_test(test_eigenvalues_are_hsic),
        cmocka_unit_test(test_knn_rules),
        cmocka_unit_test(test_determinism_and_round_trip),
        cmocka_unit_test(test_truncations_and_corruptions),
        cmocka_unit_test(test_fit_errors),
        cmocka_unit_test(test_dual_blocks),
        cmocka_unit_test(test_out_of_memory),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
