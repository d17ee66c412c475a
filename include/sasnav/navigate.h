/* sasnav -- navigation of a whole run from ping-pair estimates (paper
 * Section IV-C, SPEC 4 paper-trajectory).
 *
 * sasnav_navigate estimates the displacement of every consecutive ping pair
 * (p, p + 1) of a run, with the subspace-intersection estimator
 * (estimator.h) or the DPCA baseline (dpca.h), and optionally of the longer
 * baselines (p, p + 2). It then
 *   0. resolves the consecutive pairs jointly over the run and fuses them
 *      with the run's aiding measurements (docs/navigation.md,
 *      "Resolution over the run"): a Viterbi choice among each pair's
 *      candidates (their eta, the aiding, a motion model of the vehicle),
 *      a new estimate from the chosen candidate where it is not the
 *      pair's own, a new estimate from the aiding's (or the motion
 *      model's) prediction for failed pairs and pairs that disagree with
 *      the aiding, then a robust least-squares smoother of the motion
 *      errors (estimates, aiding, motion model): the fused motion errors;
 *   1. turns them into PCA-centroid poses: the chain composed from the
 *      run's nominal first centroid (sasnav_traj_compose) or, with long
 *      baselines, the weighted least-squares solution over all links
 *      (sasnav_traj_solve, same gauge);
 *   2. aligns the centroids to the nominal track (sasnav_traj_align): the
 *      fitted track angle is removed by a rigid rotation about the first
 *      centroid and reported;
 *   3. places the EPCA ping geometry (run->tx_lag) at each centroid
 *      (sasnav_traj_ping_poses): these are the estimated ping poses;
 *   4. where the run holds the truth: the true motion error of every pair
 *      and the estimate's error, and the cumulative / differential errors of
 *      the trajectory (sasnav_traj_errors) against the true centroids
 *      carried rigidly into the estimate's frame so that the first
 *      centroids coincide (the first pose is the gauge: a pair estimator
 *      cannot know it).
 *
 * Motion error = displacement - nominal displacement (component-wise,
 * surge, sway, yaw), nominal = displacement between the run's own /nav
 * poses.
 *
 * Failed pairs. An estimate that cannot be made (the estimator reports no
 * overlap, bad channel data, a DPCA geometry it refuses...) does not stop
 * the navigation: the pair's status holds the code, its displacement is
 * taken as nominal (motion error 0) and n_failed counts it. Out of memory,
 * FFTW and internal errors stop it and are returned.
 *
 * Long baselines (p, p + 2) are estimated only when at least two phase
 * centres of the two pings nominally overlap; in paper-trajectory (20 cm
 * ping spacing, 40 cm of phase centres) they share none and are skipped
 * (n_skipped).
 *
 * The library never prints: progress is reported through the optional
 * callback in the options.
 *
 * Threads: re-entrant for distinct outputs; the run is only read. OpenMP
 * with opts.nthreads threads (0 = omp_get_max_threads() at the call; at most
 * 2 n_pings, one below 3 pings). With several, the pairs are estimated
 * concurrently, one estimator per thread with single-threaded operators;
 * with one, the operators use it. Same bits whatever the count. The progress
 * callback may run on any of those threads, never two at once (`done`
 * counts pairs in the order they finish). FFTW planning: op.h.
 */
#ifndef SASNAV_NAVIGATE_H
#define SASNAV_NAVIGATE_H

#include "sasnav/dpca.h"
#include "sasnav/estimator.h"
#include "sasnav/run.h"

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    SASNAV_METHOD_SUBSPACE = 0, /* subspace intersection (paper Section III) */
    SASNAV_METHOD_DPCA = 1,     /* DPCA baseline (Bellettini & Pinto 2002) */
    SASNAV_METHOD_AIDING = 2    /* no pair estimates: the run's aiding
                                   measurements and the motion model alone
                                   (dead reckoning; needs a gyro and a DVL,
                                   no long baselines; an interval either
                                   does not measure is "failed", its step
                                   the motion model's) */
} sasnav_method;

/* What the progress callback is told. Called once before the first pair
 * (done = 0, pair = NULL) and after every estimated pair. */
typedef struct {
    int done, total;     /* pairs estimated so far / to estimate */
    int p, q;            /* the pair just estimated (-1 before the first) */
    int status;          /* its status (SASNAV_OK or the failure code) */
    const sasnav_pair_result *result; /* its result (NULL before the first) */
    double seconds;      /* wall time since sasnav_navigate started */
    uint64_t key;        /* content key of the pair (below; 0 before the first) */
    int resumed;         /* 1: taken from opts.done, not estimated */
} sasnav_navigate_progress;

