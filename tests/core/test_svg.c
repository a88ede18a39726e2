/*
 * test_svg.c — SVG film strips: well-formed standalone documents (balanced tags, escaped
 * text, no nan/inf), one label per panel with the right frames and times, the axis mapping of
 * every view and up axis (checked on dot positions), one shared scale and a fixed vertical
 * placement, side colours and the hidden reference root, trajectories and their decimation,
 * degenerate motions, exact option and data errors, determinism, the size bound, and
 * out-of-memory at every allocation.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"
#include "affect/svg.h"

/* ---- helpers ---- */

/* Text of panel k (the nested <svg x=…> element), copied into a malloc'd string. */
static char *panel_text(const char *s, size_t k)
{
    const char *p = s;
    for (size_t i = 0; i <= k; i++) {
        p = strstr(p + 1, "<svg x=");
        assert_non_null(p);
    }
    const char *e = strstr(p, "</svg>");
    assert_non_null(e);
    char *out = malloc((size_t)(e - p) + 1);
    assert_non_null(out);
    memcpy(out, p, (size_t)(e - p));
    out[e - p] = '\0';
    return out;
}

/* Centre of the n-th <circle> of a text. */
static void circle_at(const char *s, size_t n, double *cx, double *cy)
{
    const char *p = s;
    for (size_t i = 0; i <= n; i++) {
        p = strstr(i ? p + 1 : p, "<circle cx=\"");
        assert_non_null(p);
    }
    char *end;
    *cx = strtod(p + 12, &end);
    assert_true(strncmp(end, "\" cy=\"", 6) == 0);
    *cy = strtod(end + 6, NULL);
}

/* Out of line: inlined into the tests, gcc 12 at -O3 takes the returned text for a pointer to
 * the local `svg` variable and reports a false -Wdangling-pointer. */
__attribute__((noinline)) static char *render(const affect_motion *m, const affect_roles *roles,
                                              const affect_svg_options *opt, size_t *len_out)
{
    char *svg = NULL;
    size_t len = 0;
    affect_error err;
    affect_status st = affect_motion_svg(m, roles, opt, &svg, &len, &err);
    if (st != AFFECT_OK)
        fail_msg("affect_motion_svg: %s", err.msg);
    tu_assert_svg_well_formed(svg, len);
    if (len_out)
        *len_out = len;
    return svg;
}

static affect_motion *make_motion(uint32_t frames, uint32_t joints, double fps)
{
    affect_motion *m = NULL;
    assert_int_equal(affect_motion_create(frames, joints, fps, &m, NULL), AFFECT_OK);
    return m;
}

static void set_pos(affect_motion *m, uint32_t t, uint32_t j, double x, double y, double z)
{
    float *p = affect_motion_at(m, t, j);
    p[0] = (float)x;
    p[1] = (float)y;
    p[2] = (float)z;
}

/* A 27-joint walker shaped like the corpus's skeleton (y up, cm, facing +z, left = +x): a
 * reference root at the origin, Hips … Head_end, clavicles, arms, legs and end sites. */
enum {
    H_ROOT,
    H_HIPS,
    H_SPINE,
    H_CHEST,
    H_NECK,
    H_HEAD,
    H_HEAD_END,
    H_SHOULDER_L,
    H_ARM_L,
    H_FOREARM_L,
    H_HAND_L,
    H_HAND_L_END,
    H_SHOULDER_R,
    H_ARM_R,
    H_FOREARM_R,
    H_HAND_R,
    H_HAND_R_END,
    H_LEG_L,
    H_KNEE_L,
    H_FOOT_L,
    H_TOE_L,
    H_TOE_L_END,
    H_LEG_R,
    H_KNEE_R,
    H_FOOT_R,
    H_TOE_R,
    H_TOE_R_END,
    H_COUNT
};

static const int32_t human_parents[H_COUNT] = {-1, 0,  1,  2, 3,  4,  5,  3,  7, 8,  9,  10, 3, 12,
                                               13, 14, 15, 1, 17, 18, 19, 20, 1, 22, 23, 24, 25};
static const double human_pose[H_COUNT][3] = {
    {0, 0, 0},    {0, 95, 0},    {0, 105, 0},   {0, 120, 0},  {0, 145, 0},  {0, 155, 0},
    {0, 170, 0},  {5, 140, 0},   {18, 140, 0},  {20, 112, 0}, {21, 88, 0},  {21, 80, 0},
    {-5, 140, 0}, {-18, 140, 0}, {-20, 112, 0}, {-21, 88, 0}, {-21, 80, 0}, {9, 92, 0},
    {9, 50, 0},   {9, 8, 0},     {9, 2, 12},    {9, 0, 18},   {-9, 92, 0},  {-9, 50, 0},
    {-9, 8, 0},   {-9, 2, 12},   {-9, 0, 18}};

static affect_motion *make_human(uint32_t frames)
{
    affect_motion *m = make_motion(frames, H_COUNT, 30);
    for (uint32_t j = 0; j < H_COUNT; j++)
        m->parents[j] = human_parents[j];
    for (uint32_t t = 0; t < frames; t++) {
        double ph = 2 * 3.14159265358979 * t / 30.0, walk = 100.0 * t / 30.0;
        for (uint32_t j = 1; j < H_COUNT; j++) {
            const double *b = human_pose[j];
            double side = b[0] > 0 ? 1 : b[0] < 0 ? -1 : 0;
            bool leg = j >= H_LEG_L, arm = j >= H_SHOULDER_L && j < H_LEG_L;
            double swing = leg ? (92 - b[1]) * 0.4 : arm ? (140 - b[1]) * 0.5 : 0;
            double z = b[2] + walk + (leg ? side : -side) * swing * sin(ph);
            set_pos(m, t, j, b[0], b[1] + 2 * fabs(sin(ph)), z);
        }
    }
    return m;
}

