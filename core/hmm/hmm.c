/*
 * hmm.c — hidden Markov models with Gaussian-mixture outputs (see affect/hmm.h): k-means
 * initialisation, Baum–Welch training, forward log-likelihood, Viterbi and posteriors.
 *
 * Usage: see the block at the top of affect/hmm.h (compiled by the style/header-usage test).
 *
 * How it works.
 *
 * Densities. Per (state i, mixture j) = component k the model keeps the Cholesky factor L_k of
 * Σ_k (Σ = L Lᵀ, row-major lower triangle), the constant c_k = log w_k − ½ m log 2π − Σ log L_rr,
 * and for full covariances the inverse factor W_k = L_k⁻¹, a centre c (the mean of all component
 * means) and ib_k = W_k (μ_k − c) (prepare_inverses). Then ‖L_k⁻¹(x − μ_k)‖² = ‖W_k (x − c) −
 * ib_k‖² for every component from one set of matrix products: the rows of all the W_k are cut into
 * panels of TRI_ROWS rows; a panel needs only the columns up to its last row (W is lower
 * triangular), so per 128 frames each panel is one cblas_dgemm of the centred frames by an
 * (N·M·rows) × r1 matrix, about (1 + TRI_ROWS/m)/2 of the full product's flops. dgemm runs near
 * the core's peak where N·M small triangular solves do not (docs/BENCHMARKS.md: the engine scores
 * faster than the bare dtrsm calls of the solve formulation). Subtracting c first keeps
 * W x − W μ from cancelling when the data sit far from the origin (test_wide_full: 3e-15
 * relative instead of 8e-12). log(w N(x_t)) = c_k − ½‖y‖². Diagonal covariances keep 1/σ and use
 * a direct loop. Frames are processed in blocks of up to 1024 (fewer for very large models, see
 * block_frames).
 * log b_i(x_t) is the log-sum-exp over j; the within-state responsibilities
 * ρ_tij = w_ij N_ij(x_t) / b_i(x_t) are kept when posteriors are wanted. Factoring calls
 * LAPACKE_dpotrf_work in column-major 'U' form on the row-major array: Σ is symmetric, so this
 * is the row-major lower factorisation, without the transposed copy (a hidden malloc outside
 * our allocator) that the row-major LAPACKE entry point makes.
 *
 * Recursions. Log space throughout: log α_t(l) = log b_l(x_t) + LSE_i(log α_{t−1}(i) + log a_il),
 * log β likewise backwards. Each step subtracts the largest log α (or log b + log β), does the
 * N × N sum in linear space with the linear transition matrix, and takes the log; when a sum
 * falls below 1e-100 (an entry whose terms would lose precision to underflow, as happens for
 * the unreachable states of a left-right model), that entry is recomputed exactly as a
 * log-sum-exp with its own maximum. Impossible transitions are log 0 = −∞ and never produce a
 * NaN. Posteriors γ_t and ξ_t are normalised frame by frame, so they sum to 1 exactly up to
 * rounding however long the sequence. Viterbi is max-plus with ties to the lowest state.
 *
 * Training. Every sequence is cut into N equal segments (segment i = frames
 * ⌊iT/N⌋ .. ⌊(i+1)T/N⌋ − 1); the frames of segment i, pooled over the sequences, are clustered
 * by k-means (k-means++ seeding from one generator seeded by cfg->seed, states in order; at
 * most 30 Lloyd iterations; an empty cluster jumps to the point farthest from its centre) into M
 * clusters whose member means, covariances (maximum likelihood, + reg) and size fractions
 * initialise state i; a cluster that stays empty gets the segment's pooled covariance and
 * weight 0 (and is re-seeded by the first M-step). Initial transitions: a_ii = 1 − 1/L (L the
 * mean segment length, a_ii at least 0.5), the rest spread evenly over the allowed
 * destinations; π = (1, 0, …, 0), or uniform when learned.
 * Each Baum–Welch iteration runs forward–backward sequence by sequence (workspace sized by the
 * longest sequence: T × N × M doubles of responsibilities, T × N of log α and of log b) and
 * accumulates, per component, Σγ, Σγ(x − c) and the scatter Σγ(x − c)(x − c)ᵀ with
 * c = the component's current mean (shifting by c avoids cancellation when the data sit far
 * from the origin); the scatter is one cblas_dsyrk per block of frames on rows scaled by √γ,
 * leaving out (from PRUNE_MIN_DIM dimensions on) the rows below one unit roundoff of the block's
 * scale (see scatter).
 * The M-step sets w = n_ij / n_i, μ = c + s/n, Σ = S/n − (s/n)(s/n)ᵀ + reg I, transitions from
 * Σξ with forbidden entries kept at 0, π from γ_0 when learned. A covariance that still fails
 * to factor gets 9 × reg + 1e-9 × its mean variance more on its diagonal, once; then training
 * stops with an error. A component whose total weight is below 1e-10 × the training frames is
 * re-seeded at the frames of its state (frames whose most probable state it is) worst explained
 * by the state's mixture — the k-th empty component of a state at the k-th worst frame — with
 * the state's pooled covariance and weight 1/max(n_i, 1) before the state's weights are
 * renormalised; report->reseeded counts these. A state (or a transition row) with less weight
 * than that keeps its parameters. Training stops when
 * |L_k − L_{k−1}| ≤ tol |L_{k−1}| (converged) or after max_iter iterations; the
 * log-likelihoods L_0 (after initialisation) .. L_k are those of the parameters the model ends
 * with, so the last equals the sum of affect_hmm_loglik over the training sequences.
 *
 * Memory: each call makes one workspace allocation (sizes overflow-checked), training one more
 * for the model. Determinism: no threads of our own, fixed block sizes and OpenBLAS on one
 * thread in every call (AFFECT_BLAS, blas.c), so the same sequences and configuration give
 * bit-identical parameters whatever OPENBLAS_NUM_THREADS says.
 */
#include "affect/hmm.h"

#include <cblas.h>
#include <lapacke.h>
#include <math.h>
#include <string.h>

#include "util/rng.h"
#include "util/internal.h"

#define LOG_2PI 1.83787706640934548356
#define BLOCK_FRAMES 1024u    /* frames per density / scatter block, at most */
#define BLOCK_DOUBLES 262144u /* ... and at most this many doubles per block buffer */
#define SUB_FRAMES 128u       /* frames per panel product (full covariances) */
#define TRI_ROWS                                                                                   \
    8u                    /* rows of the inverse factors per product (full covariances); 8 was the \
                             fastest of 4 .. 64 in bench_hmm at m = 15 and m = 63 */
#define LINEAR_MIN 1e-100 /* a linear-space sum below this is redone in log space */
/* scatter: rows below this share of the block's scale are left out, from PRUNE_MIN_DIM
 * dimensions on (below, the test costs more than the rows) */
#define PRUNE_ROUNDOFF 0x1p-53
#define PRUNE_MIN_DIM 24u
/* the quick test's widening: the relative rounding of the two distances, of z and of the
 * weighted sums is below 3 (m + 4) 2⁻⁵³, under 1e-9 for m up to 10⁶ (AFFECT_HMM_MAX_DIM: 4096) */
#define PRUNE_BOUND_SLACK (1.0 + 1e-9)
/* exp of less than EXP_MIN is taken as 0: below DBL_MIN, it skips libm's slow underflow path, and
 * such terms are below one ulp of the sums they join (whose largest term is 1) */
#define EXP_MIN (-708.0)
#define SUM_TOL 1e-6            /* probabilities must sum to 1 within this */
#define SYM_TOL 1e-9            /* relative asymmetry allowed in a full covariance */
#define EMPTY_FRACTION 1e-10    /* empty component: weight below this × training frames */
#define KMEANS_MAX_ITER 30u     /* Lloyd iterations of the initialisation, at most */
#define MIN_INIT_SELF 0.5       /* initial self-transition, at least */
#define RETRY_REG_FACTOR 9.0    /* second try: this × reg more on the diagonal ... */
#define RETRY_REG_RELATIVE 1e-9 /* ... plus this × the mean variance */
#define MAX_ITER_LIMIT 100000u

struct affect_hmm {
    affect_hmm_config cfg;
    size_t cs;           /* doubles per covariance: m × m (full) or m (diagonal) */
    uint32_t block;      /* frames per block (block_frames) */
    double *start;       /* N */
    double *trans;       /* N × N */
    double *weights;     /* N × M */
    double *means;       /* N × M × m */
    double *covs;        /* N × M × cs */
    double *log_start;   /* N */
    double *log_trans;   /* N × N */
    double *fac;         /* N × M × cs: Cholesky factors (full) or 1/σ (diagonal) */
    double *half_logdet; /* N × M: ½ log det Σ */
    double *cnorm;       /* N × M: log w − ½ m log 2π − ½ log det Σ */
    double *inv;         /* full: the inverse factors L⁻¹ by row panels (see prepare_inverses) */
    double *ib;          /* full: m × N × M, row r of L_k⁻¹ (μ_k − centre) at [r][k] */
    double *centre;      /* full: m, the mean of the component means */
    /* training report */
    bool has_report;
    bool converged;
    uint32_t iterations;
    uint32_t reseeded;
    uint32_t n_sequences;
    uint64_t n_frames;
    double *loglik;      /* max_iter + 1 */
    affect_monitor *mon; /* during training only: the caller's hooks (else NULL) */
};

/* ------------------------------------------------------------------------------------------ */
/* configuration                                                                              */

void affect_hmm_config_default(affect_hmm_config *cfg)
{
    memset(cfg, 0, sizeof *cfg);
    cfg->n_states = 7;
    cfg->n_mix = 4;
    cfg->dim = 0;
    cfg->cov = AFFECT_HMM_FULL;
    cfg->topology = AFFECT_HMM_ERGODIC;
    cfg->max_jump = 0;
    cfg->learn_start = false;
    cfg->max_iter = 50;
    cfg->tol = 1e-4;
    cfg->reg = 1e-4;
    cfg->seed = 1;
}

const char *affect_hmm_config_check(const affect_hmm_config *cfg)
{
    if (!cfg)
        return "no configuration";
    if (cfg->n_states < 1 || cfg->n_states > AFFECT_HMM_MAX_STATES)
        return "states must be between 1 and 256";
    if (cfg->n_mix < 1 || cfg->n_mix > AFFECT_HMM_MAX_MIX)
        return "mixtures must be between 1 and 64";
    if (cfg->dim < 1 || cfg->dim > AFFECT_HMM_MAX_DIM)
        return "observation dimension must be between 1 and 4096";
    if (cfg->cov != AFFECT_HMM_FULL && cfg->cov != AFFECT_HMM_DIAG)
        return "covariance must be full or diagonal";
    if (cfg->topology != AFFECT_HMM_ERGODIC && cfg->topology != AFFECT_HMM_LEFT_RIGHT)
        return "topology must be ergodic or left-right";
    if (cfg->max_jump != 0 && cfg->topology != AFFECT_HMM_LEFT_RIGHT)
        return "max_jump needs the left-right topology";
    if (cfg->max_jump >= cfg->n_states)
        return "max_jump must be less than the number of states";
    if (cfg->max_iter > MAX_ITER_LIMIT)
        return "max_iter must be at most 100000";
    if (!(cfg->tol >= 0) || !isfinite(cfg->tol))
        return "tol must be a finite number, 0 or more";
    if (!(cfg->reg >= 0) || !isfinite(cfg->reg))
        return "reg must be a finite number, 0 or more";
    return NULL;
}

