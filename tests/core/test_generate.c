/*
 * test_generate.c — HMM_NN generation (affect/generate.h) on procedural motions: a neutral knock
 * regenerated from sad neighbours (other performers) has lower WeightAll and TimeAll than the
 * source, from angry neighbours higher; the output has the desired motion's length, fps, names,
 * parents and unit; copies of the desired path keep it closer (DTW); a larger covariance scale
 * changes state less often; same seed → identical bytes; the inverse normalization is exact;
 * mismatched skeletons are excluded and counted; DTW is 0 on itself, symmetric, and small for a
 * time-warped copy; every error message; every allocation failing in turn.
 */
#include <string.h>

#include "testutil.h"
#include "affect/skeleton.h"
#include "affect/features.h"
#include "affect/generate.h"
#include "affect/laban.h"
#include "affect/synth.h"

#define N_NB 5

static affect_motion *synth(const char *action, const char *emotion, uint64_t seed, double fps)
{
    affect_synth_options so;
    affect_synth_options_default(&so);
    so.fps = fps;
    affect_motion *m = NULL;
    affect_error err;
    assert_int_equal(affect_motion_synth(action, emotion, seed, &so, &m, &err), AFFECT_OK);
    return m;
}

static void free_all(affect_motion **m, uint32_t n)
{
    for (uint32_t i = 0; i < n; i++)
        affect_motion_free(m[i]);
}

static void laban(const affect_motion *m, double v[AFFECT_LABAN_N])
{
    affect_roles roles;
    affect_roles_resolve(m, &roles);
    affect_laban_options lo;
    affect_laban_options_default(&lo);
    affect_error err;
    assert_int_equal(affect_laban_vector(m, &roles, &lo, v, &err), AFFECT_OK);
}

static affect_motion *generate(const affect_motion *d, affect_motion **nb, uint32_t n,
                               const affect_generate_options *opt, affect_generate_report *rep)
{
    affect_motion *out = NULL;
    affect_error err = {0};
    affect_status st =
        affect_generate(d, (const affect_motion *const *)nb, n, opt, &out, rep, &err);
    if (st)
        fail_msg("affect_generate: %s", err.msg);
    return out;
}

static double dtw(const affect_motion *a, const affect_motion *b)
{
    double d = -1;
    affect_error err;
    assert_int_equal(affect_dtw_distance(a, b, &d, NULL, &err), AFFECT_OK);
    return d;
}

static uint32_t state_changes(const affect_generate_report *rep)
{
    uint32_t c = 0;
    for (uint32_t t = 1; t < rep->n_frames; t++)
        c += rep->path[t] != rep->path[t - 1];
    return c;
}

/* ---- behaviour ---- */

