/* Monte Carlo study of trustworthy navigation (docs/navigation.md,
 * "Trust: Monte Carlo"): seeded paper-trajectory runs with simulated
 * aiding, navigated five ways on the same data:
 *   paper      subspace pair estimates, each pair alone (--no-resolve)
 *   subspace   subspace, joint resolution over the run, no aiding
 *   dpca       DPCA baseline, joint resolution, no aiding
 *   aiding     the gyro and DVL alone (dead reckoning)
 *   fused      subspace + aiding (the pair estimates of 'subspace' reused)
 *   fused+bias the same with a constant aiding error per interval estimated
 *              jointly (--aiding-bias M, surge and sway, default 4e-4 m):
 *              the default fusion before the DVL's speed-scaled offsets
 * and with --lag-rows / --fused-lags / --sub-lags (below) the rows
 *   sub+lags   subspace with the pairs' speed-scaled offsets (opts.speed_lags 2)
 *   fused+lags fused+bias estimated afresh with the DVL's speed-scaled
 *              offsets (opts.speed_lags 1): the default fusion
 *
 * usage: bench_trust [--seeds S0 N] [--snr DB] [--threads T] [--pairs FILE]
 *                    [--speed-lags 0|1|2] [--aiding-bias M] [--lag-rows]
 *                    [--fused-lags] [--sub-lags] [--methods M1,M2,...]
 *                    [--k K] [--i I] [--gpu] [--final auto|eta|joint] [--joint-eta-ratio R]
 *                    [--aiding-bias-yaw R] [--gyro-arw R] [--gyro-bias R] [--dvl-noise M] [--dvl-bias M]
 *                    [--dvl-scale S] [--no-gyro] [--no-dvl] [--link-sigma S,W,Y]
 *                    [--link-eta E] [--alt-link-eta E1,E2,...]
 *
 * Seeds follow `sasnav simulate --seed S --aiding` (scene 3S+1, trajectory
 * 3S+2, noise 3S+3, aiding 3S+4). Prints one line per run and method, then
 * per method: slips (a pair's fused motion error off by more than a
 * quarter phase-centre spacing in surge or 2e-3 rad in yaw), unflagged
 * slips (slips whose pair is "ok" and not bridged), flagged pairs, final
 * cumulative sway / surge / yaw errors and rms cumulative sway (median and
 * 95th percentile of the absolute values over the runs), and the runs with
 * final sway within lambda/25; and the navigation's formal standard
 * deviations of the final errors against them (sasnav_navigation
 * formal_sigma: |error| / sd, runs within 2 sd, and the runs within
 * lambda/25 that the formal sd predicts, the sum over runs of erf(lambda
 * / 25 / (sqrt 2 sd))). --pairs FILE writes one line per subspace
 * pair (first estimate: error, eta, margin, verdict, candidates) for the
 * calibration of the verdict. --speed-lags sets opts.speed_lags of the
 * subspace navigation (its estimates are reused by paper and fused);
 * --aiding-bias M sets fused+bias's aiding_bias_sigma (surge and sway, m).
 * --lag-rows adds two methods estimated afresh with speed-scaled EPCA
 * offsets (docs/estimator.md): sub+lags (the pairs' own surge, opts.speed_lags
 * = 2, no aiding) and fused+lags (the DVL's speed, opts.speed_lags = 1, fused
 * with the aiding-bias term: fused+bias with the offsets); --fused-lags adds
 * fused+lags only, --sub-lags sub+lags only. --methods runs only the
 * named rows (e.g. `--methods fused+lags,aiding`: the default fusion and
 * dead reckoning, half the time of all rows). --k, --i set the subspace
 * estimator's final-stage iterations (default the estimator's 8, 8);
 * --final its final-stage criterion (default the estimator's, auto).
 * --aiding-bias-yaw R adds a yaw term to those rows' aiding bias (rad per
 * ping interval: a gyro bias estimated jointly; `navigate --aiding-bias
 * S,W,Y`). --gyro-arw (rad/sqrt(s)), --gyro-bias (rad/s), --dvl-noise, --dvl-bias
 * (m/s), --dvl-scale (relative), --no-gyro and --no-dvl set the simulated
 * aiding sensors (`aiding:` of docs/config.md; default its navigation-grade
 * gyro and 600 kHz DVL): the same error draws scaled, so grades compare on
 * common random numbers (docs/navigation.md, "Which aiding is enough").
 * --link-sigma S,W,Y sets every row's opts.link_sigma (an ok pair's
 * standard deviations in the fusion; `navigate --link-sigma`).
 * --link-eta E sets every row's opts.link_eta (`navigate --link-eta`; 0:
 * off). --alt-link-eta E1,E2,... (at most 4 values) navigates the
 * subspace and fused+lags rows again with each link_eta, reusing their
 * estimates (rows "subspace@E", "fused+lags@E"): an A/B of the fusion's
 * weights on the same pair estimates (link_eta acts only where aiding is
 * fused: "subspace@E" shows the unaided rows left as they are).
 * --gpu runs the subspace rows' error evaluations on a CUDA GPU (builds with
 * -DSASNAV_CUDA=ON; docs/estimator.md, "GPU": the CPU's estimates to float
 * rounding, not to the bit). */
