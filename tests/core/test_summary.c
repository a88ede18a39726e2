/*
 * test_summary.c — kinematic summaries and motion-level descriptors (affect/summary.h), on
 * motions whose every summary is known by hand: a body walking straight ahead at constant
 * speed, and the same body turning in place at a constant rate (which the body frame must see
 * as still).
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <string.h>
#include <cmocka.h>

#include "affect/laban.h"
#include "affect/summary.h"
#include "testutil.h"

enum { J = 10, T = 11 };

/* A 10-joint body, 11 frames at 10 fps, y up, facing +z (lateral vector left − right = +x),
 * right arm 0.3 + 0.2 = 0.5 long (the body size). Frame t: the posture turned by rate · t
 * radians about y (positive: counter-clockwise seen from above) and moved by speed · t / 10
 * along +z. */
static affect_motion *make_body(double speed, double rate)
{
    static const char *const names[J] = {"Hips",   "Head",   "UpperArm_R", "LowerArm_R",
                                         "Hand_R", "Hand_L", "UpperLeg_L", "UpperLeg_R",
                                         "Foot_L", "Foot_R"};
    static const int32_t parents[J] = {-1, 0, 0, 2, 3, 0, 0, 0, 6, 7};
    static const double pose[J][3] = {
        {0, 1, 0},     {0, 1.6, 0.1}, {-0.2, 1.4, 0}, {-0.5, 1.4, 0},  {-0.5, 1.2, 0},
        {0.5, 1.2, 0}, {0.1, 0.9, 0}, {-0.1, 0.9, 0}, {0.15, 0.05, 0}, {-0.15, 0.05, 0}};
    affect_motion *m = NULL;
    affect_error err;
    assert_int_equal(affect_motion_create(T, J, 10.0, &m, &err), AFFECT_OK);
    for (uint32_t j = 0; j < J; j++) {
        assert_int_equal(affect_motion_set_name(m, j, names[j], strlen(names[j]), &err), AFFECT_OK);
        m->parents[j] = parents[j];
    }
    for (uint32_t t = 0; t < T; t++) {
        double a = rate * t, c = cos(a),
               s = sin(a); /* +a about y: (x, z) → (x c + z s, −x s + z c) */
        for (uint32_t j = 0; j < J; j++) {
            float *p = affect_motion_at(m, t, j);
            p[0] = (float)(pose[j][0] * c + pose[j][2] * s);
            p[1] = (float)pose[j][1];
            p[2] = (float)(-pose[j][0] * s + pose[j][2] * c + speed * t / 10.0);
        }
    }
    return m;
}

static double get(const double *v, const char *name)
{
    for (int i = 0; i < AFFECT_SUMMARY_N; i++)
        if (strcmp(affect_summary_names[i], name) == 0)
            return v[i];
    fail_msg("no summary named %s", name);
    return NAN;
}

static void test_walking_straight(void **state)
{
    (void)state;
    affect_motion *m = make_body(2.0, 0.0);
    double v[AFFECT_SUMMARY_N];
    affect_error err;
    assert_int_equal(affect_motion_summary(m, 1, v, NULL, &err), AFFECT_OK);
    tu_assert_near(get(v, "duration"), 1.1, 1e-12);
    tu_assert_near(get(v, "root_speed"), 2.0 / 0.5, 1e-5); /* 2 m/s in arms of 0.5 m */
    tu_assert_near(get(v, "root_speed_p90"), 4.0, 1e-5);
    tu_assert_near(get(v, "root_bounce"), 0.0, 1e-9);
    tu_assert_near(get(v, "turn_rate"), 0.0, 1e-6);
    tu_assert_near(get(v, "net_turn"), 0.0, 1e-6);
    static const char *const still[] = {"head_speed",       "left_hand_speed",
                                        "right_hand_speed", "left_foot_speed",
                                        "right_foot_speed", "right_hand_speed_p90"};
    for (size_t i = 0; i < sizeof still / sizeof still[0]; i++) /* rigid: still in the body */
        tu_assert_near(get(v, still[i]), 0.0, 1e-4);
    tu_assert_near(get(v, "head_height"), 0.6 / 0.5, 1e-5);
    tu_assert_near(get(v, "head_forward"), 0.1 / 0.5, 1e-5); /* forward is +z here */
    tu_assert_near(get(v, "hand_height"), 0.2 / 0.5, 1e-5);
    tu_assert_near(get(v, "hand_spread"), 1.0 / 0.5, 1e-5);
    tu_assert_near(get(v, "foot_spread"), 0.3 / 0.5, 1e-5);
    affect_motion_free(m);
}

