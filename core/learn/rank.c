/*
 * rank.c — relative-attribute ranking (affect/rank.h; SCIENCE.md §6): the primal Newton
 * solver, pairs from label levels, k-means pose clusters, and the ranker BLOB.
 *
 * How the solver works (see the header for the equations): the samples are first put in
 * coordinates Y (n × r) — X itself when d ≤ n, else U S from the eigenvectors of XXᵀ, so that
 * w = Xᵀ β with β = U S⁻¹ u. Each Newton iteration:
 *   1. scores s = Y u; the active set: ordered pairs with s_i − s_j < 1, every similar pair;
 *   2. T = L Y accumulated pair by pair (T_i += Y_i − Y_j, T_j −= Y_i − Y_j), never forming the
 *      n × n matrix L; H = I + 2C Yᵀ T (cblas_dgemm); rhs = 2C Yᵀ g, g = Σ_ordered e_i − e_j;
 *   3. the Newton point solves H u' = rhs (LAPACKE_dposv, called in column-major form on the
 *      symmetric array, which is the same matrix, so LAPACKE makes no transposed copy);
 *   4. u' is taken when f does not increase, else the step u' − u is halved until it does.
 * The loop stops when the active set at u equals the one u was solved on (u is then the exact
 * minimizer: the gradient of the quadratic on that set vanishes and the set is consistent).
 *
 * Memory: one workspace per fit (n r + n² when reduced, r² + 3r + n + the pair flags); sizes
 * are overflow-checked. The eigen-decomposition runs LAPACKE_dsyev_work with the minimal
 * workspace 3n − 1, so it allocates nothing outside ours.
 */
#include "affect/rank.h"

#include <cblas.h>
#include <lapacke.h>
#include <limits.h>
#include <math.h>
#include <string.h>

#include "util/bytes.h"
#include "affect/hmm_blob.h" /* affect_fnv1a64 */
#include "util/rng.h"
#include "util/internal.h"

#define KMEANS_MAX_ITER 100
#define MAX_HALVINGS 40
#define BLAS_MAX ((size_t)INT_MAX)
#define HEADER_SIZE 72u

void affect_rank_options_default(affect_rank_options *opt)
{
    memset(opt, 0, sizeof *opt);
    opt->C = 1.0;
    opt->max_iter = 50;
    opt->clusters = 1;
}

const char *affect_rank_check(const affect_rank_options *opt)
{
    if (!(isfinite(opt->C) && opt->C > 0))
        return "C must be finite and > 0";
    if (opt->max_iter < 1 || opt->max_iter > AFFECT_RANK_MAX_ITER)
        return "max_iter must be from 1 to 100";
    if (opt->clusters > AFFECT_RANK_MAX_CLUSTERS)
        return "clusters must be from 0 to 256";
    return NULL;
}

double affect_rank_objective(const double *X, uint32_t d, const affect_rank_pair *pairs,
                             size_t n_pairs, double C, const double *w, double *grad)
{
    double f = 0;
    for (uint32_t k = 0; k < d; k++) {
        f += 0.5 * w[k] * w[k];
        if (grad)
            grad[k] = w[k];
    }
    for (size_t p = 0; p < n_pairs; p++) {
        const double *xi = X + (size_t)pairs[p].i * d, *xj = X + (size_t)pairs[p].j * d;
        double m = 0;
        for (uint32_t k = 0; k < d; k++)
            m += w[k] * (xi[k] - xj[k]);
        double res = pairs[p].similar ? m : (m < 1 ? m - 1 : 0);
        f += C * res * res;
        if (grad && res != 0)
            for (uint32_t k = 0; k < d; k++)
                grad[k] += 2 * C * res * (xi[k] - xj[k]);
    }
    return f;
}

