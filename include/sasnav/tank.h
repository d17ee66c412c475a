/* sasnav -- the tank experiment of SPEC 4 as a passband simulator, and the
 * reader that turns its recordings back into a run.
 *
 * Simulator: 8 omni receivers (5 cm spaced 5 cm) and a transmitter at the
 * array midpoint, all at height `array_height` above the plate plane (z = 0);
 * the sensor is stepped along +x by a plotter. Ping p's nominal pose is
 * (x_start + p * step, 0, 0); its true pose adds cumulative, seeded stepping
 * errors (surge and sway, per step), a surge jump between pings jump_ping - 1
 * and jump_ping, and a constant array yaw. The scene: n_reflectors point-like
 * reflectors plus n_clutter weak random points on an octagonal plate. Each
 * channel records the real passband sum of the transmitted LFM chirp delayed
 * by the exact 3-D two-way delay (r_t + r_r) / c of every scatterer, times
 * its amplitude, the recording gain and the spreading loss, plus seeded
 * white Gaussian noise.
 * Sample 0 of a record is the instant of transmission (t = 0); records span
 * [0, 2 range_max / c + T_chirp].
 *
 * Recording directory (sasnav_tank_write_dir, `sasnav tank`):
 *   ping_000.wav ..   n_rx-channel 32-bit float WAV at sample_rate
 *   chirp.wav         the transmitted chirp (mono, same rate)
 *   positions.csv     "ping,x,y,yaw": the nominal (plotter) positions
 *   truth.csv         "ping,x,y,yaw": the true poses (Tx = array midpoint)
 *   array.csv         "rx_spacing,element_length,directivity": the sensor
 *                     (the reader takes it over its options when present)
 * Reader (sasnav_tank_read_dir, `sasnav ingest --wav DIR`): checks every WAV
 * (same channel count and length, sample-rate match with the chirp, not
 * empty, finite, not clipped), runs the ingest chain (include/sasnav/ingest.h)
 * per ping and returns a run with the nominal navigation of positions.csv and,
 * when truth.csv exists, the truth.
 *
 * Threads: no shared state, no OpenMP: distinct calls (distinct directories)
 * may run concurrently. sasnav_tank_read_dir makes an ingest plan (FFTW
 * planning under the lock of op.h); WAV files go through libsndfile, one
 * handle per file.
 */
#ifndef SASNAV_TANK_H
#define SASNAV_TANK_H

#include <stdint.h>

#include "sasnav/geometry.h"
#include "sasnav/ingest.h"
#include "sasnav/model.h"
#include "sasnav/run.h"

