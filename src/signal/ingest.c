/* Passband records -> baseband, pulse-compressed samples (ingest.h, SPEC 2).
 *
 * Why the output is exactly the operators' model. Let r[n] = c(t_n - tau),
 * t_n = t_start + n / fs, be the record of one echo, c the real chirp and C
 * its DTFT (c band-limited below fs/2). Then R(f) = C(f) exp(-j 2 pi f tau')
 * with tau' = tau - t_start, and since the echo lies inside the zero-padded
 * record the DFT of length nfft samples that DTFT exactly. With the
 * equalising filter H = w(f - f0) / (W C(f)) on the positive band,
 *     Y(f_k) = (w(f_k - f0) / W) exp(-j 2 pi f_k tau'),
 * and the (unnormalised) inverse DFT evaluated at t_n gives
 *     y(t) = sum_k (w_k / W) exp(j 2 pi f_k (t - tau)),
 * so y(t) exp(-j 2 pi f0 t) = exp(-j 2 pi f0 tau) sum_k (w_k / W)
 * exp(j 2 pi (f_k - f0)(t - tau)) = p(t - tau) exp(-j 2 pi f0 tau), the
 * band-limited pulse with p(0) = 1 (W = sum_k w_k). It contains only
 * frequencies |f_k - f0| <= B/2, so sampling it every D input samples is
 * exact when fs / D >= B. (p is periodic with period nfft / fs, a little
 * longer than the record; the operators' pulse has the period of their own
 * grid. The two agree to the level of the pulse's tails at one period: far
 * below 1e-6 with a Hann taper, ~1 / (pi B T) without.)
 * The regularisation eps replaces 1 / C by conj(C) / (|C|^2 + eps max|C|^2),
 * a relative bias of about eps max|C|^2 / |C|^2 where the chirp is weak.
 */
#include "sasnav/ingest.h"
#include "sasnav/error.h"

#include <fftw3.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

struct sasnav_ingest {
    sasnav_ingest_opts opts;
    int n_in, n_chirp, nfft, n_out;
    int k_lo, k_hi;          /* band bins: f_k = k fs / nfft, |f_k - f0| <= B/2 */
    sasnav_cfloat *filter;   /* H[k - k_lo] */
    sasnav_cfloat *demod;    /* exp(-j 2 pi f0 (t_start + m D / fs)), n_out */
    float *record;           /* nfft real samples (zero-padded record) */
    sasnav_cfloat *spectrum; /* nfft / 2 + 1 */
    sasnav_cfloat *signal;   /* nfft, the compressed analytic signal */
    fftwf_plan forward, backward;
};

/* ---------------------------------------------------------------- chirps */

static int lfm_check(const sasnav_lfm *lfm, double fs)
{
    if (!lfm) return sasnav_set_error(SASNAV_ERR_ARG, "chirp: LFM description is NULL");
    if (!isfinite(fs) || !(fs > 0))
        return sasnav_set_error(SASNAV_ERR_ARG, "chirp: sample rate must be finite and > 0, got %g", fs);
    if (!isfinite(lfm->f_start) || !isfinite(lfm->f_end) || !(lfm->f_start > 0) ||
        !(lfm->f_end > 0) || !(lfm->f_start < 0.5 * fs) || !(lfm->f_end < 0.5 * fs))
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "chirp: start and end frequencies %g, %g Hz must lie in (0, fs/2 = %g Hz)",
                                lfm->f_start, lfm->f_end, 0.5 * fs);
    if (!isfinite(lfm->duration) || !(lfm->duration > 0))
        return sasnav_set_error(SASNAV_ERR_ARG, "chirp: duration must be finite and > 0, got %g s",
                                lfm->duration);
    if (!isfinite(lfm->tukey) || lfm->tukey < 0 || lfm->tukey > 1)
        return sasnav_set_error(SASNAV_ERR_ARG, "chirp: Tukey ratio must be in [0, 1], got %g",
                                lfm->tukey);
    double n = floor(lfm->duration * fs + 1e-6);
    if (n < 2 || n > 1e8)
        return sasnav_set_error(SASNAV_ERR_ARG, "chirp: %g s at %g Hz is %.0f samples (need 2..1e8)",
                                lfm->duration, fs, n);
    return SASNAV_OK;
}

