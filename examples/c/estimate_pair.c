/* Simulates the paper's ping pair and estimates its motion error with the
 * subspace-intersection estimator, then compares with the simulation's truth.
 *
 *   estimate_pair [SEED]
 *
 * Uses the numerical core only (no files). Exit status 0 when the estimate
 * is within the paper's bounds (surge 0.5 mm, sway 0.2 mm, yaw 5e-4 rad) and
 * the verdict is "ok", 1 otherwise. */
#include <sasnav/sasnav.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

int main(int argc, char **argv)
{
    printf("sasnav %s (headers %s)\n", sasnav_version(), SASNAV_VERSION_STRING);
    sasnav_scenario sc;
    int rc = sasnav_scenario_preset("paper-pair", &sc);
    if (!rc && argc > 1) sasnav_scenario_seed(&sc, strtoull(argv[1], NULL, 10));
    sasnav_op_opts oo;
    sasnav_op_default_opts(&oo);
    sasnav_run *run = NULL;
    if (!rc) rc = sasnav_simulate(&sc, NULL, &oo, &run);
    if (rc) {
        fprintf(stderr, "estimate_pair: simulation failed: %s\n", sasnav_last_error());
        return 1;
    }

    /* the nominal displacement of ping 1 seen from ping 0, and the truth */
    sasnav_pose nominal = sasnav_ping_displacement(&run->nav[0], &run->nav[1]);
    sasnav_pose d = sasnav_ping_displacement(&run->truth[0], &run->truth[1]);
    sasnav_pose truth = {d.x - nominal.x, d.y - nominal.y, sasnav_wrap_angle(d.theta - nominal.theta)};

    sasnav_pair_opts po;
    sasnav_pair_default_opts(&po);
    po.tx_lag = run->tx_lag;
    sasnav_pair *pair = NULL;
    sasnav_pair_result res;
    rc = sasnav_pair_create(&run->sys, &run->array, &run->win, &po, &pair);
    if (!rc) rc = sasnav_pair_set_data(pair, sasnav_run_ping(run, 0), sasnav_run_ping(run, 1), nominal);
    if (!rc) rc = sasnav_pair_estimate(pair, &res);
    if (rc) {
        fprintf(stderr, "estimate_pair: %s\n", sasnav_last_error());
        sasnav_pair_destroy(pair);
        sasnav_run_free(run);
        return 1;
    }
    double du = res.error.x - truth.x, dw = res.error.y - truth.y;
    double dt = sasnav_wrap_angle(res.error.theta - truth.theta);
    printf("estimate: surge %+.3f mm, sway %+.3f mm, yaw %+.2e rad (verdict %s, eta %.3f)\n",
           1e3 * res.error.x, 1e3 * res.error.y, res.error.theta, sasnav_verdict_name(res.verdict),
           res.eta);
    printf("truth:    surge %+.3f mm, sway %+.3f mm, yaw %+.2e rad\n", 1e3 * truth.x, 1e3 * truth.y,
           truth.theta);
    int within = fabs(du) <= 0.5e-3 && fabs(dw) <= 0.2e-3 && fabs(dt) <= 5e-4;
    printf("error:    surge %+.3f mm, sway %+.3f mm, yaw %+.2e rad: %s\n", 1e3 * du, 1e3 * dw, dt,
           within ? "within the paper's bounds" : "OUTSIDE the paper's bounds");
    sasnav_pair_destroy(pair);
    sasnav_run_free(run);
    return within && res.verdict == SASNAV_VERDICT_OK ? 0 : 1;
}
