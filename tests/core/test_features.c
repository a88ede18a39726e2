/*
 * test_features.c — the observation definition of the models: joint and role resolution,
 * normalization, velocities, the skeleton kept for postures, the binary form and its
 * corruptions, every error message, and allocation failure.
 */
#include <stdio.h>
#include <string.h>

#include "testutil.h"

#include "affect/features.h"
#include "affect/synth.h"
#include "util/rng.h"

/* A 7-joint skeleton, 4 frames at 10 fps, facing +z with the lateral vector along +x, right
 * arm 0.3 + 0.2 = 0.5 long; the hips move along x by 0, 1, 3, 6. Then every position is
 * turned by yaw quarter turns about y and shifted by (dx, 0, dz). */
static affect_motion *make_motion(int quarter_turns, float dx, float dz)
{
    static const char *const names[7] = {"Hips",   "Chest",      "UpperArm_R", "LowerArm_R",
                                         "Hand_R", "UpperLeg_L", "UpperLeg_R"};
    static const int32_t parents[7] = {-1, 0, 1, 2, 3, 0, 0};
    static const float base[7][3] = {{0, 1, 0},        {0, 1.5f, 0},     {-0.2f, 1.4f, 0},
                                     {-0.5f, 1.4f, 0}, {-0.5f, 1.2f, 0}, {0.1f, 0.9f, 0},
                                     {-0.1f, 0.9f, 0}};
    static const float shift[4] = {0, 1, 3, 6};
    affect_motion *m = NULL;
    affect_error err;
    assert_int_equal(affect_motion_create(4, 7, 10.0, &m, &err), AFFECT_OK);
    assert_int_equal(affect_motion_set_unit(m, "m", &err), AFFECT_OK);
    for (uint32_t j = 0; j < 7; j++) {
        assert_int_equal(affect_motion_set_name(m, j, names[j], strlen(names[j]), &err), AFFECT_OK);
        m->parents[j] = parents[j];
    }
    for (uint32_t t = 0; t < 4; t++)
        for (uint32_t j = 0; j < 7; j++) {
            float p[3] = {base[j][0] + (j == 0 ? shift[t] : 0), base[j][1], base[j][2]};
            for (int q = 0; q < quarter_turns; q++) { /* (x, z) → (z, −x): +90° about y */
                float x = p[0];
                p[0] = p[2];
                p[2] = -x;
            }
            float *o = affect_motion_at(m, t, j);
            o[0] = p[0] + dx;
            o[1] = p[1];
            o[2] = p[2] + dz;
        }
    return m;
}

static affect_features *create(const affect_features_options *opt, const affect_motion *m)
{
    affect_features *f = NULL;
    affect_error err;
    affect_status st = affect_features_create(opt, m, &f, &err);
    if (st)
        fail_msg("create: %s", err.msg);
    return f;
}

static double *extract(const affect_features *f, const affect_motion *m, uint32_t *n_frames)
{
    double *x = NULL;
    affect_error err;
    affect_status st = affect_features_extract(f, m, &x, n_frames, NULL, &err);
    if (st)
        fail_msg("extract: %s", err.msg);
    return x;
}

