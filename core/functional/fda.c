/*
 * fda.c — functional analysis of movements (see affect/fda.h): B-spline fits of every
 * coordinate series, the dual Gram matrix of the centred functions in L², and FPCA, FSPCA,
 * FFDA and F-Isomap fitted on it; embedding of unseen motions, k-NN classification, class
 * prototypes from the FPCA space, and the functional-model BLOB.
 *
 * How training runs (n motions, h = G m coefficients each):
 *   1. λ (given, or GCV over the grid: every motion's GCV term at every λ; O(n G² k) per λ);
 *   2. the coefficients C (n × h) by band Cholesky fits, the mean c̄, C̃ = C − c̄,
 *      W = C̃ (M ⊗ I) (band products), K = C̃ Wᵀ (one cblas_dgemm, n² h);
 *   3. K's eigenpairs (LAPACK dsyevr, column-major on the symmetric array so no transposed
 *      copies are made, workspace from our allocator): FPCA scores, eigenfunctions, class
 *      centroids;
 *   4. the method: FPCA axes Wᵀ v / √λ; FSPCA by affect_spca_fit_dual on K and
 *      affect_spca_add_rows on W; FFDA in the FPCA score space (R × R, plain C Cholesky);
 *      F-Isomap from K's distances (kNN graph, its pieces joined by their shortest distances,
 *      Floyd–Warshall, MDS by dsyevr).
 * The monitor is polled between motions, between λ values and between Floyd–Warshall rounds.
 */
#include "affect/fda.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <cblas.h>
#include <lapacke.h>

#include "util/bytes.h"
#include "affect/hmm_blob.h" /* affect_fnv1a64 */
#include "affect/skeleton.h"
#include "util/internal.h"

#define GCV_E_MIN (-30)
#define GCV_E_MAX 0

/* Landmark registration (affect/fda.h): the speed's moving-average half-width as a share of the
 * frame count, the least rise or fall kept (share of the speed's range), the margin at either
 * end, the matching's cost of an unmatched landmark and its largest time shift, and the least
 * gap between consecutive warp knots. */
#define LM_SMOOTH 0.03
#define LM_PROMINENCE 0.15
#define LM_EDGE 0.02
#define LM_SKIP 0.1
#define LM_MAX_SHIFT 0.2
#define LM_MIN_GAP 0.01
#define LM_MAX AFFECT_FDA_MAX_LANDMARKS

struct affect_fda {
    affect_fda_config cfg;
    affect_bspline b;
    uint32_t m, n, c, p, P, R;
    size_t h;
    affect_features *feat;
    char **classes;
    uint32_t *y;
    double *frames;   /* c */
    double *fpca_eig; /* R */
    double total_var;
    double *eig;       /* p */
    double *explained; /* p */
    double *mean;      /* h */
    double *efun;      /* P × h */
    double *centroid;  /* c × P */
    double *cmean;     /* c × h: the classes' mean centred coefficients (proto_dims 0, "all") */
    double *train_z;   /* n × p */
    double *axes;      /* p × h (FPCA, FFDA, FSPCA) */
    double *train_c;   /* n × h centred (F-Isomap) */
    double *mds_v;     /* n × p (F-Isomap) */
    double *d2mean;    /* n (F-Isomap) */
    double *geo;       /* n × n (F-Isomap) */
    /* derived from the above */
    double *mband, *rband; /* G × k */
    double *train_norm;    /* n: c̃_jᵀ (M ⊗ I) c̃_j (F-Isomap) */
    uint32_t n_lm;         /* the landmark template (alignment "landmarks") */
    affect_fda_landmark lm[LM_MAX];
};

void affect_fda_config_default(affect_fda_config *cfg)
{
    memset(cfg, 0, sizeof *cfg);
    cfg->method = AFFECT_FDA_FFDA; /* the measured best (docs/EVALUATION.md) */
    cfg->order = 4;
    cfg->n_basis = 200;
    cfg->lambda = 1e-10;
    cfg->gcv = false;
    cfg->dims = 3;
    cfg->kernel = AFFECT_SPCA_LINEAR;
    cfg->sigma = 1.0;
    cfg->ffda_reg = 1e-3;
    cfg->isomap_k = 7;
    cfg->proto_dims = 0; /* every component: the class's mean function (the measured best) */
    cfg->alignment = AFFECT_FDA_ALIGN_LINEAR;
    cfg->monitor = NULL;
}

const char *affect_fda_config_check(const affect_fda_config *cfg)
{
    if ((unsigned)cfg->method > AFFECT_FDA_FISOMAP)
        return "unknown method";
    affect_bspline b = {cfg->order, cfg->n_basis};
    const char *msg = affect_bspline_check(&b);
    if (msg)
        return msg;
    if (cfg->order < 3)
        return "order must be at least 3 for the roughness penalty";
    if (cfg->dims < 1 || cfg->dims > AFFECT_FDA_MAX_DIMS)
        return "dims must be from 1 to 64";
    if (!(cfg->lambda >= 0) || !isfinite(cfg->lambda))
        return "lambda must be a finite number, 0 or more";
    if ((unsigned)cfg->kernel > AFFECT_SPCA_RBF)
        return "unknown label kernel";
    if (!(cfg->sigma > 0) || !isfinite(cfg->sigma))
        return "sigma must be a positive finite number";
    if (!(cfg->ffda_reg >= 0) || !isfinite(cfg->ffda_reg))
        return "ffda_reg must be a finite number, 0 or more";
    if (cfg->isomap_k < 1 || cfg->isomap_k > AFFECT_FDA_MAX_ISOMAP_K)
        return "isomap_k must be from 1 to 1024";
    if (cfg->proto_dims > AFFECT_FDA_MAX_DIMS)
        return "proto_dims must be from 1 to 64, or all";
    if ((unsigned)cfg->alignment > AFFECT_FDA_ALIGN_LANDMARKS)
        return "unknown alignment";
    return NULL;
}

void affect_fda_free(affect_fda *f)
{
    if (!f)
        return;
    affect_features_free(f->feat);
    if (f->classes)
        for (uint32_t k = 0; k < f->c; k++)
            affect_free(f->classes[k]);
    affect_free(f->classes);
    affect_free(f->y);
    affect_free(f->frames);
    affect_free(f->fpca_eig);
    affect_free(f->eig);
    affect_free(f->explained);
    affect_free(f->mean);
    affect_free(f->efun);
    affect_free(f->centroid);
    affect_free(f->cmean);
    affect_free(f->train_z);
    affect_free(f->axes);
    affect_free(f->train_c);
    affect_free(f->mds_v);
    affect_free(f->d2mean);
    affect_free(f->geo);
    affect_free(f->mband);
    affect_free(f->rband);
    affect_free(f->train_norm);
    affect_free(f);
}

static bool is_linear(affect_fda_method m)
{
    return m != AFFECT_FDA_FISOMAP;
}

/* ---- symmetric eigendecomposition (dsyevr) ----
 * a: n × n symmetric (overwritten); w: n eigenvalues ascending; z: n × n with eigenvector r
 * contiguous at z + r n. Column-major call on the symmetric array: no transposed copies. */
static affect_status sym_eig(double *a, uint32_t n, double *w, double *z, affect_error *err)
{
    size_t lwork = 26 * (size_t)n, liwork = 10 * (size_t)n;
    double *work = affect_malloc_array(lwork ? lwork : 1, sizeof *work);
    lapack_int *iwork = affect_malloc_array(liwork + 2 * (size_t)n + 1, sizeof *iwork);
    affect_status st = AFFECT_OK;
    if (!work || !iwork) {
        st = affect_nomem(err);
        goto done;
    }
    lapack_int found = 0, info;
    AFFECT_BLAS(info = LAPACKE_dsyevr_work(LAPACK_COL_MAJOR, 'V', 'A', 'U', (lapack_int)n, a,
                                           (lapack_int)n, 0.0, 0.0, 0, 0, 0.0, &found, w, z,
                                           (lapack_int)n, iwork + liwork, work, (lapack_int)lwork,
                                           iwork, (lapack_int)liwork));
    if (info != 0 || found != (lapack_int)n)
        st = affect_fail(err, AFFECT_ERR_RANGE,
                         "the eigendecomposition did not converge (LAPACK info %d)", (int)info);
done:
    affect_free(work);
    affect_free(iwork);
    return st;
}

affect_status affect_fda_gram_sqrt(const affect_bspline *b, double *out, affect_error *err)
{
    uint32_t G = b->n, k = b->order;
    double *band = affect_malloc_array((size_t)G * k, sizeof *band);
    double *a = affect_calloc((size_t)G * G, sizeof *a);
    double *z = affect_malloc_array((size_t)G * G, sizeof *z);
    double *w = affect_malloc_array(G, sizeof *w);
    affect_status st = AFFECT_OK;
    if (!band || !a || !z || !w) {
        st = affect_nomem(err);
        goto done;
    }
    affect_bspline_gram(b, 0, band);
    for (uint32_t i = 0; i < G; i++)
        for (uint32_t d = 0; d < k && i + d < G; d++)
            a[(size_t)i * G + i + d] = a[(size_t)(i + d) * G + i] = band[(size_t)i * k + d];
    if ((st = sym_eig(a, G, w, z, err)) != AFFECT_OK)
        goto done;
    for (uint32_t r = 0; r < G; r++)
        w[r] = w[r] > 0 ? sqrt(w[r]) : 0.0;
    for (uint32_t i = 0; i < G; i++)
        for (uint32_t j = 0; j < G; j++) {
            double s = 0.0;
            for (uint32_t r = 0; r < G; r++)
                s += z[(size_t)r * G + i] * w[r] * z[(size_t)r * G + j];
            out[(size_t)i * G + j] = s;
        }
done:
    affect_free(band);
    affect_free(a);
    affect_free(z);
    affect_free(w);
    return st;
}

/* Basis matrices of a model (train and decode). */
static affect_status make_bands(affect_fda *f, affect_error *err)
{
    size_t cells = (size_t)f->b.n * f->b.order;
    f->mband = affect_malloc_array(cells, sizeof *f->mband);
    f->rband = affect_malloc_array(cells, sizeof *f->rband);
    if (!f->mband || !f->rband)
        return affect_nomem(err);
    affect_bspline_gram(&f->b, 0, f->mband);
    affect_bspline_gram(&f->b, 2, f->rband);
    return AFFECT_OK;
}

/* Σ_j a_j b_j in index order. */
static double dot(const double *a, const double *b, size_t n)
{
    double s = 0.0;
    for (size_t i = 0; i < n; i++)
        s += a[i] * b[i];
    return s;
}

/* train_norm for F-Isomap. */
static affect_status make_norms(affect_fda *f, affect_error *err)
{
    if (f->cfg.method != AFFECT_FDA_FISOMAP)
        return AFFECT_OK;
    f->train_norm = affect_malloc_array(f->n, sizeof *f->train_norm);
    double *w = affect_malloc_array(f->h, sizeof *w);
    if (!f->train_norm || !w) {
        affect_free(w);
        return affect_nomem(err);
    }
    for (uint32_t j = 0; j < f->n; j++) {
        const double *cj = f->train_c + (size_t)j * f->h;
        affect_band_mul(f->mband, f->b.n, f->b.order, cj, f->m, w);
        f->train_norm[j] = dot(cj, w, f->h);
    }
    affect_free(w);
    return AFFECT_OK;
}

/* ---- training ---- */

/* ---- landmark registration ---- */

