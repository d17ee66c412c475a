/* The GPU evaluation path's contract, in any build (docs/estimator.md, "GPU"):
 *
 * 1. The operator view (src/operators/op_view.h), which the GPU copies, holds
 *    everything T is made of: a slow direct evaluation of T from the view
 *    alone (spread onto the periodic fine grid, a direct DFT, the spectral
 *    weights, an inverse DFT, the window's samples; double precision) agrees
 *    with sasnav_op_forward. Tolerance 2e-5 relative: the operator runs in
 *    float (its own adjoint test holds it to ~1e-6), the reference in double.
 *    Serial numbers: unique per geometry set, 0 never, an error before any.
 * 2. The option: gpu = 1 is refused with SASNAV_ERR_UNSUPPORTED by a build
 *    without CUDA (and accepted by one with it); other values are refused.
 * 3. Builds with CUDA, where a device is present: the GPU's evaluation at
 *    each level agrees with the CPU's (zeta and eta within 1e-5 relative:
 *    float arithmetic in another order, measured 1e-7 on an H200) and its
 *    T, T^H within 1e-5 of the CPU operator's. Without a device this part
 *    says so and is not run (the CI machines have none).
 * 4. Where a device is present: an estimator's kept device contexts give a
 *    second pair the bits a fresh estimator gives it.
 * 5. Where a device is present: a whole estimate with three threads is one
 *    thread's, to the bit, counts included (the host's parts run on the
 *    threads; the GPU path evaluates one hypothesis at a time: pair.c,
 *    pair_workers). */
#include "sasnav/error.h"
#include "sasnav/estimator.h"
#include "sasnav/geometry.h"
#include "sasnav/model.h"
#include "sasnav/op.h"
#include "sasnav/sim.h"
#include "operators/op_view.h"
#ifdef SASNAV_HAVE_CUDA
#include "gpu/gpu_eval.h"
#endif
#include "testutil.h"

#include <complex.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static double rel_diff(const sasnav_cfloat *a, const double complex *ref, size_t n)
{
    double d = 0, r = 0;
    for (size_t i = 0; i < n; i++) {
        double complex e = (double complex)a[i] - ref[i];
        d += creal(e) * creal(e) + cimag(e) * cimag(e);
        r += creal(ref[i]) * creal(ref[i]) + cimag(ref[i]) * cimag(ref[i]);
    }
    return sqrt(d / r);
}

/* T rho from the view alone (op.c's steps 1-4, in double, direct DFTs). */
static void forward_from_view(const op_view *v, const sasnav_cfloat *rho, double complex *out)
{
    int lf = v->lf, mp = v->mp, kmax = v->kmax;
    double complex *fine = malloc(sizeof *fine * lf), *coarse = malloc(sizeof *coarse * mp);
    for (int l = 0; l < v->n_rx; l++) {
        for (int j = 0; j < lf; j++) fine[j] = 0;
        for (int n = 0; n < v->n_points; n++) {
            size_t q = ((size_t)(n / OP_BLOCK) * v->n_rx + l) * OP_BLOCK + n % OP_BLOCK;
            double complex c = (v->green[2 * q] + I * v->green[2 * q + 1]) * (double complex)rho[n];
            for (int j = 0; j < v->wpad; j++) fine[(v->index[q] + j) % lf] += v->taps[q * v->wpad + j] * c;
        }
        for (int m = 0; m < mp; m++) coarse[m] = 0;
        for (int k = -kmax; k <= kmax; k++) { /* X_k = w_k FFT_Lf(fine)[k] */
            double complex f = 0;
            for (int j = 0; j < lf; j++) f += fine[j] * cexp(-2 * I * M_PI * (double)k * j / lf);
            coarse[k < 0 ? k + mp : k] = v->spectral[k + kmax] * f;
        }
        for (int m = 0; m < v->n_samples; m++) { /* unnormalised inverse DFT */
            double complex s = 0;
            int mm = m + v->pad;
            for (int k = -kmax; k <= kmax; k++)
                s += coarse[k < 0 ? k + mp : k] * cexp(2 * I * M_PI * (double)k * mm / mp);
            out[(size_t)l * v->n_samples + m] = s;
        }
    }
    free(fine);
    free(coarse);
}

