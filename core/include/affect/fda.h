/*
 * affect/fda.h — functional analysis of movements (thesis chapter 3, SCIENCE.md §4): every
 * coordinate series of a motion becomes a smooth function (a B-spline expansion fitted by
 * penalized least squares, affect/bspline.h), and four dimensionality reductions of those
 * functions — FPCA, functional FDA, functional supervised PCA (HSIC) and functional Isomap —
 * are fitted on training motions and applied to unseen ones; k-NN classifies in the embedding,
 * and each class gets a prototype motion from the FPCA space (§3.2).
 *
 * Usage:
 *     const affect_hmm_seq *seqs = ...;  uint32_t n = ..., m = ...;   // T × m values each
 *     const uint32_t *y = ...;  const char *const classes[3] = {"happy", "sad", "angry"};
 *     affect_error err;
 *     affect_fda_config cfg;
 *     affect_fda_config_default(&cfg);
 *     cfg.method = AFFECT_FDA_FSPCA;
 *     affect_fda *f = NULL;
 *     uint32_t label;                                  // feat NULL: no prototype motions
 *     if (affect_fda_train(&cfg, NULL, seqs, n, m, y, classes, 3, &f, &err) != AFFECT_OK
 *         || affect_fda_classify(f, seqs[0].x, seqs[0].n_frames, 5, &label, NULL, &err)
 *                != AFFECT_OK)
 *         puts(err.msg);
 *     else
 *         printf("%s in %u dims\n", affect_fda_class_name(f, label), affect_fda_dims(f));
 *     affect_fda_free(f);
 *
 * Representation. A motion is T frames × m coordinates (the observation vectors of
 * affect/features.h: body-frame or first-frame-normalized joint positions). Its frames are put
 * at the normalized times t_j = j / (T − 1) — the linear length normalization: every motion
 * spans [0, 1] whatever its duration — and each of the m columns is fitted with G B-splines of
 * order k (affect_bspline_fit, penalty λ ∫ f″²), giving the coefficient matrix c (G × m,
 * row-major) = the vector c of h = G m values. λ is given, or chosen by generalized
 * cross-validation: the λ of the grid 10^(e/2), e = −30 .. 0, with the least GCV summed over
 * every coordinate of every training motion (ties: the smaller λ).
 *
 * The L² geometry. With M the Gram matrix of the basis, ⟨x_i, x_j⟩ = Σ_coordinates ∫ x_i x_j =
 * c_iᵀ (M ⊗ I) c_j = z_iᵀ z_j for z = (M^{1/2} ⊗ I) c, so the functional methods are the
 * ordinary ones on z (SCIENCE.md §4). They are computed in the dual: with C̃ the centred
 * coefficients (n × h) and W = C̃ (M ⊗ I), the Gram matrix of the centred functions is
 * K = C̃ Wᵀ (n × n), which needs the band matrix M only; affect_fda_gram_sqrt gives M^{1/2}
 * itself (the tests check that the dual equals PCA of the M^{1/2}-weighted coefficients).
 *   FPCA     K = V Λ Vᵀ; the covariance eigenvalues are Λ/(n − 1); the r-th score of a motion
 *            is ∫ ψ_r (x − μ) with the eigenfunction ψ_r = Σ e_r,g B_g, e_r = C̃ᵀ v_r / √λ_r
 *            (orthonormal in L²); scores = b_r · (c − c̄) with b_r = Wᵀ v_r / √λ_r.
 *   FSPCA    sPCA (affect/spca.h: HSIC, linear or Gaussian-RBF label kernel) on z, by its dual
 *            solver on K: the axes are Aᵀ W in coefficient space (p ≤ c − 1).
 *   FFDA     Fisher's discriminant on z, regularized: within the span of the training
 *            functions (their FPCA scores q, all R = rank K components), the axes a maximize
 *            aᵀ S_b a / aᵀ (S_w + γ (tr S_t / R) I) a (γ = ffda_reg, default 1e-3, S_t the
 *            total scatter), scaled so that aᵀ (S_w + …) a = 1; p ≤ c − 1. Without γ, S_w is
 *            singular whenever R ≥ n − c + 1, which is the rule with h ≫ n: the thesis's FFDA
 *            overfits for that reason.
 *   F-Isomap the L² distances between the training functions, the symmetric k-nearest-
 *            neighbour graph, geodesic distances D by Floyd–Warshall (the graph must be
 *            connected), classical MDS of D (B = −½ H D² H, Y = V Λ^{1/2}). An unseen motion x:
 *            δ_j = min over its k nearest training functions l of (‖x − x_l‖ + D_lj), then the
 *            landmark-MDS (Nyström) formula y = ½ Λ^{−1/2} Vᵀ (δ̄² − δ²), δ̄² the column means of
 *            D²; for a training motion it gives back its training coordinates.
 * Axis signs: each axis is turned so that its training coordinate of largest magnitude is
 * positive (FSPCA: affect/spca.h's rule). The embedding of the FPCA, FSPCA and FFDA models is
 * linear in the motion's coefficients, y = B (c − c̄).
 *
 * Landmark registration (alignment "landmarks"). Instead of t_j = j / (T − 1), each motion's
 * frames are put at registered times h(t_j), h a piecewise-linear warp of [0, 1] that takes
 * its landmarks to the model's template. Landmarks (affect_fda_find_landmarks): the start and
 * end (h(0) = 0, h(1) = 1) and the extrema of the joint trajectories, found on the overall
 * speed ‖x_{j+1} − x_j‖ (all coordinates) smoothed by a moving average of ± 3 % of T: its
 * minima (the joints at rest, where the trajectories turn) and maxima (peaks of the movement),
 * keeping those whose rise or fall to the next extremum is at least 15 % of the speed's range
 * (the least pronounced pair removed first) and at most 32, none within 2 % of either end.
 * The template: per class, the class's motion with the median landmark count is the
 * reference, every motion of the class is matched to it by dynamic programming
 * (affect_fda_match_landmarks), and the reference landmarks matched in at least half of the
 * class's motions are kept at the mean of their matched times; the class templates are merged
 * the same way (reference: the class template with the median count, kept when matched in at
 * least half of the classes). Every motion, training or unseen, is then matched to that one
 * template and warped (affect_fda_warp_times), so a training motion embeds to its training
 * coordinates. λ by GCV uses the registered times too. The prototypes are in template time.
 *
 * Prototypes (§3.2): the class centroid of the training scores on the first P FPCA
 * components (proto_dims; the thesis's is 3), mapped back by the inverse transform
 * c̄ + Σ q_r e_r; by default (proto_dims 0, "all") on every component, which is the class's mean
 * function c̄ + mean of its centred coefficients — the measured best: on bandai-namco-2-dev's
 * per-movement models the recognizer names 74–83 % of these prototypes' styles against 40–45 %
 * with 3 components (docs/EVALUATION.md, "Prototypes");
 * evaluated at the class's mean frame count (rounded, ≥ 2), its positions put on the feature
 * definition's skeleton (affect_features_posture_motion) and made rigid (affect_motion_rigid,
 * constant bone lengths), so motion_to_bvh exports it (when no observed joint has an observed
 * ancestor there are no bones: the positions are returned as they are). Every model, whatever
 * its method, keeps the P eigenfunctions and centroids for this, or (proto_dims 0) the c class
 * means (version 3 of the BLOB).
 *
 * Determinism: the same inputs give bit-identical models and embeddings on a given BLAS build.
 */
