/*
 * transfer.c — emotion transfer onto the desired motion (see affect/transfer.h for the method,
 * the options and every error message): per-joint posture changes and band amplitude ratios
 * learned from donor pairs, applied to the desired motion's local rotations, with the legs
 * held at foot contacts; and the choice of the donor pairs.
 *
 * How it works. Each motion is used in its skeletal form (affect_motion_skeletal). For every
 * joint of the desired motion that is changed, each pair's two motions give their statistics
 * (mean rotation, band energies) on the fly; the change is then applied to a clone of the
 * desired motion's skeletal form, the legs are blended back at contacts, and the positions are
 * recomputed by forward kinematics. All scratch memory is sized for the longest motion once.
 */
#include "affect/transfer.h"

#include <math.h>
#include <string.h>

#include "affect/laban.h"
#include "affect/quat.h"
#include "affect/roles.h"
#include "affect/skeleton.h"

#define PI 3.14159265358979323846
/* Energy floor of a band: (0.5°)² of displacement, (2° per second)² of velocity. */
#define DISPLACEMENT_FLOOR ((0.5 * PI / 180) * (0.5 * PI / 180))
#define VELOCITY_FLOOR ((2 * PI / 180) * (2 * PI / 180))

void affect_transfer_options_default(affect_transfer_options *opt)
{
    opt->strength = 1.0;
    opt->band_hz[0] = 1.0;
    opt->band_hz[1] = 3.0;
    opt->max_ratio = 3.0;
    opt->keep_contacts = true;
    opt->amplitude = AFFECT_TRANSFER_VELOCITY;
    opt->pooled = false;
    opt->monitor = NULL;
}

const char *affect_transfer_options_check(const affect_transfer_options *opt)
{
    if (!(opt->strength >= 0 && opt->strength <= AFFECT_TRANSFER_MAX_STRENGTH))
        return "strength must be between 0 and 2";
    if (!(opt->band_hz[0] > 0 && opt->band_hz[1] > opt->band_hz[0] && isfinite(opt->band_hz[1])))
        return "band edges must satisfy 0 < low < high (Hz)";
    if (!(opt->max_ratio >= 1 && isfinite(opt->max_ratio)))
        return "max_ratio must be a finite number of at least 1";
    if (opt->amplitude != AFFECT_TRANSFER_VELOCITY &&
        opt->amplitude != AFFECT_TRANSFER_DISPLACEMENT)
        return "amplitude must be \"velocity\" or \"displacement\"";
    return NULL;
}

/* ---- per-joint statistics ---- */

typedef struct scratch {
    double *q;    /* T × 4 rotations */
    double *d;    /* T × 3 deviations */
    double *band; /* 3 × T × 3 */
    double *tmp;  /* T + 18 for affect_lowpass, then T × 3 */
} scratch;

/* Joint j's rotations as doubles, each on the hemisphere of the one before. */
static void load_rotations(const affect_motion *m, uint32_t j, double *q)
{
    uint32_t nj = m->n_joints;
    for (uint32_t t = 0; t < m->n_frames; t++) {
        const float *p = m->rot + ((size_t)t * nj + j) * 4;
        double *o = q + 4 * (size_t)t;
        for (int i = 0; i < 4; i++)
            o[i] = p[i];
        affect_quat_normalize(o);
        if (t > 0) {
            const double *r = o - 4;
            if (o[0] * r[0] + o[1] * r[1] + o[2] * r[2] + o[3] * r[3] < 0)
                for (int i = 0; i < 4; i++)
                    o[i] = -o[i];
        }
    }
}

/* The normalized sum of the rotations, aligned first to the first one, then to that mean. */
static void mean_rotation(const double *q, uint32_t T, double mean[4])
{
    memcpy(mean, q, 4 * sizeof *mean);
    for (int pass = 0; pass < 2; pass++) {
        double sum[4] = {0, 0, 0, 0};
        for (uint32_t t = 0; t < T; t++) {
            const double *o = q + 4 * (size_t)t;
            double s =
                o[0] * mean[0] + o[1] * mean[1] + o[2] * mean[2] + o[3] * mean[3] < 0 ? -1.0 : 1.0;
            for (int i = 0; i < 4; i++)
                sum[i] += s * o[i];
        }
        memcpy(mean, sum, sizeof sum);
        affect_quat_normalize(mean);
    }
}

