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
 * Which pings form a group, and which groups are compared
 * (docs/navigation.md, "Virtual arrays", for the measurements):
 * - disjoint groups (interleave 1, stride K, the default): pings
 *   gK .. gK + K - 1 against the next K. The two apertures do not overlap:
 *   their images share little but the scene's range structure, so sway is
 *   well observed and surge weakly (simulated AirSAS, K = 4: surge 3.3 mm
 *   rms per step, sway 0.11 mm, noise-free).
 * - interleaved groups (interleave m = 2, stride 1): pings g, g + 2, ...,
 *   g + 2 (K - 1) against g + 1, g + 3, ...: the apertures overlap
 *   (redundant-phase-centre-like), no ping is shared, and both components
 *   are well observed (the same run: surge 0.2-0.5 mm, sway 0.01-0.07
 *   mm) for one estimate per ping.
 * - groups that share pings (stride < the span of a group, same parity):
 *   a shared ping holds the same samples in both virtual pings, so it
 *   pulls the estimate towards the input navigation's displacement (for
 *   which the shared channels coincide); they refine little.
 * The motion inside a group comes from the input navigation. A flagged
 * estimate (verdict not "ok") is not used: that step keeps the input
 * navigation's displacement. The first
 * group is anchored at its input centroid; each group's correction (its
 * estimated centroid against its input one) is interpolated between the
 * groups' middle pings and applied to every ping; further passes
 * (iterations) start from that navigation, so that the geometry inside the
 * groups follows the estimates. Relative navigation: the per-step errors
 * accumulate along the run (a random walk, and a drift where they have a
 * bias). The layouts come from the input: an input error that is smooth
 * over a group (an INS-like drift) distorts both groups of a pair alike,
 * and the estimate keeps it (89-99.6 % of the input's step error,
 * docs/airsas.md); what the steps correct is an error not shared by the
 * two groups (a jump, a wrong ping).
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
 * poses[0..k-1] (world frame; one transmitter per ping: sasnav_navigate_virtual
 * also applies a run's channel_offset to each ping's channels): *centroid receives the centroid of its
 * k * n_rx channels (sasnav_channels_centroid), local[c] channel c's Tx
 * and array poses in that centroid's frame (k * n_rx entries). */
int sasnav_virtual_layout(const sasnav_array *array, const sasnav_ping_pose *poses, int k,
                          sasnav_ping_pose *local, sasnav_pose *centroid);

typedef struct {
    int k;                  /* pings per virtual ping (default 4) */
    int interleave;         /* m: a virtual ping takes every m-th ping,
                               pings first + m j, j < k (default 1:
                               consecutive pings) */
    int stride;             /* pings between the first pings of consecutive
                               virtual pings (default 0: k when m = 1,
                               disjoint groups; 1 when m > 1, interleaved
                               groups) */
    sasnav_pair_opts pair;  /* the estimator's options (default: fix_yaw 1,
                               the rest sasnav_pair_default_opts; set range, pixel,
                               cross_extent and box for the layout) */
    int closed;             /* 1: the track closes on itself (a full circle,
                               a turntable): groups wrap round the end of
                               the run, one more pair links the last group
                               to the first, and the chain's misclosure is
                               spread evenly over its steps (default 0) */
    int iterations;         /* passes (default 2): each pass takes the
                               previous one's navigation as its input, so
                               that the geometry inside the groups follows
                               the estimates (1..20) */
    int nthreads;           /* pairs estimated at once (0: OpenMP default) */
    int keep_length;        /* 1: the used estimates' translations are scaled
                               by one factor so that their total length is
                               the input navigation's over the same steps:
                               the estimates give the track's shape, the
                               input (an INS, a DVL, a turntable's nominal
                               rate) its length. The estimator's steps are
                               0.5-3 % too long on interleaved groups of
                               omnidirectional pings (docs/airsas.md), and on
                               a closed loop a uniform length error is a
                               change of scale that the closure cannot see.
                               Right only where the input's length is: a
                               drift that returns, not an INS scale-factor
                               error (default 0) */
    int align_heading;      /* 1: each group's layout (where its pings are
                               relative to one another) is turned about its
                               centroid so that the pings' principal axis
                               lies along their mean heading: the track
                               inside a group follows the headings (a
                               gyro's; no crab), its spacing the input's.
                               A position drift of the input tilts the
                               layouts of neighbouring groups alike, and
                               the steps between two such groups keep the
                               tilt (docs/airsas.md, section 3, "Cause 1
                               taken apart");
                               with this the sway part of the drift is
                               measured. Wrong where the vehicle crabs
                               (default 0) */
    int along_input;        /* 1: the input navigation's along-track is
                               kept and the echoes correct only the
                               across-track (the field's practice with a
                               single-channel sonar: along track from a DVL
                               or an INS, across track from the echoes):
                               group g's centroid moves along its normal
                               (its input yaw + 90 degrees) by c_g, chained
                               from the used steps' sway, (X_h - X_g) . n_g
                               = the step's sway (nominal + (c_h cos(yaw_h -
                               yaw_g) - c_g) in group g's frame), c_0 = 0
                               (closed: the misclosure spread evenly); the
                               yaws stay the input's. Use it with
                               align_heading, without which the steps'
                               sway keeps the input's drift; like it, it
                               needs headings that the true track follows
                               (a vehicle crabbing unknown to the input
                               keeps its across-track error). With
                               keep_length the sway steps are scaled too
                               (the estimator's length bias; every
                               measurement used it). Consecutive groups
                               whose input yaws differ by more than 60
                               degrees are refused (the step's sway is read
                               across the next normal, 1 / cos). Removes an
                               across-track drift down to the first
                               group's own error; an along-track drift
                               stays (measured: docs/airsas.md, section 3)
                               (default 0) */
} sasnav_virtual_opts;

