/*
 * strength.c — emotion strength by relative attributes (affect/strength.h): features, PCA,
 * the ranker, the regression from strength to features, synthesis, editing, and the model BLOB.
 *
 * PCA: the eigenvectors of the Gram matrix Xc Xcᵀ when n ≤ D (axes Xcᵀ u / √λ), else of the
 * covariance Xcᵀ Xc; LAPACKE_dsyev_work in column-major form on the symmetric array with the
 * minimal workspace 3N − 1 (no allocation outside ours; the eigenvectors land in the rows).
 * Each axis is flipped so that its largest-magnitude component is positive.
 *
 * Regression (one input s, outputs z ∈ R^p), h a bandwidth in strength units:
 *   kernel ridge: f(s) = z̄ + Σ_i α_i k(s, r_i), k = exp(−(s − r)²/(2h²)), α = (K + λI)⁻¹(Z − z̄)
 *                 (LAPACKE_dposv, column-major on the symmetric K + λI, nrhs = p);
 *   local linear: the weighted least-squares line through (r_i, z_i) with weights
 *                 exp(−(s − r_i)²/(2h²)) evaluated at s (it extrapolates linearly beyond the
 *                 training strengths, where kernel ridge falls back to z̄).
 * Grids: h ∈ {0.05, 0.1, 0.2, 0.4, 0.8} × sd(r); λ ∈ {10⁻⁴, 10⁻³, 10⁻², 10⁻¹}. Folds: the
 * motions sorted by strength, fold = rank mod 5. The error is the mean over motions of
 * ‖f(r_i) − z_i‖² predicted by the fold that held motion i out.
 *
 * Laban features: the ranker's input is built by rank_input from z and the raw Laban vector
 * (laban_raw: affect_laban_vector with missing_null); laban_stats sets the means, deviations and
 * the keyframe block's weight. Only the ranker changes: the keyframe features, PCA and the
 * regression are computed as without them.
 *
 * Fisher features: fisher_train builds the observations and descriptors of the used motions as
 * affect_train does (affect_classifier_features_default, affect_features_extract,
 * affect_descriptors), trains the recognizer on them with the levels as classes, and evaluates
 * each training motion's normalized Fisher representation (affect_classifier_eval); those
 * n × D_F rows are the ranker's input, and a scored motion's vector comes from fisher_of (the
 * same two calls). The model's BLOB keeps the recognizer's own BLOB (version 3).
 *
 * Memory: the features (n × D), the PCA workspace (N² + N + 3N doubles, N = min(n, D)), the
 * model's arrays, with Fisher features the recognizer's training (affect/classifier.h) and the
 * n × D_F representations; every size overflow-checked.
 */
#include "affect/strength.h"

#include <cblas.h>
#include <lapacke.h>
#include <limits.h>
#include <math.h>
#include <string.h>

#include "util/bytes.h"
#include "util/rng.h"
#include "affect/hmm_blob.h" /* affect_fnv1a64 */
#include "affect/keyframes.h"
#include "affect/normalize.h"
#include "affect/roles.h"
#include "affect/skeleton.h"
#include "util/internal.h"

#define PCA_RANK_TOL 1e-10
#define FLAG_PCA 1u
#define FLAG_RELATIVE 2u
#define FLAG_STANDARDIZE 4u
#define FLAG_LABAN 8u       /* version 2: the ranker sees the Laban vector */
#define FLAG_BOTH 16u       /* version 2: … after the weighted keyframe coordinates */
#define FLAG_CV_C 32u       /* version 2: C chosen by the inner cross-validation */
#define FLAG_FISHER 64u     /* version 3: the ranker sees the recognizer's representation */
#define CV_SEED 0x5c0ffee5u /* the inner folds' draw: opt->seed mixed with this */
#define DT_CLAMP 10.0       /* durations kept within [mean / 10, mean × 10] */
#define MAX_OUT_FRAMES 1000000u
#define HEADER_SIZE 44u
#define FIXED_SIZE (HEADER_SIZE + 8 * 8 + 4 * 4 + 8 * 4 + AFFECT_MOTION_UNIT_MAX + 1)

static const double H_GRID[] = {0.05, 0.1, 0.2, 0.4, 0.8};
static const double L_GRID[] = {1e-4, 1e-3, 1e-2, 1e-1};
#define N_H (sizeof H_GRID / sizeof H_GRID[0])
#define N_L (sizeof L_GRID / sizeof L_GRID[0])

void affect_strength_options_default(affect_strength_options *opt)
{
    memset(opt, 0, sizeof *opt);
    opt->features = AFFECT_STRENGTH_FEAT_FISHER;
    opt->keyframes = AFFECT_KEYFRAMES_DEFAULT;
    opt->pca_dims = 40;
    opt->C = 1.0;
    opt->fraction = 1.0;
    opt->similar = true;
    opt->standardize = true;
    opt->cv_C = true;
    affect_classifier_config cc;
    affect_classifier_config_default(&cc);
    opt->descriptors = cc.descriptors;
}

void affect_strength_free(affect_strength *s)
{
    if (!s)
        return;
    if (s->names)
        for (uint32_t j = 0; j < s->n_joints; j++)
            affect_free(s->names[j]);
    affect_free(s->names);
    affect_free(s->parents);
    affect_free(s->mean);
    affect_free(s->scale);
    affect_free(s->comps);
    affect_free(s->seg_dt);
    affect_free(s->w);
    if (s->level_names)
        for (uint32_t l = 0; l < s->n_levels; l++)
            affect_free(s->level_names[l]);
    affect_free(s->level_names);
    affect_free(s->level_strength);
    affect_free(s->level_count);
    affect_free(s->train_r);
    affect_free(s->train_z);
    affect_free(s->alpha);
    affect_free(s->zbar);
    affect_classifier_free(s->fisher);
    affect_free(s);
}

uint32_t affect_strength_rank_dim(const affect_strength *s)
{
    switch (s->features) {
    case AFFECT_STRENGTH_FEAT_LABAN:
        return AFFECT_LABAN_N;
    case AFFECT_STRENGTH_FEAT_BOTH:
        return s->pdim + AFFECT_LABAN_N;
    case AFFECT_STRENGTH_FEAT_FISHER: /* 1 until the recognizer is there (decoding) */
        return s->fisher ? (uint32_t)affect_classifier_dim(s->fisher) : 1u;
    default:
        return s->pdim;
    }
}

/* Allocates the arrays of s from its sizes (names and level names zeroed). */
static bool alloc_arrays(affect_strength *s)
{
    size_t pd, nz;
    if (!affect_mul_size(s->pdim, s->dim, &pd) || !affect_mul_size(s->n_train, s->pdim, &nz))
        return false;
    s->names = affect_calloc(s->n_joints, sizeof *s->names);
    s->parents = affect_calloc(s->n_joints, sizeof *s->parents);
    s->seg_dt = affect_calloc(s->keyframes, sizeof(double));
    s->w = affect_calloc(affect_strength_rank_dim(s), sizeof(double));
    s->level_names = affect_calloc(s->n_levels, sizeof *s->level_names);
    s->level_strength = affect_calloc(s->n_levels, sizeof(double));
    s->level_count = affect_calloc(s->n_levels, sizeof(uint32_t));
    s->train_r = affect_calloc(s->n_train, sizeof(double));
    s->train_z = affect_calloc(nz, sizeof(double));
    s->zbar = affect_calloc(s->pdim, sizeof(double));
    if (!s->names || !s->parents || !s->seg_dt || !s->w || !s->level_names || !s->level_strength ||
        !s->level_count || !s->train_r || !s->train_z || !s->zbar)
        return false;
    if (s->pca) {
        s->mean = affect_calloc(s->dim, sizeof(double));
        s->comps = affect_calloc(pd, sizeof(double));
        if (!s->mean || !s->comps)
            return false;
    }
    if (s->regression == AFFECT_STRENGTH_REG_KERNEL_RIDGE) {
        s->alpha = affect_calloc(nz, sizeof(double));
        if (!s->alpha)
            return false;
    }
    return true;
}

/* ---- features ---- */

static affect_status check_skeleton(uint32_t J, char *const *names, const affect_motion *m,
                                    affect_error *err)
{
    if (m->n_joints != J)
        return affect_fail(err, AFFECT_ERR_INVALID, "%u joints, the model has %u", m->n_joints, J);
    for (uint32_t j = 0; j < J; j++)
        if (strcmp(m->names[j], names[j]) != 0)
            return affect_fail(err, AFFECT_ERR_INVALID, "joint %u is \"%s\", the model's is \"%s\"",
                               j, m->names[j], names[j]);
    return AFFECT_OK;
}

/* Normalized positions Y (T × 3J), the transform, the q keyframes, and the features x (6 J q).
 * Y may be NULL (then freed inside). */
/* The root joint of relative features: the pelvis role, else joint 0. */
static uint32_t root_joint(const affect_motion *m)
{
    affect_roles roles;
    affect_roles_resolve(m, &roles);
    int32_t p = roles.joint[AFFECT_ROLE_PELVIS];
    return p >= 0 ? (uint32_t)p : 0;
}

/* Pose in place: every joint but the root minus the root (relative features). */
static void to_relative(double *pose, uint32_t J, uint32_t root)
{
    for (uint32_t j = 0; j < J; j++)
        if (j != root)
            for (uint32_t c = 0; c < 3; c++)
                pose[3 * j + c] -= pose[3 * root + c];
}

static void from_relative(double *pose, uint32_t J, uint32_t root)
{
    for (uint32_t j = 0; j < J; j++)
        if (j != root)
            for (uint32_t c = 0; c < 3; c++)
                pose[3 * j + c] += pose[3 * root + c];
}

static affect_status motion_features(const affect_motion *m, uint32_t q, bool relative,
                                     uint32_t root, double *x, uint32_t *kf, double **Y_out,
                                     affect_normalize_transform *tf_out, affect_monitor *mon,
                                     affect_error *err)
{
    if (Y_out)
        *Y_out = NULL;
    uint32_t T = m->n_frames, J = m->n_joints, D3 = 3 * J;
    if (T < q || T < 2)
        return affect_fail(err, AFFECT_ERR_RANGE, "%u frames, fewer than the %u keyframes", T,
                           q < 2 ? 2 : q);
    if (!(m->fps > 0))
        return affect_fail(err, AFFECT_ERR_INVALID, "the frame rate must be > 0");
    affect_roles roles;
    affect_roles_resolve(m, &roles);
    affect_normalize_options no;
    affect_normalize_options_default(&no);
    affect_normalize_transform tf;
    affect_status st = affect_normalize_transform_compute(m, &roles, &no, &tf, err);
    if (st != AFFECT_OK)
        return st;
    double *Y = affect_malloc_array((size_t)T * D3, sizeof(double));
    if (!Y)
        return affect_nomem_of(err, (size_t)T * D3, sizeof(double), "the motion's positions");
    for (uint32_t t = 0; t < T; t++)
        for (uint32_t j = 0; j < J; j++) {
            const float *p = affect_motion_at(m, t, j);
            double d[3] = {p[0] - tf.origin[0], p[1] - tf.origin[1], p[2] - tf.origin[2]};
            for (int a = 0; a < 3; a++)
                Y[(size_t)t * D3 + 3 * j + (uint32_t)a] =
                    (tf.rot[3 * a] * d[0] + tf.rot[3 * a + 1] * d[1] + tf.rot[3 * a + 2] * d[2]) /
                    tf.scale;
        }
    uint32_t nk;
    st = affect_keyframes_select(Y, T, D3, q, kf, &nk, NULL, mon, err);
    if (st != AFFECT_OK)
        goto cleanup;
    for (uint32_t i = 0; i < q; i++) {
        double *pose = x + (size_t)i * 2 * D3, *vel = pose + D3;
        memcpy(pose, Y + (size_t)kf[i] * D3, sizeof(double) * D3);
        if (relative)
            to_relative(pose, J, root);
        if (i == 0) {
            memset(vel, 0, sizeof(double) * D3);
            continue;
        }
        const double *prev = pose - 2 * (size_t)D3;
        double dt = (double)(kf[i] - kf[i - 1]) / m->fps;
        for (uint32_t c = 0; c < D3; c++)
            vel[c] = (pose[c] - prev[c]) / dt;
    }
    if (tf_out)
        *tf_out = tf;
cleanup:
    if (st == AFFECT_OK && Y_out)
        *Y_out = Y;
    else
        affect_free(Y);
    return st;
}

