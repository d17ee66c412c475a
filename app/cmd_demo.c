/* sasnav demo: the paper's trajectory simulation (Section IV-C) end to end:
 * simulate paper-trajectory, navigate it with the subspace estimator and
 * with DPCA, image it with the nominal, true and estimated navigations,
 * compare the images and trajectories, and write a Markdown report. */
#include "cli.h"
#include "sasnav/io.h"
#include "sasnav/navigate.h"
#include "sasnav/plot.h"
#include "sasnav/sim.h"
#include "sasnav/trajectory.h"
#include "io/textfile.h"
#include "core/clock.h"

#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static const char *help =
    "usage: sasnav demo [-o DIR] [--threads N] [--quick]\n"
    "\n"
    "Simulates the paper-trajectory preset (16 pings over 3 m, 30 dB SNR, true\n"
    "bistatic Tx/array poses), navigates it with the subspace-intersection\n"
    "estimator and with DPCA, backprojects it on one grid with the nominal,\n"
    "true and both estimated navigations (the estimated trajectories are\n"
    "placed on the true first ping, the one pose a pair estimator cannot\n"
    "know), and writes into DIR: run.h5, nav-subspace.h5, nav-dpca.h5,\n"
    "image-*.png, trajectory.png, error plots and report.md (errors, image\n"
    "correlations with the true-navigation image, timings).\n"
    "\n"
    "  -o DIR        output directory (default: demo; created if missing)\n"
    "  --threads N   OpenMP threads (default: all cores)\n"
    "  --quick       6 pings and the estimator's coarse iterations only\n"
    "                (k = 2, i = 1): a smoke run of about a minute, not the\n"
    "                paper's accuracy\n";

#define N_IMAGES 5

typedef struct {
    const char *dir;
    int threads, quick;
    sasnav_scenario sc;
    sasnav_run *run;
    sasnav_navigation nav[2]; /* subspace, DPCA */
    sasnav_cfloat *image[N_IMAGES];
    double correlation[N_IMAGES];
    double seconds_simulate, seconds_images, t_start;
} demo;

/* Navigations imaged: the estimates are placed on the true first ping
 * (anchored); "subspace-aligned" is the subspace estimate as written to
 * nav-subspace.h5 (nominal first ping, track angle removed), to show what
 * the unknown first pose does to the comparison. */
static const char *image_name[N_IMAGES] = {"nominal", "true", "subspace", "dpca",
                                           "subspace-aligned"};
static const char *method_name[2] = {"subspace", "DPCA"};

static void path_in(const demo *d, const char *name, char *buf, size_t size)
{
    snprintf(buf, size, "%s/%s", d->dir, name);
}

static void progress_bar(const sasnav_navigate_progress *pr, void *user)
{
    const char *label = user;
    const int width = 30;
    int filled = pr->total > 0 ? width * pr->done / pr->total : width;
    char bar[64];
    for (int j = 0; j < width; j++) bar[j] = j < filled ? '#' : '.';
    bar[width] = '\0';
    fprintf(stderr, "\rsasnav demo: %-8s [%s] %d/%d pairs  %.1f s", label, bar, pr->done,
            pr->total, pr->seconds);
    if (pr->done == pr->total) fputc('\n', stderr);
    fflush(stderr);
}

static int simulate(demo *d)
{
    double t0 = sasnav_now_seconds();
    int rc = sasnav_scenario_preset("paper-trajectory", &d->sc);
    if (rc) return cli_fail("demo", rc, "preset");
    d->sc.snr_db = 30.0;
    if (d->quick) d->sc.traj.n_pings = 6;
    sasnav_op_opts oo;
    sasnav_op_default_opts(&oo);
    oo.nthreads = d->threads;
    rc = sasnav_simulate(&d->sc, NULL, &oo, &d->run);
    if (rc) return cli_fail("demo", rc, "simulation failed");
    char path[4096];
    path_in(d, "run.h5", path, sizeof path);
    rc = sasnav_run_write(path, d->run);
    if (rc) return cli_fail("demo", rc, "cannot write %s", path);
    d->seconds_simulate = sasnav_now_seconds() - t0;
    return 0;
}

