/*
 * spca.c — supervised PCA with the Hilbert–Schmidt independence criterion, computed in the
 * dual, the HSIC itself, and k-nearest-neighbour classification (see affect/spca.h).
 *
 * Usage: see the block at the top of affect/spca.h (compiled by the style/header-usage test).
 *
 * How it works. Notation of the header: X n × d, H = I − eeᵀ/n, B = Δ Δᵀ.
 *   1. The centred Gram matrix K̃ = H X Xᵀ H is built from centred copies of column blocks of X
 *      (each block of at most BLOCK_DOUBLES doubles has its column means subtracted, then one
 *      cblas_dsyrk adds its contribution), so nothing cancels when the data sit far from the
 *      origin and X is never copied whole. With a Gram matrix K given, K̃_ij = K_ij − r_i − r_j
 *      + m instead (r the row means, m the mean, of K's symmetric completion).
 *   2. The label factor: G^{1/2} = Q diag(√max(μ, 0)) Qᵀ from G = Q diag(μ) Qᵀ (G = I, so
 *      G^{1/2} = I, for the linear kernel); Δ_i = row y_i of G^{1/2}; Δ̃ = H Δ (column means
 *      removed: redundant in exact arithmetic since K̃ is centred, it keeps the columns of A
 *      below summing to zero up to rounding). Any Δ with Δ Δᵀ = B gives the same axes
 *      (another factor is Δ R with R orthogonal, which turns M into Rᵀ M R and v into Rᵀ v),
 *      so the choice is immaterial.
 *   3. M = Δ̃ᵀ K̃ Δ̃ (c × c; two cblas_dgemm), symmetrised, and its eigenpairs by
 *      LAPACKE_dsyev_work, called in column-major form on the symmetric row-major array (the
 *      eigenvectors then land in its rows) with the minimal workspace 3c − 1, so it makes no
 *      allocation outside ours and always runs the same (unblocked) algorithm.
 *   4. p = min(dims, #{λ > AFFECT_SPCA_RANK_TOL · λ_max}); A = Δ̃ [v_1 … v_p] diag(1/√λ) (n × p).
 *   5. U = Aᵀ H X (p × d), again block by block of centred columns (cblas_dgemm), so
 *      U_r = Xᵀ H Δ v_r / √λ_r. Each row is then flipped, if needed, so that its first
 *      largest-magnitude component is positive.
 * U_rᵀ U_s = v_rᵀ Δ̃ᵀ K̃ Δ̃ v_s / √(λ_r λ_s) = δ_rs: the axes are orthonormal by construction.
 *
 * The HSIC uses tr(K H B H) = tr(K B) − (1ᵀ B K 1 + 1ᵀ K B 1)/n + (1ᵀ K 1)(1ᵀ B 1)/n² on K and
 * B with their overall means subtracted (which changes nothing, H e = 0) — O(n²), no memory.
 *
 * k-NN keeps the k best (squared distance, index) pairs in a sorted array by insertion
 * (O(n k)); a later index never displaces an equal distance, which gives the tie rule.
 *
 * Memory: fitting makes one workspace allocation (n² + n(2c + 1) + 3c² + 5c doubles plus a
 * column block of at most 2 MB) and one for the model; k-NN one of k + 2c words. Sizes are
 * overflow-checked.
 */
#include "affect/spca.h"

#include <cblas.h>
#include <inttypes.h>
#include <lapacke.h>
#include <float.h>
#include <limits.h>
#include <math.h>
#include <string.h>

#include "affect/hmm_blob.h" /* affect_fnv1a64 */
#include "util/quant.h"
#include "util/internal.h"

#define FLAG_F32 1u           /* record flag: the axes are float32 */
#define FLAG_Q4 2u            /* record flag: the axes are in 4-bit blocks (util/quant.h) */
#define BLOCK_DOUBLES 262144u /* doubles in one centred column block of X */
#define GRAM_MATCH_TOL 1e-6   /* relative trace mismatch tolerated by affect_spca_fit_gram */
#define BLAS_MAX ((size_t)INT_MAX)

struct affect_spca {
    affect_spca_kernel kernel;
    uint32_t classes, dims;
    double sigma;
    uint64_t n_train;
    size_t input_dim;
    double *eigenvalues; /* dims, descending */
    double *axes;        /* dims × input_dim, row-major */
    double *coef;        /* n_train × dims: A of a dual fit until affect_spca_finish, else NULL */
    bool f32;            /* every axis component is a float32 value: encoded with flag 1 */
    bool q4;             /* every axis is in its 4-bit form: encoded with flag 2 */
};

/* The struct, rounded up so the doubles after it are aligned. */
#define MODEL_HEAD ((sizeof(affect_spca) + 15u) & ~(size_t)15u)

/* A model with room for p eigenvalues and p × d axes (one block), or NULL. */
static affect_spca *model_alloc(uint32_t p, size_t d)
{
    size_t pd, doubles, bytes;
    if (!affect_mul_size(p, d, &pd) || !affect_add_size(pd, p, &doubles) ||
        !affect_mul_size(doubles, sizeof(double), &bytes) ||
        !affect_add_size(bytes, MODEL_HEAD, &bytes))
        return NULL;
    unsigned char *block = affect_malloc(bytes);
    if (!block)
        return NULL;
    affect_spca *s = (affect_spca *)block;
    memset(s, 0, sizeof *s);
    s->dims = p;
    s->input_dim = d;
    s->eigenvalues = (double *)(block + MODEL_HEAD);
    s->axes = s->eigenvalues + p;
    return s;
}

