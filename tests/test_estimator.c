/* The subspace-intersection estimator against known truths from simulation
 * (SPEC 3, issue acceptance): recovery of known displacements, minima of the
 * error functions at the truth, the lambda/2 period of eta along sway, and
 * the refusal of bad inputs. */
#include "sasnav/error.h"
#include "sasnav/estimator.h"
#include "sasnav/sim.h"
#include "estimator/pair_internal.h"
#include "testutil.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static sasnav_run *simulate(sasnav_pose err, uint64_t seed)
{
    sasnav_scenario sc;
    sasnav_scenario_preset("paper-pair", &sc);
    sc.snr_db = INFINITY;
    sc.traj.pair_error = err;
    sc.ripples.seed = seed;
    sasnav_run *run = NULL;
    CHECK_OK(sasnav_simulate(&sc, NULL, NULL, &run));
    return run;
}

/* The point preset's run (one reflector on an empty seabed), or NULL
 * after a failed check. */
static sasnav_run *point_run(void)
{
    sasnav_scenario sc;
    sasnav_scenario_preset("point", &sc);
    sasnav_run *run = NULL;
    CHECK_OK(sasnav_simulate(&sc, NULL, NULL, &run));
    return run;
}

/* In sanitized builds (about 20x slower) the estimates use k = i = 2 and
 * only the sanitizer's findings and coarse bounds are checked. */
#ifdef SASNAV_TEST_SANITIZED
static const int reduced = 1;
#else
static const int reduced = 0;
#endif

static sasnav_pair *make_pair_opts(const sasnav_run *run, const sasnav_pair_opts *base)
{
    sasnav_pair_opts po = *base;
    po.range = run->range_of_interest;
    po.tx_lag = run->tx_lag;
    sasnav_pair *pair = NULL;
    CHECK_OK(sasnav_pair_create(&run->sys, &run->array, &run->win, &po, &pair));
    if (pair) CHECK_OK(sasnav_pair_set_data(pair, sasnav_run_ping(run, 0), sasnav_run_ping(run, 1),
                                            sasnav_ping_displacement(&run->nav[0], &run->nav[1])));
    return pair;
}

static sasnav_pair *make_pair(const sasnav_run *run)
{
    sasnav_pair_opts po;
    sasnav_pair_default_opts(&po);
    if (reduced) po.k = po.i = 2;
    return make_pair_opts(run, &po);
}

/* Acceptance bounds of the issue: 0.5 mm surge, lambda/25 = 0.2 mm sway,
 * 5e-4 rad yaw (surge is the weak axis: eta is flat along surge ~ R yaw). */
static void check_recovery(sasnav_pose truth, uint64_t seed)
{
    sasnav_run *run = simulate(truth, seed);
    if (!run) return;
    sasnav_pair *pair = make_pair(run);
    sasnav_pair_result r;
    if (pair) {
        CHECK_OK(sasnav_pair_estimate(pair, &r));
        CHECK(r.status == SASNAV_OK, "status %d", r.status);
        /* Reduced (k = i = 2) runs: surge 2 mm, sway lambda/10, yaw 2e-3
         * (the coarse iterations' accuracy, SPEC 6: 0.2-1.3 mm surge). */
        double bs = reduced ? 2e-3 : 5e-4, bw = reduced ? 5e-4 : 2e-4, by = reduced ? 2e-3 : 5e-4;
        CHECK(fabs(r.error.x - truth.x) <= bs, "surge error %.3f mm", 1e3 * (r.error.x - truth.x));
        CHECK(fabs(r.error.y - truth.y) <= bw, "sway error %.4f mm", 1e3 * (r.error.y - truth.y));
        CHECK(fabs(r.error.theta - truth.theta) <= by, "yaw error %.2e rad", r.error.theta - truth.theta);
        CHECK(r.ambiguity >= 0 && r.ambiguity <= 1, "ambiguity %g outside [0, 1]", r.ambiguity);
        CHECK(r.verdict == SASNAV_VERDICT_OK, "verdict %s", sasnav_verdict_name(r.verdict));
        /* a speckle-like seabed (contrast ~2): AUTO searches on the coarse grid */
        CHECK(r.search_grid == SASNAV_SEARCH_COARSE, "search grid %s",
              sasnav_search_grid_name(r.search_grid));
        CHECK(r.n_candidates >= 1 && r.chosen >= 0 && r.candidates[r.chosen].refined,
              "%d candidates, chosen %d", r.n_candidates, r.chosen);
        /* The stage accounting covers the whole estimate: only the closing
         * evaluation at the estimate (its overlap), when not kept from the
         * final stage, lies outside the stages: one level-2 evaluation,
         * 2k + 4i(2k + 1) applications. (The CGLS of q's contrast at the
         * estimate counts with the final stage.) */
        const sasnav_pair_opts *po = sasnav_pair_options(pair);
        long staged = r.applications_global + r.applications_zeta + r.applications_eta +
                      r.applications_final;
        long one = 2L * po->k + 4L * po->i * (2L * po->k + 1);
        CHECK(r.applications - staged == 0 || r.applications - staged == one,
              "stages account for %ld of %ld applications", staged, r.applications);
        if (!reduced) {
            /* The final stage's last step (below its 0.1-unit tolerance) is
             * taken on its model: the reported eta is the model's there and
             * the overlap that of the last evaluated point, within 0.1 unit.
             * Both against a direct level-2 evaluation at the estimate: a
             * step that small changes eta by ~1e-5 relative (measured
             * 5e-6) and the overlap by ~2e-4 (measured 1.7e-4); a wrong
             * model value (eta^2 reported for eta, a mutation) fails it. */
            double eta2 = 0, ov2 = 0;
            CHECK_OK(sasnav_pair_eval(pair, r.error, 2, 0, NULL, &eta2, &ov2));
            CHECK(fabs(r.eta - eta2) <= 1e-4 * eta2, "eta %.7f, directly %.7f", r.eta, eta2);
            CHECK(fabs(r.overlap - ov2) <= 2e-3 * ov2, "overlap %.6f, directly %.6f", r.overlap, ov2);
        }
        CHECK(r.evaluations_final <= r.evaluations_eta && r.seconds_global >= 0 && r.seconds_final >= 0 &&
                  r.seconds_global + r.seconds_zeta + r.seconds_eta + r.seconds_final <= r.seconds,
              "stage times %.3f %.3f %.3f %.3f of %.3f s", r.seconds_global, r.seconds_zeta, r.seconds_eta,
              r.seconds_final, r.seconds);
        printf("truth (%.2f mm, %.2f mm, %.4f rad): error (%.3f mm, %.4f mm, %.1e rad), %d evaluations\n",
               1e3 * truth.x, 1e3 * truth.y, truth.theta, 1e3 * (r.error.x - truth.x),
               1e3 * (r.error.y - truth.y), r.error.theta - truth.theta, r.evaluations);
    }
    sasnav_pair_destroy(pair);
    sasnav_run_free(run);
}

static double *axis(sasnav_pose *e, int a) { return a == 0 ? &e->x : a == 1 ? &e->y : &e->theta; }

