/*
 * fn_plot.c — laban_plot(x, y, label [, options]): an aggregate that draws its rows as an SVG
 * scatter plot, one colour per label, with a legend of point counts (core: affect/plot.h).
 *
 *   SELECT laban_plot(laban_weight(motion), laban_time(motion), emotion,
 *                     '{"title":"Weight vs Time","x_label":"WeightAll","y_label":"TimeAll",
 *                       "log_x":true,"log_y":true,"means":true}')
 *     FROM motions;
 *
 * Arguments: x and y are numbers (a row with a NULL x or y is skipped, as aggregates skip
 * NULLs; a non-finite one is drawn as skipped in the plot's note); label is text, a number
 * (converted to text) or NULL (drawn as "(none)"); options is a JSON object with the keys
 * title, x_label, y_label (strings), width, height, radius (numbers), log_x, log_y, means
 * (booleans), mode ("scatter", the default, or "series": a time series, each label's points
 * joined by a line in x order — laban_plot(seconds, weight, part, '{"mode":"series"}') over
 * laban_series). The options are read from the first row and must be the same text on every
 * row. The result is the SVG document as text; over no rows at all it is the empty plot with
 * the default options ("no data").
 *
 * How it works: the aggregate context holds one pointer to a plot_state, allocated on the first
 * row, which owns the core accumulator, the parsed options and a copy of the options text.
 * xFinal renders and frees it. SQLite calls xFinal for every aggregate context that was
 * created, also when the statement stops early (an error in a later row, a reset or finalize
 * before the end, a GROUP BY cut short): its cleanup of the context cell finalizes it. After
 * an error that laban_plot itself reported, the state is marked failed and xFinal only frees.
 *
 * Errors: "laban_plot: x (argument 1) must be a number, got text" (likewise y, argument 2),
 * "laban_plot: label (argument 3) must be text, a number or NULL, got blob", "laban_plot:
 * options must be the same on every row", the option errors of common.c ("laban_plot: unknown
 * option …", "laban_plot: option \"width\" must be a number, got string") and of the core
 * ("laban_plot: width must be between 100 and 4000, got 50").
 */
#include "fn_plot.h"

#include <string.h>

#include "affect/plot.h"

static const char *const plot_keys[] = {"title", "x_label", "y_label", "width", "height", "log_x",
                                        "log_y", "radius",  "means",   "mode",  NULL};

typedef struct plot_state {
    affect_scatter *sc;
    ax_opts opts; /* the first row's options; owns the strings in po */
    affect_plot_options po;
    ax_opts_text opts_text; /* copy of the first row's options text (NULL when none) */
    bool failed;            /* an error was reported: xFinal only frees */
} plot_state;

static void state_free(plot_state *ps)
{
    if (!ps)
        return;
    affect_scatter_free(ps->sc);
    ax_opts_free(&ps->opts);
    sqlite3_free(ps->opts_text.text);
    sqlite3_free(ps);
}

/* Parses and checks the options (argument 4) of the first row into ps. */
static ax_arg read_options(sqlite3_context *ctx, int argc, sqlite3_value **argv, plot_state *ps)
{
    static const char *const modes[] = {"scatter", "series", NULL};
    int mode = 0;
    affect_plot_options_default(&ps->po);
    if (ax_opts_parse(ctx, argc, argv, 3, plot_keys, &ps->opts) != AX_OK)
        return AX_ERROR;
    if (ax_opt_string(ctx, &ps->opts, "title", &ps->po.title) ||
        ax_opt_string(ctx, &ps->opts, "x_label", &ps->po.x_label) ||
        ax_opt_string(ctx, &ps->opts, "y_label", &ps->po.y_label) ||
        ax_opt_number(ctx, &ps->opts, "width", &ps->po.width) ||
        ax_opt_number(ctx, &ps->opts, "height", &ps->po.height) ||
        ax_opt_number(ctx, &ps->opts, "radius", &ps->po.radius) ||
        ax_opt_bool(ctx, &ps->opts, "log_x", &ps->po.log_x) ||
        ax_opt_bool(ctx, &ps->opts, "log_y", &ps->po.log_y) ||
        ax_opt_bool(ctx, &ps->opts, "means", &ps->po.means) ||
        ax_opt_enum(ctx, &ps->opts, "mode", modes, &mode))
        return AX_ERROR;
    ps->po.lines = mode == 1;
    affect_error err;
    if (affect_plot_options_check(&ps->po, &err)) {
        ax_error(ctx, &err);
        return AX_ERROR;
    }
    return ax_opts_text_keep(ctx, argc, argv, 3, &ps->opts_text);
}

