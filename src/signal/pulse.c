/* The acoustic system, the sample window and the band-limited compressed
 * pulse (SPEC 2, paper eq. acmod).
 *
 * The pulse used by the operators is the ideal band-limited compressed pulse
 * of the (periodic) FFT grid: p(t) = (1/W) sum_k w(f_k) exp(j 2 pi f_k t),
 * f_k = k / period, over the frequencies of the band |f_k| <= B/2 that the
 * coarse grid represents (|f_k| < fs/2). sasnav_pulse_direct evaluates that
 * sum directly; the operators (src/operators/op.c) reproduce it with a NUFFT
 * and use the same band (signal/kernel.h: sasnav_band_kmax) and weights. */
#include "sasnav/model.h"
#include "sasnav/error.h"
#include "signal/kernel.h"

#include <math.h>

/* Two-way delay 2 r / c of ranges [range_min, range_max] plus margin samples at
 * both ends: t0 = 2 range_min / c - margin / fs, last sample at or after
 * 2 range_max / c + margin / fs. */
int sasnav_window_for_ranges(const sasnav_system *sys, double range_min, double range_max,
                             int margin_samples, sasnav_window *win)
{
    int rc = sasnav_system_check(sys);
    if (rc) return rc;
    if (!win) return sasnav_set_error(SASNAV_ERR_ARG, "window output is NULL");
    if (!isfinite(range_min) || !isfinite(range_max) || range_min < 0.0 ||
        !(range_max >= range_min))
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "window: need 0 <= range_min <= range_max, got [%g, %g] m",
                                range_min, range_max);
    if (margin_samples < 0)
        return sasnav_set_error(SASNAV_ERR_ARG, "window: margin_samples must be >= 0, got %d",
                                margin_samples);
    double fs = sys->sample_rate, c = sys->sound_speed;
    double t0 = 2.0 * range_min / c - margin_samples / fs;
    double t_end = 2.0 * range_max / c + margin_samples / fs;
    /* Samples t0 + m / fs, m = 0 .. n-1, with the last one >= t_end. The
     * 1e-9 guards against ceil(integer + rounding noise). */
    double n = ceil((t_end - t0) * fs - 1e-9) + 1.0;
    if (n > (double)(1 << 26))
        return sasnav_set_error(SASNAV_ERR_ARG, "window: %.0f samples is too many", n);
    win->t0 = t0;
    win->n_samples = (int)n;
    return SASNAV_OK;
}

double sasnav_wavelength(const sasnav_system *sys)
{
    if (!sys || !(sys->f0 > 0.0)) return NAN;
    return sys->sound_speed / sys->f0;
}

/* Taper over [-B/2, B/2]; u = f / B in [-1/2, 1/2].
 * Hann: cos^2(pi u) = 0.5 (1 + cos(2 pi u)); Hamming: 0.54 + 0.46 cos(2 pi u). */
double sasnav_pulse_weight(const sasnav_system *sys, double f)
{
    if (!sys || !(sys->bandwidth > 0.0) || !isfinite(f)) return 0.0;
    double half = 0.5 * sys->bandwidth;
    if (fabs(f) > half * (1.0 + 1e-12)) return 0.0;
    double u = f / sys->bandwidth;
    switch (sys->taper) {
    case SASNAV_TAPER_HANN: return 0.5 * (1.0 + cos(2.0 * M_PI * u));
    case SASNAV_TAPER_HAMMING: return 0.54 + 0.46 * cos(2.0 * M_PI * u);
    default: return 1.0;
    }
}

/* p(t) = (1/W) sum_{|k| <= K} w(f_k) exp(j 2 pi f_k t). The band and the
 * weights are symmetric (w(-f) = w(f)), so p is real:
 * p(t) = (w_0 + 2 sum_{k >= 1} w_k cos(2 pi k t / period)) / W. */
sasnav_cfloat sasnav_pulse_direct(const sasnav_system *sys, double period, double t)
{
    if (!sys || !(period > 0.0) || !isfinite(period) || !isfinite(t)) return NAN;
    int kmax = sasnav_band_kmax(sys, period);
    if (kmax < 0) return NAN;
    double sum = sasnav_pulse_weight(sys, 0.0), norm = sum;
    for (int k = 1; k <= kmax; k++) {
        double w = sasnav_pulse_weight(sys, k / period);
        sum += 2.0 * w * cos(2.0 * M_PI * k * (t / period));
        norm += 2.0 * w;
    }
    return (float)(sum / norm);
}
