/* Where the pair estimator's errors come from (docs/estimator.md, "What the
 * remaining errors are not"): the pairs of seeded paper-trajectory runs
 * (true bistatic Tx and array poses, as `sasnav simulate --preset
 * paper-trajectory --seed S`) estimated each alone with four models of the
 * pings' Tx-array geometry, on the same data:
 *   fixed  the EPCA model with the run's fixed Tx-array offset (what
 *          `sasnav navigate --no-aiding` uses)
 *   lags   the EPCA model with each ping's true offset (an oracle of what
 *          the speed-scaled offsets estimate, docs/navigation.md)
 *   yaw    the same plus each ping's true Tx yaw relative to its array
 *   full   each ping's true Tx and array poses in its centroid frame (an
 *          oracle: nothing of the geometry left to model)
 * With `full` and `--snr inf` what remains is the criterion's own error on
 * this scene: not noise, not the geometry.
 *
 * usage: bench_bias [--seeds S0 N] [--snr DB|inf] [--models fixed,lags,yaw,full]
 *                   [--range-extent M] [--cross-extent M] [--error-extent M]
 *                   [--k K] [--i I] [--scene-range Y0,Y1] [--disc-amplitude A]
 *                   [--threads T] [--quiet] [--gpu]
 *
 * --scene-range puts the ripple seabed between ranges Y0 and Y1 (the
 * preset's 9-11 m by default) and widens the recorded swath to hold it:
 * with the grid's --range-extent it measures how the criterion's yaw
 * error depends on the range span of seabed the grid sees
 * (docs/estimator.md, "The yaw floor is the seabed's range span").
 *
 * --disc-amplitude sets the bright disc's rms amplitude (the preset's 4;
 * 16 puts it 24 dB above the ripple seabed: docs/validation.md, "A bright
 * feature entering the beam").
 *
 * --gpu: the error evaluations on a CUDA GPU (builds with -DSASNAV_CUDA=ON;
 * the CPU's estimates to float rounding, docs/estimator.md "GPU").
 *
 * Seeds follow `sasnav simulate --seed S` (scene 3S+1, trajectory 3S+2,
 * noise 3S+3). Pairs run in parallel (one estimator per thread, one
 * thread each): the same bits for any thread count. Prints each pair's
 * error (surge mm, sway mm, yaw rad) per model, then per model and over
 * all pairs: rms, median and 95th percentile of |error|, and the final
 * sway that the per-pair errors alone give each run (the estimated
 * displacements composed from the first ping against the true ones,
 * expressed in the first ping's frame; no resolution, no alignment:
 * the "paper" way) with the runs within lambda/25, and which way the
 * errors lie (the yaw errors' correlation with the surge and sway
 * errors, the sway per unit yaw). For independent
 * per-pair yaw errors of rms s over n pairs of step L the final sway has
 * an rms of s L sqrt(sum_{k<n} k^2) (6.4 m x s for paper-trajectory);
 * printed as "yaw-only prediction". */
#include "sasnav/error.h"
#include "sasnav/estimator.h"
#include "sasnav/geometry.h"
#include "sasnav/model.h"
#include "sasnav/run.h"
#include "sasnav/sim.h"
#include "bench_util.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { G_FIXED, G_LAGS, G_YAW, G_FULL, N_MODELS };
static const char *const model_names[N_MODELS] = {"fixed", "lags", "yaw", "full"};

/* Channel geometries of one ping for model m (local: the true local ping). */
static sasnav_ping_pose model_local(int m, const sasnav_ping_pose *local)
{
    double lag = local->array.x - local->tx.x;
    if (m == G_YAW) return sasnav_epca_local(lag, local->tx.theta - local->array.theta);
    return *local;
}

