/*
 * svg.c — motion previews as standalone SVG film strips (see affect/svg.h).
 *
 * Usage:
 *   affect_svg_options opt; affect_svg_options_default(&opt);
 *   opt.view = AFFECT_SVG_SIDE; opt.title = "walk, happy";
 *   affect_roles roles; affect_roles_resolve(m, &roles);
 *   char *svg; size_t len; affect_error err;
 *   if (affect_motion_svg(m, &roles, &opt, &svg, &len, &err) == AFFECT_OK) {
 *       ...; affect_free(svg);
 *   }
 *
 * Layout: an optional title row, then opt->frames square panels of opt->panel_size pixels side
 * by side (frame k of n is round(k (T − 1) / (n − 1)), so the first and last frames are shown;
 * n is clamped to the frame count T, and n = 1 shows frame 0), then, when opt->labels, one
 * "frame N · T.TT s" caption under each panel (N is 0-based, T.TT = N / fps). Each panel is a
 * nested <svg> element, so whatever leaves it (trajectories, limbs) is clipped at its border.
 *
 * Axes. Let u = opt->up_axis and a < b the two other axes (y-up: a = x, b = z; z-up: a = x,
 * b = y; x-up: a = y, b = z). Screen right / screen up are:
 *   front  +a / +u     (y-up: looks along −z; z-up: along +y; x-up: along +z)
 *   side   +b / +u     (y-up: looks along +x; z-up: along −x; x-up: along −y)
 *   top    +a / ±b     looking down the up axis, never mirrored: screen up is +b when
 *                      (a, b, u) is a right-handed cycle (z-up, x-up) and −b otherwise (y-up).
 * SVG's y grows downward, so screen-up values are negated.
 *
 * Scale and placement. Joints that are proper ancestors of the pelvis role joint (a ground
 * "reference" root such as the corpus's joint_Root, which stays at the origin while the body
 * walks away) are neither drawn nor measured. Each frame has a centre: the pelvis role joint,
 * or the centroid of the joints when there is no pelvis. ONE scale serves every panel: the
 * largest extent over ALL frames of (front/side) twice the largest horizontal distance of a
 * joint from its frame's centre and the whole motion's vertical range, or (top) twice the
 * largest distance from the centre along either axis, fitted into the panel minus margins.
 * Each panel is centred horizontally on its frame's centre; vertically, front and side views
 * use one fixed placement for the whole motion (so jumps and crouches show), with a ground
 * line at the motion's lowest point; the top view centres both axes on the frame's centre.
 * A degenerate motion (one joint, all points equal) gets scale 1 and is drawn as a point.
 * Without a pelvis role nothing is hidden, so a static reference root far from the body
 * shrinks the figure: resolve or assign the pelvis role.
 *
 * Drawing, back to front: panel background, ground line, end-effector trajectories, bones,
 * joint dots, head circle. Bones join each joint to its parent (parents[j] ≥ 0), one <path>
 * per colour; without a skeleton (all parents −1) only dots are drawn. Colours: left blue,
 * right red, centre dark grey. A joint's side is that of its nearest ancestor-or-self with an
 * own side, where a joint's own side is (1) its role's side (left_*, right_* roles; pelvis,
 * spine, chest, neck and head are centre) or, (2) when both sides have resolved roles, left
 * (right) if it is an ancestor of some left (right) role joint but of no role joint of the
 * other side and of no centre role joint (clavicles such as Shoulder_L); joints with no such
 * ancestor are centre. NULL roles draw everything in one colour, without head or paths.
 * With a title and sides to show (and a strip at least 320 px wide) a small "left / right"
 * colour legend sits at the right end of the title row.
 * The head is a circle of radius 6.5 % of the body's size (the largest per-frame extent of
 * the visible joints along any axis), moved outwards along the neck-to-head direction in
 * front and side views so that it sits on the neck.
 *
 * Trajectories of the head, hands and feet roles (those that resolve) are sampled at ≤ 200
 * evenly spaced frames and written once into <defs> as polylines in the coordinates of the
 * first frame's centre; each panel shows them with a <use> translated by the shift of its own
 * centre, so in every panel they sit exactly where the joints pass relative to that frame's
 * body. Their ids, "afm<16 hex digits>-<k>", are a hash of the polylines themselves, so
 * several previews inlined in one HTML page never collide (equal ids mean equal content).
 *
 * Numbers: coordinates with one decimal (two for transforms and stroke widths), clamped to
 * ±1e6 so that pathological data cannot produce huge literals; output is byte-for-byte
 * deterministic. NULL options mean the defaults. Errors: AFFECT_ERR_INVALID for options ("frames
 * must be between 1 and 64, got 0", "panel_size must be between 32 and 1024, got 16", "up_axis must
 * be 0 (x), 1 (y) or 2 (z), got 3", "view must be 0 (front), 1 (side) or 2 (top), got 3"),
 * AFFECT_ERR_RANGE for a role or parent index outside the motion ("role left_hand: joint 40 out of
 * range (the motion has 27 joints)", "joint 3: parent 99 out of range (the motion has 27 joints)"),
 * AFFECT_ERR_FORMAT for a non-finite coordinate ("frame 5, joint 2: coordinate is not
 * finite"), AFFECT_ERR_NOMEM ("out of memory"); an empty motion
 * (AFFECT_ERR_INVALID, "the motion has no frames or no joints") cannot come from
 * affect_motion_create.
 */