static void test_emotion_transfer(void **state)
{
    (void)state;
    affect_motion *d = synth("knock", "neutral", 1, 30);
    affect_motion *sad[N_NB], *angry[N_NB];
    for (uint32_t i = 0; i < N_NB; i++) {
        sad[i] = synth("knock", "sad", 11 + i, 30);
        angry[i] = synth("knock", "angry", 11 + i, 30);
    }
    /* At 6 Hz the jumps between state means dominate the output's peak energy and
     * acceleration whatever the emotion; 3 Hz smooths them (see the report). */
    affect_generate_options opt;
    affect_generate_options_default(&opt);
    opt.cutoff_hz = 3;
    affect_generate_report rep;
    affect_motion *gs = generate(d, sad, N_NB, &opt, &rep);
    assert_int_equal(rep.neighbours_used, N_NB);
    assert_int_equal(rep.excluded, 0);
    assert_true(rep.iterations >= 1);
    assert_true(isfinite(rep.loglik) && isfinite(rep.viterbi_logprob));
    assert_int_equal(rep.n_frames, d->n_frames);
    for (uint32_t t = 0; t < rep.n_frames; t++)
        assert_true(rep.path[t] >= 0 && rep.path[t] < 12);
    assert_int_equal(rep.path[0], 0); /* π = first state */
    affect_free(rep.path);
    affect_motion *ga = generate(d, angry, N_NB, &opt, NULL);

    /* the desired motion's skeleton, fps, unit and length */
    const affect_motion *g[2] = {gs, ga};
    for (int k = 0; k < 2; k++) {
        assert_int_equal(g[k]->n_frames, d->n_frames);
        assert_int_equal(g[k]->n_joints, d->n_joints);
        assert_true(g[k]->fps == d->fps);
        assert_string_equal(g[k]->unit, d->unit);
        for (uint32_t j = 0; j < d->n_joints; j++) {
            assert_string_equal(g[k]->names[j], d->names[j]);
            assert_int_equal(g[k]->parents[j], d->parents[j]);
        }
        affect_error err;
        assert_int_equal(affect_motion_validate(g[k], &err), AFFECT_OK);
        /* back in the desired motion's place: the root starts within 10 cm of it */
        const float *r0 = affect_motion_at(d, 0, 0), *r1 = affect_motion_at(g[k], 0, 0);
        assert_true(fabs(r0[0] - r1[0]) < 0.1 && fabs(r0[2] - r1[2]) < 0.1);
        assert_true(fabs(r0[1] - r1[1]) < 0.1);
    }

    double vd[AFFECT_LABAN_N], vs[AFFECT_LABAN_N], va[AFFECT_LABAN_N];
    laban(d, vd);
    laban(gs, vs);
    laban(ga, va);
    int w = affect_laban_index("WeightAll"), t = affect_laban_index("TimeAll");
    assert_true(vs[w] < vd[w]);
    assert_true(vs[t] < vd[t]);
    assert_true(va[w] > vd[w]);
    assert_true(va[t] > vd[t]);
    /* at the default cut-off, sad still below angry */
    affect_motion *s6 = generate(d, sad, N_NB, NULL, NULL),
                  *a6 = generate(d, angry, N_NB, NULL, NULL);
    laban(s6, vs);
    laban(a6, va);
    assert_true(vs[w] < va[w]);
    assert_true(vs[t] < va[t]);
    affect_motion_free(s6);
    affect_motion_free(a6);

    affect_motion_free(gs);
    affect_motion_free(ga);
    free_all(sad, N_NB);
    free_all(angry, N_NB);
    affect_motion_free(d);
}

static void test_copies_and_scale(void **state)
{
    (void)state;
    affect_motion *d = synth("knock", "neutral", 1, 30);
    affect_motion *nb[N_NB];
    for (uint32_t i = 0; i < N_NB; i++)
        nb[i] = synth("knock", "sad", 21 + i, 30);
    affect_generate_options opt;
    affect_generate_options_default(&opt);
    affect_motion *g0 = generate(d, nb, N_NB, &opt, NULL);
    opt.copies = 2;
    affect_motion *g2 = generate(d, nb, N_NB, &opt, NULL);
    assert_true(dtw(g2, d) < dtw(g0, d));

    opt.copies = 0;
    affect_generate_report r1, r2;
    affect_motion *s1 = generate(d, nb, N_NB, &opt, &r1);
    opt.covariance_scale = 50;
    affect_motion *s2 = generate(d, nb, N_NB, &opt, &r2);
    assert_true(state_changes(&r2) < state_changes(&r1));
    affect_free(r1.path);
    affect_free(r2.path);

    affect_motion_free(s1);
    affect_motion_free(s2);
    affect_motion_free(g0);
    affect_motion_free(g2);
    free_all(nb, N_NB);
    affect_motion_free(d);
}

/* A clock that ticks once per reading, so each stage lasts exactly 1 "second" when the
 * stages read it once at each boundary. */
static double ticks;
static double tick_clock(void)
{
    return ticks += 1.0;
}

