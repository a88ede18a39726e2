/*
 * affect/synth.h — procedural affective movements for tests, demos and users without data.
 *
 * Usage:
 *     affect_error err;
 *     affect_synth_options opt;
 *     affect_synth_options_default(&opt);
 *     opt.intensity = 0.8;
 *     affect_motion *m = NULL;
 *     if (affect_motion_synth("walk", "happy", 42, &opt, &m, &err) != AFFECT_OK)   // seed 42
 *         puts(err.msg);                               // names: affect_synth_actions, _emotions
 *     affect_motion_free(m);
 *
 * Actions: "knock" (knock three times on a door in front with the right hand), "wave" (raise
 * the right hand and wave), "walk" (walk forward), "bow" (bow from the waist), on a named
 * full-body skeleton (y up, metres, facing +z; joint names in the style of the real corpus:
 * Hips, Spine, Chest, Neck, Head, Shoulder_L, UpperArm_L, LowerArm_L, Hand_L, …, with end sites
 * Head_end, Hand_L_end, Toes_L_end, …).
 * Emotions follow the cues reported in the thesis (§4.4.3, §5.1.7): sad — slow, small, long,
 * drooped head and shoulders, slumped trunk; angry — fast, sudden, forceful, forward lean;
 * happy — expansive, upward, bouncy; neutral — moderate.
 * The seed draws the performer's variation: limb lengths (±6 %), tempo (±8 %), amplitude,
 * phase and a small measurement noise. The same (action, emotion, seed, options) always gives
 * the same motion, byte for byte.
 */
#ifndef AFFECT_SYNTH_H
#define AFFECT_SYNTH_H

#include "affect/motion.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct affect_synth_options {
    double fps;       /* frame rate, 0 < fps <= 1000 (default 30) */
    double intensity; /* 0..2, scales how strongly the emotion shows (default 1) */
    double noise;     /* standard deviation of the measurement noise in metres, 0..0.1
                       * (default 0.0003) */
} affect_synth_options;

void affect_synth_options_default(affect_synth_options *opt);

/* Names accepted, for error messages and documentation (NULL-terminated lists). */
extern const char *const affect_synth_actions[];
extern const char *const affect_synth_emotions[];

/* Generates a motion (joint names, parents, unit "m"); opt NULL means the defaults. */
affect_status affect_motion_synth(const char *action, const char *emotion, uint64_t seed,
                                  const affect_synth_options *opt, affect_motion **out,
                                  affect_error *err);

#ifdef __cplusplus
}
#endif
#endif