/* Whether the topology allows the transition i → l. */
static bool allowed(const affect_hmm_config *cfg, uint32_t i, uint32_t l)
{
    if (cfg->topology == AFFECT_HMM_ERGODIC)
        return true;
    if (l < i)
        return false;
    return cfg->max_jump == 0 || l - i <= cfg->max_jump;
}

/* Doubles per frame of the densities' second block buffer: the frame (diagonal), or the
 * centred frame and one panel product over all components (full, see densities). */
static uint32_t dbuf_width(const affect_hmm_config *cfg)
{
    uint32_t rows = cfg->dim < TRI_ROWS ? cfg->dim : TRI_ROWS;
    if (cfg->cov != AFFECT_HMM_FULL)
        return cfg->dim;
    return cfg->dim +
           cfg->n_states * cfg->n_mix * rows; /* (the product needs min(n, SUB_FRAMES) rows) */
}

/* Frames per block: at most BLOCK_FRAMES, and the block buffers (frames × N × M and
 * frames × dbuf_width doubles) at most BLOCK_DOUBLES each. Depends on the configuration only, so
 * the arithmetic (and its rounding) is the same in every call. */
static uint32_t block_frames(const affect_hmm_config *cfg)
{
    uint32_t k = cfg->n_states * cfg->n_mix, d = dbuf_width(cfg);
    uint32_t wide = k > d ? k : d;
    uint32_t b = BLOCK_DOUBLES / wide;
    if (b > BLOCK_FRAMES)
        b = BLOCK_FRAMES;
    return b ? b : 1;
}

/* ------------------------------------------------------------------------------------------ */
/* one-allocation workspaces                                                                  */

/* ------------------------------------------------------------------------------------------ */
/* the model object                                                                           */

static affect_hmm *model_alloc(const affect_hmm_config *cfg)
{
    size_t n = cfg->n_states, k = (size_t)cfg->n_states * cfg->n_mix, m = cfg->dim, cs, km, kc;
    bool full = cfg->cov == AFFECT_HMM_FULL;
    if (full) {
        if (!affect_mul_size(m, m, &cs))
            return NULL;
    } else {
        cs = m;
    }
    if (!affect_mul_size(k, m, &km) || !affect_mul_size(k, cs, &kc))
        return NULL;
    affect_hmm *h = NULL;
    affect_ws_part parts[] = {
        {(void **)&h, 1, sizeof *h},
        {NULL, n, sizeof(double)},                         /* start */
        {NULL, n * n, sizeof(double)},                     /* trans */
        {NULL, k, sizeof(double)},                         /* weights */
        {NULL, km, sizeof(double)},                        /* means */
        {NULL, kc, sizeof(double)},                        /* covs */
        {NULL, n, sizeof(double)},                         /* log_start */
        {NULL, n * n, sizeof(double)},                     /* log_trans */
        {NULL, kc, sizeof(double)},                        /* fac */
        {NULL, k, sizeof(double)},                         /* half_logdet */
        {NULL, k, sizeof(double)},                         /* cnorm */
        {NULL, (size_t)cfg->max_iter + 1, sizeof(double)}, /* loglik */
        {NULL, full ? kc : 0, sizeof(double)},             /* inv */
        {NULL, full ? km : 0, sizeof(double)},             /* ib */
        {NULL, m, sizeof(double)},                         /* centre */
    };
    double *p[14];
    for (int i = 0; i < 14; i++)
        parts[i + 1].slot = (void **)&p[i];
    void *block = affect_ws_alloc(parts, sizeof parts / sizeof parts[0]);
    if (!block)
        return NULL;
    memset(h, 0, sizeof *h);
    h->cfg = *cfg;
    h->cfg.monitor = NULL;
    h->cs = cs;
    h->block = block_frames(cfg);
    h->start = p[0];
    h->trans = p[1];
    h->weights = p[2];
    h->means = p[3];
    h->covs = p[4];
    h->log_start = p[5];
    h->log_trans = p[6];
    h->fac = p[7];
    h->half_logdet = p[8];
    h->cnorm = p[9];
    h->loglik = p[10];
    h->inv = p[11];
    h->ib = p[12];
    h->centre = p[13];
    h->loglik[0] = 0.0;
    return h;
}

void affect_hmm_free(affect_hmm *h)
{
    affect_free(h); /* the model is one block, the struct first */
}

/* Factors component k's covariance into fac (and half_logdet). Returns 0, or the LAPACK-style
 * index (≥ 1) of the first pivot that is not positive. */
static int factor_one(affect_hmm *h, size_t k)
{
    uint32_t m = h->cfg.dim;
    const double *cov = h->covs + k * h->cs;
    double *f = h->fac + k * h->cs;
    double hld = 0.0;
    if (h->cfg.cov == AFFECT_HMM_FULL) {
        memcpy(f, cov, h->cs * sizeof *f);
        /* column-major 'U' on a symmetric row-major array = row-major 'L', without a copy */
        lapack_int info;
        AFFECT_BLAS(
            info = LAPACKE_dpotrf_work(LAPACK_COL_MAJOR, 'U', (lapack_int)m, f, (lapack_int)m));
        if (info != 0)
            return info > 0 ? (int)info : 1;
        for (uint32_t d = 0; d < m; d++) {
            double l = f[(size_t)d * m + d];
            if (!(l > 0) || !isfinite(l))
                return (int)d + 1;
            hld += log(l);
            for (uint32_t e = d + 1; e < m; e++) /* clear the strict upper part */
                f[(size_t)d * m + e] = 0.0;
        }
    } else {
        for (uint32_t d = 0; d < m; d++) {
            double v = cov[d];
            if (!(v > 0) || !isfinite(v))
                return (int)d + 1;
            f[d] = 1.0 / sqrt(v);
            hld += 0.5 * log(v);
        }
    }
    if (!isfinite(hld))
        return 1;
    h->half_logdet[k] = hld;
    return 0;
}

/* Full covariances: the inverse factors W_k = L_k⁻¹ (lower triangular) stored by panels of
 * TRI_ROWS rows for densities: panel p holds rows r0 .. r1 − 1 of every W_k, columns 0 .. r1 − 1
 * only (the rest is 0), as one row-major (K·(r1 − r0)) × r1 matrix, row-major over (r, k) (row r
 * of every component, then row r + 1, ...); the panels follow one another. */
static double *inv_row(const affect_hmm *h, uint32_t k, uint32_t r)
{
    uint32_t m = h->cfg.dim, K = h->cfg.n_states * h->cfg.n_mix;
    uint32_t r0 = r - r % TRI_ROWS, r1 = m - r0 < TRI_ROWS ? m : r0 + TRI_ROWS;
    /* the panels before: Σ_{p < P} K × TRI_ROWS × (p + 1) TRI_ROWS, P = r0 / TRI_ROWS */
    size_t P = r0 / TRI_ROWS;
    size_t base = (size_t)K * TRI_ROWS * TRI_ROWS * (P * (P + 1) / 2);
    return h->inv + base + ((size_t)(r - r0) * K + k) * r1;
}

/* Fills the panels of W_k (forward substitution, row by row: W[r][c] = (δ_rc −
 * Σ_{c ≤ s < r} L[r][s] W[s][c]) / L[r][r]), the centre c (the mean of the component means) and
 * ib_k = W_k (μ_k − c). The densities then need one matrix product per panel for all components
 * together instead of one triangular solve per component; subtracting c first keeps the
 * cancellation in W x − W μ small when the data sit far from the origin. */
static void prepare_inverses(affect_hmm *h)
{
    uint32_t m = h->cfg.dim, K = h->cfg.n_states * h->cfg.n_mix;
    for (uint32_t d = 0; d < m; d++) {
        double s = 0.0;
        for (uint32_t k = 0; k < K; k++)
            s += h->means[(size_t)k * m + d];
        h->centre[d] = s / K;
    }
    for (uint32_t k = 0; k < K; k++) {
        const double *f = h->fac + (size_t)k * h->cs;
        const double *mu = h->means + (size_t)k * m;
        for (uint32_t r = 0; r < m; r++) {
            double *w = inv_row(h, k, r);
            const double *l = f + (size_t)r * m;
            uint32_t r1 = r - r % TRI_ROWS + TRI_ROWS < m ? r - r % TRI_ROWS + TRI_ROWS : m;
            for (uint32_t c = 0; c < r1; c++)
                w[c] = 0.0;
            for (uint32_t s = 0; s < r; s++) { /* w −= L[r][s] W[s] (row s has s + 1 entries) */
                const double *ws = inv_row(h, k, s);
                double lrs = l[s];
                for (uint32_t c = 0; c <= s; c++)
                    w[c] -= lrs * ws[c];
            }
            w[r] += 1.0;
            double d = l[r];
            double y = 0.0;
            for (uint32_t c = 0; c <= r; c++) {
                w[c] /= d;
                y += w[c] * (mu[c] - h->centre[c]);
            }
            h->ib[(size_t)r * K + k] = y;
        }
    }
}

/* Recomputes the logs of start, transitions and the per-component constants (and, for full
 * covariances, the inverse factors), after the factors changed. */
static void refresh_logs(affect_hmm *h)
{
    size_t n = h->cfg.n_states, k = n * h->cfg.n_mix;
    for (size_t i = 0; i < n; i++)
        h->log_start[i] = h->start[i] > 0 ? log(h->start[i]) : -INFINITY;
    for (size_t i = 0; i < n * n; i++)
        h->log_trans[i] = h->trans[i] > 0 ? log(h->trans[i]) : -INFINITY;
    double c = -0.5 * (double)h->cfg.dim * LOG_2PI;
    for (size_t i = 0; i < k; i++)
        h->cnorm[i] = h->weights[i] > 0 ? log(h->weights[i]) + c - h->half_logdet[i] : -INFINITY;
    if (h->cfg.cov == AFFECT_HMM_FULL)
        prepare_inverses(h);
}

/* ------------------------------------------------------------------------------------------ */
/* densities                                                                                  */

/* exp(v) for v ≤ 0, with 0 below EXP_MIN (and for −∞). */
static inline double exp0(double v)
{
    return v < EXP_MIN ? 0.0 : exp(v);
}

