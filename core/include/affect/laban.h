/*
 * affect/laban.h — Laban Effort and Shape descriptors (SCIENCE.md §1; thesis §5.1–§5.2.1).
 *
 * Usage:
 *     const affect_motion *m = ...;
 *     affect_error err;
 *     affect_roles roles;
 *     affect_roles_resolve(m, &roles);
 *     affect_laban_options opt;
 *     affect_laban_options_default(&opt);
 *     opt.missing_null = true;                         // NaN where a role is missing
 *     double v[AFFECT_LABAN_N];                        // in affect_laban_names order
 *     if (affect_laban_vector(m, &roles, &opt, v, &err) != AFFECT_OK)
 *         puts(err.msg);
 *     else
 *         printf("%s = %g\n", affect_laban_names[0], v[0]);
 *
 * Kinematics. For a body part with position p(t) (a joint, or the centroid of several), the
 * velocity, acceleration and jerk are central differences at the motion's fps (one-sided at the
 * two ends), each low-pass filtered by a zero-lag 2nd-order Butterworth filter (cut-off 6 Hz by
 * default) run forward and backward; see affect_lowpass for the edge handling. With a cut-off at
 * or above the Nyquist frequency (fps / 2) nothing is filtered.
 *
 * Parts. torso = centroid of the resolved pelvis, spine and chest roles; head, left_hand,
 * right_hand, left_foot, right_foot = those roles; "all" = torso + the five end-effectors; or
 * any joint by name. Mass coefficients are all 1.
 *
 * Components (units follow the motion's: u = its length unit, s = seconds):
 *   Weight  Q1  max_t Σ_k ‖v_k(t)‖²                               u²/s²   (peak kinetic energy)
 *           Q2  max_t Σ_k max(0, −d‖v_k‖/dt)                        u/s²    (peak deceleration)
 *   Time    Q1  max_t Σ_k ‖a_k(t)‖                                  u/s²    (peak acceleration)
 *           Q2  Σ_k Σ_{t≥1} ‖v_k(t) − v_k(t−1)‖ / Δt                u/s²    (÷ duration: u/s³)
 *   Flow    Q2  Σ_k Σ_{t≥1} ‖a_k(t) − a_k(t−1)‖ / Δt                u/s³    (aggregated jerk)
 *   Space   Q2  mean_k  path_k / max(‖p_k(T) − p_k(1)‖, path_k / max_ratio)   (1 .. max_ratio)
 *           Q1  peaks of v_hand(t)·v_torso(t) (with hysteresis: rise and fall by 10 % of its
 *               range), binned: 0–1 → 1, 2–3 → 2, 4–5 → 3, 6–7 → 4, ≥8 → 5
 *   Shape Directional  mean over moving frames of |ẍẏ − ÿẋ| / (ẋ² + ẏ²)^{3/2} in the plane of the
 *           hand path's two principal axes (PCA); frames slower than speed_floor × the peak
 *           speed are left out (curvature of a still hand is noise)                   1/u
 *   Shape Shaping  vertical: max_t |torso_up(t) − torso_up(0)|; sagittal: the same along the
 *           body's forward direction in the first frame; horizontal: max_t area of the convex
 *           hull of all joints projected on the horizontal plane                      u, u, u²
 *   Shape Flow  max_t volume of the convex hull (or bounding box) of all joints        u³
 */
#ifndef AFFECT_LABAN_H
#define AFFECT_LABAN_H

#include "affect/monitor.h"
#include "affect/roles.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The number of Laban components, in laban_names() order. It is also a storage format: the
 * Laban vector BLOB (27 float32) that `laban_vector` returns and the `laban` index stores, the
 * index's `_info` statistics (27 means and sds), the classifier BLOB's descriptor block (D counts
 * 27 Laban values) and the RMLR fit over the components (p = 27) are all sized by it
 * (docs/FORMATS.md). Changing it is a format change: bump those formats' versions. */
