/* Truncated, optionally Tikhonov-regularised pseudo-inverse by CGLS
 * (SPEC 2 and 3: rho = T^+ phi with k iterations).
 *
 * Solves min ||T x - d||^2 + lambda ||x||^2 from x = 0 (CGLS of Hestenes and
 * Stiefel applied to the normal equations; the iterate after k steps is the
 * truncated pseudo-inverse of the paper). k iterations cost 2k operator
 * applications: T^H once, then T and T^H per iteration, except the last
 * iteration's T^H (it only prepares a next direction). */
#include "sasnav/error.h"
#include "sasnav/image.h"
#include "operators/op_team.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

void sasnav_cgls_default_opts(sasnav_cgls_opts *opts)
{
    opts->iterations = 5;
    opts->tikhonov = 0.0;
}

/* ||v||^2 in double: the squares of the 2n floats summed in NORM_LANES
 * interleaved partial sums (float j into sum j mod NORM_LANES), which are
 * then added in order. The lanes are independent chains that vectorise;
 * one sequential sum waited on each addition (about 2 % of an estimate's
 * time, perf). The order is fixed whatever the target: results are
 * reproducible. */
#define NORM_LANES 8
static double norm2(const sasnav_cfloat *v, size_t n)
{
    const float *f = (const float *)v;
    size_t m = 2 * n, full = m / NORM_LANES * NORM_LANES;
    double lane[NORM_LANES] = {0};
    for (size_t i = 0; i < full; i += NORM_LANES)
        for (int j = 0; j < NORM_LANES; j++) {
            double a = f[i + j];
            lane[j] += a * a;
        }
    for (size_t i = full; i < m; i++) {
        double a = f[i];
        lane[i - full] += a * a;
    }
    double s = 0;
    for (int j = 0; j < NORM_LANES; j++) s += lane[j];
    return s;
}

int sasnav_cgls(sasnav_op *op, const sasnav_cfloat *data, const sasnav_cgls_opts *opts,
                sasnav_cfloat *x, sasnav_cfloat *work)
{
    if (!op || !data || !x) return sasnav_set_error(SASNAV_ERR_ARG, "NULL CGLS argument");
    sasnav_cgls_opts o;
    if (opts) o = *opts;
    else sasnav_cgls_default_opts(&o);
    if (o.iterations < 0 || !(o.tikhonov >= 0) || !isfinite(o.tikhonov))
        return sasnav_set_error(SASNAV_ERR_ARG, "CGLS needs iterations >= 0 and lambda >= 0");
    size_t np = (size_t)sasnav_op_n_points(op);
    size_t nd = (size_t)sasnav_op_n_rx(op) * (size_t)sasnav_op_n_samples(op);
    sasnav_cfloat *own = NULL;
    if (!work) {
        own = malloc(sizeof(sasnav_cfloat) * (2 * np + 2 * nd));
        if (!own) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory for CGLS");
        work = own;
    }
    sasnav_cfloat *s = work, *p = work + np, *r = work + 2 * np, *q = work + 2 * np + nd;
    int rc = SASNAV_OK;
    memset(x, 0, sizeof(sasnav_cfloat) * np);
    memcpy(r, data, sizeof(sasnav_cfloat) * nd);
    if (o.iterations == 0) goto done;
    rc = sasnav_op_adjoint(op, r, s); /* s = T^H r - lambda x, x = 0 */
    if (rc) goto done;
    memcpy(p, s, sizeof(sasnav_cfloat) * np);
    double gamma = norm2(s, np), gamma0 = gamma;
    /* Stop once the normal-equation residual has fallen to float rounding
     * level: further float iterations only amplify rounding noise. */
    for (int it = 0; it < o.iterations && gamma > 1e-12 * gamma0; it++) {
        rc = sasnav_op_forward(op, p, q);
        if (rc) goto done;
        double delta = norm2(q, nd);
        if (o.tikhonov > 0) delta += o.tikhonov * norm2(p, np);
        if (!(delta > 0)) break;
        float alpha = (float)(gamma / delta);
        for (size_t i = 0; i < np; i++) x[i] += alpha * p[i];
        /* The last iterate is complete: the next direction (T^H r) would
         * never be used, and skipping it leaves x exactly the same. */
        if (it == o.iterations - 1) break;
        for (size_t i = 0; i < nd; i++) r[i] -= alpha * q[i];
        rc = sasnav_op_adjoint(op, r, s);
        if (rc) goto done;
        if (o.tikhonov > 0) {
            float lam = (float)o.tikhonov;
            for (size_t i = 0; i < np; i++) s[i] -= lam * x[i];
        }
        double gamma_new = norm2(s, np);
        float beta = (float)(gamma_new / gamma);
        for (size_t i = 0; i < np; i++) p[i] = s[i] + beta * p[i];
        gamma = gamma_new;
    }
done:
    free(own);
    return rc;
}

