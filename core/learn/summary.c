/*
 * summary.c — kinematic summaries of a whole motion (see affect/summary.h).
 *
 * How it works: one pass turns the five end-effectors into the body frame of every frame
 * (affect_normalize_headings for the heading, the pelvis as origin, the arm length as unit),
 * keeping per frame the pelvis's horizontal speed and height; speeds are central differences of
 * the stored series; means, percentiles (nearest rank on a sorted copy) and the posture means
 * follow.
 */
#include "affect/summary.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "affect/laban.h"
#include "affect/normalize.h"

const char *const affect_summary_names[AFFECT_SUMMARY_N] = {"duration",
                                                            "root_speed",
                                                            "root_speed_p90",
                                                            "root_bounce",
                                                            "turn_rate",
                                                            "net_turn",
                                                            "head_speed",
                                                            "left_hand_speed",
                                                            "right_hand_speed",
                                                            "left_foot_speed",
                                                            "right_foot_speed",
                                                            "head_speed_p90",
                                                            "left_hand_speed_p90",
                                                            "right_hand_speed_p90",
                                                            "left_foot_speed_p90",
                                                            "right_foot_speed_p90",
                                                            "head_height",
                                                            "head_forward",
                                                            "hand_height",
                                                            "hand_spread",
                                                            "foot_spread"};

enum { N_EFF = 5 }; /* head, left hand, right hand, left foot, right foot */

static const affect_role effectors[N_EFF] = {AFFECT_ROLE_HEAD, AFFECT_ROLE_LEFT_HAND,
                                             AFFECT_ROLE_RIGHT_HAND, AFFECT_ROLE_LEFT_FOOT,
                                             AFFECT_ROLE_RIGHT_FOOT};

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Nearest-rank 90th percentile of v (n ≥ 1), sorting v in place. */
static double p90(double *v, uint32_t n)
{
    qsort(v, n, sizeof *v, cmp_double);
    uint32_t rank = (uint32_t)ceil(0.9 * n);
    return v[rank ? rank - 1 : 0];
}

static double mean(const double *v, uint32_t n)
{
    double s = 0.0;
    for (uint32_t i = 0; i < n; i++)
        s += v[i];
    return s / n;
}

/* Speeds (central differences × fps) of the 3-vectors p (T × stride, the 3 values at offset
 * off; only `dims` of them when dims < 3, the horizontal ones listed in axes) into sp. */
static void speeds(const double *p, uint32_t T, size_t stride, const int *axes, int dims,
                   double fps, double *sp)
{
    for (uint32_t t = 0; t < T; t++) {
        if (T == 1) {
            sp[t] = 0.0;
            continue;
        }
        uint32_t a = t > 0 ? t - 1 : 0, b = t + 1 < T ? t + 1 : T - 1;
        double k = fps / (double)(b - a), s = 0.0;
        for (int i = 0; i < dims; i++) {
            double d = (p[(size_t)b * stride + axes[i]] - p[(size_t)a * stride + axes[i]]) * k;
            s += d * d;
        }
        sp[t] = sqrt(s);
    }
}

/* Body size: the right arm's length in the first frame, or 1. */
static double body_size(const affect_motion *m, const affect_roles *roles)
{
    int32_t s = roles->joint[AFFECT_ROLE_RIGHT_SHOULDER], e = roles->joint[AFFECT_ROLE_RIGHT_ELBOW],
            h = roles->joint[AFFECT_ROLE_RIGHT_HAND];
    if (s < 0 || h < 0)
        return 1.0;
    int32_t chain[3] = {s, e >= 0 ? e : h, h};
    double len = 0.0;
    for (int i = 0; i + 1 < 3; i++) {
        const float *a = affect_motion_at(m, 0, (uint32_t)chain[i]),
                    *b = affect_motion_at(m, 0, (uint32_t)chain[i + 1]);
        double dx = (double)a[0] - b[0], dy = (double)a[1] - b[1], dz = (double)a[2] - b[2];
        len += sqrt(dx * dx + dy * dy + dz * dz);
    }
    return len > 1e-9 ? len : 1.0;
}

