/*
 * bench_hmm.c — the GMM-HMM engine (affect/hmm.h) on one core: scoring throughput
 * (affect_hmm_loglik, frames/s) next to the compute bound of its Gaussian evaluations (the
 * OpenBLAS triangular solves), seconds per Baum–Welch iteration, and the peak memory of
 * training on 400,000 frames × 63 dimensions. It also writes the data and models to files that
 * tests/bench/hmm_peer.py reads, so that pomegranate is timed on exactly the same numbers.
 *
 * Usage:
 *     bench_hmm [--out DIR] [--no-memory]
 *     bash tests/bench/run.sh            # Release build, pinned to one core, runs the peer too
 * --out DIR writes DIR/hmm-m15.bin and DIR/hmm-m63.bin for the peer (the directory must
 * exist); --no-memory skips the peak-memory children. Run it with OPENBLAS_NUM_THREADS=1 (run.sh
 * does): the program prints OpenBLAS's configuration and thread count, and warns when that
 * count is not 1.
 *
 * Configuration (the issue's): N = 7 states, M = 4 mixtures, full covariances, ergodic, π fixed
 * to the first state, for m = 15 and m = 63 dimensions. Training uses reg = 0 and tol = 0, so
 * that Baum–Welch is the plain maximum-likelihood update pomegranate does (its M-step adds
 * nothing to the diagonal) and never stops early; the cost of an iteration does not depend on
 * either. Data: a random GMM-HMM drawn from a fixed seed (MODEL_SEED; a_ii = 0.95 and the rest of
 * each row random, weights uniform in [0.5, 1.5] normalised, means N(0, 2²) per coordinate,
 * Σ = B Bᵀ/m + 0.2 I with B standard normal), then 200 sequences of 500 frames sampled from it
 * (DATA_SEED): each starts in state 0, picks a component by its weight, draws x = μ + L z.
 *
 * Kernels, each a pass over the 100,000 frames (every sequence once):
 *     trsm bound   for each sequence and each of the N × M components: the centred frames
 *                  D = X − μ (T × m), one cblas_dtrsm against the component's Cholesky factor
 *                  (Y = D L^{-T}, what the engine's densities do) and the row norms ‖y_t‖²:
 *                  the arithmetic any Gaussian evaluation by triangular solves needs;
 *     centre+norm  the same without the dtrsm (the bound's non-BLAS part; the bound minus it
 *                  is the time OpenBLAS spends in the solves);
 *     gemm alt.    pomegranate's formulation: the same ‖y_t‖² from precomputed inverse
 *                  factors — per sequence one cblas_dgemm of X (T × m) by
 *                  W = [L_1^{-T} … L_{NM}^{-T}] (m × N·M·m), then ‖x_t W_k − μ_k W_k‖² per
 *                  component. Twice the flops of the solves, but dgemm runs closer to the core's
 *                  peak; without centring it cancels (x W − μ W). Before timing, its values are
 *                  compared with the bound's;
 *     panel gemm   the BLAS part of the engine's method (hmm.c, densities): the inverse
 *                  factors cut into panels of PANEL_ROWS rows, each panel of all N·M
 *                  components one (N·M·rows) × r1 matrix that skips the zero upper triangle,
 *                  and per 128 frames one cblas_dgemm per panel; only the products, no
 *                  centring, no sums of squares: the engine's own compute bound;
 *     score        affect_hmm_loglik of every sequence under the generating model (built with
 *                  affect_hmm_from_params), everything included: checks, workspace, densities,
 *                  log-sum-exp, forward recursion.
 * Training: affect_hmm_train on the 200 sequences with max_iter = 0 (k-means initialisation and
 * one scoring pass for the report) and max_iter = 2 (the same plus two E+M iterations); a
 * Baum–Welch iteration is (t(2) − t(0)) / 2 of the median times. The log-likelihoods of the
 * report (L0 after initialisation, L1, L2) go to the peer file with the initial model, so the
 * peer can start from the same parameters and check that it computes the same iterations.
 *
 * How it measures: as bench_import — one untimed warm-up pass, then N passes per run (N chosen
 * so that a run takes about a second; training: one call per run), 5 runs, the median run
 * reported with the fastest and slowest; clock_gettime(CLOCK_MONOTONIC).
 * Peak memory: a child process (fork, before the parent holds any data) generates 400,000
 * frames × 63 (800 sequences of 500, or 4 sequences of 100,000 for the long-sequence case) and
 * trains on them with max_iter = 1 (the training workspace is allocated once, before the
 * initialisation, so later iterations do not raise the peak) and sends its getrusage
 * ru_maxrss to the parent through a pipe. A child that only generates the data gives the data's
 * own share, and one that generates a single short sequence the process's baseline.
 * Output: a table per dimension, then one line per metric for scripts:
 *     BENCH <metric> <value> <unit>
 * Exit status 1 if a computation fails.
 *
 * Peer file (little-endian; written only on a little-endian host): the 8 bytes "AFHMMBN1",
 * 8 uint32 (N, M, m, sequences, frames per sequence, 0, 0, 0), then float64 arrays:
 * 8 results (score frames/s, trsm bound frames/s, seconds per Baum–Welch iteration, L0, L1, L2,
 * total log-likelihood of the data under the generating model, 0), the generating model and
 * the initial model (each: start N, transitions N × N, weights N × M, means N × M × m,
 * covariances N × M × m × m), the per-sequence log-likelihoods under the generating model, and
 * the data (sequences × frames × m).
 */
