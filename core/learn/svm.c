/*
 * svm.c — linear multi-class SVM on libsvm for very long, few vectors (see affect/svm.h).
 *
 * Usage: see the block at the top of affect/svm.h (compiled by the style/header-usage test).
 *
 * How it works. Training computes G = X Xᵀ once (cblas_dsyrk, mirrored) and gives libsvm a
 * C-SVC problem with kernel_type PRECOMPUTED: problem row r (a sample, the samples grouped by
 * class in class order and in their original order within a class) is the node array
 *     {0, r+1}, {1, G[r][0]}, …, {m, G[r][m−1]}, {−1, 0}
 * in problem order, where r+1 is the sample's serial number: libsvm's kernel value K(r, s) is
 * x_r[serial of s].value. Labels are the class indices, so libsvm's class order (first
 * appearance) is ours. From the trained model we copy nSV, rho, sv_coef and the support
 * vectors' training indices (svm_get_sv_indices, 1-based problem rows, mapped to 0-based
 * sample indices), and build the primal weights of the linear kernel exactly as
 * svm_predict_values combines kernel values: for the pair (i, j), i < j,
 *     w_ij = Σ_{SV s of class i} sv_coef[j−1][s] x_s + Σ_{SV s of class j} sv_coef[i][s] x_s,
 * accumulated in that order; dec_ij(x) = w_ij·x − rho_ij. The libsvm model is then freed: it
 * points into our problem's node arrays and owns memory from the C library's malloc.
 *
 * Cross-validation trains on the rows and columns of G of the training folds (one problem
 * per fold, reused across the candidates of C) and predicts the held-out samples in the dual,
 * Σ coef · G[t][s] − rho with libsvm's layout and vote, so X is touched only once.
 *
 * The encoding is the layout documented in affect/svm.h, written and read field by field
 * through util/bytes.h.
 */
#include "affect/svm.h"

#include <cblas.h>
#include <float.h>
#include <inttypes.h>
#include <math.h>
#include <string.h>
#include <threads.h>
#include <svm.h>

#include "util/quant.h"
#include "util/rng.h"
#include "util/internal.h"

struct affect_svm {
    uint32_t c;       /* classes */
    uint32_t n_train; /* samples of the training set (of the whole data set in a CV model) */
    uint32_t l;       /* total support vectors */
    size_t d;         /* dimension */
    double C;
    uint32_t *label;    /* c: libsvm's class k is our class label[k] */
    uint32_t *nsv;      /* c: support vectors per libsvm class */
    uint32_t *sv_index; /* l: 0-based sample index of each support vector */
    double *sv_coef;    /* (c − 1) × l, libsvm's sv_coef row after row */
    double *rho;        /* c(c − 1)/2 */
    double *w;          /* c(c − 1)/2 × d; NULL in cross-validation models */
    bool f32;           /* every weight is a float32 value: encoded as version 2 */
    bool q4;            /* every weight vector is in its 4-bit form: encoded as version 3 */
};

/* A libsvm problem over a subset of the samples, built from the Gram matrix. */
typedef struct problem {
    struct svm_problem prob;
    struct svm_node *nodes; /* m × (m + 2) */
    struct svm_node **rows; /* m */
    double *labels;         /* m */
    uint32_t *ids;          /* m: problem row → sample index */
    size_t m;
    uint32_t n_classes; /* classes present */
} problem;

static size_t n_pairs(uint32_t c)
{
    return (size_t)c * (c - 1) / 2;
}

static void quiet(const char *s)
{
    (void)s;
}

static once_flag quiet_once = ONCE_FLAG_INIT;

static void install_quiet(void)
{
    svm_set_print_string_function(quiet);
}

void affect_svm_free(affect_svm *m)
{
    if (!m)
        return;
    affect_free(m->label);
    affect_free(m->nsv);
    affect_free(m->sv_index);
    affect_free(m->sv_coef);
    affect_free(m->rho);
    affect_free(m->w);
    affect_free(m);
}

/* ---- checks ---- */

static affect_status check_sizes(size_t n, size_t d, affect_error *err)
{
    if (d == 0)
        return affect_fail(err, AFFECT_ERR_RANGE, "dimension must be at least 1");
    if (d > AFFECT_SVM_MAX_DIM)
        return affect_fail(err, AFFECT_ERR_RANGE, "dimension %zu too large (at most %u)", d,
                           AFFECT_SVM_MAX_DIM);
    if (n > AFFECT_SVM_MAX_SAMPLES)
        return affect_fail(err, AFFECT_ERR_RANGE, "too many samples: %zu (at most %u)", n,
                           AFFECT_SVM_MAX_SAMPLES);
    return AFFECT_OK;
}

/* Classes, sizes, labels in range and every class present. */
static affect_status check_data(size_t n, size_t d, const uint32_t *y, uint32_t c,
                                affect_error *err)
{
    if (c < 2)
        return affect_fail(err, AFFECT_ERR_INVALID, "need at least 2 classes");
    if (c > AFFECT_SVM_MAX_CLASSES)
        return affect_fail(err, AFFECT_ERR_INVALID, "at most %u classes, got %u",
                           AFFECT_SVM_MAX_CLASSES, c);
    affect_status st = check_sizes(n, d, err);
    if (st != AFFECT_OK)
        return st;
    bool seen[AFFECT_SVM_MAX_CLASSES] = {false};
    for (size_t i = 0; i < n; i++) {
        if (y[i] >= c)
            return affect_fail(err, AFFECT_ERR_INVALID, "sample %zu: class %u out of range 0 .. %u",
                               i, y[i], c - 1);
        seen[y[i]] = true;
    }
    for (uint32_t k = 0; k < c; k++)
        if (!seen[k])
            return affect_fail(err, AFFECT_ERR_INVALID, "class %u has no training sample", k);
    return AFFECT_OK;
}

