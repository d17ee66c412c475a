/* sasnav -- the ping operator T and its adjoint T^H (paper eq. acop, SPEC 2).
 *
 * T maps a complex reflectivity sampled at P points z_n (a rectangular grid or
 * any list of scatterers) to the baseband, pulse-compressed samples of all N
 * channels of one ping over a window:
 *
 *   phi_l(t_m) = sum_n p(t_m - tau_ln) G_ln rho_n,
 *   G_ln = alpha_ln exp(-j 2 pi f0 tau_ln),
 *   tau_ln = (|z_n - z_t| + |z_n - z_rl|) / c      (3-D distances: heights),
 *   alpha_ln = Tx pattern * Rx pattern * attenuation,
 *
 * with channel l's heights and apertures (the array's, or its own with
 * sasnav_array.per_channel: geometry.h).
 *
 * Time interpolation is a type-1/type-2 NUFFT: spread each point's
 * contribution with an "exponential of semicircle" kernel onto an oversampled
 * periodic grid, FFT, apply pulse spectrum / kernel transform, inverse FFT on
 * the coarse grid. The adjoint is the exact reverse. Delays outside the
 * operator's periodic grid are dropped (for T and T^H alike, so adjointness is
 * kept) and counted.
 *
 * Lifecycle (FINUFFT style): sasnav_op_default_opts -> sasnav_op_create
 * (points, FFTW plans: once) -> sasnav_op_set_geometry (per ping pose; may be
 * called many times) -> sasnav_op_forward / sasnav_op_adjoint (many times)
 * -> sasnav_op_destroy.
 *
 * Grids: the coarse periodic grid has Mp >= n_samples + 2 pad samples at
 * 1/fs starting pad samples before the window (Mp even, with factors 2, 3, 5,
 * 7 only), so T uses the band-limited pulse of period Mp / fs
 * (sasnav_op_period, sasnav_pulse_direct). A pair (n, l) is kept when its
 * delay lies at least half a kernel inside that period; otherwise it is
 * dropped (sasnav_op_n_dropped). The fine grid has Lf >= oversampling * Mp
 * samples over the same period.
 *
 * Accuracy: the relative error of T rho and T^H data against the direct sums
 * is about tolerance / 5 (measured, test_nufft), down to a float floor of
 * ~3e-7. G and the kernel taps are stored in float; delays and phases are
 * computed in double.
 *
 * Threads: distinct operators may be used concurrently from different
 * threads; one operator (it owns work buffers) by one thread at a time.
 * set_geometry, forward and adjoint use OpenMP with opts.nthreads threads,
 * 0 = omp_get_max_threads() of the creating thread at create (OMP_NUM_THREADS
 * or omp_set_num_threads); results do not depend on the count (fixed-order
 * sums). Called inside an OpenMP parallel region, the inner regions get one
 * thread unless nesting is enabled. FFTW plans are made and destroyed only in
 * create/destroy, see "FFTW" below.
 *
 * FFTW: the planner is not thread-safe. sasnav plans and destroys plans
 * (operators, estimators, ingest plans, each sasnav_dpca_estimate) only
 * inside `#pragma omp critical(sasnav_fftw_planner)`, serialising its own
 * planning across threads. In the shared library that lock is private
 * (cmake/sasnav.map exports sasnav_* only): an application's section of the
 * same name is another lock. So an application that plans FFTW while sasnav
 * may must call fftwf_make_planner_thread_safe() (FFTW >= 3.3.5) first, or
 * not plan concurrently with those sasnav calls.
 *
 * Memory: about (4 + 4 * ceil4(w) + 8) bytes per (point, channel) pair, e.g.
 * 44 bytes for w = 7 (the default tolerance 1e-6).
 */
#ifndef SASNAV_OP_H
#define SASNAV_OP_H

#include "sasnav/geometry.h"
#include "sasnav/model.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    double tolerance;   /* requested relative accuracy of the time interpolation
                           (1e-2 .. 1e-9, default 1e-6; accepted: [1e-12, 1)) */
    double oversampling;/* fine-grid oversampling factor sigma (default 2.0;
                           accepted: [1.25, 8]) */
    int pad_samples;    /* extra periodic samples beyond the window at both ends
                           (default: -1 = automatic, about 10% + 16) */
    int nthreads;       /* OpenMP threads (0 = OpenMP default) */
} sasnav_op_opts;