/* Turning in place: the body frame removes the turn, so the effectors are still; the turning
 * rate and the net turn are the rotation's. */
static void test_turning_in_place(void **state)
{
    (void)state;
    affect_motion *m = make_body(0.0, 0.1);
    double v[AFFECT_SUMMARY_N];
    affect_error err;
    assert_int_equal(affect_motion_summary(m, 1, v, NULL, &err), AFFECT_OK);
    tu_assert_near(get(v, "turn_rate"), 0.1 * 10.0, 1e-5);
    tu_assert_near(get(v, "net_turn"), 0.1 * (T - 1), 1e-5);
    tu_assert_near(get(v, "root_speed"), 0.0, 1e-5);
    tu_assert_near(get(v, "left_hand_speed"), 0.0, 1e-4);
    tu_assert_near(get(v, "hand_spread"), 2.0, 1e-5);
    affect_motion_free(m);
}

/* Descriptors: sizes, the log scale, the mirror swap, and the errors. */
static void test_descriptors(void **state)
{
    (void)state;
    assert_int_equal(affect_descriptors_dim(0), 0);
    assert_int_equal(affect_descriptors_dim(AFFECT_DESC_KINEMATICS), AFFECT_SUMMARY_N);
    assert_int_equal(affect_descriptors_dim(AFFECT_DESC_LABAN), AFFECT_LABAN_N);
    assert_int_equal(affect_descriptors_dim(8), 0);
    affect_motion *m = make_body(2.0, 0.0);
    double s[AFFECT_SUMMARY_N], d[AFFECT_SUMMARY_N + AFFECT_LABAN_N],
        e[AFFECT_SUMMARY_N + AFFECT_LABAN_N];
    affect_error err;
    assert_int_equal(affect_motion_summary(m, 1, s, NULL, &err), AFFECT_OK);
    assert_int_equal(affect_descriptors(AFFECT_DESC_ALL, m, 1, d, NULL, &err), AFFECT_OK);
    for (int i = 0; i < AFFECT_SUMMARY_N; i++)
        tu_assert_near(d[i], log1p(s[i]), 1e-12); /* all summaries are ≥ 0 */
    for (int i = 0; i < AFFECT_SUMMARY_N + AFFECT_LABAN_N; i++)
        assert_true(isfinite(d[i]));
    affect_descriptors_mirror(AFFECT_DESC_ALL, d, e);
    assert_true(e[7] == d[8] && e[8] == d[7] && e[14] == d[15]); /* hand and foot speeds */
    int lh = AFFECT_SUMMARY_N + affect_laban_index("WeightLHand"),
        rh = AFFECT_SUMMARY_N + affect_laban_index("WeightRHand"),
        dl = AFFECT_SUMMARY_N + affect_laban_index("ShapeDirLHand"),
        dr = AFFECT_SUMMARY_N + affect_laban_index("ShapeDirRHand");
    assert_true(e[lh] == d[rh] && e[rh] == d[lh] && e[dl] == d[dr]);
    affect_descriptors_mirror(AFFECT_DESC_ALL, e, e); /* in place, twice = the identity */
    assert_memory_equal(e, d, sizeof d);
    assert_int_equal(affect_descriptors(4, m, 1, d, NULL, &err), AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "descriptors must be a combination of kinematics and laban");
    assert_int_equal(affect_motion_summary(m, 3, s, NULL, &err), AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "up axis must be x, y or z");
    affect_motion_free(m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_walking_straight),
        cmocka_unit_test(test_turning_in_place),
        cmocka_unit_test(test_descriptors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
