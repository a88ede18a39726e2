/*
 * svg.c — motion previews as standalone SVG film strips (see affect/svg.h).
 *
 * Usage: see the block at the top of affect/svg.h (compiled by the style/header-usage test).
 *
 * Layout of a strip: an optional title row, then opt->frames square panels of opt->panel_size
 * pixels side by side (frame k of n is round(k (T − 1) / (n − 1)), so the first and last frames are
 * shown; n is clamped to the frame count T, and n = 1 shows frame 0), then, when opt->labels, one
 * "frame N · T.TT s" caption under each panel (N is 0-based, T.TT = N / fps; "state N+1" with
 * opt->state_labels). Each panel is a nested <svg> element, so whatever leaves it (trajectories,
 * limbs) is clipped at its border. A group (affect_motion_svg_group) stacks one such strip per
 * motion, each under its caption, below one title row.
 *
 * Animation (opt->animate): one panel per motion side by side (title row above; under each a
 * time bar, the caption and "T.TT s · N frames"). n keyframes at the times tf_k = k (T − 1) /
 * (n − 1) (n = opt->keyframes, or 1 + ceil(AFFECT_SVG_KEY_RATE × (T − 1) / fps) up to
 * AFFECT_SVG_KEY_AUTO_MAX; at most T), positions interpolated linearly between the frames around
 * tf_k. Each bone colour is one <path> whose d is animated (<animate attributeName="d"
 * values="d_0;…;d_n−1">): every keyframe writes every bone, zero-length ones included, so the
 * lists have the same commands and the browser interpolates them; without a skeleton the joints
 * are zero-length segments drawn with round caps. The head circle's cx and cy, the facing
 * marker's points and the trajectories' translation are animated the same way, and the time
 * bar's width grows from 0 to the panel's over the loop. Evenly spaced values need no keyTimes;
 * every element has dur = (T − 1) / fps seconds and repeatCount="indefinite", so the loop plays
 * in real time. A one-frame motion is drawn still.
 *
 * Axes. Let u = opt->up_axis and a < b the two other axes (y-up: a = x, b = z; z-up: a = x,
 * b = y; x-up: a = y, b = z). Screen right / screen up are:
 *   front  +a / +u     (y-up: looks along −z; z-up: along +y; x-up: along +z)
 *   side   +b / +u     (y-up: looks along +x; z-up: along −x; x-up: along −y)
 *   top    +a / ±b     looking down the up axis, never mirrored: screen up is +b when
 *                      (a, b, u) is a right-handed cycle (z-up, x-up) and −b otherwise (y-up).
 * SVG's y grows downward, so screen-up values are negated.
 *
 * Top view: looking down the up axis; when the centre's travel from the first to the last frame
 * is longer than SVG_TOP_TRAVEL × the body's size, the view is turned (a rotation, never a
 * mirror) so that this travel points right: a walk reads left to right. Its only trajectory is
 * the centre's (the pelvis's path: the five end-effector paths of a walk seen from above were a
 * tangle), and a triangle beside the head points where the body faces, (left − right shoulder,
 * else hip) × up, projected; none when neither pair resolves or the body is edge-on.
 *
 * Scale and placement. Joints that are proper ancestors of the pelvis role joint (a ground
 * "reference" root such as the corpus's joint_Root, which stays at the origin while the body
 * walks away) are neither drawn nor measured. Each frame has a centre: the pelvis role joint,
 * or the centroid of the joints when there is no pelvis. ONE scale serves every panel: the
 * largest extent over ALL frames of (front/side) twice the largest horizontal distance of a
 * joint from its frame's centre and the whole motion's vertical range, or (top) twice the
 * largest distance from the centre (any turn keeps it), fitted into the panel minus margins; a
 * group uses the smallest of its motions' scales.
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
 * Trajectories (front and side) of the head, hands and feet roles (those that resolve) are sampled
 * at ≤ 200 evenly spaced frames and written once into <defs> as polylines in the coordinates of the
 * first frame's centre; each panel shows them with a <use> translated by the shift of its own
 * centre, so in every panel they sit exactly where the joints pass relative to that frame's
 * body. Their ids, "afm<16 hex digits>-<k>", are a hash of the polylines themselves (and of
 * the motion's place in a group, after the first), so several previews inlined in one HTML page
 * never collide (equal ids mean equal content).
 *
 * Numbers: coordinates with one decimal (two for transforms and stroke widths), clamped to
 * ±1e6 so that pathological data cannot produce huge literals; output is byte-for-byte
 * deterministic. NULL options mean the defaults. Errors: AFFECT_ERR_INVALID for options ("frames
 * must be between 1 and 64, got 0", "keyframes must be 0 (automatic) or between 2 and 1000, got
 * 1", "panel_size must be between 32 and 1024, got 16", "up_axis must
 * be 0 (x), 1 (y) or 2 (z), got 3", "view must be 0 (front), 1 (side) or 2 (top), got 3"),
 * AFFECT_ERR_RANGE for a role or parent index outside the motion ("role left_hand: joint 40 out of
 * range (the motion has 27 joints)", "joint 3: parent 99 out of range (the motion has 27 joints)"),
 * AFFECT_ERR_FORMAT for a non-finite coordinate ("frame 5, joint 2: coordinate is not
 * finite"; in a group of several, "motion 2: " before it), AFFECT_ERR_NOMEM ("out of memory"),
 * "a group holds 1 to 64 motions, got 0"; an empty motion
 * (AFFECT_ERR_INVALID, "the motion has no frames or no joints") cannot come from
 * affect_motion_create.
 */
#include "affect/svg.h"
#include "util/strbuf.h"

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
#define SVG_TOP_TRAVEL 0.25    /* top view: travel (× body size) from which the view turns */
#define SVG_TIME_BAR 3.0       /* animated panels: height of the time bar, pixels */
#define SVG_CAPTION_EM 0.6     /* estimated advance of a caption's character, em */

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

