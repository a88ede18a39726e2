/*
 * laban.c — Laban Effort and Shape descriptors (see affect/laban.h for the definitions).
 *
 * How it works: every part's position series (a joint, or a centroid) is differentiated by
 * central differences and low-pass filtered three times (velocity, acceleration, jerk). The
 * Effort components reduce those series; affect_laban_vector computes the six parts' velocity
 * and acceleration once, all 18 channels interleaved and filtered in one lockstep pass (the
 * same bits as affect_lowpass per channel), and derives all 21 Effort values from them; its
 * hull areas are bounded per frame first, and only frames that can beat the best get a hull.
 * Shape components use the raw positions: Directional projects the hand path on its two
 * principal axes (LAPACKE_dsyev on the 3 × 3 covariance), Shaping and Flow take convex hulls
 * per frame (hull.c). Shape Flow is the largest 3-D hull volume over the frames: the frame of
 * the largest bounding box is built first, then every frame is bounded from the last hull
 * built (affect_hull3d_bound, rigorous and tight while the hull's faces change little; first
 * by the cheaper affect_hull3d_bound_quick when the last bound was well below the best) and its
 * hull is built only when the bound reaches the best so far (on the corpora about a quarter
 * of the frames: fast limbs soon make the last hull's faces a loose fit). The volumes built
 * are Quickhull's, so the result has the same bits as a hull of every frame.
 *
 * The filter: a 2nd-order Butterworth low-pass from the bilinear transform with the cut-off
 * pre-warped, K = tan(π fc / fs), applied forward and then backward (zero phase, the
 * biomechanics convention for marker data, and what the thesis's footnote describes). Each end
 * is extended by an odd reflection of up to 9 samples (as scipy's filtfilt does for a biquad)
 * and each pass starts from the steady state of the line through its first two inputs (scipy
 * starts from a constant's), so a constant or a straight line is not bent at the edges: a still
 * or uniformly moving part shows no spurious acceleration at the start or end of a recording.
 */
#include "affect/laban.h"

#include <lapacke.h>
#include <math.h>
#include <string.h>

#include "util/internal.h"

const char *const affect_laban_names[AFFECT_LABAN_N] = {
    "WeightAll",     "WeightTorso",   "WeightHead",    "WeightLHand",     "WeightRHand",
    "WeightLFoot",   "WeightRFoot",   "TimeAll",       "TimeTorso",       "TimeHead",
    "TimeLHand",     "TimeRHand",     "TimeLFoot",     "TimeRFoot",       "FlowAll",
    "FlowTorso",     "FlowHead",      "FlowLHand",     "FlowRHand",       "FlowLFoot",
    "FlowRFoot",     "ShapeVertical", "ShapeSagittal", "ShapeHorizontal", "ShapeFlow",
    "ShapeDirLHand", "ShapeDirRHand"};

enum {
    IDX_WEIGHT = 0,
    IDX_TIME = 7,
    IDX_FLOW = 14,
    IDX_VERTICAL = 21,
    IDX_SAGITTAL,
    IDX_HORIZONTAL,
    IDX_SHAPE_FLOW,
    IDX_DIR_LHAND,
    IDX_DIR_RHAND
};

/* The six parts of "all", in component order after "All". */
static const char *const all_parts[6] = {"torso",      "head",      "left_hand",
                                         "right_hand", "left_foot", "right_foot"};

#define MIN_FRAMES 4                 /* Effort and Directional need differences of differences */
#define PAD_MAX 9                    /* odd-reflection padding of the filter */
#define HULL_GRID_STEPS 1073741824.0 /* hull.c's grid: 2^30 steps over the longest side */
#define AREA_BOUND_SLACK 1e-6        /* relative widening of the hull area bound */
/* Shape Flow tries affect_hull3d_bound_quick first when the last bound was below this fraction
 * of the best volume (it then usually suffices; closer, it rarely does and only adds cost) */
#define FLOW_QUICK_MARGIN 0.85

int affect_laban_index(const char *name)
{
    for (int i = 0; i < AFFECT_LABAN_N; i++)
        if (strcmp(affect_laban_names[i], name) == 0)
            return i;
    return -1;
}

void affect_laban_options_default(affect_laban_options *opt)
{
    opt->cutoff_hz = 6.0;
    opt->up_axis = 1;
    opt->missing_null = false;
    opt->hull_box = false;
    opt->time_per_second = false;
    opt->speed_floor = 0.05;
    opt->max_ratio = 100.0;
    opt->monitor = NULL;
}

/* The frame loops poll the monitor every this many frames (a few milliseconds of work). */
#define POLL_FRAMES 4096

/* True when frame t of a loop is a polling point and the caller asked to stop. */
static bool stop_at(const affect_laban_options *opt, size_t t)
{
    return t % POLL_FRAMES == 0 && affect_monitor_stopped(opt->monitor);
}

static affect_status check_options(const affect_laban_options *opt, affect_error *err)
{
    if (!(opt->cutoff_hz > 0) || !isfinite(opt->cutoff_hz))
        return affect_fail(err, AFFECT_ERR_INVALID, "cutoff_hz must be a positive number, got %g",
                           opt->cutoff_hz);
    if (opt->up_axis < 0 || opt->up_axis > 2)
        return affect_fail(err, AFFECT_ERR_INVALID, "up axis must be x, y or z");
    if (!(opt->speed_floor >= 0 && opt->speed_floor < 1))
        return affect_fail(err, AFFECT_ERR_INVALID, "speed_floor must be in [0, 1), got %g",
                           opt->speed_floor);
    if (!(opt->max_ratio >= 1) || !isfinite(opt->max_ratio))
        return affect_fail(err, AFFECT_ERR_INVALID, "max_ratio must be at least 1, got %g",
                           opt->max_ratio);
    return AFFECT_OK;
}

/* ---- filter and derivatives ---- */

/* One pass of the biquad over s[0..len) (len ≥ 2) in place, in transposed direct form II,
 * starting from the steady state of the straight line through its first two inputs: for a
 * line x[n] = x0 + d·n a filter of unit DC gain settles to y[n] = x[n] − d·τ, τ its group
 * delay at DC; choosing z1, z2 so that y[0] and y[1] take those values makes a line pass
 * with no start-up transient (and a constant, d = 0, too). */
static void biquad_pass(double *s, size_t len, double b0, double b1, double b2, double a1,
                        double a2, bool backward)
{
    double x0 = backward ? s[len - 1] : s[0], x1 = backward ? s[len - 2] : s[1];
    double d = x1 - x0;
    double tau = 1.0 - (a1 + 2.0 * a2) / (1.0 + a1 + a2); /* b = b0·(1, 2, 1): its delay is 1 */
    double y0 = x0 - d * tau, y1 = x1 - d * tau;
    double z1 = y0 - b0 * x0;
    double z2 = y1 - b0 * x1 - b1 * x0 + a1 * y0;
    for (size_t k = 0; k < len; k++) {
        size_t i = backward ? len - 1 - k : k;
        double x = s[i];
        double y = b0 * x + z1;
        z1 = b1 * x - a1 * y + z2;
        z2 = b2 * x - a2 * y;
        s[i] = y;
    }
}
/* Second-order Butterworth low-pass coefficients (bilinear transform) for the zero-lag filter:
 * y_t = b0 x_t + b1 x_{t-1} + b2 x_{t-2} − a1 y_{t-1} − a2 y_{t-2}. */
