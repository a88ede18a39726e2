/*
 * generate.c — affective motion generation by HMM_NN (SCIENCE.md §5 steps 5–7; see
 * affect/generate.h for the definitions, options and every error message), and the DTW
 * distance between two motions of one skeleton.
 *
 * Usage: see the block at the top of affect/generate.h (compiled by the style/header-usage test).
 *
 * How it works. One feature definition (affect/features.h, every joint of the desired motion
 * by name, normalized, arm scale when it resolves) is built on the desired motion and applied
 * to it and to each neighbour whose joint names are the desired motion's (the others are
 * counted and skipped before anything is computed). The engine (affect/hmm.h) trains a
 * 1-Gaussian full-covariance ergodic model on the neighbours' observations followed by
 * `copies` references to the desired motion's (no copy is made). With a covariance scale
 * s ≠ 1 the trained parameters are rebuilt with every covariance × s (affect_hmm_from_params)
 * before Viterbi. The output rows are the state means along the path, filtered in place
 * column by column with affect_lowpass, de-normalized with the inverse of the desired
 * motion's transform (recomputed exactly as affect_features_extract computes it), and written
 * into a clone of the desired motion, which brings its names, parents, fps and unit.
 *
 * DTW keeps two rows of (cost, path length) and compares them lexicographically, so the
 * result does not depend on the order of the two motions (when their joint orders agree the
 * arithmetic is the same, and the distance is bit-for-bit symmetric).
 */
#include "affect/generate.h"

#include <math.h>
#include <string.h>

#include "affect/features.h"
#include "affect/hmm.h"
#include "affect/laban.h"
#include "affect/roles.h"
#include "affect/skeleton.h"

/* Relative difference of two frame rates below which they are one rate (a neighbour at another
 * rate is refused: the engine's states have one time step). Far above the rounding of a rate
 * computed from a frame time or read back from text (about 1e-15 of it), far below any rate
 * that differs really (29.97 and 30 fps differ by 1e-3 of it). */
#define FPS_TOLERANCE 1e-6

void affect_generate_options_default(affect_generate_options *opt)
{
    opt->states = 12;
    opt->copies = 0;
    /* 3 Hz: at 6 Hz the jumps between state means keep their energy and swamp the emotion
     * (a neutral knock made sad came out with twice the source's WeightAll) */
    opt->cutoff_hz = 3.0;
    opt->covariance_scale = 1.0;
    opt->seed = 1;
    opt->max_iter = 50;
    opt->tol = 1e-4;
    opt->reg = 1e-4;
    opt->up_axis = 1;
    opt->clock = NULL;
    opt->render = AFFECT_GENERATE_STEPS;
    opt->keep_path = true;
    opt->rigid = true;
    opt->monitor = NULL;
}

/* The output rows before filtering: with AFFECT_GENERATE_STEPS the mean of state path[t] at
 * every frame t; with AFFECT_GENERATE_LINEAR each run of equal states puts its state's mean at
 * the run's centre frame (a real-valued time) and the frames between two consecutive centres
 * are interpolated linearly (before the first centre and after the last, the first and last
 * means are held). */
