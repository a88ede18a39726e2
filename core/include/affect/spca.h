/*
 * affect/spca.h — supervised principal component analysis with the Hilbert–Schmidt
 * independence criterion (HSIC), computed in the dual, and k-nearest-neighbour classification
 * in the projection (thesis §3.1.2.3 and §4.2.4; SCIENCE.md §3).
 *
 * Usage:
 *     const double *x = ...;  size_t n = ..., d = ...;     // n × d, row-major
 *     const uint32_t *y = ...;                         // classes 0 .. 2
 *     affect_error err;
 *     affect_spca *s = NULL;
 *     if (affect_spca_fit(x, n, d, y, 3, AFFECT_SPCA_LINEAR, 0, 2, &s, &err) != AFFECT_OK) return;
 *     uint32_t p = affect_spca_dims(s), label;         // at most c - 1 = 2, maybe fewer
 *     double *train_z = affect_malloc_array(n, 2 * sizeof *train_z), z[2];
 *     if (train_z) {
 *         affect_spca_embed_rows(s, x, n, train_z);    // n × p
 *         affect_spca_embed(s, x, z);                  // one query
 *         if (affect_knn_classify(train_z, y, n, p, 3, z, 5, &label, NULL, &err) == AFFECT_OK)
 *             printf("class %u\n", label);
 *     }
 *     affect_free(train_z);  affect_spca_free(s);
 *
 * The problem. Training data X (n × d, one sample per row, row-major), labels y_i in 0 .. c−1
 * with every class present, a kernel B (n × n) on the labels, H = I − (1/n) e eᵀ. sPCA finds
 * the p orthonormal axes U (p × d, one axis per row) that maximise
 *     tr(U Xᵀ H B H X Uᵀ)   subject to   U Uᵀ = I,
 * the top eigenvectors of Xᵀ H B H X (the thesis writes X H B H Xᵀ with its X being d × n):
 * the directions along which the data depend most on the labels, as the HSIC measures
 * dependence. The d × d matrix is never formed (d may be 10⁶): B has rank ≤ c, B = Δ Δᵀ with
 * Δ = E G^{1/2} (E the n × c one-hot matrix, G the c × c kernel of the class values), and the
 * nonzero eigenvalues are those of the c × c matrix M = Δᵀ H K H Δ, K = X Xᵀ; for M's eigenpairs
 * (λ_r, v_r) the axes are U_r = Xᵀ H Δ v_r / √λ_r, orthonormal. Cost: n² d / 2 multiply–adds
 * for K (none when the caller passes K), n p d for U; memory n² + n (2c + 1) + 3c² + 5c
 * doubles and a 2 MB column block, besides the model's p × d (X is never copied whole).
 *
 * Label kernels (the kernel on y; the kernel on X is always linear):
 *   AFFECT_SPCA_LINEAR  B_ij = 1 when y_i = y_j, else 0 (one-hot labels, G = I). sigma is
 *                       ignored (and stored as 0).
 *   AFFECT_SPCA_RBF     B_ij = exp(−(y_i − y_j)² / (2σ²)): the Gaussian RBF on the class
 *                       INDEX taken as a number. The order of the classes matters: with the
 *                       order the caller gives, classes 0 and 1 count as more alike than 0
 *                       and 3, so number the classes in a meaningful order (by arousal, say)
 *                       or use the linear kernel. As σ → 0, B tends to the linear kernel
 *                       (σ ≤ 0.025 gives it exactly in double precision); as σ grows, B tends
 *                       to e eᵀ, which H removes, and the neighbouring classes merge. The
 *                       thesis chose σ in 0.25 .. 25 by cross-validation. G^{1/2} comes
 *                       from G's eigendecomposition, tiny negative eigenvalues clipped to 0.
 *
 * Number of axes: H Δ = H E G^{1/2} and the columns of H E add up to H e = 0, so M has rank
 * ≤ c − 1 (and ≤ d, ≤ n − 1): at most c − 1 axes carry label information. The model keeps p =
 * min(dims, the number of eigenvalues of M above AFFECT_SPCA_RANK_TOL × the largest) axes, which
 * may be FEWER than asked: affect_spca_dims says how many.
 *
 * Signs and determinism: each axis is oriented so that its largest-magnitude component (the
 * first such on a tie) is positive, so results do not flip sign between LAPACK builds (they
 * still may when two components are equal in magnitude up to rounding, or when M has a
 * repeated eigenvalue, whose eigenvectors are any basis of the eigenspace). The same inputs
 * give bit-identical models for a given BLAS build, whatever its thread count (the core runs
 * OpenBLAS on one thread in its calls).
 *
 * Embedding: z = U x (p values), with no centring of x: shifting every point by the same
 * vector shifts every embedding by the same vector, which changes no distance, so k-NN does
 * not care. Train and query points must of course be embedded the same way.
 */
