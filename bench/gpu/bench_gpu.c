/* The GPU evaluation path against the CPU (builds with -DSASNAV_CUDA=ON).
 *
 *   bench_gpu [--draws N] [--threads T] [--evals M] [--no-estimates]
 *             [--concurrent N1,N2,...] [--replay N1,N2,...]
 *
 * On paper-pair (30 dB; the paper's case, then N seeded draws of bench_pair's
 * distribution, seed 2026):
 *  1. the operator: T, T^H and 8 CGLS iterations on the GPU against the CPU
 *     (sasnav_op, sasnav_cgls) on the estimator's 129 x 129 grid, seeded
 *     random input: relative differences ||gpu - cpu|| / ||cpu||;
 *  2. one evaluation (sasnav_pair_eval) at each level, CPU and GPU, at the
 *     truth and off it: zeta and eta of both; the wall time of level-1 and
 *     level-2 evaluations (median of M, distinct hypotheses), the GPU with
 *     q's pairs copied from the CPU operator (every step launched, or the
 *     evaluation replayed as one CUDA graph) and computed on the device;
 *  3. whole estimates (sasnav_pair_estimate), CPU (T threads), GPU with the
 *     pairs copied (GPc) and with device geometry (GPd, the default):
 *     estimate, error against the truth, evaluations, applications, wall
 *     time per stage; the ratios of the wall times.
 * --concurrent: instead of 3, Ni GPU estimators on the paper pair (one
 * host thread and one OpenMP thread each) evaluate M distinct hypotheses
 * each at the same time, levels 1 and 2: evaluations per second against
 * the number of estimators, which tells whether the device or the host
 * side limits a navigate's pairs per second. --replay: the same with Ni
 * bare device contexts (both operators at one geometry) replaying the
 * level-2 evaluation (gpu_eval: its host copies and graph launch, without
 * a hypothesis's placement or the host's zeta and eta), with pageable and
 * with pinned host buffers of its own (since gpu_eval stages its transfers
 * through pinned buffers, the two differ by one host copy; the comparison
 * of docs/estimator.md, "Pinned transfers", ran before that).
 * The CPU figures are of the machine this runs on. */
#include "sasnav/error.h"
#include "sasnav/estimator.h"
#include "sasnav/geometry.h"
#include "sasnav/op.h"
#include "sasnav/sim.h"

#include "gpu/gpu_eval.h"

#include <complex.h>
#include <cuda_runtime_api.h>
#include <math.h>
#include <omp.h>
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

static double rel_diff(const sasnav_cfloat *a, const sasnav_cfloat *ref, size_t n)
{
    double d = 0, r = 0;
    for (size_t i = 0; i < n; i++) {
        double complex e = (double complex)a[i] - (double complex)ref[i];
        d += creal(e) * creal(e) + cimag(e) * cimag(e);
        r += crealf(ref[i]) * crealf(ref[i]) + cimagf(ref[i]) * cimagf(ref[i]);
        if (!isfinite(crealf(a[i])) || !isfinite(cimagf(a[i]))) return INFINITY;
    }
    return r > 0 ? sqrt(d / r) : sqrt(d);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* An operator on the estimator's 129 x 129 grid (1.25 cm pixels about 10 m
 * range) of the paper pair's system, NUFFT tolerance tol, with a ping
 * placed off the origin. */
static int grid_op(const sasnav_run *run, double tol, sasnav_op **out)
{
    int nx = 129, ny = 129, np = nx * ny;
    double pixel = 0.0125;
    double *x = malloc(sizeof(double) * np), *y = malloc(sizeof(double) * np);
    if (!x || !y) {
        free(x);
        free(y);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory for the grid");
    }
    for (int j = 0; j < ny; j++)
        for (int i = 0; i < nx; i++) {
            x[j * nx + i] = (i - 0.5 * (nx - 1)) * pixel;
            y[j * nx + i] = 10.0 + (j - 0.5 * (ny - 1)) * pixel;
        }
    sasnav_op_opts o;
    sasnav_op_default_opts(&o);
    o.tolerance = tol;
    int rc = sasnav_op_create(&run->sys, &run->array, &run->win, np, x, y, &o, out);
    free(x);
    free(y);
    if (rc) return rc;
    sasnav_ping_pose local = sasnav_epca_local(0.10, 0.0);
    sasnav_ping_pose ping = sasnav_ping_place((sasnav_pose){0.004, -0.002, 0.01}, &local);
    rc = sasnav_op_set_geometry(*out, &ping);
    if (rc) {
        sasnav_op_destroy(*out);
        *out = NULL;
    }
    return rc;
}

