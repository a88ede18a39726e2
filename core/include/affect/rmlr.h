/*
 * affect/rmlr.h — elastic-net regularized multinomial logistic regression (RMLR), the thesis's
 * tool for finding the salient (discriminative) Laban components of each emotion.
 *
 * Usage:
 *     const double *x = ...;  size_t n = ..., p = ...;     // n × p, row-major
 *     const uint32_t *y = ...;                         // classes 0 .. 3
 *     affect_error err;
 *     affect_rmlr_options o;
 *     affect_rmlr_options_default(&o);                 // alpha and lambda by cross-validation
 *     affect_rmlr *fit = NULL;
 *     double probs[4];
 *     if (affect_rmlr_cv(x, n, p, y, 4, &o, &fit, &err) != AFFECT_OK) { puts(err.msg); return; }
 *     const double *beta = affect_rmlr_beta(fit);      // K × p; beta[k p + j] != 0: salient
 *     printf("class %u, beta %g\n", affect_rmlr_predict(fit, x, probs), beta[0]);
 *     affect_rmlr_free(fit);
 *
 * Model, for K classes and p features:
 *     P(y = k | x) = exp(β0k + βkᵀz) / Σ_l exp(β0l + βlᵀz),
 * where z is x standardized: z_j = (x_j − mean_j) / sd_j with the training data's mean and
 * population standard deviation (divisor n). A constant feature (all training values equal) has
 * sd 0, z_j = 0 and coefficient 0. Coefficients are reported on this standardized scale, so
 * their sizes are comparable across features (that is what "salient components" need); a
 * feature is salient for class k when β_kj ≠ 0. The fit minimises
 *     −(1/n) Σ_i log P(y_i | x_i) + λ Σ_k Σ_j (α|β_kj| + (1−α)/2 β_kj²)
 * (intercepts unpenalised; as the softmax is unchanged by adding one constant to every
 * intercept, the intercepts are reported centred: Σ_k β0k = 0).
 *
 * Method (Friedman, Hastie & Tibshirani 2010, "Regularization paths for generalized linear
 * models via coordinate descent"): for each class in turn, a partial Newton step — the
 * quadratic approximation of the log-likelihood in that class's parameters, the others held —
 * solved by cyclic coordinate descent with soft-thresholding and an active set; the step is
 * halved until the penalised objective does not increase; warm starts along a decreasing λ path.
 * Screening (sequential strong rule, Tibshirani et al. 2012, by feature over the classes as
 * glmnet): at λ after λ', coordinate descent visits only the features with a non-zero
 * coefficient or max_k |g_kj| ≥ α(2λ − λ'), g the log-likelihood's gradient at the fit of λ'
 * (the threshold is αλ for the first λ fitted, or one larger than the previous); after it
 * converges, every other feature's KKT condition (max_k |g_kj| ≤ αλ at the new fit) is checked
 * and any that fails joins the set and the fit goes on, so the rule only saves work and never
 * changes the solution. Once the signs of the coefficients settle (by default, options.solver),
 * Newton's method on the non-zero coefficients and the intercepts, with the signs held, takes
 * over from the cycles (where the data are nearly separable the cycles crawl: a λ took 13 on
 * average, up to 80), its Hessian's Cholesky factor kept along the path, updated as
 * coefficients enter or leave; zero coefficients whose KKT condition fails join it. At α = 1,
 * where a feature's coefficients can sometimes be shifted together at no cost, the solution is
 * moved to the sparsest such point (one coefficient 0). The path is not stopped early (glmnet stops
 * when the fraction of deviance explained reaches 0.999 or changes by less than 1e-5 between λ
 * values): every n_lambda value is fitted.
 *
 * λ path: λ_max = max_kj |(1/n) Σ_i z_ij (y_ik − π_k)| / max(α, 1e-3), with π_k the class
 * frequencies (the gradient at the intercept-only fit): for α ≥ 1e-3 it is the smallest λ at
 * which every β is 0 (below 1e-3 it is glmnet's convention and the first fit is already
 * slightly non-zero). The automatic path has n_lambda values log-spaced from λ_max down to
 * λ_max × lambda_min_ratio (1e-4 when n > p, else 1e-2, when the option is 0).
 *
 * Convergence: a λ's fit stops when a full cycle over the classes changes the penalised
 * objective by at most tol relative (each class's inner coordinate descent stops when no
 * v_j Δβ_j², v_j the weighted variance of feature j, exceeds tol); it gives up after max_iter
 * coordinate-descent passes (one pass = one sweep over one class's coefficients), and is then
 * reported as not converged (a flag, not an error). Newton's method stops when the decrease its
 * quadratic model promises (half of gᵀH⁻¹g) is at most tol/100 relative and the zero
 * coefficients meet their KKT conditions within 0.3 √tol relative to λα (1e-4 at the default). The
 * criteria are on the objective's scale, as glmnet's; the tests check the KKT conditions to 2e-6
 * with tol = 1e-13 (on the corpus's Laban vectors with the default tol, the chosen models' largest
 * violations are 6e-7 to 7e-5 of λ with Newton's method, 1.5e-4 to 1e-2 with the cycles alone).
 *
 * Everything is deterministic: fixed orders, plain loops, no BLAS, the folds seeded; the
 * result of affect_rmlr_cv is the same bytes whatever its number of threads.
 */
