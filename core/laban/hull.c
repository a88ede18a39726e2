/*
 * hull.c — convex hulls for the Laban Shape descriptors (see affect/laban.h): the area of the
 * 2-D hull of the joints projected on the horizontal plane (Shape Shaping, horizontal) and the
 * volume of the 3-D hull of all joints of a frame (Shape Flow).
 *
 * Usage:
 *     double scratch[4 * 27];
 *     double area = affect_hull_area_2d(xy, 27, scratch);      // xy: 27 interleaved (x, y)
 *
 *     affect_hull3d *h = affect_hull3d_new(27);               // once; NULL when out of memory
 *     for (each frame)
 *         volume = affect_hull3d_volume(h, xyz, 27);           // allocates nothing
 *     affect_hull3d_free(h);
 *
 * Results. Area: 0 when n < 3 or the points are collinear. Volume: −1 when n > max_points (or
 * h is NULL), 0 when n < 4 or the points are collinear, coplanar or identical. Both are NaN
 * when a coordinate is not finite (n ≥ 3, resp. n ≥ 4). "Collinear" and "coplanar" mean
 * within HULL_FLAT·L (L = the longest side of the points' bounding box) of a line or plane;
 * for the area, a hull of at most HULL_FLAT·L² counts as collinear. Same input, same bits.
 *
 * Exact decisions on a grid. Every decision of both algorithms (which side of a line or of a
 * plane a point lies on) is made exactly, because an inexact one is not merely imprecise: a
 * wrong answer for two points a billionth apart can tilt a tiny face and make a far point
 * look outside, and the volume is then wrong by tens of percent. So the points are first
 * mapped onto an integer grid, X = round((x − c) / L · 2^30) with c the centre of the
 * bounding box (|X| ≤ 2^29), which moves each point by at most 0.87 · 2^-30 · L (a relative
 * change of the result of about 10^-9, far below the precision of motion capture); scale and
 * position do not matter. On the grid, differences of coordinates have at most 30 bits and
 * the 2-D cross product (b − a) × (c − a) is exact in 64-bit integers. A 3-D orientation
 * n · (q − a) with n = (b − a) × (c − a) (exact in 62 bits) needs 93 bits: it is first
 * computed in doubles as nd · q − nd · a (nd = n rounded) and trusted when its magnitude
 * exceeds 2e-15 · Σ|n_i| · 2^30, over three times the worst rounding error (10 units of
 * 2^-53 on Σ|n_i| · 2^29), which is almost always; otherwise it is 0 if q is a vertex of the
 * face (duplicate points), else computed exactly with n split as n_hi · 2^31 + n_lo
 * (0 ≤ n_lo < 2^31), so that both partial sums fit in 64 bits. The hull of the grid points is
 * therefore exact; its area or volume is then summed in doubles (all terms of the volume are
 * positive) and scaled back by (L · 2^-30)² or ³.
 *
 * 2-D: Andrew's monotone chain. Each grid point becomes one 64-bit key, x in the high bits
 * and y in the low, so that sorting keys sorts points by (x, y); the keys are written into
 * scratch[0, n), those strictly inside the quadrilateral of the extreme points along x and y
 * are dropped (exact; never a vertex of the hull, so the chains and the area's bits are
 * unchanged) and the rest are sorted —
 * insertion sort up to 32 points, a bottom-up merge sort through scratch[n, 2n) above; the lower
 * and the upper chain are then built in turn in scratch[n, 2n) (a point stays only on a strict left
 * turn, so duplicates and collinear points drop out) and the shoelace sum is accumulated over both.
 * Only 2n of the 4n doubles of scratch are used.
 *
 * 3-D: Quickhull (Barber, Dobkin & Huhdanpaa 1996) on a triangulated surface with face
 * adjacency. Start: the extreme points a, b on the axis of largest extent, c the farthest from
 * line ab, d the farthest from plane abc (0 is returned when c or d is within HULL_FLAT·L).
 * Every other point goes into the outside set of the first face of this tetrahedron that it
 * is strictly above; points above no face are inside, or on the hull, and are dropped for
 * good. Then, while a face has an outside set, its farthest point p is added: the faces
 * visible from p (p strictly above their plane) are found by a breadth-first search over the
 * adjacency from that face, the horizon is the cycle of edges between visible and other
 * faces, each horizon edge (a, b) gets a new face (a, b, p), the visible faces are freed and
 * the points of their outside sets go to the first new face they are above (or are dropped:
 * Quickhull's lemma says they are then inside). With exact decisions the surface is convex at
 * every step, the visible faces form a disc and the horizon is one simple cycle; the code
 * still checks this (every horizon vertex starts one horizon edge and following them from
 * the first visits all) and that there is room for the new faces, and would drop p rather
 * than corrupt the surface. Each point is added or dropped once, so the loop ends after at
 * most n rounds; every stored index is a valid slot of the workspace.
 * The volume is Σ over faces of n · (v0 − r) / 6 (the cones from r over the faces) with r the
 * centroid of the starting tetrahedron: an interior point of every hull built, so every term
 * is positive. It is kept as a running sum, adding each new face's term and taking off each
 * deleted face's (the terms ever added are a few times the volume, so this costs a few units
 * of rounding; the sum is still the same for the same input).
 *
 * Workspace (affect_hull3d_new): four blocks sized from max_points m with checked arithmetic:
 * the handle, 3m + 8 faces and a spare (at most 2m − 4 are alive and a round adds at most m
 * before it frees the visible ones), 3m grid coordinates as doubles and as 64-bit integers
 * plus 3m + 6(3m + 8) doubles for the bounds, and 7m + 4(3m + 8) 32-bit indices
 * (outside-set links, per-vertex marks, horizon edges, new faces; the search queue, the
 * stack of faces waiting with an outside set, free face slots, the bound's reference faces).
 * max_points must leave 3m + 8 below 2^32 − 1 (else affect_hull3d_new returns NULL).
 *
 * Bound (affect_hull3d_bound): an upper bound of the next frames' volumes from the last hull
 * built, so that a maximum over frames (Shape Flow) builds only the hulls that can beat it.
 * The reference S is that hull's list of faces (vertex indices), closed and oriented; for a
 * frame, r is the centroid of its points and P_i = p_i − r. If every face of S, with the
 * frame's coordinates, has r strictly on one side (turned to r or away from it), the cones
 * from r over the faces cover space as often as S winds around r; when all faces turn away
 * from r that is at least once, otherwise the winding number is counted along the ray r + x·e1
 * (+∞ when it is 0 or uncertain). A point y of the frame's grid hull in the cone over face f
 * then satisfies g · y ≤ top_f = max_i g · P_i (g the face's normal n, turned outward from r,
 * rounded to floats; widened for the grid and rounding), so it lies in the cone truncated at
 * λ_f = top_f / min_{z ∈ f} g · z, of volume det_f · λ_f³ / 6 (det_f = |det(P_a, P_b, P_c)|),
 * and the volume is at most Σ_f det_f · λ_f³ / 6. (Any other face's g with g · z > 0 on f
 * bounds λ_f too; taking the least for the faces with λ_f > 1 builds a quarter fewer hulls on
 * the corpus but costs more than it saves.) When no point is above any face (S is still the
 * frame's hull) the bound is the volume itself up to the widening (about 1e-5 relative, from
 * the float extents); it grows with how far points rise above the faces, fast for thin cones
 * (a swinging leg seen from the torso). All
 * decisions are in doubles with explicit error terms (HULL_BOUND_EPS*), after scaling the
 * points by a power of two; the extents, 26 points × about 36 faces, are computed in floats,
 * four faces at a time. A bound costs about a third of a hull and changes nothing that
 * affect_hull3d_volume returns.
 *
 * Quick bound (affect_hull3d_bound_quick): the last finite bound's cones frozen — each face's
 * float normal g, its lower bound of g · z on the face and its upper bound of |det|, with
 * the scale exponent. That surface wound around its centroid, so translated to any apex (the
 * new points' centroid) its cones still cover space; only the extents along the frozen g are
 * recomputed (the same float loop and the same widening for the grid and rounding, at the
 * frozen scale), so the bound is Σ_f |det_f| · (top_f / min g · z)³ / 6 again, without the
 * normals and the winding test: about half the cost,
 * looser as the body turns and bends (the normals do not follow). On the corpus, right after
 * a full bound well below the best volume it rules the frame out about 80 % of the time.
 *
 * Speed (27 joints, gcc -O2, the project's 2-vCPU x86-64 build machine): a volume takes about
 * 2.3 µs on consecutive frames of the real corpus and 3.1 µs on unrelated random skeletons
 * (whose branches the predictor cannot learn); it makes about 10 rounds, 47 faces and 190
 * orientation tests; about 15 % of the time goes to the bounding box, the grid and the choice
 * of the starting tetrahedron. An area takes about 0.6 µs.
 */
