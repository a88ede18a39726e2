/*
 * affect/bspline.h — B-spline bases on [0, 1] with equally spaced knots, their derivatives, the
 * exact Gram and roughness-penalty matrices, and penalized least-squares fits of sampled curves
 * (thesis chapter 3, SCIENCE.md §4).
 *
 * Usage:
 *     const double *x = ...;  uint32_t T = ...;        // T samples of 1 column, at equal spacing
 *     affect_error err;
 *     affect_bspline b = {4, 10};                      // cubic (k = 4), G = 10 functions
 *     double r[10 * 4], c[10], work[2 * 10 * 4 + 10], f[100];
 *     if (affect_bspline_check(&b)) { puts(affect_bspline_check(&b)); return; }
 *     affect_bspline_gram(&b, 2, r);                   // the roughness penalty, band form
 *     if (affect_bspline_fit(&b, r, NULL, x, T, 1, 1e-4, c, work, &err) != AFFECT_OK)
 *         puts(err.msg);
 *     else
 *         affect_bspline_values(&b, c, 1, NULL, 100, f);   // the fit at 100 equally spaced times
 *
 * The basis. G functions B_0 .. B_{G−1} of order k (degree k − 1; k = 4 is the cubic spline)
 * on the clamped knot sequence with L = G − k + 1 equal intervals over [0, 1]: k knots at 0,
 * the interior breakpoints 1/L, 2/L, …, (L − 1)/L, k knots at 1. They are non-negative, add up
 * to 1 everywhere on [0, 1] (partition of unity), and at most k of them are nonzero at any t:
 * those with indices first .. first + k − 1 where first = min(⌊t L⌋, L − 1) (the last interval
 * is closed at 1). Derivatives up to order k − 1 come from the usual recursion
 * B′_{i,r} = (r − 1) [B_{i,r−1} / (t_{i+r−1} − t_i) − B_{i+1,r−1} / (t_{i+r} − t_{i+1})].
 *
 * Matrices (G × G, symmetric, banded: entry (i, j) is 0 when |i − j| ≥ k):
 *   Gram     M_ij = ∫₀¹ B_i(t) B_j(t) dt
 *   penalty  R_ij = ∫₀¹ B_i″(t) B_j″(t) dt   (so cᵀ R c = ∫ f″² for f = Σ c_i B_i)
 * both by k-point Gauss–Legendre quadrature on each knot interval, exact (up to rounding) since
 * the integrands are polynomials of degree ≤ 2k − 2 there. Stored in band form: band[i·k + d]
 * = entry (i, i + d) for d = 0 .. k − 1 (entries past the last column are 0).
 *
 * Penalized least squares. A curve sampled at T times t_0 .. t_{T−1} (each in [0, 1]) with m
 * values per time (the rows of x, T × m row-major) is fitted, each of its m columns separately,
 * by the coefficients c (G × m) minimizing
 *     (1/T) Σ_t (x_t − Σ_i c_i B_i(t_t))² + λ ∫₀¹ f″(t)² dt
 * i.e. (A + λ R) c = (1/T) Φᵀ x with A = Φᵀ Φ / T, Φ the T × G basis values. The 1/T makes λ
 * mean the same for short and long motions. The banded system is solved by a band Cholesky
 * factorization written here (no LAPACK band layouts; deterministic, plain sums in index
 * order). It needs A + λ R positive definite: with λ > 0, T ≥ 2 distinct times are enough
 * (R's null space is the straight lines); with λ = 0 the times must determine every
 * coefficient (T ≥ G in practice).
 *
 * Generalized cross-validation (Craven & Wahba): for a set of sampled curves, GCV(λ) =
 * Σ_curves Σ_columns T · SSE / (T − df(λ))², df(λ) = tr((A + λR)⁻¹ A) the effective degrees of
 * freedom of the curve's smoother, SSE its residual sum of squares; ∞ when df ≥ T.
 */
#ifndef AFFECT_BSPLINE_H
#define AFFECT_BSPLINE_H

#include "affect/base.h"