static void human_roles(affect_roles *r)
{
    static const int32_t joints[AFFECT_ROLE_COUNT] = {[AFFECT_ROLE_PELVIS] = H_HIPS,
                                                      [AFFECT_ROLE_SPINE] = H_SPINE,
                                                      [AFFECT_ROLE_CHEST] = H_CHEST,
                                                      [AFFECT_ROLE_NECK] = H_NECK,
                                                      [AFFECT_ROLE_HEAD] = H_HEAD,
                                                      [AFFECT_ROLE_LEFT_SHOULDER] = H_ARM_L,
                                                      [AFFECT_ROLE_LEFT_ELBOW] = H_FOREARM_L,
                                                      [AFFECT_ROLE_LEFT_HAND] = H_HAND_L,
                                                      [AFFECT_ROLE_RIGHT_SHOULDER] = H_ARM_R,
                                                      [AFFECT_ROLE_RIGHT_ELBOW] = H_FOREARM_R,
                                                      [AFFECT_ROLE_RIGHT_HAND] = H_HAND_R,
                                                      [AFFECT_ROLE_LEFT_HIP] = H_LEG_L,
                                                      [AFFECT_ROLE_LEFT_KNEE] = H_KNEE_L,
                                                      [AFFECT_ROLE_LEFT_FOOT] = H_FOOT_L,
                                                      [AFFECT_ROLE_LEFT_TOE] = H_TOE_L,
                                                      [AFFECT_ROLE_RIGHT_HIP] = H_LEG_R,
                                                      [AFFECT_ROLE_RIGHT_KNEE] = H_KNEE_R,
                                                      [AFFECT_ROLE_RIGHT_FOOT] = H_FOOT_R,
                                                      [AFFECT_ROLE_RIGHT_TOE] = H_TOE_R};
    memcpy(r->joint, joints, sizeof joints);
}

/* Number of bones ("M" commands) in the bone path of a colour inside a panel's text. */
static size_t bones_of(const char *panel, const char *colour)
{
    char key[64];
    snprintf(key, sizeof key, "<path stroke=\"%s\" d=\"", colour);
    const char *p = strstr(panel, key);
    if (!p)
        return 0;
    p += strlen(key);
    size_t n = 0;
    for (; *p && *p != '"'; p++)
        n += *p == 'M';
    return n;
}

#define BLUE "#1f6fd1"
#define RED "#e0452b"
#define GREY "#3a3f47"

/* ---- tests ---- */

static void test_defaults(void **state)
{
    affect_svg_options opt;
    memset(&opt, 0x55, sizeof opt);
    affect_svg_options_default(&opt);
    assert_int_equal(opt.view, AFFECT_SVG_FRONT);
    assert_int_equal(opt.frames, 8);
    assert_int_equal(opt.panel_size, 160);
    assert_int_equal(opt.up_axis, 1);
    assert_true(opt.trajectories);
    assert_true(opt.labels);
    assert_null(opt.title);
}

static void test_human_strip(void **state)
{
    affect_motion *m = make_human(60);
    affect_roles roles;
    human_roles(&roles);
    affect_svg_options opt;
    affect_svg_options_default(&opt);
    size_t len;
    char *svg = render(m, &roles, &opt, &len);
    assert_non_null(strstr(svg, "width=\"1280\" height=\"180\" viewBox=\"0 0 1280 180\" "
                                "font-family=\"sans-serif\">\n"
                                "<rect width=\"100%\" height=\"100%\" fill=\"#fff\"/>\n"));
    /* 8 panels, 8 labels, evenly spaced frames 0 … 59 */
    assert_int_equal(tu_count(svg, "<svg x="), 8);
    assert_int_equal(tu_count(svg, ">frame "), 8);
    static const char *const labels[] = {
        ">frame 0 \xc2\xb7 0.00 s<",  ">frame 8 \xc2\xb7 0.27 s<",  ">frame 17 \xc2\xb7 0.57 s<",
        ">frame 25 \xc2\xb7 0.83 s<", ">frame 34 \xc2\xb7 1.13 s<", ">frame 42 \xc2\xb7 1.40 s<",
        ">frame 51 \xc2\xb7 1.70 s<", ">frame 59 \xc2\xb7 1.97 s<"};
    const char *prev = svg;
    for (size_t i = 0; i < 8; i++) {
        const char *p = strstr(svg, labels[i]);
        if (!p || p < prev)
            fail_msg("label %s missing or out of order", labels[i]);
        prev = p;
    }
    /* sides: clavicle + arm + hand end, leg chain + toe end = 10 bones per side; the centre
     * has Spine, Chest, Neck, Head, Head_end (the Hips → reference-root bone is hidden) */
    char *panel = panel_text(svg, 0);
    assert_int_equal(bones_of(panel, BLUE), 10);
    assert_int_equal(bones_of(panel, RED), 10);
    assert_int_equal(bones_of(panel, GREY), 5);
    /* a head circle with a white fill, a ground line, five trajectories */
    assert_int_equal(tu_count(panel, "fill=\"#fff\" stroke=\"" GREY "\""), 1);
    assert_int_equal(tu_count(panel, "<path stroke=\"#b9bec6\""), 1);
    assert_int_equal(tu_count(panel, "<use href=\"#afm"), 5);
    /* every dot of the panel lies inside it (the reference root at the origin, 0–2 m away
     * from the walker, neither shows nor shrinks the figure) */
    size_t dots = tu_count(panel, "<circle cx=");
    assert_true(dots >= 20);
    double ymin = 1e9, ymax = -1e9;
    for (size_t i = 0; i < dots; i++) {
        double cx, cy;
        circle_at(panel, i, &cx, &cy);
        assert_true(cx > 0 && cx < 160 && cy > 0 && cy < 160);
        ymin = fmin(ymin, cy);
        ymax = fmax(ymax, cy);
    }
    assert_true(ymax - ymin > 100); /* the figure fills most of the panel's height */
    free(panel);
    /* the legend comes with a title */
    assert_null(strstr(svg, "<tspan"));
    opt.title = "walk";
    char *titled = render(m, &roles, &opt, NULL);
    assert_int_equal(tu_count(titled, "<tspan fill=\"" BLUE "\">"), 1);
    affect_free(titled);
    /* without roles: one colour, no head, no trajectories, no legend */
    char *plain = render(m, NULL, &opt, NULL);
    assert_null(strstr(plain, BLUE));
    assert_null(strstr(plain, RED));
    assert_null(strstr(plain, "<defs>"));
    assert_null(strstr(plain, "<use"));
    assert_null(strstr(plain, "<tspan"));
    assert_null(strstr(plain, "fill=\"#fff\" stroke="));
    affect_free(plain);
    affect_free(svg);
    affect_motion_free(m);
}

