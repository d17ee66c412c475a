/* Progress of long commands (cli.h): a bar on a terminal, otherwise a
 * line on stderr every so often, with the rate and the time left. */
#include "cli.h"

#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include <unistd.h>

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

void cli_progress_init(cli_progress *p, const char *command, const char *unit)
{
    p->command = command;
    p->unit = unit;
    p->t0 = p->last = now();
    p->tty = isatty(STDERR_FILENO);
    p->lines = 0;
    p->open_bar = 0;
    const char *env = getenv("SASNAV_PROGRESS_SECONDS");
    p->interval = 10.0;
    if (env && *env) {
        char *end;
        double v = strtod(env, &end);
        if (end != env && *end == '\0' && v >= 0) p->interval = v;
    }
}

/* "1 min 05 s" or "12 s". */
static void duration(char *buf, size_t n, double s)
{
    if (!(s >= 0) || s > 3.6e6) snprintf(buf, n, "?");
    else if (s >= 3600) snprintf(buf, n, "%d h %02d min", (int)(s / 3600), (int)(s / 60) % 60);
    else if (s >= 60) snprintf(buf, n, "%d min %02d s", (int)(s / 60), (int)s % 60);
    else snprintf(buf, n, "%.0f s", s);
}

void cli_progress_update(cli_progress *p, int done, int total)
{
    if (cli_mpi_rank() != 0) return; /* rank 0 speaks for an MPI job (its own share) */
    double t = now(), el = t - p->t0;
    double rate = el > 0 ? done / el : 0;
    char left[32] = "";
    if (total > 0 && done > 0 && done < total) {
        char d[24];
        duration(d, sizeof d, (total - done) / rate);
        snprintf(left, sizeof left, ", %s left", d);
    }
    char count[48];
    if (total > 0) snprintf(count, sizeof count, "%d/%d", done, total);
    else snprintf(count, sizeof count, "%d", done);
    if (p->tty) {
        const int width = 30;
        char bar[64] = "";
        if (total > 0) {
            int filled = width * done / total;
            bar[0] = '[';
            for (int j = 0; j < width; j++) bar[1 + j] = j < filled ? '#' : '.';
            bar[width + 1] = ']';
            bar[width + 2] = ' ';
            bar[width + 3] = '\0';
        }
        fprintf(stderr, "\r\033[Ksasnav %s: %s%s %s, %.2f %s/s%s", p->command, bar, count, p->unit, rate,
                p->unit, left);
        p->open_bar = 1;
        fflush(stderr);
        return;
    }
    int last = total > 0 && done >= total;
    if (t - p->last < p->interval && !(last && p->lines > 0)) return;
    if (done == 0 && !last) return;
    p->last = t;
    p->lines++;
    fprintf(stderr, "sasnav %s: %s %s, %.2f %s/s%s\n", p->command, count, p->unit, rate, p->unit, left);
}

void cli_progress_end(cli_progress *p)
{
    if (p->open_bar) fputc('\n', stderr);
    p->open_bar = 0;
}

void cli_ping_progress(int done, int total, void *user) { cli_progress_update(user, done, total); }
