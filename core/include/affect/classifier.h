/*
 * affect/classifier.h — the hybrid generative–discriminative emotion recognizer (SCIENCE.md §3;
 * thesis chapter 4, Fig. 4.1): one HMM per class, Fisher scores of a motion under every class
 * HMM, a per-dimension normalization, a linear SVM, and supervised PCA with k-nearest-neighbour
 * classification in the projection. Maximum-likelihood recognition (the class HMM with the
 * highest log-likelihood) comes with it.
 *
 * Usage:
 *     const affect_features *feat = ...;               // affect_features_create
 *     const affect_hmm_seq *seqs = ...;  const uint32_t *y = ...;  uint32_t n = ...;
 *     const char *const labels[4] = {"neutral", "happy", "sad", "angry"};
 *     affect_error err;
 *     affect_classifier_config cfg;
 *     affect_classifier_config_default(&cfg);
 *     cfg.hmm.dim = affect_features_dim(feat);
 *     affect_classifier *c = NULL;
 *     affect_classifier_out o = {0};                   // only the labels wanted
 *     if (affect_classifier_train(&cfg, feat, seqs, NULL, y, n, labels, 4, &c, &err) != AFFECT_OK
 *         || affect_classifier_eval(c, seqs[0].x, seqs[0].n_frames, NULL, false, &o, NULL, &err)
 *                != AFFECT_OK)
 *         puts(err.msg);
 *     else
 *         printf("svm: %s\n", affect_classifier_label(c, o.svm));      // o.knn, o.ml alike
 *     affect_classifier_free(c);
 *
 * Training (affect_classifier_train), everything on the training sequences only:
 *   1. one HMM per class (affect_hmm_train, the same configuration and seed for every class);
 *   2. F_i = [F(x_i | Λ_1) … F(x_i | Λ_C)], each part affect_fisher_score with the chosen groups;
 *   0. with cfg->mirror on (or auto, when every observed joint has a mirror partner), the
 *      training set is every motion and its mirror image (left and right
 *      swapped, affect_features_mirror; descriptors by affect_descriptors_mirror), with the
 *      motion's class: a style or an emotion does not depend on which hand waves, and a
 *      recognizer that saw only right-hand waves then knows left-hand ones. Everything below
 *      runs on the 2n motions (the kNN keeps 2n training points);
 *   2b. with cfg->descriptors, the motion's descriptors d_i (affect_descriptors, computed by the
 *      caller from the motion with the feature definition's up axis) are appended: the
 *      representation is [F_i, d_i];
 *   3. normalization fitted on the rows F_i: z-score per dimension (mean, population standard
 *      deviation; a dimension that is constant over the training set keeps scale 1, so it is 0
 *      for every training motion), or none; z-scores are limited to ±score_clip (default 5),
 *      for training rows and evaluated motions alike. Without the limit one entry decides:
 *      the score of a tiny transition probability is Σ_t ξ_t(i, l) / a_il, nearly constant
 *      over the training motions (that is why a_il is tiny) and huge for a new motion that
 *      takes the transition, so its z-score reaches 10⁶ and more. On motion_synth's held-out
 *      performers this limit takes Fisher + SVM from 71 % to 100 % (tests/sql/affect.sql);
 *      With descriptors, their z-scores (after the limit) are multiplied by
 *      ω = √(descriptor_weight × D_F / D_d), D_F and D_d the two blocks' sizes: each z-scored
 *      entry adds about 1 to a squared norm, so the Fisher block (10³ .. 10⁶ entries) would
 *      drown a few dozen descriptors in the linear kernel; with ω the descriptor block counts
 *      descriptor_weight times as much as the whole Fisher block;
 *   4. linear SVM (affect/svm.h) with C given, or chosen from AFFECT_CLASSIFIER_C_GRID by
 *      seeded stratified inner cross-validation (svm_folds folds) when cfg->svm_c is 0;
 *   5. sPCA (affect/spca.h) with the label kernel and dims asked (dims are capped by the label
 *      kernel's rank: at most C − 1 for C classes), and the training rows' coordinates kept for
 *      kNN (k = knn_k, capped at the training count). With a grid (affect_classifier_grid),
 *      dims, σ and k are first chosen by inner cross-validation on the training rows. The
 *      inner folds reuse the HMMs and normalization fitted on all training motions (retraining
 *      the HMMs per inner fold would multiply the cost by the fold count); no motion outside
 *      the training set is ever used.
 * Training accuracies are kept for affect_classifier_info-style reports: ML and SVM by
 * resubstitution; kNN leave-one-out (each training motion among the others, since with itself
 * among its neighbours the count is meaningless).
 *
 * Evaluation (affect_classifier_eval) of a new sequence: log-likelihood under every class HMM
 * (ML label), its normalized Fisher representation, SVM decision values and label, sPCA
 * coordinates, kNN votes and label. Labels are class indices 0 .. C − 1 into the names given
 * at training.
 *
 * Binary form (docs/FORMATS.md, "classifier BLOB"): magic "AFCL", version, then the labels,
 * configuration, the class HMMs as model BLOBs (affect/hmm_blob.h, each with the feature
 * definition), normalization, SVM, sPCA, the training coordinates and labels, the training
 * report, and an FNV-1a 64 checksum of everything before it.
 *
 * Errors (AFFECT_ERR_INVALID unless said) name the place: "class \"sad\" has no training
 * motion", "motion 4: Fisher score under class \"angry\" is not finite", the HMM's, Fisher's,
 * SVM's and sPCA's own messages prefixed by the stage ("training the HMM of class \"happy\": …");
 * decoding: "truncated: …", "not a classifier (bad magic bytes at offset 0)", "classifier
 * checksum mismatch: the BLOB is corrupt" (AFFECT_ERR_FORMAT); AFFECT_ERR_NOMEM.
 *
 * Thread safety: no global state; a trained classifier is read-only and may be shared.
 */
