/*
 * fk.c — Euler angles to matrices and forward kinematics (see affect/fk.h).
 */
#include "affect/fk.h"

#include <math.h>
#include <string.h>

static void axis_matrix(int axis, double deg, double r[9])
{
    double a = deg * (3.14159265358979323846 / 180.0);
    double c = cos(a), s = sin(a);
    switch (axis) {
    case 0: /* x */
        r[0] = 1, r[1] = 0, r[2] = 0;
        r[3] = 0, r[4] = c, r[5] = -s;
        r[6] = 0, r[7] = s, r[8] = c;
        break;
    case 1: /* y */
        r[0] = c, r[1] = 0, r[2] = s;
        r[3] = 0, r[4] = 1, r[5] = 0;
        r[6] = -s, r[7] = 0, r[8] = c;
        break;
    default: /* z */
        r[0] = c, r[1] = -s, r[2] = 0;
        r[3] = s, r[4] = c, r[5] = 0;
        r[6] = 0, r[7] = 0, r[8] = 1;
        break;
    }
}

void affect_mat3_mul(const double a[9], const double b[9], double r[9])
{
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            r[i * 3 + j] = a[i * 3] * b[j] + a[i * 3 + 1] * b[3 + j] + a[i * 3 + 2] * b[6 + j];
}

void affect_euler_deg_to_matrix(const int order[3], const double deg[3], double r[9])
{
    double a[9], b[9], t[9];
    axis_matrix(order[0], deg[0], a);
    axis_matrix(order[1], deg[1], b);
    affect_mat3_mul(a, b, t);
    axis_matrix(order[2], deg[2], a);
    affect_mat3_mul(t, a, r);
}

void affect_fk_frame(uint32_t n_joints, const int32_t *parents, const double *local_trans,
                     const double *local_rot, double *scratch, float *out)
{
    /* scratch per joint: world rotation (9 doubles) then world position (3 doubles), so
     * positions accumulate down the chain in double precision and round to float once */
    for (uint32_t j = 0; j < n_joints; j++) {
        const double *t = local_trans + (size_t)j * 3;
        const double *lr = local_rot + (size_t)j * 9;
        double *wr = scratch + (size_t)j * 12;
        double *wp = wr + 9;
        int32_t p = parents[j];
        if (p < 0) {
            memcpy(wr, lr, 9 * sizeof(double));
            wp[0] = t[0], wp[1] = t[1], wp[2] = t[2];
        } else {
            const double *pr = scratch + (size_t)p * 12;
            const double *pp = pr + 9;
            affect_mat3_mul(pr, lr, wr);
            wp[0] = pp[0] + (pr[0] * t[0] + pr[1] * t[1] + pr[2] * t[2]);
            wp[1] = pp[1] + (pr[3] * t[0] + pr[4] * t[1] + pr[5] * t[2]);
            wp[2] = pp[2] + (pr[6] * t[0] + pr[7] * t[1] + pr[8] * t[2]);
        }
        out[(size_t)j * 3] = (float)wp[0];
        out[(size_t)j * 3 + 1] = (float)wp[1];
        out[(size_t)j * 3 + 2] = (float)wp[2];
    }
}
