/* Accuracy, speed and memory of the multi-ping refinement (refine.h).
 *
 * usage: bench_refine run.h5 [nav.h5] [--seed S] [--surge-std M]
 *                    [--sway-std M] [--sweeps N] [--threads T]
 * run.h5 must hold the truth, e.g. the simulated tank:
 *   sasnav simulate --preset tank -o rec && sasnav ingest --wav rec -o tank.h5
 * The start is nav.h5 when given (e.g. `sasnav navigate tank.h5 --fix-yaw
 * --surge-sigma 0.025 -o nav.h5`), otherwise the truth moved along / across
 * each ping's array axis by independent seeded normal errors (default
 * 2.5 mm and 0.3 mm, the size of the pair estimator's errors on the tank).
 * Prints the rms surge and sway errors against the truth (after the best
 * rigid fit of the centroids) before and after, the misfit and move of each
 * sweep, the wall time (total, per sweep, per ping and sweep) and the peak
 * resident memory (ru_maxrss). */
#include "sasnav/error.h"
#include "sasnav/io.h"
#include "sasnav/refine.h"
#include "sasnav/scene.h"
#include "sasnav/trajectory.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

int main(int argc, char **argv)
{
    const char *run_path = NULL, *nav_path = NULL;
    unsigned long long seed = 1;
    double surge_std = 2.5e-3, sway_std = 3e-4;
    sasnav_refine_opts o;
    sasnav_refine_default_opts(&o);
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--seed") && i + 1 < argc) seed = strtoull(argv[++i], NULL, 10);
        else if (!strcmp(argv[i], "--surge-std") && i + 1 < argc) surge_std = atof(argv[++i]);
        else if (!strcmp(argv[i], "--sway-std") && i + 1 < argc) sway_std = atof(argv[++i]);
        else if (!strcmp(argv[i], "--sweeps") && i + 1 < argc) o.sweeps = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--threads") && i + 1 < argc) o.nthreads = atoi(argv[++i]);
        else if (argv[i][0] != '-' && !run_path) run_path = argv[i];
        else if (argv[i][0] != '-' && !nav_path) nav_path = argv[i];
        else {
            fprintf(stderr, "usage: bench_refine run.h5 [nav.h5] [--seed S] [--surge-std M] [--sway-std M] "
                            "[--sweeps N] [--threads T]\n");
            return 2;
        }
    }
    if (!run_path) {
        fprintf(stderr, "bench_refine: a run file with the truth is required (see the source's header)\n");
        return 2;
    }
    sasnav_run *run = NULL;
    if (sasnav_run_read(run_path, &run) || !run->truth) {
        fprintf(stderr, "bench_refine: %s: %s\n", run_path, run ? "no truth in the run" : sasnav_last_error());
        sasnav_run_free(run);
        return 1;
    }
    int n = run->n_pings;
    sasnav_ping_pose *start = NULL, *out = malloc(sizeof *out * n);
    if (nav_path) {
        int m = 0;
        if (sasnav_nav_read(nav_path, &m, &start, NULL) || m != n) {
            fprintf(stderr, "bench_refine: %s: %s\n", nav_path, m != n ? "ping count differs" : sasnav_last_error());
            return 1;
        }
    } else {
        start = malloc(sizeof *start * n);
        sasnav_rng rng;
        sasnav_rng_seed(&rng, seed);
        for (int p = 0; p < n; p++) {
            double u = surge_std * sasnav_rng_normal(&rng), v = sway_std * sasnav_rng_normal(&rng);
            double c = cos(run->truth[p].array.theta), s = sin(run->truth[p].array.theta);
            start[p] = run->truth[p];
            start[p].tx.x += u * c - v * s;
            start[p].array.x += u * c - v * s;
            start[p].tx.y += u * s + v * c;
            start[p].array.y += u * s + v * c;
        }
    }
    sasnav_refine_report rep;
    int rc = sasnav_refine(run, start, &o, out, &rep);
    if (rc) {
        fprintf(stderr, "bench_refine: %s\n", sasnav_last_error());
        return 1;
    }
    double su0, sw0, su1, sw1;
    if (sasnav_traj_rms_rigid(start, run->truth, n, &su0, &sw0)) su0 = sw0 = NAN;
    if (sasnav_traj_rms_rigid(out, run->truth, n, &su1, &sw1)) su1 = sw1 = NAN;
    printf("run %s: %d pings x %d channels x %d samples; start %s\n", run_path, n, run->array.n_rx,
           run->win.n_samples, nav_path ? nav_path : "truth + seeded errors");
    for (int s = 0; s < rep.sweeps; s++)
        printf("  sweep %d: mean misfit %.5f -> %.5f, rms move %.3f mm\n", s + 1, rep.misfit[s], rep.misfit[s + 1],
               1e3 * rep.rms_move[s]);
    if (rep.undone) printf("  (a further sweep raised the misfit and was undone)\n");
    printf("rms error vs truth (best rigid fit): surge %.3f -> %.3f mm, sway %.3f -> %.3f mm\n", 1e3 * su0,
           1e3 * su1, 1e3 * sw0, 1e3 * sw1);
    printf("time %.2f s (%.2f s per sweep, %.3f s per ping and sweep)\n", rep.seconds,
           rep.seconds / (rep.sweeps + rep.undone), rep.seconds / ((rep.sweeps + rep.undone) * (double)n));
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    printf("peak resident memory: %.1f MB\n", ru.ru_maxrss / 1024.0);
    sasnav_run_free(run);
    free(start);
    free(out);
    return 0;
}
