/* sasnav -- the validation method of the paper's tank experiment (Sec. V-B
 * to V-E, SPEC 4 "tank"), for runs without an independent ground truth.
 *
 * With N receivers and a ping step of m phase-centre spacings d (the tank:
 * m = 1, K = N - 1 = 7 phase centres shared by consecutive pings), taking
 * every s-th ping gives runs with K = N - m s shared phase centres and s
 * phases (first ping 0..s-1). sasnav_validate
 *   1. navigates every phase of every K in [k_min, k_max] (consecutive pairs
 *      of the sub-sampled run, and with opts.nav.long_baselines the pairs two
 *      steps apart where they share phase centres; sasnav_navigate without
 *      alignment);
 *   2. combines the phases of a K into one trajectory of all pings: the
 *      phase starting at ping 0 of the largest K is the reference (it starts
 *      at the run's nominal first ping); every other phase, whose start is
 *      not observable, is placed by the rigid motion (rotation and
 *      translation, least squares) that best matches it to the reference
 *      (to the nominal track for the reference's own other phases);
 *   3. aligns each combined trajectory to the track (sasnav_traj_align:
 *      rotation by minus the fitted track angle; the yaws then hold the
 *      array's yaw relative to the track);
 *   4. measures the agreement of the trajectories: the largest spread
 *      (max - min over K) of the along-track and cross-track positions;
 *   5. re-arranges the data into N SISO apertures (one receiver, every ping)
 *      and s0 = N / m SIMO apertures (every s0-th ping, every receiver: the
 *      K = 0 runs), images each with each trajectory (and with the nominal
 *      navigation, for comparison) and measures the pairwise normalised
 *      correlation |<a, b>| / (|a| |b|) of the complex images over the
 *      region around the reflectors (pixels within region_db of the peak of
 *      the mean magnitude).
 * Where the run holds the truth, it also reports the error of the largest
 * surge step (the tank's jump) and of the array's yaw relative to the track.
 *
 * The library never prints; progress goes through opts.nav.progress
 * (called for every pair of every phase).
 *
 * Threads: re-entrant for distinct outputs; the run is only read. OpenMP
 * through its parts: navigation with opts.nav.nthreads (navigate.h),
 * refinement with opts.refine_opts.nthreads (0: opts.nav.nthreads), the
 * images with opts.op.nthreads (op.h); 0 everywhere = omp_get_max_threads().
 * The progress callback follows navigate.h's rules. */
#ifndef SASNAV_VALIDATE_H
#define SASNAV_VALIDATE_H

#include "sasnav/image.h"
#include "sasnav/navigate.h"
#include "sasnav/refine.h"