static void test_single_neighbour_and_no_filter(void **state)
{
    (void)state;
    affect_motion *d = synth("wave", "neutral", 3, 30);
    affect_motion *nb = synth("wave", "happy", 4, 30);
    affect_generate_options opt;
    affect_generate_options_default(&opt);
    opt.cutoff_hz = 0;
    opt.keep_path = false; /* every output frame is exactly a state mean */
    opt.rigid = false;
    affect_generate_report rep;
    affect_motion *g = generate(d, &nb, 1, &opt, &rep);
    assert_int_equal(rep.neighbours_used, 1);
    /* no clock: no stage times */
    assert_true(rep.t_features == 0 && rep.t_train == 0 && rep.t_viterbi == 0 && rep.t_render == 0);
    affect_free(rep.path);
    /* with a clock: five readings, one per stage boundary, and the same motion */
    opt.clock = tick_clock;
    ticks = 0;
    affect_motion *g2 = generate(d, &nb, 1, &opt, &rep);
    assert_true(ticks == 5);
    assert_true(rep.t_features == 1 && rep.t_train == 1 && rep.t_viterbi == 1 && rep.t_render == 1);
    assert_memory_equal(g->pos, g2->pos, (size_t)d->n_frames * d->n_joints * 3 * sizeof(float));
    affect_motion_free(g2);
    /* linear rendering, unfiltered: the same path; at each run's centre frame (odd-length
     * runs) the frame equals the step output (the state mean), and between the centres of two
     * runs every frame lies on the segment between the two means */
    opt.clock = NULL;
    opt.render = AFFECT_GENERATE_LINEAR;
    affect_generate_report rl;
    affect_motion *gl = generate(d, &nb, 1, &opt, &rl);
    assert_memory_equal(rl.path, rep.path, (size_t)rl.n_frames * sizeof *rl.path);
    uint32_t runs = 0, checked = 0;
    size_t row = (size_t)d->n_joints * 3;
    double prev_c = -1;
    uint32_t prev_s = 0;
    for (uint32_t s = 0; s < rl.n_frames;) {
        uint32_t e = s + 1;
        while (e < rl.n_frames && rl.path[e] == rl.path[s])
            e++;
        double c = 0.5 * (double)(s + e - 1);
        if ((e - s) % 2 == 1) {
            uint32_t ci = (s + e - 1) / 2;
            for (size_t i = 0; i < row; i++)
                assert_float_equal(gl->pos[ci * row + i], g->pos[ci * row + i], 1e-5);
            checked++;
        }
        if (runs > 0) /* a frame strictly between the two centres, against the two means */
            for (uint32_t t = (uint32_t)prev_c + 1; (double)t < c; t++) {
                double u = ((double)t - prev_c) / (c - prev_c);
                for (size_t i = 0; i < row; i++) {
                    double want = g->pos[prev_s * row + i] +
                                  u * (g->pos[s * row + i] - g->pos[prev_s * row + i]);
                    assert_float_equal(gl->pos[t * row + i], want, 1e-4);
                }
            }
        prev_c = c;
        prev_s = s;
        runs++;
        s = e;
    }
    assert_true(runs >= 3 && checked >= 1);
    affect_free(rl.path);
    affect_motion_free(gl);
    /* unfiltered: every frame is a state mean, de-normalized; equal states give equal frames */
    for (uint32_t t = 1; t < rep.n_frames; t++)
        if (rep.path[t] == rep.path[t - 1])
            assert_memory_equal(affect_motion_at(g, t, 0), affect_motion_at(g, t - 1, 0),
                                (size_t)d->n_joints * 3 * sizeof(float));
    affect_free(rep.path);
    affect_motion_free(g);
    affect_motion_free(nb);
    affect_motion_free(d);
}

/* m with a fixed origin joint "joint_Root" put before its joints (the corpus's layout: its
 * first joint stays at 0 and the hips carry the travel). */
static affect_motion *with_origin(const affect_motion *m)
{
    affect_motion *o = NULL;
    affect_error err;
    assert_int_equal(affect_motion_create(m->n_frames, m->n_joints + 1, m->fps, &o, &err),
                     AFFECT_OK);
    memcpy(o->unit, m->unit, sizeof o->unit);
    assert_int_equal(affect_motion_set_name(o, 0, "joint_Root", 10, &err), AFFECT_OK);
    for (uint32_t j = 0; j < m->n_joints; j++) {
        assert_int_equal(affect_motion_set_name(o, j + 1, m->names[j], strlen(m->names[j]), &err),
                         AFFECT_OK);
        o->parents[j + 1] = m->parents[j] + 1; /* the old root hangs from joint_Root */
    }
    for (uint32_t t = 0; t < m->n_frames; t++)
        memcpy(affect_motion_at(o, t, 1), affect_motion_at(m, t, 0),
               (size_t)m->n_joints * 3 * sizeof(float));
    affect_motion_free((affect_motion *)m);
    return o;
}