static int estimate(const sasnav_run *run, const sasnav_pair_opts *po, int m, int p, sasnav_pose *err,
                    int *verdict)
{
    int q = p + 1;
    sasnav_pair *pr = NULL;
    int rc = sasnav_pair_create(&run->sys, &run->array, &run->win, po, &pr);
    if (rc) return rc;
    const sasnav_cfloat *dp = sasnav_run_ping(run, p), *dq = sasnav_run_ping(run, q);
    sasnav_pose nominal = sasnav_ping_displacement(&run->nav[p], &run->nav[q]);
    sasnav_ping_pose lp = sasnav_ping_local(&run->truth[p]), lq = sasnav_ping_local(&run->truth[q]);
    if (m == G_FIXED) rc = sasnav_pair_set_data_lags(pr, dp, dq, nominal, run->tx_lag, run->tx_lag);
    else if (m == G_LAGS)
        rc = sasnav_pair_set_data_lags(pr, dp, dq, nominal, lp.array.x - lp.tx.x, lq.array.x - lq.tx.x);
    else {
        sasnav_ping_pose cp[SASNAV_MAX_RX], cq[SASNAV_MAX_RX];
        sasnav_ping_pose a = model_local(m, &lp), b = model_local(m, &lq);
        for (int l = 0; l < run->array.n_rx; l++) {
            cp[l] = a;
            cq[l] = b;
        }
        rc = sasnav_pair_set_data_channels(pr, dp, dq, nominal, cp, cq);
    }
    sasnav_pair_result res;
    if (!rc) rc = sasnav_pair_estimate(pr, &res);
    sasnav_pair_destroy(pr);
    if (rc) return rc;
    sasnav_pose t = sasnav_ping_displacement(&run->truth[p], &run->truth[q]);
    *err = (sasnav_pose){res.displacement.x - t.x, res.displacement.y - t.y,
                         res.displacement.theta - t.theta};
    *verdict = res.verdict;
    return SASNAV_OK;
}

static int parse_models(const char *s, int *use)
{
    for (int m = 0; m < N_MODELS; m++) use[m] = 0;
    char buf[256];
    snprintf(buf, sizeof buf, "%s", s);
    for (char *tok = strtok(buf, ","); tok; tok = strtok(NULL, ",")) {
        int found = 0;
        for (int m = 0; m < N_MODELS; m++)
            if (!strcmp(tok, model_names[m])) use[m] = found = 1;
        if (!found) return 0;
    }
    return 1;
}

static void usage(void)
{
    fprintf(stderr, "usage: bench_bias [--seeds S0 N] [--snr DB|inf] [--models fixed,lags,yaw,full]\n"
                    "                  [--range-extent M] [--cross-extent M] [--error-extent M]\n"
                    "                  [--k K] [--i I] [--scene-range Y0,Y1] [--disc-amplitude A]\n"
                    "                  [--threads T] [--quiet] [--gpu]\n"
                    "                  [--final auto|eta|joint] [--joint-k K] [--joint-mu M]\n");
}

