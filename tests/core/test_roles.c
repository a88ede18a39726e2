/*
 * test_roles.c — body-part roles from the naming conventions we promise (this corpus,
 * CMU/Mixamo, short forms), overrides, and pose normalization (translation, heading, arm
 * scale) on a hand-built skeleton.
 */
#include <math.h>
#include <string.h>

#include "testutil.h"
#include "affect/normalize.h"

static affect_motion *skeleton(const char *const *names, uint32_t n)
{
    affect_motion *m = NULL;
    affect_error err;
    assert_int_equal(affect_motion_create(1, n, 30, &m, &err), AFFECT_OK);
    for (uint32_t j = 0; j < n; j++)
        assert_int_equal(affect_motion_set_name(m, j, names[j], strlen(names[j]), &err), AFFECT_OK);
    return m;
}

static void expect_role(const affect_motion *m, const affect_roles *r, affect_role role,
                        const char *joint)
{
    int32_t j = r->joint[role];
    if (!joint) {
        if (j >= 0)
            fail_msg("role %s resolved to %s, expected none", affect_role_name(role), m->names[j]);
        return;
    }
    if (j < 0)
        fail_msg("role %s unresolved, expected %s", affect_role_name(role), joint);
    if (strcmp(m->names[j], joint) != 0)
        fail_msg("role %s resolved to %s, expected %s", affect_role_name(role), m->names[j], joint);
}

static void test_corpus_names(void **state)
{
    static const char *const names[] = {
        "joint_Root", "Hips",       "Spine",      "Chest",      "Neck",       "Head",
        "Head_end",   "Shoulder_L", "UpperArm_L", "LowerArm_L", "Hand_L",     "Hand_L_end",
        "Shoulder_R", "UpperArm_R", "LowerArm_R", "Hand_R",     "Hand_R_end", "UpperLeg_L",
        "LowerLeg_L", "Foot_L",     "Toes_L",     "Toes_L_end", "UpperLeg_R", "LowerLeg_R",
        "Foot_R",     "Toes_R",     "Toes_R_end"};
    affect_motion *m = skeleton(names, sizeof names / sizeof names[0]);
    affect_roles r;
    affect_roles_resolve(m, &r);
    const char *want[AFFECT_ROLE_COUNT] = {
        "Hips",   "Spine",      "Chest",      "Neck",   "Head",       "UpperArm_L", "LowerArm_L",
        "Hand_L", "UpperArm_R", "LowerArm_R", "Hand_R", "UpperLeg_L", "LowerLeg_L", "Foot_L",
        "Toes_L", "UpperLeg_R", "LowerLeg_R", "Foot_R", "Toes_R"};
    for (int k = 0; k < AFFECT_ROLE_COUNT; k++)
        expect_role(m, &r, (affect_role)k, want[k]);
    affect_motion_free(m);
}

static void test_mixamo_cmu_names(void **state)
{
    static const char *const names[] = {
        "mixamorig:Hips",          "mixamorig:Spine",        "mixamorig:Spine1",
        "mixamorig:Spine2",        "mixamorig:Neck",         "mixamorig:Head",
        "mixamorig:HeadTop_End",   "mixamorig:LeftShoulder", "mixamorig:LeftArm",
        "mixamorig:LeftForeArm",   "mixamorig:LeftHand",     "mixamorig:LeftHandIndex1",
        "mixamorig:RightShoulder", "mixamorig:RightArm",     "mixamorig:RightForeArm",
        "mixamorig:RightHand",     "mixamorig:LeftUpLeg",    "mixamorig:LeftLeg",
        "mixamorig:LeftFoot",      "mixamorig:LeftToeBase",  "mixamorig:RightUpLeg",
        "mixamorig:RightLeg",      "mixamorig:RightFoot",    "mixamorig:RightToeBase"};
    affect_motion *m = skeleton(names, sizeof names / sizeof names[0]);
    affect_roles r;
    affect_roles_resolve(m, &r);
    expect_role(m, &r, AFFECT_ROLE_PELVIS, "mixamorig:Hips");
    expect_role(m, &r, AFFECT_ROLE_SPINE, "mixamorig:Spine");
    expect_role(m, &r, AFFECT_ROLE_CHEST, "mixamorig:Spine2");
    expect_role(m, &r, AFFECT_ROLE_HEAD, "mixamorig:Head");
    expect_role(m, &r, AFFECT_ROLE_LEFT_SHOULDER, "mixamorig:LeftArm");
    expect_role(m, &r, AFFECT_ROLE_LEFT_ELBOW, "mixamorig:LeftForeArm");
    expect_role(m, &r, AFFECT_ROLE_LEFT_HAND, "mixamorig:LeftHand");
    expect_role(m, &r, AFFECT_ROLE_RIGHT_HAND, "mixamorig:RightHand");
    expect_role(m, &r, AFFECT_ROLE_LEFT_HIP, "mixamorig:LeftUpLeg");
    expect_role(m, &r, AFFECT_ROLE_LEFT_KNEE, "mixamorig:LeftLeg");
    expect_role(m, &r, AFFECT_ROLE_RIGHT_TOE, "mixamorig:RightToeBase");
    affect_motion_free(m);
}

