/*
 * rmlr.c — elastic-net multinomial logistic regression by coordinate descent (see
 * affect/rmlr.h for the model, the path and the cross-validation).
 *
 * Usage: see the block at the top of affect/rmlr.h (compiled by the style/header-usage test).
 *
 * How it works (written from the published method, Friedman, Hastie & Tibshirani 2010, §4; no
 * code of glmnet's). A "fitter" holds one training set: its standardized features stored
 * column by column (z, n × p column-major), labels, the coefficients and the linear
 * predictors η (n × K). To fit one λ, the classes are visited in order 0 .. K−1; for class k,
 * with p_i = P(y_i = k) at the current η, the log-likelihood in (β0k, βk) is replaced by its
 * quadratic approximation: weights w_i = p_i(1 − p_i) (floored at W_MIN), working residuals
 * r_i = (1{y_i = k} − p_i) / w_i. That weighted least-squares problem with the elastic-net
 * penalty is solved by cyclic coordinate descent:
 *     intercept  β0 += Σ w_i r_i / Σ w_i
 *     feature j  β_j ← S((1/n) Σ w_i z_ij r_i + v_j β_j, λα) / (v_j + λ(1 − α)),
 *                v_j = (1/n) Σ w_i z_ij², S the soft-threshold,
 * updating r after every change; after a full pass, passes run over the non-zero
 * coefficients only until they settle, then a full pass confirms (the active-set strategy).
 * The inner loop stops when a pass changes no coordinate by more than tol in the weighted
 * squared sense v_j Δβ_j² (the scale of the objective; the intercept with Σw/n). The step from
 * the old to the new class-k parameters is halved (at most MAX_HALVINGS times) until the
 * penalised objective does not increase, which keeps the partial Newton iteration from
 * overshooting when probabilities approach 0 or 1. After each cycle over the classes, every
 * feature's K coefficients are shifted by the common c_j that minimises their penalty (the
 * likelihood does not change: the softmax ignores a shift common to all classes); without it
 * block coordinate descent crawls along that flat direction. The cycle repeats until the
 * penalised objective changes by at most tol relative; the intercepts are then centred.
 * Successive λ values start from the previous solution (warm starts); at the automatic path's
 * first λ (λ_max) the intercept-only start is the solution and is kept as is.
 * Screening (fitter_solve): the cycles visit only the strong set — features with a non-zero
 * coefficient or max_k |g_kj| ≥ α(2λ − λ_prev) at the previous fit, the sequential strong rule —
 * and, once they settle, the gradient of every feature is computed at the new fit: a feature
 * outside the set whose KKT condition fails (max_k |g_kj| > αλ) joins it and the cycles go on.
 * Those gradients are the next λ's screening values, so each λ computes them once (plus once
 * per repair).
 *
 * Speed (the first two devices compute the very numbers, in the very order, of the plain
 * loops, and halved the time of a 53 × 27, 4-class cross-validation: 10 s → 5.5 s):
 *   - the softmax cache: the fitter keeps, per sample, the row maximum mx_i of η, the terms
 *     exp(η_il − mx_i) and their sum. The step-halving's loss of a trial refreshes them for
 *     class k only (a row's other terms are reused when its maximum is unchanged: same
 *     operands, same bits), and once the trial is accepted they are η's, so the next class
 *     step reads its probabilities and loss from them instead of recomputing n·K exp and n log;
 *   - block sums: a full pass computes the gradients Σ w_i z_ij r_i of up to GRAD_BLOCK
 *     consecutive features together, each with its own accumulator in sample order (one sum's
 *     additions wait on each other; four sums overlap). The block ends at the first non-zero
 *     coefficient; a coordinate that moves makes the block's later gradients stale, and they
 *     are computed again on the new r. v_j is computed when first needed (a zero coefficient
 *     whose gradient stays under λα does not need it), the non-zero ones' in blocks;
 *   - the centring shift is skipped for a feature whose K coefficients have no penalty, and
 *     keeps the softmax cache (shift_rows): adding one value to a row's K predictors changes
 *     neither the probabilities nor which one is the row's maximum, so the row maximum moves
 *     by the same value and the exp terms are kept (the intercepts' centring likewise).
 * These last two (the strong set and the kept cache) change the result in its last bits only.
 * Newton steps on the non-zero coefficients (options.solver AFFECT_RMLR_SOLVER_NEWTON, the
 * default). The cycles alone are slow where the data are nearly separable (small λ): most
 * samples share their probability between two classes, moving both classes' coefficient
 * vectors together hardly changes the likelihood, and class-by-class steps crawl along those
 * directions (the objective fell by a factor of about 0.99 per cycle for 60 cycles; a λ took
 * 13 cycles on average). Those directions run across features, so no coordinate-wise solver
 * escapes them (a proximal Newton loop with per-feature K × K blocks was tried and was 2×
 * slower, docs/BENCHMARKS.md). Once the signs of the coefficients have settled the problem is
 * smooth: with the zeros held at 0 and the signs s held, the objective is
 *     −(1/n) log-likelihood + λα Σ s β + λ(1−α)/2 Σ β²
 * in the m = (non-zero coefficients) + (K − 1 intercepts) variables (the last intercept is
 * held: a shift common to all intercepts changes nothing), and Newton's method takes it in a
 * few steps (newton_solve). Its Hessian, Σ_i (diag(p_i) − p_i p_iᵀ) ⊗ u_i u_iᵀ over the
 * variables' features u_i (1 for an intercept), plus λ(1−α) on the coefficients' diagonal, is
 * built sample by sample (n m²/2 multiply-adds) and factored by Cholesky (m³/6), with a tiny
 * damping raised if a pivot fails (at α = 1 a feature whose K coefficients are all non-zero
 * has an exactly flat direction). The factor is then kept: the next steps, and the next λ
 * values while the variables stay the same, reuse it with a fresh gradient each step (a
 * simplified Newton iteration; it is rebuilt when the decrement no longer falls by
 * NEWTON_SLOW per step), a coefficient that reaches 0 is removed from it by Givens rotations
 * (O(m²)), and one that must enter is appended by a bordering step (its Hessian column, n m,
 * and one triangular solve, m²/2). Each step is halved until the objective falls, projected
 * onto the signs' orthant (a coefficient that would change sign stops at 0). It converges
 * when half the decrement gᵀH⁻¹g (the decrease the quadratic model promises) is at most
 * NEWTON_TOL × tol × the objective; then the zero coefficients' KKT conditions are checked on
 * the full gradient (computed anyway for the next λ's screening): those that fail (beyond
 * KKT_SLACK √tol relative) join as variables with the sign of their gradient and Newton goes on;
 * after KKT_ENTER_MAX such rounds the cycles take over. So a λ costs a few gradients and
 * triangular solves when its pattern is the last one's, where it took 13 cycles. Along a
 * stretch of the path where the signs hold, the start is extrapolated from the last two
 * solutions (path_predict, a secant step in log λ), which saves about one Newton step per λ.
 * When to use it (fitter_solve, fitter_cycles): first at a λ whose predecessor converged by
 * Newton or whose factor is still that of the non-zero coefficients, or when the cycles of
 * the predecessor cost more than one factorisation; else after a cycle that changed no sign,
 * when the cycles still expected (from the ratio of the last two decreases of the objective)
 * cost more than a factorisation. Beyond NEWTON_MAX variables only the cycles run.
 * At α = 1 the solution need not be unique: a feature whose K coefficients have as many
 * positive as negative signs can be shifted along a stretch of equal objective. After each
 * λ (with the Newton solver), newton_sparsify moves such a feature to the end of the stretch of
 * smallest shift, where one coefficient is 0 (the sparsest point, as the cycles' coordinate moves
 * tend to reach); the zero it leaves is exempt from the KKT check (flat_zero: there its gradient is
 * within ±λ by the classes' gradients summing to 0).
 * All of it is plain loops in fixed orders (sums with four partial accumulators in a fixed
 * assignment), so results stay the same bytes for the same inputs and whatever the threads.
 *
 * Cross-validation keeps one fitter per worker and, after each λ, predicts the held-out
 * samples, so no path of coefficients is stored. Counts of misclassified samples are integers,
 * so ties are exact. With options.threads = T > 1 the α values are shared among the calling
 * thread and T − 1 C11 threads (<threads.h>): each takes the next α under a mutex and runs its
 * folds with its own fitter, writing only its α's row of the miss counts; the fitters are
 * allocated before any thread starts, so workers never allocate (nor fail), and a thread or
 * lock that cannot be created only leaves more of the work to the calling thread. The result
 * is the same bytes whatever T (tests/core/test_rmlr.c compares the encodings).
 *
 * affect_impute_column_means (column means for missing values) lives here because its users
 * are the RMLR's: Laban vectors with components that could not be computed.
 */
#include "affect/rmlr.h"

#include <math.h>
#include <string.h>
#include <threads.h>

#include "affect/svm.h"
#include "util/bytes.h"

/* The losses sum log Σ_l exp(η_il − mx_i) over the samples as the log of products of up to
 * LOG_CHUNK of those sums, one log per chunk instead of one per sample (log was a tenth of a
 * cross-validation's time): each sum lies in [1, K] (its largest term is exp(0) = 1) and
 * K ≤ 256 = 2⁸, so a chunk's product stays in [1, 2⁹⁶⁰]; its rounding (LOG_CHUNK ulps relative)
 * is that of summing the logs one by one. */
#define LOG_CHUNK 120u
_Static_assert(AFFECT_RMLR_MAX_CLASSES <= 256, "LOG_CHUNK assumes K <= 2^8");

/* Floor on the Newton weights p(1 − p) (the paper's 1e-5). */
#define W_MIN 1e-5
/* glmnet's floor on α in λ_max. */
#define ALPHA_FLOOR 1e-3
/* Step halvings before a class update is abandoned. */
#define MAX_HALVINGS 30
/* Relative slack of the descent test (floating-point noise in the objective). */
#define DESCENT_SLACK 1e-13
/* Sums over the samples computed together (see block_sums). */
#define GRAD_BLOCK 4
/* Newton steps (see newton_solve): variables at most (the Hessian's factor has this many
 * squared doubles, 512 KiB per fitter); beyond, coordinate descent alone. */
#define NEWTON_MAX 256
/* Newton's stop: half the decrement at most NEWTON_TOL × tol × the objective (stricter than the
 * cycles' tol: the rest of a Newton step is about the square of the last). */
#define NEWTON_TOL 0.01
/* Steps per call at most. */
#define NEWTON_ITERS 20
/* A kept factor is refreshed when the decrement falls by less than this factor in a step
 * (0.1: measured against 0.02, 0.05, 0.25 and 0.5 on both corpora, docs/BENCHMARKS.md). */
#define NEWTON_SLOW 0.1
/* Damping added to the Hessian's diagonal, relative to its largest entry, and the tries (each
 * 1000 times more) before giving up on a factorisation. */
#define NEWTON_DAMP 1e-10
#define NEWTON_DAMP_TRIES 6
/* A zero coefficient's KKT condition, |g| ≤ λα, is taken as met within KKT_SLACK × √tol
 * relative after Newton's method, whose gradients are accurate to about the square root of its
 * decrement (1e-4 at the default tol 1e-7). */
#define KKT_SLACK 0.3
/* Rounds of Newton steps with entering coefficients per λ before the cycles take over. */
#define KKT_ENTER_MAX 4
/* The cycles switch to Newton when (cycles still expected) × (a cycle's work) exceeds
 * NEWTON_GAIN × (a factorisation's work); a cycle's fixed work per class and sample. */
#define NEWTON_GAIN 1.0
#define CYCLE_FIXED 20.0

struct affect_rmlr {
    uint32_t K, n_train, n_lambda, lambda_index;
    size_t p;
    bool converged;
    double alpha, cv_error;
    double *lambdas, *cv_errors, *mean, *sd, *beta0, *beta; /* one block, carved */
};

void affect_rmlr_options_default(affect_rmlr_options *o)
{
    memset(o, 0, sizeof *o);
    o->n_lambda = 100;
    o->lambda_min_ratio = 0;
    o->alphas = NULL;
    o->n_alpha = AFFECT_RMLR_DEFAULT_N_ALPHA;
    o->folds = 10;
    o->seed = 0;
    o->max_iter = 10000;
    o->tol = 1e-7;
    o->threads = 1;
}

/* ---- the fitter ---- */

/* Samples per pass of the Hessian's accumulation (newton_factor); its code is written for 4. */
#define HESS_BLOCK 4u
_Static_assert(HESS_BLOCK == 4, "newton_factor accumulates four samples per pass");

typedef struct fitter {
    size_t n, p; /* n: the rows loaded, at most the capacity allocated */
    uint32_t K;
    double alpha;
    uint32_t max_iter;
    double tol;
    uint32_t *y;                 /* n */
    uint32_t *strong;            /* p: 1 = in the strong set (see fitter_solve) */
    double *z;                   /* p × n: column j at z + j·n */
    double *mean;                /* p */
    double *sd;                  /* p */
    double *beta;                /* K × p */
    double *beta0;               /* K */
    double *eta;                 /* n × K */
    double *ex;                  /* n × K: exp(η_il − mx_i) (the softmax cache) */
    double *mx, *sum;            /* n each: row maxima of η, Σ_l ex_il */
    double *w, *r, *deta, *etak; /* n each */
    double *v, *bold;            /* p each */
    double *grad;                /* K × p: (1/n) Σ_i z_ij (y_ik − p_ik) at η (when grad_ok) */
    double *s0;                  /* K × p + K: the state before a cycle */
    double *bprev;     /* K × p + K: the solution before the current one (path_predict) */
    double lam1, lam2; /* the λ of the current solution, of bprev's */
    bool sol_newton, prev_newton; /* each converged by Newton (path_predict may use it) */
    double *et;                   /* n × K: a trial η, or the residuals (class-major) */
    double *tex, *tmx, *tsum;     /* n × K, n, n: the trial's softmax cache (see loss_at) */
    size_t nv_cap;                /* Newton variables at most (see fitter_newton) */
    uint32_t *vk, *vj;            /* nv_cap each: variable q is β_{vk,vj} (vj = p: intercept) */
    uint32_t *vend;               /* K: the end of class k's variables */
    size_t nv;                    /* the Newton variables' count */
    double *vs;                   /* nv_cap: their signs (0: intercept) */
    bool newton_on;               /* options.solver: Newton steps allowed */
    double kkt_slack;             /* KKT_SLACK √tol */
    bool fac_ok;                  /* hess holds the factor for the variables vk, vj, vs */
    double fac_mu;                /* the μ added to its diagonal */
    bool newton_last;             /* the last λ converged by Newton steps */
    double lambda_now;            /* the λ being fitted */
    double work_now, work_last;   /* cycles' estimated work at this λ, at the last one */
    double *hess, *hg, *hd, *hu;  /* nv_cap², nv_cap, nv_cap, HESS_BLOCK nv_cap */
    double *hc;                   /* HESS_BLOCK K */
    double *prob, *one;           /* K × n (class-major), n */
    bool grad_ok;                 /* grad is that of the current probabilities */
    bool cached;                  /* ex, mx, sum and loss are those of η */
    double loss;                  /* −(1/n) log-likelihood at η (when cached) */
} fitter;

