/* sasnav -- passband recordings to the baseband, pulse-compressed samples of
 * the observation model (SPEC 2).
 *
 * A recorded echo of a point at two-way delay tau is the transmitted chirp
 * delayed by tau, c(t - tau), on its carrier. The ingest chain turns the real
 * passband samples of N channels into what the operators model:
 *
 *     phi(t) = p(t - tau) exp(-j 2 pi f0 tau),
 *
 * p the compressed pulse, band-limited to [-B/2, B/2], p(0) = 1 for an echo
 * of unit amplitude. The chain, per channel (all in the frequency domain, one
 * forward real FFT and one inverse complex FFT of nfft >= n_in + n_chirp
 * samples, so the correlation is linear, not circular):
 *
 *   1. pulse compression: Y(f) = H(f) R(f) on the positive-frequency band
 *      |f - f0| <= B/2 (the analytic signal of the compressed echo), with
 *        SASNAV_COMPRESS_MODEL   H = w(f - f0) conj(C) / (|C|^2 + eps max|C|^2) / W
 *          (equalised: the output pulse is exactly the operators' pulse,
 *          spectrum w(f)/W over the band, taper w of sasnav_pulse_weight),
 *        SASNAV_COMPRESS_MATCHED H = w(f - f0) conj(C) / sum_band w |C|^2
 *          (matched filter: spectrum ~ |C|^2, the conventional choice);
 *      C = DFT of the transmitted chirp. H is zero outside the band: it is
 *      also the low-pass filter (FFT-domain brick wall at B/2 <= fs_out/2,
 *      optionally tapered) and has zero phase, so there is no filter delay.
 *   2. back to time at the full rate (inverse FFT), demodulation by
 *      exp(-j 2 pi f0 t_n), t_n = t_start + n / fs the time since
 *      transmission of input sample n;
 *   3. decimation by D: output sample m is the value at t_start + m D / fs.
 *      The demodulated signal occupies [-B/2, B/2] exactly, so keeping every
 *      D-th sample is alias-free as long as fs / D >= B (checked).
 * The output window is therefore t0 = t_start, n_out = ceil(n_in / D)
 * samples at fs / D: a point echo lands where sasnav_op puts it.
 *
 * Lifecycle (FFTW style): sasnav_ingest_default_opts -> sasnav_ingest_create
 * (validates the options and the chirp, computes the filter, makes the FFTW
 * plans once, inside the OpenMP critical section `sasnav_fftw_planner` like
 * the operators) -> sasnav_ingest_execute (many times) ->
 * sasnav_ingest_destroy. The chirp is given as samples; sasnav_lfm_samples
 * synthesises an LFM (f_start, f_end, duration, Tukey taper).
 *
 * Accuracy (tests/test_ingest.c): a point echo on the tank system of SPEC 4
 * (90-120 kHz, 3 ms, 1 MHz, D = 33) matches sasnav_op to 3.5e-5 relative
 * error with a Hann taper, the fitted complex scale being 0.9987 (the eps
 * bias); with a flat spectrum to 2e-2, the two periodic sinc pulses'
 * band edges falling on different discrete frequencies.
 *
 * Threads: distinct plans may run concurrently; one plan owns work buffers
 * and must be executed by one thread at a time. No OpenMP. create and
 * destroy plan FFTW under the planner lock of op.h.
 * No file I/O: readers (src/io/airsas.c, the CLI) hand samples to it.
 */
#ifndef SASNAV_INGEST_H
#define SASNAV_INGEST_H

#include "sasnav/model.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Linear FM chirp: frequency f_start at t = 0 sweeping linearly to f_end at
 * t = duration, times a Tukey window of taper ratio `tukey` (0: rectangular,
 * 1: Hann). */
typedef struct {
    double f_start, f_end; /* Hz, both in (0, fs/2) */
    double duration;       /* s */
    double tukey;          /* in [0, 1] */
} sasnav_lfm;

/* Number of samples of the chirp at `sample_rate`: floor(duration fs)
 * (tolerant to rounding: 1 ms at 100 kHz is 100 samples). Returns 0 on bad
 * input (and sets the last error). */
int sasnav_lfm_length(const sasnav_lfm *lfm, double sample_rate);

/* Fills chirp[n], n = 0..n_samples-1 (n_samples from sasnav_lfm_length):
 *   chirp[n] = w[n] cos(2 pi (f_start t + (f_end - f_start) t^2 / (2 duration))),
 *   t = n / fs, w the symmetric Tukey window over the n_samples samples
 *   (w[0] = w[n-1] = 0 for tukey > 0).
 * Errors: SASNAV_ERR_ARG (frequencies outside (0, fs/2), duration <= 0,
 * tukey outside [0, 1], wrong length, NULL). */
