/* Helpers shared by the bench programs: statistics, the seeded
 * paper-trajectory runs and the common options. */
#ifndef SASNAV_BENCH_UTIL_H
#define SASNAV_BENCH_UTIL_H

#include "sasnav/error.h"
#include "sasnav/sim.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static inline int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* Percentile (0..100) of n values by linear interpolation (sorts v). */
static inline double percentile(double *v, int n, double pc)
{
    if (n < 1) return NAN;
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    double r = pc / 100.0 * (n - 1);
    int i = (int)floor(r);
    if (i >= n - 1) return v[n - 1];
    return v[i] + (r - i) * (v[i + 1] - v[i]);
}

/* The paper-trajectory run of seed s, as `sasnav simulate --preset
 * paper-trajectory --seed S [--aiding]`: scene 3S+1, trajectory 3S+2,
 * noise 3S+3, aiding 3S+4; the seabed between ranges y0 and y1 (m; the
 * preset's 9-11 m where y0 is not finite) with the recorded swath widened
 * to hold it with the preset's margins (0.2 m before, 0.6 m after); the
 * aiding sensors of `ap` (NULL: none). NULL (message printed) on failure.
 * The _scene variant: the default sensors of docs/config.md where aiding
 * is set; bench_trajectory_run: the preset's seabed too. */
static inline sasnav_run *bench_trajectory_run_aided(long s, double snr, const sasnav_aiding_params *ap,
                                                     double y0, double y1, double disc_amplitude)
{
    sasnav_scenario sc;
    sasnav_scenario_preset("paper-trajectory", &sc);
    if (isfinite(disc_amplitude)) sc.ripples.disc_amplitude = disc_amplitude;
    if (isfinite(y0) && isfinite(y1)) {
        sc.ripples.y_min = y0;
        sc.ripples.y_max = y1;
        if (y0 - 0.2 < sc.range_min) sc.range_min = y0 - 0.2;
        if (y1 + 0.6 > sc.range_max) sc.range_max = y1 + 0.6;
    }
    sc.snr_db = snr;
    sc.ripples.seed = (uint64_t)s * 3 + 1;
    sc.traj.seed = (uint64_t)s * 3 + 2;
    sc.noise_seed = (uint64_t)s * 3 + 3;
    if (ap) {
        sc.aiding = *ap;
        sc.aiding.enabled = 1;
        sc.aiding.seed = (uint64_t)s * 3 + 4;
    }
    sasnav_run *run = NULL;
    if (sasnav_simulate(&sc, NULL, NULL, &run)) {
        fprintf(stderr, "simulate: %s\n", sasnav_last_error());
        return NULL;
    }
    return run;
}

static inline sasnav_run *bench_trajectory_run_scene(long s, double snr, int aiding, double y0,
                                                     double y1, double disc_amplitude)
{
    sasnav_aiding_params ap;
    sasnav_aiding_default(&ap);
    return bench_trajectory_run_aided(s, snr, aiding ? &ap : NULL, y0, y1, disc_amplitude);
}

static inline sasnav_run *bench_trajectory_run(long s, double snr, int aiding)
{
    return bench_trajectory_run_scene(s, snr, aiding, NAN, NAN, NAN);
}

/* Consumes `--seeds S0 N` or `--snr DB|inf` at argv[*a] (advancing *a);
 * returns 0 where argv[*a] is neither. */
static inline int bench_seed_option(int argc, char **argv, int *a, long *s0, long *ns, double *snr)
{
    if (!strcmp(argv[*a], "--seeds") && *a + 2 < argc) {
        *s0 = atol(argv[++*a]);
        *ns = atol(argv[++*a]);
        return 1;
    }
    if (!strcmp(argv[*a], "--snr") && *a + 1 < argc) {
        ++*a;
        *snr = !strcmp(argv[*a], "inf") ? INFINITY : atof(argv[*a]);
        return 1;
    }
    return 0;
}

#endif