/* 1. The operator and CGLS on the paper pair's system. */
static int check_operator(const sasnav_run *run, double tol)
{
    sasnav_op *op = NULL;
    int rc = grid_op(run, tol, &op);
    if (rc) return rc;
    op_view v;
    rc = op_view_get(op, &v);
    int np = rc ? 0 : v.n_points;
    gpu_ctx *g = NULL;
    if (!rc) rc = gpu_create(&v, &g);
    if (!rc) rc = gpu_set_op(g, 0, &v);
    if (rc) {
        sasnav_op_destroy(op);
        return rc;
    }
    size_t nd = (size_t)run->array.n_rx * run->win.n_samples;
    sasnav_cfloat *img = malloc(sizeof *img * np), *img2 = malloc(sizeof *img2 * np);
    sasnav_cfloat *dat = malloc(sizeof *dat * nd), *dat2 = malloc(sizeof *dat2 * nd);
    unsigned long s = 12345;
    for (int n = 0; n < np; n++) {
        s = s * 6364136223846793005UL + 1442695040888963407UL;
        float a = (float)((s >> 33) % 20001) / 10000.0f - 1.0f;
        s = s * 6364136223846793005UL + 1442695040888963407UL;
        float b = (float)((s >> 33) % 20001) / 10000.0f - 1.0f;
        img[n] = a + b * I;
    }
    rc = sasnav_op_forward(op, img, dat);
    if (!rc) rc = gpu_apply(g, 0, 0, (const float *)img, (float *)dat2);
    if (!rc) printf("operator  T     relative difference GPU - CPU %.2e\n", rel_diff(dat2, dat, nd));
    if (!rc) rc = sasnav_op_adjoint(op, dat, img2);
    if (!rc) rc = gpu_apply(g, 0, 1, (const float *)dat, (float *)img);
    if (!rc) printf("operator  T^H   relative difference GPU - CPU %.2e\n", rel_diff(img, img2, (size_t)np));
    sasnav_cgls_opts co = {8, 0.0};
    if (!rc) rc = sasnav_cgls(op, dat, &co, img2, NULL);
    if (!rc) rc = gpu_cgls(g, 0, (const float *)dat, 8, 0.0, (float *)img);
    if (!rc) printf("CGLS k = 8      relative difference GPU - CPU %.2e\n", rel_diff(img, img2, (size_t)np));
    if (!rc) {
        /* timing of single applications (host copies included) */
        double t0 = now();
        int reps = 200;
        for (int r = 0; r < reps && !rc; r++) rc = gpu_apply(g, 0, 0, (const float *)img, (float *)dat2);
        double tg = (now() - t0) / reps;
        t0 = now();
        for (int r = 0; r < reps && !rc; r++) rc = sasnav_op_forward(op, img, dat);
        double tc = (now() - t0) / reps;
        if (!rc) printf("forward with host copies: GPU %.3f ms, CPU %.3f ms (the operator's default threads)\n",
                        1e3 * tg, 1e3 * tc);
        if (!rc) printf("device: %s\n", gpu_name(g));
    }
    free(img);
    free(img2);
    free(dat);
    free(dat2);
    gpu_destroy(g);
    sasnav_op_destroy(op);
    return rc;
}

typedef struct {
    sasnav_pair *cpu, *gpu;
} pair2;

static int make_pairs(const sasnav_run *run, const sasnav_pair_opts *po, pair2 *pp)
{
    sasnav_pose nominal = sasnav_ping_displacement(&run->nav[0], &run->nav[1]);
    sasnav_pair_opts o = *po;
    memset(pp, 0, sizeof *pp);
    for (int k = 0; k < 2; k++) {
        o.gpu = k;
        sasnav_pair **p = k ? &pp->gpu : &pp->cpu;
        int rc = sasnav_pair_create(&run->sys, &run->array, &run->win, &o, p);
        if (!rc) rc = sasnav_pair_set_data(*p, sasnav_run_ping(run, 0), sasnav_run_ping(run, 1), nominal);
        if (rc) return rc;
    }
    return SASNAV_OK;
}

