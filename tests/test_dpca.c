/* DPCA baseline (dpca.h) on simulated paper-pair data: accuracy on a pure
 * sway/yaw error, sign conventions, the reverse pair, thread independence,
 * bad input, and the breakdown under a surge error larger than half a
 * phase-centre spacing (SPEC 5). */
#include "sasnav/dpca.h"
#include "sasnav/error.h"
#include "sasnav/sim.h"
#include "testutil.h"

#include <math.h>
#include <string.h>

#define LAMBDA 0.005 /* m, c / f0 of paper-pair */

/* Tolerances of the noise-free accuracy checks.
 * Sway: lambda / 10 (SPEC 5: SAS imaging needs about lambda / 10 on the
 * phase-centre positions). Measured: 2-8 um on 5 scenes.
 * Yaw: 2.5e-4 rad moves the phase centres at the ends of the 0.4 m array
 * (0.19 m from the centroid) by 47 um, under lambda / 100, and is 8 times
 * smaller than the simulated yaw, so a wrong sign, a missing asin or a fit
 * about the wrong centre fails it. Measured: 1e-5 .. 5e-5 rad. */
#define SWAY_TOL (LAMBDA / 10)
#define YAW_TOL 2.5e-4

/* Simulates a noise-free paper-pair run with the given motion error of
 * ping 1 relative to ping 0 on ripple scene `seed`. */
static sasnav_run *simulate(sasnav_pose error, uint64_t seed)
{
    sasnav_scenario sc;
    if (sasnav_scenario_preset("paper-pair", &sc)) return NULL;
    sc.traj.pair_error = error;
    sc.snr_db = INFINITY;
    sc.ripples.seed = seed;
    sasnav_run *run = NULL;
    int rc = sasnav_simulate(&sc, NULL, NULL, &run);
    CHECK(rc == 0, "simulation failed: %s", sasnav_last_error());
    return rc ? NULL : run;
}

/* Motion error of ping q relative to ping p according to the truth. */
static sasnav_pose true_error(const sasnav_run *run, int p, int q)
{
    sasnav_pose d = sasnav_ping_displacement(&run->truth[p], &run->truth[q]);
    d.x -= (q - p) * run->ping_spacing;
    return d;
}

