/*
 * test_fisher.c — Fisher scores (affect/fisher.h) against finite differences: on small models
 * (full and diagonal covariances, ergodic and left-right, learned and fixed start, with zero
 * transitions, a zero weight and a zero start probability) EVERY entry of every group equals a
 * central difference of affect_hmm_loglik with respect to that one parameter (both (r, s) and
 * (s, r) moved together for a covariance off-diagonal); each group scored alone is bit-identical
 * to its slice of the full score; the dimension formula; describe() over every index of every
 * mask; determinism; every error message; every allocation failing in turn; and a realistic
 * size (7 states, 4 mixtures, 45 dimensions, 300 frames) scores finitely and matches finite
 * differences on a few entries.
 *
 * Finite differences: probabilities move by ±PROB_STEP (affect_hmm_from_params accepts sums
 * within 1e-6 of 1), means and covariances by ±DENS_STEP. An entry passes when
 * |score − fd| ≤ FD_REL |fd| + FD_ABS; the rounding of log P (about 1e-14 here) divided by the
 * step bounds the error of the difference at about 1e-7 for probabilities, hence their FD_ABS.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "testutil.h"
#include "affect/fisher.h"
#include "affect/hmm.h"
#include "util/rng.h"

#define PROB_STEP 4e-7
#define DENS_STEP 1e-5
#define FD_REL 1e-5
#define FD_ABS_PROB 1e-6
#define FD_ABS_DENS 1e-7

static const char GROUPS_MSG[] =
    "groups must be a non-empty combination of start, transitions, weights, means, covariances";

static void expect_msg(affect_status st, const affect_error *err, affect_status want,
                       const char *msg)
{
    assert_int_equal(st, want);
    assert_string_equal(err->msg, msg);
}

/* ---- models ---- */

#define SMALL_N 3
#define SMALL_M 2
#define SMALL_DIM 3

/* Parameters, in the layouts of affect_hmm_from_params. */
typedef struct params {
    affect_hmm_config cfg;
    double *start, *trans, *w, *mu, *cov;
} params;

typedef struct small_store {
    double start[SMALL_N], trans[SMALL_N * SMALL_N], w[SMALL_N * SMALL_M];
    double mu[SMALL_N * SMALL_M * SMALL_DIM], cov[SMALL_N * SMALL_M * SMALL_DIM * SMALL_DIM];
} small_store;

static void config(affect_hmm_config *c, uint32_t N, uint32_t M, uint32_t m, affect_hmm_cov cov,
                   affect_hmm_topology top, uint32_t jump, bool learn_start)
{
    affect_hmm_config_default(c);
    c->n_states = N;
    c->n_mix = M;
    c->dim = m;
    c->cov = cov;
    c->topology = top;
    c->max_jump = jump;
    c->learn_start = learn_start;
}

static bool allowed(const affect_hmm_config *c, uint32_t i, uint32_t l)
{
    if (c->topology == AFFECT_HMM_ERGODIC)
        return true;
    return l >= i && (c->max_jump == 0 || l - i <= c->max_jump);
}

/* Normalises v[0 .. n) to sum 1 (entries already 0 stay 0). */
static void normalise(double *v, uint32_t n)
{
    double s = 0.0;
    for (uint32_t i = 0; i < n; i++)
        s += v[i];
    for (uint32_t i = 0; i < n; i++)
        v[i] /= s;
}

/* Random parameters for the configuration in p->cfg (arrays already pointed at storage):
 * probabilities at least 0.1 before normalisation, covariances B Bᵀ / m + c I built exactly
 * symmetric. */
static void random_params(params *p, affect_rng *rng, double spread)
{
    const affect_hmm_config *c = &p->cfg;
    uint32_t N = c->n_states, M = c->n_mix, m = c->dim;
    for (uint32_t i = 0; i < N; i++)
        p->start[i] = c->learn_start ? affect_rng_range(rng, 0.3, 1.0) : (i == 0 ? 1.0 : 0.0);
    normalise(p->start, N);
    for (uint32_t i = 0; i < N; i++) {
        for (uint32_t l = 0; l < N; l++)
            p->trans[i * N + l] =
                allowed(c, i, l) ? affect_rng_range(rng, 0.1, 1.0) + (l == i ? 1.0 : 0.0) : 0.0;
        normalise(p->trans + i * N, N);
        for (uint32_t j = 0; j < M; j++)
            p->w[i * M + j] = affect_rng_range(rng, 0.3, 1.0);
        normalise(p->w + i * M, M);
    }
    double b[64 * 64];
    assert_true(m <= 64);
    for (uint32_t k = 0; k < N * M; k++) {
        for (uint32_t d = 0; d < m; d++)
            p->mu[k * m + d] = spread * affect_rng_normal(rng);
        if (c->cov == AFFECT_HMM_FULL) {
            double *cv = p->cov + (size_t)k * m * m;
            for (uint32_t e = 0; e < m * m; e++)
                b[e] = affect_rng_normal(rng);
            for (uint32_t r = 0; r < m; r++)
                for (uint32_t s = r; s < m; s++) {
                    double v = r == s ? 0.5 : 0.0;
                    for (uint32_t e = 0; e < m; e++)
                        v += b[r * m + e] * b[s * m + e] / m;
                    cv[r * m + s] = v;
                    cv[s * m + r] = v;
                }
        } else {
            for (uint32_t d = 0; d < m; d++)
                p->cov[k * m + d] = affect_rng_range(rng, 0.4, 2.0);
        }
    }
}

