/* Virtual-array navigation (virtual.h) on circular SISO runs: the
 * simulated AirSAS ("circular" preset) with known truth, or a run file
 * (e.g. the AirSAS recording ingested with `sasnav ingest --airsas`,
 * whose nominal circle is the turntable's truth).
 *
 * usage: bench_virtual [--seeds S0 N] [--snr DB|inf] [--k K] [--stride S]
 *                      [--pings N] [--first P] [--threads T] [--pixel M]
 *                      [--extent M] [--box SURGE,SWAY,YAW]
 *                      [--iterations N] [--interleave M] [--free-yaw]
 *                      [--motion-rms M] [--write-nav PREFIX] [--closed] [--keep-length]
 *                      [--align-heading] [--along-input]
 *                      [--file run.h5 [--drift MM]] [--quiet]
 *                      [--plot PREFIX] [--refine | --refine-only [--sweeps N] [--cg N] [--damping X]
 *                       [--refine-pixel M] [--refine-half M] [--surge-range M] [--sway-range M]]
 *
 * Simulated runs (default: seed 201, one run): the preset's smooth motion
 * errors are the truth, its nominal circle the input navigation. For each
 * pair of virtual pings prints the error of the estimated displacement
 * against the truth (surge, sway in mm, yaw in mrad), the verdict and eta;
 * then, over the run: rms and worst per-pair error, and the per-ping
 * position error (in each ping's frame: along-track, across-track) of the
 * input navigation and of the estimated one, both aligned on the first
 * group's true centroid (the estimate is anchored there).
 *
 * --file: the run's own /nav is the truth (a turntable), and the input
 * navigation is it plus a smooth drift of --drift mm (default 5: surge
 * and sway, 2.5 and 1.5 cycles over the run's pings, zero at ping 0).
 *
 * --keep-length: the steps scaled to the input navigation's length
 * (virtual.h). --along-input: the input's along-track kept, the echoes'
 * sway steps correct the across-track (virtual.h along_input; implies
 * --align-heading). --plot PREFIX: PREFIX-steps.png (each step's error) and
 * PREFIX-nav.png (each ping's position error). --refine: the multi-ping
 * refinement (refine.h, leave-one-out scenes on a square grid round the
 * circle's centre) after the virtual navigation; --refine-only: instead of
 * it (docs/airsas.md: why it does not work on these runs).
 *
 * Acceptance lines of the issue (docs/airsas.md, docs/navigation.md):
 * per-step motion within lambda/10 in sway and a quarter of the phase-centre
 * spacing in surge (simulated); drift removed to within 1 mm rms. */
#include "sasnav/error.h"
#include "sasnav/io.h"
#include "sasnav/plot.h"
#include "sasnav/refine.h"
#include "sasnav/sim.h"
#include "sasnav/trajectory.h"
#include "sasnav/virtual.h"
#include "bench_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

typedef struct {
    double along, across;
} pos_err;

/* Position error of pose `est` against `truth`, in truth's frame. */
static pos_err err_in_frame(sasnav_pose est, sasnav_pose truth)
{
    double dx = est.x - truth.x, dy = est.y - truth.y;
    double c = cos(truth.theta), s = sin(truth.theta);
    pos_err e = {c * dx + s * dy, -s * dx + c * dy};
    return e;
}

static void nav_errors(const sasnav_run *run, const sasnav_ping_pose *nav, const sasnav_ping_pose *truth,
                       sasnav_pose align, double *rms_along, double *rms_across, double *worst)
{
    double sa = 0, sc = 0, w = 0;
    for (int i = 0; i < run->n_pings; i++) {
        sasnav_pose e = sasnav_pose_compose(align, sasnav_ping_centroid(&nav[i]));
        pos_err d = err_in_frame(e, sasnav_ping_centroid(&truth[i]));
        sa += d.along * d.along;
        sc += d.across * d.across;
        double m = hypot(d.along, d.across);
        w = m > w ? m : w;
    }
    *rms_along = sqrt(sa / run->n_pings);
    *rms_across = sqrt(sc / run->n_pings);
    *worst = w;
}

