/*
 * features.c — the observation definition stored in every model (see affect/features.h): which
 * joints, normalization, velocities; extraction of the T × dim observations of a motion; the
 * posture motion of model means; the definition's binary form.
 *
 * How it works: every call resolves the definition's entries on the motion at hand (roles by
 * affect_roles_resolve, names exactly), computes the normalization transform of
 * affect/normalize.h from that motion's first frame and applies it, in double precision, to
 * the listed joints only. Velocities are the central differences of the normalized positions
 * times fps. The first training motion also fixes the automatic scale choice, the fps, the
 * unit and the skeleton (names and nearest listed ancestors) shown by posture motions.
 */
#include "affect/features.h"

#include "util/bytes.h"

#include <math.h>
#include <string.h>

#include "util/json.h"
#include "affect/normalize.h"

void affect_features_options_default(affect_features_options *opt)
{
    opt->joints = NULL;
    opt->n_joints = 0;
    opt->frame = AFFECT_FEATURES_FRAME_FIRST;
    opt->normalize = true;
    opt->scale = AFFECT_FEATURES_SCALE_AUTO;
    opt->up_axis = 1;
    opt->velocity = false;
    opt->root = false;
}

enum { ROOT_DIMS = 4 }; /* root velocity (3) and turning rate */

void affect_features_free(affect_features *f)
{
    if (!f)
        return;
    for (uint32_t j = 0; j < f->n_joints; j++) {
        if (f->joints)
            affect_free(f->joints[j]);
        if (f->skeleton)
            affect_free(f->skeleton[j]);
    }
    affect_free(f->joints);
    affect_free(f->skeleton);
    affect_free(f->parents);
    affect_free(f);
}

uint32_t affect_features_dim(const affect_features *f)
{
    return f->n_joints * 3u * (f->velocity ? 2u : 1u) + (f->root ? ROOT_DIMS : 0u);
}

/* An empty definition with room for n entries (names NULL, parents −1). */
static affect_features *features_alloc(uint32_t n)
{
    affect_features *f = affect_calloc(1, sizeof *f);
    if (!f)
        return NULL;
    f->n_joints = n;
    f->joints = affect_calloc(n, sizeof *f->joints);
    f->skeleton = affect_calloc(n, sizeof *f->skeleton);
    f->parents = affect_malloc_array(n, sizeof *f->parents);
    if (!f->joints || !f->skeleton || !f->parents) {
        affect_features_free(f);
        return NULL;
    }
    for (uint32_t j = 0; j < n; j++)
        f->parents[j] = -1;
    return f;
}

/* The joint of m that entry names, or a MISSING error. */
static affect_status resolve_entry(const char *entry, const affect_motion *m,
                                   const affect_roles *roles, uint32_t *joint, affect_error *err)
{
    int r = affect_role_from_name(entry);
    int32_t j = r >= 0 ? roles->joint[r] : affect_motion_find_joint(m, entry);
    if (j >= 0 && (uint32_t)j < m->n_joints) {
        *joint = (uint32_t)j;
        return AFFECT_OK;
    }
    if (r >= 0)
        return affect_fail(err, AFFECT_ERR_MISSING,
                           "no joint of the motion has the %s role (used by the model)",
                           affect_role_name((affect_role)r));
    char q[80];
    affect_json_quote(q, sizeof q, entry, strlen(entry));
    return affect_fail(err, AFFECT_ERR_MISSING, "joint %s of the model is not in the motion", q);
}

static bool arm_resolves(const affect_roles *roles)
{
    return roles->joint[AFFECT_ROLE_RIGHT_SHOULDER] >= 0 &&
           roles->joint[AFFECT_ROLE_RIGHT_HAND] >= 0;
}

