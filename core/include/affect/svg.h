/*
 * affect/svg.h — motion previews as SVG: a film strip of evenly spaced frames drawn as stick
 * figures (bones from the parent indices; dots when the skeleton is unknown), with the
 * end-effector trajectories (head, hands, feet when the roles resolve) drawn faintly behind.
 *
 * Views: "front" looks along −z at the x–up plane, "side" along +x at the z–up plane, "top"
 * down the up axis at the x–z plane (for y-up data; the axes rotate with opt->up_axis). All
 * panels share one scale so sizes compare across frames; each panel is centred horizontally
 * on the pelvis (or the body's centroid) at its frame, so travelling motions stay in view.
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
    affect_svg_view view;   /* default front */
    uint32_t frames;        /* panels in the strip (default 8; clamped to the frame count) */
    uint32_t panel_size;    /* panel width and height in pixels (default 160) */
    int up_axis;            /* 0 = x, 1 = y (default), 2 = z */
    bool trajectories;      /* draw end-effector paths (default true) */
    bool labels;            /* frame number and time under each panel (default true) */
    const char *title;      /* optional caption above the strip (NULL for none) */
} affect_svg_options;

void affect_svg_options_default(affect_svg_options *opt);

/* Writes a complete standalone <svg> document (free *out with affect_free). */
affect_status affect_motion_svg(const affect_motion *m, const affect_roles *roles,
                                const affect_svg_options *opt, char **out, size_t *len,
                                affect_error *err);

#ifdef __cplusplus
}
#endif
#endif
