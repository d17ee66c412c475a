/* The search for the displacement (paper Section III-A, procedure 1-3, and
 * docs/estimator.md):
 *   0. global stage: grid search of a blurred zeta at coarse pixels and
 *      coarse (k, i) over the search box: first (surge, yaw) with sway at
 *      the prior, then sway at the best (surge, yaw), then a bounded local
 *      refinement of the blurred zeta (NLopt BOBYQA);
 *   1. zeta stage: local minimisation of zeta (coarse k, i; full pixels is
 *      level 1 with coarse iterations is not offered: level 1 is used) from
 *      the global result;
 *   2. eta stage: local minimisation of eta from the zeta result, started
 *      also one sway fringe (lambda/2) either side when eta there is lower.
 * Steps and bounds derive from the geometry: phase-centre spacing, range and
 * wavelength. */
#include "pair_internal.h"
#include "core/clock.h"

#include <math.h>
#include <nlopt.h>
#include <stdlib.h>
#include <string.h>

#ifndef SCAN_LEVEL
#define SCAN_LEVEL 1
#endif
#define HW10 ((sasnav_pose){10.0, 10.0, 10.0})
/* zeta ratio of the scan's two best minima above which both are refined */
#define AMBIGUOUS 0.8

typedef struct {
    sasnav_pair *pr;
    int level, blurred, use_eta;
    int use_prior;          /* weight by the surge prior (opts.surge_sigma) */
    int ndim;               /* 3, or 2 with the yaw held (opts.fix_yaw) */
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

static int global_stage(sasnav_pair *pr, double pc_spacing, sasnav_pose *best, int *evals,
                        double *ambiguity, sasnav_pose *second, int *has_second)
{
    const sasnav_pair_opts *o = sasnav_pair_options(pr);
    const pair_level *lv = &pr->level[0];
    sasnav_pose c = o->prior, b = o->box;
    double zx = lv->grid.x0 + 0.5 * (lv->grid.nx - 1) * lv->grid.dx;
    double zy = lv->grid.y0 + 0.5 * (lv->grid.ny - 1) * lv->grid.dy;
    int n = 0, rc;
    sasnav_pose hyp = c;
    double sx = 0, sy = 0;
    /* Two correlation passes: the second, at the first pass's point of the
     * valley with the prior yaw, removes most of the distortion of the
     * first image. */
    for (int pass = 0; pass < 2; pass++) {
        if ((rc = pair_image_shift(pr, 0, hyp, &sx, &sy))) return rc;
        sasnav_pose hd = {pr->nominal.x + hyp.x, pr->nominal.y + hyp.y, pr->nominal.theta + hyp.theta};
        hyp = valley_point(pr, hd, zx, zy, sx, sy, pr->nominal.theta + c.theta);
        if (fabs(hyp.x - c.x) > b.x || fabs(hyp.y - c.y) > b.y) hyp = c;
    }
    sasnav_pose hd = {pr->nominal.x + hyp.x, pr->nominal.y + hyp.y, pr->nominal.theta + hyp.theta};
    if ((rc = pair_image_shift(pr, 0, hyp, &sx, &sy))) return rc;
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
    if (!zs || !es) {
        free(zs);
        free(es);
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
        if (fabs(e.x - c.x) > b.x || fabs(e.y - c.y) > b.y) continue;
        double z;
        if ((rc = sasnav_pair_eval(pr, e, SCAN_LEVEL, 0, &z, NULL, NULL))) {
            free(zs);
            free(es);
            return rc;
        }
        n++;
        zs[it + nt] = z;
    }
    /* The candidates are the local minima of the scan's zeta weighted by
     * the priors: 1 + (yaw offset / yaw_sigma)^2 and 1 + (surge offset /
     * surge_sigma)^2 (each where given). The ratio of the two lowest minima
     * of zeta itself measures how well the data alone resolve the valley. */
    double fbest = HUGE_VAL, sbest = HUGE_VAL, sbest2 = HUGE_VAL, z1 = HUGE_VAL, z2 = HUGE_VAL;
    sasnav_pose arg = hyp, arg2 = hyp;
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
    for (int j = 0; j < ns; j++) {
        if (!(zs[j] < HUGE_VAL)) continue;
        if (!((j > 0 && score[j - 1] < score[j]) || (j + 1 < ns && score[j + 1] <= score[j]))) {
            if (score[j] < sbest) {
                sbest2 = sbest;
                arg2 = arg;
                sbest = score[j];
                fbest = zs[j];
                arg = es[j];
            } else if (score[j] < sbest2) {
                sbest2 = score[j];
                arg2 = es[j];
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
    *second = arg2;
    *has_second = sbest2 < HUGE_VAL;
    /* Local refinement of zeta at level 0 around the best valley point. */
    stage_ctx ctx = {.pr = pr, .level = 0, .use_prior = 1};
    sasnav_pose unit = {pc_spacing, pc_spacing, pc_spacing / o->range};
    sasnav_pose refined;
    double fr;
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
    int evaluations_zeta, evaluations_eta, zrc, erc;
} refine_out;

/* Stages 1 and 2 from `start` (a global-stage candidate). */
static int refine(sasnav_pair *pr, sasnav_pose start, double pc_spacing, refine_out *out)
{
    const sasnav_pair_opts *o = sasnav_pair_options(pr);
    double lambda = sasnav_wavelength(&pr->sys), range = o->range;
    int rc;
    memset(out, 0, sizeof *out);
    /* Zeta stage (level 1: full pixels, coarse iterations): steps of a
     * fifth of a phase-centre spacing in surge and sway, and the yaw that
     * moves the scene by as much at the grid's range. */
    /* With a surge prior the stage minimises zeta times its factor, so that
     * it stays with the candidate the global stage chose; the zeta reported
     * is the data's. */
    stage_ctx ctx = {.pr = pr, .level = 1, .use_prior = 1};
    sasnav_pose zstep = {0.2 * pc_spacing, 0.2 * pc_spacing, 0.2 * pc_spacing / range};
    sasnav_pose zbest;
    double zval;
    int zrc = local_stage(&ctx, start, zstep, HW10, 0.01, o->max_evaluations, &zbest, &zval);
    out->evaluations_zeta = ctx.evals;
    out->zrc = zrc;
    if (zrc && zrc != SASNAV_ERR_NOT_CONVERGED) return zrc;
    out->zeta_stage = zbest;
    zval /= surge_prior(pr, zbest); /* the data's zeta (factor 1 without a prior) */
    out->zeta = zval;

    /* Eta stage, first at level 1 then at level 2 (final k, i): steps of
     * lambda/40 in sway (bounds +-lambda/4: one fringe), a 25th of the
     * phase-centre spacing in surge and twice the matching yaw (bounds +-10
     * steps). The fringes either side of the zeta result are tried too and
     * kept when eta is lower there. */
    ctx.use_eta = 1;
    sasnav_pose estep = {pc_spacing / 25.0, lambda / 40.0, 2.0 * pc_spacing / 25.0 / range};
    sasnav_pose best = zbest;
    double fbest = HUGE_VAL;
    int erc = SASNAV_OK, nevals = 0;
    for (int fringe = 0; fringe < 3; fringe++) {
        sasnav_pose s0 = zbest;
        s0.y += (fringe == 0 ? 0.0 : fringe == 1 ? -0.5 : 0.5) * lambda;
        if (fringe > 0) {
            double e0;
            rc = sasnav_pair_eval(pr, s0, 1, 0, NULL, &e0, NULL);
            nevals++;
            if (rc) return rc;
            if (!(e0 < fbest)) continue;
        }
        sasnav_pose b;
        double f;
        int r = local_stage(&ctx, s0, estep, HW10, 0.01, o->max_evaluations, &b, &f);
        nevals += ctx.evals;
        if (r && r != SASNAV_ERR_NOT_CONVERGED) return r;
        if (f < fbest) {
            fbest = f;
            best = b;
            erc = r;
        }
    }
    if (o->k != o->coarse_k || o->i != o->coarse_i) {
        ctx.level = 2;
        /* Half the eta steps; stop at 0.05 step (25 microns of surge, 3
         * microns of sway): tighter costs up to 2x the applications for
         * changes well inside the bias (docs/estimator.md). */
        sasnav_pose fstep = {estep.x / 2, estep.y / 2, estep.theta / 2};
        sasnav_pose b;
        double f;
        erc = local_stage(&ctx, best, fstep, HW10, 0.05, o->max_evaluations, &b, &f);
        nevals += ctx.evals;
        if (erc && erc != SASNAV_ERR_NOT_CONVERGED) return erc;
        best = b;
        fbest = f;
    }
    out->evaluations_eta = nevals;
    out->eta = fbest;
    out->error = best;
    out->erc = erc;
    return SASNAV_OK;
}

int sasnav_pair_estimate(sasnav_pair *pr, sasnav_pair_result *res)
{
    if (!pr || !res) return sasnav_set_error(SASNAV_ERR_ARG, "NULL argument");
    memset(res, 0, sizeof *res);
    if (!pr->ready) return sasnav_set_error(SASNAV_ERR_ARG, "estimator has no data (call set_data)");
    double t0 = sasnav_now_seconds();
    long apps0 = pr->applications;
    const sasnav_pair_opts *o = sasnav_pair_options(pr);
    double pc_spacing = pr->array.n_rx > 1 ? fabs(pr->array.rx_u[1] - pr->array.rx_u[0]) / 2.0 : 0.025;

    /* Overlap check at the prior. */
    double ov = 0;
    /* Level 1 (full pixels): at coarse pixels truncated CGLS rescales the
     * faint sidelobe-lit part of a grid and the kept energy stays high even
     * for pings metres apart. */
    int rc = sasnav_pair_eval(pr, o->prior, 1, 0, NULL, NULL, &ov);
    if (rc) return rc;
    if (!(ov >= o->min_overlap)) {
        res->status = SASNAV_ERR_NO_OVERLAP;
        res->overlap = ov;
        return sasnav_set_error(SASNAV_ERR_NO_OVERLAP,
                                "pings share no observed scene at the prior (kept energy %.2g < %.2g)",
                                ov, o->min_overlap);
    }

    sasnav_pose start = o->prior, second = o->prior;
    int nglob = 0, has_second = 0;
    if (o->global_stage) {
        rc = global_stage(pr, pc_spacing, &start, &nglob, &res->ambiguity, &second, &has_second);
        if (rc) return rc;
    }
    res->global_stage = start;
    res->evaluations_global = nglob;

    refine_out r1, r2;
    rc = refine(pr, start, pc_spacing, &r1);
    if (rc) return rc;
    int nzeta = r1.evaluations_zeta, neta = r1.evaluations_eta;
    /* When the scan's two best candidates are nearly alike in zeta, both are
     * carried through the eta stage and the lower final eta decides: at the
     * tank's track ends zeta prefers the candidate one phase-centre spacing
     * short (one more shared phase centre) while eta there is 3-6x higher
     * than at the right one (docs/estimator.md). */
    if (has_second && res->ambiguity > AMBIGUOUS) {
        rc = refine(pr, second, pc_spacing, &r2);
        if (rc) return rc;
        nzeta += r2.evaluations_zeta;
        neta += r2.evaluations_eta;
        if (r2.eta < r1.eta) {
            r1 = r2;
            res->global_stage = second;
        }
    }
    res->evaluations_zeta = nzeta;
    res->zeta_stage = r1.zeta_stage;
    res->zeta = r1.zeta;
    res->evaluations_eta = neta;
    res->eta = r1.eta;
    res->error = r1.error;
    sasnav_pose best = r1.error;
    int zrc = r1.zrc, erc = r1.erc;
    res->displacement = (sasnav_pose){pr->nominal.x + best.x, pr->nominal.y + best.y,
                                      pr->nominal.theta + best.theta};
    rc = sasnav_pair_eval(pr, best, PAIR_LEVELS - 1, 0, NULL, NULL, &res->overlap);
    if (rc) return rc;
    res->evaluations = 1 + nglob + res->evaluations_zeta + res->evaluations_eta + 1;
    res->applications = pr->applications - apps0;
    res->seconds = sasnav_now_seconds() - t0;
    res->status = (zrc || erc) ? SASNAV_ERR_NOT_CONVERGED : SASNAV_OK;
    if (res->overlap < o->min_overlap) res->status = SASNAV_ERR_NO_OVERLAP;
    return SASNAV_OK;
}