affect_status affect_features_create(const affect_features_options *opt, const affect_motion *first,
                                     affect_features **out, affect_error *err)
{
    if (opt->up_axis < 0 || opt->up_axis > 2)
        return affect_fail(err, AFFECT_ERR_INVALID, "up axis must be x, y or z");
    if (opt->frame != AFFECT_FEATURES_FRAME_FIRST && opt->frame != AFFECT_FEATURES_FRAME_BODY)
        return affect_fail(err, AFFECT_ERR_INVALID, "frame must be first or body");
    if (opt->root && opt->frame != AFFECT_FEATURES_FRAME_BODY)
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "root velocity and turning rate need the body frame");
    if (opt->joints && opt->n_joints == 0)
        return affect_fail(err, AFFECT_ERR_INVALID, "the joint list is empty");
    uint32_t n = opt->joints ? opt->n_joints : first->n_joints;
    if (n > AFFECT_MOTION_MAX_JOINTS)
        return affect_fail(err, AFFECT_ERR_RANGE, "%u joints listed; at most %u", n,
                           AFFECT_MOTION_MAX_JOINTS);
    char q[80], q2[80];
    for (uint32_t j = 0; opt->joints && j < n; j++) {
        const char *e = opt->joints[j];
        size_t len = strlen(e);
        if (len == 0 || len > AFFECT_MOTION_MAX_NAME)
            return affect_fail(err, AFFECT_ERR_INVALID,
                               "joint entry %u: a name must have 1 to %u bytes", j + 1,
                               AFFECT_MOTION_MAX_NAME);
        affect_status ust =
            affect_utf8_check(err, AFFECT_ERR_INVALID, e, len, "joint entry %u: the name", j + 1);
        if (ust)
            return ust;
        for (uint32_t k = 0; k < j; k++)
            if (strcmp(opt->joints[k], e) == 0) {
                affect_json_quote(q, sizeof q, e, len);
                return affect_fail(err, AFFECT_ERR_INVALID, "joint %s is listed twice", q);
            }
    }
    affect_roles roles;
    affect_roles_resolve(first, &roles);
    affect_status st = AFFECT_OK;
    int32_t *entry_of = NULL; /* joint of first → entry index, or −1 */
    uint32_t *joint_of = NULL;
    affect_features *f = features_alloc(n);
    entry_of = affect_malloc_array(first->n_joints, sizeof *entry_of);
    joint_of = affect_malloc_array(n, sizeof *joint_of);
    if (!f || !entry_of || !joint_of) {
        st = affect_nomem(err);
        goto done;
    }
    for (uint32_t j = 0; j < first->n_joints; j++)
        entry_of[j] = -1;
    for (uint32_t e = 0; e < n; e++) {
        const char *name = opt->joints ? opt->joints[e] : first->names[e];
        uint32_t j = e;
        if (opt->joints && (st = resolve_entry(name, first, &roles, &j, err)) != AFFECT_OK)
            goto done;
        if (entry_of[j] >= 0) {
            const char *other = opt->joints[entry_of[j]];
            affect_json_quote(q, sizeof q, other, strlen(other));
            affect_json_quote(q2, sizeof q2, name, strlen(name));
            char q3[80];
            affect_json_quote(q3, sizeof q3, first->names[j], strlen(first->names[j]));
            st = affect_fail(err, AFFECT_ERR_INVALID, "joints %s and %s are the same joint %s", q,
                             q2, q3);
            goto done;
        }
        entry_of[j] = (int32_t)e;
        joint_of[e] = j;
        f->joints[e] = affect_strndup(name, strlen(name));
        f->skeleton[e] = affect_strndup(first->names[j], strlen(first->names[j]));
        if (!f->joints[e] || !f->skeleton[e]) {
            st = affect_nomem(err);
            goto done;
        }
    }
    /* nearest listed ancestor (the motion's parents are acyclic) */
    for (uint32_t e = 0; e < n; e++) {
        int32_t p = first->parents[joint_of[e]];
        for (uint32_t steps = 0; p >= 0 && entry_of[p] < 0 && steps < first->n_joints; steps++)
            p = first->parents[p];
        f->parents[e] = p >= 0 ? entry_of[p] : -1;
    }
    f->up_axis = opt->up_axis;
    f->frame = opt->frame;
    f->root = opt->root;
    f->normalize = opt->frame == AFFECT_FEATURES_FRAME_FIRST && opt->normalize;
    f->scale_arm = opt->scale == AFFECT_FEATURES_SCALE_ARM ||
                   (opt->scale == AFFECT_FEATURES_SCALE_AUTO && arm_resolves(&roles));
    f->velocity = opt->velocity;
    f->fps = first->fps;
    const char *unit = f->scale_arm ? "arm" : first->unit;
    size_t unit_len = strlen(unit);
    memcpy(f->unit, unit, unit_len + 1); /* ≤ AFFECT_MOTION_UNIT_MAX: a motion's unit */
    *out = f;
    f = NULL;