/* f in coordinates Y (n × r) for u, with the scores s = Y u written. */
static double coord_objective(const double *Y, uint32_t n, uint32_t r,
                              const affect_rank_pair *pairs, size_t n_pairs, double C,
                              const double *u, double *s)
{
    AFFECT_BLAS(
        cblas_dgemv(CblasRowMajor, CblasNoTrans, (int)n, (int)r, 1.0, Y, (int)r, u, 1, 0.0, s, 1));
    double f = 0;
    for (uint32_t k = 0; k < r; k++)
        f += 0.5 * u[k] * u[k];
    for (size_t p = 0; p < n_pairs; p++) {
        double m = s[pairs[p].i] - s[pairs[p].j];
        double res = pairs[p].similar ? m : (m < 1 ? m - 1 : 0);
        f += C * res * res;
    }
    return f;
}

static affect_status check_pairs(uint32_t n, const affect_rank_pair *pairs, size_t n_pairs,
                                 affect_error *err)
{
    for (size_t p = 0; p < n_pairs; p++) {
        if (pairs[p].i >= n || pairs[p].j >= n)
            return affect_fail(err, AFFECT_ERR_RANGE, "pair %zu refers to sample %u of %u", p,
                               pairs[p].i >= n ? pairs[p].i : pairs[p].j, n);
        if (pairs[p].i == pairs[p].j)
            return affect_fail(err, AFFECT_ERR_INVALID, "pair %zu pairs sample %u with itself", p,
                               pairs[p].i);
    }
    return AFFECT_OK;
}

