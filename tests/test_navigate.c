/* Navigation of a whole run (navigate.h): trajectory recovery with the
 * subspace estimator and with DPCA on small noise-free simulations, the
 * least-squares path with long baselines, failed pairs, progress reports,
 * the consistency of the outputs and bad input. */
#include "sasnav/error.h"
#include "sasnav/navigate.h"
#include "sasnav/sim.h"
#include "sasnav/trajectory.h"
#include "testutil.h"

#include <math.h>
#include <string.h>

#define LAMBDA 0.005 /* m, c / f0 of the paper's system */

/* Tolerances of the subspace trajectory (4 pings, 3 pairs, noise-free,
 * exact EPCA geometry, small smooth errors of 3 mm / 3 mrad rms). To keep
 * the test short (it also runs under ASan) the estimator runs its coarse
 * iterations only, k = 2 and i = 1: a tenth of the cost of k = i = 5 and,
 * per pair (SPEC 6), still sway errors of <= 0.02 mm, surge errors of
 * 0.2-1.3 mm (surge is the weak axis: eta is flat along a surge ~ R yaw
 * valley) and yaw errors of ~1e-4 rad.
 *  - cumulative sway <= 0.2 mm = lambda / 25, the paper's final figure:
 *    the sway drift is the sum of the pair sway errors plus each yaw error
 *    times the distance still to go (1e-4 rad x (0.2 + 0.4 + 0.6) m =
 *    0.12 mm at worst), so 0.2 mm still catches a sign or frame error (a
 *    wrong composition moves the last centroid by millimetres);
 *  - cumulative surge <= 1.5 mm: three pair surge errors of up to ~0.5 mm
 *    adding up;
 *  - cumulative yaw <= 1e-3 rad: 3 pairs of ~1e-4 rad with a factor 3 to
 *    spare, and a third of the simulated yaw errors' 3e-3 rad rms.
 * Measured: final errors +0.41 mm, +0.007 mm, -1e-4 rad (k = 2, i = 1 on
 * this 0.6 m range extent); -0.21 mm, -0.005 mm, +9e-6 rad with k = i = 5
 * on the full 1.6 m grid. */
#define SUB_SWAY_TOL 0.2e-3
#define SUB_SURGE_TOL 1.5e-3
#define SUB_YAW_TOL 1e-3
/* DPCA without surge: lambda / 10, the SAS imaging requirement (SPEC 5);
 * its pair sway errors are microns (test_dpca). */
#define DPCA_SWAY_TOL (LAMBDA / 10)

static int pose_close(sasnav_pose a, sasnav_pose b, double tol)
{
    return fabs(a.x - b.x) <= tol && fabs(a.y - b.y) <= tol &&
           fabs(sasnav_wrap_angle(a.theta - b.theta)) <= tol;
}

/* paper-trajectory reduced to n pings facing the disc, noise-free, exact
 * EPCA geometry (true_bistatic 0) and small smooth errors. */
static int g_aiding; /* 1: the next simulate() writes aiding measurements */
static uint64_t g_ripple_seed; /* nonzero: the next simulate()'s speckle draw */

static sasnav_run *simulate(int n, double spacing, double surge_rms, double sway_rms,
                            double yaw_rms)
{
    sasnav_scenario sc;
    if (sasnav_scenario_preset("paper-trajectory", &sc)) return NULL;
    sc.aiding.enabled = g_aiding;
    sc.traj.n_pings = n;
    sc.traj.ping_spacing = spacing;
    sc.traj.x_start = -0.5 * (n - 1) * spacing;
    sc.traj.true_bistatic = 0;
    sc.traj.surge_rms = surge_rms;
    sc.traj.sway_rms = sway_rms;
    sc.traj.yaw_rms = yaw_rms;
    if (g_ripple_seed) sc.ripples.seed = g_ripple_seed;
    sc.snr_db = INFINITY;
    sasnav_run *run = NULL;
    int rc = sasnav_simulate(&sc, NULL, NULL, &run);
    CHECK(rc == 0, "simulation failed: %s", sasnav_last_error());
    return rc ? NULL : run;
}

typedef struct {
    int calls, last_done, total, monotone, null_first;
} progress_log;

static void record(const sasnav_navigate_progress *pr, void *user)
{
    progress_log *log = user;
    if (log->calls == 0) log->null_first = pr->done == 0 && pr->result == NULL && pr->p == -1;
    else if (pr->done != log->last_done + 1 || pr->result == NULL) log->monotone = 0;
    log->calls++;
    log->last_done = pr->done;
    log->total = pr->total;
}

static void print_errors(const char *label, const sasnav_navigation *nav)
{
    for (int i = 0; i < nav->n_pings; i++)
        printf("  %s ping %d: cumulative error surge %+.4f mm, sway %+.4f mm, yaw %+.2e rad\n",
               label, i, 1e3 * nav->cumulative[i].x, 1e3 * nav->cumulative[i].y,
               nav->cumulative[i].theta);
    printf("  %s: track angle %.3e rad, %.2f s per pair, %.2f s in all\n", label, nav->track_angle,
           nav->seconds_per_pair, nav->seconds);
}

/* Properties every navigation output has, whatever its accuracy. */
static void check_consistency(const sasnav_run *run, const sasnav_navigation *nav)
{
    int n = run->n_pings;
    CHECK(nav->n_pings == n, "n_pings %d", nav->n_pings);
    int ok = 1;
    for (int i = 0; i < n; i++) {
        sasnav_pose c = sasnav_ping_centroid(&nav->nav[i]);
        ok &= pose_close(c, nav->centroids[i], 1e-12);
        sasnav_pose a = sasnav_pose_between(nav->nav[i].tx, nav->nav[i].array);
        ok &= fabs(a.x - run->tx_lag) < 1e-12 && fabs(a.y) < 1e-12;
    }
    CHECK(ok, "ping poses are not the EPCA geometry at the centroids");
    sasnav_pose first = sasnav_ping_centroid(&run->nav[0]);
    CHECK(fabs(nav->centroids[0].x - first.x) < 1e-12 && fabs(nav->centroids[0].y - first.y) < 1e-12,
          "the trajectory does not start at the nominal first centroid");
    double angle = 1;
    CHECK_OK(sasnav_traj_track_angle(nav->centroids, n, &angle));
    CHECK(fabs(angle) < 1e-9, "aligned trajectory keeps a track angle of %.2e rad", angle);
    for (int j = 0; j < n - 1; j++) {
        const sasnav_navigate_pair *np = &nav->pairs[j];
        CHECK(np->p == j && np->q == j + 1, "pair %d is (%d, %d)", j, np->p, np->q);
        sasnav_pose d = sasnav_ping_displacement(&run->truth[j], &run->truth[j + 1]);
        CHECK(fabs(np->truth.y - d.y) < 1e-12 && fabs(np->truth.x - (d.x - run->ping_spacing)) < 1e-12,
              "pair %d: true motion error wrong", j);
        CHECK(fabs(np->error.y - (np->fused.y - np->truth.y)) < 1e-15, "pair %d: error", j);
        /* Displacements of consecutive pairs are nominal + fused. */
        CHECK(fabs(np->result.displacement.y - (np->nominal.y + np->fused.y)) < 1e-15 &&
                  fabs(np->result.displacement.x - (np->nominal.x + np->fused.x)) < 1e-15,
              "pair %d: displacement is not nominal + fused", j);
    }
    if (!nav->has_truth) return;
    CHECK(nav->cumulative[0].x == 0 && nav->cumulative[0].y == 0 && nav->cumulative[0].theta == 0,
          "cumulative error of the first ping is not 0");
    /* The anchored estimate starts on the true first centroid. */
    sasnav_pose a0 = sasnav_ping_centroid(&nav->anchored[0]);
    sasnav_pose t0 = sasnav_ping_centroid(&run->truth[0]);
    CHECK(pose_close(a0, t0, 1e-12), "anchored navigation does not start on the truth");
    /* The truth moved onto the estimate keeps its own displacements. */
    sasnav_pose t_last = sasnav_ping_centroid(&run->truth[n - 1]);
    sasnav_pose between_true = sasnav_pose_between(t0, t_last);
    sasnav_pose between_moved = sasnav_pose_between(nav->truth_centroids[0], nav->truth_centroids[n - 1]);
    CHECK(pose_close(between_true, between_moved, 1e-12), "moved truth is not rigid");
}

