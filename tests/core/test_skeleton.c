/*
 * test_skeleton.c — quaternions and Euler angles, the rigid projection (against a brute-force
 * search on small cases), inverse kinematics (recovering known rotations' positions, twist
 * continuity, multi-child joints, 1-frame and 1-joint motions), BVH export in every Euler
 * order and at gimbal lock, and out-of-memory sweeps.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "testutil.h"
#include "affect/fk.h"
#include "affect/io.h"
#include "affect/quat.h"
#include "affect/skeleton.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static const int orders[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};

/* Deterministic uniform numbers in [lo, hi). */
static uint64_t rng_state = 88172645463325252ull;
static double uni(double lo, double hi)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return lo + (hi - lo) * (double)(rng_state >> 11) / 9007199254740992.0;
}

static double mat_diff(const double a[9], const double b[9])
{
    double d = 0;
    for (int i = 0; i < 9; i++)
        d = fmax(d, fabs(a[i] - b[i]));
    return d;
}

/* ---- quaternions and Euler angles ---- */

static void test_euler_round_trip_every_order(void **state)
{
    for (int o = 0; o < 6; o++)
        for (int trial = 0; trial < 2000; trial++) {
            double deg[3] = {uni(-180, 180), uni(-90, 90), uni(-180, 180)}, q[4], back[3];
            if (trial % 10 == 0)
                deg[1] = trial % 20 == 0 ? 90 : -90; /* gimbal lock */
            double r1[9], r2[9], r3[9];
            affect_euler_deg_to_matrix(orders[o], deg, r1);
            affect_quat_from_euler_deg(orders[o], deg, q);
            affect_quat_to_matrix(q, r2);
            assert_true(mat_diff(r1, r2) < 1e-12);
            affect_quat_to_euler_deg(q, orders[o], NULL, back);
            affect_euler_deg_to_matrix(orders[o], back, r3);
            if (mat_diff(r1, r3) > 1e-9)
                fail_msg("order %d angles %g %g %g -> %g %g %g", o, deg[0], deg[1], deg[2], back[0],
                         back[1], back[2]);
            if (fabs(deg[1]) < 89) /* away from the lock the angles themselves come back */
                for (int k = 0; k < 3; k++)
                    tu_assert_near(back[k], deg[k], 1e-9);
        }
}

static void test_euler_continuity(void **state)
{
    /* a rotation sweeping through ±180° about the first axis: angles keep growing */
    int zxy[3] = {2, 0, 1};
    double prev[3], deg[3], q[4];
    for (int k = 0; k <= 400; k++) {
        double in[3] = {k * 1.0, 20, -30};
        affect_quat_from_euler_deg(zxy, in, q);
        affect_quat_to_euler_deg(q, zxy, k ? prev : NULL, deg);
        for (int a = 0; a < 3; a++)
            tu_assert_near(deg[a], in[a], 1e-9);
        memcpy(prev, deg, sizeof prev);
    }
    /* the equivalent solution (β beyond 90°) is taken when it is the continuous one */
    for (int k = 0; k <= 60; k++) {
        double in[3] = {10, 60 + k, 5}, r1[9], r2[9];
        affect_quat_from_euler_deg(zxy, in, q);
        affect_quat_to_euler_deg(q, zxy, k ? prev : NULL, deg);
        affect_euler_deg_to_matrix(zxy, in, r1);
        affect_euler_deg_to_matrix(zxy, deg, r2);
        assert_true(mat_diff(r1, r2) < 1e-12); /* the same rotation, at the lock too */
        for (int a = 0; a < 3; a++)            /* and, through the lock (k = 30), the same angles */
            tu_assert_near(deg[a], in[a], 1e-6);
        memcpy(prev, deg, sizeof prev);
    }
}

