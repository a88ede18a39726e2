/*
 * test_plot.c — SVG scatter plots: well-formed documents, one series group and one legend
 * row per label with its count, colours and marker shapes in sorted label order, tick values
 * (1-2-5 steps, exact labels, linear pixel placement) for many ranges — negative, tiny, huge,
 * ±DBL_MAX, equal min and max — and for log axes, the skipped-points note, no data, means
 * with sample sd (also in log space), text escaping and truncation, the legend kept right of
 * the points, option errors with their exact messages, determinism and independence of the
 * order of points, and out-of-memory at every allocation.
 */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"
#include "util/numparse.h"
#include "affect/plot.h"

/* ---- helpers ---- */

static affect_scatter *new_scatter(void)
{
    affect_scatter *sc = NULL;
    affect_error err;
    assert_int_equal(affect_scatter_create(&sc, &err), AFFECT_OK);
    return sc;
}

static void add(affect_scatter *sc, double x, double y, const char *label)
{
    affect_error err;
    assert_int_equal(affect_scatter_add(sc, x, y, label, &err), AFFECT_OK);
}

/* Out of line: inlined into the tests, gcc 12 at -O3 takes the returned text for a pointer to
 * the local `svg` variable and reports a false -Wdangling-pointer (as in test_svg.c). */
__attribute__((noinline)) static char *render(const affect_scatter *sc,
                                              const affect_plot_options *opt)
{
    char *svg = NULL;
    size_t len = 0;
    affect_error err;
    if (affect_scatter_render(sc, opt, &svg, &len, &err) != AFFECT_OK)
        fail_msg("render failed: %s", err.msg);
    tu_assert_svg_well_formed(svg, len);
    return svg;
}

/* The numeric value of attribute name in the element that starts at or after p. */
static double attr(const char *p, const char *name)
{
    char key[64];
    snprintf(key, sizeof key, " %s=\"", name);
    const char *a = strstr(p, key);
    if (!a)
        fail_msg("no attribute %s", name);
    a += strlen(key);
    double v = 0;
    const char *end = affect_parse_double(a, a + strlen(a), &v);
    if (!end || *end != '"')
        fail_msg("attribute %s is not a number: %.20s", name, a);
    return v;
}

/* Text of the k-th element of the given class (after "class=\"cls\""), into buf. */
static bool class_text(const char *svg, const char *cls, size_t k, char *buf, size_t size)
{
    char key[64];
    snprintf(key, sizeof key, "class=\"%s\"", cls);
    const char *p = strstr(svg, key);
    for (size_t i = 0; p && i < k; i++)
        p = strstr(p + 1, key);
    if (!p)
        return false;
    const char *s = strchr(p, '>') + 1, *e = strstr(s, "</text>");
    size_t n = (size_t)(e - s);
    assert_true(n < size);
    memcpy(buf, s, n);
    buf[n] = '\0';
    return true;
}

/* A tick label back to a number: "−1.5×10⁻⁷" → -1.5e-7. */
static double parse_tick(const char *t)
{
    char buf[128];
    size_t o = 0;
    bool mantissa = false;
    for (const char *p = t; *p;) {
        static const char *const sup[10] = {
            "\xe2\x81\xb0", "\xc2\xb9",     "\xc2\xb2",     "\xc2\xb3",     "\xe2\x81\xb4",
            "\xe2\x81\xb5", "\xe2\x81\xb6", "\xe2\x81\xb7", "\xe2\x81\xb8", "\xe2\x81\xb9"};
        bool done = false;
        for (int d = 0; d < 10 && !done; d++)
            if (strncmp(p, sup[d], strlen(sup[d])) == 0) {
                buf[o++] = (char)('0' + d);
                p += strlen(sup[d]);
                done = true;
            }
        if (done)
            continue;
        if (strncmp(p, "\xe2\x88\x92", 3) == 0) { /* minus sign */
            buf[o++] = '-';
            p += 3;
        } else if (strncmp(p, "\xe2\x81\xbb", 3) == 0) { /* superscript minus */
            buf[o++] = '-';
            p += 3;
        } else if (strncmp(p,
                           "\xc3\x97"
                           "10",
                           4) == 0) { /* ×10 */
            buf[o++] = 'e';
            p += 4;
        } else if (strncmp(p, "10", 2) == 0 && !mantissa && p[2] != '\0' &&
                   (unsigned char)p[2] >= 0x80) { /* a bare power of ten: 10ⁿ */
            memcpy(buf + o, "1e", 2);
            o += 2;
            p += 2;
        } else {
            mantissa = true;
            buf[o++] = *p++;
        }
        assert_true(o < sizeof buf - 4);
    }
    buf[o] = '\0';
    char *e = strchr(buf, 'e');
    double m = 0, x = 0;
    const char *end = affect_parse_double(buf, e ? e : buf + o, &m);
    if (!end || end != (e ? e : buf + o) ||
        (e && affect_parse_double(e + 1, buf + o, &x) != buf + o))
        fail_msg("tick label \"%s\" (\"%s\") is not a number", t, buf);
    return e ? m * pow(10, x) : m; /* 2×10³⁰⁸ is +inf: beyond the double range */
}

typedef struct ticks {
    size_t n;
    double v[64];  /* values */
    double px[64]; /* pixel positions */
    char text[64][64];
} ticks;

/* The tick labels of one axis ("x" or "y") with their values and pixel positions. */
static void get_ticks(const char *svg, const char *which, ticks *t)
{
    char cls[16];
    snprintf(cls, sizeof cls, "tick-%s", which);
    t->n = 0;
    while (t->n < 64 && class_text(svg, cls, t->n, t->text[t->n], sizeof t->text[0])) {
        t->v[t->n] = parse_tick(t->text[t->n]);
        char key[32];
        snprintf(key, sizeof key, "class=\"%s\"", cls);
        const char *p = strstr(svg, key);
        for (size_t i = 0; i < t->n; i++)
            p = strstr(p + 1, key);
        t->px[t->n] = strcmp(which, "x") == 0 ? attr(p, "x") : attr(p, "y");
        t->n++;
    }
}