#include "affect/svg.h"
#include "affect/strbuf.h"

#include <math.h>
#include <string.h>

#define SVG_MAX_FRAMES 64u
#define SVG_MIN_PANEL 32u
#define SVG_MAX_PANEL 1024u
#define SVG_TRAJ_POINTS 200u   /* most points of one trajectory polyline */
#define SVG_COORD_LIMIT 1e6    /* |coordinate| clamp, pixels */
#define SVG_MARGIN_SIDE 0.08   /* fraction of the panel left free at each side */
#define SVG_MARGIN_TOP 0.13    /* above the highest joint (room for the head circle) */
#define SVG_MARGIN_BOTTOM 0.07 /* below the lowest joint */
#define SVG_HEAD_RADIUS 0.065  /* head radius as a fraction of the body's size */

enum { SIDE_CENTRE = 0, SIDE_LEFT = 1, SIDE_RIGHT = 2, SIDE_NONE = 3 };

static const char *const side_colour[3] = {"#3a3f47", "#1f6fd1", "#e0452b"};

static const affect_role left_roles[] = {
    AFFECT_ROLE_LEFT_SHOULDER, AFFECT_ROLE_LEFT_ELBOW, AFFECT_ROLE_LEFT_HAND, AFFECT_ROLE_LEFT_HIP,
    AFFECT_ROLE_LEFT_KNEE,     AFFECT_ROLE_LEFT_FOOT,  AFFECT_ROLE_LEFT_TOE};
static const affect_role right_roles[] = {AFFECT_ROLE_RIGHT_SHOULDER, AFFECT_ROLE_RIGHT_ELBOW,
                                          AFFECT_ROLE_RIGHT_HAND,     AFFECT_ROLE_RIGHT_HIP,
                                          AFFECT_ROLE_RIGHT_KNEE,     AFFECT_ROLE_RIGHT_FOOT,
                                          AFFECT_ROLE_RIGHT_TOE};
static const affect_role centre_roles[] = {AFFECT_ROLE_PELVIS, AFFECT_ROLE_SPINE, AFFECT_ROLE_CHEST,
                                           AFFECT_ROLE_NECK, AFFECT_ROLE_HEAD};
static const affect_role effector_roles[] = {AFFECT_ROLE_HEAD, AFFECT_ROLE_LEFT_HAND,
                                             AFFECT_ROLE_RIGHT_HAND, AFFECT_ROLE_LEFT_FOOT,
                                             AFFECT_ROLE_RIGHT_FOOT};
#define N_EFFECTORS (sizeof effector_roles / sizeof effector_roles[0])

/* Everything the drawing needs, computed once. */
typedef struct svg_ctx {
    const affect_motion *m;
    const affect_svg_options *opt;
    int32_t role[AFFECT_ROLE_COUNT];
    int ax_h, ax_v; /* world axes drawn horizontally and vertically */
    double dir_v;   /* +1 when screen up is +ax_v, −1 when it is −ax_v */
    bool top;
    unsigned char *side;   /* per joint: SIDE_* */
    unsigned char *hidden; /* per joint: 1 for proper ancestors of the pelvis */
    double scale;          /* pixels per motion unit */
    double xc, yc;         /* panel point where a frame's centre is drawn */
    double vmin, vmid;     /* front/side: lowest point and fixed vertical centre */
    double head_r;         /* head circle radius, pixels */
    double panel;          /* panel size, pixels */
} svg_ctx;

void affect_svg_options_default(affect_svg_options *opt)
{
    opt->view = AFFECT_SVG_FRONT;
    opt->frames = 8;
    opt->panel_size = 160;
    opt->up_axis = 1;
    opt->trajectories = true;
    opt->labels = true;
    opt->title = NULL;
}

