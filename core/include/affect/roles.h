/*
 * affect/roles.h — body-part roles resolved from joint names.
 *
 * Usage:
 *     const affect_motion *m = ...;
 *     affect_error err;
 *     affect_roles roles;
 *     affect_roles_resolve(m, &roles);                 // every role by the joint names, else -1
 *     if (roles.joint[AFFECT_ROLE_LEFT_HAND] < 0
 *         && affect_roles_set(m, &roles, "left_hand", "LWrist", &err) != AFFECT_OK)
 *         puts(err.msg);
 *     double lat[3];                                   // left - right at frame 0
 *     if (affect_roles_lateral(m, &roles, 0, lat))
 *         printf("%s: %d\n", affect_role_name(AFFECT_ROLE_HEAD), roles.joint[AFFECT_ROLE_HEAD]);
 *
 * A role is an anatomical landmark (pelvis, head, left hand, …). affect_roles_resolve() maps
 * every role to a joint by case-insensitive patterns that cover the common naming conventions:
 *   this corpus (Bandai-Namco):  Hips, Spine, Chest, Neck, Head, UpperArm_L, LowerArm_R, Hand_L,
 *                                UpperLeg_L, LowerLeg_R, Foot_L, Toes_R
 *   CMU / Mixamo:                LeftArm, RightForeArm, LeftUpLeg, LeftLeg, mixamorig:LeftHand
 *   short forms:                 l_wrist, LWrist, lhand, r_knee, RAnkle, left_toe
 * A side is read from a "left"/"right" word, an "l"/"r" prefix or suffix separated by '_', '.',
 * '-', ' ' or a case change ("LWrist"), or a glued prefix before a known body word ("lhand").
 * End-site joints ("Head_end") never take a role. Unresolved roles are −1.
 */
#ifndef AFFECT_ROLES_H
#define AFFECT_ROLES_H

#include "affect/motion.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum affect_role {
    AFFECT_ROLE_PELVIS,
    AFFECT_ROLE_SPINE,
    AFFECT_ROLE_CHEST,
    AFFECT_ROLE_NECK,
    AFFECT_ROLE_HEAD,
    AFFECT_ROLE_LEFT_SHOULDER,
    AFFECT_ROLE_LEFT_ELBOW,
    AFFECT_ROLE_LEFT_HAND,
    AFFECT_ROLE_RIGHT_SHOULDER,
    AFFECT_ROLE_RIGHT_ELBOW,
    AFFECT_ROLE_RIGHT_HAND,
    AFFECT_ROLE_LEFT_HIP,
    AFFECT_ROLE_LEFT_KNEE,
    AFFECT_ROLE_LEFT_FOOT,
    AFFECT_ROLE_LEFT_TOE,
    AFFECT_ROLE_RIGHT_HIP,
    AFFECT_ROLE_RIGHT_KNEE,
    AFFECT_ROLE_RIGHT_FOOT,
    AFFECT_ROLE_RIGHT_TOE,
    AFFECT_ROLE_COUNT
} affect_role;

typedef struct affect_roles {
    int32_t joint[AFFECT_ROLE_COUNT]; /* joint index, or −1 when unresolved */
} affect_roles;

/* Stable snake_case name of a role ("pelvis", "left_hand", …). */
const char *affect_role_name(affect_role role);

/* Role with that name (exact, lower case; "left_wrist"/"right_wrist" are accepted for the
 * hands), or −1. */
int affect_role_from_name(const char *name);

/* Resolves every role from the motion's joint names. */
void affect_roles_resolve(const affect_motion *m, affect_roles *roles);

/* Assigns a role explicitly: role_name must be a role name, joint_name a joint of m (exact
 * match first, then case-insensitive). A NULL joint_name unassigns the role. */
affect_status affect_roles_set(const affect_motion *m, affect_roles *roles, const char *role_name,
                               const char *joint_name, affect_error *err);

/* The body's lateral vector left − right at a frame: from the left_hip/right_hip roles, or the
 * shoulders when a hip is unresolved (the heading used by normalization and Shape Shaping).
 * Returns false when neither pair is resolved. */
bool affect_roles_lateral(const affect_motion *m, const affect_roles *roles, uint32_t frame,
                          double out[3]);

#ifdef __cplusplus
}
#endif
#endif
