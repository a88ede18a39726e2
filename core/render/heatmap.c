/*
 * heatmap.c — heat maps as standalone SVG (see affect/heatmap.h).
 *
 * Usage: see the block at the top of affect/heatmap.h (compiled by the style/header-usage test).
 *
 * Accumulating: row and column labels are interned in two tables (FNV-1a, open addressing) in
 * the order they first appear; cells are kept as a list (row, column, value) and folded into a
 * dense grid when rendering (a cell given twice keeps the larger value).
 *
 * Layout (pixels; c = opt->cell, font 11 px, label widths estimated at 0.6 em per character,
 * labels cut at 40 characters with "…"): an optional title row (28); the rotated y title and
 * the row labels (right-aligned) left of the grid; the grid of rows × columns cells of c × c,
 * each drawn 1 px smaller so that a white line separates them; under it the column labels,
 * slanted up by 45° and ending under their column's centre, then the x title and the note
 * ("3 values not finite"); right of the grid a colour bar (at most 160 px high) with the
 * scale's top and bottom values.
 *
 * Colour: t = (v − min) / (max − min) clamped to [0, 1] (t = 0.5 when max = min) through the
 * ColorBrewer "Blues" ramp (#f7fbff #c6dbef #6baed6 #2171b5 #08306b, interpolated linearly in
 * sRGB between those five stops); values printed in a cell are white from t = 0.55. A cell
 * without a value is light grey. Every cell carries a <title> tooltip "row × column: value"
 * (the value with six significant digits).
 *
 * Structure (stable, for tools and tests): <g class="cells"> holds one <rect class="cell"
 * data-row="i" data-column="j"> per cell (0-based); the labels are <text class="row-label">
 * and <text class="column-label">; values <text class="value">; the bar <g class="colour-bar">.
 * Numbers are written with three significant digits ("0.0454", "1.5e+03" style of %g, locale-
 * independent).
 */
#include "affect/heatmap.h"
#include "util/strbuf.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define HM_FS 11.0
#define HM_EM 0.6          /* estimated advance of a character, em */
#define HM_LABEL_CHARS 40  /* labels longer than this are cut */
#define HM_BAR_MAX 160.0   /* colour bar height, at most */
#define HM_BAR_STEPS 32    /* rectangles of the colour bar */
#define HM_SLANT 0.7071068 /* sin 45° */
#define HM_DARK_TEXT 0.55  /* from this t on, values are written in white */
#define HM_AUTO_VALUES 30.0

typedef struct labels {
    char **names;
    uint32_t n, cap;
    uint32_t *slots; /* label index + 1, 0 = empty; n_slots a power of two */
    size_t n_slots;
} labels;

typedef struct cell {
    uint32_t row, col;
    double value;
} cell;

struct affect_heatmap {
    labels rows, cols;
    cell *cells;
    size_t n_cells, cap_cells;
    size_t n_nonfinite;
};

static const unsigned char ramp[5][3] = {{0xf7, 0xfb, 0xff},
                                         {0xc6, 0xdb, 0xef},
                                         {0x6b, 0xae, 0xd6},
                                         {0x21, 0x71, 0xb5},
                                         {0x08, 0x30, 0x6b}};

void affect_heatmap_options_default(affect_heatmap_options *opt)
{
    opt->title = NULL;
    opt->x_label = NULL;
    opt->y_label = NULL;
    opt->cell = 24;
    opt->values = -1;
    opt->sort_rows = opt->sort_columns = false;
    opt->has_min = opt->has_max = false;
    opt->min = 0;
    opt->max = 1;
}

static const char *num_text(char buf[40], double v)
{
    affect_format_g(buf, 40, 6, v);
    return buf;
}

