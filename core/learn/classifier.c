/*
 * classifier.c — the hybrid recognizer of affect/classifier.h: class HMMs → Fisher scores →
 * normalization → linear SVM, and sPCA → kNN; maximum likelihood alongside.
 *
 * Usage: see the block at the top of affect/classifier.h (compiled by the style/header-usage test).
 *
 * How it works. Training (train_on) never holds the n × D matrix of representations (D = C ×
 * the per-HMM score dimension + the descriptors): it computes it block by block (one class
 * HMM's scores of every motion, or the descriptors; held in slabs of rows of at most 1 GiB,
 * block_rows), adds each normalized block to the n × n
 * Gram matrix, fits C, the SVM, the grid and the sPCA in the dual, then computes the blocks again
 * for the SVM's weights and the sPCA's axes. With mirror images (affect_classifier_train) the
 * training set is first doubled. The classifier keeps the HMMs, the normalization (mean and
 * scale per dimension), the SVM's one-vs-one weight vectors, the sPCA axes and the training
 * coordinates — O(D) doubles, not O(n D). Evaluation computes the sequence's score under each
 * HMM into one D-vector (then its descriptors), normalizes it exactly as training did and
 * applies the SVM and the projection.
 *
 * The binary form, version 2 (little-endian, util/bytes.h; version 1 lacks the three fields
 * after knn_k and is read as descriptors 0, weight 1, no mirror images):
 *     "AFCL", u32 version, u32 flags (0)
 *     u32 C, C × (u32 length, bytes) labels
 *     u32 groups, u8 zscore, f64 score_clip, f64 svm_c, u32 svm_folds, u32 spca_dims, u8 kernel,
 * f64 sigma, u32 knn_k (the chosen values when a grid was searched) u32 descriptors, f64
 * descriptor_weight, u8 mirror u32 grid n_dims, n_sigma, n_k, folds; the lists (u32, f64, u32); f64
 * grid CV accuracy f64 C used, f64 its inner CV accuracy, f64 × 3 training accuracies (ML, SVM,
 * kNN) C × (u64 length, the class HMM's model BLOB) u64 D, D × f64 mean, D × f64 scale the SVM
 * (affect_svm_encode), the sPCA (affect_spca_encode) u32 n, n × u32 training labels, n × p × f64
 * training coordinates u64 FNV-1a 64 of every byte before it Every HMM BLOB carries the feature
 * definition; the decoder requires them to be identical and keeps the first. Version 3, the compact
 * storage (make_compact; "storage" of affect/classifier.h): each class HMM as u8 form, u64 length,
 * bytes (form 1: covariances as lower triangles, no checksum); the mean and scale as 24-bit floats;
 * the SVM record's version 3 and the sPCA record's flag 2 (4-bit blocks, util/quant.h). Version 2
 * is still written for the float32 storage.
 */
#include "affect/classifier.h"

#include <cblas.h>
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "util/bytes.h"
#include "affect/hmm_blob.h"
#include "util/quant.h"
#include "util/internal.h"

struct affect_classifier {
    affect_classifier_config cfg;
    uint32_t n_classes;
    char **labels;
    affect_features *feat;
    affect_hmm **hmms;
    size_t part;   /* Fisher entries per class HMM */
    size_t fdim;   /* n_classes × part: the Fisher block */
    uint32_t ddim; /* descriptors appended after it */
    double desc_w; /* ω, the descriptor block's factor */
    size_t dim;    /* fdim + ddim */
    double *mean, *scale;
    bool compact; /* the compact storage (version 3): mean and scale are 24-bit floats */
    affect_svm *svm;
    affect_spca *spca;
    uint32_t n_train;
    uint32_t *train_y;
    double *train_z; /* n_train × p */
    affect_classifier_report report;
};

void affect_classifier_config_default(affect_classifier_config *cfg)
{
    memset(cfg, 0, sizeof *cfg);
    affect_hmm_config_default(&cfg->hmm);
    /* the recognizer's measured best (docs/EVALUATION.md, "Choosing the defaults") */
    cfg->hmm.n_states = 5;
    cfg->hmm.n_mix = 1;
    cfg->hmm.cov = AFFECT_HMM_DIAG;
    cfg->hmm.max_iter = 20;
    cfg->groups = AFFECT_FISHER_ALL;
    cfg->zscore = true;
    cfg->svm_c = 0.0;
    cfg->svm_folds = 5;
    cfg->spca_dims = 3;
    cfg->spca_kernel = AFFECT_SPCA_RBF;
    cfg->spca_sigma = 0.25;
    cfg->knn_k = 5;
    cfg->score_clip = 5.0;
    cfg->grid.folds = 5;
    cfg->descriptors = AFFECT_DESC_KINEMATICS;
    cfg->descriptor_weight = 0.1;
    cfg->mirror = AFFECT_MIRROR_AUTO;
    cfg->threads = 1;
}

void affect_classifier_free(affect_classifier *c)
{
    if (!c)
        return;
    for (uint32_t k = 0; c->labels && k < c->n_classes; k++)
        affect_free(c->labels[k]);
    affect_free(c->labels);
    for (uint32_t k = 0; c->hmms && k < c->n_classes; k++)
        affect_hmm_free(c->hmms[k]);
    affect_free(c->hmms);
    affect_features_free(c->feat);
    affect_free(c->mean);
    affect_free(c->scale);
    affect_svm_free(c->svm);
    affect_spca_free(c->spca);
    affect_free(c->train_y);
    affect_free(c->train_z);
    affect_free(c);
}

/* A copy of a feature definition (through its binary form). */
static affect_status copy_features(const affect_features *f, affect_features **out,
                                   affect_error *err)
{
    size_t size;
    if (!affect_features_encoded_size(f, &size))
        return affect_nomem(err);
    unsigned char *buf = affect_malloc(size);
    if (!buf)
        return affect_nomem(err);
    affect_features_encode_into(f, buf);
    affect_status st = affect_features_decode(buf, size, out, err);
    affect_free(buf);
    return st;
}

/* Allocates c with room for n_classes labels and HMMs (all NULL). */
static affect_classifier *alloc_classifier(uint32_t n_classes)
{
    affect_classifier *c = affect_calloc(1, sizeof *c);
    if (!c)
        return NULL;
    c->n_classes = n_classes;
    c->labels = affect_calloc(n_classes, sizeof *c->labels);
    c->hmms = affect_calloc(n_classes, sizeof *c->hmms);
    if (!c->labels || !c->hmms) {
        affect_classifier_free(c);
        return NULL;
    }
    return c;
}

const char *affect_classifier_config_check(const affect_classifier_config *cfg)
{
    if (cfg->groups == 0 || (cfg->groups & ~(unsigned)AFFECT_FISHER_ALL) != 0)
        return "groups must be a non-empty combination of start, transitions, weights, means, "
               "covariances";
    if (!(cfg->svm_c >= 0) || !isfinite(cfg->svm_c))
        return "svm_c must be a positive finite number, or 0 to choose it by cross-validation";
    if (!(cfg->score_clip >= 0) || !isfinite(cfg->score_clip))
        return "score_clip must be a finite number, 0 or more (0: no limit)";
    if (cfg->svm_folds < 2)
        return "svm_folds must be at least 2";
    if (cfg->spca_dims < 1)
        return "spca_dims must be at least 1";
    if (cfg->spca_kernel != AFFECT_SPCA_LINEAR && cfg->spca_kernel != AFFECT_SPCA_RBF)
        return "spca_kernel must be linear or rbf";
    if (!(cfg->spca_sigma > 0) || !isfinite(cfg->spca_sigma))
        return "spca_sigma must be a positive finite number";
    if (cfg->knn_k < 1)
        return "knn_k must be at least 1";
    if (cfg->descriptors != 0 && affect_descriptors_dim(cfg->descriptors) == 0)
        return "descriptors must be a combination of kinematics and laban";
    if (!(cfg->descriptor_weight > 0) || !isfinite(cfg->descriptor_weight))
        return "descriptor_weight must be a positive finite number";
    if (cfg->mirror != AFFECT_MIRROR_OFF && cfg->mirror != AFFECT_MIRROR_ON &&
        cfg->mirror != AFFECT_MIRROR_AUTO)
        return "mirror must be off, on or auto";
    if (cfg->threads < 1 || cfg->threads > 64)
        return "threads must be from 1 to 64";
    if (cfg->storage != AFFECT_STORAGE_AUTO && cfg->storage != AFFECT_STORAGE_FLOAT32 &&
        cfg->storage != AFFECT_STORAGE_COMPACT)
        return "storage must be auto, float32 or compact";
    const affect_classifier_grid *g = &cfg->grid;
    if (g->n_dims > AFFECT_CLASSIFIER_GRID_MAX || g->n_sigma > AFFECT_CLASSIFIER_GRID_MAX ||
        g->n_k > AFFECT_CLASSIFIER_GRID_MAX)
        return "grid lists must have at most 128 values";
    if (g->folds < 2)
        return "grid folds must be at least 2";
    for (uint32_t i = 0; i < g->n_dims; i++)
        if (g->dims[i] < 1)
            return "grid spca_dims must be whole numbers of at least 1";
    for (uint32_t i = 0; i < g->n_sigma; i++)
        if (!(g->sigma[i] > 0) || !isfinite(g->sigma[i]))
            return "grid spca_sigma must be positive finite numbers";
    for (uint32_t i = 0; i < g->n_k; i++)
        if (g->k[i] < 1)
            return "grid knn_k must be whole numbers of at least 1";
    return affect_hmm_config_check(&cfg->hmm);
}

/* The sizes of the representation: the Fisher block, the descriptors and ω; false when the
 * sizes overflow. */
static bool set_dims(affect_classifier *c)
{
    c->part = affect_fisher_dim(&c->cfg.hmm, c->cfg.groups);
    c->ddim = c->cfg.descriptors ? affect_descriptors_dim(c->cfg.descriptors) : 0;
    c->desc_w =
        c->ddim ? sqrt(c->cfg.descriptor_weight * (double)c->part * c->n_classes / c->ddim) : 1.0;
    return affect_mul_size(c->part, c->n_classes, &c->fdim) &&
           affect_add_size(c->fdim, c->ddim, &c->dim);
}