static void render_path(const double *means, uint32_t dim, const int32_t *path, uint32_t T,
                        affect_generate_render mode, double *out)
{
    if (mode == AFFECT_GENERATE_STEPS) {
        for (uint32_t t = 0; t < T; t++)
            memcpy(out + (size_t)t * dim, means + (size_t)path[t] * dim, (size_t)dim * sizeof *out);
        return;
    }
    /* runs: [s, e) of equal states; the previous run's centre and state are carried along */
    double prev_c = -1.0;
    int32_t prev_s = -1;
    uint32_t t = 0, s = 0;
    while (s < T) {
        uint32_t e = s + 1;
        while (e < T && path[e] == path[s])
            e++;
        double c = 0.5 * (double)(s + e - 1);
        const double *mu = means + (size_t)path[s] * dim;
        if (prev_s < 0) {
            for (; (double)t <= c; t++) /* before the first centre: hold */
                memcpy(out + (size_t)t * dim, mu, (size_t)dim * sizeof *out);
        } else {
            const double *mp = means + (size_t)prev_s * dim;
            for (; (double)t <= c; t++) {
                double u = ((double)t - prev_c) / (c - prev_c);
                for (uint32_t k = 0; k < dim; k++)
                    out[(size_t)t * dim + k] = mp[k] + u * (mu[k] - mp[k]);
            }
        }
        prev_c = c;
        prev_s = path[s];
        s = e;
    }
    for (; t < T; t++) /* after the last centre: hold */
        memcpy(out + (size_t)t * dim, means + (size_t)prev_s * dim, (size_t)dim * sizeof *out);
}

/* The feature index of the root among the observation's joints (desired's joints in its
 * order): the pelvis role, as the normalization uses, else joint 0 (so on skeletons whose
 * first joint is a fixed origin, such as the corpus's joint_Root, the travelling hips). */
static uint32_t root_index(const affect_motion *desired)
{
    affect_roles roles;
    affect_roles_resolve(desired, &roles);
    int32_t r = roles.joint[AFFECT_ROLE_PELVIS];
    return r >= 0 && (uint32_t)r < desired->n_joints ? (uint32_t)r : 0;
}

/* Subtracts, frame by frame, the root's two horizontal coordinates (the axes other than up)
 * from every joint's (x: T rows of 3 J); saves them in path (T × 2) when path is not NULL. */
static void remove_root_path(double *x, uint32_t T, uint32_t J, uint32_t root, int up, double *path)
{
    int a0 = up == 0 ? 1 : 0, a1 = up == 2 ? 1 : 2;
    for (uint32_t t = 0; t < T; t++) {
        double *row = x + (size_t)t * J * 3;
        double h0 = row[root * 3 + (uint32_t)a0], h1 = row[root * 3 + (uint32_t)a1];
        if (path) {
            path[(size_t)t * 2] = h0;
            path[(size_t)t * 2 + 1] = h1;
        }
        for (uint32_t j = 0; j < J; j++) {
            row[j * 3 + (uint32_t)a0] -= h0;
            row[j * 3 + (uint32_t)a1] -= h1;
        }
    }
}

/* Adds path (T × 2) back to every joint's horizontal coordinates. */
static void add_root_path(double *x, uint32_t T, uint32_t J, int up, const double *path)
{
    int a0 = up == 0 ? 1 : 0, a1 = up == 2 ? 1 : 2;
    for (uint32_t t = 0; t < T; t++) {
        double *row = x + (size_t)t * J * 3;
        for (uint32_t j = 0; j < J; j++) {
            row[j * 3 + (uint32_t)a0] += path[(size_t)t * 2];
            row[j * 3 + (uint32_t)a1] += path[(size_t)t * 2 + 1];
        }
    }
}

/* The caller's clock, or 0 without one. */
static double now(const affect_generate_options *opt)
{
    return opt->clock ? opt->clock() : 0.0;
}

/* Rewrites a failure message as "what: message", or "what index: message" when index ≥ 0
 * ("out of memory" stays as it is). */
static affect_status prefixed(affect_error *err, affect_status st, const char *what, int64_t index)
{
    if (!err || st == AFFECT_OK || st == AFFECT_ERR_NOMEM)
        return st;
    char msg[AFFECT_ERROR_MSG_MAX];
    memcpy(msg, err->msg, sizeof msg);
    msg[sizeof msg - 1] = '\0';
    if (index >= 0)
        return affect_fail(err, st, "%s %lld: %s", what, (long long)index, msg);
    return affect_fail(err, st, "%s: %s", what, msg);
}

/* True when b has exactly a's joint names (same count, every name of a present in b; the
 * names of a motion are unique, so the sets are equal). */