static void test_labels_and_frame_choice(void **state)
{
    affect_motion *m = make_motion(10, 2, 30);
    set_pos(m, 0, 1, 0, 1, 0);
    affect_svg_options opt;
    affect_svg_options_default(&opt);
    opt.frames = 4;
    char *svg = render(m, NULL, &opt, NULL);
    assert_int_equal(tu_count(svg, "<svg x="), 4);
    assert_non_null(strstr(svg, ">frame 0 \xc2\xb7 0.00 s</text>"));
    assert_non_null(strstr(svg, ">frame 3 \xc2\xb7 0.10 s</text>"));
    assert_non_null(strstr(svg, ">frame 6 \xc2\xb7 0.20 s</text>"));
    assert_non_null(strstr(svg, ">frame 9 \xc2\xb7 0.30 s</text>"));
    assert_non_null(strstr(svg, "width=\"640\""));
    affect_free(svg);
    /* clamped to the frame count */
    affect_motion *s = NULL;
    assert_int_equal(affect_motion_slice(m, 0, 2, &s, NULL), AFFECT_OK);
    opt.frames = 8;
    svg = render(s, NULL, &opt, NULL);
    assert_int_equal(tu_count(svg, "<svg x="), 3);
    assert_int_equal(tu_count(svg, ">frame "), 3);
    assert_non_null(strstr(svg, ">frame 2 \xc2\xb7 0.07 s</text>"));
    affect_free(svg);
    /* one panel shows frame 0; no labels means no label row */
    opt.frames = 1;
    opt.labels = false;
    svg = render(m, NULL, &opt, NULL);
    assert_int_equal(tu_count(svg, "<svg x="), 1);
    assert_int_equal(tu_count(svg, "frame"), 0);
    assert_int_equal(tu_count(svg, "<text"), 0);
    assert_non_null(strstr(svg, "width=\"160\" height=\"160\""));
    affect_free(svg);
    affect_motion_free(s);
    affect_motion_free(m);
}

/* Dot positions of joint 1 relative to joint 0 in the first panel: sign of Δx and Δy. */
static void dot_direction(const affect_motion *m, affect_svg_view view, int up, int *sx, int *sy)
{
    affect_svg_options opt;
    affect_svg_options_default(&opt);
    opt.view = view;
    opt.up_axis = up;
    opt.frames = 1;
    char *svg = render(m, NULL, &opt, NULL);
    char *panel = panel_text(svg, 0);
    assert_int_equal(tu_count(panel, "<circle"), 2);
    double x0, y0, x1, y1;
    circle_at(panel, 0, &x0, &y0);
    circle_at(panel, 1, &x1, &y1);
    *sx = x1 > x0 + 1 ? 1 : x1 < x0 - 1 ? -1 : 0;
    *sy = y1 > y0 + 1 ? 1 : y1 < y0 - 1 ? -1 : 0;
    free(panel);
    affect_free(svg);
}