void sasnav_virtual_default_opts(sasnav_virtual_opts *opts);

typedef struct {
    int first_p, first_q;     /* first pings of the two virtual pings */
    sasnav_pose nominal;      /* displacement of q's centroid in p's frame,
                                 from the input navigation */
    sasnav_pose truth;        /* the same from the run's truth (NaN: none) */
    sasnav_pair_result est;   /* the estimate (est.displacement) */
    int used;                 /* 1: the estimate is "ok" and went into the
                                 navigation; 0: it was flagged and the
                                 input navigation's step was kept */
    sasnav_pose step;         /* the displacement the navigation used */
} sasnav_virtual_pair;

typedef struct {
    int n_pings, k, stride, interleave;
    int n_groups;             /* virtual pings */
    int n_pairs;              /* n_groups - 1 (n_groups when closed) */
    int closed;
    int align_heading;        /* the layouts were turned onto the headings */
    int along_input;          /* the along-track was kept from the input
                                 (along_input): centroid[g] - centroid_in[g]
                                 lies along group g's normal */
    sasnav_pose misclosure;   /* closed: where the chained steps ended
                                 minus where they started (world frame,
                                 before it was spread; along_input: the
                                 across-track correction's, c_n n_0, yaw 0) */
    sasnav_virtual_pair *pairs;
    sasnav_pose *centroid_in; /* n_groups: centroids from the input navigation */
    sasnav_pose *centroid;    /* n_groups: estimated (the first one anchored
                                 at its input value; along_input: each moved
                                 from its input value along its normal) */
    double *layout_turn;      /* n_groups: the angle (rad, counter-clockwise)
                                 by which align_heading turned each group's
                                 layout in the last pass (0 without it) */
    double turn_mean, turn_rms; /* their mean and rms over the groups */
    double turn_exposure;     /* the largest position error (m) that a
                                 constant crab or heading bias of turn_mean
                                 would leave in the chained centroids, since
                                 align_heading turns every step by it:
                                 |turn_mean| times the largest distance of a
                                 centroid from the first (the track's length
                                 on a straight track, at most the diameter of
                                 a closed circle); along_input: times the
                                 length chained to a group (a closed loop's
                                 spread takes out the part proportional to
                                 the group's index: nearly all of it with
                                 even steps). 0 without align_heading. A sideways
                                 drift that returns turns the layouts both
                                 ways (mean 0); a large exposure means a
                                 constant turn: a crab, a heading bias, a
                                 sideways drift that grows along the run,
                                 or on a curved track an along-track
                                 offset (a turn of offset / radius), which
                                 the echoes cannot tell apart
                                 (docs/airsas.md, section 3) */
    sasnav_ping_pose *nav;    /* n_pings: the estimated navigation */
    int n_fallback;           /* steps of the last pass that kept the input
                                 navigation's (flagged estimates) */
    double length_scale;      /* the factor applied to the used steps'
                                 translations (keep_length; 1 otherwise) */
    int iterations;           /* passes made (pairs, centroid_in and
                                 centroid are the last pass's) */
    double seconds;           /* wall time */
} sasnav_virtual_navigation;

/* Navigates `run` by virtual pings of opts->k pings (every
 * opts->interleave-th) every opts->stride pings (see the top of this
 * file): estimates the displacement of each virtual ping relative to the
 * previous one, chains them from the first group's input centroid, and
 * spreads the groups' corrections over the pings. Errors: fewer than two
 * groups, k * n_rx > SASNAV_MAX_RX, bad options, the estimator's errors
 * (prefixed with the pair). Free the result with
 * sasnav_virtual_navigation_free. */
int sasnav_navigate_virtual(const sasnav_run *run, const sasnav_virtual_opts *opts,
                            sasnav_virtual_navigation *out);

void sasnav_virtual_navigation_free(sasnav_virtual_navigation *nav);

#ifdef __cplusplus
}
#endif
#endif
