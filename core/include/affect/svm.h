/*
 * affect/svm.h — a linear multi-class support vector machine (C-SVC, one-vs-one) for
 * Fisher-score vectors: very high dimension d (10^4 .. 10^6), few samples n (40 .. 400).
 *
 * Usage:
 *     const double *X = ...;  size_t n = ..., d = ...;     // n × d, row-major
 *     const uint32_t *y = ...;                         // classes 0 .. 2
 *     affect_error err;
 *     const double cands[3] = {0.1, 1, 10};
 *     double C = 1, acc = 0, dec[3];                   // dec: the c (c - 1) / 2 decision values
 *     affect_svm *m = NULL;
 *     if (affect_svm_select_c(X, n, d, y, 3, cands, 3, 5, 42, &C, &acc, &err) != AFFECT_OK
 *         || affect_svm_train(X, n, d, y, 3, C, &m, &err) != AFFECT_OK)
 *         puts(err.msg);
 *     else
 *         printf("class %u (C = %g, cv accuracy %g)\n", affect_svm_predict(m, X, dec), C, acc);
 *     affect_svm_free(m);
 *
 * Training runs libsvm 3.24 with a precomputed kernel on the n × n Gram matrix G = X Xᵀ, so
 * libsvm never sees the d-dimensional vectors; the trained libsvm model is then turned into
 * the primal one-vs-one weight vectors of the linear kernel and freed, so prediction costs one
 * dot product of length d per class pair and the model owns no libsvm memory.
 *
 * Classes are our indices 0 .. c−1. For the pair (p, q), p < q, the decision value is
 * dec_pq(x) = w_pq·x − rho_pq; pairs are ordered (0,1), (0,2), …, (0,c−1), (1,2), …, (c−2,c−1)
 * (libsvm's order, which is ours: see affect_svm_train). Prediction is libsvm's one-vs-one
 * vote: dec_pq > 0 is a vote for p, otherwise for q; the class with most votes wins, a tie going
 * to the smallest class index.
 *
 * Choosing C: affect_svm_select_c runs our own stratified k-fold cross-validation (never
 * libsvm's, which draws its folds from rand()) with folds from affect_stratified_folds.
 *
 * Costs: the Gram matrix takes n²d/2 multiply-adds and n² doubles; a model holds
 * c(c−1)/2 × d doubles of weights (21 × 8 MB for 7 classes in d = 10^6).
 *
 * Memory: our allocations go through affect_malloc; libsvm's own (inside svm_train: malloc
 * and C++ operator new) come from the C library and are outside our allocator, its
 * accounting and its fault injection; libsvm does not check them, so an allocation failure
 * inside libsvm aborts the process rather than returning AFFECT_ERR_NOMEM. libsvm's memory is
 * freed before each function returns.
 *
 * Thread safety: a trained model is read-only and may be shared, and trainings may run
 * concurrently. The first training installs a silent print function in libsvm
 * (svm_set_print_string_function, libsvm's only process-wide setting) exactly once per process
 * (C11 call_once), so concurrent trainings never write it. A program that gives libsvm its own
 * print function before that will find it replaced; one that does so afterwards keeps its own
 * (and libsvm's training messages).
 */
#ifndef AFFECT_SVM_H
#define AFFECT_SVM_H

#include "affect/base.h"
#include "affect/monitor.h"

/* the byte writer and reader of the BLOB codec (internal: core/util/bytes.h) */
typedef struct affect_bw affect_bw;
typedef struct affect_br affect_br;

