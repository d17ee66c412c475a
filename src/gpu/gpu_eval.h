/* The estimator's error evaluation on a CUDA GPU (optional: built with
 * -DSASNAV_CUDA=ON, which defines SASNAV_HAVE_CUDA; docs/estimator.md,
 * "GPU").
 *
 * One context per estimator level holds the level's two operators on the
 * device (p's copied from the CPU operator, again only when its geometry
 * changed: op_view.h's serial; q's computed on the device at each
 * hypothesis, gpu_place, or copied) and runs what sasnav_pair_eval runs on
 * the CPU: rho_q = T_q^+ phi_q, then psi_p = (Q_p Q_q)^i rho_p and psi_q =
 * (Q_q Q_p)^i rho_q, the two chains on two streams, captured once as a CUDA
 * graph. The operator is the same NUFFT as src/operators/op.c, computed in
 * another order: the spread gathers, per fine-grid sample, the pairs sorted
 * by fine index (no floating-point atomics), the adjoint interpolates per
 * point over the channels, the FFTs are cuFFT's. Results agree with the
 * CPU's to float rounding, not to the bit; for a given GPU and build they
 * should be the same bits from run to run (fixed reduction orders, a
 * stable sort). Internal: not part of the installed API. */
#ifndef SASNAV_GPU_EVAL_H
#define SASNAV_GPU_EVAL_H

#include "operators/op_view.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct gpu_ctx gpu_ctx;

/* Complex vectors are interleaved (re, im) floats (sasnav_cfloat's layout;
 * the CUDA side has no C complex type). */

/* SASNAV_OK where a CUDA device is usable, SASNAV_ERR_UNSUPPORTED (with a
 * message saying why) otherwise. */
int gpu_check_device(void);

/* A context for operators shaped like `shape` (points, channels, samples,
 * grids: op_view_get). SASNAV_ERR_UNSUPPORTED without a usable
 * device. */
int gpu_create(const op_view *shape, gpu_ctx **out);
void gpu_destroy(gpu_ctx *g);

/* Whether g can hold operators shaped like v (the same grids, points and
 * channels): a context is kept from one pair to the next where it can
 * (plans, buffers and captured graphs made once). */
int gpu_fits(const gpu_ctx *g, const op_view *v);

/* Copies op's current geometry to the device as operator `which` (0: p,
 * 1: q), unless the copy already holds it. */
int gpu_set_op(gpu_ctx *g, int which, const op_view *op);

/* out = T x (adjoint = 0: x has n_points entries, out n_rx x n_samples) or
 * T^H x (adjoint = 1) with operator `which`; host arrays (checks, benches). */
int gpu_apply(gpu_ctx *g, int which, int adjoint, const float *x, float *out);

/* x = T^+ data by k CGLS iterations with operator `which` (sasnav_cgls). */
int gpu_cgls(gpu_ctx *g, int which, const float *data, int k, double tikhonov,
                    float *x);

/* The evaluation: rho_q = T_q^+ data_q (k iterations), psi_p = (Q_p
 * Q_q)^i rho_p, psi_q = (Q_q Q_p)^i rho_q, Q = T^+ T; host arrays (rho_q,
 * psi_p, psi_q: n_points each). */
int gpu_eval(gpu_ctx *g, const float *data_q, const float *rho_p, int k, int i,
                    double tikhonov, float *rho_q, float *psi_p, float *psi_q);

/* Device-side geometry (instead of copying the CPU operator's pairs after
 * its set_geometry): gpu_set_points once per context with the
 * operator's constants (op_geometry_consts_get), then
 * gpu_place per hypothesis with the channel geometries
 * (op_channel_geometry_get): the pairs (fine index, taps, G) are
 * computed on the device by set_geometry's formulas, in double, and sorted
 * there (stable radix sort). SASNAV_ERR_GEOMETRY where a point coincides
 * with a sensor. */
int gpu_set_points(gpu_ctx *g, const op_geometry_consts *c);
int gpu_place(gpu_ctx *g, int which, const op_channel_geometry *channels);

/* Whether the estimator places q's operator on the device (1, the default)
 * or copies the CPU operator's pairs (0). Not thread-safe: set it before
 * use. */
void gpu_use_device_geometry(int on);
int gpu_device_geometry(void);

/* Whether contexts created from now on run the evaluation as one captured
 * CUDA graph (1, the default) or launch its ~4,700 steps one by one (0;
 * the same results: for benches). Not thread-safe: set it before use. */
void gpu_use_graphs(int on);

/* The device's name (for reports); "" without a context. */
const char *gpu_name(const gpu_ctx *g);

#ifdef __cplusplus
}
#endif

#endif