/* Removes entries k and k + 1 of the extrema (idx, type, val: *n of them). */
static void drop_pair(uint32_t *idx, int32_t *type, double *val, uint32_t *n, uint32_t k)
{
    for (uint32_t j = k; j + 2 < *n; j++) {
        idx[j] = idx[j + 2];
        type[j] = type[j + 2];
        val[j] = val[j + 2];
    }
    *n -= 2;
}

affect_status affect_fda_find_landmarks(const double *x, uint32_t T, uint32_t m,
                                        affect_fda_landmark *out, uint32_t *count,
                                        affect_error *err)
{
    *count = 0;
    if (T < 5)
        return AFFECT_OK;
    uint32_t S = T - 1; /* speed samples, at times (j + ½) / (T − 1) */
    double *v = affect_malloc_array((size_t)S, 4 * sizeof *v);
    if (!v)
        return affect_nomem(err);
    double *sm = v + S, *val = v + 2 * (size_t)S;
    uint32_t *idx = (uint32_t *)(v + 3 * (size_t)S); /* S × 4 bytes fit in S doubles' half */
    int32_t *type = (int32_t *)(idx + S);
    for (uint32_t j = 0; j < S; j++) {
        double q = 0.0;
        for (uint32_t i = 0; i < m; i++) {
            double d = x[(size_t)(j + 1) * m + i] - x[(size_t)j * m + i];
            q += d * d;
        }
        v[j] = sqrt(q);
    }
    uint32_t w = (uint32_t)lround(LM_SMOOTH * T);
    if (w < 1)
        w = 1;
    double lo = INFINITY, hi = -INFINITY;
    for (uint32_t j = 0; j < S; j++) {
        uint32_t a = j > w ? j - w : 0, b = j + w < S ? j + w : S - 1;
        double q = 0.0;
        for (uint32_t k = a; k <= b; k++)
            q += v[k];
        sm[j] = q / (b - a + 1);
        lo = sm[j] < lo ? sm[j] : lo;
        hi = sm[j] > hi ? sm[j] : hi;
    }
    double range = hi - lo;
    uint32_t n = 0;
    if (!(range > 0) || !isfinite(range))
        goto done;
    for (uint32_t j = 1; j + 1 < S; j++) {
        int32_t ty = 0;
        if (sm[j] > sm[j - 1] && sm[j] >= sm[j + 1])
            ty = 1;
        else if (sm[j] < sm[j - 1] && sm[j] <= sm[j + 1])
            ty = -1;
        if (!ty)
            continue;
        if (n > 0 && type[n - 1] == ty) { /* two of a kind in a row: keep the more extreme */
            if ((ty > 0 && sm[j] > val[n - 1]) || (ty < 0 && sm[j] < val[n - 1])) {
                idx[n - 1] = j;
                val[n - 1] = sm[j];
            }
            continue;
        }
        idx[n] = j;
        type[n] = ty;
        val[n++] = sm[j];
    }
    /* the least pronounced adjacent pair goes first, while below the threshold or too many */
    while (n >= 2) {
        uint32_t best = 0;
        double bd = INFINITY;
        for (uint32_t k = 0; k + 1 < n; k++) {
            double d = fabs(val[k] - val[k + 1]);
            if (d < bd) {
                bd = d;
                best = k;
            }
        }
        if (bd >= LM_PROMINENCE * range && n <= LM_MAX)
            break;
        drop_pair(idx, type, val, &n, best);
    }
    if (n == 1 && fabs(val[0] - sm[0]) < LM_PROMINENCE * range &&
        fabs(val[0] - sm[S - 1]) < LM_PROMINENCE * range)
        n = 0; /* one shallow bump */
done:;
    uint32_t c = 0;
    for (uint32_t k = 0; k < n; k++) {
        double t = (idx[k] + 0.5) / (double)(T - 1);
        if (t > LM_EDGE && t < 1.0 - LM_EDGE && c < LM_MAX)
            out[c++] = (affect_fda_landmark){t, type[k]};
    }
    *count = c;
    affect_free(v);
    return AFFECT_OK;
}

uint32_t affect_fda_match_landmarks(const affect_fda_landmark *a, uint32_t na,
                                    const affect_fda_landmark *b, uint32_t nb, uint32_t *ia,
                                    uint32_t *ib)
{
    enum { W = LM_MAX + 1 };
    double d[W * W];
    unsigned char how[W * W]; /* 0 match, 1 skip a's, 2 skip b's */
    na = na < LM_MAX ? na : LM_MAX;
    nb = nb < LM_MAX ? nb : LM_MAX;
    for (uint32_t i = 0; i <= na; i++)
        for (uint32_t k = 0; k <= nb; k++) {
            double best;
            unsigned char h = 0;
            if (i == 0 && k == 0) {
                best = 0.0;
            } else {
                best = INFINITY;
                if (i > 0 && k > 0 && a[i - 1].type == b[k - 1].type) {
                    double dt = fabs(a[i - 1].t - b[k - 1].t);
                    if (dt <= LM_MAX_SHIFT)
                        best = d[(i - 1) * W + k - 1] + dt;
                }
                if (i > 0 && d[(i - 1) * W + k] + LM_SKIP < best) {
                    best = d[(i - 1) * W + k] + LM_SKIP;
                    h = 1;
                }
                if (k > 0 && d[i * W + k - 1] + LM_SKIP < best) {
                    best = d[i * W + k - 1] + LM_SKIP;
                    h = 2;
                }
            }
            d[i * W + k] = best;
            how[i * W + k] = h;
        }
    uint32_t n = 0, i = na, k = nb;
    uint32_t pa[LM_MAX], pb[LM_MAX];
    while (i > 0 || k > 0) {
        unsigned char h = how[i * W + k];
        if (i > 0 && k > 0 && h == 0) {
            pa[n] = i - 1;
            pb[n++] = k - 1;
            i--;
            k--;
        } else if (i > 0 && (h == 1 || k == 0)) {
            i--;
        } else {
            k--;
        }
    }
    for (uint32_t j = 0; j < n; j++) { /* back to time order */
        ia[j] = pa[n - 1 - j];
        ib[j] = pb[n - 1 - j];
    }
    return n;
}

void affect_fda_warp_times(const affect_fda_landmark *a, uint32_t na,
                           const affect_fda_landmark *tmpl, uint32_t nt, uint32_t T, double *times)
{
    uint32_t ia[LM_MAX], ib[LM_MAX];
    uint32_t np = affect_fda_match_landmarks(a, na, tmpl, nt, ia, ib);
    double u[LM_MAX + 2], h[LM_MAX + 2];
    uint32_t K = 0;
    u[K] = 0.0;
    h[K++] = 0.0;
    for (uint32_t j = 0; j < np; j++) {
        double s = a[ia[j]].t, g = tmpl[ib[j]].t;
        if (s > u[K - 1] + LM_MIN_GAP && g > h[K - 1] + LM_MIN_GAP && s < 1.0 - LM_MIN_GAP &&
            g < 1.0 - LM_MIN_GAP) {
            u[K] = s;
            h[K++] = g;
        }
    }
    u[K] = 1.0;
    h[K++] = 1.0;
    uint32_t seg = 0;
    for (uint32_t j = 0; j < T; j++) {
        double t = T > 1 ? (double)j / (T - 1) : 0.0;
        while (seg + 2 < K && t > u[seg + 1])
            seg++;
        double r = (t - u[seg]) / (u[seg + 1] - u[seg]);
        double v = h[seg] + r * (h[seg + 1] - h[seg]);
        times[j] = v < 0.0 ? 0.0 : v > 1.0 ? 1.0 : v;
    }
}

/* The consensus of the landmark sets sets[members[i]] (counts cnt): the reference (the
 * member with the median count, the first such in member order) keeps the landmarks matched
 * in at least half of the members, at their mean matched time. */
static void consensus(const affect_fda_landmark *sets, const uint32_t *cnt, const uint32_t *members,
                      uint32_t nm, affect_fda_landmark *out, uint32_t *n_out)
{
    *n_out = 0;
    if (nm == 0)
        return;
    /* the median count's member: the (nm − 1) / 2-th by (count, order) */
    uint32_t ref = members[0];
    uint32_t want = (nm - 1) / 2;
    for (uint32_t i = 0; i < nm; i++) {
        uint32_t below = 0, same_before = 0;
        for (uint32_t j = 0; j < nm; j++) {
            below += cnt[members[j]] < cnt[members[i]];
            same_before += j < i && cnt[members[j]] == cnt[members[i]];
        }
        if (below + same_before == want) {
            ref = members[i];
            break;
        }
    }
    const affect_fda_landmark *r = sets + (size_t)ref * LM_MAX;
    uint32_t nr = cnt[ref];
    double sum[LM_MAX] = {0};
    uint32_t hits[LM_MAX] = {0};
    for (uint32_t i = 0; i < nm; i++) {
        uint32_t ia[LM_MAX], ib[LM_MAX];
        uint32_t np = affect_fda_match_landmarks(sets + (size_t)members[i] * LM_MAX,
                                                 cnt[members[i]], r, nr, ia, ib);
        for (uint32_t k = 0; k < np; k++) {
            sum[ib[k]] += sets[(size_t)members[i] * LM_MAX + ia[k]].t;
            hits[ib[k]]++;
        }
    }
    uint32_t n = 0;
    double last = 0.0;
    for (uint32_t k = 0; k < nr; k++) {
        if (2 * hits[k] < nm)
            continue;
        double t = sum[k] / hits[k];
        if (t > last + LM_MIN_GAP && t < 1.0 - LM_MIN_GAP) {
            out[n++] = (affect_fda_landmark){t, r[k].type};
            last = t;
        }
    }
    *n_out = n;
}

/* The template of the training motions (f->lm, f->n_lm) and their registered times (one
 * buffer, motion i's from offset off[i]). */
static affect_status build_template(affect_fda *f, const affect_hmm_seq *seqs, uint32_t n,
                                    uint32_t m, const uint32_t *y, uint32_t c,
                                    const affect_fda_config *cfg, double *times, const size_t *off,
                                    affect_error *err)
{
    affect_fda_landmark *sets = affect_malloc_array((size_t)n + c, LM_MAX * sizeof *sets);
    uint32_t *cnt = affect_malloc_array((size_t)n + c, sizeof *cnt);
    uint32_t *members = affect_malloc_array((size_t)n + c, sizeof *members);
    affect_status st = AFFECT_OK;
    if (!sets || !cnt || !members) {
        st = affect_nomem(err);
        goto done;
    }
    for (uint32_t i = 0; i < n; i++) {
        if ((st = affect_monitor_check(cfg->monitor, err)) != AFFECT_OK)
            goto done;
        st = affect_fda_find_landmarks(seqs[i].x, seqs[i].n_frames, m, sets + (size_t)i * LM_MAX,
                                       &cnt[i], err);
        if (st)
            goto done;
    }
    for (uint32_t k = 0; k < c; k++) { /* class templates at n + k */
        uint32_t nm = 0;
        for (uint32_t i = 0; i < n; i++)
            if (y[i] == k)
                members[nm++] = i;
        consensus(sets, cnt, members, nm, sets + (size_t)(n + k) * LM_MAX, &cnt[n + k]);
    }
    for (uint32_t k = 0; k < c; k++)
        members[k] = n + k;
    consensus(sets, cnt, members, c, f->lm, &f->n_lm);
    for (uint32_t i = 0; i < n; i++)
        affect_fda_warp_times(sets + (size_t)i * LM_MAX, cnt[i], f->lm, f->n_lm, seqs[i].n_frames,
                              times + off[i]);
done:
    affect_free(sets);
    affect_free(cnt);
    affect_free(members);
    return st;
}

