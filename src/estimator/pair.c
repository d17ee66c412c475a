/* The subspace-intersection error functions (paper Section III, SPEC 3).
 *
 * Two "levels" share the code: level 0 (coarse pixels, coarse k and i) for
 * the global stage and level 1 (full pixels, final k and i). Each level owns
 * the operators of p and q on its grid, the fixed reconstruction rho_p of
 * ping p (computed once per level: reuse of p's work across evaluations),
 * and work buffers. */
#include "pair_internal.h"
#include "operators/op_team.h"
#ifdef SASNAV_HAVE_CUDA
#include "gpu/gpu_eval.h"
#endif

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void sasnav_pair_default_opts(sasnav_pair_opts *o)
{
    memset(o, 0, sizeof *o);
    /* Final iterations: the paper's 5, 5 leave a surge bias of up to
     * ~1 mm; 8, 8 meet 0.5 mm on 9 of 10 draws (docs/estimator.md). */
    o->k = 8;
    o->i = 8;
    o->coarse_k = 2;
    o->coarse_i = 1;
    o->tikhonov = 0.0;
    o->norm = SASNAV_NORM_MAX;
    o->tx_lag = 0.10;
    o->range = 10.0;
    o->range_extent = 1.6;
    o->cross_extent = 0.0;
    o->pixel = 0.0;
    o->coarse_pixel = 0.0;
    o->search_grid = SASNAV_SEARCH_AUTO;
    o->blur = 0.075;
    o->verdict_eta_max = 0.6;
    o->verdict_margin_min = 1.15;
    o->verdict_coincidence = 0.5;
    o->verdict_margin_compact = 1.25;
    o->blur_cross = 0.0;
    o->error_extent = 0.0;
    o->error_taper = 0.0;
    o->box = (sasnav_pose){0.06, 0.035, 0.0};
    o->grid_step = (sasnav_pose){0.01, 0.01, 0.01};
    o->global_stage = 1;
    o->min_overlap = 1e-2;
    o->max_evaluations = 400;
    o->nthreads = 0;
    sasnav_op_default_opts(&o->op);
    /* The estimator's operators interpolate to 1e-3 (4 kernel taps instead
     * of 7 at 1e-6; relative model error ~2e-4, far below 30 dB noise):
     * 30 % faster, estimates within 3 microns of those at 1e-6 on 40 draws
     * (docs/estimator.md). Simulated data keep the operator's default. */
    o->op.tolerance = 1e-3;
    o->final_criterion = SASNAV_FINAL_AUTO;
    o->joint_k = 40;
    o->joint_mu = 1e-3;
    o->joint_shift_max = 0.125;
    o->joint_eta_ratio = INFINITY;
    o->joint_contrast_max = 5.0;
    o->verdict_contrast = 4.0;
    o->joint_coverage_min = 0.5;
    o->equalise = 0.05;
}

static double nrm2(const sasnav_cfloat *v, size_t n)
{
    double s = 0;
    for (size_t j = 0; j < n; j++) {
        double re = crealf(v[j]), im = cimagf(v[j]);
        s += re * re + im * im;
    }
    return sqrt(s);
}

static void level_free(pair_level *lv)
{
#ifdef SASNAV_HAVE_CUDA
    gpu_destroy(lv->gpu);
#endif
    if (!lv->borrowed) {
        sasnav_op_destroy(lv->op_p);
        sasnav_op_destroy(lv->op_q);
    }
    free(lv->rho_p);
    free(lv->rho_q);
    free(lv->psi_p);
    free(lv->psi_q);
    free(lv->tmp);
    free(lv->data_tmp);
    free(lv->cgls_work);
    free(lv->tmp2);
    free(lv->data_tmp2);
    free(lv->cgls_work2);
    free(lv->mod_p);
    free(lv->mod_q);
    free(lv->blur_tmp);
    free(lv->window);
    free(lv->eqw);
    free(lv->eq_gate);
#pragma omp critical(sasnav_fftw_planner)
    {
        if (lv->xc_fwd_p) fftwf_destroy_plan(lv->xc_fwd_p);
        if (lv->xc_fwd_q) fftwf_destroy_plan(lv->xc_fwd_q);
        if (lv->xc_inv) fftwf_destroy_plan(lv->xc_inv);
    }
    fftwf_free(lv->xc_p);
    fftwf_free(lv->xc_q);
    memset(lv, 0, sizeof *lv);
}

/* The scale (m) at which the equalising gate reads the smoothed
 * intensity's peak (EQUALISE_PEAK_MIN below), whatever opts.equalise
 * smooths the weights with: the peak over the mean falls as the smoothing
 * widens (on paper-trajectory pairs, against this scale's, 1.3-2.2x at
 * 2.5 cm, 0.5-0.8x at 10 cm), so a gate read at the weights' own scale
 * would mean something else at each setting. */
#define EQUALISE_GATE_BLUR 0.05

static int level_init(sasnav_pair *pr, pair_level *lv, double pixel, int k, int i)
{
    const sasnav_pair_opts *o = &pr->opts;
    memset(lv, 0, sizeof *lv);
    int nx = (int)floor(o->cross_extent / pixel) + 1;
    int ny = (int)floor(o->range_extent / pixel) + 1;
    if (nx < 2 || ny < 2)
        return sasnav_set_error(SASNAV_ERR_ARG, "estimation grid too small (%d x %d)", ny, nx);
    lv->k = k;
    lv->i = i;
    /* Placed around x = 0 here; sasnav_pair_set_data recentres it between
     * the pings by rebuilding the operators' points. */
    int rc = sasnav_grid_make(-0.5 * (nx - 1) * pixel, 0.5 * (nx - 1) * pixel, nx,
                              o->range - 0.5 * (ny - 1) * pixel, o->range + 0.5 * (ny - 1) * pixel,
                              ny, &lv->grid);
    if (rc) return rc;
    lv->np = (size_t)nx * ny;
    lv->nd = (size_t)pr->array.n_rx * pr->win.n_samples;
    size_t np = lv->np, nd = lv->nd;
    lv->rho_p = malloc(sizeof(sasnav_cfloat) * np);
    lv->rho_q = malloc(sizeof(sasnav_cfloat) * np);
    lv->psi_p = malloc(sizeof(sasnav_cfloat) * np);
    lv->psi_q = malloc(sizeof(sasnav_cfloat) * np);
    lv->tmp = malloc(sizeof(sasnav_cfloat) * np);
    lv->data_tmp = malloc(sizeof(sasnav_cfloat) * nd);
    lv->cgls_work = malloc(sizeof(sasnav_cfloat) * (2 * np + 2 * nd));
    lv->tmp2 = malloc(sizeof(sasnav_cfloat) * np);
    lv->data_tmp2 = malloc(sizeof(sasnav_cfloat) * nd);
    lv->cgls_work2 = malloc(sizeof(sasnav_cfloat) * (2 * np + 2 * nd));
    lv->mod_p = malloc(sizeof(double) * np);
    lv->mod_q = malloc(sizeof(double) * np);
    lv->blur_tmp = malloc(sizeof(double) * np);
    lv->window = malloc(sizeof(float) * np);
    /* the search's levels (0, 1) hold the equalising weights */
    int equalises = o->equalise > 0 && lv - pr->level < 2;
    if (equalises) lv->eqw = malloc(sizeof(double) * np);
    /* the gate reads level 1's peak only (make_levels) */
    int gate_apart = equalises && lv - pr->level == 1 && o->equalise != EQUALISE_GATE_BLUR;
    if (gate_apart) lv->eq_gate = malloc(sizeof(double) * np);
    if (!lv->rho_p || !lv->rho_q || !lv->psi_p || !lv->psi_q || !lv->tmp || !lv->data_tmp ||
        !lv->cgls_work || !lv->tmp2 || !lv->data_tmp2 || !lv->cgls_work2 || !lv->mod_p || !lv->mod_q || !lv->blur_tmp || !lv->window ||
        (equalises && !lv->eqw) || (gate_apart && !lv->eq_gate))
        return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory for the estimator");
    /* Correlation buffers zero-padded to twice the grid (linear, not
     * circular, correlation); plans made once here. */
    lv->xc_nx = 2 * nx;
    lv->xc_ny = 2 * ny;
    size_t nxc = (size_t)lv->xc_nx * lv->xc_ny;
    lv->xc_p = fftwf_malloc(sizeof(fftwf_complex) * nxc);
    lv->xc_q = fftwf_malloc(sizeof(fftwf_complex) * nxc);
    if (!lv->xc_p || !lv->xc_q) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory for the estimator");
    /* The FFTW planner is not re-entrant: same named section as the
     * operators' planning (src/operators/op.c). */
#pragma omp critical(sasnav_fftw_planner)
    {
        lv->xc_fwd_p = fftwf_plan_dft_2d(lv->xc_ny, lv->xc_nx, lv->xc_p, lv->xc_p, FFTW_FORWARD, FFTW_ESTIMATE);
        lv->xc_fwd_q = fftwf_plan_dft_2d(lv->xc_ny, lv->xc_nx, lv->xc_q, lv->xc_q, FFTW_FORWARD, FFTW_ESTIMATE);
        lv->xc_inv = fftwf_plan_dft_2d(lv->xc_ny, lv->xc_nx, lv->xc_q, lv->xc_q, FFTW_BACKWARD, FFTW_ESTIMATE);
    }
    if (!lv->xc_fwd_p || !lv->xc_fwd_q || !lv->xc_inv)
        return sasnav_set_error(SASNAV_ERR_FFT, "FFTW could not plan the image correlation");
    return SASNAV_OK;
}

/* The level that owns the operators used at `level` (level 2 shares level
 * 1's grid, hence its operators). */
static pair_level *ops_owner(sasnav_pair *pr, int level)
{
    return level == 2 ? &pr->level[1] : &pr->level[level];
}

/* Operator applications of k CGLS iterations (sasnav_cgls: T^H once, then
 * T and T^H per iteration but the last's T^H). The counts are nominal: an
 * early stop of CGLS does fewer. */
static long cgls_cost(int k) { return 2L * k; }

/* The contrast of an image's intensity |rho|^2 over the level's error
 * window (standard deviation over mean): about 1 for fully developed
 * speckle, 1.7-3.9 on the simulated seabeds, 6-13 on the tank's four
 * reflectors (docs/estimator.md, "A joint-misfit final stage"). */
static double window_contrast(const pair_level *lv, const sasnav_cfloat *rho)
{
    double s1 = 0, s2 = 0, w = 0;
    for (size_t j = 0; j < lv->np; j++) {
        double iv = (double)crealf(rho[j]) * crealf(rho[j]) + (double)cimagf(rho[j]) * cimagf(rho[j]);
        s1 += lv->window[j] * iv;
        s2 += lv->window[j] * iv * iv;
        w += lv->window[j];
    }
    double mean = w > 0 ? s1 / w : 0, var = w > 0 ? s2 / w - mean * mean : 0;
    return mean > 0 && var > 0 ? sqrt(var) / mean : 0.0;
}