typedef struct butter_coef {
    double b0, b1, b2, a1, a2;
} butter_coef;

static butter_coef butterworth(double fps, double cutoff_hz)
{
    double k = tan(3.14159265358979323846 * cutoff_hz / fps);
    double norm = 1.0 / (1.0 + sqrt(2.0) * k + k * k);
    butter_coef c;
    c.b0 = k * k * norm;
    c.b1 = 2.0 * c.b0;
    c.b2 = c.b0;
    c.a1 = 2.0 * (k * k - 1.0) * norm;
    c.a2 = (1.0 - sqrt(2.0) * k + k * k) * norm;
    return c;
}

void affect_lowpass(const double *x, size_t n, size_t stride, double fps, double cutoff_hz,
                    double *scratch, double *out)
{
    if (n < 2 || !(cutoff_hz < fps / 2.0) || !(cutoff_hz > 0)) {
        if (out != x)
            for (size_t i = 0; i < n; i++)
                out[i * stride] = x[i * stride];
        return;
    }
    butter_coef bc = butterworth(fps, cutoff_hz);
    double b0 = bc.b0, b1 = bc.b1, b2 = bc.b2, a1 = bc.a1, a2 = bc.a2;
    size_t pad = n - 1 < PAD_MAX ? n - 1 : PAD_MAX;
    size_t len = n + 2 * pad;
    double first = x[0], last = x[(n - 1) * stride];
    for (size_t i = 0; i < pad; i++) {
        scratch[i] = 2.0 * first - x[(pad - i) * stride];
        scratch[pad + n + i] = 2.0 * last - x[(n - 2 - i) * stride];
    }
    for (size_t i = 0; i < n; i++)
        scratch[pad + i] = x[i * stride];
    biquad_pass(scratch, len, b0, b1, b2, a1, a2, false);
    biquad_pass(scratch, len, b0, b1, b2, a1, a2, true);
    for (size_t i = 0; i < n; i++)
        out[i * stride] = scratch[pad + i];
}

/* d[t] = (x[t+1] − x[t−1]) · fps / 2 inside, one-sided at the ends; T × 3 row-major. */
static void gradient3(const double *x, uint32_t n, double fps, double *d)
{
    for (int a = 0; a < 3; a++) {
        if (n == 1) {
            d[a] = 0;
            continue;
        }
        d[a] = (x[3 + a] - x[a]) * fps;
        d[(size_t)(n - 1) * 3 + a] =
            (x[(size_t)(n - 1) * 3 + a] - x[(size_t)(n - 2) * 3 + a]) * fps;
        for (uint32_t t = 1; t + 1 < n; t++)
            d[(size_t)t * 3 + a] =
                (x[(size_t)(t + 1) * 3 + a] - x[(size_t)(t - 1) * 3 + a]) * fps * 0.5;
    }
}

/* out = lowpass(gradient(x)), T × 3. */
static void derivative3(const double *x, uint32_t n, double fps, double cutoff, double *scratch,
                        double *out)
{
    gradient3(x, n, fps, out);
    for (int a = 0; a < 3; a++)
        affect_lowpass(out + a, n, 3, fps, cutoff, scratch, out + a);
}

/* ---- parts ---- */

static affect_status missing_role(const char *role, affect_error *err)
{
    return affect_fail(err, AFFECT_ERR_MISSING, "no joint has the %s role", role);
}

affect_status affect_part_resolve(const affect_motion *m, const affect_roles *roles,
                                  const char *name, affect_part *part, affect_error *err)
{
    memset(part, 0, sizeof *part);
    part->name = name;
    if (strcmp(name, "torso") == 0) {
        static const affect_role torso[3] = {AFFECT_ROLE_PELVIS, AFFECT_ROLE_SPINE,
                                             AFFECT_ROLE_CHEST};
        for (int i = 0; i < 3; i++)
            if (roles->joint[torso[i]] >= 0)
                part->joints[part->n_joints++] = roles->joint[torso[i]];
        if (part->n_joints == 0)
            return affect_fail(err, AFFECT_ERR_MISSING,
                               "no joint has the pelvis, spine or chest role (the torso)");
        return AFFECT_OK;
    }
    static const struct {
        const char *part;
        affect_role role;
    } simple[] = {{"head", AFFECT_ROLE_HEAD},
                  {"left_hand", AFFECT_ROLE_LEFT_HAND},
                  {"right_hand", AFFECT_ROLE_RIGHT_HAND},
                  {"left_foot", AFFECT_ROLE_LEFT_FOOT},
                  {"right_foot", AFFECT_ROLE_RIGHT_FOOT}};
    for (size_t i = 0; i < sizeof simple / sizeof simple[0]; i++)
        if (strcmp(name, simple[i].part) == 0) {
            if (roles->joint[simple[i].role] < 0)
                return missing_role(name, err);
            part->joints[part->n_joints++] = roles->joint[simple[i].role];
            return AFFECT_OK;
        }
    int32_t j = affect_motion_find_joint(m, name);
    if (j < 0)
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "\"%.64s\" is neither a part (all, torso, head, left_hand, right_hand, "
                           "left_foot, right_foot) nor a joint of the motion",
                           name);
    part->joints[part->n_joints++] = j;
    return AFFECT_OK;
}

affect_status affect_parts_all(const affect_motion *m, const affect_roles *roles,
                               affect_part parts[6], affect_error *err)
{
    for (int i = 0; i < 6; i++) {
        affect_status st = affect_part_resolve(m, roles, all_parts[i], &parts[i], err);
        if (st)
            return st;
    }
    return AFFECT_OK;
}

static void part_positions(const affect_motion *m, const affect_part *part, double *pos)
{
    double inv = 1.0 / part->n_joints;
    for (uint32_t t = 0; t < m->n_frames; t++) {
        double c[3] = {0, 0, 0};
        for (uint32_t i = 0; i < part->n_joints; i++) {
            const float *p = affect_motion_at(m, t, (uint32_t)part->joints[i]);
            c[0] += p[0], c[1] += p[1], c[2] += p[2];
        }
        for (int a = 0; a < 3; a++)
            pos[(size_t)t * 3 + a] = part->n_joints == 1 ? c[a] : c[a] * inv;
    }
}