/* keep_path: a walk generated from standing neighbours (knocks) keeps its own horizontal root
 * path exactly, and its posture comes from the model; without it the standing neighbours pull
 * the walk back toward the start. */
static void test_keep_path(void **state)
{
    (void)state;
    affect_motion *d = synth("walk", "neutral", 2, 30);
    affect_motion *nb[2] = {synth("knock", "sad", 3, 30), synth("knock", "sad", 4, 30)};
    affect_generate_options opt;
    affect_generate_options_default(&opt);
    assert_true(opt.keep_path);
    opt.rigid = false; /* the path exactly (the rigid projection moves the root a little) */
    affect_motion *g = generate(d, nb, 2, &opt, NULL);
    double worst = 0, travel = 0;
    for (uint32_t t = 0; t < d->n_frames; t++) {
        const float *a = affect_motion_at(d, t, 0), *b = affect_motion_at(g, t, 0);
        worst = fmax(worst, fmax(fabs(a[0] - b[0]), fabs(a[2] - b[2])));
        const float *a0 = affect_motion_at(d, 0, 0);
        travel = fmax(travel, hypot(a[0] - a0[0], a[2] - a0[2]));
    }
    assert_true(travel > 1.0); /* the walk travels more than a metre */
    assert_true(worst < 1e-4); /* and the output's root follows it (float32 rounding) */
    /* the posture is not the walk's: the hands are the knocks' (no copies of the walk) */
    double dk = dtw(g, d);
    assert_true(dk > 0.05);
    opt.keep_path = false;
    affect_motion *g0 = generate(d, nb, 2, &opt, NULL);
    const float *end_d = affect_motion_at(d, d->n_frames - 1, 0),
                *end_g = affect_motion_at(g0, d->n_frames - 1, 0);
    assert_true(hypot(end_d[0] - end_g[0], end_d[2] - end_g[2]) > 0.5); /* left the path */
    assert_true(dtw(g0, d) > dk);
    affect_motion_free(g0);
    affect_motion_free(g);

    /* with a fixed origin as joint 0, the path kept is the pelvis role's (the hips') */
    d = with_origin(d);
    nb[0] = with_origin(nb[0]);
    nb[1] = with_origin(nb[1]);
    opt.keep_path = true;
    g = generate(d, nb, 2, &opt, NULL);
    worst = 0;
    for (uint32_t t = 0; t < d->n_frames; t++) {
        const float *a = affect_motion_at(d, t, 1), *b = affect_motion_at(g, t, 1);
        worst = fmax(worst, fmax(fabs(a[0] - b[0]), fabs(a[2] - b[2])));
    }
    assert_true(worst < 1e-4);
    affect_motion_free(g);
    free_all(nb, 2);
    affect_motion_free(d);
}

static void test_determinism(void **state)
{
    (void)state;
    affect_motion *d = synth("bow", "neutral", 5, 30);
    affect_motion *nb[3] = {synth("bow", "angry", 6, 30), synth("bow", "angry", 7, 30),
                            synth("bow", "angry", 8, 30)};
    affect_generate_options opt;
    affect_generate_options_default(&opt);
    opt.copies = 1;
    opt.seed = 42;
    unsigned char *b[2];
    size_t n[2];
    for (int k = 0; k < 2; k++) {
        affect_motion *g = generate(d, nb, 3, &opt, NULL);
        affect_error err;
        assert_int_equal(affect_motion_encode(g, &b[k], &n[k], &err), AFFECT_OK);
        affect_motion_free(g);
    }
    assert_int_equal(n[0], n[1]);
    assert_memory_equal(b[0], b[1], n[0]);
    affect_free(b[0]);
    affect_free(b[1]);
    free_all(nb, 3);
    affect_motion_free(d);
}