static void test_short_names(void **state)
{
    static const char *const names[] = {"pelvis",    "l_wrist", "RWrist",   "lhand_unused",
                                        "lknee",     "R.Ankle", "left_toe", "neck1",
                                        "LShoulder", "r_elbow", "RightHip"};
    affect_motion *m = skeleton(names, sizeof names / sizeof names[0]);
    affect_roles r;
    affect_roles_resolve(m, &r);
    expect_role(m, &r, AFFECT_ROLE_PELVIS, "pelvis");
    expect_role(m, &r, AFFECT_ROLE_LEFT_HAND, "l_wrist");
    expect_role(m, &r, AFFECT_ROLE_RIGHT_HAND, "RWrist");
    expect_role(m, &r, AFFECT_ROLE_LEFT_KNEE, "lknee");
    expect_role(m, &r, AFFECT_ROLE_RIGHT_FOOT, "R.Ankle");
    expect_role(m, &r, AFFECT_ROLE_LEFT_TOE, "left_toe");
    expect_role(m, &r, AFFECT_ROLE_NECK, "neck1");
    expect_role(m, &r, AFFECT_ROLE_LEFT_SHOULDER, "LShoulder");
    expect_role(m, &r, AFFECT_ROLE_RIGHT_ELBOW, "r_elbow");
    expect_role(m, &r, AFFECT_ROLE_RIGHT_HIP, "RightHip");
    expect_role(m, &r, AFFECT_ROLE_HEAD, NULL);
    expect_role(m, &r, AFFECT_ROLE_SPINE, NULL);
    affect_motion_free(m);
}

static void test_override_and_names(void **state)
{
    static const char *const names[] = {"a", "b", "MyHand"};
    affect_motion *m = skeleton(names, 3);
    affect_roles r;
    affect_error err;
    affect_roles_resolve(m, &r);
    expect_role(m, &r, AFFECT_ROLE_PELVIS, "a"); /* the first root when nothing matches */
    assert_int_equal(affect_roles_set(m, &r, "left_wrist", "myhand", &err), AFFECT_OK);
    expect_role(m, &r, AFFECT_ROLE_LEFT_HAND, "MyHand");
    assert_int_equal(affect_roles_set(m, &r, "left_hand", NULL, &err), AFFECT_OK);
    expect_role(m, &r, AFFECT_ROLE_LEFT_HAND, NULL);
    assert_int_equal(affect_roles_set(m, &r, "hand", "b", &err), AFFECT_ERR_INVALID);
    assert_true(strncmp(err.msg, "unknown role \"hand\" (expected pelvis", 36) == 0);
    assert_int_equal(affect_roles_set(m, &r, "head", "zz", &err), AFFECT_ERR_MISSING);
    assert_string_equal(err.msg, "role head: no joint named \"zz\"");
    for (int k = 0; k < AFFECT_ROLE_COUNT; k++)
        assert_int_equal(affect_role_from_name(affect_role_name((affect_role)k)), k);
    affect_motion_free(m);
}

/* Hips at (5, 1, 7) with the hips' lateral axis turned 90° about y (left hip along −z), and a
 * right arm of bones 0.3 + 0.25. */