static affect_status check_finite(const double *X, size_t n, size_t d, affect_error *err)
{
    for (size_t i = 0; i < n; i++)
        for (size_t j = 0; j < d; j++)
            if (!isfinite(X[i * d + j]))
                return affect_fail(err, AFFECT_ERR_INVALID,
                                   "sample %zu, component %zu is not finite", i, j);
    return AFFECT_OK;
}

static bool positive_finite(double v)
{
    return isfinite(v) && v > 0;
}

/* ---- Gram matrix ---- */

affect_status affect_svm_gram(const double *X, size_t n, size_t d, double *G, affect_error *err)
{
    affect_status st = check_sizes(n, d, err);
    if (st != AFFECT_OK || n == 0)
        return st;
    AFFECT_BLAS(cblas_dsyrk(CblasRowMajor, CblasUpper, CblasNoTrans, (int)n, (int)d, 1.0, X, (int)d,
                            0.0, G, (int)n));
    for (size_t i = 1; i < n; i++)
        for (size_t j = 0; j < i; j++)
            G[i * n + j] = G[j * n + i];
    return AFFECT_OK;
}

/* A new Gram matrix of X (sizes already checked), with every entry finite. */
static affect_status gram_new(const double *X, size_t n, size_t d, double **out, affect_error *err)
{
    size_t nn;
    *out = NULL;
    if (!affect_mul_size(n, n, &nn))
        return affect_fail(err, AFFECT_ERR_RANGE, "too many samples: %zu", n);
    double *G = affect_malloc_array(nn, sizeof *G);
    if (!G)
        return affect_nomem_of(err, nn, sizeof *G, "the %zu x %zu Gram matrix", n, n);
    affect_status st = affect_svm_gram(X, n, d, G, err);
    if (st != AFFECT_OK) {
        affect_free(G);
        return st;
    }
    for (size_t i = 0; i < n; i++)
        for (size_t j = i; j < n; j++)
            if (!isfinite(G[i * n + j])) {
                affect_free(G);
                return affect_fail(
                    err, AFFECT_ERR_RANGE,
                    "Gram entry (%zu, %zu) is not finite (the features are too large)", i, j);
            }
    *out = G;
    return AFFECT_OK;
}

/* ---- the libsvm problem ---- */

static void problem_free(problem *p)
{
    affect_free(p->nodes);
    affect_free(p->rows);
    affect_free(p->labels);
    affect_free(p->ids);
    memset(p, 0, sizeof *p);
}

/* The problem of the samples i with fold_of[i] != skip (all of them when fold_of is NULL),
 * grouped by class in class order, in their original order within a class. */
static affect_status problem_build(const double *G, size_t n, const uint32_t *y, uint32_t c,
                                   const uint32_t *fold_of, uint32_t skip, problem *p,
                                   affect_error *err)
{
    memset(p, 0, sizeof *p);
    size_t m = 0, stride, count;
    for (size_t i = 0; i < n; i++)
        if (!fold_of || fold_of[i] != skip)
            m++;
    if (!affect_add_size(m, 2, &stride) || !affect_mul_size(m, stride, &count))
        return affect_fail(err, AFFECT_ERR_RANGE, "too many samples: %zu", m);
    p->ids = affect_malloc_array(m, sizeof *p->ids);
    p->labels = affect_malloc_array(m, sizeof *p->labels);
    p->rows = affect_malloc_array(m, sizeof *p->rows);
    p->nodes = affect_malloc_array(count, sizeof *p->nodes);
    if (!p->ids || !p->labels || !p->rows || !p->nodes) {
        bool nodes = !p->nodes;
        problem_free(p);
        if (nodes)
            return affect_nomem_of(err, count, sizeof *p->nodes,
                                   "libsvm's problem of %zu samples (%zu kernel entries)", m,
                                   count);
        return affect_nomem(err);
    }
    size_t r = 0;
    for (uint32_t k = 0; k < c; k++) {
        size_t r0 = r;
        for (size_t i = 0; i < n; i++)
            if (y[i] == k && (!fold_of || fold_of[i] != skip))
                p->ids[r++] = (uint32_t)i;
        if (r > r0)
            p->n_classes++;
    }
    for (r = 0; r < m; r++) {
        struct svm_node *row = p->nodes + r * stride;
        const double *g = G + (size_t)p->ids[r] * n;
        row[0].index = 0;
        row[0].value = (double)(r + 1);
        for (size_t s = 0; s < m; s++) {
            row[s + 1].index = (int)(s + 1);
            row[s + 1].value = g[p->ids[s]];
        }
        row[m + 1].index = -1;
        row[m + 1].value = 0;
        p->rows[r] = row;
        p->labels[r] = (double)y[p->ids[r]];
    }
    p->m = m;
    p->prob.l = (int)m;
    p->prob.y = p->labels;
    p->prob.x = p->rows;
    return AFFECT_OK;
}

/* Trains libsvm on p with penalty C; *out is libsvm's model (free with
 * svm_free_and_destroy_model, before p). */
static affect_status fit(const problem *p, double C, struct svm_model **out, affect_error *err)
{
    struct svm_parameter param;
    memset(&param, 0, sizeof param);
    param.svm_type = C_SVC;
    param.kernel_type = PRECOMPUTED;
    param.degree = 3;
    param.cache_size = AFFECT_SVM_CACHE_MB;
    param.eps = AFFECT_SVM_EPS;
    param.C = C;
    param.nr_weight = 0;
    param.weight_label = NULL;
    param.weight = NULL;
    param.nu = 0.5;
    param.p = 0.1;
    param.shrinking = 1;
    param.probability = 0;
    *out = NULL;
    const char *msg = svm_check_parameter(&p->prob, &param);
    if (msg)
        return affect_fail(err, AFFECT_ERR_INVALID, "libsvm rejected the parameters: %s", msg);
    call_once(&quiet_once, install_quiet); /* once per process: no concurrent writes */
    *out = svm_train(&p->prob, &param);
    if (!*out)
        return affect_nomem(err);
    return AFFECT_OK;
}

/* Copies the description of libsvm's model sm, trained on p, into a new model without
 * weights. */
