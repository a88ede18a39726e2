/*
 * test_hmm.c — Gaussian-mixture HMMs (affect/hmm.h) against known answers: training recovers a
 * known 3-state model from its samples; the forward log-likelihood, Viterbi and the posteriors
 * equal brute-force enumeration of every state path and mixture assignment on tiny models
 * (ergodic and left-right, full and diagonal); a 200,000-frame sequence scores finitely and at
 * the entropy rate; degenerate data train (a constant coordinate, one sequence, identical
 * sequences, single frames with one state) or are refused with their message; an empty mixture
 * component is re-seeded and reported; one Baum–Welch iteration at m = 32 with sharp posteriors
 * (where the M-step leaves negligible rows out of its scatter) equals the maximum-likelihood
 * update computed from the posteriors; training is bit-for-bit deterministic; every error
 * message; and every allocation failing in turn.
 */
#include <math.h>
#include <string.h>

#include "testutil.h"
#include "affect/hmm.h"
#include "util/rng.h"

#define LOG_2PI 1.83787706640934548356

/* ---- helpers ---- */

static void expect_msg(affect_status st, const affect_error *err, affect_status want,
                       const char *msg)
{
    assert_int_equal(st, want);
    assert_string_equal(err->msg, msg);
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

/* Lower Cholesky factor of a small SPD matrix (m ≤ 3), written out by hand. */
static void small_cholesky(const double *a, uint32_t m, double *l)
{
    memset(l, 0, m * m * sizeof *l);
    for (uint32_t i = 0; i < m; i++)
        for (uint32_t j = 0; j <= i; j++) {
            double s = a[i * m + j];
            for (uint32_t k = 0; k < j; k++)
                s -= l[i * m + k] * l[j * m + k];
            l[i * m + j] = i == j ? sqrt(s) : s / l[j * m + j];
        }
}

/* Samples T frames from model h (full or diagonal covariances, m ≤ 3); states may be NULL.
 * With path not NULL the states are path[t] instead of draws from π and A. */
static void sample_path(const affect_hmm *h, affect_rng *rng, uint32_t T, double *x,
                        int32_t *states, const int32_t *path)
{
    const affect_hmm_config *c = affect_hmm_get_config(h);
    uint32_t N = c->n_states, M = c->n_mix, m = c->dim;
    bool full = c->cov == AFFECT_HMM_FULL;
    const double *covs = affect_hmm_covariances(h);
    double fac[64 * 9];
    assert_true(N * M <= 64 && m <= 3);
    for (uint32_t k = 0; k < N * M; k++) {
        if (full) {
            small_cholesky(covs + k * m * m, m, fac + k * 9);
        } else {
            memset(fac + k * 9, 0, 9 * sizeof(double));
            for (uint32_t d = 0; d < m; d++)
                fac[k * 9 + d * m + d] = sqrt(covs[k * m + d]);
        }
    }
    uint32_t s = path ? (uint32_t)path[0] : draw(rng, affect_hmm_start(h), N);
    for (uint32_t t = 0; t < T; t++) {
        if (path)
            s = (uint32_t)path[t];
        else if (t > 0)
            s = draw(rng, affect_hmm_transitions(h) + s * N, N);
        uint32_t j = draw(rng, affect_hmm_weights(h) + s * M, M);
        uint32_t k = s * M + j;
        double z[3];
        for (uint32_t d = 0; d < m; d++)
            z[d] = affect_rng_normal(rng);
        for (uint32_t d = 0; d < m; d++) {
            double v = affect_hmm_means(h)[k * m + d];
            for (uint32_t e = 0; e <= d; e++)
                v += fac[k * 9 + d * m + e] * z[e];
            x[t * m + d] = v;
        }
        if (states)
            states[t] = (int32_t)s;
    }
}

static void sample(const affect_hmm *h, affect_rng *rng, uint32_t T, double *x, int32_t *states)
{
    sample_path(h, rng, T, x, states, NULL);
}

/* log N(x; μ, Σ) computed independently of the library: explicit inverse and determinant by
 * cofactors (m ≤ 3), or the product of the diagonal. */
static double gauss_logpdf(const double *x, const double *mu, const double *cov, uint32_t m,
                           bool full)
{
    double e[3];
    for (uint32_t d = 0; d < m; d++)
        e[d] = x[d] - mu[d];
    if (!full) {
        double s = 0.0;
        for (uint32_t d = 0; d < m; d++)
            s += -0.5 * (LOG_2PI + log(cov[d]) + e[d] * e[d] / cov[d]);
        return s;
    }
    double det, inv[9];
    if (m == 1) {
        det = cov[0];
        inv[0] = 1.0 / det;
    } else if (m == 2) {
        det = cov[0] * cov[3] - cov[1] * cov[2];
        inv[0] = cov[3] / det;
        inv[1] = -cov[1] / det;
        inv[2] = -cov[2] / det;
        inv[3] = cov[0] / det;
    } else {
        const double *a = cov;
        double c00 = a[4] * a[8] - a[5] * a[7], c01 = -(a[3] * a[8] - a[5] * a[6]),
               c02 = a[3] * a[7] - a[4] * a[6];
        det = a[0] * c00 + a[1] * c01 + a[2] * c02;
        inv[0] = c00 / det;
        inv[3] = c01 / det;
        inv[6] = c02 / det;
        inv[1] = -(a[1] * a[8] - a[2] * a[7]) / det;
        inv[4] = (a[0] * a[8] - a[2] * a[6]) / det;
        inv[7] = -(a[0] * a[7] - a[1] * a[6]) / det;
        inv[2] = (a[1] * a[5] - a[2] * a[4]) / det;
        inv[5] = -(a[0] * a[5] - a[2] * a[3]) / det;
        inv[8] = (a[0] * a[4] - a[1] * a[3]) / det;
    }
    double q = 0.0;
    for (uint32_t r = 0; r < m; r++)
        for (uint32_t c = 0; c < m; c++)
            q += e[r] * inv[r * m + c] * e[c];
    return -0.5 * (m * LOG_2PI + log(det) + q);
}

static double safe_log(double p)
{
    return p > 0 ? log(p) : -INFINITY;
}

/* Everything by enumeration of every state path and mixture assignment. */
typedef struct brute {
    double loglik;
    double vit_logprob;
    int32_t vit_path[8];
    double gamma[8 * 3 * 3];
    double xi[9];
} brute;

static void brute_force(const affect_hmm *h, const double *x, uint32_t T, brute *b)
{
    const affect_hmm_config *c = affect_hmm_get_config(h);
    uint32_t N = c->n_states, M = c->n_mix, m = c->dim;
    bool full = c->cov == AFFECT_HMM_FULL;
    assert_true(T <= 8 && N <= 3 && M <= 3);
    double lg[8][3][3], lbs[8][3];
    for (uint32_t t = 0; t < T; t++)
        for (uint32_t i = 0; i < N; i++) {
            double mx = -INFINITY;
            for (uint32_t j = 0; j < M; j++) {
                uint32_t k = i * M + j;
                lg[t][i][j] =
                    safe_log(affect_hmm_weights(h)[k]) +
                    gauss_logpdf(x + t * m, affect_hmm_means(h) + k * m,
                                 affect_hmm_covariances(h) + k * (full ? m * m : m), m, full);
                if (lg[t][i][j] > mx)
                    mx = lg[t][i][j];
            }
            double s = 0.0;
            for (uint32_t j = 0; j < M; j++)
                s += exp(lg[t][i][j] - mx);
            lbs[t][i] = mx + log(s);
        }
    uint64_t n_paths = 1, n_asg = 1;
    for (uint32_t t = 0; t < T; t++) {
        n_paths *= N;
        n_asg *= M;
    }
    memset(b, 0, sizeof *b);
    /* pass 1: total (running log-sum-exp) and Viterbi */
    double mx = -INFINITY, sum = 0.0;
    b->vit_logprob = -INFINITY;
    for (int pass = 0; pass < 2; pass++) {
        for (uint64_t pc = 0; pc < n_paths; pc++) {
            uint32_t s[8] = {0};
            uint64_t q = pc;
            for (uint32_t t = 0; t < T; t++) {
                s[t] = (uint32_t)(q % N);
                q /= N;
            }
            double lp = safe_log(affect_hmm_start(h)[s[0]]);
            for (uint32_t t = 1; t < T; t++)
                lp += safe_log(affect_hmm_transitions(h)[s[t - 1] * N + s[t]]);
            if (lp == -INFINITY)
                continue;
            if (pass == 0) {
                double v = lp;
                for (uint32_t t = 0; t < T; t++)
                    v += lbs[t][s[t]];
                if (v > b->vit_logprob) {
                    b->vit_logprob = v;
                    for (uint32_t t = 0; t < T; t++)
                        b->vit_path[t] = (int32_t)s[t];
                }
            }
            for (uint64_t ac = 0; ac < n_asg; ac++) {
                uint32_t j[8];
                uint64_t r = ac;
                double term = lp;
                for (uint32_t t = 0; t < T; t++) {
                    j[t] = (uint32_t)(r % M);
                    r /= M;
                    term += lg[t][s[t]][j[t]];
                }
                if (term == -INFINITY)
                    continue;
                if (pass == 0) {
                    if (term > mx) {
                        sum = sum * exp(mx - term) + 1.0;
                        mx = term;
                    } else {
                        sum += exp(term - mx);
                    }
                } else {
                    double p = exp(term - b->loglik);
                    for (uint32_t t = 0; t < T; t++) {
                        b->gamma[(t * N + s[t]) * M + j[t]] += p;
                        if (t + 1 < T)
                            b->xi[s[t] * N + s[t + 1]] += p;
                    }
                }
            }
        }
        if (pass == 0)
            b->loglik = mx + log(sum);
    }
}

/* Random parameters for the brute-force models. */
static affect_hmm *random_model(affect_rng *rng, const affect_hmm_config *cfg)
{
    uint32_t N = cfg->n_states, M = cfg->n_mix, m = cfg->dim;
    bool full = cfg->cov == AFFECT_HMM_FULL;
    double start[3], trans[9], w[9], mu[27], cov[81];
    double s = 0.0;
    for (uint32_t i = 0; i < N; i++) {
        start[i] = cfg->learn_start ? affect_rng_range(rng, 0.2, 1.0) : (i == 0);
        s += start[i];
    }
    for (uint32_t i = 0; i < N; i++)
        start[i] /= s;
    for (uint32_t i = 0; i < N; i++) {
        s = 0.0;
        for (uint32_t l = 0; l < N; l++) {
            bool ok = cfg->topology == AFFECT_HMM_ERGODIC ||
                      (l >= i && (cfg->max_jump == 0 || l - i <= cfg->max_jump));
            trans[i * N + l] = ok ? affect_rng_range(rng, 0.1, 1.0) : 0.0;
            s += trans[i * N + l];
        }
        for (uint32_t l = 0; l < N; l++)
            trans[i * N + l] /= s;
        s = 0.0;
        for (uint32_t j = 0; j < M; j++) {
            w[i * M + j] = affect_rng_range(rng, 0.2, 1.0);
            s += w[i * M + j];
        }
        for (uint32_t j = 0; j < M; j++)
            w[i * M + j] /= s;
    }
    for (uint32_t k = 0; k < N * M; k++) {
        for (uint32_t d = 0; d < m; d++)
            mu[k * m + d] = 1.5 * affect_rng_normal(rng);
        if (full) {
            double a[9];
            for (uint32_t e = 0; e < m * m; e++)
                a[e] = 0.7 * affect_rng_normal(rng);
            for (uint32_t r = 0; r < m; r++)
                for (uint32_t c = 0; c < m; c++) {
                    double v = r == c ? 0.3 : 0.0;
                    for (uint32_t e = 0; e < m; e++)
                        v += a[r * m + e] * a[c * m + e];
                    cov[k * m * m + r * m + c] = v;
                }
        } else {
            for (uint32_t d = 0; d < m; d++)
                cov[k * m + d] = affect_rng_range(rng, 0.3, 2.0);
        }
    }
    affect_hmm *h = NULL;
    affect_error err;
    assert_int_equal(affect_hmm_from_params(cfg, start, trans, w, mu, cov, &h, &err), AFFECT_OK);
    return h;
}

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

/* ---- (2, 6) forward, Viterbi and posteriors equal brute force on tiny models ---- */

static void test_brute_force(void **state)
{
    (void)state;
    static const struct {
        uint32_t N, M, m;
        affect_hmm_cov cov;
        affect_hmm_topology top;
        uint32_t jump;
        bool learn_start;
        uint32_t T;
    } cases[] = {
        {2, 2, 2, AFFECT_HMM_FULL, AFFECT_HMM_ERGODIC, 0, false, 6},
        {2, 3, 3, AFFECT_HMM_FULL, AFFECT_HMM_ERGODIC, 0, true, 5},
        {3, 2, 2, AFFECT_HMM_FULL, AFFECT_HMM_LEFT_RIGHT, 1, false, 6},
        {3, 2, 1, AFFECT_HMM_DIAG, AFFECT_HMM_LEFT_RIGHT, 0, false, 5},
        {3, 1, 3, AFFECT_HMM_DIAG, AFFECT_HMM_ERGODIC, 0, true, 6},
        {3, 2, 3, AFFECT_HMM_DIAG, AFFECT_HMM_LEFT_RIGHT, 2, true, 4},
        {3, 2, 2, AFFECT_HMM_FULL, AFFECT_HMM_ERGODIC, 0, true, 1},
        {2, 2, 2, AFFECT_HMM_FULL, AFFECT_HMM_LEFT_RIGHT, 0, false, 2},
    };
    affect_rng rng;
    affect_rng_seed(&rng, 7);
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        affect_hmm_config cfg;
        config(&cfg, cases[c].N, cases[c].M, cases[c].m, cases[c].cov, cases[c].top, cases[c].jump,
               cases[c].learn_start);
        for (int rep = 0; rep < 3; rep++) {
            affect_hmm *h = random_model(&rng, &cfg);
            uint32_t T = cases[c].T, N = cfg.n_states, M = cfg.n_mix;
            double x[8 * 3];
            for (uint32_t e = 0; e < T * cfg.dim; e++)
                x[e] = 1.5 * affect_rng_normal(&rng);
            brute b;
            brute_force(h, x, T, &b);
            affect_error err;
            double ll, lp, ll2, gamma[8 * 9], xi[9];
            int32_t path[8];
            assert_int_equal(affect_hmm_loglik(h, x, T, &ll, NULL, &err), AFFECT_OK);
            tu_assert_near(ll, b.loglik, 1e-10 * fabs(b.loglik) + 1e-12);
            assert_int_equal(affect_hmm_viterbi(h, x, T, path, &lp, NULL, &err), AFFECT_OK);
            tu_assert_near(lp, b.vit_logprob, 1e-10 * fabs(b.vit_logprob) + 1e-12);
            for (uint32_t t = 0; t < T; t++)
                assert_int_equal(path[t], b.vit_path[t]);
            assert_int_equal(affect_hmm_posteriors(h, x, T, gamma, xi, &ll2, NULL, &err),
                             AFFECT_OK);
            tu_assert_near(ll2, b.loglik, 1e-10 * fabs(b.loglik) + 1e-12);
            for (uint32_t e = 0; e < T * N * M; e++)
                tu_assert_near(gamma[e], b.gamma[e], 1e-10);
            for (uint32_t e = 0; e < N * N; e++)
                tu_assert_near(xi[e], b.xi[e], 1e-10);
            affect_hmm_free(h);
        }
    }
}