/* Least-squares slope b of y on x (y ~ a + b x) and the correlation. */
static void regress(const double *x, const double *y, int n, double *slope, double *corr)
{
    double mx = 0, my = 0, sxx = 0, syy = 0, sxy = 0;
    for (int i = 0; i < n; i++) {
        mx += x[i] / n;
        my += y[i] / n;
    }
    for (int i = 0; i < n; i++) {
        sxx += (x[i] - mx) * (x[i] - mx);
        syy += (y[i] - my) * (y[i] - my);
        sxy += (x[i] - mx) * (y[i] - my);
    }
    *slope = sxx > 0 ? sxy / sxx : NAN;
    *corr = sxx > 0 && syy > 0 ? sxy / sqrt(sxx * syy) : NAN;
}

/* PREFIX-SUFFIX.h5: a navigation file (with the run's truth) for
 * `sasnav image --nav`. */
static void write_nav(const char *prefix, const char *suffix, const sasnav_run *run, const sasnav_ping_pose *nav)
{
    char path[1100];
    snprintf(path, sizeof path, "%s-%s.h5", prefix, suffix);
    if (sasnav_nav_write(path, run->n_pings, nav, run->truth)) fprintf(stderr, "bench_virtual: %s\n", sasnav_last_error());
}

/* Along / across position errors of each ping of `nav` against `truth`
 * (after `align`, as nav_errors), mm. */
static void per_ping_errors(const sasnav_run *run, const sasnav_ping_pose *nav, const sasnav_ping_pose *truth,
                            sasnav_pose align, double *along, double *across)
{
    for (int i = 0; i < run->n_pings; i++) {
        sasnav_pose e = sasnav_pose_compose(align, sasnav_ping_centroid(&nav[i]));
        pos_err d = err_in_frame(e, sasnav_ping_centroid(&truth[i]));
        along[i] = 1e3 * d.along;
        across[i] = 1e3 * d.across;
    }
}

/* PREFIX-steps.png: each step's surge and sway error against the truth;
 * PREFIX-nav.png: each ping's along / across position error, input and
 * estimated (and refined when given). */
static void write_plots(const char *prefix, const sasnav_run *run, const sasnav_virtual_navigation *vn,
                        sasnav_pose align, const sasnav_ping_pose *refined)
{
    int np = vn->n_pairs, n = run->n_pings;
    double *buf = malloc(sizeof(double) * (size_t)(3 * np + 7 * n));
    if (!buf) return;
    double *xs = buf, *eu = buf + np, *ev = buf + 2 * np, *xp = buf + 3 * np;
    double *ia = xp + n, *ic = ia + n, *ea = ic + n, *ec = ea + n, *ra = ec + n, *rc = ra + n;
    int nu = 0; /* the used steps: a flagged one is not in the navigation */
    for (int j = 0; j < np; j++) {
        const sasnav_virtual_pair *vp = &vn->pairs[j];
        if (!vp->used) continue;
        xs[nu] = vp->first_p;
        eu[nu] = 1e3 * (vp->est.displacement.x - vp->truth.x);
        ev[nu] = 1e3 * (vp->est.displacement.y - vp->truth.y);
        nu++;
    }
    for (int i = 0; i < n; i++) xp[i] = i;
    char path[1100], title[256];
    snprintf(path, sizeof path, "%s-steps.png", prefix);
    snprintf(title, sizeof title, "step errors, K = %d every %d, %d steps (%d flagged, not shown)", vn->k,
             vn->interleave, np, np - nu);
    const double *sx[2] = {xs, xs}, *sy[2] = {eu, ev};
    const int sn[2] = {nu, nu};
    const char *sl[2] = {"surge", "sway"};
    sasnav_line_plot lp = {title, "first ping of the step", "error against the truth (mm)", 2, sn, sx, sy, sl, 0,
                           NAN, NAN};
    if (sasnav_plot_lines(path, &lp)) fprintf(stderr, "bench_virtual: %s\n", sasnav_last_error());
    per_ping_errors(run, run->nav, run->truth, align, ia, ic);
    per_ping_errors(run, vn->nav, run->truth, align, ea, ec);
    if (refined) per_ping_errors(run, refined, run->truth, align, ra, rc);
    snprintf(path, sizeof path, "%s-nav.png", prefix);
    const double *nx[6] = {xp, xp, xp, xp, xp, xp}, *ny[6] = {ia, ic, ea, ec, ra, rc};
    const int nn[6] = {n, n, n, n, n, n};
    const char *nl[6] = {"input along", "input across", "estimated along", "estimated across", "refined along",
                         "refined across"};
    sasnav_line_plot lq = {"navigation error per ping", "ping", "position error (mm)", refined ? 6 : 4, nn, nx, ny,
                           nl, 0, NAN, NAN};
    if (sasnav_plot_lines(path, &lq)) fprintf(stderr, "bench_virtual: %s\n", sasnav_last_error());
    free(buf);
}

