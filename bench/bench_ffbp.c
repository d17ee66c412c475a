/* Fast factorised backprojection against direct backprojection
 * (docs/survey.md "FFBP"), in one process on the same run and grid, back
 * to back.
 *
 * usage: bench_ffbp [--pings N] [--grid X0,X1,NX,Y0,Y1,NY] [--reps R]
 *                   [--threads T] [--oversampling S] [--points]
 *
 * The run: the "survey" preset (300 kHz, 32 channels, 25-120 m, a varied
 * seabed with rocks and man-made targets, 30 dB), N pings (default 300),
 * simulated in memory and imaged with its true poses. Default grid: the
 * preset's 20 m x 20 m patch at 2 cm (1001 x 1001). --points replaces the
 * seabed by point targets on a 4 m lattice over the grid (noise-free).
 * Direct and FFBP run alternately R times (default 1); each prints its
 * wall time and pixel x ping x channel updates per second (pings that
 * reach the grid); then the ratio of the medians, the image error of FFBP
 * against direct (dB, energy), and for every target in the grid the peak
 * pixel of each image and the ratio of their -3 dB widths along track and
 * in range. */
#include "sasnav/error.h"
#include "sasnav/image.h"
#include "sasnav/scene.h"
#include "sasnav/sim.h"

#include <complex.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double width_3db(const sasnav_grid *g, const sasnav_cfloat *img, int iy, int ix, int dir)
{
    double peak = cabsf(img[(size_t)iy * g->nx + ix]), half = peak / sqrt(2.0), w = 0;
    for (int side = -1; side <= 1; side += 2) {
        int k;
        double prev = peak, cur = peak;
        for (k = 1; k < 100; k++) {
            int jx = dir == 0 ? ix + side * k : ix, jy = dir == 1 ? iy + side * k : iy;
            if (jx < 0 || jx >= g->nx || jy < 0 || jy >= g->ny) return NAN;
            cur = cabsf(img[(size_t)jy * g->nx + jx]);
            if (cur < half) break;
            prev = cur;
        }
        w += (k - 1 + (prev - half) / (prev - cur)) * (dir == 0 ? g->dx : g->dy);
    }
    return w;
}

static void peak_near(const sasnav_grid *g, const sasnav_cfloat *img, int cx, int cy, int r, int *px, int *py)
{
    double m = -1;
    *px = cx;
    *py = cy;
    for (int iy = cy - r; iy <= cy + r; iy++)
        for (int ix = cx - r; ix <= cx + r; ix++) {
            if (ix < 0 || iy < 0 || ix >= g->nx || iy >= g->ny) continue;
            double a = cabsf(img[(size_t)iy * g->nx + ix]);
            if (a > m) m = a, *px = ix, *py = iy;
        }
}

