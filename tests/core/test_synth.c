/*
 * test_synth.c — the procedural affective movements (affect/synth.h): skeleton and naming,
 * rest poses at both ends, constant bone lengths, frame rate and noise, the kinematic and
 * postural signature of each emotion (Weight and Time effort measures, durations, head
 * posture), determinism, performer variation, intensity, error messages and out-of-memory.
 */
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "affect/synth.h"

#define N_SEEDS 5
#define N_ACTIONS 4
#define N_EMOTIONS 4
#define N_JOINTS 26

enum { NEUTRAL, HAPPY, SAD, ANGRY };

static const char *const expected_names[N_JOINTS] = {
    "Hips",       "Spine",      "Chest",      "Neck",       "Head",       "Head_end",
    "Shoulder_L", "UpperArm_L", "LowerArm_L", "Hand_L",     "Hand_L_end", "Shoulder_R",
    "UpperArm_R", "LowerArm_R", "Hand_R",     "Hand_R_end", "UpperLeg_L", "LowerLeg_L",
    "Foot_L",     "Toes_L",     "Toes_L_end", "UpperLeg_R", "LowerLeg_R", "Foot_R",
    "Toes_R",     "Toes_R_end",
};

static const int32_t expected_parents[N_JOINTS] = {
    -1, 0, 1, 2, 3, 4, 2, 6, 7, 8, 9, 2, 11, 12, 13, 14, 0, 16, 17, 18, 19, 0, 21, 22, 23, 24,
};

static affect_motion *synth_ok(const char *action, const char *emotion, uint64_t seed,
                               const affect_synth_options *opt)
{
    affect_motion *m = NULL;
    affect_error err;
    affect_error_clear(&err);
    affect_status st = affect_motion_synth(action, emotion, seed, opt, &m, &err);
    if (st != AFFECT_OK)
        fail_msg("synth(%s, %s, %llu): %s", action, emotion, (unsigned long long)seed, err.msg);
    assert_non_null(m);
    return m;
}

static int joint(const affect_motion *m, const char *name)
{
    int32_t j = affect_motion_find_joint(m, name);
    if (j < 0)
        fail_msg("joint %s missing", name);
    return (int)j;
}

static double dist(const float *a, const float *b)
{
    double dx = (double)a[0] - b[0], dy = (double)a[1] - b[1], dz = (double)a[2] - b[2];
    return sqrt(dx * dx + dy * dy + dz * dz);
}

/* ---- the effort measures that later work relies on ---- */

/* Weight = max over frames of Σ|v|², Time = max over frames of Σ|a| over six parts (torso =
 * centroid of Hips, Spine, Chest; Head; both hands; both feet), from positions smoothed by a
 * 5-frame moving average, with central differences at the frame rate. */
static void effort(const affect_motion *m, double *weight, double *time)
{
    const char *single[5] = {"Head", "Hand_L", "Hand_R", "Foot_L", "Foot_R"};
    int torso[3] = {joint(m, "Hips"), joint(m, "Spine"), joint(m, "Chest")}, parts[5];
    for (int i = 0; i < 5; i++)
        parts[i] = joint(m, single[i]);
    size_t T = m->n_frames;
    double *raw = malloc(T * 18 * sizeof *raw), *sm = malloc(T * 18 * sizeof *sm);
    assert_non_null(raw);
    assert_non_null(sm);
    for (size_t t = 0; t < T; t++)
        for (int a = 0; a < 3; a++) {
            double c = 0;
            for (int i = 0; i < 3; i++)
                c += affect_motion_at(m, (uint32_t)t, (uint32_t)torso[i])[a];
            raw[t * 18 + a] = c / 3.0;
            for (int k = 0; k < 5; k++)
                raw[t * 18 + (k + 1) * 3 + a] =
                    affect_motion_at(m, (uint32_t)t, (uint32_t)parts[k])[a];
        }
    for (size_t t = 0; t < T; t++)
        for (int q = 0; q < 18; q++) {
            double s = 0;
            int n = 0;
            for (int d = -2; d <= 2; d++) {
                long u = (long)t + d;
                if (u < 0 || u >= (long)T)
                    continue;
                s += raw[(size_t)u * 18 + q];
                n++;
            }
            sm[t * 18 + q] = s / n;
        }
    double fps = m->fps;
    *weight = 0;
    *time = 0;
    for (size_t t = 2; t + 2 < T; t++) {
        double w = 0, tm = 0;
        for (int k = 0; k < 6; k++) {
            double v2 = 0, a2 = 0;
            for (int a = 0; a < 3; a++) {
                int q = k * 3 + a;
                double vm = (sm[t * 18 + q] - sm[(t - 2) * 18 + q]) * fps / 2.0;
                double v0 = (sm[(t + 1) * 18 + q] - sm[(t - 1) * 18 + q]) * fps / 2.0;
                double vp = (sm[(t + 2) * 18 + q] - sm[t * 18 + q]) * fps / 2.0;
                double acc = (vp - vm) * fps / 2.0;
                v2 += v0 * v0;
                a2 += acc * acc;
            }
            w += v2;
            tm += sqrt(a2);
        }
        if (w > *weight)
            *weight = w;
        if (tm > *time)
            *time = tm;
    }
    free(raw);
    free(sm);
}

