/*
 * test_fda.c — functional analysis (affect/fda.h): FPCA against the primal PCA of the
 * M^{1/2}-weighted coefficients (solved here by Jacobi rotations, independent of LAPACK),
 * FSPCA against the non-functional sPCA on those weighted coefficients, out-of-sample
 * embeddings of training motions equal to their training embeddings for every method,
 * F-Isomap unrolling a swiss roll, classification of well-separated classes, GCV choosing an
 * interior λ, determinism and bit-identical BLOB round trips, truncations and corruptions of
 * the BLOB, the errors, and allocation failure.
 */
#include <stdio.h>
#include <string.h>

#include "testutil.h"

#include "affect/fda.h"
#include "affect/hmm_blob.h" /* affect_fnv1a64 */
#include "util/rng.h"
#include "affect/spca.h"

/* ---- synthetic motions ---- */

typedef struct data {
    uint32_t n, m, c;
    affect_hmm_seq *seqs;
    double **x;
    uint32_t *y;
} data;

/* n motions of m = 2 coordinates and 40 .. 79 frames; class k's curves are
 * (sin(2π t) + sep·k·t², cos(2π t) − sep·k·t) plus a random amplitude and noise. */
static data make_data(uint32_t n, uint32_t c, double sep, uint64_t seed)
{
    data d = {n, 2, c, NULL, NULL, NULL};
    affect_rng r;
    affect_rng_seed(&r, seed);
    d.seqs = calloc(n, sizeof *d.seqs);
    d.x = calloc(n, sizeof *d.x);
    d.y = calloc(n, sizeof *d.y);
    assert_non_null(d.seqs);
    assert_non_null(d.x);
    assert_non_null(d.y);
    for (uint32_t i = 0; i < n; i++) {
        uint32_t T = 40 + (uint32_t)(affect_rng_uniform(&r) * 40);
        d.y[i] = i % c;
        d.x[i] = malloc((size_t)T * 2 * sizeof(double));
        assert_non_null(d.x[i]);
        double amp = 1.0 + 0.3 * affect_rng_normal(&r);
        for (uint32_t s = 0; s < T; s++) {
            double t = s / (double)(T - 1), k = d.y[i];
            d.x[i][2 * s] =
                amp * sin(6.283185307179586 * t) + sep * k * t * t + 0.05 * affect_rng_normal(&r);
            d.x[i][2 * s + 1] =
                amp * cos(6.283185307179586 * t) - sep * k * t + 0.05 * affect_rng_normal(&r);
        }
        d.seqs[i].x = d.x[i];
        d.seqs[i].n_frames = T;
    }
    return d;
}

static void free_data(data *d)
{
    for (uint32_t i = 0; i < d->n; i++)
        free(d->x[i]);
    free(d->x);
    free(d->seqs);
    free(d->y);
}

static const char *const NAMES[] = {"angry", "happy", "normal", "sad", "e", "f", "g", "h"};

static affect_fda *train_ok(const affect_fda_config *cfg, const data *d)
{
    affect_fda *f = NULL;
    affect_error err;
    affect_status st =
        affect_fda_train(cfg, NULL, d->seqs, d->n, d->m, d->y, NAMES, d->c, &f, &err);
    if (st != AFFECT_OK)
        fail_msg("train: %s", err.msg);
    return f;
}

static void small_cfg(affect_fda_config *cfg, affect_fda_method method)
{
    affect_fda_config_default(cfg);
    cfg->method = method;
    cfg->n_basis = 12;
    cfg->lambda = 1e-6;
}

/* ---- Jacobi eigenvalues of a small symmetric matrix (a: n × n, destroyed; vectors in
 * columns of v) ---- */
static void jacobi(double *a, uint32_t n, double *v)
{
    for (uint32_t i = 0; i < n; i++)
        for (uint32_t j = 0; j < n; j++)
            v[i * n + j] = i == j;
    for (int sweep = 0; sweep < 100; sweep++) {
        double off = 0.0;
        for (uint32_t i = 0; i < n; i++)
            for (uint32_t j = i + 1; j < n; j++)
                off += a[i * n + j] * a[i * n + j];
        if (off < 1e-30)
            break;
        for (uint32_t p = 0; p < n; p++)
            for (uint32_t q = p + 1; q < n; q++) {
                if (fabs(a[p * n + q]) < 1e-300)
                    continue;
                double theta = (a[q * n + q] - a[p * n + p]) / (2 * a[p * n + q]);
                double t = (theta >= 0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1));
                double cs = 1 / sqrt(t * t + 1), sn = t * cs;
                for (uint32_t k = 0; k < n; k++) {
                    double akp = a[k * n + p], akq = a[k * n + q];
                    a[k * n + p] = cs * akp - sn * akq;
                    a[k * n + q] = sn * akp + cs * akq;
                }
                for (uint32_t k = 0; k < n; k++) {
                    double apk = a[p * n + k], aqk = a[q * n + k];
                    a[p * n + k] = cs * apk - sn * aqk;
                    a[q * n + k] = sn * apk + cs * aqk;
                }
                for (uint32_t k = 0; k < n; k++) {
                    double vkp = v[k * n + p], vkq = v[k * n + q];
                    v[k * n + p] = cs * vkp - sn * vkq;
                    v[k * n + q] = sn * vkp + cs * vkq;
                }
            }
    }
}

/* z (n × h) = M^{1/2}-weighted coefficients of the training motions under f. */
static double *weighted(const affect_fda *f, const data *d, size_t *h_out)
{
    const affect_fda_config *cfg = affect_fda_get_config(f);
    uint32_t G = cfg->n_basis, m = d->m;
    size_t h = (size_t)G * m;
    affect_bspline b = {cfg->order, G};
    double *sq = malloc((size_t)G * G * sizeof *sq), *c = malloc(h * sizeof *c);
    double *z = calloc(d->n * h, sizeof *z);
    assert_non_null(sq);
    assert_non_null(c);
    assert_non_null(z);
    affect_error err;
    assert_int_equal(affect_fda_gram_sqrt(&b, sq, &err), AFFECT_OK);
    for (uint32_t i = 0; i < d->n; i++) {
        assert_int_equal(affect_fda_coefficients(f, d->x[i], d->seqs[i].n_frames, c, &err),
                         AFFECT_OK);
        for (uint32_t g = 0; g < G; g++)
            for (uint32_t j = 0; j < m; j++) {
                double s = 0;
                for (uint32_t l = 0; l < G; l++)
                    s += sq[g * G + l] * c[l * m + j];
                z[i * h + g * m + j] = s;
            }
    }
    free(sq);
    free(c);
    *h_out = h;
    return z;
}