affect_status affect_kinematics_compute(const affect_motion *m, const affect_part *part,
                                        const affect_laban_options *opt, affect_kinematics *k,
                                        affect_error *err)
{
    memset(k, 0, sizeof *k);
    uint32_t n = m->n_frames;
    size_t len;
    if (!affect_mul_size(n, 12, &len))
        return affect_fail(err, AFFECT_ERR_RANGE, "motion too long");
    double *block = affect_malloc_array(len + n + 2 * PAD_MAX, sizeof *block);
    if (!block)
        return affect_nomem(err);
    k->n_frames = n;
    k->fps = m->fps;
    k->pos = block;
    k->vel = block + (size_t)n * 3;
    k->acc = block + (size_t)n * 6;
    k->jerk = block + (size_t)n * 9;
    double *scratch = block + (size_t)n * 12;
    part_positions(m, part, k->pos);
    derivative3(k->pos, n, m->fps, opt->cutoff_hz, scratch, k->vel);
    derivative3(k->vel, n, m->fps, opt->cutoff_hz, scratch, k->acc);
    derivative3(k->acc, n, m->fps, opt->cutoff_hz, scratch, k->jerk);
    return AFFECT_OK;
}

void affect_kinematics_free(affect_kinematics *k)
{
    affect_free(k->pos);
    memset(k, 0, sizeof *k);
}

/* ---- Effort from kinematics ---- */

