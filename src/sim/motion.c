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
 * Circular tracks (circle_radius R > 0): the nominal pose at s is
 * N(s) = (R sin(s / R), -R cos(s / R), s / R) (counter-clockwise about the
 * origin, looking at it) and the true pose N(s) * (e_surge, e_sway, e_yaw)
 * (the errors in the vehicle's frame; for the straight track this is the
 * formula above).
 * The explicit pair error replaces ping pair_q's displacement relative to
 * ping pair_q - 1 by (spacing + surge, sway, yaw); other pings are unchanged.
 */
#include "sasnav/error.h"
#include "sasnav/sim.h"

#include <math.h>
#include <string.h>

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
        !(tp->sway_rms >= 0) || !(tp->yaw_rms >= 0) || !(tp->smooth_length > 0) ||
        !(tp->circle_radius >= 0) || !isfinite(tp->circle_radius))
        return sasnav_set_error(SASNAV_ERR_ARG, "trajectory parameters must be finite and >= 0");
    if (tp->has_pair_error && (tp->pair_q < 1 || tp->pair_q >= tp->n_pings))
        return sasnav_set_error(SASNAV_ERR_ARG, "pair error ping %d outside 1..%d", tp->pair_q,
                                tp->n_pings - 1);
    return SASNAV_OK;
}

/* The nominal vehicle pose at arc length s. */
static sasnav_pose path_nominal(const sasnav_trajectory_params *tp, double s)
{
    double r = tp->circle_radius;
    if (!(r > 0)) return (sasnav_pose){s, 0.0, 0.0};
    double a = s / r;
    return (sasnav_pose){r * sin(a), -r * cos(a), sasnav_wrap_angle(a)};
}

/* The vehicle pose at s with errors (surge, sway, yaw) in its own frame. */
static sasnav_pose path_pose(const sasnav_trajectory_params *tp, double s, double surge,
                             double sway, double yaw)
{
    /* The straight track as it always was (no rounding of a composition:
     * the same bits as before circular tracks existed). */
    if (!(tp->circle_radius > 0)) return (sasnav_pose){s + surge, sway, yaw};
    return sasnav_pose_compose(path_nominal(tp, s), (sasnav_pose){surge, sway, yaw});
}

int sasnav_trajectory_nominal(const sasnav_trajectory_params *tp, sasnav_ping_pose *poses)
{
    int rc = check_traj(tp, poses);
    if (rc) return rc;
    sasnav_ping_pose local = sasnav_epca_local(tp->tx_lag, 0.0);
    for (int p = 0; p < tp->n_pings; p++) {
        sasnav_pose c = path_nominal(tp, tp->x_start + p * tp->ping_spacing);
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
            sasnav_pose tx = path_pose(tp, st, smooth_error_at(&surge, st),
                                       smooth_error_at(&sway, st), smooth_error_at(&yaw, st));
            sasnav_pose ar = path_pose(tp, sr, smooth_error_at(&surge, sr),
                                       smooth_error_at(&sway, sr), smooth_error_at(&yaw, sr));
            poses[p].tx = tx;
            poses[p].array = ar;
        } else {
            sasnav_pose c = path_pose(tp, s, smooth_error_at(&surge, s), smooth_error_at(&sway, s),
                                      smooth_error_at(&yaw, s));
            poses[p] = sasnav_ping_place(c, &local);
        }
    }
    if (tp->has_pair_error) {
        int q = tp->pair_q;
        sasnav_ping_pose local_q = sasnav_ping_local(&poses[q]);
        sasnav_pose d = {tp->ping_spacing + tp->pair_error.x, tp->pair_error.y,
                         tp->pair_error.theta};
        if (tp->circle_radius > 0) {
            double s1 = tp->x_start + q * tp->ping_spacing;
            sasnav_pose n = sasnav_pose_between(path_nominal(tp, s1 - tp->ping_spacing),
                                                path_nominal(tp, s1));
            d = (sasnav_pose){n.x + tp->pair_error.x, n.y + tp->pair_error.y,
                              n.theta + tp->pair_error.theta};
        }
        sasnav_pose cq = sasnav_pose_compose(sasnav_ping_centroid(&poses[q - 1]), d);
        poses[q] = sasnav_ping_place(cq, &local_q);
    }
    return SASNAV_OK;
}

