/* sasnav navigate: the trajectory of a whole run from ping-pair estimates
 * (paper Section IV-C). */
#include "cli.h"
#include "core/clock.h"
#include "sasnav/io.h"
#include "sasnav/navigate.h"
#include "sasnav/virtual.h"

#include <getopt.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* getopt value of --equalise (no short option) */
#define OPT_EQUALISE 1001
#define OPT_ALONG_TRACK 1002
#define OPT_LINK_SIGMA 1003
#define OPT_LINK_ETA 1004

static const char *help =
    "usage: sasnav navigate run.h5 [--method subspace|dpca|aiding] [--long-baselines]\n"
    "                       [--k K] [--i I] [--yaw-sigma S | --fix-yaw] [--surge-sigma S]\n"
    "                       [--cross-extent M] [--range-extent M] [--eta-max E] [--final C]\n"
    "                       [--search-grid G] [--coincidence F] [--compact-contrast C]\n"
    "                       [--eta-outlier R] [--equalise M] [--no-aiding] [--no-resolve]\n"
    "                       [--motion-sigma S,W,Y] [--speed-lags none|dvl|pairs]\n"
    "                       [--aiding-bias S,W,Y] [--link-sigma S,W,Y] [--link-eta E]\n"
    "                       [--threads N] [--gpu] [--json] [--checkpoint FILE]\n"
    "                       [--first-pose X,Y,YAW | --anchor-truth] -o nav.h5\n"
    "       sasnav navigate run.h5 --virtual-array K [--interleave M] [--stride S]\n"
    "                       [--iterations N] [--closed] [--keep-length] [--align-heading]\n"
    "                       [--along-track echoes|input] [--estimate-yaw] [--k K] [--i I]\n"
    "                       [--cross-extent M] [--range-extent M] [--threads N] [--json]\n"
    "                       -o nav.h5\n"
    "\n"
    "Estimates the displacement of every consecutive ping pair, composes them\n"
    "into a trajectory starting at the run's nominal first ping, aligns it to\n"
    "the nominal track (the removed track angle is reported) and writes the\n"
    "estimated navigation (docs/format.md; with the run's ground truth when it\n"
    "has one). Where the run holds the truth, prints the per-pair errors and\n"
    "the cumulative errors of the trajectory (the true trajectory moved\n"
    "rigidly onto the estimated first ping: the first pose is not observable).\n"
    "\n"
    "Every pair gets a verdict (ok, ambiguous, failed, no_overlap; one warning\n"
    "line on stderr for each pair that is not ok; DPCA's estimates are\n"
    "'unchecked', one line for them all). The pairs are then resolved\n"
    "jointly over the run: a choice among each pair's candidates with a motion\n"
    "model of the vehicle and the run's aiding measurements (gyro, DVL: written\n"
    "by 'sasnav simulate --aiding' or by the user, docs/format.md), new estimates\n"
    "where a pair failed or disagrees with the aiding, and a robust smoother\n"
    "fusing estimates, aiding and motion model (docs/navigation.md). A pair\n"
    "without a usable estimate is bridged by the aiding and the motion model\n"
    "and reported; the exit status stays 0.\n"
    "\n"
    "  --method M        subspace (default; subspace intersection), dpca, or\n"
    "                    aiding (the run's gyro and DVL alone: dead reckoning)\n"
    "  --long-baselines  also estimate pairs (p, p+2) and combine all by least\n"
    "                    squares (skipped where they share < 2 phase centres)\n"
    "  --k K, --i I      CGLS and alternating-projection iterations of the\n"
    "                    subspace estimator's final stage (default: the\n"
    "                    estimator's, see 'sasnav pair --help')\n"
    "  --yaw-sigma S     prior on each pair's yaw error, rad (gyro or rail;\n"
    "                    default none): resolves the surge-yaw ambiguity of\n"
    "                    compact scenes (see 'sasnav pair --help')\n"
    "  --surge-sigma S   scale of a prior on each pair's surge error, m (the\n"
    "                    nominal step's accuracy; default none; see 'sasnav\n"
    "                    pair --help')\n"
    "  --cross-extent M  along-track extent of the estimation grid (see\n"
    "                    'sasnav pair --help')\n"
    "  --range-extent M  range extent of the estimation grid (m, default 1.6;\n"
    "                    without a gyro a longer grid tells yaw better on a\n"
    "                    seabed that fills the swath: 4 m, 3x smaller yaw\n"
    "                    errors for 2.5x the time; docs/estimator.md)\n"
    "  --eta-max E       final eta above which a pair's verdict is 'failed'\n"
    "                    (default 0.6; see 'sasnav pair --help')\n"
    "  --coincidence F   compact scenes: a pair within F phase-centre spacings\n"
    "                    of a coincidence is 'ambiguous' (default 0.5: all, 0 off;\n"
    "                    with --virtual-array off unless given); compact\n"
    "                    scenes also need an eta margin of 1.25 for 'ok' (see\n"
    "                    'sasnav pair --help')\n"
    "  --compact-contrast C  the contrast of p's image or q's above which a\n"
    "                    pair's scene is compact for its verdict (default 4; 'inf':\n"
    "                    never; see 'sasnav pair --help')\n"
    "  --eta-outlier R   a consecutive pair on a speckle-like scene (both\n"
    "                    contrasts at most the gate) whose eta exceeds R times\n"
    "                    the median of the run's such pairs is 'ambiguous' at\n"
    "                    best (default 1.6; > 1, or 'inf': off; needs 6 such\n"
    "                    pairs; docs/navigation.md)\n"
    "  --equalise M      each pair's search weights the images by their smoothed\n"
    "                    intensity on speckle-like scenes where a feature stands\n"
    "                    out (default 0.05 m; 0: off; see 'sasnav pair --help')\n"
    "  --final C         each pair's final-stage criterion: auto (default), eta\n"
    "                    or joint (see 'sasnav pair --help')\n"
    "  --fix-yaw         hold each pair's yaw error at 0 (rail or plotter)\n"
    "  --search-grid G   grid of each pair's search stages: auto (default),\n"
    "                    fine or coarse (see 'sasnav pair --help')\n"
    "  --no-aiding       ignore the run's aiding measurements\n"
    "  --no-resolve      take each pair's own estimate (no joint resolution, no\n"
    "                    fusion: the paper's method)\n"
    "  --speed-lags M    per-ping EPCA Tx-array offsets scaled by the speed at\n"
    "                    each ping: none (the run's offset), dvl (default:\n"
    "                    from the aiding's DVL when the run has one, no\n"
    "                    extra cost; otherwise none), pairs (the DVL, or\n"
    "                    without one the pairs' own surges before their final\n"
    "                    stage: every pair's final stage runs once the\n"
    "                    offsets are known: about the time of the default)\n"
    "  --tx-yaw M        channels with transmitters of their own: the yaw\n"
    "                    between transmission and reception that turns each\n"
    "                    transmitter: auto (default: from the gyro when the\n"
    "                    run has one, otherwise from the pairs' own yaw\n"
    "                    estimates and a second estimate of every ok pair),\n"
    "                    pairs (from the pairs even with a gyro), none\n"
    "  --aiding-bias S,W,Y  estimate a constant error of the aiding per ping\n"
    "                    interval (a DVL's bias and scale factor) with these\n"
    "                    standard deviations (m, m, rad; default\n"
    "                    0.0004,0.0004,0: a 0.2 % DVL scale factor over a 0.2 m\n"
    "                    step; 0,0,0: none)\n"
    "  --motion-sigma S,W,Y  standard deviations of the change of the motion\n"
    "                    error from one pair to the next (m, m, rad; default\n"
    "                    0.01,0.01,0.01)\n"
    "  --link-sigma S,W,Y  standard deviations of an ok pair's estimate in the\n"
    "                    fusion (m, m, rad; default 0.001,0.00002,0.00005;\n"
    "                    long baselines twice these); larger ones give the\n"
    "                    aiding (without it, the motion model) more weight\n"
    "                    (at about 5 dB and below the pairs' surge is biased:\n"
    "                    docs/navigation.md, \"Below 10 dB\")\n"
    "  --link-eta E      with aiding fused, a pair whose final eta exceeds E\n"
    "                    has its standard deviations multiplied by\n"
    "                    (eta / E)^2 where the aiding measures them: noisy\n"
    "                    pairs (low SNR) weigh less against the aiding\n"
    "                    (default 0.2; 0: off, every ok pair weighs\n"
    "                    --link-sigma, as without aiding)\n"
    "  --first-pose X,Y,YAW  place the trajectory so that the first ping's PCA\n"
    "                    centroid is at this world pose (an external fix:\n"
    "                    GNSS, USBL); default: the run's nominal first ping\n"
    "  --anchor-truth    the same with the run's true first pose (simulations:\n"
    "                    the written navigation then images on the truth's grid)\n"
    "  --threads N       OpenMP threads (default: all cores); with several, pairs\n"
    "                    are estimated concurrently (same results, bit for bit)\n"
    "  --gpu             the pairs' error evaluations on a CUDA GPU (builds\n"
    "                    configured with -DSASNAV_CUDA=ON; the same estimates to\n"
    "                    float rounding: docs/estimator.md, \"GPU\")\n"
    "  --checkpoint FILE  keep every pair estimate in FILE as it is made; if the\n"
    "                    command is interrupted (Ctrl-C, kill, a crash), the same\n"
    "                    command resumes from FILE and gives the same result\n"
    "                    (docs/cli.md). FILE is removed once -o is written\n"
    "  --json            machine-readable summary on stdout, with the\n"
    "                    trajectory's formal standard deviations (formal_sigma:\n"
    "                    the smoother's, as right as its weights; docs/\n"
    "                    navigation.md, \"Formal standard deviations\")\n"
    "\n"
    "Virtual arrays (single-channel sonars, AirSAS; docs/navigation.md,\n"
    "\"Virtual arrays\"): K consecutive pings form one virtual ping of K x N\n"
    "channels, each with its own transmitter and receiver pose from the\n"
    "input navigation; the motion between virtual pings S pings apart is\n"
    "estimated and spread over the pings (corrections interpolated between\n"
    "the groups' middle pings):\n"
    "  --virtual-array K pings per virtual ping (2..128 / channels)\n"
    "  --interleave M    a virtual ping takes every M-th ping (default 1);\n"
    "                    M = 2 with stride 1 compares interleaved groups\n"
    "                    (pings 0,2,4,.. with 1,3,5,..): their apertures\n"
    "                    overlap, 7-15x more precise than disjoint groups\n"
    "                    on the simulated AirSAS, at K x M ping spacings of\n"
    "                    aperture per group (keep it short enough for the\n"
    "                    scene: grating lobes)\n"
    "  --stride S        pings between virtual pings (default K when M = 1:\n"
    "                    disjoint groups; 1 when M > 1. Groups sharing pings\n"
    "                    tie the estimate to the input navigation)\n"
    "  --iterations N    passes, each on the previous pass's navigation\n"
    "                    (default 2)\n"
    "  --closed          the track closes on itself (a full circle, a\n"
    "                    turntable): groups wrap round, one more pair links\n"
    "                    the last group to the first and the misclosure is\n"
    "                    spread over the steps (a scale error stays)\n"
    "  --keep-length     scale the estimated steps so that their total length\n"
    "                    is the input navigation's: the estimates give the\n"
    "                    track's shape, the input its length (the steps are\n"
    "                    0.5-3 % too long on AirSAS-like layouts; right only\n"
    "                    where the input's length is, docs/airsas.md)\n"
    "  --align-heading   turn each group's layout so that its pings lie along\n"
    "                    their headings (a gyro's; no crab): a smooth drift of\n"
    "                    the input's positions tilts the layouts, and the\n"
    "                    steps keep the tilt's sway without it (docs/airsas.md);\n"
    "                    the turns are reported, with a warning when their\n"
    "                    mean would move the track by over 1 mm (what a\n"
    "                    crab or a heading bias would do to every step)\n"
    "  --along-track input  keep the input's along-track (a DVL's, an INS's)\n"
    "                    and correct only the across-track from the echoes:\n"
    "                    each group moves along its normal by the chained\n"
    "                    steps' sway; yaws stay the input's. Removes an\n"
    "                    across-track drift down to the first group's own\n"
    "                    error, keeps an along-track one (implies\n"
    "                    --align-heading; default echoes: both axes)\n"
    "  --estimate-yaw    estimate each step's yaw too (default: held at the\n"
    "                    input navigation's: an omnidirectional group shows\n"
    "                    its yaw only through its length)\n"
    "  A flagged step (verdict not ok) keeps the input navigation's. The steps\n"
    "  correct jumps and ping-to-ping errors of the input, not a smooth drift:\n"
    "  both groups of a pair carry the input's layout error alike\n"
    "  (docs/airsas.md).\n"
    "  The estimation grid is square, centred at the run's range of interest,\n"
    "  --cross-extent / --range-extent default 0.35 x that range (0.3 m for\n"
    "  AirSAS); the search box is +-0.7 ping spacings in surge and sway.\n"
    "  -o FILE           output navigation file (HDF5)\n"
    "\n"
    "Progress on stderr: a bar on a terminal, otherwise a line every 10 s\n"
    "(pairs done, rate, time left; SASNAV_PROGRESS_SECONDS sets the period).\n"
    "\n"
    "Survey scale: the run is read ping by ping (only the pings in flight are\n"
    "in memory). 'mpirun -np N sasnav navigate ...' spreads the pairs over N\n"
    "processes (one node or many); rank 0 gathers them and writes the same\n"
    "navigation as one process, bit for bit (docs/survey.md). --threads then\n"
    "counts per process; --checkpoint is for one process.\n";