#include "affect/laban.h"

#include <float.h>
#include <math.h>
#include <string.h>

/* Degeneracy: within this fraction of the bounding box's longest side of a line or plane. */
#define HULL_FLAT 1e-8
/* The grid: coordinates in [−HULL_HALF, HULL_HALF], HULL_SCALE steps per bounding box. */
#define HULL_SCALE 1073741824.0 /* 2^30 */
#define HULL_HALF 536870912     /* 2^29 */
#define HULL_SPLIT 2147483648LL /* 2^31: n = n_hi · HULL_SPLIT + n_lo */
/* A 3-D orientation computed in doubles is trusted beyond HULL_FILTER · Σ|n_i| · 2^30. */
#define HULL_FILTER 2e-15
/* 2-D inputs up to this many points are sorted by insertion. */
#define HULL_INSERTION_MAX 32
#define HULL_NONE UINT32_MAX
/* affect_hull3d_bound: the final relative widening (beyond the rounding of its sum, of the
 * cubes, and of the volume's running sum, all a few units of 2^-53) */
#define HULL_BOUND_SLACK 1e-9
/* a grid point lies within this many steps of its point along each axis */
#define HULL_BOUND_STEP 0.51
/* rounding of a dot product n · P per unit of |n|_1 · max|P| (3 · 2^-53, and 2^-53 for P
 * itself, widened) and of a triple product per unit of max|P|³ (about 120 · 2^-53, widened) */
#define HULL_BOUND_EPS 1e-14
#define HULL_BOUND_EPS3 1e-13
/* the same for a dot product in floats (5 · 2^-24: rounding of the points to floats and of
 * three products and two sums, widened) */
#define HULL_BOUND_EPSF 1e-6
/* |det(P_a, P_b, P_c) − g · P_v| for g the face normal rounded to floats, per unit of
 * |g|_1 · max|P| (2^-24 and the dot product's rounding, widened), besides det_slack */
#define HULL_BOUND_EPSG 1e-7
/* affect_hull3d_bound_quick: the final relative widening (the rounding of λ, the cubes and
 * the sum, a few units of 2^-53, and the volume's running sum) */
#define HULL_QUICK_SLACK 2e-9
/* and the range of max|P| at the frozen scale in which its float extents are trusted */
#define HULL_QUICK_BIG_MIN 0.015625
#define HULL_QUICK_BIG_MAX 64.0

/* Bounding box of n points of dimension dim (2 or 3): its centre c, its longest side len
 * (0 when all points are equal) and the axis of that side; false when a coordinate is not
 * finite or the box is too wide for a double. */
static bool bounding_box(const double *p, size_t n, int dim, double *c, double *len, int *axis)
{
    double lo[3] = {p[0], p[1], dim > 2 ? p[2] : 0}, hi[3] = {lo[0], lo[1], lo[2]}, zero = 0;
    for (size_t i = 0; i < n; i++) {
        for (int k = 0; k < dim; k++) {
            double v = p[(size_t)dim * i + (size_t)k];
            lo[k] = v < lo[k] ? v : lo[k];
            hi[k] = v > hi[k] ? v : hi[k];
            zero += v * 0; /* stays 0 unless v is infinite or NaN */
        }
    }
    if (zero != 0 || zero != zero)
        return false;
    int a = 0;
    for (int k = 0; k < dim; k++) {
        c[k] = 0.5 * lo[k] + 0.5 * hi[k];
        if (hi[k] - lo[k] > hi[a] - lo[a])
            a = k;
    }
    *len = hi[a] - lo[a];
    *axis = a;
    return isfinite(*len);
}

/* The grid coordinate of v: (v − c) · scale rounded (half away from zero) and clamped. */
static inline int64_t grid(double v, double c, double scale)
{
    double t = (v - c) * scale;
    int64_t x = (int64_t)(t + (t >= 0 ? 0.5 : -0.5));
    return x > HULL_HALF ? HULL_HALF : x < -HULL_HALF ? -HULL_HALF : x;
}

/* ---- 2-D ---- */

/* A grid point (x, y) as one sortable key, (x + 2^29) · 2^31 + (y + 2^29) < 2^62. Keys live in
 * the caller's double scratch and are copied in and out with memcpy, so no double register
 * ever holds one (their bit patterns are never NaN anyway: bit 62 is clear). */
static inline uint64_t key_get(const double *slot)
{
    uint64_t k;
    memcpy(&k, slot, sizeof k);
    return k;
}

static inline void key_put(double *slot, uint64_t k)
{
    memcpy(slot, &k, sizeof k);
}

#define KEY_X(k) ((int64_t)((k) >> 31))
#define KEY_Y(k) ((int64_t)((k) & (HULL_SPLIT - 1)))