/* Mean over frames of (joint a − joint b) along axis. */
static double mean_offset(const affect_motion *m, const char *a, const char *b, int axis)
{
    int ja = joint(m, a), jb = joint(m, b);
    double s = 0;
    for (uint32_t t = 0; t < m->n_frames; t++)
        s +=
            affect_motion_at(m, t, (uint32_t)ja)[axis] - affect_motion_at(m, t, (uint32_t)jb)[axis];
    return s / m->n_frames;
}

/* ---- tests ---- */

static void test_names_and_defaults(void **state)
{
    (void)state;
    static const char *const actions[] = {"knock", "wave", "walk", "bow"};
    static const char *const emotions[] = {"neutral", "happy", "sad", "angry"};
    for (int i = 0; i < N_ACTIONS; i++)
        assert_string_equal(affect_synth_actions[i], actions[i]);
    assert_null(affect_synth_actions[N_ACTIONS]);
    for (int i = 0; i < N_EMOTIONS; i++)
        assert_string_equal(affect_synth_emotions[i], emotions[i]);
    assert_null(affect_synth_emotions[N_EMOTIONS]);

    affect_synth_options opt;
    memset(&opt, 0xff, sizeof opt);
    affect_synth_options_default(&opt);
    assert_true(opt.fps == 30.0);
    assert_true(opt.intensity == 1.0);
    assert_true(opt.noise == 0.0003);
}

/* Checks that frame t is a plausible standing rest pose. */
static void check_rest_frame(const affect_motion *m, uint32_t t, const char *what)
{
    const float *hips = affect_motion_at(m, t, (uint32_t)joint(m, "Hips"));
    const float *chest = affect_motion_at(m, t, (uint32_t)joint(m, "Chest"));
    const float *top = affect_motion_at(m, t, (uint32_t)joint(m, "Head_end"));
    if (!(hips[1] > 0.85f && hips[1] < 1.05f))
        fail_msg("%s: Hips at %g m", what, hips[1]);
    if (!(top[1] > 1.55f && top[1] < 1.90f))
        fail_msg("%s: top of the head at %g m", what, top[1]);
    /* upright: the head above the hips */
    if (fabs(top[0] - hips[0]) > 0.05 || fabs(top[2] - hips[2]) > 0.08)
        fail_msg("%s: head not above the hips", what);
    static const char *const hands[] = {"Hand_L", "Hand_R"};
    for (int s = 0; s < 2; s++) {
        const float *h = affect_motion_at(m, t, (uint32_t)joint(m, hands[s]));
        /* arms down: wrists below the hips, beside the body */
        if (!(h[1] < hips[1] && h[1] > hips[1] - 0.35f))
            fail_msg("%s: %s at height %g (Hips %g)", what, hands[s], h[1], hips[1]);
        if (!(fabs(h[0] - hips[0]) > 0.15 && fabs(h[2] - chest[2]) < 0.12))
            fail_msg("%s: %s not hanging beside the body", what, hands[s]);
    }
    static const char *const feet[] = {"Foot_L", "Foot_R", "Toes_L_end", "Toes_R_end"};
    for (int i = 0; i < 4; i++) {
        const float *f = affect_motion_at(m, t, (uint32_t)joint(m, feet[i]));
        double lo = i < 2 ? 0.05 : -0.01, hi = i < 2 ? 0.11 : 0.03;
        if (!(f[1] > lo && f[1] < hi))
            fail_msg("%s: %s at height %g", what, feet[i], f[1]);
    }
}

