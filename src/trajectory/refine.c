/* Multi-ping refinement of a trajectory in the data domain
 * (include/sasnav/refine.h). */
#include "sasnav/refine.h"

#include "sasnav/error.h"
#include "core/clock.h"
#include "core/hash.h"

#include <complex.h>
#include <math.h>
#include <nlopt.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

void sasnav_refine_default_opts(sasnav_refine_opts *o)
{
    if (!o) return;
    memset(o, 0, sizeof *o);
    o->sweeps = 8;
    o->cg_first = 40;
    o->cg_iterations = 12;
    o->damping = 1e-3;
    o->surge_range = 0.012;
    o->sway_range = 0.0015;
    o->stop_move = 5e-5;
    o->sparsity = 0.01;
    sasnav_op_default_opts(&o->op);
    o->op.tolerance = 1e-3;
}

typedef struct {
    const sasnav_run *run;
    const sasnav_refine_opts *o;
    int n;              /* pings */
    size_t np, nd;      /* pixels, samples of one ping */
    sasnav_op **op;     /* one per ping, at its current pose */
    sasnav_op **top;    /* one per thread, for trial poses */
    int nthreads;
    sasnav_cfloat *tb;  /* n * np: per-ping adjoint outputs */
    sasnav_cfloat *td;  /* n * nd: per-ping forward outputs */
    sasnav_cfloat *td2; /* nthreads * nd: trial predictions */
    double mu;          /* absolute damping, < 0 until set */
    float *w;           /* np: per-pixel damping weights (all 1: uniform) */
} refine_ctx;

static double energy(const sasnav_cfloat *a, size_t n)
{
    double s = 0;
    for (size_t i = 0; i < n; i++) s += (double)crealf(a[i]) * crealf(a[i]) + (double)cimagf(a[i]) * cimagf(a[i]);
    return s;
}

/* out = sum_{p != skip} T_p^H T_p in (+ mu in once mu is set). Per-ping
 * terms in parallel, summed in a fixed order. */
static int normal_apply(refine_ctx *c, int skip, const sasnav_cfloat *in, sasnav_cfloat *out)
{
    int rc = SASNAV_OK;
#pragma omp parallel for num_threads(c->nthreads) schedule(dynamic) reduction(min : rc)
    for (int p = 0; p < c->n; p++) {
        if (p == skip) continue;
        int r = sasnav_op_forward(c->op[p], in, c->td + c->nd * p);
        if (!r) r = sasnav_op_adjoint(c->op[p], c->td + c->nd * p, c->tb + c->np * p);
        if (r < rc) rc = r;
    }
    if (rc) return rc;
    memset(out, 0, sizeof *out * c->np);
    for (int p = 0; p < c->n; p++) {
        if (p == skip) continue;
        const sasnav_cfloat *t = c->tb + c->np * p;
        for (size_t i = 0; i < c->np; i++) out[i] += t[i];
    }
    return SASNAV_OK;
}