#define _POSIX_C_SOURCE 200809L

#include "affect/hmm.h"
#include "util/rng.h"

#include <cblas.h>
#include <lapacke.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/time.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "benchutil.h"

#define N_STATES 7u
#define N_MIX 4u
#define SEQ_FRAMES 500u
#define N_SEQS 200u
#define MEM_FRAMES 400000u
#define MEM_DIM 63u
#define LONG_SEQ_FRAMES 100000u
#define SELF_TRANSITION 0.95
#define MODEL_SEED 20261121u
#define DATA_SEED 7u
#define PANEL_ROWS 8u     /* as TRI_ROWS in hmm.c */
#define PANEL_FRAMES 128u /* as SUB_FRAMES in hmm.c */
#define BOUND_GOAL 0.5    /* scoring at ≥ 50 % of the trsm bound */
#define MEMORY_GOAL_MB 1000.0

/* A GMM-HMM's parameters (row-major, the shapes of affect/hmm.h) and Cholesky factors. */
typedef struct params {
    uint32_t N, M, m;
    double *start, *trans, *weights, *means, *covs, *chol;
} params;

typedef struct dataset {
    uint32_t n_seqs, T, m;
    double *x; /* n_seqs × T × m */
    affect_hmm_seq *seqs;
} dataset;

/* What the kernels need. */
typedef struct bench_ctx {
    const params *p;
    const dataset *d;
    const affect_hmm *h;   /* the generating model */
    double *buf;           /* T × m */
    double *out;           /* N × M × T */
    double *winv;          /* m × N·M·m: the inverse factors L_k^{-T} side by side (gemm alt.) */
    double *mw;            /* N·M × m: μ_k L_k^{-T} */
    double *g;             /* T × N·M·m */
    double *panels;        /* the engine's panels of L_k^{-1} (panel gemm) */
    double *ll;            /* per-sequence log-likelihoods */
    affect_hmm_config cfg; /* training */
} bench_ctx;

/* Values the timed loops write so the compiler cannot drop their work. */
static volatile double g_sink;

/* ---- the random GMM-HMM and its data ---- */

static void free_params(params *p)
{
    free(p->start);
    free(p->trans);
    free(p->weights);
    free(p->means);
    free(p->covs);
    free(p->chol);
}

/* Draws the model described in the file header; 1 on failure. */
static int make_params(uint32_t m, uint64_t seed, params *p)
{
    uint32_t N = N_STATES, M = N_MIX, K = N * M;
    memset(p, 0, sizeof *p);
    p->N = N;
    p->M = M;
    p->m = m;
    p->start = calloc(N, sizeof(double));
    p->trans = calloc((size_t)N * N, sizeof(double));
    p->weights = calloc(K, sizeof(double));
    p->means = calloc((size_t)K * m, sizeof(double));
    p->covs = calloc((size_t)K * m * m, sizeof(double));
    p->chol = calloc((size_t)K * m * m, sizeof(double));
    double *b = calloc((size_t)m * m, sizeof(double));
    if (!p->start || !p->trans || !p->weights || !p->means || !p->covs || !p->chol || !b) {
        free(b);
        fprintf(stderr, "out of memory\n");
        return 1;
    }
    affect_rng rng;
    affect_rng_seed(&rng, seed);
    p->start[0] = 1.0;
    for (uint32_t i = 0; i < N; i++) {
        double *row = p->trans + (size_t)i * N, rest = 0.0;
        for (uint32_t l = 0; l < N; l++)
            if (l != i)
                rest += row[l] = affect_rng_range(&rng, 0.2, 1.0);
        for (uint32_t l = 0; l < N; l++)
            row[l] = l == i ? SELF_TRANSITION : (1.0 - SELF_TRANSITION) * row[l] / rest;
        double sum = 0.0;
        for (uint32_t j = 0; j < M; j++)
            sum += p->weights[(size_t)i * M + j] = affect_rng_range(&rng, 0.5, 1.5);
        for (uint32_t j = 0; j < M; j++)
            p->weights[(size_t)i * M + j] /= sum;
    }
    for (size_t e = 0; e < (size_t)K * m; e++)
        p->means[e] = 2.0 * affect_rng_normal(&rng);
    for (uint32_t k = 0; k < K; k++) {
        double *cov = p->covs + (size_t)k * m * m, *l = p->chol + (size_t)k * m * m;
        for (size_t e = 0; e < (size_t)m * m; e++)
            b[e] = affect_rng_normal(&rng);
        cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasTrans, (int)m, (int)m, (int)m, 1.0 / m, b,
                    (int)m, b, (int)m, 0.0, cov, (int)m);
        for (uint32_t r = 0; r < m; r++) {
            cov[(size_t)r * m + r] += 0.2;
            for (uint32_t s = 0; s < r; s++) /* exactly symmetric */
                cov[(size_t)r * m + s] = cov[(size_t)s * m + r];
        }
        memcpy(l, cov, (size_t)m * m * sizeof(double));
        if (LAPACKE_dpotrf(LAPACK_ROW_MAJOR, 'L', (lapack_int)m, l, (lapack_int)m) != 0) {
            free(b);
            fprintf(stderr, "component %u: covariance not positive definite\n", k);
            return 1;
        }
        for (uint32_t r = 0; r < m; r++)
            for (uint32_t s = r + 1; s < m; s++)
                l[(size_t)r * m + s] = 0.0;
    }
    free(b);
    return 0;
}

