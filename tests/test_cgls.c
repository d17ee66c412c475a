/* CGLS pseudo-inverse against a dense direct solve of the (regularised)
 * normal equations on a small problem, where k = n_points iterations of
 * CGLS are exact in exact arithmetic; CGLS of two operators stacked
 * (cgls_stack, the joint misfit's) against sasnav_cgls on the one operator
 * that holds both pings' channels. */
#include "sasnav/error.h"
#include "sasnav/image.h"
#include "sasnav/scene.h"
#include "operators/op_team.h"
#include "testutil.h"

#include <complex.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Solves the n x n complex system M x = b by Gaussian elimination with
 * partial pivoting (double precision). */
static void solve(int n, double complex *M, double complex *b)
{
    for (int c = 0; c < n; c++) {
        int piv = c;
        for (int r = c + 1; r < n; r++)
            if (cabs(M[r * n + c]) > cabs(M[piv * n + c])) piv = r;
        for (int j = 0; j < n; j++) {
            double complex t = M[c * n + j];
            M[c * n + j] = M[piv * n + j];
            M[piv * n + j] = t;
        }
        double complex t = b[c];
        b[c] = b[piv];
        b[piv] = t;
        for (int r = c + 1; r < n; r++) {
            double complex f = M[r * n + c] / M[c * n + c];
            for (int j = c; j < n; j++) M[r * n + j] -= f * M[c * n + j];
            b[r] -= f * b[c];
        }
    }
    for (int r = n - 1; r >= 0; r--) {
        for (int j = r + 1; j < n; j++) b[r] -= M[r * n + j] * b[j];
        b[r] /= M[r * n + r];
    }
}

/* cgls_stack(A, B) is CGLS on [A; B]: the same iterates as sasnav_cgls on
 * one operator of both pings' channels (a 2N-channel array whose first N
 * channels have A's pose and the others B's), up to float rounding (the
 * sums are ordered differently); its residuals are the data minus the
 * stacked operator's image of x; the two-thread path gives the same bits. */
static void check_stack(const sasnav_system *sys, const sasnav_array *arr, const sasnav_window *win, int np,
                        const double *x, const double *y, sasnav_rng *rng)
{
    sasnav_op *A = NULL, *B = NULL, *AB = NULL;
    sasnav_op_opts oo;
    sasnav_op_default_opts(&oo);
    oo.nthreads = 2;
    CHECK_OK(sasnav_op_create(sys, arr, win, np, x, y, &oo, &A));
    CHECK_OK(sasnav_op_create(sys, arr, win, np, x, y, &oo, &B));
    sasnav_array arr2 = *arr;
    arr2.n_rx = 2 * arr->n_rx;
    for (int l = 0; l < arr->n_rx; l++) arr2.rx_u[arr->n_rx + l] = arr->rx_u[l];
    CHECK_OK(sasnav_op_create(sys, &arr2, win, np, x, y, &oo, &AB));
    if (!A || !B || !AB) return;
    sasnav_ping_pose loc = sasnav_epca_local(0.1, 0.0);
    sasnav_ping_pose pa = sasnav_ping_place((sasnav_pose){0, 0, 0}, &loc);
    sasnav_ping_pose pb = sasnav_ping_place((sasnav_pose){0.031, -0.012, 0.004}, &loc);
    sasnav_ping_pose ch[SASNAV_MAX_RX];
    for (int l = 0; l < arr->n_rx; l++) {
        ch[l] = pa;
        ch[arr->n_rx + l] = pb;
    }
    CHECK_OK(sasnav_op_set_geometry(A, &pa));
    CHECK_OK(sasnav_op_set_geometry(B, &pb));
    CHECK_OK(sasnav_op_set_channels(AB, ch));
    size_t nd = (size_t)arr->n_rx * win->n_samples;
    sasnav_cfloat *d = malloc(sizeof *d * 2 * nd), *r = malloc(sizeof *r * 2 * nd), *r2 = malloc(sizeof *r2 * 2 * nd);
    sasnav_cfloat *xs = malloc(sizeof *xs * np), *xr = malloc(sizeof *xr * np), *x2 = malloc(sizeof *x2 * np);
    sasnav_cfloat *work = malloc(sizeof *work * (3 * np + 2 * nd)), *img = malloc(sizeof *img * 2 * nd);
    for (size_t m = 0; m < 2 * nd; m++) d[m] = (float)sasnav_rng_normal(rng) + I * (float)sasnav_rng_normal(rng);
    for (int t = 0; t < 2; t++) {
        double lambda = t == 0 ? 0.0 : 0.3;
        int k = 7;
        CHECK_OK(cgls_stack(A, B, d, d + nd, k, lambda, 0, xs, r, r + nd, work));
        sasnav_cgls_opts co = {k, lambda};
        CHECK_OK(sasnav_cgls(AB, d, &co, xr, NULL));
        double num = 0, den = 0;
        for (int i = 0; i < np; i++) {
            num += pow(cabsf(xs[i] - xr[i]), 2);
            den += pow(cabsf(xr[i]), 2);
        }
        /* float vectors, sums in another order: 1e-4 relative */
        CHECK(sqrt(num / den) < 1e-4, "lambda %g: stacked CGLS vs one operator, relative error %g", lambda,
              sqrt(num / den));
        CHECK_OK(sasnav_op_forward(AB, xs, img));
        num = den = 0;
        for (size_t m = 0; m < 2 * nd; m++) {
            num += pow(cabsf(d[m] - img[m] - r[m]), 2);
            den += pow(cabsf(d[m]), 2);
        }
        /* the recursive residual against the direct one (float drift) */
        CHECK(sqrt(num / den) < 1e-4, "lambda %g: residual off by %g of the data", lambda, sqrt(num / den));
        CHECK_OK(cgls_stack(A, B, d, d + nd, k, lambda, 1, x2, r2, r2 + nd, work));
        CHECK(!memcmp(xs, x2, sizeof *xs * np) && !memcmp(r, r2, sizeof *r * 2 * nd),
              "lambda %g: the two-thread path changed the bits", lambda);
    }
    CHECK(cgls_stack(A, B, d, d + nd, -1, 0, 0, xs, r, r + nd, work) == SASNAV_ERR_ARG, "negative k accepted");
    free(d);
    free(r);
    free(r2);
    free(xs);
    free(xr);
    free(x2);
    free(work);
    free(img);
    sasnav_op_destroy(A);
    sasnav_op_destroy(B);
    sasnav_op_destroy(AB);
}