static void fitter_free(fitter *f)
{
    affect_free(f->y);
    affect_free(f->z);
    memset(f, 0, sizeof *f);
}

/* Allocates f for up to n_cap rows of p features and K classes (n_cap·p, n_cap·K and K·p are
 * known to fit: the caller checked the sizes); fitter_load fills it. */
static affect_status fitter_alloc(fitter *f, size_t n_cap, size_t p, uint32_t K, affect_error *err)
{
    size_t np, nk, kp, total, t;
    memset(f, 0, sizeof *f);
    if (!affect_mul_size(n_cap, p, &np) || !affect_mul_size(n_cap, K, &nk) ||
        !affect_mul_size(K, p, &kp) || !affect_add_size(np, nk, &total) ||
        !affect_add_size(total, nk, &total) || !affect_add_size(total, kp, &total) ||
        !affect_mul_size(p, 4, &t) || !affect_add_size(total, t, &total) ||
        !affect_mul_size(n_cap, 6, &t) || !affect_add_size(total, t, &total) ||
        !affect_add_size(total, K, &total) || !affect_add_size(total, kp, &total) ||
        !affect_add_size(total, nk, &total) || !affect_add_size(kp, K, &t) ||
        !affect_add_size(total, t, &total) || !affect_add_size(total, t, &total) ||
        !affect_add_size(n_cap, p, &t))
        return affect_fail(err, AFFECT_ERR_RANGE, "too many values: %zu samples × %zu features",
                           n_cap, p);
    size_t nv = kp + K - 1, nt, nn;
    if (nv > NEWTON_MAX)
        nv = NEWTON_MAX;
    if (!affect_mul_size(nv, nv, &nn) || !affect_add_size(nn, (3 + HESS_BLOCK) * nv, &nn) ||
        !affect_add_size(nn, HESS_BLOCK * (size_t)K, &nn) || !affect_add_size(nn, nk, &nn) ||
        !affect_add_size(nn, n_cap, &nn) || !affect_add_size(nn, nk, &nn) ||
        !affect_mul_size(n_cap, 2, &nt) || !affect_add_size(nn, nt, &nn) ||
        !affect_add_size(total, nn, &total) || !affect_add_size(t, 2 * nv, &nt) ||
        !affect_add_size(nt, K, &nt))
        return affect_fail(err, AFFECT_ERR_RANGE, "too many values: %zu samples × %zu features",
                           n_cap, p);
    f->y = affect_malloc_array(nt, sizeof *f->y); /* the labels, the strong set, vk, vj */
    f->z = affect_malloc_array(total, sizeof *f->z);
    if (!f->y || !f->z) {
        fitter_free(f);
        return affect_nomem(err);
    }
    f->p = p;
    f->K = K;
    f->strong = f->y + n_cap;
    f->nv_cap = nv;
    f->vk = f->strong + p;
    f->vj = f->vk + nv;
    f->vend = f->vj + nv;
    double *q = f->z + np;
    f->mean = q, q += p;
    f->sd = q, q += p;
    f->v = q, q += p;
    f->bold = q, q += p;
    f->beta = q, q += kp;
    f->grad = q, q += kp;
    f->beta0 = q, q += K;
    f->eta = q, q += nk;
    f->ex = q, q += nk;
    f->mx = q, q += n_cap;
    f->sum = q, q += n_cap;
    f->w = q, q += n_cap;
    f->r = q, q += n_cap;
    f->deta = q, q += n_cap;
    f->etak = q, q += n_cap;
    f->et = q, q += nk;
    f->s0 = q, q += kp + K;
    f->bprev = q, q += kp + K;
    f->hess = q, q += nv * nv;
    f->hg = q, q += nv;
    f->hd = q, q += nv;
    f->hu = q, q += HESS_BLOCK * nv;
    f->vs = q, q += nv;
    f->hc = q, q += HESS_BLOCK * K;
    f->prob = q, q += nk;
    f->tex = q, q += nk;
    f->tmx = q, q += n_cap;
    f->tsum = q, q += n_cap;
    f->one = q;
    for (size_t i = 0; i < n_cap; i++)
        f->one[i] = 1.0;
    return AFFECT_OK;
}

/* Loads the rows i of x (n_all × p) with fold_of[i] != skip (all rows when fold_of is NULL)
 * into f, allocated for at least that many: standardizes, and starts from the intercept-only
 * fit. Every class must be present. Allocates nothing, so workers can call it. */
static void fitter_load(fitter *f, const double *x, size_t n_all, const uint32_t *y,
                        const uint32_t *fold_of, uint32_t skip, double alpha,
                        const affect_rmlr_options *o)
{
    size_t n = 0, p = f->p;
    uint32_t K = f->K;
    for (size_t i = 0, row = 0; i < n_all; i++) {
        if (fold_of && fold_of[i] == skip)
            continue;
        f->y[row++] = y[i];
        n++;
    }
    f->n = n;
    f->alpha = alpha;
    f->max_iter = o->max_iter;
    f->tol = o->tol;
    f->newton_on = o->solver == AFFECT_RMLR_SOLVER_NEWTON;
    f->kkt_slack = KKT_SLACK * sqrt(o->tol);
    f->cached = false;
    f->grad_ok = false;
    f->fac_ok = false;
    f->newton_last = false;
    f->sol_newton = f->prev_newton = false;
    f->work_last = 0;
    for (size_t i = 0, row = 0; i < n_all; i++) {
        if (fold_of && fold_of[i] == skip)
            continue;
        for (size_t j = 0; j < p; j++)
            f->z[j * n + row] = x[i * p + j];
        row++;
    }
    for (size_t j = 0; j < p; j++) {
        double *c = f->z + j * n, s = 0, ss = 0;
        bool constant = true;
        for (size_t i = 0; i < n; i++) {
            s += c[i];
            if (c[i] != c[0])
                constant = false;
        }
        double m = s / (double)n;
        for (size_t i = 0; i < n; i++)
            ss += (c[i] - m) * (c[i] - m);
        double sd = constant ? 0.0 : sqrt(ss / (double)n);
        f->mean[j] = m;
        f->sd[j] = sd;
        for (size_t i = 0; i < n; i++)
            c[i] = sd > 0 ? (c[i] - m) / sd : 0.0;
    }
    /* Intercept-only start: β0k = log(n_k / n), centred. */
    memset(f->beta, 0, (size_t)K * p * sizeof *f->beta);
    memset(f->beta0, 0, K * sizeof *f->beta0);
    for (size_t i = 0; i < n; i++)
        f->beta0[f->y[i]] += 1.0;
    double mb = 0;
    for (uint32_t k = 0; k < K; k++) {
        f->beta0[k] = log(f->beta0[k] / (double)n);
        mb += f->beta0[k];
    }
    mb /= K;
    for (uint32_t k = 0; k < K; k++)
        f->beta0[k] -= mb;
    for (size_t i = 0; i < n; i++)
        for (uint32_t k = 0; k < K; k++)
            f->eta[i * K + k] = f->beta0[k];
}

/* max_kj |(1/n) Σ_i z_ij (y_ik − π_k)| of the fitter's data (which must be at its
 * intercept-only start); it does not depend on α. */
static double fitter_grad_max(const fitter *f)
{
    double g = 0;
    for (uint32_t k = 0; k < f->K; k++) {
        double pik = 0;
        for (size_t i = 0; i < f->n; i++)
            pik += f->y[i] == k;
        pik /= (double)f->n;
        for (size_t j = 0; j < f->p; j++) {
            const double *c = f->z + j * f->n;
            double s = 0;
            for (size_t i = 0; i < f->n; i++)
                s += c[i] * ((f->y[i] == k) - pik);
            s = fabs(s / (double)f->n);
            if (s > g)
                g = s;
        }
    }
    return g;
}

/* λ_max for α from fitter_grad_max's g. */
static double lambda_max(double g, double alpha)
{
    return g / (alpha > ALPHA_FLOOR ? alpha : ALPHA_FLOOR);
}

static double soft(double g, double t)
{
    return g > t ? g - t : g < -t ? g + t : 0.0;
}

/* The penalty of class k's coefficients b (p values), without λ. */
static double penalty(const fitter *f, const double *b)
{
    double s = 0;
    for (size_t j = 0; j < f->p; j++)
        s += f->alpha * fabs(b[j]) + 0.5 * (1 - f->alpha) * b[j] * b[j];
    return s;
}

/* The softmax cache of the linear predictors e (n × K) into ex, mx, sum; returns −(1/n)
 * log-likelihood. */
static double softmax_into(const fitter *f, const double *e, double *ex, double *mx, double *sum)
{
    uint32_t K = f->K, c = 0;
    double s = 0, prod = 1;
    for (size_t i = 0; i < f->n; i++) {
        const double *r = e + i * K;
        double *x = ex + i * K, m = r[0], t = 0;
        uint32_t am = 0;
        for (uint32_t l = 1; l < K; l++)
            if (r[l] > m)
                m = r[l], am = l;
        for (uint32_t l = 0; l < K; l++) /* exp(0) = 1 exactly: the maximum's term is free */
            t += x[l] = l == am ? 1.0 : exp(r[l] - m);
        mx[i] = m;
        sum[i] = t;
        s += m - r[f->y[i]];
        prod *= t;
        if (++c == LOG_CHUNK)
            s += log(prod), prod = 1, c = 0;
    }
    return (s + log(prod)) / (double)f->n;
}

/* Fills the softmax cache from η and returns −(1/n) log-likelihood (also kept in f->loss). */
static double softmax_fresh(fitter *f)
{
    f->loss = softmax_into(f, f->eta, f->ex, f->mx, f->sum);
    f->cached = true;
    return f->loss;
}

/* −(1/n) log-likelihood with class k's linear predictor replaced by ek (n values), the cache
 * being that of η in every other class. Updates the cache to the trial: a row's other terms
 * exp(η_il − mx_i) are reused when its maximum is unchanged (the same operands give the same
 * bits), so most rows cost one exp instead of K. */
static double trial_loss(fitter *f, uint32_t k, const double *ek)
{
    double s = 0, prod = 1;
    uint32_t K = f->K, c = 0;
    for (size_t i = 0; i < f->n; i++) {
        const double *e = f->eta + i * K;
        double *x = f->ex + i * K, eki = ek[i], mx = eki, sum = 0;
        for (uint32_t l = 0; l < K; l++)
            if (l != k && e[l] > mx)
                mx = e[l];
        if (mx != f->mx[i]) {
            for (uint32_t l = 0; l < K; l++)
                x[l] = exp((l == k ? eki : e[l]) - mx);
            f->mx[i] = mx;
        } else {
            x[k] = exp(eki - mx);
        }
        for (uint32_t l = 0; l < K; l++)
            sum += x[l];
        f->sum[i] = sum;
        double ey = f->y[i] == k ? eki : e[f->y[i]];
        s += mx - ey;
        prod *= sum;
        if (++c == LOG_CHUNK)
            s += log(prod), prod = 1, c = 0;
    }
    return (s + log(prod)) / (double)f->n;
}

/* For the m ≤ GRAD_BLOCK features j = blk[q]: out[q] = Σ_i w_i z_ij r_i, or Σ_i w_i z_ij² when
 * r is NULL. Each sum runs over i in order with its own accumulator, so it has the bits it has
 * alone; interleaving them only lets the additions overlap (a single sum waits on its previous
 * addition at every step). */
static void block_sums(const fitter *f, const size_t *blk, size_t m, const double *r, double *out)
{
    const double *w = f->w;
    size_t n = f->n;
    if (m == 0)
        return;
    const double *c0 = f->z + blk[0] * n;
    if (m == 1) {
        double s = 0;
        if (r)
            for (size_t i = 0; i < n; i++)
                s += w[i] * c0[i] * r[i];
        else
            for (size_t i = 0; i < n; i++)
                s += w[i] * c0[i] * c0[i];
        out[0] = s;
        return;
    }
    /* a block of 2 or 3 repeats its first feature in the unused lanes */
    const double *c1 = f->z + blk[1] * n;
    const double *c2 = f->z + blk[m > 2 ? 2 : 0] * n, *c3 = f->z + blk[m > 3 ? 3 : 0] * n;
    double s0 = 0, s1 = 0, s2 = 0, s3 = 0;
    if (r) {
        for (size_t i = 0; i < n; i++) {
            double wi = w[i], ri = r[i];
            s0 += wi * c0[i] * ri;
            s1 += wi * c1[i] * ri;
            s2 += wi * c2[i] * ri;
            s3 += wi * c3[i] * ri;
        }
    } else {
        for (size_t i = 0; i < n; i++) {
            double wi = w[i];
            s0 += wi * c0[i] * c0[i];
            s1 += wi * c1[i] * c1[i];
            s2 += wi * c2[i] * c2[i];
            s3 += wi * c3[i] * c3[i];
        }
    }
    double all[4] = {s0, s1, s2, s3};
    for (size_t q = 0; q < m; q++)
        out[q] = all[q];
}

