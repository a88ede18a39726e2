/*
 * test_laban_series.c — the windowed Effort series (core/laban/laban_series.c): a window covering
 * the whole motion gives the per-clip laban values (peaks to the bit, sums within
 * AFFECT_LABAN_SERIES_RTOL) with both methods of Weight and Time; every window of a sliding
 * series against a brute-force reduction of the same kinematics over its frames (several
 * windows and hops, overlapping or not); a body that starts moving halfway shows its Weight
 * rising in the second half; a part still after moving is exactly direct and free of jerk
 * (Space 1, Flow 0); window layouts at the edges; bad options; and the monitor stops it.
 */
#include <math.h>
#include <string.h>

#include "testutil.h"
#include "affect/laban.h"
#include "affect/synth.h"

static const char *const part_names[6] = {"torso",      "head",      "left_hand",
                                          "right_hand", "left_foot", "right_foot"};

static affect_motion *synth(const char *action, const char *emotion)
{
    affect_motion *m = NULL;
    affect_error err;
    if (affect_motion_synth(action, emotion, 1, NULL, &m, &err))
        fail_msg("%s", err.msg);
    return m;
}

static void six_parts(const affect_motion *m, affect_part parts[6])
{
    affect_roles roles;
    affect_error err;
    affect_roles_resolve(m, &roles);
    if (affect_parts_all(m, &roles, parts, &err))
        fail_msg("%s", err.msg);
}

static bool near_rel(double a, double b, double rtol)
{
    return fabs(a - b) <= rtol * fmax(fabs(a), fabs(b)) || a == b;
}

/* The series of m's six parts (combined + each) with one window of the whole motion, against
 * affect_laban_weight / time / space / flow of "all" and of every part. */
static void check_whole(const affect_motion *m, affect_laban_method wm, affect_laban_method tm,
                        bool per_second)
{
    affect_part parts[6];
    six_parts(m, parts);
    affect_laban_options opt;
    affect_laban_options_default(&opt);
    opt.time_per_second = per_second;
    affect_laban_series_options so;
    affect_laban_series_options_default(&so);
    so.window = m->n_frames + (wm == AFFECT_LABAN_Q2 ? 0 : 5); /* equal to, and longer than */
    so.weight = wm;
    so.time = tm;
    so.combined = true;
    affect_laban_series *s = NULL;
    affect_error err;
    if (affect_laban_series_new(m, parts, 6, &opt, &so, &s, &err))
        fail_msg("%s", err.msg);
    assert_int_equal(affect_laban_series_windows(s), 1);
    assert_int_equal(affect_laban_series_rows(s), 7);
    double v[7 * AFFECT_SERIES_N];
    uint32_t first, last;
    assert_int_equal(affect_laban_series_next(s, &first, &last, v, &err), AFFECT_OK);
    assert_int_equal(first, 0);
    assert_int_equal(last, m->n_frames - 1);
    assert_int_equal(affect_laban_series_next(s, &first, &last, v, &err), AFFECT_ERR_RANGE);
    for (uint32_t r = 0; r < 7; r++) {
        const affect_part *p = r == 0 ? parts : &parts[r - 1];
        uint32_t n = r == 0 ? 6 : 1;
        double w, t, sp, f;
        assert_int_equal(affect_laban_weight(m, p, n, wm, &opt, &w, &err), AFFECT_OK);
        assert_int_equal(affect_laban_time(m, p, n, tm, &opt, &t, &err), AFFECT_OK);
        assert_int_equal(affect_laban_space(m, p, n, AFFECT_LABAN_Q2, &opt, &sp, &err), AFFECT_OK);
        assert_int_equal(affect_laban_flow(m, p, n, &opt, &f, &err), AFFECT_OK);
        const double *row = v + r * AFFECT_SERIES_N;
        const char *name = r == 0 ? "all" : part_names[r - 1];
        if (!(row[AFFECT_SERIES_WEIGHT] == w)) /* a peak: the same bits */
            fail_msg("%s Weight %.17g, per clip %.17g", name, row[AFFECT_SERIES_WEIGHT], w);
        if (tm == AFFECT_LABAN_Q1 ? !(row[AFFECT_SERIES_TIME] == t)
                                  : !near_rel(row[AFFECT_SERIES_TIME], t, AFFECT_LABAN_SERIES_RTOL))
            fail_msg("%s Time %.17g, per clip %.17g", name, row[AFFECT_SERIES_TIME], t);
        if (!near_rel(row[AFFECT_SERIES_SPACE], sp, AFFECT_LABAN_SERIES_RTOL))
            fail_msg("%s Space %.17g, per clip %.17g", name, row[AFFECT_SERIES_SPACE], sp);
        if (!near_rel(row[AFFECT_SERIES_FLOW], f, AFFECT_LABAN_SERIES_RTOL))
            fail_msg("%s Flow %.17g, per clip %.17g", name, row[AFFECT_SERIES_FLOW], f);
    }
    affect_laban_series_free(s);
}