static affect_status check_options(const affect_svg_options *opt, affect_error *err)
{
    if (opt->frames < 1 || opt->frames > SVG_MAX_FRAMES)
        return affect_fail(err, AFFECT_ERR_INVALID, "frames must be between 1 and %u, got %u",
                           SVG_MAX_FRAMES, opt->frames);
    if (opt->panel_size < SVG_MIN_PANEL || opt->panel_size > SVG_MAX_PANEL)
        return affect_fail(err, AFFECT_ERR_INVALID, "panel_size must be between %u and %u, got %u",
                           SVG_MIN_PANEL, SVG_MAX_PANEL, opt->panel_size);
    if (opt->up_axis < 0 || opt->up_axis > 2)
        return affect_fail(err, AFFECT_ERR_INVALID, "up_axis must be 0 (x), 1 (y) or 2 (z), got %d",
                           opt->up_axis);
    int view = (int)opt->view;
    if (view < 0 || view > 2)
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "view must be 0 (front), 1 (side) or 2 (top), got %d", view);
    return AFFECT_OK;
}

/* Parents and roles in range, every coordinate finite. */
static affect_status check_motion(const affect_motion *m, const affect_roles *roles,
                                  affect_error *err)
{
    for (uint32_t j = 0; j < m->n_joints; j++) {
        int32_t p = m->parents[j];
        if (p < -1 || p >= (int64_t)m->n_joints)
            return affect_fail(err, AFFECT_ERR_RANGE,
                               "joint %u: parent %d out of range (the motion has %u joints)", j,
                               (int)p, m->n_joints);
    }
    if (roles) {
        for (int r = 0; r < AFFECT_ROLE_COUNT; r++) {
            int32_t j = roles->joint[r];
            if (j < -1 || j >= (int64_t)m->n_joints)
                return affect_fail(err, AFFECT_ERR_RANGE,
                                   "role %s: joint %d out of range (the motion has %u joints)",
                                   affect_role_name((affect_role)r), (int)j, m->n_joints);
        }
    }
    size_t n = (size_t)m->n_frames * m->n_joints * 3;
    for (size_t i = 0; i < n; i++) {
        if (!isfinite(m->pos[i])) {
            size_t k = i / 3;
            return affect_fail(err, AFFECT_ERR_FORMAT,
                               "frame %zu, joint %zu: coordinate is not finite", k / m->n_joints,
                               k % m->n_joints);
        }
    }
    return AFFECT_OK;
}

/* ---- sides and hidden joints ---- */

/* ORs bit into mark[] for k and its ancestors (k itself only when self), bounded against
 * cycles by the joint count. */
static void mark_ancestors(const affect_motion *m, int32_t k, bool self, unsigned char bit,
                           unsigned char *mark)
{
    if (!self)
        k = m->parents[k];
    for (uint32_t steps = 0; k >= 0 && steps < m->n_joints; steps++) {
        mark[k] |= bit;
        k = m->parents[k];
    }
}

/* Fills ctx->side and ctx->hidden; own and below are scratch arrays of n_joints bytes. */
static void classify_joints(svg_ctx *ctx, unsigned char *own, unsigned char *below)
{
    const affect_motion *m = ctx->m;
    uint32_t nj = m->n_joints;
    bool any_left = false, any_right = false;
    memset(own, SIDE_NONE, nj);
    for (size_t i = 0; i < sizeof centre_roles / sizeof centre_roles[0]; i++) {
        int32_t j = ctx->role[centre_roles[i]];
        if (j >= 0) {
            own[j] = SIDE_CENTRE;
            mark_ancestors(m, j, true, 4, below);
        }
    }
    for (size_t i = 0; i < sizeof left_roles / sizeof left_roles[0]; i++) {
        int32_t j = ctx->role[left_roles[i]];
        if (j >= 0) {
            own[j] = own[j] == SIDE_NONE ? SIDE_LEFT : SIDE_CENTRE;
            mark_ancestors(m, j, false, 1, below);
            any_left = true;
        }
    }
    for (size_t i = 0; i < sizeof right_roles / sizeof right_roles[0]; i++) {
        int32_t j = ctx->role[right_roles[i]];
        if (j >= 0) {
            own[j] = own[j] == SIDE_NONE ? SIDE_RIGHT : SIDE_CENTRE;
            mark_ancestors(m, j, false, 2, below);
            any_right = true;
        }
    }
    if (any_left && any_right) {
        for (uint32_t j = 0; j < nj; j++) {
            if (own[j] == SIDE_NONE && below[j] == 1)
                own[j] = SIDE_LEFT;
            else if (own[j] == SIDE_NONE && below[j] == 2)
                own[j] = SIDE_RIGHT;
        }
    }
    for (uint32_t j = 0; j < nj; j++) {
        int32_t k = (int32_t)j;
        for (uint32_t steps = 0; k >= 0 && own[k] == SIDE_NONE && steps < nj; steps++)
            k = m->parents[k];
        ctx->side[j] = k >= 0 && own[k] != SIDE_NONE ? own[k] : SIDE_CENTRE;
    }
    memset(ctx->hidden, 0, nj);
    if (ctx->role[AFFECT_ROLE_PELVIS] >= 0)
        mark_ancestors(m, ctx->role[AFFECT_ROLE_PELVIS], false, 1, ctx->hidden);
}

