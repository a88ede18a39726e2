/*
 * quat.c — unit quaternions, rotation matrices and Euler angles (see affect/quat.h).
 *
 * Euler angles: for R = Ra(α) · Rb(β) · Rc(γ) with (a, b, c) a permutation of the axes and
 * e = +1 for the cyclic orders (XYZ, YZX, ZXY), −1 for the others,
 *   β = atan2(e · R[a][c], hypot(R[a][a], R[a][b])),
 *   α = atan2(−e · R[b][c], R[c][c]),  γ = atan2(−e · R[a][b], R[a][a]);
 * at gimbal lock (cos β ≈ 0) only α + e · sign(β) · γ = atan2(e · R[c][b], R[b][b]) is defined:
 * γ is kept at the previous frame's value (or 0) and α takes the rest.
 * The other solution of the same rotation is (α + 180°, 180° − β, γ + 180°).
 */
#include "affect/quat.h"

#include <math.h>
#include <string.h>

#define PI 3.14159265358979323846
#define DEG (180.0 / PI)
/* cos β below this is gimbal lock: α and γ are then not separable */
#define GIMBAL_LOCK_COS 1e-9

void affect_quat_mul(const double a[4], const double b[4], double r[4])
{
    double w = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
    double x = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
    double y = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
    double z = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
    r[0] = w, r[1] = x, r[2] = y, r[3] = z;
}

void affect_quat_rotate(const double q[4], const double v[3], double out[3])
{
    /* v + 2w (u × v) + 2 u × (u × v), u the vector part */
    double ux = q[1], uy = q[2], uz = q[3], w = q[0];
    double tx = 2 * (uy * v[2] - uz * v[1]);
    double ty = 2 * (uz * v[0] - ux * v[2]);
    double tz = 2 * (ux * v[1] - uy * v[0]);
    double x = v[0] + w * tx + (uy * tz - uz * ty);
    double y = v[1] + w * ty + (uz * tx - ux * tz);
    double z = v[2] + w * tz + (ux * ty - uy * tx);
    out[0] = x, out[1] = y, out[2] = z;
}

void affect_quat_to_matrix(const double q[4], double r[9])
{
    double w = q[0], x = q[1], y = q[2], z = q[3];
    r[0] = 1 - 2 * (y * y + z * z);
    r[1] = 2 * (x * y - z * w);
    r[2] = 2 * (x * z + y * w);
    r[3] = 2 * (x * y + z * w);
    r[4] = 1 - 2 * (x * x + z * z);
    r[5] = 2 * (y * z - x * w);
    r[6] = 2 * (x * z - y * w);
    r[7] = 2 * (y * z + x * w);
    r[8] = 1 - 2 * (x * x + y * y);
}

void affect_quat_from_matrix(const double r[9], double q[4])
{
    double tr = r[0] + r[4] + r[8];
    if (tr >= r[0] && tr >= r[4] && tr >= r[8]) {
        double s = 2 * sqrt(1 + tr);
        q[0] = s / 4;
        q[1] = (r[7] - r[5]) / s;
        q[2] = (r[2] - r[6]) / s;
        q[3] = (r[3] - r[1]) / s;
    } else if (r[0] >= r[4] && r[0] >= r[8]) {
        double s = 2 * sqrt(1 + r[0] - r[4] - r[8]);
        q[0] = (r[7] - r[5]) / s;
        q[1] = s / 4;
        q[2] = (r[1] + r[3]) / s;
        q[3] = (r[2] + r[6]) / s;
    } else if (r[4] >= r[8]) {
        double s = 2 * sqrt(1 + r[4] - r[0] - r[8]);
        q[0] = (r[2] - r[6]) / s;
        q[1] = (r[1] + r[3]) / s;
        q[2] = s / 4;
        q[3] = (r[5] + r[7]) / s;
    } else {
        double s = 2 * sqrt(1 + r[8] - r[0] - r[4]);
        q[0] = (r[3] - r[1]) / s;
        q[1] = (r[2] + r[6]) / s;
        q[2] = (r[5] + r[7]) / s;
        q[3] = s / 4;
    }
    if (q[0] < 0)
        for (int i = 0; i < 4; i++)
            q[i] = -q[i];
    affect_quat_normalize(q);
}

void affect_quat_normalize(double q[4])
{
    double n = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (!(n > 0) || !isfinite(n)) {
        q[0] = 1, q[1] = q[2] = q[3] = 0;
        return;
    }
    for (int i = 0; i < 4; i++)
        q[i] /= n;
}

void affect_quat_slerp(const double a[4], const double b[4], double t, double r[4])
{
    double d = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
    double s = 1;
    if (d < 0) { /* the shorter arc: −b is the same rotation */
        d = -d;
        s = -1;
    }
    double wa, wb;
    if (d > 0.9995) { /* nearly equal: linear interpolation is exact to rounding */
        wa = 1 - t;
        wb = t;
    } else {
        double theta = acos(d), st = sin(theta);
        wa = sin((1 - t) * theta) / st;
        wb = sin(t * theta) / st;
    }
    for (int i = 0; i < 4; i++)
        r[i] = wa * a[i] + s * wb * b[i];
    affect_quat_normalize(r);
}

