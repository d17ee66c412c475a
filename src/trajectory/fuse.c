/* Joint resolution and fusion of a run's consecutive pairs (fuse.h). */
#include "trajectory/fuse.h"
#include "sasnav/error.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static double comp(sasnav_pose p, int k) { return k == 0 ? p.x : k == 1 ? p.y : p.theta; }

static void set_comp(sasnav_pose *p, int k, double v)
{
    if (k == 0) p->x = v;
    else if (k == 1) p->y = v;
    else p->theta = v;
}

void fuse_aiding_error(const sasnav_run *run, int p, int q, sasnav_pose nom, double est_yaw,
                       sasnav_pose *a, sasnav_pose *sa)
{
    const sasnav_aiding *ad = run->aiding;
    *a = (sasnav_pose){0, 0, 0};
    *sa = (sasnav_pose){INFINITY, INFINITY, INFINITY};
    if (!ad || q != p + 1) return;
    double dt = ad->time[q] - ad->time[p];
    double dpsi = nom.theta + est_yaw;
    if (ad->yaw_rate && isfinite(ad->yaw_rate_sigma[q])) { /* (+inf: no measurement there) */
        dpsi = ad->yaw_rate[q] * dt;
        a->theta = dpsi - nom.theta;
        sa->theta = ad->yaw_rate_sigma[q] * dt;
    }
    if (ad->velocity) {
        /* The mean velocity is given in the frame at the interval's mean
         * heading: rotate by half the interval's yaw into p's frame. */
        double c = cos(0.5 * dpsi), s = sin(0.5 * dpsi);
        double v0 = ad->velocity[2 * q], v1 = ad->velocity[2 * q + 1];
        a->x = (c * v0 - s * v1) * dt - nom.x;
        a->y = (s * v0 + c * v1) * dt - nom.y;
        sa->x = ad->velocity_sigma[2 * q] * dt;
        sa->y = ad->velocity_sigma[2 * q + 1] * dt;
    }
}

/* 1/2 sum_k ((u_k - v_k) / s_k)^2 over the components with finite s. */
static double half_chi2(sasnav_pose u, sasnav_pose v, sasnav_pose s)
{
    double c = 0;
    for (int k = 0; k < 3; k++) {
        double sk = comp(s, k);
        if (!isfinite(sk)) continue;
        double r = (comp(u, k) - comp(v, k)) / sk;
        c += 0.5 * r * r;
    }
    return c;
}

int fuse_choose(int n, fuse_option *const *opts, const int *nopt, const sasnav_pose *a,
                const sasnav_pose *sa, sasnav_pose motion, double eta_weight, int *choice)
{
    if (n < 1) return SASNAV_OK;
    int width = 1;
    for (int j = 0; j < n; j++)
        if (nopt[j] > width) width = nopt[j];
    double *cost = malloc(sizeof(double) * (size_t)n * (size_t)width);
    int *from = malloc(sizeof(int) * (size_t)n * (size_t)width);
    if (!cost || !from) {
        free(cost);
        free(from);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory in the joint resolution");
    }
    for (int j = 0; j < n; j++) {
        double eta_min = HUGE_VAL;
        for (int c = 0; c < nopt[j]; c++)
            if (opts[j][c].eta < eta_min) eta_min = opts[j][c].eta;
        for (int c = 0; c < nopt[j]; c++) {
            const fuse_option *o = &opts[j][c];
            double u = half_chi2(o->e, a[j], sa[j]);
            if (eta_min > 0 && o->eta > 0 && isfinite(o->eta)) u += eta_weight * log(o->eta / eta_min);
            double best = 0;
            int arg = -1;
            if (j > 0) {
                /* the first option unless a cost is lower: non-finite
                 * costs (absurd aiding values) must not leave no choice */
                best = HUGE_VAL;
                arg = 0;
                for (int b = 0; b < nopt[j - 1]; b++) {
                    double t = cost[(size_t)(j - 1) * width + b] + half_chi2(o->e, opts[j - 1][b].e, motion);
                    if (t < best) {
                        best = t;
                        arg = b;
                    }
                }
            }
            cost[(size_t)j * width + c] = best + u;
            from[(size_t)j * width + c] = arg;
        }
    }
    int c = 0;
    for (int b = 1; b < nopt[n - 1]; b++)
        if (cost[(size_t)(n - 1) * width + b] < cost[(size_t)(n - 1) * width + c]) c = b;
    for (int j = n - 1; j >= 0; j--) {
        choice[j] = c;
        if (j > 0) c = from[(size_t)j * width + c];
    }
    free(cost);
    free(from);
    return SASNAV_OK;
}