static void test_defaults_and_raw_values(void **state)
{
    affect_features_options opt;
    affect_features_options_default(&opt);
    assert_true(opt.normalize);
    assert_int_equal(opt.scale, AFFECT_FEATURES_SCALE_AUTO);
    assert_int_equal(opt.up_axis, 1);
    assert_false(opt.velocity);

    affect_motion *m = make_motion(0, 0, 0);
    /* raw positions and velocities of one joint: exact central differences × fps */
    const char *hips[] = {"Hips"};
    opt.joints = hips;
    opt.n_joints = 1;
    opt.normalize = false;
    opt.scale = AFFECT_FEATURES_SCALE_NONE;
    opt.velocity = true;
    affect_features *f = create(&opt, m);
    assert_int_equal(affect_features_dim(f), 6);
    assert_string_equal(f->unit, "m");
    assert_true(f->fps == 10.0);
    uint32_t T = 0;
    double *x = extract(f, m, &T);
    assert_int_equal(T, 4);
    const double want_x[4] = {0, 1, 3, 6}, want_v[4] = {10, 15, 25, 30};
    for (uint32_t t = 0; t < 4; t++) {
        assert_true(x[t * 6 + 0] == want_x[t]);
        assert_true(x[t * 6 + 1] == 1.0);
        assert_true(x[t * 6 + 2] == 0.0);
        assert_true(x[t * 6 + 3] == want_v[t]);
        assert_true(x[t * 6 + 4] == 0.0 && x[t * 6 + 5] == 0.0);
    }
    affect_free(x);
    affect_features_free(f);

    /* default: every joint by name, scale decided on the first motion (arm: it resolves) */
    affect_features_options_default(&opt);
    f = create(&opt, m);
    assert_int_equal(f->n_joints, 7);
    assert_int_equal(affect_features_dim(f), 21);
    assert_true(f->normalize && f->scale_arm && !f->velocity);
    assert_string_equal(f->unit, "arm");
    for (uint32_t j = 0; j < 7; j++) {
        assert_string_equal(f->joints[j], m->names[j]);
        assert_string_equal(f->skeleton[j], m->names[j]);
        assert_int_equal(f->parents[j], m->parents[j]);
    }
    x = extract(f, m, &T);
    /* first frame: hips at the origin horizontally, height divided by the arm (0.5) */
    tu_assert_near(x[0], 0, 1e-7);
    tu_assert_near(x[1], 2.0, 1e-6);
    tu_assert_near(x[2], 0, 1e-7);
    /* the right hand: (−0.5, 1.2, 0) / 0.5 */
    tu_assert_near(x[4 * 3 + 0], -1.0, 1e-6);
    tu_assert_near(x[4 * 3 + 1], 2.4, 1e-6);
    /* last frame: the hips moved 6 m = 12 arms along x */
    tu_assert_near(x[3 * 21 + 0], 12.0, 1e-5);
    affect_free(x);
    affect_features_free(f);

    /* scale "none" keeps the unit */
    opt.scale = AFFECT_FEATURES_SCALE_NONE;
    f = create(&opt, m);
    assert_false(f->scale_arm);
    assert_string_equal(f->unit, "m");
    affect_features_free(f);
    affect_motion_free(m);
}

/* Normalization removes the first frame's position and heading: a turned and shifted copy of
 * a motion gives the same observations. */
static void test_normalization_invariance(void **state)
{
    affect_motion *a = make_motion(0, 0, 0), *b = make_motion(1, 5, -3), *c = make_motion(3, -2, 7);
    affect_features_options opt;
    affect_features_options_default(&opt);
    opt.velocity = true;
    affect_features *f = create(&opt, a);
    uint32_t ta, tb, tc;
    double *xa = extract(f, a, &ta), *xb = extract(f, b, &tb), *xc = extract(f, c, &tc);
    assert_int_equal(ta, tb);
    for (size_t i = 0; i < (size_t)ta * 42; i++) {
        tu_assert_near(xb[i], xa[i], 1e-4);
        tu_assert_near(xc[i], xa[i], 1e-4);
    }
    /* without normalization they differ */
    affect_free(xb);
    affect_features_free(f);
    opt.normalize = false;
    opt.scale = AFFECT_FEATURES_SCALE_NONE;
    f = create(&opt, a);
    xb = extract(f, b, &tb);
    assert_true(fabs(xb[0] - 5.0) < 1e-6); /* the hips keep their shift */
    affect_free(xa);
    affect_free(xb);
    affect_free(xc);
    affect_features_free(f);
    affect_motion_free(a);
    affect_motion_free(b);
    affect_motion_free(c);
}

/* The body frame: every frame relative to its own pelvis and heading, so a turned and shifted
 * copy gives the same observations, and so does a copy that turns while it moves; the root
 * columns carry the pelvis's body-frame velocity and the turning rate. */
static unsigned char *encode(const affect_features *f, size_t *size);

static void turn_frames(affect_motion *m, double rate)
{
    for (uint32_t t = 0; t < m->n_frames; t++) {
        double a = rate * t, c = cos(a), s = sin(a);
        for (uint32_t j = 0; j < m->n_joints; j++) {
            float *p = affect_motion_at(m, t, j);
            double x = p[0], z = p[2]; /* +a about y: (x, z) → (x c + z s, −x s + z c) */
            p[0] = (float)(x * c + z * s);
            p[2] = (float)(-x * s + z * c);
        }
    }
}