/* ---- geometry ---- */

/* The centre of frame t along the drawn axes: the pelvis, or the centroid of visible joints. */
static void frame_centre(const svg_ctx *ctx, uint32_t t, double *ch, double *cv)
{
    const affect_motion *m = ctx->m;
    int32_t pelvis = ctx->role[AFFECT_ROLE_PELVIS];
    if (pelvis >= 0) {
        const float *p = affect_motion_at(m, t, (uint32_t)pelvis);
        *ch = p[ctx->ax_h];
        *cv = p[ctx->ax_v];
        return;
    }
    double sh = 0, sv = 0;
    for (uint32_t j = 0; j < m->n_joints; j++) {
        const float *p = affect_motion_at(m, t, j);
        sh += p[ctx->ax_h];
        sv += p[ctx->ax_v];
    }
    *ch = sh / m->n_joints;
    *cv = sv / m->n_joints;
}

/* Scale, placement and head size from every frame of the motion. */
static void measure(svg_ctx *ctx)
{
    const affect_motion *m = ctx->m;
    double maxdev = 0, vmin = HUGE_VAL, vmax = -HUGE_VAL, body = 0;
    for (uint32_t t = 0; t < m->n_frames; t++) {
        double ch, cv, lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL},
                       hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
        frame_centre(ctx, t, &ch, &cv);
        for (uint32_t j = 0; j < m->n_joints; j++) {
            if (ctx->hidden[j])
                continue;
            const float *p = affect_motion_at(m, t, j);
            maxdev = fmax(maxdev, fabs(p[ctx->ax_h] - ch));
            if (ctx->top) {
                maxdev = fmax(maxdev, fabs(p[ctx->ax_v] - cv));
            } else {
                vmin = fmin(vmin, p[ctx->ax_v]);
                vmax = fmax(vmax, p[ctx->ax_v]);
            }
            for (int a = 0; a < 3; a++) {
                lo[a] = fmin(lo[a], p[a]);
                hi[a] = fmax(hi[a], p[a]);
            }
        }
        for (int a = 0; a < 3; a++)
            body = fmax(body, hi[a] - lo[a]);
    }
    double panel = ctx->panel;
    double avail_h = panel * (1 - 2 * SVG_MARGIN_SIDE);
    double avail_v = ctx->top ? avail_h : panel * (1 - SVG_MARGIN_TOP - SVG_MARGIN_BOTTOM);
    double scale = HUGE_VAL;
    if (maxdev > 0)
        scale = avail_h / (2 * maxdev);
    if (!ctx->top && vmax - vmin > 0)
        scale = fmin(scale, avail_v / (vmax - vmin));
    if (!(scale < HUGE_VAL) || !(scale > 0))
        scale = 1;
    ctx->scale = scale;
    ctx->xc = panel / 2;
    if (ctx->top) {
        ctx->yc = panel / 2;
        ctx->vmin = ctx->vmid = 0;
    } else {
        ctx->yc = panel * SVG_MARGIN_TOP + avail_v / 2;
        ctx->vmin = vmin;
        ctx->vmid = vmin + (vmax - vmin) / 2;
    }
    ctx->head_r = fmin(fmax(SVG_HEAD_RADIUS * body * scale, 2.0), panel / 8);
}

/* Coordinates clamped to a sane range (non-finite never happens after check_motion, but a
 * value stays printable whatever happens). */
static double clamp_coord(double v)
{
    if (!(v > -SVG_COORD_LIMIT))
        return -SVG_COORD_LIMIT;
    if (v > SVG_COORD_LIMIT)
        return SVG_COORD_LIMIT;
    return v;
}

/* Rounds a pixel coordinate to tenths, as printed. */
static long tenths(double v)
{
    return lround(clamp_coord(v) * 10);
}

static void put_tenths(affect_strbuf *sb, long v)
{
    affect_strbuf_fixed(sb, (double)v / 10, 1);
}

static void put_num(affect_strbuf *sb, double v, int decimals)
{
    affect_strbuf_fixed(sb, clamp_coord(v), decimals);
}