static void frame_of(const char *svg, double *l, double *t, double *r, double *b)
{
    const char *f = strstr(svg, "<rect class=\"frame\"");
    assert_non_null(f);
    *l = attr(f, "x");
    *t = attr(f, "y");
    *r = *l + attr(f, "width");
    *b = *t + attr(f, "height");
}

/* Every drawn marker centre inside the frame. */
static void assert_points_in_frame(const char *svg)
{
    double l, t, r, b;
    frame_of(svg, &l, &t, &r, &b);
    const char *pts = strstr(svg, "<g class=\"points\"");
    const char *end = strstr(pts, "\n</g>\n");
    for (const char *c = strstr(pts, "<circle"); c && c < end; c = strstr(c + 1, "<circle")) {
        double cx = attr(c, "cx"), cy = attr(c, "cy");
        if (!(cx >= l && cx <= r && cy >= t && cy <= b))
            fail_msg("point (%g, %g) outside the frame [%g, %g] × [%g, %g]", cx, cy, l, r, t, b);
    }
}

/* The checks every linear axis must pass: at least two ticks, increasing, one 1-2-5 step
 * apart, placed linearly, and the data [lo, hi] inside the axis. */
static void check_linear_axis(const char *svg, const char *which, double lo, double hi)
{
    ticks t;
    get_ticks(svg, which, &t);
    if (t.n < 2)
        fail_msg("%s axis for [%g, %g]: %zu ticks", which, lo, hi, t.n);
    assert_true(t.n <= 12);
    double step = t.v[1] - t.v[0];
    assert_true(step > 0);
    double e = floor(log10(step) + 1e-9), m = step / pow(10, e);
    if (!(fabs(m - 1) < 1e-6 || fabs(m - 2) < 1e-6 || fabs(m - 5) < 1e-6))
        fail_msg("%s axis for [%g, %g]: step %g is not 1, 2 or 5 × 10^k", which, lo, hi, step);
    step = round(m) * pow(10, e); /* exact, not a difference of rounded values */
    double scale = (t.px[t.n - 1] - t.px[0]) / (t.v[t.n - 1] - t.v[0]);
    for (size_t i = 1; i < t.n; i++) {
        if (fabs(t.v[i] - t.v[i - 1] - step) > 1e-6 * fabs(step))
            fail_msg("%s axis for [%g, %g]: uneven ticks %s, %s", which, lo, hi, t.text[i - 1],
                     t.text[i]);
        double expect = t.px[0] + (t.v[i] - t.v[0]) * scale;
        if (fabs(t.px[i] - expect) > 0.11)
            fail_msg("%s axis: tick %s at %g px, expected %g", which, t.text[i], t.px[i], expect);
        /* integral multiples of the step */
        double k = t.v[i] / step;
        if (!(fabs(k - round(k)) < 1e-6 * fmax(1, fabs(k) * 1e-6)))
            fail_msg("%s axis for [%g, %g]: tick %s is not a multiple of %g", which, lo, hi,
                     t.text[i], step);
    }
    /* ticks stay near the data: within one step of the data range, padding included */
    assert_true(t.v[0] >= lo - step - 0.1 * (hi - lo));
    assert_true(t.v[t.n - 1] <= hi + step + 0.1 * (hi - lo));
    assert_points_in_frame(svg);
}

/* ---- tests ---- */

/* Time-series mode: each label's points joined in x order by one path (added out of order),
 * a label of one point drawn as its marker, the legend's line swatches; the same axes as the
 * scatter of the same points. */
static void test_series_mode(void **state)
{
    affect_scatter *sc = new_scatter();
    add(sc, 3, 1, "left_hand");
    add(sc, 1, 2, "left_hand");
    add(sc, 2, 5, "left_hand");
    add(sc, 0, 4, "right_hand");
    add(sc, 4, 3, "right_hand");
    add(sc, 2, 2, "all");
    affect_plot_options o;
    affect_plot_options_default(&o);
    assert_false(o.lines);
    char *scatter = render(sc, &o);
    o.lines = true;
    char *svg = render(sc, &o);
    assert_null(strstr(svg, "class=\"points\""));
    assert_non_null(strstr(svg, "<g class=\"lines\""));
    assert_int_equal(tu_count(svg, "<path d=\"M"), 2);
    /* left_hand's path: three points, x increasing */
    const char *g = strstr(svg, "data-label=\"left_hand\" data-count=\"3\"");
    assert_non_null(g);
    const char *d = strstr(g, "<path d=\"M");
    assert_non_null(d);
    d += strlen("<path d=\"M");
    double x[3], y[3];
    char sep[2];
    assert_int_equal(sscanf(d, "%lf %lf%1[L]%lf %lf%1[L]%lf %lf", &x[0], &y[0], sep, &x[1], &y[1],
                            sep, &x[2], &y[2]),
                     8);
    assert_true(x[0] < x[1] && x[1] < x[2]);
    assert_true(y[1] < y[0] && y[1] < y[2]); /* y = 5 at x = 2 is the highest (smallest px) */
    /* "all" has one point: a marker */
    g = strstr(svg, "data-label=\"all\" data-count=\"1\"");
    assert_non_null(g);
    assert_true(strstr(g, "<circle") < strstr(g, "</g>\n"));
    assert_int_equal(tu_count(svg, "class=\"legend-item\"><path"), 3);
    /* the same ticks as the scatter */
    const char *ts = strstr(scatter, "class=\"tick-x\""), *tl = strstr(svg, "class=\"tick-x\"");
    assert_non_null(ts);
    assert_non_null(tl);
    assert_int_equal(tu_count(scatter, "class=\"tick-x\""), tu_count(svg, "class=\"tick-x\""));
    affect_free(scatter);
    affect_free(svg);
    affect_scatter_free(sc);
}