/* Conjugate gradients on (sum_{p != skip} T_p^H T_p + mu) s = rhs, from s. */
static int scene_solve(refine_ctx *c, int skip, int iterations, sasnav_cfloat *s, sasnav_cfloat *r,
                       sasnav_cfloat *d, sasnav_cfloat *ad)
{
    size_t np = c->np;
    /* rhs = sum T_p^H phi_p */
    int rc = SASNAV_OK;
#pragma omp parallel for num_threads(c->nthreads) schedule(dynamic) reduction(min : rc)
    for (int p = 0; p < c->n; p++) {
        if (p == skip) continue;
        int e = sasnav_op_adjoint(c->op[p], sasnav_run_ping(c->run, p), c->tb + np * p);
        if (e < rc) rc = e;
    }
    if (rc) return rc;
    memset(r, 0, sizeof *r * np);
    for (int p = 0; p < c->n; p++) {
        if (p == skip) continue;
        const sasnav_cfloat *t = c->tb + np * p;
        for (size_t i = 0; i < np; i++) r[i] += t[i];
    }
    double eb = energy(r, np);
    if (!(eb > 0)) return sasnav_set_error(SASNAV_ERR_NO_OVERLAP, "no ping reaches the refinement's scene grid");
    if (c->mu < 0) {
        /* mu from the normal operator's scale along the data's direction. */
        if ((rc = normal_apply(c, skip, r, ad))) return rc;
        double complex num = 0;
        for (size_t i = 0; i < np; i++) num += conj(r[i]) * ad[i];
        c->mu = c->o->damping * creal(num) / eb;
    }
    /* r = rhs - A s */
    if ((rc = normal_apply(c, skip, s, ad))) return rc;
    for (size_t i = 0; i < np; i++) r[i] -= ad[i] + (float)c->mu * c->w[i] * s[i];
    memcpy(d, r, sizeof *d * np);
    double rr = energy(r, np);
    for (int it = 0; it < iterations && rr > 1e-14 * eb; it++) {
        if ((rc = normal_apply(c, skip, d, ad))) return rc;
        double complex dad = 0;
        for (size_t i = 0; i < np; i++) {
            ad[i] += (float)c->mu * c->w[i] * d[i];
            dad += conj(d[i]) * ad[i];
        }
        if (!(creal(dad) > 0)) break;
        float alpha = (float)(rr / creal(dad));
        for (size_t i = 0; i < np; i++) {
            s[i] += alpha * d[i];
            r[i] -= alpha * ad[i];
        }
        double rn = energy(r, np);
        float beta = (float)(rn / rr);
        rr = rn;
        for (size_t i = 0; i < np; i++) d[i] = r[i] + beta * d[i];
    }
    return SASNAV_OK;
}

/* Reweighted damping from the scene just solved: pixel i is damped by
 * mu / (|s_i|^2 / mean |s|^2 + eps), so that the next scene keeps its
 * strong scatterers and is pushed towards zero elsewhere (iteratively
 * reweighted least squares towards a scene of few scatterers). */
static void update_weights(refine_ctx *c, const sasnav_cfloat *s)
{
    double m = energy(s, c->np) / (double)c->np;
    if (!(m > 0)) return;
    for (size_t i = 0; i < c->np; i++) {
        double a = ((double)crealf(s[i]) * crealf(s[i]) + (double)cimagf(s[i]) * cimagf(s[i])) / m;
        c->w[i] = (float)(1.0 / (a + c->o->sparsity));
    }
}

/* Ping pose moved by (u, v) along / across its array axis. */
static sasnav_ping_pose moved(const sasnav_ping_pose *p, double u, double v)
{
    double cs = cos(p->array.theta), sn = sin(p->array.theta);
    double dx = u * cs - v * sn, dy = u * sn + v * cs;
    sasnav_ping_pose q = *p;
    q.tx.x += dx;
    q.tx.y += dy;
    q.array.x += dx;
    q.array.y += dy;
    return q;
}

typedef struct {
    refine_ctx *c;
    int q, thread;
    const sasnav_ping_pose *pose;
    const sasnav_cfloat *s;
    double eq; /* ||phi_q||^2 */
    int rc;
    int evals;
} misfit_arg;

/* Normalised misfit of ping q moved by (u, v) against the scene s. */
static double misfit(misfit_arg *a, double u, double v)
{
    refine_ctx *c = a->c;
    sasnav_op *op = c->top[a->thread];
    sasnav_cfloat *d = c->td2 + c->nd * a->thread;
    sasnav_ping_pose pp = moved(a->pose, u, v);
    int rc = sasnav_op_set_ping(op, &pp, c->run->channel_offset);
    if (!rc) rc = sasnav_op_forward(op, a->s, d);
    a->evals++;
    if (rc) {
        a->rc = rc;
        return 2.0;
    }
    const sasnav_cfloat *y = sasnav_run_ping(c->run, a->q);
    double complex cc = 0;
    double ed = 0;
    for (size_t i = 0; i < c->nd; i++) {
        cc += conj(d[i]) * y[i];
        ed += (double)crealf(d[i]) * crealf(d[i]) + (double)cimagf(d[i]) * cimagf(d[i]);
    }
    if (!(ed > 0)) return 1.0;
    return 1.0 - creal(cc * conj(cc)) / (ed * a->eq);
}

