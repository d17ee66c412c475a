/* sasnav -- multi-ping refinement of a trajectory in the data domain.
 *
 * The pair estimator compares single-ping images, and one ping's phase
 * centres sample the array every d (2.5 cm in the tank), far coarser than
 * lambda / 4: each single-ping image of a compact target carries a grating
 * lobe that agrees between two pings only where their phase centres
 * coincide, which pulls the surge of nearly-coincident pairs towards the
 * nominal step (docs/estimator.md, "Known weakness"). Many pings together
 * fill the aperture and their common scene has no such ghost. The
 * refinement uses that scene:
 *
 *   for each sweep, for each ping q in turn (Gauss-Seidel):
 *     1. s = argmin sum_{p != q} ||T_p s - phi_p||^2 + mu ||W^1/2 s||^2,
 *        the regularised least-squares reflectivity on a scene grid
 *        explaining every other ping at its current pose (conjugate
 *        gradients on the normal equations, warm-started from the previous
 *        ping's scene; mu = damping x the Rayleigh quotient of the first
 *        direction; W = 1 for the first scene, then reweighted from the
 *        last scene, W_i = 1 / (|s_i|^2 / mean |s|^2 + sparsity), so that
 *        the scene is drawn towards a few strong scatterers and cannot
 *        absorb a pose error by smearing them: without it the phases of
 *        8 pings never settle, docs/navigation.md).
 *        The warm start held q's data and cg_iterations do not remove
 *        all of it, so q stays partly anchored where it was: the fit is
 *        between a leave-one-out and a joint one, and that anchoring is
 *        what keeps it stable: with cg_iterations = 40 an 8-ping run
 *        drifts apart along the track, and with scenes solved from zero
 *        its second sweep is undone (docs/navigation.md, "Why the sparse
 *        phases refined poorly");
 *     2. ping q's pose is moved rigidly along its own array axis (surge)
 *        and across it (sway) to minimise the normalised misfit
 *          c(u, v) = 1 - |<phi_q, T_q(u, v) s>|^2 / (||phi_q||^2 ||T_q s||^2)
 *        (the best complex scale of the prediction is free): in the first
 *        sweep a grid search over +-surge_range x +-sway_range (steps of
 *        surge_range / 12 and sway_range / 6) and a local polish (NLopt
 *        BOBYQA), in later sweeps BOBYQA alone within four times the
 *        previous sweep's rms move (at least 1 mm, 0.5 mm), never further
 *        than the ranges from the input pose;
 *   a sweep whose mean misfit (over the pings, at their chosen poses) is
 *   more than 10% above the previous sweep's is undone and ends the
 *   refinement (on short runs the sweeps can drift apart instead of
 *   converging, docs/navigation.md); then every pose is moved back by the
 *   mean of the moves (a common
 *   translation of all pings and the scene is not observable: the
 *   refinement keeps the input's mean position). Sweeps stop early when
 *   the rms move of a sweep falls below stop_move.
 * Yaw is left as it is (held: a yaw error is nearly a surge error on a
 * compact scene).
 *
 * The input must already be within the search ranges of the truth (a pair
 * navigation, sasnav_navigate): sway within about lambda / 4 (the misfit
 * has fringes of lambda / 2 across the line of sight).
 *
 * Cost: sweeps x pings x (cg_iterations x 2 (n_pings - 1) operator
 * applications + about 400 single-ping predictions). Memory: one operator
 * per ping on the scene grid (about 28 bytes per pixel and channel at the
 * default tolerance 1e-3), e.g. 160 MB for 32 pings of 8 channels on
 * 22,000 pixels.
 *
 * Threads: re-entrant for distinct outputs (nav_out may equal nav_in); the
 * run is only read. OpenMP over pings and trial poses with opts.nthreads
 * threads (0 = omp_get_max_threads() at the call), each operator on one
 * thread; it makes one operator per ping plus one per thread (FFTW planning
 * under the lock of op.h). The library never prints. */
