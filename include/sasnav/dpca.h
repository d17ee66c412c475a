/* sasnav -- the DPCA baseline (Displaced Phase Centre Antenna micronavigation,
 * Bellettini & Pinto 2002), for comparison with the subspace estimator.
 *
 * Model. Each ping is described by its EPCA geometry (paper III-B, SPEC 3):
 * in the ping's centroid frame the transmitter sits run->tx_lag / 2 behind the
 * centroid and the array midpoint tx_lag / 2 ahead, so that the phase centre
 * (PCA) of receiver l is at u_l / 2 along the array axis (u_l = rx_u[l]). A
 * uniform array of receiver spacing e has phase centres every d = e / 2.
 * For pings p and q with nominal along-track displacement
 * D = (q - p) * run->ping_spacing, the phase centre of q's channel l nominally
 * coincides with that of p's channel l + shift, shift = D / d (an integer, or
 * the call is refused); K = N - |shift| >= 2 phase centres overlap.
 *
 * Estimate. For each overlapping pair the delay tau_k of q's channel relative
 * to p's channel is measured over a range window:
 *   - coarse: peak of |cross-correlation| (FFT, zero-padded to avoid wrap,
 *     upsampled by FFT zero-padding, parabolic refinement of the peak);
 *   - fine: the phase of the cross-correlation at the coarse peak, which for
 *     baseband data carries exp(-j 2 pi f0 tau); it fixes tau modulo 1 / f0
 *     and the branch is the one nearest to the coarse delay (so the coarse
 *     delay must be right within 1 / (2 f0), i.e. lambda / 4 of sway); by
 *     default the coarse delay used for that choice is the line fitted to
 *     the coarse range shifts of all K pairs, which averages their errors.
 * The PCA approximation is corrected: the nominal delay difference of the two
 * bistatic pairs (they share a phase centre but not their Tx-Rx baseline) is
 * computed for a scatterer at broadside of the phase centre at the window
 * centre and subtracted. The range shift of overlapping phase centre k is
 *   dr_k = -c (tau_k - tau_nominal_k) / 2
 * (positive = the phase centre moved towards the scene, +y: ranges shorten).
 * A phase centre at along-track coordinate v_k in q's centroid frame moves by
 * sway + sin(yaw) v_k, so a least-squares line dr_k = a + b (v_k - mean v)
 * gives yaw = asin(b) and the sway of q's centroid, a - b mean(v).
 * Surge is not observable: it is taken as nominal (motion error 0).
 *
 * Limits (by design, SPEC 5): the surge error must be well below d / 2 (the
 * paired phase centres stop coinciding and decorrelate), the sway error
 * within about lambda / 4 of what the envelope can resolve, and the yaw small
 * enough that the beams of the two pings still illuminate the same patch.
 *
 * Threads: re-entrant, no shared state; calls on the same (read-only) run
 * may run concurrently. Each estimate plans and destroys its FFTW plans
 * under the planner lock of op.h. The channel pairs are processed by
 * opts.nthreads OpenMP threads (0 = omp_get_max_threads() at the call, at
 * most one per channel pair); the result does not depend on the count.
 */
#ifndef SASNAV_DPCA_H
#define SASNAV_DPCA_H

#include "sasnav/estimator.h"
#include "sasnav/run.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    double range;         /* m, centre of the range window (default 0: the
                             run's range_of_interest) */
    double half_width;    /* m, half-width of the range window (default 0.5) */
    int upsampling;       /* FFT upsampling of the correlation (default 8,
                             accepted 1..64) */
    double max_sway;      /* m, the correlation peak is searched within
                             +-max_sway of range shift around the nominal
                             delay (default 0.04) */
    int use_phase;        /* 1 (default): coarse + fine (phase) delays;
                             0: coarse (envelope) delays only */
    int unwrap;           /* phase branch of each pair taken nearest to:
                             1 (default) the line fitted to the coarse range
                             shifts of all pairs; 0 the pair's own coarse
                             delay */
    int bistatic_correction; /* 1 (default): subtract the nominal delay
                             difference of the paired bistatic channels */
    double min_coherence; /* mean peak coherence below which the result's
                             status is SASNAV_ERR_NO_OVERLAP (default 0.1) */
    int nthreads;         /* OpenMP threads over channel pairs (0 = default) */
} sasnav_dpca_opts;

/* Fills the defaults above. */
void sasnav_dpca_default_opts(sasnav_dpca_opts *opts);

/* Per-pair measurements of one estimate (optional output). */
typedef struct {
    int n_pairs;                        /* K */
    int shift;                          /* channel shift (q's l pairs p's l + shift) */
    int channel_q[SASNAV_MAX_RX];
    int channel_p[SASNAV_MAX_RX];
    double along[SASNAV_MAX_RX];        /* m, v_k: phase centre along q's array axis,
                                           in q's centroid frame */
    double delay_coarse[SASNAV_MAX_RX]; /* s, envelope delay of q's channel vs p's */
    double delay[SASNAV_MAX_RX];        /* s, final (fine) delay */
    double delay_nominal[SASNAV_MAX_RX];/* s, bistatic (PCA) correction subtracted */
    double range_shift[SASNAV_MAX_RX];  /* m, dr_k */
    double coherence[SASNAV_MAX_RX];    /* |normalised correlation| at the peak, 0..1 */
    double residual_rms;                /* m, rms residual of the line fit */
    double sway_overlap;                /* m, fitted sway at the overlap centroid (a) */
    double mean_coherence;
    int window_first, window_samples;   /* samples used (index of the first, count) */
} sasnav_dpca_detail;

/* DPCA estimate of the displacement of ping q relative to ping p of `run`
 * (q != p; q > p is the usual case, q - p > 1 gives a longer baseline with
 * fewer overlapping phase centres). Fills `res` like the subspace estimator:
 * error = (0, sway, yaw) motion error, displacement = nominal + error,
 * zeta_stage = global_stage = error, zeta = eta = 0, overlap = mean
 * coherence, evaluations = applications = 0, seconds = wall time, status =
 * SASNAV_OK or SASNAV_ERR_NO_OVERLAP (mean coherence below
 * opts.min_coherence), verdict = SASNAV_VERDICT_UNCHECKED (DPCA cannot tell
 * a right estimate from one slipped by a phase-centre spacing: its surge
 * is not observed at all, estimator.h), or SASNAV_VERDICT_NO_OVERLAP. `opts` may be NULL (defaults); `detail` may be NULL.
 * Returns SASNAV_OK, or SASNAV_ERR_ARG (bad run, ping indices or options, a
 * run whose channels have transmitters of their own (channel_offset), a
 * non-uniform array, a nominal shift that is not a whole number of phase
 * centres within 1e-6, fewer than 2 overlapping phase centres, a range
 * window outside the samples), SASNAV_ERR_NOMEM, SASNAV_ERR_FFT,
 * SASNAV_ERR_GEOMETRY (range window too close to the sensors). */
int sasnav_dpca_estimate(const sasnav_run *run, int p, int q, const sasnav_dpca_opts *opts,
                         sasnav_pair_result *res, sasnav_dpca_detail *detail);

#ifdef __cplusplus
}
#endif
#endif