int main(int argc, char **argv)
{
    int n_pings = 300, reps = 1, threads = 0, points = 0;
    double os = 2.0;
    sasnav_scenario sc;
    if (sasnav_scenario_preset("survey", &sc)) return 1;
    sasnav_grid g = sc.image_grid;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--pings") && i + 1 < argc) n_pings = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--reps") && i + 1 < argc) reps = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--threads") && i + 1 < argc) threads = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--oversampling") && i + 1 < argc) os = atof(argv[++i]);
        else if (!strcmp(argv[i], "--points")) points = 1;
        else if (!strcmp(argv[i], "--grid") && i + 1 < argc) {
            double x0, x1, y0, y1;
            int nx, ny;
            if (sscanf(argv[++i], "%lf,%lf,%d,%lf,%lf,%d", &x0, &x1, &nx, &y0, &y1, &ny) != 6 ||
                sasnav_grid_make(x0, x1, nx, y0, y1, ny, &g)) {
                fprintf(stderr, "bench_ffbp: bad --grid\n");
                return 2;
            }
        } else {
            fprintf(stderr, "usage: bench_ffbp [--pings N] [--grid X0,X1,NX,Y0,Y1,NY] [--reps R] "
                            "[--threads T] [--oversampling S] [--points]\n");
            return 2;
        }
    }
    if (n_pings < 2 || reps < 1) return 2;
    sc.traj.n_pings = n_pings;
    double x_end = sc.traj.x_start + (n_pings - 1) * sc.traj.ping_spacing;
    sc.ripples.x_max = x_end + 10.0;
    /* Target centres within the grid: the seabed's, or a lattice. */
    double tx[SASNAV_MAX_TARGETS], ty[SASNAV_MAX_TARGETS];
    int nt = 0;
    if (points) {
        sc.scene_kind = SASNAV_SCENE_POINTS;
        sc.snr_db = INFINITY;
        for (double y = g.y0 + 2.0; y < g.y0 + (g.ny - 1) * g.dy - 1.0 && nt < SASNAV_MAX_TARGETS; y += 4.0)
            for (double x = g.x0 + 2.0; x < g.x0 + (g.nx - 1) * g.dx - 1.0 && nt < SASNAV_MAX_TARGETS; x += 4.0) {
                sc.target_x[nt] = tx[nt] = x + 0.0037;
                sc.target_y[nt] = ty[nt] = y + 0.0051;
                sc.target_amp[nt] = 1.0;
                nt++;
            }
        sc.n_targets = nt;
    } else {
        sasnav_scene *scene = NULL;
        double ax[256], ay[256];
        int na = 0;
        if (sasnav_scene_survey(&sc.ripples, 256, ax, ay, &na, &scene)) {
            fprintf(stderr, "bench_ffbp: %s\n", sasnav_last_error());
            return 1;
        }
        sasnav_scene_free(scene);
        for (int k = 0; k < na && nt < SASNAV_MAX_TARGETS; k++)
            if (ax[k] > g.x0 + 1 && ax[k] < g.x0 + (g.nx - 1) * g.dx - 1 && ay[k] > g.y0 + 1 &&
                ay[k] < g.y0 + (g.ny - 1) * g.dy - 1)
                tx[nt] = ax[k], ty[nt++] = ay[k];
    }
    double t0 = now();
    sasnav_run *run = NULL;
    if (sasnav_simulate(&sc, NULL, NULL, &run)) {
        fprintf(stderr, "bench_ffbp: %s\n", sasnav_last_error());
        return 1;
    }
    printf("survey preset: %d pings x %d channels x %d samples, simulated in %.1f s%s\n", run->n_pings,
           run->array.n_rx, run->win.n_samples, now() - t0, points ? " (point lattice)" : "");
    printf("grid %d x %d pixels (%.3g m), x %.2f..%.2f m, y %.2f..%.2f m; %d targets inside\n", g.ny, g.nx,
           g.dx, g.x0, g.x0 + (g.nx - 1) * g.dx, g.y0, g.y0 + (g.ny - 1) * g.dy, nt);
    size_t n = (size_t)g.nx * g.ny;
    sasnav_cfloat *d = malloc(sizeof *d * n), *f = malloc(sizeof *f * n);
    if (!d || !f) return 1;
    sasnav_op_opts oo;
    sasnav_op_default_opts(&oo);
    oo.nthreads = threads;
    sasnav_ffbp_opts fo;
    sasnav_ffbp_default_opts(&fo);
    fo.oversampling = os;
    double td[64], tf[64], ratio[64];
    if (reps > 64) reps = 64;
    double updates = (double)n * run->n_pings * run->array.n_rx;
    for (int r = 0; r < reps; r++) {
        double a = now();
        if (sasnav_backproject_tile(run, run->truth, &g, 0, g.nx, 0, g.ny, &oo, d, NULL, NULL)) {
            fprintf(stderr, "bench_ffbp: direct: %s\n", sasnav_last_error());
            return 1;
        }
        double b = now();
        if (sasnav_ffbp_tile(run, run->truth, &g, 0, g.nx, 0, g.ny, &oo, &fo, f, NULL, NULL)) {
            fprintf(stderr, "bench_ffbp: FFBP: %s\n", sasnav_last_error());
            return 1;
        }
        double c = now();
        td[r] = b - a;
        tf[r] = c - b;
        ratio[r] = td[r] / tf[r];
        printf("rep %d: direct %.2f s (%.3g G updates/s), FFBP %.2f s (%.3g G equivalent updates/s), ratio %.2f\n",
               r, td[r], updates / td[r] * 1e-9, tf[r], updates / tf[r] * 1e-9, ratio[r]);
        fflush(stdout);
    }
    qsort(ratio, (size_t)reps, sizeof *ratio, cmp_double);
    qsort(td, (size_t)reps, sizeof *td, cmp_double);
    qsort(tf, (size_t)reps, sizeof *tf, cmp_double);
    double e = 0, ref = 0, peak = 0;
    for (size_t i = 0; i < n; i++) {
        sasnav_cfloat q = f[i] - d[i];
        e += crealf(q) * crealf(q) + cimagf(q) * cimagf(q);
        ref += crealf(d[i]) * crealf(d[i]) + cimagf(d[i]) * cimagf(d[i]);
        if (cabsf(d[i]) > peak) peak = cabsf(d[i]);
    }
    double emax = 0;
    for (size_t i = 0; i < n; i++)
        if (cabsf(f[i] - d[i]) > emax) emax = cabsf(f[i] - d[i]);
    printf("median: direct %.2f s, FFBP %.2f s, speed-up %.2fx (median of per-rep ratios)\n", td[reps / 2],
           tf[reps / 2], ratio[reps / 2]);
    printf("FFBP error against direct: %.1f dB (energy), largest pixel error %.1f dB of the peak\n",
           10 * log10(e / ref), 20 * log10(emax / peak));
    printf("%6s %8s %8s %12s %12s %10s %10s\n", "target", "x m", "y m", "peak direct", "peak FFBP",
           "w_x ratio", "w_y ratio");
    double worst = 0;
    for (int t = 0; t < nt; t++) {
        int cx = (int)lround((tx[t] - g.x0) / g.dx), cy = (int)lround((ty[t] - g.y0) / g.dy);
        int dx, dy, fx, fy;
        peak_near(&g, d, cx, cy, (int)ceil(0.3 / g.dx), &dx, &dy);
        peak_near(&g, f, cx, cy, (int)ceil(0.3 / g.dx), &fx, &fy);
        double rx = width_3db(&g, f, fy, fx, 0) / width_3db(&g, d, dy, dx, 0);
        double ry = width_3db(&g, f, fy, fx, 1) / width_3db(&g, d, dy, dx, 1);
        if (fabs(rx - 1) > worst) worst = fabs(rx - 1);
        if (fabs(ry - 1) > worst) worst = fabs(ry - 1);
        printf("%6d %8.2f %8.2f %5d,%-6d %5d,%-6d %10.4f %10.4f\n", t, tx[t], ty[t], dx, dy, fx, fy, rx, ry);
    }
    if (nt) printf("largest -3 dB width difference: %.2f %%\n", 100 * worst);
    free(d);
    free(f);
    sasnav_run_free(run);
    return 0;
}
