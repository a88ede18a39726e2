/*
 * plot.c — labelled scatter plots as standalone SVG (see affect/plot.h).
 *
 * Usage: see the block at the top of affect/plot.h (compiled by the style/header-usage test).
 *
 * Accumulating. Points are kept as (x, y, label index); labels are interned in a hash table
 * (FNV-1a, open addressing). Points with a non-finite coordinate are only counted.
 *
 * Rendering works in "axis space": the value itself on a linear axis, its log10 on a log axis
 * (points with a value <= 0 on a log axis are skipped and counted). The points are copied and
 * sorted by (label in strcmp order, x, y), so the document depends only on the multiset of
 * points, not on the order they were added. Label i in that order gets colour i mod 8 of the
 * Okabe–Ito palette (reordered so that the low-contrast yellow comes late) and marker shape
 * (i / 8) mod 4: circle, square, triangle, diamond.
 *
 * Axes. The data range (of the points, and of the mean ± sd crosses when drawn) is padded by
 * 5 % of its span on each side; a degenerate range (all values equal, or a span below 1e-10 of
 * the magnitude) becomes value ± 5 % (± 1 at zero) on a linear axis and ± 0.1 decade on a log
 * axis; spans below 1e-290 are widened to it; no data gives [0, 1] (log: [1, 10]). Linear ticks
 * are the multiples of a 1-2-5 step (s × 10^e) inside the range: the step nearest (on a log
 * scale) to the span over a target count from the axis length (one tick per 85 px across,
 * 60 px up), made coarser until the labels do not collide. Log axes use powers of ten when at least
 * three fall inside (every k-th decade, k in 1, 2, 3, 5, 10, 20, …, when there are more than the
 * target plus one or their labels collide; minor ticks at 2..9 × 10^k when every decade is
 * labelled), else 1-2-5 × 10^k when that gives at least three ticks, else linear 1-2-5 ticks of the
 * values. Tick labels are written from the integers (n, e) with value n × 10^e, so they are exact
 * and independent of the locale: fixed notation ("0.25", "1500", "−3") unless a label would exceed
 * six characters and scientific notation is shorter ("1.5×10⁶", "10⁻⁴", with superscript
 * digits); negative numbers use the minus sign U+2212.
 *
 * Layout (pixels at 560 × 420 and larger; smaller plots scale every font size and spacing by
 * k = min(width / 560, height / 420), but not below 0.5): title row (40) when there is a title; y
 * tick labels and the rotated y axis title on the left, sized from the widest label; the legend
 * right of the plot area (never over points), one 18 px row per label, "label (count)", labels cut
 * at 24 characters with "…" (fewer when the legend would take more than 30 % of the width), "+ N
 * more" when the rows do not fit the plot's height, and a "mean ± 1 sd" row when the crosses are
 * drawn; x tick labels and the x axis title below; then the note line, when points were skipped:
 * "skipped 3 of 58 points: 2 not finite, 1 ≤ 0 on a log axis". With no point to draw,
 * "no data" is written in the middle of the plot area.
 *
 * Means: for each label with points, the mean of x and of y in axis space (so on a log axis
 * the geometric mean) and ± 1 sample standard deviation (n − 1; bars only when n ≥ 2) as a
 * cross with end caps, in the label's colour over a white halo, and a larger marker with a
 * black outline at the mean, drawn after every cross so that none is hidden by another
 * label's bars. The crosses' <g class="mean"> elements carry data-n, data-mean-x,
 * data-mean-y, data-sd-x, data-sd-y in axis space (log10 units on a log axis).
 *
 * Structure (stable, for tools and tests): every label's points are in one
 * <g class="series" data-label="…" data-count="N" fill="#rrggbb"> inside <g class="points">;
 * markers are <circle>, <rect> or <path> elements; ticks labels are <text class="tick-x"> and
 * <text class="tick-y">; legend rows are <g class="legend-item">; the note is <text
 * class="note">. Text is XML-escaped; invalid UTF-8 becomes U+FFFD and control characters '?'.
 * Coordinates have one decimal and are clamped to ±1e6.
 *
 * Time-series mode (opt->lines): each label's points, sorted by (x, y) as above, are one
 * <path> in a <g class="series" data-label="…" data-count="N" stroke="#rrggbb"> inside
 * <g class="lines"> (a label with one point gets its marker instead); the legend shows a short
 * stretch of each label's line. Axes, means and the note are as for the scatter.
 *
 * Errors: AFFECT_ERR_INVALID for options (affect_plot_options_check), AFFECT_ERR_RANGE when a
 * scatter would get more than 2^32 − 2 labels, AFFECT_ERR_NOMEM ("out of memory").
 */
#include "affect/plot.h"
#include "util/strbuf.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define PLOT_COORD_LIMIT 1e6
#define PLOT_MAX_TICKS 40
#define PLOT_MAX_MINOR 160
#define PLOT_TICK_TEXT 64
#define PLOT_MIN_HALF_SPAN 1e-290 /* narrowest half-range of a linear axis */
#define PLOT_DEGENERATE 1e-10     /* relative span below which a range is one value */
#define PLOT_PAD 0.05             /* padding, fraction of the span, each side */
#define PLOT_FS_TICK 11.0
#define PLOT_FS_AXIS 12.5
#define PLOT_FS_TITLE 15.0
#define PLOT_FS_LEGEND 11.5
#define PLOT_FS_NOTE 10.5
#define PLOT_LEGEND_ROW 18.0
#define PLOT_LEGEND_CHARS 24
#define PLOT_TITLE_CHARS 200
#define PLOT_TICK_LEN 5.0

/* Okabe & Ito (2008), "Color Universal Design": blue, orange, bluish green, vermillion, sky
 * blue, reddish purple, yellow, black. */
static const char *const palette[8] = {"#0072B2", "#E69F00", "#009E73", "#D55E00",
                                       "#56B4E9", "#CC79A7", "#F0E442", "#000000"};

typedef struct point {
    double x, y;
    uint32_t label;
} point;

struct affect_scatter {
    point *pts;
    size_t n, cap;
    char **names; /* n_labels interned labels */
    uint32_t n_labels, names_cap;
    uint32_t *slots; /* hash table: label index + 1, 0 = empty; n_slots is a power of two */
    size_t n_slots;
    size_t n_added; /* every add, skipped ones included */
    size_t n_nonfinite;
};

/* ---- options ---- */

void affect_plot_options_default(affect_plot_options *opt)
{
    opt->title = NULL;
    opt->x_label = NULL;
    opt->y_label = NULL;
    opt->width = 560;
    opt->height = 420;
    opt->log_x = false;
    opt->log_y = false;
    opt->radius = 3;
    opt->means = false;
    opt->lines = false;
}

/* A number for a message, "%g"-like but independent of the locale. */
static const char *num_text(char buf[40], double v)
{
    affect_format_g(buf, 40, 6, v);
    return buf;
}

static affect_status check_size(const char *name, double v, affect_error *err)
{
    char buf[40];
    if (!(v >= AFFECT_PLOT_MIN_SIZE && v <= AFFECT_PLOT_MAX_SIZE))
        return affect_fail(err, AFFECT_ERR_INVALID, "%s must be between %d and %d, got %s", name,
                           (int)AFFECT_PLOT_MIN_SIZE, (int)AFFECT_PLOT_MAX_SIZE, num_text(buf, v));
    if (v != floor(v))
        return affect_fail(err, AFFECT_ERR_INVALID, "%s must be a whole number, got %s", name,
                           num_text(buf, v));
    return AFFECT_OK;
}

affect_status affect_plot_options_check(const affect_plot_options *opt, affect_error *err)
{
    affect_status st;
    char buf[40];
    if ((st = check_size("width", opt->width, err)) != AFFECT_OK ||
        (st = check_size("height", opt->height, err)) != AFFECT_OK)
        return st;
    if (!(opt->radius >= AFFECT_PLOT_MIN_RADIUS && opt->radius <= AFFECT_PLOT_MAX_RADIUS))
        return affect_fail(err, AFFECT_ERR_INVALID, "radius must be between 0.5 and 20, got %s",
                           num_text(buf, opt->radius));
    return AFFECT_OK;
}