/* Processes of the MPI job that estimated the pairs (1: this one alone). */
static int nav_ranks = 1;

/* Progress (cli_progress: a bar on a terminal, lines otherwise). */
static void progress_pairs(const sasnav_navigate_progress *pr, void *user)
{
    cli_progress_update(user, pr->done, pr->total);
}

static json_t *real_or_null(double v) { return isfinite(v) ? json_real(v) : json_null(); }

static json_t *pose_json(sasnav_pose e)
{
    json_t *o = json_object();
    json_object_set_new(o, "surge", real_or_null(e.x));
    json_object_set_new(o, "sway", real_or_null(e.y));
    json_object_set_new(o, "yaw", real_or_null(e.theta));
    return o;
}

static const char *status_text(int status)
{
    return status == SASNAV_OK ? "ok" : sasnav_strerror(status);
}

static json_t *candidates_json(const sasnav_pair_result *r)
{
    json_t *a = json_array();
    for (int k = 0; k < r->n_candidates; k++) {
        const sasnav_pair_candidate *c = &r->candidates[k];
        json_t *o = pose_json(c->error);
        json_object_set_new(o, "zeta_scan", real_or_null(c->zeta_scan));
        json_object_set_new(o, "zeta", real_or_null(c->zeta));
        json_object_set_new(o, "eta", real_or_null(c->eta));
        json_object_set_new(o, "refined", json_boolean(c->refined));
        if (c->same_as >= 0) json_object_set_new(o, "same_as", json_integer(c->same_as));
        json_object_set_new(o, "chosen", json_boolean(k == r->chosen));
        json_array_append_new(a, o);
    }
    return a;
}

