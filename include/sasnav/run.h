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

/* In-memory run. raw[(p * n_rx + l) * n_samples + m] is sample m of channel l
 * of ping p (file layout /raw [ping][channel][sample]). */
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
} sasnav_run;

/* Allocates a run with zeroed raw data and zeroed navigation; truth is
 * allocated when with_truth != 0. */
int sasnav_run_alloc(const sasnav_system *sys, const sasnav_array *array,
                     const sasnav_window *win, int n_pings, int with_truth, sasnav_run **run);

/* Gives `run` an aiding record (replacing any): time always, the gyro
 * arrays when with_yaw_rate, the DVL arrays when with_velocity; values
 * zeroed, standard deviations set to +inf. */
int sasnav_run_alloc_aiding(sasnav_run *run, int with_yaw_rate, int with_velocity);

/* Checks an aiding record against n_pings: finite values, standard
 * deviations > 0 (or +inf), strictly increasing times. */
int sasnav_aiding_check(const sasnav_aiding *aiding, int n_pings);

/* Frees an aiding record (safe on NULL). */
void sasnav_aiding_free(sasnav_aiding *aiding);

/* Pointer to channel data of ping p (n_rx * n_samples samples). */
sasnav_cfloat *sasnav_run_ping(const sasnav_run *run, int p);

/* Validates shapes and values (finite navigation, finite samples, the
 * aiding record when present). */
int sasnav_run_check(const sasnav_run *run);

/* A new run holding pings[0..n_pings-1] of `run` (in that order) and, when
 * `channels` is not NULL, only channels[0..n_channels-1] (the array keeps
 * those receivers' positions); navigation, truth and the run's constants
 * are carried over (ping_spacing scaled to the mean index step), and the
 * aiding record when the pings are consecutive and increasing. Free with
 * sasnav_run_free. Errors: indices out of range, no ping, no channel. */
int sasnav_run_subset(const sasnav_run *run, const int *pings, int n_pings, const int *channels,
                      int n_channels, sasnav_run **out);

/* Safe on NULL. */
void sasnav_run_free(sasnav_run *run);

#ifdef __cplusplus
}
#endif
#endif