affect_status affect_heatmap_options_check(const affect_heatmap_options *opt, affect_error *err)
{
    char a[40], b[40];
    if (!(opt->cell >= AFFECT_HEATMAP_MIN_CELL && opt->cell <= AFFECT_HEATMAP_MAX_CELL))
        return affect_fail(err, AFFECT_ERR_INVALID, "cell must be between %d and %d, got %s",
                           (int)AFFECT_HEATMAP_MIN_CELL, (int)AFFECT_HEATMAP_MAX_CELL,
                           num_text(a, opt->cell));
    if (opt->cell != floor(opt->cell))
        return affect_fail(err, AFFECT_ERR_INVALID, "cell must be a whole number, got %s",
                           num_text(a, opt->cell));
    if ((opt->has_min && !isfinite(opt->min)) || (opt->has_max && !isfinite(opt->max)))
        return affect_fail(err, AFFECT_ERR_INVALID, "min and max must be finite");
    if (opt->has_min && opt->has_max && !(opt->min < opt->max))
        return affect_fail(err, AFFECT_ERR_INVALID, "min must be below max, got %s and %s",
                           num_text(a, opt->min), num_text(b, opt->max));
    return AFFECT_OK;
}

/* ---- labels ---- */

static uint64_t hash_label(const char *s)
{
    uint64_t h = 14695981039346656037u;
    for (; *s; s++)
        h = (h ^ (unsigned char)*s) * 1099511628211u;
    return h;
}

static size_t find_slot(const labels *L, const char *s, uint64_t h)
{
    size_t mask = L->n_slots - 1, i = (size_t)h & mask;
    while (L->slots[i] != 0 && strcmp(L->names[L->slots[i] - 1], s) != 0)
        i = (i + 1) & mask;
    return i;
}

/* Index of label s in L, or −1 when it is not there. */
static int64_t lookup(const labels *L, const char *s)
{
    if (L->n_slots == 0)
        return -1;
    size_t i = find_slot(L, s, hash_label(s));
    return L->slots[i] ? (int64_t)L->slots[i] - 1 : -1;
}

/* Index of label s in L, interned when new. */
static affect_status intern(labels *L, const char *s, uint32_t *index, affect_error *err)
{
    uint64_t h = hash_label(s);
    if (L->n_slots > 0) {
        size_t i = find_slot(L, s, h);
        if (L->slots[i] != 0) {
            *index = L->slots[i] - 1;
            return AFFECT_OK;
        }
    }
    if (L->n == L->cap) {
        uint32_t cap = L->cap ? 2 * L->cap : 8;
        char **names = affect_realloc(L->names, (size_t)cap * sizeof *names);
        if (!names)
            return affect_nomem(err);
        L->names = names;
        L->cap = cap;
    }
    if ((size_t)(L->n + 1) * 2 > L->n_slots) {
        size_t n = L->n_slots ? 2 * L->n_slots : 16;
        uint32_t *slots = affect_calloc(n, sizeof *slots);
        if (!slots)
            return affect_nomem(err);
        for (uint32_t k = 0; k < L->n; k++) {
            size_t i = (size_t)hash_label(L->names[k]) & (n - 1);
            while (slots[i] != 0)
                i = (i + 1) & (n - 1);
            slots[i] = k + 1;
        }
        affect_free(L->slots);
        L->slots = slots;
        L->n_slots = n;
    }
    char *copy = affect_strndup(s, strlen(s));
    if (!copy)
        return affect_nomem(err);
    L->names[L->n] = copy;
    L->slots[find_slot(L, s, h)] = L->n + 1;
    *index = L->n++;
    return AFFECT_OK;
}

static void labels_free(labels *L)
{
    for (uint32_t i = 0; i < L->n; i++)
        affect_free(L->names[i]);
    affect_free(L->names);
    affect_free(L->slots);
}

/* ---- the accumulator ---- */

affect_status affect_heatmap_create(affect_heatmap **out, affect_error *err)
{
    *out = affect_calloc(1, sizeof **out);
    return *out ? AFFECT_OK : affect_nomem(err);
}

void affect_heatmap_free(affect_heatmap *hm)
{
    if (!hm)
        return;
    labels_free(&hm->rows);
    labels_free(&hm->cols);
    affect_free(hm->cells);
    affect_free(hm);
}

size_t affect_heatmap_rows(const affect_heatmap *hm)
{
    return hm->rows.n;
}

size_t affect_heatmap_columns(const affect_heatmap *hm)
{
    return hm->cols.n;
}