/* A desired motion with joint rotations (imported from BVH, here from IK): the output has new
 * positions, so it must not carry the desired motion's rotations (they would describe the
 * source, and motion_to_bvh would refuse them); by default it gets rotations of its own (a
 * rigid skeleton whose forward kinematics are its positions, bones of the desired motion's
 * lengths). */
static void test_output_drops_source_rotations(void **state)
{
    (void)state;
    affect_motion *pos = synth("bow", "neutral", 5, 30), *d = NULL;
    assert_int_equal(affect_motion_ik(pos, NULL, &d, NULL), AFFECT_OK);
    assert_non_null(d->rot);
    affect_motion *nb[2] = {synth("bow", "angry", 6, 30), synth("bow", "angry", 7, 30)};
    affect_generate_options opt;
    affect_generate_options_default(&opt);
    opt.rigid = false;
    affect_motion *g = generate(d, nb, 2, &opt, NULL);
    assert_null(g->skel);
    assert_null(g->rot);
    affect_motion_free(g);
    opt.rigid = true;
    g = generate(d, nb, 2, &opt, NULL);
    assert_non_null(g->rot);
    double fk, variation;
    uint32_t frame, joint;
    int32_t worst;
    assert_int_equal(affect_motion_fk_error(g, &fk, &frame, &joint, NULL), AFFECT_OK);
    assert_true(fk < 1e-5);
    assert_int_equal(affect_motion_bone_variation(g, &variation, &worst, NULL), AFFECT_OK);
    assert_true(variation <= 1e-4);
    assert_int_equal(g->n_frames, d->n_frames);
    affect_motion_free(g);
    free_all(nb, 2);
    affect_motion_free(d);
    affect_motion_free(pos);
}

/* p' = R (p − o) / s computed here in double, then inverted: the original within 1e-9; and
 * the transform is exactly the one the observations use. */
static void test_denormalize_round_trip(void **state)
{
    (void)state;
    affect_motion *m = synth("walk", "happy", 9, 30);
    /* turn and move it so that every part of the transform matters */
    for (size_t i = 0; i < (size_t)m->n_frames * m->n_joints; i++) {
        float *p = m->pos + i * 3;
        float x = p[0], z = p[2];
        p[0] = (float)(0.6 * x + 0.8 * z + 3.0);
        p[2] = (float)(-0.8 * x + 0.6 * z - 2.0);
    }
    affect_normalize_transform tf;
    affect_error err;
    assert_int_equal(affect_generate_transform(m, 1, &tf, &err), AFFECT_OK);
    assert_true(tf.scale > 0.3 && tf.scale < 1.0); /* the arm, in metres */

    affect_features_options fo;
    affect_features_options_default(&fo);
    affect_features *f = NULL;
    assert_int_equal(affect_features_create(&fo, m, &f, &err), AFFECT_OK);
    double *x = NULL;
    uint32_t T = 0;
    assert_int_equal(affect_features_extract(f, m, &x, &T, NULL, &err), AFFECT_OK);

    size_t n = (size_t)T * m->n_joints;
    double *y = test_malloc(n * 3 * sizeof *y);
    for (size_t i = 0; i < n; i++) {
        const float *p = m->pos + i * 3;
        double a = p[0] - tf.origin[0], b = p[1] - tf.origin[1], c = p[2] - tf.origin[2];
        for (int r = 0; r < 3; r++) {
            double v =
                (tf.rot[r * 3] * a + tf.rot[r * 3 + 1] * b + tf.rot[r * 3 + 2] * c) / tf.scale;
            tu_assert_near(v, x[i * 3 + r], 1e-12); /* the features' transform */
            y[i * 3 + r] = v;
        }
    }
    affect_normalize_invert(&tf, y, n, y);
    for (size_t i = 0; i < n * 3; i++)
        tu_assert_near(y[i], m->pos[i], 1e-9);

    /* and it inverts affect_normalize_apply (float storage: within float rounding) */
    affect_motion *c = NULL;
    assert_int_equal(affect_motion_clone(m, &c, &err), AFFECT_OK);
    affect_normalize_apply(c, &tf);
    for (size_t i = 0; i < n; i++) {
        double p[3] = {c->pos[i * 3], c->pos[i * 3 + 1], c->pos[i * 3 + 2]};
        affect_normalize_invert(&tf, p, 1, p);
        for (int r = 0; r < 3; r++)
            tu_assert_near(p[r], m->pos[i * 3 + r], 1e-5);
    }
    affect_motion_free(c);
    test_free(y);
    affect_free(x);
    affect_features_free(f);
    affect_motion_free(m);
}