/* Solves the symmetric tridiagonal system (diag d, off-diagonal o between
 * i and i + 1) in place (Thomas algorithm; d is positive definite here). */
static void tridiag_solve(int n, double *d, double *o, double *b)
{
    for (int i = 1; i < n; i++) {
        double f = o[i - 1] / d[i - 1];
        d[i] -= f * o[i - 1];
        b[i] -= f * b[i - 1];
    }
    b[n - 1] /= d[n - 1];
    for (int i = n - 2; i >= 0; i--) b[i] = (b[i] - o[i] * b[i + 1]) / d[i];
}

int fuse_smooth(int n, const sasnav_pose *m, const sasnav_pose *sm, const sasnav_pose *a,
                const sasnav_pose *sa, sasnav_pose motion, double huber, sasnav_pose *e)
{
    return fuse_smooth_bias(n, m, sm, a, sa, motion, huber, (sasnav_pose){0, 0, 0}, e, NULL);
}

int fuse_smooth_bias(int n, const sasnav_pose *m, const sasnav_pose *sm, const sasnav_pose *a,
                     const sasnav_pose *sa, sasnav_pose motion, double huber, sasnav_pose bias_sigma,
                     sasnav_pose *e, sasnav_pose *bias)
{
    return fuse_smooth_post(n, m, sm, a, sa, motion, huber, bias_sigma, e, bias, NULL);
}