/* Everything the drawing of one motion needs, computed once. */
typedef struct svg_ctx {
    const affect_motion *m;
    const affect_svg_options *opt;
    int32_t role[AFFECT_ROLE_COUNT];
    int ax_h, ax_v; /* world axes drawn horizontally and vertically */
    double dir_v;   /* +1 when screen up is +ax_v, −1 when it is −ax_v */
    bool top;
    double rot_c, rot_s;   /* top view: screen turned so that the travel points right */
    unsigned char *side;   /* per joint: SIDE_* */
    unsigned char *hidden; /* per joint: 1 for proper ancestors of the pelvis */
    double fit;            /* the scale at which this motion alone fills its panels */
    double body;           /* the body's size, motion units */
    double scale;          /* pixels per motion unit */
    double xc, yc;         /* panel point where a frame's centre is drawn */
    double vmin, vmax;     /* front/side: the motion's vertical range */
    double vmid;           /* front/side: fixed vertical centre */
    double head_r;         /* head circle radius, pixels */
    double panel;          /* panel size, pixels */
    uint64_t salt;         /* mixed into the trajectory ids: the motion's place in a group */
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
    opt->animate = false;
    opt->keyframes = 0;
    opt->state_labels = false;
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
    if (opt->keyframes == 1 || opt->keyframes > AFFECT_SVG_MAX_KEYFRAMES)
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "keyframes must be 0 (automatic) or between 2 and %u, got %u",
                           AFFECT_SVG_MAX_KEYFRAMES, opt->keyframes);
    return AFFECT_OK;
}