done:
    affect_features_free(f);
    affect_free(entry_of);
    affect_free(joint_of);
    return st;
}

/* affect_features_extract polls the monitor between slices of this many frames */
#define FEATURES_POLL_FRAMES 8192

/* Positions in the body frame of frames t0 .. t1 − 1, and the root columns, into obs (T × dim). */
static void body_positions(const affect_features *f, const affect_motion *m, const uint32_t *idx,
                           uint32_t root, const double *ang, double scale, uint32_t t0, uint32_t t1,
                           double *obs)
{
    uint32_t J = f->n_joints, T = m->n_frames, dim = affect_features_dim(f);
    double inv = 1.0 / scale;
    for (uint32_t t = t0; t < t1; t++) {
        double r[9], *row = obs + (size_t)t * dim;
        affect_normalize_axis_rotation(f->up_axis, ang[t], r);
        const float *o = affect_motion_at(m, t, root);
        for (uint32_t e = 0; e < J; e++) {
            const float *p = affect_motion_at(m, t, idx[e]);
            double a = (double)p[0] - o[0], b = (double)p[1] - o[1], c = (double)p[2] - o[2];
            row[e * 3 + 0] = (r[0] * a + r[1] * b + r[2] * c) * inv;
            row[e * 3 + 1] = (r[3] * a + r[4] * b + r[5] * c) * inv;
            row[e * 3 + 2] = (r[6] * a + r[7] * b + r[8] * c) * inv;
        }
        if (!f->root)
            continue;
        double *rc = row + dim - ROOT_DIMS;
        if (T == 1) {
            memset(rc, 0, ROOT_DIMS * sizeof *rc);
            continue;
        }
        uint32_t ta = t > 0 ? t - 1 : 0, tb = t + 1 < T ? t + 1 : T - 1;
        double k = m->fps / (double)(tb - ta);
        const float *pa = affect_motion_at(m, ta, root), *pb = affect_motion_at(m, tb, root);
        double a = ((double)pb[0] - pa[0]) * k, b = ((double)pb[1] - pa[1]) * k,
               c = ((double)pb[2] - pa[2]) * k;
        rc[0] = (r[0] * a + r[1] * b + r[2] * c) * inv;
        rc[1] = (r[3] * a + r[4] * b + r[5] * c) * inv;
        rc[2] = (r[6] * a + r[7] * b + r[8] * c) * inv;
        rc[3] = -(ang[tb] - ang[ta]) * k; /* the heading turns opposite to its correction */
    }
}

/* Positions of frames t0 .. t1 − 1 in the first frame's normalized frame (tf) into obs (T × dim).
 */
static void first_positions(const affect_features *f, const affect_motion *m, const uint32_t *idx,
                            const affect_normalize_transform *tf, uint32_t t0, uint32_t t1,
                            double *obs)
{
    uint32_t J = f->n_joints, dim = affect_features_dim(f);
    const double *r = tf->rot;
    double inv = 1.0 / tf->scale;
    for (uint32_t t = t0; t < t1; t++) {
        double *row = obs + (size_t)t * dim;
        for (uint32_t e = 0; e < J; e++) {
            const float *p = affect_motion_at(m, t, idx[e]);
            double a = (double)p[0] - tf->origin[0], b = (double)p[1] - tf->origin[1],
                   c = (double)p[2] - tf->origin[2];
            row[e * 3 + 0] = (r[0] * a + r[1] * b + r[2] * c) * inv;
            row[e * 3 + 1] = (r[3] * a + r[4] * b + r[5] * c) * inv;
            row[e * 3 + 2] = (r[6] * a + r[7] * b + r[8] * c) * inv;
        }
    }
}

/* Velocities of frames t0 .. t1 − 1: central differences × fps of the positions already in
 * obs (every frame's). */
static void velocities(const affect_features *f, const affect_motion *m, uint32_t t0, uint32_t t1,
                       double *obs)
{
    uint32_t T = m->n_frames, dim = affect_features_dim(f);
    size_t np = (size_t)f->n_joints * 3;
    for (uint32_t t = t0; t < t1; t++) {
        double *v = obs + (size_t)t * dim + np;
        if (T == 1) {
            memset(v, 0, np * sizeof *v);
            continue;
        }
        uint32_t a = t > 0 ? t - 1 : 0, b = t + 1 < T ? t + 1 : T - 1;
        const double *pa = obs + (size_t)a * dim, *pb = obs + (size_t)b * dim;
        double k = m->fps / (double)(b - a);
        for (size_t i = 0; i < np; i++)
            v[i] = (pb[i] - pa[i]) * k;
    }
}