static void test_subspace(void)
{
    sasnav_run *run = simulate(4, 0.20, 3e-3, 3e-3, 3e-3);
    if (!run) return;
    sasnav_navigate_opts o;
    sasnav_navigate_default_opts(&o);
    o.pair.k = o.pair.coarse_k;
    o.pair.i = o.pair.coarse_i;
    o.pair.range_extent = 0.6; /* m, instead of 1.6: cost / 2.7, same texture */
    progress_log log = {0, 0, 0, 1, 0};
    o.progress = record;
    o.progress_user = &log;
    sasnav_navigation nav;
    CHECK_OK(sasnav_navigate(run, &o, &nav));
    if (nav.n_pings == run->n_pings) {
        print_errors("subspace", &nav);
        for (int j = 0; j < nav.n_pairs; j++)
            printf("  pair %d-%d: error surge %+.4f mm, sway %+.5f mm, yaw %+.2e rad (status %d)\n",
                   nav.pairs[j].p, nav.pairs[j].q, 1e3 * nav.pairs[j].error.x,
                   1e3 * nav.pairs[j].error.y, nav.pairs[j].error.theta, nav.pairs[j].status);
        CHECK(nav.n_pairs == 3 && nav.n_failed == 0, "%d pairs, %d failed", nav.n_pairs, nav.n_failed);
        CHECK(nav.has_truth, "truth not used");
        check_consistency(run, &nav);
        sasnav_pose f = nav.cumulative[3];
        CHECK(fabs(f.y) <= SUB_SWAY_TOL, "final sway error %.4f mm", 1e3 * f.y);
        CHECK(fabs(f.x) <= SUB_SURGE_TOL, "final surge error %.4f mm", 1e3 * f.x);
        CHECK(fabs(f.theta) <= SUB_YAW_TOL, "final yaw error %.2e rad", f.theta);
        for (int i = 0; i < 4; i++)
            CHECK(fabs(nav.cumulative[i].y) <= SUB_SWAY_TOL, "ping %d sway error %.4f mm", i,
                  1e3 * nav.cumulative[i].y);
        CHECK(log.null_first && log.monotone && log.calls == 4 && log.last_done == 3 && log.total == 3,
              "progress: %d calls, last done %d of %d", log.calls, log.last_done, log.total);
        CHECK(nav.seconds > 0 && nav.seconds_per_pair > 0 && nav.seconds_estimation <= nav.seconds,
              "timings %.3f %.3f %.3f", nav.seconds, nav.seconds_pairs, nav.seconds_per_pair);
        /* paper-trajectory's 20 cm spacing leaves (p, p + 2) no common phase
         * centre: long baselines are skipped, not failed (checked on the
         * DPCA run below, where it costs nothing). */
    }
    sasnav_navigation_free(&nav);
    CHECK(nav.pairs == NULL && nav.nav == NULL, "free does not zero");
    sasnav_navigation_free(&nav); /* twice is harmless */
    sasnav_run_free(run);
}

static void test_dpca(void)
{
    /* Zero surge: DPCA's model (surge not observable) holds. */
    sasnav_run *run = simulate(6, 0.20, 0.0, 3e-3, 3e-3);
    if (!run) return;
    sasnav_navigate_opts o;
    sasnav_navigate_default_opts(&o);
    o.method = SASNAV_METHOD_DPCA;
    sasnav_navigation nav;
    CHECK_OK(sasnav_navigate(run, &o, &nav));
    if (nav.n_pings == run->n_pings) {
        print_errors("DPCA", &nav);
        check_consistency(run, &nav);
        CHECK(nav.n_failed == 0, "%d DPCA pairs failed", nav.n_failed);
        for (int i = 0; i < nav.n_pings; i++)
            CHECK(fabs(nav.cumulative[i].y) <= DPCA_SWAY_TOL, "DPCA ping %d sway error %.4f mm", i,
                  1e3 * nav.cumulative[i].y);
        /* DPCA has no verdict: even right estimates are never "ok" alone. */
        for (int j = 0; j < nav.n_pairs; j++)
            CHECK(nav.pairs[j].verdict == SASNAV_VERDICT_UNCHECKED &&
                      nav.pairs[j].first_verdict == SASNAV_VERDICT_UNCHECKED,
                  "DPCA pair %d verdict %s", j, sasnav_verdict_name(nav.pairs[j].verdict));
        CHECK(nav.n_flagged == nav.n_pairs, "%d of %d DPCA pairs flagged", nav.n_flagged, nav.n_pairs);
    }
    sasnav_navigation_free(&nav);
    sasnav_run_free(run);

    /* With aiding: estimates that agree with it are confirmed ("ok"); one
     * moved by a phase-centre spacing of surge (what DPCA cannot see) is
     * not, and is bridged. */
    g_aiding = 1;
    run = simulate(6, 0.20, 0.0, 3e-3, 3e-3);
    g_aiding = 0;
    if (!run) return;
    CHECK(run->aiding != NULL, "no aiding simulated");
    CHECK_OK(sasnav_navigate(run, &o, &nav));
    if (nav.n_pings == run->n_pings) {
        CHECK(nav.aiding_used == 1 && nav.n_flagged == 0, "DPCA with aiding: %d flagged, aiding used %d",
              nav.n_flagged, nav.aiding_used);
        for (int j = 0; j < nav.n_pairs; j++)
            CHECK(nav.pairs[j].verdict == SASNAV_VERDICT_OK, "aided DPCA pair %d verdict %s", j,
                  sasnav_verdict_name(nav.pairs[j].verdict));
    }
    sasnav_navigation_free(&nav);
    /* The DVL of interval 2-3 now says the vehicle went one phase-centre
     * spacing (2.5 cm) further than the DPCA estimate (surge error 0). */
    double dt = run->aiding->time[3] - run->aiding->time[2];
    run->aiding->velocity[2 * 3] += 0.025 / dt;
    CHECK_OK(sasnav_navigate(run, &o, &nav));
    if (nav.n_pings == run->n_pings) {
        CHECK(nav.pairs[2].resolution == SASNAV_RESOLVED_BRIDGED && nav.n_flagged == 1,
              "DPCA pair 2-3 against its aiding: %s, %d flagged",
              sasnav_resolution_name(nav.pairs[2].resolution), nav.n_flagged);
    }
    sasnav_navigation_free(&nav);
    sasnav_run_free(run);
    run = simulate(6, 0.20, 0.0, 3e-3, 3e-3);
    if (!run) return;

    /* 20 cm spacing: (p, p + 2) shares no phase centre and is skipped. */
    o.long_baselines = 1;
    CHECK_OK(sasnav_navigate(run, &o, &nav));
    CHECK(nav.n_pairs == 5 && nav.n_skipped == 4 && nav.lsq_iterations == 0,
          "long baselines at 20 cm: %d pairs, %d skipped", nav.n_pairs, nav.n_skipped);
    sasnav_navigation_free(&nav);
    sasnav_run_free(run);

    /* 10 cm spacing: 12 phase centres shared by consecutive pings, 8 by
     * (p, p + 2); all links combined by least squares. */
    run = simulate(6, 0.10, 0.0, 3e-3, 3e-3);
    if (!run) return;
    CHECK_OK(sasnav_navigate(run, &o, &nav));
    if (nav.n_pings == run->n_pings) {
        print_errors("DPCA, long baselines", &nav);
        CHECK(nav.n_pairs == 9 && nav.n_skipped == 0 && nav.n_failed == 0 && nav.lsq_iterations > 0,
              "%d pairs, %d skipped, %d failed, %d iterations", nav.n_pairs, nav.n_skipped,
              nav.n_failed, nav.lsq_iterations);
        CHECK(nav.pairs[5].p == 0 && nav.pairs[5].q == 2, "first long baseline is (%d, %d)",
              nav.pairs[5].p, nav.pairs[5].q);
        check_consistency(run, &nav);
        for (int i = 0; i < nav.n_pings; i++)
            CHECK(fabs(nav.cumulative[i].y) <= DPCA_SWAY_TOL, "ping %d sway error %.4f mm", i,
                  1e3 * nav.cumulative[i].y);
    }
    sasnav_navigation_free(&nav);
    sasnav_run_free(run);
}

