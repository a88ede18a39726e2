/*
 * affect/summary.h — kinematic summaries of a whole motion: a short fixed-length vector of how
 * fast and how far the body and its end-effectors moved, how it turned, and how it held itself.
 * They are the motion-level descriptors the recognizer can append to its Fisher representation
 * (affect/classifier.h), and what the scikit-learn peer of the evaluation classifies.
 *
 * Usage:
 *     const affect_motion *m = ...;
 *     affect_error err;
 *     double s[AFFECT_SUMMARY_N];
 *     if (affect_motion_summary(m, 1, s, NULL, &err) == AFFECT_OK)   // up axis 1 = y
 *         printf("%s = %g\n", affect_summary_names[0], s[0]);
 *     uint32_t d = affect_descriptors_dim(AFFECT_DESC_ALL);
 *     double *desc = affect_malloc_array(d, sizeof *desc);
 *     if (desc && affect_descriptors(AFFECT_DESC_ALL, m, 1, desc, NULL, &err) != AFFECT_OK)
 *         puts(err.msg);
 *     affect_free(desc);
 *
 * Frames. Lengths are divided by the body size (the right arm's length, shoulder → elbow → hand,
 * in the first frame; 1 when those roles do not resolve), so a summary does not depend on the
 * unit or the performer's size. "Body frame" is that of affect/features.h: relative to the
 * pelvis of the frame, turned so that the frame's lateral vector lies on +x (up stays up; the
 * body faces +z for y-up data). Speeds are central differences × fps (one-sided at the ends).
 *
 * Entries (affect_summary_names order; u = body size, s = seconds):
 *   duration            T / fps                                                  s
 *   root_speed          mean horizontal speed of the pelvis                       u/s
 *   root_speed_p90      its 90th percentile                                       u/s
 *   root_bounce         standard deviation of the pelvis height                   u
 *   turn_rate           mean |turning rate| of the heading                        rad/s
 *   net_turn            |heading(T) − heading(0)| (unwrapped)                     rad
 *   head_speed … right_foot_speed          mean body-frame speed of head, left hand,
 *                       right hand, left foot, right foot                         u/s
 *   head_speed_p90 … right_foot_speed_p90  their 90th percentiles                 u/s
 *   head_height         mean height of the head above the pelvis                  u
 *   head_forward        mean forward offset of the head from the pelvis (lean)    u
 *   hand_height         mean height of the two hands above the pelvis             u
 *   hand_spread         mean distance between the hands                           u
 *   foot_spread         mean distance between the feet                            u
 * An entry whose role does not resolve is 0 (the heading needs the hips or the shoulders; without
 * them the frames are not turned and turning entries are 0). A single frame has zero speeds.
 *
 * Percentiles: the value at rank ⌈0.9 T⌉ of the sorted values (nearest rank).
 */
#ifndef AFFECT_SUMMARY_H
#define AFFECT_SUMMARY_H

#include "affect/monitor.h"
#include "affect/roles.h"

#ifdef __cplusplus
extern "C" {
#endif

#define AFFECT_SUMMARY_N 21

extern const char *const affect_summary_names[AFFECT_SUMMARY_N];

/* The summary of m (up axis 0 = x, 1 = y, 2 = z) into out. Errors: "up axis must be x, y or z";
 * AFFECT_ERR_NOMEM; AFFECT_ERR_INTERRUPTED when mon (may be NULL), polled between the passes
 * over the frames, says stop. */
affect_status affect_motion_summary(const affect_motion *m, int up_axis,
                                    double out[AFFECT_SUMMARY_N], affect_monitor *mon,
                                    affect_error *err);

/* ---- motion-level descriptors for the recognizer ----
 * A combination of blocks, in this order: the kinematic summary above (AFFECT_SUMMARY_N
 * values) and the Laban vector (affect/laban.h, default options, AFFECT_LABAN_N values, a
 * component that cannot be computed 0). Every value v becomes sign(v) · log(1 + |v|): the
 * components span orders of magnitude (peak kinetic energies, hull volumes), and a linear
 * classifier on z-scores of the logarithms is not led by one outlying motion. */
enum { AFFECT_DESC_KINEMATICS = 1u, AFFECT_DESC_LABAN = 2u, AFFECT_DESC_ALL = 3u };

/* Values for a mask (0 for 0 or an unknown bit). */
uint32_t affect_descriptors_dim(unsigned mask);
/* The descriptors of m (up axis as for the summary) into out (affect_descriptors_dim(mask)
 * values). Errors: "descriptors must be a combination of kinematics and laban", the summary's,
 * and the Laban vector's (AFFECT_ERR_NOMEM; roles are not required: missing ones give 0). */
affect_status affect_descriptors(unsigned mask, const affect_motion *m, int up_axis, double *out,
                                 affect_monitor *mon, affect_error *err);

/* The descriptors of the mirror image (affect_features_mirror) from those of the motion: the
 * left and right entries swap (hand and foot speeds; the Laban LHand/RHand and LFoot/RFoot
 * components, Shape Directional of the hands); the rest are symmetric. in and out may be the
 * same. */
void affect_descriptors_mirror(unsigned mask, const double *in, double *out);

#ifdef __cplusplus
}
#endif
#endif
