/* sasnav -- a run: the raw data of a sequence of pings and their navigation.
 *
 * Threads: no shared state and no OpenMP. A run may be read by any number
 * of threads at once (every library function takes it as const, e.g.
 * several sasnav_navigate / sasnav_backproject calls on one run); allocating,
 * filling or freeing one needs the caller's exclusive access. */
#ifndef SASNAV_RUN_H
#define SASNAV_RUN_H

#include "sasnav/geometry.h"
#include "sasnav/model.h"

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Aiding measurements of a run (docs/format.md, "/aiding"): what the
 * vehicle's navigation sensors say about each ping interval. Entry p
 * describes the interval (t[p - 1], t[p]] that ends at ping p; entry 0 (the
 * interval before the first ping) is stored for a uniform layout and not
 * used. The quantities refer to the pings' PCA-centroid frames (the
 * sensors' lever arms and time tags already applied, as an INS does).
 * Either the gyro or the DVL part may be absent (NULL). Standard
 * deviations are > 0; +inf marks an entry without a measurement. */
typedef struct {
    double *time;            /* n_pings: s, ping epochs (strictly increasing) */
    double *yaw_rate;        /* n_pings: rad/s, mean yaw rate over the interval
                                (gyro / INS), or NULL */
    double *yaw_rate_sigma;  /* n_pings: rad/s, its standard deviation */
    double *velocity;        /* 2 n_pings: m/s, mean velocity over the interval
                                (surge, sway) in the frame at the interval's
                                mean heading (DVL), or NULL */
    double *velocity_sigma;  /* 2 n_pings: m/s, their standard deviations */
} sasnav_aiding;

/* Where the samples of a streamed run come from (sasnav_run_open, io.h:
 * a run file read ping by ping). read() fills `out` (n_rx * n_samples
 * values) with ping p and returns SASNAV_OK or an error code (message
 * set); close() releases ctx (called by sasnav_run_free). The library
 * never calls read() from two threads at once (sasnav_run_get_ping
 * serialises the calls), so ctx needs no locking of its own. */
typedef struct {
    int (*read)(void *ctx, int p, sasnav_cfloat *out);
    void (*close)(void *ctx);
    void *ctx;
} sasnav_ping_source;

/* A run. raw[(p * n_rx + l) * n_samples + m] is sample m of channel l of
 * ping p (file layout /raw [ping][channel][sample]), or raw is NULL and the
 * pings come from `source` (a streamed run: only the pings in use are in
 * memory; docs/library.md, "Streamed runs"). Code that reads samples goes
 * through sasnav_run_get_ping, which serves both. */
typedef struct {
    sasnav_system sys;
    sasnav_array array;
    sasnav_window win;
    int n_pings;
    sasnav_cfloat *raw;        /* n_pings * n_rx * n_samples */
    sasnav_ping_pose *nav;     /* navigation to process with (nominal or measured), n_pings */
    sasnav_ping_pose *truth;   /* true sensor poses, or NULL when unknown */
    double ping_spacing;       /* nominal along-track spacing, m */
    double speed;              /* nominal speed, m/s (0 if unknown) */
    double tx_lag;             /* EPCA Tx-array offset used for processing, m */
    double range_of_interest;  /* centre range of the swath, m */
    sasnav_aiding *aiding;     /* aiding measurements, or NULL */
    sasnav_ping_source source; /* streamed runs (raw NULL); zero otherwise */
    sasnav_ping_pose *channel_offset; /* n_rx: each channel's transmitter and
                                 array pose relative to its ping's
                                 (sasnav_channel_poses; a head with several
                                 transmitters, receivers off the axis), or
                                 NULL: one transmitter and N receivers on
                                 the axis, the common case. The same for
                                 every ping; file: /channels, format
                                 version 2 */
} sasnav_run;

/* Allocates a run with zeroed raw data and zeroed navigation; truth is
 * allocated when with_truth != 0. */
int sasnav_run_alloc(const sasnav_system *sys, const sasnav_array *array,
                     const sasnav_window *win, int n_pings, int with_truth, sasnav_run **run);