/* Every DPCA pair refused (the nominal shift is not a whole number of
 * phase centres): the navigation goes on with the nominal displacements. */
static void test_failed_pairs(void)
{
    sasnav_run *run = simulate(3, 0.20, 0.0, 3e-3, 3e-3);
    if (!run) return;
    run->ping_spacing = 0.21;
    sasnav_navigate_opts o;
    sasnav_navigate_default_opts(&o);
    o.method = SASNAV_METHOD_DPCA;
    sasnav_navigation nav;
    CHECK_OK(sasnav_navigate(run, &o, &nav));
    CHECK(nav.n_failed == 2 && nav.pairs && nav.pairs[0].status == SASNAV_ERR_ARG,
          "failed pairs: %d", nav.n_failed);
    if (nav.centroids) {
        sasnav_pose nominal[3];
        sasnav_traj_centroids(run->nav, 3, nominal);
        int ok = 1;
        for (int i = 0; i < 3; i++) ok &= pose_close(nav.centroids[i], nominal[i], 1e-12);
        CHECK(ok, "failed pairs do not fall back to the nominal trajectory");
    }
    sasnav_navigation_free(&nav);
    sasnav_run_free(run);
}

/* A ping whose echoes are another seabed's (a corrupt ping) in the middle
 * of a run without aiding: both of its pairs fail, are estimated again
 * from the motion model's prediction (the nearest usable pairs on either
 * side, interpolated) and stay "failed" (the new estimate may be kept if
 * its eta is lower, still failed, or the pair bridged). A failed estimate
 * has no weight, and with no aiding the smoother's motion model alone
 * spans them: equal changes of the motion error from pair 0 to pair 3,
 * i.e. their fused errors on the straight line between those two pairs'
 * (to 1e-6 m or rad: the smoother's 1 m prior on each motion error is
 * 1e-4 of the motion model's weight, on errors of a few millimetres; the
 * line spans 6e-4 rad of yaw). Pairs 0 and 3 stay ok. */
static void test_bridged_middle(void)
{
    sasnav_run *run = simulate(5, 0.20, 3e-3, 3e-3, 3e-3);
    g_ripple_seed = 99;
    sasnav_run *other = simulate(5, 0.20, 3e-3, 3e-3, 3e-3);
    g_ripple_seed = 0;
    if (run && other) {
        memcpy(sasnav_run_ping(run, 2), sasnav_run_ping(other, 2), sizeof(sasnav_cfloat) * sasnav_run_ping_size(run));
        sasnav_navigate_opts o;
        sasnav_navigate_default_opts(&o);
        o.pair.k = o.pair.coarse_k;
        o.pair.i = o.pair.coarse_i;
        o.pair.range_extent = 0.6; /* m: cost / 2.7 */
        sasnav_navigation nav;
        CHECK_OK(sasnav_navigate(run, &o, &nav));
        if (nav.n_pairs == 4 && nav.pairs) {
            const sasnav_navigate_pair *pr = nav.pairs;
            for (int j = 0; j < 4; j++)
                printf("corrupt ping 2: pair %d-%d %s (%s), eta %.3f, fused %+.4f mm %+.5f mm %+.2e rad\n",
                       pr[j].p, pr[j].q, sasnav_verdict_name(pr[j].verdict),
                       sasnav_resolution_name(pr[j].resolution), pr[j].result.eta, 1e3 * pr[j].fused.x,
                       1e3 * pr[j].fused.y, pr[j].fused.theta);
            CHECK(pr[0].verdict == SASNAV_VERDICT_OK && pr[3].verdict == SASNAV_VERDICT_OK,
                  "the pairs beside the corrupt ping: %s, %s", sasnav_verdict_name(pr[0].verdict),
                  sasnav_verdict_name(pr[3].verdict));
            for (int j = 1; j <= 2; j++) {
                CHECK(pr[j].verdict == SASNAV_VERDICT_FAILED && (pr[j].resolution == SASNAV_RESOLVED_BRIDGED ||
                                                                 pr[j].resolution == SASNAV_RESOLVED_REESTIMATED),
                      "pair %d-%d of the corrupt ping: %s, %s", pr[j].p, pr[j].q,
                      sasnav_verdict_name(pr[j].verdict), sasnav_resolution_name(pr[j].resolution));
                double t = j / 3.0;
                sasnav_pose a = pr[0].fused, b = pr[3].fused, f = pr[j].fused;
                sasnav_pose line = {a.x + t * (b.x - a.x), a.y + t * (b.y - a.y), a.theta + t * (b.theta - a.theta)};
                CHECK(pose_close(f, line, 1e-6), "bridged pair %d-%d off the motion model's line by "
                      "%.2e m, %.2e m, %.2e rad", pr[j].p, pr[j].q, f.x - line.x, f.y - line.y, f.theta - line.theta);
            }
            CHECK(nav.n_flagged >= 2, "%d flagged pairs", nav.n_flagged);
        }
        sasnav_navigation_free(&nav);
    }
    sasnav_run_free(run);
    sasnav_run_free(other);
}

