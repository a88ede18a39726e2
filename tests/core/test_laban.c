/*
 * test_laban.c — Laban Effort and Shape descriptors against analytic answers: the filter keeps
 * constants, lines and slow sinusoids and removes fast ones; constant velocity has no
 * acceleration; a known speed gives a known kinetic energy; a straight path is direct (Space 1,
 * Directional 0); a circle of radius r has curvature 1/r; the shaping and flow components of a
 * rigid box; missing roles and short motions; and on motion_synth, WeightAll and TimeAll order
 * angry > neutral > sad for every action; and the vector, bit for bit, against the same values
 * computed component by component (every part alone, a hull area and a hull volume for every
 * frame, Shape Directional axis by axis with affect_lowpass).
 */
#include <lapacke.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"
#include "affect/laban.h"
#include "affect/synth.h"

#define PI 3.14159265358979323846

/* OpenBLAS's (the library the core links) */
int openblas_get_num_threads(void);
void openblas_set_num_threads(int num_threads);

/* The six parts' joints plus two hips for the heading: every role that "all" needs. */
static const char *const body_names[] = {"Hips",   "Spine",  "Chest",  "Head",       "Hand_L",
                                         "Hand_R", "Foot_L", "Foot_R", "UpperLeg_L", "UpperLeg_R"};
enum { N_BODY = 10 };

/* A rigid body: joint j at base[j] + f(t), with f given per frame by the callback. */
typedef void (*path_fn)(double t, double out[3], void *ctx);

static affect_motion *rigid_body(uint32_t frames, double fps, path_fn f, void *ctx)
{
    static const double base[N_BODY][3] = {
        {0, 1, 0},      {0, 1.2, 0},    {0, 1.4, 0},     {0, 1.7, 0},    {0.3, 1.0, 0},
        {-0.3, 1.0, 0}, {0.1, 0.05, 0}, {-0.1, 0.05, 0}, {0.1, 0.95, 0}, {-0.1, 0.95, 0}};
    affect_motion *m = NULL;
    affect_error err;
    assert_int_equal(affect_motion_create(frames, N_BODY, fps, &m, &err), AFFECT_OK);
    for (uint32_t j = 0; j < N_BODY; j++)
        assert_int_equal(affect_motion_set_name(m, j, body_names[j], strlen(body_names[j]), &err),
                         AFFECT_OK);
    for (uint32_t t = 0; t < frames; t++) {
        double d[3];
        f(t / fps, d, ctx);
        for (uint32_t j = 0; j < N_BODY; j++)
            for (int a = 0; a < 3; a++)
                affect_motion_at(m, t, j)[a] = (float)(base[j][a] + d[a]);
    }
    return m;
}

static void still(double t, double out[3], void *ctx)
{
    out[0] = out[1] = out[2] = 0;
}

static void uniform(double t, double out[3], void *ctx)
{
    const double *v = ctx; /* velocity */
    for (int a = 0; a < 3; a++)
        out[a] = v[a] * t;
}

static void circle(double t, double out[3], void *ctx)
{
    const double *rw = ctx; /* radius, angular speed: a circle in the x–z plane */
    out[0] = rw[0] * cos(rw[1] * t);
    out[1] = 0;
    out[2] = rw[0] * sin(rw[1] * t);
}