static double misfit_nlopt(unsigned n, const double *x, double *grad, void *data)
{
    (void)n;
    (void)grad;
    return misfit((misfit_arg *)data, x[0], x[1]);
}

/* Best move of ping q against the scene s: with `search`, a grid search
 * over the whole ranges, then BOBYQA within one grid step of its best
 * point; without, BOBYQA alone within (wu, wv) of the current pose. */
static int fit_ping(refine_ctx *c, int q, const sasnav_ping_pose *pose, const sasnav_cfloat *s, int search,
                    double wu, double wv, double tu, double tv, double *u, double *v, double *best_cost)
{
    const sasnav_refine_opts *o = c->o;
    double eq = energy(sasnav_run_ping(c->run, q), c->nd);
    if (!(eq > 0)) return sasnav_set_error(SASNAV_ERR_ARG, "ping %d has no signal", q);
    double x[2] = {0, 0}, fx, hu = wu, hv = wv;
    misfit_arg a = {c, q, 0, pose, s, eq, SASNAV_OK, 0};
    if (search) {
        enum { NU = 25, NV = 13 };
        double cost[NU * NV];
        hu = o->surge_range / 12.0;
        hv = o->sway_range / 6.0;
        int rc = SASNAV_OK;
#pragma omp parallel num_threads(c->nthreads) reduction(min : rc)
        {
            misfit_arg b = {c, q, omp_get_thread_num(), pose, s, eq, SASNAV_OK, 0};
#pragma omp for schedule(dynamic)
            for (int j = 0; j < NU * NV; j++)
                cost[j] = misfit(&b, -o->surge_range + hu * (j / NV), -o->sway_range + hv * (j % NV));
            rc = b.rc;
        }
        if (rc) return rc;
        int jb = 0;
        for (int j = 1; j < NU * NV; j++)
            if (cost[j] < cost[jb]) jb = j;
        x[0] = -o->surge_range + hu * (jb / NV);
        x[1] = -o->sway_range + hv * (jb % NV);
        fx = cost[jb];
    } else {
        fx = misfit(&a, 0, 0);
        if (a.rc) return a.rc;
    }
    nlopt_opt opt = nlopt_create(NLOPT_LN_BOBYQA, 2);
    if (!opt) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    /* Within one step of the start, and within the search ranges of the
     * input pose (tu, tv: the ping's total move so far). */
    double lb[2] = {fmax(x[0] - hu, -o->surge_range - tu), fmax(x[1] - hv, -o->sway_range - tv)};
    double ub[2] = {fmin(x[0] + hu, o->surge_range - tu), fmin(x[1] + hv, o->sway_range - tv)};
    for (int k = 0; k < 2; k++) {
        if (x[k] < lb[k]) x[k] = lb[k];
        if (x[k] > ub[k]) x[k] = ub[k];
    }
    double step[2] = {fmax(0.25 * (ub[0] - lb[0]), 1e-6), fmax(0.25 * (ub[1] - lb[1]), 1e-6)};
    nlopt_set_lower_bounds(opt, lb);
    nlopt_set_upper_bounds(opt, ub);
    nlopt_set_initial_step(opt, step);
    nlopt_set_min_objective(opt, misfit_nlopt, &a);
    nlopt_set_xtol_abs1(opt, 1e-6);
    nlopt_set_maxeval(opt, 60);
    double x0[2] = {x[0], x[1]}, f = fx;
    nlopt_result nr = nlopt_optimize(opt, x0, &f);
    nlopt_destroy(opt);
    if (a.rc) return a.rc;
    if (nr > 0 || nr == NLOPT_MAXEVAL_REACHED) {
        if (f < fx) {
            x[0] = x0[0];
            x[1] = x0[1];
            fx = f;
        }
    }
    *u = x[0];
    *v = x[1];
    *best_cost = fx;
    return SASNAV_OK;
}

