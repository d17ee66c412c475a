/* A joint-misfit criterion for a ping pair, measured against the truth
 * (docs/estimator.md, "What the data allow: a Cramer-Rao bound"): one scene
 * s on a grid explains both pings,
 *
 *   J(sigma) = min_s ||phi_p - T_p s||^2 + ||phi_q - T_q(sigma) s||^2 + mu ||s||^2,
 *
 * (the Gaussian-scene likelihood's data term, mu the noise-to-scene power
 * ratio), solved by CGLS on the two pings stacked as one operator of 2N
 * channels (each with its ping's poses: sasnav_op_set_channels); J / ||phi||^2
 * is minimised over sigma by BOBYQA from a start off the truth. Pings'
 * sensors at their true places in their centroid frames (bench_bias's
 * "full" oracle), so what remains is the criterion's error.
 *
 * usage: bench_joint --seeds S0 N [--snr DB|inf] [--pairs A:B] [--k K] [--mu M]
 *                    [--pixel M] [--cross-pixel M] [--range-extent M]
 *                    [--cross-extent M] [--epca]
 * --epca: both pings modelled by the EPCA geometry with the run's fixed
 * Tx-array offset (what `navigate` assumes; bench_bias's "fixed") instead
 * of their true sensor poses.
 * mu is relative to ||T^H phi||^2 / ||phi||^2 (the normal operator's
 * Rayleigh quotient along the data). Prints per pair the error of the
 * minimiser (surge mm, sway microns, yaw rad) and the evaluations. */
#include "sasnav/error.h"
#include "sasnav/geometry.h"
#include "sasnav/image.h"
#include "sasnav/model.h"
#include "sasnav/op.h"
#include "sasnav/run.h"
#include "sasnav/sim.h"
#include "bench_util.h"

#include <nlopt.h>
#include <omp.h>

typedef struct {
    sasnav_op *op;
    sasnav_ping_pose chan[SASNAV_MAX_RX];
    sasnav_ping_pose lq;
    sasnav_pose cp, s0;
    int n_rx, np, nd, k, evals;
    double lambda, nphi2;
    const sasnav_cfloat *phi;
    sasnav_cfloat *s, *r, *work;
    double scale[3];
} joint;

static double criterion(unsigned n, const double *u, double *grad, void *data)
{
    (void)n;
    (void)grad;
    joint *J = data;
    sasnav_pose s = {J->s0.x + u[0] * J->scale[0], J->s0.y + u[1] * J->scale[1],
                     J->s0.theta + u[2] * J->scale[2]};
    sasnav_ping_pose q = sasnav_ping_place(sasnav_pose_compose(J->cp, s), &J->lq);
    for (int l = 0; l < J->n_rx; l++) J->chan[J->n_rx + l] = q;
    if (sasnav_op_set_channels(J->op, J->chan)) return HUGE_VAL;
    sasnav_cgls_opts co = {J->k, J->lambda};
    if (sasnav_cgls(J->op, J->phi, &co, J->s, J->work)) return HUGE_VAL;
    if (sasnav_op_forward(J->op, J->s, J->r)) return HUGE_VAL;
    double e = 0, x2 = 0;
    for (int i = 0; i < J->nd; i++) {
        sasnav_cfloat d = J->phi[i] - J->r[i];
        e += crealf(d * conjf(d));
    }
    for (int i = 0; i < J->np; i++) x2 += crealf(J->s[i] * conjf(J->s[i]));
    J->evals++;
    return (e + J->lambda * x2) / J->nphi2;
}