static void test_gram_sqrt(void **state)
{
    (void)state;
    affect_bspline b = {4, 15};
    double sq[15 * 15], band[15 * 4];
    affect_error err;
    assert_int_equal(affect_fda_gram_sqrt(&b, sq, &err), AFFECT_OK);
    affect_bspline_gram(&b, 0, band);
    for (int i = 0; i < 15; i++)
        for (int j = 0; j < 15; j++) {
            double s = 0;
            for (int l = 0; l < 15; l++)
                s += sq[i * 15 + l] * sq[l * 15 + j];
            int lo = i < j ? i : j, dd = abs(i - j);
            double want = dd < 4 ? band[lo * 4 + dd] : 0.0;
            tu_assert_near(s, want, 1e-14);
            tu_assert_near(sq[i * 15 + j], sq[j * 15 + i], 1e-15);
        }
}

static void test_fpca_is_pca_of_weighted(void **state)
{
    (void)state;
    data d = make_data(30, 3, 1.0, 11);
    affect_fda_config cfg;
    small_cfg(&cfg, AFFECT_FDA_FPCA);
    affect_fda *f = train_ok(&cfg, &d);
    size_t h;
    double *z = weighted(f, &d, &h);
    uint32_t n = d.n;
    double *mean = calloc(h, sizeof *mean), *cov = calloc(h * h, sizeof *cov);
    double *v = malloc(h * h * sizeof *v);
    for (uint32_t i = 0; i < n; i++)
        for (size_t j = 0; j < h; j++)
            mean[j] += z[i * h + j] / n;
    for (uint32_t i = 0; i < n; i++)
        for (size_t a = 0; a < h; a++)
            for (size_t b = 0; b < h; b++)
                cov[a * h + b] += (z[i * h + a] - mean[a]) * (z[i * h + b] - mean[b]) / (n - 1);
    jacobi(cov, (uint32_t)h, v);
    /* the two largest eigenvalues and their scores */
    const double *ev = affect_fda_fpca_eigenvalues(f);
    const double *tz = affect_fda_train_embedding(f);
    uint32_t p = affect_fda_dims(f);
    assert_int_equal(p, 3);
    bool used[64] = {false};
    for (uint32_t r = 0; r < 3; r++) {
        size_t best = 0;
        for (size_t j = 0; j < h; j++)
            if (!used[j] && (used[best] || cov[j * h + j] > cov[best * h + best]))
                best = j;
        used[best] = true;
        tu_assert_near(cov[best * h + best], ev[r], 1e-9 * ev[0]);
        double sign = 0;
        for (uint32_t i = 0; i < n; i++) {
            double s = 0;
            for (size_t j = 0; j < h; j++)
                s += v[j * h + best] * (z[i * h + j] - mean[j]);
            if (sign == 0)
                sign = (s * tz[i * p + r] >= 0) ? 1 : -1;
            tu_assert_near(sign * s, tz[i * p + r], 1e-7 * sqrt(ev[0]));
        }
    }
    /* explained shares: of the total variance, which is Σ of all eigenvalues */
    double total = 0;
    for (size_t j = 0; j < h; j++)
        total += cov[j * h + j];
    tu_assert_near(affect_fda_total_variance(f), total, 1e-9 * total);
    free(mean);
    free(cov);
    free(v);
    free(z);
    affect_fda_free(f);
    free_data(&d);
}

static void test_fspca_is_spca_of_weighted(void **state)
{
    (void)state;
    data d = make_data(24, 4, 0.5, 5);
    for (int kernel = 0; kernel < 2; kernel++) {
        affect_fda_config cfg;
        small_cfg(&cfg, AFFECT_FDA_FSPCA);
        cfg.kernel = (affect_spca_kernel)kernel;
        cfg.sigma = 0.7;
        affect_fda *f = train_ok(&cfg, &d);
        size_t h;
        double *z = weighted(f, &d, &h);
        affect_spca *s = NULL;
        affect_error err;
        assert_int_equal(
            affect_spca_fit(z, d.n, h, d.y, 4, (affect_spca_kernel)kernel, 0.7, 3, &s, &err),
            AFFECT_OK);
        uint32_t p = affect_spca_dims(s);
        assert_int_equal(p, affect_fda_dims(f));
        double *sz = malloc(d.n * p * sizeof *sz);
        affect_spca_embed_rows(s, z, d.n, sz);
        const double *tz = affect_fda_train_embedding(f);
        for (uint32_t r = 0; r < p; r++) {
            /* equal up to a shift (sPCA does not centre) and a sign */
            double sign =
                (sz[1 * p + r] - sz[0 * p + r]) * (tz[1 * p + r] - tz[0 * p + r]) >= 0 ? 1 : -1;
            for (uint32_t i = 1; i < d.n; i++)
                tu_assert_near(sign * (sz[i * p + r] - sz[r]), tz[i * p + r] - tz[r], 1e-7);
            tu_assert_near(affect_fda_eigenvalues(f)[r], affect_spca_eigenvalues(s)[r],
                           1e-8 * affect_spca_eigenvalues(s)[0]);
        }
        free(sz);
        free(z);
        affect_spca_free(s);
        affect_fda_free(f);
    }
    free_data(&d);
}

