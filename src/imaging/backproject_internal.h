/* Internal: pieces shared by direct and factorised backprojection. */
#ifndef SASNAV_BACKPROJECT_INTERNAL_H
#define SASNAV_BACKPROJECT_INTERNAL_H

#include "sasnav/image.h"

/* Whether ping `pose` can reach the rectangle [xa, xb] x [ya, yb] within
 * the operator's kept delays (t_last: sasnav_op_delay_span). */
int sasnav_bp_ping_reaches(const sasnav_run *run, const sasnav_ping_pose *pose, double xa,
                           double xb, double ya, double yb, double t_last);

/* Side of the square tiles of SASNAV_BACKPROJECT_TILE_PAIRS pairs, and
 * the tile size over a (cols x rows) rectangle. */
void sasnav_bp_tile_size(const sasnav_run *run, int cols, int rows, int *tw, int *th);
void sasnav_bp_tile_size_pairs(const sasnav_run *run, long pairs, int cols, int rows, int *tw, int *th);

/* The argument checks of sasnav_backproject_tile and sasnav_ffbp_tile. */
int sasnav_bp_check_args(const sasnav_run *run, const sasnav_ping_pose *nav, const sasnav_grid *grid,
                         int col0, int col1, int row0, int row1, const sasnav_cfloat *image);

/* The coordinates of pixels [c0, c0 + w) x [r0, r0 + h) of the grid, row
 * by row (the whole grid's: a pixel's value does not depend on the
 * tiling), into x, y of w * h values. */
void sasnav_bp_tile_points(const sasnav_grid *grid, int c0, int r0, int w, int h, double *x, double *y);

#endif