/* The Fisher scores of x under class HMM k into out (part values), its log-likelihood into
 * *ll (ll may be NULL). */
static affect_status score_part(const affect_classifier *c, uint32_t k, const double *x, uint32_t T,
                                double *out, double *ll, affect_monitor *mon, affect_error *err)
{
    if (affect_fisher_score(c->hmms[k], x, T, c->cfg.groups, out, ll, mon, err))
        return affect_prefix(err, "Fisher score under the HMM of class \"%s\"", c->labels[k]);
    for (size_t e = 0; e < c->part; e++) {
        if (isnan(out[e]))
            return affect_fail(err, AFFECT_ERR_RANGE,
                               "Fisher score under class \"%s\" is not a number (entry %zu)",
                               c->labels[k], e);
        if (isinf(out[e])) /* Σ ξ / a_il with a_il subnormal: the largest finite value */
            out[e] = out[e] > 0 ? DBL_MAX : -DBL_MAX;
    }
    return AFFECT_OK;
}

/* desc (ddim values) into out, each checked. */
static affect_status copy_descriptors(const affect_classifier *c, const double *desc, double *out,
                                      affect_error *err)
{
    for (uint32_t e = 0; e < c->ddim; e++) {
        if (!isfinite(desc[e]))
            return affect_fail(err, AFFECT_ERR_INVALID, "descriptor %u is not finite", e);
        out[e] = desc[e];
    }
    return AFFECT_OK;
}

/* The raw representation of x (and its descriptors desc) into f (dim): the Fisher scores under
 * every class HMM, then the descriptors; the log-likelihoods into ll (n_classes). */
static affect_status represent(const affect_classifier *c, const double *x, uint32_t T,
                               const double *desc, double *f, double *ll, affect_monitor *mon,
                               affect_error *err)
{
    affect_status st = copy_descriptors(c, desc, f + c->fdim, err);
    for (uint32_t k = 0; k < c->n_classes && st == AFFECT_OK; k++)
        st = score_part(c, k, x, T, f + (size_t)k * c->part, &ll[k], mon, err);
    return st;
}

static uint32_t argmax(const double *v, uint32_t n)
{
    uint32_t best = 0;
    for (uint32_t k = 1; k < n; k++)
        if (v[k] > v[best])
            best = k;
    return best;
}

/* v limited to [−limit, limit] (limit 0: unchanged). */
static double clip(double v, double limit)
{
    if (limit > 0)
        return v > limit ? limit : v < -limit ? -limit : v;
    return v;
}

/* ---- the representation block by block ----
 * Block b < C is the Fisher part under class HMM b (columns b · part ..), block C the
 * descriptors (columns fdim ..). Training never holds more than one block of n rows. */

static size_t block_width(const affect_classifier *c, uint32_t b)
{
    return b < c->n_classes ? c->part : c->ddim;
}

static size_t block_col0(const affect_classifier *c, uint32_t b)
{
    return b < c->n_classes ? (size_t)b * c->part : c->fdim;
}

static uint32_t block_count(const affect_classifier *c)
{
    return c->n_classes + (c->ddim ? 1 : 0);
}

/* The rows of a block of the representation (n rows of w values) held in slabs of whole rows,
 * each one allocation of at most cfg.slab_bytes (AFFECT_CLASSIFIER_SLAB_BYTES): the block is
 * n × 95,333 values at the thesis's configuration, 3.1 GB for 2,016 motions and their mirror
 * images, and SQLite refuses any single allocation of 2 GiB or more. Slab s holds rows
 * s·per .. s·per + per − 1, row-major with the current block's width (at most the widest
 * block's, which sized the slabs). With one slab (whenever the block fits in one) every
 * product is the one cblas call on one array, as before slabs existed, and gives the same
 * bits. */
typedef struct block_rows {
    double **slab; /* n_slabs allocations */
    uint32_t n_slabs, per;
    double **row; /* n pointers: row i of the current block */
    double *cols; /* several slabs: n × cols_w, a band of columns for the SVM and sPCA */
    size_t cols_w;
} block_rows;

static void rows_free(block_rows *R)
{
    for (uint32_t s = 0; R->slab && s < R->n_slabs; s++)
        affect_free(R->slab[s]);
    affect_free(R->slab);
    affect_free(R->row);
    affect_free(R->cols);
    memset(R, 0, sizeof *R);
}

/* Slabs of at most slab bytes (0: AFFECT_CLASSIFIER_SLAB_BYTES) for n rows of up to widest
 * values (n, widest ≥ 1, n × widest checked by the caller). */
static affect_status rows_alloc(block_rows *R, uint32_t n, size_t widest, size_t slab,
                                affect_error *err)
{
    memset(R, 0, sizeof *R);
    if (slab == 0)
        slab = AFFECT_CLASSIFIER_SLAB_BYTES;
    size_t per = slab / sizeof(double) / widest;
    if (per < 1)
        per = 1;
    if (per > n)
        per = n;
    R->per = (uint32_t)per;
    R->n_slabs = (uint32_t)((n + per - 1) / per);
    R->slab = affect_calloc(R->n_slabs, sizeof *R->slab);
    R->row = affect_malloc_array(n, sizeof *R->row);
    if (!R->slab || !R->row)
        return affect_nomem(err);
    for (uint32_t s = 0; s < R->n_slabs; s++) {
        size_t rows = s + 1 < R->n_slabs ? per : n - (size_t)s * per;
        R->slab[s] = affect_malloc_array(rows * widest, sizeof(double));
        if (!R->slab[s] && R->n_slabs == 1)
            return affect_nomem_of(err, rows * widest, sizeof(double),
                                   "the %u x %zu block of Fisher scores", n, widest);
        if (!R->slab[s])
            return affect_nomem_of(err, rows * widest, sizeof(double),
                                   "rows %zu .. %zu of the %u x %zu block of Fisher scores",
                                   (size_t)s * per, (size_t)s * per + rows - 1, n, widest);
    }
    if (R->n_slabs > 1) { /* a band of whole columns, also at most a slab's size */
        R->cols_w = slab / sizeof(double) / n;
        if (R->cols_w < 1)
            R->cols_w = 1;
        if (R->cols_w > widest)
            R->cols_w = widest;
        R->cols = affect_malloc_array((size_t)n * R->cols_w, sizeof(double));
        if (!R->cols)
            return affect_nomem_of(err, (size_t)n * R->cols_w, sizeof(double),
                                   "a %u x %zu band of Fisher scores", n, R->cols_w);
    }
    return AFFECT_OK;
}

/* Points R->row at the rows of a block of width w. */
static void rows_set(block_rows *R, uint32_t n, size_t w)
{
    for (uint32_t i = 0; i < n; i++)
        R->row[i] = R->slab[i / R->per] + (size_t)(i % R->per) * w;
}

/* G (n × n, upper triangle) += B Bᵀ for rows r0 .. r1 − 1 of G and the block's columns k0 ..
 * k1 − 1 (B row-major, width w): per slab the band's product with its own later rows (dsyrk on
 * the diagonal, dgemm beside it) and with the later slabs' rows (dgemm). */
static void gram_piece(const block_rows *R, uint32_t n, size_t w, size_t r0, size_t r1, size_t k0,
                       size_t k1, double *G)
{
    size_t a = r0 / R->per, end_a = (a + 1) * (size_t)R->per < n ? (a + 1) * (size_t)R->per : n;
    int K = (int)(k1 - k0), lda = (int)w, ldg = (int)n, m = (int)(r1 - r0);
    const double *band = R->row[r0] + k0;
    AFFECT_BLAS(cblas_dsyrk(CblasRowMajor, CblasUpper, CblasNoTrans, m, K, 1.0, band, lda, 1.0,
                            G + r0 * n + r0, ldg));
    if (r1 < end_a)
        AFFECT_BLAS(cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasTrans, m, (int)(end_a - r1), K,
                                1.0, band, lda, R->row[r1] + k0, lda, 1.0, G + r0 * n + r1, ldg));
    for (size_t ib = end_a; ib < n; ib += R->per) {
        size_t nb = n - ib < R->per ? n - ib : R->per;
        AFFECT_BLAS(cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasTrans, m, (int)nb, K, 1.0, band,
                                lda, R->row[ib] + k0, lda, 1.0, G + r0 * n + ib, ldg));
    }
}

/* G (n × n, upper triangle) += B Bᵀ for the current block (width w). A product of up to
 * GRAM_WHOLE_FLOPS multiply-adds is one piece per slab (the results of the small trainings are
 * those of earlier versions to the bit); a larger one (thousands of motions at the thesis's
 * configuration: 4,032 × 95,333 is 1.5e12, half a minute) goes in pieces of GRAM_ROWS rows and
 * GRAM_COLS columns, with a poll of mon between them, so that it stops when asked. */
#define GRAM_WHOLE_FLOPS 2e9
#define GRAM_ROWS 256
#define GRAM_COLS 1024

static affect_status rows_gram(const block_rows *R, uint32_t n, size_t w, double *G,
                               affect_monitor *mon, affect_error *err)
{
    bool whole = (double)n * n * (double)w <= GRAM_WHOLE_FLOPS;
    size_t rows = whole ? R->per : GRAM_ROWS, cols = whole ? w : GRAM_COLS;
    for (size_t k0 = 0; k0 < w; k0 += cols) {
        size_t k1 = w - k0 < cols ? w : k0 + cols;
        for (size_t r0 = 0; r0 < n;) {
            size_t slab_end = (r0 / R->per + 1) * (size_t)R->per;
            size_t r1 = r0 + rows < slab_end ? r0 + rows : slab_end;
            r1 = r1 < n ? r1 : n;
            affect_status st = affect_monitor_check(mon, err);
            if (st)
                return st;
            gram_piece(R, n, w, r0, r1, k0, k1, G);
            r0 = r1;
        }
    }
    return AFFECT_OK;
}

/* Fits the normalization of the columns of a block (n rows of w values, starting at column
 * col0; B[i] is row i). Per column the values are first divided by their largest magnitude a
 * (Fisher scores of tiny probabilities reach 1e200 and more, whose sums of squares would
 * overflow): with u = f / a, mean = a · mean(u) and scale = a · sd(u) (population). A column
 * that is constant over the training set (sd 0) keeps scale 1. Without z-scores: mean 0,
 * scale 1. */
