/* The search for the displacement (paper Section III-A, procedure 1-3, and
 * docs/estimator.md, "Search"):
 *   0. global stage: the image shift of q's content against p's fixes a
 *      1-D valley of hypotheses; zeta is scanned along it, its local minima
 *      are the candidates, the best is refined by BOBYQA (NLopt) on zeta at
 *      level 0;
 *   1. zeta stage: Levenberg-Marquardt on the residual vector
 *      |psi_p| - |psi_q| (Broyden-updated Jacobian, a parabola along each
 *      step);
 *   2. eta stage: the same on psi_p - psi_q, from the zeta result and one
 *      sway fringe (lambda/2) either side when eta is lower there; then at
 *      level 2 (full pixels, final k, i) Newton steps on the quadratic
 *      model of eta measured from ten residual vectors.
 * The scan and stages 1-2 before level 2 run at the search level
 * (search_level: the coarse grid of level 0 or the full pixels of level 1,
 * opts.search_grid).
 * Steps and bounds derive from the geometry: phase-centre spacing, range and
 * wavelength. Why each choice: docs/estimator.md, "Search cost". */
#include "pair_internal.h"
#include "core/clock.h"

#include <math.h>
#include <nlopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define HW10 ((sasnav_pose){10.0, 10.0, 10.0})
/* zeta ratio of the scan's two best minima above which both are refined */
#define AMBIGUOUS 0.8

/* The level of the search stages (valley scan, zeta stage, first eta stage,
 * slip check): the coarse grid (0) or full pixels (1) as opts.search_grid
 * says, AUTO by the contrast of p's full-pixel reconstruction; full pixels
 * where there is no final stage (the search's result is then the
 * estimate). The overlap check stays at full pixels (level 1) either way. */
static int search_level(const sasnav_pair *pr)
{
    const sasnav_pair_opts *o = sasnav_pair_options(pr);
    if (o->k == o->coarse_k && o->i == o->coarse_i) return 1;
    if (o->search_grid == SASNAV_SEARCH_AUTO) return pair_contrast(pr) <= o->joint_contrast_max ? 0 : 1;
    return o->search_grid == SASNAV_SEARCH_COARSE ? 0 : 1;
}

typedef struct {
    sasnav_pair *pr;
    int level, blurred, use_eta;
    int use_prior;          /* weight by the surge prior (opts.surge_sigma) */
    int ndim;               /* 3, or 2 with the yaw held (opts.fix_yaw) */
    int joint;              /* 1: the joint misfit (pair_eval_joint) instead of zeta or eta */
    double lam;             /* its Tikhonov weight */
    sasnav_pose centre, scale;
    int rc;
    int evals;
} stage_ctx;

static sasnav_pose from_unit(const stage_ctx *c, const double *u)
{
    sasnav_pose e = {c->centre.x + c->scale.x * u[0], c->centre.y + c->scale.y * u[1],
                     c->centre.theta + (c->ndim > 2 ? c->scale.theta * u[2] : 0.0)};
    return e;
}

/* The factor 1 + (surge offset / surge_sigma)^2 of the surge prior (1
 * without one). */
static double surge_prior(const sasnav_pair *pr, sasnav_pose e)
{
    const sasnav_pair_opts *o = sasnav_pair_options(pr);
    if (!(o->surge_sigma > 0)) return 1.0;
    double u = (e.x - o->prior.x) / o->surge_sigma;
    return 1.0 + u * u;
}

static double stage_objective(unsigned n, const double *u, double *grad, void *data)
{
    stage_ctx *c = data;
    (void)n;
    (void)grad;
    if (c->rc) return HUGE_VAL;
    double zeta = 0, eta = 0;
    int rc = sasnav_pair_eval(c->pr, from_unit(c, u), c->level, c->blurred,
                              c->use_eta ? NULL : &zeta, c->use_eta ? &eta : NULL, NULL);
    c->evals++;
    if (rc) {
        c->rc = rc;
        return HUGE_VAL;
    }
    if (c->use_eta) return eta;
    return c->use_prior ? zeta * surge_prior(c->pr, from_unit(c, u)) : zeta;
}

/* Bounded local minimisation in units scaled so that one unit = one step;
 * bounds +-hw steps around the start (per axis). */
static int local_stage(stage_ctx *c, sasnav_pose start, sasnav_pose step, sasnav_pose hw,
                       double xtol_units, int max_evals, sasnav_pose *best, double *fbest)
{
    c->centre = start;
    c->scale = step;
    c->evals = 0;
    c->rc = 0;
    c->ndim = sasnav_pair_options(c->pr)->fix_yaw ? 2 : 3;
    nlopt_opt opt = nlopt_create(NLOPT_LN_BOBYQA, (unsigned)c->ndim);
    if (!opt) return sasnav_set_error(SASNAV_ERR_NOMEM, "NLopt could not create an optimiser");
    double lb[3] = {-hw.x, -hw.y, -hw.theta}, ub[3] = {hw.x, hw.y, hw.theta};
    /* Initial steps of half a unit, within the bounds (NLopt refuses a
     * step larger than the box). */
    double dx[3] = {fmin(0.5, hw.x), fmin(0.5, hw.y), fmin(0.5, hw.theta)};
    double u[3] = {0, 0, 0};
    *best = start;
    *fbest = HUGE_VAL;
    nlopt_set_lower_bounds(opt, lb);
    nlopt_set_upper_bounds(opt, ub);
    nlopt_set_initial_step(opt, dx);
    nlopt_set_min_objective(opt, stage_objective, c);
    nlopt_set_xtol_abs1(opt, xtol_units);
    nlopt_set_maxeval(opt, max_evals);
    double f = HUGE_VAL;
    nlopt_result res = nlopt_optimize(opt, u, &f);
    nlopt_destroy(opt);
    if (c->rc) return c->rc;
    if (res < 0 && res != NLOPT_ROUNDOFF_LIMITED)
        return sasnav_set_error(SASNAV_ERR_NOT_CONVERGED, "NLopt failed (code %d)", (int)res);
    *best = from_unit(c, u);
    *fbest = f;
    return res == NLOPT_MAXEVAL_REACHED ? SASNAV_ERR_NOT_CONVERGED : SASNAV_OK;
}

/* Solves the n x n (n <= 3) system M d = b by Gaussian elimination with
 * partial pivoting. Returns 0 when M is singular. */
static int solve_small(int n, double M[3][3], const double *b, double *d)
{
    double a[3][4];
    for (int i = 0; i < n; i++) {
        for (int j = 0; j < n; j++) a[i][j] = M[i][j];
        a[i][n] = b[i];
    }
    for (int c = 0; c < n; c++) {
        int p = c;
        for (int i = c + 1; i < n; i++)
            if (fabs(a[i][c]) > fabs(a[p][c])) p = i;
        if (!(fabs(a[p][c]) > 0)) return 0;
        if (p != c)
            for (int j = 0; j <= n; j++) {
                double t = a[c][j];
                a[c][j] = a[p][j];
                a[p][j] = t;
            }
        for (int i = c + 1; i < n; i++) {
            double f = a[i][c] / a[c][c];
            for (int j = c; j <= n; j++) a[i][j] -= f * a[c][j];
        }
    }
    for (int i = n - 1; i >= 0; i--) {
        double t = a[i][n];
        for (int j = i + 1; j < n; j++) t -= a[i][j] * d[j];
        d[i] = t / a[i][i];
        if (!isfinite(d[i])) return 0;
    }
    return 1;
}

/* The surge prior's factor at unit point u (1 without a prior, ps = 0). */
static double prior_factor(const stage_ctx *c, double ps, const double *u)
{
    if (!(ps > 0)) return 1.0;
    double x = (c->centre.x + c->scale.x * u[0] - sasnav_pair_options(c->pr)->prior.x) / ps;
    return 1.0 + x * x;
}

/* Shortens step d (keeping its direction per axis) to stay in the box. */
static void clip_step(int n, const double *u, double *d, const double *lb, const double *ub)
{
    for (int k = 0; k < n; k++) {
        double v = u[k] + d[k];
        v = v < lb[k] ? lb[k] : v > ub[k] ? ub[k] : v;
        d[k] = v - u[k];
    }
}

/* Residual of the stage at unit point u (evaluation counted). */
static int stage_residual(stage_ctx *c, const double *u, sasnav_cfloat *r, double *f)
{
    c->evals++;
    if (c->joint) return pair_eval_joint(c->pr, from_unit(c, u), c->lam, r, f);
    return pair_eval_residual(c->pr, from_unit(c, u), c->level, c->use_eta, r, f);
}

/* Length of the stage's residual vector. */
static size_t stage_len(const stage_ctx *c)
{
    return c->joint ? pair_joint_len(c->pr) : pair_level_points(c->pr, c->level);
}

/* Residuals at n unit points (n evaluations counted), as many at once as
 * the estimator has workers (pair_batch: point j on the estimator or one
 * of its one-thread twins, each on its own thread and with both projection
 * chains through one operator, pair.c project_chains); every residual is
 * the same bits either way. */
typedef struct {
    stage_ctx *c;
    const double (*u)[3];
    sasnav_cfloat *const *r;
    double *f;
} residuals_job;

static int residual_item(sasnav_pair *w, int j, void *ctx)
{
    residuals_job *b = ctx;
    if (b->c->joint) return pair_eval_joint(w, from_unit(b->c, b->u[j]), b->c->lam, b->r[j], &b->f[j]);
    return pair_eval_residual(w, from_unit(b->c, b->u[j]), b->c->level, b->c->use_eta, b->r[j],
                              &b->f[j]);
}

