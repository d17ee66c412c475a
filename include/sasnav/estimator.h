/* sasnav -- the subspace-intersection ping-pair estimator (paper Section III,
 * SPEC 3).
 *
 * For pings p and q and a hypothesised displacement sigma of q's PCA centroid
 * in p's centroid frame:
 *   rho_p = T_p^+ phi_p,  rho_q(sigma) = T_q(sigma)^+ phi_q     (CGLS, k its)
 *   Q(sigma) x = T(sigma)^+ T(sigma) x                        (projector)
 *   psi_p = (Q_p Q_q)^i rho_p,  psi_q = (Q_q Q_p)^i rho_q     (intersection)
 *   zeta = || |psi_p| - |psi_q| || / nrm,  eta = || psi_p - psi_q || / nrm.
 * sigma moves q's sensors (T_q(sigma) is rebuilt); images are never resampled.
 * Each ping is modelled by its EPCA geometry (paper III-B): array tx_lag/2
 * ahead of the centroid, Tx tx_lag/2 behind, so that the centroid is the PCA
 * centroid of SPEC 1.
 *
 * Search (docs/estimator.md): a global stage (image-shift valley scan of
 * zeta, then BOBYQA from NLopt at coarse pixels), a local stage on zeta and
 * one on eta at coarse iterations (Levenberg-Marquardt on the residual
 * vectors whose norms zeta and eta are, with a check of the neighbouring
 * sway fringes: eta oscillates along sway with period lambda/2), then a
 * Newton step at the final iterations (k, i) on the quadratic model of eta
 * measured from ten residual vectors.
 *
 * Threads: distinct estimator objects may be used concurrently, one object
 * by one thread at a time (sasnav_navigate runs one per thread over pairs);
 * the sasnav_system / array / window and data passed in may be shared
 * read-only. It uses opts.nthreads OpenMP threads (0 =
 * omp_get_max_threads() at create): with one, both projection chains of
 * an evaluation go through each operator at once; with two or three,
 * single evaluations run the chains side by side, one thread each; with
 * four or more, both chains through each operator, each application
 * shared by four threads; with two or more the searches' batches of
 * hypotheses (the global stage's image shifts and valley scan, LM
 * Jacobians, the candidates' and slip points' local stages, the final
 * model's ten points) are evaluated as many at a time as there are
 * threads (up to ten), on the estimator and one-thread twins of it (made
 * at the first batch, about 22 MiB each on the paper pair; none inside
 * another parallel region, nor on the GPU path). Results do not depend on
 * that number.
 * create, set_data (it rebuilds the operators) and destroy plan FFTW under
 * the planner lock of op.h.
 */
#ifndef SASNAV_ESTIMATOR_H
#define SASNAV_ESTIMATOR_H

#include "sasnav/image.h"
#include "sasnav/op.h"
#include "sasnav/run.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    SASNAV_NORM_MAX = 0, /* max(||psi_p||, ||psi_q||) (default) */
    SASNAV_NORM_P = 1,   /* ||psi_p|| */
    SASNAV_NORM_Q = 2,   /* ||psi_q|| */
    SASNAV_NORM_NONE = 3
} sasnav_norm;

/* The grid of the search stages before the final one (opts.search_grid;
 * docs/estimator.md, "The search stages on the coarse grid"). The final
 * stage and the overlap check are at full pixels whatever this says, and
 * without a final stage (k, i equal to coarse_k, coarse_i) so is the
 * search. */
typedef enum {
    SASNAV_SEARCH_AUTO = 0,  /* COARSE on speckle-like scenes (the contrast of p's
                                reconstruction at most joint_contrast_max), FINE
                                on a few bright reflectors (default) */
    SASNAV_SEARCH_FINE = 1,  /* full pixels (every scene before this option) */
    SASNAV_SEARCH_COARSE = 2 /* the global stage's coarse pixels: 1.25x faster
                                on seabed pairs (two threads), the same final
                                estimates to 0.1 mm rms there; on the tank's
                                compact scene it slips (tests/test_tank_pairs.c) */
} sasnav_search_grid;

/* "auto", "fine", "coarse" ("unknown" otherwise). */
const char *sasnav_search_grid_name(int grid);
/* The grid named "auto", "fine" or "coarse"; -1 for any other name. */
int sasnav_search_grid_parse(const char *name);