void affect_spca_free(affect_spca *s)
{
    if (s)
        affect_free(s->coef);
    affect_free(s); /* one block, the struct first */
}

/* ---- validation shared by the fits and the label kernel ---- */

static affect_status check_kernel(affect_spca_kernel kernel, double sigma, affect_error *err)
{
    if (kernel != AFFECT_SPCA_LINEAR && kernel != AFFECT_SPCA_RBF)
        return affect_fail(err, AFFECT_ERR_INVALID, "unknown label kernel %d (0 = linear, 1 = rbf)",
                           (int)kernel);
    if (kernel == AFFECT_SPCA_RBF && !(sigma > 0 && isfinite(sigma)))
        return affect_fail(err, AFFECT_ERR_INVALID, "sigma must be a positive finite number");
    return AFFECT_OK;
}

static affect_status check_labels(const uint32_t *y, size_t n, uint32_t c, const char *what,
                                  affect_error *err)
{
    for (size_t i = 0; i < n; i++)
        if (y[i] >= c)
            return affect_fail(err, AFFECT_ERR_INVALID,
                               "%srow %zu: label %u is out of range (%u classes: 0 .. %u)", what, i,
                               y[i], c, c - 1);
    return AFFECT_OK;
}

/* Everything the fits check before any work. */
static affect_status check_fit(const double *x, size_t n, size_t d, const uint32_t *y, uint32_t c,
                               affect_spca_kernel kernel, double sigma, uint32_t dims,
                               affect_error *err)
{
    if (c < 2)
        return affect_fail(err, AFFECT_ERR_INVALID, "need at least 2 classes");
    if (d == 0)
        return affect_fail(err, AFFECT_ERR_INVALID, "d must be at least 1");
    affect_status st = check_kernel(kernel, sigma, err);
    if (st != AFFECT_OK)
        return st;
    if (dims == 0)
        return affect_fail(err, AFFECT_ERR_INVALID, "dims must be at least 1");
    if ((st = check_labels(y, n, c, "", err)) != AFFECT_OK)
        return st;
    /* every class present (c ≤ n then, so this is O(n²) at worst, without memory) */
    for (uint32_t k = 0; k < c; k++) {
        bool found = false;
        for (size_t i = 0; i < n && !found; i++)
            found = y[i] == k;
        if (!found)
            return affect_fail(err, AFFECT_ERR_INVALID, "class %u has no training sample", k);
    }
    if (n > BLAS_MAX)
        return affect_fail(err, AFFECT_ERR_RANGE, "n = %zu exceeds the BLAS limit of %d", n,
                           INT_MAX);
    if (d > BLAS_MAX)
        return affect_fail(err, AFFECT_ERR_RANGE, "d = %zu exceeds the BLAS limit of %d", d,
                           INT_MAX);
    for (size_t i = 0; x && i < n; i++) { /* x NULL: the dual fit, the Gram matrix only */
        const double *row = x + i * d;
        for (size_t j = 0; j < d; j++)
            if (!isfinite(row[j]))
                return affect_fail(err, AFFECT_ERR_INVALID, "row %zu, column %zu: non-finite value",
                                   i, j);
    }
    return AFFECT_OK;
}

/* ---- fitting ---- */

/* Copies columns j0 .. j0 + b − 1 of x (n × d) into blk (n × b) and subtracts their means
 * (left in mean). With sums not NULL, adds Σ x² to sums[0] and Σ (x − mean)² to sums[1]. */
static void centred_block(const double *x, size_t n, size_t d, size_t j0, size_t b, double *blk,
                          double *mean, double *sums)
{
    memset(mean, 0, b * sizeof *mean);
    for (size_t i = 0; i < n; i++) {
        const double *src = x + i * d + j0;
        double *dst = blk + i * b;
        memcpy(dst, src, b * sizeof *dst);
        for (size_t j = 0; j < b; j++)
            mean[j] += dst[j];
    }
    for (size_t j = 0; j < b; j++)
        mean[j] /= (double)n;
    double raw = 0.0, cen = 0.0;
    for (size_t i = 0; i < n; i++) {
        double *dst = blk + i * b;
        for (size_t j = 0; j < b; j++) {
            raw += dst[j] * dst[j];
            dst[j] -= mean[j];
            cen += dst[j] * dst[j];
        }
    }
    if (sums) {
        sums[0] += raw;
        sums[1] += cen;
    }
}

/* The workspace of one fit, carved from one zeroed allocation. */
typedef struct work {
    double *kc;   /* n × n  centred Gram matrix H K H */
    double *dt;   /* n × c  Δ̃ = H Δ */
    double *t;    /* n × c  K̃ Δ̃, then A (n × p) */
    double *m;    /* c × c  M, then its eigenvectors (rows) */
    double *lam;  /* c      M's eigenvalues, ascending; column means of Δ */
    double *g;    /* c × c  G, then its eigenvectors (rows) */
    double *root; /* c × c  G^{1/2} */
    double *mu;   /* c      G's eigenvalues */
    double *lwork;
    double *rows; /* n      row means of a given K */
    double *blk;  /* n × bw centred column block of X */
    double *mean; /* bw     its column means */
    size_t bw, nlwork;
    double *base;
} work;

/* Sum of the products a_i × b_i (i < count) into *out; false on overflow. */
static bool sum_products(const size_t *a, const size_t *b, size_t count, size_t *out)
{
    size_t total = 0;
    for (size_t i = 0; i < count; i++) {
        size_t prod;
        if (!affect_mul_size(a[i], b[i], &prod) || !affect_add_size(total, prod, &total))
            return false;
    }
    *out = total;
    return true;
}