/* Sorts the n keys in a; tmp holds n more. */
static void sort_keys(double *a, double *tmp, size_t n)
{
    if (n <= HULL_INSERTION_MAX) {
        for (size_t i = 1; i < n; i++) {
            uint64_t key = key_get(a + i);
            size_t j = i;
            for (; j > 0 && key < key_get(a + j - 1); j--)
                key_put(a + j, key_get(a + j - 1));
            key_put(a + j, key);
        }
        return;
    }
    double *src = a, *dst = tmp;
    for (size_t width = 1; width < n; width *= 2) {
        for (size_t lo = 0; lo < n; lo += 2 * width) {
            size_t mid = lo + width < n ? lo + width : n;
            size_t hi = mid + width < n ? mid + width : n;
            size_t i = lo, j = mid, k = lo;
            while (i < mid && j < hi) {
                uint64_t ki = key_get(src + i), kj = key_get(src + j);
                key_put(dst + k++, kj < ki ? kj : ki);
                i += !(kj < ki);
                j += kj < ki;
            }
            while (i < mid)
                key_put(dst + k++, key_get(src + i++));
            while (j < hi)
                key_put(dst + k++, key_get(src + j++));
        }
        double *t = src;
        src = dst;
        dst = t;
    }
    if (src != a)
        memcpy(a, src, n * sizeof(double));
}

/* One monotone chain over the n sorted keys (forward or backward), built in st (n keys);
 * returns its part of the shoelace sum. Coordinates are in [0, 2^30], so the cross products
 * of differences, and the shoelace terms (taken about the centre of the grid), are exact in
 * int64_t. */
static double chain_2d(const double *p, size_t n, bool backward, double *st)
{
    size_t k = 0;
    for (size_t t = 0; t < n; t++) {
        uint64_t q = key_get(p + (backward ? n - 1 - t : t));
        int64_t qx = KEY_X(q), qy = KEY_Y(q);
        while (k >= 2) {
            uint64_t o = key_get(st + k - 2), a = key_get(st + k - 1);
            int64_t ox = KEY_X(o), oy = KEY_Y(o);
            if ((KEY_X(a) - ox) * (qy - oy) - (KEY_Y(a) - oy) * (qx - ox) > 0)
                break;
            k--;
        }
        key_put(st + k++, q);
    }
    double sum = 0;
    for (size_t j = 0; j + 1 < k; j++) {
        uint64_t a = key_get(st + j), b = key_get(st + j + 1);
        int64_t ax = KEY_X(a) - HULL_HALF, ay = KEY_Y(a) - HULL_HALF;
        int64_t bx = KEY_X(b) - HULL_HALF, by = KEY_Y(b) - HULL_HALF;
        sum += (double)(ax * by - ay * bx);
    }
    return sum;
}

/* Drops the keys (grid points) of p[0, n) that lie strictly inside the quadrilateral of the
 * extreme points along x and y (Akl and Toussaint's heuristic), keeping the others in order at
 * the front; returns their number. Such a point is strictly inside the hull, so it is never a
 * vertex of either chain: the chains, and so the area's bits, are those of all the points. The
 * extremes, taken in the counter-clockwise order of their directions, lie on the hull in
 * counter-clockwise order (ties may repeat a point); a point strictly left of every edge
 * between two different extremes is strictly inside (the quadrilateral winds around it). Exact:
 * the cross products of grid differences fit in int64_t. (The octagon of the diagonal extremes
 * as well drops more points but costs more than the sort it saves.) */
static size_t interior_filter_2d(double *p, size_t n)
{
    /* extremes: min y, max x, max y, min x */
    size_t ext[4] = {0, 0, 0, 0};
    int64_t b0, b1, b2, b3;
    {
        uint64_t k = key_get(p);
        b0 = -KEY_Y(k), b1 = KEY_X(k), b2 = KEY_Y(k), b3 = -KEY_X(k);
    }
    for (size_t i = 1; i < n; i++) {
        uint64_t k = key_get(p + i);
        int64_t x = KEY_X(k), y = KEY_Y(k);
        ext[0] = -y > b0 ? i : ext[0], b0 = -y > b0 ? -y : b0;
        ext[1] = x > b1 ? i : ext[1], b1 = x > b1 ? x : b1;
        ext[2] = y > b2 ? i : ext[2], b2 = y > b2 ? y : b2;
        ext[3] = -x > b3 ? i : ext[3], b3 = -x > b3 ? -x : b3;
    }
    int64_t ex[4], ey[4], dx[4], dy[4];
    int ne = 0;
    for (int d = 0; d < 4; d++) {
        uint64_t a = key_get(p + ext[d]), b = key_get(p + ext[(d + 1) % 4]);
        if (a == b)
            continue;
        ex[ne] = KEY_X(a), ey[ne] = KEY_Y(a);
        dx[ne] = KEY_X(b) - ex[ne], dy[ne] = KEY_Y(b) - ey[ne];
        ne++;
    }
    if (ne < 3)
        return n;
    size_t m = 0;
    for (size_t i = 0; i < n; i++) {
        uint64_t k = key_get(p + i);
        int64_t x = KEY_X(k), y = KEY_Y(k);
        bool inside = true;
        for (int e = 0; e < ne; e++)
            inside &= dx[e] * (y - ey[e]) - dy[e] * (x - ex[e]) > 0;
        if (!inside)
            key_put(p + m++, k);
    }
    return m;
}

double affect_hull_area_2d(const double *xy, uint32_t n, double *scratch)
{
    if (n < 3)
        return 0;
    double c[2], len;
    int axis;
    if (!bounding_box(xy, n, 2, c, &len, &axis))
        return NAN;
    if (!(len > 0))
        return 0;
    double scale = HULL_SCALE / len, *p = scratch, *tmp = scratch + n;
    for (size_t i = 0; i < n; i++) {
        uint64_t x = (uint64_t)(grid(xy[2 * i], c[0], scale) + HULL_HALF);
        uint64_t y = (uint64_t)(grid(xy[2 * i + 1], c[1], scale) + HULL_HALF);
        key_put(p + i, x << 31 | y);
    }
    size_t m = interior_filter_2d(p, n);
    sort_keys(p, tmp, m);
    double area = 0.5 * (chain_2d(p, m, false, tmp) + chain_2d(p, m, true, tmp));
    if (!(area > HULL_FLAT * HULL_SCALE * HULL_SCALE))
        return 0;
    double step = len / HULL_SCALE;
    return area * step * step;
}

/* ---- 3-D ---- */