/* ------------------------------------------------------------------------ */
/* CGLS of one or two systems in lockstep on a team (op_team.h): the steps
 * of sasnav_cgls above, system by system, with the operator applied to the
 * systems still iterating at once. The `omp for` loops over the systems
 * bind to the caller's parallel region (one system per thread with two
 * threads) and end with a barrier, after which every thread reads the same
 * shared flags. */

/* The systems still iterating, in order (the same list on every thread),
 * and the vectors at offsets a and b of their work areas as the inputs and
 * outputs of an application. */
static int team_active(int n, const cgls_team_state *st, sasnav_cfloat *const *work, size_t a,
                       size_t b, int *which, const sasnav_cfloat **in, sasnav_cfloat **out)
{
    int m = 0;
    for (int c = 0; c < n; c++)
        if (st[c].active) {
            in[m] = work[c] + a;
            out[m] = work[c] + b;
            which[m++] = c;
        }
    return m;
}

void cgls_team(const sasnav_op *op, int n, const sasnav_cfloat *const *data, int iterations,
               double tikhonov, sasnav_cfloat *const *x, sasnav_cfloat *const *work,
               cgls_team_state *st)
{
    size_t np = (size_t)sasnav_op_n_points(op);
    size_t nd = (size_t)sasnav_op_n_rx(op) * (size_t)sasnav_op_n_samples(op);
    /* per system: s = work, p = work + np, r = work + 2 np, q = work + 2 np + nd */
#define S_(c) (work[c])
#define P_(c) (work[c] + np)
#define R_(c) (work[c] + 2 * np)
#define Q_(c) (work[c] + 2 * np + nd)
#pragma omp for schedule(static, 1)
    for (int c = 0; c < n; c++) {
        memset(x[c], 0, sizeof(sasnav_cfloat) * np);
        memcpy(R_(c), data[c], sizeof(sasnav_cfloat) * nd);
        st[c].active = iterations > 0;
    }
    if (iterations <= 0) return;
    const sasnav_cfloat *in[2];
    sasnav_cfloat *out[2];
    for (int c = 0; c < n; c++) {
        in[c] = R_(c);
        out[c] = S_(c);
    }
    op_adjoint_team(op, n, in, out); /* s = T^H r - lambda x, x = 0 */
#pragma omp for schedule(static, 1)
    for (int c = 0; c < n; c++) {
        memcpy(P_(c), S_(c), sizeof(sasnav_cfloat) * np);
        st[c].gamma = st[c].gamma0 = norm2(S_(c), np);
    }
    int which[2];
    for (int it = 0; it < iterations; it++) {
        /* sasnav_cgls's loop condition, per system */
#pragma omp for schedule(static, 1)
        for (int c = 0; c < n; c++)
            if (st[c].active && !(st[c].gamma > 1e-12 * st[c].gamma0)) st[c].active = 0;
        int m = team_active(n, st, work, np, 2 * np + nd, which, in, out); /* p -> q */
        if (!m) break;
        op_forward_team(op, m, in, out);
#pragma omp for schedule(static, 1)
        for (int k = 0; k < m; k++) {
            int c = which[k];
            sasnav_cfloat *p = P_(c), *q = Q_(c), *r = R_(c), *xc = x[c];
            double delta = norm2(q, nd);
            if (tikhonov > 0) delta += tikhonov * norm2(p, np);
            if (!(delta > 0)) {
                st[c].active = 0;
                continue;
            }
            float alpha = (float)(st[c].gamma / delta);
            for (size_t i = 0; i < np; i++) xc[i] += alpha * p[i];
            if (it == iterations - 1) continue;
            for (size_t i = 0; i < nd; i++) r[i] -= alpha * q[i];
        }
        if (it == iterations - 1) break;
        m = team_active(n, st, work, 2 * np, 0, which, in, out); /* r -> s */
        if (!m) break;
        op_adjoint_team(op, m, in, out);
#pragma omp for schedule(static, 1)
        for (int k = 0; k < m; k++) {
            int c = which[k];
            sasnav_cfloat *s = S_(c), *p = P_(c), *xc = x[c];
            if (tikhonov > 0) {
                float lam = (float)tikhonov;
                for (size_t i = 0; i < np; i++) s[i] -= lam * xc[i];
            }
            double gamma_new = norm2(s, np);
            float beta = (float)(gamma_new / st[c].gamma);
            for (size_t i = 0; i < np; i++) p[i] = s[i] + beta * p[i];
            st[c].gamma = gamma_new;
        }
    }
#undef S_
#undef P_
#undef R_
#undef Q_
}

/* ------------------------------------------------------------------------ */
/* CGLS on two operators stacked (op_team.h, cgls_stack): the steps of
 * sasnav_cgls with T = [A; B], T x = (A x, B x) and T^H (u, v) = A^H u +
 * B^H v. With two_threads the two operators' applications run side by
 * side, one thread each (each operator then applies on that thread alone,
 * nested parallelism being off): every application is the same bits as
 * alone, so x and the residuals do not depend on it. */