static int stage_residuals(stage_ctx *c, int n, const double (*u)[3], sasnav_cfloat *const *r,
                           double *f)
{
    c->evals += n;
    residuals_job b = {c, u, r, f};
    return pair_batch(c->pr, n, residual_item, &b);
}

/* The trial point of lm_stage becomes (dnew, unew) with residual *r1 and
 * values Fn = fn^2 P^2, fn (the buffers of the old trial and the new one
 * swap). */
static void adopt_trial(int n, double *d, double *ut, const double *dnew, const double *unew,
                        sasnav_cfloat **rt, sasnav_cfloat **r1, double *Ft, double *ft, double Fn,
                        double fn)
{
    sasnav_cfloat *sw = *rt;
    *rt = *r1;
    *r1 = sw;
    *Ft = Fn;
    *ft = fn;
    for (int k = 0; k < n; k++) {
        d[k] = dnew[k];
        ut[k] = unew[k];
    }
}

/* Levenberg-Marquardt on the residual vector of the error function
 * (docs/estimator.md, "Search cost"): eta (or zeta) is the norm of a vector
 * r(sigma) of np entries, so one forward-difference Jacobian (ndim extra
 * evaluations) gives the gradient and a Gauss-Newton model of the whole
 * bowl, where a derivative-free optimiser sees one number per evaluation.
 * After an accepted step the Jacobian is carried by a Broyden update (no
 * evaluations); a rejected step with a carried Jacobian computes a fresh
 * one. The objective is f(u)^2 P(u)^2 with P the surge prior's factor
 * (use_prior), i.e. the same minimiser as f P. Units: one unit = one step;
 * bounds +-hw units; stops when a step moves less than xtol units. */
static int lm_stage(stage_ctx *c, sasnav_pose start, sasnav_pose step, sasnav_pose hw,
                    double xtol, int max_evals, sasnav_pose *best, double *fbest)
{
    sasnav_pair *pr = c->pr;
    const sasnav_pair_opts *o = sasnav_pair_options(pr);
    c->centre = start;
    c->scale = step;
    c->evals = 0;
    c->rc = 0;
    c->ndim = o->fix_yaw ? 2 : 3;
    const int n = c->ndim;
    const size_t np = pair_level_points(pr, c->level);
    sasnav_cfloat *buf = malloc(sizeof(sasnav_cfloat) * np * (size_t)(n + 3));
    if (!buf) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory in the local search");
    sasnav_cfloat *r0 = buf, *rt = buf + np, *r1 = buf + 2 * np;
    sasnav_cfloat *J[3] = {buf + 3 * np, buf + 4 * np, n > 2 ? buf + 5 * np : NULL};
    double lb[3] = {-hw.x, -hw.y, -hw.theta}, ub[3] = {hw.x, hw.y, hw.theta};
    double u[3] = {0, 0, 0}, f0 = 0, ft = 0;
    /* The surge prior's factor P = 1 + ((x - prior) / s)^2 along unit 0. */
    double ps = c->use_prior && o->surge_sigma > 0 ? o->surge_sigma : 0;
    const double h = 0.1; /* forward-difference step, units */
    int rc = stage_residual(c, u, r0, &f0);
    int have_j = 0, fresh = 0, rejects = 0;
    double mu = 1e-3;
    while (!rc && c->evals < max_evals) {
        if (!have_j) {
            /* the n forward differences at once (stage_residuals), into J */
            double ut[3][3], hk[3], fk[3];
            for (int k = 0; k < n; k++) {
                for (int m = 0; m < 3; m++) ut[k][m] = u[m];
                hk[k] = u[k] + h <= ub[k] ? h : -h;
                ut[k][k] += hk[k];
            }
            rc = stage_residuals(c, n, (const double(*)[3])ut, J, fk);
            if (rc) break;
            for (int k = 0; k < n; k++)
                for (size_t j = 0; j < np; j++) J[k][j] = (J[k][j] - r0[j]) / (float)hk[k];
            have_j = fresh = 1;
        }
        /* Normal equations of the model |r0 + J d|^2 P^2 (double). */
        double A[3][3] = {{0}}, g[3] = {0}, S = 0;
        for (int k = 0; k < n; k++) {
            double gk = 0;
            for (size_t j = 0; j < np; j++)
                gk += (double)crealf(J[k][j]) * crealf(r0[j]) + (double)cimagf(J[k][j]) * cimagf(r0[j]);
            g[k] = gk;
            for (int m = 0; m <= k; m++) {
                double a = 0;
                for (size_t j = 0; j < np; j++)
                    a += (double)crealf(J[k][j]) * crealf(J[m][j]) + (double)cimagf(J[k][j]) * cimagf(J[m][j]);
                A[k][m] = A[m][k] = a;
            }
        }
        for (size_t j = 0; j < np; j++)
            S += (double)crealf(r0[j]) * crealf(r0[j]) + (double)cimagf(r0[j]) * cimagf(r0[j]);
        double P = prior_factor(c, ps, u), dP = 0, d2P = 0;
        if (ps > 0) {
            double x = (c->centre.x + c->scale.x * u[0] - o->prior.x) / ps;
            dP = 2 * x * c->scale.x / ps;
            d2P = 2 * c->scale.x * c->scale.x / (ps * ps);
        }
        /* F = S W, W = P^2: grad F = 2 W g + S W' e0, Hess ~ 2 W A +
         * 2 (g W' e0^T + e0 W' g^T) + S W'' e0 e0^T. */
        double W = P * P, W1 = 2 * P * dP, W2 = 2 * (dP * dP + P * d2P);
        double H[3][3], G[3];
        for (int k = 0; k < n; k++) {
            G[k] = 2 * W * g[k] + (k == 0 ? S * W1 : 0);
            for (int m = 0; m < n; m++) H[k][m] = 2 * W * A[k][m];
        }
        if (ps > 0) {
            for (int k = 0; k < n; k++) {
                H[k][0] += 2 * g[k] * W1;
                H[0][k] += 2 * g[k] * W1;
            }
            H[0][0] += S * W2;
        }
        double d[3] = {0, 0, 0}, M[3][3], mb[3];
        for (int k = 0; k < n; k++) {
            for (int m = 0; m < n; m++) M[k][m] = H[k][m];
            M[k][k] += mu * (fabs(H[k][k]) + 1e-12 * (fabs(H[0][0]) + 1e-300));
            mb[k] = -G[k];
        }
        if (!solve_small(n, M, mb, d)) {
            mu *= 10;
            if (mu > 1e8) break;
            continue;
        }
        clip_step(n, u, d, lb, ub);
        double dmax = 0, slope = 0;
        for (int k = 0; k < n; k++) {
            dmax = fabs(d[k]) > dmax ? fabs(d[k]) : dmax;
            slope += G[k] * d[k];
        }
        if (dmax < 1e-6 || !(slope < 0)) {
            if (fresh) break;
            have_j = 0;
            continue;
        }
        double F0 = f0 * f0 * W;
        double ut[3] = {u[0] + d[0], u[1] + d[1], u[2] + d[2]};
        rc = stage_residual(c, ut, rt, &ft);
        if (rc) break;
        double Ft = ft * prior_factor(c, ps, ut);
        Ft *= Ft;
        /* The model's curvature along d is that of |J d|^2 only (no second
         * derivatives of r): along the flat surge-yaw valley the steps fall
         * short (each ~60 % of the way on paper-pair). A parabola through
         * F0, F(d) and F(2d) (or the slope, when F(d) is not lower) decides
         * how far to go along d. */
        double t = 1.0, F2 = HUGE_VAL;
        if (Ft < F0) {
            double d2[3] = {2 * d[0], 2 * d[1], 2 * d[2]};
            clip_step(n, u, d2, lb, ub);
            double u2[3] = {u[0] + d2[0], u[1] + d2[1], u[2] + d2[2]}, f2 = 0;
            rc = stage_residual(c, u2, r1, &f2);
            if (rc) break;
            F2 = f2 * prior_factor(c, ps, u2);
            F2 *= F2;
            /* parabola through t = 0, 1, 2 */
            double a2 = 0.5 * (F2 - 2 * Ft + F0), a1 = Ft - F0 - a2;
            t = a2 > 0 ? -a1 / (2 * a2) : 2.0;
            t = t > 4.0 ? 4.0 : t < 0.25 ? 0.25 : t;
            if (F2 < Ft) {
                /* F(2d) is the best point so far: move the trial there; the
                 * parabola's vertex, when it says more, is tried next. */
                t = a2 > 0 && fabs(t - 2) > 0.25 ? t / 2 : 1.0;
                adopt_trial(n, d, ut, d2, u2, &rt, &r1, &Ft, &ft, F2, f2);
            }
        } else {
            double curv = Ft - F0 - slope;
            t = curv > 0 ? -slope / (2 * curv) : 0.5;
        }
        if (fabs(t - 1.0) > 0.2 && t > 0.05) {
            double dt[3] = {t * d[0], t * d[1], t * d[2]};
            clip_step(n, u, dt, lb, ub);
            double uq[3] = {u[0] + dt[0], u[1] + dt[1], u[2] + dt[2]}, fq = 0;
            rc = stage_residual(c, uq, r1, &fq);
            if (rc) break;
            double Fq = fq * prior_factor(c, ps, uq);
            Fq *= Fq;
            if (Fq < Ft) adopt_trial(n, d, ut, dt, uq, &rt, &r1, &Ft, &ft, Fq, fq);
        }
        dmax = 0;
        for (int k = 0; k < n; k++) dmax = fabs(d[k]) > dmax ? fabs(d[k]) : dmax;
        if (Ft < F0) {
            /* Broyden update J += (r_t - r0 - J d) d^T / |d|^2, then move. */
            double dd = 0;
            for (int k = 0; k < n; k++) dd += d[k] * d[k];
            for (size_t j = 0; j < np; j++) {
                sasnav_cfloat jd = 0;
                for (int k = 0; k < n; k++) jd += J[k][j] * (float)d[k];
                sasnav_cfloat e = rt[j] - r0[j] - jd;
                for (int k = 0; k < n; k++) J[k][j] += e * (float)(d[k] / dd);
            }
            sasnav_cfloat *sw = r0;
            r0 = rt;
            rt = sw;
            for (int k = 0; k < n; k++) u[k] = ut[k];
            f0 = ft;
            fresh = 0;
            rejects = 0;
            mu = mu / 3 > 1e-6 ? mu / 3 : 1e-6;
            if (dmax < xtol) break;
        } else {
            if (++rejects > 4) break;
            if (fresh) {
                if (dmax < xtol) break; /* even a short step fails: at the minimum */
                mu *= 4;
            } else {
                have_j = 0; /* the carried Jacobian misled: a fresh one at u */
            }
        }
    }
    free(buf);
    if (rc) return rc;
    *best = from_unit(c, u);
    *fbest = f0 * prior_factor(c, ps, u);
    return c->evals >= max_evals ? SASNAV_ERR_NOT_CONVERGED : SASNAV_OK;
}