typedef struct hull_face {
    double nd[3];    /* the outward normal n = (v1 − v0) × (v2 − v0), rounded to doubles */
    double d;        /* nd · v0, rounded */
    double thr;      /* |nd · q − d| above this has the sign of n · (q − v0) */
    double far_dist; /* nd · q − d for the farthest point of the outside set (0 if empty) */
    double cone;     /* d − nd · r: six times the volume of the cone from r over the face */
    int64_t n[3];    /* the normal exactly */
    uint32_t v[3];   /* vertices, counter-clockwise seen from outside */
    uint32_t nb[3];  /* nb[i]: the face across the edge v[i] → v[i + 1] */
    uint32_t head;   /* first point of the outside set (linked through next[]), or none */
    uint32_t far;    /* farthest point of the outside set */
    uint32_t mark;   /* round in which the face was found visible */
    uint32_t seen;   /* round in which the face was tested */
    uint8_t alive;
    uint8_t queued; /* on the stack of faces waiting with an outside set */
} hull_face;

struct affect_hull3d {
    uint32_t max_points, cap; /* cap = 3·max_points + 8 face slots, plus a spare one */
    hull_face *f;             /* cap + 1 */
    double *x;                /* 3·max: grid coordinates (integers) as doubles */
    int64_t *xi;              /* 3·max: the same as integers */
    uint32_t *idx;            /* the one block of the index arrays below */
    uint32_t *next;           /* max: outside-set links */
    uint32_t *vmark;          /* max: round in which the vertex started a horizon edge */
    uint32_t *vedge;          /* max: that horizon edge */
    uint32_t *hz_a, *hz_b;    /* max: horizon edges a → b (as in the visible face) */
    uint32_t *hz_g;           /* max: the face beyond each */
    uint32_t *newf;           /* max: the horizon walk, then the new faces */
    uint32_t *queue;          /* cap: visible faces of a round (breadth-first order) */
    uint32_t *stack;          /* cap: faces waiting with an outside set */
    uint32_t *freel;          /* cap: free face slots */
    uint32_t n_fresh, n_free, n_stack;
    double r[3]; /* an interior point: the centroid of the starting tetrahedron */
    double vol;  /* Σ cone over the faces alive: six times the volume */
    /* the reference of affect_hull3d_bound: the faces of the last hull built with a positive
     * volume, and its number of points */
    uint32_t *ref_tri; /* 3 per face, as in hull_face.v */
    uint32_t ref_faces, ref_points;
    double *ys; /* 3·max: a bound's points about their centroid, x, y, z apart */
    double *bf; /* 6·cap: a bound's points and face normals as floats, per-face sums */
    /* the frozen cones of affect_hull3d_bound_quick: the last finite affect_hull3d_bound's
     * faces (their float normals stay in bf, their |det|, |g|_1 and least g · z after them), their
     * number (0: none), its number of points and its scale exponent */
    uint32_t q_faces, q_points;
    int q_exp;
};

affect_hull3d *affect_hull3d_new(uint32_t max_points)
{
    size_t m = max_points, cap, n_coord, n_faces, n_idx, t, n_bnd;
    if (!affect_mul_size(m, 3, &n_coord) || !affect_add_size(n_coord, 8, &cap) ||
        cap >= HULL_NONE || !affect_add_size(cap, 1, &n_faces) || !affect_mul_size(m, 7, &n_idx) ||
        !affect_mul_size(cap, 3, &t) || !affect_add_size(n_idx, t, &n_idx) ||
        !affect_add_size(n_idx, t, &n_idx) || !affect_mul_size(n_coord, 3, &t) ||
        !affect_mul_size(cap, 6, &n_bnd) || !affect_add_size(t, n_bnd, &t))
        return NULL;
    affect_hull3d *h = affect_malloc(sizeof *h);
    if (!h)
        return NULL;
    memset(h, 0, sizeof *h);
    h->max_points = max_points;
    h->cap = (uint32_t)cap;
    /* doubles and 64-bit integers in one block: both are 8 bytes with the same alignment
     * needs, and affect_malloc's blocks suit any type */
    void *coords = NULL;
    if (!(h->f = affect_malloc_array(n_faces, sizeof(hull_face))) ||
        !(coords = affect_malloc_array(t, sizeof(double))) ||
        !(h->idx = affect_malloc_array(n_idx, sizeof(uint32_t)))) {
        affect_free(coords);
        goto fail;
    }
    h->x = coords;
    h->xi = (int64_t *)(void *)(h->x + n_coord);
    h->ys = h->x + 2 * n_coord;
    h->bf = h->ys + n_coord;
    uint32_t *q = h->idx;
    uint32_t **per_point[] = {&h->next, &h->vmark, &h->vedge, &h->hz_a,
                              &h->hz_b, &h->hz_g,  &h->newf};
    for (size_t i = 0; i < sizeof per_point / sizeof per_point[0]; i++, q += m)
        *per_point[i] = q;
    uint32_t **per_face[] = {&h->queue, &h->stack, &h->freel, &h->ref_tri};
    for (size_t i = 0; i < sizeof per_face / sizeof per_face[0]; i++, q += cap)
        *per_face[i] = q;
    return h;

fail:
    affect_hull3d_free(h);
    return NULL;
}

void affect_hull3d_free(affect_hull3d *h)
{
    if (!h)
        return;
    affect_free(h->f);
    affect_free(h->x);
    affect_free(h->idx);
    affect_free(h);
}

/* Exact sign of n · (q − v0) for face f (rarely needed: see face_dist). It is 0 when q is
 * one of the face's vertices, the usual case (duplicate points). Otherwise, with n_i split as
 * hi_i · 2^31 + lo_i (0 ≤ lo_i < 2^31) and |q_i − v0_i| ≤ 2^30, the value is
 * 2^31 · Σ hi_i w_i + Σ lo_i w_i, and both sums are below 2^62 and 3 · 2^61 in magnitude.
 * (int64_t is two's complement, so x & (2^31 − 1) is the remainder of floor division.) */
static int face_side_exact(const affect_hull3d *h, const hull_face *f, uint32_t q)
{
    const int64_t *iq = h->xi + 3 * (size_t)q;
    for (int k = 0; k < 3; k++) {
        const int64_t *iv = h->xi + 3 * (size_t)f->v[k];
        if (iq[0] == iv[0] && iq[1] == iv[1] && iq[2] == iv[2])
            return 0;
    }
    const int64_t *ia = h->xi + 3 * (size_t)f->v[0];
    int64_t hi = 0, lo = 0;
    for (int k = 0; k < 3; k++) {
        int64_t w = iq[k] - ia[k], nl = f->n[k] & (HULL_SPLIT - 1);
        hi += (f->n[k] - nl) / HULL_SPLIT * w;
        lo += nl * w;
    }
    int64_t rest = lo & (HULL_SPLIT - 1);
    hi += (lo - rest) / HULL_SPLIT; /* the value is hi · 2^31 + rest, 0 ≤ rest < 2^31 */
    return hi > 0 || (hi == 0 && rest > 0) ? 1 : hi < 0 ? -1 : 0;
}