static void qconj(const double q[4], double r[4])
{
    r[0] = q[0], r[1] = -q[1], r[2] = -q[2], r[3] = -q[3];
}

/* d_t = log(mean⁻¹ q_t), then its three bands (slow, middle, fast; their sum is d). */
static void split_bands(const double *q, uint32_t T, double fps, const double mean[4],
                        const double band_hz[2], scratch *s)
{
    double inv[4];
    qconj(mean, inv);
    for (uint32_t t = 0; t < T; t++) {
        double r[4];
        affect_quat_mul(inv, q + 4 * (size_t)t, r);
        affect_quat_log(r, s->d + 3 * (size_t)t);
    }
    double *low = s->band, *mid = s->band + 3 * (size_t)T, *high = s->band + 6 * (size_t)T;
    for (int a = 0; a < 3; a++) {
        affect_lowpass(s->d + a, T, 3, fps, band_hz[0], s->tmp, low + a);
        affect_lowpass(s->d + a, T, 3, fps, band_hz[1], s->tmp, mid + a);
    }
    for (size_t i = 0; i < 3 * (size_t)T; i++) {
        high[i] = s->d[i] - mid[i];
        mid[i] -= low[i];
    }
}

/* Mean rotation and each band's mean squared amplitude (AFFECT_TRANSFER_DISPLACEMENT, rad²)
 * or mean squared rate of change (AFFECT_TRANSFER_VELOCITY, central differences, rad² s⁻²)
 * of joint j of m. */
static void joint_stats(const affect_motion *m, uint32_t j, const affect_transfer_options *opt,
                        scratch *s, double mean[4], double energy[AFFECT_TRANSFER_BANDS])
{
    uint32_t T = m->n_frames;
    load_rotations(m, j, s->q);
    mean_rotation(s->q, T, mean);
    split_bands(s->q, T, m->fps, mean, opt->band_hz, s);
    for (int b = 0; b < AFFECT_TRANSFER_BANDS; b++) {
        const double *x = s->band + (size_t)b * 3 * T;
        double e = 0;
        if (opt->amplitude == AFFECT_TRANSFER_VELOCITY) {
            for (uint32_t t = 0; t < T && T > 1; t++) {
                uint32_t a = t > 0 ? t - 1 : t, c = t + 1 < T ? t + 1 : t;
                for (int k = 0; k < 3; k++) {
                    double v = (x[3 * (size_t)c + (size_t)k] - x[3 * (size_t)a + (size_t)k]) *
                               m->fps / (double)(c - a);
                    e += v * v;
                }
            }
        } else {
            for (size_t i = 0; i < 3 * (size_t)T; i++)
                e += x[i] * x[i];
        }
        energy[b] = e / T;
    }
}

/* ---- which joints change ---- */

/* Joint j of `m` with the same name as joint j of d, if it is not a root there. */
static int32_t same_joint(const affect_motion *m, const affect_motion *d, uint32_t j)
{
    int32_t k = affect_motion_find_joint(m, d->names[j]);
    return k < 0 || m->parents[k] < 0 ? -1 : k;
}

/* ---- foot contacts ---- */

/* Whether joint j is in the subtree rooted at `top`. */
static bool below(const affect_motion *m, uint32_t j, uint32_t top);

/* Speed of joint j from frame t to frame t + 1, per second. */
static double joint_speed(const affect_motion *m, uint32_t t, uint32_t j)
{
    uint32_t nj = m->n_joints;
    const float *pa = m->pos + ((size_t)t * nj + j) * 3;
    const float *pb = pa + (size_t)nj * 3;
    double v2 = 0;
    for (int i = 0; i < 3; i++)
        v2 += ((double)pb[i] - pa[i]) * ((double)pb[i] - pa[i]);
    return sqrt(v2) * m->fps;
}