static void test_excluded_skeletons(void **state)
{
    (void)state;
    affect_motion *d = synth("knock", "neutral", 1, 30);
    affect_motion *nb[3] = {synth("knock", "sad", 2, 30), synth("knock", "sad", 3, 30),
                            synth("knock", "sad", 4, 30)};
    affect_error err;
    assert_int_equal(affect_motion_set_name(nb[0], 5, "Crown", 5, &err), AFFECT_OK);
    affect_generate_options opt;
    affect_generate_options_default(&opt);
    opt.max_iter = 3;
    affect_generate_report rep;
    affect_motion *g = generate(d, nb, 3, &opt, &rep);
    assert_int_equal(rep.neighbours_used, 2);
    assert_int_equal(rep.excluded, 1);
    affect_free(rep.path);
    affect_motion_free(g);

    /* the same joints in another order are the same skeleton */
    affect_motion *names[2] = {NULL, NULL};
    const char *order[26];
    for (uint32_t j = 0; j < 26; j++)
        order[j] = d->names[25 - j];
    assert_int_equal(affect_motion_select(nb[1], order, 26, &names[0], &err), AFFECT_OK);
    names[1] = nb[2];
    g = generate(d, names, 2, &opt, &rep);
    assert_int_equal(rep.neighbours_used, 2);
    assert_int_equal(rep.excluded, 0);
    affect_free(rep.path);
    affect_motion_free(g);
    affect_motion_free(names[0]);

    /* none left */
    affect_motion *out = (affect_motion *)1;
    assert_int_equal(
        affect_generate(d, (const affect_motion *const *)nb, 1, &opt, &out, &rep, &err),
        AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "no neighbour has the desired motion's skeleton (joint names)");
    assert_null(out);
    assert_null(rep.path);
    free_all(nb, 3);
    affect_motion_free(d);
}

static void test_dtw(void **state)
{
    (void)state;
    affect_motion *a = synth("knock", "neutral", 1, 30);
    affect_motion *b = synth("knock", "neutral", 2, 30);
    affect_motion *w = synth("wave", "neutral", 1, 30);
    affect_motion *r = NULL;
    affect_error err;
    assert_int_equal(affect_motion_resample(a, 21, &r, &err), AFFECT_OK);
    assert_true(r->n_frames < a->n_frames * 3 / 4);
    assert_true(dtw(a, a) == 0);
    double ab = dtw(a, b), ba = dtw(b, a);
    assert_true(ab > 0);
    assert_true(ab == ba);
    assert_true(dtw(a, r) == dtw(r, a));
    assert_true(dtw(a, r) * 5 < dtw(a, w));
    /* a constant offset of every joint in every frame is removed by the normalization */
    affect_motion *s = NULL;
    assert_int_equal(affect_motion_clone(a, &s, &err), AFFECT_OK);
    for (size_t i = 0; i < (size_t)s->n_frames * s->n_joints; i++)
        s->pos[i * 3] += 5.0f;
    assert_true(dtw(a, s) < 1e-5);
    affect_motion_free(s);
    affect_motion_free(r);
    affect_motion_free(w);
    affect_motion_free(b);
    affect_motion_free(a);
}

/* ---- errors ---- */

static void expect_gen_error(const affect_motion *d, affect_motion **nb, uint32_t n,
                             const affect_generate_options *opt, affect_status want,
                             const char *msg)
{
    affect_motion *out = NULL;
    affect_error err = {0};
    affect_generate_report rep;
    affect_status st =
        affect_generate(d, (const affect_motion *const *)nb, n, opt, &out, &rep, &err);
    assert_int_equal(st, want);
    assert_string_equal(err.msg, msg);
    assert_null(out);
    assert_null(rep.path);
}