static void test_lowpass(void **state)
{
    enum { N = 300 };
    double x[N], y[N], scratch[N + 18];
    const double fps = 30;
    /* constant, straight line */
    for (int i = 0; i < N; i++)
        x[i] = 2.5;
    affect_lowpass(x, N, 1, fps, 6, scratch, y);
    for (int i = 0; i < N; i++)
        tu_assert_near(y[i], 2.5, 1e-12);
    /* a line: the padding continues it and each pass starts in its steady state */
    for (int i = 0; i < N; i++)
        x[i] = 0.1 * i - 3;
    affect_lowpass(x, N, 1, fps, 6, scratch, y);
    for (int i = 0; i < N; i++)
        tu_assert_near(y[i], x[i], 1e-10);
    /* a slow sinusoid (0.5 Hz) passes; a fast one (12 Hz) is removed away from the edges */
    for (int i = 0; i < N; i++)
        x[i] = sin(2 * PI * 0.5 * i / fps);
    affect_lowpass(x, N, 1, fps, 6, scratch, y);
    for (int i = 0; i < N; i++)
        tu_assert_near(y[i], x[i], 2e-3);
    for (int i = 0; i < N; i++)
        x[i] = sin(2 * PI * 12 * i / fps);
    affect_lowpass(x, N, 1, fps, 6, scratch, y);
    for (int i = 30; i < N - 30; i++)
        tu_assert_near(y[i], 0, 0.02);
    /* at or above Nyquist: unchanged; strided layout */
    affect_lowpass(x, N, 1, fps, 15, scratch, y);
    assert_memory_equal(x, y, sizeof x);
    double xyz[3 * 50], out[3 * 50];
    for (int i = 0; i < 150; i++)
        xyz[i] = i % 3 == 1 ? 7.0 : (double)i;
    affect_lowpass(xyz + 1, 50, 3, fps, 6, scratch, out + 1);
    for (int i = 0; i < 50; i++)
        tu_assert_near(out[3 * i + 1], 7.0, 1e-12);
}

static void test_constant_velocity(void **state)
{
    double v[3] = {0.5, 0, 1.2}; /* |v|² = 1.69 per part */
    affect_motion *m = rigid_body(120, 30, uniform, v);
    affect_roles roles;
    affect_roles_resolve(m, &roles);
    double out[AFFECT_LABAN_N];
    affect_error err;
    assert_int_equal(affect_laban_vector(m, &roles, NULL, out, &err), AFFECT_OK);
    /* six parts each with kinetic energy 1.69 (u²/s²); positions are float32, so differences
     * of metres-sized coordinates carry ~1e-5 relative error */
    tu_assert_near(out[affect_laban_index("WeightAll")], 6 * 1.69, 1e-3);
    tu_assert_near(out[affect_laban_index("WeightLHand")], 1.69, 2e-4);
    /* no acceleration, no jerk: Time and Flow vanish everywhere, edges included, but for the
     * float32 rounding of the positions (~5e-7 m, ×30 per derivative, summed over six parts) */
    tu_assert_near(out[affect_laban_index("TimeAll")], 0, 5e-3);
    tu_assert_near(out[affect_laban_index("FlowAll")], 0, 0.5); /* a sum over 119 frames × 6 */
    /* straight path: spoke-like, perfectly direct */
    tu_assert_near(out[affect_laban_index("ShapeDirLHand")], 0, 1e-4); /* 1/m; a 1 m circle: 1 */
    affect_part part;
    assert_int_equal(affect_part_resolve(m, &roles, "right_hand", &part, &err), AFFECT_OK);
    double space;
    assert_int_equal(affect_laban_space(m, &part, 1, AFFECT_LABAN_Q2, NULL, &space, &err),
                     AFFECT_OK);
    tu_assert_near(space, 1.0, 1e-9);
    /* the torso moved 0.5·4 = 2 sideways-ish, 1.2·4 = 4.8 forward over 4 s (forward is +z:
     * the left hip is at +x) */
    tu_assert_near(out[affect_laban_index("ShapeVertical")], 0, 1e-6);
    tu_assert_near(out[affect_laban_index("ShapeSagittal")], 1.2 * 119 / 30.0, 1e-5);
    affect_motion_free(m);
}

