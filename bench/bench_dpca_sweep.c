/* DPCA (Bellettini & Pinto 2002) versus the subspace-intersection estimator
 * on the same simulated ping pairs (paper-pair system, 30 dB SNR), sweeping
 * the surge error (0..5 cm, yaw 0) and the yaw error (0..4e-2 rad, surge 0),
 * with a fixed sway error of 5 mm.
 *
 * usage: bench_dpca_sweep [-o DIR] [--k K] [--i I] [--threads T]
 * Prints a table of the sway (and yaw) errors of both methods, the first
 * surge and yaw at which DPCA's sway error exceeds lambda/10, and writes
 * DIR/dpca_sweep.csv, DIR/dpca_sweep_surge.png, DIR/dpca_sweep_yaw.png. */
#include "sasnav/dpca.h"
#include "sasnav/error.h"
#include "sasnav/estimator.h"
#include "sasnav/plot.h"
#include "sasnav/sim.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define SWAY 0.005

typedef struct {
    sasnav_pose truth, dpca, subspace;
    int dpca_rc, sub_rc;
} sweep_case;

static void run_case(sasnav_pose err, const sasnav_pair_opts *po, sweep_case *c)
{
    sasnav_scenario sc;
    sasnav_scenario_preset("paper-pair", &sc);
    sc.traj.pair_error = err;
    c->truth = err;
    sasnav_run *run = NULL;
    if (sasnav_simulate(&sc, NULL, NULL, &run)) {
        c->dpca_rc = c->sub_rc = -1;
        return;
    }
    sasnav_pair_result r;
    sasnav_dpca_opts dopts;
    sasnav_dpca_default_opts(&dopts);
    c->dpca_rc = sasnav_dpca_estimate(run, 0, 1, &dopts, &r, NULL);
    c->dpca = r.error;
    sasnav_pair *pair = NULL;
    c->sub_rc = sasnav_pair_create(&run->sys, &run->array, &run->win, po, &pair);
    if (!c->sub_rc)
        c->sub_rc = sasnav_pair_set_data(pair, sasnav_run_ping(run, 0), sasnav_run_ping(run, 1),
                                         sasnav_ping_displacement(&run->nav[0], &run->nav[1]));
    if (!c->sub_rc) c->sub_rc = sasnav_pair_estimate(pair, &r);
    c->subspace = r.error;
    sasnav_pair_destroy(pair);
    sasnav_run_free(run);
}

static double err_or_nan(int rc, double est, double truth) { return rc ? NAN : est - truth; }