/* 2. Evaluations at each level, CPU against GPU. */
static int check_evals(const sasnav_run *run, const sasnav_pair_opts *po, sasnav_pose truth, int m)
{
    pair2 pp;
    int rc = make_pairs(run, po, &pp);
    sasnav_pose off = {truth.x + 2e-3, truth.y - 1e-3, truth.theta + 1e-3};
    for (int level = 0; level < 3 && !rc; level++)
        for (int h = 0; h < 2 && !rc; h++) {
            sasnav_pose e = h ? off : truth;
            double zc, ec, zg, eg, oc, og;
            rc = sasnav_pair_eval(pp.cpu, e, level, 0, &zc, &ec, &oc);
            if (!rc) rc = sasnav_pair_eval(pp.gpu, e, level, 0, &zg, &eg, &og);
            if (!rc)
                printf("level %d %-6s zeta CPU %.6f GPU %.6f (%+.1e)  eta CPU %.6f GPU %.6f (%+.1e)\n", level,
                       h ? "off" : "truth", zc, zg, zg / zc - 1, ec, eg, eg / ec - 1);
        }
    sasnav_pair_destroy(pp.gpu);
    pp.gpu = NULL;
    /* Evaluations at distinct hypotheses, levels 1 and 2: the GPU in three
     * ways (q's pairs copied from the CPU and every step launched; copied,
     * the evaluation replayed as one graph; computed on the device, one
     * graph), and the CPU. */
    static const char *mode_name[3] = {"copied, step by step", "copied, one graph", "device geometry, one graph"};
    double *tc = malloc(sizeof(double) * m), *tg = malloc(sizeof(double) * m);
    double med[2][3] = {{0}}, medc[2] = {0, 0};
    for (int mode = 0; mode < 3 && !rc; mode++) {
        gpu_use_graphs(mode > 0);
        gpu_use_device_geometry(mode == 2);
        sasnav_pose nominal = sasnav_ping_displacement(&run->nav[0], &run->nav[1]);
        sasnav_pair_opts o = *po;
        o.gpu = 1;
        rc = sasnav_pair_create(&run->sys, &run->array, &run->win, &o, &pp.gpu);
        if (!rc) rc = sasnav_pair_set_data(pp.gpu, sasnav_run_ping(run, 0), sasnav_run_ping(run, 1), nominal);
        for (int level = 1; level <= 2 && !rc; level++) {
            for (int j = 0; j < m && !rc; j++) {
                sasnav_pose e = {truth.x + 1e-4 * (j + 1) + 1e-2 * level, truth.y, truth.theta};
                double z, et, ov, t0 = now();
                rc = sasnav_pair_eval(pp.gpu, e, level, 0, &z, &et, &ov);
                tg[j] = now() - t0;
                if (rc || mode) continue;
                if (j < 3) { /* the CPU's evaluations take long: three */
                    t0 = now();
                    rc = sasnav_pair_eval(pp.cpu, e, level, 0, &z, &et, &ov);
                    tc[j] = now() - t0;
                }
            }
            if (rc) break;
            qsort(tg, (size_t)m, sizeof(double), cmp_double);
            med[level - 1][mode] = tg[m / 2];
            if (mode == 0) {
                int nc = m < 3 ? m : 3;
                qsort(tc, (size_t)nc, sizeof(double), cmp_double);
                medc[level - 1] = tc[nc / 2];
            }
            printf("level-%d evaluation, GPU (%s): median %.2f ms (min %.2f, %d)\n", level, mode_name[mode],
                   1e3 * tg[m / 2], 1e3 * tg[0], m);
        }
        sasnav_pair_destroy(pp.gpu);
        pp.gpu = NULL;
    }
    gpu_use_graphs(1);
    gpu_use_device_geometry(1);
    for (int level = 1; level <= 2 && !rc; level++)
        printf("level-%d evaluation, CPU (%d threads): median %.2f ms (3); CPU / GPU: %.1f, %.1f, %.1f\n",
               level, po->nthreads, 1e3 * medc[level - 1], medc[level - 1] / med[level - 1][0],
               medc[level - 1] / med[level - 1][1], medc[level - 1] / med[level - 1][2]);
    free(tc);
    free(tg);
    sasnav_pair_destroy(pp.cpu);
    return rc;
}