static void test_circle_curvature(void **state)
{
    /* radius 0.25 m, one turn per 2 s, 8 s at 60 fps: curvature 4 per metre */
    double rw[2] = {0.25, PI};
    affect_motion *m = rigid_body(480, 60, circle, rw);
    affect_roles roles;
    affect_roles_resolve(m, &roles);
    affect_part hand;
    affect_error err;
    double k;
    assert_int_equal(affect_part_resolve(m, &roles, "left_hand", &hand, &err), AFFECT_OK);
    assert_int_equal(affect_laban_shape_directional(m, &hand, NULL, &k, &err), AFFECT_OK);
    tu_assert_near(k, 4.0, 0.02);
    /* circular motion: speed ω r = 0.785 m/s, centripetal acceleration ω² r = 2.47 m/s² */
    double w, acc;
    assert_int_equal(affect_laban_weight(m, &hand, 1, AFFECT_LABAN_Q1, NULL, &w, &err), AFFECT_OK);
    tu_assert_near(w, pow(PI * 0.25, 2), 1e-3);
    assert_int_equal(affect_laban_time(m, &hand, 1, AFFECT_LABAN_Q1, NULL, &acc, &err), AFFECT_OK);
    /* the peak is reached at the ends, where the odd-reflection padding (which continues
     * position and velocity but mirrors curvature) adds a small transient: within 1.5 % */
    tu_assert_near(acc, PI * PI * 0.25, 0.037);
    /* the path returns to its start: Space Q2 hits its documented cap */
    double space;
    affect_laban_options opt;
    affect_laban_options_default(&opt);
    assert_int_equal(affect_laban_space(m, &hand, 1, AFFECT_LABAN_Q2, &opt, &space, &err),
                     AFFECT_OK);
    tu_assert_near(space, opt.max_ratio, 1e-9);
    affect_motion_free(m);
}

static void test_shape_of_a_still_body(void **state)
{
    affect_motion *m = rigid_body(10, 30, still, NULL);
    affect_roles roles;
    affect_roles_resolve(m, &roles);
    double out[AFFECT_LABAN_N];
    affect_error err;
    assert_int_equal(affect_laban_vector(m, &roles, NULL, out, &err), AFFECT_OK);
    for (int i = 0; i < 21; i++)
        tu_assert_near(out[i], 0, 1e-12);
    tu_assert_near(out[affect_laban_index("ShapeVertical")], 0, 0);
    /* all joints lie in the plane z = 0: the horizontal hull (x–z) is a segment, the volume 0 */
    tu_assert_near(out[affect_laban_index("ShapeHorizontal")], 0, 1e-12);
    tu_assert_near(out[affect_laban_index("ShapeFlow")], 0, 1e-12);
    /* the bounding box of a flat body is flat too */
    affect_laban_options opt;
    affect_laban_options_default(&opt);
    opt.hull_box = true;
    double flow;
    assert_int_equal(affect_laban_shape_flow(m, &opt, &flow, &err), AFFECT_OK);
    tu_assert_near(flow, 0, 1e-12);
    affect_motion_free(m);
}

static void test_hull_components(void **state)
{
    /* move Hand_L forward by 0.2 in frame 5: the horizontal hull gains a triangle */
    affect_motion *m = rigid_body(10, 30, still, NULL);
    affect_motion_at(m, 5, 4)[2] = 0.2f; /* Hand_L at (0.3, 1.0, 0.2) */
    affect_roles roles;
    affect_roles_resolve(m, &roles);
    double out[AFFECT_LABAN_N];
    affect_error err;
    assert_int_equal(affect_laban_vector(m, &roles, NULL, out, &err), AFFECT_OK);
    /* x–z points: a segment from x = −0.3 (Hand_R) to 0.1 (left foot and hip) plus the moved
     * hand at (0.3, 0.2): the triangle (−0.3, 0), (0.1, 0), (0.3, 0.2) of area 0.4·0.2/2 */
    tu_assert_near(out[affect_laban_index("ShapeHorizontal")], 0.04, 1e-6);
    affect_motion_free(m);
}

