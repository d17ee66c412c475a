/* sasnav -- the acoustic system and the sampled observation window (SPEC 2).
 *
 * Threads: every function here is pure (no state, no OpenMP, no FFTW):
 * safe to call concurrently from any threads; a sasnav_system or
 * sasnav_window may be shared read-only. */
#ifndef SASNAV_MODEL_H
#define SASNAV_MODEL_H

#include <complex.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Complex single-precision sample (baseband data, reflectivity). Layout is
 * two floats (re, im), identical to fftwf_complex and to the HDF5 compound
 * {r, i} of the file format. */
typedef float _Complex sasnav_cfloat;

/* Spreading-loss model (SPEC 2). */
typedef enum {
    SASNAV_ATTEN_EXPLODING = 0, /* 1 / sqrt(r_t + r_r), the paper's default */
    SASNAV_ATTEN_SPHERICAL = 1, /* 1 / (r_t r_r) */
    SASNAV_ATTEN_NONE = 2
} sasnav_attenuation;

/* Spectral taper of the compressed pulse. */
typedef enum {
    SASNAV_TAPER_NONE = 0, /* flat spectrum over [-B/2, B/2]: sinc pulse */
    SASNAV_TAPER_HANN = 1,
    SASNAV_TAPER_HAMMING = 2
} sasnav_taper;

/* Acoustic system: everything that does not change from ping to ping. */
typedef struct {
    double sound_speed;  /* c, m/s */
    double f0;           /* carrier (centre) frequency, Hz */
    double bandwidth;    /* B, Hz; the compressed pulse occupies [-B/2, B/2] */
    double sample_rate;  /* complex baseband sampling rate fs, Hz (>= B) */
    sasnav_taper taper;
    sasnav_attenuation attenuation;
    int beam_pattern;    /* 1: line-aperture sinc patterns of Tx and Rx; 0: omni */
} sasnav_system;

/* The time window of a ping's samples: t_m = t0 + m / fs, m = 0..n_samples-1,
 * t measured from transmission. */
typedef struct {
    double t0;       /* s */
    int n_samples;
} sasnav_window;

/* Physically possible ranges (docs/format.md, "Plausibility"): every
 * system, array and run is checked against them (sasnav_system_check,
 * sasnav_array_check, sasnav_run_check), so every reader and every command
 * refuses the same impossible inputs. They are wide on purpose: from air
 * (AirSAS, c ~ 343 m/s, f0 ~ 20 kHz) to sea water, from tanks to surveys. */
#define SASNAV_SOUND_SPEED_MIN 200.0   /* m/s: below any gas at survey temperatures */
#define SASNAV_SOUND_SPEED_MAX 2000.0  /* m/s: above sea water (1450-1550) with margin */
#define SASNAV_F0_MIN 100.0            /* Hz */
#define SASNAV_F0_MAX 10e6             /* Hz: above any imaging sonar */
#define SASNAV_SAMPLE_RATE_MAX 1e9     /* Hz, complex baseband */
#define SASNAV_SIZE_MAX_M 100.0        /* m: receiver positions, element lengths,
                                          ping spacing, Tx-array separation */
#define SASNAV_HEIGHT_MAX_M 10e3       /* m: |sensor height| above the scene plane */
#define SASNAV_RANGE_MAX_M 100e3       /* m: range of interest, one-way range of
                                          the window's end */
#define SASNAV_SPEED_MAX 100.0         /* m/s: nominal platform speed */
#define SASNAV_POSITION_MAX_M 1e8      /* m: |x|, |y| of any pose (Earth scale) */

/* Fills `sys` with the paper-pair system: c = 1500, f0 = 300 kHz,
 * B = 30 kHz, fs = 2B, no taper, exploding sources, beam patterns on. */
void sasnav_system_default(sasnav_system *sys);

/* Validates the system (finite, positive, fs >= B, f0 > B/2). */
int sasnav_system_check(const sasnav_system *sys);

/* Window covering two-way ranges (r_t + r_r)/2 in [range_min, range_max]
 * (metres) with `margin_samples` extra samples at both ends. */
int sasnav_window_for_ranges(const sasnav_system *sys, double range_min, double range_max,
                             int margin_samples, sasnav_window *win);

/* Wavelength c / f0. */
double sasnav_wavelength(const sasnav_system *sys);

/* Direct (slow, exact) evaluation of the band-limited compressed pulse used by
 * the operators: p(t) = (1/W) sum_k w(f_k) exp(j 2 pi f_k t) over the discrete
 * frequencies f_k = k / (period) with |f_k| <= B/2, W = sum_k w(f_k), so that
 * p(0) = 1. `period` is the periodic extent of the operator's FFT grid (see
 * sasnav_op_period). Used as the reference in tests and for documentation. */
sasnav_cfloat sasnav_pulse_direct(const sasnav_system *sys, double period, double t);

/* Spectral weight w(f) of the taper at baseband frequency f (0 outside band). */
double sasnav_pulse_weight(const sasnav_system *sys, double f);

#ifdef __cplusplus
}
#endif
#endif