/* v_j = (1/n) Σ_i w_i z_ij² of the current class step, computed on first use (f->v[j] < 0
 * until then). */
static double weighted_var(fitter *f, size_t j)
{
    if (f->v[j] < 0) {
        double s;
        block_sums(f, &j, 1, NULL, &s);
        f->v[j] = s / (double)f->n;
    }
    return f->v[j];
}

/* v_j of the m features blk[q], computed together. */
static void weighted_var_block(fitter *f, const size_t *blk, size_t m)
{
    double s[GRAD_BLOCK];
    block_sums(f, blk, m, NULL, s);
    for (size_t q = 0; q < m; q++)
        f->v[blk[q]] = s[q] / (double)f->n;
}

/* v_j of every feature with a non-zero coefficient in b (the first full pass needs them all),
 * GRAD_BLOCK at a time. */
static void weighted_vars(fitter *f, const double *b)
{
    size_t blk[GRAD_BLOCK], m = 0;
    for (size_t j = 0; j < f->p; j++)
        if (f->sd[j] != 0 && b[j] != 0) {
            blk[m++] = j;
            if (m == GRAD_BLOCK) {
                weighted_var_block(f, blk, m);
                m = 0;
            }
        }
    weighted_var_block(f, blk, m);
}

/* f->grad of the features j with strong[j] == want (every feature when want > 1; a feature with
 * sd 0 has gradient 0): g_kj = (1/n) Σ_i z_ij (1{y_i = k} − p_ik), the probabilities from the
 * softmax cache (filled first if need be). Uses f->r. Four features' sums run together, each
 * in sample order with its own accumulator. */
static void fitter_gradients(fitter *f, uint32_t want)
{
    size_t n = f->n, p = f->p;
    uint32_t K = f->K;
    double *r = f->r;
    if (!f->cached)
        softmax_fresh(f);
    for (uint32_t k = 0; k < K; k++) {
        double *g = f->grad + (size_t)k * p;
        for (size_t i = 0; i < n; i++)
            r[i] = (f->y[i] == k) - f->ex[i * K + k] / f->sum[i];
        size_t blk[GRAD_BLOCK], m = 0;
        for (size_t j = 0; j <= p; j++) {
            bool take = j < p && (want > 1 || f->strong[j] == want);
            if (take && f->sd[j] == 0) {
                g[j] = 0;
                take = false;
            }
            if (take)
                blk[m++] = j;
            if (m == GRAD_BLOCK || (j == p && m > 0)) {
                const double *c0 = f->z + blk[0] * n, *c1 = f->z + blk[m > 1 ? 1 : 0] * n;
                const double *c2 = f->z + blk[m > 2 ? 2 : 0] * n;
                const double *c3 = f->z + blk[m > 3 ? 3 : 0] * n;
                double s0 = 0, s1 = 0, s2 = 0, s3 = 0;
                for (size_t i = 0; i < n; i++) {
                    s0 += c0[i] * r[i];
                    s1 += c1[i] * r[i];
                    s2 += c2[i] * r[i];
                    s3 += c3[i] * r[i];
                }
                double all[4] = {s0, s1, s2, s3};
                for (size_t q = 0; q < m; q++)
                    g[blk[q]] = all[q] / (double)n;
                m = 0;
            }
        }
    }
}

/* max_k |g_kj| of f->grad. */
static double grad_max(const fitter *f, size_t j)
{
    double g = 0;
    for (uint32_t k = 0; k < f->K; k++) {
        double a = fabs(f->grad[(size_t)k * f->p + j]);
        if (a > g)
            g = a;
    }
    return g;
}

/* One partial Newton step for class k at λ. Counts coordinate passes in *passes; *loss receives
 * −(1/n) log-likelihood after the step. */
static void class_step(fitter *f, uint32_t k, double lambda, uint32_t *passes, double *loss)
{
    size_t n = f->n, p = f->p;
    uint32_t K = f->K;
    double *b = f->beta + (size_t)k * p, *w = f->w, *r = f->r, *v = f->v;
    double la = lambda * f->alpha, l2 = lambda * (1 - f->alpha), sw = 0, lo;
    if (*passes >= f->max_iter)
        return;

    lo = f->cached ? f->loss : softmax_fresh(f);
    for (size_t i = 0; i < n; i++) {
        double pk = f->ex[i * K + k] / f->sum[i];
        double wi = pk * (1 - pk);
        if (wi < W_MIN)
            wi = W_MIN;
        w[i] = wi;
        r[i] = ((f->y[i] == k) - pk) / wi;
        sw += wi;
    }
    for (size_t j = 0; j < p; j++)
        v[j] = -1; /* computed when first needed (weighted_var) */
    weighted_vars(f, b);
    double f_old = lo + lambda * penalty(f, b);
    double b0old = f->beta0[k], b0 = b0old;
    memcpy(f->bold, b, p * sizeof *b);

    bool full = true;
    while (*passes < f->max_iter) {
        (*passes)++;
        double s = 0, maxd;
        for (size_t i = 0; i < n; i++)
            s += w[i] * r[i];
        double d = s / sw;
        b0 += d;
        for (size_t i = 0; i < n; i++)
            r[i] -= d;
        maxd = sw / (double)n * d * d;
        for (size_t j = 0; j < p;) {
            /* The next features to visit, up to GRAD_BLOCK, their gradients computed together
             * on the current r; the block ends at the first non-zero coefficient, the one that
             * most likely moves r (a zero one seldom does). */
            size_t blk[GRAD_BLOCK], nblk = 0;
            while (j < p && nblk < GRAD_BLOCK) {
                size_t jj = j++;
                if (!f->strong[jj] || (!full && b[jj] == 0))
                    continue;
                blk[nblk++] = jj;
                if (b[jj] != 0)
                    break;
            }
            double g[GRAD_BLOCK];
            block_sums(f, blk, nblk, r, g);
            for (size_t q = 0; q < nblk; q++) {
                size_t jj = blk[q];
                double gn = g[q] / (double)n;
                if (b[jj] == 0 && soft(gn, la) == 0)
                    continue; /* stays 0, whatever v_j */
                double vj = weighted_var(f, jj);
                double nb = soft(gn + vj * b[jj], la) / (vj + l2);
                double dj = nb - b[jj];
                if (dj != 0) {
                    const double *c = f->z + jj * n;
                    for (size_t i = 0; i < n; i++)
                        r[i] -= c[i] * dj;
                    b[jj] = nb;
                    if (vj * dj * dj > maxd)
                        maxd = vj * dj * dj;
                    if (q + 1 < nblk) { /* r moved: the block's later gradients are stale */
                        j = blk[q + 1];
                        break;
                    }
                }
            }
        }
        if (maxd < f->tol) {
            if (full)
                break;
            full = true;
        } else {
            full = false;
        }
    }

    /* The step old → new, halved until the objective does not increase. */
    double db0 = b0 - b0old;
    for (size_t i = 0; i < n; i++)
        f->deta[i] = db0;
    for (size_t j = 0; j < p; j++) {
        double dj = b[j] - f->bold[j];
        if (dj == 0)
            continue;
        const double *c = f->z + j * n;
        for (size_t i = 0; i < n; i++)
            f->deta[i] += c[i] * dj;
    }
    for (size_t j = 0; j < p; j++)
        v[j] = b[j] - f->bold[j]; /* v now holds the full step of the coefficients */
    double t = 1;
    for (int h = 0;; h++) {
        for (size_t i = 0; i < n; i++)
            f->etak[i] = f->eta[i * K + k] + t * f->deta[i];
        for (size_t j = 0; j < p; j++)
            b[j] = f->bold[j] + t * v[j];
        double l_new = trial_loss(f, k, f->etak);
        if (l_new + lambda * penalty(f, b) <= f_old + DESCENT_SLACK * (1 + fabs(f_old))) {
            lo = l_new;
            break;
        }
        if (h == MAX_HALVINGS) {
            t = 0;
            memcpy(b, f->bold, p * sizeof *b);
            break;
        }
        t *= 0.5;
    }
    *loss = lo;
    f->beta0[k] = b0old + t * db0;
    for (size_t i = 0; i < n; i++)
        f->eta[i * K + k] += t * f->deta[i];
    /* Accepted, η's column k is the last trial's (the same sums), so the cache is η's. */
    f->cached = t != 0;
    f->grad_ok = false;
    f->loss = lo;
}

static double total_penalty(const fitter *f)
{
    double pen = 0;
    for (uint32_t k = 0; k < f->K; k++)
        pen += penalty(f, f->beta + (size_t)k * f->p);
    return pen;
}

/* The shift c minimising Σ_k α|b_k − c| + (1−α)/2 (b_k − c)² over the K values b (stride p),
 * or 0 when no shift lowers it by more than rounding noise. The minimiser is where the
 * (non-decreasing) subgradient crosses 0: either inside an interval between sorted values, where
 * it solves a linear equation, or at one of the values; all candidates are tried. */
static double center_shift(const double *b, size_t stride, uint32_t K, double alpha)
{
    double sum = 0;
    for (uint32_t k = 0; k < K; k++)
        sum += b[k * stride];
    double f0 = 0, best = 0, fbest;
    for (uint32_t k = 0; k < K; k++)
        f0 += alpha * fabs(b[k * stride]) + 0.5 * (1 - alpha) * b[k * stride] * b[k * stride];
    double bar = f0 - DESCENT_SLACK * (1 + f0);
    if (bar <= 0)
        return 0.0; /* no penalty (all zero, say) is below 0 */
    fbest = f0;
    for (uint32_t m = 0; m <= 2 * K; m++) {
        double c;
        if (m < K) {
            c = b[m * stride]; /* a breakpoint */
        } else {
            if (alpha >= 1)
                break;
            /* m − K values below c: the stationary point of that piece */
            double below = (double)(m - K), above = (double)K - below;
            c = (sum - alpha * (below - above) / (1 - alpha)) / (double)K;
        }
        double fc = 0;
        for (uint32_t k = 0; k < K; k++) {
            double d = b[k * stride] - c;
            fc += alpha * fabs(d) + 0.5 * (1 - alpha) * d * d;
        }
        if (fc < fbest) {
            fbest = fc;
            best = c;
        }
    }
    return fbest < bar ? best : 0.0;
}

/* Adds c to η's column k for every k of every sample i, the softmax cache kept: the
 * probabilities do not change, and as the row maximum is one of the row's values, subtracting
 * the same d from both keeps it the maximum, bit for bit; the terms exp(η_il − mx_i) and their
 * sum are kept (their arguments are unchanged but for rounding). c[i] per sample (stride 1),
 * or the one value *c when step is 0. */
static void shift_rows(fitter *f, const double *c, size_t step)
{
    uint32_t K = f->K;
    for (size_t i = 0; i < f->n; i++) {
        double d = c[i * step];
        for (uint32_t k = 0; k < K; k++)
            f->eta[i * K + k] -= d;
        f->mx[i] -= d;
    }
}

/* −(1/n) log-likelihood at the linear predictors e (n × K); the trial's softmax cache (as
 * softmax_fresh computes it) goes to f->tex, f->tmx, f->tsum. */
static double loss_at(fitter *f, const double *e)
{
    return softmax_into(f, e, f->tex, f->tmx, f->tsum);
}

/* Makes the trial of loss_at (η in f->et, its cache in tex, tmx, tsum) the current state, by
 * swapping the buffers. */
static void take_trial(fitter *f, double loss)
{
    double *t;
    t = f->eta, f->eta = f->et, f->et = t;
    t = f->ex, f->ex = f->tex, f->tex = t;
    t = f->mx, f->mx = f->tmx, f->tmx = t;
    t = f->sum, f->sum = f->tsum, f->tsum = t;
    f->cached = true;
    f->loss = loss;
}

/* Whether the coefficients have the signs (and zeros) of the state s0. */
static bool same_pattern(const fitter *f, const double *s0)
{
    size_t kp = (size_t)f->K * f->p;
    for (size_t q = 0; q < kp; q++)
        if ((f->beta[q] > 0) != (s0[q] > 0) || (f->beta[q] < 0) != (s0[q] < 0))
            return false;
    return true;
}

/* In-place Cholesky factor U (upper, UᵀU = A + μI) of the m × m matrix a (row-major with row
 * stride S, upper triangle read and written); false when a pivot is not positive. The updates
 * run along rows (contiguous, independent: they vectorise), each entry's in a fixed order. */
static bool cholesky_upper(double *a, size_t m, size_t S, double mu)
{
    for (size_t c = 0; c < m; c++) {
        double *uc = a + c * S, d = uc[c] + mu;
        if (!(d > 0))
            return false;
        d = sqrt(d);
        uc[c] = d;
        for (size_t s = c + 1; s < m; s++)
            uc[s] /= d;
        for (size_t r = c + 1; r < m; r++) {
            double fr = uc[r], *ur = a + r * S;
            for (size_t s = r; s < m; s++)
                ur[s] -= fr * uc[s];
        }
    }
    return true;
}

/* Sign of a coefficient's variable: +1, −1, or 0 (zero: not a variable). */
static double sign_of(double b)
{
    return b > 0 ? 1 : b < 0 ? -1 : 0;
}

/* Whether the zero coefficient (k0, j) needs no KKT check at α = 1: the feature's other K − 1
 * coefficients are all non-zero with signs s_k summing to −1, 0 or 1. The log-likelihood's
 * gradient sums to 0 over the classes (Σ_k (1{y = k} − p_k) = 0), so where the others are
 * stationary (g_k = λ s_k) g_k0 = −λ Σ s_k, within [−λ, λ]: such a zero is at the end of a
 * flat stretch (newton_sparsify puts it there) and entering it cannot lower the objective. */