static void test_missing_roles_and_short_motions(void **state)
{
    affect_motion *m = rigid_body(3, 30, still, NULL);
    affect_roles roles;
    affect_roles_resolve(m, &roles);
    double out[AFFECT_LABAN_N];
    affect_error err;
    assert_int_equal(affect_laban_vector(m, &roles, NULL, out, &err), AFFECT_ERR_RANGE);
    assert_string_equal(err.msg, "the motion has 3 frames; Weight, Time and Flow need at least 4");
    affect_laban_options opt;
    affect_laban_options_default(&opt);
    opt.missing_null = true;
    assert_int_equal(affect_laban_vector(m, &roles, &opt, out, &err), AFFECT_OK);
    assert_true(isnan(out[0]) && isnan(out[20]) && isnan(out[25]));
    assert_false(isnan(out[affect_laban_index("ShapeVertical")]));
    affect_motion_free(m);

    m = rigid_body(10, 30, still, NULL);
    affect_roles_resolve(m, &roles);
    roles.joint[AFFECT_ROLE_LEFT_HAND] = -1;
    assert_int_equal(affect_laban_vector(m, &roles, NULL, out, &err), AFFECT_ERR_MISSING);
    assert_string_equal(err.msg, "no joint has the left_hand role");
    assert_int_equal(affect_laban_vector(m, &roles, &opt, out, &err), AFFECT_OK);
    assert_true(isnan(out[affect_laban_index("WeightAll")]));
    assert_true(isnan(out[affect_laban_index("WeightLHand")]));
    assert_true(isnan(out[affect_laban_index("ShapeDirLHand")]));
    assert_false(isnan(out[affect_laban_index("WeightRHand")]));
    affect_part part;
    assert_int_equal(affect_part_resolve(m, &roles, "Tail", &part, &err), AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "\"Tail\" is neither a part (all, torso, head, left_hand, "
                                 "right_hand, left_foot, right_foot) nor a joint of the motion");
    assert_int_equal(affect_part_resolve(m, &roles, "Spine", &part, &err), AFFECT_OK);
    assert_int_equal(part.joints[0], 1);
    opt.cutoff_hz = -1;
    assert_int_equal(affect_laban_vector(m, &roles, &opt, out, &err), AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "cutoff_hz must be a positive number, got -1");
    affect_motion_free(m);
    for (int i = 0; i < AFFECT_LABAN_N; i++)
        assert_int_equal(affect_laban_index(affect_laban_names[i]), i);
    assert_int_equal(affect_laban_index("WeightBoth"), -1);
}

/* The thesis's expectation on our synthetic corpus: angry is Strong and Sudden, sad Light and
 * Sustained, for every action and performer. */
static void test_synth_ordering(void **state)
{
    for (int a = 0; affect_synth_actions[a]; a++)
        for (uint64_t seed = 1; seed <= 3; seed++) {
            double w[3], t[3];
            static const char *const emotions[3] = {"angry", "neutral", "sad"};
            for (int e = 0; e < 3; e++) {
                affect_motion *m = NULL;
                affect_error err;
                assert_int_equal(
                    affect_motion_synth(affect_synth_actions[a], emotions[e], seed, NULL, &m, &err),
                    AFFECT_OK);
                affect_roles roles;
                affect_roles_resolve(m, &roles);
                double out[AFFECT_LABAN_N];
                if (affect_laban_vector(m, &roles, NULL, out, &err))
                    fail_msg("%s", err.msg);
                w[e] = out[affect_laban_index("WeightAll")];
                t[e] = out[affect_laban_index("TimeAll")];
                affect_motion_free(m);
            }
            if (!(w[0] > w[1] && w[1] > w[2] && t[0] > t[1] && t[1] > t[2]))
                fail_msg("%s seed %u: Weight %g %g %g, Time %g %g %g (angry, neutral, sad)",
                         affect_synth_actions[a], (unsigned)seed, w[0], w[1], w[2], t[0], t[1],
                         t[2]);
        }
}

/* Shape Directional as it was first written, channel by channel: the hand's path projected on
 * its two principal axes (LAPACKE_dsyev), velocity and acceleration by central differences
 * and affect_lowpass of each axis, the mean curvature over the frames above the speed floor.
 * affect_laban_shape_directional filters both axes in lockstep; it must give these bits. */