/* What the positions' transform of m needs: each entry's joint (idx, J), the root, each frame's
 * heading (ang, T; body frame) and the first frame's transform (tf; identity when neither
 * normalization nor scaling is asked). Free idx and ang with affect_free, also on failure. */
typedef struct frames_ctx {
    uint32_t *idx;
    double *ang;
    affect_normalize_transform tf;
    uint32_t root;
} frames_ctx;

static affect_status frames_setup(const affect_features *f, const affect_motion *m, frames_ctx *c,
                                  affect_monitor *mon, affect_error *err)
{
    uint32_t J = f->n_joints, T = m->n_frames;
    c->idx = NULL;
    c->ang = NULL;
    /* observations not scaled by the arm are in the motions' unit: one of another unit would
     * be 100 times off (cm against m) without a word */
    if (!f->scale_arm && f->unit[0] && m->unit[0] && strcmp(f->unit, m->unit) != 0)
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "the motion is in %s, the observations in %s (convert it, or use "
                           "motions of one unit; {\"scale\":\"arm\"} makes observations "
                           "unit-free)",
                           m->unit, f->unit);
    bool body = f->frame == AFFECT_FEATURES_FRAME_BODY;
    affect_roles roles;
    affect_roles_resolve(m, &roles);
    c->idx = affect_malloc_array(J, sizeof *c->idx);
    if (!c->idx || (body && !(c->ang = affect_malloc_array(T ? T : 1, sizeof *c->ang))))
        return affect_nomem(err);
    affect_status st;
    for (uint32_t e = 0; e < J; e++)
        if ((st = resolve_entry(f->joints[e], m, &roles, &c->idx[e], err)) != AFFECT_OK)
            return st;
    memset(&c->tf, 0, sizeof c->tf);
    c->tf.rot[0] = c->tf.rot[4] = c->tf.rot[8] = 1;
    c->tf.scale = 1;
    if (body && !affect_normalize_headings(m, &roles, f->up_axis, c->ang))
        return affect_fail(err, AFFECT_ERR_MISSING,
                           "cannot find the body frame: no left/right hip or shoulder roles "
                           "resolve in the motion (train with {\"frame\": \"first\", "
                           "\"normalize\": false})");
    if ((st = affect_monitor_check(mon, err)) != AFFECT_OK) /* between the passes */
        return st;
    if (f->normalize || f->scale_arm) {
        double lat[3];
        if (f->normalize && !affect_roles_lateral(m, &roles, 0, lat))
            return affect_fail(err, AFFECT_ERR_MISSING,
                               "cannot remove the heading: no left/right hip or shoulder roles "
                               "resolve in the motion (train with {\"normalize\": false})");
        if (f->scale_arm && !arm_resolves(&roles))
            return affect_fail(err, AFFECT_ERR_MISSING,
                               "cannot scale by the arm: the right_shoulder and right_hand roles "
                               "do not both resolve in the motion (train with {\"scale\": "
                               "\"none\"})");
        affect_normalize_options no;
        affect_normalize_options_default(&no);
        no.up_axis = f->up_axis;
        no.translation = no.heading = f->normalize;
        no.scale_arm = f->scale_arm;
        if ((st = affect_normalize_transform_compute(m, &roles, &no, &c->tf, err)) != AFFECT_OK)
            return st;
    }
    int32_t root = roles.joint[AFFECT_ROLE_PELVIS];
    c->root = root < 0 || (uint32_t)root >= m->n_joints ? 0 : (uint32_t)root;
    return AFFECT_OK;
}