/* Re sum conj(a) b (double accumulation). */
static double redot(const sasnav_cfloat *a, const sasnav_cfloat *b, size_t n)
{
    double s = 0;
    for (size_t j = 0; j < n; j++)
        s += (double)crealf(a[j]) * crealf(b[j]) + (double)cimagf(a[j]) * cimagf(b[j]);
    return s;
}

/* Newton stage on f^2 (f = eta at the context's level) from `start`, on a
 * quadratic model of the residual VECTOR measured around an anchor (units
 * of `unit`): r at the anchor, anchor +- h e_k and anchor + h (e_k + e_m),
 * 1 + 2n + n(n-1)/2 evaluations (10 in 3-D), give
 *   r(u) ~ r0 + J u + 1/2 R[u, u]
 * with J by central differences and the second derivatives R_kk, R_km.
 * At a point u of the model, with the true residual r there, the gradient
 * of f^2 is 2 Re(J(u)^H r) and its Hessian 2 Re(J(u)^H J(u) + r^H R),
 * J(u) = J + R u: the second-order part is what a Gauss-Newton model leaves
 * out, and it is large here (eta ~0.3 at the minimum; without it the steps
 * along the flat surge-yaw valley fall 40 % short each time,
 * docs/estimator.md). Each Newton step costs one evaluation (its true
 * residual re-anchors the gradient); steps stop below `xtol` units or after
 * `max_steps`. When the estimate has moved more than `far` units from the
 * anchor, the model is measured again there (up to `rounds` models). A
 * step below `xtol` is the last and is taken on the model (not evaluated);
 * *measured is then the point before it, the last one evaluated. 11
 * evaluations on most pairs. */
static int newton_stage(stage_ctx *c, sasnav_pose start, sasnav_pose unit, double h, double far,
                        int rounds, double xtol, int max_steps, sasnav_pose *best, double *fbest,
                        sasnav_pose *measured)
{
    const sasnav_pair_opts *o = sasnav_pair_options(c->pr);
    const int n = o->fix_yaw ? 2 : 3;
    const size_t np = stage_len(c);
    static const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
    const int npair = n * (n - 1) / 2;
    const int nv = 1 + 2 * n + npair + n + 2; /* model, J(u), r, trial r */
    c->evals = 0;
    c->rc = 0;
    c->ndim = n;
    c->scale = unit;
    sasnav_cfloat *buf = malloc(sizeof(sasnav_cfloat) * np * (size_t)nv);
    if (!buf) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory in the local search");
    sasnav_cfloat *r0 = buf, *J[3], *Rd[3], *Rx[3], *Ju[3], *r = buf + np * (size_t)(nv - 2),
                  *rt = buf + np * (size_t)(nv - 1);
    for (int k = 0; k < n; k++) {
        J[k] = buf + np * (size_t)(1 + 2 * k);
        Rd[k] = buf + np * (size_t)(2 + 2 * k);
        Ju[k] = buf + np * (size_t)(1 + 2 * n + npair + k);
    }
    for (int q = 0; q < npair; q++) Rx[q] = buf + np * (size_t)(1 + 2 * n + q);
    sasnav_pose at = start, last = start;
    double fat = HUGE_VAL;
    int rc = SASNAV_OK;
    for (int round = 0; round < rounds && !rc; round++) {
        /* Measure the model around the anchor `at`. */
        c->centre = at;
        /* the model's points: the anchor, +-h e_k, h (e_k + e_m); all at
         * once (stage_residuals) */
        double um[10][3] = {{0}}, fm[10];
        sasnav_cfloat *rm[10];
        int nm = 0;
        rm[nm++] = r0;
        for (int k = 0; k < n; k++) {
            um[nm][k] = h;
            rm[nm++] = J[k]; /* r(+h e_k), for now */
            um[nm][k] = -h;
            rm[nm++] = Rd[k]; /* r(-h e_k) */
        }
        for (int q = 0; q < npair; q++) {
            um[nm][pairs[q][0]] = h;
            um[nm][pairs[q][1]] = h;
            rm[nm++] = Rx[q];
        }
        rc = stage_residuals(c, nm, (const double(*)[3])um, rm, fm);
        if (rc) break;
        fat = fm[0];
        const float ih2 = (float)(1.0 / (h * h)), i2h = (float)(0.5 / h);
        /* R_km = (r(h, h) - r(h, 0) - r(0, h) + r0) / h^2, before r(+h e_k)
         * becomes J_k. */
        for (int q = 0; q < npair; q++) {
            int k = pairs[q][0], m = pairs[q][1];
            for (size_t j = 0; j < np; j++) Rx[q][j] = (Rx[q][j] - J[k][j] - J[m][j] + r0[j]) * ih2;
        }
        for (int k = 0; k < n; k++)
            for (size_t j = 0; j < np; j++) {
                sasnav_cfloat p = J[k][j], m = Rd[k][j];
                J[k][j] = (p - m) * i2h;
                Rd[k][j] = (p + m - 2.0f * r0[j]) * ih2;
            }
        /* Newton steps on the model from the anchor. */
        double u[3] = {0, 0, 0}, fu = fat;
        int model_step = 0;
        memcpy(r, r0, sizeof(sasnav_cfloat) * np);
        int moved_far = 0;
        for (int step = 0; step < max_steps; step++) {
            /* J(u) = J + R u */
            for (int k = 0; k < n; k++)
                for (size_t j = 0; j < np; j++) {
                    sasnav_cfloat v = J[k][j] + Rd[k][j] * (float)u[k];
                    for (int q = 0; q < npair; q++) {
                        int a = pairs[q][0], b = pairs[q][1];
                        if (a == k) v += Rx[q][j] * (float)u[b];
                        else if (b == k) v += Rx[q][j] * (float)u[a];
                    }
                    Ju[k][j] = v;
                }
            double G[3] = {0, 0, 0}, H[3][3], A[3][3], S[3][3];
            for (int k = 0; k < n; k++) {
                G[k] = 2 * redot(Ju[k], r, np);
                for (int m = 0; m <= k; m++) A[k][m] = A[m][k] = 2 * redot(Ju[k], Ju[m], np);
                S[k][k] = 2 * redot(r, Rd[k], np);
            }
            for (int q = 0; q < npair; q++) {
                int k = pairs[q][0], m = pairs[q][1];
                S[k][m] = S[m][k] = 2 * redot(r, Rx[q], np);
            }
            for (int k = 0; k < n; k++)
                for (int m = 0; m < n; m++) H[k][m] = A[k][m] + S[k][m];
            /* Newton step; where the model is not convex along it, the
             * Gauss-Newton step (second-order part dropped). */
            double d[3] = {0, 0, 0}, mb[3] = {-G[0], -G[1], -G[2]}, slope = 0;
            double (*M)[3] = H;
            int ok = solve_small(n, H, mb, d);
            for (int k = 0; k < n; k++) slope += G[k] * d[k];
            if (!ok || !(slope < 0)) {
                M = A;
                ok = solve_small(n, A, mb, d);
                slope = 0;
                for (int k = 0; k < n; k++) slope += G[k] * d[k];
                if (!ok || !(slope < 0)) break;
            }
            /* Within the stage's box of +-10 units around `start`. */
            double lb[3], ub[3], uu[3];
            for (int k = 0; k < 3; k++) {
                double off = k == 0 ? (at.x - start.x) / unit.x : k == 1 ? (at.y - start.y) / unit.y
                                                                         : (at.theta - start.theta) / unit.theta;
                lb[k] = -10 - off;
                ub[k] = 10 - off;
            }
            clip_step(n, u, d, lb, ub);
            double dmax = 0;
            for (int k = 0; k < n; k++) dmax = fabs(d[k]) > dmax ? fabs(d[k]) : dmax;
            if (dmax < 1e-9) break;
            if (dmax < xtol) {
                /* The last step, below the tolerance: taken on the model
                 * without an evaluation of its own (where f^2 decreases on
                 * it: G d + d^T M d / 2, M the matrix of the step). Before,
                 * it was evaluated and then the steps stopped, so the
                 * estimate is the same; f is the model's there, a change of
                 * second order in a step this small (docs/estimator.md,
                 * "The last Newton step on the model"). */
                double q = 0;
                for (int k = 0; k < n; k++) {
                    q += G[k] * d[k];
                    for (int m = 0; m < n; m++) q += 0.5 * d[k] * M[k][m] * d[m];
                }
                if (q < 0 && fu * fu + q > 0) {
                    last = from_unit(c, u);
                    for (int k = 0; k < 3; k++) u[k] += d[k];
                    fu = sqrt(fu * fu + q);
                    model_step = 1;
                    break;
                }
            }
            int accepted = 0;
            for (int half = 0; half < 2 && !accepted; half++) {
                for (int k = 0; k < 3; k++) uu[k] = u[k] + d[k];
                double ft;
                rc = stage_residual(c, uu, rt, &ft);
                if (rc) break;
                if (ft < fu) {
                    sasnav_cfloat *sw = r;
                    r = rt;
                    rt = sw;
                    memcpy(u, uu, sizeof u);
                    fu = ft;
                    accepted = 1;
                } else {
                    for (int k = 0; k < 3; k++) d[k] *= 0.5;
                    dmax *= 0.5;
                }
            }
            if (rc || !accepted) break;
            double umax = 0;
            for (int k = 0; k < n; k++) umax = fabs(u[k]) > umax ? fabs(u[k]) : umax;
            if (umax > far) {
                moved_far = 1;
                break;
            }
            if (dmax < xtol) break;
        }
        at = from_unit(c, u);
        if (!model_step) last = at;
        fat = fu;
        if (!moved_far) break;
    }
    free(buf);
    if (rc) return rc;
    *best = at;
    *fbest = fat;
    if (measured) *measured = last;
    return SASNAV_OK;
}

