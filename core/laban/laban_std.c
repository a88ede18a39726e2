/*
 * laban_std.c — standardization of Laban vectors (affect/laban.h, "standardization"): the
 * statistics the laban index keeps (mean and sample standard deviation per component, missing
 * values skipped), the z-scores it searches (affect_laban_standardize; laban_search.c compares
 * them), their validation when read back, and the float32 z-score vector whose L2
 * distances are the index's distances, for sqlite-vec's vec0 and other L2 searches.
 *
 * Why the L2 vector equals the index's distance: the index computes
 *   d(q, x) = sqrt( Σ_{j ∈ C, both present} ((q_j − m_j)/s_j − (x_j − m_j)/s_j)² )
 * over the chosen components C, in double from the stored float32 x_j. With every component of
 * C present in both vectors this is exactly the Euclidean distance of the two z-vectors; the
 * components missing everywhere (m_j NaN) are skipped for every pair, which writing 0 for them
 * reproduces. The only difference left is rounding: vec0 takes float32 z-scores and sums in
 * float32, so two distances closer than about 1e-6 relative may come out in either order.
 */
#include <float.h>
#include <math.h>

#include "affect/laban.h"

float affect_laban_f32(double v)
{
    return fabs(v) <= FLT_MAX ? (float)v : NAN; /* NaN, ±inf and overflow are missing */
}

void affect_laban_standardize(const float *x, size_t n, const double mean[AFFECT_LABAN_N],
                              const double sd[AFFECT_LABAN_N], double *z)
{
    for (size_t i = 0; i < n; i++)
        for (int j = 0; j < AFFECT_LABAN_N; j++)
            z[i * AFFECT_LABAN_N + j] = ((double)x[i * AFFECT_LABAN_N + j] - mean[j]) / sd[j];
}

void affect_laban_acc_init(affect_laban_acc *a)
{
    for (int j = 0; j < AFFECT_LABAN_N; j++) {
        a->sum[j] = a->ss[j] = a->mean[j] = 0;
        a->cnt[j] = 0;
    }
}

void affect_laban_acc_sums(affect_laban_acc *a, const float *x, size_t n)
{
    for (int j = 0; j < AFFECT_LABAN_N; j++) {
        double sum = a->sum[j];
        size_t cnt = a->cnt[j];
        for (size_t i = 0; i < n; i++) {
            double v = x[i * AFFECT_LABAN_N + j];
            if (!isnan(v)) {
                sum += v;
                cnt++;
            }
        }
        a->sum[j] = sum;
        a->cnt[j] = cnt;
    }
}

void affect_laban_acc_means(affect_laban_acc *a)
{
    for (int j = 0; j < AFFECT_LABAN_N; j++)
        a->mean[j] = a->cnt[j] ? a->sum[j] / (double)a->cnt[j] : NAN;
}

void affect_laban_acc_squares(affect_laban_acc *a, const float *x, size_t n)
{
    for (int j = 0; j < AFFECT_LABAN_N; j++) {
        double m = a->mean[j], ss = a->ss[j];
        for (size_t i = 0; i < n && a->cnt[j]; i++) {
            double v = x[i * AFFECT_LABAN_N + j];
            if (!isnan(v))
                ss += (v - m) * (v - m);
        }
        a->ss[j] = ss;
    }
}

void affect_laban_acc_result(const affect_laban_acc *a, double mean[AFFECT_LABAN_N],
                             double sd[AFFECT_LABAN_N])
{
    for (int j = 0; j < AFFECT_LABAN_N; j++) {
        size_t cnt = a->cnt[j];
        double s = cnt > 1 ? sqrt(a->ss[j] / (double)(cnt - 1)) : 0;
        mean[j] = a->mean[j];
        sd[j] = s > 0 && isfinite(s) ? s : 1;
    }
}

void affect_laban_stats(const float *x, size_t n, double mean[AFFECT_LABAN_N],
                        double sd[AFFECT_LABAN_N])
{
    affect_laban_acc a;
    affect_laban_acc_init(&a);
    affect_laban_acc_sums(&a, x, n);
    affect_laban_acc_means(&a);
    affect_laban_acc_squares(&a, x, n);
    affect_laban_acc_result(&a, mean, sd);
}

affect_status affect_laban_stats_check(const double mean[AFFECT_LABAN_N],
                                       const double sd[AFFECT_LABAN_N], affect_error *err)
{
    for (int j = 0; j < AFFECT_LABAN_N; j++) {
        if (isinf(mean[j]))
            return affect_fail(err, AFFECT_ERR_FORMAT,
                               "mean[%d] (%s) is %s, expected a finite "
                               "number or null",
                               j, affect_laban_names[j], mean[j] > 0 ? "inf" : "-inf");
        if (!(isfinite(sd[j]) && sd[j] > 0))
            return affect_fail(err, AFFECT_ERR_FORMAT,
                               "sd[%d] (%s) is %.17g, expected a finite "
                               "number > 0",
                               j, affect_laban_names[j], sd[j]);
    }
    return AFFECT_OK;
}

affect_status affect_laban_l2_vector(const float x[AFFECT_LABAN_N],
                                     const double mean[AFFECT_LABAN_N],
                                     const double sd[AFFECT_LABAN_N], const int *comp, int n_comp,
                                     float *out, affect_error *err)
{
    if (comp ? n_comp < 1 || n_comp > AFFECT_LABAN_N : n_comp != AFFECT_LABAN_N)
        return affect_fail(err, AFFECT_ERR_INVALID, "%d components, expected 1 to %d", n_comp,
                           AFFECT_LABAN_N);
    for (int t = 0; t < n_comp; t++) {
        int c = comp ? comp[t] : t;
        if (c < 0 || c >= AFFECT_LABAN_N)
            return affect_fail(err, AFFECT_ERR_INVALID,
                               "component index %d is out of range "
                               "(0 to %d)",
                               c, AFFECT_LABAN_N - 1);
        if (isnan(mean[c])) {
            out[t] = 0;
            continue;
        }
        if (isnan(x[c]))
            return affect_fail(err, AFFECT_ERR_MISSING,
                               "component %s is missing in this motion "
                               "but present in the index, so no L2 vector gives the index's "
                               "distances",
                               affect_laban_names[c]);
        float z = (float)(((double)x[c] - mean[c]) / sd[c]);
        if (!isfinite(z))
            return affect_fail(err, AFFECT_ERR_RANGE,
                               "the z-score of %s, (%.9g - %.17g) / "
                               "%.17g, is beyond the float32 range",
                               affect_laban_names[c], (double)x[c], mean[c], sd[c]);
        out[t] = z;
    }
    return AFFECT_OK;
}
