/* Backprojection of a run (paper eq. bckprj): the sum over pings of the
 * adjoint ping operators, on a user grid, with given navigation. */
#include "sasnav/error.h"
#include "sasnav/image.h"
#include "backproject_internal.h"

#include <complex.h>
#include <limits.h>
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
    return sasnav_backproject_tile(run, nav, grid, 0, grid->nx, 0, grid->ny, opts, image, progress, user);
}

int sasnav_backproject_rows(const sasnav_run *run, const sasnav_ping_pose *nav,
                            const sasnav_grid *grid, int row0, int row1,
                            const sasnav_op_opts *opts, sasnav_cfloat *image,
                            sasnav_ping_progress_fn progress, void *user)
{
    if (!grid) return sasnav_set_error(SASNAV_ERR_ARG, "NULL backprojection argument");
    return sasnav_backproject_tile(run, nav, grid, 0, grid->nx, row0, row1, opts, image, progress, user);
}

/* Whether ping `pose` can reach the rectangle [xa, xb] x [ya, yb] within
 * the operator's kept delays (t_last: sasnav_op_delay_span): every sensor
 * lies within `radius` of the array's reference point, so every bistatic
 * path to the rectangle is at least twice its distance to that disc. A
 * ping that cannot would contribute exact zeros (all its pairs dropped):
 * skipping it changes no bit and makes a long survey's cost linear in its
 * length instead of quadratic. Conservative: a nanosecond of margin. */
int sasnav_bp_ping_reaches(const sasnav_run *run, const sasnav_ping_pose *pose, double xa,
                           double xb, double ya, double yb, double t_last)
{
    double cx = pose->array.x, cy = pose->array.y;
    double radius = hypot(pose->tx.x - cx, pose->tx.y - cy);
    for (int l = 0; l < run->array.n_rx; l++)
        if (fabs(run->array.rx_u[l]) > radius) radius = fabs(run->array.rx_u[l]);
    radius += sasnav_channel_offset_radius(run->channel_offset, run->array.n_rx);
    double dx = cx < xa ? xa - cx : cx > xb ? cx - xb : 0.0;
    double dy = cy < ya ? ya - cy : cy > yb ? cy - yb : 0.0;
    double d = hypot(dx, dy) - radius;
    if (!(d > 0)) return 1;
    return 2.0 * d / run->sys.sound_speed <= t_last + 1e-9;
}

/* One tile: pixels [c0, c1) x [r0, r1) of the grid into out (row stride
 * `stride`), every ping that can reach it. */
static int backproject_one(const sasnav_run *run, const sasnav_ping_pose *nav,
                           const sasnav_grid *grid, int c0, int c1, int r0, int r1,
                           const sasnav_op_opts *opts, sasnav_cfloat *out, size_t stride,
                           sasnav_cfloat *ping_buf, long *step, long steps,
                           sasnav_ping_progress_fn progress, void *user)
{
    int w = c1 - c0, h = r1 - r0;
    size_t np = (size_t)w * (size_t)h;
    double *x = malloc(sizeof(double) * np), *y = malloc(sizeof(double) * np);
    sasnav_cfloat *tile = malloc(sizeof *tile * np);
    if (!x || !y || !tile) {
        free(x);
        free(y);
        free(tile);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory for a tile of %zu pixels", np);
    }
    /* The same coordinates as sasnav_grid_points gives the whole grid (the
     * pixel's own indices), so a pixel's value does not depend on the
     * tiling. */
    sasnav_bp_tile_points(grid, c0, r0, w, h, x, y);
    double xa = grid->x0 + c0 * grid->dx, xb = grid->x0 + (c1 - 1) * grid->dx;
    double ya = grid->y0 + r0 * grid->dy, yb = grid->y0 + (r1 - 1) * grid->dy;
    sasnav_op *op = NULL;
    int rc = sasnav_op_create(&run->sys, &run->array, &run->win, (int)np, x, y, opts, &op);
    free(x);
    free(y);
    if (rc) {
        free(tile);
        return rc;
    }
    double t_first, t_last;
    sasnav_op_delay_span(op, &t_first, &t_last);
    memset(tile, 0, sizeof *tile * np);
    for (int p = 0; p < run->n_pings && !rc; p++) {
        if (sasnav_bp_ping_reaches(run, &nav[p], xa, xb, ya, yb, t_last)) {
            const sasnav_cfloat *ping = NULL;
            rc = sasnav_run_get_ping(run, p, ping_buf, &ping);
            if (!rc) rc = sasnav_op_set_ping(op, &nav[p], run->channel_offset);
            if (!rc) rc = sasnav_op_adjoint_add(op, ping, tile);
        }
        ++*step;
        if (!rc && progress) progress((int)(*step < INT_MAX ? *step : INT_MAX), (int)(steps < INT_MAX ? steps : INT_MAX), user);
    }
    sasnav_op_destroy(op);
    for (int iy = 0; iy < h && !rc; iy++)
        memcpy(out + (size_t)iy * stride, tile + (size_t)iy * (size_t)w, sizeof *tile * (size_t)w);
    free(tile);
    return rc;
}