static double norm3(const double *v)
{
    return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

static double dist3(const double *a, const double *b)
{
    double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return norm3(d);
}

/* The series the Effort reductions read: part k's velocity and acceleration at frame t are
 * vel[k] + t·stride and acc[k] + t·stride (3 doubles each), so the reductions run on the
 * kinematics of affect_kinematics_compute (stride 3) and on the frame-interleaved series of
 * affect_laban_vector (stride 3 × parts) alike, with the same arithmetic. */
typedef struct effort_series {
    uint32_t n_frames, n_parts;
    size_t stride;
    double fps;
    const double *vel[6], *acc[6];
} effort_series;

static effort_series series_of(const affect_kinematics *ks, uint32_t n)
{
    effort_series s = {ks[0].n_frames, n, 3, ks[0].fps, {NULL}, {NULL}};
    for (uint32_t k = 0; k < n; k++) {
        s.vel[k] = ks[k].vel;
        s.acc[k] = ks[k].acc;
    }
    return s;
}

/* max over frames of Σ_k f(x_k(t)), x = vel with f = ‖·‖² (Weight Q1) or acc with f = ‖·‖
 * (Time Q1). */
static double peak_sum(const effort_series *s, bool of_acc)
{
    double best = 0;
    for (uint32_t t = 0; t < s->n_frames; t++) {
        double sum = 0;
        for (uint32_t k = 0; k < s->n_parts; k++) {
            const double *x = (of_acc ? s->acc[k] : s->vel[k]) + (size_t)t * s->stride;
            double sq = x[0] * x[0] + x[1] * x[1] + x[2] * x[2];
            sum += of_acc ? sqrt(sq) : sq;
        }
        if (sum > best)
            best = sum;
    }
    return best;
}

static double weight_q1(const effort_series *s)
{
    return peak_sum(s, false);
}

static double weight_q2(const effort_series *s)
{
    double best = 0;
    for (uint32_t t = 1; t < s->n_frames; t++) {
        double d = 0;
        for (uint32_t k = 0; k < s->n_parts; k++) {
            double drop = (norm3(s->vel[k] + (size_t)(t - 1) * s->stride) -
                           norm3(s->vel[k] + (size_t)t * s->stride)) *
                          s->fps;
            if (drop > 0)
                d += drop;
        }
        if (d > best)
            best = d;
    }
    return best;
}

static double time_q1(const effort_series *s)
{
    return peak_sum(s, true);
}

/* Σ_k Σ_{t≥1} ‖x_k(t) − x_k(t−1)‖ · fps for x = vel (Time Q2) or acc (Flow). */
static double accumulated(const effort_series *s, bool of_acc)
{
    double sum = 0;
    for (uint32_t k = 0; k < s->n_parts; k++) {
        const double *x = of_acc ? s->acc[k] : s->vel[k];
        for (uint32_t t = 1; t < s->n_frames; t++)
            sum += dist3(x + (size_t)t * s->stride, x + (size_t)(t - 1) * s->stride) * s->fps;
    }
    return sum;
}

/* ---- the six parts' kinematics at once (affect_laban_vector) ---- */

#define MAX_CHANNELS 18 /* six parts × three axes */

/* affect_lowpass of c channels interleaved frame by frame (value of channel j at frame i in
 * x[i·c + j]), in place; x has PAD_MAX rows of room before frame 0 and after frame n − 1 for the
 * padding. Each channel gets exactly affect_lowpass's arithmetic (the same padding, the same
 * two passes, the same operations in the same order), so the results are the same bits; the
 * channels only run in lockstep, which overlaps the filter recursions whose latency bounds a
 * single channel (and lets the compiler vectorise across channels). */
static void lowpass_channels(double *x, size_t n, size_t c, double fps, double cutoff_hz)
{
    if (n < 2 || !(cutoff_hz < fps / 2.0) || !(cutoff_hz > 0))
        return;
    butter_coef bc = butterworth(fps, cutoff_hz);
    double b0 = bc.b0, b1 = bc.b1, b2 = bc.b2, a1 = bc.a1, a2 = bc.a2;
    size_t pad = n - 1 < PAD_MAX ? n - 1 : PAD_MAX;
    size_t len = n + 2 * pad;
    double *s = x - pad * c; /* row i of the padded series: s + i·c */
    for (size_t i = 0; i < pad; i++)
        for (size_t j = 0; j < c; j++) {
            s[i * c + j] = 2.0 * x[j] - x[(pad - i) * c + j];
            s[(pad + n + i) * c + j] = 2.0 * x[(n - 1) * c + j] - x[(n - 2 - i) * c + j];
        }
    double tau = 1.0 - (a1 + 2.0 * a2) / (1.0 + a1 + a2);
    double z1[MAX_CHANNELS], z2[MAX_CHANNELS];
    for (int pass = 0; pass < 2; pass++) {
        bool backward = pass == 1;
        /* biquad_pass's start from the steady state of the line through the first two inputs */
        const double *r0 = backward ? s + (len - 1) * c : s,
                     *r1 = backward ? s + (len - 2) * c : s + c;
        for (size_t j = 0; j < c; j++) {
            double x0 = r0[j], x1 = r1[j];
            double d = x1 - x0;
            double y0 = x0 - d * tau, y1 = x1 - d * tau;
            z1[j] = y0 - b0 * x0;
            z2[j] = y1 - b0 * x1 - b1 * x0 + a1 * y0;
        }
        for (size_t i = 0; i < len; i++) {
            double *row = s + (backward ? len - 1 - i : i) * c;
            for (size_t j = 0; j < c; j++) {
                double xi = row[j];
                double y = b0 * xi + z1[j];
                z1[j] = b1 * xi - a1 * y + z2[j];
                z2[j] = b2 * xi - a2 * y;
                row[j] = y;
            }
        }
    }
}

/* gradient3 of c interleaved channels (n ≥ 2): d[t] from x[t ± 1], the same arithmetic. */
static void gradient_channels(const double *x, size_t n, size_t c, double fps, double *d)
{
    for (size_t j = 0; j < c; j++) {
        d[j] = (x[c + j] - x[j]) * fps;
        d[(n - 1) * c + j] = (x[(n - 1) * c + j] - x[(n - 2) * c + j]) * fps;
    }
    for (size_t t = 1; t + 1 < n; t++)
        for (size_t j = 0; j < c; j++)
            d[t * c + j] = (x[(t + 1) * c + j] - x[(t - 1) * c + j]) * fps * 0.5;
}

/* Row t of the parts' positions (each part's centroid, as part_positions computes it) into
 * row: part k at row[3 · slot[k]]. */
static void centroid_row(const affect_motion *m, const affect_part *parts, const bool have[6],
                         const uint32_t slot[6], size_t t, double *row)
{
    for (int k = 0; k < 6; k++) {
        if (!have[k])
            continue;
        const affect_part *part = &parts[k];
        double inv = 1.0 / part->n_joints, p3[3] = {0, 0, 0};
        for (uint32_t i = 0; i < part->n_joints; i++) {
            const float *p = affect_motion_at(m, (uint32_t)t, (uint32_t)part->joints[i]);
            p3[0] += p[0], p3[1] += p[1], p3[2] += p[2];
        }
        for (int a = 0; a < 3; a++)
            row[3 * slot[k] + (size_t)a] = part->n_joints == 1 ? p3[a] : p3[a] * inv;
    }
}

/* Velocity and acceleration of the parts k with have[k] (as affect_kinematics_compute computes
 * them, to the bit; the jerk, which no component of the vector uses, is skipped) in one block
 * (*block, freed by the caller), all parts' channels interleaved frame by frame so that one
 * pass filters them all; s->vel[k] and s->acc[k] point at part k's series (stride 3 × the
 * number of parts present). The positions are not stored: the velocity's central differences
 * (gradient_channels' arithmetic) read them from a ring of three rows, which keeps the block
 * a third smaller (on a long motion the fresh pages of the block, not the arithmetic, are the
 * cost). m->n_frames ≥ 2. */
static affect_status vector_kinematics(const affect_motion *m, const affect_part *parts,
                                       const bool have[6], const affect_laban_options *opt,
                                       double **block, effort_series *s, affect_error *err)
{
    size_t n = m->n_frames, c = 0, rows, len, total;
    uint32_t slot[6];
    for (int k = 0; k < 6; k++)
        if (have[k]) {
            slot[k] = (uint32_t)(c / 3);
            c += 3;
        }
    if (!affect_add_size(n, 2 * PAD_MAX, &rows) || !affect_mul_size(rows, c, &len) ||
        !affect_mul_size(len, 2, &total))
        return affect_fail(err, AFFECT_ERR_RANGE, "motion too long");
    double *b = affect_malloc_array(total, sizeof *b);
    if (!b)
        return affect_nomem(err);
    double *vel = b + PAD_MAX * c, *acc = vel + len, ring[3][MAX_CHANNELS];
    double fps = m->fps;
    centroid_row(m, parts, have, slot, 0, ring[0]);
    centroid_row(m, parts, have, slot, 1, ring[1]);
    for (size_t j = 0; j < c; j++)
        vel[j] = (ring[1][j] - ring[0][j]) * fps;
    for (size_t t = 1; t + 1 < n; t++) {
        if (stop_at(opt, t)) {
            affect_free(b);
            return affect_monitor_check(opt->monitor, err);
        }
        const double *lo = ring[(t - 1) % 3];
        double *hi = ring[(t + 1) % 3];
        centroid_row(m, parts, have, slot, t + 1, hi);
        for (size_t j = 0; j < c; j++)
            vel[t * c + j] = (hi[j] - lo[j]) * fps * 0.5;
    }
    for (size_t j = 0; j < c; j++)
        vel[(n - 1) * c + j] = (ring[(n - 1) % 3][j] - ring[(n - 2) % 3][j]) * fps;
    lowpass_channels(vel, n, c, m->fps, opt->cutoff_hz);
    gradient_channels(vel, n, c, m->fps, acc);
    lowpass_channels(acc, n, c, m->fps, opt->cutoff_hz);
    affect_status st = affect_monitor_check(opt->monitor, err);
    if (st) {
        affect_free(b);
        return st;
    }
    memset(s, 0, sizeof *s);
    s->n_frames = (uint32_t)n;
    s->n_parts = (uint32_t)(c / 3);
    s->stride = c;
    s->fps = m->fps;
    for (int k = 0; k < 6; k++)
        if (have[k]) {
            s->vel[k] = vel + 3 * (size_t)slot[k];
            s->acc[k] = acc + 3 * (size_t)slot[k];
        }
    *block = b;
    return AFFECT_OK;
}

static double space_q2(const affect_kinematics *ks, uint32_t n, double max_ratio)
{
    double mean = 0;
    for (uint32_t k = 0; k < n; k++) {
        uint32_t T = ks[k].n_frames;
        double path = 0;
        for (uint32_t t = 1; t < T; t++)
            path += dist3(ks[k].pos + (size_t)t * 3, ks[k].pos + (size_t)(t - 1) * 3);
        double disp = dist3(ks[k].pos + (size_t)(T - 1) * 3, ks[k].pos);
        double ratio = 1.0; /* a part that does not move is perfectly direct */
        if (path > 0)
            ratio = path / fmax(disp, path / max_ratio);
        mean += ratio;
    }
    return mean / n;
}

/* Peaks of s(t) = v_hand(t) · v_torso(t) counted with hysteresis: a peak is a rise of at least
 * h above the last trough followed by a fall of at least h, h = 10 % of the range of s, so
 * ripples of a noisy product do not count. Binned: 0–1 peaks → 1, 2–3 → 2, …, ≥ 8 → 5. */
static double space_q1(const affect_kinematics *hand, const affect_kinematics *torso)
{
    uint32_t T = hand->n_frames, peaks = 0;
    double lo = INFINITY, hi = -INFINITY;
    for (uint32_t t = 0; t < T; t++) {
        const double *a = hand->vel + (size_t)t * 3, *b = torso->vel + (size_t)t * 3;
        double s = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        lo = fmin(lo, s);
        hi = fmax(hi, s);
    }
    double h = 0.1 * (hi - lo);
    bool rising = true;
    double trough = INFINITY, top = -INFINITY;
    for (uint32_t t = 0; t < T && h > 0; t++) {
        const double *a = hand->vel + (size_t)t * 3, *b = torso->vel + (size_t)t * 3;
        double s = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        if (rising) {
            trough = fmin(trough, s);
            top = fmax(top, s);
            if (top - trough >= h && top - s >= h) { /* rose enough, then fell enough */
                peaks++;
                rising = false;
                trough = s;
            }
        } else {
            trough = fmin(trough, s);
            if (s - trough >= h) { /* a new rise begins */
                rising = true;
                top = s;
            }
        }
    }
    uint32_t bin = 1 + peaks / 2;
    return bin > 5 ? 5 : bin;
}

/* Computes the kinematics of n parts into ks (freed by the caller with free_all). */
static affect_status kinematics_all(const affect_motion *m, const affect_part *parts, uint32_t n,
                                    const affect_laban_options *opt, affect_kinematics *ks,
                                    affect_error *err)
{
    for (uint32_t k = 0; k < n; k++)
        memset(&ks[k], 0, sizeof ks[k]);
    for (uint32_t k = 0; k < n; k++) {
        affect_status st = affect_kinematics_compute(m, &parts[k], opt, &ks[k], err);
        if (st || (st = affect_monitor_check(opt->monitor, err)))
            return st;
    }
    return AFFECT_OK;
}

static void free_all(affect_kinematics *ks, uint32_t n)
{
    for (uint32_t k = 0; k < n; k++)
        affect_kinematics_free(&ks[k]);
}

static affect_status check_effort_input(const affect_motion *m, uint32_t n,
                                        const affect_laban_options *opt, const char *what,
                                        affect_error *err)
{
    affect_status st = check_options(opt, err);
    if (st)
        return st;
    if (n < 1 || n > 6)
        return affect_fail(err, AFFECT_ERR_INVALID, "%s needs 1 to 6 parts, got %u", what, n);
    if (m->n_frames < MIN_FRAMES)
        return affect_fail(err, AFFECT_ERR_RANGE, "the motion has %u frames; %s needs at least %d",
                           m->n_frames, what, MIN_FRAMES);
    return AFFECT_OK;
}

typedef enum effort_kind {
    WEIGHT_Q1,
    WEIGHT_Q2,
    TIME_Q1,
    TIME_Q2,
    FLOW,
    SPACE_Q1,
    SPACE_Q2
} effort_kind;

static double effort_value(const affect_motion *m, const affect_kinematics *ks, uint32_t n,
                           effort_kind kind, const affect_laban_options *opt)
{
    effort_series s = series_of(ks, n);
    switch (kind) {
    case WEIGHT_Q1:
        return weight_q1(&s);
    case WEIGHT_Q2:
        return weight_q2(&s);
    case TIME_Q1:
        return time_q1(&s);
    case TIME_Q2: {
        double v = accumulated(&s, false);
        return opt->time_per_second ? v / affect_motion_duration(m) : v;
    }
    case FLOW:
        return accumulated(&s, true);
    case SPACE_Q1:
        return space_q1(&ks[0], &ks[1]);
    default:
        return space_q2(ks, n, opt->max_ratio);
    }
}

static affect_status effort(const affect_motion *m, const affect_part *parts, uint32_t n,
                            effort_kind kind, const char *what, const affect_laban_options *opt,
                            double *out, affect_error *err)
{
    affect_laban_options def;
    if (!opt) {
        affect_laban_options_default(&def);
        opt = &def;
    }
    affect_status st = check_effort_input(m, n, opt, what, err);
    if (st)
        return st;
    affect_kinematics ks[6];
    st = kinematics_all(m, parts, n, opt, ks, err);
    if (!st)
        *out = effort_value(m, ks, n, kind, opt);
    free_all(ks, n);
    return st;
}

affect_status affect_laban_weight(const affect_motion *m, const affect_part *parts, uint32_t n,
                                  affect_laban_method method, const affect_laban_options *opt,
                                  double *out, affect_error *err)
{
    return effort(m, parts, n, method == AFFECT_LABAN_Q2 ? WEIGHT_Q2 : WEIGHT_Q1, "Weight", opt,
                  out, err);
}

affect_status affect_laban_time(const affect_motion *m, const affect_part *parts, uint32_t n,
                                affect_laban_method method, const affect_laban_options *opt,
                                double *out, affect_error *err)
{
    return effort(m, parts, n, method == AFFECT_LABAN_Q2 ? TIME_Q2 : TIME_Q1, "Time", opt, out,
                  err);
}

affect_status affect_laban_flow(const affect_motion *m, const affect_part *parts, uint32_t n,
                                const affect_laban_options *opt, double *out, affect_error *err)
{
    return effort(m, parts, n, FLOW, "Flow", opt, out, err);
}

affect_status affect_laban_space(const affect_motion *m, const affect_part *parts, uint32_t n,
                                 affect_laban_method method, const affect_laban_options *opt,
                                 double *out, affect_error *err)
{
    if (method == AFFECT_LABAN_Q1 && n != 2)
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "Space (peaks) needs a hand and the torso, got %u parts", n);
    return effort(m, parts, n, method == AFFECT_LABAN_Q1 ? SPACE_Q1 : SPACE_Q2, "Space", opt, out,
                  err);
}