int sasnav_lfm_length(const sasnav_lfm *lfm, double sample_rate)
{
    if (lfm_check(lfm, sample_rate)) return 0;
    return (int)floor(lfm->duration * sample_rate + 1e-6);
}

/* Symmetric Tukey window over n samples, x = i / (n - 1) in [0, 1]:
 * 0.5 (1 - cos(2 pi x / a)) for x < a/2, 1 in the middle, mirrored at the end. */
static double tukey(int i, int n, double a)
{
    if (a <= 0) return 1.0;
    double x = (double)i / (double)(n - 1);
    if (x > 0.5) x = 1.0 - x;
    if (x >= 0.5 * a) return 1.0;
    return 0.5 * (1.0 - cos(2.0 * M_PI * x / a));
}

int sasnav_lfm_samples(const sasnav_lfm *lfm, double sample_rate, int n_samples, float *chirp)
{
    int rc = lfm_check(lfm, sample_rate);
    if (rc) return rc;
    if (!chirp) return sasnav_set_error(SASNAV_ERR_ARG, "chirp: output is NULL");
    int n = sasnav_lfm_length(lfm, sample_rate);
    if (n_samples != n)
        return sasnav_set_error(SASNAV_ERR_ARG, "chirp: needs %d samples, got a buffer of %d", n,
                                n_samples);
    double rate = (lfm->f_end - lfm->f_start) / lfm->duration; /* Hz / s */
    for (int i = 0; i < n; i++) {
        double t = i / sample_rate;
        double cycles = lfm->f_start * t + 0.5 * rate * t * t;
        cycles -= floor(cycles);
        chirp[i] = (float)(tukey(i, n, lfm->tukey) * cos(2.0 * M_PI * cycles));
    }
    return SASNAV_OK;
}

/* --------------------------------------------------------------- the plan */

void sasnav_ingest_default_opts(sasnav_ingest_opts *opts)
{
    if (!opts) return;
    memset(opts, 0, sizeof *opts);
    opts->decimation = 1;
    opts->compression = SASNAV_COMPRESS_MODEL;
    opts->taper = SASNAV_TAPER_NONE;
    opts->regularisation = 1e-3;
    opts->clip_run = 3;
}

/* Smallest even n' >= n whose prime factors are 2, 3, 5, 7 only. */
static int fft_size(int n)
{
    for (int m = n + (n & 1);; m += 2) {
        int r = m;
        static const int primes[4] = {2, 3, 5, 7};
        for (int i = 0; i < 4; i++)
            while (r % primes[i] == 0) r /= primes[i];
        if (r == 1) return m;
    }
}

static int opts_check(const sasnav_ingest_opts *o)
{
    double fs = o->sample_rate, f0 = o->f0, b = o->bandwidth;
    if (!isfinite(fs) || !(fs > 0))
        return sasnav_set_error(SASNAV_ERR_ARG, "ingest: sample rate must be finite and > 0, got %g Hz", fs);
    if (!isfinite(f0) || !(f0 > 0))
        return sasnav_set_error(SASNAV_ERR_ARG, "ingest: carrier f0 must be finite and > 0, got %g Hz", f0);
    if (!isfinite(b) || !(b > 0))
        return sasnav_set_error(SASNAV_ERR_ARG, "ingest: bandwidth must be finite and > 0, got %g Hz", b);
    if (!isfinite(o->t_start))
        return sasnav_set_error(SASNAV_ERR_ARG, "ingest: t_start must be finite");
    if (!(f0 - 0.5 * b > 0) || !(f0 + 0.5 * b < 0.5 * fs))
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "ingest: the band [%g, %g] Hz (f0 %g Hz +- B/2) must lie inside "
                                "(0, fs/2 = %g Hz)",
                                f0 - 0.5 * b, f0 + 0.5 * b, f0, 0.5 * fs);
    if (o->decimation < 1)
        return sasnav_set_error(SASNAV_ERR_ARG, "ingest: decimation must be >= 1, got %d", o->decimation);
    if (fs / o->decimation < b * (1.0 - 1e-12))
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "ingest: decimation by %d aliases the band: fs/D = %g Hz is below "
                                "the bandwidth B = %g Hz (the largest D is %d)",
                                o->decimation, fs / o->decimation, b, (int)floor(fs / b * (1 + 1e-12)));
    if (o->compression != SASNAV_COMPRESS_MODEL && o->compression != SASNAV_COMPRESS_MATCHED)
        return sasnav_set_error(SASNAV_ERR_ARG, "ingest: unknown compression %d", (int)o->compression);
    if (o->taper != SASNAV_TAPER_NONE && o->taper != SASNAV_TAPER_HANN &&
        o->taper != SASNAV_TAPER_HAMMING)
        return sasnav_set_error(SASNAV_ERR_ARG, "ingest: unknown taper %d", (int)o->taper);
    if (!isfinite(o->regularisation) || !(o->regularisation > 0) || o->regularisation > 1)
        return sasnav_set_error(SASNAV_ERR_ARG, "ingest: regularisation must be in (0, 1], got %g",
                                o->regularisation);
    if (o->clip_run < 0 || o->clip_run == 1)
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "ingest: clip_run must be 0 (no check) or >= 2, got %d", o->clip_run);
    return SASNAV_OK;
}