static affect_status fit_block(affect_classifier *c, const double *const *B, uint32_t n, size_t w,
                               size_t col0, affect_error *err)
{
    for (size_t e = 0; e < w; e++) {
        if (e % 256 == 0 && affect_monitor_stopped(c->cfg.hmm.monitor))
            return affect_monitor_check(c->cfg.hmm.monitor, err);
        double *mean = &c->mean[col0 + e], *scale = &c->scale[col0 + e];
        *mean = 0.0;
        *scale = 1.0;
        if (!c->cfg.zscore)
            continue;
        double a = 0.0, mu = 0.0, var = 0.0;
        for (uint32_t i = 0; i < n; i++)
            if (fabs(B[i][e]) > a)
                a = fabs(B[i][e]);
        if (a == 0.0)
            continue; /* all 0: mean 0, scale 1 */
        for (uint32_t i = 0; i < n; i++)
            mu += B[i][e] / a;
        mu /= n;
        for (uint32_t i = 0; i < n; i++) {
            double d = B[i][e] / a - mu;
            var += d * d;
        }
        double sd = sqrt(var / n), s = sd * a;
        *mean = mu * a;
        if (sd > 0 && s > 0 && isfinite(s))
            *scale = s;
    }
    return AFFECT_OK;
}

/* The normalization of the representation's entries e0 .. e0 + w − 1 in place (v: w values):
 * z-scores limited to ±score_clip, and the descriptors times ω — exactly as evaluation does. */
static void normalize(const affect_classifier *c, double *v, size_t w, size_t e0)
{
    if (c->cfg.zscore)
        for (size_t e = 0; e < w; e++)
            v[e] = clip((v[e] - c->mean[e0 + e]) / c->scale[e0 + e], c->cfg.score_clip);
    if (e0 + w > c->fdim)
        for (size_t e = e0 < c->fdim ? c->fdim - e0 : 0; e < w; e++)
            v[e] *= c->desc_w;
}

/* Leave-one-out kNN accuracy over the training coordinates. */
static affect_status loo_knn(const affect_classifier *c, double *acc, affect_error *err)
{
    uint32_t n = c->n_train, p = affect_spca_dims(c->spca);
    if (n < 2) {
        *acc = NAN;
        return AFFECT_OK;
    }
    double *z = affect_malloc_array((size_t)(n - 1) * p, sizeof *z);
    uint32_t *y = affect_malloc_array(n - 1, sizeof *y);
    affect_status st = AFFECT_OK;
    if (!z || !y) {
        st = affect_nomem(err);
        goto done;
    }
    uint32_t hits = 0;
    for (uint32_t i = 0; i < n; i++) {
        for (uint32_t j = 0, o = 0; j < n; j++) {
            if (j == i)
                continue;
            memcpy(z + (size_t)o * p, c->train_z + (size_t)j * p, p * sizeof *z);
            y[o++] = c->train_y[j];
        }
        uint32_t label;
        st = affect_knn_classify(z, y, n - 1, p, c->n_classes, c->train_z + (size_t)i * p,
                                 c->cfg.knn_k, &label, NULL, err);
        if (st)
            goto done;
        hits += label == c->train_y[i];
    }
    *acc = (double)hits / n;
done:
    affect_free(z);
    affect_free(y);
    return st;
}

/* The grid's candidate lists (a list left empty: the configuration's value). */
typedef struct grid_lists {
    uint32_t n_dims, n_sigma, n_k, max_dims;
    const uint32_t *dims, *k;
    const double *sigma;
} grid_lists;

static void grid_lists_of(const affect_classifier_config *cfg, grid_lists *g)
{
    const affect_classifier_grid *gr = &cfg->grid;
    g->n_dims = gr->n_dims ? gr->n_dims : 1;
    g->dims = gr->n_dims ? gr->dims : &cfg->spca_dims;
    g->n_sigma = cfg->spca_kernel == AFFECT_SPCA_RBF && gr->n_sigma ? gr->n_sigma : 1;
    g->sigma = cfg->spca_kernel == AFFECT_SPCA_RBF && gr->n_sigma ? gr->sigma : &cfg->spca_sigma;
    g->n_k = gr->n_k ? gr->n_k : 1;
    g->k = gr->n_k ? gr->k : &cfg->knn_k;
    g->max_dims = 0;
    for (uint32_t i = 0; i < g->n_dims; i++)
        if (g->dims[i] > g->max_dims)
            g->max_dims = g->dims[i];
}

/* Scratch of the grid search (everything n × n at most: the search works on the Gram matrix). */
typedef struct grid_ws {
    uint32_t *fold_of, *tr_y, *te_y;
    double *sub_gram, *te_k, *tr_z, *te_z, *tr_p, *te_p;
    uint32_t *hits; /* n_dims × n_sigma × n_k */
} grid_ws;

static void grid_ws_free(grid_ws *w)
{
    affect_free(w->fold_of);
    affect_free(w->tr_y);
    affect_free(w->te_y);
    affect_free(w->sub_gram);
    affect_free(w->te_k);
    affect_free(w->tr_z);
    affect_free(w->te_z);
    affect_free(w->tr_p);
    affect_free(w->te_p);
    affect_free(w->hits);
}

static bool grid_ws_alloc(grid_ws *w, uint32_t n, uint32_t max_dims, size_t combos)
{
    size_t nn, np;
    memset(w, 0, sizeof *w);
    if (!affect_mul_size(n, n, &nn) || !affect_mul_size(n, max_dims, &np))
        return false;
    w->fold_of = affect_malloc_array(n, sizeof *w->fold_of);
    w->tr_y = affect_malloc_array(n, sizeof *w->tr_y);
    w->te_y = affect_malloc_array(n, sizeof *w->te_y);
    w->sub_gram = affect_malloc_array(nn, sizeof *w->sub_gram);
    w->te_k = affect_malloc_array(nn, sizeof *w->te_k);
    w->tr_z = affect_malloc_array(np, sizeof *w->tr_z);
    w->te_z = affect_malloc_array(np, sizeof *w->te_z);
    w->tr_p = affect_malloc_array(np, sizeof *w->tr_p);
    w->te_p = affect_malloc_array(np, sizeof *w->te_p);
    w->hits = affect_calloc(combos, sizeof *w->hits);
    return w->fold_of && w->tr_y && w->te_y && w->sub_gram && w->te_k && w->tr_z && w->te_z &&
           w->tr_p && w->te_p && w->hits;
}

/* The first p of q coordinates of n rows, contiguous. */
static void prefix_rows(const double *z, uint32_t n, uint32_t q, uint32_t p, double *out)
{
    for (uint32_t i = 0; i < n; i++)
        memcpy(out + (size_t)i * p, z + (size_t)i * q, p * sizeof *out);
}

/* One inner fold: fits sPCA per σ on the other folds' rows of the Gram matrix G (dual) and
 * counts the kNN hits of every (dims, σ, k) on this fold's rows, whose coordinates are their
 * kernel rows times the dual coefficients. */
static affect_status grid_fold(const affect_classifier *c, const double *G, const uint32_t *y,
                               uint32_t n, uint32_t fold, const grid_lists *g, grid_ws *w,
                               affect_error *err)
{
    affect_status st0 = affect_monitor_check(c->cfg.hmm.monitor, err);
    if (st0)
        return st0;
    uint32_t n_tr = 0, n_te = 0;
    for (uint32_t i = 0; i < n; i++) {
        if (w->fold_of[i] == fold)
            w->te_y[n_te++] = y[i];
        else
            w->tr_y[n_tr++] = y[i];
    }
    if (n_te == 0 || n_tr == 0)
        return AFFECT_OK;
    for (uint32_t i = 0, a = 0, t = 0; i < n;
         i++) { /* rows: training, held out; columns: training */
        double *row =
            w->fold_of[i] == fold ? w->te_k + (size_t)t++ * n_tr : w->sub_gram + (size_t)a++ * n_tr;
        for (uint32_t j = 0, b = 0; j < n; j++)
            if (w->fold_of[j] != fold)
                row[b++] = G[(size_t)i * n + j];
    }
    for (uint32_t s = 0; s < g->n_sigma; s++) {
        affect_spca *sp = NULL;
        affect_status st = affect_monitor_check(c->cfg.hmm.monitor, err);
        if (st)
            return st;
        st = affect_spca_fit_dual(w->sub_gram, n_tr, c->dim, w->tr_y, c->n_classes,
                                  c->cfg.spca_kernel, g->sigma[s], g->max_dims, &sp, err);
        if (st)
            return st;
        uint32_t q = affect_spca_dims(sp);
        affect_spca_dual_embed(sp, w->sub_gram, n_tr, w->tr_z);
        affect_spca_dual_embed(sp, w->te_k, n_te, w->te_z);
        affect_spca_free(sp);
        for (uint32_t di = 0; di < g->n_dims; di++) {
            uint32_t p = g->dims[di] < q ? g->dims[di] : q;
            prefix_rows(w->tr_z, n_tr, q, p, w->tr_p);
            prefix_rows(w->te_z, n_te, q, p, w->te_p);
            for (uint32_t ki = 0; ki < g->n_k; ki++)
                for (uint32_t t = 0; t < n_te; t++) {
                    uint32_t label;
                    st = affect_knn_classify(w->tr_p, w->tr_y, n_tr, p, c->n_classes,
                                             w->te_p + (size_t)t * p, g->k[ki], &label, NULL, err);
                    if (st)
                        return st;
                    w->hits[((size_t)di * g->n_sigma + s) * g->n_k + ki] += label == w->te_y[t];
                }
        }
    }
    return AFFECT_OK;
}

/* Chooses spca_dims, spca_sigma and knn_k (into c->cfg) by inner cross-validation on the
 * training rows' Gram matrix G. */
