/*
 * test_rank.c — the relative-attribute ranker (affect/rank.h): optimality (the gradient of the
 * objective vanishes at the solution, in both the direct and the reduced d > n paths), recovery
 * of a known w from pairs it ordered, similar pairs honoured, few Newton iterations, pairs from
 * levels (groups, fractions, determinism), k-means clusters, the BLOB (round trip, corruption),
 * errors, and out-of-memory handling.
 */
#include <stdio.h>
#include <string.h>

#include "testutil.h"

#include "affect/rank.h"
#include "util/rng.h"

static void random_x(double *X, uint32_t n, uint32_t d, uint64_t seed)
{
    affect_rng r;
    affect_rng_seed(&r, seed);
    for (size_t k = 0; k < (size_t)n * d; k++)
        X[k] = affect_rng_normal(&r);
}

/* Levels by a hidden w: level = quantile bin (0 .. L−1) of w_trueᵀx. */
static void levels_from(const double *X, uint32_t n, uint32_t d, const double *wt, int L,
                        int32_t *level)
{
    for (uint32_t i = 0; i < n; i++) {
        double s = 0;
        for (uint32_t k = 0; k < d; k++)
            s += wt[k] * X[(size_t)i * d + k];
        int lv = (int)floor((s + 3.0) / 6.0 * L);
        level[i] = lv < 0 ? 0 : lv >= L ? L - 1 : lv;
    }
}

static double grad_norm(const double *X, uint32_t d, const affect_rank_pair *p, size_t np, double C,
                        const double *w)
{
    double *g = malloc(sizeof(double) * d);
    affect_rank_objective(X, d, p, np, C, w, g);
    double s = 0;
    for (uint32_t k = 0; k < d; k++)
        s += g[k] * g[k];
    free(g);
    return sqrt(s);
}

static void check_kkt(uint32_t n, uint32_t d, double C, uint64_t seed)
{
    double *X = malloc(sizeof(double) * n * d), *wt = malloc(sizeof(double) * d);
    double *w = malloc(sizeof(double) * d);
    int32_t *level = malloc(sizeof(int32_t) * n);
    random_x(X, n, d, seed);
    random_x(wt, 1, d, seed + 99);
    levels_from(X, n, d, wt, 3, level);
    affect_rank_pair *pairs;
    size_t np;
    affect_error err;
    assert_int_equal(affect_rank_pairs(level, NULL, n, true, 1.0, 1, &pairs, &np, &err), AFFECT_OK);
    assert_true(np > 0);
    affect_rank_options opt;
    affect_rank_options_default(&opt);
    opt.C = C;
    affect_rank_stats st;
    assert_int_equal(affect_rank_fit(X, n, d, pairs, np, &opt, w, &st, &err), AFFECT_OK);
    assert_true(st.converged);
    assert_true(st.iterations <= 15);
    double gn = grad_norm(X, d, pairs, np, C, w);
    double f0 = affect_rank_objective(X, d, pairs, np, C, w, NULL);
    if (!(gn < 1e-6 * (1 + f0)))
        fail_msg("n %u d %u C %g: gradient norm %g at f = %g", n, d, C, gn, f0);
    tu_assert_near(st.objective, f0, 1e-8 * (1 + f0));
    /* no random perturbation lowers f (convexity + zero gradient, checked independently) */
    affect_rng r;
    affect_rng_seed(&r, seed + 7);
    double *w2 = malloc(sizeof(double) * d);
    for (int t = 0; t < 20; t++) {
        for (uint32_t k = 0; k < d; k++)
            w2[k] = w[k] + 1e-3 * affect_rng_normal(&r);
        assert_true(affect_rank_objective(X, d, pairs, np, C, w2, NULL) >= f0 - 1e-12);
    }
    affect_free(pairs);
    free(X);
    free(wt);
    free(w);
    free(w2);
    free(level);
}

static void test_kkt(void **state)
{
    (void)state;
    check_kkt(60, 5, 1.0, 1);
    check_kkt(80, 12, 0.1, 2);
    check_kkt(40, 3, 10.0, 3);
    check_kkt(20, 200, 1.0, 4); /* d > n: the reduced path */
    check_kkt(30, 31, 0.01, 5);
}

