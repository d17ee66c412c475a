/* The information two pings hold about their displacement: the matrices of
 * a Cramer-Rao bound for (surge, sway, yaw) of a ping pair of a seeded
 * paper-trajectory run, for any estimator that sees both pings' samples and
 * knows the seabed's statistics but not its scatterers (docs/estimator.md,
 * "What the data allow: a Cramer-Rao bound").
 *
 * Model (the simulator's): the seabed is circular complex Gaussian speckle
 * of intensity I(x) per square metre (sasnav_scene_ripples: 1e4 m(x)^2 with
 * the ripple modulation m and the disc), so the samples of pings p and q
 * stacked, phi = A s + n with A = [T_p; T_q(sigma)], are circular Gaussian
 * with covariance
 *
 *   C(sigma) = A W A^H + sigma_n^2 I,   W = diag(I(x_n) dx dy),
 *
 * the scene sampled at points x_n on a grid fine enough for the integrand
 * (dy = 5 mm in range: the product of two pulses of band B lives below
 * 2 x 2B / c = 80 cycles per metre; dx = 1 cm along track: two phase
 * centres 0.6 m apart change their phase difference by a cycle per 4 cm at
 * 10 m). sigma is q's centroid pose in p's centroid frame (the estimator's
 * displacement), q's sensors kept at their true places in its centroid
 * frame (the "full" oracle of bench_bias). The Fisher information is
 * F_ij = tr(C^-1 dC/dsigma_i C^-1 dC/dsigma_j) and the bound on the error
 * of component i is sqrt((F^-1)_ii).
 *
 * This program writes the matrices; bench/crlb.py does the linear algebra
 * (numpy): `bench_crlb --seed S --pair J -o PREFIX`, then
 * `python3 bench/crlb.py PREFIX --snr 30 20`.
 *   PREFIX.txt  M (samples of both pings), the sample window, the signal
 *               power of the clean run (the simulator's SNR reference), the
 *               model's mean power on the diagonal against the clean data's
 *               in the same window (the model's check), h per component
 *   PREFIX.bin  C0 = A W A^H at the true sigma (M x M, complex64, row
 *               major), then for each component i the q rows of its central
 *               difference (C(sigma + h_i) - C(sigma - h_i)) / (2 h_i)
 *               (M/2 x M each; the p rows follow by Hermitian symmetry and
 *               the p-p block does not depend on sigma)
 * C's columns come from the operators: column j is A W A^H e_j.
 *
 * usage: bench_crlb --seed S --pair J -o PREFIX [--samples A:B] [--dx M]
 *                   [--dy M] [--half-width M] [--h-scale F] [--threads T]
 * --samples keeps samples A..B-1 of every channel (default all);
 * --half-width: the scene grid's along-track half-extent about the pair's
 * centre (default 2.1 m: the two-way beam's first sidelobes at 10 m);
 * --h-scale multiplies the difference steps (0.25 mm, 31 microns, 5e-5 rad:
 * the estimator's final-stage half units) to check the derivatives. */
#include "sasnav/error.h"
#include "sasnav/geometry.h"
#include "sasnav/model.h"
#include "sasnav/op.h"
#include "sasnav/run.h"
#include "sasnav/sim.h"
#include "bench_util.h"

#include <omp.h>

enum { N_SIG = 7 }; /* sigma0, then +h_i, -h_i for i = 0, 1, 2 */

static void usage(void)
{
    fprintf(stderr, "usage: bench_crlb --seed S --pair J -o PREFIX [--samples A:B] [--dx M] [--dy M]\n"
                    "                  [--half-width M] [--h-scale F] [--threads T]\n");
}