#ifdef __cplusplus
extern "C" {
#endif

#define SASNAV_VALIDATE_MAX_K 16

typedef struct {
    int k_min, k_max;          /* overlaps to test (default 4 and 0 = the run's
                                  own, N - m) */
    sasnav_navigate_opts nav;  /* per-phase navigation (align is forced off;
                                  nav.long_baselines adds the pairs two
                                  steps apart within each sub-sampled run,
                                  combined by least squares; nav.resolve
                                  defaults to 0 here: each pair's estimate
                                  chained, the paper's method, without the
                                  vehicle motion model of the joint
                                  resolution) */
    sasnav_grid grid;          /* image grid; nx = 0 (default): the track's
                                  along-track extent, range of interest
                                  +-0.35 m, 5 mm pixels */
    double region_db;          /* compared region, dB below the peak of the
                                  mean magnitude (default 12) */
    sasnav_op_opts op;         /* backprojection options */
    int refine;                /* 1: refine every phase's trajectory on the
                                  phase's own pings with the multi-ping
                                  data-domain fit (refine.h) before placing
                                  it; 0 (default): the paper's pair
                                  trajectories only */
    sasnav_refine_opts refine_opts; /* its options (grid: the image grid) */
} sasnav_validate_opts;

void sasnav_validate_default_opts(sasnav_validate_opts *opts);

/* One overlap K. */
typedef struct {
    int k;                     /* shared phase centres */
    int stride;                /* ping stride s */
    int n_phases;              /* = stride */
    int n_pairs;               /* pairs estimated over all phases */
    sasnav_navigate_pair *pairs; /* their results (p, q in the run's indices) */
    int n_failed;              /* pairs whose estimate failed (nominal used) */
    int n_flagged;             /* pairs whose verdict is not "ok" (ambiguous,
                                  failed), used as estimated */
    sasnav_pose *centroids;    /* n_pings combined, aligned centroids (refined
                                  when opts.refine) */
    sasnav_pose *centroids_pairs; /* the same from the pair estimates alone */
    double track_angle;        /* rad, removed by the alignment */
    sasnav_pose rms_error;     /* vs the truth (aligned the same way, first
                                  centroids made to coincide); 0 without */
    sasnav_pose rms_error_pairs; /* the same for centroids_pairs */
    int refine_sweeps;         /* refinement sweeps over all phases */
    double refine_seconds;     /* wall time of the refinements */
    double seconds;
} sasnav_validate_k;

typedef struct {
    int n_pings, n_k;
    sasnav_validate_k k[SASNAV_VALIDATE_MAX_K]; /* largest K first */
    double surge_spread;       /* m, max over pings of (max - min over K) of
                                  the along-track position */
    double sway_spread;        /* m, the same across track */
    double surge_spread_pairs, sway_spread_pairs; /* the same for the pair
                                  trajectories (equal without opts.refine) */
    int surge_spread_ping;     /* the ping where surge_spread is reached */
    int surge_spread_k[2];     /* the K whose positions there are lowest and
                                  highest along track */
    int sway_spread_ping;      /* the ping where sway_spread is reached */
    int has_truth;
    int jump_p;                /* the largest true surge step is (jump_p,
                                  jump_p + 1) */
    double surge_jump_error;   /* m, its estimate's error (largest K) */
    double yaw_estimate;       /* rad, mean aligned yaw (largest K): the
                                  array's yaw relative to the track */
    double yaw_error;          /* rad, yaw_estimate - the truth's */
    /* Images: n_images = n_k * (N + s0) navigated, then N + s0 made with
     * the nominal navigation, then (runs with truth) N + s0 made with the
     * true navigation. Image i is images + i * nx * ny. */
    sasnav_grid grid;
    int n_siso, n_simo;        /* N and s0 */
    int n_images;
    sasnav_cfloat *images;
    int *image_k;              /* K of the trajectory, -1 nominal, -2 truth */
    int *image_simo;           /* 0: SISO receiver j; 1: SIMO set j */
    int *image_index;          /* j */
    int n_region;              /* pixels compared */
    double *correlation;       /* n_nav x n_nav, n_nav = n_k * (N + s0) */
    double min_correlation;    /* over all navigated pairs */
    double min_correlation_siso, min_correlation_simo, min_correlation_cross;
    double min_correlation_nominal; /* among the nominal-navigation images */
    double min_correlation_truth;   /* among the true-navigation images (NAN
                                       without truth): what the method can
                                       reach with perfect navigation */
    double seconds;
} sasnav_validation;

/* Runs the validation. Needs a run whose nominal step is a whole number m of
 * phase-centre spacings (1 for the tank), at least 2 receivers and enough
 * pings for 2 pings per phase. Errors: SASNAV_ERR_ARG (geometry, options),
 * SASNAV_ERR_NOMEM, and those of sasnav_navigate and sasnav_backproject.
 * On failure `out` holds no memory. */
int sasnav_validate(const sasnav_run *run, const sasnav_validate_opts *opts,
                    sasnav_validation *out);

void sasnav_validation_free(sasnav_validation *v);

#ifdef __cplusplus
}
#endif
#endif