static void test_defaults(void **state)
{
    affect_plot_options o;
    affect_plot_options_default(&o);
    assert_null(o.title);
    assert_null(o.x_label);
    assert_null(o.y_label);
    assert_true(o.width == 560 && o.height == 420 && o.radius == 3);
    assert_false(o.log_x || o.log_y || o.means);
    affect_scatter *sc = new_scatter();
    add(sc, 1, 2, "a");
    char *a = render(sc, NULL), *b = render(sc, &o);
    assert_string_equal(a, b);
    assert_non_null(strstr(a, "width=\"560\" height=\"420\" viewBox=\"0 0 560 420\""));
    assert_non_null(strstr(a, " r=\"3\""));
    assert_null(strstr(a, "class=\"title\""));
    assert_null(strstr(a, "class=\"axis-title\""));
    assert_null(strstr(a, "class=\"note\""));
    assert_null(strstr(a, "class=\"means\""));
    affect_free(a);
    affect_free(b);
    affect_scatter_free(sc);
    affect_scatter_free(NULL);
}

static void test_structure_and_legend(void **state)
{
    affect_scatter *sc = new_scatter();
    /* added out of order; NULL is "(none)" */
    add(sc, 1, 1, "sad");
    add(sc, 2, 3, "angry");
    add(sc, 3, 2, "sad");
    add(sc, 4, 5, NULL);
    add(sc, 5, 4, "happy");
    add(sc, 6, 6, "sad");
    add(sc, 7, 1, "angry");
    assert_int_equal(affect_scatter_count(sc), 7);
    assert_int_equal(affect_scatter_labels(sc), 4);
    affect_plot_options o;
    affect_plot_options_default(&o);
    o.title = "Weight vs Time";
    o.x_label = "WeightAll";
    o.y_label = "TimeAll";
    char *svg = render(sc, &o);
    /* series in strcmp order, palette colours in that order, counts */
    const char *s0 = strstr(svg, "<g class=\"series\" data-label=\"(none)\" data-count=\"1\" "
                                 "fill=\"#0072B2\">");
    const char *s1 = strstr(svg, "<g class=\"series\" data-label=\"angry\" data-count=\"2\" "
                                 "fill=\"#E69F00\">");
    const char *s2 = strstr(svg, "<g class=\"series\" data-label=\"happy\" data-count=\"1\" "
                                 "fill=\"#009E73\">");
    const char *s3 = strstr(svg, "<g class=\"series\" data-label=\"sad\" data-count=\"3\" "
                                 "fill=\"#D55E00\">");
    assert_true(s0 && s1 && s2 && s3 && s0 < s1 && s1 < s2 && s2 < s3);
    assert_int_equal(tu_count(svg, "class=\"series\""), 4);
    assert_int_equal(tu_count(svg, "<circle"), 7 + 4); /* points + legend markers */
    /* sad's three circles are inside its group */
    const char *end3 = strstr(s3, "</g>");
    size_t in3 = 0;
    for (const char *c = strstr(s3, "<circle"); c && c < end3; c = strstr(c + 1, "<circle"))
        in3++;
    assert_int_equal(in3, 3);
    /* legend rows: label and count, sorted */
    assert_int_equal(tu_count(svg, "class=\"legend-item\""), 4);
    const char *l0 = strstr(svg, ">(none) <tspan fill=\"#777\">(1)</tspan>");
    const char *l1 = strstr(svg, ">angry <tspan fill=\"#777\">(2)</tspan>");
    const char *l2 = strstr(svg, ">happy <tspan fill=\"#777\">(1)</tspan>");
    const char *l3 = strstr(svg, ">sad <tspan fill=\"#777\">(3)</tspan>");
    assert_true(l0 && l1 && l2 && l3 && l0 < l1 && l1 < l2 && l2 < l3);
    /* titles */
    char buf[256];
    assert_true(class_text(svg, "title", 0, buf, sizeof buf));
    assert_string_equal(buf, "Weight vs Time");
    assert_true(class_text(svg, "axis-title", 0, buf, sizeof buf));
    assert_string_equal(buf, "WeightAll");
    assert_true(class_text(svg, "axis-title", 1, buf, sizeof buf));
    assert_string_equal(buf, "TimeAll");
    assert_non_null(strstr(svg, "rotate(-90)"));
    /* legend right of the frame, points inside it */
    double l, t, r, b;
    frame_of(svg, &l, &t, &r, &b);
    const char *leg = strstr(svg, "<g class=\"legend\"");
    for (const char *c = strstr(leg, "<circle"); c; c = strstr(c + 1, "<circle"))
        assert_true(attr(c, "cx") - 3.5 > r);
    assert_points_in_frame(svg);
    /* x grows right, y grows up: the point (7, 1) is right of and below (4, 5) */
    const char *p71 = strstr(s1, "<circle");
    p71 = strstr(p71 + 1, "<circle");
    const char *p45 = strstr(s0, "<circle");
    assert_true(attr(p71, "cx") > attr(p45, "cx"));
    assert_true(attr(p71, "cy") > attr(p45, "cy"));
    affect_free(svg);
    affect_scatter_free(sc);
}

static void test_linear_ticks(void **state)
{
    static const double ranges[][2] = {
        {0, 10},    {-3, 7},          {-250, -3},     {1e-9, 3e-9}, {1e12, 5e12},
        {0.1, 0.3}, {123456, 123789}, {-1e-5, 2e-5},  {0, 1},       {-0.001, 0.001},
        {3.7, 3.9}, {1e9, 1e9 + 1},   {-7e20, -6e20}, {2, 1000},    {0.5, 0.51}};
    for (size_t i = 0; i < sizeof ranges / sizeof ranges[0]; i++) {
        affect_scatter *sc = new_scatter();
        add(sc, ranges[i][0], ranges[i][1], "a");
        add(sc, ranges[i][1], ranges[i][0], "a");
        add(sc, (ranges[i][0] + ranges[i][1]) / 2, ranges[i][1], "b");
        char *svg = render(sc, NULL);
        check_linear_axis(svg, "x", ranges[i][0], ranges[i][1]);
        check_linear_axis(svg, "y", ranges[i][0], ranges[i][1]);
        affect_free(svg);
        affect_scatter_free(sc);
    }
}