static void test_out_of_sample_training(void **state)
{
    (void)state;
    data d = make_data(28, 4, 0.8, 3);
    for (int method = 0; method < 4; method++) {
        affect_fda_config cfg;
        small_cfg(&cfg, (affect_fda_method)method);
        cfg.isomap_k = 6;
        affect_fda *f = train_ok(&cfg, &d);
        uint32_t p = affect_fda_dims(f);
        assert_true(p >= 2 && p <= 3);
        const double *tz = affect_fda_train_embedding(f);
        double scale = 0;
        for (uint32_t i = 0; i < d.n * p; i++)
            scale = fmax(scale, fabs(tz[i]));
        for (uint32_t i = 0; i < d.n; i++) {
            double z[3];
            affect_error err;
            assert_int_equal(affect_fda_embed(f, d.x[i], d.seqs[i].n_frames, z, &err), AFFECT_OK);
            for (uint32_t r = 0; r < p; r++)
                if (!(fabs(z[r] - tz[i * p + r]) <= 1e-6 * scale))
                    fail_msg("method %d, motion %u, axis %u: %.12g, trained %.12g", method, i, r,
                             z[r], tz[i * p + r]);
        }
        affect_fda_free(f);
    }
    free_data(&d);
}

/* A neighbour graph in pieces (two far clusters, k = 1: every motion's nearest is in its own
 * cluster, and 1-NN graphs split further) is joined by the shortest distances between its pieces:
 * training succeeds, the geodesic distances are finite (the embedding of every training motion
 * is reproduced out of sample), and the first axis separates the two clusters. */
static void test_isomap_joins_components(void **state)
{
    (void)state;
    data e = make_data(12, 2, 30.0, 2);
    affect_fda_config cfg;
    small_cfg(&cfg, AFFECT_FDA_FISOMAP);
    cfg.isomap_k = 1;
    affect_fda *f = train_ok(&cfg, &e);
    uint32_t p = affect_fda_dims(f);
    const double *tz = affect_fda_train_embedding(f);
    double scale = 0;
    for (uint32_t i = 0; i < e.n * p; i++) {
        assert_true(isfinite(tz[i]));
        scale = fmax(scale, fabs(tz[i]));
    }
    assert_true(scale > 0);
    for (uint32_t i = 0; i < e.n; i++) {
        double z[AFFECT_FDA_MAX_DIMS];
        affect_error err;
        assert_int_equal(affect_fda_embed(f, e.x[i], e.seqs[i].n_frames, z, &err), AFFECT_OK);
        for (uint32_t r = 0; r < p; r++)
            if (!(fabs(z[r] - tz[i * p + r]) <= 1e-6 * scale))
                fail_msg("motion %u, axis %u: %.12g, trained %.12g", i, r, z[r], tz[i * p + r]);
        /* class 0 on one side of the first axis, class 1 on the other */
        assert_true((tz[i * p] > 0) == (tz[(i % 2) * p] > 0));
        assert_true((tz[i * p] > 0) != (tz[(1 - i % 2) * p] > 0));
    }
    affect_fda_free(f);
    free_data(&e);
}

static void test_classify_separated(void **state)
{
    (void)state;
    data d = make_data(40, 4, 2.0, 9);
    data q = make_data(20, 4, 2.0, 99); /* unseen motions of the same classes */
    for (int method = 0; method < 4; method++) {
        affect_fda_config cfg;
        small_cfg(&cfg, (affect_fda_method)method);
        cfg.isomap_k = 12; /* the classes are far apart: 10 neighbours stay in one class */
        affect_fda *f = train_ok(&cfg, &d);
        uint32_t right = 0;
        for (uint32_t i = 0; i < q.n; i++) {
            uint32_t label, votes[4];
            affect_error err;
            assert_int_equal(
                affect_fda_classify(f, q.x[i], q.seqs[i].n_frames, 1, &label, votes, &err),
                AFFECT_OK);
            right += label == q.y[i];
        }
        if (right < 19)
            fail_msg("method %d: %u of 20 right", method, right);
        affect_fda_free(f);
    }
    free_data(&d);
    free_data(&q);
}

static void test_swiss_roll(void **state)
{
    (void)state;
    /* constant "motions": each a point of a swiss roll, so L² distances are Euclidean ones */
    uint32_t n = 300;
    data d = {n,
              3,
              2,
              calloc(n, sizeof(affect_hmm_seq)),
              calloc(n, sizeof(double *)),
              calloc(n, sizeof(uint32_t))};
    double *arc = malloc(n * sizeof *arc);
    affect_rng r;
    affect_rng_seed(&r, 42);
    for (uint32_t i = 0; i < n; i++) {
        double t = 1.5 * 3.141592653589793 * (1 + 2 * affect_rng_uniform(&r));
        double hgt = 10 * affect_rng_uniform(&r);
        d.x[i] = malloc(2 * 3 * sizeof(double));
        for (int s = 0; s < 2; s++) {
            d.x[i][s * 3] = t * cos(t);
            d.x[i][s * 3 + 1] = hgt;
            d.x[i][s * 3 + 2] = t * sin(t);
        }
        d.seqs[i].x = d.x[i];
        d.seqs[i].n_frames = 2;
        d.y[i] = hgt > 5;
        arc[i] = 0.5 * (t * sqrt(1 + t * t) + asinh(t)); /* arc length of the spiral */
    }
    affect_fda_config cfg;
    affect_fda_config_default(&cfg);
    cfg.n_basis = 4;
    cfg.lambda = 1e-3;
    cfg.dims = 2;
    cfg.isomap_k = 8;
    double corr[2];
    for (int method = 0; method < 2; method++) {
        cfg.method = method ? AFFECT_FDA_FISOMAP : AFFECT_FDA_FPCA;
        affect_fda *f = train_ok(&cfg, &d);
        const double *tz = affect_fda_train_embedding(f);
        /* the best |correlation| of an embedding axis with the arc length */
        double best = 0;
        for (uint32_t a = 0; a < 2; a++) {
            double mx = 0, my = 0, sxy = 0, sxx = 0, syy = 0;
            for (uint32_t i = 0; i < n; i++)
                mx += tz[i * 2 + a] / n, my += arc[i] / n;
            for (uint32_t i = 0; i < n; i++) {
                double dx = tz[i * 2 + a] - mx, dy = arc[i] - my;
                sxy += dx * dy, sxx += dx * dx, syy += dy * dy;
            }
            best = fmax(best, fabs(sxy) / sqrt(sxx * syy));
        }
        corr[method] = best;
        affect_fda_free(f);
    }
    if (!(corr[1] > 0.99 && corr[0] < 0.9))
        fail_msg("arc length correlation: Isomap %.4f (want > 0.99), FPCA %.4f (want < 0.9)",
                 corr[1], corr[0]);
    free(arc);
    free_data(&d);
}