static uint32_t draw(affect_rng *rng, const double *prob, uint32_t n)
{
    double u = affect_rng_uniform(rng), cum = 0.0;
    for (uint32_t i = 0; i < n; i++) {
        cum += prob[i];
        if (u < cum)
            return i;
    }
    return n - 1;
}

static void free_data(dataset *d)
{
    free(d->x);
    free(d->seqs);
}

/* n_seqs sequences of T frames sampled from p; 1 on failure. */
static int make_data(const params *p, uint32_t n_seqs, uint32_t T, uint64_t seed, dataset *d)
{
    uint32_t m = p->m, M = p->M;
    d->n_seqs = n_seqs;
    d->T = T;
    d->m = m;
    d->x = malloc((size_t)n_seqs * T * m * sizeof(double));
    d->seqs = malloc(n_seqs * sizeof *d->seqs);
    double *z = malloc(m * sizeof(double));
    if (!d->x || !d->seqs || !z) {
        free(z);
        fprintf(stderr, "out of memory\n");
        return 1;
    }
    affect_rng rng;
    affect_rng_seed(&rng, seed);
    for (uint32_t s = 0; s < n_seqs; s++) {
        uint32_t state = draw(&rng, p->start, p->N);
        double *xs = d->x + (size_t)s * T * m;
        d->seqs[s].x = xs;
        d->seqs[s].n_frames = T;
        for (uint32_t t = 0; t < T; t++) {
            size_t k = (size_t)state * M + draw(&rng, p->weights + (size_t)state * M, M);
            const double *mu = p->means + k * m, *l = p->chol + k * m * m;
            double *xt = xs + (size_t)t * m;
            for (uint32_t e = 0; e < m; e++)
                z[e] = affect_rng_normal(&rng);
            for (uint32_t r = 0; r < m; r++) {
                double v = mu[r];
                for (uint32_t e = 0; e <= r; e++)
                    v += l[(size_t)r * m + e] * z[e];
                xt[r] = v;
            }
            state = draw(&rng, p->trans + (size_t)state * p->N, p->N);
        }
    }
    free(z);
    return 0;
}

/* ---- kernels: one pass over the data set; non-zero return = failure ---- */

typedef int (*kernel_fn)(bench_ctx *c);

static double sumsq(const double *v, uint32_t n)
{
    double s0 = 0, s1 = 0, s2 = 0, s3 = 0;
    uint32_t d = 0;
    for (; d + 4 <= n; d += 4) {
        s0 += v[d] * v[d];
        s1 += v[d + 1] * v[d + 1];
        s2 += v[d + 2] * v[d + 2];
        s3 += v[d + 3] * v[d + 3];
    }
    for (; d < n; d++)
        s0 += v[d] * v[d];
    return (s0 + s1) + (s2 + s3);
}

/* The bound (solve = true) or its non-BLAS part (solve = false). */
static int bound_pass(bench_ctx *c, bool solve)
{
    const params *p = c->p;
    uint32_t T = c->d->T, m = p->m, K = p->N * p->M;
    double acc = 0.0;
    for (uint32_t s = 0; s < c->d->n_seqs; s++) {
        const double *x = c->d->seqs[s].x;
        for (uint32_t k = 0; k < K; k++) {
            const double *mu = p->means + (size_t)k * m;
            for (uint32_t t = 0; t < T; t++) {
                const double *xt = x + (size_t)t * m;
                double *dt = c->buf + (size_t)t * m;
                for (uint32_t e = 0; e < m; e++)
                    dt[e] = xt[e] - mu[e];
            }
            if (solve)
                cblas_dtrsm(CblasRowMajor, CblasRight, CblasLower, CblasTrans, CblasNonUnit, (int)T,
                            (int)m, 1.0, p->chol + (size_t)k * m * m, (int)m, c->buf, (int)m);
            double *o = c->out + (size_t)k * T;
            for (uint32_t t = 0; t < T; t++)
                o[t] = sumsq(c->buf + (size_t)t * m, m);
        }
        acc += c->out[s % ((size_t)K * T)];
    }
    g_sink += acc;
    return 0;
}

static int k_bound(bench_ctx *c)
{
    return bound_pass(c, true);
}

static int k_centre(bench_ctx *c)
{
    return bound_pass(c, false);
}

