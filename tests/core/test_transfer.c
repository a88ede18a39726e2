/*
 * test_transfer.c — emotion transfer (affect/transfer.h): a change whose answer is known (a
 * posture offset and a doubled slow amplitude applied to one action, learned back from
 * another), strength 0 and monotonicity, rigidity, foot contacts held, determinism, the donor
 * pairs and components, and the errors.
 */
#include <string.h>

#include "testutil.h"

#include "affect/laban.h"
#include "affect/quat.h"
#include "affect/roles.h"
#include "affect/skeleton.h"
#include "affect/synth.h"
#include "affect/transfer.h"

#define PI 3.14159265358979323846

/* A 4-joint chain Root (position channels) → Arm → Fore → Fore_end at 30 fps: Arm turns about
 * axis `axis` by amp · sin(2π f t) after a fixed posture rotation about y by `tilt`. */
static affect_motion *chain(uint32_t frames, int axis, double amp, double f, double tilt)
{
    static const char *const names[4] = {"Root", "Arm", "Fore", "Fore_end"};
    static const int32_t parents[4] = {-1, 0, 1, 2};
    static const double offsets[4][3] = {{0, 1, 0}, {0, 0.1, 0}, {0.3, 0, 0}, {0.25, 0, 0}};
    affect_motion *m = NULL;
    assert_int_equal(affect_motion_create(frames, 4, 30, &m, NULL), AFFECT_OK);
    assert_int_equal(affect_motion_add_skeleton(m, true, NULL), AFFECT_OK);
    for (uint32_t j = 0; j < 4; j++) {
        m->parents[j] = parents[j];
        assert_int_equal(affect_motion_set_name(m, j, names[j], strlen(names[j]), NULL), AFFECT_OK);
        memcpy(m->skel[j].offset, offsets[j], sizeof offsets[j]);
    }
    for (int a = 0; a < 3; a++)
        m->skel[0].channel[a] = (uint8_t)(AFFECT_CH_XPOS + a);
    for (int a = 0; a < 3; a++)
        m->skel[0].channel[3 + a] = (uint8_t)(AFFECT_CH_ZROT + (a == 0 ? 0 : a == 1 ? -2 : -1));
    m->skel[0].n_channels = 6;
    for (uint32_t j = 1; j < 3; j++) {
        m->skel[j].channel[0] = AFFECT_CH_ZROT;
        m->skel[j].channel[1] = AFFECT_CH_XROT;
        m->skel[j].channel[2] = AFFECT_CH_YROT;
        m->skel[j].n_channels = 3;
    }
    m->skel[3].flags = AFFECT_JOINT_END_SITE;
    double post[4], v[3] = {0, tilt, 0};
    affect_quat_exp(v, post);
    for (uint32_t t = 0; t < frames; t++)
        for (uint32_t j = 0; j < 4; j++) {
            double q[4] = {1, 0, 0, 0};
            if (j == 1) {
                double w[3] = {0, 0, 0}, r[4];
                w[axis] = amp * sin(2 * PI * f * t / 30.0);
                affect_quat_exp(w, r);
                affect_quat_mul(post, r, q);
            }
            float *qf = m->rot + ((size_t)t * 4 + j) * 4, *tr = m->trans + ((size_t)t * 4 + j) * 3;
            for (int a = 0; a < 4; a++)
                qf[a] = (float)q[a];
            for (int a = 0; a < 3; a++)
                tr[a] = (float)offsets[j][a];
        }
    assert_int_equal(affect_motion_fk(m, NULL), AFFECT_OK);
    return m;
}

/* Joint 1's rotation vector at frame t. */
static void arm_rotation(const affect_motion *m, uint32_t t, double v[3])
{
    const float *p = m->rot + ((size_t)t * m->n_joints + 1) * 4;
    double q[4] = {p[0], p[1], p[2], p[3]};
    affect_quat_log(q, v);
}