static void test_views_and_up_axes(void **state)
{
    static const struct {
        int up;
        double p[3];                   /* joint 1; joint 0 is at the origin */
        int front[2], side[2], top[2]; /* expected signs of (Δx, Δy) in SVG coordinates */
    } cases[] = {
        /* y up: front x/y, side z/y, top x/z with +z pointing down the screen */
        {1, {1, 2, -3}, {1, -1}, {-1, -1}, {1, -1}},
        {1, {-1, -2, 3}, {-1, 1}, {1, 1}, {-1, 1}},
        /* z up: front x/z, side y/z, top x/y with +y pointing up the screen */
        {2, {1, -3, 2}, {1, -1}, {-1, -1}, {1, 1}},
        /* x up: front y/x, side z/x, top y/z with +z pointing up the screen */
        {0, {2, 1, -3}, {1, -1}, {-1, -1}, {1, 1}},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        affect_motion *m = make_motion(1, 2, 30);
        set_pos(m, 0, 1, cases[i].p[0], cases[i].p[1], cases[i].p[2]);
        int sx, sy;
        dot_direction(m, AFFECT_SVG_FRONT, cases[i].up, &sx, &sy);
        if (sx != cases[i].front[0] || sy != cases[i].front[1])
            fail_msg("case %zu front: (%d, %d)", i, sx, sy);
        dot_direction(m, AFFECT_SVG_SIDE, cases[i].up, &sx, &sy);
        if (sx != cases[i].side[0] || sy != cases[i].side[1])
            fail_msg("case %zu side: (%d, %d)", i, sx, sy);
        dot_direction(m, AFFECT_SVG_TOP, cases[i].up, &sx, &sy);
        if (sx != cases[i].top[0] || sy != cases[i].top[1])
            fail_msg("case %zu top: (%d, %d)", i, sx, sy);
        affect_motion_free(m);
    }
    /* and the whole documents differ between views and up axes */
    affect_motion *m = make_human(40);
    affect_roles roles;
    human_roles(&roles);
    affect_svg_options opt;
    affect_svg_options_default(&opt);
    char *docs[5];
    for (int v = 0; v < 3; v++) {
        opt.view = (affect_svg_view)v;
        docs[v] = render(m, &roles, &opt, NULL);
    }
    opt.view = AFFECT_SVG_FRONT;
    opt.up_axis = 0;
    docs[3] = render(m, &roles, &opt, NULL);
    opt.up_axis = 2;
    docs[4] = render(m, &roles, &opt, NULL);
    for (int i = 0; i < 5; i++)
        for (int k = i + 1; k < 5; k++)
            if (strcmp(docs[i], docs[k]) == 0)
                fail_msg("documents %d and %d are equal", i, k);
    /* the top view has no ground line */
    assert_int_equal(tu_count(docs[2], "#b9bec6"), 0);
    assert_int_equal(tu_count(docs[0], "#b9bec6"), 8);
    for (int i = 0; i < 5; i++)
        affect_free(docs[i]);
    affect_motion_free(m);
}

static void test_one_scale_fixed_vertical(void **state)
{
    /* frame 0: a 1-unit vertical segment at x = 0; frame 1: 2 units, lifted by 1 and moved
     * 5 units to the right */
    affect_motion *m = make_motion(2, 2, 30);
    set_pos(m, 0, 0, 0, 0, 0);
    set_pos(m, 0, 1, 0, 1, 0);
    set_pos(m, 1, 0, 5, 1, 0);
    set_pos(m, 1, 1, 5, 3, 0);
    affect_svg_options opt;
    affect_svg_options_default(&opt);
    char *svg = render(m, NULL, &opt, NULL);
    char *p0 = panel_text(svg, 0), *p1 = panel_text(svg, 1);
    double a0x, a0y, b0x, b0y, a1x, a1y, b1x, b1y;
    circle_at(p0, 0, &a0x, &a0y);
    circle_at(p0, 1, &b0x, &b0y);
    circle_at(p1, 0, &a1x, &a1y);
    circle_at(p1, 1, &b1x, &b1y);
    /* one scale: the second segment is twice as long */
    tu_assert_near((a1y - b1y) / (a0y - b0y), 2.0, 0.02);
    /* centred horizontally on the centroid, vertically fixed: frame 1's bottom joint is one
     * unit (half the first segment's length) higher than frame 0's */
    tu_assert_near(a0x, 80, 0.05);
    tu_assert_near(a1x, 80, 0.05);
    tu_assert_near(a0y - a1y, a0y - b0y, 0.1);
    /* the vertical range 0..3 fills the panel between its margins */
    tu_assert_near(a0y - b1y, 160 * 0.8, 0.2);
    free(p0);
    free(p1);
    affect_free(svg);
    affect_motion_free(m);
}

static void test_dots_only_without_skeleton(void **state)
{
    affect_motion *m = make_human(20);
    affect_roles roles;
    human_roles(&roles);
    affect_svg_options opt;
    affect_svg_options_default(&opt);
    opt.frames = 2;
    char *with = render(m, &roles, &opt, NULL);
    assert_int_equal(tu_count(with, "stroke-linecap"), 2);
    assert_true(tu_count(with, "<path stroke=\"") >= 6);
    for (uint32_t j = 0; j < H_COUNT; j++)
        m->parents[j] = -1;
    char *without = render(m, &roles, &opt, NULL);
    assert_int_equal(tu_count(without, "stroke-linecap"), 0);
    /* only the ground lines remain as paths; every joint is a dot, plus the head circle */
    assert_int_equal(tu_count(without, "<path stroke=\""), 2);
    assert_int_equal(tu_count(without, "<circle"), 2 * (H_COUNT + 1));
    /* sides still colour the dots */
    assert_non_null(strstr(without, "<g fill=\"" BLUE "\"><circle"));
    assert_non_null(strstr(without, "<g fill=\"" RED "\"><circle"));
    affect_free(with);
    affect_free(without);
    affect_motion_free(m);
}