static affect_status extract(const struct svm_model *sm, const problem *p, size_t d, double C,
                             affect_svm **out, affect_error *err)
{
    affect_status st = AFFECT_OK;
    int *svi = NULL;
    int labels[AFFECT_SVM_MAX_CLASSES];
    uint32_t c = (uint32_t)svm_get_nr_class(sm);
    uint32_t l = (uint32_t)svm_get_nr_sv(sm);
    /* 2 ≤ c ≤ the classes we gave libsvm, l ≤ the rows of the problem: no overflow */
    size_t n_coef = (size_t)(c - 1) * l;
    *out = NULL;
    affect_svm *m = affect_calloc(1, sizeof *m);
    if (!m)
        return affect_nomem(err);
    m->c = c;
    m->n_train = (uint32_t)p->m;
    m->l = l;
    m->d = d;
    m->C = C;
    m->label = affect_malloc_array(c, sizeof *m->label);
    m->nsv = affect_malloc_array(c, sizeof *m->nsv);
    m->sv_index = affect_malloc_array(l, sizeof *m->sv_index);
    m->sv_coef = affect_malloc_array(n_coef, sizeof *m->sv_coef);
    m->rho = affect_malloc_array(n_pairs(c), sizeof *m->rho);
    svi = affect_malloc_array(l, sizeof *svi);
    if (!m->label || !m->nsv || !m->sv_index || !m->sv_coef || !m->rho || !svi) {
        st = affect_nomem(err);
        goto cleanup;
    }
    svm_get_labels(sm, labels);
    svm_get_sv_indices(sm, svi);
    for (uint32_t k = 0; k < c; k++) {
        m->label[k] = (uint32_t)labels[k];
        m->nsv[k] = (uint32_t)sm->nSV[k];
    }
    for (uint32_t i = 0; i < l; i++)
        m->sv_index[i] = p->ids[svi[i] - 1];
    for (uint32_t j = 0; j + 1 < c; j++)
        for (uint32_t i = 0; i < l; i++)
            m->sv_coef[(size_t)j * l + i] = sm->sv_coef[j][i];
    for (size_t k = 0; k < n_pairs(c); k++)
        m->rho[k] = sm->rho[k];
    *out = m;
    m = NULL;
cleanup:
    affect_free(svi);
    affect_svm_free(m);
    return st;
}

/* First offset of each class's support vectors. */
static void sv_starts(const affect_svm *m, uint32_t *start)
{
    start[0] = 0;
    for (uint32_t k = 1; k < m->c; k++)
        start[k] = start[k - 1] + m->nsv[k - 1];
}

/* The primal weights of the linear kernel, from the support vectors' rows of X: every column at
 * once (affect_svm_add_rows). */
static affect_status primal(affect_svm *m, const double *X, affect_error *err)
{
    return affect_svm_add_rows(m, X, m->d, 0, err);
}

/* ---- training and prediction ---- */

/* The dual part of training: libsvm on the Gram matrix G, a model without weights. */
static affect_status train_dual(const double *G, size_t n, size_t d, const uint32_t *y, uint32_t c,
                                double C, affect_svm **out, affect_error *err)
{
    affect_status st;
    problem p;
    struct svm_model *sm = NULL;
    affect_svm *m = NULL;
    memset(&p, 0, sizeof p);
    *out = NULL;
    if ((st = problem_build(G, n, y, c, NULL, 0, &p, err)) != AFFECT_OK)
        goto cleanup;
    if ((st = fit(&p, C, &sm, err)) != AFFECT_OK)
        goto cleanup;
    if ((uint32_t)svm_get_nr_class(sm) != c) {
        st = affect_fail(err, AFFECT_ERR_RANGE, "libsvm returned %d classes, expected %u",
                         svm_get_nr_class(sm), c);
        goto cleanup;
    }
    if ((st = extract(sm, &p, d, C, &m, err)) != AFFECT_OK)
        goto cleanup;
    for (uint32_t k = 0; k < c; k++)
        if (m->label[k] != k) {
            st = affect_fail(err, AFFECT_ERR_RANGE,
                             "libsvm reordered the classes (class %u at position %u)", m->label[k],
                             k);
            goto cleanup;
        }
    *out = m;
    m = NULL;
cleanup:
    if (sm)
        svm_free_and_destroy_model(&sm);
    problem_free(&p);
    affect_svm_free(m);
    return st;
}

affect_status affect_svm_train(const double *X, size_t n, size_t d, const uint32_t *y, uint32_t c,
                               double C, affect_svm **out, affect_error *err)
{
    affect_status st;
    double *G = NULL;
    *out = NULL;
    if ((st = check_data(n, d, y, c, err)) != AFFECT_OK)
        return st;
    if (!positive_finite(C))
        return affect_fail(err, AFFECT_ERR_INVALID, "C must be a positive finite number, got %g",
                           C);
    if ((st = check_finite(X, n, d, err)) != AFFECT_OK)
        return st;
    if ((st = gram_new(X, n, d, &G, err)) != AFFECT_OK)
        return st;
    affect_svm *m = NULL;
    st = train_dual(G, n, d, y, c, C, &m, err);
    affect_free(G);
    if (st == AFFECT_OK && (st = primal(m, X, err)) != AFFECT_OK) {
        affect_svm_free(m);
        m = NULL;
    }
    *out = m;
    return st;
}

/* Every entry of the upper triangle of G finite. */
static affect_status check_gram(const double *G, size_t n, affect_error *err)
{
    for (size_t i = 0; i < n; i++)
        for (size_t j = i; j < n; j++)
            if (!isfinite(G[i * n + j]))
                return affect_fail(
                    err, AFFECT_ERR_RANGE,
                    "Gram entry (%zu, %zu) is not finite (the features are too large)", i, j);
    return AFFECT_OK;
}