static void test_quat_helpers(void **state)
{
    double a[3] = {1, 0, 0}, b[3] = {0, 2, 0}, c[3] = {-3, 0, 0}, q[4], v[3];
    affect_quat_between(a, b, q);
    affect_quat_rotate(q, a, v);
    tu_assert_near(v[0], 0, 1e-15);
    tu_assert_near(v[1], 1, 1e-15);
    tu_assert_near(affect_quat_angle(q), M_PI / 2, 1e-15);
    affect_quat_between(a, c, q); /* antiparallel: half a turn */
    affect_quat_rotate(q, a, v);
    tu_assert_near(v[0], -1, 1e-15);
    tu_assert_near(affect_quat_angle(q), M_PI, 1e-15);
    double id[4] = {1, 0, 0, 0}, z90[4] = {cos(M_PI / 4), 0, 0, sin(M_PI / 4)}, mid[4], neg[4];
    affect_quat_slerp(id, z90, 0.5, mid);
    tu_assert_near(affect_quat_angle(mid), M_PI / 4, 1e-15);
    tu_assert_near(mid[3], sin(M_PI / 8), 1e-15);
    for (int i = 0; i < 4; i++)
        neg[i] = -z90[i];
    affect_quat_slerp(id, neg, 0.5, mid); /* the shorter arc either way */
    tu_assert_near(affect_quat_angle(mid), M_PI / 4, 1e-15);
    for (int trial = 0; trial < 1000; trial++) { /* matrix → quaternion → matrix */
        double deg[3] = {uni(-180, 180), uni(-90, 90), uni(-180, 180)}, r[9], r2[9];
        affect_euler_deg_to_matrix(orders[trial % 6], deg, r);
        affect_quat_from_matrix(r, q);
        assert_true(q[0] >= 0);
        affect_quat_to_matrix(q, r2);
        assert_true(mat_diff(r, r2) < 1e-14);
    }
    int o[3];
    char name[4];
    assert_true(affect_euler_order_parse("zxy", o));
    affect_euler_order_name(o, name);
    assert_string_equal(name, "ZXY");
    assert_false(affect_euler_order_parse("ZZY", o));
    assert_false(affect_euler_order_parse("ZX", o));
    assert_false(affect_euler_order_parse("ZXW", o));
}

/* ---- small motions ---- */

/* A chain root → 1 → 2 (→ 3 …) of n joints, T frames, with the given positions. */
static affect_motion *chain(uint32_t n, uint32_t frames)
{
    affect_motion *m = NULL;
    assert_int_equal(affect_motion_create(frames, n, 30, &m, NULL), AFFECT_OK);
    for (uint32_t j = 1; j < n; j++)
        m->parents[j] = (int32_t)j - 1;
    return m;
}

static double sq_dist(const affect_motion *a, const affect_motion *b, uint32_t t)
{
    double s = 0;
    for (uint32_t j = 0; j < a->n_joints; j++)
        for (int k = 0; k < 3; k++) {
            double d = (double)affect_motion_at(a, t, j)[k] - affect_motion_at(b, t, j)[k];
            s += d * d;
        }
    return s;
}

/* The least Σ‖p − q‖² over a 3-joint chain with lengths L1, L2, searched over a grid of both
 * bone directions (the root's best position is the mean residual, in closed form). */
static double brute_force_chain3(const float *q, double l1, double l2, int steps)
{
    double best = INFINITY;
    for (int a = 0; a <= steps; a++)
        for (int b = 0; b < 2 * steps; b++) {
            double th1 = M_PI * a / steps, ph1 = M_PI * b / steps;
            double u[3] = {sin(th1) * cos(ph1), cos(th1), sin(th1) * sin(ph1)};
            for (int c = 0; c <= steps; c++)
                for (int d = 0; d < 2 * steps; d++) {
                    double th2 = M_PI * c / steps, ph2 = M_PI * d / steps;
                    double v[3] = {sin(th2) * cos(ph2), cos(th2), sin(th2) * sin(ph2)};
                    double rel[3][3], root[3], s = 0;
                    for (int k = 0; k < 3; k++) {
                        rel[0][k] = 0;
                        rel[1][k] = l1 * u[k];
                        rel[2][k] = l1 * u[k] + l2 * v[k];
                        root[k] = (q[k] + q[3 + k] + q[6 + k] - rel[1][k] - rel[2][k]) / 3;
                    }
                    for (int j = 0; j < 3; j++)
                        for (int k = 0; k < 3; k++) {
                            double e = root[k] + rel[j][k] - q[j * 3 + k];
                            s += e * e;
                        }
                    best = fmin(best, s);
                }
        }
    return best;
}