/* Global stage (docs/estimator.md). The moduli of p's and q's images are
 * alike up to a shift of the scene content: a cross-correlation at the
 * prior measures it, and for any candidate yaw the shift fixes the
 * translation exactly (the image of q's data made with pose Q_h shows a
 * scene point z at Q_h Q_t^-1 z, Q_t the true pose). This leaves a 1-D
 * family ("valley": surge ~ -R yaw) that zeta scans; then the best point is
 * refined locally. */
static sasnav_pose valley_point(const sasnav_pair *pr, sasnav_pose hyp_disp, double zx, double zy,
                                double sx, double sy, double theta_t)
{
    const sasnav_pose nominal = pr->nominal;
    double wx, wy;
    sasnav_pose_apply(sasnav_pose_inverse(hyp_disp), zx + sx, zy + sy, &wx, &wy);
    double c = cos(theta_t), s = sin(theta_t);
    sasnav_pose disp = {zx - (c * wx - s * wy), zy - (s * wx + c * wy), theta_t};
    sasnav_pose e = {disp.x - nominal.x, disp.y - nominal.y, disp.theta - nominal.theta};
    return e;
}

/* A local minimum of the valley scan. */
typedef struct {
    sasnav_pose e;
    double zeta, score;
} scan_min;

/* The valley scan's zeta at es[at[j]] into zs[at[j]] (pair_batch). */
typedef struct {
    const sasnav_pose *es;
    double *zs;
    int *at, n;
} scan_job;

static int scan_item(sasnav_pair *w, int j, void *ctx)
{
    scan_job *b = ctx;
    int k = b->at[j];
    return sasnav_pair_eval(w, b->es[k], search_level(w), 0, &b->zs[k], NULL, NULL);
}

/* The global stage's shift at yaw hypothesis j (pair_batch): the shift
 * at the hypothesis, then a second pass at its point of the valley, whose
 * correlation peak is the hypothesis's score; ok[j] = 0 where a point
 * falls outside the box. */
typedef struct {
    sasnav_pose c, box;
    double ystep, zx, zy;
    int ny_h;
    sasnav_pose *v2;
    double *peak;
    int *ok;
} shift_job;

static int shift_item(sasnav_pair *w, int j, void *ctx)
{
    shift_job *b = ctx;
    sasnav_pose c = b->c, box = b->box;
    b->ok[j] = 0;
    sasnav_pose h0 = {c.x, c.y, c.theta + (j - b->ny_h) * b->ystep};
    double sx, sy, peak;
    int rc = pair_image_shift(w, 0, h0, &sx, &sy, &peak);
    if (rc) return rc;
    sasnav_pose hd0 = {w->nominal.x + h0.x, w->nominal.y + h0.y, w->nominal.theta + h0.theta};
    sasnav_pose v = valley_point(w, hd0, b->zx, b->zy, sx, sy, w->nominal.theta + h0.theta);
    if (fabs(v.x - c.x) > box.x || fabs(v.y - c.y) > box.y) return SASNAV_OK;
    /* The second pass at the valley point: there the two images align
     * when the hypothesis's yaw is right, and their correlation is the
     * hypothesis's score. */
    if ((rc = pair_image_shift(w, 0, v, &sx, &sy, &peak))) return rc;
    sasnav_pose hv = {w->nominal.x + v.x, w->nominal.y + v.y, w->nominal.theta + v.theta};
    sasnav_pose v2 = valley_point(w, hv, b->zx, b->zy, sx, sy, w->nominal.theta + v.theta);
    if (fabs(v2.x - c.x) > box.x || fabs(v2.y - c.y) > box.y) return SASNAV_OK;
    b->v2[j] = v2;
    b->peak[j] = peak;
    b->ok[j] = 1;
    return SASNAV_OK;
}

static int global_stage(sasnav_pair *pr, double pc_spacing, sasnav_pose *best, int *evals,
                        double *ambiguity, scan_min *mins, int *n_mins)
{
    const sasnav_pair_opts *o = sasnav_pair_options(pr);
    const pair_level *lv = &pr->level[0];
    sasnav_pose c = o->prior, b = o->box;
    double zx = lv->grid.x0 + 0.5 * (lv->grid.nx - 1) * lv->grid.dx;
    double zy = lv->grid.y0 + 0.5 * (lv->grid.ny - 1) * lv->grid.dy;
    int n = 0, rc;
    sasnav_pose hyp = c;
    (void)0;
    double sx = 0, sy = 0;
    /* The image shift at one yaw hypothesis fixes the valley only when the
     * two images correlate: a yaw error of the hypothesis of more than
     * about 5e-3 rad (a 5 cm rotation of the scene across a 1.6 m grid at
     * 10 m) decorrelates their moduli, and the peak then comes from the
     * beam-pattern envelopes the two images share (near zero shift). So the
     * shift is measured at yaw hypotheses every `ystep` over the box and
     * the one whose moduli correlate best gives the valley; then a second
     * pass at that hypothesis's point of the valley removes most of the
     * translation's distortion. docs/estimator.md, "Global stage". */
    double ystep = 0.004;
    int ny_h = o->fix_yaw ? 0 : (int)floor(b.theta / ystep);
    if (ny_h > 50) ny_h = 50;
    double best_peak = -HUGE_VAL;
    sasnav_pose best_hyp = c;
    /* The hypotheses are independent: measured side by side on the
     * workers (pair_batch), then taken in order. */
    int nh = 2 * ny_h + 1;
    shift_job sj = {c, b, ystep, zx, zy, ny_h, malloc(sizeof(sasnav_pose) * (size_t)nh),
                    malloc(sizeof(double) * (size_t)nh), malloc(sizeof(int) * (size_t)nh)};
    if (!sj.v2 || !sj.peak || !sj.ok) {
        free(sj.v2);
        free(sj.peak);
        free(sj.ok);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory in the global stage");
    }
    rc = pair_batch(pr, nh, shift_item, &sj);
    for (int j = 0; j < nh && !rc; j++)
        if (sj.ok[j] && sj.peak[j] > best_peak) {
            best_peak = sj.peak[j];
            best_hyp = sj.v2[j];
        }
    free(sj.v2);
    free(sj.peak);
    free(sj.ok);
    if (rc) return rc;
    hyp = best_hyp;
    sasnav_pose hd = {pr->nominal.x + hyp.x, pr->nominal.y + hyp.y, pr->nominal.theta + hyp.theta};
    if ((rc = pair_image_shift(pr, 0, hyp, &sx, &sy, NULL))) return rc;
    /* Scan the valley (with the yaw held: its single point at the prior
     * yaw) in yaw steps that move the scene by half a
     * phase-centre spacing at the grid's range: the valley's ambiguous
     * minima (one spacing of surge, spacing / R of yaw apart) are then
     * sampled at least twice per period whatever the prior. */
    double step = 0.5 * pc_spacing / o->range;
    int nt = o->fix_yaw ? 0 : (int)ceil(b.theta / step);
    if (nt > 2000) nt = 2000;
    /* With the yaw held the comb lies along surge itself (a phase-centre
     * spacing apart): scan surge in quarter spacings over the box instead. */
    double sstep = 0.25 * pc_spacing;
    if (o->fix_yaw) {
        nt = (int)ceil(b.x / sstep);
        if (nt > 2000) nt = 2000;
    }
    int ns = 2 * nt + 1;
    double *zs = malloc(sizeof(double) * (size_t)ns);
    sasnav_pose *es = malloc(sizeof(sasnav_pose) * (size_t)ns);
    scan_job job = {es, zs, malloc(sizeof(int) * (size_t)ns), 0};
    if (!zs || !es || !job.at) {
        free(zs);
        free(es);
        free(job.at);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory in the valley scan");
    }
    for (int it = -nt; it <= nt; it++) {
        sasnav_pose e;
        if (o->fix_yaw) {
            e = valley_point(pr, hd, zx, zy, sx, sy, pr->nominal.theta + c.theta);
            e.x = c.x + it * sstep;
        } else {
            double theta_t = pr->nominal.theta + c.theta + (nt > 0 ? it * b.theta / nt : 0.0);
            e = valley_point(pr, hd, zx, zy, sx, sy, theta_t);
        }
        zs[it + nt] = HUGE_VAL;
        es[it + nt] = e;
        if (!(fabs(e.x - c.x) > b.x || fabs(e.y - c.y) > b.y)) job.at[job.n++] = it + nt;
    }
    /* zeta at the scan's points in the box, as many at once as the
     * estimator has workers (the same values either way) */
    rc = pair_batch(pr, job.n, scan_item, &job);
    /* The refinement below starts at a scanned point: kept on pr only when
     * pr scanned it (one worker), so forget the scan for equal counts. */
    pair_forget(pr, search_level(pr));
    free(job.at);
    if (rc) {
        free(zs);
        free(es);
        return rc;
    }
    n += job.n;
    /* The candidates are the local minima of the scan's zeta weighted by
     * the priors: 1 + (yaw offset / yaw_sigma)^2 and 1 + (surge offset /
     * surge_sigma)^2 (each where given). The ratio of the two lowest minima
     * of zeta itself measures how well the data alone resolve the valley. */
    double z1 = HUGE_VAL, z2 = HUGE_VAL;
    double *score = malloc(sizeof(double) * (size_t)ns);
    if (!score) {
        free(zs);
        free(es);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory in the valley scan");
    }
    for (int j = 0; j < ns; j++) {
        score[j] = zs[j];
        if (!(zs[j] < HUGE_VAL)) continue;
        if (o->yaw_sigma > 0) {
            double u = (es[j].theta - c.theta) / o->yaw_sigma;
            score[j] *= 1.0 + u * u;
        }
        score[j] *= surge_prior(pr, es[j]);
    }
    /* The local minima of the score, lowest first (insertion into the
     * short sorted list). */
    int nm = 0;
    for (int j = 0; j < ns; j++) {
        if (!(zs[j] < HUGE_VAL)) continue;
        if (!((j > 0 && score[j - 1] < score[j]) || (j + 1 < ns && score[j + 1] <= score[j]))) {
            scan_min m = {es[j], zs[j], score[j]};
            int at = nm < SASNAV_PAIR_SCAN_CANDIDATES ? nm : SASNAV_PAIR_SCAN_CANDIDATES;
            while (at > 0 && mins[at - 1].score > m.score) {
                if (at < SASNAV_PAIR_SCAN_CANDIDATES) mins[at] = mins[at - 1];
                at--;
            }
            if (at < SASNAV_PAIR_SCAN_CANDIDATES) {
                mins[at] = m;
                if (nm < SASNAV_PAIR_SCAN_CANDIDATES) nm++;
            }
        }
        if ((j > 0 && zs[j - 1] < zs[j]) || (j + 1 < ns && zs[j + 1] <= zs[j])) continue;
        if (zs[j] < z1) {
            z2 = z1;
            z1 = zs[j];
        } else if (zs[j] < z2) {
            z2 = zs[j];
        }
    }
    free(score);
    free(zs);
    free(es);
    *ambiguity = z2 < HUGE_VAL && z2 > 0 ? z1 / z2 : 0.0;
    *n_mins = nm;
    sasnav_pose arg = nm > 0 ? mins[0].e : hyp;
    double fbest = nm > 0 ? mins[0].zeta : HUGE_VAL;
    /* Local refinement of zeta at level 0 around the best valley point. */
    stage_ctx ctx = {.pr = pr, .level = 0, .use_prior = 1};
    sasnav_pose unit = {pc_spacing, pc_spacing, pc_spacing / o->range};
    sasnav_pose refined = arg;
    double fr = HUGE_VAL;
    /* Bounds: 2 units in sway, half a unit along surge and yaw so that the
     * refinement stays with the chosen candidate of the valley. */
    sasnav_pose hw = {o->fix_yaw ? sstep / pc_spacing : 0.5, 2.0, 0.5};
    rc = local_stage(&ctx, arg, unit, hw, 0.02, o->max_evaluations, &refined, &fr);
    n += ctx.evals;
    if (rc && rc != SASNAV_ERR_NOT_CONVERGED) return rc;
    *best = fr < fbest * surge_prior(pr, arg) ? refined : arg;
    *evals = n;
    return SASNAV_OK;
}

