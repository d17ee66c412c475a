/* The "exponential of semicircle" NUFFT kernel and its Fourier transform
 * (see kernel.h for the reference).
 *
 * Choice of width and shape (Barnett, Magland & af Klinteberg 2019, Sec. 4):
 * spreading onto a fine grid oversampled by sigma and deconvolving leaves an
 * aliasing error set by how much of the kernel's transform lies beyond the
 * first alias of the band. For the ES kernel with
 *     beta = gamma pi w (1 - 1/(2 sigma)),   gamma ~ 0.98,
 * (which puts the transform's cut-off just at that alias), the error decays
 * like exp(-pi w sqrt(1 - 1/sigma)): at sigma = 2, 10^(-0.96 w) per tap, and
 * the paper's rule w = ceil(log10(1/tol)) + 1, beta = 2.30 w meets the
 * tolerance (the +1 absorbs the constant in front of the exponential).
 * For another sigma the decimal digits per tap scale with sqrt(1 - 1/sigma),
 * so we use
 *     w = ceil(log10(1/tol) * sqrt(1/2) / sqrt(1 - 1/sigma)) + 1,
 *     beta = 0.98 pi w (1 - 1/(2 sigma))          (= 2.309 w at sigma = 2),
 * which reduces to the paper's rule at sigma = 2. w is clamped to 2..16.
 * In the operators the pulse occupies only |f| <= B/2 of the coarse band
 * |f| < fs/2, so the effective oversampling is sigma fs / B (4 for the paper
 * pair) and the rule is conservative; test_nufft checks the achieved error
 * against the request over a sweep of tolerances. */
#include "signal/kernel.h"
#include "sasnav/error.h"

#include <stdlib.h>

int sasnav_kernel_choose(double tolerance, double oversampling, sasnav_kernel *kernel)
{
    if (!kernel) return sasnav_set_error(SASNAV_ERR_ARG, "kernel output is NULL");
    if (!isfinite(tolerance) || !(tolerance > 0.0) || !(tolerance < 1.0))
        return sasnav_set_error(SASNAV_ERR_ARG, "kernel tolerance must be in (0, 1), got %g",
                                tolerance);
    if (!isfinite(oversampling) || !(oversampling > 1.0))
        return sasnav_set_error(SASNAV_ERR_ARG, "kernel oversampling must be > 1, got %g",
                                oversampling);
    double digits_per_tap = sqrt(1.0 - 1.0 / oversampling) / sqrt(0.5);
    double w = ceil(log10(1.0 / tolerance) / digits_per_tap - 1e-9) + 1.0;
    if (w < SASNAV_KERNEL_MIN_WIDTH) w = SASNAV_KERNEL_MIN_WIDTH;
    if (w > SASNAV_KERNEL_MAX_WIDTH) w = SASNAV_KERNEL_MAX_WIDTH;
    kernel->width = (int)w;
    kernel->beta = 0.98 * M_PI * w * (1.0 - 0.5 / oversampling);
    return SASNAV_OK;
}

double sasnav_kernel_eval(const sasnav_kernel *kernel, double z)
{
    if (!(fabs(z) <= 1.0)) return 0.0;
    return exp(kernel->beta * (sqrt(1.0 - z * z) - 1.0));
}

/* Legendre P_n(x) and P_{n-1}(x) by (k+1) P_{k+1} = (2k+1) x P_k - k P_{k-1}. */
static void legendre_pair(int n, double x, double *pn, double *pn1)
{
    double p0 = 1.0, p1 = x;
    if (n == 0) {
        *pn = 1.0;
        *pn1 = 0.0;
        return;
    }
    for (int k = 1; k < n; k++) {
        double p2 = ((2.0 * k + 1.0) * x * p1 - k * p0) / (k + 1.0);
        p0 = p1;
        p1 = p2;
    }
    *pn = p1;
    *pn1 = p0;
}

int sasnav_gauss_legendre(int n, double *nodes, double *weights)
{
    if (n < 1 || !nodes || !weights)
        return sasnav_set_error(SASNAV_ERR_ARG, "Gauss-Legendre: need n >= 1 and outputs");
    for (int i = 0; i < (n + 1) / 2; i++) {
        /* Tricomi's initial guess for the i-th largest root. */
        double x = cos(M_PI * (i + 0.75) / (n + 0.5));
        double dp = 1.0;
        int converged = 0;
        for (int it = 0; it < 100; it++) {
            double pn, pn1;
            legendre_pair(n, x, &pn, &pn1);
            /* P_n'(x) = n (x P_n - P_{n-1}) / (x^2 - 1) */
            dp = n * (x * pn - pn1) / (x * x - 1.0);
            double dx = pn / dp;
            x -= dx;
            if (fabs(dx) <= 1e-15 * (1.0 + fabs(x))) {
                converged = 1;
                break;
            }
        }
        if (!converged)
            return sasnav_set_error(SASNAV_ERR_NOT_CONVERGED,
                                    "Gauss-Legendre: Newton iteration failed for node %d of %d",
                                    i, n);
        double pn, pn1;
        legendre_pair(n, x, &pn, &pn1);
        dp = n * (x * pn - pn1) / (x * x - 1.0);
        double w = 2.0 / ((1.0 - x * x) * dp * dp);
        nodes[n - 1 - i] = x;
        nodes[i] = -x;
        weights[n - 1 - i] = w;
        weights[i] = w;
    }
    if (n % 2) nodes[n / 2] = 0.0; /* exact centre for odd n */
    return SASNAV_OK;
}