static void check_error_functions(void)
{
    sasnav_pose truth = {-0.0345, 0.0217, 0.041};
    sasnav_run *run = simulate(truth, 3);
    if (!run) return;
    /* The default 1.6 m range extent (the feasibility study's): on a 0.8 m
     * grid zeta's minimum along surge sits 5-6 mm from the truth (the zeta
     * stage lands at -28.3 mm for -34.5, measured), which the eta stage
     * then removes; the cut below checks the error function where its
     * minimum is at the truth. */
    sasnav_pair *pair = make_pair(run);
    if (!pair) {
        sasnav_run_free(run);
        return;
    }
    /* zeta (level 1) along each axis: the minimum of a 9-point cut centred
     * on the truth is the centre sample. Spans are inside the convexity
     * intervals the paper reports (surge and sway ~ phase-centre spacing,
     * yaw ~ 0.02 rad). */
    const double span[3] = {0.02, 0.01, 0.016};
    for (int a = 0; a < 3; a++) {
        int arg = -1;
        double best = HUGE_VAL;
        for (int j = 0; j < 9; j++) {
            sasnav_pose e = truth;
            *axis(&e, a) += span[a] * (j - 4) / 4.0;
            double z;
            CHECK_OK(sasnav_pair_eval(pair, e, 1, 0, &z, NULL, NULL));
            if (z < best) {
                best = z;
                arg = j;
            }
        }
        CHECK(arg == 4, "zeta along axis %d is minimal at sample %d, not at the truth", a, arg);
    }
    /* eta along sway oscillates with period lambda/2 = 2.5 mm: find the
     * local minima of a fine cut over +-5 mm and measure their spacing. */
    enum { NS = 81 };
    double eta[NS], h[NS];
    for (int j = 0; j < NS; j++) {
        sasnav_pose e = truth;
        h[j] = 0.010 * (j - (NS - 1) / 2.0) / ((NS - 1) / 2.0) * 0.5;
        e.y += h[j];
        CHECK_OK(sasnav_pair_eval(pair, e, 1, 0, NULL, &eta[j], NULL));
    }
    double mins[NS];
    int nm = 0;
    for (int j = 1; j < NS - 1; j++)
        if (eta[j] < eta[j - 1] && eta[j] <= eta[j + 1]) mins[nm++] = h[j];
    double period = nm >= 2 ? (mins[nm - 1] - mins[0]) / (nm - 1) : NAN;
    printf("eta along sway: %d local minima over +-5 mm, mean spacing %.3f mm (lambda/2 = 2.5 mm)\n", nm,
           1e3 * period);
    /* Sampling step 0.125 mm: the measured spacing is within +-15 % of
     * lambda/2 (the period is "near" lambda/2, SPEC 6). */
    CHECK(nm >= 3 && fabs(period - 0.0025) < 0.15 * 0.0025, "eta period %.3f mm", 1e3 * period);
    int centre_min = 0;
    for (int j = 1; j < NS - 1; j++)
        if (eta[j] < eta[(NS - 1) / 2] - 1e-12) centre_min = -1;
    CHECK(centre_min == 0, "eta's lowest sample along sway is not at the truth");

    /* Bad inputs. */
    const sasnav_cfloat *d0 = sasnav_run_ping(run, 0), *d1 = sasnav_run_ping(run, 1);
    sasnav_pose nominal = {0.2, 0, 0};
    CHECK(sasnav_pair_set_data(pair, d0, d0, nominal) == SASNAV_ERR_ARG, "same ping twice accepted");
    size_t nd = (size_t)run->array.n_rx * run->win.n_samples;
    sasnav_cfloat *bad = malloc(sizeof(sasnav_cfloat) * nd);
    memcpy(bad, d1, sizeof(sasnav_cfloat) * nd);
    memset(bad + 3 * run->win.n_samples, 0, sizeof(sasnav_cfloat) * run->win.n_samples);
    CHECK(sasnav_pair_set_data(pair, d0, bad, nominal) == SASNAV_ERR_ARG, "missing channel accepted");
    CHECK(strstr(sasnav_last_error(), "channel 3") != NULL, "message does not name the channel: %s",
          sasnav_last_error());
    bad[5] = NAN;
    CHECK(sasnav_pair_set_data(pair, d0, bad, nominal) == SASNAV_ERR_ARG, "NaN sample accepted");
    free(bad);
    /* Non-overlapping pings: q declared 3 m further along track. */
    CHECK_OK(sasnav_pair_set_data(pair, d0, d1, (sasnav_pose){3.0, 0, 0}));
    sasnav_pair_result r;
    int rc = sasnav_pair_estimate(pair, &r);
    CHECK(rc == SASNAV_ERR_NO_OVERLAP, "non-overlapping pings gave %d, not NO_OVERLAP", rc);
    sasnav_pair_destroy(pair);
    sasnav_run_free(run);
}

/* The yaw held (a rail): with the prior at the true yaw error the result
 * keeps it exactly and recovers surge and sway (coarse iterations, the
 * reduced bounds above); a negative yaw sigma is refused. */
static void check_fixed_yaw(void)
{
    sasnav_pose truth = {0.0153, -0.0081, 0.012};
    sasnav_run *run = simulate(truth, 4);
    if (!run) return;
    sasnav_pair_opts po;
    sasnav_pair_default_opts(&po);
    po.k = 2;
    po.i = 1;
    po.fix_yaw = 1;
    po.prior.theta = truth.theta;
    sasnav_pair *pair = make_pair_opts(run, &po);
    sasnav_pair_result r;
    if (pair) {
        CHECK_OK(sasnav_pair_estimate(pair, &r));
        CHECK(r.error.theta == truth.theta, "held yaw moved to %.3e", r.error.theta);
        CHECK(fabs(r.error.x - truth.x) <= 2e-3 && fabs(r.error.y - truth.y) <= 5e-4,
              "held yaw: surge / sway errors %.3f / %.4f mm", 1e3 * (r.error.x - truth.x),
              1e3 * (r.error.y - truth.y));
    }
    sasnav_pair_destroy(pair);
    po.fix_yaw = 0;
    po.yaw_sigma = -1e-3;
    pair = NULL;
    CHECK(sasnav_pair_create(&run->sys, &run->array, &run->win, &po, &pair) == SASNAV_ERR_ARG && !pair,
          "negative yaw sigma accepted");
    sasnav_run_free(run);
}

/* The verdict. (1) A compact scene (one point target, the `point` preset,
 * pings 8 and 9): the valley offers candidates a phase-centre spacing apart
 * that explain the data almost equally (level-1 eta within 1 %), and
 * whichever wins, the estimate must not be passed as "ok". (2) Two pings of
 * unrelated scenes (q from another speckle draw): nothing explains them,
 * eta stays high: "failed". (3) The well-posed paper pair is "ok" with its
 * candidates listed (check_recovery). Coarse iterations keep it fast: the
 * verdict does not depend on the final stage's accuracy. */
