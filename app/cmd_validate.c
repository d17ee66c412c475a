/* sasnav validate: the tank experiment's validation method (paper Sec. V,
 * include/sasnav/validate.h). */
#include "cli.h"
#include "io/textfile.h"
#include "sasnav/io.h"
#include "sasnav/plot.h"
#include "sasnav/validate.h"

#include <errno.h>
#include <getopt.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static const char *help =
    "usage: sasnav validate run.h5 -o DIR [--k-min K] [--k-max K]\n"
    "                       [--fix-yaw | --yaw-sigma S] [--surge-sigma S] [--long-baselines]\n"
    "                       [--k K] [--i I] [--refine [--sweeps N] [--sparsity EPS]]\n"
    "                       [--grid X0,X1,NX,Y0,Y1,NY] [--threads N] [--gpu] [--json]\n"
    "                       [--checkpoint FILE]\n"
    "\n"
    "The validation method of the paper's tank experiment (Sec. V): from a run\n"
    "whose pings step by whole phase-centre spacings (the tank: K = 7 of 8\n"
    "phase centres shared), builds the sub-sampled runs with K = k-min..k-max\n"
    "shared phase centres and all their phases, navigates each (every pair's\n"
    "estimate chained as it is, the paper's method: no joint resolution;\n"
    "pairs whose verdict is not \"ok\" are counted and warned about), combines the\n"
    "phases into one trajectory per K (placed on the largest K's, which is\n"
    "rotated by its fitted track angle), re-arranges the data into SISO (one\n"
    "receiver, all pings) and SIMO (every N-th ping, all receivers) apertures,\n"
    "images each with each trajectory and measures how well the complex\n"
    "images agree around the reflectors (docs/validation.md). On compact\n"
    "scenes such as the tank, hold the pair yaws (--fix-yaw). With --refine,\n"
    "every phase's pair trajectory is refined on the phase's own pings by the\n"
    "multi-ping data-domain fit of 'sasnav refine' (docs/navigation.md), and\n"
    "the spreads of the pair trajectories alone are reported too.\n"
    "Writes into DIR:\n"
    "  validate.json       the summary (also on stdout with --json)\n"
    "  trajectories.csv    ping, K, along-track, cross-track, yaw (aligned)\n"
    "  pairs.csv           every pair estimate (motion error; its error vs the\n"
    "                      truth when known), its margin, whether it sits at a\n"
    "                      phase-centre coincidence, the contrasts of p's and\n"
    "                      q's images (either above 4: compact-scene verdicts),\n"
    "                      eta, whether that is far above its phase's\n"
    "                      (navigate --eta-outlier), status and verdict,\n"
    "                      whether the search was equalised and the peak of\n"
    "                      its smoothed intensity (0 where not measured)\n"
    "  trajectories.png    along/cross-track deviation from the mean of the K\n"
    "  correlation.csv     pairwise image correlations (navigated images)\n"
    "  siso_J.png, simo_J.png   images with the largest K's trajectory\n"
    "  nominal_siso_0.png, nominal_simo_0.png   the same, nominal navigation\n"
    "  report.md           tables and figures\n"
    "\n"
    "  --k-min K, --k-max K  overlaps to test (default 4 .. the run's own)\n"
    "  --fix-yaw          hold every pair's yaw error at 0 (rail, plotter)\n"
    "  --yaw-sigma S      prior on the pair yaw error (rad; default none)\n"
    "  --surge-sigma S    scale of a prior on the pair surge error (m; the\n"
    "                     plotter's step accuracy; default none; the tank:\n"
    "                     0.025, see docs/validation.md)\n"
    "  --long-baselines   also estimate the pairs two steps apart within each\n"
    "                     sub-sampled run (where they share phase centres) and\n"
    "                     combine by least squares\n"
    "  --k K, --i I       estimator iterations of the final stage (default 8, 8)\n"
    "  --refine           refine each phase on its own pings (see above)\n"
    "  --sweeps N         refinement sweeps at most (default 8)\n"
    "  --sparsity EPS     the refinement's reweighted scene damping (default\n"
    "                     0.01; 0: uniform; see sasnav refine --help)\n"
    "  --grid ...         image grid (default: the track's extent x range of\n"
    "                     interest +-0.35 m, 5 mm pixels)\n"
    "  --threads N        OpenMP threads (default: all cores)\n"
    "  --gpu              the pair estimates' error evaluations on a CUDA GPU\n"
    "                     (builds configured with -DSASNAV_CUDA=ON)\n"
    "  --json             print the summary on stdout\n"
    "  --checkpoint FILE  keep every pair estimate in FILE as it is made; an\n"
    "                     interrupted validation run again with the same\n"
    "                     command resumes from FILE (the same results; the\n"
    "                     refinement and the images are redone). FILE is\n"
    "                     removed once the outputs are written\n"
    "\n"
    "Progress on stderr (pairs estimated, rate): a status line on a terminal,\n"
    "otherwise a line every 10 s (SASNAV_PROGRESS_SECONDS sets the period).\n";

