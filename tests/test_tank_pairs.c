/* The pair estimator on the weak pairs of the simulated tank (the default
 * 32-ping recording, read through the WAV ingest chain), the yaw held as for
 * a plotter (opts.fix_yaw):
 * - at the track ends the reflectors sit near the first null of the 5 cm
 *   elements and several surge hypotheses one phase-centre spacing
 *   d = 2.5 cm apart look alike (docs/estimator.md, "Compact scenes"). The
 *   estimate must take the right one: its surge error below d / 2 (the
 *   comb's spacing is d; the measured bias towards phase-centre coincidence
 *   is up to about 0.4 d on these pairs). Before the surge scan of the
 *   held-yaw global stage these pairs came out one spacing short (errors
 *   of -18 to -29 mm);
 * - the estimate's eta is no higher than eta at the true displacement
 *   (sway re-optimised there on a fine line): the search found a minimum at
 *   least as deep as the truth's, i.e. no search failure (the remaining
 *   error is the criterion's, not the search's). 2 % slack covers the final
 *   stage's stopping tolerance.
 * - the strong pair facing the plate (14, 16) is estimated within 0.5 mm;
 * - another draw of the tank (seed 4) whose end pairs (24, 28), (3, 6) and
 *   (28, 31) came out one spacing short even with the surge scan (zeta
 *   lower there: one more phase centre shared), with the plotter's surge
 *   prior (opts.surge_sigma = d): within d / 2 again, and the jump pair
 *   (11, 12), 17 mm off the nominal step and so penalised by the prior,
 *   still within 0.5 mm; (3, 6) also without the prior, where the scan's
 *   two candidates are alike in zeta and the lower final eta picks the
 *   right one. */
#include "sasnav/error.h"
#include "sasnav/estimator.h"
#include "sasnav/tank.h"
#include "testutil.h"

#include <math.h>
#include <stdio.h>

static void check_pair(const sasnav_run *run, int p, int q, double bound, double surge_sigma)
{
    sasnav_pair_opts po;
    sasnav_pair_default_opts(&po);
    po.range = run->range_of_interest;
    po.tx_lag = run->tx_lag;
    po.fix_yaw = 1;
    po.surge_sigma = surge_sigma;
    po.k = EST_K;
    po.i = EST_I;
    po.coarse_k = EST_K < 2 ? EST_K : 2;
    sasnav_pair *pr = NULL;
    CHECK_OK(sasnav_pair_create(&run->sys, &run->array, &run->win, &po, &pr));
    if (!pr) return;
    sasnav_pose nominal = sasnav_ping_displacement(&run->nav[p], &run->nav[q]);
    sasnav_pose d = sasnav_ping_displacement(&run->truth[p], &run->truth[q]);
    sasnav_pose truth = {d.x - nominal.x, d.y - nominal.y, 0.0};
    CHECK_OK(sasnav_pair_set_data(pr, sasnav_run_ping(run, p), sasnav_run_ping(run, q), nominal));
    sasnav_pair_result r;
    CHECK_OK(sasnav_pair_estimate(pr, &r));
    double es = r.error.x - truth.x, ew = r.error.y - truth.y;
    fprintf(stderr, "pair %d-%d: truth %+.2f / %+.3f mm, error %+.2f / %+.3f mm, eta %.4f\n", p, q,
            truth.x * 1e3, truth.y * 1e3, es * 1e3, ew * 1e3, r.eta);
    CHECK(fabs(es) < bound, "pair %d-%d surge error %.3g m (bound %.3g)", p, q, es, bound);
    CHECK(r.error.theta == 0.0, "pair %d-%d held yaw moved (%g)", p, q, r.error.theta);
    /* eta at the truth's surge, sway re-optimised on a 0.1 mm line of
     * +-1.5 mm around the true sway (eta's fringe is lambda/2 = 7 mm wide). */
    double eta_truth = HUGE_VAL;
    for (int j = -15; j <= 15; j++) {
        sasnav_pose e = {truth.x, truth.y + 1e-4 * j, 0.0};
        double v;
        CHECK_OK(sasnav_pair_eval(pr, e, 2, 0, NULL, &v, NULL));
        if (v < eta_truth) eta_truth = v;
    }
    CHECK(r.eta <= 1.02 * eta_truth, "pair %d-%d: estimate's eta %.4f above the truth's %.4f (search failure)",
          p, q, r.eta, eta_truth);
    sasnav_pair_destroy(pr);
}

int main(void)
{
    sasnav_tank_params p;
    sasnav_tank_default(&p);
    sasnav_run *run = test_tank_run(&p);
    if (!run) return test_summary("test_tank_pairs");
    CHECK(run->n_pings == 32 && run->truth, "tank run: %d pings", run->n_pings);
    double d = 0.5 * fabs(run->array.rx_u[1] - run->array.rx_u[0]);
    check_pair(run, 1, 4, 0.5 * d, 0.0);
    check_pair(run, 27, 29, 0.5 * d, 0.0);
    check_pair(run, 26, 30, 0.5 * d, 0.0);
    check_pair(run, 14, 16, 5e-4, 0.0);
    sasnav_run_free(run);

    p.seed = 4;
    run = test_tank_run(&p);
    if (!run) return test_summary("test_tank_pairs");
    check_pair(run, 3, 6, 0.5 * d, 0.0); /* no prior: the eta tie-break alone */
    check_pair(run, 24, 28, 0.5 * d, d);
    check_pair(run, 3, 6, 0.5 * d, d);
    check_pair(run, 28, 31, 0.5 * d, d);
    check_pair(run, 11, 12, 5e-4, d);
    sasnav_run_free(run);
    return test_summary("test_tank_pairs");
}