static void test_whole_window_is_the_clip(void **state)
{
    static const char *const actions[] = {"knock", "walk"};
    static const char *const emotions[] = {"angry", "sad"};
    for (int a = 0; a < 2; a++)
        for (int e = 0; e < 2; e++) {
            affect_motion *m = synth(actions[a], emotions[e]);
            check_whole(m, AFFECT_LABAN_Q1, AFFECT_LABAN_Q1, false);
            check_whole(m, AFFECT_LABAN_Q2, AFFECT_LABAN_Q2, false);
            check_whole(m, AFFECT_LABAN_Q1, AFFECT_LABAN_Q2, true);
            affect_motion_free(m);
        }
}

/* Brute force: the reductions of a window [f, l] computed directly from each part's
 * kinematics (affect_kinematics_compute, the bits the series reads). */
static void brute_window(const affect_motion *m, const affect_part *parts,
                         const affect_kinematics *ks, uint32_t lo, uint32_t hi, uint32_t f,
                         uint32_t l, const affect_laban_series_options *so, double max_ratio,
                         double out[AFFECT_SERIES_N])
{
    double fps = m->fps, w = 0, t = 0, flow = 0, space = 0;
    for (uint32_t i = f; i <= l; i++) {
        double ke = 0, an = 0, dec = 0, dv = 0;
        for (uint32_t k = lo; k < hi; k++) {
            const double *v = ks[k].vel + (size_t)i * 3, *a = ks[k].acc + (size_t)i * 3;
            ke += v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
            an += sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
            if (i > f) {
                const double *v0 = v - 3, *a0 = a - 3;
                double d = (sqrt(v0[0] * v0[0] + v0[1] * v0[1] + v0[2] * v0[2]) -
                            sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])) *
                           fps;
                if (d > 0)
                    dec += d;
                dv += sqrt((v[0] - v0[0]) * (v[0] - v0[0]) + (v[1] - v0[1]) * (v[1] - v0[1]) +
                           (v[2] - v0[2]) * (v[2] - v0[2])) *
                      fps;
                flow += sqrt((a[0] - a0[0]) * (a[0] - a0[0]) + (a[1] - a0[1]) * (a[1] - a0[1]) +
                             (a[2] - a0[2]) * (a[2] - a0[2])) *
                        fps;
            }
        }
        if (so->weight == AFFECT_LABAN_Q1 ? ke > w : (i > f && dec > w))
            w = so->weight == AFFECT_LABAN_Q1 ? ke : dec;
        if (so->time == AFFECT_LABAN_Q1 && an > t)
            t = an;
        if (so->time == AFFECT_LABAN_Q2)
            t += dv;
    }
    for (uint32_t k = lo; k < hi; k++) {
        double path = 0;
        for (uint32_t i = f + 1; i <= l; i++) {
            const double *p1 = ks[k].pos + (size_t)i * 3, *p0 = p1 - 3;
            path += sqrt((p1[0] - p0[0]) * (p1[0] - p0[0]) + (p1[1] - p0[1]) * (p1[1] - p0[1]) +
                         (p1[2] - p0[2]) * (p1[2] - p0[2]));
        }
        const double *a = ks[k].pos + (size_t)f * 3, *b = ks[k].pos + (size_t)l * 3;
        double disp = sqrt((b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]) +
                           (b[2] - a[2]) * (b[2] - a[2]));
        space += path > 0 ? path / fmax(disp, path / max_ratio) : 1.0;
    }
    (void)parts;
    out[AFFECT_SERIES_WEIGHT] = w;
    out[AFFECT_SERIES_TIME] = t;
    out[AFFECT_SERIES_SPACE] = space / (hi - lo);
    out[AFFECT_SERIES_FLOW] = flow;
}