/* ---- (1) training recovers a known model ---- */

static affect_hmm *truth_model(void)
{
    affect_hmm_config cfg;
    config(&cfg, 3, 2, 2, AFFECT_HMM_FULL, AFFECT_HMM_ERGODIC, 0, false);
    static const double start[3] = {1, 0, 0};
    static const double trans[9] = {0.90, 0.06, 0.04, 0.05, 0.90, 0.05, 0.04, 0.06, 0.90};
    static const double w[6] = {0.6, 0.4, 0.5, 0.5, 0.3, 0.7};
    static const double mu[12] = {-0.8, 0, 0.8, 0, 5, -0.8, 5, 0.8, -0.5, 4.5, 0.5, 5.5};
    static const double cov[24] = {0.20, 0.05, 0.05, 0.15, 0.15, -0.04, -0.04, 0.25,
                                   0.25, 0.00, 0.00, 0.10, 0.10, 0.02,  0.02,  0.20,
                                   0.18, 0.06, 0.06, 0.18, 0.12, -0.03, -0.03, 0.22};
    affect_hmm *h = NULL;
    affect_error err;
    assert_int_equal(affect_hmm_from_params(&cfg, start, trans, w, mu, cov, &h, &err), AFFECT_OK);
    return h;
}

static affect_hmm *train_ok(const affect_hmm_config *cfg, const affect_hmm_seq *seqs, uint32_t n)
{
    affect_hmm *h = NULL;
    affect_error err;
    affect_status st = affect_hmm_train(cfg, seqs, n, &h, &err);
    if (st != AFFECT_OK)
        fail_msg("training failed: %s", err.msg);
    return h;
}

