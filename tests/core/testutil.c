/*
 * testutil.c — see testutil.h. The SVG checker is a small XML checker for exactly what
 * svg.c and plot.c emit (no comments, CDATA, processing instructions or single-quoted
 * attributes), strict enough to catch a missing escape or a misnested group. The out-of-memory
 * helpers keep the counting allocator's state
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

double tu_max_dist(const affect_motion *a, const affect_motion *b)
{
    double worst = 0;
    for (uint32_t t = 0; t < a->n_frames; t++)
        for (uint32_t j = 0; j < a->n_joints; j++) {
            const float *p = affect_motion_at(a, t, j), *q = affect_motion_at(b, t, j);
            double d[3] = {(double)p[0] - q[0], (double)p[1] - q[1], (double)p[2] - q[2]};
            worst = fmax(worst, sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]));
        }
    return worst;
}

/* ---- text and SVG ---- */

size_t tu_count(const char *s, const char *needle)
{
    size_t n = 0, k = strlen(needle);
    for (const char *p = strstr(s, needle); p; p = strstr(p + k, needle))
        n++;
    return n;
}

/* Whether s contains needle (lowercase ASCII letters) in any case. */
static bool has_ci(const char *s, const char *needle)
{
    size_t k = strlen(needle);
    for (; *s; s++) {
        size_t i = 0;
        while (i < k && s[i] && (s[i] | 0x20) == needle[i])
            i++;
        if (i == k)
            return true;
    }
    return false;
}

void tu_assert_svg_well_formed(const char *s, size_t len)
{
    assert_int_equal(strlen(s), len);
    assert_true(strncmp(s, "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"", 47) == 0);
    assert_true(len > 7 && strcmp(s + len - 7, "</svg>\n") == 0);
    assert_false(has_ci(s, "nan"));
    assert_false(has_ci(s, "inf"));
    for (const unsigned char *u = (const unsigned char *)s; *u; u++) {
        if (*u >= 0x80) { /* UTF-8: a lead byte and its continuation bytes */
            int n = *u >= 0xF0 ? 3 : *u >= 0xE0 ? 2 : 1;
            assert_true(*u >= 0xC2 && *u <= 0xF4);
            for (int i = 1; i <= n; i++)
                assert_int_equal(u[i] & 0xC0, 0x80);
            u += n;
        }
    }
    char stack[64][20];
    int depth = 0;
    bool root_closed = false;
    for (const char *p = s; *p; p++) {
        if (*p == '&') {
            static const char *const ents[] = {"&amp;", "&lt;", "&gt;", "&quot;", "&#39;"};
            bool ok = false;
            for (int i = 0; i < 5; i++)
                ok = ok || strncmp(p, ents[i], strlen(ents[i])) == 0;
            if (!ok)
                fail_msg("bad entity at byte %zu", (size_t)(p - s));
            continue;
        }
        if (*p == '>')
            fail_msg("stray '>' at byte %zu", (size_t)(p - s));
        if (*p != '<')
            continue;
        assert_false(root_closed);
        bool closing = p[1] == '/';
        const char *name = p + (closing ? 2 : 1);
        /* lowercase, or camelCase as SVG's animateTransform and linearGradient */
        size_t n = strspn(name, "abcdefghijklmnopqrstuvwxyz");
        n += n > 0 ? strspn(name + n, "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ") : 0;
        assert_true(n > 0 && n < 20);
        if (name[n] == '\0' || !strchr(" />\n", name[n]))
            fail_msg("bad tag name at byte %zu", (size_t)(p - s));
        const char *q = name + n;
        bool in_quote = false;
        for (; *q && (in_quote || *q != '>'); q++) {
            if (*q == '"')
                in_quote = !in_quote;
            if (*q == '<' || (in_quote && *q == '>'))
                fail_msg("unescaped %c inside a tag at byte %zu", *q, (size_t)(q - s));
        }
        assert_int_equal(*q, '>');
        if (closing) {
            assert_true(depth > 0);
            depth--;
            if (strlen(stack[depth]) != n || strncmp(stack[depth], name, n) != 0)
                fail_msg("</%.*s> closes <%s>", (int)n, name, stack[depth]);
            if (depth == 0)
                root_closed = true;
        } else if (q[-1] != '/') {
            assert_true(depth < 64);
            memcpy(stack[depth], name, n);
            stack[depth][n] = '\0';
            depth++;
        }
        p = q;
    }
    assert_int_equal(depth, 0);
    assert_true(root_closed);
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
                     "out of memory",
                     n, calls);
    }
    fail_msg("still allocating with allocation %d failing", TU_OOM_MAX_RUNS);
    return -1;
}
