/*
 * test_svm.c — the linear SVM on libsvm (affect/svm.h): separable data in d = 2000 learnt
 * perfectly and held-out points predicted correctly; the primal decision values against
 * libsvm's own svm_predict_values on the precomputed model (and the model's fields against
 * libsvm's, bit for bit); the one-vs-one vote and its tie rule, on hand-made models and on a
 * trained one; choosing C by cross-validation on data where a small C underfits;
 * stratified folds; bit-identical round trips of the encoding; every truncation and each
 * corrupt field refused with its message; exact error messages; allocation failure.
 */
#include <stdio.h>
#include <string.h>

#include <libsvm/svm.h>

#include "testutil.h"

#include "util/rng.h"
#include "affect/svm.h"
#include "util/bytes.h"

enum { D = 2000 };

static void silent(const char *s)
{
    (void)s;
}

/* ---- data ---- */

/* Gaussian blobs: class k has mean mu[k] (components N(0, sep²), drawn from seed) and noise
 * N(0, noise²) per component. */
typedef struct blobs {
    uint32_t c;
    size_t d;
    double *mu;
} blobs;

static blobs blobs_new(uint32_t c, size_t d, double sep, uint64_t seed)
{
    blobs b = {c, d, malloc(sizeof(double) * c * d)};
    assert_non_null(b.mu);
    affect_rng r;
    affect_rng_seed(&r, seed);
    for (size_t i = 0; i < c * d; i++)
        b.mu[i] = sep * affect_rng_normal(&r);
    return b;
}

/* n samples of classes y (given) into X (n × d). */
static void blobs_draw(const blobs *b, const uint32_t *y, size_t n, double noise, uint64_t seed,
                       double *X)
{
    affect_rng r;
    affect_rng_seed(&r, seed);
    for (size_t i = 0; i < n; i++)
        for (size_t j = 0; j < b->d; j++)
            X[i * b->d + j] = b->mu[y[i] * b->d + j] + noise * affect_rng_normal(&r);
}

static double dot(const double *a, const double *b, size_t d)
{
    double s = 0;
    for (size_t j = 0; j < d; j++)
        s += a[j] * b[j];
    return s;
}

static size_t n_pairs(uint32_t c)
{
    return (size_t)c * (c - 1) / 2;
}

static void expect_error(affect_status got, const affect_error *err, affect_status status,
                         const char *msg)
{
    if (got != status || strcmp(err->msg, msg) != 0)
        fail_msg("got status %d \"%s\", expected %d \"%s\"", (int)got, err->msg, (int)status, msg);
}

/* ---- training on separable data ---- */

static void test_separable(void **state)
{
    (void)state;
    enum { C4 = 4, PER = 12, N = C4 * PER, NT = 40 };
    blobs b = blobs_new(C4, D, 1.0, 11);
    uint32_t y[N], yt[NT];
    for (int i = 0; i < N; i++)
        y[i] = (uint32_t)((i * 7) % C4); /* interleaved */
    for (int i = 0; i < NT; i++)
        yt[i] = (uint32_t)(i % C4);
    double *X = malloc(sizeof(double) * N * D), *Xt = malloc(sizeof(double) * NT * D);
    blobs_draw(&b, y, N, 0.5, 12, X);
    blobs_draw(&b, yt, NT, 0.5, 13, Xt);

    affect_svm *m = NULL;
    affect_error err;
    assert_int_equal(affect_svm_train(X, N, D, y, C4, 1.0, &m, &err), AFFECT_OK);
    assert_non_null(m);
    assert_int_equal(affect_svm_n_classes(m), C4);
    assert_int_equal(affect_svm_dim(m), D);
    assert_true(affect_svm_C(m) == 1.0);
    assert_int_equal(affect_svm_n_train(m), N);

    for (int i = 0; i < N; i++)
        assert_int_equal(affect_svm_predict(m, X + (size_t)i * D, NULL), y[i]);
    double dec[6];
    for (int i = 0; i < NT; i++) {
        uint32_t k = affect_svm_predict(m, Xt + (size_t)i * D, dec);
        assert_int_equal(k, yt[i]);
        /* the winner wins all its pairs here */
        for (uint32_t p = 0, q = 0; p < C4; p++)
            for (uint32_t r = p + 1; r < C4; r++, q++) {
                if (p == k)
                    assert_true(dec[q] > 0);
                if (r == k)
                    assert_true(dec[q] <= 0);
            }
    }

    /* support vectors: grouped by class, increasing within a class, of that class */
    uint32_t total = 0;
    const uint32_t *svi = affect_svm_sv_indices(m);
    for (uint32_t k = 0; k < C4; k++) {
        uint32_t nk = affect_svm_n_sv(m, k);
        assert_true(nk >= 1);
        for (uint32_t i = 0; i < nk; i++) {
            assert_true(svi[total + i] < N);
            assert_int_equal(y[svi[total + i]], k);
            if (i > 0)
                assert_true(svi[total + i] > svi[total + i - 1]);
        }
        total += nk;
    }
    assert_int_equal(affect_svm_n_sv(m, C4), 0);
    assert_int_equal(affect_svm_total_sv(m), total);
    assert_non_null(affect_svm_sv_coef(m, C4 - 2));
    assert_null(affect_svm_sv_coef(m, C4 - 1));

    /* pairs and weights */
    assert_int_equal(affect_svm_pair_index(m, 0, 1), 0);
    assert_int_equal(affect_svm_pair_index(m, 0, 3), 2);
    assert_int_equal(affect_svm_pair_index(m, 1, 2), 3);
    assert_int_equal(affect_svm_pair_index(m, 2, 3), 5);
    assert_int_equal(affect_svm_pair_index(m, 1, 1), UINT32_MAX);
    assert_int_equal(affect_svm_pair_index(m, 2, 1), UINT32_MAX);
    assert_int_equal(affect_svm_pair_index(m, 0, 4), UINT32_MAX);
    assert_null(affect_svm_weights(m, 1, 0, NULL));
    assert_null(affect_svm_weights(m, 3, 4, NULL));
    double rho;
    const double *w = affect_svm_weights(m, 1, 3, &rho);
    assert_non_null(w);
    affect_svm_predict(m, Xt, dec);
    tu_assert_near(dec[4], dot(w, Xt, D) - rho, 1e-12 * (1 + fabs(dec[4])));
    /* w_13 from the dual: Σ over class 1's SVs of sv_coef[2] x + over class 3's of sv_coef[1] x */
    {
        uint32_t s1 = affect_svm_n_sv(m, 0),
                 s3 = s1 + affect_svm_n_sv(m, 1) + affect_svm_n_sv(m, 2);
        const double *coef1 = affect_svm_sv_coef(m, 2), *coef2 = affect_svm_sv_coef(m, 1);
        double *ref = calloc(D, sizeof *ref);
        for (uint32_t i = 0; i < affect_svm_n_sv(m, 1); i++)
            for (int j = 0; j < D; j++)
                ref[j] += coef1[s1 + i] * X[(size_t)svi[s1 + i] * D + j];
        for (uint32_t i = 0; i < affect_svm_n_sv(m, 3); i++)
            for (int j = 0; j < D; j++)
                ref[j] += coef2[s3 + i] * X[(size_t)svi[s3 + i] * D + j];
        assert_memory_equal(ref, w, sizeof(double) * D);
        free(ref);
    }
    affect_svm_free(m);
    free(X);
    free(Xt);
    free(b.mu);
}

/* ---- against libsvm itself ---- */

