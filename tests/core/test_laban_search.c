/*
 * test_laban_search.c — the laban index's search arithmetic (core/laban/laban_search.c): the
 * masked distance (components missing in either vector skipped, a chosen subset, none in common
 * → no distance), the k nearest in ascending distance with ties by id whatever the storage
 * order, k larger than the rows, the relative radius ball and its boundary (a distance exactly
 * at radius · farthest is in), the nearest alone when the ball is empty, the empty index, the
 * query's own row and the label filter left out, NaN queries and a NaN radius; then random sets
 * with many ties compared with a brute-force reference (every distance, sorted, cut).
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"
#include "affect/laban.h"

#define N AFFECT_LABAN_N

static const int ALL[N] = {0,  1,  2,  3,  4,  5,  6,  7,  8,  9,  10, 11, 12, 13,
                           14, 15, 16, 17, 18, 19, 20, 21, 22, 23, 24, 25, 26};

/* Every component NaN. */
static void missing(double *v)
{
    for (int j = 0; j < N; j++)
        v[j] = NAN;
}

static void test_distance(void **state)
{
    (void)state;
    double q[N], x[N];
    missing(q);
    missing(x);
    /* nothing in common: no distance */
    assert_true(isnan(affect_laban_distance(q, x, ALL, N)));
    q[0] = 1, x[0] = 4;   /* 3 */
    q[1] = 2;             /* missing in x: skipped */
    x[2] = 7;             /* missing in q: skipped */
    q[3] = -1, x[3] = 3;  /* 4 */
    q[26] = 5, x[26] = 5; /* 0, but counts as in common */
    assert_true(affect_laban_distance(q, x, ALL, N) == 5);
    assert_true(affect_laban_distance(x, q, ALL, N) == 5); /* symmetric */
    /* a subset: only component 3 */
    int c3[1] = {3};
    assert_true(affect_laban_distance(q, x, c3, 1) == 4);
    /* a subset with nothing in common */
    int c12[2] = {1, 2};
    assert_true(isnan(affect_laban_distance(q, x, c12, 2)));
    /* present only in component 26, equal: distance 0, not "none" */
    int c26[1] = {26};
    assert_true(affect_laban_distance(q, x, c26, 1) == 0);
    /* ±inf against a finite value is an infinite distance; inf − inf is NaN, skipped */
    q[4] = INFINITY, x[4] = 0;
    assert_true(isinf(affect_laban_distance(q, x, ALL, N)));
    x[4] = INFINITY;
    assert_true(affect_laban_distance(q, x, ALL, N) == 5);
}

/* A set of n rows whose component 0 is d[i] (the query is 0 there) and the rest missing. */
typedef struct set {
    size_t n;
    double z[16 * N];
    int64_t ids[16];
    int32_t label[16];
} set;

static void make_set(set *s, const double *d, const int64_t *ids, size_t n)
{
    s->n = n;
    for (size_t i = 0; i < n; i++) {
        missing(s->z + i * N);
        s->z[i * N] = d[i];
        s->ids[i] = ids[i];
        s->label[i] = (int32_t)(i % 2);
    }
}

/* The query of those sets: 0 in component 0, the rest missing. */
static void query_0(double *q)
{
    missing(q);
    q[0] = 0;
}

static affect_laban_search search_of(const set *s, uint64_t k, double radius)
{
    affect_laban_search q = {.z = s->z,
                             .ids = s->ids,
                             .lo = 0,
                             .hi = s->n,
                             .self = SIZE_MAX,
                             .label = s->label,
                             .label_ok = NULL,
                             .comp = ALL,
                             .n_comp = N,
                             .k = k,
                             .radius = radius};
    return q;
}

static size_t run(const affect_laban_search *s, const double *q, affect_laban_hit *hits)
{
    size_t n = 12345;
    affect_laban_search_run(s, q, hits, &n);
    assert_true(n <= affect_laban_search_capacity(s));
    return n;
}