typedef struct {
    int k;                 /* CGLS iterations of the final stage (default 8; the
                              paper used 5) */
    int i;                 /* alternating-projection iterations (default 8) */
    int coarse_k, coarse_i;/* iterations of the global and zeta stages (default 2, 1) */
    double tikhonov;       /* CGLS Tikhonov weight (default 0) */
    sasnav_norm norm;
    double tx_lag;         /* m, EPCA Tx-array offset (default 0.10) */
    double range;          /* m, centre range of the estimation grid (default 10) */
    double range_extent;   /* m, range extent of the grid (default 1.6; 0.8
                              halves the cost but separates yaw from surge
                              worse: docs/estimator.md, "Search cost") */
    double cross_extent;   /* m, along-track extent of the grid (default 0: 80 %
                              of the element beam's footprint between first
                              nulls at the grid's range, 1.6 R lambda / D,
                              1.6 m in paper-pair) */
    double pixel;          /* m, pixel size (default: min(D/4, c/(4B))) */
    double coarse_pixel;   /* m, pixel of the global stage (default 2 * pixel) */
    int search_grid;       /* sasnav_search_grid: the grid of the search
                              stages (valley scan, zeta stage, first eta
                              stage, slip check); default AUTO */
    double blur;           /* m, range sigma of the Gaussian blur of the global
                              stage's moduli (default 0.075) */
    double blur_cross;     /* m, along-track sigma of that blur (default 0: the
                              cross-range detail separates the true yaw from
                              its grating-lobe ambiguity) */
    sasnav_pose prior;     /* prior motion error (default 0) */
    sasnav_pose box;       /* half-widths of the search box around the prior
                              (default 0.06 m, 0.035 m and, for yaw, 0 = auto:
                              90 % of lambda / (4 d), d the phase-centre
                              spacing, i.e. 0.045 rad in paper-pair) */
    double yaw_sigma;      /* rad, standard deviation of a prior on the yaw
                              error (e.g. a gyro's, or a rail's), 0 = none
                              (default). Resolves the surge-yaw ambiguity
                              of compact scenes (docs/estimator.md): points
                              of the valley one phase-centre spacing d of
                              surge and d / R of yaw apart look alike when
                              the scene spans little range. */
    double surge_sigma;    /* m, scale of a prior on the surge error (the
                              nominal step's accuracy: a plotter, a DVL),
                              0 = none (default). The global stage ranks
                              its candidates by zeta (1 + (surge / sigma)^2):
                              on compact scenes seen at a squint the
                              candidates one spacing d apart along the
                              weakly observed direction look alike and
                              zeta leans to the one sharing more phase
                              centres (docs/estimator.md). */
    int fix_yaw;           /* 1: hold the yaw error at prior.theta and estimate
                              surge and sway only (a rail or plotter, or a
                              gyro far better than the scene's yaw
                              information; default 0) */
    sasnav_pose grid_step; /* steps of the global grid (default 0.01 m, 0.01 m, 0.01 rad) */
    int global_stage;      /* 1 (default): run the global stage; 0: local only */
    double error_extent;   /* m, along-track extent over which zeta and eta
                              compare the projections (0 = the whole grid) */
    double error_taper;    /* m, raised-cosine taper beyond it on each side */
    double min_overlap;    /* minimum ||psi_p|| / ||rho_p|| at full pixels before
                              "no overlap" (default 1e-2; ~0.5 at nominal
                              paper-pair, < 1e-3 once no phase centres overlap) */
    int max_evaluations;   /* per local stage (default 400) */
    double verdict_eta_max;   /* final eta above which the estimate is
                                 "failed" (default 0.6: docs/estimator.md,
                                 "Verdict") */
    double verdict_margin_min;/* search-grid eta of the best other candidate over
                                 the chosen one's below which the estimate
                                 is "ambiguous" (default 1.15) */
    double verdict_coincidence;/* on compact scenes (the intensity contrast of
                                 p's or q's reconstruction above
                                 verdict_contrast)
                                 an estimate whose along-track displacement
                                 lies within this fraction of the
                                 phase-centre spacing of a multiple of it
                                 shorter than the array (a phase-centre
                                 coincidence) is
                                 "ambiguous": there the criterion is drawn
                                 to the coincidence from up to 0.4 spacing
                                 away (docs/estimator.md, "Known weakness:
                                 attraction to phase-centre coincidence");
                                 default 0.5, i.e. every estimate whose
                                 phase centres overlap p's: on four tank
                                 scenes tolerances of 0.04-0.25 all left
                                 slipped pairs "ok" (docs/validation.md,
                                 "Flagged pairs"); 0 never */
    double verdict_margin_compact;/* on compact scenes, the margin below
                                 which the estimate is "ambiguous" (the
                                 larger of this and verdict_margin_min;
                                 default 1.25: the attraction's partial
                                 slips, 6.8-12.7 mm on the tank, came
                                 with margins of 1.16-1.64;
                                 docs/validation.md, "Flagged pairs") */
    int nthreads;          /* OpenMP threads (0 = default; see "Threads" above) */
    sasnav_op_opts op;     /* operator options (default: sasnav_op's, with
                              tolerance 1e-3: docs/estimator.md) */
    int gpu;               /* 1: the error evaluations on a CUDA GPU (builds
                              made with -DSASNAV_CUDA=ON; otherwise
                              SASNAV_ERR_UNSUPPORTED); 0 (default): the CPU.
                              Same criterion, agreeing to float rounding
                              (docs/estimator.md, "GPU") */
    int final_criterion;   /* the final stage's criterion (docs/estimator.md,
                              "A joint-misfit final stage"): SASNAV_FINAL_AUTO
                              (default), SASNAV_FINAL_ETA or SASNAV_FINAL_JOINT */
    int joint_k;           /* CGLS iterations of the joint misfit (default 40) */
    double joint_mu;       /* its Tikhonov weight relative to the normal
                              operator's Rayleigh quotient along the data
                              (default 1e-3) */
    double joint_shift_max;/* AUTO: the joint misfit when the pings' relative
                              yaw shifts the beam footprint at the grid's
                              range by at most this fraction of the grid's
                              along-track extent (default 0.125: 0.02 rad
                              in paper-pair), eta otherwise */
    double joint_contrast_max; /* AUTO: the joint misfit only where the
                              intensity contrast of p's reconstruction
                              (std / mean of |rho_p|^2 over the window) is
                              at most this (default 5: speckle-like
                              seabeds, not a few bright points) */
    double joint_eta_ratio;/* finite: the joint stage's estimate is kept
                              when eta there is at most this ratio of eta
                              at its start (one more level-2 evaluation),
                              otherwise eta's final stage runs from the
                              start; default INFINITY: no such check
                              (docs/estimator.md: on trajectory pairs it
                              did harm; the contrast rule keeps compact
                              scenes on eta's stage) */
    double verdict_contrast;  /* the verdict's compact-scene rules
                              (verdict_margin_compact, verdict_coincidence)
                              apply where the intensity contrast of p's
                              reconstruction, or of q's at the estimate
                              (result.contrast_q; since a bright feature
                              that q's beam sees and p's hardly pulled
                              pairs with "ok" verdicts), exceeds this (default 4: the
                              simulated seabeds reach 3.9 where a bright
                              patch fills the beam, and tank scenes of
                              contrast 4.6-5.0, under joint_contrast_max,
                              slipped with "ok" verdicts; docs/validation.md,
                              "Scenes just under the compact gate"); the
                              search grid and final stage keep
                              joint_contrast_max; INFINITY: never */
    double joint_coverage_min;/* AUTO: the joint misfit only where the grid's
                              along-track extent is at least this fraction
                              of the element beam's footprint between its
                              first nulls at the grid's range (default
                              0.5; the default grid covers 0.8 where the
                              4 m cap does not bind: the paper system at
                              10 m; 0.29 on the survey system at 70 m,
                              whose surge errors the joint stage doubled;
                              never with omnidirectional elements; 0:
                              always, the rule before) */
    double equalise;          /* m (default 0.05; 0: off): on a scene
                              speckle-like at the prior (the intensity
                              contrast of p's reconstruction and of q's
                              placed at the prior both at most 4, the
                              verdict's default gate; a constant, so
                              that verdict_contrast does not move the
                              estimates) where a feature stands out
                              (the peak of |rho_p|^2 + |rho_q|^2
                              smoothed over a fixed 5 cm, whatever
                              this sets, over the error window at
                              least 8 times its mean over the window;
                              smoothed speckle peaks at 2.5-5.6 times
                              on the simulated seabeds;
                              result.equalise_peak), the search
                              stages' criteria
                              (zeta and eta on the search grid: the
                              global stage's valley scan and its
                              refinement, not its image-shift
                              correlation; the zeta and first eta
                              stages; the slip check) weight each pixel
                              by 1 / sqrt(S + 0.1 mean S), S the two
                              images' intensity smoothed by a Gaussian
                              of this many metres (truncated at 127
                              pixels either side; the CLI takes at most
                              0.25 m), so that a feature 20 dB or more
                              above the seabed, seen by one ping's beam
                              and hardly by the other's, does not lead
                              the search into a wrong basin; the chosen
                              candidate then goes through an unweighted
                              eta stage, and the final stage, the
                              reported eta, the verdict's eta bound and
                              the overlap are never weighted; the
                              reported zeta, the candidates' zeta and
                              eta and the margin are the weighted
                              search's (result.equalised;
                              docs/estimator.md, "An equalised search") */
} sasnav_pair_opts;

