/*
 * roles.c — resolve body-part roles from joint names (see affect/roles.h).
 *
 * How it works: each joint name is reduced to (side, body word). The part after the last ':'
 * is kept (mixamorig:LeftHand → LeftHand); a side is found as a "left"/"right" word anywhere,
 * an "l"/"r" token at either end separated by '_', '.', '-' or ' ' (Hand_L, l_wrist, R.Knee),
 * a capital L/R followed by another capital (LWrist, RHand), or a lower-case l/r glued before a
 * known body word (lhand, rknee). The body word is the remaining letters in lower case with
 * separators removed and trailing digits kept apart ("Spine1" → "spine" + 1). Each role then
 * takes the first joint (in joint order) whose word is in the role's list, trying the list in
 * priority order: e.g. the shoulder role prefers "upperarm"/"arm" (the shoulder joint in Mixamo,
 * CMU and this corpus) over "shoulder" (often the clavicle), and the hand prefers "hand" over
 * "wrist".
 */
#include "affect/roles.h"

#include <string.h>

static const char *const role_names[AFFECT_ROLE_COUNT] = {
    "pelvis",        "spine",      "chest",      "neck",           "head",
    "left_shoulder", "left_elbow", "left_hand",  "right_shoulder", "right_elbow",
    "right_hand",    "left_hip",   "left_knee",  "left_foot",      "left_toe",
    "right_hip",     "right_knee", "right_foot", "right_toe"};

const char *affect_role_name(affect_role role)
{
    return (unsigned)role < AFFECT_ROLE_COUNT ? role_names[role] : NULL;
}

int affect_role_from_name(const char *name)
{
    for (int r = 0; r < AFFECT_ROLE_COUNT; r++)
        if (strcmp(role_names[r], name) == 0)
            return r;
    if (strcmp(name, "left_wrist") == 0)
        return AFFECT_ROLE_LEFT_HAND;
    if (strcmp(name, "right_wrist") == 0)
        return AFFECT_ROLE_RIGHT_HAND;
    return -1;
}

enum { SIDE_NONE = 0, SIDE_LEFT = 1, SIDE_RIGHT = 2 };

#define WORD_MAX 48

typedef struct parsed_name {
    int side;
    char word[WORD_MAX]; /* lower-case letters only */
    int number;          /* trailing number, or −1 */
    bool end_site;
} parsed_name;

static char lower(char c)
{
    return c >= 'A' && c <= 'Z' ? (char)(c - 'A' + 'a') : c;
}

static bool is_upper(char c)
{
    return c >= 'A' && c <= 'Z';
}

static bool is_alpha(char c)
{
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z');
}

static bool is_sep(char c)
{
    return c == '_' || c == '.' || c == '-' || c == ' ';
}

/* Body words that may carry a glued l/r prefix ("lhand"). */
static const char *const glued_words[] = {
    "shoulder", "clavicle", "collar", "arm",    "upperarm", "forearm", "lowerarm", "elbow",
    "hand",     "wrist",    "hip",    "upleg",  "upperleg", "thigh",   "leg",      "lowerleg",
    "knee",     "shin",     "calf",   "foot",   "ankle",    "toe",     "toes",     "toebase",
    "humerus",  "femur",    "tibia",  "radius", NULL};

static bool is_glued_word(const char *w)
{
    for (int i = 0; glued_words[i]; i++)
        if (strcmp(w, glued_words[i]) == 0)
            return true;
    return false;
}

static bool ends_with(const char *s, size_t n, const char *suffix)
{
    size_t k = strlen(suffix);
    if (k > n)
        return false;
    for (size_t i = 0; i < k; i++)
        if (lower(s[n - k + i]) != suffix[i])
            return false;
    return true;
}