affect_status affect_motion_summary(const affect_motion *m, int up, double out[AFFECT_SUMMARY_N],
                                    affect_monitor *mon, affect_error *err)
{
    if (up < 0 || up > 2)
        return affect_fail(err, AFFECT_ERR_INVALID, "up axis must be x, y or z");
    uint32_t T = m->n_frames;
    affect_roles roles;
    affect_roles_resolve(m, &roles);
    /* per frame: 5 effectors × 3 body-frame coordinates, then the pelvis's world x, y, z */
    enum { STRIDE = N_EFF * 3 + 3 };
    double *buf = affect_malloc_array((size_t)T * STRIDE + 2u * T, sizeof *buf);
    if (!buf)
        return affect_nomem(err);
    double *ang = buf + (size_t)T * STRIDE, *tmp = ang + T;
    bool turned = affect_normalize_headings(m, &roles, up, ang);
    if (!turned)
        memset(ang, 0, T * sizeof *ang);
    int32_t root = roles.joint[AFFECT_ROLE_PELVIS];
    if (root < 0 || (uint32_t)root >= m->n_joints)
        root = 0;
    double inv = 1.0 / body_size(m, &roles);
    /* forward = lateral × up: +z for y-up data (lateral +x), −y for z-up (+x), −z for x-up (+y) */
    int ha = (up + 1) % 3, hb = (up + 2) % 3, fwd = up == 2 ? 1 : 2;
    double fwd_sign = up == 1 ? 1.0 : -1.0;
    for (uint32_t t = 0; t < T; t++) {
        if (t % 4096 == 0 && affect_monitor_stopped(mon))
            break; /* checked below */
        double r[9], *row = buf + (size_t)t * STRIDE;
        affect_normalize_axis_rotation(up, ang[t], r);
        const float *o = affect_motion_at(m, t, (uint32_t)root);
        for (int e = 0; e < N_EFF; e++) {
            int32_t j = roles.joint[effectors[e]];
            const float *p = j >= 0 ? affect_motion_at(m, t, (uint32_t)j) : o;
            double a = (double)p[0] - o[0], b = (double)p[1] - o[1], c = (double)p[2] - o[2];
            for (int i = 0; i < 3; i++)
                row[e * 3 + i] = (r[i * 3] * a + r[i * 3 + 1] * b + r[i * 3 + 2] * c) * inv;
        }
        for (int i = 0; i < 3; i++)
            row[N_EFF * 3 + i] = (double)o[i] * inv;
    }
    affect_status st = affect_monitor_check(mon, err); /* between passes over the frames */
    if (st) {
        affect_free(buf);
        return st;
    }
    memset(out, 0, AFFECT_SUMMARY_N * sizeof *out);
    out[0] = T / m->fps;
    int horiz[2] = {ha, hb}, all[3] = {0, 1, 2};
    speeds(buf + N_EFF * 3, T, STRIDE, horiz, 2, m->fps, tmp);
    out[1] = mean(tmp, T);
    out[2] = p90(tmp, T);
    double hm = 0.0, hv = 0.0;
    for (uint32_t t = 0; t < T; t++)
        hm += buf[(size_t)t * STRIDE + N_EFF * 3 + up];
    hm /= T;
    for (uint32_t t = 0; t < T; t++) {
        double d = buf[(size_t)t * STRIDE + N_EFF * 3 + up] - hm;
        hv += d * d;
    }
    out[3] = sqrt(hv / T);
    if (turned && T > 1) {
        double s = 0.0;
        for (uint32_t t = 0; t < T; t++) {
            uint32_t a = t > 0 ? t - 1 : 0, b = t + 1 < T ? t + 1 : T - 1;
            s += fabs(ang[b] - ang[a]) * m->fps / (double)(b - a);
        }
        out[4] = s / T;
        out[5] = fabs(ang[T - 1] - ang[0]);
    }
    for (int e = 0; e < N_EFF; e++) {
        if (roles.joint[effectors[e]] < 0)
            continue;
        speeds(buf + e * 3, T, STRIDE, all, 3, m->fps, tmp);
        out[6 + e] = mean(tmp, T);
        out[11 + e] = p90(tmp, T);
        if ((st = affect_monitor_check(mon, err))) {
            affect_free(buf);
            return st;
        }
    }
    bool head = roles.joint[AFFECT_ROLE_HEAD] >= 0,
         hands =
             roles.joint[AFFECT_ROLE_LEFT_HAND] >= 0 && roles.joint[AFFECT_ROLE_RIGHT_HAND] >= 0,
         feet = roles.joint[AFFECT_ROLE_LEFT_FOOT] >= 0 && roles.joint[AFFECT_ROLE_RIGHT_FOOT] >= 0;
    for (uint32_t t = 0; t < T; t++) {
        const double *row = buf + (size_t)t * STRIDE;
        if (head) {
            out[16] += row[up];
            out[17] += fwd_sign * row[fwd];
        }
        if (hands) {
            out[18] += 0.5 * (row[3 + up] + row[6 + up]);
            out[19] +=
                sqrt((row[3] - row[6]) * (row[3] - row[6]) + (row[4] - row[7]) * (row[4] - row[7]) +
                     (row[5] - row[8]) * (row[5] - row[8]));
        }
        if (feet)
            out[20] += sqrt((row[9] - row[12]) * (row[9] - row[12]) +
                            (row[10] - row[13]) * (row[10] - row[13]) +
                            (row[11] - row[14]) * (row[11] - row[14]));
    }
    for (int i = 16; i < AFFECT_SUMMARY_N; i++)
        out[i] /= T;
    affect_free(buf);
    return AFFECT_OK;
}