static bool same_joint_names(const affect_motion *a, const affect_motion *b)
{
    if (a->n_joints != b->n_joints)
        return false;
    for (uint32_t j = 0; j < a->n_joints; j++) {
        if (j < b->n_joints && strcmp(a->names[j], b->names[j]) == 0)
            continue; /* the common case: the same order */
        if (affect_motion_find_joint(b, a->names[j]) < 0)
            return false;
    }
    return true;
}

static affect_status make_features(const affect_motion *first, int up_axis, affect_features **f,
                                   affect_error *err)
{
    affect_features_options fo;
    affect_features_options_default(&fo);
    fo.up_axis = up_axis;
    return affect_features_create(&fo, first, f, err);
}

affect_status affect_generate_transform(const affect_motion *m, int up_axis,
                                        affect_normalize_transform *tf, affect_error *err)
{
    affect_roles roles;
    affect_roles_resolve(m, &roles);
    affect_normalize_options no;
    affect_normalize_options_default(&no);
    no.up_axis = up_axis;
    no.translation = no.heading = true;
    no.scale_arm =
        roles.joint[AFFECT_ROLE_RIGHT_SHOULDER] >= 0 && roles.joint[AFFECT_ROLE_RIGHT_HAND] >= 0;
    return affect_normalize_transform_compute(m, &roles, &no, tf, err);
}

void affect_normalize_invert(const affect_normalize_transform *tf, const double *in, size_t n,
                             double *out)
{
    const double *r = tf->rot;
    for (size_t i = 0; i < n; i++) {
        double a = in[i * 3] * tf->scale, b = in[i * 3 + 1] * tf->scale,
               c = in[i * 3 + 2] * tf->scale;
        out[i * 3 + 0] = tf->origin[0] + (r[0] * a + r[3] * b + r[6] * c);
        out[i * 3 + 1] = tf->origin[1] + (r[1] * a + r[4] * b + r[7] * c);
        out[i * 3 + 2] = tf->origin[2] + (r[2] * a + r[5] * b + r[8] * c);
    }
}

static affect_status check_options(const affect_generate_options *opt, affect_error *err)
{
    if (opt->states < 1 || opt->states > AFFECT_HMM_MAX_STATES)
        return affect_fail(err, AFFECT_ERR_INVALID, "states must be between 1 and %u",
                           AFFECT_HMM_MAX_STATES);
    if (opt->copies > AFFECT_GENERATE_MAX_COPIES)
        return affect_fail(err, AFFECT_ERR_INVALID, "copies must be at most %u, got %u",
                           AFFECT_GENERATE_MAX_COPIES, opt->copies);
    if (!isfinite(opt->cutoff_hz) || opt->cutoff_hz < 0)
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "cut-off must be a finite frequency of 0 Hz or more, got %g",
                           opt->cutoff_hz);
    if (!isfinite(opt->covariance_scale) || !(opt->covariance_scale > 0))
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "covariance scale must be finite and greater than 0, got %g",
                           opt->covariance_scale);
    if (opt->up_axis < 0 || opt->up_axis > 2)
        return affect_fail(err, AFFECT_ERR_INVALID, "up axis must be x, y or z");
    return AFFECT_OK;
}

/* The trained model with every covariance multiplied by s. */
static affect_status scaled_model(const affect_hmm *h, double s, affect_hmm **out,
                                  affect_error *err)
{
    const affect_hmm_config *cfg = affect_hmm_get_config(h);
    size_t n;
    if (!affect_mul_size((size_t)cfg->n_states * cfg->n_mix, (size_t)cfg->dim * cfg->dim, &n))
        return affect_fail(err, AFFECT_ERR_RANGE, "the model is too large");
    double *covs = affect_malloc_array(n, sizeof *covs);
    if (!covs)
        return affect_nomem(err);
    const double *c = affect_hmm_covariances(h);
    for (size_t i = 0; i < n; i++)
        covs[i] = c[i] * s;
    affect_status st =
        affect_hmm_from_params(cfg, affect_hmm_start(h), affect_hmm_transitions(h),
                               affect_hmm_weights(h), affect_hmm_means(h), covs, out, err);
    affect_free(covs);
    return st;
}