static int navigate(demo *d, int m)
{
    sasnav_navigate_opts no;
    sasnav_navigate_default_opts(&no);
    no.method = m == 0 ? SASNAV_METHOD_SUBSPACE : SASNAV_METHOD_DPCA;
    no.nthreads = d->threads;
    if (d->quick) {
        no.pair.k = no.pair.coarse_k;
        no.pair.i = no.pair.coarse_i;
    }
    if (isatty(STDERR_FILENO)) {
        no.progress = progress_bar;
        no.progress_user = (void *)method_name[m];
    }
    int rc = sasnav_navigate(d->run, &no, &d->nav[m]);
    if (rc) return cli_fail("demo", rc, "%s navigation failed", method_name[m]);
    char path[4096];
    path_in(d, m == 0 ? "nav-subspace.h5" : "nav-dpca.h5", path, sizeof path);
    rc = sasnav_nav_write(path, d->nav[m].n_pings, d->nav[m].nav, d->run->truth);
    if (rc) return cli_fail("demo", rc, "cannot write %s", path);
    int n_unchecked = 0;
    for (int j = 0; j < d->nav[m].n_pairs; j++) {
        const sasnav_navigate_pair *np = &d->nav[m].pairs[j];
        if (np->verdict == SASNAV_VERDICT_UNCHECKED && np->resolution == SASNAV_RESOLVED_NONE)
            n_unchecked++;
        else if (np->verdict != SASNAV_VERDICT_OK || np->resolution == SASNAV_RESOLVED_BRIDGED)
            fprintf(stderr, "sasnav demo: warning: %s pair %d-%d is %s (%s)\n", method_name[m], np->p,
                    np->q, np->resolution == SASNAV_RESOLVED_BRIDGED ? "bridged" : sasnav_verdict_name(np->verdict),
                    np->status != SASNAV_OK ? sasnav_strerror(np->status) : "see report.md");
    }
    if (n_unchecked > 0)
        fprintf(stderr, "sasnav demo: %s: %d pairs unchecked (no verdict of its own)\n", method_name[m],
                n_unchecked);
    return 0;
}

static int images(demo *d)
{
    double t0 = sasnav_now_seconds();
    const sasnav_grid *g = &d->sc.image_grid;
    size_t np = (size_t)g->nx * g->ny;
    const sasnav_ping_pose *navs[N_IMAGES] = {d->run->nav, d->run->truth, d->nav[0].anchored,
                                              d->nav[1].anchored, d->nav[0].nav};
    sasnav_op_opts oo;
    sasnav_op_default_opts(&oo);
    oo.nthreads = d->threads;
    for (int k = 0; k < N_IMAGES; k++) {
        d->image[k] = malloc(sizeof(sasnav_cfloat) * np);
        if (!d->image[k]) return cli_fail("demo", 0, "out of memory for the images");
        int rc = sasnav_backproject(d->run, navs[k], g, &oo, d->image[k]);
        if (rc) return cli_fail("demo", rc, "backprojection (%s navigation)", image_name[k]);
    }
    d->seconds_images = sasnav_now_seconds() - t0;
    for (int k = 0; k < N_IMAGES; k++) {
        d->correlation[k] = sasnav_image_correlation(d->image[k], d->image[1], NULL, np);
        char name[64], path[4096], title[128];
        snprintf(name, sizeof name, "image-%s.png", image_name[k]);
        path_in(d, name, path, sizeof path);
        snprintf(title, sizeof title, "paper-trajectory, %s navigation (correlation %.3f)",
                 image_name[k], d->correlation[k]);
        int rc = sasnav_plot_image_db(path, g, d->image[k], 40.0, title);
        if (rc) return cli_fail("demo", rc, "cannot write %s", path);
    }
    return 0;
}

/* Sway (mm) against along-track position (m) of the true and estimated
 * centroids, all in the world frame (estimates on the true first ping). */