/* z = P (x − mean), or x itself without PCA. */
static void project(const affect_strength *s, const double *x, double *z, double *work)
{
    if (!s->pca) {
        for (uint32_t c = 0; c < s->dim; c++)
            z[c] = s->scale ? x[c] / s->scale[c] : x[c];
        return;
    }
    for (uint32_t c = 0; c < s->dim; c++)
        work[c] = (s->scale ? x[c] / s->scale[c] : x[c]) - s->mean[c];
    AFFECT_BLAS(cblas_dgemv(CblasRowMajor, CblasNoTrans, (int)s->pdim, (int)s->dim, 1.0, s->comps,
                            (int)s->dim, work, 1, 0.0, z, 1));
}

/* x = mean + Pᵀ z (or z). */
static void unproject(const affect_strength *s, const double *z, double *x)
{
    if (!s->pca) {
        memcpy(x, z, sizeof(double) * s->dim);
    } else {
        memcpy(x, s->mean, sizeof(double) * s->dim);
        AFFECT_BLAS(cblas_dgemv(CblasRowMajor, CblasTrans, (int)s->pdim, (int)s->dim, 1.0, s->comps,
                                (int)s->dim, z, 1, 1.0, x, 1));
    }
    if (s->scale)
        for (uint32_t c = 0; c < s->dim; c++)
            x[c] *= s->scale[c];
}

affect_status affect_strength_features(const affect_strength *s, const affect_motion *m, double *x,
                                       double *z, uint32_t *keyframes, affect_monitor *mon,
                                       affect_error *err)
{
    affect_status st = check_skeleton(s->n_joints, s->names, m, err);
    if (st != AFFECT_OK)
        return st;
    uint32_t *kf = affect_malloc_array(s->keyframes, sizeof *kf);
    double *work = affect_malloc_array(s->dim, sizeof(double));
    if (!kf || !work) {
        st = affect_nomem(err);
        goto cleanup;
    }
    st = motion_features(m, s->keyframes, s->relative, s->root, x, kf, NULL, NULL, mon, err);
    if (st != AFFECT_OK)
        goto cleanup;
    if (z)
        project(s, x, z, work);
    if (keyframes)
        memcpy(keyframes, kf, sizeof *kf * s->keyframes);
cleanup:
    affect_free(kf);
    affect_free(work);
    return st;
}

static double dotp(const double *a, const double *b, size_t n)
{
    double s = 0;
    for (size_t k = 0; k < n; k++)
        s += a[k] * b[k];
    return s;
}

/* The Laban vector of m (affect/laban.h with its defaults; NaN where a component cannot be
 * computed, e.g. a role the skeleton lacks). */
static affect_status laban_raw(const affect_motion *m, double *v, affect_monitor *mon,
                               affect_error *err)
{
    affect_roles roles;
    affect_roles_resolve(m, &roles);
    affect_laban_options lo;
    affect_laban_options_default(&lo);
    lo.missing_null = true;
    lo.monitor = mon;
    affect_status st = affect_laban_vector(m, &roles, &lo, v, err);
    if (st != AFFECT_OK)
        affect_prefix(err, "Laban vector");
    return st;
}

/* The normalized Fisher representation of m under the recognizer c into u
 * (affect_classifier_dim(c) doubles): its observations and descriptors, then its evaluation. */
static affect_status fisher_of(const affect_classifier *c, const affect_motion *m, double *u,
                               affect_monitor *mon, affect_error *err)
{
    double *x = NULL, *desc = NULL;
    uint32_t T = 0;
    affect_status st = affect_classifier_observe(c, m, &x, &T, &desc, mon, err);
    if (st == AFFECT_OK) {
        affect_classifier_out o = {0};
        o.fisher = u;
        st = affect_classifier_eval(c, x, T, desc, false, &o, mon, err);
    }
    affect_free(x);
    affect_free(desc);
    if (st != AFFECT_OK)
        affect_prefix(err, "Fisher features");
    return st;
}

/* The recognizer of Fisher features: affect_classifier_train with its defaults (and the
 * observations that go with them) on the used motions (idx, n of them), their levels lv as
 * classes: the levels that have a motion, in level order, named as in level_names (a level of
 * the order without a training motion is no class); then each motion's representation into *F
 * (n × its dimension). */
static affect_status fisher_train(const affect_motion *const *motions, const uint32_t *idx,
                                  const int32_t *lv, uint32_t n, const char *const *level_names,
                                  uint32_t n_levels, unsigned descriptors, affect_monitor *mon,
                                  affect_classifier **out, double **F, affect_error *err)
{
    *out = NULL;
    *F = NULL;
    affect_classifier_config cfg;
    affect_classifier_config_default(&cfg);
    cfg.descriptors = descriptors;
    affect_features_options fo;
    affect_classifier_features_default(&fo);
    affect_features *feat = NULL;
    affect_hmm_seq *seqs = affect_calloc(n, sizeof *seqs);
    uint32_t *y = affect_malloc_array(n, sizeof *y);
    uint32_t dd = cfg.descriptors ? affect_descriptors_dim(cfg.descriptors) : 0;
    double *desc = dd ? affect_malloc_array((size_t)n * dd, sizeof(double)) : NULL;
    /* the classes: the levels present, in order (cls[l] = the class of level l) */
    uint32_t cls[AFFECT_STRENGTH_MAX_LEVELS], n_cls = 0;
    const char *names[AFFECT_STRENGTH_MAX_LEVELS];
    for (uint32_t l = 0; l < n_levels; l++) {
        bool has = false;
        for (uint32_t i = 0; i < n && !has; i++)
            has = lv[i] == (int32_t)l;
        cls[l] = n_cls;
        if (has)
            names[n_cls++] = level_names[l];
    }
    affect_status st = AFFECT_OK;
    if (!seqs || !y || (dd && !desc)) {
        st = affect_nomem(err);
        goto cleanup;
    }
    st = affect_features_create(&fo, motions[idx[0]], &feat, err);
    for (uint32_t i = 0; st == AFFECT_OK && i < n; i++) {
        const affect_motion *m = motions[idx[i]];
        double *x = NULL;
        st = affect_features_extract(feat, m, &x, &seqs[i].n_frames, mon, err);
        seqs[i].x = x;
        if (st == AFFECT_OK && dd)
            st = affect_descriptors(cfg.descriptors, m, feat->up_axis, desc + (size_t)i * dd, mon,
                                    err);
        if (st != AFFECT_OK)
            affect_prefix(err, "motion %u", idx[i]);
        y[i] = cls[lv[i]];
    }
    if (st == AFFECT_OK) {
        cfg.hmm.dim = affect_features_dim(feat);
        cfg.hmm.monitor = mon;
        st = affect_classifier_train(&cfg, feat, seqs, desc, y, n, names, n_cls, out, err);
    }
    size_t D = st == AFFECT_OK ? affect_classifier_dim(*out) : 0;
    if (st == AFFECT_OK && !(*F = affect_malloc_array((size_t)n, D * sizeof(double))))
        st = affect_nomem_of(err, (size_t)n, D * sizeof(double), "the %u x %zu Fisher features", n,
                             D);
    for (uint32_t i = 0; st == AFFECT_OK && i < n; i++) {
        affect_classifier_out o = {0};
        o.fisher = *F + (size_t)i * D;
        st = affect_classifier_eval(*out, seqs[i].x, seqs[i].n_frames,
                                    dd ? desc + (size_t)i * dd : NULL, false, &o, mon, err);
        if (st != AFFECT_OK)
            affect_prefix(err, "motion %u", idx[i]);
    }
cleanup:
    if (st != AFFECT_OK) {
        affect_prefix(err, "Fisher features");
        affect_classifier_free(*out);
        *out = NULL;
        affect_free(*F);
        *F = NULL;
    }
    for (uint32_t i = 0; seqs && i < n; i++)
        affect_free((void *)seqs[i].x);
    affect_free(seqs);
    affect_free(y);
    affect_free(desc);
    affect_features_free(feat);
    return st;
}

/* The ranker's input u (affect_strength_rank_dim(s)) from the keyframe coordinates z (pdim;
 * unused with Laban features alone) and the raw Laban vector lab (unused with keyframes). */
static void rank_input(const affect_strength *s, const double *z, const double *lab, double *u)
{
    uint32_t o = 0;
    if (s->features != AFFECT_STRENGTH_FEAT_LABAN) {
        double a = s->features == AFFECT_STRENGTH_FEAT_BOTH ? s->kf_weight : 1;
        for (uint32_t c = 0; c < s->pdim; c++)
            u[c] = a * z[c];
        o = s->pdim;
    }
    if (s->features != AFFECT_STRENGTH_FEAT_KEYFRAMES)
        for (uint32_t k = 0; k < AFFECT_LABAN_N; k++)
            u[o + k] = isfinite(lab[k]) ? (lab[k] - s->lab_mean[k]) / s->lab_sd[k] : 0;
}

affect_status affect_strength_score(const affect_strength *s, const affect_motion *m,
                                    double *strength, affect_monitor *mon, affect_error *err)
{
    uint32_t rd = affect_strength_rank_dim(s);
    double lab[AFFECT_LABAN_N];
    double *x = affect_malloc_array(s->dim, sizeof(double));
    double *z = affect_malloc_array(s->pdim, sizeof(double));
    double *u = affect_malloc_array(rd, sizeof(double));
    affect_status st = AFFECT_OK;
    if (!x || !z || !u)
        st = affect_nomem(err);
    else if (s->features == AFFECT_STRENGTH_FEAT_KEYFRAMES ||
             s->features == AFFECT_STRENGTH_FEAT_BOTH)
        st = affect_strength_features(s, m, x, z, NULL, mon, err);
    else
        st = check_skeleton(s->n_joints, s->names, m, err);
    if (st == AFFECT_OK && s->features == AFFECT_STRENGTH_FEAT_FISHER)
        st = fisher_of(s->fisher, m, u, mon, err);
    else if (st == AFFECT_OK && s->features != AFFECT_STRENGTH_FEAT_KEYFRAMES)
        st = laban_raw(m, lab, mon, err);
    if (st == AFFECT_OK) {
        if (s->features != AFFECT_STRENGTH_FEAT_FISHER)
            rank_input(s, z, lab, u);
        *strength = dotp(s->w, u, rd);
    }
    affect_free(x);
    affect_free(z);
    affect_free(u);
    return st;
}

/* ---- PCA ---- */

static affect_status pca_fit(affect_strength *s, const double *X, uint32_t n, uint32_t want,
                             affect_error *err)
{
    uint32_t D = s->dim;
    bool gram = n <= D;
    uint32_t N = gram ? n : D;
    double *Xc = NULL, *G = NULL, *ev = NULL, *work = NULL;
    affect_ws_part parts[] = {
        {(void **)&Xc, (size_t)n * D, sizeof(double)},
        {(void **)&G, (size_t)N * N, sizeof(double)},
        {(void **)&ev, N, sizeof(double)},
        {(void **)&work, 3 * (size_t)N, sizeof(double)},
    };
    void *block = affect_ws_alloc(parts, 4);
    if (!block)
        return affect_nomem_of(err, (size_t)N * N + (size_t)n * D, sizeof(double),
                               "the PCA workspace");
    affect_status st = AFFECT_OK;
    double *mean = affect_calloc(D, sizeof(double));
    double *comps = NULL;
    if (!mean) {
        st = affect_nomem(err);
        goto cleanup;
    }
    for (uint32_t i = 0; i < n; i++)
        for (uint32_t c = 0; c < D; c++)
            mean[c] += X[(size_t)i * D + c];
    for (uint32_t c = 0; c < D; c++)
        mean[c] /= n;
    for (uint32_t i = 0; i < n; i++)
        for (uint32_t c = 0; c < D; c++)
            Xc[(size_t)i * D + c] = X[(size_t)i * D + c] - mean[c];
    if (gram)
        AFFECT_BLAS(cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasTrans, (int)n, (int)n, (int)D,
                                1.0, Xc, (int)D, Xc, (int)D, 0.0, G, (int)n));
    else
        AFFECT_BLAS(cblas_dgemm(CblasRowMajor, CblasTrans, CblasNoTrans, (int)D, (int)D, (int)n,
                                1.0, Xc, (int)D, Xc, (int)D, 0.0, G, (int)D));
    int info = affect_sym_eigen(G, N, ev, work);
    if (info != 0) {
        st = affect_fail(err, AFFECT_ERR_RANGE, "PCA: the eigen-decomposition failed (info %d)",
                         (int)info);
        goto cleanup;
    }
    double lmax = ev[N - 1], total = 0;
    for (uint32_t k = 0; k < N; k++)
        total += ev[k] > 0 ? ev[k] : 0;
    uint32_t rank = 0;
    for (uint32_t k = 0; k < N; k++)
        if (lmax > 0 && ev[k] > PCA_RANK_TOL * lmax)
            rank++;
    if (rank == 0) {
        st = affect_fail(err, AFFECT_ERR_INVALID,
                         "PCA: the training motions have identical features");
        goto cleanup;
    }
    uint32_t p = want < rank ? want : rank;
    comps = affect_calloc((size_t)p * D, sizeof(double));
    if (!comps) {
        st = affect_nomem(err);
        goto cleanup;
    }
    double kept = 0;
    for (uint32_t c = 0; c < p; c++) {
        uint32_t k = N - 1 - c;
        double *axis = comps + (size_t)c * D;
        kept += ev[k];
        if (gram) {
            AFFECT_BLAS(cblas_dgemv(CblasRowMajor, CblasTrans, (int)n, (int)D, 1.0 / sqrt(ev[k]),
                                    Xc, (int)D, G + (size_t)k * N, 1, 0.0, axis, 1));
        } else {
            memcpy(axis, G + (size_t)k * N, sizeof(double) * D);
        }
        uint32_t big = 0;
        for (uint32_t a = 1; a < D; a++)
            if (fabs(axis[a]) > fabs(axis[big]))
                big = a;
        if (axis[big] < 0)
            for (uint32_t a = 0; a < D; a++)
                axis[a] = -axis[a];
    }
    s->pdim = p;
    s->mean = mean;
    s->comps = comps;
    s->pca_variance = total > 0 ? kept / total : 1;
    mean = comps = NULL;
