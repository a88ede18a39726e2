/*
 * fisher.c — Fisher scores of a sequence under a Gaussian-mixture HMM (see affect/fisher.h):
 * the gradient of log P(x | Λ) with respect to the start, transition and mixture-weight
 * probabilities, the means and the covariances, in a layout fixed by the configuration.
 *
 * Usage: see the block at the top of affect/fisher.h (compiled by the style/header-usage test).
 *
 * How it works. affect_hmm_posteriors gives γ_t(i, j) (T × N × M) and Σ_t ξ_t(i, l); the
 * probability groups are then ratios (γ_0(i)/π_i, Σξ/a, Σ_t γ/w, with 0 for a zero parameter).
 * For the means and covariances each component k = (i, j) gathers, over the frames where
 * γ_tk > 0 (a frame with γ exactly 0 adds exactly nothing, and left-right models or separated
 * components have many), n = Σγ, s = Σγ(x − μ) and S = Σγ(x − μ)(x − μ)ᵀ — the scatter as one
 * cblas_dsyrk per block of up to BLOCK_ROWS rows √γ (x − μ), centred on μ so nothing cancels.
 * P = Σ⁻¹ comes from LAPACKE_dpotrf_work + LAPACKE_dpotri_work called in column-major 'U' form
 * on the row-major array (Σ is symmetric, so that is the row-major lower triangle, as the HMM
 * engine factors it), without the transposed copy the row-major LAPACKE entry points make
 * outside our allocator. Then ∂/∂μ = P s (cblas_dsymv) and, since
 * ½ Σ_t γ [P d dᵀ P − P] = ½ P (S − n Σ) P, the covariance gradient is G = ½ P D P with
 * D = S − n Σ formed first (the cancellation between the two terms happens once, on the scale
 * of the covariance, not after two products), as two cblas_dsymm. Full covariances give
 * G_rr for (r, r) and G_rs + G_sr for r < s (see the header for why); diagonal ones
 * ½ (S_r − n σ²_r) / σ⁴_r and s_r / σ²_r directly. A component with n = 0 (a zero weight, or
 * never visited) gets zeros without any factorisation.
 *
 * Cost, full covariances: T·m² per component for the scatter (only frames with γ > 0), plus
 * about 3 m³ (factor, inverse, two symmetric products). Memory: one workspace allocation
 * (γ: T·N·M doubles, plus three m × m matrices and a block of rows; sizes overflow-checked),
 * besides affect_hmm_posteriors's own. Determinism: fixed block sizes and summation orders, and
 * OpenBLAS on one thread in every call (AFFECT_BLAS, blas.c), so the same model and sequence give
 * bit-identical scores whatever OPENBLAS_NUM_THREADS says.
 */
#include "affect/fisher.h"
#include "util/internal.h"

#include <cblas.h>
#include <lapacke.h>
#include <math.h>
#include <string.h>

#define N_GROUPS 5
#define BLOCK_ROWS 256u       /* rows √γ (x − μ) per cblas_dsyrk, at most ... */
#define BLOCK_DOUBLES 262144u /* ... and at most this many doubles in the block */

static const unsigned group_bit[N_GROUPS] = {AFFECT_FISHER_START, AFFECT_FISHER_TRANS,
                                             AFFECT_FISHER_WEIGHTS, AFFECT_FISHER_MEANS,
                                             AFFECT_FISHER_COVS};
static const char *const group_names[N_GROUPS] = {"start", "transitions", "weights", "means",
                                                  "covariances"};

static const char GROUPS_MSG[] =
    "groups must be a non-empty combination of start, transitions, weights, means, covariances";
static const char START_MSG[] = "start scores need a model with a learned start";
static const char TOO_MANY_MSG[] = "the score would have too many entries";

const char *affect_fisher_group_name(unsigned group)
{
    for (int g = 0; g < N_GROUPS; g++)
        if (group == group_bit[g])
            return group_names[g];
    return NULL;
}

/* NULL when the mask is usable with cfg, else the message. */
static const char *check_groups(const affect_hmm_config *cfg, unsigned groups)
{
    if (groups == 0 || (groups & ~(unsigned)AFFECT_FISHER_ALL) != 0)
        return GROUPS_MSG;
    if (groups == AFFECT_FISHER_START && !cfg->learn_start)
        return START_MSG;
    return NULL;
}

/* Entries per component of the covariance group. */
static size_t cov_entries(const affect_hmm_config *cfg)
{
    size_t m = cfg->dim;
    return cfg->cov == AFFECT_HMM_FULL ? m * (m + 1) / 2 : m; /* m ≤ 4096: no overflow */
}

/* Entries of every group (in the mask or not; start is 0 with a fixed start) into size, and
 * the total over the mask into *total; false on overflow. */