static int check_opts(const sasnav_refine_opts *o)
{
    if (o->sweeps < 1 || o->sweeps > SASNAV_REFINE_MAX_SWEEPS)
        return sasnav_set_error(SASNAV_ERR_ARG, "refinement sweeps must be in 1..%d", SASNAV_REFINE_MAX_SWEEPS);
    if (o->cg_first < 1 || o->cg_iterations < 1 || o->cg_first > 10000 || o->cg_iterations > 10000)
        return sasnav_set_error(SASNAV_ERR_ARG, "refinement CG iterations must be in 1..10000");
    if (!(o->damping > 0) || !isfinite(o->damping))
        return sasnav_set_error(SASNAV_ERR_ARG, "refinement damping must be positive");
    if (!(o->surge_range > 0) || !(o->sway_range > 0) || !isfinite(o->surge_range) || !isfinite(o->sway_range) ||
        o->surge_range > 1 || o->sway_range > 1)
        return sasnav_set_error(SASNAV_ERR_ARG, "refinement search ranges must be in (0, 1] m");
    if (!(o->sparsity >= 0) || !isfinite(o->sparsity))
        return sasnav_set_error(SASNAV_ERR_ARG, "refinement sparsity must be >= 0");
    if (!(o->stop_move >= 0) || !isfinite(o->stop_move))
        return sasnav_set_error(SASNAV_ERR_ARG, "refinement stop_move must be >= 0");
    if (o->nthreads < 0) return sasnav_set_error(SASNAV_ERR_ARG, "negative thread count");
    return SASNAV_OK;
}

void sasnav_refine_state_free(sasnav_refine_state *st)
{
    if (!st) return;
    free(st->poses);
    free(st->move_u);
    free(st->move_v);
    free(st->scene);
    free(st->weights);
    memset(st, 0, sizeof *st);
}

/* What a refinement's result depends on: the run (samples, geometry,
 * system), the input poses, the options and the grid, field by field. */
static uint64_t refine_digest(const sasnav_run *run, const sasnav_ping_pose *nav_in,
                              const sasnav_refine_opts *o, const sasnav_grid *g)
{
    uint64_t h = SASNAV_HASH_INIT;
    const int64_t ints[10] = {run->n_pings, run->array.n_rx, run->win.n_samples, run->sys.beam_pattern,
                              o->sweeps, o->cg_first, o->cg_iterations, o->op.pad_samples,
                              (int64_t)run->sys.taper, (int64_t)run->sys.attenuation};
    h = sasnav_hash_bytes(h, ints, sizeof ints);
    h = sasnav_hash_words(h, run->raw, sizeof(sasnav_cfloat) * (size_t)run->n_pings *
                                           (size_t)run->array.n_rx * (size_t)run->win.n_samples);
    const double d[25] = {run->sys.sound_speed, run->sys.f0, run->sys.bandwidth, run->sys.sample_rate,
                          run->win.t0, run->array.rx_length, run->array.tx_length, run->array.rx_height,
                          run->array.tx_height, o->damping, o->surge_range, o->sway_range, o->stop_move,
                          o->sparsity, o->op.tolerance, o->op.oversampling, g->x0, g->dx, g->y0, g->dy,
                          (double)g->nx, (double)g->ny, 0, 0, 0};
    h = sasnav_hash_doubles(h, d, 25);
    h = sasnav_hash_doubles(h, run->array.rx_u, run->array.n_rx);
    for (int l = 0; run->array.per_channel && l < run->array.n_rx; l++) {
        const sasnav_channel_size *z = &run->array.size[l];
        const double zd[4] = {z->rx_length, z->tx_length, z->rx_height, z->tx_height};
        h = sasnav_hash_doubles(h, zd, 4);
    }
    if (run->channel_offset) h = sasnav_hash_ping_poses(h, run->channel_offset, run->array.n_rx);
    return sasnav_hash_ping_poses(h, nav_in, run->n_pings);
}