/* W and μ_k W_k for the gemm alternative; 1 on failure. */
static int make_inverse(bench_ctx *c)
{
    const params *p = c->p;
    uint32_t m = p->m, K = p->N * p->M;
    size_t KM = (size_t)K * m;
    c->winv = malloc(m * KM * sizeof(double));
    c->mw = malloc(KM * sizeof(double));
    c->g = malloc((size_t)c->d->T * KM * sizeof(double));
    double *inv = malloc((size_t)m * m * sizeof(double));
    if (!c->winv || !c->mw || !c->g || !inv) {
        free(inv);
        fprintf(stderr, "out of memory\n");
        return 1;
    }
    for (uint32_t k = 0; k < K; k++) {
        memset(inv, 0, (size_t)m * m * sizeof(double));
        for (uint32_t e = 0; e < m; e++)
            inv[(size_t)e * m + e] = 1.0;
        cblas_dtrsm(CblasRowMajor, CblasRight, CblasLower, CblasTrans, CblasNonUnit, (int)m, (int)m,
                    1.0, p->chol + (size_t)k * m * m, (int)m, inv, (int)m); /* L^{-T} */
        const double *mu = p->means + (size_t)k * m;
        for (uint32_t col = 0; col < m; col++) {
            double v = 0.0;
            for (uint32_t r = 0; r < m; r++) {
                c->winv[(size_t)r * KM + (size_t)k * m + col] = inv[(size_t)r * m + col];
                v += mu[r] * inv[(size_t)r * m + col];
            }
            c->mw[(size_t)k * m + col] = v;
        }
    }
    free(inv);
    /* the panels: rows r0 .. r1 − 1 of every L_k⁻¹, columns 0 .. r1 − 1, k-major */
    c->panels = malloc((size_t)K * m * m * sizeof(double));
    if (!c->panels) {
        fprintf(stderr, "out of memory\n");
        return 1;
    }
    double *pp = c->panels;
    for (uint32_t r0 = 0; r0 < m; r0 += PANEL_ROWS) {
        uint32_t r1 = m - r0 < PANEL_ROWS ? m : r0 + PANEL_ROWS;
        for (uint32_t k = 0; k < K; k++)
            for (uint32_t row = r0; row < r1; row++)
                for (uint32_t col = 0; col < r1; col++) /* L⁻¹[row][col] = (L^{-T})[col][row] */
                    *pp++ = c->winv[(size_t)col * KM + (size_t)k * m + row];
    }
    return 0;
}

/* Sequence s's ‖y_t‖² by the gemm alternative into out (N·M × T). */
static void gemm_seq(bench_ctx *c, uint32_t s, double *out)
{
    uint32_t T = c->d->T, m = c->p->m, K = c->p->N * c->p->M;
    size_t KM = (size_t)K * m;
    cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, (int)T, (int)KM, (int)m, 1.0,
                c->d->seqs[s].x, (int)m, c->winv, (int)KM, 0.0, c->g, (int)KM);
    for (uint32_t t = 0; t < T; t++) {
        const double *gt = c->g + (size_t)t * KM;
        for (uint32_t k = 0; k < K; k++) {
            const double *v = gt + (size_t)k * m, *w = c->mw + (size_t)k * m;
            double s0 = 0, s1 = 0, s2 = 0, s3 = 0;
            uint32_t e = 0;
            for (; e + 4 <= m; e += 4) {
                double d0 = v[e] - w[e], d1 = v[e + 1] - w[e + 1], d2 = v[e + 2] - w[e + 2],
                       d3 = v[e + 3] - w[e + 3];
                s0 += d0 * d0;
                s1 += d1 * d1;
                s2 += d2 * d2;
                s3 += d3 * d3;
            }
            for (; e < m; e++)
                s0 += (v[e] - w[e]) * (v[e] - w[e]);
            out[(size_t)k * T + t] = (s0 + s1) + (s2 + s3);
        }
    }
}

/* The panel products of the engine's densities (hmm.c), without anything else. */
static int k_panel(bench_ctx *c)
{
    uint32_t T = c->d->T, m = c->p->m, K = c->p->N * c->p->M;
    for (uint32_t s = 0; s < c->d->n_seqs; s++) {
        const double *x = c->d->seqs[s].x;
        for (uint32_t t0 = 0; t0 < T; t0 += PANEL_FRAMES) {
            uint32_t nt = T - t0 < PANEL_FRAMES ? T - t0 : PANEL_FRAMES;
            const double *panel = c->panels;
            for (uint32_t r0 = 0; r0 < m; r0 += PANEL_ROWS) {
                uint32_t r1 = m - r0 < PANEL_ROWS ? m : r0 + PANEL_ROWS, wide = K * (r1 - r0);
                cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasTrans, (int)nt, (int)wide, (int)r1,
                            1.0, x + (size_t)t0 * m, (int)m, panel, (int)r1, 1.0, c->g, (int)wide);
                panel += (size_t)wide * r1;
            }
        }
        g_sink += c->g[s % K];
    }
    return 0;
}

static int k_gemm(bench_ctx *c)
{
    double acc = 0.0;
    uint32_t KT = c->p->N * c->p->M * c->d->T;
    for (uint32_t s = 0; s < c->d->n_seqs; s++) {
        gemm_seq(c, s, c->out);
        acc += c->out[s % KT];
    }
    g_sink += acc;
    return 0;
}