#ifdef __cplusplus
extern "C" {
#endif

/* libsvm's stopping tolerance (its default). */
#define AFFECT_SVM_EPS 1e-3
/* libsvm's kernel cache, in MB (the Gram matrix is precomputed, so this only bounds the cache
 * of float copies of its rows). */
#define AFFECT_SVM_CACHE_MB 100.0
/* Number of classes, 2 .. AFFECT_SVM_MAX_CLASSES. */
#define AFFECT_SVM_MAX_CLASSES 256u
/* Samples at most (libsvm counts them in an int, and node indices run to n). */
#define AFFECT_SVM_MAX_SAMPLES 2147483645u
/* Dimension at most (BLAS counts it in an int). */
#define AFFECT_SVM_MAX_DIM 2147483647u
/* Version of the encoding written by affect_svm_encode. */
#define AFFECT_SVM_FORMAT_VERSION 3u

typedef struct affect_svm affect_svm; /* opaque */

/* G = X Xᵀ into G (n × n, row-major) for X (n × d, row-major), by cblas_dsyrk on the upper
 * triangle, mirrored to the lower one so that G is exactly symmetric. This is the matrix
 * affect_svm_train and affect_svm_select_c give libsvm. Errors: "dimension must be at least
 * 1", "dimension 3000000000 too large (at most 2147483647)", "too many samples: 3000000000 (at
 * most 2147483645)" (AFFECT_ERR_RANGE). */
affect_status affect_svm_gram(const double *X, size_t n, size_t d, double *G, affect_error *err);

/* Trains a linear C-SVC on n samples X (n × d, row-major doubles) with classes y[i] in
 * 0 .. c−1 and penalty C. *out is NULL on failure.
 *
 * libsvm orders classes by their first appearance in the problem. We hand it the samples
 * grouped by class — all of class 0 in their original order, then class 1, … — labelled with
 * their class index, which is the grouping libsvm makes internally anyway; so libsvm's class
 * k is our class k. The trained model's labels are read back and checked.
 *
 * libsvm parameters: C_SVC, PRECOMPUTED kernel, eps AFFECT_SVM_EPS, cache AFFECT_SVM_CACHE_MB,
 * shrinking on, no probability estimates, no class weights.
 *
 * Errors, in the order checked (AFFECT_ERR_INVALID unless said): "need at least 2 classes",
 * "at most 256 classes, got 300", the sizes as for affect_svm_gram (AFFECT_ERR_RANGE),
 * "sample 5: class 7 out of range 0 .. 2", "class 2 has no training sample", "C must be a
 * positive finite number, got -1", "sample 3, component 17 is not finite", "Gram entry (3, 5)
 * is not finite (the features are too large)" (AFFECT_ERR_RANGE), "libsvm rejected the
 * parameters: …", and two that would mean libsvm changed its behaviour (AFFECT_ERR_RANGE):
 * "libsvm returned 2 classes, expected 3", "libsvm reordered the classes (class 1 at position
 * 0)"; AFFECT_ERR_NOMEM. */
affect_status affect_svm_train(const double *X, size_t n, size_t d, const uint32_t *y, uint32_t c,
                               double C, affect_svm **out, affect_error *err);

/* ---- training on the Gram matrix, weights block by block ----
 * For data too large to hold at once (n × d with d ~ 10⁶): the caller accumulates G = X Xᵀ
 * (n × n, row-major, only the upper triangle read) block of columns by block, trains on it, then
 * gives the columns again, block by block, for the weights.
 *
 * affect_svm_train_gram: as affect_svm_train on the Gram matrix (d is the dimension of the
 * weights to come); the model has no weights yet: affect_svm_predict needs them, and
 * affect_svm_predict_gram does not. Errors: affect_svm_train's, with "Gram entry (3, 5) is not
 * finite (the features are too large)" for G.
 * affect_svm_add_rows: the weight columns col0 .. col0 + b − 1 from B (n × b, row-major, the
 * columns col0 .. of every training sample, in training order): w_pq[col0 + t] += Σ coef ·
 * B[s][t] over the support vectors; the weights start at 0 (allocated on the first call), so
 * after every column was given once they equal affect_svm_train's up to the order of the
 * additions (the same order: support vector after support vector). Errors: "columns 5 .. 9 are
 * outside the model's 8 dimensions", "weights of 21 pairs x 3000000000 too large"
 * (AFFECT_ERR_RANGE), AFFECT_ERR_NOMEM.
 * affect_svm_predict_gram: the prediction of a sample from its kernel values g with every
 * training sample (a row of G), libsvm's sums and vote.
 * affect_svm_select_c_gram: affect_svm_select_c on the Gram matrix, polling mon (may be NULL)
 * before each fit of the cross-validation: AFFECT_ERR_INTERRUPTED once it says stop. */
affect_status affect_svm_train_gram(const double *G, size_t n, size_t d, const uint32_t *y,
                                    uint32_t c, double C, affect_svm **out, affect_error *err);
affect_status affect_svm_add_rows(affect_svm *m, const double *B, size_t b, size_t col0,
                                  affect_error *err);
uint32_t affect_svm_predict_gram(const affect_svm *m, const double *g);
affect_status affect_svm_select_c_gram(const double *G, size_t n, size_t d, const uint32_t *y,
                                       uint32_t c, const double *candidates, size_t n_cand,
                                       uint32_t folds, uint64_t seed, double *best_c,
                                       double *best_acc, affect_monitor *mon, affect_error *err);

/* Rounds every weight to the nearest float32 value, so that the model is encoded with float32
 * weights (format version 2, half the bytes) and decodes to exactly these weights; false (and
 * nothing changed) when the model has no weights or a weight is beyond float32's range. The
 * recognizer does this once its weights are complete: its z-scored inputs are at most ±5, so
 * the rounding moves a decision value by about 1e-7 of its size. */
bool affect_svm_round_weights(affect_svm *m);

/* Whether affect_svm_compact_weights(m, factor) can succeed: the model has weights and every
 * weight times its column's factor (factor NULL: 1) gives blocks whose scales fit a float32. */
bool affect_svm_compact_fits(const affect_svm *m, const double *factor);

/* Multiplies column t of every weight vector by factor[t] (factor: d values, or NULL) and rounds
 * each vector to its 4-bit block form (util/quant.h), so that the model is encoded with
 * compact weights (format version 3, about 0.56 byte a weight) and decodes to exactly these
 * weights. The caller has checked affect_svm_compact_fits. The recognizer folds the ratio of its
 * stored to its exact normalization scales into the factors (affect/classifier.h). */
void affect_svm_compact_weights(affect_svm *m, const double *factor);

void affect_svm_free(affect_svm *m);

/* The predicted class of x (dim() values). When dec is not NULL it receives the
 * c(c−1)/2 decision values in pair order. Values of x are not checked: a NaN gives NaN
 * decision values, each a vote for the pair's second class. */
uint32_t affect_svm_predict(const affect_svm *m, const double *x, double *dec);

/* The one-vs-one vote on decision values already computed: dec holds the c(c−1)/2 values in
 * pair order (as affect_svm_predict gives them); dec_pq > 0 is a vote for p, anything else (NaN
 * too) for q. Returns the class with the most votes, the smallest index among equals, and the
 * c vote counts in votes (when not NULL): the vote affect_svm_predict makes, so that a caller
 * reporting the votes reports the ones that chose the label. UINT32_MAX (and votes untouched)
 * when c is 0 or above AFFECT_SVM_MAX_CLASSES. */
uint32_t affect_svm_vote(const double *dec, uint32_t c, uint32_t *votes);

/* ---- accessors ---- */
uint32_t affect_svm_n_classes(const affect_svm *m);
size_t affect_svm_dim(const affect_svm *m);
double affect_svm_C(const affect_svm *m);
/* Number of training samples the model was trained on. */
uint32_t affect_svm_n_train(const affect_svm *m);
/* Support vectors in all, and of class k (0 when k ≥ c). */
uint32_t affect_svm_total_sv(const affect_svm *m);
uint32_t affect_svm_n_sv(const affect_svm *m, uint32_t k);
/* The 0-based training indices of the support vectors (total_sv of them), grouped by class
 * (class 0's first) and increasing within a class. */
const uint32_t *affect_svm_sv_indices(const affect_svm *m);
/* libsvm's dual coefficients: row j (0 .. c−2) has total_sv values, in the layout of
 * libsvm's sv_coef. NULL when j ≥ c − 1. */
const double *affect_svm_sv_coef(const affect_svm *m, uint32_t j);
/* Index of the pair (p, q) in the pair order, for p < q < c; or UINT32_MAX. */
uint32_t affect_svm_pair_index(const affect_svm *m, uint32_t p, uint32_t q);
/* The weight vector w_pq (dim() values) of the pair (p, q), p < q < c, and its rho in *rho
 * (when not NULL); NULL for any other p, q. */
const double *affect_svm_weights(const affect_svm *m, uint32_t p, uint32_t q, double *rho);

/* ---- cross-validation ---- */

/* Stratified assignment of n samples (classes y[i] in 0 .. c−1; a class may be absent) to
 * k folds: fold_of[i] in 0 .. k'−1, where k' = min(k, n) (k is clamped to n so that no fold is
 * empty). Deterministic for a seed: one generator (util/rng.h) seeded with seed shuffles
 * each class's samples in turn, class 0 first, by Fisher–Yates (for i = m−1 down to 1, swap
 * i with a uniform j in 0 .. i drawn by rejection, so without bias); then the samples are
 * dealt round-robin to the folds, class 0's shuffled list first, the deal continuing across
 * classes. So every fold holds floor or ceil of n_k / k' samples of class k, and fold sizes
 * differ by at most 1. Errors: "need at least 2 folds, got 1", "need at least 1 class",
 * "sample 5: class 7 out of range 0 .. 2" (AFFECT_ERR_INVALID), "too many samples: …"
 * (AFFECT_ERR_RANGE), AFFECT_ERR_NOMEM. */
affect_status affect_stratified_folds(const uint32_t *y, size_t n, uint32_t c, uint32_t k,
                                      uint64_t seed, uint32_t *fold_of, affect_error *err);

/* Chooses C among n_cand candidates by stratified k-fold cross-validation (folds from
 * affect_stratified_folds(y, n, c, folds, seed)): for each fold, a model is trained on the
 * other folds — on the rows and columns of the Gram matrix, computed once — and predicts the
 * held-out fold. The accuracy of a candidate is the mean over folds of the fraction of the
 * fold predicted correctly; the best accuracy wins, ties going to the smallest C. A fold
 * whose training part lacks a class trains on the classes it has; one whose training part
 * has a single class predicts that class. *best_c and *best_acc receive the winner.
 * Errors: those of affect_svm_train for the data (C excepted), "need at least one candidate
 * C", "candidate 2: C = 0 is not a positive finite number", "need at least 2 folds, got 1",
 * AFFECT_ERR_NOMEM. */
affect_status affect_svm_select_c(const double *X, size_t n, size_t d, const uint32_t *y,
                                  uint32_t c, const double *candidates, size_t n_cand,
                                  uint32_t folds, uint64_t seed, double *best_c, double *best_acc,
                                  affect_error *err);

/* ---- serialisation ----
 * Layout, version 1 (little-endian, through util/bytes.h), offsets relative to the start:
 *    0  1      format version (1; 2 when the weights are float32: affect_svm_round_weights;
 *              3 when they are in 4-bit blocks: affect_svm_compact_weights)
 *    1  4      classes c (2 .. 256)
 *    5  8      dimension d (1 .. 2147483647)
 *   13  8      C (float64, positive, finite)
 *   21  4      training samples n (c .. 2147483645)
 *   25  4      number of labels (= c)
 *       4c     labels: libsvm's class k is our class label[k]; always 0, 1, …, c−1
 *       4      number of support-vector counts (= c)
 *       4c     support vectors per class, nSV[k]
 *       4      total support vectors l (= Σ nSV[k], ≤ n)
 *       4l     their 0-based training indices (< n, increasing within a class)
 *       4      number of coefficient rows (= c − 1)
 *       8(c−1)l  dual coefficients sv_coef[j][i] (float64, finite)
 *       4      number of rho values P (= c(c−1)/2)
 *       8P     rho (float64, finite)
 *       4      number of weight vectors (= P)
 *       8Pd    weight vectors w, pair after pair (float64, finite; version 2: 4Pd bytes of
 *              float32, finite; version 3: each vector in the 4-bit form of util/quant.h,
 *              canonical)
 * No checksum and no length: the object is embedded in the classifier BLOB, which carries
 * both; decoding stops after the weights. */

/* Appends m to w (a failed allocation sets w->failed). */
void affect_svm_encode(const affect_svm *m, affect_bw *w);

/* Reads a model from r at its offset and advances past it; every count and length is checked
 * before anything is read or allocated, and offsets in messages are r's (AFFECT_ERR_FORMAT):
 * "SVM: truncated in the weights (offset 1234)", "SVM: unknown format version 3 at offset 0
 * (this build reads 1 .. 2)", "SVM: class count 1 out of range 2 .. 256 (offset 1)", "SVM:
 * dimension 0 out of range 1 .. 2147483647 (offset 5)", "SVM: C = -1 is not a positive finite
 * number (offset 13)", "SVM: sample count 2 out of range 3 .. 2147483645 (offset 21)", "SVM: 7
 * classes but 3 labels (offset 25)", "SVM: label 2 at position 0, expected 0 (offset 29)", "SVM: 7
 * classes but 3 support-vector counts (offset 57)", "SVM: support-vector counts sum to 12 but
 * the total is 10 (offset 89)", "SVM: 50 support vectors but 40 training samples (offset 89)",
 * "SVM: support vector 3 has training index 50, not below 40 (offset 105)", "SVM: support
 * vector 4 has training index 7, not above the previous 9 of its class (offset 109)", "SVM: 3
 * classes but 1 coefficient rows (offset 133)", "SVM: 3 classes but 2 rho values (offset 200)",
 * "SVM: 3 classes but 2 weight vectors (offset 230)", "SVM: non-finite value in the
 * coefficients (offset 141)" (likewise "the rho values", "the weights"); AFFECT_ERR_NOMEM.
 * *out is NULL on failure. */
affect_status affect_svm_decode(affect_br *r, affect_svm **out, affect_error *err);

#ifdef __cplusplus
}
#endif
#endif
