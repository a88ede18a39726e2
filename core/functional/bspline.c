/*
 * bspline.c — B-spline bases on [0, 1] with equally spaced knots (see affect/bspline.h): values
 * and derivatives by the Cox–de Boor recursion, exact Gram and penalty matrices by Gauss–
 * Legendre quadrature per knot interval, a band Cholesky solver, penalized least-squares fits
 * and the generalized cross-validation score.
 *
 * Everything here is plain C in a fixed order of operations (no BLAS): the matrices are banded
 * with half-bandwidth k − 1 ≤ 9, so a fit costs O(T k² + G k m), far below a dense solve.
 */
#include "affect/bspline.h"

#include <math.h>
#include <string.h>

#define NEWTON_MAX_ITER 100

const char *affect_bspline_check(const affect_bspline *b)
{
    if (b->order < 2 || b->order > AFFECT_BSPLINE_MAX_ORDER)
        return "order must be from 2 to 10";
    if (b->n < b->order || b->n > AFFECT_BSPLINE_MAX_BASIS)
        return "the basis size must be from the order to 4096";
    return NULL;
}

static uint32_t n_intervals(const affect_bspline *b)
{
    return b->n - b->order + 1;
}

double affect_bspline_knot(const affect_bspline *b, uint32_t j)
{
    uint32_t k = b->order, L = n_intervals(b);
    if (j < k)
        return 0.0;
    if (j >= b->n)
        return 1.0;
    return (double)(j - k + 1) / (double)L;
}