static void test_rigid_against_brute_force(void **state)
{
    for (int trial = 0; trial < 6; trial++) {
        affect_motion *m = chain(3, 3), *r = NULL;
        /* frames 0 and 1 fix the median lengths at 0.5 and 0.3; frame 2 is stretched */
        for (uint32_t t = 0; t < 3; t++) {
            double l1 = t == 2 ? uni(0.3, 0.8) : 0.5, l2 = t == 2 ? uni(0.1, 0.6) : 0.3;
            double a1 = uni(0, 2 * M_PI), a2 = uni(0, 2 * M_PI), h = t == 2 ? uni(-0.2, 0.2) : 0;
            float *p = affect_motion_at(m, t, 0);
            p[0] = (float)uni(-0.1, 0.1), p[1] = (float)uni(-0.1, 0.1),
            p[2] = (float)uni(-0.1, 0.1);
            p[3] = p[0] + (float)(l1 * cos(a1)), p[4] = p[1] + (float)(l1 * sin(a1)),
            p[5] = p[2] + (float)h;
            p[6] = p[3] + (float)(l2 * cos(a2)), p[7] = p[4] + (float)(l2 * sin(a2)),
            p[8] = p[5] - (float)h;
        }
        assert_int_equal(affect_motion_rigid(m, NULL, &r, NULL), AFFECT_OK);
        double var;
        int32_t worst;
        assert_int_equal(affect_motion_bone_variation(r, &var, &worst, NULL), AFFECT_OK);
        if (var > 1e-6)
            fail_msg("trial %d: bone-length variation %g", trial, var);
        double ours = sq_dist(r, m, 2);
        double brute = brute_force_chain3(affect_motion_at(m, 2, 0), 0.5, 0.3, 48);
        if (ours > brute + 1e-9)
            fail_msg("trial %d: our projection is %g away, brute force %g", trial, ours, brute);
        if (sq_dist(r, m, 0) > 1e-12) /* already rigid frames stay */
            fail_msg("trial %d: a rigid frame moved by %g", trial, sqrt(sq_dist(r, m, 0)));
        affect_motion_free(r);
        affect_motion_free(m);
    }
}