/* Pairs estimated over all phases (their total is not known ahead). */
typedef struct {
    cli_progress p;
    int count;
} validate_progress;
static void progress_line(const sasnav_navigate_progress *pr, void *user)
{
    validate_progress *v = user;
    if (pr->done > 0) v->count++;
    cli_progress_update(&v->p, v->count, 0);
}

static json_t *num(double v) { return isfinite(v) ? json_real(v) : json_null(); }

static void join(char *buf, size_t n, const char *dir, const char *name)
{
    snprintf(buf, n, "%s/%s", dir, name);
}

static json_t *summary(const char *input, const sasnav_validation *v, int refined)
{
    json_t *root = json_object();
    json_object_set_new(root, "input", json_string(input));
    json_object_set_new(root, "n_pings", json_integer(v->n_pings));
    json_object_set_new(root, "has_truth", json_boolean(v->has_truth));
    json_object_set_new(root, "surge_jump_error", num(v->surge_jump_error));
    json_object_set_new(root, "jump_pair", v->jump_p >= 0 ? json_pack("[i,i]", v->jump_p, v->jump_p + 1)
                                                          : json_null());
    json_object_set_new(root, "yaw_estimate", num(v->yaw_estimate));
    json_object_set_new(root, "yaw_error", num(v->yaw_error));
    json_object_set_new(root, "sway_spread", num(v->sway_spread));
    json_object_set_new(root, "surge_spread", num(v->surge_spread));
    json_object_set_new(root, "surge_spread_ping", json_integer(v->surge_spread_ping));
    json_t *sk = json_array();
    json_array_append_new(sk, json_integer(v->surge_spread_k[0]));
    json_array_append_new(sk, json_integer(v->surge_spread_k[1]));
    json_object_set_new(root, "surge_spread_k", sk);
    json_object_set_new(root, "sway_spread_ping", json_integer(v->sway_spread_ping));
    json_object_set_new(root, "refined", json_boolean(refined));
    json_object_set_new(root, "sway_spread_pairs", num(v->sway_spread_pairs));
    json_object_set_new(root, "surge_spread_pairs", num(v->surge_spread_pairs));
    json_object_set_new(root, "min_image_correlation", num(v->min_correlation));
    json_object_set_new(root, "min_image_correlation_siso", num(v->min_correlation_siso));
    json_object_set_new(root, "min_image_correlation_simo", num(v->min_correlation_simo));
    json_object_set_new(root, "min_image_correlation_siso_simo", num(v->min_correlation_cross));
    json_object_set_new(root, "min_image_correlation_nominal", num(v->min_correlation_nominal));
    json_object_set_new(root, "min_image_correlation_truth", num(v->min_correlation_truth));
    json_object_set_new(root, "region_pixels", json_integer(v->n_region));
    json_t *ks = json_array();
    for (int k = 0; k < v->n_k; k++) {
        const sasnav_validate_k *vk = &v->k[k];
        json_t *o = json_object();
        json_object_set_new(o, "k", json_integer(vk->k));
        json_object_set_new(o, "stride", json_integer(vk->stride));
        json_object_set_new(o, "pairs", json_integer(vk->n_pairs));
        json_object_set_new(o, "failed_pairs", json_integer(vk->n_failed));
        json_object_set_new(o, "flagged_pairs", json_integer(vk->n_flagged));
        json_object_set_new(o, "track_angle", num(vk->track_angle));
        if (v->has_truth)
            json_object_set_new(o, "rms_error", json_pack("{s:f,s:f,s:f}", "surge", vk->rms_error.x, "sway",
                                                          vk->rms_error.y, "yaw", vk->rms_error.theta));
        if (v->has_truth)
            json_object_set_new(o, "rms_error_pairs",
                                json_pack("{s:f,s:f,s:f}", "surge", vk->rms_error_pairs.x, "sway",
                                          vk->rms_error_pairs.y, "yaw", vk->rms_error_pairs.theta));
        json_object_set_new(o, "refine_sweeps", json_integer(vk->refine_sweeps));
        json_object_set_new(o, "refine_seconds", num(vk->refine_seconds));
        json_object_set_new(o, "seconds", num(vk->seconds));
        json_array_append_new(ks, o);
    }
    json_object_set_new(root, "trajectories", ks);
    json_object_set_new(root, "seconds", num(v->seconds));
    return root;
}