static void blur_map(const sasnav_grid *g, double sigma_x, double sigma_y, double *f, double *tmp);
static int place_q(sasnav_pair *pr, int level, sasnav_pose error);

/* Floor of the equalising weights' intensity, as a fraction of its mean
 * over the error window: at most 1 / sqrt(0.1) = 3.2 times the weight of
 * a pixel of mean intensity where the seabed is dark. */
#define EQUALISE_FLOOR 0.1

/* The search is equalised where the full-pixel images of p and of q at the
 * prior both have an intensity contrast of at most this: speckle-like
 * seabeds (1.7-3.9 on the simulated ones), not a few bright reflectors
 * (the tank's 6-13). The verdict's default compact gate, but a constant of
 * its own: a verdict setting (opts.verdict_contrast) does not move the
 * estimates. */
#define EQUALISE_CONTRAST_MAX 4.0

/* ... and where the peak of the weights' intensity S, smoothed at
 * EQUALISE_GATE_BLUR, over the window (its inner part, taper >= 0.5) is at
 * least this times S's window-weighted mean (9 dB): a feature stands out.
 * On paper-trajectory runs pairs with the disc
 * out of view peak at 2.5-5.6 times the mean, at its edge up to 7.9, with
 * the disc in view at 8.6-30.8 (over 15.8 also over the contrast gate);
 * below the gate the weights changed estimates by at most 0.41 mm, either
 * way, at 1.3x the evaluations (docs/estimator.md, "the peak gate"). */
#define EQUALISE_PEAK_MIN 8.0

/* The window-weighted mean of a map S over the error window; with peak,
 * also the largest S in the window's inner part (taper >= 0.5) over that
 * mean (0 where the window sees nothing). */
static double window_peak(const pair_level *lv, const double *S, double *peak_ratio)
{
    double s = 0, w = 0, peak = 0;
    for (size_t j = 0; j < lv->np; j++) {
        s += lv->window[j] * S[j];
        w += lv->window[j];
        if (lv->window[j] >= 0.5f && S[j] > peak) peak = S[j];
    }
    if (peak_ratio) *peak_ratio = w > 0 && s > 0 ? peak / (s / w) : 0.0;
    return w > 0 ? s / w : 0.0;
}

/* The search's equalising weights of a level (opts.equalise): q's
 * reconstruction at the prior, then w = 1 / sqrt(S + floor), S = |rho_p|^2
 * + |rho_q|^2 smoothed by a Gaussian of opts.equalise metres (both axes),
 * floor = EQUALISE_FLOOR x the window's mean of S; and the gates: q's
 * contrast there, and S's peak over its mean with S smoothed at
 * EQUALISE_GATE_BLUR. Leaves rho_q as q's image at the prior (a scratch buffer:
 * each evaluation makes its own). */
static int level_weights(sasnav_pair *pr, pair_level *lv)
{
    int level = (int)(lv - pr->level);
    int rc = place_q(pr, level, pr->opts.prior);
    if (rc) return rc;
    sasnav_cgls_opts co = {lv->k, pr->opts.tikhonov};
    rc = sasnav_cgls(ops_owner(pr, level)->op_q, pr->data_q, &co, lv->rho_q, lv->cgls_work);
    pr->applications += cgls_cost(lv->k);
    if (rc) return rc;
    lv->last_valid = 0;
    lv->contrast_q0 = window_contrast(lv, lv->rho_q);
    for (size_t j = 0; j < lv->np; j++) {
        double a = crealf(lv->rho_p[j]), b = cimagf(lv->rho_p[j]);
        double c = crealf(lv->rho_q[j]), d = cimagf(lv->rho_q[j]);
        lv->eqw[j] = a * a + b * b + c * c + d * d;
    }
    if (lv->eq_gate) {
        memcpy(lv->eq_gate, lv->eqw, sizeof(double) * lv->np);
        blur_map(&lv->grid, EQUALISE_GATE_BLUR, EQUALISE_GATE_BLUR, lv->eq_gate, lv->blur_tmp);
        window_peak(lv, lv->eq_gate, &lv->eq_peak);
    }
    blur_map(&lv->grid, pr->opts.equalise, pr->opts.equalise, lv->eqw, lv->blur_tmp);
    double mean = window_peak(lv, lv->eqw, lv->eq_gate ? NULL : &lv->eq_peak);
    double floor_ = EQUALISE_FLOOR * mean;
    if (!(floor_ > 0)) floor_ = 1.0; /* nothing seen: weights uniform */
    for (size_t j = 0; j < lv->np; j++) lv->eqw[j] = 1.0 / sqrt(lv->eqw[j] + floor_);
    return SASNAV_OK;
}

/* p's reconstruction on the level's grid, with the level's iterations
 * (and the level's equalising weights). */
static int level_rho_p(sasnav_pair *pr, pair_level *lv)
{
    const pair_level *src = pr->twin_of ? &pr->twin_of->level[lv - pr->level] : NULL;
    if (src && src->np == lv->np && src->k == lv->k) {
        memcpy(lv->rho_p, src->rho_p, sizeof(sasnav_cfloat) * lv->np);
        lv->rho_p_norm = src->rho_p_norm;
        lv->contrast = src->contrast;
        if (lv->eqw && src->eqw) memcpy(lv->eqw, src->eqw, sizeof(double) * lv->np);
        lv->contrast_q0 = src->contrast_q0;
        lv->eq_peak = src->eq_peak;
        return SASNAV_OK;
    }
    sasnav_cgls_opts co = {lv->k, pr->opts.tikhonov};
    int rc = sasnav_cgls(lv->op_p, pr->data_p, &co, lv->rho_p, lv->cgls_work);
    pr->applications += cgls_cost(lv->k);
    if (rc) return rc;
    lv->rho_p_norm = nrm2(lv->rho_p, lv->np);
    lv->contrast = window_contrast(lv, lv->rho_p);
    if (!(lv->rho_p_norm > 0))
        return sasnav_set_error(SASNAV_ERR_NO_OVERLAP,
                                "ping p sees nothing on the estimation grid (range %g m): "
                                "check the range of interest", pr->opts.range);
    return lv->eqw ? level_weights(pr, lv) : SASNAV_OK;
}

static int level_make_ops(sasnav_pair *pr, pair_level *lv, double xcentre, pair_level *share)
{
    if (!lv->borrowed) {
        sasnav_op_destroy(lv->op_p);
        sasnav_op_destroy(lv->op_q);
    }
    /* The GPU context is kept (gpu_project makes a new one only where the
     * new operators do not fit it); its points and geometries are set
     * again. */
    lv->gpu_q_placed = lv->gpu_points = 0;
    lv->op_p = lv->op_q = NULL;
    lv->borrowed = 0;
    lv->q_placed = 0;
    lv->last_valid = 0;
    lv->n_kept = lv->next_kept = 0;
    double w = (lv->grid.nx - 1) * lv->grid.dx;
    lv->grid.x0 = xcentre - 0.5 * w;
    if (share) {
        /* Same grid as `share` (same pixel, extents and centre): use its
         * operators; p's geometry is already set on them. */
        lv->op_p = share->op_p;
        lv->op_q = share->op_q;
        lv->borrowed = 1;
        memcpy(lv->window, share->window, sizeof(float) * lv->np);
        return level_rho_p(pr, lv);
    }
    double *x = malloc(sizeof(double) * lv->np), *y = malloc(sizeof(double) * lv->np);
    if (!x || !y) {
        free(x);
        free(y);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory for the estimator grid");
    }
    sasnav_pose id = {0, 0, 0};
    sasnav_grid_points(&lv->grid, id, x, y);
    /* Flat over the central error_extent along track, raised-cosine tapers
     * of error_taper on both sides, zero beyond. */
    double half = 0.5 * pr->opts.error_extent, taper = pr->opts.error_taper;
    for (size_t j = 0; j < lv->np; j++) {
        double u = fabs(x[j] - xcentre) - half;
        lv->window[j] = u <= 0 ? 1.0f : u >= taper ? 0.0f : (float)(0.5 + 0.5 * cos(M_PI * u / taper));
    }
    sasnav_op_opts oo = pr->opts.op;
    oo.nthreads = pr->opts.nthreads > 0 ? pr->opts.nthreads : omp_get_max_threads();
    if (oo.nthreads > PAIR_OP_THREADS_MAX) oo.nthreads = PAIR_OP_THREADS_MAX;
    int rc = sasnav_op_create(&pr->sys, &pr->array, &pr->win, (int)lv->np, x, y, &oo, &lv->op_p);
    if (!rc) rc = sasnav_op_create(&pr->sys, &pr->array, &pr->win, (int)lv->np, x, y, &oo, &lv->op_q);
    free(x);
    free(y);
    if (rc) return rc;
    /* Ping p sits at the origin of its own centroid frame. */
    rc = pr->per_channel ? sasnav_op_set_channels(lv->op_p, pr->chan_p)
                         : sasnav_op_set_geometry(lv->op_p, &pr->local_p);
    if (rc) return rc;
    return level_rho_p(pr, lv);
}