/* The final stage's criterion (sasnav_pair_opts.final_criterion):
 *   ETA    eta at the final iterations (k, i), the paper's;
 *   JOINT  the joint misfit: one scene s on the grid explains both pings,
 *          min_s ||phi_p - T_p s||^2 + ||phi_q - T_q(sigma) s||^2 +
 *          mu ||s||^2 (joint_k CGLS iterations on the two pings stacked),
 *          then eta at (k, i) once at its minimum for the verdict;
 *   AUTO   JOINT when the pings' relative yaw is small (joint_shift_max),
 *          the scene is speckle-like (joint_contrast_max), the grid covers
 *          enough of the beam's footprint (joint_coverage_min), and (with a
 *          finite joint_eta_ratio) eta agrees with its estimate; ETA
 *          otherwise and on the GPU path (opts.gpu). */
typedef enum {
    SASNAV_FINAL_NONE = -1, /* in results: no final stage ran (sasnav_pair_estimate_first) */
    SASNAV_FINAL_ETA = 0,
    SASNAV_FINAL_JOINT = 1,
    SASNAV_FINAL_AUTO = 2
} sasnav_final_criterion;

/* "eta", "joint", "auto", "none" ("unknown" otherwise). */
const char *sasnav_final_criterion_name(int criterion);
/* The criterion named "eta", "joint" or "auto"; -1 for any other name. */
int sasnav_final_criterion_parse(const char *name);