static int write_text(const char *path, const char *text)
{
    sasnav_text_out out;
    int rc = sasnav_text_open(&out, path);
    if (rc) return rc;
    fputs(text, out.f);
    return sasnav_text_commit(&out);
}

static int write_tables(const char *dir, const sasnav_validation *v)
{
    char path[4096];
    sasnav_text_out out;
    join(path, sizeof path, dir, "trajectories.csv");
    int rc = sasnav_text_open(&out, path);
    if (rc) return rc;
    fprintf(out.f, "ping,k,x,y,yaw\n");
    for (int k = 0; k < v->n_k; k++)
        for (int i = 0; i < v->n_pings; i++)
            fprintf(out.f, "%d,%d,%.9f,%.9f,%.6e\n", i, v->k[k].k, v->k[k].centroids[i].x,
                    v->k[k].centroids[i].y, v->k[k].centroids[i].theta);
    if ((rc = sasnav_text_commit(&out))) return rc;
    join(path, sizeof path, dir, "pairs.csv");
    if ((rc = sasnav_text_open(&out, path))) return rc;
    fprintf(out.f, "k,p,q,surge,sway,yaw,error_surge,error_sway,error_yaw,margin,coincidence,contrast,contrast_q,eta,eta_outlier,status,verdict,equalised,equalise_peak\n");
    for (int k = 0; k < v->n_k; k++)
        for (int j = 0; j < v->k[k].n_pairs; j++) {
            const sasnav_navigate_pair *np = &v->k[k].pairs[j];
            fprintf(out.f, "%d,%d,%d,%.9f,%.9f,%.6e,", v->k[k].k, np->p, np->q, np->result.error.x,
                    np->result.error.y, np->result.error.theta);
            if (v->has_truth) fprintf(out.f, "%.9f,%.9f,%.6e,", np->error.x, np->error.y, np->error.theta);
            else fprintf(out.f, ",,,");
            if (isfinite(np->result.margin)) fprintf(out.f, "%.4f,", np->result.margin);
            else fprintf(out.f, "inf,");
            fprintf(out.f, "%d,%.3f,%.3f,%.4f,%d,", np->result.coincidence, np->result.contrast, np->result.contrast_q,
                    np->result.eta, np->eta_outlier);
            fprintf(out.f, "%s,%s,%d,%.3f\n", np->status == SASNAV_OK ? "ok" : sasnav_strerror(np->status),
                    sasnav_verdict_name(np->verdict), np->result.equalised, np->result.equalise_peak);
        }
    if ((rc = sasnav_text_commit(&out))) return rc;
    join(path, sizeof path, dir, "correlation.csv");
    if ((rc = sasnav_text_open(&out, path))) return rc;
    int nn = v->n_k * (v->n_siso + v->n_simo);
    fprintf(out.f, "image");
    for (int b = 0; b < nn; b++)
        fprintf(out.f, ",K%d_%s%d", v->image_k[b], v->image_simo[b] ? "simo" : "siso", v->image_index[b]);
    fputc('\n', out.f);
    for (int a = 0; a < nn; a++) {
        fprintf(out.f, "K%d_%s%d", v->image_k[a], v->image_simo[a] ? "simo" : "siso", v->image_index[a]);
        for (int b = 0; b < nn; b++) fprintf(out.f, ",%.5f", v->correlation[a * nn + b]);
        fputc('\n', out.f);
    }
    return sasnav_text_commit(&out);
}

/* Along- and cross-track deviation of each K's trajectory from the mean of
 * all K (mm), per ping. */