affect_status affect_features_extract(const affect_features *f, const affect_motion *m, double **x,
                                      uint32_t *n_frames, affect_monitor *mon, affect_error *err)
{
    uint32_t T = m->n_frames, dim = affect_features_dim(f);
    size_t n_vals;
    if (!affect_mul_size(T, dim, &n_vals))
        return affect_fail(err, AFFECT_ERR_RANGE, "too many observations");
    bool body = f->frame == AFFECT_FEATURES_FRAME_BODY;
    frames_ctx c;
    double *obs = NULL;
    affect_status st = frames_setup(f, m, &c, mon, err);
    if (st != AFFECT_OK)
        goto fail;
    obs = affect_malloc_array(n_vals, sizeof *obs);
    if (!obs) {
        st = affect_nomem(err);
        goto fail;
    }
    /* the positions, then the velocities (which read the neighbours' positions), in slices of
     * FEATURES_POLL_FRAMES between polls */
    for (uint32_t t0 = 0; t0 < T; t0 += FEATURES_POLL_FRAMES) {
        uint32_t t1 = T - t0 < FEATURES_POLL_FRAMES ? T : t0 + FEATURES_POLL_FRAMES;
        if ((st = affect_monitor_check(mon, err)) != AFFECT_OK)
            goto fail;
        if (body)
            body_positions(f, m, c.idx, c.root, c.ang, c.tf.scale, t0, t1, obs);
        else
            first_positions(f, m, c.idx, &c.tf, t0, t1, obs);
    }
    for (uint32_t t0 = 0; f->velocity && t0 < T; t0 += FEATURES_POLL_FRAMES) {
        uint32_t t1 = T - t0 < FEATURES_POLL_FRAMES ? T : t0 + FEATURES_POLL_FRAMES;
        if ((st = affect_monitor_check(mon, err)) != AFFECT_OK)
            goto fail;
        velocities(f, m, t0, t1, obs);
    }
    if ((st = affect_monitor_check(mon, err)) != AFFECT_OK)
        goto fail;
    affect_free(c.idx);
    affect_free(c.ang);
    *x = obs;
    *n_frames = T;
    return AFFECT_OK;
fail:
    affect_free(c.idx);
    affect_free(c.ang);
    affect_free(obs);
    return st;
}

affect_status affect_features_position_gradient(const affect_features *f, const affect_motion *m,
                                                const double *g, double *out, affect_monitor *mon,
                                                affect_error *err)
{
    if (f->velocity || f->root)
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "the observations have velocity or root columns: only positions map "
                           "back to the joints");
    uint32_t J = f->n_joints, T = m->n_frames, dim = affect_features_dim(f);
    frames_ctx c;
    affect_status st = frames_setup(f, m, &c, mon, err);
    if (st == AFFECT_OK) {
        bool body = f->frame == AFFECT_FEATURES_FRAME_BODY;
        memset(out, 0, (size_t)T * m->n_joints * 3 * sizeof *out);
        double inv = 1.0 / c.tf.scale, r[9];
        memcpy(r, c.tf.rot, sizeof r);
        for (uint32_t t = 0; t < T; t++) {
            if (t % FEATURES_POLL_FRAMES == 0 && (st = affect_monitor_check(mon, err)) != AFFECT_OK)
                break;
            if (body)
                affect_normalize_axis_rotation(f->up_axis, c.ang[t], r);
            const double *row = g + (size_t)t * dim;
            double *o = out + (size_t)t * m->n_joints * 3, *root = o + (size_t)c.root * 3;
            for (uint32_t e = 0; e < J; e++) { /* the transpose of p ↦ r p / scale */
                const double *ge = row + (size_t)e * 3;
                double *oe = o + (size_t)c.idx[e] * 3;
                for (int k = 0; k < 3; k++) {
                    double v = (r[k] * ge[0] + r[3 + k] * ge[1] + r[6 + k] * ge[2]) * inv;
                    oe[k] += v;
                    if (body)
                        root[k] -= v; /* positions relative to the root */
                }
            }
        }
    }
    affect_free(c.idx);
    affect_free(c.ang);
    return st;
}

/* name with Left ↔ Right and the L ↔ R tokens swapped, into out (same length). */
static void mirrored_name(const char *name, char *out)
{
    static const char *const words[][2] = {{"Left", "Right"}, {"left", "right"}, {"LEFT", "RIGHT"}};
    size_t len = strlen(name), o = 0;
    for (size_t i = 0; i < len;) {
        bool done = false;
        for (size_t w = 0; w < 3 && !done; w++)
            for (int side = 0; side < 2 && !done; side++) {
                const char *from = words[w][side], *to = words[w][!side];
                size_t fl = strlen(from);
                if (strncmp(name + i, from, fl) == 0) {
                    memcpy(out + o, to, strlen(to));
                    o += strlen(to);
                    i += fl;
                    done = true;
                }
            }
        if (done)
            continue;
        char ch = name[i];
        bool alone = (i == 0 || strchr("_.-:", name[i - 1])) &&
                     (i + 1 == len || strchr("_.-:", name[i + 1]));
        if (alone && (ch == 'L' || ch == 'R' || ch == 'l' || ch == 'r'))
            ch = ch == 'L' ? 'R' : ch == 'R' ? 'L' : ch == 'l' ? 'r' : 'l';
        out[o++] = ch;
        i++;
    }
    out[o] = '\0';
}