static int plot_trajectories(demo *d)
{
    int n = d->run->n_pings;
    size_t sz = sizeof(double) * (size_t)n;
    double *x[3], *y[3];
    sasnav_pose *c = malloc(sizeof(sasnav_pose) * (size_t)n);
    int ok = c != NULL;
    for (int s = 0; s < 3; s++) {
        x[s] = malloc(sz);
        y[s] = malloc(sz);
        ok = ok && x[s] && y[s];
    }
    int rc = ok ? 0 : SASNAV_ERR_NOMEM;
    for (int s = 0; s < 3 && !rc; s++) {
        const sasnav_ping_pose *p = s == 0 ? d->run->truth : d->nav[s - 1].anchored;
        rc = sasnav_traj_centroids(p, n, c);
        for (int i = 0; i < n && !rc; i++) {
            x[s][i] = c[i].x;
            y[s][i] = 1e3 * c[i].y;
        }
    }
    if (!rc) {
        int counts[3] = {n, n, n};
        const double *xs[3] = {x[0], x[1], x[2]}, *ys[3] = {y[0], y[1], y[2]};
        const char *labels[3] = {"true", "subspace estimate", "DPCA estimate"};
        sasnav_line_plot lp = {"PCA centroids: true and estimated trajectories",
                               "along-track x (m)", "sway y (mm)", 3, counts, xs, ys, labels,
                               0, NAN, NAN};
        char path[4096];
        path_in(d, "trajectory.png", path, sizeof path);
        rc = sasnav_plot_lines(path, &lp);
    }
    free(c);
    for (int s = 0; s < 3; s++) {
        free(x[s]);
        free(y[s]);
    }
    return rc ? cli_fail("demo", rc, "trajectory plot") : 0;
}

/* Differential and cumulative surge / sway / yaw errors per ping, both
 * methods (paper Fig. nav3): six plots. */
static int plot_errors(demo *d)
{
    int n = d->run->n_pings;
    double *ping = malloc(sizeof(double) * (size_t)n);
    double *e[2] = {malloc(sizeof(double) * (size_t)n), malloc(sizeof(double) * (size_t)n)};
    int rc = (ping && e[0] && e[1]) ? 0 : SASNAV_ERR_NOMEM;
    static const char *kind[2] = {"differential", "cumulative"};
    static const char *comp[3] = {"surge", "sway", "yaw"};
    static const char *unit[3] = {"mm", "mm", "mrad"};
    for (int i = 0; i < n && !rc; i++) ping[i] = i;
    /* the paper's final sway bound, +-lambda/25, on the cumulative sway: one
     * curve round the band (its ends lie on the plot's frame) */
    double b = 1e3 * sasnav_wavelength(&d->run->sys) / 25;
    double band_x[5] = {0, n - 1, n - 1, 0, 0}, band_y[5] = {b, b, -b, -b, b};
    /* and the subspace trajectory's +-2 formal standard deviations: one
     * closed curve, out along + and back along - */
    const sasnav_pose *fs = d->nav[0].formal_sigma;
    double *sd_x = malloc(sizeof(double) * (size_t)(2 * n + 1));
    double *sd_y = malloc(sizeof(double) * (size_t)(2 * n + 1));
    if (!sd_x || !sd_y) rc = SASNAV_ERR_NOMEM;
    for (int i = 0; i < n && !rc && fs; i++) {
        sd_x[i] = i;
        sd_y[i] = 2e3 * fs[i].y;
        sd_x[2 * n - 1 - i] = i;
        sd_y[2 * n - 1 - i] = -2e3 * fs[i].y;
    }
    if (!rc && fs) {
        sd_x[2 * n] = sd_x[0];
        sd_y[2 * n] = sd_y[0];
    }
    for (int k = 0; k < 2 && !rc; k++) {
        for (int c = 0; c < 3 && !rc; c++) {
            for (int m = 0; m < 2; m++) {
                const sasnav_pose *err = k == 0 ? d->nav[m].differential : d->nav[m].cumulative;
                for (int i = 0; i < n; i++)
                    e[m][i] = 1e3 * (c == 0 ? err[i].x : c == 1 ? err[i].y : err[i].theta);
            }
            int counts[4] = {n, n, 5, 2 * n + 1};
            const double *xs[4] = {ping, ping, band_x, sd_x}, *ys[4] = {e[0], e[1], band_y, sd_y};
            const char *labels[4] = {"subspace", "DPCA", "+-lambda/25", "subspace +-2 formal sd"};
            int ns = k == 1 && c == 1 ? (fs ? 4 : 3) : 2;
            char title[128], ylabel[64], name[64], path[4096];
            snprintf(title, sizeof title, "%s %s error", kind[k], comp[c]);
            snprintf(ylabel, sizeof ylabel, "%s error (%s)", comp[c], unit[c]);
            sasnav_line_plot lp = {title, "ping", ylabel, ns, counts, xs, ys, labels, 0, NAN, NAN};
            snprintf(name, sizeof name, "error-%s-%s.png", kind[k], comp[c]);
            path_in(d, name, path, sizeof path);
            rc = sasnav_plot_lines(path, &lp);
        }
    }
    free(ping);
    free(e[0]);
    free(e[1]);
    free(sd_x);
    free(sd_y);
    return rc ? cli_fail("demo", rc, "error plots") : 0;
}