affect_status affect_generate(const affect_motion *desired, const affect_motion *const *neighbours,
                              uint32_t n_neighbours, const affect_generate_options *opt,
                              affect_motion **out, affect_generate_report *rep, affect_error *err)
{
    affect_generate_options defaults;
    if (!opt) {
        affect_generate_options_default(&defaults);
        opt = &defaults;
    }
    if (rep)
        memset(rep, 0, sizeof *rep);
    *out = NULL;
    if (!desired)
        return affect_fail(err, AFFECT_ERR_INVALID, "no desired motion");
    if (!neighbours || n_neighbours == 0)
        return affect_fail(err, AFFECT_ERR_INVALID, "no neighbours");
    affect_status st = check_options(opt, err);
    if (st)
        return st;

    uint32_t used = 0, excluded = 0, N = opt->states, T = desired->n_frames;
    for (uint32_t i = 0; i < n_neighbours; i++) {
        const affect_motion *nb = neighbours[i];
        if (!nb)
            return affect_fail(err, AFFECT_ERR_INVALID, "neighbour %u is missing", i);
        if (!same_joint_names(desired, nb)) {
            excluded++;
            continue;
        }
        if (fabs(nb->fps - desired->fps) > FPS_TOLERANCE * desired->fps)
            return affect_fail(err, AFFECT_ERR_INVALID,
                               "neighbour %u is at %g fps, the desired motion at %g (resample it "
                               "first)",
                               i, nb->fps, desired->fps);
        if (nb->n_frames < N)
            return affect_fail(err, AFFECT_ERR_INVALID,
                               "neighbour %u has %u frames, fewer than the %u states", i,
                               nb->n_frames, N);
        used++;
    }
    if (used == 0)
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "no neighbour has the desired motion's skeleton (joint names)");
    if (opt->copies > 0 && T < N)
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "the desired motion has %u frames, fewer than the %u states (it is "
                           "trained on with copies > 0)",
                           T, N);

    affect_features *f = NULL;
    double *xd = NULL, **xs = NULL, *scratch = NULL, *pts = NULL, *root_path = NULL;
    affect_hmm_seq *seqs = NULL;
    affect_hmm *h = NULL, *hs = NULL;
    int32_t *path = NULL;
    affect_motion *m = NULL;
    uint32_t n_seqs = used + opt->copies, dim = 0, frames = 0;
    double t0 = now(opt), t1 = 0, t2 = 0, t3 = 0;

    if ((st = make_features(desired, opt->up_axis, &f, err)) != AFFECT_OK)
        goto done;
    dim = affect_features_dim(f);
    if ((st = affect_features_extract(f, desired, &xd, &frames, opt->monitor, err)) != AFFECT_OK) {
        st = prefixed(err, st, "desired motion", -1);
        goto done;
    }
    xs = affect_calloc(used, sizeof *xs);
    seqs = affect_malloc_array(n_seqs, sizeof *seqs);
    path = affect_malloc_array(T, sizeof *path);
    if (opt->keep_path)
        root_path = affect_malloc_array((size_t)T * 2, sizeof *root_path);
    if (!xs || !seqs || !path || (opt->keep_path && !root_path)) {
        st = affect_nomem(err);
        goto done;
    }
    uint32_t root = root_index(desired), J = desired->n_joints;
    if (opt->keep_path)
        remove_root_path(xd, T, J, root, opt->up_axis, root_path);
    for (uint32_t i = 0, k = 0; i < n_neighbours; i++) {
        if (!same_joint_names(desired, neighbours[i]))
            continue;
        if ((st = affect_features_extract(f, neighbours[i], &xs[k], &frames, opt->monitor, err)) !=
            AFFECT_OK) {
            st = prefixed(err, st, "neighbour", i);
            goto done;
        }
        if (opt->keep_path)
            remove_root_path(xs[k], frames, J, root, opt->up_axis, NULL);
        seqs[k].x = xs[k];
        seqs[k].n_frames = frames;
        k++;
    }
    for (uint32_t c = 0; c < opt->copies; c++) {
        seqs[used + c].x = xd;
        seqs[used + c].n_frames = T;
    }

    t1 = now(opt);
    affect_hmm_config cfg;
    affect_hmm_config_default(&cfg);
    cfg.n_states = N;
    cfg.n_mix = 1;
    cfg.dim = dim;
    cfg.cov = AFFECT_HMM_FULL;
    cfg.topology = AFFECT_HMM_ERGODIC;
    cfg.learn_start = false;
    cfg.max_iter = opt->max_iter;
    cfg.tol = opt->tol;
    cfg.reg = opt->reg;
    cfg.seed = opt->seed;
    cfg.monitor = opt->monitor;
    const char *msg = affect_hmm_config_check(&cfg);
    if (msg) {
        st = affect_fail(err, AFFECT_ERR_INVALID, "%s", msg);
        goto done;
    }
    if ((st = affect_hmm_train(&cfg, seqs, n_seqs, &h, err)) != AFFECT_OK)
        goto done;
    t2 = now(opt);
    if (opt->covariance_scale != 1.0 &&
        (st = scaled_model(h, opt->covariance_scale, &hs, err)) != AFFECT_OK)
        goto done;
    double logprob = 0;
    if ((st = affect_hmm_viterbi(hs ? hs : h, xd, T, path, &logprob, opt->monitor, err)) !=
        AFFECT_OK)
        goto done;
    t3 = now(opt);

    /* state means along the path, filtered column by column, in place in xd */
    const double *means = affect_hmm_means(h);
    render_path(means, dim, path, T, opt->render, xd);
    if (opt->cutoff_hz > 0 && opt->cutoff_hz < desired->fps / 2 && T >= 2) {
        size_t n_scratch;
        if (!affect_add_size(T, 18, &n_scratch)) {
            st = affect_fail(err, AFFECT_ERR_RANGE, "too many frames");
            goto done;
        }
        scratch = affect_malloc_array(n_scratch, sizeof *scratch);
        if (!scratch) {
            st = affect_nomem(err);
            goto done;
        }
        for (uint32_t c = 0; c < dim; c++)
            affect_lowpass(xd + c, T, dim, desired->fps, opt->cutoff_hz, scratch, xd + c);
    }

    if (opt->keep_path)
        add_root_path(xd, T, J, opt->up_axis, root_path);

    /* back to the desired motion's position, heading and scale, on its skeleton */
    affect_normalize_transform tf;
    if ((st = affect_generate_transform(desired, opt->up_axis, &tf, err)) != AFFECT_OK) {
        st = prefixed(err, st, "desired motion", -1);
        goto done;
    }
    if ((st = affect_motion_clone(desired, &m, err)) != AFFECT_OK)
        goto done;
    affect_motion_drop_skeleton(
        m); /* new positions: the desired motion's rotations no longer apply */
    pts = affect_malloc_array((size_t)J * 3, sizeof *pts);
    if (!pts) {
        st = affect_nomem(err);
        goto done;
    }
    for (uint32_t t = 0; t < T; t++) {
        affect_normalize_invert(&tf, xd + (size_t)t * dim, J, pts);
        float *row = m->pos + (size_t)t * J * 3;
        for (size_t i = 0; i < (size_t)J * 3; i++)
            row[i] = (float)pts[i];
    }

    if (opt->rigid) {
        /* a skeleton that plays the output: the desired motion's bone lengths, rotations */
        affect_rigid_options ro;
        affect_rigid_options_default(&ro);
        ro.model = AFFECT_RIGID_SKELETON;
        ro.lengths = AFFECT_RIGID_REFERENCE;
        ro.reference = desired;
        ro.monitor = opt->monitor;
        affect_motion *r = NULL;
        if ((st = affect_motion_rigid(m, &ro, &r, err)) != AFFECT_OK) {
            st = prefixed(err, st, "making the output rigid", -1);
            goto done;
        }
        affect_motion_free(m);
        m = r;
    }

    if (rep) {
        affect_hmm_report hr;
        affect_hmm_get_report(h, &hr);
        rep->neighbours_used = used;
        rep->excluded = excluded;
        rep->iterations = hr.iterations;
        rep->loglik = hr.loglik[hr.iterations];
        rep->viterbi_logprob = logprob;
        rep->path = path;
        rep->n_frames = T;
        rep->t_features = t1 - t0;
        rep->t_train = t2 - t1;
        rep->t_viterbi = t3 - t2;
        rep->t_render = now(opt) - t3;
        path = NULL;
    }
    *out = m;
    m = NULL;
