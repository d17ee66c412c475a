/* sasnav -- image grids, backprojection of runs and CGLS inversion of pings.
 *
 * Threads: the grid functions and sasnav_image_correlation are pure.
 * sasnav_backproject is re-entrant (the run is only read): it makes its own
 * operator with opts (OpenMP with opts->nthreads, FFTW planning: op.h).
 * sasnav_cgls uses the caller's operator, which must not be in use by
 * another thread; its own loops are serial. */
#ifndef SASNAV_IMAGE_H
#define SASNAV_IMAGE_H

#include "sasnav/op.h"
#include "sasnav/run.h"

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Rectangular grid in the scene plane. Pixel (iy, ix) is at
 * (x0 + ix dx, y0 + iy dy); images are stored row-major [iy][ix]
 * (rows along range y, columns along track x). */
typedef struct {
    double x0, y0;  /* m, centre of the first pixel */
    double dx, dy;  /* m, pixel spacing (> 0) */
    int nx, ny;
} sasnav_grid;

/* Grid covering [x_min, x_max] x [y_min, y_max] with nx x ny pixels (n >= 2,
 * or n = 1 with min == max). */
int sasnav_grid_make(double x_min, double x_max, int nx, double y_min, double y_max, int ny,
                     sasnav_grid *grid);
int sasnav_grid_check(const sasnav_grid *grid);

/* Pixel coordinates of the grid, transformed by `frame` (world = frame * local)
 * into x[n], y[n], n = iy * nx + ix. Arrays must hold nx * ny values. */
void sasnav_grid_points(const sasnav_grid *grid, sasnav_pose frame, double *x, double *y);

/* Backprojection of a whole run (paper eq. bckprj): image = sum_p T_p^H phi_p
 * on `grid`, with ping poses nav[p] (world frame). image has nx * ny values.
 * Any grid size: computed in tiles of rows (sasnav_backproject_rows); the
 * run may be streamed. */
int sasnav_backproject(const sasnav_run *run, const sasnav_ping_pose *nav,
                       const sasnav_grid *grid, const sasnav_op_opts *opts,
                       sasnav_cfloat *image);

/* Progress of a per-ping loop: `done` of `total` pings finished (called
 * after each ping, on the calling thread). */
typedef void (*sasnav_ping_progress_fn)(int done, int total, void *user);

/* sasnav_backproject with a progress callback (may be NULL). */
int sasnav_backproject_progress(const sasnav_run *run, const sasnav_ping_pose *nav,
                                const sasnav_grid *grid, const sasnav_op_opts *opts,
                                sasnav_cfloat *image, sasnav_ping_progress_fn progress, void *user);

/* Backprojection in tiles of at most this many (pixel, channel) pairs
 * (about 44 bytes of operator memory each: some 180 MB per tile; square
 * tiles of 512 x 512 pixels with 16 channels). */
#define SASNAV_BACKPROJECT_TILE_PAIRS (1L << 22)

/* Pixels col0 .. col1 - 1 x rows row0 .. row1 - 1 of the backprojection on
 * `grid` into image ((col1 - col0) x (row1 - row0) values, row-major, the
 * first row first): the same bits as those pixels of sasnav_backproject on
 * the whole grid, whatever the split (tiles, processes of a distributed
 * image). Made in tiles of SASNAV_BACKPROJECT_TILE_PAIRS pairs, each with
 * only the pings whose echoes can reach it (the others would add exact
 * zeros): the cost of a survey grows with its length, not its square. The
 * run may be streamed (sasnav_run_open): each tile reads the pings it
 * needs. progress counts (tile, ping) steps. */
int sasnav_backproject_tile(const sasnav_run *run, const sasnav_ping_pose *nav,
                            const sasnav_grid *grid, int col0, int col1, int row0, int row1,
                            const sasnav_op_opts *opts, sasnav_cfloat *image,
                            sasnav_ping_progress_fn progress, void *user);

/* sasnav_backproject_tile over whole rows row0 .. row1 - 1. */
int sasnav_backproject_rows(const sasnav_run *run, const sasnav_ping_pose *nav,
                            const sasnav_grid *grid, int row0, int row1,
                            const sasnav_op_opts *opts, sasnav_cfloat *image,
                            sasnav_ping_progress_fn progress, void *user);

/* Fast factorised backprojection (FFBP; docs/survey.md): the same image as
 * sasnav_backproject_tile up to interpolation errors (about -50 dB per
 * level at the default oversampling, measured there), at a cost that grows
 * as log(pings x channels) instead of pings x channels per pixel. Each
 * channel of each ping is imaged on a polar grid about its own phase
 * centre; subapertures of consecutive channels and pings are merged two by two
 * by interpolation, and the largest ones no bigger than a tile are
 * interpolated onto its pixels; tiles as sasnav_backproject_tile. Where a
 * polar frame does not suit (pixels near the track's line or near
 * end-fire), those pings go through the direct operator. Deterministic:
 * the same bits for the same inputs and any thread count. Unlike the
 * direct sum, a pixel's value depends (within the error) on the tile it is
 * made in: the same rectangle, split the same way, gives the same bits. */
typedef struct {
    double oversampling;  /* polar sampling over the Nyquist rate (default 2;
                             1.25..4): the interpolation error's knob */
} sasnav_ffbp_opts;

void sasnav_ffbp_default_opts(sasnav_ffbp_opts *opts);

/* FFBP tiles: at most this many (pixel, channel) pairs (4x the direct
 * tiles: their memory is the leaves' polar grids, a fraction of the
 * pixels; larger tiles spend less on the grids' margins). */
#define SASNAV_FFBP_TILE_PAIRS (1L << 24)

/* FFBP of pixels col0 .. col1 - 1 x rows row0 .. row1 - 1 (as
 * sasnav_backproject_tile; fopts NULL: defaults). */
int sasnav_ffbp_tile(const sasnav_run *run, const sasnav_ping_pose *nav, const sasnav_grid *grid,
                     int col0, int col1, int row0, int row1, const sasnav_op_opts *opts,
                     const sasnav_ffbp_opts *fopts, sasnav_cfloat *image,
                     sasnav_ping_progress_fn progress, void *user);

/* Options of the CGLS pseudo-inverse. */
typedef struct {
    int iterations;   /* k, default 5 */
    double tikhonov;  /* lambda >= 0: minimises ||T x - d||^2 + lambda ||x||^2 (default 0) */
} sasnav_cgls_opts;

/* Normalised correlation |<a, b>| / (||a|| ||b||) of two complex images of
 * n pixels, over the pixels where region[j] != 0 (region NULL: all); 0 when
 * either image is zero there. Insensitive to a common phase and scale. */
double sasnav_image_correlation(const sasnav_cfloat *a, const sasnav_cfloat *b,
                                const unsigned char *region, size_t n);

void sasnav_cgls_default_opts(sasnav_cgls_opts *opts);

/* x = T^+ d by k iterations of CGLS started from 0 (truncated, regularised
 * pseudo-inverse). The operator's geometry must be set. `work` may be NULL
 * (allocated internally) or hold 2 * n_points + 2 * n_rx * n_samples values. */
int sasnav_cgls(sasnav_op *op, const sasnav_cfloat *data, const sasnav_cgls_opts *opts,
                sasnav_cfloat *x, sasnav_cfloat *work);

#ifdef __cplusplus
}
#endif
#endif