const affect_fda_landmark *affect_fda_template(const affect_fda *f, uint32_t *n)
{
    *n = f->n_lm;
    return f->lm;
}

affect_status affect_fda_times(const affect_fda *f, const double *x, uint32_t T, double *times,
                               affect_error *err)
{
    if (f->cfg.alignment != AFFECT_FDA_ALIGN_LANDMARKS) {
        for (uint32_t j = 0; j < T; j++)
            times[j] = T > 1 ? (double)j / (T - 1) : 0.0;
        return AFFECT_OK;
    }
    affect_fda_landmark lm[LM_MAX];
    uint32_t n = 0;
    affect_status st = affect_fda_find_landmarks(x, T, f->m, lm, &n, err);
    if (st)
        return st;
    affect_fda_warp_times(lm, n, f->lm, f->n_lm, T, times);
    return AFFECT_OK;
}

static affect_status choose_lambda(const affect_fda_config *cfg, const affect_bspline *b,
                                   const double *rband, const affect_hmm_seq *seqs, uint32_t n,
                                   uint32_t m, const double *times, const size_t *off,
                                   double *lambda, affect_error *err)
{
    double *work = affect_malloc_array(affect_bspline_gcv_work(b, 0, m), sizeof *work);
    if (!work)
        return affect_nomem(err);
    double best = INFINITY, best_lam = cfg->lambda;
    affect_status st = AFFECT_OK;
    for (int e = GCV_E_MIN; e <= GCV_E_MAX; e++) {
        double lam = pow(10.0, e / 2.0), total = 0.0;
        for (uint32_t i = 0; i < n && isfinite(total); i++) {
            if ((st = affect_monitor_check(cfg->monitor, err)) != AFFECT_OK)
                goto done;
            total += affect_bspline_gcv(b, rband, times ? times + off[i] : NULL, seqs[i].x,
                                        seqs[i].n_frames, m, lam, NULL, work);
        }
        affect_monitor_report(cfg->monitor, "GCV", (uint64_t)(e - GCV_E_MIN + 1),
                              (uint64_t)(GCV_E_MAX - GCV_E_MIN + 1));
        if (total < best) {
            best = total;
            best_lam = lam;
        }
    }
    if (!isfinite(best))
        st = affect_fail(err, AFFECT_ERR_INVALID,
                         "GCV is infinite for every lambda of the grid "
                         "(motions too short for the basis: use a smaller basis)");
    *lambda = best_lam;
done:
    affect_free(work);
    return st;
}

/* Orients each of p columns of z (n × p) so that its largest-magnitude entry (the first on
 * a tie) is positive; flips (p) records which were turned. */
static void orient_columns(double *z, uint32_t n, uint32_t p, bool *flips)
{
    for (uint32_t r = 0; r < p; r++) {
        double best = 0.0;
        uint32_t at = 0;
        for (uint32_t i = 0; i < n; i++)
            if (fabs(z[(size_t)i * p + r]) > best) {
                best = fabs(z[(size_t)i * p + r]);
                at = i;
            }
        flips[r] = z[(size_t)at * p + r] < 0;
        if (flips[r])
            for (uint32_t i = 0; i < n; i++)
                z[(size_t)i * p + r] = -z[(size_t)i * p + r];
    }
}

/* In-place dense Cholesky a = L Lᵀ (n × n row-major, L in the lower triangle). */
static bool dense_cholesky(double *a, uint32_t n)
{
    for (uint32_t j = 0; j < n; j++) {
        double d = a[(size_t)j * n + j];
        for (uint32_t l = 0; l < j; l++)
            d -= a[(size_t)j * n + l] * a[(size_t)j * n + l];
        if (!(d > 0) || !isfinite(d))
            return false;
        d = sqrt(d);
        a[(size_t)j * n + j] = d;
        for (uint32_t i = j + 1; i < n; i++) {
            double s = a[(size_t)i * n + j];
            for (uint32_t l = 0; l < j; l++)
                s -= a[(size_t)i * n + l] * a[(size_t)j * n + l];
            a[(size_t)i * n + j] = s / d;
        }
    }
    return true;
}

/* x (n) := L⁻¹ x */
static void lower_solve(const double *l, uint32_t n, double *x)
{
    for (uint32_t i = 0; i < n; i++) {
        double s = x[i];
        for (uint32_t j = 0; j < i; j++)
            s -= l[(size_t)i * n + j] * x[j];
        x[i] = s / l[(size_t)i * n + i];
    }
}

/* x (n) := L⁻ᵀ x */
static void upper_solve(const double *l, uint32_t n, double *x)
{
    for (uint32_t i = n; i-- > 0;) {
        double s = x[i];
        for (uint32_t j = i + 1; j < n; j++)
            s -= l[(size_t)j * n + i] * x[j];
        x[i] = s / l[(size_t)i * n + i];
    }
}

/* The training context: what the method steps share. */
typedef struct train_ctx {
    affect_fda *f;
    const affect_fda_config *cfg;
    double *cc;  /* n × h centred coefficients */
    double *w;   /* n × h: C̃ (M ⊗ I) */
    double *k;   /* n × n Gram of the centred functions (kept intact) */
    double *v;   /* n × n: eigenvector r (descending order) at v + r n, signs fixed */
    double *lam; /* n eigenvalues of K, descending */
    double *q;   /* n × R FPCA scores */
} train_ctx;

/* Axes of a linear method whose training coordinates are K g_r: axis_r = Wᵀ g_r. g: p × n. */
static void axes_from_dual(train_ctx *t, const double *g, uint32_t p)
{
    affect_fda *f = t->f;
    AFFECT_BLAS(cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, (int)p, (int)f->h, (int)f->n,
                            1.0, g, (int)f->n, t->w, (int)f->h, 0.0, f->axes, (int)f->h));
}

static affect_status fit_fpca(train_ctx *t, affect_error *err)
{
    affect_fda *f = t->f;
    uint32_t n = f->n, p = t->cfg->dims < f->R ? t->cfg->dims : f->R;
    f->p = p;
    f->eig = affect_malloc_array(p, sizeof *f->eig);
    f->explained = affect_malloc_array(p, sizeof *f->explained);
    f->train_z = affect_malloc_array((size_t)n * p, sizeof *f->train_z);
    f->axes = affect_malloc_array((size_t)p * f->h, sizeof *f->axes);
    double *g = affect_malloc_array((size_t)p * n, sizeof *g);
    if (!f->eig || !f->explained || !f->train_z || !f->axes || !g) {
        affect_free(g);
        return affect_nomem(err);
    }
    double sum = 0.0;
    for (uint32_t r = 0; r < f->R; r++)
        sum += f->fpca_eig[r];
    for (uint32_t r = 0; r < p; r++) {
        f->eig[r] = f->fpca_eig[r];
        f->explained[r] = f->fpca_eig[r] / sum;
        for (uint32_t i = 0; i < n; i++) {
            f->train_z[(size_t)i * p + r] = t->q[(size_t)i * f->R + r];
            g[(size_t)r * n + i] = t->v[(size_t)r * n + i] / sqrt(t->lam[r]);
        }
    }
    axes_from_dual(t, g, p);
    affect_free(g);
    return AFFECT_OK;
}

static affect_status fit_fspca(train_ctx *t, const uint32_t *y, affect_error *err)
{
    affect_fda *f = t->f;
    uint32_t n = f->n;
    affect_spca *s = NULL;
    affect_status st = affect_spca_fit_dual(t->k, n, f->h, y, f->c, t->cfg->kernel, t->cfg->sigma,
                                            t->cfg->dims, &s, err);
    if (st)
        return st;
    uint32_t p = affect_spca_dims(s);
    f->p = p;
    f->eig = affect_malloc_array(p, sizeof *f->eig);
    f->explained = affect_malloc_array(p, sizeof *f->explained);
    f->train_z = affect_malloc_array((size_t)n * p, sizeof *f->train_z);
    f->axes = affect_malloc_array((size_t)p * f->h, sizeof *f->axes);
    if (!f->eig || !f->explained || !f->train_z || !f->axes) {
        affect_spca_free(s);
        return affect_nomem(err);
    }
    affect_spca_dual_embed(s, t->k, n, f->train_z);
    affect_spca_add_rows(s, t->w, f->h, 0);
    affect_spca_finish(s, f->train_z, n);
    memcpy(f->axes, affect_spca_axes(s), (size_t)p * f->h * sizeof *f->axes);
    memcpy(f->eig, affect_spca_eigenvalues(s), p * sizeof *f->eig);
    affect_spca_free(s);
    for (uint32_t r = 0; r < p; r++) {
        double mean = 0.0, ss = 0.0;
        for (uint32_t i = 0; i < n; i++)
            mean += f->train_z[(size_t)i * p + r];
        mean /= n;
        for (uint32_t i = 0; i < n; i++) {
            double d = f->train_z[(size_t)i * p + r] - mean;
            ss += d * d;
        }
        f->explained[r] = f->total_var > 0 ? ss / (n - 1) / f->total_var : 0.0;
    }
    return AFFECT_OK;
}

