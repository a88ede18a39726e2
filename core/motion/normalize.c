/*
 * normalize.c — remove the first frame's root translation and heading, optionally scale by
 * the right arm length (see affect/normalize.h for the definitions).
 *
 * The heading rotation is about the up axis u. With h the horizontal part of the first
 * frame's lateral vector (left − right) and e the unit axis that should carry it (x for y-up
 * and z-up data, y for x-up data), the rotation turns h onto e; both lie in the plane
 * perpendicular to u, so it is a rotation by the signed angle between them about u.
 * A skeletal motion's roots turn and move with it, so its rotations stay consistent.
 */
#include "affect/normalize.h"
#include "affect/quat.h"

#include <math.h>
#include <string.h>

void affect_normalize_options_default(affect_normalize_options *opt)
{
    opt->up_axis = 1;
    opt->translation = true;
    opt->vertical = false;
    opt->heading = true;
    opt->scale_arm = false;
}

static double dist3(const float *a, const float *b)
{
    double dx = (double)a[0] - b[0], dy = (double)a[1] - b[1], dz = (double)a[2] - b[2];
    return sqrt(dx * dx + dy * dy + dz * dz);
}

void affect_normalize_axis_rotation(int u, double angle, double r[9])
{
    double c = cos(angle), s = sin(angle);
    int a = (u + 1) % 3, b = (u + 2) % 3; /* (a, b, u) is a right-handed frame */
    memset(r, 0, 9 * sizeof *r);
    r[u * 3 + u] = 1;
    r[a * 3 + a] = c;
    r[a * 3 + b] = -s;
    r[b * 3 + a] = s;
    r[b * 3 + b] = c;
}

bool affect_normalize_heading_angle(const double lat[3], int u, double *angle)
{
    int a = (u + 1) % 3, b = (u + 2) % 3;
    double ha = lat[a], hb = lat[b];
    if (!(hypot(ha, hb) >= 1e-9))
        return false;
    /* target axis e: x for y-up or z-up data, y for x-up data */
    int e = u == 0 ? 1 : 0;
    double ea = e == a ? 1 : 0, eb = e == b ? 1 : 0;
    /* turn h onto e: by angle(e) − angle(h), angles measured in the (a, b) plane */
    *angle = atan2(eb, ea) - atan2(hb, ha);
    return true;
}

bool affect_normalize_headings(const affect_motion *m, const affect_roles *roles, int up,
                               double *ang)
{
    uint32_t T = m->n_frames, have = 0;
    double last = 0.0;
    for (uint32_t t = 0; t < T; t++) {
        double lat[3], a;
        if (!affect_roles_lateral(m, roles, t, lat))
            return false;
        if (affect_normalize_heading_angle(lat, up, &a)) {
            if (have == 0)
                for (uint32_t k = 0; k < t; k++)
                    ang[k] = a;
            last = have++ ? last + remainder(a - last, 6.28318530717958647693) : a;
        }
        ang[t] = last;
    }
    return true;
}

affect_status affect_normalize_transform_compute(const affect_motion *m, const affect_roles *roles,
                                                 const affect_normalize_options *opt,
                                                 affect_normalize_transform *tf, affect_error *err)
{
    int u = opt->up_axis;
    if (u < 0 || u > 2)
        return affect_fail(err, AFFECT_ERR_INVALID, "up axis must be x, y or z");
    memset(tf, 0, sizeof *tf);
    tf->rot[0] = tf->rot[4] = tf->rot[8] = 1;
    tf->scale = 1;

    int32_t root = roles->joint[AFFECT_ROLE_PELVIS];
    if (root < 0 || (uint32_t)root >= m->n_joints)
        root = 0;
    const float *rp = affect_motion_at(m, 0, (uint32_t)root);
    if (opt->translation)
        for (int a = 0; a < 3; a++)
            if (a != u || opt->vertical)
                tf->origin[a] = rp[a];

    if (opt->heading) {
        double lat[3];
        if (!affect_roles_lateral(m, roles, 0, lat))
            return affect_fail(err, AFFECT_ERR_MISSING,
                               "cannot find the heading: the left/right hip and shoulder roles are "
                               "not resolved (set them with \"roles\", or \"heading\": false)");
        double angle;
        if (!affect_normalize_heading_angle(lat, u, &angle))
            return affect_fail(err, AFFECT_ERR_INVALID,
                               "cannot find the heading: left and right joints coincide "
                               "horizontally in the first frame");
        affect_normalize_axis_rotation(u, angle, tf->rot);
    }

    if (opt->scale_arm) {
        int32_t s = roles->joint[AFFECT_ROLE_RIGHT_SHOULDER],
                el = roles->joint[AFFECT_ROLE_RIGHT_ELBOW],
                h = roles->joint[AFFECT_ROLE_RIGHT_HAND];
        if (s < 0 || h < 0)
            return affect_fail(err, AFFECT_ERR_MISSING,
                               "cannot scale by the arm: the right_shoulder and right_hand roles "
                               "are not both resolved");
        const float *ps = affect_motion_at(m, 0, (uint32_t)s),
                    *ph = affect_motion_at(m, 0, (uint32_t)h);
        double len = el >= 0 ? dist3(ps, affect_motion_at(m, 0, (uint32_t)el)) +
                                   dist3(affect_motion_at(m, 0, (uint32_t)el), ph)
                             : dist3(ps, ph);
        if (!(len > 1e-9))
            return affect_fail(err, AFFECT_ERR_INVALID,
                               "cannot scale by the arm: its length is zero in the first frame");
        tf->scale = len;
    }
    return AFFECT_OK;
}

