/* DPCA micronavigation baseline (Bellettini & Pinto 2002): sway and yaw of
 * a ping pair from the delays between the channels whose phase centres
 * overlap. See include/sasnav/dpca.h for the model and its limits. */
#include "sasnav/dpca.h"
#include "sasnav/error.h"

#include <complex.h>
#include <fftw3.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

void sasnav_dpca_default_opts(sasnav_dpca_opts *opts)
{
    if (!opts) return;
    memset(opts, 0, sizeof *opts);
    opts->range = 0.0;
    opts->half_width = 0.5;
    opts->upsampling = 8;
    opts->max_sway = 0.04;
    opts->use_phase = 1;
    opts->unwrap = 1;
    opts->bistatic_correction = 1;
    opts->min_coherence = 0.1;
    opts->nthreads = 0;
}

/* Smallest even n >= m whose only prime factors are 2, 3, 5, 7. */
static int fft_size(int m)
{
    for (int n = m < 2 ? 2 : m;; n++) {
        if (n % 2) continue;
        int r = n;
        while (r % 2 == 0) r /= 2;
        while (r % 3 == 0) r /= 3;
        while (r % 5 == 0) r /= 5;
        while (r % 7 == 0) r /= 7;
        if (r == 1) return n;
    }
}

static int opts_check(const sasnav_dpca_opts *o)
{
    if (!isfinite(o->range) || o->range < 0)
        return sasnav_set_error(SASNAV_ERR_ARG, "DPCA: window centre must be >= 0, got %g m", o->range);
    if (!(o->half_width > 0) || !isfinite(o->half_width))
        return sasnav_set_error(SASNAV_ERR_ARG, "DPCA: window half-width must be > 0, got %g m",
                                o->half_width);
    if (o->upsampling < 1 || o->upsampling > 64)
        return sasnav_set_error(SASNAV_ERR_ARG, "DPCA: upsampling must be 1..64, got %d",
                                o->upsampling);
    if (!(o->max_sway > 0) || !isfinite(o->max_sway))
        return sasnav_set_error(SASNAV_ERR_ARG, "DPCA: max_sway must be > 0, got %g m", o->max_sway);
    if (!(o->min_coherence >= 0) || !(o->min_coherence <= 1))
        return sasnav_set_error(SASNAV_ERR_ARG, "DPCA: min_coherence must be in [0, 1], got %g",
                                o->min_coherence);
    if (o->nthreads < 0)
        return sasnav_set_error(SASNAV_ERR_ARG, "DPCA: nthreads must be >= 0, got %d", o->nthreads);
    return SASNAV_OK;
}

/* Phase-centre spacing d of a uniform array (half the receiver spacing), or
 * an error for a non-uniform one. */
static int pc_spacing(const sasnav_array *a, double *d)
{
    if (a->n_rx < 2)
        return sasnav_set_error(SASNAV_ERR_ARG, "DPCA needs at least 2 receivers, got %d", a->n_rx);
    double e = (a->rx_u[a->n_rx - 1] - a->rx_u[0]) / (a->n_rx - 1);
    if (!(e > 0))
        return sasnav_set_error(SASNAV_ERR_ARG, "DPCA needs receivers in increasing order along the array");
    for (int l = 1; l < a->n_rx; l++)
        if (fabs(a->rx_u[l] - a->rx_u[l - 1] - e) > 1e-9 * (1.0 + e))
            return sasnav_set_error(SASNAV_ERR_ARG,
                                    "DPCA needs a uniform array (receiver %d breaks the %g m spacing)",
                                    l, e);
    *d = 0.5 * e;
    return SASNAV_OK;
}

/* Two-way delay (s) from the Tx to the scene point (x, y, 0) and back to
 * receiver l, sensors of `ping` (channel l's heights). */
static double delay_to(const sasnav_run *run, const sasnav_ping_pose *ping, int l, double x,
                       double y)
{
    const sasnav_array *a = &run->array;
    double rx, ry;
    sasnav_pose_apply(ping->array, a->rx_u[l], 0.0, &rx, &ry);
    double dtx = x - ping->tx.x, dty = y - ping->tx.y;
    double drx = x - rx, dry = y - ry;
    sasnav_channel_size z = sasnav_array_channel_size(a, l);
    double rt = sqrt(dtx * dtx + dty * dty + z.tx_height * z.tx_height);
    double rr = sqrt(drx * drx + dry * dry + z.rx_height * z.rx_height);
    return (rt + rr) / run->sys.sound_speed;
}