static void test_known_change(void **state)
{
    (void)state;
    /* donors: another action (about x), its target doubles the amplitude and tilts by 0.3 */
    affect_motion *a = chain(300, 0, 0.2, 0.5, 0.0), *b = chain(300, 0, 0.4, 0.5, 0.3);
    affect_motion *src = chain(240, 2, 0.1, 0.5, 0.0), *out = NULL;
    const affect_motion *from[1] = {a}, *to[1] = {b};
    affect_transfer_options opt;
    affect_transfer_options_default(&opt);
    affect_transfer_report rep;
    affect_error err;
    assert_int_equal(affect_transfer(src, from, to, 1, &opt, &out, &rep, &err), AFFECT_OK);
    /* Arm and Fore (Root has positions, Fore_end no child); Fore does not move: the report's
     * means are over both */
    assert_int_equal(rep.joints_changed, 2);
    tu_assert_near(rep.posture_deg, 0.3 * 180 / PI / 2, 0.03);
    tu_assert_near(rep.ratio[0], sqrt(2.0), 0.02);
    /* the output: the tilt about y added, the swing about z doubled */
    double lo = 0, hi = 0, ymean = 0;
    for (uint32_t t = 0; t < out->n_frames; t++) {
        double v[3];
        arm_rotation(out, t, v);
        ymean += v[1] / out->n_frames;
        double turned[4], inv[4], q[4];
        double tilt[3] = {0, -0.3, 0};
        affect_quat_exp(tilt, inv);
        const float *p = out->rot + ((size_t)t * 4 + 1) * 4;
        double qq[4] = {p[0], p[1], p[2], p[3]};
        affect_quat_mul(inv, qq, q);
        affect_quat_log(q, turned);
        lo = fmin(lo, turned[2]);
        hi = fmax(hi, turned[2]);
    }
    tu_assert_near(ymean, 0.3, 0.01);
    tu_assert_near(hi, 0.2, 0.01);
    tu_assert_near(lo, -0.2, 0.01);
    affect_motion_free(out);
    /* strength 0.5: half the tilt, √2 the amplitude */
    opt.strength = 0.5;
    assert_int_equal(affect_transfer(src, from, to, 1, &opt, &out, &rep, &err), AFFECT_OK);
    tu_assert_near(rep.posture_deg, 0.15 * 180 / PI / 2, 0.03);
    tu_assert_near(rep.ratio[0], pow(2.0, 0.25), 0.02);
    affect_motion_free(out);
    /* strength 0: the source itself, byte for byte */
    opt.strength = 0;
    assert_int_equal(affect_transfer(src, from, to, 1, &opt, &out, &rep, &err), AFFECT_OK);
    assert_memory_equal(out->rot, src->rot, (size_t)src->n_frames * 4 * 4 * sizeof(float));
    assert_memory_equal(out->pos, src->pos, (size_t)src->n_frames * 4 * 3 * sizeof(float));
    affect_motion_free(out);
    affect_motion_free(a);
    affect_motion_free(b);
    affect_motion_free(src);
}

static double weight_of(const affect_motion *m)
{
    affect_roles roles;
    affect_roles_resolve(m, &roles);
    affect_laban_options lo;
    affect_laban_options_default(&lo);
    double v[AFFECT_LABAN_N];
    affect_error err;
    assert_int_equal(affect_laban_vector(m, &roles, &lo, v, &err), AFFECT_OK);
    return v[0]; /* WeightAll */
}

/* Largest speed of the joint during the frames where it rests in src (contact: as transfer.c). */
static double foot_slide(const affect_motion *src, const affect_motion *m, int32_t foot)
{
    uint32_t nj = src->n_joints;
    double worst = 0;
    for (uint32_t t = 1; t < src->n_frames; t++) {
        double ds = 0, dm = 0;
        for (int a = 0; a < 3; a++) {
            double u = src->pos[((size_t)t * nj + (size_t)foot) * 3 + (size_t)a] -
                       src->pos[((size_t)(t - 1) * nj + (size_t)foot) * 3 + (size_t)a];
            double w = m->pos[((size_t)t * nj + (size_t)foot) * 3 + (size_t)a] -
                       m->pos[((size_t)(t - 1) * nj + (size_t)foot) * 3 + (size_t)a];
            ds += u * u;
            dm += w * w;
        }
        if (sqrt(ds) * src->fps < 0.1) /* resting in the source */
            worst = fmax(worst, (sqrt(dm) - sqrt(ds)) * src->fps);
    }
    return worst;
}