/* libsvm trained directly on the precomputed Gram matrix G, the problem's rows being the
 * samples order[0 .. n−1] with serials 1 .. n. */
typedef struct direct {
    struct svm_problem prob;
    struct svm_node *nodes;
    struct svm_node **rows;
    double *labels;
    struct svm_model *model;
} direct;

static void direct_train(direct *t, const double *G, size_t n, const uint32_t *y,
                         const uint32_t *order, double C)
{
    t->nodes = malloc(sizeof *t->nodes * n * (n + 2));
    t->rows = malloc(sizeof *t->rows * n);
    t->labels = malloc(sizeof *t->labels * n);
    for (size_t r = 0; r < n; r++) {
        struct svm_node *row = t->nodes + r * (n + 2);
        row[0].index = 0;
        row[0].value = (double)(r + 1);
        for (size_t s = 0; s < n; s++) {
            row[s + 1].index = (int)(s + 1);
            row[s + 1].value = G[order[r] * n + order[s]];
        }
        row[n + 1].index = -1;
        t->rows[r] = row;
        t->labels[r] = y[order[r]];
    }
    t->prob.l = (int)n;
    t->prob.y = t->labels;
    t->prob.x = t->rows;
    struct svm_parameter param;
    memset(&param, 0, sizeof param);
    param.svm_type = C_SVC;
    param.kernel_type = PRECOMPUTED;
    param.cache_size = 100;
    param.eps = 1e-3;
    param.C = C;
    param.shrinking = 1;
    assert_null(svm_check_parameter(&t->prob, &param));
    svm_set_print_string_function(silent);
    t->model = svm_train(&t->prob, &param);
    assert_non_null(t->model);
}

static void direct_free(direct *t)
{
    svm_free_and_destroy_model(&t->model);
    free(t->nodes);
    free(t->rows);
    free(t->labels);
}

/* Trains both ways on n samples (problem order `order` for libsvm) and compares the models and
 * the decision values and predictions of the nt held-out points. */
static void compare_with_libsvm(const double *X, size_t n, const uint32_t *y, uint32_t c,
                                const uint32_t *order, const double *Xt, size_t nt, double C)
{
    affect_error err;
    double *G = malloc(sizeof(double) * n * n);
    assert_int_equal(affect_svm_gram(X, n, D, G, &err), AFFECT_OK);
    for (size_t i = 0; i < n; i++)
        for (size_t j = 0; j < n; j++) {
            assert_true(G[i * n + j] == G[j * n + i]);
            tu_assert_near(G[i * n + j], dot(X + i * D, X + j * D, D),
                           1e-12 * (1 + fabs(G[i * n + j])));
        }
    direct t;
    direct_train(&t, G, n, y, order, C);
    affect_svm *m = NULL;
    assert_int_equal(affect_svm_train(X, n, D, y, c, C, &m, &err), AFFECT_OK);

    /* libsvm's class order is ours; its fields are ours, bit for bit */
    assert_int_equal(svm_get_nr_class(t.model), c);
    int labels[8];
    svm_get_labels(t.model, labels);
    for (uint32_t k = 0; k < c; k++) {
        assert_int_equal(labels[k], k);
        assert_int_equal(t.model->nSV[k], affect_svm_n_sv(m, k));
    }
    uint32_t l = affect_svm_total_sv(m);
    assert_int_equal(svm_get_nr_sv(t.model), l);
    int *svi = malloc(sizeof(int) * l);
    svm_get_sv_indices(t.model, svi);
    for (uint32_t i = 0; i < l; i++)
        assert_int_equal(order[svi[i] - 1], affect_svm_sv_indices(m)[i]);
    for (uint32_t j = 0; j + 1 < c; j++)
        assert_memory_equal(t.model->sv_coef[j], affect_svm_sv_coef(m, j), sizeof(double) * l);
    for (uint32_t p = 0, q = 0; p < c; p++)
        for (uint32_t r = p + 1; r < c; r++, q++) {
            double rho;
            assert_non_null(affect_svm_weights(m, p, r, &rho));
            assert_true(rho == t.model->rho[q]);
        }

    /* held-out points: kernel values in libsvm's serial order */
    struct svm_node *x = malloc(sizeof *x * (n + 2));
    double dec_ours[6], dec_lib[6];
    size_t P = n_pairs(c);
    double worst = 0;
    for (size_t i = 0; i < nt; i++) {
        const double *xt = Xt + i * D;
        x[0].index = 0;
        x[0].value = 0;
        for (size_t s = 0; s < n; s++) {
            x[s + 1].index = (int)(s + 1);
            x[s + 1].value = dot(xt, X + order[s] * D, D);
        }
        x[n + 1].index = -1;
        double lab = svm_predict_values(t.model, x, dec_lib);
        uint32_t k = affect_svm_predict(m, xt, dec_ours);
        assert_int_equal(k, (uint32_t)lab);
        for (size_t q = 0; q < P; q++) {
            double rel = fabs(dec_ours[q] - dec_lib[q]) / fabs(dec_lib[q]);
            if (!(rel <= 1e-9))
                fail_msg("point %zu, pair %zu: ours %.17g, libsvm %.17g", i, q, dec_ours[q],
                         dec_lib[q]);
            if (rel > worst)
                worst = rel;
        }
    }
    assert_true(worst < 1e-9);
    free(x);
    free(svi);
    affect_svm_free(m);
    direct_free(&t);
    free(G);
}

static void test_matches_libsvm(void **state)
{
    (void)state;
    enum { N = 40, NT = 30 };
    uint32_t y[N], yt[NT], order[N];
    double *X = malloc(sizeof(double) * N * D), *Xt = malloc(sizeof(double) * NT * D);
    for (int i = 0; i < NT; i++)
        yt[i] = (uint32_t)(i % 4);

    /* four classes in first-appearance order, interleaved: libsvm groups them itself */
    blobs b = blobs_new(4, D, 0.3, 21);
    for (int i = 0; i < N; i++) {
        y[i] = (uint32_t)(i % 4);
        order[i] = (uint32_t)i;
    }
    blobs_draw(&b, y, N, 1.0, 22, X); /* noisy: overlapping classes, bounded SVs */
    blobs_draw(&b, yt, NT, 1.0, 23, Xt);
    compare_with_libsvm(X, N, y, 4, order, Xt, NT, 1e-4); /* every α at its bound */
    compare_with_libsvm(X, N, y, 4, order, Xt, NT, 3e-4); /* some at the bound */
    compare_with_libsvm(X, N, y, 4, order, Xt, NT, 10.0); /* hard margin */
    free(b.mu);

    /* three well-separated classes appearing as 2, 0, 1 (few support vectors): libsvm is given
     * them grouped in our order */
    b = blobs_new(3, D, 1.0, 31);
    for (int i = 0; i < N; i++)
        y[i] = (uint32_t)((i + 2) % 3);
    for (int k = 0, r = 0; k < 3; k++)
        for (int i = 0; i < N; i++)
            if (y[i] == (uint32_t)k)
                order[r++] = (uint32_t)i;
    for (int i = 0; i < NT; i++)
        yt[i] = (uint32_t)(i % 3);
    blobs_draw(&b, y, N, 0.2, 32, X);
    blobs_draw(&b, yt, NT, 0.2, 33, Xt);
    compare_with_libsvm(X, N, y, 3, order, Xt, NT, 1.0);
    free(b.mu);
    free(X);
    free(Xt);
}

/* ---- the vote ---- */

/* The encoding of a hand-made model: c classes, d = 1, one support vector per class, weights
 * 0 and rho[q] = −target[q], so that the decision value of any point is target[q]. */