int main(int argc, char **argv)
{
    const char *dir = ".";
    sasnav_pair_opts po;
    sasnav_pair_default_opts(&po);
    for (int a = 1; a < argc; a++) {
        if (!strcmp(argv[a], "-o") && a + 1 < argc) dir = argv[++a];
        else if (!strcmp(argv[a], "--k") && a + 1 < argc) po.k = atoi(argv[++a]);
        else if (!strcmp(argv[a], "--i") && a + 1 < argc) po.i = atoi(argv[++a]);
        else if (!strcmp(argv[a], "--threads") && a + 1 < argc) po.nthreads = atoi(argv[++a]);
        else {
            fprintf(stderr, "usage: bench_dpca_sweep [-o DIR] [--k K] [--i I] [--threads T]\n");
            return 2;
        }
    }
    const double surges[] = {0, 0.005, 0.01, 0.0125, 0.015, 0.02, 0.03, 0.04, 0.05};
    const double yaws[] = {0, 0.005, 0.01, 0.02, 0.03, 0.04};
    enum { NS = sizeof surges / sizeof surges[0], NY = sizeof yaws / sizeof yaws[0] };
    sweep_case cs[NS + NY];
    double lambda = 1500.0 / 300e3;
    printf("sway error %.1f mm in every case; lambda/10 = %.2f mm; k = %d, i = %d\n", 1e3 * SWAY,
           1e3 * lambda / 10, po.k, po.i);
    printf("%-6s %9s %10s | %14s %12s | %14s %12s\n", "sweep", "surge mm", "yaw rad", "DPCA sway err", "DPCA yaw err",
           "subsp sway err", "subsp yaw err");
    double surge_break = NAN, yaw_break = NAN;
    for (int j = 0; j < NS + NY; j++) {
        sasnav_pose e = j < NS ? (sasnav_pose){surges[j], SWAY, 0} : (sasnav_pose){0, SWAY, yaws[j - NS]};
        run_case(e, &po, &cs[j]);
        double dw = err_or_nan(cs[j].dpca_rc, cs[j].dpca.y, e.y), dy = err_or_nan(cs[j].dpca_rc, cs[j].dpca.theta, e.theta);
        double sw = err_or_nan(cs[j].sub_rc, cs[j].subspace.y, e.y), sy = err_or_nan(cs[j].sub_rc, cs[j].subspace.theta, e.theta);
        printf("%-6s %9.2f %10.4f | %11.4f mm %12.2e | %11.4f mm %12.2e\n", j < NS ? "surge" : "yaw", 1e3 * e.x,
               e.theta, 1e3 * dw, dy, 1e3 * sw, sy);
        fflush(stdout);
        int broken = !(fabs(dw) <= lambda / 10);
        if (j < NS && broken && isnan(surge_break)) surge_break = e.x;
        if (j >= NS && broken && isnan(yaw_break)) yaw_break = e.theta;
    }
    printf("DPCA's sway error first exceeds lambda/10 at surge %.4g m (phase-centre spacing 0.025 m) "
           "and at yaw %.4g rad (NaN: never in the sweep)\n", surge_break, yaw_break);

    char path[1024];
    snprintf(path, sizeof path, "%s/dpca_sweep.csv", dir);
    FILE *f = fopen(path, "w");
    if (f) {
        fprintf(f, "sweep,surge_m,sway_m,yaw_rad,dpca_sway_err_m,dpca_yaw_err_rad,subspace_sway_err_m,subspace_yaw_err_rad\n");
        for (int j = 0; j < NS + NY; j++)
            fprintf(f, "%s,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g\n", j < NS ? "surge" : "yaw", cs[j].truth.x, cs[j].truth.y,
                    cs[j].truth.theta, err_or_nan(cs[j].dpca_rc, cs[j].dpca.y, cs[j].truth.y),
                    err_or_nan(cs[j].dpca_rc, cs[j].dpca.theta, cs[j].truth.theta),
                    err_or_nan(cs[j].sub_rc, cs[j].subspace.y, cs[j].truth.y),
                    err_or_nan(cs[j].sub_rc, cs[j].subspace.theta, cs[j].truth.theta));
        fclose(f);
    }
    for (int s = 0; s < 2; s++) {
        int n = s == 0 ? NS : NY, off = s == 0 ? 0 : NS;
        double x[NS > NY ? NS : NY], yd[NS > NY ? NS : NY], ys[NS > NY ? NS : NY], lim[NS > NY ? NS : NY];
        for (int j = 0; j < n; j++) {
            x[j] = s == 0 ? 1e2 * cs[off + j].truth.x : cs[off + j].truth.theta;
            yd[j] = 1e3 * fabs(err_or_nan(cs[off + j].dpca_rc, cs[off + j].dpca.y, cs[off + j].truth.y));
            ys[j] = 1e3 * fabs(err_or_nan(cs[off + j].sub_rc, cs[off + j].subspace.y, cs[off + j].truth.y));
            if (ys[j] < 1e-4) ys[j] = 1e-4;
            if (yd[j] < 1e-4) yd[j] = 1e-4;
            lim[j] = 1e3 * lambda / 10;
        }
        const double *xs[3] = {x, x, x}, *yv[3] = {yd, ys, lim};
        int ns[3] = {n, n, n};
        const char *labels[3] = {"DPCA", "subspace intersection", "lambda/10"};
        sasnav_line_plot lp = {s == 0 ? "|sway error| vs surge error (yaw 0)" : "|sway error| vs yaw error (surge 0)",
                               s == 0 ? "surge error (cm)" : "yaw error (rad)", "|sway error| (mm)", 3, ns, xs, yv,
                               labels, 1, NAN, NAN};
        snprintf(path, sizeof path, "%s/dpca_sweep_%s.png", dir, s == 0 ? "surge" : "yaw");
        if (sasnav_plot_lines(path, &lp)) fprintf(stderr, "plot: %s\n", sasnav_last_error());
    }
    return 0;
}