static void test_structure_every_combination(void **state)
{
    (void)state;
    affect_synth_options opt;
    affect_synth_options_default(&opt);
    for (int a = 0; a < N_ACTIONS; a++)
        for (int e = 0; e < N_EMOTIONS; e++)
            for (uint64_t seed = 1; seed <= N_SEEDS; seed++) {
                affect_motion *m =
                    synth_ok(affect_synth_actions[a], affect_synth_emotions[e], seed, &opt);
                affect_error err;
                if (affect_motion_validate(m, &err) != AFFECT_OK)
                    fail_msg("%s %s %llu: %s", affect_synth_actions[a], affect_synth_emotions[e],
                             (unsigned long long)seed, err.msg);
                assert_int_equal(m->n_joints, N_JOINTS);
                for (int j = 0; j < N_JOINTS; j++) {
                    assert_string_equal(m->names[j], expected_names[j]);
                    assert_int_equal(m->parents[j], expected_parents[j]);
                }
                assert_string_equal(m->unit, "m");
                assert_true(m->fps == 30.0);
                double dur = affect_motion_duration(m);
                if (!(dur >= 2.0 && dur <= 10.0))
                    fail_msg("%s %s: duration %g s", affect_synth_actions[a],
                             affect_synth_emotions[e], dur);

                /* starts and ends standing still in the same rest pose */
                check_rest_frame(m, 0, "first frame");
                check_rest_frame(m, m->n_frames - 1, "last frame");
                int hips = joint(m, "Hips");
                const float *h0 = affect_motion_at(m, 0, (uint32_t)hips);
                const float *h1 = affect_motion_at(m, m->n_frames - 1, (uint32_t)hips);
                for (uint32_t j = 0; j < N_JOINTS; j++) {
                    const float *p0 = affect_motion_at(m, 0, j);
                    const float *p1 = affect_motion_at(m, m->n_frames - 1, j);
                    const float *q = affect_motion_at(m, 5, j); /* still holding */
                    for (int ax = 0; ax < 3; ax++) {
                        double d = (p1[ax] - h1[ax]) - (p0[ax] - h0[ax]);
                        if (fabs(d) > 0.005)
                            fail_msg("%s %s %llu: joint %s ends %g m away from its start pose",
                                     affect_synth_actions[a], affect_synth_emotions[e],
                                     (unsigned long long)seed, m->names[j], d);
                        if (fabs(q[ax] - p0[ax]) > 0.004)
                            fail_msg("%s: joint %s moves in the initial hold",
                                     affect_synth_actions[a], m->names[j]);
                    }
                }
                if (a == 2) { /* walk: forward along +z, not sideways */
                    double dz = h1[2] - h0[2], dx = h1[0] - h0[0];
                    if (!(dz > 1.2 && dz < 5.0 && fabs(dx) < 0.05))
                        fail_msg("walk %s: travelled dx %g dz %g", affect_synth_emotions[e], dx,
                                 dz);
                } else {
                    assert_true(fabs(h1[2] - h0[2]) < 0.005);
                }
                affect_motion_free(m);
            }
}