static int write_report(demo *d)
{
    char path[4096];
    path_in(d, "report.md", path, sizeof path);
    sasnav_text_out out;
    int rc = sasnav_text_open(&out, path);
    if (rc) return cli_fail("demo", rc, "cannot write the report");
    FILE *f = out.f;
    const sasnav_scenario *sc = &d->sc;
    int n = d->run->n_pings;
    double lambda = sc->sys.sound_speed / sc->sys.f0;
    fprintf(f, "# sasnav demo: paper-trajectory (paper Section IV-C)\n\n");
    fprintf(f, "%d pings at %.2f m spacing (%.1f m/s), %d receivers, f0 %.0f kHz (lambda %.1f mm), "
               "B %.0f kHz, SNR %.0f dB; smooth random surge/sway/yaw errors (rms %.0f mm, %.0f mm, "
               "%.0e rad), raw data from the true, different Tx and array poses; processing with the "
               "EPCA model and a known %.0f cm Tx-array offset.%s\n\n",
            n, sc->traj.ping_spacing, sc->traj.speed, sc->array.n_rx, 1e-3 * sc->sys.f0,
            1e3 * lambda, 1e-3 * sc->sys.bandwidth, sc->snr_db, 1e3 * sc->traj.surge_rms,
            1e3 * sc->traj.sway_rms, sc->traj.yaw_rms, 1e2 * sc->traj.tx_lag,
            d->quick ? " **Quick run: 6 pings, coarse iterations (k = 2, i = 1) only.**" : "");
    fprintf(f, "Errors are against the true trajectory moved rigidly onto the estimated first "
               "ping (a pair estimator cannot know the first pose); the estimated trajectories "
               "are aligned to the nominal track (track angle removed). DPCA does not observe "
               "surge (taken as nominal).\n\n");
    fprintf(f, "## Trajectory errors\n\n");
    fprintf(f, "| method | final surge (mm) | final sway (mm) | final yaw (rad) | formal sd of the final "
               "sway (mm) | rms cumulative sway (mm) | rms differential sway (mm) | track angle (rad) | "
               "failed pairs | flagged pairs |\n");
    fprintf(f, "|---|---|---|---|---|---|---|---|---|---|\n");
    for (int m = 0; m < 2; m++) {
        const sasnav_navigation *nv = &d->nav[m];
        sasnav_pose fe = nv->cumulative[n - 1];
        char sd[32] = "-";
        if (nv->formal_sigma) snprintf(sd, sizeof sd, "%.4f", 1e3 * nv->formal_sigma[n - 1].y);
        fprintf(f, "| %s | %+.3f | %+.4f | %+.2e | %s | %.4f | %.4f | %+.3e | %d | %d |\n", method_name[m],
                1e3 * fe.x, 1e3 * fe.y, fe.theta, sd, 1e3 * nv->rms_cumulative.y,
                1e3 * nv->rms_differential.y, nv->track_angle, nv->n_failed, nv->n_flagged);
    }
    fprintf(f, "\nThe formal standard deviation is the smoother's (docs/navigation.md, \"Formal standard "
               "deviations\"): without aiding it understates the final sway's error (on held-out runs "
               "of this preset it would have to be about 1.8x larger); none for DPCA.\n");
    /* Flagged pairs, one row each (docs/navigation.md, "Trust"). */
    int any = 0;
    for (int m = 0; m < 2; m++)
        for (int j = 0; j < d->nav[m].n_pairs; j++) {
            const sasnav_navigate_pair *np = &d->nav[m].pairs[j];
            if ((np->verdict == SASNAV_VERDICT_OK || np->verdict == SASNAV_VERDICT_UNCHECKED) &&
                np->resolution == SASNAV_RESOLVED_NONE)
                continue; /* DPCA's unchecked pairs: one sentence below */
            if (!any)
                fprintf(f, "\n**Pairs flagged or resolved over the run** (status of the estimate; how "
                           "the run resolved it):\n\n| method | pair | first status | status | "
                           "resolution | eta | margin | error surge (mm) | yaw (rad) |\n"
                           "|---|---|---|---|---|---|---|---|---|\n");
            any = 1;
            fprintf(f, "| %s | %d-%d | %s | %s | %s | %.3f | %.3f | %+.3f | %+.2e |\n", method_name[m],
                    np->p, np->q, sasnav_verdict_name(np->first_verdict), sasnav_verdict_name(np->verdict),
                    sasnav_resolution_name(np->resolution), np->result.eta, np->result.margin,
                    1e3 * np->error.x, np->error.theta);
        }
    if (!any) fprintf(f, "\nNo pair flagged or resolved over the run.\n");
    fprintf(f, "\nDPCA has no verdict of its own: its pairs are \"unchecked\" (counted as flagged; a "
               "slip of one phase-centre spacing would go unseen) unless aiding measurements confirm "
               "them.\n");
    fprintf(f, "\nlambda / 10 = %.2f mm (SAS imaging tolerance), lambda / 25 = %.2f mm (the paper's "
               "final sway error).\n\n",
            1e3 * lambda / 10, 1e3 * lambda / 25);
    fprintf(f, "![trajectories](trajectory.png)\n\n");
    fprintf(f, "| | surge | sway | yaw |\n|---|---|---|---|\n");
    fprintf(f, "| differential | ![](error-differential-surge.png) | ![](error-differential-sway.png) "
               "| ![](error-differential-yaw.png) |\n");
    fprintf(f, "| cumulative | ![](error-cumulative-surge.png) | ![](error-cumulative-sway.png) | "
               "![](error-cumulative-yaw.png) |\n\n");
    fprintf(f, "### Per pair (motion error estimate minus truth)\n\n");
    fprintf(f, "| pair | true surge (mm) | true sway (mm) | true yaw (rad) | subspace error surge "
               "(mm) | sway (mm) | yaw (rad) | DPCA error sway (mm) | yaw (rad) |\n");
    fprintf(f, "|---|---|---|---|---|---|---|---|---|\n");
    for (int j = 0; j < d->nav[0].n_pairs && j < d->nav[1].n_pairs; j++) {
        const sasnav_navigate_pair *a = &d->nav[0].pairs[j], *b = &d->nav[1].pairs[j];
        fprintf(f, "| %d-%d | %+.3f | %+.3f | %+.2e | %+.3f | %+.4f | %+.1e | %+.4f | %+.1e |\n",
                a->p, a->q, 1e3 * a->truth.x, 1e3 * a->truth.y, a->truth.theta, 1e3 * a->error.x,
                1e3 * a->error.y, a->error.theta, 1e3 * b->error.y, b->error.theta);
    }
    fprintf(f, "\n## Images\n\n");
    fprintf(f, "Backprojection of all pings on the same %d x %d grid (%.2f cm pixels). "
               "Correlation = |<a, b>| / (||a|| ||b||) of the complex image with the "
               "true-navigation image over the whole grid.\n\n",
            sc->image_grid.ny, sc->image_grid.nx, 1e2 * sc->image_grid.dx);
    fprintf(f, "The estimated navigations are placed on the true first ping; "
               "`subspace-aligned` is the subspace estimate as written to nav-subspace.h5 "
               "(nominal first ping, track angle removed): its image is the true one moved "
               "rigidly by the first ping's unknown pose, which the correlation does not "
               "forgive.\n\n");
    fprintf(f, "| navigation | correlation with true | image |\n|---|---|---|\n");
    for (int k = 0; k < N_IMAGES; k++)
        fprintf(f, "| %s | %.4f | ![](image-%s.png) |\n", image_name[k], d->correlation[k],
                image_name[k]);
    fprintf(f, "\n## Timings (wall clock)\n\n");
    if (d->threads > 0) fprintf(f, "OpenMP threads: %d.\n\n", d->threads);
    else fprintf(f, "OpenMP threads: default (OMP_NUM_THREADS or all cores).\n\n");
    fprintf(f, "| step | seconds |\n|---|---|\n");
    fprintf(f, "| simulation | %.2f |\n", d->seconds_simulate);
    for (int m = 0; m < 2; m++)
        fprintf(f, "| %s navigation (%d pairs, %.3g s per pair, %.3g pairs/s, %d at a time) | %.2f |\n",
                method_name[m], d->nav[m].n_pairs, d->nav[m].seconds_per_pair, d->nav[m].pairs_per_second,
                d->nav[m].threads_over_pairs, d->nav[m].seconds);
    fprintf(f, "| %d backprojections | %.2f |\n", N_IMAGES, d->seconds_images);
    fprintf(f, "| whole demo | %.2f |\n", sasnav_now_seconds() - d->t_start);
    rc = sasnav_text_commit(&out);
    return rc ? cli_fail("demo", rc, "cannot write the report") : 0;
}