void sasnav_aiding_default(sasnav_aiding_params *ap)
{
    if (!ap) return;
    memset(ap, 0, sizeof *ap);
    const double deg = M_PI / 180.0;
    ap->gyro = 1;
    ap->dvl = 1;
    ap->gyro_arw = 0.002 * deg / 60.0;   /* 0.002 deg/sqrt(h) in rad/sqrt(s) */
    ap->gyro_bias = 0.003 * deg / 3600.0; /* 0.003 deg/h in rad/s */
    ap->dvl_noise = 0.003;
    ap->dvl_bias = 0.001;
    ap->dvl_scale = 0.002;
    ap->seed = 13;
}

int sasnav_simulate_aiding(const sasnav_aiding_params *ap, double speed, sasnav_run *run)
{
    if (!ap || !run) return sasnav_set_error(SASNAV_ERR_ARG, "NULL aiding argument");
    if (!run->truth) return sasnav_set_error(SASNAV_ERR_ARG, "aiding needs the true trajectory");
    if (!(speed > 0) || !isfinite(speed) || !(run->ping_spacing > 0))
        return sasnav_set_error(SASNAV_ERR_ARG, "aiding needs a speed and a ping spacing > 0");
    if (!(ap->gyro_arw >= 0) || !(ap->gyro_bias >= 0) || !(ap->dvl_noise >= 0) ||
        !(ap->dvl_bias >= 0) || !(ap->dvl_scale >= 0) ||
        !isfinite(ap->gyro_arw + ap->gyro_bias + ap->dvl_noise + ap->dvl_bias + ap->dvl_scale))
        return sasnav_set_error(SASNAV_ERR_ARG, "aiding error parameters must be finite and >= 0");
    if (!ap->gyro && !ap->dvl) return sasnav_set_error(SASNAV_ERR_ARG, "aiding without a sensor");
    int rc = sasnav_run_alloc_aiding(run, ap->gyro, ap->dvl);
    if (rc) return rc;
    sasnav_aiding *a = run->aiding;
    sasnav_rng rng;
    sasnav_rng_seed(&rng, ap->seed);
    /* Per-run errors first, then per-interval noise in ping order. */
    double bg = ap->gyro_bias * sasnav_rng_normal(&rng);
    double sv = ap->dvl_scale * sasnav_rng_normal(&rng);
    double bv[2] = {ap->dvl_bias * sasnav_rng_normal(&rng), ap->dvl_bias * sasnav_rng_normal(&rng)};
    double dt = run->ping_spacing / speed;
    for (int p = 0; p < run->n_pings; p++) {
        a->time[p] = p * dt;
        /* The true interval ending at ping p (the first ping: the interval
         * after it, as a stand-in). */
        int i0 = p > 0 ? p - 1 : 0, i1 = p > 0 ? p : (run->n_pings > 1 ? 1 : 0);
        sasnav_pose d = {0, 0, 0};
        if (i1 != i0) d = sasnav_ping_displacement(&run->truth[i0], &run->truth[i1]);
        double rate = d.theta / dt;
        double c = cos(0.5 * d.theta), s = sin(0.5 * d.theta);
        double v[2] = {(c * d.x + s * d.y) / dt, (-s * d.x + c * d.y) / dt};
        double ng = sasnav_rng_normal(&rng), nv0 = sasnav_rng_normal(&rng), nv1 = sasnav_rng_normal(&rng);
        if (ap->gyro) {
            double sig_n = ap->gyro_arw / sqrt(dt);
            a->yaw_rate[p] = rate + bg + sig_n * ng;
            double sig = sqrt(sig_n * sig_n + ap->gyro_bias * ap->gyro_bias);
            a->yaw_rate_sigma[p] = fmax(sig, 1e-12); /* the readers' smallest sigma */
        }
        if (ap->dvl) {
            double nv[2] = {nv0, nv1};
            for (int k = 0; k < 2; k++) {
                a->velocity[2 * p + k] = (1.0 + sv) * v[k] + bv[k] + ap->dvl_noise * nv[k];
                double sc = ap->dvl_scale * v[k];
                double sig = sqrt(ap->dvl_noise * ap->dvl_noise + ap->dvl_bias * ap->dvl_bias + sc * sc);
                a->velocity_sigma[2 * p + k] = fmax(sig, 1e-12);
            }
        }
    }
    return SASNAV_OK;
}