#ifndef AFFECT_FDA_H
#define AFFECT_FDA_H

#include "affect/bspline.h"
#include "affect/features.h"
#include "affect/hmm.h"
#include "affect/monitor.h"
#include "affect/spca.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum affect_fda_method {
    AFFECT_FDA_FPCA = 0,
    AFFECT_FDA_FFDA = 1,
    AFFECT_FDA_FSPCA = 2,
    AFFECT_FDA_FISOMAP = 3
} affect_fda_method;

/* Time alignment of the motions before the fits (see "Landmark registration" above). */
typedef enum affect_fda_alignment {
    AFFECT_FDA_ALIGN_LINEAR = 0,   /* t_j = j / (T − 1) */
    AFFECT_FDA_ALIGN_LANDMARKS = 1 /* piecewise-linear warp to the model's landmark template */
} affect_fda_alignment;

#define AFFECT_FDA_MAX_LANDMARKS 32u
#define AFFECT_FDA_MAX_DIMS 64u
#define AFFECT_FDA_MAX_ISOMAP_K 1024u
/* Eigenvalues at or below this fraction of the largest are treated as zero (rank). */
#define AFFECT_FDA_RANK_TOL 1e-10
/* The functions count as all equal when tr K ≤ this × Σ ‖x_i‖² (rounding of the mean). */
#define AFFECT_FDA_NOVAR_TOL 1e-20