#ifdef __cplusplus
extern "C" {
#endif

#define SASNAV_TANK_MAX_REFLECTORS 16

typedef struct {
    /* acoustics and recording */
    double sound_speed;     /* m/s (1480) */
    sasnav_lfm chirp;       /* 90 -> 120 kHz, 3 ms, Tukey 0.1 */
    double sample_rate;     /* Hz (1e6) */
    double range_max;       /* m, farthest range recorded (3.0) */
    double range_min;       /* m, nearest range of interest (0.5; informative) */
    sasnav_attenuation attenuation; /* SPHERICAL (1/(r_t r_r)) or EXPLODING */
    double gain;            /* recording gain applied to every echo (0.25: keeps the
                               float samples inside [-1, 1]) */
    double noise_std;       /* std of the white noise per passband sample (1e-3) */
    /* sensor */
    int n_rx;               /* 8 */
    double rx_spacing;      /* m (0.05) */
    double array_height;    /* m above the plate plane, Tx and Rx (0) */
    double element_length;  /* m, Tx and Rx apertures (0.05) */
    int directivity;        /* 1 (default): the elements' line-aperture
                               patterns sinc(D sin(phi) / lambda0) at the
                               chirp's centre frequency (the model's, see
                               docs/model.md) weight every echo; 0: omni */
    /* plotter track */
    int n_pings;            /* 32 */
    double step;            /* m, nominal step along +x (0.025) */
    double x_start;         /* m, nominal x of ping 0 (-(n_pings-1) step / 2) */
    double surge_step_std;  /* m, std of each step's along-track error (2e-3) */
    double sway_step_std;   /* m, std of each step's cross-track error (1e-3) */
    int jump_ping;          /* the surge jump happens between jump_ping-1 and jump_ping (12) */
    double jump;            /* m (+0.017) */
    double yaw;             /* rad, constant true array yaw (1.27e-2) */
    /* scene */
    int n_reflectors;       /* 4 */
    double refl_x[SASNAV_TANK_MAX_REFLECTORS], refl_y[SASNAV_TANK_MAX_REFLECTORS];
    double refl_amp[SASNAV_TANK_MAX_REFLECTORS];
    double plate_x, plate_y;/* plate centre (0, 1.5) */
    double plate_radius;    /* m, circumradius of the octagon (0.3) */
    int n_clutter;          /* 200 */
    double clutter_std;     /* std of the clutter amplitudes (0.02) */
    uint64_t seed;          /* seeds errors, clutter and noise (1) */
} sasnav_tank_params;

/* The SPEC 4 tank set-up: reflectors at the corners of a 20 cm square
 * centred at (0, 1.5), amplitude 1; see the field comments for the rest. */
void sasnav_tank_default(sasnav_tank_params *p);

/* Validates the parameters. SASNAV_OK or SASNAV_ERR_ARG. */
int sasnav_tank_check(const sasnav_tank_params *p);

/* Samples per channel of a record, and of the chirp (0 on bad parameters). */
int sasnav_tank_n_samples(const sasnav_tank_params *p);
int sasnav_tank_n_chirp(const sasnav_tank_params *p);

/* The scatterers: reflectors first, then the clutter (n_reflectors +
 * n_clutter entries each; amplitudes before `gain`). Deterministic in seed. */
int sasnav_tank_scene(const sasnav_tank_params *p, double *x, double *y, double *amp);

/* Nominal and true poses of every ping (n_pings each; either may be NULL). */
int sasnav_tank_poses(const sasnav_tank_params *p, sasnav_ping_pose *nominal,
                      sasnav_ping_pose *truth);

/* Synthesises ping `ping`: passband[l * n_samples + n] for l < n_rx, n <
 * sasnav_tank_n_samples. `truth` (may be NULL) receives the ping's true pose.
 * Deterministic in (params, ping). */
int sasnav_tank_record(const sasnav_tank_params *p, int ping, float *passband,
                       sasnav_ping_pose *truth);

/* Writes the recording directory described above (created if missing; files
 * written under temporary names, then renamed). Errors: SASNAV_ERR_ARG,
 * SASNAV_ERR_IO, SASNAV_ERR_NOMEM. */
int sasnav_tank_write_dir(const sasnav_tank_params *p, const char *dir);

/* Options of the reader. */
typedef struct {
    double sound_speed;       /* m/s (1480) */
    double f0, bandwidth;     /* Hz (105e3, 30e3) */
    int decimation;           /* 33 */
    sasnav_taper taper;       /* NONE */
    sasnav_compression compression; /* MODEL */
    sasnav_attenuation attenuation; /* recorded in the run's system (SPHERICAL) */
    int clip_run;             /* as in sasnav_ingest_opts (3) */
    double rx_spacing;        /* m (0.05); n_rx comes from the WAV files */
    double element_length;    /* m (0.05), Rx and Tx */
    int directivity;          /* 1 (default): the run's model has the
                                 elements' beam patterns; 0: omnidirectional */
    double range_of_interest; /* m (1.5) */
} sasnav_tank_read_opts;

void sasnav_tank_default_read_opts(sasnav_tank_read_opts *o);

/* Reads a recording directory into a run (see above). The run's system has
 * beam patterns when o->directivity (tx_lag 0, speed 0, ping_spacing from the median
 * step of positions.csv). Errors: SASNAV_ERR_IO (missing files),
 * SASNAV_ERR_FORMAT (bad WAV/CSV, channel/length/rate mismatch, empty,
 * clipped), SASNAV_ERR_ARG, SASNAV_ERR_NOMEM, SASNAV_ERR_FFT. */
int sasnav_tank_read_dir(const char *dir, const sasnav_tank_read_opts *o, sasnav_run **run);

/* The same, written to the run file `path` ping by ping as each WAV is
 * ingested (sasnav_run_writer: the same file as sasnav_run_write of the
 * run sasnav_tank_read_dir returns; memory of one ping whatever the
 * recording's length; nothing left at `path` on failure). `info` (may be
 * NULL) receives the run's header: its shape and constants (raw, nav and
 * truth NULL). Errors: those of sasnav_tank_read_dir and of the writer. */
int sasnav_tank_ingest_dir(const char *dir, const sasnav_tank_read_opts *o, const char *path, sasnav_run *info);

#ifdef __cplusplus
}
#endif
#endif