int sasnav_pair_opts_check(const sasnav_pair_opts *o)
{
#define OPT_FAIL(...) return sasnav_set_error(SASNAV_ERR_ARG, "estimator options: " __VA_ARGS__)
    if (!o) OPT_FAIL("NULL");
    if (o->k < 1 || o->i < 1) OPT_FAIL("k = %d and i = %d must be >= 1", o->k, o->i);
    if (o->coarse_k < 1 || o->coarse_i < 1)
        OPT_FAIL("coarse_k = %d and coarse_i = %d must be >= 1", o->coarse_k, o->coarse_i);
    if (!(o->range > 0) || !isfinite(o->range)) OPT_FAIL("range %g m must be > 0", o->range);
    if (!(o->range_extent > 0) || !isfinite(o->range_extent))
        OPT_FAIL("range_extent %g m must be > 0", o->range_extent);
    if (!(o->cross_extent >= 0) || !isfinite(o->cross_extent))
        OPT_FAIL("cross_extent %g m must be >= 0", o->cross_extent);
    if (!(o->tx_lag >= 0) || !isfinite(o->tx_lag)) OPT_FAIL("tx_lag %g m must be >= 0", o->tx_lag);
    if (!(o->blur >= 0) || !isfinite(o->blur)) OPT_FAIL("blur %g must be >= 0", o->blur);
    if (!(o->yaw_sigma >= 0) || !isfinite(o->yaw_sigma))
        OPT_FAIL("yaw_sigma %g rad must be finite and >= 0", o->yaw_sigma);
    if (!(o->surge_sigma >= 0) || !isfinite(o->surge_sigma))
        OPT_FAIL("surge_sigma %g m must be finite and >= 0", o->surge_sigma);
    if (o->fix_yaw && o->yaw_sigma > 0)
        OPT_FAIL("fix_yaw and yaw_sigma > 0 exclude each other (a held yaw has no prior)");
    if (!(o->box.x >= 0 && o->box.y >= 0 && o->box.theta >= 0))
        OPT_FAIL("the search box half-widths must be >= 0");
    if (!(o->verdict_eta_max > 0)) OPT_FAIL("verdict_eta_max %g must be > 0", o->verdict_eta_max);
    if (!(o->verdict_margin_min >= 1) || !isfinite(o->verdict_margin_min))
        OPT_FAIL("verdict_margin_min %g must be finite and >= 1", o->verdict_margin_min);
    if (!(o->verdict_coincidence >= 0 && o->verdict_coincidence <= 0.5))
        OPT_FAIL("verdict_coincidence %g must be in [0, 0.5]", o->verdict_coincidence);
    if (!(o->verdict_margin_compact >= 1) || !isfinite(o->verdict_margin_compact))
        OPT_FAIL("verdict_margin_compact %g must be finite and >= 1", o->verdict_margin_compact);
    if (o->gpu != 0 && o->gpu != 1) OPT_FAIL("gpu = %d must be 0 or 1", o->gpu);
    if (o->final_criterion != SASNAV_FINAL_ETA && o->final_criterion != SASNAV_FINAL_JOINT &&
        o->final_criterion != SASNAV_FINAL_AUTO)
        OPT_FAIL("final_criterion = %d must be SASNAV_FINAL_ETA, _JOINT or _AUTO", o->final_criterion);
    if (!(o->joint_shift_max >= 0) || !isfinite(o->joint_shift_max))
        OPT_FAIL("joint_shift_max %g must be finite and >= 0", o->joint_shift_max);
    if (o->search_grid < SASNAV_SEARCH_AUTO || o->search_grid > SASNAV_SEARCH_COARSE)
        OPT_FAIL("search_grid %d is not a sasnav_search_grid", o->search_grid);
    if (!(o->joint_contrast_max >= 0)) OPT_FAIL("joint_contrast_max %g must be >= 0", o->joint_contrast_max);
    if (!(o->joint_coverage_min >= 0) || !isfinite(o->joint_coverage_min))
        OPT_FAIL("joint_coverage_min %g must be finite and >= 0", o->joint_coverage_min);
    if (!(o->equalise >= 0) || !isfinite(o->equalise))
        OPT_FAIL("equalise %g must be finite and >= 0 (0: off)", o->equalise);
    if (!(o->verdict_contrast >= 0))
        OPT_FAIL("verdict_contrast %g must be >= 0 (inf: no compact-scene verdict)", o->verdict_contrast);
    if (!(o->joint_eta_ratio >= 1))
        OPT_FAIL("joint_eta_ratio %g must be >= 1 (inf: never reject the joint estimate)", o->joint_eta_ratio);
    if (o->joint_k < 1) OPT_FAIL("joint_k = %d must be >= 1", o->joint_k);
    if (!(o->joint_mu >= 0) || !isfinite(o->joint_mu)) OPT_FAIL("joint_mu %g must be finite and >= 0", o->joint_mu);
#undef OPT_FAIL
#ifndef SASNAV_HAVE_CUDA
    if (o->gpu)
        return sasnav_set_error(SASNAV_ERR_UNSUPPORTED,
                                "estimator options: gpu = 1, but this build has no CUDA "
                                "(configure with -DSASNAV_CUDA=ON)");
#endif
    return SASNAV_OK;
}

int sasnav_pair_create(const sasnav_system *sys, const sasnav_array *array,
                       const sasnav_window *win, const sasnav_pair_opts *opts,
                       sasnav_pair **out)
{
    if (!sys || !array || !win || !out) return sasnav_set_error(SASNAV_ERR_ARG, "NULL argument");
    *out = NULL;
    int rc = sasnav_system_check(sys);
    if (!rc) rc = sasnav_array_check(array);
    if (rc) return rc;
    if (win->n_samples < 1) return sasnav_set_error(SASNAV_ERR_ARG, "empty sample window");
    sasnav_pair *pr = calloc(1, sizeof *pr);
    if (!pr) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    pr->sys = *sys;
    pr->array = *array;
    pr->win = *win;
    if (opts) pr->opts = *opts;
    else sasnav_pair_default_opts(&pr->opts);
    sasnav_pair_opts *o = &pr->opts;
    rc = sasnav_pair_opts_check(o);
#ifdef SASNAV_HAVE_CUDA
    if (!rc && o->gpu) rc = gpu_check_device(); /* at once, not at the first evaluation */
#endif
    if (rc) {
        free(pr);
        return rc;
    }
    /* The coarse stages never use more iterations than the final one. */
    if (o->coarse_k > o->k) o->coarse_k = o->k;
    if (o->coarse_i > o->i) o->coarse_i = o->i;
    if (!(o->pixel > 0)) {
        o->pixel = sys->sound_speed / (4.0 * sys->bandwidth);
        double d_rx = sasnav_array_min_rx_length(array);
        if (d_rx > 0 && d_rx / 4.0 < o->pixel) o->pixel = d_rx / 4.0;
    }
    if (!(o->coarse_pixel > 0)) o->coarse_pixel = 2.0 * o->pixel;
    double lambda = sasnav_wavelength(sys);
    double dmax = 0.0; /* the largest aperture over the channels */
    for (int l = 0; l < (array->per_channel ? array->n_rx : 1); l++) {
        sasnav_channel_size z = sasnav_array_channel_size(array, l);
        dmax = fmax(dmax, fmax(z.rx_length, z.tx_length));
    }
    pr->footprint = dmax > lambda ? 2.0 * o->range * lambda / sqrt(dmax * dmax - lambda * lambda) : INFINITY;
    if (!(o->cross_extent > 0)) {
        /* 80 % of the along-track footprint between the first nulls of the
         * element beam at the grid's range (1.6 m in paper-pair). Echoes
         * from outside the grid fold onto its edges; measured on paper-pair
         * (docs/estimator.md) 80 % gave smaller surge biases than 50 %,
         * 100 % or 150 %. */
        o->cross_extent = dmax > lambda ? 1.6 * o->range * lambda / sqrt(dmax * dmax - lambda * lambda) : 4.0;
        if (o->cross_extent < 0.5) o->cross_extent = 0.5;
        if (o->cross_extent > 4.0) o->cross_extent = 4.0;
    }
    if (!(o->error_extent > 0)) o->error_extent = o->cross_extent;
    if (o->error_taper < 0) o->error_taper = 0;
    if (!(o->box.theta > 0)) {
        /* Yaw is unambiguous within +-lambda / (4 d) of the truth, d the
         * phase-centre spacing (a grating lobe of the phase-centre sampling
         * sits lambda / (2 d) away): stay within 90 % of it. */
        double d = array->n_rx > 1 ? 0.5 * fabs(array->rx_u[1] - array->rx_u[0]) : dmax / 2.0;
        o->box.theta = d > 0 ? 0.9 * lambda / (4.0 * d) : 0.05;
    }
    pr->local_p = pr->local_q = sasnav_epca_local(o->tx_lag, 0.0);
    pr->nd = (size_t)array->n_rx * win->n_samples;
    pr->data_p = malloc(sizeof(sasnav_cfloat) * pr->nd);
    pr->data_q = malloc(sizeof(sasnav_cfloat) * pr->nd);
    pr->chan_p = malloc(sizeof(sasnav_ping_pose) * (size_t)array->n_rx);
    pr->chan_q = malloc(sizeof(sasnav_ping_pose) * (size_t)array->n_rx);
    if (!pr->data_p || !pr->data_q || !pr->chan_p || !pr->chan_q) {
        sasnav_pair_destroy(pr);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    }
    rc = level_init(pr, &pr->level[0], o->coarse_pixel, o->coarse_k, o->coarse_i);
    if (!rc) rc = level_init(pr, &pr->level[1], o->pixel, o->coarse_k, o->coarse_i);
    if (!rc) rc = level_init(pr, &pr->level[2], o->pixel, o->k, o->i);
    if (rc) {
        sasnav_pair_destroy(pr);
        return rc;
    }
    *out = pr;
    return SASNAV_OK;
}

static void drop_twins(sasnav_pair *pr)
{
    for (int t = 0; t < pr->n_twins; t++) sasnav_pair_destroy(pr->twin[t]);
    pr->n_twins = 0;
    pr->twin_failed = 0;
}

void sasnav_pair_destroy(sasnav_pair *pr)
{
    if (!pr) return;
    drop_twins(pr);
    for (int v = 0; v < PAIR_LEVELS; v++) level_free(&pr->level[v]);
    free(pr->data_p);
    free(pr->data_q);
    free(pr->chan_p);
    free(pr->chan_q);
    free(pr->joint_x);
    free(pr->joint_work);
    free(pr);
}

static int check_channels(const sasnav_pair *pr, const sasnav_cfloat *d, const char *which)
{
    int ns = pr->win.n_samples;
    for (int l = 0; l < pr->array.n_rx; l++) {
        double e = 0;
        for (int m = 0; m < ns; m++) {
            sasnav_cfloat v = d[(size_t)l * ns + m];
            if (!isfinite(crealf(v)) || !isfinite(cimagf(v)))
                return sasnav_set_error(SASNAV_ERR_ARG, "ping %s channel %d holds a non-finite sample",
                                        which, l);
            e += crealf(v) * crealf(v) + cimagf(v) * cimagf(v);
        }
        if (!(e > 0))
            return sasnav_set_error(SASNAV_ERR_ARG, "ping %s channel %d is empty (missing channel)",
                                    which, l);
    }
    return SASNAV_OK;
}

int sasnav_pair_set_data(sasnav_pair *pr, const sasnav_cfloat *data_p,
                         const sasnav_cfloat *data_q, sasnav_pose nominal)
{
    if (!pr) return sasnav_set_error(SASNAV_ERR_ARG, "NULL argument");
    return sasnav_pair_set_data_lags(pr, data_p, data_q, nominal, pr->opts.tx_lag, pr->opts.tx_lag);
}

/* Checks and copies the two pings' data and the nominal displacement. */
static int take_data(sasnav_pair *pr, const sasnav_cfloat *data_p, const sasnav_cfloat *data_q,
                     sasnav_pose nominal)
{
    if (!isfinite(nominal.x) || !isfinite(nominal.y) || !isfinite(nominal.theta))
        return sasnav_set_error(SASNAV_ERR_ARG, "nominal displacement is not finite");
    int rc = check_channels(pr, data_p, "p");
    if (!rc) rc = check_channels(pr, data_q, "q");
    if (rc) return rc;
    if (data_p == data_q || !memcmp(data_p, data_q, sizeof(sasnav_cfloat) * pr->nd))
        return sasnav_set_error(SASNAV_ERR_ARG, "pings p and q hold identical data (the same ping twice?)");
    memcpy(pr->data_p, data_p, sizeof(sasnav_cfloat) * pr->nd);
    memcpy(pr->data_q, data_q, sizeof(sasnav_cfloat) * pr->nd);
    pr->nominal = nominal;
    return SASNAV_OK;
}