/* w[t] in [0, 1]: 1 at both ends of every step t → t + 1 in which the foot joint or one below
 * it (a toe) moves slower than AFFECT_TRANSFER_CONTACT_SPEED × body size per second (so that
 * the step is the desired motion's own), ramping down to 0 over the ramp around them. */
static uint32_t contact_weights(const affect_motion *m, uint32_t foot, double *w)
{
    uint32_t T = m->n_frames, nj = m->n_joints;
    double limit = AFFECT_TRANSFER_CONTACT_SPEED * affect_motion_body_size(m);
    uint32_t ramp = (uint32_t)fmax(1.0, round(AFFECT_TRANSFER_CONTACT_RAMP * m->fps));
    uint32_t count = 0;
    for (uint32_t t = 0; t < T; t++)
        w[t] = 0;
    bool slow_before = false; /* the step into frame t */
    for (uint32_t t = 0; t < T && T > 1; t++) {
        bool slow_after = false;
        for (uint32_t j = 0; j < nj && t + 1 < T && !slow_after; j++)
            slow_after = below(m, j, foot) && joint_speed(m, t, j) < limit;
        bool rests = slow_before || slow_after;
        slow_before = slow_after;
        if (!rests)
            continue;
        count++;
        uint32_t lo = t > ramp ? t - ramp : 0, hi = t + ramp < T ? t + ramp : T - 1;
        for (uint32_t u = lo; u <= hi; u++) {
            double dist = u > t ? (double)(u - t) : (double)(t - u);
            w[u] = fmax(w[u], 1.0 - dist / ramp);
        }
    }
    return count;
}

/* Whether joint j is in the subtree rooted at `top`. */
static bool below(const affect_motion *m, uint32_t j, uint32_t top)
{
    for (int32_t k = (int32_t)j, steps = 0; k >= 0 && steps <= (int32_t)m->n_joints;
         k = m->parents[k], steps++)
        if ((uint32_t)k == top)
            return true;
    return false;
}

/* Leg joints take back the desired motion's rotations (src) where its foot rests. */
static void hold_legs(const affect_motion *src, affect_motion *out, double *w, uint32_t contacts[2])
{
    affect_roles roles;
    affect_roles_resolve(src, &roles);
    const affect_role hips[2] = {AFFECT_ROLE_LEFT_HIP, AFFECT_ROLE_RIGHT_HIP};
    const affect_role feet[2] = {AFFECT_ROLE_LEFT_FOOT, AFFECT_ROLE_RIGHT_FOOT};
    uint32_t T = src->n_frames, nj = src->n_joints;
    for (int side = 0; side < 2; side++) {
        int32_t hip = roles.joint[hips[side]], foot = roles.joint[feet[side]];
        if (hip < 0 || foot < 0 || !below(src, (uint32_t)foot, (uint32_t)hip))
            continue;
        contacts[side] = contact_weights(src, (uint32_t)foot, w);
        if (contacts[side] == 0)
            continue;
        for (uint32_t j = 0; j < nj; j++) {
            if (!below(src, j, (uint32_t)hip))
                continue;
            for (uint32_t t = 0; t < T; t++) {
                if (w[t] <= 0)
                    continue;
                float *po = out->rot + ((size_t)t * nj + j) * 4;
                const float *ps = src->rot + ((size_t)t * nj + j) * 4;
                double a[4], b[4], r[4];
                for (int i = 0; i < 4; i++)
                    a[i] = po[i], b[i] = ps[i];
                if (w[t] >= 1)
                    memcpy(r, b, sizeof r);
                else
                    affect_quat_slerp(a, b, w[t], r);
                for (int i = 0; i < 4; i++)
                    po[i] = (float)r[i];
            }
        }
    }
}

/* ---- the transfer ---- */

typedef struct change {
    bool on;
    double delta[3];                     /* posture change, rotation vector */
    double ratio[AFFECT_TRANSFER_BANDS]; /* amplitude ratios */
} change;