affect_status affect_svm_train_gram(const double *G, size_t n, size_t d, const uint32_t *y,
                                    uint32_t c, double C, affect_svm **out, affect_error *err)
{
    affect_status st;
    *out = NULL;
    if ((st = check_data(n, d, y, c, err)) != AFFECT_OK)
        return st;
    if (!positive_finite(C))
        return affect_fail(err, AFFECT_ERR_INVALID, "C must be a positive finite number, got %g",
                           C);
    if ((st = check_gram(G, n, err)) != AFFECT_OK)
        return st;
    return train_dual(G, n, d, y, c, C, out, err);
}

affect_status affect_svm_add_rows(affect_svm *m, const double *B, size_t b, size_t col0,
                                  affect_error *err)
{
    size_t d = m->d, P = n_pairs(m->c), total;
    if (b == 0 || col0 > d || b > d - col0)
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "columns %zu .. %zu are outside the model's %zu dimensions", col0,
                           col0 + b, d);
    if (!m->w) {
        if (!affect_mul_size(P, d, &total))
            return affect_fail(err, AFFECT_ERR_RANGE, "weights of %zu pairs x %zu too large", P, d);
        m->w = affect_calloc(total, sizeof *m->w);
        if (!m->w)
            return affect_nomem_of(err, total, sizeof *m->w, "the SVM's %zu x %zu weights", P, d);
    }
    uint32_t start[AFFECT_SVM_MAX_CLASSES];
    sv_starts(m, start);
    size_t p = 0;
    for (uint32_t i = 0; i < m->c; i++)
        for (uint32_t j = i + 1; j < m->c; j++, p++) {
            double *w = m->w + p * d + col0;
            const double *coef1 = m->sv_coef + (size_t)(j - 1) * m->l;
            const double *coef2 = m->sv_coef + (size_t)i * m->l;
            for (uint32_t k = 0; k < m->nsv[i]; k++) {
                uint32_t s = start[i] + k;
                const double *x = B + (size_t)m->sv_index[s] * b;
                for (size_t t = 0; t < b; t++)
                    w[t] += coef1[s] * x[t];
            }
            for (uint32_t k = 0; k < m->nsv[j]; k++) {
                uint32_t s = start[j] + k;
                const double *x = B + (size_t)m->sv_index[s] * b;
                for (size_t t = 0; t < b; t++)
                    w[t] += coef2[s] * x[t];
            }
        }
    return AFFECT_OK;
}

/* ---- the one-vs-one vote ---- */

/* The decision value of the pair number p, (i, j) with i < j, for the sample of ctx. */
typedef double (*pair_value)(const void *ctx, size_t p, uint32_t i, uint32_t j);

/* libsvm's vote (svm_predict_values) over the pairs of c classes, 1 ≤ c ≤ AFFECT_SVM_MAX_CLASSES,
 * in pair order: value(ctx, p, i, j) > 0 is a vote for i, anything else (NaN too) a vote for j;
 * the class with the most votes wins, the first in class order among equals. The votes (c
 * counts) go to votes when it is not NULL. The one place where votes are counted: prediction in
 * the primal and in the dual, and affect_svm_vote on decision values already computed. */
static uint32_t vote(uint32_t c, pair_value value, const void *ctx, uint32_t *votes)
{
    uint32_t own[AFFECT_SVM_MAX_CLASSES];
    uint32_t *v = votes ? votes : own;
    memset(v, 0, c * sizeof *v);
    size_t p = 0;
    for (uint32_t i = 0; i < c; i++)
        for (uint32_t j = i + 1; j < c; j++, p++)
            v[value(ctx, p, i, j) > 0 ? i : j]++;
    uint32_t best = 0;
    for (uint32_t k = 1; k < c; k++)
        if (v[k] > v[best])
            best = k;
    return best;
}

static double stored_value(const void *ctx, size_t p, uint32_t i, uint32_t j)
{
    (void)i;
    (void)j;
    return ((const double *)ctx)[p];
}

uint32_t affect_svm_vote(const double *dec, uint32_t c, uint32_t *votes)
{
    if (c == 0 || c > AFFECT_SVM_MAX_CLASSES)
        return UINT32_MAX;
    return vote(c, stored_value, dec, votes);
}

/* ---- prediction ---- */

typedef struct primal_sample {
    const affect_svm *m;
    const double *x;
    double *dec; /* the decision values, or NULL */
} primal_sample;

/* dec_ij(x) = w_ij·x − rho_ij, kept in dec[p] when asked for. */
static double primal_value(const void *ctx, size_t p, uint32_t i, uint32_t j)
{
    (void)i;
    (void)j;
    const primal_sample *q = ctx;
    size_t d = q->m->d;
    const double *w = q->m->w + p * d;
    double s = 0;
    for (size_t t = 0; t < d; t++)
        s += w[t] * q->x[t];
    s -= q->m->rho[p];
    if (q->dec)
        q->dec[p] = s;
    return s;
}

uint32_t affect_svm_predict(const affect_svm *m, const double *x, double *dec)
{
    primal_sample q = {m, x, dec};
    return m->label[vote(m->c, primal_value, &q, NULL)];
}

typedef struct dual_sample {
    const affect_svm *m;
    const double *g; /* the kernel values of the sample with every training sample */
    uint32_t start[AFFECT_SVM_MAX_CLASSES];
} dual_sample;

/* svm_predict_values's sum for the pair (i, j): Σ coef · g over both classes' support vectors,
 * class i's first, minus rho. */
static double dual_value(const void *ctx, size_t p, uint32_t i, uint32_t j)
{
    const dual_sample *q = ctx;
    const affect_svm *m = q->m;
    const double *coef1 = m->sv_coef + (size_t)(j - 1) * m->l;
    const double *coef2 = m->sv_coef + (size_t)i * m->l;
    double s = 0;
    for (uint32_t k = 0; k < m->nsv[i]; k++)
        s += coef1[q->start[i] + k] * q->g[m->sv_index[q->start[i] + k]];
    for (uint32_t k = 0; k < m->nsv[j]; k++)
        s += coef2[q->start[j] + k] * q->g[m->sv_index[q->start[j] + k]];
    return s - m->rho[p];
}

/* The prediction of a model without weights for the sample whose kernel values with every
 * sample are g (a row of the Gram matrix): svm_predict_values's sums and vote. */