/* Builds the operators of every level for the data and geometry set. */
static int make_levels(sasnav_pair *pr)
{
    int rc = SASNAV_OK;
    drop_twins(pr); /* of the previous data */
    double xc = 0.5 * pr->nominal.x;
    for (int v = 0; v < PAIR_LEVELS && !rc; v++)
        rc = level_make_ops(pr, &pr->level[v], xc, v == 2 ? &pr->level[1] : NULL);
    /* The search is equalised on scenes speckle-like at the prior by the
     * full-pixel images (level 1) of both pings, where a feature stands
     * out of the smoothed intensity. */
    const pair_level *l1 = &pr->level[1];
    pr->equalised = !rc && pr->level[0].eqw && l1->eqw &&
                    (l1->contrast > l1->contrast_q0 ? l1->contrast : l1->contrast_q0) <= EQUALISE_CONTRAST_MAX &&
                    l1->eq_peak >= EQUALISE_PEAK_MIN;
    pr->eq_suspended = 0;
    pr->ready = (rc == 0);
    return rc;
}

int sasnav_pair_set_data_lags(sasnav_pair *pr, const sasnav_cfloat *data_p,
                              const sasnav_cfloat *data_q, sasnav_pose nominal, double lag_p,
                              double lag_q)
{
    if (!pr || !data_p || !data_q) return sasnav_set_error(SASNAV_ERR_ARG, "NULL argument");
    if (!(lag_p >= 0) || !(lag_q >= 0) || !isfinite(lag_p) || !isfinite(lag_q))
        return sasnav_set_error(SASNAV_ERR_ARG, "Tx-array offsets must be finite and >= 0 (got %g, %g)",
                                lag_p, lag_q);
    int rc = take_data(pr, data_p, data_q, nominal);
    if (rc) return rc;
    pr->ready = 0;
    pr->per_channel = 0;
    pr->pc_spacing = 0;
    pr->local_p = sasnav_epca_local(lag_p, 0.0);
    pr->local_q = sasnav_epca_local(lag_q, 0.0);
    return make_levels(pr);
}

/* Mean spacing of the phase centres of a channel layout along its frame's
 * x axis: their extent over (n - 1). */
static double layout_pc_spacing(const sasnav_array *array, const sasnav_ping_pose *ch)
{
    double lo = INFINITY, hi = -INFINITY;
    for (int l = 0; l < array->n_rx; l++) {
        double xc = pair_phase_centre_x(array, &ch[l], l);
        lo = xc < lo ? xc : lo;
        hi = xc > hi ? xc : hi;
    }
    return array->n_rx > 1 ? (hi - lo) / (array->n_rx - 1) : 0.0;
}

int sasnav_pair_set_data_channels(sasnav_pair *pr, const sasnav_cfloat *data_p,
                                  const sasnav_cfloat *data_q, sasnav_pose nominal,
                                  const sasnav_ping_pose *channels_p,
                                  const sasnav_ping_pose *channels_q)
{
    if (!pr || !data_p || !data_q || !channels_p || !channels_q)
        return sasnav_set_error(SASNAV_ERR_ARG, "NULL argument");
    for (int l = 0; l < pr->array.n_rx; l++) {
        const sasnav_ping_pose *c[2] = {&channels_p[l], &channels_q[l]};
        for (int j = 0; j < 2; j++)
            if (!isfinite(c[j]->tx.x) || !isfinite(c[j]->tx.y) || !isfinite(c[j]->tx.theta) ||
                !isfinite(c[j]->array.x) || !isfinite(c[j]->array.y) ||
                !isfinite(c[j]->array.theta))
                return sasnav_set_error(SASNAV_ERR_ARG, "channel %d of ping %s: pose is not finite",
                                        l, j ? "q" : "p");
    }
    int rc = take_data(pr, data_p, data_q, nominal);
    if (rc) return rc;
    pr->ready = 0;
    size_t bytes = sizeof(sasnav_ping_pose) * (size_t)pr->array.n_rx;
    memcpy(pr->chan_p, channels_p, bytes);
    memcpy(pr->chan_q, channels_q, bytes);
    pr->per_channel = 1;
    double sp = layout_pc_spacing(&pr->array, channels_p);
    pr->pc_spacing = sp > 0 ? sp : 0.0;
    return make_levels(pr);
}

/* Ping p's channels in its PCA-centroid frame (navigation and offsets;
 * the transmitter turned by tx_yaw[p] where its heading is the array's). */
static void run_layout(const sasnav_run *run, int p, const double *tx_yaw, sasnav_ping_pose *local)
{
    sasnav_ping_pose ping = run->nav[p];
    if (tx_yaw && ping.tx.theta == ping.array.theta) ping.tx.theta += tx_yaw[p];
    sasnav_run_channel_poses(run, &ping, local);
    sasnav_pose c = sasnav_ping_centroid(&run->nav[p]);
    for (int l = 0; l < run->array.n_rx; l++) {
        local[l].tx = sasnav_pose_between(c, local[l].tx);
        local[l].array = sasnav_pose_between(c, local[l].array);
    }
}

int sasnav_tx_yaw_from_rates(int n, const double *epoch, const double *rate, const unsigned char *valid,
                             double interval, double *tx_yaw)
{
    if (n < 1 || !epoch || !rate || !valid || !tx_yaw) return sasnav_set_error(SASNAV_ERR_ARG, "NULL argument");
    if (!(interval >= 0) || !isfinite(interval))
        return sasnav_set_error(SASNAV_ERR_ARG, "transmitter yaw: interval %g must be finite and >= 0", interval);
    for (int p = 0; p < n; p++) {
        if (!isfinite(epoch[p]) || (p > 0 && !(epoch[p] > epoch[p - 1])))
            return sasnav_set_error(SASNAV_ERR_ARG, "transmitter yaw: epochs must be finite and strictly increasing "
                                                    "(entry %d)", p);
        if (p > 0 && valid[p] && !isfinite(rate[p]))
            return sasnav_set_error(SASNAV_ERR_ARG, "transmitter yaw: rate %d is not finite", p);
    }
    for (int p = 0; p < n; p++) {
        /* The heading of ping p is the array's at reception (epoch[p]); the
         * turn between transmission and reception is the rate at their
         * midpoint, interval / 2 before it: interpolated linearly between
         * the means of the two intervals around it, each placed at its
         * interval's middle. */
        int lo = p, hi = p + 1; /* intervals ending at p and at p + 1 */
        int ok_lo = lo >= 1 && valid[lo], ok_hi = hi < n && valid[hi];
        double r = 0.0;
        if (ok_lo && ok_hi) {
            double t = epoch[p] - 0.5 * interval;
            double m_lo = 0.5 * (epoch[lo - 1] + epoch[lo]), m_hi = 0.5 * (epoch[hi - 1] + epoch[hi]);
            double w = (t - m_lo) / (m_hi - m_lo);
            r = (1.0 - w) * rate[lo] + w * rate[hi];
        } else if (ok_lo || ok_hi) {
            r = rate[ok_lo ? lo : hi];
        }
        tx_yaw[p] = -interval * r;
    }
    return SASNAV_OK;
}

void sasnav_pair_result_carry(const sasnav_pair_result *first, sasnav_pair_result *again)
{
    if (!first || !again) return;
    again->n_candidates = first->n_candidates;
    memcpy(again->candidates, first->candidates, sizeof again->candidates);
    again->chosen = first->chosen;
    again->ambiguity = first->ambiguity;
    again->margin = first->margin;
    again->seconds += first->seconds;
    again->applications += first->applications;
    again->evaluations += first->evaluations;
}

int sasnav_run_tx_yaw_from_estimate(const sasnav_run *run, sasnav_pose displacement, double range,
                                    double *tx_yaw)
{
    if (!run || !tx_yaw) return sasnav_set_error(SASNAV_ERR_ARG, "NULL argument");
    double interval = run->tx_lag > 0 ? run->tx_lag : run->speed * 2.0 * range / run->sys.sound_speed;
    double len = hypot(displacement.x, displacement.y);
    if (!(interval > 0) || !isfinite(interval) || !(len > 0) || !isfinite(displacement.theta))
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "transmitter yaw: no distance between transmission and reception (tx_lag %g m, "
                                "speed %g m/s) or no step (%g m)",
                                run->tx_lag, run->speed, len);
    double yaw = -interval * displacement.theta / len;
    for (int p = 0; p < run->n_pings; p++) tx_yaw[p] = yaw;
    return SASNAV_OK;
}

int sasnav_run_tx_yaw(const sasnav_run *run, double range, double *tx_yaw)
{
    if (!run || !tx_yaw) return sasnav_set_error(SASNAV_ERR_ARG, "NULL argument");
    if (!run->aiding || !run->aiding->yaw_rate)
        return sasnav_set_error(SASNAV_ERR_ARG, "transmitter yaw: the run has no gyro measurements");
    /* The time the navigation's Tx-array offset stands for (the vehicle's
     * travel between transmission and reception), else the two-way delay. */
    double t2 = run->speed > 0 && run->tx_lag > 0 ? run->tx_lag / run->speed : 2.0 * range / run->sys.sound_speed;
    if (!(t2 >= 0) || !isfinite(t2))
        return sasnav_set_error(SASNAV_ERR_ARG, "transmitter yaw: interval %g s must be >= 0 (range %g m)", t2,
                                range);
    const sasnav_aiding *a = run->aiding;
    int n = run->n_pings;
    unsigned char *valid = malloc((size_t)n);
    if (!valid) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    for (int p = 0; p < n; p++) valid[p] = isfinite(a->yaw_rate_sigma[p]) != 0;
    int rc = sasnav_tx_yaw_from_rates(n, a->time, a->yaw_rate, valid, t2, tx_yaw);
    free(valid);
    return rc;
}

int sasnav_pair_set_data_run(sasnav_pair *pr, const sasnav_run *run, int p, int q,
                             const sasnav_cfloat *data_p, const sasnav_cfloat *data_q, sasnav_pose nominal,
                             const double *tx_yaw)
{
    if (!pr || !run) return sasnav_set_error(SASNAV_ERR_ARG, "NULL argument");
    if (!run->channel_offset) return sasnav_pair_set_data(pr, data_p, data_q, nominal);
    if (p < 0 || q < 0 || p >= run->n_pings || q >= run->n_pings)
        return sasnav_set_error(SASNAV_ERR_ARG, "pair (%d, %d) outside the run's %d pings", p, q, run->n_pings);
    if (run->array.n_rx != pr->array.n_rx)
        return sasnav_set_error(SASNAV_ERR_ARG, "the run has %d channels, the estimator %d", run->array.n_rx,
                                pr->array.n_rx);
    sasnav_ping_pose lp[SASNAV_MAX_RX], lq[SASNAV_MAX_RX];
    run_layout(run, p, tx_yaw, lp);
    run_layout(run, q, tx_yaw, lq);
    return sasnav_pair_set_data_channels(pr, data_p, data_q, nominal, lp, lq);
}

