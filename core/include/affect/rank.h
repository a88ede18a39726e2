/*
 * affect/rank.h — relative attributes (Parikh & Grauman; SCIENCE.md §6, the emotion-strength
 * paper's eq. 6): a linear ranking function r(x) = wᵀx learned from ordered and similar pairs
 * of vectors, on any vectors (motion features, facial landmarks, embeddings).
 *
 * Usage:
 *     const double *X = ...;  uint32_t n = ..., d = ...;   // n samples × d, row-major
 *     const int32_t *level = ...;                      // per sample: 0 sad < 1 normal < 2 happy
 *     affect_error err;
 *     affect_rank_pair *pairs = NULL;  size_t n_pairs = 0;
 *     affect_rank_options opt;
 *     affect_rank_options_default(&opt);
 *     affect_ranker *r = NULL;
 *     if (affect_rank_pairs(level, NULL, n, true, 1.0, 42, &pairs, &n_pairs, &err) != AFFECT_OK
 *         || affect_ranker_train(X, n, d, pairs, n_pairs, &opt, &r, &err) != AFFECT_OK)
 *         puts(err.msg);
 *     else
 *         printf("r(x_0) = %g\n", affect_ranker_score(r, X));
 *     affect_ranker_free(r);  affect_free(pairs);
 *
 *     min_w ½‖w‖² + C (Σ_O ξ_ij² + Σ_S γ_ij²)
 *     s.t. wᵀ(x_i − x_j) ≥ 1 − ξ_ij on ordered pairs O (x_i ranks above x_j),
 *          |wᵀ(x_i − x_j)| ≤ γ_ij on similar pairs S.
 *
 * Eliminating the slacks gives the unconstrained, strictly convex, piecewise-quadratic
 *     f(w) = ½‖w‖² + C Σ_O max(0, 1 − wᵀz)² + C Σ_S (wᵀz)²,   z = x_i − x_j,
 * minimized in the primal by Newton's method (Chapelle, "Training a support vector machine in
 * the primal", 2007): with the active set A (the ordered pairs with wᵀz < 1, and every similar
 * pair) as the rows of a matrix and b their targets (1 ordered, 0 similar), the Newton point is
 * the solution of (I + 2C AᵀA) w = 2C Aᵀ b. It is taken when it lowers f, else the step is
 * halved (never needed in our tests, kept for the guarantee); the loop ends when the active
 * set no longer changes (w is then the exact minimizer: the gradient vanishes on that set).
 * Usually 3–8 iterations.
 *
 * Computing AᵀA = Xᵀ L X with L = Σ_A (e_i − e_j)(e_i − e_j)ᵀ (n × n, built in O(|A|)) costs
 * O(n² d + n d²) whatever the number of pairs. When d > n the problem is first written in the
 * row space of X (the minimizer lies there: w = 2C Aᵀ(b − Aw)): X = U S Vᵀ by the eigenvectors
 * of XXᵀ, coordinates U S (n × r), then w = V u; so the cost is O(n² d + n³), not O(d³).
 *
 * Pairs: affect_rank_pairs builds them from per-sample levels (an order of labels): every two
 * samples of different levels make an ordered pair (the higher level first), every two of the
 * same level a similar pair; optionally only samples of one group (content) are paired, and a
 * seeded fraction of each kind is kept (the paper's 10–90 % of training pairs).
 *
 * Clusters (the paper's facial-landmark variant, §5): k-means (k-means++ seeding from the seed,
 * then Lloyd iterations; deterministic) groups the samples, one ranker is trained per cluster on
 * the pairs inside it, and a vector is scored by the ranker of its nearest centroid.
 *
 * Errors: "C must be finite and > 0 (got -1)", "pair 3 refers to sample 12 of 10", "no pairs",
 * "clusters (5) exceeds the number of samples (3)", non-finite input values.
 */
#ifndef AFFECT_RANK_H
#define AFFECT_RANK_H

#include "affect/base.h"
#include "affect/monitor.h"