static void test_body_frame(void **state)
{
    affect_motion *a = make_motion(0, 0, 0), *b = make_motion(1, 5, -3), *c = make_motion(0, 0, 0);
    turn_frames(c, 0.1);
    affect_features_options opt;
    affect_features_options_default(&opt);
    opt.frame = AFFECT_FEATURES_FRAME_BODY;
    opt.velocity = true;
    opt.root = true;
    affect_features *f = create(&opt, a);
    assert_int_equal(affect_features_dim(f), 7 * 6 + 4);
    assert_false(f->normalize);
    assert_true(f->scale_arm);
    uint32_t ta, tb, tc;
    double *xa = extract(f, a, &ta), *xb = extract(f, b, &tb), *xc = extract(f, c, &tc);
    const uint32_t D = 46;
    const double shift[4] = {0, 1, 3, 6}, vx[4] = {20, 30, 50, 60}; /* arms, arms/s */
    for (uint32_t t = 0; t < 4; t++) {
        const double *r = xa + t * D;
        tu_assert_near(r[0], 0, 1e-12);                              /* the pelvis is the origin */
        tu_assert_near(r[4 * 3 + 0], (-0.5 - shift[t]) / 0.5, 1e-5); /* the right hand */
        tu_assert_near(r[4 * 3 + 1], 0.2 / 0.5, 1e-5);
        tu_assert_near(r[D - 4], vx[t], 1e-4); /* forward … sideways: the pelvis moves on x */
        tu_assert_near(r[D - 3], 0, 1e-9);
        tu_assert_near(r[D - 2], 0, 1e-9);
        tu_assert_near(r[D - 1], 0, 1e-9); /* no turning */
        for (uint32_t i = 0; i < D - 1; i++) {
            tu_assert_near(xb[t * D + i], r[i], 1e-4);
            if (i < D - 4)
                tu_assert_near(xc[t * D + i], r[i], 1e-4);
        }
        tu_assert_near(xc[t * D + D - 1], 0.1 * 10.0, 1e-6); /* 0.1 rad per frame at 10 fps */
    }
    /* the first frame's normalization does not see through the turning copy */
    affect_free(xc);
    affect_features_free(f);
    affect_features_options_default(&opt);
    f = create(&opt, a);
    xc = extract(f, c, &tc);
    double *xa2 = extract(f, a, &ta);
    assert_true(fabs(xc[3 * 21 + 4 * 3 + 2] - xa2[3 * 21 + 4 * 3 + 2]) > 0.1);
    affect_free(xa2);
    /* root needs the body frame */
    affect_features *g = NULL;
    affect_error err;
    opt.root = true;
    assert_int_equal(affect_features_create(&opt, a, &g, &err), AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "root velocity and turning rate need the body frame");
    /* the binary form keeps the frame and the root */
    affect_features_free(f);
    opt.frame = AFFECT_FEATURES_FRAME_BODY;
    f = create(&opt, a);
    size_t size;
    unsigned char *buf = encode(f, &size);
    assert_int_equal(buf[1], 2 | 8 | 16);
    assert_int_equal(affect_features_decode(buf, size, &g, &err), AFFECT_OK);
    assert_true(g->frame == AFFECT_FEATURES_FRAME_BODY && g->root && !g->normalize);
    affect_features_free(g);
    free(buf);
    affect_free(xa);
    affect_free(xb);
    affect_free(xc);
    affect_features_free(f);
    affect_motion_free(a);
    affect_motion_free(b);
    affect_motion_free(c);
}