/* A pair estimated earlier, e.g. read back from a checkpoint (checkpoint.h): the first estimate of the pair whose content `key`
 * names. The key is a 64-bit hash of what the pair's first estimate
 * depends on: the two pings' samples and nominal poses, the run's
 * Tx-array offset (or the per-ping offsets in use), range of interest,
 * sound speed, carrier, band, sample rate, pulse taper, spreading model,
 * window, beam-pattern switch and array (receiver positions, apertures,
 * heights), for DPCA the ping spacing and q - p, the estimation method and
 * every option of its estimator (pair or dpca) but the thread counts.
 * Not covered: the code itself (keep records per sasnav version: the
 * checkpoint files do) and the aiding measurements, which the first
 * estimates do not use (except through per-ping offsets, covered).
 * Same pings in another sub-run (sasnav_validate's phases): same key. */
typedef struct {
    uint64_t key;              /* sasnav_navigate_progress.key of the pair */
    int p, q;                  /* its pings where it was estimated (informative) */
    int status;                /* the pair's first status */
    sasnav_pair_result result; /* the pair's first result */
} sasnav_pair_record;

/* How the joint resolution treated a pair (sasnav_navigate_pair.resolution). */
typedef enum {
    SASNAV_RESOLVED_NONE = 0,        /* the pair's own estimate, kept */
    SASNAV_RESOLVED_CANDIDATE = 1,   /* another candidate of the pair won the
                                        joint choice (aiding, motion model)
                                        and was estimated again from */
    SASNAV_RESOLVED_REESTIMATED = 2, /* estimated again from the aiding's or
                                        the motion model's prediction (the
                                        estimate failed or disagreed with
                                        the aiding) */
    SASNAV_RESOLVED_BRIDGED = 3      /* no usable estimate: the fused motion
                                        error comes from the aiding and the
                                        motion model alone */
} sasnav_resolution;

/* "kept", "candidate", "re-estimated", "bridged". */
const char *sasnav_resolution_name(int resolution);

typedef void (*sasnav_progress_fn)(const sasnav_navigate_progress *progress, void *user);

typedef struct sasnav_navigation sasnav_navigation;