/* ---- Shape ---- */

affect_status affect_laban_shape_directional(const affect_motion *m, const affect_part *hand,
                                             const affect_laban_options *opt, double *out,
                                             affect_error *err)
{
    affect_laban_options def;
    if (!opt) {
        affect_laban_options_default(&def);
        opt = &def;
    }
    affect_status st = check_effort_input(m, 1, opt, "Shape Directional", err);
    if (st)
        return st;
    uint32_t n = m->n_frames;
    /* the positions (3n), then the path's two channels' derivatives, each with PAD_MAX rows of
     * room for the filter's padding before and after (lowpass_channels) */
    size_t rows = (size_t)n + 2 * PAD_MAX;
    double *block = affect_malloc_array((size_t)n * 3 + 4 * rows, sizeof *block);
    if (!block)
        return affect_nomem(err);
    double *pos = block, *d1 = block + (size_t)n * 3 + 2 * PAD_MAX, *d2 = d1 + 2 * rows;
    part_positions(m, hand, pos);

    /* principal axes of the path */
    double mean[3] = {0, 0, 0}, cov[9] = {0}, w[3];
    for (uint32_t t = 0; t < n; t++)
        for (int a = 0; a < 3; a++)
            mean[a] += pos[(size_t)t * 3 + a];
    for (int a = 0; a < 3; a++)
        mean[a] /= n;
    for (uint32_t t = 0; t < n; t++)
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++)
                cov[a * 3 + b] +=
                    (pos[(size_t)t * 3 + a] - mean[a]) * (pos[(size_t)t * 3 + b] - mean[b]);
    lapack_int info;
    AFFECT_BLAS(info = LAPACKE_dsyev(LAPACK_ROW_MAJOR, 'V', 'U', 3, cov, 3, w));
    if (info != 0) {
        affect_free(block);
        return info == LAPACK_WORK_MEMORY_ERROR || info == LAPACK_TRANSPOSE_MEMORY_ERROR
                   ? affect_nomem(err)
                   : affect_fail(err, AFFECT_ERR_INVALID,
                                 "eigen-decomposition failed (LAPACK info %d)", (int)info);
    }
    /* eigenvalues ascend: columns 2 and 1 are the two main axes; project onto them (x, y),
     * two interleaved channels written over the positions (row t is read before rows ≤ t are
     * written) */
    double *xy = pos;
    for (uint32_t t = 0; t < n; t++) {
        double c[3] = {pos[(size_t)t * 3] - mean[0], pos[(size_t)t * 3 + 1] - mean[1],
                       pos[(size_t)t * 3 + 2] - mean[2]};
        double x = c[0] * cov[2] + c[1] * cov[5] + c[2] * cov[8];
        double y = c[0] * cov[1] + c[1] * cov[4] + c[2] * cov[7];
        xy[(size_t)t * 2] = x;
        xy[(size_t)t * 2 + 1] = y;
    }
    /* the derivatives of both channels in lockstep: per channel the arithmetic of gradient3
     * and affect_lowpass (derivative3), so the same bits */
    gradient_channels(xy, n, 2, m->fps, d1);
    lowpass_channels(d1, n, 2, m->fps, opt->cutoff_hz);
    gradient_channels(d1, n, 2, m->fps, d2);
    lowpass_channels(d2, n, 2, m->fps, opt->cutoff_hz);
    double peak = 0, *speeds = pos; /* the path is no longer needed */
    for (uint32_t t = 0; t < n; t++) {
        double v = hypot(d1[(size_t)t * 2], d1[(size_t)t * 2 + 1]);
        speeds[t] = v;
        peak = v > peak ? v : peak; /* fmax(peak, v), NaN too, without the libm call */
    }
    double sum = 0;
    uint32_t used = 0;
    for (uint32_t t = 0; t < n && peak > 0; t++) {
        double xd = d1[(size_t)t * 2], yd = d1[(size_t)t * 2 + 1];
        double xdd = d2[(size_t)t * 2], ydd = d2[(size_t)t * 2 + 1];
        double speed = speeds[t];
        if (speed <= 0 || speed < opt->speed_floor * peak)
            continue;
        sum += fabs(xdd * yd - ydd * xd) / (speed * speed * speed);
        used++;
    }
    *out = used ? sum / used : 0.0;
    affect_free(block);
    return affect_monitor_check(opt->monitor, err);
}

