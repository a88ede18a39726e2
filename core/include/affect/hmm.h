/*
 * affect/hmm.h — hidden Markov models with Gaussian-mixture outputs (SCIENCE.md §2; thesis
 * §4.1.1, §4.2.2, §5.3.2): training by Baum–Welch, forward log-likelihood, Viterbi, posteriors.
 *
 * Usage:
 *     const double *x = ...;  uint32_t T = ...;        // T frames × 63 values, row-major
 *     affect_error err;
 *     affect_hmm_config cfg;
 *     affect_hmm_config_default(&cfg);
 *     cfg.dim = 63;                                    // the caller sets the dimension
 *     affect_hmm_seq seqs[1] = {{x, T}};
 *     affect_hmm *h = NULL;
 *     double ll;
 *     if (affect_hmm_train(&cfg, seqs, 1, &h, &err) != AFFECT_OK ||
 *         affect_hmm_loglik(h, x, T, &ll, NULL, &err) != AFFECT_OK)
 *         puts(err.msg);
 *     affect_hmm_free(h);
 *
 * Λ = (A, B, π): N states, transition matrix A (N × N, row-stochastic), per state i a mixture
 * b_i(x) = Σ_j w_ij N(x; μ_ij, Σ_ij) of M Gaussians in m dimensions with full or diagonal
 * covariances, start probabilities π (fixed to the first state, the thesis's setting, or learned).
 * Topology: ergodic (full A) or left-to-right (a_il = 0 for l < i, and for l > i + max_jump when
 * max_jump > 0).
 *
 * Observations are T × m row-major doubles. Every recursion runs in log space with careful
 * log-sum-exp, so sequences of any length neither underflow nor overflow. Gaussian densities use
 * the Cholesky factor of each covariance, computed once per model (LAPACKE_dpotrf), and its
 * inverse, so that the Mahalanobis distances of a block of frames under every component are a
 * few matrix products (cblas_dgemm; see hmm.c).
 *
 * Training: every sequence is split into N equal segments; the frames of segment i, pooled over
 * all sequences, are clustered by k-means (k-means++ seeding from the seed) into M clusters whose
 * means, covariances and size fractions initialise state i. Then Baum–Welch until the relative
 * change of the total log-likelihood is below tol, or max_iter iterations. A floor `reg` is added
 * to every covariance diagonal so EM never fails on degenerate data; a mixture component that
 * loses all its frames is re-seeded at the frame of its state worst explained by the model, and
 * the report records it. Sequences shorter than N frames are rejected with a message.
 *
 * Errors name their place with 0-based indices ("sequence 3 has 4 frames, fewer than the 7
 * states", "sequence 2, frame 10: value 5 is not finite", "transition row 2 sums to 0.9, not 1",
 * "covariance of state 1, mixture 0 is not positive definite"); AFFECT_ERR_INVALID for bad
 * arguments, AFFECT_ERR_RANGE for numerical failures (a sequence of probability 0, a covariance
 * no floor makes positive definite), AFFECT_ERR_NOMEM.
 *
 * Thread safety: no global state; a trained model is read-only and may be shared.
 */
#ifndef AFFECT_HMM_H
#define AFFECT_HMM_H

#include "affect/base.h"
#include "affect/monitor.h"

