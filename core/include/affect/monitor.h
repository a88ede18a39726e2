/*
 * affect/monitor.h — stopping a long call when its caller asks, and reporting how far it got.
 *
 * Usage:
 *     bool (*my_stop)(void *ctx) = ...;                // true: stop now (or NULL)
 *     void (*my_progress)(void *, const char *, uint64_t, uint64_t) = ...;   // or NULL
 *     void *my_ctx = ...;
 *     affect_monitor mon;
 *     affect_monitor_init(&mon, my_stop, my_progress, my_ctx);
 *     // cfg.monitor = &mon (affect_hmm_config, affect_classifier_config, ...): the long call
 *     // (affect_hmm_train, ...) returns AFFECT_ERR_INTERRUPTED once my_stop says true.
 *     // Inside such a call, the library's loops do:
 *     affect_error err;
 *     affect_monitor_report(&mon, "frames", 0, 100);
 *     if (affect_monitor_check(&mon, &err) != AFFECT_OK)   // "interrupted"
 *         puts(err.msg);
 *
 * A long call of the library (HMM training, classifier training, cross-validation, RMLR fits,
 * DTW, generation) takes an optional monitor in its options (NULL: neither). While it runs it
 *   - polls monitor->stop, at most every AFFECT_MONITOR_POLL_MS milliseconds and only from the
 *     thread that called affect_monitor_init (its worker threads learn the answer through an
 *     atomic flag), and once stop says true it frees what it holds and returns
 *     AFFECT_ERR_INTERRUPTED with the message "interrupted";
 *   - reports its advance (a stage name such as "Fisher scores", the units done and the total)
 *     to monitor->progress, from the same thread only, at most every AFFECT_MONITOR_SHOW_MS
 *     milliseconds and whenever a stage starts or ends.
 * The hooks therefore never run concurrently and may call back into the caller's single-threaded
 * world (the SQLite glue runs a statement on the calling connection from them).
 *
 * A monitor belongs to one call at a time; models keep no pointer to it.
 */
#ifndef AFFECT_MONITOR_H
#define AFFECT_MONITOR_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>
#include <threads.h>

#include "affect/base.h"

#ifdef __cplusplus
extern "C" {
#endif

#define AFFECT_MONITOR_POLL_MS 10  /* stop is asked at most this often */
#define AFFECT_MONITOR_SHOW_MS 250 /* progress is shown at most this often within a stage */

typedef struct affect_monitor {
    bool (*stop)(void *ctx); /* true: stop now (may be NULL) */
    void (*progress)(void *ctx, const char *stage, uint64_t done, uint64_t total); /* or NULL */
    void *ctx;
    /* private, set by affect_monitor_init */
    struct affect_monitor *parent; /* affect_monitor_child's: stopped when it is */
    thrd_t owner;
    atomic_bool stopped;
    _Atomic(const char *) stage;
    atomic_uint_fast64_t done, total;
    const char *shown_stage;
    uint64_t shown_done, shown_total;
    int64_t next_poll_ns, next_show_ns;
} affect_monitor;

void affect_monitor_init(affect_monitor *mon, bool (*stop)(void *ctx),
                         void (*progress)(void *ctx, const char *stage, uint64_t done,
                                          uint64_t total),
                         void *ctx);

/* True once the caller asked to stop (mon may be NULL: false). Cheap: a clock read between
 * polls. From the owner thread it also shows pending progress. */
bool affect_monitor_stopped(affect_monitor *mon);

/* AFFECT_ERR_INTERRUPTED with "interrupted" in err once stopped, else AFFECT_OK. */
affect_status affect_monitor_check(affect_monitor *mon, affect_error *err);

/* Records the advance of a stage (stage: a static string); any thread. */
void affect_monitor_report(affect_monitor *mon, const char *stage, uint64_t done, uint64_t total);

/* done + 1 of the current stage (any thread). */
void affect_monitor_step(affect_monitor *mon);

/* Owner thread, after worker threads advanced a stage: shows what they recorded now. */
void affect_monitor_flush(affect_monitor *mon);

/* A monitor for a part of a call (the class HMMs of a classifier, the classifiers of the
 * folds) that stops when parent stops and shows no progress, so that the parts do not overwrite
 * the call's own stages. Returns child, or NULL when parent is NULL. Called from the owner
 * thread. */
affect_monitor *affect_monitor_child(affect_monitor *child, affect_monitor *parent);

#ifdef __cplusplus
}
#endif
#endif