static void check_verdict(void)
{
    sasnav_run *run = point_run();
    if (!run) return;
    sasnav_pair_opts po;
    sasnav_pair_default_opts(&po);
    po.k = po.coarse_k;
    po.i = po.coarse_i;
    po.range_extent = 0.6; /* m: cost / 2.7; the target and the speckle stay inside */
    po.range = run->range_of_interest;
    po.tx_lag = run->tx_lag;
    sasnav_pair *pair = NULL;
    CHECK_OK(sasnav_pair_create(&run->sys, &run->array, &run->win, &po, &pair));
    sasnav_pair_result r;
    if (pair) {
        CHECK_OK(sasnav_pair_set_data(pair, sasnav_run_ping(run, 8), sasnav_run_ping(run, 9),
                                      sasnav_ping_displacement(&run->nav[8], &run->nav[9])));
        CHECK_OK(sasnav_pair_estimate(pair, &r));
        printf("point target: verdict %s, margin %.3f, %d candidates, estimate surge %.2f mm\n",
               sasnav_verdict_name(r.verdict), r.margin, r.n_candidates, 1e3 * r.error.x);
        CHECK(r.n_candidates >= 2 && r.candidates[1].refined, "%d candidates", r.n_candidates);
        CHECK(r.verdict == SASNAV_VERDICT_AMBIGUOUS, "compact-scene pair judged %s (margin %.3f)",
              sasnav_verdict_name(r.verdict), r.margin);
        CHECK(r.chosen >= 0 && r.chosen < r.n_candidates && r.margin >= 1.0 && r.margin < 1.15,
              "chosen %d, margin %.3f", r.chosen, r.margin);
        /* The coincidence rule (opts.verdict_coincidence), recomputed here
         * from its definition: the along-track displacement within
         * opts.verdict_coincidence phase-centre spacings (d = 2.5 cm, half the receiver pitch) of
         * a multiple of it shorter than the array (phase centres of q on
         * p's), on a scene compact for the verdict (contrast above
         * opts.verdict_contrast, 4). */
        double d = 0.5 * (run->array.rx_u[1] - run->array.rx_u[0]);
        double u = r.displacement.x / d;
        double cmax = r.contrast_q > r.contrast ? r.contrast_q : r.contrast;
        int expect = cmax > po.verdict_contrast && fabs(nearbyint(u)) < run->array.n_rx &&
                     fabs(u - nearbyint(u)) < po.verdict_coincidence;
        printf("point target: contrast %.2f, displacement %.3f spacings, coincidence %d\n",
               pair_contrast(pair), u, r.coincidence);
        CHECK(pair_contrast(pair) > po.joint_contrast_max, "point target's contrast %.2f", pair_contrast(pair));
        CHECK(r.contrast == pair_contrast(pair), "reported contrast %.3f, the estimator's %.3f", r.contrast,
              pair_contrast(pair));
        CHECK(r.coincidence == expect, "coincidence %d at %.4f spacings, expected %d", r.coincidence, u, expect);
    }
    sasnav_pair_destroy(pair);
    /* The rule alone decides a local estimate (estimate_from: one
     * candidate, no margin): with a tolerance of half a spacing every
     * estimate on the compact scene is at a coincidence and "ambiguous",
     * with 0 none is and the same estimate is "ok". Then the compact
     * scene's margin (opts.verdict_margin_compact): the same estimate
     * finished from a first result whose margin is set to 1.2 (between
     * verdict_margin_min, 1.15, and the compact default, 1.25) is
     * "ambiguous" with the default and "ok" with the compact margin at 1.
     * Last, the verdict's own gate (opts.verdict_contrast), apart from the
     * one that picks the search grid and final stage (joint_contrast_max):
     * with the latter above the point target's contrast (the speckle
     * scenes' final stage) the verdict's rules still apply, tolerance half a spacing:
     * "ambiguous" (t = 4); with the verdict's gate at infinity they do
     * not: "ok" (t = 5). */
    for (int t = 0; t < 6; t++) {
        sasnav_pair_opts pc = po;
        pc.verdict_coincidence = t == 0 || t >= 4 ? 0.5 : 0.0;
        if (t == 3) pc.verdict_margin_compact = 1.0;
        if (t == 4) pc.joint_contrast_max = 1e9;
        if (t == 5) pc.verdict_contrast = INFINITY;
        int flag = t == 0 || t == 4;
        pair = NULL;
        CHECK_OK(sasnav_pair_create(&run->sys, &run->array, &run->win, &pc, &pair));
        if (!pair) continue;
        CHECK_OK(sasnav_pair_set_data(pair, sasnav_run_ping(run, 8), sasnav_run_ping(run, 9),
                                      sasnav_ping_displacement(&run->nav[8], &run->nav[9])));
        sasnav_pose dt = sasnav_ping_displacement(&run->truth[8], &run->truth[9]),
                    dn = sasnav_ping_displacement(&run->nav[8], &run->nav[9]);
        sasnav_pose start = {dt.x - dn.x, dt.y - dn.y, dt.theta - dn.theta};
        CHECK_OK(sasnav_pair_estimate_from(pair, start, &r));
        printf("point target from the truth, coincidence tolerance %.1f: verdict %s, coincidence %d, eta %.3f\n",
               pc.verdict_coincidence, sasnav_verdict_name(r.verdict), r.coincidence, r.eta);
        CHECK(r.coincidence == flag, "case %d, tolerance %.1f: coincidence %d", t, pc.verdict_coincidence,
              r.coincidence);
        CHECK(r.verdict == (flag ? SASNAV_VERDICT_AMBIGUOUS : SASNAV_VERDICT_OK), "case %d, tolerance %.1f: verdict %s",
              t, pc.verdict_coincidence, sasnav_verdict_name(r.verdict));
        if (t == 2 || t == 3) {
            CHECK(po.verdict_margin_min < 1.2 && 1.2 < po.verdict_margin_compact, "default margins %.2f, %.2f",
                  po.verdict_margin_min, po.verdict_margin_compact);
            sasnav_pair_result first = r, fin;
            first.margin = 1.2;
            CHECK_OK(sasnav_pair_finish(pair, &first, &fin));
            printf("point target, margin 1.2, compact margin %.2f: verdict %s\n", pc.verdict_margin_compact,
                   sasnav_verdict_name(fin.verdict));
            CHECK(!fin.coincidence && fin.verdict == (t == 2 ? SASNAV_VERDICT_AMBIGUOUS : SASNAV_VERDICT_OK),
                  "compact margin %.2f, margin 1.2: verdict %s", pc.verdict_margin_compact,
                  sasnav_verdict_name(fin.verdict));
        }
        sasnav_pair_destroy(pair);
    }
    /* The verdict's gate reads q's image too (opts.verdict_contrast on the
     * larger of contrast and contrast_q): the point target's pair in both
     * orders, from the truth, with the gate set between the two images'
     * contrasts. In the order where q's image is the more contrasted
     * (asserted to exist: the two pings see the reflector at different
     * angles) p's contrast alone is under the gate, and the compact rules
     * must still apply (a coincidence, "ambiguous"); with the gate above
     * both they do not ("ok": estimate_from has no margin to fail). */
    int q_higher = 0;
    for (int order = 0; order < 2; order++) {
        int a = order ? 9 : 8, b = order ? 8 : 9;
        sasnav_pose dt = sasnav_ping_displacement(&run->truth[a], &run->truth[b]),
                    dn = sasnav_ping_displacement(&run->nav[a], &run->nav[b]);
        sasnav_pose start = {dt.x - dn.x, dt.y - dn.y, dt.theta - dn.theta};
        double c = 0, cq = 0;
        for (int t = 0; t < 3; t++) {
            sasnav_pair_opts pc = po;
            if (t == 1) pc.verdict_contrast = 0.5 * (c + cq);
            if (t == 2) pc.verdict_contrast = 1.01 * (c > cq ? c : cq);
            pair = NULL;
            CHECK_OK(sasnav_pair_create(&run->sys, &run->array, &run->win, &pc, &pair));
            if (!pair) continue;
            CHECK_OK(sasnav_pair_set_data(pair, sasnav_run_ping(run, a), sasnav_run_ping(run, b), dn));
            CHECK_OK(sasnav_pair_estimate_from(pair, start, &r));
            sasnav_pair_destroy(pair);
            if (t == 0) {
                c = r.contrast;
                cq = r.contrast_q;
                printf("point target, pings %d -> %d: contrast %.2f, q's %.2f\n", a, b, c, cq);
                CHECK(cq > po.joint_contrast_max && fabs(cq - c) > 1e-3 * c, "pings %d -> %d: contrasts %.3f, %.3f",
                      a, b, c, cq);
                q_higher += cq > c;
                continue;
            }
            int flag = t == 1;
            printf("  gate %.2f: verdict %s, coincidence %d\n", pc.verdict_contrast, sasnav_verdict_name(r.verdict),
                   r.coincidence);
            CHECK(r.contrast == c && r.contrast_q == cq, "pings %d -> %d: contrasts moved with the gate", a, b);
            CHECK(r.coincidence == flag && r.verdict == (flag ? SASNAV_VERDICT_AMBIGUOUS : SASNAV_VERDICT_OK),
                  "pings %d -> %d, gate %.2f between %.2f and %.2f: coincidence %d, verdict %s", a, b,
                  pc.verdict_contrast, c, cq, r.coincidence, sasnav_verdict_name(r.verdict));
        }
    }
    CHECK(q_higher == 1, "q's image the more contrasted in %d of the 2 orders", q_higher);
    /* The same pair given channel by channel (set_data_channels, each
     * channel with the EPCA geometry): the rule then reads each channel's
     * phase centres. With q's channels placed a quarter spacing further
     * along in q's frame, the estimated displacement moves a quarter
     * spacing back (the echoes put the phase centres where they were), so
     * the phase centres still meet while the displacement is no longer near
     * a multiple of the spacing: the rule must follow the phase centres
     * (the test of multiples of the spacing, the rule before, says no). */
    for (int t = 0; t < 2; t++) {
        sasnav_pair_opts pc = po;
        pc.verdict_coincidence = 0.1;
        pair = NULL;
        CHECK_OK(sasnav_pair_create(&run->sys, &run->array, &run->win, &pc, &pair));
        if (!pair) continue;
        int n = run->array.n_rx;
        sasnav_ping_pose chp[SASNAV_MAX_RX], chq[SASNAV_MAX_RX];
        double d = 0.5 * (run->array.rx_u[1] - run->array.rx_u[0]);
        for (int l = 0; l < n; l++) {
            chp[l] = chq[l] = sasnav_epca_local(run->tx_lag, 0.0);
            if (t == 1) { /* q's transmitter and array a quarter spacing further on */
                chq[l].tx.x += 0.25 * d;
                chq[l].array.x += 0.25 * d;
            }
        }
        CHECK_OK(sasnav_pair_set_data_channels(pair, sasnav_run_ping(run, 8), sasnav_run_ping(run, 9),
                                               sasnav_ping_displacement(&run->nav[8], &run->nav[9]), chp,
                                               chq));
        sasnav_pose dt = sasnav_ping_displacement(&run->truth[8], &run->truth[9]),
                    dn = sasnav_ping_displacement(&run->nav[8], &run->nav[9]);
        CHECK_OK(sasnav_pair_estimate_from(pair, (sasnav_pose){dt.x - dn.x, dt.y - dn.y, dt.theta - dn.theta},
                                           &r));
        /* expected from the displacement and the layouts above: q's phase
         * centres at (l + t / 4) d + x, p's at l d (common offset aside) */
        double u = r.displacement.x / d + 0.25 * t, m = nearbyint(u);
        double cmax = r.contrast_q > r.contrast ? r.contrast_q : r.contrast;
        int expect = cmax > pc.verdict_contrast && fabs(m) < n && fabs(u - m) < 0.1;
        printf("point target by channels, q moved %.2f spacing: displacement %.3f spacings, coincidence %d\n",
               0.25 * t, r.displacement.x / d, r.coincidence);
        CHECK(r.coincidence == expect, "by channels, q moved %.2f: coincidence %d, expected %d", 0.25 * t,
              r.coincidence, expect);
        if (t == 1)
            CHECK(expect != (fabs(r.displacement.x / d - nearbyint(r.displacement.x / d)) < 0.1),
                  "the moved layout does not tell the phase centres from the mean spacing "
                  "(displacement %.3f spacings)", r.displacement.x / d);
        sasnav_pair_destroy(pair);
    }
    sasnav_run_free(run);

    /* Unrelated scenes: ping 1 of one speckle draw against ping 0 of another. */
    sasnav_run *a = simulate((sasnav_pose){0.005, 0.002, 0.004}, 1);
    sasnav_run *b = simulate((sasnav_pose){0.005, 0.002, 0.004}, 2);
    if (a && b) {
        pair = NULL;
        po.range = a->range_of_interest;
        po.tx_lag = a->tx_lag;
        CHECK_OK(sasnav_pair_create(&a->sys, &a->array, &a->win, &po, &pair));
        if (pair) {
            CHECK_OK(sasnav_pair_set_data(pair, sasnav_run_ping(a, 0), sasnav_run_ping(b, 1),
                                          sasnav_ping_displacement(&a->nav[0], &a->nav[1])));
            CHECK_OK(sasnav_pair_estimate(pair, &r));
            printf("unrelated scenes: verdict %s, eta %.3f\n", sasnav_verdict_name(r.verdict), r.eta);
            CHECK(r.verdict == SASNAV_VERDICT_FAILED, "unrelated pings judged %s (eta %.3f)",
                  sasnav_verdict_name(r.verdict), r.eta);
        }
        sasnav_pair_destroy(pair);
        /* A speckle seabed is not compact: even a tolerance of half a
         * spacing flags nothing there (the contrast gate), nor does a
         * compact scene's margin of 100 (finished from a first result
         * whose margin is set to 1.2, above verdict_margin_min). */
        sasnav_pair_opts pc = po;
        pc.verdict_coincidence = 0.5;
        pc.verdict_margin_compact = 100.0;
        pair = make_pair_opts(a, &pc);
        if (pair) {
            CHECK_OK(sasnav_pair_estimate_from(pair, (sasnav_pose){0.005, 0.002, 0.004}, &r));
            printf("speckle pair: contrast %.2f, verdict %s, coincidence %d\n", pair_contrast(pair),
                   sasnav_verdict_name(r.verdict), r.coincidence);
            CHECK(pair_contrast(pair) <= pc.verdict_contrast && !r.coincidence && r.verdict == SASNAV_VERDICT_OK,
                  "speckle pair: contrast %.2f, coincidence %d, verdict %s", pair_contrast(pair), r.coincidence,
                  sasnav_verdict_name(r.verdict));
            sasnav_pair_result first = r, fin;
            first.margin = 1.2;
            CHECK_OK(sasnav_pair_finish(pair, &first, &fin));
            CHECK(fin.verdict == SASNAV_VERDICT_OK, "speckle pair, margin 1.2, compact margin 100: verdict %s",
                  sasnav_verdict_name(fin.verdict));
        }
        sasnav_pair_destroy(pair);
    }
    sasnav_run_free(a);
    sasnav_run_free(b);
    CHECK(!strcmp(sasnav_verdict_name(SASNAV_VERDICT_NO_OVERLAP), "no_overlap") &&
              !strcmp(sasnav_verdict_name(42), "unknown"),
          "verdict names");
}