static void test_gcv(void **state)
{
    (void)state;
    data d = make_data(12, 2, 1.0, 21);
    affect_fda_config cfg;
    small_cfg(&cfg, AFFECT_FDA_FPCA);
    cfg.n_basis = 40;
    cfg.gcv = true;
    affect_fda *f = train_ok(&cfg, &d);
    double lam = affect_fda_get_config(f)->lambda;
    /* noise 0.05 on smooth curves: an interior λ of the grid, neither end */
    assert_true(lam > 1e-15 && lam < 1.0);
    affect_fda *g = train_ok(&cfg, &d);
    assert_true(affect_fda_get_config(g)->lambda == lam);
    affect_fda_free(f);
    affect_fda_free(g);
    free_data(&d);
}

static void test_determinism_and_blob(void **state)
{
    (void)state;
    data d = make_data(20, 4, 0.8, 13);
    for (int method = 0; method < 4; method++) {
        affect_fda_config cfg;
        small_cfg(&cfg, (affect_fda_method)method);
        affect_fda *a = train_ok(&cfg, &d), *b = train_ok(&cfg, &d), *c = NULL;
        unsigned char *ba, *bb, *bc;
        size_t na, nb, nc;
        affect_error err;
        assert_int_equal(affect_fda_encode(a, &ba, &na, &err), AFFECT_OK);
        assert_int_equal(affect_fda_encode(b, &bb, &nb, &err), AFFECT_OK);
        assert_int_equal(na, nb);
        assert_memory_equal(ba, bb, na);
        assert_int_equal(affect_fda_decode(ba, na, &c, &err), AFFECT_OK);
        assert_int_equal(affect_fda_encode(c, &bc, &nc, &err), AFFECT_OK);
        assert_int_equal(na, nc);
        assert_memory_equal(ba, bc, na);
        double za[3], zc[3];
        assert_int_equal(affect_fda_embed(a, d.x[3], d.seqs[3].n_frames, za, &err), AFFECT_OK);
        assert_int_equal(affect_fda_embed(c, d.x[3], d.seqs[3].n_frames, zc, &err), AFFECT_OK);
        assert_memory_equal(za, zc, affect_fda_dims(a) * sizeof(double));
        /* every truncation fails cleanly; a flipped byte fails the checksum */
        for (size_t len = 0; len < na; len += (len < 200 ? 1 : 97)) {
            affect_fda *x = NULL;
            assert_int_equal(affect_fda_decode(ba, len, &x, &err), AFFECT_ERR_FORMAT);
            assert_null(x);
        }
        ba[na / 2] ^= 0x10;
        affect_fda *x = NULL;
        assert_int_equal(affect_fda_decode(ba, na, &x, &err), AFFECT_ERR_FORMAT);
        assert_string_equal(err.msg, "functional model checksum mismatch: the BLOB is corrupt");
        assert_int_equal(affect_fda_decode((const unsigned char *)"AFDX0000", 8, &x, &err),
                         AFFECT_ERR_FORMAT);
        assert_string_equal(err.msg, "truncated: 8 bytes is shorter than the functional model "
                                     "header");
        free(ba);
        free(bb);
        free(bc);
        affect_fda_free(a);
        affect_fda_free(b);
        affect_fda_free(c);
    }
    free_data(&d);
}

static void train_fails(const affect_fda_config *cfg, const data *d, uint32_t n, uint32_t c,
                        const uint32_t *y, const char *msg)
{
    affect_fda *f = NULL;
    affect_error err;
    assert_int_not_equal(affect_fda_train(cfg, NULL, d->seqs, n, d->m, y, NAMES, c, &f, &err),
                         AFFECT_OK);
    assert_null(f);
    assert_string_equal(err.msg, msg);
}

static void test_errors(void **state)
{
    (void)state;
    data d = make_data(12, 3, 1.0, 1);
    affect_fda_config cfg;
    small_cfg(&cfg, AFFECT_FDA_FPCA);
    cfg.dims = 0;
    train_fails(&cfg, &d, d.n, 3, d.y, "dims must be from 1 to 64");
    small_cfg(&cfg, AFFECT_FDA_FPCA);
    cfg.lambda = -1;
    train_fails(&cfg, &d, d.n, 3, d.y, "lambda must be a finite number, 0 or more");
    small_cfg(&cfg, AFFECT_FDA_FPCA);
    cfg.n_basis = 2;
    train_fails(&cfg, &d, d.n, 3, d.y, "the basis size must be from the order to 4096");
    small_cfg(&cfg, AFFECT_FDA_FPCA);
    train_fails(&cfg, &d, 2, 3, d.y, "need at least 3 motions");
    train_fails(&cfg, &d, d.n, 1, d.y, "need at least 2 classes");
    train_fails(&cfg, &d, d.n, 5, d.y, "class 3 (\"sad\") has no motion");
    uint32_t bad[12];
    memcpy(bad, d.y, sizeof bad);
    bad[4] = 7;
    train_fails(&cfg, &d, d.n, 3, bad, "motion 4: label 7 is out of range (3 classes)");
    d.x[2][3] = NAN;
    train_fails(&cfg, &d, d.n, 3, d.y, "motion 2: sample 1, column 1: non-finite value");
    d.x[2][3] = 0;
    cfg.lambda = 0;
    cfg.n_basis = 100; /* more coefficients than frames */
    train_fails(&cfg, &d, d.n, 3, d.y,
                "motion 0: the fit is singular: 68 samples cannot "
                "determine 100 coefficients with lambda = 0 (give a "
                "positive lambda or a smaller basis)");
    /* all equal: no variance */
    for (uint32_t i = 1; i < d.n; i++) {
        d.seqs[i].x = d.x[0];
        d.seqs[i].n_frames = d.seqs[0].n_frames;
    }
    small_cfg(&cfg, AFFECT_FDA_FPCA);
    train_fails(&cfg, &d, d.n, 3, d.y, "the training functions are all equal (no variance)");
    for (uint32_t i = 0; i < d.n; i++)
        d.seqs[i].x = d.x[i];
    free_data(&d);
}