static void craft(affect_bw *w, uint32_t c, const double *target)
{
    size_t P = n_pairs(c);
    affect_bw_init(w);
    affect_bw_u8(w, 1);
    affect_bw_u32(w, c);
    affect_bw_u64(w, 1);
    affect_bw_f64(w, 1.0);
    affect_bw_u32(w, c); /* training samples */
    affect_bw_u32(w, c);
    for (uint32_t k = 0; k < c; k++)
        affect_bw_u32(w, k);
    affect_bw_u32(w, c);
    for (uint32_t k = 0; k < c; k++)
        affect_bw_u32(w, 1);
    affect_bw_u32(w, c);
    for (uint32_t k = 0; k < c; k++)
        affect_bw_u32(w, k);
    affect_bw_u32(w, c - 1);
    for (uint32_t k = 0; k < (c - 1) * c; k++)
        affect_bw_f64(w, 0.5);
    affect_bw_u32(w, (uint32_t)P);
    for (size_t q = 0; q < P; q++)
        affect_bw_f64(w, -target[q]);
    affect_bw_u32(w, (uint32_t)P);
    for (size_t q = 0; q < P; q++)
        affect_bw_f64(w, 0.0);
    assert_false(w->failed);
}

static uint32_t vote_of(uint32_t c, const double *target)
{
    affect_bw w;
    craft(&w, c, target);
    affect_br r;
    affect_br_init(&r, w.data, w.len);
    affect_svm *m = NULL;
    affect_error err;
    assert_int_equal(affect_svm_decode(&r, &m, &err), AFFECT_OK);
    assert_int_equal(r.off, w.len);
    double x = 123.0, dec[16];
    uint32_t k = affect_svm_predict(m, &x, dec);
    for (size_t q = 0; q < n_pairs(c); q++)
        assert_true(dec[q] == target[q]);
    /* the vote on the decision values is the model's (its classes are 0 .. c − 1 in order) */
    uint32_t votes[8];
    assert_int_equal(affect_svm_vote(dec, c, votes), k);
    assert_int_equal(affect_svm_vote(dec, c, NULL), k);
    uint32_t total = 0;
    for (uint32_t i = 0; i < c; i++)
        total += votes[i];
    assert_int_equal(total, n_pairs(c));
    affect_svm_free(m);
    affect_bw_free(&w);
    return k;
}

/* affect_svm_vote's counts, and its answer outside 1 .. AFFECT_SVM_MAX_CLASSES classes. */
static void test_vote_counts(void **state)
{
    (void)state;
    static const double clear[6] = {-1, 1, 1, 1, 1, 1};
    static const double tie123[6] = {-1, -1, -1, 1, -1, 1};
    static const double nan6[6] = {NAN, NAN, NAN, NAN, NAN, NAN}; /* each a vote for q */
    static const uint32_t clear_votes[4] = {2, 3, 1, 0}, tie_votes[4] = {0, 2, 2, 2};
    static const uint32_t nan_votes[4] = {0, 1, 2, 3};
    uint32_t v[4];
    assert_int_equal(affect_svm_vote(clear, 4, v), 1);
    assert_memory_equal(v, clear_votes, sizeof v);
    assert_int_equal(affect_svm_vote(tie123, 4, v), 1);
    assert_memory_equal(v, tie_votes, sizeof v);
    assert_int_equal(affect_svm_vote(nan6, 4, v), 3);
    assert_memory_equal(v, nan_votes, sizeof v);
    assert_int_equal(affect_svm_vote(NULL, 1, v), 0); /* one class: no pair, it wins */
    assert_int_equal(v[0], 0);
    v[0] = 7;
    assert_int_equal(affect_svm_vote(clear, 0, v), UINT32_MAX);
    assert_int_equal(affect_svm_vote(clear, AFFECT_SVM_MAX_CLASSES + 1, v), UINT32_MAX);
    assert_int_equal(v[0], 7);
}

static void test_vote(void **state)
{
    (void)state;
    /* pairs (0,1) (0,2) (0,3) (1,2) (1,3) (2,3) */
    static const double clear[6] = {-1, 1, 1, 1, 1, 1};     /* votes 2 3 1 0 */
    static const double tie12[6] = {-1, -1, 1, 1, -1, 1};   /* votes 1 2 2 1: tie 1, 2 */
    static const double tie23[6] = {1, -1, -1, 1, -1, 1};   /* votes 1 1 2 2: tie 2, 3 */
    static const double tie123[6] = {-1, -1, -1, 1, -1, 1}; /* 0 2 2 2 */
    static const double zeros[6] = {0, 0, 0, 0, 0, 0};      /* 0 is a vote for q: 0 1 2 3 */
    static const double tiny[6] = {0x1p-1074, 0x1p-1074, 0x1p-1074, 0, 0, 0}; /* 3 0 1 2 */
    assert_int_equal(vote_of(4, clear), 1);
    assert_int_equal(vote_of(4, tie12), 1);
    assert_int_equal(vote_of(4, tie23), 2);
    assert_int_equal(vote_of(4, tie123), 1);
    assert_int_equal(vote_of(4, zeros), 3);
    assert_int_equal(vote_of(4, tiny), 0);
    /* a three-cycle: one vote each, the first class wins */
    static const double cycle[3] = {1, -1, 1}; /* 0 beats 1, 2 beats 0, 1 beats 2 */
    assert_int_equal(vote_of(3, cycle), 0);
    static const double neg[1] = {-0.0};
    assert_int_equal(vote_of(2, neg), 1);
}

/* Solves the n × n system A a = b in place by Gaussian elimination with partial pivoting. */
static void solve(double *A, double *b, int n)
{
    for (int k = 0; k < n; k++) {
        int p = k;
        for (int i = k + 1; i < n; i++)
            if (fabs(A[i * n + k]) > fabs(A[p * n + k]))
                p = i;
        for (int j = 0; j < n; j++) {
            double t = A[k * n + j];
            A[k * n + j] = A[p * n + j];
            A[p * n + j] = t;
        }
        double t = b[k];
        b[k] = b[p];
        b[p] = t;
        for (int i = k + 1; i < n; i++) {
            double f = A[i * n + k] / A[k * n + k];
            for (int j = k; j < n; j++)
                A[i * n + j] -= f * A[k * n + j];
            b[i] -= f * b[k];
        }
    }
    for (int k = n - 1; k >= 0; k--) {
        for (int j = k + 1; j < n; j++)
            b[k] -= A[k * n + j] * b[j];
        b[k] /= A[k * n + k];
    }
}

/* On a trained four-class model: points whose decision values have chosen signs, found in the
 * span of the six weight vectors, give the ties their first class. */