static void check_sliding(const affect_motion *m, uint32_t window, uint32_t hop,
                          affect_laban_method wm, affect_laban_method tm)
{
    affect_part parts[6];
    six_parts(m, parts);
    affect_laban_options opt;
    affect_laban_options_default(&opt);
    affect_kinematics ks[6];
    affect_error err;
    for (int k = 0; k < 6; k++)
        assert_int_equal(affect_kinematics_compute(m, &parts[k], &opt, &ks[k], &err), AFFECT_OK);
    affect_laban_series_options so;
    affect_laban_series_options_default(&so);
    so.window = window;
    so.hop = hop;
    so.weight = wm;
    so.time = tm;
    so.combined = true;
    affect_laban_series *s = NULL;
    if (affect_laban_series_new(m, parts, 6, &opt, &so, &s, &err))
        fail_msg("%s", err.msg);
    uint32_t T = m->n_frames, expect = window < T ? (T - window) / hop + 1 : 1;
    assert_int_equal(affect_laban_series_windows(s), expect);
    double v[7 * AFFECT_SERIES_N], ref[AFFECT_SERIES_N];
    uint32_t first, last, i = 0;
    affect_status st;
    while ((st = affect_laban_series_next(s, &first, &last, v, &err)) == AFFECT_OK) {
        assert_int_equal(first, i * hop);
        assert_int_equal(last, first + (window < T ? window : T) - 1);
        for (uint32_t r = 0; r < 7; r++) {
            uint32_t lo = r == 0 ? 0 : r - 1, hi = r == 0 ? 6 : r;
            brute_window(m, parts, ks, lo, hi, first, last, &so, opt.max_ratio, ref);
            for (int q = 0; q < AFFECT_SERIES_N; q++) {
                bool peak =
                    q == AFFECT_SERIES_WEIGHT || (q == AFFECT_SERIES_TIME && tm == AFFECT_LABAN_Q1);
                double got = v[r * AFFECT_SERIES_N + (uint32_t)q];
                /* brute force sums in another order: a few ulps per term */
                if (peak ? !(got == ref[q]) : !near_rel(got, ref[q], 1e-11))
                    fail_msg("window %u (frames %u-%u, W %u hop %u) row %u quantity %d: %.17g, "
                             "brute force %.17g",
                             i, first, last, window, hop, r, q, got, ref[q]);
            }
        }
        i++;
    }
    assert_int_equal(st, AFFECT_ERR_RANGE);
    assert_int_equal(i, expect);
    affect_laban_series_free(s);
    for (int k = 0; k < 6; k++)
        affect_kinematics_free(&ks[k]);
}

static void test_sliding_matches_brute_force(void **state)
{
    affect_motion *m = synth("wave", "happy");
    static const uint32_t cases[][2] = {{2, 1},   {17, 1},  {17, 3}, {30, 29},
                                        {30, 30}, {12, 40}, {64, 7}};
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        check_sliding(m, cases[c][0], cases[c][1], AFFECT_LABAN_Q1, AFFECT_LABAN_Q1);
        check_sliding(m, cases[c][0], cases[c][1], AFFECT_LABAN_Q2, AFFECT_LABAN_Q2);
    }
    affect_motion_free(m);
}

/* A body still for the first half that then shakes its right hand: Weight is 0 in the windows of
 * the first half and large in those of the second; once the hand stops again (last quarter)
 * its windows are exactly direct (the positions do not move: Space exactly 1, not a running
 * sum's residue) and free of jerk (Flow below 1e-6: the filter's ringing has died out). */