static void test_trajectories(void **state)
{
    affect_motion *m = make_human(2000);
    affect_roles roles;
    human_roles(&roles);
    affect_svg_options opt;
    affect_svg_options_default(&opt);
    size_t len;
    char *svg = render(m, &roles, &opt, &len);
    assert_int_equal(tu_count(svg, "<defs>"), 1);
    assert_int_equal(tu_count(svg, "<polyline id=\"afm"), 5);
    assert_int_equal(tu_count(svg, "<use href=\"#afm"), 5 * 8);
    /* every <use> names a polyline of the <defs> */
    const char *def = strstr(svg, "<polyline id=\"");
    char id[32];
    memcpy(id, def + 14, 21);
    id[21] = '\0';
    assert_int_equal(id[19], '-');
    char href[48];
    snprintf(href, sizeof href, "<use href=\"#%.19s-", id);
    assert_int_equal(tu_count(svg, href), 5 * 8);
    /* at most 200 points per polyline */
    for (const char *p = strstr(svg, "points=\""); p; p = strstr(p + 1, "points=\"")) {
        size_t pts = 1;
        for (const char *q = p + 8; *q != '"'; q++)
            pts += *q == ' ';
        assert_true(pts >= 2 && pts <= 200);
    }
    /* the size stays small: 27 joints, 8 panels, 2000 frames */
    if (len >= 60000)
        fail_msg("%zu bytes", len);
    /* off: none at all */
    opt.trajectories = false;
    char *off = render(m, &roles, &opt, NULL);
    assert_null(strstr(off, "<defs>"));
    assert_null(strstr(off, "<use"));
    assert_true(strlen(off) < len);
    /* another motion gets other ids (inlined previews never collide) */
    set_pos(m, 0, H_HAND_L, 30, 90, 0);
    opt.trajectories = true;
    char *other = render(m, &roles, &opt, NULL);
    assert_null(strstr(other, id));
    affect_free(other);
    affect_free(off);
    affect_free(svg);
    affect_motion_free(m);
}

static void test_title_escaped(void **state)
{
    affect_motion *m = make_motion(3, 2, 30);
    affect_svg_options opt;
    affect_svg_options_default(&opt);
    opt.title = "<&> \"quoted\" 'single'";
    char *svg = render(m, NULL, &opt, NULL);
    assert_non_null(strstr(svg, ">&lt;&amp;&gt; &quot;quoted&quot; &#39;single&#39;</text>"));
    assert_null(strstr(svg, "<&>"));
    affect_free(svg);
    affect_motion_free(m);
}

static void test_degenerate(void **state)
{
    affect_svg_options opt;
    affect_svg_options_default(&opt);
    /* one frame, one joint */
    affect_motion *m = make_motion(1, 1, 30);
    set_pos(m, 0, 0, 3, 4, 5);
    char *svg = render(m, NULL, &opt, NULL);
    assert_int_equal(tu_count(svg, "<svg x="), 1);
    assert_int_equal(tu_count(svg, "<circle"), 1);
    double cx, cy;
    char *panel = panel_text(svg, 0);
    circle_at(panel, 0, &cx, &cy);
    tu_assert_near(cx, 80, 1e-9);
    free(panel);
    affect_free(svg);
    for (int v = 0; v < 3; v++) {
        opt.view = (affect_svg_view)v;
        svg = render(m, NULL, &opt, NULL);
        affect_free(svg);
    }
    affect_motion_free(m);
    /* a full skeleton with every point equal, with roles and trajectories */
    m = make_human(50);
    for (uint32_t t = 0; t < 50; t++)
        for (uint32_t j = 0; j < H_COUNT; j++)
            set_pos(m, t, j, 1, 1, 1);
    affect_roles roles;
    human_roles(&roles);
    opt.view = AFFECT_SVG_FRONT;
    opt.title = "all equal";
    svg = render(m, &roles, &opt, NULL);
    assert_int_equal(tu_count(svg, "<svg x="), 8);
    affect_free(svg);
    opt.view = AFFECT_SVG_TOP;
    svg = render(m, &roles, &opt, NULL);
    affect_free(svg);
    /* extreme coordinates and a tiny panel still give finite, bounded numbers */
    for (uint32_t j = 0; j < H_COUNT; j++)
        set_pos(m, 7, j, 3e38, -3e38, 1e-30 * j);
    opt.panel_size = 32;
    opt.frames = 64;
    svg = render(m, &roles, &opt, NULL);
    assert_int_equal(tu_count(svg, "<svg x="), 50);
    affect_free(svg);
    affect_motion_free(m);
}

