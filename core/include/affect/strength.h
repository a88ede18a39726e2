/*
 * affect/strength.h — emotion strength by relative attributes (SCIENCE.md §6; the
 * emotion-strength paper): measure a continuous strength of a motion, synthesize a motion of a
 * target strength, and edit a motion to a target strength.
 *
 * Usage:
 *     const affect_motion *const *motions = ...;  uint32_t n = ...;   // n motions of one skeleton
 *     const int32_t *level = ...;                      // an index into names, or -1 (left out)
 *     const char *const names[3] = {"sad", "normal", "happy"};
 *     affect_error err;
 *     affect_strength_options opt;
 *     affect_strength_options_default(&opt);
 *     opt.features = AFFECT_STRENGTH_FEAT_KEYFRAMES;   // to edit (the default ranks by Fisher)
 *     affect_strength *s = NULL;
 *     affect_motion *stronger = NULL;  double r = 0;
 *     if (affect_strength_train(motions, level, NULL, n, names, 3, &opt, &s, &err) != AFFECT_OK
 *         || affect_strength_score(s, motions[0], &r, NULL, &err) != AFFECT_OK
 *         || affect_strength_edit(s, motions[0], r + 1, true, &stronger, NULL, &err) != AFFECT_OK)
 *         puts(err.msg);
 *     affect_motion_free(stronger);  affect_strength_free(s);
 *
 * Training (affect_strength_train), for n motions of one skeleton with levels from a label
 * order (e.g. sad < normal < happy):
 *   1. each motion is normalized (affect/normalize.h: the first frame's root translation and
 *      heading removed);
 *   2. q keyframes (default 13) by exact curve simplification (affect/keyframes.h);
 *   3. features: per keyframe the pose k_i (3J) and the velocity v_i = (k_i − k_{i−1})/Δt_i
 *      from the previous keyframe (v_0 = 0), concatenated: D = 6 J q;
 *   4. each feature divided by its training standard deviation (option standardize, default
 *      on; without it the centimetre-scale positions and velocities of the root dominate), then
 *      PCA to pca_dims (default 40; 0 = none), fitted on the training motions (the Gram matrix
 *      when n < D); its rank caps the dimension. Option relative: poses relative to the root
 *      joint (its own position kept), default off (the paper's first-frame-normalized poses);
 *   5. the ranker (affect/rank.h) on pairs from the levels (all pairs, or within the same
 *      content group; a seeded fraction); r(x) = wᵀ u is the strength, where the ranker's
 *      input u is (option features) the motion's normalized Fisher representation under a
 *      recognizer (affect/classifier.h with its defaults and the observations that go with
 *      them; option descriptors) trained on the training motions with the levels as its
 *      classes (FISHER, the default: the best of the four on all three tasks of
 *      docs/EVALUATION.md; a level without training motions is no class); or the Laban vector L
 *      (affect/laban.h, default options, on the motion as given) standardized by the training
 *      motions' means and population deviations, (L − mean)/sd, a missing component counting as
 *      0 (LABAN); or z (KEYFRAMES); or both, (a z, (L − mean)/sd) with a making the two blocks'
 *      total training variances equal (BOTH). With Laban features the ranker's C multiplies
 *      the mean pair loss (it gets C / the number of pairs) and, with cv_C (the default), is
 *      chosen among 0.01 … 100 by 5-fold cross-validation over the training motions
 *      (stratified by level; the C whose rankers order the held-out motions' pairs best);
 *      with keyframes and Fisher features C multiplies the sum;
 *   6. the regression z = f(s) from strength back to the (PCA) features, chosen by 5-fold
 *      cross-validated reconstruction error among kernel ridge regression (Gaussian kernel,
 *      bandwidth and ridge on a grid) and local linear regression (Gaussian weights, bandwidth
 *      on a grid); both errors are kept for the report. The paper's 10-unit MLP is not built:
 *      with tens to hundreds of training motions and a one-dimensional input, these two
 *      smoothers have closed forms, no random initialization, and are the same function class
 *      an MLP of 10 tanh units approximates.
 *
 * Synthesis (affect_strength_synthesize): z = f(s) → x (inverse PCA) → keyframe poses and
 * velocities → durations Δt_i = (Δk_i · v_i)/(v_i · v_i) (the training mean of that segment
 * when v_i ≈ 0 or the ratio is not positive) → C¹ Hermite interpolation at the model's frame
 * rate → the nearest rigid motion (affect_motion_rigid), which motion_to_bvh exports.
 *
 * Editing (affect_strength_edit): the motion's features x move along the learned direction,
 * z' = z + (s − r(x)) w/‖w‖² (so r(x') = s exactly), x' = x + Pᵀ(z' − z): what lies outside the
 * PCA subspace, the motion's own content, is kept. The motion itself is then warped: its
 * keyframes move by k'_i − k_i (interpolated linearly between keyframes and added to every
 * frame) and its time between keyframes is rescaled to the new durations; the result is put
 * back where the original stood (the inverse of step 1) and made rigid.
 *
 * With BOTH, editing moves z by the regression's f(s) − f(r(x)) instead (the ranker does not act
 * on z alone). A FISHER model edits the motion itself: steps along the gradient of r = wᵀu with
 * respect to its joint positions — through the means and diagonal covariance scores of the
 * recognizer's class HMMs (posteriors held fixed), the z-scores (0 where clipped), and the
 * observations' transform (affect_features_position_gradient) — each the Newton step of the
 * linearized r, halved until the rigid result comes closer, up to 12 steps; the frames, timing
 * and path stay the motion's. LABAN models refuse synthesis and editing, FISHER models
 * synthesis (AFFECT_ERR_INVALID): the motions they would make do not follow those rankers
 * (docs/EVALUATION.md, "Laban features"), and a Fisher ranker has no features to synthesize.
 *
 * Both then measure the strength of what they made (keyframes chosen again, the rigid
 * projection and the interpolation move it off the target) and correct the target by the miss,
 * t ← t + (s − r), up to AFFECT_STRENGTH_CORRECTIONS times while the miss shrinks, keeping the
 * closest motion.
 *
 * Errors: motions of another skeleton ("motion 3: 19 joints, the model has 22"), fewer frames
 * than keyframes, fewer than two levels present, no pairs, options out of range.
 */