typedef struct affect_fda_config {
    affect_fda_method method;  /* default FFDA, the measured best (docs/EVALUATION.md) */
    uint32_t order;            /* B-spline order k (default 4: cubic) */
    uint32_t n_basis;          /* G (default 200, the thesis's for recognition) */
    double lambda;             /* roughness penalty (default 1e-10; ignored with gcv) */
    bool gcv;                  /* choose λ by GCV (default false) */
    uint32_t dims;             /* embedding dimensions (default 3; 1 .. 64) */
    affect_spca_kernel kernel; /* FSPCA label kernel (default linear) */
    double sigma;              /* FSPCA RBF σ (default 1) */
    double ffda_reg;           /* FFDA γ (default 1e-3; ≥ 0) */
    uint32_t isomap_k;         /* F-Isomap neighbours (default 7) */
    uint32_t proto_dims; /* P FPCA components of the prototype space, 1 .. 64; 0 (the default):
                            all of them, the class means */
    affect_fda_alignment alignment; /* default linear (the measured best, docs/EVALUATION.md) */
    affect_monitor *monitor;        /* may be NULL */
} affect_fda_config;

void affect_fda_config_default(affect_fda_config *cfg);
/* NULL, or a message: "unknown method", "order must be at least 3 for the roughness penalty",
 * "dims must be from 1 to 64", "lambda must be a finite number, 0 or more", "unknown label
 * kernel", "sigma must be a positive finite number", "ffda_reg must be a finite number, 0 or
 * more", "isomap_k must be from 1 to 1024", "proto_dims must be from 1 to 64, or all", "unknown
 * alignment", and affect_bspline_check's. */
const char *affect_fda_config_check(const affect_fda_config *cfg);

typedef struct affect_fda affect_fda;

/* Trains on n motions (seqs[i].x: n_frames × m, row-major; at least 1 frame each) with labels
 * y (0 .. c − 1, every class present, c ≥ 2; class names classes[0 .. c − 1], valid UTF-8),
 * feat the observation definition they came from (copied into the model; NULL for plain
 * data, when m is free and there are no prototypes). Errors (AFFECT_ERR_INVALID unless said):
 * the configuration's, "need at least 3 motions", "need at least 2 classes", "m must be from
 * 1 to 4096", "m is 12 but the feature definition gives 9", "motion 4: label 9 is out of range
 * (3 classes)", "class 2 (\"sad\") has no motion", "motion 3: <the fit's error>", "the
 * training functions are all equal (no variance)", "the eigendecomposition did
 * not converge (LAPACK info 3)" (AFFECT_ERR_RANGE), the sPCA's ("the data carry no label
 * information …"), AFFECT_ERR_INTERRUPTED, AFFECT_ERR_NOMEM. */
affect_status affect_fda_train(const affect_fda_config *cfg, const affect_features *feat,
                               const affect_hmm_seq *seqs, uint32_t n, uint32_t m,
                               const uint32_t *y, const char *const *classes, uint32_t c,
                               affect_fda **out, affect_error *err);
void affect_fda_free(affect_fda *f);

/* The embedding of a motion x (T × m, T ≥ 1) into z (affect_fda_dims values), always finite on
 * success. Errors: the fit's ("sample 3, column 2: non-finite value", "the fit is singular …"),
 * "the embedding overflows (coordinate 0 is not finite)" (AFFECT_ERR_RANGE: data or a model
 * with values near DBL_MAX), AFFECT_ERR_NOMEM. */
