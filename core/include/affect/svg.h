/*
 * affect/svg.h — motion previews as SVG: a film strip of evenly spaced frames drawn as stick
 * figures (bones from the parent indices; dots when the skeleton is unknown), with the
 * end-effector trajectories (head, hands, feet when the roles resolve) drawn faintly behind.
 *
 * Usage:
 *     const affect_motion *m = ...;
 *     affect_error err;
 *     affect_roles roles;
 *     affect_roles_resolve(m, &roles);
 *     affect_svg_options opt;
 *     affect_svg_options_default(&opt);
 *     opt.view = AFFECT_SVG_SIDE;
 *     opt.title = "walk, happy";
 *     char *svg = NULL;  size_t len = 0;
 *     if (affect_motion_svg(m, &roles, &opt, &svg, &len, &err) == AFFECT_OK)
 *         fwrite(svg, 1, len, stdout);
 *     affect_free(svg);
 *
 * Views: "front" looks along −z at the x–up plane, "side" along +x at the z–up plane, "top"
 * down the up axis at the x–z plane (for y-up data; the axes rotate with opt->up_axis), turned
 * so that a travelling motion goes to the right, with the pelvis's path and a facing mark. All
 * panels share one scale so sizes compare across frames; each panel is centred horizontally
 * on the pelvis (or the body's centroid) at its frame, so travelling motions stay in view.
 *
 * Animated previews (opt->animate): one panel whose stick figure moves, written with SMIL
 * <animate> elements (no script; plays in any browser, also as an <img>), looping in real time
 * over evenly spaced keyframes. Groups (affect_motion_svg_group): several motions drawn at one
 * scale, side by side when animated, one strip per row otherwise, each with its caption.
 */
#ifndef AFFECT_SVG_H
#define AFFECT_SVG_H

#include "affect/roles.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum affect_svg_view {
    AFFECT_SVG_FRONT = 0,
    AFFECT_SVG_SIDE = 1,
    AFFECT_SVG_TOP = 2
} affect_svg_view;

typedef struct affect_svg_options {
    affect_svg_view view; /* default front */
    uint32_t frames;      /* panels in the strip (default 8; clamped to the frame count) */
    uint32_t panel_size;  /* panel width and height in pixels (default 160) */
    int up_axis;          /* 0 = x, 1 = y (default), 2 = z */
    bool trajectories;    /* draw end-effector paths (default true) */
    bool labels;          /* frame number and time under each panel (default true) */
    const char *title;    /* optional caption above the strip (NULL for none) */
    bool animate;         /* one animated panel instead of the strip (default false) */
    uint32_t keyframes;   /* animate: keyframes per loop, 2..1000, at most the frame count;
                             0 (default) = AFFECT_SVG_KEY_RATE per second of motion, at most
                             AFFECT_SVG_KEY_AUTO_MAX */
    bool state_labels;    /* labels read "state N" (N = frame + 1: hmm_postures) */
} affect_svg_options;

#define AFFECT_SVG_KEY_RATE 15.0     /* automatic keyframes per second */
#define AFFECT_SVG_KEY_AUTO_MAX 150u /* most automatic keyframes */
#define AFFECT_SVG_MAX_KEYFRAMES 1000u
#define AFFECT_SVG_MAX_GROUP 64u /* most motions of one group */

void affect_svg_options_default(affect_svg_options *opt);

/* Writes a complete standalone <svg> document (free *out with affect_free). */
affect_status affect_motion_svg(const affect_motion *m, const affect_roles *roles,
                                const affect_svg_options *opt, char **out, size_t *len,
                                affect_error *err);

/* Several motions in one document, drawn at ONE scale (the largest at which each fits) so their
 * sizes compare: with opt->animate, one animated panel per motion side by side (each loops at
 * its own real-time duration); otherwise one film strip per motion, one under the other. roles
 * is an array of n (NULL: no roles); captions an array of n strings (NULL, or NULL entries, for
 * none) written under each animated panel or above each strip. n is 1..AFFECT_SVG_MAX_GROUP;
 * "group: motion 3: …" prefixes the errors of one motion (0-based). A group of one motion
 * without caption is affect_motion_svg's document. */
affect_status affect_motion_svg_group(const affect_motion *const *m, const affect_roles *roles,
                                      const char *const *captions, size_t n,
                                      const affect_svg_options *opt, char **out, size_t *len,
                                      affect_error *err);

#ifdef __cplusplus
}
#endif
#endif
