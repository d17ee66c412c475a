/* A signal that arrives while a file is being written: the sasnav tool's
 * handler (sasnav_remove_partial_outputs, then the default action) leaves
 * no temporary file and the previous output intact.
 *
 * A child process writes a 32 MB run again and again onto a target that
 * holds a complete earlier run; the parent waits until the child's
 * temporary file exists (a write is in progress), sends SIGTERM, and
 * checks: the child died of the signal, no "<target>.tmp-*" is left, and
 * the target still reads back as the earlier run. Repeated with SIGINT. */
#include "sasnav/error.h"
#include "sasnav/io.h"
#include "sasnav/run.h"
#include "testutil.h"

#include <dirent.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

static void on_signal(int sig)
{
    sasnav_remove_partial_outputs();
    signal(sig, SIG_DFL);
    raise(sig);
}

static int tmp_count(const char *dir)
{
    DIR *d = opendir(dir);
    int n = 0;
    struct dirent *e;
    while (d && (e = readdir(d)))
        if (strstr(e->d_name, ".tmp-")) n++;
    if (d) closedir(d);
    return n;
}

static sasnav_run *make_run(int n_pings, int n_rx, int n_samples, float value)
{
    sasnav_system sys;
    sasnav_system_default(&sys);
    sasnav_array a;
    sasnav_array_uniform(&a, n_rx, 0.05, 0.05, 0.05);
    sasnav_window w = {1e-2, n_samples};
    sasnav_run *r = NULL;
    if (sasnav_run_alloc(&sys, &a, &w, n_pings, 0, &r)) return NULL;
    size_t n = (size_t)n_pings * n_rx * n_samples;
    for (size_t k = 0; k < n; k++) r->raw[k] = value + (float)(k % 7);
    for (int p = 0; p < n_pings; p++) {
        r->nav[p].array = (sasnav_pose){0.2 * p, 0, 0};
        r->nav[p].tx = (sasnav_pose){0.2 * p - 0.1, 0, 0};
    }
    r->ping_spacing = 0.2;
    return r;
}

static void interrupt_write(int sig)
{
    char dir[4096], target[4200];
    snprintf(dir, sizeof dir, "%s/sig%d", test_tmpdir(), sig);
    mkdir(dir, 0755);
    snprintf(target, sizeof target, "%s/out.h5", dir);
    sasnav_run *before = make_run(2, 4, 64, 1.0f);
    CHECK(before && sasnav_run_write(target, before) == SASNAV_OK, "writing the earlier run: %s",
          sasnav_last_error());
    sasnav_run *big = make_run(64, 64, 1024, 2.0f); /* 4.2 M samples, 32 MB */
    CHECK(big != NULL, "allocating the big run");
    pid_t pid = fork();
    if (pid == 0) {
        signal(sig, on_signal);
        for (;;) sasnav_run_write(target, big);
    }
    /* wait (at most 60 s) for a write in progress */
    int seen = 0;
    for (int k = 0; k < 120000 && !seen; k++) {
        seen = tmp_count(dir) > 0;
        if (!seen) nanosleep(&(struct timespec){0, 500000}, NULL);
    }
    CHECK(seen, "no temporary file appeared");
    kill(pid, sig);
    int status = 0;
    waitpid(pid, &status, 0);
    CHECK(WIFSIGNALED(status) && WTERMSIG(status) == sig, "the writer should die of signal %d",
          sig);
    CHECK(tmp_count(dir) == 0, "a temporary file is left after signal %d", sig);
    /* the target: the earlier run, or a complete big run if a write had
     * finished before the signal; never anything else */
    sasnav_run *back = NULL;
    CHECK(sasnav_run_read(target, &back) == SASNAV_OK, "target unreadable after signal %d: %s",
          sig, sasnav_last_error());
    if (back)
        CHECK(back->n_pings == 2 || back->n_pings == 64, "target holds %d pings", back->n_pings);
    printf("signal %d during a write: no temporary file, target %s\n", sig,
           back && back->n_pings == 2 ? "unchanged" : "a complete later run");
    sasnav_run_free(back);
    sasnav_run_free(before);
    sasnav_run_free(big);
}

int main(void)
{
    interrupt_write(SIGTERM);
    interrupt_write(SIGINT);
    return test_summary("test_faults");
}