void sasnav_pair_default_opts(sasnav_pair_opts *opts);

/* How far an estimate can be trusted (docs/estimator.md, "Verdict"),
 * calibrated on simulations:
 *   OK          the data chose one candidate clearly and explain it well;
 *   AMBIGUOUS   another candidate of the valley (typically one phase-centre
 *               spacing of surge and spacing / range of yaw away) explains
 *               the data nearly as well: the pair needs outside help (the
 *               run's motion model, aiding sensors: sasnav_navigate);
 *   FAILED      no candidate explains the data (eta above its bound), or a
 *               stage did not converge: the estimate is probably wrong;
 *   NO_OVERLAP  the pings share (almost) no observed scene;
 *   UNCHECKED   the method has no criteria of its own (the DPCA baseline,
 *               dpca.h): the estimate may be wrong, e.g. by one
 *               phase-centre spacing of surge, without any sign; only
 *               the aiding can confirm it (sasnav_navigate).
 * From least to most grave: ok, unchecked, ambiguous, failed, no_overlap
 * (sasnav_verdict_rank). */
typedef enum {
    SASNAV_VERDICT_OK = 0,
    SASNAV_VERDICT_AMBIGUOUS = 1,
    SASNAV_VERDICT_FAILED = 2,
    SASNAV_VERDICT_NO_OVERLAP = 3,
    SASNAV_VERDICT_UNCHECKED = 4
} sasnav_verdict;

/* Gravity of a verdict: 0 ok, 1 unchecked, 2 ambiguous, 3 failed,
 * 4 no_overlap (5 for an unknown value). */
int sasnav_verdict_rank(int verdict);

/* "ok", "ambiguous", "failed", "no_overlap", "unchecked" ("unknown"
 * otherwise). */
const char *sasnav_verdict_name(int verdict);

/* Candidates: the local minima of the global stage's valley scan (lowest
 * score first, at most SASNAV_PAIR_SCAN_CANDIDATES), then the slip check's
 * points one phase-centre slip either side of the winner. */
#define SASNAV_PAIR_SCAN_CANDIDATES 4
#define SASNAV_PAIR_MAX_CANDIDATES 8
/* At most this many of them go through the zeta and first eta stages. */
#define SASNAV_PAIR_REFINED_CANDIDATES 3