static void point_small(params *p, small_store *s)
{
    p->start = s->start;
    p->trans = s->trans;
    p->w = s->w;
    p->mu = s->mu;
    p->cov = s->cov;
}

static affect_hmm *build(const params *p)
{
    affect_hmm *h = NULL;
    affect_error err;
    affect_status st =
        affect_hmm_from_params(&p->cfg, p->start, p->trans, p->w, p->mu, p->cov, &h, &err);
    if (st != AFFECT_OK)
        fail_msg("from_params: %s", err.msg);
    return h;
}

static uint32_t draw(affect_rng *rng, const double *p, uint32_t n)
{
    double u = affect_rng_uniform(rng), cum = 0.0;
    for (uint32_t i = 0; i < n; i++) {
        cum += p[i];
        if (u < cum)
            return i;
    }
    return n - 1;
}

/* T frames sampled from small model p (m ≤ 3): states from π and A, mixtures from w, then
 * μ + L z with L the Cholesky factor of Σ (by hand). */
static void sample(const params *p, affect_rng *rng, uint32_t T, double *x)
{
    const affect_hmm_config *c = &p->cfg;
    uint32_t N = c->n_states, M = c->n_mix, m = c->dim;
    assert_true(m <= 3);
    uint32_t s = draw(rng, p->start, N);
    for (uint32_t t = 0; t < T; t++) {
        if (t > 0)
            s = draw(rng, p->trans + s * N, N);
        uint32_t k = s * M + draw(rng, p->w + s * M, M);
        double l[9] = {0}, z[3];
        if (c->cov == AFFECT_HMM_FULL) {
            const double *a = p->cov + (size_t)k * m * m;
            for (uint32_t i = 0; i < m; i++)
                for (uint32_t j = 0; j <= i; j++) {
                    double v = a[i * m + j];
                    for (uint32_t e = 0; e < j; e++)
                        v -= l[i * m + e] * l[j * m + e];
                    l[i * m + j] = i == j ? sqrt(v) : v / l[j * m + j];
                }
        } else {
            for (uint32_t d = 0; d < m; d++)
                l[d * m + d] = sqrt(p->cov[k * m + d]);
        }
        for (uint32_t d = 0; d < m; d++)
            z[d] = affect_rng_normal(rng);
        for (uint32_t d = 0; d < m; d++) {
            double v = p->mu[k * m + d];
            for (uint32_t e = 0; e <= d; e++)
                v += l[d * m + e] * z[e];
            x[t * m + d] = v;
        }
    }
}

/* ---- finite differences ---- */

static double loglik_of(const params *p, const double *x, uint32_t T)
{
    affect_hmm *h = build(p);
    double ll;
    affect_error err;
    assert_int_equal(affect_hmm_loglik(h, x, T, &ll, NULL, &err), AFFECT_OK);
    affect_hmm_free(h);
    assert_true(isfinite(ll));
    return ll;
}

/* The parameter entry e stands for (*b: its mirror for a covariance off-diagonal, else NULL). */
static void param_slots(params *p, const affect_fisher_entry *e, double **a, double **b)
{
    const affect_hmm_config *c = &p->cfg;
    size_t N = c->n_states, M = c->n_mix, m = c->dim, k = e->state * M + e->other;
    *b = NULL;
    switch (e->group) {
    case AFFECT_FISHER_START:
        *a = p->start + e->state;
        break;
    case AFFECT_FISHER_TRANS:
        *a = p->trans + e->state * N + e->other;
        break;
    case AFFECT_FISHER_WEIGHTS:
        *a = p->w + k;
        break;
    case AFFECT_FISHER_MEANS:
        *a = p->mu + k * m + e->r;
        break;
    default:
        assert_int_equal(e->group, AFFECT_FISHER_COVS);
        if (c->cov == AFFECT_HMM_DIAG) {
            assert_int_equal(e->r, e->s);
            *a = p->cov + k * m + e->r;
        } else {
            *a = p->cov + k * m * m + e->r * m + e->s;
            if (e->r != e->s)
                *b = p->cov + k * m * m + e->s * m + e->r;
        }
    }
}

