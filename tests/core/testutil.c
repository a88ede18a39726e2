/*
 * testutil.c — see testutil.h. The out-of-memory helpers keep the counting allocator's state
 * in three file-level counters: affect_set_allocator takes plain function pointers, and the
 * test executables are single-threaded.
 */
#include "testutil.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

char *tu_read_file(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    if (fseek(f, 0, SEEK_END) != 0) {
        fclose(f);
        return NULL;
    }
    long n = ftell(f);
    rewind(f);
    char *buf = n >= 0 ? malloc((size_t)n + 1) : NULL;
    if (!buf || fread(buf, 1, (size_t)n, f) != (size_t)n) {
        free(buf);
        fclose(f);
        return NULL;
    }
    fclose(f);
    buf[n] = '\0';
    if (len)
        *len = (size_t)n;
    return buf;
}

const char *tu_corpus_dir(void)
{
    static const char dir[] = AFFECT_SHARED_DIR "/corpora/bandai-namco-1/data";
    struct stat st;
    if (stat(dir, &st) != 0 || !S_ISDIR(st.st_mode)) {
        printf("SKIP: the real corpus is absent (%s): tests that need it are skipped\n", dir);
        return NULL;
    }
    return dir;
}

/* ---- out of memory ---- */

#define TU_OOM_MAX_RUNS 100000

static long oom_fail_at, oom_calls, oom_outstanding;

static void *oom_malloc(size_t n)
{
    if (++oom_calls == oom_fail_at)
        return NULL;
    void *p = malloc(n);
    if (p)
        oom_outstanding++;
    return p;
}

static void *oom_realloc(void *p, size_t n)
{
    if (!p)
        return oom_malloc(n); /* affect_realloc never does this, but a realloc may */
    if (++oom_calls == oom_fail_at)
        return NULL;
    return realloc(p, n);
}

static void oom_free(void *p)
{
    if (p)
        oom_outstanding--;
    free(p);
}

void tu_oom_install(long fail_at)
{
    static const affect_allocator counting = {oom_malloc, oom_realloc, oom_free};
    oom_fail_at = fail_at;
    oom_calls = 0;
    oom_outstanding = 0;
    affect_set_allocator(&counting);
}

void tu_oom_remove(void)
{
    affect_set_allocator(NULL);
}

long tu_oom_outstanding(void)
{
    return oom_outstanding;
}

long tu_oom_calls(void)
{
    return oom_calls;
}

long tu_oom_sweep(tu_oom_op op, void *ctx, tu_oom_finish finish, long *absorbed)
{
    long n_absorbed = 0;
    for (long n = 1; n <= TU_OOM_MAX_RUNS; n++) {
        affect_error err;
        affect_error_clear(&err);
        tu_oom_install(n);
        affect_status st = op(ctx, &err);
        long calls = oom_calls;
        if (finish)
            finish(ctx, st);
        tu_oom_remove();
        if (oom_outstanding != 0)
            fail_msg("with allocation %ld failing, %ld blocks leaked (status %d: %s)", n,
                     oom_outstanding, (int)st, err.msg);
        if (st == AFFECT_OK) {
            if (calls < n) { /* nothing failed: every allocation has had its turn */
                if (absorbed)
                    *absorbed = n_absorbed;
                return n - 1;
            }
            if (!absorbed)
                fail_msg("allocation %ld failed but the operation succeeded", n);
            n_absorbed++;
            continue;
        }
        if (st != AFFECT_ERR_NOMEM || err.status != AFFECT_ERR_NOMEM ||
            strcmp(err.msg, "out of memory") != 0)
            fail_msg("allocation %ld failing gave status %d: %s", n, (int)st, err.msg);
        if (calls < n)
            fail_msg("allocation %ld never happened (%ld calls) but the operation reported "
                     "out of memory", n, calls);
    }
    fail_msg("still allocating with allocation %d failing", TU_OOM_MAX_RUNS);
    return -1;
}