typedef struct {
    sasnav_method method;     /* default SASNAV_METHOD_SUBSPACE */
    int long_baselines;       /* 1: also estimate (p, p + 2), combined by least
                                 squares (default 0) */
    sasnav_pair_opts pair;    /* subspace estimator options (defaults);
                                 range and tx_lag are replaced by the run's
                                 range_of_interest and tx_lag */
    sasnav_dpca_opts dpca;    /* DPCA options (defaults) */
    sasnav_pose link_sigma;   /* standard deviations of a consecutive pair's
                                 surge, sway, yaw in the least squares
                                 (default 1e-3 m, 2e-5 m, 5e-5 rad: the
                                 subspace estimator's measured spread, SPEC 6) */
    sasnav_pose long_sigma;   /* same for (p, p + 2) (default twice link_sigma:
                                 fewer phase centres overlap) */
    double link_eta;          /* with aiding fused, a consecutive pair's
                                 standard deviations in the smoother grow
                                 with its final eta above this: link_sigma
                                 x (eta / link_eta)^2, in the components
                                 the pair's aiding measures (surge and sway
                                 with a DVL, yaw with a gyro), so that the
                                 pairs of a noisy run weigh less against
                                 the aiding
                                 (their surge and sway errors grow about so
                                 with eta at low SNR, the yaw's less: a
                                 conservative factor there;
                                 docs/navigation.md, "Standard deviations
                                 that grow with eta"). Without aiding they
                                 stay link_sigma (the motion model is a
                                 loose bridge, not a measurement to weigh
                                 ok pairs against); the long baselines'
                                 least squares keeps long_sigma. Default
                                 0.2; 0 or +inf: off (the fixed
                                 link_sigma) */
    int align;                /* 1 (default): remove the fitted track angle */
    int resolve;              /* 1 (default): joint resolution and fusion of
                                 the consecutive pairs (step 0 above); 0:
                                 each pair's estimate alone (the paper's
                                 method) */
    int use_aiding;           /* 1 (default): fuse the run's aiding
                                 measurements when it has them */
    sasnav_pose motion_sigma; /* standard deviation of the change of the
                                 motion error from one pair to the next (the
                                 vehicle's changes of surge velocity and
                                 yaw rate over a ping interval; default
                                 0.01 m, 0.01 m, 0.01 rad: the agile
                                 paper-trajectory motion, docs/navigation.md) */
    double eta_weight;        /* weight of ln(eta / lowest eta) in the joint
                                 choice (default 20) */
    double aiding_gate;       /* an estimate further from the aiding than
                                 half a phase-centre slip (d / 2 of surge,
                                 d / (2 R) of yaw) plus this many of
                                 the aiding's standard deviations is
                                 estimated again from the aiding (default 5) */
    double eta_outlier;       /* a consecutive pair on a speckle-like scene
                                 (neither contrast above
                                 pair.verdict_contrast) whose final eta
                                 exceeds this multiple of the median eta of
                                 the run's such pairs (usable subspace
                                 estimates, "ok" or "ambiguous", at least
                                 6; their etas before the resolution) is
                                 "ambiguous" at best (also without the
                                 resolution): on one run the pairs share the
                                 system, the noise and the seabed
                                 statistics, so an eta far above theirs
                                 marks an estimate off the truth, or one
                                 whose scene differs (a bright feature on
                                 one ping's beam flank; docs/navigation.md,
                                 "Pairs whose eta stands out from the
                                 run's"). Default 1.6; must be > 1; +inf:
                                 off */
    int nthreads;             /* OpenMP threads of the estimators (0 = OpenMP
                                 default); copied into pair and dpca */
    int speed_lags;           /* per-ping EPCA Tx-array offsets scaled by the
                                 vehicle's speed at each ping (the offset is
                                 speed x two-way delay; docs/estimator.md,
                                 "Where the yaw errors come from"): 0 = the
                                 run's tx_lag for every ping; 1 (default) =
                                 from the DVL aiding when the run has it and
                                 use_aiding is on (no extra cost; otherwise
                                 as 0); 2 = the same, and without a DVL
                                 from the pairs' own surge in two passes:
                                 every pair first without its final stage
                                 (sasnav_pair_estimate_first), the offsets
                                 from their first surges, then every
                                 pair's final stage with them
                                 (sasnav_pair_finish; about the time of
                                 one pass; not with reuse, not for runs
                                 with channel offsets; docs/navigation.md,
                                 "Two passes"). The re-estimates of a
                                 reused navigation take the DVL's offsets
                                 too */
    sasnav_pose aiding_bias_sigma; /* standard deviation of a constant error
                                 of the aiding per ping interval (surge m,
                                 sway m, yaw rad), estimated jointly with
                                 the motion errors by the smoother: a DVL's
                                 bias and scale factor at a steady speed,
                                 a gyro's bias; 0 = none. Default 4e-4 m,
                                 4e-4 m, 0 rad: a DVL of 0.2 % scale factor
                                 at 2 m/s and 0.1 s per interval (set it to
                                 your DVL's scale-factor spec x the ping
                                 step); the fused table of
                                 docs/navigation.md ("Aiding bias") */
    int tx_yaw;               /* runs with channel offsets (transmitters of
                                 their own), subspace method: the vehicle's
                                 yaw between transmission and reception
                                 turns each transmitter (docs/model.md).
                                 1 (default): from the gyro when the run
                                 has one and use_aiding is on, otherwise
                                 from the pairs' own first estimates (the
                                 track's turn per metre times the distance
                                 tx_lag; every ok consecutive pair then
                                 estimated again, local stages; not with
                                 reuse); 2: from the pairs even with a
                                 gyro; 0: none (each transmitter keeps the
                                 array's heading) */
    const sasnav_navigation *reuse; /* a navigation of the same run by the
                                 same method and pair options: its pairs'
                                 first estimates (first_result) are used
                                 instead of estimating them again, e.g. to
                                 compare fusion settings (default NULL) */
    const sasnav_pair_record *done; /* pairs estimated earlier (resuming
                                 after an interruption): a pair whose key
                                 is here is taken from its record instead
                                 of being estimated, and reported to the
                                 progress callback with resumed = 1; the
                                 result is then the same bits as when it
                                 is estimated (same options). Keys absent
                                 from the run are ignored. Default NULL */
    int n_done;               /* entries of done */
    int compact_pairs;        /* 1: the pairs stay packed in the navigation
                                 (`pairs` is NULL; read them one at a time
                                 with sasnav_navigation_pair): about a third
                                 of the memory of `pairs` on long runs
                                 (docs/survey.md). 0 (default): `pairs` */
    sasnav_progress_fn progress; /* may be NULL */
    void *progress_user;      /* passed to progress */
} sasnav_navigate_opts;

