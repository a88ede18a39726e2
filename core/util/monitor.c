/*
 * monitor.c — the stop and progress hooks of long calls (see affect/monitor.h): an atomic
 * "stopped" flag that any thread reads, and hooks called only from the owner thread, throttled
 * by a monotonic clock.
 */
#define _POSIX_C_SOURCE 200809L /* clock_gettime */

#include "affect/monitor.h"

#include <time.h>

static int64_t now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

void affect_monitor_init(affect_monitor *mon, bool (*stop)(void *ctx),
                         void (*progress)(void *ctx, const char *stage, uint64_t done,
                                          uint64_t total),
                         void *ctx)
{
    mon->stop = stop;
    mon->progress = progress;
    mon->ctx = ctx;
    mon->parent = NULL;
    mon->owner = thrd_current();
    atomic_init(&mon->stopped, false);
    atomic_init(&mon->stage, NULL);
    atomic_init(&mon->done, 0);
    atomic_init(&mon->total, 0);
    mon->shown_stage = NULL;
    mon->shown_done = mon->shown_total = 0;
    int64_t t = now_ns();
    mon->next_poll_ns = t + (int64_t)AFFECT_MONITOR_POLL_MS * 1000000;
    mon->next_show_ns = t;
}

/* Owner thread: shows the recorded advance when it changed and the stage is new or complete, or
 * the last showing is old enough. */
static void show(affect_monitor *mon, int64_t t)
{
    if (!mon->progress)
        return;
    const char *stage = atomic_load(&mon->stage);
    uint64_t done = atomic_load(&mon->done), total = atomic_load(&mon->total);
    if (!stage ||
        (stage == mon->shown_stage && done == mon->shown_done && total == mon->shown_total))
        return;
    bool edge = stage != mon->shown_stage || done == total;
    if (!edge && t < mon->next_show_ns)
        return;
    mon->shown_stage = stage;
    mon->shown_done = done;
    mon->shown_total = total;
    mon->next_show_ns = t + (int64_t)AFFECT_MONITOR_SHOW_MS * 1000000;
    mon->progress(mon->ctx, stage, done, total);
}

bool affect_monitor_stopped(affect_monitor *mon)
{
    if (!mon)
        return false;
    if (atomic_load_explicit(&mon->stopped, memory_order_relaxed))
        return true;
    for (affect_monitor *p = mon->parent; p; p = p->parent) /* asked by another thread */
        if (atomic_load_explicit(&p->stopped, memory_order_relaxed)) {
            atomic_store(&mon->stopped, true);
            return true;
        }
    if (!thrd_equal(thrd_current(), mon->owner))
        return false;
    int64_t t = now_ns();
    if (t < mon->next_poll_ns)
        return false;
    mon->next_poll_ns = t + (int64_t)AFFECT_MONITOR_POLL_MS * 1000000;
    show(mon, t);
    if (mon->stop && mon->stop(mon->ctx)) {
        atomic_store(&mon->stopped, true);
        return true;
    }
    return false;
}

affect_status affect_monitor_check(affect_monitor *mon, affect_error *err)
{
    if (affect_monitor_stopped(mon))
        return affect_fail(err, AFFECT_ERR_INTERRUPTED, "interrupted");
    return AFFECT_OK;
}

void affect_monitor_report(affect_monitor *mon, const char *stage, uint64_t done, uint64_t total)
{
    if (!mon)
        return;
    atomic_store(&mon->total, total);
    atomic_store(&mon->done, done);
    atomic_store(&mon->stage, stage);
    if (thrd_equal(thrd_current(), mon->owner))
        show(mon, now_ns());
}

void affect_monitor_step(affect_monitor *mon)
{
    if (!mon)
        return;
    atomic_fetch_add(&mon->done, 1);
    if (thrd_equal(thrd_current(), mon->owner))
        show(mon, now_ns());
}

void affect_monitor_flush(affect_monitor *mon)
{
    if (mon && thrd_equal(thrd_current(), mon->owner)) {
        mon->next_show_ns = 0;
        show(mon, now_ns());
    }
}

static bool parent_stopped(void *parent)
{
    return affect_monitor_stopped(parent);
}

affect_monitor *affect_monitor_child(affect_monitor *child, affect_monitor *parent)
{
    if (!parent)
        return NULL;
    affect_monitor_init(child, parent_stopped, NULL, parent);
    child->parent = parent;
    child->next_poll_ns = 0; /* the parent throttles */
    return child;
}
