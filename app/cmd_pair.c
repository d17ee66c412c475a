/* sasnav pair: subspace-intersection estimate of the motion error between
 * two pings of a run (paper Section III). */
#include "cli.h"
#include "sasnav/estimator.h"
#include "sasnav/io.h"

#include <getopt.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *help =
    "usage: sasnav pair run.h5 [--p I --q J] [--json] [--k K] [--i I]\n"
    "                   [--prior S,W,Y] [--yaw-sigma S | --fix-yaw] [--surge-sigma S]\n"
    "                   [--cross-extent M] [--range-extent M]\n"
    "                   [--no-global] [--search-grid G] [--subintervals N]\n"
    "                   [--eta-max E] [--coincidence F] [--compact-contrast C]\n"
    "                   [--final C] [--equalise M]\n"
    "                   [--range R] [--lag-model fixed|motion] [--threads N] [--gpu]\n"
    "\n"
    "Estimates the motion error (displacement minus nominal) of ping q relative\n"
    "to ping p: surge and sway in metres, yaw in radians. Without --p/--q the\n"
    "first two pings are used. Where the file holds ground truth, prints the\n"
    "true values and the errors.\n"
    "\n"
    "A single pair's verdict lacks the run's checks: `sasnav navigate` also\n"
    "flags a pair whose eta stands far above its run's (a bright feature just\n"
    "under the compact gate can pull an estimate that passes here as 'ok':\n"
    "docs/navigation.md, \"On scenarios drawn at random\").\n"
    "\n"
    "  --p I, --q J      ping indices (0-based)\n"
    "  --json            machine-readable output\n"
    "  --k K, --i I      CGLS and alternating-projection iterations of the\n"
    "                    final stage (default 8, 8; the paper's 5, 5 are 1.5x\n"
    "                    faster, with larger surge errors: docs/estimator.md)\n"
    "  --prior S,W,Y     prior motion error (default 0,0,0)\n"
    "  --surge-sigma S   scale of a prior on the surge error (m; the nominal\n"
    "                    step's accuracy, e.g. a plotter's; default none): ranks\n"
    "                    the global stage's candidates one phase-centre spacing\n"
    "                    apart, which look alike on compact scenes at a squint\n"
    "  --no-global       skip the global stage (local search from the prior)\n"
    "  --search-grid G   grid of the search stages before the final one: auto\n"
    "                    (default: coarse on a speckle-like scene, fine on a\n"
    "                    few bright reflectors), fine (full pixels) or coarse\n"
    "                    (the global stage's; 1.25x faster on seabed pairs;\n"
    "                    docs/estimator.md)\n"
    "  --box S,W,Y       half-widths of the search box around the prior (m, m,\n"
    "                    rad; default 0.06, 0.035 and the grating-lobe-safe yaw)\n"
    "  --range R         centre range of the estimation grid (default: the run's\n"
    "                    range of interest)\n"
    "  --range-extent M  range extent of the estimation grid (m, default 1.6;\n"
    "                    split between the sub-intervals)\n"
    "  --subintervals N  split the swath into N range sub-intervals, each with\n"
    "                    its own EPCA offset and estimate (paper III-B)\n"
    "  --lag-model M     Tx-array offset per sub-interval: 'fixed' (the run's\n"
    "                    tx_lag, default) or 'motion' (speed x 2 R / c at the\n"
    "                    sub-interval's centre range R)\n"
    "  --final C         the final stage's criterion: 'auto' (default: the joint\n"
    "                    misfit when the pings' relative yaw is small, the\n"
    "                    scene speckle-like and the grid covers half the beam's\n"
    "                    footprint, eta otherwise),\n"
    "                    'eta' (the paper's) or 'joint' (one scene explains\n"
    "                    both pings; docs/estimator.md, \"A joint-misfit final\n"
    "                    stage\")\n"
    "  --eta-max E       final eta above which the verdict is 'failed' (default\n"
    "                    0.6, calibrated at 10 m; correct survey-class pairs at\n"
    "                    70 m reach 0.6, slipped ones ~0.95: docs/estimator.md,\n"
    "                    \"A survey-class system\")\n"
    "  --coincidence F   on compact scenes, an estimate within F phase-centre\n"
    "                    spacings of a phase-centre coincidence is 'ambiguous'\n"
    "                    (its surge is not resolved there; default 0.5: all, 0 off;\n"
    "                    compact scenes also need an eta margin of 1.25 for\n"
    "                    'ok': docs/estimator.md, \"Verdict\")\n"
    "  --compact-contrast C  the intensity contrast of p's image or of q's above\n"
    "                    which the scene is compact for the verdict (default 4;\n"
    "                    speckle about 1, simulated seabeds up to 3.9; 'inf':\n"
    "                    never; reported as 'contrast', 'contrast_q' in --json)\n"
    "  --equalise M      on a scene speckle-like at the prior where a feature\n"
    "                    stands out (its intensity smoothed over 5 cm peaks 9 dB\n"
    "                    over the mean),\n"
    "                    the search weights each pixel by the inverse square root\n"
    "                    of the images' intensity smoothed over M metres, so that\n"
    "                    a feature far brighter than the seabed does not lead it\n"
    "                    astray; the final stage and the verdict's eta stay\n"
    "                    unweighted\n"
    "                    (default 0.05, at most 0.25; 0: off; 'equalised' and the\n"
    "                    gate's 'equalise_peak' in --json;\n"
    "                    docs/estimator.md, \"An equalised search\")\n"
    "  --threads N       OpenMP threads\n"
    "  --gpu             the error evaluations on a CUDA GPU (builds configured\n"
    "                    with -DSASNAV_CUDA=ON; the same estimates to float\n"
    "                    rounding: docs/estimator.md, \"GPU\")\n";