static affect_status grid_search(affect_classifier *c, const double *G, const uint32_t *y,
                                 uint32_t n, affect_error *err)
{
    grid_lists g;
    grid_lists_of(&c->cfg, &g);
    size_t combos = (size_t)g.n_dims * g.n_sigma * g.n_k;
    grid_ws w;
    affect_status st;
    if (!grid_ws_alloc(&w, n, g.max_dims, combos)) {
        st = affect_nomem(err);
        goto done;
    }
    if ((st = affect_stratified_folds(y, n, c->n_classes, c->cfg.grid.folds, c->cfg.hmm.seed,
                                      w.fold_of, err)) != AFFECT_OK)
        goto done;
    for (uint32_t fold = 0; fold < c->cfg.grid.folds; fold++)
        if ((st = grid_fold(c, G, y, n, fold, &g, &w, err)) != AFFECT_OK)
            goto done;
    size_t best = 0;
    for (size_t e = 1; e < combos; e++)
        if (w.hits[e] > w.hits[best])
            best = e;
    c->cfg.knn_k = g.k[best % g.n_k];
    c->cfg.spca_sigma = g.sigma[best / g.n_k % g.n_sigma];
    c->cfg.spca_dims = g.dims[best / g.n_k / g.n_sigma];
    c->report.grid_cv_acc = (double)w.hits[best] / n;
done:
    grid_ws_free(&w);
    return st;
}

/* Steps 4 and 5 on the Gram matrix G (n × n) of the normalized rows: C, the SVM's dual, the
 * grid, the sPCA's dual and the training coordinates (signs fixed later, by
 * affect_spca_finish); the ML and SVM training accuracies. */
static affect_status fit_dual(affect_classifier *c, const double *G, const uint32_t *y, uint32_t n,
                              const double *ll, affect_error *err)
{
    const affect_classifier_config *cfg = &c->cfg;
    size_t D = c->dim;
    double C = cfg->svm_c, cv = NAN;
    if (C == 0) {
        static const double grid[] = AFFECT_CLASSIFIER_C_GRID;
        if (affect_svm_select_c_gram(G, n, D, y, c->n_classes, grid, sizeof grid / sizeof grid[0],
                                     cfg->svm_folds, cfg->hmm.seed, &C, &cv, cfg->hmm.monitor, err))
            return affect_prefix(err, "choosing the SVM's C");
    }
    affect_monitor_report(cfg->hmm.monitor, "SVM, sPCA grid and sPCA", 0, 3);
    affect_status st = affect_monitor_check(cfg->hmm.monitor, err);
    if (st)
        return st;
    if (affect_svm_train_gram(G, n, D, y, c->n_classes, C, &c->svm, err))
        return affect_prefix(err, "training the SVM");
    affect_monitor_report(cfg->hmm.monitor, "SVM, sPCA grid and sPCA", 1, 3);
    if ((st = affect_monitor_check(cfg->hmm.monitor, err)))
        return st;
    c->report.grid_cv_acc = NAN;
    const affect_classifier_grid *gr = &cfg->grid;
    if ((gr->n_dims || gr->n_sigma || gr->n_k) && grid_search(c, G, y, n, err))
        return affect_prefix(err, "searching the sPCA/kNN grid");
    affect_monitor_report(cfg->hmm.monitor, "SVM, sPCA grid and sPCA", 2, 3);
    if ((st = affect_monitor_check(cfg->hmm.monitor, err)))
        return st;
    if (affect_spca_fit_dual(G, n, D, y, c->n_classes, cfg->spca_kernel, cfg->spca_sigma,
                             cfg->spca_dims, &c->spca, err))
        return affect_prefix(err, "fitting the supervised PCA");
    affect_monitor_report(cfg->hmm.monitor, "SVM, sPCA grid and sPCA", 3, 3);
    uint32_t p = affect_spca_dims(c->spca);
    c->n_train = n;
    c->train_y = affect_malloc_array(n, sizeof *c->train_y);
    c->train_z = affect_malloc_array((size_t)n * p, sizeof *c->train_z);
    if (!c->train_y || !c->train_z)
        return affect_nomem(err);
    memcpy(c->train_y, y, n * sizeof *y);
    affect_spca_dual_embed(c->spca, G, n, c->train_z);
    uint32_t hit_ml = 0, hit_svm = 0;
    for (uint32_t i = 0; i < n; i++) {
        hit_ml += argmax(ll + (size_t)i * c->n_classes, c->n_classes) == y[i];
        hit_svm += affect_svm_predict_gram(c->svm, G + (size_t)i * n) == y[i];
    }
    c->report.svm_c = C;
    c->report.svm_cv_acc = cv;
    c->report.train_acc_ml = (double)hit_ml / n;
    c->report.train_acc_svm = (double)hit_svm / n;
    return AFFECT_OK;
}

/* The work of training shared by the threads (affect_parallel_for): every item writes only its
 * own class HMM, or its own row of the block B and of ll. */
typedef struct train_job {
    affect_classifier *c;
    const affect_hmm_seq *seqs;
    const uint32_t *y;
    uint32_t n;
    const double *desc;
    uint32_t block;        /* the block being computed */
    block_rows *B;         /* the block being computed, in slabs of rows */
    double *ll;            /* NULL: the second pass */
    affect_hmm_config hmm; /* the class HMMs' configuration: stopped with the call, silent */
} train_job;

/* Item k: the HMM of class k on its motions. */
static affect_status train_class(void *ctx, uint32_t k, affect_error *err)
{
    train_job *j = ctx;
    affect_hmm_seq *mine = affect_malloc_array(j->n ? j->n : 1, sizeof *mine);
    if (!mine)
        return affect_nomem(err);
    uint32_t count = 0;
    for (uint32_t i = 0; i < j->n; i++)
        if (j->y[i] == k)
            mine[count++] = j->seqs[i];
    affect_status st = affect_hmm_train(&j->hmm, mine, count, &j->c->hmms[k], err);
    affect_free(mine);
    if (st)
        return affect_prefix(err, "training the HMM of class \"%s\"", j->c->labels[k]);
    affect_monitor_step(j->c->cfg.hmm.monitor);
    return AFFECT_OK;
}

/* Item i: row i of the current block (raw). */
static affect_status block_row(void *ctx, uint32_t i, affect_error *err)
{
    train_job *j = ctx;
    const affect_classifier *c = j->c;
    double *row = j->B->row[i]; /* the block's width: block_width(c, j->block) */
    affect_status st = affect_monitor_check(c->cfg.hmm.monitor, err);
    if (st)
        return st;
    affect_monitor_step(c->cfg.hmm.monitor);
    st = j->block < c->n_classes
             ? score_part(c, j->block, j->seqs[i].x, j->seqs[i].n_frames, row,
                          j->ll ? &j->ll[(size_t)i * c->n_classes + j->block] : NULL,
                          c->cfg.hmm.monitor, err)
             : copy_descriptors(c, j->desc + (size_t)i * c->ddim, row, err);
    return st ? affect_prefix(err, "motion %u", i) : AFFECT_OK;
}

/* Block b of every training motion into j->B, normalized (the first pass also fits the
 * normalization of its columns). */
static affect_status compute_block(train_job *j, uint32_t b, bool fit, affect_error *err)
{
    affect_classifier *c = j->c;
    size_t w = block_width(c, b), col0 = block_col0(c, b);
    j->block = b;
    rows_set(j->B, j->n, w);
    affect_monitor_report(c->cfg.hmm.monitor,
                          fit ? "Fisher scores, first pass" : "Fisher scores, second pass",
                          (uint64_t)b * j->n, (uint64_t)block_count(c) * j->n);
    affect_status st =
        affect_parallel_for(j->n, c->cfg.threads, block_row, j, c->cfg.hmm.monitor, err);
    if (st)
        return st;
    if (fit && (st = fit_block(c, (const double *const *)j->B->row, j->n, w, col0, err)))
        return st;
    for (uint32_t i = 0; i < j->n; i++) {
        if (i % 64 == 0 && (st = affect_monitor_check(c->cfg.hmm.monitor, err)))
            return st;
        normalize(c, j->B->row[i], w, col0);
    }
    return AFFECT_OK;
}

/* Adds the current block (width w, the representation's columns col0 ..) to the SVM's weights
 * and the sPCA's axes: the one array of a single slab, else band after band of whole columns
 * copied into R->cols (every weight and axis entry sums over the rows of its own column, so
 * the bands give the same sums; the SVM's to the bit). */
static affect_status rows_add_weights(affect_classifier *c, const block_rows *R, uint32_t n,
                                      size_t w, size_t col0, affect_error *err)
{
    for (size_t e0 = 0; e0 < w; e0 += R->n_slabs == 1 ? w : R->cols_w) {
        size_t bw = w;
        const double *band = R->row[0];
        if (R->n_slabs > 1) {
            bw = w - e0 < R->cols_w ? w - e0 : R->cols_w;
            for (uint32_t i = 0; i < n; i++)
                memcpy(R->cols + (size_t)i * bw, R->row[i] + e0, bw * sizeof *R->cols);
            band = R->cols;
        }
        if (affect_svm_add_rows(c->svm, band, bw, col0 + e0, err))
            return affect_prefix(err, "the SVM's weights");
        affect_spca_add_rows(c->spca, band, bw, col0 + e0);
    }
    return AFFECT_OK;
}

/* The compact storage (affect_classifier_storage), made once the model is complete: the mean
 * and scale rounded to 24-bit floats (μ̃, σ̃), and the SVM's weights and the sPCA's axes
 * multiplied column by column by σ̃ / σ and rounded to 4-bit blocks (util/quant.h). Folding
 * the ratio keeps the linear maps what they were: w · (x − μ) / σ = (w σ̃ / σ) · (x − μ) / σ̃;
 * what remains is the mean's rounding (at most 2⁻¹³ |μ| / σ in z-units), the clipping at
 * ±score_clip σ̃ instead of σ (relative 2⁻¹³) and the 4-bit codes. When a value cannot be
 * rounded (a scale beyond float32's range: never seen), the model stays as it was and c->compact
 * false (the float32 storage follows). */