/* Joints the body hull uses: all but the pelvis's ancestors (a reference root such as the
 * corpus's joint_Root stays at the origin while the body walks away). */
static uint32_t body_joints(const affect_motion *m, int32_t pelvis, int32_t *out)
{
    uint32_t n = 0;
    for (uint32_t j = 0; j < m->n_joints; j++) {
        bool ancestor = false;
        for (int32_t p = pelvis >= 0 ? m->parents[pelvis] : -1, guard = 0;
             p >= 0 && guard <= (int32_t)m->n_joints; p = m->parents[p], guard++)
            if (p == (int32_t)j)
                ancestor = true;
        if (!ancestor)
            out[n++] = (int32_t)j;
    }
    return n;
}

/* An upper bound of what affect_hull_area_2d returns for frame t's joints projected on axes
 * (a, b): the area of their bounding octagon (the box cut by the four diagonal lines x ± y =
 * const through the extreme points, which contains the hull), widened for hull.c's grid (each
 * point moves by at most half a step, len / 2^30, per axis: the area grows by at most
 * step · (w_a + w_b) + step²; twice that is used) and for rounding (a relative 1e-6, far
 * beyond the few units of 2^-53 of either side). Positions are finite (validated). */
static double area_bound_2d(const affect_motion *m, uint32_t t, const int32_t *joints, uint32_t nb,
                            int a, int b)
{
    if (nb < 3)
        return 0;
    const float *p0 = affect_motion_at(m, t, (uint32_t)joints[0]);
    double x0 = p0[a], x1 = x0, y0 = p0[b], y1 = y0, u0 = x0 + y0, u1 = u0, w0 = x0 - y0, w1 = w0;
    for (uint32_t i = 1; i < nb; i++) {
        const float *p = affect_motion_at(m, t, (uint32_t)joints[i]);
        double x = p[a], y = p[b], u = x + y, w = x - y;
        x0 = x < x0 ? x : x0;
        x1 = x > x1 ? x : x1;
        y0 = y < y0 ? y : y0;
        y1 = y > y1 ? y : y1;
        u0 = u < u0 ? u : u0;
        u1 = u > u1 ? u : u1;
        w0 = w < w0 ? w : w0;
        w1 = w > w1 ? w : w1;
    }
    double wa = x1 - x0, wb = y1 - y0;
    /* the corner triangles cut off the box (legs ≥ 0 up to rounding; they do not overlap,
     * each cut passing through a point of the set) */
    double c1 = u0 - (x0 + y0), c2 = (x1 + y1) - u1, c3 = (x1 - y0) - w1, c4 = w0 - (x0 - y1);
    c1 = c1 > 0 ? c1 : 0, c2 = c2 > 0 ? c2 : 0, c3 = c3 > 0 ? c3 : 0, c4 = c4 > 0 ? c4 : 0;
    double oct = wa * wb - 0.5 * (c1 * c1 + c2 * c2 + c3 * c3 + c4 * c4);
    double step = (wa > wb ? wa : wb) / HULL_GRID_STEPS;
    return (oct + 2.0 * step * (wa + wb) + 4.0 * step * step) * (1.0 + AREA_BOUND_SLACK);
}