typedef struct {
    sasnav_pose error;   /* motion error: after the zeta and first eta
                            stages (on the search grid, result.search_grid)
                            when refined, else the scan's point */
    double zeta_scan;    /* zeta of the valley scan there (NaN: no scan, or
                            a slip-check neighbour) */
    double zeta, eta;    /* after those stages, on the search grid with
                            the coarse iterations (NaN when not refined) */
    int refined;
    int same_as;         /* index of an earlier candidate it converged to
                            (-1: a distinct point) */
} sasnav_pair_candidate;

/* Result of one estimate. Motion error = displacement - nominal displacement
 * (component-wise; surge, sway, yaw). */
typedef struct {
    int status;                /* SASNAV_OK, SASNAV_ERR_NO_OVERLAP, SASNAV_ERR_NOT_CONVERGED */
    sasnav_pose error;         /* final motion-error estimate (after eta) */
    sasnav_pose displacement;  /* final displacement estimate */
    sasnav_pose global_stage;  /* motion error after the global stage */
    sasnav_pose zeta_stage;    /* motion error after the zeta stage */
    double zeta, eta;          /* error-function values at the stage minima
                                  (eta's final stage: the value of its
                                  Newton model where its last step, below
                                  the stage's tolerance, was not evaluated) */
    double overlap;            /* ||psi_p|| / ||rho_p|| at the estimate (at
                                  the final stage's last evaluated point,
                                  within its tolerance of the estimate) */
    double ambiguity;          /* global stage: zeta of the valley scan's lowest
                                  local minimum over its second lowest (near
                                  1: the data hardly tell the surge-yaw
                                  candidates apart, docs/estimator.md; 0: a
                                  single minimum or no global stage) */
    int evaluations;           /* total error-function evaluations */
    int evaluations_global, evaluations_zeta, evaluations_eta;
    long applications;         /* total operator applications (T or T^H) */
    double seconds;            /* wall time */
    /* Where the time goes (summed over the candidates carried through):
     * wall seconds and operator applications of the overlap check and the
     * global stage, the zeta stage, the eta stage on the search grid (fringe
     * checks included), and the final stage at level 2 (k, i). */
    double seconds_global, seconds_zeta, seconds_eta, seconds_final;
    long applications_global, applications_zeta, applications_eta, applications_final;
    int evaluations_final;     /* of evaluations_eta, those at level 2 */
    /* Trust (docs/estimator.md, "Verdict"): */
    int verdict;               /* sasnav_verdict */
    int n_candidates;          /* entries of candidates[] */
    sasnav_pair_candidate candidates[SASNAV_PAIR_MAX_CANDIDATES];
    int chosen;                /* index of the candidate that became the
                                  estimate (error: its final-stage value) */
    double margin;             /* eta (search grid, coarse k, i) of the best
                                  other distinct refined candidate over the
                                  chosen one's
                                  (INFINITY: no other candidate) */
    int final_criterion;       /* the final stage's criterion used:
                                  SASNAV_FINAL_ETA or SASNAV_FINAL_JOINT */
    int joint_rejected;        /* 1: the joint stage ran, but eta at its
                                  estimate was above joint_eta_ratio of eta
                                  at its start, and eta's final stage was
                                  used instead */
    int search_grid;           /* the search stages' grid used:
                                  SASNAV_SEARCH_COARSE or SASNAV_SEARCH_FINE */
    int coincidence;           /* 1: the estimate sits at a phase-centre
                                  coincidence on a compact scene
                                  (opts.verdict_coincidence), which makes
                                  it "ambiguous" at best: its surge is not
                                  resolved there */
    double contrast;           /* the intensity contrast (standard deviation
                                  over mean of |rho_p|^2 over the error
                                  window) of p's full-pixel reconstruction:
                                  about 1 on speckle; above
                                  opts.verdict_contrast the verdict took
                                  the compact-scene rules (margin,
                                  coincidence; so did it where
                                  contrast_q is), above joint_contrast_max
                                  the search the full pixels and the final
                                  stage eta's; 0 where no estimate was
                                  made (DPCA) */
    double contrast_q;         /* the same of q's reconstruction placed at
                                  the estimate; the verdict takes the
                                  compact-scene rules where either image's
                                  contrast is above opts.verdict_contrast
                                  (a bright feature that q's beam sees and
                                  p's hardly: docs/validation.md); 0 where
                                  no estimate was made */
    int equalised;             /* 1: the search's criteria were weighted
                                  (opts.equalise on a scene speckle-like at
                                  the prior where a feature stands out) */
    float equalise_peak;       /* the equalising gate's peak: the largest
                                  smoothed intensity over the error window
                                  over its mean (full-pixel grid, at the
                                  prior; equalised needs at least 8 and
                                  the contrast gate, so a compact scene
                                  reports its peak unequalised); 0 where
                                  the weights were not made (opts.equalise
                                  0, DPCA) or no estimate was made */
} sasnav_pair_result;