static bool flat_zero(const fitter *f, uint32_t k0, size_t j)
{
    if (f->alpha < 1)
        return false;
    double sum = 0;
    for (uint32_t k = 0; k < f->K; k++) {
        double b = f->beta[(size_t)k * f->p + j];
        if (k == k0)
            continue;
        if (b == 0)
            return false;
        sum += sign_of(b);
    }
    return fabs(sum) <= 1;
}

/* The sign an entering zero coefficient (class k, feature j of the strong set) would move to:
 * that of its log-likelihood gradient when it exceeds λα (beyond the slack), else 0. */
static double entering_sign(const fitter *f, uint32_t k, size_t j)
{
    double la = f->lambda_now * f->alpha, g = f->grad[(size_t)k * f->p + j];
    if (flat_zero(f, k, j))
        return 0;
    return g > la * (1 + f->kkt_slack) ? 1 : g < -la * (1 + f->kkt_slack) ? -1 : 0;
}

/* The Newton variables: the non-zero coefficients (with enter, also the zero ones of the
 * strong set whose KKT condition fails, f->grad being current), class by class, and every
 * class's intercept but the last (the softmax ignores a common shift), with their signs;
 * false when there are more than nv_cap. */
static bool newton_vars(fitter *f, bool enter)
{
    size_t p = f->p, m = 0;
    uint32_t K = f->K;
    for (uint32_t k = 0; k < K; k++)
        for (size_t j = 0; j <= p; j++) {
            double sg = 0;
            if (j < p) {
                sg = sign_of(f->beta[(size_t)k * p + j]);
                if (sg == 0 && enter && f->strong[j])
                    sg = entering_sign(f, k, j);
                if (sg == 0)
                    continue;
            } else if (k + 1 == K) {
                continue;
            }
            if (m == f->nv_cap)
                return false;
            f->vk[m] = k;
            f->vj[m] = (uint32_t)j;
            f->vs[m] = sg;
            m++;
        }
    f->nv = m;
    return true;
}

/* Whether the factor's variables are still the non-zero coefficients, signs and all. */
static bool newton_vars_current(const fitter *f)
{
    size_t p = f->p, kp = (size_t)f->K * p, nz = 0, coef = 0;
    for (size_t q = 0; q < kp; q++)
        nz += f->beta[q] != 0;
    for (size_t a = 0; a < f->nv; a++) {
        if (f->vj[a] == p)
            continue;
        if (sign_of(f->beta[(size_t)f->vk[a] * p + f->vj[a]]) != f->vs[a])
            return false;
        coef++;
    }
    return coef == nz;
}

/* The probabilities p_ik (class-major) at η, the softmax cache current, into f->prob; with
 * resid, the residuals 1{y_i = k} − p_ik instead, into f->et as scratch (the same p_ik, bit
 * for bit: a step needs only those, a factorisation or an append the probabilities). */
static void newton_probs(fitter *f, bool resid)
{
    size_t n = f->n;
    uint32_t K = f->K;
    for (uint32_t k = 0; k < K; k++) {
        double *o = (resid ? f->et : f->prob) + (size_t)k * n;
        for (size_t i = 0; i < n; i++) {
            double pk = f->ex[i * K + k] / f->sum[i];
            o[i] = resid ? (f->y[i] == k) - pk : pk;
        }
    }
}

/* The gradient of the objective in the Newton variables (f->hg; the penalty's from the signs)
 * from newton_probs's residuals. */
static void newton_grad(fitter *f, double lambda)
{
    size_t n = f->n, p = f->p, m = f->nv;
    double la = lambda * f->alpha, l2 = lambda * (1 - f->alpha);
    const double *R = f->et;
    double *g = f->hg;
    for (size_t a = 0; a < m; a++) {
        uint32_t ka = f->vk[a], ja = f->vj[a];
        const double *za = ja < p ? f->z + (size_t)ja * n : f->one, *ra = R + (size_t)ka * n;
        double s0 = 0, s1 = 0, s2 = 0, s3 = 0;
        size_t i = 0;
        for (; i + 4 <= n; i += 4) {
            s0 += za[i] * ra[i];
            s1 += za[i + 1] * ra[i + 1];
            s2 += za[i + 2] * ra[i + 2];
            s3 += za[i + 3] * ra[i + 3];
        }
        for (; i < n; i++)
            s0 += za[i] * ra[i];
        g[a] = -((s0 + s1) + (s2 + s3)) / (double)n;
        if (ja < p)
            g[a] += f->vs[a] * la + l2 * f->beta[(size_t)ka * p + ja];
    }
}

/* The Hessian of the objective in the Newton variables at η (the softmax cache current), factored
 * (UᵀU, upper, in f->hess, row stride nv_cap); false when it cannot be (f->fac_ok tells). The
 * variables are first ordered by class (a stable counting sort: appends may have mixed them). */
static bool newton_factor(fitter *f, double lambda)
{
    size_t n = f->n, p = f->p, m = f->nv, S = f->nv_cap;
    uint32_t K = f->K;
    double l2 = lambda * (1 - f->alpha), *P = f->prob, *H = f->hess, *u = f->hu, *cls = f->hc;
    double *dg = f->hd;
    f->fac_ok = false;
    newton_probs(f, false);
    bool sorted = true;
    for (size_t a = 1; a < m && sorted; a++)
        sorted = f->vk[a - 1] <= f->vk[a];
    if (!sorted) { /* through the Hessian's rows as scratch (rebuilt below) */
        uint32_t *tk = (uint32_t *)(void *)H, *tj = tk + m;
        double *ts = H + m;
        size_t q = 0;
        for (uint32_t k = 0; k < K; k++)
            for (size_t a = 0; a < m; a++)
                if (f->vk[a] == k) {
                    tk[q] = k;
                    tj[q] = f->vj[a];
                    ts[q] = f->vs[a];
                    q++;
                }
        memcpy(f->vk, tk, m * sizeof *tk);
        memcpy(f->vj, tj, m * sizeof *tj);
        memcpy(f->vs, ts, m * sizeof *ts);
    }
    for (uint32_t k = 0, a = 0; k < K; k++) {
        while (a < m && f->vk[a] == k)
            a++;
        f->vend[k] = a;
    }
    /* The upper triangle, sample by sample: H_ab += A_i[k_a][k_b] u_a u_b with
     * A_i = diag(p_i) − p_i p_iᵀ and u_a = z_{i, j_a} (1 for an intercept); along a row the
     * factor A_i[k_a][k_b] u_a is constant within each class's range and the update is an
     * axpy. Every entry sums its samples in order; HESS_BLOCK samples at a time, so that an
     * entry is loaded and stored once per block (the same additions in the same order). */
    for (size_t a = 0; a < m; a++)
        memset(H + a * S + a, 0, (m - a) * sizeof *H);
    size_t i = 0;
    for (; i + HESS_BLOCK <= n; i += HESS_BLOCK) {
        double *u0 = u, *u1 = u + m, *u2 = u + 2 * m, *u3 = u + 3 * m;
        for (size_t a = 0; a < m; a++) {
            const double *za = f->vj[a] < p ? f->z + (size_t)f->vj[a] * n + i : f->one;
            u0[a] = za[0], u1[a] = za[1], u2[a] = za[2], u3[a] = za[3];
        }
        for (size_t a = 0; a < m; a++) {
            uint32_t ka = f->vk[a];
            for (size_t r = 0; r < HESS_BLOCK; r++) {
                double pa = P[(size_t)ka * n + i + r], *cr = cls + r * K, ua = u[r * m + a];
                for (uint32_t l = ka; l < K; l++)
                    cr[l] = (l == ka ? pa * (1 - pa) : -pa * P[(size_t)l * n + i + r]) * ua;
            }
            double *h = H + a * S;
            size_t b = a;
            for (uint32_t l = ka; l < K; l++) {
                double c0 = cls[l], c1 = cls[K + l], c2 = cls[2 * K + l], c3 = cls[3 * K + l];
                for (size_t e = f->vend[l]; b < e; b++)
                    h[b] = h[b] + c0 * u0[b] + c1 * u1[b] + c2 * u2[b] + c3 * u3[b];
            }
        }
    }
    for (; i < n; i++) {
        for (size_t a = 0; a < m; a++)
            u[a] = f->vj[a] < p ? f->z[(size_t)f->vj[a] * n + i] : 1.0;
        for (size_t a = 0; a < m; a++) {
            uint32_t ka = f->vk[a];
            double pa = P[(size_t)ka * n + i];
            for (uint32_t l = ka; l < K; l++)
                cls[l] = (l == ka ? pa * (1 - pa) : -pa * P[(size_t)l * n + i]) * u[a];
            double *h = H + a * S;
            size_t b = a;
            for (uint32_t l = ka; l < K; l++) {
                double c = cls[l];
                for (size_t e = f->vend[l]; b < e; b++)
                    h[b] += c * u[b];
            }
        }
    }
    double hmax = 0;
    for (size_t a = 0; a < m; a++) {
        for (size_t b = a; b < m; b++)
            H[a * S + b] /= (double)n;
        if (f->vj[a] < p)
            H[a * S + a] += l2;
        if (H[a * S + a] > hmax)
            hmax = H[a * S + a];
    }
    /* Cholesky of H + μI, μ tiny and raised while a pivot fails (at α = 1 a feature whose K
     * coefficients are all non-zero has a flat direction); the lower triangle keeps H for a
     * retry, dg its diagonal. */
    for (size_t a = 0; a < m; a++) {
        dg[a] = H[a * S + a];
        for (size_t b = a + 1; b < m; b++)
            H[b * S + a] = H[a * S + b];
    }
    double mu = NEWTON_DAMP * hmax;
    for (int tries = 0; tries < NEWTON_DAMP_TRIES; tries++, mu *= 1e3) {
        if (tries > 0)
            for (size_t a = 0; a < m; a++) {
                H[a * S + a] = dg[a];
                for (size_t b = a + 1; b < m; b++)
                    H[a * S + b] = H[b * S + a];
            }
        if (cholesky_upper(H, m, S, mu)) {
            f->fac_ok = true;
            f->fac_mu = mu;
            break;
        }
    }
    return f->fac_ok;
}

/* Appends the zero coefficient (k, j) with sign sg to the factor: its Hessian column at
 * f->prob (n m multiply-adds) and one forward substitution (m²/2). False when it cannot be
 * (no room, or the new pivot is not positive: the factor being of an older point, the
 * bordered matrix need not be positive definite); the factor is then left as it was. */
static bool newton_append(fitter *f, double lambda, uint32_t k, size_t j, double sg)
{
    size_t n = f->n, p = f->p, m = f->nv, S = f->nv_cap;
    double *H = f->hess, *c = f->hu, *P = f->prob;
    const double *zj = f->z + j * n, *pk = P + (size_t)k * n;
    if (m == S)
        return false;
    /* c_a = Σ_i A_i[k_a][k] z_{i, j_a} z_ij / n: four variables at a time, each its own sum in
     * order of the samples (a term subtracted is the same as its negation added, and the
     * negation is exact), so that four chains of additions run side by side */
    size_t a0 = 0;
    for (; a0 + 4 <= m; a0 += 4) {
        const double *za[4], *pa[4];
        double sgn[4], sum[4] = {0, 0, 0, 0};
        bool same[4];
        for (size_t r = 0; r < 4; r++) {
            uint32_t ka = f->vk[a0 + r];
            za[r] = f->vj[a0 + r] < p ? f->z + (size_t)f->vj[a0 + r] * n : f->one;
            pa[r] = P + (size_t)ka * n;
            same[r] = ka == k;
            sgn[r] = same[r] ? 1.0 : -1.0;
        }
        for (size_t i = 0; i < n; i++) {
            double q = pk[i], w = 1 - pk[i], zz = zj[i];
            /* same class: pk (1 − pk) (pa is pk); else pa pk */
            sum[0] += sgn[0] * (pa[0][i] * (same[0] ? w : q) * za[0][i] * zz);
            sum[1] += sgn[1] * (pa[1][i] * (same[1] ? w : q) * za[1][i] * zz);
            sum[2] += sgn[2] * (pa[2][i] * (same[2] ? w : q) * za[2][i] * zz);
            sum[3] += sgn[3] * (pa[3][i] * (same[3] ? w : q) * za[3][i] * zz);
        }
        for (size_t r = 0; r < 4; r++)
            c[a0 + r] = sum[r] / (double)n;
    }
    for (size_t a = a0; a < m; a++) {
        uint32_t ka = f->vk[a];
        const double *za = f->vj[a] < p ? f->z + (size_t)f->vj[a] * n : f->one;
        const double *pa = P + (size_t)ka * n;
        double s = 0;
        if (ka == k)
            for (size_t i = 0; i < n; i++)
                s += pk[i] * (1 - pk[i]) * za[i] * zj[i];
        else
            for (size_t i = 0; i < n; i++)
                s -= pa[i] * pk[i] * za[i] * zj[i];
        c[a] = s / (double)n;
    }
    double hnn = 0;
    for (size_t i = 0; i < n; i++)
        hnn += pk[i] * (1 - pk[i]) * zj[i] * zj[i];
    hnn = hnn / (double)n + lambda * (1 - f->alpha) + f->fac_mu;
    for (size_t a = 0; a < m; a++) { /* Uᵀc = h, by columns */
        c[a] /= H[a * S + a];
        for (size_t b = a + 1; b < m; b++)
            c[b] -= H[a * S + b] * c[a];
    }
    double d = hnn;
    for (size_t a = 0; a < m; a++)
        d -= c[a] * c[a];
    if (!(d > NEWTON_DAMP * hnn))
        return false;
    for (size_t a = 0; a < m; a++)
        H[a * S + m] = c[a];
    H[m * S + m] = sqrt(d);
    f->vk[m] = k;
    f->vj[m] = (uint32_t)j;
    f->vs[m] = sg;
    f->nv = m + 1;
    return true;
}

/* Removes variable r from the factor: its column deleted, the rows below made triangular
 * again by Givens rotations (the product UᵀU is that of the other variables). O(m²). */