static void test_bone_lengths_and_floor(void **state)
{
    (void)state;
    affect_synth_options opt;
    affect_synth_options_default(&opt);
    opt.noise = 0.0;
    for (int a = 0; a < N_ACTIONS; a++)
        for (int e = 0; e < N_EMOTIONS; e++)
            for (uint64_t seed = 1; seed <= N_SEEDS; seed++) {
                affect_motion *m =
                    synth_ok(affect_synth_actions[a], affect_synth_emotions[e], seed, &opt);
                int toes[2] = {joint(m, "Toes_L"), joint(m, "Toes_R")};
                for (uint32_t j = 1; j < m->n_joints; j++) {
                    uint32_t p = (uint32_t)m->parents[j];
                    double l0 = dist(affect_motion_at(m, 0, j), affect_motion_at(m, 0, p));
                    if (l0 == 0.0)
                        continue;
                    for (uint32_t t = 1; t < m->n_frames; t++) {
                        double l = dist(affect_motion_at(m, t, j), affect_motion_at(m, t, p));
                        if (fabs(l - l0) > 1e-5 * l0)
                            fail_msg("%s %s: bone %s length %.9g at frame %u, %.9g at 0",
                                     affect_synth_actions[a], affect_synth_emotions[e], m->names[j],
                                     l, t, l0);
                    }
                }
                if (a != 2) { /* standing actions: the feet stay planted */
                    static const char *const feet[] = {"Foot_L", "Toes_L", "Toes_L_end",
                                                       "Foot_R", "Toes_R", "Toes_R_end"};
                    for (int f = 0; f < 6; f++) {
                        uint32_t j = (uint32_t)joint(m, feet[f]);
                        for (uint32_t t = 1; t < m->n_frames; t++)
                            if (dist(affect_motion_at(m, t, j), affect_motion_at(m, 0, j)) > 1e-4)
                                fail_msg("%s %s: %s moves at frame %u", affect_synth_actions[a],
                                         affect_synth_emotions[e], feet[f], t);
                    }
                }
                for (uint32_t t = 0; t < m->n_frames; t++) {
                    /* nothing below the floor */
                    for (uint32_t j = 0; j < m->n_joints; j++)
                        assert_true(affect_motion_at(m, t, j)[1] > -0.001f);
                    /* a planted foot does not skate */
                    for (int s = 0; t > 0 && s < 2; s++) {
                        const float *p1 = affect_motion_at(m, t, (uint32_t)toes[s]);
                        const float *p0 = affect_motion_at(m, t - 1, (uint32_t)toes[s]);
                        if (p0[1] < 0.0105f && p1[1] < 0.0105f) {
                            double v = hypot(p1[0] - p0[0], p1[2] - p0[2]) * m->fps;
                            if (v > 0.05)
                                fail_msg("%s: planted toes slide at %g m/s", m->names[toes[s]], v);
                        }
                    }
                }
                affect_motion_free(m);
            }
}

/* Samples with a planted foot during a walk exist (the foot test above is not vacuous), and
 * the swinging foot clears the floor. */
static void test_walk_gait(void **state)
{
    (void)state;
    affect_synth_options opt;
    affect_synth_options_default(&opt);
    opt.noise = 0.0;
    affect_motion *m = synth_ok("walk", "neutral", 3, &opt);
    int toes = joint(m, "Toes_L"), foot = joint(m, "Foot_L"), knee = joint(m, "LowerLeg_L");
    int hip = joint(m, "UpperLeg_L"), hips = joint(m, "Hips");
    uint32_t planted = 0;
    double max_ankle = 0, max_knee = 0, min_hips = 10, max_hips = 0;
    for (uint32_t t = 0; t < m->n_frames; t++) {
        if (affect_motion_at(m, t, (uint32_t)toes)[1] < 0.0105f)
            planted++;
        double y = affect_motion_at(m, t, (uint32_t)foot)[1];
        if (y > max_ankle)
            max_ankle = y;
        const float *h = affect_motion_at(m, t, (uint32_t)hip);
        const float *k = affect_motion_at(m, t, (uint32_t)knee);
        const float *f = affect_motion_at(m, t, (uint32_t)foot);
        double u[3], v[3];
        for (int a = 0; a < 3; a++) {
            u[a] = (double)k[a] - h[a];
            v[a] = (double)f[a] - k[a];
        }
        double c = (u[0] * v[0] + u[1] * v[1] + u[2] * v[2]) /
                   sqrt((u[0] * u[0] + u[1] * u[1] + u[2] * u[2]) *
                        (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]));
        double flex = acos(fmin(1.0, c)) * 180.0 / 3.14159265358979;
        if (flex > max_knee)
            max_knee = flex;
        double hy = affect_motion_at(m, t, (uint32_t)hips)[1];
        min_hips = fmin(min_hips, hy);
        max_hips = fmax(max_hips, hy);
    }
    assert_true(planted > m->n_frames / 3);
    assert_true(max_ankle > 0.13);               /* the foot is lifted in swing */
    assert_true(max_knee > 35 && max_knee < 75); /* the knee flexes in swing */
    double bob = max_hips - min_hips;            /* the Hips bob */
    assert_true(bob > 0.02 && bob < 0.09);
    affect_motion_free(m);
}

