/*
 * laban_search.c — the laban index's queries as arithmetic (affect/laban.h, "search of
 * standardized vectors"): the masked distance, the k nearest rows kept in a bounded max-heap,
 * the relative radius ball, and the tie rule (distance, then id) that orders the hits.
 *
 * The index (ext/vt_laban.c) keeps its rows' z-scores in memory and calls
 * affect_laban_search_run once per query; the arithmetic here is what it answers with, so its
 * order of operations is fixed: the squared differences are summed in the order of comp, in
 * double, and the distance is the sqrt of that sum (the README's outputs and the SQL specs
 * print these distances).
 *
 * The heap. For k > 0 the hits array is a max-heap (by the tie rule) of the k best rows seen so
 * far: a row enters while the heap is not full, then only when it is better than the root, which
 * it replaces before sifting down. At the end the array is sorted. For the radius the array
 * holds every qualifying row, then keeps those within radius · the largest distance (or the
 * nearest one alone when none is: a small radius, or a NaN one), then is sorted.
 */
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>

#include "affect/laban.h"

/* The sum of squares over the components present in both, in *sum; false when there is none. */
static inline bool sum_squares(const double *q, const double *x, const int *comp, int n_comp,
                               double *sum)
{
    double s = 0;
    int used = 0;
    for (int t = 0; t < n_comp; t++) {
        double diff = q[comp[t]] - x[comp[t]];
        if (!isnan(diff)) {
            s += diff * diff;
            used++;
        }
    }
    *sum = s;
    return used > 0;
}

double affect_laban_distance(const double *q, const double *x, const int *comp, int n_comp)
{
    double s;
    return sum_squares(q, x, comp, n_comp, &s) ? sqrt(s) : NAN;
}

/* Static, so that it inlines: the exported name of a shared library could be interposed, and
 * the compiler calls it through the PLT (2.6 × slower searches of 2 components, measured). */
static inline int hit_cmp(const affect_laban_hit *a, const affect_laban_hit *b)
{
    if (a->d != b->d)
        return a->d < b->d ? -1 : 1;
    return (a->id > b->id) - (a->id < b->id);
}

int affect_laban_hit_cmp(const affect_laban_hit *a, const affect_laban_hit *b)
{
    return hit_cmp(a, b);
}

static int hit_qsort(const void *a, const void *b)
{
    return hit_cmp(a, b);
}

/* Keeps the cap smallest hits seen so far in a max-heap h of *n entries. */
static void heap_offer(affect_laban_hit *h, size_t *n, size_t cap, affect_laban_hit x)
{
    size_t i;
    if (*n < cap) {
        for (i = (*n)++; i > 0; i = (i - 1) / 2) {
            if (hit_cmp(&h[(i - 1) / 2], &x) >= 0)
                break;
            h[i] = h[(i - 1) / 2];
        }
        h[i] = x;
        return;
    }
    if (hit_cmp(&x, &h[0]) >= 0)
        return;
    for (i = 0;;) {
        size_t l = 2 * i + 1, big = l;
        if (l >= cap)
            break;
        if (l + 1 < cap && hit_cmp(&h[l + 1], &h[l]) > 0)
            big = l + 1;
        if (hit_cmp(&h[big], &x) <= 0)
            break;
        h[i] = h[big];
        i = big;
    }
    h[i] = x;
}

size_t affect_laban_search_capacity(const affect_laban_search *s)
{
    size_t cap = s->hi > s->lo ? s->hi - s->lo : 0;
    if (s->k > 0 && s->k < cap)
        cap = (size_t)s->k;
    return cap;
}

void affect_laban_search_run(const affect_laban_search *s, const double *q, affect_laban_hit *hits,
                             size_t *n_hits)
{
    size_t cap = affect_laban_search_capacity(s), n = 0;
    double dmax = 0;
    affect_laban_hit nearest = {INFINITY, 0, 0};
    /* in locals: the stores into hits could alias *s as far as the compiler knows */
    const double *z = s->z;
    const int64_t *ids = s->ids;
    const int32_t *label = s->label;
    const unsigned char *label_ok = s->label_ok;
    const int *comp = s->comp;
    const int n_comp = s->n_comp;
    const size_t self = s->self, hi = s->hi;
    const bool knn = s->k > 0;
    for (size_t i = s->lo; i < hi; i++) {
        if (i == self || (label_ok && (label[i] < 0 || !label_ok[label[i]])))
            continue;
        double s2;
        if (!sum_squares(q, z + i * AFFECT_LABAN_N, comp, n_comp, &s2))
            continue; /* nothing in common with the query */
        affect_laban_hit h = {sqrt(s2), ids[i], i};
        if (knn) {
            heap_offer(hits, &n, cap, h);
        } else {
            hits[n++] = h;
            if (h.d > dmax)
                dmax = h.d;
            if (hit_cmp(&h, &nearest) < 0)
                nearest = h;
        }
    }
    if (s->k == 0 && n > 0) {
        double limit = s->radius * dmax;
        size_t kept = 0;
        for (size_t i = 0; i < n; i++)
            if (hits[i].d <= limit)
                hits[kept++] = hits[i];
        if (kept == 0)
            hits[kept++] = nearest;
        n = kept;
    }
    qsort(hits, n, sizeof *hits, hit_qsort);
    *n_hits = n;
}