/* |z| as glibc's cabsf computes it for finite z (hypotf: the float
 * squares summed in double, where they are exact, then one double square
 * root rounded to float; 2e8 random finite pairs gave the same bits), but
 * inline, so that the loops over a grid vectorise (the library call was
 * 1 % of `sasnav pair`). */
static inline float modulus(sasnav_cfloat z)
{
    double r = crealf(z), i = cimagf(z);
    return (float)sqrt(r * r + i * i);
}

/* q's sensors at the hypothesised motion error: T_q(sigma) = q's EPCA
 * geometry (or its channels, pr->per_channel) placed at sigma = nominal +
 * error; poses[0] or poses[0 .. n_rx - 1]. */
static void q_poses(const sasnav_pair *pr, sasnav_pose error, sasnav_ping_pose *poses)
{
    sasnav_pose sigma = {pr->nominal.x + error.x, pr->nominal.y + error.y,
                         pr->nominal.theta + error.theta};
    if (pr->per_channel)
        for (int l = 0; l < pr->array.n_rx; l++) poses[l] = sasnav_ping_place(sigma, &pr->chan_q[l]);
    else
        poses[0] = sasnav_ping_place(sigma, &pr->local_q);
}

static int same_pose(sasnav_pose a, sasnav_pose b)
{
    return a.x == b.x && a.y == b.y && a.theta == b.theta;
}

/* Places q's (CPU) operator at the hypothesised motion error (skipped when
 * it is already there). */
static int place_q(sasnav_pair *pr, int level, sasnav_pose error)
{
    pair_level *own = ops_owner(pr, level);
    if (own->q_placed && same_pose(own->q_sigma, error)) return SASNAV_OK;
    own->q_placed = 0;
    sasnav_ping_pose poses[SASNAV_MAX_RX];
    q_poses(pr, error, poses);
    int rc = pr->per_channel ? sasnav_op_set_channels(own->op_q, poses)
                             : sasnav_op_set_geometry(own->op_q, &poses[0]);
    if (rc) return rc;
    own->q_sigma = error;
    own->q_placed = 1;
    return SASNAV_OK;
}

/* out = Q x = T^+ (T x) with the operator's current geometry, using the
 * given buffers (data_tmp: nd, cgls_work: 2 np + 2 nd). Applications are
 * counted by the caller. */
static int project(const sasnav_pair *pr, const pair_level *lv, sasnav_op *op,
                   const sasnav_cfloat *x, sasnav_cfloat *out, sasnav_cfloat *data_tmp,
                   sasnav_cfloat *cgls_work)
{
    int rc = sasnav_op_forward(op, x, data_tmp);
    if (rc) return rc;
    sasnav_cgls_opts co = {lv->k, pr->opts.tikhonov};
    return sasnav_cgls(op, data_tmp, &co, out, cgls_work);
}

/* psi_p <- (Q_p Q_q)^i psi_p and psi_q <- (Q_q Q_p)^i psi_q by alternating
 * projections, for two or three threads. The two chains are independent
 * and, step by step, use different operators (psi_p's applies Q_q while
 * psi_q's applies Q_p, then the other way round), so they run side by side
 * in lockstep, one thread each, each operator used by one thread at a time
 * (its applications then run on that thread alone, nested parallelism
 * being off). The threads meet once per projection step: on a busy machine
 * this holds up far better than sharing every application between them
 * (project_chains with a team), which is 1.10x faster on an idle two-core
 * machine but 1.4-2x slower with another such estimate running
 * (docs/estimator.md, "One evaluation on a team of threads"). Each chain
 * computes exactly what it computes alone, so the bits do not depend on
 * the thread count. */
static int intersect_both(sasnav_pair *pr, pair_level *lv, sasnav_op *op_p, sasnav_op *op_q)
{
    int steps = 2 * lv->i;
    int rc[2] = {SASNAV_OK, SASNAV_OK};
    char msg[2][512] = {"", ""};
#pragma omp parallel num_threads(2)
    {
        int nt = omp_get_num_threads(), t = omp_get_thread_num();
        for (int s = 0; s < steps; s++) {
            for (int c = t; c < 2; c += nt) {
                if (rc[c]) continue;
                /* chain 0: psi_p, first Q_q; chain 1: psi_q, first Q_p */
                sasnav_op *op = (s % 2 == 0) == (c == 0) ? op_q : op_p;
                sasnav_cfloat *x = c == 0 ? lv->psi_p : lv->psi_q;
                sasnav_cfloat *tmp = c == 0 ? lv->tmp : lv->tmp2;
                const sasnav_cfloat *in = s % 2 == 0 ? x : tmp;
                sasnav_cfloat *out = s % 2 == 0 ? tmp : x;
                rc[c] = project(pr, lv, op, in, out, c == 0 ? lv->data_tmp : lv->data_tmp2,
                                c == 0 ? lv->cgls_work : lv->cgls_work2);
                if (rc[c]) snprintf(msg[c], sizeof msg[c], "%s", sasnav_last_error());
            }
#pragma omp barrier
        }
    }
    pr->applications += 2L * steps * (1 + cgls_cost(lv->k)); /* T x, then T^+ */
    for (int c = 0; c < 2; c++)
        if (rc[c]) return sasnav_set_error(rc[c], "%s", msg[c]);
    return SASNAV_OK;
}

/* rho_q = T_q^+ d_q, psi_p = (Q_p Q_q)^i rho_p and psi_q = (Q_q Q_p)^i rho_q
 * (Q x = T^+ T x, T^+ by k CGLS iterations) for the operators' current
 * geometries. The two chains apply the two projectors alternately, psi_p's
 * starting with Q_q and psi_q's with Q_p; with psi_q's chain one step
 * behind, both use the same operator at every step, so each step applies
 * it to the two chains' images at once (op_team.h: the pair data are read
 * once for both; docs/estimator.md, "Both chains through one operator"):
 *
 *   step s = 0 .. 2i, operator Q_q at even s, Q_p at odd s;
 *   psi_p's chain at its step s (s < 2i), psi_q's at its step s - 1 (s >= 1);
 *   at step 0 the CGLS of rho_q (on T_q) runs beside psi_p's first one.
 *
 * A chain's step j reads rho (j = 0), psi (even j) or tmp (odd j) and
 * writes tmp (even j) or psi (odd j). Every result is the bits of the
 * chains computed one after the other with sasnav_op_forward and
 * sasnav_cgls (op_team.h), whatever the team. The team (chosen by
 * sasnav_pair_eval): one thread (one thread in all, or inside another
 * parallel region: navigate's one pair
 * per thread, pair_batch's one hypothesis per worker), or the operators'
 * threads when they are four (PAIR_OP_THREADS_MAX), sharing each
 * application: 1.3-1.5x faster than the chains one after the other with
 * the operators' own parallel loops, the path before, on a 16-core host
 * (docs/estimator.md, "One evaluation on a team of threads"). Two or three
 * threads run intersect_both instead. */
static int project_chains(sasnav_pair *pr, pair_level *lv, int team)
{
    sasnav_op *op_p = lv->op_p, *op_q = lv->op_q;
    int rc = op_team_prepare(op_p);
    if (!rc) rc = op_team_prepare(op_q);
    if (rc) return rc;
    int steps = 2 * lv->i, k = lv->k;
    double lam = pr->opts.tikhonov;
    cgls_team_state st[2];
    sasnav_cfloat *rho[2] = {lv->rho_p, lv->rho_q}, *psi[2] = {lv->psi_p, lv->psi_q};
    sasnav_cfloat *tmp[2] = {lv->tmp, lv->tmp2}, *dt[2] = {lv->data_tmp, lv->data_tmp2};
    sasnav_cfloat *work[2] = {lv->cgls_work, lv->cgls_work2};
    /* A region of its own: the team functions see this team whatever
     * region the caller runs in (a region of one inside another). */
#pragma omp parallel num_threads(team)
    {
        /* step 0: T_q rho_p, then T_q^+ of it beside rho_q = T_q^+ d_q */
        const sasnav_cfloat *in[2] = {lv->rho_p, NULL};
        sasnav_cfloat *out[2] = {lv->data_tmp, NULL};
        op_forward_team(op_q, 1, in, out);
        const sasnav_cfloat *cg_in[2] = {lv->data_tmp, pr->data_q};
        sasnav_cfloat *cg_out[2] = {lv->tmp, lv->rho_q};
        cgls_team(op_q, 2, cg_in, k, lam, cg_out, work, st);
        for (int s = 1; s <= steps; s++) {
            sasnav_op *op = s % 2 == 0 ? op_q : op_p;
            int m = 0;
            sasnav_cfloat *wk[2];
            for (int c = 0; c < 2; c++) {
                int j = c == 0 ? s : s - 1; /* the chain's own step */
                if (j >= steps) continue;
                in[m] = j == 0 ? rho[c] : j % 2 == 0 ? psi[c] : tmp[c];
                cg_out[m] = j % 2 == 0 ? tmp[c] : psi[c];
                out[m] = dt[c];
                cg_in[m] = dt[c];
                wk[m] = work[c];
                m++;
            }
            op_forward_team(op, m, in, out);
            cgls_team(op, m, cg_in, k, lam, cg_out, wk, st);
        }
    }
    /* the nominal counts of the chains computed one by one */
    pr->applications += cgls_cost(k) + 2L * steps * (1 + cgls_cost(k));
    return SASNAV_OK;
}

#ifdef SASNAV_HAVE_CUDA
/* rho_q, psi_p and psi_q of the evaluation on the GPU (src/gpu/): the same
 * steps as the CPU path. p's operator is copied to the device (once per
 * geometry); q's pairs are computed there at each new hypothesis, or, with
 * gpu_use_device_geometry(0), placed on the CPU and copied. The context
 * belongs to the level that owns the operators. Applications are counted
 * as on the CPU. */
static int gpu_project(sasnav_pair *pr, int level, pair_level *lv, sasnav_pose error)
{
    pair_level *own = ops_owner(pr, level);
    op_view vp, vq;
    int device_geometry = gpu_device_geometry();
    int rc = op_view_get(own->op_p, &vp);
    if (!rc && own->gpu && !gpu_fits(own->gpu, &vp)) {
        gpu_destroy(own->gpu);
        own->gpu = NULL;
    }
    if (!rc && !own->gpu) {
        rc = gpu_create(&vp, &own->gpu);
        own->gpu_q_placed = own->gpu_points = 0;
    }
    if (!rc && device_geometry && !own->gpu_points) {
        op_geometry_consts c;
        rc = op_geometry_consts_get(own->op_q, &c);
        if (!rc) rc = gpu_set_points(own->gpu, &c);
        own->gpu_points = !rc;
        own->gpu_q_placed = 0;
    }
    if (!rc) rc = gpu_set_op(own->gpu, 0, &vp);
    if (rc) return rc;
    if (device_geometry) {
        /* q's pairs computed on the device (the CPU operator stays where it
         * was: place_q keeps its own record) */
        if (!own->gpu_q_placed || !same_pose(own->gpu_q_sigma, error)) {
            own->gpu_q_placed = 0;
            sasnav_ping_pose poses[SASNAV_MAX_RX];
            op_channel_geometry ch[SASNAV_MAX_RX];
            q_poses(pr, error, poses);
            rc = op_channel_geometry_get(own->op_q, poses, pr->per_channel, ch);
            if (!rc) rc = gpu_place(own->gpu, 1, ch);
            if (rc) return rc;
            own->gpu_q_sigma = error;
            own->gpu_q_placed = 1;
        }
    } else {
        own->gpu_q_placed = 0; /* the device's q is now the copy */
        rc = place_q(pr, level, error);
        if (!rc) rc = op_view_get(own->op_q, &vq);
        if (!rc) rc = gpu_set_op(own->gpu, 1, &vq);
    }
    if (!rc)
        rc = gpu_eval(own->gpu, (const float *)pr->data_q, (const float *)lv->rho_p, lv->k, lv->i,
                      pr->opts.tikhonov, (float *)lv->rho_q, (float *)lv->psi_p, (float *)lv->psi_q);
    if (rc) return rc;
    pr->applications += cgls_cost(lv->k) + 4L * lv->i * (1 + cgls_cost(lv->k));
    return SASNAV_OK;
}
#endif