/* log b_i(x_t) for frames x[0 .. n) (n ≤ block) into lb (n × N) and, when rho is not NULL, the
 * within-state responsibilities into rho (n × N × M), from c (n × N × M, frame-major): the
 * components' log(w N(x_t)). The largest term of each log-sum-exp is exp(0) = 1 exactly, so it
 * is not computed. */
static void mix_lse(const affect_hmm *h, const double *c, uint32_t n, double *lb, double *rho)
{
    uint32_t N = h->cfg.n_states, M = h->cfg.n_mix;
    for (uint32_t t = 0; t < n; t++) {
        for (uint32_t i = 0; i < N; i++) {
            const double *ci = c + ((size_t)t * N + i) * M;
            double mx = ci[0];
            uint32_t top = 0;
            for (uint32_t j = 1; j < M; j++)
                if (ci[j] > mx) {
                    mx = ci[j];
                    top = j;
                }
            double *r = rho ? rho + ((size_t)t * N + i) * M : NULL;
            if (mx == -INFINITY) {
                lb[(size_t)t * N + i] = -INFINITY;
                if (r)
                    for (uint32_t j = 0; j < M; j++)
                        r[j] = 0.0;
                continue;
            }
            double s = 0.0;
            for (uint32_t j = 0; j < M; j++) {
                double e = j == top ? 1.0 : exp0(ci[j] - mx);
                s += e;
                if (r)
                    r[j] = e;
            }
            lb[(size_t)t * N + i] = mx + log(s);
            if (r)
                for (uint32_t j = 0; j < M; j++)
                    r[j] /= s;
        }
    }
}

/* One frame's sums over a panel's rows: for each component k, s_k = Σ_r y[r][k]² (rows
 * ascending), stored into out[k] (first panel) or added to it. Eight components at a time in
 * registers, so that the loop over r vectorizes across them. */
static void panel_sums(const double *restrict y, uint32_t K, uint32_t rows, bool first,
                       double *restrict out)
{
    uint32_t k0 = 0;
    for (; k0 + 8 <= K; k0 += 8) {
        double s[8];
        for (uint32_t j = 0; j < 8; j++)
            s[j] = y[k0 + j] * y[k0 + j];
        for (uint32_t r = 1; r < rows; r++) {
            const double *restrict yr = y + (size_t)r * K + k0;
            for (uint32_t j = 0; j < 8; j++)
                s[j] += yr[j] * yr[j];
        }
        if (first)
            for (uint32_t j = 0; j < 8; j++)
                out[k0 + j] = s[j];
        else
            for (uint32_t j = 0; j < 8; j++)
                out[k0 + j] += s[j];
    }
    for (; k0 < K; k0++) {
        double s = y[k0] * y[k0];
        for (uint32_t r = 1; r < rows; r++)
            s += y[(size_t)r * K + k0] * y[(size_t)r * K + k0];
        out[k0] = first ? s : out[k0] + s;
    }
}

/* log b_i(x_t) for frames x[0 .. n) (n ≤ block) into lb (n × N) and, when rho is not NULL, the
 * within-state responsibilities into rho (n × N × M). cbuf holds (block + 1) × N × M doubles,
 * dbuf block × dbuf_width. */
static void densities(const affect_hmm *h, const double *x, uint32_t n, double *lb, double *rho,
                      double *cbuf, double *dbuf)
{
    uint32_t N = h->cfg.n_states, M = h->cfg.n_mix, m = h->cfg.dim, K = N * M;
    if (h->cfg.cov != AFFECT_HMM_FULL) {
        for (uint32_t t = 0; t < n; t++) {
            const double *xt = x + (size_t)t * m;
            double *out = cbuf + (size_t)t * K;
            for (uint32_t k = 0; k < K; k++) {
                const double *mu = h->means + (size_t)k * m;
                const double *f = h->fac + (size_t)k * h->cs;
                double c = h->cnorm[k];
                double q = 0.0;
                for (uint32_t d = 0; d < m; d++) {
                    double v = (xt[d] - mu[d]) * f[d];
                    q += v * v;
                }
                out[k] = c == -INFINITY ? -INFINITY : c - 0.5 * q;
            }
        }
        mix_lse(h, cbuf, n, lb, rho);
        return;
    }
    /* ‖L⁻¹(x − μ)‖² = ‖W (x − c) − ib‖², SUB_FRAMES frames at a time (so that everything stays
     * in cache), panel by panel: Y = −ib, then Y += (X − c)[:, 0..r1) Pᵀ for all components at
     * once (one dgemm with β = 1), then per frame and component the panel's sum of squares over
     * its rows, added to the frame's total (rows r-major in the panel, so that these loops run
     * across the components); then log(w N) = cnorm − ½ total and the log-sum-exps of these
     * frames */
    for (uint32_t t0 = 0; t0 < n; t0 += SUB_FRAMES) {
        uint32_t nt = n - t0 < SUB_FRAMES ? n - t0 : SUB_FRAMES;
        double *restrict xc = dbuf, *restrict y = dbuf + (size_t)nt * m;
        double *restrict acc = cbuf;
        const double *restrict ctr = h->centre;
        for (uint32_t t = 0; t < nt; t++) {
            const double *restrict xt = x + (size_t)(t0 + t) * m;
            double *restrict ct = xc + (size_t)t * m;
            for (uint32_t d = 0; d < m; d++)
                ct[d] = xt[d] - ctr[d];
        }
        const double *panel = h->inv;
        for (uint32_t r0 = 0; r0 < m; r0 += TRI_ROWS) {
            uint32_t r1 = m - r0 < TRI_ROWS ? m : r0 + TRI_ROWS, rows = r1 - r0;
            uint32_t wide = K * rows;
            const double *restrict ib = h->ib + (size_t)r0 * K;
            for (uint32_t e = 0; e < wide; e++)
                y[e] = -ib[e];
            for (uint32_t t = 1; t < nt; t++)
                memcpy(y + (size_t)t * wide, y, wide * sizeof *y);
            AFFECT_BLAS(cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasTrans, (int)nt, (int)wide,
                                    (int)r1, 1.0, xc, (int)m, panel, (int)r1, 1.0, y, (int)wide));
            for (uint32_t t = 0; t < nt; t++)
                panel_sums(y + (size_t)t * wide, K, rows, r0 == 0, acc + (size_t)t * K);
            panel += (size_t)wide * r1;
        }
        const double *restrict cn = h->cnorm;
        for (uint32_t t = 0; t < nt; t++) {
            double *restrict at = acc + (size_t)t * K;
            for (uint32_t k = 0; k < K; k++)
                at[k] = cn[k] == -INFINITY ? -INFINITY : cn[k] - 0.5 * at[k];
        }
        mix_lse(h, acc, nt, lb + (size_t)t0 * N, rho ? rho + (size_t)t0 * K : NULL);
    }
}

/* ------------------------------------------------------------------------------------------ */
/* recursions                                                                                 */

static double vmax(const double *v, uint32_t n)
{
    double mx = -INFINITY;
    for (uint32_t i = 0; i < n; i++)
        if (v[i] > mx)
            mx = v[i];
    return mx;
}

static double lse(const double *v, uint32_t n)
{
    double mx = vmax(v, n);
    if (mx == -INFINITY)
        return -INFINITY;
    double s = 0.0;
    for (uint32_t i = 0; i < n; i++)
        s += exp0(v[i] - mx);
    return mx + log(s);
}

/* log α_0 = log π + log b(x_0). */
static void forward_first(const affect_hmm *h, const double *lb0, double *a0)
{
    for (uint32_t i = 0; i < h->cfg.n_states; i++)
        a0[i] = h->log_start[i] + lb0[i];
}

/* log α_t from log α_{t−1} (prev) and log b(x_t) (lbt); p is N scratch. */
static void forward_step(const affect_hmm *h, const double *prev, const double *lbt, double *cur,
                         double *p)
{
    uint32_t N = h->cfg.n_states, top = 0;
    double A = prev[0];
    for (uint32_t i = 1; i < N; i++)
        if (prev[i] > A) {
            A = prev[i];
            top = i;
        }
    if (A == -INFINITY) {
        for (uint32_t l = 0; l < N; l++)
            cur[l] = -INFINITY;
        return;
    }
    for (uint32_t i = 0; i < N; i++)
        p[i] = i == top ? 1.0 : exp0(prev[i] - A); /* exp(0) = 1 exactly */
    for (uint32_t l = 0; l < N; l++)
        cur[l] = 0.0;
    for (uint32_t i = 0; i < N; i++) {
        const double *a = h->trans + (size_t)i * N;
        double pi = p[i];
        if (pi == 0.0)
            continue;
        for (uint32_t l = 0; l < N; l++)
            cur[l] += pi * a[l];
    }
    for (uint32_t l = 0; l < N; l++) {
        double s = cur[l];
        if (s >= LINEAR_MIN) {
            cur[l] = lbt[l] + (A + log(s));
        } else { /* exact: log-sum-exp with this column's own maximum */
            double mx = -INFINITY;
            for (uint32_t i = 0; i < N; i++) {
                double v = prev[i] + h->log_trans[(size_t)i * N + l];
                if (v > mx)
                    mx = v;
            }
            if (mx == -INFINITY) {
                cur[l] = -INFINITY;
                continue;
            }
            double e = 0.0;
            for (uint32_t i = 0; i < N; i++)
                e += exp0(prev[i] + h->log_trans[(size_t)i * N + l] - mx);
            cur[l] = lbt[l] + (mx + log(e));
        }
    }
}

/* Scratch of the forward–backward pass. */
typedef struct fb_ws {
    double *lb;    /* T × N */
    double *alpha; /* T × N */
    double *cbuf;  /* (block + 1) × N × M */
    double *dbuf;  /* block × dbuf_width */
    double *v[6];  /* N each */
    double *vv;    /* N × N */
} fb_ws;

/* The M worst-explained frames of each state (ascending log b), for re-seeding; a frame
 * belongs to its most probable state. Frames are met sequence by sequence, each from its last
 * frame back (the backward pass), and ties keep the frame met first. */
typedef struct worst_frame {
    double lb;
    uint32_t seq;
    uint32_t t;
} worst_frame;

typedef struct tracker {
    worst_frame *w;  /* N × M */
    uint32_t *count; /* N */
} tracker;

static void track(tracker *tr, uint32_t M, uint32_t i, double lb, uint32_t seq, uint32_t t)
{
    worst_frame *w = tr->w + (size_t)i * M;
    uint32_t c = tr->count[i];
    if (c == M && !(lb < w[M - 1].lb))
        return;
    uint32_t pos = c < M ? c : M - 1;
    while (pos > 0 && lb < w[pos - 1].lb) { /* strict: on ties the frame met first stays */
        w[pos] = w[pos - 1];
        pos--;
    }
    w[pos].lb = lb;
    w[pos].seq = seq;
    w[pos].t = t;
    if (c < M)
        tr->count[i] = c + 1;
}