/* The search grid (opts.search_grid). (1) The paper's case with the search
 * forced onto full pixels: within the same bounds as check_recovery's
 * default (coarse) search, and reported FINE. (2) The compact scene of
 * check_verdict, now with a final stage (k, i above the coarse ones, so the
 * grid is chosen): AUTO takes full pixels there (a point target's contrast
 * is far above joint_contrast_max), and the search forced onto the coarse
 * grid must not pass the pair as "ok" either. */
/* The point preset's pair 8 -> 9 with cheap final iterations (k = 3, i =
 * 2; the verdict is the search's) on a 0.6 m range extent, the options in
 * *po (their k, i, range extent, range and offset set here); NULL (and a
 * failed check) when it cannot be made. */
static sasnav_pair *point_pair(const sasnav_run *run, sasnav_pair_opts *po)
{
    po->k = 3;
    po->i = 2;
    po->range_extent = 0.6;
    po->range = run->range_of_interest;
    po->tx_lag = run->tx_lag;
    sasnav_pair *pair = NULL;
    CHECK_OK(sasnav_pair_create(&run->sys, &run->array, &run->win, po, &pair));
    if (pair) CHECK_OK(sasnav_pair_set_data(pair, sasnav_run_ping(run, 8), sasnav_run_ping(run, 9),
                                            sasnav_ping_displacement(&run->nav[8], &run->nav[9])));
    return pair;
}

static void check_search_grid(void)
{
    sasnav_pose truth = {-0.0345, 0.0217, 0.041};
    sasnav_run *run = simulate(truth, 1);
    sasnav_pair_opts po;
    sasnav_pair_default_opts(&po);
    po.search_grid = SASNAV_SEARCH_FINE;
    sasnav_pair *pair = run ? make_pair_opts(run, &po) : NULL;
    sasnav_pair_result r;
    if (pair) {
        CHECK_OK(sasnav_pair_estimate(pair, &r));
        printf("paper case, full-pixel search: error (%.3f mm, %.4f mm, %.1e rad)\n",
               1e3 * (r.error.x - truth.x), 1e3 * (r.error.y - truth.y), r.error.theta - truth.theta);
        CHECK(r.search_grid == SASNAV_SEARCH_FINE, "search grid %s", sasnav_search_grid_name(r.search_grid));
        CHECK(fabs(r.error.x - truth.x) <= 5e-4 && fabs(r.error.y - truth.y) <= 2e-4 &&
                  fabs(r.error.theta - truth.theta) <= 5e-4 && r.verdict == SASNAV_VERDICT_OK,
              "full-pixel search: error (%.3f mm, %.4f mm, %.2e rad), verdict %s", 1e3 * (r.error.x - truth.x),
              1e3 * (r.error.y - truth.y), r.error.theta - truth.theta, sasnav_verdict_name(r.verdict));
    }
    sasnav_pair_destroy(pair);
    sasnav_run_free(run);

    run = point_run();
    if (!run) return;
    for (int g = 0; g < 2; g++) {
        sasnav_pair_default_opts(&po);
        po.search_grid = g == 0 ? SASNAV_SEARCH_AUTO : SASNAV_SEARCH_COARSE;
        pair = point_pair(run, &po);
        if (!pair) continue;
        CHECK_OK(sasnav_pair_estimate(pair, &r));
        printf("point target, search grid %s: %s, verdict %s, margin %.3f\n",
               sasnav_search_grid_name(po.search_grid), sasnav_search_grid_name(r.search_grid),
               sasnav_verdict_name(r.verdict), r.margin);
        CHECK(r.search_grid == (g == 0 ? SASNAV_SEARCH_FINE : SASNAV_SEARCH_COARSE), "grid %s used (asked %s)",
              sasnav_search_grid_name(r.search_grid), sasnav_search_grid_name(po.search_grid));
        CHECK(r.verdict != SASNAV_VERDICT_OK, "compact-scene pair judged ok with the %s search",
              sasnav_search_grid_name(r.search_grid));
        sasnav_pair_destroy(pair);
    }
    sasnav_run_free(run);
}

/* Per-ping Tx-array offsets: a noise-free pair simulated with exact EPCA
 * geometry whose second ping has a 4 mm longer offset (a ping made 4 %
 * faster). Told the offsets (set_data_lags), the estimator recovers the
 * yaw within 8e-5 rad (measured 4.9e-5: its accuracy on such a pair, cf.
 * 1-2e-4 on the draws of check_recovery); with the common offset
 * (set_data) the unmodelled difference biases it by more than twice as
 * much (measured 1.5e-4 rad).
 * Bad offsets are refused. */
static void check_lags(void)
{
    sasnav_scenario sc;
    sasnav_scenario_preset("paper-pair", &sc);
    sc.snr_db = INFINITY;
    sasnav_pose truth = {0.004, -0.003, 0.006};
    sasnav_run *run = simulate(truth, 3);
    if (!run) return;
    /* Re-simulate ping 1 with a longer offset around the same centroid. */
    double lag_q = run->tx_lag + 0.004;
    sasnav_ping_pose local_q = sasnav_epca_local(lag_q, 0.0);
    sasnav_pose cq = sasnav_ping_centroid(&run->truth[1]);
    run->truth[1] = sasnav_ping_place(cq, &local_q);
    sasnav_scene *scene = NULL;
    sc.ripples.seed = 3; /* the scene simulate() drew */
    CHECK_OK(sasnav_scene_ripples(&sc.ripples, &scene));
    if (scene) CHECK_OK(sasnav_simulate_raw(&sc, scene, run->truth, run, NULL));
    sasnav_scene_free(scene);
    sasnav_pair_opts po;
    sasnav_pair_default_opts(&po);
    if (reduced) po.k = po.i = 2;
    po.range = run->range_of_interest;
    po.tx_lag = run->tx_lag;
    sasnav_pair *pair = NULL;
    CHECK_OK(sasnav_pair_create(&run->sys, &run->array, &run->win, &po, &pair));
    if (!pair) {
        sasnav_run_free(run);
        return;
    }
    sasnav_pose nominal = sasnav_ping_displacement(&run->nav[0], &run->nav[1]);
    sasnav_pose d = sasnav_ping_displacement(&run->truth[0], &run->truth[1]);
    sasnav_pose t = {d.x - nominal.x, d.y - nominal.y, d.theta - nominal.theta};
    sasnav_pair_result common, own;
    CHECK_OK(sasnav_pair_set_data(pair, sasnav_run_ping(run, 0), sasnav_run_ping(run, 1), nominal));
    CHECK_OK(sasnav_pair_estimate(pair, &common));
    CHECK_OK(sasnav_pair_set_data_lags(pair, sasnav_run_ping(run, 0), sasnav_run_ping(run, 1), nominal,
                                       run->tx_lag, lag_q));
    CHECK_OK(sasnav_pair_estimate(pair, &own));
    double e_common = fabs(common.error.theta - t.theta), e_own = fabs(own.error.theta - t.theta);
    printf("offsets %.3f / %.3f m: yaw error with the common offset %.2e rad, with each ping's %.2e rad\n",
           run->tx_lag, lag_q, e_common, e_own);
    if (!reduced) {
        CHECK(e_own < 8e-5, "own offsets: yaw error %.2e rad", e_own);
        CHECK(e_common > 2.0 * e_own, "common offset: yaw error %.2e not above own %.2e", e_common, e_own);
    }
    CHECK(sasnav_pair_set_data_lags(pair, sasnav_run_ping(run, 0), sasnav_run_ping(run, 1), nominal, -0.1,
                                    0.1) == SASNAV_ERR_ARG,
          "negative offset accepted");
    CHECK(sasnav_pair_set_data_lags(pair, sasnav_run_ping(run, 0), sasnav_run_ping(run, 1), nominal, 0.1,
                                    NAN) == SASNAV_ERR_ARG,
          "NaN offset accepted");
    sasnav_pair_destroy(pair);
    sasnav_run_free(run);
}