affect_status affect_rank_fit(const double *X, uint32_t n, uint32_t d,
                              const affect_rank_pair *pairs, size_t n_pairs,
                              const affect_rank_options *opt, double *w, affect_rank_stats *stats,
                              affect_error *err)
{
    affect_rank_options def;
    if (!opt) {
        affect_rank_options_default(&def);
        opt = &def;
    }
    affect_rank_stats st;
    memset(&st, 0, sizeof st);
    const char *bad = affect_rank_check(opt);
    if (bad)
        return affect_fail(err, AFFECT_ERR_INVALID, "%s (got C = %g, max_iter = %u)", bad, opt->C,
                           opt->max_iter);
    if (n < 2 || d < 1 || d > AFFECT_RANK_MAX_DIM || n > (uint32_t)INT_MAX / 2)
        return affect_fail(err, AFFECT_ERR_RANGE,
                           "need at least 2 samples of 1 to 1048576 dimensions (got %u of %u)", n,
                           d);
    if (n_pairs == 0)
        return affect_fail(err, AFFECT_ERR_INVALID, "no pairs");
    affect_status st_chk = check_pairs(n, pairs, n_pairs, err);
    if (st_chk != AFFECT_OK)
        return st_chk;
    size_t nd;
    if (!affect_mul_size(n, d, &nd) || nd > BLAS_MAX)
        return affect_fail(err, AFFECT_ERR_RANGE, "%u samples of %u dimensions is too large", n, d);
    for (size_t k = 0; k < nd; k++)
        if (!isfinite(X[k]))
            return affect_fail(err, AFFECT_ERR_FORMAT, "non-finite value in sample %zu", k / d);
    affect_status status = AFFECT_OK;
    bool reduce = d > n;
    uint32_t r = reduce ? n : d;
    double *Y = NULL, *G = NULL, *ev = NULL, *work = NULL, *T = NULL, *H = NULL, *rhs = NULL;
    double *u = NULL, *un = NULL, *s = NULL, *gvec = NULL;
    unsigned char *act = NULL, *prev = NULL;
    affect_ws_part parts[] = {
        {(void **)&Y, reduce ? (size_t)n * n : 0, sizeof(double)},
        {(void **)&G, reduce ? (size_t)n * n : 0, sizeof(double)},
        {(void **)&ev, reduce ? n : 0, sizeof(double)},
        {(void **)&work, reduce ? 3 * (size_t)n : 0, sizeof(double)},
        {(void **)&T, (size_t)n * r, sizeof(double)},
        {(void **)&H, (size_t)r * r, sizeof(double)},
        {(void **)&rhs, r, sizeof(double)},
        {(void **)&u, r, sizeof(double)},
        {(void **)&un, r, sizeof(double)},
        {(void **)&s, n, sizeof(double)},
        {(void **)&gvec, n, sizeof(double)},
        {(void **)&act, n_pairs, 1},
        {(void **)&prev, n_pairs, 1},
    };
    void *block = affect_ws_alloc(parts, sizeof parts / sizeof parts[0]);
    if (!block)
        return affect_nomem_of(err, (size_t)n * r, sizeof(double) * 3, "the ranker's workspace");
    const double *coords = X;
    if (reduce) {
        /* G = X Xᵀ, eigenvectors in the rows of G (column-major call on a symmetric array) */
        AFFECT_BLAS(cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasTrans, (int)n, (int)n, (int)d,
                                1.0, X, (int)d, X, (int)d, 0.0, G, (int)n));
        int info = affect_sym_eigen(G, n, ev, work);
        if (info != 0) {
            status = affect_fail(err, AFFECT_ERR_RANGE,
                                 "the eigen-decomposition of the Gram matrix failed (info %d)",
                                 (int)info);
            goto cleanup;
        }
        double lmax = ev[n - 1] > 0 ? ev[n - 1] : 0;
        r = 0;
        for (uint32_t k = n; k-- > 0;)
            if (ev[k] > AFFECT_RANK_RANK_TOL * lmax && lmax > 0)
                r++;
        if (r == 0)
            r = 1; /* all samples zero: one zero coordinate */
        /* column c of Y = sqrt(λ) × eigenvector, largest first */
        for (uint32_t c = 0; c < r; c++) {
            uint32_t k = n - 1 - c;
            double sl = ev[k] > 0 ? sqrt(ev[k]) : 0;
            for (uint32_t i = 0; i < n; i++)
                Y[(size_t)i * r + c] = sl * G[(size_t)k * n + i];
        }
        coords = Y;
    }
    memset(u, 0, sizeof(double) * r);
    double f = coord_objective(coords, n, r, pairs, n_pairs, opt->C, u, s);
    bool full_step = false;
    uint32_t it = 0;
    for (;;) {
        status = affect_monitor_check(opt->monitor, err);
        if (status != AFFECT_OK)
            goto cleanup;
        for (size_t p = 0; p < n_pairs; p++)
            act[p] = pairs[p].similar || s[pairs[p].i] - s[pairs[p].j] < 1;
        if (it > 0 && full_step && memcmp(act, prev, n_pairs) == 0) {
            st.converged = true;
            break;
        }
        if (it == opt->max_iter)
            break;
        it++;
        memcpy(prev, act, n_pairs);
        memset(T, 0, sizeof(double) * (size_t)n * r);
        memset(gvec, 0, sizeof(double) * n);
        for (size_t p = 0; p < n_pairs; p++) {
            if (!act[p])
                continue;
            uint32_t i = pairs[p].i, j = pairs[p].j;
            double *ti = T + (size_t)i * r, *tj = T + (size_t)j * r;
            const double *yi = coords + (size_t)i * r, *yj = coords + (size_t)j * r;
            for (uint32_t k = 0; k < r; k++) {
                double z = yi[k] - yj[k];
                ti[k] += z;
                tj[k] -= z;
            }
            if (!pairs[p].similar) {
                gvec[i] += 1;
                gvec[j] -= 1;
            }
        }
        double c2 = 2 * opt->C;
        AFFECT_BLAS(cblas_dgemm(CblasRowMajor, CblasTrans, CblasNoTrans, (int)r, (int)r, (int)n, c2,
                                coords, (int)r, T, (int)r, 0.0, H, (int)r));
        for (uint32_t a = 0; a < r; a++) {
            H[(size_t)a * r + a] += 1.0;
            for (uint32_t b = 0; b < a; b++)
                H[(size_t)a * r + b] = H[(size_t)b * r + a] =
                    0.5 * (H[(size_t)a * r + b] + H[(size_t)b * r + a]);
        }
        AFFECT_BLAS(cblas_dgemv(CblasRowMajor, CblasTrans, (int)n, (int)r, c2, coords, (int)r, gvec,
                                1, 0.0, rhs, 1));
        lapack_int info;
        AFFECT_BLAS(info = LAPACKE_dposv(LAPACK_COL_MAJOR, 'U', (lapack_int)r, 1, H, (lapack_int)r,
                                         rhs, (lapack_int)r));
        if (info != 0) {
            status = affect_fail(err, AFFECT_ERR_RANGE,
                                 "the Newton system is not positive definite (info %d)", (int)info);
            goto cleanup;
        }
        /* rhs holds the Newton point; take it, or halve the step until f does not increase */
        double step = 1.0;
        full_step = true;
        for (uint32_t h = 0;; h++) {
            for (uint32_t k = 0; k < r; k++)
                un[k] = u[k] + step * (rhs[k] - u[k]);
            double fn = coord_objective(coords, n, r, pairs, n_pairs, opt->C, un, s);
            if (fn <= f || h == MAX_HALVINGS) {
                f = fn;
                break;
            }
            step *= 0.5;
            full_step = false;
            st.halvings++;
        }
        memcpy(u, un, sizeof(double) * r);
    }
    st.iterations = it;
    /* back to w */
    if (reduce) {
        /* β = U S⁻¹ u, w = Xᵀ β (gvec reused for β) */
        memset(gvec, 0, sizeof(double) * n);
        for (uint32_t c = 0; c < r; c++) {
            uint32_t k = n - 1 - c;
            if (!(ev[k] > 0))
                continue;
            double scale = u[c] / sqrt(ev[k]);
            for (uint32_t i = 0; i < n; i++)
                gvec[i] += scale * G[(size_t)k * n + i];
        }
        AFFECT_BLAS(cblas_dgemv(CblasRowMajor, CblasTrans, (int)n, (int)d, 1.0, X, (int)d, gvec, 1,
                                0.0, w, 1));
    } else {
        memcpy(w, u, sizeof(double) * d);
    }
    for (size_t p = 0; p < n_pairs; p++) {
        if (pairs[p].similar) {
            st.similar++;
            continue;
        }
        st.ordered++;
        if (s[pairs[p].i] - s[pairs[p].j] > 0)
            st.correct++;
    }
    st.objective = f;
    if (stats)
        *stats = st;
