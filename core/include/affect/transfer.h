/*
 * affect/transfer.h — emotion transfer: the change that a target emotion makes to a movement,
 * learned from donor pairs (one motion in the source emotion, one in the target emotion, of
 * the same content) and applied to the desired motion itself, so that its action, timing and
 * path stay and only how it is performed changes (affect_generate's default method; the
 * thesis's HMM_NN is affect/generate.h).
 *
 * Usage:
 *     const affect_motion *desired = ...;              // e.g. a neutral walk
 *     const affect_motion *from[1] = ..., *to[1] = ...;    // a donor pair: neutral, happy knock
 *     affect_error err;
 *     affect_transfer_options opt;
 *     affect_transfer_options_default(&opt);           // strength 1, bands 1 and 3 Hz
 *     affect_transfer_report rep;
 *     affect_motion *out = NULL;
 *     if (affect_transfer(desired, from, to, 1, &opt, &out, &rep, &err) != AFFECT_OK)
 *         puts(err.msg);
 *     else
 *         printf("%u joints changed\n", rep.joints_changed);
 *     affect_motion_free(out);
 *
 * What changes. Per joint, in its local rotations (the skeletal form, affect_motion_skeletal:
 * stored rotations, else inverse kinematics), a motion is described by its mean rotation q̄
 * (the normalized sum of its quaternions on one hemisphere) and by the deviations
 * d_t = log(q̄⁻¹ q_t), rotation vectors split by two zero-lag low-pass filters (affect_lowpass
 * at band_hz[0] and band_hz[1]) into a slow, a middle and a fast band whose sum is d_t. A donor
 * pair (A in the source emotion, B in the target) gives per joint the posture change
 * log(q̄_B q̄_A⁻¹) and per band the energy of each: the mean squared rate of change of the
 * band (amplitude = AFFECT_TRANSFER_VELOCITY, the default: a faster performance of the same
 * action shows as more energy even where its excursions are no wider) or of the band itself
 * (AFFECT_TRANSFER_DISPLACEMENT); over the pairs the posture changes are averaged and each
 * band's amplitude ratio is √((Σ E_B + e) / (Σ E_A + e)) (e = (2°/s)², resp. (0.5°)², per
 * pair, so a joint that hardly moves in the donors does not get a huge ratio), limited to
 * [1 / max_ratio, max_ratio]; with `pooled` one ratio per band from the energies of all joints
 * together. Applied to the desired motion with strength s:
 *     q'_t = exp(s · Δ) · q̄ · exp(Σ_b r_b^s · d_b,t),
 * the rotation vector limited to an angle of π. s = 0 returns the desired motion's skeletal
 * form unchanged (the same bytes); s = 1 is the change seen in the donors; s = 2 doubles the
 * posture change and squares the ratios. Each joint's posture angle and log-ratios are linear
 * in s, so Weight and Time move monotonically with s as long as the ratios move them one way.
 * The joints changed are those with a rotation that moves other joints (a child) that are
 * neither roots nor free links (affect/skeleton.h: a joint whose position channels move, such
 * as the corpus's Hips): those keep their values, so the root path and heading are the desired
 * motion's, frame by frame.
 * A joint that a pair's motions lack (by name) takes no change from that pair.
 *
 * Foot contacts (keep_contacts, default true; needs the left/right foot and hip roles): a foot
 * rests during a step from frame t to t + 1 when the foot joint or a joint below it (a toe)
 * moves slower than AFFECT_TRANSFER_CONTACT_SPEED × body size per second in the desired motion
 * (a planted heel or a planted toe); both frames of the step are contact frames. The leg's joints
 * (from the hip role's joint down to the foot's descendants) take the desired motion's own
 * rotations at contact frames, blended back to the transferred ones by slerp over 0.2 s on either
 * side. As the pelvis is unchanged, a foot at rest in the desired motion is exactly where it was:
 * no sliding is added.
 *
 * Output: the desired motion's skeletal form with the new rotations and the forward
 * kinematics as positions (rigid: every bone keeps its rest length), the desired motion's
 * joint names, parents, frame count, fps and unit.
 *
 * Donor pairs (affect_transfer_pairs), the thesis's way of choosing: the rows of the source
 * emotion nearest to the desired motion on the chosen components (distances given), each
 * paired with the row of the target emotion nearest to it on the same components (z-scored
 * Laban vectors, the index's standardization: sample standard deviation, 1 when it is 0;
 * missing components skipped), so that the pair shows the same content in both emotions when
 * the corpus has it; when the caller knows each row's content (a content key), the target row
 * must also have the source row's key. Without a source emotion (source < 0) any row not of the
 * target emotion can donate the first motion.
 *
 * Errors (AFFECT_ERR_INVALID unless said): an option out of range, named with every value:
 * "strength must be between 0 and 2 (strength 3, bands 1 and 3 Hz, max_ratio 3)", "band edges
 * must satisfy 0 < low < high (Hz) (…)", "max_ratio must be a finite number of at least 1 (…)",
 * "amplitude must be \"velocity\" or \"displacement\" (…)"; "no donor pairs"; "donor pair 2:
 * its motion in the source emotion is missing"; the skeletal form's errors prefixed with
 * "desired motion: " or "donor pair 1 (motion in the target emotion): "; "no donor pair has a
 * joint of the desired motion's skeleton (joint names)"; "out of memory" (AFFECT_ERR_NOMEM).
 * affect_transfer_pairs fails only when out of memory.
 */