typedef struct {
    sasnav_pose zeta_stage, error;
    double zeta, eta;
    int evaluations_zeta, evaluations_eta, evaluations_final, zrc, erc;
    double seconds_zeta, seconds_eta, seconds_final;
    long applications_zeta, applications_eta, applications_final;
    int final_criterion; /* the final stage's: SASNAV_FINAL_ETA or _JOINT */
    int joint_rejected;  /* the joint stage ran and eta rejected its estimate */
    sasnav_pose measured; /* the final stage's last evaluated point (its
                             overlap); `error` unless its last step was
                             taken on the model */
} refine_out;

/* Stage 1 and the search-level part of stage 2 from `start` (a global-stage
 * candidate). */
static int refine(sasnav_pair *pr, sasnav_pose start, double pc_spacing, refine_out *out)
{
    const sasnav_pair_opts *o = sasnav_pair_options(pr);
    double lambda = sasnav_wavelength(&pr->sys), range = o->range;
    int rc;
    memset(out, 0, sizeof *out);
    double t = sasnav_now_seconds();
    long apps = sasnav_pair_applications(pr);
    /* Zeta stage (search level, coarse iterations): steps of a
     * fifth of a phase-centre spacing in surge and sway, and the yaw that
     * moves the scene by as much at the grid's range. */
    /* With a surge prior the stage minimises zeta times its factor, so that
     * it stays with the candidate the global stage chose; the zeta reported
     * is the data's. */
    stage_ctx ctx = {.pr = pr, .level = search_level(pr), .use_prior = 1};
    sasnav_pose zstep = {0.2 * pc_spacing, 0.2 * pc_spacing, 0.2 * pc_spacing / range};
    sasnav_pose zbest;
    double zval;
    int zrc = lm_stage(&ctx, start, zstep, HW10, 0.05, o->max_evaluations, &zbest, &zval);
    out->evaluations_zeta = ctx.evals;
    out->zrc = zrc;
    if (zrc && zrc != SASNAV_ERR_NOT_CONVERGED) return zrc;
    out->zeta_stage = zbest;
    zval /= surge_prior(pr, zbest); /* the data's zeta (factor 1 without a prior) */
    out->zeta = zval;
    out->seconds_zeta = sasnav_now_seconds() - t;
    out->applications_zeta = sasnav_pair_applications(pr) - apps;
    t = sasnav_now_seconds();
    apps = sasnav_pair_applications(pr);

    /* Eta stage, first at the search level then at level 2 (final k, i): units of
     * lambda/40 in sway (bounds +-lambda/4: one fringe), a 25th of the
     * phase-centre spacing in surge and twice the matching yaw (bounds +-10
     * units). The fringes either side of the zeta result are tried too and
     * kept when eta is lower there. */
    ctx.use_eta = 1;
    ctx.use_prior = 0;
    sasnav_pose estep = {pc_spacing / 25.0, lambda / 40.0, 2.0 * pc_spacing / 25.0 / range};
    sasnav_pose best = zbest;
    double fbest = HUGE_VAL;
    int erc = SASNAV_OK, nevals = 0;
    for (int fringe = 0; fringe < 3; fringe++) {
        sasnav_pose s0 = zbest;
        s0.y += (fringe == 0 ? 0.0 : fringe == 1 ? -0.5 : 0.5) * lambda;
        if (fringe > 0) {
            double e0;
            rc = sasnav_pair_eval(pr, s0, ctx.level, 0, NULL, &e0, NULL);
            nevals++;
            if (rc) return rc;
            if (!(e0 < fbest)) continue;
        }
        sasnav_pose b = s0;
        double f = HUGE_VAL;
        /* 0.05 units (50 microns of surge, 6 of sway): level 2 moves the
         * estimate further than that anyway. */
        int r = lm_stage(&ctx, s0, estep, HW10, 0.05, o->max_evaluations, &b, &f);
        nevals += ctx.evals;
        if (r && r != SASNAV_ERR_NOT_CONVERGED) return r;
        if (f < fbest) {
            fbest = f;
            best = b;
            erc = r;
        }
    }
    out->seconds_eta = sasnav_now_seconds() - t;
    out->applications_eta = sasnav_pair_applications(pr) - apps;
    out->evaluations_eta = nevals;
    out->eta = fbest;
    out->error = best;
    out->erc = erc;
    return SASNAV_OK;
}

/* The search-level eta stage alone from `start` (the slip check's neighbours of
 * the chosen candidate). */
static int refine_eta(sasnav_pair *pr, sasnav_pose start, double pc_spacing, refine_out *out)
{
    const sasnav_pair_opts *o = sasnav_pair_options(pr);
    double lambda = sasnav_wavelength(&pr->sys), range = o->range;
    memset(out, 0, sizeof *out);
    double t = sasnav_now_seconds();
    long apps = sasnav_pair_applications(pr);
    stage_ctx ctx = {.pr = pr, .level = search_level(pr), .use_eta = 1};
    sasnav_pose estep = {pc_spacing / 25.0, lambda / 40.0, 2.0 * pc_spacing / 25.0 / range};
    sasnav_pose b = start;
    double f = HUGE_VAL;
    int r = lm_stage(&ctx, start, estep, HW10, 0.05, o->max_evaluations, &b, &f);
    if (r && r != SASNAV_ERR_NOT_CONVERGED) return r;
    out->zeta_stage = start;
    out->zeta = NAN;
    out->eta = f;
    out->error = b;
    out->erc = r;
    out->evaluations_eta = ctx.evals;
    out->seconds_eta = sasnav_now_seconds() - t;
    out->applications_eta = sasnav_pair_applications(pr) - apps;
    return SASNAV_OK;
}