#ifndef AFFECT_SPCA_H
#define AFFECT_SPCA_H

#include "affect/base.h"

/* the byte writer and reader of the BLOB codec (internal: core/util/bytes.h) */
typedef struct affect_bw affect_bw;
typedef struct affect_br affect_br;

#ifdef __cplusplus
extern "C" {
#endif

typedef enum affect_spca_kernel {
    AFFECT_SPCA_LINEAR = 0, /* one-hot labels */
    AFFECT_SPCA_RBF = 1     /* Gaussian RBF on the class index */
} affect_spca_kernel;

/* A trained projection: p axes (p × d), their eigenvalues, the kernel and its σ. */
typedef struct affect_spca affect_spca;

/* Eigenvalues of M at or below this fraction of the largest are dropped (rank). */
#define AFFECT_SPCA_RANK_TOL 1e-10
/* The fit fails when the largest eigenvalue is at or below this fraction of n · tr(H K H),
 * its largest possible value: the labels do not explain the data beyond rounding. */
#define AFFECT_SPCA_INFO_TOL 1e-12

/* Fits sPCA to x (n × d, row-major) with labels y (n values in 0 .. c−1, every class present),
 * keeping at most dims axes. On success *out is a new model (free with affect_spca_free).
 * Errors (AFFECT_ERR_INVALID unless said):
 *   "need at least 2 classes"
 *   "d must be at least 1"
 *   "unknown label kernel 7 (0 = linear, 1 = rbf)"
 *   "sigma must be a positive finite number"           (rbf only)
 *   "dims must be at least 1"
 *   "row 4: label 9 is out of range (3 classes: 0 .. 2)"
 *   "class 3 has no training sample"
 *   "row 5, column 17: non-finite value"
 *   "d = 3000000000 exceeds the BLAS limit of 2147483647"  (likewise n; AFFECT_ERR_RANGE)
 *   "the data are too large: the centred Gram matrix overflows"            (AFFECT_ERR_RANGE)
 *   "the eigendecomposition did not converge (LAPACK info 3)"              (AFFECT_ERR_RANGE)
 *   "the data carry no label information (all projections are 0)" — the largest eigenvalue is
 *     at or below AFFECT_SPCA_INFO_TOL × n · tr(H K H) (all samples equal, or every class
 *     with the same mean under the linear kernel)
 *   AFFECT_ERR_NOMEM. */
affect_status affect_spca_fit(const double *x, size_t n, size_t d, const uint32_t *y, uint32_t c,
                              affect_spca_kernel kernel, double sigma, uint32_t dims,
                              affect_spca **out, affect_error *err);

/* The same with the Gram matrix k = X Xᵀ (n × n, row-major) given, which saves the n² d / 2
 * work; only its upper triangle (j ≥ i) is read. Any k that centres to the same H K H works
 * (the Gram matrix of the data shifted by a constant vector, for instance); x is still needed
 * for the axes. Besides fit's errors: "K row 2, column 7: non-finite value", and "the Gram
 * matrix does not match the data (trace of H K H 12.5, the data give 10.25)" when the traces
 * differ by more than 1e-6 × max(tr K, Σ x²) (K computed from other data, or in single
 * precision). */
affect_status affect_spca_fit_gram(const double *x, const double *k, size_t n, size_t d,
                                   const uint32_t *y, uint32_t c, affect_spca_kernel kernel,
                                   double sigma, uint32_t dims, affect_spca **out,
                                   affect_error *err);

/* ---- the dual fit, axes block by block ----
 * For data too large to hold at once: the fit needs only the Gram matrix k (n × n, upper
 * triangle read); the axes U = Aᵀ X (A the n × p dual coefficients; Aᵀ H = Aᵀ because the
 * columns of A = H Δ v / √λ sum to 0) are then accumulated from blocks of columns of X.
 * affect_spca_fit_dual: fit's errors except the data's own (d is the dimension of the axes to
 * come); the model's axes are 0 and it keeps A until affect_spca_finish.
 * affect_spca_dual_embed: z (m × p) = k_rows (m × n: kernel values of m samples with the
 * training samples) · A — the coordinates U x of those samples, before the signs are fixed (the
 * training coordinates with k_rows = k).
 * affect_spca_add_rows: the axes' columns col0 .. col0 + b − 1 += Aᵀ B (B: n × b, those columns
 * of every training sample, in training order), one cblas_dgemm.
 * affect_spca_finish: orients each axis as affect_spca_fit does (largest-magnitude component
 * positive), changes the sign of the same columns of z (m × p; NULL for none), and frees A. The
 * model is then used and encoded like a fitted one. */
affect_status affect_spca_fit_dual(const double *k, size_t n, size_t d, const uint32_t *y,
                                   uint32_t c, affect_spca_kernel kernel, double sigma,
                                   uint32_t dims, affect_spca **out, affect_error *err);
void affect_spca_dual_embed(const affect_spca *s, const double *k, size_t m, double *z);
void affect_spca_add_rows(affect_spca *s, const double *B, size_t b, size_t col0);
void affect_spca_finish(affect_spca *s, double *z, size_t m);

void affect_spca_free(affect_spca *s);

/* z (p values) = U x for x of affect_spca_input_dim values; plain sums in index order, so
 * the result does not depend on the BLAS. */
void affect_spca_embed(const affect_spca *s, const double *x, double *z);
/* The same for n rows of x (n × d) into z (n × p); row i equals affect_spca_embed of row i. */
void affect_spca_embed_rows(const affect_spca *s, const double *x, size_t n, double *z);

/* The number of axes p kept (1 .. c − 1; may be fewer than asked, see above). */
uint32_t affect_spca_dims(const affect_spca *s);
/* The input dimension d. */
size_t affect_spca_input_dim(const affect_spca *s);
/* The number of classes c and of training samples n. */
uint32_t affect_spca_classes(const affect_spca *s);
uint64_t affect_spca_train_size(const affect_spca *s);
affect_spca_kernel affect_spca_get_kernel(const affect_spca *s);
/* σ of the rbf kernel; 0 for the linear kernel. */
double affect_spca_sigma(const affect_spca *s);
/* The axes, p × d row-major, orthonormal rows. */
const double *affect_spca_axes(const affect_spca *s);
/* The p kept eigenvalues of M, descending, positive: λ_r = u_rᵀ Xᵀ H B H X u_r, so
 * Σ λ_r = (n − 1)² × the HSIC between the embedded training data (linear kernel) and y. */
const double *affect_spca_eigenvalues(const affect_spca *s);

/* ---- serialisation (a record inside a larger BLOB; docs/FORMATS.md) ----
 * Layout, version 1 (little-endian, offsets from the start of the record):
 *    0  4  magic "AFSP"
 *    4  4  format version (1)
 *    8  4  flags (0; 1: the axes are float32 — affect_spca_round_axes; 2: the axes are in
 *          4-bit blocks — affect_spca_compact_axes; not both)
 *   12  4  label kernel (0 linear, 1 rbf)
 *   16  4  classes c (≥ 2)
 *   20  4  axes p (1 .. c − 1)
 *   24  8  training samples n (≥ c)
 *   32  8  input dimension d (1 .. 2147483647)
 *   40  8  sigma (float64; > 0 and finite for rbf, 0 for linear)
 *   48  p × float64      eigenvalues, positive, non-increasing
 *       p × d × float64  axes, row-major (p × d × float32 with flag 1; with flag 2 each axis
 *                        in the 4-bit form of util/quant.h, canonical)
 *       8  FNV-1a 64-bit hash of the record's bytes before it
 */
#define AFFECT_SPCA_MAGIC "AFSP"
#define AFFECT_SPCA_VERSION 1u
#define AFFECT_SPCA_HEADER_SIZE 48u

/* Rounds every axis component to the nearest float32 value, so that the record stores the axes
 * as float32 (flag 1, half the bytes) and decodes to exactly these axes; false (and nothing
 * changed) when a component is beyond float32's range. The recognizer does this once its axes
 * are complete. */
bool affect_spca_round_axes(affect_spca *s);

/* Whether affect_spca_compact_axes(s, factor) can succeed (affect_q4_fits of every axis). */
bool affect_spca_compact_fits(const affect_spca *s, const double *factor);

/* Multiplies component t of every axis by factor[t] (d values, or NULL) and rounds each axis to
 * its 4-bit block form (util/quant.h), so that the record stores the axes with flag 2 and
 * decodes to exactly these axes. The caller has checked affect_spca_compact_fits. */
void affect_spca_compact_axes(affect_spca *s, const double *factor);

/* Appends the record to w (check w->failed once at the end, see util/bytes.h). */
void affect_spca_encode(const affect_spca *s, affect_bw *w);

/* Reads one record at r's position; on success *out is a new model and r is just past the
 * record (its position is unspecified after an error). Never reads outside r's bytes, and
 * allocates only after the data it will hold are known to be present. Errors
 * (AFFECT_ERR_FORMAT; offsets are r's, i.e. from the start of the reader's buffer):
 *   "sPCA: truncated in the header (offset 0)"           (fewer than 48 bytes)
 *   "sPCA: bad magic bytes (offset 0)"
 *   "sPCA: unknown format version 2, this build reads 1 (offset 4)"
 *   "sPCA: unknown flags 0x1 (offset 8)"
 *   "sPCA: unknown label kernel 2 (offset 12)"
 *   "sPCA: 1 class, need at least 2 (offset 16)"
 *   "sPCA: 3 axes, expected 1 .. 2 for 3 classes (offset 20)"
 *   "sPCA: 2 training samples for 3 classes (offset 24)"
 *   "sPCA: input dimension 0 is not in 1 .. 2147483647 (offset 32)"
 *   "sPCA: sigma -1 is not a positive finite number (offset 40)"
 *   "sPCA: sigma 0.5 with the linear kernel, expected 0 (offset 40)"
 *   "sPCA: truncated in the eigenvalues (offset 48)"
 *   "sPCA: truncated in the axes (offset 64)"
 *   "sPCA: truncated in the checksum (offset 224)"
 *   "sPCA: checksum mismatch, the record is corrupt (offset 224)"
 *   "sPCA: eigenvalue 1 is not a positive finite number (offset 56)"   (counted from 0)
 *   "sPCA: eigenvalue 1 exceeds eigenvalue 0 (offset 56)"
 *   "sPCA: non-finite value in the axes (offset 88)"
 *   AFFECT_ERR_NOMEM. */
affect_status affect_spca_decode(affect_br *r, affect_spca **out, affect_error *err);

/* ---- kernels and the HSIC ---- */

/* Fills b (n × n, row-major) with the label kernel B of y (values in 0 .. c−1). Errors
 * (AFFECT_ERR_INVALID): "unknown label kernel ...", "sigma must be a positive finite number",
 * "need at least 1 class", "row 4: label 9 is out of range (3 classes: 0 .. 2)". */
affect_status affect_spca_label_kernel(const uint32_t *y, size_t n, uint32_t c,
                                       affect_spca_kernel kernel, double sigma, double *b,
                                       affect_error *err);

/* The empirical HSIC tr(K H B H) / (n − 1)² of two n × n kernel matrices (row-major; need not
 * be symmetric); 0 when n < 2. O(n²) time, no allocation. Adding a constant to every entry of
 * K or of B does not change it; the means are removed first so large offsets cost little
 * precision. */
double affect_hsic(const double *k, const double *b, size_t n);

/* ---- k-nearest-neighbour classification ---- */

/* Classifies the query z (p values) among n training points train_z (n × p, row-major) with
 * labels train_y (values in 0 .. c−1): the k nearest by Euclidean distance (k clamped to n;
 * equal distances — compared as squared sums — go to the lower training index) vote, the
 * class with most votes wins; among tied classes the smallest sum of the voters' distances,
 * then the lower class index. Deterministic. *label receives the class; votes (c counts, may
 * be NULL) the votes per class. Errors (AFFECT_ERR_INVALID): "no training points", "the
 * embedding has no dimensions", "need at least 1 class", "k must be at least 1",
 * "training row 3: label 7 is out of range (3 classes: 0 .. 2)", "training row 3,
 * coordinate 1: non-finite value", "query coordinate 0: non-finite value";
 * AFFECT_ERR_NOMEM. */
affect_status affect_knn_classify(const double *train_z, const uint32_t *train_y, size_t n,
                                  uint32_t p, uint32_t c, const double *z, uint32_t k,
                                  uint32_t *label, uint32_t *votes, affect_error *err);

#ifdef __cplusplus
}
#endif
#endif