static void test_synthetic_corpus(void **state)
{
    (void)state;
    affect_motion *src = NULL, *a[2] = {NULL, NULL}, *b[2] = {NULL, NULL}, *out[5] = {NULL};
    affect_error err;
    assert_int_equal(affect_motion_synth("walk", "neutral", 1, NULL, &src, &err), AFFECT_OK);
    assert_int_equal(affect_motion_synth("knock", "neutral", 2, NULL, &a[0], &err), AFFECT_OK);
    assert_int_equal(affect_motion_synth("knock", "angry", 2, NULL, &b[0], &err), AFFECT_OK);
    assert_int_equal(affect_motion_synth("wave", "neutral", 3, NULL, &a[1], &err), AFFECT_OK);
    assert_int_equal(affect_motion_synth("wave", "angry", 3, NULL, &b[1], &err), AFFECT_OK);
    affect_transfer_options opt;
    affect_transfer_options_default(&opt);
    affect_transfer_report rep;
    double last = -1;
    for (int k = 0; k < 5; k++) {
        opt.strength = 0.5 * k;
        assert_int_equal(affect_transfer(src, (const affect_motion *const *)a,
                                         (const affect_motion *const *)b, 2, &opt, &out[k], &rep,
                                         &err),
                         AFFECT_OK);
        assert_int_equal(out[k]->n_frames, src->n_frames);
        assert_true(out[k]->fps == src->fps);
        assert_int_equal(out[k]->n_joints, src->n_joints);
        double variation;
        int32_t worst;
        assert_int_equal(affect_motion_bone_variation(out[k], &variation, &worst, &err), AFFECT_OK);
        assert_true(variation <= 1e-4);
        double w = weight_of(out[k]);
        assert_true(w > last); /* toward angry: WeightAll rises with the strength */
        last = w;
        if (k > 0)
            assert_true(rep.contact_frames[0] > 0 && rep.contact_frames[1] > 0);
    }
    /* the walk's root path stays; its feet do not slide where they rested */
    affect_roles roles;
    affect_roles_resolve(src, &roles);
    int32_t pelvis = roles.joint[AFFECT_ROLE_PELVIS];
    assert_true(pelvis >= 0);
    for (uint32_t t = 0; t < src->n_frames; t += 7)
        for (int ax = 0; ax < 3; ax++)
            tu_assert_near(
                out[4]->pos[((size_t)t * src->n_joints + (size_t)pelvis) * 3 + (size_t)ax],
                out[0]->pos[((size_t)t * src->n_joints + (size_t)pelvis) * 3 + (size_t)ax], 1e-5);
    for (int side = 0; side < 2; side++) {
        int32_t foot = roles.joint[side ? AFFECT_ROLE_RIGHT_FOOT : AFFECT_ROLE_LEFT_FOOT];
        assert_true(foot >= 0);
        assert_true(foot_slide(out[0], out[2], foot) <= 0.01);
        assert_true(foot_slide(out[0], out[4], foot) <= 0.01);
    }
    /* deterministic */
    affect_motion *again = NULL;
    opt.strength = 2;
    assert_int_equal(affect_transfer(src, (const affect_motion *const *)a,
                                     (const affect_motion *const *)b, 2, &opt, &again, NULL, &err),
                     AFFECT_OK);
    assert_memory_equal(again->rot, out[4]->rot,
                        (size_t)src->n_frames * src->n_joints * 4 * sizeof(float));
    affect_motion_free(again);
    for (int k = 0; k < 5; k++)
        affect_motion_free(out[k]);
    for (int i = 0; i < 2; i++) {
        affect_motion_free(a[i]);
        affect_motion_free(b[i]);
    }
    affect_motion_free(src);
}