static affect_status make_compact(affect_classifier *c, affect_error *err)
{
    size_t D = c->dim;
    double *mean = affect_malloc_array(D, sizeof *mean), *scale = NULL, *factor = NULL;
    scale = affect_malloc_array(D, sizeof *scale);
    factor = affect_malloc_array(D, sizeof *factor);
    affect_status st = AFFECT_OK;
    if (!mean || !scale || !factor) {
        st =
            affect_nomem_of(err, D, 3 * sizeof *mean, "the compact normalization of %zu values", D);
        goto done;
    }
    for (size_t e = 0; e < D; e++) {
        mean[e] = affect_f24_round(c->mean[e]);
        scale[e] = affect_f24_round(c->scale[e]);
        if (!isfinite(mean[e]) || !isfinite(scale[e]) || !(scale[e] > 0))
            goto done; /* not representable: the float32 storage */
        factor[e] = scale[e] / c->scale[e];
    }
    if (!affect_svm_compact_fits(c->svm, factor) || !affect_spca_compact_fits(c->spca, factor))
        goto done;
    affect_svm_compact_weights(c->svm, factor);
    affect_spca_compact_axes(c->spca, factor);
    memcpy(c->mean, mean, D * sizeof *mean);
    memcpy(c->scale, scale, D * sizeof *scale);
    c->compact = true;
done:
    affect_free(mean);
    affect_free(scale);
    affect_free(factor);
    return st;
}

/* Training on the given set (the mirror images already added when asked). The representation
 * is never held whole: a first pass computes it block by block (one class HMM's Fisher scores,
 * or the descriptors, for every motion), fits each block's normalization and adds the block's
 * products to the Gram matrix G = Z Zᵀ; the SVM, the grid and the sPCA are fitted in the dual
 * on G; a second pass computes the blocks again (the same bits) and adds their columns to the
 * SVM's weights and the sPCA's axes. Memory: n² for G plus n × the largest block (in slabs of
 * at most AFFECT_CLASSIFIER_SLAB_BYTES, block_rows), against n × the whole representation
 * before (n × 667,331 doubles at the thesis's configuration). */
static affect_status train_on(const affect_classifier_config *cfg, const affect_features *feat,
                              const affect_hmm_seq *seqs, const double *desc, const uint32_t *y,
                              uint32_t n, const char *const *labels, uint32_t n_classes,
                              affect_classifier **out, affect_error *err)
{
    *out = NULL;
    const char *msg = affect_classifier_config_check(cfg);
    if (msg)
        return affect_fail(err, AFFECT_ERR_INVALID, "%s", msg);
    if (n_classes < 2 || n_classes > AFFECT_CLASSIFIER_MAX_CLASSES)
        return affect_fail(err, AFFECT_ERR_INVALID, "need 2 to %u classes, got %u",
                           AFFECT_CLASSIFIER_MAX_CLASSES, n_classes);
    if (cfg->hmm.dim != affect_features_dim(feat))
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "the HMM dimension %u is not the feature dimension %u", cfg->hmm.dim,
                           affect_features_dim(feat));
    for (uint32_t i = 0; i < n; i++)
        if (y[i] >= n_classes)
            return affect_fail(err, AFFECT_ERR_INVALID, "motion %u: class %u of %u classes", i,
                               y[i], n_classes);
    if (cfg->descriptors && !desc)
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "the configuration appends descriptors but none were given");
    affect_classifier *c = alloc_classifier(n_classes);
    block_rows B = {0};
    double *ll = NULL, *G = NULL;
    affect_status st;
    if (!c) {
        st = affect_nomem(err);
        goto done;
    }
    c->cfg = *cfg;
    for (uint32_t k = 0; k < n_classes; k++) {
        uint32_t count = 0;
        for (uint32_t i = 0; i < n; i++)
            count += y[i] == k;
        if (count == 0) {
            st = affect_fail(err, AFFECT_ERR_INVALID, "class \"%s\" has no training motion",
                             labels[k]);
            goto done;
        }
        /* the decoder refuses a label that is not UTF-8: never write one */
        st = affect_utf8_check(err, AFFECT_ERR_INVALID, labels[k], strlen(labels[k]),
                               "the label \"%.64s\" of class %u", labels[k], k);
        if (st)
            goto done;
        c->labels[k] = affect_strndup(labels[k], strlen(labels[k]));
        if (!c->labels[k]) {
            st = affect_nomem(err);
            goto done;
        }
    }
    affect_monitor child;
    train_job job = {c, seqs, y, n, desc, 0, NULL, NULL, cfg->hmm};
    job.hmm.monitor = affect_monitor_child(&child, cfg->hmm.monitor);
    affect_monitor_report(cfg->hmm.monitor, "class HMMs", 0, n_classes);
    if ((st = affect_parallel_for(n_classes, cfg->threads, train_class, &job, cfg->hmm.monitor,
                                  err)) != AFFECT_OK)
        goto done;
    if ((st = copy_features(feat, &c->feat, err)) != AFFECT_OK)
        goto done;
    size_t widest = 0, cells, nn;
    if (!set_dims(c)) {
        st = affect_nomem(err);
        goto done;
    }
    uint32_t blocks = block_count(c);
    for (uint32_t b = 0; b < blocks; b++)
        if (block_width(c, b) > widest)
            widest = block_width(c, b);
    if (!affect_mul_size(widest, n, &cells) || !affect_mul_size(n, n, &nn) || widest > INT_MAX ||
        n > INT_MAX) {
        st = affect_fail(err, AFFECT_ERR_RANGE, "%u motions of %zu-value blocks are too many", n,
                         widest);
        goto done;
    }
    if ((st = rows_alloc(&B, n ? n : 1, widest ? widest : 1, cfg->slab_bytes, err)) != AFFECT_OK)
        goto done;
    G = affect_calloc(nn ? nn : 1, sizeof *G);
    if (!G) {
        st = affect_nomem_of(err, nn, sizeof *G, "the %u x %u Gram matrix", n, n);
        goto done;
    }
    ll = affect_malloc_array((size_t)n * n_classes, sizeof *ll);
    c->mean = affect_malloc_array(c->dim, sizeof *c->mean);
    c->scale = affect_malloc_array(c->dim, sizeof *c->scale);
    if (!ll) {
        st = affect_nomem(err);
        goto done;
    }
    if (!c->mean || !c->scale) {
        st = affect_nomem_of(err, c->dim, sizeof *c->mean,
                             "the normalization's %zu-long mean or scale", c->dim);
        goto done;
    }
    job.B = &B;
    job.ll = ll;
    for (uint32_t b = 0; b < blocks; b++) { /* first pass: normalization and G */
        if ((st = compute_block(&job, b, true, err)) != AFFECT_OK)
            goto done;
        if ((st = rows_gram(&B, n, block_width(c, b), G, cfg->hmm.monitor, err)) != AFFECT_OK)
            goto done;
    }
    for (size_t i = 1; i < n; i++)
        for (size_t k = 0; k < i; k++)
            G[i * n + k] = G[k * n + i];
    if ((st = fit_dual(c, G, y, n, ll, err)) != AFFECT_OK)
        goto done;
    job.ll = NULL;
    for (uint32_t b = 0; b < blocks; b++) { /* second pass: the primal weights and axes */
        if ((st = compute_block(&job, b, false, err)) != AFFECT_OK)
            goto done;
        if ((st = rows_add_weights(c, &B, n, block_width(c, b), block_col0(c, b), err)) !=
            AFFECT_OK)
            goto done;
    }
    affect_spca_finish(c->spca, c->train_z, n);
    bool compact = cfg->storage == AFFECT_STORAGE_COMPACT ||
                   (cfg->storage == AFFECT_STORAGE_AUTO && c->dim >= AFFECT_CLASSIFIER_COMPACT_DIM);
    if (compact && (st = make_compact(c, err)) != AFFECT_OK)
        goto done;
    if (!c->compact) {
        /* the D-long vectors as float32 (half the BLOB; they act on z-scores of at most ±5, so
         * a decision value moves by about 1e-7 of its size); out of float32's range: float64 */
        affect_svm_round_weights(c->svm);
        affect_spca_round_axes(c->spca);
    }
    c->cfg.storage = c->compact ? AFFECT_STORAGE_COMPACT : AFFECT_STORAGE_FLOAT32;
    st = loo_knn(c, &c->report.train_acc_knn, err);
done:
    if (c)
        c->cfg.hmm.monitor = NULL; /* the caller's, for this call only */
    rows_free(&B);
    affect_free(G);
    affect_free(ll);
    if (st == AFFECT_OK)
        *out = c;
    else
        affect_classifier_free(c);
    return st;
}

affect_status affect_classifier_train(const affect_classifier_config *cfg,
                                      const affect_features *feat, const affect_hmm_seq *seqs,
                                      const double *desc, const uint32_t *y, uint32_t n,
                                      const char *const *labels, uint32_t n_classes,
                                      affect_classifier **out, affect_error *err)
{
    *out = NULL;
    const char *msg = affect_classifier_config_check(cfg);
    if (msg)
        return affect_fail(err, AFFECT_ERR_INVALID, "%s", msg);
    if (cfg->mirror == AFFECT_MIRROR_AUTO) { /* on when every observed joint has a partner */
        uint32_t *partner = affect_malloc_array(feat->n_joints, sizeof *partner);
        if (!partner)
            return affect_nomem(err);
        affect_error ignored;
        affect_classifier_config on = *cfg;
        on.mirror = affect_features_mirror_map(feat, partner, &ignored) == AFFECT_OK
                        ? AFFECT_MIRROR_ON
                        : AFFECT_MIRROR_OFF;
        affect_free(partner);
        return affect_classifier_train(&on, feat, seqs, desc, y, n, labels, n_classes, out, err);
    }
    if (cfg->mirror == AFFECT_MIRROR_OFF)
        return train_on(cfg, feat, seqs, desc, y, n, labels, n_classes, out, err);
    if (n > UINT32_MAX / 2)
        return affect_fail(err, AFFECT_ERR_RANGE, "too many motions to mirror: %u", n);
    if (cfg->hmm.dim != affect_features_dim(feat))
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "the HMM dimension %u is not the feature dimension %u", cfg->hmm.dim,
                           affect_features_dim(feat));
    if (cfg->descriptors && !desc)
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "the configuration appends descriptors but none were given");
    uint32_t dim = affect_features_dim(feat), dd = affect_descriptors_dim(cfg->descriptors);
    uint32_t *partner = affect_malloc_array(feat->n_joints, sizeof *partner);
    affect_hmm_seq *all = affect_calloc(2 * (size_t)n + 1, sizeof *all);
    uint32_t *y2 = affect_malloc_array(2 * (size_t)n + 1, sizeof *y2);
    double *desc2 = dd ? affect_malloc_array(2 * (size_t)n * dd, sizeof *desc2) : NULL;
    affect_status st = AFFECT_OK;
    if (!partner || !all || !y2 || (dd && !desc2)) {
        st = affect_nomem(err);
        goto done;
    }
    if ((st = affect_features_mirror_map(feat, partner, err)) != AFFECT_OK)
        goto done;
    for (uint32_t i = 0; i < n; i++) {
        size_t cells;
        double *x = NULL;
        if (affect_mul_size(seqs[i].n_frames, dim, &cells))
            x = affect_malloc_array(cells ? cells : 1, sizeof *x);
        if (!x) {
            st = affect_nomem(err);
            goto done;
        }
        affect_features_mirror(feat, partner, seqs[i].x, seqs[i].n_frames, x);
        all[i] = seqs[i];
        all[n + i].x = x;
        all[n + i].n_frames = seqs[i].n_frames;
        y2[i] = y2[n + i] = y[i];
        if (dd) {
            memcpy(desc2 + (size_t)i * dd, desc + (size_t)i * dd, dd * sizeof *desc2);
            affect_descriptors_mirror(cfg->descriptors, desc + (size_t)i * dd,
                                      desc2 + ((size_t)n + i) * dd);
        }
    }
    st = train_on(cfg, feat, all, desc2, y2, 2 * n, labels, n_classes, out, err);
