/*
 * synth.c — procedural affective movements on a named full-body skeleton (see affect/synth.h).
 *
 * Usage: see the block at the top of affect/synth.h (compiled by the style/header-usage test).
 *
 * Errors (all AFFECT_ERR_INVALID):
 *     unknown action "jump" (expected knock, wave, walk, bow)
 *     unknown emotion "fear" (expected neutral, happy, sad, angry)
 *     fps must be greater than 0 and at most 1000, got 0
 *     intensity must be between 0 and 2, got 3
 *     noise must be between 0 and 0.1, got 0.5
 * plus "out of memory" (AFFECT_ERR_NOMEM); nothing leaks on any error.
 *
 * The skeleton. 26 joints in the corpus's naming and order (parents precede children):
 * Hips (root, carries the translation, ≈0.95 m high), Spine, Chest, Neck, Head, Head_end (top
 * of the head, ≈1.72 m), Shoulder_L (clavicle), UpperArm_L (shoulder joint), LowerArm_L
 * (elbow), Hand_L (wrist), Hand_L_end (finger tip), the same for _R, UpperLeg_L (hip joint),
 * LowerLeg_L (knee), Foot_L (ankle, 8 cm above the floor), Toes_L (ball of the foot),
 * Toes_L_end (toe tip), the same for _R. The performer's left is +x. Every frame is built
 * from local rotations (affect_euler_deg_to_matrix) and the root translation and turned into
 * positions by affect_fk_frame, so bone lengths are exactly constant (up to float rounding
 * and the measurement noise, which is added last).
 *
 * How a frame is made. Each action is a function of time giving an "action pose": for knock,
 * wave and bow a list of keyframes over a few anatomical parameters (right shoulder flexion
 * and abduction, elbow flexion, forearm swing, wrist, left arm, bow depth, neck, head) joined
 * by the emotion's easing curve; for walk a gait generator (foot placements every step, the
 * swing foot on an eased arc, heel lift about the ball of the foot whenever the stance leg
 * would otherwise be over-stretched, the pelvis moving forward at the speed the steps imply,
 * rising over the stance leg and lowest at double support, swaying towards the stance foot and
 * turning with the stepping leg, arms swinging against the legs). The emotion then adds a
 * posture (trunk, head, clavicles, arm abduction, elbows) that fades in as the movement starts
 * and out as it ends, and, for happy, a 2 Hz bounce. Legs are solved by two-bone inverse
 * kinematics from the hip joint to the ankle target with the knee towards the toes, so feet
 * stay planted (standing actions) or planted during stance (walk) whatever the trunk does.
 * Arms are given relative to an upright chest and mostly compensated for trunk pitch, so they
 * hang with gravity when the performer slumps or bows.
 *
 * Emotions (values at intensity 1; intensity I scales every additive change by I and every
 * factor f to f^I, so 0 is neutral and 2 doubles the effect):
 *     neutral  tempo ×1,    amplitude ×1,   upright
 *     happy    tempo ×1.2,  amplitude ×1.3, chest lifted (spine −2°, chest −5°), head up 11°,
 *              shoulders up and arms 10° more abducted, a 2 cm vertical bounce at 2 Hz
 *     sad      tempo ×0.6,  amplitude ×0.6, slumped trunk (spine 5°, chest 8°), head drooped
 *              28° (neck 18°, head 10°), clavicles down 10° and forward 8°, elbows +4°,
 *              sinusoidal (sustained) easing
 *     angry    tempo ×1.5,  amplitude ×1.2, forward lean 12° (hips 6°, spine 4°, chest 2°),
 *              head thrust forward (neck 20°, head −15°), arms out 5°, elbows +15°, sudden
 *              easing
 * Easing: every transition between keyframes follows smoothstep(w(u)) with
 * w(u) = 1 − (1 − u)^k: k = 1 + 1.2·I for angry puts most of the movement in the first part of
 * the interval (a sharp, high-acceleration onset: peak acceleration 6k² instead of 6), k = 1
 * otherwise; sad blends smoothstep towards (1 − cos πu)/2 by I/2 (lower peak acceleration).
 * Tempo divides every movement duration (not the rest holds), amplitude multiplies every
 * keyframe's departure from rest (the bow's depth by √amplitude, at most 65°: a bow's depth
 * carries its social meaning), the step length by amplitude^0.6 and the arm swing by
 * amplitude. Sad movements thus last about 1.7× and angry ones 0.67× the neutral ones.
 *
 * The performer. The seed alone (never the action or the emotion) draws, in a fixed order:
 * an overall size (±4.5 %) times a factor per body segment (±1.5 %) for limb lengths within
 * ±6 % with left and right equal, tempo (±8 %), amplitude (±10 %), the rest holds at the start
 * and end (0.45–0.65 s), the rest posture (arm abduction, elbow and head angles, stance width,
 * toe-out), the style of each action (knock height, wave height, bow depth, 3 or 4 waves, 5
 * or 6 steps, the leading foot, step length and duration) and a ±6 % jitter of each keyframe
 * interval. So one seed is one performer whatever the emotion, and at intensity 0 every
 * emotion of a seed gives the same motion. The measurement noise (Gaussian, opt->noise metres
 * per coordinate) continues the same generator. Every motion starts and ends with the
 * performer standing still in the rest pose, arms down.
 */
#include "affect/synth.h"

#include "affect/fk.h"
#include "util/rng.h"

#include <math.h>
#include <string.h>

#define PI 3.14159265358979323846
#define DEG (PI / 180.0)

#define SYNTH_MAX_FPS 1000.0
#define SYNTH_MAX_NOISE 0.1
#define SYNTH_MAX_INTENSITY 2.0
#define MAX_KEYS 32
#define BOUNCE_HZ 2.0

const char *const affect_synth_actions[] = {"knock", "wave", "walk", "bow", NULL};
const char *const affect_synth_emotions[] = {"neutral", "happy", "sad", "angry", NULL};

enum { A_KNOCK, A_WAVE, A_WALK, A_BOW };

void affect_synth_options_default(affect_synth_options *opt)
{
    opt->fps = 30.0;
    opt->intensity = 1.0;
    opt->noise = 0.0003;
}

/* ---- small rotation helpers (3×3 row-major, acting on column vectors) ---- */

static void rot_yxz(double pitch, double yaw, double roll, double r[9])
{
    static const int order[3] = {1, 0, 2};
    double deg[3] = {yaw, pitch, roll};
    affect_euler_deg_to_matrix(order, deg, r);
}