#ifdef __cplusplus
extern "C" {
#endif

#define AFFECT_BSPLINE_MAX_ORDER 10u
#define AFFECT_BSPLINE_MAX_BASIS 4096u

typedef struct affect_bspline {
    uint32_t order; /* k, 2 .. AFFECT_BSPLINE_MAX_ORDER (penalty needs k ≥ 3) */
    uint32_t n;     /* G, k .. AFFECT_BSPLINE_MAX_BASIS */
} affect_bspline;

/* NULL when the basis is usable, else a message: "order must be from 2 to 10",
 * "the basis size must be from the order to 4096". */
const char *affect_bspline_check(const affect_bspline *b);

/* The knot t_j, j = 0 .. G + k − 1 (clamped, see above). */
double affect_bspline_knot(const affect_bspline *b, uint32_t j);

/* The index of the first nonzero function at t (t clamped to [0, 1]); the k values of the
 * deriv-th derivative (0 .. k − 1) of B_first .. B_{first+k−1} at t into v. */
uint32_t affect_bspline_eval(const affect_bspline *b, double t, uint32_t deriv, double *v);

/* Band-form Gram (deriv 0) or the ∫ of products of deriv-th derivatives (2: the roughness
 * penalty R), G × k doubles into band (see above). deriv < k. */
void affect_bspline_gram(const affect_bspline *b, uint32_t deriv, double *band);

/* y (G × m) = S x for the symmetric banded S (band form) and x (G × m). */
void affect_band_mul(const double *band, uint32_t g, uint32_t k, const double *x, uint32_t m,
                     double *y);

/* In-place band Cholesky S = Uᵀ U (U upper, band form). False when S is not positive
 * definite (a pivot ≤ AFFECT_BAND_PIVOT_TOL × the largest diagonal entry, or not finite). */
#define AFFECT_BAND_PIVOT_TOL 1e-13
bool affect_band_cholesky(double *band, uint32_t g, uint32_t k);
/* Solves Uᵀ U x = rhs in place for the m columns of x (G × m), U from affect_band_cholesky. */
void affect_band_solve(const double *u, uint32_t g, uint32_t k, double *x, uint32_t m);

/* The samples' normal equations for a fit: a (band form, G × k) = Φᵀ Φ / T and rhs (G × m) =
 * Φᵀ x / T for x (T × m) at times t (T values in [0, 1]; NULL: t_j = j / (T − 1), 0 for T = 1). */
void affect_bspline_normal(const affect_bspline *b, const double *t, const double *x, uint32_t T,
                           uint32_t m, double *a, double *rhs);

/* Fits x (T × m at times t, or the equally spaced times when t is NULL) with penalty lambda
 * (≥ 0, finite) into c (G × m), given r the band-form penalty (affect_bspline_gram deriv 2).
 * work: 2 G k + G doubles. Errors (AFFECT_ERR_INVALID): "need at least 1 sample",
 * "the fit is singular: 3 samples cannot determine 20 coefficients with lambda = 0 (give a
 * positive lambda or a smaller basis)", "sample 4, column 2: non-finite value". */
affect_status affect_bspline_fit(const affect_bspline *b, const double *r, const double *t,
                                 const double *x, uint32_t T, uint32_t m, double lambda, double *c,
                                 double *work, affect_error *err);

/* f (T × m) = Φ c: the fitted curve at T times (t, or equally spaced when NULL). */
void affect_bspline_values(const affect_bspline *b, const double *c, uint32_t m, const double *t,
                           uint32_t T, double *f);

/* One curve's contribution to GCV(λ) (see above) with its smoother's degrees of freedom in
 * *df (may be NULL): T Σ_columns SSE / (T − df)², +∞ when df ≥ T − AFFECT_GCV_DF_MARGIN or
 * A + λR is not positive definite. work: affect_bspline_gcv_work doubles (3 G k + G m).
 * No allocation; O(T k² + G k (k + m)): the trace needs only the band of (A + λR)⁻¹, which the
 * recursion of Hutchinson and de Hoog gives from the Cholesky factor. */
#define AFFECT_GCV_DF_MARGIN 1e-9
size_t affect_bspline_gcv_work(const affect_bspline *b, uint32_t T, uint32_t m);
double affect_bspline_gcv(const affect_bspline *b, const double *r, const double *t,
                          const double *x, uint32_t T, uint32_t m, double lambda, double *df,
                          double *work);

/* Gauss–Legendre nodes (in [−1, 1], ascending) and weights of n points (1 .. 16) by Newton's
 * method on the Legendre polynomial, to full double precision. */
void affect_gauss_legendre(uint32_t n, double *nodes, double *weights);

#ifdef __cplusplus
}
#endif
#endif