/* The final stage at level 2 (k, i) from the search-level eta result in `out`:
 * Newton steps on the measured quadratic model, in half the eta units,
 * differences of half a unit (0.25 mm of surge, 31 microns of sway, 5e-5
 * rad), until a step is below 0.1 unit (50 microns of surge) or after 4
 * steps; a new model when the estimate moves more than 4 units (2 mm of
 * surge) from where the model was measured. */
static int refine_final(sasnav_pair *pr, double pc_spacing, refine_out *out)
{
    const sasnav_pair_opts *o = sasnav_pair_options(pr);
    out->measured = out->error;
    if (o->k == o->coarse_k && o->i == o->coarse_i) return SASNAV_OK;
    double lambda = sasnav_wavelength(&pr->sys), t = sasnav_now_seconds();
    long apps = sasnav_pair_applications(pr);
    stage_ctx ctx = {.pr = pr, .level = 2, .use_eta = 1};
    sasnav_pose fstep = {pc_spacing / 50.0, lambda / 80.0, pc_spacing / 25.0 / o->range};
    sasnav_pose b = out->error, m = b;
    double f = out->eta;
    int rc = SASNAV_OK, joint = o->final_criterion == SASNAV_FINAL_JOINT;
    if (o->final_criterion == SASNAV_FINAL_AUTO && !o->gpu) {
        /* The joint misfit when the two beams' footprints at the grid's
         * range are shifted by at most joint_shift_max of the grid's
         * along-track extent by the pings' relative yaw: beyond that its
         * bias from the echoes of the seabed off the grid grows past eta's
         * (docs/estimator.md, "A joint-misfit final stage"); and only on
         * a speckle-like scene (the joint misfit's white Gaussian scene):
         * on a few bright reflectors (the tank) it biases the surge. Not on the
         * GPU path: the joint misfit has no device implementation, and on
         * the CPU it would cost more than eta's stage on the device. */
        const sasnav_grid *g = sasnav_pair_grid(pr);
        double yaw = pr->nominal.theta + out->error.theta;
        double along = (g->nx - 1) * g->dx;
        /* ... and only where the grid covers enough of the beam's
         * footprint (joint_coverage_min): one scene on the grid explains
         * both pings, and the echoes of the seabed off it bias the joint
         * misfit; at 70 m the survey system's 4 m grid covers 29 % of the
         * footprint and the joint stage doubled its surge errors
         * (docs/estimator.md, "A survey-class system"). */
        joint = fabs(yaw) * o->range <= o->joint_shift_max * along &&
                pair_contrast(pr) <= o->joint_contrast_max &&
                (!(o->joint_coverage_min > 0) || along >= o->joint_coverage_min * pr->footprint);
    }
    out->final_criterion = joint ? SASNAV_FINAL_JOINT : SASNAV_FINAL_ETA;
    if (joint) {
        /* The joint misfit's Newton stage from the search-level result, then eta
         * at (k, i) at its minimum (the verdict's eta bound and the overlap
         * are eta's). With a finite joint_eta_ratio (default: none), kept
         * only when eta there is at most that ratio of eta at the start,
         * else eta's own final stage runs from the start: the check fired
         * on 2 of 120 trajectory pairs and made both worse, and the scenes
         * it was made for (the tank: eta 1.1-3.2x higher at the joint
         * minimum) take eta's stage by their contrast (docs/estimator.md,
         * "A joint-misfit final stage"). */
        int check = isfinite(o->joint_eta_ratio);
        double e0 = HUGE_VAL;
        if (check) rc = sasnav_pair_eval(pr, out->error, PAIR_LEVELS - 1, 0, NULL, &e0, NULL);
        ctx.joint = 1;
        if (!rc) rc = pair_joint_tikhonov(pr, out->error, &ctx.lam);
        if (!rc) rc = newton_stage(&ctx, out->error, fstep, 0.5, 4.0, 2, 0.1, 4, &b, &f, NULL);
        int nj = ctx.evals + 1 + check;
        if (!rc) rc = sasnav_pair_eval(pr, b, PAIR_LEVELS - 1, 0, NULL, &f, NULL);
        m = b;
        if (!rc && check && !(f <= o->joint_eta_ratio * e0)) {
            ctx.joint = 0;
            b = out->error;
            rc = newton_stage(&ctx, out->error, fstep, 0.5, 4.0, 2, 0.1, 4, &b, &f, &m);
            nj += ctx.evals;
            out->final_criterion = SASNAV_FINAL_ETA;
            out->joint_rejected = 1;
        }
        ctx.evals = nj;
    } else {
        rc = newton_stage(&ctx, out->error, fstep, 0.5, 4.0, 2, 0.1, 4, &b, &f, &m);
    }
    out->evaluations_eta += ctx.evals;
    out->evaluations_final = ctx.evals;
    if (rc) return rc;
    out->error = b;
    out->measured = m;
    out->eta = f;
    out->seconds_final = sasnav_now_seconds() - t;
    out->applications_final = sasnav_pair_applications(pr) - apps;
    return SASNAV_OK;
}

/* Two refined candidates are the same point when they are within a quarter
 * phase-centre spacing in surge and sway and a quarter of its yaw at the
 * grid's range. */
static int same_point(sasnav_pose a, sasnav_pose b, double pc_spacing, double range)
{
    return fabs(a.x - b.x) < 0.25 * pc_spacing && fabs(a.y - b.y) < 0.25 * pc_spacing &&
           fabs(a.theta - b.theta) < 0.25 * pc_spacing / range;
}

/* The first of res's candidates 0 .. n-1 that is refined, distinct (not
 * converged onto an earlier one) and at point p (same_point); -1 if none. */
static int distinct_at(const sasnav_pair_result *res, int n, sasnav_pose p, double pc_spacing,
                       double range)
{
    for (int j = 0; j < n; j++)
        if (res->candidates[j].refined && res->candidates[j].same_as < 0 &&
            same_point(p, res->candidates[j].error, pc_spacing, range))
            return j;
    return -1;
}

static void add_costs(refine_out *sum, const refine_out *r)
{
    sum->seconds_zeta += r->seconds_zeta;
    sum->seconds_eta += r->seconds_eta;
    sum->seconds_final += r->seconds_final;
    sum->applications_zeta += r->applications_zeta;
    sum->applications_eta += r->applications_eta;
    sum->applications_final += r->applications_final;
    sum->evaluations_zeta += r->evaluations_zeta;
    sum->evaluations_eta += r->evaluations_eta;
    sum->evaluations_final += r->evaluations_final;
}

/* Along-track positions of a ping's phase centres (the midpoints of its
 * transmitter and each receiver) in its own centroid frame: every
 * channel's own geometry where the layout is per channel, the ping's EPCA
 * geometry otherwise. */
static void phase_centres(const sasnav_pair *pr, int q, double *x)
{
    const sasnav_ping_pose *ch = pr->per_channel ? (q ? pr->chan_q : pr->chan_p) : NULL;
    const sasnav_ping_pose *one = q ? &pr->local_q : &pr->local_p;
    for (int l = 0; l < pr->array.n_rx; l++) x[l] = pair_phase_centre_x(&pr->array, ch ? &ch[l] : one, l);
}

/* 1 when, moved by the estimate's along-track displacement, a phase centre
 * of q lies within opts.verdict_coincidence phase-centre spacings of one of
 * p's (on a uniform array: the displacement within that tolerance of a
 * multiple of the spacing shorter than the array; disjoint apertures share
 * none), on a compact scene (p's or q's intensity contrast above
 * verdict_contrast, compact_verdict below): there the
 * criterion is drawn to the coincidence from up to about 0.4 spacing away,
 * so the surge it reports is not a measurement (docs/estimator.md, "Known
 * weakness: attraction to phase-centre coincidence"). The phase centres
 * themselves, not multiples of a mean spacing: a per-channel layout (a
 * virtual array, several transmitters) need not be uniform. The turn
 * between the pings is left out: it moves a phase centre on the array's
 * axis, x from the centroid, by x yaw^2 / 2 along track (20 microns at
 * 0.4 m and 1e-2 rad). */
/* Whether the verdict takes the compact-scene rules: the intensity
 * contrast of p's image or of q's (at the estimate) above
 * opts.verdict_contrast (lower than joint_contrast_max, which picks the
 * search grid and final stage from p's alone: tank scenes just under that
 * gate slipped with "ok" verdicts, docs/validation.md "Scenes just under
 * the compact gate"; and pairs whose q alone sees a bright feature
 * slipped with p's contrast under it, "A bright feature entering the
 * beam"). */
static int compact_verdict(const sasnav_pair *pr, const sasnav_pair_result *res)
{
    return sasnav_pair_result_contrast(res) > sasnav_pair_options(pr)->verdict_contrast;
}

double sasnav_pair_result_contrast(const sasnav_pair_result *res)
{
    if (!res) return 0.0;
    return res->contrast_q > res->contrast ? res->contrast_q : res->contrast;
}

static int at_coincidence(const sasnav_pair *pr, const sasnav_pair_result *res, double pc_spacing)
{
    const sasnav_pair_opts *o = sasnav_pair_options(pr);
    if (!(o->verdict_coincidence > 0) || !(pc_spacing > 0)) return 0;
    if (!compact_verdict(pr, res)) return 0;
    double dx = res->displacement.x, tol = o->verdict_coincidence * pc_spacing;
    if (!isfinite(dx)) return 0;
    double xp[SASNAV_MAX_RX], xq[SASNAV_MAX_RX];
    phase_centres(pr, 0, xp);
    phase_centres(pr, 1, xq);
    for (int i = 0; i < pr->array.n_rx; i++)
        for (int j = 0; j < pr->array.n_rx; j++)
            if (fabs(xq[j] + dx - xp[i]) < tol) return 1;
    return 0;
}

