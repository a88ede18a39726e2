/*
 * affect/io.h — text formats in and out of the motion model: BVH, CSV and JSON.
 *
 * Usage:
 *     const char *text = ...;  size_t len = ...;       // the bytes of a .bvh file
 *     affect_error err;
 *     affect_motion *m = NULL;
 *     if (affect_bvh_parse(text, len, NULL, &m, &err) != AFFECT_OK) {   // opt NULL: the defaults
 *         puts(err.msg);                                // "line 57: expected CHANNELS, found ..."
 *         return;
 *     }
 *     char *csv = NULL;  size_t csv_len = 0;
 *     if (affect_csv_write(m, &csv, &csv_len, NULL, &err) == AFFECT_OK)
 *         fwrite(csv, 1, csv_len, stdout);
 *     affect_free(csv);
 *     affect_motion_free(m);
 *
 * Importers check everything they read and report the line (BVH), row (CSV) or byte offset
 * (JSON) of the first problem. Writers use the shortest decimal form that reads back as the
 * same float32, so text round trips are exact.
 */
#ifndef AFFECT_IO_H
#define AFFECT_IO_H

#include "affect/monitor.h"
#include "affect/motion.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct affect_bvh_options {
    double scale;            /* multiply every position by this (default 1) */
    const char *unit;        /* recorded unit, or NULL/"" for unknown (default) */
    uint64_t max_samples;    /* largest frames × joints accepted; 0 (default) =
                                AFFECT_MOTION_MAX_SAMPLES */
    affect_monitor *monitor; /* polled every few thousand frames (may be NULL): the parse
                                stops with AFFECT_ERR_INTERRUPTED once it says so */
} affect_bvh_options;

/* BVH: HIERARCHY with ROOT (one or more), JOINT and End Site; any channel count (0–6) and any
 * order per joint; position channels replace the OFFSET components they name; rotations in
 * degrees composed in the order CHANNELS lists them. End Sites become joints named
 * "<parent>_end". Every frame must be on one line with exactly the declared channel count.
 * "Frames: N" is checked before anything is allocated for the frames: against the text left
 * (a frame line takes at least two bytes per value, and its line end even when no joint has
 * channels; the last line may lack one) and against the limit on frames × joints
 * ("line 14: 20000 frames x 1000 joints is 20000000 samples, above the limit of 16777216
 * (option max_samples)", AFFECT_ERR_RANGE). */
affect_status affect_bvh_parse(const char *text, size_t len, const affect_bvh_options *opt,
                               affect_motion **out, affect_error *err);

typedef struct affect_bvh_write_options {
    int order[3];            /* rotation channel order for every joint; order[0] < 0 (default)
                                keeps each joint's own channels */
    double frame_time;       /* seconds per frame; 0 (default) = 1 / fps */
    int precision;           /* decimals of every number, 1 .. 9 (default 6) */
    const char *root_name;   /* name written for the first root, or NULL (default) */
    affect_monitor *monitor; /* polled every few thousand frames (default NULL): the export
                                stops with AFFECT_ERR_INTERRUPTED once it says so */
} affect_bvh_write_options;

void affect_bvh_write_options_default(affect_bvh_write_options *opt);

/* BVH text of a skeletal motion (m->rot set: imported from BVH, or from affect_motion_ik).
 * The hierarchy lists the joints depth first from each root (children in joint order), with
 * the skeleton's offsets and channels; End Sites as End Site blocks. Each frame line holds the
 * channels' values: translations, and Euler angles (degrees) of the local rotations in each
 * joint's channel order, continuous from frame to frame (angles move by whole turns and
 * switch to the equivalent solution so that no angle jumps). White space and braces in joint
 * names become '_'. Numbers are fixed-point with trailing zeros removed. */
affect_status affect_bvh_write(const affect_motion *m, const affect_bvh_write_options *opt,
                               char **out, size_t *len, affect_error *err);

typedef struct affect_csv_options {
    char delimiter;          /* ',' (default), ';', '\t' or ' ' */
    int header;              /* −1 detect (default), 0 no header row, 1 header row */
    const char *unit;        /* recorded unit, or NULL/"" */
    uint64_t max_samples;    /* largest frames × joints accepted; 0 (default) =
                                AFFECT_MOTION_MAX_SAMPLES */
    affect_monitor *monitor; /* polled every few thousand rows (default NULL): the parse stops
                                with AFFECT_ERR_INTERRUPTED once it says so */
} affect_csv_options;

void affect_csv_options_default(affect_csv_options *opt);

/* CSV: one row per frame, three columns per joint. A header names the joints as "Head.x",
 * "Head_x", "Head X" or "Head:x" (case-insensitive axis, columns in x, y, z order); without a
 * header joints are j0, j1, …. Blank lines are ignored; fields may be double-quoted. */
affect_status affect_csv_parse(const char *text, size_t len, double fps,
                               const affect_csv_options *opt, affect_motion **out,
                               affect_error *err);

/* CSV with a "name.x,name.y,name.z,…" header, one line per frame, '\n' line ends. The text
 * writers and the JSON reader poll mon (may be NULL) every few thousand frames and stop with
 * AFFECT_ERR_INTERRUPTED once it says so. */
affect_status affect_csv_write(const affect_motion *m, char **out, size_t *len, affect_monitor *mon,
                               affect_error *err);

/* JSON: {"fps": f, "joints": [names], "parents": [ints] (optional), "unit": "cm" (optional),
 *        "frames": [[[x, y, z], …joints], …frames]}. Frames × joints may not exceed
 * AFFECT_MOTION_MAX_SAMPLES (no option raises it: the parsed document takes far more memory
 * than the motion, so larger motions come as CSV or BLOBs). */
affect_status affect_motion_from_json(const char *text, size_t len, affect_motion **out,
                                      affect_monitor *mon, affect_error *err);
affect_status affect_motion_to_json(const affect_motion *m, char **out, size_t *len,
                                    affect_monitor *mon, affect_error *err);

#ifdef __cplusplus
}
#endif
#endif