static void test_recovers_w(void **state)
{
    (void)state;
    const uint32_t n = 300, d = 6;
    double X[300 * 6], wt[6] = {1, -2, 0.5, 0, 3, -1}, w[6];
    random_x(X, n, d, 11);
    /* ordered pairs (i above j) whenever wtᵀ(x_i − x_j) > 0.5, no similar pairs */
    affect_rank_pair *pairs = malloc(sizeof *pairs * n * n);
    size_t np = 0;
    for (uint32_t i = 0; i < n; i++)
        for (uint32_t j = 0; j < n; j++) {
            double m = 0;
            for (uint32_t k = 0; k < d; k++)
                m += wt[k] * (X[i * d + k] - X[j * d + k]);
            if (m > 0.5 && (i * 7 + j) % 5 == 0)
                pairs[np++] = (affect_rank_pair){i, j, 0};
        }
    affect_rank_options opt;
    affect_rank_options_default(&opt);
    opt.C = 10;
    affect_rank_stats st;
    affect_error err;
    assert_int_equal(affect_rank_fit(X, n, d, pairs, np, &opt, w, &st, &err), AFFECT_OK);
    double dot = 0, nw = 0, nt = 0;
    for (uint32_t k = 0; k < d; k++) {
        dot += w[k] * wt[k];
        nw += w[k] * w[k];
        nt += wt[k] * wt[k];
    }
    double cosine = dot / sqrt(nw * nt);
    if (!(cosine > 0.99))
        fail_msg("cosine between learned and true w: %g", cosine);
    assert_true(st.correct == st.ordered);
    if (!(st.converged && st.iterations <= 20 && st.halvings == 0))
        fail_msg("%u Newton iterations, %u halvings", st.iterations, st.halvings);
    free(pairs);
}

static void test_similar_pairs(void **state)
{
    (void)state;
    /* two samples marked similar that differ along axis 0; ordered pairs along axis 1 only:
     * the similar pair pulls w_0 to 0 as C grows */
    const uint32_t n = 4, d = 2;
    double X[] = {0, 0, 0, 1, 1, 0.2, 1, 1.2};
    affect_rank_pair pairs[] = {{1, 0, 0}, {3, 2, 0}, {0, 2, 1}, {1, 3, 1}};
    double w[2];
    affect_rank_options opt;
    affect_rank_options_default(&opt);
    opt.C = 100;
    affect_error err;
    affect_rank_stats st;
    assert_int_equal(affect_rank_fit(X, n, d, pairs, 4, &opt, w, &st, &err), AFFECT_OK);
    /* similar: |w_0 + 0.2 w_1| small; ordered: w_1 ≥ 1 nearly */
    assert_true(fabs(w[0] + 0.2 * w[1]) < 0.02);
    assert_true(w[1] > 0.95);
    assert_int_equal(st.similar, 2);
    assert_int_equal(st.ordered, 2);
    /* without the similar pairs, w_0 is free to be 0 anyway; make it matter: an ordered pair
     * along axis 0 too, contradicted by the similar pair */
    affect_rank_pair p2[] = {{1, 0, 0}, {2, 0, 0}, {0, 2, 1}};
    assert_int_equal(affect_rank_fit(X, n, d, p2, 3, &opt, w, &st, &err), AFFECT_OK);
    double sim = fabs(w[0] * (0 - 1) + w[1] * (0 - 0.2));
    double with_sim = sim;
    assert_int_equal(affect_rank_fit(X, n, d, p2, 2, &opt, w, &st, &err), AFFECT_OK);
    double without = fabs(w[0] * (0 - 1) + w[1] * (0 - 0.2));
    assert_true(with_sim < 0.6 * without);
}

static void test_pairs(void **state)
{
    (void)state;
    int32_t level[] = {0, 1, 2, 0, -1, 2, 1};
    uint32_t group[] = {0, 0, 0, 1, 1, 1, 1};
    affect_rank_pair *p;
    size_t np;
    affect_error err;
    assert_int_equal(affect_rank_pairs(level, NULL, 7, true, 1.0, 0, &p, &np, &err), AFFECT_OK);
    /* 6 samples in: 15 pairs; same level: (0,3) (1,6) (2,5) similar */
    assert_int_equal(np, 15);
    size_t sim = 0;
    for (size_t k = 0; k < np; k++) {
        if (p[k].similar)
            sim++;
        else
            assert_true(level[p[k].i] > level[p[k].j]);
    }
    assert_int_equal(sim, 3);
    affect_free(p);
    assert_int_equal(affect_rank_pairs(level, group, 7, false, 1.0, 0, &p, &np, &err), AFFECT_OK);
    /* group 0: (0,1) (0,2) (1,2); group 1: 3,5,6 → (3,5) (3,6) (5,6) */
    assert_int_equal(np, 6);
    affect_free(p);
    /* fractions are seeded and deterministic */
    int32_t lv[40];
    for (int i = 0; i < 40; i++)
        lv[i] = i % 3;
    affect_rank_pair *a, *b;
    size_t na, nb;
    assert_int_equal(affect_rank_pairs(lv, NULL, 40, true, 0.3, 5, &a, &na, &err), AFFECT_OK);
    assert_int_equal(affect_rank_pairs(lv, NULL, 40, true, 0.3, 5, &b, &nb, &err), AFFECT_OK);
    assert_int_equal(na, nb);
    for (size_t k = 0; k < na; k++)
        assert_true(a[k].i == b[k].i && a[k].j == b[k].j && a[k].similar == b[k].similar);
    /* 780 pairs: 520 ordered, 260 similar → 156 + 78 */
    assert_int_equal(na, 234);
    affect_free(b);
    assert_int_equal(affect_rank_pairs(lv, NULL, 40, true, 0.3, 6, &b, &nb, &err), AFFECT_OK);
    assert_int_equal(nb, 234);
    size_t differ = 0;
    for (size_t k = 0; k < na; k++)
        differ += a[k].i != b[k].i || a[k].j != b[k].j;
    assert_true(differ > 0);
    affect_free(a);
    affect_free(b);
    assert_int_equal(affect_rank_pairs(lv, NULL, 40, true, 0, 5, &a, &na, &err),
                     AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "fraction must be in (0, 1] (got 0)");
}