/* An estimator of the default system with a small uniform array (8
 * elements of 5 cm) and a 9-11 m window, for checks that need one but no
 * data. */
static int small_pair(const sasnav_pair_opts *o, sasnav_pair **pr)
{
    sasnav_system sys;
    sasnav_system_default(&sys);
    sasnav_array a;
    sasnav_array_uniform(&a, 8, 0.05, 0.05, 0.05);
    sasnav_window w;
    sasnav_window_for_ranges(&sys, 9.0, 11.0, 8, &w);
    return sasnav_pair_create(&sys, &a, &w, o, pr);
}

/* Option rules in the library (they were the CLI's alone): each bad option
 * or combination refused with SASNAV_ERR_ARG and a message naming it; the
 * defaults pass; coarse iterations above the final ones are lowered. */
static void check_opts_rules(void)
{
    sasnav_pair_opts o;
    sasnav_pair_default_opts(&o);
    CHECK(sasnav_pair_opts_check(&o) == SASNAV_OK, "defaults refused: %s", sasnav_last_error());
    CHECK(o.final_criterion == SASNAV_FINAL_AUTO, "default final criterion %d", o.final_criterion);
    for (int c = SASNAV_FINAL_ETA; c <= SASNAV_FINAL_AUTO; c++)
        CHECK(sasnav_final_criterion_parse(sasnav_final_criterion_name(c)) == c, "criterion %d's name", c);
    CHECK(sasnav_final_criterion_parse("best") == -1 && sasnav_final_criterion_parse(NULL) == -1,
          "an unknown criterion name accepted");
    CHECK(o.search_grid == SASNAV_SEARCH_AUTO, "default search grid %d", o.search_grid);
    for (int g = SASNAV_SEARCH_AUTO; g <= SASNAV_SEARCH_COARSE; g++)
        CHECK(sasnav_search_grid_parse(sasnav_search_grid_name(g)) == g, "search grid %d's name", g);
    CHECK(sasnav_search_grid_parse("finest") == -1 && sasnav_search_grid_parse(NULL) == -1 &&
              !strcmp(sasnav_search_grid_name(9), "unknown"),
          "an unknown search grid name accepted");
    static const char *const says[] = {"fix_yaw and yaw_sigma", "k = 0", "surge_sigma", "tx_lag",
                                       "final_criterion = 7", "joint_k = 0", "joint_mu", "joint_eta_ratio 0.9",
                                       "joint_shift_max", "joint_contrast_max", "search_grid 3"};
    for (int c = 0; c < 11; c++) {
        sasnav_pair_default_opts(&o);
        if (c == 0) { o.fix_yaw = 1; o.yaw_sigma = 1e-3; }
        if (c == 1) o.k = 0;
        if (c == 2) o.surge_sigma = NAN;
        if (c == 3) o.tx_lag = -0.1;
        if (c == 4) o.final_criterion = 7;
        if (c == 5) o.joint_k = 0;
        if (c == 6) o.joint_mu = -1;
        if (c == 7) o.joint_eta_ratio = 0.9;
        if (c == 8) o.joint_shift_max = INFINITY;
        if (c == 9) o.joint_contrast_max = NAN;
        if (c == 10) o.search_grid = 3;
        CHECK(sasnav_pair_opts_check(&o) == SASNAV_ERR_ARG && strstr(sasnav_last_error(), says[c]),
              "case %d should be refused naming '%s': %s", c, says[c], sasnav_last_error());
    }
    /* coarse_k = 5 > k = 3: created, with coarse_k lowered to 3 */
    sasnav_pair_default_opts(&o);
    o.k = 3;
    o.coarse_k = 5;
    sasnav_pair *pr = NULL;
    CHECK(small_pair(&o, &pr) == SASNAV_OK, "create: %s", sasnav_last_error());
    if (pr) CHECK(sasnav_pair_options(pr)->coarse_k == 3, "coarse_k %d, expected 3",
                  sasnav_pair_options(pr)->coarse_k);
    sasnav_pair_destroy(pr);
}

/* Range sub-intervals (sasnav_pair_estimate_intervals, once the CLI's
 * alone): interval s of n must be exactly the estimate that a direct
 * create / set_data / estimate gives with the options built by hand from
 * the definition (centre R - E/2 + (s + 1/2) E/n, extent E/n, Tx-array
 * offset speed x 2 R_s / c for the motion model); the same bits, since it
 * is the same computation. Cheap options (coarse iterations, no global
 * stage): the test is of the bookkeeping, not of accuracy. */
static void check_intervals(void)
{
    sasnav_scenario sc;
    sasnav_op_opts oo;
    sasnav_op_default_opts(&oo);
    sasnav_run *run = NULL;
    CHECK(sasnav_scenario_preset("paper-pair", &sc) == SASNAV_OK, "preset");
    CHECK(sasnav_simulate(&sc, NULL, &oo, &run) == SASNAV_OK, "simulate: %s", sasnav_last_error());
    if (!run) return;
    run->speed = 2.0;
    sasnav_pair_opts o;
    sasnav_pair_default_opts(&o);
    o.k = o.coarse_k = 2;
    o.i = o.coarse_i = 1;
    o.global_stage = 0;
    o.range = 10.0;
    o.range_extent = 1.2;
    sasnav_pair_interval iv[2];
    CHECK(sasnav_pair_estimate_intervals(run, 0, 1, &o, 2, 1, iv) == SASNAV_OK, "intervals: %s",
          sasnav_last_error());
    sasnav_pose nominal = sasnav_ping_displacement(&run->nav[0], &run->nav[1]);
    for (int s = 0; s < 2; s++) {
        sasnav_pair_opts so = o;
        so.range_extent = 0.6;
        so.range = 9.4 + (s + 0.5) * 0.6;
        so.tx_lag = 2.0 * 2.0 * so.range / run->sys.sound_speed;
        sasnav_pair *pr = NULL;
        sasnav_pair_result r;
        int rc = sasnav_pair_create(&run->sys, &run->array, &run->win, &so, &pr);
        if (!rc) rc = sasnav_pair_set_data(pr, sasnav_run_ping(run, 0), sasnav_run_ping(run, 1), nominal);
        if (!rc) rc = sasnav_pair_estimate(pr, &r);
        sasnav_pair_destroy(pr);
        CHECK(rc == SASNAV_OK && iv[s].status == SASNAV_OK, "interval %d: %d / %d", s, rc, iv[s].status);
        CHECK(fabs(iv[s].range - so.range) < 1e-12 && fabs(iv[s].tx_lag - so.tx_lag) < 1e-12,
              "interval %d: range %g (expected %g), lag %g (expected %g)", s, iv[s].range, so.range,
              iv[s].tx_lag, so.tx_lag);
        CHECK(!rc && iv[s].result.error.x == r.error.x && iv[s].result.error.y == r.error.y &&
                  iv[s].result.error.theta == r.error.theta && iv[s].result.eta == r.eta,
              "interval %d differs from the direct estimate", s);
    }
    /* the motion model without a speed, and bad n: refused */
    run->speed = 0;
    CHECK(sasnav_pair_estimate_intervals(run, 0, 1, &o, 2, 1, iv) == SASNAV_ERR_ARG, "no speed");
    CHECK(sasnav_pair_estimate_intervals(run, 0, 1, &o, 0, 0, iv) == SASNAV_ERR_ARG, "n = 0");
    CHECK(sasnav_pair_estimate_intervals(run, 0, 0, &o, 1, 0, iv) == SASNAV_ERR_ARG, "p = q");
    sasnav_run_free(run);
}

/* The evaluation's projection chains (pair.c, project_chains: both chains
 * through each operator at once, each application shared by a team of the
 * operators' threads) against a slow reference computed here from the
 * plain operator functions, one chain after the other: rho_q = T_q^+ d_q,
 * psi_p = (Q_p Q_q)^i rho_p, psi_q = (Q_q Q_p)^i rho_q with Q x = T^+ T x
 * (sasnav_op_forward, sasnav_cgls), then the error window; to the last
 * bit, for the estimator's level-`level` evaluation just made. */