static void test_view(void)
{
    sasnav_system sys;
    sasnav_system_default(&sys);
    sasnav_array array;
    sasnav_array_uniform(&array, 16, 0.05, 0.05, 0.05);
    int nx = 21, ny = 25, np = nx * ny;
    double pixel = 0.0125;
    sasnav_window win;
    CHECK_OK(sasnav_window_for_ranges(&sys, 9.8, 10.3, 8, &win));
    double *x = malloc(sizeof(double) * np), *y = malloc(sizeof(double) * np);
    for (int j = 0; j < ny; j++)
        for (int i = 0; i < nx; i++) {
            x[j * nx + i] = (i - 0.5 * (nx - 1)) * pixel;
            y[j * nx + i] = 10.0 + (j - 0.5 * (ny - 1)) * pixel;
        }
    sasnav_op_opts o;
    sasnav_op_default_opts(&o);
    o.tolerance = 1e-3; /* the estimator's */
    o.nthreads = 1;
    sasnav_op *a = NULL, *b = NULL;
    CHECK_OK(sasnav_op_create(&sys, &array, &win, np, x, y, &o, &a));
    CHECK_OK(sasnav_op_create(&sys, &array, &win, np, x, y, &o, &b));
    free(x);
    free(y);
    if (!a || !b) return;
    op_view va, vb;
    CHECK(op_view_get(a, &va) == SASNAV_ERR_ARG, "a view before any geometry is an error");
    sasnav_ping_pose local = sasnav_epca_local(0.10, 0.0);
    sasnav_ping_pose ping = sasnav_ping_place((sasnav_pose){0.01, -0.003, 0.02}, &local);
    CHECK_OK(sasnav_op_set_geometry(a, &ping));
    CHECK_OK(sasnav_op_set_geometry(b, &ping));
    CHECK_OK(op_view_get(a, &va));
    CHECK_OK(op_view_get(b, &vb));
    unsigned long first = va.serial;
    CHECK(va.serial != 0 && vb.serial != 0 && va.serial != vb.serial, "serials %lu, %lu", va.serial,
          vb.serial);
    CHECK_OK(sasnav_op_set_geometry(a, &ping));
    CHECK_OK(op_view_get(a, &va));
    CHECK(va.serial != first && va.serial != vb.serial, "a new geometry has a new serial (%lu)", va.serial);
    CHECK(va.n_points == np && va.n_rx == 16 && va.n_samples == win.n_samples &&
              va.n_pairs == (size_t)va.n_blocks * OP_BLOCK * 16,
          "view sizes %d %d %d %zu", va.n_points, va.n_rx, va.n_samples, va.n_pairs);
    size_t nd = (size_t)va.n_rx * va.n_samples;
    sasnav_cfloat *rho = malloc(sizeof *rho * np), *data = malloc(sizeof *data * nd);
    double complex *ref = malloc(sizeof *ref * nd);
    for (int n = 0; n < np; n++) rho[n] = (float)sin(0.37 * n) + I * (float)cos(0.11 * n * n);
    CHECK_OK(sasnav_op_forward(a, rho, data));
    forward_from_view(&va, rho, ref);
    double d = rel_diff(data, ref, nd);
    CHECK(d < 2e-5, "T from the view against sasnav_op_forward: relative difference %.2e", d);
    printf("view: T from the view alone against sasnav_op_forward: %.2e relative\n", d);

#ifdef SASNAV_HAVE_CUDA
    gpu_ctx *g = NULL;
    int rc = gpu_create(&va, &g);
    if (rc == SASNAV_ERR_UNSUPPORTED) {
        printf("GPU checks not run: %s\n", sasnav_last_error());
    } else {
        CHECK_OK(rc);
        CHECK_OK(gpu_set_op(g, 0, &va));
        sasnav_cfloat *gd = malloc(sizeof *gd * nd), *gr = malloc(sizeof *gr * np), *cr = malloc(sizeof *cr * np);
        CHECK_OK(gpu_apply(g, 0, 0, (const float *)rho, (float *)gd));
        d = rel_diff(gd, ref, nd);
        CHECK(d < 1e-5, "GPU T against the reference: %.2e", d);
        CHECK_OK(sasnav_op_adjoint(a, data, cr));
        CHECK_OK(gpu_apply(g, 0, 1, (const float *)data, (float *)gr));
        double complex *crd = malloc(sizeof *crd * np);
        for (int n = 0; n < np; n++) crd[n] = cr[n];
        d = rel_diff(gr, crd, (size_t)np);
        CHECK(d < 1e-5, "GPU T^H against the CPU's: %.2e", d);
        /* the pairs computed on the device from the channel geometry */
        op_geometry_consts gc;
        op_channel_geometry ch[SASNAV_MAX_RX];
        CHECK_OK(op_geometry_consts_get(a, &gc));
        CHECK_OK(op_channel_geometry_get(a, &ping, 0, ch));
        CHECK_OK(gpu_set_points(g, &gc));
        CHECK_OK(gpu_place(g, 1, ch));
        CHECK_OK(gpu_apply(g, 1, 0, (const float *)rho, (float *)gd));
        d = rel_diff(gd, ref, nd);
        CHECK(d < 1e-5, "GPU T placed on the device against the reference: %.2e", d);
        CHECK_OK(gpu_apply(g, 1, 1, (const float *)data, (float *)gr));
        d = rel_diff(gr, crd, (size_t)np);
        CHECK(d < 1e-5, "GPU T^H placed on the device against the CPU's: %.2e", d);
        printf("GPU: T, T^H (copied and placed on the device) within 1e-5 of the CPU's\n");
        free(crd);
        free(gd);
        free(gr);
        free(cr);
        gpu_destroy(g);
    }
#endif
    free(rho);
    free(data);
    free(ref);
    sasnav_op_destroy(a);
    sasnav_op_destroy(b);
}