static void test_pairs(void **state)
{
    (void)state;
    /* 6 rows of 2 components: classes 0 (source) and 1 (target); contents 0, 1, 2 */
    const double x[12] = {0, 0, 5, 5, 10, 0,  /* rows 0..2: class 0, contents 0, 1, 2 */
                          0, 1, 5, 6, 10, 1}; /* rows 3..5: class 1, the same contents */
    const int32_t label[6] = {0, 0, 0, 1, 1, 1};
    const bool use[2] = {true, true};
    const double dq[6] = {3.0, 1.0, 2.0, NAN, NAN, NAN};
    uint32_t from[3], to[3], got;
    double dist[3];
    affect_error err;
    assert_int_equal(affect_transfer_pairs(x, 6, 2, label, NULL, use, dq, 0, 1, 3, 1, from, to,
                                           dist, &got, &err),
                     AFFECT_OK);
    assert_int_equal(got, 3);
    assert_int_equal(from[0], 1);
    assert_int_equal(to[0], 4);
    assert_int_equal(from[1], 2);
    assert_int_equal(to[1], 5);
    assert_int_equal(from[2], 0);
    assert_int_equal(to[2], 3);
    /* two candidates each: the nearest and the next */
    uint32_t to2[6];
    double d2[6];
    assert_int_equal(
        affect_transfer_pairs(x, 6, 2, label, NULL, use, dq, 0, 1, 3, 2, from, to2, d2, &got, &err),
        AFFECT_OK);
    assert_int_equal(got, 3);
    assert_int_equal(to2[0], 4);
    assert_int_equal(to2[1], 3); /* from row 1 (5, 5): rows 3 (0, 1) and 5 (10, 1) tie */
    assert_true(d2[0] < d2[1]);
    assert_int_equal(to2[2], 5); /* from row 2 (10, 0): row 5 (10, 1), then row 3 (0, 1) */
    assert_int_equal(to2[3], 3);
    /* no row of the target: no pair */
    const int32_t only0[6] = {0, 0, 0, 0, 0, 0};
    assert_int_equal(affect_transfer_pairs(x, 6, 2, only0, NULL, use, dq, 0, 1, 3, 1, from, to,
                                           NULL, &got, &err),
                     AFFECT_OK);
    assert_int_equal(got, 0);
    /* with content keys: row 1 (content 8) pairs with row 4; row 2 has no key */
    const int64_t group[6] = {7, 8, INT64_MIN, 7, 8, 9};
    assert_int_equal(affect_transfer_pairs(x, 6, 2, label, group, use, dq, 0, 1, 3, 1, from, to,
                                           NULL, &got, &err),
                     AFFECT_OK);
    assert_int_equal(got, 2);
    assert_int_equal(from[0], 1);
    assert_int_equal(to[0], 4);
    assert_int_equal(from[1], 0);
    assert_int_equal(to[1], 3);
    const int64_t apart[6] = {1, 2, 3, 4, 5, 6};
    assert_int_equal(affect_transfer_pairs(x, 6, 2, label, apart, use, dq, 0, 1, 3, 1, from, to,
                                           NULL, &got, &err),
                     AFFECT_OK);
    assert_int_equal(got, 0);
    /* components: salient for both emotions are dropped; all when none is left */
    const bool salient[6] = {true, true, false, /* class 0 */ true, false, true};
    bool out[3];
    assert_false(affect_transfer_components(salient, 3, 0, 1, out));
    assert_true(!out[0] && out[1] && out[2]);
    assert_false(affect_transfer_components(salient, 3, -1, 1, out));
    assert_true(!out[0] && out[1] && !out[2]);
    const bool all[6] = {true, true, true, true, true, true};
    assert_true(affect_transfer_components(all, 3, 0, 1, out));
    assert_true(out[0] && out[1] && out[2]);
}