/* Shared, read-only inputs of the per-pair delay measurement. */
typedef struct {
    const sasnav_cfloat *data_p, *data_q; /* the two pings, n_rx * n_samples */
    int n_samples;
    int m0, m;          /* window: first sample and count */
    int l;              /* FFT length (zero-padded correlation) */
    int up;             /* upsampling factor */
    double fs, f0;
    fftwf_plan fwd, bwd;/* length l forward, length up * l backward, in place */
} corr_setup;

/* Measures the delay of q's channel cq relative to p's channel cp: the lag
 * at which r(tau) = sum_t q(t) conj(p(t - tau)) peaks. max_lag and centre
 * are in samples. Buffers: bq, bp of l values, bu of up * l values. */
static void measure_delay(const corr_setup *s, int cq, int cp, double centre, double max_lag,
                          fftwf_complex *bq, fftwf_complex *bp, fftwf_complex *bu,
                          double *coarse, double *phase_delay, double *coherence)
{
    const sasnav_cfloat *xq = s->data_q + (size_t)cq * s->n_samples + s->m0;
    const sasnav_cfloat *xp = s->data_p + (size_t)cp * s->n_samples + s->m0;
    int l = s->l, lu = s->up * s->l;
    sasnav_cfloat *q = (sasnav_cfloat *)bq, *p = (sasnav_cfloat *)bp, *u = (sasnav_cfloat *)bu;
    double eq = 0, ep = 0;
    for (int t = 0; t < l; t++) {
        q[t] = t < s->m ? xq[t] : 0.0f;
        p[t] = t < s->m ? xp[t] : 0.0f;
    }
    for (int t = 0; t < s->m; t++) {
        eq += (double)crealf(q[t]) * crealf(q[t]) + (double)cimagf(q[t]) * cimagf(q[t]);
        ep += (double)crealf(p[t]) * crealf(p[t]) + (double)cimagf(p[t]) * cimagf(p[t]);
    }
    fftwf_execute_dft(s->fwd, bq, bq);
    fftwf_execute_dft(s->fwd, bp, bp);
    /* Cross spectrum Q conj(P) (kept in q), zero-padded to up * l in the
     * middle of the spectrum (band-limited interpolation of r). */
    for (int k = 0; k < l; k++) q[k] = q[k] * conjf(p[k]);
    int half = l / 2;
    if (s->up == 1) {
        memcpy(u, q, sizeof(sasnav_cfloat) * (size_t)l);
    } else {
        memset(u, 0, sizeof(sasnav_cfloat) * (size_t)lu);
        for (int k = 0; k < half; k++) u[k] = q[k];
        /* Nyquist bin split between +/- (l is even). */
        u[half] = 0.5f * q[half];
        u[lu - half] = 0.5f * q[half];
        for (int k = half + 1; k < l; k++) u[lu - l + k] = q[k];
    }
    fftwf_execute_dft(s->bwd, bu, bu);

    /* Peak of |r| over lags centre +- max_lag (samples), on the fine grid. */
    int j_lo = (int)ceil((centre - max_lag) * s->up), j_hi = (int)floor((centre + max_lag) * s->up);
    int j_lim = (l / 2 - 1) * s->up;
    if (j_lo < -j_lim) j_lo = -j_lim;
    if (j_hi > j_lim) j_hi = j_lim;
    if (j_hi < j_lo) j_hi = j_lo;
    int best = j_lo;
    double best_v = -1.0;
    for (int j = j_lo; j <= j_hi; j++) {
        double v = cabsf(u[(j + lu) % lu]);
        if (v > best_v) {
            best_v = v;
            best = j;
        }
    }
    double ym = cabsf(u[(best - 1 + lu) % lu]), y0 = best_v, yp = cabsf(u[(best + 1 + lu) % lu]);
    double den = ym - 2.0 * y0 + yp, frac = 0.0;
    if (den < 0) frac = 0.5 * (ym - yp) / den;
    if (frac > 0.5) frac = 0.5;
    if (frac < -0.5) frac = -0.5;
    double lag = (best + frac) / s->up; /* samples */
    *coarse = lag / s->fs;

    /* r at the refined lag by the exact band-limited sum (double precision):
     * r(tau) = (1/l) sum_k S_k exp(j 2 pi k tau / l), k signed. */
    double complex r = 0;
    for (int k = 0; k < l; k++) {
        int ks = k < half ? k : (k == half ? 0 : k - l);
        double w = k == half ? cos(M_PI * lag) : 1.0; /* Nyquist bin: +/- half */
        double ph = 2.0 * M_PI * ks * lag / l;
        r += w * (double complex)q[k] * cexp(I * ph);
    }
    r /= l;
    *coherence = (eq > 0 && ep > 0) ? cabs(r) / sqrt(eq * ep) : 0.0;
    /* Baseband: a delay tau shows as exp(-j 2 pi f0 tau) at the peak; the
     * phase fixes tau modulo 1 / f0 (the branch is chosen by the caller). */
    *phase_delay = -carg(r) / (2.0 * M_PI * s->f0);
}

