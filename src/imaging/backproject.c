/* Backprojection of a run (paper eq. bckprj): the sum over pings of the
 * adjoint ping operators, on a user grid, with given navigation. */
#include "sasnav/error.h"
#include "sasnav/image.h"

#include <complex.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

int sasnav_backproject(const sasnav_run *run, const sasnav_ping_pose *nav,
                       const sasnav_grid *grid, const sasnav_op_opts *opts,
                       sasnav_cfloat *image)
{
    return sasnav_backproject_progress(run, nav, grid, opts, image, NULL, NULL);
}

int sasnav_backproject_progress(const sasnav_run *run, const sasnav_ping_pose *nav,
                                const sasnav_grid *grid, const sasnav_op_opts *opts,
                                sasnav_cfloat *image, sasnav_ping_progress_fn progress, void *user)
{
    if (!grid) return sasnav_set_error(SASNAV_ERR_ARG, "NULL backprojection argument");
    return sasnav_backproject_rows(run, nav, grid, 0, grid->ny, opts, image, progress, user);
}

/* One tile: rows [r0, r1) of the grid, every ping. */
static int backproject_tile(const sasnav_run *run, const sasnav_ping_pose *nav,
                            const sasnav_grid *grid, int r0, int r1, const sasnav_op_opts *opts,
                            sasnav_cfloat *image, sasnav_cfloat *ping_buf, int tile, int n_tiles,
                            sasnav_ping_progress_fn progress, void *user)
{
    size_t np = (size_t)grid->nx * (size_t)(r1 - r0);
    double *x = malloc(sizeof(double) * np), *y = malloc(sizeof(double) * np);
    if (!x || !y) {
        free(x);
        free(y);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory for %zu pixels", np);
    }
    /* The same coordinates as sasnav_grid_points gives the whole grid (the
     * pixel's own row index), so a pixel's value does not depend on the
     * tiling. */
    for (int iy = r0; iy < r1; iy++)
        for (int ix = 0; ix < grid->nx; ix++) {
            size_t n = (size_t)(iy - r0) * (size_t)grid->nx + (size_t)ix;
            x[n] = grid->x0 + ix * grid->dx;
            y[n] = grid->y0 + iy * grid->dy;
        }
    sasnav_op *op = NULL;
    int rc = sasnav_op_create(&run->sys, &run->array, &run->win, (int)np, x, y, opts, &op);
    free(x);
    free(y);
    if (rc) return rc;
    for (int p = 0; p < run->n_pings && !rc; p++) {
        const sasnav_cfloat *ping = NULL;
        rc = sasnav_run_get_ping(run, p, ping_buf, &ping);
        if (!rc) rc = sasnav_op_set_geometry(op, &nav[p]);
        if (!rc) rc = sasnav_op_adjoint_add(op, ping, image);
        if (!rc && progress) progress(tile * run->n_pings + p + 1, n_tiles * run->n_pings, user);
    }
    sasnav_op_destroy(op);
    return rc;
}

int sasnav_backproject_rows(const sasnav_run *run, const sasnav_ping_pose *nav,
                            const sasnav_grid *grid, int row0, int row1,
                            const sasnav_op_opts *opts, sasnav_cfloat *image,
                            sasnav_ping_progress_fn progress, void *user)
{
    if (!run || !nav || !grid || !image)
        return sasnav_set_error(SASNAV_ERR_ARG, "NULL backprojection argument");
    int rc = sasnav_grid_check(grid);
    if (rc) return rc;
    if (row0 < 0 || row1 > grid->ny || row0 >= row1)
        return sasnav_set_error(SASNAV_ERR_ARG, "rows %d..%d are not within the grid's 0..%d", row0,
                                row1 - 1, grid->ny - 1);
    /* Tiles of whole rows, at most SASNAV_BACKPROJECT_TILE_PAIRS (pixel,
     * channel) pairs each: the operator's memory is per pair. */
    long per_row = (long)grid->nx * run->array.n_rx;
    int rows_per_tile = per_row >= SASNAV_BACKPROJECT_TILE_PAIRS ? 1 : (int)(SASNAV_BACKPROJECT_TILE_PAIRS / per_row);
    int n_tiles = (row1 - row0 + rows_per_tile - 1) / rows_per_tile;
    sasnav_cfloat *ping_buf = NULL;
    if (!run->raw) {
        ping_buf = malloc(sizeof *ping_buf * sasnav_run_ping_size(run));
        if (!ping_buf) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory for a ping");
    }
    memset(image, 0, sizeof(sasnav_cfloat) * (size_t)grid->nx * (size_t)(row1 - row0));
    for (int t = 0; t < n_tiles && !rc; t++) {
        int r0 = row0 + t * rows_per_tile, r1 = r0 + rows_per_tile < row1 ? r0 + rows_per_tile : row1;
        rc = backproject_tile(run, nav, grid, r0, r1, opts, image + (size_t)(r0 - row0) * (size_t)grid->nx,
                              ping_buf, t, n_tiles, progress, user);
    }
    free(ping_buf);
    return rc;
}

double sasnav_image_correlation(const sasnav_cfloat *a, const sasnav_cfloat *b,
                                const unsigned char *region, size_t n)
{
    if (!a || !b) return 0.0;
    double re = 0, im = 0, na = 0, nb = 0;
    for (size_t j = 0; j < n; j++) {
        if (region && !region[j]) continue;
        double ar = crealf(a[j]), ai = cimagf(a[j]), br = crealf(b[j]), bi = cimagf(b[j]);
        re += ar * br + ai * bi; /* conj(a) b */
        im += ar * bi - ai * br;
        na += ar * ar + ai * ai;
        nb += br * br + bi * bi;
    }
    return na > 0 && nb > 0 ? hypot(re, im) / sqrt(na * nb) : 0.0;
}