/* 3. Whole estimates. */
static int estimate_both(const sasnav_run *run, const sasnav_pair_opts *po, sasnav_pose truth, int idx,
                         double *ratio /* 3 */)
{
    pair2 pp;
    int rc = make_pairs(run, po, &pp);
    /* CPU; GPU with q's pairs copied; GPU with device geometry (a second
     * estimator: the first one's contexts stay as they were made) */
    sasnav_pair *gpu2 = NULL;
    if (!rc) {
        sasnav_pair_opts o = *po;
        o.gpu = 1;
        sasnav_pose nominal = sasnav_ping_displacement(&run->nav[0], &run->nav[1]);
        rc = sasnav_pair_create(&run->sys, &run->array, &run->win, &o, &gpu2);
        if (!rc) rc = sasnav_pair_set_data(gpu2, sasnav_run_ping(run, 0), sasnav_run_ping(run, 1), nominal);
    }
    for (int k = 0; k < 3 && !rc; k++) {
        sasnav_pair_result r;
        gpu_use_device_geometry(k == 2);
        double t0 = now();
        rc = sasnav_pair_estimate(k == 0 ? pp.cpu : k == 1 ? pp.gpu : gpu2, &r);
        double t = now() - t0;
        if (rc) break;
        ratio[k] = t;
        double es = r.error.x - truth.x, ew = r.error.y - truth.y, ey = r.error.theta - truth.theta;
        int ok = fabs(es) <= 5e-4 && fabs(ew) <= 2e-4 && fabs(ey) <= 5e-4 && r.status == SASNAV_OK;
        printf("%3d %s final %+9.4f %+9.5f mm %+.6f | err %+7.3f %+8.4f mm %+.1e | %4d ev %6ld app | %6.3f s"
               " (global %.3f, zeta %.3f, eta %.3f, final %.3f s) %s\n",
               idx, k == 0 ? "CPU" : k == 1 ? "GPc" : "GPd", 1e3 * r.error.x, 1e3 * r.error.y, r.error.theta, 1e3 * es, 1e3 * ew, ey,
               r.evaluations, r.applications, t, r.seconds_global, r.seconds_zeta, r.seconds_eta,
               r.seconds_final, ok ? "ok" : "FAIL");
    }
    gpu_use_device_geometry(1);
    if (!rc)
        printf("    wall-time ratio CPU / GPU: %.1f (GPc: pairs copied), %.1f (GPd: device geometry)\n",
               ratio[0] / ratio[1], ratio[0] / ratio[2]);
    fflush(stdout);
    sasnav_pair_destroy(pp.cpu);
    sasnav_pair_destroy(pp.gpu);
    sasnav_pair_destroy(gpu2);
    return rc;
}

/* The next number of a comma-separated list ("1,8,16"), the list moved on
 * past it; 0 at its end. */
static int next_count(const char **c)
{
    if (!**c) return 0;
    int n = atoi(*c);
    while (**c && **c != ',') (*c)++;
    if (**c == ',') (*c)++;
    return n ? n : -1; /* -1: a 0 or a bad entry, skipped */
}

