/*
 * affect/generate.h — affective motion generation by an HMM trained on Laban nearest
 * neighbours (SCIENCE.md §5 steps 5–7; thesis §5.3, Fig. 5.4), given the neighbours already
 * chosen by the caller (steps 1–4 select them), and the DTW distance used to judge how much of
 * the desired path a generated motion keeps.
 *
 * Usage:
 *     const affect_motion *neutral = ..., *neighbours[5] = ...;   // 5 neighbours
 *     affect_error err;
 *     affect_generate_options opt;
 *     affect_generate_options_default(&opt);           // 12 states, n_d = 0, 3 Hz, s = 1
 *     affect_generate_report rep;
 *     affect_motion *sad = NULL;
 *     if (affect_generate(neutral, neighbours, 5, &opt, &sad, &rep, &err) != AFFECT_OK)
 *         puts(err.msg);
 *     else
 *         affect_free(rep.path);                       // rep.path: the Viterbi states
 *     affect_motion_free(sad);
 *
 * Observations. Every joint of the desired motion x_d, normalized as the HMM engine's default
 * feature definition does (affect/features.h with normalize = true, scale = auto: the first
 * frame's horizontal root position and heading removed, positions divided by the right arm
 * length when the right_shoulder and right_hand roles resolve in x_d); each neighbour gets the
 * same definition, normalized by its own first frame. Up axis: opt->up_axis.
 * With opt->keep_path (the default), the root's (the pelvis role's, else joint 0's)
 * horizontal position at each frame is then
 * subtracted from every joint of that frame (of x_d and of every neighbour alike), so the HMM
 * models postures about a travelling root, and x_d's own horizontal root path is added back
 * to the output frame by frame (unfiltered): a walk stays a walk along its own path, and a
 * neighbour that travels (or stands still) does not drag the output off it. Without it the
 * observations are the positions relative to the first frame, as the thesis's (hand and arm
 * movements, no travel).
 *
 * Skeletons. A neighbour is used only when its joint names are exactly those of x_d (the same
 * set, any order); any other neighbour is EXCLUDED — never mapped by roles, never mixed — and
 * counted in the report. When every neighbour is excluded the call fails. A neighbour at
 * another frame rate is an error (resample it first), since state durations are in frames.
 *
 * Method (HMM_NN). opt->states states, one full-covariance Gaussian per state, ergodic, start
 * fixed to the first state, trained by Baum–Welch (affect_hmm_train with opt->seed,
 * opt->max_iter, opt->tol and the covariance floor opt->reg) on the used neighbours (in their
 * order) followed by opt->copies copies of x_d's observations; every sequence initialised from
 * N equal segments. Every training sequence must have at least `states` frames (an error
 * names the first that has not; the state count is never reduced silently); x_d itself may be
 * shorter when copies = 0. Then the Viterbi path S of x_d's observations under the model with
 * every state covariance multiplied by opt->covariance_scale (s): log N(x; μ, sΣ) =
 * −½ d²_Σ(x, μ) / s − (m/2) log s + const, so s weighs the emission term against the
 * transitions by 1/s — s > 1 lets the path follow x_d more loosely (fewer state changes,
 * stronger affect), s < 1 more tightly; s = 1 is the trained model. Output frame t is the mean
 * of state S_t (opt->render = AFFECT_GENERATE_STEPS, the thesis's), or, with
 * AFFECT_GENERATE_LINEAR, each run of equal states of S contributes its mean at the run's
 * centre frame (real-valued) and frames between two centres are linear between the two means
 * (the first and last means held before the first and after the last centre), so that the
 * output has no jumps between state means; then it is low-pass filtered coordinate by coordinate
 * (affect_lowpass: zero-lag Butterworth at opt->cutoff_hz for x_d's fps; not filtered when the
 * cut-off is 0, at or above the Nyquist frequency, or the output has one frame), then de-normalized
 * by the inverse of x_d's normalization transform: p = origin + Rᵀ (scale · p'). With opt->rigid
 * (the default) these positions are then made a skeletal motion that plays them with constant bones
 * (affect_motion_rigid, AFFECT_RIGID_SKELETON, the desired motion's median bone lengths): it
 * exports to BVH as it is. The result has x_d's joint names, parents, fps, unit and frame
 * count.
 *
 * Errors (0-based neighbour indices): AFFECT_ERR_INVALID for
 *   "no desired motion", "no neighbours", "neighbour 2 is missing",
 *   "states must be between 1 and 256" (and the engine's other option messages),
 *   "copies must be at most 1000, got 5000",
 *   "cut-off must be a finite frequency of 0 Hz or more, got -1",
 *   "covariance scale must be finite and greater than 0, got 0",
 *   "no neighbour has the desired motion's skeleton (joint names)",
 *   "neighbour 1 is at 60 fps, the desired motion at 30 (resample it first)",
 *   "neighbour 3 has 8 frames, fewer than the 12 states",
 *   "the desired motion has 8 frames, fewer than the 12 states (it is trained on with copies > 0)";
 * the normalization's own errors prefixed with "desired motion: " or "neighbour 2: "
 * (AFFECT_ERR_MISSING when the heading or arm roles do not resolve); the engine's numerical
 * errors (AFFECT_ERR_RANGE); "out of memory" (AFFECT_ERR_NOMEM). Nothing leaks on any error.
 */
#ifndef AFFECT_GENERATE_H
#define AFFECT_GENERATE_H

#include "affect/monitor.h"
#include "affect/normalize.h"