/* ---- the accumulator ---- */

affect_status affect_scatter_create(affect_scatter **out, affect_error *err)
{
    *out = affect_calloc(1, sizeof **out);
    return *out ? AFFECT_OK : affect_nomem(err);
}

void affect_scatter_free(affect_scatter *sc)
{
    if (!sc)
        return;
    for (uint32_t i = 0; i < sc->n_labels; i++)
        affect_free(sc->names[i]);
    affect_free(sc->names);
    affect_free(sc->slots);
    affect_free(sc->pts);
    affect_free(sc);
}

size_t affect_scatter_count(const affect_scatter *sc)
{
    return sc->n_added;
}

size_t affect_scatter_labels(const affect_scatter *sc)
{
    return sc->n_labels;
}

static uint64_t hash_label(const char *s)
{
    uint64_t h = 14695981039346656037u;
    for (; *s; s++)
        h = (h ^ (unsigned char)*s) * 1099511628211u;
    return h;
}

/* Slot of label s: where it is, or the empty slot where it would go. */
static size_t find_slot(const affect_scatter *sc, const char *s, uint64_t h)
{
    size_t mask = sc->n_slots - 1, i = (size_t)h & mask;
    while (sc->slots[i] != 0 && strcmp(sc->names[sc->slots[i] - 1], s) != 0)
        i = (i + 1) & mask;
    return i;
}

/* Doubles the hash table (at least 16 slots). */
static affect_status grow_slots(affect_scatter *sc, affect_error *err)
{
    size_t n = sc->n_slots ? sc->n_slots : 8, bytes;
    if (!affect_mul_size(n, 2, &n) || !affect_mul_size(n, sizeof(uint32_t), &bytes))
        return affect_nomem(err);
    uint32_t *slots = affect_calloc(n, sizeof *slots);
    if (!slots)
        return affect_nomem(err);
    size_t mask = n - 1;
    for (uint32_t k = 0; k < sc->n_labels; k++) {
        size_t i = (size_t)hash_label(sc->names[k]) & mask;
        while (slots[i] != 0)
            i = (i + 1) & mask;
        slots[i] = k + 1;
    }
    affect_free(sc->slots);
    sc->slots = slots;
    sc->n_slots = n;
    return AFFECT_OK;
}

/* Index of label s, interning it when new. */
static affect_status intern(affect_scatter *sc, const char *s, uint32_t *index, affect_error *err)
{
    uint64_t h = hash_label(s);
    if (sc->n_slots > 0) {
        size_t i = find_slot(sc, s, h);
        if (sc->slots[i] != 0) {
            *index = sc->slots[i] - 1;
            return AFFECT_OK;
        }
    }
    if (sc->n_labels >= UINT32_MAX - 1)
        return affect_fail(err, AFFECT_ERR_RANGE, "too many labels (at most %u)", UINT32_MAX - 2);
    if (sc->n_labels == sc->names_cap) {
        uint32_t cap = sc->names_cap ? sc->names_cap : 8;
        cap = cap > UINT32_MAX / 2 ? UINT32_MAX - 1 : cap * 2;
        size_t bytes;
        if (!affect_mul_size(cap, sizeof(char *), &bytes))
            return affect_nomem(err);
        char **names = affect_realloc(sc->names, bytes);
        if (!names)
            return affect_nomem(err);
        sc->names = names;
        sc->names_cap = cap;
    }
    if ((size_t)(sc->n_labels + 1) * 2 > sc->n_slots) {
        affect_status st = grow_slots(sc, err);
        if (st != AFFECT_OK)
            return st;
    }
    char *copy = affect_strndup(s, strlen(s));
    if (!copy)
        return affect_nomem(err);
    sc->names[sc->n_labels] = copy;
    sc->slots[find_slot(sc, s, h)] = sc->n_labels + 1;
    *index = sc->n_labels++;
    return AFFECT_OK;
}

affect_status affect_scatter_add(affect_scatter *sc, double x, double y, const char *label,
                                 affect_error *err)
{
    uint32_t index;
    affect_status st;
    if (!label)
        label = AFFECT_PLOT_NONE_LABEL;
    if (!isfinite(x) || !isfinite(y)) {
        if ((st = intern(sc, label, &index, err)) != AFFECT_OK)
            return st;
        sc->n_added++;
        sc->n_nonfinite++;
        return AFFECT_OK;
    }
    if (sc->n == sc->cap) {
        size_t cap = sc->cap ? sc->cap : 64, bytes;
        if (!affect_mul_size(cap, 2, &cap) || !affect_mul_size(cap, sizeof(point), &bytes))
            return affect_nomem(err);
        point *pts = affect_realloc(sc->pts, bytes);
        if (!pts)
            return affect_nomem(err);
        sc->pts = pts;
        sc->cap = cap;
    }
    if ((st = intern(sc, label, &index, err)) != AFFECT_OK)
        return st;
    sc->pts[sc->n].x = x;
    sc->pts[sc->n].y = y;
    sc->pts[sc->n].label = index;
    sc->n++;
    sc->n_added++;
    return AFFECT_OK;
}

/* ---- text ---- */

/* Next code point of a NUL-terminated UTF-8 string; an invalid byte gives U+FFFD and is
 * consumed alone. */
static uint32_t next_cp(const char **pp)
{
    const unsigned char *p = (const unsigned char *)*pp;
    unsigned c = p[0];
    int n;
    uint32_t cp, min;
    if (c < 0x80) {
        *pp += 1;
        return c;
    }
    if (c >= 0xC2 && c <= 0xDF)
        n = 1, cp = c & 0x1F, min = 0x80;
    else if (c >= 0xE0 && c <= 0xEF)
        n = 2, cp = c & 0x0F, min = 0x800;
    else if (c >= 0xF0 && c <= 0xF4)
        n = 3, cp = c & 0x07, min = 0x10000;
    else {
        *pp += 1;
        return 0xFFFD;
    }
    for (int i = 1; i <= n; i++) {
        if ((p[i] & 0xC0) != 0x80) {
            *pp += 1;
            return 0xFFFD;
        }
        cp = (cp << 6) | (p[i] & 0x3F);
    }
    if (cp < min || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF) || cp == 0xFFFE ||
        cp == 0xFFFF) {
        *pp += 1;
        return 0xFFFD;
    }
    *pp += n + 1;
    return cp;
}

/* Approximate advance of a code point in ems, for a sans-serif font (layout estimates). */
static double cp_width(uint32_t c)
{
    if (c == ' ' || c == '.' || c == ',' || c == ':' || c == ';' || c == '\'' || c == '!' ||
        c == '|' || c == 'i' || c == 'j' || c == 'l' || c == 'I')
        return 0.32;
    if (c == 'f' || c == 't' || c == 'r' || c == '(' || c == ')' || c == '[' || c == ']' ||
        c == '-')
        return 0.4;
    if (c == 'm' || c == 'w' || c == 'M' || c == 'W' || c == '@')
        return 0.92;
    if (c >= 'A' && c <= 'Z')
        return 0.7;
    if (c < 0x80)
        return 0.62;
    if (c == 0xB2 || c == 0xB3 || c == 0xB9 || (c >= 0x2070 && c <= 0x209F))
        return 0.42;
    if (c >= 0x2E80)
        return 1.0;
    return 0.66;
}

/* Estimated width in pixels of the first max_cp code points of s (with "…" when cut). */
static double text_width(const char *s, size_t max_cp, double fs)
{
    double w = 0;
    size_t k = 0;
    while (*s) {
        if (k == max_cp)
            return (w + 1.0) * fs; /* the ellipsis */
        w += cp_width(next_cp(&s));
        k++;
    }
    return w * fs;
}