static void test_bad_input(void)
{
    sasnav_run *run = simulate(2, 0.20, 0.0, 0.0, 0.0);
    if (!run) return;
    sasnav_navigate_opts o;
    sasnav_navigate_default_opts(&o);
    sasnav_navigation nav;
    CHECK(sasnav_navigate(NULL, &o, &nav) == SASNAV_ERR_ARG, "NULL run accepted");
    CHECK(sasnav_navigate(run, &o, NULL) == SASNAV_ERR_ARG, "NULL output accepted");
    o.method = (sasnav_method)7;
    CHECK(sasnav_navigate(run, &o, &nav) == SASNAV_ERR_ARG, "unknown method accepted");
    CHECK(nav.pairs == NULL && nav.nav == NULL, "output not empty after a failure");
    sasnav_navigate_default_opts(&o);
    o.link_sigma.y = 0;
    CHECK(sasnav_navigate(run, &o, &nav) == SASNAV_ERR_ARG, "zero link sigma accepted");
    sasnav_navigate_default_opts(&o);
    run->n_pings = 1;
    CHECK(sasnav_navigate(run, &o, &nav) == SASNAV_ERR_ARG, "one-ping run accepted");
    run->n_pings = 2;
    run->nav[1].array.x = NAN;
    CHECK(sasnav_navigate(run, &o, &nav) != SASNAV_OK, "non-finite navigation accepted");
    sasnav_run_free(run);
}

/* Pairs estimated concurrently (two threads, one estimator each) give the
 * same bits as one after the other: each pair depends on its own data, and
 * the operators sum in a fixed order whatever their thread count. Coarse
 * iterations keep it short; the check is exact equality, so any race or
 * shared state between the estimators (the operators' work buffers, the
 * estimator's evaluation cache) shows up as a difference. */
static void test_threads_over_pairs(void)
{
    sasnav_run *run = simulate(4, 0.20, 3e-3, 3e-3, 3e-3);
    if (!run) return;
    sasnav_navigation nav[2];
    memset(nav, 0, sizeof nav);
    for (int t = 0; t < 2; t++) {
        sasnav_navigate_opts o;
        sasnav_navigate_default_opts(&o);
        o.pair.k = o.pair.coarse_k;
        o.pair.i = o.pair.coarse_i;
        o.pair.range_extent = 0.6;
        o.nthreads = t + 1;
        progress_log log = {0, 0, 0, 1, 0};
        o.progress = record;
        o.progress_user = &log;
        CHECK_OK(sasnav_navigate(run, &o, &nav[t]));
        CHECK(nav[t].threads_over_pairs == t + 1, "%d threads: %d pairs at a time", t + 1,
              nav[t].threads_over_pairs);
        CHECK(log.null_first && log.monotone && log.calls == 4 && log.last_done == 3,
              "%d threads: progress %d calls, last done %d", t + 1, log.calls, log.last_done);
        CHECK(nav[t].pairs_per_second > 0 && nav[t].seconds_estimation > 0, "no throughput reported");
    }
    if (nav[0].n_pairs == 3 && nav[1].n_pairs == 3) {
        for (int j = 0; j < 3; j++) {
            const sasnav_pair_result *a = &nav[0].pairs[j].result, *b = &nav[1].pairs[j].result;
            CHECK(!memcmp(&a->error, &b->error, sizeof a->error) && a->eta == b->eta &&
                      a->zeta == b->zeta && a->applications == b->applications &&
                      a->evaluations == b->evaluations,
                  "pair %d differs between 1 and 2 threads: surge %.9g / %.9g", j, a->error.x,
                  b->error.x);
        }
        CHECK(!memcmp(nav[0].centroids, nav[1].centroids, sizeof(sasnav_pose) * 4),
              "centroids differ between 1 and 2 threads");
    }
    sasnav_navigation_free(&nav[0]);
    sasnav_navigation_free(&nav[1]);
    sasnav_run_free(run);
}

/* The pairs' own speed-scaled offsets (opts.speed_lags 2) in two passes:
 * every pair ends with a final stage (none is left at level 1), the
 * first pass's candidates and margin stay with it, and the result is the
 * same bits on one and two threads. */
static void test_two_pass(void)
{
    sasnav_run *run = simulate(4, 0.20, 3e-3, 3e-3, 3e-3);
    if (!run) return;
    sasnav_navigation nav[2];
    memset(nav, 0, sizeof nav);
    for (int t = 0; t < 2; t++) {
        sasnav_navigate_opts o;
        sasnav_navigate_default_opts(&o);
        o.pair.k = o.pair.i = 3; /* a final stage, cheaply */
        o.pair.range_extent = 0.6;
        o.speed_lags = 2;
        o.nthreads = t + 1;
        CHECK_OK(sasnav_navigate(run, &o, &nav[t]));
    }
    if (nav[0].n_pairs == 3 && nav[1].n_pairs == 3) {
        for (int j = 0; j < 3; j++) {
            const sasnav_pair_result *a = &nav[0].pairs[j].result, *b = &nav[1].pairs[j].result;
            CHECK(a->final_criterion != SASNAV_FINAL_NONE, "pair %d left without its final stage", j);
            CHECK(a->n_candidates >= 1 && a->margin > 0, "pair %d: the first pass's candidates lost", j);
            CHECK(!memcmp(&a->error, &b->error, sizeof a->error) && a->eta == b->eta,
                  "pair %d differs between 1 and 2 threads", j);
        }
        CHECK(!memcmp(nav[0].centroids, nav[1].centroids, sizeof(sasnav_pose) * 4),
              "centroids differ between 1 and 2 threads");
    }
    sasnav_navigation_free(&nav[0]);
    sasnav_navigation_free(&nav[1]);
    sasnav_run_free(run);
}

/* Resuming (opts.done, the checkpoints' mechanism): records collected
 * through the progress callback of a first navigation, given back whole or
 * in part, give the same bits as estimating; records made with other
 * options or of other pings are not used. Also through sasnav_validate's
 * sub-runs: keys name the pings' content, not their index. */
typedef struct {
    sasnav_pair_record rec[32];
    int n, resumed;
} record_log;

static void collect(const sasnav_navigate_progress *pr, void *user)
{
    record_log *l = user;
    if (!pr->result) return;
    if (pr->resumed) {
        l->resumed++;
        return;
    }
    if (l->n < 32) l->rec[l->n++] = (sasnav_pair_record){pr->key, pr->p, pr->q, pr->status, *pr->result};
}

static int same_navigation(const sasnav_navigation *a, const sasnav_navigation *b)
{
    if (a->n_pairs != b->n_pairs || a->n_pings != b->n_pings) return 0;
    for (int j = 0; j < a->n_pairs; j++) {
        const sasnav_navigate_pair *x = &a->pairs[j], *y = &b->pairs[j];
        if (memcmp(&x->fused, &y->fused, sizeof x->fused) || memcmp(&x->result.error, &y->result.error, sizeof x->result.error) ||
            x->result.eta != y->result.eta || x->verdict != y->verdict || x->resolution != y->resolution ||
            x->first_status != y->first_status || x->result.n_candidates != y->result.n_candidates)
            return 0;
    }
    return !memcmp(a->nav, b->nav, sizeof *a->nav * (size_t)a->n_pings) &&
           !memcmp(a->centroids, b->centroids, sizeof *a->centroids * (size_t)a->n_pings);
}

