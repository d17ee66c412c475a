/* Accuracy of the NUFFT-based ping operator against slow direct sums
 * (FINUFFT-style: tolerance sweep against a direct reference), plus the pulse,
 * window, quadrature and kernel helpers it relies on.
 *
 * The reference of the forward operator is
 *     d_l[m] = sum_n alpha_ln exp(-j 2 pi f0 tau_ln) rho_n p(t_m - tau_ln),
 * with p = sasnav_pulse_direct (period = sasnav_op_period) and the delays,
 * beam patterns and attenuation computed here, in double precision, from the
 * formulas of SPEC 2 (not from the operator's code). */
#include "sasnav/error.h"
#include "sasnav/geometry.h"
#include "sasnav/model.h"
#include "sasnav/op.h"
#include "signal/kernel.h"
#include "testutil.h"

#include <complex.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>

/* Deterministic generator (splitmix64) so the test is reproducible. */
static uint64_t rng_state = 0x9E3779B97F4A7C15ull;
static double uniform(void)
{
    uint64_t z = (rng_state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return (z >> 11) * (1.0 / 9007199254740992.0);
}
static double gauss(void)
{
    double u = uniform(), v = uniform();
    return sqrt(-2.0 * log(u + 1e-300)) * cos(2.0 * M_PI * v);
}

/* Float rounding floor of the operator: G, taps, grids and FFTs are float
 * (relative rounding 6e-8 per operation; the FFTs of ~300 points add about
 * log2(300) ~ 8 roundings, the spreading sums ~10 overlapping terms). The
 * measured floor is 2-3e-7 (tolerance 1e-7, 1e-8 below); requests below
 * FLOOR are checked against FLOOR. */
#define FLOOR 1e-6

/* ------------------------------------------------------------------------ */

static void test_system_and_window(void)
{
    sasnav_system sys;
    sasnav_system_default(&sys);
    CHECK(sys.sound_speed == 1500.0 && sys.f0 == 300e3 && sys.bandwidth == 30e3 &&
              sys.sample_rate == 60e3 && sys.taper == SASNAV_TAPER_NONE &&
              sys.attenuation == SASNAV_ATTEN_EXPLODING && sys.beam_pattern == 1,
          "default system is the paper pair");
    CHECK_OK(sasnav_system_check(&sys));
    CHECK(fabs(sasnav_wavelength(&sys) - 0.005) < 1e-15, "lambda = 5 mm");

    sasnav_system bad = sys;
    bad.sound_speed = NAN;
    CHECK(sasnav_system_check(&bad) == SASNAV_ERR_ARG, "NaN sound speed rejected");
    bad = sys;
    bad.sample_rate = 20e3;
    CHECK(sasnav_system_check(&bad) == SASNAV_ERR_ARG, "fs < B rejected");
    bad = sys;
    bad.f0 = 10e3;
    CHECK(sasnav_system_check(&bad) == SASNAV_ERR_ARG, "f0 <= B/2 rejected");
    bad = sys;
    bad.taper = (sasnav_taper)7;
    CHECK(sasnav_system_check(&bad) == SASNAV_ERR_ARG, "unknown taper rejected");
    CHECK(sasnav_system_check(NULL) == SASNAV_ERR_ARG, "NULL system rejected");

    sasnav_window win;
    CHECK_OK(sasnav_window_for_ranges(&sys, 9.5, 10.5, 8, &win));
    double fs = sys.sample_rate, c = sys.sound_speed;
    double t_last = win.t0 + (win.n_samples - 1) / fs;
    /* t0 exactly 8 samples before 2 r_min / c; last sample within one sample
     * after 2 r_max / c + 8 samples. */
    CHECK(fabs(win.t0 - (2 * 9.5 / c - 8 / fs)) < 1e-15, "t0 = %.12g", win.t0);
    CHECK(t_last >= 2 * 10.5 / c + 8 / fs - 1e-12 && t_last < 2 * 10.5 / c + 9 / fs,
          "window end %.9g", t_last);
    CHECK(sasnav_window_for_ranges(&sys, 10.0, 9.0, 0, &win) == SASNAV_ERR_ARG,
          "range_max < range_min rejected");
    CHECK(sasnav_window_for_ranges(&sys, 1.0, 2.0, -1, &win) == SASNAV_ERR_ARG,
          "negative margin rejected");
}

static void test_pulse(void)
{
    sasnav_system sys;
    sasnav_system_default(&sys);
    double period = 300.0 / sys.sample_rate;
    CHECK(fabs(crealf(sasnav_pulse_direct(&sys, period, 0.0)) - 1.0f) < 1e-6, "p(0) = 1");
    /* Flat spectrum: p is the Dirichlet kernel sin(pi (2K+1) t / T) /
     * ((2K+1) sin(pi t / T)), K = floor(B T / 2) = 75 here. */
    int K = sasnav_band_kmax(&sys, period);
    CHECK(K == 75, "K = %d", K);
    for (int i = 1; i < 20; i++) {
        double t = i * 0.37e-4;
        double ref = sin(M_PI * (2 * K + 1) * t / period) / ((2 * K + 1) * sin(M_PI * t / period));
        float complex p = sasnav_pulse_direct(&sys, period, t);
        CHECK(fabs(crealf(p) - ref) < 1e-6 && cimagf(p) == 0.0f, "Dirichlet at t = %g: %g vs %g", t,
              crealf(p), ref);
    }
    /* Periodicity and symmetry. */
    float complex a = sasnav_pulse_direct(&sys, period, 1.1e-4);
    float complex b = sasnav_pulse_direct(&sys, period, 1.1e-4 + period);
    float complex c = sasnav_pulse_direct(&sys, period, -1.1e-4);
    CHECK(cabsf(a - b) < 1e-6 && cabsf(a - c) < 1e-6, "p periodic and even");
    /* Tapers: weights at band centre and edge, zero outside. */
    sys.taper = SASNAV_TAPER_HANN;
    CHECK(fabs(sasnav_pulse_weight(&sys, 0.0) - 1.0) < 1e-15 &&
              fabs(sasnav_pulse_weight(&sys, 15e3)) < 1e-15 &&
              fabs(sasnav_pulse_weight(&sys, 7.5e3) - 0.5) < 1e-15,
          "Hann weights");
    sys.taper = SASNAV_TAPER_HAMMING;
    CHECK(fabs(sasnav_pulse_weight(&sys, 15e3) - 0.08) < 1e-12, "Hamming edge 0.08");
    CHECK(sasnav_pulse_weight(&sys, 15.001e3) == 0.0, "weight 0 outside band");
    CHECK(fabs(crealf(sasnav_pulse_direct(&sys, period, 0.0)) - 1.0f) < 1e-6, "tapered p(0) = 1");
    /* The coarse Nyquist frequency is excluded when fs = B. */
    sys.sample_rate = sys.bandwidth;
    CHECK(sasnav_band_kmax(&sys, 100.0 / sys.sample_rate) == 49, "fs = B: K = Mp/2 - 1");
}

static void test_quadrature_and_kernel(void)
{
    /* n-point Gauss-Legendre integrates x^k exactly for k <= 2n - 1. */
    int n = 12;
    double x[400], w[400];
    CHECK_OK(sasnav_gauss_legendre(n, x, w));
    for (int k = 0; k <= 2 * n - 1; k++) {
        double s = 0.0;
        for (int i = 0; i < n; i++) s += w[i] * pow(x[i], k);
        double ref = k % 2 ? 0.0 : 2.0 / (k + 1);
        CHECK(fabs(s - ref) < 1e-14, "GL(12) x^%d: %.17g vs %.17g", k, s, ref);
    }
    for (int i = 1; i < n; i++) CHECK(x[i] > x[i - 1], "nodes ascending");
    /* Transform of the kernel converged: 200 (the default) vs 400 nodes, for
     * every width, at frequencies covering the operator's band (xi up to
     * pi w / 2). Agreement to 1e-12 relative to F(0) (double rounding of a
     * 200-term sum is ~1e-14). A plain 200-node rule in z (no substitution)
     * is only good to ~1e-7 at w = 2. */
    for (int wd = 2; wd <= 16; wd++) {
        sasnav_kernel k = {wd, 0.98 * M_PI * wd * 0.75};
        double xi[8], f1[8], f2[8];
        for (int i = 0; i < 8; i++) xi[i] = i * M_PI * wd / 14.0;
        CHECK_OK(sasnav_kernel_transform(&k, 0, 8, xi, f1));
        CHECK_OK(sasnav_kernel_transform(&k, 400, 8, xi, f2));
        for (int i = 0; i < 8; i++)
            CHECK(fabs(f1[i] - f2[i]) < 1e-12 * f2[0], "w %d xi %g: %g vs %g", wd, xi[i], f1[i],
                  f2[i]);
    }
    /* Polynomial taps (what the operator stores): for each width, the fit of
     * degree sasnav_kernel_taps_degree against phi itself over the whole
     * offset range. Bound: a tenth of the tolerance the width is chosen for
     * (10^-(w-1)), so the fit adds at most ~10 % to the NUFFT error; 1e-13
     * below that (double rounding of the monomial conversion; the operator
     * rounds the taps to float anyway). Measured: ~tol/20 up to w = 13. */
    for (int wd = 2; wd <= 16; wd++) {
        sasnav_kernel kw = {wd, 0.98 * M_PI * wd * 0.75};
        int p = sasnav_kernel_taps_degree(&kw);
        double coef[(SASNAV_KERNEL_MAX_DEGREE + 1) * 16];
        CHECK_OK(sasnav_kernel_fit_taps(&kw, p, 16, coef));
        double err = 0.0;
        for (int j = 0; j < 16; j++)
            for (int i = 0; i < 1000; i++) {
                double d = i / 1000.0, t = 2.0 * d - 1.0, v = 0.0;
                for (int q = p; q >= 0; q--) v = v * t + coef[q * 16 + j];
                double ref = j < wd ? sasnav_kernel_eval(&kw, -1.0 + (2.0 / wd) * (j + d)) : 0.0;
                err = fmax(err, fabs(v - ref));
            }
        double bound = fmax(0.1 * pow(10.0, -(wd - 1)), 1e-13);
        CHECK(err <= bound, "w %d: tap polynomial error %g > %g", wd, err, bound);
    }
    /* Width from the tolerance: the paper's rule at sigma = 2. */
    sasnav_kernel k;
    for (int d = 2; d <= 9; d++) {
        CHECK_OK(sasnav_kernel_choose(pow(10.0, -d), 2.0, &k));
        CHECK(k.width == d + 1 && fabs(k.beta - 2.309 * k.width) < 0.01 * k.width,
              "tol 1e-%d: w %d beta %g", d, k.width, k.beta);
    }
    CHECK_OK(sasnav_kernel_choose(1e-16, 2.0, &k));
    CHECK(k.width == 16, "w clamped to 16");
    CHECK(sasnav_kernel_choose(0.0, 2.0, &k) == SASNAV_ERR_ARG, "tol 0 rejected");
}

/* ------------------------------------------------------------------------ */

typedef struct {
    sasnav_system sys;
    sasnav_array array;
    sasnav_window win;
    sasnav_ping_pose ping;
    const sasnav_ping_pose *chan; /* per-channel poses (set_channels), or NULL */
    int np;
    double *x, *y;
    sasnav_cfloat *rho;
} scene;

static double line_pattern(double D, double lambda, double s)
{
    if (D <= 0.0) return 1.0;
    double u = M_PI * D * s / lambda;
    return u == 0.0 ? 1.0 : sin(u) / u;
}

/* Delay and Green's function of (channel l, point n), SPEC 2, double. */
static void green_ref(const scene *s, int l, int n, double *tau, double complex *g)
{
    const sasnav_array *a = &s->array;
    double lambda = s->sys.sound_speed / s->sys.f0;
    sasnav_pose tx = s->chan ? s->chan[l].tx : s->ping.tx;
    sasnav_pose ar = s->chan ? s->chan[l].array : s->ping.array;
    double xr = ar.x + a->rx_u[l] * cos(ar.theta), yr = ar.y + a->rx_u[l] * sin(ar.theta);
    double dtx[3] = {s->x[n] - tx.x, s->y[n] - tx.y, -a->tx_height};
    double drx[3] = {s->x[n] - xr, s->y[n] - yr, -a->rx_height};
    double rt = sqrt(dtx[0] * dtx[0] + dtx[1] * dtx[1] + dtx[2] * dtx[2]);
    double rr = sqrt(drx[0] * drx[0] + drx[1] * drx[1] + drx[2] * drx[2]);
    double alpha = 1.0;
    if (s->sys.beam_pattern) {
        alpha *= line_pattern(a->tx_length, lambda,
                              (dtx[0] * cos(tx.theta) + dtx[1] * sin(tx.theta)) / rt);
        alpha *= line_pattern(a->rx_length, lambda,
                              (drx[0] * cos(ar.theta) + drx[1] * sin(ar.theta)) / rr);
    }
    if (s->sys.attenuation == SASNAV_ATTEN_EXPLODING) alpha /= sqrt(rt + rr);
    if (s->sys.attenuation == SASNAV_ATTEN_SPHERICAL) alpha /= rt * rr;
    *tau = (rt + rr) / s->sys.sound_speed;
    *g = alpha * cexp(-2.0 * M_PI * I * s->sys.f0 * *tau);
}

/* Direct forward sum (double accumulation). */
static void forward_ref(const scene *s, double period, double complex *d)
{
    int ns = s->win.n_samples;
    for (int l = 0; l < s->array.n_rx; l++) {
        for (int m = 0; m < ns; m++) d[l * ns + m] = 0.0;
        for (int n = 0; n < s->np; n++) {
            double tau;
            double complex g;
            green_ref(s, l, n, &tau, &g);
            double complex c = g * s->rho[n];
            for (int m = 0; m < ns; m++) {
                double t = s->win.t0 + m / s->sys.sample_rate;
                d[l * ns + m] += c * sasnav_pulse_direct(&s->sys, period, t - tau);
            }
        }
    }
}

/* Direct adjoint sum: rho[n] = sum_l conj(G_ln) sum_m conj(p(t_m - tau)) y_lm. */
static void adjoint_ref(const scene *s, double period, const sasnav_cfloat *y, double complex *r)
{
    int ns = s->win.n_samples;
    for (int n = 0; n < s->np; n++) {
        r[n] = 0.0;
        for (int l = 0; l < s->array.n_rx; l++) {
            double tau;
            double complex g, acc = 0.0;
            green_ref(s, l, n, &tau, &g);
            for (int m = 0; m < ns; m++) {
                double t = s->win.t0 + m / s->sys.sample_rate;
                acc += conj(sasnav_pulse_direct(&s->sys, period, t - tau)) * y[l * ns + m];
            }
            r[n] += conj(g) * acc;
        }
    }
}

static double rel_err_f(const sasnav_cfloat *a, const double complex *ref, size_t n)
{
    double e = 0.0, r = 0.0;
    for (size_t i = 0; i < n; i++) {
        e += pow(cabs((double complex)a[i] - ref[i]), 2);
        r += pow(cabs(ref[i]), 2);
    }
    return sqrt(e / r);
}

/* Forward and adjoint errors of one scene at one tolerance. */
static void compare(const scene *s, double tol, const char *what, double *err_fwd, double *err_adj)
{
    sasnav_op_opts o;
    sasnav_op_default_opts(&o);
    o.tolerance = tol;
    sasnav_op *op = NULL;
    CHECK_OK(sasnav_op_create(&s->sys, &s->array, &s->win, s->np, s->x, s->y, &o, &op));
    if (!op) return;
    CHECK_OK(s->chan ? sasnav_op_set_channels(op, s->chan) : sasnav_op_set_geometry(op, &s->ping));
    CHECK(sasnav_op_n_dropped(op) == 0, "%s: nothing dropped (%ld)", what, sasnav_op_n_dropped(op));
    size_t nd = (size_t)s->array.n_rx * (size_t)s->win.n_samples;
    sasnav_cfloat *d = malloc(nd * sizeof *d), *y = malloc(nd * sizeof *y);
    sasnav_cfloat *r = malloc((size_t)s->np * sizeof *r);
    double complex *dref = malloc(nd * sizeof *dref), *rref = malloc((size_t)s->np * sizeof *rref);
    CHECK_OK(sasnav_op_forward(op, s->rho, d));
    forward_ref(s, sasnav_op_period(op), dref);
    *err_fwd = rel_err_f(d, dref, nd);
    for (size_t i = 0; i < nd; i++) y[i] = (float)gauss() + I * (float)gauss();
    CHECK_OK(sasnav_op_adjoint(op, y, r));
    adjoint_ref(s, sasnav_op_period(op), y, rref);
    *err_adj = rel_err_f(r, rref, (size_t)s->np);
    double bound = tol > FLOOR ? tol : FLOOR;
    printf("  %-28s tol %.0e  w %2d  forward %.2e  adjoint %.2e\n", what, tol,
           sasnav_op_kernel_width(op), *err_fwd, *err_adj);
    CHECK(*err_fwd <= bound, "%s tol %g: forward error %g", what, tol, *err_fwd);
    CHECK(*err_adj <= bound, "%s tol %g: adjoint error %g", what, tol, *err_adj);
    free(d);
    free(y);
    free(r);
    free(dref);
    free(rref);
    sasnav_op_destroy(op);
}

static void scene_alloc(scene *s, int np)
{
    s->np = np;
    s->x = malloc((size_t)np * sizeof *s->x);
    s->y = malloc((size_t)np * sizeof *s->y);
    s->rho = malloc((size_t)np * sizeof *s->rho);
    for (int n = 0; n < np; n++) s->rho[n] = (float)gauss() + I * (float)gauss();
}

static void scene_free(scene *s)
{
    free(s->x);
    free(s->y);
    free(s->rho);
}

/* One channel, monostatic at the origin, omni, no attenuation: a pure test of
 * the time interpolation. Points at random ranges 9.6..10.4 m inside a window
 * for 9.5..10.5 m (every delay strictly inside). */
static void test_sweep(void)
{
    scene s = {0};
    sasnav_system_default(&s.sys);
    s.sys.beam_pattern = 0;
    s.sys.attenuation = SASNAV_ATTEN_NONE;
    CHECK_OK(sasnav_array_uniform(&s.array, 1, 0.05, 0.0, 0.0));
    CHECK_OK(sasnav_window_for_ranges(&s.sys, 9.5, 10.5, 8, &s.win));
    scene_alloc(&s, 300);
    for (int n = 0; n < s.np; n++) {
        double r = 9.6 + 0.8 * uniform(), a = uniform() - 0.5;
        s.x[n] = r * sin(a);
        s.y[n] = r * cos(a);
    }
    printf("tolerance sweep (1 channel, 300 points, %d samples):\n", s.win.n_samples);
    double prev = 1.0;
    for (int d = 2; d <= 8; d++) {
        double ef, ea;
        compare(&s, pow(10.0, -d), "flat spectrum", &ef, &ea);
        /* The error must fall with the tolerance until the float floor. */
        if (prev > 10 * FLOOR) CHECK(ef < prev, "error decreases with tolerance");
        prev = ef;
    }
    double ef, ea;
    s.sys.taper = SASNAV_TAPER_HANN;
    compare(&s, 1e-5, "Hann taper", &ef, &ea);
    s.sys.taper = SASNAV_TAPER_HAMMING;
    compare(&s, 1e-3, "Hamming taper", &ef, &ea);
    scene_free(&s);
}

/* Every geometric term: 16 Rx, bistatic Tx with its own yaw, heights, beam
 * patterns on, exploding and spherical attenuation. */
static void test_geometry(void)
{
    scene s = {0};
    sasnav_system_default(&s.sys);
    CHECK_OK(sasnav_array_uniform(&s.array, 16, 0.05, 0.05, 0.05));
    s.array.rx_height = 0.7;
    s.array.tx_height = 0.9;
    sasnav_ping_pose local = sasnav_epca_local(0.10, 0.02);
    sasnav_pose centroid = {0.3, -0.2, 0.05};
    s.ping = sasnav_ping_place(centroid, &local);
    CHECK_OK(sasnav_window_for_ranges(&s.sys, 9.3, 10.9, 8, &s.win));
    scene_alloc(&s, 120);
    for (int n = 0; n < s.np; n++) {
        s.x[n] = 0.3 + 1.6 * (uniform() - 0.5);
        s.y[n] = 9.6 + 0.8 * uniform();
    }
    double ef, ea;
    compare(&s, 1e-6, "16 Rx, heights, exploding", &ef, &ea);
    s.sys.attenuation = SASNAV_ATTEN_SPHERICAL;
    compare(&s, 1e-4, "16 Rx, heights, spherical", &ef, &ea);
    scene_free(&s);
}

/* Channels as Tx-Rx pairs (sasnav_op_set_channels): four pings of a
 * 3-channel bistatic array on a curved track, each ping's Tx and array
 * poses its own, as one 12-channel virtual ping, against the direct sums
 * with each channel's own Tx. */
static void test_channels(void)
{
    scene s = {0};
    sasnav_system_default(&s.sys);
    sasnav_array a;
    CHECK_OK(sasnav_array_uniform(&a, 3, 0.05, 0.05, 0.05));
    s.array = a;
    s.array.n_rx = 12;
    s.array.rx_height = 0.7;
    s.array.tx_height = 0.9;
    sasnav_ping_pose chan[12];
    for (int j = 0; j < 4; j++) {
        sasnav_ping_pose local = sasnav_epca_local(0.10, 0.01 * j);
        sasnav_pose c = {0.3 + 0.075 * j, -0.2 + 0.002 * j * j, 0.05 + 0.01 * j};
        sasnav_ping_pose ping = sasnav_ping_place(c, &local);
        for (int l = 0; l < 3; l++) {
            s.array.rx_u[3 * j + l] = a.rx_u[l];
            chan[3 * j + l] = ping;
        }
    }
    s.chan = chan;
    CHECK_OK(sasnav_window_for_ranges(&s.sys, 9.2, 11.0, 8, &s.win));
    scene_alloc(&s, 120);
    for (int n = 0; n < s.np; n++) {
        s.x[n] = 0.4 + 1.4 * (uniform() - 0.5);
        s.y[n] = 9.6 + 0.8 * uniform();
    }
    double ef, ea;
    compare(&s, 1e-6, "12 channels, own Tx each", &ef, &ea);
    scene_free(&s);
}

/* Delays outside the periodic grid are dropped and counted, for T and T^H. */
static void test_dropped(void)
{
    sasnav_system sys;
    sasnav_system_default(&sys);
    sasnav_array array;
    CHECK_OK(sasnav_array_uniform(&array, 4, 0.05, 0.05, 0.05));
    sasnav_window win;
    CHECK_OK(sasnav_window_for_ranges(&sys, 9.5, 10.5, 8, &win));
    /* Beyond the window, before it, and absurdly far (distances overflow to
     * inf: must be dropped without NaN reaching the data). */
    double x[4] = {0.0, 0.0, 0.1, 1e300}, y[4] = {10.0, 30.0, 2.0, 1e300};
    sasnav_op *op = NULL;
    CHECK_OK(sasnav_op_create(&sys, &array, &win, 4, x, y, NULL, &op));
    sasnav_ping_pose ping = {{0, 0, 0}, {0, 0, 0}};
    CHECK_OK(sasnav_op_set_geometry(op, &ping));
    CHECK(sasnav_op_n_dropped(op) == 12, "3 points x 4 channels dropped, got %ld",
          sasnav_op_n_dropped(op));
    sasnav_cfloat rho[4] = {0, 1, 1, 1}, data[4 * 200], back[4];
    int ns = sasnav_op_n_samples(op);
    CHECK(ns <= 200, "window size");
    CHECK_OK(sasnav_op_forward(op, rho, data));
    double e = 0.0;
    for (int i = 0; i < 4 * ns; i++) e += cabsf(data[i]);
    CHECK(e == 0.0, "dropped points give no data (%g)", e);
    for (int i = 0; i < 4 * ns; i++) data[i] = 1.0f;
    CHECK_OK(sasnav_op_adjoint(op, data, back));
    CHECK(back[1] == 0.0f && back[2] == 0.0f && back[3] == 0.0f && cabsf(back[0]) > 0.0f,
          "adjoint of dropped is 0");
    sasnav_op_destroy(op);
}

int main(void)
{
    test_system_and_window();
    test_pulse();
    test_quadrature_and_kernel();
    test_sweep();
    test_geometry();
    test_channels();
    test_dropped();
    return test_summary("test_nufft");
}