typedef struct sasnav_op sasnav_op;

void sasnav_op_default_opts(sasnav_op_opts *opts);

/* Creates an operator for `n_points` points at (x[n], y[n]) (metres, scene
 * plane z = 0; arrays copied). Makes the FFTW plans. `opts` may be NULL.
 * Errors: SASNAV_ERR_ARG (bad sizes, non-finite input), SASNAV_ERR_NOMEM,
 * SASNAV_ERR_FFT. */
int sasnav_op_create(const sasnav_system *sys, const sasnav_array *array,
                     const sasnav_window *win, int n_points, const double *x,
                     const double *y, const sasnav_op_opts *opts, sasnav_op **op);

/* Replaces the operator's points (as at create; arrays copied), keeping its
 * plans and tables: for callers that evaluate many small point sets (fast
 * factorised backprojection). Storage grows when needed. The geometry must
 * be set again. */
int sasnav_op_set_points(sasnav_op *op, int n_points, const double *x, const double *y);

/* Sets the ping geometry (tx pose at transmission, array pose at reception):
 * computes delays (double precision), Green's functions and kernel weights.
 * Returns SASNAV_ERR_GEOMETRY if a point coincides with a sensor. */
int sasnav_op_set_geometry(sasnav_op *op, const sasnav_ping_pose *ping);

/* Channels as Tx-Rx pairs (docs/model.md, "Channel layouts"): channel l is
 * receiver l of the array (rx_u[l] along the axis of channels[l].array)
 * with its own transmitter channels[l].tx; n_rx entries. Lengths and
 * heights are channel l's (sasnav_array_channel_size). Every channel with the same pose gives exactly
 * set_geometry's result (the one-Tx, N-Rx ping); a virtual array made of K
 * pings of a SISO or SIMO sonar is K groups of channels, each group with
 * its ping's poses (sasnav_virtual_ping, virtual.h). Consecutive channels
 * that share a Tx pose share its range computation. Errors as
 * set_geometry, naming the channel. */
int sasnav_op_set_channels(sasnav_op *op, const sasnav_ping_pose *channels);

/* A ping of a run whose channels may be offset (sasnav_run.channel_offset,
 * n_rx entries, or NULL): set_channels with the channels' poses
 * (sasnav_channel_poses) when `offset` is not NULL, set_geometry (the same
 * bits as before) when it is. */
int sasnav_op_set_ping(sasnav_op *op, const sasnav_ping_pose *ping, const sasnav_ping_pose *offset);

/* data[l * n_samples + m] = (T rho)_l(t_m). data has n_rx * n_samples entries,
 * rho has n_points entries. */
int sasnav_op_forward(sasnav_op *op, const sasnav_cfloat *rho, sasnav_cfloat *data);

/* rho[n] = (T^H data)[n]. */
int sasnav_op_adjoint(sasnav_op *op, const sasnav_cfloat *data, sasnav_cfloat *rho);

/* Adjoint accumulated into rho (rho += T^H data), for backprojection sums. */
int sasnav_op_adjoint_add(sasnav_op *op, const sasnav_cfloat *data, sasnav_cfloat *rho);

int sasnav_op_n_points(const sasnav_op *op);
int sasnav_op_n_rx(const sasnav_op *op);
int sasnav_op_n_samples(const sasnav_op *op);
/* Periodic extent of the internal grid, seconds (for sasnav_pulse_direct). */
double sasnav_op_period(const sasnav_op *op);
/* Number of (point, channel) pairs whose delay fell outside the periodic grid
 * at the last set_geometry (they contribute nothing). */
long sasnav_op_n_dropped(const sasnav_op *op);
/* The bistatic delays (s) a pair may have and be kept: a point whose delay
 * to every channel lies outside [*first, *last] contributes nothing (to T,
 * nor through T^H). Depends on the window and options only. */
void sasnav_op_delay_span(const sasnav_op *op, double *first, double *last);
/* Kernel width (taps) chosen for the requested tolerance. */
int sasnav_op_kernel_width(const sasnav_op *op);

/* Safe on NULL. */
void sasnav_op_destroy(sasnav_op *op);

#ifdef __cplusplus
}
#endif
#endif