/* Separable Gaussian blur of a real map (sigmas in metres along track and
 * in range; 0 = no blur along that axis), zero outside. */
static void blur_map(const sasnav_grid *g, double sigma_x, double sigma_y, double *f, double *tmp)
{
    int nx = g->nx, ny = g->ny;
    double sx = sigma_x > 0 ? sigma_x / g->dx : 1e-6, sy = sigma_y > 0 ? sigma_y / g->dy : 1e-6;
    int hx = (int)ceil(3 * sx), hy = (int)ceil(3 * sy);
    double kx[256], ky[256];
    if (hx > 127) hx = 127;
    if (hy > 127) hy = 127;
    double s = 0;
    for (int j = -hx; j <= hx; j++) s += (kx[j + hx] = exp(-0.5 * j * j / (sx * sx)));
    for (int j = -hx; j <= hx; j++) kx[j + hx] /= s;
    s = 0;
    for (int j = -hy; j <= hy; j++) s += (ky[j + hy] = exp(-0.5 * j * j / (sy * sy)));
    for (int j = -hy; j <= hy; j++) ky[j + hy] /= s;
    for (int iy = 0; iy < ny; iy++)
        for (int ix = 0; ix < nx; ix++) {
            double a = 0;
            for (int j = -hx; j <= hx; j++) {
                int jx = ix + j;
                if (jx >= 0 && jx < nx) a += kx[j + hx] * f[iy * nx + jx];
            }
            tmp[iy * nx + ix] = a;
        }
    for (int iy = 0; iy < ny; iy++)
        for (int ix = 0; ix < nx; ix++) {
            double a = 0;
            for (int j = -hy; j <= hy; j++) {
                int jy = iy + j;
                if (jy >= 0 && jy < ny) a += ky[j + hy] * tmp[jy * nx + ix];
            }
            f[iy * nx + ix] = a;
        }
}

int sasnav_pair_eval(sasnav_pair *pr, sasnav_pose error, int level, int blurred, double *zeta,
                     double *eta, double *overlap)
{
    if (!pr || level < 0 || level >= PAIR_LEVELS) return sasnav_set_error(SASNAV_ERR_ARG, "bad evaluation arguments");
    if (!pr->ready) return sasnav_set_error(SASNAV_ERR_ARG, "estimator has no data (call set_data)");
    if (!isfinite(error.x) || !isfinite(error.y) || !isfinite(error.theta))
        return sasnav_set_error(SASNAV_ERR_ARG, "hypothesis is not finite");
    pair_level *lv = &pr->level[level];
    size_t np = lv->np;
    for (int j = 0; j < lv->n_kept; j++) {
        if (lv->kept[j].error.x == error.x && lv->kept[j].error.y == error.y &&
            lv->kept[j].error.theta == error.theta && (lv->kept[j].blurred == blurred || !zeta)) {
            /* A hypothesis met again (optimisers re-evaluate their best
             * point): the same values, without the work. */
            if (zeta) *zeta = lv->kept[j].zeta;
            if (eta) *eta = lv->kept[j].eta;
            if (overlap) *overlap = lv->kept[j].overlap;
            return SASNAV_OK;
        }
    }
    lv->last_valid = 0;
    int rc;
#ifdef SASNAV_HAVE_CUDA
    if (pr->opts.gpu) {
        rc = gpu_project(pr, level, lv, error);
        if (rc) return rc;
    } else
#endif
    {
        rc = place_q(pr, level, error);
        if (rc) return rc;
        int th = op_threads(lv->op_q) < op_threads(lv->op_p) ? op_threads(lv->op_q) : op_threads(lv->op_p);
        if (omp_in_parallel()) th = 1;
        if (th == 1 || th >= 4) {
            /* both chains through each operator at once: on one thread (or
             * a thread of the caller's team, as beside a twin), or shared
             * by a team of four */
            rc = project_chains(pr, lv, th);
            if (rc) return rc;
        } else {
            /* two or three: the chains side by side (intersect_both) */
            sasnav_cgls_opts co = {lv->k, pr->opts.tikhonov};
            rc = sasnav_cgls(lv->op_q, pr->data_q, &co, lv->rho_q, lv->cgls_work);
            pr->applications += cgls_cost(lv->k);
            if (rc) return rc;
            /* psi_p = (Q_p Q_q)^i rho_p and psi_q = (Q_q Q_p)^i rho_q */
            memcpy(lv->psi_p, lv->rho_p, sizeof(sasnav_cfloat) * np);
            memcpy(lv->psi_q, lv->rho_q, sizeof(sasnav_cfloat) * np);
            rc = intersect_both(pr, lv, lv->op_p, lv->op_q);
            if (rc) return rc;
        }
    }
    pr->evaluations++;
    /* Error window: the operators' grid is wider than the compared region
     * (echoes from outside a grid fold onto its edges, differently for p and
     * q); psi is weighted by the window before any norm. */
    for (size_t j = 0; j < np; j++) {
        lv->psi_p[j] *= lv->window[j];
        lv->psi_q[j] *= lv->window[j];
    }
    double np_ = nrm2(lv->psi_p, np), nq_ = nrm2(lv->psi_q, np);
    double ov = np_ / lv->rho_p_norm;
    /* The search's equalising weights (opts.equalise) after the overlap,
     * which stays the unweighted share of p's image. */
    if (lv->eqw && pr->equalised && !pr->eq_suspended) {
        for (size_t j = 0; j < np; j++) {
            lv->psi_p[j] *= (float)lv->eqw[j];
            lv->psi_q[j] *= (float)lv->eqw[j];
        }
        np_ = nrm2(lv->psi_p, np);
        nq_ = nrm2(lv->psi_q, np);
    }
    double nrm = 1.0;
    switch (pr->opts.norm) {
    case SASNAV_NORM_P: nrm = np_; break;
    case SASNAV_NORM_Q: nrm = nq_; break;
    case SASNAV_NORM_NONE: nrm = 1.0; break;
    default: nrm = np_ > nq_ ? np_ : nq_; break;
    }
    if (!(nrm > 0)) nrm = 1.0;
    /* Both error functions are computed (their cost is nothing next to the
     * projections) and kept for a repeated hypothesis. */
    double s = 0;
    for (size_t j = 0; j < np; j++) {
        sasnav_cfloat d = lv->psi_p[j] - lv->psi_q[j];
        s += (double)crealf(d) * crealf(d) + (double)cimagf(d) * cimagf(d);
    }
    double eta_v = sqrt(s) / nrm;
    for (size_t j = 0; j < np; j++) {
        lv->mod_p[j] = modulus(lv->psi_p[j]);
        lv->mod_q[j] = modulus(lv->psi_q[j]);
    }
    double bn = nrm;
    if (blurred && pr->opts.blur > 0) {
        blur_map(&lv->grid, pr->opts.blur_cross, pr->opts.blur, lv->mod_p, lv->blur_tmp);
        blur_map(&lv->grid, pr->opts.blur_cross, pr->opts.blur, lv->mod_q, lv->blur_tmp);
        double a = 0, b = 0;
        for (size_t j = 0; j < np; j++) {
            a += lv->mod_p[j] * lv->mod_p[j];
            b += lv->mod_q[j] * lv->mod_q[j];
        }
        a = sqrt(a);
        b = sqrt(b);
        bn = pr->opts.norm == SASNAV_NORM_P ? a : pr->opts.norm == SASNAV_NORM_Q ? b
             : pr->opts.norm == SASNAV_NORM_NONE ? 1.0 : (a > b ? a : b);
        if (!(bn > 0)) bn = 1.0;
    }
    s = 0;
    for (size_t j = 0; j < np; j++) {
        double d = lv->mod_p[j] - lv->mod_q[j];
        s += d * d;
    }
    double zeta_v = sqrt(s) / bn;
    lv->last_error = error;
    lv->last_nrm = nrm;
    lv->last_valid = 1;
    int kj = lv->next_kept;
    lv->kept[kj].error = error;
    lv->kept[kj].blurred = blurred;
    lv->kept[kj].zeta = zeta_v;
    lv->kept[kj].eta = eta_v;
    lv->kept[kj].overlap = ov;
    lv->next_kept = (kj + 1) % PAIR_KEPT;
    if (lv->n_kept < PAIR_KEPT) lv->n_kept++;
    if (zeta) *zeta = zeta_v;
    if (eta) *eta = eta_v;
    if (overlap) *overlap = ov;
    return SASNAV_OK;
}

const sasnav_grid *sasnav_pair_grid(const sasnav_pair *pr) { return &pr->level[PAIR_LEVELS - 1].grid; }
const sasnav_pair_opts *sasnav_pair_options(const sasnav_pair *pr) { return &pr->opts; }
long sasnav_pair_applications(const sasnav_pair *pr) { return pr->applications; }

/* Loads |v| minus its mean into the zero-padded correlation buffer. */
static double load_modulus(const pair_level *lv, const sasnav_cfloat *v, fftwf_complex *buf)
{
    int nx = lv->grid.nx, ny = lv->grid.ny;
    double mean = 0, energy = 0;
    for (size_t j = 0; j < lv->np; j++) mean += modulus(v[j]);
    mean /= (double)lv->np;
    memset(buf, 0, sizeof(fftwf_complex) * (size_t)lv->xc_nx * lv->xc_ny);
    for (int iy = 0; iy < ny; iy++)
        for (int ix = 0; ix < nx; ix++) {
            double m = modulus(v[(size_t)iy * nx + ix]) - mean;
            buf[(size_t)iy * lv->xc_nx + ix] = (float)m;
            energy += m * m;
        }
    return energy;
}

/* Parabolic sub-sample offset of a peak from three samples. */
static double parabolic(double a, double b, double c)
{
    double d = a - 2 * b + c;
    return d < 0 ? 0.5 * (a - c) / d : 0.0;
}

