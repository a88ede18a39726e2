/*
 * test_heatmap.c — heat maps: well-formed standalone documents, one cell per (row, column) in
 * first-appearance or sorted order, a repeated cell keeping its largest value, missing and
 * non-finite values, the colour scale's ends, labels escaped and cut, values printed or not,
 * exact option errors, the label limit, determinism, and out-of-memory at every allocation.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"
#include "affect/heatmap.h"

__attribute__((noinline)) static char *render(const affect_heatmap *hm,
                                              const affect_heatmap_options *opt)
{
    char *svg = NULL;
    size_t len = 0;
    affect_error err;
    if (affect_heatmap_render(hm, opt, &svg, &len, &err) != AFFECT_OK)
        fail_msg("affect_heatmap_render: %s", err.msg);
    tu_assert_svg_well_formed(svg, len);
    return svg;
}

static affect_heatmap *make(void)
{
    affect_heatmap *hm = NULL;
    assert_int_equal(affect_heatmap_create(&hm, NULL), AFFECT_OK);
    return hm;
}

static void add(affect_heatmap *hm, const char *r, const char *c, double v)
{
    affect_error err;
    if (affect_heatmap_add(hm, r, c, v, &err) != AFFECT_OK)
        fail_msg("affect_heatmap_add: %s", err.msg);
}

/* The fill of the cell at (row, column) as drawn. */
static void fill_of(const char *svg, int row, int col, char out[8])
{
    char key[80];
    snprintf(key, sizeof key, "data-row=\"%d\" data-column=\"%d\"", row, col);
    const char *p = strstr(svg, key);
    assert_non_null(p);
    p = strstr(p, "fill=\"");
    assert_non_null(p);
    memcpy(out, p + 6, 7);
    out[7] = '\0';
}

static void test_cells_and_labels(void **state)
{
    affect_heatmap *hm = make();
    add(hm, "sad · state 2", "Head", 0.5);
    add(hm, "sad · state 1", "Hand_L", 1.0);
    add(hm, "sad · state 1", "Head", 0.0);
    add(hm, "sad · state 1", "Head", 0.25); /* a repeated cell keeps the larger value */
    add(hm, "sad · state 2", "Foot <R>", NAN);
    assert_int_equal(affect_heatmap_rows(hm), 2);
    assert_int_equal(affect_heatmap_columns(hm), 3);
    affect_heatmap_options opt;
    affect_heatmap_options_default(&opt);
    opt.cell = 30;
    opt.title = "Salience";
    char *svg = render(hm, &opt);
    /* labels written (not only in tooltips), in first-appearance order, escaped */
    assert_int_equal(tu_count(svg, "<text class=\"row-label\""), 2);
    assert_int_equal(tu_count(svg, "<text class=\"column-label\""), 3);
    const char *r2 = strstr(svg, ">sad · state 2</text>"),
               *r1 = strstr(svg, ">sad · state 1</text>");
    assert_non_null(r1);
    assert_non_null(r2);
    assert_true(r2 < r1);
    assert_non_null(strstr(svg, "rotate(-45)\">Foot &lt;R&gt;</text>"));
    assert_int_equal(tu_count(svg, "<rect class=\"cell\""), 6);
    /* colours: the ends of the ramp at the range's ends, grey without a value */
    char f[8];
    fill_of(svg, 1, 1, f); /* state 1 × Hand_L = 1.0, the maximum */
    assert_string_equal(f, "#08306b");
    fill_of(svg, 0, 0, f); /* state 2 × Head = 0.5 */
    assert_string_equal(f, "#6baed6");
    fill_of(svg, 1, 0, f); /* state 1 × Head = 0.25 (the larger of 0 and 0.25) */
    assert_string_equal(f, "#c6dbef");
    fill_of(svg, 0, 2, f); /* NaN: no value */
    assert_string_equal(f, "#ececec");
    fill_of(svg, 0, 1, f); /* never given */
    assert_string_equal(f, "#ececec");
    /* values in the cells (30 px), the tooltips, the non-finite note, the bar's ends */
    assert_non_null(strstr(svg, "<title>sad · state 1 \xc3\x97 Head: 0.25</title>"));
    assert_int_equal(tu_count(svg, "<text class=\"value\""), 3);
    assert_non_null(strstr(svg, ">1 value not finite</text>"));
    assert_non_null(strstr(svg, "class=\"bar-max\""));
    affect_free(svg);
    /* sorted rows and columns; no values at 24 px unless asked */
    opt.cell = 24;
    opt.sort_rows = opt.sort_columns = true;
    svg = render(hm, &opt);
    r2 = strstr(svg, ">sad · state 2</text>");
    r1 = strstr(svg, ">sad · state 1</text>");
    assert_true(r1 < r2);
    assert_true(strstr(svg, ">Foot &lt;R&gt;</text>") < strstr(svg, ">Hand_L</text>"));
    fill_of(svg, 0, 1, f); /* state 1 × Hand_L */
    assert_string_equal(f, "#08306b");
    assert_int_equal(tu_count(svg, "<text class=\"value\""), 0);
    affect_free(svg);
    opt.values = 1;
    opt.has_min = opt.has_max = true;
    opt.min = 0;
    opt.max = 2;
    svg = render(hm, &opt);
    assert_int_equal(tu_count(svg, "<text class=\"value\""), 3);
    fill_of(svg, 0, 1, f); /* 1.0 is now the middle of [0, 2] */
    assert_string_equal(f, "#6baed6");
    /* deterministic */
    char *again = render(hm, &opt);
    assert_string_equal(svg, again);
    affect_free(again);
    affect_free(svg);
    affect_heatmap_free(hm);
}

