/*
 * affect/skeleton.h — skeletal motions: forward kinematics from stored rotations, the rigid
 * projection of position-only motions (constant bone lengths), inverse kinematics (local joint
 * rotations from positions) and joint angles.
 *
 * Usage:
 *     const affect_motion *m = ...;                    // positions only (CSV, JSON, a BLOB)
 *     affect_error err;
 *     affect_motion *rigid = NULL, *skeletal = NULL;
 *     affect_rigid_options ro;
 *     affect_rigid_options_default(&ro);
 *     affect_ik_options io;
 *     affect_ik_options_default(&io);
 *     if (affect_motion_rigid(m, &ro, &rigid, &err) != AFFECT_OK ||   // constant bone lengths
 *         affect_motion_ik(m, &io, &skeletal, &err) != AFFECT_OK)          // skeleton + rotations
 *         puts(err.msg);
 *     affect_motion_free(skeletal);
 *     affect_motion_free(rigid);
 *
 * Bones and free links: the link from a joint to its parent is a bone (constant length) unless
 * it is free: the parent is a reference root (a root whose only child is the pelvis role, such
 * as the corpus's joint_Root above Hips, whose link carries the global translation), or the
 * motion's skeleton gives the
 * joint position channels whose values leave its offset by more than AFFECT_FREE_LINK_REL of
 * the offset's length (the corpus's Hips), or the caller names it.
 */
#ifndef AFFECT_SKELETON_H
#define AFFECT_SKELETON_H

#include "affect/monitor.h"
#include "affect/motion.h"