#define AFFECT_LABAN_N 27

/* Component names in vector order: WeightAll, WeightTorso, WeightHead, WeightLHand,
 * WeightRHand, WeightLFoot, WeightRFoot, the same seven for Time and Flow, ShapeVertical,
 * ShapeSagittal, ShapeHorizontal, ShapeFlow, ShapeDirLHand, ShapeDirRHand. */
extern const char *const affect_laban_names[AFFECT_LABAN_N];

/* Index of a component name, or −1. */
int affect_laban_index(const char *name);

typedef struct affect_laban_options {
    double cutoff_hz;     /* low-pass cut-off (default 6) */
    int up_axis;          /* 0 = x, 1 = y (default), 2 = z */
    bool missing_null;    /* a component that cannot be computed becomes NaN instead of an error */
    bool hull_box;        /* Shape Flow from the bounding box instead of the convex hull */
    bool time_per_second; /* Time Q2 divided by the duration */
    double speed_floor;   /* Shape Directional: ignore frames slower than this × peak (0.05) */
    double max_ratio;     /* Space Q2 cap when the net displacement is near zero (100) */
    affect_monitor *monitor; /* polled every few thousand frames (default NULL): a component
                                or vector stops with AFFECT_ERR_INTERRUPTED once it says so */
} affect_laban_options;

void affect_laban_options_default(affect_laban_options *opt);

/* ---- filtering and derivatives ---- */

/* Zero-lag low-pass: 2nd-order Butterworth (bilinear transform, pre-warped) run forward then
 * backward over x[0], x[stride], … (n values), into out (same layout; out == x allowed).
 * Edges: the series is extended at each end by min(9, n − 1) samples of its odd reflection
 * (2·x[0] − x[k]), and each pass starts from the filter's steady state for the straight line
 * through its first two inputs, so constants and straight lines pass unchanged. No filtering when
 * cutoff_hz ≥ fps / 2 or n < 2. scratch holds at least n + 18 doubles. */
void affect_lowpass(const double *x, size_t n, size_t stride, double fps, double cutoff_hz,
                    double *scratch, double *out);

/* A body part: the centroid of up to 4 joints. */
typedef struct affect_part {
    uint32_t n_joints;
    int32_t joints[4];
    const char *name; /* for messages: "torso", "left_hand", a joint name */
} affect_part;

/* Resolves a part name ("torso", "head", "left_hand", "right_hand", "left_foot",
 * "right_foot", or a joint name) with the roles; "all" is not a single part. */
affect_status affect_part_resolve(const affect_motion *m, const affect_roles *roles,
                                  const char *name, affect_part *part, affect_error *err);

/* The six parts of "all": torso, head, left_hand, right_hand, left_foot, right_foot. */
affect_status affect_parts_all(const affect_motion *m, const affect_roles *roles,
                               affect_part parts[6], affect_error *err);

/* Filtered kinematics of one part: T × 3 doubles each (row-major). */
typedef struct affect_kinematics {
    uint32_t n_frames;
    double fps;
    double *pos, *vel, *acc, *jerk;
} affect_kinematics;

affect_status affect_kinematics_compute(const affect_motion *m, const affect_part *part,
                                        const affect_laban_options *opt, affect_kinematics *k,
                                        affect_error *err);
void affect_kinematics_free(affect_kinematics *k);

/* ---- Effort components over a set of parts ---- */

typedef enum affect_laban_method { AFFECT_LABAN_Q1 = 1, AFFECT_LABAN_Q2 = 2 } affect_laban_method;

/* Each takes n parts (1 for a single part, 6 for "all") and writes one value. */
affect_status affect_laban_weight(const affect_motion *m, const affect_part *parts, uint32_t n,
                                  affect_laban_method method, const affect_laban_options *opt,
                                  double *out, affect_error *err);