#ifndef AFFECT_STRENGTH_H
#define AFFECT_STRENGTH_H

#include "affect/base.h"
#include "affect/classifier.h"
#include "affect/laban.h"
#include "affect/monitor.h"
#include "affect/motion.h"
#include "affect/rank.h"

#ifdef __cplusplus
extern "C" {
#endif

#define AFFECT_STRENGTH_MAGIC "AFST"
/* 3: Fisher features; 2: Laban features (keyframe-only models still write 1) */
#define AFFECT_STRENGTH_VERSION 3u
#define AFFECT_STRENGTH_MAX_LEVELS 64u
#define AFFECT_STRENGTH_MAX_PCA 4096u
#define AFFECT_STRENGTH_MAX_DIM 16777216u /* D = 6 J q */
#define AFFECT_STRENGTH_CV_FOLDS 5u
#define AFFECT_STRENGTH_CORRECTIONS 4u /* target corrections of synthesis and editing */
#define AFFECT_STRENGTH_TOL 0.01       /* strength miss at which the corrections stop */
#define AFFECT_STRENGTH_SD_FLOOR 1e-9  /* standardization: sd below this × the largest → 1 */
#define AFFECT_STRENGTH_SD_REL 0.1  /* … and at least this × the mean sd (no amplified noise) */
#define AFFECT_STRENGTH_V_MIN 1e-12 /* v·v below this: the segment keeps its mean duration */

typedef enum affect_strength_regression {
    AFFECT_STRENGTH_REG_AUTO, /* the better of the two by cross-validation (default) */
    AFFECT_STRENGTH_REG_KERNEL_RIDGE,
    AFFECT_STRENGTH_REG_LOCAL_LINEAR
} affect_strength_regression;

/* What the ranker sees (the regression and synthesis always use the keyframe features). */
typedef enum affect_strength_feature_kind {
    AFFECT_STRENGTH_FEAT_KEYFRAMES, /* the (PCA) keyframe features z */
    AFFECT_STRENGTH_FEAT_LABAN,     /* the standardized Laban vector */
    AFFECT_STRENGTH_FEAT_BOTH,      /* both blocks, weighted to equal total training variance */
    AFFECT_STRENGTH_FEAT_FISHER     /* the recognizer's representation (below; default) */
} affect_strength_feature_kind;

typedef struct affect_strength_options {
    affect_strength_feature_kind features; /* default AFFECT_STRENGTH_FEAT_FISHER */
    uint32_t keyframes;                    /* default 13 */
    uint32_t pca_dims;                     /* default 40; 0 = no PCA */
    double C;             /* ranker C (default 1); with Laban features it multiplies the MEAN
                             pair loss (the ranker gets C / number of pairs) */
    bool cv_C;            /* Laban features: choose C among {0.01, 0.1, 1, 10, 100} by 5-fold
                             cross-validation over the training motions (default true; C is then
                             the fallback when no fold can be scored) */
    double fraction;      /* of the pairs kept, (0, 1] (default 1) */
    bool similar;         /* use similar pairs (same label) too (default true) */
    bool relative;        /* poses relative to the root joint (the pelvis role, else joint 0),
                             the root's own position kept (default false: the paper's
                             first-frame-normalized poses) */
    bool standardize;     /* divide each feature by its training standard deviation before
                             PCA and the ranker (default true: +5 to +19 points of held-out
                             pair accuracy on all three tasks of docs/EVALUATION.md) */
    uint64_t seed;        /* the pair sample */
    unsigned descriptors; /* Fisher features: the descriptors the recognizer appends
                             (affect/summary.h mask; default its default, the kinematic
                             summaries; 0 = none, the Fisher scores alone) */
    affect_strength_regression regression;
    affect_monitor *monitor; /* may be NULL */
} affect_strength_options;

void affect_strength_options_default(affect_strength_options *opt);

typedef struct affect_strength {
    /* skeleton (for synthesis) */
    uint32_t n_joints;
    char **names;
    int32_t *parents;
    double fps;
    char unit[AFFECT_MOTION_UNIT_MAX + 1];
    /* features */
    uint32_t keyframes; /* q */
    uint32_t dim;       /* D = 6 J q */
    uint32_t pdim;      /* the ranker's dimension: the PCA dimension, or D without PCA */
    bool pca;
    bool relative;       /* relative poses (see the options) */
    uint32_t root;       /* the root joint of relative poses */
    double *scale;       /* D standard deviations (standardize), else NULL */
    double *mean;        /* D (PCA only; of the standardized features) */
    double *comps;       /* pdim × D, orthonormal rows (PCA only) */
    double pca_variance; /* fraction of the training variance kept (1 without PCA) */
    double *seg_dt;      /* q − 1 mean training durations (s) */
    /* Laban features (features ≠ KEYFRAMES): the ranker's vector is u = (L − lab_mean) / lab_sd
     * (a component missing in the motion counts as the mean: 0), preceded with BOTH by
     * kf_weight × z; its dimension is affect_strength_rank_dim(s) */
    affect_strength_feature_kind features;
    double lab_mean[AFFECT_LABAN_N], lab_sd[AFFECT_LABAN_N];
    double kf_weight; /* BOTH: the keyframe block's weight (else 0) */
    /* Fisher features (FISHER): a recognizer (affect/classifier.h, its defaults) trained on the
     * training motions with the levels as classes; the ranker's vector is a motion's normalized
     * Fisher representation under it (affect_classifier_eval's fisher, with its descriptors),
     * of dimension affect_classifier_dim(fisher) */
    affect_classifier *fisher;
    bool cv_C; /* C (below) was chosen by the inner cross-validation */
    /* ranker */
    double C;
    double *w; /* affect_strength_rank_dim(s): pdim (keyframes), 27 (laban), pdim + 27 (both),
                  the representation's dimension (fisher) */
    affect_rank_stats stats;
    /* levels */
    uint32_t n_levels;
    char **level_names;
    double *level_strength; /* mean strength of the training motions of each level */
    uint32_t *level_count;
    /* training set and regression */
    uint32_t n_train;
    double *train_r;                       /* n_train strengths */
    double *train_z;                       /* n_train × pdim */
    affect_strength_regression regression; /* the one used (never AUTO) */
    double reg_h, reg_lambda; /* bandwidth (strength units) and ridge (kernel ridge only) */
    double cv_kernel_ridge, cv_local_linear, cv_constant; /* mean squared error per motion */
    double *alpha; /* pdim × n_train (kernel ridge), else NULL */
    double *zbar;  /* pdim: the training mean of z */
} affect_strength;

/* Trains a model. level[i] indexes level_names (n_levels names, in increasing strength); −1
 * leaves motion i out. group (NULL, or n entries) restricts pairs to the same content. */
affect_status affect_strength_train(const affect_motion *const *motions, const int32_t *level,
                                    const uint32_t *group, uint32_t n,
                                    const char *const *level_names, uint32_t n_levels,
                                    const affect_strength_options *opt, affect_strength **out,
                                    affect_error *err);

/* The feature vector of a motion (D doubles; keyframes: q frames, may be NULL) and its PCA
 * coordinates (pdim doubles, may be NULL). */
affect_status affect_strength_features(const affect_strength *s, const affect_motion *m, double *x,
                                       double *z, uint32_t *keyframes, affect_monitor *mon,
                                       affect_error *err);

/* The ranker's dimension (the length of s->w). */
uint32_t affect_strength_rank_dim(const affect_strength *s);

/* The strength r(x) of a motion. */
affect_status affect_strength_score(const affect_strength *s, const affect_motion *m,
                                    double *strength, affect_monitor *mon, affect_error *err);

/* The regression's feature coordinates for a strength (pdim doubles). */
void affect_strength_predict(const affect_strength *s, double strength, double *z);

/* A motion of the target strength (rigid: projected to constant bone lengths, as the header
 * says; false: the interpolated positions as they are). */
affect_status affect_strength_synthesize(const affect_strength *s, double strength, bool rigid,
                                         affect_motion **out, affect_monitor *mon,
                                         affect_error *err);

/* m edited to the target strength (rigid as above). */
affect_status affect_strength_edit(const affect_strength *s, const affect_motion *m,
                                   double strength, bool rigid, affect_motion **out,
                                   affect_monitor *mon, affect_error *err);

/* (Re)fits the regression of s from its train_r and train_z (n_train × pdim) by 5-fold
 * cross-validation (see the file header): sets regression, reg_h, reg_lambda, the cv_* errors,
 * zbar and alpha. Training calls it; exposed for tests. */
affect_status affect_strength_fit_regression(affect_strength *s, affect_strength_regression want,
                                             affect_monitor *mon, affect_error *err);

void affect_strength_free(affect_strength *s);

affect_status affect_strength_encode(const affect_strength *s, unsigned char **out, size_t *size,
                                     affect_error *err);
affect_status affect_strength_decode(const unsigned char *data, size_t size, affect_strength **out,
                                     affect_error *err);

#ifdef __cplusplus
}
#endif
#endif