static affect_status work_alloc(work *w, size_t n, size_t d, uint32_t c, affect_error *err)
{
    memset(w, 0, sizeof *w);
    size_t bw = BLOCK_DOUBLES / n;
    if (bw < 1)
        bw = 1;
    if (bw > d)
        bw = d;
    size_t nlwork = 3 * (size_t)c - 1; /* c ≥ 2 */
    const size_t a[] = {n, n, n, c, c, c, c, c, nlwork, n, n, bw};
    const size_t b[] = {n, c, c, c, 1, c, c, 1, 1, 1, bw, 1};
    size_t count;
    if (!sum_products(a, b, sizeof a / sizeof a[0], &count))
        return affect_fail(err, AFFECT_ERR_RANGE, "n = %zu samples and %u classes are too many", n,
                           c);
    double *p = affect_calloc(count, sizeof *p);
    if (!p)
        return affect_nomem_of(err, count, sizeof *p, "the sPCA's workspace for %zu samples", n);
    w->base = p;
    double **slot[] = {&w->kc,   &w->dt, &w->t,     &w->m,    &w->lam, &w->g,
                       &w->root, &w->mu, &w->lwork, &w->rows, &w->blk, &w->mean};
    for (size_t i = 0; i < sizeof slot / sizeof slot[0]; i++) {
        *slot[i] = p;
        p += a[i] * b[i];
    }
    w->bw = bw;
    w->nlwork = nlwork;
    return AFFECT_OK;
}

/* Step 1 from the data: kc = H X Xᵀ H, block by block of centred columns. */
static void gram_from_data(work *w, const double *x, size_t n, size_t d)
{
    for (size_t j0 = 0; j0 < d; j0 += w->bw) {
        size_t b = d - j0 < w->bw ? d - j0 : w->bw;
        centred_block(x, n, d, j0, b, w->blk, w->mean, NULL);
        AFFECT_BLAS(cblas_dsyrk(CblasRowMajor, CblasUpper, CblasNoTrans, (int)n, (int)b, 1.0,
                                w->blk, (int)b, 1.0, w->kc, (int)n));
    }
    for (size_t i = 0; i < n; i++)
        for (size_t j = 0; j < i; j++)
            w->kc[i * n + j] = w->kc[j * n + i];
}

/* Step 1 from a given K (upper triangle): kc = H K H; *trace_k receives tr K. */
static affect_status gram_from_k(work *w, const double *k, size_t n, double *trace_k,
                                 affect_error *err)
{
    for (size_t i = 0; i < n; i++)
        for (size_t j = i; j < n; j++) {
            double v = k[i * n + j];
            if (!isfinite(v))
                return affect_fail(err, AFFECT_ERR_INVALID,
                                   "K row %zu, column %zu: non-finite value", i, j);
            w->kc[i * n + j] = w->kc[j * n + i] = v;
        }
    double total = 0.0, tr = 0.0;
    for (size_t i = 0; i < n; i++) {
        double s = 0.0;
        for (size_t j = 0; j < n; j++)
            s += w->kc[i * n + j];
        w->rows[i] = s / (double)n;
        total += w->rows[i];
        tr += w->kc[i * n + i];
    }
    double mean = total / (double)n;
    for (size_t i = 0; i < n; i++)
        for (size_t j = 0; j < n; j++)
            w->kc[i * n + j] = ((w->kc[i * n + j] - w->rows[i]) - w->rows[j]) + mean;
    *trace_k = tr;
    return AFFECT_OK;
}

static affect_status eig_failed(int info, affect_error *err)
{
    return affect_fail(err, AFFECT_ERR_RANGE,
                       "the eigendecomposition did not converge (LAPACK info %d)", info);
}

/* Step 2: dt = H Δ with Δ_i = row y_i of G^{1/2}. */
static affect_status label_factor(work *w, const uint32_t *y, size_t n, uint32_t c,
                                  affect_spca_kernel kernel, double sigma, affect_error *err)
{
    double *root = w->root;
    if (kernel == AFFECT_SPCA_LINEAR) {
        for (uint32_t k = 0; k < c; k++)
            root[(size_t)k * c + k] = 1.0;
    } else {
        double *g = w->g;
        for (uint32_t k = 0; k < c; k++)
            for (uint32_t l = 0; l < c; l++) {
                double diff = (double)k - (double)l;
                g[(size_t)k * c + l] = exp(-diff * diff / (2.0 * sigma * sigma));
            }
        /* column-major 'U' on the symmetric row-major array: eigenvector r is row r */
        lapack_int info;
        AFFECT_BLAS(info =
                        LAPACKE_dsyev_work(LAPACK_COL_MAJOR, 'V', 'U', (lapack_int)c, g,
                                           (lapack_int)c, w->mu, w->lwork, (lapack_int)w->nlwork));
        if (info != 0)
            return eig_failed((int)info, err);
        for (uint32_t r = 0; r < c; r++)
            w->mu[r] = w->mu[r] > 0 ? sqrt(w->mu[r]) : 0.0;
        for (uint32_t k = 0; k < c; k++)
            for (uint32_t l = 0; l < c; l++) {
                double s = 0.0;
                for (uint32_t r = 0; r < c; r++)
                    s += g[(size_t)r * c + k] * w->mu[r] * g[(size_t)r * c + l];
                root[(size_t)k * c + l] = s;
            }
    }
    double *mean = w->lam;
    memset(mean, 0, c * sizeof *mean);
    for (size_t i = 0; i < n; i++) {
        memcpy(w->dt + i * c, root + (size_t)y[i] * c, c * sizeof *root);
        for (uint32_t k = 0; k < c; k++)
            mean[k] += w->dt[i * c + k];
    }
    for (uint32_t k = 0; k < c; k++)
        mean[k] /= (double)n;
    for (size_t i = 0; i < n; i++)
        for (uint32_t k = 0; k < c; k++)
            w->dt[i * c + k] -= mean[k];
    return AFFECT_OK;
}