typedef struct sasnav_pair sasnav_pair;

/* Checks estimator options: ranges of every field and the rules between
 * them (fix_yaw excludes yaw_sigma > 0). SASNAV_ERR_ARG with a message
 * naming the option. sasnav_pair_create calls it, then lowers coarse_k and
 * coarse_i to k and i when they exceed them (the coarse stages never
 * iterate more than the final one). */
int sasnav_pair_opts_check(const sasnav_pair_opts *opts);

/* Creates an estimator for pings with the given system, array and window.
 * The grid is built in p's centroid frame around (nominal.x / 2, range). */
int sasnav_pair_create(const sasnav_system *sys, const sasnav_array *array,
                       const sasnav_window *win, const sasnav_pair_opts *opts,
                       sasnav_pair **pair);

/* Sets the two pings: their data (n_rx * n_samples each, copied) and the
 * nominal displacement of q relative to p (e.g. (spacing, 0, 0)).
 * Errors: identical data (the same ping twice), an empty (all-zero) or
 * non-finite channel. */
int sasnav_pair_set_data(sasnav_pair *pair, const sasnav_cfloat *data_p,
                         const sasnav_cfloat *data_q, sasnav_pose nominal);

/* The same with each ping's own EPCA Tx-array offset (m; set_data uses
 * opts.tx_lag for both). The offset is speed x two-way delay: a ping made
 * while the vehicle is faster than nominal has a longer one, and a
 * difference between the two pings' offsets that the model ignores biases
 * the yaw estimate (docs/estimator.md, "Where the yaw errors come from"). */
int sasnav_pair_set_data_lags(sasnav_pair *pair, const sasnav_cfloat *data_p,
                              const sasnav_cfloat *data_q, sasnav_pose nominal, double lag_p,
                              double lag_q);

/* The same for pings whose channels are Tx-Rx pairs of their own
 * (sasnav_op_set_channels; a virtual array of consecutive pings,
 * sasnav_virtual_ping): channels_p[l] and channels_q[l] (n_rx each, the
 * estimator's array) are channel l's Tx and array poses in its ping's
 * centroid frame (the centroid of the channels' phase centres for a
 * virtual ping). They replace the EPCA model. The search's phase-centre
 * spacing becomes the layout's (extent of p's phase centres over n_rx -
 * 1); the yaw box and pixel defaults still come from the array, so set
 * opts.box and opts.pixel for such layouts. Errors: as set_data, a
 * non-finite pose. */
int sasnav_pair_set_data_channels(sasnav_pair *pair, const sasnav_cfloat *data_p,
                                  const sasnav_cfloat *data_q, sasnav_pose nominal,
                                  const sasnav_ping_pose *channels_p,
                                  const sasnav_ping_pose *channels_q);

/* Pings p and q of `run` (data_p, data_q: their samples): set_data for a
 * run of one transmitter and N receivers, set_data_channels with each
 * ping's channels (its navigation and the run's channel_offset, in its
 * PCA-centroid frame) for a run whose channels have offsets. What
 * navigate and pair call. tx_yaw (n_pings, or NULL: none) turns each
 * ping's transmitter pose by tx_yaw[p] before the offsets are applied,
 * where the navigation gives the transmitter the array's heading: the
 * vehicle's yaw between transmission and reception
 * (sasnav_run_tx_yaw). A transmitter d metres from the ping's moves
 * sideways by d x that yaw, and where the overlapping phase centres of
 * two pings come from different transmitters the sway estimate moves
 * with it (docs/model.md, "Channel layouts"). Errors: as those, p or q
 * outside the run, a run whose channel count is not the estimator's. */
int sasnav_pair_set_data_run(sasnav_pair *pair, const sasnav_run *run, int p, int q,
                             const sasnav_cfloat *data_p, const sasnav_cfloat *data_q, sasnav_pose nominal,
                             const double *tx_yaw);