static int stack_forward(sasnav_op *A, sasnav_op *B, const sasnav_cfloat *x, sasnav_cfloat *ya,
                         sasnav_cfloat *yb, int two)
{
    int rc[2] = {SASNAV_OK, SASNAV_OK};
    if (!two) {
        rc[0] = sasnav_op_forward(A, x, ya);
        if (!rc[0]) rc[1] = sasnav_op_forward(B, x, yb);
        return rc[0] ? rc[0] : rc[1];
    }
#pragma omp parallel num_threads(2)
    {
        int t = omp_get_thread_num(), nt = omp_get_num_threads();
        for (int c = t; c < 2; c += nt) rc[c] = c == 0 ? sasnav_op_forward(A, x, ya) : sasnav_op_forward(B, x, yb);
    }
    return rc[0] ? rc[0] : rc[1];
}

static int stack_adjoint(sasnav_op *A, sasnav_op *B, const sasnav_cfloat *ua, const sasnav_cfloat *ub,
                         sasnav_cfloat *s, sasnav_cfloat *tmp, size_t np, int two)
{
    int rc[2] = {SASNAV_OK, SASNAV_OK};
    if (!two) {
        rc[0] = sasnav_op_adjoint(A, ua, s);
        if (!rc[0]) rc[1] = sasnav_op_adjoint(B, ub, tmp);
    } else {
#pragma omp parallel num_threads(2)
        {
            int t = omp_get_thread_num(), nt = omp_get_num_threads();
            for (int c = t; c < 2; c += nt) rc[c] = c == 0 ? sasnav_op_adjoint(A, ua, s) : sasnav_op_adjoint(B, ub, tmp);
        }
    }
    if (rc[0] || rc[1]) return rc[0] ? rc[0] : rc[1];
    for (size_t i = 0; i < np; i++) s[i] += tmp[i];
    return SASNAV_OK;
}

int cgls_stack(sasnav_op *A, sasnav_op *B, const sasnav_cfloat *a, const sasnav_cfloat *b,
               int iterations, double tikhonov, int two_threads, sasnav_cfloat *x, sasnav_cfloat *ra,
               sasnav_cfloat *rb, sasnav_cfloat *work)
{
    if (!A || !B || !a || !b || !x || !ra || !rb || !work)
        return sasnav_set_error(SASNAV_ERR_ARG, "NULL CGLS argument");
    if (iterations < 0 || !(tikhonov >= 0) || !isfinite(tikhonov))
        return sasnav_set_error(SASNAV_ERR_ARG, "CGLS needs iterations >= 0 and lambda >= 0");
    size_t np = (size_t)sasnav_op_n_points(A);
    size_t na = (size_t)sasnav_op_n_rx(A) * (size_t)sasnav_op_n_samples(A);
    size_t nb = (size_t)sasnav_op_n_rx(B) * (size_t)sasnav_op_n_samples(B);
    if ((size_t)sasnav_op_n_points(B) != np)
        return sasnav_set_error(SASNAV_ERR_ARG, "stacked CGLS: the operators' grids differ");
    sasnav_cfloat *s = work, *p = work + np, *tmp = work + 2 * np, *qa = work + 3 * np, *qb = qa + na;
    memset(x, 0, sizeof(sasnav_cfloat) * np);
    memcpy(ra, a, sizeof(sasnav_cfloat) * na);
    memcpy(rb, b, sizeof(sasnav_cfloat) * nb);
    if (iterations == 0) return SASNAV_OK;
    int rc = stack_adjoint(A, B, ra, rb, s, tmp, np, two_threads);
    if (rc) return rc;
    memcpy(p, s, sizeof(sasnav_cfloat) * np);
    double gamma = norm2(s, np), gamma0 = gamma;
    for (int it = 0; it < iterations && gamma > 1e-12 * gamma0; it++) {
        rc = stack_forward(A, B, p, qa, qb, two_threads);
        if (rc) return rc;
        double delta = norm2(qa, na) + norm2(qb, nb);
        if (tikhonov > 0) delta += tikhonov * norm2(p, np);
        if (!(delta > 0)) break;
        float alpha = (float)(gamma / delta);
        for (size_t i = 0; i < np; i++) x[i] += alpha * p[i];
        /* the data residuals are kept up to date on the last iteration too
         * (they are outputs); only the next direction is skipped */
        for (size_t i = 0; i < na; i++) ra[i] -= alpha * qa[i];
        for (size_t i = 0; i < nb; i++) rb[i] -= alpha * qb[i];
        if (it == iterations - 1) break;
        rc = stack_adjoint(A, B, ra, rb, s, tmp, np, two_threads);
        if (rc) return rc;
        if (tikhonov > 0) {
            float lam = (float)tikhonov;
            for (size_t i = 0; i < np; i++) s[i] -= lam * x[i];
        }
        double gamma_new = norm2(s, np);
        float beta = (float)(gamma_new / gamma);
        for (size_t i = 0; i < np; i++) p[i] = s[i] + beta * p[i];
        gamma = gamma_new;
    }
    return SASNAV_OK;
}
