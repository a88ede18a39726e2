/*
 * affect/features.h — the observation definition of a model: which joints, how the motion is
 * normalized, whether velocities are appended. Every model stores its definition, so scoring
 * a motion applies exactly the transform the model was trained on.
 *
 * Usage:
 *     const affect_motion *first = ..., *m = ...;      // the first training motion, any motion
 *     affect_error err;
 *     affect_features_options opt;
 *     affect_features_options_default(&opt);           // every joint of first, by name
 *     opt.frame = AFFECT_FEATURES_FRAME_BODY;
 *     affect_features *f = NULL;
 *     double *x = NULL;                                // n_frames × affect_features_dim(f)
 *     uint32_t n_frames = 0;
 *     if (affect_features_create(&opt, first, &f, &err) != AFFECT_OK ||
 *         affect_features_extract(f, m, &x, &n_frames, NULL, &err) != AFFECT_OK)
 *         puts(err.msg);
 *     affect_free(x);  affect_features_free(f);
 *
 * Joints: a list of entries, each a role name ("left_hand", resolved per motion with
 * affect_roles_resolve) or a joint name (matched exactly); an entry that is a role name is
 * always read as the role. The default is every joint of the first training motion, by name.
 * The definition also keeps, for each entry, the joint it resolved to in the first training
 * motion (its "skeleton" name) and that joint's nearest listed ancestor, so that model
 * parameters can be shown as postures on the training skeleton.
 *
 * Per frame the observation is [p_0, p_1, …, p_{J−1}] (3 values per joint: x, y, z) followed,
 * with velocity, by [v_0, …, v_{J−1}], and with root by [r_0, r_1, r_2, ω]: dim = 3 J, 6 J
 * with velocity, + 4 with root. The positions are taken in one of two frames:
 *   first  (the thesis's observations) — normalized when asked (affect/normalize.h): the first
 *          frame's horizontal root position and heading are removed, and with scale_arm they
 *          are divided by the right arm's length in the first frame. They carry where the body
 *          went: a walk's positions drift with its path.
 *   body   — the body's own frame at every frame: positions relative to the root (the pelvis
 *          role, joint 0 when unresolved) of that frame, turned about the up axis so that that
 *          frame's lateral vector (affect_roles_lateral: hips, else shoulders) lies on +x
 *          (+y for x-up data), divided by the arm length with scale_arm. Posture only:
 *          invariant to where the body is and where it faces. A frame whose lateral vector has
 *          no horizontal part keeps the previous frame's heading (the next one's for the first
 *          frame; the first frame's own axes when no frame has one).
 * Velocities are central differences × fps of those positions (one-sided at the two ends, zero
 * for a single frame), in the positions' unit per second: in the body frame, the limbs' motion
 * relative to the body. Root (body frame only): the root's velocity (central differences of its
 * world position × fps) turned into each frame's body axes and scaled like the positions
 * (forward speed, sideways speed and vertical speed of the body), and the turning rate ω, the
 * central difference of the heading angle (unwrapped) × fps, in radians per second.
 */
#ifndef AFFECT_FEATURES_H
#define AFFECT_FEATURES_H

#include "affect/monitor.h"
#include "affect/roles.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum affect_features_frame {
    AFFECT_FEATURES_FRAME_FIRST = 0, /* the first frame's root and heading removed (thesis) */
    AFFECT_FEATURES_FRAME_BODY = 1   /* every frame in its own body frame */
} affect_features_frame;

typedef struct affect_features {
    uint32_t n_joints;
    char **joints;    /* n_joints entries as requested: role names or joint names */
    char **skeleton;  /* n_joints: the joint each entry resolved to in the first motion */
    int32_t *parents; /* n_joints: index of the nearest listed ancestor in the first motion,
                         or −1 */
    int up_axis;      /* 0 = x, 1 = y, 2 = z */
    affect_features_frame frame;
    bool normalize; /* first frame: remove the first frame's root translation and heading */
    bool scale_arm; /* divide by the right arm length */
    bool velocity;  /* append velocities */
    bool root;      /* append the root's body-frame velocity and turning rate (body frame) */
    double fps;     /* frame rate of the training motions */
    char unit[AFFECT_MOTION_UNIT_MAX + 1]; /* unit of the positions ("arm" when scaled) */
} affect_features;

typedef enum affect_features_scale {
    AFFECT_FEATURES_SCALE_AUTO = 0, /* arm when right_shoulder and right_hand resolve */
    AFFECT_FEATURES_SCALE_NONE = 1,
    AFFECT_FEATURES_SCALE_ARM = 2
} affect_features_scale;

typedef struct affect_features_options {
    const char *const *joints; /* entries (role or joint names); NULL = every joint */
    uint32_t n_joints;
    affect_features_frame frame; /* default first */
    bool normalize;              /* first frame only; default true */
    affect_features_scale scale; /* default auto (decided on the first motion, then fixed) */
    int up_axis;                 /* default 1 (y) */
    bool velocity;               /* default false */
    bool root;                   /* body frame only; default false */
} affect_features_options;