/* --concurrent: n GPU estimators evaluating at once. */
static int concurrency(const sasnav_run *run, const sasnav_pair_opts *po, sasnav_pose truth, const char *list,
                       int m)
{
    int rc = SASNAV_OK;
    char message[256] = "";
    const char *c = list;
    for (int n; !rc && (n = next_count(&c)) != 0;) {
        if (n < 1 || n > 64) continue;
        sasnav_pair **pp = calloc((size_t)n, sizeof *pp);
        if (!pp) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
        sasnav_pair_opts o = *po;
        o.gpu = 1;
        o.nthreads = 1;
        sasnav_pose nominal = sasnav_ping_displacement(&run->nav[0], &run->nav[1]);
        for (int k = 0; k < n && !rc; k++) {
            rc = sasnav_pair_create(&run->sys, &run->array, &run->win, &o, &pp[k]);
            if (!rc) rc = sasnav_pair_set_data(pp[k], sasnav_run_ping(run, 0), sasnav_run_ping(run, 1), nominal);
        }
        for (int level = 1; level <= 2 && !rc; level++) {
            int fail = 0;
            double t = 0;
            for (int rep = 0; rep < 2 && !fail; rep++) { /* rep 0: warm-up (graph captures) */
                int mm = rep ? m : 1;
                double t0 = now();
#pragma omp parallel for num_threads(n) schedule(static, 1) reduction(| : fail)
                for (int k = 0; k < n; k++)
                    for (int j = 0; j < mm; j++) {
                        sasnav_pose e = {truth.x + 1e-4 * (j + 1) + 1e-5 * k, truth.y, truth.theta};
                        double z, et, ov;
                        if (sasnav_pair_eval(pp[k], e, level, 0, &z, &et, &ov) != SASNAV_OK) {
                            fail = 1;
#pragma omp critical(bench_gpu_message)
                            snprintf(message, sizeof message, "%s", sasnav_last_error());
                        }
                    }
                t = now() - t0;
            }
            if (fail) {
                rc = sasnav_set_error(SASNAV_ERR_INTERNAL, "an evaluation failed: %s", message);
                break;
            }
            printf("concurrent %2d estimators, level %d: %7.1f evaluations/s, %.2f ms per evaluation each\n", n,
                   level, n * m / t, 1e3 * t / m);
            fflush(stdout);
        }
        for (int k = 0; k < n; k++) sasnav_pair_destroy(pp[k]);
        free(pp);
    }
    return rc;
}

/* --replay: n contexts replaying gpu_eval at level 2 (k = i = 8). */
static int replay(const sasnav_run *run, const char *list, int m, int pinned)
{
    char message[256] = "";
    sasnav_op *op = NULL;
    sasnav_op_opts d; /* the operator's default tolerance */
    sasnav_op_default_opts(&d);
    int rc = grid_op(run, d.tolerance, &op);
    if (rc) return rc;
    op_view v;
    rc = op_view_get(op, &v);
    int np = rc ? 0 : v.n_points;
    size_t nd = (size_t)run->array.n_rx * run->win.n_samples;
    const char *c = list;
    for (int n; !rc && (n = next_count(&c)) != 0;) {
        if (n < 1 || n > 64) continue;
        gpu_ctx **g = calloc((size_t)n, sizeof *g);
        if (!g) {
            rc = sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
            break;
        }
        size_t nb = (size_t)n * (2 * nd + 4 * (size_t)np);
        float *buf = NULL;
        if (pinned) {
            if (cudaMallocHost((void **)&buf, nb * sizeof(float)) != cudaSuccess) buf = NULL;
        } else {
            buf = malloc(nb * sizeof(float));
        }
        if (!buf) rc = sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory for the replay's host buffers");
        for (int k = 0; k < n && !rc; k++) {
            rc = gpu_create(&v, &g[k]);
            if (!rc) rc = gpu_set_op(g[k], 0, &v);
            if (!rc) rc = gpu_set_op(g[k], 1, &v);
        }
        for (size_t e = 0; e < nb && buf; e++)
            buf[e] = (float)((e * 7919) % 1000) * 1e-3f; /* data and rho_p: any non-zero values */
        int fail = 0;
        double t = 0;
        for (int rep = 0; rep < 2 && !rc && !fail; rep++) {
            int mm = rep ? m : 1;
            double t0 = now();
#pragma omp parallel for num_threads(n) schedule(static, 1) reduction(| : fail)
            for (int k = 0; k < n; k++) {
                float *b = buf + (size_t)k * (2 * nd + 4 * (size_t)np);
                float *out = b + 2 * nd + 2 * (size_t)np; /* rho_q, psi_p, psi_q: one buffer */
                for (int j = 0; j < mm; j++)
                    if (gpu_eval(g[k], b, b + 2 * nd, 8, 8, 0.0, out, out, out) != SASNAV_OK) {
                        fail = 1;
#pragma omp critical(bench_gpu_message)
                        snprintf(message, sizeof message, "%s", sasnav_last_error());
                    }
            }
            t = now() - t0;
        }
        if (fail) rc = sasnav_set_error(SASNAV_ERR_INTERNAL, "an evaluation failed: %s", message);
        if (!rc)
            printf("replay %2d contexts (%s host buffers), level-2 gpu_eval: %7.1f evaluations/s, %.2f ms each\n",
                   n, pinned ? "pinned" : "pageable", n * m / t, 1e3 * t / m);
        fflush(stdout);
        for (int k = 0; k < n; k++) gpu_destroy(g[k]);
        free(g);
        if (pinned) cudaFreeHost(buf);
        else free(buf);
    }
    sasnav_op_destroy(op);
    return rc;
}