/* A fixture's bytes (*bytes, *len) and its decoded model. */
static affect_fda *decode_fixture(const char *path, char **bytes, size_t *len)
{
    *bytes = tu_read_file(path, len);
    assert_non_null(*bytes);
    affect_fda *f = NULL;
    affect_error err;
    if (affect_fda_decode((const unsigned char *)*bytes, *len, &f, &err))
        fail_msg("decode %s: %s", path, err.msg);
    return f;
}

/* Today's encoder writes the fixture's bytes again. */
static void encodes_to(const affect_fda *f, const char *bytes, size_t len)
{
    unsigned char *again;
    size_t n;
    affect_error err;
    assert_int_equal(affect_fda_encode(f, &again, &n, &err), AFFECT_OK);
    assert_int_equal(n, len);
    assert_memory_equal(again, bytes, len);
    free(again);
}

/* tests/fixtures/fda-v1.bin: the SQL spec's small model (right hand, first-frame
 * observations, 6 B-splines, FPCA 2-D, 12 motion_synth waves of 4 emotions). */
static void test_fixture_v1(void **state)
{
    (void)state;
    size_t len;
    char *bytes;
    affect_fda *f = decode_fixture(AFFECT_FIXTURES_DIR "/fda-v1.bin", &bytes, &len);
    const affect_fda_config *cfg = affect_fda_get_config(f);
    assert_int_equal(cfg->method, AFFECT_FDA_FPCA);
    assert_int_equal(cfg->n_basis, 6);
    assert_int_equal(cfg->order, 4);
    assert_true(cfg->lambda == 1e-10);
    assert_int_equal(affect_fda_dims(f), 2);
    assert_int_equal(affect_fda_coords(f), 3);
    assert_int_equal(affect_fda_train_size(f), 12);
    assert_int_equal(affect_fda_classes(f), 4);
    assert_string_equal(affect_fda_class_name(f, 0), "angry");
    assert_string_equal(affect_fda_class_name(f, 3), "sad");
    assert_non_null(affect_fda_features(f));
    assert_int_equal(affect_fda_features(f)->frame, AFFECT_FEATURES_FRAME_FIRST);
    encodes_to(f, bytes, len);
    /* the training embedding is the FPCA scores: centred, the first axis the wider */
    const double *z = affect_fda_train_embedding(f);
    double m0 = 0, v0 = 0, v1 = 0;
    for (int i = 0; i < 12; i++)
        m0 += z[2 * i] / 12, v0 += z[2 * i] * z[2 * i], v1 += z[2 * i + 1] * z[2 * i + 1];
    tu_assert_near(m0, 0.0, 1e-9);
    assert_true(v0 >= v1);
    tu_assert_near(v0 / 11, affect_fda_eigenvalues(f)[0], 1e-9 * v0);
    free(bytes);
    affect_fda_free(f);
}

/* tests/fixtures/fda-v2.bin: fda-v1.bin's motions and options with "alignment":"landmarks"
 * (version 2: flags 1 and the landmark template). */
static void test_fixture_v2(void **state)
{
    (void)state;
    size_t len;
    char *bytes;
    affect_fda *f = decode_fixture(AFFECT_FIXTURES_DIR "/fda-v2.bin", &bytes, &len);
    assert_int_equal(len, 1615);
    assert_int_equal((unsigned char)bytes[4], 2);
    const affect_fda_config *cfg = affect_fda_get_config(f);
    assert_int_equal(cfg->method, AFFECT_FDA_FPCA);
    assert_int_equal(cfg->alignment, AFFECT_FDA_ALIGN_LANDMARKS);
    assert_int_equal(affect_fda_train_size(f), 12);
    uint32_t nt;
    const affect_fda_landmark *tp = affect_fda_template(f, &nt);
    assert_int_equal(nt, 6);
    for (uint32_t k = 0; k < nt; k++) {
        assert_true(tp[k].t > (k ? tp[k - 1].t : 0.0) && tp[k].t < 1.0);
        assert_int_equal(tp[k].type, k % 2 == 0 ? 1 : -1);
    }
    encodes_to(f, bytes, len);
    /* a version 2 without the landmark flag would re-encode as version 1: refused */
    bytes[8] = 0;
    uint64_t sum = affect_fnv1a64((const unsigned char *)bytes, len - 8);
    for (int i = 0; i < 8; i++)
        bytes[len - 8 + (size_t)i] = (char)(unsigned char)(sum >> (8 * i));
    affect_fda *bad = NULL;
    affect_error err;
    assert_int_equal(affect_fda_decode((const unsigned char *)bytes, len, &bad, &err),
                     AFFECT_ERR_FORMAT);
    assert_string_equal(err.msg, "flags 0 is out of range (offset 8)");
    free(bytes);
    affect_fda_free(f);
}

/* tests/fixtures/fda-v3.bin: fda-v1.bin's motions and options with the default prototypes
 * (every component: the class means; version 3, flags 2, no eigenfunctions). */
static void test_fixture_v3(void **state)
{
    (void)state;
    size_t len;
    char *bytes;
    affect_fda *f = decode_fixture(AFFECT_FIXTURES_DIR "/fda-v3.bin", &bytes, &len);
    assert_int_equal(len, 1587);
    assert_int_equal((unsigned char)bytes[4], 3);
    assert_int_equal((unsigned char)bytes[8], 2);
    assert_int_equal(affect_fda_proto_dims(f), 0);
    assert_int_equal(affect_fda_get_config(f)->proto_dims, 0);
    assert_int_equal(affect_fda_get_config(f)->alignment, AFFECT_FDA_ALIGN_LINEAR);
    assert_int_equal(affect_fda_train_size(f), 12);
    encodes_to(f, bytes, len);
    affect_motion *p = NULL;
    affect_error err;
    assert_int_equal(affect_fda_prototype(f, 1, &p, &err), AFFECT_OK);
    affect_motion_free(p);
    free(bytes);
    affect_fda_free(f);
}