static void test_emotion_signatures(void **state)
{
    (void)state;
    affect_synth_options opt;
    affect_synth_options_default(&opt);
    for (int a = 0; a < N_ACTIONS; a++)
        for (uint64_t seed = 1; seed <= N_SEEDS; seed++) {
            double w[N_EMOTIONS], tm[N_EMOTIONS], dur[N_EMOTIONS], head_up[N_EMOTIONS],
                head_fwd[N_EMOTIONS];
            for (int e = 0; e < N_EMOTIONS; e++) {
                affect_motion *m =
                    synth_ok(affect_synth_actions[a], affect_synth_emotions[e], seed, &opt);
                effort(m, &w[e], &tm[e]);
                dur[e] = affect_motion_duration(m);
                head_up[e] = mean_offset(m, "Head", "Chest", 1);
                head_fwd[e] = mean_offset(m, "Head", "Hips", 2);
                affect_motion_free(m);
            }
            const char *act = affect_synth_actions[a];
            unsigned long long sd = (unsigned long long)seed;
            /* Weight and Time: angry > neutral > sad, each by at least 30 % */
            if (!(w[ANGRY] > 1.3 * w[NEUTRAL] && w[NEUTRAL] > 1.3 * w[SAD]))
                fail_msg("%s seed %llu: Weight angry %g neutral %g sad %g", act, sd, w[ANGRY],
                         w[NEUTRAL], w[SAD]);
            if (!(tm[ANGRY] > 1.3 * tm[NEUTRAL] && tm[NEUTRAL] > 1.3 * tm[SAD]))
                fail_msg("%s seed %llu: Time angry %g neutral %g sad %g", act, sd, tm[ANGRY],
                         tm[NEUTRAL], tm[SAD]);
            if (!(w[HAPPY] > 1.2 * w[NEUTRAL]))
                fail_msg("%s seed %llu: Weight happy %g neutral %g", act, sd, w[HAPPY], w[NEUTRAL]);
            /* sad lingers, angry is quick */
            if (!(dur[SAD] > dur[NEUTRAL] + 0.5 && dur[NEUTRAL] > dur[ANGRY] + 0.3))
                fail_msg("%s seed %llu: durations sad %g neutral %g angry %g", act, sd, dur[SAD],
                         dur[NEUTRAL], dur[ANGRY]);
            /* drooped head for sad, head forward for angry */
            if (!(head_up[SAD] < head_up[NEUTRAL] - 0.005))
                fail_msg("%s seed %llu: head above chest sad %g neutral %g", act, sd, head_up[SAD],
                         head_up[NEUTRAL]);
            if (!(head_fwd[ANGRY] > head_fwd[NEUTRAL] + 0.008))
                fail_msg("%s seed %llu: head ahead of hips angry %g neutral %g", act, sd,
                         head_fwd[ANGRY], head_fwd[NEUTRAL]);
        }
}

/* Happy looks up, sad looks down: the top of the head relative to the head joint. */
static void test_head_orientation(void **state)
{
    (void)state;
    affect_synth_options opt;
    affect_synth_options_default(&opt);
    for (int a = 0; a < N_ACTIONS; a++) {
        double tilt[N_EMOTIONS];
        for (int e = 0; e < N_EMOTIONS; e++) {
            affect_motion *m = synth_ok(affect_synth_actions[a], affect_synth_emotions[e], 2, &opt);
            /* mean height of the head's top above the head joint: lower when pitched */
            tilt[e] = mean_offset(m, "Head_end", "Head", 1);
            affect_motion_free(m);
        }
        assert_true(tilt[SAD] < tilt[NEUTRAL] - 0.005);
    }
    /* happy bounces: the Hips go up and down while the neutral performer stands still */
    opt.noise = 0.0;
    for (int e = NEUTRAL; e <= HAPPY; e++) {
        affect_motion *m = synth_ok("wave", affect_synth_emotions[e], 2, &opt);
        uint32_t hips = (uint32_t)joint(m, "Hips");
        double lo = 10, hi = -10;
        int cycles = 0;
        for (uint32_t t = 0; t < m->n_frames; t++) {
            double y = affect_motion_at(m, t, hips)[1];
            lo = fmin(lo, y);
            hi = fmax(hi, y);
            /* count the descents through 1 cm below the rest height */
            if (t > 0) {
                double y0 = affect_motion_at(m, t - 1, hips)[1];
                double mark = affect_motion_at(m, 0, hips)[1] - 0.01;
                cycles += y0 >= mark && y < mark;
            }
        }
        if (e == NEUTRAL) {
            assert_true(hi - lo < 1e-4);
        } else {
            double dur = affect_motion_duration(m);
            assert_true(hi - lo > 0.015 && hi - lo < 0.03);
            assert_true(cycles >= 1.0 * (dur - 1.5) && cycles <= 2.0 * dur); /* about 2 Hz */
        }
        affect_motion_free(m);
    }
    opt.noise = 0.0003;

    /* happy lifts the chest and head: the top of the head is further back than neutral's */
    affect_motion *n = synth_ok("knock", "neutral", 2, &opt);
    affect_motion *h = synth_ok("knock", "happy", 2, &opt);
    assert_true(mean_offset(h, "Head_end", "Hips", 2) < mean_offset(n, "Head_end", "Hips", 2));
    affect_motion_free(n);
    affect_motion_free(h);
}