static uint32_t dual_predict(const affect_svm *m, const double *g)
{
    dual_sample q = {.m = m, .g = g};
    sv_starts(m, q.start);
    return m->label[vote(m->c, dual_value, &q, NULL)];
}

uint32_t affect_svm_predict_gram(const affect_svm *m, const double *g)
{
    return dual_predict(m, g);
}

/* ---- accessors ---- */

uint32_t affect_svm_n_classes(const affect_svm *m)
{
    return m->c;
}

size_t affect_svm_dim(const affect_svm *m)
{
    return m->d;
}

double affect_svm_C(const affect_svm *m)
{
    return m->C;
}

uint32_t affect_svm_n_train(const affect_svm *m)
{
    return m->n_train;
}

uint32_t affect_svm_total_sv(const affect_svm *m)
{
    return m->l;
}

uint32_t affect_svm_n_sv(const affect_svm *m, uint32_t k)
{
    return k < m->c ? m->nsv[k] : 0;
}

const uint32_t *affect_svm_sv_indices(const affect_svm *m)
{
    return m->sv_index;
}

const double *affect_svm_sv_coef(const affect_svm *m, uint32_t j)
{
    return j + 1 < m->c ? m->sv_coef + (size_t)j * m->l : NULL;
}

uint32_t affect_svm_pair_index(const affect_svm *m, uint32_t p, uint32_t q)
{
    if (p >= q || q >= m->c)
        return UINT32_MAX;
    return (uint32_t)((size_t)p * (2 * (size_t)m->c - p - 1) / 2 + (q - p - 1));
}

const double *affect_svm_weights(const affect_svm *m, uint32_t p, uint32_t q, double *rho)
{
    uint32_t k = affect_svm_pair_index(m, p, q);
    if (k == UINT32_MAX)
        return NULL;
    if (rho)
        *rho = m->rho[k];
    return m->w + (size_t)k * m->d;
}

/* ---- cross-validation ---- */

/* Uniform in 0 .. bound−1 (bound ≥ 1), without modulo bias: draws below 2^64 mod bound are
 * rejected. */
static uint64_t rng_below(affect_rng *r, uint64_t bound)
{
    uint64_t threshold = (0 - bound) % bound;
    for (;;) {
        uint64_t x = affect_rng_next(r);
        if (x >= threshold)
            return x % bound;
    }
}

affect_status affect_stratified_folds(const uint32_t *y, size_t n, uint32_t c, uint32_t k,
                                      uint64_t seed, uint32_t *fold_of, affect_error *err)
{
    if (k < 2)
        return affect_fail(err, AFFECT_ERR_INVALID, "need at least 2 folds, got %u", k);
    if (c == 0)
        return affect_fail(err, AFFECT_ERR_INVALID, "need at least 1 class");
    if (n > AFFECT_SVM_MAX_SAMPLES)
        return affect_fail(err, AFFECT_ERR_RANGE, "too many samples: %zu (at most %u)", n,
                           AFFECT_SVM_MAX_SAMPLES);
    for (size_t i = 0; i < n; i++)
        if (y[i] >= c)
            return affect_fail(err, AFFECT_ERR_INVALID, "sample %zu: class %u out of range 0 .. %u",
                               i, y[i], c - 1);
    if (n == 0)
        return AFFECT_OK;
    size_t *start = affect_calloc((size_t)c + 1, sizeof *start);
    uint32_t *order = affect_malloc_array(n, sizeof *order);
    if (!start || !order) {
        affect_free(start);
        affect_free(order);
        return affect_nomem(err);
    }
    /* counting sort by class, stable */
    for (size_t i = 0; i < n; i++)
        start[y[i] + 1]++;
    for (uint32_t j = 0; j < c; j++)
        start[j + 1] += start[j];
    for (size_t i = 0; i < n; i++)
        order[start[y[i]]++] = (uint32_t)i;
    /* start[j] is now the end of class j's run */
    affect_rng rng;
    affect_rng_seed(&rng, seed);
    size_t begin = 0;
    for (uint32_t j = 0; j < c; j++) {
        size_t end = start[j];
        for (size_t i = end - begin; i > 1; i--) {
            size_t a = begin + i - 1, b = begin + (size_t)rng_below(&rng, i);
            uint32_t t = order[a];
            order[a] = order[b];
            order[b] = t;
        }
        begin = end;
    }
    uint32_t kk = n < k ? (uint32_t)n : k;
    for (size_t r = 0; r < n; r++)
        fold_of[order[r]] = (uint32_t)(r % kk);
    affect_free(start);
    affect_free(order);
    return AFFECT_OK;
}

/* The argument checks of the two selections. */
static affect_status check_select(size_t n, size_t d, const uint32_t *y, uint32_t c,
                                  const double *candidates, size_t n_cand, uint32_t folds,
                                  affect_error *err)
{
    affect_status st = check_data(n, d, y, c, err);
    if (st != AFFECT_OK)
        return st;
    if (n_cand == 0)
        return affect_fail(err, AFFECT_ERR_INVALID, "need at least one candidate C");
    for (size_t i = 0; i < n_cand; i++)
        if (!positive_finite(candidates[i]))
            return affect_fail(err, AFFECT_ERR_INVALID,
                               "candidate %zu: C = %g is not a positive finite number", i,
                               candidates[i]);
    if (folds < 2)
        return affect_fail(err, AFFECT_ERR_INVALID, "need at least 2 folds, got %u", folds);
    return AFFECT_OK;
}

static affect_status select_c(const double *G, size_t n, const uint32_t *y, uint32_t c,
                              const double *candidates, size_t n_cand, uint32_t folds,
                              uint64_t seed, double *best_c, double *best_acc, affect_monitor *mon,
                              affect_error *err);