#ifndef AFFECT_TRANSFER_H
#define AFFECT_TRANSFER_H

#include "affect/monitor.h"
#include "affect/motion.h"

#ifdef __cplusplus
extern "C" {
#endif

#define AFFECT_TRANSFER_MAX_STRENGTH 2.0
#define AFFECT_TRANSFER_BANDS 3
/* Foot contact threshold, relative to the body size (affect_motion_body_size) per second. */
#define AFFECT_TRANSFER_CONTACT_SPEED 0.1
/* Seconds over which a leg returns from its own rotations to the transferred ones. */
#define AFFECT_TRANSFER_CONTACT_RAMP 0.2

/* What a band's amplitude ratio compares. */
typedef enum affect_transfer_amplitude {
    AFFECT_TRANSFER_VELOCITY = 0,    /* its rate of change (default) */
    AFFECT_TRANSFER_DISPLACEMENT = 1 /* its deviation from the mean rotation */
} affect_transfer_amplitude;

typedef struct affect_transfer_options {
    double strength;    /* s in [0, 2] (default 1) */
    double band_hz[2];  /* the bands' edges (default 1 and 3 Hz) */
    double max_ratio;   /* amplitude ratios limited to [1/max_ratio, max_ratio] (default 3) */
    bool keep_contacts; /* (default true) */
    affect_transfer_amplitude amplitude; /* what the ratios compare (default: velocity) */
    bool pooled; /* one ratio per band for the whole body instead of one per joint (false) */
    affect_monitor *monitor; /* polled through inverse kinematics and between the stages
                                (default NULL): AFFECT_ERR_INTERRUPTED once it says stop */
} affect_transfer_options;

void affect_transfer_options_default(affect_transfer_options *opt);

/* NULL when opt is usable, else a static message. */
const char *affect_transfer_options_check(const affect_transfer_options *opt);

typedef struct affect_transfer_report {
    uint32_t pairs;          /* donor pairs given */
    uint32_t joints_changed; /* joints that took a change */
    double posture_deg;      /* mean posture change over those joints at strength s (degrees) */
    double ratio[AFFECT_TRANSFER_BANDS]; /* geometric mean of each band's ratio^s over them */
    uint32_t contact_frames[2];          /* frames with the left, right foot in contact */
} affect_transfer_report;

/* Transfers the change from from[i] to to[i] (n_pairs ≥ 1) onto desired. rep may be NULL. */
affect_status affect_transfer(const affect_motion *desired, const affect_motion *const *from,
                              const affect_motion *const *to, uint32_t n_pairs,
                              const affect_transfer_options *opt, affect_motion **out,
                              affect_transfer_report *rep, affect_error *err);

/* Donor pairs (see above). x: n × p raw vectors, row-major (NaN = missing); label[i] the class
 * of row i; group (NULL: none) a content key per row: a source row then pairs only with a
 * target row of its own key, and one with no such row, or with the key INT64_MIN (none), is
 * passed over; use[j] the components of the distances; dq[i] the distance of row i to the desired
 * motion on those components (NaN: not a candidate); up to n_pairs source rows from[k] in
 * order of dq, ties by row, each with its n_cand ≥ 1 nearest target rows to[k · n_cand + c],
 * nearest first (UINT32_MAX where there are fewer), and their distances dist[k · n_cand + c]
 * (dist may be NULL; NaN where there is none): the caller takes the first, or chooses among
 * them (affect_generate's default ranks them by DTW to the source row: the same action).
 * *got = 0 when no row can donate one side. */
affect_status affect_transfer_pairs(const double *x, uint32_t n, uint32_t p, const int32_t *label,
                                    const int64_t *group, const bool *use, const double *dq,
                                    int32_t source, int32_t target, uint32_t n_pairs,
                                    uint32_t n_cand, uint32_t *from, uint32_t *to, double *dist,
                                    uint32_t *got, affect_error *err);

/* The components for the donor search: those that do not discriminate the two emotions,
 * L \ (L′_source ∩ L′_target), or L \ L′_target when source < 0, from the salience flags
 * salient[k · p + j] (class k, component j); all of them when that leaves none. Returns
 * whether it fell back to all. */
bool affect_transfer_components(const bool *salient, uint32_t p, int32_t source, int32_t target,
                                bool *use);

/* The target row of donor pair k among its m candidates rows[0 .. m), ranked best first by
 * order (order[c] indexes rows; affect_generate ranks them by DTW to the pair's source row):
 * the best one that is not already the target of an earlier pair (to[0 .. k)), so that pairs
 * donate different recordings when they can; the best one when all are taken. Returns its
 * index into rows (m ≥ 1). */
uint32_t affect_transfer_pick_target(const uint32_t *order, const uint32_t *rows, uint32_t m,
                                     const uint32_t *to, uint32_t k);

#ifdef __cplusplus
}
#endif
#endif
