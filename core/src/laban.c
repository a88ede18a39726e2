/*
 * laban.c — Laban Effort and Shape descriptors (see affect/laban.h for the definitions).
 *
 * How it works: every part's position series (a joint, or a centroid) is differentiated by
 * central differences and low-pass filtered three times (velocity, acceleration, jerk). The
 * Effort components reduce those series; affect_laban_vector computes the six parts' kinematics
 * once and derives all 21 Effort values from them. Shape components use the raw positions:
 * Directional projects the hand path on its two principal axes (LAPACKE_dsyev on the 3 × 3
 * covariance), Shaping and Flow take convex hulls per frame (hull.c).
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

const char *const affect_laban_names[AFFECT_LABAN_N] = {
    "WeightAll",   "WeightTorso", "WeightHead",      "WeightLHand",   "WeightRHand",
    "WeightLFoot", "WeightRFoot", "TimeAll",         "TimeTorso",     "TimeHead",
    "TimeLHand",   "TimeRHand",   "TimeLFoot",       "TimeRFoot",     "FlowAll",
    "FlowTorso",   "FlowHead",    "FlowLHand",       "FlowRHand",     "FlowLFoot",
    "FlowRFoot",   "ShapeVertical", "ShapeSagittal", "ShapeHorizontal", "ShapeFlow",
    "ShapeDirLHand", "ShapeDirRHand"};

enum { IDX_WEIGHT = 0, IDX_TIME = 7, IDX_FLOW = 14, IDX_VERTICAL = 21, IDX_SAGITTAL,
       IDX_HORIZONTAL, IDX_SHAPE_FLOW, IDX_DIR_LHAND, IDX_DIR_RHAND };

/* The six parts of "all", in component order after "All". */
static const char *const all_parts[6] = {"torso", "head", "left_hand", "right_hand",
                                         "left_foot", "right_foot"};

#define MIN_FRAMES 4 /* Effort and Directional need differences of differences */
#define PAD_MAX 9    /* odd-reflection padding of the filter */

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

