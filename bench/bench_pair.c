/* Accuracy and cost of the ping-pair estimator on paper-pair variants.
 *
 * usage: bench_pair [--draws N] [--seed S] [--snr DB|inf] [--threads T]
 *                   [--k K] [--i I] [--cross M] [--error-extent M]
 *                   [--error-taper M] [--tolerance T] [--paper-only]
 * Prints, for the paper's case and N random motion errors drawn uniformly
 * in surge +-4 cm, sway +-2.5 cm, yaw +-4e-2 rad (seeded): the truth, the
 * zeta-stage and final estimates, their errors, evaluations, operator
 * applications and wall time; then the number of draws within the
 * acceptance bounds (0.5 mm surge, 0.2 mm sway, 5e-4 rad yaw) and the
 * peak memory (ru_maxrss). Per estimate also where the time goes: wall
 * seconds and operator applications of each stage. --range-extent M sets
 * the grid's range extent (default 0.8 m). */
#include "sasnav/error.h"
#include "sasnav/estimator.h"
#include "sasnav/sim.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

static double sim_tolerance = 1e-6; /* --tolerance: data and estimator alike */

static int run_case(const sasnav_scenario *base, sasnav_pose err, const sasnav_pair_opts *po, int idx)
{
    sasnav_scenario sc = *base;
    sc.traj.pair_error = err;
    sasnav_run *run = NULL;
    /* The data always at the default NUFFT tolerance; --est-tolerance
     * changes the estimator's operators only. */
    sasnav_op_opts sim_op;
    sasnav_op_default_opts(&sim_op);
    if (po->op.tolerance == sim_tolerance) sim_op = po->op;
    int rc = sasnav_simulate(&sc, NULL, &sim_op, &run);
    if (rc) {
        fprintf(stderr, "simulate: %s\n", sasnav_last_error());
        return -1;
    }
    sasnav_pair *pair = NULL;
    sasnav_pair_result r;
    sasnav_pose nominal = sasnav_ping_displacement(&run->nav[0], &run->nav[1]);
    rc = sasnav_pair_create(&run->sys, &run->array, &run->win, po, &pair);
    if (!rc) rc = sasnav_pair_set_data(pair, sasnav_run_ping(run, 0), sasnav_run_ping(run, 1), nominal);
    if (!rc) rc = sasnav_pair_estimate(pair, &r);
    sasnav_pair_destroy(pair);
    sasnav_run_free(run);
    if (rc) {
        printf("%3d  estimate failed: %s\n", idx, sasnav_last_error());
        return 0;
    }
    double es = r.error.x - err.x, ew = r.error.y - err.y, ey = r.error.theta - err.theta;
    int ok = fabs(es) <= 5e-4 && fabs(ew) <= 2e-4 && fabs(ey) <= 5e-4 && r.status == SASNAV_OK;
    printf("%3d  truth %+7.2f %+7.2f mm %+.4f | zeta %+7.2f %+7.3f mm %+.5f | final %+8.3f %+8.4f mm %+.5f"
           " | err %+7.3f %+8.4f mm %+.1e | %4d ev %6ld app %6.2f s %s\n",
           idx, 1e3 * err.x, 1e3 * err.y, err.theta, 1e3 * r.zeta_stage.x, 1e3 * r.zeta_stage.y,
           r.zeta_stage.theta, 1e3 * r.error.x, 1e3 * r.error.y, r.error.theta, 1e3 * es, 1e3 * ew, ey,
           r.evaluations, r.applications, r.seconds, ok ? "ok" : "FAIL");
    printf("     stages (s / applications): global %.2f / %ld, zeta %.2f / %ld, eta %.2f / %ld, "
           "final %.2f / %ld (%d evaluations)\n",
           r.seconds_global, r.applications_global, r.seconds_zeta, r.applications_zeta, r.seconds_eta,
           r.applications_eta, r.seconds_final, r.applications_final, r.evaluations_final);
    fflush(stdout);
    return ok;
}