/* The transmitter's yaw at transmission relative to the array's at
 * reception, per ping, from the run's gyro: -r x interval, interval the
 * time from transmission to reception that the navigation's Tx-array
 * offset stands for (tx_lag / speed where the run has both; otherwise
 * 2 range / c, the two-way delay at `range`),
 * r the yaw rate at the midpoint of transmission and reception: the
 * aiding's headings are the centroid frames', i.e. the array's at
 * reception (time[p]), so r is interpolated linearly at time[p] -
 * interval / 2 between the mean rates of the two ping intervals around
 * the ping, each placed at its interval's middle (one of them alone where
 * the other has no measurement; 0 where neither has). Errors: no gyro in
 * the run, an interval that is not finite and >= 0. */
int sasnav_run_tx_yaw(const sasnav_run *run, double range, double *tx_yaw);

/* The interpolation of sasnav_run_tx_yaw on any abscissa: epoch[n]
 * (strictly increasing; time in s, or distance along the track in m),
 * rate[p] the mean turn rate over (epoch[p - 1], epoch[p]] (rad per unit
 * of epoch; used where valid[p] != 0; entry 0 is not used), interval the
 * span between transmission and reception in the same unit (>= 0).
 * tx_yaw[p] = -interval x the rate at epoch[p] - interval / 2. What
 * sasnav_navigate uses without a gyro, with the rates from its own first
 * estimates (yaw per metre of track). Errors: NULL arguments, n < 1, an
 * interval that is not finite and >= 0, epochs not finite and strictly
 * increasing, a valid rate that is not finite. */
int sasnav_tx_yaw_from_rates(int n, const double *epoch, const double *rate, const unsigned char *valid,
                             double interval, double *tx_yaw);

/* A second estimate made from a first one (sasnav_pair_estimate_from):
 * `again` takes the first's candidates, choice, ambiguity and margin (the
 * global stage is the first's), and its time, applications and
 * evaluations become the sum of both. */
void sasnav_pair_result_carry(const sasnav_pair_result *first, sasnav_pair_result *again);

/* The verdict of `result` again, from its overlap, status, eta, margin,
 * contrasts and coincidence, under `pair`'s options: after
 * sasnav_pair_result_carry has given an estimate made by
 * sasnav_pair_estimate_from (judged with an infinite margin) the first
 * estimate's margin. On a scene that is compact for the verdict by the new
 * estimate's contrasts, that margin must reach verdict_margin_compact.
 * Nothing on NULL. */
void sasnav_pair_rejudge(const sasnav_pair *pair, sasnav_pair_result *result);

/* The contrast the verdict's compact-scene gate reads: the larger of
 * `result`'s contrast (p's image) and contrast_q (q's at the estimate); a
 * scene is compact for the verdict where it exceeds
 * opts.verdict_contrast. 0 on NULL. */
double sasnav_pair_result_contrast(const sasnav_pair_result *result);

/* Without a gyro, the transmitters' turn between transmission and
 * reception from an estimated displacement between two pings: the turn
 * per metre of that displacement (theta / its length) times the distance
 * travelled between transmission and reception (run->tx_lag; without it
 * run->speed x 2 range / c), the same for every ping (tx_yaw[n_pings]).
 * What `sasnav pair` uses on a run with channel offsets and no gyro; a
 * navigation interpolates the turn along the track instead (opts.tx_yaw).
 * Errors: NULL, no such distance, a zero or non-finite displacement. */
int sasnav_run_tx_yaw_from_estimate(const sasnav_run *run, sasnav_pose displacement, double range,
                                    double *tx_yaw);

/* Evaluates zeta and eta at a hypothesised MOTION ERROR (displacement =
 * nominal + error). level 0: coarse pixels, coarse (k, i); level 1: full
 * pixels, coarse (k, i); level 2: full pixels, final (k, i). blurred != 0
 * blurs the moduli before zeta (global-stage criterion). Either output may
 * be NULL. At levels 0 and 1 of an equalised pair (result.equalised:
 * opts.equalise on a scene speckle-like at the prior where a feature
 * stands out) zeta and eta are the search's weighted
 * ones; with opts.equalise = 0 (or at level 2) the data's own.
 * overlap (may be NULL) receives ||psi_p|| / ||rho_p|| (never weighted). */
int sasnav_pair_eval(sasnav_pair *pair, sasnav_pose error, int level, int blurred,
                     double *zeta, double *eta, double *overlap);