static void test_option(void)
{
    sasnav_pair_opts po;
    sasnav_pair_default_opts(&po);
    CHECK(po.gpu == 0, "the CPU by default");
    po.gpu = 2;
    CHECK(sasnav_pair_opts_check(&po) == SASNAV_ERR_ARG, "gpu = 2 is refused");
    po.gpu = 1;
    int rc = sasnav_pair_opts_check(&po);
#ifdef SASNAV_HAVE_CUDA
    CHECK(rc == SASNAV_OK, "a CUDA build accepts gpu = 1 (%d)", rc);
#else
    CHECK(rc == SASNAV_ERR_UNSUPPORTED && strstr(sasnav_last_error(), "SASNAV_CUDA"),
          "a build without CUDA refuses gpu = 1 and says how to get it (%d: %s)", rc, sasnav_last_error());
#endif
}

#ifdef SASNAV_HAVE_CUDA
/* A run of the preset (n_pings of it, 0: all; its scenario in sc) and the
 * estimator options for it (one thread, the CPU). */
static sasnav_run *simulate_preset(const char *name, int n_pings, sasnav_scenario *sc,
                                   sasnav_pair_opts *po)
{
    sasnav_run *run = NULL;
    CHECK_OK(sasnav_scenario_preset(name, sc));
    if (n_pings > 0) sc->traj.n_pings = n_pings;
    CHECK_OK(sasnav_simulate(sc, NULL, NULL, &run));
    sasnav_pair_default_opts(po);
    po->range = sc->range_of_interest;
    po->tx_lag = sc->traj.tx_lag;
    po->nthreads = 1;
    return run;
}