static void test_clusters(void **state)
{
    (void)state;
    /* two well-separated blobs, each with its own direction of strength */
    const uint32_t n = 120, d = 3;
    double X[120 * 3];
    int32_t level[120];
    affect_rng r;
    affect_rng_seed(&r, 3);
    for (uint32_t i = 0; i < n; i++) {
        bool second = i >= n / 2;
        double a = affect_rng_normal(&r), b = affect_rng_normal(&r);
        X[i * d + 0] = (second ? 50 : -50) + a;
        X[i * d + 1] = b;
        X[i * d + 2] = affect_rng_normal(&r);
        double s = second ? -b : b; /* the strength axis flips between clusters */
        level[i] = s > 0.5 ? 2 : s > -0.5 ? 1 : 0;
    }
    affect_rank_pair *p;
    size_t np;
    affect_error err;
    assert_int_equal(affect_rank_pairs(level, NULL, n, false, 1.0, 0, &p, &np, &err), AFFECT_OK);
    affect_rank_options opt;
    affect_rank_options_default(&opt);
    opt.clusters = 2;
    opt.seed = 9;
    affect_ranker *rk, *rk2;
    assert_int_equal(affect_ranker_train(X, n, d, p, np, &opt, &rk, &err), AFFECT_OK);
    assert_int_equal(rk->clusters, 2);
    assert_true(affect_ranker_cluster(rk, X) != affect_ranker_cluster(rk, X + (n - 1) * d));
    /* within each cluster the ranking is nearly perfect; one global ranker cannot be */
    assert_true((double)rk->stats.correct / (double)rk->stats.ordered > 0.97);
    opt.clusters = 1;
    assert_int_equal(affect_ranker_train(X, n, d, p, np, &opt, &rk2, &err), AFFECT_OK);
    assert_true((double)rk2->stats.correct / (double)rk2->stats.ordered < 0.75);
    /* same seed, same bytes */
    opt.clusters = 2;
    affect_ranker *rk3;
    assert_int_equal(affect_ranker_train(X, n, d, p, np, &opt, &rk3, &err), AFFECT_OK);
    unsigned char *b1, *b3;
    size_t s1, s3;
    assert_int_equal(affect_ranker_encode(rk, &b1, &s1, &err), AFFECT_OK);
    assert_int_equal(affect_ranker_encode(rk3, &b3, &s3, &err), AFFECT_OK);
    assert_int_equal(s1, s3);
    assert_memory_equal(b1, b3, s1);
    /* round trip */
    affect_ranker *back;
    assert_int_equal(affect_ranker_decode(b1, s1, &back, &err), AFFECT_OK);
    for (uint32_t i = 0; i < n; i++)
        assert_true(affect_ranker_score(back, X + i * d) == affect_ranker_score(rk, X + i * d));
    affect_ranker_free(back);
    /* corruption: every truncation and a flipped byte are refused */
    for (size_t cut = 0; cut < s1; cut += 7)
        assert_int_equal(affect_ranker_decode(b1, cut, &back, &err) == AFFECT_OK, 0);
    b1[40] ^= 1;
    assert_int_equal(affect_ranker_decode(b1, s1, &back, &err), AFFECT_ERR_FORMAT);
    assert_string_equal(err.msg, "ranker checksum mismatch: the BLOB is corrupt");
    affect_free(b1);
    affect_free(b3);
    affect_ranker_free(rk);
    affect_ranker_free(rk2);
    affect_ranker_free(rk3);
    affect_free(p);
}