/* The margin an "ok" estimate needs: verdict_margin_min, and on a compact
 * scene (compact_verdict, which also gates the coincidence rule) at least
 * verdict_margin_compact (docs/validation.md, "Flagged pairs"). */
static double margin_min(const sasnav_pair *pr, const sasnav_pair_result *res)
{
    const sasnav_pair_opts *o = sasnav_pair_options(pr);
    double m = o->verdict_margin_min;
    if (compact_verdict(pr, res) && o->verdict_margin_compact > m) m = o->verdict_margin_compact;
    return m;
}

/* The verdict from a result's overlap, eta, margin, contrasts and
 * coincidence. */
static void verdict_of(const sasnav_pair *pr, sasnav_pair_result *res, int converged)
{
    const sasnav_pair_opts *o = sasnav_pair_options(pr);
    if (!(res->overlap >= o->min_overlap)) res->verdict = SASNAV_VERDICT_NO_OVERLAP;
    else if (!converged || !(res->eta <= o->verdict_eta_max)) res->verdict = SASNAV_VERDICT_FAILED;
    else if (!(res->margin >= margin_min(pr, res)) || res->coincidence)
        res->verdict = SASNAV_VERDICT_AMBIGUOUS;
    else res->verdict = SASNAV_VERDICT_OK;
}

/* The verdict on a finished estimate (docs/estimator.md, "Verdict"). */
static void judge(const sasnav_pair *pr, sasnav_pair_result *res, int converged, double pc_spacing)
{
    res->contrast = pair_contrast(pr);
    res->coincidence = at_coincidence(pr, res, pc_spacing);
    verdict_of(pr, res, converged);
}

void sasnav_pair_rejudge(const sasnav_pair *pr, sasnav_pair_result *res)
{
    if (!pr || !res) return;
    verdict_of(pr, res, res->status != SASNAV_ERR_NOT_CONVERGED);
}

/* The final stage (unless final_stage is 0) and the result fields from the
 * search-level result r of the chosen candidate. */
static int finish(sasnav_pair *pr, double pc_spacing, refine_out *r, refine_out *sum,
                  double t0, long apps0, int nglob, int final_stage, sasnav_pair_result *res)
{
    const sasnav_pair_opts *o = sasnav_pair_options(pr);
    int rc = SASNAV_OK;
    if (final_stage) rc = refine_final(pr, pc_spacing, r);
    else r->final_criterion = SASNAV_FINAL_NONE;
    if (rc) return rc;
    sum->evaluations_final += r->evaluations_final;
    sum->evaluations_eta += r->evaluations_final;
    sum->seconds_final += r->seconds_final;
    sum->applications_final += r->applications_final;
    res->evaluations_zeta = sum->evaluations_zeta;
    res->evaluations_eta = sum->evaluations_eta;
    res->evaluations_final = sum->evaluations_final;
    res->seconds_zeta = sum->seconds_zeta;
    res->seconds_eta = sum->seconds_eta;
    res->seconds_final = sum->seconds_final;
    res->applications_zeta = sum->applications_zeta;
    res->applications_eta = sum->applications_eta;
    res->applications_final = sum->applications_final;
    res->zeta_stage = r->zeta_stage;
    res->zeta = r->zeta;
    res->eta = r->eta;
    res->final_criterion = r->final_criterion;
    res->joint_rejected = r->joint_rejected;
    res->search_grid = search_level(pr) ? SASNAV_SEARCH_FINE : SASNAV_SEARCH_COARSE;
    res->equalised = pr->equalised;
    res->equalise_peak = pr->level[1].eqw ? (float)pr->level[1].eq_peak : 0.0f;
    res->error = r->error;
    res->displacement = (sasnav_pose){pr->nominal.x + r->error.x, pr->nominal.y + r->error.y,
                                      pr->nominal.theta + r->error.theta};
    /* The overlap where the final stage last evaluated (kept: no work) */
    rc = sasnav_pair_eval(pr, final_stage ? r->measured : r->error, final_stage ? PAIR_LEVELS - 1 : 1, 0,
                          NULL, NULL, &res->overlap);
    /* q's contrast at the estimate, for the verdict (counted with the
     * final stage: one CGLS) */
    long apps_q = pr->applications;
    if (!rc) rc = pair_contrast_q(pr, res->error, &res->contrast_q);
    if (rc) return rc;
    res->applications_final += pr->applications - apps_q;
    res->evaluations = 1 + nglob + res->evaluations_zeta + res->evaluations_eta + 1;
    res->applications = pr->applications - apps0;
    res->seconds = sasnav_now_seconds() - t0;
    int converged = !r->zrc && !r->erc;
    res->status = converged ? SASNAV_OK : SASNAV_ERR_NOT_CONVERGED;
    if (res->overlap < o->min_overlap) res->status = SASNAV_ERR_NO_OVERLAP;
    judge(pr, res, converged, pc_spacing);
    return SASNAV_OK;
}

/* On an equalised search (opts.equalise), the chosen candidate's search-
 * level eta stage again without the weights, from where the weighted one
 * ended: the weights find the basin, the data's own criterion settles the
 * point in it (with the weights the paper-trajectory's surge errors were
 * 0.56 mm rms against 0.33, docs/estimator.md "An equalised search"). The
 * weights stay off until pair_equalise_suspend(pr, 0) (after the final
 * stage). Nothing on a search that was not equalised. */
static int unweighted_eta(sasnav_pair *pr, double pc_spacing, refine_out *r, refine_out *sum)
{
    if (!pr->equalised) return SASNAV_OK;
    pair_equalise_suspend(pr, 1);
    refine_out r2;
    int rc = refine_eta(pr, r->error, pc_spacing, &r2);
    if (rc) return rc;
    add_costs(sum, &r2);
    r->error = r2.error;
    r->eta = r2.eta;
    if (r2.erc) r->erc = r2.erc;
    return SASNAV_OK;
}

static double pair_pc_spacing(const sasnav_pair *pr)
{
    if (pr->per_channel && pr->pc_spacing > 0) return pr->pc_spacing;
    return pr->array.n_rx > 1 ? fabs(pr->array.rx_u[1] - pr->array.rx_u[0]) / 2.0 : 0.025;
}

/* Candidates refined side by side (pair_batch): item j refines from
 * start[j] into out[j], through the zeta and search-level eta stages (refine)
 * or the eta stage alone (refine_eta, the slip check's points). Each
 * candidate's stages are the same on the estimator or on a twin (the same
 * bits), so only the wall time depends on the workers. */
typedef struct {
    const sasnav_pose *start;
    refine_out *out;
    double pc_spacing;
    int eta_only;
} refine_job;

static int refine_item(sasnav_pair *w, int j, void *ctx)
{
    refine_job *b = ctx;
    return b->eta_only ? refine_eta(w, b->start[j], b->pc_spacing, &b->out[j])
                       : refine(w, b->start[j], b->pc_spacing, &b->out[j]);
}

/* Runs the job's n items and, when they ran side by side, scales their
 * stage times so that they add up to the batch's wall time (the result's
 * per-stage seconds stay a split of the estimate's wall time). */
static int refine_batch(sasnav_pair *pr, int n, refine_job *job)
{
    double t = sasnav_now_seconds();
    int rc = pair_batch(pr, n, refine_item, job);
    if (rc) return rc;
    double wall = sasnav_now_seconds() - t, sum = 0;
    for (int j = 0; j < n; j++) sum += job->out[j].seconds_zeta + job->out[j].seconds_eta;
    if (sum > wall && sum > 0) {
        double f = wall / sum;
        for (int j = 0; j < n; j++) {
            job->out[j].seconds_zeta *= f;
            job->out[j].seconds_eta *= f;
        }
    }
    return SASNAV_OK;
}