static int plot_trajectories(const char *dir, const sasnav_validation *v)
{
    int n = v->n_pings, nk = v->n_k, rc = SASNAV_OK;
    double *x = malloc(sizeof(double) * n), *ys = malloc(sizeof(double) * (size_t)2 * nk * n);
    const double *xs[2 * SASNAV_VALIDATE_MAX_K], *yv[2 * SASNAV_VALIDATE_MAX_K];
    int ns[2 * SASNAV_VALIDATE_MAX_K];
    char lab[SASNAV_VALIDATE_MAX_K][32];
    const char *labels[SASNAV_VALIDATE_MAX_K];
    if (!x || !ys) {
        free(x);
        free(ys);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    }
    for (int i = 0; i < n; i++) {
        x[i] = i;
        double mx = 0, my = 0;
        for (int k = 0; k < nk; k++) {
            mx += v->k[k].centroids[i].x / nk;
            my += v->k[k].centroids[i].y / nk;
        }
        for (int k = 0; k < nk; k++) {
            ys[(size_t)k * n + i] = 1e3 * (v->k[k].centroids[i].x - mx);
            ys[(size_t)(nk + k) * n + i] = 1e3 * (v->k[k].centroids[i].y - my);
        }
    }
    for (int k = 0; k < nk; k++) {
        snprintf(lab[k], sizeof lab[k], "K = %d", v->k[k].k);
        labels[k] = lab[k];
        for (int a = 0; a < 2; a++) {
            xs[a * nk + k] = x;
            yv[a * nk + k] = ys + (size_t)(a * nk + k) * n;
            ns[a * nk + k] = n;
        }
    }
    const char *name[2] = {"trajectories_surge.png", "trajectories_sway.png"};
    const char *title[2] = {"along-track position minus the mean over K",
                            "cross-track position minus the mean over K"};
    for (int a = 0; a < 2 && !rc; a++) {
        char path[4096];
        join(path, sizeof path, dir, name[a]);
        sasnav_line_plot lp = {title[a], "ping", a ? "cross-track (mm)" : "along-track (mm)", nk, ns + a * nk,
                               xs + a * nk, yv + a * nk, labels, 0, NAN, NAN};
        rc = sasnav_plot_lines(path, &lp);
    }
    free(x);
    free(ys);
    return rc;
}

static int plot_images(const char *dir, const sasnav_validation *v)
{
    size_t npx = (size_t)v->grid.nx * v->grid.ny;
    int per = v->n_siso + v->n_simo, rc = SASNAV_OK;
    for (int j = 0; j < per && !rc; j++) {
        char name[64], path[4096], title[128];
        int simo = j >= v->n_siso, idx = simo ? j - v->n_siso : j;
        snprintf(name, sizeof name, "%s_%d.png", simo ? "simo" : "siso", idx);
        snprintf(title, sizeof title, "%s %d, K = %d trajectory", simo ? "SIMO set" : "SISO receiver", idx,
                 v->k[0].k);
        join(path, sizeof path, dir, name);
        rc = sasnav_plot_image_db(path, &v->grid, v->images + (size_t)j * npx, 30.0, title);
    }
    for (int s = 0; s < 2 && !rc; s++) {
        char path[4096];
        int j = v->n_k * per + (s ? v->n_siso : 0);
        join(path, sizeof path, dir, s ? "nominal_simo_0.png" : "nominal_siso_0.png");
        rc = sasnav_plot_image_db(path, &v->grid, v->images + (size_t)j * npx, 30.0,
                                  s ? "SIMO set 0, nominal navigation" : "SISO receiver 0, nominal navigation");
    }
    return rc;
}