/* Tick labels of the x axis joined with spaces. */
static void x_labels(const affect_scatter *sc, const affect_plot_options *o, char *out, size_t size)
{
    char *svg = render(sc, o);
    ticks t;
    get_ticks(svg, "x", &t);
    out[0] = '\0';
    for (size_t i = 0; i < t.n; i++) {
        if (i)
            strncat(out, " ", size - strlen(out) - 1);
        strncat(out, t.text[i], size - strlen(out) - 1);
    }
    affect_free(svg);
}

static void expect_x_labels(double lo, double hi, bool log, const char *expect)
{
    affect_scatter *sc = new_scatter();
    add(sc, lo, 1, "a");
    add(sc, hi, 2, "a");
    affect_plot_options o;
    affect_plot_options_default(&o);
    o.log_x = log;
    char got[1024];
    x_labels(sc, &o, got, sizeof got);
    if (strcmp(got, expect) != 0)
        fail_msg("x in [%g, %g]%s: ticks \"%s\", expected \"%s\"", lo, hi, log ? " (log)" : "", got,
                 expect);
    affect_scatter_free(sc);
}

static void test_tick_labels_exact(void **state)
{
    /* padded by 5 %: [−0.5, 10.5] → step 2 */
    expect_x_labels(0, 10, false, "0 2 4 6 8 10");
    expect_x_labels(-250, -3, false,
                    "\xe2\x88\x92"
                    "250 \xe2\x88\x92"
                    "200 \xe2\x88\x92"
                    "150 \xe2\x88\x92"
                    "100 \xe2\x88\x92"
                    "50 0");
    expect_x_labels(0.1, 0.3, false, "0.1 0.15 0.2 0.25 0.3");
    /* long fixed labels switch to scientific notation */
    expect_x_labels(1e-9, 3e-9, false,
                    "10\xe2\x81\xbb\xe2\x81\xb9 1.5\xc3\x97"
                    "10\xe2\x81\xbb\xe2\x81\xb9 "
                    "2\xc3\x97"
                    "10\xe2\x81\xbb\xe2\x81\xb9 2.5\xc3\x97"
                    "10\xe2\x81\xbb\xe2\x81\xb9 "
                    "3\xc3\x97"
                    "10\xe2\x81\xbb\xe2\x81\xb9");
    expect_x_labels(1e12, 5e12, false,
                    "10\xc2\xb9\xc2\xb2 2\xc3\x97"
                    "10\xc2\xb9\xc2\xb2 3\xc3\x97"
                    "10\xc2\xb9\xc2\xb2 "
                    "4\xc3\x97"
                    "10\xc2\xb9\xc2\xb2 5\xc3\x97"
                    "10\xc2\xb9\xc2\xb2");
    /* equal min and max: value ± 5 %, or ± 1 at zero */
    expect_x_labels(5, 5, false, "4.8 4.9 5 5.1 5.2");
    expect_x_labels(0, 0, false,
                    "\xe2\x88\x92"
                    "1 \xe2\x88\x92"
                    "0.5 0 0.5 1");
    /* log axes: decades, 1-2-5, linear values for a narrow range */
    expect_x_labels(0.01, 1000, true, "0.01 0.1 1 10 100 1000");
    expect_x_labels(0.3, 8, true, "0.5 1 2 5");
    expect_x_labels(3, 8, true, "3 4 5 6 7 8");
    /* 600 decades: every 200th labelled, so that the labels do not collide */
    expect_x_labels(1e-300, 1e300, true,
                    "10\xe2\x81\xbb\xc2\xb2\xe2\x81\xb0\xe2\x81\xb0 1 "
                    "10\xc2\xb2\xe2\x81\xb0\xe2\x81\xb0");
}

static void test_extreme_ranges(void **state)
{
    static const double pairs[][2] = {
        {-DBL_MAX, DBL_MAX}, {DBL_MAX, DBL_MAX}, {-DBL_MAX, -DBL_MAX},   {5e-324, 1e-320},
        {0, 1e-300},         {1e300, DBL_MAX},   {1.2345e-7, 1.2346e-7}, {1e15, 1e15 + 2}};
    for (int log = 0; log < 2; log++)
        for (size_t i = 0; i < sizeof pairs / sizeof pairs[0]; i++) {
            affect_scatter *sc = new_scatter();
            add(sc, pairs[i][0], pairs[i][1], "a");
            add(sc, pairs[i][1], pairs[i][0], "b");
            affect_plot_options o;
            affect_plot_options_default(&o);
            o.log_x = o.log_y = log;
            o.means = true;
            char *svg = render(sc, &o);
            ticks t;
            get_ticks(svg, "x", &t);
            assert_true(t.n >= 1);
            for (size_t k = 1; k < t.n; k++)
                assert_true(t.v[k] > t.v[k - 1]);
            get_ticks(svg, "y", &t);
            assert_true(t.n >= 1);
            if (pairs[i][0] > 0 || !log)
                assert_points_in_frame(svg);
            affect_free(svg);
            affect_scatter_free(sc);
        }
}