int sasnav_refine(const sasnav_run *run, const sasnav_ping_pose *nav_in, const sasnav_refine_opts *opts,
                  sasnav_ping_pose *nav_out, sasnav_refine_report *report)
{
    double t0 = sasnav_now_seconds();
    if (!run || !nav_in || !nav_out) return sasnav_set_error(SASNAV_ERR_ARG, "NULL argument");
    sasnav_refine_opts o;
    if (opts)
        o = *opts;
    else
        sasnav_refine_default_opts(&o);
    int rc = check_opts(&o);
    if (!rc) rc = sasnav_run_check(run);
    if (!rc && !run->raw)
        rc = sasnav_set_error(SASNAV_ERR_ARG, "refine needs the run in memory (sasnav_run_read), "
                                              "not streamed");
    if (rc) return rc;
    int n = run->n_pings;
    if (n < 3) return sasnav_set_error(SASNAV_ERR_ARG, "refinement needs at least 3 pings (got %d)", n);
    for (int p = 0; p < n; p++) {
        const sasnav_ping_pose *q = &nav_in[p];
        if (!isfinite(q->tx.x) || !isfinite(q->tx.y) || !isfinite(q->tx.theta) || !isfinite(q->array.x) ||
            !isfinite(q->array.y) || !isfinite(q->array.theta))
            return sasnav_set_error(SASNAV_ERR_ARG, "ping %d: non-finite pose", p);
    }
    sasnav_grid grid = o.grid;
    if (grid.nx == 0) {
        double xmin = HUGE_VAL, xmax = -HUGE_VAL;
        for (int p = 0; p < n; p++) {
            sasnav_pose c = sasnav_ping_centroid(&run->nav[p]);
            xmin = fmin(xmin, c.x);
            xmax = fmax(xmax, c.x);
        }
        double pix = 0.005, r = run->range_of_interest;
        int nx = (int)ceil((xmax - xmin) / pix) + 1, ny = (int)ceil(0.7 / pix) + 1;
        rc = sasnav_grid_make(xmin, xmin + (nx - 1) * pix, nx, r - 0.35, r - 0.35 + (ny - 1) * pix, ny, &grid);
    } else {
        rc = sasnav_grid_check(&grid);
    }
    if (rc) return rc;

    refine_ctx c;
    memset(&c, 0, sizeof c);
    c.run = run;
    c.o = &o;
    c.n = n;
    c.np = (size_t)grid.nx * grid.ny;
    c.nd = (size_t)run->array.n_rx * run->win.n_samples;
    c.nthreads = o.nthreads > 0 ? o.nthreads : omp_get_max_threads();
    c.mu = -1;
    sasnav_op_opts oo = o.op;
    oo.nthreads = 1; /* parallel over pings and trial poses instead */
    double *px = malloc(sizeof(double) * c.np), *py = malloc(sizeof(double) * c.np);
    sasnav_ping_pose *cur = malloc(sizeof *cur * n);
    c.op = calloc((size_t)n, sizeof *c.op);
    c.top = calloc((size_t)c.nthreads, sizeof *c.top);
    c.tb = malloc(sizeof *c.tb * c.np * n);
    c.td = malloc(sizeof *c.td * c.nd * n);
    c.td2 = malloc(sizeof *c.td2 * c.nd * c.nthreads);
    c.w = malloc(sizeof *c.w * c.np);
    sasnav_cfloat *s = calloc(c.np, sizeof *s), *r = malloc(sizeof *r * c.np), *d = malloc(sizeof *d * c.np),
                  *ad = malloc(sizeof *ad * c.np);
    if (!px || !py || !cur || !c.op || !c.top || !c.tb || !c.td || !c.td2 || !s || !r || !d || !ad || !c.w)
        rc = sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    uint64_t digest = refine_digest(run, nav_in, &o, &grid);
    const sasnav_refine_state *rs = o.resume;
    if (!rc && rs) {
        if (rs->digest != digest || rs->n_pings != n || (size_t)rs->n_pixels != c.np)
            rc = sasnav_set_error(SASNAV_ERR_ARG, "the refinement state to resume is of another run, input "
                                  "navigation, grid or options");
        else if (rs->sweeps_done < 0 || rs->sweeps_done > o.sweeps || !rs->poses || !rs->move_u ||
                 !rs->move_v || !rs->scene || !rs->weights || !(rs->mu > 0) || !isfinite(rs->mu))
            rc = sasnav_set_error(SASNAV_ERR_ARG, "the refinement state to resume is invalid");
    }
    if (!rc) {
        for (size_t i = 0; i < c.np; i++) c.w[i] = 1.0f;
        sasnav_grid_points(&grid, (sasnav_pose){0, 0, 0}, px, py);
        memcpy(cur, nav_in, sizeof *cur * n);
        if (rs) {
            memcpy(cur, rs->poses, sizeof *cur * n);
            memcpy(s, rs->scene, sizeof *s * c.np);
            memcpy(c.w, rs->weights, sizeof *c.w * c.np);
            c.mu = rs->mu;
        }
    }
    for (int p = 0; p < n && !rc; p++) {
        rc = sasnav_op_create(&run->sys, &run->array, &run->win, (int)c.np, px, py, &oo, &c.op[p]);
        if (!rc) rc = sasnav_op_set_ping(c.op[p], &cur[p], run->channel_offset);
    }
    for (int t = 0; t < c.nthreads && !rc; t++)
        rc = sasnav_op_create(&run->sys, &run->array, &run->win, (int)c.np, px, py, &oo, &c.top[t]);

    sasnav_refine_report rep;
    memset(&rep, 0, sizeof rep);
    double *mu_ = malloc(sizeof(double) * n), *mv_ = malloc(sizeof(double) * n);
    if (!rc && (!mu_ || !mv_)) rc = sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    if (!rc) {
        for (int p = 0; p < n; p++) mu_[p] = mv_[p] = 0;
        if (rs) {
            memcpy(mu_, rs->move_u, sizeof(double) * n);
            memcpy(mv_, rs->move_v, sizeof(double) * n);
            rep = rs->report;
        }
    }
    sasnav_ping_pose *saved = malloc(sizeof *saved * n);
    double *saved_u = malloc(sizeof(double) * n), *saved_v = malloc(sizeof(double) * n);
    if (!rc && (!saved || !saved_u || !saved_v)) rc = sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    int first = !(rs && rs->sweeps_done > 0);
    int sw0 = rs ? (rs->finished ? o.sweeps : rs->sweeps_done) : 0;
    double t_prior = rs ? rs->report.seconds : 0; /* sweeps before the resumption */
    for (int sw = sw0; sw < o.sweeps && !rc; sw++) {
        double sum_cost = 0, sum_move = 0, sum_before = 0;
        memcpy(saved, cur, sizeof *saved * n);
        memcpy(saved_u, mu_, sizeof(double) * n);
        memcpy(saved_v, mv_, sizeof(double) * n);
        for (int q = 0; q < n && !rc; q++) {
            rc = scene_solve(&c, q, first ? o.cg_first : o.cg_iterations, s, r, d, ad);
            first = 0;
            if (!rc && o.sparsity > 0) update_weights(&c, s);
            double u = 0, v = 0, cost = 0;
            if (!rc) {
                misfit_arg a = {&c, q, 0, &cur[q], s, energy(sasnav_run_ping(run, q), c.nd), SASNAV_OK, 0};
                sum_before += misfit(&a, 0, 0);
                rc = a.rc;
            }
            if (!rc) {
                /* Later sweeps: a local search around the current pose,
                 * four times the previous sweep's rms move wide. */
                double w = sw ? 4.0 * rep.rms_move[sw - 1] : 0;
                rc = fit_ping(&c, q, &cur[q], s, sw == 0, fmin(o.surge_range, fmax(w, 1e-3)),
                              fmin(o.sway_range, fmax(w, 5e-4)), mu_[q], mv_[q], &u, &v, &cost);
            }
            if (!rc) {
                cur[q] = moved(&cur[q], u, v);
                mu_[q] += u;
                mv_[q] += v;
                rc = sasnav_op_set_ping(c.op[q], &cur[q], run->channel_offset);
                sum_cost += cost;
                sum_move += u * u + v * v;
            }
        }
        if (rc) break;
        if (sw == 0) rep.misfit[0] = sum_before / n;
        if (sw > 0 && sum_cost / n > 1.1 * rep.misfit[sw]) {
            /* The sweep made the leave-one-out predictions clearly worse on
             * the whole (by more than 10%; smaller changes are the scenes'
             * noise): undo it and stop (docs/navigation.md). */
            memcpy(cur, saved, sizeof *cur * n);
            memcpy(mu_, saved_u, sizeof(double) * n);
            memcpy(mv_, saved_v, sizeof(double) * n);
            rep.undone = 1;
            break;
        }
        rep.misfit[sw + 1] = sum_cost / n;
        rep.rms_move[sw] = sqrt(sum_move / n);
        rep.sweeps = sw + 1;
        int stop = rep.rms_move[sw] < o.stop_move;
        if (o.sweep_done) {
            sasnav_refine_state st = {digest, n, (int)c.np, sw + 1, stop || sw + 1 == o.sweeps, c.mu, cur,
                                      mu_, mv_, s, c.w, rep};
            st.report.seconds = t_prior + sasnav_now_seconds() - t0;
            o.sweep_done(&st, o.sweep_user);
        }
        if (stop) break;
    }
    if (!rc) {
        /* Gauge: remove the common move. */
        double au = 0, av = 0;
        for (int p = 0; p < n; p++) {
            au += mu_[p];
            av += mv_[p];
        }
        au /= n;
        av /= n;
        rep.unreliable = !(rep.misfit[0] <= SASNAV_REFINE_MISFIT_MAX);
        rep.mean_move_surge = au;
        rep.mean_move_sway = av;
        for (int p = 0; p < n; p++) nav_out[p] = moved(&cur[p], -au, -av);
        rep.seconds = t_prior + sasnav_now_seconds() - t0;
        if (report) *report = rep;
    }
    for (int p = 0; c.op && p < n; p++) sasnav_op_destroy(c.op[p]);
    for (int t = 0; c.top && t < c.nthreads; t++) sasnav_op_destroy(c.top[t]);
    free(c.op);
    free(c.top);
    free(c.tb);
    free(c.td);
    free(c.td2);
    free(c.w);
    free(px);
    free(py);
    free(cur);
    free(s);
    free(r);
    free(d);
    free(ad);
    free(mu_);
    free(mv_);
    free(saved);
    free(saved_u);
    free(saved_v);
    return rc;
}