/* The largest relative difference between the gemm alternative's and the solves' ‖y_t‖² over
 * the first sequence. */
static double gemm_check(bench_ctx *c)
{
    uint32_t T = c->d->T, m = c->p->m, K = c->p->N * c->p->M;
    double *ref = malloc((size_t)K * T * sizeof(double));
    if (!ref)
        return INFINITY;
    const double *x = c->d->seqs[0].x;
    for (uint32_t k = 0; k < K; k++) {
        const double *mu = c->p->means + (size_t)k * m;
        for (size_t e = 0; e < (size_t)T * m; e++)
            c->buf[e] = x[e] - mu[e % m];
        cblas_dtrsm(CblasRowMajor, CblasRight, CblasLower, CblasTrans, CblasNonUnit, (int)T, (int)m,
                    1.0, c->p->chol + (size_t)k * m * m, (int)m, c->buf, (int)m);
        for (uint32_t t = 0; t < T; t++)
            ref[(size_t)k * T + t] = sumsq(c->buf + (size_t)t * m, m);
    }
    gemm_seq(c, 0, c->out);
    double worst = 0.0;
    for (size_t e = 0; e < (size_t)K * T; e++) {
        double r = fabs(c->out[e] - ref[e]) / ref[e];
        if (!(r <= worst))
            worst = r;
    }
    free(ref);
    return worst;
}

static int k_score(bench_ctx *c)
{
    double acc = 0.0;
    for (uint32_t s = 0; s < c->d->n_seqs; s++) {
        affect_error err;
        if (affect_hmm_loglik(c->h, c->d->seqs[s].x, c->d->seqs[s].n_frames, &c->ll[s], NULL,
                              &err)) {
            fprintf(stderr, "sequence %u: %s\n", s, err.msg);
            return 1;
        }
        acc += c->ll[s];
    }
    g_sink += acc;
    return isfinite(acc) ? 0 : 1;
}

static int k_train(bench_ctx *c)
{
    affect_hmm *h = NULL;
    affect_error err;
    if (affect_hmm_train(&c->cfg, c->d->seqs, c->d->n_seqs, &h, &err)) {
        fprintf(stderr, "training (max_iter %u): %s\n", c->cfg.max_iter, err.msg);
        return 1;
    }
    affect_hmm_report rep;
    affect_hmm_get_report(h, &rep);
    int rc = rep.iterations == c->cfg.max_iter ? 0 : 1;
    if (rc)
        fprintf(stderr, "training ran %u iterations, not %u\n", rep.iterations, c->cfg.max_iter);
    g_sink += rep.loglik[rep.iterations];
    affect_hmm_free(h);
    return rc;
}

/* One kernel, measured by bench_measure (benchutil.h). */
typedef struct pass_args {
    kernel_fn fn;
    bench_ctx *c;
} pass_args;

static int one_pass(void *arg)
{
    const pass_args *a = arg;
    return a->fn(a->c);
}

static int measure(kernel_fn fn, bench_ctx *c, unsigned repeat, result *r)
{
    pass_args a = {fn, c};
    return bench_measure(one_pass, &a, repeat, r);
}

static void row(const char *name, const result *r, double frames)
{
    double s = r->median / r->repeat;
    printf("%-24s %6u %9.4f %9.4f %9.4f %12.0f %9.3f\n", name, r->repeat, r->median, r->min, r->max,
           frames / s, s / frames * 1e6);
}

/* ---- the peer file ---- */

static bool little_endian(void)
{
    uint32_t one = 1;
    unsigned char b;
    memcpy(&b, &one, 1);
    return b == 1;
}

static int put(FILE *f, const void *v, size_t n, size_t size)
{
    return fwrite(v, size, n, f) == n ? 0 : 1;
}

static int put_model(FILE *f, const params *p)
{
    size_t N = p->N, K = N * p->M, m = p->m;
    return put(f, p->start, N, 8) || put(f, p->trans, N * N, 8) || put(f, p->weights, K, 8) ||
           put(f, p->means, K * m, 8) || put(f, p->covs, K * m * m, 8);
}

static int write_peer(const char *path, const params *gen, const params *init, const dataset *d,
                      const double *ll, const double results[8])
{
    FILE *f = fopen(path, "wb");
    if (!f) {
        perror(path);
        return 1;
    }
    uint32_t hdr[8] = {gen->N, gen->M, gen->m, d->n_seqs, d->T, 0, 0, 0};
    int rc = put(f, "AFHMMBN1", 8, 1) || put(f, hdr, 8, 4) || put(f, results, 8, 8) ||
             put_model(f, gen) || put_model(f, init) || put(f, ll, d->n_seqs, 8) ||
             put(f, d->x, (size_t)d->n_seqs * d->T * d->m, 8);
    if (fclose(f) != 0)
        rc = 1;
    if (rc)
        fprintf(stderr, "%s: write failed\n", path);
    return rc;
}

/* ---- one dimension ---- */