static void test_vote_trained(void **state)
{
    (void)state;
    enum { N = 32 };
    blobs b = blobs_new(4, D, 1.0, 41);
    uint32_t y[N];
    for (int i = 0; i < N; i++)
        y[i] = (uint32_t)(i % 4);
    double *X = malloc(sizeof(double) * N * D);
    blobs_draw(&b, y, N, 0.5, 42, X);
    affect_svm *m = NULL;
    affect_error err;
    assert_int_equal(affect_svm_train(X, N, D, y, 4, 1.0, &m, &err), AFFECT_OK);
    const double *w[6];
    double rho[6];
    for (uint32_t p = 0, q = 0; p < 4; p++)
        for (uint32_t r = p + 1; r < 4; r++, q++)
            w[q] = affect_svm_weights(m, p, r, &rho[q]);
    static const double targets[3][6] = {
        {-1, -1, 1, 1, -1, 1}, /* votes 1 2 2 1 */
        {1, -1, -1, 1, -1, 1}, /* votes 1 1 2 2 */
        {1, -1, 1, 1, -1, 1},  /* votes 2 1 2 1 */
    };
    static const uint32_t expect[3] = {1, 2, 0};
    double *x = malloc(sizeof(double) * D);
    for (int t = 0; t < 3; t++) {
        double A[36], a[6];
        for (int i = 0; i < 6; i++) {
            a[i] = targets[t][i] + rho[i];
            for (int j = 0; j < 6; j++)
                A[i * 6 + j] = dot(w[i], w[j], D);
        }
        solve(A, a, 6);
        for (int j = 0; j < D; j++) {
            x[j] = 0;
            for (int i = 0; i < 6; i++)
                x[j] += a[i] * w[i][j];
        }
        double dec[6];
        assert_int_equal(affect_svm_predict(m, x, dec), expect[t]);
        for (int q = 0; q < 6; q++)
            tu_assert_near(dec[q], targets[t][q], 1e-6);
    }
    free(x);
    affect_svm_free(m);
    free(X);
    free(b.mu);
}

/* ---- stratified folds ---- */

static uint64_t ref_below(affect_rng *r, uint64_t bound)
{
    uint64_t threshold = (0 - bound) % bound;
    for (;;) {
        uint64_t x = affect_rng_next(r);
        if (x >= threshold)
            return x % bound;
    }
}

/* The documented algorithm, written out again. */
static void ref_folds(const uint32_t *y, size_t n, uint32_t c, uint32_t k, uint64_t seed,
                      uint32_t *fold_of)
{
    uint32_t *order = malloc(sizeof *order * n);
    affect_rng r;
    affect_rng_seed(&r, seed);
    size_t len = 0;
    for (uint32_t j = 0; j < c; j++) {
        size_t begin = len;
        for (size_t i = 0; i < n; i++)
            if (y[i] == j)
                order[len++] = (uint32_t)i;
        for (size_t i = len - begin; i > 1; i--) {
            size_t b = begin + ref_below(&r, i);
            uint32_t t = order[begin + i - 1];
            order[begin + i - 1] = order[b];
            order[b] = t;
        }
    }
    uint32_t kk = k < n ? k : (uint32_t)n;
    for (size_t i = 0; i < n; i++)
        fold_of[order[i]] = (uint32_t)(i % kk);
    free(order);
}

static void test_folds(void **state)
{
    (void)state;
    enum { N = 53, C3 = 3, K = 5 };
    uint32_t y[N], f1[N], f2[N], f3[N], ref[N];
    size_t nk[C3] = {0};
    affect_rng r;
    affect_rng_seed(&r, 5);
    /* classes of 20, 17 and 16 samples, in a scrambled order */
    for (int i = 0; i < N; i++)
        y[i] = i < 20 ? 0 : i < 37 ? 1 : 2;
    for (int i = N - 1; i > 0; i--) {
        int j = (int)(affect_rng_next(&r) % (uint64_t)(i + 1));
        uint32_t t = y[i];
        y[i] = y[j];
        y[j] = t;
    }
    for (int i = 0; i < N; i++)
        nk[y[i]]++;
    affect_error err;
    memset(f1, 0xff, sizeof f1);
    assert_int_equal(affect_stratified_folds(y, N, C3, K, 77, f1, &err), AFFECT_OK);
    size_t count[K][C3], size[K];
    memset(count, 0, sizeof count);
    memset(size, 0, sizeof size);
    for (int i = 0; i < N; i++) {
        assert_true(f1[i] < K); /* every sample in exactly one fold */
        count[f1[i]][y[i]]++;
        size[f1[i]]++;
    }
    for (int f = 0; f < K; f++) {
        for (int k = 0; k < C3; k++) {
            assert_true(count[f][k] == nk[k] / K || count[f][k] == (nk[k] + K - 1) / K);
        }
        assert_true(size[f] == N / K || size[f] == N / K + 1);
    }
    ref_folds(y, N, C3, K, 77, ref);
    assert_memory_equal(f1, ref, sizeof ref);

    assert_int_equal(affect_stratified_folds(y, N, C3, K, 77, f2, &err), AFFECT_OK);
    assert_memory_equal(f1, f2, sizeof f1);
    assert_int_equal(affect_stratified_folds(y, N, C3, K, 78, f3, &err), AFFECT_OK);
    assert_memory_not_equal(f1, f3, sizeof f1);

    /* a class may be absent; k is clamped to n */
    uint32_t ys[3] = {2, 0, 2}, fs[3];
    assert_int_equal(affect_stratified_folds(ys, 3, 4, 10, 1, fs, &err), AFFECT_OK);
    assert_true(fs[0] < 3 && fs[1] < 3 && fs[2] < 3);
    assert_true(fs[0] != fs[1] && fs[0] != fs[2] && fs[1] != fs[2]);
    ref_folds(ys, 3, 4, 10, 1, ref);
    assert_memory_equal(fs, ref, sizeof fs);
    assert_int_equal(affect_stratified_folds(ys, 0, 4, 10, 1, fs, &err), AFFECT_OK);

    expect_error(affect_stratified_folds(y, N, C3, 1, 1, f1, &err), &err, AFFECT_ERR_INVALID,
                 "need at least 2 folds, got 1");
    expect_error(affect_stratified_folds(y, N, 0, 2, 1, f1, &err), &err, AFFECT_ERR_INVALID,
                 "need at least 1 class");
    expect_error(affect_stratified_folds(ys, 3, 2, 2, 1, f1, &err), &err, AFFECT_ERR_INVALID,
                 "sample 0: class 2 out of range 0 .. 1");
}

/* ---- choosing C ---- */

/* Two classes that differ by 6 along a direction of standard deviation 10 (useless) and by
 * 2 along one of standard deviation 0.05 (perfectly separating), plus weak noise elsewhere.
 * A tiny C leaves every α at its bound, w ∝ the difference of the class means, dominated by
 * the useless direction; a large C finds the separating one. */
static void underfit_data(size_t n, uint64_t seed, double *X, uint32_t *y)
{
    affect_rng r;
    affect_rng_seed(&r, seed);
    for (size_t i = 0; i < n; i++) {
        y[i] = (uint32_t)(i % 2);
        double s = y[i] ? 1 : -1;
        double *x = X + i * D;
        x[0] = 3 * s + 10 * affect_rng_normal(&r);
        x[1] = s + 0.05 * affect_rng_normal(&r);
        for (int j = 2; j < D; j++)
            x[j] = 0.01 * affect_rng_normal(&r);
    }
}