cleanup:
    affect_free(block);
    return status;
}

int affect_sym_eigen(double *G, uint32_t n, double *ev, double *work)
{
    for (uint32_t i = 0; i < n; i++)
        for (uint32_t j = 0; j < i; j++)
            G[(size_t)i * n + j] = G[(size_t)j * n + i] =
                0.5 * (G[(size_t)i * n + j] + G[(size_t)j * n + i]);
    lapack_int info;
    AFFECT_BLAS(info = LAPACKE_dsyev_work(LAPACK_COL_MAJOR, 'V', 'U', (lapack_int)n, G,
                                          (lapack_int)n, ev, work, (lapack_int)(3 * n - 1)));
    return (int)info;
}

/* ---- pairs ---- */

/* Keeps round(fraction × count) (at least 1) of the count flagged pairs of one kind. */
static void sample_kind(affect_rank_pair *pairs, unsigned char *keep, size_t n_pairs,
                        uint8_t similar, size_t count, double fraction, affect_rng *rng,
                        size_t *idx)
{
    size_t m = 0;
    for (size_t p = 0; p < n_pairs; p++)
        if (pairs[p].similar == similar)
            idx[m++] = p;
    size_t want = (size_t)floor(fraction * (double)count + 0.5);
    if (want < 1 && count > 0)
        want = 1;
    if (want > m)
        want = m;
    /* partial Fisher–Yates: the first want of a seeded shuffle */
    for (size_t a = 0; a < want; a++) {
        size_t b = a + (size_t)(affect_rng_uniform(rng) * (double)(m - a));
        if (b >= m)
            b = m - 1;
        size_t t = idx[a];
        idx[a] = idx[b];
        idx[b] = t;
        keep[idx[a]] = 1;
    }
}

