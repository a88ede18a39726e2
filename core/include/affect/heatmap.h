/*
 * affect/heatmap.h — heat maps as standalone SVG: a grid of cells (row label × column label →
 * value) coloured on a sequential scale, with the row labels written left of the grid and the
 * column labels under it (slanted), a colour bar with the scale's ends, the values printed in
 * the cells when they fit, and a tooltip per cell. For the salience of joints per HMM state
 * (affect_salience), or any table of numbers with named rows and columns.
 *
 * Usage:
 *     affect_error err;
 *     affect_heatmap *hm = NULL;
 *     affect_heatmap_options opt;
 *     affect_heatmap_options_default(&opt);
 *     opt.title = "Salience";
 *     char *svg = NULL;  size_t len = 0;
 *     if (affect_heatmap_create(&hm, &err) != AFFECT_OK
 *         || affect_heatmap_add(hm, "sad, state 1", "Hand_L", 0.045, &err) != AFFECT_OK   // a cell
 *         || affect_heatmap_render(hm, &opt, &svg, &len, &err) != AFFECT_OK)
 *         puts(err.msg);
 *     affect_free(svg);
 *     affect_heatmap_free(hm);
 *
 * An affect_heatmap is an accumulator: create it, add cells (row, column, value) in any order,
 * render it, free it. Rows and columns are drawn in the order of their first appearance (or
 * sorted by label, opt->sort_rows and opt->sort_columns); a cell
 * given twice keeps the larger value (the salience of a joint is its heaviest entry). Rendering
 * is byte-for-byte deterministic for the same sequence of additions.
 */
#ifndef AFFECT_HEATMAP_H
#define AFFECT_HEATMAP_H

#include "affect/base.h"

#ifdef __cplusplus
extern "C" {
#endif

#define AFFECT_HEATMAP_MAX_LABELS 1000 /* most rows, and most columns */
#define AFFECT_HEATMAP_MIN_CELL 8.0    /* cell side, pixels */
#define AFFECT_HEATMAP_MAX_CELL 120.0

typedef struct affect_heatmap_options {
    const char *title;     /* above the grid; NULL or "" for none */
    const char *x_label;   /* under the column labels; NULL or "" for none */
    const char *y_label;   /* left of the row labels (rotated); NULL or "" for none */
    double cell;           /* cell side in whole pixels, 8..120 (default 24) */
    int values;            /* print the values in the cells: 1 yes, 0 no, −1 (default) when the
                              cells are at least 30 px wide */
    bool sort_rows;        /* rows in byte order of their labels (default: first appearance) */
    bool sort_columns;     /* likewise the columns */
    bool has_min, has_max; /* the colour scale's ends; default the values' range */
    double min, max;
} affect_heatmap_options;

void affect_heatmap_options_default(affect_heatmap_options *opt);

/* AFFECT_ERR_INVALID with "cell must be between 8 and 120, got 4", "cell must be a whole number,
 * got 20.5", "min and max must be finite", "min must be below max, got 1 and 1". */
affect_status affect_heatmap_options_check(const affect_heatmap_options *opt, affect_error *err);

typedef struct affect_heatmap affect_heatmap;

affect_status affect_heatmap_create(affect_heatmap **out, affect_error *err);
void affect_heatmap_free(affect_heatmap *hm); /* NULL is allowed */

/* Adds a cell. row and column are NUL-terminated labels (copied; bytes that are not UTF-8 are
 * drawn as U+FFFD). A non-finite value is counted in the note under the grid and leaves the
 * cell as it was. AFFECT_ERR_RANGE: "more than 1000 rows" (likewise columns), the map
 * unchanged; AFFECT_ERR_NOMEM. */
affect_status affect_heatmap_add(affect_heatmap *hm, const char *row, const char *column,
                                 double value, affect_error *err);

size_t affect_heatmap_rows(const affect_heatmap *hm);
size_t affect_heatmap_columns(const affect_heatmap *hm);

/* Writes the map as a complete <svg> document (free *out with affect_free); opt NULL means the
 * defaults. With no cell at all the document says "no data". */
affect_status affect_heatmap_render(const affect_heatmap *hm, const affect_heatmap_options *opt,
                                    char **out, size_t *len, affect_error *err);

#ifdef __cplusplus
}
#endif
#endif