affect_status affect_laban_time(const affect_motion *m, const affect_part *parts, uint32_t n,
                                affect_laban_method method, const affect_laban_options *opt,
                                double *out, affect_error *err);
affect_status affect_laban_flow(const affect_motion *m, const affect_part *parts, uint32_t n,
                                const affect_laban_options *opt, double *out, affect_error *err);
/* Space Q2 (mean over parts) or Q1 (hand = parts[0], torso = parts[1]; n must be 2). */
affect_status affect_laban_space(const affect_motion *m, const affect_part *parts, uint32_t n,
                                 affect_laban_method method, const affect_laban_options *opt,
                                 double *out, affect_error *err);

/* ---- Shape components ---- */

affect_status affect_laban_shape_directional(const affect_motion *m, const affect_part *hand,
                                             const affect_laban_options *opt, double *out,
                                             affect_error *err);
/* out = {vertical, sagittal, horizontal}. */
affect_status affect_laban_shape_shaping(const affect_motion *m, const affect_roles *roles,
                                         const affect_laban_options *opt, double out[3],
                                         affect_error *err);
affect_status affect_laban_shape_flow(const affect_motion *m, const affect_laban_options *opt,
                                      double *out, affect_error *err);

/* ---- all 27 ---- */

/* Every component in affect_laban_names order. With opt->missing_null a component that needs
 * an unresolved role (or more frames) is NaN; otherwise that is an error naming the role. */
affect_status affect_laban_vector(const affect_motion *m, const affect_roles *roles,
                                  const affect_laban_options *opt, double out[AFFECT_LABAN_N],
                                  affect_error *err);

/* ---- standardization (SCIENCE.md §5 step 1) and vectors for L2 search ----
 *
 * The laban index (ext/vt_laban.c) stores each vector as float32 and compares motions by the
 * Euclidean distance of their z-scores z_j = (x_j − mean_j) / sd_j, computed in double from the
 * float32 values, over the components present in both vectors. These functions are that
 * arithmetic, shared by the index and by the vectors it hands to other L2 searches. */

/* A component as the index stores it: v rounded to float32; NaN, ±inf and values beyond the
 * float range are missing (NaN). */
float affect_laban_f32(double v);

/* mean and sd per component over n vectors x (n × AFFECT_LABAN_N, row-major, NaN = missing),
 * missing values skipped: mean is NaN where every value is missing; sd is the sample standard
 * deviation (n − 1 divisor), and 1 where it is 0, not finite or undefined (fewer than two
 * values), so it is always a usable divisor. */
void affect_laban_stats(const float *x, size_t n, double mean[AFFECT_LABAN_N],
                        double sd[AFFECT_LABAN_N]);

/* affect_laban_stats in parts, for a caller that polls an interrupt between them (the laban
 * index over millions of rows): affect_laban_acc_init, affect_laban_acc_sums over every part of
 * the rows in order, affect_laban_acc_means, affect_laban_acc_squares over the same parts in the
 * same order, then affect_laban_acc_result. Each component's sums take the rows in the same
 * order as affect_laban_stats, so the result has the same bits, whatever the parts. */
typedef struct affect_laban_acc {
    double sum[AFFECT_LABAN_N], ss[AFFECT_LABAN_N], mean[AFFECT_LABAN_N];
    size_t cnt[AFFECT_LABAN_N];
} affect_laban_acc;
void affect_laban_acc_init(affect_laban_acc *a);
void affect_laban_acc_sums(affect_laban_acc *a, const float *x, size_t n);
void affect_laban_acc_means(affect_laban_acc *a);
void affect_laban_acc_squares(affect_laban_acc *a, const float *x, size_t n);
void affect_laban_acc_result(const affect_laban_acc *a, double mean[AFFECT_LABAN_N],
                             double sd[AFFECT_LABAN_N]);