uint32_t affect_bspline_eval(const affect_bspline *b, double t, uint32_t deriv, double *v)
{
    uint32_t k = b->order, L = n_intervals(b);
    if (!(t > 0.0))
        t = 0.0;
    if (t > 1.0)
        t = 1.0;
    uint32_t s = (uint32_t)floor(t * (double)L);
    if (s >= L)
        s = L - 1;
    uint32_t mu = s + k - 1; /* t_mu <= t < t_{mu+1} */
    /* values of order r = 1 .. k − deriv (Cox–de Boor, the form of de Boor's BSPLVB) */
    uint32_t top = k - deriv;
    double left[AFFECT_BSPLINE_MAX_ORDER], right[AFFECT_BSPLINE_MAX_ORDER];
    double cur[AFFECT_BSPLINE_MAX_ORDER];
    cur[0] = 1.0;
    for (uint32_t j = 1; j < top; j++) {
        left[j] = t - affect_bspline_knot(b, mu + 1 - j);
        right[j] = affect_bspline_knot(b, mu + j) - t;
        double saved = 0.0;
        for (uint32_t r = 0; r < j; r++) {
            double den = right[r + 1] + left[j - r];
            double temp = den > 0 ? cur[r] / den : 0.0;
            cur[r] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        cur[j] = saved;
    }
    /* derivatives: raise the order from top to k; at order r entry j is B_{mu−r+1+j, r} */
    for (uint32_t r = top + 1; r <= k; r++) {
        double next[AFFECT_BSPLINE_MAX_ORDER];
        for (uint32_t j = 0; j < r; j++) {
            uint32_t i = mu - r + 1 + j;
            double a = 0.0, c = 0.0;
            if (j >= 1) {
                double den = affect_bspline_knot(b, i + r - 1) - affect_bspline_knot(b, i);
                if (den > 0)
                    a = cur[j - 1] / den;
            }
            if (j < r - 1) {
                double den = affect_bspline_knot(b, i + r) - affect_bspline_knot(b, i + 1);
                if (den > 0)
                    c = cur[j] / den;
            }
            next[j] = (double)(r - 1) * (a - c);
        }
        memcpy(cur, next, r * sizeof *cur);
    }
    memcpy(v, cur, k * sizeof *v);
    return mu - k + 1;
}

/* P_n(x) by the three-term recurrence, and P_n′(x) (|x| < 1) into *dp. */
static double legendre(uint32_t n, double x, double *dp)
{
    double p0 = 1.0, p1 = x;
    for (uint32_t j = 2; j <= n; j++) {
        double p2 = ((double)(2 * j - 1) * x * p1 - (double)(j - 1) * p0) / (double)j;
        p0 = p1;
        p1 = p2;
    }
    *dp = (double)n * (x * p1 - p0) / (x * x - 1.0);
    return p1;
}

void affect_gauss_legendre(uint32_t n, double *nodes, double *weights)
{
    const double pi = 3.14159265358979323846;
    for (uint32_t i = 0; i < n; i++) {
        /* root i (descending from cos), refined by Newton on P_n */
        double x = cos(pi * ((double)i + 0.75) / ((double)n + 0.5)), dp;
        for (int it = 0; it < NEWTON_MAX_ITER; it++) {
            double dx = legendre(n, x, &dp) / dp;
            x -= dx;
            if (fabs(dx) <= 1e-16)
                break;
        }
        legendre(n, x, &dp);
        nodes[n - 1 - i] = x;
        weights[n - 1 - i] = 2.0 / ((1.0 - x * x) * dp * dp);
    }
}

void affect_bspline_gram(const affect_bspline *b, uint32_t deriv, double *band)
{
    uint32_t k = b->order, G = b->n, L = n_intervals(b);
    double nodes[AFFECT_BSPLINE_MAX_ORDER], weights[AFFECT_BSPLINE_MAX_ORDER];
    double v[AFFECT_BSPLINE_MAX_ORDER];
    affect_gauss_legendre(k, nodes, weights);
    memset(band, 0, (size_t)G * k * sizeof *band);
    double h = 1.0 / (double)L;
    for (uint32_t s = 0; s < L; s++) {
        double a = (double)s * h;
        for (uint32_t q = 0; q < k; q++) {
            double t = a + 0.5 * h * (nodes[q] + 1.0), w = 0.5 * h * weights[q];
            uint32_t first = affect_bspline_eval(b, t, deriv, v);
            for (uint32_t i = 0; i < k; i++)
                for (uint32_t j = i; j < k; j++)
                    band[(size_t)(first + i) * k + (j - i)] += w * v[i] * v[j];
        }
    }
}

void affect_band_mul(const double *band, uint32_t g, uint32_t k, const double *x, uint32_t m,
                     double *y)
{
    memset(y, 0, (size_t)g * m * sizeof *y);
    for (uint32_t i = 0; i < g; i++) {
        for (uint32_t d = 0; d < k && i + d < g; d++) {
            double s = band[(size_t)i * k + d];
            uint32_t j = i + d;
            for (uint32_t c = 0; c < m; c++) {
                y[(size_t)i * m + c] += s * x[(size_t)j * m + c];
                if (d)
                    y[(size_t)j * m + c] += s * x[(size_t)i * m + c];
            }
        }
    }
}

bool affect_band_cholesky(double *band, uint32_t g, uint32_t k)
{
    double dmax = 0.0;
    for (uint32_t i = 0; i < g; i++)
        if (band[(size_t)i * k] > dmax)
            dmax = band[(size_t)i * k];
    if (!(dmax > 0) || !isfinite(dmax))
        return false;
    for (uint32_t i = 0; i < g; i++) {
        double d = band[(size_t)i * k];
        uint32_t l0 = i >= k - 1 ? i - (k - 1) : 0;
        for (uint32_t l = l0; l < i; l++) {
            double u = band[(size_t)l * k + (i - l)];
            d -= u * u;
        }
        if (!(d > AFFECT_BAND_PIVOT_TOL * dmax) || !isfinite(d))
            return false;
        double uii = sqrt(d);
        band[(size_t)i * k] = uii;
        for (uint32_t j = i + 1; j < g && j - i < k; j++) {
            double s = band[(size_t)i * k + (j - i)];
            uint32_t m0 = j >= k - 1 ? j - (k - 1) : 0;
            for (uint32_t l = m0 > l0 ? m0 : l0; l < i; l++)
                s -= band[(size_t)l * k + (i - l)] * band[(size_t)l * k + (j - l)];
            band[(size_t)i * k + (j - i)] = s / uii;
        }
    }
    return true;
}

void affect_band_solve(const double *u, uint32_t g, uint32_t k, double *x, uint32_t m)
{
    /* Uᵀ y = rhs (forward) */
    for (uint32_t i = 0; i < g; i++) {
        uint32_t l0 = i >= k - 1 ? i - (k - 1) : 0;
        for (uint32_t c = 0; c < m; c++) {
            double s = x[(size_t)i * m + c];
            for (uint32_t l = l0; l < i; l++)
                s -= u[(size_t)l * k + (i - l)] * x[(size_t)l * m + c];
            x[(size_t)i * m + c] = s / u[(size_t)i * k];
        }
    }
    /* U x = y (backward) */
    for (uint32_t ii = g; ii-- > 0;) {
        for (uint32_t c = 0; c < m; c++) {
            double s = x[(size_t)ii * m + c];
            for (uint32_t j = ii + 1; j < g && j - ii < k; j++)
                s -= u[(size_t)ii * k + (j - ii)] * x[(size_t)j * m + c];
            x[(size_t)ii * m + c] = s / u[(size_t)ii * k];
        }
    }
}

static double sample_time(const double *t, uint32_t j, uint32_t T)
{
    if (t)
        return t[j];
    return T > 1 ? (double)j / (double)(T - 1) : 0.0;
}

void affect_bspline_normal(const affect_bspline *b, const double *t, const double *x, uint32_t T,
                           uint32_t m, double *a, double *rhs)
{
    uint32_t k = b->order, G = b->n;
    double v[AFFECT_BSPLINE_MAX_ORDER];
    memset(a, 0, (size_t)G * k * sizeof *a);
    memset(rhs, 0, (size_t)G * m * sizeof *rhs);
    double inv = 1.0 / (double)(T ? T : 1);
    for (uint32_t s = 0; s < T; s++) {
        uint32_t first = affect_bspline_eval(b, sample_time(t, s, T), 0, v);
        for (uint32_t i = 0; i < k; i++) {
            for (uint32_t j = i; j < k; j++)
                a[(size_t)(first + i) * k + (j - i)] += inv * v[i] * v[j];
            for (uint32_t c = 0; c < m; c++)
                rhs[(size_t)(first + i) * m + c] += inv * v[i] * x[(size_t)s * m + c];
        }
    }
}

affect_status affect_bspline_fit(const affect_bspline *b, const double *r, const double *t,
                                 const double *x, uint32_t T, uint32_t m, double lambda, double *c,
                                 double *work, affect_error *err)
{
    uint32_t k = b->order, G = b->n;
    if (T == 0)
        return affect_fail(err, AFFECT_ERR_INVALID, "need at least 1 sample");
    for (uint32_t s = 0; s < T; s++)
        for (uint32_t j = 0; j < m; j++)
            if (!isfinite(x[(size_t)s * m + j]))
                return affect_fail(err, AFFECT_ERR_INVALID,
                                   "sample %u, column %u: non-finite "
                                   "value",
                                   s, j);
    double *a = work;
    affect_bspline_normal(b, t, x, T, m, a, c);
    for (size_t i = 0; i < (size_t)G * k; i++)
        a[i] += lambda * r[i];
    if (!affect_band_cholesky(a, G, k))
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "the fit is singular: %u samples cannot determine %u coefficients "
                           "with lambda = %g (give a positive lambda or a smaller basis)",
                           T, G, lambda);
    affect_band_solve(a, G, k, c, m);
    return AFFECT_OK;
}