affect_status affect_rank_pairs(const int32_t *level, const uint32_t *group, uint32_t n,
                                bool similar, double fraction, uint64_t seed,
                                affect_rank_pair **pairs, size_t *n_pairs, affect_error *err)
{
    *pairs = NULL;
    *n_pairs = 0;
    if (!(fraction > 0 && fraction <= 1))
        return affect_fail(err, AFFECT_ERR_INVALID, "fraction must be in (0, 1] (got %g)",
                           fraction);
    size_t total = 0, ordered = 0, sim = 0;
    for (uint32_t i = 0; i < n; i++) {
        if (level[i] < 0)
            continue;
        for (uint32_t j = i + 1; j < n; j++) {
            if (level[j] < 0 || (group && group[i] != group[j]))
                continue;
            if (level[i] != level[j])
                ordered++;
            else if (similar)
                sim++;
        }
    }
    total = ordered + sim;
    if (total == 0)
        return AFFECT_OK;
    affect_rank_pair *all = affect_malloc_array(total, sizeof *all);
    unsigned char *keep = affect_calloc(total, 1);
    size_t *idx = affect_malloc_array(total, sizeof *idx);
    affect_status status = AFFECT_OK;
    if (!all || !keep || !idx) {
        status = affect_nomem_of(err, total, sizeof *all + sizeof *idx + 1, "%zu pairs", total);
        goto cleanup;
    }
    size_t m = 0;
    for (uint32_t i = 0; i < n; i++) {
        if (level[i] < 0)
            continue;
        for (uint32_t j = i + 1; j < n; j++) {
            if (level[j] < 0 || (group && group[i] != group[j]))
                continue;
            if (level[i] == level[j] && !similar)
                continue;
            affect_rank_pair pr;
            pr.similar = level[i] == level[j];
            pr.i = level[i] >= level[j] ? i : j;
            pr.j = level[i] >= level[j] ? j : i;
            all[m++] = pr;
        }
    }
    if (fraction < 1) {
        affect_rng rng;
        affect_rng_seed(&rng, seed);
        sample_kind(all, keep, total, 0, ordered, fraction, &rng, idx);
        sample_kind(all, keep, total, 1, sim, fraction, &rng, idx);
        size_t k = 0;
        for (size_t p = 0; p < total; p++)
            if (keep[p])
                all[k++] = all[p];
        m = k;
    }
    *pairs = all;
    *n_pairs = m;
    all = NULL;
cleanup:
    affect_free(all);
    affect_free(keep);
    affect_free(idx);
    return status;
}

/* ---- k-means ---- */

static double sqdist(const double *a, const double *b, uint32_t d)
{
    double s = 0;
    for (uint32_t k = 0; k < d; k++) {
        double t = a[k] - b[k];
        s += t * t;
    }
    return s;
}

static uint32_t nearest(const double *centroids, uint32_t k, uint32_t d, const double *x)
{
    uint32_t best = 0;
    double bd = INFINITY;
    for (uint32_t c = 0; c < k; c++) {
        double dd = sqdist(centroids + (size_t)c * d, x, d);
        if (dd < bd) {
            bd = dd;
            best = c;
        }
    }
    return best;
}