void affect_features_options_default(affect_features_options *opt);

/* Builds the definition from the options and the first training motion: resolves every entry
 * in it (an entry missing there is an error, as are two entries naming the same joint),
 * records the skeleton names, parents, fps and unit, and decides the automatic scale. */
affect_status affect_features_create(const affect_features_options *opt, const affect_motion *first,
                                     affect_features **out, affect_error *err);
void affect_features_free(affect_features *f);

/* Observation dimension: 3 × joints, × 2 with velocity, + 4 with root. */
uint32_t affect_features_dim(const affect_features *f);

/* The observations of m: *x receives n_frames × dim doubles, row-major (free with
 * affect_free), *n_frames the motion's frame count. Errors (AFFECT_ERR_MISSING):
 * 'joint "Hand_L" of the model is not in the motion', 'no joint of the motion has the
 * left_hand role (used by the model)', and the normalization's missing roles; mon (may be
 * NULL) is polled between the passes over the frames (AFFECT_ERR_INTERRUPTED). */
affect_status affect_features_extract(const affect_features *f, const affect_motion *m, double **x,
                                      uint32_t *n_frames, affect_monitor *mon, affect_error *err);

/* The gradient with respect to m's joint positions of a function of m's observations whose
 * gradient with respect to the observations is g (n_frames × dim): out (n_frames × m's joints
 * × 3, world coordinates, overwritten) is the transpose of the positions' linear map applied
 * to g — each entry's rotation and scale (body frame: that frame's heading, relative to the
 * root, so the root gains minus the others' share; first frame: the first frame's transform),
 * the headings and the scale held fixed. Positions only: "the observations have velocity or
 * root columns: only positions map back to the joints" (AFFECT_ERR_INVALID) otherwise; the
 * extraction's errors. */
affect_status affect_features_position_gradient(const affect_features *f, const affect_motion *m,
                                                const double *g, double *out, affect_monitor *mon,
                                                affect_error *err);

/* ---- mirror images (training-set augmentation, affect/classifier.h) ----
 * The mirror image of a motion swaps its left and right: each entry's partner is the entry
 * whose skeleton name is its own with Left ↔ Right (any case: "LeftHand" ↔ "RightHand") and the
 * single-letter tokens L ↔ R, l ↔ r between separators (_ . - : or the ends: "Hand_L_end" ↔
 * "Hand_R_end"); a name without such a token is its own partner (the spine, the head). In the
 * body frame, and in the first frame's normalized positions, the lateral axis is x (y for x-up
 * data): the mirror negates it. partner receives n_joints indices. Errors: "mirroring needs
 * the body frame or normalized positions", 'joint "Hand_L" has no mirror partner ("Hand_R"
 * is not among the observed joints)'. */
affect_status affect_features_mirror_map(const affect_features *f, uint32_t *partner,
                                         affect_error *err);
/* The observations of the mirror image: out (T × dim) from x (T × dim): every entry's
 * coordinates go to its partner with the lateral one negated, velocities likewise, and the
 * root's sideways speed and turning rate change sign. out must not overlap x. */
void affect_features_mirror(const affect_features *f, const uint32_t *partner, const double *x,
                            uint32_t n_frames, double *out);

/* A motion on the definition's skeleton (skeleton names, parents, unit, fps) whose frame k is
 * the first 3 × joints values of row k of x (n_frames × dim, e.g. one mean per HMM state). */
affect_status affect_features_posture_motion(const affect_features *f, const double *x,
                                             uint32_t n_frames, affect_motion **out,
                                             affect_error *err);

/* ---- binary form (embedded in the model BLOB, docs/FORMATS.md) ----
 *   0  1  up axis (0 .. 2)
 *   1  1  flag bits: 1 normalize, 2 scale by the arm, 4 velocity, 8 body frame, 16 root
 *         (others zero; root only with the body frame)
 *   2  1  unit length U (0 .. 15)
 *   3  1  reserved, zero
 *   4  4  joint count J (1 .. 4096)
 *   8  8  fps (float64, finite, 0 < fps ≤ 100000)
 *  16  U  unit
 *      J × { uint16 length L (1 .. 1024), L bytes }  entries
 *      J × { uint16 length L (1 .. 1024), L bytes }  skeleton names
 *      J × int32 parents (−1 or 0 .. J−1, acyclic)
 * little-endian, written byte by byte. */
#define AFFECT_FEATURES_HEADER_SIZE 16u

/* Size of the binary form; false on overflow. */
bool affect_features_encoded_size(const affect_features *f, size_t *size);
/* Writes the binary form into buf (affect_features_encoded_size bytes). */
void affect_features_encode_into(const affect_features *f, unsigned char *buf);
/* Decodes exactly size bytes; never reads outside them. */
affect_status affect_features_decode(const unsigned char *data, size_t size, affect_features **out,
                                     affect_error *err);

#ifdef __cplusplus
}
#endif
#endif