affect_status affect_features_mirror_map(const affect_features *f, uint32_t *partner,
                                         affect_error *err)
{
    if (f->frame != AFFECT_FEATURES_FRAME_BODY && !f->normalize)
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "mirroring needs the body frame or normalized positions");
    char m[2 * AFFECT_MOTION_MAX_NAME + 1];
    for (uint32_t e = 0; e < f->n_joints; e++) {
        mirrored_name(f->skeleton[e], m);
        partner[e] = UINT32_MAX;
        for (uint32_t k = 0; k < f->n_joints; k++)
            if (strcmp(f->skeleton[k], m) == 0)
                partner[e] = k;
        if (partner[e] == UINT32_MAX) {
            char q[80], q2[80];
            affect_json_quote(q, sizeof q, f->skeleton[e], strlen(f->skeleton[e]));
            affect_json_quote(q2, sizeof q2, m, strlen(m));
            return affect_fail(err, AFFECT_ERR_INVALID,
                               "joint %s has no mirror partner (%s is not among the observed "
                               "joints)",
                               q, q2);
        }
    }
    return AFFECT_OK;
}

void affect_features_mirror(const affect_features *f, const uint32_t *partner, const double *x,
                            uint32_t n_frames, double *out)
{
    uint32_t J = f->n_joints, dim = affect_features_dim(f);
    int lat = f->up_axis == 0 ? 1 : 0;
    uint32_t blocks = f->velocity ? 2 : 1;
    for (uint32_t t = 0; t < n_frames; t++) {
        const double *r = x + (size_t)t * dim;
        double *w = out + (size_t)t * dim;
        for (uint32_t b = 0; b < blocks; b++)
            for (uint32_t e = 0; e < J; e++)
                for (int k = 0; k < 3; k++) {
                    double v = r[(size_t)b * 3 * J + 3 * e + k];
                    w[(size_t)b * 3 * J + 3 * partner[e] + k] = k == lat ? -v : v;
                }
        if (f->root) {
            const double *rr = r + dim - ROOT_DIMS;
            double *wr = w + dim - ROOT_DIMS;
            for (int k = 0; k < 3; k++)
                wr[k] = k == lat ? -rr[k] : rr[k];
            wr[3] = -rr[3];
        }
    }
}

affect_status affect_features_posture_motion(const affect_features *f, const double *x,
                                             uint32_t n_frames, affect_motion **out,
                                             affect_error *err)
{
    affect_motion *m = NULL;
    affect_status st = affect_motion_create(n_frames, f->n_joints, f->fps, &m, err);
    if (st)
        return st;
    uint32_t dim = affect_features_dim(f);
    for (uint32_t j = 0; j < f->n_joints; j++) {
        st = affect_motion_set_name(m, j, f->skeleton[j], strlen(f->skeleton[j]), err);
        if (st)
            goto fail;
        m->parents[j] = f->parents[j];
    }
    if ((st = affect_motion_set_unit(m, f->unit, err)) != AFFECT_OK)
        goto fail;
    for (uint32_t t = 0; t < n_frames; t++)
        for (uint32_t i = 0; i < f->n_joints * 3; i++)
            m->pos[(size_t)t * f->n_joints * 3 + i] = (float)x[(size_t)t * dim + i];
    if ((st = affect_motion_validate(m, err)) != AFFECT_OK)
        goto fail;
    *out = m;
    return AFFECT_OK;
fail:
    affect_motion_free(m);
    return st;
}

/* ---- binary form ---- */

enum { FLAG_NORMALIZE = 1, FLAG_SCALE_ARM = 2, FLAG_VELOCITY = 4, FLAG_BODY = 8, FLAG_ROOT = 16 };

