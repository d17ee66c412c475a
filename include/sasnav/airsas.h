/* sasnav -- AirSAS circular SAS recordings (Penn State ARL in-air system, as
 * published with Reed et al., "SINR", arXiv:2204.10428).
 *
 * A recording directory holds Flight-000001.csv ... (one ping each: rows of
 * real passband samples, one column per microphone, Mic1 first),
 * Coordinates.csv (header, then: flight number, turntable angle in degrees,
 * height in mm, air temperature in deg C, waveform index), SysParams.csv
 * ("key,value" rows: Speaker/Mic1/Mic2/Center x, y, z in m, Fs in Hz,
 * Group Delay in samples, ...) and WaveformParams.csv (one token string such
 * as LFM_3.00E+4Hz_1.00E+4Hz_1.00E-3s_5.00E-1V_tukeywin_1.00E-1).
 *
 * sasnav_airsas_read loads one directory (file I/O, this is the io layer);
 * sasnav_airsas_to_run is pure computation: background subtraction, removal
 * of the mean room response, pulse compression and demodulation (ingest.h),
 * and the circular geometry, giving a sasnav_run in the raw-data layout.
 *
 * Threads: the functions share no state and use no OpenMP; distinct objects
 * may be used from different threads. A recording opened with
 * sasnav_airsas_open reads its flights through scratch space of its own:
 * one such recording (or background) is used by one call at a time.
 * sasnav_airsas_to_run makes an ingest
 * plan (FFTW planning under the lock of op.h); sasnav_airsas_read only reads
 * text files.
 */
#ifndef SASNAV_AIRSAS_H
#define SASNAV_AIRSAS_H

#include "sasnav/ingest.h"
#include "sasnav/run.h"