/* Score entry `index` (of the layout for `groups`) against a central difference. */
static void check_entry(params *p, unsigned groups, size_t index, double score, const double *x,
                        uint32_t T)
{
    affect_fisher_entry e;
    affect_error err;
    assert_int_equal(affect_fisher_describe(&p->cfg, groups, index, &e, &err), AFFECT_OK);
    double *a, *b;
    param_slots(p, &e, &a, &b);
    bool prob = e.group <= AFFECT_FISHER_WEIGHTS;
    if (prob && *a == 0.0) { /* a zero probability: the entry is 0 by definition */
        if (score != 0.0)
            fail_msg("entry %zu (%s %u %u) is %.9g for a zero parameter", index,
                     affect_fisher_group_name(e.group), e.state, e.other, score);
        return;
    }
    double step = prob ? PROB_STEP : DENS_STEP, a0 = *a, b0 = b ? *b : 0.0, fd;
    if (prob && a0 + step > 1.0) { /* a probability of 1: second-order one-sided, from below */
        double l0 = loglik_of(p, x, T);
        *a = a0 - step;
        double l1 = loglik_of(p, x, T);
        *a = a0 - 2 * step;
        double l2 = loglik_of(p, x, T);
        *a = a0;
        fd = (3 * l0 - 4 * l1 + l2) / (2 * step);
    } else {
        *a = a0 + step;
        if (b)
            *b = b0 + step;
        double lp = loglik_of(p, x, T);
        *a = a0 - step;
        if (b)
            *b = b0 - step;
        double lm = loglik_of(p, x, T);
        *a = a0;
        if (b)
            *b = b0;
        fd = (lp - lm) / (2 * step);
    }
    double tol = FD_REL * fabs(fd) + (prob ? FD_ABS_PROB : FD_ABS_DENS);
    if (!(fabs(score - fd) <= tol))
        fail_msg("entry %zu (%s, state %u, other %u, r %u, s %u): score %.12g, finite difference "
                 "%.12g",
                 index, affect_fisher_group_name(e.group), e.state, e.other, e.r, e.s, score, fd);
}

/* Every entry of the full score of x under p against finite differences; each group alone
 * equals its slice bit for bit. Returns the number of exact-zero entries met. */
static size_t check_model(params *p, const double *x, uint32_t T)
{
    affect_hmm *h = build(p);
    affect_error err;
    size_t d = affect_fisher_dim(&p->cfg, AFFECT_FISHER_ALL);
    assert_true(d > 0 && d <= 512);
    double f[512], g[512], ll, ref;
    assert_int_equal(affect_fisher_score(h, x, T, AFFECT_FISHER_ALL, f, &ll, NULL, &err),
                     AFFECT_OK);
    assert_int_equal(affect_hmm_loglik(h, x, T, &ref, NULL, &err), AFFECT_OK);
    tu_assert_near(ll, ref, 1e-10 * fabs(ref));
    size_t zeros = 0;
    for (size_t i = 0; i < d; i++) {
        assert_true(isfinite(f[i]));
        zeros += f[i] == 0.0;
        check_entry(p, AFFECT_FISHER_ALL, i, f[i], x, T);
    }
    /* the groups alone, and a mixed mask, are slices of the full score */
    size_t off = 0;
    for (unsigned bit = 1; bit <= AFFECT_FISHER_COVS; bit <<= 1) {
        size_t n = affect_fisher_dim(&p->cfg, bit);
        if (bit == AFFECT_FISHER_START && !p->cfg.learn_start) {
            assert_int_equal(n, 0);
            continue;
        }
        assert_true(n > 0);
        assert_int_equal(affect_fisher_score(h, x, T, bit, g, NULL, NULL, &err), AFFECT_OK);
        assert_memory_equal(g, f + off, n * sizeof(double));
        off += n;
    }
    assert_int_equal(off, d);
    unsigned mix = AFFECT_FISHER_START | AFFECT_FISHER_WEIGHTS | AFFECT_FISHER_COVS;
    size_t ns = affect_fisher_dim(&p->cfg, AFFECT_FISHER_START),
           nt = affect_fisher_dim(&p->cfg, AFFECT_FISHER_TRANS),
           nw = affect_fisher_dim(&p->cfg, AFFECT_FISHER_WEIGHTS),
           nm = affect_fisher_dim(&p->cfg, AFFECT_FISHER_MEANS),
           nc = affect_fisher_dim(&p->cfg, AFFECT_FISHER_COVS);
    assert_int_equal(affect_fisher_dim(&p->cfg, mix), ns + nw + nc);
    assert_int_equal(affect_fisher_score(h, x, T, mix, g, NULL, NULL, &err), AFFECT_OK);
    assert_memory_equal(g, f, ns * sizeof(double));
    assert_memory_equal(g + ns, f + ns + nt, nw * sizeof(double));
    assert_memory_equal(g + ns + nw, f + ns + nt + nw + nm, nc * sizeof(double));
    affect_hmm_free(h);
    return zeros;
}