/* Allocates a streamed run: no samples in memory (raw NULL), its pings
 * read through `source` (which the run owns from here: sasnav_run_free
 * closes it, also when this call fails), zeroed navigation, truth
 * allocated when with_truth != 0. */
int sasnav_run_alloc_streamed(const sasnav_system *sys, const sasnav_array *array,
                              const sasnav_window *win, int n_pings, int with_truth,
                              const sasnav_ping_source *source, sasnav_run **run);

/* Gives `run` an aiding record (replacing any): time always, the gyro
 * arrays when with_yaw_rate, the DVL arrays when with_velocity; values
 * zeroed, standard deviations set to +inf. */
int sasnav_run_alloc_aiding(sasnav_run *run, int with_yaw_rate, int with_velocity);

/* Checks an aiding record against n_pings: finite values, standard
 * deviations > 0 (or +inf), strictly increasing times. */
int sasnav_aiding_check(const sasnav_aiding *aiding, int n_pings);

/* Gives `run` per-channel offsets (n_rx entries, copied; NULL removes
 * them). Errors: non-finite offsets, positions beyond the plausible size,
 * NULL run. */
int sasnav_run_set_channel_offset(sasnav_run *run, const sasnav_ping_pose *offset);

/* Ping p's channel poses from `ping` (its navigation or truth) and the
 * run's offsets: n_rx entries, each the ping's own poses when the run has
 * no offsets. */
void sasnav_run_channel_poses(const sasnav_run *run, const sasnav_ping_pose *ping, sasnav_ping_pose *out);

/* Frees an aiding record (safe on NULL). */
void sasnav_aiding_free(sasnav_aiding *aiding);

/* Pointer to channel data of ping p (n_rx * n_samples samples) of an
 * in-memory run; NULL for a streamed run (use sasnav_run_get_ping). */
sasnav_cfloat *sasnav_run_ping(const sasnav_run *run, int p);

/* Ping p's samples, from either kind of run: *ping points into raw (an
 * in-memory run) or at `buf` (n_rx * n_samples values), into which a
 * streamed run's source has read it. Calls to a source are serialised
 * (an OpenMP critical section), so any number of threads may call this on
 * one run. Errors: p out of range, NULL arguments, the source's error. */
int sasnav_run_get_ping(const sasnav_run *run, int p, sasnav_cfloat *buf,
                        const sasnav_cfloat **ping);

/* Samples per ping (n_rx * n_samples). */
size_t sasnav_run_ping_size(const sasnav_run *run);

/* Validates shapes and values (finite navigation, finite samples, the
 * aiding record when present). A streamed run's samples are checked as
 * each ping is read (by its source), not here. */
int sasnav_run_check(const sasnav_run *run);

/* Plausible ping poses (what sasnav_run_check asks of a run's navigation
 * and truth): finite, within Earth scale (|x|, |y| <= SASNAV_POSITION_MAX_M),
 * the transmitter within SASNAV_SIZE_MAX_M of the array in each ping.
 * SASNAV_ERR_ARG naming `what` and the ping. */
int sasnav_poses_check(const sasnav_ping_pose *poses, int n, const char *what);

/* sasnav_run_check without the samples (a run's header: shapes,
 * constants, navigation, truth, aiding; raw and source may be absent). */
int sasnav_run_check_header(const sasnav_run *run);

/* A new in-memory run holding pings[0..n_pings-1] of `run` (in that order; read from its source when `run` is streamed) and, when
 * `channels` is not NULL, only channels[0..n_channels-1] (the array keeps
 * those receivers' positions); navigation, truth and the run's constants
 * are carried over (ping_spacing scaled to the mean index step), and the
 * aiding record when the pings are consecutive and increasing. Free with
 * sasnav_run_free. Errors: indices out of range, no ping, no channel. */
int sasnav_run_subset(const sasnav_run *run, const int *pings, int n_pings, const int *channels,
                      int n_channels, sasnav_run **out);

/* Frees the run (and closes a streamed run's source). Safe on NULL. */
void sasnav_run_free(sasnav_run *run);

#ifdef __cplusplus
}
#endif
#endif