cleanup:
    affect_free(mean);
    affect_free(comps);
    affect_free(block);
    return st;
}

/* ---- regression ---- */

static double kern(double a, double b, double h)
{
    double d = (a - b) / h;
    return exp(-0.5 * d * d);
}

/* Local linear prediction at s from the m points (r, Z: m × p). */
static void llr_predict(const double *r, const double *Z, uint32_t m, uint32_t p, double h,
                        double s, double *out, double *wt)
{
    double dmin = INFINITY;
    for (uint32_t i = 0; i < m; i++) {
        double d = fabs(r[i] - s);
        if (d < dmin)
            dmin = d;
    }
    double S0 = 0, S1 = 0, S2 = 0;
    for (uint32_t i = 0; i < m; i++) {
        double d = r[i] - s;
        double e = (d * d - dmin * dmin) / (2 * h * h);
        wt[i] = exp(-e);
        S0 += wt[i];
        S1 += wt[i] * d;
        S2 += wt[i] * d * d;
    }
    double den = S0 * S2 - S1 * S1;
    bool linear = den > 1e-10 * S0 * S2 && S2 > 0;
    memset(out, 0, sizeof(double) * p);
    for (uint32_t i = 0; i < m; i++) {
        double l = linear ? wt[i] * (S2 - S1 * (r[i] - s)) / den : wt[i] / S0;
        const double *z = Z + (size_t)i * p;
        for (uint32_t c = 0; c < p; c++)
            out[c] += l * z[c];
    }
}

/* Kernel ridge fit on m points: zbar (p), alpha_t (p × m); K (m × m) is workspace. */
static affect_status krr_fit(const double *r, const double *Z, uint32_t m, uint32_t p, double h,
                             double lambda, double *zbar, double *alpha_t, double *K,
                             affect_error *err)
{
    memset(zbar, 0, sizeof(double) * p);
    for (uint32_t i = 0; i < m; i++)
        for (uint32_t c = 0; c < p; c++)
            zbar[c] += Z[(size_t)i * p + c] / m;
    for (uint32_t i = 0; i < m; i++) {
        for (uint32_t j = 0; j < m; j++)
            K[(size_t)i * m + j] = kern(r[i], r[j], h);
        K[(size_t)i * m + i] += lambda;
    }
    for (uint32_t c = 0; c < p; c++)
        for (uint32_t i = 0; i < m; i++)
            alpha_t[(size_t)c * m + i] = Z[(size_t)i * p + c] - zbar[c];
    lapack_int info;
    AFFECT_BLAS(info = LAPACKE_dposv(LAPACK_COL_MAJOR, 'U', (lapack_int)m, (lapack_int)p, K,
                                     (lapack_int)m, alpha_t, (lapack_int)m));
    if (info != 0)
        return affect_fail(err, AFFECT_ERR_RANGE,
                           "kernel ridge regression: the system is singular (info %d)", (int)info);
    return AFFECT_OK;
}

static void krr_predict(const double *r, uint32_t m, uint32_t p, double h, const double *zbar,
                        const double *alpha_t, double s, double *out)
{
    memcpy(out, zbar, sizeof(double) * p);
    for (uint32_t i = 0; i < m; i++) {
        double k = kern(s, r[i], h);
        for (uint32_t c = 0; c < p; c++)
            out[c] += k * alpha_t[(size_t)c * m + i];
    }
}

void affect_strength_predict(const affect_strength *s, double strength, double *z)
{
    if (s->regression == AFFECT_STRENGTH_REG_KERNEL_RIDGE) {
        krr_predict(s->train_r, s->n_train, s->pdim, s->reg_h, s->zbar, s->alpha, strength, z);
        return;
    }
    /* local linear: the weights need n_train doubles; predict in blocks without allocation
     * by accumulating the sums first */
    const double *r = s->train_r;
    uint32_t m = s->n_train, p = s->pdim;
    double h = s->reg_h, dmin = INFINITY;
    for (uint32_t i = 0; i < m; i++)
        if (fabs(r[i] - strength) < dmin)
            dmin = fabs(r[i] - strength);
    double S0 = 0, S1 = 0, S2 = 0;
    for (uint32_t i = 0; i < m; i++) {
        double d = r[i] - strength, wgt = exp(-(d * d - dmin * dmin) / (2 * h * h));
        S0 += wgt;
        S1 += wgt * d;
        S2 += wgt * d * d;
    }
    double den = S0 * S2 - S1 * S1;
    bool linear = den > 1e-10 * S0 * S2 && S2 > 0;
    memset(z, 0, sizeof(double) * p);
    for (uint32_t i = 0; i < m; i++) {
        double d = r[i] - strength, wgt = exp(-(d * d - dmin * dmin) / (2 * h * h));
        double l = linear ? wgt * (S2 - S1 * d) / den : wgt / S0;
        for (uint32_t c = 0; c < p; c++)
            z[c] += l * s->train_z[(size_t)i * p + c];
    }
}

affect_status affect_strength_fit_regression(affect_strength *s, affect_strength_regression want,
                                             affect_monitor *mon, affect_error *err)
{
    uint32_t n = s->n_train, p = s->pdim;
    uint32_t F = n < AFFECT_STRENGTH_CV_FOLDS ? n : AFFECT_STRENGTH_CV_FOLDS;
    double sd = 0, mr = 0;
    for (uint32_t i = 0; i < n; i++)
        mr += s->train_r[i] / n;
    for (uint32_t i = 0; i < n; i++)
        sd += (s->train_r[i] - mr) * (s->train_r[i] - mr) / n;
    sd = sqrt(sd);
    if (!(sd > 0))
        sd = 1;
    uint32_t *fold = NULL, *order = NULL;
    double *rr = NULL, *ZZ = NULL, *K = NULL, *at = NULL, *zb = NULL, *pred = NULL, *wt = NULL;
    affect_ws_part parts[] = {
        {(void **)&fold, n, sizeof(uint32_t)},
        {(void **)&order, n, sizeof(uint32_t)},
        {(void **)&rr, n, sizeof(double)},
        {(void **)&ZZ, (size_t)n * p, sizeof(double)},
        {(void **)&K, (size_t)n * n, sizeof(double)},
        {(void **)&at, (size_t)n * p, sizeof(double)},
        {(void **)&zb, p, sizeof(double)},
        {(void **)&pred, p, sizeof(double)},
        {(void **)&wt, n, sizeof(double)},
    };
    void *block = affect_ws_alloc(parts, sizeof parts / sizeof parts[0]);
    if (!block)
        return affect_nomem_of(err, (size_t)n * n, sizeof(double), "the regression workspace");
    affect_status st = AFFECT_OK;
    /* folds by rank of strength (insertion sort: n is small, ties by index) */
    for (uint32_t i = 0; i < n; i++) {
        uint32_t k = i;
        while (k > 0 && s->train_r[order[k - 1]] > s->train_r[i]) {
            order[k] = order[k - 1];
            k--;
        }
        order[k] = i;
    }
    for (uint32_t k = 0; k < n; k++)
        fold[order[k]] = k % F;
    double best_kr = INFINITY, best_ll = INFINITY, kr_h = sd, kr_l = L_GRID[0], ll_h = sd;
    double base = 0;
    /* candidates: index 0 .. N_H·N_L − 1 kernel ridge, then N_H local linear, then constant */
    size_t n_cand = N_H * N_L + N_H + 1;
    for (size_t cand = 0; cand < n_cand; cand++) {
        st = affect_monitor_check(mon, err);
        if (st != AFFECT_OK)
            goto cleanup;
        bool kr = cand < N_H * N_L, ll = !kr && cand < N_H * N_L + N_H;
        double h = kr ? H_GRID[cand / N_L] * sd : ll ? H_GRID[cand - N_H * N_L] * sd : 0;
        double lambda = kr ? L_GRID[cand % N_L] : 0;
        double total = 0;
        for (uint32_t f = 0; f < F; f++) {
            uint32_t m = 0;
            for (uint32_t i = 0; i < n; i++)
                if (fold[i] != f || F == 1) {
                    rr[m] = s->train_r[i];
                    memcpy(ZZ + (size_t)m * p, s->train_z + (size_t)i * p, sizeof(double) * p);
                    m++;
                }
            if (kr) {
                st = krr_fit(rr, ZZ, m, p, h, lambda, zb, at, K, err);
                if (st != AFFECT_OK)
                    goto cleanup;
            } else if (!ll) {
                memset(zb, 0, sizeof(double) * p);
                for (uint32_t i = 0; i < m; i++)
                    for (uint32_t c = 0; c < p; c++)
                        zb[c] += ZZ[(size_t)i * p + c] / m;
            }
            for (uint32_t i = 0; i < n; i++) {
                if (fold[i] != f)
                    continue;
                if (kr)
                    krr_predict(rr, m, p, h, zb, at, s->train_r[i], pred);
                else if (ll)
                    llr_predict(rr, ZZ, m, p, h, s->train_r[i], pred, wt);
                else
                    memcpy(pred, zb, sizeof(double) * p);
                const double *z = s->train_z + (size_t)i * p;
                for (uint32_t c = 0; c < p; c++)
                    total += (pred[c] - z[c]) * (pred[c] - z[c]);
            }
        }
        total /= n;
        if (kr && total < best_kr) {
            best_kr = total;
            kr_h = h;
            kr_l = lambda;
        } else if (ll && total < best_ll) {
            best_ll = total;
            ll_h = h;
        } else if (!kr && !ll) {
            base = total;
        }
    }
    s->cv_kernel_ridge = best_kr;
    s->cv_local_linear = best_ll;
    s->cv_constant = base;
    affect_strength_regression use = want;
    if (use == AFFECT_STRENGTH_REG_AUTO)
        use =
            best_kr < best_ll ? AFFECT_STRENGTH_REG_KERNEL_RIDGE : AFFECT_STRENGTH_REG_LOCAL_LINEAR;
    s->regression = use;
    memset(s->zbar, 0, sizeof(double) * p);
    for (uint32_t i = 0; i < n; i++)
        for (uint32_t c = 0; c < p; c++)
            s->zbar[c] += s->train_z[(size_t)i * p + c] / n;
    affect_free(s->alpha);
    s->alpha = NULL;
    if (use == AFFECT_STRENGTH_REG_KERNEL_RIDGE) {
        s->reg_h = kr_h;
        s->reg_lambda = kr_l;
        s->alpha = affect_calloc((size_t)n * p, sizeof(double));
        if (!s->alpha) {
            st = affect_nomem(err);
            goto cleanup;
        }
        st = krr_fit(s->train_r, s->train_z, n, p, kr_h, kr_l, s->zbar, s->alpha, K, err);
    } else {
        s->reg_h = ll_h;
        s->reg_lambda = 0;
    }
cleanup:
    affect_free(block);
    return st;
}

/* ---- training ---- */

/* The C grid of the inner cross-validation, in the order ties are broken (the middle first). */
static const double C_GRID[] = {1, 0.1, 10, 0.01, 100};
#define N_C (sizeof C_GRID / sizeof C_GRID[0])