static void test_knn_ties(void **state)
{
    (void)state;
    /* distances 2, 1, 1, 3, 1, NaN (no component in common) stored with ids out of order */
    const double d[6] = {2, 1, -1, 3, 1, NAN};
    const int64_t ids[6] = {10, 30, 20, 5, 25, 1};
    set s;
    make_set(&s, d, ids, 6);
    double q[N];
    query_0(q);
    affect_laban_hit h[16];
    affect_laban_search se = search_of(&s, 3, 0);
    assert_int_equal(affect_laban_search_capacity(&se), 3);
    /* the three at distance 1, by id: 20, 25, 30 */
    assert_int_equal(run(&se, q, h), 3);
    const int64_t want3[3] = {20, 25, 30};
    for (int i = 0; i < 3; i++) {
        assert_true(h[i].d == 1);
        assert_int_equal(h[i].id, want3[i]);
        assert_int_equal(s.ids[h[i].row], h[i].id);
    }
    /* k = 2 cuts inside the tie: the smaller ids win */
    se.k = 2;
    assert_int_equal(run(&se, q, h), 2);
    assert_int_equal(h[0].id, 20);
    assert_int_equal(h[1].id, 25);
    /* k larger than the rows: every row with a distance, the NaN row never */
    se.k = 100;
    assert_int_equal(affect_laban_search_capacity(&se), 6);
    assert_int_equal(run(&se, q, h), 5);
    const int64_t want5[5] = {20, 25, 30, 10, 5};
    for (int i = 0; i < 5; i++)
        assert_int_equal(h[i].id, want5[i]);
    /* the query's own row left out (row 2, id 20) */
    se.self = 2;
    assert_int_equal(run(&se, q, h), 4);
    assert_int_equal(h[0].id, 25);
    se.self = SIZE_MAX;
    /* label filter: only label 1 (rows 1, 3, 5: ids 30, 5, 1) */
    const unsigned char ok[2] = {0, 1};
    se.label_ok = ok;
    assert_int_equal(run(&se, q, h), 2);
    assert_int_equal(h[0].id, 30);
    assert_int_equal(h[1].id, 5);
    s.label[1] = -1; /* an unlabelled row never passes a label filter */
    assert_int_equal(run(&se, q, h), 1);
    assert_int_equal(h[0].id, 5);
    se.label_ok = NULL;
    assert_int_equal(run(&se, q, h), 5); /* but is searched without one */
    /* a row range: rows [3, 6) */
    se.lo = 3;
    assert_int_equal(affect_laban_search_capacity(&se), 3);
    assert_int_equal(run(&se, q, h), 2);
    assert_int_equal(h[0].id, 25);
    assert_int_equal(h[1].id, 5);
    /* a query with nothing in common with any row */
    se.lo = 0;
    missing(q);
    assert_int_equal(run(&se, q, h), 0);
}

static void test_radius(void **state)
{
    (void)state;
    const double d[4] = {4, 1, 2, -2};
    const int64_t ids[4] = {1, 2, 3, 4};
    set s;
    make_set(&s, d, ids, 4);
    double q[N];
    query_0(q);
    affect_laban_hit h[16];
    affect_laban_search se = search_of(&s, 0, 0.5);
    assert_int_equal(affect_laban_search_capacity(&se), 4);
    /* farthest 4: radius 0.5 → within 2, the boundary included: 1 (id 2), then 2 (ids 3, 4) */
    assert_int_equal(run(&se, q, h), 3);
    assert_int_equal(h[0].id, 2);
    assert_int_equal(h[1].id, 3);
    assert_int_equal(h[2].id, 4);
    /* radius 1: all */
    se.radius = 1;
    assert_int_equal(run(&se, q, h), 4);
    assert_int_equal(h[3].id, 1);
    /* just under the boundary: only the nearest inside */
    se.radius = nextafter(0.5, 0);
    assert_int_equal(run(&se, q, h), 1);
    assert_int_equal(h[0].id, 2);
    /* nothing within the radius: the nearest alone */
    se.radius = 0.1;
    assert_int_equal(run(&se, q, h), 1);
    assert_int_equal(h[0].id, 2);
    assert_true(h[0].d == 1);
    /* a NaN radius keeps the nearest alone */
    se.radius = NAN;
    assert_int_equal(run(&se, q, h), 1);
    assert_int_equal(h[0].id, 2);
    /* the nearest tied: the smaller id */
    s.z[1 * N] = -2; /* row 1 (id 2) now at 2, like ids 3 and 4 */
    se.radius = 0.1;
    assert_int_equal(run(&se, q, h), 1);
    assert_int_equal(h[0].id, 2);
    /* every row at distance 0: the farthest is 0 and every row is within it */
    for (int i = 0; i < 4; i++)
        s.z[i * N] = 0;
    assert_int_equal(run(&se, q, h), 4);
    /* a NaN query: nothing */
    missing(q);
    assert_int_equal(run(&se, q, h), 0);
}

static void test_empty(void **state)
{
    (void)state;
    set s;
    make_set(&s, NULL, NULL, 0);
    double q[N];
    for (int j = 0; j < N; j++)
        q[j] = j;
    affect_laban_hit h[1];
    affect_laban_search se = search_of(&s, 5, 0);
    assert_int_equal(affect_laban_search_capacity(&se), 0);
    assert_int_equal(run(&se, q, h), 0);
    se.k = 0;
    se.radius = 1;
    assert_int_equal(affect_laban_search_capacity(&se), 0);
    assert_int_equal(run(&se, q, h), 0);
}