static double reference_directional(const affect_motion *m, const affect_part *hand,
                                    const affect_laban_options *opt)
{
    uint32_t n = m->n_frames;
    double *pos = malloc(((size_t)n * 11 + 20) * sizeof *pos);
    assert_non_null(pos);
    double *d1 = pos + 2 * (size_t)n, *d2 = d1 + 2 * (size_t)n, *col = d2 + 2 * (size_t)n;
    double *scratch = col + 3 * (size_t)n, mean[3] = {0, 0, 0}, cov[9] = {0}, w[3];
    for (uint32_t t = 0; t < n; t++) {
        double c[3] = {0, 0, 0};
        for (uint32_t i = 0; i < hand->n_joints; i++)
            for (int a = 0; a < 3; a++)
                c[a] += affect_motion_at(m, t, (uint32_t)hand->joints[i])[a];
        for (int a = 0; a < 3; a++)
            col[3 * (size_t)t + a] = hand->n_joints == 1 ? c[a] : c[a] * (1.0 / hand->n_joints);
    }
    for (uint32_t t = 0; t < n; t++)
        for (int a = 0; a < 3; a++)
            mean[a] += col[3 * (size_t)t + a];
    for (int a = 0; a < 3; a++)
        mean[a] /= n;
    for (uint32_t t = 0; t < n; t++)
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++)
                cov[a * 3 + b] +=
                    (col[3 * (size_t)t + a] - mean[a]) * (col[3 * (size_t)t + b] - mean[b]);
    /* on one OpenBLAS thread, as the core's calls run (dsyev's last bits depend on it) */
    int threads = openblas_get_num_threads();
    openblas_set_num_threads(1);
    lapack_int info = LAPACKE_dsyev(LAPACK_ROW_MAJOR, 'V', 'U', 3, cov, 3, w);
    openblas_set_num_threads(threads);
    assert_int_equal(info, 0);
    for (uint32_t t = 0; t < n; t++) {
        const double *p = col + 3 * (size_t)t;
        double c[3] = {p[0] - mean[0], p[1] - mean[1], p[2] - mean[2]};
        pos[2 * (size_t)t] = c[0] * cov[2] + c[1] * cov[5] + c[2] * cov[8];
        pos[2 * (size_t)t + 1] = c[0] * cov[1] + c[1] * cov[4] + c[2] * cov[7];
    }
    /* one axis at a time: central differences, then affect_lowpass, twice */
    const double *src = pos;
    double *dst = d1;
    for (int order = 0; order < 2; order++, src = d1, dst = d2)
        for (int a = 0; a < 2; a++) {
            for (uint32_t t = 0; t < n; t++) {
                double d =
                    t == 0 ? (src[2 + a] - src[a]) * m->fps
                    : t == n - 1
                        ? (src[2 * (size_t)t + a] - src[2 * (size_t)t - 2 + a]) * m->fps
                        : (src[2 * (size_t)t + 2 + a] - src[2 * (size_t)t - 2 + a]) * m->fps * 0.5;
                dst[2 * (size_t)t + a] = d;
            }
            affect_lowpass(dst + a, n, 2, m->fps, opt->cutoff_hz, scratch, dst + a);
        }
    double peak = 0, sum = 0;
    uint32_t used = 0;
    for (uint32_t t = 0; t < n; t++)
        peak = fmax(peak, hypot(d1[2 * (size_t)t], d1[2 * (size_t)t + 1]));
    for (uint32_t t = 0; t < n && peak > 0; t++) {
        double xd = d1[2 * (size_t)t], yd = d1[2 * (size_t)t + 1];
        double xdd = d2[2 * (size_t)t], ydd = d2[2 * (size_t)t + 1], speed = hypot(xd, yd);
        if (speed <= 0 || speed < opt->speed_floor * peak)
            continue;
        sum += fabs(xdd * yd - ydd * xd) / (speed * speed * speed);
        used++;
    }
    free(pos);
    return used ? sum / used : 0.0;
}