void affect_bspline_values(const affect_bspline *b, const double *c, uint32_t m, const double *t,
                           uint32_t T, double *f)
{
    uint32_t k = b->order;
    double v[AFFECT_BSPLINE_MAX_ORDER];
    for (uint32_t s = 0; s < T; s++) {
        uint32_t first = affect_bspline_eval(b, sample_time(t, s, T), 0, v);
        for (uint32_t j = 0; j < m; j++) {
            double sum = 0.0;
            for (uint32_t i = 0; i < k; i++)
                sum += v[i] * c[(size_t)(first + i) * m + j];
            f[(size_t)s * m + j] = sum;
        }
    }
}

size_t affect_bspline_gcv_work(const affect_bspline *b, uint32_t T, uint32_t m)
{
    (void)T;
    return 3 * (size_t)b->n * b->order + (size_t)b->n * m;
}

double affect_bspline_gcv(const affect_bspline *b, const double *r, const double *t,
                          const double *x, uint32_t T, uint32_t m, double lambda, double *df,
                          double *work)
{
    uint32_t k = b->order, G = b->n;
    double *a = work, *u = a + (size_t)G * k, *c = u + (size_t)G * k, *sb = c + (size_t)G * m;
    affect_bspline_normal(b, t, x, T, m, a, c);
    for (size_t i = 0; i < (size_t)G * k; i++)
        u[i] = a[i] + lambda * r[i];
    if (df)
        *df = INFINITY;
    if (!affect_band_cholesky(u, G, k))
        return INFINITY;
    affect_band_solve(u, G, k, c, m);
    /* df = tr((A + λR)⁻¹ A) = Σ_{|i−j|<k} S_ij A_ji with S = (A + λR)⁻¹: only S's band is
     * needed, and it follows from the factor U by the recursion of Hutchinson and de Hoog
     * (S_ij = δ_ij / U_ii² − Σ_{l>i} (U_il / U_ii) S_lj for j ≥ i), O(G k²) */
    /* sb: S's band, sb[i k + d] = S_{i, i+d} */
    for (uint32_t ii = G; ii-- > 0;) {
        double uii = u[(size_t)ii * k];
        for (uint32_t d = k; d-- > 0;) {
            uint32_t j = ii + d;
            if (j >= G) {
                sb[(size_t)ii * k + d] = 0.0;
                continue;
            }
            double sum = 0.0;
            for (uint32_t l = ii + 1; l < G && l - ii < k; l++) {
                double slj = l <= j ? sb[(size_t)l * k + (j - l)] : sb[(size_t)j * k + (l - j)];
                sum += u[(size_t)ii * k + (l - ii)] * slj;
            }
            sb[(size_t)ii * k + d] = (d == 0 ? 1.0 / uii : 0.0) / uii - sum / uii;
        }
    }
    double tr = 0.0;
    for (uint32_t i = 0; i < G; i++)
        for (uint32_t d = 0; d < k && i + d < G; d++)
            tr += (d ? 2.0 : 1.0) * sb[(size_t)i * k + d] * a[(size_t)i * k + d];
    if (df)
        *df = tr;
    if (!(tr < (double)T - AFFECT_GCV_DF_MARGIN))
        return INFINITY;
    double v[AFFECT_BSPLINE_MAX_ORDER], sse = 0.0;
    for (uint32_t s = 0; s < T; s++) {
        uint32_t first = affect_bspline_eval(b, sample_time(t, s, T), 0, v);
        for (uint32_t j = 0; j < m; j++) {
            double f = 0.0;
            for (uint32_t i = 0; i < k; i++)
                f += v[i] * c[(size_t)(first + i) * m + j];
            double e = x[(size_t)s * m + j] - f;
            sse += e * e;
        }
    }
    double den = (double)T - tr;
    return (double)T * sse / (den * den);
}