/* nd · q − d for face f: its sign is that of n · (q − v0), exactly (> 0: q is strictly above
 * the face's plane); its value is only used to pick the farthest point. */
static inline double face_dist(const affect_hull3d *h, const hull_face *f, uint32_t q)
{
    const double *pq = h->x + 3 * (size_t)q;
    double s = f->nd[0] * pq[0] + f->nd[1] * pq[1] + f->nd[2] * pq[2] - f->d;
    if (fabs(s) > f->thr)
        return s;
    int side = face_side_exact(h, f, q);
    return side > 0 ? (s > 0 ? s : DBL_MIN) : side < 0 ? (s < 0 ? s : -DBL_MIN) : 0;
}

/* A free face slot (the caller has checked that one exists): the last freed one, else a
 * fresh one. */
static inline uint32_t face_alloc(affect_hull3d *h)
{
    if (h->n_free > 0)
        return h->freel[--h->n_free];
    uint32_t i = h->n_fresh++;
    h->f[i].queued = 0; /* a freed slot keeps its flag: it may still be on the stack */
    return i;
}

/* Sets face fi to the triangle a, b, c (its neighbours are set by the caller). */
static void face_set(affect_hull3d *h, uint32_t fi, uint32_t a, uint32_t b, uint32_t c)
{
    hull_face *f = &h->f[fi];
    const int64_t *pa = h->xi + 3 * (size_t)a, *pb = h->xi + 3 * (size_t)b;
    const int64_t *pc = h->xi + 3 * (size_t)c;
    int64_t u0 = pb[0] - pa[0], u1 = pb[1] - pa[1], u2 = pb[2] - pa[2];
    int64_t v0 = pc[0] - pa[0], v1 = pc[1] - pa[1], v2 = pc[2] - pa[2];
    int64_t n0 = u1 * v2 - u2 * v1, n1 = u2 * v0 - u0 * v2, n2 = u0 * v1 - u1 * v0;
    double d0 = (double)n0, d1 = (double)n1, d2 = (double)n2;
    const double *xa = h->x + 3 * (size_t)a;
    f->n[0] = n0;
    f->n[1] = n1;
    f->n[2] = n2;
    f->nd[0] = d0;
    f->nd[1] = d1;
    f->nd[2] = d2;
    f->d = d0 * xa[0] + d1 * xa[1] + d2 * xa[2];
    f->thr = HULL_FILTER * HULL_SCALE * (fabs(d0) + fabs(d1) + fabs(d2));
    f->cone = f->d - (d0 * h->r[0] + d1 * h->r[1] + d2 * h->r[2]);
    f->far_dist = 0;
    f->v[0] = a;
    f->v[1] = b;
    f->v[2] = c;
    f->head = HULL_NONE;
    f->far = HULL_NONE;
    f->mark = 0;
    f->seen = 0;
    f->alive = 1;
}

/* Puts point q into the outside set of face fi (dist above it). */
static inline void outside_add(affect_hull3d *h, uint32_t fi, uint32_t q, double dist)
{
    hull_face *f = &h->f[fi];
    h->next[q] = f->head;
    f->head = q;
    bool farther = dist > f->far_dist;
    f->far = farther ? q : f->far;
    f->far_dist = farther ? dist : f->far_dist;
    if (!f->queued) {
        f->queued = 1;
        h->stack[h->n_stack++] = fi;
    }
}

/* Puts point q into the outside set of the first face among faces[0, n) that it is above;
 * a point above none of them is dropped for good. */
static inline void outside_assign(affect_hull3d *h, const uint32_t *faces, uint32_t n, uint32_t q)
{
    for (uint32_t j = 0; j < n; j++) {
        double dist = face_dist(h, &h->f[faces[j]], q);
        if (dist > 0) {
            outside_add(h, faces[j], q, dist);
            return;
        }
    }
}

/* Recomputes the farthest point of face fi (after its farthest point p was taken out and
 * could not be added) and puts the face back on the stack when its set is not empty. */
static void outside_refresh(affect_hull3d *h, uint32_t fi)
{
    hull_face *f = &h->f[fi];
    f->far = HULL_NONE;
    f->far_dist = 0;
    for (uint32_t q = f->head; q != HULL_NONE; q = h->next[q]) {
        double dist = face_dist(h, f, q); /* > 0: q is in the outside set */
        if (dist > f->far_dist) {
            f->far = q;
            f->far_dist = dist;
        }
    }
    if (f->head != HULL_NONE && !f->queued) {
        f->queued = 1;
        h->stack[h->n_stack++] = fi;
    }
}

/* Adds point p, above face f0 and already taken out of its outside set, in round `round`;
 * false (and nothing changed) when the horizon is not one simple cycle or the face slots
 * would not suffice. */
static bool hull_add_point(affect_hull3d *h, uint32_t f0, uint32_t p, uint32_t round)
{
    hull_face *F = h->f; /* also reached through h by the helpers: not restrict */
    uint32_t *restrict queue = h->queue, *restrict vmark = h->vmark, *restrict vedge = h->vedge;
    uint32_t *restrict hz_a = h->hz_a, *restrict hz_b = h->hz_b, *restrict hz_g = h->hz_g;
    uint32_t *restrict newf = h->newf;
    /* breadth-first search of the visible faces; each edge from a visible face to another
     * face is a horizon edge */
    uint32_t nq = 1, nh = 0;
    queue[0] = f0;
    F[f0].mark = round;
    for (uint32_t k = 0; k < nq; k++) {
        const hull_face *f = &F[queue[k]];
        for (int e = 0; e < 3; e++) {
            static const int next3[3] = {1, 2, 0};
            uint32_t g = f->nb[e];
            if (F[g].mark == round)
                continue;
            if (F[g].seen != round) {
                F[g].seen = round;
                if (face_dist(h, &F[g], p) > 0) {
                    F[g].mark = round;
                    queue[nq++] = g;
                    continue;
                }
            }
            uint32_t a = f->v[e];
            if (vmark[a] == round)
                return false; /* the visible region touches itself at a */
            vmark[a] = round;
            vedge[a] = nh;
            hz_a[nh] = a;
            hz_b[nh] = f->v[next3[e]];
            hz_g[nh] = g;
            nh++;
        }
    }
    /* the horizon must be one cycle: walk it from edge 0, listing its edges in newf */
    uint32_t e = 0, steps = 0;
    do {
        newf[steps++] = e;
        uint32_t b = hz_b[e];
        if (vmark[b] != round)
            return false;
        e = vedge[b];
    } while (e != 0 && steps < nh);
    if (e != 0 || steps != nh || nh < 3)
        return false; /* more than one cycle, or a degenerate one */
    if (h->n_free + (h->cap - h->n_fresh) < nh)
        return false;

    /* new face k on the k-th horizon edge a → b: (a, b, p), its neighbours the face beyond
     * the edge, then the next and the previous new face around p (the spare slot cap stands
     * for the previous face of the first, then the links are closed) */
    uint32_t first = 0, prev = h->cap;
    for (uint32_t k = 0; k < nh; k++) {
        uint32_t ek = newf[k], nf = face_alloc(h), b = hz_b[ek];
        newf[k] = nf; /* the k-th edge of the walk is no longer needed */
        face_set(h, nf, hz_a[ek], b, p);
        h->vol += F[nf].cone;
        hull_face *g = &F[hz_g[ek]];
        F[nf].nb[0] = hz_g[ek];
        g->nb[(g->v[1] == b) + 2 * (g->v[2] == b)] = nf; /* g's edge b → a starts at b */
        F[nf].nb[2] = prev;
        F[prev].nb[1] = nf;
        first = k == 0 ? nf : first;
        prev = nf;
    }
    F[first].nb[2] = prev;
    F[prev].nb[1] = first;
    /* the deleted faces' outside points go to the first new face they are above */
    for (uint32_t k = 0; k < nq; k++) {
        hull_face *vf = &F[queue[k]];
        for (uint32_t r = vf->head, nx; r != HULL_NONE; r = nx) {
            nx = h->next[r];
            outside_assign(h, newf, nh, r);
        }
        vf->head = HULL_NONE;
        vf->alive = 0;
        h->vol -= vf->cone;
        h->freel[h->n_free++] = queue[k];
    }
    return true;
}

