/*
 * parallel.c — affect_parallel_for (internal.h): items handed out in increasing order by a
 * counter under a mutex; the lowest-index failure is kept under the same mutex.
 */
#include <threads.h>

#include "util/internal.h"

typedef struct pool {
    uint32_t n, next;
    affect_item_fn fn;
    void *ctx;
    mtx_t lock;
    bool stop;
    uint32_t finished; /* workers that returned */
    uint32_t failed;   /* lowest failing index, or n */
    affect_status status;
    affect_error err;
} pool;

static int worker(void *arg)
{
    pool *p = arg;
    for (;;) {
        mtx_lock(&p->lock);
        uint32_t i = p->stop ? p->n : p->next++;
        if (i >= p->n)
            p->finished++;
        mtx_unlock(&p->lock);
        if (i >= p->n)
            return 0;
        affect_error e;
        affect_status st = p->fn(p->ctx, i, &e);
        if (st != AFFECT_OK) {
            mtx_lock(&p->lock);
            p->stop = true;
            if (i < p->failed) {
                p->failed = i;
                p->status = st;
                p->err = e;
            }
            mtx_unlock(&p->lock);
        }
    }
}

affect_status affect_parallel_for(uint32_t n, uint32_t threads, affect_item_fn fn, void *ctx,
                                  affect_monitor *mon, affect_error *err)
{
    if (threads <= 1 || n <= 1) {
        for (uint32_t i = 0; i < n; i++) {
            affect_status st = fn(ctx, i, err);
            if (st != AFFECT_OK)
                return st;
        }
        return AFFECT_OK;
    }
    pool p = {.n = n, .fn = fn, .ctx = ctx, .failed = n, .status = AFFECT_OK};
    if (mtx_init(&p.lock, mtx_plain) != thrd_success)
        return affect_parallel_for(n, 1, fn, ctx, mon, err);
    enum { MAX_THREADS = 64 };
    thrd_t th[MAX_THREADS];
    uint32_t want = threads < n ? threads : n, started = 0;
    if (want > MAX_THREADS)
        want = MAX_THREADS;
    for (uint32_t t = 1; t < want; t++) { /* the caller is the first worker */
        if (thrd_create(&th[started], worker, &p) != thrd_success)
            break;
        started++;
    }
    worker(&p);
    for (bool all = false; mon && !all;) { /* the others' items: keep asking the monitor */
        mtx_lock(&p.lock);
        all = p.finished == started + 1;
        mtx_unlock(&p.lock);
        if (!all) {
            (void)affect_monitor_stopped(mon);
            thrd_sleep(&(struct timespec){.tv_nsec = 2000000}, NULL);
        }
    }
    for (uint32_t t = 0; t < started; t++)
        thrd_join(th[t], NULL);
    affect_monitor_flush(mon);
    mtx_destroy(&p.lock);
    if (p.status != AFFECT_OK)
        *err = p.err;
    return p.status;
}