int main(int argc, char **argv)
{
    long s0 = 101, ns = 3;
    double snr = 30.0;
    int use[N_MODELS] = {1, 1, 1, 1}, threads = 0, quiet = 0;
    double scene_y0 = NAN, scene_y1 = NAN, disc_amplitude = NAN;
    sasnav_pair_opts po;
    sasnav_pair_default_opts(&po);
    for (int a = 1; a < argc; a++) {
        if (bench_seed_option(argc, argv, &a, &s0, &ns, &snr)) continue;
        if (!strcmp(argv[a], "--models") && a + 1 < argc) {
            if (!parse_models(argv[++a], use)) {
                usage();
                return 2;
            }
        } else if (!strcmp(argv[a], "--range-extent") && a + 1 < argc) po.range_extent = atof(argv[++a]);
        else if (!strcmp(argv[a], "--cross-extent") && a + 1 < argc) po.cross_extent = atof(argv[++a]);
        else if (!strcmp(argv[a], "--error-extent") && a + 1 < argc) po.error_extent = atof(argv[++a]);
        else if (!strcmp(argv[a], "--k") && a + 1 < argc) po.k = atoi(argv[++a]);
        else if (!strcmp(argv[a], "--i") && a + 1 < argc) po.i = atoi(argv[++a]);
        else if (!strcmp(argv[a], "--scene-range") && a + 1 < argc) {
            if (sscanf(argv[++a], "%lf,%lf", &scene_y0, &scene_y1) != 2 || !(scene_y1 > scene_y0) ||
                !(scene_y0 > 1.0)) {
                usage();
                return 2;
            }
        } else if (!strcmp(argv[a], "--disc-amplitude") && a + 1 < argc) {
            disc_amplitude = atof(argv[++a]);
            if (!(disc_amplitude >= 0) || !isfinite(disc_amplitude)) {
                usage();
                return 2;
            }
        } else if (!strcmp(argv[a], "--threads") && a + 1 < argc) threads = atoi(argv[++a]);
        else if (!strcmp(argv[a], "--quiet")) quiet = 1;
        else if (!strcmp(argv[a], "--gpu")) po.gpu = 1;
        else if (!strcmp(argv[a], "--final") && a + 1 < argc) {
            a++;
            po.final_criterion = !strcmp(argv[a], "joint") ? SASNAV_FINAL_JOINT
                                 : !strcmp(argv[a], "eta") ? SASNAV_FINAL_ETA : SASNAV_FINAL_AUTO;
        } else if (!strcmp(argv[a], "--joint-k") && a + 1 < argc) po.joint_k = atoi(argv[++a]);
        else if (!strcmp(argv[a], "--joint-mu") && a + 1 < argc) po.joint_mu = atof(argv[++a]);
        else if (!strcmp(argv[a], "--joint-eta-ratio") && a + 1 < argc) po.joint_eta_ratio = atof(argv[++a]);
        else {
            usage();
            return 2;
        }
    }
    if (ns < 1 || ns > 10000 || !(po.range_extent > 0) || po.k < 1 || po.i < 1) {
        usage();
        return 2;
    }
    if (threads > 0) omp_set_num_threads(threads);
    po.nthreads = 1;
    const int max_pairs = 64;
    size_t cap = (size_t)ns * max_pairs;
    double *e[N_MODELS][3], *final_sway[N_MODELS];
    int n_err[N_MODELS] = {0}, n_runs = 0, within[N_MODELS] = {0}, not_ok[N_MODELS] = {0};
    int pairs_per_run = 0; /* the same for every seed of the preset */
    for (int m = 0; m < N_MODELS; m++) {
        for (int c = 0; c < 3; c++) e[m][c] = malloc(cap * sizeof(double));
        final_sway[m] = malloc((size_t)ns * sizeof(double));
        if (!e[m][0] || !e[m][1] || !e[m][2] || !final_sway[m]) return 1;
    }
    double lambda = 0, step = 0;
    printf("paper-trajectory, SNR %g dB, seeds %ld..%ld, k = %d, i = %d, range extent %g m, "
           "cross extent %g m (0 = auto), error extent %g m (0 = the grid)\n",
           snr, s0, s0 + ns - 1, po.k, po.i, po.range_extent, po.cross_extent, po.error_extent);
    if (isfinite(scene_y0)) printf("seabed between %g and %g m\n", scene_y0, scene_y1);
    if (isfinite(disc_amplitude)) printf("disc amplitude %g\n", disc_amplitude);
    for (long s = s0; s < s0 + ns; s++) {
        sasnav_run *run = bench_trajectory_run_scene(s, snr, 0, scene_y0, scene_y1, disc_amplitude);
        if (!run) return 1;
        int np = run->n_pings - 1;
        pairs_per_run = np;
        if (np > max_pairs || !run->truth) {
            fprintf(stderr, "bench_bias: unexpected run (%d pairs)\n", np);
            return 1;
        }
        lambda = sasnav_wavelength(&run->sys);
        step = run->ping_spacing;
        sasnav_pair_opts o = po;
        o.range = run->range_of_interest;
        o.tx_lag = run->tx_lag;
        sasnav_pose err[64][N_MODELS];
        int verdict[64][N_MODELS], rc = SASNAV_OK;
#pragma omp parallel for schedule(dynamic, 1)
        for (int t = 0; t < np * N_MODELS; t++) {
            int p = t / N_MODELS, m = t % N_MODELS;
            if (!use[m]) continue;
            int r = estimate(run, &o, m, p, &err[p][m], &verdict[p][m]);
            if (r) {
#pragma omp critical(bench_bias_error)
                {
                    if (!rc) fprintf(stderr, "bench_bias: seed %ld pair %d: %s\n", s, p, sasnav_last_error());
                    rc = r;
                }
            }
        }
        if (rc) return 1;
        for (int m = 0; m < N_MODELS; m++) {
            if (!use[m]) continue;
            /* Compose the estimated and the true displacements from the
             * first ping's centroid. */
            sasnav_pose est = {0, 0, 0}, tru = {0, 0, 0};
            for (int p = 0; p < np; p++) {
                sasnav_pose t = sasnav_ping_displacement(&run->truth[p], &run->truth[p + 1]);
                sasnav_pose d = {t.x + err[p][m].x, t.y + err[p][m].y, t.theta + err[p][m].theta};
                est = sasnav_pose_compose(est, d);
                tru = sasnav_pose_compose(tru, t);
                e[m][0][n_err[m]] = err[p][m].x;
                e[m][1][n_err[m]] = err[p][m].y;
                e[m][2][n_err[m]] = err[p][m].theta;
                n_err[m]++;
                not_ok[m] += verdict[p][m] != SASNAV_VERDICT_OK;
            }
            final_sway[m][n_runs] = est.y - tru.y;
            within[m] += fabs(est.y - tru.y) <= lambda / 25.0;
        }
        if (!quiet)
            for (int p = 0; p < np; p++) {
                printf("%5ld %2d", s, p);
                for (int m = 0; m < N_MODELS; m++)
                    if (use[m])
                        printf(" | %s %+7.3f %+8.4f %+9.2e", model_names[m], 1e3 * err[p][m].x,
                               1e3 * err[p][m].y, err[p][m].theta);
                printf("\n");
            }
        printf("%5ld final sway (mm):", s);
        for (int m = 0; m < N_MODELS; m++)
            if (use[m]) printf(" %s %+.3f", model_names[m], 1e3 * final_sway[m][n_runs]);
        printf("\n");
        fflush(stdout);
        n_runs++;
        sasnav_run_free(run);
    }
    double sumk2 = 0; /* sum_{k < n} k^2 over a run's n pairs */
    for (int k = 0; k < pairs_per_run; k++) sumk2 += (double)k * k;
    /* Which way the errors lie: the yaw errors' correlation with the surge
     * and the sway errors, and the sway per unit yaw (the least-squares
     * slope: a rotation about a point that far behind q's centroid). */
    for (int m = 0; m < N_MODELS; m++) {
        if (!use[m] || n_err[m] < 2) continue;
        int n = n_err[m];
        double mean[3] = {0, 0, 0}, cov[3][3] = {{0}};
        for (int j = 0; j < n; j++)
            for (int c = 0; c < 3; c++) mean[c] += e[m][c][j] / n;
        for (int j = 0; j < n; j++)
            for (int a = 0; a < 3; a++)
                for (int b = 0; b < 3; b++) cov[a][b] += (e[m][a][j] - mean[a]) * (e[m][b][j] - mean[b]);
        double cs = cov[0][2] / sqrt(cov[0][0] * cov[2][2]), cw = cov[1][2] / sqrt(cov[1][1] * cov[2][2]);
        printf("%s: yaw error against surge error: correlation %+.2f; against sway error: %+.2f, "
               "sway = %+.3f m x yaw\n",
               model_names[m], cs, cw, cov[1][2] / cov[2][2]);
    }
    printf("\n| model | pairs | not ok | surge mm rms / median / p95 | sway microns rms / median / p95 | "
           "yaw rad rms / median / p95 | final sway mm median / p95 | within lambda/25 | yaw-only "
           "prediction of final sway rms (mm) |\n|---|---|---|---|---|---|---|---|---|\n");
    for (int m = 0; m < N_MODELS; m++) {
        if (!use[m]) continue;
        int n = n_err[m];
        double rms[3], med[3], p95[3];
        for (int c = 0; c < 3; c++) {
            double s2 = 0;
            for (int j = 0; j < n; j++) {
                s2 += e[m][c][j] * e[m][c][j];
                e[m][c][j] = fabs(e[m][c][j]);
            }
            rms[c] = sqrt(s2 / n);
            med[c] = percentile(e[m][c], n, 50);
            p95[c] = percentile(e[m][c], n, 95);
        }
        for (int r = 0; r < n_runs; r++) final_sway[m][r] = fabs(final_sway[m][r]);
        double fs50 = percentile(final_sway[m], n_runs, 50), fs95 = percentile(final_sway[m], n_runs, 95);
        printf("| %s | %d | %d | %.3f / %.3f / %.3f | %.1f / %.1f / %.1f | %.2e / %.2e / %.2e | %.3f / "
               "%.3f | %d of %d | %.3f |\n",
               model_names[m], n, not_ok[m], 1e3 * rms[0], 1e3 * med[0], 1e3 * p95[0], 1e6 * rms[1],
               1e6 * med[1], 1e6 * p95[1], rms[2], med[2], p95[2], 1e3 * fs50, 1e3 * fs95, within[m],
               n_runs, 1e3 * rms[2] * step * sqrt(sumk2));
    }
    for (int m = 0; m < N_MODELS; m++) {
        for (int c = 0; c < 3; c++) free(e[m][c]);
        free(final_sway[m]);
    }
    return 0;
}