static void newton_remove(fitter *f, size_t r)
{
    size_t m = f->nv, S = f->nv_cap;
    double *H = f->hess;
    for (size_t i = 0; i < m; i++) {
        double *row = H + i * S;
        memmove(row + r, row + r + 1, (m - 1 - r) * sizeof *row);
    }
    for (size_t c = r; c + 1 < m; c++) {
        double *rc = H + c * S, *rn = H + (c + 1) * S;
        double x = rc[c], y = rn[c], h = hypot(x, y);
        double cs = x / h, sn = y / h;
        for (size_t q = c; q + 1 < m; q++) {
            double a = rc[q], b = rn[q];
            rc[q] = cs * a + sn * b;
            rn[q] = -sn * a + cs * b;
        }
        rn[c] = 0;
    }
    memmove(f->vk + r, f->vk + r + 1, (m - 1 - r) * sizeof *f->vk);
    memmove(f->vj + r, f->vj + r + 1, (m - 1 - r) * sizeof *f->vj);
    memmove(f->vs + r, f->vs + r + 1, (m - 1 - r) * sizeof *f->vs);
    f->nv = m - 1;
}

/* The first half of the Newton direction: f->hd = y with Uᵀy = −g; returns the decrement
 * gᵀ(UᵀU)⁻¹g = |y|² (enough to decide convergence; newton_back finishes the direction). */
static double newton_fwd(fitter *f)
{
    size_t m = f->nv, S = f->nv_cap;
    const double *H = f->hess, *g = f->hg;
    double *d = f->hd, dec = 0;
    for (size_t a = 0; a < m; a++)
        d[a] = -g[a];
    for (size_t a = 0; a < m; a++) { /* Uᵀy = −g, by columns */
        d[a] /= H[a * S + a];
        for (size_t b = a + 1; b < m; b++)
            d[b] -= H[a * S + b] * d[a];
    }
    for (size_t a = 0; a < m; a++)
        dec += d[a] * d[a];
    return dec;
}

/* The Newton direction f->hd = −(UᵀU)⁻¹ g from newton_fwd's y: U d = y. */
static void newton_back(fitter *f)
{
    size_t m = f->nv, S = f->nv_cap;
    const double *H = f->hess;
    double *d = f->hd;
    /* Four partial sums taken from the far end, so that the value just solved, d[a + 1],
     * enters last: the products of the older values do not wait for it, and each row waits
     * only on one multiply-add, the sums' combination and the division. */
    for (size_t a = m; a-- > 0;) {
        const double *u = H + a * S;
        double s0 = 0, s1 = 0, s2 = 0, s3 = 0;
        size_t b = m;
        for (; b >= a + 5; b -= 4) {
            s0 += u[b - 1] * d[b - 1];
            s1 += u[b - 2] * d[b - 2];
            s2 += u[b - 3] * d[b - 3];
            s3 += u[b - 4] * d[b - 4];
        }
        for (; b > a + 1; b--)
            s0 += u[b - 1] * d[b - 1];
        d[a] = (d[a] - ((s0 + s1) + (s2 + s3))) / u[a];
    }
}

/* The step along f->hd, halved until the objective (*obj now) falls, each coefficient that
 * would leave its sign stopping at 0 (the step projected onto the signs' orthant). Returns
 * whether a step was taken. */
static bool newton_line(fitter *f, double lambda, double *obj)
{
    size_t n = f->n, p = f->p, m = f->nv;
    uint32_t K = f->K;
    const double *d = f->hd;
    double *et = f->et, *dl = f->hu, *col = f->deta, pen0 = total_penalty(f), o0 = *obj;
    for (int h = 0; h <= MAX_HALVINGS; h++) {
        double t = ldexp(1.0, -h), pen = pen0;
        for (size_t a = 0; a < m; a++) {
            uint32_t ka = f->vk[a], ja = f->vj[a];
            double delta = t * d[a];
            if (ja < p) {
                double b = f->beta[(size_t)ka * p + ja], nb = b + delta;
                if (f->vs[a] * nb <= 0)
                    nb = 0;
                delta = nb - b;
                pen += f->alpha * (fabs(nb) - fabs(b)) + 0.5 * (1 - f->alpha) * (nb * nb - b * b);
            }
            dl[a] = delta;
        }
        /* η + Z Δ class by class in a contiguous column (each entry takes its class's
         * variables in their order, as a pass over the variables would) */
        for (uint32_t k = 0; k < K; k++) {
            for (size_t i = 0; i < n; i++)
                col[i] = f->eta[i * K + k];
            /* the class's variables four at a time (the same additions, in order) */
            const double *zs[4];
            double ds[4];
            size_t nq = 0;
            for (size_t a = 0; a <= m; a++) {
                if (a < m && f->vk[a] == k) {
                    zs[nq] = f->vj[a] < p ? f->z + (size_t)f->vj[a] * n : f->one;
                    ds[nq++] = dl[a];
                }
                if (nq == 4) {
                    for (size_t i = 0; i < n; i++)
                        col[i] = col[i] + zs[0][i] * ds[0] + zs[1][i] * ds[1] + zs[2][i] * ds[2] +
                                 zs[3][i] * ds[3];
                    nq = 0;
                } else if (a == m) {
                    for (size_t q = 0; q < nq; q++)
                        for (size_t i = 0; i < n; i++)
                            col[i] += zs[q][i] * ds[q];
                }
            }
            for (size_t i = 0; i < n; i++)
                et[i * K + k] = col[i];
        }
        double lo = loss_at(f, et), o = lo + lambda * pen;
        if (!(o < o0 - DESCENT_SLACK * (1 + fabs(o0))))
            continue;
        for (size_t a = 0; a < m; a++) {
            uint32_t ka = f->vk[a], ja = f->vj[a];
            if (ja == p) {
                f->beta0[ka] += t * d[a];
                continue;
            }
            double *bp = f->beta + (size_t)ka * p + ja, nb = *bp + t * d[a];
            *bp = f->vs[a] * nb <= 0 ? 0 : nb;
        }
        take_trial(f, lo);
        f->grad_ok = false;
        *obj = lo + lambda * total_penalty(f);
        return true;
    }
    return false;
}

/* Newton's method on the smooth problem that holds the coefficients' signs (the zeros at 0),
 * from the current state; *obj: the objective, updated. The factor of the Hessian is kept
 * while the variables are the same (a simplified Newton iteration: the gradient is new at
 * every step) and rebuilt when the decrement does not fall fast enough or a step fails; a
 * coefficient that reaches 0 leaves the variables (the factor downdated). With enter, the zero
 * coefficients of the strong set whose KKT condition fails (f->grad current) join them first
 * (the factor bordered). Returns true when converged: the decrement's half (the decrease the
 * quadratic model predicts) is at most tol × the objective; false when a step fails on a
 * fresh factor, there are too many variables, or after NEWTON_ITERS steps. The caller then
 * checks the zero coefficients' KKT conditions. */
static bool newton_solve(fitter *f, double lambda, double *obj, bool enter)
{
    f->lambda_now = lambda;
    if (!f->cached)
        softmax_fresh(f);
    if (!f->fac_ok || !newton_vars_current(f)) {
        f->fac_ok = false;
        if (!newton_vars(f, enter))
            return false;
    } else if (enter) {
        newton_probs(f, false);
        for (uint32_t k = 0; k < f->K && f->fac_ok; k++)
            for (size_t j = 0; j < f->p && f->fac_ok; j++) {
                double sg;
                if (!f->strong[j] || f->beta[(size_t)k * f->p + j] != 0 ||
                    (sg = entering_sign(f, k, j)) == 0)
                    continue;
                if (!newton_append(f, lambda, k, j, sg)) {
                    f->fac_ok = false;
                    if (!newton_vars(f, true))
                        return false;
                }
            }
    }
    double dec_prev = INFINITY;
    for (int it = 0; it < NEWTON_ITERS; it++) {
        bool fresh = false;
        newton_probs(f, true);
        newton_grad(f, lambda);
        if (!f->fac_ok) {
            if (!newton_factor(f, lambda))
                return false;
            newton_grad(f, lambda); /* the order of the variables may have changed */
            fresh = true;
        }
        double dec = newton_fwd(f);
        if (!(dec > 2 * NEWTON_TOL * f->tol * *obj))
            return true;
        if (!fresh && !(dec <= NEWTON_SLOW * dec_prev)) { /* the old factor is too far off */
            if (!newton_factor(f, lambda))
                return false;
            newton_grad(f, lambda);
            fresh = true;
            dec = newton_fwd(f);
        }
        newton_back(f);
        if (!newton_line(f, lambda, obj)) {
            f->fac_ok = false;
            if (fresh)
                return false;
            continue;
        }
        for (size_t a = f->nv; a-- > 0;) /* the coefficients that reached 0 leave */
            if (f->vj[a] < f->p && f->beta[(size_t)f->vk[a] * f->p + f->vj[a]] == 0)
                newton_remove(f, a);
        dec_prev = dec;
    }
    return false;
}

/* After Newton's method converged: a feature whose K coefficients are all non-zero may sit
 * inside a flat stretch of the penalty (at α = 1 with as many positive as negative
 * coefficients, any common shift between the two middle values leaves the objective
 * unchanged). Coordinate descent stops at an end of it, where one coefficient is 0; this
 * moves there too (the shift to the coefficient value of smallest magnitude among those that
 * do not raise the penalty beyond rounding), so the solution is as sparse. The
 * probabilities do not change (η's rows shift by a common value); the coefficient that
 * becomes 0 leaves Newton's variables (the factor downdated). */
static void newton_sparsify(fitter *f)
{
    size_t p = f->p, n = f->n;
    uint32_t K = f->K;
    for (size_t j = 0; j < p; j++) {
        const double *b = f->beta + j;
        bool all = f->strong[j];
        for (uint32_t k = 0; k < K && all; k++)
            all = b[(size_t)k * p] != 0;
        if (!all)
            continue;
        double p0 = 0;
        for (uint32_t k = 0; k < K; k++)
            p0 += f->alpha * fabs(b[(size_t)k * p]) +
                  0.5 * (1 - f->alpha) * b[(size_t)k * p] * b[(size_t)k * p];
        double bar = p0 + DESCENT_SLACK * (1 + p0), best = 0;
        bool found = false;
        for (uint32_t m = 0; m < K; m++) {
            double c = b[(size_t)m * p], pc = 0;
            for (uint32_t k = 0; k < K; k++) {
                double d = b[(size_t)k * p] - c;
                pc += f->alpha * fabs(d) + 0.5 * (1 - f->alpha) * d * d;
            }
            if (pc <= bar && (!found || fabs(c) < fabs(best))) {
                best = c;
                found = true;
            }
        }
        if (!found)
            continue;
        for (uint32_t k = 0; k < K; k++) {
            double *bk = f->beta + (size_t)k * p + j;
            *bk = *bk == best ? 0 : *bk - best;
        }
        const double *zc = f->z + j * n;
        for (size_t i = 0; i < n; i++)
            f->deta[i] = best * zc[i];
        shift_rows(f, f->deta, 1);
        for (size_t a = f->nv; f->fac_ok && a-- > 0;)
            if (f->vj[a] == j && f->beta[(size_t)f->vk[a] * p + j] == 0)
                newton_remove(f, a);
    }
}

/* The work of a factorisation for the current non-zero coefficients (n m²/2 + m³/6, in
 * multiply-adds) and of a cycle that made `passes` passes over ns features. */
static double newton_work(const fitter *f)
{
    size_t nz = 0, kp = (size_t)f->K * f->p;
    for (size_t q = 0; q < kp; q++)
        nz += f->beta[q] != 0;
    double mv = (double)(nz + f->K - 1), nd = (double)f->n;
    return nd * mv * mv / 2 + mv * mv * mv / 6;
}

static double cycle_work(const fitter *f, uint32_t passes)
{
    size_t ns = 0;
    for (size_t j = 0; j < f->p; j++)
        ns += f->strong[j];
    return (double)passes * (double)f->n * (double)ns + (double)f->K * (double)f->n * CYCLE_FIXED;
}

/* Cycles over the classes of the strong set at λ until the penalised objective settles (or
 * *passes reaches max_iter), switching to Newton's method (newton_solve) when its signs hold
 * and it is expected to be cheaper (see below). Returns 0: not converged, 1: converged by the
 * cycles, 2: converged by Newton (the zero coefficients' KKT conditions still to check). With
 * newton_first, Newton's method is tried before the first cycle. */
static int fitter_cycles(fitter *f, double lambda, uint32_t *passes, bool newton_first, bool enter)
{
    double obj = (f->cached ? f->loss : softmax_fresh(f)) + lambda * total_penalty(f);
    double loss = obj, prev_delta = -1;
    size_t kp = (size_t)f->K * f->p;
    if (newton_first && newton_solve(f, lambda, &obj, enter))
        return 2;
    loss = f->loss;
    for (;;) {
        uint32_t passes_before = *passes;
        memcpy(f->s0, f->beta, kp * sizeof *f->beta);
        memcpy(f->s0 + kp, f->beta0, f->K * sizeof *f->beta0);
        for (uint32_t k = 0; k < f->K; k++)
            class_step(f, k, lambda, passes, &loss);
        /* Adding c_j to feature j's coefficients of every class leaves the probabilities
         * alone; the shift minimising the penalty removes that flat direction, along which
         * coordinate descent would crawl. */
        for (size_t j = 0; j < f->p; j++) {
            if (!f->strong[j])
                continue; /* all its coefficients are 0 */
            double c = center_shift(f->beta + j, f->p, f->K, f->alpha);
            if (c == 0)
                continue;
            for (uint32_t k = 0; k < f->K; k++)
                f->beta[(size_t)k * f->p + j] -= c;
            double *d = f->deta;
            const double *zc = f->z + j * f->n;
            for (size_t i = 0; i < f->n; i++)
                d[i] = c * zc[i];
            shift_rows(f, d, 1);
        }
        double now = loss + lambda * total_penalty(f); /* centring keeps the loss */
        double cw = cycle_work(f, *passes - passes_before);
        f->work_now += cw;
        if (fabs(obj - now) <= f->tol * now)
            return 1;
        /* Newton when the signs held through the cycle and the cycles still expected (from
         * the last two decreases' ratio) cost more than a factorisation. */
        double delta = obj - now;
        bool newton = false;
        if (f->newton_on && prev_delta > 0 && delta > 0 && same_pattern(f, f->s0)) {
            double rho = delta / prev_delta;
            double left = rho >= 1 ? 1e30 : log(f->tol * now / delta) / log(rho);
            newton = left * cw > NEWTON_GAIN * newton_work(f);
        }
        prev_delta = delta;
        if (newton) {
            if (newton_solve(f, lambda, &now, false))
                return 2;
            prev_delta = -1;
            loss = f->loss;
        }
        obj = now;
        if (*passes >= f->max_iter)
            return 0;
    }
}