static void test_fps_and_noise(void **state)
{
    (void)state;
    affect_synth_options opt;
    affect_synth_options_default(&opt);
    opt.noise = 0.0;
    affect_motion *m30 = synth_ok("wave", "happy", 4, &opt);
    opt.fps = 60.0;
    affect_motion *m60 = synth_ok("wave", "happy", 4, &opt);
    assert_true(m60->fps == 60.0);
    tu_assert_near(affect_motion_duration(m60), affect_motion_duration(m30), 2.0 / 30.0);
    /* the same movement sampled twice as often: frame 2k at 60 fps is frame k at 30 */
    for (uint32_t t = 0; t < m30->n_frames && 2 * t < m60->n_frames; t++)
        for (uint32_t j = 0; j < N_JOINTS; j++)
            for (int a = 0; a < 3; a++)
                tu_assert_near(affect_motion_at(m60, 2 * t, j)[a], affect_motion_at(m30, t, j)[a],
                               1e-6);
    opt.fps = 12.5;
    affect_motion *m12 = synth_ok("wave", "happy", 4, &opt);
    assert_true(m12->fps == 12.5);
    tu_assert_near(affect_motion_duration(m12), affect_motion_duration(m30), 2.0 / 12.5);

    /* the noise is Gaussian with the requested standard deviation */
    opt.fps = 30.0;
    opt.noise = 0.0003;
    affect_motion *noisy = synth_ok("wave", "happy", 4, &opt);
    assert_int_equal(noisy->n_frames, m30->n_frames);
    size_t n = (size_t)m30->n_frames * N_JOINTS * 3;
    double ss = 0, s = 0;
    for (size_t i = 0; i < n; i++) {
        double d = (double)noisy->pos[i] - m30->pos[i];
        s += d;
        ss += d * d;
    }
    double sd = sqrt(ss / n - (s / n) * (s / n));
    assert_true(sd > 0.00027 && sd < 0.00033);
    assert_true(fabs(s / n) < 0.00003);
    affect_motion_free(m30);
    affect_motion_free(m60);
    affect_motion_free(m12);
    affect_motion_free(noisy);
}

static void test_determinism_and_performers(void **state)
{
    (void)state;
    affect_synth_options opt;
    affect_synth_options_default(&opt);
    for (int a = 0; a < N_ACTIONS; a++) {
        affect_motion *m1 = synth_ok(affect_synth_actions[a], "angry", 42, &opt);
        affect_motion *m2 = synth_ok(affect_synth_actions[a], "angry", 42, &opt);
        assert_int_equal(m1->n_frames, m2->n_frames);
        assert_memory_equal(m1->pos, m2->pos, (size_t)m1->n_frames * N_JOINTS * 3 * sizeof(float));
        /* NULL options are the defaults */
        affect_motion *m3 = synth_ok(affect_synth_actions[a], "angry", 42, NULL);
        assert_int_equal(m1->n_frames, m3->n_frames);
        assert_memory_equal(m1->pos, m3->pos, (size_t)m1->n_frames * N_JOINTS * 3 * sizeof(float));
        affect_motion_free(m2);
        affect_motion_free(m3);

        /* another seed is another performer: other limb lengths, other timing */
        affect_motion *o = synth_ok(affect_synth_actions[a], "angry", 43, &opt);
        int ua = joint(m1, "UpperArm_L"), la = joint(m1, "LowerArm_L");
        double arm1 =
            dist(affect_motion_at(m1, 0, (uint32_t)ua), affect_motion_at(m1, 0, (uint32_t)la));
        double arm2 =
            dist(affect_motion_at(o, 0, (uint32_t)ua), affect_motion_at(o, 0, (uint32_t)la));
        assert_true(fabs(arm1 - arm2) > 1e-4);
        assert_true(arm1 > 0.29 * 0.94 - 0.002 && arm1 < 0.29 * 1.06 + 0.002);
        size_t n = (size_t)(m1->n_frames < o->n_frames ? m1->n_frames : o->n_frames) * N_JOINTS * 3;
        assert_true(memcmp(m1->pos, o->pos, n * sizeof(float)) != 0);
        /* left and right limbs are equally long */
        int ur = joint(o, "UpperArm_R"), lr = joint(o, "LowerArm_R");
        int kl = joint(o, "LowerLeg_L"), fl = joint(o, "Foot_L");
        int kr = joint(o, "LowerLeg_R"), fr = joint(o, "Foot_R");
        tu_assert_near(
            dist(affect_motion_at(o, 0, (uint32_t)ua), affect_motion_at(o, 0, (uint32_t)la)),
            dist(affect_motion_at(o, 0, (uint32_t)ur), affect_motion_at(o, 0, (uint32_t)lr)),
            0.003);
        tu_assert_near(
            dist(affect_motion_at(o, 0, (uint32_t)kl), affect_motion_at(o, 0, (uint32_t)fl)),
            dist(affect_motion_at(o, 0, (uint32_t)kr), affect_motion_at(o, 0, (uint32_t)fr)),
            0.003);
        affect_motion_free(m1);
        affect_motion_free(o);
    }
    /* seeds vary the durations too (tempo, holds) */
    int differ = 0;
    affect_motion *base = synth_ok("knock", "neutral", 1, &opt);
    for (uint64_t seed = 2; seed <= 6; seed++) {
        affect_motion *m = synth_ok("knock", "neutral", seed, &opt);
        differ += m->n_frames != base->n_frames;
        affect_motion_free(m);
    }
    assert_true(differ >= 3);
    affect_motion_free(base);
}