/* The branch of the phase delay (modulo 1 / f0) nearest to `guess`. */
static double nearest_branch(double phase_delay, double guess, double f0)
{
    double period = 1.0 / f0;
    return phase_delay + nearbyint((guess - phase_delay) / period) * period;
}

/* Least-squares line y = a + b (x - mean x); returns a, b and the rms
 * residual. */
static void line_fit(int n, const double *x, const double *y, double *xbar, double *a, double *b,
                     double *rms)
{
    double sx = 0, sy = 0;
    for (int k = 0; k < n; k++) {
        sx += x[k];
        sy += y[k];
    }
    *xbar = sx / n;
    *a = sy / n;
    double sxx = 0, sxy = 0;
    for (int k = 0; k < n; k++) {
        sxx += (x[k] - *xbar) * (x[k] - *xbar);
        sxy += (x[k] - *xbar) * (y[k] - *a);
    }
    *b = sxx > 0 ? sxy / sxx : 0.0;
    double ss = 0;
    for (int k = 0; k < n; k++) {
        double e = y[k] - *a - *b * (x[k] - *xbar);
        ss += e * e;
    }
    *rms = sqrt(ss / n);
}

/* Sample range [m0, m0 + m) of the range window; error if it is too short. */
static int window_samples(const sasnav_run *run, double centre, double half_width, int *m0, int *m)
{
    double c = run->sys.sound_speed, fs = run->sys.sample_rate;
    double lo = centre - half_width, hi = centre + half_width;
    if (!(lo > 0))
        return sasnav_set_error(SASNAV_ERR_GEOMETRY,
                                "DPCA: range window [%g, %g] m reaches the sensors", lo, hi);
    int a = (int)ceil((2.0 * lo / c - run->win.t0) * fs);
    int b = (int)floor((2.0 * hi / c - run->win.t0) * fs);
    if (a < 0) a = 0;
    if (b > run->win.n_samples - 1) b = run->win.n_samples - 1;
    if (b - a + 1 < 8)
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "DPCA: range window [%g, %g] m holds %d samples of the data (need >= 8)",
                                lo, hi, b - a + 1 < 0 ? 0 : b - a + 1);
    *m0 = a;
    *m = b - a + 1;
    return SASNAV_OK;
}

/* Pairs the channels: fills the detail's channel lists, shift and K. */
static int pair_channels(const sasnav_run *run, int p, int q, double d, sasnav_dpca_detail *det)
{
    double nominal = (q - p) * run->ping_spacing;
    double ratio = nominal / d;
    double shift = nearbyint(ratio);
    if (fabs(ratio - shift) > 1e-6)
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "DPCA: nominal displacement %g m is %.6f phase-centre spacings of %g m, "
                                "not a whole number",
                                nominal, ratio, d);
    int n = run->array.n_rx;
    if (fabs(shift) > n - 2)
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "DPCA: pings %d and %d share %d phase centres (shift %.0f of %d); need >= 2",
                                p, q, fabs(shift) >= n ? 0 : n - (int)fabs(shift), shift, n);
    int sh = (int)shift, k = 0;
    for (int l = 0; l < n; l++) {
        int m = l + sh;
        if (m < 0 || m >= n) continue;
        det->channel_q[k] = l;
        det->channel_p[k] = m;
        k++;
    }
    det->shift = sh;
    det->n_pairs = k;
    return SASNAV_OK;
}