/* Full two-stage estimate (with the global stage if enabled). */
int sasnav_pair_estimate(sasnav_pair *pair, sasnav_pair_result *result);

/* The local stages only (zeta, first eta, final), from a given motion
 * error (e.g. a candidate of an earlier estimate chosen by
 * sasnav_navigate's joint resolution); margin INFINITY, one candidate. */
int sasnav_pair_estimate_from(sasnav_pair *pair, sasnav_pose start, sasnav_pair_result *result);

/* Two passes over a run (sasnav_navigate with the pairs' own speed-scaled
 * offsets, docs/navigation.md "Two passes"):
 * sasnav_pair_estimate_first is sasnav_pair_estimate without its final
 * (level-2) stage: the chosen candidate's estimate on the search grid, with
 * the candidates, margin and verdict, its eta that grid's and its overlap
 * that of level 1
 * (final_criterion SASNAV_FINAL_NONE; a preliminary verdict).
 * sasnav_pair_finish then runs the final stage alone from first->error on
 * the estimator's present data (set again, e.g. with other Tx-array
 * offsets): the result carries first's candidates, choice, ambiguity,
 * margin and costs (sasnav_pair_result_carry), and its verdict is judged
 * on the final eta and overlap. sasnav_pair_estimate = the two on the
 * same data. Errors: NULL arguments, no data, a first result without a
 * finite estimate. */
int sasnav_pair_estimate_first(sasnav_pair *pair, sasnav_pair_result *result);
int sasnav_pair_finish(sasnav_pair *pair, const sasnav_pair_result *first, sasnav_pair_result *result);

/* The estimator's grid (p's centroid frame). */
const sasnav_grid *sasnav_pair_grid(const sasnav_pair *pair);
/* The options in use, with the automatic values resolved. */
const sasnav_pair_opts *sasnav_pair_options(const sasnav_pair *pair);
/* Operator applications so far. */
long sasnav_pair_applications(const sasnav_pair *pair);

void sasnav_pair_destroy(sasnav_pair *pair);

/* One range sub-interval of sasnav_pair_estimate_intervals. */
typedef struct {
    double range;                /* centre range of the sub-interval, m */
    double tx_lag;               /* EPCA Tx-array offset used there, m */
    int status;                  /* SASNAV_OK or the code that stopped it */
    sasnav_pair_result result;   /* valid when status is SASNAV_OK */
    int tx_yaw_from_estimate;    /* 1: a run with channel offsets and no
                                    gyro whose "ok" first estimate gave the
                                    transmitters' turn
                                    (sasnav_run_tx_yaw_from_estimate), and
                                    result is the estimate made again with
                                    it, its verdict judged with the first
                                    estimate's margin (sasnav_pair_rejudge:
                                    "ambiguous" where that margin is short
                                    of a compact scene's) */
} sasnav_pair_interval;

/* Estimates the motion error of ping q relative to ping p of `run` in n
 * range sub-intervals that split [opts->range - opts->range_extent / 2,
 * opts->range + opts->range_extent / 2] into equal parts (paper Sec. III-D:
 * the Tx-array offset of the EPCA model grows with range). Each interval
 * has its own estimator and Tx-array offset: run->tx_lag (motion_lag 0), or
 * the distance the vehicle covers while the pulse reaches the interval's
 * centre and returns, run->speed x 2 R / c (motion_lag 1; needs
 * run->speed > 0). A run with channel offsets uses its channels' layouts
 * instead of the EPCA model (sasnav_pair_set_data_run; the Tx-array offset
 * is the navigation's, motion_lag does not apply), with the gyro's
 * transmitter yaw when the run has one; without a gyro an "ok" estimate
 * gives the transmitters' turn (sasnav_run_tx_yaw_from_estimate) and is
 * made again from itself with it (kept when that estimate is "ok" on its
 * own, then judged again with the first's margin:
 * out[s].tx_yaw_from_estimate). The nominal displacement comes
 * from run->nav. Returns
 * SASNAV_OK when every interval was attempted (each interval's own status
 * in out[s].status), SASNAV_ERR_ARG for bad arguments (pings, n outside
 * 1..64, options: sasnav_pair_opts_check). */
int sasnav_pair_estimate_intervals(const sasnav_run *run, int p, int q,
                                   const sasnav_pair_opts *opts, int n, int motion_lag,
                                   sasnav_pair_interval *out);

#ifdef __cplusplus
}
#endif
#endif