static void check_chain_reference(sasnav_pair *pr, int level, const char *what)
{
    pair_level *lv = &pr->level[level];
    size_t np = lv->np, nd = pr->nd;
    sasnav_cfloat *x = malloc(sizeof(sasnav_cfloat) * np), *y = malloc(sizeof(sasnav_cfloat) * np);
    sasnav_cfloat *rq = malloc(sizeof(sasnav_cfloat) * np), *d = malloc(sizeof(sasnav_cfloat) * nd);
    if (!x || !y || !rq || !d) {
        CHECK(0, "out of memory");
        goto done;
    }
    sasnav_cgls_opts co = {lv->k, pr->opts.tikhonov};
    CHECK_OK(sasnav_cgls(lv->op_q, pr->data_q, &co, rq, NULL));
    CHECK(!memcmp(rq, lv->rho_q, sizeof(sasnav_cfloat) * np), "%s, level %d: rho_q differs", what, level);
    for (int c = 0; c < 2; c++) {
        memcpy(x, c == 0 ? lv->rho_p : rq, sizeof(sasnav_cfloat) * np);
        for (int s = 0; s < 2 * lv->i; s++) {
            /* psi_p's chain applies Q_q first, psi_q's Q_p */
            sasnav_op *op = (s % 2 == 0) == (c == 0) ? lv->op_q : lv->op_p;
            CHECK_OK(sasnav_op_forward(op, x, d));
            CHECK_OK(sasnav_cgls(op, d, &co, y, NULL));
            memcpy(x, y, sizeof(sasnav_cfloat) * np);
        }
        for (size_t j = 0; j < np; j++) x[j] *= lv->window[j];
        CHECK(!memcmp(x, c == 0 ? lv->psi_p : lv->psi_q, sizeof(sasnav_cfloat) * np),
              "%s, level %d: psi_%c differs from the chain computed one step at a time", what, level,
              c == 0 ? 'p' : 'q');
    }
done:
    free(x);
    free(y);
    free(rq);
    free(d);
}

/* Evaluations with one to four threads (one thread: both chains through
 * each operator at once; two or three: the chains side by side, one thread
 * each; four: a team of four sharing each application) are the plain
 * chains' bits (check_chain_reference) at every level. Then whole
 * estimates: with two or more threads the stages
 * evaluate as many hypotheses at once (search.c, stage_residuals; pair.c,
 * pair_batch: the model's ten points and the valley scan's unevenly over
 * three workers, the global stage's image shifts, the candidates' and slip
 * points' local stages); the estimate, its values and its counts are those
 * of one thread. */
static void check_chain_paths(void)
{
    sasnav_pose truth = {-0.0345, 0.0217, 0.041};
    sasnav_run *run = simulate(truth, 4);
    if (!run) return;
    sasnav_pair_opts po;
    sasnav_pair_default_opts(&po);
    if (reduced) po.k = po.i = 2;
    /* the evaluations below compare the level buffers with the chains
     * computed one step at a time: without the equalising weights
     * (opts.equalise), which multiply the buffers after the chains; the
     * whole estimates further down are made with them (the default) */
    po.equalise = 0;
    po.nthreads = 1;
    sasnav_pair *one = make_pair_opts(run, &po);
    po.nthreads = 2;
    sasnav_pair *two = make_pair_opts(run, &po);
    po.nthreads = 3;
    sasnav_pair *three = make_pair_opts(run, &po);
    po.nthreads = 4;
    sasnav_pair *four = make_pair_opts(run, &po);
    sasnav_pair *est[4] = {one, two, three, four};
    const sasnav_pose at[2] = {{-0.030, 0.021, 0.040}, {-0.0345, 0.0219, 0.0405}};
    for (int level = 0; one && two && three && four && level < 3; level++)
        for (int h = 0; h < 2; h++) {
            double z[4], e[4], o[4];
            for (int m = 0; m < 4; m++) {
                char what[64];
                snprintf(what, sizeof what, "%d thread(s), point %d", m + 1, h);
                CHECK_OK(sasnav_pair_eval(est[m], at[h], level, 0, &z[m], &e[m], &o[m]));
                check_chain_reference(est[m], level, what);
            }
            for (int m = 1; m < 4; m++)
                CHECK(z[0] == z[m] && e[0] == e[m] && o[0] == o[m],
                      "level %d, point %d: one thread zeta %.17g eta %.17g overlap %.17g, %d threads "
                      "%.17g %.17g %.17g", level, h, z[0], e[0], o[0], m + 1, z[m], e[m], o[m]);
        }
    sasnav_pair_destroy(four);
    sasnav_pair_destroy(one);
    sasnav_pair_destroy(two);
    sasnav_pair_destroy(three);
    /* whole estimates with the default options, on the seabed of ripple
     * seed 1, whose search is equalised (a feature stands out of its
     * smoothed intensity; seed 4's does not): the workers must follow the
     * estimator's suspension of the weights, pair_workers */
    sasnav_run_free(run);
    run = simulate(truth, 1);
    if (!run) return;
    sasnav_pair_default_opts(&po);
    if (reduced) po.k = po.i = 2;
    po.nthreads = 1;
    one = make_pair_opts(run, &po);
    po.nthreads = 2;
    two = make_pair_opts(run, &po);
    po.nthreads = 3;
    three = make_pair_opts(run, &po);
    if (one && two && three) {
        sasnav_pair_result r1, rn[2];
        CHECK_OK(sasnav_pair_estimate(one, &r1));
        CHECK_OK(sasnav_pair_estimate(two, &rn[0]));
        CHECK_OK(sasnav_pair_estimate(three, &rn[1]));
        for (int m = 0; m < 2; m++) {
            const sasnav_pair_result *r2 = &rn[m];
            CHECK(r1.error.x == r2->error.x && r1.error.y == r2->error.y &&
                      r1.error.theta == r2->error.theta && r1.eta == r2->eta && r1.zeta == r2->zeta,
                  "estimates differ: one thread (%.9g, %.9g, %.9g) eta %.17g, %d threads (%.9g, %.9g, "
                  "%.9g) eta %.17g",
                  r1.error.x, r1.error.y, r1.error.theta, r1.eta, m + 2, r2->error.x, r2->error.y,
                  r2->error.theta, r2->eta);
            CHECK(r1.evaluations == r2->evaluations && r1.applications == r2->applications,
                  "counts differ: %d / %ld evaluations / applications against %d / %ld (%d threads)",
                  r1.evaluations, r1.applications, r2->evaluations, r2->applications, m + 2);
        }
        CHECK(r1.equalised == 1 && rn[0].equalised == 1 && rn[1].equalised == 1, "the search was not equalised");
    }
    sasnav_pair_destroy(one);
    sasnav_pair_destroy(two);
    sasnav_pair_destroy(three);
    sasnav_run_free(run);
}

/* The joint misfit (pair_eval_joint, the final stage of pairs whose
 * relative yaw is small) against a slow reference: sasnav_cgls on one
 * operator holding both pings' channels (p's EPCA pose for the first N, q's
 * at the hypothesis for the others) and the misfit computed from its image;
 * it is lower at the truth than one phase-centre slip away (surge d and
 * yaw d / R: the points that share as many phase centres); then whole
 * estimates of a small-yaw draw take the joint path (auto), recover the
 * truth within the paper bounds and give the same bits on one and two
 * threads. */
static double joint_reference(sasnav_pair *pr, sasnav_pose err, double lam)
{
    const pair_level *lv = &pr->level[1];
    size_t np = lv->np, nd = lv->nd;
    double *x = malloc(sizeof(double) * np), *y = malloc(sizeof(double) * np);
    sasnav_cfloat *s = malloc(sizeof *s * np), *img = malloc(sizeof *img * 2 * nd), *d = malloc(sizeof *d * 2 * nd);
    double f = NAN;
    sasnav_op *op = NULL;
    if (!x || !y || !s || !img || !d) {
        CHECK(0, "out of memory");
        goto done;
    }
    sasnav_grid_points(&lv->grid, (sasnav_pose){0, 0, 0}, x, y);
    sasnav_array arr2 = pr->array;
    arr2.n_rx = 2 * pr->array.n_rx;
    for (int l = 0; l < pr->array.n_rx; l++) arr2.rx_u[pr->array.n_rx + l] = pr->array.rx_u[l];
    sasnav_op_opts oo = pr->opts.op;
    oo.nthreads = 1;
    CHECK_OK(sasnav_op_create(&pr->sys, &arr2, &pr->win, (int)np, x, y, &oo, &op));
    if (!op) goto done;
    sasnav_pose sigma = {pr->nominal.x + err.x, pr->nominal.y + err.y, pr->nominal.theta + err.theta};
    sasnav_ping_pose ch[SASNAV_MAX_RX];
    for (int l = 0; l < pr->array.n_rx; l++) {
        ch[l] = pr->local_p;
        ch[pr->array.n_rx + l] = sasnav_ping_place(sigma, &pr->local_q);
    }
    CHECK_OK(sasnav_op_set_channels(op, ch));
    memcpy(d, pr->data_p, sizeof *d * nd);
    memcpy(d + nd, pr->data_q, sizeof *d * nd);
    sasnav_cgls_opts co = {pr->opts.joint_k, lam};
    CHECK_OK(sasnav_cgls(op, d, &co, s, NULL));
    CHECK_OK(sasnav_op_forward(op, s, img));
    double e = 0, m = 0, x2 = 0;
    for (size_t j = 0; j < 2 * nd; j++) {
        e += pow(cabsf(d[j] - img[j]), 2);
        m += pow(cabsf(d[j]), 2);
    }
    for (size_t j = 0; j < np; j++) x2 += pow(cabsf(s[j]), 2);
    f = sqrt((e + lam * x2) / m);
done:
    sasnav_op_destroy(op);
    free(x);
    free(y);
    free(s);
    free(img);
    free(d);
    return f;
}