static size_t cp_count(const char *s)
{
    size_t k = 0;
    while (*s) {
        next_cp(&s);
        k++;
    }
    return k;
}

/* s as XML text, valid UTF-8, at most max_cp code points (the last one "…" when cut). */
static void put_text(affect_strbuf *sb, const char *s, size_t max_cp)
{
    size_t total = cp_count(s), keep = total > max_cp ? max_cp - 1 : total;
    for (size_t k = 0; k < keep; k++) {
        const char *start = s;
        uint32_t c = next_cp(&s);
        switch (c) {
        case '&':
            affect_strbuf_puts(sb, "&amp;");
            break;
        case '<':
            affect_strbuf_puts(sb, "&lt;");
            break;
        case '>':
            affect_strbuf_puts(sb, "&gt;");
            break;
        case '"':
            affect_strbuf_puts(sb, "&quot;");
            break;
        case '\'':
            affect_strbuf_puts(sb, "&#39;");
            break;
        case 0xFFFD:
            affect_strbuf_puts(sb, "\xef\xbf\xbd");
            break;
        default:
            if (c < 0x20)
                affect_strbuf_putc(sb, '?');
            else
                affect_strbuf_append(sb, start, (size_t)(s - start));
        }
    }
    if (keep < total)
        affect_strbuf_puts(sb, "\xe2\x80\xa6");
}

static bool has_text(const char *s)
{
    return s && *s;
}

/* ---- numbers ---- */

static double clamp_coord(double v)
{
    if (!(v > -PLOT_COORD_LIMIT))
        return -PLOT_COORD_LIMIT;
    return v > PLOT_COORD_LIMIT ? PLOT_COORD_LIMIT : v;
}

static void put_px(affect_strbuf *sb, double v)
{
    affect_strbuf_fixed(sb, clamp_coord(v), 1);
}

/* Decimal digits of v (> 0) into buf, most significant first; returns their count. */
static int digits_of(uint64_t v, char *buf)
{
    char tmp[24];
    int n = 0;
    do {
        tmp[n++] = (char)('0' + v % 10);
        v /= 10;
    } while (v);
    for (int i = 0; i < n; i++)
        buf[i] = tmp[n - 1 - i];
    return n;
}

static const char *const superscript[10] = {
    "\xe2\x81\xb0", "\xc2\xb9",     "\xc2\xb2",     "\xc2\xb3",     "\xe2\x81\xb4",
    "\xe2\x81\xb5", "\xe2\x81\xb6", "\xe2\x81\xb7", "\xe2\x81\xb8", "\xe2\x81\xb9"};
#define MINUS_SIGN "\xe2\x88\x92"

/* Appends s to buf[*o..] if it fits in size (keeping a NUL); false when it does not. */
static bool cat(char *buf, size_t size, size_t *o, const char *s, size_t n)
{
    if (*o + n >= size)
        return false;
    memcpy(buf + *o, s, n);
    *o += n;
    buf[*o] = '\0';
    return true;
}

/* Strips trailing zeros of n into the exponent. */
static void normalize_ne(int64_t *n, int *e)
{
    while (*n != 0 && *n % 10 == 0) {
        *n /= 10;
        (*e)++;
    }
}

/* n × 10^e in fixed notation ("−0.025", "1500"); false if longer than 30 characters. */
static bool format_fixed(int64_t n, int e, char *buf, size_t size)
{
    size_t o = 0;
    char d[24];
    buf[0] = '\0';
    normalize_ne(&n, &e);
    if (n == 0)
        return cat(buf, size, &o, "0", 1);
    if (e > 30 || e < -30)
        return false;
    uint64_t mag = n < 0 ? (uint64_t)0 - (uint64_t)n : (uint64_t)n;
    int nd = digits_of(mag, d);
    if (n < 0 && !cat(buf, size, &o, MINUS_SIGN, 3))
        return false;
    if (e >= 0) {
        if (nd + e > 30 || !cat(buf, size, &o, d, (size_t)nd))
            return false;
        for (int i = 0; i < e; i++)
            if (!cat(buf, size, &o, "0", 1))
                return false;
        return true;
    }
    int frac = -e;
    if (nd > frac) {
        return cat(buf, size, &o, d, (size_t)(nd - frac)) && cat(buf, size, &o, ".", 1) &&
               cat(buf, size, &o, d + nd - frac, (size_t)frac);
    }
    if (!cat(buf, size, &o, "0.", 2))
        return false;
    for (int i = 0; i < frac - nd; i++)
        if (!cat(buf, size, &o, "0", 1))
            return false;
    return cat(buf, size, &o, d, (size_t)nd);
}

/* n × 10^e in scientific notation: "1.5×10⁶", "10⁻⁴", "−2×10³"; exponent 0 gives "1.5". */
static void format_sci(int64_t n, int e, char *buf, size_t size)
{
    size_t o = 0;
    char d[24], ed[24];
    buf[0] = '\0';
    normalize_ne(&n, &e);
    if (n == 0) {
        cat(buf, size, &o, "0", 1);
        return;
    }
    uint64_t mag = n < 0 ? (uint64_t)0 - (uint64_t)n : (uint64_t)n;
    int nd = digits_of(mag, d);
    int ex = e + nd - 1;
    if (n < 0)
        cat(buf, size, &o, MINUS_SIGN, 3);
    bool one = nd == 1 && d[0] == '1';
    if (!one || ex == 0) {
        cat(buf, size, &o, d, 1);
        if (nd > 1) {
            cat(buf, size, &o, ".", 1);
            cat(buf, size, &o, d + 1, (size_t)(nd - 1));
        }
        if (ex == 0)
            return;
        cat(buf, size, &o, "\xc3\x97", 2); /* × */
    }
    cat(buf, size, &o, "10", 2);
    if (ex < 0)
        cat(buf, size, &o, "\xe2\x81\xbb", 3); /* superscript minus */
    int ne = digits_of((uint64_t)(ex < 0 ? -(int64_t)ex : ex), ed);
    for (int i = 0; i < ne; i++)
        cat(buf, size, &o, superscript[ed[i] - '0'], strlen(superscript[ed[i] - '0']));
}

/* ---- axes ---- */

typedef struct axis {
    bool log;
    bool vertical;
    double k;      /* layout scale (fonts, spacing) */
    double lo, hi; /* limits in axis space */
    double p0, p1; /* pixels of lo and hi */
    size_t n_ticks;
    double tick[PLOT_MAX_TICKS]; /* positions in axis space */
    int64_t tn[PLOT_MAX_TICKS];  /* tick value = tn × 10^te */
    int te[PLOT_MAX_TICKS];
    char text[PLOT_MAX_TICKS][PLOT_TICK_TEXT];
    double tw[PLOT_MAX_TICKS]; /* estimated label widths, pixels */
    size_t n_minor;
    double minor[PLOT_MAX_MINOR];
    double max_w; /* widest tick label */
} axis;

/* Pixel of an axis-space value (halves avoid overflow near ±DBL_MAX). */
static double to_px(const axis *a, double v)
{
    double f = (v * 0.5 - a->lo * 0.5) / (a->hi * 0.5 - a->lo * 0.5);
    return a->p0 + f * (a->p1 - a->p0);
}

static double pow10i(int e)
{
    return pow(10.0, (double)e);
}

/* Ticks at the multiples of s × 10^e of the values in [vlo, vhi]; positions are the values,
 * or their log10 when log. Returns false when there would be too many. */
static bool gen_linear(axis *a, double vlo, double vhi, int s, int e)
{
    double step = s * pow10i(e);
    double k0 = ceil(vlo / step), k1 = floor(vhi / step);
    a->n_ticks = 0;
    a->n_minor = 0;
    if (!(k1 - k0 < PLOT_MAX_TICKS) || !(fabs(k0) < 1e17) || !(fabs(k1) < 1e17))
        return false;
    for (int64_t k = (int64_t)k0; k <= (int64_t)k1; k++) {
        int64_t n = k * s;
        double v = (double)n * pow10i(e);
        if (a->log && !(v > 0))
            continue;
        a->tick[a->n_ticks] = a->log ? log10(v) : v;
        a->tn[a->n_ticks] = n;
        a->te[a->n_ticks] = e;
        a->n_ticks++;
    }
    return true;
}