done:
    for (uint32_t i = 0; all && i < n; i++)
        affect_free((void *)all[n + i].x);
    affect_free(all);
    affect_free(partner);
    affect_free(y2);
    affect_free(desc2);
    return st;
}

affect_status affect_classifier_eval(const affect_classifier *c, const double *x, uint32_t T,
                                     const double *desc, bool ml_only, affect_classifier_out *out,
                                     affect_monitor *mon, affect_error *err)
{
    uint32_t C = c->n_classes;
    double *ll = affect_malloc_array(C, sizeof *ll), *f = NULL;
    affect_status st = AFFECT_OK;
    if (!ll) {
        st = affect_nomem(err);
        goto done;
    }
    if (ml_only) {
        for (uint32_t k = 0; k < C; k++)
            if ((st = affect_hmm_loglik(c->hmms[k], x, T, &ll[k], mon, err)) != AFFECT_OK) {
                st = affect_prefix(err, "scoring under the HMM of class \"%s\"", c->labels[k]);
                goto done;
            }
    } else {
        f = out->fisher ? out->fisher : affect_malloc_array(c->dim, sizeof *f);
        if (!f) {
            st = affect_nomem(err);
            goto done;
        }
        if (c->ddim && !desc) {
            st = affect_fail(err, AFFECT_ERR_INVALID,
                             "the classifier appends descriptors but none were given");
            goto done;
        }
        if ((st = represent(c, x, T, desc, f, ll, mon, err)) != AFFECT_OK)
            goto done;
        normalize(c, f, c->dim, 0); /* as training's second pass */
        out->svm = affect_svm_predict(c->svm, f, out->decision);
        uint32_t p = affect_spca_dims(c->spca);
        double zbuf[64], *z = out->embed ? out->embed : zbuf;
        if (!out->embed && p > 64) {
            st = affect_fail(err, AFFECT_ERR_INVALID, "too many sPCA dimensions (%u)", p);
            goto done;
        }
        affect_spca_embed(c->spca, f, z);
        if ((st = affect_knn_classify(c->train_z, c->train_y, c->n_train, p, C, z, c->cfg.knn_k,
                                      &out->knn, out->votes, err)) != AFFECT_OK)
            goto done;
    }
    out->ml = argmax(ll, C);
    if (out->loglik)
        memcpy(out->loglik, ll, C * sizeof *ll);
done:
    if (f != out->fisher)
        affect_free(f);
    affect_free(ll);
    return st;
}

void affect_classifier_features_default(affect_features_options *opt)
{
    affect_features_options_default(opt);
    opt->frame = AFFECT_FEATURES_FRAME_BODY;
}

affect_status affect_classifier_observe(const affect_classifier *c, const affect_motion *m,
                                        double **x, uint32_t *n_frames, double **desc,
                                        affect_monitor *mon, affect_error *err)
{
    *x = NULL;
    *desc = NULL;
    affect_status st = affect_features_extract(c->feat, m, x, n_frames, mon, err);
    if (st || !c->ddim)
        return st;
    *desc = affect_malloc_array(c->ddim, sizeof **desc);
    if (!*desc)
        st = affect_nomem(err);
    else
        st = affect_descriptors(c->cfg.descriptors, m, c->feat->up_axis, *desc, mon, err);
    if (st) {
        affect_free(*x);
        affect_free(*desc);
        *x = *desc = NULL;
    }
    return st;
}

/* ---- views ---- */

const affect_classifier_config *affect_classifier_get_config(const affect_classifier *c)
{
    return &c->cfg;
}

uint32_t affect_classifier_n_classes(const affect_classifier *c)
{
    return c->n_classes;
}

const char *affect_classifier_label(const affect_classifier *c, uint32_t k)
{
    return k < c->n_classes ? c->labels[k] : NULL;
}

const affect_features *affect_classifier_features(const affect_classifier *c)
{
    return c->feat;
}

const affect_hmm *affect_classifier_hmm(const affect_classifier *c, uint32_t k)
{
    return k < c->n_classes ? c->hmms[k] : NULL;
}

size_t affect_classifier_dim(const affect_classifier *c)
{
    return c->dim;
}

size_t affect_classifier_part_dim(const affect_classifier *c)
{
    return c->part;
}

const affect_svm *affect_classifier_svm(const affect_classifier *c)
{
    return c->svm;
}

const affect_spca *affect_classifier_spca(const affect_classifier *c)
{
    return c->spca;
}

uint32_t affect_classifier_n_train(const affect_classifier *c)
{
    return c->n_train;
}

const uint32_t *affect_classifier_train_labels(const affect_classifier *c)
{
    return c->train_y;
}

const double *affect_classifier_train_embed(const affect_classifier *c)
{
    return c->train_z;
}

const double *affect_classifier_norm_mean(const affect_classifier *c)
{
    return c->mean;
}

const double *affect_classifier_norm_scale(const affect_classifier *c)
{
    return c->scale;
}

void affect_classifier_get_report(const affect_classifier *c, affect_classifier_report *r)
{
    *r = c->report;
}

/* ---- salient features ---- */

/* Inserts (r, s, weight) into the row's top list (heaviest first; ties keep the earlier). */
static void top_insert(affect_salience_row *row, uint32_t top_n, uint32_t r, uint32_t s,
                       double weight)
{
    uint32_t n = row->n_top;
    if (n == top_n && !(weight > row->top[n - 1].weight))
        return;
    uint32_t pos = n < top_n ? n : top_n - 1;
    while (pos > 0 && weight > row->top[pos - 1].weight) {
        row->top[pos] = row->top[pos - 1];
        pos--;
    }
    row->top[pos] = (affect_salience_item){r, s, weight};
    if (n < top_n)
        row->n_top = n + 1;
}

affect_status affect_classifier_salience(const affect_classifier *c, uint32_t top_n,
                                         affect_salience_row **rows, size_t *n_rows,
                                         affect_error *err)
{
    *rows = NULL;
    *n_rows = 0;
    if (top_n < 1 || top_n > AFFECT_SALIENCE_TOP_MAX)
        return affect_fail(err, AFFECT_ERR_INVALID, "top must be between 1 and %u",
                           AFFECT_SALIENCE_TOP_MAX);
    if (!(c->cfg.groups & AFFECT_FISHER_COVS))
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "the classifier has no covariance scores "
                           "(trained without the covariances group)");
    uint32_t N = c->cfg.hmm.n_states, M = c->cfg.hmm.n_mix, C = c->n_classes;
    size_t count = (size_t)C * N * M;
    affect_salience_row *out = affect_calloc(count, sizeof *out);
    if (!out)
        return affect_nomem(err);
    for (size_t e = 0; e < count; e++) {
        out[e].cls = (uint32_t)(e / ((size_t)N * M));
        out[e].state = (uint32_t)(e / M % N);
        out[e].mix = (uint32_t)(e % M);
    }
    const double *U = affect_spca_axes(c->spca);
    uint32_t p = affect_spca_dims(c->spca);
    for (size_t e = 0; e < c->part; e++) {
        affect_fisher_entry fe;
        affect_status st = affect_fisher_describe(&c->cfg.hmm, c->cfg.groups, e, &fe, err);
        if (st) {
            affect_free(out);
            return st;
        }
        if (fe.group != AFFECT_FISHER_COVS)
            continue;
        for (uint32_t k = 0; k < C; k++) {
            size_t idx = (size_t)k * c->part + e;
            double w = 0.0;
            for (uint32_t a = 0; a < p; a++) {
                double v = fabs(U[(size_t)a * c->dim + idx]);
                if (v > w)
                    w = v;
            }
            affect_salience_row *row = &out[((size_t)k * N + fe.state) * M + fe.other];
            if (w > row->weight)
                row->weight = w;
            top_insert(row, top_n, fe.r, fe.s, w);
        }
    }
    *rows = out;
    *n_rows = count;
    return AFFECT_OK;
}

/* ---- binary form ---- */

/* The bytes of the covariances of a model BLOB of N × M full m × m covariances (they end the
 * BLOB, before its 8-byte checksum), and those of their lower triangles; false on overflow. */
static bool cov_sizes(uint32_t N, uint32_t M, uint32_t m, size_t *full, size_t *tri)
{
    size_t nm, mm, t;
    return affect_mul_size(N, M, &nm) && affect_mul_size(m, m, &mm) &&
           affect_mul_size(nm, mm, full) && affect_mul_size(*full, 8, full) &&
           affect_mul_size(m, (size_t)m + 1, &t) && affect_mul_size(nm, t / 2, tri) &&
           affect_mul_size(*tri, 8, tri);
}

/* Whether the model BLOB (of the configuration hc) has full covariances, each equal to its
 * transpose bit for bit (training always gives that). */
