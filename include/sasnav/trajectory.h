/* sasnav -- trajectories from ping-pair displacements.
 *
 * A trajectory is the list of PCA centroid poses of the pings (SPEC 1): each
 * pair estimate gives the displacement of ping q's centroid in ping p's
 * centroid frame, an element of SE(2), and trajectories are compositions of
 * them (sasnav_pose_compose). This module
 *   - composes a chain of consecutive displacements into centroid poses and
 *     back (sasnav_traj_compose, sasnav_traj_displacements);
 *   - turns centroid poses into ping (Tx, array) poses with the EPCA
 *     geometry (sasnav_traj_ping_poses);
 *   - combines redundant estimates (consecutive pairs and longer baselines)
 *     by weighted nonlinear least squares over the centroid poses
 *     (Gauss-Newton on SE(2), banded Cholesky; sasnav_traj_solve);
 *   - aligns an estimated trajectory to the nominal track by the fitted
 *     track angle (sasnav_traj_align, as in paper Sec. V-D);
 *   - measures cumulative and differential errors against a true trajectory
 *     (sasnav_traj_errors).
 *
 * Threads: all functions are pure (no global state, no OpenMP, no FFTW):
 * safe to call concurrently; inputs may be shared read-only.
 */
#ifndef SASNAV_TRAJECTORY_H
#define SASNAV_TRAJECTORY_H

#include "sasnav/geometry.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Centroid poses from a chain: centroids[0] = first,
 * centroids[i + 1] = centroids[i] * displacements[i], i = 0..n - 2
 * (displacements[i] = pose of ping i + 1 in ping i's centroid frame).
 * Returns SASNAV_ERR_ARG for NULL arrays (displacements may be NULL when
 * n = 1), n < 1 or non-finite input. */
int sasnav_traj_compose(sasnav_pose first, const sasnav_pose *displacements, int n,
                        sasnav_pose *centroids);

/* Inverse of sasnav_traj_compose: displacements[i] = pose of centroids[i + 1]
 * in centroids[i]'s frame, i = 0..n - 2. Needs n >= 2. */
int sasnav_traj_displacements(const sasnav_pose *centroids, int n, sasnav_pose *displacements);

/* Ping poses with the EPCA geometry (paper eq. epcar/epcat): each ping is
 * sasnav_epca_local(tx_lag, dtheta_tx) placed at its centroid, so that
 * sasnav_ping_centroid(&pings[i]) == centroids[i]. */
int sasnav_traj_ping_poses(const sasnav_pose *centroids, int n, double tx_lag, double dtheta_tx,
                           sasnav_ping_pose *pings);

/* Centroid poses of ping poses (sasnav_ping_centroid of each). */
int sasnav_traj_centroids(const sasnav_ping_pose *pings, int n, sasnav_pose *centroids);

/* The rigid motion M (rotation + translation, returned as a pose) that
 * minimises sum_i |M a_i - b_i|^2 over the positions of the n poses (2-D
 * Procrustes, closed form; the identity's rotation when n < 2 or the
 * points coincide). */
sasnav_pose sasnav_traj_rigid_fit(const sasnav_pose *a, const sasnav_pose *b, int n);

/* Rms along-track (*surge_rms) and across-track (*sway_rms) error, m, of the
 * centroids of `nav` after the rigid motion that best fits them onto those
 * of `truth` (sasnav_traj_rigid_fit: a common move and turn of a whole
 * trajectory is not observable from pairs). SASNAV_ERR_ARG, _NOMEM. */
int sasnav_traj_rms_rigid(const sasnav_ping_pose *nav, const sasnav_ping_pose *truth, int n,
                          double *surge_rms, double *sway_rms);

/* One relative measurement: the displacement of ping q's centroid in ping
 * p's centroid frame, with the standard deviations of its surge, sway and
 * yaw (all > 0; the residuals are divided by them). */
typedef struct {
    int p, q;
    sasnav_pose displacement;
    sasnav_pose sigma;
} sasnav_traj_link;

typedef struct {
    int max_iterations; /* Gauss-Newton iterations (default 20) */
    double tolerance;   /* stop when the largest update is below this (metres
                           and radians, default 1e-10) */
} sasnav_traj_solve_opts;

void sasnav_traj_solve_default_opts(sasnav_traj_solve_opts *opts);

/* Least-squares centroid poses from redundant links. Ping 0 is held at
 * `first` (the gauge); the other n - 1 poses minimise
 *   sum_links || W (between(X_p, X_q) - z) ||^2
 * with the residual taken as (R(-theta_p)(t_q - t_p) - z_t, wrap(theta_q -
 * theta_p - z_theta)), W = diag(1 / sigma). Start: every ping q placed by
 * its first-listed link from an earlier ping (so every ping q >= 1 needs a
 * link (p, q) or (q, p) with the other ping < q); then Gauss-Newton with the
 * normal equations solved by a banded Cholesky factorisation (band from the
 * longest baseline |q - p|). With only the consecutive links the result is
 * the composed chain. `opts` may be NULL; `iterations` may be NULL.
 * Returns SASNAV_ERR_ARG (bad sizes, indices, sigmas, a ping not reached),
 * SASNAV_ERR_NOMEM, SASNAV_ERR_GEOMETRY (singular normal equations),
 * SASNAV_ERR_NOT_CONVERGED (iterations exhausted; the poses hold the last
 * iterate). */
int sasnav_traj_solve(int n, sasnav_pose first, const sasnav_traj_link *links, int n_links,
                      const sasnav_traj_solve_opts *opts, sasnav_pose *centroids,
                      int *iterations);

/* Track angle: direction of the principal axis (total least-squares line)
 * of the centroid positions, oriented from the first towards the last
 * centroid, in (-pi, pi]. Needs n >= 2 and distinct positions. */
int sasnav_traj_track_angle(const sasnav_pose *centroids, int n, double *angle);

/* Aligns a trajectory to the nominal track: fits the track angle, then
 * rotates every pose rigidly by minus that angle about the first centroid
 * (positions rotate, every yaw decreases by the angle; nothing else is
 * added). On return the fitted track angle of `centroids` is 0. `angle`
 * (may be NULL) receives the removed angle. */
int sasnav_traj_align(sasnav_pose *centroids, int n, double *angle);

/* Errors of an estimated trajectory against the true one, both given as
 * centroid poses, expressed in the nominal track frame (x along the track at
 * `track_angle` from +x; 0 for the simulator's track):
 *   cumulative[i] = (R(-track_angle)(t_est,i - t_true,i), wrap(theta_est,i -
 *                    theta_true,i)): surge, sway, yaw of ping i;
 *   differential[i] = between(est[i-1], est[i]) - between(true[i-1],
 *                    true[i]) component-wise (the error of the displacement
 *                    estimate of ping i relative to ping i - 1, in ping
 *                    i - 1's own frame), differential[0] = 0.
 * Either output may be NULL. */
int sasnav_traj_errors(const sasnav_pose *estimated, const sasnav_pose *truth, int n,
                       double track_angle, sasnav_pose *cumulative, sasnav_pose *differential);

#ifdef __cplusplus
}
#endif
#endif