typedef struct {
    double range, tx_lag;
    sasnav_pair_result res;
    int rc;
    int tx_yaw_from_estimate;
} interval_result;

static json_t *pose_json(sasnav_pose e)
{
    return json_pack("{s:f,s:f,s:f}", "surge", e.x, "sway", e.y, "yaw", e.theta);
}

static void print_pose(const char *label, sasnav_pose e)
{
    printf("%-14s surge %+9.3f mm   sway %+9.4f mm   yaw %+.4e rad\n", label, 1e3 * e.x, 1e3 * e.y,
           e.theta);
}

/* A value for the text output, or "-" where it was not computed (NaN: the
 * zeta of a pair stopped for want of overlap, the scan's zeta of a
 * candidate that was not found by a scan: a slip-check neighbour). */
static void format_value(char *buf, size_t size, const char *fmt, double v)
{
    if (isfinite(v)) snprintf(buf, size, fmt, v);
    else snprintf(buf, size, "-");
}

int cmd_pair(int argc, char **argv)
{
    static const struct option longopts[] = {
        {"p", required_argument, 0, 'P'},     {"q", required_argument, 0, 'Q'},
        {"json", no_argument, 0, 'j'},        {"k", required_argument, 0, 'k'},
        {"i", required_argument, 0, 'i'},     {"prior", required_argument, 0, 'r'},
        {"no-global", no_argument, 0, 'G'},   {"subintervals", required_argument, 0, 'S'},
        {"range", required_argument, 0, 'R'}, {"threads", required_argument, 0, 't'},
        {"lag-model", required_argument, 0, 'L'}, {"box", required_argument, 0, 'b'},
        {"yaw-sigma", required_argument, 0, 'y'}, {"fix-yaw", no_argument, 0, 'F'},
        {"cross-extent", required_argument, 0, 'X'}, {"surge-sigma", required_argument, 0, 'U'},
        {"range-extent", required_argument, 0, 'E'}, {"gpu", no_argument, 0, 'g'},
        {"eta-max", required_argument, 0, 'e'}, {"help", no_argument, 0, 'h'},
        {"final", required_argument, 0, 'C'},   {"search-grid", required_argument, 0, 'f'},
        {"coincidence", required_argument, 0, 'c'}, {"compact-contrast", required_argument, 0, 'T'},
        {"equalise", required_argument, 0, 'W'},
        {0, 0, 0, 0}};
    long p = 0, q = 1, k = 8, iters = 8, nsub = 1, threads = 0;
    int json = 0, no_global = 0, have_p = 0, have_q = 0, motion_lag = 0, fix_yaw = 0, gpu = 0,
        search_grid = SASNAV_SEARCH_AUTO;
    double prior[3] = {0, 0, 0}, range = NAN, box[3] = {NAN, NAN, NAN}, yaw_sigma = 0, cross_extent = 0,
           surge_sigma = 0, range_extent = 0, eta_max = 0, coincidence = NAN,
           compact_contrast = NAN, equalise = NAN;
    int final_c = SASNAV_FINAL_AUTO;
    int opt;
    optind = 1;
    while ((opt = getopt_long(argc, argv, "h", longopts, NULL)) != -1) {
        switch (opt) {
        case 'P': if (cli_parse_int(optarg, 0, 1000000, &p)) return cli_usage("pair", "--p needs a ping index"); have_p = 1; break;
        case 'Q': if (cli_parse_int(optarg, 0, 1000000, &q)) return cli_usage("pair", "--q needs a ping index"); have_q = 1; break;
        case 'j': json = 1; break;
        case 'k': if (cli_parse_int(optarg, 1, 100, &k)) return cli_usage("pair", "--k needs 1..100"); break;
        case 'i': if (cli_parse_int(optarg, 1, 100, &iters)) return cli_usage("pair", "--i needs 1..100"); break;
        case 'r': if (cli_parse_doubles(optarg, 3, prior)) return cli_usage("pair", "--prior needs SURGE,SWAY,YAW"); break;
        case 'G': no_global = 1; break;
        case 'f':
            search_grid = sasnav_search_grid_parse(optarg);
            if (search_grid < 0) return cli_usage("pair", "--search-grid needs auto, fine or coarse");
            break;
        case 'b':
            if (cli_parse_doubles(optarg, 3, box) || !(box[0] > 0 && box[1] > 0 && box[2] > 0))
                return cli_usage("pair", "--box needs three positive half-widths S,W,Y");
            break;
        case 'F': fix_yaw = 1; break;
        case 'g': gpu = 1; break;
        case 'X':
            if (cli_parse_double(optarg, &cross_extent) || !(cross_extent > 0))
                return cli_usage("pair", "--cross-extent needs a positive length (m)");
            break;
        case 'E':
            if (cli_parse_double(optarg, &range_extent) || !(range_extent > 0 && range_extent <= 100))
                return cli_usage("pair", "--range-extent needs a length in (0, 100] m");
            break;
        case 'e':
            if (cli_parse_double(optarg, &eta_max) || !(eta_max > 0 && eta_max <= 10))
                return cli_usage("pair", "--eta-max needs a bound in (0, 10]");
            break;
        case 'c':
            if (cli_parse_double(optarg, &coincidence) || !(coincidence >= 0 && coincidence <= 0.5))
                return cli_usage("pair", "--coincidence needs a fraction of the phase-centre spacing in [0, 0.5]");
            break;
        case 'T':
            if (cli_parse_nonneg_or_inf(optarg, &compact_contrast))
                return cli_usage("pair", "--compact-contrast needs a contrast >= 0 (or inf)");
            break;
        case 'W':
            if (cli_parse_double(optarg, &equalise) || !(equalise >= 0 && equalise <= 0.25))
                return cli_usage("pair", "--equalise needs a smoothing length in [0, 0.25] m (0: off)");
            break;
        case 'C':
            final_c = sasnav_final_criterion_parse(optarg);
            if (final_c < 0) return cli_usage("pair", "--final needs auto, eta or joint");
            break;
        case 'y':
            if (cli_parse_double(optarg, &yaw_sigma) || !(yaw_sigma >= 0))
                return cli_usage("pair", "--yaw-sigma needs a standard deviation >= 0 (rad)");
            break;
        case 'U':
            if (cli_parse_double(optarg, &surge_sigma) || !(surge_sigma >= 0))
                return cli_usage("pair", "--surge-sigma needs a scale >= 0 (m)");
            break;
        case 'S': if (cli_parse_int(optarg, 1, 64, &nsub)) return cli_usage("pair", "--subintervals needs 1..64"); break;
        case 'R': if (cli_parse_double(optarg, &range) || !(range > 0)) return cli_usage("pair", "--range needs a positive number"); break;
        case 't': if (cli_parse_int(optarg, 0, 1024, &threads)) return cli_usage("pair", "--threads needs 0..1024"); break;
        case 'L':
            if (!strcmp(optarg, "motion")) motion_lag = 1;
            else if (strcmp(optarg, "fixed")) return cli_usage("pair", "--lag-model is 'fixed' or 'motion'");
            break;
        case 'h': fputs(help, stdout); return 0;
        default: return cli_bad_option("pair", argv, longopts);
        }
    }
    if (optind != argc - 1) return cli_usage("pair", "exactly one input run file is required");
    if (have_p && !have_q) q = p + 1;
    if (have_q && !have_p) p = q - 1;
    const char *input = argv[optind];
    sasnav_run *run = NULL;
    int rc = sasnav_run_read(input, &run);
    if (rc) return cli_fail("pair", rc, "cannot read %s", input);
    if (p == q) {
        sasnav_run_free(run);
        return cli_usage("pair", "--p and --q name the same ping (%ld)", p);
    }
    if (p < 0 || q < 0 || p >= run->n_pings || q >= run->n_pings) {
        int n = run->n_pings;
        sasnav_run_free(run);
        long bad = p < 0 || p >= n ? p : q;
        return cli_fail("pair", 0, "--%c %ld: %s has %d pings (0..%d)", bad == p && (p < 0 || p >= n) ? 'p' : 'q',
                        bad, input, n, n - 1);
    }
    if (!isfinite(range)) range = run->range_of_interest > 0 ? run->range_of_interest : 10.0;
    sasnav_pose nominal = sasnav_ping_displacement(&run->nav[p], &run->nav[q]);
    int have_truth = run->truth != NULL;
    sasnav_pose truth = {0, 0, 0};
    if (have_truth) {
        sasnav_pose d = sasnav_ping_displacement(&run->truth[p], &run->truth[q]);
        truth = (sasnav_pose){d.x - nominal.x, d.y - nominal.y, sasnav_wrap_angle(d.theta - nominal.theta)};
    }

    interval_result *out = calloc((size_t)nsub, sizeof *out);
    if (!out) {
        sasnav_run_free(run);
        return cli_fail("pair", 0, "out of memory");
    }
    sasnav_pair_opts po;
    sasnav_pair_default_opts(&po);
    po.k = (int)k;
    po.i = (int)iters;
    po.prior = (sasnav_pose){prior[0], prior[1], prior[2]};
    po.global_stage = !no_global;
    po.search_grid = search_grid;
    if (!isnan(box[0])) po.box = (sasnav_pose){box[0], box[1], box[2]};
    po.nthreads = (int)threads;
    po.yaw_sigma = yaw_sigma;
    po.surge_sigma = surge_sigma;
    po.fix_yaw = fix_yaw;
    po.gpu = gpu;
    if (cross_extent > 0) po.cross_extent = cross_extent;
    if (range_extent > 0) po.range_extent = range_extent;
    if (eta_max > 0) po.verdict_eta_max = eta_max;
    if (!isnan(coincidence)) po.verdict_coincidence = coincidence;
    if (!isnan(compact_contrast)) po.verdict_contrast = compact_contrast;
    if (!isnan(equalise)) po.equalise = equalise;
    po.final_criterion = final_c;
    if (sasnav_pair_opts_check(&po)) {
        sasnav_run_free(run);
        free(out);
        return cli_usage("pair", "%s", sasnav_last_error());
    }
    po.range = range;
    po.tx_lag = run->tx_lag;
    sasnav_pair_interval *iv = calloc((size_t)nsub, sizeof *iv);
    rc = iv ? sasnav_pair_estimate_intervals(run, (int)p, (int)q, &po, nsub, motion_lag, iv)
            : sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    if (rc) {
        sasnav_run_free(run);
        free(out);
        free(iv);
        return rc == SASNAV_ERR_ARG ? cli_fail("pair", rc, "%s", input) : cli_fail("pair", rc, "estimate");
    }
    int failed = 0;
    for (int s = 0; s < nsub; s++) {
        out[s].range = iv[s].range;
        out[s].tx_lag = iv[s].tx_lag;
        out[s].res = iv[s].result;
        out[s].rc = iv[s].status;
        out[s].tx_yaw_from_estimate = iv[s].tx_yaw_from_estimate;
        if (iv[s].status) {
            failed = 1;
            cli_fail("pair", 0, "pings %ld-%ld, range %.2f m: %s", p, q, iv[s].range,
                     sasnav_strerror(iv[s].status));
            if (!json) break;
        }
    }
    free(iv);
    /* channels with transmitters of their own: where their turn came from */
    const char *tx_yaw = !run->channel_offset                      ? NULL
                         : run->aiding && run->aiding->yaw_rate    ? "gyro"
                         : out[0].tx_yaw_from_estimate             ? "estimate"
                                                                   : "none";
    sasnav_run_free(run);
    if (failed && !json) {
        free(out);
        return 1;
    }
    if (json) {
        json_t *root = json_object();
        const sasnav_pair_result *r0 = &out[0].res;
        json_object_set_new(root, "p", json_integer(p));
        json_object_set_new(root, "q", json_integer(q));
        json_object_set_new(root, "surge", json_real(r0->error.x));
        json_object_set_new(root, "sway", json_real(r0->error.y));
        json_object_set_new(root, "yaw", json_real(r0->error.theta));
        json_object_set_new(root, "displacement", json_pack("{s:f,s:f,s:f}", "x", r0->displacement.x,
                                                            "y", r0->displacement.y, "theta", r0->displacement.theta));
        json_object_set_new(root, "nominal", json_pack("{s:f,s:f,s:f}", "x", nominal.x, "y", nominal.y, "theta", nominal.theta));
        if (have_truth) {
            json_object_set_new(root, "truth", pose_json(truth));
            json_object_set_new(root, "estimation_error",
                                pose_json((sasnav_pose){r0->error.x - truth.x, r0->error.y - truth.y, r0->error.theta - truth.theta}));
        }
        json_object_set_new(root, "global_stage", pose_json(r0->global_stage));
        json_object_set_new(root, "zeta_stage", pose_json(r0->zeta_stage));
        json_object_set_new(root, "zeta", json_real(r0->zeta));
        json_object_set_new(root, "eta", json_real(r0->eta));
        json_object_set_new(root, "final_criterion", json_string(sasnav_final_criterion_name(r0->final_criterion)));
        json_object_set_new(root, "joint_rejected", json_boolean(r0->joint_rejected));
        json_object_set_new(root, "search_grid", json_string(sasnav_search_grid_name(r0->search_grid)));
        json_object_set_new(root, "contrast", json_real(r0->contrast));
        json_object_set_new(root, "contrast_q", json_real(r0->contrast_q));
        json_object_set_new(root, "equalised", json_boolean(r0->equalised));
        json_object_set_new(root, "equalise_peak", json_real(r0->equalise_peak));
        json_object_set_new(root, "overlap", json_real(r0->overlap));
        json_object_set_new(root, "ambiguity", json_real(r0->ambiguity));
        json_object_set_new(root, "evaluations", json_integer(r0->evaluations));
        json_object_set_new(root, "evaluations_global", json_integer(r0->evaluations_global));
        json_object_set_new(root, "evaluations_zeta", json_integer(r0->evaluations_zeta));
        json_object_set_new(root, "evaluations_eta", json_integer(r0->evaluations_eta));
        json_object_set_new(root, "operator_applications", json_integer(r0->applications));
        json_object_set_new(root, "evaluations_final", json_integer(r0->evaluations_final));
        json_object_set_new(
            root, "stages",
            json_pack("{s:{s:f,s:I},s:{s:f,s:I},s:{s:f,s:I},s:{s:f,s:I}}", "global", "seconds",
                      r0->seconds_global, "applications", (json_int_t)r0->applications_global, "zeta",
                      "seconds", r0->seconds_zeta, "applications", (json_int_t)r0->applications_zeta,
                      "eta", "seconds", r0->seconds_eta, "applications", (json_int_t)r0->applications_eta,
                      "final", "seconds", r0->seconds_final, "applications",
                      (json_int_t)r0->applications_final));
        json_object_set_new(root, "seconds", json_real(r0->seconds));
        if (tx_yaw) json_object_set_new(root, "tx_yaw", json_string(tx_yaw));
        const char *st = out[0].rc ? sasnav_strerror(out[0].rc)
                         : r0->status == SASNAV_OK ? "converged" : sasnav_strerror(r0->status);
        json_object_set_new(root, "status", json_string(st));
        json_object_set_new(root, "verdict", json_string(out[0].rc ? "failed" : sasnav_verdict_name(r0->verdict)));
        json_object_set_new(root, "margin", isfinite(r0->margin) ? json_real(r0->margin) : json_null());
        json_object_set_new(root, "coincidence", json_boolean(!out[0].rc && r0->coincidence));
        json_t *cands = json_array();
        for (int kc = 0; kc < r0->n_candidates; kc++) {
            const sasnav_pair_candidate *c = &r0->candidates[kc];
            json_t *o = pose_json(c->error);
            json_object_set_new(o, "zeta_scan", isfinite(c->zeta_scan) ? json_real(c->zeta_scan) : json_null());
            json_object_set_new(o, "zeta", isfinite(c->zeta) ? json_real(c->zeta) : json_null());
            json_object_set_new(o, "eta", isfinite(c->eta) ? json_real(c->eta) : json_null());
            json_object_set_new(o, "refined", json_boolean(c->refined));
            json_object_set_new(o, "chosen", json_boolean(kc == r0->chosen));
            if (c->same_as >= 0) json_object_set_new(o, "same_as", json_integer(c->same_as));
            json_array_append_new(cands, o);
        }
        json_object_set_new(root, "candidates", cands);
        if (nsub > 1) {
            json_t *arr = json_array();
            for (int s = 0; s < nsub; s++) {
                const sasnav_pair_result *r = &out[s].res;
                json_t *o = json_pack("{s:f,s:f,s:f,s:f,s:f,s:o,s:i,s:s}", "range", out[s].range,
                                      "tx_lag", out[s].tx_lag, "surge", r->error.x, "sway", r->error.y,
                                      "yaw", r->error.theta, "zeta_stage", pose_json(r->zeta_stage),
                                      "evaluations", r->evaluations, "status",
                                      out[s].rc ? sasnav_strerror(out[s].rc)
                                      : r->status == SASNAV_OK ? "converged" : sasnav_strerror(r->status));
                json_array_append_new(arr, o);
            }
            json_object_set_new(root, "subintervals", arr);
        }
        char *text = json_dumps(root, JSON_INDENT(2) | JSON_REAL_PRECISION(10));
        if (text) puts(text);
        free(text);
        json_decref(root);
        free(out);
        return failed ? 1 : 0;
    }
    for (int s = 0; s < nsub; s++) {
        const sasnav_pair_result *r = &out[s].res;
        if (nsub > 1) printf("sub-interval %d: range %.3f m, Tx-array offset %.3f m\n", s, out[s].range, out[s].tx_lag);
        else printf("pings %ld -> %ld, range %.3f m, nominal displacement (%.4f m, %.4f m, %.4g rad)\n", p, q,
                    out[s].range, nominal.x, nominal.y, nominal.theta);
        print_pose("global stage", r->global_stage);
        print_pose("zeta stage", r->zeta_stage);
        print_pose("estimate", r->error);
        if (have_truth) {
            print_pose("truth", truth);
            print_pose("error", (sasnav_pose){r->error.x - truth.x, r->error.y - truth.y, r->error.theta - truth.theta});
        }
        printf("displacement   x %.6f m   y %.6f m   theta %.6e rad\n", r->displacement.x, r->displacement.y,
               r->displacement.theta);
        /* No hint where the estimate stopped (without overlap there is no
         * valley to choose in). */
        int hint = r->status == SASNAV_OK && r->ambiguity > 0.8;
        if (hint && fix_yaw)
            printf("ambiguity %.2f: the second surge candidate, a phase-centre spacing away, is nearly "
                   "as good (compact scene at a squint?%s)\n", r->ambiguity,
                   surge_sigma > 0 ? "" : " consider --surge-sigma");
        else if (hint)
            printf("ambiguity %.2f: the second surge-yaw candidate of the valley is nearly as good "
                   "(compact scene? consider --yaw-sigma)\n", r->ambiguity);
        char zeta_s[32];
        format_value(zeta_s, sizeof zeta_s, "%.4g", r->zeta);
        printf("zeta %s  eta %.4g  overlap %.3g  evaluations %d (global %d, zeta %d, eta %d)  "
               "operator applications %ld  %.2f s  status %s\n",
               zeta_s, r->eta, r->overlap, r->evaluations, r->evaluations_global, r->evaluations_zeta,
               r->evaluations_eta, r->applications, r->seconds,
               r->status == SASNAV_OK ? "converged" : sasnav_strerror(r->status));
        char peak_s[48] = "";
        if (r->equalise_peak > 0)
            snprintf(peak_s, sizeof peak_s, ", intensity peak %.1f x mean", r->equalise_peak);
        printf("time per stage: global %.2f s (%ld applications), zeta %.2f s (%ld), eta %.2f s (%ld), "
               "final %.2f s (%ld, %d evaluations, criterion %s); search grid %s%s; contrast %.2f (q %.2f)%s\n",
               r->seconds_global, r->applications_global, r->seconds_zeta, r->applications_zeta,
               r->seconds_eta, r->applications_eta, r->seconds_final, r->applications_final,
               r->evaluations_final,
               r->joint_rejected ? "eta, the joint misfit's estimate rejected"
                                 : sasnav_final_criterion_name(r->final_criterion),
               sasnav_search_grid_name(r->search_grid), r->equalised ? ", equalised" : "", r->contrast,
               r->contrast_q, peak_s);
        for (int kc = 0; kc < r->n_candidates; kc++) {
            const sasnav_pair_candidate *c = &r->candidates[kc];
            char scan_s[32];
            format_value(scan_s, sizeof scan_s, "%.4f", c->zeta_scan);
            printf("candidate %d%s  surge %+8.3f mm  sway %+9.4f mm  yaw %+.4e rad  zeta(scan) %s", kc,
                   kc == r->chosen ? "*" : " ", 1e3 * c->error.x, 1e3 * c->error.y, c->error.theta,
                   scan_s);
            if (c->refined) printf("  eta(search) %.4f", c->eta);
            if (c->same_as >= 0) printf("  (= candidate %d)", c->same_as);
            printf("\n");
        }
        printf("verdict %s", sasnav_verdict_name(r->verdict));
        if (isfinite(r->margin)) printf(" (eta margin to the next candidate %.3f)", r->margin);
        if (r->coincidence) printf(" (at a phase-centre coincidence on a compact scene: surge not resolved)");
        printf("\n");
        if (r->verdict != SASNAV_VERDICT_OK)
            fprintf(stderr, "sasnav pair: warning: pings %ld-%ld: the estimate is %s%s (docs/estimator.md, \"Verdict\")\n",
                    p, q, sasnav_verdict_name(r->verdict),
                    r->coincidence ? ", at a phase-centre coincidence on a compact scene" : "");
    }
    free(out);
    return 0;
}