static affect_status fit_ffda(train_ctx *t, const uint32_t *y, affect_error *err)
{
    affect_fda *f = t->f;
    uint32_t n = f->n, R = f->R, c = f->c;
    size_t RR = (size_t)R * R;
    double *sw = affect_calloc(RR, sizeof *sw), *sb = affect_calloc(RR, sizeof *sb);
    double *mu = affect_calloc((size_t)c * R, sizeof *mu);
    double *tm = affect_malloc_array(RR, sizeof *tm);
    double *ev = affect_malloc_array(R, sizeof *ev), *ez = affect_malloc_array(RR, sizeof *ez);
    uint32_t *cnt = affect_calloc(c, sizeof *cnt);
    double *g = NULL;
    affect_status st = AFFECT_OK;
    if (!sw || !sb || !mu || !tm || !ev || !ez || !cnt) {
        st = affect_nomem(err);
        goto done;
    }
    for (uint32_t i = 0; i < n; i++) {
        cnt[y[i]]++;
        for (uint32_t r = 0; r < R; r++)
            mu[(size_t)y[i] * R + r] += t->q[(size_t)i * R + r];
    }
    for (uint32_t k = 0; k < c; k++)
        for (uint32_t r = 0; r < R; r++)
            mu[(size_t)k * R + r] /= cnt[k];
    for (uint32_t i = 0; i < n; i++) {
        const double *qi = t->q + (size_t)i * R, *mi = mu + (size_t)y[i] * R;
        for (uint32_t a = 0; a < R; a++)
            for (uint32_t b = 0; b <= a; b++)
                sw[(size_t)a * R + b] += (qi[a] - mi[a]) * (qi[b] - mi[b]);
    }
    for (uint32_t k = 0; k < c; k++) {
        const double *mk = mu + (size_t)k * R;
        for (uint32_t a = 0; a < R; a++)
            for (uint32_t b = 0; b <= a; b++)
                sb[(size_t)a * R + b] += cnt[k] * mk[a] * mk[b];
    }
    double total = 0.0; /* tr of the total scatter = Σ eigenvalues of K */
    for (uint32_t r = 0; r < R; r++)
        total += t->lam[r];
    for (uint32_t a = 0; a < R; a++) {
        sw[(size_t)a * R + a] += t->cfg->ffda_reg * total / R;
        for (uint32_t b = 0; b < a; b++) {
            sw[(size_t)b * R + a] = sw[(size_t)a * R + b];
            sb[(size_t)b * R + a] = sb[(size_t)a * R + b];
        }
    }
    if (!dense_cholesky(sw, R)) {
        st = affect_fail(err, AFFECT_ERR_INVALID,
                         "the within-class scatter is singular (every "
                         "class is one point in %u dimensions): give a positive ffda_reg",
                         R);
        goto done;
    }
    /* tm = L⁻¹ S_b L⁻ᵀ: columns of S_b through L⁻¹, then the rows of the result */
    for (uint32_t a = 0; a < R; a++) { /* row a of X = L⁻¹ S_b (S_b symmetric: column a) */
        for (uint32_t b = 0; b < R; b++)
            ev[b] = sb[(size_t)b * R + a];
        lower_solve(sw, R, ev);
        for (uint32_t b = 0; b < R; b++)
            tm[(size_t)b * R + a] = ev[b]; /* X column a */
    }
    for (uint32_t b = 0; b < R; b++) { /* (L⁻¹ Xᵀ)ᵀ: row b of X through L⁻¹ */
        memcpy(ev, tm + (size_t)b * R, R * sizeof *ev);
        lower_solve(sw, R, ev);
        memcpy(sb + (size_t)b * R, ev, R * sizeof *ev); /* sb := Y row b = T column b */
    }
    for (uint32_t a = 0; a < R; a++)
        for (uint32_t b = 0; b < R; b++)
            tm[(size_t)a * R + b] = 0.5 * (sb[(size_t)a * R + b] + sb[(size_t)b * R + a]);
    if ((st = sym_eig(tm, R, ev, ez, err)) != AFFECT_OK)
        goto done;
    double lmax = ev[R - 1], sum = 0.0;
    for (uint32_t r = 0; r < R; r++)
        if (ev[r] > 0)
            sum += ev[r];
    if (!(lmax > 0)) {
        st = affect_fail(err, AFFECT_ERR_INVALID, "the class means are equal: no discriminant");
        goto done;
    }
    uint32_t p = 0;
    while (p < t->cfg->dims && p < c - 1 && p < R && ev[R - 1 - p] > AFFECT_FDA_RANK_TOL * lmax)
        p++;
    f->p = p;
    f->eig = affect_malloc_array(p, sizeof *f->eig);
    f->explained = affect_malloc_array(p, sizeof *f->explained);
    f->train_z = affect_malloc_array((size_t)n * p, sizeof *f->train_z);
    f->axes = affect_malloc_array((size_t)p * f->h, sizeof *f->axes);
    g = affect_calloc((size_t)p * n, sizeof *g);
    if (!f->eig || !f->explained || !f->train_z || !f->axes || !g) {
        st = affect_nomem(err);
        goto done;
    }
    for (uint32_t r = 0; r < p; r++) {
        double *a = ez + (size_t)(R - 1 - r) * R; /* eigenvector, then a = L⁻ᵀ w */
        upper_solve(sw, R, a);
        f->eig[r] = ev[R - 1 - r];
        f->explained[r] = ev[R - 1 - r] / sum;
        for (uint32_t i = 0; i < n; i++)
            f->train_z[(size_t)i * p + r] = dot(t->q + (size_t)i * R, a, R);
    }
    bool flips[AFFECT_FDA_MAX_DIMS];
    orient_columns(f->train_z, n, p, flips);
    for (uint32_t r = 0; r < p; r++) {
        const double *a = ez + (size_t)(R - 1 - r) * R;
        double sign = flips[r] ? -1.0 : 1.0;
        /* axis = Σ_s a_s b_s with b_s = Wᵀ v_s / √λ_s: g = Σ_s a_s v_s / √λ_s */
        for (uint32_t s = 0; s < R; s++) {
            double coef = sign * a[s] / sqrt(t->lam[s]);
            for (uint32_t i = 0; i < n; i++)
                g[(size_t)r * n + i] += coef * t->v[(size_t)s * n + i];
        }
    }
    axes_from_dual(t, g, p);
done:
    affect_free(sw);
    affect_free(sb);
    affect_free(mu);
    affect_free(tm);
    affect_free(ev);
    affect_free(ez);
    affect_free(cnt);
    affect_free(g);
    return st;
}

/* Indices of the k smallest of d (n values, skipping skip unless it is UINT32_MAX), ties to
 * the lower index, into out (k ≤ number of candidates). */
static void k_smallest(const double *d, uint32_t n, uint32_t skip, uint32_t k, uint32_t *out)
{
    for (uint32_t s = 0; s < k; s++) {
        uint32_t best = UINT32_MAX;
        for (uint32_t j = 0; j < n; j++) {
            if (j == skip)
                continue;
            bool taken = false;
            for (uint32_t u = 0; u < s && !taken; u++)
                taken = out[u] == j;
            if (!taken && (best == UINT32_MAX || d[j] < d[best]))
                best = j;
        }
        out[s] = best;
    }
}

/* Marks in in[] every motion reachable from the motions already marked through the finite
 * entries of geo (n × n), breadth first; queue holds n entries. */
static void reach(const double *geo, uint32_t n, unsigned char *in, uint32_t *queue)
{
    uint32_t head = 0, tail = 0;
    for (uint32_t i = 0; i < n; i++)
        if (in[i])
            queue[tail++] = i;
    while (head < tail) {
        uint32_t i = queue[head++];
        const double *row = geo + (size_t)i * n;
        for (uint32_t j = 0; j < n; j++)
            if (!in[j] && isfinite(row[j])) {
                in[j] = 1;
                queue[tail++] = j;
            }
    }
}

/* Joins the components of the neighbour graph (the finite entries of geo) into one: while some
 * motion cannot be reached from motion 0, the shortest distance of d0 between a motion reached
 * and one that is not (ties to the lowest pair) becomes an edge of geo — a minimum spanning tree
 * over the components, as scikit-learn's Isomap joins them. in and queue hold n entries. */
static affect_status join_components(double *geo, const double *d0, uint32_t n, unsigned char *in,
                                     uint32_t *queue, affect_monitor *mon, affect_error *err)
{
    memset(in, 0, n);
    in[0] = 1;
    for (;;) {
        reach(geo, n, in, queue);
        uint32_t bi = UINT32_MAX, bj = 0;
        for (uint32_t i = 0; i < n; i++) {
            if (!in[i])
                continue;
            const double *row = d0 + (size_t)i * n;
            for (uint32_t j = 0; j < n; j++)
                if (!in[j] && (bi == UINT32_MAX || row[j] < d0[(size_t)bi * n + bj])) {
                    bi = i;
                    bj = j;
                }
        }
        if (bi == UINT32_MAX)
            return AFFECT_OK;
        geo[(size_t)bi * n + bj] = geo[(size_t)bj * n + bi] = d0[(size_t)bi * n + bj];
        affect_status st = affect_monitor_check(mon, err);
        if (st)
            return st;
    }
}

static affect_status fit_isomap(train_ctx *t, affect_error *err)
{
    affect_fda *f = t->f;
    uint32_t n = f->n, kk = t->cfg->isomap_k < n - 1 ? t->cfg->isomap_k : n - 1;
    size_t nn = (size_t)n * n;
    double *d0 = affect_malloc_array(nn, sizeof *d0), *bm = affect_malloc_array(nn, sizeof *bm);
    double *ev = affect_malloc_array(n, sizeof *ev), *ez = affect_malloc_array(nn, sizeof *ez);
    uint32_t *nb = affect_malloc_array(kk, sizeof *nb),
             *queue = affect_malloc_array(n, sizeof *queue);
    unsigned char *in = affect_malloc(n);
    affect_status st = AFFECT_OK;
    f->geo = affect_malloc_array(nn, sizeof *f->geo);
    f->d2mean = affect_malloc_array(n, sizeof *f->d2mean);
    if (!d0 || !bm || !ev || !ez || !nb || !queue || !in || !f->geo || !f->d2mean) {
        st = affect_nomem(err);
        goto done;
    }
    for (uint32_t i = 0; i < n; i++)
        for (uint32_t j = 0; j < n; j++) {
            double s =
                t->k[(size_t)i * n + i] + t->k[(size_t)j * n + j] - 2.0 * t->k[(size_t)i * n + j];
            d0[(size_t)i * n + j] = i == j ? 0.0 : sqrt(s > 0 ? s : 0.0);
        }
    for (size_t i = 0; i < nn; i++)
        f->geo[i] = INFINITY;
    for (uint32_t i = 0; i < n; i++) {
        f->geo[(size_t)i * n + i] = 0.0;
        k_smallest(d0 + (size_t)i * n, n, i, kk, nb);
        for (uint32_t s = 0; s < kk; s++) {
            uint32_t j = nb[s];
            f->geo[(size_t)i * n + j] = f->geo[(size_t)j * n + i] = d0[(size_t)i * n + j];
        }
    }
    if ((st = join_components(f->geo, d0, n, in, queue, t->cfg->monitor, err)) != AFFECT_OK)
        goto done;
    for (uint32_t l = 0; l < n; l++) {
        if ((st = affect_monitor_check(t->cfg->monitor, err)) != AFFECT_OK)
            goto done;
        for (uint32_t i = 0; i < n; i++) {
            double dil = f->geo[(size_t)i * n + l];
            if (!isfinite(dil))
                continue;
            for (uint32_t j = 0; j < n; j++) {
                double v = dil + f->geo[(size_t)l * n + j];
                if (v < f->geo[(size_t)i * n + j])
                    f->geo[(size_t)i * n + j] = v;
            }
        }
    }
    /* B = −½ H D² H */
    double all = 0.0;
    for (uint32_t j = 0; j < n; j++) {
        double s = 0.0;
        for (uint32_t i = 0; i < n; i++) {
            double d = f->geo[(size_t)i * n + j];
            s += d * d;
        }
        f->d2mean[j] = s / n;
        all += s;
    }
    all /= (double)nn;
    for (uint32_t i = 0; i < n; i++)
        for (uint32_t j = 0; j < n; j++) {
            double d = f->geo[(size_t)i * n + j];
            bm[(size_t)i * n + j] = -0.5 * (d * d - f->d2mean[i] - f->d2mean[j] + all);
        }
    for (uint32_t i = 0; i < n; i++) /* symmetric up to rounding: make it exactly so */
        for (uint32_t j = 0; j < i; j++)
            bm[(size_t)i * n + j] = bm[(size_t)j * n + i] =
                0.5 * (bm[(size_t)i * n + j] + bm[(size_t)j * n + i]);
    if ((st = sym_eig(bm, n, ev, ez, err)) != AFFECT_OK)
        goto done;
    double lmax = ev[n - 1], sum = 0.0;
    for (uint32_t r = 0; r < n; r++)
        if (ev[r] > 0)
            sum += ev[r];
    uint32_t p = 0;
    while (p < t->cfg->dims && p < n && lmax > 0 && ev[n - 1 - p] > AFFECT_FDA_RANK_TOL * lmax)
        p++;
    if (p == 0) {
        st = affect_fail(err, AFFECT_ERR_INVALID,
                         "the training functions are all equal (no "
                         "variance)");
        goto done;
    }
    f->p = p;
    f->eig = affect_malloc_array(p, sizeof *f->eig);
    f->explained = affect_malloc_array(p, sizeof *f->explained);
    f->train_z = affect_malloc_array((size_t)n * p, sizeof *f->train_z);
    f->mds_v = affect_malloc_array((size_t)n * p, sizeof *f->mds_v);
    f->train_c = affect_malloc_array((size_t)n * f->h, sizeof *f->train_c);
    if (!f->eig || !f->explained || !f->train_z || !f->mds_v || !f->train_c) {
        st = affect_nomem(err);
        goto done;
    }
    for (uint32_t r = 0; r < p; r++) {
        double l = ev[n - 1 - r];
        f->eig[r] = l;
        f->explained[r] = l / sum;
        for (uint32_t i = 0; i < n; i++) {
            f->mds_v[(size_t)i * p + r] = ez[(size_t)(n - 1 - r) * n + i];
            f->train_z[(size_t)i * p + r] = sqrt(l) * f->mds_v[(size_t)i * p + r];
        }
    }
    bool flips[AFFECT_FDA_MAX_DIMS];
    orient_columns(f->train_z, n, p, flips);
    for (uint32_t r = 0; r < p; r++)
        if (flips[r])
            for (uint32_t i = 0; i < n; i++)
                f->mds_v[(size_t)i * p + r] = -f->mds_v[(size_t)i * p + r];
    memcpy(f->train_c, t->cc, (size_t)n * f->h * sizeof *f->train_c);
done:
    affect_free(d0);
    affect_free(bm);
    affect_free(ev);
    affect_free(ez);
    affect_free(nb);
    affect_free(queue);
    affect_free(in);
    return st;
}