/* The secant predictor along the path: when the current solution (at λ1) and the one before
 * it (at λ2) were both found by Newton's method with the same signs, the start for λ becomes
 * β1 + t (β1 − β2), t = log(λ / λ1) / log(λ1 / λ2) (1 on the geometric path), intercepts too,
 * kept only when no coefficient changes sign and the objective at λ falls; on a smooth stretch
 * of the path the start is then off by the second order of the step in log λ instead of the
 * first, which saves Newton about one step. The current solution becomes bprev either way. */
static void path_predict(fitter *f, double lambda)
{
    size_t n = f->n, p = f->p, kp = (size_t)f->K * p;
    uint32_t K = f->K;
    bool use = f->newton_on && f->sol_newton && f->prev_newton && f->lam1 > 0 && f->lam2 > 0 &&
               f->lam1 != f->lam2 && same_pattern(f, f->bprev);
    double t = use ? log(lambda / f->lam1) / log(f->lam1 / f->lam2) : 0;
    double *b1 = f->s0, *d = f->bprev; /* b1: a copy of the current solution; d: the step */
    memcpy(b1, f->beta, kp * sizeof *b1);
    memcpy(b1 + kp, f->beta0, K * sizeof *b1);
    if (use && t > 0 && t <= 2) {
        for (size_t q = 0; q < kp + K; q++) {
            d[q] = t * (b1[q] - d[q]);
            if (q < kp && b1[q] != 0 && (b1[q] + d[q] > 0) != (b1[q] > 0))
                use = false;
        }
        if (use) {
            if (!f->cached)
                softmax_fresh(f);
            double o0 = f->loss + lambda * total_penalty(f);
            double *et = f->et;
            memcpy(et, f->eta, n * K * sizeof *et);
            for (uint32_t k = 0; k < K; k++) {
                for (size_t j = 0; j < p; j++) {
                    double dq = d[(size_t)k * p + j];
                    if (b1[(size_t)k * p + j] == 0 || dq == 0)
                        continue;
                    const double *zj = f->z + j * n;
                    for (size_t i = 0; i < n; i++)
                        et[i * K + k] += zj[i] * dq;
                }
                for (size_t i = 0; i < n; i++)
                    et[i * K + k] += d[kp + k];
            }
            for (size_t q = 0; q < kp; q++)
                if (b1[q] != 0)
                    f->beta[q] = b1[q] + d[q];
            for (uint32_t k = 0; k < K; k++)
                f->beta0[k] = b1[kp + k] + d[kp + k];
            double lo = loss_at(f, et);
            if (lo + lambda * total_penalty(f) < o0) {
                take_trial(f, lo);
                f->grad_ok = false;
            } else {
                memcpy(f->beta, b1, kp * sizeof *b1);
                memcpy(f->beta0, b1 + kp, K * sizeof *b1);
            }
        }
    }
    memcpy(f->bprev, b1, (kp + K) * sizeof *b1);
    f->prev_newton = f->sol_newton;
    f->lam2 = f->lam1;
}

/* Fits λ from the current state; lambda_prev is the λ of that state's fit (0 when there was
 * none). Sequential strong rule (Tibshirani et al. 2012, for the multinomial as glmnet: by
 * feature, over the classes): coordinate descent visits only the features with a non-zero
 * coefficient or max_k |g_kj| ≥ α(2λ − λ_prev), g the gradient at the previous fit (α λ when
 * there is no previous λ or it is smaller). Once it settles, the KKT conditions of the others
 * (max_k |g_kj| ≤ αλ, their coefficients being 0) are checked on the new fit; any that fails
 * joins the set and the fit goes on, until none fails. Returns whether it converged. */
static bool fitter_solve(fitter *f, double lambda, double lambda_prev)
{
    uint32_t passes = 0;
    bool converged;
    double la = f->alpha * lambda;
    double thr = lambda_prev > lambda ? f->alpha * (2 * lambda - lambda_prev) : la;
    if (!f->grad_ok)
        fitter_gradients(f, 2);
    for (size_t j = 0; j < f->p; j++) {
        bool nz = false;
        for (uint32_t k = 0; k < f->K && !nz; k++)
            nz = f->beta[(size_t)k * f->p + j] != 0;
        f->strong[j] = f->sd[j] != 0 && (nz || grad_max(f, j) >= thr);
    }
    path_predict(f, lambda);
    bool newton_first = f->newton_on && (f->newton_last || (f->fac_ok && newton_vars_current(f)) ||
                                         f->work_last > NEWTON_GAIN * newton_work(f));
    bool enter = false;
    f->work_now = 0;
    int kkt_fails = 0;
    for (;;) {
        int how = fitter_cycles(f, lambda, &passes, newton_first, enter);
        converged = how != 0;
        if (how != 0 && f->newton_on)
            newton_sparsify(f);
        fitter_gradients(f, 2); /* the next λ's screening needs them all */
        f->grad_ok = true;
        newton_first = enter = false;
        f->newton_last = how == 2;
        size_t added = 0;
        for (size_t j = 0; j < f->p; j++)
            if (!f->strong[j] && f->sd[j] != 0 && grad_max(f, j) > la) {
                f->strong[j] = 1;
                added++;
            }
        if (how == 2) {
            /* Newton held the zeros at 0: their KKT conditions, as a cycle would see them */
            bool ok = added == 0;
            for (size_t j = 0; j < f->p && ok; j++)
                for (uint32_t k = 0; k < f->K && f->strong[j] && ok; k++)
                    ok = f->beta[(size_t)k * f->p + j] != 0 ||
                         fabs(f->grad[(size_t)k * f->p + j]) <= la * (1 + f->kkt_slack) ||
                         flat_zero(f, k, j);
            if (ok)
                break;
            converged = false;
            f->newton_last = false;
            if (passes >= f->max_iter)
                break;
            /* the failing ones join Newton's variables; after KKT_ENTER_MAX rounds the
             * cycles take over */
            newton_first = enter = ++kkt_fails <= KKT_ENTER_MAX;
            continue;
        }
        if (added == 0)
            break;
        f->newton_last = false;
        if (passes >= f->max_iter) {
            converged = false;
            break;
        }
    }
    f->work_last = f->work_now;
    f->lam1 = lambda;
    f->sol_newton = converged && f->newton_last;
    double m = 0;
    for (uint32_t k = 0; k < f->K; k++)
        m += f->beta0[k];
    m /= f->K;
    for (uint32_t k = 0; k < f->K; k++)
        f->beta0[k] -= m;
    if (m != 0)
        shift_rows(f, &m, 0);
    return converged;
}

/* argmax_k of β0k + βkᵀz for raw x, standardized with mean and sd; probs optional. */
static uint32_t predict_raw(uint32_t K, size_t p, const double *mean, const double *sd,
                            const double *beta0, const double *beta, const double *x, double *probs)
{
    uint32_t best = 0;
    double best_eta = 0, mx = 0;
    for (uint32_t k = 0; k < K; k++) {
        double e = beta0[k];
        const double *b = beta + (size_t)k * p;
        for (size_t j = 0; j < p; j++)
            if (sd[j] > 0 && b[j] != 0)
                e += b[j] * ((x[j] - mean[j]) / sd[j]);
        if (probs)
            probs[k] = e;
        if (k == 0 || e > best_eta) {
            best_eta = e;
            best = k;
        }
    }
    if (probs) {
        double sum = 0;
        mx = best_eta;
        for (uint32_t k = 0; k < K; k++) {
            probs[k] = exp(probs[k] - mx);
            sum += probs[k];
        }
        for (uint32_t k = 0; k < K; k++)
            probs[k] /= sum;
    }
    return best;
}

/* ---- argument checks ---- */

static affect_status check_options(const affect_rmlr_options *o, bool cv, affect_error *err)
{
    if (cv) {
        if (o->n_lambda < 1)
            return affect_fail(err, AFFECT_ERR_INVALID, "n_lambda must be at least 1");
        if (o->n_lambda > AFFECT_RMLR_MAX_LAMBDAS)
            return affect_fail(err, AFFECT_ERR_RANGE, "too many lambdas: %u (at most %u)",
                               o->n_lambda, AFFECT_RMLR_MAX_LAMBDAS);
    }
    if (!(o->lambda_min_ratio == 0 || (o->lambda_min_ratio > 0 && o->lambda_min_ratio < 1)))
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "lambda_min_ratio must be in (0, 1), or 0 for automatic, got %g",
                           o->lambda_min_ratio);
    if (cv) {
        if (o->alphas) {
            if (o->n_alpha < 1)
                return affect_fail(err, AFFECT_ERR_INVALID, "need at least 1 alpha");
            for (uint32_t a = 0; a < o->n_alpha; a++)
                if (!(o->alphas[a] >= 0 && o->alphas[a] <= 1))
                    return affect_fail(err, AFFECT_ERR_INVALID, "alpha %u = %g is not in [0, 1]", a,
                                       o->alphas[a]);
        }
        if (o->folds < 2)
            return affect_fail(err, AFFECT_ERR_INVALID, "need at least 2 folds, got %u", o->folds);
        if (o->threads < 1 || o->threads > AFFECT_RMLR_MAX_THREADS)
            return affect_fail(err, AFFECT_ERR_INVALID, "threads must be from 1 to %u, got %u",
                               AFFECT_RMLR_MAX_THREADS, o->threads);
    }
    if (o->max_iter < 1)
        return affect_fail(err, AFFECT_ERR_INVALID, "max_iter must be at least 1");
    if (!(o->tol > 0 && isfinite(o->tol)))
        return affect_fail(err, AFFECT_ERR_INVALID, "tol must be a positive finite number, got %g",
                           o->tol);
    if (o->solver > AFFECT_RMLR_SOLVER_CD)
        return affect_fail(err, AFFECT_ERR_INVALID, "solver must be 0 (Newton) or 1 (CD), got %u",
                           o->solver);
    return AFFECT_OK;
}

static affect_status check_sizes(size_t n, size_t p, uint32_t K, affect_error *err)
{
    size_t np;
    if (n < 1)
        return affect_fail(err, AFFECT_ERR_INVALID, "need at least 1 sample");
    if (p < 1)
        return affect_fail(err, AFFECT_ERR_INVALID, "need at least 1 feature");
    if (p > AFFECT_RMLR_MAX_FEATURES)
        return affect_fail(err, AFFECT_ERR_RANGE, "too many features: %zu (at most %u)", p,
                           AFFECT_RMLR_MAX_FEATURES);
    if (n > AFFECT_RMLR_MAX_SAMPLES || !affect_mul_size(n, p, &np) ||
        !affect_mul_size(np, sizeof(double), &np))
        return affect_fail(err, AFFECT_ERR_RANGE, "too many samples: %zu", n);
    if (K < 2)
        return affect_fail(err, AFFECT_ERR_INVALID, "need at least 2 classes, got %u", K);
    if (K > AFFECT_RMLR_MAX_CLASSES)
        return affect_fail(err, AFFECT_ERR_INVALID, "at most %u classes, got %u",
                           AFFECT_RMLR_MAX_CLASSES, K);
    return AFFECT_OK;
}

/* Labels in range, values finite; counts[k] (K values) receives the class sizes. */
static affect_status check_data(const double *x, size_t n, size_t p, const uint32_t *y, uint32_t K,
                                size_t *counts, affect_error *err)
{
    for (size_t i = 0; i < n; i++)
        if (y[i] >= K)
            return affect_fail(err, AFFECT_ERR_INVALID, "sample %zu: class %u out of range 0 .. %u",
                               i, y[i], K - 1);
    for (size_t i = 0; i < n; i++)
        for (size_t j = 0; j < p; j++)
            if (!isfinite(x[i * p + j]))
                return affect_fail(err, AFFECT_ERR_INVALID, "sample %zu, feature %zu is not finite",
                                   i, j);
    for (uint32_t k = 0; k < K; k++)
        counts[k] = 0;
    for (size_t i = 0; i < n; i++)
        counts[y[i]]++;
    for (uint32_t k = 0; k < K; k++)
        if (counts[k] == 0)
            return affect_fail(err, AFFECT_ERR_INVALID, "class %u has no sample", k);
    return AFFECT_OK;
}

static double min_ratio(const affect_rmlr_options *o, size_t n, size_t p)
{
    return o->lambda_min_ratio > 0 ? o->lambda_min_ratio : n > p ? 1e-4 : 1e-2;
}

/* n_lambda values log-spaced from lmax down to lmax·ratio. */
static void make_path(double lmax, double ratio, uint32_t n_lambda, double *out)
{
    for (uint32_t l = 0; l < n_lambda; l++)
        out[l] = n_lambda == 1 ? lmax : lmax * exp(log(ratio) * (double)l / (double)(n_lambda - 1));
}