static void test_select_c(void **state)
{
    (void)state;
    enum { N = 60 };
    uint32_t y[N];
    double *X = malloc(sizeof(double) * N * D);
    underfit_data(N, 51, X, y);
    static const double cands[5] = {100, 1e-4, 1e-3, 10, 1};
    double acc[5], best_c, best_acc, c2, a2;
    affect_error err;
    for (int i = 0; i < 5; i++) {
        assert_int_equal(affect_svm_select_c(X, N, D, y, 2, &cands[i], 1, 5, 9, &c2, &acc[i], &err),
                         AFFECT_OK);
        assert_true(c2 == cands[i]);
        printf("C = %g: cross-validated accuracy %.4f\n", cands[i], acc[i]);
    }
    assert_true(acc[1] < 0.8);   /* 1e-4 underfits */
    assert_true(acc[0] >= 0.95); /* 100 separates */
    assert_int_equal(affect_svm_select_c(X, N, D, y, 2, cands, 5, 5, 9, &best_c, &best_acc, &err),
                     AFFECT_OK);
    double max = 0, smallest = 0;
    for (int i = 0; i < 5; i++)
        if (acc[i] > max)
            max = acc[i];
    for (int i = 0; i < 5; i++)
        if (acc[i] == max && (smallest == 0 || cands[i] < smallest))
            smallest = cands[i];
    assert_true(best_acc == max);
    assert_true(best_c == smallest);
    assert_true(best_c >= 1);
    /* deterministic */
    assert_int_equal(affect_svm_select_c(X, N, D, y, 2, cands, 5, 5, 9, &c2, &a2, &err), AFFECT_OK);
    assert_true(c2 == best_c && a2 == best_acc);

    /* the model trained with the chosen C generalises */
    uint32_t yt[N];
    double *Xt = malloc(sizeof(double) * N * D);
    underfit_data(N, 52, Xt, yt);
    affect_svm *m = NULL;
    assert_int_equal(affect_svm_train(X, N, D, y, 2, best_c, &m, &err), AFFECT_OK);
    int right = 0;
    for (int i = 0; i < N; i++)
        right += affect_svm_predict(m, Xt + (size_t)i * D, NULL) == yt[i];
    assert_true(right >= N - 2);
    affect_svm_free(m);
    assert_int_equal(affect_svm_train(X, N, D, y, 2, 1e-4, &m, &err), AFFECT_OK);
    right = 0;
    for (int i = 0; i < N; i++)
        right += affect_svm_predict(m, Xt + (size_t)i * D, NULL) == yt[i];
    assert_true(right < 0.85 * N);
    affect_svm_free(m);
    free(Xt);

    /* folds whose training part lacks a class, or has a single one */
    uint32_t ys[6] = {0, 0, 0, 0, 1, 2};
    assert_int_equal(affect_svm_select_c(X, 6, D, ys, 3, cands, 2, 3, 1, &c2, &a2, &err),
                     AFFECT_OK);
    assert_true(a2 >= 0 && a2 <= 1);
    uint32_t yp[2] = {0, 1};
    assert_int_equal(affect_svm_select_c(X, 2, D, yp, 2, cands, 2, 5, 1, &c2, &a2, &err),
                     AFFECT_OK);
    assert_true(a2 == 0 && c2 == 1e-4); /* each fold predicts the other class; tie → smallest */
    free(X);
}

/* ---- errors ---- */

/* Training on the Gram matrix with the weights given block by block gives affect_svm_train's
 * model: the same support vectors and coefficients, the same weights (the same additions in the
 * same order), the same predictions; the dual prediction agrees; select_c on G agrees. */
static void test_gram_blocks(void **state)
{
    (void)state;
    enum { N = 45, DD = 37, C3 = 3 };
    uint32_t y[N];
    for (uint32_t i = 0; i < N; i++)
        y[i] = i % C3;
    blobs b = blobs_new(C3, DD, 1.0, 71);
    double *X = malloc(sizeof(double) * N * DD), *G = malloc(sizeof(double) * N * N);
    double *B = malloc(sizeof(double) * N * DD);
    blobs_draw(&b, y, N, 1.5, 72, X);
    affect_error err;
    assert_int_equal(affect_svm_gram(X, N, DD, G, &err), AFFECT_OK);
    affect_svm *ref = NULL, *m = NULL;
    assert_int_equal(affect_svm_train(X, N, DD, y, C3, 0.5, &ref, &err), AFFECT_OK);
    assert_int_equal(affect_svm_train_gram(G, N, DD, y, C3, 0.5, &m, &err), AFFECT_OK);
    static const size_t cuts[] = {0, 10, 11, 30, DD};
    for (size_t k = 0; k + 1 < sizeof cuts / sizeof cuts[0]; k++) {
        size_t w = cuts[k + 1] - cuts[k];
        for (size_t i = 0; i < N; i++)
            memcpy(B + i * w, X + i * DD + cuts[k], w * sizeof *B);
        assert_int_equal(affect_svm_add_rows(m, B, w, cuts[k], &err), AFFECT_OK);
    }
    assert_int_equal(affect_svm_total_sv(m), affect_svm_total_sv(ref));
    for (uint32_t p = 0; p < C3; p++)
        for (uint32_t q = p + 1; q < C3; q++) {
            double r1, r2;
            const double *w1 = affect_svm_weights(ref, p, q, &r1),
                         *w2 = affect_svm_weights(m, p, q, &r2);
            assert_true(r1 == r2);
            assert_memory_equal(w1, w2, DD * sizeof *w1);
        }
    for (size_t i = 0; i < N; i++) {
        uint32_t a = affect_svm_predict(ref, X + i * DD, NULL);
        assert_int_equal(affect_svm_predict(m, X + i * DD, NULL), a);
        assert_int_equal(affect_svm_predict_gram(m, G + i * N), a);
    }
    assert_int_equal(affect_svm_add_rows(m, B, 5, DD - 4, &err), AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "columns 33 .. 38 are outside the model's 37 dimensions");
    static const double cands[3] = {0.01, 1, 100};
    double c1, a1, c2, a2;
    assert_int_equal(affect_svm_select_c(X, N, DD, y, C3, cands, 3, 5, 3, &c1, &a1, &err),
                     AFFECT_OK);
    assert_int_equal(
        affect_svm_select_c_gram(G, N, DD, y, C3, cands, 3, 5, 3, &c2, &a2, NULL, &err), AFFECT_OK);
    assert_true(c1 == c2 && a1 == a2);
    /* float32 weights: version 2, 4 bytes a weight, the same weights after a round trip */
    affect_bw w64, w32;
    affect_bw_init(&w64);
    affect_bw_init(&w32);
    affect_svm_encode(m, &w64);
    assert_int_equal(w64.data[0], 1);
    assert_true(affect_svm_round_weights(m));
    affect_svm_encode(m, &w32);
    assert_int_equal(w32.data[0], 2);
    assert_int_equal(w64.len - w32.len, (size_t)4 * 3 * DD);
    affect_br rd = {w32.data, w32.len, 0};
    affect_svm *back = NULL;
    assert_int_equal(affect_svm_decode(&rd, &back, &err), AFFECT_OK);
    for (uint32_t p = 0; p < C3; p++)
        for (uint32_t q = p + 1; q < C3; q++) {
            const double *w1 = affect_svm_weights(m, p, q, NULL);
            assert_memory_equal(w1, affect_svm_weights(back, p, q, NULL), DD * sizeof *w1);
            for (size_t t = 0; t < DD; t++)
                assert_true(w1[t] == (float)w1[t]);
        }
    affect_bw out2;
    affect_bw_init(&out2);
    affect_svm_encode(back, &out2);
    assert_int_equal(out2.len, w32.len);
    assert_memory_equal(out2.data, w32.data, w32.len);
    affect_bw_free(&out2);
    affect_bw_free(&w64);
    affect_bw_free(&w32);
    affect_svm_free(back);
    G[3] = NAN;
    affect_svm *bad = NULL;
    assert_int_equal(affect_svm_train_gram(G, N, DD, y, C3, 0.5, &bad, &err), AFFECT_ERR_RANGE);
    assert_string_equal(err.msg, "Gram entry (0, 3) is not finite (the features are too large)");
    affect_svm_free(ref);
    affect_svm_free(m);
    free(b.mu);
    free(X);
    free(G);
    free(B);
}