static affect_status check_train(const affect_fda_config *cfg, const affect_features *feat,
                                 const affect_hmm_seq *seqs, uint32_t n, uint32_t m,
                                 const uint32_t *y, const char *const *classes, uint32_t c,
                                 affect_error *err)
{
    const char *msg = affect_fda_config_check(cfg);
    if (msg)
        return affect_fail(err, AFFECT_ERR_INVALID, "%s", msg);
    if (c < 2)
        return affect_fail(err, AFFECT_ERR_INVALID, "need at least 2 classes");
    if (n < 3)
        return affect_fail(err, AFFECT_ERR_INVALID, "need at least 3 motions");
    if (m < 1 || m > AFFECT_HMM_MAX_DIM)
        return affect_fail(err, AFFECT_ERR_INVALID, "m must be from 1 to 4096");
    if (feat && affect_features_dim(feat) != m)
        return affect_fail(err, AFFECT_ERR_INVALID, "m is %u but the feature definition gives %u",
                           m, affect_features_dim(feat));
    size_t h, cells;
    if (!affect_mul_size(cfg->n_basis, m, &h) || h > INT32_MAX)
        return affect_fail(err, AFFECT_ERR_RANGE,
                           "%u basis functions x %u coordinates exceed "
                           "the BLAS limit",
                           cfg->n_basis, m);
    if (n > INT32_MAX || !affect_mul_size(n, h > n ? h : n, &cells) ||
        !affect_mul_size(cells, sizeof(double), &cells))
        return affect_fail(err, AFFECT_ERR_RANGE, "%u motions x %zu coefficients are too many", n,
                           h);
    for (uint32_t k = 0; k < c; k++) {
        if (!classes || !classes[k])
            return affect_fail(err, AFFECT_ERR_INVALID, "class %u has no name", k);
        if (affect_utf8_check(err, AFFECT_ERR_INVALID, classes[k], strlen(classes[k]),
                              "class %u's name", k))
            return AFFECT_ERR_INVALID;
    }
    for (uint32_t i = 0; i < n; i++) {
        if (y[i] >= c)
            return affect_fail(err, AFFECT_ERR_INVALID,
                               "motion %u: label %u is out of range "
                               "(%u classes)",
                               i, y[i], c);
        if (seqs[i].n_frames < 1 || !seqs[i].x)
            return affect_fail(err, AFFECT_ERR_INVALID, "motion %u has no frames", i);
    }
    for (uint32_t k = 0; k < c; k++) {
        bool seen = false;
        for (uint32_t i = 0; i < n && !seen; i++)
            seen = y[i] == k;
        if (!seen)
            return affect_fail(err, AFFECT_ERR_INVALID, "class %u (\"%s\") has no motion", k,
                               classes[k]);
    }
    return AFFECT_OK;
}

static affect_status copy_features(const affect_features *feat, affect_features **out,
                                   affect_error *err)
{
    *out = NULL;
    if (!feat)
        return AFFECT_OK;
    size_t size;
    if (!affect_features_encoded_size(feat, &size))
        return affect_fail(err, AFFECT_ERR_RANGE, "the feature definition is too large");
    unsigned char *buf = affect_malloc(size);
    if (!buf)
        return affect_nomem(err);
    affect_features_encode_into(feat, buf);
    affect_status st = affect_features_decode(buf, size, out, err);
    affect_free(buf);
    return st;
}

/* 0. Landmark registration: the template into f, each training motion's registered times
 * into *times (*off: where motion i's begin). */
static affect_status register_landmarks(affect_fda *f, const affect_hmm_seq *seqs, uint32_t n,
                                        uint32_t m, const uint32_t *y, uint32_t c,
                                        const affect_fda_config *cfg, double **times, size_t **off,
                                        affect_error *err)
{
    size_t total = 0;
    if (!(*off = affect_malloc_array(n, sizeof **off)))
        return affect_nomem(err);
    for (uint32_t i = 0; i < n; i++) {
        (*off)[i] = total;
        if (total > SIZE_MAX / sizeof(double) - seqs[i].n_frames)
            return affect_nomem(err);
        total += seqs[i].n_frames;
    }
    if (!(*times = affect_malloc_array(total ? total : 1, sizeof **times)))
        return affect_nomem(err);
    return build_template(f, seqs, n, m, y, c, cfg, *times, *off, err);
}

/* 2. Every training motion's B-spline coefficients (times: registered, or NULL), their mean
 * (f->mean), the centred coefficients t->cc and t->w = C̃ (M ⊗ I); the classes' mean frame
 * counts. */
static affect_status fit_coefficients(train_ctx *t, const affect_hmm_seq *seqs, const uint32_t *y,
                                      const double *times, const size_t *off, affect_error *err)
{
    affect_fda *f = t->f;
    const affect_fda_config *cfg = t->cfg;
    uint32_t n = f->n, m = f->m, c = f->c;
    size_t h = f->h, G = f->b.n, kb = f->b.order;
    affect_status st = AFFECT_OK;
    t->cc = affect_malloc_array((size_t)n * h, sizeof *t->cc);
    t->w = affect_malloc_array((size_t)n * h, sizeof *t->w);
    f->mean = affect_calloc(h, sizeof *f->mean);
    double *fit_work = affect_malloc_array(2 * G * kb + G, sizeof *fit_work);
    double *num = affect_calloc(c, sizeof *num);
    if (!t->cc || !t->w || !f->mean || !fit_work || !num) {
        st = affect_nomem(err);
        goto done;
    }
    for (uint32_t i = 0; i < n; i++) {
        if ((st = affect_monitor_check(cfg->monitor, err)) != AFFECT_OK)
            goto done;
        affect_monitor_report(cfg->monitor, "B-spline fits", i, n);
        st = affect_bspline_fit(&f->b, f->rband, times ? times + off[i] : NULL, seqs[i].x,
                                seqs[i].n_frames, m, f->cfg.lambda, t->cc + (size_t)i * h, fit_work,
                                err);
        if (st) {
            affect_prefix(err, "motion %u", i);
            goto done;
        }
    }
    for (uint32_t i = 0; i < n; i++)
        for (size_t j = 0; j < h; j++)
            f->mean[j] += t->cc[(size_t)i * h + j];
    for (size_t j = 0; j < h; j++)
        f->mean[j] /= n;
    for (uint32_t i = 0; i < n; i++) {
        for (size_t j = 0; j < h; j++)
            t->cc[(size_t)i * h + j] -= f->mean[j];
        affect_band_mul(f->mband, (uint32_t)G, (uint32_t)kb, t->cc + (size_t)i * h, m,
                        t->w + (size_t)i * h);
    }
    for (uint32_t i = 0; i < n; i++) {
        f->frames[y[i]] += seqs[i].n_frames;
        num[y[i]] += 1.0;
    }
    for (uint32_t k = 0; k < c; k++)
        f->frames[k] /= num[k];
done:
    affect_free(fit_work);
    affect_free(num);
    return st;
}

/* 3. FPCA: the Gram matrix K = C̃ Wᵀ (t->k), its eigendecomposition (t->lam, t->v), the total
 * variance, the rank R, the covariance eigenvalues and the scores t->q (n × R, each column's
 * sign fixed by orient_columns, t->v's with it). */
static affect_status fpca_space(train_ctx *t, affect_error *err)
{
    affect_fda *f = t->f;
    uint32_t n = f->n, m = f->m;
    size_t h = f->h, G = f->b.n, kb = f->b.order;
    affect_status st = AFFECT_OK;
    t->k = affect_malloc_array((size_t)n * n, sizeof *t->k);
    t->v = affect_malloc_array((size_t)n * n, sizeof *t->v);
    t->lam = affect_malloc_array(n, sizeof *t->lam);
    double *kw = affect_malloc_array((size_t)n * n, sizeof *kw);
    double *asc = affect_malloc_array(n, sizeof *asc);
    double *zv = affect_malloc_array((size_t)n * n, sizeof *zv);
    double *mw = affect_malloc_array(h, sizeof *mw);
    bool *flips = NULL;
    if (!t->k || !t->v || !t->lam || !kw || !asc || !zv || !mw)
        goto nomem;
    AFFECT_BLAS(cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasTrans, (int)n, (int)n, (int)h, 1.0,
                            t->cc, (int)h, t->w, (int)h, 0.0, t->k, (int)n));
    double trace = 0.0;
    for (uint32_t i = 0; i < n; i++) {
        trace += t->k[(size_t)i * n + i];
        for (uint32_t j = 0; j < i; j++)
            t->k[(size_t)i * n + j] = t->k[(size_t)j * n + i] =
                0.5 * (t->k[(size_t)i * n + j] + t->k[(size_t)j * n + i]);
    }
    f->total_var = trace / (n - 1);
    if (!isfinite(trace)) {
        st = affect_fail(err, AFFECT_ERR_RANGE,
                         "the data are too large: the Gram matrix "
                         "overflows");
        goto done;
    }
    memcpy(kw, t->k, (size_t)n * n * sizeof *kw);
    if ((st = sym_eig(kw, n, asc, zv, err)) != AFFECT_OK)
        goto done;
    for (uint32_t r = 0; r < n; r++) {
        t->lam[r] = asc[n - 1 - r];
        memcpy(t->v + (size_t)r * n, zv + (size_t)(n - 1 - r) * n, n * sizeof *zv);
    }
    double energy = trace; /* Σ ‖x_i‖² = tr K + n ‖x̄‖² */
    affect_band_mul(f->mband, (uint32_t)G, (uint32_t)kb, f->mean, m, mw);
    energy += n * dot(f->mean, mw, h);
    if (!(t->lam[0] > 0) || !(trace > AFFECT_FDA_NOVAR_TOL * energy)) {
        st = affect_fail(err, AFFECT_ERR_INVALID,
                         "the training functions are all equal (no "
                         "variance)");
        goto done;
    }
    uint32_t R = 0;
    while (R < n - 1 && t->lam[R] > AFFECT_FDA_RANK_TOL * t->lam[0])
        R++;
    f->R = R;
    f->fpca_eig = affect_malloc_array(R, sizeof *f->fpca_eig);
    t->q = affect_malloc_array((size_t)n * R, sizeof *t->q);
    flips = affect_malloc_array(R, sizeof *flips);
    if (!f->fpca_eig || !t->q || !flips)
        goto nomem;
    for (uint32_t r = 0; r < R; r++) {
        f->fpca_eig[r] = t->lam[r] / (n - 1);
        for (uint32_t i = 0; i < n; i++)
            t->q[(size_t)i * R + r] = sqrt(t->lam[r]) * t->v[(size_t)r * n + i];
    }
    orient_columns(t->q, n, R, flips);
    for (uint32_t r = 0; r < R; r++)
        if (flips[r])
            for (uint32_t i = 0; i < n; i++)
                t->v[(size_t)r * n + i] = -t->v[(size_t)r * n + i];
    goto done;