#ifdef __cplusplus
extern "C" {
#endif

#define AFFECT_RANK_MAX_ITER 100 /* Newton iterations (default 50) */
#define AFFECT_RANK_MAX_CLUSTERS 256u
#define AFFECT_RANK_MAX_DIM 1048576u /* 2^20 */
#define AFFECT_RANK_RANK_TOL 1e-10   /* singular values below this × the largest are dropped */

typedef struct affect_rank_pair {
    uint32_t i, j; /* ordered: x_i ranks above x_j; similar: unordered */
    uint8_t similar;
} affect_rank_pair;

typedef struct affect_rank_options {
    double C;                /* > 0 (default 1) */
    uint32_t max_iter;       /* Newton iterations (default 50, ≤ AFFECT_RANK_MAX_ITER) */
    uint32_t clusters;       /* 0 or 1: one ranker; k > 1: k-means pose clusters */
    uint64_t seed;           /* k-means++ seeding */
    affect_monitor *monitor; /* may be NULL */
} affect_rank_options;

void affect_rank_options_default(affect_rank_options *opt);
/* NULL, or a message for a bad option. */
const char *affect_rank_check(const affect_rank_options *opt);

/* What training measured (per ranker; summed or worst over clusters in a model). */
typedef struct affect_rank_stats {
    uint32_t iterations;       /* Newton iterations (the largest over clusters) */
    uint32_t halvings;         /* step halvings taken */
    uint64_t ordered, similar; /* pairs used */
    uint64_t correct;          /* ordered pairs with wᵀ(x_i − x_j) > 0 after training */
    double objective;          /* f(w) (summed over clusters) */
    bool converged;            /* the active set stabilized within max_iter */
} affect_rank_stats;

/* One ranker: w (d doubles) minimizing f over the n × d row-major samples X and the pairs. */
affect_status affect_rank_fit(const double *X, uint32_t n, uint32_t d,
                              const affect_rank_pair *pairs, size_t n_pairs,
                              const affect_rank_options *opt, double *w, affect_rank_stats *stats,
                              affect_error *err);

/* f(w) and its gradient (grad: d doubles, may be NULL) — for tests and diagnostics. */
double affect_rank_objective(const double *X, uint32_t d, const affect_rank_pair *pairs,
                             size_t n_pairs, double C, const double *w, double *grad);

/* Pairs from levels: level[i] < 0 leaves sample i out; group (NULL: no restriction) pairs only
 * samples of the same group; fraction in (0, 1] keeps round(fraction × count) of the ordered
 * and of the similar pairs, drawn by seed (at least one of each kind that exists); similar
 * false leaves similar pairs out. *pairs (affect_free) in increasing (i, j) order. */
affect_status affect_rank_pairs(const int32_t *level, const uint32_t *group, uint32_t n,
                                bool similar, double fraction, uint64_t seed,
                                affect_rank_pair **pairs, size_t *n_pairs, affect_error *err);

/* A ranker model: one w, or k centroids and k w's. */
typedef struct affect_ranker {
    uint32_t dim, clusters; /* clusters ≥ 1 */
    double *centroids;      /* clusters × dim (all zero for one ranker) */
    double *w;              /* clusters × dim */
    affect_rank_stats stats;
} affect_ranker;

/* Trains a ranker (with opt->clusters > 1, k-means first; pairs across clusters are dropped). */
affect_status affect_ranker_train(const double *X, uint32_t n, uint32_t d,
                                  const affect_rank_pair *pairs, size_t n_pairs,
                                  const affect_rank_options *opt, affect_ranker **out,
                                  affect_error *err);
/* The cluster of x (nearest centroid; 0 for one ranker). */
uint32_t affect_ranker_cluster(const affect_ranker *r, const double *x);
/* r(x) = w_c ᵀ x for x's cluster c. */
double affect_ranker_score(const affect_ranker *r, const double *x);
void affect_ranker_free(affect_ranker *r);

/* k-means: centroids (k × d) and assign (n) for the samples, k-means++ from seed, Lloyd until
 * no assignment changes (at most 100 iterations). */
affect_status affect_kmeans(const double *X, uint32_t n, uint32_t d, uint32_t k, uint64_t seed,
                            double *centroids, uint32_t *assign, affect_monitor *mon,
                            affect_error *err);

/* ---- the ranker BLOB (docs/FORMATS.md: magic AFRK) ---- */
#define AFFECT_RANKER_MAGIC "AFRK"
#define AFFECT_RANKER_VERSION 1u
affect_status affect_ranker_encode(const affect_ranker *r, unsigned char **out, size_t *size,
                                   affect_error *err);
affect_status affect_ranker_decode(const unsigned char *data, size_t size, affect_ranker **out,
                                   affect_error *err);

#ifdef __cplusplus
}
#endif
#endif