/* affect_laban_vector (one pass filtering the six parts together, hull areas bounded before
 * they are computed) against a straightforward reference built from the per-component
 * functions (each part's kinematics computed alone with affect_lowpass) and a hull area and a
 * hull volume (or box) for every frame: the same bits, on synthetic motions with several
 * options (filtered, another cut-off and up axis, no filtering at all, the bounding box). */
static void reference_vector(const affect_motion *m, const affect_roles *roles,
                             const affect_laban_options *opt, double ref[AFFECT_LABAN_N])
{
    affect_error err;
    affect_part parts[6];
    assert_int_equal(affect_parts_all(m, roles, parts, &err), AFFECT_OK);
    for (uint32_t k = 0; k <= 6; k++) {
        const affect_part *p = k == 0 ? parts : &parts[k - 1];
        uint32_t n = k == 0 ? 6 : 1;
        assert_int_equal(affect_laban_weight(m, p, n, AFFECT_LABAN_Q1, opt, &ref[k], &err),
                         AFFECT_OK);
        assert_int_equal(affect_laban_time(m, p, n, AFFECT_LABAN_Q1, opt, &ref[7 + k], &err),
                         AFFECT_OK);
        assert_int_equal(affect_laban_flow(m, p, n, opt, &ref[14 + k], &err), AFFECT_OK);
    }
    double shaping[3];
    assert_int_equal(affect_laban_shape_shaping(m, roles, opt, shaping, &err), AFFECT_OK);
    ref[21] = shaping[0];
    ref[22] = shaping[1];
    /* horizontal: the hull area of every frame, over the joints that are not the pelvis's
     * ancestors */
    int32_t pelvis = roles->joint[AFFECT_ROLE_PELVIS];
    double xy[2 * 64], xyz[3 * 64], scratch[4 * 64], horizontal = 0, flow = 0;
    assert_true(m->n_joints <= 64);
    affect_hull3d *hull = affect_hull3d_new(64);
    assert_non_null(hull);
    int a = (opt->up_axis + 1) % 3, b = (opt->up_axis + 2) % 3;
    for (uint32_t t = 0; t < m->n_frames; t++) {
        uint32_t nb = 0;
        for (uint32_t j = 0; j < m->n_joints; j++) {
            bool ancestor = false;
            for (int32_t q = pelvis >= 0 ? m->parents[pelvis] : -1; q >= 0; q = m->parents[q])
                ancestor |= q == (int32_t)j;
            if (ancestor)
                continue;
            const float *p = affect_motion_at(m, t, j);
            xy[2 * nb] = p[a];
            xy[2 * nb + 1] = p[b];
            for (int k = 0; k < 3; k++)
                xyz[3 * nb + k] = p[k];
            nb++;
        }
        horizontal = fmax(horizontal, affect_hull_area_2d(xy, nb, scratch));
        /* Shape Flow: the hull volume (or the box) of every frame, so that the vector may
         * skip frames only when that cannot change the maximum */
        double v;
        if (opt->hull_box) {
            double lo[3] = {xyz[0], xyz[1], xyz[2]}, hi[3] = {xyz[0], xyz[1], xyz[2]};
            for (uint32_t i = 1; i < nb; i++)
                for (int k = 0; k < 3; k++) {
                    double c = xyz[3 * i + k];
                    lo[k] = c < lo[k] ? c : lo[k];
                    hi[k] = c > hi[k] ? c : hi[k];
                }
            v = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
        } else {
            v = affect_hull3d_volume(hull, xyz, nb);
        }
        flow = v > flow ? v : flow;
    }
    affect_hull3d_free(hull);
    ref[23] = horizontal;
    ref[24] = flow;
    ref[25] = reference_directional(m, &parts[2], opt);
    ref[26] = reference_directional(m, &parts[3], opt);
}

