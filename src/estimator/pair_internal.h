/* Private state of the ping-pair estimator. */
#ifndef SASNAV_PAIR_INTERNAL_H
#define SASNAV_PAIR_INTERNAL_H

#include <stddef.h>
#include <complex.h>
#include <fftw3.h>

#include "sasnav/error.h"
#include "sasnav/estimator.h"

#define PAIR_LEVELS 3
#define PAIR_KEPT 4 /* evaluations whose values a level keeps */
/* Most estimators evaluating hypotheses at once (pair_workers): the final
 * stage's model has ten points. */
#define PAIR_MAX_WORKERS 10
/* Most threads of one operator application: beyond four the applications
 * (16 channels of a 129 x 129 grid) get slower, not faster (measured on a
 * 16-core host, `--threads 16`: the paper pair 6.0-8.2 s with sixteen
 * threads in the operators, 2.9-3.5 s with four;
 * docs/estimator.md, "Batches on as many workers as threads"). The
 * workers still use every thread. */
#define PAIR_OP_THREADS_MAX 4

typedef struct {
    int k, i;
    sasnav_grid grid;
    size_t np, nd;
    sasnav_op *op_p, *op_q;  /* level 2 borrows level 1's (same grid) */
    int borrowed;            /* 1: op_p, op_q belong to another level */
    /* The hypothesis op_q was last placed at (valid: q_placed), so that a
     * repeated hypothesis skips set_geometry. Kept by the owning level. */
    sasnav_pose q_sigma;
    int q_placed;
    /* The hypothesis whose psi_p, psi_q the level's buffers hold (valid:
     * last_valid) and its normalisation, for pair_eval_residual. */
    sasnav_pose last_error;
    int last_valid;
    double last_nrm;
    /* Values (not psi) of the last PAIR_KEPT evaluations. */
    struct {
        sasnav_pose error;
        int blurred;
        double zeta, eta, overlap;
    } kept[PAIR_KEPT];
    int n_kept, next_kept;
    sasnav_cfloat *rho_p, *rho_q, *psi_p, *psi_q, *tmp, *data_tmp, *cgls_work;
    /* Second set of projection buffers: psi_q's chain runs beside psi_p's
     * (pair.c, project_chains and intersect_both). */
    sasnav_cfloat *tmp2, *data_tmp2, *cgls_work2;
    double *mod_p, *mod_q, *blur_tmp;
    float *window;
    /* The search's equalising weights (opts.equalise; levels 0 and 1,
     * NULL elsewhere or when off) and the contrast of q's reconstruction
     * at the prior (their gate, with p's), and the peak of the weights'
     * smoothed intensity over its mean in the window (their other gate;
     * the intensity smoothed at the gate's own scale in eq_gate, at level
     * 1 where opts.equalise differs from it, NULL otherwise). */
    double *eqw, *eq_gate;
    double contrast_q0;
    double eq_peak;
    double rho_p_norm;
    double contrast;         /* of |rho_p|^2 over the window (std / mean) */
    /* 2-D cross-correlation of |rho_p| and |rho_q| (global stage). */
    int xc_nx, xc_ny;
    fftwf_complex *xc_p, *xc_q;
    fftwf_plan xc_fwd_p, xc_fwd_q, xc_inv;
    /* Device copy of the operators this level owns (opts.gpu; src/gpu/). */
    struct gpu_ctx *gpu;
    /* The hypothesis q's device operator was last placed at (valid:
     * gpu_q_placed; device-side geometry). */
    sasnav_pose gpu_q_sigma;
    int gpu_q_placed, gpu_points; /* gpu_points: gpu_set_points done */
} pair_level;

struct sasnav_pair {
    sasnav_system sys;
    sasnav_array array;
    sasnav_window win;
    sasnav_pair_opts opts;
    sasnav_ping_pose local_p, local_q; /* EPCA geometry of each ping in its centroid frame */
    int per_channel;           /* 1: chan_p / chan_q hold each channel's geometry */
    sasnav_ping_pose *chan_p, *chan_q; /* n_rx each: channel geometries in each
                                          ping's centroid frame (set_data_channels) */
    double pc_spacing;         /* phase-centre spacing of the channel layout
                                  (0: from the array's rx_u) */
    double footprint;          /* m, along-track footprint between the first
                                  nulls of the beam of the largest aperture
                                  (Tx or Rx, the narrowest beam) at the
                                  grid's range (INFINITY: apertures of at
                                  most a wavelength); from the lengths
                                  alone, whether or not the run's model
                                  has beam patterns */
    size_t nd;
    sasnav_cfloat *data_p, *data_q;
    sasnav_pose nominal;
    int ready;
    /* equalised: the search's criteria are weighted (levels 0 and 1 hold
     * eqw, the scene is speckle-like at the prior and a feature stands
     * out: make_levels); eq_suspended: not
     * now (the unweighted eta stage before the final one). */
    int equalised, eq_suspended;
    pair_level level[PAIR_LEVELS];
    long applications;
    int evaluations;
    /* More estimators on the same data and geometry, one thread each, for
     * evaluating hypotheses at once (pair_workers); made when first
     * needed, dropped with new data. twin_failed: one could not be made
     * (no more are tried for this data). */
    struct sasnav_pair *twin[PAIR_MAX_WORKERS - 1];
    int n_twins, twin_failed;
    /* While a twin is made: the estimator it twins, whose p
     * reconstructions it copies instead of computing them again (the same
     * bits: the operators' sums do not depend on their thread count). */
    const struct sasnav_pair *twin_of;
    /* The joint misfit's scene and CGLS work (pair_eval_joint). */
    sasnav_cfloat *joint_x, *joint_work;
};