static void test_errors(void **state)
{
    (void)state;
    enum { N = 6, d = 20 };
    double X[N * d];
    uint32_t y[N] = {0, 1, 2, 0, 1, 2};
    for (int i = 0; i < N * d; i++)
        X[i] = (double)((i * 37) % 11) - 5;
    affect_svm *m = (affect_svm *)1;
    affect_error err;
    expect_error(affect_svm_train(X, N, d, y, 1, 1.0, &m, &err), &err, AFFECT_ERR_INVALID,
                 "need at least 2 classes");
    assert_null(m);
    expect_error(affect_svm_train(X, N, d, y, 300, 1.0, &m, &err), &err, AFFECT_ERR_INVALID,
                 "at most 256 classes, got 300");
    expect_error(affect_svm_train(X, N, 0, y, 3, 1.0, &m, &err), &err, AFFECT_ERR_RANGE,
                 "dimension must be at least 1");
    expect_error(affect_svm_train(X, N, 3000000000u, y, 3, 1.0, &m, &err), &err, AFFECT_ERR_RANGE,
                 "dimension 3000000000 too large (at most 2147483647)");
    expect_error(affect_svm_train(X, 3000000000u, d, y, 3, 1.0, &m, &err), &err, AFFECT_ERR_RANGE,
                 "too many samples: 3000000000 (at most 2147483645)");
    y[5] = 7;
    expect_error(affect_svm_train(X, N, d, y, 3, 1.0, &m, &err), &err, AFFECT_ERR_INVALID,
                 "sample 5: class 7 out of range 0 .. 2");
    y[5] = 1;
    y[2] = 1;
    expect_error(affect_svm_train(X, N, d, y, 3, 1.0, &m, &err), &err, AFFECT_ERR_INVALID,
                 "class 2 has no training sample");
    y[2] = 2;
    expect_error(affect_svm_train(X, N, d, y, 3, -1.0, &m, &err), &err, AFFECT_ERR_INVALID,
                 "C must be a positive finite number, got -1");
    expect_error(affect_svm_train(X, N, d, y, 3, 0.0, &m, &err), &err, AFFECT_ERR_INVALID,
                 "C must be a positive finite number, got 0");
    expect_error(affect_svm_train(X, N, d, y, 3, INFINITY, &m, &err), &err, AFFECT_ERR_INVALID,
                 "C must be a positive finite number, got inf");
    X[3 * d + 17] = NAN;
    expect_error(affect_svm_train(X, N, d, y, 3, 1.0, &m, &err), &err, AFFECT_ERR_INVALID,
                 "sample 3, component 17 is not finite");
    X[3 * d + 17] = 0;
    X[2 * d + 4] = 1e200;
    expect_error(affect_svm_train(X, N, d, y, 3, 1.0, &m, &err), &err, AFFECT_ERR_RANGE,
                 "Gram entry (2, 2) is not finite (the features are too large)");
    X[2 * d + 4] = 0;
    assert_null(m);
    assert_int_equal(affect_svm_train(X, N, d, y, 3, 1.0, &m, &err), AFFECT_OK);
    affect_svm_free(m);
    affect_svm_free(NULL);

    double G[4];
    expect_error(affect_svm_gram(X, 2, 0, G, &err), &err, AFFECT_ERR_RANGE,
                 "dimension must be at least 1");

    double c2, a2;
    static const double cands[2] = {1, 0};
    expect_error(affect_svm_select_c(X, N, d, y, 1, cands, 1, 3, 1, &c2, &a2, &err), &err,
                 AFFECT_ERR_INVALID, "need at least 2 classes");
    expect_error(affect_svm_select_c(X, N, d, y, 3, cands, 0, 3, 1, &c2, &a2, &err), &err,
                 AFFECT_ERR_INVALID, "need at least one candidate C");
    expect_error(affect_svm_select_c(X, N, d, y, 3, cands, 2, 3, 1, &c2, &a2, &err), &err,
                 AFFECT_ERR_INVALID, "candidate 1: C = 0 is not a positive finite number");
    expect_error(affect_svm_select_c(X, N, d, y, 3, cands, 1, 1, 1, &c2, &a2, &err), &err,
                 AFFECT_ERR_INVALID, "need at least 2 folds, got 1");
    X[0] = INFINITY;
    expect_error(affect_svm_select_c(X, N, d, y, 3, cands, 1, 3, 1, &c2, &a2, &err), &err,
                 AFFECT_ERR_INVALID, "sample 0, component 0 is not finite");
}

/* ---- encoding ---- */

typedef struct small {
    double X[15 * 30], Xt[12 * 30];
    uint32_t y[15];
    affect_svm *m;
} small;

/* A three-class model of 15 samples in dimension 30. */
static void small_model(small *s)
{
    affect_rng r;
    affect_rng_seed(&r, 61);
    for (int i = 0; i < 15; i++) {
        s->y[i] = (uint32_t)(i % 3);
        for (int j = 0; j < 30; j++)
            s->X[i * 30 + j] = (j % 3 == (int)s->y[i] ? 1.0 : 0.0) + affect_rng_normal(&r);
    }
    for (int i = 0; i < 12 * 30; i++)
        s->Xt[i] = affect_rng_normal(&r);
    affect_error err;
    assert_int_equal(affect_svm_train(s->X, 15, 30, s->y, 3, 0.5, &s->m, &err), AFFECT_OK);
}