/* Panel coordinates, in tenths of a pixel, of joint j at frame t for a frame centre (ch, cv). */
static void project(const svg_ctx *ctx, uint32_t t, uint32_t j, double ch, double cv, long *x,
                    long *y)
{
    const float *p = affect_motion_at(ctx->m, t, j);
    *x = tenths(ctx->xc + ctx->scale * (p[ctx->ax_h] - ch));
    *y = tenths(ctx->yc - ctx->dir_v * ctx->scale * (p[ctx->ax_v] - cv));
}

/* ---- document parts ---- */

static uint64_t fnv1a(const char *s, size_t n, uint64_t h)
{
    for (size_t i = 0; i < n; i++) {
        h ^= (unsigned char)s[i];
        h *= 1099511628211u;
    }
    return h;
}

/* The trajectories' polylines (in the coordinates of frame 0's centre) into sb as <defs>;
 * *count receives how many were written, id the shared id prefix. */
static void write_trajectories(const svg_ctx *ctx, affect_strbuf *sb, affect_strbuf *tmp,
                               size_t *count, char id[24])
{
    const affect_motion *m = ctx->m;
    size_t start[N_EFFECTORS + 1];
    int colour[N_EFFECTORS];
    size_t n = 0;
    double ch0, cv0;
    frame_centre(ctx, 0, &ch0, &cv0);
    if (!ctx->top)
        cv0 = ctx->vmid;
    uint32_t points = m->n_frames < SVG_TRAJ_POINTS ? m->n_frames : SVG_TRAJ_POINTS;
    for (size_t e = 0; e < N_EFFECTORS; e++) {
        int32_t j = ctx->role[effector_roles[e]];
        if (j < 0 || ctx->hidden[j])
            continue;
        start[n] = tmp->len;
        colour[n] = ctx->side[j];
        long px = 0, py = 0;
        for (uint32_t k = 0; k < points; k++) {
            uint32_t t = points > 1
                             ? (uint32_t)(((uint64_t)k * (m->n_frames - 1) + (points - 1) / 2) /
                                          (points - 1))
                             : 0;
            long x, y;
            project(ctx, t, (uint32_t)j, ch0, cv0, &x, &y);
            x -= tenths(ctx->xc);
            y -= tenths(ctx->yc);
            if (k > 0 && x == px && y == py)
                continue;
            if (k > 0)
                affect_strbuf_putc(tmp, ' ');
            put_tenths(tmp, x);
            affect_strbuf_putc(tmp, ',');
            put_tenths(tmp, y);
            px = x;
            py = y;
        }
        n++;
    }
    start[n] = tmp->len;
    *count = tmp->failed ? 0 : n;
    if (*count == 0)
        return;
    uint64_t h = 14695981039346656037u;
    for (size_t i = 0; i < n; i++) {
        h = fnv1a(side_colour[colour[i]], strlen(side_colour[colour[i]]), h);
        h = fnv1a(tmp->data + start[i], start[i + 1] - start[i], h);
        h = fnv1a("|", 1, h);
    }
    static const char hex[] = "0123456789abcdef";
    memcpy(id, "afm", 3);
    for (int i = 0; i < 16; i++)
        id[3 + i] = hex[(h >> (60 - 4 * i)) & 15];
    id[19] = '\0';
    affect_strbuf_puts(sb, "<defs>\n");
    for (size_t i = 0; i < n; i++) {
        affect_strbuf_printf(sb, "<polyline id=\"%s-%zu\" stroke=\"%s\" points=\"", id, i,
                             side_colour[colour[i]]);
        affect_strbuf_append(sb, tmp->data + start[i], start[i + 1] - start[i]);
        affect_strbuf_puts(sb, "\"/>\n");
    }
    affect_strbuf_puts(sb, "</defs>\n");
}

/* Bones of one colour as a single path; nothing when there are none. */
static void write_bones(const svg_ctx *ctx, affect_strbuf *sb, uint32_t t, double ch, double cv,
                        int side)
{
    const affect_motion *m = ctx->m;
    bool open = false;
    for (uint32_t j = 0; j < m->n_joints; j++) {
        int32_t p = m->parents[j];
        if (p < 0 || ctx->side[j] != side || ctx->hidden[j] || ctx->hidden[p])
            continue;
        long x0, y0, x1, y1;
        project(ctx, t, (uint32_t)p, ch, cv, &x0, &y0);
        project(ctx, t, j, ch, cv, &x1, &y1);
        if (x0 == x1 && y0 == y1)
            continue;
        if (!open) {
            affect_strbuf_printf(sb, "<path stroke=\"%s\" d=\"", side_colour[side]);
            open = true;
        }
        affect_strbuf_putc(sb, 'M');
        put_tenths(sb, x0);
        affect_strbuf_putc(sb, ' ');
        put_tenths(sb, y0);
        affect_strbuf_putc(sb, 'L');
        put_tenths(sb, x1);
        affect_strbuf_putc(sb, ' ');
        put_tenths(sb, y1);
    }
    if (open)
        affect_strbuf_puts(sb, "\"/>\n");
}

