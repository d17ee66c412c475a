/* A navigate timing driver for any version of the library (its public API
 * only: sasnav_scenario_preset, sasnav_simulate, sasnav_navigate), to
 * compare builds of different versions on one machine
 * (bench/gpu/device-compare.sh; docs/estimator.md, "GPU"). Not built by
 * CMake: against another version's build tree,
 *
 *   gcc -O2 -std=c11 -D_POSIX_C_SOURCE=200809L -IOLD/include -IOLD/build/include \
 *       bench/gpu/navigate_driver.c OLD/build/libsasnav.a -lfftw3f -lnlopt -fopenmp -lm \
 *       -o oldnav
 *
 * usage: oldnav [SEED [THREADS]]   (default 3301 2; THREADS 0: the data's
 * checksum only). Simulates paper-trajectory with `sasnav simulate --seed`'s
 * convention (scene 3s+1, trajectory 3s+2, noise 3s+3) at 30 dB, prints a
 * checksum of the pings (equal checksums: the versions simulate the same
 * data), the wall time of sasnav_navigate and the final sway error. */
#include "sasnav/error.h"
#include "sasnav/navigate.h"
#include "sasnav/sim.h"

#include <complex.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

int main(int argc, char **argv)
{
    long s = argc > 1 ? atol(argv[1]) : 3301;
    int threads = argc > 2 ? atoi(argv[2]) : 2;
    sasnav_scenario sc;
    sasnav_scenario_preset("paper-trajectory", &sc);
    sc.snr_db = 30;
    sc.ripples.seed = (uint64_t)s * 3 + 1;
    sc.traj.seed = (uint64_t)s * 3 + 2;
    sc.noise_seed = (uint64_t)s * 3 + 3;
    sasnav_run *run = NULL;
    if (sasnav_simulate(&sc, NULL, NULL, &run)) {
        fprintf(stderr, "%s\n", sasnav_last_error());
        return 1;
    }
    double sum = 0;
    size_t nd = (size_t)run->array.n_rx * run->win.n_samples;
    for (int p = 0; p < run->n_pings; p++) {
        const sasnav_cfloat *d = sasnav_run_ping(run, p);
        for (size_t i = 0; i < nd; i++) sum += fabs(crealf(d[i])) + 2 * fabs(cimagf(d[i]));
    }
    if (threads == 0) {
        printf("seed %ld data checksum %.9e\n", s, sum);
        return 0;
    }
    sasnav_navigate_opts no;
    sasnav_navigate_default_opts(&no);
    no.nthreads = threads;
    sasnav_navigation nav;
    double t0 = now();
    if (sasnav_navigate(run, &no, &nav)) {
        fprintf(stderr, "%s\n", sasnav_last_error());
        return 1;
    }
    double t = now() - t0;
    printf("navigate seed %ld (data checksum %.9e): %d pairs, %.2f s with %d threads, final sway %+.4f mm\n",
           s, sum, nav.n_pairs, t, threads, nav.has_truth ? 1e3 * nav.cumulative[nav.n_pings - 1].y : 0.0);
    return 0;
}