static void test_rigid_tree_and_options(void **state)
{
    /* a reference root above the pelvis (the corpus's joint_Root → Hips) and two legs */
    affect_motion *m = NULL, *r = NULL, *ref = NULL;
    assert_int_equal(affect_motion_create(20, 5, 30, &m, NULL), AFFECT_OK);
    int32_t parents[5] = {-1, 0, 1, 2, 1};
    memcpy(m->parents, parents, sizeof parents);
    static const char *const names[5] = {"joint_Root", "Hips", "UpperLeg_L", "LowerLeg_L",
                                         "UpperLeg_R"};
    for (uint32_t j = 0; j < 5; j++)
        assert_int_equal(affect_motion_set_name(m, j, names[j], strlen(names[j]), NULL), AFFECT_OK);
    for (uint32_t t = 0; t < 20; t++) {
        float *p = affect_motion_at(m, t, 0);
        float x = 0.05f * (float)t, s = 1.0f + 0.1f * (float)sin(t);
        float v[15] = {0, 0,        0, x,    1,        0,    x + 0.1f, 0.5f * s,
                       0, x + 0.1f, 0, 0.1f, x - 0.1f, 0.5f, 0};
        memcpy(p, v, sizeof v);
    }
    bool free_link[5];
    assert_int_equal(affect_motion_free_links(m, free_link, NULL), AFFECT_OK);
    assert_true(free_link[1]);
    assert_false(free_link[2] || free_link[3] || free_link[4] || free_link[0]);
    /* a root that is itself the pelvis keeps its bones, moving or not */
    affect_motion *upper = NULL;
    assert_int_equal(affect_motion_select(m,
                                          (const char *const[]){"Hips", "UpperLeg_L", "LowerLeg_L"},
                                          3, &upper, NULL),
                     AFFECT_OK);
    assert_int_equal(affect_motion_free_links(upper, free_link, NULL), AFFECT_OK);
    assert_false(free_link[0] || free_link[1] || free_link[2]);
    affect_motion_free(upper);
    assert_int_equal(affect_motion_free_links(m, free_link, NULL), AFFECT_OK);
    assert_int_equal(affect_motion_rigid(m, NULL, &r, NULL), AFFECT_OK);
    double var;
    int32_t worst;
    assert_int_equal(affect_motion_bone_variation(m, &var, &worst, NULL), AFFECT_OK);
    assert_true(var > 0.1);
    assert_int_equal(affect_motion_bone_variation(r, &var, &worst, NULL), AFFECT_OK);
    assert_true(var <= 1e-6);
    for (uint32_t t = 0; t < 20; t++) /* the free joint keeps travelling */
        tu_assert_near(affect_motion_at(r, t, 1)[0], 0.05 * t, 0.02);
    /* the projection of a rigid motion is itself */
    affect_motion *r2 = NULL;
    assert_int_equal(affect_motion_rigid(r, NULL, &r2, NULL), AFFECT_OK);
    for (uint32_t t = 0; t < 20; t++)
        assert_true(sq_dist(r, r2, t) < 1e-12);
    affect_motion_free(r2);
    /* lengths from a reference motion, and its checks */
    affect_rigid_options ro;
    affect_rigid_options_default(&ro);
    ro.lengths = AFFECT_RIGID_REFERENCE;
    ro.reference = r;
    assert_int_equal(affect_motion_rigid(m, &ro, &r2, NULL), AFFECT_OK);
    affect_motion_free(r2);
    assert_int_equal(affect_motion_create(2, 4, 30, &ref, NULL), AFFECT_OK);
    affect_error err;
    ro.reference = ref;
    assert_int_equal(affect_motion_rigid(m, &ro, &r2, &err), AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "the reference motion has 4 joints, the motion 5");
    ro.reference = NULL;
    assert_int_equal(affect_motion_rigid(m, &ro, &r2, &err), AFFECT_ERR_INVALID);
    affect_motion_free(ref);
    /* no skeleton at all */
    assert_int_equal(affect_motion_create(2, 3, 30, &ref, NULL), AFFECT_OK);
    assert_int_equal(affect_motion_rigid(ref, NULL, &r2, &err), AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "the motion has no skeleton: no joint has a parent (set parents "
                                 "when importing, e.g. \"parents\" in JSON)");
    affect_motion_free(ref);
    affect_motion_free(r);
    affect_motion_free(m);
}

/* ---- inverse kinematics ---- */

/* A random skeletal motion: a pelvis with a spine chain and two legs (joints with one, several
 * and no children), smooth random rotations, positions by forward kinematics. */
