/* The OpenMP wait policy (docs/performance.md, "Threads").
 *
 * GNU libgomp's threads spin for about 300,000 rounds at every barrier
 * before they sleep. On idle processors that is the fastest; on processors
 * that other work keeps busy the spinning threads take the cores from the
 * threads with work, and a 2-thread run beside another 2-thread run took
 * 8-10 times as long as with sleeping threads. Sleeping threads cost an
 * idle machine 20-25 % (the wake-up at each barrier). So: when the
 * environment sets no policy (OMP_WAIT_POLICY or GOMP_SPINCOUNT), the
 * threads sleep (passive) when other runnable work and this run's threads
 * together exceed the processors this process may use, and spin (libgomp's
 * default) otherwise. libgomp reads its environment when it is loaded,
 * before main: the program sets OMP_WAIT_POLICY and runs itself again. */
#define _GNU_SOURCE
#include "wait_policy.h"

#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

/* Runnable tasks on the machine now (procs_running of /proc/stat, this
 * process included); -1 when unknown. */
static long running_tasks(void)
{
    FILE *f = fopen("/proc/stat", "r");
    if (!f)
        return -1;
    char line[256];
    long running = -1;
    while (fgets(line, sizeof line, f))
        if (strncmp(line, "procs_running ", 14) == 0) {
            running = strtol(line + 14, NULL, 10);
            break;
        }
    fclose(f);
    return running;
}

/* The threads this run will start: --threads N, else OMP_NUM_THREADS,
 * else the processors. */
static long run_threads(int argc, char **argv, long processors)
{
    for (int i = 2; i + 1 < argc; i++)
        if (strcmp(argv[i], "--threads") == 0)
            return strtol(argv[i + 1], NULL, 10);
    const char *omp = getenv("OMP_NUM_THREADS");
    long n = omp ? strtol(omp, NULL, 10) : 0;
    return n > 0 ? n : processors;
}

void sluice_cli_set_wait_policy(int argc, char **argv)
{
    if (argc < 2 || getenv("OMP_WAIT_POLICY") || getenv("GOMP_SPINCOUNT"))
        return;
    if (strcmp(argv[1], "run") != 0)
        return;
    cpu_set_t set;
    long processors = sched_getaffinity(0, sizeof set, &set) == 0 ? CPU_COUNT(&set) : 0;
    if (processors <= 0)
        processors = sysconf(_SC_NPROCESSORS_ONLN);
    /* the most other runnable tasks in five looks 2 ms apart (a task that
     * waits for input now and then still counts) */
    long others = -1;
    for (int k = 0; k < 5; k++) {
        long running = running_tasks();
        if (running - 1 > others)
            others = running - 1;
        if (k < 4)
            nanosleep(&(struct timespec){0, 2000000}, NULL);
    }
    if (others < 0 || processors <= 0 || others + run_threads(argc, argv, processors) <= processors)
        return;
    if (setenv("OMP_WAIT_POLICY", "passive", 1) != 0)
        return;
    execv("/proc/self/exe", argv);
    unsetenv("OMP_WAIT_POLICY"); /* not run again: libgomp's default */
}