static void test_accuracy(double sway, double yaw)
{
    sasnav_run *run = simulate((sasnav_pose){0.0, sway, yaw}, 1);
    if (!run) return;
    sasnav_pair_result res;
    sasnav_dpca_detail det;
    CHECK_OK(sasnav_dpca_estimate(run, 0, 1, NULL, &res, &det));
    sasnav_pose truth = true_error(run, 0, 1);
    double e_sway = res.error.y - truth.y, e_yaw = res.error.theta - truth.theta;
    printf("  sway %+.2f mm, yaw %+.1e rad: DPCA error sway %+.4f mm, yaw %+.2e rad "
           "(K = %d, coherence %.3f, fit residual %.4f mm)\n",
           1e3 * sway, yaw, 1e3 * e_sway, e_yaw, det.n_pairs, res.overlap, 1e3 * det.residual_rms);
    CHECK(res.status == SASNAV_OK, "status %d", res.status);
    CHECK(fabs(e_sway) < SWAY_TOL, "sway error %.4f mm >= lambda/10", 1e3 * e_sway);
    CHECK(fabs(e_yaw) < YAW_TOL, "yaw error %.2e rad", e_yaw);
    CHECK(res.error.x == 0.0, "DPCA must leave surge at its nominal value");
    CHECK(det.n_pairs == 8 && det.shift == 8, "paper-pair: K = %d, shift %d (expected 8, 8)",
          det.n_pairs, det.shift);
    CHECK(fabs(res.displacement.x - 0.20) < 1e-15 && res.displacement.y == res.error.y &&
              res.displacement.theta == res.error.theta,
          "displacement is not nominal + error");
    CHECK(memcmp(&res.zeta_stage, &res.error, sizeof res.error) == 0 && res.evaluations == 0,
          "zeta_stage / evaluations not filled as documented");

    /* Coarse (envelope) delays only: reported, not asserted beyond the
     * half-wavelength scale that the phase step needs. */
    sasnav_dpca_opts o;
    sasnav_dpca_default_opts(&o);
    o.use_phase = 0;
    sasnav_pair_result coarse;
    CHECK_OK(sasnav_dpca_estimate(run, 0, 1, &o, &coarse, NULL));
    printf("    envelope only: sway error %+.4f mm, yaw %+.2e rad\n", 1e3 * (coarse.error.y - truth.y),
           coarse.error.theta - truth.theta);
    CHECK(fabs(coarse.error.y - truth.y) < LAMBDA / 4, "envelope sway error beyond lambda/4");

    /* The reverse pair: displacement of ping 0 in ping 1's frame. */
    sasnav_pair_result rev;
    CHECK_OK(sasnav_dpca_estimate(run, 1, 0, NULL, &rev, NULL));
    sasnav_pose tr = true_error(run, 1, 0);
    /* The true reverse surge error is -0.2 (1 - cos yaw) - sway sin yaw ~ 3 um,
     * not estimated: only sway and yaw are checked. */
    CHECK(fabs(rev.error.y - tr.y) < SWAY_TOL && fabs(rev.error.theta - tr.theta) < YAW_TOL,
          "reverse pair: error (%.4f mm, %.2e) vs true (%.4f mm, %.2e)", 1e3 * rev.error.y,
          rev.error.theta, 1e3 * tr.y, tr.theta);

    /* Results do not depend on the thread count. */
    sasnav_pair_result r1, r2;
    o.use_phase = 1;
    o.nthreads = 1;
    CHECK_OK(sasnav_dpca_estimate(run, 0, 1, &o, &r1, NULL));
    o.nthreads = 2;
    CHECK_OK(sasnav_dpca_estimate(run, 0, 1, &o, &r2, NULL));
    CHECK(memcmp(&r1.error, &r2.error, sizeof r1.error) == 0, "result depends on nthreads");
    sasnav_run_free(run);
}

static void test_bad_input(void)
{
    sasnav_run *run = simulate((sasnav_pose){0, 0, 0}, 1);
    if (!run) return;
    sasnav_pair_result res;
    sasnav_dpca_opts o;
    sasnav_dpca_default_opts(&o);
    CHECK(sasnav_dpca_estimate(run, 0, 0, NULL, &res, NULL) == SASNAV_ERR_ARG, "p == q accepted");
    CHECK(sasnav_dpca_estimate(run, 0, 2, NULL, &res, NULL) == SASNAV_ERR_ARG, "ping 2 accepted");
    CHECK(sasnav_dpca_estimate(run, 0, 1, NULL, NULL, NULL) == SASNAV_ERR_ARG, "NULL result accepted");
    CHECK(sasnav_dpca_estimate(NULL, 0, 1, NULL, &res, NULL) == SASNAV_ERR_ARG, "NULL run accepted");
    o.range = 30.0; /* outside the recorded swath */
    CHECK(sasnav_dpca_estimate(run, 0, 1, &o, &res, NULL) == SASNAV_ERR_ARG, "empty window accepted");
    o.range = 0;
    o.upsampling = 0;
    CHECK(sasnav_dpca_estimate(run, 0, 1, &o, &res, NULL) == SASNAV_ERR_ARG, "upsampling 0 accepted");

    double spacing = run->ping_spacing;
    run->ping_spacing = 0.21; /* 8.4 phase-centre spacings */
    CHECK(sasnav_dpca_estimate(run, 0, 1, NULL, &res, NULL) == SASNAV_ERR_ARG,
          "non-integer shift accepted");
    run->ping_spacing = 0.375; /* shift 15: K = 1 */
    CHECK(sasnav_dpca_estimate(run, 0, 1, NULL, &res, NULL) == SASNAV_ERR_ARG, "K = 1 accepted");
    run->ping_spacing = 0.35; /* shift 14: K = 2, the smallest accepted */
    sasnav_dpca_detail det;
    CHECK_OK(sasnav_dpca_estimate(run, 0, 1, NULL, &res, &det));
    CHECK(det.n_pairs == 2, "K = %d for shift 14", det.n_pairs);
    run->ping_spacing = spacing;
    run->array.rx_u[3] += 1e-3;
    CHECK(sasnav_dpca_estimate(run, 0, 1, NULL, &res, NULL) == SASNAV_ERR_ARG,
          "non-uniform array accepted");
    sasnav_run_free(run);
}