nomem:
    st = affect_nomem(err);
done:
    affect_free(kw);
    affect_free(asc);
    affect_free(zv);
    affect_free(mw);
    affect_free(flips);
    return st;
}

/* The prototypes' space: the first P FPCA eigenfunctions and the class centroids of the scores
 * on them, or (proto_dims 0) the class means of the centred coefficients. */
static affect_status fit_prototypes(train_ctx *t, const uint32_t *y, affect_error *err)
{
    affect_fda *f = t->f;
    uint32_t n = f->n, c = f->c, R = f->R, P;
    size_t h = f->h;
    f->P = P = t->cfg->proto_dims < R ? t->cfg->proto_dims : R; /* 0: the class means instead */
    double *g = NULL, *num = affect_calloc(c, sizeof *num);
    if (P > 0) {
        f->efun = affect_malloc_array((size_t)P * h, sizeof *f->efun);
        f->centroid = affect_calloc((size_t)c * P, sizeof *f->centroid);
        g = affect_malloc_array((size_t)P * n, sizeof *g);
    } else {
        f->cmean = affect_calloc((size_t)c * h, sizeof *f->cmean);
    }
    if (!num || (P && (!f->efun || !f->centroid || !g)) || (!P && !f->cmean)) {
        affect_free(g);
        affect_free(num);
        return affect_nomem(err);
    }
    if (P > 0) {
        for (uint32_t r = 0; r < P; r++)
            for (uint32_t i = 0; i < n; i++)
                g[(size_t)r * n + i] = t->v[(size_t)r * n + i] / sqrt(t->lam[r]);
        AFFECT_BLAS(cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, (int)P, (int)h, (int)n,
                                1.0, g, (int)n, t->cc, (int)h, 0.0, f->efun, (int)h));
    }
    for (uint32_t i = 0; i < n; i++) {
        num[y[i]] += 1.0;
        for (uint32_t r = 0; r < P; r++)
            f->centroid[(size_t)y[i] * P + r] += t->q[(size_t)i * R + r];
    }
    for (uint32_t k = 0; k < c; k++)
        for (uint32_t r = 0; r < P; r++)
            f->centroid[(size_t)k * P + r] /= num[k];
    if (f->cmean) { /* every component's centroid mapped back: the class's mean */
        for (uint32_t i = 0; i < n; i++)
            for (size_t j = 0; j < h; j++)
                f->cmean[(size_t)y[i] * h + j] += t->cc[(size_t)i * h + j];
        for (uint32_t k = 0; k < c; k++)
            for (size_t j = 0; j < h; j++)
                f->cmean[(size_t)k * h + j] /= num[k];
    }
    affect_free(g);
    affect_free(num);
    return AFFECT_OK;
}

affect_status affect_fda_train(const affect_fda_config *cfg, const affect_features *feat,
                               const affect_hmm_seq *seqs, uint32_t n, uint32_t m,
                               const uint32_t *y, const char *const *classes, uint32_t c,
                               affect_fda **out, affect_error *err)
{
    *out = NULL;
    affect_status st = check_train(cfg, feat, seqs, n, m, y, classes, c, err);
    if (st)
        return st;
    train_ctx t;
    memset(&t, 0, sizeof t);
    double *times = NULL;
    size_t *off = NULL;
    affect_fda *f = affect_calloc(1, sizeof *f);
    if (!f)
        return affect_nomem(err);
    f->cfg = *cfg;
    f->cfg.monitor = NULL;
    f->b.order = cfg->order;
    f->b.n = cfg->n_basis;
    f->m = m;
    f->n = n;
    f->c = c;
    f->h = (size_t)cfg->n_basis * m;
    t.f = f;
    t.cfg = cfg;
    if ((st = make_bands(f, err)) != AFFECT_OK || (st = copy_features(feat, &f->feat, err)))
        goto fail;
    f->classes = affect_calloc(c, sizeof *f->classes);
    f->y = affect_malloc_array(n, sizeof *f->y);
    f->frames = affect_calloc(c, sizeof *f->frames);
    if (!f->classes || !f->y || !f->frames) {
        st = affect_nomem(err);
        goto fail;
    }
    for (uint32_t k = 0; k < c; k++)
        if (!(f->classes[k] = affect_strndup(classes[k], strlen(classes[k])))) {
            st = affect_nomem(err);
            goto fail;
        }
    memcpy(f->y, y, n * sizeof *y);
    /* 0. landmark registration; 1. λ; 2. coefficients; 3. FPCA and the prototypes' space */
    if ((cfg->alignment == AFFECT_FDA_ALIGN_LANDMARKS &&
         (st = register_landmarks(f, seqs, n, m, y, c, cfg, &times, &off, err)) != AFFECT_OK) ||
        (cfg->gcv && (st = choose_lambda(cfg, &f->b, f->rband, seqs, n, m, times, off,
                                         &f->cfg.lambda, err)) != AFFECT_OK))
        goto fail;
    f->cfg.gcv = cfg->gcv;
    if ((st = fit_coefficients(&t, seqs, y, times, off, err)) != AFFECT_OK ||
        (st = fpca_space(&t, err)) != AFFECT_OK || (st = fit_prototypes(&t, y, err)) != AFFECT_OK)
        goto fail;
    /* 4. the method */
    switch (cfg->method) {
    case AFFECT_FDA_FPCA:
        st = fit_fpca(&t, err);
        break;
    case AFFECT_FDA_FSPCA:
        st = fit_fspca(&t, y, err);
        break;
    case AFFECT_FDA_FFDA:
        st = fit_ffda(&t, y, err);
        break;
    case AFFECT_FDA_FISOMAP:
        st = fit_isomap(&t, err);
        break;
    }
    if (st == AFFECT_OK)
        st = make_norms(f, err);
    if (st)
        goto fail;
    affect_monitor_report(cfg->monitor, "B-spline fits", n, n);
    *out = f;
    f = NULL;
fail:
    affect_fda_free(f);
    affect_free(times);
    affect_free(off);
    affect_free(t.cc);
    affect_free(t.w);
    affect_free(t.k);
    affect_free(t.v);
    affect_free(t.lam);
    affect_free(t.q);
    return st;
}

/* ---- use ---- */

affect_status affect_fda_coefficients(const affect_fda *f, const double *x, uint32_t T,
                                      double *coef, affect_error *err)
{
    size_t G = f->b.n, kb = f->b.order;
    bool warp = f->cfg.alignment == AFFECT_FDA_ALIGN_LANDMARKS;
    double *work = affect_malloc_array(2 * G * kb + G, sizeof *work);
    double *times = warp ? affect_malloc_array(T ? T : 1, sizeof *times) : NULL;
    if (!work || (warp && !times)) {
        affect_free(work);
        affect_free(times);
        return affect_nomem(err);
    }
    affect_status st = warp ? affect_fda_times(f, x, T, times, err) : AFFECT_OK;
    if (st == AFFECT_OK)
        st = affect_bspline_fit(&f->b, f->rband, times, x, T, f->m, f->cfg.lambda, coef, work, err);
    affect_free(work);
    affect_free(times);
    return st;
}

affect_status affect_fda_embed(const affect_fda *f, const double *x, uint32_t T, double *z,
                               affect_error *err)
{
    size_t h = f->h;
    uint32_t n = f->n, p = f->p;
    bool iso = f->cfg.method == AFFECT_FDA_FISOMAP;
    double *d = affect_malloc_array(iso ? 2 * h + 2 * (size_t)n : h, sizeof *d);
    uint32_t *nb = NULL;
    if (!d)
        return affect_nomem(err);
    affect_status st = affect_fda_coefficients(f, x, T, d, err);
    if (st)
        goto done;
    for (size_t j = 0; j < h; j++)
        d[j] -= f->mean[j];
    if (!iso) {
        for (uint32_t r = 0; r < p; r++)
            z[r] = dot(f->axes + (size_t)r * h, d, h);
        goto done;
    }
    uint32_t kk = f->cfg.isomap_k < n ? f->cfg.isomap_k : n;
    nb = affect_malloc_array(kk, sizeof *nb);
    if (!nb) {
        st = affect_nomem(err);
        goto done;
    }
    double *w = d + h, *e = w + h, *delta = e + n;
    affect_band_mul(f->mband, f->b.n, f->b.order, d, f->m, w);
    double self = dot(d, w, h);
    for (uint32_t j = 0; j < n; j++) {
        double s = self - 2.0 * dot(f->train_c + (size_t)j * h, w, h) + f->train_norm[j];
        e[j] = sqrt(s > 0 ? s : 0.0);
    }
    k_smallest(e, n, UINT32_MAX, kk, nb);
    for (uint32_t j = 0; j < n; j++) {
        double best = INFINITY;
        for (uint32_t s = 0; s < kk; s++) {
            double v = e[nb[s]] + f->geo[(size_t)nb[s] * n + j];
            if (v < best)
                best = v;
        }
        delta[j] = f->d2mean[j] - best * best;
    }
    for (uint32_t r = 0; r < p; r++) {
        double s = 0.0;
        for (uint32_t j = 0; j < n; j++)
            s += f->mds_v[(size_t)j * p + r] * delta[j];
        z[r] = 0.5 * s / sqrt(f->eig[r]);
    }
done:
    for (uint32_t r = 0; st == AFFECT_OK && r < p; r++)
        if (!isfinite(z[r]))
            st = affect_fail(err, AFFECT_ERR_RANGE,
                             "the embedding overflows (coordinate %u is "
                             "not finite)",
                             r);
    affect_free(d);
    affect_free(nb);
    return st;
}

affect_status affect_fda_classify(const affect_fda *f, const double *x, uint32_t T, uint32_t k,
                                  uint32_t *label, uint32_t *votes, affect_error *err)
{
    double z[AFFECT_FDA_MAX_DIMS];
    affect_status st = affect_fda_embed(f, x, T, z, err);
    if (st)
        return st;
    return affect_knn_classify(f->train_z, f->y, f->n, f->p, f->c, z, k, label, votes, err);
}

void affect_fda_prototype_coefs(const affect_fda *f, uint32_t label, double *coef)
{
    memcpy(coef, f->mean, f->h * sizeof *coef);
    if (f->cmean)
        for (size_t j = 0; j < f->h; j++)
            coef[j] += f->cmean[(size_t)label * f->h + j];
    for (uint32_t r = 0; r < f->P; r++) {
        double q = f->centroid[(size_t)label * f->P + r];
        const double *e = f->efun + (size_t)r * f->h;
        for (size_t j = 0; j < f->h; j++)
            coef[j] += q * e[j];
    }
}