/* phi has square-root behaviour at z = +-1 (sqrt(1 - z^2)), which would slow
 * Gauss-Legendre down to algebraic convergence. The substitution z = sin(a)
 * removes it:
 *   F(xi) = int_{-pi/2}^{pi/2} exp(beta (cos a - 1)) cos(xi sin a) cos a da,
 * an entire function of a, for which Gauss-Legendre converges exponentially:
 * 200 nodes (the default) give ~1e-15 relative for every width 2..16 and
 * |xi| <= pi w (test_nufft compares 200 and 400 nodes). */
int sasnav_kernel_transform(const sasnav_kernel *kernel, int n_quad, int n_freq, const double *xi,
                            double *ft)
{
    if (!kernel || n_freq < 0 || (n_freq > 0 && (!xi || !ft)))
        return sasnav_set_error(SASNAV_ERR_ARG, "kernel transform: bad arguments");
    if (n_quad <= 0) n_quad = 200;
    double *z = malloc(2 * (size_t)n_quad * sizeof *z);
    if (!z) return sasnav_set_error(SASNAV_ERR_NOMEM, "kernel transform: out of memory");
    double *wq = z + n_quad;
    int rc = sasnav_gauss_legendre(n_quad, z, wq);
    if (rc) {
        free(z);
        return rc;
    }
    for (int q = 0; q < n_quad; q++) {
        double a = 0.5 * M_PI * z[q];
        z[q] = sin(a);
        wq[q] *= 0.5 * M_PI * cos(a) * exp(kernel->beta * (cos(a) - 1.0));
    }
    for (int i = 0; i < n_freq; i++) {
        double s = 0.0;
        for (int q = 0; q < n_quad; q++) s += wq[q] * cos(xi[i] * z[q]);
        ft[i] = s;
    }
    free(z);
    return SASNAV_OK;
}

int sasnav_kernel_taps_degree(const sasnav_kernel *kernel)
{
    /* Measured max interpolation error at degree w + 2: ~tol/20 for the
     * tolerance the width was chosen for (7e-3 at w = 2 ... 5e-8 at w = 7,
     * below float rounding from w = 8); more degrees gain little because the
     * error comes from the square-root edge of phi, of size exp(-beta). */
    int p = kernel->width + 2;
    return p > SASNAV_KERNEL_MAX_DEGREE ? SASNAV_KERNEL_MAX_DEGREE : p;
}

/* Chebyshev interpolation of each tap at the points t_m = cos(pi (m + 1/2) /
 * (p + 1)), then conversion of the Chebyshev series to monomials in t (the
 * Chebyshev coefficients of the smooth taps decay fast, so the conversion
 * loses nothing that matters in float). */
int sasnav_kernel_fit_taps(const sasnav_kernel *kernel, int degree, int stride, double *coef)
{
    if (!kernel || !coef || degree < 0 || degree > SASNAV_KERNEL_MAX_DEGREE ||
        stride < kernel->width)
        return sasnav_set_error(SASNAV_ERR_ARG, "kernel fit: bad arguments");
    int n = degree + 1, w = kernel->width;
    double cheb[SASNAV_KERNEL_MAX_DEGREE + 1];
    /* T_k as monomials: tk[k][i] = coefficient of t^i in T_k. */
    double tk[SASNAV_KERNEL_MAX_DEGREE + 1][SASNAV_KERNEL_MAX_DEGREE + 1] = {{0}};
    tk[0][0] = 1.0;
    if (n > 1) tk[1][1] = 1.0;
    for (int k = 2; k < n; k++)
        for (int i = 0; i <= k; i++)
            tk[k][i] = (i > 0 ? 2.0 * tk[k - 1][i - 1] : 0.0) - tk[k - 2][i];
    for (int i = 0; i < n * stride; i++) coef[i] = 0.0;
    for (int j = 0; j < w; j++) {
        for (int k = 0; k < n; k++) {
            double s = 0.0;
            for (int m = 0; m < n; m++) {
                double a = M_PI * (m + 0.5) / n, t = cos(a);
                double z = -1.0 + (2.0 / w) * (j + 0.5 * (t + 1.0));
                s += sasnav_kernel_eval(kernel, z) * cos(k * a);
            }
            cheb[k] = (k ? 2.0 : 1.0) * s / n;
        }
        for (int k = 0; k < n; k++)
            for (int i = 0; i <= k; i++) coef[i * stride + j] += cheb[k] * tk[k][i];
    }
    return SASNAV_OK;
}
