/* sasnav -- planar geometry: SE(2) poses, the array, ping poses, PCA centroids.
 *
 * Conventions (SPEC 1): x along-track, y range (towards the scene), theta yaw
 * counter-clockwise from +x. At theta = 0 the array axis is +x and every
 * element looks along +y. Metres and radians.
 *
 * Threads: every function here is pure (no state, no OpenMP, no FFTW):
 * safe to call concurrently from any threads; inputs may be shared
 * read-only.
 */
#ifndef SASNAV_GEOMETRY_H
#define SASNAV_GEOMETRY_H

#ifdef __cplusplus
extern "C" {
#endif

#define SASNAV_MAX_RX 128

/* A pose in SE(2): position (x, y) and yaw theta. */
typedef struct {
    double x, y, theta;
} sasnav_pose;

/* Composition a * b: b expressed in a's frame, returned in the world frame. */
sasnav_pose sasnav_pose_compose(sasnav_pose a, sasnav_pose b);
/* Inverse: a * inverse(a) = identity. */
sasnav_pose sasnav_pose_inverse(sasnav_pose a);
/* Pose of q in p's frame: inverse(p) * q. */
sasnav_pose sasnav_pose_between(sasnav_pose p, sasnav_pose q);
/* Applies pose a to a point (px, py) given in a's frame. */
void sasnav_pose_apply(sasnav_pose a, double px, double py, double *wx, double *wy);
/* Wraps an angle to (-pi, pi]. */
double sasnav_wrap_angle(double theta);

/* The apertures and heights of one channel's transmitter and receiver. */
typedef struct {
    double rx_length;           /* m, receiver aperture D_r (0 = omnidirectional) */
    double tx_length;           /* m, transmitter aperture D_t (0 = omnidirectional) */
    double rx_height;           /* m above the scene plane */
    double tx_height;           /* m above the scene plane */
} sasnav_channel_size;

/* The sensor head: N receivers along the array axis and one transmitter.
 * rx_u[l] is the along-array coordinate of receiver l relative to the array
 * midpoint (SPEC 1: (l - (N-1)/2) * spacing for a uniform array).
 * Heights are above the scene plane (3-D geometries, e.g. in-air rigs);
 * motion stays in the plane.
 *
 * Channels of their own sizes (docs/model.md, "Channel layouts"): with
 * per_channel = 1, channel l's apertures and heights are size[l] (a head
 * whose receivers sit at several heights, e.g. AirSAS's two microphones, or
 * transmitters of several lengths) and the four array-wide values are not
 * used by the operators (sasnav_array_set_sizes keeps them as the channels'
 * largest lengths and mean heights, for the summaries that want one value).
 * per_channel = 0 (every array built before) is the one-size head. */
typedef struct {
    int n_rx;
    double rx_u[SASNAV_MAX_RX]; /* m, along the array axis */
    double rx_length;           /* m, receiver aperture D_r (0 = omnidirectional) */
    double tx_length;           /* m, transmitter aperture D_t (0 = omnidirectional) */
    double rx_height;           /* m above the scene plane (default 0) */
    double tx_height;           /* m above the scene plane (default 0) */
    int per_channel;            /* 1: size[l] holds channel l's sizes */
    sasnav_channel_size size[SASNAV_MAX_RX];
} sasnav_array;

/* Channel l's sizes: size[l] with per_channel, the array's four otherwise. */
sasnav_channel_size sasnav_array_channel_size(const sasnav_array *array, int l);

/* Gives the array's n_rx channels sizes of their own (per_channel = 1) and
 * sets the array-wide values to the channels' largest lengths and mean
 * heights. Checks them as sasnav_array_check does (SASNAV_ERR_ARG, naming
 * the channel; the array is unchanged then). sizes NULL: back to one size
 * (the array-wide values kept). */
int sasnav_array_set_sizes(sasnav_array *array, const sasnav_channel_size *sizes);

/* The array of channels pick[0..n-1] of `array` (repeats allowed): their
 * rx_u and, with per_channel, their sizes (array-wide values recomputed as
 * sasnav_array_set_sizes does); the other fields copied. Errors
 * (SASNAV_ERR_ARG): n outside 1..SASNAV_MAX_RX, a pick outside the array. */
int sasnav_array_select(const sasnav_array *array, const int *pick, int n, sasnav_array *out);

/* The smallest nonzero receiver aperture over the channels (0: all
 * omnidirectional): what bounds the along-track resolution D/2. */
double sasnav_array_min_rx_length(const sasnav_array *array);

/* Fills a uniform array of n receivers spaced `spacing`, all of length
 * `length`, transmitter of length `tx_length`. Returns SASNAV_ERR_ARG for
 * n < 1, n > SASNAV_MAX_RX, or non-finite / negative sizes. */
int sasnav_array_uniform(sasnav_array *array, int n, double spacing, double length,
                         double tx_length);

/* Validates an array description (finite values, 1 <= n_rx <= MAX; with
 * per_channel, every channel's sizes). */
int sasnav_array_check(const sasnav_array *array);

/* The true (or modelled) geometry of one ping: the transmitter pose at
 * transmission and the array (midpoint) pose at reception. */
typedef struct {
    sasnav_pose tx;
    sasnav_pose array;
} sasnav_ping_pose;

/* PCA centroid of a ping: ((x_a + x_t)/2, (y_a + y_t)/2, theta_array)
 * (SPEC 1; the paper's (y_a + x_t)/2 is a typo). */
sasnav_pose sasnav_ping_centroid(const sasnav_ping_pose *ping);

/* Displacement of ping q relative to ping p: pose of q's centroid in p's
 * centroid frame, (surge, sway, yaw). */
sasnav_pose sasnav_ping_displacement(const sasnav_ping_pose *p, const sasnav_ping_pose *q);

/* The ping's sensors expressed in its own centroid frame (paper sigma_r0,
 * sigma_t0, rotated into the centroid frame). */
sasnav_ping_pose sasnav_ping_local(const sasnav_ping_pose *ping);

/* Places a local (centroid-frame) ping geometry at a centroid pose:
 * world = centroid * local, for both tx and array. */
sasnav_ping_pose sasnav_ping_place(sasnav_pose centroid, const sasnav_ping_pose *local);

/* Channels with poses of their own (docs/model.md, "Channel layouts";
 * stored in a run file as /channels, docs/format.md): offset[l] places
 * channel l relative to its ping, out[l].tx = ping.tx * offset[l].tx (the
 * channel's transmitter in the ping's transmitter frame) and out[l].array
 * = ping.array * offset[l].array (the array frame in which receiver l sits
 * at rx_u[l]). An offset of zeros is the one-Tx ping: a head with several
 * transmitters, receivers off the array axis or rotated staves are the
 * others. `out` has n entries (sasnav_op_set_channels' input). */
void sasnav_channel_poses(const sasnav_ping_pose *ping, const sasnav_ping_pose *offset, int n,
                          sasnav_ping_pose *out);

/* Largest distance of a channel's transmitter or array origin from its
 * ping's (the margin that reach tests add for offset channels); 0 for
 * offset NULL. */
double sasnav_channel_offset_radius(const sasnav_ping_pose *offset, int n);

/* EPCA replacement geometry (paper eq. epcar/epcat, SPEC 3) in the centroid
 * frame: the array midpoint ahead of the transmitter by `tx_lag` metres along
 * the array axis (the distance the vehicle covers while the pulse travels to
 * the range of interest and back), sharing the centroid: array at (+lag/2, 0,
 * 0), Tx at (-lag/2, 0, dtheta_tx). */
sasnav_ping_pose sasnav_epca_local(double tx_lag, double dtheta_tx);

/* Tx-array offset caused by vehicle motion: speed * 2 R / c (metres). */
double sasnav_motion_tx_lag(double speed, double range, double sound_speed);

#ifdef __cplusplus
}
#endif
#endif