uint32_t affect_descriptors_dim(unsigned mask)
{
    if (mask == 0 || (mask & ~(unsigned)AFFECT_DESC_ALL))
        return 0;
    return ((mask & AFFECT_DESC_KINEMATICS) ? AFFECT_SUMMARY_N : 0u) +
           ((mask & AFFECT_DESC_LABAN) ? AFFECT_LABAN_N : 0u);
}

static double signed_log(double v)
{
    if (!isfinite(v))
        return 0.0;
    return v < 0 ? -log1p(-v) : log1p(v);
}

affect_status affect_descriptors(unsigned mask, const affect_motion *m, int up_axis, double *out,
                                 affect_monitor *mon, affect_error *err)
{
    if (affect_descriptors_dim(mask) == 0)
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "descriptors must be a combination of kinematics and laban");
    uint32_t n = 0;
    if (mask & AFFECT_DESC_KINEMATICS) {
        affect_status st = affect_motion_summary(m, up_axis, out, mon, err);
        if (st)
            return st;
        n = AFFECT_SUMMARY_N;
    }
    if (mask & AFFECT_DESC_LABAN) {
        affect_roles roles;
        affect_roles_resolve(m, &roles);
        affect_laban_options lo;
        affect_laban_options_default(&lo);
        lo.up_axis = up_axis;
        lo.missing_null = true;
        lo.monitor = mon;
        affect_status st = affect_laban_vector(m, &roles, &lo, out + n, err);
        if (st)
            return st;
        n += AFFECT_LABAN_N;
    }
    for (uint32_t i = 0; i < n; i++)
        out[i] = signed_log(out[i]);
    return AFFECT_OK;
}

static void swap_pair(double *v, uint32_t a, uint32_t b)
{
    double t = v[a];
    v[a] = v[b];
    v[b] = t;
}

void affect_descriptors_mirror(unsigned mask, const double *in, double *out)
{
    uint32_t n = affect_descriptors_dim(mask), base = 0;
    if (out != in)
        memmove(out, in, n * sizeof *out);
    if (mask & AFFECT_DESC_KINEMATICS) {
        static const uint32_t pairs[][2] = {{7, 8}, {9, 10}, {12, 13}, {14, 15}};
        for (size_t i = 0; i < sizeof pairs / sizeof pairs[0]; i++)
            swap_pair(out, pairs[i][0], pairs[i][1]);
        base = AFFECT_SUMMARY_N;
    }
    if (mask & AFFECT_DESC_LABAN) {
        for (uint32_t g = 0; g < 21; g += 7) { /* Weight, Time, Flow: All Torso Head L R L R */
            swap_pair(out + base, g + 3, g + 4);
            swap_pair(out + base, g + 5, g + 6);
        }
        swap_pair(out + base, 25, 26); /* ShapeDirLHand, ShapeDirRHand */
    }
}