/* (1) every entry against finite differences */
static void test_finite_differences(void **state)
{
    (void)state;
    affect_rng rng;
    affect_rng_seed(&rng, 2024);
    small_store s;
    params p;
    point_small(&p, &s);
    double x[12 * SMALL_DIM];

    /* full, ergodic, learned start */
    config(&p.cfg, 2, 2, 2, AFFECT_HMM_FULL, AFFECT_HMM_ERGODIC, 0, true);
    random_params(&p, &rng, 1.0);
    sample(&p, &rng, 9, x);
    assert_int_equal(check_model(&p, x, 9), 0);

    /* full, left-right with jumps of 1, fixed start: the forbidden 0 → 2 and l < i are 0 */
    config(&p.cfg, 3, 2, 3, AFFECT_HMM_FULL, AFFECT_HMM_LEFT_RIGHT, 1, false);
    random_params(&p, &rng, 1.0);
    sample(&p, &rng, 10, x);
    assert_true(check_model(&p, x, 10) >= 4);

    /* diagonal, ergodic, fixed start, one zero transition and one zero weight (whose
     * component's mean and variance entries are then 0 too) */
    config(&p.cfg, 3, 2, 3, AFFECT_HMM_DIAG, AFFECT_HMM_ERGODIC, 0, false);
    random_params(&p, &rng, 1.0);
    s.trans[1 * 3 + 2] = 0.0;
    normalise(s.trans + 3, 3);
    s.w[2 * 2 + 1] = 0.0;
    s.w[2 * 2 + 0] = 1.0;
    sample(&p, &rng, 12, x);
    assert_int_equal(check_model(&p, x, 12), 1 + 1 + 3 + 3);

    /* diagonal, left-right (any jump), learned start */
    config(&p.cfg, 2, 2, 2, AFFECT_HMM_DIAG, AFFECT_HMM_LEFT_RIGHT, 0, true);
    random_params(&p, &rng, 1.0);
    sample(&p, &rng, 8, x);
    assert_int_equal(check_model(&p, x, 8), 1);

    /* full, ergodic, learned start with π_1 = 0, one mixture per state, means far apart */
    config(&p.cfg, 3, 1, 2, AFFECT_HMM_FULL, AFFECT_HMM_ERGODIC, 0, true);
    random_params(&p, &rng, 3.0);
    s.start[1] = 0.0;
    normalise(s.start, 3);
    sample(&p, &rng, 11, x);
    assert_true(check_model(&p, x, 11) >= 1);

    /* one state, one frame, m = 1 */
    config(&p.cfg, 1, 2, 1, AFFECT_HMM_FULL, AFFECT_HMM_ERGODIC, 0, false);
    random_params(&p, &rng, 1.0);
    x[0] = 0.3;
    check_model(&p, x, 1);
}