static affect_motion *turned_body(void)
{
    static const char *const names[] = {"Hips",       "UpperLeg_L", "UpperLeg_R",
                                        "UpperArm_R", "LowerArm_R", "Hand_R"};
    affect_motion *m = skeleton(names, 6);
    const float p[6][3] = {{5, 1, 7},       {5, 1, 6.9f},    {5, 1, 7.1f},
                           {5, 1.5f, 7.2f}, {5, 1.2f, 7.2f}, {5, 0.95f, 7.2f}};
    memcpy(m->pos, p, sizeof p);
    return m;
}

static void test_normalize(void **state)
{
    affect_motion *m = turned_body(), *n = NULL;
    affect_roles r;
    affect_error err;
    affect_normalize_options o;
    affect_roles_resolve(m, &r);
    affect_normalize_options_default(&o);
    assert_int_equal(affect_motion_normalize(m, &r, &o, &n, &err), AFFECT_OK);
    /* root moved to x = z = 0, height kept; left hip now along +x */
    tu_assert_near(affect_motion_at(n, 0, 0)[0], 0, 1e-6);
    tu_assert_near(affect_motion_at(n, 0, 0)[1], 1, 1e-6);
    tu_assert_near(affect_motion_at(n, 0, 0)[2], 0, 1e-6);
    tu_assert_near(affect_motion_at(n, 0, 1)[0], 0.1, 1e-6);
    tu_assert_near(affect_motion_at(n, 0, 1)[2], 0, 1e-6);
    tu_assert_near(affect_motion_at(n, 0, 2)[0], -0.1, 1e-6);
    assert_string_equal(n->unit, "");
    affect_motion_free(n);
    /* with vertical removal and arm scaling (arm = 0.3 + 0.25 = 0.55) */
    o.vertical = true;
    o.scale_arm = true;
    assert_int_equal(affect_motion_normalize(m, &r, &o, &n, &err), AFFECT_OK);
    tu_assert_near(affect_motion_at(n, 0, 0)[1], 0, 1e-6);
    tu_assert_near(affect_motion_at(n, 0, 1)[0], 0.1 / 0.55, 1e-6);
    tu_assert_near(affect_motion_at(n, 0, 3)[1], 0.5 / 0.55, 1e-6);
    assert_string_equal(n->unit, "arm");
    affect_motion_free(n);
    /* missing roles */
    affect_roles none;
    for (int k = 0; k < AFFECT_ROLE_COUNT; k++)
        none.joint[k] = -1;
    affect_normalize_options_default(&o);
    assert_int_equal(affect_motion_normalize(m, &none, &o, &n, &err), AFFECT_ERR_MISSING);
    assert_true(strncmp(err.msg, "cannot find the heading", 23) == 0);
    o.heading = false;
    o.scale_arm = true;
    assert_int_equal(affect_motion_normalize(m, &none, &o, &n, &err), AFFECT_ERR_MISSING);
    assert_string_equal(err.msg, "cannot scale by the arm: the right_shoulder and right_hand "
                                 "roles are not both resolved");
    affect_motion_free(m);
}

static void test_normalize_z_up(void **state)
{
    /* z-up data: lateral along +y must turn onto +x, heights (z) untouched */
    static const char *const names[] = {"Hips", "LeftUpLeg", "RightUpLeg"};
    affect_motion *m = skeleton(names, 3), *n = NULL;
    const float p[3][3] = {{1, 2, 0.9f}, {1, 2.1f, 0.9f}, {1, 1.9f, 0.9f}};
    memcpy(m->pos, p, sizeof p);
    affect_roles r;
    affect_error err;
    affect_normalize_options o;
    affect_roles_resolve(m, &r);
    affect_normalize_options_default(&o);
    o.up_axis = 2;
    assert_int_equal(affect_motion_normalize(m, &r, &o, &n, &err), AFFECT_OK);
    tu_assert_near(affect_motion_at(n, 0, 1)[0], 0.1, 1e-6);
    tu_assert_near(affect_motion_at(n, 0, 1)[1], 0, 1e-6);
    tu_assert_near(affect_motion_at(n, 0, 1)[2], 0.9, 1e-6);
    affect_motion_free(n);
    affect_motion_free(m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_corpus_names), cmocka_unit_test(test_mixamo_cmu_names),
        cmocka_unit_test(test_short_names),  cmocka_unit_test(test_override_and_names),
        cmocka_unit_test(test_normalize),    cmocka_unit_test(test_normalize_z_up),
    };
    return cmocka_run_group_tests_name("roles", tests, NULL, NULL);
}