static bool all_finite(const double *v, size_t count)
{
    for (size_t i = 0; i < count; i++)
        if (!isfinite(v[i]))
            return false;
    return true;
}

static const char OVERFLOW_MSG[] = "the data are too large: the centred Gram matrix overflows";

/* Steps 3–4: M, its eigenpairs, p and A (in w->t). */
static affect_status dual_solve(work *w, size_t n, uint32_t c, uint32_t dims, uint32_t *p_out,
                                affect_error *err)
{
    AFFECT_BLAS(cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, (int)n, (int)c, (int)n, 1.0,
                            w->kc, (int)n, w->dt, (int)c, 0.0, w->t, (int)c));
    AFFECT_BLAS(cblas_dgemm(CblasRowMajor, CblasTrans, CblasNoTrans, (int)c, (int)c, (int)n, 1.0,
                            w->dt, (int)c, w->t, (int)c, 0.0, w->m, (int)c));
    double *m = w->m;
    for (uint32_t k = 0; k < c; k++)
        for (uint32_t l = k + 1; l < c; l++) {
            double v = 0.5 * (m[(size_t)k * c + l] + m[(size_t)l * c + k]);
            m[(size_t)k * c + l] = m[(size_t)l * c + k] = v;
        }
    if (!all_finite(m, (size_t)c * c))
        return affect_fail(err, AFFECT_ERR_RANGE, "%s", OVERFLOW_MSG);
    lapack_int info;
    AFFECT_BLAS(info = LAPACKE_dsyev_work(LAPACK_COL_MAJOR, 'V', 'U', (lapack_int)c, m,
                                          (lapack_int)c, w->lam, w->lwork, (lapack_int)w->nlwork));
    if (info != 0)
        return eig_failed((int)info, err);
    double trace = 0.0;
    for (size_t i = 0; i < n; i++)
        trace += w->kc[i * n + i];
    double lmax = w->lam[c - 1];
    if (!(lmax > AFFECT_SPCA_INFO_TOL * (double)n * trace))
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "the data carry no label information (all projections are 0)");
    uint32_t p = 0;
    while (p < dims && p < c && w->lam[c - 1 - p] > AFFECT_SPCA_RANK_TOL * lmax)
        p++;
    /* A_iq = (Δ̃ v_q)_i / √λ_q, v_q = row c − 1 − q of m */
    for (uint32_t q = 0; q < p; q++) {
        const double *v = m + (size_t)(c - 1 - q) * c;
        double scale = 1.0 / sqrt(w->lam[c - 1 - q]);
        for (size_t i = 0; i < n; i++) {
            double s = 0.0;
            for (uint32_t k = 0; k < c; k++)
                s += w->dt[i * c + k] * v[k];
            w->t[i * p + q] = s * scale;
        }
    }
    *p_out = p;
    return AFFECT_OK;
}

/* Each axis's largest-magnitude component (the first such) made positive; the same columns of
 * z (m × dims, NULL for none) change sign with their axis. */
static void orient_axes(affect_spca *s, double *z, size_t m)
{
    size_t d = s->input_dim;
    uint32_t p = s->dims;
    for (uint32_t q = 0; q < p; q++) {
        double *row = s->axes + (size_t)q * d;
        size_t best = 0;
        for (size_t j = 1; j < d; j++)
            if (fabs(row[j]) > fabs(row[best]))
                best = j;
        if (row[best] < 0) {
            for (size_t j = 0; j < d; j++)
                row[j] = -row[j];
            for (size_t i = 0; z && i < m; i++)
                z[i * p + q] = -z[i * p + q];
        }
    }
}

/* Step 5: the axes U = Aᵀ H X, block by block; sums as centred_block's when not NULL. */
static void axes_from_data(work *w, const double *x, size_t n, size_t d, affect_spca *s,
                           double *sums)
{
    uint32_t p = s->dims;
    memset(s->axes, 0, (size_t)p * d * sizeof *s->axes);
    for (size_t j0 = 0; j0 < d; j0 += w->bw) {
        size_t b = d - j0 < w->bw ? d - j0 : w->bw;
        centred_block(x, n, d, j0, b, w->blk, w->mean, sums);
        AFFECT_BLAS(cblas_dgemm(CblasRowMajor, CblasTrans, CblasNoTrans, (int)p, (int)b, (int)n,
                                1.0, w->t, (int)p, w->blk, (int)b, 0.0, s->axes + j0, (int)d));
    }
    orient_axes(s, NULL, 0);
}

/* The fitted model's eigenvalues (from w), kernel, σ, classes and training size. */
static void describe(affect_spca *s, const work *w, affect_spca_kernel kernel, double sigma,
                     uint32_t c, size_t n)
{
    for (uint32_t q = 0; q < s->dims; q++)
        s->eigenvalues[q] = w->lam[c - 1 - q];
    s->kernel = kernel;
    s->sigma = kernel == AFFECT_SPCA_RBF ? sigma : 0.0;
    s->classes = c;
    s->n_train = n;
}