static affect_status skeletal(const affect_motion *m, const char *what, uint32_t pair,
                              const affect_ik_options *io, affect_motion **made, affect_error *err)
{
    if (!m) {
        if (pair == 0)
            return affect_fail(err, AFFECT_ERR_INVALID, "no %s", what);
        return affect_fail(err, AFFECT_ERR_INVALID, "donor pair %u: its %s is missing", pair - 1,
                           what);
    }
    affect_status st = affect_motion_skeletal(m, AFFECT_ROTATIONS_AUTO, io, made, err);
    if (st && pair == 0)
        return affect_prefix(err, "desired motion");
    if (st)
        return affect_prefix(err, "donor pair %u (%s)", pair - 1, what);
    return AFFECT_OK;
}

/* The changes of every joint of d from the pairs (a[i], b[i]). */
static uint32_t learn(const affect_motion *d, const affect_motion *const *a,
                      const affect_motion *const *b, uint32_t n, const bool *rotational,
                      const affect_transfer_options *opt, scratch *s, change *ch)
{
    uint32_t changed = 0, total = 0;
    double ta[AFFECT_TRANSFER_BANDS] = {0}, tb[AFFECT_TRANSFER_BANDS] = {0};
    double floor = opt->amplitude == AFFECT_TRANSFER_VELOCITY ? VELOCITY_FLOOR : DISPLACEMENT_FLOOR;
    for (uint32_t j = 0; j < d->n_joints; j++) {
        memset(&ch[j], 0, sizeof ch[j]);
        if (!rotational[j])
            continue;
        double ea[AFFECT_TRANSFER_BANDS] = {0}, eb[AFFECT_TRANSFER_BANDS] = {0};
        uint32_t count = 0;
        for (uint32_t i = 0; i < n; i++) {
            int32_t ja = same_joint(a[i], d, j), jb = same_joint(b[i], d, j);
            if (ja < 0 || jb < 0)
                continue;
            double ma[4], mb[4], e1[AFFECT_TRANSFER_BANDS], e2[AFFECT_TRANSFER_BANDS];
            joint_stats(a[i], (uint32_t)ja, opt, s, ma, e1);
            joint_stats(b[i], (uint32_t)jb, opt, s, mb, e2);
            double inv[4], r[4], v[3];
            qconj(ma, inv);
            affect_quat_mul(mb, inv, r);
            affect_quat_log(r, v);
            for (int k = 0; k < 3; k++)
                ch[j].delta[k] += v[k];
            for (int k = 0; k < AFFECT_TRANSFER_BANDS; k++)
                ea[k] += e1[k], eb[k] += e2[k];
            count++;
        }
        if (count == 0)
            continue;
        ch[j].on = true;
        changed++;
        for (int k = 0; k < 3; k++)
            ch[j].delta[k] /= count;
        for (int k = 0; k < AFFECT_TRANSFER_BANDS; k++) {
            double r = sqrt((eb[k] + count * floor) / (ea[k] + count * floor));
            ch[j].ratio[k] = fmin(opt->max_ratio, fmax(1.0 / opt->max_ratio, r));
            ta[k] += ea[k];
            tb[k] += eb[k];
        }
        total += count;
    }
    if (opt->pooled && changed)
        for (int k = 0; k < AFFECT_TRANSFER_BANDS; k++) {
            double r = sqrt((tb[k] + total * floor) / (ta[k] + total * floor));
            r = fmin(opt->max_ratio, fmax(1.0 / opt->max_ratio, r));
            for (uint32_t j = 0; j < d->n_joints; j++)
                ch[j].ratio[k] = ch[j].on ? r : ch[j].ratio[k];
        }
    return changed;
}