static int check_inputs(const sasnav_run *run, int p, int q, const sasnav_dpca_opts *o)
{
    if (!run) return sasnav_set_error(SASNAV_ERR_ARG, "DPCA: run is NULL");
    int rc = sasnav_run_check(run);
    if (rc) return rc;
    if (p < 0 || q < 0 || p >= run->n_pings || q >= run->n_pings || p == q)
        return sasnav_set_error(SASNAV_ERR_ARG, "DPCA: pings %d, %d must be distinct and in 0..%d", p,
                                q, run->n_pings - 1);
    if (!(run->ping_spacing > 0))
        return sasnav_set_error(SASNAV_ERR_ARG, "DPCA: the run's nominal ping spacing must be > 0");
    if (run->channel_offset)
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "DPCA: the run's channels have transmitters of their own (channel offsets); "
                                "this DPCA pairs receivers of one transmitter: use the subspace estimator");
    return opts_check(o);
}

int sasnav_dpca_estimate(const sasnav_run *run, int p, int q, const sasnav_dpca_opts *opts,
                         sasnav_pair_result *res, sasnav_dpca_detail *detail)
{
    if (!res) return sasnav_set_error(SASNAV_ERR_ARG, "DPCA: result is NULL");
    double t_start = omp_get_wtime();
    sasnav_dpca_opts o;
    if (opts) o = *opts;
    else sasnav_dpca_default_opts(&o);
    int rc = check_inputs(run, p, q, &o);
    if (rc) return rc;
    double d = 0;
    if ((rc = pc_spacing(&run->array, &d))) return rc;
    sasnav_dpca_detail *det = malloc(sizeof *det);
    if (!det) return sasnav_set_error(SASNAV_ERR_NOMEM, "DPCA: out of memory");
    memset(det, 0, sizeof *det);
    rc = pair_channels(run, p, q, d, det);
    double centre = o.range > 0 ? o.range : run->range_of_interest;
    int m0 = 0, m = 0;
    if (!rc) rc = window_samples(run, centre, o.half_width, &m0, &m);
    if (rc) {
        free(det);
        return rc;
    }
    det->window_first = m0;
    det->window_samples = m;

    /* Nominal EPCA geometry in p's centroid frame: p at the origin, q at
     * (D, 0, 0). The along-track coordinate of q's phase centre l in q's
     * frame is u_l / 2. */
    double c = run->sys.sound_speed, fs = run->sys.sample_rate;
    double disp = (q - p) * run->ping_spacing;
    sasnav_ping_pose local = sasnav_epca_local(run->tx_lag, 0.0);
    sasnav_pose cp0 = {0, 0, 0}, cq0 = {disp, 0, 0};
    sasnav_ping_pose gp = sasnav_ping_place(cp0, &local), gq = sasnav_ping_place(cq0, &local);
    double h = 0.5 * (run->array.tx_height + run->array.rx_height);
    double y_sc = centre * centre > h * h ? sqrt(centre * centre - h * h) : centre;
    int kp = det->n_pairs;
    for (int k = 0; k < kp; k++) {
        int lq = det->channel_q[k], lp = det->channel_p[k];
        det->along[k] = 0.5 * run->array.rx_u[lq];
        double x_pc = disp + det->along[k];
        det->delay_nominal[k] = o.bistatic_correction
                                    ? delay_to(run, &gq, lq, x_pc, y_sc) - delay_to(run, &gp, lp, x_pc, y_sc)
                                    : 0.0;
    }

    /* FFT set-up: correlation without wrap-around needs l >= 2 m. */
    corr_setup s = {sasnav_run_ping(run, p), sasnav_run_ping(run, q), run->win.n_samples, m0, m,
                    fft_size(2 * m), o.upsampling, fs, run->sys.f0, NULL, NULL};
    size_t lu = (size_t)s.up * s.l;
    fftwf_complex *plan_a = fftwf_malloc(sizeof(fftwf_complex) * (size_t)s.l);
    fftwf_complex *plan_b = fftwf_malloc(sizeof(fftwf_complex) * lu);
    if (!plan_a || !plan_b) {
        fftwf_free(plan_a);
        fftwf_free(plan_b);
        free(det);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "DPCA: out of memory");
    }