/* ---- against a brute-force reference ---- */

static uint64_t rng_state;
static uint32_t rnd(uint32_t n)
{
    rng_state = rng_state * 6364136223846793005u + 1442695040888963407u;
    return (uint32_t)((rng_state >> 33) % n);
}

static int ref_cmp(const void *a, const void *b)
{
    const affect_laban_hit *x = a, *y = b;
    if (x->d < y->d)
        return -1;
    if (x->d > y->d)
        return 1;
    return x->id < y->id ? -1 : x->id > y->id;
}

/* Every qualifying row with its distance written out independently, sorted, then cut. */
static size_t reference(const affect_laban_search *s, const double *q, affect_laban_hit *out)
{
    size_t n = 0;
    for (size_t i = s->lo; i < s->hi; i++) {
        if (i == s->self || (s->label_ok && (s->label[i] < 0 || !s->label_ok[s->label[i]])))
            continue;
        double sum = 0;
        bool any = false;
        for (int t = 0; t < s->n_comp; t++) {
            double a = q[s->comp[t]], b = s->z[i * N + s->comp[t]];
            if (isnan(a) || isnan(b))
                continue;
            sum += (a - b) * (a - b);
            any = true;
        }
        if (any)
            out[n++] = (affect_laban_hit){sqrt(sum), s->ids[i], i};
    }
    qsort(out, n, sizeof *out, ref_cmp);
    if (s->k > 0)
        return n < s->k ? n : (size_t)s->k;
    if (n == 0)
        return 0;
    double far = out[n - 1].d;
    size_t kept = 0;
    while (kept < n && out[kept].d <= s->radius * far)
        kept++;
    return kept ? kept : 1;
}

static void test_random(void **state)
{
    (void)state;
    enum { MAXN = 300 };
    double *z = malloc(sizeof(double) * MAXN * N), q[N];
    int64_t ids[MAXN];
    int32_t label[MAXN];
    affect_laban_hit *got = malloc(sizeof *got * MAXN), *want = malloc(sizeof *want * MAXN);
    assert_non_null(z);
    assert_non_null(got);
    assert_non_null(want);
    rng_state = 42;
    for (int round = 0; round < 2000; round++) {
        size_t n = rnd(MAXN + 1);
        /* distinct ids in a random order */
        for (size_t i = 0; i < n; i++)
            ids[i] = (int64_t)i * 3 - 100;
        for (size_t i = n; i > 1; i--) {
            size_t j = rnd((uint32_t)i);
            int64_t t = ids[i - 1];
            ids[i - 1] = ids[j];
            ids[j] = t;
        }
        /* values on a coarse grid (many equal distances), some missing */
        uint32_t miss = rnd(4); /* 0 .. 3 in 8 missing */
        for (size_t i = 0; i < n * N; i++)
            z[i] = rnd(8) < miss ? NAN : (double)rnd(3) - 1;
        for (size_t i = 0; i < n; i++)
            label[i] = (int32_t)rnd(4) - 1;
        for (int j = 0; j < N; j++)
            q[j] = rnd(8) < miss ? NAN : (double)rnd(3) - 1;
        int comp[N], nc = 0;
        uint32_t keep = 1 + rnd(8);
        for (int j = 0; j < N; j++)
            if (rnd(8) < keep)
                comp[nc++] = j;
        if (nc == 0)
            comp[nc++] = (int)rnd(N);
        const unsigned char ok[3] = {1, (unsigned char)rnd(2), 1};
        affect_laban_search s = {.z = z,
                                 .ids = ids,
                                 .lo = n ? rnd((uint32_t)n) / 4 : 0,
                                 .hi = n,
                                 .self = rnd(2) && n ? rnd((uint32_t)n) : SIZE_MAX,
                                 .label = label,
                                 .label_ok = rnd(2) ? ok : NULL,
                                 .comp = comp,
                                 .n_comp = nc,
                                 .k = rnd(3) ? 1 + rnd(40) : 0,
                                 .radius = (1 + rnd(10)) / 10.0};
        if (rnd(4) == 0)
            s.hi = s.lo + rnd((uint32_t)(n - s.lo + 1));
        size_t ng = run(&s, q, got), nw = reference(&s, q, want);
        assert_int_equal(ng, nw);
        for (size_t i = 0; i < nw; i++) {
            assert_true(got[i].d == want[i].d);
            assert_int_equal(got[i].id, want[i].id);
            assert_int_equal(got[i].row, want[i].row);
        }
    }
    free(z);
    free(got);
    free(want);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_distance), cmocka_unit_test(test_knn_ties),
        cmocka_unit_test(test_radius),   cmocka_unit_test(test_empty),
        cmocka_unit_test(test_random),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
