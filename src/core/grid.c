/* Rectangular image grids in the scene plane. */
#include "sasnav/error.h"
#include "sasnav/image.h"

#include <limits.h>
#include <math.h>
#include <stddef.h>

/* Pixel spacing of one axis, 0 when the axis has a single pixel. */
static int axis_spacing(const char *name, double lo, double hi, int n, double *d)
{
    if (!isfinite(lo) || !isfinite(hi))
        return sasnav_set_error(SASNAV_ERR_ARG, "grid %s bounds must be finite", name);
    if (n < 1) return sasnav_set_error(SASNAV_ERR_ARG, "grid needs >= 1 pixel along %s, got %d", name, n);
    if (n == 1) {
        if (lo != hi)
            return sasnav_set_error(SASNAV_ERR_ARG,
                                    "grid with 1 pixel along %s needs min == max (%g, %g)", name, lo, hi);
        *d = 0.0;
        return SASNAV_OK;
    }
    *d = (hi - lo) / (n - 1);
    if (!(hi > lo) || !(*d > 0) || !isfinite(*d))
        return sasnav_set_error(SASNAV_ERR_ARG, "grid %s range [%g, %g] must be increasing", name, lo, hi);
    return SASNAV_OK;
}

int sasnav_grid_make(double x_min, double x_max, int nx, double y_min, double y_max, int ny,
                     sasnav_grid *grid)
{
    if (!grid) return sasnav_set_error(SASNAV_ERR_ARG, "grid is NULL");
    double dx = 0.0, dy = 0.0;
    int rc = axis_spacing("x", x_min, x_max, nx, &dx);
    if (rc) return rc;
    rc = axis_spacing("y", y_min, y_max, ny, &dy);
    if (rc) return rc;
    /* A single-pixel axis has no spacing of its own: give it the other
     * axis's (square pixels), or 1 m when both axes have one pixel. */
    if (dx == 0.0) dx = dy > 0.0 ? dy : 1.0;
    if (dy == 0.0) dy = dx;
    sasnav_grid g = {x_min, y_min, dx, dy, nx, ny};
    rc = sasnav_grid_check(&g);
    if (rc) return rc;
    *grid = g;
    return SASNAV_OK;
}

int sasnav_grid_check(const sasnav_grid *grid)
{
    if (!grid) return sasnav_set_error(SASNAV_ERR_ARG, "grid is NULL");
    if (grid->nx < 1 || grid->ny < 1)
        return sasnav_set_error(SASNAV_ERR_ARG, "grid needs >= 1 x 1 pixels, got %d x %d", grid->nx,
                                grid->ny);
    if (grid->nx > INT_MAX / grid->ny)
        return sasnav_set_error(SASNAV_ERR_ARG, "grid of %d x %d pixels is too large", grid->nx, grid->ny);
    if (!isfinite(grid->x0) || !isfinite(grid->y0))
        return sasnav_set_error(SASNAV_ERR_ARG, "grid origin must be finite");
    if (!isfinite(grid->dx) || !isfinite(grid->dy) || !(grid->dx > 0) || !(grid->dy > 0))
        return sasnav_set_error(SASNAV_ERR_ARG, "grid spacing must be finite and > 0 (dx %g, dy %g)",
                                grid->dx, grid->dy);
    if (!isfinite(grid->x0 + (grid->nx - 1) * grid->dx) || !isfinite(grid->y0 + (grid->ny - 1) * grid->dy))
        return sasnav_set_error(SASNAV_ERR_ARG, "grid extent is not finite");
    return SASNAV_OK;
}

void sasnav_grid_points(const sasnav_grid *grid, sasnav_pose frame, double *x, double *y)
{
    for (int iy = 0; iy < grid->ny; iy++) {
        double ly = grid->y0 + iy * grid->dy;
        for (int ix = 0; ix < grid->nx; ix++) {
            size_t n = (size_t)iy * (size_t)grid->nx + (size_t)ix;
            sasnav_pose_apply(frame, grid->x0 + ix * grid->dx, ly, &x[n], &y[n]);
        }
    }
}