/* Parents and roles in range, every coordinate finite. */
static affect_status check_motion(const affect_motion *m, const affect_roles *roles,
                                  affect_error *err)
{
    if (m->n_frames == 0 || m->n_joints == 0)
        return affect_fail(err, AFFECT_ERR_INVALID, "the motion has no frames or no joints");
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

/* ---- geometry ----
 * Time is a frame number tf, whole for the strip's panels and fractional for the keyframes of
 * an animation (positions are then interpolated linearly between the two frames around it). */

/* Position of joint j at time tf. */
static void joint_at(const svg_ctx *ctx, double tf, uint32_t j, double p[3])
{
    const affect_motion *m = ctx->m;
    uint32_t t = (uint32_t)tf;
    double w = tf - t;
    const float *a = affect_motion_at(m, t, j);
    if (w <= 0 || t + 1 >= m->n_frames) {
        p[0] = a[0], p[1] = a[1], p[2] = a[2];
        return;
    }
    const float *b = affect_motion_at(m, t + 1, j);
    for (int k = 0; k < 3; k++)
        p[k] = a[k] + w * ((double)b[k] - a[k]);
}

/* The centre at time tf along the drawn axes: the pelvis, or the centroid of the joints. */
static void frame_centre(const svg_ctx *ctx, double tf, double *ch, double *cv)
{
    const affect_motion *m = ctx->m;
    int32_t pelvis = ctx->role[AFFECT_ROLE_PELVIS];
    double p[3];
    if (pelvis >= 0) {
        joint_at(ctx, tf, (uint32_t)pelvis, p);
        *ch = p[ctx->ax_h];
        *cv = p[ctx->ax_v];
        return;
    }
    double sh = 0, sv = 0;
    for (uint32_t j = 0; j < m->n_joints; j++) {
        joint_at(ctx, tf, j, p);
        sh += p[ctx->ax_h];
        sv += p[ctx->ax_v];
    }
    *ch = sh / m->n_joints;
    *cv = sv / m->n_joints;
}

/* A world offset along the drawn axes (dh, dv) as a screen offset (right, up), motion units. */
static void to_screen(const svg_ctx *ctx, double dh, double dv, double *sx, double *sy)
{
    double y = ctx->dir_v * dv;
    *sx = ctx->rot_c * dh + ctx->rot_s * y;
    *sy = -ctx->rot_s * dh + ctx->rot_c * y;
}

/* What fits this motion (ctx->fit, ctx->body, vertical range) and, in the top view, the turn. */
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
            if (ctx->top) { /* any turn keeps the distance from the centre */
                maxdev = fmax(maxdev, hypot(p[ctx->ax_h] - ch, p[ctx->ax_v] - cv));
            } else {
                maxdev = fmax(maxdev, fabs(p[ctx->ax_h] - ch));
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
    ctx->fit = scale;
    ctx->body = body;
    ctx->vmin = ctx->top ? 0 : vmin;
    ctx->vmax = ctx->top ? 0 : vmax;
    ctx->rot_c = 1;
    ctx->rot_s = 0;
    if (ctx->top) {
        double h0, v0, h1, v1;
        frame_centre(ctx, 0, &h0, &v0);
        frame_centre(ctx, m->n_frames - 1, &h1, &v1);
        double dx = h1 - h0, dy = ctx->dir_v * (v1 - v0), d = hypot(dx, dy);
        if (d > SVG_TOP_TRAVEL * body && d > 0) {
            ctx->rot_c = dx / d;
            ctx->rot_s = dy / d;
        }
    }
}

/* Scale and placement at a given scale (the motion's own fit, or a group's). */
static void place(svg_ctx *ctx, double scale)
{
    double panel = ctx->panel;
    double avail_v = panel * (1 - SVG_MARGIN_TOP - SVG_MARGIN_BOTTOM);
    ctx->scale = scale;
    ctx->xc = panel / 2;
    if (ctx->top) {
        ctx->yc = panel / 2;
        ctx->vmid = 0;
    } else {
        ctx->yc = panel * SVG_MARGIN_TOP + avail_v / 2;
        ctx->vmid = ctx->vmin + (ctx->vmax - ctx->vmin) / 2;
    }
    ctx->head_r = fmin(fmax(SVG_HEAD_RADIUS * ctx->body * scale, 2.0), panel / 8);
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

/* Panel coordinates, in tenths of a pixel, of a point (h, v) along the drawn axes for a centre
 * (ch, cv). */
static void project_hv(const svg_ctx *ctx, double h, double v, double ch, double cv, long *x,
                       long *y)
{
    double sx, sy;
    to_screen(ctx, h - ch, v - cv, &sx, &sy);
    *x = tenths(ctx->xc + ctx->scale * sx);
    *y = tenths(ctx->yc - ctx->scale * sy);
}

/* The same for joint j at time tf. */
static void project(const svg_ctx *ctx, double tf, uint32_t j, double ch, double cv, long *x,
                    long *y)
{
    double p[3];
    joint_at(ctx, tf, j, p);
    project_hv(ctx, p[ctx->ax_h], p[ctx->ax_v], ch, cv, x, y);
}

/* The centre a panel at time tf is drawn around (front and side: the fixed vertical centre). */
static void panel_centre(const svg_ctx *ctx, double tf, double *ch, double *cv)
{
    frame_centre(ctx, tf, ch, cv);
    if (!ctx->top)
        *cv = ctx->vmid;
}

/* The shift, pixels, of the trajectories (drawn about frame 0's centre) in a panel at time tf. */
static void traj_shift(const svg_ctx *ctx, double tf, double *tx, double *ty)
{
    double ch0, cv0, ch, cv, sx, sy;
    panel_centre(ctx, 0, &ch0, &cv0);
    panel_centre(ctx, tf, &ch, &cv);
    to_screen(ctx, ch0 - ch, cv0 - cv, &sx, &sy);
    *tx = tenths(ctx->xc) / 10.0 + ctx->scale * sx;
    *ty = tenths(ctx->yc) / 10.0 - ctx->scale * sy;
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

/* The trajectories' polylines (about frame 0's centre) into sb as <defs>: the head, hand and
 * foot paths in front and side views, the centre's (pelvis) path in the top view. *count
 * receives how many were written, id the shared id prefix. */
static void write_trajectories(const svg_ctx *ctx, affect_strbuf *sb, affect_strbuf *tmp,
                               size_t *count, char id[24])
{
    const affect_motion *m = ctx->m;
    size_t start[N_EFFECTORS + 1];
    int colour[N_EFFECTORS];
    size_t n = 0;
    double ch0, cv0;
    panel_centre(ctx, 0, &ch0, &cv0);
    uint32_t points = m->n_frames < SVG_TRAJ_POINTS ? m->n_frames : SVG_TRAJ_POINTS;
    size_t n_paths = ctx->top ? 1 : N_EFFECTORS;
    tmp->len = 0;
    for (size_t e = 0; e < n_paths; e++) {
        int32_t j = ctx->top ? -1 : ctx->role[effector_roles[e]];
        if (!ctx->top && (j < 0 || ctx->hidden[j]))
            continue;
        start[n] = tmp->len;
        colour[n] = ctx->top ? SIDE_CENTRE : ctx->side[j];
        long px = 0, py = 0;
        for (uint32_t k = 0; k < points; k++) {
            uint32_t t = points > 1
                             ? (uint32_t)(((uint64_t)k * (m->n_frames - 1) + (points - 1) / 2) /
                                          (points - 1))
                             : 0;
            long x, y;
            if (ctx->top) {
                double h, v;
                frame_centre(ctx, t, &h, &v);
                project_hv(ctx, h, v, ch0, cv0, &x, &y);
            } else {
                project(ctx, t, (uint32_t)j, ch0, cv0, &x, &y);
            }
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
    for (int i = 0; ctx->salt && i < 8; i++) { /* a group's motions never share ids */
        h ^= (ctx->salt >> (8 * i)) & 0xff;
        h *= 1099511628211u;
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

/* "Mx0 y0Lx1 y1", tenths of a pixel. */
static void put_segment(affect_strbuf *sb, long x0, long y0, long x1, long y1)
{
    affect_strbuf_putc(sb, 'M');
    put_tenths(sb, x0);
    affect_strbuf_putc(sb, ' ');
    put_tenths(sb, y0);
    affect_strbuf_putc(sb, 'L');
    put_tenths(sb, x1);
    affect_strbuf_putc(sb, ' ');
    put_tenths(sb, y1);
}

/* Whether bone j (joint j to its parent) is drawn in colour side. */
static bool bone_shown(const svg_ctx *ctx, uint32_t j, int side)
{
    int32_t p = ctx->m->parents[j];
    return p >= 0 && ctx->side[j] == side && !ctx->hidden[j] && !ctx->hidden[p];
}

/* The path data of every bone of one colour at time tf (an animation's keyframes must all have
 * the same commands, so bones of zero length on screen are kept); a bone that starts where the
 * previous one ended continues its line ("L" only), a third shorter for the usual skeletons. */
static void bones_d(const svg_ctx *ctx, affect_strbuf *sb, double tf, double ch, double cv,
                    int side)
{
    const affect_motion *m = ctx->m;
    int64_t last = -1; /* the joint the pen stands on */
    for (uint32_t j = 0; j < m->n_joints; j++) {
        if (!bone_shown(ctx, j, side))
            continue;
        long x0, y0, x1, y1;
        project(ctx, tf, j, ch, cv, &x1, &y1);
        if (m->parents[j] == last) { /* a chain goes on (joints in depth-first order) */
            affect_strbuf_putc(sb, 'L');
            put_tenths(sb, x1);
            affect_strbuf_putc(sb, ' ');
            put_tenths(sb, y1);
        } else {
            project(ctx, tf, (uint32_t)m->parents[j], ch, cv, &x0, &y0);
            put_segment(sb, x0, y0, x1, y1);
        }
        last = j;
    }
}

/* Bones of one colour as a single path; nothing when there are none. */
static void write_bones(const svg_ctx *ctx, affect_strbuf *sb, uint32_t t, double ch, double cv,
                        int side)
{
    const affect_motion *m = ctx->m;
    bool open = false;
    for (uint32_t j = 0; j < m->n_joints; j++) {
        if (!bone_shown(ctx, j, side))
            continue;
        long x0, y0, x1, y1;
        project(ctx, t, (uint32_t)m->parents[j], ch, cv, &x0, &y0);
        project(ctx, t, j, ch, cv, &x1, &y1);
        if (x0 == x1 && y0 == y1)
            continue;
        if (!open) {
            affect_strbuf_printf(sb, "<path stroke=\"%s\" d=\"", side_colour[side]);
            open = true;
        }
        put_segment(sb, x0, y0, x1, y1);
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

/* Centre of the head circle at time tf (front and side views: moved out along the neck so that
 * it sits on it); false when there is no visible head. */
static bool head_at(const svg_ctx *ctx, double tf, double ch, double cv, double *cx, double *cy)
{
    int32_t head = ctx->role[AFFECT_ROLE_HEAD];
    if (head < 0 || ctx->hidden[head])
        return false;
    long x, y;
    project(ctx, tf, (uint32_t)head, ch, cv, &x, &y);
    double r = ctx->head_r;
    *cx = x / 10.0;
    *cy = y / 10.0;
    int32_t p = ctx->m->parents[head];
    if (!ctx->top && p >= 0 && !ctx->hidden[p]) {
        long px, py;
        project(ctx, tf, (uint32_t)p, ch, cv, &px, &py);
        double dx = (x - px) / 10.0, dy = (y - py) / 10.0, d = sqrt(dx * dx + dy * dy);
        if (d > 0.2 * r) {
            *cx += 0.7 * r * dx / d;
            *cy += 0.7 * r * dy / d;
        }
    }
    return true;
}

/* Top view: the screen direction the body faces at time tf, (left − right) × up over the
 * shoulders (else the hips); false when neither pair resolves or the body is seen edge-on. */
static bool facing_at(const svg_ctx *ctx, double tf, double *fx, double *fy)
{
    static const affect_role pairs[2][2] = {{AFFECT_ROLE_LEFT_SHOULDER, AFFECT_ROLE_RIGHT_SHOULDER},
                                            {AFFECT_ROLE_LEFT_HIP, AFFECT_ROLE_RIGHT_HIP}};
    for (int k = 0; k < 2; k++) {
        int32_t l = ctx->role[pairs[k][0]], r = ctx->role[pairs[k][1]];
        if (l < 0 || r < 0)
            continue;
        double pl[3], pr[3], d[3], f[3];
        joint_at(ctx, tf, (uint32_t)l, pl);
        joint_at(ctx, tf, (uint32_t)r, pr);
        for (int a = 0; a < 3; a++)
            d[a] = pl[a] - pr[a];
        int u = ctx->opt->up_axis, u1 = (u + 1) % 3, u2 = (u + 2) % 3;
        /* d × e_u: component u is 0; e_u1 × e_u = −e_u2 and e_u2 × e_u = e_u1 */
        f[u] = 0;
        f[u1] = d[u2];
        f[u2] = -d[u1];
        double sx, sy;
        to_screen(ctx, f[ctx->ax_h], f[ctx->ax_v], &sx, &sy);
        double n = hypot(sx, sy);
        if (!(n > 1e-9 * (fabs(d[0]) + fabs(d[1]) + fabs(d[2]))) || !(n > 0))
            return false;
        *fx = sx / n;
        *fy = -sy / n; /* SVG's y grows downward */
        return true;
    }
    return false;
}

/* The facing marker's triangle, about the head circle's centre. */
static void facing_points(affect_strbuf *sb, double cx, double cy, double r, double fx, double fy)
{
    double px = -fy, py = fx; /* perpendicular */
    double pts[3][2] = {{cx + fx * 2.1 * r, cy + fy * 2.1 * r},
                        {cx + fx * 1.05 * r + px * 0.7 * r, cy + fy * 1.05 * r + py * 0.7 * r},
                        {cx + fx * 1.05 * r - px * 0.7 * r, cy + fy * 1.05 * r - py * 0.7 * r}};
    for (int i = 0; i < 3; i++) {
        if (i)
            affect_strbuf_putc(sb, ' ');
        put_num(sb, pts[i][0], 1);
        affect_strbuf_putc(sb, ',');
        put_num(sb, pts[i][1], 1);
    }
}

/* The head circle's opening tag, without its closing "/>" or ">". */
static void open_head(const svg_ctx *ctx, affect_strbuf *sb, double cx, double cy, double r,
                      double stroke)
{
    affect_strbuf_puts(sb, "<circle cx=\"");
    put_num(sb, cx, 1);
    affect_strbuf_puts(sb, "\" cy=\"");
    put_num(sb, cy, 1);
    affect_strbuf_puts(sb, "\" r=\"");
    put_num(sb, r, 1);
    affect_strbuf_printf(sb, "\" fill=\"%s\" stroke=\"%s\" stroke-width=\"",
                         ctx->top ? "none" : "#fff",
                         side_colour[ctx->side[ctx->role[AFFECT_ROLE_HEAD]]]);
    put_num(sb, stroke, 2);
    affect_strbuf_putc(sb, '"');
}

static void write_head(const svg_ctx *ctx, affect_strbuf *sb, uint32_t t, double ch, double cv,
                       double stroke)
{
    double cx, cy, r = ctx->top ? 0.6 * ctx->head_r : ctx->head_r;
    if (!head_at(ctx, t, ch, cv, &cx, &cy))
        return;
    int head_side = ctx->side[ctx->role[AFFECT_ROLE_HEAD]];
    open_head(ctx, sb, cx, cy, r, stroke);
    affect_strbuf_puts(sb, "/>\n");
    double fx, fy;
    if (ctx->top && facing_at(ctx, t, &fx, &fy)) {
        affect_strbuf_printf(sb, "<polygon class=\"facing\" fill=\"%s\" points=\"",
                             side_colour[head_side]);
        facing_points(sb, cx, cy, r, fx, fy);
        affect_strbuf_puts(sb, "\"/>\n");
    }
}

/* "frame N · T.TT s" with the time printed from integers (locale-independent), or "state N". */
static void write_label_text(affect_strbuf *sb, uint32_t t, double fps, bool state)
{
    if (state) {
        affect_strbuf_printf(sb, "state %llu", (unsigned long long)t + 1);
        return;
    }
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

/* The opening of a panel (nested <svg>), its background and, in front and side views, the
 * ground line. */
static void open_panel(const svg_ctx *ctx, affect_strbuf *sb, double x0, double y0)
{
    unsigned size = ctx->opt->panel_size;
    affect_strbuf_puts(sb, "<svg x=\"");
    put_num(sb, x0, 1);
    affect_strbuf_puts(sb, "\" y=\"");
    put_num(sb, y0, 1);
    affect_strbuf_printf(sb, "\" width=\"%u\" height=\"%u\">\n", size, size);
    affect_strbuf_printf(sb,
                         "<rect x=\"1\" y=\"1\" width=\"%u\" height=\"%u\" rx=\"4\" "
                         "fill=\"#f5f6f8\"/>\n",
                         size - 2, size - 2);
    if (!ctx->top) {
        long gy = tenths(ctx->yc - ctx->scale * (ctx->vmin - ctx->vmid));
        affect_strbuf_puts(sb, "<path stroke=\"#b9bec6\" stroke-width=\"1\" d=\"M0 ");
        put_tenths(sb, gy);
        affect_strbuf_printf(sb, "H%u\"/>\n", size);
    }
}

static bool has_skeleton(const affect_motion *m)
{
    for (uint32_t j = 0; j < m->n_joints; j++)
        if (m->parents[j] >= 0)
            return true;
    return false;
}

static void write_panel(const svg_ctx *ctx, affect_strbuf *sb, uint32_t t, double x0, double y0,
                        size_t n_traj, const char *traj_id)
{
    const affect_motion *m = ctx->m;
    double panel = ctx->panel;
    double ch, cv;
    panel_centre(ctx, t, &ch, &cv);
    open_panel(ctx, sb, x0, y0);
    if (n_traj > 0) {
        double tx, ty;
        traj_shift(ctx, t, &tx, &ty);
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
    bool skeleton = has_skeleton(m);
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

/* ---- animation ----
 * n_keys keyframes at the times tf_k = k (T − 1) / (n_keys − 1), k = 0 … n_keys − 1: evenly
 * spaced, so SMIL's default (evenly spaced values, linear interpolation) plays them in real
 * time without keyTimes; dur = (T − 1) / fps. */

static double key_time(const svg_ctx *ctx, uint32_t k, uint32_t n_keys)
{
    if (n_keys < 2)
        return 0;
    return (double)k * (ctx->m->n_frames - 1) / (n_keys - 1);
}

/* Keyframes of an animation: opt->keyframes or automatic, at most the frame count. */
static uint32_t key_count(const svg_ctx *ctx)
{
    const affect_motion *m = ctx->m;
    if (m->n_frames < 2)
        return 1;
    double n = ctx->opt->keyframes;
    if (n == 0) {
        double secs = (m->n_frames - 1) / m->fps;
        n = fmin(1 + ceil(secs * AFFECT_SVG_KEY_RATE), AFFECT_SVG_KEY_AUTO_MAX);
        n = fmax(n, 2);
    }
    return n < m->n_frames ? (uint32_t)n : m->n_frames;
}

/* " dur=… repeatCount=…" of every animation element of a panel. */
static void put_timing(const svg_ctx *ctx, affect_strbuf *sb)
{
    affect_strbuf_puts(sb, " dur=\"");
    affect_strbuf_fixed(sb, (ctx->m->n_frames - 1) / ctx->m->fps, 3);
    affect_strbuf_puts(sb, "s\" repeatCount=\"indefinite\"");
}

/* The path data of the bones (dots false) or the joint dots (zero-length segments drawn with
 * round caps) of one colour at time tf; the same commands at every time. */
static void moving_d(const svg_ctx *ctx, affect_strbuf *sb, double tf, int side, bool dots)
{
    const affect_motion *m = ctx->m;
    double ch, cv;
    panel_centre(ctx, tf, &ch, &cv);
    if (!dots) {
        bones_d(ctx, sb, tf, ch, cv, side);
        return;
    }
    for (uint32_t j = 0; j < m->n_joints; j++) {
        if (ctx->side[j] != side || ctx->hidden[j])
            continue;
        long x, y;
        project(ctx, tf, j, ch, cv, &x, &y);
        affect_strbuf_putc(sb, 'M');
        put_tenths(sb, x);
        affect_strbuf_putc(sb, ' ');
        put_tenths(sb, y);
        affect_strbuf_puts(sb, "h0");
    }
}

/* One path element whose data move: bones or joint dots of one colour; nothing when there are
 * none. */
static void write_moving_path(const svg_ctx *ctx, affect_strbuf *sb, uint32_t n_keys, int side,
                              bool dots, double r)
{
    const affect_motion *m = ctx->m;
    bool any = false;
    for (uint32_t j = 0; j < m->n_joints && !any; j++)
        any = dots ? ctx->side[j] == side && !ctx->hidden[j] : bone_shown(ctx, j, side);
    if (!any)
        return;
    affect_strbuf_printf(sb, "<path stroke=\"%s\"", side_colour[side]);
    if (dots) {
        affect_strbuf_puts(sb, " stroke-width=\"");
        put_num(sb, 2 * r, 2);
        affect_strbuf_putc(sb, '"');
    }
    affect_strbuf_puts(sb, " d=\"");
    moving_d(ctx, sb, 0, side, dots);
    if (n_keys < 2) {
        affect_strbuf_puts(sb, "\"/>\n");
        return;
    }
    affect_strbuf_puts(sb, "\"><animate attributeName=\"d\"");
    put_timing(ctx, sb);
    affect_strbuf_puts(sb, " values=\"");
    for (uint32_t k = 0; k < n_keys; k++) {
        if (k)
            affect_strbuf_putc(sb, ';');
        moving_d(ctx, sb, key_time(ctx, k, n_keys), side, dots);
    }
    affect_strbuf_puts(sb, "\"/></path>\n");
}

/* A list of values "a;b;…" of one attribute over the keyframes, written by put_value. */
typedef void (*value_fn)(const svg_ctx *ctx, affect_strbuf *sb, double tf, int which);

static void put_values(const svg_ctx *ctx, affect_strbuf *sb, uint32_t n_keys, value_fn fn,
                       int which)
{
    for (uint32_t k = 0; k < n_keys; k++) {
        if (k)
            affect_strbuf_putc(sb, ';');
        fn(ctx, sb, key_time(ctx, k, n_keys), which);
    }
}

/* Head circle coordinate which (0: cx, 1: cy) at time tf. */
static void head_value(const svg_ctx *ctx, affect_strbuf *sb, double tf, int which)
{
    double ch, cv, cx = 0, cy = 0;
    panel_centre(ctx, tf, &ch, &cv);
    head_at(ctx, tf, ch, cv, &cx, &cy);
    put_num(sb, which ? cy : cx, 1);
}

/* Translation of the trajectories at time tf. */
static void shift_value(const svg_ctx *ctx, affect_strbuf *sb, double tf, int which)
{
    (void)which;
    double tx, ty;
    traj_shift(ctx, tf, &tx, &ty);
    put_num(sb, tx, 2);
    affect_strbuf_putc(sb, ' ');
    put_num(sb, ty, 2);
}

/* Facing marker's points at time tf (top view). */
static void facing_value(const svg_ctx *ctx, affect_strbuf *sb, double tf, int which)
{
    (void)which;
    double ch, cv, cx = 0, cy = 0, fx = 0, fy = 0;
    panel_centre(ctx, tf, &ch, &cv);
    head_at(ctx, tf, ch, cv, &cx, &cy);
    if (!facing_at(ctx, tf, &fx, &fy))
        fx = fy = 0; /* edge-on: the triangle collapses onto the head's centre */
    facing_points(sb, cx, cy, 0.6 * ctx->head_r, fx, fy);
}

/* An <animate> (or, for "transform", <animateTransform type="translate">) element. */
static void write_animate(const svg_ctx *ctx, affect_strbuf *sb, uint32_t n_keys, const char *attr,
                          value_fn fn, int which)
{
    if (n_keys < 2)
        return;
    if (strcmp(attr, "transform") == 0)
        affect_strbuf_puts(sb, "<animateTransform attributeName=\"transform\" type=\"translate\"");
    else
        affect_strbuf_printf(sb, "<animate attributeName=\"%s\"", attr);
    put_timing(ctx, sb);
    affect_strbuf_puts(sb, " values=\"");
    put_values(ctx, sb, n_keys, fn, which);
    affect_strbuf_puts(sb, "\"/>");
}

/* An animated panel at (x0, y0) and the time bar under it. */
static void write_anim_panel(const svg_ctx *ctx, affect_strbuf *sb, double x0, double y0,
                             size_t n_traj, const char *traj_id)
{
    const affect_motion *m = ctx->m;
    uint32_t n_keys = key_count(ctx);
    double panel = ctx->panel;
    open_panel(ctx, sb, x0, y0);
    if (n_traj > 0) {
        affect_strbuf_puts(sb, "<g fill=\"none\" stroke-width=\"1.2\" stroke-opacity=\"0.35\" "
                               "stroke-linejoin=\"round\" transform=\"translate(");
        shift_value(ctx, sb, 0, 0);
        affect_strbuf_puts(sb, ")\">");
        write_animate(ctx, sb, n_keys, "transform", shift_value, 0);
        for (size_t i = 0; i < n_traj; i++)
            affect_strbuf_printf(sb, "<use href=\"#%s-%zu\"/>", traj_id, i);
        affect_strbuf_puts(sb, "</g>\n");
    }
    double stroke = fmax(1.5, panel / 55);
    bool skeleton = has_skeleton(m);
    double r = skeleton ? stroke * 0.62 : fmax(1.5, panel / 60);
    affect_strbuf_puts(sb, "<g class=\"figure\" fill=\"none\" stroke-linecap=\"round\" "
                           "stroke-linejoin=\"round\" stroke-width=\"");
    put_num(sb, stroke, 2);
    affect_strbuf_puts(sb, "\">\n");
    /* bones, or joint dots when there is no skeleton (round caps mark the joints) */
    for (int s = 0; s < 3; s++)
        write_moving_path(ctx, sb, n_keys, s, !skeleton, r);
    affect_strbuf_puts(sb, "</g>\n");
    double cx, cy, ch, cv;
    panel_centre(ctx, 0, &ch, &cv);
    if (head_at(ctx, 0, ch, cv, &cx, &cy)) {
        int head_side = ctx->side[ctx->role[AFFECT_ROLE_HEAD]];
        open_head(ctx, sb, cx, cy, ctx->top ? 0.6 * ctx->head_r : ctx->head_r, stroke * 0.8);
        affect_strbuf_putc(sb, '>');
        write_animate(ctx, sb, n_keys, "cx", head_value, 0);
        write_animate(ctx, sb, n_keys, "cy", head_value, 1);
        affect_strbuf_puts(sb, "</circle>\n");
        double fx, fy;
        if (ctx->top && facing_at(ctx, 0, &fx, &fy)) {
            affect_strbuf_printf(sb, "<polygon class=\"facing\" fill=\"%s\" points=\"",
                                 side_colour[head_side]);
            facing_value(ctx, sb, 0, 0);
            affect_strbuf_puts(sb, "\">");
            write_animate(ctx, sb, n_keys, "points", facing_value, 0);
            affect_strbuf_puts(sb, "</polygon>\n");
        }
    }
    affect_strbuf_puts(sb, "</svg>\n");
    /* the time bar: grows from 0 to the panel's width over one loop */
    affect_strbuf_puts(sb, "<rect class=\"time\" x=\"");
    put_num(sb, x0 + 1, 1);
    affect_strbuf_puts(sb, "\" y=\"");
    put_num(sb, y0 + panel + 1, 1);
    affect_strbuf_puts(sb, "\" width=\"");
    put_num(sb, n_keys > 1 ? 0 : panel - 2, 1);
    affect_strbuf_puts(sb, "\" height=\"");
    put_num(sb, SVG_TIME_BAR, 1);
    affect_strbuf_puts(sb, "\" fill=\"#9aa3af\">");
    if (n_keys > 1) {
        affect_strbuf_puts(sb, "<animate attributeName=\"width\"");
        put_timing(ctx, sb);
        affect_strbuf_puts(sb, " values=\"0;");
        put_num(sb, panel - 2, 1);
        affect_strbuf_puts(sb, "\"/>");
    }
    affect_strbuf_puts(sb, "</rect>\n");
}

/* ---- documents ---- */

/* "T.TT s" from integers (locale-independent). */
static void put_seconds(affect_strbuf *sb, double secs)
{
    if (secs * 100 < 9e15) {
        long long cs = llround(secs * 100);
        affect_strbuf_printf(sb, "%lld.%02lld s", cs / 100, cs % 100);
    } else {
        affect_strbuf_double(sb, secs);
        affect_strbuf_puts(sb, " s");
    }
}

static void put_text_at(affect_strbuf *sb, double x, double y, double fs, const char *attrs)
{
    affect_strbuf_puts(sb, "<text x=\"");
    put_num(sb, x, 1);
    affect_strbuf_puts(sb, "\" y=\"");
    put_num(sb, y, 1);
    affect_strbuf_puts(sb, "\" font-size=\"");
    put_num(sb, fs, 1);
    affect_strbuf_printf(sb, "\"%s>", attrs);
}

/* Text escaped for XML, cut to at most max_cp code points (the last one "…" when cut): an
 * animated panel's caption within its panel's width. */
static void put_cut(affect_strbuf *sb, const char *s, size_t max_cp)
{
    size_t n = 0;
    for (const char *p = s; *p; p++)
        n += ((unsigned char)*p & 0xC0) != 0x80;
    if (n <= max_cp) {
        affect_strbuf_xml(sb, s);
        return;
    }
    size_t keep = max_cp - 1, k = 0;
    const char *p = s;
    char one[2] = {0, 0};
    for (; *p; p++) {
        if (((unsigned char)*p & 0xC0) != 0x80 && k++ == keep)
            break;
        one[0] = *p;
        affect_strbuf_xml(sb, one);
    }
    affect_strbuf_puts(sb, "\xe2\x80\xa6");
}

/* The root element, background, and the title row with its left / right legend. */
static void open_document(const svg_ctx *ctxs, size_t n, affect_strbuf *sb, double width,
                          double height, double title_fs)
{
    const affect_svg_options *opt = ctxs[0].opt;
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
    if (!opt->title)
        return;
    put_text_at(sb, 6, title_fs + 4, title_fs, " font-weight=\"bold\" fill=\"#222\"");
    affect_strbuf_xml(sb, opt->title);
    affect_strbuf_puts(sb, "</text>\n");
    bool sides = false;
    for (size_t i = 0; i < n; i++)
        for (uint32_t j = 0; j < ctxs[i].m->n_joints && !sides; j++)
            sides = ctxs[i].side[j] != SIDE_CENTRE && !ctxs[i].hidden[j];
    if (sides && width >= 320) {
        put_text_at(sb, width - 6, title_fs + 4, 11, " text-anchor=\"end\" fill=\"#777\"");
        affect_strbuf_printf(sb,
                             "<tspan fill=\"%s\">\xe2\x96\xa0 left</tspan>  "
                             "<tspan fill=\"%s\">\xe2\x96\xa0 right</tspan></text>\n",
                             side_colour[SIDE_LEFT], side_colour[SIDE_RIGHT]);
    }
}

/* Film strips, one row per motion (a caption above each row when given). */
static void write_strips(const svg_ctx *ctxs, size_t n_motions, const char *const *captions,
                         affect_strbuf *sb, affect_strbuf *tmp)
{
    const affect_svg_options *opt = ctxs[0].opt;
    unsigned panel = opt->panel_size;
    double title_fs = panel >= 96 ? 14 : 11, title_h = opt->title ? title_fs + 12 : 0;
    double label_fs = fmin(12, panel / 10.5), label_h = opt->labels ? label_fs + 8 : 0;
    double cap_fs = fmin(13, panel / 9.0), cap_h = cap_fs + 8;
    double width = 0, height = title_h;
    for (size_t i = 0; i < n_motions; i++) {
        uint32_t n = opt->frames < ctxs[i].m->n_frames ? opt->frames : ctxs[i].m->n_frames;
        width = fmax(width, (double)n * panel);
        height += (captions && captions[i] ? cap_h : 0) + panel + label_h;
    }
    open_document(ctxs, n_motions, sb, width, height, title_fs);
    double y = title_h;
    for (size_t i = 0; i < n_motions; i++) {
        const svg_ctx *ctx = &ctxs[i];
        const affect_motion *m = ctx->m;
        uint32_t n = opt->frames < m->n_frames ? opt->frames : m->n_frames;
        if (captions && captions[i]) {
            put_text_at(sb, 6, y + cap_fs + 3, cap_fs, " class=\"caption\" fill=\"#333\"");
            affect_strbuf_xml(sb, captions[i]);
            affect_strbuf_puts(sb, "</text>\n");
            y += cap_h;
        }
        size_t n_traj = 0;
        char traj_id[24] = "";
        if (opt->trajectories)
            write_trajectories(ctx, sb, tmp, &n_traj, traj_id);
        for (uint32_t k = 0; k < n; k++) {
            uint32_t t =
                n > 1 ? (uint32_t)(((uint64_t)k * (m->n_frames - 1) + (n - 1) / 2) / (n - 1)) : 0;
            write_panel(ctx, sb, t, (double)k * panel, y, n_traj, traj_id);
            if (opt->labels) {
                put_text_at(sb, (k + 0.5) * panel, y + panel + label_fs + 2, label_fs,
                            " text-anchor=\"middle\" fill=\"#555\"");
                write_label_text(sb, t, m->fps, opt->state_labels);
                affect_strbuf_puts(sb, "</text>\n");
            }
        }
        y += panel + label_h;
    }
    affect_strbuf_puts(sb, "</svg>\n");
}

/* Animated panels side by side, each with its time bar, caption and label under it. */
static void write_animations(const svg_ctx *ctxs, size_t n_motions, const char *const *captions,
                             affect_strbuf *sb, affect_strbuf *tmp)
{
    const affect_svg_options *opt = ctxs[0].opt;
    unsigned panel = opt->panel_size;
    double title_fs = panel >= 96 ? 14 : 11, title_h = opt->title ? title_fs + 12 : 0;
    double label_fs = fmin(12, panel / 10.5), label_h = opt->labels ? label_fs + 6 : 0;
    double cap_fs = fmin(13, panel / 9.0), cap_h = 0;
    for (size_t i = 0; i < n_motions && captions; i++)
        if (captions[i])
            cap_h = cap_fs + 6;
    double bar_h = SVG_TIME_BAR + 3;
    double width = (double)n_motions * panel;
    double height = title_h + panel + bar_h + cap_h + label_h;
    open_document(ctxs, n_motions, sb, width, height, title_fs);
    for (size_t i = 0; i < n_motions; i++) {
        const svg_ctx *ctx = &ctxs[i];
        const affect_motion *m = ctx->m;
        size_t n_traj = 0;
        char traj_id[24] = "";
        if (opt->trajectories)
            write_trajectories(ctx, sb, tmp, &n_traj, traj_id);
        double x0 = (double)i * panel, y = title_h + panel + bar_h;
        write_anim_panel(ctx, sb, x0, title_h, n_traj, traj_id);
        if (captions && captions[i]) {
            put_text_at(sb, x0 + panel / 2.0, y + cap_fs, cap_fs,
                        " class=\"caption\" text-anchor=\"middle\" fill=\"#333\"");
            put_cut(sb, captions[i], (size_t)fmax(4, floor(panel / (SVG_CAPTION_EM * cap_fs))));
            affect_strbuf_puts(sb, "</text>\n");
        }
        y += cap_h;
        if (opt->labels) {
            put_text_at(sb, x0 + panel / 2.0, y + label_fs, label_fs,
                        " text-anchor=\"middle\" fill=\"#555\"");
            put_seconds(sb, m->n_frames / m->fps);
            affect_strbuf_printf(sb, " \xc2\xb7 %u frames</text>\n", m->n_frames);
        }
    }
    affect_strbuf_puts(sb, "</svg>\n");
}

/* Sets up ctx for motion m (checked): roles, axes, sides, measures. */
static affect_status setup(svg_ctx *ctx, const affect_motion *m, const affect_roles *roles,
                           const affect_svg_options *opt, uint64_t salt, affect_error *err)
{
    memset(ctx, 0, sizeof *ctx);
    ctx->m = m;
    ctx->opt = opt;
    ctx->panel = opt->panel_size;
    ctx->salt = salt;
    for (int r = 0; r < AFFECT_ROLE_COUNT; r++)
        ctx->role[r] = roles ? roles->joint[r] : -1;
    int up = opt->up_axis, a = up == 0 ? 1 : 0, b = up == 2 ? 1 : 2;
    ctx->top = opt->view == AFFECT_SVG_TOP;
    ctx->ax_h = opt->view == AFFECT_SVG_SIDE ? b : a;
    ctx->ax_v = ctx->top ? b : up;
    /* (a, b, up) is a right-handed cycle when b follows a and up follows b */
    ctx->dir_v = !ctx->top || (b == (a + 1) % 3 && up == (b + 1) % 3) ? 1 : -1;
    /* one block: side, hidden, and two scratch arrays for classify_joints */
    ctx->side = affect_calloc(m->n_joints, 4);
    if (!ctx->side)
        return affect_nomem(err);
    ctx->hidden = ctx->side + m->n_joints;
    classify_joints(ctx, ctx->side + 2 * (size_t)m->n_joints, ctx->side + 3 * (size_t)m->n_joints);
    measure(ctx);
    return AFFECT_OK;
}

affect_status affect_motion_svg_group(const affect_motion *const *m, const affect_roles *roles,
                                      const char *const *captions, size_t n,
                                      const affect_svg_options *opt, char **out, size_t *len,
                                      affect_error *err)
{
    affect_svg_options defaults;
    affect_strbuf sb, tmp;
    svg_ctx *ctxs = NULL;
    affect_status st;
    affect_strbuf_init(&sb);
    affect_strbuf_init(&tmp);
    *out = NULL;
    if (len)
        *len = 0;
    if (!opt) {
        affect_svg_options_default(&defaults);
        opt = &defaults;
    }
    if ((st = check_options(opt, err)) != AFFECT_OK)
        goto cleanup;
    if (n < 1 || n > AFFECT_SVG_MAX_GROUP) {
        st = affect_fail(err, AFFECT_ERR_INVALID, "a group holds 1 to %u motions, got %zu",
                         AFFECT_SVG_MAX_GROUP, n);
        goto cleanup;
    }
    for (size_t i = 0; i < n; i++) {
        if ((st = check_motion(m[i], roles ? &roles[i] : NULL, err)) != AFFECT_OK) {
            if (n > 1) {
                affect_error inner = *err;
                st = affect_fail(err, st, "motion %zu: %s", i, inner.msg);
            }
            goto cleanup;
        }
    }
    ctxs = affect_calloc(n, sizeof *ctxs);
    if (!ctxs) {
        st = affect_nomem(err);
        goto cleanup;
    }
    double scale = HUGE_VAL;
    for (size_t i = 0; i < n; i++) {
        if ((st = setup(&ctxs[i], m[i], roles ? &roles[i] : NULL, opt, i, err)) != AFFECT_OK)
            goto cleanup;
        scale = fmin(scale, ctxs[i].fit);
    }
    for (size_t i = 0; i < n; i++)
        place(&ctxs[i], scale);
    if (opt->animate)
        write_animations(ctxs, n, captions, &sb, &tmp);
    else
        write_strips(ctxs, n, captions, &sb, &tmp);
    if (tmp.failed)
        sb.failed = true;
    st = affect_strbuf_finish(&sb, out, len, err);

cleanup:
    affect_strbuf_free(&sb);
    affect_strbuf_free(&tmp);
    for (size_t i = 0; ctxs && i < n; i++)
        affect_free(ctxs[i].side);
    affect_free(ctxs);
    return st;
}

affect_status affect_motion_svg(const affect_motion *m, const affect_roles *roles,
                                const affect_svg_options *opt, char **out, size_t *len,
                                affect_error *err)
{
    return affect_motion_svg_group(&m, roles, NULL, 1, opt, out, len, err);
}