bool affect_features_encoded_size(const affect_features *f, size_t *size)
{
    size_t total = AFFECT_FEATURES_HEADER_SIZE + strlen(f->unit);
    for (uint32_t j = 0; j < f->n_joints; j++)
        if (!affect_add_size(total, 4 + strlen(f->joints[j]) + strlen(f->skeleton[j]), &total))
            return false;
    if (!affect_add_size(total, (size_t)f->n_joints * 4, &total))
        return false;
    *size = total;
    return true;
}

static unsigned char *put_name(unsigned char *p, const char *s)
{
    size_t len = strlen(s);
    affect_put_u16(p, (uint16_t)len);
    memcpy(p + 2, s, len);
    return p + 2 + len;
}

void affect_features_encode_into(const affect_features *f, unsigned char *buf)
{
    size_t unit_len = strlen(f->unit);
    buf[0] = (unsigned char)f->up_axis;
    buf[1] =
        (unsigned char)((f->normalize ? FLAG_NORMALIZE : 0) | (f->scale_arm ? FLAG_SCALE_ARM : 0) |
                        (f->velocity ? FLAG_VELOCITY : 0) |
                        (f->frame == AFFECT_FEATURES_FRAME_BODY ? FLAG_BODY : 0) |
                        (f->root ? FLAG_ROOT : 0));
    buf[2] = (unsigned char)unit_len;
    buf[3] = 0;
    affect_put_u32(buf + 4, f->n_joints);
    affect_put_f64(buf + 8, f->fps);
    unsigned char *p = buf + AFFECT_FEATURES_HEADER_SIZE;
    memcpy(p, f->unit, unit_len);
    p += unit_len;
    for (uint32_t j = 0; j < f->n_joints; j++)
        p = put_name(p, f->joints[j]);
    for (uint32_t j = 0; j < f->n_joints; j++)
        p = put_name(p, f->skeleton[j]);
    for (uint32_t j = 0; j < f->n_joints; j++, p += 4)
        affect_put_u32(p, (uint32_t)f->parents[j]);
}

/* Reads one length-prefixed name at *off into a new string *out. */
static affect_status get_name(const unsigned char *data, size_t size, size_t *off, const char *what,
                              uint32_t j, char **out, affect_error *err)
{
    if (size - *off < 2)
        return affect_fail(err, AFFECT_ERR_FORMAT, "truncated in %s %u (offset %zu)", what, j,
                           *off);
    size_t len = affect_get_u16(data + *off);
    if (len == 0 || len > AFFECT_MOTION_MAX_NAME)
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "%s %u: length %zu out of range (1 .. %u) at offset %zu", what, j, len,
                           AFFECT_MOTION_MAX_NAME, *off);
    if (size - *off - 2 < len)
        return affect_fail(err, AFFECT_ERR_FORMAT, "truncated in %s %u (offset %zu)", what, j,
                           *off);
    if (memchr(data + *off + 2, '\0', len))
        return affect_fail(err, AFFECT_ERR_FORMAT, "%s %u contains a NUL byte (offset %zu)", what,
                           j, *off);
    affect_status st = affect_utf8_check(err, AFFECT_ERR_FORMAT, (const char *)data + *off + 2, len,
                                         "%s %u", what, j);
    if (st)
        return st;
    *out = affect_strndup((const char *)data + *off + 2, len);
    if (!*out)
        return affect_nomem(err);
    *off += 2 + len;
    return AFFECT_OK;
}

static bool unit_char_ok(unsigned char c)
{
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
           c == '.' || c == '-';
}