done:
    affect_motion_free(m);
    affect_free(pts);
    affect_free(root_path);
    affect_free(scratch);
    affect_free(path);
    affect_hmm_free(hs);
    affect_hmm_free(h);
    affect_free(seqs);
    for (uint32_t k = 0; xs && k < used; k++)
        affect_free(xs[k]);
    affect_free(xs);
    affect_free(xd);
    affect_features_free(f);
    return st;
}

/* ---- DTW ---- */

/* Mean over J joints of the distance between rows a and b (3 J values each). */
static double frame_cost(const double *a, const double *b, uint32_t J)
{
    double s = 0;
    for (uint32_t j = 0; j < J; j++) {
        double dx = a[j * 3] - b[j * 3], dy = a[j * 3 + 1] - b[j * 3 + 1],
               dz = a[j * 3 + 2] - b[j * 3 + 2];
        s += sqrt(dx * dx + dy * dy + dz * dz);
    }
    return s / J;
}

/* (c1, l1) better than (c2, l2): less cost, then a shorter path. */
static bool dtw_better(double c1, uint64_t l1, double c2, uint64_t l2)
{
    return c1 < c2 || (c1 == c2 && l1 < l2);
}

affect_status affect_dtw_distance(const affect_motion *a, const affect_motion *b, double *dist,
                                  affect_monitor *mon, affect_error *err)
{
    if (!a || !b)
        return affect_fail(err, AFFECT_ERR_INVALID, "missing motion");
    if (!same_joint_names(a, b))
        return affect_fail(err, AFFECT_ERR_INVALID, "the motions have different joint names");
    affect_features *f = NULL;
    double *xa = NULL, *xb = NULL, *cost = NULL;
    uint64_t *len = NULL;
    uint32_t Ta = 0, Tb = 0;
    affect_status st = make_features(a, 1, &f, err);
    if (st)
        goto done;
    if ((st = affect_features_extract(f, a, &xa, &Ta, mon, err)) != AFFECT_OK) {
        st = prefixed(err, st, "first motion", -1);
        goto done;
    }
    if ((st = affect_features_extract(f, b, &xb, &Tb, mon, err)) != AFFECT_OK) {
        st = prefixed(err, st, "second motion", -1);
        goto done;
    }
    if (Ta == 0 || Tb == 0) {
        st = affect_fail(err, AFFECT_ERR_INVALID, "a motion has no frames");
        goto done;
    }
    uint32_t J = a->n_joints, dim = affect_features_dim(f);
    size_t n;
    if (!affect_mul_size(Tb, 2, &n)) {
        st = affect_fail(err, AFFECT_ERR_RANGE, "too many frames");
        goto done;
    }
    cost = affect_malloc_array(n, sizeof *cost);
    len = affect_malloc_array(n, sizeof *len);
    if (!cost || !len) {
        st = affect_nomem(err);
        goto done;
    }
    double *pc = cost, *cc = cost + Tb; /* previous and current rows */
    uint64_t *pl = len, *cl = len + Tb;
    for (uint32_t i = 0; i < Ta; i++) {
        if ((st = affect_monitor_check(mon, err)) != AFFECT_OK)
            goto done;
        const double *ra = xa + (size_t)i * dim;
        for (uint32_t k = 0; k < Tb; k++) {
            double c = frame_cost(ra, xb + (size_t)k * dim, J);
            if (i == 0 && k == 0) {
                cc[k] = c;
                cl[k] = 1;
                continue;
            }
            double best = 0;
            uint64_t bl = 0; /* 0: no predecessor yet */
            if (i > 0 && k > 0) {
                best = pc[k - 1];
                bl = pl[k - 1];
            }
            if (i > 0 && (bl == 0 || dtw_better(pc[k], pl[k], best, bl))) {
                best = pc[k];
                bl = pl[k];
            }
            if (k > 0 && (bl == 0 || dtw_better(cc[k - 1], cl[k - 1], best, bl))) {
                best = cc[k - 1];
                bl = cl[k - 1];
            }
            cc[k] = best + c;
            cl[k] = bl + 1;
        }
        double *tc = pc;
        pc = cc;
        cc = tc;
        uint64_t *tl = pl;
        pl = cl;
        cl = tl;
    }
    *dist = pc[Tb - 1] / (double)pl[Tb - 1];
done:
    affect_free(cost);
    affect_free(len);
    affect_free(xa);
    affect_free(xb);
    affect_features_free(f);
    return st;
}