/* (2) the dimension formula */
static void test_dim(void **state)
{
    (void)state;
    affect_hmm_config c;
    config(&c, 7, 4, 45, AFFECT_HMM_FULL, AFFECT_HMM_ERGODIC, 0, false);
    size_t N = 7, M = 4, m = 45;
    size_t full = N * N + N * M + N * M * m + N * M * m * (m + 1) / 2;
    assert_int_equal(affect_fisher_dim(&c, AFFECT_FISHER_ALL), full);
    assert_int_equal(full, 30317);
    assert_int_equal(affect_fisher_dim(&c, AFFECT_FISHER_START), 0);
    assert_int_equal(affect_fisher_dim(&c, AFFECT_FISHER_START | AFFECT_FISHER_TRANS), 49);
    assert_int_equal(affect_fisher_dim(&c, AFFECT_FISHER_WEIGHTS), 28);
    assert_int_equal(affect_fisher_dim(&c, AFFECT_FISHER_MEANS), 1260);
    assert_int_equal(affect_fisher_dim(&c, AFFECT_FISHER_COVS), 28 * 1035);
    c.learn_start = true;
    assert_int_equal(affect_fisher_dim(&c, AFFECT_FISHER_ALL), full + N);
    assert_int_equal(affect_fisher_dim(&c, AFFECT_FISHER_START), 7);
    c.cov = AFFECT_HMM_DIAG;
    assert_int_equal(affect_fisher_dim(&c, AFFECT_FISHER_ALL), N + N * N + N * M + 2 * N * M * m);
    /* the topology does not change the layout */
    c.topology = AFFECT_HMM_LEFT_RIGHT;
    c.max_jump = 2;
    assert_int_equal(affect_fisher_dim(&c, AFFECT_FISHER_TRANS), 49);
    /* refused: bad masks, nothing selected, bad configurations */
    assert_int_equal(affect_fisher_dim(&c, 0), 0);
    assert_int_equal(affect_fisher_dim(&c, 32), 0);
    assert_int_equal(affect_fisher_dim(&c, AFFECT_FISHER_ALL | 64), 0);
    c.dim = 0;
    assert_int_equal(affect_fisher_dim(&c, AFFECT_FISHER_ALL), 0);
    assert_int_equal(affect_fisher_dim(NULL, AFFECT_FISHER_ALL), 0);
    /* the largest configuration fits */
    config(&c, 256, 64, 4096, AFFECT_HMM_FULL, AFFECT_HMM_ERGODIC, 0, true);
    size_t big =
        256 + 256 * 256 + 256 * 64 + (size_t)256 * 64 * 4096 + (size_t)256 * 64 * (4096 * 4097 / 2);
    assert_true(affect_fisher_dim(&c, AFFECT_FISHER_ALL) == big);
}

/* (3) describe(): every index of every mask, against an independent enumeration */
static void test_describe(void **state)
{
    (void)state;
    affect_hmm_config cfgs[4];
    config(&cfgs[0], 3, 2, 3, AFFECT_HMM_FULL, AFFECT_HMM_ERGODIC, 0, true);
    config(&cfgs[1], 2, 3, 4, AFFECT_HMM_FULL, AFFECT_HMM_LEFT_RIGHT, 0, false);
    config(&cfgs[2], 3, 2, 3, AFFECT_HMM_DIAG, AFFECT_HMM_ERGODIC, 0, true);
    config(&cfgs[3], 1, 1, 1, AFFECT_HMM_FULL, AFFECT_HMM_ERGODIC, 0, false);
    affect_error err;
    for (int ci = 0; ci < 4; ci++) {
        const affect_hmm_config *c = &cfgs[ci];
        uint32_t N = c->n_states, M = c->n_mix, m = c->dim;
        for (unsigned groups = 1; groups <= AFFECT_FISHER_ALL; groups++) {
            size_t d = affect_fisher_dim(c, groups);
            if (groups == AFFECT_FISHER_START && !c->learn_start) {
                assert_int_equal(d, 0);
                continue;
            }
            size_t idx = 0;
            affect_fisher_entry e;
#define EXPECT(G, I, O, R, S)                                                                      \
    do {                                                                                           \
        assert_int_equal(affect_fisher_describe(c, groups, idx, &e, &err), AFFECT_OK);             \
        assert_int_equal(e.group, (G));                                                            \
        assert_int_equal(e.state, (I));                                                            \
        assert_int_equal(e.other, (O));                                                            \
        assert_int_equal(e.r, (R));                                                                \
        assert_int_equal(e.s, (S));                                                                \
        idx++;                                                                                     \
    } while (0)
            if ((groups & AFFECT_FISHER_START) && c->learn_start)
                for (uint32_t i = 0; i < N; i++)
                    EXPECT(AFFECT_FISHER_START, i, 0, 0, 0);
            if (groups & AFFECT_FISHER_TRANS)
                for (uint32_t i = 0; i < N; i++)
                    for (uint32_t l = 0; l < N; l++)
                        EXPECT(AFFECT_FISHER_TRANS, i, l, 0, 0);
            if (groups & AFFECT_FISHER_WEIGHTS)
                for (uint32_t i = 0; i < N; i++)
                    for (uint32_t j = 0; j < M; j++)
                        EXPECT(AFFECT_FISHER_WEIGHTS, i, j, 0, 0);
            if (groups & AFFECT_FISHER_MEANS)
                for (uint32_t i = 0; i < N; i++)
                    for (uint32_t j = 0; j < M; j++)
                        for (uint32_t r = 0; r < m; r++)
                            EXPECT(AFFECT_FISHER_MEANS, i, j, r, 0);
            if (groups & AFFECT_FISHER_COVS)
                for (uint32_t i = 0; i < N; i++)
                    for (uint32_t j = 0; j < M; j++)
                        for (uint32_t r = 0; r < m; r++) {
                            if (c->cov == AFFECT_HMM_DIAG) {
                                EXPECT(AFFECT_FISHER_COVS, i, j, r, r);
                                continue;
                            }
                            for (uint32_t s = r; s < m; s++)
                                EXPECT(AFFECT_FISHER_COVS, i, j, r, s);
                        }
#undef EXPECT
            assert_int_equal(idx, d);
            char want[96];
            snprintf(want, sizeof want, "entry %zu is out of range: the score has %zu entries", d,
                     d);
            expect_msg(affect_fisher_describe(c, groups, d, &e, &err), &err, AFFECT_ERR_RANGE,
                       want);
        }
    }
    assert_string_equal(affect_fisher_group_name(AFFECT_FISHER_START), "start");
    assert_string_equal(affect_fisher_group_name(AFFECT_FISHER_TRANS), "transitions");
    assert_string_equal(affect_fisher_group_name(AFFECT_FISHER_WEIGHTS), "weights");
    assert_string_equal(affect_fisher_group_name(AFFECT_FISHER_MEANS), "means");
    assert_string_equal(affect_fisher_group_name(AFFECT_FISHER_COVS), "covariances");
    assert_null(affect_fisher_group_name(0));
    assert_null(affect_fisher_group_name(AFFECT_FISHER_ALL));
    assert_null(affect_fisher_group_name(32));
}