/* --- windows over long runs ----------------------------------------------- */

/* Adds window w's report to the joined one (sums; refine_windows finishes
 * the means). */
static void add_window_report(sasnav_refine_report *all, const sasnav_refine_report *w, double *rms2)
{
    if (w->sweeps > all->sweeps) all->sweeps = w->sweeps;
    for (int i = 0; i <= SASNAV_REFINE_MAX_SWEEPS; i++)
        all->misfit[i] += w->misfit[i <= w->sweeps ? i : w->sweeps];
    for (int i = 0; i < SASNAV_REFINE_MAX_SWEEPS; i++)
        if (i < w->sweeps) rms2[i] += w->rms_move[i] * w->rms_move[i];
    all->undone |= w->undone;
    all->unreliable |= w->unreliable;
}

/* Start of window k of n pings in windows of W, `step` apart. */
static int window_start(int k, int n, int W, int step) { return k * step < n - W ? k * step : n - W; }

/* The window whose centre is nearest to ping i (the earlier on a tie). */
static int window_owning(int i, int n, int W, int step)
{
    int n_win = (n - W + step - 1) / step + 1, best = 0;
    double best_d = HUGE_VAL;
    for (int k = 0; k < n_win; k++) {
        double d = fabs(i - (window_start(k, n, W, step) + 0.5 * (W - 1)));
        if (d < best_d) {
            best_d = d;
            best = k;
        }
    }
    return best;
}

