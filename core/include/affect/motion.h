/*
 * affect/motion.h — the motion model: T frames × J joints × (x, y, z) world positions at a
 * fixed frame rate, with joint names, a parent index per joint (−1 for a root; all −1 when the
 * skeleton is unknown) and the coordinate unit when it is known.
 *
 * Usage:
 *     affect_error err;
 *     affect_motion *m = NULL, *back = NULL;
 *     unsigned char *blob = NULL;  size_t size = 0;
 *     if (affect_motion_create(2, 1, 30.0, &m, &err) == AFFECT_OK &&          // 2 frames, 1 joint
 *         affect_motion_set_name(m, 0, "Hips", 4, &err) == AFFECT_OK) {
 *         affect_motion_at(m, 1, 0)[1] = 0.9f;                          // y of joint 0, frame 1
 *         if (affect_motion_encode(m, &blob, &size, &err) == AFFECT_OK &&
 *             affect_motion_decode(blob, size, &back, &err) == AFFECT_OK)
 *             printf("%u frames, %g s\n", back->n_frames, affect_motion_duration(back));
 *     }
 *     affect_free(blob);  affect_motion_free(back);  affect_motion_free(m);
 *
 * Positions are a flat row-major float array, frame-major: pos[(t * J + j) * 3 + axis].
 * Every joint name is a NUL-terminated string of valid UTF-8, unique within the motion. Parent
 * indices form a forest (no cycles); they need not precede their children.
 *
 * A motion may also carry a skeleton (docs/FORMATS.md, version 2): per joint its rest offset
 * from the parent and its BVH channel list, and, per frame, every joint's local rotation (a
 * unit quaternion) and local translation. Positions stay the primary data that every analysis
 * reads; when rotations are present the positions are their forward kinematics (the importers
 * and editors keep the two consistent, affect/skeleton.h recomputes one from the other).
 *
 * The binary form (the "motion BLOB", docs/FORMATS.md) is produced by affect_motion_encode and
 * checked field by field by affect_motion_decode.
 */
#ifndef AFFECT_MOTION_H
#define AFFECT_MOTION_H

#include "affect/base.h"
#include "affect/monitor.h"