#include "sasnav/error.h"
#include "sasnav/navigate.h"
#include "sasnav/sim.h"
#include "bench_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { M_PAPER, M_SUB, M_DPCA, M_AID, M_FUSED, M_FUSED_BIAS, M_SUB_LAGS, M_FUSED_LAGS, N_METHODS };
enum { MAX_ALT = 4, N_ROWS = N_METHODS + 2 * MAX_ALT }; /* rows: methods, then subspace@E, fused+lags@E */
static const char *const names[N_METHODS] = {"paper", "subspace", "dpca", "aiding", "fused", "fused+bias",
                                             "sub+lags", "fused+lags"};

typedef struct {
    double *final_sway, *final_surge, *final_yaw, *rms_sway;
    double *z[3];       /* final error / formal standard deviation (surge, sway, yaw) */
    double *sd_sway;    /* formal standard deviation of the final sway */
    double p_within;    /* sum over runs of the formal sd's probability of lambda/25 */
    int n_sd;           /* runs with a prediction */
    int slips, unflagged, flagged, pairs, within;
} stats;

int main(int argc, char **argv)
{
    long s0 = 1001, ns = 10;
    double snr = 30.0;
    int threads = 0, speed_lags = 0, k_final = 0, i_final = 0, gpu = 0, final_c = -1;
    double eta_ratio = 0; /* > 0: opts.pair.joint_eta_ratio */
    int use[N_ROWS] = {1, 1, 1, 1, 1, 1, 0, 0}; /* the methods (and alternative rows) run */
    double aiding_bias = 4e-4, aiding_bias_yaw = 0;
    sasnav_pose link_sigma = {0, 0, 0}; /* 0: the library's default */
    double link_eta = -1;                /* < 0: the library's default */
    double alt_eta[MAX_ALT];
    int n_alt = 0;
    char row_name[N_ROWS][32];
    const char *pairs_path = NULL;
    sasnav_aiding_params aid;
    sasnav_aiding_default(&aid);
    for (int a = 1; a < argc; a++) {
        if (bench_seed_option(argc, argv, &a, &s0, &ns, &snr)) continue;
        if (!strcmp(argv[a], "--threads") && a + 1 < argc) {
            threads = atoi(argv[++a]);
        } else if (!strcmp(argv[a], "--aiding-bias") && a + 1 < argc) {
            aiding_bias = atof(argv[++a]);
        } else if (!strcmp(argv[a], "--speed-lags") && a + 1 < argc) {
            speed_lags = atoi(argv[++a]);
        } else if (!strcmp(argv[a], "--lag-rows")) {
            use[M_SUB_LAGS] = use[M_FUSED_LAGS] = 1;
        } else if (!strcmp(argv[a], "--fused-lags")) {
            use[M_FUSED_LAGS] = 1;
        } else if (!strcmp(argv[a], "--sub-lags")) {
            use[M_SUB_LAGS] = 1;
        } else if (!strcmp(argv[a], "--methods") && a + 1 < argc) {
            /* only these rows (comma-separated names); rows that reuse
             * subspace's estimates (paper, fused, fused+bias) add it */
            char *list = argv[++a];
            memset(use, 0, sizeof use);
            for (char *tok = strtok(list, ","); tok; tok = strtok(NULL, ",")) {
                int found = 0;
                for (int m = 0; m < N_METHODS; m++)
                    if (!strcmp(tok, names[m])) use[m] = found = 1;
                if (!found) {
                    fprintf(stderr, "bench_trust: unknown method %s\n", tok);
                    return 2;
                }
            }
            if (use[M_PAPER] || use[M_FUSED] || use[M_FUSED_BIAS]) use[M_SUB] = 1;
        } else if (!strcmp(argv[a], "--gpu")) {
            gpu = 1;
        } else if (!strcmp(argv[a], "--pairs") && a + 1 < argc) {
            pairs_path = argv[++a];
        } else if (!strcmp(argv[a], "--k") && a + 1 < argc) {
            k_final = atoi(argv[++a]);
        } else if (!strcmp(argv[a], "--i") && a + 1 < argc) {
            i_final = atoi(argv[++a]);
        } else if (!strcmp(argv[a], "--final") && a + 1 < argc) {
            final_c = sasnav_final_criterion_parse(argv[++a]);
            if (final_c < 0) return 2;
        } else if (!strcmp(argv[a], "--joint-eta-ratio") && a + 1 < argc) {
            eta_ratio = atof(argv[++a]);
        } else if (!strcmp(argv[a], "--aiding-bias-yaw") && a + 1 < argc) {
            aiding_bias_yaw = atof(argv[++a]);
            if (!(aiding_bias_yaw >= 0) || !isfinite(aiding_bias_yaw)) return 2;
        } else if (!strcmp(argv[a], "--gyro-arw") && a + 1 < argc) {
            aid.gyro_arw = atof(argv[++a]);
        } else if (!strcmp(argv[a], "--gyro-bias") && a + 1 < argc) {
            aid.gyro_bias = atof(argv[++a]);
        } else if (!strcmp(argv[a], "--dvl-noise") && a + 1 < argc) {
            aid.dvl_noise = atof(argv[++a]);
        } else if (!strcmp(argv[a], "--dvl-bias") && a + 1 < argc) {
            aid.dvl_bias = atof(argv[++a]);
        } else if (!strcmp(argv[a], "--dvl-scale") && a + 1 < argc) {
            aid.dvl_scale = atof(argv[++a]);
        } else if (!strcmp(argv[a], "--no-gyro")) {
            aid.gyro = 0;
        } else if (!strcmp(argv[a], "--no-dvl")) {
            aid.dvl = 0;
        } else if (!strcmp(argv[a], "--link-sigma") && a + 1 < argc) {
            if (sscanf(argv[++a], "%lf,%lf,%lf", &link_sigma.x, &link_sigma.y, &link_sigma.theta) != 3 ||
                !(link_sigma.x > 0 && link_sigma.y > 0 && link_sigma.theta > 0))
                return 2;
        } else if (!strcmp(argv[a], "--link-eta") && a + 1 < argc) {
            char *end;
            link_eta = strtod(argv[++a], &end);
            if (end == argv[a] || *end || !(link_eta >= 0)) {
                fprintf(stderr, "bench_trust: --link-eta needs an eta >= 0 (0: off)\n");
                return 2;
            }
        } else if (!strcmp(argv[a], "--alt-link-eta") && a + 1 < argc) {
            for (char *tok = strtok(argv[++a], ","); tok; tok = strtok(NULL, ",")) {
                char *end;
                if (n_alt < MAX_ALT) alt_eta[n_alt] = strtod(tok, &end);
                if (n_alt == MAX_ALT || end == tok || *end || !(alt_eta[n_alt] >= 0)) {
                    fprintf(stderr, "bench_trust: --alt-link-eta needs 1 to %d etas >= 0\n", MAX_ALT);
                    return 2;
                }
                n_alt++;
            }
        } else {
            fprintf(stderr, "usage: bench_trust [--seeds S0 N] [--snr DB] [--threads T] [--pairs FILE] "
                            "[--speed-lags 0|1|2] [--aiding-bias M] [--lag-rows] [--fused-lags] [--sub-lags] "
                            "[--methods M1,M2,...] [--k K] [--i I] [--gpu] [--final auto|eta|joint] "
                            "[--joint-eta-ratio R] [--aiding-bias-yaw R] [--gyro-arw R] [--gyro-bias R] [--dvl-noise M] "
                            "[--dvl-bias M] [--dvl-scale S] [--no-gyro] [--no-dvl] [--link-sigma S,W,Y] "
                            "[--link-eta E] [--alt-link-eta E1,E2,...]\n");
            return 2;
        }
    }
    if ((!aid.gyro || !aid.dvl) && use[M_AID]) {
        use[M_AID] = 0; /* dead reckoning needs both (sasnav_navigate refuses it) */
        fprintf(stderr, "bench_trust: without a gyro or a DVL there is no 'aiding' row\n");
    }
    if (ns < 1 || threads < 0 || speed_lags < 0 || speed_lags > 2 || k_final < 0 || i_final < 0) return 2;
    if (n_alt && speed_lags == 2) {
        /* the subspace row's two passes give each pair its own offsets; a
         * reused navigation re-estimates without them: not an A/B */
        fprintf(stderr, "bench_trust: --alt-link-eta with --speed-lags 2 would compare other estimates\n");
        return 2;
    }
    FILE *pf = pairs_path ? fopen(pairs_path, "w") : NULL;
    if (pairs_path && !pf) {
        fprintf(stderr, "bench_trust: cannot write %s\n", pairs_path);
        return 1;
    }
    const double lambda = 1500.0 / 300e3, d = 0.025, yaw_slip = 2e-3;
    for (int m = 0; m < N_ROWS; m++) {
        if (m < N_METHODS) {
            snprintf(row_name[m], sizeof row_name[m], "%s", names[m]);
        } else {
            int r = m - N_METHODS, base = r % 2 ? M_FUSED_LAGS : M_SUB;
            use[m] = r / 2 < n_alt && use[base];
            if (use[m]) snprintf(row_name[m], sizeof row_name[m], "%s@%g", names[base], alt_eta[r / 2]);
        }
    }
    stats st[N_ROWS];
    memset(st, 0, sizeof st);
    for (int m = 0; m < N_ROWS; m++) {
        st[m].final_sway = calloc((size_t)ns, sizeof(double));
        st[m].final_surge = calloc((size_t)ns, sizeof(double));
        st[m].final_yaw = calloc((size_t)ns, sizeof(double));
        st[m].rms_sway = calloc((size_t)ns, sizeof(double));
        for (int k = 0; k < 3; k++) st[m].z[k] = calloc((size_t)ns, sizeof(double));
        st[m].sd_sway = calloc((size_t)ns, sizeof(double));
        if (!st[m].final_sway || !st[m].final_surge || !st[m].final_yaw || !st[m].rms_sway || !st[m].z[0] ||
            !st[m].z[1] || !st[m].z[2] || !st[m].sd_sway)
            return 1;
    }
    setvbuf(stdout, NULL, _IOLBF, 0); /* one line per run as it ends (long studies) */
    printf("paper-trajectory with aiding, SNR %g dB, seeds %ld..%ld%s\n", snr, s0, s0 + ns - 1,
           gpu ? ", subspace evaluations on the GPU" : "");
    printf("aiding: gyro %s (arw %.3g rad/sqrt(s), bias %.3g rad/s), DVL %s (noise %.3g m/s, bias %.3g m/s, "
           "scale %.3g)\n",
           aid.gyro ? "on" : "off", aid.gyro_arw, aid.gyro_bias, aid.dvl ? "on" : "off", aid.dvl_noise,
           aid.dvl_bias, aid.dvl_scale);
    printf("%6s %-16s %6s %9s %8s %14s %14s %12s %10s %9s %9s %9s\n", "seed", "method", "slips", "unflagged",
           "flagged", "final sway mm", "final surge mm", "final yaw", "s/pair", "sd sway", "sd surge", "sd yaw");
    for (long s = s0; s < s0 + ns; s++) {
        int r = (int)(s - s0);
        sasnav_run *run = bench_trajectory_run_aided(s, snr, &aid, NAN, NAN, NAN);
        if (!run) return 1;
        sasnav_navigation nav[N_ROWS];
        memset(nav, 0, sizeof nav);
        int order[N_ROWS] = {M_SUB, M_PAPER, M_FUSED, M_FUSED_BIAS, M_DPCA, M_AID, M_SUB_LAGS, M_FUSED_LAGS};
        for (int k = N_METHODS; k < N_ROWS; k++) order[k] = k;
        for (int k = 0; k < N_ROWS; k++) {
            int row = order[k], m = row;
            if (!use[row]) continue;
            if (row >= N_METHODS) m = (row - N_METHODS) % 2 ? M_FUSED_LAGS : M_SUB;
            sasnav_navigate_opts o;
            sasnav_navigate_default_opts(&o);
            o.nthreads = threads;
            if (k_final > 0) o.pair.k = k_final;
            if (final_c >= 0) o.pair.final_criterion = final_c;
            if (eta_ratio > 0) o.pair.joint_eta_ratio = eta_ratio;
            if (i_final > 0) o.pair.i = i_final;
            if (link_sigma.x > 0) {
                o.link_sigma = link_sigma;
                o.long_sigma = (sasnav_pose){2 * link_sigma.x, 2 * link_sigma.y, 2 * link_sigma.theta};
            }
            if (link_eta >= 0) o.link_eta = link_eta;
            o.use_aiding = m == M_FUSED || m == M_FUSED_BIAS || m == M_AID || m == M_FUSED_LAGS;
            o.resolve = m != M_PAPER;
            if (m == M_PAPER || m == M_FUSED || m == M_FUSED_BIAS) o.reuse = &nav[M_SUB];
            if (m == M_DPCA) o.method = SASNAV_METHOD_DPCA;
            if (m == M_AID) o.method = SASNAV_METHOD_AIDING;
            o.pair.gpu = gpu && o.method == SASNAV_METHOD_SUBSPACE;
            /* The rows that reuse M_SUB's estimates keep its offsets in
             * their re-estimates (0 unless --speed-lags). */
            o.speed_lags = m == M_SUB ? speed_lags : 0;
            if (m == M_SUB_LAGS) o.speed_lags = 2;
            if (m == M_FUSED_LAGS) o.speed_lags = 1;
            /* fused and aiding without the aiding-bias term (the defaults
             * before it was on); fused+bias with it (the default since). */
            o.aiding_bias_sigma = m == M_FUSED_BIAS || m == M_FUSED_LAGS ? (sasnav_pose){aiding_bias, aiding_bias, aiding_bias_yaw}
                                                    : (sasnav_pose){0, 0, 0};
            if (row >= N_METHODS) { /* the same estimates, the alternative weights */
                o.reuse = &nav[m];
                o.link_eta = alt_eta[(row - N_METHODS) / 2];
            }
            if (sasnav_navigate(run, &o, &nav[row])) {
                fprintf(stderr, "navigate (%s, seed %ld): %s\n", row_name[row], s, sasnav_last_error());
                return 1;
            }
        }
        for (int m = 0; m < N_ROWS; m++) {
            if (!use[m]) continue;
            const sasnav_navigation *nv = &nav[m];
            int slips = 0, unflagged = 0, flagged = 0;
            for (int j = 0; j < nv->n_pairs; j++) {
                const sasnav_navigate_pair *np = &nv->pairs[j];
                int slip = fabs(np->error.x) > 0.25 * d || fabs(np->error.theta) > yaw_slip;
                int flag = m == M_PAPER ? np->first_verdict != SASNAV_VERDICT_OK
                                        : np->verdict != SASNAV_VERDICT_OK ||
                                              np->resolution == SASNAV_RESOLVED_BRIDGED;
                slips += slip;
                unflagged += slip && !flag;
                flagged += flag;
            }
            sasnav_pose f = nv->cumulative[nv->n_pings - 1];
            st[m].final_sway[r] = fabs(f.y);
            st[m].final_surge[r] = fabs(f.x);
            st[m].final_yaw[r] = fabs(f.theta);
            st[m].rms_sway[r] = nv->rms_cumulative.y;
            st[m].slips += slips;
            st[m].unflagged += unflagged;
            st[m].flagged += flagged;
            st[m].pairs += nv->n_pairs;
            st[m].within += fabs(f.y) <= lambda / 25;
            /* the navigation's own prediction of these errors */
            sasnav_pose sd = nv->formal_sigma ? nv->formal_sigma[nv->n_pings - 1] : (sasnav_pose){NAN, NAN, NAN};
            if (nv->formal_sigma) {
                int i = st[m].n_sd++;
                st[m].z[0][i] = fabs(f.x) / sd.x;
                st[m].z[1][i] = fabs(f.y) / sd.y;
                st[m].z[2][i] = fabs(f.theta) / sd.theta;
                st[m].sd_sway[i] = sd.y;
                st[m].p_within += erf(lambda / 25 / (sqrt(2.0) * sd.y));
            }
            printf("%6ld %-16s %6d %9d %8d %+14.4f %+14.3f %+12.3e %10.2f %9.4f %9.3f %9.2e\n", s, row_name[m],
                   slips, unflagged, flagged, 1e3 * f.y, 1e3 * f.x, f.theta, nv->seconds_per_pair, 1e3 * sd.y,
                   1e3 * sd.x, sd.theta);
        }
        if (pf && use[M_SUB]) {
            const sasnav_navigation *nv = &nav[M_SUB];
            for (int j = 0; j < nv->n_pairs; j++) {
                const sasnav_navigate_pair *np = &nv->pairs[j];
                const sasnav_pair_result *pr = &np->first_result;
                sasnav_pose e = {pr->error.x - np->truth.x, pr->error.y - np->truth.y,
                                 pr->error.theta - np->truth.theta};
                fprintf(pf,
                        "%g %ld %d err %+.6f %+.7f %+.7f eta %.4f zeta %.4f overlap %.3f margin %.4f "
                        "ambiguity %.3f verdict %s candidates %d resolution %s fused %+.6f %+.7f %+.7f\n",
                        snr, s, np->p, e.x, e.y, e.theta, pr->eta, pr->zeta, pr->overlap, pr->margin,
                        pr->ambiguity, sasnav_verdict_name(pr->verdict), pr->n_candidates,
                        sasnav_resolution_name(np->resolution), np->error.x, np->error.y,
                        np->error.theta);
            }
            fflush(pf);
        }
        fflush(stdout);
        for (int m = 0; m < N_ROWS; m++) sasnav_navigation_free(&nav[m]);
        sasnav_run_free(run);
    }
    if (pf) fclose(pf);
    printf("\n| method | slips | unflagged slips | flagged pairs | final sway mm, median / p95 | "
           "final surge mm | final yaw rad | rms sway mm | runs within lambda/25 |\n"
           "|---|---|---|---|---|---|---|---|---|\n");
    for (int m = 0; m < N_ROWS; m++) {
        if (!use[m]) continue;
        stats *t = &st[m];
        int n = (int)ns;
        double sw50 = percentile(t->final_sway, n, 50), sw95 = percentile(t->final_sway, n, 95);
        double su50 = percentile(t->final_surge, n, 50), su95 = percentile(t->final_surge, n, 95);
        double y50 = percentile(t->final_yaw, n, 50), y95 = percentile(t->final_yaw, n, 95);
        double r50 = percentile(t->rms_sway, n, 50), r95 = percentile(t->rms_sway, n, 95);
        printf("| %s | %d of %d | %d | %d | %.3f / %.3f | %.2f / %.2f | %.2e / %.2e | %.3f / %.3f | "
               "%d of %d |\n",
               row_name[m], t->slips, t->pairs, t->unflagged, t->flagged, 1e3 * sw50, 1e3 * sw95,
               1e3 * su50, 1e3 * su95, y50, y95, 1e3 * r50, 1e3 * r95, t->within, n);
    }
    printf("\nThe navigation's formal standard deviations (sd) of the final errors against the errors:\n"
           "| method | runs | formal sd of final sway mm, median | |error| / sd, median and p95: surge, "
           "sway, yaw | within 2 sd: surge, sway, yaw | runs within lambda/25: formal (sum of "
           "probabilities) / seen |\n|---|---|---|---|---|---|\n");
    for (int m = 0; m < N_ROWS; m++) {
        if (!use[m] || st[m].n_sd == 0) continue;
        stats *t = &st[m];
        int n = t->n_sd, in2[3] = {0, 0, 0};
        for (int k = 0; k < 3; k++)
            for (int i = 0; i < n; i++) in2[k] += t->z[k][i] <= 2.0;
        double zm[3], zp[3];
        for (int k = 0; k < 3; k++) {
            zm[k] = percentile(t->z[k], n, 50);
            zp[k] = percentile(t->z[k], n, 95);
        }
        printf("| %s | %d | %.3f | %.2f / %.2f, %.2f / %.2f, %.2f / %.2f | %d, %d, %d of %d | %.1f / %d |\n",
               row_name[m], n, 1e3 * percentile(t->sd_sway, n, 50), zm[0], zp[0], zm[1], zp[1], zm[2], zp[2],
               in2[0], in2[1], in2[2], n, t->p_within, t->within);
    }
    for (int m = 0; m < N_ROWS; m++) {
        for (int k = 0; k < 3; k++) free(st[m].z[k]);
        free(st[m].sd_sway);
        free(st[m].final_sway);
        free(st[m].final_surge);
        free(st[m].final_yaw);
        free(st[m].rms_sway);
    }
    return 0;
}