affect_status affect_fda_prototype(const affect_fda *f, uint32_t label, affect_motion **out,
                                   affect_error *err)
{
    *out = NULL;
    if (label >= f->c)
        return affect_fail(err, AFFECT_ERR_INVALID, "class %u is out of range (%u classes)", label,
                           f->c);
    if (!f->feat)
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "the model has no feature definition "
                           "(trained on plain data): no prototypes");
    double fr = floor(f->frames[label] + 0.5);
    uint32_t T = fr < 2 ? 2 : fr > 1e6 ? 1000000 : (uint32_t)fr;
    double *coef = affect_malloc_array(f->h, sizeof *coef);
    double *x = affect_malloc_array((size_t)T * f->m, sizeof *x);
    affect_motion *pm = NULL;
    affect_status st = AFFECT_OK;
    if (!coef || !x) {
        st = affect_nomem(err);
        goto done;
    }
    affect_fda_prototype_coefs(f, label, coef);
    affect_bspline_values(&f->b, coef, f->m, NULL, T, x);
    if ((st = affect_features_posture_motion(f->feat, x, T, &pm, err)) != AFFECT_OK)
        goto done;
    bool bones = false; /* observed joints without a parent among them have no bones */
    for (uint32_t j = 0; j < pm->n_joints; j++)
        bones = bones || pm->parents[j] >= 0;
    if (!bones) {
        *out = pm;
        pm = NULL;
        goto done;
    }
    affect_rigid_options ro;
    affect_rigid_options_default(&ro);
    st = affect_motion_rigid(pm, &ro, out, err);
    if (st)
        affect_prefix(err, "making the prototype rigid");
done:
    affect_motion_free(pm);
    affect_free(coef);
    affect_free(x);
    return st;
}

affect_status affect_fda_perturbation(const affect_fda *f, uint32_t r, uint32_t j, double alpha,
                                      uint32_t T, double *mean, double *plus, double *minus,
                                      affect_error *err)
{
    if (!is_linear(f->cfg.method))
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "perturbation plots need a linear method "
                           "(fpca, ffda, fspca), not fisomap");
    if (r >= f->p)
        return affect_fail(err, AFFECT_ERR_INVALID, "axis %u is out of range (%u dimensions)",
                           r + 1, f->p);
    if (j >= f->m)
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "coordinate %u is out of range (%u "
                           "coordinates)",
                           j + 1, f->m);
    if (!isfinite(alpha))
        return affect_fail(err, AFFECT_ERR_INVALID, "alpha must be a finite number");
    if (T < 2)
        return affect_fail(err, AFFECT_ERR_INVALID, "need at least 2 times");
    uint32_t G = f->b.n, k = f->b.order, m = f->m;
    size_t h = f->h;
    double *u = affect_malloc_array((size_t)G * k, sizeof *u);
    double *w = affect_malloc_array(h, sizeof *w);
    double *mc = affect_malloc_array(G, sizeof *mc), *wc = affect_malloc_array(G, sizeof *wc);
    affect_status st = AFFECT_OK;
    if (!u || !w || !mc || !wc) {
        st = affect_nomem(err);
        goto done;
    }
    /* w = M⁻¹ b (block by block), ‖w‖² = bᵀ M⁻¹ b */
    memcpy(u, f->mband, (size_t)G * k * sizeof *u);
    if (!affect_band_cholesky(u, G, k)) {
        st = affect_fail(err, AFFECT_ERR_RANGE, "the Gram matrix of the basis is singular");
        goto done;
    }
    const double *b = f->axes + (size_t)r * h;
    memcpy(w, b, h * sizeof *w);
    affect_band_solve(u, G, k, w, m);
    double norm2 = dot(w, b, h);
    double mu = 0.0, ss = 0.0;
    for (uint32_t i = 0; i < f->n; i++)
        mu += f->train_z[(size_t)i * f->p + r];
    mu /= f->n;
    for (uint32_t i = 0; i < f->n; i++) {
        double d = f->train_z[(size_t)i * f->p + r] - mu;
        ss += d * d;
    }
    double sd = sqrt(ss / (f->n - 1));
    double scale = norm2 > 0 ? alpha * sd / norm2 : 0.0;
    for (uint32_t g = 0; g < G; g++) {
        mc[g] = f->mean[(size_t)g * m + j];
        wc[g] = w[(size_t)g * m + j];
    }
    affect_bspline_values(&f->b, mc, 1, NULL, T, mean);
    affect_bspline_values(&f->b, wc, 1, NULL, T, plus);
    for (uint32_t t = 0; t < T; t++) {
        double d = scale * plus[t];
        plus[t] = mean[t] + d;
        minus[t] = mean[t] - d;
    }
done:
    affect_free(u);
    affect_free(w);
    affect_free(mc);
    affect_free(wc);
    return st;
}

/* ---- accessors ---- */

const affect_fda_config *affect_fda_get_config(const affect_fda *f)
{
    return &f->cfg;
}
uint32_t affect_fda_dims(const affect_fda *f)
{
    return f->p;
}
uint32_t affect_fda_coords(const affect_fda *f)
{
    return f->m;
}
uint32_t affect_fda_train_size(const affect_fda *f)
{
    return f->n;
}
uint32_t affect_fda_classes(const affect_fda *f)
{
    return f->c;
}
const char *affect_fda_class_name(const affect_fda *f, uint32_t k)
{
    return f->classes[k];
}
const affect_features *affect_fda_features(const affect_fda *f)
{
    return f->feat;
}
const double *affect_fda_eigenvalues(const affect_fda *f)
{
    return f->eig;
}
const double *affect_fda_explained(const affect_fda *f)
{
    return f->explained;
}
uint32_t affect_fda_fpca_rank(const affect_fda *f)
{
    return f->R;
}
const double *affect_fda_fpca_eigenvalues(const affect_fda *f)
{
    return f->fpca_eig;
}
double affect_fda_total_variance(const affect_fda *f)
{
    return f->total_var;
}
const double *affect_fda_train_embedding(const affect_fda *f)
{
    return f->train_z;
}
const uint32_t *affect_fda_train_labels(const affect_fda *f)
{
    return f->y;
}
double affect_fda_class_frames(const affect_fda *f, uint32_t k)
{
    return f->frames[k];
}
const double *affect_fda_mean(const affect_fda *f)
{
    return f->mean;
}
const double *affect_fda_eigenfunctions(const affect_fda *f)
{
    return f->efun;
}
uint32_t affect_fda_proto_dims(const affect_fda *f)
{
    return f->P;
}

/* ---- BLOB ---- */

affect_status affect_fda_encode(const affect_fda *f, unsigned char **out, size_t *size,
                                affect_error *err)
{
    *out = NULL;
    *size = 0;
    affect_bw w;
    affect_bw_init(&w);
    const affect_fda_config *cfg = &f->cfg;
    bool lm = cfg->alignment == AFFECT_FDA_ALIGN_LANDMARKS, all = f->cmean != NULL;
    affect_bw_header(&w, AFFECT_FDA_MAGIC,
                     all  ? 3u
                     : lm ? 2u
                          : 1u,
                     (lm ? 1u : 0u) | (all ? 2u : 0u));
    affect_bw_u32(&w, (uint32_t)cfg->method);
    affect_bw_u32(&w, f->b.order);
    affect_bw_u32(&w, f->b.n);
    affect_bw_u32(&w, f->m);
    affect_bw_u32(&w, f->n);
    affect_bw_u32(&w, f->c);
    affect_bw_u32(&w, f->p);
    affect_bw_u32(&w, f->P);
    affect_bw_u32(&w, f->R);
    affect_bw_u32(&w, cfg->isomap_k);
    affect_bw_u32(&w, (uint32_t)cfg->kernel);
    affect_bw_u32(&w, cfg->dims);
    affect_bw_u32(&w, cfg->gcv ? 1u : 0u);
    affect_bw_f64(&w, cfg->lambda);
    affect_bw_f64(&w, cfg->sigma);
    affect_bw_f64(&w, cfg->ffda_reg);
    affect_bw_f64(&w, f->total_var);
    size_t fsize = 0;
    if (f->feat && !affect_features_encoded_size(f->feat, &fsize)) {
        affect_bw_free(&w);
        return affect_fail(err, AFFECT_ERR_RANGE, "the feature definition is too large");
    }
    affect_bw_u32(&w, (uint32_t)fsize);
    if (fsize) {
        unsigned char *buf = affect_malloc(fsize);
        if (!buf) {
            affect_bw_free(&w);
            return affect_nomem(err);
        }
        affect_features_encode_into(f->feat, buf);
        affect_bw_bytes(&w, buf, fsize);
        affect_free(buf);
    }
    for (uint32_t k = 0; k < f->c; k++) {
        size_t len = strlen(f->classes[k]);
        affect_bw_u32(&w, (uint32_t)len);
        affect_bw_bytes(&w, f->classes[k], len);
    }
    size_t h = f->h, n = f->n, p = f->p;
    affect_bw_u32s(&w, f->y, f->n);
    affect_bw_f64s(&w, f->frames, f->c);
    affect_bw_f64s(&w, f->fpca_eig, f->R);
    affect_bw_f64s(&w, f->eig, p);
    affect_bw_f64s(&w, f->explained, p);
    affect_bw_f64s(&w, f->mean, h);
    affect_bw_f64s(&w, f->efun, (size_t)f->P * h);
    affect_bw_f64s(&w, f->centroid, (size_t)f->c * f->P);
    if (all) /* version 3: the class means' centred coefficients */
        affect_bw_f64s(&w, f->cmean, (size_t)f->c * h);
    affect_bw_f64s(&w, f->train_z, n * p);
    if (is_linear(cfg->method)) {
        affect_bw_f64s(&w, f->axes, p * h);
    } else {
        affect_bw_f64s(&w, f->train_c, n * h);
        affect_bw_f64s(&w, f->mds_v, n * p);
        affect_bw_f64s(&w, f->d2mean, n);
        affect_bw_f64s(&w, f->geo, n * n);
    }
    if (lm) { /* version 2: the landmark template */
        affect_bw_u32(&w, f->n_lm);
        for (uint32_t k = 0; k < f->n_lm; k++) {
            affect_bw_f64(&w, f->lm[k].t);
            affect_bw_u32(&w, f->lm[k].type > 0 ? 1u : 0u);
        }
    }
    if (!w.failed)
        affect_bw_checksum(&w, 0);
    if (w.failed) {
        size_t len = w.len;
        affect_bw_free(&w);
        return affect_nomem_of(err, len, 1,
                               "the functional model BLOB beyond its first %zu "
                               "bytes",
                               len);
    }
    *out = w.data;
    *size = w.len;
    return AFFECT_OK;
}

static affect_status truncated(affect_error *err, const affect_br *r, const char *what)
{
    return affect_fail(err, AFFECT_ERR_FORMAT, "truncated in %s (offset %zu)", what, r->off);
}

/* Reads count doubles into a new array (*out), after checking they are present; finite
 * unless allow_inf (geodesic distances are finite too once connected: never allowed). */
static affect_status read_f64s(affect_br *r, size_t count, const char *what, double **out,
                               affect_error *err)
{
    if (!affect_br_has(r, count, 8))
        return truncated(err, r, what);
    size_t at = r->off;
    *out = affect_malloc_array(count ? count : 1, sizeof **out);
    if (!*out)
        return affect_nomem_of(err, count, sizeof **out, "the %s", what);
    affect_br_f64s(r, *out, count);
    for (size_t i = 0; i < count; i++)
        if (!isfinite((*out)[i]))
            return affect_fail(err, AFFECT_ERR_FORMAT, "non-finite value in %s (offset %zu)", what,
                               at + 8 * i);
    return AFFECT_OK;
}

static affect_status out_of_range(affect_error *err, const char *what, uint64_t v, size_t off)
{
    return affect_fail(err, AFFECT_ERR_FORMAT, "%s %llu is out of range (offset %zu)", what,
                       (unsigned long long)v, off);
}