affect_status affect_kmeans(const double *X, uint32_t n, uint32_t d, uint32_t k, uint64_t seed,
                            double *centroids, uint32_t *assign, affect_monitor *mon,
                            affect_error *err)
{
    if (k < 1 || k > n)
        return affect_fail(err, AFFECT_ERR_RANGE,
                           "clusters (%u) must be from 1 to the number of samples (%u)", k, n);
    double *dist = affect_malloc_array(n, sizeof *dist);
    uint32_t *count = affect_malloc_array(k, sizeof *count);
    affect_status status = AFFECT_OK;
    if (!dist || !count) {
        status = affect_nomem(err);
        goto cleanup;
    }
    affect_rng rng;
    affect_rng_seed(&rng, seed);
    uint32_t first = (uint32_t)(affect_rng_uniform(&rng) * n);
    if (first >= n)
        first = n - 1;
    memcpy(centroids, X + (size_t)first * d, sizeof(double) * d);
    for (uint32_t i = 0; i < n; i++)
        dist[i] = sqdist(X + (size_t)i * d, centroids, d);
    for (uint32_t c = 1; c < k; c++) {
        double total = 0;
        for (uint32_t i = 0; i < n; i++)
            total += dist[i];
        uint32_t pick = 0;
        if (total > 0) {
            double target = affect_rng_uniform(&rng) * total, acc = 0;
            pick = n - 1;
            for (uint32_t i = 0; i < n; i++) {
                acc += dist[i];
                if (acc > target && dist[i] > 0) {
                    pick = i;
                    break;
                }
            }
        } else {
            pick = c; /* all samples coincide with the centroids: any distinct index */
        }
        memcpy(centroids + (size_t)c * d, X + (size_t)pick * d, sizeof(double) * d);
        for (uint32_t i = 0; i < n; i++) {
            double dd = sqdist(X + (size_t)i * d, centroids + (size_t)c * d, d);
            if (dd < dist[i])
                dist[i] = dd;
        }
    }
    for (uint32_t i = 0; i < n; i++)
        assign[i] = UINT32_MAX;
    for (uint32_t iter = 0; iter < KMEANS_MAX_ITER; iter++) {
        status = affect_monitor_check(mon, err);
        if (status != AFFECT_OK)
            goto cleanup;
        bool changed = false;
        for (uint32_t i = 0; i < n; i++) {
            uint32_t c = nearest(centroids, k, d, X + (size_t)i * d);
            if (c != assign[i]) {
                assign[i] = c;
                changed = true;
            }
        }
        if (!changed)
            break;
        memset(count, 0, sizeof(uint32_t) * k);
        for (uint32_t i = 0; i < n; i++)
            count[assign[i]]++;
        for (uint32_t c = 0; c < k; c++)
            if (count[c] > 0)
                memset(centroids + (size_t)c * d, 0, sizeof(double) * d);
        for (uint32_t i = 0; i < n; i++) {
            double *ce = centroids + (size_t)assign[i] * d;
            const double *x = X + (size_t)i * d;
            for (uint32_t a = 0; a < d; a++)
                ce[a] += x[a];
        }
        for (uint32_t c = 0; c < k; c++)
            if (count[c] > 0)
                for (uint32_t a = 0; a < d; a++)
                    centroids[(size_t)c * d + a] /= count[c];
    }
cleanup:
    affect_free(dist);
    affect_free(count);
    return status;
}

/* ---- the model ---- */

static affect_ranker *ranker_alloc(uint32_t dim, uint32_t clusters)
{
    size_t cd;
    if (!affect_mul_size(dim, clusters, &cd))
        return NULL;
    affect_ranker *r = affect_calloc(1, sizeof *r);
    if (!r)
        return NULL;
    r->dim = dim;
    r->clusters = clusters;
    r->centroids = affect_calloc(cd, sizeof(double));
    r->w = affect_calloc(cd, sizeof(double));
    if (!r->centroids || !r->w) {
        affect_ranker_free(r);
        return NULL;
    }
    return r;
}

void affect_ranker_free(affect_ranker *r)
{
    if (!r)
        return;
    affect_free(r->centroids);
    affect_free(r->w);
    affect_free(r);
}

uint32_t affect_ranker_cluster(const affect_ranker *r, const double *x)
{
    return r->clusters <= 1 ? 0 : nearest(r->centroids, r->clusters, r->dim, x);
}

double affect_ranker_score(const affect_ranker *r, const double *x)
{
    const double *w = r->w + (size_t)affect_ranker_cluster(r, x) * r->dim;
    double s = 0;
    for (uint32_t k = 0; k < r->dim; k++)
        s += w[k] * x[k];
    return s;
}