static void test_resume(void)
{
    /* Sanitized builds (about 20x slower): 3 pings, 2 pairs. */
#ifdef SASNAV_TEST_SANITIZED
    const int np_run = 3;
#else
    const int np_run = 5;
#endif
    const int npairs = np_run - 1;
    sasnav_run *run = simulate(np_run, 0.20, 3e-3, 3e-3, 3e-3);
    if (!run) return;
    sasnav_navigate_opts o;
    sasnav_navigate_default_opts(&o);
    o.pair.k = o.pair.coarse_k;
    o.pair.i = o.pair.coarse_i;
    o.pair.range_extent = 0.6;
    record_log full = {0}, part = {0}, none = {0};
    sasnav_navigation ref, nav;
    o.progress = collect;
    o.progress_user = &full;
    CHECK_OK(sasnav_navigate(run, &o, &ref));
    CHECK(full.n == npairs && full.resumed == 0, "%d records, %d resumed", full.n, full.resumed);
    for (int j = 0; j < full.n; j++)
        for (int i = 0; i < j; i++)
            CHECK(full.rec[i].key != full.rec[j].key, "pairs %d and %d share a key", i, j);

    /* The odd pairs done (an interrupted run), in reverse order. */
    sasnav_pair_record some[16];
    int n_some = 0;
    for (int j = npairs - 1; j >= 0; j--)
        if (j % 2 == 1) some[n_some++] = full.rec[j];
    o.done = some;
    o.n_done = n_some;
    o.progress_user = &part;
    CHECK_OK(sasnav_navigate(run, &o, &nav));
    CHECK(part.resumed == n_some && part.n == npairs - n_some, "resumed %d, estimated %d (want %d, %d)",
          part.resumed, part.n, n_some, npairs - n_some);
    CHECK(same_navigation(&ref, &nav), "a resumed navigation differs from the uninterrupted one");
    for (int j = 0; j < part.n; j++) {
        int given = 0;
        for (int i = 0; i < n_some; i++) given |= part.rec[j].key == some[i].key;
        CHECK(!given, "estimated a pair that was given");
    }
    sasnav_navigation_free(&nav);

    /* All done: nothing estimated, same result. */
    o.done = full.rec;
    o.n_done = full.n;
    part = (record_log){0};
    CHECK_OK(sasnav_navigate(run, &o, &nav));
    CHECK(part.resumed == npairs && part.n == 0, "all given: resumed %d, estimated %d", part.resumed, part.n);
    CHECK(same_navigation(&ref, &nav), "a navigation from records differs");
    sasnav_navigation_free(&nav);

    /* Other options: no record applies. k; and options that change an
     * estimate or its verdict only in some cases (the final criterion, the
     * joint misfit's contrast gate, the coincidence tolerance, the compact
     * scenes' margin, the verdict's contrast gate, the joint misfit's
     * coverage rule): a record made under others must not be taken, even
     * where (as here, without a final stage) they would give the same. */
    for (int v = 0; v < 7; v++) {
        sasnav_navigate_opts ov = o;
        if (v == 0) ov.pair.k = o.pair.coarse_k + 1;
        if (v == 1) ov.pair.final_criterion = SASNAV_FINAL_ETA;
        if (v == 2) ov.pair.joint_contrast_max = 3.0;
        if (v == 3) ov.pair.verdict_coincidence = 0.5 * o.pair.verdict_coincidence;
        if (v == 4) ov.pair.verdict_margin_compact = o.pair.verdict_margin_compact + 0.1;
        if (v == 5) ov.pair.verdict_contrast = o.pair.verdict_contrast + 0.5;
        if (v == 6) ov.pair.joint_coverage_min = o.pair.joint_coverage_min + 0.1;
        none = (record_log){0};
        ov.progress_user = &none;
        CHECK_OK(sasnav_navigate(run, &ov, &nav));
        CHECK(none.resumed == 0 && none.n == npairs, "records used under other options (case %d: %d)", v,
              none.resumed);
        sasnav_navigation_free(&nav);
    }
    o.progress_user = &none;

    /* Same pings in a sub-run (pings 1..): the keys still match. */
    sasnav_run *sub = NULL;
    int pings[16];
    for (int i = 1; i < np_run; i++) pings[i - 1] = i;
    CHECK_OK(sasnav_run_subset(run, pings, np_run - 1, NULL, 0, &sub));
    if (sub) {
        none = (record_log){0};
        CHECK_OK(sasnav_navigate(sub, &o, &nav));
        CHECK(none.resumed == npairs - 1 && none.n == 0, "sub-run: resumed %d, estimated %d", none.resumed, none.n);
        for (int j = 0; j < npairs - 1 && nav.n_pairs == npairs - 1; j++)
            CHECK(!memcmp(&nav.pairs[j].first_result.error, &ref.pairs[j + 1].first_result.error,
                          sizeof(sasnav_pose)),
                  "sub-run pair %d differs", j);
        sasnav_navigation_free(&nav);
        sasnav_run_free(sub);
    }
    /* A changed last ping: its one pair is estimated again. */
    sasnav_run_ping(run, np_run - 1)[100] += 1e-3f;
    none = (record_log){0};
    CHECK_OK(sasnav_navigate(run, &o, &nav));
    CHECK(none.resumed == npairs - 1 && none.n == 1, "changed ping: resumed %d, estimated %d", none.resumed,
          none.n);
    sasnav_navigation_free(&nav);
    o.n_done = -1;
    CHECK(sasnav_navigate(run, &o, &nav) == SASNAV_ERR_ARG, "n_done < 0 accepted");
    sasnav_navigation_free(&ref);
    sasnav_run_free(run);
}

/* Trust over a run: a compact scene (the `point` preset: one point
 * target, 4 pings around it) where single pairs are ambiguous and their
 * best candidates slip by phase-centre spacings. Without aiding every
 * slipped pair must be flagged (never "ok"); with the simulated gyro and
 * DVL the resolution re-estimates them from the aiding and no pair slips
 * (a quarter phase-centre spacing of surge, 2e-3 rad of yaw). Coarse
 * iterations: the slips are 25-50 mm, far above their accuracy. */