/* ---- neighbours of the same action ---- */

/* m at no more than AFFECT_RANK_FPS frames per second: *made (free it) or m itself. */
static affect_status coarse(const affect_motion *m, affect_motion **made, affect_error *err)
{
    *made = NULL;
    if (m->fps <= AFFECT_RANK_FPS || m->n_frames < 2)
        return AFFECT_OK;
    return affect_motion_resample(m, AFFECT_RANK_FPS, made, err);
}

affect_status affect_generate_rank_by_action(const affect_motion *desired,
                                             const affect_motion *const *candidates, uint32_t n,
                                             uint32_t *order, double *dist, affect_monitor *mon,
                                             affect_error *err)
{
    double *d = affect_malloc_array(n ? n : 1, sizeof *d);
    affect_motion *dc = NULL, *cc = NULL;
    affect_status st = d ? coarse(desired, &dc, err) : affect_nomem(err);
    if (st) {
        affect_free(d);
        return st;
    }
    const affect_motion *dm = dc ? dc : desired;
    for (uint32_t i = 0; i < n; i++) {
        order[i] = i;
        d[i] = INFINITY;
        if (!candidates[i] || !same_joint_names(desired, candidates[i]))
            continue;
        st = coarse(candidates[i], &cc, err);
        if (st == AFFECT_OK)
            st = affect_dtw_distance(dm, cc ? cc : candidates[i], &d[i], mon, err);
        affect_motion_free(cc);
        cc = NULL;
        if (st == AFFECT_ERR_NOMEM || st == AFFECT_ERR_INTERRUPTED) {
            affect_free(d);
            affect_motion_free(dc);
            return st;
        }
        if (st)
            d[i] = INFINITY;
    }
    affect_motion_free(dc);
    /* insertion sort: stable, so ties keep the given order */
    for (uint32_t i = 1; i < n; i++) {
        uint32_t v = order[i];
        uint32_t k = i;
        while (k > 0 && d[order[k - 1]] > d[v]) {
            order[k] = order[k - 1];
            k--;
        }
        order[k] = v;
    }
    if (dist)
        memcpy(dist, d, n * sizeof *d);
    affect_free(d);
    return AFFECT_OK;
}