/* Forward–backward over one sequence. Writes log P(x) into *loglik; when it is finite:
 * rho (T × N × M, filled with within-state responsibilities by densities) becomes the
 * posteriors γ_t(i, j), xi (N × N, may be NULL) gains Σ_t ξ_t, g0 (may be NULL) gains γ_0, and
 * tr (may be NULL) records the frames of each state worst explained by it. */
static void forward_backward(const affect_hmm *h, const double *x, uint32_t T, fb_ws *w,
                             double *rho, double *xi, double *g0, tracker *tr, uint32_t seq,
                             affect_monitor *mon, double *loglik)
{
    uint32_t N = h->cfg.n_states, M = h->cfg.n_mix, m = h->cfg.dim;
    for (uint32_t t0 = 0; t0 < T; t0 += h->block) {
        if (affect_monitor_stopped(mon)) { /* the caller checks the monitor */
            *loglik = NAN;
            return;
        }
        uint32_t n = T - t0 < h->block ? T - t0 : h->block;
        densities(h, x + (size_t)t0 * m, n, w->lb + (size_t)t0 * N,
                  rho ? rho + (size_t)t0 * N * M : NULL, w->cbuf, w->dbuf);
    }
    double *alpha = w->alpha, *lb = w->lb;
    forward_first(h, lb, alpha);
    for (uint32_t t = 1; t < T; t++)
        forward_step(h, alpha + (size_t)(t - 1) * N, lb + (size_t)t * N, alpha + (size_t)t * N,
                     w->v[0]);
    double L = lse(alpha + (size_t)(T - 1) * N, N);
    *loglik = L;
    if (!isfinite(L))
        return;

    double *beta = w->v[0], *nbeta = w->v[1], *g = w->v[2], *q = w->v[3], *s = w->v[4],
           *p = w->v[5];
    for (uint32_t i = 0; i < N; i++)
        beta[i] = 0.0;
    for (uint32_t t = T;;) {
        t--;
        const double *at = alpha + (size_t)t * N;
        /* γ_t, normalised over the states */
        for (uint32_t i = 0; i < N; i++)
            g[i] = at[i] + beta[i];
        double G = lse(g, N);
        uint32_t best = 0;
        for (uint32_t i = 0; i < N; i++) {
            g[i] = G == -INFINITY ? 0.0 : exp0(g[i] - G);
            if (g[i] > g[best])
                best = i;
        }
        if (rho) {
            double *r = rho + (size_t)t * N * M;
            for (uint32_t i = 0; i < N; i++)
                for (uint32_t j = 0; j < M; j++)
                    r[(size_t)i * M + j] *= g[i];
        }
        if (tr)
            track(tr, M, best, lb[(size_t)t * N + best], seq, t);
        if (t == 0) {
            if (g0)
                for (uint32_t i = 0; i < N; i++)
                    g0[i] += g[i];
            break;
        }
        /* w_l = log b_l(x_t) + log β_t(l); β_{t−1}(i) = LSE_l(log a_il + w_l) */
        const double *lbt = lb + (size_t)t * N;
        for (uint32_t l = 0; l < N; l++)
            g[l] = lbt[l] + beta[l]; /* g reused as w */
        double B = vmax(g, N);
        if (B == -INFINITY) {
            for (uint32_t i = 0; i < N; i++)
                beta[i] = -INFINITY;
            continue;
        }
        for (uint32_t l = 0; l < N; l++)
            q[l] = exp0(g[l] - B);
        for (uint32_t i = 0; i < N; i++) {
            const double *a = h->trans + (size_t)i * N;
            double acc = 0.0;
            for (uint32_t l = 0; l < N; l++)
                acc += a[l] * q[l];
            s[i] = acc;
            if (acc >= LINEAR_MIN) {
                nbeta[i] = B + log(acc);
            } else {
                const double *la = h->log_trans + (size_t)i * N;
                double mx = -INFINITY;
                for (uint32_t l = 0; l < N; l++)
                    if (la[l] + g[l] > mx)
                        mx = la[l] + g[l];
                if (mx == -INFINITY) {
                    nbeta[i] = -INFINITY;
                    continue;
                }
                double e = 0.0;
                for (uint32_t l = 0; l < N; l++)
                    e += exp0(la[l] + g[l] - mx);
                nbeta[i] = mx + log(e);
            }
        }
        /* ξ_{t−1}(i, l) ∝ α_{t−1}(i) a_il b_l(x_t) β_t(l), normalised over (i, l) */
        if (xi) {
            const double *ap = alpha + (size_t)(t - 1) * N;
            double A = vmax(ap, N);
            double Z = 0.0;
            if (A != -INFINITY) {
                for (uint32_t i = 0; i < N; i++) {
                    p[i] = exp0(ap[i] - A);
                    Z += p[i] * s[i];
                }
            }
            if (Z >= LINEAR_MIN) {
                for (uint32_t i = 0; i < N; i++) {
                    double pi = p[i] / Z;
                    if (pi == 0.0)
                        continue;
                    const double *a = h->trans + (size_t)i * N;
                    double *xr = xi + (size_t)i * N;
                    for (uint32_t l = 0; l < N; l++)
                        xr[l] += pi * a[l] * q[l];
                }
            } else if (A != -INFINITY) { /* exact, in log space */
                double *vv = w->vv;
                for (uint32_t i = 0; i < N; i++)
                    for (uint32_t l = 0; l < N; l++)
                        vv[(size_t)i * N + l] = ap[i] + h->log_trans[(size_t)i * N + l] + g[l];
                double Zl = lse(vv, N * N);
                if (Zl != -INFINITY)
                    for (size_t k = 0; k < (size_t)N * N; k++)
                        xi[k] += exp0(vv[k] - Zl);
            }
        }
        double *tmp = beta;
        beta = nbeta;
        nbeta = tmp;
    }
}

/* ------------------------------------------------------------------------------------------ */
/* checks                                                                                     */

static const char *plural(uint64_t n, const char *one, const char *many)
{
    return n == 1 ? one : many;
}