/* Scale (m) of the Gaussian high-pass applied to the moduli before their
 * cross-correlation (tuned on 40 paper-trajectory runs: 0.05 m, 0.1 m and
 * 0.15 m left 4, 1 and 3 of 600 global-stage points off the truth's
 * basin, none 61). */
#define PAIR_SHIFT_HIGHPASS 0.1

/* Shift (m, along track and range) of the scene content in q's image at
 * the hypothesised error relative to p's image, from the peak of the
 * cross-correlation of their moduli at `level`; `peak` (may be NULL)
 * receives the correlation coefficient of the moduli at that shift (their
 * means removed; 1 = the same content). */
int pair_image_shift(sasnav_pair *pr, int level, sasnav_pose error, double *sx, double *sy,
                     double *peak);

/* Evaluates at `level` (as sasnav_pair_eval, unblurred) and writes the
 * residual vector whose norm is the error function: eta ? (psi_p - psi_q) /
 * nrm : (|psi_p| - |psi_q|) / nrm (real, in the real parts), windowed; np
 * entries (pair_level_points). *f receives its norm (eta or zeta). */
int pair_eval_residual(sasnav_pair *pr, sasnav_pose error, int level, int use_eta,
                       sasnav_cfloat *r, double *f);
size_t pair_level_points(const sasnav_pair *pr, int level);

/* Suspends (on = 1) or restores (0) the search's equalising weights
 * (opts.equalise) and forgets the kept evaluations, which were made with
 * the other criterion. Nothing where the pair is not equalised. */
void pair_equalise_suspend(sasnav_pair *pr, int on);

/* The joint misfit (docs/estimator.md, "A joint-misfit final stage") at
 * the hypothesised error on the final level's grid: one scene s explains
 * both pings, s = argmin ||phi_p - T_p s||^2 + ||phi_q - T_q s||^2 + lam
 * ||s||^2 by opts.joint_k CGLS iterations on the two operators stacked;
 * r (pair_joint_len entries) = (phi_p - T_p s, phi_q - T_q s, sqrt(lam) s)
 * / ||phi||, *f = ||r||. pair_joint_tikhonov gives lam = joint_mu ||T^H
 * phi||^2 / ||phi||^2 at a hypothesis (fixed for a whole stage, so that
 * the misfit is one function of the hypothesis). */
size_t pair_joint_len(const sasnav_pair *pr);
/* The intensity contrast (standard deviation over mean of |rho_p|^2 over
 * the error window) of p's reconstruction at level 1: ~1 for speckle, far
 * above for a few bright points. */
double pair_contrast(const sasnav_pair *pr);
/* The same contrast of q's reconstruction (level 1, its iterations) with
 * q placed at the motion error `error` (one CGLS: 2 k applications); q's
 * operator is placed back where it was (left at `error` if it had not
 * been placed). */
int pair_contrast_q(sasnav_pair *pr, sasnav_pose error, double *contrast);
int pair_joint_tikhonov(sasnav_pair *pr, sasnav_pose error, double *lam);
int pair_eval_joint(sasnav_pair *pr, sasnav_pose error, double lam, sasnav_cfloat *r, double *f);

/* The estimators that may evaluate hypotheses at once: w[0] = pr and up
 * to want - 1 twins (the same data, geometry and options but one thread,
 * made at the first call that needs them and dropped with new data), whose
 * evaluations are the same bits as the estimator's own. Returns how many
 * (at least 1): at most want, the estimator's threads (opts.nthreads, or
 * all) and PAIR_MAX_WORKERS; 1 on the GPU path, inside a parallel region
 * (navigate's one pair per thread) or where no twin can be had (no
 * memory). */
int pair_workers(sasnav_pair *pr, int want, sasnav_pair **w);
/* Adds the twins' evaluations and operator applications since the last
 * call to the estimator's own counts. */
void pair_twin_merge(sasnav_pair *pr);
/* fn(worker, j, ctx) for j = 0 .. n - 1, item j on worker j % W of
 * pair_workers(pr, n) (each worker on a thread of its own, its items in
 * order; fn must write only item j's outputs). The counts merged after.
 * Returns the error of the lowest item that failed (with its message);
 * a worker stops at its first error, the others go on. */
int pair_batch(sasnav_pair *pr, int n, int (*fn)(sasnav_pair *w, int j, void *ctx), void *ctx);

/* Forget the values a level keeps (and its last psi): after a batch whose
 * points pr evaluated only in part (the rest on twins), so that what pr
 * evaluates next costs the same whatever the number of workers. */
void pair_forget(sasnav_pair *pr, int level);

/* Along-track position of channel l's phase centre (the midpoint of its
 * transmitter and receiver) in the frame of the ping geometry g. */
static inline double pair_phase_centre_x(const sasnav_array *array, const sasnav_ping_pose *g, int l)
{
    double xr, yr;
    sasnav_pose_apply(g->array, array->rx_u[l], 0.0, &xr, &yr);
    return 0.5 * (xr + g->tx.x);
}

#endif