double affect_hull3d_volume(affect_hull3d *h, const double *xyz, uint32_t n)
{
    if (!h || n > h->max_points)
        return -1;
    if (n < 4)
        return 0;
    double c[3], len;
    int axis;
    if (!bounding_box(xyz, n, 3, c, &len, &axis))
        return NAN;
    if (!(len > 0))
        return 0;
    double scale = HULL_SCALE / len, *X = h->x;
    uint32_t ia = 0, ib = 0, ic = 0, id = 0;
    for (uint32_t i = 0; i < n; i++) {
        for (int k = 0; k < 3; k++) {
            size_t j = 3 * (size_t)i + (size_t)k;
            h->xi[j] = grid(xyz[j], c[k], scale);
            X[j] = (double)h->xi[j];
        }
        /* the first points of smallest and largest grid coordinate on the longest axis */
        ia = X[3 * (size_t)i + (size_t)axis] < X[3 * (size_t)ia + (size_t)axis] ? i : ia;
        ib = X[3 * (size_t)i + (size_t)axis] > X[3 * (size_t)ib + (size_t)axis] ? i : ib;
    }

    /* starting tetrahedron a, b, c, d; the degeneracy tests in doubles (grid units) */
    const double flat = HULL_FLAT * HULL_SCALE;
    const double *pa = X + 3 * (size_t)ia, *pb = X + 3 * (size_t)ib;
    double u[3] = {pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]}, best = -1;
    for (uint32_t i = 0; i < n; i++) {
        const double *pi = X + 3 * (size_t)i;
        double w0 = pi[0] - pa[0], w1 = pi[1] - pa[1], w2 = pi[2] - pa[2];
        double x = w1 * u[2] - w2 * u[1], y = w2 * u[0] - w0 * u[2], z = w0 * u[1] - w1 * u[0];
        double d2 = x * x + y * y + z * z;
        ic = d2 > best ? i : ic;
        best = d2 > best ? d2 : best;
    }
    if (!(best > flat * flat * (u[0] * u[0] + u[1] * u[1] + u[2] * u[2])))
        return 0; /* collinear */
    const double *pc = X + 3 * (size_t)ic;
    double w[3] = {pc[0] - pa[0], pc[1] - pa[1], pc[2] - pa[2]};
    double nrm[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2],
                     u[0] * w[1] - u[1] * w[0]};
    best = -1;
    for (uint32_t i = 0; i < n; i++) {
        const double *pi = X + 3 * (size_t)i;
        double dist =
            fabs(nrm[0] * (pi[0] - pa[0]) + nrm[1] * (pi[1] - pa[1]) + nrm[2] * (pi[2] - pa[2]));
        id = dist > best ? i : id;
        best = dist > best ? dist : best;
    }
    if (!(best * best > flat * flat * (nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2])))
        return 0; /* coplanar */

    h->n_fresh = h->n_free = h->n_stack = 0;
    for (uint32_t i = 0; i < n; i++)
        h->vmark[i] = 0;
    for (int k = 0; k < 3; k++)
        h->r[k] = 0.25 * (X[3 * (size_t)ia + (size_t)k] + X[3 * (size_t)ib + (size_t)k] +
                          X[3 * (size_t)ic + (size_t)k] + X[3 * (size_t)id + (size_t)k]);
    face_set(h, face_alloc(h), ia, ib, ic);
    if (face_dist(h, &h->f[0], id) > 0) { /* d must lie below the face a, b, c */
        uint32_t t = ib;
        ib = ic;
        ic = t;
        face_set(h, 0, ia, ib, ic);
    }
    /* faces abc, adb, bdc, acd; nb[i] is the face holding the edge v[i + 1] → v[i] */
    static const uint32_t tet_nb[4][3] = {{1, 2, 3}, {3, 2, 0}, {1, 3, 0}, {0, 2, 1}};
    face_set(h, face_alloc(h), ia, id, ib);
    face_set(h, face_alloc(h), ib, id, ic);
    face_set(h, face_alloc(h), ia, ic, id);
    for (int k = 0; k < 4; k++)
        memcpy(h->f[k].nb, tet_nb[k], sizeof tet_nb[k]);
    h->vol = h->f[0].cone + h->f[1].cone + h->f[2].cone + h->f[3].cone;

    static const uint32_t tet_faces[4] = {0, 1, 2, 3};
    for (uint32_t i = 0; i < n; i++) {
        if (i != ia && i != ib && i != ic && i != id)
            outside_assign(h, tet_faces, 4, i);
    }

    /* add the farthest point of a waiting face until none waits; each point once at most */
    uint32_t round = 0;
    while (h->n_stack > 0) {
        uint32_t fi = h->stack[--h->n_stack];
        hull_face *f = &h->f[fi];
        f->queued = 0;
        if (!f->alive || f->head == HULL_NONE)
            continue;
        uint32_t p = f->far, *link = &f->head;
        while (*link != p && *link != HULL_NONE)
            link = &h->next[*link];
        if (*link == p)
            *link = h->next[p]; /* take p out of the outside set */
        if (!hull_add_point(h, fi, p, ++round))
            outside_refresh(h, fi); /* p is dropped */
    }

    /* keep this hull as the reference of affect_hull3d_bound */
    if (h->vol > 0) {
        uint32_t nf = 0;
        for (uint32_t fi = 0; fi < h->n_fresh; fi++) {
            const hull_face *f = &h->f[fi];
            if (f->alive) {
                memcpy(h->ref_tri + 3 * (size_t)nf, f->v, sizeof f->v);
                nf++;
            }
        }
        h->ref_faces = nf;
        h->ref_points = n;
    }
    double step = len / HULL_SCALE;
    return h->vol / 6 * step * step * step;
}