/* Joint dots of one colour; a joint drawn exactly on its (visible) parent is skipped. */
static void write_dots(const svg_ctx *ctx, affect_strbuf *sb, uint32_t t, double ch, double cv,
                       int side, double r)
{
    const affect_motion *m = ctx->m;
    bool open = false;
    for (uint32_t j = 0; j < m->n_joints; j++) {
        if (ctx->side[j] != side || ctx->hidden[j])
            continue;
        long x, y;
        project(ctx, t, j, ch, cv, &x, &y);
        int32_t p = m->parents[j];
        if (p >= 0 && !ctx->hidden[p]) {
            long px, py;
            project(ctx, t, (uint32_t)p, ch, cv, &px, &py);
            if (px == x && py == y)
                continue;
        }
        if (!open) {
            affect_strbuf_printf(sb, "<g fill=\"%s\">", side_colour[side]);
            open = true;
        }
        affect_strbuf_puts(sb, "<circle cx=\"");
        put_tenths(sb, x);
        affect_strbuf_puts(sb, "\" cy=\"");
        put_tenths(sb, y);
        affect_strbuf_puts(sb, "\" r=\"");
        put_num(sb, r, 2);
        affect_strbuf_puts(sb, "\"/>");
    }
    if (open)
        affect_strbuf_puts(sb, "</g>\n");
}

static void write_head(const svg_ctx *ctx, affect_strbuf *sb, uint32_t t, double ch, double cv,
                       double stroke)
{
    int32_t head = ctx->role[AFFECT_ROLE_HEAD];
    if (head < 0 || ctx->hidden[head])
        return;
    long x, y;
    project(ctx, t, (uint32_t)head, ch, cv, &x, &y);
    double cx = x / 10.0, cy = y / 10.0, r = ctx->top ? 0.6 * ctx->head_r : ctx->head_r;
    int32_t p = ctx->m->parents[head];
    if (!ctx->top && p >= 0 && !ctx->hidden[p]) {
        long px, py;
        project(ctx, t, (uint32_t)p, ch, cv, &px, &py);
        double dx = (x - px) / 10.0, dy = (y - py) / 10.0, d = sqrt(dx * dx + dy * dy);
        if (d > 0.2 * r) {
            cx += 0.7 * r * dx / d;
            cy += 0.7 * r * dy / d;
        }
    }
    affect_strbuf_puts(sb, "<circle cx=\"");
    put_num(sb, cx, 1);
    affect_strbuf_puts(sb, "\" cy=\"");
    put_num(sb, cy, 1);
    affect_strbuf_puts(sb, "\" r=\"");
    put_num(sb, r, 1);
    affect_strbuf_printf(sb, "\" fill=\"%s\" stroke=\"%s\" stroke-width=\"",
                         ctx->top ? "none" : "#fff", side_colour[ctx->side[head]]);
    put_num(sb, stroke, 2);
    affect_strbuf_puts(sb, "\"/>\n");
}

/* "frame N · T.TT s" with the time printed from integers (locale-independent). */
static void write_label_text(affect_strbuf *sb, uint32_t t, double fps)
{
    double secs = t / fps;
    affect_strbuf_printf(sb, "frame %u \xc2\xb7 ", t);
    if (secs * 100 < 9e15) {
        long long cs = llround(secs * 100);
        affect_strbuf_printf(sb, "%lld.%02lld s", cs / 100, cs % 100);
    } else {
        affect_strbuf_double(sb, secs);
        affect_strbuf_puts(sb, " s");
    }
}