static void test_intensity(void **state)
{
    (void)state;
    affect_synth_options opt;
    affect_synth_options_default(&opt);
    opt.intensity = 0.0;
    for (int a = 0; a < N_ACTIONS; a++) {
        affect_motion *n = synth_ok(affect_synth_actions[a], "neutral", 9, &opt);
        for (int e = 1; e < N_EMOTIONS; e++) {
            affect_motion *m = synth_ok(affect_synth_actions[a], affect_synth_emotions[e], 9, &opt);
            /* the same tempo and the same posture: the same motion */
            assert_int_equal(m->n_frames, n->n_frames);
            size_t cnt = (size_t)m->n_frames * N_JOINTS * 3;
            for (size_t i = 0; i < cnt; i++)
                tu_assert_near(m->pos[i], n->pos[i], 1e-6);
            affect_motion_free(m);
        }
        /* at intensity 0 neutral is neutral at any intensity */
        opt.intensity = 1.0;
        affect_motion *n1 = synth_ok(affect_synth_actions[a], "neutral", 9, &opt);
        assert_int_equal(n1->n_frames, n->n_frames);
        assert_memory_equal(n1->pos, n->pos, (size_t)n->n_frames * N_JOINTS * 3 * sizeof(float));
        affect_motion_free(n1);
        affect_motion_free(n);
        opt.intensity = 0.0;
    }
    /* a stronger emotion is slower (sad) or quicker (angry), still valid */
    double prev_sad = 0, prev_angry = 1e9;
    for (int i = 0; i <= 4; i++) {
        opt.intensity = 0.5 * i;
        affect_motion *s = synth_ok("bow", "sad", 5, &opt);
        affect_motion *g = synth_ok("bow", "angry", 5, &opt);
        affect_error err;
        assert_int_equal(affect_motion_validate(s, &err), AFFECT_OK);
        assert_int_equal(affect_motion_validate(g, &err), AFFECT_OK);
        double ds = affect_motion_duration(s), dg = affect_motion_duration(g);
        if (i > 0) {
            assert_true(ds > prev_sad);
            assert_true(dg < prev_angry);
        }
        prev_sad = ds;
        prev_angry = dg;
        affect_motion_free(s);
        affect_motion_free(g);
    }
}

static void expect_error(const char *action, const char *emotion, const affect_synth_options *opt,
                         affect_status status, const char *msg)
{
    affect_motion *m = (affect_motion *)(uintptr_t)1;
    affect_error err;
    affect_error_clear(&err);
    assert_int_equal(affect_motion_synth(action, emotion, 1, opt, &m, &err), status);
    assert_null(m);
    assert_int_equal(err.status, status);
    assert_string_equal(err.msg, msg);
}