/* Mirror images: partners by name, the lateral axis negated, twice = the identity. */
static void test_mirror(void **state)
{
    affect_motion *m = make_motion(0, 0, 0);
    affect_features_options opt;
    affect_features_options_default(&opt);
    opt.frame = AFFECT_FEATURES_FRAME_BODY;
    opt.velocity = true;
    opt.root = true;
    affect_features *f = create(&opt, m);
    uint32_t partner[7];
    affect_error err;
    assert_int_equal(affect_features_mirror_map(f, partner, &err), AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "joint \"UpperArm_R\" has no mirror partner (\"UpperArm_L\" is "
                                 "not among the observed joints)");
    affect_features_free(f);
    const char *entries[] = {"Hips", "UpperLeg_R", "Chest", "UpperLeg_L"};
    opt.joints = entries;
    opt.n_joints = 4;
    f = create(&opt, m);
    assert_int_equal(affect_features_mirror_map(f, partner, &err), AFFECT_OK);
    const uint32_t want[4] = {0, 3, 2, 1};
    assert_memory_equal(partner, want, sizeof want);
    uint32_t T;
    double *x = extract(f, m, &T);
    uint32_t D = affect_features_dim(f);
    assert_int_equal(D, 4 * 6 + 4);
    double *y = malloc(sizeof *y * T * D), *z = malloc(sizeof *z * T * D);
    affect_features_mirror(f, partner, x, T, y);
    affect_features_mirror(f, partner, y, T, z);
    for (uint32_t i = 0; i < T * D; i++)
        assert_true(z[i] == x[i]);
    for (uint32_t t = 0; t < T; t++) {
        const double *a = x + t * D, *b = y + t * D;
        assert_true(b[3 * 3 + 0] == -a[1 * 3 + 0]); /* UpperLeg_L ← −UpperLeg_R on x */
        assert_true(b[3 * 3 + 1] == a[1 * 3 + 1]);
        assert_true(b[12 + 1 * 3 + 0] == -a[12 + 3 * 3 + 0]); /* velocities */
        assert_true(b[D - 4] == -a[D - 4] && b[D - 3] == a[D - 3] && b[D - 1] == -a[D - 1]);
    }
    free(y);
    free(z);
    affect_free(x);
    affect_features_free(f);
    /* the first frame without normalization has no lateral axis to mirror */
    affect_features_options_default(&opt);
    opt.normalize = false;
    opt.joints = entries;
    opt.n_joints = 4;
    f = create(&opt, m);
    assert_int_equal(affect_features_mirror_map(f, partner, &err), AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "mirroring needs the body frame or normalized positions");
    affect_features_free(f);
    affect_motion_free(m);
}

/* Role entries resolve per motion; the skeleton and parents come from the first motion. */
static void test_roles_and_skeleton(void **state)
{
    affect_motion *synth = NULL;
    affect_error err;
    assert_int_equal(affect_motion_synth("wave", "happy", 1, NULL, &synth, &err), AFFECT_OK);
    const char *entries[] = {"right_hand", "head", "Chest", "left_wrist", "Hips"};
    affect_features_options opt;
    affect_features_options_default(&opt);
    opt.joints = entries;
    opt.n_joints = 5;
    affect_features *f = create(&opt, synth);
    const char *skel[] = {"Hand_R", "Head", "Chest", "Hand_L", "Hips"};
    const int32_t parents[] = {2, 2, 4, 2, -1}; /* nearest listed ancestors */
    for (int j = 0; j < 5; j++) {
        assert_string_equal(f->joints[j], entries[j]);
        assert_string_equal(f->skeleton[j], skel[j]);
        assert_int_equal(f->parents[j], parents[j]);
    }
    /* another skeleton with other names: the roles follow, the names must exist */
    affect_motion *m = make_motion(0, 0, 0);
    double *x = NULL;
    uint32_t T;
    assert_int_equal(affect_features_extract(f, m, &x, &T, NULL, &err), AFFECT_ERR_MISSING);
    assert_string_equal(err.msg, "no joint of the motion has the head role (used by the model)");
    affect_features_free(f);
    const char *entries2[] = {"right_hand", "Chest", "pelvis"};
    opt.joints = entries2;
    opt.n_joints = 3;
    f = create(&opt, synth);
    x = extract(f, m, &T);
    /* the hand of make_motion after normalization: (−0.5, 1.2, 0) / 0.5 */
    tu_assert_near(x[0], -1.0, 1e-6);
    tu_assert_near(x[1], 2.4, 1e-6);
    affect_free(x);
    affect_features_free(f);
    affect_motion_free(m);
    affect_motion_free(synth);
}

static void expect_create_error(const affect_features_options *opt, const affect_motion *m,
                                affect_status status, const char *msg)
{
    affect_features *f = NULL;
    affect_error err;
    assert_int_equal(affect_features_create(opt, m, &f, &err), status);
    assert_null(f);
    assert_string_equal(err.msg, msg);
}

static void expect_extract_error(const affect_features *f, const affect_motion *m, const char *msg)
{
    double *x = NULL;
    uint32_t T = 0;
    affect_error err;
    assert_int_equal(affect_features_extract(f, m, &x, &T, NULL, &err), AFFECT_ERR_MISSING);
    assert_null(x);
    assert_string_equal(err.msg, msg);
}