/* The default prototype is the class's mean function: its coefficients are the mean of the
 * class's training coefficients; P = R components give the same (they span every centred
 * training function), 3 components do not; the BLOB is version 3 and decodes to the same
 * prototypes. */
static void test_prototype_class_mean(void **state)
{
    (void)state;
    data d = make_data(24, 4, 0.8, 5);
    affect_fda_config cfg;
    small_cfg(&cfg, AFFECT_FDA_FFDA);
    affect_fda *all = train_ok(&cfg, &d);
    assert_int_equal(affect_fda_proto_dims(all), 0);
    cfg.proto_dims = 64; /* clamped to the rank R */
    affect_fda *every = train_ok(&cfg, &d);
    assert_int_equal(affect_fda_proto_dims(every), affect_fda_fpca_rank(every));
    cfg.proto_dims = 3;
    affect_fda *three = train_ok(&cfg, &d);
    size_t h = 12 * 2;
    double pa[24], pe[24], p3[24], mean[24], c[24];
    affect_error err;
    for (uint32_t k = 0; k < 4; k++) {
        memset(mean, 0, sizeof mean);
        uint32_t nk = 0;
        for (uint32_t i = 0; i < d.n; i++) {
            if (d.y[i] != k)
                continue;
            assert_int_equal(affect_fda_coefficients(all, d.x[i], d.seqs[i].n_frames, c, &err),
                             AFFECT_OK);
            for (size_t j = 0; j < h; j++)
                mean[j] += c[j];
            nk++;
        }
        affect_fda_prototype_coefs(all, k, pa);
        affect_fda_prototype_coefs(every, k, pe);
        affect_fda_prototype_coefs(three, k, p3);
        double far = 0;
        for (size_t j = 0; j < h; j++) {
            tu_assert_near(pa[j], mean[j] / nk, 1e-9 * (1 + fabs(pa[j])));
            tu_assert_near(pe[j], pa[j], 1e-7 * (1 + fabs(pa[j])));
            far = fmax(far, fabs(p3[j] - pa[j]));
        }
        assert_true(far > 1e-3);
    }
    unsigned char *b;
    size_t n;
    assert_int_equal(affect_fda_encode(all, &b, &n, &err), AFFECT_OK);
    assert_int_equal(b[4], 3);
    assert_int_equal(b[8], 2);
    affect_fda *back = NULL;
    if (affect_fda_decode(b, n, &back, &err))
        fail_msg("decode: %s", err.msg);
    encodes_to(back, (const char *)b, n);
    for (uint32_t k = 0; k < 4; k++) {
        affect_fda_prototype_coefs(all, k, pa);
        affect_fda_prototype_coefs(back, k, pe);
        assert_memory_equal(pa, pe, sizeof pa);
    }
    free(b);
    affect_fda_free(back);
    affect_fda_free(all);
    affect_fda_free(every);
    affect_fda_free(three);
    free_data(&d);
}

static void test_perturbation(void **state)
{
    (void)state;
    data d = make_data(20, 4, 0.8, 17);
    affect_fda_config cfg;
    small_cfg(&cfg, AFFECT_FDA_FPCA);
    cfg.proto_dims = 3; /* keeps the eigenfunctions the check compares with */
    affect_fda *f = train_ok(&cfg, &d);
    double mean[11], plus[11], minus[11], psi[11], mc[12], ec[12];
    affect_error err;
    const double *efun = affect_fda_eigenfunctions(f), *mu = affect_fda_mean(f);
    affect_bspline b = {4, 12};
    for (uint32_t r = 0; r < 2; r++)
        for (uint32_t j = 0; j < 2; j++) {
            assert_int_equal(affect_fda_perturbation(f, r, j, 2.0, 11, mean, plus, minus, &err),
                             AFFECT_OK);
            for (int g = 0; g < 12; g++) {
                mc[g] = mu[g * 2 + j];
                ec[g] = efun[r * 24 + g * 2 + j];
            }
            double m2[11];
            affect_bspline_values(&b, mc, 1, NULL, 11, m2);
            affect_bspline_values(&b, ec, 1, NULL, 11, psi);
            double s = 2.0 * sqrt(affect_fda_fpca_eigenvalues(f)[r]);
            for (int t = 0; t < 11; t++) {
                tu_assert_near(mean[t], m2[t], 1e-12);
                tu_assert_near(plus[t] - mean[t], s * psi[t], 1e-8);
                tu_assert_near(mean[t] - minus[t], s * psi[t], 1e-8);
            }
        }
    assert_int_equal(affect_fda_perturbation(f, 3, 0, 2.0, 11, mean, plus, minus, &err),
                     AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "axis 4 is out of range (3 dimensions)");
    assert_int_equal(affect_fda_perturbation(f, 0, 2, 2.0, 11, mean, plus, minus, &err),
                     AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "coordinate 3 is out of range (2 coordinates)");
    affect_fda_free(f);
    small_cfg(&cfg, AFFECT_FDA_FISOMAP);
    f = train_ok(&cfg, &d);
    assert_int_equal(affect_fda_perturbation(f, 0, 0, 2.0, 11, mean, plus, minus, &err),
                     AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "perturbation plots need a linear method (fpca, ffda, fspca), "
                                 "not fisomap");
    affect_fda_free(f);
    free_data(&d);
}

/* ---- allocation failure ---- */
typedef struct oom_ctx {
    data *d;
    affect_fda_method method;
    affect_fda *f;
    affect_fda_alignment alignment;
} oom_ctx;

