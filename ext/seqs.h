/*
 * seqs.h — the observation sequences an aggregate collects for training (hmm_train,
 * affect_train): the HMM and observation options, the feature definition fixed by the first
 * motion, and one observation sequence per non-NULL motion.
 *
 * Usage in an aggregate's xStep (options at argument opt_i, the motion at argument 0):
 *     first row:  ax_seqs_options(ctx, argc, argv, opt_i, allowed_keys, ts, &opts)
 *                 (reads the HMM/feature keys; the caller reads its own keys from opts, then
 *                 ax_opts_free(&opts))
 *     every row:  ax_seqs_add(ctx, argc, argv, ts)   (ts->n_seqs grows unless the motion is NULL)
 *     xFinal:     train on ts->seqs, then ax_seqs_free(ts)
 */
#ifndef AFFECT_EXT_SEQS_H
#define AFFECT_EXT_SEQS_H

#include "common.h"

#include "affect/features.h"
#include "affect/hmm.h"

typedef struct ax_seqs {
    bool failed;            /* an error was reported: xFinal only frees */
    int opt_i;              /* the options' argument index */
    ax_opts_text opts_text; /* the first row's options text (NULL when none) */
    affect_hmm_config cfg;
    affect_features_options fo;
    char **joints; /* fo.joints storage: copies of the "joints" option's names */
    uint32_t n_joints;
    affect_features *feat; /* fixed by the first non-NULL motion */
    affect_hmm_seq *seqs;  /* observation sequences (each x owned) */
    uint32_t n_seqs, cap;
    bool preset;        /* cfg and fo hold the caller's defaults (set before
                           ax_seqs_options); otherwise the HMM's and observations' own */
    unsigned desc_mask; /* set by the caller before the rows: descriptors to compute */
    double *desc;       /* n_seqs × affect_descriptors_dim(desc_mask), or NULL */
    uint64_t rows;      /* rows seen, NULL motions included */
    char *progress;     /* the "progress" option: an SQL function's name, or NULL */
    ax_monitor probe;   /* asked after every row (see ax_seqs_add) */
    bool probing;       /* probe begun */
    bool any_length;    /* no HMM is trained: motions shorter than cfg.n_states are fine */
} ax_seqs;

/* The HMM and observation option keys (states … seed), for building an allowed-keys list. */
#define AX_SEQS_KEYS                                                                               \
    "states", "mixtures", "covariance", "topology", "max_jump", "start", "joints", "normalize",    \
        "scale", "up", "velocity", "frame", "root", "max_iter", "tol", "reg", "seed", "progress"

/* Parses the first row's options (argument opt_i; keys must be in allowed) into opts and reads
 * the HMM and observation keys into ts; on AX_OK the caller frees opts. */
ax_arg ax_seqs_options(sqlite3_context *ctx, int argc, sqlite3_value **argv, int opt_i,
                       const char *const *allowed, ax_seqs *ts, ax_opts *opts);
/* Checks one row (same options as the first, a motion or NULL at argument 0) and keeps its
 * observation sequence; AX_ERROR when an error was reported. */
ax_arg ax_seqs_add(sqlite3_context *ctx, int argc, sqlite3_value **argv, ax_seqs *ts);
/* Reports a core error met on the current row: "row 3: …" (out of memory as SQLITE_NOMEM). */
void ax_seqs_row_error(sqlite3_context *ctx, const ax_seqs *ts, const affect_error *err);
/* Frees ts and everything it holds (sqlite3_free for ts itself); NULL is fine. */
void ax_seqs_free(ax_seqs *ts);

/* ---- labelled training aggregates: fn(motion, label [, options]) ----
 * affect_train, fda_train (and affect_crossval's rows): the sequences and, paired with them,
 * each row's label. A function's state starts with an ax_labelled. */
typedef struct ax_labelled {
    ax_seqs s;     /* first: ax_seqs_free frees the whole state */
    char **labels; /* one per sequence */
} ax_labelled;

/* The row's label (argument 1) kept with the row's sequence (ax_seqs_add); a NULL label skips
 * the row. Errors: "row 3: label must be text or a number, got a BLOB", "row 3: label must not
 * be empty or contain NUL", "row 3: label is not valid UTF-8 (byte 0xff at offset 2)". */
ax_arg ax_labelled_add(sqlite3_context *ctx, int argc, sqlite3_value **argv, ax_labelled *t);
/* Frees the labels, then the whole state (ax_seqs_free); NULL is fine. */
void ax_labelled_free(ax_labelled *t);

/* xStep and xFinal of such a function. The state (size bytes, zeroed) is made at the first
 * row, where first() sets the defaults and reads the options (AX_ERROR: reported, the
 * aggregate fails); every row then goes through ax_labelled_add. xFinal gives NULL without
 * rows, else calls train() with the distinct labels (ax_label_classes) to set the result, and
 * frees the state. */
typedef struct ax_labelled_kind {
    size_t size;
    ax_arg (*first)(sqlite3_context *ctx, int argc, sqlite3_value **argv, ax_labelled *state);
    void (*train)(sqlite3_context *ctx, ax_labelled *state, char *const *classes,
                  uint32_t n_classes, const uint32_t *y);
} ax_labelled_kind;
void ax_labelled_step(sqlite3_context *ctx, int argc, sqlite3_value **argv,
                      const ax_labelled_kind *kind);
void ax_labelled_final(sqlite3_context *ctx, const ax_labelled_kind *kind);

/* A whole-number option in [0, max] (unchanged when absent): "option \"states\" must be a
 * whole number from 0 to 256, got 2.5". */
ax_arg ax_opt_whole(sqlite3_context *ctx, const ax_opts *opts, const char *key, double max,
                    double *out);
ax_arg ax_opt_u32(sqlite3_context *ctx, const ax_opts *opts, const char *key, uint32_t *out);

/* JSON pieces: an array of doubles, a rows × cols matrix as an array of arrays, an array of
 * names, an HMM configuration object, a feature definition object. */
struct affect_strbuf;
void ax_json_doubles(struct affect_strbuf *sb, const double *v, size_t n);
void ax_json_matrix(struct affect_strbuf *sb, const double *v, size_t rows, size_t cols);
void ax_json_names(struct affect_strbuf *sb, char *const *names, uint32_t n);
void ax_json_hmm_config(struct affect_strbuf *sb, const affect_hmm_config *c);
void ax_json_features(struct affect_strbuf *sb, const affect_features *f);

#endif
