/* Joint resolution and fusion of the consecutive pairs of a run
 * (sasnav_navigate; docs/navigation.md, "Resolution over the run").
 * Internal to the library. All poses are motion errors (displacement minus
 * nominal displacement: surge, sway, yaw) of the consecutive pairs
 * j = 0..n-1 (pings j, j + 1). */
#ifndef SASNAV_TRAJECTORY_FUSE_H
#define SASNAV_TRAJECTORY_FUSE_H

#include "sasnav/navigate.h"

/* The aiding measurement of pair (p, q) with nominal displacement `nom`
 * as a motion error in *a, with its standard deviations in *sa (+inf for a
 * component without measurement: no gyro, no DVL, no aiding at all, or q
 * not p + 1). `est_yaw` is the pair's estimated yaw motion error, to
 * rotate DVL velocities with when there is no gyro. */
void fuse_aiding_error(const sasnav_run *run, int p, int q, sasnav_pose nom, double est_yaw,
                       sasnav_pose *a, sasnav_pose *sa);

/* One option of a pair in the joint choice. */
typedef struct {
    sasnav_pose e;  /* motion error */
    double eta;     /* level-1 eta (the data's cost) */
    int candidate;  /* index in the pair's candidates[] */
} fuse_option;

/* Viterbi choice of one option per pair: minimises
 *   sum_j [ w ln(eta / min eta_j) + 1/2 |(e - a_j) / sa_j|^2 ]
 *   + sum_j 1/2 |(e_{j+1} - e_j) / motion|^2.
 * opts[j][0..nopt[j]-1]; writes choice[j]. Returns SASNAV_ERR_NOMEM or OK. */
int fuse_choose(int n, fuse_option *const *opts, const int *nopt, const sasnav_pose *a,
                const sasnav_pose *sa, sasnav_pose motion, double eta_weight, int *choice);

/* Robust smoother per component (iteratively reweighted least squares,
 * Huber weights on the estimates' residuals):
 *   min sum_j rho((e_j - m_j) / sm_j) + |(e_j - a_j) / sa_j|^2
 *       + |(e_{j+1} - e_j) / motion|^2,
 * a tridiagonal system per component. m, sm: the estimates and their
 * standard deviations (+inf: no estimate). Writes e. Returns
 * SASNAV_ERR_NOMEM, SASNAV_ERR_GEOMETRY (a component observed by nothing:
 * cannot happen with a finite motion sigma and n >= 1 finite term) or OK. */
int fuse_smooth(int n, const sasnav_pose *m, const sasnav_pose *sm, const sasnav_pose *a,
                const sasnav_pose *sa, sasnav_pose motion, double huber, sasnav_pose *e);

/* The same with a constant error of the aiding estimated jointly (a_j = e_j
 * + b + noise; a DVL's bias and scale factor at a steady speed, a gyro's
 * bias), b with standard deviation bias_sigma per component (0: not
 * estimated, as fuse_smooth). Writes the estimate of b to *b (may be NULL). */
int fuse_smooth_bias(int n, const sasnav_pose *m, const sasnav_pose *sm, const sasnav_pose *a,
                     const sasnav_pose *sa, sasnav_pose motion, double huber, sasnav_pose bias_sigma,
                     sasnav_pose *e, sasnav_pose *b);

/* What the smoother's last system was, per component k (0 surge, 1 sway,
 * 2 yaw), for its posterior covariance: the system T e = r (tridiagonal,
 * Huber weights at their last values) factored T = L D L^T, L unit lower
 * bidiagonal with L[i][i-1] = off[k][i-1] / d[k][i-1]; with a bias term
 * also yu[k] = T^-1 u (u: the aiding's weights) and the Schur complement's
 * denominator denom[k] = beta - u^T T^-1 u (0: no bias term). The
 * posterior covariance of e (the bias marginalised) is then T^-1 + yu
 * yu^T / denom (Sherman-Morrison). Arrays of n doubles each, the caller's
 * (yu[k] may be NULL: the bias term is then left out, denom[k] = 0). The
 * Huber weights are those of the last solve (the loop's change test
 * passed, or its five passes spent). */
typedef struct {
    double *d[3];
    double *off[3];
    double *yu[3];
    double denom[3];
} fuse_posterior;

/* fuse_smooth_bias that also writes the last system into *post (may be
 * NULL: the same as fuse_smooth_bias). */
int fuse_smooth_post(int n, const sasnav_pose *m, const sasnav_pose *sm, const sasnav_pose *a,
                     const sasnav_pose *sa, sasnav_pose motion, double huber, sasnav_pose bias_sigma,
                     sasnav_pose *e, sasnav_pose *b, fuse_posterior *post);

/* Standard deviations of the poses of pings 0..n (n + 1 poses: the
 * composition of the n smoothed steps) relative to ping 0, in the frame of
 * `poses` (the composed poses: x, y, heading), from the posterior of the
 * steps' motion errors in *post, linearised about `poses`: for each ping
 * the diagonal of the covariance sum_k J_k^T C_k J_k over the components k, C_k the
 * posterior covariance of component k of the steps (the components
 * independent, as in the smoother). O(n) for all pings (prefix sums of the
 * factored system). Writes sigma[0..n] (x, y, heading; sigma[0] = 0).
 * Returns SASNAV_OK, SASNAV_ERR_ARG or SASNAV_ERR_NOMEM. */
int fuse_pose_sigma(int n, const fuse_posterior *post, const sasnav_pose *poses, sasnav_pose *sigma);

#endif
