/* Reads a run file (HDF5, docs/format.md), navigates it and writes the
 * estimated navigation.
 *
 *   navigate_run RUN.h5 OUT.h5 [subspace|dpca]
 *
 * Uses the I/O layer (libsasnav) and the core. Prints one line per pair
 * (with its verdict) and, for simulated runs, the final across-track error.
 * Exit status 0 on success, 1 on a failure, 2 on a usage error. */
#include <sasnav/sasnav.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

int main(int argc, char **argv)
{
    if (argc < 3 || argc > 4 ||
        (argc == 4 && strcmp(argv[3], "subspace") != 0 && strcmp(argv[3], "dpca") != 0)) {
        fprintf(stderr, "usage: navigate_run RUN.h5 OUT.h5 [subspace|dpca]\n");
        return 2;
    }
    sasnav_run *run = NULL;
    int rc = sasnav_run_read(argv[1], &run);
    if (rc) {
        fprintf(stderr, "navigate_run: %s\n", sasnav_last_error());
        return 1;
    }
    sasnav_navigate_opts opts;
    sasnav_navigate_default_opts(&opts);
    if (argc == 4 && !strcmp(argv[3], "dpca")) opts.method = SASNAV_METHOD_DPCA;
    sasnav_navigation nav;
    rc = sasnav_navigate(run, &opts, &nav);
    if (!rc) {
        for (int k = 0; k < nav.n_pairs; k++) {
            const sasnav_navigate_pair *pr = &nav.pairs[k];
            printf("pair %2d-%2d: surge %+8.3f mm, sway %+7.3f mm, yaw %+9.2e rad  %s\n", pr->p,
                   pr->q, 1e3 * pr->fused.x, 1e3 * pr->fused.y, pr->fused.theta,
                   sasnav_verdict_name(pr->verdict));
        }
        if (nav.has_truth)
            printf("final across-track error %+.3f mm (lambda/25 = %.3f mm)\n",
                   1e3 * nav.cumulative[nav.n_pings - 1].y,
                   1e3 * run->sys.sound_speed / run->sys.f0 / 25.0);
        rc = sasnav_nav_write(argv[2], nav.n_pings, nav.nav, run->truth);
        sasnav_navigation_free(&nav);
    }
    if (rc) fprintf(stderr, "navigate_run: %s\n", sasnav_last_error());
    sasnav_run_free(run);
    return rc ? 1 : 0;
}