static int estimate(sasnav_pair *pr, int final_stage, sasnav_pair_result *res)
{
    if (!pr || !res) return sasnav_set_error(SASNAV_ERR_ARG, "NULL argument");
    memset(res, 0, sizeof *res);
    if (!pr->ready) return sasnav_set_error(SASNAV_ERR_ARG, "estimator has no data (call set_data)");
    double t0 = sasnav_now_seconds();
    long apps0 = pr->applications;
    const sasnav_pair_opts *o = sasnav_pair_options(pr);
    double pc_spacing = pair_pc_spacing(pr);
    res->margin = INFINITY;

    /* Overlap check at the prior. */
    double ov = 0;
    /* Level 1 (full pixels): at coarse pixels truncated CGLS rescales the
     * faint sidelobe-lit part of a grid and the kept energy stays high even
     * for pings metres apart. */
    int rc = sasnav_pair_eval(pr, o->prior, 1, 0, NULL, NULL, &ov);
    if (rc) return rc;
    if (!(ov >= o->min_overlap)) {
        res->status = SASNAV_ERR_NO_OVERLAP;
        res->verdict = SASNAV_VERDICT_NO_OVERLAP;
        res->overlap = ov;
        res->contrast = pair_contrast(pr);
        return sasnav_set_error(SASNAV_ERR_NO_OVERLAP,
                                "pings share no observed scene at the prior (kept energy %.2g < %.2g)",
                                ov, o->min_overlap);
    }

    sasnav_pose start = o->prior;
    scan_min mins[SASNAV_PAIR_SCAN_CANDIDATES];
    int nglob = 0, nm = 0;
    if (o->global_stage) {
        rc = global_stage(pr, pc_spacing, &start, &nglob, &res->ambiguity, mins, &nm);
        if (rc) return rc;
    }
    res->global_stage = start;
    res->evaluations_global = nglob;
    res->seconds_global = sasnav_now_seconds() - t0;
    res->applications_global = pr->applications - apps0;

    /* The candidates: the scan's lowest minimum (from the global stage's
     * local refinement), the second lowest, and any further one whose
     * score is within AMBIGUOUS of the lowest, each through the zeta and
     * search-level eta stages; the lowest eta wins and alone goes on to the
     * final stage. The other candidates' eta tells how clearly the data
     * chose (the margin of the verdict). Without a global stage the prior
     * is the only candidate. */
    if (nm == 0) {
        mins[0] = (scan_min){start, NAN, NAN};
        nm = 1;
    }
    refine_out r[SASNAV_PAIR_MAX_CANDIDATES], sum;
    memset(&sum, 0, sizeof sum);
    int win = -1;
    res->n_candidates = nm;
    /* The candidates to refine, refined side by side (independent of one
     * another), then taken in order. */
    int refine_it[SASNAV_PAIR_MAX_CANDIDATES], ks[SASNAV_PAIR_MAX_CANDIDATES], nr = 0;
    sasnav_pose starts[SASNAV_PAIR_MAX_CANDIDATES];
    refine_out rr[SASNAV_PAIR_MAX_CANDIDATES];
    for (int k = 0; k < nm; k++) {
        refine_it[k] = k == 0 || k == 1 || (k < SASNAV_PAIR_REFINED_CANDIDATES &&
                                            mins[0].score > AMBIGUOUS * mins[k].score);
        if (refine_it[k]) {
            ks[nr] = k;
            starts[nr++] = k == 0 ? start : mins[k].e;
        }
    }
    refine_job job = {starts, rr, pc_spacing, 0};
    rc = refine_batch(pr, nr, &job);
    if (rc) return rc;
    for (int j = 0; j < nr; j++) r[ks[j]] = rr[j];
    for (int k = 0; k < nm; k++) {
        sasnav_pair_candidate *cd = &res->candidates[k];
        cd->error = mins[k].e;
        cd->zeta_scan = mins[k].zeta;
        cd->zeta = cd->eta = NAN;
        cd->same_as = -1;
        if (!refine_it[k]) continue;
        add_costs(&sum, &r[k]);
        cd->refined = 1;
        cd->error = r[k].error;
        cd->zeta = r[k].zeta;
        cd->eta = r[k].eta;
        cd->same_as = distinct_at(res, k, cd->error, pc_spacing, o->range);
        if (cd->same_as < 0 && (win < 0 || r[k].eta < r[win].eta)) win = k;
    }
    /* The slip check: the points one phase-centre slip either side of the
     * winner along the valley (surge +-d, yaw +-d / R: the comb of
     * hypotheses that share as many phase centres) go through the level-1
     * eta stage unless a refined candidate already sits there. A lower eta
     * there takes over (and its own far neighbour is checked in turn);
     * either way their eta enters the margin. On compact scenes the scan
     * may miss the right basin altogether (docs/estimator.md, "Verdict"). */
    sasnav_pose slip = {pc_spacing, 0.0, o->fix_yaw ? 0.0 : pc_spacing / o->range};
    int nc = nm;
    for (int round = 0; round < 2 && nc < SASNAV_PAIR_MAX_CANDIDATES; round++) {
        int moved = 0;
        sasnav_pose centre = r[win].error;
        /* Both neighbours refined side by side, from the candidates known
         * before the round; the second is then taken only if it is not at
         * the first's result, as when they were refined in turn (two slips
         * apart, the bounded stage cannot bring the first there). */
        sasnav_pose st[2];
        int todo[2], nt = 0;
        for (int side = 0; side < 2; side++) {
            int sgn = side == 0 ? -1 : 1;
            st[side] = (sasnav_pose){centre.x + sgn * slip.x, centre.y, centre.theta + sgn * slip.theta};
            int known = distinct_at(res, nc, st[side], pc_spacing, o->range) >= 0;
            todo[side] = !known && nc + nt < SASNAV_PAIR_MAX_CANDIDATES;
            if (todo[side]) starts[nt++] = st[side];
        }
        refine_job sjob = {starts, rr, pc_spacing, 1};
        rc = refine_batch(pr, nt, &sjob);
        if (rc) return rc;
        for (int side = 0, next = 0; side < 2 && nc < SASNAV_PAIR_MAX_CANDIDATES; side++) {
            if (!todo[side]) continue;
            const refine_out *got = &rr[next++];
            if (distinct_at(res, nc, st[side], pc_spacing, o->range) >= 0) continue;
            int k = nc++;
            r[k] = *got;
            add_costs(&sum, &r[k]);
            sasnav_pair_candidate *cd = &res->candidates[k];
            *cd = (sasnav_pair_candidate){r[k].error, NAN, NAN, r[k].eta, 1, -1};
            cd->same_as = distinct_at(res, k, cd->error, pc_spacing, o->range);
            if (cd->same_as < 0 && r[k].eta < r[win].eta) {
                win = k;
                moved = 1;
            }
        }
        if (!moved) break;
    }
    res->n_candidates = nc;
    res->chosen = win;
    if (win != 0) res->global_stage = win < nm ? mins[win].e : r[win].zeta_stage;
    for (int k = 0; k < nc; k++) {
        const sasnav_pair_candidate *cd = &res->candidates[k];
        if (k != win && cd->refined && cd->same_as < 0 && cd->eta / r[win].eta < res->margin)
            res->margin = cd->eta / r[win].eta;
    }
    rc = unweighted_eta(pr, pc_spacing, &r[win], &sum);
    if (!rc) rc = finish(pr, pc_spacing, &r[win], &sum, t0, apps0, nglob, final_stage, res);
    pair_equalise_suspend(pr, 0);
    return rc;
}

int sasnav_pair_estimate(sasnav_pair *pr, sasnav_pair_result *res) { return estimate(pr, 1, res); }

int sasnav_pair_estimate_first(sasnav_pair *pr, sasnav_pair_result *res) { return estimate(pr, 0, res); }

int sasnav_pair_finish(sasnav_pair *pr, const sasnav_pair_result *first, sasnav_pair_result *res)
{
    if (!pr || !first || !res) return sasnav_set_error(SASNAV_ERR_ARG, "NULL argument");
    if (!pr->ready) return sasnav_set_error(SASNAV_ERR_ARG, "estimator has no data (call set_data)");
    sasnav_pose start = first->error;
    if (!isfinite(start.x) || !isfinite(start.y) || !isfinite(start.theta))
        return sasnav_set_error(SASNAV_ERR_ARG, "finish: the first estimate is not finite");
    sasnav_pair_result one = *first;
    memset(res, 0, sizeof *res);
    double t0 = sasnav_now_seconds();
    long apps0 = pr->applications;
    /* the final stage from the first estimate, with its search-level eta on
     * the present data */
    refine_out r, sum;
    memset(&r, 0, sizeof r);
    memset(&sum, 0, sizeof sum);
    r.error = r.zeta_stage = start;
    r.zeta = one.zeta;
    r.zrc = one.status == SASNAV_ERR_NOT_CONVERGED ? SASNAV_ERR_NOT_CONVERGED : SASNAV_OK;
    /* (the first estimate's search is done: the criteria unweighted) */
    pair_equalise_suspend(pr, 1);
    int rc = sasnav_pair_eval(pr, start, search_level(pr), 0, NULL, &r.eta, NULL);
    if (!rc) rc = finish(pr, pair_pc_spacing(pr), &r, &sum, t0, apps0, 0, 1, res);
    pair_equalise_suspend(pr, 0);
    if (rc) return rc;
    /* the first pass's stages, candidates and margin; the verdict again */
    sasnav_pair_result_carry(&one, res);
    res->global_stage = one.global_stage;
    res->zeta_stage = one.zeta_stage;
    res->zeta = one.zeta;
    res->evaluations_global = one.evaluations_global;
    res->evaluations_zeta = one.evaluations_zeta;
    res->evaluations_eta += one.evaluations_eta;
    res->seconds_global = one.seconds_global;
    res->seconds_zeta = one.seconds_zeta;
    res->seconds_eta += one.seconds_eta;
    res->applications_global = one.applications_global;
    res->applications_zeta = one.applications_zeta;
    res->applications_eta += one.applications_eta;
    if (res->status == SASNAV_OK && one.status == SASNAV_ERR_NOT_CONVERGED) res->status = one.status;
    judge(pr, res, res->status != SASNAV_ERR_NOT_CONVERGED, pair_pc_spacing(pr));
    return SASNAV_OK;
}

int sasnav_pair_estimate_from(sasnav_pair *pr, sasnav_pose start, sasnav_pair_result *res)
{
    if (!pr || !res) return sasnav_set_error(SASNAV_ERR_ARG, "NULL argument");
    memset(res, 0, sizeof *res);
    if (!pr->ready) return sasnav_set_error(SASNAV_ERR_ARG, "estimator has no data (call set_data)");
    if (!isfinite(start.x) || !isfinite(start.y) || !isfinite(start.theta))
        return sasnav_set_error(SASNAV_ERR_ARG, "estimate_from: the start is not finite");
    double t0 = sasnav_now_seconds();
    long apps0 = pr->applications;
    double pc_spacing = pair_pc_spacing(pr);
    refine_out r, sum;
    memset(&sum, 0, sizeof sum);
    int rc = refine(pr, start, pc_spacing, &r);
    if (rc) return rc;
    add_costs(&sum, &r);
    res->global_stage = start;
    res->n_candidates = 1;
    res->candidates[0] = (sasnav_pair_candidate){r.error, NAN, r.zeta, r.eta, 1, -1};
    res->chosen = 0;
    res->margin = INFINITY;
    rc = unweighted_eta(pr, pc_spacing, &r, &sum);
    if (!rc) rc = finish(pr, pc_spacing, &r, &sum, t0, apps0, 0, 1, res);
    pair_equalise_suspend(pr, 0);
    return rc;
}