static affect_status fit(const double *x, const double *k, size_t n, size_t d, const uint32_t *y,
                         uint32_t c, affect_spca_kernel kernel, double sigma, uint32_t dims,
                         affect_spca **out, affect_error *err)
{
    *out = NULL;
    affect_status st = check_fit(x, n, d, y, c, kernel, sigma, dims, err);
    if (st != AFFECT_OK)
        return st;
    work w;
    if ((st = work_alloc(&w, n, d, c, err)) != AFFECT_OK)
        return st;
    affect_spca *s = NULL;
    double trace_k = 0.0;
    if (k) {
        if ((st = gram_from_k(&w, k, n, &trace_k, err)) != AFFECT_OK)
            goto cleanup;
    } else {
        gram_from_data(&w, x, n, d);
    }
    if (!all_finite(w.kc, n * n)) {
        st = affect_fail(err, AFFECT_ERR_RANGE, "%s", OVERFLOW_MSG);
        goto cleanup;
    }
    uint32_t p = 0;
    if ((st = label_factor(&w, y, n, c, kernel, sigma, err)) != AFFECT_OK ||
        (st = dual_solve(&w, n, c, dims, &p, err)) != AFFECT_OK)
        goto cleanup;
    s = model_alloc(p, d);
    if (!s) {
        st = affect_nomem_of(err, (size_t)p + 1, d * sizeof(double), "the sPCA's %u x %zu axes", p,
                             d);
        goto cleanup;
    }
    double sums[2] = {0.0, 0.0};
    axes_from_data(&w, x, n, d, s, k ? sums : NULL);
    if (k) {
        double trace_kc = 0.0;
        for (size_t i = 0; i < n; i++)
            trace_kc += w.kc[i * n + i];
        double scale = trace_k > sums[0] ? trace_k : sums[0];
        if (!(fabs(trace_kc - sums[1]) <= GRAM_MATCH_TOL * scale)) {
            st = affect_fail(err, AFFECT_ERR_INVALID,
                             "the Gram matrix does not match the data (trace of H K H %.6g, the "
                             "data give %.6g)",
                             trace_kc, sums[1]);
            goto cleanup;
        }
    }
    describe(s, &w, kernel, sigma, c, n);
    *out = s;
    s = NULL;
cleanup:
    affect_spca_free(s);
    affect_free(w.base);
    return st;
}

affect_status affect_spca_fit_dual(const double *k, size_t n, size_t d, const uint32_t *y,
                                   uint32_t c, affect_spca_kernel kernel, double sigma,
                                   uint32_t dims, affect_spca **out, affect_error *err)
{
    *out = NULL;
    affect_status st = check_fit(NULL, n, d, y, c, kernel, sigma, dims, err);
    if (st != AFFECT_OK)
        return st;
    work w;
    if ((st = work_alloc(&w, n, 1, c, err)) != AFFECT_OK)
        return st;
    affect_spca *s = NULL;
    double trace_k = 0.0;
    uint32_t p = 0;
    if ((st = gram_from_k(&w, k, n, &trace_k, err)) != AFFECT_OK)
        goto cleanup;
    if (!all_finite(w.kc, n * n)) {
        st = affect_fail(err, AFFECT_ERR_RANGE, "%s", OVERFLOW_MSG);
        goto cleanup;
    }
    if ((st = label_factor(&w, y, n, c, kernel, sigma, err)) != AFFECT_OK ||
        (st = dual_solve(&w, n, c, dims, &p, err)) != AFFECT_OK)
        goto cleanup;
    s = model_alloc(p, d);
    if (!s) {
        st = affect_nomem_of(err, (size_t)p + 1, d * sizeof(double), "the sPCA's %u x %zu axes", p,
                             d);
        goto cleanup;
    }
    if (!(s->coef = affect_malloc_array(n * p, sizeof *s->coef))) {
        st = affect_nomem(err);
        goto cleanup;
    }
    memcpy(s->coef, w.t, n * p * sizeof *s->coef);
    memset(s->axes, 0, (size_t)p * d * sizeof *s->axes);
    describe(s, &w, kernel, sigma, c, n);
    *out = s;
    s = NULL;
cleanup:
    affect_spca_free(s);
    affect_free(w.base);
    return st;
}

void affect_spca_dual_embed(const affect_spca *s, const double *k, size_t m, double *z)
{
    size_t n = (size_t)s->n_train;
    uint32_t p = s->dims;
    for (size_t i = 0; i < m; i++)
        for (uint32_t q = 0; q < p; q++) {
            double acc = 0.0;
            for (size_t j = 0; j < n; j++)
                acc += k[i * n + j] * s->coef[j * p + q];
            z[i * p + q] = acc;
        }
}

void affect_spca_add_rows(affect_spca *s, const double *B, size_t b, size_t col0)
{
    size_t n = (size_t)s->n_train, d = s->input_dim;
    uint32_t p = s->dims;
    AFFECT_BLAS(cblas_dgemm(CblasRowMajor, CblasTrans, CblasNoTrans, (int)p, (int)b, (int)n, 1.0,
                            s->coef, (int)p, B, (int)b, 1.0, s->axes + col0, (int)d));
}

void affect_spca_finish(affect_spca *s, double *z, size_t m)
{
    orient_axes(s, z, m);
    affect_free(s->coef);
    s->coef = NULL;
}

affect_status affect_spca_fit(const double *x, size_t n, size_t d, const uint32_t *y, uint32_t c,
                              affect_spca_kernel kernel, double sigma, uint32_t dims,
                              affect_spca **out, affect_error *err)
{
    return fit(x, NULL, n, d, y, c, kernel, sigma, dims, out, err);
}