/* The evaluations of a GPU estimator against a CPU one on the paper pair. */
static void test_evaluations(void)
{
    if (gpu_check_device() == SASNAV_ERR_UNSUPPORTED) {
        printf("GPU evaluations not run: %s\n", sasnav_last_error());
        return;
    }
    sasnav_scenario sc;
    sasnav_pair_opts po;
    sasnav_run *run = simulate_preset("paper-pair", 0, &sc, &po);
    if (!run) return;
    sasnav_pose nominal = sasnav_ping_displacement(&run->nav[0], &run->nav[1]);
    sasnav_pair *cpu = NULL, *gpu = NULL;
    CHECK_OK(sasnav_pair_create(&run->sys, &run->array, &run->win, &po, &cpu));
    po.gpu = 1;
    CHECK_OK(sasnav_pair_create(&run->sys, &run->array, &run->win, &po, &gpu));
    CHECK_OK(sasnav_pair_set_data(cpu, sasnav_run_ping(run, 0), sasnav_run_ping(run, 1), nominal));
    CHECK_OK(sasnav_pair_set_data(gpu, sasnav_run_ping(run, 0), sasnav_run_ping(run, 1), nominal));
    sasnav_pose t = sc.traj.pair_error, off = {t.x + 2e-3, t.y - 1e-3, t.theta + 1e-3};
    /* q's pairs copied from the CPU operator (geom 0), then computed on the
     * device (1); the hypotheses differ between the two (a repeated one
     * would come from the estimator's record of its last evaluations) */
    for (int geom = 0; geom < 2; geom++) {
        gpu_use_device_geometry(geom);
        for (int level = 0; level < 3; level++)
            for (int h = 0; h < 2; h++) {
                sasnav_pose e = h ? off : t;
                e.x += 1e-4 * geom;
                double zc, ec, zg, eg;
                CHECK_OK(sasnav_pair_eval(cpu, e, level, 0, &zc, &ec, NULL));
                CHECK_OK(sasnav_pair_eval(gpu, e, level, 0, &zg, &eg, NULL));
                CHECK(fabs(zg / zc - 1) < 1e-5 && fabs(eg / ec - 1) < 1e-5,
                      "level %d, device geometry %d: zeta %.8f / %.8f, eta %.8f / %.8f (GPU / CPU)",
                      level, geom, zg, zc, eg, ec);
            }
    }
    gpu_use_device_geometry(1);
    sasnav_pair_destroy(cpu);
    sasnav_pair_destroy(gpu);
    sasnav_run_free(run);
}
#endif

#ifdef SASNAV_HAVE_CUDA
/* An estimator's device contexts are kept from one pair to the next (and
 * levels 1 and 2 keep a graph each): after a first pair, the evaluations of
 * a second pair must be those of a fresh estimator given only that pair, to
 * the bit (the same kernels on the same data; a stale point set, geometry
 * or graph would change them by far more), and within 1e-5 of the CPU's. */