#ifdef __cplusplus
extern "C" {
#endif

#define AFFECT_HMM_MAX_STATES 256u
#define AFFECT_HMM_MAX_MIX 64u
#define AFFECT_HMM_MAX_DIM 4096u

typedef enum affect_hmm_cov { AFFECT_HMM_FULL = 0, AFFECT_HMM_DIAG = 1 } affect_hmm_cov;
typedef enum affect_hmm_topology {
    AFFECT_HMM_ERGODIC = 0,
    AFFECT_HMM_LEFT_RIGHT = 1
} affect_hmm_topology;

typedef struct affect_hmm_config {
    uint32_t n_states;            /* N (default 7) */
    uint32_t n_mix;               /* M (default 4) */
    uint32_t dim;                 /* m, the observation dimension (set by the caller) */
    affect_hmm_cov cov;           /* default full */
    affect_hmm_topology topology; /* default ergodic */
    uint32_t max_jump;            /* left-right: largest forward jump, 0 = any (default 0) */
    bool learn_start;             /* learn π (default false: π = (1, 0, …, 0)) */
    uint32_t max_iter;            /* Baum–Welch iterations at most (default 50) */
    double tol;                   /* relative log-likelihood change to stop (default 1e-4) */
    double reg;                   /* covariance diagonal floor, added (default 1e-4) */
    uint64_t seed;                /* k-means++ seeding (default 1) */
    affect_monitor *monitor;      /* training: stop and progress hooks (default NULL); a model
                                     keeps none (its copy of the configuration says NULL) */
} affect_hmm_config;

void affect_hmm_config_default(affect_hmm_config *cfg);

/* Returns NULL when cfg is usable, else a static message ("states must be between 1 and 256"). */
const char *affect_hmm_config_check(const affect_hmm_config *cfg);

/* One observation sequence: T frames × dim values, row-major. */
typedef struct affect_hmm_seq {
    const double *x;
    uint32_t n_frames;
} affect_hmm_seq;

typedef struct affect_hmm affect_hmm; /* opaque */

/* Trains a model on n sequences (each at least n_states frames, every value finite). *out is
 * NULL on failure. */
affect_status affect_hmm_train(const affect_hmm_config *cfg, const affect_hmm_seq *seqs, uint32_t n,
                               affect_hmm **out, affect_error *err);
void affect_hmm_free(affect_hmm *h);

/* Scoring (the three functions below) takes an optional monitor (NULL: none): its stop hook is
 * polled once per block of frames (at most 128), so a long sequence returns
 * AFFECT_ERR_INTERRUPTED ("interrupted") soon after the caller asks; nothing is written then. */

/* Total natural-log likelihood log P(x | Λ) by the forward algorithm. −∞ when impossible.
 * Any n_frames ≥ 1 (shorter than N is fine); every value must be finite. */
affect_status affect_hmm_loglik(const affect_hmm *h, const double *x, uint32_t n_frames,
                                double *loglik, affect_monitor *mon, affect_error *err);

/* Most likely state path (n_frames entries; ties go to the lower state) and its
 * log-probability (logprob may be NULL). */
affect_status affect_hmm_viterbi(const affect_hmm *h, const double *x, uint32_t n_frames,
                                 int32_t *path, double *logprob, affect_monitor *mon,
                                 affect_error *err);

/* Posteriors for Fisher scores: gamma = T × N × M (state i and mixture j at t), xi = N × N
 * (Σ_t ξ_t(i, l), the expected transition counts); either may be NULL. Returns log P(x | Λ).
 * γ_t and ξ_t are normalised frame by frame (Σ_ij γ_t = 1, Σ xi = T − 1). A sequence of
 * probability 0 has no posteriors: AFFECT_ERR_RANGE. */
affect_status affect_hmm_posteriors(const affect_hmm *h, const double *x, uint32_t n_frames,
                                    double *gamma, double *xi, double *loglik, affect_monitor *mon,
                                    affect_error *err);

/* ---- parameters (read-only views, row-major) ---- */
const affect_hmm_config *affect_hmm_get_config(const affect_hmm *h);
const double *affect_hmm_start(const affect_hmm *h);       /* N */
const double *affect_hmm_transitions(const affect_hmm *h); /* N × N */
const double *affect_hmm_weights(const affect_hmm *h);     /* N × M */
const double *affect_hmm_means(const affect_hmm *h);       /* N × M × m */
/* N × M × m × m for full covariances, N × M × m (the diagonals) for diagonal ones. */
const double *affect_hmm_covariances(const affect_hmm *h);

/* ---- training report ---- */
typedef struct affect_hmm_report {
    uint32_t iterations;  /* Baum–Welch iterations run */
    bool converged;       /* stopped by tol rather than max_iter */
    const double *loglik; /* total log-likelihood after initialisation and each iteration
                             (iterations + 1 values) */
    uint32_t reseeded;    /* mixture components re-seeded during training */
    uint32_t n_sequences;
    uint64_t n_frames;
} affect_hmm_report;

/* A model from affect_hmm_from_params has an empty report until affect_hmm_set_report:
 * 0 iterations, not converged, no sequences or frames, and loglik = one value, 0. */
void affect_hmm_get_report(const affect_hmm *h, affect_hmm_report *report);

/* Mean state duration of states 2..N in frames: (1/(N−1)) Σ_{i≥2} 1/(1 − a_ii) (thesis
 * §4.4.3.1); per-state durations 1/(1 − a_ii) into per_state (N values) when not NULL. A state
 * with a_ii = 1 lasts +∞; with N = 1 the result is the single state's duration. */
double affect_hmm_mean_duration(const affect_hmm *h, double *per_state);

/* ---- building a model from parameters (deserialization, tests) ---- */

/* Copies the parameters (shapes as above), checks them (stochastic rows, weights summing to 1,
 * positive-definite covariances) and precomputes the Cholesky factors. The report is empty.
 * Sums must be 1 within 1e-6; transitions the topology forbids must be 0; π must be
 * (1, 0, …, 0) unless cfg->learn_start; full covariances symmetric within 1e-9 (relative). */
affect_status affect_hmm_from_params(const affect_hmm_config *cfg, const double *start,
                                     const double *trans, const double *weights,
                                     const double *means, const double *covs, affect_hmm **out,
                                     affect_error *err);

/* Restores a training report on a model built from parameters (loglik has iterations + 1
 * values, all finite; iterations at most the configuration's max_iter). Copies; never
 * allocates. */
affect_status affect_hmm_set_report(affect_hmm *h, const affect_hmm_report *report,
                                    affect_error *err);

#ifdef __cplusplus
}
#endif
#endif