static void test_trust_point(void)
{
    sasnav_scenario sc;
    sasnav_scenario_preset("point", &sc);
    sc.aiding.enabled = 1;
    sasnav_run *full = NULL, *run = NULL;
    CHECK_OK(sasnav_simulate(&sc, NULL, NULL, &full));
    if (!full) return;
    /* Sanitized builds (about 20x slower): 3 pings, the same code paths. */
#ifdef SASNAV_TEST_SANITIZED
    const int np_run = 3;
#else
    const int np_run = 4;
#endif
    int pings[4] = {7, 8, 9, 10};
    CHECK_OK(sasnav_run_subset(full, pings, np_run, NULL, 0, &run));
    sasnav_run_free(full);
    if (!run) return;
    CHECK(run->aiding != NULL, "the subset of consecutive pings lost the aiding");
    const double d = 0.025;
    for (int aided = 0; aided <= 1; aided++) {
        sasnav_navigate_opts o;
        sasnav_navigate_default_opts(&o);
        o.pair.k = o.pair.coarse_k;
        o.pair.i = o.pair.coarse_i;
        o.pair.range_extent = 0.6; /* m: cost / 2.7, the target stays inside */
        o.use_aiding = aided;
        sasnav_navigation nav;
        CHECK_OK(sasnav_navigate(run, &o, &nav));
        if (nav.n_pairs != np_run - 1) continue;
        int slips = 0, unflagged = 0, first_flagged = 0;
        for (int j = 0; j < nav.n_pairs; j++) {
            const sasnav_navigate_pair *np = &nav.pairs[j];
            int slip = fabs(np->error.x) > 0.25 * d || fabs(np->error.theta) > 2e-3;
            int flag = np->verdict != SASNAV_VERDICT_OK || np->resolution == SASNAV_RESOLVED_BRIDGED;
            slips += slip;
            unflagged += slip && !flag;
            first_flagged += np->first_verdict != SASNAV_VERDICT_OK;
            printf("  point, aiding %d: pair %d-%d first %s, now %s (%s), error surge %+.2f mm, yaw %+.2e\n",
                   aided, np->p, np->q, sasnav_verdict_name(np->first_verdict),
                   sasnav_verdict_name(np->verdict), sasnav_resolution_name(np->resolution),
                   1e3 * np->error.x, np->error.theta);
        }
        CHECK(unflagged == 0, "aiding %d: %d slipped pairs passed as ok", aided, unflagged);
        CHECK(first_flagged >= 1, "aiding %d: no pair of the compact scene was flagged", aided);
        CHECK(nav.aiding_used == aided, "aiding_used %d", nav.aiding_used);
        if (aided) {
            /* On a point target eta even prefers points further along the
             * comb (by up to 28 %): the aiding cannot always make a pair's
             * own estimate agree; such a pair is bridged (flagged), its
             * fused value the aiding's. */
            CHECK(slips == 0, "with aiding %d pairs still slip", slips);
            int ok_or_bridged = 1;
            for (int j = 0; j < nav.n_pairs; j++)
                ok_or_bridged &= nav.pairs[j].verdict == SASNAV_VERDICT_OK ||
                                 nav.pairs[j].resolution == SASNAV_RESOLVED_BRIDGED;
            CHECK(nav.n_resolved >= 1 && ok_or_bridged, "with aiding: %d resolved, %d flagged",
                  nav.n_resolved, nav.n_flagged);
            /* The same navigation with its pairs kept packed
             * (compact_pairs; first estimates reused, the resolution's
             * re-estimates made again): the same pairs and trajectory. */
            sasnav_navigate_opts oc = o;
            oc.compact_pairs = 1;
            oc.reuse = &nav;
            sasnav_navigation cn;
            CHECK_OK(sasnav_navigate(run, &oc, &cn));
            CHECK(cn.pairs == NULL && cn.packed != NULL && cn.n_pairs == nav.n_pairs, "compact: pairs %p, %d",
                  (void *)cn.pairs, cn.n_pairs);
            for (int j = 0; j < cn.n_pairs && j < nav.n_pairs; j++) {
                sasnav_navigate_pair c;
                CHECK_OK(sasnav_navigation_pair(&cn, j, &c));
                const sasnav_navigate_pair *f = &nav.pairs[j];
                CHECK(c.p == f->p && c.q == f->q && c.status == f->status && c.verdict == f->verdict &&
                          c.first_verdict == f->first_verdict && c.resolution == f->resolution &&
                          !memcmp(&c.fused, &f->fused, sizeof c.fused) &&
                          !memcmp(&c.result.error, &f->result.error, sizeof c.result.error) &&
                          !memcmp(&c.first_result.error, &f->first_result.error, sizeof c.result.error) &&
                          c.result.eta == f->result.eta && c.result.n_candidates == f->result.n_candidates,
                      "compact pair %d differs", j);
            }
            CHECK(cn.centroids && !memcmp(cn.centroids, nav.centroids, sizeof *cn.centroids * (size_t)cn.n_pings),
                  "compact: other centroids");
            /* A packed navigation can be reused in turn (it was refused). */
            sasnav_navigate_opts orp = o;
            orp.reuse = &cn;
            sasnav_navigation rn;
            CHECK_OK(sasnav_navigate(run, &orp, &rn));
            CHECK(rn.centroids && !memcmp(rn.centroids, nav.centroids, sizeof *rn.centroids * (size_t)rn.n_pings),
                  "reuse of a packed navigation: other centroids");
            sasnav_navigation_free(&rn);
            sasnav_navigation_free(&cn);
        } else {
            CHECK(nav.n_flagged >= 1, "without aiding nothing flagged");
        }
        sasnav_navigation_free(&nav);
    }
    /* A coarse aiding (sigmas 1e4 times larger: its gate wider than half a
     * slip) agrees with slipped candidates too: it must not settle any
     * ambiguity, so no pair the estimator flagged comes out "ok". */
    {
        sasnav_aiding *ad = run->aiding;
        for (int p = 0; p < run->n_pings; p++) {
            ad->yaw_rate_sigma[p] *= 1e4;
            ad->velocity_sigma[2 * p] *= 1e4;
            ad->velocity_sigma[2 * p + 1] *= 1e4;
        }
        sasnav_navigate_opts o;
        sasnav_navigate_default_opts(&o);
        o.pair.k = o.pair.coarse_k;
        o.pair.i = o.pair.coarse_i;
        o.pair.range_extent = 0.6;
        sasnav_navigation nav;
        CHECK_OK(sasnav_navigate(run, &o, &nav));
        int settled = 0, flagged = 0;
        for (int j = 0; j < nav.n_pairs; j++) {
            flagged += nav.pairs[j].first_verdict != SASNAV_VERDICT_OK;
            settled += nav.pairs[j].first_verdict != SASNAV_VERDICT_OK && nav.pairs[j].verdict == SASNAV_VERDICT_OK;
        }
        printf("  point, coarse aiding: %d of %d pairs flagged by the estimator, %d of them made ok\n", flagged,
               nav.n_pairs, settled);
        CHECK(flagged >= 1 && settled == 0, "coarse aiding settled %d of %d flagged pairs", settled, flagged);
        sasnav_navigation_free(&nav);
        for (int p = 0; p < run->n_pings; p++) {
            ad->yaw_rate_sigma[p] /= 1e4;
            ad->velocity_sigma[2 * p] /= 1e4;
            ad->velocity_sigma[2 * p + 1] /= 1e4;
        }
    }
    /* Navigation by aiding alone needs aiding; bad aiding is refused. */
    sasnav_navigate_opts o;
    sasnav_navigate_default_opts(&o);
    o.method = SASNAV_METHOD_AIDING;
    sasnav_navigation nav;
    CHECK_OK(sasnav_navigate(run, &o, &nav));
    CHECK(nav.n_pairs == np_run - 1 && nav.aiding_used, "aiding-only navigation");
    /* Dead reckoning with a navigation-grade gyro and a 3 mm/s DVL over 3
     * pings: within 1 mm and 1e-5 rad. */
    if (nav.n_pings == np_run) {
        sasnav_pose f = nav.cumulative[np_run - 1];
        CHECK(fabs(f.y) < 1e-3 && fabs(f.theta) < 1e-5, "aiding alone: final sway %.3f mm, yaw %.2e",
              1e3 * f.y, f.theta);
    }
    sasnav_navigation_free(&nav);
    /* An interval without a DVL or a gyro measurement (+inf): its pair is
     * "failed" (its step the motion model's), the others stay ok; the
     * same when the navigation is reused (its records carry no verdict
     * of the aiding's). */
    {
        sasnav_aiding *ad = run->aiding;
        double keep_v = ad->velocity_sigma[2 * 2], keep_g = ad->yaw_rate_sigma[1];
        ad->velocity_sigma[2 * 2] = INFINITY; /* the interval that ends at ping 2: pair 1-2 */
        ad->yaw_rate_sigma[1] = INFINITY;     /* pair 0-1 */
        sasnav_navigation first;
        CHECK_OK(sasnav_navigate(run, &o, &first));
        sasnav_navigate_opts ore = o;
        ore.reuse = &first;
        CHECK_OK(sasnav_navigate(run, &ore, &nav));
        for (int pass = 0; pass < 2; pass++) {
            const sasnav_navigation *nv = pass ? &nav : &first;
            for (int j = 0; j < nv->n_pairs; j++) {
                sasnav_navigate_pair np;
                sasnav_navigation_pair(nv, j, &np);
                int want = np.q <= 2 ? SASNAV_VERDICT_FAILED : SASNAV_VERDICT_OK;
                CHECK(np.verdict == want, "aiding alone%s, pair %d-%d: verdict %s, expected %s",
                      pass ? " (reused)" : "", np.p, np.q, sasnav_verdict_name(np.verdict),
                      sasnav_verdict_name(want));
            }
        }
        sasnav_navigation_free(&nav);
        sasnav_navigation_free(&first);
        ad->velocity_sigma[2 * 2] = keep_v;
        ad->yaw_rate_sigma[1] = keep_g;
        /* Long baselines: the aiding measures consecutive steps only. */
        sasnav_navigate_opts olb = o;
        olb.long_baselines = 1;
        CHECK(sasnav_navigate(run, &olb, &nav) == SASNAV_ERR_ARG, "aiding alone with long baselines accepted");
        /* Without a DVL (or a gyro) at all: refused. */
        double *v = ad->velocity, *vs = ad->velocity_sigma;
        ad->velocity = ad->velocity_sigma = NULL;
        CHECK(sasnav_navigate(run, &o, &nav) == SASNAV_ERR_ARG &&
                  strstr(sasnav_last_error(), "no velocity"),
              "aiding alone without a DVL accepted (%s)", sasnav_last_error());
        ad->velocity = v;
        ad->velocity_sigma = vs;
        double *y = ad->yaw_rate, *ys = ad->yaw_rate_sigma;
        ad->yaw_rate = ad->yaw_rate_sigma = NULL;
        CHECK(sasnav_navigate(run, &o, &nav) == SASNAV_ERR_ARG &&
                  strstr(sasnav_last_error(), "no yaw rate"),
              "aiding alone without a gyro accepted (%s)", sasnav_last_error());
        ad->yaw_rate = y;
        ad->yaw_rate_sigma = ys;
    }
    run->aiding->velocity_sigma[3] = -1.0;
    CHECK(sasnav_navigate(run, &o, &nav) == SASNAV_ERR_ARG, "negative aiding sigma accepted");
    sasnav_aiding_free(run->aiding);
    run->aiding = NULL;
    CHECK(sasnav_navigate(run, &o, &nav) == SASNAV_ERR_ARG, "aiding-only navigation without aiding accepted");
    sasnav_run_free(run);
}