static affect_status oom_op(void *p, affect_error *err)
{
    oom_ctx *o = p;
    affect_fda_config cfg;
    small_cfg(&cfg, o->method);
    cfg.n_basis = 6;
    cfg.alignment = o->alignment;
    affect_status st = affect_fda_train(&cfg, NULL, o->d->seqs, o->d->n, o->d->m, o->d->y, NAMES,
                                        o->d->c, &o->f, err);
    if (st)
        return st;
    unsigned char *blob = NULL;
    size_t size;
    affect_fda *g = NULL;
    double z[3];
    if ((st = affect_fda_encode(o->f, &blob, &size, err)) == AFFECT_OK &&
        (st = affect_fda_decode(blob, size, &g, err)) == AFFECT_OK)
        st = affect_fda_embed(g, o->d->x[0], o->d->seqs[0].n_frames, z, err);
    affect_free(blob);
    affect_fda_free(g);
    return st;
}

static void oom_finish(void *p, affect_status st)
{
    (void)st;
    oom_ctx *o = p;
    affect_fda_free(o->f);
    o->f = NULL;
}

static void test_oom(void **state)
{
    (void)state;
    data d = make_data(10, 3, 1.0, 4);
    for (int method = 0; method < 4; method++) {
        oom_ctx o = {&d, (affect_fda_method)method, NULL, AFFECT_FDA_ALIGN_LINEAR};
        long calls = tu_oom_sweep(oom_op, &o, oom_finish, NULL);
        assert_true(calls > 10);
    }
    oom_ctx o = {&d, AFFECT_FDA_FFDA, NULL, AFFECT_FDA_ALIGN_LANDMARKS};
    assert_true(tu_oom_sweep(oom_op, &o, oom_finish, NULL) > 10);
    free_data(&d);
}

/* ---- landmark registration ---- */

#define PI 3.141592653589793

/* A known warp g of [0, 1] (piecewise linear through (0, 0), (0.35, 0.45), (0.75, 0.8), (1, 1))
 * and its inverse. Its kinks lie between landmarks: a kink at a rest makes the smoothed speed
 * lopsided there and moves the found rest by up to 0.02. */
static const double WARP_U[] = {0.0, 0.35, 0.75, 1.0}, WARP_S[] = {0.0, 0.45, 0.8, 1.0};

static double pwl(const double *from, const double *to, double t)
{
    int k = 0;
    while (k < 2 && t > from[k + 1])
        k++;
    return to[k] + (t - from[k]) * (to[k + 1] - to[k]) / (from[k + 1] - from[k]);
}

/* The base movement at canonical time u: amplitude a × (sin 5πu, ½ sin 5πu); its speed peaks
 * at u = 0.2, 0.4, 0.6, 0.8 and rests (zero speed) at u = 0.1, 0.3, …, 0.9. A motion of T
 * frames shows it at u = inverse warp of j / (T − 1) (warped) or at j / (T − 1). */
static double *warped_motion(uint32_t T, double a, const double *wu, const double *ws)
{
    double *x = malloc((size_t)T * 2 * sizeof *x);
    assert_non_null(x);
    for (uint32_t j = 0; j < T; j++) {
        double s = j / (double)(T - 1), u = wu ? pwl(ws, wu, s) : s;
        x[2 * j] = a * sin(5 * PI * u);
        x[2 * j + 1] = 0.5 * a * sin(5 * PI * u);
    }
    return x;
}

static void test_landmarks_known_warp(void **state)
{
    (void)state;
    const uint32_t T = 301;
    double *base = warped_motion(T, 1.0, NULL, NULL);
    double *warp = warped_motion(T, 1.0, WARP_U, WARP_S);
    affect_fda_landmark lb[AFFECT_FDA_MAX_LANDMARKS], lw[AFFECT_FDA_MAX_LANDMARKS];
    uint32_t nb = 0, nw = 0;
    affect_error err;
    assert_int_equal(affect_fda_find_landmarks(base, T, 2, lb, &nb, &err), AFFECT_OK);
    assert_int_equal(affect_fda_find_landmarks(warp, T, 2, lw, &nw, &err), AFFECT_OK);
    /* the base: rests at 0.1 .. 0.9 and peaks at 0.2 .. 0.8, alternating */
    assert_int_equal(nb, 9);
    for (uint32_t k = 0; k < nb; k++) {
        tu_assert_near(lb[k].t, 0.1 * (k + 1), 0.01);
        assert_int_equal(lb[k].type, k % 2 == 0 ? -1 : 1);
    }
    /* the warped motion's landmarks are the base's moved by g */
    assert_int_equal(nw, 9);
    uint32_t ia[AFFECT_FDA_MAX_LANDMARKS], ib[AFFECT_FDA_MAX_LANDMARKS];
    assert_int_equal(affect_fda_match_landmarks(lw, nw, lb, nb, ia, ib), 9);
    for (uint32_t k = 0; k < 9; k++) {
        assert_int_equal(ia[k], k);
        assert_int_equal(ib[k], k);
        tu_assert_near(lw[k].t, pwl(WARP_U, WARP_S, lb[k].t), 0.012);
    }
    /* and the registration recovers the warp: frame j goes back to u = g⁻¹(j / (T − 1)) */
    double times[301];
    affect_fda_warp_times(lw, nw, lb, nb, T, times);
    assert_true(times[0] == 0.0 && times[T - 1] == 1.0);
    for (uint32_t j = 0; j < T; j++) {
        tu_assert_near(times[j], pwl(WARP_S, WARP_U, j / (double)(T - 1)), 0.012);
        if (j)
            assert_true(times[j] > times[j - 1]);
    }
    /* matching skips what has no partner: the base against its first half */
    assert_int_equal(affect_fda_match_landmarks(lb, 4, lb, nb, ia, ib), 4);
    assert_int_equal(ib[3], 3);
    /* no movement, or too few frames: no landmarks */
    double still[20] = {0};
    assert_int_equal(affect_fda_find_landmarks(still, 10, 2, lb, &nb, &err), AFFECT_OK);
    assert_int_equal(nb, 0);
    assert_int_equal(affect_fda_find_landmarks(base, 4, 2, lb, &nb, &err), AFFECT_OK);
    assert_int_equal(nb, 0);
    free(base);
    free(warp);
}

/* 12 motions of 2 classes (amplitudes 1 and 1.6), each the base movement under its own warp
 * (interior knots moved by up to ±0.12) and of 90 .. 200 frames. */
