/* sasnav (private) -- the NUFFT spreading kernel and the pulse band.
 *
 * "Exponential of semicircle" (ES) kernel of Barnett, Magland & af Klinteberg,
 * "A parallel non-uniform fast Fourier transform library based on an
 * 'exponential of semicircle' kernel", SIAM J. Sci. Comput. 41 (2019):
 *
 *   phi(z) = exp(beta (sqrt(1 - z^2) - 1)),   |z| <= 1,   0 outside,
 *
 * normalised so that phi(0) = 1. Its Fourier transform has no closed form; it
 * is computed numerically (Gauss-Legendre quadrature) once per operator and
 * divided out ("deconvolution").
 *
 * All functions are pure and thread-safe.
 */
#ifndef SASNAV_SIGNAL_KERNEL_H
#define SASNAV_SIGNAL_KERNEL_H

#include <math.h>

#include "sasnav/model.h"

#define SASNAV_KERNEL_MIN_WIDTH 2
#define SASNAV_KERNEL_MAX_WIDTH 16

typedef struct {
    int width;    /* w: number of grid samples the kernel covers (taps) */
    double beta;  /* shape parameter */
} sasnav_kernel;

/* Chooses w and beta for a requested relative accuracy `tolerance` (> 0) on a
 * fine grid oversampled by `oversampling` (> 1) with respect to the coarse
 * grid. See kernel.c for the derivation. Returns SASNAV_ERR_ARG on bad input. */
int sasnav_kernel_choose(double tolerance, double oversampling, sasnav_kernel *kernel);

/* phi(z) (0 for |z| > 1). */
double sasnav_kernel_eval(const sasnav_kernel *kernel, double z);

/* Fourier transform of phi on [-1, 1] at angular frequencies xi[i]:
 *   F(xi) = int_{-1}^{1} phi(z) exp(-j xi z) dz = int phi(z) cos(xi z) dz
 * (phi is even, so F is real), by `n_quad`-point Gauss-Legendre quadrature
 * (n_quad <= 0: a default that is converged to ~1e-14 for the widths used).
 * Returns SASNAV_ERR_NOMEM or SASNAV_ERR_ARG. */
int sasnav_kernel_transform(const sasnav_kernel *kernel, int n_quad, int n_freq, const double *xi,
                            double *ft);

/* Polynomial form of the kernel taps (as FINUFFT evaluates its kernel): a
 * kernel centred at fine-grid coordinate u covers the samples i0 + j,
 * j = 0..w-1, i0 = ceil(u - w/2); with d = i0 - (u - w/2) in [0, 1) and
 * t = 2 d - 1 in [-1, 1), tap j is
 *     phi(-1 + (2/w) (j + d)) ~= sum_{k=0}^{degree} coef[k * stride + j] t^k.
 * The polynomials interpolate phi at degree + 1 Chebyshev points (monomial
 * coefficients in t, for Horner evaluation); lanes w..stride-1 are zero.
 * `coef` holds (degree + 1) * stride doubles. Returns SASNAV_ERR_ARG on bad
 * input. */
#define SASNAV_KERNEL_MAX_DEGREE 24
int sasnav_kernel_fit_taps(const sasnav_kernel *kernel, int degree, int stride, double *coef);

/* Degree used by the operators for a kernel: interpolation error well below
 * the tolerance the width was chosen for (test_nufft checks it). */
int sasnav_kernel_taps_degree(const sasnav_kernel *kernel);

/* Gauss-Legendre nodes and weights on [-1, 1] (n >= 1): Newton iteration on
 * the Legendre polynomial P_n (three-term recurrence). Nodes ascending.
 * Returns SASNAV_ERR_ARG for n < 1 or NULL, SASNAV_ERR_NOT_CONVERGED if a
 * Newton iteration fails (does not happen for n <= 10^4). */
int sasnav_gauss_legendre(int n, double *nodes, double *weights);

/* The discrete pulse band of a periodic grid of extent `period` seconds: the
 * largest K such that every f_k = k / period, |k| <= K, satisfies
 * |f_k| <= B/2 and |f_k| < fs/2 (the coarse grid's Nyquist frequency is
 * excluded, so the band is symmetric). Used by sasnav_pulse_direct and by the
 * operators so that both use exactly the same frequencies. -1 on bad input. */
static inline int sasnav_band_kmax(const sasnav_system *sys, double period)
{
    if (!(period > 0.0) || !(sys->bandwidth > 0.0) || !(sys->sample_rate > 0.0)) return -1;
    double k_band = floor(0.5 * sys->bandwidth * period + 1e-9);
    double k_nyq = ceil(0.5 * sys->sample_rate * period - 1e-9) - 1.0;
    double k = k_band < k_nyq ? k_band : k_nyq;
    if (!(k >= 0.0) || k > 1e8) return -1;
    return (int)k;
}

#endif