static void rot_zxy(double z, double x, double y, double r[9])
{
    static const int order[3] = {2, 0, 1};
    double deg[3] = {z, x, y};
    affect_euler_deg_to_matrix(order, deg, r);
}

static void mat_vec(const double r[9], const double v[3], double out[3])
{
    for (int i = 0; i < 3; i++)
        out[i] = r[i * 3] * v[0] + r[i * 3 + 1] * v[1] + r[i * 3 + 2] * v[2];
}

/* r = aᵀ · b */
static void mat_tmul(const double a[9], const double b[9], double r[9])
{
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            r[i * 3 + j] = a[i] * b[j] + a[3 + i] * b[3 + j] + a[6 + i] * b[6 + j];
}

static double dist3(const double a[3], const double b[3])
{
    double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
    return sqrt(dx * dx + dy * dy + dz * dz);
}

static void identity(double r[9])
{
    static const double id[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    memcpy(r, id, sizeof id);
}

/* ---- the skeleton ---- */

enum {
    J_HIPS,
    J_SPINE,
    J_CHEST,
    J_NECK,
    J_HEAD,
    J_HEAD_END,
    J_SHOULDER_L,
    J_UPPERARM_L,
    J_LOWERARM_L,
    J_HAND_L,
    J_HAND_L_END,
    J_SHOULDER_R,
    J_UPPERARM_R,
    J_LOWERARM_R,
    J_HAND_R,
    J_HAND_R_END,
    J_UPPERLEG_L,
    J_LOWERLEG_L,
    J_FOOT_L,
    J_TOES_L,
    J_TOES_L_END,
    J_UPPERLEG_R,
    J_LOWERLEG_R,
    J_FOOT_R,
    J_TOES_R,
    J_TOES_R_END,
    J_COUNT
};

/* Offsets of the right side are the left's mirrored in x; arm and leg joints of side s
 * (0 = left, 1 = right) are the left ones plus 5 * s. */
#define SIDE_STRIDE 5

/* Body segments scaled together by the performer's proportions. */
enum {
    G_TRUNK,
    G_HEAD,
    G_CLAV,
    G_UPPERARM,
    G_FOREARM,
    G_HAND,
    G_PELVIS,
    G_THIGH,
    G_SHIN,
    G_FOOT,
    G_COUNT
};

typedef struct bone {
    const char *name;
    int32_t parent;
    double off[3]; /* local offset from the parent at rest, metres (left side) */
    int group;
} bone;

static const bone skeleton[J_COUNT] = {
    {"Hips", -1, {0, 0, 0}, G_TRUNK},
    {"Spine", J_HIPS, {0, 0.10, 0}, G_TRUNK},
    {"Chest", J_SPINE, {0, 0.15, 0}, G_TRUNK},
    {"Neck", J_CHEST, {0, 0.24, -0.01}, G_TRUNK},
    {"Head", J_NECK, {0, 0.10, 0.01}, G_HEAD},
    {"Head_end", J_HEAD, {0, 0.17, 0}, G_HEAD},
    {"Shoulder_L", J_CHEST, {0.02, 0.20, -0.01}, G_TRUNK},
    {"UpperArm_L", J_SHOULDER_L, {0.16, 0, 0}, G_CLAV},
    {"LowerArm_L", J_UPPERARM_L, {0, -0.29, 0}, G_UPPERARM},
    {"Hand_L", J_LOWERARM_L, {0, -0.26, 0}, G_FOREARM},
    {"Hand_L_end", J_HAND_L, {0, -0.18, 0}, G_HAND},
    {"Shoulder_R", J_CHEST, {-0.02, 0.20, -0.01}, G_TRUNK},
    {"UpperArm_R", J_SHOULDER_R, {-0.16, 0, 0}, G_CLAV},
    {"LowerArm_R", J_UPPERARM_R, {0, -0.29, 0}, G_UPPERARM},
    {"Hand_R", J_LOWERARM_R, {0, -0.26, 0}, G_FOREARM},
    {"Hand_R_end", J_HAND_R, {0, -0.18, 0}, G_HAND},
    {"UpperLeg_L", J_HIPS, {0.09, -0.07, 0}, G_PELVIS},
    {"LowerLeg_L", J_UPPERLEG_L, {0, -0.41, 0}, G_THIGH},
    {"Foot_L", J_LOWERLEG_L, {0, -0.40, 0}, G_SHIN},
    {"Toes_L", J_FOOT_L, {0, -0.07, 0.13}, G_FOOT},
    {"Toes_L_end", J_TOES_L, {0, 0, 0.06}, G_FOOT},
    {"UpperLeg_R", J_HIPS, {-0.09, -0.07, 0}, G_PELVIS},
    {"LowerLeg_R", J_UPPERLEG_R, {0, -0.41, 0}, G_THIGH},
    {"Foot_R", J_LOWERLEG_R, {0, -0.40, 0}, G_SHIN},
    {"Toes_R", J_FOOT_R, {0, -0.07, 0.13}, G_FOOT},
    {"Toes_R_end", J_TOES_R, {0, 0, 0.06}, G_FOOT},
};

/* ---- the performer, drawn from the seed ---- */

enum { S_KNOCK_FLEX, S_KNOCK_ELBOW, S_WAVE_ABD, S_WAVE_SWING, S_BOW_DEPTH, S_COUNT };

typedef struct performer {
    double off[J_COUNT][3];
    double thigh, shin, leg; /* segment lengths; leg = thigh + shin */
    double ankle_h;          /* height of the ankle joint above the floor, foot flat */
    double root_y;           /* Hips height standing at rest */
    double tempo, amp;       /* personal factors */
    double hold0, hold1;     /* rest holds at the start and the end, seconds */
    double rest_abd, rest_elbow, rest_head, rest_trunk; /* rest posture, degrees */
    double stance, toe_out; /* half distance between the ankles (m); toe-out (deg) */
    int lead;               /* walk: 0 = left foot first, 1 = right */
    int n_steps;            /* walk: foot movements including the closing step */
    int n_waves;
    double step_len, step_time, arm_swing;
    double style[S_COUNT];
    double jitter[MAX_KEYS];
} performer;

static void draw_performer(affect_rng *rng, performer *p)
{
    double scale[G_COUNT];
    double size = affect_rng_range(rng, 0.955, 1.045);
    for (int g = 0; g < G_COUNT; g++)
        scale[g] = size * affect_rng_range(rng, 0.985, 1.015);
    for (int j = 0; j < J_COUNT; j++)
        for (int a = 0; a < 3; a++)
            p->off[j][a] = skeleton[j].off[a] * scale[skeleton[j].group];
    p->thigh = -p->off[J_LOWERLEG_L][1];
    p->shin = -p->off[J_FOOT_L][1];
    p->leg = p->thigh + p->shin;
    p->ankle_h = -p->off[J_TOES_L][1] + 0.01 * scale[G_FOOT];
    p->root_y = 0.0; /* set by finish_performer once the stance is known */

    p->tempo = affect_rng_range(rng, 0.92, 1.08);
    p->amp = affect_rng_range(rng, 0.90, 1.10);
    p->hold0 = affect_rng_range(rng, 0.45, 0.65);
    p->hold1 = affect_rng_range(rng, 0.45, 0.65);
    p->rest_abd = affect_rng_range(rng, 4.0, 8.0);
    p->rest_elbow = affect_rng_range(rng, 5.0, 14.0);
    p->rest_head = affect_rng_range(rng, -3.0, 3.0);
    p->rest_trunk = affect_rng_range(rng, -2.0, 2.0);
    p->stance = scale[G_PELVIS] * affect_rng_range(rng, 0.085, 0.115);
    p->toe_out = affect_rng_range(rng, 3.0, 10.0);
    p->lead = affect_rng_uniform(rng) < 0.5 ? 0 : 1;
    p->n_steps = affect_rng_uniform(rng) < 0.5 ? 5 : 6;
    p->n_waves = affect_rng_uniform(rng) < 0.5 ? 3 : 4;
    p->step_len = p->leg * affect_rng_range(rng, 0.68, 0.76);
    p->step_time = affect_rng_range(rng, 0.52, 0.60);
    p->arm_swing = affect_rng_range(rng, 13.0, 19.0);
    p->style[S_KNOCK_FLEX] = affect_rng_range(rng, -6.0, 6.0);
    p->style[S_KNOCK_ELBOW] = affect_rng_range(rng, -8.0, 8.0);
    p->style[S_WAVE_ABD] = affect_rng_range(rng, -8.0, 8.0);
    p->style[S_WAVE_SWING] = affect_rng_range(rng, -8.0, 8.0);
    p->style[S_BOW_DEPTH] = affect_rng_range(rng, -6.0, 6.0);
    for (int k = 0; k < MAX_KEYS; k++)
        p->jitter[k] = affect_rng_range(rng, 0.94, 1.06);
}

/* World position of side's hip joint for a pelvis at root with rotation rot (degrees). */
static void hip_joint(const performer *p, int side, const double root[3], const double rot[3],
                      double out[3])
{
    double r[9], v[3];
    rot_yxz(rot[0], rot[1], rot[2], r);
    mat_vec(r, p->off[J_UPPERLEG_L + SIDE_STRIDE * side], v);
    for (int a = 0; a < 3; a++)
        out[a] = root[a] + v[a];
}

/* Highest Hips height at which both legs still reach their ankle targets with the knees at
 * their standing flexion, for a pelvis at root (x, z) with rotation rot. */
#define STAND_REACH 0.997

static double standing_height(const performer *p, const double root[3], const double rot[3],
                              const double ankle[2][3])
{
    double best = HUGE_VAL, r = STAND_REACH * p->leg;
    for (int s = 0; s < 2; s++) {
        double base[3] = {root[0], 0.0, root[2]}, hip[3];
        hip_joint(p, s, base, rot, hip);
        double dx = hip[0] - ankle[s][0], dz = hip[2] - ankle[s][2];
        double h = ankle[s][1] + sqrt(fmax(0.0, r * r - dx * dx - dz * dz)) - hip[1];
        if (h < best)
            best = h;
    }
    return best;
}

/* The rest height of the Hips: legs nearly straight (knee ≈ 9°) over the rest stance. */
static void finish_performer(performer *p)
{
    double root[3] = {0, 0, 0}, rot[3] = {0, 0, 0}, ankle[2][3];
    for (int s = 0; s < 2; s++) {
        ankle[s][0] = (s ? -1.0 : 1.0) * p->stance;
        ankle[s][1] = p->ankle_h;
        ankle[s][2] = 0.0;
    }
    p->root_y = standing_height(p, root, rot, ankle);
}

/* ---- emotions ---- */

typedef struct emotion {
    double tempo, amp;     /* factors */
    double k;              /* onset steepness of the easing (1 = smoothstep) */
    double sustain;        /* blend of the easing towards (1 − cos πu)/2, 0..1 */
    double lean;           /* forward pitch of the pelvis (deg) */
    double spine, chest;   /* forward pitch (deg; negative = lifted) */
    double neck, head;     /* forward/down pitch (deg; negative = up) */
    double clav_elev;      /* clavicle elevation (deg; negative = drooped) */
    double clav_prot;      /* clavicle protraction (deg, forward) */
    double arm_abd, elbow; /* extra arm abduction and elbow flexion (deg) */
    double bounce;         /* peak-to-peak vertical bounce of the pelvis at 2 Hz (m) */
} emotion;

static const emotion emotion_table[4] = {
    /* tempo amp  k    sust  lean spine chest neck  head  elev   prot  abd   elbow bounce */
    {1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0},
    {1.2, 1.3, 1.0, 0.0, 0.0, -2.0, -5.0, -3.0, -8.0, 4.0, -3.0, 10.0, 0.0, 0.02},
    {0.6, 0.6, 1.0, 1.0, 0.0, 5.0, 8.0, 18.0, 10.0, -10.0, 8.0, 0.0, 4.0, 0.0},
    {1.5, 1.2, 2.2, 0.0, 6.0, 4.0, 2.0, 20.0, -15.0, 3.0, 4.0, 5.0, 15.0, 0.0},
};

/* The emotion at intensity x: additive changes times x, factors to the power x. */
static emotion emotion_at(int which, double x, const performer *p)
{
    const emotion *b = &emotion_table[which];
    emotion e;
    e.tempo = pow(b->tempo, x) * p->tempo;
    e.amp = pow(b->amp, x) * p->amp;
    e.k = 1.0 + x * (b->k - 1.0);
    e.sustain = x * 0.5 * b->sustain;
    if (e.sustain > 1.0)
        e.sustain = 1.0;
    e.lean = x * b->lean;
    e.spine = x * b->spine;
    e.chest = x * b->chest;
    e.neck = x * b->neck;
    e.head = x * b->head;
    e.clav_elev = x * b->clav_elev;
    e.clav_prot = x * b->clav_prot;
    e.arm_abd = x * b->arm_abd;
    e.elbow = x * b->elbow;
    e.bounce = x * b->bounce;
    return e;
}

static double clamp(double v, double lo, double hi)
{
    return v < lo ? lo : v > hi ? hi : v;
}

static double smoothstep(double u)
{
    u = clamp(u, 0.0, 1.0);
    return u * u * (3.0 - 2.0 * u);
}

/* The emotion's easing: 0 → 0, 1 → 1, zero velocity at both ends. */
static double ease(const emotion *e, double u)
{
    u = clamp(u, 0.0, 1.0);
    double w = e->k == 1.0 ? u : 1.0 - pow(1.0 - u, e->k);
    double s = w * w * (3.0 - 2.0 * w);
    if (e->sustain > 0.0)
        s = (1.0 - e->sustain) * s + e->sustain * (0.5 - 0.5 * cos(PI * u));
    return s;
}

/* ---- keyframed actions (knock, wave, bow) ---- */

enum {
    P_RFLEX,
    P_RABD,
    P_RELB,
    P_RSWING,
    P_RWRIST,
    P_LFLEX,
    P_LABD,
    P_LELB,
    P_BOW,
    P_NECK,
    P_HEAD,
    P_COUNT
};

typedef struct keyframe {
    double t;          /* seconds from the start of the motion */
    double v[P_COUNT]; /* departures from rest, degrees, already scaled by the amplitude */
} keyframe;

typedef struct timeline {
    int n;
    keyframe key[MAX_KEYS];
} timeline;

/* Appends a key reached dur neutral seconds after the previous one. */
static void add_key(timeline *tl, const performer *p, const emotion *e, double dur,
                    const double v[P_COUNT])
{
    keyframe *k = &tl->key[tl->n];
    k->t = tl->key[tl->n - 1].t + dur * p->jitter[tl->n] / e->tempo;
    for (int i = 0; i < P_COUNT; i++) {
        double f = i == P_BOW ? sqrt(e->amp) : e->amp;
        k->v[i] = v[i] * f;
    }
    k->v[P_RELB] = clamp(k->v[P_RELB], -20.0, 145.0);
    k->v[P_RSWING] = clamp(k->v[P_RSWING], 0.0, 165.0);
    k->v[P_RFLEX] = clamp(k->v[P_RFLEX], -30.0, 150.0);
    k->v[P_RABD] = clamp(k->v[P_RABD], -30.0, 150.0);
    k->v[P_BOW] = clamp(k->v[P_BOW], 0.0, 65.0);
    tl->n++;
}

static void build_timeline(int action, const performer *p, const emotion *e, timeline *tl)
{
    double rest[P_COUNT] = {0};
    double a[P_COUNT], b[P_COUNT], c[P_COUNT];
    tl->n = 1;
    tl->key[0].t = p->hold0;
    memset(tl->key[0].v, 0, sizeof tl->key[0].v);
    memset(a, 0, sizeof a);
    if (action == A_KNOCK) {
        /* right hand raised in front to head height, forearm up, knuckles to the door */
        a[P_RFLEX] = 75.0 + p->style[S_KNOCK_FLEX];
        a[P_RABD] = -8.0;
        a[P_RELB] = 85.0 + p->style[S_KNOCK_ELBOW];
        a[P_RWRIST] = 10.0;
        a[P_LFLEX] = 4.0;
        a[P_LELB] = 6.0;
        a[P_NECK] = 3.0;
        memcpy(b, a, sizeof b); /* drawn back */
        b[P_RELB] += 14.0;
        b[P_RWRIST] = 24.0;
        memcpy(c, a, sizeof c); /* the knock: forearm forward onto the door */
        c[P_RELB] -= 14.0;
        c[P_RWRIST] = 0.0;
        add_key(tl, p, e, 1.0, a);
        add_key(tl, p, e, 0.25, a);
        for (int i = 0; i < 3; i++) {
            add_key(tl, p, e, 0.16, b);
            add_key(tl, p, e, 0.14, c);
        }
        add_key(tl, p, e, 0.3, c);
        add_key(tl, p, e, 1.0, rest);
    } else if (action == A_WAVE) {
        /* right arm out to the side and up, forearm vertical, waving in the frontal plane */
        a[P_RFLEX] = 20.0;
        a[P_RABD] = 75.0 + p->style[S_WAVE_ABD];
        a[P_RELB] = 10.0;
        a[P_RSWING] = 90.0 + p->style[S_WAVE_SWING];
        a[P_LELB] = 5.0;
        a[P_HEAD] = -3.0;
        memcpy(b, a, sizeof b); /* outwards */
        b[P_RSWING] -= 30.0;
        b[P_RWRIST] = -12.0;
        memcpy(c, a, sizeof c); /* inwards */
        c[P_RSWING] += 30.0;
        c[P_RWRIST] = 12.0;
        add_key(tl, p, e, 0.9, a);
        for (int i = 0; i < p->n_waves; i++) {
            add_key(tl, p, e, i == 0 ? 0.2 : 0.28, b);
            add_key(tl, p, e, 0.28, c);
        }
        add_key(tl, p, e, 0.2, a);
        add_key(tl, p, e, 0.9, rest);
    } else { /* A_BOW */
        a[P_BOW] = 50.0 + p->style[S_BOW_DEPTH];
        a[P_NECK] = 6.0;
        a[P_HEAD] = 6.0;
        add_key(tl, p, e, 1.0, a);
        add_key(tl, p, e, 0.9, a);
        add_key(tl, p, e, 1.2, rest);
    }
}

static void timeline_eval(const timeline *tl, const emotion *e, double t, double v[P_COUNT])
{
    if (t <= tl->key[0].t || tl->n == 1) {
        memcpy(v, tl->key[0].v, sizeof tl->key[0].v);
        return;
    }
    for (int k = 1; k < tl->n; k++) {
        const keyframe *k0 = &tl->key[k - 1], *k1 = &tl->key[k];
        if (t < k1->t) {
            double s = ease(e, (t - k0->t) / (k1->t - k0->t));
            for (int i = 0; i < P_COUNT; i++)
                v[i] = k0->v[i] + (k1->v[i] - k0->v[i]) * s;
            return;
        }
    }
    memcpy(v, tl->key[tl->n - 1].v, sizeof tl->key[0].v);
}

/* ---- what one frame needs ---- */

typedef struct frame_pose {
    double root[3]; /* Hips position, world */
    double hips[3]; /* Hips world rotation: pitch (forward), yaw (left), roll; degrees */
    double spine[3], chest[3], neck[3], head[3]; /* local pitch, yaw, roll */
    double clav_elev[2], clav_prot[2];
    double arm_flex[2], arm_abd[2]; /* relative to an upright chest */
    double elbow[2], swing[2], wrist[2];
    double ankle[2][3];   /* ankle targets, world */
    double foot_pitch[2]; /* world pitch of the foot (positive = heel up) */
    double toe[2];        /* toe flexion relative to the foot */
} frame_pose;

/* Posture weight: 0 in the rest holds, eased to 1 over the first and last stretch of the
 * movement [t0, t1]. */
static double posture_weight(const emotion *e, double t, double t0, double t1)
{
    double ramp = 1.0 / e->tempo;
    if (ramp > (t1 - t0) / 3.0)
        ramp = (t1 - t0) / 3.0;
    return ease(e, (t - t0) / ramp) * ease(e, (t1 - t) / ramp);
}

static void rest_pose(const performer *p, frame_pose *fp)
{
    memset(fp, 0, sizeof *fp);
    fp->root[1] = p->root_y;
    fp->spine[0] = p->rest_trunk;
    fp->head[0] = p->rest_head;
    for (int s = 0; s < 2; s++) {
        double sign = s ? -1.0 : 1.0;
        fp->arm_abd[s] = p->rest_abd;
        fp->elbow[s] = p->rest_elbow;
        fp->ankle[s][0] = sign * p->stance;
        fp->ankle[s][1] = p->ankle_h;
    }
}

/* Adds the emotion's posture, weighted by w. */
static void add_posture(const emotion *e, double w, frame_pose *fp)
{
    fp->hips[0] += w * e->lean;
    fp->spine[0] += w * e->spine;
    fp->chest[0] += w * e->chest;
    fp->neck[0] += w * e->neck;
    fp->head[0] += w * e->head;
    for (int s = 0; s < 2; s++) {
        fp->clav_elev[s] += w * e->clav_elev;
        fp->clav_prot[s] += w * e->clav_prot;
        fp->arm_abd[s] += w * e->arm_abd;
        fp->elbow[s] += w * e->elbow;
    }
}

static void keyed_pose(const performer *p, const emotion *e, const timeline *tl, double t,
                       frame_pose *fp)
{
    double v[P_COUNT];
    timeline_eval(tl, e, t, v);
    rest_pose(p, fp);
    double t0 = tl->key[0].t, t1 = tl->key[tl->n - 1].t;
    double w = posture_weight(e, t, t0, t1);
    add_posture(e, w, fp);

    fp->arm_flex[1] += v[P_RFLEX];
    fp->arm_abd[1] += v[P_RABD];
    fp->elbow[1] += v[P_RELB];
    fp->swing[1] += v[P_RSWING];
    fp->wrist[1] += v[P_RWRIST];
    fp->arm_flex[0] += v[P_LFLEX];
    fp->arm_abd[0] += v[P_LABD];
    fp->elbow[0] += v[P_LELB];
    fp->hips[0] += 0.55 * v[P_BOW];
    fp->spine[0] += 0.25 * v[P_BOW];
    fp->chest[0] += 0.20 * v[P_BOW];
    fp->neck[0] += v[P_NECK];
    fp->head[0] += v[P_HEAD];

    /* balance: the pelvis goes back as the trunk goes forward; the Hips come down as far as
     * the feet, planted, require (and, for happy, bounce) */
    fp->root[2] -= 0.16 * sin(fp->hips[0] * DEG);
    if (e->bounce > 0.0 && t > t0 && t < t1)
        fp->root[1] -= w * e->bounce * 0.5 * (1.0 - cos(2.0 * PI * BOUNCE_HZ * (t - t0)));
    double h = standing_height(p, fp->root, fp->hips, (const double(*)[3])fp->ankle);
    if (fp->root[1] > h)
        fp->root[1] = h;
}

/* ---- walking ---- */

typedef struct gait {
    double t0, T, s; /* start, step duration, step length */
    double duty;     /* double-support fraction of a step */
    int n, lead;
    double low, high; /* Hips height at double support and at mid-stance */
    double reach;     /* longest hip-to-ankle distance of a stance leg */
    double lift, sway, arm, lean;
} gait;

static int step_foot(const gait *g, int k)
{
    return (k % 2 == 1) ? g->lead : 1 - g->lead;
}

static double step_from(const gait *g, int k)
{
    return k <= 2 ? 0.0 : (k - 2) * g->s;
}

static double step_to(const gait *g, int k)
{
    return k == g->n ? (k - 1) * g->s : k * g->s;
}

/* Step index k (1..n) and phase psi in [0, 1) at time t; k = 0 before, n + 1 after. */
static int gait_step(const gait *g, double t, double *psi)
{
    double x = (t - g->t0) / g->T;
    if (x < 0.0) {
        *psi = 0.0;
        return 0;
    }
    if (x >= g->n) {
        *psi = 0.0;
        return g->n + 1;
    }
    int k = (int)floor(x);
    *psi = x - k;
    return k + 1;
}

/* Where the foot is along z by plan (no heel lift), and whether it is swinging. */
static double foot_plan_z(const gait *g, const emotion *e, int side, double t)
{
    double z = 0.0;
    for (int k = 1; k <= g->n; k++) {
        if (step_foot(g, k) != side)
            continue;
        double t_off = g->t0 + (k - 1 + g->duty) * g->T, t_land = g->t0 + k * g->T;
        if (t < t_off)
            return z;
        if (t < t_land)
            return step_from(g, k) +
                   (step_to(g, k) - step_from(g, k)) * ease(e, (t - t_off) / (t_land - t_off));
        z = step_to(g, k);
    }
    return z;
}

static void gait_pelvis(const gait *g, const performer *p, const emotion *e, double t,
                        double root[3], double rot[3])
{
    double psi;
    int k = gait_step(g, t, &psi);
    double z, y, x = 0.0;
    double f_in = 2.0 * psi * psi * psi - psi * psi * psi * psi; /* 0 → 1, end slope 2 */
    double q = 1.0 - psi;
    double f_out = 1.0 - (2.0 * q * q * q - q * q * q * q); /* start slope 2 → 1 */
    if (k == 0) {
        z = 0.0;
        y = p->root_y;
    } else if (k > g->n) {
        z = (g->n - 1) * g->s;
        y = p->root_y;
    } else if (k == 1) {
        z = 0.5 * g->s * f_in;
        y = p->root_y + (g->low - p->root_y) * smoothstep(psi);
        x = sin(PI * psi) * smoothstep(psi);
    } else if (k == g->n) {
        z = (k - 1.5) * g->s + 0.5 * g->s * f_out;
        y = g->low + (p->root_y - g->low) * smoothstep(psi);
        x = sin(PI * psi) * smoothstep(1.0 - psi);
    } else {
        z = (k - 1.5 + psi) * g->s;
        y = g->low + (g->high - g->low) * 0.5 * (1.0 - cos(2.0 * PI * psi));
        x = sin(PI * psi);
    }
    if (k >= 1 && k <= g->n) {
        /* sway towards the stance foot (the one not stepping); happy bounces at each step */
        double stance_sign = step_foot(g, k) == 0 ? -1.0 : 1.0;
        x *= g->sway * stance_sign;
        double b = e->bounce;
        if (k == 1)
            y -= b * smoothstep(psi);
        else if (k == g->n)
            y -= b * (1.0 - smoothstep(psi));
        else
            y -= b * 0.5 * (1.0 + cos(2.0 * PI * psi));
    }
    root[0] = x;
    root[1] = y;
    root[2] = z;
    double t1 = g->t0 + g->n * g->T;
    double gw = smoothstep((t - g->t0) / g->T) * smoothstep((t1 - t) / g->T);
    double d = (foot_plan_z(g, e, 1, t) - foot_plan_z(g, e, 0, t)) / g->s;
    rot[0] = gw * g->lean + posture_weight(e, t, g->t0, t1) * e->lean;
    rot[1] = 4.0 * clamp(d, -1.0, 1.0) * (g->arm / 16.0);
    rot[2] = 0.0;
}

/* Ankle of a foot whose ball is planted at ball, heel raised by phi degrees. */
static void ankle_about_ball(const performer *p, int side, const double ball[3], double phi,
                             double out[3])
{
    double sign = side ? -1.0 : 1.0, r[9], v[3];
    rot_yxz(phi, sign * p->toe_out, 0.0, r);
    mat_vec(r, p->off[J_TOES_L + SIDE_STRIDE * side], v);
    for (int a = 0; a < 3; a++)
        out[a] = ball[a] - v[a];
}

/* A stance foot at (x, z) on the floor: raises the heel about the ball just enough for the
 * leg to reach it from hip. Returns the heel lift in degrees and the ankle in out. */
static double stance_foot(const gait *g, const performer *p, int side, double z,
                          const double hip[3], double out[3])
{
    double sign = side ? -1.0 : 1.0;
    double flat[3] = {sign * p->stance, p->ankle_h, z}, ball[3], r[9], v[3];
    memcpy(out, flat, sizeof flat);
    if (dist3(flat, hip) <= g->reach)
        return 0.0;
    rot_yxz(0.0, sign * p->toe_out, 0.0, r);
    mat_vec(r, p->off[J_TOES_L + SIDE_STRIDE * side], v);
    for (int a = 0; a < 3; a++)
        ball[a] = flat[a] + v[a];
    double lo = 0.0, hi = 60.0;
    ankle_about_ball(p, side, ball, hi, out);
    if (dist3(out, hip) > g->reach)
        return hi;
    for (int i = 0; i < 40; i++) {
        double mid = 0.5 * (lo + hi);
        ankle_about_ball(p, side, ball, mid, out);
        if (dist3(out, hip) > g->reach)
            lo = mid;
        else
            hi = mid;
    }
    ankle_about_ball(p, side, ball, hi, out);
    return hi;
}

static void gait_foot(const gait *g, const performer *p, const emotion *e, int side, double t,
                      double ankle[3], double *pitch, double *toe)
{
    double root[3], rot[3], hip[3];
    double z = 0.0;
    for (int k = 1; k <= g->n; k++) {
        if (step_foot(g, k) != side)
            continue;
        double t_off = g->t0 + (k - 1 + g->duty) * g->T, t_land = g->t0 + k * g->T;
        if (t < t_off)
            break;
        if (t < t_land) {
            /* swinging: from the toe-off state to a flat landing */
            double a_off[3], sign = side ? -1.0 : 1.0;
            gait_pelvis(g, p, e, t_off, root, rot);
            hip_joint(p, side, root, rot, hip);
            double phi_off = stance_foot(g, p, side, step_from(g, k), hip, a_off);
            double land[3] = {sign * p->stance, p->ankle_h, step_to(g, k)};
            double u = (t - t_off) / (t_land - t_off), s = ease(e, u);
            double bump = sin(PI * u);
            for (int a = 0; a < 3; a++)
                ankle[a] = a_off[a] + (land[a] - a_off[a]) * s;
            ankle[1] += g->lift * bump;
            *pitch = phi_off * (1.0 - s) - 12.0 * bump * u;
            *toe = -phi_off * (1.0 - s);
            return;
        }
        z = step_to(g, k);
    }
    gait_pelvis(g, p, e, t, root, rot);
    hip_joint(p, side, root, rot, hip);
    *pitch = stance_foot(g, p, side, z, hip, ankle);
    *toe = -*pitch;
}

static void make_gait(const performer *p, const emotion *e, gait *g)
{
    g->t0 = p->hold0;
    g->T = p->step_time / e->tempo;
    g->s = p->step_len * pow(e->amp, 0.6);
    if (g->s > 0.95 * p->leg)
        g->s = 0.95 * p->leg;
    g->duty = 0.2;
    g->n = p->n_steps;
    g->lead = p->lead;
    double hip_off = -p->off[J_UPPERLEG_L][1];
    double r_low = 0.995 * p->leg;
    g->low = p->ankle_h + sqrt(r_low * r_low - 0.25 * g->s * g->s) + hip_off - 0.01;
    g->high = p->ankle_h + 0.993 * p->leg + hip_off;
    if (g->high > p->root_y)
        g->high = p->root_y;
    g->reach = 0.999 * p->leg;
    g->lift = 0.05 * p->leg * sqrt(e->amp);
    g->sway = 0.02;
    g->arm = clamp(p->arm_swing * e->amp, 0.0, 45.0);
    g->lean = 3.0;
}

static void walk_pose(const performer *p, const emotion *e, const gait *g, double t, frame_pose *fp)
{
    rest_pose(p, fp);
    double t1 = g->t0 + g->n * g->T;
    double w = posture_weight(e, t, g->t0, t1);
    double gw = smoothstep((t - g->t0) / g->T) * smoothstep((t1 - t) / g->T);
    add_posture(e, w, fp);
    gait_pelvis(g, p, e, t, fp->root, fp->hips); /* includes the emotion's lean */
    double yaw = fp->hips[1];
    fp->spine[1] = -0.7 * yaw;
    fp->chest[1] = -0.7 * yaw;
    fp->neck[1] = 0.4 * yaw;
    for (int s = 0; s < 2; s++)
        gait_foot(g, p, e, s, t, fp->ankle[s], &fp->foot_pitch[s], &fp->toe[s]);
    double d = clamp((foot_plan_z(g, e, 1, t) - foot_plan_z(g, e, 0, t)) / g->s, -1.0, 1.0);
    fp->arm_flex[0] += g->arm * d;
    fp->arm_flex[1] -= g->arm * d;
    fp->elbow[0] += gw * 6.0 + 8.0 * (d > 0.0 ? d : 0.0);
    fp->elbow[1] += gw * 6.0 + 8.0 * (d < 0.0 ? -d : 0.0);
}

/* ---- legs by inverse kinematics, then forward kinematics ---- */

/* Rotation whose image of the bone direction (0, −1, 0) is u, with local z towards fwd. */
static void bone_frame(const double u[3], const double fwd[3], double r[9])
{
    double y[3] = {-u[0], -u[1], -u[2]}, z[3], x[3];
    double d = fwd[0] * y[0] + fwd[1] * y[1] + fwd[2] * y[2];
    for (int a = 0; a < 3; a++)
        z[a] = fwd[a] - d * y[a];
    double n = sqrt(z[0] * z[0] + z[1] * z[1] + z[2] * z[2]);
    for (int a = 0; a < 3; a++)
        z[a] /= n;
    x[0] = y[1] * z[2] - y[2] * z[1];
    x[1] = y[2] * z[0] - y[0] * z[2];
    x[2] = y[0] * z[1] - y[1] * z[0];
    for (int i = 0; i < 3; i++) {
        r[i * 3] = x[i];
        r[i * 3 + 1] = y[i];
        r[i * 3 + 2] = z[i];
    }
}

/* Two-bone IK: thigh and shank world rotations putting the ankle at (or, out of reach, as
 * near as possible to) target, the knee bending towards fwd. */
static void leg_ik(const double hip[3], const double target[3], double l1, double l2,
                   const double fwd[3], double r_thigh[9], double r_shank[9])
{
    double d[3], dn[3], perp[3], knee[3], u1[3], u2[3];
    for (int a = 0; a < 3; a++)
        d[a] = target[a] - hip[a];
    double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (int a = 0; a < 3; a++)
        dn[a] = d[a] / len;
    len = clamp(len, fabs(l1 - l2) + 1e-4, 0.9999 * (l1 + l2));
    double along = (l1 * l1 - l2 * l2 + len * len) / (2.0 * len);
    double h = sqrt(fmax(0.0, l1 * l1 - along * along));
    double fd = fwd[0] * dn[0] + fwd[1] * dn[1] + fwd[2] * dn[2];
    for (int a = 0; a < 3; a++)
        perp[a] = fwd[a] - fd * dn[a];
    double pn = sqrt(perp[0] * perp[0] + perp[1] * perp[1] + perp[2] * perp[2]);
    for (int a = 0; a < 3; a++) {
        perp[a] /= pn;
        knee[a] = hip[a] + along * dn[a] + h * perp[a];
        u1[a] = (knee[a] - hip[a]) / l1;
        u2[a] = (hip[a] + len * dn[a] - knee[a]) / l2;
    }
    bone_frame(u1, fwd, r_thigh);
    bone_frame(u2, fwd, r_shank);
}

/* Local rotations and translations of one frame, then positions by FK. */
static void pose_to_positions(const performer *p, const frame_pose *fp, double *trans, double *rot,
                              double *scratch, float *out)
{
    int32_t parents[J_COUNT];
    for (int j = 0; j < J_COUNT; j++) {
        parents[j] = skeleton[j].parent;
        memcpy(trans + j * 3, p->off[j], 3 * sizeof(double));
        identity(rot + j * 9);
    }
    memcpy(trans + J_HIPS * 3, fp->root, 3 * sizeof(double));
    double r_hips[9];
    rot_yxz(fp->hips[0], fp->hips[1], fp->hips[2], r_hips);
    memcpy(rot + J_HIPS * 9, r_hips, sizeof r_hips);
    rot_yxz(fp->spine[0], fp->spine[1], fp->spine[2], rot + J_SPINE * 9);
    rot_yxz(fp->chest[0], fp->chest[1], fp->chest[2], rot + J_CHEST * 9);
    rot_yxz(fp->neck[0], fp->neck[1], fp->neck[2], rot + J_NECK * 9);
    rot_yxz(fp->head[0], fp->head[1], fp->head[2], rot + J_HEAD * 9);

    /* arms hang mostly with gravity: compensate 80 % of the chest's forward pitch */
    double chest_pitch = fp->hips[0] + fp->spine[0] + fp->chest[0];
    double hang[9];
    rot_yxz(-0.8 * chest_pitch, 0.0, 0.0, hang);
    for (int s = 0; s < 2; s++) {
        double sign = s ? -1.0 : 1.0;
        int js = J_SHOULDER_L + SIDE_STRIDE * s;
        static const int zyx[3] = {2, 1, 0};
        double clav_deg[3] = {sign * fp->clav_elev[s], -sign * fp->clav_prot[s], 0.0};
        double r_clav[9], anat[9], rel[9];
        affect_euler_deg_to_matrix(zyx, clav_deg, r_clav);
        memcpy(rot + js * 9, r_clav, sizeof r_clav);
        rot_zxy(sign * fp->arm_abd[s], -fp->arm_flex[s], 0.0, anat);
        affect_mat3_mul(hang, anat, rel);
        mat_tmul(r_clav, rel, rot + (js + 1) * 9);
        rot_zxy(sign * fp->swing[s], -clamp(fp->elbow[s], 0.0, 150.0), 0.0, rot + (js + 2) * 9);
        rot_zxy(0.0, -fp->wrist[s], 0.0, rot + (js + 3) * 9);
    }

    for (int s = 0; s < 2; s++) {
        double sign = s ? -1.0 : 1.0;
        int jl = J_UPPERLEG_L + SIDE_STRIDE * s;
        double hip[3], fwd[3], r_thigh[9], r_shank[9], r_foot[9];
        hip_joint(p, s, fp->root, fp->hips, hip);
        fwd[0] = sin(sign * p->toe_out * DEG);
        fwd[1] = 0.0;
        fwd[2] = cos(sign * p->toe_out * DEG);
        leg_ik(hip, fp->ankle[s], p->thigh, p->shin, fwd, r_thigh, r_shank);
        rot_yxz(fp->foot_pitch[s], sign * p->toe_out, 0.0, r_foot);
        mat_tmul(r_hips, r_thigh, rot + jl * 9);
        mat_tmul(r_thigh, r_shank, rot + (jl + 1) * 9);
        mat_tmul(r_shank, r_foot, rot + (jl + 2) * 9);
        rot_yxz(fp->toe[s], 0.0, 0.0, rot + (jl + 3) * 9);
    }
    affect_fk_frame(J_COUNT, parents, trans, rot, scratch, out);
}

/* ---- the entry point ---- */

static int lookup(const char *const *names, const char *name)
{
    for (int i = 0; names[i]; i++)
        if (strcmp(names[i], name) == 0)
            return i;
    return -1;
}

static affect_status unknown_name(const char *what, const char *name, const char *const *names,
                                  affect_error *err)
{
    char list[128];
    size_t len = 0;
    for (int i = 0; names[i]; i++) {
        size_t n = strlen(names[i]);
        if (len + n + 3 >= sizeof list)
            break;
        if (i) {
            memcpy(list + len, ", ", 2);
            len += 2;
        }
        memcpy(list + len, names[i], n);
        len += n;
    }
    list[len] = '\0';
    return affect_fail(err, AFFECT_ERR_INVALID, "unknown %s \"%.64s\" (expected %s)", what, name,
                       list);
}

affect_status affect_motion_synth(const char *action, const char *emotion_name, uint64_t seed,
                                  const affect_synth_options *opt, affect_motion **out,
                                  affect_error *err)
{
    affect_synth_options defaults;
    affect_motion *m = NULL;
    double *work = NULL;
    affect_status st = AFFECT_OK;

    *out = NULL;
    if (!action)
        return affect_fail(err, AFFECT_ERR_INVALID, "action is NULL");
    if (!emotion_name)
        return affect_fail(err, AFFECT_ERR_INVALID, "emotion is NULL");
    int act = lookup(affect_synth_actions, action);
    if (act < 0)
        return unknown_name("action", action, affect_synth_actions, err);
    int emo = lookup(affect_synth_emotions, emotion_name);
    if (emo < 0)
        return unknown_name("emotion", emotion_name, affect_synth_emotions, err);
    if (!opt) {
        affect_synth_options_default(&defaults);
        opt = &defaults;
    }
    if (!(opt->fps > 0.0 && opt->fps <= SYNTH_MAX_FPS))
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "fps must be greater than 0 and at most %g, got %g", SYNTH_MAX_FPS,
                           opt->fps);
    if (!(opt->intensity >= 0.0 && opt->intensity <= SYNTH_MAX_INTENSITY))
        return affect_fail(err, AFFECT_ERR_INVALID, "intensity must be between 0 and %g, got %g",
                           SYNTH_MAX_INTENSITY, opt->intensity);
    if (!(opt->noise >= 0.0 && opt->noise <= SYNTH_MAX_NOISE))
        return affect_fail(err, AFFECT_ERR_INVALID, "noise must be between 0 and %g, got %g",
                           SYNTH_MAX_NOISE, opt->noise);

    affect_rng rng;
    affect_rng_seed(&rng, seed);
    performer p;
    draw_performer(&rng, &p);
    finish_performer(&p);
    emotion e = emotion_at(emo, opt->intensity, &p);

    timeline tl;
    gait g;
    double t_end;
    if (act == A_WALK) {
        make_gait(&p, &e, &g);
        t_end = g.t0 + g.n * g.T + p.hold1;
    } else {
        build_timeline(act, &p, &e, &tl);
        t_end = tl.key[tl.n - 1].t + p.hold1;
    }
    double frames = floor(t_end * opt->fps) + 1.0;
    if (frames > AFFECT_MOTION_MAX_FRAMES || frames * J_COUNT > AFFECT_MOTION_MAX_SAMPLES)
        return affect_fail(err, AFFECT_ERR_RANGE,
                           "motion too long: %.0f frames x %d joints (at most %u samples)", frames,
                           (int)J_COUNT, AFFECT_MOTION_MAX_SAMPLES);
    uint32_t n_frames = (uint32_t)frames;

    st = affect_motion_create(n_frames, J_COUNT, opt->fps, &m, err);
    if (st)
        goto cleanup;
    for (uint32_t j = 0; j < J_COUNT; j++) {
        st = affect_motion_set_name(m, j, skeleton[j].name, strlen(skeleton[j].name), err);
        if (st)
            goto cleanup;
        m->parents[j] = skeleton[j].parent;
    }
    st = affect_motion_set_unit(m, "m", err);
    if (st)
        goto cleanup;
    /* local translations (J×3), local rotations (J×9), FK scratch (J×12) */
    work = affect_malloc_array((size_t)J_COUNT * 24, sizeof *work);
    if (!work) {
        st = affect_nomem(err);
        goto cleanup;
    }

    for (uint32_t t = 0; t < n_frames; t++) {
        double time = t / opt->fps;
        frame_pose fp;
        if (act == A_WALK)
            walk_pose(&p, &e, &g, time, &fp);
        else
            keyed_pose(&p, &e, &tl, time, &fp);
        float *pos = affect_motion_at(m, t, 0);
        pose_to_positions(&p, &fp, work, work + J_COUNT * 3, work + J_COUNT * 12, pos);
    }
    if (opt->noise > 0.0) {
        size_t n = (size_t)n_frames * J_COUNT * 3;
        for (size_t i = 0; i < n; i++)
            m->pos[i] = (float)((double)m->pos[i] + opt->noise * affect_rng_normal(&rng));
    }
    *out = m;
    m = NULL;

cleanup:
    affect_free(work);
    affect_motion_free(m);
    return st;
}