int main(int argc, char **argv)
{
    long s0 = 8101, ns = 1;
    double snr = INFINITY, mu = 1e-3, pixel = 0.0125, cpixel = 0, range_extent = 1.6, cross_extent = 1.6;
    int k = 40, pa = 0, pb = 15, epca = 0;
    for (int a = 1; a < argc; a++) {
        if (bench_seed_option(argc, argv, &a, &s0, &ns, &snr)) continue;
        if (!strcmp(argv[a], "--pairs") && a + 1 < argc) sscanf(argv[++a], "%d:%d", &pa, &pb);
        else if (!strcmp(argv[a], "--k") && a + 1 < argc) k = atoi(argv[++a]);
        else if (!strcmp(argv[a], "--mu") && a + 1 < argc) mu = atof(argv[++a]);
        else if (!strcmp(argv[a], "--pixel") && a + 1 < argc) pixel = atof(argv[++a]);
        else if (!strcmp(argv[a], "--cross-pixel") && a + 1 < argc) cpixel = atof(argv[++a]);
        else if (!strcmp(argv[a], "--epca")) epca = 1;
        else if (!strcmp(argv[a], "--range-extent") && a + 1 < argc) range_extent = atof(argv[++a]);
        else if (!strcmp(argv[a], "--cross-extent") && a + 1 < argc) cross_extent = atof(argv[++a]);
        else {
            fprintf(stderr, "usage: bench_joint --seeds S0 N [--snr DB|inf] [--pairs A:B] [--k K] [--mu M]\n"
                            "                   [--pixel M] [--cross-pixel M] [--range-extent M]\n"
                            "                   [--cross-extent M] [--epca]\n");
            return 2;
        }
    }
    if (!(cpixel > 0)) cpixel = pixel;
    double sum2[3] = {0}, cnt = 0;
    for (long seed = s0; seed < s0 + ns; seed++) {
        sasnav_run *run = bench_trajectory_run(seed, snr, 0);
        if (!run) return 1;
        int n_rx = run->array.n_rx, nsamp = run->win.n_samples;
        sasnav_array arr2 = run->array;
        arr2.n_rx = 2 * n_rx;
        for (int l = 0; l < n_rx; l++) arr2.rx_u[n_rx + l] = run->array.rx_u[l];
        for (int p = pa; p < pb && p + 1 < run->n_pings; p++) {
            joint J = {0};
            J.n_rx = n_rx;
            J.k = k;
            J.cp = sasnav_ping_centroid(&run->truth[p]);
            sasnav_pose cq = sasnav_ping_centroid(&run->truth[p + 1]);
            J.s0 = sasnav_ping_displacement(&run->truth[p], &run->truth[p + 1]);
            J.lq = sasnav_ping_local(&run->truth[p + 1]);
            sasnav_ping_pose ping_p = run->truth[p];
            if (epca) {
                /* The EPCA model with the run's fixed offset at both pings'
                 * true centroids (what navigate assumes). */
                J.lq = sasnav_epca_local(run->tx_lag, 0.0);
                ping_p = sasnav_ping_place(J.cp, &J.lq);
            }
            for (int l = 0; l < n_rx; l++) J.chan[l] = ping_p;
            /* Grid in p's centroid frame's orientation, centred between the
             * pings at the swath's middle range. */
            double xc = 0.5 * (J.cp.x + cq.x), yc = J.cp.y + run->range_of_interest;
            int nx = (int)lround(cross_extent / cpixel) + 1, ny = (int)lround(range_extent / pixel) + 1;
            J.np = nx * ny;
            double *gx = malloc((size_t)J.np * sizeof *gx), *gy = malloc((size_t)J.np * sizeof *gy);
            if (!gx || !gy) return 1;
            for (int iy = 0; iy < ny; iy++)
                for (int ix = 0; ix < nx; ix++) {
                    double lx = -0.5 * cross_extent + ix * cpixel, ly = -0.5 * range_extent + iy * pixel;
                    double c = cos(J.cp.theta), sn = sin(J.cp.theta);
                    gx[iy * nx + ix] = xc + c * lx - sn * ly;
                    gy[iy * nx + ix] = yc + sn * lx + c * ly;
                }
            int rc = sasnav_op_create(&run->sys, &arr2, &run->win, J.np, gx, gy, NULL, &J.op);
            free(gx);
            free(gy);
            if (rc) {
                fprintf(stderr, "op: %s\n", sasnav_last_error());
                return 1;
            }
            J.nd = 2 * n_rx * nsamp;
            sasnav_cfloat *phi = malloc((size_t)J.nd * sizeof *phi);
            memcpy(phi, sasnav_run_ping(run, p), (size_t)n_rx * nsamp * sizeof *phi);
            memcpy(phi + (size_t)n_rx * nsamp, sasnav_run_ping(run, p + 1), (size_t)n_rx * nsamp * sizeof *phi);
            J.phi = phi;
            J.s = malloc((size_t)J.np * sizeof *J.s);
            J.r = malloc((size_t)J.nd * sizeof *J.r);
            J.work = malloc((size_t)(2 * J.np + 2 * J.nd) * sizeof *J.work);
            if (!phi || !J.s || !J.r || !J.work) {
                fprintf(stderr, "bench_joint: out of memory\n");
                return 1;
            }
            J.nphi2 = 0;
            for (int i = 0; i < J.nd; i++) J.nphi2 += crealf(phi[i] * conjf(phi[i]));
            /* lambda from the normal operator's Rayleigh quotient at the truth. */
            for (int l = 0; l < n_rx; l++) J.chan[n_rx + l] = sasnav_ping_place(cq, &J.lq);
            if (sasnav_op_set_channels(J.op, J.chan) || sasnav_op_adjoint(J.op, phi, J.s)) {
                fprintf(stderr, "bench_joint: %s\n", sasnav_last_error());
                return 1;
            }
            double a2 = 0;
            for (int i = 0; i < J.np; i++) a2 += crealf(J.s[i] * conjf(J.s[i]));
            J.lambda = mu * a2 / J.nphi2;
            J.scale[0] = 0.25e-3;
            J.scale[1] = 31.25e-6;
            J.scale[2] = 5e-5;
            double u[3] = {2.0, 0.4, -2.0}, lb[3] = {-40, -20, -40}, ub[3] = {40, 20, 40}, f = 0;
            double t0 = omp_get_wtime();
            nlopt_opt opt = nlopt_create(NLOPT_LN_BOBYQA, 3);
            nlopt_set_lower_bounds(opt, lb);
            nlopt_set_upper_bounds(opt, ub);
            double dx[3] = {1, 0.5, 1};
            nlopt_set_initial_step(opt, dx);
            nlopt_set_min_objective(opt, criterion, &J);
            nlopt_set_xtol_abs1(opt, 0.02);
            nlopt_set_maxeval(opt, 300);
            nlopt_optimize(opt, u, &f);
            nlopt_destroy(opt);
            double e[3] = {u[0] * J.scale[0], u[1] * J.scale[1], u[2] * J.scale[2]};
            printf("%6ld %2d  surge %+8.4f mm  sway %+8.3f um  yaw %+10.3e  J %.6f  evals %d  %.1f s\n", seed, p,
                   1e3 * e[0], 1e6 * e[1], e[2], f, J.evals, omp_get_wtime() - t0);
            fflush(stdout);
            for (int i = 0; i < 3; i++) sum2[i] += e[i] * e[i];
            cnt++;
            sasnav_op_destroy(J.op);
            free(phi);
            free(J.s);
            free(J.r);
            free(J.work);
        }
        sasnav_run_free(run);
    }
    printf("rms over %.0f pairs: surge %.4f mm, sway %.3f um, yaw %.3e rad\n", cnt, 1e3 * sqrt(sum2[0] / cnt),
           1e6 * sqrt(sum2[1] / cnt), sqrt(sum2[2] / cnt));
    return 0;
}
