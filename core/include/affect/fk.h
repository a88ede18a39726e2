/*
 * affect/fk.h — forward kinematics for hierarchical skeletons (BVH and the synthetic
 * generator share it).
 *
 * Usage:
 *     int32_t parents[2] = {-1, 0};                    // a root and its child (parents[j] < j)
 *     double trans[2 * 3] = {0, 0, 0, 0, 1, 0};        // local translations (the child 1 up)
 *     double rot[2 * 9], scratch[2 * 12];
 *     float pos[2 * 3];
 *     const int zxy[3] = {2, 0, 1};
 *     affect_euler_deg_to_matrix(zxy, (const double[3]){90, 0, 0}, rot);   // the root's
 *     affect_euler_deg_to_matrix(zxy, (const double[3]){0, 0, 0}, rot + 9);
 *     affect_fk_frame(2, parents, trans, rot, scratch, pos);   // pos + 3: the child at (-1, 0, 0)
 *
 * Rotations are 3×3 row-major matrices acting on column vectors. A joint's world rotation is
 * its parent's world rotation times its local rotation; its world position is its parent's
 * world position plus the parent's world rotation applied to the joint's local translation.
 */
#ifndef AFFECT_FK_H
#define AFFECT_FK_H

#include "affect/base.h"

#ifdef __cplusplus
extern "C" {
#endif

/* R = R_axis(order[0]) · R_axis(order[1]) · R_axis(order[2]) with angles in degrees; order
 * holds axis indices 0 = x, 1 = y, 2 = z (the BVH convention: the order CHANNELS lists them). */
void affect_euler_deg_to_matrix(const int order[3], const double deg[3], double r[9]);

/* r = a · b for 3×3 row-major matrices (r may not alias a or b). */
void affect_mat3_mul(const double a[9], const double b[9], double r[9]);

/* World positions of one frame. parents[j] < j for every non-root j (topological order);
 * local_trans and local_rot are J×3 and J×9; scratch is J×12 doubles (on return it holds each
 * joint's world rotation, 9, then world position, 3); out receives J×3 floats. */
void affect_fk_frame(uint32_t n_joints, const int32_t *parents, const double *local_trans,
                     const double *local_rot, double *scratch, float *out);

#ifdef __cplusplus
}
#endif
#endif