static void test_errors(void **state)
{
    affect_motion *m = make_motion(0, 0, 0);
    affect_features_options opt;
    affect_features_options_default(&opt);
    const char *missing[] = {"Hips", "Hand_L"};
    opt.joints = missing;
    opt.n_joints = 2;
    expect_create_error(&opt, m, AFFECT_ERR_MISSING,
                        "joint \"Hand_L\" of the model is not in the motion");
    const char *role[] = {"left_hand"};
    opt.joints = role;
    opt.n_joints = 1;
    expect_create_error(&opt, m, AFFECT_ERR_MISSING,
                        "no joint of the motion has the left_hand role (used by the model)");
    const char *twice[] = {"Hips", "Chest", "Hips"};
    opt.joints = twice;
    opt.n_joints = 3;
    expect_create_error(&opt, m, AFFECT_ERR_INVALID, "joint \"Hips\" is listed twice");
    const char *same[] = {"Hand_R", "right_hand"};
    opt.joints = same;
    opt.n_joints = 2;
    expect_create_error(&opt, m, AFFECT_ERR_INVALID,
                        "joints \"Hand_R\" and \"right_hand\" are the same joint \"Hand_R\"");
    const char *empty[] = {""};
    opt.joints = empty;
    opt.n_joints = 1;
    expect_create_error(&opt, m, AFFECT_ERR_INVALID,
                        "joint entry 1: a name must have 1 to 1024 bytes");
    opt.n_joints = 0;
    expect_create_error(&opt, m, AFFECT_ERR_INVALID, "the joint list is empty");
    affect_features_options_default(&opt);
    opt.up_axis = 3;
    expect_create_error(&opt, m, AFFECT_ERR_INVALID, "up axis must be x, y or z");

    /* a motion without the roles that the normalization needs */
    affect_features_options_default(&opt);
    affect_features *f = create(&opt, m); /* scale arm, normalize */
    const char *keep[] = {"Hips", "Chest", "UpperArm_R", "LowerArm_R", "Hand_R"};
    affect_motion *no_hips = NULL, *no_arm = NULL;
    affect_error err;
    assert_int_equal(affect_motion_select(m, keep, 5, &no_hips, &err), AFFECT_OK);
    expect_extract_error(f, no_hips, "joint \"UpperLeg_L\" of the model is not in the motion");
    const char *hips_only[] = {"Hips", "Chest"};
    opt.joints = hips_only;
    opt.n_joints = 2;
    affect_features_free(f);
    f = create(&opt, m);
    expect_extract_error(f, no_hips,
                         "cannot remove the heading: no left/right hip or shoulder roles resolve "
                         "in the motion (train with {\"normalize\": false})");
    const char *legs[] = {"Hips", "Chest", "UpperLeg_L", "UpperLeg_R"};
    assert_int_equal(affect_motion_select(m, legs, 4, &no_arm, &err), AFFECT_OK);
    expect_extract_error(f, no_arm,
                         "cannot scale by the arm: the right_shoulder and right_hand roles do "
                         "not both resolve in the motion (train with {\"scale\": \"none\"})");
    /* the automatic scale is decided on the first motion: none when the arm is absent */
    affect_features_free(f);
    f = create(&opt, no_arm);
    assert_false(f->scale_arm);
    affect_features_free(f);
    opt.scale = AFFECT_FEATURES_SCALE_ARM;
    f = create(&opt, no_arm);
    expect_extract_error(f, no_arm,
                         "cannot scale by the arm: the right_shoulder and right_hand roles do "
                         "not both resolve in the motion (train with {\"scale\": \"none\"})");
    affect_features_free(f);
    affect_motion_free(no_hips);
    affect_motion_free(no_arm);
    affect_motion_free(m);
}

/* ---- the binary form ---- */