static bool group_sizes(const affect_hmm_config *cfg, unsigned groups, size_t size[N_GROUPS],
                        size_t *total)
{
    size_t N = cfg->n_states, K = N * cfg->n_mix; /* ≤ 256 × 64 */
    size[0] = cfg->learn_start ? N : 0;
    size[1] = N * N;
    size[2] = K;
    if (!affect_mul_size(K, cfg->dim, &size[3]) || !affect_mul_size(K, cov_entries(cfg), &size[4]))
        return false;
    *total = 0;
    for (int g = 0; g < N_GROUPS; g++)
        if ((groups & group_bit[g]) && !affect_add_size(*total, size[g], total))
            return false;
    return true;
}

size_t affect_fisher_dim(const affect_hmm_config *cfg, unsigned groups)
{
    size_t size[N_GROUPS], total;
    if (affect_hmm_config_check(cfg) || check_groups(cfg, groups) ||
        !group_sizes(cfg, groups, size, &total))
        return 0;
    return total;
}

affect_status affect_fisher_describe(const affect_hmm_config *cfg, unsigned groups, size_t index,
                                     affect_fisher_entry *e, affect_error *err)
{
    const char *msg = affect_hmm_config_check(cfg);
    if (!msg)
        msg = check_groups(cfg, groups);
    if (msg)
        return affect_fail(err, AFFECT_ERR_INVALID, "%s", msg);
    if (!e)
        return affect_fail(err, AFFECT_ERR_INVALID, "no room for the entry");
    size_t size[N_GROUPS], total;
    if (!group_sizes(cfg, groups, size, &total))
        return affect_fail(err, AFFECT_ERR_RANGE, "%s", TOO_MANY_MSG);
    if (index >= total)
        return affect_fail(err, AFFECT_ERR_RANGE,
                           "entry %zu is out of range: the score has %zu entries", index, total);
    size_t N = cfg->n_states, M = cfg->n_mix, m = cfg->dim;
    memset(e, 0, sizeof *e);
    int g = 0;
    for (;; g++) {
        if (!(groups & group_bit[g]))
            continue;
        if (index < size[g])
            break;
        index -= size[g];
    }
    e->group = group_bit[g];
    switch (g) {
    case 0:
        e->state = (uint32_t)index;
        break;
    case 1:
        e->state = (uint32_t)(index / N);
        e->other = (uint32_t)(index % N);
        break;
    case 2:
        e->state = (uint32_t)(index / M);
        e->other = (uint32_t)(index % M);
        break;
    case 3:
        e->state = (uint32_t)(index / m / M);
        e->other = (uint32_t)(index / m % M);
        e->r = (uint32_t)(index % m);
        break;
    default: {
        size_t cp = cov_entries(cfg), p = index % cp;
        e->state = (uint32_t)(index / cp / M);
        e->other = (uint32_t)(index / cp % M);
        if (cfg->cov != AFFECT_HMM_FULL) {
            e->r = e->s = (uint32_t)p;
            break;
        }
        size_t r = 0;
        while (p >= m - r) { /* row r of the upper triangle has m − r entries */
            p -= m - r;
            r++;
        }
        e->r = (uint32_t)r;
        e->s = (uint32_t)(r + p);
        break;
    }
    }
    return AFFECT_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* the workspace: one allocation (affect_ws_alloc, internal.h)                               */

typedef struct fisher_ws {
    const affect_hmm *h;
    const double *x;
    uint32_t T;
    size_t block;  /* rows per dsyrk */
    double *gamma; /* T × N × M */
    double *xi;    /* N × N */
    double *n;     /* N × M: Σ_t γ_t(i, j) */
    double *s;     /* m: Σγ(x − μ) */
    double *S; /* m × m (full) or m (diagonal): Σγ(x − μ)(x − μ)ᵀ, then D, then P D P */
    double *P; /* m × m: Σ⁻¹ (row-major lower triangle) */
    double *Y; /* m × m: P D */
    double *rows;        /* block × m: √γ (x − μ) */
    affect_monitor *mon; /* the caller's (may be NULL) */
} fisher_ws;

/* gather polls the monitor every this many frames */
#define POLL_FRAMES 1024

/* n, s and (when want_S) S of component k over the frames with γ > 0; n is w->n[k]. */
static void gather(const fisher_ws *w, size_t k, bool want_S)
{
    const affect_hmm_config *cfg = affect_hmm_get_config(w->h);
    size_t m = cfg->dim, K = (size_t)cfg->n_states * cfg->n_mix;
    bool full = cfg->cov == AFFECT_HMM_FULL;
    const double *mu = affect_hmm_means(w->h) + k * m;
    double *s = w->s, *S = w->S;
    memset(s, 0, m * sizeof *s);
    if (want_S)
        memset(S, 0, (full ? m * m : m) * sizeof *S);
    size_t nb = 0;
    for (uint32_t t = 0; t < w->T; t++) {
        if (t % POLL_FRAMES == 0 && affect_monitor_stopped(w->mon))
            return; /* component checks the monitor */
        double g = w->gamma[(size_t)t * K + k];
        if (g == 0.0)
            continue;
        const double *xt = w->x + (size_t)t * m;
        if (!want_S) {
            for (size_t d = 0; d < m; d++)
                s[d] += g * (xt[d] - mu[d]);
        } else if (!full) {
            for (size_t d = 0; d < m; d++) {
                double v = xt[d] - mu[d], gv = g * v;
                s[d] += gv;
                S[d] += gv * v;
            }
        } else {
            double sq = sqrt(g), *row = w->rows + nb * m;
            for (size_t d = 0; d < m; d++) {
                double v = xt[d] - mu[d];
                s[d] += g * v;
                row[d] = sq * v;
            }
            if (++nb == w->block) {
                AFFECT_BLAS(cblas_dsyrk(CblasRowMajor, CblasUpper, CblasTrans, (int)m, (int)nb, 1.0,
                                        w->rows, (int)m, 1.0, S, (int)m));
                nb = 0;
            }
        }
    }
    if (nb > 0)
        AFFECT_BLAS(cblas_dsyrk(CblasRowMajor, CblasUpper, CblasTrans, (int)m, (int)nb, 1.0,
                                w->rows, (int)m, 1.0, S, (int)m));
}

/* The mean (om, m entries) and covariance (oc, cov_entries) scores of component k; either may
 * be NULL when its group is not wanted. */
static affect_status component(const fisher_ws *w, size_t k, double *om, double *oc,
                               affect_error *err)
{
    const affect_hmm_config *cfg = affect_hmm_get_config(w->h);
    size_t m = cfg->dim, M = cfg->n_mix;
    double n = w->n[k];
    if (!(n > 0)) { /* no posterior weight (a zero weight, or a component never visited) */
        if (om)
            memset(om, 0, m * sizeof *om);
        if (oc)
            memset(oc, 0, cov_entries(cfg) * sizeof *oc);
        return AFFECT_OK;
    }
    gather(w, k, oc != NULL);
    affect_status st = affect_monitor_check(w->mon, err);
    if (st)
        return st;
    if (cfg->cov != AFFECT_HMM_FULL) {
        const double *var = affect_hmm_covariances(w->h) + k * m;
        for (size_t d = 0; d < m; d++) {
            if (om)
                om[d] = w->s[d] / var[d];
            if (oc)
                oc[d] = 0.5 * (w->S[d] - n * var[d]) / (var[d] * var[d]);
        }
        return AFFECT_OK;
    }

    const double *cov = affect_hmm_covariances(w->h) + k * m * m;
    double *P = w->P;
    memcpy(P, cov, m * m * sizeof *P);
    /* column-major 'U' on a symmetric row-major array = row-major 'L', without a copy */
    lapack_int info;
    AFFECT_BLAS(info = LAPACKE_dpotrf_work(LAPACK_COL_MAJOR, 'U', (lapack_int)m, P, (lapack_int)m));
    if (info == 0)
        AFFECT_BLAS(
            info = LAPACKE_dpotri_work(LAPACK_COL_MAJOR, 'U', (lapack_int)m, P, (lapack_int)m));
    if (info != 0)
        return affect_fail(err, AFFECT_ERR_RANGE,
                           "covariance of state %zu, mixture %zu is not positive definite", k / M,
                           k % M);
    if (om)
        AFFECT_BLAS(
            cblas_dsymv(CblasRowMajor, CblasLower, (int)m, 1.0, P, (int)m, w->s, 1, 0.0, om, 1));
    if (!oc)
        return AFFECT_OK;
    /* D = S − n Σ (S's upper triangle, Σ's lower one), made symmetric in place */
    double *D = w->S;
    for (size_t r = 0; r < m; r++)
        for (size_t c = r; c < m; c++) {
            double v = D[r * m + c] - n * cov[c * m + r];
            D[r * m + c] = v;
            D[c * m + r] = v;
        }
    /* Y = P D, then P D P into D's place */
    AFFECT_BLAS(cblas_dsymm(CblasRowMajor, CblasLeft, CblasLower, (int)m, (int)m, 1.0, P, (int)m, D,
                            (int)m, 0.0, w->Y, (int)m));
    AFFECT_BLAS(cblas_dsymm(CblasRowMajor, CblasRight, CblasLower, (int)m, (int)m, 1.0, P, (int)m,
                            w->Y, (int)m, 0.0, D, (int)m));
    /* G = ½ P D P: G_rr, and G_rs + G_sr = ½ (Z_rs + Z_sr) for r < s */
    size_t p = 0;
    for (size_t r = 0; r < m; r++) {
        oc[p++] = 0.5 * D[r * m + r];
        for (size_t c = r + 1; c < m; c++)
            oc[p++] = 0.5 * (D[r * m + c] + D[c * m + r]);
    }
    return AFFECT_OK;
}

affect_status affect_fisher_score(const affect_hmm *h, const double *x, uint32_t n_frames,
                                  unsigned groups, double *out, double *loglik, affect_monitor *mon,
                                  affect_error *err)
{
    if (!h)
        return affect_fail(err, AFFECT_ERR_INVALID, "no model");
    const affect_hmm_config *cfg = affect_hmm_get_config(h);
    const char *msg = check_groups(cfg, groups);
    if (msg)
        return affect_fail(err, AFFECT_ERR_INVALID, "%s", msg);
    if (!out)
        return affect_fail(err, AFFECT_ERR_INVALID, "no room for the score");
    size_t size[N_GROUPS], total;
    if (!group_sizes(cfg, groups, size, &total))
        return affect_fail(err, AFFECT_ERR_RANGE, "%s", TOO_MANY_MSG);

    size_t N = cfg->n_states, M = cfg->n_mix, K = N * M, m = cfg->dim, TK;
    bool full = cfg->cov == AFFECT_HMM_FULL;
    bool dens = (groups & (AFFECT_FISHER_MEANS | AFFECT_FISHER_COVS)) != 0;
    bool want_S = (groups & AFFECT_FISHER_COVS) != 0;
    if (!affect_mul_size(n_frames, K, &TK))
        return affect_nomem(err);
    fisher_ws w = {0};
    w.h = h;
    w.x = x;
    w.T = n_frames;
    w.mon = mon;
    w.block = BLOCK_DOUBLES / m < BLOCK_ROWS ? BLOCK_DOUBLES / m : BLOCK_ROWS; /* ≥ 64 */
    if (w.block > n_frames)
        w.block = n_frames;
    size_t mm = m * m; /* m ≤ 4096 */
    affect_ws_part parts[] = {
        {(void **)&w.gamma, TK, sizeof(double)},
        {(void **)&w.xi, N * N, sizeof(double)},
        {(void **)&w.n, K, sizeof(double)},
        {(void **)&w.s, dens ? m : 0, sizeof(double)},
        {(void **)&w.S, want_S ? (full ? mm : m) : 0, sizeof(double)},
        {(void **)&w.P, dens && full ? mm : 0, sizeof(double)},
        {(void **)&w.Y, want_S && full ? mm : 0, sizeof(double)},
        {(void **)&w.rows, want_S && full ? w.block * m : 0, sizeof(double)},
    };
    void *ws = affect_ws_alloc(parts, sizeof parts / sizeof parts[0]);
    if (!ws)
        return affect_nomem(err);
    double L;
    affect_status st = affect_hmm_posteriors(h, x, n_frames, w.gamma, w.xi, &L, mon, err);
    if (st)
        goto cleanup;

    /* n_k = Σ_t γ_t(k), t ascending */
    memset(w.n, 0, K * sizeof *w.n);
    for (uint32_t t = 0; t < n_frames; t++) {
        const double *g = w.gamma + (size_t)t * K;
        for (size_t k = 0; k < K; k++)
            w.n[k] += g[k];
    }
    double *o = out;
    if ((groups & AFFECT_FISHER_START) && cfg->learn_start) {
        const double *pi = affect_hmm_start(h);
        for (size_t i = 0; i < N; i++) {
            double g0 = 0.0;
            for (size_t j = 0; j < M; j++)
                g0 += w.gamma[i * M + j];
            o[i] = pi[i] > 0 ? g0 / pi[i] : 0.0;
        }
        o += N;
    }
    if (groups & AFFECT_FISHER_TRANS) {
        const double *a = affect_hmm_transitions(h);
        for (size_t e = 0; e < N * N; e++)
            o[e] = a[e] > 0 ? w.xi[e] / a[e] : 0.0;
        o += N * N;
    }
    if (groups & AFFECT_FISHER_WEIGHTS) {
        const double *wt = affect_hmm_weights(h);
        for (size_t k = 0; k < K; k++)
            o[k] = wt[k] > 0 ? w.n[k] / wt[k] : 0.0;
        o += K;
    }
    if (dens) {
        double *om = (groups & AFFECT_FISHER_MEANS) ? o : NULL;
        double *oc = want_S ? o + (om ? size[3] : 0) : NULL;
        size_t cp = cov_entries(cfg);
        for (size_t k = 0; k < K; k++) {
            st = component(&w, k, om ? om + k * m : NULL, oc ? oc + k * cp : NULL, err);
            if (st)
                goto cleanup;
        }
    }
    if (loglik)
        *loglik = L;
cleanup:
    affect_free(ws);
    return st;
}