/* Copies a trained model's parameters (the initial model: max_iter 0) into p. */
static int copy_model(const affect_hmm *h, params *p)
{
    const affect_hmm_config *cfg = affect_hmm_get_config(h);
    size_t N = cfg->n_states, K = N * cfg->n_mix, m = cfg->dim;
    memset(p, 0, sizeof *p);
    p->N = cfg->n_states;
    p->M = cfg->n_mix;
    p->m = cfg->dim;
    p->start = malloc(N * sizeof(double));
    p->trans = malloc(N * N * sizeof(double));
    p->weights = malloc(K * sizeof(double));
    p->means = malloc(K * m * sizeof(double));
    p->covs = malloc(K * m * m * sizeof(double));
    if (!p->start || !p->trans || !p->weights || !p->means || !p->covs)
        return 1;
    memcpy(p->start, affect_hmm_start(h), N * sizeof(double));
    memcpy(p->trans, affect_hmm_transitions(h), N * N * sizeof(double));
    memcpy(p->weights, affect_hmm_weights(h), K * sizeof(double));
    memcpy(p->means, affect_hmm_means(h), K * m * sizeof(double));
    memcpy(p->covs, affect_hmm_covariances(h), K * m * m * sizeof(double));
    return 0;
}

static void train_config(affect_hmm_config *cfg, uint32_t m, uint32_t max_iter)
{
    affect_hmm_config_default(cfg);
    cfg->n_states = N_STATES;
    cfg->n_mix = N_MIX;
    cfg->dim = m;
    cfg->cov = AFFECT_HMM_FULL;
    cfg->topology = AFFECT_HMM_ERGODIC;
    cfg->max_iter = max_iter;
    cfg->tol = 0.0;
    cfg->reg = 0.0;
}

static int bench_dim(uint32_t m, const char *out_dir)
{
    params gen, init;
    dataset d = {0};
    bench_ctx c = {0};
    affect_hmm *h = NULL, *h2 = NULL;
    affect_error err;
    int rc = 1;
    memset(&init, 0, sizeof init);
    if (make_params(m, MODEL_SEED + m, &gen) || make_data(&gen, N_SEQS, SEQ_FRAMES, DATA_SEED, &d))
        goto cleanup;
    affect_hmm_config cfg;
    train_config(&cfg, m, 0);
    if (affect_hmm_from_params(&cfg, gen.start, gen.trans, gen.weights, gen.means, gen.covs, &h,
                               &err)) {
        fprintf(stderr, "m = %u: generating model: %s\n", m, err.msg);
        goto cleanup;
    }
    uint32_t K = N_STATES * N_MIX;
    c.p = &gen;
    c.d = &d;
    c.h = h;
    c.buf = malloc((size_t)SEQ_FRAMES * m * sizeof(double));
    c.out = malloc((size_t)K * SEQ_FRAMES * sizeof(double));
    c.ll = malloc(N_SEQS * sizeof(double));
    if (!c.buf || !c.out || !c.ll || make_inverse(&c))
        goto cleanup;
    double gemm_diff = gemm_check(&c);

    result bound_r, centre_r, gemm_r, panel_r, score_r, t0_r, t2_r;
    if (measure(k_bound, &c, 0, &bound_r) || measure(k_centre, &c, 0, &centre_r) ||
        measure(k_gemm, &c, 0, &gemm_r) || measure(k_panel, &c, 0, &panel_r) ||
        measure(k_score, &c, 0, &score_r))
        goto cleanup;
    double total_ll = 0.0;
    for (uint32_t s = 0; s < N_SEQS; s++)
        total_ll += c.ll[s];
    train_config(&c.cfg, m, 0);
    if (measure(k_train, &c, 1, &t0_r))
        goto cleanup;
    train_config(&c.cfg, m, 2);
    if (measure(k_train, &c, 1, &t2_r))
        goto cleanup;

    /* the initial model and the report's log-likelihoods, for the peer */
    train_config(&cfg, m, 0);
    if (affect_hmm_train(&cfg, d.seqs, d.n_seqs, &h2, &err)) {
        fprintf(stderr, "m = %u: training: %s\n", m, err.msg);
        goto cleanup;
    }
    if (copy_model(h2, &init)) {
        fprintf(stderr, "out of memory\n");
        goto cleanup;
    }
    affect_hmm_free(h2);
    h2 = NULL;
    train_config(&cfg, m, 2);
    if (affect_hmm_train(&cfg, d.seqs, d.n_seqs, &h2, &err)) {
        fprintf(stderr, "m = %u: training: %s\n", m, err.msg);
        goto cleanup;
    }
    affect_hmm_report rep;
    affect_hmm_get_report(h2, &rep);

    double frames = (double)N_SEQS * SEQ_FRAMES;
    double bound_s = bound_r.median / bound_r.repeat, centre_s = centre_r.median / centre_r.repeat;
    double score_s = score_r.median / score_r.repeat;
    double iter_s = (t2_r.median - t0_r.median) / 2.0;
    printf("m = %u: %u sequences x %u frames = %.0f frames, %.1f MB of float64 data; "
           "log-likelihood under the generating model %.6f (%.4f per frame)\n",
           m, N_SEQS, SEQ_FRAMES, frames, frames * m * 8 / 1e6, total_ll, total_ll / frames);
    printf("%-24s %6s %9s %9s %9s %12s %9s\n", "kernel", "passes", "median", "fastest", "slowest",
           "frames/s", "us/frame");
    row("trsm bound", &bound_r, frames);
    row("  centre+norm (no BLAS)", &centre_r, frames);
    row("gemm alt. (full W)", &gemm_r, frames);
    row("panel gemm (engine's)", &panel_r, frames);
    row("score (loglik)", &score_r, frames);
    row("train max_iter 0", &t0_r, frames);
    row("train max_iter 2", &t2_r, frames);
    printf("OpenBLAS dtrsm: %.4f s per pass (bound minus centre+norm), %.1f%% of the bound\n",
           bound_s - centre_s, 100.0 * (bound_s - centre_s) / bound_s);
    printf("gemm alternative: %.2fx the trsm bound's speed; its values differ from the "
           "bound's by %.1e relative at most (first sequence)\n",
           bound_s / (gemm_r.median / gemm_r.repeat), gemm_diff);
    printf("Baum-Welch iteration (E+M, (t(2) - t(0)) / 2): %.4f s per %.0f frames = %.0f frames/s, "
           "%.2fx the scoring pass\n",
           iter_s, frames, frames / iter_s, iter_s / score_s);
    printf("report: L0 %.6f, L1 %.6f, L2 %.6f, %u re-seeded\n", rep.loglik[0], rep.loglik[1],
           rep.loglik[2], rep.reseeded);
    double panel_s = panel_r.median / panel_r.repeat;
    printf("scoring runs at %.1f%% of the trsm bound's speed; goal >= %.0f%%: %s\n",
           100.0 * bound_s / score_s, 100.0 * BOUND_GOAL,
           bound_s / score_s >= BOUND_GOAL ? "met" : "NOT met");
    printf("scoring runs at %.1f%% of its own panel-gemm bound's speed\n\n",
           100.0 * panel_s / score_s);

    printf("BENCH hmm_m%u_trsm_bound %.0f frames/s\n", m, frames / bound_s);
    printf("BENCH hmm_m%u_dtrsm_share %.4f ratio\n", m, (bound_s - centre_s) / bound_s);
    printf("BENCH hmm_m%u_gemm_alternative %.0f frames/s\n", m,
           frames / (gemm_r.median / gemm_r.repeat));
    printf("BENCH hmm_m%u_panel_gemm %.0f frames/s\n", m, frames / panel_s);
    printf("BENCH hmm_m%u_score %.0f frames/s\n", m, frames / score_s);
    printf("BENCH hmm_m%u_score_vs_bound %.4f ratio\n", m, bound_s / score_s);
    printf("BENCH hmm_m%u_train_init %.4f s\n", m, t0_r.median);
    printf("BENCH hmm_m%u_bw_iteration %.4f s\n", m, iter_s);
    printf("\n");

    if (out_dir) {
        char path[4096];
        double results[8] = {frames / score_s, frames / bound_s, iter_s,   rep.loglik[0],
                             rep.loglik[1],    rep.loglik[2],    total_ll, 0.0};
        snprintf(path, sizeof path, "%s/hmm-m%u.bin", out_dir, m);
        if (write_peer(path, &gen, &init, &d, c.ll, results))
            goto cleanup;
        printf("wrote %s for hmm_peer.py\n\n", path);
    }
    rc = 0;
cleanup:
    affect_hmm_free(h);
    affect_hmm_free(h2);
    free(c.buf);
    free(c.out);
    free(c.ll);
    free(c.winv);
    free(c.mw);
    free(c.g);
    free(c.panels);
    free_data(&d);
    free_params(&gen);
    free_params(&init);
    return rc;
}