static void write_panel(const svg_ctx *ctx, affect_strbuf *sb, uint32_t t, double x0, double y0,
                        size_t n_traj, const char *traj_id)
{
    const affect_motion *m = ctx->m;
    double panel = ctx->panel;
    double ch, cv;
    frame_centre(ctx, t, &ch, &cv);
    if (!ctx->top)
        cv = ctx->vmid;
    affect_strbuf_puts(sb, "<svg x=\"");
    put_num(sb, x0, 1);
    affect_strbuf_puts(sb, "\" y=\"");
    put_num(sb, y0, 1);
    affect_strbuf_printf(sb, "\" width=\"%u\" height=\"%u\">\n", ctx->opt->panel_size,
                         ctx->opt->panel_size);
    affect_strbuf_printf(sb,
                         "<rect x=\"1\" y=\"1\" width=\"%u\" height=\"%u\" rx=\"4\" "
                         "fill=\"#f5f6f8\"/>\n",
                         ctx->opt->panel_size - 2, ctx->opt->panel_size - 2);
    if (!ctx->top) {
        long gy = tenths(ctx->yc - ctx->scale * (ctx->vmin - ctx->vmid));
        affect_strbuf_puts(sb, "<path stroke=\"#b9bec6\" stroke-width=\"1\" d=\"M0 ");
        put_tenths(sb, gy);
        affect_strbuf_printf(sb, "H%u\"/>\n", ctx->opt->panel_size);
    }
    if (n_traj > 0) {
        double ch0, cv0;
        frame_centre(ctx, 0, &ch0, &cv0);
        if (!ctx->top)
            cv0 = ctx->vmid;
        double tx = tenths(ctx->xc) / 10.0 + ctx->scale * (ch0 - ch);
        double ty = tenths(ctx->yc) / 10.0 - ctx->dir_v * ctx->scale * (cv0 - cv);
        affect_strbuf_puts(sb, "<g fill=\"none\" stroke-width=\"1.2\" stroke-opacity=\"0.35\" "
                               "stroke-linejoin=\"round\" transform=\"translate(");
        put_num(sb, tx, 2);
        affect_strbuf_putc(sb, ' ');
        put_num(sb, ty, 2);
        affect_strbuf_puts(sb, ")\">");
        for (size_t i = 0; i < n_traj; i++)
            affect_strbuf_printf(sb, "<use href=\"#%s-%zu\"/>", traj_id, i);
        affect_strbuf_puts(sb, "</g>\n");
    }
    double stroke = fmax(1.5, panel / 55);
    bool skeleton = false;
    for (uint32_t j = 0; j < m->n_joints && !skeleton; j++)
        skeleton = m->parents[j] >= 0;
    if (skeleton) {
        affect_strbuf_puts(sb, "<g fill=\"none\" stroke-linecap=\"round\" "
                               "stroke-linejoin=\"round\" stroke-width=\"");
        put_num(sb, stroke, 2);
        affect_strbuf_puts(sb, "\">\n");
        for (int s = 0; s < 3; s++)
            write_bones(ctx, sb, t, ch, cv, s);
        affect_strbuf_puts(sb, "</g>\n");
    }
    double r = skeleton ? stroke * 0.62 : fmax(1.5, panel / 60);
    for (int s = 0; s < 3; s++)
        write_dots(ctx, sb, t, ch, cv, s, r);
    write_head(ctx, sb, t, ch, cv, stroke * 0.8);
    affect_strbuf_puts(sb, "</svg>\n");
}