/* The points' (xf, yf, zf; n) extent along every face normal (n0f, n1f, n2f; nf) into top, in
 * floats: points outside, faces inside (a loop that gcc vectorises, four faces at a time). */
static void bound_extents(const float *xf, const float *yf, const float *zf, uint32_t n,
                          const float *n0f, const float *n1f, const float *n2f, uint32_t nf,
                          float *top)
{
    for (uint32_t f = 0; f < nf; f++)
        top[f] = -INFINITY;
    for (uint32_t i = 0; i < n; i++) {
        float x = xf[i], y = yf[i], z = zf[i];
        for (uint32_t f = 0; f < nf; f++) {
            float d = n0f[f] * x + n1f[f] * y + n2f[f] * z;
            top[f] = d > top[f] ? d : top[f];
        }
    }
}

/* The winding number of the reference surface (its points X, Y, Z about r) around r: the
 * signed count of its faces that the ray from r along +x crosses; 0 also when a face's
 * projection along x passes within rounding of r (the count would not be certain). */
static int bound_winding(const affect_hull3d *h, const double *X, const double *Y, const double *Z,
                         double big)
{
    double eps = HULL_BOUND_EPS3 * big * big;
    int w = 0;
    for (uint32_t f = 0; f < h->ref_faces; f++) {
        const uint32_t *v = h->ref_tri + 3 * (size_t)f;
        uint32_t a = v[0], b = v[1], c = v[2];
        /* twice the signed areas of the projections of (r, a, b), (r, b, c), (r, c, a) on the
         * y, z plane: r is inside the projected face when all three have the same sign, that
         * of the face normal's x component */
        double oab = Y[a] * Z[b] - Z[a] * Y[b], obc = Y[b] * Z[c] - Z[b] * Y[c];
        double oca = Y[c] * Z[a] - Z[c] * Y[a];
        if (!(fabs(oab) > eps && fabs(obc) > eps && fabs(oca) > eps))
            return 0;
        if ((oab > 0) != (obc > 0) || (oab > 0) != (oca > 0))
            continue;
        /* the orientation of (r, a, b, c): the crossing is at x > 0 when it has the sign of the
         * normal's x component, and counts with that sign */
        double u0 = X[b] - X[a], u1 = Y[b] - Y[a], u2 = Z[b] - Z[a];
        double w0 = X[c] - X[a], w1 = Y[c] - Y[a], w2 = Z[c] - Z[a];
        double det =
            (u1 * w2 - u2 * w1) * X[a] + (u2 * w0 - u0 * w2) * Y[a] + (u0 * w1 - u1 * w0) * Z[a];
        if ((det > 0) == (oab > 0))
            w += det > 0 ? 1 : -1;
    }
    return w;
}

/* 2^k: built from its bits when it is a normal double (ldexp is a library call) */
static double pow2(int k)
{
    if (k < -1022 || k > 1023)
        return ldexp(1.0, k);
    uint64_t bits = (uint64_t)(k + 1023) << 52;
    double v;
    memcpy(&v, &bits, sizeof v);
    return v;
}

/* The points xyz (n) about their centroid, scaled by 2^-e, as doubles x, y, z apart in X (3n)
 * and floats in xf (x, y, z apart, n apart; only the *nu points that differ from the one
 * before them); *big = their largest |coordinate| and *len = the longest side of their
 * bounding box, both scaled; e is *e when keep_e, else taken from big (max|P| then in [1/2, 1))
 * into *e. False when a coordinate is not finite. */
static bool bound_points(const double *xyz, uint32_t n, double *X, float *xf, uint32_t *nu,
                         bool keep_e, int *e, double *big, double *len)
{
    /* r: the points' centroid; their bounding box's longest side gives the grid's step. The
     * sums are not finite when a coordinate is not (or when they overflow: refused too). */
    double sum[3] = {0, 0, 0}, lo[3] = {xyz[0], xyz[1], xyz[2]}, hi[3] = {lo[0], lo[1], lo[2]};
    double *Y = X + n, *Z = Y + n;
    for (uint32_t i = 0; i < n; i++) {
        double x = xyz[3 * (size_t)i], y = xyz[3 * (size_t)i + 1], z = xyz[3 * (size_t)i + 2];
        X[i] = x, Y[i] = y, Z[i] = z;
        sum[0] += x, sum[1] += y, sum[2] += z;
        lo[0] = x < lo[0] ? x : lo[0], hi[0] = x > hi[0] ? x : hi[0];
        lo[1] = y < lo[1] ? y : lo[1], hi[1] = y > hi[1] ? y : hi[1];
        lo[2] = z < lo[2] ? z : lo[2], hi[2] = z > hi[2] ? z : hi[2];
    }
    if (!(fabs(sum[0]) <= DBL_MAX && fabs(sum[1]) <= DBL_MAX && fabs(sum[2]) <= DBL_MAX))
        return false;
    double r[3] = {sum[0] / n, sum[1] / n, sum[2] / n};
    double l = hi[0] - lo[0];
    l = hi[1] - lo[1] > l ? hi[1] - lo[1] : l;
    l = hi[2] - lo[2] > l ? hi[2] - lo[2] : l;
    /* max |x_i − r| over the points is max(hi − r, r − lo) (rounding is monotone) */
    double b = 0;
    for (int k = 0; k < 3; k++) {
        double u = hi[k] - r[k], v = r[k] - lo[k];
        b = u > b ? u : b;
        b = v > b ? v : b;
    }
    if (!(b <= DBL_MAX) || !(l <= DBL_MAX))
        return false;
    if (!keep_e)
        frexp(b, e); /* 0 when b is */
    double unit = pow2(-*e);
    for (int k = 0; k < 3; k++) {
        double *c = X + (size_t)k * n, rk = r[k];
        for (uint32_t i = 0; i < n; i++)
            c[i] = (c[i] - rk) * unit;
    }
    /* the floats without the points equal to the one before (an end site on its joint: the
     * same extents) */
    float *yf = xf + n, *zf = yf + n;
    uint32_t u = 0;
    for (uint32_t i = 0; i < n; i++) {
        if (i > 0 && X[i] == X[i - 1] && Y[i] == Y[i - 1] && Z[i] == Z[i - 1])
            continue;
        xf[u] = (float)X[i], yf[u] = (float)Y[i], zf[u] = (float)Z[i];
        u++;
    }
    *nu = u;
    *big = b * unit;
    *len = l * unit;
    return true;
}

