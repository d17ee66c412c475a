/* Team applications (src/operators/op_team.h) against the plain operator
 * and CGLS, which are their slow references: two images through one
 * operator, with one thread or two sharing the work, must give each image
 * exactly (bit for bit) what sasnav_op_forward, sasnav_op_adjoint and
 * sasnav_cgls give it alone. Grids of several blocks, 4 and 8 kernel taps
 * (the estimator's 1e-3 and the default 1e-6), a CGLS system that stops at
 * once (zero data) beside one that iterates, and Tikhonov damping. */
#include "operators/op_team.h"
#include "sasnav/error.h"
#include "sasnav/image.h"
#include "sasnav/model.h"
#include "sasnav/scene.h"
#include "testutil.h"

#include <complex.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { NX = 70, NY = 20, NP = NX * NY };

static void fill(sasnav_cfloat *v, size_t n, uint64_t seed)
{
    sasnav_rng rng;
    sasnav_rng_seed(&rng, seed);
    for (size_t i = 0; i < n; i++)
        v[i] = (float)sasnav_rng_normal(&rng) + I * (float)sasnav_rng_normal(&rng);
}

static int same(const sasnav_cfloat *a, const sasnav_cfloat *b, size_t n)
{
    return memcmp(a, b, n * sizeof *a) == 0;
}

static void check_tolerance(double tol)
{
    sasnav_system sys;
    sasnav_system_default(&sys);
    sasnav_array arr;
    CHECK_OK(sasnav_array_uniform(&arr, 16, 0.05, 0.05, 0.05));
    sasnav_window win;
    CHECK_OK(sasnav_window_for_ranges(&sys, 9.8, 10.25, 8, &win));
    double x[NP], y[NP];
    for (int j = 0; j < NY; j++)
        for (int i = 0; i < NX; i++) {
            x[j * NX + i] = -0.43 + 0.0125 * i;
            y[j * NX + i] = 9.88 + 0.0125 * j;
        }
    sasnav_op_opts o;
    sasnav_op_default_opts(&o);
    o.tolerance = tol;
    o.nthreads = 2;
    sasnav_op *op = NULL;
    CHECK_OK(sasnav_op_create(&sys, &arr, &win, NP, x, y, &o, &op));
    if (!op) return;
    sasnav_ping_pose ping = sasnav_epca_local(0.1, 0.0);
    CHECK_OK(sasnav_op_set_geometry(op, &ping));
    CHECK_OK(op_team_prepare(op));
    size_t nd = (size_t)arr.n_rx * (size_t)win.n_samples;
    sasnav_cfloat *img[2], *dat[2], *ref_d[2], *ref_i[2], *out_d[2], *out_i[2];
    for (int c = 0; c < 2; c++) {
        img[c] = malloc(NP * sizeof(sasnav_cfloat));
        ref_i[c] = malloc(NP * sizeof(sasnav_cfloat));
        out_i[c] = malloc(NP * sizeof(sasnav_cfloat));
        dat[c] = malloc(nd * sizeof(sasnav_cfloat));
        ref_d[c] = malloc(nd * sizeof(sasnav_cfloat));
        out_d[c] = malloc(nd * sizeof(sasnav_cfloat));
        fill(img[c], NP, 11 + c);
        fill(dat[c], nd, 21 + c);
        CHECK_OK(sasnav_op_forward(op, img[c], ref_d[c]));
        CHECK_OK(sasnav_op_adjoint(op, dat[c], ref_i[c]));
    }
    const sasnav_cfloat *ci[2] = {img[0], img[1]}, *cd[2] = {dat[0], dat[1]};
    for (int team = 1; team <= 2; team++)
        for (int n = 1; n <= 2; n++) {
            memset(out_d[1], 0, nd * sizeof(sasnav_cfloat));
#pragma omp parallel num_threads(team)
            {
                op_forward_team(op, n, ci, out_d);
                op_adjoint_team(op, n, cd, out_i);
            }
            for (int c = 0; c < n; c++) {
                CHECK(same(out_d[c], ref_d[c], nd), "tol %g, team %d, %d images: forward of image %d differs",
                      tol, team, n, c);
                CHECK(same(out_i[c], ref_i[c], NP), "tol %g, team %d, %d images: adjoint of image %d differs",
                      tol, team, n, c);
            }
        }

    /* CGLS: system 0 iterates, system 1 has zero data (stops before its
     * first step) or other data; with and without damping. */
    sasnav_cfloat *work[2], *xs[2], *xr = malloc(NP * sizeof(sasnav_cfloat));
    for (int c = 0; c < 2; c++) {
        work[c] = malloc((2 * NP + 2 * nd) * sizeof(sasnav_cfloat));
        xs[c] = malloc(NP * sizeof(sasnav_cfloat));
    }
    sasnav_cfloat *zero = calloc(nd, sizeof(sasnav_cfloat));
    for (int variant = 0; variant < 3; variant++) {
        double lam = variant == 2 ? 0.3 : 0.0;
        const sasnav_cfloat *rhs[2] = {ref_d[0], variant == 0 ? zero : dat[1]};
        for (int team = 1; team <= 2; team++) {
            cgls_team_state st[2];
#pragma omp parallel num_threads(team)
            cgls_team(op, 2, rhs, 5, lam, xs, work, st);
            for (int c = 0; c < 2; c++) {
                sasnav_cgls_opts co = {5, lam};
                CHECK_OK(sasnav_cgls(op, rhs[c], &co, xr, NULL));
                CHECK(same(xs[c], xr, NP), "tol %g, variant %d, team %d: CGLS system %d differs", tol,
                      variant, team, c);
            }
        }
    }
    free(zero);
    free(xr);
    for (int c = 0; c < 2; c++) {
        free(img[c]);
        free(dat[c]);
        free(ref_d[c]);
        free(ref_i[c]);
        free(out_d[c]);
        free(out_i[c]);
        free(work[c]);
        free(xs[c]);
    }
    sasnav_op_destroy(op);
}

int main(void)
{
    check_tolerance(1e-3);
    check_tolerance(1e-6);
    CHECK(op_team_prepare(NULL) == SASNAV_ERR_ARG, "NULL operator accepted");
    return test_summary("test_op_team");
}