#ifdef __cplusplus
extern "C" {
#endif

#define AFFECT_GENERATE_MAX_COPIES 1000u

/* How the output is drawn from the Viterbi path S (before the low-pass filter). */
typedef enum affect_generate_render {
    AFFECT_GENERATE_STEPS = 0, /* the thesis's: frame t is the mean of state S_t */
    AFFECT_GENERATE_LINEAR = 1 /* state means at the centres of S's runs, linear in between */
} affect_generate_render;

typedef struct affect_generate_options {
    uint32_t states;               /* HMM states N (default 12) */
    uint32_t copies;               /* n_d copies of x_d added to the training set (default 0) */
    double cutoff_hz;              /* low-pass cut-off of the output (default 3; 0 = no filter) */
    double covariance_scale;       /* s > 0 multiplying every state covariance for Viterbi (1) */
    uint64_t seed;                 /* k-means seeding of the engine (default 1) */
    uint32_t max_iter;             /* Baum–Welch iterations at most (default 50) */
    double tol;                    /* relative log-likelihood change to stop (default 1e-4) */
    double reg;                    /* covariance diagonal floor, in normalized units² (1e-4) */
    int up_axis;                   /* 0 = x, 1 = y (default), 2 = z */
    affect_generate_render render; /* AFFECT_GENERATE_STEPS (default) or _LINEAR */
    bool keep_path;                /* keep x_d's horizontal root path (default true; see above) */
    bool rigid; /* output made a rigid skeletal motion (default true; see above) */
    /* Optional clock (seconds, monotonic) for the report's stage times; NULL (default) = not
     * timed. The core has no clock of its own: a benchmark passes one. It never changes the
     * result. */
    double (*clock)(void);
    affect_monitor *monitor; /* stop hook of the engine's training (default NULL) */
} affect_generate_options;

void affect_generate_options_default(affect_generate_options *opt);

typedef struct affect_generate_report {
    uint32_t neighbours_used; /* neighbours in the training set */
    uint32_t excluded;        /* neighbours left out: their joint names differ from x_d's */
    uint32_t iterations;      /* Baum–Welch iterations run */
    double loglik;            /* final training log-likelihood (all sequences) */
    double viterbi_logprob;   /* log-probability of the path S (under the scaled model) */
    int32_t *path;            /* n_frames states S_t; the caller frees it with affect_free */
    uint32_t n_frames;        /* entries of path */
    /* Stage times in seconds, measured with opt->clock (all 0 without one): observations of
     * the desired motion and the neighbours, Baum–Welch training, Viterbi (with the covariance
     * scaling), and rendering (state means, low-pass filter, de-normalization). */
    double t_features, t_train, t_viterbi, t_render;
} affect_generate_report;

/* Generates *out (free with affect_motion_free) from desired and the neighbours (opt NULL =
 * the defaults). rep may be NULL; when given it is filled on success (path allocated) and
 * zeroed on failure. */
affect_status affect_generate(const affect_motion *desired, const affect_motion *const *neighbours,
                              uint32_t n_neighbours, const affect_generate_options *opt,
                              affect_motion **out, affect_generate_report *rep, affect_error *err);

/* The normalization transform that the observations of m use (as affect_features_extract
 * with the default definition computes it: translation and heading, arm scale when the
 * right_shoulder and right_hand roles resolve). */
affect_status affect_generate_transform(const affect_motion *m, int up_axis,
                                        affect_normalize_transform *tf, affect_error *err);

/* The exact inverse of the transform: out = origin + Rᵀ (scale · in) for n points of 3
 * doubles (in == out allowed). */
void affect_normalize_invert(const affect_normalize_transform *tf, const double *in, size_t n,
                             double *out);

/* Dynamic-time-warping distance between a and b, which must have the same joint names (same
 * set, any order; frame rates and lengths may differ). Both are normalized as the generation's
 * observations (the arm scale decided on a), the cost of matching frame i of a with frame k of
 * b is the mean over joints of the Euclidean distance between the joint's normalized
 * positions, the warping path runs from (0, 0) to (T_a − 1, T_b − 1) by steps (1, 0), (0, 1)
 * and (1, 1), and *dist is the least total cost divided by the number of frame pairs on the
 * path (ties: the shorter path). So it is the mean per-step joint distance in the normalized
 * unit (right arm lengths when scaled), 0 for a motion and itself, and symmetric. Up axis y.
 * Errors: "the motions have different joint names" (AFFECT_ERR_INVALID), the normalization's
 * errors prefixed with "first motion: " / "second motion: ", "out of memory"; mon (may be
 * NULL) is asked every row and can stop it: AFFECT_ERR_INTERRUPTED. */
affect_status affect_dtw_distance(const affect_motion *a, const affect_motion *b, double *dist,
                                  affect_monitor *mon, affect_error *err);

/* Frame rate at which affect_generate_rank_by_action compares motions. */
#define AFFECT_RANK_FPS 10.0

/* The preference for motions of the desired motion's own action (HMM_NN's neighbours, the
 * transfer's donor pairs): order[0 .. n) gets the candidates' indices by their
 * affect_dtw_distance to desired, both resampled to AFFECT_RANK_FPS when they are faster
 * (the action's shape, at a ninth of the cost for 30 fps motions), nearest first (ties: the
 * lower index; a candidate on another skeleton, or NULL, or one that cannot be compared, comes
 * last in its given order). dist (may be NULL) gets each candidate's distance (INFINITY for
 * those). Errors: out of memory, the resampling of the desired motion, AFFECT_ERR_INTERRUPTED
 * when mon (may be NULL) says stop. */
affect_status affect_generate_rank_by_action(const affect_motion *desired,
                                             const affect_motion *const *candidates, uint32_t n,
                                             uint32_t *order, double *dist, affect_monitor *mon,
                                             affect_error *err);

#ifdef __cplusplus
}
#endif
#endif
