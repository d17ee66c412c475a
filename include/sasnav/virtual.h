/* sasnav -- virtual arrays: K consecutive pings as one "virtual ping" whose
 * channels are Tx-Rx pairs of their own, and navigation from the motion
 * between virtual pings (docs/navigation.md, "Virtual arrays").
 *
 * A sonar with one channel (SISO: AirSAS, a single-beam side-scan) or with
 * too few channels for a ping to form an image of its own cannot be
 * navigated ping to ping by the subspace estimator: one Tx-Rx pair sees the
 * scene only along ellipses (paper Section II). K consecutive pings seen
 * together are an array of K x N channels, each with its own transmitter
 * and receiver pose (sasnav_op_set_channels). The estimator compares two
 * such virtual pings S pings apart: the geometry inside each group (where
 * its pings are relative to one another) is taken from the input
 * navigation, the motion between the groups is estimated.
 *
 * Stride S = K (the default): disjoint groups, every ping in one group;
 * the groups move rigidly with their estimated centroids, the motion
 * inside a group is the input navigation's. S < K: groups share pings; a
 * ping's estimate is the mean over the groups that hold it. Beware: a
 * shared ping holds the same samples in both virtual pings, so it pulls
 * the estimate towards the input navigation's displacement (for which the
 * shared channels coincide); S < K refines little.
 *
 * Threads: sasnav_navigate_virtual runs opts.nthreads pairs at once (one
 * estimator per thread); results do not depend on the number. The other
 * functions are pure. */
#ifndef SASNAV_VIRTUAL_H
#define SASNAV_VIRTUAL_H

#include "sasnav/estimator.h"
#include "sasnav/run.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Centroid of a ping's channels (channel l: receiver l of `array` on
 * channels[l].array, its transmitter channels[l].tx): the mean of the
 * channels' phase centres ((Tx + Rx_l) / 2, in the plane) and the circular
 * mean of the array yaws. For a one-Tx ping whose rx_u average to 0 it is
 * sasnav_ping_centroid. */
sasnav_pose sasnav_channels_centroid(const sasnav_array *array, const sasnav_ping_pose *channels);

/* The array of a virtual ping of k pings: k * n_rx channels, channel
 * j * n_rx + l being receiver l of ping j (rx_u repeated; lengths and
 * heights kept). Errors: k < 1, k * n_rx > SASNAV_MAX_RX. */
int sasnav_virtual_array(const sasnav_array *array, int k, sasnav_array *out);

/* The channel layout of a virtual ping made of pings with poses
 * poses[0..k-1] (world frame): *centroid receives the centroid of its
 * k * n_rx channels (sasnav_channels_centroid), local[c] channel c's Tx
 * and array poses in that centroid's frame (k * n_rx entries). */
int sasnav_virtual_layout(const sasnav_array *array, const sasnav_ping_pose *poses, int k,
                          sasnav_ping_pose *local, sasnav_pose *centroid);

typedef struct {
    int k;                  /* pings per virtual ping (default 4) */
    int stride;             /* pings between the first pings of consecutive
                               virtual pings (default 0 = k: disjoint) */
    sasnav_pair_opts pair;  /* the estimator's options (default: fix_yaw 1,
                               the rest sasnav_pair_default_opts; set range, pixel,
                               cross_extent and box for the layout) */
    int iterations;         /* passes (default 2): each pass takes the
                               previous one's navigation as its input, so
                               that the geometry inside the groups follows
                               the estimates (1..20) */
    int nthreads;           /* pairs estimated at once (0: OpenMP default) */
} sasnav_virtual_opts;

void sasnav_virtual_default_opts(sasnav_virtual_opts *opts);

typedef struct {
    int first_p, first_q;     /* first pings of the two virtual pings */
    sasnav_pose nominal;      /* displacement of q's centroid in p's frame,
                                 from the input navigation */
    sasnav_pose truth;        /* the same from the run's truth (NaN: none) */
    sasnav_pair_result est;   /* the estimate (est.displacement) */
} sasnav_virtual_pair;

typedef struct {
    int n_pings, k, stride;
    int n_groups;             /* virtual pings */
    int n_pairs;              /* n_groups - 1 */
    sasnav_virtual_pair *pairs;
    sasnav_pose *centroid_in; /* n_groups: centroids from the input navigation */
    sasnav_pose *centroid;    /* n_groups: estimated (the first one anchored
                                 at its input value) */
    sasnav_ping_pose *nav;    /* n_pings: the estimated navigation */
    int iterations;           /* passes made (pairs, centroid_in and
                                 centroid are the last pass's) */
    double seconds;           /* wall time */
} sasnav_virtual_navigation;

/* Navigates `run` by virtual pings of opts->k pings every opts->stride
 * pings (see the top of this file): estimates the displacement of each
 * virtual ping relative to the previous one, chains them from the first
 * group's input centroid, and moves each group's pings rigidly with its
 * centroid (mean over the groups that hold a ping; pings after the last
 * group move with it). Errors: fewer than two groups (n_pings < k +
 * stride), k * n_rx > SASNAV_MAX_RX, the estimator's errors (prefixed with
 * the pair). Free the result with sasnav_virtual_navigation_free. */
int sasnav_navigate_virtual(const sasnav_run *run, const sasnav_virtual_opts *opts,
                            sasnav_virtual_navigation *out);

void sasnav_virtual_navigation_free(sasnav_virtual_navigation *nav);

#ifdef __cplusplus
}
#endif
#endif