#ifndef SASNAV_REFINE_H
#define SASNAV_REFINE_H
#include "sasnav/image.h"
#include "sasnav/op.h"
#include "sasnav/run.h"

#include <stdint.h>
#ifdef __cplusplus
extern "C" {
#endif

#define SASNAV_REFINE_MAX_SWEEPS 32

typedef struct sasnav_refine_state sasnav_refine_state;

typedef struct {
    sasnav_grid grid;     /* scene grid, world frame; nx = 0 (default): the
                             nominal track's along-track extent x the range
                             of interest +-0.35 m, 5 mm pixels (pixels must
                             sample the scene's band: see docs/navigation.md) */
    int sweeps;           /* maximum sweeps over the pings (default 8, <= 32) */
    int cg_first;         /* CG iterations of the first scene (default 40) */
    int cg_iterations;    /* CG iterations of each later, warm-started scene
                             (default 12) */
    double damping;       /* mu relative to the normal operator's scale
                             (default 1e-3) */
    double surge_range;   /* m, half-width of the surge search (default 0.012);
                             both ranges also bound each ping's total move
                             from its input pose */
    double sway_range;    /* m, half-width of the sway search (default 0.0015:
                             inside lambda / 4 of the tank's 105 kHz, so that
                             the search cannot hop a fringe) */
    double stop_move;     /* m, stop when a sweep's rms move is below this
                             (default 5e-5) */
    double sparsity;      /* eps of the reweighted damping (default 0.01):
                             after each scene, pixel i is damped by
                             mu / (|s_i|^2 / mean |s|^2 + eps) in the next,
                             i.e. iteratively reweighted least squares
                             towards a scene of few strong scatterers;
                             0: uniform damping mu */
    sasnav_op_opts op;    /* operator options (default tolerance 1e-3) */
    int nthreads;         /* OpenMP threads (0 = OpenMP default) */
    /* Checkpoints (docs/cli.md, "Resuming"): */
    void (*sweep_done)(const sasnav_refine_state *state, void *user);
                          /* called after every completed sweep with the
                             state to resume from (may be NULL); the
                             state's arrays are valid during the call */
    void *sweep_user;     /* passed to sweep_done */
    const sasnav_refine_state *resume; /* continue from this state (one
                             that sweep_done was given, e.g. read back with
                             sasnav_refine_state_read) instead of from the
                             input: the same bits as a refinement that was
                             never interrupted. It must be of the same run,
                             input navigation and options (its digest):
                             else SASNAV_ERR_ARG. Default NULL */
} sasnav_refine_opts;

void sasnav_refine_default_opts(sasnav_refine_opts *opts);

typedef struct {
    int sweeps;                                 /* sweeps made */
    double misfit[SASNAV_REFINE_MAX_SWEEPS + 1]; /* mean misfit c over the pings
                                                   before sweep i (i = 0: the
                                                   input), at the sweep's
                                                   chosen pose */
    double rms_move[SASNAV_REFINE_MAX_SWEEPS];  /* m, rms (surge, sway) move of
                                                   sweep i */
    int undone;                                 /* 1: the last sweep tried
                                                   raised the mean misfit by
                                                   more than 10% and was
                                                   undone (not counted) */
    double mean_move_surge, mean_move_sway;     /* m, the common move removed */
    double seconds;
    int unreliable;                             /* 1: the input's mean misfit
                                                   (misfit[0]) is above
                                                   SASNAV_REFINE_MISFIT_MAX:
                                                   the scenes do not explain
                                                   the pings (an extended,
                                                   speckle-like scene), and
                                                   the moves are not to be
                                                   trusted (docs/navigation.md) */
} sasnav_refine_report;

/* Mean misfit above which a refinement is reported unreliable: the tank's
 * compact scenes sit at 0.004-0.12 (docs/navigation.md), paper-trajectory's
 * extended speckle scene at 0.75. */
#define SASNAV_REFINE_MISFIT_MAX 0.3

/* The state of a refinement after a completed sweep. */
struct sasnav_refine_state {
    uint64_t digest;             /* of the run, the input navigation and the
                                    options (thread count and callbacks
                                    aside): what the state belongs to */
    int n_pings;
    int n_pixels;                /* of the scene grid */
    int sweeps_done;             /* sweeps completed (= report.sweeps) */
    int finished;                /* 1: no sweep is left (the stop rule or
                                    the sweep count ended the refinement) */
    double mu;                   /* absolute scene damping in use */
    sasnav_ping_pose *poses;     /* n_pings: current poses */
    double *move_u, *move_v;     /* n_pings: accumulated surge / sway moves */
    sasnav_cfloat *scene;        /* n_pixels: the last scene (warm start) */
    float *weights;              /* n_pixels: the reweighted damping */
    sasnav_refine_report report; /* so far (seconds: of the sweeps so far) */
};

/* Frees the arrays of a state made by the I/O layer
 * (sasnav_refine_state_read) and zeroes it; safe on NULL. */
void sasnav_refine_state_free(sasnav_refine_state *state);

/* Refines the ping poses `nav_in` (n = run->n_pings >= 3, world frame) of
 * `run` into `nav_out` (may equal nav_in). `opts` and `report` may be
 * NULL. Errors: SASNAV_ERR_ARG (bad run, options or grid, fewer than 3
 * pings), SASNAV_ERR_NOMEM, SASNAV_ERR_FFT, SASNAV_ERR_GEOMETRY (a sensor
 * on a pixel), SASNAV_ERR_ARG also for a ping with no signal,
 * SASNAV_ERR_NO_OVERLAP (a scene grid that no ping reaches). nav_out is written only on success. */
int sasnav_refine(const sasnav_run *run, const sasnav_ping_pose *nav_in,
                  const sasnav_refine_opts *opts, sasnav_ping_pose *nav_out,
                  sasnav_refine_report *report);

/* Told after each window of sasnav_refine_windows: windows done / in all,
 * and that window's report. */
typedef void (*sasnav_refine_window_fn)(int done, int total, const sasnav_refine_report *window,
                                        void *user);

/* sasnav_refine of a long run in windows of `window` consecutive pings
 * (>= 3), each starting window / 2 pings after the last (the last one ends
 * at the run's last ping), so that memory and the cost per sweep are those
 * of one window whatever the run's length; `run` may be streamed
 * (sasnav_run_open: each window's pings are read into memory in turn).
 * Each window is refined from nav_in as sasnav_refine does (its scene grid
 * the window's own when opts->grid is the default). The windows' moves are
 * joined: each window's common move is not observable (sasnav_refine
 * removes it), so window k is shifted by the mean difference between its
 * moves and window k - 1's over the pings they share; each ping takes its
 * move from the window whose centre is nearest; the mean of all moves is
 * removed (the input's mean position kept, as sasnav_refine). The shifts
 * are a random walk over the windows: on long runs the moves can drift
 * slowly along the run (docs/navigation.md, "Windows").
 * window <= 0 or >= run->n_pings: one window, the same bits as
 * sasnav_refine on the run in memory (checkpoints allowed). With several
 * windows opts->sweep_done and opts->resume must be NULL (SASNAV_ERR_ARG).
 * The report: sweeps = the most of any window; misfit[i] the mean over
 * the windows of their misfit after sweep i (a window that stopped earlier
 * counts with its last); rms_move[i] the rms over the windows (0 for one
 * that stopped); undone and unreliable: any window's; mean_move_*: the
 * common move removed from the joined moves, along and across the run's
 * mean heading; seconds: all. `done` (may be NULL) is called after each
 * window. Errors: those of sasnav_refine and of sasnav_run_subset. */
int sasnav_refine_windows(const sasnav_run *run, const sasnav_ping_pose *nav_in, int window,
                          const sasnav_refine_opts *opts, sasnav_ping_pose *nav_out,
                          sasnav_refine_report *report, sasnav_refine_window_fn done, void *user);

#ifdef __cplusplus
}
#endif
#endif