void sasnav_ingest_destroy(sasnav_ingest *plan)
{
    if (!plan) return;
#pragma omp critical(sasnav_fftw_planner)
    {
        if (plan->forward) fftwf_destroy_plan(plan->forward);
        if (plan->backward) fftwf_destroy_plan(plan->backward);
    }
    fftwf_free(plan->record);
    fftwf_free(plan->spectrum);
    fftwf_free(plan->signal);
    free(plan->filter);
    free(plan->demod);
    free(plan);
}

/* The compression filter on the band bins (see the top of the file). */
static int make_filter(sasnav_ingest *p, const float *chirp)
{
    const sasnav_ingest_opts *o = &p->opts;
    double df = o->sample_rate / p->nfft;
    sasnav_system band = {0};
    band.bandwidth = o->bandwidth;
    band.taper = o->taper;
    /* Band bins: DC and Nyquist excluded (the band is inside (0, fs/2)). */
    int k_lo = (int)ceil((o->f0 - 0.5 * o->bandwidth) / df - 1e-9);
    int k_hi = (int)floor((o->f0 + 0.5 * o->bandwidth) / df + 1e-9);
    if (k_lo < 1) k_lo = 1;
    if (k_hi > p->nfft / 2 - 1) k_hi = p->nfft / 2 - 1;
    if (k_hi < k_lo)
        return sasnav_set_error(SASNAV_ERR_ARG, "ingest: the band holds no frequency of the %d-point FFT",
                                p->nfft);
    p->k_lo = k_lo;
    p->k_hi = k_hi;
    int nb = k_hi - k_lo + 1;
    p->filter = malloc(sizeof *p->filter * (size_t)nb);
    if (!p->filter) return sasnav_set_error(SASNAV_ERR_NOMEM, "ingest: out of memory");

    memset(p->record, 0, sizeof(float) * (size_t)p->nfft);
    memcpy(p->record, chirp, sizeof(float) * (size_t)p->n_chirp);
    fftwf_execute(p->forward);
    double max_c2 = 0, total_c2 = 0, sum_w = 0, sum_wc2 = 0;
    for (int k = 0; k <= p->nfft / 2; k++) {
        double c2 = crealf(p->spectrum[k]) * crealf(p->spectrum[k]) +
                    cimagf(p->spectrum[k]) * cimagf(p->spectrum[k]);
        total_c2 += c2;
        if (k < k_lo || k > k_hi) continue;
        double w = sasnav_pulse_weight(&band, k * df - o->f0);
        if (c2 > max_c2) max_c2 = c2;
        sum_w += w;
        sum_wc2 += w * c2;
    }
    if (!(sum_wc2 > 1e-10 * total_c2) || !(sum_w > 0))
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "ingest: the chirp has no energy in the band [%g, %g] Hz",
                                o->f0 - 0.5 * o->bandwidth, o->f0 + 0.5 * o->bandwidth);
    double floor_c2 = o->regularisation * max_c2;
    for (int k = k_lo; k <= k_hi; k++) {
        double w = sasnav_pulse_weight(&band, k * df - o->f0);
        double cr = crealf(p->spectrum[k]), ci = cimagf(p->spectrum[k]);
        double scale = o->compression == SASNAV_COMPRESS_MODEL
                           ? w / ((cr * cr + ci * ci + floor_c2) * sum_w)
                           : w / sum_wc2;
        p->filter[k - k_lo] = (float)(scale * cr) - I * (float)(scale * ci); /* scale conj(C) */
    }
    return SASNAV_OK;
}