#ifndef AFFECT_CLASSIFIER_H
#define AFFECT_CLASSIFIER_H

#include "affect/features.h"
#include "affect/fisher.h"
#include "affect/hmm.h"
#include "affect/spca.h"
#include "affect/summary.h"
#include "affect/svm.h"

#ifdef __cplusplus
extern "C" {
#endif

#define AFFECT_CLASSIFIER_MAGIC "AFCL"
#define AFFECT_CLASSIFIER_VERSION 3u
/* The representation's dimension D from which "storage": "auto" chooses the compact storage. */
#define AFFECT_CLASSIFIER_COMPACT_DIM 65536u
#define AFFECT_CLASSIFIER_MAX_CLASSES 64u
/* Training holds one block of the representation for every motion (n × one class HMM's Fisher
 * scores: 4,032 × 95,333 doubles, 3.1 GB, for 2,016 motions and their mirror images at the
 * thesis's configuration) in slabs of whole rows of at most this many bytes each: SQLite
 * refuses any single allocation of 2 GiB or more, and a large working set should not need one
 * block. A block that fits in one slab is computed exactly as with one array. */
#define AFFECT_CLASSIFIER_SLAB_BYTES ((size_t)1 << 30)
/* C values tried when svm_c = 0 (chosen by inner cross-validation; ties → the smallest) */
#define AFFECT_CLASSIFIER_C_GRID                                                                   \
    {                                                                                              \
        0.001, 0.01, 0.1, 1.0, 10.0, 100.0, 1000.0                                                 \
    }

#define AFFECT_CLASSIFIER_GRID_MAX 128u

/* Optional search over sPCA dims, RBF σ and k, by seeded stratified inner cross-validation on
 * the training motions (kNN accuracy in the projection fitted on the inner training rows);
 * a list left empty keeps the configuration's single value. Ties go to the earliest
 * combination in the order dims, σ, k as listed. */
typedef struct affect_classifier_grid {
    uint32_t n_dims, n_sigma, n_k;
    uint32_t folds; /* inner folds (default 5) */
    uint32_t dims[AFFECT_CLASSIFIER_GRID_MAX];
    double sigma[AFFECT_CLASSIFIER_GRID_MAX];
    uint32_t k[AFFECT_CLASSIFIER_GRID_MAX];
} affect_classifier_grid;

/* Mirror images in training: off, on (an observed joint without a partner is an error), or
 * auto (on when every observed joint has a partner, else off). A trained classifier's
 * configuration says what was done: off or on. */
typedef enum affect_classifier_mirror {
    AFFECT_MIRROR_OFF = 0,
    AFFECT_MIRROR_ON = 1,
    AFFECT_MIRROR_AUTO = 2
} affect_classifier_mirror;

/* How the classifier keeps (and its BLOB stores) its D-long vectors (docs/FORMATS.md, "The
 * compact storage"). FLOAT32: the normalization's mean and scale as float64, the SVM's weights
 * and the sPCA's axes as float32 (classifier version 2). COMPACT: the mean and scale rounded to
 * 24-bit floats, the ratio of the stored to the exact scale folded into the weights and axes,
 * which are then rounded to 4-bit codes in blocks of 64 with a float32 scale each, and the class
 * HMMs' symmetric covariances stored as triangles (version 3; about 4.4 times smaller at the
 * thesis's configuration; the decisions measured in docs/BENCHMARKS.md). AUTO (default):
 * COMPACT when D ≥ AFFECT_CLASSIFIER_COMPACT_DIM, else FLOAT32. Either way training rounds the
 * model it returns, so it is exactly the decoded BLOB's model. A decoded classifier says which
 * it is (FLOAT32 for versions 1 and 2). */
typedef enum affect_classifier_storage {
    AFFECT_STORAGE_AUTO = 0,
    AFFECT_STORAGE_FLOAT32 = 1,
    AFFECT_STORAGE_COMPACT = 2
} affect_classifier_storage;

typedef struct affect_classifier_config {
    affect_hmm_config hmm;             /* the class HMMs (dim = the feature dimension) */
    unsigned groups;                   /* Fisher groups (default AFFECT_FISHER_ALL) */
    bool zscore;                       /* z-score normalization (default true) */
    double score_clip;                 /* z-scores limited to ± this (default 5; 0 = no limit) */
    double svm_c;                      /* > 0, or 0 = inner cross-validation (default 0) */
    uint32_t svm_folds;                /* inner folds for C (default 5) */
    uint32_t spca_dims;                /* default 3 */
    affect_spca_kernel spca_kernel;    /* default RBF (the thesis's best) */
    double spca_sigma;                 /* RBF σ (default 0.25) */
    uint32_t knn_k;                    /* default 5 */
    affect_classifier_grid grid;       /* default: no search */
    unsigned descriptors;              /* motion-level descriptors appended (affect/summary.h:
                                          AFFECT_DESC_* mask, 0 = none; default kinematics) */
    double descriptor_weight;          /* their block's share of the kernel (default 0.1) */
    affect_classifier_mirror mirror;   /* train on every motion and its mirror image (default
                                          auto) */
    affect_classifier_storage storage; /* default auto (above) */
    uint32_t threads;                  /* training: class HMMs and motions' Fisher scores on this
                                          many threads (default 1, at most 64; the result does not
                                          depend on it; not stored in the BLOB) */
    size_t slab_bytes;                 /* training: the largest allocation for the rows of a block
                                          of Fisher scores; 0 (default) =
                                          AFFECT_CLASSIFIER_SLAB_BYTES (tests set less; not stored) */
} affect_classifier_config;

/* The measured best (docs/EVALUATION.md, "Choosing the defaults"), not the thesis's: class
 * HMMs of 5 states × 1 diagonal Gaussian, ergodic, 20 Baum–Welch iterations at most;
 * kinematic-summary descriptors with weight 0.1; mirror images auto; every other field as
 * listed above. The thesis's configuration is hmm 7 × 4 full, descriptors 0, mirror off, with
 * the first-frame observations. */
void affect_classifier_config_default(affect_classifier_config *cfg);
/* The observation options that go with those defaults: affect_features_options_default with
 * the body frame (positions only: no velocities, no root columns). */
void affect_classifier_features_default(affect_features_options *opt);
/* NULL when cfg is usable, else a static message ("knn_k must be at least 1"). */
const char *affect_classifier_config_check(const affect_classifier_config *cfg);

typedef struct affect_classifier affect_classifier; /* opaque */

/* Trains on n sequences with class indices y[i] in 0 .. n_classes − 1 named labels[k] (copied;
 * every class needs at least one sequence, n_classes ≥ 2). feat (copied) is the observation
 * definition the sequences were extracted with; cfg->hmm.dim must be its dimension. desc:
 * n × affect_descriptors_dim(cfg->descriptors) values, row i motion i's descriptors; required
 * when cfg->descriptors is not 0 ("the configuration appends descriptors but none were
 * given"), ignored otherwise; a non-finite value is "motion 3: descriptor 5 is not finite". */
affect_status affect_classifier_train(const affect_classifier_config *cfg,
                                      const affect_features *feat, const affect_hmm_seq *seqs,
                                      const double *desc, const uint32_t *y, uint32_t n,
                                      const char *const *labels, uint32_t n_classes,
                                      affect_classifier **out, affect_error *err);
void affect_classifier_free(affect_classifier *c);

/* What evaluating one sequence gives; every pointer may be NULL (not wanted). */
typedef struct affect_classifier_out {
    double *loglik;        /* n_classes: log P(x | Λ_k) */
    double *fisher;        /* dim: the normalized Fisher representation */
    double *decision;      /* n_classes (n_classes − 1) / 2: SVM one-vs-one decision values */
    double *embed;         /* spca_dims: sPCA coordinates */
    uint32_t *votes;       /* n_classes: kNN votes */
    uint32_t ml, svm, knn; /* labels (class indices) */
} affect_classifier_out;

/* Evaluates a sequence (T × dim, from affect_features_extract with the classifier's
 * definition) with its motion's descriptors desc (as for training; NULL when the classifier
 * has none). With ml_only, only loglik and ml are filled (no Fisher scores: much faster).
 * mon (may be NULL) is polled per block of frames: AFFECT_ERR_INTERRUPTED once it says stop. */
affect_status affect_classifier_eval(const affect_classifier *c, const double *x, uint32_t T,
                                     const double *desc, bool ml_only, affect_classifier_out *out,
                                     affect_monitor *mon, affect_error *err);

/* What evaluating a motion needs: its observations (*x, *n_frames, from affect_features_extract
 * with the classifier's definition) and, when the classifier appends descriptors, *desc
 * (affect_descriptors with its mask and the definition's up axis; NULL otherwise). Free both
 * with affect_free. Errors: the extraction's and the descriptors'. */
affect_status affect_classifier_observe(const affect_classifier *c, const affect_motion *m,
                                        double **x, uint32_t *n_frames, double **desc,
                                        affect_monitor *mon, affect_error *err);

/* ---- read-only views ---- */
const affect_classifier_config *affect_classifier_get_config(const affect_classifier *c);
uint32_t affect_classifier_n_classes(const affect_classifier *c);
const char *affect_classifier_label(const affect_classifier *c, uint32_t k);
const affect_features *affect_classifier_features(const affect_classifier *c);
const affect_hmm *affect_classifier_hmm(const affect_classifier *c, uint32_t k);
size_t affect_classifier_dim(const affect_classifier *c);      /* the whole representation */
size_t affect_classifier_part_dim(const affect_classifier *c); /* per class HMM */
const affect_svm *affect_classifier_svm(const affect_classifier *c);
const affect_spca *affect_classifier_spca(const affect_classifier *c);
uint32_t affect_classifier_n_train(const affect_classifier *c);
const uint32_t *affect_classifier_train_labels(const affect_classifier *c); /* n_train */
const double *affect_classifier_train_embed(const affect_classifier *c);    /* n_train × p */
const double *affect_classifier_norm_mean(const affect_classifier *c);      /* dim */
const double *affect_classifier_norm_scale(const affect_classifier *c);     /* dim */

typedef struct affect_classifier_report {
    double svm_c;        /* the C used */
    double svm_cv_acc;   /* inner cross-validated accuracy of that C (NaN when C was given) */
    double train_acc_ml; /* resubstitution */
    double train_acc_svm;
    double train_acc_knn; /* leave-one-out */
    double grid_cv_acc;   /* inner cross-validated kNN accuracy of the chosen combination (NaN
                             without a grid search); cfg's spca_dims, spca_sigma and knn_k hold
                             the chosen values */
} affect_classifier_report;
void affect_classifier_get_report(const affect_classifier *c, affect_classifier_report *r);

/* ---- salient features (thesis §4.2.4, Figs. 4.6 and 4.8) ----
 * The weight of a Fisher-score entry is the largest magnitude of its coefficient over the sPCA
 * axes (the axes are unit vectors in the normalized score space). For each class HMM, state
 * and mixture component, the component's weight is the largest weight among its covariance
 * entries, and top lists its top_n heaviest covariance entries (observation coordinates r ≤ s:
 * a variance when r = s), heaviest first, ties to the lower index. The classifier must have
 * been trained with the covariance group. */
#define AFFECT_SALIENCE_TOP_MAX 32u
typedef struct affect_salience_item {
    uint32_t r, s;
    double weight;
} affect_salience_item;
typedef struct affect_salience_row {
    uint32_t cls, state, mix;
    double weight;
    uint32_t n_top;
    affect_salience_item top[AFFECT_SALIENCE_TOP_MAX];
} affect_salience_row;
/* *rows (free with affect_free) receives n_classes × N × M rows, class-major then state, then
 * mixture. Errors: "the classifier has no covariance scores (trained without the covariances
 * group)", "top must be between 1 and 32". */
affect_status affect_classifier_salience(const affect_classifier *c, uint32_t top_n,
                                         affect_salience_row **rows, size_t *n_rows,
                                         affect_error *err);

/* ---- binary form ---- */
affect_status affect_classifier_encode(const affect_classifier *c, unsigned char **out,
                                       size_t *size, affect_error *err);
affect_status affect_classifier_decode(const unsigned char *data, size_t size,
                                       affect_classifier **out, affect_error *err);

#ifdef __cplusplus
}
#endif

#endif