/* The whole document into sb (tmp is scratch for the trajectories). */
static void write_document(const svg_ctx *ctx, affect_strbuf *sb, affect_strbuf *tmp)
{
    const affect_motion *m = ctx->m;
    const affect_svg_options *opt = ctx->opt;
    uint32_t n = opt->frames < m->n_frames ? opt->frames : m->n_frames;
    unsigned panel = opt->panel_size;
    double title_fs = panel >= 96 ? 14 : 11, title_h = opt->title ? title_fs + 12 : 0;
    double label_fs = fmin(12, panel / 10.5), label_h = opt->labels ? label_fs + 8 : 0;
    double width = (double)n * panel, height = title_h + panel + label_h;

    affect_strbuf_puts(sb, "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"");
    put_num(sb, width, 1);
    affect_strbuf_puts(sb, "\" height=\"");
    put_num(sb, height, 1);
    affect_strbuf_puts(sb, "\" viewBox=\"0 0 ");
    put_num(sb, width, 1);
    affect_strbuf_putc(sb, ' ');
    put_num(sb, height, 1);
    affect_strbuf_puts(sb, "\" font-family=\"sans-serif\">\n"
                           "<rect width=\"100%\" height=\"100%\" fill=\"#fff\"/>\n");
    if (opt->title) {
        affect_strbuf_puts(sb, "<text x=\"6\" y=\"");
        put_num(sb, title_fs + 4, 1);
        affect_strbuf_puts(sb, "\" font-size=\"");
        put_num(sb, title_fs, 1);
        affect_strbuf_puts(sb, "\" font-weight=\"bold\" fill=\"#222\">");
        affect_strbuf_xml(sb, opt->title);
        affect_strbuf_puts(sb, "</text>\n");
        bool sides = false;
        for (uint32_t j = 0; j < m->n_joints && !sides; j++)
            sides = ctx->side[j] != SIDE_CENTRE && !ctx->hidden[j];
        if (sides && width >= 320) {
            affect_strbuf_puts(sb, "<text x=\"");
            put_num(sb, width - 6, 1);
            affect_strbuf_puts(sb, "\" y=\"");
            put_num(sb, title_fs + 4, 1);
            affect_strbuf_printf(sb,
                                 "\" font-size=\"11\" text-anchor=\"end\" fill=\"#777\">"
                                 "<tspan fill=\"%s\">\xe2\x96\xa0 left</tspan>  "
                                 "<tspan fill=\"%s\">\xe2\x96\xa0 right</tspan></text>\n",
                                 side_colour[SIDE_LEFT], side_colour[SIDE_RIGHT]);
        }
    }
    size_t n_traj = 0;
    char traj_id[24] = "";
    if (opt->trajectories)
        write_trajectories(ctx, sb, tmp, &n_traj, traj_id);
    for (uint32_t k = 0; k < n; k++) {
        uint32_t t =
            n > 1 ? (uint32_t)(((uint64_t)k * (m->n_frames - 1) + (n - 1) / 2) / (n - 1)) : 0;
        write_panel(ctx, sb, t, (double)k * panel, title_h, n_traj, traj_id);
        if (opt->labels) {
            affect_strbuf_puts(sb, "<text x=\"");
            put_num(sb, (k + 0.5) * panel, 1);
            affect_strbuf_puts(sb, "\" y=\"");
            put_num(sb, title_h + panel + label_fs + 2, 1);
            affect_strbuf_puts(sb, "\" font-size=\"");
            put_num(sb, label_fs, 1);
            affect_strbuf_puts(sb, "\" text-anchor=\"middle\" fill=\"#555\">");
            write_label_text(sb, t, m->fps);
            affect_strbuf_puts(sb, "</text>\n");
        }
    }
    affect_strbuf_puts(sb, "</svg>\n");
    if (tmp->failed)
        sb->failed = true;
}

affect_status affect_motion_svg(const affect_motion *m, const affect_roles *roles,
                                const affect_svg_options *opt, char **out, size_t *len,
                                affect_error *err)
{
    affect_svg_options defaults;
    affect_strbuf sb, tmp;
    svg_ctx ctx;
    affect_status st;
    affect_strbuf_init(&sb);
    affect_strbuf_init(&tmp);
    memset(&ctx, 0, sizeof ctx);
    *out = NULL;
    if (len)
        *len = 0;
    if (!opt) {
        affect_svg_options_default(&defaults);
        opt = &defaults;
    }
    if ((st = check_options(opt, err)) != AFFECT_OK)
        goto cleanup;
    if (m->n_frames == 0 || m->n_joints == 0) {
        st = affect_fail(err, AFFECT_ERR_INVALID, "the motion has no frames or no joints");
        goto cleanup;
    }
    if ((st = check_motion(m, roles, err)) != AFFECT_OK)
        goto cleanup;

    ctx.m = m;
    ctx.opt = opt;
    ctx.panel = opt->panel_size;
    for (int r = 0; r < AFFECT_ROLE_COUNT; r++)
        ctx.role[r] = roles ? roles->joint[r] : -1;
    int up = opt->up_axis, a = up == 0 ? 1 : 0, b = up == 2 ? 1 : 2;
    ctx.top = opt->view == AFFECT_SVG_TOP;
    ctx.ax_h = opt->view == AFFECT_SVG_SIDE ? b : a;
    ctx.ax_v = ctx.top ? b : up;
    /* (a, b, up) is a right-handed cycle when b follows a and up follows b */
    ctx.dir_v = !ctx.top || (b == (a + 1) % 3 && up == (b + 1) % 3) ? 1 : -1;
    /* one block: side, hidden, and two scratch arrays for classify_joints */
    ctx.side = affect_calloc(m->n_joints, 4);
    if (!ctx.side) {
        st = affect_nomem(err);
        goto cleanup;
    }
    ctx.hidden = ctx.side + m->n_joints;
    classify_joints(&ctx, ctx.side + 2 * (size_t)m->n_joints, ctx.side + 3 * (size_t)m->n_joints);
    measure(&ctx);
    write_document(&ctx, &sb, &tmp);
    st = affect_strbuf_finish(&sb, out, len, err);

cleanup:
    affect_strbuf_free(&sb);
    affect_strbuf_free(&tmp);
    affect_free(ctx.side);
    return st;
}