static void test_weight_rises_in_second_half(void **state)
{
    static const char *const names[] = {"Hips",   "Spine",  "Chest",  "Head",
                                        "Hand_L", "Hand_R", "Foot_L", "Foot_R"};
    const uint32_t T = 400, J = 8;
    const double fps = 50;
    affect_motion *m = NULL;
    affect_error err;
    assert_int_equal(affect_motion_create(T, J, fps, &m, &err), AFFECT_OK);
    for (uint32_t j = 0; j < J; j++)
        assert_int_equal(affect_motion_set_name(m, j, names[j], strlen(names[j]), &err), AFFECT_OK);
    for (uint32_t t = 0; t < T; t++)
        for (uint32_t j = 0; j < J; j++) {
            float *p = affect_motion_at(m, t, j);
            p[0] = (float)(0.1 * j);
            p[1] = (float)(0.2 * j);
            p[2] = 0;
            if (j == 5 && t >= 200 && t < 300) /* the right hand shakes, 3 Hz, 20 cm */
                p[0] += (float)(0.2 * sin(2 * 3.14159265358979 * 3 * (t - 200) / fps));
        }
    affect_roles roles;
    affect_roles_resolve(m, &roles);
    affect_part hand;
    assert_int_equal(affect_part_resolve(m, &roles, "right_hand", &hand, &err), AFFECT_OK);
    affect_laban_series_options so;
    affect_laban_series_options_default(&so);
    so.window = affect_laban_series_frames(0.5, fps);
    so.hop = affect_laban_series_frames(0.1, fps);
    assert_int_equal(so.window, 25);
    assert_int_equal(so.hop, 5);
    affect_laban_series *s = NULL;
    if (affect_laban_series_new(m, &hand, 1, NULL, &so, &s, &err))
        fail_msg("%s", err.msg);
    double v[AFFECT_SERIES_N], first_half = 0, second_half = 0;
    uint32_t first, last, n_still = 0;
    while (affect_laban_series_next(s, &first, &last, v, &err) == AFFECT_OK) {
        if (last < 180)
            first_half = fmax(first_half, v[AFFECT_SERIES_WEIGHT]);
        else if (first >= 210 && last < 290)
            second_half = fmin(second_half == 0 ? INFINITY : second_half, v[AFFECT_SERIES_WEIGHT]);
        if (first >= 370) { /* still again, 70 frames past the filter's ringing */
            n_still++;
            if (!(v[AFFECT_SERIES_SPACE] == 1.0 && v[AFFECT_SERIES_FLOW] < 1e-6))
                fail_msg("frames %u-%u: Space %.17g, Flow %.17g after the hand stopped", first,
                         last, v[AFFECT_SERIES_SPACE], v[AFFECT_SERIES_FLOW]);
        }
    }
    affect_laban_series_free(s);
    /* 3 Hz × 0.2 m: peak speed 2π·3·0.2 ≈ 3.77 m/s, kinetic energy ≈ 14 m²/s² (filtered: less) */
    if (!(first_half < 1e-9 && second_half > 5.0))
        fail_msg("Weight %g in the first half, at least %g in the second", first_half, second_half);
    assert_true(n_still > 0);
    affect_motion_free(m);
}

/* Windows at the edges: window 2, window = motion, window > motion, hop > window; seconds to
 * frames. */
static void test_layouts(void **state)
{
    affect_motion *m = synth("bow", "neutral");
    uint32_t T = m->n_frames;
    affect_part parts[6];
    six_parts(m, parts);
    static const uint32_t cases[][2] = {{2, 1}, {0, 1}, {0, 0}, {5, 11}, {3, 2}};
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        affect_laban_series_options so;
        affect_laban_series_options_default(&so);
        so.window = cases[c][0] ? cases[c][0] : T + (uint32_t)cases[c][1] * 100;
        so.hop = cases[c][0] ? cases[c][1] : 1;
        affect_laban_series *s = NULL;
        affect_error err;
        if (affect_laban_series_new(m, parts + 2, 1, NULL, &so, &s, &err))
            fail_msg("%s", err.msg);
        uint32_t expect = so.window < T ? (T - so.window) / so.hop + 1 : 1, n = 0, first, last;
        double v[AFFECT_SERIES_N];
        while (affect_laban_series_next(s, &first, &last, v, &err) == AFFECT_OK) {
            assert_true(last < T);
            assert_true(last - first + 1 == (so.window < T ? so.window : T));
            for (int q = 0; q < AFFECT_SERIES_N; q++)
                assert_true(isfinite(v[q]) && v[q] >= 0);
            assert_true(v[AFFECT_SERIES_SPACE] >= 1.0);
            n++;
        }
        assert_int_equal(n, expect);
        affect_laban_series_free(s);
    }
    assert_int_equal(affect_laban_series_frames(1.0, 30), 30);
    assert_int_equal(affect_laban_series_frames(0.05, 30), 2); /* 1.5 rounds up */
    assert_int_equal(affect_laban_series_frames(0.01, 30), 0);
    assert_int_equal(affect_laban_series_frames(NAN, 30), 0);
    assert_int_equal(affect_laban_series_frames(-1, 30), 0);
    assert_int_equal(affect_laban_series_frames(1e300, 30), UINT32_MAX);
    assert_int_equal(affect_laban_series_frames(INFINITY, 30), 0);
    affect_motion_free(m);
}