static void test_errors(void **state)
{
    (void)state;
    affect_synth_options opt;
    affect_synth_options_default(&opt);
    expect_error("jump", "happy", &opt, AFFECT_ERR_INVALID,
                 "unknown action \"jump\" (expected knock, wave, walk, bow)");
    expect_error("Knock", "happy", &opt, AFFECT_ERR_INVALID,
                 "unknown action \"Knock\" (expected knock, wave, walk, bow)");
    expect_error("", "happy", &opt, AFFECT_ERR_INVALID,
                 "unknown action \"\" (expected knock, wave, walk, bow)");
    expect_error("walk", "fear", &opt, AFFECT_ERR_INVALID,
                 "unknown emotion \"fear\" (expected neutral, happy, sad, angry)");
    expect_error(NULL, "sad", &opt, AFFECT_ERR_INVALID, "action is NULL");
    expect_error("walk", NULL, &opt, AFFECT_ERR_INVALID, "emotion is NULL");

    opt.intensity = 3.0;
    expect_error("walk", "sad", &opt, AFFECT_ERR_INVALID,
                 "intensity must be between 0 and 2, got 3");
    opt.intensity = -0.5;
    expect_error("walk", "sad", &opt, AFFECT_ERR_INVALID,
                 "intensity must be between 0 and 2, got -0.5");
    opt.intensity = NAN;
    expect_error("walk", "sad", &opt, AFFECT_ERR_INVALID,
                 "intensity must be between 0 and 2, got nan");
    affect_synth_options_default(&opt);
    opt.fps = 0.0;
    expect_error("bow", "sad", &opt, AFFECT_ERR_INVALID,
                 "fps must be greater than 0 and at most 1000, got 0");
    opt.fps = 1000.5;
    expect_error("bow", "sad", &opt, AFFECT_ERR_INVALID,
                 "fps must be greater than 0 and at most 1000, got 1000.5");
    opt.fps = INFINITY;
    expect_error("bow", "sad", &opt, AFFECT_ERR_INVALID,
                 "fps must be greater than 0 and at most 1000, got inf");
    affect_synth_options_default(&opt);
    opt.noise = 0.5;
    expect_error("knock", "angry", &opt, AFFECT_ERR_INVALID,
                 "noise must be between 0 and 0.1, got 0.5");
    opt.noise = -0.001;
    expect_error("knock", "angry", &opt, AFFECT_ERR_INVALID,
                 "noise must be between 0 and 0.1, got -0.001");

    /* the limits themselves are accepted */
    affect_synth_options_default(&opt);
    opt.intensity = 2.0;
    opt.noise = 0.1;
    opt.fps = 1000.0;
    affect_motion *m = synth_ok("knock", "angry", 1, &opt);
    assert_true(m->fps == 1000.0);
    affect_motion_free(m);
}

/* ---- out of memory: every allocation of a synthesis fails in turn (tu_oom_sweep) ---- */

typedef struct synth_oom {
    const char *action;
    const affect_synth_options *opt;
    affect_motion *m;
} synth_oom;

static affect_status oom_synth(void *ctx, affect_error *err)
{
    synth_oom *c = ctx;
    c->m = NULL;
    return affect_motion_synth(c->action, "happy", 3, c->opt, &c->m, err);
}

static void oom_synth_finish(void *ctx, affect_status st)
{
    synth_oom *c = ctx;
    if (st != AFFECT_OK) {
        assert_null(c->m);
        return;
    }
    assert_non_null(c->m);
    assert_true(tu_oom_outstanding() > 0);
    affect_motion_free(c->m);
}

static void test_out_of_memory(void **state)
{
    (void)state;
    affect_synth_options opt;
    affect_synth_options_default(&opt);
    for (int a = 0; a < N_ACTIONS; a++) {
        synth_oom c = {affect_synth_actions[a], &opt, NULL};
        long failures = tu_oom_sweep(oom_synth, &c, oom_synth_finish, NULL);
        /* every allocation of the motion was exercised */
        if (failures <= 20 || failures > 10000)
            fail_msg("%s: %ld allocations failed in turn", c.action, failures);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_names_and_defaults),
        cmocka_unit_test(test_structure_every_combination),
        cmocka_unit_test(test_bone_lengths_and_floor),
        cmocka_unit_test(test_walk_gait),
        cmocka_unit_test(test_emotion_signatures),
        cmocka_unit_test(test_head_orientation),
        cmocka_unit_test(test_fps_and_noise),
        cmocka_unit_test(test_determinism_and_performers),
        cmocka_unit_test(test_intensity),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_out_of_memory),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