/* C for the mean pair loss by AFFECT_STRENGTH_CV_FOLDS-fold cross-validation over the n training
 * motions (inputs U, n × d; levels lv; groups grp or NULL): folds stratified by level, drawn by
 * the seed; for each C of C_GRID a ranker on the other folds' pairs (drawn as training draws
 * them) scores every motion, and each held-out motion's ordered pairs with every motion (of its
 * group) count right when ordered right. The C with the most right wins (ties: C_GRID's order);
 * *C_out is untouched when no fold can be scored. */
static affect_status cv_choose_C(const double *U, uint32_t n, uint32_t d, const int32_t *lv,
                                 const uint32_t *grp, uint32_t n_levels,
                                 const affect_strength_options *opt, double *C_out,
                                 affect_error *err)
{
    uint32_t F = AFFECT_STRENGTH_CV_FOLDS;
    uint32_t *fold = NULL, *perm = NULL;
    int32_t *inner = NULL;
    double *w = NULL, *score = NULL;
    affect_rank_pair *pairs = NULL;
    affect_ws_part parts[] = {
        {(void **)&fold, n, sizeof(uint32_t)}, {(void **)&perm, n, sizeof(uint32_t)},
        {(void **)&inner, n, sizeof(int32_t)}, {(void **)&w, d, sizeof(double)},
        {(void **)&score, n, sizeof(double)},
    };
    void *block = affect_ws_alloc(parts, sizeof parts / sizeof parts[0]);
    if (!block)
        return affect_nomem(err);
    affect_status st = AFFECT_OK;
    affect_rng rng;
    affect_rng_seed(&rng, opt->seed ^ CV_SEED);
    /* stratified folds: each level's motions shuffled, then dealt round-robin */
    uint32_t dealt = 0;
    for (uint32_t l = 0; l < n_levels; l++) {
        uint32_t m = 0;
        for (uint32_t i = 0; i < n; i++)
            if (lv[i] == (int32_t)l)
                perm[m++] = i;
        for (uint32_t k = m; k > 1; k--) {
            uint32_t j = (uint32_t)(affect_rng_next(&rng) % k), t = perm[k - 1];
            perm[k - 1] = perm[j];
            perm[j] = t;
        }
        for (uint32_t k = 0; k < m; k++)
            fold[perm[k]] = (dealt + k) % F;
        dealt += m;
    }
    uint64_t best = 0;
    bool any = false;
    for (size_t c = 0; c < N_C; c++) {
        uint64_t right = 0, total = 0;
        for (uint32_t f = 0; f < F; f++) {
            st = affect_monitor_check(opt->monitor, err);
            if (st != AFFECT_OK)
                goto cleanup;
            for (uint32_t i = 0; i < n; i++)
                inner[i] = fold[i] == f ? -1 : lv[i];
            size_t np = 0, no = 0;
            affect_free(pairs);
            pairs = NULL;
            st = affect_rank_pairs(inner, grp, n, opt->similar, opt->fraction, opt->seed, &pairs,
                                   &np, err);
            if (st != AFFECT_OK)
                goto cleanup;
            for (size_t p = 0; p < np; p++)
                no += !pairs[p].similar;
            if (no == 0)
                continue;
            affect_rank_options ro;
            affect_rank_options_default(&ro);
            ro.C = C_GRID[c] / (double)np;
            ro.monitor = opt->monitor;
            affect_rank_stats rs;
            st = affect_rank_fit(U, n, d, pairs, np, &ro, w, &rs, err);
            if (st != AFFECT_OK)
                goto cleanup;
            for (uint32_t i = 0; i < n; i++)
                score[i] = dotp(w, U + (size_t)i * d, d);
            for (uint32_t i = 0; i < n; i++) {
                if (fold[i] != f)
                    continue;
                for (uint32_t j = 0; j < n; j++) {
                    if (lv[j] == lv[i] || (grp && grp[j] != grp[i]))
                        continue;
                    total++;
                    right += lv[i] > lv[j] ? score[i] > score[j] : score[j] > score[i];
                }
            }
        }
        if (total > 0 && (!any || right > best)) {
            best = right;
            any = true;
            *C_out = C_GRID[c];
        }
    }
cleanup:
    affect_free(pairs);
    affect_free(block);
    return st;
}

/* lab_mean and lab_sd from the n raw Laban vectors L (NaN = missing): the mean and population
 * standard deviation of the values present; a component missing everywhere gets mean 0, one
 * with a zero or undefined deviation sd 1. With both feature blocks, kf_weight makes the
 * keyframe block's total training variance equal the Laban block's. */
static void laban_stats(affect_strength *s, const double *L, uint32_t n)
{
    double vl = 0;
    for (uint32_t k = 0; k < AFFECT_LABAN_N; k++) {
        double mu = 0, var = 0;
        uint32_t c = 0;
        for (uint32_t i = 0; i < n; i++)
            if (isfinite(L[(size_t)i * AFFECT_LABAN_N + k])) {
                mu += L[(size_t)i * AFFECT_LABAN_N + k];
                c++;
            }
        mu = c ? mu / c : 0;
        for (uint32_t i = 0; i < n; i++) {
            double v = L[(size_t)i * AFFECT_LABAN_N + k];
            if (isfinite(v))
                var += (v - mu) * (v - mu);
        }
        var = c ? var / c : 0;
        s->lab_mean[k] = mu;
        s->lab_sd[k] = var > 0 && isfinite(var) ? sqrt(var) : 1;
        if (var > 0 && isfinite(var)) /* the standardized block's variance: present share */
            vl += (double)c / n;
    }
    s->kf_weight = 0;
    if (s->features == AFFECT_STRENGTH_FEAT_BOTH) {
        double vk = 0;
        for (uint32_t c = 0; c < s->pdim; c++) {
            double mu = 0, var = 0;
            for (uint32_t i = 0; i < n; i++)
                mu += s->train_z[(size_t)i * s->pdim + c] / n;
            for (uint32_t i = 0; i < n; i++) {
                double d = s->train_z[(size_t)i * s->pdim + c] - mu;
                var += d * d / n;
            }
            vk += var;
        }
        s->kf_weight = vk > 0 && vl > 0 ? sqrt(vl / vk) : 1;
    }
}

affect_status affect_strength_train(const affect_motion *const *motions, const int32_t *level,
                                    const uint32_t *group, uint32_t n,
                                    const char *const *level_names, uint32_t n_levels,
                                    const affect_strength_options *opt, affect_strength **out,
                                    affect_error *err)
{
    *out = NULL;
    affect_strength_options def;
    if (!opt) {
        affect_strength_options_default(&def);
        opt = &def;
    }
    if (opt->keyframes < 2 || opt->keyframes > AFFECT_KEYFRAMES_MAX)
        return affect_fail(err, AFFECT_ERR_INVALID, "keyframes must be from 2 to %u (got %u)",
                           AFFECT_KEYFRAMES_MAX, opt->keyframes);
    if (opt->pca_dims > AFFECT_STRENGTH_MAX_PCA)
        return affect_fail(err, AFFECT_ERR_INVALID, "pca_dims must be from 0 to %u (got %u)",
                           AFFECT_STRENGTH_MAX_PCA, opt->pca_dims);
    if (!(isfinite(opt->C) && opt->C > 0))
        return affect_fail(err, AFFECT_ERR_INVALID, "C must be finite and > 0 (got %g)", opt->C);
    if (!(opt->fraction > 0 && opt->fraction <= 1))
        return affect_fail(err, AFFECT_ERR_INVALID, "fraction must be in (0, 1] (got %g)",
                           opt->fraction);
    if (opt->descriptors > AFFECT_DESC_ALL)
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "descriptors must be a mask of 0 to %u (got %u)",
                           (unsigned)AFFECT_DESC_ALL, opt->descriptors);
    if (opt->features > AFFECT_STRENGTH_FEAT_FISHER)
        return affect_fail(err, AFFECT_ERR_INVALID, "features must be 0 to 3 (got %d)",
                           (int)opt->features);
    if (n_levels < 2 || n_levels > AFFECT_STRENGTH_MAX_LEVELS)
        return affect_fail(err, AFFECT_ERR_INVALID, "the order must have 2 to %u labels (got %u)",
                           AFFECT_STRENGTH_MAX_LEVELS, n_levels);
    /* the motions used */
    uint32_t used = 0, first = UINT32_MAX;
    for (uint32_t i = 0; i < n; i++) {
        if (level[i] >= (int32_t)n_levels)
            return affect_fail(err, AFFECT_ERR_RANGE, "motion %u: level %d of %u", i, (int)level[i],
                               n_levels);
        if (level[i] >= 0) {
            used++;
            if (first == UINT32_MAX)
                first = i;
        }
    }
    if (used < 2)
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "need at least 2 motions with a label of the order (got %u)", used);
    const affect_motion *m0 = motions[first];
    uint32_t J = m0->n_joints, q = opt->keyframes;
    size_t D;
    if (!affect_mul_size((size_t)6 * q, J, &D) || D > AFFECT_STRENGTH_MAX_DIM)
        return affect_fail(err, AFFECT_ERR_RANGE, "%u keyframes of %u joints is too many", q, J);
    affect_strength *s = affect_calloc(1, sizeof *s);
    if (!s)
        return affect_nomem(err);
    affect_status st = AFFECT_OK;
    double *X = NULL, *Z = NULL, *work = NULL, *Lab = NULL, *U = NULL;
    bool fisher = opt->features == AFFECT_STRENGTH_FEAT_FISHER;
    bool lab_on = opt->features != AFFECT_STRENGTH_FEAT_KEYFRAMES && !fisher;
    uint32_t *kf = NULL, *idx = NULL, *grp = NULL;
    int32_t *lv = NULL;
    affect_rank_pair *pairs = NULL;
    size_t n_pairs = 0;
    s->n_joints = J;
    s->keyframes = q;
    s->dim = (uint32_t)D;
    s->n_levels = n_levels;
    s->n_train = used;
    s->C = opt->C;
    s->features = opt->features;
    s->fps = m0->fps;
    memcpy(s->unit, m0->unit, sizeof s->unit);
    s->pca = false; /* the PCA arrays are made by pca_fit */
    s->relative = opt->relative;
    s->root = opt->relative ? root_joint(m0) : 0;
    s->pdim = opt->pca_dims == 0 ? (uint32_t)D : 1;
    s->regression = AFFECT_STRENGTH_REG_LOCAL_LINEAR; /* alpha made by fit_regression */
    if (!alloc_arrays(s)) {
        st = affect_nomem(err);
        goto cleanup;
    }
    for (uint32_t j = 0; j < J; j++) {
        s->names[j] = affect_strndup(m0->names[j], strlen(m0->names[j]));
        if (!s->names[j]) {
            st = affect_nomem(err);
            goto cleanup;
        }
        s->parents[j] = m0->parents[j];
    }
    for (uint32_t l = 0; l < n_levels; l++) {
        s->level_names[l] = affect_strndup(level_names[l], strlen(level_names[l]));
        if (!s->level_names[l]) {
            st = affect_nomem(err);
            goto cleanup;
        }
    }
    X = affect_malloc_array((size_t)used * D, sizeof(double));
    kf = affect_malloc_array(q, sizeof *kf);
    idx = affect_malloc_array(used, sizeof *idx);
    lv = affect_malloc_array(used, sizeof *lv);
    grp = group ? affect_malloc_array(used, sizeof *grp) : NULL;
    work = affect_malloc_array(D, sizeof(double));
    Lab = lab_on ? affect_malloc_array((size_t)used * AFFECT_LABAN_N, sizeof(double)) : NULL;
    if (!X || !kf || !idx || !lv || (group && !grp) || !work || (lab_on && !Lab)) {
        st = affect_nomem_of(err, (size_t)used, D * sizeof(double), "the %u x %zu features", used,
                             D);
        goto cleanup;
    }
    uint32_t k = 0;
    for (uint32_t i = 0; i < n; i++) {
        if (level[i] < 0)
            continue;
        st = affect_monitor_check(opt->monitor, err);
        if (st != AFFECT_OK)
            goto cleanup;
        affect_monitor_report(opt->monitor, "features", k, used);
        st = check_skeleton(J, s->names, motions[i], err);
        if (st == AFFECT_OK)
            st = motion_features(motions[i], q, s->relative, s->root, X + (size_t)k * D, kf, NULL,
                                 NULL, opt->monitor, err);
        if (st == AFFECT_OK && lab_on)
            st = laban_raw(motions[i], Lab + (size_t)k * AFFECT_LABAN_N, opt->monitor, err);
        if (st != AFFECT_OK) {
            affect_prefix(err, "motion %u", i);
            goto cleanup;
        }
        for (uint32_t a = 1; a < q; a++)
            s->seg_dt[a - 1] += (double)(kf[a] - kf[a - 1]) / motions[i]->fps / used;
        idx[k] = i;
        lv[k] = level[i];
        if (grp)
            grp[k] = group[i];
        k++;
    }
    /* standardization: X is divided in place for the PCA fit, then restored */
    if (opt->standardize) {
        s->scale = affect_malloc_array(D, sizeof(double));
        if (!s->scale) {
            st = affect_nomem(err);
            goto cleanup;
        }
        double top = 0, mean_sd = 0;
        for (size_t c = 0; c < D; c++) {
            double mu = 0, var = 0;
            for (uint32_t i = 0; i < used; i++)
                mu += X[(size_t)i * D + c] / used;
            for (uint32_t i = 0; i < used; i++)
                var += (X[(size_t)i * D + c] - mu) * (X[(size_t)i * D + c] - mu) / used;
            s->scale[c] = sqrt(var);
            mean_sd += s->scale[c] / (double)D;
            if (s->scale[c] > top)
                top = s->scale[c];
        }
        for (size_t c = 0; c < D; c++) {
            if (!(s->scale[c] > AFFECT_STRENGTH_SD_FLOOR * top))
                s->scale[c] = 1; /* constant features (the first keyframe's velocity) */
            else if (s->scale[c] < AFFECT_STRENGTH_SD_REL * mean_sd)
                s->scale[c] = AFFECT_STRENGTH_SD_REL * mean_sd; /* no amplified noise */
        }
    }
    /* PCA */
    if (opt->pca_dims > 0) {
        if (s->scale)
            for (uint32_t i = 0; i < used; i++)
                for (size_t c = 0; c < D; c++)
                    X[(size_t)i * D + c] /= s->scale[c];
        affect_free(s->train_z);
        affect_free(s->w);
        affect_free(s->zbar);
        s->train_z = s->w = s->zbar = NULL;
        st = pca_fit(s, X, used, opt->pca_dims, err);
        if (st != AFFECT_OK)
            goto cleanup;
        if (s->scale)
            for (uint32_t i = 0; i < used; i++)
                for (size_t c = 0; c < D; c++)
                    X[(size_t)i * D + c] *= s->scale[c];
        s->pca = true;
        s->train_z = affect_calloc((size_t)used * s->pdim, sizeof(double));
        s->w = affect_calloc(affect_strength_rank_dim(s), sizeof(double));
        s->zbar = affect_calloc(s->pdim, sizeof(double));
        if (!s->train_z || !s->w || !s->zbar) {
            st = affect_nomem(err);
            goto cleanup;
        }
    } else {
        s->pca_variance = 1;
    }
    for (uint32_t i = 0; i < used; i++)
        project(s, X + (size_t)i * D, s->train_z + (size_t)i * s->pdim, work);
    /* the pairs */
    st = affect_rank_pairs(lv, grp, used, opt->similar, opt->fraction, opt->seed, &pairs, &n_pairs,
                           err);
    if (st != AFFECT_OK)
        goto cleanup;
    size_t n_ordered = 0;
    for (size_t p = 0; p < n_pairs; p++)
        n_ordered += !pairs[p].similar;
    if (n_ordered == 0) {
        st = affect_fail(err, AFFECT_ERR_INVALID,
                         "no ordered pairs: the motions need at least two different labels%s",
                         group ? " within one content" : "");
        goto cleanup;
    }
    /* the ranker's inputs: U = train_z (keyframes), the standardized Laban vectors (after the
     * weighted train_z with both), or the Fisher representations */
    if (fisher) {
        st = fisher_train(motions, idx, lv, used, level_names, n_levels, opt->descriptors,
                          opt->monitor, &s->fisher, &U, err);
        affect_free(s->w);
        s->w = st == AFFECT_OK ? affect_calloc(affect_strength_rank_dim(s), sizeof(double)) : NULL;
        if (st == AFFECT_OK && !s->w)
            st = affect_nomem(err);
        if (st != AFFECT_OK)
            goto cleanup;
    }
    uint32_t rd = affect_strength_rank_dim(s);
    const double *rank_x = fisher ? U : s->train_z;
    if (lab_on) {
        laban_stats(s, Lab, used);
        U = affect_malloc_array((size_t)used * rd, sizeof(double));
        if (!U) {
            st = affect_nomem(err);
            goto cleanup;
        }
        for (uint32_t i = 0; i < used; i++)
            rank_input(s, s->train_z + (size_t)i * s->pdim, Lab + (size_t)i * AFFECT_LABAN_N,
                       U + (size_t)i * rd);
        rank_x = U;
    }
    /* the ranker */
    affect_rank_options ro;
    affect_rank_options_default(&ro);
    /* Laban features: C multiplies the mean pair loss (the right C of the sum scales like one
     * over the number of pairs; docs/EVALUATION.md); keyframes keep the sum (their accuracy
     * does not depend on C) */
    if (lab_on && opt->cv_C) {
        double C = opt->C;
        st = cv_choose_C(rank_x, used, rd, lv, grp, n_levels, opt, &C, err);
        if (st != AFFECT_OK) {
            affect_prefix(err, "cross-validation of C");
            goto cleanup;
        }
        s->C = C;
        s->cv_C = true;
    }
    ro.C = lab_on ? s->C / (double)n_pairs : opt->C;
    ro.monitor = opt->monitor;
    st = affect_rank_fit(rank_x, used, rd, pairs, n_pairs, &ro, s->w, &s->stats, err);
    if (st != AFFECT_OK) {
        affect_prefix(err, "ranker");
        goto cleanup;
    }
    for (uint32_t i = 0; i < used; i++) {
        s->train_r[i] = dotp(s->w, rank_x + (size_t)i * rd, rd);
        s->level_strength[lv[i]] += s->train_r[i];
        s->level_count[lv[i]]++;
    }
    for (uint32_t l = 0; l < n_levels; l++)
        s->level_strength[l] = s->level_count[l] ? s->level_strength[l] / s->level_count[l] : 0;
    st = affect_strength_fit_regression(s, opt->regression, opt->monitor, err);
    if (st != AFFECT_OK)
        affect_prefix(err, "regression");