/* Surge error of 2 cm = 0.8 phase-centre spacings: the paired phase
 * centres are 2 cm apart and DPCA's surge-free model is wrong. Two effects,
 * both seen on every scene tried (16 seeds):
 *  - the paired channels decorrelate (coherence 0.7-0.8 instead of 0.99)
 *    and on about half the scenes the phase branch of some pairs slips:
 *    sway errors of 1-4 mm, yaw errors of 1e-2 rad;
 *  - on the others the phases do not slip, but the along-track offset dx
 *    biases each pair's delay by 2 dx sin(phi) towards the bright disc at
 *    x = 0, which varies across the overlap like dx / R: a yaw bias of
 *    about -dx / R = -2e-3 rad (measured -1.0e-3 .. -1.7e-3) and sway errors
 *    of 0.15-0.2 mm.
 * Asserted (robust): every scene has a yaw error above 5e-4 rad (half the
 * smallest seen; 10 times the surge-free error; over one 20 cm ping step
 * it already moves the next centroid by 0.1 mm and integrates along a
 * trajectory), and the rms sway error over the scenes exceeds lambda / 10
 * (measured 2.4 mm, five times that). The per-scene sway error is NOT
 * asserted to be large: on some scenes it is only 0.15 mm. */
static void test_surge_breakdown(void)
{
    const int n_seeds = 6;
    double ss_sway = 0, min_yaw = INFINITY, max_yaw_ok = 0;
    for (int seed = 1; seed <= n_seeds; seed++) {
        for (int with_surge = 0; with_surge <= 1; with_surge++) {
            sasnav_run *run = simulate((sasnav_pose){with_surge ? 0.02 : 0.0, 1.3e-3, 2e-3}, seed);
            if (!run) return;
            sasnav_pair_result res;
            sasnav_dpca_detail det;
            CHECK_OK(sasnav_dpca_estimate(run, 0, 1, NULL, &res, &det));
            sasnav_pose truth = true_error(run, 0, 1);
            double e_sway = res.error.y - truth.y, e_yaw = res.error.theta - truth.theta;
            printf("  scene %d, surge %2.0f mm: sway error %+8.4f mm, yaw error %+.2e rad, "
                   "coherence %.3f, fit residual %.4f mm\n",
                   seed, with_surge ? 20.0 : 0.0, 1e3 * e_sway, e_yaw, res.overlap,
                   1e3 * det.residual_rms);
            if (with_surge) {
                ss_sway += e_sway * e_sway;
                if (fabs(e_yaw) < min_yaw) min_yaw = fabs(e_yaw);
            } else {
                CHECK(fabs(e_sway) < SWAY_TOL && fabs(e_yaw) < YAW_TOL,
                      "scene %d without surge: DPCA should work", seed);
                if (fabs(e_yaw) > max_yaw_ok) max_yaw_ok = fabs(e_yaw);
            }
            sasnav_run_free(run);
        }
    }
    double rms_sway = sqrt(ss_sway / n_seeds);
    printf("  surge 2 cm: rms sway error %.3f mm over %d scenes, smallest yaw error %.2e rad "
           "(largest without surge %.2e)\n",
           1e3 * rms_sway, n_seeds, min_yaw, max_yaw_ok);
    CHECK(min_yaw > 5e-4, "surge 2 cm: yaw error only %.2e rad on some scene", min_yaw);
    CHECK(rms_sway > LAMBDA / 10, "surge 2 cm: rms sway error only %.3f mm", 1e3 * rms_sway);
}

int main(void)
{
    test_accuracy(1.3e-3, 2e-3);
    test_accuracy(-1.3e-3, -2e-3);
    test_accuracy(0.0217, 1e-2); /* the paper's sway, with a moderate yaw */
    test_bad_input();
    test_surge_breakdown();
    return test_summary("test_dpca");
}