int fuse_smooth_post(int n, const sasnav_pose *m, const sasnav_pose *sm, const sasnav_pose *a,
                     const sasnav_pose *sa, sasnav_pose motion, double huber, sasnav_pose bias_sigma,
                     sasnav_pose *e, sasnav_pose *bias, fuse_posterior *post)
{
    if (bias) *bias = (sasnav_pose){0, 0, 0};
    if (n < 1) return SASNAV_OK;
    size_t sz = sizeof(double) * (size_t)n;
    double *d = malloc(sz), *o = malloc(sz), *b = malloc(sz), *w = malloc(sz);
    double *d2 = malloc(sz), *o2 = malloc(sz), *u = malloc(sz);
    if (!d || !o || !b || !w || !d2 || !o2 || !u) {
        free(d);
        free(o);
        free(b);
        free(w);
        free(d2);
        free(o2);
        free(u);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory in the trajectory smoother");
    }
    /* A very weak prior on the motion error itself (1 m, 1 rad) keeps a
     * component that nothing observes at the nominal step. */
    const double prior_w = 1.0;
    for (int k = 0; k < 3; k++) {
        double sk = comp(motion, k), sb = comp(bias_sigma, k);
        double wm = isfinite(sk) && sk > 0 ? 1.0 / (sk * sk) : 0.0;
        int with_bias = sb > 0 && isfinite(sb);
        for (int j = 0; j < n; j++) w[j] = 1.0;
        double bk = 0;
        for (int iter = 0; iter < 5; iter++) {
            double sum_wa = 0, sum_wa_a = 0;
            for (int j = 0; j < n; j++) {
                double s1 = comp(sm[j], k), s2 = comp(sa[j], k);
                double w1 = isfinite(s1) ? w[j] / (s1 * s1) : 0.0;
                double w2 = isfinite(s2) ? 1.0 / (s2 * s2) : 0.0;
                d[j] = prior_w + w1 + w2 + (j > 0 ? wm : 0.0) + (j + 1 < n ? wm : 0.0);
                o[j] = -wm;
                /* (a term without weight adds nothing, even where its
                 * value is not finite) */
                b[j] = (w1 > 0 ? w1 * comp(m[j], k) : 0.0) + (w2 > 0 ? w2 * comp(a[j], k) : 0.0);
                u[j] = w2;
                sum_wa += w2;
                sum_wa_a += w2 > 0 ? w2 * comp(a[j], k) : 0.0;
            }
            if (with_bias && sum_wa > 0) {
                /* Bordered system: T e + u b = r, u^T e + beta b = s. Solve
                 * T x = r and T y = u (two copies of T: the solver works in
                 * place), then b = (s - u^T x) / (beta - u^T y), e = x - y b. */
                memcpy(d2, d, sz);
                memcpy(o2, o, sz);
                tridiag_solve(n, d, o, b);
                tridiag_solve(n, d2, o2, u);
                double ux = 0, uy = 0;
                for (int j = 0; j < n; j++) {
                    double s2 = comp(sa[j], k), w2 = isfinite(s2) ? 1.0 / (s2 * s2) : 0.0;
                    ux += w2 * b[j];
                    uy += w2 * u[j];
                }
                double beta = sum_wa + 1.0 / (sb * sb);
                bk = (sum_wa_a - ux) / (beta - uy);
                for (int j = 0; j < n; j++) b[j] -= u[j] * bk;
                if (post) {
                    if (post->yu[k]) memcpy(post->yu[k], u, sz);
                    post->denom[k] = post->yu[k] ? beta - uy : 0.0; /* (no yu: no bias term) */
                }
            } else {
                tridiag_solve(n, d, o, b);
                if (post) post->denom[k] = 0.0;
            }
            if (post) { /* d now holds D of T = L D L^T; o is untouched */
                memcpy(post->d[k], d, sz);
                memcpy(post->off[k], o, sz);
            }
            /* Huber weights of the estimates' residuals. */
            int changed = 0;
            for (int j = 0; j < n; j++) {
                set_comp(&e[j], k, b[j]);
                double s1 = comp(sm[j], k);
                if (!isfinite(s1) || !(huber > 0)) continue;
                double r = fabs(comp(m[j], k) - b[j]) / s1;
                double nw = r > huber ? huber / r : 1.0;
                if (fabs(nw - w[j]) > 1e-3) changed = 1;
                w[j] = nw;
            }
            if (!changed) break;
        }
        if (bias) set_comp(bias, k, bk);
    }
    free(d);
    free(o);
    free(b);
    free(w);
    free(d2);
    free(o2);
    free(u);
    return SASNAV_OK;
}

/* The derivatives of ping m's pose (x, y, heading) with respect to
 * component k of step j < m have the form alpha(m) + h_j (fuse_pose_sigma):
 * h_j written to h[0..2], alpha(m) to al[0..2] (al may be NULL). The step
 * j moves ping j + 1 by R(psi_j) (surge, sway) in the frame of ping j; a
 * yaw error of step j turns everything after ping j + 1 about it:
 * d P_m / d theta_j = J (P_m - P_{j+1}), J (x, y) = (-y, x). */
static void step_jacobian(int k, const sasnav_pose *poses, int j, int m, double *h, double *al)
{
    /* (positions from ping 0's: only differences matter, and world
     * coordinates of 1e6 m would cancel catastrophically in the prefix
     * sums' alpha^2 S - 2 alpha S_h + S_hh) */
    double x0 = poses[0].x, y0 = poses[0].y;
    double c = cos(poses[j].theta), s = sin(poses[j].theta);
    if (al) al[0] = al[1] = al[2] = 0.0;
    if (k == 0) {
        h[0] = c;
        h[1] = s;
        h[2] = 0.0;
    } else if (k == 1) {
        h[0] = -s;
        h[1] = c;
        h[2] = 0.0;
    } else {
        h[0] = poses[j + 1].y - y0;
        h[1] = -(poses[j + 1].x - x0);
        h[2] = 1.0;
        if (al) {
            al[0] = -(poses[m].y - y0);
            al[1] = poses[m].x - x0;
        }
    }
}