static void test_errors(void **state)
{
    (void)state;
    affect_motion *m = chain(60, 0, 0.2, 0.5, 0), *out = NULL;
    const affect_motion *from[1] = {m}, *to[1] = {m};
    affect_transfer_options opt;
    affect_transfer_options_default(&opt);
    affect_error err;
    opt.strength = 3;
    assert_int_equal(affect_transfer(m, from, to, 1, &opt, &out, NULL, &err), AFFECT_ERR_INVALID);
    assert_non_null(strstr(err.msg, "strength must be between 0 and 2"));
    affect_transfer_options_default(&opt);
    opt.band_hz[1] = 0.5;
    assert_int_equal(affect_transfer(m, from, to, 1, &opt, &out, NULL, &err), AFFECT_ERR_INVALID);
    assert_non_null(strstr(err.msg, "band edges"));
    affect_transfer_options_default(&opt);
    assert_int_equal(affect_transfer(m, from, to, 0, &opt, &out, NULL, &err), AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "no donor pairs");
    const affect_motion *none[1] = {NULL};
    assert_int_equal(affect_transfer(m, none, to, 1, &opt, &out, NULL, &err), AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "donor pair 0: its motion in the source emotion is missing");
    /* donors of another skeleton */
    affect_motion *walk = NULL;
    assert_int_equal(affect_motion_synth("walk", "sad", 1, NULL, &walk, &err), AFFECT_OK);
    const affect_motion *other[1] = {walk};
    assert_int_equal(affect_transfer(m, other, other, 1, &opt, &out, NULL, &err),
                     AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "no donor pair has a joint of the desired motion's skeleton "
                                 "(joint names)");
    assert_null(out);
    affect_motion_free(walk);
    affect_motion_free(m);
}

typedef struct oom_ctx {
    const affect_motion *src, *from[1], *to[1];
    affect_motion *out;
} oom_ctx;

static affect_status oom_op(void *p, affect_error *err)
{
    oom_ctx *c = p;
    return affect_transfer(c->src, c->from, c->to, 1, NULL, &c->out, NULL, err);
}

static void oom_finish(void *p, affect_status st)
{
    (void)st;
    oom_ctx *c = p;
    affect_motion_free(c->out);
    c->out = NULL;
}

static void test_out_of_memory(void **state)
{
    (void)state;
    affect_motion *a = chain(90, 0, 0.2, 0.5, 0), *b = chain(90, 0, 0.4, 0.5, 0.3);
    affect_motion *src = NULL;
    affect_error err;
    /* a position-only desired motion: its skeletal form comes from inverse kinematics */
    assert_int_equal(affect_motion_clone(a, &src, &err), AFFECT_OK);
    affect_motion_drop_skeleton(src);
    oom_ctx c = {src, {a}, {b}, NULL};
    long absorbed = 0; /* affect_roles_resolve falls back when its scratch allocation fails */
    assert_true(tu_oom_sweep(oom_op, &c, oom_finish, &absorbed) > 10);
    affect_motion_free(src);
    affect_motion_free(a);
    affect_motion_free(b);
}

/* A pair's target: the best-ranked candidate that no earlier pair took, else the best. */
static void test_pick_target(void **state)
{
    (void)state;
    const uint32_t rows[3] = {40, 41, 42};
    const uint32_t order[3] = {2, 0, 1}; /* ranked: row 42, then 40, then 41 */
    const uint32_t none[1] = {0}, took42[2] = {42, 7}, took_all[3] = {42, 40, 41};
    assert_int_equal(affect_transfer_pick_target(order, rows, 3, none, 0), 2);
    assert_int_equal(affect_transfer_pick_target(order, rows, 3, took42, 2), 0);
    assert_int_equal(affect_transfer_pick_target(order, rows, 3, took_all, 2), 1);
    assert_int_equal(affect_transfer_pick_target(order, rows, 3, took_all, 3), 2);
    assert_int_equal(affect_transfer_pick_target(order, rows, 1, took42, 1), 2);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_known_change),  cmocka_unit_test(test_synthetic_corpus),
        cmocka_unit_test(test_pairs),         cmocka_unit_test(test_errors),
        cmocka_unit_test(test_out_of_memory), cmocka_unit_test(test_pick_target),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