static void test_errors(void **state)
{
    affect_motion *m = make_human(10);
    affect_roles roles;
    human_roles(&roles);
    static const struct {
        uint32_t frames, panel;
        int up, view;
        const char *message;
    } cases[] = {
        {0, 160, 1, 0, "frames must be between 1 and 64, got 0"},
        {65, 160, 1, 0, "frames must be between 1 and 64, got 65"},
        {8, 31, 1, 0, "panel_size must be between 32 and 1024, got 31"},
        {8, 1025, 1, 0, "panel_size must be between 32 and 1024, got 1025"},
        {8, 160, -1, 0, "up_axis must be 0 (x), 1 (y) or 2 (z), got -1"},
        {8, 160, 3, 0, "up_axis must be 0 (x), 1 (y) or 2 (z), got 3"},
        {8, 160, 1, 3, "view must be 0 (front), 1 (side) or 2 (top), got 3"},
        {8, 160, 1, -1, "view must be 0 (front), 1 (side) or 2 (top), got -1"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        affect_svg_options opt;
        affect_svg_options_default(&opt);
        opt.frames = cases[i].frames;
        opt.panel_size = cases[i].panel;
        opt.up_axis = cases[i].up;
        opt.view = (affect_svg_view)cases[i].view;
        char *svg = (char *)"sentinel";
        size_t len = 99;
        affect_error err;
        assert_int_equal(affect_motion_svg(m, &roles, &opt, &svg, &len, &err), AFFECT_ERR_INVALID);
        assert_string_equal(err.msg, cases[i].message);
        assert_null(svg);
        assert_int_equal(len, 0);
    }
    /* the boundaries themselves are fine */
    affect_svg_options opt;
    affect_svg_options_default(&opt);
    opt.frames = 64;
    opt.panel_size = 32;
    affect_free(render(m, &roles, &opt, NULL));
    opt.frames = 1;
    opt.panel_size = 1024;
    affect_free(render(m, &roles, &opt, NULL));
    /* NULL options mean the defaults */
    affect_svg_options_default(&opt);
    char *a = render(m, &roles, NULL, NULL), *b = render(m, &roles, &opt, NULL);
    assert_string_equal(a, b);
    affect_free(a);
    affect_free(b);

    char *svg = NULL;
    affect_error err;
    roles.joint[AFFECT_ROLE_LEFT_HAND] = 40;
    assert_int_equal(affect_motion_svg(m, &roles, &opt, &svg, NULL, &err), AFFECT_ERR_RANGE);
    assert_string_equal(err.msg,
                        "role left_hand: joint 40 out of range (the motion has 27 joints)");
    assert_null(svg);
    human_roles(&roles);
    m->parents[3] = 99;
    assert_int_equal(affect_motion_svg(m, &roles, &opt, &svg, NULL, &err), AFFECT_ERR_RANGE);
    assert_string_equal(err.msg, "joint 3: parent 99 out of range (the motion has 27 joints)");
    m->parents[3] = human_parents[3];
    affect_motion_at(m, 5, 2)[1] = NAN;
    assert_int_equal(affect_motion_svg(m, &roles, &opt, &svg, NULL, &err), AFFECT_ERR_FORMAT);
    assert_string_equal(err.msg, "frame 5, joint 2: coordinate is not finite");
    affect_motion_at(m, 5, 2)[1] = -INFINITY;
    assert_int_equal(affect_motion_svg(m, &roles, &opt, &svg, NULL, NULL), AFFECT_ERR_FORMAT);
    assert_null(svg);
    affect_motion_free(m);
}

static void test_deterministic(void **state)
{
    affect_motion *m = make_human(300);
    affect_roles roles;
    human_roles(&roles);
    affect_svg_options opt;
    affect_svg_options_default(&opt);
    opt.title = "same";
    for (int v = 0; v < 3; v++) {
        opt.view = (affect_svg_view)v;
        size_t la, lb;
        char *a = render(m, &roles, &opt, &la), *b = render(m, &roles, &opt, &lb);
        assert_int_equal(la, lb);
        assert_memory_equal(a, b, la);
        affect_free(a);
        affect_free(b);
    }
    affect_motion_free(m);
}

/* ---- animations, groups, the top view's turn, state labels ---- */

/* The text of the values="…" attribute following the n-th occurrence of key, malloc'd. */
static char *values_after(const char *s, const char *key, size_t n)
{
    const char *p = s;
    for (size_t i = 0; i <= n; i++) {
        p = strstr(i ? p + 1 : p, key);
        assert_non_null(p);
    }
    p = strstr(p, "values=\"");
    assert_non_null(p);
    p += 8;
    const char *e = strchr(p, '"');
    assert_non_null(e);
    char *out = malloc((size_t)(e - p) + 1);
    assert_non_null(out);
    memcpy(out, p, (size_t)(e - p));
    out[e - p] = '\0';
    return out;
}

static void test_animation(void **state)
{
    affect_motion *m = make_human(91); /* 3 s at 30 fps */
    affect_roles roles;
    human_roles(&roles);
    affect_svg_options opt;
    affect_svg_options_default(&opt);
    opt.animate = true;
    opt.title = "walk";
    size_t len;
    char *svg = render(m, &roles, &opt, &len);
    /* one panel, no film strip labels, the duration and frame count under it */
    assert_int_equal(tu_count(svg, "<svg x="), 1);
    assert_int_equal(tu_count(svg, "frame 0"), 0);
    assert_non_null(strstr(svg, ">3.03 s \xc2\xb7 91 frames</text>"));
    /* bones of three colours move; real time: dur = (T - 1) / fps = 3 s, looping */
    assert_int_equal(tu_count(svg, "<animate attributeName=\"d\""), 3);
    assert_int_equal(tu_count(svg, "dur=\"3s\" repeatCount=\"indefinite\""),
                     tu_count(svg, "<animate"));
    assert_int_equal(tu_count(svg, "<animateTransform attributeName=\"transform\""), 1);
    assert_non_null(strstr(svg, "<animate attributeName=\"cx\""));
    assert_non_null(strstr(svg, "<rect class=\"time\""));
    /* automatic keyframes: 15 per second, 1 + ceil(3 × 15) = 46; every one has the same
     * commands (SMIL interpolates paths only then); the first is the static d */
    char *v = values_after(svg, "<animate attributeName=\"d\"", 0);
    assert_int_equal(tu_count(v, ";") + 1, 46);
    size_t moves = tu_count(v, "M");
    assert_int_equal(moves % 46, 0);
    char *first = strstr(svg, "<path stroke=\"" GREY "\" d=\"");
    assert_non_null(first);
    first += strlen("<path stroke=\"" GREY "\" d=\"");
    assert_true(strncmp(first, v, strcspn(v, ";")) == 0);
    free(v);
    affect_free(svg);
    /* explicit keyframes, clamped to the frame count */
    opt.keyframes = 5;
    svg = render(m, &roles, &opt, NULL);
    v = values_after(svg, "<animate attributeName=\"d\"", 1);
    assert_int_equal(tu_count(v, ";") + 1, 5);
    free(v);
    affect_free(svg);
    opt.keyframes = 1000;
    svg = render(m, &roles, &opt, NULL);
    v = values_after(svg, "<animate attributeName=\"d\"", 2);
    assert_int_equal(tu_count(v, ";") + 1, 91);
    free(v);
    affect_free(svg);
    /* a one-frame motion: a still figure, no animation element */
    affect_motion *one = make_human(1);
    svg = render(one, &roles, &opt, NULL);
    assert_int_equal(tu_count(svg, "<animate"), 0);
    affect_free(svg);
    affect_motion_free(one);
    /* a bad keyframe count */
    affect_error err;
    char *out = NULL;
    opt.keyframes = 1;
    assert_int_equal(affect_motion_svg(m, &roles, &opt, &out, NULL, &err), AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "keyframes must be 0 (automatic) or between 2 and 1000, got 1");
    assert_null(out);
    affect_motion_free(m);
}

static void test_group(void **state)
{
    affect_motion *a = make_human(31), *b = make_human(61);
    /* b is a twice larger copy of a's first 31 frames and more */
    for (uint32_t t = 0; t < b->n_frames; t++)
        for (uint32_t j = 0; j < b->n_joints; j++) {
            float *p = affect_motion_at(b, t, j);
            p[0] *= 2, p[1] *= 2, p[2] *= 2;
        }
    affect_roles roles[2];
    human_roles(&roles[0]);
    human_roles(&roles[1]);
    const affect_motion *ms[2] = {a, b};
    const char *captions[2] = {"source <a>", "real"};
    affect_svg_options opt;
    affect_svg_options_default(&opt);
    opt.animate = true;
    opt.panel_size = 100;
    char *svg = NULL;
    size_t len = 0;
    affect_error err;
    assert_int_equal(affect_motion_svg_group(ms, roles, captions, 2, &opt, &svg, &len, &err),
                     AFFECT_OK);
    tu_assert_svg_well_formed(svg, len);
    /* side by side, captions escaped, each looping at its own duration */
    assert_int_equal(tu_count(svg, "<svg x="), 2);
    assert_non_null(strstr(svg, "<svg x=\"100\" y=\"0\""));
    assert_true(strncmp(svg, "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"200\"", 50) == 0);
    assert_non_null(strstr(svg, ">source &lt;a&gt;</text>"));
    assert_non_null(strstr(svg, ">real</text>"));
    assert_non_null(strstr(svg, "dur=\"1s\""));
    assert_non_null(strstr(svg, "dur=\"2s\""));
    /* one scale: the head circle of the larger body is twice the smaller one's */
    char *p0 = panel_text(svg, 0), *p1 = panel_text(svg, 1);
    double r0 = strtod(strstr(strstr(p0, "<circle cx="), " r=\"") + 4, NULL);
    double r1 = strtod(strstr(strstr(p1, "<circle cx="), " r=\"") + 4, NULL);
    assert_true(fabs(r1 - 2 * r0) <= 0.11);
    free(p0);
    free(p1);
    /* trajectory ids differ between the two motions */
    assert_int_equal(tu_count(svg, "<defs>"), 2);
    affect_free(svg);
    /* a caption longer than its panel is cut with an ellipsis */
    const char *long_captions[2] = {"dataset-1_walk_angry_001 generated at strength 1.5", "b"};
    assert_int_equal(affect_motion_svg_group(ms, roles, long_captions, 2, &opt, &svg, &len, &err),
                     AFFECT_OK);
    tu_assert_svg_well_formed(svg, len);
    /* 100 px at 11.1 px: 15 characters, the last the ellipsis */
    assert_non_null(strstr(svg, ">dataset-1_walk\xe2\x80\xa6</text>"));
    affect_free(svg);
    /* strips: one row per motion with its caption above */
    opt.animate = false;
    opt.frames = 3;
    assert_int_equal(affect_motion_svg_group(ms, roles, captions, 2, &opt, &svg, &len, &err),
                     AFFECT_OK);
    tu_assert_svg_well_formed(svg, len);
    assert_int_equal(tu_count(svg, "<svg x="), 6);
    assert_int_equal(tu_count(svg, "class=\"caption\""), 2);
    affect_free(svg);
    /* a group of one without caption is motion_svg's document */
    char *single = render(a, &roles[0], &opt, NULL);
    assert_int_equal(affect_motion_svg_group(ms, roles, NULL, 1, &opt, &svg, &len, &err),
                     AFFECT_OK);
    assert_string_equal(svg, single);
    affect_free(svg);
    affect_free(single);
    /* errors: the group's size, and one motion's error named by its place */
    assert_int_equal(affect_motion_svg_group(ms, roles, captions, 0, &opt, &svg, &len, &err),
                     AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "a group holds 1 to 64 motions, got 0");
    affect_motion_at(b, 4, 2)[1] = NAN;
    assert_int_equal(affect_motion_svg_group(ms, roles, captions, 2, &opt, &svg, &len, &err),
                     AFFECT_ERR_FORMAT);
    assert_string_equal(err.msg, "motion 1: frame 4, joint 2: coordinate is not finite");
    assert_null(svg);
    affect_motion_free(a);
    affect_motion_free(b);
}

/* Top view of a walk along +z (y up): turned so that the walk goes right, the pelvis path is a
 * horizontal line through the centre, and a facing marker points right (the walker faces +z). */
static void test_top_view_turn(void **state)
{
    affect_motion *m = make_human(61);
    affect_roles roles;
    human_roles(&roles);
    /* a straight walk: no bounce, so that the pelvis moves along +z only */
    for (uint32_t t = 0; t < m->n_frames; t++)
        affect_motion_at(m, t, H_HIPS)[1] = 95;
    affect_svg_options opt;
    affect_svg_options_default(&opt);
    opt.view = AFFECT_SVG_TOP;
    opt.frames = 2;
    char *svg = render(m, &roles, &opt, NULL);
    /* one trajectory only, the pelvis's: every point on y = 0 and x growing */
    assert_int_equal(tu_count(svg, "<polyline"), 1);
    const char *p = strstr(svg, "points=\"");
    assert_non_null(p);
    p += 8;
    double prev = -1e9;
    while (*p != '"') {
        char *end;
        double x = strtod(p, &end);
        assert_true(*end == ',');
        double y = strtod(end + 1, &end);
        assert_true(fabs(y) < 0.05);
        assert_true(x > prev);
        prev = x;
        p = end + (*end == ' ');
    }
    /* the facing marker's tip is right of the head */
    const char *f = strstr(svg, "<polygon class=\"facing\"");
    assert_non_null(f);
    f = strstr(f, "points=\"") + 8;
    double tip = strtod(f, NULL);
    char *panel = panel_text(svg, 0);
    const char *head = strstr(panel, "fill=\"none\" stroke=");
    assert_non_null(head);
    affect_free(svg);
    /* the head circle is the last circle before the marker; its centre is left of the tip */
    double cx, cy;
    size_t n_circles = tu_count(panel, "<circle cx=\"");
    circle_at(panel, n_circles - 1, &cx, &cy);
    assert_true(tip > cx + 1);
    free(panel);
    affect_motion_free(m);
}

static void test_state_labels(void **state)
{
    affect_motion *m = make_human(5);
    affect_roles roles;
    human_roles(&roles);
    affect_svg_options opt;
    affect_svg_options_default(&opt);
    opt.state_labels = true;
    char *svg = render(m, &roles, &opt, NULL);
    assert_int_equal(tu_count(svg, "frame "), 0);
    for (int k = 1; k <= 5; k++) {
        char key[32];
        snprintf(key, sizeof key, ">state %d</text>", k);
        assert_int_equal(tu_count(svg, key), 1);
    }
    affect_free(svg);
    affect_motion_free(m);
}

/* ---- out of memory: every allocation of a render fails in turn (tu_oom_sweep) ---- */

typedef struct svg_oom {
    const affect_motion *m;
    const affect_roles *roles;
    const affect_svg_options *opt;
    char *svg;
} svg_oom;

static affect_status oom_render(void *ctx, affect_error *err)
{
    svg_oom *c = ctx;
    c->svg = NULL;
    return affect_motion_svg(c->m, c->roles, c->opt, &c->svg, NULL, err);
}

static void oom_render_finish(void *ctx, affect_status st)
{
    svg_oom *c = ctx;
    if (st != AFFECT_OK)
        assert_null(c->svg);
    affect_free(c->svg);
}

typedef struct group_oom {
    const affect_motion *const *m;
    const affect_roles *roles;
    const char *const *captions;
    const affect_svg_options *opt;
    char *svg;
} group_oom;

static affect_status oom_group(void *ctx, affect_error *err)
{
    group_oom *c = ctx;
    c->svg = NULL;
    return affect_motion_svg_group(c->m, c->roles, c->captions, 2, c->opt, &c->svg, NULL, err);
}

static void oom_group_finish(void *ctx, affect_status st)
{
    group_oom *c = ctx;
    if (st != AFFECT_OK)
        assert_null(c->svg);
    affect_free(c->svg);
}

static void test_out_of_memory_animated_group(void **state)
{
    affect_motion *a = make_human(60), *b = make_human(90);
    affect_roles roles[2];
    human_roles(&roles[0]);
    human_roles(&roles[1]);
    const affect_motion *ms[2] = {a, b};
    const char *captions[2] = {"a", NULL};
    affect_svg_options opt;
    affect_svg_options_default(&opt);
    opt.animate = true;
    opt.view = AFFECT_SVG_TOP;
    group_oom c = {ms, roles, captions, &opt, NULL};
    assert_true(tu_oom_sweep(oom_group, &c, oom_group_finish, NULL) >= 5);
    affect_motion_free(a);
    affect_motion_free(b);
}

static void test_out_of_memory(void **state)
{
    affect_motion *m = make_human(400);
    affect_roles roles;
    human_roles(&roles);
    affect_svg_options opt;
    affect_svg_options_default(&opt);
    opt.title = "oom";
    svg_oom c = {m, &roles, &opt, NULL};
    assert_true(tu_oom_sweep(oom_render, &c, oom_render_finish, NULL) >= 5);
    affect_motion_free(m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_defaults),
        cmocka_unit_test(test_human_strip),
        cmocka_unit_test(test_labels_and_frame_choice),
        cmocka_unit_test(test_views_and_up_axes),
        cmocka_unit_test(test_one_scale_fixed_vertical),
        cmocka_unit_test(test_dots_only_without_skeleton),
        cmocka_unit_test(test_trajectories),
        cmocka_unit_test(test_title_escaped),
        cmocka_unit_test(test_degenerate),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_deterministic),
        cmocka_unit_test(test_animation),
        cmocka_unit_test(test_group),
        cmocka_unit_test(test_top_view_turn),
        cmocka_unit_test(test_state_labels),
        cmocka_unit_test(test_out_of_memory),
        cmocka_unit_test(test_out_of_memory_animated_group),
    };
    return cmocka_run_group_tests_name("svg", tests, NULL, NULL);
}