affect_status affect_features_decode(const unsigned char *data, size_t size, affect_features **out,
                                     affect_error *err)
{
    if (size < AFFECT_FEATURES_HEADER_SIZE)
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "truncated: %zu bytes is shorter than the "
                           "%u-byte header",
                           size, AFFECT_FEATURES_HEADER_SIZE);
    int up = data[0];
    unsigned flags = data[1];
    size_t unit_len = data[2];
    uint32_t n = affect_get_u32(data + 4);
    double fps = affect_get_f64(data + 8);
    if (up > 2)
        return affect_fail(err, AFFECT_ERR_FORMAT, "up axis %d out of range (0 .. 2)", up);
    if (flags &
        ~(unsigned)(FLAG_NORMALIZE | FLAG_SCALE_ARM | FLAG_VELOCITY | FLAG_BODY | FLAG_ROOT))
        return affect_fail(err, AFFECT_ERR_FORMAT, "unknown flags 0x%02x (offset 1)", flags);
    if ((flags & FLAG_BODY) && (flags & FLAG_NORMALIZE))
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "flags 0x%02x: normalize and the body frame exclude each other "
                           "(offset 1)",
                           flags);
    if ((flags & FLAG_ROOT) && !(flags & FLAG_BODY))
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "flags 0x%02x: root needs the body frame (offset 1)", flags);
    if (data[3] != 0)
        return affect_fail(err, AFFECT_ERR_FORMAT, "reserved byte 3 is not zero");
    if (n < 1 || n > AFFECT_MOTION_MAX_JOINTS)
        return affect_fail(err, AFFECT_ERR_FORMAT, "joint count %u out of range (1 .. %u)", n,
                           AFFECT_MOTION_MAX_JOINTS);
    if (!(fps > 0.0) || !(fps <= AFFECT_MOTION_MAX_FPS))
        return affect_fail(err, AFFECT_ERR_FORMAT, "frames per second %g out of range (0 .. %g]",
                           fps, AFFECT_MOTION_MAX_FPS);
    size_t off = AFFECT_FEATURES_HEADER_SIZE;
    if (unit_len > AFFECT_MOTION_UNIT_MAX || size - off < unit_len)
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "truncated or bad unit (length %zu at "
                           "offset 2)",
                           unit_len);
    for (size_t i = 0; i < unit_len; i++)
        if (!unit_char_ok(data[off + i]))
            return affect_fail(err, AFFECT_ERR_FORMAT, "bad unit character at offset %zu", off + i);
    affect_features *f = features_alloc(n);
    if (!f)
        return affect_nomem(err);
    memcpy(f->unit, data + off, unit_len);
    f->unit[unit_len] = '\0';
    off += unit_len;
    f->up_axis = up;
    f->normalize = (flags & FLAG_NORMALIZE) != 0;
    f->scale_arm = (flags & FLAG_SCALE_ARM) != 0;
    f->velocity = (flags & FLAG_VELOCITY) != 0;
    f->frame = (flags & FLAG_BODY) ? AFFECT_FEATURES_FRAME_BODY : AFFECT_FEATURES_FRAME_FIRST;
    f->root = (flags & FLAG_ROOT) != 0;
    f->fps = fps;
    affect_status st = AFFECT_OK;
    for (uint32_t j = 0; j < n && !st; j++)
        st = get_name(data, size, &off, "joint entry", j, &f->joints[j], err);
    for (uint32_t j = 0; j < n && !st; j++)
        st = get_name(data, size, &off, "skeleton name", j, &f->skeleton[j], err);
    if (st)
        goto fail;
    if (size - off != (size_t)n * 4) {
        st = affect_fail(err, AFFECT_ERR_FORMAT, "%s: %zu bytes, expected %zu for %u joints",
                         size - off < (size_t)n * 4 ? "truncated" : "trailing bytes", size,
                         off + (size_t)n * 4, n);
        goto fail;
    }
    for (uint32_t j = 0; j < n; j++, off += 4) {
        int32_t p = (int32_t)affect_get_u32(data + off);
        if (p < -1 || p >= (int32_t)n) {
            st = affect_fail(err, AFFECT_ERR_FORMAT, "parent %d of joint %u out of range", (int)p,
                             j);
            goto fail;
        }
        f->parents[j] = p;
    }
    for (uint32_t j = 0; j < n; j++) { /* acyclic: every chain ends within n steps */
        int32_t p = f->parents[j];
        uint32_t steps = 0;
        while (p >= 0 && steps++ <= n)
            p = f->parents[p];
        if (p >= 0) {
            st = affect_fail(err, AFFECT_ERR_FORMAT, "joint %u is its own ancestor", j);
            goto fail;
        }
    }
    for (uint32_t j = 0; j < n; j++)
        for (uint32_t k = 0; k < j; k++)
            if (strcmp(f->skeleton[j], f->skeleton[k]) == 0 ||
                strcmp(f->joints[j], f->joints[k]) == 0) {
                st = affect_fail(err, AFFECT_ERR_FORMAT, "joints %u and %u have the same name", k,
                                 j);
                goto fail;
            }
    *out = f;
    return AFFECT_OK;
fail:
    affect_features_free(f);
    return st;
}