static int flagged(const sasnav_navigate_pair *np)
{
    return np->verdict != SASNAV_VERDICT_OK || np->resolution == SASNAV_RESOLVED_BRIDGED;
}

static void print_json(const char *input, const sasnav_navigation *nav)
{
    json_t *root = json_object();
    int n = nav->n_pings;
    json_object_set_new(root, "input", json_string(input));
    json_object_set_new(root, "method",
                        json_string(nav->method == SASNAV_METHOD_DPCA     ? "dpca"
                                    : nav->method == SASNAV_METHOD_AIDING ? "aiding"
                                                                          : "subspace"));
    json_object_set_new(root, "n_pings", json_integer(n));
    json_object_set_new(root, "failed_pairs", json_integer(nav->n_failed));
    json_object_set_new(root, "flagged_pairs", json_integer(nav->n_flagged));
    json_object_set_new(root, "resolved_pairs", json_integer(nav->n_resolved));
    json_object_set_new(root, "aiding_used", json_boolean(nav->aiding_used));
    json_object_set_new(root, "gyro_tx_yaw", json_boolean(nav->gyro_tx_yaw));
    json_object_set_new(root, "tx_yaw",
                        json_string(nav->gyro_tx_yaw ? "gyro" : nav->pairs_tx_yaw ? "pairs" : "none"));
    json_object_set_new(root, "skipped_long_baselines", json_integer(nav->n_skipped));
    json_object_set_new(root, "eta_median", real_or_null(nav->eta_median));
    json_object_set_new(root, "eta_outliers", json_integer(nav->n_eta_outliers));
    json_object_set_new(root, "has_truth", json_boolean(nav->has_truth));
    if (nav->has_truth) {
        sasnav_pose f = nav->cumulative[n - 1];
        json_object_set_new(root, "final_surge_error", real_or_null(f.x));
        json_object_set_new(root, "final_sway_error", real_or_null(f.y));
        json_object_set_new(root, "final_yaw_error", real_or_null(f.theta));
        json_object_set_new(root, "rms_sway_error", real_or_null(nav->rms_cumulative.y));
        json_object_set_new(root, "rms_cumulative_error", pose_json(nav->rms_cumulative));
        json_object_set_new(root, "rms_differential_error", pose_json(nav->rms_differential));
    } else {
        json_object_set_new(root, "final_surge_error", json_null());
        json_object_set_new(root, "final_sway_error", json_null());
        json_object_set_new(root, "final_yaw_error", json_null());
        json_object_set_new(root, "rms_sway_error", json_null());
    }
    /* the smoother's formal standard deviations, truth or not */
    json_object_set_new(root, "formal_final_sigma",
                        nav->formal_sigma ? pose_json(nav->formal_sigma[n - 1]) : json_null());
    json_t *pairs = json_array();
    for (int j = 0; j < nav->n_pairs; j++) {
        sasnav_navigate_pair pair;
        sasnav_navigation_pair(nav, j, &pair);
        const sasnav_navigate_pair *np = &pair;
        json_t *o = json_object();
        json_object_set_new(o, "p", json_integer(np->p));
        json_object_set_new(o, "q", json_integer(np->q));
        json_object_set_new(o, "status", json_string(sasnav_verdict_name(np->verdict)));
        json_object_set_new(o, "first_status", json_string(sasnav_verdict_name(np->first_verdict)));
        json_object_set_new(o, "estimator", json_string(status_text(np->status)));
        json_object_set_new(o, "resolution", json_string(sasnav_resolution_name(np->resolution)));
        json_object_set_new(o, "surge", real_or_null(np->fused.x));
        json_object_set_new(o, "sway", real_or_null(np->fused.y));
        json_object_set_new(o, "yaw", real_or_null(np->fused.theta));
        json_object_set_new(o, "estimate", pose_json(np->result.error));
        json_object_set_new(o, "eta", real_or_null(np->result.eta));
        json_object_set_new(o, "margin", isfinite(np->result.margin) ? json_real(np->result.margin) : json_null());
        json_object_set_new(o, "coincidence", json_boolean(np->result.coincidence));
        json_object_set_new(o, "eta_outlier", json_boolean(np->eta_outlier));
        if (np->result.verdict != SASNAV_VERDICT_UNCHECKED && np->result.evaluations > 0) {
            json_object_set_new(o, "final_criterion",
                                json_string(sasnav_final_criterion_name(np->result.final_criterion)));
            json_object_set_new(o, "search_grid", json_string(sasnav_search_grid_name(np->result.search_grid)));
            json_object_set_new(o, "contrast", json_real(np->result.contrast));
            json_object_set_new(o, "contrast_q", json_real(np->result.contrast_q));
            json_object_set_new(o, "equalised", json_boolean(np->result.equalised));
            json_object_set_new(o, "equalise_peak", json_real(np->result.equalise_peak));
        }
        json_object_set_new(o, "candidates", candidates_json(&np->result));
        if (nav->aiding_used) {
            json_object_set_new(o, "aiding", pose_json(np->aiding));
            json_object_set_new(o, "aiding_sigma", pose_json(np->aiding_sigma));
        }
        if (nav->has_truth) {
            json_object_set_new(o, "truth", pose_json(np->truth));
            json_object_set_new(o, "error", pose_json(np->error));
        }
        json_object_set_new(o, "evaluations", json_integer(np->result.evaluations));
        json_object_set_new(o, "seconds", real_or_null(np->result.seconds));
        json_array_append_new(pairs, o);
    }
    json_object_set_new(root, "pairs", pairs);
    if (nav->has_truth) {
        json_t *cum = json_array();
        for (int i = 0; i < n; i++) json_array_append_new(cum, pose_json(nav->cumulative[i]));
        json_object_set_new(root, "cumulative_error", cum);
    }
    if (nav->formal_sigma) {
        json_t *sg = json_array();
        for (int i = 0; i < n; i++) json_array_append_new(sg, pose_json(nav->formal_sigma[i]));
        json_object_set_new(root, "formal_sigma", sg);
    } else {
        json_object_set_new(root, "formal_sigma", json_null());
    }
    json_object_set_new(root, "track_angle", real_or_null(nav->track_angle));
    json_object_set_new(root, "least_squares_iterations", json_integer(nav->lsq_iterations));
    json_object_set_new(root, "seconds", real_or_null(nav->seconds));
    json_object_set_new(root, "seconds_per_pair", real_or_null(nav->seconds_per_pair));
    json_object_set_new(root, "pairs_per_second", real_or_null(nav->pairs_per_second));
    json_object_set_new(root, "threads_over_pairs", json_integer(nav->threads_over_pairs));
    json_object_set_new(root, "processes", json_integer(nav_ranks));
    char *text = json_dumps(root, JSON_INDENT(2) | JSON_REAL_PRECISION(10));
    if (text) puts(text);
    free(text);
    json_decref(root);
}