affect_status affect_spca_fit_gram(const double *x, const double *k, size_t n, size_t d,
                                   const uint32_t *y, uint32_t c, affect_spca_kernel kernel,
                                   double sigma, uint32_t dims, affect_spca **out,
                                   affect_error *err)
{
    return fit(x, k, n, d, y, c, kernel, sigma, dims, out, err);
}

/* ---- use ---- */

void affect_spca_embed(const affect_spca *s, const double *x, double *z)
{
    size_t d = s->input_dim;
    for (uint32_t q = 0; q < s->dims; q++) {
        const double *u = s->axes + (size_t)q * d;
        double acc = 0.0;
        for (size_t j = 0; j < d; j++)
            acc += u[j] * x[j];
        z[q] = acc;
    }
}

void affect_spca_embed_rows(const affect_spca *s, const double *x, size_t n, double *z)
{
    for (size_t i = 0; i < n; i++)
        affect_spca_embed(s, x + i * s->input_dim, z + i * s->dims);
}

uint32_t affect_spca_dims(const affect_spca *s)
{
    return s->dims;
}

size_t affect_spca_input_dim(const affect_spca *s)
{
    return s->input_dim;
}

uint32_t affect_spca_classes(const affect_spca *s)
{
    return s->classes;
}

uint64_t affect_spca_train_size(const affect_spca *s)
{
    return s->n_train;
}

affect_spca_kernel affect_spca_get_kernel(const affect_spca *s)
{
    return s->kernel;
}

double affect_spca_sigma(const affect_spca *s)
{
    return s->sigma;
}

const double *affect_spca_axes(const affect_spca *s)
{
    return s->axes;
}

const double *affect_spca_eigenvalues(const affect_spca *s)
{
    return s->eigenvalues;
}

/* ---- serialisation ---- */

bool affect_spca_round_axes(affect_spca *s)
{
    size_t pd = (size_t)s->dims * s->input_dim;
    for (size_t i = 0; i < pd; i++)
        if (!(fabs(s->axes[i]) <= FLT_MAX))
            return false;
    for (size_t i = 0; i < pd; i++)
        s->axes[i] = (float)s->axes[i];
    s->f32 = true;
    return true;
}

bool affect_spca_compact_fits(const affect_spca *s, const double *factor)
{
    for (uint32_t q = 0; q < s->dims; q++)
        if (!affect_q4_fits(s->axes + (size_t)q * s->input_dim, s->input_dim, factor))
            return false;
    return true;
}

void affect_spca_compact_axes(affect_spca *s, const double *factor)
{
    for (uint32_t q = 0; q < s->dims; q++)
        affect_q4_round(s->axes + (size_t)q * s->input_dim, s->input_dim, factor);
    s->q4 = true;
    s->f32 = false;
}

void affect_spca_encode(const affect_spca *s, affect_bw *w)
{
    if (w->failed)
        return;
    size_t start = w->len;
    affect_bw_header(w, AFFECT_SPCA_MAGIC, AFFECT_SPCA_VERSION,
                     s->q4    ? FLAG_Q4
                     : s->f32 ? FLAG_F32
                              : 0u);
    affect_bw_u32(w, (uint32_t)s->kernel);
    affect_bw_u32(w, s->classes);
    affect_bw_u32(w, s->dims);
    affect_bw_u64(w, s->n_train);
    affect_bw_u64(w, (uint64_t)s->input_dim);
    affect_bw_f64(w, s->sigma);
    affect_bw_f64s(w, s->eigenvalues, s->dims);
    size_t pd = (size_t)s->dims * s->input_dim;
    if (s->q4) /* exact: every axis is in its 4-bit form */
        for (uint32_t q = 0; q < s->dims; q++)
            affect_q4_write(w, s->axes + (size_t)q * s->input_dim, s->input_dim);
    else if (!s->f32)
        affect_bw_f64s(w, s->axes, pd);
    else /* exact: every component is a float32 value */
        affect_bw_f64s_as_f32(w, s->axes, pd);
    if (w->failed)
        return;
    affect_bw_checksum(w, start);
}

