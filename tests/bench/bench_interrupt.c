/*
 * bench_interrupt.c — how fast long SQL calls stop when asked (issue 14, item 3; the goal is
 * 0.2 s from the interrupt to the return): the calls of tests/sql/interrupt_run.h, each run
 * several times and interrupted, with the median, fastest and slowest latency and the median
 * process CPU time over that span.
 *
 * Usage:
 *     bench_interrupt [module path] [--runs N] [--case TEXT] [--uninterrupted SECONDS]
 *     bash tests/bench/run.sh            # Release build, pinned to one core, with the others
 * The module defaults to AFFECT_BENCH_MODULE (the built affect.so, set by
 * tests/bench/CMakeLists.txt); --runs (default 5) runs per call; --case runs only the calls
 * whose name contains TEXT; --uninterrupted times each call interrupted by a second thread only
 * after SECONDS instead (how long it runs when nobody stops it, up to that), each on a fresh
 * connection (laban_salient caches its fit). Run it with
 * OPENBLAS_NUM_THREADS=1 (run.sh does).
 *
 * Set-up, in an in-memory database: interrupt_run.h's corpus (80 motion_synth motions, 8 walks
 * at 1000 fps, their laban indexes). Each call runs for seconds uninterrupted (most for tens of
 * seconds); it is stopped by sqlite3_interrupt from a second thread 0.3 s after its step starts
 * (the laban rebuild: 0.05 s), by the progress function as affect_train reaches a stage, or by
 * a progress handler (every 1000 VM steps) that says stop from 0.3 s on. Latency: wall seconds
 * from the interrupt (the handler: from the moment it would say stop) to the return of
 * sqlite3_step. CPU: the process's CPU seconds over the same span, every thread (on a loaded
 * machine the wall time includes waiting for a core; the CPU time does not). A run that ends
 * with another error is counted and its code and message printed; one that returns a row or
 * ends before the interrupt is printed and left out of the statistics.
 */
#define _POSIX_C_SOURCE 200809L /* clock_gettime */
#include "../sql/interrupt_run.h"

#define MAX_RUNS 101

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(int argc, char **argv)
{
    const char *module = AFFECT_BENCH_MODULE, *only = NULL;
    int runs = 5;
    double full = 0; /* --uninterrupted */
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--runs") == 0 && i + 1 < argc)
            runs = atoi(argv[++i]);
        else if (strcmp(argv[i], "--case") == 0 && i + 1 < argc)
            only = argv[++i];
        else if (strcmp(argv[i], "--uninterrupted") == 0 && i + 1 < argc)
            full = atof(argv[++i]);
        else
            module = argv[i];
    }
    if (runs < 1 || runs > MAX_RUNS) {
        fprintf(stderr, "bench_interrupt: --runs must be from 1 to %d\n", MAX_RUNS);
        return 2;
    }
    const char *blas = getenv("OPENBLAS_NUM_THREADS");
    double t0 = ir_now();
    ir_open(module);
    ir_open_big();
    printf("corpus: 80 motions, 8 walks at 1000 fps, their laban indexes and the large motions "
           "(" IR_BIG ") in %.1f s; OPENBLAS_NUM_THREADS=%s; %d runs per call\n",
           ir_now() - t0, blas ? blas : "(unset)", runs);
    if (full > 0) {
        printf("each call uninterrupted, up to %.0f s:\n", full);
        for (size_t i = 0; i < IR_N_CASES; i++) {
            ir_case c = IR_CASES[i];
            if ((only && !strstr(c.name, only)) || c.how != IR_THREAD)
                continue;
            c.delay = full;
            sqlite3_close(ir_db); /* a fresh connection: no cached RMLR fit */
            ir_open(module);
            ir_open_big();
            ir_result res;
            if (!ir_run(&c, &res))
                printf("%-48s cannot prepare: %s\n", c.name, res.msg);
            else if (res.fired)
                printf("%-48s more than %.0f s\n", c.name, full);
            else
                printf("%-48s %.1f s (rc %d)\n", c.name, res.elapsed, res.rc);
            fflush(stdout);
        }
        sqlite3_close(ir_db);
        return 0;
    }
    printf("%-48s %-9s %9s %9s %9s %9s\n", "call (how it is stopped)", "how", "median ms", "min ms",
           "max ms", "CPU ms");
    for (size_t i = 0; i < IR_N_CASES; i++) {
        const ir_case *c = &IR_CASES[i];
        if (only && !strstr(c->name, only))
            continue;
        double lat[MAX_RUNS], cpu[MAX_RUNS];
        int n = 0;
        char odd[600] = "";
        for (int r = 0; r < runs; r++) {
            ir_result res;
            if (!ir_run(c, &res)) {
                snprintf(odd, sizeof odd, "cannot prepare: %s", res.msg);
                break;
            }
            if (!res.fired || res.rc == SQLITE_ROW || res.rc == SQLITE_DONE) {
                snprintf(odd, sizeof odd, "run %d: rc %d after %.2f s%s: %s", r + 1, res.rc,
                         res.elapsed, res.fired ? "" : ", before the interrupt", res.msg);
                continue;
            }
            if (res.rc != SQLITE_INTERRUPT)
                snprintf(odd, sizeof odd, "rc %d, not SQLITE_INTERRUPT: %s", res.rc, res.msg);
            lat[n] = res.latency;
            cpu[n] = res.cpu;
            n++;
        }
        const char *how = c->how == IR_THREAD    ? "thread"
                          : c->how == IR_HANDLER ? "handler"
                          : c->how == IR_STAGE   ? "stage"
                                                 : "row";
        if (n > 0) {
            qsort(lat, (size_t)n, sizeof lat[0], cmp_double);
            qsort(cpu, (size_t)n, sizeof cpu[0], cmp_double);
            printf("%-48s %-9s %9.1f %9.1f %9.1f %9.1f\n", c->name, how, lat[n / 2] * 1e3,
                   lat[0] * 1e3, lat[n - 1] * 1e3, cpu[n / 2] * 1e3);
        } else {
            printf("%-48s %-9s %9s\n", c->name, how, "-");
        }
        if (odd[0])
            printf("    %s\n", odd);
        fflush(stdout);
    }
    sqlite3_close(ir_db);
    printf("total %.1f s\n", ir_now() - t0);
    return 0;
}
