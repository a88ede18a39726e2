/*
 * affect/normalize.h — pose normalization used by the methods (SCIENCE.md §2, §6): remove the
 * first frame's root translation and heading, and optionally scale by the arm length.
 *
 * Usage:
 *     const affect_motion *m = ...;
 *     affect_error err;
 *     affect_roles roles;
 *     affect_roles_resolve(m, &roles);
 *     affect_normalize_options opt;
 *     affect_normalize_options_default(&opt);
 *     opt.scale_arm = true;                            // positions in arm lengths (unit "arm")
 *     affect_motion *norm = NULL;
 *     if (affect_motion_normalize(m, &roles, &opt, &norm, &err) != AFFECT_OK)
 *         puts(err.msg);
 *     affect_motion_free(norm);
 *
 * Root: the pelvis role (joint 0 when unresolved). Heading: the horizontal direction of the
 * lateral vector left_hip − right_hip (or left_shoulder − right_shoulder when the hips are not
 * resolved) in the first frame. After normalization the lateral vector points along +x, the
 * up axis stays up, and the body faces lateral × up (+z for y-up data). Arm length: the right
 * shoulder → elbow → hand bone lengths summed in the first frame (shoulder → hand when the
 * elbow is not resolved); the unit becomes "arm".
 */
#ifndef AFFECT_NORMALIZE_H
#define AFFECT_NORMALIZE_H

#include "affect/roles.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct affect_normalize_options {
    int up_axis;      /* 0 = x, 1 = y (default), 2 = z */
    bool translation; /* remove the first frame's horizontal root position (default true) */
    bool vertical;    /* also remove the root's height (default false) */
    bool heading;     /* remove the first frame's heading (default true) */
    bool scale_arm;   /* divide by the right arm length (default false) */
} affect_normalize_options;

void affect_normalize_options_default(affect_normalize_options *opt);

/* The rigid transform that normalization applies: p' = (R (p − origin)) / scale. */
typedef struct affect_normalize_transform {
    double origin[3];
    double rot[9]; /* row-major 3×3 rotation about the up axis */
    double scale;
} affect_normalize_transform;

/* Computes the transform for m under roles and options (no change to m). */
affect_status affect_normalize_transform_compute(const affect_motion *m, const affect_roles *roles,
                                                 const affect_normalize_options *opt,
                                                 affect_normalize_transform *tf, affect_error *err);

/* Applies tf to every position of m in place (out = in allowed) and sets the unit to "arm"
 * when tf->scale != 1 came from the arm length. A skeleton and rotations are transformed
 * with them (roots turn and move, offsets and translations scale). */
void affect_normalize_apply(affect_motion *m, const affect_normalize_transform *tf);

/* The rotation about the up axis that turns the horizontal part of the lateral vector lat onto
 * the axis normalization puts it on (+x, or +y for x-up data), as an angle (radians); false when
 * that horizontal part is shorter than 1e-9 (no heading). */
bool affect_normalize_heading_angle(const double lat[3], int up_axis, double *angle);
/* The rotation by angle about the up axis (right-handed, row-major 3 × 3). */
void affect_normalize_axis_rotation(int up_axis, double angle, double rot[9]);

/* The heading correction of every frame: ang[t] = the angle affect_normalize_heading_angle gives
 * for frame t's lateral vector, unwrapped so that consecutive angles differ by at most π. A
 * frame without a horizontal lateral vector keeps the previous frame's angle (leading ones the
 * first available one; 0 when no frame has one). False when no lateral roles resolve. ang holds
 * n_frames doubles. */
bool affect_normalize_headings(const affect_motion *m, const affect_roles *roles, int up_axis,
                               double *ang);

/* Returns a normalized copy of m. */
affect_status affect_motion_normalize(const affect_motion *m, const affect_roles *roles,
                                      const affect_normalize_options *opt, affect_motion **out,
                                      affect_error *err);

#ifdef __cplusplus
}
#endif
#endif
