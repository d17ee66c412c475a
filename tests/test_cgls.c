/* CGLS pseudo-inverse against a dense direct solve of the (regularised)
 * normal equations on a small problem, where k = n_points iterations of
 * CGLS are exact in exact arithmetic. */
#include "sasnav/error.h"
#include "sasnav/image.h"
#include "sasnav/scene.h"
#include "testutil.h"

#include <complex.h>
#include <math.h>
#include <stdlib.h>

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