int pair_image_shift(sasnav_pair *pr, int level, sasnav_pose error, double *sx, double *sy,
                     double *peak)
{
    pair_level *lv = &pr->level[level];
    int rc = place_q(pr, level, error);
    if (rc) return rc;
    /* rho_q is overwritten: the kept evaluation no longer matches it (only
     * the values are kept, but stay safe). */
    lv->last_valid = 0;
    sasnav_cgls_opts co = {lv->k, pr->opts.tikhonov};
    rc = sasnav_cgls(lv->op_q, pr->data_q, &co, lv->rho_q, lv->cgls_work);
    pr->applications += cgls_cost(lv->k);
    if (rc) return rc;
    double ep = load_modulus(lv, lv->rho_p, lv->xc_p);
    double eq = load_modulus(lv, lv->rho_q, lv->xc_q);
    fftwf_execute(lv->xc_fwd_p);
    fftwf_execute(lv->xc_fwd_q);
    size_t n = (size_t)lv->xc_nx * lv->xc_ny;
    /* High-pass both moduli (a Gaussian of PAIR_SHIFT_HIGHPASS metres
     * removed): the slowly varying beam-pattern envelopes the two images
     * share otherwise make a correlation peak near zero shift whatever the
     * content's shift (docs/estimator.md, "Global stage"). */
    const double hp = PAIR_SHIFT_HIGHPASS;
    {
        ep = eq = 0;
        for (int iy = 0; iy < lv->xc_ny; iy++) {
            int fy = iy <= lv->xc_ny / 2 ? iy : iy - lv->xc_ny;
            double ky = 2.0 * M_PI * fy / (lv->xc_ny * lv->grid.dy);
            for (int ix = 0; ix < lv->xc_nx; ix++) {
                int fx = ix <= lv->xc_nx / 2 ? ix : ix - lv->xc_nx;
                double kx = 2.0 * M_PI * fx / (lv->xc_nx * lv->grid.dx);
                float w = (float)(1.0 - exp(-0.5 * (kx * kx + ky * ky) * hp * hp));
                size_t j = (size_t)iy * lv->xc_nx + ix;
                lv->xc_p[j] *= w;
                lv->xc_q[j] *= w;
                ep += crealf(lv->xc_p[j] * conjf(lv->xc_p[j]));
                eq += crealf(lv->xc_q[j] * conjf(lv->xc_q[j]));
            }
        }
        ep /= (double)n;
        eq /= (double)n;
    }
    for (size_t j = 0; j < n; j++) lv->xc_q[j] *= conjf(lv->xc_p[j]);
    fftwf_execute(lv->xc_inv);
    /* c[s] = sum_z |p|(z) |q|(z + s): its peak is the shift of q's content. */
    int W = lv->xc_nx, H = lv->xc_ny, bx = 0, by = 0;
    float best = -HUGE_VALF;
    for (int iy = 0; iy < H; iy++)
        for (int ix = 0; ix < W; ix++) {
            float v = crealf(lv->xc_q[(size_t)iy * W + ix]);
            if (v > best) {
                best = v;
                bx = ix;
                by = iy;
            }
        }
#define XC(ix, iy) crealf(lv->xc_q[(size_t)(((iy) + H) % H) * W + (((ix) + W) % W)])
    double fx = bx + parabolic(XC(bx - 1, by), XC(bx, by), XC(bx + 1, by));
    double fy = by + parabolic(XC(bx, by - 1), XC(bx, by), XC(bx, by + 1));
#undef XC
    if (fx > W / 2) fx -= W;
    if (fy > H / 2) fy -= H;
    *sx = fx * lv->grid.dx;
    *sy = fy * lv->grid.dy;
    /* Unnormalised FFTs: the correlation is n times the sum. */
    if (peak) *peak = ep > 0 && eq > 0 ? best / ((double)n * sqrt(ep * eq)) : 0.0;
    return SASNAV_OK;
}

size_t pair_level_points(const sasnav_pair *pr, int level) { return pr->level[level].np; }

void pair_equalise_suspend(sasnav_pair *pr, int on)
{
    if (!pr->equalised || pr->eq_suspended == on) return;
    pr->eq_suspended = on;
    for (int v = 0; v < PAIR_LEVELS; v++) {
        pr->level[v].n_kept = pr->level[v].next_kept = 0;
        pr->level[v].last_valid = 0;
    }
}

/* A twin of pr (one thread, the same data and geometry), or NULL. */
static sasnav_pair *make_twin(sasnav_pair *pr)
{
    sasnav_pair_opts o = pr->opts;
    o.nthreads = 1;
    sasnav_pair *tw = NULL;
    int rc = sasnav_pair_create(&pr->sys, &pr->array, &pr->win, &o, &tw);
    if (!rc) tw->twin_of = pr; /* p's reconstructions copied (level_rho_p) */
    if (!rc && pr->per_channel) {
        rc = sasnav_pair_set_data_channels(tw, pr->data_p, pr->data_q, pr->nominal, pr->chan_p,
                                           pr->chan_q);
    } else if (!rc) {
        rc = take_data(tw, pr->data_p, pr->data_q, pr->nominal);
        if (!rc) {
            tw->local_p = pr->local_p;
            tw->local_q = pr->local_q;
            rc = make_levels(tw);
        }
    }
    if (tw) tw->twin_of = NULL;
    if (!rc) tw->pc_spacing = pr->pc_spacing;
    if (rc) {
        sasnav_pair_destroy(tw);
        return NULL;
    }
    tw->applications = 0;
    tw->evaluations = 0;
    return tw;
}

int pair_workers(sasnav_pair *pr, int want, sasnav_pair **w)
{
    w[0] = pr;
    /* Not on the GPU path: each twin there needs device contexts of its
     * own (cuFFT plans, buffers, captured graphs), and for one pair they
     * cost more than the concurrent evaluations save (measured on an H200:
     * the paper pair 1.1x slower with two workers, 2.8x with ten;
     * docs/estimator.md, "Batches on as many workers as threads"). */
    if (!pr || !pr->ready || pr->opts.gpu || omp_in_parallel()) return 1;
    int threads = pr->opts.nthreads > 0 ? pr->opts.nthreads : omp_get_max_threads();
    int n = want < threads ? want : threads;
    if (n > PAIR_MAX_WORKERS) n = PAIR_MAX_WORKERS;
    int need = pr->twin_failed ? 0 : n - 1 - pr->n_twins;
    if (need > 0) {
        /* made side by side (each ~25 ms on the paper pair: its operators
         * and p's reconstructions; FFTW's planner is serialised in op.c) */
        sasnav_pair *made[PAIR_MAX_WORKERS];
#pragma omp parallel for schedule(static, 1) num_threads(need)
        for (int t = 0; t < need; t++) made[t] = make_twin(pr);
        for (int t = 0; t < need; t++) {
            if (made[t]) pr->twin[pr->n_twins++] = made[t];
            else pr->twin_failed = 1; /* the workers made do the work */
        }
    }
    if (n > 1 + pr->n_twins) n = 1 + pr->n_twins;
    if (n < 1) n = 1;
    /* the workers evaluate pr's criterion: its equalising weights on or
     * suspended as pr's are (pair_equalise_suspend) */
    for (int t = 1; t < n; t++) {
        w[t] = pr->twin[t - 1];
        pair_equalise_suspend(w[t], pr->eq_suspended);
    }
    return n;
}

void pair_forget(sasnav_pair *pr, int level)
{
    if (!pr || level < 0 || level >= PAIR_LEVELS) return;
    pr->level[level].n_kept = pr->level[level].next_kept = 0;
    pr->level[level].last_valid = 0;
}

void pair_twin_merge(sasnav_pair *pr)
{
    if (!pr) return;
    for (int t = 0; t < pr->n_twins; t++) {
        sasnav_pair *tw = pr->twin[t];
        pr->applications += tw->applications;
        pr->evaluations += tw->evaluations;
        tw->applications = 0;
        tw->evaluations = 0;
    }
}

int pair_batch(sasnav_pair *pr, int n, int (*fn)(sasnav_pair *w, int j, void *ctx), void *ctx)
{
    if (n <= 0) return SASNAV_OK;
    sasnav_pair *w[PAIR_MAX_WORKERS];
    int nw = pair_workers(pr, n, w);
    if (nw == 1) {
        for (int j = 0; j < n; j++) {
            int rc = fn(pr, j, ctx);
            if (rc) return rc;
        }
        return SASNAV_OK;
    }
    /* each worker's first failing item, its code and message */
    int fail_j[PAIR_MAX_WORKERS], fail_rc[PAIR_MAX_WORKERS];
    char msg[PAIR_MAX_WORKERS][512];
    /* one iteration per worker: a worker is never used by two threads */
#pragma omp parallel for schedule(static, 1) num_threads(nw)
    for (int t = 0; t < nw; t++) {
        fail_j[t] = -1;
        fail_rc[t] = SASNAV_OK;
        msg[t][0] = 0;
        for (int j = t; j < n; j += nw) {
            int rc = fn(w[t], j, ctx);
            if (rc) {
                fail_j[t] = j;
                fail_rc[t] = rc;
                snprintf(msg[t], sizeof msg[t], "%s", sasnav_last_error());
                break;
            }
        }
    }
    pair_twin_merge(pr);
    int worst = -1;
    for (int t = 0; t < nw; t++)
        if (fail_rc[t] && (worst < 0 || fail_j[t] < fail_j[worst])) worst = t;
    if (worst >= 0) return sasnav_set_error(fail_rc[worst], "%s", msg[worst]);
    return SASNAV_OK;
}

int pair_eval_residual(sasnav_pair *pr, sasnav_pose error, int level, int use_eta,
                       sasnav_cfloat *r, double *f)
{
    pair_level *lv = &pr->level[level];
    if (!(lv->last_valid && lv->last_error.x == error.x && lv->last_error.y == error.y &&
          lv->last_error.theta == error.theta))
        lv->n_kept = lv->next_kept = 0; /* kept values only: psi must be recomputed */
    double z = 0, e = 0;
    int rc = sasnav_pair_eval(pr, error, level, 0, &z, &e, NULL);
    if (rc) return rc;
    /* The evaluation (computed or kept) left this hypothesis's windowed
     * psi_p, psi_q in the level's buffers. */
    float inv = (float)(1.0 / lv->last_nrm);
    if (use_eta)
        for (size_t j = 0; j < lv->np; j++) r[j] = (lv->psi_p[j] - lv->psi_q[j]) * inv;
    else
        for (size_t j = 0; j < lv->np; j++) r[j] = (modulus(lv->psi_p[j]) - modulus(lv->psi_q[j])) * inv;
    *f = use_eta ? e : z;
    return SASNAV_OK;
}

const char *sasnav_final_criterion_name(int criterion)
{
    switch (criterion) {
    case SASNAV_FINAL_ETA: return "eta";
    case SASNAV_FINAL_JOINT: return "joint";
    case SASNAV_FINAL_AUTO: return "auto";
    case SASNAV_FINAL_NONE: return "none";
    default: return "unknown";
    }
}