int main(int argc, char **argv)
{
    long seed = -1;
    int pair = -1, s_a = 0, s_b = -1, threads = 0;
    double dx = 0.01, dy = 0.005, half_width = 2.1, h_scale = 1.0;
    const char *prefix = NULL;
    for (int a = 1; a < argc; a++) {
        if (!strcmp(argv[a], "--seed") && a + 1 < argc) seed = atol(argv[++a]);
        else if (!strcmp(argv[a], "--pair") && a + 1 < argc) pair = atoi(argv[++a]);
        else if (!strcmp(argv[a], "-o") && a + 1 < argc) prefix = argv[++a];
        else if (!strcmp(argv[a], "--samples") && a + 1 < argc) {
            if (sscanf(argv[++a], "%d:%d", &s_a, &s_b) != 2) {
                usage();
                return 2;
            }
        } else if (!strcmp(argv[a], "--dx") && a + 1 < argc) dx = atof(argv[++a]);
        else if (!strcmp(argv[a], "--dy") && a + 1 < argc) dy = atof(argv[++a]);
        else if (!strcmp(argv[a], "--half-width") && a + 1 < argc) half_width = atof(argv[++a]);
        else if (!strcmp(argv[a], "--h-scale") && a + 1 < argc) h_scale = atof(argv[++a]);
        else if (!strcmp(argv[a], "--threads") && a + 1 < argc) threads = atoi(argv[++a]);
        else {
            usage();
            return 2;
        }
    }
    if (seed < 0 || pair < 0 || !prefix || !(dx > 0) || !(dy > 0) || !(half_width > 0) ||
        !(h_scale > 0) || threads < 0) {
        usage();
        return 2;
    }
    if (threads > 0) omp_set_num_threads(threads);

    sasnav_run *run = bench_trajectory_run(seed, INFINITY, 0);
    if (!run) return 1;
    if (pair + 1 >= run->n_pings) {
        fprintf(stderr, "bench_crlb: --pair %d: the run has %d pings\n", pair, run->n_pings);
        return 2;
    }
    const int n_rx = run->array.n_rx, ns_all = run->win.n_samples;
    if (s_b < 0) s_b = ns_all;
    if (s_a < 0 || s_b > ns_all || s_b - s_a < 8) {
        fprintf(stderr, "bench_crlb: --samples outside 0:%d\n", ns_all);
        return 2;
    }
    const int ns = s_b - s_a, mp = n_rx * ns, m = 2 * mp;
    sasnav_window win = {run->win.t0 + s_a / run->sys.sample_rate, ns};

    /* The clean run's mean power (the simulator's SNR reference) and the
     * clean samples of p and q in the window (the model's check). */
    double power_run = 0, power_win = 0;
    {
        size_t n = (size_t)run->n_pings * n_rx * ns_all;
        for (size_t i = 0; i < n; i++) power_run += crealf(run->raw[i] * conjf(run->raw[i]));
        power_run /= (double)n;
        for (int k = 0; k < 2; k++) {
            const sasnav_cfloat *d = sasnav_run_ping(run, pair + k);
            for (int l = 0; l < n_rx; l++)
                for (int s = s_a; s < s_b; s++) {
                    sasnav_cfloat v = d[(size_t)l * ns_all + s];
                    power_win += crealf(v * conjf(v));
                }
        }
        power_win /= (double)m;
    }

    /* The scene grid and its weights (sasnav_scene_ripples' intensity). */
    sasnav_scenario sc;
    sasnav_scenario_preset("paper-trajectory", &sc);
    const sasnav_ripple_params *rp = &sc.ripples;
    sasnav_pose cp = sasnav_ping_centroid(&run->truth[pair]);
    sasnav_pose cq = sasnav_ping_centroid(&run->truth[pair + 1]);
    double xc = 0.5 * (cp.x + cq.x);
    double x0 = fmax(rp->x_min, xc - half_width), x1 = fmin(rp->x_max, xc + half_width);
    double r_lo = 0.5 * run->sys.sound_speed * win.t0 - 0.3;
    double r_hi = 0.5 * run->sys.sound_speed * (win.t0 + ns / run->sys.sample_rate) + 0.3;
    double y0 = fmax(rp->y_min, r_lo), y1 = fmin(rp->y_max, r_hi);
    int nx = (int)floor((x1 - x0) / dx), ny = (int)floor((y1 - y0) / dy);
    if (nx < 1 || ny < 1) {
        fprintf(stderr, "bench_crlb: no seabed in the window\n");
        return 1;
    }
    int np = nx * ny;
    double *px = malloc((size_t)np * sizeof *px), *py = malloc((size_t)np * sizeof *py);
    float *w = malloc((size_t)np * sizeof *w);
    if (!px || !py || !w) return 1;
    double ca = cos(rp->ripple_angle), sa = sin(rp->ripple_angle);
    for (int iy = 0; iy < ny; iy++)
        for (int ix = 0; ix < nx; ix++) {
            int n = iy * nx + ix;
            double x = x0 + (ix + 0.5) * dx, y = y0 + (iy + 0.5) * dy;
            double d = -x * sa + y * ca;
            double mod = rp->background * (1.0 + rp->ripple_depth * sin(2.0 * M_PI * d / rp->ripple_period));
            double r2 = (x - rp->disc_x) * (x - rp->disc_x) + (y - rp->disc_y) * (y - rp->disc_y);
            if (rp->disc_radius > 0 && r2 <= rp->disc_radius * rp->disc_radius) mod = rp->disc_amplitude;
            px[n] = x;
            py[n] = y;
            w[n] = (float)(1e4 * mod * mod * dx * dy);
        }

    /* Operators: p at its true pose; q at sigma0 and sigma0 +- h_i. */
    sasnav_pose s0 = sasnav_ping_displacement(&run->truth[pair], &run->truth[pair + 1]);
    sasnav_ping_pose lq = sasnav_ping_local(&run->truth[pair + 1]);
    const double h[3] = {0.25e-3 * h_scale, 31.25e-6 * h_scale, 5e-5 * h_scale};
    sasnav_op_opts oo;
    sasnav_op_default_opts(&oo);
    sasnav_op *op_p = NULL, *op_q[N_SIG] = {0};
    int rc = sasnav_op_create(&run->sys, &run->array, &win, np, px, py, &oo, &op_p);
    if (!rc) rc = sasnav_op_set_geometry(op_p, &run->truth[pair]);
    for (int k = 0; k < N_SIG && !rc; k++) {
        sasnav_pose s = s0;
        if (k > 0) {
            double step = (k % 2 ? 1.0 : -1.0) * h[(k - 1) / 2];
            if ((k - 1) / 2 == 0) s.x += step;
            else if ((k - 1) / 2 == 1) s.y += step;
            else s.theta += step;
        }
        sasnav_ping_pose q = sasnav_ping_place(sasnav_pose_compose(cp, s), &lq);
        rc = sasnav_op_create(&run->sys, &run->array, &win, np, px, py, &oo, &op_q[k]);
        if (!rc) rc = sasnav_op_set_geometry(op_q[k], &q);
    }
    if (rc) {
        fprintf(stderr, "bench_crlb: %s\n", sasnav_last_error());
        return 1;
    }

    /* Columns. c0 is M x M; dq[i] holds the q rows (mp x M). Stored by
     * columns here (col j at offset j * rows) and written row-major by
     * transposition at the end. */
    sasnav_cfloat *c0 = calloc((size_t)m * m, sizeof *c0);
    sasnav_cfloat *dq[3];
    for (int i = 0; i < 3; i++) dq[i] = calloc((size_t)mp * m, sizeof *dq[i]);
    sasnav_cfloat *e = calloc((size_t)mp, sizeof *e), *u = malloc((size_t)np * sizeof *u);
    sasnav_cfloat *up = malloc((size_t)np * sizeof *up), *um = malloc((size_t)np * sizeof *um);
    sasnav_cfloat *a = malloc((size_t)mp * sizeof *a), *b = malloc((size_t)mp * sizeof *b);
    if (!c0 || !dq[0] || !dq[1] || !dq[2] || !e || !u || !up || !um || !a || !b) return 1;
    double t_start = omp_get_wtime();
    for (int j = 0; j < m && !rc; j++) {
        int in_q = j >= mp, jj = in_q ? j - mp : j;
        sasnav_cfloat *col = c0 + (size_t)j * m;
        e[jj] = 1.0f;
        /* Column j of C0: A W A^H e_j, with e_j in p's samples or in q's. */
        rc = sasnav_op_adjoint(in_q ? op_q[0] : op_p, e, u);
        for (int n = 0; n < np; n++) u[n] *= w[n];
        if (!rc) rc = sasnav_op_forward(op_p, u, col);
        if (!rc) rc = sasnav_op_forward(op_q[0], u, col + mp);
        if (!in_q) {
            for (int i = 0; i < 3 && !rc; i++) {
                rc = sasnav_op_forward(op_q[1 + 2 * i], u, a);
                if (!rc) rc = sasnav_op_forward(op_q[2 + 2 * i], u, b);
                sasnav_cfloat *d = dq[i] + (size_t)j * mp;
                for (int r = 0; r < mp; r++) d[r] = (a[r] - b[r]) / (float)(2.0 * h[i]);
            }
        } else {
            for (int i = 0; i < 3 && !rc; i++) {
                rc = sasnav_op_adjoint(op_q[1 + 2 * i], e, up);
                if (!rc) rc = sasnav_op_adjoint(op_q[2 + 2 * i], e, um);
                for (int n = 0; n < np; n++) {
                    up[n] *= w[n];
                    um[n] *= w[n];
                }
                if (!rc) rc = sasnav_op_forward(op_q[1 + 2 * i], up, a);
                if (!rc) rc = sasnav_op_forward(op_q[2 + 2 * i], um, b);
                sasnav_cfloat *d = dq[i] + (size_t)j * mp;
                for (int r = 0; r < mp; r++) d[r] = (a[r] - b[r]) / (float)(2.0 * h[i]);
            }
        }
        e[jj] = 0.0f;
        if ((j + 1) % (m / 8) == 0)
            fprintf(stderr, "bench_crlb: %d points, %d samples: %d columns in %.0f s\n", np, m, j + 1,
                    omp_get_wtime() - t_start);
    }
    if (rc) {
        fprintf(stderr, "bench_crlb: %s\n", sasnav_last_error());
        return 1;
    }
    double power_model = 0;
    for (int j = 0; j < m; j++) power_model += crealf(c0[(size_t)j * m + j]);
    power_model /= m;

    char path[4096];
    snprintf(path, sizeof path, "%s.bin", prefix);
    FILE *f = fopen(path, "wb");
    if (!f) {
        perror(path);
        return 1;
    }
    /* Row-major, transposed from the columns as computed. */
    sasnav_cfloat *row = malloc((size_t)m * sizeof *row);
    for (int r = 0; r < m; r++) {
        for (int j = 0; j < m; j++) row[j] = c0[(size_t)j * m + r];
        fwrite(row, sizeof *row, (size_t)m, f);
    }
    for (int i = 0; i < 3; i++)
        for (int r = 0; r < mp; r++) {
            for (int j = 0; j < m; j++) row[j] = dq[i][(size_t)j * mp + r];
            fwrite(row, sizeof *row, (size_t)m, f);
        }
    if (fclose(f)) {
        perror(path);
        return 1;
    }
    snprintf(path, sizeof path, "%s.txt", prefix);
    f = fopen(path, "w");
    if (!f) {
        perror(path);
        return 1;
    }
    fprintf(f, "seed %ld\npair %d\nm %d\nn_rx %d\nsamples %d %d\npoints %d\ndx %g\ndy %g\n", seed, pair, m,
            n_rx, s_a, s_b, np, dx, dy);
    fprintf(f, "power_run %.9g\npower_window_data %.9g\npower_window_model %.9g\n", power_run, power_win,
            power_model);
    fprintf(f, "h %.9g %.9g %.9g\ntruth %.9g %.9g %.9g\nseconds %.1f\n", h[0], h[1], h[2], s0.x, s0.y,
            s0.theta, omp_get_wtime() - t_start);
    fclose(f);
    printf("seed %ld pair %d: %d samples, %d scene points; mean power in the window: model %.4g, "
           "clean data %.4g (ratio %.3f)\n",
           seed, pair, m, np, power_model, power_win, power_model / power_win);

    free(row);
    free(c0);
    for (int i = 0; i < 3; i++) free(dq[i]);
    free(e);
    free(u);
    free(up);
    free(um);
    free(a);
    free(b);
    free(px);
    free(py);
    free(w);
    sasnav_op_destroy(op_p);
    for (int k = 0; k < N_SIG; k++) sasnav_op_destroy(op_q[k]);
    sasnav_run_free(run);
    return 0;
}