int sasnav_refine_windows(const sasnav_run *run, const sasnav_ping_pose *nav_in, int window,
                          const sasnav_refine_opts *opts, sasnav_ping_pose *nav_out,
                          sasnav_refine_report *report, sasnav_refine_window_fn done, void *user)
{
    double t0 = sasnav_now_seconds();
    if (!run || !nav_in || !nav_out) return sasnav_set_error(SASNAV_ERR_ARG, "NULL argument");
    int n = run->n_pings;
    if (window > 0 && window < 3)
        return sasnav_set_error(SASNAV_ERR_ARG, "refine: a window needs at least 3 pings (got %d)", window);
    int whole = window <= 0 || window >= n;
    if (!whole && opts && (opts->sweep_done || opts->resume))
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "refine: checkpoints work on one window only (a run of at most %d pings)", window);
    int W = whole ? n : window, step = W / 2 > 0 ? W / 2 : 1;
    int n_win = whole ? 1 : (n - W + step - 1) / step + 1;
    sasnav_refine_report rep, wrep;
    memset(&rep, 0, sizeof rep);
    double rms2[SASNAV_REFINE_MAX_SWEEPS] = {0};
    double *mx = malloc(sizeof(double) * 4 * (size_t)(n > 0 ? n : 1));
    int *pings = malloc(sizeof(int) * (size_t)(W > 0 ? W : 1));
    sasnav_ping_pose *wout = malloc(sizeof *wout * (size_t)(W > 0 ? W : 1));
    if (!mx || !pings || !wout) {
        free(mx);
        free(pings);
        free(wout);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    }
    double *my = mx + n, *px = mx + 2 * n, *py = mx + 3 * n; /* moves: joined, previous window's */
    double ox = 0, oy = 0;                                   /* window k's shift */
    int rc = SASNAV_OK, prev_start = -1;
    for (int k = 0; k < n_win && !rc; k++) {
        int s = whole ? 0 : window_start(k, n, W, step);
        for (int i = 0; i < W; i++) pings[i] = s + i;
        sasnav_run *sub = NULL;
        const sasnav_run *r = run;
        if (!run->raw || !whole) {
            rc = sasnav_run_subset(run, pings, W, NULL, 0, &sub);
            r = sub;
        }
        if (!rc) {
            rc = sasnav_refine(r, nav_in + s, opts, wout, &wrep);
            /* its pings are numbered from the window's first */
            if (rc && !whole) sasnav_prefix_error(rc, "window of pings %d-%d", s, s + W - 1);
        }
        sasnav_run_free(sub);
        if (rc) break;
        if (whole) {
            memcpy(nav_out, wout, sizeof *wout * (size_t)n);
            rep = wrep;
            if (done) done(1, 1, &wrep, user);
            break;
        }
        /* Window k's moves, and its shift onto window k - 1 over the pings
         * they share (prev_start + W > s: windows overlap by W - step). */
        double sx = 0, sy = 0;
        int shared = 0;
        for (int i = s; k > 0 && i < prev_start + W; i++, shared++) {
            sx += px[i] - (wout[i - s].array.x - nav_in[i].array.x);
            sy += py[i] - (wout[i - s].array.y - nav_in[i].array.y);
        }
        ox = shared > 0 ? sx / shared : 0;
        oy = shared > 0 ? sy / shared : 0;
        for (int i = s; i < s + W; i++) {
            double dx = wout[i - s].array.x - nav_in[i].array.x + ox;
            double dy = wout[i - s].array.y - nav_in[i].array.y + oy;
            if (window_owning(i, n, W, step) == k) {
                mx[i] = dx;
                my[i] = dy;
            }
            px[i] = dx;
            py[i] = dy;
        }
        prev_start = s;
        add_window_report(&rep, &wrep, rms2);
        if (done) done(k + 1, n_win, &wrep, user);
    }
    if (!rc && !whole) {
        /* The common move of the joined moves, removed; reported along and
         * across the run's mean heading. */
        double ax = 0, ay = 0, c = 0, sn = 0;
        for (int i = 0; i < n; i++) {
            ax += mx[i];
            ay += my[i];
            c += cos(nav_in[i].array.theta);
            sn += sin(nav_in[i].array.theta);
        }
        ax /= n;
        ay /= n;
        double h = atan2(sn, c);
        rep.mean_move_surge = ax * cos(h) + ay * sin(h);
        rep.mean_move_sway = -ax * sin(h) + ay * cos(h);
        for (int i = 0; i < n; i++) {
            sasnav_ping_pose q = nav_in[i];
            double dx = mx[i] - ax, dy = my[i] - ay;
            q.array.x += dx;
            q.array.y += dy;
            q.tx.x += dx;
            q.tx.y += dy;
            nav_out[i] = q;
        }
        for (int i = 0; i <= SASNAV_REFINE_MAX_SWEEPS; i++) rep.misfit[i] /= n_win;
        for (int i = 0; i < rep.sweeps; i++) rep.rms_move[i] = sqrt(rms2[i] / n_win);
    }
    rep.seconds = sasnav_now_seconds() - t0;
    if (!rc && report) *report = rep;
    free(mx);
    free(pings);
    free(wout);
    return rc;
}