int sasnav_bp_check_args(const sasnav_run *run, const sasnav_ping_pose *nav, const sasnav_grid *grid,
                         int col0, int col1, int row0, int row1, const sasnav_cfloat *image)
{
    if (!run || !nav || !grid || !image)
        return sasnav_set_error(SASNAV_ERR_ARG, "NULL backprojection argument");
    int rc = sasnav_grid_check(grid);
    if (rc) return rc;
    if (row0 < 0 || row1 > grid->ny || row0 >= row1 || col0 < 0 || col1 > grid->nx || col0 >= col1)
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "pixels %d..%d x %d..%d are not within the grid's %d x %d", col0,
                                col1 - 1, row0, row1 - 1, grid->nx, grid->ny);
    return SASNAV_OK;
}

void sasnav_bp_tile_points(const sasnav_grid *grid, int c0, int r0, int w, int h, double *x, double *y)
{
    for (int iy = 0; iy < h; iy++)
        for (int ix = 0; ix < w; ix++) {
            size_t n = (size_t)iy * (size_t)w + (size_t)ix;
            x[n] = grid->x0 + (c0 + ix) * grid->dx;
            y[n] = grid->y0 + (r0 + iy) * grid->dy;
        }
}

void sasnav_bp_tile_size_pairs(const sasnav_run *run, long pairs, int cols, int rows, int *tw, int *th)
{
    int side = (int)floor(sqrt((double)pairs / run->array.n_rx));
    if (side < 1) side = 1;
    *tw = cols < side ? cols : side;
    *th = rows < side ? rows : side;
    if (*tw < side) *th = (int)(pairs / run->array.n_rx / *tw); /* narrow: taller tiles */
    if (*th > rows) *th = rows;
    if (*th < 1) *th = 1;
}

void sasnav_bp_tile_size(const sasnav_run *run, int cols, int rows, int *tw, int *th)
{
    sasnav_bp_tile_size_pairs(run, SASNAV_BACKPROJECT_TILE_PAIRS, cols, rows, tw, th);
}

int sasnav_backproject_tile(const sasnav_run *run, const sasnav_ping_pose *nav,
                            const sasnav_grid *grid, int col0, int col1, int row0, int row1,
                            const sasnav_op_opts *opts, sasnav_cfloat *image,
                            sasnav_ping_progress_fn progress, void *user)
{
    int rc = sasnav_bp_check_args(run, nav, grid, col0, col1, row0, row1, image);
    if (rc) return rc;
    /* Square tiles of at most SASNAV_BACKPROJECT_TILE_PAIRS (pixel,
     * channel) pairs: the operator's memory is per pair. */
    int tw, th;
    sasnav_bp_tile_size(run, col1 - col0, row1 - row0, &tw, &th);
    long ntx = (col1 - col0 + tw - 1) / tw, nty = (row1 - row0 + th - 1) / th;
    long steps = ntx * nty * run->n_pings, step = 0;
    sasnav_cfloat *ping_buf = NULL;
    if (!run->raw) {
        ping_buf = malloc(sizeof *ping_buf * sasnav_run_ping_size(run));
        if (!ping_buf) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory for a ping");
    }
    size_t stride = (size_t)(col1 - col0);
    for (int r0 = row0; r0 < row1 && !rc; r0 += th)
        for (int c0 = col0; c0 < col1 && !rc; c0 += tw) {
            int r1 = r0 + th < row1 ? r0 + th : row1, c1 = c0 + tw < col1 ? c0 + tw : col1;
            rc = backproject_one(run, nav, grid, c0, c1, r0, r1, opts,
                                 image + (size_t)(r0 - row0) * stride + (size_t)(c0 - col0), stride,
                                 ping_buf, &step, steps, progress, user);
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
