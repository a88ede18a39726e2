/*
 * affect/plot.h — scatter plots as standalone SVG: points grouped by a text label (emotion,
 * performer, cluster…), one colour per label, a legend with each label's point count, "nice"
 * axes (linear or log10) and, optionally, each label's mean ± 1 sd drawn as a cross; or, in
 * time-series mode (lines), each label's points joined by a line in x order.
 *
 * Usage:
 *     affect_error err;
 *     affect_scatter *sc = NULL;
 *     affect_plot_options opt;
 *     affect_plot_options_default(&opt);
 *     opt.title = "Weight vs Time";
 *     opt.means = true;
 *     char *svg = NULL;  size_t len = 0;
 *     if (affect_scatter_create(&sc, &err) != AFFECT_OK
 *         || affect_scatter_add(sc, 1.5, 2.0, "angry", &err) != AFFECT_OK   // one call per point
 *         || affect_scatter_render(sc, &opt, &svg, &len, &err) != AFFECT_OK)
 *         puts(err.msg);
 *     affect_free(svg);  affect_scatter_free(sc);
 *
 * An affect_scatter is an accumulator: create it, add points one at a time (x, y, label), then
 * render it as often as wanted with different options, then free it. Rendering depends only
 * on the multiset of points added, never on their order, and is byte-for-byte deterministic.
 */
#ifndef AFFECT_PLOT_H
#define AFFECT_PLOT_H

#include "affect/base.h"

#ifdef __cplusplus
extern "C" {
#endif

#define AFFECT_PLOT_MIN_SIZE 100.0 /* width and height, pixels */
#define AFFECT_PLOT_MAX_SIZE 4000.0
#define AFFECT_PLOT_MIN_RADIUS 0.5 /* point radius, pixels */
#define AFFECT_PLOT_MAX_RADIUS 20.0
#define AFFECT_PLOT_NONE_LABEL "(none)" /* the label of points added with a NULL label */

typedef struct affect_plot_options {
    const char *title;   /* above the plot; NULL or "" for none */
    const char *x_label; /* axis titles; NULL or "" for none */
    const char *y_label;
    double width;  /* whole pixels, 100..4000 (default 560) */
    double height; /* whole pixels, 100..4000 (default 420) */
    bool log_x;    /* log10 axes: points with a value <= 0 on such an axis are skipped */
    bool log_y;
    double radius; /* point radius in pixels, 0.5..20 (default 3) */
    bool means;    /* draw each label's mean ± 1 sample sd as a cross (default false) */
    bool lines;    /* time-series mode: each label's points joined in x order (then y) by a
                      line instead of drawn as markers; a label of one point is a marker
                      (default false) */
} affect_plot_options;

void affect_plot_options_default(affect_plot_options *opt);

/* AFFECT_ERR_INVALID with "width must be between 100 and 4000, got 50", "width must be a whole
 * number, got 560.5" (likewise height), "radius must be between 0.5 and 20, got 0". */
affect_status affect_plot_options_check(const affect_plot_options *opt, affect_error *err);

typedef struct affect_scatter affect_scatter;

affect_status affect_scatter_create(affect_scatter **out, affect_error *err);
/* NULL is allowed. */
void affect_scatter_free(affect_scatter *sc);

/* Adds one point. label is a NUL-terminated string (copied) or NULL, which means the label
 * AFFECT_PLOT_NONE_LABEL. A point with a non-finite x or y is not stored but counted (it is
 * reported in the note under the plot), and its label still gets its legend entry. On
 * failure (AFFECT_ERR_NOMEM) the accumulator is unchanged. */
affect_status affect_scatter_add(affect_scatter *sc, double x, double y, const char *label,
                                 affect_error *err);

/* Points added so far (the skipped non-finite ones included), and distinct labels. */
size_t affect_scatter_count(const affect_scatter *sc);
size_t affect_scatter_labels(const affect_scatter *sc);

/* Writes the plot as a complete <svg> document (free *out with affect_free); opt NULL means
 * the defaults. The options are checked first (affect_plot_options_check). */
affect_status affect_scatter_render(const affect_scatter *sc, const affect_plot_options *opt,
                                    char **out, size_t *len, affect_error *err);

#ifdef __cplusplus
}
#endif
#endif