#pragma omp critical(sasnav_fftw_planner)
    {
        s.fwd = fftwf_plan_dft_1d(s.l, plan_a, plan_a, FFTW_FORWARD, FFTW_ESTIMATE);
        s.bwd = fftwf_plan_dft_1d((int)lu, plan_b, plan_b, FFTW_BACKWARD, FFTW_ESTIMATE);
    }
    fftwf_free(plan_a);
    fftwf_free(plan_b);
    if (!s.fwd || !s.bwd) rc = sasnav_set_error(SASNAV_ERR_FFT, "DPCA: FFTW could not make a plan");

    int nthreads = o.nthreads > 0 ? o.nthreads : omp_get_max_threads();
    if (nthreads > kp) nthreads = kp;
    int nomem = 0;
    if (!rc) {
#pragma omp parallel num_threads(nthreads) reduction(| : nomem)
        {
            fftwf_complex *bq = fftwf_malloc(sizeof(fftwf_complex) * (size_t)s.l);
            fftwf_complex *bp = fftwf_malloc(sizeof(fftwf_complex) * (size_t)s.l);
            fftwf_complex *bu = fftwf_malloc(sizeof(fftwf_complex) * lu);
            if (!bq || !bp || !bu) nomem = 1;
#pragma omp for schedule(static)
            for (int k = 0; k < kp; k++) {
                if (!bq || !bp || !bu) continue;
                double centre_lag = det->delay_nominal[k] * fs;
                double max_lag = 2.0 * o.max_sway / c * fs;
                measure_delay(&s, det->channel_q[k], det->channel_p[k], centre_lag, max_lag, bq, bp,
                              bu, &det->delay_coarse[k], &det->delay[k], &det->coherence[k]);
                /* det->delay holds the phase delay modulo 1 / f0 for now. */
            }
            fftwf_free(bq);
            fftwf_free(bp);
            fftwf_free(bu);
        }
        if (nomem) rc = sasnav_set_error(SASNAV_ERR_NOMEM, "DPCA: out of memory");
    }
#pragma omp critical(sasnav_fftw_planner)
    {
        if (s.fwd) fftwf_destroy_plan(s.fwd);
        if (s.bwd) fftwf_destroy_plan(s.bwd);
    }
    if (rc) {
        free(det);
        return rc;
    }

    /* Coarse range shifts; the fine delays take the phase branch nearest to
     * either the pair's own coarse delay or the line fitted to all coarse
     * range shifts (opts.unwrap = 1: the fit averages the envelope errors
     * of the K pairs, so a single poorly correlated pair does not slip by a
     * half wavelength). */
    double vbar, a, b, rms, mean_coh = 0;
    for (int k = 0; k < kp; k++) {
        det->range_shift[k] = -0.5 * c * (det->delay_coarse[k] - det->delay_nominal[k]);
        mean_coh += det->coherence[k];
    }
    mean_coh /= kp;
    line_fit(kp, det->along, det->range_shift, &vbar, &a, &b, &rms);
    for (int k = 0; k < kp; k++) {
        double guess = det->delay_coarse[k];
        if (o.unwrap) guess = det->delay_nominal[k] - 2.0 * (a + b * (det->along[k] - vbar)) / c;
        det->delay[k] = o.use_phase ? nearest_branch(det->delay[k], guess, run->sys.f0)
                                    : det->delay_coarse[k];
        det->range_shift[k] = -0.5 * c * (det->delay[k] - det->delay_nominal[k]);
    }
    /* Range shifts and the sway/yaw line fit. */
    line_fit(kp, det->along, det->range_shift, &vbar, &a, &b, &rms);
    if (b > 1) b = 1;
    if (b < -1) b = -1;
    det->sway_overlap = a;
    det->residual_rms = rms;
    det->mean_coherence = mean_coh;

    memset(res, 0, sizeof *res);
    sasnav_pose err = {0.0, a - b * vbar, asin(b)};
    res->error = err;
    res->displacement = (sasnav_pose){disp + err.x, err.y, err.theta};
    res->global_stage = err;
    res->zeta_stage = err;
    res->overlap = mean_coh;
    res->status = mean_coh < o.min_coherence ? SASNAV_ERR_NO_OVERLAP : SASNAV_OK;
    res->verdict = res->status == SASNAV_OK ? SASNAV_VERDICT_UNCHECKED : SASNAV_VERDICT_NO_OVERLAP;
    res->margin = INFINITY;
    res->seconds = omp_get_wtime() - t_start;
    if (detail) *detail = *det;
    free(det);
    return SASNAV_OK;
}