/* The value in lo..hi whose name(value) is `name`, or -1. */
static int parse_name(const char *name, int lo, int hi, const char *(*names)(int))
{
    if (!name) return -1;
    for (int v = lo; v <= hi; v++)
        if (!strcmp(name, names(v))) return v;
    return -1;
}

int sasnav_final_criterion_parse(const char *name)
{
    return parse_name(name, SASNAV_FINAL_ETA, SASNAV_FINAL_AUTO, sasnav_final_criterion_name);
}

const char *sasnav_search_grid_name(int grid)
{
    switch (grid) {
    case SASNAV_SEARCH_AUTO: return "auto";
    case SASNAV_SEARCH_FINE: return "fine";
    case SASNAV_SEARCH_COARSE: return "coarse";
    default: return "unknown";
    }
}

int sasnav_search_grid_parse(const char *name)
{
    return parse_name(name, SASNAV_SEARCH_AUTO, SASNAV_SEARCH_COARSE, sasnav_search_grid_name);
}

const char *sasnav_verdict_name(int verdict)
{
    switch (verdict) {
    case SASNAV_VERDICT_OK: return "ok";
    case SASNAV_VERDICT_AMBIGUOUS: return "ambiguous";
    case SASNAV_VERDICT_FAILED: return "failed";
    case SASNAV_VERDICT_NO_OVERLAP: return "no_overlap";
    case SASNAV_VERDICT_UNCHECKED: return "unchecked";
    default: return "unknown";
    }
}

int sasnav_verdict_rank(int verdict)
{
    switch (verdict) {
    case SASNAV_VERDICT_OK: return 0;
    case SASNAV_VERDICT_UNCHECKED: return 1;
    case SASNAV_VERDICT_AMBIGUOUS: return 2;
    case SASNAV_VERDICT_FAILED: return 3;
    case SASNAV_VERDICT_NO_OVERLAP: return 4;
    default: return 5;
    }
}

int sasnav_pair_estimate_intervals(const sasnav_run *run, int p, int q,
                                   const sasnav_pair_opts *opts, int n, int motion_lag,
                                   sasnav_pair_interval *out)
{
    if (!run || !opts || !out) return sasnav_set_error(SASNAV_ERR_ARG, "intervals: NULL argument");
    if (p < 0 || q < 0 || p >= run->n_pings || q >= run->n_pings || p == q)
        return sasnav_set_error(SASNAV_ERR_ARG, "intervals: pings %d, %d of a run of %d", p, q,
                                run->n_pings);
    if (n < 1 || n > 64) return sasnav_set_error(SASNAV_ERR_ARG, "intervals: n = %d, not 1..64", n);
    int rc = sasnav_pair_opts_check(opts);
    if (rc) return rc;
    if (motion_lag && !(run->speed > 0))
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "intervals: the motion lag model needs the run's speed (it is 0)");
    sasnav_pose nominal = sasnav_ping_displacement(&run->nav[p], &run->nav[q]);
    double extent = opts->range_extent;
    /* Channels with transmitters of their own and a gyro: the transmitters'
     * yaw between transmission and reception (as navigate does). */
    double *tx_yaw = NULL;
    if (run->channel_offset && run->aiding && run->aiding->yaw_rate) {
        tx_yaw = malloc(sizeof *tx_yaw * (size_t)run->n_pings);
        if (!tx_yaw) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
        rc = sasnav_run_tx_yaw(run, opts->range, tx_yaw);
        if (rc) {
            free(tx_yaw);
            return rc;
        }
    }
    for (int s = 0; s < n; s++) {
        sasnav_pair_opts so = *opts;
        so.range_extent = extent / n;
        so.range = opts->range - 0.5 * extent + (s + 0.5) * so.range_extent;
        so.tx_lag = motion_lag ? sasnav_motion_tx_lag(run->speed, so.range, run->sys.sound_speed)
                               : run->tx_lag;
        memset(&out[s], 0, sizeof out[s]);
        out[s].range = so.range;
        out[s].tx_lag = so.tx_lag;
        sasnav_pair *pair = NULL;
        rc = sasnav_pair_create(&run->sys, &run->array, &run->win, &so, &pair);
        if (!rc)
            rc = sasnav_pair_set_data_run(pair, run, p, q, sasnav_run_ping(run, p), sasnav_run_ping(run, q),
                                          nominal, tx_yaw);
        if (!rc) rc = sasnav_pair_estimate(pair, &out[s].result);
        if (!rc && run->channel_offset && !tx_yaw && out[s].result.verdict == SASNAV_VERDICT_OK) {
            /* No gyro: the transmitters' turn from this estimate, and the
             * estimate again from it (as navigate does). */
            double *yaw = malloc(sizeof *yaw * (size_t)run->n_pings);
            sasnav_pair_result again;
            int r2 = yaw ? sasnav_run_tx_yaw_from_estimate(run, out[s].result.displacement, so.range, yaw)
                         : sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
            if (!r2)
                r2 = sasnav_pair_set_data_run(pair, run, p, q, sasnav_run_ping(run, p), sasnav_run_ping(run, q),
                                              nominal, yaw);
            if (!r2) r2 = sasnav_pair_estimate_from(pair, out[s].result.error, &again);
            free(yaw);
            if (r2 == SASNAV_ERR_NOMEM || r2 == SASNAV_ERR_FFT || r2 == SASNAV_ERR_INTERNAL ||
                r2 == SASNAV_ERR_UNSUPPORTED)
                rc = r2;
            else if (!r2 && again.verdict == SASNAV_VERDICT_OK) {
                /* judged again with the first estimate's margin (its own
                 * was infinite): on a scene compact by the new estimate's
                 * contrasts that margin may be short of the compact one,
                 * and the pair is then flagged */
                sasnav_pair_result_carry(&out[s].result, &again);
                sasnav_pair_rejudge(pair, &again);
                out[s].result = again;
                out[s].tx_yaw_from_estimate = 1;
            }
        }
        sasnav_pair_destroy(pair);
        out[s].status = rc;
        if (rc == SASNAV_ERR_NOMEM || rc == SASNAV_ERR_FFT || rc == SASNAV_ERR_INTERNAL ||
            rc == SASNAV_ERR_UNSUPPORTED) { /* not a property of the pair (no GPU, say) */
            free(tx_yaw);
            return rc;
        }
    }
    free(tx_yaw);
    return SASNAV_OK;
}

/* The joint misfit's buffers (made at its first evaluation). */
static int joint_buffers(sasnav_pair *pr, const pair_level *own)
{
    if (pr->joint_x) return SASNAV_OK;
    pr->joint_x = malloc(sizeof(sasnav_cfloat) * own->np);
    pr->joint_work = malloc(sizeof(sasnav_cfloat) * (3 * own->np + 2 * own->nd));
    if (!pr->joint_x || !pr->joint_work) {
        free(pr->joint_x);
        free(pr->joint_work);
        pr->joint_x = pr->joint_work = NULL;
        return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory for the joint misfit");
    }
    return SASNAV_OK;
}

static double data_energy(const sasnav_pair *pr, size_t nd)
{
    double a = nrm2(pr->data_p, nd), b = nrm2(pr->data_q, nd);
    return a * a + b * b;
}

size_t pair_joint_len(const sasnav_pair *pr)
{
    const pair_level *own = &pr->level[1];
    return 2 * own->nd + own->np;
}

double pair_contrast(const sasnav_pair *pr) { return pr->level[1].contrast; }

int pair_contrast_q(sasnav_pair *pr, sasnav_pose error, double *contrast)
{
    pair_level *lv = &pr->level[1];
    sasnav_pose was = lv->q_sigma;
    int placed = lv->q_placed;
    sasnav_cfloat *rho = malloc(sizeof(sasnav_cfloat) * lv->np);
    if (!rho) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory for the estimator");
    int rc = place_q(pr, 1, error);
    if (!rc) {
        sasnav_cgls_opts co = {lv->k, pr->opts.tikhonov};
        rc = sasnav_cgls(lv->op_q, pr->data_q, &co, rho, lv->cgls_work);
        pr->applications += cgls_cost(lv->k);
    }
    if (!rc) *contrast = window_contrast(lv, rho);
    free(rho);
    /* q's operator back where the estimate's last evaluation left it */
    if (!rc && placed) rc = place_q(pr, 1, was);
    return rc;
}

int pair_joint_tikhonov(sasnav_pair *pr, sasnav_pose error, double *lam)
{
    pair_level *own = ops_owner(pr, PAIR_LEVELS - 1);
    int rc = joint_buffers(pr, own);
    if (!rc) rc = place_q(pr, PAIR_LEVELS - 1, error);
    if (rc) return rc;
    sasnav_cfloat *s = pr->joint_x, *t = pr->joint_work;
    rc = sasnav_op_adjoint(own->op_p, pr->data_p, s);
    if (!rc) rc = sasnav_op_adjoint(own->op_q, pr->data_q, t);
    pr->applications += 2;
    if (rc) return rc;
    for (size_t j = 0; j < own->np; j++) s[j] += t[j];
    double a = nrm2(s, own->np), e = data_energy(pr, own->nd);
    if (!(e > 0)) return sasnav_set_error(SASNAV_ERR_ARG, "the pings hold no signal");
    *lam = pr->opts.joint_mu * a * a / e;
    return SASNAV_OK;
}

int pair_eval_joint(sasnav_pair *pr, sasnav_pose error, double lam, sasnav_cfloat *r, double *f)
{
    if (!isfinite(error.x) || !isfinite(error.y) || !isfinite(error.theta))
        return sasnav_set_error(SASNAV_ERR_ARG, "hypothesis is not finite");
    pair_level *own = ops_owner(pr, PAIR_LEVELS - 1);
    size_t np = own->np, nd = own->nd;
    int rc = joint_buffers(pr, own);
    if (!rc) rc = place_q(pr, PAIR_LEVELS - 1, error);
    if (rc) return rc;
    int two = !omp_in_parallel() && op_threads(own->op_p) >= 2 && op_threads(own->op_q) >= 2;
    rc = cgls_stack(own->op_p, own->op_q, pr->data_p, pr->data_q, pr->opts.joint_k, lam, two, pr->joint_x,
                    r, r + nd, pr->joint_work);
    pr->applications += 2 * cgls_cost(pr->opts.joint_k);
    pr->evaluations++;
    if (rc) return rc;
    /* r = (phi - T s, sqrt(lam) s) / ||phi||: its squared norm is the
     * misfit over the data's energy */
    float sl = (float)sqrt(lam);
    for (size_t j = 0; j < np; j++) r[2 * nd + j] = sl * pr->joint_x[j];
    float inv = (float)(1.0 / sqrt(data_energy(pr, nd)));
    for (size_t j = 0; j < 2 * nd + np; j++) r[j] *= inv;
    *f = nrm2(r, 2 * nd + np);
    return SASNAV_OK;
}