affect_status affect_ranker_train(const double *X, uint32_t n, uint32_t d,
                                  const affect_rank_pair *pairs, size_t n_pairs,
                                  const affect_rank_options *opt, affect_ranker **out,
                                  affect_error *err)
{
    *out = NULL;
    affect_rank_options def;
    if (!opt) {
        affect_rank_options_default(&def);
        opt = &def;
    }
    const char *bad = affect_rank_check(opt);
    if (bad)
        return affect_fail(err, AFFECT_ERR_INVALID, "%s", bad);
    uint32_t k = opt->clusters < 1 ? 1 : opt->clusters;
    if (k > n)
        return affect_fail(err, AFFECT_ERR_RANGE,
                           "clusters (%u) exceeds the number of samples (%u)", k, n);
    if (d < 1 || d > AFFECT_RANK_MAX_DIM)
        return affect_fail(err, AFFECT_ERR_RANGE, "dimension must be from 1 to 1048576 (got %u)",
                           d);
    affect_ranker *r = ranker_alloc(d, k);
    if (!r)
        return affect_nomem(err);
    affect_status status = AFFECT_OK;
    uint32_t *assign = NULL, *map = NULL;
    double *sub = NULL;
    affect_rank_pair *sp = NULL;
    if (k == 1) {
        status = affect_rank_fit(X, n, d, pairs, n_pairs, opt, r->w, &r->stats, err);
        goto cleanup;
    }
    status = check_pairs(n, pairs, n_pairs, err);
    if (status != AFFECT_OK)
        goto cleanup;
    assign = affect_malloc_array(n, sizeof *assign);
    map = affect_malloc_array(n, sizeof *map);
    sub = affect_malloc_array((size_t)n * d, sizeof *sub);
    sp = affect_malloc_array(n_pairs, sizeof *sp);
    if (!assign || !map || !sub || !sp) {
        status = affect_nomem(err);
        goto cleanup;
    }
    status = affect_kmeans(X, n, d, k, opt->seed, r->centroids, assign, opt->monitor, err);
    if (status != AFFECT_OK)
        goto cleanup;
    r->stats.converged = true;
    for (uint32_t c = 0; c < k; c++) {
        uint32_t m = 0;
        for (uint32_t i = 0; i < n; i++) {
            if (assign[i] != c)
                continue;
            map[i] = m;
            memcpy(sub + (size_t)m * d, X + (size_t)i * d, sizeof(double) * d);
            m++;
        }
        size_t np = 0;
        for (size_t p = 0; p < n_pairs; p++)
            if (assign[pairs[p].i] == c && assign[pairs[p].j] == c) {
                sp[np] = pairs[p];
                sp[np].i = map[pairs[p].i];
                sp[np].j = map[pairs[p].j];
                np++;
            }
        if (np == 0 || m < 2)
            continue; /* no pairs inside this cluster: its w stays 0 */
        affect_rank_stats cs;
        status = affect_rank_fit(sub, m, d, sp, np, opt, r->w + (size_t)c * d, &cs, err);
        if (status != AFFECT_OK) {
            affect_prefix(err, "cluster %u", c);
            goto cleanup;
        }
        if (cs.iterations > r->stats.iterations)
            r->stats.iterations = cs.iterations;
        r->stats.halvings += cs.halvings;
        r->stats.ordered += cs.ordered;
        r->stats.similar += cs.similar;
        r->stats.correct += cs.correct;
        r->stats.objective += cs.objective;
        r->stats.converged = r->stats.converged && cs.converged;
    }
cleanup:
    affect_free(assign);
    affect_free(map);
    affect_free(sub);
    affect_free(sp);
    if (status != AFFECT_OK)
        affect_ranker_free(r);
    else
        *out = r;
    return status;
}

/* ---- the BLOB ---- */

affect_status affect_ranker_encode(const affect_ranker *r, unsigned char **out, size_t *size,
                                   affect_error *err)
{
    *out = NULL;
    *size = 0;
    size_t cd = (size_t)r->dim * r->clusters;
    affect_bw w;
    affect_bw_init(&w);
    affect_bw_header(&w, AFFECT_RANKER_MAGIC, AFFECT_RANKER_VERSION, 0);
    affect_bw_u32(&w, r->dim);
    affect_bw_u32(&w, r->clusters);
    affect_bw_u32(&w, r->stats.iterations);
    affect_bw_u32(&w, r->stats.halvings);
    affect_bw_u32(&w, r->stats.converged ? 1u : 0u);
    affect_bw_u64(&w, r->stats.ordered);
    affect_bw_u64(&w, r->stats.similar);
    affect_bw_u64(&w, r->stats.correct);
    affect_bw_f64(&w, r->stats.objective);
    affect_bw_u64(&w, 0); /* reserved */
    affect_bw_f64s(&w, r->centroids, cd);
    affect_bw_f64s(&w, r->w, cd);
    if (!w.failed)
        affect_bw_checksum(&w, 0);
    if (w.failed) {
        affect_bw_free(&w);
        return affect_nomem(err);
    }
    *out = w.data;
    *size = w.len;
    return AFFECT_OK;
}