/* The model to recover: three phases in order, two full-covariance components per state. */
static affect_hmm *truth_phases(void)
{
    affect_hmm_config cfg;
    config(&cfg, 3, 2, 2, AFFECT_HMM_FULL, AFFECT_HMM_LEFT_RIGHT, 0, false);
    static const double start[3] = {1, 0, 0};
    static const double trans[9] = {0.98, 0.02, 0, 0, 0.98, 0.02, 0, 0, 1};
    static const double w[6] = {0.6, 0.4, 0.5, 0.5, 0.3, 0.7};
    static const double mu[12] = {-0.8, 0, 0.8, 0, 5, -0.8, 5, 0.8, -0.5, 4.5, 0.5, 5.5};
    static const double cov[24] = {0.20, 0.05, 0.05, 0.15, 0.15, -0.04, -0.04, 0.25,
                                   0.25, 0.00, 0.00, 0.10, 0.10, 0.02,  0.02,  0.20,
                                   0.18, 0.06, 0.06, 0.18, 0.12, -0.03, -0.03, 0.22};
    affect_hmm *h = NULL;
    affect_error err;
    assert_int_equal(affect_hmm_from_params(&cfg, start, trans, w, mu, cov, &h, &err), AFFECT_OK);
    return h;
}

enum { REC_SEQS = 20, REC_T = 150 };

static void state_mean(const affect_hmm *h, uint32_t i, double out[2])
{
    const double *w = affect_hmm_weights(h) + i * 2, *mu = affect_hmm_means(h) + i * 4;
    out[0] = w[0] * mu[0] + w[1] * mu[2];
    out[1] = w[0] * mu[1] + w[1] * mu[3];
}

/* Trains on samples of truth_phases with the given topology and compares.
 *
 * The sequences are the thesis's setting: every recording goes through the phases in order,
 * here 50 frames each, so the initialisation's equal segments are the phases (the states'
 * outputs are sampled from the model; the path is fixed). The transitions the data show are
 * then a_ii = 49/50 for the first two states, which truth_phases states. (With random
 * durations the segments mix phases, k-means gives a state a component on its neighbour's
 * frames, and EM from there ends in a local optimum: the initialisation the thesis prescribes
 * assumes phases of comparable length.) */
static void recover(affect_hmm_topology top)
{
    affect_hmm *truth = truth_phases();
    affect_rng rng;
    affect_rng_seed(&rng, 2024);
    static double x[REC_SEQS][REC_T * 2];
    affect_hmm_seq seqs[REC_SEQS];
    int32_t phases[REC_T];
    for (int t = 0; t < REC_T; t++)
        phases[t] = t / (REC_T / 3);
    for (int s = 0; s < REC_SEQS; s++) {
        sample_path(truth, &rng, REC_T, x[s], NULL, phases);
        seqs[s].x = x[s];
        seqs[s].n_frames = REC_T;
    }
    affect_hmm_config cfg;
    config(&cfg, 3, 2, 2, AFFECT_HMM_FULL, top, 0, false);
    cfg.max_iter = 200;
    cfg.tol = 1e-7;
    affect_hmm *h = train_ok(&cfg, seqs, REC_SEQS);

    affect_hmm_report rep;
    affect_hmm_get_report(h, &rep);
    assert_true(rep.converged);
    assert_true(rep.iterations >= 2);
    assert_int_equal(rep.n_sequences, REC_SEQS);
    assert_int_equal(rep.n_frames, REC_SEQS * REC_T);
    /* EM never lowers the likelihood (up to the reg floor's tiny perturbation) */
    for (uint32_t k = 1; k <= rep.iterations; k++)
        assert_true(rep.loglik[k] >= rep.loglik[k - 1] - 1e-9 * fabs(rep.loglik[k - 1]));
    /* the last value is the sum of the sequences' log-likelihoods under the final model */
    double total = 0.0;
    affect_error err;
    for (int s = 0; s < REC_SEQS; s++) {
        double ll;
        assert_int_equal(affect_hmm_loglik(h, x[s], REC_T, &ll, NULL, &err), AFFECT_OK);
        total += ll;
    }
    assert_true(rep.loglik[rep.iterations] == total);

    /* match the learned states to the true ones by nearest state mean */
    int perm[3];
    for (uint32_t i = 0; i < 3; i++) {
        double a[2], best = INFINITY;
        state_mean(truth, i, a);
        for (uint32_t l = 0; l < 3; l++) {
            double b[2];
            state_mean(h, l, b);
            double d = hypot(a[0] - b[0], a[1] - b[1]);
            if (d < best) {
                best = d;
                perm[i] = (int)l;
            }
        }
        assert_true(best < 0.1);
    }
    assert_true(perm[0] != perm[1] && perm[1] != perm[2] && perm[0] != perm[2]);
    /* Transitions: the phases are far apart (≥ 5 standard deviations), so the posteriors are
     * the phases up to ~1e-6 and the learned transitions are the counted ones, 49/50 */
    for (uint32_t i = 0; i < 3; i++)
        for (uint32_t l = 0; l < 3; l++)
            tu_assert_near(affect_hmm_transitions(h)[perm[i] * 3 + perm[l]],
                           affect_hmm_transitions(truth)[i * 3 + l], 1e-3);
    /* Components: ~300 frames each of 1,000 per state, variances ≤ 0.25: a mean's standard
     * error is at most 0.03 and a weight's sqrt(0.3 · 0.7 / 1000) ≈ 0.015 (plus the
     * components' overlap); 0.12 and 0.08 are 4 to 5 of them. */
    for (uint32_t i = 0; i < 3; i++) {
        const double *tm = affect_hmm_means(truth) + i * 4;
        const double *lm = affect_hmm_means(h) + perm[i] * 4;
        const double *tw = affect_hmm_weights(truth) + i * 2;
        const double *lw = affect_hmm_weights(h) + perm[i] * 2;
        int swap = hypot(tm[0] - lm[0], tm[1] - lm[1]) > hypot(tm[0] - lm[2], tm[1] - lm[3]);
        for (int j = 0; j < 2; j++) {
            int lj = swap ? 1 - j : j;
            tu_assert_near(lm[lj * 2], tm[j * 2], 0.12);
            tu_assert_near(lm[lj * 2 + 1], tm[j * 2 + 1], 0.12);
            tu_assert_near(lw[lj], tw[j], 0.08);
        }
    }
    /* Viterbi on a fresh sequence with random phase lengths finds them */
    int32_t truth_states[400], path[400];
    double xs[400 * 2], lp;
    sample(truth, &rng, 400, xs, truth_states);
    assert_int_equal(affect_hmm_viterbi(h, xs, 400, path, &lp, NULL, &err), AFFECT_OK);
    int agree = 0;
    for (int t = 0; t < 400; t++)
        agree += path[t] == perm[truth_states[t]];
    assert_true(agree >= 398);
    affect_hmm_free(h);
    affect_hmm_free(truth);
}

/* ---- the inverse-factor densities on wide models, far from the origin ---- */

/* log N(x; μ, Σ) by a long-double Cholesky and forward substitution: independent of the engine's
 * inverse factors and of BLAS. */
static double wide_logpdf(const double *x, const double *mu, const double *cov, uint32_t m)
{
    long double l[48 * 48] = {0}, y[48], logdet = 0, q = 0;
    assert_true(m <= 48);
    for (uint32_t r = 0; r < m; r++)
        for (uint32_t c = 0; c <= r; c++) {
            long double s = cov[r * m + c];
            for (uint32_t e = 0; e < c; e++)
                s -= l[r * m + e] * l[c * m + e];
            l[r * m + c] = r == c ? sqrtl(s) : s / l[c * m + c];
        }
    for (uint32_t r = 0; r < m; r++) {
        long double s = (long double)x[r] - mu[r];
        for (uint32_t e = 0; e < r; e++)
            s -= l[r * m + e] * y[e];
        y[r] = s / l[r * m + r];
        q += y[r] * y[r];
        logdet += logl(l[r * m + r]);
    }
    return (double)(-0.5L * (long double)m * LOG_2PI - logdet - 0.5L * q);
}