cleanup:
    affect_free(X);
    affect_free(Z);
    affect_free(work);
    affect_free(Lab);
    affect_free(U);
    affect_free(kf);
    affect_free(idx);
    affect_free(grp);
    affect_free(lv);
    affect_free(pairs);
    if (st != AFFECT_OK)
        affect_strength_free(s);
    else
        *out = s;
    return st;
}

/* ---- synthesis and editing ---- */

/* Output frame f of T spans the keyframe times tau[0 .. q): the segment seg (advanced from its
 * previous value, frames in increasing order) and the fraction u ∈ [0, 1] within it. */
static void frame_segment(const double *tau, uint32_t q, uint32_t T, uint32_t f, uint32_t *seg,
                          double *u)
{
    double t = T > 1 ? tau[q - 1] * f / (T - 1) : 0;
    while (*seg + 2 < q && t > tau[*seg + 1])
        (*seg)++;
    double h = tau[*seg + 1] - tau[*seg], v = h > 0 ? (t - tau[*seg]) / h : 0;
    *u = v < 0 ? 0 : v > 1 ? 1 : v;
}

/* A positions-only motion of the model's skeleton with T frames (positions unset). */
static affect_status new_motion(const affect_strength *s, uint32_t T, double fps,
                                affect_motion **out, affect_error *err)
{
    affect_motion *m = NULL;
    affect_status st = affect_motion_create(T, s->n_joints, fps, &m, err);
    for (uint32_t j = 0; st == AFFECT_OK && j < s->n_joints; j++)
        st = affect_motion_set_name(m, j, s->names[j], strlen(s->names[j]), err);
    if (st == AFFECT_OK)
        st = affect_motion_set_parents(m, s->parents, err);
    if (st == AFFECT_OK && s->unit[0])
        st = affect_motion_set_unit(m, s->unit, err);
    if (st != AFFECT_OK) {
        affect_motion_free(m);
        return st;
    }
    *out = m;
    return AFFECT_OK;
}

/* Durations of the q − 1 segments of features x: (Δk·v)/(v·v), within [ref/10, ref × 10] of
 * ref[i], ref[i] itself when v ≈ 0. */
static void durations(const affect_strength *s, const double *x, const double *ref, double *dt)
{
    uint32_t D3 = 3 * s->n_joints;
    for (uint32_t i = 1; i < s->keyframes; i++) {
        const double *k1 = x + (size_t)i * 2 * D3, *k0 = x + (size_t)(i - 1) * 2 * D3;
        const double *v = k1 + D3;
        double vv = 0, kv = 0;
        for (uint32_t c = 0; c < D3; c++) {
            vv += v[c] * v[c];
            kv += (k1[c] - k0[c]) * v[c];
        }
        double r = ref[i - 1], t = vv > AFFECT_STRENGTH_V_MIN ? kv / vv : r;
        if (!(t > r / DT_CLAMP))
            t = r / DT_CLAMP;
        if (t > r * DT_CLAMP)
            t = r * DT_CLAMP;
        dt[i - 1] = t;
    }
}

/* The rigid projection of raw (freed): bone lengths from reference when given (an edited
 * motion keeps its own skeleton's), else the median over raw's frames. */
static affect_status make_rigid(affect_motion *raw, bool rigid, const affect_motion *reference,
                                affect_motion **out, affect_monitor *mon, affect_error *err)
{
    if (!rigid) {
        *out = raw;
        return AFFECT_OK;
    }
    affect_rigid_options ro;
    affect_rigid_options_default(&ro);
    ro.monitor = mon;
    if (reference) {
        ro.lengths = AFFECT_RIGID_REFERENCE;
        ro.reference = reference;
    }
    affect_status st = affect_motion_rigid(raw, &ro, out, err);
    affect_motion_free(raw);
    return st;
}

static affect_status synthesize_once(const affect_strength *s, const affect_motion *unused,
                                     double strength, bool rigid, affect_motion **out,
                                     affect_monitor *mon, affect_error *err)
{
    (void)unused;
    *out = NULL;
    if (!isfinite(strength))
        return affect_fail(err, AFFECT_ERR_INVALID, "the strength must be finite");
    uint32_t q = s->keyframes, D3 = 3 * s->n_joints;
    double *z = affect_malloc_array(s->pdim, sizeof(double));
    double *x = affect_malloc_array(s->dim, sizeof(double));
    double *tau = affect_malloc_array(q, sizeof(double));
    double *tan = affect_malloc_array((size_t)q * D3, sizeof(double));
    double *pose = affect_malloc_array(D3, sizeof(double));
    affect_motion *m = NULL;
    affect_status st = AFFECT_OK;
    if (!z || !x || !tau || !tan || !pose) {
        st = affect_nomem(err);
        goto cleanup;
    }
    affect_strength_predict(s, strength, z);
    unproject(s, z, x);
    tau[0] = 0;
    durations(s, x, s->seg_dt, tan); /* tan as scratch for the q − 1 durations */
    for (uint32_t i = 1; i < q; i++)
        tau[i] = tau[i - 1] + tan[i - 1];
    /* Hermite tangents: central differences, one-sided at the ends */
    for (uint32_t i = 0; i < q; i++) {
        uint32_t a = i > 0 ? i - 1 : 0, b = i + 1 < q ? i + 1 : q - 1;
        const double *ka = x + (size_t)a * 2 * D3, *kb = x + (size_t)b * 2 * D3;
        double span = tau[b] - tau[a];
        for (uint32_t c = 0; c < D3; c++)
            tan[(size_t)i * D3 + c] = span > 0 ? (kb[c] - ka[c]) / span : 0;
    }
    double total = tau[q - 1] * s->fps;
    if (!(total < MAX_OUT_FRAMES)) {
        st = affect_fail(err, AFFECT_ERR_RANGE, "the synthesized motion would be too long");
        goto cleanup;
    }
    uint32_t T = (uint32_t)floor(total + 0.5) + 1;
    st = new_motion(s, T, s->fps, &m, err);
    if (st != AFFECT_OK)
        goto cleanup;
    uint32_t seg = 0;
    for (uint32_t f = 0; f < T; f++) {
        double u;
        frame_segment(tau, q, T, f, &seg, &u);
        double h = tau[seg + 1] - tau[seg];
        double h00 = 2 * u * u * u - 3 * u * u + 1, h10 = u * u * u - 2 * u * u + u;
        double h01 = -2 * u * u * u + 3 * u * u, h11 = u * u * u - u * u;
        const double *k0 = x + (size_t)seg * 2 * D3, *k1 = x + (size_t)(seg + 1) * 2 * D3;
        const double *m0 = tan + (size_t)seg * D3, *m1 = tan + (size_t)(seg + 1) * D3;
        float *p = m->pos + (size_t)f * D3;
        for (uint32_t c = 0; c < D3; c++)
            pose[c] = h00 * k0[c] + h10 * h * m0[c] + h01 * k1[c] + h11 * h * m1[c];
        if (s->relative)
            from_relative(pose, s->n_joints, s->root);
        for (uint32_t c = 0; c < D3; c++)
            p[c] = (float)pose[c];
    }
    st = make_rigid(m, rigid, NULL, out, mon, err);
    m = NULL;
cleanup:
    affect_motion_free(m);
    affect_free(z);
    affect_free(x);
    affect_free(tau);
    affect_free(tan);
    affect_free(pose);
    return st;
}