static void test_errors(void **state)
{
    (void)state;
    double X[] = {0, 1, 2, 3}, w[2];
    affect_rank_pair bad[] = {{0, 5, 0}};
    affect_rank_pair self[] = {{1, 1, 0}};
    affect_error err;
    affect_rank_options opt;
    affect_rank_options_default(&opt);
    assert_int_equal(affect_rank_fit(X, 2, 2, bad, 1, &opt, w, NULL, &err), AFFECT_ERR_RANGE);
    assert_string_equal(err.msg, "pair 0 refers to sample 5 of 2");
    assert_int_equal(affect_rank_fit(X, 2, 2, self, 1, &opt, w, NULL, &err), AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "pair 0 pairs sample 1 with itself");
    assert_int_equal(affect_rank_fit(X, 2, 2, bad, 0, &opt, w, NULL, &err), AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "no pairs");
    opt.C = -1;
    assert_int_equal(affect_rank_fit(X, 2, 2, bad, 1, &opt, w, NULL, &err), AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "C must be finite and > 0 (got C = -1, max_iter = 50)");
    affect_rank_options_default(&opt);
    X[3] = NAN;
    affect_rank_pair ok[] = {{1, 0, 0}};
    assert_int_equal(affect_rank_fit(X, 2, 2, ok, 1, &opt, w, NULL, &err), AFFECT_ERR_FORMAT);
    assert_string_equal(err.msg, "non-finite value in sample 1");
    opt.clusters = 3;
    affect_ranker *rk;
    X[3] = 1;
    assert_int_equal(affect_ranker_train(X, 2, 2, ok, 1, &opt, &rk, &err), AFFECT_ERR_RANGE);
    assert_string_equal(err.msg, "clusters (3) exceeds the number of samples (2)");
}

typedef struct oom_ctx {
    double X[40 * 30];
    affect_rank_pair *pairs;
    size_t np;
    uint32_t clusters, d;
    affect_ranker *out;
} oom_ctx;

static affect_status oom_train(void *ctx, affect_error *err)
{
    oom_ctx *c = ctx;
    affect_rank_options opt;
    affect_rank_options_default(&opt);
    opt.clusters = c->clusters;
    return affect_ranker_train(c->X, 40, c->d, c->pairs, c->np, &opt, &c->out, err);
}

static void oom_finish(void *ctx, affect_status st)
{
    oom_ctx *c = ctx;
    (void)st;
    affect_ranker_free(c->out);
    c->out = NULL;
}

static void test_out_of_memory(void **state)
{
    (void)state;
    oom_ctx c;
    memset(&c, 0, sizeof c);
    random_x(c.X, 40, 30, 17);
    int32_t level[40];
    for (int i = 0; i < 40; i++)
        level[i] = i % 2;
    affect_error err;
    assert_int_equal(affect_rank_pairs(level, NULL, 40, true, 0.5, 1, &c.pairs, &c.np, &err),
                     AFFECT_OK);
    c.d = 30;
    c.clusters = 1;
    assert_true(tu_oom_sweep(oom_train, &c, oom_finish, NULL) >= 2);
    c.clusters = 3;
    assert_true(tu_oom_sweep(oom_train, &c, oom_finish, NULL) >= 5);
    c.d = 3; /* the direct path */
    c.clusters = 1;
    assert_true(tu_oom_sweep(oom_train, &c, oom_finish, NULL) >= 2);
    affect_free(c.pairs);
}

static void test_fixture_v1(void **state)
{
    (void)state;
    size_t n;
    char *data = tu_read_file(AFFECT_FIXTURES_DIR "/ranker-v1.bin", &n);
    assert_non_null(data);
    affect_ranker *r;
    affect_error err;
    assert_int_equal(affect_ranker_decode((const unsigned char *)data, n, &r, &err), AFFECT_OK);
    assert_int_equal(r->dim, 27);
    assert_int_equal(r->clusters, 2);
    assert_true(r->stats.converged);
    assert_true(r->stats.correct <= r->stats.ordered && r->stats.ordered > 0);
    unsigned char *enc;
    size_t ne;
    assert_int_equal(affect_ranker_encode(r, &enc, &ne, &err), AFFECT_OK);
    assert_int_equal(ne, n);
    assert_memory_equal(enc, data, n);
    /* a centroid belongs to its own cluster */
    assert_int_equal(affect_ranker_cluster(r, r->centroids + r->dim), 1);
    affect_free(enc);
    affect_ranker_free(r);
    free(data);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_kkt),           cmocka_unit_test(test_recovers_w),
        cmocka_unit_test(test_similar_pairs), cmocka_unit_test(test_pairs),
        cmocka_unit_test(test_clusters),      cmocka_unit_test(test_errors),
        cmocka_unit_test(test_out_of_memory), cmocka_unit_test(test_fixture_v1),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