int main(int argc, char **argv)
{
    int draws = 10, paper_only = 0;
    unsigned long seed = 2026;
    double snr = 30.0;
    sasnav_pair_opts po;
    sasnav_pair_default_opts(&po);
    for (int a = 1; a < argc; a++) {
        if (!strcmp(argv[a], "--draws") && a + 1 < argc) draws = atoi(argv[++a]);
        else if (!strcmp(argv[a], "--seed") && a + 1 < argc) seed = strtoul(argv[++a], NULL, 10);
        else if (!strcmp(argv[a], "--snr") && a + 1 < argc) {
            a++;
            snr = !strcmp(argv[a], "inf") ? INFINITY : atof(argv[a]);
        } else if (!strcmp(argv[a], "--threads") && a + 1 < argc) po.nthreads = atoi(argv[++a]);
        else if (!strcmp(argv[a], "--k") && a + 1 < argc) po.k = atoi(argv[++a]);
        else if (!strcmp(argv[a], "--i") && a + 1 < argc) po.i = atoi(argv[++a]);
        else if (!strcmp(argv[a], "--cross") && a + 1 < argc) po.cross_extent = atof(argv[++a]);
        else if (!strcmp(argv[a], "--error-extent") && a + 1 < argc) po.error_extent = atof(argv[++a]);
        else if (!strcmp(argv[a], "--error-taper") && a + 1 < argc) po.error_taper = atof(argv[++a]);
        else if (!strcmp(argv[a], "--tolerance") && a + 1 < argc) po.op.tolerance = sim_tolerance = atof(argv[++a]);
        else if (!strcmp(argv[a], "--est-tolerance") && a + 1 < argc) po.op.tolerance = atof(argv[++a]);
        else if (!strcmp(argv[a], "--paper-only")) paper_only = 1;
        else if (!strcmp(argv[a], "--range-extent") && a + 1 < argc) po.range_extent = atof(argv[++a]);
        else if (!strcmp(argv[a], "--pixel") && a + 1 < argc) po.pixel = atof(argv[++a]);
        else if (!strcmp(argv[a], "--final") && a + 1 < argc) {
            a++;
            po.final_criterion = !strcmp(argv[a], "joint") ? SASNAV_FINAL_JOINT
                                 : !strcmp(argv[a], "eta") ? SASNAV_FINAL_ETA : SASNAV_FINAL_AUTO;
        } else if (!strcmp(argv[a], "--joint-k") && a + 1 < argc) po.joint_k = atoi(argv[++a]);
        else if (!strcmp(argv[a], "--joint-eta-ratio") && a + 1 < argc) po.joint_eta_ratio = atof(argv[++a]);
        else if (!strcmp(argv[a], "--joint-mu") && a + 1 < argc) po.joint_mu = atof(argv[++a]);
        else {
            fprintf(stderr, "usage: bench_pair [--draws N] [--seed S] [--snr DB|inf] [--threads T] [--k K] [--i I] "
                            "[--range-extent M] [--paper-only] [--final auto|eta|joint] [--joint-k K] [--joint-mu M]\n");
            return 2;
        }
    }
    sasnav_scenario sc;
    sasnav_scenario_preset("paper-pair", &sc);
    sc.snr_db = snr;
    po.range = sc.range_of_interest;
    po.tx_lag = sc.traj.tx_lag;
    printf("paper-pair, SNR %g dB, k = %d, i = %d, threads %d, grid along-track %g m (0 = auto), "
           "error extent %g m, taper %g m\n", snr, po.k, po.i, po.nthreads, po.cross_extent, po.error_extent,
           po.error_taper);
    int pass = 0;
    int paper = run_case(&sc, sc.traj.pair_error, &po, 0);
    if (paper < 0) return 1;
    if (!paper_only) {
        sasnav_rng rng;
        sasnav_rng_seed(&rng, seed);
        for (int d = 1; d <= draws; d++) {
            sasnav_pose e = {0.04 * (2 * sasnav_rng_uniform(&rng) - 1), 0.025 * (2 * sasnav_rng_uniform(&rng) - 1),
                             0.04 * (2 * sasnav_rng_uniform(&rng) - 1)};
            sc.ripples.seed = seed + 100 + d;
            sc.noise_seed = seed + 200 + d;
            int ok = run_case(&sc, e, &po, d);
            if (ok < 0) return 1;
            pass += ok;
        }
        printf("random draws within bounds: %d / %d\n", pass, draws);
    }
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    printf("paper case within bounds: %s; peak memory %.1f MiB\n", paper ? "yes" : "no", ru.ru_maxrss / 1024.0);
    return 0;
}
