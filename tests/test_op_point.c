/* A point target focuses where it is, with the expected resolution (SPEC 5).
 *
 * Paper-pair system (f0 300 kHz, B 30 kHz, 16 Rx of 5 cm spaced 5 cm, 5 cm Tx
 * 10 cm behind the array midpoint), one point target off the pixel grid at
 * (0.013, 10.007). Raw data from a one-point ("scattered points") operator
 * for 21 pings along a straight track (centroids every 0.20 m, x from -2 to
 * +2 m), so that the synthetic aperture is limited by the 5 cm elements
 * (their beams reach the first null at sin(phi) = lambda / D = 0.1, i.e.
 * +-1 m at 10 m, well inside the track). The image is the sum of the pings'
 * backprojections T^H on a 2 mm grid over +-10 cm around the target.
 *
 * Expected -3 dB widths of |image| (amplitude / sqrt 2):
 * - range: T^H T for a flat band is the ideal band-limited pulse, a sinc in
 *   two-way delay, so the width is 0.886 c / (2 B) = 2.215 cm;
 * - cross-range: the backprojection weights the spatial frequency
 *   k_x = 4 pi sin(phi) / lambda by |alpha|^2 = (Tx pattern x Rx pattern)^2 =
 *   sinc^4(D sin(phi) / lambda), whose transform in x is the 4-fold
 *   convolution of rect(x / (D/2)) (a cubic B-spline with knots every D/2).
 *   Its -3 dB width is 1.025 D / 2 = 2.56 cm (the classic "D/2" of stripmap
 *   SAS, refined for this weighting).
 * One ping alone (16 Rx, phase centres over 40 cm) would only give
 * lambda R / (2 x 0.4 m) ~ 6 cm in cross-range.
 *
 * Checks: peak (parabolic sub-pixel interpolation) within 2 mm of the truth
 * (10 % of a resolution cell); both widths 2.5 cm +- 20 %; and each within
 * 5 % of its theoretical value above (the sampled aperture, the exploding-
 * source attenuation and the slight non-linearity of k_x in x explain
 * deviations of a few per cent at most). */
#include "sasnav/error.h"
#include "sasnav/geometry.h"
#include "sasnav/model.h"
#include "sasnav/op.h"
#include "testutil.h"

#include <complex.h>
#include <math.h>
#include <stdlib.h>

#define NPING 21
#define NPIX 101          /* pixels per side */
#define PIXEL 0.002       /* m */
#define TARGET_X 0.013
#define TARGET_Y 10.007
/* The grid is shifted off the target's half-pixel position so that the
 * sub-pixel interpolation is exercised (the target sits 0.15 and 0.35 pixel
 * from the nearest pixel centres rather than symmetrically between two). */
#define GRID_SHIFT_X 0.0007
#define GRID_SHIFT_Y 0.0003

/* Position of the maximum of the parabola through (-1, a), (0, b), (1, c). */
static double parabola_peak(double a, double b, double c)
{
    double den = a - 2.0 * b + c;
    return den != 0.0 ? 0.5 * (a - c) / den : 0.0;
}

/* Full width at amplitude level `level` of the profile v[0..n-1] around its
 * sample `i0`, crossings found by linear interpolation (in samples). */
static double width_at(const double *v, int n, int i0, double level)
{
    int i = i0, j = i0;
    while (i > 0 && v[i] > level) i--;
    while (j < n - 1 && v[j] > level) j++;
    if (v[i] > level || v[j] > level) return NAN; /* no crossing on the grid */
    double left = i + (level - v[i]) / (v[i + 1] - v[i]);
    double right = j - (level - v[j]) / (v[j - 1] - v[j]);
    return right - left;
}