affect_status affect_svm_select_c(const double *X, size_t n, size_t d, const uint32_t *y,
                                  uint32_t c, const double *candidates, size_t n_cand,
                                  uint32_t folds, uint64_t seed, double *best_c, double *best_acc,
                                  affect_error *err)
{
    double *G = NULL;
    affect_status st = check_select(n, d, y, c, candidates, n_cand, folds, err);
    if (st == AFFECT_OK)
        st = check_finite(X, n, d, err);
    if (st == AFFECT_OK)
        st = gram_new(X, n, d, &G, err);
    if (st == AFFECT_OK)
        st = select_c(G, n, y, c, candidates, n_cand, folds, seed, best_c, best_acc, NULL, err);
    affect_free(G);
    return st;
}

affect_status affect_svm_select_c_gram(const double *G, size_t n, size_t d, const uint32_t *y,
                                       uint32_t c, const double *candidates, size_t n_cand,
                                       uint32_t folds, uint64_t seed, double *best_c,
                                       double *best_acc, affect_monitor *mon, affect_error *err)
{
    affect_status st = check_select(n, d, y, c, candidates, n_cand, folds, err);
    if (st == AFFECT_OK)
        st = check_gram(G, n, err);
    if (st == AFFECT_OK)
        st = select_c(G, n, y, c, candidates, n_cand, folds, seed, best_c, best_acc, mon, err);
    return st;
}

/* The cross-validation of affect_svm_select_c on the Gram matrix; mon is polled before each
 * fit (a libsvm fit itself cannot be stopped). */
static affect_status select_c(const double *G, size_t n, const uint32_t *y, uint32_t c,
                              const double *candidates, size_t n_cand, uint32_t folds,
                              uint64_t seed, double *best_c, double *best_acc, affect_monitor *mon,
                              affect_error *err)
{
    affect_status st;
    uint32_t *fold_of = NULL;
    size_t *correct = NULL, *size = NULL, n_cells;
    problem p;
    struct svm_model *sm = NULL;
    affect_svm *m = NULL;
    size_t d = 1; /* the models of the folds carry no weights */
    memset(&p, 0, sizeof p);
    uint32_t k = n < folds ? (uint32_t)n : folds;
    if (!affect_mul_size(n_cand, k, &n_cells))
        return affect_fail(err, AFFECT_ERR_RANGE, "too many candidates: %zu", n_cand);
    fold_of = affect_malloc_array(n, sizeof *fold_of);
    correct = affect_calloc(n_cells, sizeof *correct);
    size = affect_calloc(k, sizeof *size);
    if (!fold_of || !correct || !size) {
        st = affect_nomem(err);
        goto cleanup;
    }
    if ((st = affect_stratified_folds(y, n, c, folds, seed, fold_of, err)) != AFFECT_OK)
        goto cleanup;
    for (size_t i = 0; i < n; i++)
        size[fold_of[i]]++;
    for (uint32_t f = 0; f < k; f++) {
        if ((st = problem_build(G, n, y, c, fold_of, f, &p, err)) != AFFECT_OK)
            goto cleanup;
        for (size_t ci = 0; ci < n_cand; ci++) {
            size_t *hits = &correct[ci * k + f];
            if (p.n_classes == 1) {
                uint32_t only = y[p.ids[0]];
                for (size_t t = 0; t < n; t++)
                    if (fold_of[t] == f && y[t] == only)
                        (*hits)++;
                continue;
            }
            affect_monitor_report(mon, "SVM C cross-validation", (uint64_t)f * n_cand + ci,
                                  (uint64_t)k * n_cand);
            if ((st = affect_monitor_check(mon, err)) != AFFECT_OK ||
                (st = fit(&p, candidates[ci], &sm, err)) != AFFECT_OK)
                goto cleanup;
            st = extract(sm, &p, d, candidates[ci], &m, err);
            svm_free_and_destroy_model(&sm);
            if (st != AFFECT_OK)
                goto cleanup;
            for (size_t t = 0; t < n; t++)
                if (fold_of[t] == f && dual_predict(m, G + t * n) == y[t])
                    (*hits)++;
            affect_svm_free(m);
            m = NULL;
        }
        problem_free(&p);
    }
    for (size_t ci = 0; ci < n_cand; ci++) {
        double acc = 0;
        for (uint32_t f = 0; f < k; f++)
            acc += (double)correct[ci * k + f] / (double)size[f];
        acc /= k;
        if (ci == 0 || acc > *best_acc || (acc == *best_acc && candidates[ci] < *best_c)) {
            *best_acc = acc;
            *best_c = candidates[ci];
        }
    }
cleanup:
    if (sm)
        svm_free_and_destroy_model(&sm);
    affect_svm_free(m);
    problem_free(&p);
    affect_free(fold_of);
    affect_free(correct);
    affect_free(size);
    return st;
}

/* ---- serialisation ---- */

void affect_svm_encode(const affect_svm *m, affect_bw *w)
{
    size_t P = n_pairs(m->c), n_coef = (size_t)(m->c - 1) * m->l;
    affect_bw_u8(w, m->q4 ? 3 : m->f32 ? 2 : 1);
    affect_bw_u32(w, m->c);
    affect_bw_u64(w, (uint64_t)m->d);
    affect_bw_f64(w, m->C);
    affect_bw_u32(w, m->n_train);
    affect_bw_u32(w, m->c);
    affect_bw_u32s(w, m->label, m->c);
    affect_bw_u32(w, m->c);
    affect_bw_u32s(w, m->nsv, m->c);
    affect_bw_u32(w, m->l);
    affect_bw_u32s(w, m->sv_index, m->l);
    affect_bw_u32(w, m->c - 1);
    affect_bw_f64s(w, m->sv_coef, n_coef);
    affect_bw_u32(w, (uint32_t)P);
    affect_bw_f64s(w, m->rho, P);
    affect_bw_u32(w, (uint32_t)P);
    if (m->q4) { /* exact: every vector is in its 4-bit form */
        for (size_t p = 0; p < P; p++)
            affect_q4_write(w, m->w + p * m->d, m->d);
        return;
    }
    if (!m->f32) {
        affect_bw_f64s(w, m->w, P * m->d);
        return;
    }
    affect_bw_f64s_as_f32(w, m->w, P * m->d); /* exact: every weight is a float32 value */
}