static void print_text(const sasnav_navigation *nav)
{
    printf("%-8s %10s %10s %12s", "pair", "surge mm", "sway mm", "yaw rad");
    if (nav->has_truth) printf(" %10s %10s %12s", "err mm", "err mm", "err rad");
    printf("  %7s  %-10s %s\n", "s", "status", "resolution");
    for (int j = 0; j < nav->n_pairs; j++) {
        sasnav_navigate_pair pair;
        sasnav_navigation_pair(nav, j, &pair);
        const sasnav_navigate_pair *np = &pair;
        char name[32];
        snprintf(name, sizeof name, "%d-%d", np->p, np->q);
        printf("%-8s %+10.3f %+10.4f %+12.4e", name, 1e3 * np->fused.x, 1e3 * np->fused.y,
               np->fused.theta);
        if (nav->has_truth)
            printf(" %+10.3f %+10.4f %+12.4e", 1e3 * np->error.x, 1e3 * np->error.y, np->error.theta);
        printf("  %7.2f  %-10s %s\n", np->result.seconds, sasnav_verdict_name(np->verdict),
               sasnav_resolution_name(np->resolution));
    }
    printf("%d pairs flagged, %d resolved over the run%s\n", nav->n_flagged, nav->n_resolved,
           nav->aiding_used ? " (aiding fused)" : "");
    printf("track angle removed: %.4e rad\n", nav->track_angle);
    if (nav->has_truth) {
        sasnav_pose f = nav->cumulative[nav->n_pings - 1];
        printf("final cumulative error: surge %+.3f mm, sway %+.4f mm, yaw %+.3e rad\n", 1e3 * f.x,
               1e3 * f.y, f.theta);
        printf("rms cumulative error:   surge %.3f mm, sway %.4f mm, yaw %.3e rad\n",
               1e3 * nav->rms_cumulative.x, 1e3 * nav->rms_cumulative.y, nav->rms_cumulative.theta);
    }
    if (nav->formal_sigma) {
        sasnav_pose s = nav->formal_sigma[nav->n_pings - 1];
        printf("formal final standard deviation:    surge %.3f mm, sway %.4f mm, yaw %.3e rad\n", 1e3 * s.x,
               1e3 * s.y, s.theta);
    }
    if (nav_ranks > 1)
        printf("%d pairs in %.2f s (%.2f s per pair; %.2f pairs/s with %d processes of %d pair%s at a "
               "time)\n",
               nav->n_pairs, nav->seconds, nav->seconds_per_pair, nav->pairs_per_second, nav_ranks,
               nav->threads_over_pairs, nav->threads_over_pairs == 1 ? "" : "s");
    else
        printf("%d pairs in %.2f s (%.2f s per pair; %.2f pairs/s with %d pair%s at a time)\n",
               nav->n_pairs, nav->seconds, nav->seconds_per_pair, nav->pairs_per_second,
               nav->threads_over_pairs, nav->threads_over_pairs == 1 ? "" : "s");
}