static void test_errors(void **state)
{
    (void)state;
    affect_motion *d = synth("knock", "neutral", 1, 30);
    affect_motion *nb[2] = {synth("knock", "sad", 2, 30), NULL};
    affect_generate_options opt;
    affect_generate_options_default(&opt);
    expect_gen_error(NULL, nb, 1, &opt, AFFECT_ERR_INVALID, "no desired motion");
    expect_gen_error(d, nb, 0, &opt, AFFECT_ERR_INVALID, "no neighbours");
    expect_gen_error(d, NULL, 1, &opt, AFFECT_ERR_INVALID, "no neighbours");
    expect_gen_error(d, nb, 2, &opt, AFFECT_ERR_INVALID, "neighbour 1 is missing");
    opt.states = 0;
    expect_gen_error(d, nb, 1, &opt, AFFECT_ERR_INVALID, "states must be between 1 and 256");
    opt.states = 257;
    expect_gen_error(d, nb, 1, &opt, AFFECT_ERR_INVALID, "states must be between 1 and 256");
    affect_generate_options_default(&opt);
    opt.copies = 5000;
    expect_gen_error(d, nb, 1, &opt, AFFECT_ERR_INVALID, "copies must be at most 1000, got 5000");
    affect_generate_options_default(&opt);
    opt.cutoff_hz = -1;
    expect_gen_error(d, nb, 1, &opt, AFFECT_ERR_INVALID,
                     "cut-off must be a finite frequency of 0 Hz or more, got -1");
    opt.cutoff_hz = NAN;
    expect_gen_error(d, nb, 1, &opt, AFFECT_ERR_INVALID,
                     "cut-off must be a finite frequency of 0 Hz or more, got nan");
    affect_generate_options_default(&opt);
    opt.covariance_scale = 0;
    expect_gen_error(d, nb, 1, &opt, AFFECT_ERR_INVALID,
                     "covariance scale must be finite and greater than 0, got 0");
    opt.covariance_scale = INFINITY;
    expect_gen_error(d, nb, 1, &opt, AFFECT_ERR_INVALID,
                     "covariance scale must be finite and greater than 0, got inf");
    affect_generate_options_default(&opt);
    opt.up_axis = 3;
    expect_gen_error(d, nb, 1, &opt, AFFECT_ERR_INVALID, "up axis must be x, y or z");
    affect_generate_options_default(&opt);
    opt.max_iter = 200000;
    expect_gen_error(d, nb, 1, &opt, AFFECT_ERR_INVALID, "max_iter must be at most 100000");

    /* frame rate, lengths */
    affect_generate_options_default(&opt);
    affect_motion *fast = synth("knock", "sad", 3, 60);
    nb[1] = fast;
    expect_gen_error(d, nb, 2, &opt, AFFECT_ERR_INVALID,
                     "neighbour 1 is at 60 fps, the desired motion at 30 (resample it first)");
    affect_error err;
    affect_motion *short_nb = NULL, *short_d = NULL;
    assert_int_equal(affect_motion_slice(nb[0], 0, 7, &short_nb, &err), AFFECT_OK);
    assert_int_equal(affect_motion_slice(d, 0, 7, &short_d, &err), AFFECT_OK);
    nb[1] = short_nb;
    expect_gen_error(d, nb, 2, &opt, AFFECT_ERR_INVALID,
                     "neighbour 1 has 8 frames, fewer than the 12 states");
    opt.copies = 1;
    expect_gen_error(short_d, nb, 1, &opt, AFFECT_ERR_INVALID,
                     "the desired motion has 8 frames, fewer than the 12 states (it is trained "
                     "on with copies > 0)");
    /* copies = 0: a desired motion shorter than the states is fine */
    opt.copies = 0;
    opt.max_iter = 2;
    affect_motion *g = generate(short_d, nb, 1, &opt, NULL);
    assert_int_equal(g->n_frames, 8);
    affect_motion_free(g);

    /* normalization errors name the motion */
    affect_motion *nohips = NULL, *nohips2 = NULL;
    const char *keep[] = {"Hips", "Spine", "Chest", "Neck", "Head"};
    assert_int_equal(affect_motion_select(d, keep, 5, &nohips, &err), AFFECT_OK);
    assert_int_equal(affect_motion_select(nb[0], keep, 5, &nohips2, &err), AFFECT_OK);
    nb[1] = nohips2;
    expect_gen_error(nohips, nb + 1, 1, &opt, AFFECT_ERR_MISSING,
                     "desired motion: cannot remove the heading: no left/right hip or shoulder "
                     "roles resolve in the motion (train with {\"normalize\": false})");

    /* DTW */
    double dist;
    assert_int_equal(affect_dtw_distance(d, nohips, &dist, NULL, &err), AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "the motions have different joint names");
    assert_int_equal(affect_dtw_distance(nohips, nohips2, &dist, NULL, &err), AFFECT_ERR_MISSING);
    assert_string_equal(err.msg, "first motion: cannot remove the heading: no left/right hip or "
                                 "shoulder roles resolve in the motion (train with "
                                 "{\"normalize\": false})");
    assert_int_equal(affect_dtw_distance(NULL, d, &dist, NULL, &err), AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "missing motion");

    affect_motion_free(nohips);
    affect_motion_free(nohips2);
    affect_motion_free(short_nb);
    affect_motion_free(short_d);
    affect_motion_free(fast);
    affect_motion_free(nb[0]);
    affect_motion_free(d);
}