int fuse_pose_sigma(int n, const fuse_posterior *post, const sasnav_pose *poses, sasnav_pose *sigma)
{
    if (n < 0 || !post || !poses || !sigma) return sasnav_set_error(SASNAV_ERR_ARG, "pose sigma: bad arguments");
    sigma[0] = (sasnav_pose){0, 0, 0};
    if (n == 0) return SASNAV_OK;
    double *tau = malloc(sizeof(double) * 3 * (size_t)(n + 1));
    if (!tau) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory for the trajectory's standard deviations");
    /* tau_k[m] = sum_{i >= m} prod_{r = m..i} l_r^2 / D_i, the tail of the
     * forward substitution of a vector that ends at m - 1. */
    for (int k = 0; k < 3; k++) {
        double *t = tau + (size_t)k * (size_t)(n + 1);
        const double *d = post->d[k], *o = post->off[k];
        t[n] = 0.0;
        for (int i = n - 1; i >= 1; i--) {
            double l = o[i - 1] / d[i - 1];
            t[i] = l * l * (1.0 / d[i] + t[i + 1]);
        }
        t[0] = 0.0; /* (unused) */
    }
    /* Running values per component: the forward substitutions A = L^-1 1
     * and H = L^-1 h (prefixes do not depend on m), their prefix sums
     * weighted by 1 / D, and the prefix sums against T^-1 u; only the
     * variances (the diagonal of each ping's covariance) are needed. */
    double A[3] = {0}, H[3][3] = {{0}}, saa[3] = {0}, sah[3][3] = {{0}}, shh[3][3] = {{0}};
    double su[3] = {0}, shu[3][3] = {{0}};
    for (int mm = 1; mm <= n; mm++) {
        int i = mm - 1; /* the step added: ping mm depends on steps 0..mm-1 */
        double var[3] = {0, 0, 0};
        for (int k = 0; k < 3; k++) {
            const double *d = post->d[k], *o = post->off[k];
            double l = i > 0 ? o[i - 1] / d[i - 1] : 0.0, h[3], al[3];
            step_jacobian(k, poses, i, mm, h, al);
            A[k] = 1.0 - l * A[k];
            for (int p = 0; p < 3; p++) H[k][p] = h[p] - l * H[k][p];
            double w = 1.0 / d[i];
            saa[k] += A[k] * A[k] * w;
            for (int p = 0; p < 3; p++) {
                sah[k][p] += A[k] * H[k][p] * w;
                shh[k][p] += H[k][p] * H[k][p] * w;
            }
            int bias = post->denom[k] > 0 && post->yu[k];
            if (bias) {
                su[k] += post->yu[k][i];
                for (int p = 0; p < 3; p++) shu[k][p] += h[p] * post->yu[k][i];
            }
            double tk = tau[(size_t)k * (size_t)(n + 1) + (size_t)mm], y[3], g[3];
            for (int p = 0; p < 3; p++) {
                y[p] = al[p] * A[k] + H[k][p];
                g[p] = al[p] * su[k] + shu[k][p];
            }
            for (int p = 0; p < 3; p++) {
                double c = al[p] * al[p] * saa[k] + al[p] * sah[k][p] + al[p] * sah[k][p] + shh[k][p] +
                           y[p] * y[p] * tk;
                if (bias) c += g[p] * g[p] / post->denom[k];
                var[p] += c;
            }
        }
        sigma[mm] = (sasnav_pose){sqrt(fmax(var[0], 0.0)), sqrt(fmax(var[1], 0.0)), sqrt(fmax(var[2], 0.0))};
    }
    free(tau);
    return SASNAV_OK;
}