static void test_log_axes(void **state)
{
    affect_scatter *sc = new_scatter();
    add(sc, 2000, 165, "sad");
    add(sc, 1.8e6, 21000, "angry");
    add(sc, 50000, 2000, "happy");
    add(sc, 0, 100, "happy"); /* x ≤ 0: skipped on a log x axis */
    add(sc, 100, -5, "sad");  /* y ≤ 0 */
    add(sc, NAN, 1, "sad");   /* not finite */
    affect_plot_options o;
    affect_plot_options_default(&o);
    o.log_x = o.log_y = true;
    char *svg = render(sc, &o);
    /* x: decades 10⁴, 10⁵, 10⁶ with minor ticks; y: 1-2-5 */
    ticks t;
    get_ticks(svg, "x", &t);
    assert_int_equal(t.n, 3);
    assert_string_equal(t.text[0], "10\xe2\x81\xb4");
    assert_string_equal(t.text[2], "10\xe2\x81\xb6");
    assert_true(t.v[0] == 1e4 && t.v[1] == 1e5 && t.v[2] == 1e6);
    /* equal pixel spacing per decade */
    tu_assert_near(t.px[1] - t.px[0], t.px[2] - t.px[1], 0.11);
    assert_non_null(strstr(svg, "class=\"grid-minor\""));
    get_ticks(svg, "y", &t);
    assert_true(t.n >= 5);
    for (size_t i = 1; i < t.n; i++) {
        /* log placement: pixels proportional to log10 differences */
        double r0 = (t.px[1] - t.px[0]) / log10(t.v[1] / t.v[0]);
        tu_assert_near((t.px[i] - t.px[0]) / log10(t.v[i] / t.v[0]), r0, 0.2);
    }
    /* the point at (50000, 2000) is drawn where the ticks say */
    const char *happy = strstr(svg, "data-label=\"happy\" data-count=\"1\"");
    assert_non_null(happy);
    ticks tx;
    get_ticks(svg, "x", &tx);
    double px_per_decade = tx.px[1] - tx.px[0];
    tu_assert_near(attr(happy, "cx"), tx.px[0] + log10(5.0) * px_per_decade, 0.11);
    /* skipped points: two ≤ 0, one not finite */
    char buf[256];
    assert_true(class_text(svg, "note", 0, buf, sizeof buf));
    assert_string_equal(buf, "skipped 3 of 6 points: 1 not finite, 2 \xe2\x89\xa4 0 on a log axis");
    assert_non_null(strstr(svg, ">sad <tspan fill=\"#777\">(1)</tspan>"));
    affect_free(svg);
    /* the same points on linear axes: only the non-finite one is skipped */
    o.log_x = o.log_y = false;
    svg = render(sc, &o);
    assert_true(class_text(svg, "note", 0, buf, sizeof buf));
    assert_string_equal(buf, "skipped 1 of 6 points: 1 not finite");
    assert_null(strstr(svg, "grid-minor"));
    assert_non_null(strstr(svg, ">sad <tspan fill=\"#777\">(2)</tspan>"));
    affect_free(svg);
    /* only the log x axis: the x ≤ 0 point is skipped, the y ≤ 0 one is not */
    o.log_x = true;
    svg = render(sc, &o);
    assert_true(class_text(svg, "note", 0, buf, sizeof buf));
    assert_string_equal(buf, "skipped 2 of 6 points: 1 not finite, 1 \xe2\x89\xa4 0 on a log axis");
    affect_free(svg);
    affect_scatter_free(sc);
}

static void test_no_data(void **state)
{
    static const bool logs[] = {false, true};
    for (int i = 0; i < 2; i++) {
        affect_scatter *sc = new_scatter();
        affect_plot_options o;
        affect_plot_options_default(&o);
        o.log_x = o.log_y = logs[i];
        o.means = true;
        o.title = "nothing";
        char *svg = render(sc, &o);
        char buf[64];
        assert_true(class_text(svg, "no-data", 0, buf, sizeof buf));
        assert_string_equal(buf, "no data");
        assert_null(strstr(svg, "class=\"note\""));
        assert_int_equal(tu_count(svg, "class=\"series\""), 0);
        assert_int_equal(tu_count(svg, "<circle"), 0);
        ticks t;
        get_ticks(svg, "x", &t);
        assert_true(t.n >= 3);
        assert_true(t.v[0] == (logs[i] ? 1 : 0) && t.v[t.n - 1] == (logs[i] ? 10 : 1));
        get_ticks(svg, "y", &t);
        assert_true(t.n >= 3);
        affect_free(svg);
        affect_scatter_free(sc);
    }
    /* every point skipped: no data, a note, and the labels in the legend with count 0 */
    affect_scatter *sc = new_scatter();
    add(sc, INFINITY, 1, "a");
    add(sc, 1, NAN, "b");
    add(sc, -INFINITY, -INFINITY, "a");
    assert_int_equal(affect_scatter_count(sc), 3);
    assert_int_equal(affect_scatter_labels(sc), 2);
    char *svg = render(sc, NULL);
    char buf[128];
    assert_true(class_text(svg, "no-data", 0, buf, sizeof buf));
    assert_true(class_text(svg, "note", 0, buf, sizeof buf));
    assert_string_equal(buf, "skipped 3 of 3 points: 3 not finite");
    assert_non_null(strstr(svg, ">a <tspan fill=\"#777\">(0)</tspan>"));
    assert_non_null(strstr(svg, ">b <tspan fill=\"#777\">(0)</tspan>"));
    affect_free(svg);
    affect_scatter_free(sc);
}