static affect_motion *random_skeletal(uint32_t frames)
{
    affect_motion *m = NULL;
    static const int32_t parents[9] = {-1, 0, 1, 2, 2, 2, 0, 6, 0};
    static const double offsets[9][3] = {{0, 1, 0},       {0, 0.2, 0},      {0, 0.25, 0},
                                         {0, 0.2, 0.02},  {0.2, 0.05, 0},   {-0.2, 0.05, 0},
                                         {0.1, -0.05, 0}, {0, -0.45, 0.01}, {-0.1, -0.05, 0}};
    static const char *const names[9] = {"Hips", "Spine", "Chest",    "Head", "ArmL",
                                         "ArmR", "LegL",  "LegL_end", "LegR"};
    assert_int_equal(affect_motion_create(frames, 9, 30, &m, NULL), AFFECT_OK);
    assert_int_equal(affect_motion_add_skeleton(m, true, NULL), AFFECT_OK);
    double phase[9][3];
    for (int j = 0; j < 9; j++)
        for (int a = 0; a < 3; a++)
            phase[j][a] = uni(0, 6.28);
    for (uint32_t j = 0; j < 9; j++) {
        m->parents[j] = parents[j];
        assert_int_equal(affect_motion_set_name(m, j, names[j], strlen(names[j]), NULL), AFFECT_OK);
        memcpy(m->skel[j].offset, offsets[j], sizeof offsets[j]);
    }
    int zxy[3] = {2, 0, 1};
    for (uint32_t t = 0; t < frames; t++)
        for (uint32_t j = 0; j < 9; j++) {
            double deg[3], q[4];
            for (int a = 0; a < 3; a++)
                deg[a] = 40 * sin(0.05 * t + phase[j][a]);
            affect_quat_from_euler_deg(zxy, deg, q);
            float *qf = m->rot + ((size_t)t * 9 + j) * 4, *tr = m->trans + ((size_t)t * 9 + j) * 3;
            for (int a = 0; a < 4; a++)
                qf[a] = (float)q[a];
            for (int a = 0; a < 3; a++)
                tr[a] = (float)(offsets[j][a] + (j == 0 ? 0.01 * t : 0));
        }
    for (uint32_t j = 0; j < 9; j++) {
        affect_skel_joint *s = &m->skel[j];
        int c = 0;
        if (j == 0)
            for (int a = 0; a < 3; a++)
                s->channel[c++] = (uint8_t)(AFFECT_CH_XPOS + a);
        if (j == 7) {
            s->flags = AFFECT_JOINT_END_SITE;
            continue;
        }
        for (int a = 0; a < 3; a++)
            s->channel[c++] = (uint8_t)(AFFECT_CH_XROT + zxy[a]);
        s->n_channels = (uint8_t)c;
    }
    assert_int_equal(affect_motion_fk(m, NULL), AFFECT_OK);
    assert_int_equal(affect_motion_validate(m, NULL), AFFECT_OK);
    return m;
}

static void test_ik_recovers_rigid_motion(void **state)
{
    affect_motion *m = random_skeletal(200), *pos = NULL, *ik = NULL;
    assert_int_equal(affect_motion_clone(m, &pos, NULL), AFFECT_OK);
    affect_motion_drop_skeleton(pos);
    assert_int_equal(affect_motion_ik(pos, NULL, &ik, NULL), AFFECT_OK);
    assert_non_null(ik->rot);
    if (tu_max_dist(ik, m) > 1e-5)
        fail_msg("IK positions differ from the input by %g", tu_max_dist(ik, m));
    double fk_err;
    uint32_t f, j;
    assert_int_equal(affect_motion_fk_error(ik, &fk_err, &f, &j, NULL), AFFECT_OK);
    assert_true(fk_err < 1e-6);
    /* channels: the root translates, the named end is an End Site, the rest rotate */
    assert_int_equal(ik->skel[0].n_channels, 6);
    assert_int_equal(ik->skel[7].flags, AFFECT_JOINT_END_SITE);
    assert_int_equal(ik->skel[3].n_channels, 3);
    /* twist continuity: no local rotation jumps between frames more than the input's does */
    double worst_step = 0;
    for (uint32_t t = 1; t < ik->n_frames; t++)
        for (uint32_t k = 0; k < ik->n_joints; k++) {
            double a[4], b[4], inv[4], d[4];
            const float *qa = ik->rot + ((size_t)(t - 1) * 9 + k) * 4,
                        *qb = ik->rot + ((size_t)t * 9 + k) * 4;
            for (int i = 0; i < 4; i++)
                a[i] = qa[i], b[i] = qb[i];
            inv[0] = a[0], inv[1] = -a[1], inv[2] = -a[2], inv[3] = -a[3];
            affect_quat_mul(inv, b, d);
            worst_step = fmax(worst_step, affect_quat_angle(d));
        }
    if (worst_step > 0.2)
        fail_msg("a local rotation turns %g rad between two frames (a flip)", worst_step);
    /* export and re-import in every Euler order reproduce the positions */
    for (int o = 0; o < 6; o++) {
        affect_bvh_write_options wo;
        affect_bvh_write_options_default(&wo);
        memcpy(wo.order, orders[o], sizeof wo.order);
        char *text = NULL;
        size_t len;
        affect_motion *back = NULL;
        assert_int_equal(affect_bvh_write(ik, &wo, &text, &len, NULL), AFFECT_OK);
        assert_int_equal(affect_bvh_parse(text, len, NULL, &back, NULL), AFFECT_OK);
        if (tu_max_dist(back, ik) > 1e-5)
            fail_msg("order %d: re-imported positions differ by %g", o, tu_max_dist(back, ik));
        affect_free(text);
        affect_motion_free(back);
    }
    affect_motion_free(ik);
    affect_motion_free(pos);
    affect_motion_free(m);
}