static void demo_free(demo *d)
{
    sasnav_run_free(d->run);
    for (int m = 0; m < 2; m++) sasnav_navigation_free(&d->nav[m]);
    for (int k = 0; k < N_IMAGES; k++) free(d->image[k]);
}

static int run_demo(demo *d)
{
    if (mkdir(d->dir, 0777) && errno != EEXIST)
        return cli_fail("demo", 0, "cannot create %s: %s", d->dir, strerror(errno));
    struct stat st;
    if (stat(d->dir, &st) || !S_ISDIR(st.st_mode))
        return cli_fail("demo", 0, "%s is not a directory", d->dir);
    int rc = simulate(d);
    for (int m = 0; m < 2 && !rc; m++) rc = navigate(d, m);
    if (!rc) rc = images(d);
    if (!rc) rc = plot_trajectories(d);
    if (!rc) rc = plot_errors(d);
    if (!rc) rc = write_report(d);
    return rc;
}

int cmd_demo(int argc, char **argv)
{
    static const struct option longopts[] = {
        {"output", required_argument, 0, 'o'}, {"threads", required_argument, 0, 't'},
        {"quick", no_argument, 0, 'q'},        {"help", no_argument, 0, 'h'},
        {0, 0, 0, 0}};
    demo d;
    memset(&d, 0, sizeof d);
    d.dir = "demo";
    d.t_start = sasnav_now_seconds();
    long threads = 0;
    int opt;
    optind = 1;
    while ((opt = getopt_long(argc, argv, "o:h", longopts, NULL)) != -1) {
        switch (opt) {
        case 'o': d.dir = optarg; break;
        case 't':
            if (cli_parse_int(optarg, 0, 1024, &threads))
                return cli_usage("demo", "--threads needs an integer 0..1024");
            break;
        case 'q': d.quick = 1; break;
        case 'h': fputs(help, stdout); return 0;
        default: return cli_bad_option("demo", argv, longopts);
        }
    }
    if (optind < argc) return cli_usage("demo", "unexpected argument '%s'", argv[optind]);
    if (!d.dir[0]) return cli_usage("demo", "-o needs a directory name");
    d.threads = (int)threads;
    int rc = run_demo(&d);
    if (!rc) {
        const sasnav_navigation *s = &d.nav[0], *p = &d.nav[1];
        int n = d.run->n_pings;
        fprintf(stderr,
                "sasnav demo: final cumulative sway error: subspace %+.4f mm, DPCA %+.4f mm; "
                "image correlation with the true image: subspace %.3f, DPCA %.3f, nominal %.3f; "
                "%.1f s -> %s/report.md\n",
                1e3 * s->cumulative[n - 1].y, 1e3 * p->cumulative[n - 1].y, d.correlation[2],
                d.correlation[3], d.correlation[0], sasnav_now_seconds() - d.t_start, d.dir);
    }
    demo_free(&d);
    return rc;
}