/* A sequence to score: frames present and every value finite. */
static affect_status check_frames(const affect_hmm *h, const double *x, uint32_t n_frames,
                                  affect_error *err)
{
    if (n_frames == 0)
        return affect_fail(err, AFFECT_ERR_INVALID, "the sequence has no frames");
    if (!x)
        return affect_fail(err, AFFECT_ERR_INVALID, "the sequence has no data");
    uint32_t m = h->cfg.dim;
    for (uint32_t t = 0; t < n_frames; t++)
        for (uint32_t d = 0; d < m; d++)
            if (!isfinite(x[(size_t)t * m + d]))
                return affect_fail(err, AFFECT_ERR_INVALID, "frame %u: value %u is not finite", t,
                                   d);
    return AFFECT_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* scoring                                                                                    */

/* Forward log-likelihood with block-sized scratch: cbuf, dbuf, lb (block × N), a0, a1, p (N). */
static double forward_loglik(const affect_hmm *h, const double *x, uint32_t T, double *cbuf,
                             double *dbuf, double *lb, double *a0, double *a1, double *p,
                             affect_monitor *mon)
{
    uint32_t N = h->cfg.n_states, m = h->cfg.dim;
    for (uint32_t t0 = 0; t0 < T; t0 += h->block) {
        if (affect_monitor_stopped(mon)) /* the caller checks the monitor */
            return NAN;
        uint32_t n = T - t0 < h->block ? T - t0 : h->block;
        densities(h, x + (size_t)t0 * m, n, lb, NULL, cbuf, dbuf);
        for (uint32_t t = 0; t < n; t++) {
            if (t0 + t == 0) {
                forward_first(h, lb, a0);
            } else {
                forward_step(h, a0, lb + (size_t)t * N, a1, p);
                double *tmp = a0;
                a0 = a1;
                a1 = tmp;
            }
        }
    }
    return lse(a0, N);
}

affect_status affect_hmm_loglik(const affect_hmm *h, const double *x, uint32_t n_frames,
                                double *loglik, affect_monitor *mon, affect_error *err)
{
    affect_status st = check_frames(h, x, n_frames, err);
    if (st)
        return st;
    size_t N = h->cfg.n_states, K = N * h->cfg.n_mix, B = h->block;
    double *cbuf, *dbuf, *lb, *a0, *a1, *p;
    affect_ws_part parts[] = {{(void **)&cbuf, (B + 1) * K, sizeof(double)},
                              {(void **)&dbuf, B * dbuf_width(&h->cfg), sizeof(double)},
                              {(void **)&lb, B * N, sizeof(double)},
                              {(void **)&a0, N, sizeof(double)},
                              {(void **)&a1, N, sizeof(double)},
                              {(void **)&p, N, sizeof(double)}};
    void *ws = affect_ws_alloc(parts, sizeof parts / sizeof parts[0]);
    if (!ws)
        return affect_nomem(err);
    double L = forward_loglik(h, x, n_frames, cbuf, dbuf, lb, a0, a1, p, mon);
    affect_free(ws);
    if ((st = affect_monitor_check(mon, err)))
        return st;
    *loglik = L;
    return AFFECT_OK;
}

affect_status affect_hmm_viterbi(const affect_hmm *h, const double *x, uint32_t n_frames,
                                 int32_t *path, double *logprob, affect_monitor *mon,
                                 affect_error *err)
{
    affect_status st = check_frames(h, x, n_frames, err);
    if (st)
        return st;
    if (!path)
        return affect_fail(err, AFFECT_ERR_INVALID, "no room for the path");
    uint32_t N = h->cfg.n_states, m = h->cfg.dim;
    size_t K = (size_t)N * h->cfg.n_mix, B = h->block, TN;
    if (!affect_mul_size(n_frames, N, &TN))
        return affect_nomem(err);
    double *cbuf, *dbuf, *lb, *d0, *d1;
    uint8_t *bp; /* N ≤ 256: a state fits in a byte */
    affect_ws_part parts[] = {{(void **)&cbuf, (B + 1) * K, sizeof(double)},
                              {(void **)&dbuf, B * dbuf_width(&h->cfg), sizeof(double)},
                              {(void **)&lb, B * N, sizeof(double)},
                              {(void **)&d0, N, sizeof(double)},
                              {(void **)&d1, N, sizeof(double)},
                              {(void **)&bp, TN, 1}};
    void *ws = affect_ws_alloc(parts, sizeof parts / sizeof parts[0]);
    if (!ws)
        return affect_nomem(err);
    for (uint32_t t0 = 0; t0 < n_frames; t0 += h->block) {
        if ((st = affect_monitor_check(mon, err))) {
            affect_free(ws);
            return st;
        }
        uint32_t n = n_frames - t0 < h->block ? n_frames - t0 : h->block;
        densities(h, x + (size_t)t0 * m, n, lb, NULL, cbuf, dbuf);
        for (uint32_t t = 0; t < n; t++) {
            const double *lbt = lb + (size_t)t * N;
            uint8_t *b = bp + (size_t)(t0 + t) * N;
            if (t0 + t == 0) {
                for (uint32_t i = 0; i < N; i++) {
                    d0[i] = h->log_start[i] + lbt[i];
                    b[i] = 0;
                }
                continue;
            }
            for (uint32_t l = 0; l < N; l++) {
                double best = -INFINITY;
                uint32_t arg = 0;
                for (uint32_t i = 0; i < N; i++) {
                    double v = d0[i] + h->log_trans[(size_t)i * N + l];
                    if (v > best) {
                        best = v;
                        arg = i;
                    }
                }
                d1[l] = best + lbt[l];
                b[l] = (uint8_t)arg;
            }
            double *tmp = d0;
            d0 = d1;
            d1 = tmp;
        }
    }
    uint32_t s = 0;
    for (uint32_t i = 1; i < N; i++)
        if (d0[i] > d0[s])
            s = i;
    if (logprob)
        *logprob = d0[s];
    for (uint32_t t = n_frames; t-- > 0;) {
        path[t] = (int32_t)s;
        s = bp[(size_t)t * N + s];
    }
    affect_free(ws);
    return AFFECT_OK;
}

#define FB_PARTS 11 /* the parts fb_parts appends */

/* Points the forward–backward scratch into a workspace (parts appended at *np). */
static void fb_parts(const affect_hmm *h, size_t T, fb_ws *w, affect_ws_part *parts, size_t *np)
{
    size_t N = h->cfg.n_states, K = N * h->cfg.n_mix, B = h->block, n = *np;
    parts[n++] = (affect_ws_part){(void **)&w->lb, T * N, sizeof(double)}; /* T·N ≤ T·K */
    parts[n++] = (affect_ws_part){(void **)&w->alpha, T * N, sizeof(double)};
    parts[n++] = (affect_ws_part){(void **)&w->cbuf, (B + 1) * K, sizeof(double)};
    parts[n++] = (affect_ws_part){(void **)&w->dbuf, B * dbuf_width(&h->cfg), sizeof(double)};
    for (int i = 0; i < 6; i++)
        parts[n++] = (affect_ws_part){(void **)&w->v[i], N, sizeof(double)};
    parts[n++] = (affect_ws_part){(void **)&w->vv, N * N, sizeof(double)};
    *np = n;
}

affect_status affect_hmm_posteriors(const affect_hmm *h, const double *x, uint32_t n_frames,
                                    double *gamma, double *xi, double *loglik, affect_monitor *mon,
                                    affect_error *err)
{
    affect_status st = check_frames(h, x, n_frames, err);
    if (st)
        return st;
    size_t N = h->cfg.n_states, TK;
    /* the sizes T × N × M (gamma, the caller's) and T × N (ours) must be representable */
    if (!affect_mul_size(n_frames, N * h->cfg.n_mix, &TK) ||
        !affect_mul_size(TK, sizeof(double), &TK))
        return affect_nomem(err);
    fb_ws w;
    affect_ws_part parts[FB_PARTS];
    size_t np = 0;
    fb_parts(h, n_frames, &w, parts, &np);
    void *ws = affect_ws_alloc(parts, np);
    if (!ws)
        return affect_nomem(err);
    if (xi)
        memset(xi, 0, N * N * sizeof *xi);
    double L;
    forward_backward(h, x, n_frames, &w, gamma, xi, NULL, NULL, 0, mon, &L);
    affect_free(ws);
    if ((st = affect_monitor_check(mon, err)))
        return st;
    if (!isfinite(L))
        return affect_fail(err, AFFECT_ERR_RANGE,
                           "the sequence has probability 0 under the model: no posteriors");
    if (loglik)
        *loglik = L;
    return AFFECT_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* accessors                                                                                  */

const affect_hmm_config *affect_hmm_get_config(const affect_hmm *h)
{
    return &h->cfg;
}

const double *affect_hmm_start(const affect_hmm *h)
{
    return h->start;
}

const double *affect_hmm_transitions(const affect_hmm *h)
{
    return h->trans;
}

const double *affect_hmm_weights(const affect_hmm *h)
{
    return h->weights;
}

const double *affect_hmm_means(const affect_hmm *h)
{
    return h->means;
}

const double *affect_hmm_covariances(const affect_hmm *h)
{
    return h->covs;
}

void affect_hmm_get_report(const affect_hmm *h, affect_hmm_report *report)
{
    memset(report, 0, sizeof *report);
    report->iterations = h->has_report ? h->iterations : 0;
    report->converged = h->has_report && h->converged;
    report->loglik = h->loglik; /* the empty report: one value, 0 */
    report->reseeded = h->has_report ? h->reseeded : 0;
    report->n_sequences = h->has_report ? h->n_sequences : 0;
    report->n_frames = h->has_report ? h->n_frames : 0;
}

double affect_hmm_mean_duration(const affect_hmm *h, double *per_state)
{
    uint32_t N = h->cfg.n_states;
    double sum = 0.0;
    for (uint32_t i = 0; i < N; i++) {
        double a = h->trans[(size_t)i * N + i];
        double d = a >= 1.0 ? INFINITY : 1.0 / (1.0 - a);
        if (per_state)
            per_state[i] = d;
        if (i > 0)
            sum += d;
    }
    if (N == 1) {
        double a = h->trans[0];
        return a >= 1.0 ? INFINITY : 1.0 / (1.0 - a);
    }
    return sum / (double)(N - 1);
}

affect_status affect_hmm_set_report(affect_hmm *h, const affect_hmm_report *report,
                                    affect_error *err)
{
    if (!report)
        return affect_fail(err, AFFECT_ERR_INVALID, "no report");
    if (report->iterations > h->cfg.max_iter)
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "the report has %u iterations, more than max_iter %u",
                           report->iterations, h->cfg.max_iter);
    if (!report->loglik)
        return affect_fail(err, AFFECT_ERR_INVALID, "the report has no log-likelihoods");
    for (uint32_t i = 0; i <= report->iterations; i++)
        if (!isfinite(report->loglik[i]))
            return affect_fail(err, AFFECT_ERR_INVALID,
                               "log-likelihood %u of the report is not finite", i);
    memmove(h->loglik, report->loglik, ((size_t)report->iterations + 1) * sizeof(double));
    h->iterations = report->iterations;
    h->converged = report->converged;
    h->reseeded = report->reseeded;
    h->n_sequences = report->n_sequences;
    h->n_frames = report->n_frames;
    h->has_report = true;
    return AFFECT_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* building from parameters                                                                   */

static bool is_prob(double v)
{
    return v >= 0 && v <= 1; /* false for NaN */
}

affect_status affect_hmm_from_params(const affect_hmm_config *cfg, const double *start,
                                     const double *trans, const double *weights,
                                     const double *means, const double *covs, affect_hmm **out,
                                     affect_error *err)
{
    *out = NULL;
    const char *msg = affect_hmm_config_check(cfg);
    if (msg)
        return affect_fail(err, AFFECT_ERR_INVALID, "%s", msg);
    if (!start || !trans || !weights || !means || !covs)
        return affect_fail(err, AFFECT_ERR_INVALID, "missing parameters");
    uint32_t N = cfg->n_states, M = cfg->n_mix, m = cfg->dim;
    double sum = 0.0;
    for (uint32_t i = 0; i < N; i++) {
        if (!is_prob(start[i]))
            return affect_fail(err, AFFECT_ERR_INVALID,
                               "start probability of state %u is %g, not a probability", i,
                               start[i]);
        sum += start[i];
    }
    if (!(fabs(sum - 1.0) <= SUM_TOL))
        return affect_fail(err, AFFECT_ERR_INVALID, "start probabilities sum to %g, not 1", sum);
    if (!cfg->learn_start)
        for (uint32_t i = 0; i < N; i++)
            if (start[i] != (i == 0 ? 1.0 : 0.0))
                return affect_fail(err, AFFECT_ERR_INVALID,
                                   "start probability of state %u is %g, but the start is not "
                                   "learned: it must be (1, 0, ..., 0)",
                                   i, start[i]);
    for (uint32_t i = 0; i < N; i++) {
        sum = 0.0;
        for (uint32_t l = 0; l < N; l++) {
            double a = trans[(size_t)i * N + l];
            if (!is_prob(a))
                return affect_fail(err, AFFECT_ERR_INVALID,
                                   "transition %u -> %u is %g, not a probability", i, l, a);
            if (a != 0.0 && !allowed(cfg, i, l)) {
                if (l > i)
                    return affect_fail(err, AFFECT_ERR_INVALID,
                                       "transition %u -> %u is %g, but max_jump is %u", i, l, a,
                                       cfg->max_jump);
                return affect_fail(err, AFFECT_ERR_INVALID,
                                   "transition %u -> %u is %g, but the left-right topology "
                                   "forbids it",
                                   i, l, a);
            }
            sum += a;
        }
        if (!(fabs(sum - 1.0) <= SUM_TOL))
            return affect_fail(err, AFFECT_ERR_INVALID, "transition row %u sums to %g, not 1", i,
                               sum);
    }
    for (uint32_t i = 0; i < N; i++) {
        sum = 0.0;
        for (uint32_t j = 0; j < M; j++) {
            double w = weights[(size_t)i * M + j];
            if (!is_prob(w))
                return affect_fail(err, AFFECT_ERR_INVALID,
                                   "weight of state %u, mixture %u is %g, not a probability", i, j,
                                   w);
            sum += w;
        }
        if (!(fabs(sum - 1.0) <= SUM_TOL))
            return affect_fail(err, AFFECT_ERR_INVALID, "weights of state %u sum to %g, not 1", i,
                               sum);
    }
    for (uint32_t k = 0; k < N * M; k++)
        for (uint32_t d = 0; d < m; d++)
            if (!isfinite(means[(size_t)k * m + d]))
                return affect_fail(err, AFFECT_ERR_INVALID,
                                   "mean of state %u, mixture %u: value %u is not finite", k / M,
                                   k % M, d);
    bool full = cfg->cov == AFFECT_HMM_FULL;
    size_t cs = full ? (size_t)m * m : m;
    for (uint32_t k = 0; k < N * M; k++) {
        const double *c = covs + k * cs;
        for (size_t e = 0; e < cs; e++)
            if (!isfinite(c[e])) {
                if (full)
                    return affect_fail(err, AFFECT_ERR_INVALID,
                                       "covariance of state %u, mixture %u: entry (%zu, %zu) is "
                                       "not finite",
                                       k / M, k % M, e / m, e % m);
                return affect_fail(err, AFFECT_ERR_INVALID,
                                   "covariance of state %u, mixture %u: variance %zu is not "
                                   "finite",
                                   k / M, k % M, e);
            }
        if (!full)
            continue;
        for (uint32_t r = 0; r < m; r++)
            for (uint32_t s = r + 1; s < m; s++) {
                double u = c[(size_t)r * m + s], v = c[(size_t)s * m + r];
                if (fabs(u - v) > SYM_TOL * (fabs(u) + fabs(v)))
                    return affect_fail(err, AFFECT_ERR_INVALID,
                                       "covariance of state %u, mixture %u is not symmetric: "
                                       "(%u, %u) is %g, (%u, %u) is %g",
                                       k / M, k % M, r, s, u, s, r, v);
            }
    }

    affect_hmm *h = model_alloc(cfg);
    if (!h)
        return affect_nomem(err);
    memcpy(h->start, start, N * sizeof(double));
    memcpy(h->trans, trans, (size_t)N * N * sizeof(double));
    memcpy(h->weights, weights, (size_t)N * M * sizeof(double));
    memcpy(h->means, means, (size_t)N * M * m * sizeof(double));
    memcpy(h->covs, covs, (size_t)N * M * cs * sizeof(double));
    for (uint32_t k = 0; k < N * M; k++)
        if (factor_one(h, k) != 0) {
            affect_hmm_free(h);
            return affect_fail(err, AFFECT_ERR_INVALID,
                               "covariance of state %u, mixture %u is not positive definite", k / M,
                               k % M);
        }
    refresh_logs(h);
    *out = h;
    return AFFECT_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* training                                                                                   */

/* The training workspace. */
typedef struct train_ws {
    fb_ws fb;
    double *rho; /* maxT × N × M */
    /* sufficient statistics, per component k = i·M + j: Σγ, Σγ(x − c), Σγ(x − c)(x − c)ᵀ */
    double *n;  /* K */
    double *s1; /* K × m */
    double *S;  /* K × cs */
    double *xi; /* N × N */
    double *g0; /* N */
    tracker tr;
    /* initialisation */
    const double **fp; /* total frames: the pooled frames of one segment */
    const double **mp; /* total frames: the members of one cluster */
    uint32_t *asg;     /* total frames */
    double *d2;        /* total frames */
    double *cen;       /* M × m */
    double *sums;      /* M × m */
    size_t *cnt;       /* M */
    double *frac;      /* M */
    double *mbar;      /* m */
    double *pool;      /* cs */
    double *dsq;       /* m: scatter's scratch */
    double *rn;        /* maxT: ‖x_t − centre‖ of the sequence (scatter's quick test) */
} train_ws;

/* Squared distance with four partial sums (fixed order). */
static double dist2(const double *a, const double *b, uint32_t m)
{
    double s0 = 0, s1 = 0, s2 = 0, s3 = 0;
    uint32_t d = 0;
    for (; d + 4 <= m; d += 4) {
        double e0 = a[d] - b[d], e1 = a[d + 1] - b[d + 1], e2 = a[d + 2] - b[d + 2],
               e3 = a[d + 3] - b[d + 3];
        s0 += e0 * e0;
        s1 += e1 * e1;
        s2 += e2 * e2;
        s3 += e3 * e3;
    }
    for (; d < m; d++) {
        double e = a[d] - b[d];
        s0 += e * e;
    }
    return (s0 + s1) + (s2 + s3);
}

static size_t pick_uniform(affect_rng *rng, size_t P)
{
    size_t p = (size_t)(affect_rng_uniform(rng) * (double)P);
    return p < P ? p : P - 1;
}

/* k-means++ then Lloyd on the P pooled frames fp: assignments into w->asg (centres in w->cen). */
static void kmeans(train_ws *w, size_t P, uint32_t M, uint32_t m, affect_rng *rng)
{
    const double **fp = w->fp;
    double *cen = w->cen, *d2 = w->d2;
    memcpy(cen, fp[pick_uniform(rng, P)], m * sizeof(double));
    for (size_t p = 0; p < P; p++)
        d2[p] = dist2(fp[p], cen, m);
    for (uint32_t k = 1; k < M; k++) {
        double total = 0.0;
        for (size_t p = 0; p < P; p++)
            total += d2[p];
        size_t pick;
        if (total > 0 && isfinite(total)) {
            double u = affect_rng_uniform(rng) * total, cum = 0.0;
            pick = P - 1;
            for (size_t p = 0; p < P; p++) {
                cum += d2[p];
                if (cum > u) {
                    pick = p;
                    break;
                }
            }
        } else {
            pick = pick_uniform(rng, P);
        }
        double *ck = cen + (size_t)k * m;
        memcpy(ck, fp[pick], m * sizeof(double));
        for (size_t p = 0; p < P; p++) {
            double d = dist2(fp[p], ck, m);
            if (d < d2[p])
                d2[p] = d;
        }
    }
    for (uint32_t iter = 0; iter < KMEANS_MAX_ITER; iter++) {
        size_t changed = 0;
        for (size_t p = 0; p < P; p++) {
            uint32_t best = 0;
            double bd = dist2(fp[p], cen, m);
            for (uint32_t k = 1; k < M; k++) {
                double d = dist2(fp[p], cen + (size_t)k * m, m);
                if (d < bd) {
                    bd = d;
                    best = k;
                }
            }
            if (iter == 0 || w->asg[p] != best)
                changed++;
            w->asg[p] = best;
            d2[p] = bd;
        }
        if (changed == 0)
            break;
        memset(w->sums, 0, (size_t)M * m * sizeof(double));
        memset(w->cnt, 0, M * sizeof(size_t));
        for (size_t p = 0; p < P; p++) {
            double *s = w->sums + (size_t)w->asg[p] * m;
            for (uint32_t d = 0; d < m; d++)
                s[d] += fp[p][d];
            w->cnt[w->asg[p]]++;
        }
        for (uint32_t k = 0; k < M; k++) {
            double *ck = cen + (size_t)k * m;
            if (w->cnt[k] > 0) {
                for (uint32_t d = 0; d < m; d++)
                    ck[d] = w->sums[(size_t)k * m + d] / (double)w->cnt[k];
                continue;
            }
            /* empty: jump to the point farthest from its centre */
            size_t far = 0;
            for (size_t p = 1; p < P; p++)
                if (d2[p] > d2[far])
                    far = p;
            if (d2[far] > 0) {
                memcpy(ck, fp[far], m * sizeof(double));
                d2[far] = 0.0;
            }
        }
    }
}

/* Σ_d z_d² s_d with eight partial sums (a fixed order). */
static double weighted_sq(const double *restrict z, const double *restrict sc, uint32_t m)
{
    double p[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    uint32_t d = 0;
    for (; d + 8 <= m; d += 8)
        for (uint32_t j = 0; j < 8; j++)
            p[j] += z[d + j] * z[d + j] * sc[d + j];
    for (uint32_t j = 0; d < m; d++, j++)
        p[j] += z[d] * z[d] * sc[d];
    return ((p[0] + p[1]) + (p[2] + p[3])) + ((p[4] + p[5]) + (p[6] + p[7]));
}

/* Adds Σ_t r_t (x_t − c)(x_t − c)ᵀ (full) or its diagonal, Σ_t r_t (x_t − c) and Σ_t r_t to S,
 * s1 and *n over the frames x[0 .. T) (rows of m), r_t = r[t · stride] (or 1 when r is NULL),
 * the frames given either as row pointers (rows) or as one row-major array (x). Full
 * covariances: per block of frames, the rows z_t = √r_t (x_t − c) go to dbuf and S gains
 * Σ_t z_t z_tᵀ by one dsyrk. With weights (r not NULL), the rows that are negligible,
 * Σ_d z_td² / D_d ≤ u with D_d = Σ_t z_td² over the block and u = 2⁻⁵³ / (frames in the block),
 * are left out of the product (most rows of most components when the posteriors are sharp).
 * Such a row has z_td² ≤ u D_d in every coordinate, so by Cauchy–Schwarz the part left out is at
 * most 2⁻⁵³ √(D_d D_e) in entry (d, e): within one unit roundoff of the scatter's own scale, the
 * size of the rounding error of a single addition to it. Only from PRUNE_MIN_DIM dimensions on
 * (below, the test costs more than the rows it saves). dsq is m doubles of scratch. With rn (the
 * frames' distances to a point g, and dc = ‖c − g‖), a row is first tested by the bound
 * r_t (rn_t + dc)² max_d(1 / (u D_d)) of its weighted norm (the triangle inequality), widened by
 * PRUNE_BOUND_SLACK for the rounding of both: when that is at most 1 the exact test would drop
 * the row too, so it is dropped unread — the same rows as the exact test alone, the same bits. */
static void scatter(const affect_hmm *h, const double *const *rows, const double *x, size_t T,
                    const double *r, size_t stride, const double *c, double *n, double *s1,
                    double *S, double *dbuf, double *dsq, const double *rn, double dc)
{
    uint32_t m = h->cfg.dim;
    bool full = h->cfg.cov == AFFECT_HMM_FULL, prune = full && r && m >= PRUNE_MIN_DIM;
    size_t B = h->block;
    for (size_t t0 = 0; t0 < T; t0 += B) {
        size_t nb = T - t0 < B ? T - t0 : B;
        if (prune)
            memset(dsq, 0, m * sizeof *dsq);
        for (size_t t = 0; t < nb; t++) {
            const double *restrict xt = rows ? rows[t0 + t] : x + (t0 + t) * m;
            double rr = r ? r[(t0 + t) * stride] : 1.0;
            *n += rr;
            double *restrict sum = s1;
            const double *restrict ctr = c;
            if (prune) {
                if (rr == 0.0)
                    continue; /* adds nothing anywhere; the row is never read */
                double sq = sqrt(rr);
                double *restrict dt = dbuf + t * m, *restrict ds = dsq;
                for (uint32_t d = 0; d < m; d++) {
                    double v = xt[d] - ctr[d], z = sq * v;
                    sum[d] += rr * v;
                    dt[d] = z;
                    ds[d] += z * z;
                }
            } else if (full) {
                double sq = r ? sqrt(rr) : 1.0;
                double *restrict dt = dbuf + t * m;
                for (uint32_t d = 0; d < m; d++) {
                    double v = xt[d] - ctr[d];
                    sum[d] += rr * v;
                    dt[d] = sq * v;
                }
            } else {
                double *restrict sq_sum = S;
                for (uint32_t d = 0; d < m; d++) {
                    double v = xt[d] - ctr[d];
                    sum[d] += rr * v;
                    sq_sum[d] += rr * v * v;
                }
            }
        }
        if (!full)
            continue;
        size_t kept = nb;
        if (prune) {
            /* dsq becomes 1 / (u D_d), or 0 where D_d = 0 (every z_td is 0 there) */
            double u = PRUNE_ROUNDOFF / (double)nb, smax = 0.0;
            for (uint32_t d = 0; d < m; d++) {
                dsq[d] = dsq[d] > 0 ? 1.0 / (u * dsq[d]) : 0.0;
                smax = dsq[d] > smax ? dsq[d] : smax;
            }
            kept = 0;
            for (size_t t = 0; t < nb; t++) {
                const double *dt = dbuf + t * m;
                if (r[(t0 + t) * stride] == 0.0)
                    continue;
                if (rn) {
                    double e = rn[t0 + t] + dc;
                    if (r[(t0 + t) * stride] * e * e * smax * PRUNE_BOUND_SLACK <= 1.0)
                        continue;
                }
                if (!(weighted_sq(dt, dsq, m) > 1.0))
                    continue;
                if (kept != t)
                    memcpy(dbuf + kept * m, dt, m * sizeof *dt);
                kept++;
            }
        }
        if (kept > 0)
            AFFECT_BLAS(cblas_dsyrk(CblasRowMajor, CblasUpper, CblasTrans, (int)m, (int)kept, 1.0,
                                    dbuf, (int)m, 1.0, S, (int)m));
    }
}

/* Turns statistics (n, s1 around c, S around c) into the mean and covariance (+ reg) of
 * component k, in place of c. */
static void moments(affect_hmm *h, size_t k, double n, const double *s1, const double *S)
{
    uint32_t m = h->cfg.dim;
    double *mu = h->means + k * m, *cov = h->covs + k * h->cs, reg = h->cfg.reg;
    for (uint32_t d = 0; d < m; d++)
        mu[d] += s1[d] / n;
    if (h->cfg.cov == AFFECT_HMM_FULL) {
        for (uint32_t r = 0; r < m; r++)
            for (uint32_t s = r; s < m; s++) {
                double v = S[(size_t)r * m + s] / n - (s1[r] / n) * (s1[s] / n);
                cov[(size_t)r * m + s] = v;
                cov[(size_t)s * m + r] = v;
            }
        for (uint32_t d = 0; d < m; d++)
            cov[(size_t)d * m + d] += reg;
    } else {
        for (uint32_t d = 0; d < m; d++) {
            double v = S[d] / n - (s1[d] / n) * (s1[d] / n);
            cov[d] = (v > 0 ? v : 0.0) + reg;
        }
    }
}

/* The covariance of state i's mixture over the components with frac[j] > 0 (fractions summing
 * to 1): Σ_j f_j (Σ_j + (μ_j − μ̄)(μ_j − μ̄)ᵀ), into out (cs doubles). */
static void pooled_cov(const affect_hmm *h, uint32_t i, const double *frac, double *mbar,
                       double *out)
{
    uint32_t M = h->cfg.n_mix, m = h->cfg.dim;
    bool full = h->cfg.cov == AFFECT_HMM_FULL;
    memset(mbar, 0, m * sizeof(double));
    memset(out, 0, h->cs * sizeof(double));
    for (uint32_t j = 0; j < M; j++) {
        if (!(frac[j] > 0))
            continue;
        const double *mu = h->means + ((size_t)i * M + j) * m;
        for (uint32_t d = 0; d < m; d++)
            mbar[d] += frac[j] * mu[d];
    }
    for (uint32_t j = 0; j < M; j++) {
        if (!(frac[j] > 0))
            continue;
        size_t k = (size_t)i * M + j;
        const double *mu = h->means + k * m, *cov = h->covs + k * h->cs;
        if (full) {
            for (uint32_t r = 0; r < m; r++)
                for (uint32_t s = 0; s < m; s++)
                    out[(size_t)r * m + s] +=
                        frac[j] * (cov[(size_t)r * m + s] + (mu[r] - mbar[r]) * (mu[s] - mbar[s]));
        } else {
            for (uint32_t d = 0; d < m; d++)
                out[d] += frac[j] * (cov[d] + (mu[d] - mbar[d]) * (mu[d] - mbar[d]));
        }
    }
}

/* Factors component (i, j) after re-estimation: on failure adds more to the diagonal once. */
static affect_status train_factor(affect_hmm *h, uint32_t i, uint32_t j, affect_error *err)
{
    size_t k = (size_t)i * h->cfg.n_mix + j;
    uint32_t m = h->cfg.dim;
    bool full = h->cfg.cov == AFFECT_HMM_FULL;
    double *cov = h->covs + k * h->cs;
    for (size_t e = 0; e < h->cs; e++)
        if (!isfinite(cov[e]))
            return affect_fail(err, AFFECT_ERR_RANGE,
                               "the covariance of state %u, mixture %u is not finite (are the "
                               "observations too large?)",
                               i, j);
    for (uint32_t d = 0; d < m; d++)
        if (!isfinite(h->means[k * m + d]))
            return affect_fail(err, AFFECT_ERR_RANGE,
                               "the mean of state %u, mixture %u is not finite (are the "
                               "observations too large?)",
                               i, j);
    if (factor_one(h, k) == 0)
        return AFFECT_OK;
    double trace = 0.0;
    for (uint32_t d = 0; d < m; d++)
        trace += fabs(full ? cov[(size_t)d * m + d] : cov[d]);
    double extra = RETRY_REG_FACTOR * h->cfg.reg + RETRY_REG_RELATIVE * trace / m;
    for (uint32_t d = 0; d < m; d++)
        cov[full ? (size_t)d * m + d : d] += extra;
    if (factor_one(h, k) == 0)
        return AFFECT_OK;
    return affect_fail(err, AFFECT_ERR_RANGE,
                       "the covariance of state %u, mixture %u is not positive definite even "
                       "with %g added to its diagonal (raise reg)",
                       i, j, h->cfg.reg + extra);
}

/* Initial parameters: equal segments, k-means per state, the fixed transition structure. */
static affect_status init_params(affect_hmm *h, const affect_hmm_seq *seqs, uint32_t n_seqs,
                                 train_ws *w, affect_error *err)
{
    const affect_hmm_config *cfg = &h->cfg;
    uint32_t N = cfg->n_states, M = cfg->n_mix, m = cfg->dim;
    affect_rng rng;
    affect_rng_seed(&rng, cfg->seed);
    double mean_len = 0.0;
    for (uint32_t s = 0; s < n_seqs; s++)
        mean_len += (double)seqs[s].n_frames / N;
    mean_len /= n_seqs;

    for (uint32_t i = 0; i < N; i++) {
        if (affect_monitor_stopped(h->mon))
            return affect_monitor_check(h->mon, err);
        size_t P = 0;
        for (uint32_t s = 0; s < n_seqs; s++) {
            uint64_t T = seqs[s].n_frames;
            uint64_t lo = (uint64_t)i * T / N, hi = (uint64_t)(i + 1) * T / N;
            for (uint64_t t = lo; t < hi; t++)
                w->fp[P++] = seqs[s].x + t * m;
        }
        kmeans(w, P, M, m, &rng);
        /* members' means, covariances and fractions */
        bool any_empty = false;
        for (uint32_t j = 0; j < M; j++) {
            size_t k = (size_t)i * M + j, nk = 0;
            for (size_t p = 0; p < P; p++)
                nk += w->asg[p] == j;
            double *mu = h->means + k * m;
            w->frac[j] = (double)nk / (double)P;
            h->weights[k] = w->frac[j];
            if (nk == 0) {
                memcpy(mu, w->cen + (size_t)j * m, m * sizeof(double));
                any_empty = true;
                continue;
            }
            /* the members' pointers, their mean, then the ML covariance (+ reg) around it */
            size_t q = 0;
            for (size_t p = 0; p < P; p++)
                if (w->asg[p] == j)
                    w->mp[q++] = w->fp[p];
            memset(mu, 0, m * sizeof(double));
            for (size_t e = 0; e < q; e++)
                for (uint32_t d = 0; d < m; d++)
                    mu[d] += w->mp[e][d];
            for (uint32_t d = 0; d < m; d++)
                mu[d] /= (double)nk;
            double n = 0.0;
            memset(w->s1, 0, m * sizeof(double));
            memset(w->S, 0, h->cs * sizeof(double));
            scatter(h, w->mp, NULL, q, NULL, 0, mu, &n, w->s1, w->S, w->fb.dbuf, NULL, NULL, 0.0);
            moments(h, k, n, w->s1, w->S);
        }
        if (any_empty) {
            pooled_cov(h, i, w->frac, w->mbar, w->pool);
            for (uint32_t j = 0; j < M; j++)
                if (w->frac[j] == 0.0) {
                    double *cov = h->covs + ((size_t)i * M + j) * h->cs;
                    memcpy(cov, w->pool, h->cs * sizeof(double));
                }
        }
        for (uint32_t j = 0; j < M; j++) {
            affect_status st = train_factor(h, i, j, err);
            if (st)
                return st;
        }
    }

    /* transitions: a_ii = 1 − 1/L (≥ 0.5), the rest spread over the allowed destinations */
    double self = 1.0 - 1.0 / mean_len;
    if (self < MIN_INIT_SELF)
        self = MIN_INIT_SELF;
    for (uint32_t i = 0; i < N; i++) {
        uint32_t others = 0;
        for (uint32_t l = 0; l < N; l++)
            others += l != i && allowed(cfg, i, l);
        for (uint32_t l = 0; l < N; l++) {
            double a;
            if (l == i)
                a = others ? self : 1.0;
            else
                a = allowed(cfg, i, l) ? (1.0 - self) / others : 0.0;
            h->trans[(size_t)i * N + l] = a;
        }
    }
    for (uint32_t i = 0; i < N; i++)
        h->start[i] = cfg->learn_start ? 1.0 / N : (i == 0 ? 1.0 : 0.0);
    refresh_logs(h);
    return AFFECT_OK;
}

/* ‖a − b‖ over m coordinates, with four partial sums (fixed order). */
static double dist(const double *a, const double *b, size_t m)
{
    return sqrt(dist2(a, b, (uint32_t)m));
}

/* Adds one sequence's posteriors (in w->rho) to the statistics, centred on the current means.
 * When scatter prunes, the frames' distances to the centre of the component means go to w->rn
 * first, for its quick test. */
static void accumulate(const affect_hmm *h, const double *x, uint32_t T, train_ws *w)
{
    size_t K = (size_t)h->cfg.n_states * h->cfg.n_mix, m = h->cfg.dim;
    bool quick = h->cfg.cov == AFFECT_HMM_FULL && m >= PRUNE_MIN_DIM;
    if (quick)
        for (uint32_t t = 0; t < T; t++)
            w->rn[t] = dist(x + (size_t)t * m, h->centre, m);
    for (size_t k = 0; k < K; k++)
        scatter(h, NULL, x, T, w->rho + k, K, h->means + k * m, &w->n[k], w->s1 + k * m,
                w->S + k * h->cs, w->fb.dbuf, w->dsq, quick ? w->rn : NULL,
                quick ? dist(h->means + k * m, h->centre, m) : 0.0);
}

/* The M-step: new parameters from the statistics of one pass over the sequences. */
static affect_status mstep(affect_hmm *h, const affect_hmm_seq *seqs, uint64_t frames, train_ws *w,
                           uint32_t *reseeded, affect_error *err)
{
    const affect_hmm_config *cfg = &h->cfg;
    uint32_t N = cfg->n_states, M = cfg->n_mix, m = cfg->dim;
    double empty = EMPTY_FRACTION * (double)frames;

    for (uint32_t i = 0; i < N; i++) {
        const double *x = w->xi + (size_t)i * N;
        double row = 0.0;
        for (uint32_t l = 0; l < N; l++)
            if (allowed(cfg, i, l))
                row += x[l];
        if (!(row >= empty && row > 0))
            continue; /* a state never left: keep its row */
        for (uint32_t l = 0; l < N; l++)
            h->trans[(size_t)i * N + l] = allowed(cfg, i, l) ? x[l] / row : 0.0;
    }
    if (cfg->learn_start) {
        double total = 0.0;
        for (uint32_t i = 0; i < N; i++)
            total += w->g0[i];
        if (total > 0)
            for (uint32_t i = 0; i < N; i++)
                h->start[i] = w->g0[i] / total;
    }

    for (uint32_t i = 0; i < N; i++) {
        const double *n = w->n + (size_t)i * M;
        double ni = 0.0, full_ni = 0.0;
        uint32_t filled = 0;
        for (uint32_t j = 0; j < M; j++) {
            ni += n[j];
            if (n[j] >= empty && n[j] > 0) {
                full_ni += n[j];
                filled++;
            }
        }
        if (filled == 0)
            continue; /* a state without frames keeps its output density */
        for (uint32_t j = 0; j < M; j++) {
            size_t k = (size_t)i * M + j;
            bool has = n[j] >= empty && n[j] > 0;
            w->frac[j] = has ? n[j] / full_ni : 0.0;
            h->weights[k] = n[j] / ni;
            if (has)
                moments(h, k, n[j], w->s1 + k * m, w->S + k * h->cs);
        }
        if (filled < M) {
            pooled_cov(h, i, w->frac, w->mbar, w->pool);
            uint32_t next = 0;
            double total = 0.0;
            for (uint32_t j = 0; j < M; j++) {
                size_t k = (size_t)i * M + j;
                if (w->frac[j] == 0.0 && next < w->tr.count[i]) {
                    const worst_frame *f = w->tr.w + (size_t)i * M + next++;
                    memcpy(h->means + k * m, seqs[f->seq].x + (size_t)f->t * m, m * sizeof(double));
                    memcpy(h->covs + k * h->cs, w->pool, h->cs * sizeof(double));
                    h->weights[k] = 1.0 / (ni > 1.0 ? ni : 1.0);
                    (*reseeded)++;
                }
                total += h->weights[(size_t)i * M + j];
            }
            for (uint32_t j = 0; j < M; j++)
                h->weights[(size_t)i * M + j] /= total;
        }
        for (uint32_t j = 0; j < M; j++) {
            affect_status st = train_factor(h, i, j, err);
            if (st)
                return st;
        }
    }
    refresh_logs(h);
    return AFFECT_OK;
}

/* Checks the training sequences; the total frames and longest sequence into *frames, *max_t. */
static affect_status check_seqs(const affect_hmm_config *cfg, const affect_hmm_seq *seqs,
                                uint32_t n, uint64_t *frames, uint32_t *max_t, affect_error *err)
{
    uint32_t N = cfg->n_states, m = cfg->dim;
    *frames = 0;
    *max_t = 0;
    for (uint32_t s = 0; s < n; s++) {
        uint32_t T = seqs[s].n_frames;
        if (T < N)
            return affect_fail(err, AFFECT_ERR_INVALID,
                               "sequence %u has %u %s, fewer than the %u %s", s, T,
                               plural(T, "frame", "frames"), N, plural(N, "state", "states"));
        if (!seqs[s].x)
            return affect_fail(err, AFFECT_ERR_INVALID, "sequence %u has no data", s);
        const double *x = seqs[s].x;
        for (uint32_t t = 0; t < T; t++)
            for (uint32_t d = 0; d < m; d++)
                if (!isfinite(x[(size_t)t * m + d]))
                    return affect_fail(err, AFFECT_ERR_INVALID,
                                       "sequence %u, frame %u: value %u is not finite", s, t, d);
        *frames += T;
        if (T > *max_t)
            *max_t = T;
    }
    return AFFECT_OK;
}

affect_status affect_hmm_train(const affect_hmm_config *cfg, const affect_hmm_seq *seqs, uint32_t n,
                               affect_hmm **out, affect_error *err)
{
    *out = NULL;
    const char *msg = affect_hmm_config_check(cfg);
    if (msg)
        return affect_fail(err, AFFECT_ERR_INVALID, "%s", msg);
    if (n == 0 || !seqs)
        return affect_fail(err, AFFECT_ERR_INVALID, "no sequences");
    uint64_t frames;
    uint32_t max_t;
    affect_status st = check_seqs(cfg, seqs, n, &frames, &max_t, err);
    if (st)
        return st;
    if (frames > SIZE_MAX)
        return affect_nomem(err);

    affect_hmm *h = model_alloc(cfg);
    if (!h)
        return affect_nomem(err);
    void *ws = NULL;
    size_t N = cfg->n_states, M = cfg->n_mix, m = cfg->dim, K = N * M, F = (size_t)frames;
    size_t km, kc, tk;
    train_ws w;
    affect_ws_part parts[FB_PARTS + 20];
    size_t np = 0;
    if (!affect_mul_size(K, m, &km) || !affect_mul_size(K, h->cs, &kc) ||
        !affect_mul_size(max_t, K, &tk)) {
        st = affect_nomem(err);
        goto cleanup;
    }
    fb_parts(h, max_t, &w.fb, parts, &np);
    parts[np++] = (affect_ws_part){(void **)&w.rho, tk, sizeof(double)};
    parts[np++] = (affect_ws_part){(void **)&w.n, K, sizeof(double)};
    parts[np++] = (affect_ws_part){(void **)&w.s1, km, sizeof(double)};
    parts[np++] = (affect_ws_part){(void **)&w.S, kc, sizeof(double)};
    parts[np++] = (affect_ws_part){(void **)&w.xi, N * N, sizeof(double)};
    parts[np++] = (affect_ws_part){(void **)&w.g0, N, sizeof(double)};
    parts[np++] = (affect_ws_part){(void **)&w.tr.w, K, sizeof(worst_frame)};
    parts[np++] = (affect_ws_part){(void **)&w.tr.count, N, sizeof(uint32_t)};
    parts[np++] = (affect_ws_part){(void **)&w.fp, F, sizeof(const double *)};
    parts[np++] = (affect_ws_part){(void **)&w.mp, F, sizeof(const double *)};
    parts[np++] = (affect_ws_part){(void **)&w.asg, F, sizeof(uint32_t)};
    parts[np++] = (affect_ws_part){(void **)&w.d2, F, sizeof(double)};
    parts[np++] = (affect_ws_part){(void **)&w.cen, M * m, sizeof(double)};
    parts[np++] = (affect_ws_part){(void **)&w.sums, M * m, sizeof(double)};
    parts[np++] = (affect_ws_part){(void **)&w.cnt, M, sizeof(size_t)};
    parts[np++] = (affect_ws_part){(void **)&w.frac, M, sizeof(double)};
    parts[np++] = (affect_ws_part){(void **)&w.mbar, m, sizeof(double)};
    parts[np++] = (affect_ws_part){(void **)&w.pool, h->cs, sizeof(double)};
    parts[np++] = (affect_ws_part){(void **)&w.dsq, m, sizeof(double)};
    parts[np++] = (affect_ws_part){(void **)&w.rn, max_t, sizeof(double)};
    ws = affect_ws_alloc(parts, np);
    if (!ws) {
        st = affect_nomem(err);
        goto cleanup;
    }

    h->mon = cfg->monitor;
    if ((st = init_params(h, seqs, n, &w, err)))
        goto cleanup;
    uint32_t it = 0, reseeded = 0;
    bool converged = false;
    for (;;) {
        bool stats = it < cfg->max_iter;
        if (stats) {
            memset(w.n, 0, K * sizeof(double));
            memset(w.s1, 0, km * sizeof(double));
            memset(w.S, 0, kc * sizeof(double));
            memset(w.xi, 0, N * N * sizeof(double));
            memset(w.g0, 0, N * sizeof(double));
            memset(w.tr.count, 0, N * sizeof(uint32_t));
        }
        double total = 0.0;
        affect_monitor_report(h->mon, "Baum-Welch iterations", it, cfg->max_iter);
        for (uint32_t s = 0; s < n; s++) {
            if ((st = affect_monitor_check(h->mon, err)))
                goto cleanup;
            double L;
            if (stats) {
                forward_backward(h, seqs[s].x, seqs[s].n_frames, &w.fb, w.rho, w.xi, w.g0, &w.tr, s,
                                 h->mon, &L);
                if (isfinite(L))
                    accumulate(h, seqs[s].x, seqs[s].n_frames, &w);
            } else {
                L = forward_loglik(h, seqs[s].x, seqs[s].n_frames, w.fb.cbuf, w.fb.dbuf, w.fb.lb,
                                   w.fb.v[0], w.fb.v[1], w.fb.v[2], h->mon);
            }
            if ((st = affect_monitor_check(h->mon, err)))
                goto cleanup;
            if (!isfinite(L)) {
                st = affect_fail(err, AFFECT_ERR_RANGE,
                                 "sequence %u has probability 0 under the model after %u "
                                 "iterations",
                                 s, it);
                goto cleanup;
            }
            total += L;
        }
        h->loglik[it] = total;
        if (it > 0 && fabs(total - h->loglik[it - 1]) <= cfg->tol * fabs(h->loglik[it - 1])) {
            converged = true;
            break;
        }
        if (!stats)
            break;
        if ((st = mstep(h, seqs, frames, &w, &reseeded, err)))
            goto cleanup;
        it++;
    }
    affect_monitor_report(h->mon, "Baum-Welch iterations", cfg->max_iter, cfg->max_iter);
    h->mon = NULL;
    h->has_report = true;
    h->iterations = it;
    h->converged = converged;
    h->reseeded = reseeded;
    h->n_sequences = n;
    h->n_frames = frames;
    *out = h;
    h = NULL;
cleanup:
    affect_free(ws);
    affect_hmm_free(h);
    return st;
}