affect_status affect_rmlr_fit_path(const double *x, size_t n, size_t p, const uint32_t *y,
                                   uint32_t K, double alpha, const double *lambdas,
                                   uint32_t n_lambda, const affect_rmlr_options *o,
                                   double *lambda_out, double *beta_out, double *beta0_out,
                                   uint8_t *converged_out, affect_error *err)
{
    affect_rmlr_options def;
    affect_status st;
    size_t *counts = NULL;
    double *path = NULL;
    fitter f = {0};
    if (!o) {
        affect_rmlr_options_default(&def);
        o = &def;
    }
    if ((st = check_sizes(n, p, K, err)) != AFFECT_OK)
        return st;
    if (!(alpha >= 0 && alpha <= 1))
        return affect_fail(err, AFFECT_ERR_INVALID, "alpha must be in [0, 1], got %g", alpha);
    if (n_lambda < 1)
        return affect_fail(err, AFFECT_ERR_INVALID, "need at least 1 lambda");
    if (n_lambda > AFFECT_RMLR_MAX_LAMBDAS)
        return affect_fail(err, AFFECT_ERR_RANGE, "too many lambdas: %u (at most %u)", n_lambda,
                           AFFECT_RMLR_MAX_LAMBDAS);
    if (lambdas)
        for (uint32_t l = 0; l < n_lambda; l++)
            if (!(lambdas[l] > 0 && isfinite(lambdas[l])))
                return affect_fail(err, AFFECT_ERR_INVALID,
                                   "lambda %u = %g is not a positive finite number", l, lambdas[l]);
    if ((st = check_options(o, false, err)) != AFFECT_OK)
        return st;
    counts = affect_malloc_array(K, sizeof *counts);
    path = affect_malloc_array(n_lambda, sizeof *path);
    if (!counts || !path) {
        st = affect_nomem(err);
        goto cleanup;
    }
    if ((st = check_data(x, n, p, y, K, counts, err)) != AFFECT_OK)
        goto cleanup;
    if ((st = fitter_alloc(&f, n, p, K, err)) != AFFECT_OK)
        goto cleanup;
    fitter_load(&f, x, n, y, NULL, 0, alpha, o);
    if (lambdas)
        memcpy(path, lambdas, n_lambda * sizeof *path);
    else
        make_path(lambda_max(fitter_grad_max(&f), alpha), min_ratio(o, n, p), n_lambda, path);
    for (uint32_t l = 0; l < n_lambda; l++) {
        if ((st = affect_monitor_check(o->monitor, err)) != AFFECT_OK)
            goto cleanup;
        /* At the automatic path's λ_max the intercept-only start is the exact solution (for
         * α ≥ 1e-3); solving would only add rounding noise at the threshold. */
        bool conv = (l == 0 && !lambdas && alpha >= ALPHA_FLOOR) ||
                    fitter_solve(&f, path[l], l > 0 ? path[l - 1] : 0);
        if (lambda_out)
            lambda_out[l] = path[l];
        if (beta_out)
            memcpy(beta_out + (size_t)l * K * p, f.beta, (size_t)K * p * sizeof *f.beta);
        if (beta0_out)
            memcpy(beta0_out + (size_t)l * K, f.beta0, K * sizeof *f.beta0);
        if (converged_out)
            converged_out[l] = conv;
    }
cleanup:
    fitter_free(&f);
    affect_free(counts);
    affect_free(path);
    return st;
}

/* ---- the model ---- */

void affect_rmlr_free(affect_rmlr *m)
{
    if (!m)
        return;
    affect_free(m->lambdas);
    affect_free(m);
}

/* A model with its one block of doubles allocated for K, p, L (sizes already bounded). */
static affect_status model_new(uint32_t K, size_t p, uint32_t L, affect_rmlr **out,
                               affect_error *err)
{
    size_t kp, total;
    *out = NULL;
    if (!affect_mul_size(K, p, &kp) || !affect_add_size(kp, K, &total) ||
        !affect_add_size(total, 2 * (size_t)L, &total) || !affect_add_size(total, p, &total) ||
        !affect_add_size(total, p, &total))
        return affect_fail(err, AFFECT_ERR_RANGE, "model too large");
    affect_rmlr *m = affect_calloc(1, sizeof *m);
    if (!m)
        return affect_nomem(err);
    m->lambdas = affect_calloc(total, sizeof(double));
    if (!m->lambdas) {
        affect_free(m);
        return affect_nomem(err);
    }
    m->K = K;
    m->p = p;
    m->n_lambda = L;
    m->cv_errors = m->lambdas + L;
    m->mean = m->cv_errors + L;
    m->sd = m->mean + p;
    m->beta0 = m->sd + p;
    m->beta = m->beta0 + K;
    *out = m;
    return AFFECT_OK;
}

/* ---- cross-validation ---- */

/* One cross-validation run: what every worker reads (read-only while they run), the α
 * counter and the miss counts, each α's row written by the one worker that took that α. */
typedef struct cv_run {
    const double *x;
    size_t n;
    const uint32_t *y;
    const uint32_t *fold_of;
    uint32_t folds;
    const double *alphas;
    uint32_t n_alpha, L;
    const double *paths; /* n_alpha × L */
    const affect_rmlr_options *o;
    size_t *miss;      /* n_alpha × L */
    mtx_t *lock;       /* guards next and finished; NULL when the calling thread works alone */
    uint32_t next;     /* the next α to take */
    uint32_t finished; /* workers that returned */
} cv_run;

/* A worker and its own fitter, allocated for all n rows before any worker starts. */
typedef struct cv_worker {
    cv_run *run;
    fitter f;
} cv_worker;

/* α a's folds along its path, each held-out sample's misclassifications after each λ counted
 * into row a of run->miss. */
static void cv_alpha(const cv_run *run, fitter *f, uint32_t a)
{
    const double *path = run->paths + (size_t)a * run->L;
    size_t *miss = run->miss + (size_t)a * run->L;
    for (uint32_t fo = 0; fo < run->folds; fo++) {
        fitter_load(f, run->x, run->n, run->y, run->fold_of, fo, run->alphas[a], run->o);
        for (uint32_t l = 0; l < run->L; l++) {
            if (affect_monitor_stopped(run->o->monitor))
                return; /* affect_rmlr_cv checks the monitor */
            fitter_solve(f, path[l], l > 0 ? path[l - 1] : 0);
            for (size_t i = 0; i < run->n; i++)
                if (run->fold_of[i] == fo &&
                    predict_raw(f->K, f->p, f->mean, f->sd, f->beta0, f->beta, run->x + i * f->p,
                                NULL) != run->y[i])
                    miss[l]++;
        }
    }
}

/* Takes the α values in order from the shared counter until none is left. */
static int cv_worker_main(void *arg)
{
    cv_worker *wk = arg;
    cv_run *run = wk->run;
    for (;;) {
        if (run->lock)
            mtx_lock(run->lock);
        uint32_t a = run->next < run->n_alpha ? run->next++ : run->n_alpha;
        if (a >= run->n_alpha)
            run->finished++;
        if (run->lock)
            mtx_unlock(run->lock);
        if (a >= run->n_alpha)
            return 0;
        cv_alpha(run, &wk->f, a);
        affect_monitor_step(run->o->monitor);
    }
}

/* Runs every α's cross-validation with T workers (wk, their fitters allocated): the calling
 * thread is worker 0, T − 1 threads the others. Nothing here can fail: without a lock, or for
 * each thread that cannot be created, the calling thread simply does more of the work. */
static void cv_run_all(cv_run *run, cv_worker *wk, thrd_t *th, uint32_t T)
{
    mtx_t lock;
    uint32_t started = 0;
    for (uint32_t t = 0; t < T; t++)
        wk[t].run = run;
    run->lock = NULL;
    run->next = 0;
    run->finished = 0;
    affect_monitor_report(run->o->monitor, "elastic-net alphas", 0, run->n_alpha);
    if (T > 1 && mtx_init(&lock, mtx_plain) == thrd_success) {
        run->lock = &lock;
        for (uint32_t t = 1; t < T; t++) {
            if (thrd_create(&th[t - 1], cv_worker_main, &wk[t]) != thrd_success)
                break;
            started++;
        }
    }
    cv_worker_main(&wk[0]);
    for (bool all = !run->lock; run->o->monitor && !all;) { /* keep asking the monitor */
        mtx_lock(run->lock);
        all = run->finished == started + 1;
        mtx_unlock(run->lock);
        if (!all) {
            (void)affect_monitor_stopped(run->o->monitor);
            thrd_sleep(&(struct timespec){.tv_nsec = 2000000}, NULL);
        }
    }
    for (uint32_t t = 0; t < started; t++)
        thrd_join(th[t], NULL);
    affect_monitor_flush(run->o->monitor);
    if (run->lock)
        mtx_destroy(&lock);
}

affect_status affect_rmlr_cv(const double *x, size_t n, size_t p, const uint32_t *y, uint32_t K,
                             const affect_rmlr_options *o, affect_rmlr **out, affect_error *err)
{
    static const double default_alphas[AFFECT_RMLR_DEFAULT_N_ALPHA] = {
        0.05, 0.10, 0.15, 0.20, 0.25, 0.30, 0.35, 0.40, 0.45, 0.50,
        0.55, 0.60, 0.65, 0.70, 0.75, 0.80, 0.85, 0.90, 0.95, 1.00};
    affect_rmlr_options def;
    affect_status st;
    size_t *counts = NULL, *miss = NULL, cells;
    uint32_t *fold_of = NULL, T = 0;
    double *paths = NULL;
    cv_worker *wk = NULL;
    thrd_t *th = NULL;
    affect_rmlr *m = NULL;
    *out = NULL;
    if (!o) {
        affect_rmlr_options_default(&def);
        o = &def;
    }
    if ((st = check_sizes(n, p, K, err)) != AFFECT_OK)
        return st;
    if ((st = check_options(o, true, err)) != AFFECT_OK)
        return st;
    const double *alphas = o->alphas ? o->alphas : default_alphas;
    uint32_t n_alpha = o->alphas ? o->n_alpha : AFFECT_RMLR_DEFAULT_N_ALPHA;
    uint32_t L = o->n_lambda;
    if (!affect_mul_size(n_alpha, L, &cells))
        return affect_fail(err, AFFECT_ERR_RANGE, "too many alpha × lambda pairs");
    counts = affect_malloc_array(K, sizeof *counts);
    fold_of = affect_malloc_array(n, sizeof *fold_of);
    miss = affect_calloc(cells, sizeof *miss);
    paths = affect_malloc_array(cells, sizeof *paths);
    if (!counts || !fold_of || !miss || !paths) {
        st = affect_nomem(err);
        goto cleanup;
    }
    if ((st = check_data(x, n, p, y, K, counts, err)) != AFFECT_OK)
        goto cleanup;
    for (uint32_t k = 0; k < K; k++)
        if (counts[k] < 2) {
            st = affect_fail(err, AFFECT_ERR_INVALID,
                             "class %u has 1 sample (cross-validation needs at least 2)", k);
            goto cleanup;
        }
    if ((st = affect_stratified_folds(y, n, K, o->folds, o->seed, fold_of, err)) != AFFECT_OK)
        goto cleanup;
    uint32_t folds = n < o->folds ? (uint32_t)n : o->folds;
    double ratio = min_ratio(o, n, p);

    /* Every worker's fitter (and the threads' handles) before any work starts: the workers
     * allocate nothing. */
    uint32_t n_workers = o->threads < n_alpha ? o->threads : n_alpha;
    wk = affect_calloc(n_workers, sizeof *wk);
    if (!wk) {
        st = affect_nomem(err);
        goto cleanup;
    }
    if (n_workers > 1 && !(th = affect_calloc(n_workers - 1, sizeof *th))) {
        st = affect_nomem(err);
        goto cleanup;
    }
    for (; T < n_workers; T++)
        if ((st = fitter_alloc(&wk[T].f, n, p, K, err)) != AFFECT_OK)
            goto cleanup;

    /* The λ paths, from all the data (λ_max's gradient does not depend on α). */
    fitter_load(&wk[0].f, x, n, y, NULL, 0, alphas[0], o);
    double g = fitter_grad_max(&wk[0].f);
    for (uint32_t a = 0; a < n_alpha; a++)
        make_path(lambda_max(g, alphas[a]), ratio, L, paths + (size_t)a * L);

    cv_run run = {.x = x,
                  .n = n,
                  .y = y,
                  .fold_of = fold_of,
                  .folds = folds,
                  .alphas = alphas,
                  .n_alpha = n_alpha,
                  .L = L,
                  .paths = paths,
                  .o = o,
                  .miss = miss};
    cv_run_all(&run, wk, th, T);
    if ((st = affect_monitor_check(o->monitor, err)) != AFFECT_OK)
        goto cleanup;

    /* The choice: fewest misclassified, then larger λ, then larger α. */
    uint32_t ba = 0, bl = 0;
    for (uint32_t a = 0; a < n_alpha; a++)
        for (uint32_t l = 0; l < L; l++) {
            size_t c = miss[(size_t)a * L + l], cb = miss[(size_t)ba * L + bl];
            double lam = paths[(size_t)a * L + l], lb = paths[(size_t)ba * L + bl];
            if (c < cb || (c == cb && (lam > lb || (lam == lb && alphas[a] > alphas[ba])))) {
                ba = a;
                bl = l;
            }
        }

    if ((st = model_new(K, p, L, &m, err)) != AFFECT_OK)
        goto cleanup;
    fitter *f = &wk[0].f;
    fitter_load(f, x, n, y, NULL, 0, alphas[ba], o);
    const double *path = paths + (size_t)ba * L;
    m->converged = true;
    for (uint32_t l = alphas[ba] >= ALPHA_FLOOR ? 1 : 0; l <= bl; l++)
        m->converged = fitter_solve(f, path[l], l > 0 ? path[l - 1] : 0);
    m->n_train = (uint32_t)n;
    m->lambda_index = bl;
    m->alpha = alphas[ba];
    m->cv_error = (double)miss[(size_t)ba * L + bl] / (double)n;
    for (uint32_t l = 0; l < L; l++) {
        m->lambdas[l] = path[l];
        m->cv_errors[l] = (double)miss[(size_t)ba * L + l] / (double)n;
    }
    memcpy(m->mean, f->mean, p * sizeof *f->mean);
    memcpy(m->sd, f->sd, p * sizeof *f->sd);
    memcpy(m->beta0, f->beta0, K * sizeof *f->beta0);
    memcpy(m->beta, f->beta, (size_t)K * p * sizeof *f->beta);
    *out = m;
    m = NULL;
cleanup:
    for (uint32_t t = 0; wk && t < T; t++)
        fitter_free(&wk[t].f);
    affect_free(wk);
    affect_free(th);
    affect_rmlr_free(m);
    affect_free(counts);
    affect_free(fold_of);
    affect_free(miss);
    affect_free(paths);
    return st;
}