affect_status affect_spca_decode(affect_br *r, affect_spca **out, affect_error *err)
{
    *out = NULL;
    size_t start = r->off;
    if (!affect_br_has(r, AFFECT_SPCA_HEADER_SIZE, 1))
        return affect_fail(err, AFFECT_ERR_FORMAT, "sPCA: truncated in the header (offset %zu)",
                           start);
    const unsigned char *magic;
    uint32_t version, flags, kernel, c, p;
    uint64_t n, d;
    double sigma;
    affect_br_bytes(r, &magic, 4);
    affect_br_u32(r, &version);
    affect_br_u32(r, &flags);
    affect_br_u32(r, &kernel);
    affect_br_u32(r, &c);
    affect_br_u32(r, &p);
    affect_br_u64(r, &n);
    affect_br_u64(r, &d);
    affect_br_f64(r, &sigma);
    if (affect_check_magic(magic, AFFECT_SPCA_MAGIC, "sPCA: ", "an sPCA record", start, err) !=
            AFFECT_OK ||
        affect_check_version(version, AFFECT_SPCA_VERSION, "sPCA: ", err) != AFFECT_OK)
        return AFFECT_ERR_FORMAT;
    if ((flags & ~(uint32_t)(FLAG_F32 | FLAG_Q4)) || flags == (FLAG_F32 | FLAG_Q4))
        return affect_fail(err, AFFECT_ERR_FORMAT, "sPCA: unknown flags 0x%" PRIx32 " (offset %zu)",
                           flags, start + 8);
    size_t width = (flags & FLAG_F32) ? 4 : 8; /* bytes per axis component */
    if (kernel != AFFECT_SPCA_LINEAR && kernel != AFFECT_SPCA_RBF)
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "sPCA: unknown label kernel %" PRIu32 " (offset %zu)", kernel,
                           start + 12);
    if (c < 2)
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "sPCA: %" PRIu32 " class%s, need at least 2 (offset %zu)", c,
                           c == 1 ? "" : "es", start + 16);
    if (p < 1 || p > c - 1)
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "sPCA: %" PRIu32 " axes, expected 1 .. %" PRIu32 " for %" PRIu32
                           " classes (offset %zu)",
                           p, c - 1, c, start + 20);
    if (n < c)
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "sPCA: %" PRIu64 " training samples for %" PRIu32 " classes "
                           "(offset %zu)",
                           n, c, start + 24);
    if (d < 1 || d > INT_MAX)
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "sPCA: input dimension %" PRIu64 " is not in 1 .. %d (offset %zu)", d,
                           INT_MAX, start + 32);
    if (kernel == AFFECT_SPCA_RBF && !(sigma > 0 && isfinite(sigma)))
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "sPCA: sigma %g is not a positive finite number (offset %zu)", sigma,
                           start + 40);
    if (kernel == AFFECT_SPCA_LINEAR && (sigma != 0 || signbit(sigma)))
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "sPCA: sigma %g with the linear kernel, expected 0 (offset %zu)", sigma,
                           start + 40);
    size_t eig_off = r->off;
    const unsigned char *eig, *axes;
    if (!affect_br_bytes(r, &eig, (size_t)p * 8))
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "sPCA: truncated in the eigenvalues (offset %zu)", eig_off);
    size_t ax_off = r->off, pd, ax_bytes, q4_bytes = 0;
    if (!affect_mul_size(p, (size_t)d, &pd) ||
        ((flags & FLAG_Q4)
             ? !affect_q4_size((size_t)d, &q4_bytes) || !affect_mul_size(p, q4_bytes, &ax_bytes)
             : !affect_mul_size(pd, width, &ax_bytes)) ||
        !affect_br_has(r, ax_bytes, 1))
        return affect_fail(err, AFFECT_ERR_FORMAT, "sPCA: truncated in the axes (offset %zu)",
                           ax_off);
    affect_br_bytes(r, &axes, ax_bytes);
    size_t sum_off = r->off;
    uint64_t sum;
    if (!affect_br_u64(r, &sum))
        return affect_fail(err, AFFECT_ERR_FORMAT, "sPCA: truncated in the checksum (offset %zu)",
                           sum_off);
    if (affect_fnv1a64(r->data + start, sum_off - start) != sum)
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "sPCA: checksum mismatch, the record is corrupt (offset %zu)", sum_off);
    affect_spca *s = model_alloc(p, (size_t)d);
    if (!s)
        return affect_nomem(err);
    affect_br sub;
    affect_br_init(&sub, eig, (size_t)p * 8);
    affect_br_f64s(&sub, s->eigenvalues, p);
    affect_br_init(&sub, axes, ax_bytes);
    affect_status st = AFFECT_OK;
    if (flags & FLAG_Q4) {
        for (uint32_t q = 0; q < p && st == AFFECT_OK; q++) {
            size_t bad, at = sub.off;
            if (!affect_q4_read(&sub, s->axes + (size_t)q * d, (size_t)d, &bad))
                st = affect_fail(err, AFFECT_ERR_FORMAT,
                                 "sPCA: axis %" PRIu32 " is not a canonical 4-bit form "
                                 "(offset %zu)",
                                 q, ax_off + at + bad);
        }
    } else if (width == 8) {
        affect_br_f64s(&sub, s->axes, pd);
    } else {
        for (size_t i = 0; i < pd; i++) {
            float f;
            affect_br_f32s(&sub, &f, 1);
            s->axes[i] = f;
        }
    }
    s->f32 = (flags & FLAG_F32) != 0;
    s->q4 = (flags & FLAG_Q4) != 0;
    for (uint32_t q = 0; q < p && st == AFFECT_OK; q++) {
        double v = s->eigenvalues[q];
        if (!(v > 0 && isfinite(v)))
            st = affect_fail(err, AFFECT_ERR_FORMAT,
                             "sPCA: eigenvalue %" PRIu32 " is not a positive finite number "
                             "(offset %zu)",
                             q, eig_off + (size_t)q * 8);
        else if (q > 0 && v > s->eigenvalues[q - 1])
            st = affect_fail(err, AFFECT_ERR_FORMAT,
                             "sPCA: eigenvalue %" PRIu32 " exceeds eigenvalue %" PRIu32
                             " (offset %zu)",
                             q, q - 1, eig_off + (size_t)q * 8);
    }
    for (size_t i = 0; i < pd && st == AFFECT_OK; i++)
        if (!isfinite(s->axes[i]))
            st = affect_fail(err, AFFECT_ERR_FORMAT,
                             "sPCA: non-finite value in the axes (offset %zu)", ax_off + i * width);
    if (st != AFFECT_OK) {
        affect_spca_free(s);
        return st;
    }
    s->kernel = (affect_spca_kernel)kernel;
    s->sigma = sigma;
    s->classes = c;
    s->n_train = n;
    *out = s;
    return AFFECT_OK;
}

/* ---- kernels and the HSIC ---- */