/* Powers of ten every kstep decades; minor ticks at 2..9 × 10^k when kstep is 1. */
static bool gen_decades(axis *a, int kstep)
{
    double k0 = ceil(a->lo), k1 = floor(a->hi);
    a->n_ticks = 0;
    a->n_minor = 0;
    int64_t first = (int64_t)ceil(k0 / kstep) * kstep;
    if ((k1 - first) / kstep >= PLOT_MAX_TICKS)
        return false;
    for (int64_t k = first; k <= (int64_t)k1; k += kstep) {
        a->tick[a->n_ticks] = (double)k;
        a->tn[a->n_ticks] = 1;
        a->te[a->n_ticks] = (int)k;
        a->n_ticks++;
    }
    if (kstep == 1 && a->hi - a->lo <= 12) {
        for (int64_t k = (int64_t)floor(a->lo); k <= (int64_t)k1; k++)
            for (int m = 2; m <= 9; m++) {
                double p = (double)k + log10((double)m);
                if (p > a->lo && p < a->hi && a->n_minor < PLOT_MAX_MINOR)
                    a->minor[a->n_minor++] = p;
            }
    }
    return true;
}

/* 1, 2 and 5 × 10^k; minor ticks at the other digits. */
static void gen_125(axis *a)
{
    a->n_ticks = 0;
    a->n_minor = 0;
    for (int64_t k = (int64_t)floor(a->lo); k <= (int64_t)floor(a->hi); k++)
        for (int m = 1; m <= 9; m++) {
            double p = (double)k + log10((double)m);
            if (!(p >= a->lo && p <= a->hi))
                continue;
            if (m == 1 || m == 2 || m == 5) {
                if (a->n_ticks < PLOT_MAX_TICKS) {
                    a->tick[a->n_ticks] = p;
                    a->tn[a->n_ticks] = m;
                    a->te[a->n_ticks] = (int)k;
                    a->n_ticks++;
                }
            } else if (a->n_minor < PLOT_MAX_MINOR) {
                a->minor[a->n_minor++] = p;
            }
        }
}

/* Formats the tick labels (fixed unless scientific is shorter for long labels) and checks
 * that neighbours do not collide; returns true when they fit. */
static bool label_ticks(axis *a)
{
    size_t max_fixed = 0, max_sci = 0;
    bool fixed_ok = true;
    char sci[PLOT_TICK_TEXT];
    for (size_t i = 0; i < a->n_ticks; i++) {
        if (format_fixed(a->tn[i], a->te[i], a->text[i], PLOT_TICK_TEXT)) {
            size_t k = cp_count(a->text[i]);
            max_fixed = k > max_fixed ? k : max_fixed;
        } else {
            fixed_ok = false;
        }
        format_sci(a->tn[i], a->te[i], sci, sizeof sci);
        size_t k = cp_count(sci);
        max_sci = k > max_sci ? k : max_sci;
    }
    bool use_sci = !fixed_ok || (max_fixed > 6 && max_sci < max_fixed);
    a->max_w = 0;
    for (size_t i = 0; i < a->n_ticks; i++) {
        if (use_sci)
            format_sci(a->tn[i], a->te[i], a->text[i], PLOT_TICK_TEXT);
        a->tw[i] = text_width(a->text[i], SIZE_MAX, PLOT_FS_TICK * a->k);
        a->max_w = fmax(a->max_w, a->tw[i]);
    }
    for (size_t i = 0; i + 1 < a->n_ticks; i++) {
        double gap = fabs(to_px(a, a->tick[i + 1]) - to_px(a, a->tick[i]));
        double need =
            a->vertical ? PLOT_FS_TICK * a->k * 1.3 : (a->tw[i] + a->tw[i + 1]) / 2 + 8 * a->k;
        if (gap < need)
            return false;
    }
    return true;
}

/* Next coarser 1-2-5 step. */
static void coarser(int *s, int *e)
{
    if (*s == 1)
        *s = 2;
    else if (*s == 2)
        *s = 5;
    else {
        *s = 1;
        (*e)++;
    }
}

/* Linear 1-2-5 ticks of the values in [vlo, vhi], about target of them, made coarser until
 * the labels fit. */
static void linear_ticks(axis *a, double vlo, double vhi, double target)
{
    double half = vhi * 0.5 - vlo * 0.5;
    double raw = half / (target * 0.5);
    int e = (int)floor(log10(raw));
    double f = raw / pow10i(e);
    int s = f < 1.4142 ? 1 : f < 3.1623 ? 2 : f < 7.0711 ? 5 : 10; /* nearest, log scale */
    if (s == 10) {
        s = 1;
        e++;
    }
    for (int iter = 0; iter < 60; iter++, coarser(&s, &e)) {
        if (!gen_linear(a, vlo, vhi, s, e))
            continue;
        if (label_ticks(a) || a->n_ticks <= 1)
            return;
    }
}

/* Chooses and labels the ticks of an axis whose limits and pixel extent are set. */
static void build_ticks(axis *a)
{
    double len = fabs(a->p1 - a->p0);
    double target = fmax(2, len / ((a->vertical ? 60 : 85) * a->k));
    if (!a->log) {
        linear_ticks(a, a->lo, a->hi, target);
        return;
    }
    double decades = floor(a->hi) - ceil(a->lo) + 1;
    if (decades < 3) {
        gen_125(a);
        if (a->n_ticks >= 3 && label_ticks(a))
            return;
        double vlo = pow(10, a->lo), vhi = pow(10, a->hi);
        if (isfinite(vhi) && vlo > 0) {
            linear_ticks(a, vlo, vhi, target);
            if (a->n_ticks >= 2)
                return;
        }
    }
    static const int ksteps[] = {1, 2, 3, 5, 10, 20, 30, 50, 100, 200, 300, 500, 1000};
    for (size_t i = 0; i < sizeof ksteps / sizeof ksteps[0]; i++) {
        if (!gen_decades(a, ksteps[i]) || (double)a->n_ticks > target + 1)
            continue;
        if (a->n_ticks == 0)
            break;
        if (label_ticks(a) || a->n_ticks <= 1)
            return;
    }
    gen_125(a); /* a sliver near the top of the double range: whatever 1-2-5 ticks there are */
    label_ticks(a);
}

/* Limits of an axis from the data range [dlo, dhi] in axis space (have = false: no data). */
static void set_limits(axis *a, bool have, double dlo, double dhi)
{
    if (!have) {
        a->lo = 0;
        a->hi = 1;
        return;
    }
    double half = dhi * 0.5 - dlo * 0.5, mid = dlo * 0.5 + dhi * 0.5;
    if (!(half > fabs(mid) * PLOT_DEGENERATE)) {
        half = a->log ? 0.1 : fabs(mid) * PLOT_PAD;
        if (!(half > 0))
            half = 1;
    } else {
        half *= 1 + 2 * PLOT_PAD;
    }
    if (!a->log && half < PLOT_MIN_HALF_SPAN)
        half = PLOT_MIN_HALF_SPAN;
    a->lo = fmax(mid - half, -DBL_MAX);
    a->hi = fmin(mid + half, DBL_MAX);
}

/* ---- rendering ---- */

typedef struct series {
    const char *name;
    uint32_t index; /* in sc->names */
    size_t start;   /* first point in the sorted copy */
    size_t count;   /* points drawn */
    double mean[2], sd[2];
} series;

typedef struct layout {
    double width, height;
    double k;                        /* scale of fonts and spacing: 1 at 560 × 420 and above */
    double left, right, top, bottom; /* plot area */
    axis x, y;
    size_t legend_rows;  /* label rows shown */
    size_t legend_chars; /* labels cut to this many code points */
    bool legend_more;    /* a "+ N more" row */
    double legend_x;
    double radius;
} layout;