affect_status affect_ranker_decode(const unsigned char *data, size_t size, affect_ranker **out,
                                   affect_error *err)
{
    *out = NULL;
    if (size < HEADER_SIZE + 8)
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "not a ranker BLOB (%zu bytes, the header alone is %u)", size,
                           HEADER_SIZE + 8);
    if (affect_check_magic(data, AFFECT_RANKER_MAGIC, NULL, "a ranker", 0, err) != AFFECT_OK)
        return AFFECT_ERR_FORMAT;
    affect_br rd;
    affect_br_init(&rd, data, size);
    const unsigned char *magic;
    uint32_t version, flags, dim, clusters, iters, halvings, conv;
    uint64_t ordered, similar, correct, reserved;
    double objective;
    affect_br_bytes(&rd, &magic, 4);
    affect_br_u32(&rd, &version);
    affect_br_u32(&rd, &flags);
    affect_br_u32(&rd, &dim);
    affect_br_u32(&rd, &clusters);
    affect_br_u32(&rd, &iters);
    affect_br_u32(&rd, &halvings);
    affect_br_u32(&rd, &conv);
    affect_br_u64(&rd, &ordered);
    affect_br_u64(&rd, &similar);
    affect_br_u64(&rd, &correct);
    affect_br_f64(&rd, &objective);
    affect_br_u64(&rd, &reserved);
    if (affect_check_version(version, AFFECT_RANKER_VERSION, NULL, err) != AFFECT_OK)
        return AFFECT_ERR_FORMAT;
    if (flags != 0 || conv > 1 || reserved != 0)
        return affect_fail(err, AFFECT_ERR_FORMAT, "reserved ranker fields are not zero");
    if (dim < 1 || dim > AFFECT_RANK_MAX_DIM || clusters < 1 || clusters > AFFECT_RANK_MAX_CLUSTERS)
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "ranker sizes out of range (dimension %u, clusters %u)", dim, clusters);
    size_t cd = (size_t)dim * clusters, expect;
    if (!affect_mul_size(cd, 16, &expect) || !affect_add_size(expect, HEADER_SIZE + 8, &expect) ||
        expect != size)
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "ranker BLOB length %zu does not match its sizes (expected %zu)", size,
                           expect);
    if (!affect_checksum_ok(data, size - 8))
        return affect_fail(err, AFFECT_ERR_FORMAT, "ranker checksum mismatch: the BLOB is corrupt");
    if (!isfinite(objective) || correct > ordered)
        return affect_fail(err, AFFECT_ERR_FORMAT, "inconsistent ranker statistics");
    affect_ranker *r = ranker_alloc(dim, clusters);
    if (!r)
        return affect_nomem(err);
    affect_br_f64s(&rd, r->centroids, cd);
    affect_br_f64s(&rd, r->w, cd);
    for (size_t k = 0; k < cd; k++)
        if (!isfinite(r->centroids[k]) || !isfinite(r->w[k])) {
            affect_ranker_free(r);
            return affect_fail(err, AFFECT_ERR_FORMAT, "non-finite value in the ranker");
        }
    r->stats.iterations = iters;
    r->stats.halvings = halvings;
    r->stats.converged = conv != 0;
    r->stats.ordered = ordered;
    r->stats.similar = similar;
    r->stats.correct = correct;
    r->stats.objective = objective;
    *out = r;
    return AFFECT_OK;
}