/* ---- accessors ---- */

uint32_t affect_rmlr_n_classes(const affect_rmlr *m)
{
    return m->K;
}

size_t affect_rmlr_n_features(const affect_rmlr *m)
{
    return m->p;
}

uint32_t affect_rmlr_n_train(const affect_rmlr *m)
{
    return m->n_train;
}

double affect_rmlr_alpha(const affect_rmlr *m)
{
    return m->alpha;
}

double affect_rmlr_lambda(const affect_rmlr *m)
{
    return m->lambdas[m->lambda_index];
}

uint32_t affect_rmlr_lambda_index(const affect_rmlr *m)
{
    return m->lambda_index;
}

double affect_rmlr_cv_error(const affect_rmlr *m)
{
    return m->cv_error;
}

bool affect_rmlr_converged(const affect_rmlr *m)
{
    return m->converged;
}

const double *affect_rmlr_lambdas(const affect_rmlr *m, uint32_t *count)
{
    if (count)
        *count = m->n_lambda;
    return m->lambdas;
}

const double *affect_rmlr_cv_errors(const affect_rmlr *m)
{
    return m->cv_errors;
}

const double *affect_rmlr_beta(const affect_rmlr *m)
{
    return m->beta;
}

const double *affect_rmlr_intercepts(const affect_rmlr *m)
{
    return m->beta0;
}

const double *affect_rmlr_means(const affect_rmlr *m)
{
    return m->mean;
}

const double *affect_rmlr_sds(const affect_rmlr *m)
{
    return m->sd;
}

uint32_t affect_rmlr_predict(const affect_rmlr *m, const double *x, double *probs)
{
    return predict_raw(m->K, m->p, m->mean, m->sd, m->beta0, m->beta, x, probs);
}

/* ---- missing values ---- */

void affect_impute_column_means(double *x, size_t n, size_t p)
{
    for (size_t j = 0; j < p; j++) {
        double s = 0.0;
        size_t c = 0;
        for (size_t i = 0; i < n; i++)
            if (isfinite(x[i * p + j])) {
                s += x[i * p + j];
                c++;
            }
        double mean = c ? s / (double)c : 0.0;
        for (size_t i = 0; i < n; i++)
            if (!isfinite(x[i * p + j]))
                x[i * p + j] = mean;
    }
}

/* ---- serialisation ---- */

/* The fit's fields after the version: the whole of version 1 but its first byte, the body of
 * version 2 (affect/rmlr.h). */
static void encode_body(const affect_rmlr *m, affect_bw *w)
{
    affect_bw_u32(w, m->K);
    affect_bw_u32(w, (uint32_t)m->p);
    affect_bw_u32(w, m->n_train);
    affect_bw_u32(w, m->n_lambda);
    affect_bw_u32(w, m->lambda_index);
    affect_bw_u8(w, m->converged ? 1 : 0);
    affect_bw_f64(w, m->alpha);
    affect_bw_f64(w, m->cv_error);
    affect_bw_f64s(w, m->lambdas, m->n_lambda);
    affect_bw_f64s(w, m->cv_errors, m->n_lambda);
    affect_bw_f64s(w, m->mean, m->p);
    affect_bw_f64s(w, m->sd, m->p);
    affect_bw_f64s(w, m->beta0, m->K);
    affect_bw_f64s(w, m->beta, (size_t)m->K * m->p);
}

void affect_rmlr_encode(const affect_rmlr *m, affect_bw *w)
{
    size_t start = w->len;
    affect_bw_header(w, AFFECT_RMLR_MAGIC, AFFECT_RMLR_FORMAT_VERSION, 0);
    affect_bw_u64(w, 0); /* the total length, known at the end */
    encode_body(m, w);
    if (w->failed)
        return;
    affect_put_u64(w->data + start + 12, (uint64_t)(w->len - start) + 8);
    affect_bw_checksum(w, start);
}

/* n float64 values into v (n checked against the bytes left first); *off receives the offset
 * of the first. Values are not checked. */
static affect_status get_f64s(affect_br *r, double *v, size_t n, size_t *off, const char *field,
                              affect_error *err)
{
    affect_status st = affect_br_need(r, n, 8, "RMLR: ", field, err);
    if (st != AFFECT_OK)
        return st;
    *off = r->off;
    affect_br_f64s(r, v, n);
    return AFFECT_OK;
}

static affect_status check_finite(const double *v, size_t n, size_t off, const char *field,
                                  affect_error *err)
{
    for (size_t i = 0; i < n; i++)
        if (!isfinite(v[i]))
            return affect_fail(err, AFFECT_ERR_FORMAT, "RMLR: non-finite value in %s (offset %zu)",
                               field, off + 8 * i);
    return AFFECT_OK;
}

/* The fields after the version (encode_body), from r's offset. */
static affect_status decode_body(affect_br *r, affect_rmlr **out, affect_error *err)
{
    affect_status st;
    size_t off, need, kp;
    uint8_t conv;
    uint32_t K, p, n, L, idx;
    double alpha, cve;
    affect_rmlr *m = NULL;

    off = r->off;
    if ((st = affect_br_u32_field(r, &K, "RMLR: ", "the class count", err)) != AFFECT_OK)
        return st;
    if (K < 2 || K > AFFECT_RMLR_MAX_CLASSES)
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "RMLR: class count %u out of range 2 .. %u (offset %zu)", K,
                           AFFECT_RMLR_MAX_CLASSES, off);
    off = r->off;
    if ((st = affect_br_u32_field(r, &p, "RMLR: ", "the feature count", err)) != AFFECT_OK)
        return st;
    if (p < 1 || p > AFFECT_RMLR_MAX_FEATURES)
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "RMLR: feature count %u out of range 1 .. %u (offset %zu)", p,
                           AFFECT_RMLR_MAX_FEATURES, off);
    off = r->off;
    if ((st = affect_br_u32_field(r, &n, "RMLR: ", "the sample count", err)) != AFFECT_OK)
        return st;
    if (n < K)
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "RMLR: sample count %u below the class count %u (offset %zu)", n, K,
                           off);
    off = r->off;
    if ((st = affect_br_u32_field(r, &L, "RMLR: ", "the lambda count", err)) != AFFECT_OK)
        return st;
    if (L < 1 || L > AFFECT_RMLR_MAX_LAMBDAS)
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "RMLR: lambda count %u out of range 1 .. %u (offset %zu)", L,
                           AFFECT_RMLR_MAX_LAMBDAS, off);
    off = r->off;
    if ((st = affect_br_u32_field(r, &idx, "RMLR: ", "the lambda index", err)) != AFFECT_OK)
        return st;
    if (idx >= L)
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "RMLR: lambda index %u not below the lambda count %u (offset %zu)", idx,
                           L, off);
    off = r->off;
    if (!affect_br_u8(r, &conv))
        return affect_fail_truncated(err, "RMLR: ", "the converged flag", off);
    if (conv > 1)
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "RMLR: converged flag %u is not 0 or 1 (offset %zu)", conv, off);
    off = r->off;
    if ((st = affect_br_f64_field(r, &alpha, "RMLR: ", "alpha", err)) != AFFECT_OK)
        return st;
    if (!(alpha >= 0 && alpha <= 1))
        return affect_fail(err, AFFECT_ERR_FORMAT, "RMLR: alpha = %g is not in [0, 1] (offset %zu)",
                           alpha, off);
    off = r->off;
    if ((st = affect_br_f64_field(r, &cve, "RMLR: ", "the cross-validation error", err)) !=
        AFFECT_OK)
        return st;
    if (!(cve >= 0 && cve <= 1))
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "RMLR: cross-validation error %g is not in [0, 1] (offset %zu)", cve,
                           off);
    /* Everything left has a known size: check it before allocating. */
    kp = (size_t)K * p; /* ≤ 2^8 · 2^20 */
    need = 2 * (size_t)L + 2 * (size_t)p + K + kp;
    if (!affect_br_has(r, need, 8)) {
        size_t at = r->off;
        const char *field = "the lambdas";
        size_t left = r->size - r->off, bounds[5] = {L, L, p, p, K};
        const char *names[5] = {"the lambdas", "the cross-validation errors", "the means",
                                "the standard deviations", "the intercepts"};
        field = "the coefficients";
        for (int s = 0; s < 5; s++) {
            if (left < 8 * bounds[s]) {
                field = names[s];
                break;
            }
            left -= 8 * bounds[s];
            at += 8 * bounds[s];
        }
        return affect_fail_truncated(err, "RMLR: ", field, at);
    }
    if ((st = model_new(K, p, L, &m, err)) != AFFECT_OK)
        return st;
    m->n_train = n;
    m->lambda_index = idx;
    m->converged = conv;
    m->alpha = alpha;
    m->cv_error = cve;
    get_f64s(r, m->lambdas, L, &off, "the lambdas", err);
    for (uint32_t l = 0; l < L; l++)
        if (!(m->lambdas[l] > 0 && isfinite(m->lambdas[l]))) {
            st = affect_fail(err, AFFECT_ERR_FORMAT,
                             "RMLR: lambda %u = %g is not a positive finite number (offset %zu)", l,
                             m->lambdas[l], off + 8 * (size_t)l);
            goto cleanup;
        }
    get_f64s(r, m->cv_errors, L, &off, "the cross-validation errors", err);
    for (uint32_t l = 0; l < L; l++)
        if (!(m->cv_errors[l] >= 0 && m->cv_errors[l] <= 1)) {
            st = affect_fail(err, AFFECT_ERR_FORMAT,
                             "RMLR: cross-validation error %g is not in [0, 1] (offset %zu)",
                             m->cv_errors[l], off + 8 * (size_t)l);
            goto cleanup;
        }
    get_f64s(r, m->mean, p, &off, "the means", err);
    if ((st = check_finite(m->mean, p, off, "the means", err)) != AFFECT_OK)
        goto cleanup;
    get_f64s(r, m->sd, p, &off, "the standard deviations", err);
    for (uint32_t j = 0; j < p; j++)
        if (!(m->sd[j] >= 0 && isfinite(m->sd[j]))) {
            st = affect_fail(err, AFFECT_ERR_FORMAT,
                             "RMLR: standard deviation %g is not a non-negative finite number "
                             "(offset %zu)",
                             m->sd[j], off + 8 * (size_t)j);
            goto cleanup;
        }
    get_f64s(r, m->beta0, K, &off, "the intercepts", err);
    if ((st = check_finite(m->beta0, K, off, "the intercepts", err)) != AFFECT_OK)
        goto cleanup;
    get_f64s(r, m->beta, kp, &off, "the coefficients", err);
    if ((st = check_finite(m->beta, kp, off, "the coefficients", err)) != AFFECT_OK)
        goto cleanup;
    *out = m;
    m = NULL;
cleanup:
    affect_rmlr_free(m);
    return st;
}

/* Bytes of version 2 around the body: the header (magic, version, flags, total length) and the
 * checksum. */
#define RMLR_HEAD 20u
#define RMLR_TAIL 8u

affect_status affect_rmlr_decode(affect_br *r, affect_rmlr **out, affect_error *err)
{
    affect_status st;
    *out = NULL;
    size_t start = r->off, left = r->size - r->off;
    const unsigned char *p = r->data + start;
    /* Version 1 has no magic: its first byte is its version, 1, never the magic's 'A'. */
    if (left >= 1 && p[0] == 1) {
        r->off++;
        return decode_body(r, out, err);
    }
    uint32_t version, flags;
    if ((st = affect_br_header(r, AFFECT_RMLR_MAGIC, AFFECT_RMLR_FORMAT_VERSION,
                               "RMLR: ", "an RMLR fit", &version, &flags, err)) != AFFECT_OK)
        return st;
    if (version != AFFECT_RMLR_FORMAT_VERSION) {
        r->off = start;
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "RMLR: version 1 is stored without a header (offset %zu)", start + 4);
    }
    if (flags != 0) {
        r->off = start;
        return affect_fail(err, AFFECT_ERR_FORMAT, "RMLR: flags 0x%x are not 0 (offset %zu)", flags,
                           start + 8);
    }
    uint64_t total;
    if (!affect_br_u64(r, &total)) {
        r->off = start;
        return affect_fail_truncated(err, "RMLR: ", "the length", start + 12);
    }
    if (total < RMLR_HEAD + RMLR_TAIL || total > left) {
        r->off = start;
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "RMLR: truncated: %zu bytes, the header says %llu (offset %zu)", left,
                           (unsigned long long)total, start + 12);
    }
    size_t body_end = start + (size_t)total - RMLR_TAIL;
    if (!affect_checksum_ok(p, (size_t)total - RMLR_TAIL)) {
        r->off = start;
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "RMLR: checksum mismatch: the fit is corrupt (offset %zu)", body_end);
    }
    affect_br body;
    affect_br_init(&body, r->data, body_end);
    body.off = r->off;
    if ((st = decode_body(&body, out, err)) != AFFECT_OK) {
        r->off = start;
        return st;
    }
    if (body.off != body_end) {
        affect_rmlr_free(*out);
        *out = NULL;
        r->off = start;
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "RMLR: %zu bytes follow the coefficients (offset %zu)",
                           body_end - body.off, body.off);
    }
    r->off = start + (size_t)total;
    return AFFECT_OK;
}