#ifdef __cplusplus
extern "C" {
#endif

#define AFFECT_FREE_LINK_REL 1e-3

/* Joints in an order where every parent precedes its children (order has n_joints entries). */
affect_status affect_motion_topo_order(const affect_motion *m, uint32_t *order, affect_error *err);

/* Recomputes the positions from the skeleton, rotations and translations (forward kinematics
 * in double precision). Joints with a position channel use their per-frame translation, the
 * others their offset. Needs m->rot. */
affect_status affect_motion_fk(affect_motion *m, affect_error *err);

/* Largest distance (in the motion's unit) between m's positions and the forward kinematics of
 * its rotations over every frame and joint, with the frame and joint where it occurs. */
affect_status affect_motion_fk_error(const affect_motion *m, double *max_dist, uint32_t *frame,
                                     uint32_t *joint, affect_error *err);

/* Marks free links (see above); free_link has n_joints entries, false for roots. */
affect_status affect_motion_free_links(const affect_motion *m, bool *free_link, affect_error *err);

/* Bone-length variation: over the bones (links that are not free), the largest
 * (max − min) / max of a bone's length over the frames (0 for a bone of length 0). *worst is
 * the joint at the bone's lower end, −1 when there is no bone. */
affect_status affect_motion_bone_variation(const affect_motion *m, double *variation,
                                           int32_t *worst, affect_error *err);

/* Largest extent of the first frame's bounding box (a body size for tolerances), > 0. */
double affect_motion_body_size(const affect_motion *m);

typedef enum affect_rigid_lengths {
    AFFECT_RIGID_MEDIAN,   /* each bone's median length over the frames (default) */
    AFFECT_RIGID_FIRST,    /* its length in the first frame */
    AFFECT_RIGID_REFERENCE /* the median length in a reference motion with the same joints */
} affect_rigid_lengths;

typedef enum affect_rigid_model {
    AFFECT_RIGID_BONES,   /* constant bone lengths (default) */
    AFFECT_RIGID_SKELETON /* what a skeleton with rotation channels only (below its roots) can
                             play: the forward kinematics of affect_motion_ik, rotations kept */
} affect_rigid_model;

typedef struct affect_rigid_options {
    affect_rigid_model model;
    affect_rigid_lengths lengths;
    const affect_motion *reference; /* for AFFECT_RIGID_REFERENCE */
    uint32_t max_sweeps;            /* coordinate-descent sweeps per frame (default 200) */
    double tolerance;               /* stop when no joint moves more than this × body size
                                       (default 1e-9) */
    const bool *free_link;          /* n_joints flags, or NULL to detect them */
    affect_monitor *monitor;        /* polled frame by frame (default NULL): the call stops
                                       with AFFECT_ERR_INTERRUPTED once it says so (also for
                                       affect_motion_ik, through its rigid options) */
} affect_rigid_options;

void affect_rigid_options_default(affect_rigid_options *opt);

/* The motion nearest to m (least sum of squared joint displacements, frame by frame) whose
 * bones keep the chosen lengths: per frame, exact block coordinate descent over the bone
 * directions (a bone's optimal direction given the others has a closed form: its whole
 * subtree moves rigidly) and the translation of each rigid part, started from m's own bone
 * directions. Joints, names, parents and fps are m's; no skeleton. Needs a skeleton: one
 * joint, or some joint with a parent. With AFFECT_RIGID_SKELETON the result is
 * affect_motion_ik's (default IK options, these lengths): a skeletal motion that BVH export
 * reproduces exactly, a little further from m where sibling bones change their angles. */
affect_status affect_motion_rigid(const affect_motion *m, const affect_rigid_options *opt,
                                  affect_motion **out, affect_error *err);

typedef enum affect_ik_siblings {
    AFFECT_IK_SIBLINGS_AUTO,     /* (default) rotations only where they reproduce a sibling
                                    group within 1e-3 of the body size over every frame (captured
                                    motions), TRANSLATE for the groups where they do not
                                    (averaged or synthesized poses whose sibling angles vary) */
    AFFECT_IK_SIBLINGS_ROTATE,   /* a joint's children are one rigid body with it: rotation
                                    channels only below the roots and free links */
    AFFECT_IK_SIBLINGS_TRANSLATE /* the children of a joint with several get position channels
                                    too (their offsets keep the bone's length but follow the
                                    positions): every position is reproduced */
} affect_ik_siblings;

typedef struct affect_ik_options {
    uint32_t rest_frame;         /* the frame whose rigid pose is the rest pose (default 0) */
    affect_ik_siblings siblings; /* see above */
    int order[3];                /* rotation channel order (default ZXY: {2, 0, 1}) */
    affect_rigid_options rigid;  /* how the positions are first made rigid */
} affect_ik_options;

void affect_ik_options_default(affect_ik_options *opt);

/* Inverse kinematics: a skeletal motion for m's positions. The positions are made rigid
 * (affect_motion_rigid); the rest skeleton is the rest frame's rigid pose (offsets = bone
 * vectors, rest rotations the identity), except that the offsets of a joint's several bone
 * children are their mean shape over all frames (generalized Procrustes, turned to the rest
 * frame's orientation), since the siblings' angles need not be constant; per frame and joint the
 * local rotation turns the rest offsets of its bone children onto their current directions: for one
 * child the smallest rotation from the previous frame's (so twist stays continuous and never
 * flips), for several the best-fit rotation (Horn's quaternion method) continued from the previous
 * frame when the children are collinear. Roots and free links get position channels. Leaves named
 * "<parent>_end" become End Sites. The result's positions are the forward kinematics of its
 * rotations. */
affect_status affect_motion_ik(const affect_motion *m, const affect_ik_options *opt,
                               affect_motion **out, affect_error *err);

typedef enum affect_rotation_source {
    AFFECT_ROTATIONS_AUTO,   /* the stored rotations when there are some, else IK (default) */
    AFFECT_ROTATIONS_STORED, /* the stored rotations; an error without them */
    AFFECT_ROTATIONS_IK      /* inverse kinematics from the positions, even over stored ones */
} affect_rotation_source;

/* Stored rotations may differ from the positions by float rounding; more than this × the body
 * size means they do not describe the positions (a BLOB edited by hand) and are refused. */
#define AFFECT_STORED_FK_TOL_REL 1e-4

/* The skeletal form of m for export and joint angles: m itself (*made = NULL) when its stored
 * rotations are wanted and reproduce its positions within AFFECT_STORED_FK_TOL_REL of the body
 * size, else affect_motion_ik's result in *made (free it). The errors say which option to use
 * instead ({"rotations":"ik"} / "auto", the SQL options' names). */
affect_status affect_motion_skeletal(const affect_motion *m, affect_rotation_source source,
                                     const affect_ik_options *opt, affect_motion **made,
                                     affect_error *err);

/* Euler angles (degrees, continuous with prev when not NULL, see affect_quat_to_euler_deg) and
 * angular speed (rad/s; central difference of the rotations, one-sided at the ends) of joint j
 * at frame t. Needs m->rot. */
void affect_motion_joint_angles(const affect_motion *m, uint32_t t, uint32_t j, const int order[3],
                                const double *prev, double q[4], double deg[3], double *speed);

#ifdef __cplusplus
}
#endif
#endif