int main(void)
{
    sasnav_system sys;
    sasnav_system_default(&sys);
    sasnav_array array;
    CHECK_OK(sasnav_array_uniform(&array, 16, 0.05, 0.05, 0.05));
    sasnav_window win;
    /* The outermost pings see the target at sqrt(10^2 + 2^2) = 10.2 m. */
    CHECK_OK(sasnav_window_for_ranges(&sys, 9.8, 10.35, 8, &win));
    int ns = win.n_samples, nd = array.n_rx * ns;

    double tx_ = TARGET_X, ty_ = TARGET_Y;
    sasnav_op *target = NULL, *imager = NULL;
    CHECK_OK(sasnav_op_create(&sys, &array, &win, 1, &tx_, &ty_, NULL, &target));

    double *px = malloc(NPIX * NPIX * sizeof *px), *py = malloc(NPIX * NPIX * sizeof *py);
    for (int j = 0; j < NPIX; j++)
        for (int i = 0; i < NPIX; i++) {
            px[j * NPIX + i] = GRID_SHIFT_X + (i - NPIX / 2) * PIXEL;
            py[j * NPIX + i] = 10.0 + GRID_SHIFT_Y + (j - NPIX / 2) * PIXEL;
        }
    CHECK_OK(sasnav_op_create(&sys, &array, &win, NPIX * NPIX, px, py, NULL, &imager));
    if (!target || !imager) return test_summary("test_op_point");

    sasnav_cfloat *data = malloc((size_t)nd * sizeof *data);
    sasnav_cfloat *image = calloc(NPIX * NPIX, sizeof *image);
    sasnav_cfloat one = 1.0f;
    sasnav_ping_pose local = sasnav_epca_local(0.10, 0.0);
    for (int p = 0; p < NPING; p++) {
        sasnav_pose centroid = {(p - NPING / 2) * 0.20, 0.0, 0.0};
        sasnav_ping_pose ping = sasnav_ping_place(centroid, &local);
        CHECK_OK(sasnav_op_set_geometry(target, &ping));
        CHECK(sasnav_op_n_dropped(target) == 0, "ping %d: target inside the window", p);
        CHECK_OK(sasnav_op_forward(target, &one, data));
        CHECK_OK(sasnav_op_set_geometry(imager, &ping));
        CHECK_OK(sasnav_op_adjoint_add(imager, data, image));
    }

    double *mag = malloc(NPIX * NPIX * sizeof *mag);
    int best = 0;
    for (int k = 0; k < NPIX * NPIX; k++) {
        mag[k] = cabsf(image[k]);
        if (mag[k] > mag[best]) best = k;
    }
    int bi = best % NPIX, bj = best / NPIX;
    CHECK(bi > 0 && bi < NPIX - 1 && bj > 0 && bj < NPIX - 1, "peak inside the grid (%d, %d)", bi,
          bj);
    if (bi > 0 && bi < NPIX - 1 && bj > 0 && bj < NPIX - 1) {
        double xp = px[best] + PIXEL * parabola_peak(mag[best - 1], mag[best], mag[best + 1]);
        double yp = py[best] +
                    PIXEL * parabola_peak(mag[best - NPIX], mag[best], mag[best + NPIX]);
        double row[NPIX], col[NPIX];
        for (int i = 0; i < NPIX; i++) row[i] = mag[bj * NPIX + i];
        for (int j = 0; j < NPIX; j++) col[j] = mag[j * NPIX + bi];
        double level = mag[best] / sqrt(2.0);
        double wx = PIXEL * width_at(row, NPIX, bi, level);
        double wy = PIXEL * width_at(col, NPIX, bj, level);
        double wy_theory = 0.886 * sys.sound_speed / (2.0 * sys.bandwidth);
        double wx_theory = 1.025 * array.rx_length / 2.0;
        printf("peak at (%.6f, %.6f) m, error (%+.3f, %+.3f) mm\n", xp, yp,
               1e3 * (xp - TARGET_X), 1e3 * (yp - TARGET_Y));
        printf("-3 dB widths: cross-range %.2f cm (theory %.2f), range %.2f cm (theory %.2f)\n",
               100 * wx, 100 * wx_theory, 100 * wy, 100 * wy_theory);
        CHECK(fabs(xp - TARGET_X) <= 0.002, "cross-range position error %g m", xp - TARGET_X);
        CHECK(fabs(yp - TARGET_Y) <= 0.002, "range position error %g m", yp - TARGET_Y);
        CHECK(fabs(wx - 0.025) <= 0.2 * 0.025, "cross-range width %g m", wx);
        CHECK(fabs(wy - 0.025) <= 0.2 * 0.025, "range width %g m", wy);
        CHECK(fabs(wx / wx_theory - 1.0) <= 0.05, "cross-range width %g vs theory %g", wx,
              wx_theory);
        CHECK(fabs(wy / wy_theory - 1.0) <= 0.05, "range width %g vs theory %g", wy, wy_theory);
    }
    free(px);
    free(py);
    free(mag);
    free(data);
    free(image);
    sasnav_op_destroy(target);
    sasnav_op_destroy(imager);
    return test_summary("test_op_point");
}