static void parse_name(const char *full, parsed_name *out)
{
    const char *s = strrchr(full, ':');
    s = s ? s + 1 : full;
    size_t n = strlen(s);
    out->side = SIDE_NONE;
    out->number = -1;
    out->word[0] = '\0';
    out->end_site = ends_with(s, n, "_end") || ends_with(s, n, "end site") ||
                    ends_with(s, n, "_end_site") || ends_with(s, n, "top_end") ||
                    ends_with(s, n, "nub") || ends_with(s, n, "_site");

    /* copy with a mask of which bytes remain after removing side markers */
    char buf[128];
    if (n >= sizeof buf)
        n = sizeof buf - 1;
    memcpy(buf, s, n);
    buf[n] = '\0';
    bool keep[128];
    for (size_t i = 0; i < n; i++)
        keep[i] = true;

    /* "left" / "right" anywhere (case-insensitive) */
    for (size_t i = 0; i < n && out->side == SIDE_NONE; i++) {
        if (i + 4 <= n && lower(buf[i]) == 'l' && lower(buf[i + 1]) == 'e' &&
            lower(buf[i + 2]) == 'f' && lower(buf[i + 3]) == 't') {
            out->side = SIDE_LEFT;
            for (size_t k = i; k < i + 4; k++)
                keep[k] = false;
        } else if (i + 5 <= n && lower(buf[i]) == 'r' && lower(buf[i + 1]) == 'i' &&
                   lower(buf[i + 2]) == 'g' && lower(buf[i + 3]) == 'h' &&
                   lower(buf[i + 4]) == 't') {
            out->side = SIDE_RIGHT;
            for (size_t k = i; k < i + 5; k++)
                keep[k] = false;
        }
    }
    /* a lone l/r token at the end or the start: Hand_L, l_wrist, R.Knee */
    if (out->side == SIDE_NONE && n >= 3 && is_sep(buf[n - 2]) &&
        (lower(buf[n - 1]) == 'l' || lower(buf[n - 1]) == 'r')) {
        out->side = lower(buf[n - 1]) == 'l' ? SIDE_LEFT : SIDE_RIGHT;
        keep[n - 1] = keep[n - 2] = false;
    }
    if (out->side == SIDE_NONE && n >= 3 && is_sep(buf[1]) &&
        (lower(buf[0]) == 'l' || lower(buf[0]) == 'r')) {
        out->side = lower(buf[0]) == 'l' ? SIDE_LEFT : SIDE_RIGHT;
        keep[0] = keep[1] = false;
    }
    /* LWrist, RHand: capital L/R followed by another capital */
    if (out->side == SIDE_NONE && n >= 3 && (buf[0] == 'L' || buf[0] == 'R') && is_upper(buf[1])) {
        out->side = buf[0] == 'L' ? SIDE_LEFT : SIDE_RIGHT;
        keep[0] = false;
    }

    /* the body word: remaining letters, lower case; a trailing number kept apart */
    size_t w = 0;
    int number = -1;
    for (size_t i = 0; i < n; i++) {
        if (!keep[i])
            continue;
        char c = buf[i];
        if (is_alpha(c)) {
            if (number >= 0) /* digits in the middle ("spine1a"): not a trailing number */
                number = -1;
            if (w + 1 < WORD_MAX)
                out->word[w++] = lower(c);
        } else if (c >= '0' && c <= '9') {
            number = (number < 0 ? 0 : number * 10) + (c - '0');
            if (number > 9999)
                number = 9999;
        }
    }
    out->word[w] = '\0';
    out->number = number;

    /* lhand, rknee: glued lower-case side prefix before a known body word */
    if (out->side == SIDE_NONE && w >= 2 && (out->word[0] == 'l' || out->word[0] == 'r') &&
        is_glued_word(out->word + 1) && !is_glued_word(out->word)) {
        out->side = out->word[0] == 'l' ? SIDE_LEFT : SIDE_RIGHT;
        memmove(out->word, out->word + 1, w);
    }
}

/* Candidate words per role, in priority order; sided roles list words without the side. */
typedef struct role_rule {
    int side;
    const char *words[8];
} role_rule;

static const role_rule rules[AFFECT_ROLE_COUNT] = {
    [AFFECT_ROLE_PELVIS] = {SIDE_NONE, {"hips", "pelvis", "hip", "root", NULL}},
    [AFFECT_ROLE_SPINE] = {SIDE_NONE, {"spine", "abdomen", "lowerback", "torso", NULL}},
    [AFFECT_ROLE_CHEST] = {SIDE_NONE, {"chest", "upperchest", "thorax", "upperback", NULL}},
    [AFFECT_ROLE_NECK] = {SIDE_NONE, {"neck", NULL}},
    [AFFECT_ROLE_HEAD] = {SIDE_NONE, {"head", "skull", NULL}},
    [AFFECT_ROLE_LEFT_SHOULDER] = {SIDE_LEFT, {"upperarm", "arm", "humerus", "shoulder", NULL}},
    [AFFECT_ROLE_LEFT_ELBOW] = {SIDE_LEFT, {"forearm", "lowerarm", "elbow", "radius", NULL}},
    [AFFECT_ROLE_LEFT_HAND] = {SIDE_LEFT, {"hand", "wrist", NULL}},
    [AFFECT_ROLE_RIGHT_SHOULDER] = {SIDE_RIGHT, {"upperarm", "arm", "humerus", "shoulder", NULL}},
    [AFFECT_ROLE_RIGHT_ELBOW] = {SIDE_RIGHT, {"forearm", "lowerarm", "elbow", "radius", NULL}},
    [AFFECT_ROLE_RIGHT_HAND] = {SIDE_RIGHT, {"hand", "wrist", NULL}},
    [AFFECT_ROLE_LEFT_HIP] = {SIDE_LEFT, {"upleg", "upperleg", "thigh", "hip", "femur", NULL}},
    [AFFECT_ROLE_LEFT_KNEE] = {SIDE_LEFT,
                               {"leg", "lowerleg", "knee", "shin", "calf", "tibia", NULL}},
    [AFFECT_ROLE_LEFT_FOOT] = {SIDE_LEFT, {"foot", "ankle", NULL}},
    [AFFECT_ROLE_LEFT_TOE] = {SIDE_LEFT, {"toebase", "toes", "toe", "ball", NULL}},
    [AFFECT_ROLE_RIGHT_HIP] = {SIDE_RIGHT, {"upleg", "upperleg", "thigh", "hip", "femur", NULL}},
    [AFFECT_ROLE_RIGHT_KNEE] = {SIDE_RIGHT,
                                {"leg", "lowerleg", "knee", "shin", "calf", "tibia", NULL}},
    [AFFECT_ROLE_RIGHT_FOOT] = {SIDE_RIGHT, {"foot", "ankle", NULL}},
    [AFFECT_ROLE_RIGHT_TOE] = {SIDE_RIGHT, {"toebase", "toes", "toe", "ball", NULL}},
};