static void test_gimbal_lock_and_small_motions(void **state)
{
    /* gimbal lock in the stored rotations: X = ±90 in ZXY on every joint */
    affect_motion *m = random_skeletal(5), *back = NULL, *ik = NULL;
    int zxy[3] = {2, 0, 1};
    for (uint32_t t = 0; t < 5; t++)
        for (uint32_t j = 0; j < 9; j++) {
            double deg[3] = {30.0 * t, t % 2 ? 90 : -90, -20.0 * j}, q[4];
            affect_quat_from_euler_deg(zxy, deg, q);
            for (int a = 0; a < 4; a++)
                m->rot[((size_t)t * 9 + j) * 4 + a] = (float)q[a];
        }
    assert_int_equal(affect_motion_fk(m, NULL), AFFECT_OK);
    char *text = NULL;
    size_t len;
    assert_int_equal(affect_bvh_write(m, NULL, &text, &len, NULL), AFFECT_OK);
    assert_int_equal(affect_bvh_parse(text, len, NULL, &back, NULL), AFFECT_OK);
    assert_true(tu_max_dist(back, m) < 1e-5);
    affect_free(text);
    affect_motion_free(back);
    /* one frame */
    affect_motion *one = NULL;
    assert_int_equal(affect_motion_slice(m, 2, 2, &one, NULL), AFFECT_OK);
    affect_motion_drop_skeleton(one);
    assert_int_equal(affect_motion_ik(one, NULL, &ik, NULL), AFFECT_OK);
    assert_true(tu_max_dist(ik, one) < 1e-5);
    assert_int_equal(affect_bvh_write(ik, NULL, &text, &len, NULL), AFFECT_OK);
    assert_int_equal(affect_bvh_parse(text, len, NULL, &back, NULL), AFFECT_OK);
    assert_true(tu_max_dist(back, one) < 1e-5);
    affect_free(text);
    affect_motion_free(back);
    affect_motion_free(ik);
    affect_motion_free(one);
    /* one joint */
    affect_motion *single = NULL;
    assert_int_equal(affect_motion_create(3, 1, 30, &single, NULL), AFFECT_OK);
    for (uint32_t t = 0; t < 3; t++)
        affect_motion_at(single, t, 0)[0] = (float)t;
    assert_int_equal(affect_motion_ik(single, NULL, &ik, NULL), AFFECT_OK);
    assert_int_equal(affect_bvh_write(ik, NULL, &text, &len, NULL), AFFECT_OK);
    assert_string_equal(text, "HIERARCHY\nROOT j0\n{\n\tOFFSET 0 0 0\n\tCHANNELS 6 Xposition "
                              "Yposition Zposition Zrotation Xrotation Yrotation\n}\nMOTION\n"
                              "Frames: 3\nFrame Time: 0.0333333333\n0 0 0 0 0 0\n1 0 0 0 0 0\n"
                              "2 0 0 0 0 0\n");
    affect_free(text);
    affect_motion_free(ik);
    affect_motion_free(single);
    affect_motion_free(m);
}

