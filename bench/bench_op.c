/* Throughput of the ping operator on the paper-pair geometry (16 Rx, 10 m).
 *
 *   bench_op [tolerance [nx ny]]     (default 1e-6; 80 x 128 and 256 x 256)
 *
 * For an 80 x 128 grid and a 256 x 256 grid at 1.25 cm (or nx x ny), with 1
 * and 2 threads:
 * the time of set_geometry, forward and adjoint, and the throughput in
 * (pixel x channel) updates per second; then the peak resident memory
 * (getrusage ru_maxrss). Times are the best of 40 batches, each batch as many
 * calls as fit in ~5 ms (at least one), after ~0.05 s of warm-up calls. */
#include "sasnav/error.h"
#include "sasnav/geometry.h"
#include "sasnav/model.h"
#include "sasnav/op.h"

#include <complex.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/resource.h>
#include <time.h>

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

typedef enum { RUN_GEOMETRY, RUN_FORWARD, RUN_ADJOINT } run_kind;

typedef struct {
    sasnav_op *op;
    sasnav_ping_pose ping;
    sasnav_cfloat *image, *data;
} bench_state;

static int run_once(bench_state *b, run_kind kind)
{
    switch (kind) {
    case RUN_GEOMETRY: return sasnav_op_set_geometry(b->op, &b->ping);
    case RUN_FORWARD: return sasnav_op_forward(b->op, b->image, b->data);
    default: return sasnav_op_adjoint(b->op, b->data, b->image);
    }
}

/* Seconds per call: best of 40 batches of ~5 ms (short batches, so that on a
 * shared machine some batches run undisturbed; the best is the figure of the
 * code, not of the load). */
static double time_call(bench_state *b, run_kind kind)
{
    if (run_once(b, kind)) return NAN;
    double t = now();
    int reps = 0;
    while (now() - t < 0.05) {
        run_once(b, kind);
        reps++;
    }
    double per = (now() - t) / reps;
    int batch = (int)(0.005 / per) + 1;
    double best = INFINITY;
    for (int k = 0; k < 40; k++) {
        double t0 = now();
        for (int r = 0; r < batch; r++) run_once(b, kind);
        double dt = (now() - t0) / batch;
        if (dt < best) best = dt;
    }
    return best;
}

static int bench_grid(int nx, int ny, double pixel, double tol)
{
    sasnav_system sys;
    sasnav_system_default(&sys);
    sasnav_array array;
    sasnav_array_uniform(&array, 16, 0.05, 0.05, 0.05);
    double half_x = 0.5 * nx * pixel, half_y = 0.5 * ny * pixel;
    sasnav_window win;
    int rc = sasnav_window_for_ranges(&sys, 10.0 - half_y - 0.05,
                                      sqrt(pow(10.0 + half_y, 2) + half_x * half_x) + 0.05, 8, &win);
    if (rc) return rc;
    int np = nx * ny;
    double *x = malloc((size_t)np * sizeof *x), *y = malloc((size_t)np * sizeof *y);
    for (int j = 0; j < ny; j++)
        for (int i = 0; i < nx; i++) {
            x[j * nx + i] = (i - 0.5 * (nx - 1)) * pixel;
            y[j * nx + i] = 10.0 + (j - 0.5 * (ny - 1)) * pixel;
        }
    bench_state b;
    sasnav_ping_pose local = sasnav_epca_local(0.10, 0.0);
    sasnav_pose centroid = {0.0, 0.0, 0.0};
    b.ping = sasnav_ping_place(centroid, &local);
    size_t nd = (size_t)array.n_rx * (size_t)win.n_samples;
    b.image = malloc((size_t)np * sizeof *b.image);
    b.data = malloc(nd * sizeof *b.data);
    for (int n = 0; n < np; n++) b.image[n] = (float)((n * 7919) % 1000) / 1000.0f + 0.5f * I;
    double updates = (double)np * array.n_rx;
    printf("grid %d x %d at %.2f cm (%d pixels x %d channels, %d samples):\n", nx, ny,
           100 * pixel, np, array.n_rx, win.n_samples);
    for (int nt = 1; nt <= 2; nt++) {
        sasnav_op_opts o;
        sasnav_op_default_opts(&o);
        o.tolerance = tol;
        o.nthreads = nt;
        double t0 = now();
        rc = sasnav_op_create(&sys, &array, &win, np, x, y, &o, &b.op);
        double t_create = now() - t0;
        if (rc) return rc;
        double tg = time_call(&b, RUN_GEOMETRY);
        double tf = time_call(&b, RUN_FORWARD);
        double ta = time_call(&b, RUN_ADJOINT);
        printf("  threads %d  w %d  period %d samples  create %6.2f ms  set_geometry %7.3f ms "
               "(%5.1f M pairs/s)\n",
               nt, sasnav_op_kernel_width(b.op),
               (int)lround(sasnav_op_period(b.op) * sys.sample_rate), 1e3 * t_create, 1e3 * tg,
               1e-6 * updates / tg);
        printf("             forward %7.3f ms  %6.3f G updates/s   adjoint %7.3f ms  %6.3f G "
               "updates/s\n",
               1e3 * tf, 1e-9 * updates / tf, 1e3 * ta, 1e-9 * updates / ta);
        sasnav_op_destroy(b.op);
    }
    free(x);
    free(y);
    free(b.image);
    free(b.data);
    return 0;
}

int main(int argc, char **argv)
{
    double tol = argc > 1 ? atof(argv[1]) : 1e-6;
    if (!(tol > 0.0 && tol < 1.0)) {
        fprintf(stderr, "usage: bench_op [tolerance [nx ny]]\n");
        return 2;
    }
    int rc;
    if (argc > 3) {
        int nx = atoi(argv[2]), ny = atoi(argv[3]);
        if (nx < 1 || ny < 1 || nx > 4096 || ny > 4096) {
            fprintf(stderr, "usage: bench_op [tolerance [nx ny]]\n");
            return 2;
        }
        rc = bench_grid(nx, ny, 0.0125, tol);
    } else {
        rc = bench_grid(80, 128, 0.0125, tol);
        if (!rc) rc = bench_grid(256, 256, 0.0125, tol);
    }
    if (rc) {
        fprintf(stderr, "bench_op: %s: %s\n", sasnav_strerror(rc), sasnav_last_error());
        return 1;
    }
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    printf("peak resident memory: %.1f MB\n", ru.ru_maxrss / 1024.0);
    return 0;
}