void affect_roles_resolve(const affect_motion *m, affect_roles *roles)
{
    for (int r = 0; r < AFFECT_ROLE_COUNT; r++)
        roles->joint[r] = -1;
    uint32_t n = m->n_joints;
    parsed_name *names = affect_malloc_array(n, sizeof *names);
    if (!names) {
        /* fall back to parsing on the fly, one joint at a time (no allocation) */
        parsed_name one;
        for (int r = 0; r < AFFECT_ROLE_COUNT; r++)
            for (int w = 0; rules[r].words[w] && roles->joint[r] < 0; w++)
                for (uint32_t j = 0; j < n && roles->joint[r] < 0; j++) {
                    parse_name(m->names[j], &one);
                    if (!one.end_site && one.side == rules[r].side &&
                        strcmp(one.word, rules[r].words[w]) == 0)
                        roles->joint[r] = (int32_t)j;
                }
        goto spine_chest;
    }
    for (uint32_t j = 0; j < n; j++)
        parse_name(m->names[j], &names[j]);
    for (int r = 0; r < AFFECT_ROLE_COUNT; r++)
        for (int w = 0; rules[r].words[w] && roles->joint[r] < 0; w++)
            for (uint32_t j = 0; j < n && roles->joint[r] < 0; j++)
                if (!names[j].end_site && names[j].side == rules[r].side &&
                    strcmp(names[j].word, rules[r].words[w]) == 0)
                    roles->joint[r] = (int32_t)j;
    /* Spine1/Spine2/Spine3 chains: spine = the lowest, chest = the highest when no chest */
    if (roles->joint[AFFECT_ROLE_CHEST] < 0) {
        int32_t best = -1;
        for (uint32_t j = 0; j < n; j++)
            if (!names[j].end_site && names[j].side == SIDE_NONE &&
                strcmp(names[j].word, "spine") == 0 &&
                (int32_t)j != roles->joint[AFFECT_ROLE_SPINE])
                best = (int32_t)j;
        roles->joint[AFFECT_ROLE_CHEST] = best;
    }
    affect_free(names);
spine_chest:
    /* a pelvis is always defined: the first root joint when no name matched */
    if (roles->joint[AFFECT_ROLE_PELVIS] < 0)
        for (uint32_t j = 0; j < n && roles->joint[AFFECT_ROLE_PELVIS] < 0; j++)
            if (m->parents[j] < 0)
                roles->joint[AFFECT_ROLE_PELVIS] = (int32_t)j;
}

static bool equal_nocase(const char *a, const char *b)
{
    for (; *a && *b; a++, b++)
        if (lower(*a) != lower(*b))
            return false;
    return *a == *b;
}

affect_status affect_roles_set(const affect_motion *m, affect_roles *roles, const char *role_name,
                               const char *joint_name, affect_error *err)
{
    int r = affect_role_from_name(role_name);
    if (r < 0)
        return affect_fail(
            err, AFFECT_ERR_INVALID,
            "unknown role \"%.64s\" (expected pelvis, spine, "
            "chest, neck, head, left_/right_ shoulder, elbow, hand, hip, knee, foot, toe)",
            role_name);
    if (!joint_name) {
        roles->joint[r] = -1;
        return AFFECT_OK;
    }
    int32_t j = affect_motion_find_joint(m, joint_name);
    for (uint32_t k = 0; j < 0 && k < m->n_joints; k++)
        if (equal_nocase(m->names[k], joint_name))
            j = (int32_t)k;
    if (j < 0)
        return affect_fail(err, AFFECT_ERR_MISSING, "role %s: no joint named \"%.64s\"", role_name,
                           joint_name);
    roles->joint[r] = j;
    return AFFECT_OK;
}

bool affect_roles_lateral(const affect_motion *m, const affect_roles *roles, uint32_t frame,
                          double out[3])
{
    int32_t l = roles->joint[AFFECT_ROLE_LEFT_HIP], r = roles->joint[AFFECT_ROLE_RIGHT_HIP];
    if (l < 0 || r < 0) {
        l = roles->joint[AFFECT_ROLE_LEFT_SHOULDER];
        r = roles->joint[AFFECT_ROLE_RIGHT_SHOULDER];
    }
    if (l < 0 || r < 0)
        return false;
    const float *pl = affect_motion_at(m, frame, (uint32_t)l);
    const float *pr = affect_motion_at(m, frame, (uint32_t)r);
    for (int a = 0; a < 3; a++)
        out[a] = (double)pl[a] - pr[a];
    return true;
}