typedef struct {
    int on, only, sweeps, cg;
    double pixel, half, surge_range, sway_range, damping;
} refine_cfg;

/* The multi-ping refinement (refine.h, leave-one-out scenes) of `start` against a scene on a
 * square grid of half-width cfg->half round the mean ping position; prints
 * its sweeps and the navigation errors (raw as above, and after the best
 * rigid fit); writes the result to out. */
static int run_refine(const sasnav_run *run, const sasnav_ping_pose *start, const refine_cfg *cfg, int threads,
                      sasnav_pose align, sasnav_ping_pose *out)
{
    double cx = 0, cy = 0;
    for (int i = 0; i < run->n_pings; i++) {
        sasnav_pose c = sasnav_ping_centroid(&start[i]);
        cx += c.x / run->n_pings;
        cy += c.y / run->n_pings;
    }
    sasnav_refine_opts ro;
    sasnav_refine_default_opts(&ro);
    int np = (int)ceil(2 * cfg->half / cfg->pixel) + 1;
    double h = 0.5 * (np - 1) * cfg->pixel;
    sasnav_grid_make(cx - h, cx + h, np, cy - h, cy + h, np, &ro.grid);
    ro.sweeps = cfg->sweeps;
    ro.surge_range = cfg->surge_range;
    ro.sway_range = cfg->sway_range;
    ro.nthreads = threads;
    if (cfg->cg > 0) ro.cg_first = ro.cg_iterations = cfg->cg;
    if (cfg->damping > 0) ro.damping = cfg->damping;
    sasnav_refine_report rep;
    int rc = sasnav_refine(run, start, &ro, out, &rep);
    if (rc) return rc;
    printf("#   refinement (%d x %d pixels of %.1f mm, ranges %.1f / %.1f mm): %d sweeps%s, "
           "%.1f s\n", np, np, 1e3 * cfg->pixel, 1e3 * cfg->surge_range, 1e3 * cfg->sway_range, rep.sweeps,
           rep.undone ? " (+1 undone)" : "", rep.seconds);
    for (int i = 0; i < rep.sweeps; i++)
        printf("#     sweep %d: misfit %.4f -> %.4f, rms move %.3f mm\n", i + 1, rep.misfit[i], rep.misfit[i + 1],
               1e3 * rep.rms_move[i]);
    double a0, c0, w0, a1, c1, w1, ra0 = NAN, rc0 = NAN, ra1 = NAN, rc1 = NAN;
    nav_errors(run, start, run->truth, align, &a0, &c0, &w0);
    nav_errors(run, out, run->truth, align, &a1, &c1, &w1);
    sasnav_traj_rms_rigid(start, run->truth, run->n_pings, &ra0, &rc0);
    sasnav_traj_rms_rigid(out, run->truth, run->n_pings, &ra1, &rc1);
    printf("#   refined nav rms along/across mm (worst): %.3f %.3f (%.3f) -> %.3f %.3f (%.3f); "
           "after the best rigid fit: %.3f %.3f -> %.3f %.3f\n",
           1e3 * a0, 1e3 * c0, 1e3 * w0, 1e3 * a1, 1e3 * c1, 1e3 * w1, 1e3 * ra0, 1e3 * rc0, 1e3 * ra1, 1e3 * rc1);
    fflush(stdout);
    return SASNAV_OK;
}