/* Applies ch with strength s to the rotations of out (a clone of d). */
static void apply(const affect_motion *d, const change *ch, const affect_transfer_options *opt,
                  scratch *s, affect_motion *out, affect_transfer_report *rep)
{
    uint32_t T = d->n_frames, nj = d->n_joints;
    double st = opt->strength, sum_deg = 0, sum_log[AFFECT_TRANSFER_BANDS] = {0};
    uint32_t changed = 0;
    for (uint32_t j = 0; j < nj; j++) {
        if (!ch[j].on)
            continue;
        double mean[4], pre[4], v[3], gain[AFFECT_TRANSFER_BANDS];
        load_rotations(d, j, s->q);
        mean_rotation(s->q, T, mean);
        split_bands(s->q, T, d->fps, mean, opt->band_hz, s);
        for (int k = 0; k < 3; k++)
            v[k] = st * ch[j].delta[k];
        affect_quat_exp(v, pre);
        affect_quat_mul(pre, mean, pre);
        for (int b = 0; b < AFFECT_TRANSFER_BANDS; b++) {
            gain[b] = pow(ch[j].ratio[b], st);
            sum_log[b] += log(gain[b]);
        }
        sum_deg += sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) * 180 / PI;
        changed++;
        for (uint32_t t = 0; t < T; t++) {
            double e[3] = {0, 0, 0}, r[4], q[4];
            for (int b = 0; b < AFFECT_TRANSFER_BANDS; b++)
                for (int k = 0; k < 3; k++)
                    e[k] += gain[b] * s->band[((size_t)b * T + t) * 3 + (size_t)k];
            double angle = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
            if (angle > PI)
                for (int k = 0; k < 3; k++)
                    e[k] *= PI / angle;
            affect_quat_exp(e, r);
            affect_quat_mul(pre, r, q);
            affect_quat_normalize(q);
            float *p = out->rot + ((size_t)t * nj + j) * 4;
            for (int i = 0; i < 4; i++)
                p[i] = (float)q[i];
        }
    }
    if (rep && changed) {
        rep->joints_changed = changed;
        rep->posture_deg = sum_deg / changed;
        for (int b = 0; b < AFFECT_TRANSFER_BANDS; b++)
            rep->ratio[b] = exp(sum_log[b] / changed);
    }
}