static void test_wide_full(void **state)
{
    (void)state;
    /* m = 40: three panels of inverse-factor rows (16, 16, 8); data and means near 1000 with
     * spreads from 0.01 to 1, so W x − W μ would cancel badly without the centring */
    enum { N = 2, M = 3, m = 40, T = 60 };
    affect_rng rng;
    affect_rng_seed(&rng, 11);
    static double start[N] = {1, 0}, trans[N * N] = {0.9, 0.1, 0.2, 0.8}, w[N * M], mu[N * M * m],
                  cov[N * M * m * m], x[T * m];
    for (uint32_t k = 0; k < N * M; k++) {
        w[k] = 1.0 / M;
        double spread = k % 2 ? 0.01 : 1.0;
        for (uint32_t d = 0; d < m; d++)
            mu[k * m + d] = 1000.0 + d + 3.0 * affect_rng_normal(&rng);
        static double a[m * m];
        for (uint32_t e = 0; e < m * m; e++)
            a[e] = spread * affect_rng_normal(&rng) / sqrt(m);
        for (uint32_t r = 0; r < m; r++)
            for (uint32_t c = 0; c < m; c++) {
                double v = r == c ? 0.05 * spread * spread : 0.0;
                for (uint32_t e = 0; e < m; e++)
                    v += a[r * m + e] * a[c * m + e];
                cov[(k * m + r) * m + c] = v;
            }
    }
    for (uint32_t t = 0; t < T; t++) { /* near component t mod (N·M), plus noise */
        uint32_t k = t % (N * M);
        for (uint32_t d = 0; d < m; d++)
            x[t * m + d] = mu[k * m + d] + (k % 2 ? 0.01 : 1.0) * affect_rng_normal(&rng);
    }
    affect_hmm_config cfg;
    config(&cfg, N, M, m, AFFECT_HMM_FULL, AFFECT_HMM_ERGODIC, 0, false);
    affect_hmm *h = NULL;
    affect_error err;
    assert_int_equal(affect_hmm_from_params(&cfg, start, trans, w, mu, cov, &h, &err), AFFECT_OK);
    /* the forward recursion by hand on the reference densities */
    double alpha[N], ref = 0.0;
    for (uint32_t t = 0; t < T; t++) {
        double lb[N], next[N], mx = -INFINITY;
        for (uint32_t i = 0; i < N; i++) {
            double lg[M], lm = -INFINITY, s = 0.0;
            for (uint32_t j = 0; j < M; j++) {
                uint32_t k = i * M + j;
                lg[j] = log(w[k]) + wide_logpdf(x + t * m, mu + k * m, cov + k * m * m, m);
                lm = lg[j] > lm ? lg[j] : lm;
            }
            for (uint32_t j = 0; j < M; j++)
                s += exp(lg[j] - lm);
            lb[i] = lm + log(s);
        }
        for (uint32_t l = 0; l < N; l++) {
            double v = t == 0 ? (l == 0 ? 0.0 : -INFINITY) : -INFINITY;
            if (t > 0) {
                double mm = -INFINITY, s = 0.0;
                for (uint32_t i = 0; i < N; i++)
                    mm = alpha[i] + log(trans[i * N + l]) > mm ? alpha[i] + log(trans[i * N + l])
                                                               : mm;
                for (uint32_t i = 0; i < N; i++)
                    s += exp(alpha[i] + log(trans[i * N + l]) - mm);
                v = mm + log(s);
            }
            next[l] = v + lb[l];
            mx = next[l] > mx ? next[l] : mx;
        }
        memcpy(alpha, next, sizeof alpha);
        if (t == T - 1) {
            double s = 0.0;
            for (uint32_t i = 0; i < N; i++)
                s += exp(alpha[i] - mx);
            ref = mx + log(s);
        }
    }
    double ll;
    assert_int_equal(affect_hmm_loglik(h, x, T, &ll, NULL, &err), AFFECT_OK);
    tu_assert_near(ll, ref, 1e-13 * fabs(ref)); /* 8e-12 without the centring */
    affect_hmm_free(h);
}

static void test_recovers_model(void **state)
{
    (void)state;
    recover(AFFECT_HMM_LEFT_RIGHT);
    recover(AFFECT_HMM_ERGODIC); /* learns the zeros below the diagonal as ~0 */
}

/* ---- (3) a 200,000-frame sequence ---- */

static void test_long_sequence(void **state)
{
    (void)state;
    enum { LONG_T = 200000, SHORT_T = 1000 };
    double *x = malloc(sizeof(double) * LONG_T * 2);
    assert_non_null(x);
    affect_rng rng;
    affect_rng_seed(&rng, 99);
    affect_error err;

    /* With every row of A equal to π, the frames are independent draws of the mixture
     * Σ_i π_i b_i, so log P(x) = Σ_t log Σ_i π_i b_i(x_t) exactly: the forward recursion over
     * 200,000 frames (log P ≈ −4e5, far below the smallest double's log, −745) must agree with
     * that sum, computed here independently, to 1e-9 relative. */
    {
        affect_hmm_config cfg;
        config(&cfg, 3, 2, 2, AFFECT_HMM_FULL, AFFECT_HMM_ERGODIC, 0, true);
        affect_hmm *base = truth_model();
        double pi[3] = {0.5, 0.3, 0.2}, trans[9];
        for (int i = 0; i < 9; i++)
            trans[i] = pi[i % 3];
        affect_hmm *iid = NULL;
        assert_int_equal(affect_hmm_from_params(&cfg, pi, trans, affect_hmm_weights(base),
                                                affect_hmm_means(base),
                                                affect_hmm_covariances(base), &iid, &err),
                         AFFECT_OK);
        sample(iid, &rng, LONG_T, x, NULL);
        double ll, want = 0.0;
        assert_int_equal(affect_hmm_loglik(iid, x, LONG_T, &ll, NULL, &err), AFFECT_OK);
        for (int t = 0; t < LONG_T; t++) {
            double terms[6], mx = -INFINITY, s = 0.0;
            for (int k = 0; k < 6; k++) {
                terms[k] = log(pi[k / 2] * affect_hmm_weights(iid)[k]) +
                           gauss_logpdf(x + t * 2, affect_hmm_means(iid) + k * 2,
                                        affect_hmm_covariances(iid) + k * 4, 2, true);
                if (terms[k] > mx)
                    mx = terms[k];
            }
            for (int k = 0; k < 6; k++)
                s += exp(terms[k] - mx);
            want += mx + log(s);
        }
        assert_true(isfinite(ll) && ll < -1e5);
        tu_assert_near(ll, want, 1e-9 * fabs(want));
        affect_hmm_free(iid);
        affect_hmm_free(base);
    }

    /* A stationary ergodic model: by the Shannon–McMillan–Breiman theorem log P(x_1..T) / T
     * tends to minus the entropy rate (here ≈ −1.994 nats per frame). The per-frame average of
     * a 1,000-frame run has a standard deviation of 0.041 nats (measured over 200 runs), that
     * of the 200,000-frame run 0.003; the two agree within 0.2 (about 5 standard deviations
     * of their difference), while a scaling or underflow bug would be off by orders of
     * magnitude (or give −∞). */
    affect_hmm *truth = truth_model();
    double ll_long, ll_short;
    sample(truth, &rng, LONG_T, x, NULL);
    assert_int_equal(affect_hmm_loglik(truth, x, LONG_T, &ll_long, NULL, &err), AFFECT_OK);
    assert_true(isfinite(ll_long));
    sample(truth, &rng, SHORT_T, x, NULL);
    assert_int_equal(affect_hmm_loglik(truth, x, SHORT_T, &ll_short, NULL, &err), AFFECT_OK);
    tu_assert_near(ll_long / LONG_T, ll_short / SHORT_T, 0.2);
    free(x);
    affect_hmm_free(truth);
}

/* ---- (6) posteriors: normalisation and consistency on a longer sequence ---- */

static void test_posteriors(void **state)
{
    (void)state;
    affect_hmm *truth = truth_model();
    enum { T = 3000 };
    double *x = malloc(sizeof(double) * T * 2), *gamma = malloc(sizeof(double) * T * 6), xi[9];
    assert_non_null(x);
    assert_non_null(gamma);
    affect_rng rng;
    affect_rng_seed(&rng, 5);
    sample(truth, &rng, T, x, NULL);
    affect_error err;
    double ll, ll2;
    assert_int_equal(affect_hmm_posteriors(truth, x, T, gamma, xi, &ll, NULL, &err), AFFECT_OK);
    assert_int_equal(affect_hmm_loglik(truth, x, T, &ll2, NULL, &err), AFFECT_OK);
    assert_true(ll == ll2); /* the same blocks, the same recursion */
    for (int t = 0; t < T; t++) {
        double s = 0.0;
        for (int k = 0; k < 6; k++) {
            assert_true(gamma[t * 6 + k] >= 0.0);
            s += gamma[t * 6 + k];
        }
        tu_assert_near(s, 1.0, 1e-12);
    }
    double sx = 0.0;
    for (int k = 0; k < 9; k++)
        sx += xi[k];
    tu_assert_near(sx, T - 1, 1e-9 * T);
    /* Σ_l ξ(i, l) = Σ_{t<T−1} γ_t(i) */
    for (int i = 0; i < 3; i++) {
        double a = xi[i * 3] + xi[i * 3 + 1] + xi[i * 3 + 2], g = 0.0;
        for (int t = 0; t < T - 1; t++)
            g += gamma[t * 6 + i * 2] + gamma[t * 6 + i * 2 + 1];
        tu_assert_near(a, g, 1e-9 * T);
    }
    /* either output may be NULL */
    assert_int_equal(affect_hmm_posteriors(truth, x, T, NULL, NULL, &ll2, NULL, &err), AFFECT_OK);
    assert_true(ll2 == ll);
    assert_int_equal(affect_hmm_posteriors(truth, x, T, NULL, xi, NULL, NULL, &err), AFFECT_OK);
    free(x);
    free(gamma);
    affect_hmm_free(truth);
}

/* ---- (5) determinism ---- */