#ifndef AFFECT_RMLR_H
#define AFFECT_RMLR_H

#include "affect/base.h"
#include "affect/monitor.h"

/* the byte writer and reader of the BLOB codec (internal: core/util/bytes.h) */
typedef struct affect_bw affect_bw;
typedef struct affect_br affect_br;

#ifdef __cplusplus
extern "C" {
#endif

/* Number of classes, 2 .. AFFECT_RMLR_MAX_CLASSES. */
#define AFFECT_RMLR_MAX_CLASSES 256u
/* Features and λ values at most (bounds of the encoding's counts). */
#define AFFECT_RMLR_MAX_FEATURES 1048576u
#define AFFECT_RMLR_MAX_LAMBDAS 1048576u
/* Samples at most. */
#define AFFECT_RMLR_MAX_SAMPLES 4294967295u
/* Number of α in the default grid 0.05, 0.10, …, 1.00. */
#define AFFECT_RMLR_DEFAULT_N_ALPHA 20u
/* Threads of affect_rmlr_cv at most. */
#define AFFECT_RMLR_MAX_THREADS 64u
/* options.solver (see the method above). */
#define AFFECT_RMLR_SOLVER_NEWTON 0u
#define AFFECT_RMLR_SOLVER_CD 1u
/* Version of the encoding written by affect_rmlr_encode (1, headerless, is still read). */
#define AFFECT_RMLR_FORMAT_VERSION 2u
#define AFFECT_RMLR_MAGIC "AFRL"

typedef struct affect_rmlr_options {
    uint32_t n_lambda;       /* λ values on the automatic path (100) */
    double lambda_min_ratio; /* λ_min / λ_max in (0, 1); 0: 1e-4 if n > p, else 1e-2 */
    const double *alphas;    /* α grid for affect_rmlr_cv, each in [0, 1]; NULL = the default */
    uint32_t n_alpha;        /* length of alphas (ignored when alphas is NULL) */
    uint32_t folds;          /* cross-validation folds (10) */
    uint64_t seed;           /* for the folds (0) */
    uint32_t max_iter;       /* coordinate-descent passes per λ at most (10000) */
    double tol;              /* convergence threshold (1e-7; see above) */
    uint32_t threads;        /* affect_rmlr_cv: α values cross-validated at once, each in its
                                own thread (1; 1 .. AFFECT_RMLR_MAX_THREADS = 64) */
    affect_monitor *monitor; /* stop and progress hooks (NULL) */
    uint32_t solver;         /* AFFECT_RMLR_SOLVER_NEWTON (0, the default: coordinate descent,
                                then Newton steps once the signs settle) or _CD (1: coordinate
                                descent alone, the method before issue 13; slower) */
} affect_rmlr_options;

/* The defaults above (alphas NULL, n_alpha 20). */
void affect_rmlr_options_default(affect_rmlr_options *o);

typedef struct affect_rmlr affect_rmlr; /* opaque: the chosen fit */

/* Fits the whole path for one α on x (n × p, row-major) with classes y[i] in 0 .. K−1, every
 * class present. lambdas: n_lambda given values (positive, finite; warm starts follow the given
 * order, so give them decreasing), or NULL for the automatic path of n_lambda values. o supplies
 * lambda_min_ratio, max_iter, tol and solver (NULL = defaults; its n_lambda, alphas, folds, seed
 * and threads are not used). Outputs, each optional (NULL): lambda_out (n_lambda), beta_out
 * (n_lambda × K × p: for path index l, class k, feature j at [(l·K + k)·p + j]), beta0_out
 * (n_lambda × K), converged_out (n_lambda: 1 converged, 0 gave up after max_iter passes).
 * Errors (AFFECT_ERR_INVALID unless said), in the order checked: "need at least 1 sample",
 * "need at least 1 feature", "too many features: 2000000 (at most 1048576)" (RANGE), "too many
 * samples: …" (RANGE), "need at least 2 classes, got 1", "at most 256 classes, got 300",
 * "alpha must be in [0, 1], got 1.5", "need at least 1 lambda", "too many lambdas: 2000000 (at
 * most 1048576)" (RANGE), "lambda 3 = -1 is not a positive finite number", the options'
 * errors (see affect_rmlr_cv), "sample 5: class 7 out of range 0 .. 2", "sample 3, feature 17
 * is not finite", "class 2 has no sample"; AFFECT_ERR_NOMEM. */
affect_status affect_rmlr_fit_path(const double *x, size_t n, size_t p, const uint32_t *y,
                                   uint32_t K, double alpha, const double *lambdas,
                                   uint32_t n_lambda, const affect_rmlr_options *o,
                                   double *lambda_out, double *beta_out, double *beta0_out,
                                   uint8_t *converged_out, affect_error *err);

/* Chooses (α, λ) by stratified k-fold cross-validated misclassification and refits on all the
 * data at the choice. The folds are affect_stratified_folds(y, n, K, folds, seed) (affect/svm.h).
 * For each α, the λ path is the automatic one of all the data (as cv.glmnet does); each fold's
 * model is fitted along it on the other folds (standardized with their own means and sds) and
 * predicts the held-out samples after each λ (argmax of the probabilities, a tie going to the
 * smallest class). The error of (α, λ) is the number misclassified over all folds divided by n;
 * the smallest wins, ties going to the larger λ (sparser), then the larger α. The refit follows
 * the same path from λ_max down to the chosen λ. *out is NULL on failure.
 * Threads: the α values are independent, and with o->threads = T > 1 they are cross-validated
 * T at a time: the calling thread and T − 1 C11 threads each take the next α (in grid order)
 * until none is left, and run its folds along its path with a fitter of their own; each α's
 * miss counts go to its own row, so every α computes exactly what it computes alone and the
 * model is the same bytes as with 1 thread. Everything is allocated on the calling thread
 * before the others start (T fitters of the data's size), so the workers allocate nothing and
 * cannot fail, and the allocator installed with affect_set_allocator is only ever called from
 * the calling thread; a thread that cannot be created (or a lock that cannot be) leaves its
 * share to the calling thread. More threads than α values are not started. The refit runs on the
 * calling thread.
 * Errors: those of affect_rmlr_fit_path for the data, then "class 2 has 1 sample
 * (cross-validation needs at least 2)", and the options' (AFFECT_ERR_INVALID): "n_lambda must
 * be at least 1", "too many lambdas: …" (RANGE), "lambda_min_ratio must be in (0, 1), or 0 for
 * automatic, got 2", "need at least 1 alpha", "alpha 3 = 1.5 is not in [0, 1]", "need at
 * least 2 folds, got 1", "threads must be from 1 to 64, got 0", "max_iter must be at least
 * 1", "tol must be a positive finite number, got 0", "solver must be 0 (Newton) or 1 (CD), got
 * 2"; AFFECT_ERR_NOMEM. */
affect_status affect_rmlr_cv(const double *x, size_t n, size_t p, const uint32_t *y, uint32_t K,
                             const affect_rmlr_options *o, affect_rmlr **out, affect_error *err);

void affect_rmlr_free(affect_rmlr *m);

/* ---- accessors ---- */
uint32_t affect_rmlr_n_classes(const affect_rmlr *m);
size_t affect_rmlr_n_features(const affect_rmlr *m);
/* Number of training samples of the refit. */
uint32_t affect_rmlr_n_train(const affect_rmlr *m);
double affect_rmlr_alpha(const affect_rmlr *m);
double affect_rmlr_lambda(const affect_rmlr *m);
/* Index of the chosen λ on the path. */
uint32_t affect_rmlr_lambda_index(const affect_rmlr *m);
/* Cross-validated misclassification rate of the choice, in [0, 1]. */
double affect_rmlr_cv_error(const affect_rmlr *m);
/* Whether the refit at the chosen λ converged. */
bool affect_rmlr_converged(const affect_rmlr *m);
/* The chosen α's λ path (*count values) and its cross-validated errors (as many). */
const double *affect_rmlr_lambdas(const affect_rmlr *m, uint32_t *count);
const double *affect_rmlr_cv_errors(const affect_rmlr *m);
/* Coefficients (K × p, row k = class k, standardized scale) and intercepts (K). */
const double *affect_rmlr_beta(const affect_rmlr *m);
const double *affect_rmlr_intercepts(const affect_rmlr *m);
/* The training means and population standard deviations (p each; sd 0 = constant feature). */
const double *affect_rmlr_means(const affect_rmlr *m);
const double *affect_rmlr_sds(const affect_rmlr *m);

/* The most probable class of x (p raw, unstandardized values; a tie goes to the smallest
 * class); probs (K values, optional) receives the probabilities. x is not checked. */
uint32_t affect_rmlr_predict(const affect_rmlr *m, const double *x, double *probs);

/* Missing values: replaces every non-finite value (NaN, ±∞) of x (n × p, row-major) by the
 * mean of the finite values of its column (their sum in row order divided by their count), or
 * by 0 when the column has none; finite values are left as they are. For Laban vectors whose
 * components could not be computed, before affect_rmlr_cv (which refuses non-finite values). */
void affect_impute_column_means(double *x, size_t n, size_t p);

/* ---- serialisation ----
 * Layout, version 2 (little-endian, through util/bytes.h; docs/FORMATS.md), offsets
 * relative to the start:
 *    0  4    magic "AFRL"
 *    4  4    format version (2)
 *    8  4    flags (0)
 *   12  8    total length N of the record, header and checksum included (uint64)
 *   20  …    the body: version 1's fields after its version byte (below, offsets + 19)
 *  N-8  8    checksum: FNV-1a 64 of every byte of the record before it
 * Version 1 (written before the header existed; still read: fits cached in laban indexes):
 *    0  1    format version (1)
 *    1  4    classes K (2 .. 256)
 *    5  4    features p (1 .. 1048576)
 *    9  4    training samples n (≥ K)
 *   13  4    λ count L (1 .. 1048576)
 *   17  4    chosen λ index (< L)
 *   21  1    converged (0 or 1)
 *   22  8    α (float64 in [0, 1])
 *   30  8    cross-validated error (float64 in [0, 1])
 *   38  8L   λ path (float64, positive, finite)
 *       8L   cross-validated errors along it (float64 in [0, 1])
 *       8p   means (float64, finite)
 *       8p   standard deviations (float64, finite, ≥ 0)
 *       8K   intercepts (float64, finite)
 *       8Kp  coefficients, class after class (float64, finite)
 * Version 1 has no checksum and no length: decoding it stops after the coefficients. */

/* Appends m to w in version 2 (a failed allocation sets w->failed). */
void affect_rmlr_encode(const affect_rmlr *m, affect_bw *w);

/* Reads a model (version 2, or version 1 when the first byte is 1) from r at its offset and
 * advances past it; every count and length is checked before anything is read or allocated;
 * offsets are r's (AFFECT_ERR_FORMAT). Version 2: "RMLR: truncated: 3 bytes is shorter than
 * the 12-byte header", "RMLR: not an RMLR fit (bad magic bytes at offset 0)", "RMLR: unknown
 * format version 3 (this build reads 1 .. 2)", "RMLR: flags 0x1 are not 0 (offset 8)",
 * "RMLR: truncated: 600 bytes, the header says 1000 (offset 12)", "RMLR: checksum mismatch:
 * the fit is corrupt (offset 992)", "RMLR: 8 bytes follow the coefficients (offset 984)"; then
 * the body's errors, at offsets 19 bytes further than version 1's. Version 1 (and the body):
 * "RMLR: truncated in the lambdas (offset 38)", "RMLR: class count 1 out of range 2 .. 256
 * (offset 1)", "RMLR: feature count 0 out of range 1 .. 1048576 (offset 5)", "RMLR: sample
 * count 1 below the class count 2 (offset 9)", "RMLR: lambda count 0 out of range 1 .. 1048576
 * (offset 13)", "RMLR: lambda index 5 not below the lambda count 5 (offset 17)", "RMLR:
 * converged flag 2 is not 0 or 1 (offset 21)", "RMLR: alpha = 2 is not in [0, 1] (offset
 * 22)", "RMLR: cross-validation error 2 is not in [0, 1] (offset 30)", "RMLR: lambda 3 = -1 is
 * not a positive finite number (offset 62)", "RMLR: cross-validation error 2 is not in [0, 1]
 * (offset 70)" (along the path), "RMLR: non-finite value in the means (offset 90)" (likewise
 * "the intercepts", "the coefficients"), "RMLR: standard deviation -1 is not a non-negative
 * finite number (offset 98)"; AFFECT_ERR_NOMEM. *out is NULL on failure. */
affect_status affect_rmlr_decode(affect_br *r, affect_rmlr **out, affect_error *err);

#ifdef __cplusplus
}
#endif
#endif