affect_status affect_spca_label_kernel(const uint32_t *y, size_t n, uint32_t c,
                                       affect_spca_kernel kernel, double sigma, double *b,
                                       affect_error *err)
{
    affect_status st = check_kernel(kernel, sigma, err);
    if (st != AFFECT_OK)
        return st;
    if (c == 0)
        return affect_fail(err, AFFECT_ERR_INVALID, "need at least 1 class");
    if ((st = check_labels(y, n, c, "", err)) != AFFECT_OK)
        return st;
    for (size_t i = 0; i < n; i++)
        for (size_t j = 0; j < n; j++) {
            double v;
            if (kernel == AFFECT_SPCA_LINEAR) {
                v = y[i] == y[j] ? 1.0 : 0.0;
            } else {
                double diff = (double)y[i] - (double)y[j];
                v = exp(-diff * diff / (2.0 * sigma * sigma));
            }
            b[i * n + j] = v;
        }
    return AFFECT_OK;
}

double affect_hsic(const double *k, const double *b, size_t n)
{
    if (n < 2)
        return 0.0;
    size_t nn = n * n;
    double mk = 0.0, mb = 0.0;
    for (size_t i = 0; i < nn; i++) {
        mk += k[i];
        mb += b[i];
    }
    mk /= (double)nn;
    mb /= (double)nn;
    /* with K' = K − mk, B' = B − mb: tr(K'B'), Σ_i row_i(K') col_i(B'), Σ_i col_i(K') row_i(B'),
     * Σ K', Σ B' */
    double s1 = 0.0, s2 = 0.0, s3 = 0.0, tk = 0.0, tb = 0.0;
    for (size_t i = 0; i < n; i++) {
        double rk = 0.0, cb = 0.0, ck = 0.0, rb = 0.0;
        for (size_t j = 0; j < n; j++) {
            s1 += (k[i * n + j] - mk) * (b[j * n + i] - mb);
            rk += k[i * n + j] - mk;
            ck += k[j * n + i] - mk;
            rb += b[i * n + j] - mb;
            cb += b[j * n + i] - mb;
        }
        s2 += rk * cb;
        s3 += ck * rb;
        tk += rk;
        tb += rb;
    }
    double dn = (double)n;
    double tr = s1 - (s2 + s3) / dn + tk * tb / (dn * dn);
    return tr / ((dn - 1.0) * (dn - 1.0));
}

/* ---- k-nearest neighbours ---- */

affect_status affect_knn_classify(const double *train_z, const uint32_t *train_y, size_t n,
                                  uint32_t p, uint32_t c, const double *z, uint32_t k,
                                  uint32_t *label, uint32_t *votes, affect_error *err)
{
    if (n == 0)
        return affect_fail(err, AFFECT_ERR_INVALID, "no training points");
    if (p == 0)
        return affect_fail(err, AFFECT_ERR_INVALID, "the embedding has no dimensions");
    if (c == 0)
        return affect_fail(err, AFFECT_ERR_INVALID, "need at least 1 class");
    if (k == 0)
        return affect_fail(err, AFFECT_ERR_INVALID, "k must be at least 1");
    affect_status st = check_labels(train_y, n, c, "training ", err);
    if (st != AFFECT_OK)
        return st;
    for (size_t i = 0; i < n; i++)
        for (uint32_t q = 0; q < p; q++)
            if (!isfinite(train_z[i * p + q]))
                return affect_fail(err, AFFECT_ERR_INVALID,
                                   "training row %zu, coordinate %" PRIu32 ": non-finite value", i,
                                   q);
    for (uint32_t q = 0; q < p; q++)
        if (!isfinite(z[q]))
            return affect_fail(err, AFFECT_ERR_INVALID,
                               "query coordinate %" PRIu32 ": non-finite value", q);
    size_t kk = k < n ? k : n;
    size_t a[] = {kk, kk, c, c};
    size_t sz[] = {sizeof(double), sizeof(size_t), sizeof(double), sizeof(uint32_t)};
    size_t bytes;
    if (!sum_products(a, sz, 4, &bytes))
        return affect_nomem(err);
    unsigned char *mem = affect_malloc(bytes);
    if (!mem)
        return affect_nomem(err);
    double *dist = (double *)mem;             /* the kk best squared distances, ascending */
    size_t *idx = (size_t *)(dist + kk);      /* their training rows */
    double *sums = (double *)(idx + kk);      /* per class: summed distances of the voters */
    uint32_t *count = (uint32_t *)(sums + c); /* per class: votes */
    size_t have = 0;
    for (size_t i = 0; i < n; i++) {
        const double *t = train_z + i * p;
        double d2 = 0.0;
        for (uint32_t q = 0; q < p; q++) {
            double e = t[q] - z[q];
            d2 += e * e;
        }
        if (have == kk && !(d2 < dist[kk - 1]))
            continue; /* an equal distance keeps the earlier row */
        size_t j = have < kk ? have++ : kk - 1;
        for (; j > 0 && dist[j - 1] > d2; j--) {
            dist[j] = dist[j - 1];
            idx[j] = idx[j - 1];
        }
        dist[j] = d2;
        idx[j] = i;
    }
    memset(sums, 0, c * sizeof *sums);
    memset(count, 0, c * sizeof *count);
    for (size_t j = 0; j < kk; j++) {
        uint32_t cl = train_y[idx[j]];
        count[cl]++;
        sums[cl] += sqrt(dist[j]);
    }
    uint32_t best = 0;
    for (uint32_t cl = 1; cl < c; cl++)
        if (count[cl] > count[best] || (count[cl] == count[best] && sums[cl] < sums[best]))
            best = cl;
    *label = best;
    if (votes)
        memcpy(votes, count, c * sizeof *count);
    affect_free(mem);
    return AFFECT_OK;
}