static void test_means(void **state)
{
    affect_scatter *sc = new_scatter();
    add(sc, 5, 9, "A");
    add(sc, 1, 2, "A");
    add(sc, 3, 4, "A");
    add(sc, 10, 100, "B");
    add(sc, 7, 7, "C");
    add(sc, 1000, 1, "B");
    affect_plot_options o;
    affect_plot_options_default(&o);
    char *svg = render(sc, &o);
    assert_null(strstr(svg, "class=\"mean\""));
    affect_free(svg);
    o.means = true;
    svg = render(sc, &o);
    /* A: mean (3, 5), sample sd (2, √13) */
    const char *a =
        strstr(svg, "<g class=\"mean\" data-label=\"A\" data-n=\"3\" data-mean-x=\"3\" "
                    "data-mean-y=\"5\" data-sd-x=\"2\" data-sd-y=\"3.605551275463989\">");
    assert_non_null(a);
    /* C has one point: no bars, a marker */
    const char *c = strstr(svg, "<g class=\"mean\" data-label=\"C\" data-n=\"1\" data-mean-x=\"7\" "
                                "data-mean-y=\"7\" data-sd-x=\"0\" data-sd-y=\"0\"></g>");
    assert_non_null(c);
    /* the three mean markers come after every cross */
    const char *mk = strstr(svg, "<g class=\"mean-markers\"");
    assert_true(mk && mk > c);
    size_t in_mk = 0;
    for (const char *q = strstr(mk, "<circle"); q && q < strchr(mk, '\n');
         q = strstr(q + 1, "<circle"))
        in_mk++;
    assert_int_equal(in_mk, 3);
    assert_non_null(strstr(mk, "<g fill=\"#009E73\"><circle"));
    assert_int_equal(tu_count(svg, "<path stroke=\"#fff\" stroke-width=\"4.5\""), 2); /* A and B */
    /* A's horizontal bar spans mean ± sd: from x = 1 to x = 5, i.e. A's extreme points */
    const char *pa = strstr(svg, "data-label=\"A\" data-count=\"3\"");
    double x1 = attr(strstr(pa, "<circle"), "cx"); /* (1, 2), first in x order */
    const char *bar = strstr(a, "stroke-width=\"2\" d=\"M");
    assert_non_null(bar);
    const char *d = strstr(bar, "d=\"M") + 4;
    double v = 0;
    affect_parse_double(d, d + 16, &v);
    tu_assert_near(v, x1, 0.051);
    assert_non_null(strstr(svg, "mean \xc2\xb1 1 sd</text>"));
    affect_free(svg);
    /* log axes: geometric means, sd of log10 values: B has x {10, 1000} → mean 2, sd √2 */
    o.log_x = o.log_y = true;
    svg = render(sc, &o);
    assert_non_null(strstr(svg, "<g class=\"mean\" data-label=\"B\" data-n=\"2\" data-mean-x=\"2\" "
                                "data-mean-y=\"1\" data-sd-x=\"1.4142135623730951\" "
                                "data-sd-y=\"1.4142135623730951\">"));
    affect_free(svg);
    affect_scatter_free(sc);
}

static void test_means_widen_axes(void **state)
{
    /* {0, 0, 0, 0, 10}: mean 2, sd √20 ≈ 4.47, so the bar reaches −2.47 < min 0 */
    affect_scatter *sc = new_scatter();
    for (int i = 0; i < 4; i++)
        add(sc, 0, 0, "a");
    add(sc, 10, 10, "a");
    affect_plot_options o;
    affect_plot_options_default(&o);
    o.means = true;
    char *svg = render(sc, &o);
    ticks t;
    get_ticks(svg, "x", &t);
    double l, top, r, b;
    frame_of(svg, &l, &top, &r, &b);
    double px_per_unit = (t.px[t.n - 1] - t.px[0]) / (t.v[t.n - 1] - t.v[0]);
    double px0 = t.px[0] - t.v[0] * px_per_unit; /* pixel of x = 0 */
    assert_true(px0 - l > 2.47 * px_per_unit);   /* the axis reaches below −2.47 */
    const char *bar = strstr(strstr(svg, "class=\"mean\""), "stroke-width=\"2\"");
    const char *d = strstr(bar, "d=\"M") + 4;
    double v = 0;
    affect_parse_double(d, d + 16, &v);
    assert_true(v > l);
    tu_assert_near(v, px0 - (sqrt(20) - 2) * px_per_unit, 0.2); /* mean − sd */
    affect_free(svg);
    affect_scatter_free(sc);
}

static void test_text(void **state)
{
    affect_scatter *sc = new_scatter();
    add(sc, 1, 1, "<b>&\"quoted\"'");
    add(sc, 2, 2, "bad \xff utf8 \xc3");
    add(sc, 3, 3, "tab\there\x01");
    add(sc, 4, 4, "an extraordinarily long emotion label indeed");
    add(sc, 5, 5, "\xe6\x80\x92\xe3\x82\x8a"); /* 怒り */
    affect_plot_options o;
    affect_plot_options_default(&o);
    o.width = 800; /* room for a 24-character legend label */
    o.title = "A & B <c>";
    o.x_label = "x \xe2\x80\x94 \"weight\"";
    char *svg = render(sc, &o);
    assert_non_null(strstr(svg, ">A &amp; B &lt;c&gt;</text>"));
    assert_non_null(strstr(svg, ">x \xe2\x80\x94 &quot;weight&quot;</text>"));
    assert_non_null(strstr(svg, "data-label=\"&lt;b&gt;&amp;&quot;quoted&quot;&#39;\""));
    assert_non_null(strstr(svg, "data-label=\"bad \xef\xbf\xbd utf8 \xef\xbf\xbd\""));
    assert_non_null(strstr(svg, "data-label=\"tab?here?\""));
    assert_non_null(strstr(svg, "data-label=\"\xe6\x80\x92\xe3\x82\x8a\""));
    /* the legend cuts long labels at 24 characters (23 and "…"); data-label keeps it all */
    assert_non_null(strstr(svg, ">an extraordinarily long\xe2\x80\xa6 <tspan"));
    assert_non_null(strstr(svg, "data-label=\"an extraordinarily long emotion label indeed\""));
    affect_free(svg);
    /* an empty title is no title */
    o.title = "";
    svg = render(sc, &o);
    assert_null(strstr(svg, "class=\"title\""));
    affect_free(svg);
    affect_scatter_free(sc);
}