static affect_status edit_once(const affect_strength *s, const affect_motion *m, double strength,
                               bool rigid, affect_motion **out, affect_monitor *mon,
                               affect_error *err)
{
    *out = NULL;
    if (!isfinite(strength))
        return affect_fail(err, AFFECT_ERR_INVALID, "the strength must be finite");
    affect_status st = check_skeleton(s->n_joints, s->names, m, err);
    if (st != AFFECT_OK)
        return st;
    uint32_t q = s->keyframes, D3 = 3 * s->n_joints;
    double *x = affect_malloc_array(s->dim, sizeof(double));
    double *xn = affect_malloc_array(s->dim, sizeof(double));
    double *z = affect_malloc_array(s->pdim, sizeof(double));
    double *dz = affect_malloc_array(s->pdim, sizeof(double));
    double *work = affect_malloc_array(s->dim, sizeof(double));
    double *dt0 = affect_malloc_array(q, sizeof(double));
    double *dt1 = affect_malloc_array(q, sizeof(double));
    double *tau = affect_malloc_array(q, sizeof(double));
    uint32_t *kf = affect_malloc_array(q, sizeof *kf);
    double *Y = NULL;
    affect_motion *e = NULL;
    if (!x || !xn || !z || !dz || !work || !dt0 || !dt1 || !tau || !kf) {
        st = affect_nomem(err);
        goto cleanup;
    }
    affect_normalize_transform tf;
    st = motion_features(m, q, s->relative, s->root, x, kf, &Y, &tf, mon, err);
    if (st != AFFECT_OK)
        goto cleanup;
    project(s, x, z, work);
    if (s->features == AFFECT_STRENGTH_FEAT_KEYFRAMES) {
        double ww = dotp(s->w, s->w, s->pdim), r = dotp(s->w, z, s->pdim);
        for (uint32_t c = 0; c < s->pdim; c++)
            dz[c] = ww > 0 ? (strength - r) * s->w[c] / ww : 0;
    } else {
        /* both blocks: the ranker does not act on z alone; move z by the regression's
         * f(s') − f(r(m)) */
        double r;
        st = affect_strength_score(s, m, &r, mon, err);
        if (st != AFFECT_OK)
            goto cleanup;
        affect_strength_predict(s, strength, dz);
        affect_strength_predict(s, r, work);
        for (uint32_t c = 0; c < s->pdim; c++)
            dz[c] -= work[c];
    }
    if (s->pca)
        AFFECT_BLAS(cblas_dgemv(CblasRowMajor, CblasTrans, (int)s->pdim, (int)s->dim, 1.0, s->comps,
                                (int)s->dim, dz, 1, 0.0, work, 1));
    else
        memcpy(work, dz, sizeof(double) * s->dim);
    for (uint32_t c = 0; c < s->dim; c++)
        xn[c] = x[c] + (s->scale ? work[c] * s->scale[c] : work[c]);
    for (uint32_t i = 1; i < q; i++)
        dt0[i - 1] = (double)(kf[i] - kf[i - 1]) / m->fps;
    durations(s, xn, dt0, dt1);
    tau[0] = 0;
    for (uint32_t i = 1; i < q; i++)
        tau[i] = tau[i - 1] + dt1[i - 1];
    double total = tau[q - 1] * m->fps;
    if (!(total < MAX_OUT_FRAMES)) {
        st = affect_fail(err, AFFECT_ERR_RANGE, "the edited motion would be too long");
        goto cleanup;
    }
    uint32_t T = (uint32_t)floor(total + 0.5) + 1;
    /* x's pose parts become the keyframes' displacements k' − k, in absolute coordinates */
    for (uint32_t i = 0; i < q; i++) {
        double *d = x + (size_t)i * 2 * D3;
        const double *kn = xn + (size_t)i * 2 * D3;
        for (uint32_t c = 0; c < D3; c++)
            d[c] = kn[c] - d[c];
        if (s->relative)
            from_relative(d, s->n_joints, s->root);
    }
    st = new_motion(s, T, m->fps, &e, err);
    if (st != AFFECT_OK)
        goto cleanup;
    uint32_t seg = 0;
    for (uint32_t f = 0; f < T; f++) {
        double a;
        frame_segment(tau, q, T, f, &seg, &a);
        double src = kf[seg] + a * (double)(kf[seg + 1] - kf[seg]);
        uint32_t f0 = (uint32_t)floor(src), f1 = f0 + 1 < m->n_frames ? f0 + 1 : f0;
        double b = src - f0;
        const double *d0 = x + (size_t)seg * 2 * D3, *d1 = x + (size_t)(seg + 1) * 2 * D3;
        for (uint32_t j = 0; j < s->n_joints; j++) {
            double pn[3];
            for (uint32_t c = 0; c < 3; c++) {
                uint32_t o = 3 * j + c;
                double y = (1 - b) * Y[(size_t)f0 * D3 + o] + b * Y[(size_t)f1 * D3 + o];
                pn[c] = y + (1 - a) * d0[o] + a * d1[o];
                pn[c] *= tf.scale;
            }
            /* back: p = Rᵀ p' scale + origin */
            float *p = e->pos + ((size_t)f * s->n_joints + j) * 3;
            for (int c = 0; c < 3; c++)
                p[c] = (float)(tf.rot[c] * pn[0] + tf.rot[3 + c] * pn[1] + tf.rot[6 + c] * pn[2] +
                               tf.origin[c]);
        }
    }
    st = make_rigid(e, rigid, m, out, mon, err);
    e = NULL;
cleanup:
    affect_motion_free(e);
    affect_free(Y);
    affect_free(x);
    affect_free(xn);
    affect_free(z);
    affect_free(dz);
    affect_free(work);
    affect_free(dt0);
    affect_free(dt1);
    affect_free(tau);
    affect_free(kf);
    return st;
}

typedef affect_status (*make_fn)(const affect_strength *s, const affect_motion *m, double strength,
                                 bool rigid, affect_motion **out, affect_monitor *mon,
                                 affect_error *err);

/* Runs make at the target, measures the result's strength, and corrects the target by the
 * miss (t ← t + (s − r)) up to AFFECT_STRENGTH_CORRECTIONS times while the miss shrinks and is
 * above AFFECT_STRENGTH_TOL; keeps the closest result. The miss comes from what the feature
 * step cannot see: the keyframes chosen again on the new motion and the rigid projection. */
static affect_status hit_target(const affect_strength *s, const affect_motion *m, double strength,
                                bool rigid, make_fn make, affect_motion **out, affect_monitor *mon,
                                affect_error *err)
{
    *out = NULL;
    if (!isfinite(strength))
        return affect_fail(err, AFFECT_ERR_INVALID, "the strength must be finite");
    affect_motion *best = NULL;
    double best_miss = INFINITY, t = strength;
    affect_status st = AFFECT_OK;
    for (uint32_t round = 0; round <= AFFECT_STRENGTH_CORRECTIONS; round++) {
        affect_motion *cand = NULL;
        double r;
        st = make(s, m, t, rigid, &cand, mon, err);
        if (st == AFFECT_OK)
            st = affect_strength_score(s, cand, &r, mon, err);
        if (st != AFFECT_OK) {
            affect_motion_free(cand);
            if (best && st != AFFECT_ERR_NOMEM && st != AFFECT_ERR_INTERRUPTED) {
                st = AFFECT_OK; /* a correction that cannot be measured: keep the best so far */
                break;
            }
            affect_motion_free(best);
            return st;
        }
        double miss = fabs(strength - r);
        if (miss < best_miss) {
            affect_motion_free(best);
            best = cand;
            best_miss = miss;
        } else {
            affect_motion_free(cand);
            break;
        }
        if (miss <= AFFECT_STRENGTH_TOL)
            break;
        t += strength - r;
    }
    *out = best;
    return st;
}

/* ---- editing by the Fisher representation ---- */

/* The gradient of r = wᵀu with respect to the observations x (T × dim) into g (T × dim), u the
 * motion's normalized representation under s->fisher: through the means and (diagonal)
 * covariance scores of every class HMM, d/dx_td of Σ_t γ_tk (x_td − μ_kd)/σ²_kd is
 * γ_tk/σ²_kd and of ½ Σ_t γ_tk ((x_td − μ_kd)² − σ²_kd)/σ⁴_kd is γ_tk (x_td − μ_kd)/σ⁴_kd,
 * each times w/scale for its entry (0 where the z-score is at its limit), the posteriors γ
 * held fixed; the probability groups and the descriptors (functions of γ and of the motion
 * as a whole) add nothing. Needs diagonal class HMMs. */
static affect_status fisher_gradient(const affect_strength *s, const double *x, uint32_t T,
                                     const double *u, double *g, affect_monitor *mon,
                                     affect_error *err)
{
    const affect_classifier *c = s->fisher;
    const affect_classifier_config *cc = affect_classifier_get_config(c);
    const double *scale = cc->zscore ? affect_classifier_norm_scale(c) : NULL;
    uint32_t C = affect_classifier_n_classes(c);
    size_t part = affect_classifier_part_dim(c), m = cc->hmm.dim;
    if (cc->hmm.cov != AFFECT_HMM_DIAG)
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "editing by the Fisher representation needs diagonal class HMMs");
    size_t K = (size_t)cc->hmm.n_states * cc->hmm.n_mix;
    double *gamma = affect_malloc_array((size_t)T * K, sizeof(double));
    double *A = affect_calloc(2 * K * m, sizeof(double)); /* means' and covariances' weights */
    affect_status st = AFFECT_OK;
    if (!gamma || !A) {
        st = affect_nomem(err);
        goto done;
    }
    memset(g, 0, (size_t)T * m * sizeof *g);
    for (uint32_t k = 0; k < C && st == AFFECT_OK; k++) {
        const affect_hmm *h = affect_classifier_hmm(c, k);
        const affect_hmm_config *hc = affect_hmm_get_config(h);
        memset(A, 0, 2 * K * m * sizeof *A);
        for (size_t i = 0; i < part && st == AFFECT_OK; i++) {
            size_t e = (size_t)k * part + i;
            if (cc->score_clip > 0 && fabs(u[e]) >= cc->score_clip)
                continue;
            affect_fisher_entry fe;
            st = affect_fisher_describe(hc, cc->groups, i, &fe, err);
            double a = s->w[e] / (scale ? scale[e] : 1.0);
            size_t comp = (size_t)fe.state * hc->n_mix + fe.other;
            if (fe.group == AFFECT_FISHER_MEANS)
                A[comp * m + fe.r] += a;
            else if (fe.group == AFFECT_FISHER_COVS)
                A[(K + comp) * m + fe.r] += a;
        }
        double ll;
        if (st == AFFECT_OK)
            st = affect_hmm_posteriors(h, x, T, gamma, NULL, &ll, mon, err);
        const double *mu = affect_hmm_means(h), *var = affect_hmm_covariances(h);
        for (uint32_t t = 0; t < T && st == AFFECT_OK; t++) {
            const double *xt = x + (size_t)t * m;
            double *gt = g + (size_t)t * m;
            for (size_t q = 0; q < K; q++) {
                double y = gamma[(size_t)t * K + q];
                if (y == 0)
                    continue;
                const double *am = A + q * m, *ac = A + (K + q) * m;
                const double *mq = mu + q * m, *vq = var + q * m;
                for (size_t d = 0; d < m; d++)
                    gt[d] += y * (am[d] + ac[d] * (xt[d] - mq[d]) / vq[d]) / vq[d];
            }
        }
    }
done:
    affect_free(gamma);
    affect_free(A);
    return st;
}

/* A Fisher model's edit of m toward strength target (an "once" for hit_target): steps along
 * the gradient of r with respect to the joint positions (fisher_gradient, taken back to the
 * joints by affect_features_position_gradient), each the Newton step of the linearized r,
 * (target − r) ∇r / ‖∇r‖², halved while it does not bring r closer (at most FISHER_HALVINGS
 * times), FISHER_STEPS steps at most; then the nearest rigid motion with m's bone lengths. The
 * timing, the path and every frame count stay m's. */