/* Fills the defaults above. */
void sasnav_navigate_default_opts(sasnav_navigate_opts *opts);

/* One estimated pair. */
typedef struct {
    int p, q;
    int status;                /* SASNAV_OK, or the code that made it fail
                                  (then result.error = 0 was used) or the
                                  estimator's own status (result.status:
                                  SASNAV_ERR_NOT_CONVERGED keeps the estimate) */
    sasnav_pose nominal;       /* nominal displacement (from run->nav) */
    sasnav_pair_result result; /* the estimator's result (motion error in
                                  result.error) */
    sasnav_pose truth;         /* true motion error (0 without truth) */
    sasnav_pose error;         /* fused - truth (0 without truth) */
    /* Trust and fusion (consecutive pairs; long baselines keep their
     * estimate: fused = result.error): */
    int verdict;               /* sasnav_verdict of the estimate in `result`
                                  after the resolution (an estimate chosen
                                  or confirmed by the aiding is "ok") */
    int first_verdict;         /* the verdict before the resolution: the
                                  estimator's, or "ambiguous" for an "ok"
                                  estimate the eta-outlier rule marked */
    int resolution;            /* sasnav_resolution */
    sasnav_pose aiding;        /* aiding measurement of the motion error */
    sasnav_pose aiding_sigma;  /* its standard deviations (+inf: none) */
    sasnav_pose fused;         /* fused motion error (what the trajectory
                                  is built from) */
    sasnav_pair_result first_result; /* the estimate before the resolution */
    int first_status;          /* its status */
    int eta_outlier;           /* 1: its eta before the resolution
                                  (first_result.eta) exceeds
                                  opts.eta_outlier x the run's median (its
                                  verdict is then "ambiguous" at best) */
} sasnav_navigate_pair;

/* Output of sasnav_navigate; release the arrays with sasnav_navigation_free. */
struct sasnav_navigation {
    sasnav_method method;
    int n_pings;
    int n_pairs;                  /* entries of pairs[]: the n_pings - 1
                                     consecutive pairs first, then the long
                                     baselines (p, p + 2) that were estimated */
    sasnav_navigate_pair *pairs;  /* NULL with opts.compact_pairs: use
                                     sasnav_navigation_pair */
    int n_failed;                 /* pairs whose estimate failed (nominal used) */
    int n_flagged;                /* pairs whose final verdict is not "ok" or
                                     that were bridged */
    int n_resolved;               /* pairs the joint resolution changed
                                     (candidate, re-estimated, bridged) */
    int aiding_used;              /* 1: the run's aiding was fused */
    int n_skipped;                /* long baselines not estimated (< 2 phase
                                     centres overlap) */
    sasnav_pose *centroids;       /* n_pings estimated PCA centroids (aligned) */
    sasnav_ping_pose *nav;        /* n_pings estimated ping poses (EPCA geometry) */
    double track_angle;           /* rad, angle removed by the alignment (0 when
                                     opts.align = 0) */
    int lsq_iterations;           /* Gauss-Newton iterations (0: chain only) */
    /* Runs with truth (otherwise NULL / 0): */
    int has_truth;
    sasnav_pose *truth_centroids; /* true centroids moved rigidly so that the
                                     first coincides with centroids[0] */
    sasnav_ping_pose *anchored;   /* estimated ping poses moved rigidly so that
                                     the first centroid coincides with the
                                     true one (what an external fix of the
                                     first pose gives; compare images with it) */
    sasnav_pose *cumulative;      /* n_pings: centroids - truth_centroids
                                     (surge, sway along / across the aligned
                                     track, yaw); cumulative[0] = 0 */
    sasnav_pose *differential;    /* n_pings: error of the displacement of
                                     ping i relative to i - 1; [0] = 0 */
    sasnav_pose rms_cumulative;   /* rms over the pings of cumulative[] */
    sasnav_pose rms_differential; /* rms over pings 1.. of differential[] */
    /* Timings (wall clock, s): */
    double seconds;               /* the whole call */
    double seconds_pairs;         /* sum of the pair estimates */
    double seconds_per_pair;      /* seconds_pairs / pairs estimated */
    double seconds_estimation;    /* wall time of all pair estimates */
    double pairs_per_second;      /* n_pairs / seconds_estimation */
    int threads_over_pairs;       /* pairs estimated concurrently (1: one
                                     after the other) */
    void *packed;                 /* internal: the packed pairs
                                     (opts.compact_pairs), or NULL */
    int gyro_tx_yaw;              /* 1: a run with channel offsets whose
                                     layouts turned each transmitter by the
                                     gyro's yaw between transmission and
                                     reception (sasnav_run_tx_yaw) */
    int pairs_tx_yaw;             /* 1: such a run whose transmitters were
                                     turned by the yaw from the pairs' own
                                     first estimates (opts.tx_yaw) and its
                                     ok consecutive pairs estimated again */
    double eta_median;            /* median final eta (before the
                                     resolution) of the consecutive pairs
                                     the eta-outlier rule reads: usable
                                     subspace estimates, "ok" or
                                     "ambiguous", on speckle-like scenes
                                     (NaN: another method, fewer than 6,
                                     or opts.eta_outlier off) */
    int n_eta_outliers;           /* consecutive pairs over opts.eta_outlier x
                                     eta_median */
    sasnav_pose *formal_sigma;    /* n_pings formal standard deviations of
                                     centroids[] relative to the first (along,
                                     across the aligned track, yaw; world x,
                                     y with opts.align 0; [0] = 0): the
                                     smoother's posterior (its standard
                                     deviations of the pairs, the aiding's
                                     and the motion model's, the Huber
                                     weights of its last solve) carried
                                     through the chain, linearised. NULL
                                     where no smoother ran (opts.resolve 0),
                                     where long baselines were estimated, for
                                     DPCA, and where a value overflowed. As right as the standard
                                     deviations it weighs with:
                                     docs/navigation.md, "Formal standard
                                     deviations" */
};