static void assert_same_model(const affect_hmm *a, const affect_hmm *b)
{
    const affect_hmm_config *c = affect_hmm_get_config(a);
    size_t N = c->n_states, M = c->n_mix, m = c->dim, cs = c->cov == AFFECT_HMM_FULL ? m * m : m;
    assert_memory_equal(affect_hmm_start(a), affect_hmm_start(b), N * sizeof(double));
    assert_memory_equal(affect_hmm_transitions(a), affect_hmm_transitions(b),
                        N * N * sizeof(double));
    assert_memory_equal(affect_hmm_weights(a), affect_hmm_weights(b), N * M * sizeof(double));
    assert_memory_equal(affect_hmm_means(a), affect_hmm_means(b), N * M * m * sizeof(double));
    assert_memory_equal(affect_hmm_covariances(a), affect_hmm_covariances(b),
                        N * M * cs * sizeof(double));
    affect_hmm_report ra, rb;
    affect_hmm_get_report(a, &ra);
    affect_hmm_get_report(b, &rb);
    assert_int_equal(ra.iterations, rb.iterations);
    assert_int_equal(ra.reseeded, rb.reseeded);
    assert_memory_equal(ra.loglik, rb.loglik, (ra.iterations + 1) * sizeof(double));
}

/* ---- one M-step at m = 32 equals the maximum-likelihood update from the posteriors ---- */

/* The scatter of the M-step leaves out the rows that are negligible (below one unit roundoff of
 * the block's scale, from 24 dimensions on): with sharp posteriors most are. One iteration from
 * the initial model must still equal the update computed here, in long double, from the
 * posteriors of that initial model. */
static void test_mstep_sharp(void **state)
{
    (void)state;
    enum { N = 2, M = 2, m = 32, S = 3, T = 80, K = N * M };
    affect_rng rng;
    affect_rng_seed(&rng, 23);
    static double x[S * T * m], gamma[T * K], xi[N * N];
    static long double n[K], s1[K * m], sc[K * m * m];
    for (uint32_t s = 0; s < S; s++)
        for (uint32_t t = 0; t < T; t++) { /* state = half of the sequence, mixture at random:
                                            * states far apart (posteriors 0 or 1 to 1e-50),
                                            * mixtures overlapping (posteriors in between) */
            uint32_t i = t < T / 2 ? 0 : 1, j = affect_rng_uniform(&rng) < 0.5 ? 1 : 0;
            double shared = affect_rng_normal(&rng);
            for (uint32_t d = 0; d < m; d++)
                x[(s * T + t) * m + d] = 6.0 * i + 0.15 * j * (d % 2) + (d % 3) + 0.5 * shared +
                                         (0.3 + 0.1 * (d % 4)) * affect_rng_normal(&rng);
        }
    affect_hmm_seq seqs[S];
    for (uint32_t s = 0; s < S; s++) {
        seqs[s].x = x + (size_t)s * T * m;
        seqs[s].n_frames = T;
    }
    affect_hmm_config cfg;
    config(&cfg, N, M, m, AFFECT_HMM_FULL, AFFECT_HMM_LEFT_RIGHT, 0, false);
    cfg.reg = 0.0;
    cfg.tol = 0.0;
    cfg.max_iter = 0;
    affect_hmm *h0 = NULL, *h1 = NULL;
    affect_error err;
    assert_int_equal(affect_hmm_train(&cfg, seqs, S, &h0, &err), AFFECT_OK);
    cfg.max_iter = 1;
    assert_int_equal(affect_hmm_train(&cfg, seqs, S, &h1, &err), AFFECT_OK);
    /* statistics from the initial model's posteriors, two passes (means, then scatter) */
    memset(n, 0, sizeof n);
    memset(s1, 0, sizeof s1);
    memset(sc, 0, sizeof sc);
    for (int pass = 0; pass < 2; pass++)
        for (uint32_t s = 0; s < S; s++) {
            double ll;
            assert_int_equal(affect_hmm_posteriors(h0, seqs[s].x, T, gamma, xi, &ll, NULL, &err),
                             AFFECT_OK);
            for (uint32_t t = 0; t < T; t++)
                for (uint32_t k = 0; k < K; k++) {
                    long double g = gamma[t * K + k];
                    const double *xt = seqs[s].x + (size_t)t * m;
                    if (pass == 0) {
                        n[k] += g;
                        for (uint32_t d = 0; d < m; d++)
                            s1[k * m + d] += g * xt[d];
                        continue;
                    }
                    for (uint32_t d = 0; d < m; d++)
                        for (uint32_t e = 0; e < m; e++)
                            sc[(k * m + d) * m + e] +=
                                g * (xt[d] - s1[k * m + d] / n[k]) * (xt[e] - s1[k * m + e] / n[k]);
                }
        }
    const double *mu = affect_hmm_means(h1), *cov = affect_hmm_covariances(h1);
    for (uint32_t k = 0; k < K; k++) {
        assert_true(n[k] > 10); /* every component has frames */
        for (uint32_t d = 0; d < m; d++) {
            long double want = s1[k * m + d] / n[k];
            tu_assert_near(mu[k * m + d], want, 1e-12 * (fabsl(want) + 1));
        }
        for (uint32_t d = 0; d < m; d++)
            for (uint32_t e = 0; e < m; e++) {
                long double want = sc[(k * m + d) * m + e] / n[k];
                long double scale = sqrtl(sc[(k * m + d) * m + d] * sc[(k * m + e) * m + e]) / n[k];
                tu_assert_near(cov[(k * m + d) * m + e], want, 1e-12 * scale);
            }
    }
    affect_hmm_free(h0);
    affect_hmm_free(h1);
}

static void test_deterministic(void **state)
{
    (void)state;
    affect_hmm *truth = truth_model();
    affect_rng rng;
    affect_rng_seed(&rng, 11);
    static double x[5][400 * 2];
    affect_hmm_seq seqs[5];
    for (int s = 0; s < 5; s++) {
        uint32_t T = 150 + 60 * s; /* different lengths */
        sample(truth, &rng, T, x[s], NULL);
        seqs[s].x = x[s];
        seqs[s].n_frames = T;
    }
    affect_hmm_config cfg;
    for (int variant = 0; variant < 2; variant++) {
        config(&cfg, 4, 3, 2, variant ? AFFECT_HMM_DIAG : AFFECT_HMM_FULL,
               variant ? AFFECT_HMM_LEFT_RIGHT : AFFECT_HMM_ERGODIC, 0, variant == 0);
        cfg.max_iter = 15;
        cfg.tol = 0;
        affect_hmm *a = train_ok(&cfg, seqs, 5), *b = train_ok(&cfg, seqs, 5);
        assert_same_model(a, b);
        /* another seed gives another initialisation */
        cfg.seed = 2;
        affect_hmm *c = train_ok(&cfg, seqs, 5);
        assert_true(memcmp(affect_hmm_means(a), affect_hmm_means(c), 4 * 3 * 2 * sizeof(double)));
        /* left-right: forbidden transitions stay exactly 0 */
        if (variant) {
            const double *t = affect_hmm_transitions(a);
            for (int i = 0; i < 4; i++)
                for (int l = 0; l < i; l++)
                    assert_true(t[i * 4 + l] == 0.0);
        }
        /* the start is (1, 0, ...) unless learned; a learned one sums to 1 */
        const double *st = affect_hmm_start(a);
        if (variant)
            assert_true(st[0] == 1.0 && st[1] == 0.0 && st[2] == 0.0 && st[3] == 0.0);
        else
            tu_assert_near(st[0] + st[1] + st[2] + st[3], 1.0, 1e-12);
        affect_hmm_free(a);
        affect_hmm_free(b);
        affect_hmm_free(c);
    }
    affect_hmm_free(truth);
}

/* ---- (4) degenerate data ---- */