static void test_vector_matches_reference(void **state)
{
    static const char *const emotions[3] = {"angry", "neutral", "sad"};
    for (int a = 0; affect_synth_actions[a]; a++)
        for (int e = 0; e < 3; e++) {
            affect_motion *m = NULL;
            affect_error err;
            assert_int_equal(affect_motion_synth(affect_synth_actions[a], emotions[e],
                                                 (uint64_t)(a + e + 1), NULL, &m, &err),
                             AFFECT_OK);
            affect_roles roles;
            affect_roles_resolve(m, &roles);
            for (int variant = 0; variant < 4; variant++) {
                affect_laban_options opt;
                affect_laban_options_default(&opt);
                if (variant == 1) {
                    opt.cutoff_hz = 3;
                    opt.up_axis = 2;
                } else if (variant == 2) {
                    opt.cutoff_hz = 20; /* above the Nyquist frequency: nothing filtered */
                } else if (variant == 3) {
                    opt.hull_box = true;
                }
                double out[AFFECT_LABAN_N], ref[AFFECT_LABAN_N];
                if (affect_laban_vector(m, &roles, &opt, out, &err))
                    fail_msg("%s", err.msg);
                reference_vector(m, &roles, &opt, ref);
                for (int i = 0; i < AFFECT_LABAN_N; i++)
                    if (memcmp(&out[i], &ref[i], sizeof out[i]) != 0)
                        fail_msg("%s %s variant %d: %s = %.17g, reference %.17g",
                                 affect_synth_actions[a], emotions[e], variant,
                                 affect_laban_names[i], out[i], ref[i]);
            }
            /* two parts missing (missing_null): the others' Effort values, the same bits as
             * each part alone, and NaN for the missing and for the combinations */
            affect_roles some = roles;
            some.joint[AFFECT_ROLE_LEFT_HAND] = -1;
            some.joint[AFFECT_ROLE_HEAD] = -1;
            affect_laban_options opt;
            affect_laban_options_default(&opt);
            opt.missing_null = true;
            double out[AFFECT_LABAN_N];
            if (affect_laban_vector(m, &some, &opt, out, &err))
                fail_msg("%s", err.msg);
            static const char *const part_names[6] = {"torso",      "head",      "left_hand",
                                                      "right_hand", "left_foot", "right_foot"};
            for (int k = 0; k < 6; k++) {
                affect_part part;
                int idx[3] = {1 + k, 8 + k, 15 + k}; /* Weight, Time, Flow of part k */
                if (affect_part_resolve(m, &some, part_names[k], &part, &err) != AFFECT_OK) {
                    for (int c = 0; c < 3; c++)
                        assert_true(isnan(out[idx[c]]));
                    continue;
                }
                double ref[3];
                assert_int_equal(
                    affect_laban_weight(m, &part, 1, AFFECT_LABAN_Q1, &opt, &ref[0], &err),
                    AFFECT_OK);
                assert_int_equal(
                    affect_laban_time(m, &part, 1, AFFECT_LABAN_Q1, &opt, &ref[1], &err),
                    AFFECT_OK);
                assert_int_equal(affect_laban_flow(m, &part, 1, &opt, &ref[2], &err), AFFECT_OK);
                for (int c = 0; c < 3; c++)
                    if (memcmp(&out[idx[c]], &ref[c], sizeof ref[c]) != 0)
                        fail_msg("%s %s without head and left hand: %s = %.17g, reference %.17g",
                                 affect_synth_actions[a], emotions[e], affect_laban_names[idx[c]],
                                 out[idx[c]], ref[c]);
            }
            assert_true(isnan(out[0]) && isnan(out[7]) && isnan(out[14]));
            affect_motion_free(m);
        }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lowpass),
        cmocka_unit_test(test_constant_velocity),
        cmocka_unit_test(test_circle_curvature),
        cmocka_unit_test(test_shape_of_a_still_body),
        cmocka_unit_test(test_hull_components),
        cmocka_unit_test(test_missing_roles_and_short_motions),
        cmocka_unit_test(test_synth_ordering),
        cmocka_unit_test(test_vector_matches_reference),
    };
    return cmocka_run_group_tests_name("laban", tests, NULL, NULL);
}