/* `navigate --virtual-array K`: virtual pings of K pings (virtual.h). */
static int navigate_virtual(const char *input, const char *output, sasnav_virtual_opts *vo,
                            int json)
{
    sasnav_run *run = NULL;
    int rc = sasnav_run_open(input, &run);
    if (rc) return cli_fail("navigate", rc, "cannot read %s", input);
    sasnav_pair_opts *po = &vo->pair;
    po->range = run->range_of_interest;
    if (!(po->cross_extent > 0)) po->cross_extent = 0.35 * run->range_of_interest;
    if (!(po->range_extent > 0)) po->range_extent = 0.35 * run->range_of_interest;
    double step = run->ping_spacing > 0 ? run->ping_spacing : 0.01;
    po->box = (sasnav_pose){0.7 * step, 0.7 * step, po->fix_yaw ? 0.02 : 0.0};
    if (sasnav_pair_opts_check(po)) {
        sasnav_run_free(run);
        return cli_usage("navigate", "%s", sasnav_last_error());
    }
    sasnav_virtual_navigation vn;
    rc = sasnav_navigate_virtual(run, vo, &vn);
    if (rc) {
        sasnav_run_free(run);
        return cli_fail("navigate", rc, "virtual-array navigation of %s failed", input);
    }
    rc = sasnav_nav_write(output, vn.n_pings, vn.nav, run->truth);
    if (rc) {
        sasnav_virtual_navigation_free(&vn);
        sasnav_run_free(run);
        return cli_fail("navigate", rc, "cannot write %s", output);
    }
    int n_flagged = 0;
    for (int j = 0; j < vn.n_pairs; j++) {
        const sasnav_virtual_pair *vp = &vn.pairs[j];
        if (vp->est.verdict != SASNAV_VERDICT_OK) {
            n_flagged++;
            fprintf(stderr,
                    "sasnav navigate: warning: virtual pings at %d and %d: %s (eta %.3f); the input "
                    "navigation's step kept\n",
                    vp->first_p, vp->first_q, sasnav_verdict_name(vp->est.verdict), vp->est.eta);
        }
    }
    /* align_heading ties the steps to the headings: a constant turn of the
     * layouts is what a crab or a heading bias would also give. */
    if (vn.align_heading && vn.turn_exposure > 1e-3)
        fprintf(stderr,
                "sasnav navigate: warning: %s turned the layouts by %+.2f mrad on "
                "average; if that is a crab or a heading bias rather than a drift of the input, "
                "every step is turned by it (moving the track by up to %.1f mm)\n",
                vn.along_input ? "--align-heading (implied by --along-track input)" : "--align-heading",
                1e3 * vn.turn_mean, 1e3 * vn.turn_exposure);
    if (json) {
        json_t *root = json_object(), *pairs = json_array();
        json_object_set_new(root, "input", json_string(input));
        json_object_set_new(root, "virtual_array", json_integer(vn.k));
        json_object_set_new(root, "stride", json_integer(vn.stride));
        json_object_set_new(root, "interleave", json_integer(vn.interleave));
        json_object_set_new(root, "closed", json_boolean(vn.closed));
        json_object_set_new(root, "align_heading", json_boolean(vn.align_heading));
        json_object_set_new(root, "along_track", json_string(vn.along_input ? "input" : "echoes"));
        if (vn.align_heading) {
            json_t *turns = json_array();
            for (int g = 0; g < vn.n_groups; g++) json_array_append_new(turns, json_real(vn.layout_turn[g]));
            json_object_set_new(root, "layout_turn", turns);
            json_object_set_new(root, "layout_turn_mean", json_real(vn.turn_mean));
            json_object_set_new(root, "layout_turn_rms", json_real(vn.turn_rms));
            json_object_set_new(root, "turn_exposure", json_real(vn.turn_exposure));
        }
        if (vn.closed) json_object_set_new(root, "misclosure", pose_json(vn.misclosure));
        json_object_set_new(root, "length_scale", json_real(vn.length_scale));
        json_object_set_new(root, "iterations", json_integer(vn.iterations));
        json_object_set_new(root, "seconds", json_real(vn.seconds));
        for (int j = 0; j < vn.n_pairs; j++) {
            const sasnav_virtual_pair *vp = &vn.pairs[j];
            json_t *o = json_object();
            json_object_set_new(o, "p", json_integer(vp->first_p));
            json_object_set_new(o, "q", json_integer(vp->first_q));
            json_object_set_new(o, "nominal", pose_json(vp->nominal));
            json_object_set_new(o, "displacement", pose_json(vp->est.displacement));
            json_object_set_new(o, "truth", pose_json(vp->truth));
            json_object_set_new(o, "status", json_string(sasnav_verdict_name(vp->est.verdict)));
            json_object_set_new(o, "used", json_boolean(vp->used));
            json_object_set_new(o, "eta", real_or_null(vp->est.eta));
            json_object_set_new(o, "seconds", json_real(vp->est.seconds));
            json_array_append_new(pairs, o);
        }
        json_object_set_new(root, "pairs", pairs);
        json_object_set_new(root, "flagged", json_integer(n_flagged));
        char *text = json_dumps(root, JSON_INDENT(2) | JSON_REAL_PRECISION(10));
        if (text) puts(text);
        free(text);
        json_decref(root);
    } else {
        printf("virtual pings of %d pings (every %d) every %d pings, %d pass%s\n", vn.k, vn.interleave,
               vn.stride, vn.iterations, vn.iterations == 1 ? "" : "es");
        printf("  p    q    displacement: surge mm  sway mm  yaw mrad | change from input mm, mm, mrad%s\n",
               run->truth ? " | error vs truth mm, mm, mrad" : "");
        for (int j = 0; j < vn.n_pairs; j++) {
            const sasnav_virtual_pair *vp = &vn.pairs[j];
            sasnav_pose d = vp->est.displacement, n = vp->nominal, t = vp->truth;
            printf("%4d %4d  %+9.3f %+8.3f %+8.3f | %+7.3f %+7.3f %+7.3f", vp->first_p, vp->first_q,
                   1e3 * d.x, 1e3 * d.y, 1e3 * d.theta, 1e3 * (d.x - n.x), 1e3 * (d.y - n.y),
                   1e3 * (d.theta - n.theta));
            if (run->truth)
                printf(" | %+7.3f %+7.3f %+7.3f", 1e3 * (d.x - t.x), 1e3 * (d.y - t.y),
                       1e3 * (d.theta - t.theta));
            printf("  %s\n", sasnav_verdict_name(vp->est.verdict));
        }
        if (vn.closed && vn.along_input)
            printf("loop misclosure of the across-track corrections %.3f mm (x %+.3f, y %+.3f mm), "
                   "spread over %d steps\n",
                   1e3 * hypot(vn.misclosure.x, vn.misclosure.y), 1e3 * vn.misclosure.x,
                   1e3 * vn.misclosure.y, vn.n_pairs);
        else if (vn.closed)
            printf("loop misclosure %+.3f %+.3f mm, %+.3f mrad, spread over %d steps\n",
                   1e3 * vn.misclosure.x, 1e3 * vn.misclosure.y, 1e3 * vn.misclosure.theta, vn.n_pairs);
        if (vn.length_scale != 1.0)
            printf("steps scaled by %.5f to the input navigation's length\n", vn.length_scale);
        if (vn.along_input)
            printf("along track kept from the input; across track corrected by the chained steps' "
                   "sway\n");
        if (vn.align_heading)
            printf("layouts turned onto the headings by %+.3f mrad mean, %.3f mrad rms (a constant "
                   "turn of the mean would move the track by up to %.3f mm)\n",
                   1e3 * vn.turn_mean, 1e3 * vn.turn_rms, 1e3 * vn.turn_exposure);
        printf("%d pairs in %.2f s (%.2f s per pair), %d flagged\n", vn.n_pairs, vn.seconds,
               vn.n_pairs > 0 ? vn.seconds / (vn.n_pairs * vn.iterations) : 0.0, n_flagged);
    }
    /* Every step may say "ok" while the chain drifts: say so (measured,
     * docs/navigation.md "Virtual arrays"), and what of the input's drift
     * the steps keep: with aligned layouts its along-track part (the
     * layouts' spacing), otherwise all of it. */
    const char *kept = vn.align_heading ? "along track: the layouts' spacing is the input's"
                                        : "their layouts are the input's";
    if (vn.along_input)
        fprintf(stderr,
                "sasnav navigate: warning: --along-track input keeps the input's along-track drift "
                "and its across-track error at the first group (on a curved track a change of "
                "radius that no step sees); the chained sway steps' errors add up along the run "
                "(docs/airsas.md)\n");
    else if (vn.length_scale != 1.0)
        fprintf(stderr,
                "sasnav navigate: warning: the steps were scaled by %.5f to the input navigation's "
                "length; virtual-array steps keep a smooth drift of the input (%s) and their errors "
                "add up along the run: the navigation can end worse than its input (docs/airsas.md)\n",
                vn.length_scale, kept);
    else
        fprintf(stderr,
                "sasnav navigate: warning: virtual-array steps keep a smooth drift of the input (%s) "
                "and are biased in length (0.5-3 %% too long on the simulated and real AirSAS; "
                "--keep-length takes the length from the input); chained over a long run the "
                "navigation can end worse than its input (docs/airsas.md)\n",
                kept);
    fprintf(stderr, "sasnav navigate: %d pings -> %s\n", vn.n_pings, output);
    sasnav_virtual_navigation_free(&vn);
    sasnav_run_free(run);
    return 0;
}