static void test_bad_options(void **state)
{
    affect_motion *m = synth("knock", "sad");
    affect_part parts[6];
    six_parts(m, parts);
    affect_laban_series_options so;
    affect_laban_series_options_default(&so);
    affect_laban_series *s = (affect_laban_series *)&so; /* must be reset to NULL */
    affect_error err;
    assert_int_equal(affect_laban_series_new(m, parts, 6, NULL, &so, &s, &err),
                     AFFECT_ERR_INVALID); /* window 0 */
    assert_null(s);
    assert_string_equal(err.msg, "the window must be at least 2 frames, got 0");
    so.window = 1;
    assert_int_equal(affect_laban_series_new(m, parts, 6, NULL, &so, &s, &err), AFFECT_ERR_INVALID);
    so.window = 10;
    so.hop = 0;
    assert_int_equal(affect_laban_series_new(m, parts, 6, NULL, &so, &s, &err), AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "the hop must be at least 1 frame, got 0");
    so.hop = 1;
    assert_int_equal(affect_laban_series_new(m, parts, 0, NULL, &so, &s, &err), AFFECT_ERR_INVALID);
    assert_int_equal(affect_laban_series_new(m, parts, 7, NULL, &so, &s, &err), AFFECT_ERR_INVALID);
    so.weight = (affect_laban_method)3;
    assert_int_equal(affect_laban_series_new(m, parts, 6, NULL, &so, &s, &err), AFFECT_ERR_INVALID);
    so.weight = AFFECT_LABAN_Q1;
    affect_laban_options opt;
    affect_laban_options_default(&opt);
    opt.cutoff_hz = -1;
    assert_int_equal(affect_laban_series_new(m, parts, 6, &opt, &so, &s, &err), AFFECT_ERR_INVALID);
    assert_null(s);
    affect_motion_free(m);

    affect_motion *shortm = NULL;
    assert_int_equal(affect_motion_create(3, 1, 30, &shortm, &err), AFFECT_OK);
    affect_part one = {1, {0, 0, 0, 0}, "j"};
    assert_int_equal(affect_laban_series_new(shortm, &one, 1, NULL, &so, &s, &err),
                     AFFECT_ERR_RANGE);
    assert_string_equal(err.msg, "the motion has 3 frames; the Laban series needs at least 4");
    affect_motion_free(shortm);
}

static bool stop_now(void *ctx)
{
    int *calls = ctx;
    return ++*calls > 0;
}

/* A long motion with a monitor that said stop: the kinematics stop; a series begun without the
 * monitor stops in a long window's computation once given it. */
static void test_monitor(void **state)
{
    affect_motion *m = NULL;
    affect_error err;
    const uint32_t T = 50000;
    assert_int_equal(affect_motion_create(T, 1, 100, &m, &err), AFFECT_OK);
    for (uint32_t t = 0; t < T; t++)
        affect_motion_at(m, t, 0)[0] = (float)sin(t * 0.01);
    affect_part one = {1, {0, 0, 0, 0}, "j"};
    affect_monitor mon;
    int calls = 0;
    affect_monitor_init(&mon, stop_now, NULL, &calls);
    affect_laban_options opt;
    affect_laban_options_default(&opt);
    opt.monitor = &mon;
    while (!affect_monitor_stopped(&mon)) { /* asked at most every AFFECT_MONITOR_POLL_MS */
    }
    affect_laban_series_options so;
    affect_laban_series_options_default(&so);
    so.window = T;
    affect_laban_series *s = NULL;
    assert_int_equal(affect_laban_series_new(m, &one, 1, &opt, &so, &s, &err),
                     AFFECT_ERR_INTERRUPTED);
    assert_null(s);
    /* started unmonitored, then asked to stop */
    opt.monitor = NULL;
    assert_int_equal(affect_laban_series_new(m, &one, 1, &opt, &so, &s, &err), AFFECT_OK);
    opt.monitor = &mon;
    double v[AFFECT_SERIES_N];
    uint32_t first, last;
    assert_int_equal(affect_laban_series_next(s, &first, &last, v, &err), AFFECT_ERR_INTERRUPTED);
    assert_string_equal(err.msg, "interrupted");
    affect_laban_series_free(s);
    affect_motion_free(m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_whole_window_is_the_clip),
        cmocka_unit_test(test_sliding_matches_brute_force),
        cmocka_unit_test(test_weight_rises_in_second_half),
        cmocka_unit_test(test_layouts),
        cmocka_unit_test(test_bad_options),
        cmocka_unit_test(test_monitor),
    };
    return cmocka_run_group_tests_name("laban_series", tests, NULL, NULL);
}