int sasnav_lfm_samples(const sasnav_lfm *lfm, double sample_rate, int n_samples, float *chirp);

typedef enum {
    SASNAV_COMPRESS_MODEL = 0,  /* equalised to the operators' pulse (default) */
    SASNAV_COMPRESS_MATCHED = 1 /* plain matched filter, band-limited */
} sasnav_compression;

typedef struct {
    double sample_rate;   /* passband sampling rate fs, Hz (required) */
    double t_start;       /* time after transmission of input sample 0, s
                             (e.g. -group_delay / fs; default 0) */
    double f0;            /* carrier, Hz (required; the band [f0 - B/2, f0 + B/2]
                             must lie inside (0, fs/2)) */
    double bandwidth;     /* B, Hz (required) */
    int decimation;       /* D >= 1 with fs / D >= B (default 1) */
    sasnav_compression compression; /* default SASNAV_COMPRESS_MODEL */
    sasnav_taper taper;   /* spectral taper of the output pulse (default none) */
    double regularisation;/* eps of the equalised filter, in (0, 1] (default 1e-3:
                             the gain is at most 1/sqrt(eps) times that at the
                             strongest frequency of the chirp) */
    int clip_run;         /* a channel is refused as clipped when at least
                             clip_run consecutive samples equal its maximum
                             (if > 0) or its minimum (if < 0): what a
                             saturated converter writes. Default 3 (a run of
                             3 needs an overdrive of about 3 at 5 samples per
                             cycle, and is very unlikely in unclipped float or
                             >= 16-bit data of a band-pass signal; coarsely
                             quantised or low-frequency-dominated records can
                             trip it: raise it or disable); 0 disables the
                             check; 1 is refused */
} sasnav_ingest_opts;

typedef struct sasnav_ingest sasnav_ingest;

/* Defaults: sample_rate, f0, bandwidth = 0 (must be set), t_start 0, D = 1,
 * MODEL compression, no taper, eps 1e-3, clip_run 3. */
void sasnav_ingest_default_opts(sasnav_ingest_opts *opts);

/* Creates a plan for records of n_in samples per channel and the transmitted
 * chirp chirp[0..n_chirp-1], sampled at opts->sample_rate with sample 0 at
 * transmission (t = 0). The chirp is copied.
 * Errors (SASNAV_ERR_ARG with a message): NULL, n_in < 1, n_chirp < 1, a
 * chirp longer than the record, non-finite chirp samples or options, a band
 * not inside (0, fs/2), a decimation that aliases the band (fs / D < B), a
 * chirp with no energy in the band, bad eps or clip_run. SASNAV_ERR_NOMEM,
 * SASNAV_ERR_FFT. */
int sasnav_ingest_create(const sasnav_ingest_opts *opts, int n_in, const float *chirp,
                         int n_chirp, sasnav_ingest **plan);

/* Processes n_channels records: passband[c * n_in + n] (real) ->
 * baseband[c * n_out + m] (complex). Every channel is validated first
 * (finite samples, not clipped); on error nothing is written and the message
 * names the channel and the samples. Errors: SASNAV_ERR_ARG. */
int sasnav_ingest_execute(sasnav_ingest *plan, int n_channels, const float *passband,
                          sasnav_cfloat *baseband);

/* Validation alone (what execute checks): SASNAV_OK or SASNAV_ERR_ARG. */
int sasnav_ingest_check_record(const sasnav_ingest *plan, int n_channels, const float *passband);

/* The output window: t0 = t_start, n_samples = ceil(n_in / D). */
int sasnav_ingest_window(const sasnav_ingest *plan, sasnav_window *win);

/* Sets the fields of `sys` the chain determines: f0, bandwidth, sample_rate
 * (fs / D) and taper. sound_speed, attenuation and beam_pattern are left to
 * the caller. */
int sasnav_ingest_system(const sasnav_ingest *plan, sasnav_system *sys);

int sasnav_ingest_n_in(const sasnav_ingest *plan);
int sasnav_ingest_n_out(const sasnav_ingest *plan);
/* FFT length used (>= n_in + n_chirp, factors 2, 3, 5, 7). */
int sasnav_ingest_nfft(const sasnav_ingest *plan);

/* Safe on NULL. */
void sasnav_ingest_destroy(sasnav_ingest *plan);

#ifdef __cplusplus
}
#endif
#endif
