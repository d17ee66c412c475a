/* sasnav -- a run: the raw data of a sequence of pings and their navigation. */
#ifndef SASNAV_RUN_H
#define SASNAV_RUN_H

#include "sasnav/geometry.h"
#include "sasnav/model.h"

#ifdef __cplusplus
extern "C" {
#endif

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
} sasnav_run;

/* Allocates a run with zeroed raw data and zeroed navigation; truth is
 * allocated when with_truth != 0. */
int sasnav_run_alloc(const sasnav_system *sys, const sasnav_array *array,
                     const sasnav_window *win, int n_pings, int with_truth, sasnav_run **run);

/* Pointer to channel data of ping p (n_rx * n_samples samples). */
sasnav_cfloat *sasnav_run_ping(const sasnav_run *run, int p);

/* Validates shapes and values (finite navigation, finite samples). */
int sasnav_run_check(const sasnav_run *run);

/* A new run holding pings[0..n_pings-1] of `run` (in that order) and, when
 * `channels` is not NULL, only channels[0..n_channels-1] (the array keeps
 * those receivers' positions); navigation, truth and the run's constants
 * are carried over (ping_spacing scaled to the mean index step). Free with
 * sasnav_run_free. Errors: indices out of range, no ping, no channel. */
int sasnav_run_subset(const sasnav_run *run, const int *pings, int n_pings, const int *channels,
                      int n_channels, sasnav_run **out);

/* Safe on NULL. */
void sasnav_run_free(sasnav_run *run);

#ifdef __cplusplus
}
#endif
#endif
