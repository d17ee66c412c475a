/* Read-only view of a ping operator's per-pair storage (internal: for a
 * second implementation of the same operator, src/gpu/). The arrays stay
 * owned by the operator and change with its next set_geometry; `serial`
 * identifies the geometry they hold (unique over the process, so a copy
 * made elsewhere knows when it is stale, even if the operator was
 * destroyed and another created at the same address). */
#ifndef SASNAV_OP_VIEW_H
#define SASNAV_OP_VIEW_H

#include <stddef.h>
#include <stdint.h>

/* No sasnav/op.h here (its complex type is C only): CUDA sources include
 * this header. */
#include "sasnav/geometry.h"
typedef struct sasnav_op sasnav_op;

#define OP_BLOCK 64 /* points per block of the pair layout (op.c) */

typedef struct {
    int n_points, n_rx, n_samples;
    int pad, mp, lf, ext; /* coarse offset, coarse and fine lengths, fine extension */
    int wpad, kmax, n_blocks;
    size_t n_pairs;       /* n_blocks x n_rx x OP_BLOCK */
    /* Pair (l, n) at ((n / BLOCK) * n_rx + l) * BLOCK + n % BLOCK: its first
     * fine index, wpad taps and G (re, im); 2 kmax + 1 spectral weights. */
    const int32_t *index;
    const float *taps, *green, *spectral;
    unsigned long serial; /* 0: no geometry set */
} op_view;

/* Fills *v; SASNAV_ERR_ARG without a geometry. */
int op_view_get(const sasnav_op *op, op_view *v);

/* What set_geometry computes the pairs from, for an implementation that
 * computes them elsewhere (src/gpu/): per channel, its transmitter and
 * receiver (positions, axes, apertures D / lambda, heights; rx_u the
 * receiver's offset along the array axis) ... */
typedef struct {
    double tx_x, tx_y, tx_cos, tx_sin, tx_aperture;
    double ar_x, ar_y, ar_cos, ar_sin, rx_aperture;
    double tx_height, rx_height, rx_u;
} op_channel_geometry;

/* ... and the operator's constants: the points, the delay-to-fine-grid map
 * u = (tau - start) inv_h, the kept range half <= u <= u_max (v clamped to
 * [0, v_max]), the spreading-loss coefficients, the kernel taps' polynomial
 * (tap_degree + 1 rows of wpad coefficients, Horner in the offset t). */
typedef struct {
    const double *x, *y;
    double inv_c, inv_h, two_f0, start, half, u_max, v_max;
    double att_exploding, att_spherical, att_none;
    int tap_degree;
    const float *tap_coef;
} op_geometry_consts;

/* The channel geometries (n_rx entries) set_geometry (per_channel = 0:
 * poses[0] for every channel) or set_channels (per_channel = 1: poses[l])
 * would use; SASNAV_ERR_ARG for a non-finite pose. */
int op_channel_geometry_get(const sasnav_op *op, const sasnav_ping_pose *poses,
                                   int per_channel, op_channel_geometry *out);
int op_geometry_consts_get(const sasnav_op *op, op_geometry_consts *out);

#endif