static void test_empty_and_odd_labels(void **state)
{
    affect_heatmap *hm = make();
    char *svg = render(hm, NULL);
    assert_non_null(strstr(svg, ">no data</text>"));
    affect_free(svg);
    /* invalid UTF-8 is drawn as U+FFFD; long labels are cut with an ellipsis */
    add(hm, "bad \xff byte", "a very long column label that goes on and on and on and on", 1);
    add(hm, "x", "y", 1); /* all values equal: the middle colour */
    svg = render(hm, NULL);
    assert_non_null(strstr(svg, "bad \xef\xbf\xbd byte"));
    assert_non_null(strstr(svg, "\xe2\x80\xa6</text>"));
    affect_free(svg);
    affect_heatmap_free(hm);
}

static void test_errors(void **state)
{
    affect_heatmap_options opt;
    affect_error err;
    affect_heatmap_options_default(&opt);
    opt.cell = 4;
    assert_int_equal(affect_heatmap_options_check(&opt, &err), AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "cell must be between 8 and 120, got 4");
    opt.cell = 20.5;
    assert_int_equal(affect_heatmap_options_check(&opt, &err), AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "cell must be a whole number, got 20.5");
    affect_heatmap_options_default(&opt);
    opt.has_min = opt.has_max = true;
    opt.min = opt.max = 1;
    assert_int_equal(affect_heatmap_options_check(&opt, &err), AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "min must be below max, got 1 and 1");
    opt.max = INFINITY;
    assert_int_equal(affect_heatmap_options_check(&opt, &err), AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "min and max must be finite");
    /* render checks the options first */
    affect_heatmap *hm = make();
    char *out = NULL;
    assert_int_equal(affect_heatmap_render(hm, &opt, &out, NULL, &err), AFFECT_ERR_INVALID);
    assert_null(out);
    /* the label limit: the map stays unchanged */
    char name[16];
    for (int i = 0; i < AFFECT_HEATMAP_MAX_LABELS; i++) {
        snprintf(name, sizeof name, "c%d", i);
        add(hm, "r", name, i);
    }
    assert_int_equal(affect_heatmap_add(hm, "r2", "one more", 1, &err), AFFECT_ERR_RANGE);
    assert_string_equal(err.msg, "more than 1000 columns");
    assert_int_equal(affect_heatmap_rows(hm), 1);
    assert_int_equal(affect_heatmap_columns(hm), 1000);
    add(hm, "r2", "c5", 1); /* known labels still go in */
    assert_int_equal(affect_heatmap_rows(hm), 2);
    affect_heatmap_free(hm);
}

/* ---- out of memory ---- */

typedef struct hm_oom {
    affect_heatmap *hm;
    char *svg;
} hm_oom;

static affect_status oom_build_render(void *ctx, affect_error *err)
{
    hm_oom *c = ctx;
    affect_status st;
    c->hm = NULL;
    c->svg = NULL;
    if ((st = affect_heatmap_create(&c->hm, err)) != AFFECT_OK)
        return st;
    static const char *const rows[] = {"angry · state 1", "sad · state 1", "sad · state 2"};
    static const char *const cols[] = {"Head", "Hand_L", "Hand_R", "Foot_L", "Foot_R"};
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 5; j++)
            if ((st = affect_heatmap_add(c->hm, rows[i], cols[j], i + 0.1 * j, err)) != AFFECT_OK)
                return st;
    affect_heatmap_options opt;
    affect_heatmap_options_default(&opt);
    opt.sort_rows = opt.sort_columns = true;
    opt.title = "oom";
    return affect_heatmap_render(c->hm, &opt, &c->svg, NULL, err);
}

static void oom_finish(void *ctx, affect_status st)
{
    hm_oom *c = ctx;
    if (st != AFFECT_OK)
        assert_null(c->svg);
    affect_free(c->svg);
    affect_heatmap_free(c->hm);
}

static void test_out_of_memory(void **state)
{
    hm_oom c = {NULL, NULL};
    assert_true(tu_oom_sweep(oom_build_render, &c, oom_finish, NULL) >= 10);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cells_and_labels),
        cmocka_unit_test(test_empty_and_odd_labels),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_out_of_memory),
    };
    return cmocka_run_group_tests_name("heatmap", tests, NULL, NULL);
}