affect_status affect_fda_embed(const affect_fda *f, const double *x, uint32_t T, double *z,
                               affect_error *err);
/* k-NN (affect_knn_classify's rules) of the embedding among the training embeddings; votes
 * (c counts) may be NULL. k ≥ 1 (clamped to n). */
affect_status affect_fda_classify(const affect_fda *f, const double *x, uint32_t T, uint32_t k,
                                  uint32_t *label, uint32_t *votes, affect_error *err);
/* The prototype of class label (see above). Errors: "class 5 is out of range (4 classes)",
 * "the model has no feature definition (trained on plain data): no prototypes", the rigid
 * projection's, AFFECT_ERR_NOMEM. */
affect_status affect_fda_prototype(const affect_fda *f, uint32_t label, affect_motion **out,
                                   affect_error *err);
/* The prototype's coefficients (G × m): c̄ + Σ_r centroid_r e_r (or c̄ + the class's mean
 * centred coefficients when proto_dims is 0). */
void affect_fda_prototype_coefs(const affect_fda *f, uint32_t label, double *coef);

/* Perturbation plot data (the thesis's Figure 3.3) for a linear method's axis r (0 .. p − 1) and
 * coordinate j (0 .. m − 1): at T equally spaced times (T ≥ 2) the mean function μ(t) and
 * μ(t) ± α σ_r w_r(t) / ‖w_r‖², where w_r is the axis's weight function (the score is
 * ∫ Σ_coordinates w_r (x − μ)), σ_r the standard deviation of the training scores on the axis
 * and ‖w_r‖² = ∫ Σ w_r²: the change of the motion that moves its score by ± α σ_r along the
 * axis with the least L² norm. For FPCA w_r is the eigenfunction ψ_r and the perturbation
 * ± α √λ_r ψ_r. mean, plus, minus: T values each. Errors (AFFECT_ERR_INVALID): "perturbation
 * plots need a linear method (fpca, ffda, fspca), not fisomap", "axis 4 is out of range (3
 * dimensions)", "coordinate 99 is out of range (42 coordinates)", "alpha must be a finite
 * number", "need at least 2 times", AFFECT_ERR_NOMEM. */
affect_status affect_fda_perturbation(const affect_fda *f, uint32_t r, uint32_t j, double alpha,
                                      uint32_t T, double *mean, double *plus, double *minus,
                                      affect_error *err);

/* ---- accessors ---- */
const affect_fda_config *affect_fda_get_config(const affect_fda *f); /* λ: the one used */
uint32_t affect_fda_dims(const affect_fda *f);                       /* p (may be below cfg.dims) */
uint32_t affect_fda_coords(const affect_fda *f);                     /* m */
uint32_t affect_fda_train_size(const affect_fda *f);                 /* n */
uint32_t affect_fda_classes(const affect_fda *f);                    /* c */
const char *affect_fda_class_name(const affect_fda *f, uint32_t k);
const affect_features *affect_fda_features(const affect_fda *f); /* or NULL */
/* The method's p eigenvalues (FPCA: covariance; FSPCA: sPCA's; FFDA: the generalized
 * between/within ratios; F-Isomap: MDS) and their explained shares (FPCA: of the total
 * variance; FSPCA: the training variance along each axis over the total variance; FFDA: of the
 * sum of all its c − 1 ratios; F-Isomap: of the sum of the positive MDS eigenvalues). */
const double *affect_fda_eigenvalues(const affect_fda *f);
const double *affect_fda_explained(const affect_fda *f);
/* The FPCA covariance eigenvalues (R of them, R = rank ≤ n − 1) and the total variance. */
uint32_t affect_fda_fpca_rank(const affect_fda *f);
const double *affect_fda_fpca_eigenvalues(const affect_fda *f);
double affect_fda_total_variance(const affect_fda *f);
const double *affect_fda_train_embedding(const affect_fda *f); /* n × p */
const uint32_t *affect_fda_train_labels(const affect_fda *f);  /* n */
/* The class's mean frame count over its training motions. */
double affect_fda_class_frames(const affect_fda *f, uint32_t k);
/* The mean function's coefficients (G × m) and the P eigenfunctions' (P × G × m; none when
 * affect_fda_proto_dims is 0: the prototypes are the class means). */