static void test_degenerate(void **state)
{
    (void)state;
    affect_rng rng;
    affect_rng_seed(&rng, 3);
    affect_hmm_config cfg;
    affect_error err;
    affect_hmm *h = NULL;

    /* a constant coordinate: its variance is the floor, nothing breaks */
    static double x[3][120 * 2];
    affect_hmm_seq seqs[3];
    for (int s = 0; s < 3; s++) {
        for (int t = 0; t < 120; t++) {
            x[s][t * 2] = (t < 60 ? 0.0 : 3.0) + 0.3 * affect_rng_normal(&rng);
            x[s][t * 2 + 1] = 42.0;
        }
        seqs[s].x = x[s];
        seqs[s].n_frames = 120;
    }
    config(&cfg, 2, 2, 2, AFFECT_HMM_FULL, AFFECT_HMM_LEFT_RIGHT, 0, false);
    h = train_ok(&cfg, seqs, 3);
    for (int k = 0; k < 4; k++) {
        tu_assert_near(affect_hmm_means(h)[k * 2 + 1], 42.0, 1e-9);
        double v = affect_hmm_covariances(h)[k * 4 + 3];
        assert_true(v >= cfg.reg * 0.999 && v <= cfg.reg * 10.0 + 1e-9);
    }
    double ll;
    assert_int_equal(affect_hmm_loglik(h, x[0], 120, &ll, NULL, &err), AFFECT_OK);
    assert_true(isfinite(ll));
    affect_hmm_free(h);
    cfg.cov = AFFECT_HMM_DIAG;
    h = train_ok(&cfg, seqs, 3);
    for (int k = 0; k < 4; k++)
        tu_assert_near(affect_hmm_covariances(h)[k * 2 + 1], cfg.reg, 1e-12);
    affect_hmm_free(h);

    /* one training sequence; identical sequences */
    config(&cfg, 2, 2, 2, AFFECT_HMM_FULL, AFFECT_HMM_ERGODIC, 0, false);
    h = train_ok(&cfg, seqs, 1);
    affect_hmm_free(h);
    affect_hmm_seq same[3] = {seqs[0], seqs[0], seqs[0]};
    h = train_ok(&cfg, same, 3);
    affect_hmm_report rep;
    affect_hmm_get_report(h, &rep);
    assert_true(isfinite(rep.loglik[rep.iterations]));
    affect_hmm_free(h);

    /* a single-frame sequence: refused with more states, fine with one */
    affect_hmm_seq with_one[2] = {seqs[0], {x[1], 1}};
    expect_msg(affect_hmm_train(&cfg, with_one, 2, &h, &err), &err, AFFECT_ERR_INVALID,
               "sequence 1 has 1 frame, fewer than the 2 states");
    assert_null(h);
    cfg.n_states = 1;
    h = train_ok(&cfg, with_one, 2);
    affect_hmm_get_report(h, &rep);
    assert_int_equal(rep.n_frames, 121);
    tu_assert_near(affect_hmm_transitions(h)[0], 1.0, 0.0);
    assert_true(isinf(affect_hmm_mean_duration(h, NULL)));
    affect_hmm_free(h);
    affect_hmm_seq one_frame = {x[1], 1};
    h = train_ok(&cfg, &one_frame, 1);
    affect_hmm_free(h);

    /* fewer frames than states */
    config(&cfg, 7, 4, 2, AFFECT_HMM_FULL, AFFECT_HMM_ERGODIC, 0, false);
    affect_hmm_seq few[4] = {seqs[0], seqs[1], seqs[2], {x[2], 4}};
    expect_msg(affect_hmm_train(&cfg, few, 4, &h, &err), &err, AFFECT_ERR_INVALID,
               "sequence 3 has 4 frames, fewer than the 7 states");
    /* exactly as many frames as states: every segment is one frame */
    few[3].n_frames = 7;
    h = train_ok(&cfg, few + 3, 1);
    affect_hmm_free(h);
}

/* A mixture component with no frames is re-seeded and reported. One state, three mixtures, on
 * frames taking only two distinct values: k-means++ picks both values, its third centre
 * duplicates one of them and never wins a frame (ties go to the lower cluster), so the third
 * component starts with weight 0 and no posterior weight at all. The first M-step re-seeds it at
 * the state's worst-explained frame with the state's pooled covariance. */
static void test_reseed(void **state)
{
    (void)state;
    static double x[100];
    for (int t = 0; t < 100; t++)
        x[t] = t % 2 ? 1.0 : -1.0;
    affect_hmm_seq seq = {x, 100};
    affect_hmm_config cfg;
    config(&cfg, 1, 3, 1, AFFECT_HMM_FULL, AFFECT_HMM_ERGODIC, 0, false);
    cfg.max_iter = 0; /* the initialisation: the third component is empty */
    affect_hmm *h = train_ok(&cfg, &seq, 1);
    const double *w = affect_hmm_weights(h);
    assert_true(w[0] == 0.5 && w[1] == 0.5 && w[2] == 0.0);
    affect_hmm_free(h);

    cfg.max_iter = 1; /* one M-step: re-seeded */
    h = train_ok(&cfg, &seq, 1);
    affect_hmm_report rep;
    affect_hmm_get_report(h, &rep);
    assert_int_equal(rep.reseeded, 1);
    w = affect_hmm_weights(h);
    const double *mu = affect_hmm_means(h), *cov = affect_hmm_covariances(h);
    /* at a data value (both are explained equally badly: the first in time wins), with the
     * state's pooled covariance ((±1)² = 1, plus reg) and one frame's weight of 100 */
    tu_assert_near(fabs(mu[2]), 1.0, 0);
    tu_assert_near(cov[2], 1.0 + cfg.reg, 1e-12);
    tu_assert_near(w[2], 1.0 / 101.0, 1e-12);
    tu_assert_near(w[0], 0.5 / 1.01, 1e-12);
    tu_assert_near(w[1], 0.5 / 1.01, 1e-12);
    affect_hmm_free(h);

    cfg.max_iter = 5; /* and training goes on from there */
    h = train_ok(&cfg, &seq, 1);
    affect_hmm_get_report(h, &rep);
    assert_true(rep.reseeded >= 1);
    w = affect_hmm_weights(h);
    for (int j = 0; j < 3; j++)
        assert_true(w[j] > 0.0);
    tu_assert_near(w[0] + w[1] + w[2], 1.0, 1e-12);
    double ll;
    affect_error err;
    assert_int_equal(affect_hmm_loglik(h, x, 100, &ll, NULL, &err), AFFECT_OK);
    assert_true(isfinite(ll));
    affect_hmm_free(h);
}

/* Impossible transitions and impossible sequences: −∞, never NaN. */
static void test_impossible(void **state)
{
    (void)state;
    affect_hmm_config cfg;
    config(&cfg, 3, 1, 1, AFFECT_HMM_DIAG, AFFECT_HMM_LEFT_RIGHT, 1, false);
    double start[3] = {1, 0, 0}, trans[9] = {0.5, 0.5, 0, 0, 0.5, 0.5, 0, 0, 1};
    double w[3] = {1, 1, 1}, mu[3] = {0, 10, 20}, cov[3] = {1, 1, 1};
    affect_hmm *h = NULL;
    affect_error err;
    assert_int_equal(affect_hmm_from_params(&cfg, start, trans, w, mu, cov, &h, &err), AFFECT_OK);
    /* 400 frames at state 2's mean: every path must pass through 0 and 1 first; the early
     * states' log α run far below the reachable maximum (exercising the exact fallback) */
    double x[400];
    for (int t = 0; t < 400; t++)
        x[t] = t < 2 ? 10.0 * t : 20.0;
    double ll, lp, gamma[1200], xi[9];
    int32_t path[400];
    assert_int_equal(affect_hmm_loglik(h, x, 400, &ll, NULL, &err), AFFECT_OK);
    assert_true(isfinite(ll));
    assert_int_equal(affect_hmm_viterbi(h, x, 400, path, &lp, NULL, &err), AFFECT_OK);
    assert_int_equal(path[0], 0);
    assert_int_equal(path[1], 1);
    assert_int_equal(path[2], 2);
    assert_int_equal(path[399], 2);
    assert_int_equal(affect_hmm_posteriors(h, x, 400, gamma, xi, &ll, NULL, &err), AFFECT_OK);
    for (int k = 0; k < 1200; k++)
        assert_false(isnan(gamma[k]));
    tu_assert_near(gamma[0], 1.0, 1e-12);
    tu_assert_near(gamma[3 + 1], 1.0, 1e-9);
    assert_true(xi[1 * 3 + 0] == 0.0 && xi[2 * 3 + 0] == 0.0 && xi[2 * 3 + 1] == 0.0);
    assert_true(xi[0 * 3 + 2] == 0.0);
    tu_assert_near(xi[0] + xi[1] + xi[2] + xi[4] + xi[5] + xi[8], 399.0, 1e-9);
    /* a value so large that every density underflows: −∞, and no posteriors */
    double far[3] = {0.0, 1e200, 20.0};
    assert_int_equal(affect_hmm_loglik(h, far, 3, &ll, NULL, &err), AFFECT_OK);
    assert_true(ll == -INFINITY);
    assert_int_equal(affect_hmm_viterbi(h, far, 3, path, &lp, NULL, &err), AFFECT_OK);
    assert_true(lp == -INFINITY);
    expect_msg(affect_hmm_posteriors(h, far, 3, gamma, xi, &ll, NULL, &err), &err, AFFECT_ERR_RANGE,
               "the sequence has probability 0 under the model: no posteriors");
    /* mean durations: 1/(1 − a_ii) */
    double per[3];
    assert_true(isinf(affect_hmm_mean_duration(h, per)));
    tu_assert_near(per[0], 2.0, 0);
    tu_assert_near(per[1], 2.0, 0);
    assert_true(isinf(per[2]));
    affect_hmm_free(h);
}

/* ---- (7) errors ---- */