static int make_demodulation(sasnav_ingest *p)
{
    const sasnav_ingest_opts *o = &p->opts;
    p->demod = malloc(sizeof *p->demod * (size_t)p->n_out);
    if (!p->demod) return sasnav_set_error(SASNAV_ERR_NOMEM, "ingest: out of memory");
    for (int m = 0; m < p->n_out; m++) {
        /* cycles of f0 since transmission, reduced in double precision */
        double t = o->t_start + (double)m * o->decimation / o->sample_rate;
        double cycles = o->f0 * t;
        cycles -= floor(cycles);
        p->demod[m] = (float)cos(2.0 * M_PI * cycles) - I * (float)sin(2.0 * M_PI * cycles);
    }
    return SASNAV_OK;
}

int sasnav_ingest_create(const sasnav_ingest_opts *opts, int n_in, const float *chirp,
                         int n_chirp, sasnav_ingest **plan)
{
    if (!plan) return sasnav_set_error(SASNAV_ERR_ARG, "ingest: plan output pointer is NULL");
    *plan = NULL;
    if (!opts || !chirp) return sasnav_set_error(SASNAV_ERR_ARG, "ingest: NULL options or chirp");
    int rc = opts_check(opts);
    if (rc) return rc;
    if (n_in < 1 || n_in > (1 << 26))
        return sasnav_set_error(SASNAV_ERR_ARG, "ingest: records need 1..2^26 samples, got %d", n_in);
    if (n_chirp < 1)
        return sasnav_set_error(SASNAV_ERR_ARG, "ingest: the chirp is empty (%d samples)", n_chirp);
    if (n_chirp > n_in)
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "ingest: the chirp (%d samples, %g s) is longer than the record "
                                "(%d samples, %g s)",
                                n_chirp, n_chirp / opts->sample_rate, n_in, n_in / opts->sample_rate);
    for (int i = 0; i < n_chirp; i++)
        if (!isfinite(chirp[i]))
            return sasnav_set_error(SASNAV_ERR_ARG, "ingest: chirp sample %d is not finite", i);

    sasnav_ingest *p = calloc(1, sizeof *p);
    if (!p) return sasnav_set_error(SASNAV_ERR_NOMEM, "ingest: out of memory");
    p->opts = *opts;
    p->n_in = n_in;
    p->n_chirp = n_chirp;
    p->nfft = fft_size(n_in + n_chirp);
    p->n_out = (n_in + opts->decimation - 1) / opts->decimation;
    p->record = fftwf_malloc(sizeof(float) * (size_t)p->nfft);
    p->spectrum = fftwf_malloc(sizeof(sasnav_cfloat) * (size_t)(p->nfft / 2 + 1));
    p->signal = fftwf_malloc(sizeof(sasnav_cfloat) * (size_t)p->nfft);
    int nfft = p->nfft;
    if (!p->record || !p->spectrum || !p->signal) {
        sasnav_ingest_destroy(p);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "ingest: out of memory for a %d-point FFT", nfft);
    }
#pragma omp critical(sasnav_fftw_planner)
    {
        p->forward = fftwf_plan_dft_r2c_1d(p->nfft, p->record, p->spectrum, FFTW_ESTIMATE);
        p->backward = fftwf_plan_dft_1d(p->nfft, p->signal, p->signal, FFTW_BACKWARD, FFTW_ESTIMATE);
    }
    if (!p->forward || !p->backward) {
        sasnav_ingest_destroy(p);
        return sasnav_set_error(SASNAV_ERR_FFT, "ingest: FFTW could not plan a %d-point FFT", nfft);
    }
    rc = make_filter(p, chirp);
    if (!rc) rc = make_demodulation(p);
    if (rc) {
        sasnav_ingest_destroy(p);
        return rc;
    }
    *plan = p;
    return SASNAV_OK;
}

/* ------------------------------------------------------------- execution */

/* Longest run of samples equal to v (v != 0) and where it starts. */
static int longest_run(const float *x, int n, float v, int *start)
{
    int best = 0, run = 0;
    for (int i = 0; i < n; i++) {
        run = x[i] == v ? run + 1 : 0;
        if (run > best) {
            best = run;
            *start = i - run + 1;
        }
    }
    return best;
}