static void test_round_trip(void **state)
{
    (void)state;
    small s;
    small_model(&s);
    affect_bw w;
    affect_bw_init(&w);
    affect_bw_u32(&w, 0xdeadbeef); /* the model sits inside a larger BLOB */
    size_t start = w.len;
    affect_svm_encode(s.m, &w);
    size_t end = w.len;
    affect_bw_u32(&w, 0xfeedface);
    assert_false(w.failed);
    uint32_t l = affect_svm_total_sv(s.m);
    assert_int_equal(end - start,
                     29 + 12 + 4 + 12 + 4 + 4 * l + 4 + 16 * l + 4 + 24 + 4 + 3 * 30 * 8);

    affect_br r;
    affect_br_init(&r, w.data, w.len);
    r.off = start;
    affect_svm *m2 = NULL;
    affect_error err;
    assert_int_equal(affect_svm_decode(&r, &m2, &err), AFFECT_OK);
    assert_int_equal(r.off, end);
    assert_int_equal(affect_svm_n_classes(m2), 3);
    assert_int_equal(affect_svm_dim(m2), 30);
    assert_true(affect_svm_C(m2) == 0.5);
    assert_int_equal(affect_svm_n_train(m2), 15);
    assert_int_equal(affect_svm_total_sv(m2), l);
    assert_memory_equal(affect_svm_sv_indices(m2), affect_svm_sv_indices(s.m), 4 * l);
    for (uint32_t k = 0; k < 3; k++)
        assert_int_equal(affect_svm_n_sv(m2, k), affect_svm_n_sv(s.m, k));
    for (int i = 0; i < 12; i++) {
        double d1[3], d2[3];
        assert_int_equal(affect_svm_predict(s.m, s.Xt + i * 30, d1),
                         affect_svm_predict(m2, s.Xt + i * 30, d2));
        assert_memory_equal(d1, d2, sizeof d1);
    }
    affect_bw w2;
    affect_bw_init(&w2);
    affect_svm_encode(m2, &w2);
    assert_int_equal(w2.len, end - start);
    assert_memory_equal(w2.data, w.data + start, w2.len);
    affect_bw_free(&w2);
    affect_svm_free(m2);

    /* a large trained model survives too */
    enum { N = 24 };
    blobs b = blobs_new(3, D, 1.0, 71);
    uint32_t y[N];
    for (int i = 0; i < N; i++)
        y[i] = (uint32_t)(i % 3);
    double *X = malloc(sizeof(double) * N * D);
    blobs_draw(&b, y, N, 1.0, 72, X);
    affect_svm *big = NULL;
    assert_int_equal(affect_svm_train(X, N, D, y, 3, 1.0, &big, &err), AFFECT_OK);
    affect_bw_free(&w);
    affect_svm_encode(big, &w);
    affect_br_init(&r, w.data, w.len);
    assert_int_equal(affect_svm_decode(&r, &m2, &err), AFFECT_OK);
    for (int i = 0; i < N; i++) {
        double d1[3], d2[3];
        affect_svm_predict(big, X + (size_t)(N - 1 - i) * D, d1);
        affect_svm_predict(m2, X + (size_t)(N - 1 - i) * D, d2);
        assert_memory_equal(d1, d2, sizeof d1);
    }
    for (uint32_t p = 0; p < 3; p++)
        for (uint32_t q = p + 1; q < 3; q++)
            assert_memory_equal(affect_svm_weights(big, p, q, NULL),
                                affect_svm_weights(m2, p, q, NULL), sizeof(double) * D);
    affect_svm_free(m2);
    affect_svm_free(big);
    free(X);
    free(b.mu);
    affect_bw_free(&w);
    affect_svm_free(s.m);
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

static void putf(unsigned char *p, double v)
{
    uint64_t u;
    memcpy(&u, &v, sizeof u);
    put64(p, u);
}

/* Decodes data (size bytes) and expects status and msg, and no model. */
static void expect_decode(const unsigned char *data, size_t size, affect_status status,
                          const char *msg)
{
    affect_br r;
    affect_br_init(&r, data, size);
    affect_svm *m = (affect_svm *)1;
    affect_error err;
    expect_error(affect_svm_decode(&r, &m, &err), &err, status, msg);
    assert_null(m);
}

static void test_corrupt(void **state)
{
    (void)state;
    small s;
    small_model(&s);
    affect_bw w;
    affect_bw_init(&w);
    affect_svm_encode(s.m, &w);
    assert_false(w.failed);
    size_t len = w.len;
    uint32_t l = affect_svm_total_sv(s.m), n0 = affect_svm_n_sv(s.m, 0);
    /* offsets of the fields */
    size_t o_svi = 61, o_rows = o_svi + 4 * l, o_coef = o_rows + 4, o_nrho = o_coef + 16 * l,
           o_rho = o_nrho + 4, o_nw = o_rho + 24, o_w = o_nw + 4;
    assert_int_equal(o_w + 3 * 30 * 8, len);
    unsigned char *b = malloc(len);
    char msg[200];

    /* every cut */
    for (size_t cut = 0; cut < len; cut++) {
        memcpy(b, w.data, cut);
        affect_br r;
        affect_br_init(&r, b, cut);
        affect_svm *m = (affect_svm *)1;
        affect_error err;
        assert_int_equal(affect_svm_decode(&r, &m, &err), AFFECT_ERR_FORMAT);
        assert_null(m);
        assert_true(strncmp(err.msg, "SVM: truncated in ", 18) == 0);
    }
    expect_decode(w.data, 0, AFFECT_ERR_FORMAT, "SVM: truncated in the version (offset 0)");
    expect_decode(w.data, 3, AFFECT_ERR_FORMAT, "SVM: truncated in the class count (offset 1)");
    expect_decode(w.data, 12, AFFECT_ERR_FORMAT, "SVM: truncated in the dimension (offset 5)");
    expect_decode(w.data, 20, AFFECT_ERR_FORMAT, "SVM: truncated in C (offset 13)");
    expect_decode(w.data, 21, AFFECT_ERR_FORMAT, "SVM: truncated in the sample count (offset 21)");
    expect_decode(w.data, 28, AFFECT_ERR_FORMAT,
                  "SVM: truncated in the number of labels (offset 25)");
    expect_decode(w.data, 40, AFFECT_ERR_FORMAT, "SVM: truncated in the labels (offset 29)");
    expect_decode(w.data, 41, AFFECT_ERR_FORMAT,
                  "SVM: truncated in the number of support-vector counts (offset 41)");
    expect_decode(w.data, 56, AFFECT_ERR_FORMAT,
                  "SVM: truncated in the support-vector counts (offset 45)");
    expect_decode(w.data, 60, AFFECT_ERR_FORMAT,
                  "SVM: truncated in the total of support vectors (offset 57)");
    snprintf(msg, sizeof msg, "SVM: truncated in the support-vector indices (offset %zu)", o_svi);
    expect_decode(w.data, o_rows - 1, AFFECT_ERR_FORMAT, msg);
    snprintf(msg, sizeof msg, "SVM: truncated in the number of coefficient rows (offset %zu)",
             o_rows);
    expect_decode(w.data, o_rows, AFFECT_ERR_FORMAT, msg);
    snprintf(msg, sizeof msg, "SVM: truncated in the coefficients (offset %zu)", o_coef);
    expect_decode(w.data, o_nrho - 1, AFFECT_ERR_FORMAT, msg);
    snprintf(msg, sizeof msg, "SVM: truncated in the number of rho values (offset %zu)", o_nrho);
    expect_decode(w.data, o_nrho + 3, AFFECT_ERR_FORMAT, msg);
    snprintf(msg, sizeof msg, "SVM: truncated in the rho values (offset %zu)", o_rho);
    expect_decode(w.data, o_rho + 8, AFFECT_ERR_FORMAT, msg);
    snprintf(msg, sizeof msg, "SVM: truncated in the number of weight vectors (offset %zu)", o_nw);
    expect_decode(w.data, o_nw, AFFECT_ERR_FORMAT, msg);
    snprintf(msg, sizeof msg, "SVM: truncated in the weights (offset %zu)", o_w);
    expect_decode(w.data, len - 1, AFFECT_ERR_FORMAT, msg);

/* b = the encoding with one change; decoding it must fail with msg. */
#define CORRUPT(change, message)                                                                   \
    do {                                                                                           \
        memcpy(b, w.data, len);                                                                    \
        change;                                                                                    \
        expect_decode(b, len, AFFECT_ERR_FORMAT, message);                                         \
    } while (0)

    CORRUPT(b[0] = 4, "SVM: unknown format version 4 (this build reads 1 .. 3)");
    CORRUPT(b[0] = 0, "SVM: unknown format version 0 (this build reads 1 .. 3)");
    CORRUPT(put32(b + 1, 1), "SVM: class count 1 out of range 2 .. 256 (offset 1)");
    CORRUPT(put32(b + 1, 257), "SVM: class count 257 out of range 2 .. 256 (offset 1)");
    CORRUPT(put64(b + 5, 0), "SVM: dimension 0 out of range 1 .. 2147483647 (offset 5)");
    CORRUPT(put64(b + 5, 1ull << 40),
            "SVM: dimension 1099511627776 out of range 1 .. 2147483647 (offset 5)");
    CORRUPT(putf(b + 13, -1), "SVM: C = -1 is not a positive finite number (offset 13)");
    CORRUPT(putf(b + 13, 0), "SVM: C = 0 is not a positive finite number (offset 13)");
    CORRUPT(putf(b + 13, INFINITY), "SVM: C = inf is not a positive finite number (offset 13)");
    CORRUPT(put32(b + 21, 2), "SVM: sample count 2 out of range 3 .. 2147483645 (offset 21)");
    CORRUPT(put32(b + 25, 2), "SVM: 3 classes but 2 labels (offset 25)");
    CORRUPT(put32(b + 29, 1), "SVM: label 1 at position 0, expected 0 (offset 29)");
    CORRUPT(put32(b + 37, 1), "SVM: label 1 at position 2, expected 2 (offset 37)");
    CORRUPT(put32(b + 41, 7), "SVM: 3 classes but 7 support-vector counts (offset 41)");
    snprintf(msg, sizeof msg,
             "SVM: support-vector counts sum to %u but the total is %u (offset 57)", l + 1, l);
    CORRUPT(put32(b + 45, n0 + 1), msg);
    snprintf(msg, sizeof msg,
             "SVM: support-vector counts sum to %llu but the total is %u (offset 57)",
             (unsigned long long)l - n0 + 0xffffffffull, l);
    CORRUPT(put32(b + 45, 0xffffffffu), msg);
    CORRUPT((put32(b + 45, n0 + 15 - l + 1), put32(b + 57, 16)),
            "SVM: 16 support vectors but 15 training samples (offset 57)");
    CORRUPT(put32(b + o_svi, 15),
            "SVM: support vector 0 has training index 15, not below 15 (offset 61)");
    assert_true(n0 >= 2);
    {
        uint32_t first = (uint32_t)w.data[o_svi] | (uint32_t)w.data[o_svi + 1] << 8 |
                         (uint32_t)w.data[o_svi + 2] << 16 | (uint32_t)w.data[o_svi + 3] << 24;
        snprintf(msg, sizeof msg,
                 "SVM: support vector 1 has training index %u, not above the previous %u of its "
                 "class (offset 65)",
                 first, first);
        CORRUPT(put32(b + o_svi + 4, first), msg);
    }
    snprintf(msg, sizeof msg, "SVM: 3 classes but 3 coefficient rows (offset %zu)", o_rows);
    CORRUPT(put32(b + o_rows, 3), msg);
    snprintf(msg, sizeof msg, "SVM: non-finite value in the coefficients (offset %zu)",
             o_coef + 8 * 5);
    CORRUPT(putf(b + o_coef + 8 * 5, NAN), msg);
    snprintf(msg, sizeof msg, "SVM: 3 classes but 2 rho values (offset %zu)", o_nrho);
    CORRUPT(put32(b + o_nrho, 2), msg);
    snprintf(msg, sizeof msg, "SVM: non-finite value in the rho values (offset %zu)", o_rho + 16);
    CORRUPT(putf(b + o_rho + 16, -INFINITY), msg);
    snprintf(msg, sizeof msg, "SVM: 3 classes but 4 weight vectors (offset %zu)", o_nw);
    CORRUPT(put32(b + o_nw, 4), msg);
    snprintf(msg, sizeof msg, "SVM: non-finite value in the weights (offset %zu)", len - 8);
    CORRUPT(putf(b + len - 8, NAN), msg);
#undef CORRUPT

    /* huge counts never allocate: a dimension of 2^31 − 1 with a short buffer */
    memcpy(b, w.data, len);
    put64(b + 5, 2147483647u);
    snprintf(msg, sizeof msg, "SVM: truncated in the weights (offset %zu)", o_w);
    expect_decode(b, len, AFFECT_ERR_FORMAT, msg);

    /* every byte flipped: an error or a model, never a crash */
    for (size_t i = 0; i < len; i++) {
        memcpy(b, w.data, len);
        b[i] ^= 0xa5;
        affect_br r;
        affect_br_init(&r, b, len);
        affect_svm *m = NULL;
        affect_error err;
        affect_status st = affect_svm_decode(&r, &m, &err);
        if (st == AFFECT_OK) {
            assert_non_null(m);
            double x[30] = {0};
            assert_true(affect_svm_predict(m, x, NULL) < 3);
            affect_svm_free(m);
        } else {
            assert_int_equal(st, AFFECT_ERR_FORMAT);
            assert_null(m);
            assert_true(strncmp(err.msg, "SVM: ", 5) == 0);
        }
    }
    free(b);
    affect_bw_free(&w);
    affect_svm_free(s.m);
}

/* ---- out of memory ---- */

typedef struct oom_ctx {
    small *s;
    affect_svm *m;
    affect_bw w;
    double best_c, best_acc;
    uint32_t folds[15];
} oom_ctx;

static affect_status oom_train(void *ctx, affect_error *err)
{
    oom_ctx *c = ctx;
    return affect_svm_train(c->s->X, 15, 30, c->s->y, 3, 0.5, &c->m, err);
}

static void oom_train_finish(void *ctx, affect_status st)
{
    oom_ctx *c = ctx;
    if (st == AFFECT_OK) {
        assert_non_null(c->m);
        assert_int_equal(affect_svm_total_sv(c->m), affect_svm_total_sv(c->s->m));
    } else {
        assert_null(c->m);
    }
    affect_svm_free(c->m);
    c->m = NULL;
}

static affect_status oom_encode(void *ctx, affect_error *err)
{
    oom_ctx *c = ctx;
    affect_bw_init(&c->w);
    affect_svm_encode(c->s->m, &c->w);
    return c->w.failed ? affect_nomem(err) : AFFECT_OK;
}

static void oom_encode_finish(void *ctx, affect_status st)
{
    oom_ctx *c = ctx;
    affect_bw_free(&c->w);
}

static affect_status oom_decode(void *ctx, affect_error *err)
{
    oom_ctx *c = ctx;
    affect_br r;
    affect_br_init(&r, c->w.data, c->w.len);
    return affect_svm_decode(&r, &c->m, err);
}

static affect_status oom_select(void *ctx, affect_error *err)
{
    oom_ctx *c = ctx;
    static const double cands[2] = {0.1, 10};
    return affect_svm_select_c(c->s->X, 15, 30, c->s->y, 3, cands, 2, 3, 4, &c->best_c,
                               &c->best_acc, err);
}

static affect_status oom_folds(void *ctx, affect_error *err)
{
    oom_ctx *c = ctx;
    return affect_stratified_folds(c->s->y, 15, 3, 4, 8, c->folds, err);
}

static void test_out_of_memory(void **state)
{
    (void)state;
    small s;
    small_model(&s);
    oom_ctx c;
    memset(&c, 0, sizeof c);
    c.s = &s;
    assert_true(tu_oom_sweep(oom_train, &c, oom_train_finish, NULL) >= 8);
    assert_true(tu_oom_sweep(oom_encode, &c, oom_encode_finish, NULL) >= 1);
    affect_bw_init(&c.w);
    affect_svm_encode(s.m, &c.w);
    assert_true(tu_oom_sweep(oom_decode, &c, oom_train_finish, NULL) >= 7);
    affect_bw_free(&c.w);
    assert_true(tu_oom_sweep(oom_select, &c, NULL, NULL) >= 10);
    assert_true(tu_oom_sweep(oom_folds, &c, NULL, NULL) == 2);
    affect_svm_free(s.m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_separable),    cmocka_unit_test(test_matches_libsvm),
        cmocka_unit_test(test_vote),         cmocka_unit_test(test_vote_counts),
        cmocka_unit_test(test_vote_trained), cmocka_unit_test(test_folds),
        cmocka_unit_test(test_select_c),     cmocka_unit_test(test_gram_blocks),
        cmocka_unit_test(test_errors),       cmocka_unit_test(test_round_trip),
        cmocka_unit_test(test_corrupt),      cmocka_unit_test(test_out_of_memory),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