/* The z-scores of n vectors x (n × AFFECT_LABAN_N, NaN = missing) into z (the same shape):
 * z = ((double)x − mean) / sd per component, NaN where x or mean is missing. */
void affect_laban_standardize(const float *x, size_t n, const double mean[AFFECT_LABAN_N],
                              const double sd[AFFECT_LABAN_N], double *z);

/* Checks statistics read back from storage: every mean finite or NaN (missing everywhere),
 * every sd finite and > 0. AFFECT_ERR_FORMAT naming the first bad one ("sd[3] (WeightLHand) is
 * -1, expected a finite number > 0"). */
affect_status affect_laban_stats_check(const double mean[AFFECT_LABAN_N],
                                       const double sd[AFFECT_LABAN_N], affect_error *err);

/* The vector whose plain Euclidean (L2) distances are the index's distances: out[t] =
 * (x[c] − mean[c]) / sd[c] for the n_comp components c = comp[t] (all AFFECT_LABAN_N in order
 * when comp is NULL), computed in double and rounded to float32. A component whose mean is NaN
 * (missing in every indexed row) is 0: the index skips it for every pair, and a constant adds
 * nothing to an L2 distance. A component missing in x whose mean is known cannot be written
 * (the index would skip it for this vector's pairs only, which no L2 vector reproduces):
 * AFFECT_ERR_MISSING naming it; a z-score beyond the float32 range (statistics with a tiny sd)
 * is AFFECT_ERR_RANGE. n_comp in 1..AFFECT_LABAN_N, comp entries in range (AFFECT_ERR_INVALID
 * otherwise). */
affect_status affect_laban_l2_vector(const float x[AFFECT_LABAN_N],
                                     const double mean[AFFECT_LABAN_N],
                                     const double sd[AFFECT_LABAN_N], const int *comp, int n_comp,
                                     float *out, affect_error *err);

/* ---- search of standardized vectors (laban_search.c) ----
 *
 * The laban index's queries as arithmetic over rows of z-scores (n × AFFECT_LABAN_N doubles,
 * row-major, NaN where a component is missing):
 *   distance   d(q, x) = sqrt( Σ_{c ∈ C, q_c and x_c present} (q_c − x_c)² ) over the chosen
 *              components C; a pair with no component of C present in both has no distance
 *              and is never a hit;
 *   k nearest  the k smallest distances (all of them when fewer rows qualify), kept in a
 *              bounded max-heap of k entries while the rows stream by;
 *   radius     relative: the rows within radius · (the largest distance among the rows that
 *              qualify) of the query, and at least the nearest row, so a query that qualifies
 *              any row always answers;
 * hits in ascending distance, ties by id ascending (the tie rule that makes an answer the same
 * whatever order the rows are stored in). */

/* The distance over the n_comp components comp[0..n_comp) (each in 0..AFFECT_LABAN_N − 1):
 * sqrt of the sum of (q_c − x_c)² over those whose difference is a number (both present);
 * NaN when there is none. */
double affect_laban_distance(const double *q, const double *x, const int *comp, int n_comp);

typedef struct affect_laban_hit {
    double d;   /* distance */
    int64_t id; /* the row's id (the tie rule) */
    size_t row; /* the row's index in the set */
} affect_laban_hit;

/* −1, 0, 1: by distance, then by id. */
int affect_laban_hit_cmp(const affect_laban_hit *a, const affect_laban_hit *b);

/* A search over rows [lo, hi) of a set of z-score rows. */
typedef struct affect_laban_search {
    const double *z;    /* the rows, n × AFFECT_LABAN_N */
    const int64_t *ids; /* their ids */
    size_t lo, hi;      /* the rows searched */
    size_t self;        /* a row left out (the query's own row), or SIZE_MAX for none */
    /* label filter: when label_ok is not NULL only rows i with label[i] ≥ 0 and
     * label_ok[label[i]] != 0 are searched */
    const int32_t *label;
    const unsigned char *label_ok;
    const int *comp; /* the components C, n_comp of them (1..AFFECT_LABAN_N) */
    int n_comp;
    uint64_t k;    /* > 0: the k nearest; 0: the radius ball */
    double radius; /* for k = 0: a number ≥ 0 (NaN keeps only the nearest) */
} affect_laban_search;