void affect_quat_log(const double q[4], double v[3])
{
    double sgn = q[0] < 0 ? -1.0 : 1.0;
    double s = sqrt(q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    double angle = 2 * atan2(s, sgn * q[0]);
    /* angle / s → 2 as s → 0 (sin(θ/2) ≈ θ/2); below 1e-12 the quotient is 2 to rounding */
    double f = s > 1e-12 ? sgn * angle / s : sgn * 2.0;
    for (int i = 0; i < 3; i++)
        v[i] = f * q[i + 1];
}

void affect_quat_exp(const double v[3], double q[4])
{
    double angle = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    double f = angle > 1e-12 ? sin(angle / 2) / angle : 0.5;
    q[0] = cos(angle / 2);
    for (int i = 0; i < 3; i++)
        q[i + 1] = f * v[i];
}

double affect_quat_angle(const double q[4])
{
    double v = sqrt(q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    return 2 * atan2(v, fabs(q[0]));
}

void affect_quat_between(const double a[3], const double b[3], double q[4])
{
    double na = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    double nb = sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
    double dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    double w = na * nb + dot;
    if (w <= 1e-12 * na * nb) { /* antiparallel: half a turn about any perpendicular axis */
        double ax[3];
        if (fabs(a[0]) <= fabs(a[1]) && fabs(a[0]) <= fabs(a[2]))
            ax[0] = 0, ax[1] = a[2], ax[2] = -a[1];
        else if (fabs(a[1]) <= fabs(a[2]))
            ax[0] = -a[2], ax[1] = 0, ax[2] = a[0];
        else
            ax[0] = a[1], ax[1] = -a[0], ax[2] = 0;
        q[0] = 0, q[1] = ax[0], q[2] = ax[1], q[3] = ax[2];
    } else {
        q[0] = w;
        q[1] = a[1] * b[2] - a[2] * b[1];
        q[2] = a[2] * b[0] - a[0] * b[2];
        q[3] = a[0] * b[1] - a[1] * b[0];
    }
    affect_quat_normalize(q);
}

void affect_quat_from_euler_deg(const int order[3], const double deg[3], double q[4])
{
    q[0] = 1, q[1] = q[2] = q[3] = 0;
    for (int k = 0; k < 3; k++) {
        double h = deg[k] / DEG / 2, a[4] = {cos(h), 0, 0, 0};
        a[1 + order[k]] = sin(h);
        affect_quat_mul(q, a, q);
    }
}

/* x moved by whole turns to within 180° of ref. */
static double unwrap(double x, double ref)
{
    if (fabs(x - ref) < 180) /* nothing to move (and no floor, a tenth of export time) */
        return x;
    return x - 360.0 * floor((x - ref) / 360.0 + 0.5);
}

void affect_quat_to_euler_deg(const double q[4], const int order[3], const double prev[3],
                              double deg[3])
{
    double r[9];
    affect_quat_to_matrix(q, r);
    int a = order[0], b = order[1], c = order[2];
    double e = (b - a + 3) % 3 == 1 ? 1.0 : -1.0;
    double s = e * r[a * 3 + c];
    /* cos β, well conditioned near the lock (entries of a rotation matrix: no overflow, so
     * sqrt rather than the slower hypot) */
    double cb = sqrt(r[a * 3 + a] * r[a * 3 + a] + r[a * 3 + b] * r[a * 3 + b]);
    double al, be = atan2(s, cb) * DEG, ga;
    if (cb < GIMBAL_LOCK_COS) {
        /* only α + e·sign(β)·γ is defined: keep γ (the previous frame's, or 0) */
        double combined = atan2(e * r[c * 3 + b], r[b * 3 + b]) * DEG;
        ga = prev ? prev[2] : 0;
        al = combined - e * (s > 0 ? 1 : -1) * ga;
    } else {
        al = atan2(-e * r[b * 3 + c], r[c * 3 + c]) * DEG;
        ga = atan2(-e * r[a * 3 + b], r[a * 3 + a]) * DEG;
    }
    al = unwrap(al, 0);
    ga = unwrap(ga, 0);
    deg[0] = al, deg[1] = be, deg[2] = ga;
    if (!prev)
        return;
    /* the two equivalent solutions, each brought to within a half turn of prev */
    double s1[3] = {unwrap(al, prev[0]), unwrap(be, prev[1]), unwrap(ga, prev[2])};
    double s2[3] = {unwrap(al + 180, prev[0]), unwrap(180 - be, prev[1]),
                    unwrap(ga + 180, prev[2])};
    double d1 = 0, d2 = 0;
    for (int k = 0; k < 3; k++) {
        d1 += fabs(s1[k] - prev[k]);
        d2 += fabs(s2[k] - prev[k]);
    }
    memcpy(deg, d2 < d1 ? s2 : s1, 3 * sizeof *deg);
}

bool affect_euler_order_parse(const char *text, int order[3])
{
    if (!text || strlen(text) != 3)
        return false;
    unsigned seen = 0;
    for (int k = 0; k < 3; k++) {
        char ch = text[k];
        int axis = ch == 'x' || ch == 'X'   ? 0
                   : ch == 'y' || ch == 'Y' ? 1
                   : ch == 'z' || ch == 'Z' ? 2
                                            : -1;
        if (axis < 0 || (seen & (1u << axis)))
            return false;
        seen |= 1u << axis;
        order[k] = axis;
    }
    return true;
}

void affect_euler_order_name(const int order[3], char out[4])
{
    for (int k = 0; k < 3; k++)
        out[k] = (char)('X' + order[k]);
    out[3] = '\0';
}