affect_status affect_heatmap_add(affect_heatmap *hm, const char *row, const char *column,
                                 double value, affect_error *err)
{
    affect_status st;
    uint32_t r, c;
    if (hm->n_cells == hm->cap_cells) {
        size_t cap = hm->cap_cells ? hm->cap_cells : 32, bytes;
        if (!affect_mul_size(cap, 2, &cap) || !affect_mul_size(cap, sizeof(cell), &bytes))
            return affect_nomem(err);
        cell *cells = affect_realloc(hm->cells, bytes);
        if (!cells)
            return affect_nomem(err);
        hm->cells = cells;
        hm->cap_cells = cap;
    }
    if (lookup(&hm->rows, row) < 0 && hm->rows.n >= AFFECT_HEATMAP_MAX_LABELS)
        return affect_fail(err, AFFECT_ERR_RANGE, "more than %d rows", AFFECT_HEATMAP_MAX_LABELS);
    if (lookup(&hm->cols, column) < 0 && hm->cols.n >= AFFECT_HEATMAP_MAX_LABELS)
        return affect_fail(err, AFFECT_ERR_RANGE, "more than %d columns",
                           AFFECT_HEATMAP_MAX_LABELS);
    if ((st = intern(&hm->rows, row, &r, err)) != AFFECT_OK ||
        (st = intern(&hm->cols, column, &c, err)) != AFFECT_OK)
        return st;
    if (!isfinite(value)) {
        hm->n_nonfinite++;
        return AFFECT_OK;
    }
    hm->cells[hm->n_cells].row = r;
    hm->cells[hm->n_cells].col = c;
    hm->cells[hm->n_cells].value = value;
    hm->n_cells++;
    return AFFECT_OK;
}

/* ---- rendering ---- */

typedef struct ranked {
    const char *name;
    uint32_t index;
} ranked;

static int cmp_ranked(const void *a, const void *b)
{
    const ranked *x = a, *y = b;
    int c = strcmp(x->name, y->name);
    return c ? c : (x->index > y->index) - (x->index < y->index);
}

/* pos[i]: where label i is drawn (its rank in byte order when sorted, else i itself). */
static affect_status order_labels(const labels *L, bool sorted, uint32_t *pos, affect_error *err)
{
    for (uint32_t i = 0; i < L->n; i++)
        pos[i] = i;
    if (!sorted || L->n < 2)
        return AFFECT_OK;
    ranked *r = affect_malloc_array(L->n, sizeof *r);
    if (!r)
        return affect_nomem(err);
    for (uint32_t i = 0; i < L->n; i++) {
        r[i].name = L->names[i];
        r[i].index = i;
    }
    qsort(r, L->n, sizeof *r, cmp_ranked);
    for (uint32_t k = 0; k < L->n; k++)
        pos[r[k].index] = k;
    affect_free(r);
    return AFFECT_OK;
}

static size_t cp_count(const char *s)
{
    size_t k = 0;
    for (; *s; s++)
        k += ((unsigned char)*s & 0xC0) != 0x80;
    return k;
}

/* Estimated width in pixels of a label as drawn (cut at HM_LABEL_CHARS). */
static double label_width(const char *s)
{
    size_t n = cp_count(s);
    return (double)(n > HM_LABEL_CHARS ? HM_LABEL_CHARS : n) * HM_EM * HM_FS;
}

/* A label as XML text: valid UTF-8 (bad bytes as U+FFFD), cut at HM_LABEL_CHARS with "…". */
static void put_label(affect_strbuf *sb, const char *s)
{
    size_t total = cp_count(s), keep = total > HM_LABEL_CHARS ? HM_LABEL_CHARS - 1 : total;
    size_t n = strlen(s), i = 0;
    for (size_t k = 0; k < keep && i < n; k++) {
        size_t len = affect_utf8_sequence((const unsigned char *)s + i, n - i);
        char one[5] = {0};
        if (len == 0) {
            affect_strbuf_puts(sb, "\xef\xbf\xbd");
            i++;
            continue;
        }
        memcpy(one, s + i, len);
        affect_strbuf_xml(sb, one);
        i += len;
    }
    if (keep < total)
        affect_strbuf_puts(sb, "\xe2\x80\xa6");
}

static void put_px(affect_strbuf *sb, double v)
{
    affect_strbuf_fixed(sb, fmax(fmin(v, 1e6), -1e6), 1);
}