/* The eta-outlier rule (opts.eta_outlier) on a navigation reused with
 * estimates made up for it (speckle-like: contrasts 0, but one case):
 * 8 pings, 7 consecutive pairs, every estimate
 * at the truth (a run without motion errors: motion error 0) but pair 3,
 * which slipped by a phase-centre spacing (+25 mm of surge) with an eta of
 * 0.60 against the others' 0.18-0.23. No pair is estimated: the pairs come
 * from the reused navigation and have no candidates, so the resolution
 * only applies the verdicts and the smoother. The median is checked
 * against the one computed here, the line on both sides of the pair's
 * ratio (0.60 / 0.21 = 2.857), the flag's effect in the smoother, and the
 * cases where the rule stands aside. */
static void test_eta_outlier(void)
{
    enum { N = 8 };
    sasnav_run *run = simulate(N, 0.2, 0, 0, 0);
    if (!run) return;
    const double eta[N - 1] = {0.20, 0.22, 0.18, 0.60, 0.19, 0.23, 0.21};
    const double median = 0.21; /* of the seven: 0.18 0.19 0.20 0.21 0.22 0.23 0.60 */
    const double slip = 0.025;
    sasnav_navigate_pair made[N - 1];
    memset(made, 0, sizeof made);
    for (int j = 0; j < N - 1; j++) {
        sasnav_navigate_pair *m = &made[j];
        m->p = j;
        m->q = j + 1;
        m->first_status = SASNAV_OK;
        sasnav_pair_result *r = &m->first_result;
        r->status = SASNAV_OK;
        r->verdict = SASNAV_VERDICT_OK;
        r->eta = eta[j];
        r->margin = INFINITY;
        r->chosen = -1;
        r->error = (sasnav_pose){j == 3 ? slip : 0.0, 0.0, 0.0};
        r->displacement = sasnav_ping_displacement(&run->nav[j], &run->nav[j + 1]);
        r->displacement.x += r->error.x;
    }
    sasnav_navigation given;
    memset(&given, 0, sizeof given);
    given.method = SASNAV_METHOD_SUBSPACE;
    given.n_pings = N;
    given.n_pairs = N - 1;
    given.pairs = made;
    sasnav_navigate_opts o;
    sasnav_navigate_default_opts(&o);
    o.reuse = &given;
    o.use_aiding = 0;
    sasnav_navigation nav;
    /* the default factor (1.6, docs/validation.md "An eta far above the
     * run's"): pair 3 alone is over the line */
    CHECK(o.eta_outlier == 1.6, "default eta outlier factor %g", o.eta_outlier);
    CHECK_OK(sasnav_navigate(run, &o, &nav));
    CHECK(fabs(nav.eta_median - median) < 1e-15, "eta median %.17g, expected %.2f", nav.eta_median, median);
    CHECK(nav.n_eta_outliers == 1, "%d eta outliers, expected 1", nav.n_eta_outliers);
    for (int j = 0; j < nav.n_pairs && j < N - 1; j++) {
        const sasnav_navigate_pair *np = &nav.pairs[j];
        int want = j == 3;
        CHECK(np->eta_outlier == want && np->verdict == (want ? SASNAV_VERDICT_AMBIGUOUS : SASNAV_VERDICT_OK) &&
                  np->first_verdict == np->verdict && np->result.verdict == SASNAV_VERDICT_OK,
              "pair %d: eta outlier %d, verdict %s, first %s", j, np->eta_outlier,
              sasnav_verdict_name(np->verdict), sasnav_verdict_name(np->first_verdict));
    }
    /* Flagged, the slip's surge goes to the motion model (the neighbours'
     * 0): within a fifth of the slip; passed as ok it stays (more than
     * four fifths: the smoother's link sigma is 1 mm, the motion model's
     * 10 mm). */
    double flagged_surge = nav.n_pairs > 3 ? nav.pairs[3].fused.x : NAN;
    sasnav_navigation_free(&nav);
    o.eta_outlier = INFINITY;
    o.link_eta = 0; /* the fixed link sigma (the eta scaling: below) */
    CHECK_OK(sasnav_navigate(run, &o, &nav));
    double kept_surge = nav.n_pairs > 3 ? nav.pairs[3].fused.x : NAN;
    CHECK(isnan(nav.eta_median) && nav.n_eta_outliers == 0 && nav.n_flagged == 0,
          "rule off: median %g, %d outliers, %d flagged", nav.eta_median, nav.n_eta_outliers, nav.n_flagged);
    CHECK(fabs(flagged_surge) < 0.2 * slip && kept_surge > 0.8 * slip,
          "slipped pair's fused surge: %.2f mm flagged, %.2f mm passed", 1e3 * flagged_surge, 1e3 * kept_surge);
    sasnav_navigation_free(&nav);
    /* opts.link_eta (default 0.2). Without aiding it changes nothing: the
     * same bits as link_eta 0 (kept_surge above). With a DVL fused, the
     * unflagged slip's standard deviations grow by (0.60 / 0.2)^2 = 9
     * (surge 9 mm); its neighbours (eta 0.18, 0.19) keep 1 mm. The aiding
     * here is made to weigh nothing (every standard deviation 1e9, no
     * aiding bias term), so the smoother is the one above with the slip
     * weighed down. With the neighbours held at 0 its surge would be slip
     * w / (w + 2 m), w = 1 / (9 mm)^2, m = 1 / (10 mm)^2 (two motion-model
     * links): 9.54 mm; the neighbours give way by about m / (1 mm)^-2 = 1 %
     * of it each, which lifts it by about 0.06 mm: within 0.3 mm of 9.54.
     * Sway and yaw stay 0 (estimates and truth 0). */
    {
        sasnav_navigate_opts d;
        sasnav_navigate_default_opts(&d);
        CHECK(d.link_eta == 0.2, "default link_eta %g", d.link_eta);
        o.link_eta = d.link_eta;
        CHECK_OK(sasnav_navigate(run, &o, &nav));
        double unaided = nav.n_pairs > 3 ? nav.pairs[3].fused.x : NAN;
        CHECK(unaided == kept_surge, "link_eta without aiding: %.6f mm against %.6f mm", 1e3 * unaided,
              1e3 * kept_surge);
        sasnav_navigation_free(&nav);
        sasnav_aiding ai;
        double t[N], rate[N], rate_s[N], vel[2 * N], vel_s[2 * N];
        for (int p = 0; p < N; p++) {
            t[p] = 0.1 * p;
            rate[p] = 0;
            rate_s[p] = 1e9;
            vel[2 * p] = 2.0;
            vel[2 * p + 1] = 0;
            vel_s[2 * p] = vel_s[2 * p + 1] = 1e9;
        }
        ai = (sasnav_aiding){t, rate, rate_s, vel, vel_s};
        run->aiding = &ai;
        o.use_aiding = 1;
        o.aiding_bias_sigma = (sasnav_pose){0, 0, 0};
        int rc = sasnav_navigate(run, &o, &nav);
        run->aiding = NULL;
        CHECK_OK(rc);
        if (!rc) {
            double w = 1.0 / (9e-3 * 9e-3), m = 1.0 / (0.01 * 0.01), want = slip * w / (w + 2 * m);
            double got = nav.n_pairs > 3 ? nav.pairs[3].fused.x : NAN;
            CHECK(fabs(got - want) < 3e-4 && fabs(nav.pairs[3].fused.y) < 1e-9 &&
                      fabs(nav.pairs[3].fused.theta) < 1e-9,
                  "link_eta 0.2 with aiding: the slip's fused motion error %.3f mm %.2e m %.2e rad, surge "
                  "expected %.3f mm",
                  1e3 * got, nav.pairs[3].fused.y, nav.pairs[3].fused.theta, 1e3 * want);
            sasnav_navigation_free(&nav);
        }
        /* A gyro alone: the surge has no aiding to weigh the pair against,
         * so it is not scaled and the slip's fused surge is the unaided
         * one (the smoother works per component). */
        ai.velocity = ai.velocity_sigma = NULL;
        run->aiding = &ai;
        rc = sasnav_navigate(run, &o, &nav);
        run->aiding = NULL;
        CHECK_OK(rc);
        if (!rc) {
            double got = nav.n_pairs > 3 ? nav.pairs[3].fused.x : NAN;
            CHECK(fabs(got - kept_surge) < 1e-12, "link_eta with a gyro alone: surge %.6f mm against %.6f mm",
                  1e3 * got, 1e3 * kept_surge);
            sasnav_navigation_free(&nav);
        }
        o.use_aiding = 0;
    }
    /* the line on either side of the pair's ratio 2.857 */
    o.eta_outlier = 2.85;
    CHECK_OK(sasnav_navigate(run, &o, &nav));
    CHECK(nav.n_eta_outliers == 1 && nav.pairs[3].eta_outlier, "factor 2.85: %d outliers", nav.n_eta_outliers);
    sasnav_navigation_free(&nav);
    o.eta_outlier = 2.86;
    CHECK_OK(sasnav_navigate(run, &o, &nav));
    CHECK(nav.n_eta_outliers == 0 && nav.pairs[3].verdict == SASNAV_VERDICT_OK, "factor 2.86: %d outliers",
          nav.n_eta_outliers);
    sasnav_navigation_free(&nav);
    /* fewer than 6 usable estimates: no median, no rule */
    o.eta_outlier = 1.8;
    made[0].first_status = made[6].first_status = SASNAV_ERR_NO_OVERLAP;
    CHECK_OK(sasnav_navigate(run, &o, &nav));
    CHECK(isnan(nav.eta_median) && nav.n_eta_outliers == 0 && nav.pairs[3].verdict == SASNAV_VERDICT_OK,
          "5 usable pairs: median %g, %d outliers", nav.eta_median, nav.n_eta_outliers);
    sasnav_navigation_free(&nav);
    made[0].first_status = made[6].first_status = SASNAV_OK;
    /* a compact scene (q's contrast over the verdict's gate): the pair is
     * left to the compact-scene rules, outside the median and the rule;
     * the median is then the six others' (0.20 + 0.21) / 2 */
    made[3].first_result.contrast_q = 1.25 * o.pair.verdict_contrast;
    CHECK_OK(sasnav_navigate(run, &o, &nav));
    CHECK(fabs(nav.eta_median - 0.205) < 1e-15 && nav.n_eta_outliers == 0 && !nav.pairs[3].eta_outlier &&
              nav.pairs[3].verdict == SASNAV_VERDICT_OK,
          "compact pair: median %.17g, %d outliers", nav.eta_median, nav.n_eta_outliers);
    sasnav_navigation_free(&nav);
    made[3].first_result.contrast_q = 0;
    /* the factor must be > 1 */
    const double bad[] = {1.0, 0.5, -2.0, NAN};
    for (int b = 0; b < 4; b++) {
        o.eta_outlier = bad[b];
        CHECK(sasnav_navigate(run, &o, &nav) == SASNAV_ERR_ARG, "eta outlier factor %g accepted", bad[b]);
    }
    sasnav_run_free(run);
}

int main(void)
{
    test_eta_outlier();
    test_bridged_middle();
    test_trust_point();
    test_threads_over_pairs();
    test_two_pass();
    test_resume();
    test_bad_input();
    test_failed_pairs();
    test_dpca();
    test_subspace();
    return test_summary("test_navigate");
}