/* sasnav_pair_estimate_first, then sasnav_pair_finish on the same data set
 * again (nothing carried over in the estimator's caches), give
 * sasnav_pair_estimate's estimate to the bit: the final stage runs from the
 * same level-1 point. The first result has no final stage and costs less;
 * a first result that is not finite is refused. */
static void check_two_pass(void)
{
    sasnav_pose truth = {0.012, -0.008, 0.004};
    sasnav_run *run = simulate(truth, 6);
    if (!run) return;
    sasnav_pair_opts po;
    sasnav_pair_default_opts(&po);
    if (reduced) po.k = po.i = 3; /* a final stage of its own */
    po.nthreads = 1;
    sasnav_pair *a = make_pair_opts(run, &po), *b = make_pair_opts(run, &po);
    if (a && b) {
        sasnav_pair_result full, first, fin;
        CHECK_OK(sasnav_pair_estimate(a, &full));
        CHECK_OK(sasnav_pair_estimate_first(b, &first));
        CHECK(first.final_criterion == SASNAV_FINAL_NONE && full.final_criterion != SASNAV_FINAL_NONE,
              "final criteria %s (first pass), %s (one pass)", sasnav_final_criterion_name(first.final_criterion),
              sasnav_final_criterion_name(full.final_criterion));
        CHECK(first.applications < full.applications, "first pass %ld applications, the whole %ld",
              first.applications, full.applications);
        CHECK_OK(sasnav_pair_set_data(b, sasnav_run_ping(run, 0), sasnav_run_ping(run, 1),
                                      sasnav_ping_displacement(&run->nav[0], &run->nav[1])));
        CHECK_OK(sasnav_pair_finish(b, &first, &fin));
        CHECK(!memcmp(&fin.error, &full.error, sizeof fin.error) && fin.eta == full.eta &&
                  fin.overlap == full.overlap && fin.verdict == full.verdict && fin.margin == full.margin &&
                  fin.n_candidates == full.n_candidates && fin.chosen == full.chosen &&
                  fin.final_criterion == full.final_criterion && fin.status == full.status,
              "two passes (%.9g, %.9g, %.9g) eta %.9g %s, one pass (%.9g, %.9g, %.9g) eta %.9g %s", fin.error.x,
              fin.error.y, fin.error.theta, fin.eta, sasnav_verdict_name(fin.verdict), full.error.x, full.error.y,
              full.error.theta, full.eta, sasnav_verdict_name(full.verdict));
        CHECK(fin.applications > first.applications, "costs not carried: %ld after %ld", fin.applications,
              first.applications);
        sasnav_pair_result bad = first;
        bad.error.x = NAN;
        CHECK(sasnav_pair_finish(b, &bad, &fin) == SASNAV_ERR_ARG, "a non-finite first estimate accepted");
        CHECK(sasnav_pair_finish(b, NULL, &fin) == SASNAV_ERR_ARG, "a NULL first estimate accepted");
    }
    sasnav_pair_destroy(a);
    sasnav_pair_destroy(b);
    sasnav_run_free(run);
}

static void check_joint(void)
{
    sasnav_pose truth = {0.012, -0.008, 0.004};
    sasnav_run *run = simulate(truth, 6);
    if (!run) return;
    sasnav_pair_opts po;
    sasnav_pair_default_opts(&po);
    if (reduced) po.k = po.i = 3; /* a final stage of its own (k, i above the coarse 2, 1) */
    po.nthreads = 1;
    sasnav_pair *one = make_pair_opts(run, &po);
    po.nthreads = 2;
    sasnav_pair *two = make_pair_opts(run, &po);
    if (one && two) {
        double d = 0.5 * (run->array.rx_u[1] - run->array.rx_u[0]), range = run->range_of_interest;
        double lam = 0, f[2] = {0, 0};
        CHECK_OK(pair_joint_tikhonov(one, truth, &lam));
        CHECK(lam > 0, "Tikhonov weight %g", lam);
        size_t n = pair_joint_len(one);
        sasnav_cfloat *r = malloc(sizeof *r * n);
        const sasnav_pose at[2] = {truth, {truth.x + d, truth.y, truth.theta + d / range}};
        for (int h = 0; r && h < 2; h++) {
            CHECK_OK(pair_eval_joint(one, at[h], lam, r, &f[h]));
            double ref = joint_reference(one, at[h], lam);
            /* float CGLS in another order of sums: 1e-4 relative */
            CHECK(fabs(f[h] - ref) <= 1e-4 * ref, "point %d: joint misfit %.9g, reference %.9g", h, f[h], ref);
        }
        CHECK(f[0] < f[1], "misfit at the truth %.6g not below one slip away %.6g", f[0], f[1]);
        free(r);
        sasnav_pair_result r1, r2;
        CHECK_OK(sasnav_pair_estimate(one, &r1));
        CHECK_OK(sasnav_pair_estimate(two, &r2));
        CHECK(r1.final_criterion == SASNAV_FINAL_JOINT, "final criterion %s",
              sasnav_final_criterion_name(r1.final_criterion));
        CHECK(r1.error.x == r2.error.x && r1.error.y == r2.error.y && r1.error.theta == r2.error.theta &&
                  r1.eta == r2.eta && r1.applications == r2.applications,
              "one thread (%.9g, %.9g, %.9g) eta %.17g, two threads (%.9g, %.9g, %.9g) eta %.17g", r1.error.x,
              r1.error.y, r1.error.theta, r1.eta, r2.error.x, r2.error.y, r2.error.theta, r2.eta);
        /* the paper bounds (reduced: the coarser bounds of check_recovery) */
        double bs = reduced ? 2e-3 : 5e-4, bw = reduced ? 5e-4 : 2e-4, by = reduced ? 2e-3 : 5e-4;
        CHECK(fabs(r1.error.x - truth.x) <= bs && fabs(r1.error.y - truth.y) <= bw &&
                  fabs(r1.error.theta - truth.theta) <= by,
              "joint estimate off by (%.3f mm, %.4f mm, %.1e rad)", 1e3 * (r1.error.x - truth.x),
              1e3 * (r1.error.y - truth.y), r1.error.theta - truth.theta);
        CHECK(r1.verdict == SASNAV_VERDICT_OK, "verdict %s", sasnav_verdict_name(r1.verdict));
        printf("joint: truth (%.2f mm, %.2f mm, %.4f rad): error (%.3f mm, %.4f mm, %.1e rad), eta %.3f\n",
               1e3 * truth.x, 1e3 * truth.y, truth.theta, 1e3 * (r1.error.x - truth.x),
               1e3 * (r1.error.y - truth.y), r1.error.theta - truth.theta, r1.eta);
        /* AUTO's coverage rule (opts.joint_coverage_min): the default grid
         * covers 0.8 of the element beam's footprint between its first
         * nulls here (1.6 * range * lambda / sqrt(D^2 - lambda^2) of 2 *
         * ...), so the joint stage runs at the default 0.5 and not when
         * the rule asks 0.9 (a survey system's far range: eta's stage). */
        const sasnav_grid *g = sasnav_pair_grid(one);
        double along = (g->nx - 1) * g->dx, cover = along / one->footprint;
        printf("joint: the grid covers %.3f of the beam's footprint (%.3f of %.3f m)\n", cover, along,
               one->footprint);
        CHECK(cover > po.joint_coverage_min && cover < 0.9, "coverage %.3f", cover);
        sasnav_pair_opts pc = po;
        pc.joint_coverage_min = 0.9;
        sasnav_pair *three = make_pair_opts(run, &pc);
        if (three) {
            sasnav_pair_result r3;
            CHECK_OK(sasnav_pair_estimate(three, &r3));
            CHECK(r3.final_criterion == SASNAV_FINAL_ETA, "coverage %.3f under 0.9: final criterion %s", cover,
                  sasnav_final_criterion_name(r3.final_criterion));
        }
        sasnav_pair_destroy(three);
    }
    sasnav_pair_destroy(one);
    sasnav_pair_destroy(two);
    sasnav_run_free(run);
}

/* sasnav_pair_rejudge: the verdict again from a result's fields, as the
 * rules of docs/estimator.md "Verdict" state them (here with the
 * estimator's own option values), for a result that took another
 * estimate's margin (sasnav_pair_result_carry): the retry of a
 * multi-transmitter pair without a gyro. Needs no data. */