static void test_context_reuse(void)
{
    if (gpu_check_device() == SASNAV_ERR_UNSUPPORTED) return;
    sasnav_scenario sc;
    sasnav_pair_opts po;
    sasnav_run *run = simulate_preset("paper-trajectory", 3, &sc, &po);
    if (!run) return;
    sasnav_pair *est[3] = {NULL, NULL, NULL}; /* reused, fresh, CPU */
    CHECK_OK(sasnav_pair_create(&run->sys, &run->array, &run->win, &po, &est[2]));
    po.gpu = 1;
    for (int e = 0; e < 2; e++) CHECK_OK(sasnav_pair_create(&run->sys, &run->array, &run->win, &po, &est[e]));
    if (!est[0] || !est[1] || !est[2]) goto done;
    sasnav_pose n01 = sasnav_ping_displacement(&run->nav[0], &run->nav[1]);
    sasnav_pose n12 = sasnav_ping_displacement(&run->nav[1], &run->nav[2]);
    CHECK_OK(sasnav_pair_set_data(est[0], sasnav_run_ping(run, 0), sasnav_run_ping(run, 1), n01));
    for (int level = 0; level < 3; level++) {
        double z, eta;
        CHECK_OK(sasnav_pair_eval(est[0], (sasnav_pose){1e-3, 0, 0}, level, 0, &z, &eta, NULL));
    }
    for (int e = 0; e < 3; e++)
        CHECK_OK(sasnav_pair_set_data(est[e], sasnav_run_ping(run, 1), sasnav_run_ping(run, 2), n12));
    /* levels 1 and 2 alternate (they share a context: two graphs) */
    const int levels[7] = {0, 1, 2, 1, 2, 1, 0};
    int same = 1;
    for (int h = 0; h < 7; h++) {
        sasnav_pose t = {1e-3 * (h - 3), 2e-4 * h, 1e-3 * (h % 3)};
        double z[3], eta[3];
        for (int e = 0; e < 3; e++) CHECK_OK(sasnav_pair_eval(est[e], t, levels[h], 0, &z[e], &eta[e], NULL));
        same &= z[0] == z[1] && eta[0] == eta[1];
        CHECK(z[0] == z[1] && eta[0] == eta[1],
              "level %d after another pair: zeta %.9g / %.9g, eta %.9g / %.9g (kept context / fresh)",
              levels[h], z[0], z[1], eta[0], eta[1]);
        CHECK(fabs(z[0] / z[2] - 1) < 1e-5 && fabs(eta[0] / eta[2] - 1) < 1e-5,
              "level %d after another pair: zeta %.8f / %.8f, eta %.8f / %.8f (GPU / CPU)", levels[h], z[0],
              z[2], eta[0], eta[2]);
    }
    if (same) printf("GPU: a second pair on kept contexts gives a fresh estimator's bits\n");
done:
    for (int e = 0; e < 3; e++) sasnav_pair_destroy(est[e]);
    sasnav_run_free(run);
}
#endif

#ifdef SASNAV_HAVE_CUDA
static void test_workers(void)
{
    if (gpu_check_device() == SASNAV_ERR_UNSUPPORTED) return;
    sasnav_scenario sc;
    sasnav_pair_opts po;
    sasnav_run *run = simulate_preset("paper-pair", 0, &sc, &po);
    if (!run) return;
    sasnav_pose nominal = sasnav_ping_displacement(&run->nav[0], &run->nav[1]);
    po.gpu = 1;
    sasnav_pair_result r[2];
    int ok = 1;
    for (int e = 0; e < 2; e++) {
        sasnav_pair *est = NULL;
        po.nthreads = e == 0 ? 1 : 3;
        CHECK_OK(sasnav_pair_create(&run->sys, &run->array, &run->win, &po, &est));
        if (est) CHECK_OK(sasnav_pair_set_data(est, sasnav_run_ping(run, 0), sasnav_run_ping(run, 1), nominal));
        if (est) CHECK_OK(sasnav_pair_estimate(est, &r[e]));
        ok &= est != NULL;
        sasnav_pair_destroy(est);
    }
    if (ok) {
        CHECK(r[0].error.x == r[1].error.x && r[0].error.y == r[1].error.y &&
                  r[0].error.theta == r[1].error.theta && r[0].eta == r[1].eta && r[0].zeta == r[1].zeta,
              "GPU estimate, 1 / 3 threads: surge %.9g / %.9g, sway %.9g / %.9g, yaw %.9g / %.9g, eta "
              "%.9g / %.9g",
              r[0].error.x, r[1].error.x, r[0].error.y, r[1].error.y, r[0].error.theta, r[1].error.theta,
              r[0].eta, r[1].eta);
        CHECK(r[0].evaluations == r[1].evaluations && r[0].applications == r[1].applications,
              "GPU estimate, 1 / 3 threads: %d / %d evaluations, %ld / %ld applications", r[0].evaluations,
              r[1].evaluations, r[0].applications, r[1].applications);
        printf("GPU: estimate with 1 / 3 threads: %.3f / %.3f s, surge error %+.4f mm\n", r[0].seconds,
               r[1].seconds, 1e3 * (r[0].error.x - sc.traj.pair_error.x));
    }
    sasnav_run_free(run);
}
#endif

int main(void)
{
    test_view();
    test_option();
#ifdef SASNAV_HAVE_CUDA
    test_evaluations();
    test_context_reuse();
    test_workers();
#endif
    return test_summary("test_gpu");
}