static int check_channel(const sasnav_ingest *p, int c, const float *x)
{
    float lo = INFINITY, hi = -INFINITY;
    for (int i = 0; i < p->n_in; i++) {
        if (!isfinite(x[i]))
            return sasnav_set_error(SASNAV_ERR_ARG, "ingest: sample %d of channel %d is not finite", i, c);
        if (x[i] < lo) lo = x[i];
        if (x[i] > hi) hi = x[i];
    }
    int k = p->opts.clip_run;
    if (k < 2) return SASNAV_OK;
    const float extremes[2] = {hi, lo};
    for (int e = 0; e < 2; e++) {
        if (extremes[e] == 0.0f) continue;
        int start = 0, run = longest_run(x, p->n_in, extremes[e], &start);
        if (run >= k)
            return sasnav_set_error(SASNAV_ERR_ARG,
                                    "ingest: channel %d is clipped: %d consecutive samples (%d..%d) "
                                    "at its %s value %g (clip_run %d)",
                                    c, run, start, start + run - 1, e ? "minimum" : "maximum",
                                    (double)extremes[e], k);
    }
    return SASNAV_OK;
}

int sasnav_ingest_check_record(const sasnav_ingest *plan, int n_channels, const float *passband)
{
    if (!plan || !passband) return sasnav_set_error(SASNAV_ERR_ARG, "ingest: NULL plan or record");
    if (n_channels < 1)
        return sasnav_set_error(SASNAV_ERR_ARG, "ingest: need >= 1 channel, got %d", n_channels);
    for (int c = 0; c < n_channels; c++) {
        int rc = check_channel(plan, c, passband + (size_t)c * plan->n_in);
        if (rc) return rc;
    }
    return SASNAV_OK;
}

int sasnav_ingest_execute(sasnav_ingest *plan, int n_channels, const float *passband,
                          sasnav_cfloat *baseband)
{
    int rc = sasnav_ingest_check_record(plan, n_channels, passband);
    if (rc) return rc;
    if (!baseband) return sasnav_set_error(SASNAV_ERR_ARG, "ingest: output is NULL");
    sasnav_ingest *p = plan;
    int d = p->opts.decimation;
    for (int c = 0; c < n_channels; c++) {
        memcpy(p->record, passband + (size_t)c * p->n_in, sizeof(float) * (size_t)p->n_in);
        memset(p->record + p->n_in, 0, sizeof(float) * (size_t)(p->nfft - p->n_in));
        fftwf_execute(p->forward);
        memset(p->signal, 0, sizeof(sasnav_cfloat) * (size_t)p->nfft);
        for (int k = p->k_lo; k <= p->k_hi; k++) p->signal[k] = p->spectrum[k] * p->filter[k - p->k_lo];
        fftwf_execute(p->backward); /* unnormalised: see the top of the file */
        sasnav_cfloat *out = baseband + (size_t)c * p->n_out;
        for (int m = 0; m < p->n_out; m++) out[m] = p->signal[(size_t)m * d] * p->demod[m];
    }
    return SASNAV_OK;
}

/* -------------------------------------------------------------- queries */

int sasnav_ingest_window(const sasnav_ingest *plan, sasnav_window *win)
{
    if (!plan || !win) return sasnav_set_error(SASNAV_ERR_ARG, "ingest: NULL plan or window");
    win->t0 = plan->opts.t_start;
    win->n_samples = plan->n_out;
    return SASNAV_OK;
}

int sasnav_ingest_system(const sasnav_ingest *plan, sasnav_system *sys)
{
    if (!plan || !sys) return sasnav_set_error(SASNAV_ERR_ARG, "ingest: NULL plan or system");
    sys->f0 = plan->opts.f0;
    sys->bandwidth = plan->opts.bandwidth;
    sys->sample_rate = plan->opts.sample_rate / plan->opts.decimation;
    sys->taper = plan->opts.taper;
    return SASNAV_OK;
}

int sasnav_ingest_n_in(const sasnav_ingest *plan) { return plan ? plan->n_in : 0; }
int sasnav_ingest_n_out(const sasnav_ingest *plan) { return plan ? plan->n_out : 0; }
int sasnav_ingest_nfft(const sasnav_ingest *plan) { return plan ? plan->nfft : 0; }