#ifdef __cplusplus
extern "C" {
#endif

#define AFFECT_MOTION_MAX_JOINTS 4096u
#define AFFECT_MOTION_MAX_FRAMES 16777216u /* 2^24 */
#define AFFECT_MOTION_MAX_NAME 1024u       /* bytes of one joint name */
#define AFFECT_MOTION_UNIT_MAX 15u         /* bytes of the unit string */
#define AFFECT_MOTION_MAX_FPS 100000.0

/* The largest motion the text importers build unless their option max_samples raises it:
 * frames × joints ("samples"). 2^24 is 39 minutes at 120 fps with 60 joints, 86 minutes with 27,
 * 7 hours at 30 fps with 22. A BVH import holds 40 bytes per sample (position 12, rotation 16,
 * translation 12: 640 MiB at the limit) and its BLOB at most as many, which stays under
 * SQLite's default limit of 10^9 bytes per value whatever the channels (2^25 would not when
 * every joint has position channels). The limit also bounds what a small text can make the
 * importers allocate (BVH joints without channels take no text per frame). The BLOB decoder
 * does not apply it (a BLOB holds every sample it declares), nor do the editing operations
 * (a result is no larger than its input), except affect_motion_resample, whose result may
 * reach it or the input's size, whichever is larger. */
#define AFFECT_MOTION_MAX_SAMPLES 16777216u /* 2^24 */

/* BLOB layout constants (docs/FORMATS.md). */
#define AFFECT_MOTION_MAGIC "AFMO"
#define AFFECT_MOTION_VERSION 2u
#define AFFECT_MOTION_HEADER_SIZE 32u
#define AFFECT_MOTION_FLAG_SKELETON 1u  /* version 2: the skeleton part follows the positions */
#define AFFECT_MOTION_FLAG_ROTATIONS 2u /* version 2: then rotations and translations */
#define AFFECT_MOTION_JOINT_SIZE 32u    /* bytes of one joint in the skeleton part */
/* decoded quaternions must have a norm within this of 1 */
#define AFFECT_MOTION_QUAT_NORM_TOL 1e-3

/* Channel types of a skeleton joint, as BVH names them. */
enum {
    AFFECT_CH_XPOS,
    AFFECT_CH_YPOS,
    AFFECT_CH_ZPOS,
    AFFECT_CH_XROT,
    AFFECT_CH_YROT,
    AFFECT_CH_ZROT,
    AFFECT_CH_COUNT
};
/* affect_skel_joint.flags: a BVH End Site (a leaf, no channels) */
#define AFFECT_JOINT_END_SITE 1u

/* One joint of a skeleton: its rest offset from its parent (in the parent's frame; for a root,
 * its rest position) and the channels it has in BVH, in file order. */
typedef struct affect_skel_joint {
    double offset[3];
    uint8_t n_channels; /* 0 .. 6 */
    uint8_t channel[6]; /* AFFECT_CH_*, distinct */
    uint8_t flags;      /* AFFECT_JOINT_END_SITE */
} affect_skel_joint;

typedef struct affect_motion {
    uint32_t n_frames;
    uint32_t n_joints;
    double fps;
    char unit[AFFECT_MOTION_UNIT_MAX + 1]; /* "" when unknown; e.g. "cm", "m", "mm", "arm" */
    char **names;                          /* n_joints strings */
    int32_t *parents;                      /* n_joints entries */
    float *pos;                            /* n_frames * n_joints * 3 */
    affect_skel_joint *skel;               /* NULL, or n_joints entries */
    float *rot;   /* NULL, or n_frames * n_joints * 4 local rotations (w, x, y, z); needs skel */
    float *trans; /* with rot: n_frames * n_joints * 3 local translations (the offset, or the
                   * position channels' values for joints that have them) */
} affect_motion;

/* Allocates a motion with zeroed positions, parents all −1 and names "j0", "j1", ….
 * Checks the sizes against the limits above and fps > 0, finite, ≤ AFFECT_MOTION_MAX_FPS. */
affect_status affect_motion_create(uint32_t n_frames, uint32_t n_joints, double fps,
                                   affect_motion **out, affect_error *err);

/* Gives m a skeleton (offsets zero, no channels) and, when rotations is true, identity
 * rotations and zero translations; any skeleton it had is replaced. */
affect_status affect_motion_add_skeleton(affect_motion *m, bool rotations, affect_error *err);

/* Removes the skeleton, rotations and translations (positions stay). */
void affect_motion_drop_skeleton(affect_motion *m);

/* True when joint j of the skeleton has at least one position channel. */
bool affect_skel_has_position(const affect_skel_joint *j);

/* Frees a motion and everything it owns; NULL is allowed. */
void affect_motion_free(affect_motion *m);

/* Replaces the name of joint j with the first len bytes of name: 1 .. AFFECT_MOTION_MAX_NAME
 * bytes of valid UTF-8 without NUL (else AFFECT_ERR_FORMAT, "joint 3: name is not valid UTF-8
 * (byte 0xff at offset 2)"). */
affect_status affect_motion_set_name(affect_motion *m, uint32_t j, const char *name, size_t len,
                                     affect_error *err);

/* Replaces the parent indices (n_joints entries, −1 for a root) after checking them (in range,
 * acyclic); m is unchanged on error. Drops any skeleton (it described the old hierarchy). */
affect_status affect_motion_set_parents(affect_motion *m, const int32_t *parents,
                                        affect_error *err);

/* Sets the unit string; it must be at most AFFECT_MOTION_UNIT_MAX bytes of [A-Za-z0-9_.-]. */
affect_status affect_motion_set_unit(affect_motion *m, const char *unit, affect_error *err);

/* Checks the invariants above: names non-empty, valid UTF-8 free of NUL, and unique; parents in
 * range and acyclic; every coordinate finite (the message names the frame and joint); the
 * skeleton's channels, End Sites, finite offsets, unit quaternions and finite translations. */
affect_status affect_motion_validate(const affect_motion *m, affect_error *err);

/* Deep copy. */
affect_status affect_motion_clone(const affect_motion *m, affect_motion **out, affect_error *err);

/* Index of the joint whose name equals name exactly, or −1. */
int32_t affect_motion_find_joint(const affect_motion *m, const char *name);

/* Pointer to frame t, joint j: three floats. */
static inline float *affect_motion_at(const affect_motion *m, uint32_t t, uint32_t j)
{
    return m->pos + ((size_t)t * m->n_joints + j) * 3;
}

/* Duration in seconds: n_frames / fps (the BVH convention, Frames × Frame Time). */
double affect_motion_duration(const affect_motion *m);

/* Axis-aligned bounding box of every position of every frame. */
void affect_motion_bbox(const affect_motion *m, float min[3], float max[3]);

/* ---- the motion BLOB ---- */

/* Size in bytes of the encoded form; false if it would overflow size_t, or if a name is not
 * 1 .. AFFECT_MOTION_MAX_NAME bytes of valid UTF-8 (a caller wrote m->names itself): such a
 * motion cannot be encoded. */
bool affect_motion_encoded_size(const affect_motion *m, size_t *size);

/* Encodes into a new buffer of *size bytes (free with affect_free). A motion without a
 * skeleton is written as version 1, byte for byte as before version 2 existed; one with a
 * skeleton as version 2. A name the decoder would refuse is AFFECT_ERR_INVALID ("cannot encode
 * the motion: joint 3: name is not valid UTF-8 (byte 0xff at offset 2)"). */
affect_status affect_motion_encode(const affect_motion *m, unsigned char **out, size_t *size,
                                   affect_error *err);

/* Encodes into buf, which must hold affect_motion_encoded_size() bytes (so only a motion for
 * which that returned true). */
void affect_motion_encode_into(const affect_motion *m, unsigned char *buf);

/* Decodes and validates a BLOB. Never reads outside [data, data + size). */
affect_status affect_motion_decode(const unsigned char *data, size_t size, affect_motion **out,
                                   affect_error *err);
/* The same, polling mon (may be NULL) between its passes over the frames (a motion at the size
 * limit takes tenths of a second): AFFECT_ERR_INTERRUPTED once it says stop. */
affect_status affect_motion_decode_monitored(const unsigned char *data, size_t size,
                                             affect_monitor *mon, affect_motion **out,
                                             affect_error *err);

/* ---- editing; each returns a new motion ---- */

/* Frames first..last inclusive, 0-based; negative values count from the end (−1 = last).
 * Keeps the skeleton and the rotations of those frames. */
affect_status affect_motion_slice(const affect_motion *m, int64_t first, int64_t last,
                                  affect_motion **out, affect_error *err);

/* Linear interpolation to a new frame rate. The result keeps the time span: it has
 * floor((T − 1) · fps / m->fps + 1e-9) + 1 frames, frame k at time k / fps. With rotations,
 * they are interpolated by slerp and translations linearly, and the positions are their
 * forward kinematics (so the result stays rigid). Frames × joints may not exceed
 * AFFECT_MOTION_MAX_SAMPLES or the input's frames × joints, whichever is larger
 * (AFFECT_ERR_RANGE). */
affect_status affect_motion_resample(const affect_motion *m, double fps, affect_motion **out,
                                     affect_error *err);

/* The joints named, in the order given (duplicates and unknown names are errors). A joint's
 * parent becomes its nearest selected ancestor, or −1. The skeleton and rotations are dropped
 * (the selected joints' offsets no longer describe their positions). */
affect_status affect_motion_select(const affect_motion *m, const char *const *names,
                                   uint32_t n_names, affect_motion **out, affect_error *err);

#ifdef __cplusplus
}
#endif
#endif
