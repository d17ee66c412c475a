/* Survey scale (docs/survey.md): peak memory against run length, and
 * throughput with 1 and 2 processes, of the command-line tool as a user
 * runs it.
 *
 * usage: bench_survey [--sasnav PATH] [--pings N1,N2,...] [--dir DIR]
 *                     [--ranks R1,R2,...] [--skip-subspace]
 *
 * 1. Memory against length: for each N (default 200, 2000, 20000) a
 *    paper-trajectory run of N pings (20 cm apart) over a ripple field as
 *    long as the track (500 scatterers per square metre) is simulated
 *    (`sasnav simulate`, streamed), navigated with DPCA (`sasnav navigate
 *    --method dpca`: every pair, 1.4 ms each) and imaged over the whole
 *    track at 5 cm pixels (`sasnav image`, tiles). Each command runs as a
 *    child process: wall time and peak resident memory (wait4's
 *    ru_maxrss). Pairs per second, track metres imaged per second.
 * 2. Throughput with 1 and 2 processes (mpirun --oversubscribe, one thread
 *    each, when mpirun is on the PATH and the tool has MPI): subspace
 *    navigation of a 16-ping paper-trajectory run (pairs/s), simulation of
 *    the longest run (pings/s), DPCA
 *    navigation of the longest run (pairs/s), and backprojection of a
 *    48-ping run on a 3.2 x 1.6 m grid of 3.125 mm pixels that every ping
 *    reaches (pixel x ping x channel updates/s). Outputs of 1 and 2 processes are compared
 *    (h5diff): "same" means bit for bit.
 * Prints one line per measurement. */
#define _GNU_SOURCE
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#define MAX_LIST 8

typedef struct {
    double seconds;
    double peak_mib;
    int status;
} run_stats;

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

/* Runs argv (stdout and stderr to `log`), waits, returns its figures. */
static run_stats run(char *const argv[], const char *log)
{
    run_stats s = {0, 0, -1};
    fflush(stdout); /* or the child would print what is buffered again */
    double t0 = now();
    pid_t pid = fork();
    if (pid < 0) return s;
    if (pid == 0) {
        if (log && (!freopen(log, "w", stdout) || dup2(fileno(stdout), 2) < 0)) _exit(127);
        execvp(argv[0], argv);
        _exit(127);
    }
    int status;
    struct rusage ru;
    if (wait4(pid, &status, 0, &ru) < 0) return s;
    s.seconds = now() - t0;
    s.peak_mib = ru.ru_maxrss / 1024.0; /* kB on Linux: the largest of the child's tree */
    s.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    return s;
}

static int parse_list(const char *text, long *out)
{
    int n = 0;
    for (const char *p = text; *p && n < MAX_LIST;) {
        char *end;
        out[n++] = strtol(p, &end, 10);
        if (end == p) return 0;
        p = *end == ',' ? end + 1 : end;
    }
    return n;
}

static int same_files(const char *a, const char *b)
{
    char *argv[] = {"h5diff", "-q", (char *)a, (char *)b, NULL};
    return run(argv, "/dev/null").status == 0;
}

static int have_mpirun(void)
{
    char *argv[] = {"mpirun", "--version", NULL};
    return run(argv, "/dev/null").status == 0;
}

/* argv of `sasnav ...` under `mpirun -np R` (R > 1) or alone. */
static void command(char **out, int ranks, const char *sasnav, char *const rest[])
{
    static char np[16];
    int k = 0;
    if (ranks > 1) {
        snprintf(np, sizeof np, "%d", ranks);
        out[k++] = "mpirun";
        out[k++] = "--oversubscribe";
        out[k++] = "-np";
        out[k++] = np;
    }
    out[k++] = (char *)sasnav;
    for (int j = 0; rest[j]; j++) out[k++] = rest[j];
    out[k] = NULL;
}