/* The same transform on the skeleton: roots' translations and offsets move, turn and scale,
 * roots' rotations turn, every other offset and translation scales, so the forward kinematics
 * of the result are the transformed positions. */
static void transform_skeleton(affect_motion *m, const affect_normalize_transform *tf)
{
    const double *r = tf->rot;
    double inv = 1.0 / tf->scale, qr[4];
    affect_quat_from_matrix(r, qr);
    uint32_t nj = m->n_joints;
    for (uint32_t j = 0; j < nj; j++) {
        double *o = m->skel[j].offset;
        if (m->parents[j] < 0) {
            double x = o[0] - tf->origin[0], y = o[1] - tf->origin[1], z = o[2] - tf->origin[2];
            o[0] = (r[0] * x + r[1] * y + r[2] * z) * inv;
            o[1] = (r[3] * x + r[4] * y + r[5] * z) * inv;
            o[2] = (r[6] * x + r[7] * y + r[8] * z) * inv;
        } else {
            o[0] *= inv, o[1] *= inv, o[2] *= inv;
        }
    }
    if (!m->rot)
        return;
    for (uint32_t t = 0; t < m->n_frames; t++)
        for (uint32_t j = 0; j < nj; j++) {
            float *tr = m->trans + ((size_t)t * nj + j) * 3;
            if (m->parents[j] >= 0) {
                for (int a = 0; a < 3; a++)
                    tr[a] = (float)(tr[a] * inv);
                continue;
            }
            double x = (double)tr[0] - tf->origin[0], y = (double)tr[1] - tf->origin[1],
                   z = (double)tr[2] - tf->origin[2];
            tr[0] = (float)((r[0] * x + r[1] * y + r[2] * z) * inv);
            tr[1] = (float)((r[3] * x + r[4] * y + r[5] * z) * inv);
            tr[2] = (float)((r[6] * x + r[7] * y + r[8] * z) * inv);
            float *qf = m->rot + ((size_t)t * nj + j) * 4;
            double q[4] = {qf[0], qf[1], qf[2], qf[3]};
            affect_quat_mul(qr, q, q);
            for (int a = 0; a < 4; a++)
                qf[a] = (float)q[a];
        }
}

void affect_normalize_apply(affect_motion *m, const affect_normalize_transform *tf)
{
    size_t n = (size_t)m->n_frames * m->n_joints;
    const double *r = tf->rot;
    double inv = 1.0 / tf->scale;
    for (size_t i = 0; i < n; i++) {
        float *p = m->pos + i * 3;
        double x = (double)p[0] - tf->origin[0], y = (double)p[1] - tf->origin[1],
               z = (double)p[2] - tf->origin[2];
        p[0] = (float)((r[0] * x + r[1] * y + r[2] * z) * inv);
        p[1] = (float)((r[3] * x + r[4] * y + r[5] * z) * inv);
        p[2] = (float)((r[6] * x + r[7] * y + r[8] * z) * inv);
    }
    if (tf->scale != 1.0)
        memcpy(m->unit, "arm", 4);
    if (m->skel)
        transform_skeleton(m, tf);
}

affect_status affect_motion_normalize(const affect_motion *m, const affect_roles *roles,
                                      const affect_normalize_options *opt, affect_motion **out,
                                      affect_error *err)
{
    affect_normalize_transform tf;
    affect_status st = affect_normalize_transform_compute(m, roles, opt, &tf, err);
    if (st)
        return st;
    affect_motion *c = NULL;
    st = affect_motion_clone(m, &c, err);
    if (st)
        return st;
    affect_normalize_apply(c, &tf);
    *out = c;
    return AFFECT_OK;
}
