/*
 * affect/quat.h — unit quaternions and Euler angles for joint rotations.
 *
 * Usage:
 *     double deg[3] = {30, 45, 10}, back[3], q[4];     // q: (w, x, y, z), w first
 *     int order[3];
 *     affect_euler_order_parse("ZXY", order);          // R = Rz(a0) · Rx(a1) · Ry(a2), BVH's way
 *     affect_quat_from_euler_deg(order, deg, q);
 *     affect_quat_to_euler_deg(q, order, NULL, back);  // back, in [-180, 180) for a0 and a2
 *     double half[4], id[4] = {1, 0, 0, 0};
 *     affect_quat_slerp(id, q, 0.5, half);             // half the rotation
 *     printf("%g degrees\n", affect_quat_angle(half) * 180 / 3.141592653589793);
 *
 * Quaternions act on column vectors as the rotation matrices of affect/fk.h: the matrix of
 * affect_quat_to_matrix(q) equals that of the same rotation built from Euler angles there.
 * A quaternion and its negation are the same rotation; the functions return w ≥ 0 where they
 * choose (from_matrix), and keep the caller's hemisphere where continuity matters (slerp).
 */
#ifndef AFFECT_QUAT_H
#define AFFECT_QUAT_H

#include "affect/base.h"

#ifdef __cplusplus
extern "C" {
#endif

/* r = a · b (apply b first, then a). r may alias a or b. */
void affect_quat_mul(const double a[4], const double b[4], double r[4]);

/* v' = q v q⁻¹ for a unit q. out may alias v. */
void affect_quat_rotate(const double q[4], const double v[3], double out[3]);

/* Row-major 3×3 matrix of a unit quaternion. */
void affect_quat_to_matrix(const double q[4], double r[9]);

/* Unit quaternion of a rotation matrix (Shepperd's method: stable for every angle); w ≥ 0. */
void affect_quat_from_matrix(const double r[9], double q[4]);

/* Scales q to unit length; a zero or non-finite q becomes the identity. */
void affect_quat_normalize(double q[4]);

/* Spherical linear interpolation from a (t = 0) to b (t = 1) along the shorter arc. */
void affect_quat_slerp(const double a[4], const double b[4], double t, double r[4]);

/* Rotation vector (axis × angle, radians, angle in [0, π]) of a unit q: the logarithm map,
 * taken on the hemisphere w ≥ 0. */
void affect_quat_log(const double q[4], double v[3]);

/* Unit quaternion of a rotation vector (the exponential map; the inverse of affect_quat_log
 * for angles up to π). */
void affect_quat_exp(const double v[3], double q[4]);

/* Rotation angle of q in radians, in [0, π]. */
double affect_quat_angle(const double q[4]);

/* The smallest rotation taking the direction of a onto the direction of b (both non-zero).
 * Antiparallel inputs turn by π about an axis perpendicular to a. */
void affect_quat_between(const double a[3], const double b[3], double q[4]);

/* q = R_axis(order[0])(deg[0]) · R_axis(order[1])(deg[1]) · R_axis(order[2])(deg[2]);
 * order is a permutation of 0 = x, 1 = y, 2 = z. */
void affect_quat_from_euler_deg(const int order[3], const double deg[3], double q[4]);

/* Euler angles (degrees) of q in the given order: deg[1] in [−90, 90], deg[0] and deg[2] in
 * [−180, 180). At gimbal lock (|deg[1]| = 90) deg[2] is prev's (0 without prev) and deg[0]
 * takes the rest of the rotation. When prev is not NULL the solution
 * closest to prev is chosen among the two equivalent ones and each angle is moved by whole
 * turns to within 180° of prev (continuous curves for animation tools). */
void affect_quat_to_euler_deg(const double q[4], const int order[3], const double prev[3],
                              double deg[3]);

/* Parses an order such as "ZXY" (case-insensitive, three distinct axes); false otherwise. */
bool affect_euler_order_parse(const char *text, int order[3]);

/* Writes an order as three capital letters and a NUL. */
void affect_euler_order_name(const int order[3], char out[4]);

#ifdef __cplusplus
}
#endif
#endif