affect_status affect_laban_shape_shaping(const affect_motion *m, const affect_roles *roles,
                                         const affect_laban_options *opt, double out[3],
                                         affect_error *err)
{
    affect_laban_options def;
    if (!opt) {
        affect_laban_options_default(&def);
        opt = &def;
    }
    affect_status st = check_options(opt, err);
    if (st)
        return st;
    affect_part torso;
    st = affect_part_resolve(m, roles, "torso", &torso, err);
    if (st)
        return st;
    int u = opt->up_axis, a = (u + 1) % 3, b = (u + 2) % 3;

    /* forward = lateral × up in the first frame, horizontal and unit length */
    double lat[3];
    if (!affect_roles_lateral(m, roles, 0, lat))
        return affect_fail(err, AFFECT_ERR_MISSING,
                           "no joints have the left_hip/right_hip (or left_shoulder/"
                           "right_shoulder) roles (the sagittal direction)");
    double up[3] = {0, 0, 0}, fwd[3];
    up[u] = 1;
    fwd[0] = lat[1] * up[2] - lat[2] * up[1];
    fwd[1] = lat[2] * up[0] - lat[0] * up[2];
    fwd[2] = lat[0] * up[1] - lat[1] * up[0];
    double fn = norm3(fwd);
    if (!(fn > 0))
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "the left and right hips (or shoulders) coincide horizontally in the "
                           "first frame");
    for (int i = 0; i < 3; i++)
        fwd[i] /= fn;

    uint32_t n = m->n_frames;
    double *block = affect_malloc_array((size_t)n * 3 + 6 * (size_t)m->n_joints, sizeof *block);
    int32_t *joints = affect_malloc_array(m->n_joints, sizeof *joints);
    if (!block || !joints) {
        affect_free(block);
        affect_free(joints);
        return affect_nomem(err);
    }
    double *pos = block, *xy = block + (size_t)n * 3, *scratch = xy + 2 * (size_t)m->n_joints;
    part_positions(m, &torso, pos);
    double vertical = 0, sagittal = 0, horizontal = 0;
    for (uint32_t t = 0; t < n; t++) {
        const double *p = pos + (size_t)t * 3;
        double d[3] = {p[0] - pos[0], p[1] - pos[1], p[2] - pos[2]};
        double dv = fabs(d[u]), ds = fabs(d[0] * fwd[0] + d[1] * fwd[1] + d[2] * fwd[2]);
        vertical = dv > vertical ? dv : vertical; /* fmax, NaN too, without the libm call */
        sagittal = ds > sagittal ? ds : sagittal;
    }
    uint32_t nb = body_joints(m, roles->joint[AFFECT_ROLE_PELVIS], joints);
    /* the largest hull area: every frame's area is bounded first (area_bound_2d); the frame
     * of the largest bound is taken first, then only the frames whose bound exceeds the best
     * area so far (the others cannot change the maximum, so the result is the same) */
    double *bound = pos; /* the torso's positions are no longer needed */
    uint32_t first = 0;
    for (uint32_t t = 0; t < n && !stop_at(opt, t); t++) {
        bound[t] = area_bound_2d(m, t, joints, nb, a, b);
        first = bound[t] > bound[first] ? t : first;
    }
    for (uint32_t k = 0; k <= n && !stop_at(opt, k); k++) {
        uint32_t t = k == 0 ? first : k - 1;
        if ((k > 0 && t == first) || !(bound[t] > horizontal))
            continue;
        for (uint32_t i = 0; i < nb; i++) {
            const float *p = affect_motion_at(m, t, (uint32_t)joints[i]);
            xy[2 * i] = p[a];
            xy[2 * i + 1] = p[b];
        }
        double area = affect_hull_area_2d(xy, nb, scratch);
        horizontal = area > horizontal ? area : horizontal; /* fmax, NaN too */
    }
    out[0] = vertical;
    out[1] = sagittal;
    out[2] = horizontal;
    affect_free(block);
    affect_free(joints);
    return affect_monitor_check(opt->monitor, err);
}

/* Frame t's body joints as doubles (xyz, 3 · nb). */
static void gather_body(const affect_motion *m, uint32_t t, const int32_t *joints, uint32_t nb,
                        double *xyz)
{
    for (uint32_t i = 0; i < nb; i++) {
        const float *p = affect_motion_at(m, t, (uint32_t)joints[i]);
        xyz[3 * i] = p[0], xyz[3 * i + 1] = p[1], xyz[3 * i + 2] = p[2];
    }
}

/* The volume of the bounding box of nb ≥ 1 points (xyz). Positions are validated finite:
 * plain comparisons (gcc does not inline fmin and fmax without fast math). */