/* Argument i as a number into *out (AX_NULL for NULL). */
static ax_arg coordinate(sqlite3_context *ctx, sqlite3_value **argv, int i, const char *what,
                         double *out)
{
    int type = sqlite3_value_type(argv[i]);
    if (type == SQLITE_NULL)
        return AX_NULL;
    if (type == SQLITE_INTEGER || type == SQLITE_FLOAT) {
        *out = sqlite3_value_double(argv[i]);
        return AX_OK;
    }
    ax_errorf(ctx, "%s (argument %d) must be a number, got %s", what, i + 1, ax_type_name(argv[i]));
    return AX_ERROR;
}

/* The label (argument 3) as text, NULL for NULL. */
static ax_arg label_of(sqlite3_context *ctx, sqlite3_value **argv, const char **out)
{
    int type = sqlite3_value_type(argv[2]);
    *out = NULL;
    if (type == SQLITE_NULL)
        return AX_OK;
    if (type == SQLITE_BLOB) {
        ax_errorf(ctx, "label (argument 3) must be text, a number or NULL, got blob");
        return AX_ERROR;
    }
    *out = (const char *)sqlite3_value_text(argv[2]);
    if (!*out) {
        sqlite3_result_error_nomem(ctx);
        return AX_ERROR;
    }
    return AX_OK;
}

/* Checks one row and adds its point; AX_ERROR when an error was reported. */
static ax_arg add_row(sqlite3_context *ctx, int argc, sqlite3_value **argv, plot_state *ps)
{
    double x = 0, y = 0;
    const char *label;
    if (ax_opts_text_same(ctx, argc, argv, 3, &ps->opts_text) != AX_OK)
        return AX_ERROR;
    ax_arg ax = coordinate(ctx, argv, 0, "x", &x);
    if (ax == AX_ERROR)
        return AX_ERROR;
    ax_arg ay = coordinate(ctx, argv, 1, "y", &y);
    if (ay == AX_ERROR || label_of(ctx, argv, &label) != AX_OK)
        return AX_ERROR;
    if (ax == AX_NULL || ay == AX_NULL)
        return AX_OK;
    affect_error err;
    if (affect_scatter_add(ps->sc, x, y, label, &err)) {
        ax_error(ctx, &err);
        return AX_ERROR;
    }
    return AX_OK;
}

void ax_laban_plot_step(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    plot_state **slot = sqlite3_aggregate_context(ctx, (int)sizeof *slot);
    if (!slot) {
        sqlite3_result_error_nomem(ctx);
        return;
    }
    plot_state *ps = *slot;
    if (ps && ps->failed)
        return;
    if (!ps) {
        ps = sqlite3_malloc64(sizeof *ps);
        if (!ps) {
            sqlite3_result_error_nomem(ctx);
            return;
        }
        memset(ps, 0, sizeof *ps);
        *slot = ps;
        affect_error err;
        if (read_options(ctx, argc, argv, ps) != AX_OK) {
            ps->failed = true;
            return;
        }
        if (affect_scatter_create(&ps->sc, &err)) {
            ax_error(ctx, &err);
            ps->failed = true;
            return;
        }
    }
    if (add_row(ctx, argc, argv, ps) != AX_OK)
        ps->failed = true;
}

void ax_laban_plot_final(sqlite3_context *ctx)
{
    plot_state **slot = sqlite3_aggregate_context(ctx, 0);
    plot_state *ps = slot ? *slot : NULL;
    affect_scatter *empty = NULL;
    char *svg = NULL;
    size_t len = 0;
    affect_error err;
    if (ps && ps->failed)
        goto done;
    if (!ps) { /* no rows: the empty plot with the default options */
        if (affect_scatter_create(&empty, &err)) {
            ax_error(ctx, &err);
            goto done;
        }
    }
    if (affect_scatter_render(ps ? ps->sc : empty, ps ? &ps->po : NULL, &svg, &len, &err))
        ax_error(ctx, &err);
    else
        ax_result_text(ctx, svg, len);
done:
    affect_scatter_free(empty);
    state_free(ps);
    if (slot)
        *slot = NULL;
}