/* ---- peak memory ---- */

/* In a child: generates n_seqs × T frames of MEM_DIM and, when train is set, trains on them
 * (max_iter 1), then sends its getrusage ru_maxrss (KiB) through a pipe. The peak and the
 * child's wall time into *kb, *seconds. */
static int child_peak(uint32_t n_seqs, uint32_t T, bool train, long *kb, double *seconds)
{
    int fd[2];
    fflush(stdout);
    if (pipe(fd) != 0) {
        perror("pipe");
        return 1;
    }
    double t0 = now();
    pid_t pid = fork();
    if (pid < 0) {
        perror("fork");
        close(fd[0]);
        close(fd[1]);
        return 1;
    }
    if (pid == 0) {
        close(fd[0]);
        params p;
        dataset d = {0};
        int code = 1;
        if (make_params(MEM_DIM, MODEL_SEED + MEM_DIM, &p) == 0 &&
            make_data(&p, n_seqs, T, DATA_SEED, &d) == 0) {
            code = 0;
            if (train) {
                affect_hmm_config cfg;
                affect_hmm *h = NULL;
                affect_error err;
                train_config(&cfg, MEM_DIM, 1);
                if (affect_hmm_train(&cfg, d.seqs, n_seqs, &h, &err)) {
                    fprintf(stderr, "peak-memory training: %s\n", err.msg);
                    code = 1;
                }
                affect_hmm_free(h);
            }
        }
        struct rusage ru;
        long peak = getrusage(RUSAGE_SELF, &ru) == 0 ? ru.ru_maxrss : -1;
        if (write(fd[1], &peak, sizeof peak) != (ssize_t)sizeof peak)
            code = 1;
        free_data(&d);
        free_params(&p);
        _exit(code);
    }
    close(fd[1]);
    long peak = -1;
    ssize_t got = read(fd[0], &peak, sizeof peak);
    close(fd[0]);
    int status;
    if (waitpid(pid, &status, 0) != pid) {
        perror("waitpid");
        return 1;
    }
    *seconds = now() - t0;
    *kb = peak;
    return got == (ssize_t)sizeof peak && peak > 0 && WIFEXITED(status) && WEXITSTATUS(status) == 0
               ? 0
               : 1;
}