static bool exactly_symmetric(const affect_hmm_config *hc, const unsigned char *blob, size_t len)
{
    size_t full, tri, m = hc->dim;
    if (hc->cov != AFFECT_HMM_FULL || !cov_sizes(hc->n_states, hc->n_mix, hc->dim, &full, &tri) ||
        full + 8 > len)
        return false;
    const unsigned char *cov = blob + len - 8 - full;
    for (size_t g = 0; g < full / (8 * m * m); g++)
        for (size_t r = 0; r < m; r++)
            for (size_t q = 0; q < r; q++)
                if (memcmp(cov + 8 * ((g * m + r) * m + q), cov + 8 * ((g * m + q) * m + r), 8))
                    return false;
    return true;
}

/* A class HMM in the compact storage: a form byte, the length, the bytes. Form 1 (full
 * covariances, every one exactly symmetric, bit for bit: exactly_symmetric): the model BLOB
 * without its checksum, each covariance cut to its lower triangle, row after row (row r:
 * columns 0 .. r); form 0 (any other model): the model BLOB as it is. */
static void put_hmm_compact(affect_bw *w, const affect_hmm_config *hc, const unsigned char *blob,
                            size_t len)
{
    size_t full = 0, tri = 0, m = hc->dim;
    bool sym = exactly_symmetric(hc, blob, len);
    if (sym)
        cov_sizes(hc->n_states, hc->n_mix, hc->dim, &full, &tri);
    const unsigned char *cov = blob + len - 8 - full;
    affect_bw_u8(w, sym);
    if (!sym) {
        affect_bw_u64(w, len);
        affect_bw_bytes(w, blob, len);
        return;
    }
    affect_bw_u64(w, len - 8 - full + tri);
    affect_bw_bytes(w, blob, len - 8 - full);
    for (size_t g = 0; g < full / (8 * m * m); g++)
        for (size_t r = 0; r < m; r++)
            affect_bw_bytes(w, cov + 8 * (g * m + r) * m, 8 * (r + 1));
}

static uint32_t le32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/* The model BLOB of a form-1 class HMM (p, len bytes): the triangles mirrored into full
 * matrices and the checksum appended, into a new array *out of *out_len bytes. */
static affect_status hmm_from_triangles(const unsigned char *p, size_t len, unsigned char **out,
                                        size_t *out_len, affect_error *err)
{
    *out = NULL;
    size_t full, tri;
    if (len < 24 || p[20] != 0 || le32(p + 8) == 0 || le32(p + 12) == 0 || le32(p + 16) == 0 ||
        !cov_sizes(le32(p + 8), le32(p + 12), le32(p + 16), &full, &tri) || tri > len - 24)
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "not a model BLOB with full covariances in triangles");
    size_t head = len - tri, m = le32(p + 16), total = head + full + 8;
    unsigned char *b = affect_malloc(total);
    if (!b)
        return affect_nomem(err);
    memcpy(b, p, head);
    const unsigned char *t = p + head;
    unsigned char *cov = b + head;
    for (size_t g = 0; g < full / (8 * m * m); g++)
        for (size_t r = 0; r < m; r++)
            for (size_t q = 0; q <= r; q++, t += 8) {
                memcpy(cov + 8 * ((g * m + r) * m + q), t, 8);
                memcpy(cov + 8 * ((g * m + q) * m + r), t, 8);
            }
    affect_put_u64(b + head + full, affect_fnv1a64(b, head + full));
    *out = b;
    *out_len = total;
    return AFFECT_OK;
}

affect_status affect_classifier_encode(const affect_classifier *c, unsigned char **out,
                                       size_t *size, affect_error *err)
{
    *out = NULL;
    *size = 0;
    affect_bw w;
    affect_bw_init(&w);
    const affect_classifier_config *cfg = &c->cfg;
    affect_bw_header(&w, AFFECT_CLASSIFIER_MAGIC, c->compact ? AFFECT_CLASSIFIER_VERSION : 2u, 0);
    affect_bw_u32(&w, c->n_classes);
    for (uint32_t k = 0; k < c->n_classes; k++) {
        size_t len = strlen(c->labels[k]);
        affect_bw_u32(&w, (uint32_t)len);
        affect_bw_bytes(&w, c->labels[k], len);
    }
    affect_bw_u32(&w, cfg->groups);
    affect_bw_u8(&w, cfg->zscore);
    affect_bw_f64(&w, cfg->score_clip);
    affect_bw_f64(&w, cfg->svm_c);
    affect_bw_u32(&w, cfg->svm_folds);
    affect_bw_u32(&w, cfg->spca_dims);
    affect_bw_u8(&w, (uint8_t)cfg->spca_kernel);
    affect_bw_f64(&w, cfg->spca_sigma);
    affect_bw_u32(&w, cfg->knn_k);
    affect_bw_u32(&w, cfg->descriptors);
    affect_bw_f64(&w, cfg->descriptor_weight);
    affect_bw_u8(&w, cfg->mirror == AFFECT_MIRROR_ON);
    const affect_classifier_grid *g = &cfg->grid;
    affect_bw_u32(&w, g->n_dims);
    affect_bw_u32(&w, g->n_sigma);
    affect_bw_u32(&w, g->n_k);
    affect_bw_u32(&w, g->folds);
    affect_bw_u32s(&w, g->dims, g->n_dims);
    affect_bw_f64s(&w, g->sigma, g->n_sigma);
    affect_bw_u32s(&w, g->k, g->n_k);
    affect_bw_f64(&w, c->report.grid_cv_acc);
    affect_bw_f64(&w, c->report.svm_c);
    affect_bw_f64(&w, c->report.svm_cv_acc);
    affect_bw_f64(&w, c->report.train_acc_ml);
    affect_bw_f64(&w, c->report.train_acc_svm);
    affect_bw_f64(&w, c->report.train_acc_knn);
    for (uint32_t k = 0; k < c->n_classes; k++) {
        unsigned char *blob;
        size_t len;
        affect_status st = affect_hmm_blob_encode(c->hmms[k], c->feat, &blob, &len, err);
        if (st) {
            affect_bw_free(&w);
            return st;
        }
        if (c->compact)
            put_hmm_compact(&w, affect_hmm_get_config(c->hmms[k]), blob, len);
        else {
            affect_bw_u64(&w, len);
            affect_bw_bytes(&w, blob, len);
        }
        affect_free(blob);
    }
    affect_bw_u64(&w, c->dim);
    if (c->compact) { /* exact: 24-bit values (make_compact) */
        for (size_t e = 0; e < c->dim; e++)
            affect_f24_write(&w, c->mean[e]);
        for (size_t e = 0; e < c->dim; e++)
            affect_f24_write(&w, c->scale[e]);
    } else {
        affect_bw_f64s(&w, c->mean, c->dim);
        affect_bw_f64s(&w, c->scale, c->dim);
    }
    affect_svm_encode(c->svm, &w);
    affect_spca_encode(c->spca, &w);
    uint32_t p = affect_spca_dims(c->spca);
    affect_bw_u32(&w, c->n_train);
    affect_bw_u32s(&w, c->train_y, c->n_train);
    affect_bw_f64s(&w, c->train_z, (size_t)c->n_train * p);
    if (!w.failed)
        affect_bw_checksum(&w, 0);
    if (w.failed) {
        size_t len = w.len;
        affect_bw_free(&w);
        return affect_nomem_of(err, len, 1, "the classifier BLOB beyond its first %zu bytes", len);
    }
    *out = w.data;
    *size = w.len;
    return AFFECT_OK;
}

/* "truncated in <what> (offset N)" */
static affect_status truncated(affect_error *err, const affect_br *r, const char *what)
{
    return affect_fail(err, AFFECT_ERR_FORMAT, "truncated in %s (offset %zu)", what, r->off);
}

static affect_status invalid(affect_error *err, const affect_br *r, const char *what)
{
    return affect_fail(err, AFFECT_ERR_FORMAT, "invalid %s (offset %zu)", what, r->off);
}

/* The grid lists (false when truncated or a count is too large). */
static bool decode_grid(affect_br *r, affect_classifier_grid *g)
{
    if (!affect_br_u32(r, &g->n_dims) || !affect_br_u32(r, &g->n_sigma) ||
        !affect_br_u32(r, &g->n_k) || !affect_br_u32(r, &g->folds))
        return false;
    if (g->n_dims > AFFECT_CLASSIFIER_GRID_MAX || g->n_sigma > AFFECT_CLASSIFIER_GRID_MAX ||
        g->n_k > AFFECT_CLASSIFIER_GRID_MAX)
        return false;
    return affect_br_u32s(r, g->dims, g->n_dims) && affect_br_f64s(r, g->sigma, g->n_sigma) &&
           affect_br_u32s(r, g->k, g->n_k);
}