int cmd_navigate(int argc, char **argv)
{
    static const struct option longopts[] = {
        {"method", required_argument, 0, 'm'}, {"long-baselines", no_argument, 0, 'L'},
        {"k", required_argument, 0, 'k'},      {"i", required_argument, 0, 'i'},
        {"threads", required_argument, 0, 't'}, {"json", no_argument, 0, 'j'},
        {"yaw-sigma", required_argument, 0, 'y'}, {"first-pose", required_argument, 0, 'f'},
        {"anchor-truth", no_argument, 0, 'A'}, {"fix-yaw", no_argument, 0, 'F'},
        {"cross-extent", required_argument, 0, 'X'}, {"surge-sigma", required_argument, 0, 'U'},
        {"range-extent", required_argument, 0, 'E'}, {"no-aiding", no_argument, 0, 'N'},
        {"no-resolve", no_argument, 0, 'R'}, {"motion-sigma", required_argument, 0, 'M'},
        {"link-sigma", required_argument, 0, OPT_LINK_SIGMA}, {"link-eta", required_argument, 0, OPT_LINK_ETA},
        {"speed-lags", required_argument, 0, 'S'}, {"aiding-bias", required_argument, 0, 'B'},
        {"tx-yaw", required_argument, 0, 'Y'},
        {"checkpoint", required_argument, 0, 'C'},
        {"virtual-array", required_argument, 0, 'V'}, {"stride", required_argument, 0, 'T'},
        {"iterations", required_argument, 0, 'I'}, {"estimate-yaw", no_argument, 0, 'W'},
        {"interleave", required_argument, 0, 'G'}, {"closed", no_argument, 0, 'Z'},
        {"keep-length", no_argument, 0, 'K'}, {"align-heading", no_argument, 0, 'H'},
        {"along-track", required_argument, 0, OPT_ALONG_TRACK},
        {"gpu", no_argument, 0, 'g'},        {"eta-max", required_argument, 0, 'e'},
        {"final", required_argument, 0, 'c'},  {"search-grid", required_argument, 0, 'P'},
        {"coincidence", required_argument, 0, 'J'}, {"compact-contrast", required_argument, 0, 'Q'},
        {"eta-outlier", required_argument, 0, 'O'}, {"equalise", required_argument, 0, OPT_EQUALISE},
        {"output", required_argument, 0, 'o'}, {"help", no_argument, 0, 'h'},
        {0, 0, 0, 0}};
    sasnav_navigate_opts no;
    sasnav_navigate_default_opts(&no);
    no.compact_pairs = 1; /* long runs: the pairs stay packed (docs/survey.md) */
    const char *output = NULL, *checkpoint = NULL;
    long threads = 0, k = no.pair.k, iters = no.pair.i;
    int json = 0, opt, anchor_truth = 0, have_first = 0, n_general = 0, estimate_yaw = 0, link_given = 0;
    long vk = 0, vstride = 0, viters = 2, vinter = 1;
    int have_cross = 0, have_range = 0, have_coinc = 0, have_cc = 0, closed = 0, keep_length = 0, align_heading = 0;
    int along_input = -1; /* --along-track: -1 not given, 0 echoes, 1 input */
    double first[3] = {0, 0, 0};
    optind = 1;
    while ((opt = getopt_long(argc, argv, "o:h", longopts, NULL)) != -1) {
        /* Options of the pair navigation alone (refused with --virtual-array). */
        if (strchr("mLyfAFUNBSRMCgePOYc", opt) || opt == OPT_EQUALISE || opt == OPT_LINK_SIGMA ||
            opt == OPT_LINK_ETA)
            n_general++;
        have_coinc |= opt == 'J';
        have_cc |= opt == 'Q';
        have_cross |= opt == 'X';
        have_range |= opt == 'E';
        switch (opt) {
        case 'V':
            if (cli_parse_int(optarg, 2, SASNAV_MAX_RX, &vk))
                return cli_usage("navigate", "--virtual-array needs 2..%d pings", SASNAV_MAX_RX);
            break;
        case 'T':
            if (cli_parse_int(optarg, 1, 100000, &vstride))
                return cli_usage("navigate", "--stride needs 1..100000 pings");
            break;
        case 'I':
            if (cli_parse_int(optarg, 1, 20, &viters)) return cli_usage("navigate", "--iterations needs 1..20");
            break;
        case 'W': estimate_yaw = 1; break;
        case 'Z': closed = 1; break;
        case 'K': keep_length = 1; break;
        case 'H': align_heading = 1; break;
        case OPT_ALONG_TRACK:
            if (!strcmp(optarg, "echoes")) along_input = 0;
            else if (!strcmp(optarg, "input")) along_input = 1;
            else return cli_usage("navigate", "--along-track needs echoes or input (got '%s')", optarg);
            break;
        case 'G':
            if (cli_parse_int(optarg, 1, 1000, &vinter)) return cli_usage("navigate", "--interleave needs 1..1000");
            break;
        case 'm':
            if (!strcmp(optarg, "subspace")) no.method = SASNAV_METHOD_SUBSPACE;
            else if (!strcmp(optarg, "dpca")) no.method = SASNAV_METHOD_DPCA;
            else if (!strcmp(optarg, "aiding")) no.method = SASNAV_METHOD_AIDING;
            else return cli_usage("navigate", "--method needs subspace, dpca or aiding (got '%s')", optarg);
            break;
        case 'L': no.long_baselines = 1; break;
        case 'k':
            if (cli_parse_int(optarg, 1, 100, &k)) return cli_usage("navigate", "--k needs 1..100");
            break;
        case 'i':
            if (cli_parse_int(optarg, 1, 100, &iters)) return cli_usage("navigate", "--i needs 1..100");
            break;
        case 't':
            if (cli_parse_int(optarg, 0, 1024, &threads))
                return cli_usage("navigate", "--threads needs an integer 0..1024");
            break;
        case 'y':
            if (cli_parse_double(optarg, &no.pair.yaw_sigma) || !(no.pair.yaw_sigma >= 0))
                return cli_usage("navigate", "--yaw-sigma needs a standard deviation >= 0 (rad)");
            break;
        case 'c':
            no.pair.final_criterion = sasnav_final_criterion_parse(optarg);
            if (no.pair.final_criterion < 0) return cli_usage("navigate", "--final needs auto, eta or joint");
            break;
        case 'e':
            if (cli_parse_double(optarg, &no.pair.verdict_eta_max) ||
                !(no.pair.verdict_eta_max > 0 && no.pair.verdict_eta_max <= 10))
                return cli_usage("navigate", "--eta-max needs a bound in (0, 10]");
            break;
        case 'J':
            if (cli_parse_double(optarg, &no.pair.verdict_coincidence) ||
                !(no.pair.verdict_coincidence >= 0 && no.pair.verdict_coincidence <= 0.5))
                return cli_usage("navigate", "--coincidence needs a fraction of the phase-centre spacing in [0, 0.5]");
            break;
        case 'Q':
            if (cli_parse_nonneg_or_inf(optarg, &no.pair.verdict_contrast))
                return cli_usage("navigate", "--compact-contrast needs a contrast >= 0 (or inf)");
            break;
        case 'O':
            if (cli_parse_nonneg_or_inf(optarg, &no.eta_outlier) || !(no.eta_outlier > 1))
                return cli_usage("navigate", "--eta-outlier needs a factor > 1 (or inf)");
            break;
        case OPT_EQUALISE:
            if (cli_parse_double(optarg, &no.pair.equalise) || !(no.pair.equalise >= 0 && no.pair.equalise <= 0.25))
                return cli_usage("navigate", "--equalise needs a smoothing length in [0, 0.25] m (0: off)");
            break;
        case 'U':
            if (cli_parse_double(optarg, &no.pair.surge_sigma) || !(no.pair.surge_sigma >= 0))
                return cli_usage("navigate", "--surge-sigma needs a scale >= 0 (m)");
            break;
        case 'f':
            if (cli_parse_doubles(optarg, 3, first)) return cli_usage("navigate", "--first-pose needs X,Y,YAW");
            have_first = 1;
            break;
        case 'A': anchor_truth = 1; break;
        case 'F': no.pair.fix_yaw = 1; break;
        case 'P':
            no.pair.search_grid = sasnav_search_grid_parse(optarg);
            if (no.pair.search_grid < 0)
                return cli_usage("navigate", "--search-grid needs auto, fine or coarse");
            break;
        case 'g': no.pair.gpu = 1; break;
        case 'X':
            if (cli_parse_double(optarg, &no.pair.cross_extent) || !(no.pair.cross_extent > 0))
                return cli_usage("navigate", "--cross-extent needs a positive length (m)");
            break;
        case 'E':
            if (cli_parse_double(optarg, &no.pair.range_extent) ||
                !(no.pair.range_extent > 0 && no.pair.range_extent <= 100))
                return cli_usage("navigate", "--range-extent needs a length in (0, 100] m");
            break;
        case 'N': no.use_aiding = 0; break;
        case 'B': {
            double ab[3];
            if (cli_parse_doubles(optarg, 3, ab) || !(ab[0] >= 0 && ab[1] >= 0 && ab[2] >= 0))
                return cli_usage("navigate", "--aiding-bias needs three standard deviations >= 0");
            no.aiding_bias_sigma = (sasnav_pose){ab[0], ab[1], ab[2]};
            break;
        }
        case 'S':
            if (!strcmp(optarg, "none")) no.speed_lags = 0;
            else if (!strcmp(optarg, "dvl")) no.speed_lags = 1;
            else if (!strcmp(optarg, "pairs")) no.speed_lags = 2;
            else return cli_usage("navigate", "--speed-lags needs none, dvl or pairs (got '%s')", optarg);
            break;
        case 'Y':
            if (!strcmp(optarg, "none")) no.tx_yaw = 0;
            else if (!strcmp(optarg, "auto")) no.tx_yaw = 1;
            else if (!strcmp(optarg, "pairs")) no.tx_yaw = 2;
            else return cli_usage("navigate", "--tx-yaw needs auto, pairs or none (got '%s')", optarg);
            break;
        case 'R': no.resolve = 0; break;
        case 'M': {
            double ms[3];
            if (cli_parse_doubles(optarg, 3, ms) || !(ms[0] > 0 && ms[1] > 0 && ms[2] > 0))
                return cli_usage("navigate", "--motion-sigma needs three standard deviations > 0");
            no.motion_sigma = (sasnav_pose){ms[0], ms[1], ms[2]};
            break;
        }
        case OPT_LINK_SIGMA: {
            double ls[3];
            if (cli_parse_doubles(optarg, 3, ls) || !(ls[0] > 0 && ls[1] > 0 && ls[2] > 0) ||
                !(ls[0] <= 1e6 && ls[1] <= 1e6 && ls[2] <= 1e6))
                return cli_usage("navigate", "--link-sigma needs three standard deviations > 0 and <= 1e6");
            no.link_sigma = (sasnav_pose){ls[0], ls[1], ls[2]};
            no.long_sigma = (sasnav_pose){2 * ls[0], 2 * ls[1], 2 * ls[2]};
            link_given = 1;
            break;
        }
        case OPT_LINK_ETA: {
            double e;
            if (cli_parse_doubles(optarg, 1, &e) || !(e >= 0 && e <= 1e6))
                return cli_usage("navigate", "--link-eta needs an eta >= 0 and <= 1e6 (0: off)");
            no.link_eta = e;
            link_given = 1;
            break;
        }
        case 'j': json = 1; break;
        case 'C': checkpoint = optarg; break;
        case 'o': output = optarg; break;
        case 'h': fputs(help, stdout); return 0;
        default: return cli_bad_option("navigate", argv, longopts);
        }
    }
    if (optind != argc - 1) return cli_usage("navigate", "exactly one input run file is required");
    if (!output) return cli_usage("navigate", "an output file is required (-o nav.h5)");
    if (checkpoint && cli_same_file(checkpoint, output))
        return cli_usage("navigate", "--checkpoint and -o name the same file (%s)", output);
    if (link_given && no.method == SASNAV_METHOD_AIDING)
        return cli_usage("navigate", "--link-sigma and --link-eta weight pair estimates; --method aiding "
                                     "uses none");
    if (have_first && anchor_truth)
        return cli_usage("navigate", "--first-pose and --anchor-truth exclude each other");
    const char *input = argv[optind];
    if (!vk && (vstride || viters != 2 || estimate_yaw || vinter != 1 || closed || keep_length ||
                align_heading || along_input >= 0))
        return cli_usage("navigate", "--interleave, --stride, --iterations, --closed, --keep-length, "
                                     "--align-heading, --along-track and --estimate-yaw need "
                                     "--virtual-array");
    if (along_input == 1 && estimate_yaw)
        return cli_usage("navigate", "--along-track input keeps the input's yaws: it excludes "
                                     "--estimate-yaw");
    if (vk) {
        if (n_general)
            return cli_usage("navigate", "--virtual-array takes only --interleave, --stride, "
                                         "--iterations, --closed, --keep-length, --align-heading, "
                                         "--along-track, --estimate-yaw, --k, --i, --cross-extent, --range-extent, "
                                         "--coincidence, --compact-contrast, --threads and --json");
        if (cli_mpi_size() > 1)
            return cli_usage("navigate", "--virtual-array runs in one process (use --threads)");
        sasnav_virtual_opts vo;
        sasnav_virtual_default_opts(&vo);
        vo.k = (int)vk;
        vo.stride = (int)vstride;
        vo.interleave = (int)vinter;
        vo.closed = closed;
        vo.keep_length = keep_length;
        vo.align_heading = align_heading || along_input == 1;
        vo.along_input = along_input == 1;
        vo.iterations = (int)viters;
        vo.nthreads = (int)threads;
        vo.pair.k = (int)k;
        vo.pair.i = (int)iters;
        vo.pair.coarse_k = vo.pair.k;
        vo.pair.coarse_i = vo.pair.i;
        vo.pair.fix_yaw = !estimate_yaw;
        vo.pair.cross_extent = have_cross ? no.pair.cross_extent : 0.0;
        vo.pair.range_extent = have_range ? no.pair.range_extent : 0.0;
        if (have_coinc) vo.pair.verdict_coincidence = no.pair.verdict_coincidence;
        if (have_cc) vo.pair.verdict_contrast = no.pair.verdict_contrast;
        return navigate_virtual(input, output, &vo, json);
    }
    no.pair.k = (int)k;
    no.pair.i = (int)iters;
    if (no.pair.gpu && no.method != SASNAV_METHOD_SUBSPACE)
        return cli_usage("navigate", "--gpu applies to the subspace method (--method subspace)");
    if (sasnav_pair_opts_check(&no.pair))
        return cli_usage("navigate", "%s", sasnav_last_error());
    no.nthreads = (int)threads;
    cli_progress prog;
    cli_progress_init(&prog, "navigate", "pairs");
    no.progress = progress_pairs;
    no.progress_user = &prog;

    int ranks = cli_mpi_size(), rank = cli_mpi_rank(), rank0_failed = 0;
    if (ranks > 1 && checkpoint)
        return cli_usage("navigate", "--checkpoint is for one process, not for the %d of mpirun", ranks);

    /* Streamed: the samples stay in the file, the pairs read their pings. */
    double t_start = sasnav_now_seconds();
    sasnav_run *run = NULL;
    int rc = sasnav_run_open(input, &run);
    if (cli_mpi_any(rc != 0, &rank0_failed)) {
        if (rc && (rank == 0 || !rank0_failed)) return cli_fail("navigate", rc, "cannot read %s", input);
        sasnav_run_free(run);
        return CLI_FAILURE;
    }
    if (anchor_truth && !run->truth) {
        sasnav_run_free(run);
        return cli_fail("navigate", 0, "--anchor-truth: %s holds no ground truth", input);
    }
    void *gathered = NULL;
    if (ranks > 1) {
        /* Each rank estimates its share of the pairs; rank 0 gathers the
         * records and navigates with them (no pair estimated twice). */
        sasnav_pair_record *mine = NULL;
        int n_mine = 0;
        rc = sasnav_navigate_part(run, &no, rank, ranks, &mine, &n_mine);
        cli_progress_end(&prog);
        if (cli_mpi_any(rc != 0, &rank0_failed)) {
            if (rc && (rank == 0 || !rank0_failed))
                cli_fail("navigate", rc, "navigation of %s failed", input);
            sasnav_run_free(run);
            return CLI_FAILURE;
        }
        size_t bytes = 0;
        rc = cli_mpi_gather(mine, sizeof *mine * (size_t)n_mine, &gathered, &bytes);
        free(mine);
        if (rc) {
            sasnav_run_free(run);
            return rank == 0 ? cli_fail("navigate", 0, "out of memory gathering the pair estimates") : CLI_FAILURE;
        }
        if (rank != 0) {
            sasnav_run_free(run);
            return 0;
        }
        no.done = gathered;
        no.n_done = (int)(bytes / sizeof(sasnav_pair_record));
        no.progress = NULL;
        nav_ranks = ranks;
    }
    cli_checkpoint ck;
    if (cli_checkpoint_begin(&ck, "navigate", checkpoint, &no)) {
        sasnav_run_free(run);
        free(gathered);
        return CLI_FAILURE;
    }
    sasnav_navigation nav;
    rc = sasnav_navigate(run, &no, &nav);
    cli_progress_end(&prog);
    free(gathered);
    if (!rc && ranks > 1) {
        /* The job's figures: wall time from the start, all pairs. */
        nav.seconds = sasnav_now_seconds() - t_start;
        nav.seconds_estimation = nav.seconds;
        nav.pairs_per_second = nav.seconds > 0 ? nav.n_pairs / nav.seconds : 0.0;
    }
    if (rc) {
        sasnav_run_free(run);
        rc = cli_fail("navigate", rc, "navigation of %s failed", input);
        cli_checkpoint_end(&ck, 0);
        return rc;
    }
    const sasnav_ping_pose *written = anchor_truth ? nav.anchored : nav.nav;
    if (have_first) {
        /* Rigid motion taking the estimated first centroid onto the fix. */
        sasnav_pose fix = {first[0], first[1], first[2]};
        sasnav_pose move = sasnav_pose_compose(fix, sasnav_pose_inverse(nav.centroids[0]));
        for (int i = 0; i < nav.n_pings; i++) {
            nav.nav[i].tx = sasnav_pose_compose(move, nav.nav[i].tx);
            nav.nav[i].array = sasnav_pose_compose(move, nav.nav[i].array);
        }
    }
    rc = sasnav_nav_write_sigma(output, nav.n_pings, written, run->truth, nav.formal_sigma);
    int channel_tx = run->channel_offset != NULL;
    sasnav_run_free(run);
    if (rc) {
        sasnav_navigation_free(&nav);
        rc = cli_fail("navigate", rc, "cannot write %s", output);
        cli_checkpoint_end(&ck, 0);
        return rc;
    }
    cli_checkpoint_end(&ck, 1);
    int n_unchecked = 0;
    for (int j = 0; j < nav.n_pairs; j++) {
        sasnav_navigate_pair pair;
        sasnav_navigation_pair(&nav, j, &pair);
        const sasnav_navigate_pair *np = &pair;
        if (np->verdict == SASNAV_VERDICT_UNCHECKED && np->resolution == SASNAV_RESOLVED_NONE)
            n_unchecked++; /* one line for them all, below */
        else if (flagged(np))
            fprintf(stderr, "sasnav navigate: warning: pair %d-%d is %s (%s%s%s%s%s)\n", np->p, np->q,
                    np->resolution == SASNAV_RESOLVED_BRIDGED ? "bridged" : sasnav_verdict_name(np->verdict),
                    np->status != SASNAV_OK                  ? sasnav_strerror(np->status)
                    : nav.method == SASNAV_METHOD_AIDING ? "no aiding measurement over the interval"
                                                         : "estimate",
                    np->result.coincidence ? " at a phase-centre coincidence on a compact scene" : "",
                    np->eta_outlier ? " with an eta far above the run's" : "",
                    np->resolution == SASNAV_RESOLVED_BRIDGED ? ": aiding and motion model used" : "",
                    np->resolution == SASNAV_RESOLVED_NONE ? "" : "; resolved over the run");
        else if (np->resolution != SASNAV_RESOLVED_NONE)
            fprintf(stderr, "sasnav navigate: pair %d-%d: first %s, %s over the run, now ok\n", np->p,
                    np->q, sasnav_verdict_name(np->first_verdict), sasnav_resolution_name(np->resolution));
    }
    if (n_unchecked > 0)
        fprintf(stderr,
                "sasnav navigate: warning: %d of %d pairs are unchecked: DPCA has no verdict of its own "
                "(a slip of one phase-centre spacing goes unseen)%s\n",
                n_unchecked, nav.n_pairs, nav.aiding_used ? "" : "; aiding measurements would confirm them");
    if (nav.n_skipped > 0)
        fprintf(stderr, "sasnav navigate: %d long baselines skipped (< 2 phase centres overlap)\n",
                nav.n_skipped);
    if (channel_tx && nav.method == SASNAV_METHOD_SUBSPACE && !nav.gyro_tx_yaw && !nav.pairs_tx_yaw)
        fprintf(stderr,
                "sasnav navigate: warning: the channels have transmitters of their own and neither a gyro "
                "nor the pairs gave the vehicle's yaw between transmission and reception: it is taken as "
                "zero (it moves each transmitter sideways by its lever arm x that yaw; docs/model.md, "
                "\"Channel layouts\")\n");
    if (json) print_json(input, &nav);
    else print_text(&nav);
    fprintf(stderr, "sasnav navigate: %d pings -> %s\n", nav.n_pings, output);
    sasnav_navigation_free(&nav);
    return 0;
}