bool affect_svm_compact_fits(const affect_svm *m, const double *factor)
{
    if (!m->w)
        return false;
    for (size_t p = 0; p < n_pairs(m->c); p++)
        if (!affect_q4_fits(m->w + p * m->d, m->d, factor))
            return false;
    return true;
}

void affect_svm_compact_weights(affect_svm *m, const double *factor)
{
    for (size_t p = 0; p < n_pairs(m->c); p++)
        affect_q4_round(m->w + p * m->d, m->d, factor);
    m->q4 = true;
    m->f32 = false;
}

bool affect_svm_round_weights(affect_svm *m)
{
    size_t total = n_pairs(m->c) * m->d;
    if (!m->w)
        return false;
    for (size_t i = 0; i < total; i++)
        if (!(fabs(m->w[i]) <= FLT_MAX))
            return false;
    for (size_t i = 0; i < total; i++)
        m->w[i] = (float)m->w[i];
    m->f32 = true;
    return true;
}

/* A count that must equal expected: "SVM: 3 classes but 2 labels (offset 25)". */
static affect_status get_count(affect_br *r, uint32_t c, uint32_t expected, const char *field,
                               const char *what, affect_error *err)
{
    size_t off = r->off;
    uint32_t v;
    affect_status st = affect_br_u32_field(r, &v, "SVM: ", field, err);
    if (st != AFFECT_OK)
        return st;
    if (v != expected)
        return affect_fail(err, AFFECT_ERR_FORMAT, "SVM: %u classes but %u %s (offset %zu)", c, v,
                           what, off);
    return AFFECT_OK;
}

/* n uint32 values into a new array (n checked against the bytes left first). */
static affect_status get_u32s(affect_br *r, size_t n, uint32_t **out, const char *field,
                              affect_error *err)
{
    affect_status st = affect_br_need(r, n, 4, "SVM: ", field, err);
    if (st != AFFECT_OK)
        return st;
    *out = affect_malloc_array(n, sizeof **out);
    if (!*out)
        return affect_nomem(err);
    affect_br_u32s(r, *out, n);
    return AFFECT_OK;
}

/* n finite float64 values into a new array. */
static affect_status get_f64s(affect_br *r, size_t n, double **out, const char *field,
                              affect_error *err)
{
    affect_status st = affect_br_need(r, n, 8, "SVM: ", field, err);
    if (st != AFFECT_OK)
        return st;
    *out = affect_malloc_array(n, sizeof **out);
    if (!*out)
        return affect_nomem(err);
    size_t off = r->off;
    affect_br_f64s(r, *out, n);
    for (size_t i = 0; i < n; i++)
        if (!isfinite((*out)[i]))
            return affect_fail(err, AFFECT_ERR_FORMAT, "SVM: non-finite value in %s (offset %zu)",
                               field, off + 8 * i);
    return AFFECT_OK;
}

/* n finite float32 values into a new array of doubles. */
static affect_status get_f32s(affect_br *r, size_t n, double **out, const char *field,
                              affect_error *err)
{
    affect_status st = affect_br_need(r, n, 4, "SVM: ", field, err);
    if (st != AFFECT_OK)
        return st;
    float *tmp = affect_malloc_array(n ? n : 1, sizeof *tmp);
    *out = affect_malloc_array(n ? n : 1, sizeof **out);
    if (!tmp || !*out) {
        affect_free(tmp);
        return affect_nomem(err);
    }
    size_t off = r->off;
    affect_br_f32s(r, tmp, n);
    for (size_t i = 0; i < n; i++) {
        if (!isfinite(tmp[i])) {
            affect_free(tmp);
            return affect_fail(err, AFFECT_ERR_FORMAT, "SVM: non-finite value in %s (offset %zu)",
                               field, off + 4 * i);
        }
        (*out)[i] = tmp[i];
    }
    affect_free(tmp);
    return AFFECT_OK;
}

/* P weight vectors of d values in their 4-bit form into a new array. */
static affect_status get_q4s(affect_br *r, size_t P, size_t d, double **out, affect_error *err)
{
    size_t bytes, n;
    if (!affect_q4_size(d, &bytes) || !affect_br_has(r, P, bytes) || !affect_mul_size(P, d, &n))
        return affect_fail_truncated(err, "SVM: ", "the weights", r->off);
    *out = affect_malloc_array(n ? n : 1, sizeof **out);
    if (!*out)
        return affect_nomem(err);
    for (size_t p = 0; p < P; p++) {
        size_t off = r->off, bad;
        if (!affect_q4_read(r, *out + p * d, d, &bad))
            return affect_fail(err, AFFECT_ERR_FORMAT,
                               "SVM: weight vector %zu is not a canonical 4-bit form "
                               "(offset %zu)",
                               p, off + bad);
    }
    return AFFECT_OK;
}