affect_status affect_transfer(const affect_motion *desired, const affect_motion *const *from,
                              const affect_motion *const *to, uint32_t n_pairs,
                              const affect_transfer_options *opt, affect_motion **out,
                              affect_transfer_report *rep, affect_error *err)
{
    *out = NULL;
    if (rep) {
        memset(rep, 0, sizeof *rep);
        rep->ratio[0] = rep->ratio[1] = rep->ratio[2] = 1;
    }
    affect_transfer_options defaults;
    if (!opt) {
        affect_transfer_options_default(&defaults);
        opt = &defaults;
    }
    const char *bad = affect_transfer_options_check(opt);
    if (bad)
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "%s (strength %g, bands %g and %g Hz, "
                           "max_ratio %g)",
                           bad, opt->strength, opt->band_hz[0], opt->band_hz[1], opt->max_ratio);
    if (n_pairs == 0 || !from || !to)
        return affect_fail(err, AFFECT_ERR_INVALID, "no donor pairs");
    affect_ik_options io;
    affect_ik_options_default(&io);
    io.rigid.monitor = opt->monitor;
    affect_status st;
    affect_motion *dmade = NULL, **made = affect_calloc(2 * (size_t)n_pairs, sizeof *made);
    const affect_motion **sk = affect_calloc(2 * (size_t)n_pairs, sizeof *sk);
    change *ch = NULL;
    bool *has_child = NULL, *free_link = NULL;
    scratch s = {NULL, NULL, NULL, NULL};
    affect_motion *res = NULL;
    if (!made || !sk) {
        st = affect_fail(err, AFFECT_ERR_NOMEM, "out of memory");
        goto done;
    }
    if ((st = skeletal(desired, "desired motion", 0, &io, &dmade, err)))
        goto done;
    const affect_motion *d = dmade ? dmade : desired;
    if (rep)
        rep->pairs = n_pairs;
    if ((st = affect_motion_clone(d, &res, err)))
        goto done;
    if (opt->strength == 0)
        goto ok;
    uint32_t longest = d->n_frames;
    for (uint32_t i = 0; i < 2 * n_pairs; i++) {
        const affect_motion *m = i < n_pairs ? from[i] : to[i - n_pairs];
        uint32_t pair = (i < n_pairs ? i : i - n_pairs) + 1;
        if ((st = skeletal(
                 m, i < n_pairs ? "motion in the source emotion" : "motion in the target emotion",
                 pair, &io, &made[i], err)))
            goto done;
        sk[i] = made[i] ? made[i] : m;
        if (sk[i]->n_frames > longest)
            longest = sk[i]->n_frames;
    }
    size_t T = longest;
    ch = affect_calloc(d->n_joints, sizeof *ch);
    has_child = affect_calloc(d->n_joints, sizeof *has_child);
    free_link = affect_calloc(d->n_joints, sizeof *free_link);
    s.q = affect_malloc_array(4 * T, sizeof *s.q);
    s.d = affect_malloc_array(3 * T, sizeof *s.d);
    s.band = affect_malloc_array(9 * T, sizeof *s.band);
    s.tmp = affect_malloc_array(3 * T + 18, sizeof *s.tmp);
    if (!ch || !has_child || !free_link || !s.q || !s.d || !s.band || !s.tmp) {
        st = affect_fail(err, AFFECT_ERR_NOMEM, "out of memory");
        goto done;
    }
    if ((st = affect_motion_free_links(d, free_link, err)))
        goto done;
    /* the joints that change: not a root or free link, with a child that they move */
    for (uint32_t j = 0; j < d->n_joints; j++)
        if (d->parents[j] >= 0)
            has_child[d->parents[j]] = true;
    for (uint32_t j = 0; j < d->n_joints; j++)
        has_child[j] = has_child[j] && d->parents[j] >= 0 && !free_link[j];
    if (learn(d, sk, sk + n_pairs, n_pairs, has_child, opt, &s, ch) == 0) {
        st = affect_fail(err, AFFECT_ERR_INVALID,
                         "no donor pair has a joint of the desired "
                         "motion's skeleton (joint names)");
        goto done;
    }
    if ((st = affect_monitor_check(opt->monitor, err)))
        goto done;
    apply(d, ch, opt, &s, res, rep);
    if ((st = affect_monitor_check(opt->monitor, err)))
        goto done;
    if (opt->keep_contacts) {
        uint32_t contacts[2] = {0, 0};
        hold_legs(d, res, s.tmp, contacts);
        if (rep)
            rep->contact_frames[0] = contacts[0], rep->contact_frames[1] = contacts[1];
    }
    if ((st = affect_motion_fk(res, err)))
        goto done;
ok:
    *out = res;
    res = NULL;
    st = AFFECT_OK;
done:
    affect_motion_free(res);
    affect_motion_free(dmade);
    for (uint32_t i = 0; made && i < 2 * n_pairs; i++)
        affect_motion_free(made[i]);
    affect_free(made);
    affect_free(sk);
    affect_free(ch);
    affect_free(has_child);
    affect_free(free_link);
    affect_free(s.q);
    affect_free(s.d);
    affect_free(s.band);
    affect_free(s.tmp);
    if (st && rep)
        memset(rep, 0, sizeof *rep);
    return st;
}

/* ---- donor pairs and components ---- */

bool affect_transfer_components(const bool *salient, uint32_t p, int32_t source, int32_t target,
                                bool *use)
{
    uint32_t used = 0;
    for (uint32_t j = 0; j < p; j++) {
        bool t = salient[(size_t)target * p + j];
        bool drop = source >= 0 ? t && salient[(size_t)source * p + j] : t;
        use[j] = !drop;
        used += use[j];
    }
    if (used > 0)
        return false;
    for (uint32_t j = 0; j < p; j++)
        use[j] = true;
    return true;
}

/* Euclidean distance of rows a and b of z over the used components both have; NaN when they
 * share none. */
static double row_distance(const double *z, uint32_t p, uint32_t a, uint32_t b, const bool *use)
{
    double sum = 0;
    bool any = false;
    for (uint32_t j = 0; j < p; j++) {
        double u = z[(size_t)a * p + j], v = z[(size_t)b * p + j];
        if (!use[j] || isnan(u) || isnan(v))
            continue;
        sum += (u - v) * (u - v);
        any = true;
    }
    return any ? sqrt(sum) : NAN;
}