/* ---- out of memory ---- */

typedef struct oom_ctx {
    const affect_motion *d;
    affect_motion *nb[2];
    affect_generate_options opt;
    affect_motion *out;
    affect_generate_report rep;
    double dist;
} oom_ctx;

static affect_status oom_op(void *p, affect_error *err)
{
    oom_ctx *c = p;
    affect_status st = affect_generate(c->d, (const affect_motion *const *)c->nb, 2, &c->opt,
                                       &c->out, &c->rep, err);
    if (st)
        return st;
    return affect_dtw_distance(c->out, c->d, &c->dist, NULL, err);
}

static void oom_finish(void *p, affect_status st)
{
    oom_ctx *c = p;
    (void)st;
    affect_motion_free(c->out);
    affect_free(c->rep.path);
    c->out = NULL;
    c->rep.path = NULL;
}

static void test_oom(void **state)
{
    (void)state;
    affect_motion *full = synth("knock", "neutral", 1, 10);
    affect_motion *d = NULL;
    affect_error err;
    const char *keep[] = {"Hips",       "Spine",      "Chest",      "Head",  "UpperLeg_L",
                          "UpperLeg_R", "UpperArm_R", "LowerArm_R", "Hand_R"};
    assert_int_equal(affect_motion_select(full, keep, 9, &d, &err), AFFECT_OK);
    oom_ctx c;
    memset(&c, 0, sizeof c);
    c.d = d;
    for (int k = 0; k < 2; k++) {
        affect_motion *m = synth("knock", "angry", 2 + (uint64_t)k, 10);
        assert_int_equal(affect_motion_select(m, keep, 9, &c.nb[k], &err), AFFECT_OK);
        affect_motion_free(m);
    }
    affect_generate_options_default(&c.opt);
    c.opt.states = 3;
    c.opt.copies = 1;
    c.opt.max_iter = 2;
    c.opt.cutoff_hz = 3;
    c.opt.covariance_scale = 2;
    long absorbed = 0; /* affect_roles_resolve falls back when its scratch allocation fails */
    long n = tu_oom_sweep(oom_op, &c, oom_finish, &absorbed);
    assert_true(n > 10);
    assert_true(absorbed < n / 4);
    free_all(c.nb, 2);
    affect_motion_free(d);
    affect_motion_free(full);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_emotion_transfer),
        cmocka_unit_test(test_copies_and_scale),
        cmocka_unit_test(test_single_neighbour_and_no_filter),
        cmocka_unit_test(test_keep_path),
        cmocka_unit_test(test_determinism),
        cmocka_unit_test(test_output_drops_source_rotations),
        cmocka_unit_test(test_denormalize_round_trip),
        cmocka_unit_test(test_excluded_skeletons),
        cmocka_unit_test(test_dtw),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_oom),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