/* Pair j (0 <= j < n_pairs) of `nav`, whether its pairs are packed
 * (opts.compact_pairs) or not: copied into *np. Returns SASNAV_OK or
 * SASNAV_ERR_ARG (NULL argument, j out of range, no pairs). */
int sasnav_navigation_pair(const sasnav_navigation *nav, int j, sasnav_navigate_pair *np);

/* Navigates `run` (at least 2 pings, validated with sasnav_run_check).
 * `opts` may be NULL (defaults). `out` is overwritten (not freed first).
 * Returns SASNAV_OK (inspect n_failed), SASNAV_ERR_ARG (bad run or
 * options; DPCA on a run whose consecutive pairs it cannot pair up is
 * reported per pair, not here), SASNAV_ERR_NOMEM, SASNAV_ERR_FFT,
 * SASNAV_ERR_INTERNAL, SASNAV_ERR_GEOMETRY (singular least squares,
 * coincident centroids when aligning), SASNAV_ERR_NOT_CONVERGED (least
 * squares iterations exhausted). On failure `out` holds no memory. */
int sasnav_navigate(const sasnav_run *run, const sasnav_navigate_opts *opts,
                    sasnav_navigation *out);

/* One part of a navigation spread over processes or nodes (e.g. the ranks
 * of `mpirun -np N sasnav navigate`). Estimates the first estimates of the
 * pairs of part `part` (0 <= part < n_parts): pair j of the output order
 * (consecutive pairs, then the long baselines) when j % n_parts == part,
 * interleaved so that every part gets early and late pairs alike. Returns
 * them as records in *records (malloc'd, free() it; *n_records entries;
 * pairs taken from opts->done count too). The navigation is then
 * sasnav_navigate with opts->done = the records of all parts: no pair is
 * estimated again and the result is the same bits as one sasnav_navigate
 * of the whole run (the keys and results do not depend on the process or
 * the thread count). What sasnav_navigate does after the first estimates
 * (the speed-lags second pass, re-estimates of the joint resolution) runs
 * in that last call. Same options and errors as sasnav_navigate;
 * SASNAV_ERR_ARG also for a bad part. The progress callback counts the
 * part's pairs. */
int sasnav_navigate_part(const sasnav_run *run, const sasnav_navigate_opts *opts, int part,
                         int n_parts, sasnav_pair_record **records, int *n_records);

/* Frees the arrays of `nav` and zeroes it. Safe on NULL and on a zeroed
 * struct. */
void sasnav_navigation_free(sasnav_navigation *nav);

#ifdef __cplusplus
}
#endif
#endif