static data warped_data(void)
{
    data d = {12, 2, 2, NULL, NULL, NULL};
    d.seqs = calloc(d.n, sizeof *d.seqs);
    d.x = calloc(d.n, sizeof *d.x);
    d.y = calloc(d.n, sizeof *d.y);
    assert_true(d.seqs && d.x && d.y);
    for (uint32_t i = 0; i < d.n; i++) {
        double a = (double)(i % 6) / 5.0 - 0.5; /* −0.5 .. 0.5 */
        double wu[] = {0.0, 0.3, 0.7, 1.0};
        double ws[] = {0.0, 0.3 + 0.24 * a, 0.7 - 0.2 * a, 1.0};
        uint32_t T = 90 + 10 * i;
        d.y[i] = i % 2;
        d.x[i] = warped_motion(T, d.y[i] ? 1.6 : 1.0, wu, ws);
        d.seqs[i].x = d.x[i];
        d.seqs[i].n_frames = T;
    }
    return d;
}

static void test_landmarks_model(void **state)
{
    (void)state;
    data d = warped_data();
    affect_fda_config cfg;
    small_cfg(&cfg, AFFECT_FDA_FPCA);
    cfg.n_basis = 40;
    cfg.lambda = 1e-8;
    cfg.proto_dims = 3; /* the thesis's prototypes: versions 1 and 2 */
    affect_fda *lin = train_ok(&cfg, &d);
    cfg.alignment = AFFECT_FDA_ALIGN_LANDMARKS;
    affect_fda *lm = train_ok(&cfg, &d);
    /* the template is the base's landmarks; registered, the curves differ by amplitude only:
     * far less variance, and the first FPCA axis carries nearly all of it */
    uint32_t nt;
    const affect_fda_landmark *tp = affect_fda_template(lm, &nt);
    assert_int_equal(nt, 9);
    for (uint32_t k = 0; k < nt; k++)
        tu_assert_near(tp[k].t, 0.1 * (k + 1), 0.05);
    double v_lin = affect_fda_total_variance(lin), v_lm = affect_fda_total_variance(lm);
    /* measured: 0.431 linear, 0.069 registered (amplitude alone: 0.061); first FPCA share
     * 0.79 linear, 0.90 registered */
    assert_true(v_lm < 0.2 * v_lin);
    assert_true(v_lm < 1.25 * 0.09 * 0.625 * 12 / 11); /* amplitude ± 0.3 of ‖f‖² = 0.625 */
    assert_true(affect_fda_fpca_eigenvalues(lm)[0] / v_lm >
                affect_fda_fpca_eigenvalues(lin)[0] / v_lin + 0.05);
    uint32_t n0;
    affect_fda_template(lin, &n0);
    assert_int_equal(n0, 0);
    /* unseen motions are registered the same way: a training motion embeds to its training
     * coordinates */
    const double *tz = affect_fda_train_embedding(lm);
    uint32_t p = affect_fda_dims(lm);
    for (uint32_t i = 0; i < d.n; i++) {
        double z[3];
        affect_error err;
        assert_int_equal(affect_fda_embed(lm, d.x[i], d.seqs[i].n_frames, z, &err), AFFECT_OK);
        for (uint32_t r = 0; r < p; r++)
            tu_assert_near(z[r], tz[i * p + r], 1e-9 * (1 + fabs(tz[i * p + r])));
    }
    /* the BLOB: version 2 with flags 1, the template back; linear models stay version 1 */
    unsigned char *b1, *b2, *b3;
    size_t n1, n2, n3;
    affect_error err;
    assert_int_equal(affect_fda_encode(lin, &b1, &n1, &err), AFFECT_OK);
    assert_int_equal(affect_fda_encode(lm, &b2, &n2, &err), AFFECT_OK);
    assert_int_equal(b1[4], 1);
    assert_int_equal(b2[4], 2);
    assert_int_equal(b2[8], 1);
    affect_fda *back = NULL;
    if (affect_fda_decode(b2, n2, &back, &err))
        fail_msg("decode: %s", err.msg);
    assert_int_equal(affect_fda_get_config(back)->alignment, AFFECT_FDA_ALIGN_LANDMARKS);
    uint32_t nb;
    const affect_fda_landmark *bt = affect_fda_template(back, &nb);
    assert_int_equal(nb, nt);
    for (uint32_t k = 0; k < nb; k++)
        assert_true(bt[k].t == tp[k].t && bt[k].type == tp[k].type);
    assert_int_equal(affect_fda_encode(back, &b3, &n3, &err), AFFECT_OK);
    assert_int_equal(n3, n2);
    assert_memory_equal(b3, b2, n2);
    /* a version-1 BLOB with flags 1 is out of range */
    b1[8] = 1;
    affect_fda *bad = NULL;
    uint64_t sum = affect_fnv1a64(b1, n1 - 8);
    for (int k = 0; k < 8; k++)
        b1[n1 - 8 + k] = (unsigned char)(sum >> (8 * k));
    assert_int_equal(affect_fda_decode(b1, n1, &bad, &err), AFFECT_ERR_FORMAT);
    assert_string_equal(err.msg, "flags 1 is out of range (offset 8)");
    free(b1);
    free(b2);
    free(b3);
    affect_fda_free(back);
    affect_fda_free(lin);
    affect_fda_free(lm);
    free_data(&d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_gram_sqrt),
        cmocka_unit_test(test_fpca_is_pca_of_weighted),
        cmocka_unit_test(test_fspca_is_spca_of_weighted),
        cmocka_unit_test(test_out_of_sample_training),
        cmocka_unit_test(test_isomap_joins_components),
        cmocka_unit_test(test_classify_separated),
        cmocka_unit_test(test_swiss_roll),
        cmocka_unit_test(test_gcv),
        cmocka_unit_test(test_determinism_and_blob),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_fixture_v1),
        cmocka_unit_test(test_fixture_v2),
        cmocka_unit_test(test_perturbation),
        cmocka_unit_test(test_oom),
        cmocka_unit_test(test_fixture_v3),
        cmocka_unit_test(test_prototype_class_mean),
        cmocka_unit_test(test_landmarks_known_warp),
        cmocka_unit_test(test_landmarks_model),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