static int cmp_series(const void *a, const void *b)
{
    return strcmp(((const series *)a)->name, ((const series *)b)->name);
}

static int cmp_point(const void *a, const void *b)
{
    const point *p = a, *q = b;
    if (p->label != q->label)
        return p->label < q->label ? -1 : 1;
    if (p->x != q->x)
        return p->x < q->x ? -1 : 1;
    if (p->y != q->y)
        return p->y < q->y ? -1 : 1;
    return 0;
}

/* One marker (shape 0 circle, 1 square, 2 triangle, 3 diamond) of radius r at (cx, cy). */
static void put_marker(affect_strbuf *sb, int shape, double cx, double cy, double r)
{
    cx = clamp_coord(cx);
    cy = clamp_coord(cy);
    switch (shape) {
    case 0:
        affect_strbuf_puts(sb, "<circle cx=\"");
        put_px(sb, cx);
        affect_strbuf_puts(sb, "\" cy=\"");
        put_px(sb, cy);
        affect_strbuf_puts(sb, "\" r=\"");
        affect_strbuf_fixed(sb, r, 2);
        affect_strbuf_puts(sb, "\"/>");
        break;
    case 1: {
        double h = r * 0.886;
        affect_strbuf_puts(sb, "<rect x=\"");
        put_px(sb, cx - h);
        affect_strbuf_puts(sb, "\" y=\"");
        put_px(sb, cy - h);
        affect_strbuf_puts(sb, "\" width=\"");
        affect_strbuf_fixed(sb, 2 * h, 2);
        affect_strbuf_puts(sb, "\" height=\"");
        affect_strbuf_fixed(sb, 2 * h, 2);
        affect_strbuf_puts(sb, "\"/>");
        break;
    }
    case 2: {
        double t = r * 1.3;
        affect_strbuf_puts(sb, "<path d=\"M");
        put_px(sb, cx);
        affect_strbuf_putc(sb, ' ');
        put_px(sb, cy - t);
        affect_strbuf_putc(sb, 'L');
        put_px(sb, cx + t * 0.866);
        affect_strbuf_putc(sb, ' ');
        put_px(sb, cy + t * 0.5);
        affect_strbuf_putc(sb, 'L');
        put_px(sb, cx - t * 0.866);
        affect_strbuf_putc(sb, ' ');
        put_px(sb, cy + t * 0.5);
        affect_strbuf_puts(sb, "Z\"/>");
        break;
    }
    default: {
        double d = r * 1.25;
        affect_strbuf_puts(sb, "<path d=\"M");
        put_px(sb, cx);
        affect_strbuf_putc(sb, ' ');
        put_px(sb, cy - d);
        affect_strbuf_putc(sb, 'L');
        put_px(sb, cx + d);
        affect_strbuf_putc(sb, ' ');
        put_px(sb, cy);
        affect_strbuf_putc(sb, 'L');
        put_px(sb, cx);
        affect_strbuf_putc(sb, ' ');
        put_px(sb, cy + d);
        affect_strbuf_putc(sb, 'L');
        put_px(sb, cx - d);
        affect_strbuf_putc(sb, ' ');
        put_px(sb, cy);
        affect_strbuf_puts(sb, "Z\"/>");
    }
    }
}

static void put_text_open(affect_strbuf *sb, const char *cls, double x, double y, double fs,
                          const char *anchor, const char *extra)
{
    affect_strbuf_printf(sb, "<text class=\"%s\" x=\"", cls);
    put_px(sb, x);
    affect_strbuf_puts(sb, "\" y=\"");
    put_px(sb, y);
    affect_strbuf_puts(sb, "\" font-size=\"");
    affect_strbuf_fixed(sb, fs, 1);
    affect_strbuf_printf(sb, "\" text-anchor=\"%s\"%s>", anchor, extra);
}

/* Estimated width of the legend text of series s: "label (count)". */
static double legend_width(const series *s, size_t chars, double fs)
{
    char num[32];
    size_t o = 0;
    num[o++] = ' ';
    num[o++] = '(';
    o += (size_t)digits_of(s->count, num + o);
    num[o++] = ')';
    num[o] = '\0';
    return text_width(s->name, chars, fs) + text_width(num, SIZE_MAX, fs);
}

/* Plot area, legend size and both axes. */
static void plan(layout *L, const affect_plot_options *opt, const series *ser, size_t n_series,
                 bool have, const double lim[4], size_t n_skipped)
{
    L->width = opt->width;
    L->height = opt->height;
    L->radius = opt->radius;
    double k = fmin(1, fmax(0.5, fmin(L->width / 560, L->height / 420)));
    L->k = k;
    L->top = floor((has_text(opt->title) ? 40 : 16) * k);
    double below = (PLOT_TICK_LEN + PLOT_FS_TICK + 8) * k;
    if (has_text(opt->x_label))
        below += (PLOT_FS_AXIS + 10) * k;
    below += (n_skipped ? PLOT_FS_NOTE + 12 : 6) * k;
    L->bottom = floor(fmax(L->height - below, L->top + 0.35 * L->height)); /* tiny plots */
    /* y axis first: its labels decide the left margin */
    memset(&L->y, 0, sizeof L->y);
    L->y.log = opt->log_y;
    L->y.vertical = true;
    L->y.k = k;
    set_limits(&L->y, have, lim[2], lim[3]);
    L->y.p0 = L->bottom;
    L->y.p1 = L->top;
    build_ticks(&L->y);
    double left = L->y.max_w + (10 + PLOT_TICK_LEN + 4) * k;
    if (has_text(opt->y_label))
        left += (PLOT_FS_AXIS + 8) * k;
    L->left = ceil(fmin(left, 0.3 * L->width));
    /* legend: rows that fit the plot's height, label length that fits 30 % of the width */
    size_t rows_fit = (size_t)fmax(1, floor((L->bottom - L->top) / (PLOT_LEGEND_ROW * k)));
    size_t wanted = n_series + (opt->means ? 1 : 0);
    L->legend_more = wanted > rows_fit;
    L->legend_rows = L->legend_more ? rows_fit - 1 : n_series;
    if (L->legend_rows > n_series)
        L->legend_rows = n_series;
    double marker = 18 * k, cap = 0.3 * L->width, w = 0, fs = PLOT_FS_LEGEND * k;
    L->legend_chars = PLOT_LEGEND_CHARS;
    for (;;) {
        w = opt->means ? text_width("mean \xc2\xb1 1 sd", SIZE_MAX, fs) : 0;
        if (L->legend_more)
            w = fmax(w, text_width("+ 0000000000 more", SIZE_MAX, fs));
        for (size_t i = 0; i < L->legend_rows; i++)
            w = fmax(w, legend_width(&ser[i], L->legend_chars, fs));
        if (marker + w <= cap || L->legend_chars <= 4)
            break;
        L->legend_chars--;
    }
    double legend_w = fmin(marker + w, cap);
    L->right = floor(L->width - (12 + 14) * k - legend_w);
    L->legend_x = L->right + 14 * k;
    memset(&L->x, 0, sizeof L->x);
    L->x.log = opt->log_x;
    L->x.k = k;
    set_limits(&L->x, have, lim[0], lim[1]);
    L->x.p0 = L->left;
    L->x.p1 = L->right;
    build_ticks(&L->x);
}