static void colour_of(double t, char out[8])
{
    static const char hex[] = "0123456789abcdef";
    if (!(t >= 0))
        t = 0;
    if (t > 1)
        t = 1;
    double x = t * 4;
    int k = (int)x;
    if (k > 3)
        k = 3;
    double w = x - k;
    out[0] = '#';
    for (int c = 0; c < 3; c++) {
        long v = lround(ramp[k][c] + w * (ramp[k + 1][c] - ramp[k][c]));
        out[1 + 2 * c] = hex[(v >> 4) & 15];
        out[2 + 2 * c] = hex[v & 15];
    }
    out[7] = '\0';
}

static void put_value(affect_strbuf *sb, double v)
{
    char buf[40];
    affect_format_g(buf, sizeof buf, 3, v);
    affect_strbuf_puts(sb, buf);
}

static void text_open(affect_strbuf *sb, const char *cls, double x, double y, const char *anchor,
                      const char *extra)
{
    affect_strbuf_printf(sb, "<text class=\"%s\" x=\"", cls);
    put_px(sb, x);
    affect_strbuf_puts(sb, "\" y=\"");
    put_px(sb, y);
    affect_strbuf_printf(sb, "\" text-anchor=\"%s\"%s>", anchor, extra);
}

static bool has_text(const char *s)
{
    return s && *s;
}