int main(int argc, char **argv)
{
    const char *sasnav = "./build/sasnav";
    char dirbuf[256] = "";
    const char *dir = NULL;
    long pings[MAX_LIST] = {200, 2000, 20000}, ranks[MAX_LIST] = {1, 2};
    int np = 3, nr = 2, skip_subspace = 0;
    for (int a = 1; a < argc; a++) {
        if (!strcmp(argv[a], "--sasnav") && a + 1 < argc) sasnav = argv[++a];
        else if (!strcmp(argv[a], "--pings") && a + 1 < argc) np = parse_list(argv[++a], pings);
        else if (!strcmp(argv[a], "--ranks") && a + 1 < argc) nr = parse_list(argv[++a], ranks);
        else if (!strcmp(argv[a], "--dir") && a + 1 < argc) dir = argv[++a];
        else if (!strcmp(argv[a], "--skip-subspace")) skip_subspace = 1;
        else {
            fprintf(stderr, "usage: bench_survey [--sasnav PATH] [--pings N1,N2,...] [--dir DIR] "
                            "[--ranks R1,R2,...] [--skip-subspace]\n");
            return 2;
        }
    }
    if (np < 1 || nr < 1) return 2;
    if (!dir) {
        snprintf(dirbuf, sizeof dirbuf, "%s/sasnav-bench-survey-XXXXXX", getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp");
        if (!mkdtemp(dirbuf)) {
            perror("mkdtemp");
            return 1;
        }
        dir = dirbuf;
    }
    setenv("SASNAV_PROGRESS_SECONDS", "1000000", 1);
    setenv("OMPI_ALLOW_RUN_AS_ROOT", "1", 1);
    setenv("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1", 1);
    char log[512], cfg[512], runf[512], out[512], out2[512], grid[128];
    snprintf(log, sizeof log, "%s/log.txt", dir);
    printf("bench_survey: %s, scratch %s\n", sasnav, dir);

    /* 1. Memory against run length (one process, its default threads). */
    printf("\n1. peak memory against run length (one process)\n");
    printf("%8s %-9s %10s %10s %14s\n", "pings", "command", "wall s", "peak MiB", "rate");
    for (int i = 0; i < np; i++) {
        long n = pings[i];
        double length = 0.2 * (n - 1);
        snprintf(cfg, sizeof cfg, "%s/run%ld.yaml", dir, n);
        FILE *f = fopen(cfg, "w");
        if (!f) return 1;
        fprintf(f, "preset: paper-trajectory\ntrajectory: {n_pings: %ld, x_start: 0.0}\n"
                   "scene: {kind: ripples, x_min: -12, x_max: %.1f, density: 500}\nnoise: {snr_db: 30}\n",
                n, length + 12.0);
        fclose(f);
        snprintf(runf, sizeof runf, "%s/run%ld.h5", dir, n);
        char *sim[] = {(char *)sasnav, "simulate", "--config", cfg, "-o", runf, NULL};
        run_stats s = run(sim, log);
        printf("%8ld %-9s %10.2f %10.1f %10.1f p/s%s\n", n, "simulate", s.seconds, s.peak_mib, n / s.seconds,
               s.status ? "  FAILED" : "");
        if (s.status) continue;
        snprintf(out, sizeof out, "%s/nav%ld.h5", dir, n);
        char *nav[] = {(char *)sasnav, "navigate", runf, "--method", "dpca", "-o", out, NULL};
        s = run(nav, log);
        printf("%8ld %-9s %10.2f %10.1f %10.1f pairs/s%s\n", n, "navigate", s.seconds, s.peak_mib,
               (n - 1) / s.seconds, s.status ? "  FAILED" : "");
        snprintf(out, sizeof out, "%s/img%ld.h5", dir, n);
        long nx = (long)(length / 0.05) + 41;
        snprintf(grid, sizeof grid, "%.3f,%.3f,%ld,9.2,10.8,33", -1.0, -1.0 + 0.05 * (nx - 1), nx);
        char *img[] = {(char *)sasnav, "image", runf, "--grid", grid, "-o", out, NULL};
        s = run(img, log);
        printf("%8ld %-9s %10.2f %10.1f %10.1f m/s (%ld x 33 px)%s\n", n, "image", s.seconds, s.peak_mib,
               (length + 2.0) / s.seconds, nx, s.status ? "  FAILED" : "");
        remove(out);
    }

    /* 2. Throughput with 1 and 2 processes. */
    int mpi = have_mpirun();
    printf("\n2. throughput with 1%s processes, one thread each\n", mpi ? " and more" : " (no mpirun)");
    setenv("OMP_NUM_THREADS", "1", 1);
    char short_run[512];
    snprintf(short_run, sizeof short_run, "%s/short.h5", dir);
    char *sim[] = {(char *)sasnav, "simulate", "--preset", "paper-trajectory", "-o", short_run, NULL};
    if (run(sim, log).status) {
        printf("simulate of the 16-ping run failed (%s)\n", log);
        return 1;
    }
    char *argvs[16];
    char first[512] = "";
    for (int j = 0; j < nr && !skip_subspace; j++) {
        if (ranks[j] > 1 && !mpi) continue;
        snprintf(out, sizeof out, "%s/sub%ld.h5", dir, ranks[j]);
        char *rest[] = {"navigate", short_run, "-o", out, NULL};
        command(argvs, (int)ranks[j], sasnav, rest);
        run_stats s = run(argvs, log);
        if (j == 0) snprintf(first, sizeof first, "%s", out);
        printf("navigate subspace, 15 pairs: %ld process%s %8.2f s  %6.3f pairs/s  peak %6.1f MiB  %s%s\n",
               ranks[j], ranks[j] > 1 ? "es" : "  ", s.seconds, 15 / s.seconds, s.peak_mib,
               j == 0 ? "" : same_files(first, out) ? "same as 1" : "DIFFERS", s.status ? "  FAILED" : "");
    }
    /* Simulation of the longest run of part 1 by 1 and 2 processes. */
    long nsim = pings[np - 1];
    snprintf(cfg, sizeof cfg, "%s/run%ld.yaml", dir, nsim);
    for (int j = 0; j < nr; j++) {
        if (ranks[j] > 1 && !mpi) continue;
        snprintf(out, sizeof out, "%s/sim-r%ld.h5", dir, ranks[j]);
        char *rest[] = {"simulate", "--config", cfg, "-o", out, NULL};
        command(argvs, (int)ranks[j], sasnav, rest);
        run_stats s = run(argvs, log);
        if (j == 0) snprintf(first, sizeof first, "%s", out);
        printf("simulate, %ld pings: %ld process%s %8.2f s  %8.1f pings/s  %s%s\n", nsim, ranks[j],
               ranks[j] > 1 ? "es" : "  ", s.seconds, nsim / s.seconds,
               j == 0 ? "" : same_files(first, out) ? "same as 1" : "DIFFERS", s.status ? "  FAILED" : "");
    }
    for (int j = 0; j < nr; j++) {
        snprintf(out, sizeof out, "%s/sim-r%ld.h5", dir, ranks[j]);
        remove(out);
    }
    long nbig = pings[np - 1];
    snprintf(runf, sizeof runf, "%s/run%ld.h5", dir, nbig);
    struct stat st;
    for (int j = 0; j < nr && stat(runf, &st) == 0; j++) {
        if (ranks[j] > 1 && !mpi) continue;
        snprintf(out, sizeof out, "%s/dpca%ld.h5", dir, ranks[j]);
        char *rest[] = {"navigate", runf, "--method", "dpca", "-o", out, NULL};
        command(argvs, (int)ranks[j], sasnav, rest);
        run_stats s = run(argvs, log);
        if (j == 0) snprintf(first, sizeof first, "%s", out);
        printf("navigate dpca, %ld pairs: %ld process%s %8.2f s  %8.1f pairs/s  %s%s\n", nbig - 1, ranks[j],
               ranks[j] > 1 ? "es" : "  ", s.seconds, (nbig - 1) / s.seconds,
               j == 0 ? "" : same_files(first, out) ? "same as 1" : "DIFFERS", s.status ? "  FAILED" : "");
    }
    /* 48 pings (9.4 m of track) around a 3.2 x 1.6 m grid of 3.125 mm
     * pixels: every ping reaches every pixel (no tile skipped), so the
     * updates are exactly pixels x pings x channels. */
    snprintf(cfg, sizeof cfg, "%s/img48.yaml", dir);
    FILE *f = fopen(cfg, "w");
    if (!f) return 1;
    fprintf(f, "preset: paper-trajectory\ntrajectory: {n_pings: 48, x_start: -4.7}\n"
               "scene: {kind: ripples, x_min: -6, x_max: 6}\nnoise: {snr_db: 30}\n");
    fclose(f);
    snprintf(runf, sizeof runf, "%s/img48.h5", dir);
    char *sim48[] = {(char *)sasnav, "simulate", "--config", cfg, "-o", runf, NULL};
    if (run(sim48, log).status) {
        printf("simulate of the 48-ping run failed (%s)\n", log);
        return 1;
    }
    /* Direct, then FFBP: its tiles are 1024 x 1024 at 16 channels (2^24
     * pairs), so this grid is a 1024-column tile and a 1-column one: a
     * second rank gains little there (FFBP keeps one process's tiles, for
     * the same bits); larger grids spread. */
    for (int ffbp = 0; ffbp < 2; ffbp++)
        for (int j = 0; j < nr; j++) {
            if (ranks[j] > 1 && !mpi) continue;
            snprintf(out2, sizeof out2, "%s/%s-r%ld.h5", dir, ffbp ? "ffbp" : "img", ranks[j]);
            char *rest[] = {"image", runf, "--grid", "-1.6,1.6,1025,9.2,10.8,513", "-o", out2,
                            ffbp ? "--ffbp" : NULL, NULL};
            command(argvs, (int)ranks[j], sasnav, rest);
            run_stats s = run(argvs, log);
            if (j == 0) snprintf(first, sizeof first, "%s", out2);
            double updates = 1025.0 * 513 * 48 * 16;
            printf("image%s 1025 x 513 px, 48 pings x 16 channels: %ld process%s %6.2f s  %6.3f G %supdates/s  "
                   "peak %6.1f MiB  %s%s\n",
                   ffbp ? " --ffbp" : "", ranks[j], ranks[j] > 1 ? "es" : "  ", s.seconds,
                   updates / s.seconds * 1e-9, ffbp ? "equivalent " : "", s.peak_mib,
                   j == 0 ? "" : same_files(first, out2) ? "same as 1" : "DIFFERS", s.status ? "  FAILED" : "");
        }
    printf("\n(scratch files kept in %s)\n", dir);
    return 0;
}