static void test_config_errors(void **state)
{
    (void)state;
    affect_hmm_config cfg;
    affect_hmm_config_default(&cfg);
    assert_int_equal(cfg.n_states, 7);
    assert_int_equal(cfg.n_mix, 4);
    assert_int_equal(cfg.cov, AFFECT_HMM_FULL);
    assert_int_equal(cfg.topology, AFFECT_HMM_ERGODIC);
    assert_false(cfg.learn_start);
    assert_int_equal(cfg.max_iter, 50);
    assert_true(cfg.tol == 1e-4 && cfg.reg == 1e-4 && cfg.seed == 1);
    assert_string_equal(affect_hmm_config_check(&cfg),
                        "observation dimension must be between 1 and 4096");
    cfg.dim = 4096;
    assert_null(affect_hmm_config_check(&cfg));
    cfg.dim = 4097;
    assert_string_equal(affect_hmm_config_check(&cfg),
                        "observation dimension must be between 1 and 4096");
#define BAD(stmt, text)                                                                            \
    do {                                                                                           \
        affect_hmm_config_default(&cfg);                                                           \
        cfg.dim = 3;                                                                               \
        stmt;                                                                                      \
        const char *got_ = affect_hmm_config_check(&cfg);                                          \
        assert_non_null(got_);                                                                     \
        assert_string_equal(got_, text);                                                           \
    } while (0)
    BAD(cfg.n_states = 0, "states must be between 1 and 256");
    BAD(cfg.n_states = 257, "states must be between 1 and 256");
    BAD(cfg.n_mix = 0, "mixtures must be between 1 and 64");
    BAD(cfg.n_mix = 65, "mixtures must be between 1 and 64");
    BAD(cfg.cov = (affect_hmm_cov)2, "covariance must be full or diagonal");
    BAD(cfg.topology = (affect_hmm_topology)5, "topology must be ergodic or left-right");
    BAD(cfg.max_jump = 1, "max_jump needs the left-right topology");
    BAD((cfg.topology = AFFECT_HMM_LEFT_RIGHT, cfg.max_jump = 7),
        "max_jump must be less than the number of states");
    BAD(cfg.max_iter = 100001, "max_iter must be at most 100000");
    BAD(cfg.tol = -1, "tol must be a finite number, 0 or more");
    BAD(cfg.tol = NAN, "tol must be a finite number, 0 or more");
    BAD(cfg.reg = INFINITY, "reg must be a finite number, 0 or more");
    BAD(cfg.reg = -1e-9, "reg must be a finite number, 0 or more");
#undef BAD
    assert_string_equal(affect_hmm_config_check(NULL), "no configuration");
}

static void test_train_errors(void **state)
{
    (void)state;
    affect_hmm_config cfg;
    config(&cfg, 2, 1, 2, AFFECT_HMM_FULL, AFFECT_HMM_ERGODIC, 0, false);
    affect_hmm *h = (affect_hmm *)&cfg; /* must be reset to NULL on failure */
    affect_error err;
    double x[40];
    for (int i = 0; i < 40; i++)
        x[i] = i % 7;
    affect_hmm_seq seqs[3] = {{x, 20}, {x, 20}, {x, 20}};
    expect_msg(affect_hmm_train(&cfg, seqs, 0, &h, &err), &err, AFFECT_ERR_INVALID, "no sequences");
    assert_null(h);
    cfg.dim = 0;
    expect_msg(affect_hmm_train(&cfg, seqs, 3, &h, &err), &err, AFFECT_ERR_INVALID,
               "observation dimension must be between 1 and 4096");
    cfg.dim = 2;
    x[2 * 10 + 1] = NAN;
    expect_msg(affect_hmm_train(&cfg, seqs, 3, &h, &err), &err, AFFECT_ERR_INVALID,
               "sequence 0, frame 10: value 1 is not finite");
    x[2 * 10 + 1] = 0;
    double x2[20] = {0};
    x2[2 * 9] = -INFINITY;
    affect_hmm_seq two[2] = {{x, 20}, {x2, 10}};
    expect_msg(affect_hmm_train(&cfg, two, 2, &h, &err), &err, AFFECT_ERR_INVALID,
               "sequence 1, frame 9: value 0 is not finite");
    seqs[1].x = NULL;
    expect_msg(affect_hmm_train(&cfg, seqs, 3, &h, &err), &err, AFFECT_ERR_INVALID,
               "sequence 1 has no data");
    seqs[1].x = x;
    seqs[2].n_frames = 0;
    cfg.n_states = 1;
    expect_msg(affect_hmm_train(&cfg, seqs, 3, &h, &err), &err, AFFECT_ERR_INVALID,
               "sequence 2 has 0 frames, fewer than the 1 state");
    /* reg 0 on a cluster of one distinct point: no floor can save it */
    seqs[2].n_frames = 20;
    double flat[40] = {0};
    affect_hmm_seq fs = {flat, 20};
    cfg.reg = 0;
    expect_msg(affect_hmm_train(&cfg, &fs, 1, &h, &err), &err, AFFECT_ERR_RANGE,
               "the covariance of state 0, mixture 0 is not positive definite even with 0 added "
               "to its diagonal (raise reg)");
    assert_null(h);
    cfg.reg = 1e-6;
    h = train_ok(&cfg, &fs, 1);
    affect_hmm_free(h);

    /* scoring errors */
    h = truth_model();
    double ll, g[6], xi[9];
    int32_t path[3];
    double y[6] = {0, 0, 1, 1, 2, 2};
    expect_msg(affect_hmm_loglik(h, y, 0, &ll, NULL, &err), &err, AFFECT_ERR_INVALID,
               "the sequence has no frames");
    expect_msg(affect_hmm_loglik(h, NULL, 3, &ll, NULL, &err), &err, AFFECT_ERR_INVALID,
               "the sequence has no data");
    y[5] = NAN;
    expect_msg(affect_hmm_loglik(h, y, 3, &ll, NULL, &err), &err, AFFECT_ERR_INVALID,
               "frame 2: value 1 is not finite");
    expect_msg(affect_hmm_viterbi(h, y, 3, path, &ll, NULL, &err), &err, AFFECT_ERR_INVALID,
               "frame 2: value 1 is not finite");
    expect_msg(affect_hmm_posteriors(h, y, 3, g, xi, &ll, NULL, &err), &err, AFFECT_ERR_INVALID,
               "frame 2: value 1 is not finite");
    y[5] = 2;
    expect_msg(affect_hmm_viterbi(h, y, 3, NULL, &ll, NULL, &err), &err, AFFECT_ERR_INVALID,
               "no room for the path");
    affect_hmm_free(h);
}