affect_status affect_heatmap_render(const affect_heatmap *hm, const affect_heatmap_options *opt,
                                    char **out, size_t *len, affect_error *err)
{
    affect_heatmap_options defaults;
    affect_strbuf sb;
    affect_status st;
    double *grid = NULL;
    uint32_t *rpos = NULL, *cpos = NULL;
    const char **rname = NULL, **cname = NULL;
    affect_strbuf_init(&sb);
    *out = NULL;
    if (len)
        *len = 0;
    if (!opt) {
        affect_heatmap_options_default(&defaults);
        opt = &defaults;
    }
    if ((st = affect_heatmap_options_check(opt, err)) != AFFECT_OK)
        goto cleanup;
    size_t nr = hm->rows.n, nc = hm->cols.n, n_grid;
    if (!affect_mul_size(nr ? nr : 1, nc ? nc : 1, &n_grid) ||
        !(grid = affect_malloc_array(n_grid, sizeof *grid))) {
        st = affect_nomem(err);
        goto cleanup;
    }
    rpos = affect_malloc_array(nr + 1, sizeof *rpos);
    cpos = affect_malloc_array(nc + 1, sizeof *cpos);
    rname = affect_malloc_array(nr + 1, sizeof *rname);
    cname = affect_malloc_array(nc + 1, sizeof *cname);
    if (!rpos || !cpos || !rname || !cname) {
        st = affect_nomem(err);
        goto cleanup;
    }
    if ((st = order_labels(&hm->rows, opt->sort_rows, rpos, err)) != AFFECT_OK ||
        (st = order_labels(&hm->cols, opt->sort_columns, cpos, err)) != AFFECT_OK)
        goto cleanup;
    for (size_t i = 0; i < nr; i++)
        rname[rpos[i]] = hm->rows.names[i];
    for (size_t j = 0; j < nc; j++)
        cname[cpos[j]] = hm->cols.names[j];
    for (size_t i = 0; i < n_grid; i++)
        grid[i] = NAN;
    double lo = HUGE_VAL, hi = -HUGE_VAL;
    for (size_t k = 0; k < hm->n_cells; k++) {
        const cell *c = &hm->cells[k];
        double *g = &grid[(size_t)rpos[c->row] * nc + cpos[c->col]];
        if (isnan(*g) || c->value > *g)
            *g = c->value;
        lo = fmin(lo, c->value);
        hi = fmax(hi, c->value);
    }
    if (opt->has_min)
        lo = opt->min;
    if (opt->has_max)
        hi = opt->max;
    if (hm->n_cells == 0 && !opt->has_min)
        lo = opt->has_max ? hi - 1 : 0;
    if (hm->n_cells == 0 && !opt->has_max)
        hi = lo + 1;

    double c = opt->cell, fs = HM_FS;
    bool values = opt->values > 0 || (opt->values < 0 && c >= HM_AUTO_VALUES);
    double rw = 0, cw = 0;
    for (size_t i = 0; i < nr; i++)
        rw = fmax(rw, label_width(rname[i]));
    for (size_t j = 0; j < nc; j++)
        cw = fmax(cw, label_width(cname[j]));
    double ylab = has_text(opt->y_label) ? 22 : 0;
    double left = fmax(8 + ylab + rw + 8, cw * HM_SLANT - c / 2 + 8);
    double top = has_text(opt->title) ? 36 : 10;
    double gw = (double)nc * c, gh = (double)nr * c;
    double bar_h = fmin(fmax(gh, 60), HM_BAR_MAX), bar_x = left + gw + 16;
    char a[40], b[40], tip[40];
    affect_format_g(a, sizeof a, 3, hi);
    affect_format_g(b, sizeof b, 3, lo);
    double bar_text = fmax(strlen(a), strlen(b)) * HM_EM * fs;
    double width = fmax(bar_x + 14 + 6 + bar_text + 10, 200);
    if (has_text(opt->title))
        width = fmax(width, 16 + cp_count(opt->title) * HM_EM * 14);
    double below = top + gh + 6 + cw * HM_SLANT + fs;
    double height = below + (has_text(opt->x_label) ? 22 : 0) + (hm->n_nonfinite ? 18 : 0) + 10;
    height = fmax(height, top + bar_h + 10);
    width = ceil(width);
    height = ceil(height);

    affect_strbuf_printf(&sb,
                         "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" "
                         "viewBox=\"0 0 %d %d\" font-family=\"sans-serif\" font-size=\"11\">\n",
                         (int)width, (int)height, (int)width, (int)height);
    affect_strbuf_puts(&sb, "<rect width=\"100%\" height=\"100%\" fill=\"#fff\"/>\n");
    if (has_text(opt->title)) {
        text_open(&sb, "title", 8, 22, "start",
                  " font-size=\"14\" font-weight=\"bold\" fill=\"#222\"");
        put_label(&sb, opt->title);
        affect_strbuf_puts(&sb, "</text>\n");
    }
    /* cells */
    affect_strbuf_puts(&sb, "<g class=\"cells\">\n");
    for (size_t i = 0; i < nr; i++) {
        for (size_t j = 0; j < nc; j++) {
            double v = grid[i * nc + j];
            char col[8] = "#ececec";
            if (!isnan(v))
                colour_of(hi > lo ? (v - lo) / (hi - lo) : 0.5, col);
            affect_strbuf_printf(
                &sb, "<rect class=\"cell\" data-row=\"%zu\" data-column=\"%zu\" x=\"", i, j);
            put_px(&sb, left + j * c);
            affect_strbuf_puts(&sb, "\" y=\"");
            put_px(&sb, top + i * c);
            affect_strbuf_puts(&sb, "\" width=\"");
            put_px(&sb, c - 1);
            affect_strbuf_puts(&sb, "\" height=\"");
            put_px(&sb, c - 1);
            affect_strbuf_printf(&sb, "\" fill=\"%s\"><title>", col);
            put_label(&sb, rname[i]);
            affect_strbuf_puts(&sb, " \xc3\x97 ");
            put_label(&sb, cname[j]);
            affect_strbuf_puts(&sb, ": ");
            if (isnan(v))
                affect_strbuf_puts(&sb, "no value");
            else
                affect_strbuf_puts(&sb, num_text(tip, v)); /* six significant digits */
            affect_strbuf_puts(&sb, "</title></rect>\n");
        }
    }
    affect_strbuf_puts(&sb, "</g>\n");
    if (values) {
        double vfs = fmin(fs, c / 3.2);
        affect_strbuf_puts(&sb, "<g class=\"values\" font-size=\"");
        affect_strbuf_fixed(&sb, vfs, 1);
        affect_strbuf_puts(&sb, "\">\n");
        for (size_t i = 0; i < nr; i++)
            for (size_t j = 0; j < nc; j++) {
                double v = grid[i * nc + j];
                if (isnan(v))
                    continue;
                double t = hi > lo ? (v - lo) / (hi - lo) : 0.5;
                text_open(&sb, "value", left + j * c + (c - 1) / 2,
                          top + i * c + (c - 1) / 2 + vfs * 0.35, "middle",
                          t >= HM_DARK_TEXT ? " fill=\"#fff\"" : " fill=\"#222\"");
                put_value(&sb, v);
                affect_strbuf_puts(&sb, "</text>\n");
            }
        affect_strbuf_puts(&sb, "</g>\n");
    }
    /* labels */
    affect_strbuf_puts(&sb, "<g fill=\"#222\">\n");
    for (size_t i = 0; i < nr; i++) {
        text_open(&sb, "row-label", left - 6, top + i * c + (c - 1) / 2 + fs * 0.35, "end", "");
        put_label(&sb, rname[i]);
        affect_strbuf_puts(&sb, "</text>\n");
    }
    for (size_t j = 0; j < nc; j++) {
        double x = left + j * c + (c - 1) / 2 + fs * 0.3, y = top + gh + 6;
        affect_strbuf_puts(
            &sb, "<text class=\"column-label\" text-anchor=\"end\" transform=\"translate(");
        put_px(&sb, x);
        affect_strbuf_putc(&sb, ' ');
        put_px(&sb, y);
        affect_strbuf_puts(&sb, ") rotate(-45)\">");
        put_label(&sb, cname[j]);
        affect_strbuf_puts(&sb, "</text>\n");
    }
    affect_strbuf_puts(&sb, "</g>\n");
    if (has_text(opt->x_label)) {
        text_open(&sb, "axis-title", left + gw / 2, below + 14, "middle",
                  " font-size=\"12\" fill=\"#222\"");
        put_label(&sb, opt->x_label);
        affect_strbuf_puts(&sb, "</text>\n");
    }
    if (has_text(opt->y_label)) {
        affect_strbuf_puts(&sb, "<text class=\"axis-title\" font-size=\"12\" fill=\"#222\" "
                                "text-anchor=\"middle\" transform=\"translate(");
        put_px(&sb, 16);
        affect_strbuf_putc(&sb, ' ');
        put_px(&sb, top + gh / 2);
        affect_strbuf_puts(&sb, ") rotate(-90)\">");
        put_label(&sb, opt->y_label);
        affect_strbuf_puts(&sb, "</text>\n");
    }
    if (hm->n_cells == 0) {
        text_open(&sb, "no-data", left + 40, top + 20, "start", " fill=\"#888\" font-size=\"14\"");
        affect_strbuf_puts(&sb, "no data</text>\n");
    }
    if (hm->n_nonfinite) {
        text_open(&sb, "note", 8, height - 10, "start", " fill=\"#777\"");
        affect_strbuf_printf(&sb, "%zu value%s not finite</text>\n", hm->n_nonfinite,
                             hm->n_nonfinite == 1 ? "" : "s");
    }
    /* colour bar: top = hi */
    affect_strbuf_puts(&sb, "<g class=\"colour-bar\">\n");
    double step = bar_h / HM_BAR_STEPS;
    for (int k = 0; k < HM_BAR_STEPS; k++) {
        char col[8];
        colour_of(1 - (k + 0.5) / HM_BAR_STEPS, col);
        affect_strbuf_puts(&sb, "<rect x=\"");
        put_px(&sb, bar_x);
        affect_strbuf_puts(&sb, "\" y=\"");
        put_px(&sb, top + k * step);
        affect_strbuf_puts(&sb, "\" width=\"14\" height=\"");
        put_px(&sb, step + 0.4);
        affect_strbuf_printf(&sb, "\" fill=\"%s\"/>\n", col);
    }
    text_open(&sb, "bar-max", bar_x + 20, top + fs * 0.8, "start", " fill=\"#444\"");
    affect_strbuf_puts(&sb, a);
    affect_strbuf_puts(&sb, "</text>\n");
    text_open(&sb, "bar-min", bar_x + 20, top + bar_h, "start", " fill=\"#444\"");
    affect_strbuf_puts(&sb, b);
    affect_strbuf_puts(&sb, "</text>\n</g>\n</svg>\n");
    st = affect_strbuf_finish(&sb, out, len, err);
cleanup:
    affect_strbuf_free(&sb);
    affect_free(grid);
    affect_free(rpos);
    affect_free(cpos);
    affect_free(rname);
    affect_free(cname);
    return st;
}