static double box_volume(const double *xyz, uint32_t nb)
{
    double lo[3] = {xyz[0], xyz[1], xyz[2]}, hi[3] = {xyz[0], xyz[1], xyz[2]};
    for (uint32_t i = 1; i < nb; i++)
        for (int a = 0; a < 3; a++) {
            double c = xyz[3 * i + a];
            lo[a] = c < lo[a] ? c : lo[a];
            hi[a] = c > hi[a] ? c : hi[a];
        }
    return (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
}

/* box_volume of frame t's body joints, read from the motion without gathering them (the
 * floats widen to the same doubles). */
static double frame_box_volume(const affect_motion *m, uint32_t t, const int32_t *joints,
                               uint32_t nb)
{
    const float *p0 = affect_motion_at(m, t, (uint32_t)joints[0]);
    double lo[3] = {p0[0], p0[1], p0[2]}, hi[3] = {p0[0], p0[1], p0[2]};
    for (uint32_t i = 1; i < nb; i++) {
        const float *p = affect_motion_at(m, t, (uint32_t)joints[i]);
        for (int a = 0; a < 3; a++) {
            double c = p[a];
            lo[a] = c < lo[a] ? c : lo[a];
            hi[a] = c > hi[a] ? c : hi[a];
        }
    }
    return (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
}

/* Shape Flow with the roles' pelvis (for the body joints). */
static affect_status shape_flow(const affect_motion *m, int32_t pelvis,
                                const affect_laban_options *opt, double *out, affect_error *err)
{
    int32_t *joints = affect_malloc_array(m->n_joints, sizeof *joints);
    double *xyz = affect_malloc_array(m->n_joints, 3 * sizeof *xyz);
    affect_hull3d *hull = opt->hull_box ? NULL : affect_hull3d_new(m->n_joints);
    affect_status st = AFFECT_OK;
    if (!joints || !xyz || (!opt->hull_box && !hull)) {
        st = affect_nomem(err);
        goto done;
    }
    uint32_t nb = body_joints(m, pelvis, joints);
    double best = 0;
    if (opt->hull_box) {
        for (uint32_t t = 0; t < m->n_frames && !stop_at(opt, t); t++) {
            gather_body(m, t, joints, nb, xyz);
            double v = box_volume(xyz, nb);
            best = v > best ? v : best;
        }
    } else {
        /* every frame's hull is bounded first from the last one built (affect_hull3d_bound)
         * and built only when the bound does not rule out that it beats the best so far; the
         * frame of the largest bounding box goes first, a good guess of the maximum */
        uint32_t first = 0;
        double box_best = -1, last = INFINITY;
        for (uint32_t t = 0; t < m->n_frames && !stop_at(opt, t); t++) {
            double v = frame_box_volume(m, t, joints, nb);
            first = v > box_best ? t : first;
            box_best = v > box_best ? v : box_best;
        }
        for (uint32_t k = 0; k <= m->n_frames && m->n_frames > 0 && !stop_at(opt, k); k++) {
            uint32_t t = k == 0 ? first : k - 1;
            if (k > 0 && t == first)
                continue;
            gather_body(m, t, joints, nb, xyz);
            if (last < FLOW_QUICK_MARGIN * best) {
                last = affect_hull3d_bound_quick(hull, xyz, nb);
                if (last < best)
                    continue; /* this frame's hull cannot beat the best */
            }
            last = affect_hull3d_bound(hull, xyz, nb);
            if (last < best)
                continue;
            double v = affect_hull3d_volume(hull, xyz, nb);
            best = v > best ? v : best;
        }
    }
    *out = best;
    st = affect_monitor_check(opt->monitor, err);
done:
    affect_hull3d_free(hull);
    affect_free(xyz);
    affect_free(joints);
    return st;
}

affect_status affect_laban_shape_flow(const affect_motion *m, const affect_laban_options *opt,
                                      double *out, affect_error *err)
{
    affect_laban_options def;
    if (!opt) {
        affect_laban_options_default(&def);
        opt = &def;
    }
    affect_status st = check_options(opt, err);
    if (st)
        return st;
    affect_roles roles;
    affect_roles_resolve(m, &roles);
    return shape_flow(m, roles.joint[AFFECT_ROLE_PELVIS], opt, out, err);
}

/* ---- all 27 ---- */

/* The vector's 21 Effort values in one pass over the frames: for each part k present (have[k],
 * in es's order) Weight (weight_q1), Time (time_q1) and Flow (accumulated of the acceleration),
 * and with all six also their combinations, with exactly those functions' arithmetic: every
 * norm is computed once and shared, the sums over parts run in part order, each part's Flow
 * sums its frames in order from 0, and the combined Flow continues one sum through the parts'
 * terms in turn (kept in a block of n per part), as accumulated does. */
static affect_status effort_vector(const effort_series *es, const bool have[6], bool all,
                                   const affect_laban_options *opt, double out[AFFECT_LABAN_N],
                                   affect_error *err)
{
    uint32_t n = es->n_frames, np = es->n_parts, slot[6], kk = 0;
    double *terms = affect_malloc_array(n, np * sizeof *terms);
    if (!terms)
        return affect_nomem(err);
    for (uint32_t k = 0; k < 6; k++)
        if (have[k])
            slot[kk++] = k;
    double wmax[6] = {0}, tmax[6] = {0}, fsum[6] = {0}, wall = 0, tall = 0;
    for (uint32_t t = 0; t < n; t++) {
        double ws = 0, ts = 0;
        for (uint32_t j = 0; j < np; j++) {
            const double *v = es->vel[slot[j]] + (size_t)t * es->stride;
            const double *a = es->acc[slot[j]] + (size_t)t * es->stride;
            double v2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
            double an = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
            ws += v2, ts += an;
            wmax[j] = v2 > wmax[j] ? v2 : wmax[j];
            tmax[j] = an > tmax[j] ? an : tmax[j];
            if (t > 0) {
                double term = dist3(a, a - es->stride) * es->fps;
                terms[(size_t)j * n + t] = term;
                fsum[j] += term;
            }
        }
        wall = ws > wall ? ws : wall;
        tall = ts > tall ? ts : tall;
    }
    for (uint32_t j = 0; j < np; j++) {
        out[IDX_WEIGHT + 1 + slot[j]] = wmax[j];
        out[IDX_TIME + 1 + slot[j]] = tmax[j];
        out[IDX_FLOW + 1 + slot[j]] = fsum[j];
    }
    if (all) {
        double sum = 0;
        for (uint32_t j = 0; j < np; j++)
            for (uint32_t t = 1; t < n; t++)
                sum += terms[(size_t)j * n + t];
        out[IDX_WEIGHT] = wall;
        out[IDX_TIME] = tall;
        out[IDX_FLOW] = sum;
    }
    affect_free(terms);
    return affect_monitor_check(opt->monitor, err);
}

/* Runs one Shape step; with missing_null a missing role or short motion gives NaN. */
static affect_status soft(affect_status st, const affect_laban_options *opt, double *dst,
                          uint32_t n)
{
    if (st && opt->missing_null && (st == AFFECT_ERR_MISSING || st == AFFECT_ERR_RANGE)) {
        for (uint32_t i = 0; i < n; i++)
            dst[i] = NAN;
        return AFFECT_OK;
    }
    return st;
}

affect_status affect_laban_vector(const affect_motion *m, const affect_roles *roles,
                                  const affect_laban_options *opt, double out[AFFECT_LABAN_N],
                                  affect_error *err)
{
    affect_laban_options def;
    if (!opt) {
        affect_laban_options_default(&def);
        opt = &def;
    }
    affect_status st = check_options(opt, err);
    if (st)
        return st;
    for (int i = 0; i < AFFECT_LABAN_N; i++)
        out[i] = NAN;

    /* Effort: the six parts' velocities and accelerations in one block, filtered together */
    affect_part parts[6];
    effort_series es;
    double *kin = NULL;
    bool have[6] = {false, false, false, false, false, false};
    uint32_t n_have = 0;
    if (m->n_frames < MIN_FRAMES) {
        st = soft(affect_fail(err, AFFECT_ERR_RANGE,
                              "the motion has %u frames; Weight, Time and Flow need at least %d",
                              m->n_frames, MIN_FRAMES),
                  opt, out, IDX_VERTICAL);
        if (st)
            return st;
    } else {
        for (int k = 0; k < 6; k++) {
            st = affect_part_resolve(m, roles, all_parts[k], &parts[k], err);
            have[k] = st == AFFECT_OK;
            if (st && !(opt->missing_null && st == AFFECT_ERR_MISSING))
                goto done;
            st = AFFECT_OK;
            n_have += have[k];
        }
        if (n_have > 0) {
            st = vector_kinematics(m, parts, have, opt, &kin, &es, err);
            if (st)
                goto done;
        }
    }
    if (n_have > 0) {
        st = effort_vector(&es, have, n_have == 6, opt, out, err);
        if (st)
            goto done;
    }

    /* Shape */
    double shaping[3];
    st = soft(affect_laban_shape_shaping(m, roles, opt, shaping, err), opt, shaping, 3);
    if (st)
        goto done;
    memcpy(out + IDX_VERTICAL, shaping, sizeof shaping);
    st = shape_flow(m, roles->joint[AFFECT_ROLE_PELVIS], opt, &out[IDX_SHAPE_FLOW], err);
    if (st)
        goto done;
    for (int h = 0; h < 2; h++) {
        int k = 2 + h; /* left_hand, right_hand */
        double *dst = &out[IDX_DIR_LHAND + h];
        if (!have[k]) {
            affect_part hand;
            st = soft(affect_part_resolve(m, roles, all_parts[k], &hand, err), opt, dst, 1);
            if (!st && m->n_frames < MIN_FRAMES)
                st = soft(affect_fail(err, AFFECT_ERR_RANGE,
                                      "the motion has %u frames; Shape "
                                      "Directional needs at least %d",
                                      m->n_frames, MIN_FRAMES),
                          opt, dst, 1);
            if (st)
                goto done;
            continue;
        }
        st = affect_laban_shape_directional(m, &parts[k], opt, dst, err);
        if (st)
            goto done;
    }
done:
    affect_free(kin);
    return st;
}

/* ---- the kinematics of laban_series.c ---- */

affect_status affect_laban_kinematics_block(const affect_motion *m, const affect_part *parts,
                                            uint32_t n, const affect_laban_options *opt,
                                            double **block, const double *vel[6],
                                            const double *acc[6], size_t *stride, affect_error *err)
{
    *block = NULL;
    affect_status st = check_effort_input(m, n, opt, "the Laban series", err);
    if (st)
        return st;
    affect_part p6[6];
    memset(p6, 0, sizeof p6);
    bool have[6] = {false, false, false, false, false, false};
    for (uint32_t k = 0; k < n; k++) {
        p6[k] = parts[k];
        have[k] = true;
    }
    effort_series s;
    st = vector_kinematics(m, p6, have, opt, block, &s, err);
    if (st)
        return st;
    for (uint32_t k = 0; k < n; k++) {
        vel[k] = s.vel[k];
        acc[k] = s.acc[k];
    }
    *stride = s.stride;
    return AFFECT_OK;
}