static void test_many_labels(void **state)
{
    affect_scatter *sc = new_scatter();
    char name[16];
    for (int i = 0; i < 40; i++) {
        snprintf(name, sizeof name, "L%02d", i);
        add(sc, i, i % 7, name);
        add(sc, i + 0.5, i % 5, name);
    }
    assert_int_equal(affect_scatter_labels(sc), 40);
    char *svg = render(sc, NULL);
    /* colour i mod 8, shape (i / 8) mod 4: circle, square, triangle, diamond */
    const char *l00 = strstr(svg, "data-label=\"L00\" data-count=\"2\" fill=\"#0072B2\"><circle");
    const char *l07 = strstr(svg, "data-label=\"L07\" data-count=\"2\" fill=\"#000000\"><circle");
    const char *l08 = strstr(svg, "data-label=\"L08\" data-count=\"2\" fill=\"#0072B2\"><rect");
    const char *l17 = strstr(svg, "data-label=\"L17\" data-count=\"2\" fill=\"#E69F00\"><path");
    const char *l25 = strstr(svg, "data-label=\"L25\" data-count=\"2\" fill=\"#E69F00\"><path");
    const char *l33 = strstr(svg, "data-label=\"L33\" data-count=\"2\" fill=\"#E69F00\"><circle");
    assert_true(l00 && l07 && l08 && l17 && l25 && l33);
    /* triangle (3 vertices) vs diamond (4) */
    const char *p17 = strstr(l17, "<path"), *e17 = strstr(p17, "/>");
    size_t ls = 0;
    for (const char *p = p17; p < e17; p++)
        ls += *p == 'L';
    assert_int_equal(ls, 2);
    const char *p25 = strstr(l25, "<path"), *e25 = strstr(p25, "/>");
    ls = 0;
    for (const char *p = p25; p < e25; p++)
        ls += *p == 'L';
    assert_int_equal(ls, 3);
    /* 40 rows do not fit 420 px: some rows and "+ N more" */
    size_t rows = tu_count(svg, "class=\"legend-item\"");
    assert_true(rows >= 10 && rows < 40);
    char buf[64], want[64];
    assert_true(class_text(svg, "legend-more", 0, buf, sizeof buf));
    snprintf(want, sizeof want, "+ %zu more", 40 - rows);
    assert_string_equal(buf, want);
    affect_free(svg);
    affect_scatter_free(sc);
}

static void test_size_and_radius(void **state)
{
    affect_scatter *sc = new_scatter();
    add(sc, 1, 2, "a");
    add(sc, 2, 1, "b");
    affect_plot_options o;
    affect_plot_options_default(&o);
    o.width = 800;
    o.height = 300;
    o.radius = 5.5;
    char *svg = render(sc, &o);
    assert_non_null(strstr(svg, "width=\"800\" height=\"300\" viewBox=\"0 0 800 300\""));
    const char *pts = strstr(svg, "<g class=\"points\""), *leg = strstr(svg, "<g class=\"legend\"");
    assert_int_equal(tu_count(pts, " r=\"5.5\"") - tu_count(leg, " r=\"5.5\""), 2);
    double l, t, r, b;
    frame_of(svg, &l, &t, &r, &b);
    assert_true(r < 800 && b < 300 && l > 0 && t > 0);
    affect_free(svg);
    /* the smallest size still lays out a frame of positive size */
    o.width = 100;
    o.height = 100;
    o.title = "t";
    o.x_label = "x";
    o.y_label = "y";
    svg = render(sc, &o);
    frame_of(svg, &l, &t, &r, &b);
    assert_true(r - l > 10 && b - t > 10);
    affect_free(svg);
    affect_scatter_free(sc);
}

static void expect_option_error(affect_plot_options *o, const char *msg)
{
    affect_error err;
    assert_int_equal(affect_plot_options_check(o, &err), AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, msg);
    affect_scatter *sc = new_scatter();
    add(sc, 1, 1, "a");
    char *svg = (char *)1;
    size_t len = 7;
    assert_int_equal(affect_scatter_render(sc, o, &svg, &len, &err), AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, msg);
    assert_null(svg);
    assert_int_equal(len, 0);
    affect_scatter_free(sc);
    affect_plot_options_default(o);
}

static void test_option_errors(void **state)
{
    affect_plot_options o;
    affect_plot_options_default(&o);
    affect_error err;
    assert_int_equal(affect_plot_options_check(&o, &err), AFFECT_OK);
    o.width = 50;
    expect_option_error(&o, "width must be between 100 and 4000, got 50");
    o.width = 4001;
    expect_option_error(&o, "width must be between 100 and 4000, got 4001");
    o.width = 560.5;
    expect_option_error(&o, "width must be a whole number, got 560.5");
    o.width = NAN;
    expect_option_error(&o, "width must be between 100 and 4000, got nan");
    o.height = 99;
    expect_option_error(&o, "height must be between 100 and 4000, got 99");
    o.height = 1e9;
    expect_option_error(&o, "height must be between 100 and 4000, got 1e+09");
    o.height = 300.25;
    expect_option_error(&o, "height must be a whole number, got 300.25");
    o.radius = 0;
    expect_option_error(&o, "radius must be between 0.5 and 20, got 0");
    o.radius = 20.5;
    expect_option_error(&o, "radius must be between 0.5 and 20, got 20.5");
    o.radius = -INFINITY;
    expect_option_error(&o, "radius must be between 0.5 and 20, got -inf");
    /* the limits themselves are accepted */
    o.width = 100;
    o.height = 4000;
    o.radius = 0.5;
    assert_int_equal(affect_plot_options_check(&o, &err), AFFECT_OK);
    o.radius = 20;
    assert_int_equal(affect_plot_options_check(&o, &err), AFFECT_OK);
}