int main(void)
{
    sasnav_system sys;
    sasnav_system_default(&sys);
    sasnav_array arr;
    CHECK_OK(sasnav_array_uniform(&arr, 4, 0.05, 0.05, 0.05));
    sasnav_window win;
    CHECK_OK(sasnav_window_for_ranges(&sys, 9.8, 10.2, 8, &win));
    /* 12 points spread over the swath, well separated in delay so the
     * system is well conditioned. */
    enum { NP = 12 };
    double x[NP], y[NP];
    sasnav_rng rng;
    sasnav_rng_seed(&rng, 5);
    for (int n = 0; n < NP; n++) {
        x[n] = -0.3 + 0.6 * sasnav_rng_uniform(&rng);
        y[n] = 9.85 + 0.3 * n / (NP - 1.0);
    }
    sasnav_op *op = NULL;
    CHECK_OK(sasnav_op_create(&sys, &arr, &win, NP, x, y, NULL, &op));
    if (!op) return test_summary("test_cgls");
    sasnav_ping_pose ping = sasnav_epca_local(0.1, 0.0);
    CHECK_OK(sasnav_op_set_geometry(op, &ping));
    int nd = arr.n_rx * win.n_samples;
    /* Dense matrix A (nd x NP) column by column. */
    double complex *A = calloc((size_t)nd * NP, sizeof *A);
    sasnav_cfloat *e = calloc(NP, sizeof *e), *col = calloc(nd, sizeof *col), *d = calloc(nd, sizeof *d);
    for (int n = 0; n < NP; n++) {
        for (int j = 0; j < NP; j++) e[j] = 0;
        e[n] = 1;
        CHECK_OK(sasnav_op_forward(op, e, col));
        for (int m = 0; m < nd; m++) A[(size_t)m * NP + n] = col[m];
    }
    for (int m = 0; m < nd; m++) d[m] = (float)sasnav_rng_normal(&rng) + I * (float)sasnav_rng_normal(&rng);
    for (int t = 0; t < 2; t++) {
        double lambda = t == 0 ? 0.0 : 0.05;
        double complex M[NP * NP], b[NP];
        double scale = 0;
        for (int i = 0; i < NP; i++) {
            b[i] = 0;
            for (int m = 0; m < nd; m++) b[i] += conj(A[(size_t)m * NP + i]) * d[m];
            for (int j = 0; j < NP; j++) {
                double complex s = 0;
                for (int m = 0; m < nd; m++) s += conj(A[(size_t)m * NP + i]) * A[(size_t)m * NP + j];
                M[i * NP + j] = s;
            }
            scale += creal(M[i * NP + i]) / NP;
        }
        for (int i = 0; i < NP; i++) M[i * NP + i] += lambda * scale;
        solve(NP, M, b);
        sasnav_cgls_opts co = {3 * NP, lambda * scale};
        sasnav_cfloat xs[NP];
        CHECK_OK(sasnav_cgls(op, d, &co, xs, NULL));
        double num = 0, den = 0;
        for (int i = 0; i < NP; i++) {
            num += pow(cabs(xs[i] - b[i]), 2);
            den += pow(cabs(b[i]), 2);
        }
        /* Float operators and float CGLS vectors: a relative error of 1e-3
         * allows for the condition number (~1e2 here) times float rounding. */
        CHECK(sqrt(num / den) < 1e-3, "lambda %g: CGLS vs direct relative error %g", lambda,
              sqrt(num / den));
    }
    check_stack(&sys, &arr, &win, NP, x, y, &rng);
    /* k = 0 gives zero; bad options are refused. */
    sasnav_cgls_opts bad = {-1, 0};
    sasnav_cfloat xs[NP];
    CHECK(sasnav_cgls(op, d, &bad, xs, NULL) == SASNAV_ERR_ARG, "negative k accepted");
    free(A);
    free(e);
    free(col);
    free(d);
    sasnav_op_destroy(op);
    return test_summary("test_cgls");
}
