/*
 * affect/fisher.h — Fisher scores of a motion under a Gaussian-mixture HMM (SCIENCE.md §3;
 * thesis §4.1.2): F(x) = ∇_Λ log P(x | Λ), a fixed-length vector for a sequence of any length.
 *
 * Usage:
 *     const affect_hmm *h = ...;  const double *x = ...;  uint32_t T = ...;
 *     affect_error err;
 *     const affect_hmm_config *cfg = affect_hmm_get_config(h);
 *     size_t d = affect_fisher_dim(cfg, AFFECT_FISHER_ALL);
 *     double *score = affect_malloc_array(d, sizeof *score), ll;
 *     affect_fisher_entry e;
 *     if (!score)
 *         affect_nomem(&err);
 *     else if (affect_fisher_score(h, x, T, AFFECT_FISHER_ALL, score, &ll, NULL, &err) == AFFECT_OK
 *              && affect_fisher_describe(cfg, AFFECT_FISHER_ALL, 0, &e, &err) == AFFECT_OK)
 *         printf("%g: %s of state %u\n", score[0], affect_fisher_group_name(e.group), e.state);
 *     affect_free(score);
 *
 * The derivatives treat every parameter as free (no sum-to-one constraint), with γ_t(i, j) the
 * posterior of state i and mixture j at frame t and Σ_t ξ_t(i, l) the expected number of
 * transitions i → l (both from affect_hmm_posteriors):
 *     ∂/∂π_i   = γ_0(i) / π_i                          (γ_0(i) = Σ_j γ_0(i, j))
 *     ∂/∂a_il  = Σ_t ξ_t(i, l) / a_il
 *     ∂/∂w_ij  = Σ_t γ_t(i, j) / w_ij
 *     ∂/∂μ_ij  = Σ_t γ_t(i, j) Σ_ij⁻¹ (x_t − μ_ij)
 *     G_ij     = ½ Σ_t γ_t(i, j) [Σ_ij⁻¹ (x_t − μ_ij)(x_t − μ_ij)ᵀ Σ_ij⁻¹ − Σ_ij⁻¹]
 * An entry whose parameter is 0 (π_i = 0, a forbidden or zero transition, a zero weight) is 0,
 * and so are the mean and covariance entries of a component with no posterior weight.
 *
 * COVARIANCE ENTRIES — a deliberate choice. A full covariance is symmetric, so it has
 * m(m+1)/2 free parameters, one per entry (r, s) with r ≤ s, which stands for both Σ_rs and
 * Σ_sr. The score entry for (r, r) is G_rr and the entry for r < s is G_rs + G_sr = 2 G_rs: the
 * derivative of log P when Σ_rs and Σ_sr move together (what a finite difference of a symmetric
 * matrix measures). SCIENCE.md says "keep the upper triangle of G"; the two differ only by a
 * factor 2 on the off-diagonal entries, which the per-entry z-score normalisation applied before
 * any classifier removes. Diagonal models have the m variances σ²_r as parameters:
 *     ∂/∂σ²_r = ½ Σ_t γ_t(i, j) [(x_tr − μ_r)² / σ⁴_r − 1 / σ²_r].
 * The model's covariance is read from its lower triangle (as the engine factors it); models
 * built from parameters are symmetric within 1e-9 anyway.
 *
 * Layout (affect_fisher_dim entries), the groups in this order, each only when in the mask:
 *     start        N                      (only when cfg->learn_start, see below)
 *     transitions  N × N, row-major (i, l); forbidden transitions are kept (as 0) so that the
 *                  layout depends on the configuration only
 *     weights      N × M (i, j)
 *     means        N × M × m (i, j, r)
 *     covariances  N × M × m(m+1)/2 (i, j, then (0,0), (0,1) .. (0,m−1), (1,1) .. (m−1,m−1))
 *                  for full covariances; N × M × m (i, j, r) for diagonal ones
 * With a fixed start (π = (1, 0, …, 0), the thesis's setting) π has no free parameter: the start
 * group has no entries, so AFFECT_FISHER_ALL gives N² + NM + NMm + NM·m(m+1)/2 entries (the
 * thesis's count); a mask that selects nothing else (the start group alone) is refused.
 *
 * Errors (AFFECT_ERR_INVALID unless said): "groups must be a non-empty combination of start,
 * transitions, weights, means, covariances"; "start scores need a model with a learned start";
 * "no model"; "no room for the score"; the sequence's errors from affect_hmm_posteriors ("the
 * sequence has no frames", "frame 3: value 2 is not finite", and AFFECT_ERR_RANGE "the sequence
 * has probability 0 under the model: no posteriors"); AFFECT_ERR_RANGE "the score would have
 * too many entries" (a count beyond size_t, 32-bit hosts only) and "covariance of state 1,
 * mixture 0 is not positive definite" (cannot happen for a model the engine accepted);
 * AFFECT_ERR_NOMEM.
 *
 * Thread safety: no global state; the model is only read.
 */
#ifndef AFFECT_FISHER_H
#define AFFECT_FISHER_H

#include "affect/base.h"
#include "affect/hmm.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Parameter groups, combined as a bit mask. */
enum {
    AFFECT_FISHER_START = 1u,
    AFFECT_FISHER_TRANS = 2u,
    AFFECT_FISHER_WEIGHTS = 4u,
    AFFECT_FISHER_MEANS = 8u,
    AFFECT_FISHER_COVS = 16u,
    AFFECT_FISHER_ALL = 31u
};

/* Number of score entries for a configuration and a group mask (the start group counts only
 * when cfg->learn_start). 0 when the configuration fails affect_hmm_config_check, the mask is
 * not a non-empty combination of the groups, it selects no entry (the start group alone with a
 * fixed start), or the count does not fit in a size_t. */
size_t affect_fisher_dim(const affect_hmm_config *cfg, unsigned groups);

/* Writes the Fisher score of x (n_frames × dim doubles, row-major) under h into out
 * (affect_fisher_dim(affect_hmm_get_config(h), groups) doubles); *loglik (loglik may be NULL)
 * = log P(x | Λ). On error out's contents are unspecified. One workspace allocation besides
 * affect_hmm_posteriors's own. mon (may be NULL) is polled as the frames are read (per block of
 * frames): AFFECT_ERR_INTERRUPTED once it says stop. */
affect_status affect_fisher_score(const affect_hmm *h, const double *x, uint32_t n_frames,
                                  unsigned groups, double *out, double *loglik, affect_monitor *mon,
                                  affect_error *err);

/* What one score entry is (for salience reports): its group (one AFFECT_FISHER_* bit), the
 * state i, `other` = the destination l (transitions) or the mixture j (weights, means,
 * covariances), and r (means), or (r, s) with r ≤ s (covariances; r = s for diagonal models).
 * Fields that do not apply are 0. */
typedef struct affect_fisher_entry {
    unsigned group;
    uint32_t state;
    uint32_t other;
    uint32_t r;
    uint32_t s;
} affect_fisher_entry;

/* Describes entry `index` of the layout above. Errors: those of affect_hmm_config_check, the
 * group messages above, "entry 12 is out of range: the score has 12 entries",
 * "no room for the entry". */
affect_status affect_fisher_describe(const affect_hmm_config *cfg, unsigned groups, size_t index,
                                     affect_fisher_entry *e, affect_error *err);

/* "start", "transitions", "weights", "means", "covariances" for one group bit; NULL otherwise. */
const char *affect_fisher_group_name(unsigned group);

#ifdef __cplusplus
}
#endif
#endif
