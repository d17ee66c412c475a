/* sasnav -- pictures (PNG through PLplot's cairo driver).
 * Writers go to a temporary name and rename on success.
 *
 * Threads: not thread-safe. PLplot keeps process-wide state and every call
 * switches its current stream (plmkstrm / plsstrm in src/plot/plot.c): call
 * these from one thread at a time, and not while other code uses PLplot. */
#ifndef SASNAV_PLOT_H
#define SASNAV_PLOT_H

#include "sasnav/image.h"

#ifdef __cplusplus
extern "C" {
#endif

/* |image| in dB re its maximum, clipped at -dynamic_range_db, with a colour
 * map, axes in metres (x along track horizontal, y range vertical) and a
 * colour bar. */
int sasnav_plot_image_db(const char *png_path, const sasnav_grid *grid,
                         const sasnav_cfloat *image, double dynamic_range_db,
                         const char *title);

/* Line plot of n_series curves sharing nothing but the axes. x[s], y[s] hold
 * n[s] points each; labels[s] names each curve in the legend (may be NULL). */
typedef struct {
    const char *title, *xlabel, *ylabel;
    int n_series;
    const int *n;
    const double *const *x;
    const double *const *y;
    const char *const *labels;
    int log_y;          /* 1: logarithmic y axis */
    double vline;       /* x of a dashed vertical marker (NAN: none) */
    double vline2;      /* second marker (NAN: none) */
} sasnav_line_plot;

int sasnav_plot_lines(const char *png_path, const sasnav_line_plot *plot);

/* Map of a real field f[iy * nx + ix] on a grid with a colour bar (linear). */
int sasnav_plot_map(const char *png_path, const sasnav_grid *grid, const double *f,
                    const char *title, const char *xlabel, const char *ylabel);

#ifdef __cplusplus
}
#endif
#endif