affect_status affect_transfer_pairs(const double *x, uint32_t n, uint32_t p, const int32_t *label,
                                    const int64_t *group, const bool *use, const double *dq,
                                    int32_t source, int32_t target, uint32_t n_pairs,
                                    uint32_t n_cand, uint32_t *from, uint32_t *to, double *dist,
                                    uint32_t *got, affect_error *err)
{
    *got = 0;
    double *z = affect_malloc_array((size_t)n * p + 1, sizeof *z);
    bool *taken = affect_calloc((size_t)n + 1, sizeof *taken);
    if (!z || !taken) {
        affect_free(z);
        affect_free(taken);
        return affect_fail(err, AFFECT_ERR_NOMEM, "out of memory");
    }
    /* z-scores: sample standard deviation over the values present, 1 when it is 0 */
    for (uint32_t j = 0; j < p; j++) {
        double sum = 0, sq = 0;
        uint32_t c = 0;
        for (uint32_t i = 0; i < n; i++) {
            double v = x[(size_t)i * p + j];
            if (!isnan(v))
                sum += v, c++;
        }
        double mean = c ? sum / c : 0;
        for (uint32_t i = 0; i < n; i++) {
            double v = x[(size_t)i * p + j];
            if (!isnan(v))
                sq += (v - mean) * (v - mean);
        }
        double sd = c > 1 ? sqrt(sq / (c - 1)) : 0;
        if (!(sd > 0))
            sd = 1;
        for (uint32_t i = 0; i < n; i++)
            z[(size_t)i * p + j] = (x[(size_t)i * p + j] - mean) / sd;
    }
    for (;;) {
        /* the nearest source row not taken yet (ties: the lower row) */
        int64_t a = -1;
        for (uint32_t i = 0; i < n; i++) {
            bool from_ok = source >= 0 ? label[i] == source : label[i] != target;
            if (!from_ok || taken[i] || isnan(dq[i]))
                continue;
            if (a < 0 || dq[i] < dq[a])
                a = i;
        }
        if (a < 0 || *got == n_pairs)
            break;
        taken[a] = true;
        if (group && group[a] == INT64_MIN)
            continue;
        /* its n_cand nearest target rows, nearest first (ties: the lower row) */
        uint32_t *tk = to + (size_t)*got * n_cand;
        double *dk = dist ? dist + (size_t)*got * n_cand : NULL;
        uint32_t found = 0;
        double last = -INFINITY;
        int64_t last_row = -1;
        for (uint32_t c = 0; c < n_cand; c++) {
            int64_t b = -1;
            double best = INFINITY;
            for (uint32_t i = 0; i < n; i++) {
                if (label[i] != target || (uint32_t)a == i || (group && group[i] != group[a]))
                    continue;
                double dd = row_distance(z, p, (uint32_t)a, i, use);
                bool after = dd > last || (dd == last && (int64_t)i > last_row);
                if (!isnan(dd) && after && (dd < best || (dd == best && i < b)))
                    best = dd, b = i;
            }
            tk[c] = b < 0 ? UINT32_MAX : (uint32_t)b;
            if (dk)
                dk[c] = b < 0 ? NAN : best;
            if (b < 0)
                continue;
            found++;
            last = best;
            last_row = b;
        }
        if (found == 0) {
            if (group)
                continue; /* no row of its content in the target emotion: the next one */
            break;
        }
        from[*got] = (uint32_t)a;
        (*got)++;
    }
    affect_free(z);
    affect_free(taken);
    return AFFECT_OK;
}

uint32_t affect_transfer_pick_target(const uint32_t *order, const uint32_t *rows, uint32_t m,
                                     const uint32_t *to, uint32_t k)
{
    for (uint32_t c = 0; c < m; c++) {
        bool used = false;
        for (uint32_t e = 0; e < k && !used; e++)
            used = to[e] == rows[order[c]];
        if (!used)
            return order[c];
    }
    return order[0];
}