static void write_grid(affect_strbuf *sb, const layout *L)
{
    const axis *x = &L->x, *y = &L->y;
    /* grid: minor (log axes) then major */
    if (x->n_minor || y->n_minor) {
        affect_strbuf_puts(sb, "<path class=\"grid-minor\" stroke=\"#f1f1f1\" d=\"");
        for (size_t i = 0; i < x->n_minor; i++) {
            affect_strbuf_putc(sb, 'M');
            put_px(sb, to_px(x, x->minor[i]));
            affect_strbuf_putc(sb, ' ');
            put_px(sb, L->top);
            affect_strbuf_putc(sb, 'V');
            put_px(sb, L->bottom);
        }
        for (size_t i = 0; i < y->n_minor; i++) {
            affect_strbuf_putc(sb, 'M');
            put_px(sb, L->left);
            affect_strbuf_putc(sb, ' ');
            put_px(sb, to_px(y, y->minor[i]));
            affect_strbuf_putc(sb, 'H');
            put_px(sb, L->right);
        }
        affect_strbuf_puts(sb, "\"/>\n");
    }
    affect_strbuf_puts(sb, "<path class=\"grid\" stroke=\"#e3e3e3\" d=\"");
    for (size_t i = 0; i < x->n_ticks; i++) {
        affect_strbuf_putc(sb, 'M');
        put_px(sb, to_px(x, x->tick[i]));
        affect_strbuf_putc(sb, ' ');
        put_px(sb, L->top);
        affect_strbuf_putc(sb, 'V');
        put_px(sb, L->bottom);
    }
    for (size_t i = 0; i < y->n_ticks; i++) {
        affect_strbuf_putc(sb, 'M');
        put_px(sb, L->left);
        affect_strbuf_putc(sb, ' ');
        put_px(sb, to_px(y, y->tick[i]));
        affect_strbuf_putc(sb, 'H');
        put_px(sb, L->right);
    }
    affect_strbuf_puts(sb, "\"/>\n");
}

/* One tick mark: "M x y" then a relative move cmd ('v' or 'h') by len. */
static void put_tick(affect_strbuf *sb, double x, double y, char cmd, double len)
{
    affect_strbuf_putc(sb, 'M');
    put_px(sb, x);
    affect_strbuf_putc(sb, ' ');
    put_px(sb, y);
    affect_strbuf_putc(sb, cmd);
    affect_strbuf_fixed(sb, len, 2);
}

static void write_frame(affect_strbuf *sb, const layout *L, const affect_plot_options *opt)
{
    const axis *x = &L->x, *y = &L->y;
    double k = L->k, fs_tick = PLOT_FS_TICK * k, fs_axis = PLOT_FS_AXIS * k;
    double major = PLOT_TICK_LEN * k, minor = 0.6 * PLOT_TICK_LEN * k;
    affect_strbuf_puts(sb, "<rect class=\"frame\" x=\"");
    put_px(sb, L->left);
    affect_strbuf_puts(sb, "\" y=\"");
    put_px(sb, L->top);
    affect_strbuf_puts(sb, "\" width=\"");
    put_px(sb, L->right - L->left);
    affect_strbuf_puts(sb, "\" height=\"");
    put_px(sb, L->bottom - L->top);
    affect_strbuf_puts(sb, "\" fill=\"none\" stroke=\"#555\"/>\n");
    affect_strbuf_puts(sb, "<path class=\"ticks\" stroke=\"#555\" d=\"");
    for (size_t i = 0; i < x->n_ticks; i++)
        put_tick(sb, to_px(x, x->tick[i]), L->bottom, 'v', major);
    for (size_t i = 0; i < x->n_minor; i++)
        put_tick(sb, to_px(x, x->minor[i]), L->bottom, 'v', minor);
    for (size_t i = 0; i < y->n_ticks; i++)
        put_tick(sb, L->left, to_px(y, y->tick[i]), 'h', -major);
    for (size_t i = 0; i < y->n_minor; i++)
        put_tick(sb, L->left, to_px(y, y->minor[i]), 'h', -minor);
    affect_strbuf_puts(sb, "\"/>\n<g fill=\"#333\">\n");
    for (size_t i = 0; i < x->n_ticks; i++) {
        put_text_open(sb, "tick-x", to_px(x, x->tick[i]), L->bottom + major + fs_tick + 2 * k,
                      fs_tick, "middle", "");
        affect_strbuf_puts(sb, x->text[i]);
        affect_strbuf_puts(sb, "</text>\n");
    }
    for (size_t i = 0; i < y->n_ticks; i++) {
        put_text_open(sb, "tick-y", L->left - major - 3 * k, to_px(y, y->tick[i]) + fs_tick * 0.35,
                      fs_tick, "end", "");
        affect_strbuf_puts(sb, y->text[i]);
        affect_strbuf_puts(sb, "</text>\n");
    }
    affect_strbuf_puts(sb, "</g>\n");
    if (has_text(opt->x_label)) {
        put_text_open(sb, "axis-title", (L->left + L->right) / 2,
                      L->bottom + major + fs_tick + 12 * k + fs_axis, fs_axis, "middle",
                      " fill=\"#222\"");
        put_text(sb, opt->x_label, PLOT_TITLE_CHARS);
        affect_strbuf_puts(sb, "</text>\n");
    }
    if (has_text(opt->y_label)) {
        /* just left of the widest tick label (the margin was sized for it) */
        double cx = fmax(L->left - major - 3 * k - y->max_w - 8 * k - fs_axis * 0.2, fs_axis * 0.8);
        double cy = (L->top + L->bottom) / 2;
        affect_strbuf_puts(sb, "<text class=\"axis-title\" transform=\"translate(");
        put_px(sb, cx);
        affect_strbuf_putc(sb, ' ');
        put_px(sb, cy);
        affect_strbuf_puts(sb, ") rotate(-90)\" font-size=\"");
        affect_strbuf_fixed(sb, fs_axis, 1);
        affect_strbuf_puts(sb, "\" text-anchor=\"middle\" fill=\"#222\">");
        put_text(sb, opt->y_label, PLOT_TITLE_CHARS);
        affect_strbuf_puts(sb, "</text>\n");
    }
}

static void write_points(affect_strbuf *sb, const layout *L, const series *ser, size_t n_series,
                         const point *pts)
{
    affect_strbuf_puts(sb, "<g class=\"points\" fill-opacity=\"0.78\" stroke=\"#000\" "
                           "stroke-opacity=\"0.4\" stroke-width=\"0.6\">\n");
    for (size_t i = 0; i < n_series; i++) {
        const series *s = &ser[i];
        affect_strbuf_puts(sb, "<g class=\"series\" data-label=\"");
        put_text(sb, s->name, SIZE_MAX);
        affect_strbuf_printf(sb, "\" data-count=\"%zu\" fill=\"%s\">", s->count, palette[i % 8]);
        for (size_t k = 0; k < s->count; k++) {
            const point *p = &pts[s->start + k];
            put_marker(sb, (int)(i / 8 % 4), to_px(&L->x, p->x), to_px(&L->y, p->y), L->radius);
        }
        affect_strbuf_puts(sb, "</g>\n");
    }
    affect_strbuf_puts(sb, "</g>\n");
}

/* Time-series mode: each label's points (sorted by x, then y) joined by one path in its colour;
 * a label with a single point gets its marker, as a path of one point would not show. */
static void write_lines(affect_strbuf *sb, const layout *L, const series *ser, size_t n_series,
                        const point *pts)
{
    affect_strbuf_puts(sb, "<g class=\"lines\" fill=\"none\" stroke-width=\"");
    affect_strbuf_fixed(sb, 1.6 * L->k, 2);
    affect_strbuf_puts(sb, "\" stroke-linejoin=\"round\" stroke-linecap=\"round\">\n");
    for (size_t i = 0; i < n_series; i++) {
        const series *s = &ser[i];
        affect_strbuf_puts(sb, "<g class=\"series\" data-label=\"");
        put_text(sb, s->name, SIZE_MAX);
        affect_strbuf_printf(sb, "\" data-count=\"%zu\" stroke=\"%s\">", s->count, palette[i % 8]);
        if (s->count == 1) {
            const point *p = &pts[s->start];
            affect_strbuf_printf(sb, "<g fill=\"%s\" stroke=\"none\">", palette[i % 8]);
            put_marker(sb, (int)(i / 8 % 4), to_px(&L->x, p->x), to_px(&L->y, p->y), L->radius);
            affect_strbuf_puts(sb, "</g>");
        } else if (s->count > 1) {
            affect_strbuf_puts(sb, "<path d=\"");
            for (size_t k = 0; k < s->count; k++) {
                const point *p = &pts[s->start + k];
                affect_strbuf_putc(sb, k ? 'L' : 'M');
                put_px(sb, clamp_coord(to_px(&L->x, p->x)));
                affect_strbuf_putc(sb, ' ');
                put_px(sb, clamp_coord(to_px(&L->y, p->y)));
            }
            affect_strbuf_puts(sb, "\"/>");
        }
        affect_strbuf_puts(sb, "</g>\n");
    }
    affect_strbuf_puts(sb, "</g>\n");
}