static affect_status decode_head(affect_br *r, affect_fda *f, affect_error *err)
{
    uint32_t version, flags, method, order, G, m, n, c, p, P, R, iso_k, kernel, dims, gcv;
    /* the caller checked the header's length and magic: skip the magic */
    affect_br_u32(r, &version);
    affect_br_u32(r, &version);
    if (affect_check_version(version, AFFECT_FDA_VERSION, NULL, err) != AFFECT_OK)
        return AFFECT_ERR_FORMAT;
    affect_br_u32(r, &flags);
    affect_br_u32(r, &method);
    affect_br_u32(r, &order);
    affect_br_u32(r, &G);
    affect_br_u32(r, &m);
    affect_br_u32(r, &n);
    affect_br_u32(r, &c);
    affect_br_u32(r, &p);
    affect_br_u32(r, &P);
    affect_br_u32(r, &R);
    affect_br_u32(r, &iso_k);
    affect_br_u32(r, &kernel);
    affect_br_u32(r, &dims);
    affect_br_u32(r, &gcv);
    affect_fda_config *cfg = &f->cfg;
    affect_fda_config_default(cfg);
    affect_br_f64(r, &cfg->lambda);
    affect_br_f64(r, &cfg->sigma);
    affect_br_f64(r, &cfg->ffda_reg);
    affect_br_f64(r, &f->total_var);
    /* exactly what the encoder writes: version 1 no flag; 2 bit 0 (landmarks); 3 bit 1 (class-
     * mean prototypes) and maybe bit 0 */
    if (version == 1 ? flags != 0 : version == 2 ? flags != 1 : (flags != 2 && flags != 3))
        return out_of_range(err, "flags", flags, 8);
    if (method > AFFECT_FDA_FISOMAP)
        return out_of_range(err, "method", method, 12);
    if (order < 3 || order > AFFECT_BSPLINE_MAX_ORDER)
        return out_of_range(err, "order", order, 16);
    if (G < order || G > AFFECT_BSPLINE_MAX_BASIS)
        return out_of_range(err, "basis size", G, 20);
    if (m < 1 || m > AFFECT_HMM_MAX_DIM)
        return out_of_range(err, "coordinate count", m, 24);
    if (n < 3 || n > INT32_MAX)
        return out_of_range(err, "training motion count", n, 28);
    if (c < 2 || c > n)
        return out_of_range(err, "class count", c, 32);
    if (dims < 1 || dims > AFFECT_FDA_MAX_DIMS)
        return out_of_range(err, "requested dimensions", dims, 56);
    if (p < 1 || p > dims || p > n)
        return out_of_range(err, "dimensions", p, 36);
    if (R < 1 || R > n - 1)
        return out_of_range(err, "FPCA rank", R, 44);
    if ((flags & 2u) ? P != 0 : (P < 1 || P > R || P > AFFECT_FDA_MAX_DIMS))
        return out_of_range(err, "prototype dimensions", P, 40);
    if (iso_k < 1 || iso_k > AFFECT_FDA_MAX_ISOMAP_K)
        return out_of_range(err, "isomap_k", iso_k, 48);
    if (kernel > AFFECT_SPCA_RBF)
        return out_of_range(err, "label kernel", kernel, 52);
    if (gcv > 1)
        return out_of_range(err, "gcv flag", gcv, 60);
    if (!(cfg->lambda >= 0) || !isfinite(cfg->lambda))
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "lambda is not a finite number >= 0 (offset "
                           "64)");
    if (!(cfg->sigma > 0) || !isfinite(cfg->sigma))
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "sigma is not a positive finite number "
                           "(offset 72)");
    if (!(cfg->ffda_reg >= 0) || !isfinite(cfg->ffda_reg))
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "ffda_reg is not a finite number >= 0 "
                           "(offset 80)");
    if (!(f->total_var > 0) || !isfinite(f->total_var))
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "the total variance is not a positive finite "
                           "number (offset 88)");
    cfg->method = (affect_fda_method)method;
    cfg->order = order;
    cfg->n_basis = G;
    cfg->dims = dims;
    cfg->isomap_k = iso_k;
    cfg->kernel = (affect_spca_kernel)kernel;
    cfg->gcv = gcv == 1;
    cfg->proto_dims = P;
    cfg->alignment = (flags & 1u) ? AFFECT_FDA_ALIGN_LANDMARKS : AFFECT_FDA_ALIGN_LINEAR;
    f->b.order = order;
    f->b.n = G;
    f->m = m;
    f->n = n;
    f->c = c;
    f->p = p;
    f->P = P;
    f->R = R;
    f->h = (size_t)G * m;
    return AFFECT_OK;
}

static affect_status decode_body(affect_br *r, affect_fda *f, affect_error *err)
{
    uint32_t fsize;
    if (!affect_br_u32(r, &fsize))
        return truncated(err, r, "the feature definition");
    if (fsize) {
        const unsigned char *fb;
        size_t at = r->off;
        if (!affect_br_bytes(r, &fb, fsize))
            return truncated(err, r, "the feature definition");
        affect_status st = affect_features_decode(fb, fsize, &f->feat, err);
        if (st)
            return affect_prefix(err, "feature definition (offset %zu)", at);
        if (affect_features_dim(f->feat) != f->m)
            return affect_fail(err, AFFECT_ERR_FORMAT,
                               "the feature definition gives %u "
                               "coordinates, the model %u (offset %zu)",
                               affect_features_dim(f->feat), f->m, at);
    }
    if (!affect_br_has(r, f->c, 5)) /* each name: a length and at least one byte */
        return truncated(err, r, "the class names");
    f->classes = affect_calloc(f->c, sizeof *f->classes);
    if (!f->classes)
        return affect_nomem(err);
    for (uint32_t k = 0; k < f->c; k++) {
        uint32_t len;
        const unsigned char *s;
        if (!affect_br_u32(r, &len) || !affect_br_bytes(r, &s, len))
            return truncated(err, r, "the class names");
        if (len == 0 || !affect_utf8_valid((const char *)s, len))
            return affect_fail(err, AFFECT_ERR_FORMAT,
                               "class %u's name is empty or not valid "
                               "UTF-8 (offset %zu)",
                               k, r->off - len);
        for (uint32_t j = 0; j < k; j++)
            if (strlen(f->classes[j]) == len && memcmp(f->classes[j], s, len) == 0)
                return affect_fail(err, AFFECT_ERR_FORMAT,
                                   "class %u repeats class %u's name "
                                   "(offset %zu)",
                                   k, j, r->off - len);
        if (!(f->classes[k] = affect_strndup((const char *)s, len)))
            return affect_nomem(err);
    }
    if (!affect_br_has(r, f->n, 4))
        return truncated(err, r, "the labels");
    size_t at = r->off;
    f->y = affect_malloc_array(f->n, sizeof *f->y);
    if (!f->y)
        return affect_nomem(err);
    affect_br_u32s(r, f->y, f->n);
    for (uint32_t i = 0; i < f->n; i++)
        if (f->y[i] >= f->c)
            return out_of_range(err, "label", f->y[i], at + 4 * (size_t)i);
    size_t h = f->h, n = f->n, p = f->p;
    affect_status st;
    if ((st = read_f64s(r, f->c, "the class frame counts", &f->frames, err)) ||
        (st = read_f64s(r, f->R, "the FPCA eigenvalues", &f->fpca_eig, err)) ||
        (st = read_f64s(r, p, "the eigenvalues", &f->eig, err)) ||
        (st = read_f64s(r, p, "the explained shares", &f->explained, err)) ||
        (st = read_f64s(r, h, "the mean function", &f->mean, err)) ||
        (st = read_f64s(r, (size_t)f->P * h, "the eigenfunctions", &f->efun, err)) ||
        (st = read_f64s(r, (size_t)f->c * f->P, "the class centroids", &f->centroid, err)) ||
        (f->P == 0 && (st = read_f64s(r, (size_t)f->c * h, "the class means", &f->cmean, err))) ||
        (st = read_f64s(r, n * p, "the training embedding", &f->train_z, err)))
        return st;
    for (uint32_t k = 0; k < f->c; k++)
        if (!(f->frames[k] >= 1))
            return affect_fail(err, AFFECT_ERR_FORMAT,
                               "class %u's mean frame count is below "
                               "1",
                               k);
    for (uint32_t i = 0; i < p; i++)
        if (f->cfg.method != AFFECT_FDA_FFDA && f->cfg.method != AFFECT_FDA_FSPCA &&
            !(f->eig[i] > 0))
            return affect_fail(err, AFFECT_ERR_FORMAT, "eigenvalue %u is not positive", i);
    if (is_linear(f->cfg.method)) {
        if ((st = read_f64s(r, p * h, "the axes", &f->axes, err)))
            return st;
    } else if ((st = read_f64s(r, n * h, "the training functions", &f->train_c, err)) ||
               (st = read_f64s(r, n * p, "the MDS eigenvectors", &f->mds_v, err)) ||
               (st = read_f64s(r, n, "the squared geodesic means", &f->d2mean, err)) ||
               (st = read_f64s(r, n * n, "the geodesic distances", &f->geo, err))) {
        return st;
    }
    if (f->cfg.alignment != AFFECT_FDA_ALIGN_LANDMARKS)
        return AFFECT_OK;
    size_t lat = r->off;
    if (!affect_br_u32(r, &f->n_lm))
        return truncated(err, r, "the landmark template");
    if (f->n_lm > LM_MAX)
        return out_of_range(err, "landmark count", f->n_lm, lat);
    double last = 0.0;
    for (uint32_t k = 0; k < f->n_lm; k++) {
        uint32_t ty;
        lat = r->off;
        if (!affect_br_f64(r, &f->lm[k].t) || !affect_br_u32(r, &ty))
            return truncated(err, r, "the landmark template");
        if (!(f->lm[k].t > last) || !(f->lm[k].t < 1.0) || ty > 1)
            return affect_fail(err, AFFECT_ERR_FORMAT,
                               "landmark %u is not increasing in (0, 1) or has an unknown type "
                               "(offset %zu)",
                               k, lat);
        f->lm[k].type = ty ? 1 : -1;
        last = f->lm[k].t;
    }
    return AFFECT_OK;
}

affect_status affect_fda_decode(const unsigned char *data, size_t size, affect_fda **out,
                                affect_error *err)
{
    *out = NULL;
    if (size < AFFECT_FDA_HEADER_SIZE + 8)
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "truncated: %zu bytes is shorter than the "
                           "functional model header",
                           size);
    if (affect_check_magic(data, AFFECT_FDA_MAGIC, NULL, "a functional model", 0, err) != AFFECT_OK)
        return AFFECT_ERR_FORMAT;
    if (!affect_checksum_ok(data, size - 8))
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "functional model checksum mismatch: the BLOB "
                           "is corrupt");
    affect_br r;
    affect_br_init(&r, data, size - 8);
    affect_fda *f = affect_calloc(1, sizeof *f);
    if (!f)
        return affect_nomem(err);
    affect_status st = decode_head(&r, f, err);
    if (st == AFFECT_OK)
        st = decode_body(&r, f, err);
    if (st == AFFECT_OK && r.off != r.size)
        st = affect_fail(err, AFFECT_ERR_FORMAT, "%zu unexpected bytes at the end (offset %zu)",
                         r.size - r.off, r.off);
    if (st == AFFECT_OK)
        st = make_bands(f, err);
    if (st == AFFECT_OK)
        st = make_norms(f, err);
    if (st) {
        affect_fda_free(f);
        return st;
    }
    *out = f;
    return AFFECT_OK;
}