void affect_lowpass(const double *x, size_t n, size_t stride, double fps, double cutoff_hz,
                    double *scratch, double *out)
{
    if (n < 2 || !(cutoff_hz < fps / 2.0) || !(cutoff_hz > 0)) {
        if (out != x)
            for (size_t i = 0; i < n; i++)
                out[i * stride] = x[i * stride];
        return;
    }
    double k = tan(3.14159265358979323846 * cutoff_hz / fps);
    double norm = 1.0 / (1.0 + sqrt(2.0) * k + k * k);
    double b0 = k * k * norm, b1 = 2.0 * b0, b2 = b0;
    double a1 = 2.0 * (k * k - 1.0) * norm, a2 = (1.0 - sqrt(2.0) * k + k * k) * norm;
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
        d[(size_t)(n - 1) * 3 + a] = (x[(size_t)(n - 1) * 3 + a] - x[(size_t)(n - 2) * 3 + a]) * fps;
        for (uint32_t t = 1; t + 1 < n; t++)
            d[(size_t)t * 3 + a] = (x[(size_t)(t + 1) * 3 + a] - x[(size_t)(t - 1) * 3 + a]) * fps * 0.5;
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
    } simple[] = {{"head", AFFECT_ROLE_HEAD},           {"left_hand", AFFECT_ROLE_LEFT_HAND},
                  {"right_hand", AFFECT_ROLE_RIGHT_HAND}, {"left_foot", AFFECT_ROLE_LEFT_FOOT},
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

/* max over frames of Σ_k f(x_k(t)), x = vel with f = ‖·‖² (Weight Q1) or acc with f = ‖·‖
 * (Time Q1). */
static double peak_sum(const affect_kinematics *ks, uint32_t n, bool of_acc)
{
    double best = 0;
    for (uint32_t t = 0; t < ks[0].n_frames; t++) {
        double sum = 0;
        for (uint32_t k = 0; k < n; k++) {
            const double *x = (of_acc ? ks[k].acc : ks[k].vel) + (size_t)t * 3;
            double sq = x[0] * x[0] + x[1] * x[1] + x[2] * x[2];
            sum += of_acc ? sqrt(sq) : sq;
        }
        if (sum > best)
            best = sum;
    }
    return best;
}

static double weight_q1(const affect_kinematics *ks, uint32_t n)
{
    return peak_sum(ks, n, false);
}

static double weight_q2(const affect_kinematics *ks, uint32_t n)
{
    double best = 0;
    for (uint32_t t = 1; t < ks[0].n_frames; t++) {
        double d = 0;
        for (uint32_t k = 0; k < n; k++) {
            double drop = (norm3(ks[k].vel + (size_t)(t - 1) * 3) - norm3(ks[k].vel + (size_t)t * 3)) *
                          ks[k].fps;
            if (drop > 0)
                d += drop;
        }
        if (d > best)
            best = d;
    }
    return best;
}

static double time_q1(const affect_kinematics *ks, uint32_t n)
{
    return peak_sum(ks, n, true);
}

/* Σ_k Σ_{t≥1} ‖x_k(t) − x_k(t−1)‖ · fps for x = vel (Time Q2) or acc (Flow). */
static double accumulated(const affect_kinematics *ks, uint32_t n, bool of_acc)
{
    double sum = 0;
    for (uint32_t k = 0; k < n; k++) {
        const double *x = of_acc ? ks[k].acc : ks[k].vel;
        for (uint32_t t = 1; t < ks[k].n_frames; t++)
            sum += dist3(x + (size_t)t * 3, x + (size_t)(t - 1) * 3) * ks[k].fps;
    }
    return sum;
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
        if (st)
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
        return affect_fail(err, AFFECT_ERR_RANGE,
                           "the motion has %u frames; %s needs at least %d", m->n_frames, what,
                           MIN_FRAMES);
    return AFFECT_OK;
}

typedef enum effort_kind { WEIGHT_Q1, WEIGHT_Q2, TIME_Q1, TIME_Q2, FLOW, SPACE_Q1, SPACE_Q2 } effort_kind;

static double effort_value(const affect_motion *m, const affect_kinematics *ks, uint32_t n,
                           effort_kind kind, const affect_laban_options *opt)
{
    switch (kind) {
    case WEIGHT_Q1: return weight_q1(ks, n);
    case WEIGHT_Q2: return weight_q2(ks, n);
    case TIME_Q1: return time_q1(ks, n);
    case TIME_Q2: {
        double v = accumulated(ks, n, false);
        return opt->time_per_second ? v / affect_motion_duration(m) : v;
    }
    case FLOW: return accumulated(ks, n, true);
    case SPACE_Q1: return space_q1(&ks[0], &ks[1]);
    default: return space_q2(ks, n, opt->max_ratio);
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
    return effort(m, parts, n, method == AFFECT_LABAN_Q1 ? SPACE_Q1 : SPACE_Q2, "Space", opt,
                  out, err);
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
    double *block = affect_malloc_array((size_t)n * 9 + n + 2 * PAD_MAX, sizeof *block);
    if (!block)
        return affect_nomem(err);
    double *pos = block, *d1 = block + (size_t)n * 3, *d2 = block + (size_t)n * 6;
    double *scratch = block + (size_t)n * 9;
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
                cov[a * 3 + b] += (pos[(size_t)t * 3 + a] - mean[a]) * (pos[(size_t)t * 3 + b] - mean[b]);
    lapack_int info = LAPACKE_dsyev(LAPACK_ROW_MAJOR, 'V', 'U', 3, cov, 3, w);
    if (info != 0) {
        affect_free(block);
        return info == LAPACK_WORK_MEMORY_ERROR || info == LAPACK_TRANSPOSE_MEMORY_ERROR
                   ? affect_nomem(err)
                   : affect_fail(err, AFFECT_ERR_INVALID, "eigen-decomposition failed (LAPACK info %d)",
                                 (int)info);
    }
    /* eigenvalues ascend: columns 2 and 1 are the two main axes; project onto them (x, y) and
     * leave z = 0 so the 3-D derivative helpers can be reused */
    for (uint32_t t = 0; t < n; t++) {
        double c[3] = {pos[(size_t)t * 3] - mean[0], pos[(size_t)t * 3 + 1] - mean[1],
                       pos[(size_t)t * 3 + 2] - mean[2]};
        double x = c[0] * cov[2] + c[1] * cov[5] + c[2] * cov[8];
        double y = c[0] * cov[1] + c[1] * cov[4] + c[2] * cov[7];
        pos[(size_t)t * 3] = x;
        pos[(size_t)t * 3 + 1] = y;
        pos[(size_t)t * 3 + 2] = 0;
    }
    derivative3(pos, n, m->fps, opt->cutoff_hz, scratch, d1);
    derivative3(d1, n, m->fps, opt->cutoff_hz, scratch, d2);
    double peak = 0;
    for (uint32_t t = 0; t < n; t++)
        peak = fmax(peak, hypot(d1[(size_t)t * 3], d1[(size_t)t * 3 + 1]));
    double sum = 0;
    uint32_t used = 0;
    for (uint32_t t = 0; t < n && peak > 0; t++) {
        double xd = d1[(size_t)t * 3], yd = d1[(size_t)t * 3 + 1];
        double xdd = d2[(size_t)t * 3], ydd = d2[(size_t)t * 3 + 1];
        double speed = hypot(xd, yd);
        if (speed <= 0 || speed < opt->speed_floor * peak)
            continue;
        sum += fabs(xdd * yd - ydd * xd) / (speed * speed * speed);
        used++;
    }
    *out = used ? sum / used : 0.0;
    affect_free(block);
    return AFFECT_OK;
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
        vertical = fmax(vertical, fabs(d[u]));
        sagittal = fmax(sagittal, fabs(d[0] * fwd[0] + d[1] * fwd[1] + d[2] * fwd[2]));
    }
    uint32_t nb = body_joints(m, roles->joint[AFFECT_ROLE_PELVIS], joints);
    for (uint32_t t = 0; t < n; t++) {
        for (uint32_t i = 0; i < nb; i++) {
            const float *p = affect_motion_at(m, t, (uint32_t)joints[i]);
            xy[2 * i] = p[a];
            xy[2 * i + 1] = p[b];
        }
        horizontal = fmax(horizontal, affect_hull_area_2d(xy, nb, scratch));
    }
    out[0] = vertical;
    out[1] = sagittal;
    out[2] = horizontal;
    affect_free(block);
    affect_free(joints);
    return AFFECT_OK;
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
    for (uint32_t t = 0; t < m->n_frames; t++) {
        for (uint32_t i = 0; i < nb; i++) {
            const float *p = affect_motion_at(m, t, (uint32_t)joints[i]);
            xyz[3 * i] = p[0], xyz[3 * i + 1] = p[1], xyz[3 * i + 2] = p[2];
        }
        double v;
        if (opt->hull_box) {
            /* positions are validated finite: plain comparisons (gcc does not inline fmin and
             * fmax without fast math) */
            double lo[3] = {xyz[0], xyz[1], xyz[2]}, hi[3] = {xyz[0], xyz[1], xyz[2]};
            for (uint32_t i = 1; i < nb; i++)
                for (int a = 0; a < 3; a++) {
                    double c = xyz[3 * i + a];
                    lo[a] = c < lo[a] ? c : lo[a];
                    hi[a] = c > hi[a] ? c : hi[a];
                }
            v = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
        } else {
            v = affect_hull3d_volume(hull, xyz, nb);
        }
        if (v > best)
            best = v;
    }
    *out = best;
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

    /* Effort: the six parts' kinematics once */
    affect_part parts[6];
    affect_kinematics ks[6];
    bool have[6];
    memset(ks, 0, sizeof ks);
    uint32_t n_have = 0;
    if (m->n_frames < MIN_FRAMES) {
        st = soft(affect_fail(err, AFFECT_ERR_RANGE,
                              "the motion has %u frames; Weight, Time and Flow need at least %d",
                              m->n_frames, MIN_FRAMES),
                  opt, out, IDX_VERTICAL);
        if (st)
            return st;
        memset(have, 0, sizeof have);
    } else {
        for (int k = 0; k < 6; k++) {
            st = affect_part_resolve(m, roles, all_parts[k], &parts[k], err);
            have[k] = st == AFFECT_OK;
            if (st && !(opt->missing_null && st == AFFECT_ERR_MISSING))
                goto done;
            st = AFFECT_OK;
            if (have[k]) {
                st = affect_kinematics_compute(m, &parts[k], opt, &ks[k], err);
                if (st)
                    goto done;
                n_have++;
            }
        }
    }
    for (int k = 0; k < 6; k++) {
        if (!have[k])
            continue;
        out[IDX_WEIGHT + 1 + k] = weight_q1(&ks[k], 1);
        out[IDX_TIME + 1 + k] = time_q1(&ks[k], 1);
        out[IDX_FLOW + 1 + k] = accumulated(&ks[k], 1, true);
    }
    if (n_have == 6) {
        out[IDX_WEIGHT] = weight_q1(ks, 6);
        out[IDX_TIME] = time_q1(ks, 6);
        out[IDX_FLOW] = accumulated(ks, 6, true);
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
                st = soft(affect_fail(err, AFFECT_ERR_RANGE, "the motion has %u frames; Shape "
                                      "Directional needs at least %d", m->n_frames, MIN_FRAMES),
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
    free_all(ks, 6);
    return st;
}