/* Hits the search can give at most: min(k, hi − lo) for k > 0, hi − lo for the radius; the
 * caller's hits array holds that many (at least 1). */
size_t affect_laban_search_capacity(const affect_laban_search *s);

/* Runs the search on query q (AFFECT_LABAN_N z-scores, NaN where missing): *n_hits hits into
 * hits (sorted as above). Allocates nothing; O((hi − lo) · (n_comp + log k)). */
void affect_laban_search_run(const affect_laban_search *s, const double *q, affect_laban_hit *hits,
                             size_t *n_hits);

/* ---- windowed Effort series (laban_series.c) ----
 *
 * Weight, Time, Space and Flow over a window sliding along the motion, for plotting an Effort
 * over a take. The kinematics are those of the whole motion (filtered once, as for the per-clip
 * values); each window then reduces the frames it covers with the per-clip definitions:
 *   weight  Q1 (default) max over the window's frames t of Σ_k ‖v_k(t)‖², or Q2 the peak
 *           deceleration max over t of Σ_k max(0, −d‖v_k‖/dt) (t and t − 1 in the window)
 *   time    Q1 (default) max_t Σ_k ‖a_k(t)‖, or Q2 Σ_k Σ_t ‖v_k(t) − v_k(t−1)‖ / Δt (t and
 *           t − 1 in the window; ÷ the window's duration, len / fps, with time_per_second)
 *   space   Q2: mean over the parts of path / max(‖p_k(last) − p_k(first)‖, path / max_ratio)
 *   flow    Σ_k Σ_t ‖a_k(t) − a_k(t−1)‖ / Δt (t and t − 1 in the window)
 * so a window covering the whole motion gives the per-clip values: the peaks bit for bit, the
 * sums to rounding (AFFECT_LABAN_SERIES_RTOL). Windows start at frames 0, hop, 2·hop, … while
 * they fit (window i covers frames i·hop … i·hop + window − 1); a window longer than the motion
 * is cut to it (one window). Cost O(frames · parts), whatever the window: the peaks come from
 * monotone queues, the sums from running sums kept in double-double (TwoSum), so adding and
 * removing frames does not drift. Memory: the parts' kinematics (6 doubles a frame and part),
 * and for overlapping windows a ring of one window's step terms (3 · rows + parts doubles a
 * frame). */

/* Quantities of a row, in this order. */
enum {
    AFFECT_SERIES_WEIGHT,
    AFFECT_SERIES_TIME,
    AFFECT_SERIES_SPACE,
    AFFECT_SERIES_FLOW,
    AFFECT_SERIES_N
};

/* A window covering the whole motion equals the per-clip sums within this relative tolerance. */
#define AFFECT_LABAN_SERIES_RTOL 1e-12

typedef struct affect_laban_series_options {
    uint32_t window;            /* frames per window, ≥ 2 */
    uint32_t hop;               /* frames between window starts, ≥ 1 */
    affect_laban_method weight; /* Q1 peak kinetic energy (default) or Q2 peak deceleration */
    affect_laban_method time;   /* Q1 peak acceleration (default) or Q2 accumulated */
    bool combined;              /* row 0 of each window: all the parts together ("all") */
} affect_laban_series_options;

/* window 0 (to be set: from affect_laban_series_frames), hop 1, Q1, Q1, combined false. */
void affect_laban_series_options_default(affect_laban_series_options *so);

/* Frames of a duration in seconds at fps: round(seconds · fps), at most UINT32_MAX (a window
 * longer than any motion), or 0 when that is not a finite number of at least 0.5 (the caller
 * reports it). */