/* The path of a cross: bars of ± sd with end caps (nothing when sd is 0 on both axes). */
static void cross_path(affect_strbuf *sb, const layout *L, const series *s)
{
    double cx = to_px(&L->x, s->mean[0]), cy = to_px(&L->y, s->mean[1]);
    double x0 = to_px(&L->x, s->mean[0] - s->sd[0]), x1 = to_px(&L->x, s->mean[0] + s->sd[0]);
    double y0 = to_px(&L->y, s->mean[1] - s->sd[1]), y1 = to_px(&L->y, s->mean[1] + s->sd[1]);
    double cap = 4 * L->k;
    affect_strbuf_putc(sb, 'M');
    put_px(sb, x0);
    affect_strbuf_putc(sb, ' ');
    put_px(sb, cy);
    affect_strbuf_putc(sb, 'H');
    put_px(sb, x1);
    affect_strbuf_putc(sb, 'M');
    put_px(sb, cx);
    affect_strbuf_putc(sb, ' ');
    put_px(sb, y0);
    affect_strbuf_putc(sb, 'V');
    put_px(sb, y1);
    double caps[4][2] = {{x0, cy}, {x1, cy}, {cx, y0}, {cx, y1}};
    for (int c = 0; c < 4; c++) {
        affect_strbuf_putc(sb, 'M');
        if (c < 2) {
            put_px(sb, caps[c][0]);
            affect_strbuf_putc(sb, ' ');
            put_px(sb, caps[c][1] - cap);
            affect_strbuf_putc(sb, 'V');
            put_px(sb, caps[c][1] + cap);
        } else {
            put_px(sb, caps[c][0] - cap);
            affect_strbuf_putc(sb, ' ');
            put_px(sb, caps[c][1]);
            affect_strbuf_putc(sb, 'H');
            put_px(sb, caps[c][0] + cap);
        }
    }
}

static void write_means(affect_strbuf *sb, const layout *L, const series *ser, size_t n_series)
{
    affect_strbuf_puts(sb, "<g class=\"means\" fill=\"none\" stroke-linecap=\"round\">\n");
    for (size_t i = 0; i < n_series; i++) {
        const series *s = &ser[i];
        if (s->count == 0)
            continue;
        affect_strbuf_puts(sb, "<g class=\"mean\" data-label=\"");
        put_text(sb, s->name, SIZE_MAX);
        affect_strbuf_printf(sb, "\" data-n=\"%zu\" data-mean-x=\"", s->count);
        affect_strbuf_double(sb, s->mean[0]);
        affect_strbuf_puts(sb, "\" data-mean-y=\"");
        affect_strbuf_double(sb, s->mean[1]);
        affect_strbuf_puts(sb, "\" data-sd-x=\"");
        affect_strbuf_double(sb, s->sd[0]);
        affect_strbuf_puts(sb, "\" data-sd-y=\"");
        affect_strbuf_double(sb, s->sd[1]);
        affect_strbuf_puts(sb, "\">");
        if (s->count >= 2) {
            affect_strbuf_puts(sb, "<path stroke=\"#fff\" stroke-width=\"");
            affect_strbuf_fixed(sb, 4.5 * L->k, 2);
            affect_strbuf_puts(sb, "\" d=\"");
            cross_path(sb, L, s);
            affect_strbuf_printf(sb, "\"/><path stroke=\"%s\" stroke-width=\"", palette[i % 8]);
            affect_strbuf_fixed(sb, 2 * L->k, 2);
            affect_strbuf_puts(sb, "\" d=\"");
            cross_path(sb, L, s);
            affect_strbuf_puts(sb, "\"/>");
        }
        affect_strbuf_puts(sb, "</g>\n");
    }
    /* the markers over every cross, so that no label's bars hide another's mean */
    affect_strbuf_puts(sb, "<g class=\"mean-markers\" stroke=\"#000\" stroke-width=\"1.2\">");
    for (size_t i = 0; i < n_series; i++) {
        const series *s = &ser[i];
        if (s->count == 0)
            continue;
        affect_strbuf_printf(sb, "<g fill=\"%s\">", palette[i % 8]);
        put_marker(sb, (int)(i / 8 % 4), to_px(&L->x, s->mean[0]), to_px(&L->y, s->mean[1]),
                   fmax(L->radius * 1.8, 4.5 * L->k));
        affect_strbuf_puts(sb, "</g>");
    }
    affect_strbuf_puts(sb, "</g>\n</g>\n");
}

static void write_legend(affect_strbuf *sb, const layout *L, const affect_plot_options *opt,
                         const series *ser, size_t n_series)
{
    double k = L->k, row = PLOT_LEGEND_ROW * k, fs = PLOT_FS_LEGEND * k;
    double r = fmin(fmax(L->radius, 3.5 * k), 6 * k);
    double x = L->legend_x, y = L->top + 4 * k + row / 2;
    affect_strbuf_puts(sb, "<g class=\"legend\" fill=\"#222\">\n");
    for (size_t i = 0; i < L->legend_rows; i++, y += row) {
        const series *s = &ser[i];
        if (opt->lines) { /* a short stretch of the line */
            affect_strbuf_printf(sb,
                                 "<g class=\"legend-item\"><path fill=\"none\" "
                                 "stroke=\"%s\" stroke-width=\"",
                                 palette[i % 8]);
            affect_strbuf_fixed(sb, 2 * k, 2);
            affect_strbuf_puts(sb, "\" d=\"");
            put_tick(sb, x, y, 'h', 12 * k);
            affect_strbuf_puts(sb, "\"/>");
        } else {
            affect_strbuf_printf(sb,
                                 "<g class=\"legend-item\"><g fill=\"%s\" stroke=\"#000\" "
                                 "stroke-opacity=\"0.4\" stroke-width=\"0.6\">",
                                 palette[i % 8]);
            put_marker(sb, (int)(i / 8 % 4), x + 6 * k, y, r);
            affect_strbuf_puts(sb, "</g>");
        }
        put_text_open(sb, "legend-text", x + 18 * k, y + fs * 0.35, fs, "start", "");
        put_text(sb, s->name, L->legend_chars);
        affect_strbuf_printf(sb, " <tspan fill=\"#777\">(%zu)</tspan></text></g>\n", s->count);
    }
    if (L->legend_more) {
        put_text_open(sb, "legend-more", x + 18 * k, y + fs * 0.35, fs, "start", " fill=\"#777\"");
        affect_strbuf_printf(sb, "+ %zu more</text>\n", n_series - L->legend_rows);
        y += row;
    }
    if (opt->means) {
        affect_strbuf_puts(sb, "<g class=\"legend-item\"><path fill=\"none\" stroke=\"#555\" "
                               "stroke-width=\"2\" d=\"");
        put_tick(sb, x, y, 'h', 12 * k);
        put_tick(sb, x + 6 * k, y - 6 * k, 'v', 12 * k);
        affect_strbuf_puts(sb, "\"/>");
        put_text_open(sb, "legend-text", x + 18 * k, y + fs * 0.35, fs, "start", "");
        affect_strbuf_puts(sb, "mean \xc2\xb1 1 sd</text></g>\n");
    }
    affect_strbuf_puts(sb, "</g>\n");
}