#define FISHER_STEPS 12u
#define FISHER_HALVINGS 4u
static affect_status fisher_edit_once(const affect_strength *s, const affect_motion *m,
                                      double target, bool rigid, affect_motion **out,
                                      affect_monitor *mon, affect_error *err)
{
    *out = NULL;
    const affect_classifier *c = s->fisher;
    const affect_features *feat = affect_classifier_features(c);
    uint32_t T = m->n_frames, J = m->n_joints;
    size_t D = affect_classifier_dim(c), np = (size_t)T * J * 3;
    double *u = affect_malloc_array(D, sizeof(double));
    double *P = affect_malloc_array(np, sizeof(double));
    double *x = NULL, *desc = NULL, *g = NULL;
    affect_motion *cur = NULL, *trial = NULL;
    affect_status st = AFFECT_OK;
    if (!u || !P) {
        st = affect_nomem(err);
        goto done;
    }
    st = new_motion(s, T, m->fps, &cur, err); /* positions only: the rotations would go stale */
    if (st == AFFECT_OK)
        memcpy(cur->pos, m->pos, np * sizeof *cur->pos);
    double r = NAN;
    for (uint32_t step = 0; st == AFFECT_OK && step <= FISHER_STEPS; step++) {
        affect_free(x);
        affect_free(desc);
        x = desc = NULL;
        uint32_t n;
        st = affect_classifier_observe(c, cur, &x, &n, &desc, mon, err);
        if (st == AFFECT_OK) {
            affect_classifier_out o = {0};
            o.fisher = u;
            st = affect_classifier_eval(c, x, n, desc, false, &o, mon, err);
        }
        if (st != AFFECT_OK)
            break;
        r = dotp(s->w, u, D);
        if (step == FISHER_STEPS || fabs(target - r) <= AFFECT_STRENGTH_TOL)
            break;
        if (!g &&
            !(g = affect_malloc_array((size_t)n, affect_features_dim(feat) * sizeof(double)))) {
            st = affect_nomem(err);
            break;
        }
        st = fisher_gradient(s, x, n, u, g, mon, err);
        if (st == AFFECT_OK)
            st = affect_features_position_gradient(feat, cur, g, P, mon, err);
        if (st != AFFECT_OK)
            break;
        double nn = dotp(P, P, np);
        if (!(nn > 0) || !isfinite(nn))
            break;
        double eta = (target - r) / nn, best = fabs(target - r);
        bool moved = false;
        for (uint32_t h = 0; h <= FISHER_HALVINGS && st == AFFECT_OK; h++, eta /= 2) {
            affect_motion_free(trial);
            trial = NULL;
            st = affect_motion_clone(cur, &trial, err);
            if (st != AFFECT_OK)
                break;
            for (size_t i = 0; i < np; i++)
                trial->pos[i] = (float)((double)trial->pos[i] + eta * P[i]);
            if (rigid) { /* measured as it will come out: rigid, back to positions only */
                affect_motion *rg = NULL;
                st = make_rigid(trial, true, m, &rg, mon, err);
                trial = NULL;
                if (st == AFFECT_OK)
                    st = new_motion(s, T, m->fps, &trial, err);
                if (st == AFFECT_OK)
                    memcpy(trial->pos, rg->pos, np * sizeof *trial->pos);
                affect_motion_free(rg);
                if (st != AFFECT_OK)
                    break;
            }
            double rt;
            st = fisher_of(c, trial, u, mon, err);
            if (st != AFFECT_OK)
                break;
            rt = dotp(s->w, u, D);
            if (fabs(target - rt) < best) {
                affect_motion_free(cur);
                cur = trial;
                trial = NULL;
                moved = true;
                break;
            }
        }
        if (!moved)
            break;
    }
    if (st == AFFECT_OK) {
        st = make_rigid(cur, rigid, m, out, mon, err);
        cur = NULL;
    }
done:
    affect_motion_free(cur);
    affect_motion_free(trial);
    affect_free(u);
    affect_free(P);
    affect_free(x);
    affect_free(desc);
    affect_free(g);
    return st;
}

/* Synthesis and editing steer the keyframe features: a ranker of the Laban vector alone does not
 * follow them (docs/EVALUATION.md, "Laban features": Spearman 0.37 synthesized, 0.52 edited),
 * nor does one of the recognizer's representation, which they cannot steer at all. */
static affect_status need_keyframes(const affect_strength *s, affect_motion **out,
                                    affect_error *err)
{
    *out = NULL;
    if (s->features == AFFECT_STRENGTH_FEAT_KEYFRAMES || s->features == AFFECT_STRENGTH_FEAT_BOTH)
        return AFFECT_OK;
    if (s->features == AFFECT_STRENGTH_FEAT_FISHER)
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "the model ranks by the recognizer's Fisher representation, which "
                           "edits a motion but has none to synthesize from: train it with "
                           "\"features\": \"keyframes\" (or \"both\") to synthesize");
    return affect_fail(err, AFFECT_ERR_INVALID,
                       "the model ranks by the Laban vector alone, which synthesized and edited "
                       "motions do not follow: train it with \"features\": \"keyframes\" (or "
                       "\"both\") to synthesize or edit");
}

affect_status affect_strength_synthesize(const affect_strength *s, double strength, bool rigid,
                                         affect_motion **out, affect_monitor *mon,
                                         affect_error *err)
{
    affect_status st = need_keyframes(s, out, err);
    if (st != AFFECT_OK)
        return st;
    return hit_target(s, NULL, strength, rigid, synthesize_once, out, mon, err);
}

affect_status affect_strength_edit(const affect_strength *s, const affect_motion *m,
                                   double strength, bool rigid, affect_motion **out,
                                   affect_monitor *mon, affect_error *err)
{
    bool fisher = s->features == AFFECT_STRENGTH_FEAT_FISHER;
    affect_status st = fisher ? AFFECT_OK : need_keyframes(s, out, err);
    if (st == AFFECT_OK)
        st = check_skeleton(s->n_joints, s->names, m, err);
    if (st != AFFECT_OK)
        return st;
    return hit_target(s, m, strength, rigid, fisher ? fisher_edit_once : edit_once, out, mon, err);
}

/* ---- the BLOB ---- */

affect_status affect_strength_encode(const affect_strength *s, unsigned char **out, size_t *size,
                                     affect_error *err)
{
    *out = NULL;
    *size = 0;
    affect_bw w;
    affect_bw_init(&w);
    bool fisher = s->features == AFFECT_STRENGTH_FEAT_FISHER;
    bool lab = s->features != AFFECT_STRENGTH_FEAT_KEYFRAMES && !fisher;
    unsigned char *cls = NULL;
    size_t cls_size = 0;
    if (fisher) {
        affect_status st = affect_classifier_encode(s->fisher, &cls, &cls_size, err);
        if (st != AFFECT_OK)
            return st;
    }
    /* a keyframe model keeps version 1's layout, byte for byte, a Laban model version 2's */
    affect_bw_header(&w, AFFECT_STRENGTH_MAGIC,
                     fisher ? 3u
                     : lab  ? 2u
                            : 1u,
                     (s->pca ? FLAG_PCA : 0u) | (s->relative ? FLAG_RELATIVE : 0u) |
                         (s->scale ? FLAG_STANDARDIZE : 0u) | (lab ? FLAG_LABAN : 0u) |
                         (fisher ? FLAG_FISHER : 0u) |
                         (s->features == AFFECT_STRENGTH_FEAT_BOTH ? FLAG_BOTH : 0u) |
                         (s->cv_C ? FLAG_CV_C : 0u));
    affect_bw_u32(&w, s->n_joints);
    affect_bw_u32(&w, s->keyframes);
    affect_bw_u32(&w, s->dim);
    affect_bw_u32(&w, s->pdim);
    affect_bw_u32(&w, s->n_train);
    affect_bw_u32(&w, s->n_levels);
    affect_bw_u32(&w, (uint32_t)s->regression);
    affect_bw_u32(&w, s->root);
    affect_bw_f64(&w, s->fps);
    affect_bw_f64(&w, s->C);
    affect_bw_f64(&w, s->pca_variance);
    affect_bw_f64(&w, s->reg_h);
    affect_bw_f64(&w, s->reg_lambda);
    affect_bw_f64(&w, s->cv_kernel_ridge);
    affect_bw_f64(&w, s->cv_local_linear);
    affect_bw_f64(&w, s->cv_constant);
    affect_bw_u32(&w, s->stats.iterations);
    affect_bw_u32(&w, s->stats.halvings);
    affect_bw_u32(&w, s->stats.converged ? 1u : 0u);
    affect_bw_u32(&w, 0);
    affect_bw_u64(&w, s->stats.ordered);
    affect_bw_u64(&w, s->stats.similar);
    affect_bw_u64(&w, s->stats.correct);
    affect_bw_f64(&w, s->stats.objective);
    affect_bw_bytes(&w, s->unit, sizeof s->unit);
    for (uint32_t j = 0; j < s->n_joints; j++) {
        size_t len = strlen(s->names[j]);
        affect_bw_u32(&w, (uint32_t)s->parents[j]);
        affect_bw_u32(&w, (uint32_t)len);
        affect_bw_bytes(&w, s->names[j], len);
    }
    for (uint32_t l = 0; l < s->n_levels; l++) {
        size_t len = strlen(s->level_names[l]);
        affect_bw_u32(&w, (uint32_t)len);
        affect_bw_bytes(&w, s->level_names[l], len);
        affect_bw_f64(&w, s->level_strength[l]);
        affect_bw_u32(&w, s->level_count[l]);
    }
    if (s->scale)
        affect_bw_f64s(&w, s->scale, s->dim);
    if (s->pca) {
        affect_bw_f64s(&w, s->mean, s->dim);
        affect_bw_f64s(&w, s->comps, (size_t)s->pdim * s->dim);
    }
    affect_bw_f64s(&w, s->seg_dt, s->keyframes - 1);
    if (!fisher) /* (a Fisher model's w follows its recognizer, whose dimension it has) */
        affect_bw_f64s(&w, s->w, affect_strength_rank_dim(s));
    affect_bw_f64s(&w, s->train_r, s->n_train);
    affect_bw_f64s(&w, s->train_z, (size_t)s->n_train * s->pdim);
    affect_bw_f64s(&w, s->zbar, s->pdim);
    if (s->regression == AFFECT_STRENGTH_REG_KERNEL_RIDGE)
        affect_bw_f64s(&w, s->alpha, (size_t)s->n_train * s->pdim);
    if (lab) {
        affect_bw_f64s(&w, s->lab_mean, AFFECT_LABAN_N);
        affect_bw_f64s(&w, s->lab_sd, AFFECT_LABAN_N);
        affect_bw_f64(&w, s->kf_weight);
    }
    if (fisher) {
        affect_bw_u64(&w, cls_size);
        affect_bw_bytes(&w, cls, cls_size);
        affect_bw_f64s(&w, s->w, affect_strength_rank_dim(s));
    }
    affect_free(cls);
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

static bool read_name(affect_br *r, char **out, affect_error *err, const char *what, uint32_t k,
                      affect_status *st)
{
    uint32_t len;
    const unsigned char *p;
    if (!affect_br_u32(r, &len) || len > AFFECT_MOTION_MAX_NAME || !affect_br_bytes(r, &p, len)) {
        *st = affect_fail(err, AFFECT_ERR_FORMAT, "strength model truncated in %s %u", what, k);
        return false;
    }
    if (len == 0 || !affect_utf8_valid((const char *)p, len)) {
        *st = affect_fail(err, AFFECT_ERR_FORMAT, "%s %u: the name is empty or not UTF-8", what, k);
        return false;
    }
    *out = affect_strndup((const char *)p, len);
    if (!*out) {
        *st = affect_nomem(err);
        return false;
    }
    return true;
}

static bool finite_all(const double *v, size_t n)
{
    for (size_t k = 0; k < n; k++)
        if (!isfinite(v[k]))
            return false;
    return true;
}

/* A Fisher model's tail: the recognizer's BLOB (u64 length, bytes; decoded and checked by
 * affect_classifier_decode), whose classes must be levels, in level order (those that had
 * training motions), then w (its dimension, finite), ending the data. */
static affect_status read_fisher(affect_br *r, affect_strength *s, affect_error *err)
{
    uint64_t len;
    const unsigned char *p;
    if (!affect_br_u64(r, &len) || len > r->size - r->off || !affect_br_bytes(r, &p, (size_t)len))
        return affect_fail(err, AFFECT_ERR_FORMAT, "strength model truncated in its recognizer");
    affect_status st = affect_classifier_decode(p, (size_t)len, &s->fisher, err);
    if (st != AFFECT_OK) {
        affect_prefix(err, "the strength model's recognizer");
        return st;
    }
    uint32_t C = affect_classifier_n_classes(s->fisher), l = 0;
    bool same = C >= 2 && C <= s->n_levels;
    for (uint32_t k = 0; same && k < C; k++, l++) {
        while (l < s->n_levels && strcmp(affect_classifier_label(s->fisher, k), s->level_names[l]))
            l++;
        same = l < s->n_levels;
    }
    if (!same)
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "the strength model's recognizer has other classes than its levels");
    size_t D = affect_classifier_dim(s->fisher);
    if (D == 0 || D > (r->size - r->off) / 8 || (r->size - r->off) != D * 8)
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "the strength model's weights do not match its recognizer's dimension "
                           "%zu",
                           D);
    affect_free(s->w);
    if (!(s->w = affect_malloc_array(D, sizeof(double))))
        return affect_nomem(err);
    if (!affect_br_f64s(r, s->w, D) || !finite_all(s->w, D))
        return affect_fail(err, AFFECT_ERR_FORMAT, "non-finite value in the strength model");
    return AFFECT_OK;
}