/* ---- a realistic size ---- */

#define BIG_N 7
#define BIG_M 4
#define BIG_DIM 45
#define BIG_T 300

static double big_start[BIG_N], big_trans[BIG_N * BIG_N], big_w[BIG_N * BIG_M];
static double big_mu[BIG_N * BIG_M * BIG_DIM], big_cov[BIG_N * BIG_M * BIG_DIM * BIG_DIM];
static double big_x[BIG_T * BIG_DIM], big_f[40000], big_g[40000];

/* A random 7 × 4 × 45 full ergodic model, and 300 frames drifting through its components. */
static void big_model(params *p)
{
    affect_rng rng;
    affect_rng_seed(&rng, 99);
    config(&p->cfg, BIG_N, BIG_M, BIG_DIM, AFFECT_HMM_FULL, AFFECT_HMM_ERGODIC, 0, false);
    p->start = big_start;
    p->trans = big_trans;
    p->w = big_w;
    p->mu = big_mu;
    p->cov = big_cov;
    random_params(p, &rng, 0.5);
    uint32_t k = 0;
    for (uint32_t t = 0; t < BIG_T; t++) {
        if (t % 20 == 0)
            k = (uint32_t)(affect_rng_uniform(&rng) * BIG_N * BIG_M);
        for (uint32_t d = 0; d < BIG_DIM; d++)
            big_x[t * BIG_DIM + d] = big_mu[k * BIG_DIM + d] + 0.8 * affect_rng_normal(&rng);
    }
}

/* (4) realistic size: finite, deterministic, and a few entries against finite differences */
static void test_realistic(void **state)
{
    (void)state;
    params p;
    big_model(&p);
    affect_hmm *h = build(&p);
    affect_error err;
    size_t d = affect_fisher_dim(&p.cfg, AFFECT_FISHER_ALL);
    assert_int_equal(d, 30317);
    double ll, ll2;
    assert_int_equal(
        affect_fisher_score(h, big_x, BIG_T, AFFECT_FISHER_ALL, big_f, &ll, NULL, &err), AFFECT_OK);
    assert_true(isfinite(ll));
    size_t nonzero = 0;
    for (size_t i = 0; i < d; i++) {
        assert_true(isfinite(big_f[i]));
        nonzero += big_f[i] != 0.0;
    }
    assert_true(nonzero > d / 2);
    /* bit-identical a second time */
    assert_int_equal(
        affect_fisher_score(h, big_x, BIG_T, AFFECT_FISHER_ALL, big_g, &ll2, NULL, &err),
        AFFECT_OK);
    assert_memory_equal(big_f, big_g, d * sizeof(double));
    assert_memory_equal(&ll, &ll2, sizeof ll);
    /* entries of the most visited component: a mean, a variance, a covariance, its weight, and
     * a transition */
    double *wts = big_g;
    assert_int_equal(
        affect_fisher_score(h, big_x, BIG_T, AFFECT_FISHER_WEIGHTS, wts, NULL, NULL, &err),
        AFFECT_OK);
    size_t best = 0;
    for (size_t k = 1; k < BIG_N * BIG_M; k++)
        if (wts[k] * big_w[k] > wts[best] * big_w[best])
            best = k;
    size_t base_m = BIG_N * BIG_N + BIG_N * BIG_M, cp = BIG_DIM * (BIG_DIM + 1) / 2;
    size_t base_c = base_m + BIG_N * BIG_M * BIG_DIM;
    size_t picks[] = {
        best / BIG_M * BIG_N + (best / BIG_M + 1) % BIG_N, /* a transition out of its state */
        BIG_N * BIG_N + best,                              /* its weight */
        base_m + best * BIG_DIM + 7,                       /* mean, coordinate 7 */
        base_c + best * cp + 0,                            /* variance (0, 0) */
        base_c + best * cp + 5,                            /* covariance (0, 5) */
        base_c + best * cp + cp - 1,                       /* variance (44, 44) */
    };
    for (size_t i = 0; i < sizeof picks / sizeof picks[0]; i++)
        check_entry(&p, AFFECT_FISHER_ALL, picks[i], big_f[picks[i]], big_x, BIG_T);
    affect_hmm_free(h);
}