static void write_document(affect_strbuf *sb, const layout *L, const affect_plot_options *opt,
                           const series *ser, size_t n_series, const point *pts, size_t drawn,
                           size_t n_added, size_t n_nonfinite, size_t n_nonpos)
{
    affect_strbuf_printf(sb,
                         "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" "
                         "viewBox=\"0 0 %d %d\" font-family=\"sans-serif\">\n",
                         (int)L->width, (int)L->height, (int)L->width, (int)L->height);
    affect_strbuf_puts(sb, "<rect width=\"100%\" height=\"100%\" fill=\"#fff\"/>\n");
    if (has_text(opt->title)) {
        put_text_open(sb, "title", (L->left + L->right) / 2, 25 * L->k, PLOT_FS_TITLE * L->k,
                      "middle", " font-weight=\"bold\" fill=\"#222\"");
        put_text(sb, opt->title, PLOT_TITLE_CHARS);
        affect_strbuf_puts(sb, "</text>\n");
    }
    affect_strbuf_puts(sb, "<g shape-rendering=\"crispEdges\" fill=\"none\">\n");
    write_grid(sb, L);
    affect_strbuf_puts(sb, "</g>\n");
    if (opt->lines)
        write_lines(sb, L, ser, n_series, pts);
    else
        write_points(sb, L, ser, n_series, pts);
    if (opt->means)
        write_means(sb, L, ser, n_series);
    affect_strbuf_puts(sb, "<g shape-rendering=\"crispEdges\">\n");
    write_frame(sb, L, opt);
    affect_strbuf_puts(sb, "</g>\n");
    write_legend(sb, L, opt, ser, n_series);
    if (drawn == 0) {
        put_text_open(sb, "no-data", (L->left + L->right) / 2, (L->top + L->bottom) / 2 + 5 * L->k,
                      14 * L->k, "middle", " fill=\"#888\"");
        affect_strbuf_puts(sb, "no data</text>\n");
    }
    if (n_nonfinite + n_nonpos > 0) {
        put_text_open(sb, "note", 10 * L->k, L->height - 8 * L->k, PLOT_FS_NOTE * L->k, "start",
                      " fill=\"#777\"");
        affect_strbuf_printf(sb, "skipped %zu of %zu points: ", n_nonfinite + n_nonpos, n_added);
        if (n_nonfinite)
            affect_strbuf_printf(sb, "%zu not finite", n_nonfinite);
        if (n_nonfinite && n_nonpos)
            affect_strbuf_puts(sb, ", ");
        if (n_nonpos)
            affect_strbuf_printf(sb, "%zu \xe2\x89\xa4 0 on a log axis", n_nonpos);
        affect_strbuf_puts(sb, "</text>\n");
    }
    affect_strbuf_puts(sb, "</svg>\n");
}

/* Means and sample standard deviations of each series, in axis space. */
static void series_stats(series *ser, size_t n_series, const point *pts)
{
    for (size_t i = 0; i < n_series; i++) {
        series *s = &ser[i];
        s->mean[0] = s->mean[1] = s->sd[0] = s->sd[1] = 0;
        if (s->count == 0)
            continue;
        double sx = 0, sy = 0;
        for (size_t k = 0; k < s->count; k++) {
            sx += pts[s->start + k].x;
            sy += pts[s->start + k].y;
        }
        s->mean[0] = sx / (double)s->count;
        s->mean[1] = sy / (double)s->count;
        if (s->count < 2)
            continue;
        double vx = 0, vy = 0;
        for (size_t k = 0; k < s->count; k++) {
            double dx = pts[s->start + k].x - s->mean[0], dy = pts[s->start + k].y - s->mean[1];
            vx += dx * dx;
            vy += dy * dy;
        }
        s->sd[0] = sqrt(vx / (double)(s->count - 1));
        s->sd[1] = sqrt(vy / (double)(s->count - 1));
        if (!isfinite(s->sd[0]))
            s->sd[0] = 0;
        if (!isfinite(s->sd[1]))
            s->sd[1] = 0;
        if (!isfinite(s->mean[0]) || !isfinite(s->mean[1])) { /* sums overflowed */
            s->mean[0] = pts[s->start + s->count / 2].x;
            s->mean[1] = pts[s->start + s->count / 2].y;
            s->sd[0] = s->sd[1] = 0;
        }
    }
}

affect_status affect_scatter_render(const affect_scatter *sc, const affect_plot_options *opt,
                                    char **out, size_t *len, affect_error *err)
{
    affect_plot_options defaults;
    affect_strbuf sb;
    affect_status st;
    point *pts = NULL;
    series *ser = NULL;
    uint32_t *rank = NULL;
    layout *L = NULL;
    affect_strbuf_init(&sb);
    *out = NULL;
    if (len)
        *len = 0;
    if (!opt) {
        affect_plot_options_default(&defaults);
        opt = &defaults;
    }
    if ((st = affect_plot_options_check(opt, err)) != AFFECT_OK)
        goto cleanup;
    size_t n_series = sc->n_labels;
    pts = affect_malloc_array(sc->n ? sc->n : 1, sizeof *pts);
    ser = affect_calloc(n_series ? n_series : 1, sizeof *ser);
    rank = affect_malloc_array(n_series ? n_series : 1, sizeof *rank);
    L = affect_calloc(1, sizeof *L);
    if (!pts || !ser || !rank || !L) {
        st = affect_nomem(err);
        goto cleanup;
    }
    for (uint32_t i = 0; i < sc->n_labels; i++) {
        ser[i].name = sc->names[i];
        ser[i].index = i;
    }
    qsort(ser, n_series, sizeof *ser, cmp_series);
    for (size_t i = 0; i < n_series; i++)
        rank[ser[i].index] = (uint32_t)i;
    /* the points to draw, in axis space, sorted by (label rank, x, y) */
    size_t drawn = 0, n_nonpos = 0;
    for (size_t k = 0; k < sc->n; k++) {
        const point *p = &sc->pts[k];
        if ((opt->log_x && !(p->x > 0)) || (opt->log_y && !(p->y > 0))) {
            n_nonpos++;
            continue;
        }
        pts[drawn].x = opt->log_x ? log10(p->x) : p->x;
        pts[drawn].y = opt->log_y ? log10(p->y) : p->y;
        pts[drawn].label = rank[p->label];
        ser[rank[p->label]].count++;
        drawn++;
    }
    qsort(pts, drawn, sizeof *pts, cmp_point);
    size_t start = 0;
    for (size_t i = 0; i < n_series; i++) {
        ser[i].start = start;
        start += ser[i].count;
    }
    series_stats(ser, n_series, pts);
    double lim[4] = {HUGE_VAL, -HUGE_VAL, HUGE_VAL, -HUGE_VAL};
    for (size_t k = 0; k < drawn; k++) {
        lim[0] = fmin(lim[0], pts[k].x);
        lim[1] = fmax(lim[1], pts[k].x);
        lim[2] = fmin(lim[2], pts[k].y);
        lim[3] = fmax(lim[3], pts[k].y);
    }
    if (opt->means) {
        for (size_t i = 0; i < n_series; i++) {
            const series *s = &ser[i];
            if (s->count < 2)
                continue;
            lim[0] = fmin(lim[0], fmax(s->mean[0] - s->sd[0], -DBL_MAX));
            lim[1] = fmax(lim[1], fmin(s->mean[0] + s->sd[0], DBL_MAX));
            lim[2] = fmin(lim[2], fmax(s->mean[1] - s->sd[1], -DBL_MAX));
            lim[3] = fmax(lim[3], fmin(s->mean[1] + s->sd[1], DBL_MAX));
        }
    }
    plan(L, opt, ser, n_series, drawn > 0, lim, sc->n_nonfinite + n_nonpos);
    write_document(&sb, L, opt, ser, n_series, pts, drawn, sc->n_added, sc->n_nonfinite, n_nonpos);
    st = affect_strbuf_finish(&sb, out, len, err);
cleanup:
    affect_strbuf_free(&sb);
    affect_free(pts);
    affect_free(ser);
    affect_free(rank);
    affect_free(L);
    return st;
}