static int write_report(const char *dir, const char *input, const sasnav_validation *v, const char *mode,
                        const sasnav_validate_opts *vo)
{
    char path[4096];
    join(path, sizeof path, dir, "report.md");
    sasnav_text_out out;
    int rc = sasnav_text_open(&out, path);
    if (rc) return rc;
    FILE *f = out.f;
    fprintf(f, "# sasnav validate: %s\n\n", input);
    fprintf(f, "Paper Sec. V: %d pings; sub-sampled runs with K = %d..%d shared phase centres, all "
               "phases%s, combined per K (phases other than the reference placed by a rigid "
               "least-squares fit on the largest K's trajectory, which is rotated by its fitted "
               "track angle). Pair yaw: %s.",
            v->n_pings, v->k[v->n_k - 1].k, v->k[0].k,
            vo->nav.long_baselines ? " (with the pairs two steps apart, least squares)" : "", mode);
    if (vo->nav.pair.surge_sigma > 0)
        fprintf(f, " Surge prior (--surge-sigma): %.4g m.", vo->nav.pair.surge_sigma);
    if (vo->refine)
        fprintf(f, " Every phase refined on its own pings by the multi-ping data-domain fit "
                   "(docs/navigation.md).");
    fputs("\n\n", f);
    fprintf(f, "| K | stride | pairs | failed | flagged | track angle (rad) |%s time (s) |\n",
            v->has_truth ? " rms surge / sway vs truth (mm) | pairs alone (mm) |" : "");
    fprintf(f, "|---|---|---|---|---|---|%s---|\n", v->has_truth ? "---|---|" : "");
    for (int k = 0; k < v->n_k; k++) {
        const sasnav_validate_k *vk = &v->k[k];
        fprintf(f, "| %d | %d | %d | %d | %d | %+.4e |", vk->k, vk->stride, vk->n_pairs, vk->n_failed,
                vk->n_flagged, vk->track_angle);
        if (v->has_truth)
            fprintf(f, " %.3f / %.3f | %.3f / %.3f |", 1e3 * vk->rms_error.x, 1e3 * vk->rms_error.y,
                    1e3 * vk->rms_error_pairs.x, 1e3 * vk->rms_error_pairs.y);
        fprintf(f, " %.1f |\n", vk->seconds);
    }
    fprintf(f,
            "\nAgreement of the K trajectories: largest spread %.3f mm along track (ping %d, between K = %d "
            "and K = %d), %.3f mm across (ping %d) (paper: < 5 mm and < 0.5 mm).\n\n",
            1e3 * v->surge_spread, v->surge_spread_ping, v->surge_spread_k[0], v->surge_spread_k[1],
            1e3 * v->sway_spread, v->sway_spread_ping);
    if (vo->refine)
        fprintf(f, "The pair trajectories alone (before refinement): %.3f mm along track, %.3f mm across.\n\n",
                1e3 * v->surge_spread_pairs, 1e3 * v->sway_spread_pairs);
    fprintf(f, "Array yaw relative to the track: %.4e rad", v->yaw_estimate);
    if (v->has_truth)
        fprintf(f, " (error %+.2e rad); largest surge step (pings %d-%d) error %+.3f mm", v->yaw_error,
                v->jump_p, v->jump_p + 1, 1e3 * v->surge_jump_error);
    fprintf(f, ".\n\n");
    fprintf(f, "Complex image agreement over %d pixels within %g dB of the peak: minimum correlation "
               "%.3f over all %d navigated images (SISO-SISO %.3f, SIMO-SIMO %.3f, SISO-SIMO %.3f); "
               "with the nominal navigation %.3f, with the true navigation %.3f.\n\n",
            v->n_region, vo->region_db, v->min_correlation, v->n_k * (v->n_siso + v->n_simo), v->min_correlation_siso,
            v->min_correlation_simo, v->min_correlation_cross, v->min_correlation_nominal,
            v->min_correlation_truth);
    fprintf(f, "![surge](trajectories_surge.png)\n![sway](trajectories_sway.png)\n\n");
    fprintf(f, "![SISO 0](siso_0.png) ![SIMO 0](simo_0.png)\n\n");
    fprintf(f, "![SISO 0 nominal](nominal_siso_0.png) ![SIMO 0 nominal](nominal_simo_0.png)\n");
    return sasnav_text_commit(&out);
}