uint32_t affect_laban_series_frames(double seconds, double fps);

typedef struct affect_laban_series affect_laban_series;

/* Prepares the series of n parts (1 to 6) of m: checks both options (AFFECT_ERR_INVALID: window
 * < 2, hop < 1; AFFECT_ERR_RANGE: fewer than 4 frames), computes the kinematics (polling
 * opt->monitor, which the series keeps polling in affect_laban_series_next). m and opt (NULL:
 * the defaults) must outlive the series; after an error of affect_laban_series_next only
 * affect_laban_series_free may be called. */
affect_status affect_laban_series_new(const affect_motion *m, const affect_part *parts, uint32_t n,
                                      const affect_laban_options *opt,
                                      const affect_laban_series_options *so,
                                      affect_laban_series **out, affect_error *err);
/* Windows in all, and rows per window (n, + 1 with combined). */
uint32_t affect_laban_series_windows(const affect_laban_series *s);
uint32_t affect_laban_series_rows(const affect_laban_series *s);
/* The next window (in order, from window 0): its first and last frame and rows ×
 * AFFECT_SERIES_N values (row 0 the combined one when asked, then the parts in order).
 * AFFECT_ERR_RANGE once every window was given; AFFECT_ERR_INTERRUPTED when the monitor says
 * stop (polled every few thousand frames). */
affect_status affect_laban_series_next(affect_laban_series *s, uint32_t *first, uint32_t *last,
                                       double *values, affect_error *err);
void affect_laban_series_free(affect_laban_series *s);

/* ---- geometry (exposed for tests) ---- */

/* Area of the convex hull of n 2-D points (xy interleaved); 0 for fewer than 3 or collinear.
 * scratch holds 4·n doubles. */
double affect_hull_area_2d(const double *xy, uint32_t n, double *scratch);

/* Volume of the convex hull of n 3-D points (xyz interleaved) with a reusable workspace sized
 * for up to max_points points; 0 when they are coplanar or fewer than 4. */
typedef struct affect_hull3d affect_hull3d;
affect_hull3d *affect_hull3d_new(uint32_t max_points); /* NULL if an allocation fails */
void affect_hull3d_free(affect_hull3d *h);
double affect_hull3d_volume(affect_hull3d *h, const double *xyz, uint32_t n); /* n ≤ max */
/* An upper bound of affect_hull3d_volume(h, xyz, n) from the last hull h built with a positive
 * volume (its reference), without building this one: the reference's faces, with these
 * coordinates, seen from the points' centroid, each cone cut where the points' extent ends
 * (hull.c). It is the volume itself (to about 1e-5) while no point rises above a reference
 * face, and grows as the hull's faces change (the next frames of a motion are the intended
 * use). +∞ when there is no reference, the reference had another n, n > max, a coordinate is
 * not finite or the centroid is too close to a face's plane; 0 when n < 4. Allocates nothing;
 * changes nothing that affect_hull3d_volume returns. */
double affect_hull3d_bound(affect_hull3d *h, const double *xyz, uint32_t n);
/* A cheaper, looser upper bound of affect_hull3d_volume(h, xyz, n): the cones of the last finite
 * affect_hull3d_bound frozen (their faces' normals and shapes as they were then, moved to these
 * points' centroid), each cut where these points' extent along its normal ends; only the
 * extents are computed (hull.c). Meant for the frames right after that bound: as the body
 * turns and bends it loosens. +∞ when there is no such bound (none yet, or the last one was
 * +∞ or for another n), n > max, a coordinate is not finite or the points' size is far from
 * that bound's (a factor 32); 0 when n < 4. Allocates nothing; changes nothing that
 * affect_hull3d_volume or affect_hull3d_bound return. */
double affect_hull3d_bound_quick(affect_hull3d *h, const double *xyz, uint32_t n);

#ifdef __cplusplus
}
#endif
#endif