/* (5) determinism on a small model, and a score independent of the output's previous contents */
static void test_deterministic(void **state)
{
    (void)state;
    affect_rng rng;
    affect_rng_seed(&rng, 5);
    small_store s;
    params p;
    point_small(&p, &s);
    config(&p.cfg, 3, 2, 3, AFFECT_HMM_FULL, AFFECT_HMM_LEFT_RIGHT, 0, true);
    random_params(&p, &rng, 1.0);
    double x[40 * 3];
    sample(&p, &rng, 40, x);
    affect_hmm *h = build(&p);
    affect_error err;
    size_t d = affect_fisher_dim(&p.cfg, AFFECT_FISHER_ALL);
    double a[200], b[200];
    memset(a, 0, sizeof a);
    for (size_t i = 0; i < 200; i++)
        b[i] = NAN;
    assert_int_equal(affect_fisher_score(h, x, 40, AFFECT_FISHER_ALL, a, NULL, NULL, &err),
                     AFFECT_OK);
    assert_int_equal(affect_fisher_score(h, x, 40, AFFECT_FISHER_ALL, b, NULL, NULL, &err),
                     AFFECT_OK);
    assert_memory_equal(a, b, d * sizeof(double));
    assert_true(isnan(b[d])); /* nothing written past the end */
    affect_hmm_free(h);
}