static void test_writer_text_and_options(void **state)
{
    static const char bvh[] =
        "HIERARCHY\nROOT My Hips\n{\n  OFFSET 0 0 0\n"
        "  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
        "  JOINT Chest\n  {\n    OFFSET 0 10 0\n    CHANNELS 3 Xrotation Yrotation Zrotation\n"
        "    End Site\n    {\n      OFFSET 0 5.25 0\n    }\n  }\n}\nMOTION\n"
        "Frames: 2\nFrame Time: 0.04\n1 2 3 0 0 0 0 0 0\n1 2.5 3 90 0 0 -30 0 0\n";
    affect_motion *m = NULL, *back = NULL;
    assert_int_equal(affect_bvh_parse(bvh, strlen(bvh), NULL, &m, NULL), AFFECT_OK);
    char *text = NULL;
    size_t len;
    assert_int_equal(affect_bvh_write(m, NULL, &text, &len, NULL), AFFECT_OK);
    assert_string_equal(
        text,
        "HIERARCHY\nROOT My_Hips\n{\n\tOFFSET 0 0 0\n"
        "\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
        "\tJOINT Chest\n\t{\n\t\tOFFSET 0 10 0\n\t\tCHANNELS 3 Xrotation Yrotation Zrotation\n"
        "\t\tEnd Site\n\t\t{\n\t\t\tOFFSET 0 5.25 0\n\t\t}\n\t}\n}\nMOTION\n"
        "Frames: 2\nFrame Time: 0.04\n1 2 3 0 0 0 0 0 0\n1 2.5 3 90 0 0 -30 0 0\n");
    assert_int_equal(strlen(text), len);
    affect_free(text);
    affect_bvh_write_options wo;
    affect_bvh_write_options_default(&wo);
    wo.precision = 2;
    wo.frame_time = 0.02;
    wo.root_name = "root";
    wo.order[0] = 0, wo.order[1] = 1, wo.order[2] = 2;
    assert_int_equal(affect_bvh_write(m, &wo, &text, &len, NULL), AFFECT_OK);
    assert_non_null(strstr(text, "ROOT root\n"));
    assert_non_null(strstr(text, "Frame Time: 0.02\n"));
    assert_non_null(
        strstr(text, "\tCHANNELS 6 Xposition Yposition Zposition Xrotation Yrotation Zrotation\n"));
    assert_int_equal(affect_bvh_parse(text, len, NULL, &back, NULL), AFFECT_OK);
    tu_assert_near(back->fps, 50, 1e-9);
    assert_true(tu_max_dist(back, m) < 1e-2);
    affect_free(text);
    affect_motion_free(back);
    affect_error err;
    wo.precision = 0;
    assert_int_equal(affect_bvh_write(m, &wo, &text, &len, &err), AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "precision 0 out of range (1 .. 9)");
    affect_motion_drop_skeleton(m);
    assert_int_equal(affect_bvh_write(m, NULL, &text, &len, &err), AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "the motion has no joint rotations");
    affect_motion_free(m);
}

/* Joints with one or two rotation channels (fuzz_motion_v2 found both): the angle about the
 * missing axis must not be dropped after a general decomposition. A middle angle beyond ±90°,
 * and one next to it with a long child bone. */
static void test_fewer_rotation_channels(void **state)
{
    static const char *const cases[] = {
        "HIERARCHY\nROOT a\n{\n OFFSET 0 0 0\n CHANNELS 2 Zrotation Xrotation\n End Site\n {\n"
        "  OFFSET 0 0 1\n }\n}\nMOTION\nFrames: 2\nFrame Time: 0.1\n0 120\n10 -150\n",
        "HIERARCHY\nROOT a\n{\n OFFSET 0 0 0\n CHANNELS 2 Zrotation Yrotation\n End Site\n {\n"
        "  OFFSET 0 0 400\n }\n}\nMOTION\nFrames: 2\nFrame Time: 0.1\n30 -89.9999\n30 89.9999\n",
        "HIERARCHY\nROOT a\n{\n OFFSET 0 0 0\n CHANNELS 1 Yrotation\n End Site\n {\n"
        "  OFFSET 0 0 10\n }\n}\nMOTION\nFrames: 3\nFrame Time: 0.1\n170\n-170\n-10\n",
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        affect_motion *m = NULL, *back = NULL;
        char *text = NULL;
        size_t len;
        assert_int_equal(affect_bvh_parse(cases[i], strlen(cases[i]), NULL, &m, NULL), AFFECT_OK);
        assert_int_equal(affect_bvh_write(m, NULL, &text, &len, NULL), AFFECT_OK);
        assert_int_equal(affect_bvh_parse(text, len, NULL, &back, NULL), AFFECT_OK);
        if (tu_max_dist(back, m) > 1e-4)
            fail_msg("case %zu: re-imported positions differ by %g:\n%s", i, tu_max_dist(back, m),
                     text);
        affect_free(text);
        affect_motion_free(back);
        affect_motion_free(m);
    }
}