double affect_hull3d_bound_quick(affect_hull3d *h, const double *xyz, uint32_t n)
{
    if (!h || n > h->max_points)
        return INFINITY;
    if (n < 4)
        return 0;
    if (h->q_faces == 0 || h->q_points != n)
        return INFINITY;
    uint32_t nf = h->q_faces;
    int e = h->q_exp;
    double big, len;
    float *xf = (float *)(void *)h->bf, *n0f = xf + 3 * (size_t)n, *n1f = n0f + nf;
    float *n2f = n1f + nf, *top = n2f + nf;
    const double *det = h->bf + 2 * (size_t)n + 4 * (size_t)nf, *g1 = det + nf, *dmin = g1 + nf;
    uint32_t nu;
    if (!bound_points(xyz, n, h->ys, xf, &nu, true, &e, &big, &len) ||
        !(big >= HULL_QUICK_BIG_MIN && big <= HULL_QUICK_BIG_MAX))
        return INFINITY; /* not finite, or too far from the frozen scale for the floats */
    bound_extents(xf, xf + n, xf + 2 * (size_t)n, nu, n0f, n1f, n2f, nf, top);
    double grid_slack = HULL_BOUND_STEP * (len / HULL_SCALE) + HULL_BOUND_EPS * big, total = 0;
    for (uint32_t f = 0; f < nf; f++) {
        double toph = (double)top[f] + g1[f] * (grid_slack + HULL_BOUND_EPSF * big);
        toph = toph > 0 ? toph : 0;
        double lambda = toph / dmin[f];
        total += det[f] * lambda * lambda * lambda;
    }
    double u = ldexp(total / 6 * (1 + HULL_QUICK_SLACK), 3 * e);
    return u > 2 * DBL_MIN ? u : 2 * DBL_MIN;
}

double affect_hull3d_bound(affect_hull3d *h, const double *xyz, uint32_t n)
{
    if (!h || n > h->max_points)
        return INFINITY;
    h->q_faces = 0; /* the frozen cones are kept again below when this bound is finite */
    if (n < 4)
        return 0;
    if (h->ref_faces == 0 || h->ref_points != n)
        return INFINITY;
    /* the points about their centroid r, scaled by a power of two (exactly) to max|P| in
     * [1/2, 1): the floats below can then neither overflow nor lose more than their rounding */
    int e = 0;
    double big, len, *X = h->ys, *Y = X + n, *Z = Y + n;
    float *xf = (float *)(void *)h->bf, *yf = xf + n, *zf = yf + n;
    uint32_t nu;
    if (!bound_points(xyz, n, X, xf, &nu, false, &e, &big, &len))
        return INFINITY; /* a coordinate is not finite */
    if (!(big > 0))
        return 0; /* all points coincide */
    /* slack of N · y per unit of |N|_1: the grid's rounding (each grid point within
     * HULL_BOUND_STEP steps of its point per axis), the rounding of the points P about r and
     * of the dot product; and of the triple product */
    double grid_slack = HULL_BOUND_STEP * (len / HULL_SCALE) + HULL_BOUND_EPS * big;
    double det_slack = HULL_BOUND_EPS3 * big * big * big, total = 0;
    uint32_t inverted = 0, nf = h->ref_faces;
    float *n0f = zf + n, *n1f = n0f + nf, *n2f = n1f + nf, *top = n2f + nf;
    double *lo_d = h->bf + 2 * (size_t)n + 2 * (size_t)nf, *hi_d = lo_d + nf;
    /* the frozen cones' |det| and |g|_1 and least g · z (bf: 2n + 7nf doubles in all) */
    double *dets = hi_d + nf, *g1s = dets + nf, *dmins = g1s + nf;
    /* each face's normal n = (P_b − P_a) × (P_c − P_a) rounded to floats, g, turned to face
     * away from r, and the range of g · P over its vertices (all the triple product
     * |det(P_a, P_b, P_c)| but for rounding: within HULL_BOUND_EPSG · |g|_1 · max|P| plus
     * det_slack) */
    for (uint32_t f = 0; f < nf; f++) {
        const uint32_t *v = h->ref_tri + 3 * (size_t)f;
        uint32_t a = v[0], b = v[1], c = v[2];
        double u0 = X[b] - X[a], u1 = Y[b] - Y[a], u2 = Z[b] - Z[a];
        double w0 = X[c] - X[a], w1 = Y[c] - Y[a], w2 = Z[c] - Z[a];
        double g0 = (float)(u1 * w2 - u2 * w1), g1 = (float)(u2 * w0 - u0 * w2);
        double g2 = (float)(u0 * w1 - u1 * w0);
        double da = g0 * X[a] + g1 * Y[a] + g2 * Z[a];
        if (da < 0) {
            /* the face turned its back to r: bound its cone with the opposite normal */
            g0 = -g0, g1 = -g1, g2 = -g2, da = -da;
            inverted++;
        }
        double db = g0 * X[b] + g1 * Y[b] + g2 * Z[b], dc = g0 * X[c] + g1 * Y[c] + g2 * Z[c];
        double dmin = da < db ? da : db, dmax = da > db ? da : db;
        lo_d[f] = dc < dmin ? dc : dmin;
        hi_d[f] = dc > dmax ? dc : dmax;
        n0f[f] = (float)g0, n1f[f] = (float)g1, n2f[f] = (float)g2;
    }
    bound_extents(xf, yf, zf, nu, n0f, n1f, n2f, nf, top);
    /* each face's cone, cut at λ = widened extent / least g · z on the face (≥ 1; exactly 1
     * but for the widening when no point is above the face) */
    for (uint32_t f = 0; f < nf; f++) {
        double g1 = fabs((double)n0f[f]) + fabs((double)n1f[f]) + fabs((double)n2f[f]);
        double toph = (double)top[f] + g1 * (grid_slack + HULL_BOUND_EPSF * big);
        double dmin = lo_d[f] - HULL_BOUND_EPS * g1 * big, err = HULL_BOUND_EPSG * g1 * big;
        if (!(dmin > 0) || !(lo_d[f] - err - det_slack > 0))
            return INFINITY; /* r is (nearly) on the face's plane */
        double lambda = toph / dmin;
        total += (hi_d[f] + err + det_slack) * lambda * lambda * lambda;
        dets[f] = hi_d[f] + err + det_slack, dmins[f] = dmin;
        g1s[f] = g1;
    }
    if (inverted > 0 && bound_winding(h, X, Y, Z, big) == 0)
        return INFINITY;
    h->q_faces = nf, h->q_points = n, h->q_exp = e;
    /* back to the points' scale; a bound that underflows is raised to 2 · DBL_MIN, above any
     * volume that affect_hull3d_volume can round up to from below DBL_MIN */
    double u = ldexp(total / 6 * (1 + HULL_BOUND_SLACK), 3 * e);
    return u > 2 * DBL_MIN ? u : 2 * DBL_MIN;
}