int cmd_validate(int argc, char **argv)
{
    static const struct option longopts[] = {
        {"k-min", required_argument, 0, 'a'}, {"k-max", required_argument, 0, 'b'},
        {"fix-yaw", no_argument, 0, 'F'},     {"yaw-sigma", required_argument, 0, 'y'},
        {"long-baselines", no_argument, 0, 'L'}, {"surge-sigma", required_argument, 0, 'U'},
        {"k", required_argument, 0, 'k'},     {"i", required_argument, 0, 'i'},
        {"grid", required_argument, 0, 'g'},  {"threads", required_argument, 0, 't'},
        {"gpu", no_argument, 0, 'G'},
        {"json", no_argument, 0, 'j'},        {"output", required_argument, 0, 'o'},
        {"refine", no_argument, 0, 'R'},   {"sweeps", required_argument, 0, 's'},
        {"sparsity", required_argument, 0, 'e'}, {"help", no_argument, 0, 'h'},
        {"checkpoint", required_argument, 0, 'C'},
        {0, 0, 0, 0}};
    sasnav_validate_opts vo;
    sasnav_validate_default_opts(&vo);
    const char *output = NULL, *checkpoint = NULL;
    long kmin = vo.k_min, kmax = 0, k = vo.nav.pair.k, iters = vo.nav.pair.i, threads = 0,
         sweeps = vo.refine_opts.sweeps;
    int json = 0, opt;
    optind = 1;
    while ((opt = getopt_long(argc, argv, "o:h", longopts, NULL)) != -1) {
        switch (opt) {
        case 'a': if (cli_parse_int(optarg, 1, 127, &kmin)) return cli_usage("validate", "--k-min needs 1..127"); break;
        case 'b': if (cli_parse_int(optarg, 1, 127, &kmax)) return cli_usage("validate", "--k-max needs 1..127"); break;
        case 'F': vo.nav.pair.fix_yaw = 1; break;
        case 'G': vo.nav.pair.gpu = 1; break;
        case 'L': vo.nav.long_baselines = 1; break;
        case 'y':
            if (cli_parse_double(optarg, &vo.nav.pair.yaw_sigma) || !(vo.nav.pair.yaw_sigma >= 0))
                return cli_usage("validate", "--yaw-sigma needs a standard deviation >= 0 (rad)");
            break;
        case 'U':
            if (cli_parse_double(optarg, &vo.nav.pair.surge_sigma) || !(vo.nav.pair.surge_sigma >= 0))
                return cli_usage("validate", "--surge-sigma needs a scale >= 0 (m)");
            break;
        case 'k': if (cli_parse_int(optarg, 1, 100, &k)) return cli_usage("validate", "--k needs 1..100"); break;
        case 'i': if (cli_parse_int(optarg, 1, 100, &iters)) return cli_usage("validate", "--i needs 1..100"); break;
        case 'g': if (cli_parse_grid(optarg, &vo.grid)) return cli_usage("validate", "--grid: %s", sasnav_last_error()); break;
        case 't': if (cli_parse_int(optarg, 0, 1024, &threads)) return cli_usage("validate", "--threads needs 0..1024"); break;
        case 'j': json = 1; break;
        case 'R': vo.refine = 1; break;
        case 's':
            if (cli_parse_int(optarg, 1, SASNAV_REFINE_MAX_SWEEPS, &sweeps))
                return cli_usage("validate", "--sweeps needs 1..%d", SASNAV_REFINE_MAX_SWEEPS);
            break;
        case 'e':
            if (cli_parse_double(optarg, &vo.refine_opts.sparsity) ||
                !(vo.refine_opts.sparsity >= 0 && vo.refine_opts.sparsity <= 1e6))
                return cli_usage("validate", "--sparsity needs a number in [0, 1e6]");
            break;
        case 'o': output = optarg; break;
        case 'C': checkpoint = optarg; break;
        case 'h': fputs(help, stdout); return 0;
        default: return cli_bad_option("validate", argv, longopts);
        }
    }
    if (optind != argc - 1) return cli_usage("validate", "exactly one input run file is required");
    if (!output) return cli_usage("validate", "an output directory is required (-o DIR)");
    if (sasnav_pair_opts_check(&vo.nav.pair))
        return cli_usage("validate", "%s", sasnav_last_error());
    const char *input = argv[optind];
    vo.k_min = (int)kmin;
    vo.k_max = (int)kmax;
    vo.nav.pair.k = (int)k;
    vo.nav.pair.i = (int)iters;
    if (vo.nav.pair.coarse_k > vo.nav.pair.k) vo.nav.pair.coarse_k = vo.nav.pair.k;
    if (vo.nav.pair.coarse_i > vo.nav.pair.i) vo.nav.pair.coarse_i = vo.nav.pair.i;
    vo.nav.nthreads = (int)threads;
    vo.refine_opts.sweeps = (int)sweeps;
    vo.refine_opts.nthreads = (int)threads;
    vo.op.nthreads = (int)threads;

    validate_progress vp = {{0}, 0};
    cli_progress_init(&vp.p, "validate", "pairs");
    vo.nav.progress = progress_line;
    vo.nav.progress_user = &vp;
    sasnav_run *run = NULL;
    int rc = sasnav_run_read(input, &run);
    if (rc) return cli_fail("validate", rc, "cannot read %s", input);
    cli_checkpoint ck;
    if (cli_checkpoint_begin(&ck, "validate", checkpoint, &vo.nav)) {
        sasnav_run_free(run);
        return CLI_FAILURE;
    }
    sasnav_validation v;
    rc = sasnav_validate(run, &vo, &v);
    sasnav_run_free(run);
    cli_progress_end(&vp.p);
    if (rc) {
        rc = cli_fail("validate", rc, "validation of %s failed", input);
        cli_checkpoint_end(&ck, 0);
        return rc;
    }
    if (mkdir(output, 0777) && errno != EEXIST) {
        sasnav_validation_free(&v);
        rc = cli_fail("validate", 0, "cannot create %s: %s", output, strerror(errno));
        cli_checkpoint_end(&ck, 0);
        return rc;
    }
    json_t *root = summary(input, &v, vo.refine);
    char *text = json_dumps(root, JSON_INDENT(2) | JSON_REAL_PRECISION(10));
    json_decref(root);
    char path[4096];
    join(path, sizeof path, output, "validate.json");
    const char *mode = vo.nav.pair.fix_yaw ? "held at 0 (--fix-yaw)"
                       : vo.nav.pair.yaw_sigma > 0 ? "estimated with a prior (--yaw-sigma)" : "estimated";
    rc = text ? write_text(path, text) : sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    if (!rc) rc = write_tables(output, &v);
    if (!rc) rc = plot_trajectories(output, &v);
    if (!rc) rc = plot_images(output, &v);
    if (!rc) rc = write_report(output, input, &v, mode, &vo);
    if (rc) {
        free(text);
        sasnav_validation_free(&v);
        rc = cli_fail("validate", rc, "cannot write the outputs in %s", output);
        cli_checkpoint_end(&ck, 0);
        return rc;
    }
    cli_checkpoint_end(&ck, 1);
    if (json) puts(text);
    else {
        printf("K trajectories: spread %.3f mm along track (ping %d, K = %d vs %d), %.3f mm across (ping %d)\n",
               1e3 * v.surge_spread, v.surge_spread_ping, v.surge_spread_k[0], v.surge_spread_k[1],
               1e3 * v.sway_spread, v.sway_spread_ping);
        if (vo.refine)
            printf("pair trajectories alone: spread %.3f mm along track, %.3f mm across\n",
                   1e3 * v.surge_spread_pairs, 1e3 * v.sway_spread_pairs);
        printf("array yaw relative to the track %.4e rad", v.yaw_estimate);
        if (v.has_truth)
            printf(" (error %+.2e); surge jump %d-%d error %+.3f mm", v.yaw_error, v.jump_p, v.jump_p + 1,
                   1e3 * v.surge_jump_error);
        printf("\nimage correlation: min %.3f (SISO %.3f, SIMO %.3f, SISO-SIMO %.3f; nominal nav %.3f",
               v.min_correlation, v.min_correlation_siso, v.min_correlation_simo, v.min_correlation_cross,
               v.min_correlation_nominal);
        if (v.has_truth) printf(", true nav %.3f", v.min_correlation_truth);
        printf(")\n");
    }
    int n_pairs = 0, n_flagged = 0, n_coincident = 0;
    for (int j = 0; j < v.n_k; j++) {
        n_pairs += v.k[j].n_pairs;
        n_flagged += v.k[j].n_flagged;
        for (int i = 0; i < v.k[j].n_pairs; i++)
            n_coincident += v.k[j].pairs[i].verdict != SASNAV_VERDICT_OK && v.k[j].pairs[i].result.coincidence;
    }
    if (n_flagged)
        fprintf(stderr,
                "sasnav validate: warning: %d of %d pairs flagged (verdict not \"ok\"; %d of them at a "
                "phase-centre coincidence on a compact scene, where surge is not resolved), used as "
                "estimated; see pairs.csv\n",
                n_flagged, n_pairs, n_coincident);
    fprintf(stderr, "sasnav validate: %d trajectories, %d images, %.1f s -> %s\n", v.n_k, v.n_images,
            v.seconds, output);
    free(text);
    sasnav_validation_free(&v);
    return 0;
}