static int parse3(const char *s, double v[3])
{
    return sscanf(s, "%lf,%lf,%lf", &v[0], &v[1], &v[2]) == 3;
}

int main(int argc, char **argv)
{
    long s0 = 201, ns = 1;
    double snr = 30.0, pixel = 0, extent = 0.3, drift_mm = 5.0, motion_rms = -1;
    double box[3] = {0.01, 0.01, 0.02};
    int k = 4, stride = 0, n_pings = 0, first = 0, threads = 0, quiet = 0, free_yaw = 0, iterations = 2, interleave = 1, closed = 0, keep_length = 0,
        align_heading = 0, along_input = 0;
    const char *file = NULL, *write_prefix = NULL, *plot_prefix = NULL, *drift_shape = "smooth",
               *dump_file = NULL;
    refine_cfg rf = {0, 0, 4, 0, 0.0025, 0.3, 0.012, 0.006, 0};
    for (int a = 1; a < argc; a++) {
        if (bench_seed_option(argc, argv, &a, &s0, &ns, &snr)) continue;
        if (!strcmp(argv[a], "--k") && a + 1 < argc) {
            k = atoi(argv[++a]);
        } else if (!strcmp(argv[a], "--stride") && a + 1 < argc) {
            stride = atoi(argv[++a]);
        } else if (!strcmp(argv[a], "--pings") && a + 1 < argc) {
            n_pings = atoi(argv[++a]);
        } else if (!strcmp(argv[a], "--first") && a + 1 < argc) {
            first = atoi(argv[++a]);
        } else if (!strcmp(argv[a], "--threads") && a + 1 < argc) {
            threads = atoi(argv[++a]);
        } else if (!strcmp(argv[a], "--pixel") && a + 1 < argc) {
            pixel = atof(argv[++a]);
        } else if (!strcmp(argv[a], "--extent") && a + 1 < argc) {
            extent = atof(argv[++a]);
        } else if (!strcmp(argv[a], "--box") && a + 1 < argc) {
            if (!parse3(argv[++a], box)) goto usage;
        } else if (!strcmp(argv[a], "--file") && a + 1 < argc) {
            file = argv[++a];
        } else if (!strcmp(argv[a], "--drift") && a + 1 < argc) {
            drift_mm = atof(argv[++a]);
        } else if (!strcmp(argv[a], "--drift-shape") && a + 1 < argc) {
            drift_shape = argv[++a];
            if (strcmp(drift_shape, "smooth") && strcmp(drift_shape, "alternate") && strcmp(drift_shape, "ramp") &&
                strcmp(drift_shape, "sway") && strcmp(drift_shape, "surge"))
                goto usage;
        } else if (!strcmp(argv[a], "--closed")) {
            closed = 1;
        } else if (!strcmp(argv[a], "--keep-length")) {
            keep_length = 1;
        } else if (!strcmp(argv[a], "--dump") && a + 1 < argc) {
            dump_file = argv[++a];
        } else if (!strcmp(argv[a], "--align-heading")) {
            align_heading = 1;
        } else if (!strcmp(argv[a], "--along-input")) {
            along_input = align_heading = 1;
        } else if (!strcmp(argv[a], "--interleave") && a + 1 < argc) {
            interleave = atoi(argv[++a]);
        } else if (!strcmp(argv[a], "--iterations") && a + 1 < argc) {
            iterations = atoi(argv[++a]);
        } else if (!strcmp(argv[a], "--free-yaw")) {
            free_yaw = 1;
        } else if (!strcmp(argv[a], "--motion-rms") && a + 1 < argc) {
            motion_rms = atof(argv[++a]);
        } else if (!strcmp(argv[a], "--write-nav") && a + 1 < argc) {
            write_prefix = argv[++a];
        } else if (!strcmp(argv[a], "--plot") && a + 1 < argc) {
            plot_prefix = argv[++a];
        } else if (!strcmp(argv[a], "--refine")) {
            rf.on = 1;
        } else if (!strcmp(argv[a], "--refine-only")) {
            rf.on = rf.only = 1;
        } else if (!strcmp(argv[a], "--refine-pixel") && a + 1 < argc) {
            rf.pixel = atof(argv[++a]);
        } else if (!strcmp(argv[a], "--refine-half") && a + 1 < argc) {
            rf.half = atof(argv[++a]);
        } else if (!strcmp(argv[a], "--cg") && a + 1 < argc) {
            rf.cg = atoi(argv[++a]);
        } else if (!strcmp(argv[a], "--damping") && a + 1 < argc) {
            rf.damping = atof(argv[++a]);
        } else if (!strcmp(argv[a], "--sweeps") && a + 1 < argc) {
            rf.sweeps = atoi(argv[++a]);
        } else if (!strcmp(argv[a], "--surge-range") && a + 1 < argc) {
            rf.surge_range = atof(argv[++a]);
        } else if (!strcmp(argv[a], "--sway-range") && a + 1 < argc) {
            rf.sway_range = atof(argv[++a]);
        } else if (!strcmp(argv[a], "--quiet")) {
            quiet = 1;
        } else {
        usage:
            fprintf(stderr, "usage: bench_virtual [--seeds S0 N] [--snr DB|inf] [--k K] [--stride S]\n"
                            "         [--pings N] [--first P] [--threads T] [--pixel M] [--extent M]\n"
                            "         [--box SURGE,SWAY,YAW] [--iterations N] [--interleave M] [--closed] [--keep-length]\n"
                            "         [--align-heading] [--along-input]\n"
                            "         [--free-yaw] [--motion-rms M] [--file run.h5 [--drift MM]\n"
                            "         [--drift-shape smooth|sway|surge|alternate|ramp]] [--write-nav PREFIX]\n"
                            "         [--plot PREFIX] [--refine | --refine-only] [--sweeps N] [--cg N] [--damping X]\n"
                            "         [--refine-pixel M] [--refine-half M] [--surge-range M] [--sway-range M] [--quiet]\n");
            return 2;
        }
    }
    if (file) ns = 1;
    printf("# virtual arrays of k = %d pings (every %d), stride %d, %d pass(es); grid %.2f m square; "
           "box %.3g m, %.3g m, %.3g rad\n",
           k, interleave, stride > 0 ? stride : interleave > 1 ? 1 : k, iterations, extent, box[0],
           box[1], box[2]);
    printf("# run  pairs  per-pair error rms: surge mm  sway mm  yaw mrad | worst: surge  sway | "
           "mean: surge sway | not ok | input nav rms along/across mm (worst) -> estimated | s/pair\n");
    int status = 0;
    for (long si = 0; si < ns; si++) {
        sasnav_run *full = NULL, *run = NULL;
        int rc;
        char name[64];
        if (file) {
            rc = sasnav_run_read(file, &full);
            snprintf(name, sizeof name, "file");
        } else {
            sasnav_scenario sc;
            sasnav_scenario_preset("circular", &sc);
            sasnav_scenario_seed(&sc, (uint64_t)(s0 + si));
            sc.snr_db = snr;
            if (motion_rms >= 0) sc.traj.surge_rms = sc.traj.sway_rms = motion_rms;
            rc = sasnav_simulate(&sc, NULL, NULL, &full);
            snprintf(name, sizeof name, "%ld", s0 + si);
        }
        if (rc) {
            fprintf(stderr, "bench_virtual: %s\n", sasnav_last_error());
            return 1;
        }
        int n = n_pings > 0 && first + n_pings <= full->n_pings ? n_pings : full->n_pings - first;
        int *idx = malloc(sizeof *idx * (size_t)n);
        for (int i = 0; i < n; i++) idx[i] = first + i;
        rc = sasnav_run_subset(full, idx, n, NULL, 0, &run);
        free(idx);
        sasnav_run_free(full);
        if (rc) {
            fprintf(stderr, "bench_virtual: %s\n", sasnav_last_error());
            return 1;
        }
        if (file) {
            /* The file's navigation is the truth; the input is it plus a
             * smooth drift in each ping's frame. */
            run->truth = malloc(sizeof *run->truth * (size_t)run->n_pings);
            for (int i = 0; i < run->n_pings; i++) {
                run->truth[i] = run->nav[i];
                double u = (double)i / (run->n_pings > 1 ? run->n_pings - 1 : 1);
                sasnav_pose d = {1e-3 * drift_mm * sin(2.5 * 2 * M_PI * u),
                                 1e-3 * drift_mm * sin(1.5 * 2 * M_PI * u), 0.0};
                if (!strcmp(drift_shape, "alternate")) /* odd pings moved: exact layouts */
                    d = (sasnav_pose){1e-3 * drift_mm * (i % 2), 1e-3 * drift_mm * (i % 2), 0.0};
                else if (!strcmp(drift_shape, "sway")) /* the smooth drift's sway alone */
                    d.x = 0.0;
                else if (!strcmp(drift_shape, "surge")) /* its surge alone */
                    d.y = 0.0;
                else if (!strcmp(drift_shape, "ramp")) /* a uniform stretch and tilt */
                    d = (sasnav_pose){1e-3 * drift_mm * u, 1e-3 * drift_mm * u, 0.0};
                run->nav[i].tx = sasnav_pose_compose(run->nav[i].tx, d);
                run->nav[i].array = sasnav_pose_compose(run->nav[i].array, d);
            }
        }
        sasnav_virtual_opts vo;
        sasnav_virtual_default_opts(&vo);
        vo.k = k;
        vo.stride = stride;
        vo.nthreads = threads;
        vo.pair.range = run->range_of_interest;
        vo.pair.range_extent = extent;
        vo.pair.cross_extent = extent;
        if (pixel > 0) vo.pair.pixel = pixel;
        vo.pair.box = (sasnav_pose){box[0], box[1], box[2]};
        if (free_yaw) vo.pair.fix_yaw = 0;
        vo.iterations = iterations;
        vo.interleave = interleave;
        vo.closed = closed;
        vo.keep_length = keep_length;
        vo.align_heading = align_heading;
        vo.along_input = along_input;
        if (rf.only) {
            /* The refinement alone, from the input navigation (errors in
             * the world frame: no alignment). */
            sasnav_ping_pose *out = malloc(sizeof *out * (size_t)run->n_pings);
            rc = run_refine(run, run->nav, &rf, threads, (sasnav_pose){0, 0, 0}, out);
            if (rc) {
                fprintf(stderr, "bench_virtual: %s\n", sasnav_last_error());
                status = 1;
            } else if (write_prefix) {
                write_nav(write_prefix, "input", run, run->nav);
                write_nav(write_prefix, "refined", run, out);
            }
            free(out);
            sasnav_run_free(run);
            continue;
        }
        sasnav_virtual_navigation vn;
        rc = sasnav_navigate_virtual(run, &vo, &vn);
        if (rc) {
            fprintf(stderr, "bench_virtual: %s\n", sasnav_last_error());
            sasnav_run_free(run);
            status = 1;
            continue;
        }
        double se[3] = {0, 0, 0}, we[2] = {0, 0}, me[2] = {0, 0};
        int not_ok = 0;
        for (int j = 0; j < vn.n_pairs; j++) {
            const sasnav_virtual_pair *vp = &vn.pairs[j];
            sasnav_pose d = vp->est.displacement;
            double e[3] = {d.x - vp->truth.x, d.y - vp->truth.y, sasnav_wrap_angle(d.theta - vp->truth.theta)};
            for (int c = 0; c < 3; c++) se[c] += e[c] * e[c];
            me[0] += e[0];
            me[1] += e[1];
            we[0] = fabs(e[0]) > we[0] ? fabs(e[0]) : we[0];
            we[1] = fabs(e[1]) > we[1] ? fabs(e[1]) : we[1];
            not_ok += vp->est.verdict != SASNAV_VERDICT_OK;
            if (!quiet)
                printf("  pair %3d (pings %3d, %3d): truth %+8.3f %+8.3f mm %+7.3f mrad  error %+7.3f "
                       "%+7.3f mm %+7.3f mrad  %-10s eta %.3f  %.1f s\n",
                       j, vp->first_p, vp->first_q, 1e3 * vp->truth.x, 1e3 * vp->truth.y,
                       1e3 * vp->truth.theta, 1e3 * e[0], 1e3 * e[1], 1e3 * e[2],
                       sasnav_verdict_name(vp->est.verdict), vp->est.eta, vp->est.seconds);
        }
        if (dump_file) {
            /* Per group: input and true centroids; per pair (g -> g + 1):
             * nominal, estimate, used. One line per group g. */
            FILE *df = fopen(dump_file, "w");
            sasnav_ping_pose *sc2 = malloc(sizeof *sc2 * (size_t)k * run->array.n_rx);
            sasnav_ping_pose *g2 = malloc(sizeof *g2 * (size_t)k);
            for (int g = 0; df && sc2 && g2 && g < vn.n_groups; g++) {
                sasnav_pose ct;
                for (int j = 0; j < k; j++) g2[j] = run->truth[(g * vn.stride + interleave * j) % run->n_pings];
                sasnav_virtual_layout(&run->array, g2, k, sc2, &ct);
                const sasnav_pose ci = vn.centroid_in[g];
                fprintf(df, "%d %.9f %.9f %.9f %.9f %.9f %.9f", g, ci.x, ci.y, ci.theta, ct.x, ct.y, ct.theta);
                if (g < vn.n_pairs) {
                    const sasnav_virtual_pair *vp = &vn.pairs[g];
                    fprintf(df, " %.9f %.9f %.9f %.9f %.9f %.9f %d\n", vp->nominal.x, vp->nominal.y,
                            vp->nominal.theta, vp->est.displacement.x, vp->est.displacement.y,
                            vp->est.displacement.theta, vp->used);
                } else {
                    fprintf(df, " nan nan nan nan nan nan 0\n");
                }
            }
            free(sc2);
            free(g2);
            if (df) fclose(df);
        }
        /* Align both navigations on the first group's true centroid. */
        sasnav_pose c_true, c_in;
        sasnav_ping_pose *scratch = malloc(sizeof *scratch * (size_t)k * run->array.n_rx);
        sasnav_ping_pose *gt = malloc(sizeof *gt * (size_t)k), *gi = malloc(sizeof *gi * (size_t)k);
        for (int j = 0; j < k; j++) {
            gt[j] = run->truth[interleave * j];
            gi[j] = run->nav[interleave * j];
        }
        sasnav_virtual_layout(&run->array, gt, k, scratch, &c_true);
        sasnav_virtual_layout(&run->array, gi, k, scratch, &c_in);
        free(scratch);
        free(gt);
        free(gi);
        sasnav_pose align = sasnav_pose_compose(c_true, sasnav_pose_inverse(c_in));
        double ia, ic, iw, ea, ec, ew;
        nav_errors(run, run->nav, run->truth, align, &ia, &ic, &iw);
        nav_errors(run, vn.nav, run->truth, align, &ea, &ec, &ew);
        int np = vn.n_pairs;
        printf("%5s  %5d  %8.3f %8.3f %8.3f | %7.3f %7.3f | %+7.3f %+7.3f | %3d | %6.3f %6.3f (%6.3f) "
               "-> %6.3f %6.3f (%6.3f) | %.2f\n",
               name, np, 1e3 * sqrt(se[0] / np), 1e3 * sqrt(se[1] / np), 1e3 * sqrt(se[2] / np),
               1e3 * we[0], 1e3 * we[1], 1e3 * me[0] / np, 1e3 * me[1] / np, not_ok, 1e3 * ia,
               1e3 * ic, 1e3 * iw, 1e3 * ea, 1e3 * ec, 1e3 * ew, vn.seconds / np / vn.iterations);
        printf("#   flagged steps (input navigation's step kept): %d; length scale %.5f\n", vn.n_fallback,
               vn.length_scale);
        if (vn.align_heading)
            printf("#   layouts turned onto the headings: mean %+.3f mrad, rms %.3f mrad, exposure %.3f mm\n",
                   1e3 * vn.turn_mean, 1e3 * vn.turn_rms, 1e3 * vn.turn_exposure);
        {
            /* How much of the input's step error each estimate keeps: the
             * used steps' estimate error regressed on the input's error
             * over the same step (docs/airsas.md, cause 1). */
            double *buf = malloc(sizeof(double) * 4 * (size_t)np);
            if (!buf) {
                fprintf(stderr, "bench_virtual: out of memory\n");
                return 1;
            }
            int nu = 0;
            for (int j = 0; j < np; j++) {
                const sasnav_virtual_pair *vp = &vn.pairs[j];
                if (!vp->used) continue;
                buf[nu] = vp->nominal.x - vp->truth.x;
                buf[np + nu] = vp->est.displacement.x - vp->truth.x;
                buf[2 * np + nu] = vp->nominal.y - vp->truth.y;
                buf[3 * np + nu] = vp->est.displacement.y - vp->truth.y;
                nu++;
            }
            double bu, ru, bv, rv;
            regress(buf, buf + np, nu, &bu, &ru);
            regress(buf + 2 * np, buf + 3 * np, nu, &bv, &rv);
            double iu = 0, iv = 0;
            for (int j = 0; j < nu; j++) {
                iu += buf[j] * buf[j] / nu;
                iv += buf[2 * np + j] * buf[2 * np + j] / nu;
            }
            printf("#   estimate error = b x input error per step: surge b %.3f (corr %.3f), sway b %.3f "
                   "(corr %.3f); input step error rms %.3f / %.3f mm\n",
                   bu, ru, bv, rv, 1e3 * sqrt(iu), 1e3 * sqrt(iv));
            free(buf);
        }
        if (vn.closed)
            printf("#   misclosure of the %s: %+.3f %+.3f mm, %+.3f mrad (spread over %d steps)\n",
                   vn.along_input ? "across-track corrections (world x, y)" : "chained steps", 1e3 * vn.misclosure.x, 1e3 * vn.misclosure.y, 1e3 * vn.misclosure.theta, np);
        fflush(stdout);
        if (write_prefix) {
            /* PREFIX-input.h5 and PREFIX-estimated.h5 (sasnav image --nav). */
            write_nav(write_prefix, "input", run, run->nav);
            write_nav(write_prefix, "estimated", run, vn.nav);
        }
        sasnav_ping_pose *refined = NULL;
        if (rf.on) {
            refined = malloc(sizeof *refined * (size_t)run->n_pings);
            rc = run_refine(run, vn.nav, &rf, threads, align, refined);
            if (rc) {
                fprintf(stderr, "bench_virtual: %s\n", sasnav_last_error());
                status = 1;
                free(refined);
                refined = NULL;
            } else if (write_prefix) {
                write_nav(write_prefix, "refined", run, refined);
            }
        }
        if (plot_prefix) {
            char prefix[900];
            if (ns > 1)
                snprintf(prefix, sizeof prefix, "%s-%s", plot_prefix, name);
            else
                snprintf(prefix, sizeof prefix, "%s", plot_prefix);
            write_plots(prefix, run, &vn, align, refined);
        }
        free(refined);
        sasnav_virtual_navigation_free(&vn);
        sasnav_run_free(run);
    }
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    printf("# peak RSS %.1f MiB\n", ru.ru_maxrss / 1024.0);
    return status;
}