static void test_deterministic_and_order_free(void **state)
{
    /* the same multiset of points in two orders gives the same bytes */
    affect_scatter *a = new_scatter(), *b = new_scatter();
    enum { N = 300 };
    double xs[N], ys[N];
    const char *labels[] = {"angry", "happy", "sad", "normal", NULL};
    uint64_t seed = 12345;
    for (int i = 0; i < N; i++) {
        seed = seed * 6364136223846793005u + 1442695040888963407u;
        xs[i] = (double)(seed >> 11) * 0x1.0p-53 * 1000 + 1;
        seed = seed * 6364136223846793005u + 1442695040888963407u;
        ys[i] = (double)(seed >> 11) * 0x1.0p-53 * 50 + 0.1;
    }
    for (int i = 0; i < N; i++)
        add(a, xs[i], ys[i], labels[i % 5]);
    for (int i = N - 1; i >= 0; i--)
        add(b, xs[i], ys[i], labels[i % 5]);
    affect_plot_options o;
    affect_plot_options_default(&o);
    o.means = true;
    o.title = "order";
    for (int log = 0; log < 2; log++) {
        o.log_x = o.log_y = log;
        char *sa = render(a, &o), *sa2 = render(a, &o), *sb = render(b, &o);
        assert_string_equal(sa, sa2);
        assert_string_equal(sa, sb);
        assert_int_equal(tu_count(sa, "<circle"), N + 5 + 5);
        affect_free(sa);
        affect_free(sa2);
        affect_free(sb);
    }
    affect_scatter_free(a);
    affect_scatter_free(b);
}

/* ---- out of memory ---- */

typedef struct plot_oom {
    const affect_plot_options *opt;
    char *svg;
} plot_oom;

/* Builds a scatter (enough points and labels to grow every array) and renders it. */
static affect_status oom_build_render(void *ctx, affect_error *err)
{
    plot_oom *c = ctx;
    affect_scatter *sc = NULL;
    affect_status st;
    char name[16];
    c->svg = NULL;
    if ((st = affect_scatter_create(&sc, err)) != AFFECT_OK)
        return st;
    for (int i = 0; i < 300; i++) {
        snprintf(name, sizeof name, "label %d", i % 20);
        double x = i % 17 == 0 ? NAN : 1 + i * 3.5, y = 0.5 + (i * 7 % 13);
        if ((st = affect_scatter_add(sc, x, y, i % 23 == 0 ? NULL : name, err)) != AFFECT_OK)
            goto done;
    }
    st = affect_scatter_render(sc, c->opt, &c->svg, NULL, err);
done:
    affect_scatter_free(sc);
    return st;
}

static void oom_finish(void *ctx, affect_status st)
{
    plot_oom *c = ctx;
    if (st != AFFECT_OK)
        assert_null(c->svg);
    affect_free(c->svg);
    c->svg = NULL;
}

static void test_out_of_memory(void **state)
{
    affect_plot_options o;
    affect_plot_options_default(&o);
    o.title = "oom";
    o.x_label = "x";
    o.y_label = "y";
    o.means = true;
    o.log_x = true;
    plot_oom c = {&o, NULL};
    assert_true(tu_oom_sweep(oom_build_render, &c, oom_finish, NULL) >= 10);
}

/* 128 points with 16 labels: the point array, the name array and half the hash table are
 * full, so a point with a new label grows all three and then copies the label. */
static affect_scatter *full_scatter(void)
{
    affect_scatter *sc = new_scatter();
    char name[16];
    for (int i = 0; i < 128; i++) {
        snprintf(name, sizeof name, "l%d", i % 16);
        add(sc, i, i % 9, name);
    }
    return sc;
}

/* A failed add leaves the accumulator as it was, whichever of its allocations fails. */
static void test_failed_add_changes_nothing(void **state)
{
    affect_scatter *ref = full_scatter();
    char *before = render(ref, NULL);
    affect_scatter_free(ref);
    affect_error err;
    long k = 1;
    for (;; k++) {
        affect_scatter *sc = full_scatter();
        tu_oom_install(k);
        affect_status st = affect_scatter_add(sc, 2.5, 2.5, "new label", &err);
        long calls = tu_oom_calls();
        tu_oom_remove();
        if (calls < k) {
            assert_int_equal(st, AFFECT_OK);
            assert_int_equal(affect_scatter_count(sc), 129);
            assert_int_equal(affect_scatter_labels(sc), 17);
            char *svg = render(sc, NULL);
            assert_non_null(strstr(svg, "data-label=\"new label\" data-count=\"1\""));
            affect_free(svg);
            affect_scatter_free(sc);
            break;
        }
        assert_int_equal(st, AFFECT_ERR_NOMEM);
        assert_string_equal(err.msg, "out of memory");
        assert_int_equal(affect_scatter_count(sc), 128);
        assert_int_equal(affect_scatter_labels(sc), 16);
        char *now = render(sc, NULL);
        assert_string_equal(now, before);
        affect_free(now);
        /* and it keeps working */
        add(sc, 3.5, 3.5, "l1");
        assert_int_equal(affect_scatter_count(sc), 129);
        affect_scatter_free(sc);
    }
    assert_int_equal(k, 5); /* points, names, hash table, label copy */
    affect_free(before);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_defaults),
        cmocka_unit_test(test_structure_and_legend),
        cmocka_unit_test(test_linear_ticks),
        cmocka_unit_test(test_tick_labels_exact),
        cmocka_unit_test(test_extreme_ranges),
        cmocka_unit_test(test_log_axes),
        cmocka_unit_test(test_no_data),
        cmocka_unit_test(test_means),
        cmocka_unit_test(test_means_widen_axes),
        cmocka_unit_test(test_text),
        cmocka_unit_test(test_many_labels),
        cmocka_unit_test(test_size_and_radius),
        cmocka_unit_test(test_option_errors),
        cmocka_unit_test(test_deterministic_and_order_free),
        cmocka_unit_test(test_out_of_memory),
        cmocka_unit_test(test_failed_add_changes_nothing),
        cmocka_unit_test(test_series_mode),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