const double *affect_fda_mean(const affect_fda *f);
const double *affect_fda_eigenfunctions(const affect_fda *f);
uint32_t affect_fda_proto_dims(const affect_fda *f);

/* M^{1/2} (G × G, dense, row-major) of the basis's Gram matrix by its symmetric
 * eigendecomposition (LAPACK dsyevr; eigenvalues below 0 from rounding clipped to 0). */
affect_status affect_fda_gram_sqrt(const affect_bspline *b, double *out, affect_error *err);

/* The coefficients (G × m) of motion x (T × m) under the model's basis and λ. */
affect_status affect_fda_coefficients(const affect_fda *f, const double *x, uint32_t T,
                                      double *coef, affect_error *err);

/* ---- landmark registration ---- */

/* A landmark: a time in (0, 1) of the motion's normalized time and its type (+1: a peak of
 * the smoothed overall speed; −1: a rest, the speed's minimum, where the joints turn). */
typedef struct affect_fda_landmark {
    double t;
    int32_t type;
} affect_fda_landmark;

/* The landmarks of x (T × m), at most AFFECT_FDA_MAX_LANDMARKS, in time order (none when
 * T < 5 or the motion does not move). */
affect_status affect_fda_find_landmarks(const double *x, uint32_t T, uint32_t m,
                                        affect_fda_landmark *out, uint32_t *count,
                                        affect_error *err);
/* Monotone matching of a (na) to b (nb) (each ≤ AFFECT_FDA_MAX_LANDMARKS, in time order) by
 * dynamic programming: the least total |Δt| of the matched pairs (same type, |Δt| ≤ 0.2)
 * plus 0.1 per landmark left unmatched. The pairs (a[ia[k]], b[ib[k]]) in order; returns
 * their count. */
uint32_t affect_fda_match_landmarks(const affect_fda_landmark *a, uint32_t na,
                                    const affect_fda_landmark *b, uint32_t nb, uint32_t *ia,
                                    uint32_t *ib);
/* The registered times of a T-frame motion with landmarks a (na) matched to the template
 * (nt): times[j] = h(j / (T − 1)), h piecewise linear through (0, 0), the matched pairs
 * (a.t, template.t) that keep h increasing, and (1, 1). */
void affect_fda_warp_times(const affect_fda_landmark *a, uint32_t na,
                           const affect_fda_landmark *tmpl, uint32_t nt, uint32_t T, double *times);
/* The model's landmark template (count in *n; none with linear alignment). */
const affect_fda_landmark *affect_fda_template(const affect_fda *f, uint32_t *n);
/* The times at which the model fits motion x (T values): j / (T − 1), or registered. */
affect_status affect_fda_times(const affect_fda *f, const double *x, uint32_t T, double *times,
                               affect_error *err);

/* ---- BLOB (docs/FORMATS.md "Functional model") ---- */
#define AFFECT_FDA_MAGIC "AFFD"
/* Version 2 adds the landmark template (flags bit 0); models with linear alignment are still
 * written as version 1, byte for byte as before. */
#define AFFECT_FDA_VERSION 3u
#define AFFECT_FDA_HEADER_SIZE 96u
affect_status affect_fda_encode(const affect_fda *f, unsigned char **out, size_t *size,
                                affect_error *err);
/* Errors (AFFECT_ERR_FORMAT): "truncated: 10 bytes is shorter than the functional model
 * header", "not a functional model (bad magic bytes at offset 0)", "unknown format version 2,
 * this build reads 1 (offset 4)", "functional model checksum mismatch: the BLOB is corrupt",
 * "truncated in <part> (offset N)", "<field> <value> is out of range (offset N)",
 * "non-finite value in <part> (offset N)", "N unexpected bytes at the end (offset N)",
 * the feature definition's; AFFECT_ERR_NOMEM. */
affect_status affect_fda_decode(const unsigned char *data, size_t size, affect_fda **out,
                                affect_error *err);

#ifdef __cplusplus
}
#endif
#endif
