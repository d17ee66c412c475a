/* Team applications of a ping operator (internal: the pair estimator's
 * projection chains, src/estimator/pair.c).
 *
 * op_forward_team and op_adjoint_team apply T or T^H to n = 1 or 2 images
 * at once, sharing the pair data between them (op.c: spread2_W,
 * interp2_W). Every thread of the enclosing OpenMP parallel region calls
 * them with the same arguments; each does its share (contiguous channels,
 * then contiguous blocks) and they return after a barrier. Outside a
 * parallel region the one thread does all of it. Each output is computed
 * by one thread, in the same order as sasnav_op_forward / sasnav_op_adjoint
 * on that image alone: the same bits whatever n and the team's size.
 *
 * The team may have at most op_threads(op) threads (per-thread work
 * buffers). op_team_prepare, outside the region, checks that the operator
 * has a geometry and allocates the second image's fine grids; after it the
 * team functions cannot fail. Thread t of the team uses the operator's work
 * buffers t: call them from a region of at most op_threads(op) threads (a
 * region of one inside another is fine), not straight from a wider one. */
#ifndef SASNAV_OP_TEAM_H
#define SASNAV_OP_TEAM_H

#include "sasnav/op.h"

int op_team_prepare(sasnav_op *op);
int op_threads(const sasnav_op *op);
void op_forward_team(const sasnav_op *op, int n, const sasnav_cfloat *const *rho,
                     sasnav_cfloat *const *data);
void op_adjoint_team(const sasnav_op *op, int n, const sasnav_cfloat *const *data,
                     sasnav_cfloat *const *rho);

/* Truncated CGLS (sasnav_cgls) of n = 1 or 2 right-hand sides in lockstep
 * on one operator, called by every thread of the region as above: each
 * system's vectors and scalars are handled by one thread (system c by
 * thread c mod team size), its operator applications shared. x[c], work[c]
 * (2 np + 2 nd, laid out as sasnav_cgls's) and state (n entries) are
 * shared by the team. Each x[c] is the same bits as sasnav_cgls gives. */
typedef struct {
    double gamma, gamma0;
    int active;
} cgls_team_state;

void cgls_team(const sasnav_op *op, int n, const sasnav_cfloat *const *data, int iterations,
               double tikhonov, sasnav_cfloat *const *x, sasnav_cfloat *const *work,
               cgls_team_state *state);

/* CGLS of min ||A x - a||^2 + ||B x - b||^2 + tikhonov ||x||^2 from x = 0
 * (the two operators stacked as one: the joint misfit of a ping pair,
 * src/estimator/pair.c), `iterations` steps: 2 applications of each
 * operator per step but the last adjoint. Writes x (np) and the data
 * residuals ra = a - A x, rb = b - B x of the last iterate (recursively
 * updated, as CGLS does). work: 3 np + na + nb. two_threads: A's and B's
 * applications side by side, one thread each (same bits). The operators
 * must share one grid (the same np). */
int cgls_stack(sasnav_op *A, sasnav_op *B, const sasnav_cfloat *a, const sasnav_cfloat *b,
               int iterations, double tikhonov, int two_threads, sasnav_cfloat *x, sasnav_cfloat *ra,
               sasnav_cfloat *rb, sasnav_cfloat *work);

#endif