affect_status affect_svm_decode(affect_br *r, affect_svm **out, affect_error *err)
{
    affect_status st;
    size_t off;
    uint8_t version;
    uint32_t c, n, l;
    uint64_t d, sum = 0;
    size_t P, n_coef, n_w;
    double C;
    *out = NULL;
    affect_svm *m = affect_calloc(1, sizeof *m);
    if (!m)
        return affect_nomem(err);

    off = r->off;
    if (!affect_br_u8(r, &version)) {
        st = affect_fail_truncated(err, "SVM: ", "the version", off);
        goto cleanup;
    }
    if ((st = affect_check_version(version, AFFECT_SVM_FORMAT_VERSION, "SVM: ", err)) != AFFECT_OK)
        goto cleanup;
    off = r->off;
    if ((st = affect_br_u32_field(r, &c, "SVM: ", "the class count", err)) != AFFECT_OK)
        goto cleanup;
    if (c < 2 || c > AFFECT_SVM_MAX_CLASSES) {
        st = affect_fail(err, AFFECT_ERR_FORMAT,
                         "SVM: class count %u out of range 2 .. %u (offset %zu)", c,
                         AFFECT_SVM_MAX_CLASSES, off);
        goto cleanup;
    }
    off = r->off;
    if (!affect_br_u64(r, &d)) {
        st = affect_fail_truncated(err, "SVM: ", "the dimension", off);
        goto cleanup;
    }
    if (d < 1 || d > AFFECT_SVM_MAX_DIM) {
        st = affect_fail(err, AFFECT_ERR_FORMAT,
                         "SVM: dimension %" PRIu64 " out of range 1 .. %u (offset %zu)", d,
                         AFFECT_SVM_MAX_DIM, off);
        goto cleanup;
    }
    off = r->off;
    if (!affect_br_f64(r, &C)) {
        st = affect_fail_truncated(err, "SVM: ", "C", off);
        goto cleanup;
    }
    if (!positive_finite(C)) {
        st = affect_fail(err, AFFECT_ERR_FORMAT,
                         "SVM: C = %g is not a positive finite number (offset %zu)", C, off);
        goto cleanup;
    }
    off = r->off;
    if ((st = affect_br_u32_field(r, &n, "SVM: ", "the sample count", err)) != AFFECT_OK)
        goto cleanup;
    if (n < c || n > AFFECT_SVM_MAX_SAMPLES) {
        st = affect_fail(err, AFFECT_ERR_FORMAT,
                         "SVM: sample count %u out of range %u .. %u (offset %zu)", n, c,
                         AFFECT_SVM_MAX_SAMPLES, off);
        goto cleanup;
    }
    m->c = c;
    m->d = (size_t)d;
    m->C = C;
    m->n_train = n;

    if ((st = get_count(r, c, c, "the number of labels", "labels", err)) != AFFECT_OK)
        goto cleanup;
    off = r->off;
    if ((st = get_u32s(r, c, &m->label, "the labels", err)) != AFFECT_OK)
        goto cleanup;
    for (uint32_t k = 0; k < c; k++)
        if (m->label[k] != k) {
            st = affect_fail(err, AFFECT_ERR_FORMAT,
                             "SVM: label %u at position %u, expected %u (offset %zu)", m->label[k],
                             k, k, off + 4 * (size_t)k);
            goto cleanup;
        }

    if ((st = get_count(r, c, c, "the number of support-vector counts", "support-vector counts",
                        err)) != AFFECT_OK)
        goto cleanup;
    if ((st = get_u32s(r, c, &m->nsv, "the support-vector counts", err)) != AFFECT_OK)
        goto cleanup;
    for (uint32_t k = 0; k < c; k++)
        sum += m->nsv[k];
    off = r->off;
    if ((st = affect_br_u32_field(r, &l, "SVM: ", "the total of support vectors", err)) !=
        AFFECT_OK)
        goto cleanup;
    if (sum != l) {
        st = affect_fail(err, AFFECT_ERR_FORMAT,
                         "SVM: support-vector counts sum to %" PRIu64 " but the total is %u "
                         "(offset %zu)",
                         sum, l, off);
        goto cleanup;
    }
    if (l > n) {
        st = affect_fail(err, AFFECT_ERR_FORMAT,
                         "SVM: %u support vectors but %u training samples (offset %zu)", l, n, off);
        goto cleanup;
    }
    m->l = l;
    off = r->off;
    if ((st = get_u32s(r, l, &m->sv_index, "the support-vector indices", err)) != AFFECT_OK)
        goto cleanup;
    for (uint32_t k = 0, s = 0; k < c; k++)
        for (uint32_t i = 0; i < m->nsv[k]; i++, s++) {
            size_t at = off + 4 * (size_t)s;
            if (m->sv_index[s] >= n) {
                st = affect_fail(err, AFFECT_ERR_FORMAT,
                                 "SVM: support vector %u has training index %u, not below %u "
                                 "(offset %zu)",
                                 s, m->sv_index[s], n, at);
                goto cleanup;
            }
            if (i > 0 && m->sv_index[s] <= m->sv_index[s - 1]) {
                st = affect_fail(err, AFFECT_ERR_FORMAT,
                                 "SVM: support vector %u has training index %u, not above the "
                                 "previous %u of its class (offset %zu)",
                                 s, m->sv_index[s], m->sv_index[s - 1], at);
                goto cleanup;
            }
        }

    P = n_pairs(c);
    if ((st = get_count(r, c, c - 1, "the number of coefficient rows", "coefficient rows", err)) !=
        AFFECT_OK)
        goto cleanup;
    if (!affect_mul_size(c - 1, l, &n_coef)) {
        st = affect_fail_truncated(err, "SVM: ", "the coefficients", r->off);
        goto cleanup;
    }
    if ((st = get_f64s(r, n_coef, &m->sv_coef, "the coefficients", err)) != AFFECT_OK)
        goto cleanup;
    if ((st = get_count(r, c, (uint32_t)P, "the number of rho values", "rho values", err)) !=
        AFFECT_OK)
        goto cleanup;
    if ((st = get_f64s(r, P, &m->rho, "the rho values", err)) != AFFECT_OK)
        goto cleanup;
    if ((st = get_count(r, c, (uint32_t)P, "the number of weight vectors", "weight vectors",
                        err)) != AFFECT_OK)
        goto cleanup;
    if (!affect_mul_size(P, m->d, &n_w)) {
        st = affect_fail_truncated(err, "SVM: ", "the weights", r->off);
        goto cleanup;
    }
    if (version == 1) {
        if ((st = get_f64s(r, n_w, &m->w, "the weights", err)) != AFFECT_OK)
            goto cleanup;
    } else if (version == 2) {
        if ((st = get_f32s(r, n_w, &m->w, "the weights", err)) != AFFECT_OK)
            goto cleanup;
    } else if ((st = get_q4s(r, P, m->d, &m->w, err)) != AFFECT_OK) {
        goto cleanup;
    }
    m->f32 = version == 2;
    m->q4 = version == 3;
    *out = m;
    m = NULL;
cleanup:
    affect_svm_free(m);
    return st;
}