/* (6) every error message */
static void test_errors(void **state)
{
    (void)state;
    affect_rng rng;
    affect_rng_seed(&rng, 8);
    small_store s;
    params p;
    point_small(&p, &s);
    config(&p.cfg, 2, 2, 2, AFFECT_HMM_FULL, AFFECT_HMM_LEFT_RIGHT, 0, false);
    random_params(&p, &rng, 1.0);
    affect_hmm *h = build(&p);
    affect_error err;
    double x[6] = {0.1, 0.2, 0.3, 0.4, 0.5, 0.6}, f[64], ll = 7.0;

    expect_msg(affect_fisher_score(h, x, 3, 0, f, &ll, NULL, &err), &err, AFFECT_ERR_INVALID,
               GROUPS_MSG);
    expect_msg(affect_fisher_score(h, x, 3, 32, f, &ll, NULL, &err), &err, AFFECT_ERR_INVALID,
               GROUPS_MSG);
    expect_msg(affect_fisher_score(h, x, 3, AFFECT_FISHER_ALL | 128, f, &ll, NULL, &err), &err,
               AFFECT_ERR_INVALID, GROUPS_MSG);
    expect_msg(affect_fisher_score(h, x, 3, AFFECT_FISHER_START, f, &ll, NULL, &err), &err,
               AFFECT_ERR_INVALID, "start scores need a model with a learned start");
    expect_msg(affect_fisher_score(NULL, x, 3, AFFECT_FISHER_ALL, f, &ll, NULL, &err), &err,
               AFFECT_ERR_INVALID, "no model");
    expect_msg(affect_fisher_score(h, x, 3, AFFECT_FISHER_ALL, NULL, &ll, NULL, &err), &err,
               AFFECT_ERR_INVALID, "no room for the score");
    expect_msg(affect_fisher_score(h, x, 0, AFFECT_FISHER_ALL, f, &ll, NULL, &err), &err,
               AFFECT_ERR_INVALID, "the sequence has no frames");
    expect_msg(affect_fisher_score(h, NULL, 3, AFFECT_FISHER_ALL, f, &ll, NULL, &err), &err,
               AFFECT_ERR_INVALID, "the sequence has no data");
    x[5] = NAN;
    expect_msg(affect_fisher_score(h, x, 3, AFFECT_FISHER_ALL, f, &ll, NULL, &err), &err,
               AFFECT_ERR_INVALID, "frame 2: value 1 is not finite");
    /* every density underflows: probability 0, the posteriors' error passed through */
    x[5] = 1e200;
    expect_msg(affect_fisher_score(h, x, 3, AFFECT_FISHER_ALL, f, &ll, NULL, &err), &err,
               AFFECT_ERR_RANGE, "the sequence has probability 0 under the model: no posteriors");
    assert_true(ll == 7.0); /* untouched on error */
    /* with a fixed start the start bit alongside others selects nothing more */
    x[5] = 0.6;
    double g[64];
    assert_int_equal(affect_fisher_score(h, x, 3, AFFECT_FISHER_ALL, f, NULL, NULL, &err),
                     AFFECT_OK);
    assert_int_equal(
        affect_fisher_score(h, x, 3, AFFECT_FISHER_ALL & ~AFFECT_FISHER_START, g, &ll, NULL, &err),
        AFFECT_OK);
    assert_memory_equal(f, g, affect_fisher_dim(&p.cfg, AFFECT_FISHER_ALL) * sizeof(double));
    assert_true(isfinite(ll));

    /* describe */
    affect_fisher_entry e;
    expect_msg(affect_fisher_describe(NULL, AFFECT_FISHER_ALL, 0, &e, &err), &err,
               AFFECT_ERR_INVALID, "no configuration");
    affect_hmm_config bad = p.cfg;
    bad.dim = 0;
    expect_msg(affect_fisher_describe(&bad, AFFECT_FISHER_ALL, 0, &e, &err), &err,
               AFFECT_ERR_INVALID, "observation dimension must be between 1 and 4096");
    expect_msg(affect_fisher_describe(&p.cfg, 0, 0, &e, &err), &err, AFFECT_ERR_INVALID,
               GROUPS_MSG);
    expect_msg(affect_fisher_describe(&p.cfg, 33, 0, &e, &err), &err, AFFECT_ERR_INVALID,
               GROUPS_MSG);
    expect_msg(affect_fisher_describe(&p.cfg, AFFECT_FISHER_START, 0, &e, &err), &err,
               AFFECT_ERR_INVALID, "start scores need a model with a learned start");
    expect_msg(affect_fisher_describe(&p.cfg, AFFECT_FISHER_ALL, 0, NULL, &err), &err,
               AFFECT_ERR_INVALID, "no room for the entry");
    expect_msg(affect_fisher_describe(&p.cfg, AFFECT_FISHER_ALL, 42, &e, &err), &err,
               AFFECT_ERR_RANGE, "entry 42 is out of range: the score has 28 entries");
    expect_msg(affect_fisher_describe(&p.cfg, AFFECT_FISHER_ALL, SIZE_MAX, &e, &err), &err,
               AFFECT_ERR_RANGE,
               "entry 18446744073709551615 is out of range: the score has 28 entries");
    affect_hmm_free(h);
}

/* (7) out of memory: our workspace and the posteriors' */
typedef struct oom_ctx {
    const affect_hmm *h;
    const double *x;
    uint32_t T;
    unsigned groups;
    double *out;
} oom_ctx;

static affect_status oom_score(void *ctx, affect_error *err)
{
    oom_ctx *c = ctx;
    return affect_fisher_score(c->h, c->x, c->T, c->groups, c->out, NULL, NULL, err);
}

static void test_out_of_memory(void **state)
{
    (void)state;
    affect_rng rng;
    affect_rng_seed(&rng, 31);
    small_store s;
    params p;
    point_small(&p, &s);
    double x[30 * 3], f[200];
    for (int cov = 0; cov < 2; cov++) {
        config(&p.cfg, 3, 2, 3, cov ? AFFECT_HMM_DIAG : AFFECT_HMM_FULL, AFFECT_HMM_ERGODIC, 0,
               true);
        random_params(&p, &rng, 1.0);
        sample(&p, &rng, 30, x);
        affect_hmm *h = build(&p);
        unsigned masks[] = {AFFECT_FISHER_ALL, AFFECT_FISHER_TRANS, AFFECT_FISHER_MEANS};
        for (int i = 0; i < 3; i++) {
            oom_ctx c = {h, x, 30, masks[i], f};
            assert_int_equal(tu_oom_sweep(oom_score, &c, NULL, NULL), 2);
        }
        affect_hmm_free(h);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_finite_differences), cmocka_unit_test(test_dim),
        cmocka_unit_test(test_describe),           cmocka_unit_test(test_realistic),
        cmocka_unit_test(test_deterministic),      cmocka_unit_test(test_errors),
        cmocka_unit_test(test_out_of_memory),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