static void test_from_params_errors(void **state)
{
    (void)state;
    affect_hmm_config cfg;
    config(&cfg, 3, 2, 2, AFFECT_HMM_FULL, AFFECT_HMM_ERGODIC, 0, false);
    double start[3] = {1, 0, 0};
    double trans[9] = {0.8, 0.1, 0.1, 0.1, 0.8, 0.1, 0.1, 0.1, 0.8};
    double w[6] = {0.5, 0.5, 0.5, 0.5, 0.5, 0.5};
    double mu[12] = {0};
    double cov[24];
    for (int k = 0; k < 6; k++) {
        cov[k * 4] = 1.0;
        cov[k * 4 + 1] = cov[k * 4 + 2] = 0.5;
        cov[k * 4 + 3] = 1.0;
    }
    affect_hmm *h = NULL;
    affect_error err;
#define EXPECT(text)                                                                               \
    do {                                                                                           \
        expect_msg(affect_hmm_from_params(&cfg, start, trans, w, mu, cov, &h, &err), &err,         \
                   AFFECT_ERR_INVALID, text);                                                      \
        assert_null(h);                                                                            \
    } while (0)
    assert_int_equal(affect_hmm_from_params(&cfg, start, trans, w, mu, cov, &h, &err), AFFECT_OK);
    affect_hmm_free(h);

    trans[7] = 0.0; /* row 2: 0.1 + 0 + 0.8 */
    EXPECT("transition row 2 sums to 0.9, not 1");
    trans[7] = -0.1;
    EXPECT("transition 2 -> 1 is -0.1, not a probability");
    trans[7] = NAN;
    EXPECT("transition 2 -> 1 is nan, not a probability");
    trans[7] = 0.1;
    cfg.topology = AFFECT_HMM_LEFT_RIGHT;
    EXPECT("transition 1 -> 0 is 0.1, but the left-right topology forbids it");
    trans[3] = 0.0; /* upper triangular; 0 -> 2 jumps two states */
    trans[6] = 0.0;
    trans[7] = 0.0;
    trans[4] = 0.9;
    trans[8] = 1.0;
    cfg.max_jump = 1;
    EXPECT("transition 0 -> 2 is 0.1, but max_jump is 1");
    cfg.max_jump = 2;
    assert_int_equal(affect_hmm_from_params(&cfg, start, trans, w, mu, cov, &h, &err), AFFECT_OK);
    affect_hmm_free(h);
    cfg.max_jump = 0;
    cfg.topology = AFFECT_HMM_ERGODIC;
    trans[3] = trans[6] = trans[7] = 0.1;
    trans[4] = trans[8] = 0.8;

    start[1] = 0.5;
    EXPECT("start probabilities sum to 1.5, not 1");
    start[0] = 0.5;
    EXPECT("start probability of state 0 is 0.5, but the start is not learned: it must be "
           "(1, 0, ..., 0)");
    cfg.learn_start = true;
    assert_int_equal(affect_hmm_from_params(&cfg, start, trans, w, mu, cov, &h, &err), AFFECT_OK);
    tu_assert_near(affect_hmm_start(h)[1], 0.5, 0);
    affect_hmm_free(h);
    start[2] = 1.5;
    EXPECT("start probability of state 2 is 1.5, not a probability");
    start[0] = 1;
    start[1] = start[2] = 0;
    cfg.learn_start = false;

    w[3] = 0.25;
    EXPECT("weights of state 1 sum to 0.75, not 1");
    w[3] = -0.5;
    EXPECT("weight of state 1, mixture 1 is -0.5, not a probability");
    w[3] = 0.5;

    mu[2 * 2 + 1] = INFINITY;
    EXPECT("mean of state 1, mixture 0: value 1 is not finite");
    mu[2 * 2 + 1] = 0;

    cov[1 * 4 + 1] = 2.0; /* state 0, mixture 1: |ρ| > 1 */
    cov[1 * 4 + 2] = 2.0;
    EXPECT("covariance of state 0, mixture 1 is not positive definite");
    cov[1 * 4 + 2] = 0.4;
    EXPECT("covariance of state 0, mixture 1 is not symmetric: (0, 1) is 2, (1, 0) is 0.4");
    cov[1 * 4 + 1] = cov[1 * 4 + 2] = 0.5;
    cov[5 * 4 + 3] = NAN;
    EXPECT("covariance of state 2, mixture 1: entry (1, 1) is not finite");
    cov[5 * 4 + 3] = 1.0;
    cov[2 * 4] = 0.0;
    cov[2 * 4 + 1] = cov[2 * 4 + 2] = 0.0;
    EXPECT("covariance of state 1, mixture 0 is not positive definite");
    cov[2 * 4] = 1.0;

    cfg.cov = AFFECT_HMM_DIAG; /* the diagonals: first 12 values */
    double var[12] = {1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1};
    var[7] = 0.0;
    expect_msg(affect_hmm_from_params(&cfg, start, trans, w, mu, var, &h, &err), &err,
               AFFECT_ERR_INVALID, "covariance of state 1, mixture 1 is not positive definite");
    var[7] = -INFINITY;
    expect_msg(affect_hmm_from_params(&cfg, start, trans, w, mu, var, &h, &err), &err,
               AFFECT_ERR_INVALID, "covariance of state 1, mixture 1: variance 1 is not finite");
    cfg.cov = AFFECT_HMM_FULL;

    cfg.n_mix = 0;
    EXPECT("mixtures must be between 1 and 64");
    cfg.n_mix = 2;
    expect_msg(affect_hmm_from_params(&cfg, start, NULL, w, mu, cov, &h, &err), &err,
               AFFECT_ERR_INVALID, "missing parameters");
#undef EXPECT

    /* the report */
    assert_int_equal(affect_hmm_from_params(&cfg, start, trans, w, mu, cov, &h, &err), AFFECT_OK);
    affect_hmm_report rep;
    affect_hmm_get_report(h, &rep);
    assert_int_equal(rep.iterations, 0);
    assert_false(rep.converged);
    assert_non_null(rep.loglik);
    assert_true(rep.loglik[0] == 0.0);
    double hist[3] = {-100, -90, -89.5};
    affect_hmm_report in = {2, true, hist, 1, 4, 1000};
    assert_int_equal(affect_hmm_set_report(h, &in, &err), AFFECT_OK);
    affect_hmm_get_report(h, &rep);
    assert_int_equal(rep.iterations, 2);
    assert_true(rep.converged);
    assert_memory_equal(rep.loglik, hist, sizeof hist);
    assert_int_equal(rep.reseeded, 1);
    assert_int_equal(rep.n_sequences, 4);
    assert_int_equal(rep.n_frames, 1000);
    in.iterations = 51;
    expect_msg(affect_hmm_set_report(h, &in, &err), &err, AFFECT_ERR_INVALID,
               "the report has 51 iterations, more than max_iter 50");
    in.iterations = 2;
    hist[1] = NAN;
    expect_msg(affect_hmm_set_report(h, &in, &err), &err, AFFECT_ERR_INVALID,
               "log-likelihood 1 of the report is not finite");
    in.loglik = NULL;
    expect_msg(affect_hmm_set_report(h, &in, &err), &err, AFFECT_ERR_INVALID,
               "the report has no log-likelihoods");
    affect_hmm_free(h);
}

/* ---- (8) out of memory ---- */

typedef struct oom_train_ctx {
    const affect_hmm_seq *seqs;
    uint32_t n;
    affect_hmm_config cfg;
    affect_hmm *h;
} oom_train_ctx;

static affect_status oom_train(void *ctx, affect_error *err)
{
    oom_train_ctx *c = ctx;
    c->h = NULL;
    return affect_hmm_train(&c->cfg, c->seqs, c->n, &c->h, err);
}

static void oom_train_finish(void *ctx, affect_status st)
{
    oom_train_ctx *c = ctx;
    if (st != AFFECT_OK) {
        assert_null(c->h);
        return;
    }
    assert_non_null(c->h);
    affect_hmm_free(c->h);
}

typedef struct oom_score_ctx {
    const affect_hmm *h;
    const double *x;
    uint32_t T;
    int what;
} oom_score_ctx;

static affect_status oom_score(void *ctx, affect_error *err)
{
    oom_score_ctx *c = ctx;
    double ll, g[40 * 6], xi[9];
    int32_t path[40];
    if (c->what == 0)
        return affect_hmm_loglik(c->h, c->x, c->T, &ll, NULL, err);
    if (c->what == 1)
        return affect_hmm_viterbi(c->h, c->x, c->T, path, &ll, NULL, err);
    return affect_hmm_posteriors(c->h, c->x, c->T, g, xi, &ll, NULL, err);
}

static affect_hmm *oom_built;

static affect_status oom_from_params(void *ctx, affect_error *err)
{
    const affect_hmm *h = ctx;
    oom_built = NULL;
    return affect_hmm_from_params(affect_hmm_get_config(h), affect_hmm_start(h),
                                  affect_hmm_transitions(h), affect_hmm_weights(h),
                                  affect_hmm_means(h), affect_hmm_covariances(h), &oom_built, err);
}

static void oom_from_params_finish(void *ctx, affect_status st)
{
    (void)ctx;
    if (st != AFFECT_OK) {
        assert_null(oom_built);
        return;
    }
    assert_same_model(ctx, oom_built);
    affect_hmm_free(oom_built);
}

static void test_out_of_memory(void **state)
{
    (void)state;
    affect_hmm *truth = truth_model();
    affect_rng rng;
    affect_rng_seed(&rng, 17);
    static double x[2][60 * 2];
    affect_hmm_seq seqs[2];
    for (int s = 0; s < 2; s++) {
        sample(truth, &rng, 40 + 20 * s, x[s], NULL);
        seqs[s].x = x[s];
        seqs[s].n_frames = 40 + 20 * s;
    }
    oom_train_ctx c = {seqs, 2, {0}, NULL};
    config(&c.cfg, 3, 2, 2, AFFECT_HMM_FULL, AFFECT_HMM_ERGODIC, 0, false);
    c.cfg.max_iter = 3;
    /* one block for the model, one workspace */
    assert_int_equal(tu_oom_sweep(oom_train, &c, oom_train_finish, NULL), 2);
    for (int what = 0; what < 3; what++) {
        oom_score_ctx s = {truth, x[0], 40, what};
        assert_int_equal(tu_oom_sweep(oom_score, &s, NULL, NULL), 1);
    }
    /* from_params: the model block */
    assert_int_equal(tu_oom_sweep(oom_from_params, truth, oom_from_params_finish, NULL), 1);
    affect_hmm_free(truth);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_brute_force),
        cmocka_unit_test(test_wide_full),
        cmocka_unit_test(test_recovers_model),
        cmocka_unit_test(test_long_sequence),
        cmocka_unit_test(test_posteriors),
        cmocka_unit_test(test_mstep_sharp),
        cmocka_unit_test(test_deterministic),
        cmocka_unit_test(test_degenerate),
        cmocka_unit_test(test_reseed),
        cmocka_unit_test(test_impossible),
        cmocka_unit_test(test_config_errors),
        cmocka_unit_test(test_train_errors),
        cmocka_unit_test(test_from_params_errors),
        cmocka_unit_test(test_out_of_memory),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