int main(int argc, char **argv)
{
    int draws = 3, evals = 20, estimates = 1;
    const char *concurrent = NULL, *replays = NULL;
    sasnav_pair_opts po;
    sasnav_pair_default_opts(&po);
    po.nthreads = 2;
    for (int a = 1; a < argc; a++) {
        if (!strcmp(argv[a], "--draws") && a + 1 < argc) draws = atoi(argv[++a]);
        else if (!strcmp(argv[a], "--threads") && a + 1 < argc) po.nthreads = atoi(argv[++a]);
        else if (!strcmp(argv[a], "--evals") && a + 1 < argc) evals = atoi(argv[++a]);
        else if (!strcmp(argv[a], "--no-estimates")) estimates = 0;
        else if (!strcmp(argv[a], "--concurrent") && a + 1 < argc) concurrent = argv[++a];
        else if (!strcmp(argv[a], "--replay") && a + 1 < argc) replays = argv[++a];
        else {
            fprintf(stderr, "usage: bench_gpu [--draws N] [--threads T] [--evals M] [--no-estimates]"
                            " [--concurrent N1,N2,...] [--replay N1,N2,...]\n");
            return 2;
        }
    }
    if (evals < 1) evals = 1;
    sasnav_scenario sc;
    sasnav_scenario_preset("paper-pair", &sc);
    sc.snr_db = 30.0;
    po.range = sc.range_of_interest;
    po.tx_lag = sc.traj.tx_lag;
    sasnav_run *run = NULL;
    int rc = sasnav_simulate(&sc, NULL, NULL, &run);
    if (!rc && (concurrent || replays)) {
        if (concurrent) rc = concurrency(run, &po, sc.traj.pair_error, concurrent, evals);
        if (!rc && replays) rc = replay(run, replays, evals, 0);
        if (!rc && replays) rc = replay(run, replays, evals, 1);
        sasnav_run_free(run);
        if (rc) fprintf(stderr, "bench_gpu: %s\n", sasnav_last_error());
        return rc ? 1 : 0;
    }
    if (!rc) rc = check_operator(run, po.op.tolerance);
    if (!rc) rc = check_evals(run, &po, sc.traj.pair_error, evals);
    double t[3] = {0, 0, 0}, sum_c = 0, sum_g = 0, sum_d = 0;
    if (!rc && !estimates) {
        sasnav_run_free(run);
        printf("checks done (no estimates)\n");
        return 0;
    }
    if (!rc) rc = estimate_both(run, &po, sc.traj.pair_error, 0, t);
    sum_c += t[0];
    sum_g += t[1];
    sum_d += t[2];
    sasnav_run_free(run);
    run = NULL;
    unsigned long seed = 2026;
    sasnav_rng rng;
    sasnav_rng_seed(&rng, seed);
    for (int d = 1; d <= draws && !rc; d++) {
        sasnav_pose e = {0.04 * (2 * sasnav_rng_uniform(&rng) - 1), 0.025 * (2 * sasnav_rng_uniform(&rng) - 1),
                         0.04 * (2 * sasnav_rng_uniform(&rng) - 1)};
        sc.traj.pair_error = e;
        sc.ripples.seed = seed + 100 + d;
        sc.noise_seed = seed + 200 + d;
        rc = sasnav_simulate(&sc, NULL, NULL, &run);
        if (!rc) rc = estimate_both(run, &po, e, d, t);
        sum_c += t[0];
        sum_g += t[1];
        sum_d += t[2];
        sasnav_run_free(run);
        run = NULL;
    }
    if (rc) {
        fprintf(stderr, "bench_gpu: %s\n", sasnav_last_error());
        return 1;
    }
    printf("all estimates: CPU %.2f s, GPU pairs copied %.2f s (ratio %.1f), device geometry %.2f s (ratio %.1f)\n",
           sum_c, sum_g, sum_c / sum_g, sum_d, sum_c / sum_d);
    return 0;
}