affect_status affect_strength_decode(const unsigned char *data, size_t size, affect_strength **out,
                                     affect_error *err)
{
    *out = NULL;
    if (size < FIXED_SIZE + 8)
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "not a strength model BLOB (%zu bytes, the header alone is %u)", size,
                           (unsigned)(FIXED_SIZE + 8));
    if (affect_check_magic(data, AFFECT_STRENGTH_MAGIC, NULL, "a strength model", 0, err) !=
        AFFECT_OK)
        return AFFECT_ERR_FORMAT;
    affect_br r;
    affect_br_init(&r, data, size - 8);
    const unsigned char *magic;
    uint32_t version, flags, J, q, D, p, n, L, reg, root;
    affect_br_bytes(&r, &magic, 4);
    affect_br_u32(&r, &version);
    affect_br_u32(&r, &flags);
    affect_br_u32(&r, &J);
    affect_br_u32(&r, &q);
    affect_br_u32(&r, &D);
    affect_br_u32(&r, &p);
    affect_br_u32(&r, &n);
    affect_br_u32(&r, &L);
    affect_br_u32(&r, &reg);
    affect_br_u32(&r, &root);
    if (affect_check_version(version, AFFECT_STRENGTH_VERSION, NULL, err) != AFFECT_OK)
        return AFFECT_ERR_FORMAT;
    bool pca = (flags & FLAG_PCA) != 0, stdz = (flags & FLAG_STANDARDIZE) != 0;
    bool relative = (flags & FLAG_RELATIVE) != 0, lab = (flags & FLAG_LABAN) != 0;
    bool fisher = (flags & FLAG_FISHER) != 0;
    uint32_t known = FLAG_PCA | FLAG_RELATIVE | FLAG_STANDARDIZE |
                     (version >= 2 ? FLAG_LABAN | FLAG_BOTH | FLAG_CV_C : 0u) |
                     (version >= 3 ? FLAG_FISHER : 0u);
    if ((flags & ~known) != 0 || (version == 2 && !lab) ||
        (version >= 3 && (!fisher || lab || (flags & FLAG_CV_C))) ||
        ((flags & FLAG_BOTH) && !lab) || root >= J || (!relative && root != 0) ||
        reg < AFFECT_STRENGTH_REG_KERNEL_RIDGE || reg > AFFECT_STRENGTH_REG_LOCAL_LINEAR)
        return affect_fail(err, AFFECT_ERR_FORMAT, "reserved strength model fields are not valid");
    if (J < 1 || J > AFFECT_MOTION_MAX_JOINTS || q < 2 || q > AFFECT_KEYFRAMES_MAX ||
        (uint64_t)D != (uint64_t)6 * J * q || D > AFFECT_STRENGTH_MAX_DIM || p < 1 || p > D ||
        (pca && p > AFFECT_STRENGTH_MAX_PCA) || (!pca && p != D) || n < 2 ||
        n > AFFECT_MOTION_MAX_FRAMES || L < 2 || L > AFFECT_STRENGTH_MAX_LEVELS)
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "strength model sizes out of range (%u joints, %u keyframes, "
                           "dimension %u of %u, %u motions, %u levels)",
                           J, q, p, D, n, L);
    if (!affect_checksum_ok(data, size - 8))
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "strength model checksum mismatch: the BLOB is corrupt");
    /* the arrays must fit in what is left (before allocating them) */
    uint64_t rd = fisher ? 0 /* after the recognizer */
                  : lab  ? ((flags & FLAG_BOTH) ? (uint64_t)p : 0) + AFFECT_LABAN_N
                         : p;
    uint64_t doubles = (uint64_t)(q - 1) + rd + n + (uint64_t)n * p + p +
                       (lab ? 2 * AFFECT_LABAN_N + 1 : 0) +
                       (reg == AFFECT_STRENGTH_REG_KERNEL_RIDGE ? (uint64_t)n * p : 0) +
                       (pca ? (uint64_t)D + (uint64_t)p * D : 0) + (stdz ? (uint64_t)D : 0);
    if (doubles > (size - 8) / 8)
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "strength model BLOB length %zu is too short for its sizes", size);
    affect_strength *s = affect_calloc(1, sizeof *s);
    if (!s)
        return affect_nomem(err);
    affect_status st = AFFECT_OK;
    s->n_joints = J;
    s->keyframes = q;
    s->dim = D;
    s->pdim = p;
    s->n_train = n;
    s->n_levels = L;
    s->pca = pca;
    s->relative = relative;
    s->root = root;
    s->regression = (affect_strength_regression)reg;
    s->cv_C = (flags & FLAG_CV_C) != 0;
    s->features = fisher                ? AFFECT_STRENGTH_FEAT_FISHER
                  : !lab                ? AFFECT_STRENGTH_FEAT_KEYFRAMES
                  : (flags & FLAG_BOTH) ? AFFECT_STRENGTH_FEAT_BOTH
                                        : AFFECT_STRENGTH_FEAT_LABAN;
    if (stdz && !(s->scale = affect_malloc_array(D, sizeof(double)))) {
        st = affect_nomem(err);
        goto cleanup;
    }
    if (!alloc_arrays(s)) {
        st = affect_nomem(err);
        goto cleanup;
    }
    uint32_t iters, halv, conv, pad;
    affect_br_f64(&r, &s->fps);
    affect_br_f64(&r, &s->C);
    affect_br_f64(&r, &s->pca_variance);
    affect_br_f64(&r, &s->reg_h);
    affect_br_f64(&r, &s->reg_lambda);
    affect_br_f64(&r, &s->cv_kernel_ridge);
    affect_br_f64(&r, &s->cv_local_linear);
    affect_br_f64(&r, &s->cv_constant);
    affect_br_u32(&r, &iters);
    affect_br_u32(&r, &halv);
    affect_br_u32(&r, &conv);
    affect_br_u32(&r, &pad);
    affect_br_u64(&r, &s->stats.ordered);
    affect_br_u64(&r, &s->stats.similar);
    affect_br_u64(&r, &s->stats.correct);
    affect_br_f64(&r, &s->stats.objective);
    const unsigned char *unit;
    affect_br_bytes(&r, &unit, sizeof s->unit);
    memcpy(s->unit, unit, sizeof s->unit);
    s->stats.iterations = iters;
    s->stats.halvings = halv;
    s->stats.converged = conv != 0;
    if (conv > 1 || pad != 0 || s->unit[AFFECT_MOTION_UNIT_MAX] != '\0' ||
        !(s->fps > 0 && s->fps <= AFFECT_MOTION_MAX_FPS) || !(s->C > 0 && isfinite(s->C)) ||
        !(s->reg_h > 0 && isfinite(s->reg_h)) || !isfinite(s->reg_lambda) || s->reg_lambda < 0 ||
        !isfinite(s->pca_variance) || s->stats.correct > s->stats.ordered ||
        !isfinite(s->stats.objective)) {
        st = affect_fail(err, AFFECT_ERR_FORMAT, "strength model header values out of range");
        goto cleanup;
    }
    for (uint32_t j = 0; j < J; j++) {
        uint32_t par;
        if (!affect_br_u32(&r, &par)) {
            st = affect_fail(err, AFFECT_ERR_FORMAT, "strength model truncated in joint %u", j);
            goto cleanup;
        }
        s->parents[j] = (int32_t)par;
        if (s->parents[j] < -1 || s->parents[j] >= (int32_t)J || s->parents[j] == (int32_t)j) {
            st = affect_fail(err, AFFECT_ERR_FORMAT, "joint %u: parent %d out of range", j,
                             (int)s->parents[j]);
            goto cleanup;
        }
        if (!read_name(&r, &s->names[j], err, "joint", j, &st))
            goto cleanup;
    }
    for (uint32_t l = 0; l < L; l++) {
        if (!read_name(&r, &s->level_names[l], err, "level", l, &st))
            goto cleanup;
        if (!affect_br_f64(&r, &s->level_strength[l]) || !affect_br_u32(&r, &s->level_count[l])) {
            st = affect_fail(err, AFFECT_ERR_FORMAT, "strength model truncated in level %u", l);
            goto cleanup;
        }
        if (!isfinite(s->level_strength[l]) || s->level_count[l] > n) {
            st = affect_fail(err, AFFECT_ERR_FORMAT, "level %u: values out of range", l);
            goto cleanup;
        }
    }
    size_t nz = (size_t)n * p;
    bool ok = true;
    if (stdz) {
        ok = affect_br_f64s(&r, s->scale, D);
        for (uint32_t c = 0; ok && c < D; c++)
            ok = s->scale[c] > 0 && isfinite(s->scale[c]);
    }
    if (ok && pca)
        ok = affect_br_f64s(&r, s->mean, D) && affect_br_f64s(&r, s->comps, (size_t)p * D) &&
             finite_all(s->mean, D) && finite_all(s->comps, (size_t)p * D);
    ok = ok && affect_br_f64s(&r, s->seg_dt, q - 1) && affect_br_f64s(&r, s->w, (size_t)rd) &&
         affect_br_f64s(&r, s->train_r, n) && affect_br_f64s(&r, s->train_z, nz) &&
         affect_br_f64s(&r, s->zbar, p);
    if (ok && s->regression == AFFECT_STRENGTH_REG_KERNEL_RIDGE)
        ok = affect_br_f64s(&r, s->alpha, nz) && finite_all(s->alpha, nz);
    if (ok && lab)
        ok = affect_br_f64s(&r, s->lab_mean, AFFECT_LABAN_N) &&
             affect_br_f64s(&r, s->lab_sd, AFFECT_LABAN_N) && affect_br_f64(&r, &s->kf_weight);
    if (ok && fisher) {
        st = read_fisher(&r, s, err);
        if (st != AFFECT_OK)
            goto cleanup;
    }
    if (!ok || r.off != r.size) {
        st = affect_fail(err, AFFECT_ERR_FORMAT,
                         "strength model BLOB length %zu does not match its sizes", size);
        goto cleanup;
    }
    for (uint32_t i = 0; i + 1 < q; i++)
        if (!(s->seg_dt[i] > 0 && isfinite(s->seg_dt[i]))) {
            st = affect_fail(err, AFFECT_ERR_FORMAT, "segment %u: duration out of range", i);
            goto cleanup;
        }
    if (!finite_all(s->w, (size_t)rd) || !finite_all(s->train_r, n) ||
        !finite_all(s->train_z, nz) || !finite_all(s->zbar, p) ||
        (lab && (!finite_all(s->lab_mean, AFFECT_LABAN_N) || !isfinite(s->kf_weight)))) {
        st = affect_fail(err, AFFECT_ERR_FORMAT, "non-finite value in the strength model");
        goto cleanup;
    }
    for (uint32_t k = 0; lab && k < AFFECT_LABAN_N; k++)
        if (!(s->lab_sd[k] > 0 && isfinite(s->lab_sd[k]))) {
            st = affect_fail(err, AFFECT_ERR_FORMAT, "Laban component %u: deviation out of range",
                             k);
            goto cleanup;
        }
    if (lab &&
        (s->features == AFFECT_STRENGTH_FEAT_BOTH ? !(s->kf_weight > 0) : s->kf_weight != 0)) {
        st = affect_fail(err, AFFECT_ERR_FORMAT, "the keyframe block's weight is out of range");
        goto cleanup;
    }
cleanup:
    if (st != AFFECT_OK)
        affect_strength_free(s);
    else
        *out = s;
    return st;
}