static void check_rejudge(void)
{
    sasnav_pair_opts o;
    sasnav_pair_default_opts(&o);
    sasnav_pair *pr = NULL;
    CHECK_OK(small_pair(&o, &pr));
    if (!pr) return;
    const sasnav_pair_opts *po = sasnav_pair_options(pr);
    double m_min = po->verdict_margin_min, m_cpt = po->verdict_margin_compact, gate = po->verdict_contrast;
    CHECK(m_cpt > m_min, "the compact margin %.3f is not above the margin %.3f", m_cpt, m_min);
    sasnav_pair_result base;
    memset(&base, 0, sizeof base);
    base.status = SASNAV_OK;
    base.overlap = 1.0;
    base.eta = 0.5 * po->verdict_eta_max;
    base.margin = 0.5 * (m_min + m_cpt); /* between the two margins */
    base.contrast = base.contrast_q = 0.5 * gate;
    base.verdict = SASNAV_VERDICT_OK;
    struct {
        const char *what;
        int field;
        double value;
        int want;
    } cases[] = {
        {"speckle, margin between the two", 0, 0, SASNAV_VERDICT_OK},
        {"p's image compact", 1, 1.5, SASNAV_VERDICT_AMBIGUOUS},
        {"q's image compact", 2, 1.5, SASNAV_VERDICT_AMBIGUOUS},
        {"margin under the minimum", 3, 0.9, SASNAV_VERDICT_AMBIGUOUS},
        {"eta over the bound", 4, 2.5, SASNAV_VERDICT_FAILED},
        {"not converged", 5, 0, SASNAV_VERDICT_FAILED},
        {"no overlap", 6, 0, SASNAV_VERDICT_NO_OVERLAP},
        {"at a coincidence, speckle", 7, 0, SASNAV_VERDICT_AMBIGUOUS},
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        sasnav_pair_result r = base;
        r.verdict = cases[c].want == SASNAV_VERDICT_OK ? SASNAV_VERDICT_AMBIGUOUS : SASNAV_VERDICT_OK;
        switch (cases[c].field) {
        case 1: r.contrast = cases[c].value * gate; break;
        case 2: r.contrast_q = cases[c].value * gate; break;
        case 3: r.margin = cases[c].value * m_min; break;
        case 4: r.eta = cases[c].value * base.eta; break;
        case 5: r.status = SASNAV_ERR_NOT_CONVERGED; break;
        case 6: r.overlap = 0.0; break;
        case 7: r.coincidence = 1; break;
        default: break;
        }
        sasnav_pair_rejudge(pr, &r);
        CHECK(r.verdict == cases[c].want, "rejudge, %s: %s, expected %s", cases[c].what,
              sasnav_verdict_name(r.verdict), sasnav_verdict_name(cases[c].want));
    }
    sasnav_pair_destroy(pr);
}


/* The equalised search (opts.equalise): refused when negative or not
 * finite; off on a compact scene (a point target: the gate, contrast above
 * verdict_contrast) and on a seabed where nothing stands out (ripple seed
 * 4 without the disc: the peak gate), whose estimates are then the bits
 * of equalise = 0; on on the paper pair's seabed (seed 1), whose estimate
 * stays within the bounds either way (the final stage is
 * unweighted), and with the same gate peak at a wider smoothing. Its purpose,
 * a pair whose search a bright feature led astray, is tested from the
 * command line (tests/cli_equalise.sh). */
static void check_equalise(void)
{
    sasnav_pair_opts o;
    const double bad[] = {-0.01, NAN, INFINITY};
    for (int j = 0; j < 3; j++) {
        sasnav_pair_default_opts(&o);
        o.equalise = bad[j];
        CHECK(sasnav_pair_opts_check(&o) == SASNAV_ERR_ARG && strstr(sasnav_last_error(), "equalise"),
              "equalise %g accepted (or the message does not name it)", bad[j]);
    }
    sasnav_pair_default_opts(&o);
    CHECK(o.equalise == 0.05, "default equalise %g", o.equalise);

    sasnav_pose truth = {-0.0345, 0.0217, 0.041};
    sasnav_run *run = simulate(truth, 1);
    if (!run) return;
    /* the default, a wider smoothing of the weights (the gate reads its
     * peak at its own 5 cm whatever the weights' smoothing: the same peak;
     * read at 10 cm it would be about 0.7x, under the gate), and off */
    const double blurs[] = {0.05, 0.1, 0};
    float peak_default = -1;
    for (int b = 0; b < 3; b++) {
        int on = blurs[b] > 0;
        sasnav_pair_default_opts(&o);
        if (reduced) o.k = o.i = 2;
        o.equalise = blurs[b];
        sasnav_pair *pair = make_pair_opts(run, &o);
        sasnav_pair_result r;
        if (!pair) continue;
        CHECK_OK(sasnav_pair_estimate(pair, &r));
        if (b == 0) peak_default = r.equalise_peak;
        if (b == 1)
            CHECK(peak_default > 0 && r.equalise_peak == peak_default, "paper case: the gate's peak %.3f with the weights smoothed at "
                  "10 cm, %.3f at 5 cm (it should not depend on the weights' smoothing)",
                  r.equalise_peak, peak_default);
        printf("paper case, equalise %g: equalised %d, error (%.3f mm, %.4f mm, %.1e rad), contrasts %.2f / %.2f, "
               "peak %.2f\n",
               o.equalise, r.equalised, 1e3 * (r.error.x - truth.x), 1e3 * (r.error.y - truth.y),
               r.error.theta - truth.theta, pair->level[1].contrast, pair->level[1].contrast_q0,
               r.equalise_peak);
        CHECK(r.equalised == on, "paper case, equalise %g: equalised %d", o.equalise, r.equalised);
        double tol = reduced ? 3 : 1; /* the sanitised build's k = i = 2 */
        CHECK(fabs(r.error.x - truth.x) <= tol * 5e-4 && fabs(r.error.y - truth.y) <= tol * 2e-4 &&
                  fabs(r.error.theta - truth.theta) <= tol * 5e-4,
              "paper case, equalise %g: error (%.3f mm, %.4f mm, %.2e rad)", o.equalise,
              1e3 * (r.error.x - truth.x), 1e3 * (r.error.y - truth.y), r.error.theta - truth.theta);
        sasnav_pair_destroy(pair);
    }
    sasnav_run_free(run);

    /* ripple seed 4 without the disc: speckle and ripples, nothing
     * standing out of the smoothed intensity (its peak about 3 times the
     * mean, far under the gate's 8; with the preset's disc the paper-pair
     * seeds 1-12 peak at 7.5-11.5, at the gate): not equalised, the bits
     * of equalise = 0 */
    {
        sasnav_scenario sc;
        sasnav_scenario_preset("paper-pair", &sc);
        sc.snr_db = INFINITY;
        sc.traj.pair_error = truth;
        sc.ripples.seed = 4;
        sc.ripples.disc_radius = 0;
        run = NULL;
        CHECK_OK(sasnav_simulate(&sc, NULL, NULL, &run));
    }
    if (!run) return;
    sasnav_pair_result rs[2];
    memset(rs, 0, sizeof rs);
    for (int on = 1; on >= 0; on--) {
        sasnav_pair_default_opts(&o);
        if (reduced) o.k = o.i = 2;
        if (!on) o.equalise = 0;
        sasnav_pair *pair = make_pair_opts(run, &o);
        if (!pair) continue;
        CHECK_OK(sasnav_pair_estimate(pair, &rs[on]));
        sasnav_pair_destroy(pair);
    }
    printf("speckle seabed (ripple seed 4, no disc): peak %.2f, equalised %d\n", rs[1].equalise_peak,
           rs[1].equalised);
    /* under 6: the disc-free pairs of paper-trajectory runs peak at
     * 2.5-5.6 (docs/estimator.md, "the peak gate"); 8 is the gate */
    CHECK(rs[1].equalise_peak > 1 && rs[1].equalise_peak < 6 && rs[1].equalised == 0,
          "speckle seabed: peak %.2f, equalised %d", rs[1].equalise_peak, rs[1].equalised);
    CHECK(rs[0].error.x == rs[1].error.x && rs[0].error.y == rs[1].error.y &&
              rs[0].error.theta == rs[1].error.theta && rs[0].eta == rs[1].eta,
          "speckle seabed: the estimate depends on equalise although the gate is closed");
    sasnav_run_free(run);

    run = point_run();
    if (!run) return;
    sasnav_pair_result r[2];
    memset(r, 0, sizeof r);
    for (int on = 1; on >= 0; on--) {
        sasnav_pair_default_opts(&o);
        if (!on) o.equalise = 0;
        sasnav_pair *pair = point_pair(run, &o);
        if (!pair) continue;
        CHECK_OK(sasnav_pair_estimate(pair, &r[on]));
        CHECK(r[on].equalised == 0 && sasnav_pair_result_contrast(&r[on]) > o.verdict_contrast,
              "point target: equalised %d (contrast %.2f)", r[on].equalised, sasnav_pair_result_contrast(&r[on]));
        sasnav_pair_destroy(pair);
    }
    CHECK(r[0].error.x == r[1].error.x && r[0].error.y == r[1].error.y && r[0].error.theta == r[1].error.theta &&
              r[0].eta == r[1].eta && r[0].verdict == r[1].verdict,
          "point target: the estimate depends on equalise although the gate is closed");
    sasnav_run_free(run);
}

int main(void)
{
    check_equalise();
    check_rejudge();
    check_opts_rules();
    check_joint();
    check_two_pass();
    check_chain_paths();
    if (!reduced) check_intervals();
    check_lags();
    check_verdict();
    if (!reduced) check_search_grid();
    check_fixed_yaw();
    check_error_functions();
    check_recovery((sasnav_pose){-0.0345, 0.0217, 0.041}, 1); /* the paper's case */
    if (!reduced) check_recovery((sasnav_pose){0.0281, -0.0143, -0.0322}, 9); /* another draw */
    return test_summary("test_estimator");
}