typedef struct peaks {
    long empty, data, train, long_data, long_train; /* kB */
    double t_data, t_train, t_long_train;
} peaks;

static int measure_memory(peaks *pk)
{
    double t;
    uint32_t short_n = MEM_FRAMES / SEQ_FRAMES, long_n = MEM_FRAMES / LONG_SEQ_FRAMES;
    return child_peak(1, N_STATES, false, &pk->empty, &t) ||
           child_peak(short_n, SEQ_FRAMES, false, &pk->data, &pk->t_data) ||
           child_peak(short_n, SEQ_FRAMES, true, &pk->train, &pk->t_train) ||
           child_peak(long_n, LONG_SEQ_FRAMES, false, &pk->long_data, &t) ||
           child_peak(long_n, LONG_SEQ_FRAMES, true, &pk->long_train, &pk->t_long_train);
}

static void print_memory(const peaks *pk)
{
    double mb = 1024.0 / 1e6; /* ru_maxrss is in KiB */
    double data_mb = (double)MEM_FRAMES * MEM_DIM * 8 / 1e6;
    printf("peak memory (ru_maxrss of a child process), %u frames x %u dims (%.1f MB of "
           "float64 data), training with max_iter 1:\n",
           MEM_FRAMES, MEM_DIM, data_mb);
    printf("%-36s %10s %14s %10s\n", "child", "peak MB", "minus data MB", "seconds");
    printf("%-36s %10.1f %14s %10s\n", "empty (1 short sequence, no training)", pk->empty * mb, "",
           "");
    printf("%-36s %10.1f %14s %10.2f\n", "data, 800 x 500 frames", pk->data * mb, "", pk->t_data);
    printf("%-36s %10.1f %14.1f %10.2f\n", "train, 800 x 500 frames", pk->train * mb,
           (pk->train - pk->data) * mb, pk->t_train);
    printf("%-36s %10.1f %14s %10s\n", "data, 4 x 100000 frames", pk->long_data * mb, "", "");
    printf("%-36s %10.1f %14.1f %10.2f\n", "train, 4 x 100000 frames", pk->long_train * mb,
           (pk->long_train - pk->long_data) * mb, pk->t_long_train);
    double worst = (pk->train > pk->long_train ? pk->train : pk->long_train) * mb;
    printf("goal: peak <= %.0f MB for training on %u x %u: %s (%.1f MB at most)\n\n",
           MEMORY_GOAL_MB, MEM_FRAMES, MEM_DIM, worst <= MEMORY_GOAL_MB ? "met" : "NOT met", worst);
    printf("BENCH hmm_train_peak_rss %.1f MB\n", pk->train * mb);
    printf("BENCH hmm_train_peak_rss_minus_data %.1f MB\n", (pk->train - pk->data) * mb);
    printf("BENCH hmm_train_long_peak_rss %.1f MB\n", pk->long_train * mb);
    printf("BENCH hmm_train_long_peak_rss_minus_data %.1f MB\n",
           (pk->long_train - pk->long_data) * mb);
    printf("\n");
}

int main(int argc, char **argv)
{
    const char *out_dir = NULL;
    bool memory = true;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--out") == 0 && i + 1 < argc) {
            out_dir = argv[++i];
        } else if (strcmp(argv[i], "--no-memory") == 0) {
            memory = false;
        } else {
            fprintf(stderr, "usage: %s [--out DIR] [--no-memory]\n", argv[0]);
            return 2;
        }
    }
    if (out_dir && !little_endian()) {
        printf("bench_hmm: not a little-endian host: no files for the peer\n");
        out_dir = NULL;
    }

    /* the children first, while this process holds no data */
    peaks pk;
    if (memory && measure_memory(&pk)) {
        fprintf(stderr, "bench_hmm: a peak-memory child failed\n");
        return 1;
    }

    int threads = openblas_get_num_threads();
    printf("hmm: N = %u states, M = %u mixtures, full covariances, ergodic, pi = first state; "
           "training with reg 0, tol 0\n",
           N_STATES, N_MIX);
    printf("openblas: %s; %d thread%s%s\n\n", openblas_get_config(), threads,
           threads == 1 ? "" : "s",
           threads == 1 ? "" : " (WARNING: set OPENBLAS_NUM_THREADS=1 for single-core numbers)");
    static const uint32_t dims[] = {15, 63};
    for (size_t i = 0; i < sizeof dims / sizeof dims[0]; i++)
        if (bench_dim(dims[i], out_dir))
            return 1;
    if (memory)
        print_memory(&pk);
    return 0;
}