#ifdef __cplusplus
extern "C" {
#endif

/* One recording directory, as read. */
typedef struct {
    int n_pings;         /* flights (rows of Coordinates.csv) */
    int n_samples;       /* samples per flight (rows of a Flight file) */
    int n_channels;      /* columns of the Flight files (microphones) */
    float *samples;      /* [ping][channel][sample], volts */
    double *angle_deg;   /* turntable angle of each ping */
    double *height_mm;   /* sensor height setting of each ping */
    double *temperature; /* air temperature of each ping, deg C */
    double speaker[3];   /* m */
    double mic[2][3];    /* Mic1, Mic2 (m); Mic2 only if has_mic2 */
    int has_mic2;
    double center[3];    /* scene centre, m */
    double sample_rate;  /* Fs, Hz */
    double group_delay;  /* samples: a delay tau is at sample tau Fs + group_delay */
    sasnav_lfm lfm;      /* transmitted LFM (WaveformParams.csv) */
    double drive_volts;  /* drive amplitude (informative) */
    /* A recording opened with sasnav_airsas_open: samples is NULL and
     * read_flight(flight_ctx, p, out) reads flight p into
     * out[channel][sample] (n_channels * n_samples values) when it is
     * needed. NULL for a recording read whole. */
    int (*read_flight)(void *flight_ctx, int p, float *out);
    void (*close_flights)(void *flight_ctx); /* called by sasnav_airsas_free */
    void *flight_ctx;
} sasnav_airsas;

/* Reads DIR/{Coordinates,SysParams,WaveformParams}.csv and
 * DIR/Flight-%06d.csv for every flight listed in Coordinates.csv.
 * Errors: SASNAV_ERR_IO (missing or unreadable file), SASNAV_ERR_FORMAT
 * (non-numeric field, wrong column or row count, flights out of order,
 * missing SysParams key, unknown waveform, non-finite value), each with a
 * message naming the file and line; SASNAV_ERR_NOMEM. */
int sasnav_airsas_read(const char *dir, sasnav_airsas **rec);

/* The same, but the flights are left in their files: only the first is
 * read (for the shape), the others by rec->read_flight when a computation
 * needs them (checked then, with the same errors). The memory of one
 * flight whatever the recording's length (sasnav_airsas_stream). */
int sasnav_airsas_open(const char *dir, sasnav_airsas **rec);

/* Safe on NULL. */
void sasnav_airsas_free(sasnav_airsas *rec);

typedef struct {
    double radius;      /* m, radius of the sensor circle (default 0.85, the
                           authors' value; SysParams puts the speaker at
                           0.8485 m and the microphones at 0.8615 m) */
    int microphone;     /* 1 (default, the authors' channel), 2, or 0: both,
                           one ping of two channels (Mic1, Mic2) at the same
                           (x, y) and their own heights (per-channel sizes,
                           geometry.h) */
    int first_ping;     /* first ping used (0-based, default 0) */
    int ping_stride;    /* use every ping_stride-th ping (default 1) */
    int max_pings;      /* at most this many pings (0: all, default) */
    int remove_room;    /* remove the mean room response (default 1) */
    int decimation;     /* baseband decimation of the 100 kHz records
                           (default 4: 25 kHz >= B = 20 kHz) */
    sasnav_compression compression; /* default SASNAV_COMPRESS_MODEL */
    sasnav_taper taper; /* spectral taper of the pulse (default none) */
    double f0;          /* carrier, Hz (0: centre of the chirp's sweep) */
    double bandwidth;   /* B, Hz (0: the chirp's sweep width) */
    int clip_run;       /* clipping check of the raw records (ingest.h;
                           default 3) */
} sasnav_airsas_opts;

void sasnav_airsas_default_opts(sasnav_airsas_opts *opts);

/* Removes the mean room response from real records ts[p * n + m] in place,
 * as the AirSAS authors do: with cm[m] the mean over the n_pings pings,
 *   dang = arg(cm) - arg(ts) wrapped to (-pi, pi] (0 or pi on real data),
 *   beta = 1 / (1 + dang^2), alpha = 1 / (1 + (|cm| - |ts|)^2),
 *   ts <- ts - alpha beta |cm| sign(ts)   (arg(ts) kept; 0 stays 0).
 * Errors: SASNAV_ERR_ARG (NULL, n_pings < 1, n < 1), SASNAV_ERR_NOMEM. */
int sasnav_airsas_remove_room(int n_pings, int n, float *ts);

/* Builds a run from a recording (and optionally an empty-scene recording of
 * the same shape, subtracted ping by ping):
 *  - raw records of the chosen microphone, minus the background, minus the
 *    mean room response (over all pings of the recording, whatever subset
 *    is kept), then for the kept pings the ingest chain (ingest.h) with the
 *    recorded LFM at Fs, t_start = -group_delay / Fs, carrier f0 and band B
 *    (default 20 kHz and 20 kHz for the 30 -> 10 kHz chirp);
 *  - geometry: ping p at angle a = 90 - angle_deg[p] degrees on the circle
 *    of `radius` around the scene centre (the origin), Tx and Rx at the same
 *    (x, y), yaw a + 90 degrees (boresight towards the centre); heights above
 *    the scene plane z = 0: speaker z + height / 1000 - centre z and
 *    microphone z + height / 1000 - centre z; omnidirectional elements
 *    (beam_pattern 0), no spreading loss (SASNAV_ATTEN_NONE), one receiver
 *    (two with microphone 0: channel l is Mic(l+1), rx_u 0, each with its
 *    own height; the room response removed per microphone);
 *  - one sound speed for the run: c = 331.4 + 0.6 T with T the mean
 *    temperature of all pings of the recording (the authors use one c per
 *    ping; over a recording T varies by ~0.05 deg C, i.e. 0.03 m/s, a delay
 *    change of 4e-7 s at 1.7 m two-way: 1% of a 20 kHz cycle);
 *  - nav = the nominal circle, truth = NULL, ping_spacing = radius times the
 *    angle step between kept pings (arc length), speed 0, tx_lag 0,
 *    range_of_interest = radius.
 * Errors: SASNAV_ERR_ARG (bad options, background of another shape, pings
 * at different heights, no ping selected, a clipped or non-finite raw record,
 * a band the chain refuses), SASNAV_ERR_NOMEM, SASNAV_ERR_FFT. */
int sasnav_airsas_to_run(const sasnav_airsas *rec, const sasnav_airsas *background,
                         const sasnav_airsas_opts *opts, sasnav_run **run);

/* Where sasnav_airsas_stream hands its run: `begin` gets the run's header
 * (everything but the samples: raw NULL, n_pings kept pings, the nominal
 * circle in nav) before the first ping, `ping` each kept ping k (0-based,
 * in order) as n_samples baseband values. A nonzero return stops the
 * stream with that code. */
typedef struct {
    int (*begin)(void *ctx, const sasnav_run *header);
    int (*ping)(void *ctx, int k, const sasnav_cfloat *samples);
    void *ctx;
} sasnav_airsas_sink;

/* sasnav_airsas_to_run ping by ping, for recordings of any length: the
 * same processing and the same samples bit for bit, but the output goes to
 * `sink` as it is made and, for a recording opened with sasnav_airsas_open
 * (and its background), the flights are read twice one at a time (the
 * mean room response over all flights first, then each kept flight):
 * memory of a few flights. Recordings read whole work too. Errors: those
 * of sasnav_airsas_to_run, the flight reader's and the sink's. */
int sasnav_airsas_stream(const sasnav_airsas *rec, const sasnav_airsas *background,
                         const sasnav_airsas_opts *opts, const sasnav_airsas_sink *sink);

#ifdef __cplusplus
}
#endif
#endif
