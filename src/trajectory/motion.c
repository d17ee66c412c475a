/* Nominal and true trajectories of simulated runs (SPEC 4).
 *
 * The vehicle follows a nominal straight track along +x at y = 0 with zero
 * yaw. Its true pose at nominal along-track position s is
 *   (s + e_surge(s), e_sway(s), e_yaw(s)),
 * where each error is a sum of four random sinusoids (seeded) with periods
 * between 1 and 4 correlation lengths, scaled to the requested rms. Ping p's
 * PCA centroid nominally sits at x_start + p * ping_spacing.
 * - true_bistatic = 0: each ping is the exact EPCA geometry (array lag/2
 *   ahead of the centroid, Tx lag/2 behind) placed at the erroneous centroid.
 * - true_bistatic = 1: the Tx pose is the vehicle pose at transmission (path
 *   position s - lag/2) and the array pose the vehicle pose at reception
 *   (s + lag/2): positions and yaws of Tx and array differ as in a real ping.
 * The explicit pair error replaces ping pair_q's displacement relative to
 * ping pair_q - 1 by (spacing + surge, sway, yaw); other pings are unchanged.
 */
#include "sasnav/error.h"
#include "sasnav/sim.h"

#include <math.h>

#define N_WAVES 4

typedef struct {
    double amp[N_WAVES], k[N_WAVES], phase[N_WAVES];
} smooth_error;

static void smooth_error_draw(smooth_error *e, double rms, double length, sasnav_rng *rng)
{
    double power = 0;
    for (int j = 0; j < N_WAVES; j++) {
        double period = length * (1.0 + 3.0 * sasnav_rng_uniform(rng));
        e->k[j] = 2.0 * M_PI / period;
        e->phase[j] = 2.0 * M_PI * sasnav_rng_uniform(rng);
        e->amp[j] = sasnav_rng_normal(rng);
        power += 0.5 * e->amp[j] * e->amp[j];
    }
    double scale = power > 0 ? rms / sqrt(power) : 0.0;
    for (int j = 0; j < N_WAVES; j++) e->amp[j] *= scale;
}

static double smooth_error_at(const smooth_error *e, double s)
{
    double v = 0;
    for (int j = 0; j < N_WAVES; j++) v += e->amp[j] * sin(e->k[j] * s + e->phase[j]);
    return v;
}

static int check_traj(const sasnav_trajectory_params *tp, const sasnav_ping_pose *poses)
{
    if (!tp || !poses) return sasnav_set_error(SASNAV_ERR_ARG, "NULL trajectory argument");
    if (tp->n_pings < 1) return sasnav_set_error(SASNAV_ERR_ARG, "need at least one ping");
    if (!(tp->ping_spacing > 0) || !isfinite(tp->ping_spacing))
        return sasnav_set_error(SASNAV_ERR_ARG, "ping spacing must be > 0");
    if (!isfinite(tp->x_start) || !isfinite(tp->tx_lag) || !(tp->surge_rms >= 0) ||
        !(tp->sway_rms >= 0) || !(tp->yaw_rms >= 0) || !(tp->smooth_length > 0))
        return sasnav_set_error(SASNAV_ERR_ARG, "trajectory parameters must be finite and >= 0");
    if (tp->has_pair_error && (tp->pair_q < 1 || tp->pair_q >= tp->n_pings))
        return sasnav_set_error(SASNAV_ERR_ARG, "pair error ping %d outside 1..%d", tp->pair_q,
                                tp->n_pings - 1);
    return SASNAV_OK;
}

int sasnav_trajectory_nominal(const sasnav_trajectory_params *tp, sasnav_ping_pose *poses)
{
    int rc = check_traj(tp, poses);
    if (rc) return rc;
    sasnav_ping_pose local = sasnav_epca_local(tp->tx_lag, 0.0);
    for (int p = 0; p < tp->n_pings; p++) {
        sasnav_pose c = {tp->x_start + p * tp->ping_spacing, 0.0, 0.0};
        poses[p] = sasnav_ping_place(c, &local);
    }
    return SASNAV_OK;
}

int sasnav_trajectory_true(const sasnav_trajectory_params *tp, sasnav_ping_pose *poses)
{
    int rc = check_traj(tp, poses);
    if (rc) return rc;
    sasnav_rng rng;
    sasnav_rng_seed(&rng, tp->seed);
    smooth_error surge, sway, yaw;
    smooth_error_draw(&surge, tp->surge_rms, tp->smooth_length, &rng);
    smooth_error_draw(&sway, tp->sway_rms, tp->smooth_length, &rng);
    smooth_error_draw(&yaw, tp->yaw_rms, tp->smooth_length, &rng);
    sasnav_ping_pose local = sasnav_epca_local(tp->tx_lag, 0.0);
    for (int p = 0; p < tp->n_pings; p++) {
        double s = tp->x_start + p * tp->ping_spacing;
        if (tp->true_bistatic) {
            double st = s - 0.5 * tp->tx_lag, sr = s + 0.5 * tp->tx_lag;
            sasnav_pose tx = {st + smooth_error_at(&surge, st), smooth_error_at(&sway, st),
                              smooth_error_at(&yaw, st)};
            sasnav_pose ar = {sr + smooth_error_at(&surge, sr), smooth_error_at(&sway, sr),
                              smooth_error_at(&yaw, sr)};
            poses[p].tx = tx;
            poses[p].array = ar;
        } else {
            sasnav_pose c = {s + smooth_error_at(&surge, s), smooth_error_at(&sway, s),
                             smooth_error_at(&yaw, s)};
            poses[p] = sasnav_ping_place(c, &local);
        }
    }
    if (tp->has_pair_error) {
        int q = tp->pair_q;
        sasnav_ping_pose local_q = sasnav_ping_local(&poses[q]);
        sasnav_pose d = {tp->ping_spacing + tp->pair_error.x, tp->pair_error.y,
                         tp->pair_error.theta};
        sasnav_pose cq = sasnav_pose_compose(sasnav_ping_centroid(&poses[q - 1]), d);
        poses[q] = sasnav_ping_place(cq, &local_q);
    }
    return SASNAV_OK;
}