/* The header, labels and configuration. */
static affect_status decode_head(affect_br *r, affect_classifier **out, affect_error *err)
{
    const unsigned char *magic;
    uint32_t version, flags, n_classes;
    if (!affect_br_bytes(r, &magic, 4) || !affect_br_u32(r, &version) ||
        !affect_br_u32(r, &flags) || !affect_br_u32(r, &n_classes))
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "truncated: %zu bytes is shorter than the classifier header", r->size);
    affect_status st;
    if ((st = affect_check_magic(magic, AFFECT_CLASSIFIER_MAGIC, NULL, "a classifier", 0, err)) !=
        AFFECT_OK)
        return st;
    if ((st = affect_check_version(version, AFFECT_CLASSIFIER_VERSION, NULL, err)) != AFFECT_OK)
        return st;
    if (flags != 0)
        return affect_fail(err, AFFECT_ERR_FORMAT, "unknown classifier flags %u (offset 8)", flags);
    if (n_classes < 2 || n_classes > AFFECT_CLASSIFIER_MAX_CLASSES)
        return affect_fail(err, AFFECT_ERR_FORMAT, "invalid class count %u (offset 12)", n_classes);
    affect_classifier *c = alloc_classifier(n_classes);
    if (!c)
        return affect_nomem(err);
    *out = c;
    c->compact = version >= 3;
    for (uint32_t k = 0; k < n_classes; k++) {
        uint32_t len;
        const unsigned char *p;
        if (!affect_br_u32(r, &len) || !affect_br_bytes(r, &p, len))
            return truncated(err, r, "the labels");
        if (len == 0 || memchr(p, 0, len))
            return invalid(err, r, "label");
        if (!affect_utf8_valid((const char *)p, len))
            return affect_utf8_check(err, AFFECT_ERR_FORMAT, (const char *)p, len,
                                     "label %u (offset %zu)", k, r->off - len);
        c->labels[k] = affect_strndup((const char *)p, len);
        if (!c->labels[k])
            return affect_nomem(err);
    }
    affect_classifier_config *cfg = &c->cfg;
    affect_classifier_config_default(cfg);
    cfg->descriptors = 0; /* version 1: no descriptors, no mirror images */
    cfg->descriptor_weight = 1.0;
    cfg->mirror = AFFECT_MIRROR_OFF;
    uint8_t zscore, kernel, mirror = 0;
    if (!affect_br_u32(r, &cfg->groups) || !affect_br_u8(r, &zscore) ||
        !affect_br_f64(r, &cfg->score_clip) || !affect_br_f64(r, &cfg->svm_c) ||
        !affect_br_u32(r, &cfg->svm_folds) || !affect_br_u32(r, &cfg->spca_dims) ||
        !affect_br_u8(r, &kernel) || !affect_br_f64(r, &cfg->spca_sigma) ||
        !affect_br_u32(r, &cfg->knn_k) ||
        (version >= 2 &&
         (!affect_br_u32(r, &cfg->descriptors) || !affect_br_f64(r, &cfg->descriptor_weight) ||
          !affect_br_u8(r, &mirror))) ||
        !decode_grid(r, &cfg->grid) || !affect_br_f64(r, &c->report.grid_cv_acc) ||
        !affect_br_f64(r, &c->report.svm_c) || !affect_br_f64(r, &c->report.svm_cv_acc) ||
        !affect_br_f64(r, &c->report.train_acc_ml) || !affect_br_f64(r, &c->report.train_acc_svm) ||
        !affect_br_f64(r, &c->report.train_acc_knn))
        return truncated(err, r, "the configuration");
    if (zscore > 1 || kernel > 1 || mirror > 1)
        return invalid(err, r, "configuration");
    cfg->mirror = mirror ? AFFECT_MIRROR_ON : AFFECT_MIRROR_OFF;
    cfg->storage = c->compact ? AFFECT_STORAGE_COMPACT : AFFECT_STORAGE_FLOAT32;
    cfg->zscore = zscore;
    cfg->spca_kernel = kernel ? AFFECT_SPCA_RBF : AFFECT_SPCA_LINEAR;
    return AFFECT_OK;
}

/* Whether two feature definitions have the same binary form. */
static affect_status same_features(const affect_features *a, const affect_features *b, bool *same,
                                   affect_error *err)
{
    size_t na, nb;
    if (!affect_features_encoded_size(a, &na) || !affect_features_encoded_size(b, &nb))
        return affect_nomem(err);
    *same = false;
    if (na != nb)
        return AFFECT_OK;
    unsigned char *ba = affect_malloc(na), *bb = affect_malloc(nb);
    if (!ba || !bb) {
        affect_free(ba);
        affect_free(bb);
        return affect_nomem(err);
    }
    affect_features_encode_into(a, ba);
    affect_features_encode_into(b, bb);
    *same = memcmp(ba, bb, na) == 0;
    affect_free(ba);
    affect_free(bb);
    return AFFECT_OK;
}

/* The class HMMs (and the feature definition). */
static affect_status decode_hmms(affect_br *r, affect_classifier *c, affect_error *err)
{
    for (uint32_t k = 0; k < c->n_classes; k++) {
        uint64_t len;
        uint8_t form = 0;
        const unsigned char *p;
        if ((c->compact && !affect_br_u8(r, &form)) || !affect_br_u64(r, &len) ||
            len > r->size - r->off || !affect_br_bytes(r, &p, (size_t)len))
            return truncated(err, r, "the class HMMs");
        if (form > 1)
            return affect_fail(err, AFFECT_ERR_FORMAT,
                               "invalid form %u of the HMM of class \"%s\" (offset %zu)", form,
                               c->labels[k], r->off - (size_t)len - 9);
        unsigned char *whole = NULL;
        size_t whole_len = (size_t)len;
        affect_status st = AFFECT_OK;
        if (form == 1 &&
            (st = hmm_from_triangles(p, (size_t)len, &whole, &whole_len, err)) == AFFECT_OK)
            p = whole;
        affect_features *f = NULL;
        if (st == AFFECT_OK)
            st = affect_hmm_blob_decode(p, whole_len, &c->hmms[k], &f, err);
        affect_free(whole);
        if (st == AFFECT_OK && form == 0 && c->compact &&
            exactly_symmetric(affect_hmm_get_config(c->hmms[k]), p, whole_len)) {
            affect_features_free(f);
            return affect_fail(err, AFFECT_ERR_FORMAT,
                               "the HMM of class \"%s\" is stored whole but its covariances are "
                               "symmetric (offset %zu)",
                               c->labels[k], r->off - (size_t)len - 9);
        }
        if (st && affect_prefix(err, "the HMM of class \"%s\"", c->labels[k]) != AFFECT_ERR_NOMEM)
            err->status = AFFECT_ERR_FORMAT;
        if (st)
            return err->status;
        if (!c->feat) {
            c->feat = f;
        } else {
            bool same = false;
            st = same_features(c->feat, f, &same, err);
            affect_features_free(f);
            if (st)
                return st;
            if (!same)
                return affect_fail(err, AFFECT_ERR_FORMAT,
                                   "the HMM of class \"%s\" has another feature definition",
                                   c->labels[k]);
        }
        const affect_hmm_config *hc = affect_hmm_get_config(c->hmms[k]);
        const affect_hmm_config *h0 = affect_hmm_get_config(c->hmms[0]);
        if (hc->n_states != h0->n_states || hc->n_mix != h0->n_mix || hc->dim != h0->dim ||
            hc->cov != h0->cov || hc->learn_start != h0->learn_start)
            return affect_fail(err, AFFECT_ERR_FORMAT,
                               "the HMM of class \"%s\" has another configuration", c->labels[k]);
    }
    c->cfg.hmm = *affect_hmm_get_config(c->hmms[0]);
    return AFFECT_OK;
}

/* Everything after the HMMs. */
static affect_status decode_rest(affect_br *r, affect_classifier *c, affect_error *err)
{
    const char *msg = affect_classifier_config_check(&c->cfg);
    if (msg)
        return affect_fail(err, AFFECT_ERR_FORMAT, "invalid configuration: %s", msg);
    uint64_t dim;
    if (!affect_br_u64(r, &dim))
        return truncated(err, r, "the normalization");
    if (!set_dims(c) || dim != c->dim)
        return invalid(err, r, "representation dimension");
    if (!affect_br_has(r, c->dim, c->compact ? 6 : 16))
        return truncated(err, r, "the normalization");
    c->mean = affect_malloc_array(c->dim, sizeof *c->mean);
    c->scale = affect_malloc_array(c->dim, sizeof *c->scale);
    if (!c->mean || !c->scale)
        return affect_nomem(err);
    if (c->compact) {
        for (size_t e = 0; e < c->dim; e++)
            c->mean[e] = affect_f24_read(r);
        for (size_t e = 0; e < c->dim; e++)
            c->scale[e] = affect_f24_read(r);
    } else {
        affect_br_f64s(r, c->mean, c->dim);
        affect_br_f64s(r, c->scale, c->dim);
    }
    for (size_t e = 0; e < c->dim; e++)
        if (!isfinite(c->mean[e]) || !(c->scale[e] > 0) || !isfinite(c->scale[e]))
            return invalid(err, r, "normalization");
    affect_status st;
    if ((st = affect_svm_decode(r, &c->svm, err)) != AFFECT_OK)
        return st;
    if ((st = affect_spca_decode(r, &c->spca, err)) != AFFECT_OK)
        return st;
    if (affect_svm_n_classes(c->svm) != c->n_classes || affect_svm_dim(c->svm) != c->dim ||
        affect_spca_input_dim(c->spca) != c->dim)
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "the SVM or sPCA does not match the classifier's %u classes and %zu "
                           "dimensions",
                           c->n_classes, c->dim);
    uint32_t p = affect_spca_dims(c->spca), n;
    if (!affect_br_u32(r, &n))
        return truncated(err, r, "the training set");
    if (n == 0 || !affect_br_has(r, n, 4 + 8 * (size_t)p))
        return truncated(err, r, "the training set");
    c->n_train = n;
    c->train_y = affect_malloc_array(n, sizeof *c->train_y);
    c->train_z = affect_malloc_array((size_t)n * p, sizeof *c->train_z);
    if (!c->train_y || !c->train_z)
        return affect_nomem(err);
    affect_br_u32s(r, c->train_y, n);
    affect_br_f64s(r, c->train_z, (size_t)n * p);
    for (uint32_t i = 0; i < n; i++)
        if (c->train_y[i] >= c->n_classes)
            return invalid(err, r, "training label");
    for (size_t e = 0; e < (size_t)n * p; e++)
        if (!isfinite(c->train_z[e]))
            return invalid(err, r, "training coordinates");
    return AFFECT_OK;
}

affect_status affect_classifier_decode(const unsigned char *data, size_t size,
                                       affect_classifier **out, affect_error *err)
{
    *out = NULL;
    if (size < 24)
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "truncated: %zu bytes is shorter than the classifier header", size);
    if (affect_check_magic(data, AFFECT_CLASSIFIER_MAGIC, NULL, "a classifier", 0, err) !=
        AFFECT_OK)
        return AFFECT_ERR_FORMAT;
    if (!affect_checksum_ok(data, size - 8))
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "classifier checksum mismatch: the BLOB is corrupt");
    affect_br r;
    affect_br_init(&r, data, size - 8);
    affect_classifier *c = NULL;
    affect_status st = decode_head(&r, &c, err);
    if (st == AFFECT_OK)
        st = decode_hmms(&r, c, err);
    if (st == AFFECT_OK)
        st = decode_rest(&r, c, err);
    if (st == AFFECT_OK && r.off != r.size)
        st = affect_fail(err, AFFECT_ERR_FORMAT,
                         "%zu unexpected bytes after the training set "
                         "(offset %zu)",
                         r.size - r.off, r.off);
    if (st) {
        affect_classifier_free(c);
        return st;
    }
    *out = c;
    return AFFECT_OK;
}