static void put32(unsigned char *p, uint32_t v)
{
    for (int i = 0; i < 4; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}

static unsigned char *encode(const affect_features *f, size_t *size)
{
    assert_true(affect_features_encoded_size(f, size));
    unsigned char *buf = malloc(*size);
    affect_features_encode_into(f, buf);
    return buf;
}

static void expect_decode_error(const unsigned char *data, size_t size, const char *msg)
{
    affect_features *f = NULL;
    affect_error err;
    assert_int_equal(affect_features_decode(data, size, &f, &err), AFFECT_ERR_FORMAT);
    assert_null(f);
    if (msg)
        assert_string_equal(err.msg, msg);
}

static void test_binary_form(void **state)
{
    affect_motion *m = make_motion(0, 0, 0);
    const char *entries[] = {"right_hand", "Chest", "pelvis"};
    affect_features_options opt;
    affect_features_options_default(&opt);
    opt.joints = entries;
    opt.n_joints = 3;
    opt.velocity = true;
    opt.up_axis = 1;
    affect_features *f = create(&opt, m);
    size_t size;
    unsigned char *buf = encode(f, &size);
    /* 16 header + 3 unit + entries (12 + 7 + 8) + skeleton (8 + 7 + 6) + 12 parents */
    assert_int_equal(size, 16 + 3 + 27 + 21 + 12);
    assert_memory_equal(buf, "\x01\x07\x03\x00\x03\x00\x00\x00", 8);
    assert_memory_equal(buf + 16, "arm", 3);
    affect_features *g = NULL;
    affect_error err;
    assert_int_equal(affect_features_decode(buf, size, &g, &err), AFFECT_OK);
    assert_int_equal(g->n_joints, 3);
    for (int j = 0; j < 3; j++) {
        assert_string_equal(g->joints[j], f->joints[j]);
        assert_string_equal(g->skeleton[j], f->skeleton[j]);
        assert_int_equal(g->parents[j], f->parents[j]);
    }
    assert_true(g->normalize && g->scale_arm && g->velocity && g->up_axis == 1);
    assert_true(g->fps == 10.0);
    assert_string_equal(g->unit, "arm");
    size_t size2;
    unsigned char *buf2 = encode(g, &size2);
    assert_int_equal(size, size2);
    assert_memory_equal(buf, buf2, size);
    free(buf2);
    affect_features_free(g);

    /* every truncation is refused */
    for (size_t n = 0; n < size; n++)
        expect_decode_error(buf, n, NULL);
    expect_decode_error(buf, 15, "truncated: 15 bytes is shorter than the 16-byte header");
    expect_decode_error(buf, size - 1, "truncated: 78 bytes, expected 79 for 3 joints");
    unsigned char *c = malloc(size + 1);
    memcpy(c, buf, size);
    c[size] = 0;
    expect_decode_error(c, size + 1, "trailing bytes: 80 bytes, expected 79 for 3 joints");
#define CORRUPT(stmt, msg)                                                                         \
    do {                                                                                           \
        memcpy(c, buf, size);                                                                      \
        stmt;                                                                                      \
        expect_decode_error(c, size, msg);                                                         \
    } while (0)
    CORRUPT(c[0] = 3, "up axis 3 out of range (0 .. 2)");
    CORRUPT(c[1] = 0x27, "unknown flags 0x27 (offset 1)");
    CORRUPT(c[1] = 0x0f, "flags 0x0f: normalize and the body frame exclude each other (offset 1)");
    CORRUPT(c[1] = 0x16, "flags 0x16: root needs the body frame (offset 1)");
    CORRUPT(c[3] = 1, "reserved byte 3 is not zero");
    CORRUPT(put32(c + 4, 0), "joint count 0 out of range (1 .. 4096)");
    CORRUPT(c[15] = 0x7f; c[14] = 0xf0, "frames per second inf out of range (0 .. 100000]");
    CORRUPT(c[2] = 16, "truncated or bad unit (length 16 at offset 2)");
    CORRUPT(c[17] = '/', "bad unit character at offset 17");
    CORRUPT(c[19] = 0, "joint entry 0: length 0 out of range (1 .. 1024) at offset 19");
    CORRUPT(c[23] = 0, "joint entry 0 contains a NUL byte (offset 19)");
    CORRUPT(c[54] = 200, "truncated in skeleton name 1 (offset 54)");
    CORRUPT(c[47] = 9, "skeleton name 0: length 2310 out of range (1 .. 1024) at offset 46");
    CORRUPT(put32(c + size - 4, 3), "parent 3 of joint 2 out of range");
    CORRUPT(put32(c + size - 4, 0xfffffffeu), "parent -2 of joint 2 out of range");
    CORRUPT(put32(c + size - 4, 0), "joint 0 is its own ancestor"); /* 2 → 0 → 1 → 2 */
#undef CORRUPT
    /* two joints with one name (a definition no encoder of ours writes) */
    char *dup[3] = {"Hand_R", "Chest", "Chest"};
    affect_features bad = *f;
    bad.skeleton = dup;
    size_t gsize;
    unsigned char *gbuf = encode(&bad, &gsize);
    expect_decode_error(gbuf, gsize, "joints 1 and 2 have the same name");
    free(gbuf);
    free(c);
    free(buf);
    affect_features_free(f);
    affect_motion_free(m);
}

static void test_posture_motion(void **state)
{
    affect_motion *m = make_motion(0, 0, 0);
    const char *entries[] = {"Hand_R", "Chest", "pelvis"};
    affect_features_options opt;
    affect_features_options_default(&opt);
    opt.joints = entries;
    opt.n_joints = 3;
    opt.velocity = true;
    affect_features *f = create(&opt, m);
    uint32_t T;
    double *x = extract(f, m, &T);
    affect_motion *p = NULL;
    affect_error err;
    assert_int_equal(affect_features_posture_motion(f, x, T, &p, &err), AFFECT_OK);
    assert_int_equal(p->n_frames, 4);
    assert_int_equal(p->n_joints, 3);
    assert_string_equal(p->names[0], "Hand_R");
    assert_string_equal(p->names[2], "Hips");
    assert_int_equal(p->parents[0], 1);
    assert_int_equal(p->parents[1], 2);
    assert_int_equal(p->parents[2], -1);
    assert_string_equal(p->unit, "arm");
    assert_true(p->fps == 10.0);
    for (uint32_t t = 0; t < 4; t++)
        for (int i = 0; i < 9; i++)
            assert_true(p->pos[t * 9 + i] == (float)x[t * 18 + i]);
    affect_motion_free(p);
    x[5] = 1e300; /* does not fit a float */
    p = NULL;
    assert_int_equal(affect_features_posture_motion(f, x, T, &p, &err), AFFECT_ERR_FORMAT);
    assert_null(p);
    affect_free(x);
    affect_features_free(f);
    affect_motion_free(m);
}

/* ---- out of memory ---- */

typedef struct oom_ctx {
    const affect_motion *m;
    const affect_features *f;
    const unsigned char *blob;
    size_t size;
    affect_features *out;
    double *x;
    affect_motion *posture;
} oom_ctx;

static affect_status oom_create(void *ctx, affect_error *err)
{
    oom_ctx *c = ctx;
    static const char *const entries[] = {"right_hand", "Chest", "pelvis"};
    affect_features_options opt;
    affect_features_options_default(&opt);
    opt.joints = entries;
    opt.n_joints = 3;
    c->out = NULL;
    return affect_features_create(&opt, c->m, &c->out, err);
}

static affect_status oom_decode(void *ctx, affect_error *err)
{
    oom_ctx *c = ctx;
    c->out = NULL;
    return affect_features_decode(c->blob, c->size, &c->out, err);
}

static void oom_finish_features(void *ctx, affect_status st)
{
    oom_ctx *c = ctx;
    if (st)
        assert_null(c->out);
    affect_features_free(c->out);
    c->out = NULL;
}

static affect_status oom_extract(void *ctx, affect_error *err)
{
    oom_ctx *c = ctx;
    uint32_t T;
    c->x = NULL;
    affect_status st = affect_features_extract(c->f, c->m, &c->x, &T, NULL, err);
    if (!st)
        st = affect_features_posture_motion(c->f, c->x, T, &c->posture, err);
    return st;
}

static void oom_finish_extract(void *ctx, affect_status st)
{
    oom_ctx *c = ctx;
    affect_free(c->x);
    affect_motion_free(c->posture);
    c->x = NULL;
    c->posture = NULL;
}

/* affect_features_position_gradient is the transpose of the positions' map: for a weight g on
 * the observations and a displacement δ of joints that move neither the heading (hips,
 * shoulders) nor the arm's scale (the right arm), g · (x(p + δ) − x(p)) = out · δ, in the body
 * frame (the root among them: every entry is relative to it) and the first frame (not its
 * first frame's root: the transform's origin); velocity columns are refused. */
static void test_position_gradient(void **state)
{
    (void)state;
    affect_motion *m, *moved;
    affect_error err;
    assert_int_equal(affect_motion_synth("wave", "happy", 1, NULL, &m, &err), AFFECT_OK);
    static const char *const free_joints[] = {"Hips", "Head", "Hand_L", "LowerArm_L", "Foot_R"};
    for (int body = 0; body < 2; body++) {
        affect_features_options opt;
        affect_features_options_default(&opt);
        opt.frame = body ? AFFECT_FEATURES_FRAME_BODY : AFFECT_FEATURES_FRAME_FIRST;
        affect_features *f = create(&opt, m);
        uint32_t T, dim = affect_features_dim(f), J = m->n_joints;
        double *x0 = extract(f, m, &T);
        double *g = test_malloc(sizeof(double) * T * dim),
               *out = test_malloc(sizeof(double) * T * J * 3);
        affect_rng rng;
        affect_rng_seed(&rng, 7);
        for (size_t i = 0; i < (size_t)T * dim; i++)
            g[i] = affect_rng_uniform(&rng) - 0.5;
        assert_int_equal(affect_features_position_gradient(f, m, g, out, NULL, &err), AFFECT_OK);
        assert_int_equal(affect_motion_clone(m, &moved, &err), AFFECT_OK);
        double lin = 0;
        for (uint32_t t = 0; t < T; t++)
            for (size_t k = 0; k < sizeof free_joints / sizeof *free_joints; k++) {
                int32_t j = affect_motion_find_joint(m, free_joints[k]);
                assert_true(j >= 0);
                if (!body && t == 0 && k == 0)
                    continue; /* the first frame's root is the first-frame transform's origin */
                float *p = affect_motion_at(moved, t, (uint32_t)j);
                const float *q = affect_motion_at(m, t, (uint32_t)j);
                for (int c = 0; c < 3; c++) {
                    p[c] = q[c] + (float)((affect_rng_uniform(&rng) - 0.5) / 32);
                    lin += out[((size_t)t * J + (uint32_t)j) * 3 + c] * ((double)p[c] - q[c]);
                }
            }
        double *x1 = extract(f, moved, &T), dx = 0, scale = 0;
        for (size_t i = 0; i < (size_t)T * dim; i++) {
            dx += g[i] * (x1[i] - x0[i]);
            scale += fabs(g[i] * (x1[i] - x0[i]));
        }
        if (!(fabs(dx - lin) <= 1e-9 * scale + 1e-12))
            fail_msg("%s frame: g . dx = %.17g, out . delta = %.17g", body ? "body" : "first", dx,
                     lin);
        assert_true(scale > 0);
        affect_free(x0);
        affect_free(x1);
        test_free(g);
        test_free(out);
        affect_motion_free(moved);
        affect_features_free(f);
    }
    affect_features_options opt;
    affect_features_options_default(&opt);
    opt.velocity = true;
    affect_features *f = create(&opt, m);
    double g[1] = {0}, out[1];
    assert_int_equal(affect_features_position_gradient(f, m, g, out, NULL, &err),
                     AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "the observations have velocity or root columns: only positions "
                                 "map back to the joints");
    affect_features_free(f);
    affect_motion_free(m);
}

static void test_out_of_memory(void **state)
{
    affect_motion *m = make_motion(0, 0, 0);
    oom_ctx c = {m, NULL, NULL, 0, NULL, NULL, NULL};
    long absorbed; /* affect_roles_resolve parses names on the fly when it cannot allocate */
    assert_true(tu_oom_sweep(oom_create, &c, oom_finish_features, &absorbed) >= 8);
    affect_error err;
    assert_int_equal(oom_create(&c, &err), AFFECT_OK);
    c.f = c.out;
    c.out = NULL;
    size_t size;
    unsigned char *blob = encode(c.f, &size);
    c.blob = blob;
    c.size = size;
    assert_true(tu_oom_sweep(oom_decode, &c, oom_finish_features, NULL) >= 8);
    assert_true(tu_oom_sweep(oom_extract, &c, oom_finish_extract, &absorbed) >= 3);
    free(blob);
    affect_features_free((affect_features *)c.f);
    affect_motion_free(m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_defaults_and_raw_values),
        cmocka_unit_test(test_normalization_invariance),
        cmocka_unit_test(test_body_frame),
        cmocka_unit_test(test_mirror),
        cmocka_unit_test(test_roles_and_skeleton),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_binary_form),
        cmocka_unit_test(test_posture_motion),
        cmocka_unit_test(test_position_gradient),
        cmocka_unit_test(test_out_of_memory),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