/* Which rotations export and angles use: stored ones that agree with the positions, IK when
 * asked or when there are none, and an error for stored ones that do not agree (a BLOB edited
 * by hand) or when stored ones are demanded of a position-only motion. */
static void test_rotation_source(void **state)
{
    affect_motion *m = random_skeletal(10), *made = NULL, *pos = NULL;
    affect_error err;
    assert_int_equal(affect_motion_skeletal(m, AFFECT_ROTATIONS_AUTO, NULL, &made, &err),
                     AFFECT_OK);
    assert_null(made);
    assert_int_equal(affect_motion_skeletal(m, AFFECT_ROTATIONS_IK, NULL, &made, &err), AFFECT_OK);
    assert_non_null(made);
    affect_motion_free(made);
    affect_motion_at(m, 4, 3)[1] += 0.5f;
    assert_int_equal(affect_motion_skeletal(m, AFFECT_ROTATIONS_AUTO, NULL, &made, &err),
                     AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "the stored rotations do not reproduce the positions (joint 3 "
                                 "\"Head\", frame 4: 0.5 apart); use {\"rotations\":\"ik\"} to "
                                 "rebuild them");
    assert_int_equal(affect_motion_clone(m, &pos, NULL), AFFECT_OK);
    affect_motion_drop_skeleton(pos);
    assert_int_equal(affect_motion_skeletal(pos, AFFECT_ROTATIONS_STORED, NULL, &made, &err),
                     AFFECT_ERR_INVALID);
    assert_null(made);
    affect_motion_free(pos);
    affect_motion_free(m);
}

/* ---- out of memory ---- */

typedef struct oom_ctx {
    affect_motion *in, *out;
    char *text;
} oom_ctx;

static affect_status run_ik(void *p, affect_error *err)
{
    oom_ctx *c = p;
    c->out = NULL;
    return affect_motion_ik(c->in, NULL, &c->out, err);
}

static affect_status run_write(void *p, affect_error *err)
{
    oom_ctx *c = p;
    size_t len;
    c->text = NULL;
    return affect_bvh_write(c->in, NULL, &c->text, &len, err);
}

static void finish_oom(void *p, affect_status st)
{
    oom_ctx *c = p;
    affect_motion_free(c->out);
    affect_free(c->text);
    c->out = NULL;
    c->text = NULL;
}

static void test_out_of_memory(void **state)
{
    oom_ctx c = {random_skeletal(4), NULL, NULL};
    assert_true(tu_oom_sweep(run_write, &c, finish_oom, NULL) >= 3);
    affect_motion_drop_skeleton(c.in);
    long absorbed = 0; /* role resolution falls back to parsing names without allocating */
    assert_true(tu_oom_sweep(run_ik, &c, finish_oom, &absorbed) >= 5);
    assert_true(absorbed <= 1);
    affect_motion_free(c.in);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_euler_round_trip_every_order),
        cmocka_unit_test(test_euler_continuity),
        cmocka_unit_test(test_quat_helpers),
        cmocka_unit_test(test_rigid_against_brute_force),
        cmocka_unit_test(test_rigid_tree_and_options),
        cmocka_unit_test(test_ik_recovers_rigid_motion),
        cmocka_unit_test(test_gimbal_lock_and_small_motions),
        cmocka_unit_test(test_writer_text_and_options),
        cmocka_unit_test(test_fewer_rotation_channels),
        cmocka_unit_test(test_rotation_source),
        cmocka_unit_test(test_out_of_memory),
    };
    return cmocka_run_group_tests_name("skeleton", tests, NULL, NULL);
}
