/* The tank experiment of SPEC 4: the passband simulator (include/sasnav/tank.h).
 * Its WAV/CSV writer and the recording reader are in src/io/tank_files.c. */
#include "sasnav/tank.h"

#include "sasnav/error.h"
#include "sasnav/scene.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void sasnav_tank_default(sasnav_tank_params *p)
{
    if (!p) return;
    memset(p, 0, sizeof *p);
    p->sound_speed = 1480.0;
    p->chirp.f_start = 90e3;
    p->chirp.f_end = 120e3;
    p->chirp.duration = 3e-3;
    p->chirp.tukey = 0.1;
    p->sample_rate = 1e6;
    p->range_min = 0.5;
    p->range_max = 3.0;
    p->attenuation = SASNAV_ATTEN_SPHERICAL;
    p->gain = 0.25;
    p->noise_std = 1e-3;
    p->n_rx = 8;
    p->rx_spacing = 0.05;
    p->array_height = 0.0;
    p->element_length = 0.05;
    p->directivity = 1;
    p->n_pings = 32;
    p->step = 0.025;
    p->x_start = -0.5 * (p->n_pings - 1) * p->step;
    p->surge_step_std = 2e-3;
    p->sway_step_std = 1e-3;
    p->jump_ping = 12;
    p->jump = 0.017;
    p->yaw = 1.27e-2;
    p->plate_x = 0.0;
    p->plate_y = 1.5;
    p->plate_radius = 0.3;
    p->n_reflectors = 4;
    for (int i = 0; i < 4; i++) {
        p->refl_x[i] = p->plate_x + ((i & 1) ? 0.1 : -0.1);
        p->refl_y[i] = p->plate_y + ((i & 2) ? 0.1 : -0.1);
        p->refl_amp[i] = 1.0;
    }
    p->n_clutter = 200;
    p->clutter_std = 0.02;
    p->seed = 1;
}

#define FIN(v) isfinite((double)(v))

int sasnav_tank_check(const sasnav_tank_params *p)
{
    if (!p) return sasnav_set_error(SASNAV_ERR_ARG, "tank: parameters are NULL");
    if (!FIN(p->sound_speed) || p->sound_speed <= 0)
        return sasnav_set_error(SASNAV_ERR_ARG, "tank: sound speed %g", p->sound_speed);
    if (!FIN(p->sample_rate) || p->sample_rate <= 0)
        return sasnav_set_error(SASNAV_ERR_ARG, "tank: sample rate %g", p->sample_rate);
    if (sasnav_lfm_length(&p->chirp, p->sample_rate) < 2) return SASNAV_ERR_ARG;
    if (!FIN(p->range_max) || p->range_max <= 0 || !FIN(p->range_min) || p->range_min < 0 ||
        p->range_min >= p->range_max)
        return sasnav_set_error(SASNAV_ERR_ARG, "tank: ranges [%g, %g]", p->range_min, p->range_max);
    if (p->attenuation != SASNAV_ATTEN_SPHERICAL && p->attenuation != SASNAV_ATTEN_EXPLODING &&
        p->attenuation != SASNAV_ATTEN_NONE)
        return sasnav_set_error(SASNAV_ERR_ARG, "tank: unknown attenuation %d", (int)p->attenuation);
    if (!FIN(p->gain) || !FIN(p->noise_std) || p->noise_std < 0)
        return sasnav_set_error(SASNAV_ERR_ARG, "tank: noise std %g", p->noise_std);
    if (p->n_rx < 1 || p->n_rx > SASNAV_MAX_RX || !FIN(p->rx_spacing) || p->rx_spacing < 0 ||
        !FIN(p->array_height) || !FIN(p->element_length) || p->element_length < 0 ||
        (p->directivity != 0 && p->directivity != 1))
        return sasnav_set_error(SASNAV_ERR_ARG, "tank: array of %d Rx spaced %g", p->n_rx,
                                p->rx_spacing);
    if (p->n_pings < 1 || p->n_pings > 100000 || !FIN(p->step) || !FIN(p->x_start) ||
        !FIN(p->surge_step_std) || p->surge_step_std < 0 || !FIN(p->sway_step_std) ||
        p->sway_step_std < 0 || !FIN(p->jump) || !FIN(p->yaw))
        return sasnav_set_error(SASNAV_ERR_ARG, "tank: bad track parameters");
    if (p->n_reflectors < 0 || p->n_reflectors > SASNAV_TANK_MAX_REFLECTORS || p->n_clutter < 0 ||
        p->n_clutter > 1000000 || !FIN(p->clutter_std) || p->clutter_std < 0 ||
        !FIN(p->plate_radius) || p->plate_radius < 0 || !FIN(p->plate_x) || !FIN(p->plate_y))
        return sasnav_set_error(SASNAV_ERR_ARG, "tank: bad scene parameters");
    for (int i = 0; i < p->n_reflectors; i++)
        if (!FIN(p->refl_x[i]) || !FIN(p->refl_y[i]) || !FIN(p->refl_amp[i]))
            return sasnav_set_error(SASNAV_ERR_ARG, "tank: reflector %d is not finite", i);
    return SASNAV_OK;
}

int sasnav_tank_n_chirp(const sasnav_tank_params *p)
{
    if (sasnav_tank_check(p)) return 0;
    return sasnav_lfm_length(&p->chirp, p->sample_rate);
}

int sasnav_tank_n_samples(const sasnav_tank_params *p)
{
    if (sasnav_tank_check(p)) return 0;
    double t_end = 2.0 * p->range_max / p->sound_speed + p->chirp.duration;
    double n = ceil(t_end * p->sample_rate) + 1;
    if (n > 1e8) {
        sasnav_set_error(SASNAV_ERR_ARG, "tank: records of %.0f samples are too long", n);
        return 0;
    }
    return (int)n;
}

int sasnav_tank_poses(const sasnav_tank_params *p, sasnav_ping_pose *nominal,
                      sasnav_ping_pose *truth)
{
    int rc = sasnav_tank_check(p);
    if (rc) return rc;
    sasnav_rng rng;
    sasnav_rng_seed(&rng, p->seed ^ 0x7a6e6b5354455053ULL);
    double ex = 0.0, ey = 0.0; /* cumulative stepping errors */
    for (int k = 0; k < p->n_pings; k++) {
        if (k > 0) {
            ex += p->surge_step_std * sasnav_rng_normal(&rng);
            ey += p->sway_step_std * sasnav_rng_normal(&rng);
            if (k == p->jump_ping) ex += p->jump;
        }
        double xn = p->x_start + k * p->step;
        if (nominal) {
            sasnav_pose q = {xn, 0.0, 0.0};
            nominal[k].tx = q;
            nominal[k].array = q;
        }
        if (truth) {
            sasnav_pose q = {xn + ex, ey, p->yaw};
            truth[k].tx = q;
            truth[k].array = q;
        }
    }
    return SASNAV_OK;
}

/* Continuous transmitted chirp (the samples of sasnav_lfm_samples are its
 * values at t = n / fs): Tukey envelope over [0, (n_chirp - 1) / fs]. */
static double chirp_at(const sasnav_lfm *l, double len, double t)
{
    if (t < 0 || t > len) return 0.0;
    double x = t / len, env = 1.0;
    double xe = x < 0.5 ? x : 1.0 - x;
    if (l->tukey > 0 && xe < 0.5 * l->tukey) env = 0.5 * (1.0 - cos(2.0 * M_PI * xe / l->tukey));
    double rate = (l->f_end - l->f_start) / l->duration;
    double cycles = l->f_start * t + 0.5 * rate * t * t;
    cycles -= floor(cycles);
    return env * cos(2.0 * M_PI * cycles);
}

static double sinc_pi(double a)
{
    return fabs(a) < 1e-9 ? 1.0 : sin(M_PI * a) / (M_PI * a);
}

/* The scene: reflectors then clutter (x, y, amplitude); deterministic. */
static int tank_scene(const sasnav_tank_params *p, double **xs, double **ys, double **as, int *n)
{
    int m = p->n_reflectors + p->n_clutter;
    *n = m;
    *xs = malloc(sizeof(double) * (m + 1));
    *ys = malloc(sizeof(double) * (m + 1));
    *as = malloc(sizeof(double) * (m + 1));
    if (!*xs || !*ys || !*as) return sasnav_set_error(SASNAV_ERR_NOMEM, "tank: out of memory");
    for (int i = 0; i < p->n_reflectors; i++) {
        (*xs)[i] = p->refl_x[i];
        (*ys)[i] = p->refl_y[i];
        (*as)[i] = p->refl_amp[i];
    }
    sasnav_rng rng;
    sasnav_rng_seed(&rng, p->seed ^ 0x636c757474657221ULL);
    /* uniform points inside the regular octagon of circumradius R (rejection) */
    double R = p->plate_radius, apothem = R * cos(M_PI / 8);
    for (int i = p->n_reflectors; i < m; i++) {
        double x, y;
        for (;;) {
            x = (2 * sasnav_rng_uniform(&rng) - 1) * R;
            y = (2 * sasnav_rng_uniform(&rng) - 1) * R;
            int inside = 1;
            for (int k = 0; k < 8 && inside; k++) {
                double a = (k + 0.5) * M_PI / 4;
                if (x * cos(a) + y * sin(a) > apothem) inside = 0;
            }
            if (inside || R == 0) break;
        }
        (*xs)[i] = p->plate_x + x;
        (*ys)[i] = p->plate_y + y;
        (*as)[i] = p->clutter_std * sasnav_rng_normal(&rng);
    }
    return SASNAV_OK;
}

int sasnav_tank_scene(const sasnav_tank_params *p, double *x, double *y, double *amp)
{
    int rc = sasnav_tank_check(p);
    if (rc) return rc;
    if (!x || !y || !amp) return sasnav_set_error(SASNAV_ERR_ARG, "tank: scene output is NULL");
    double *xs = NULL, *ys = NULL, *as = NULL;
    int m = 0;
    rc = tank_scene(p, &xs, &ys, &as, &m);
    if (!rc) {
        memcpy(x, xs, sizeof(double) * m);
        memcpy(y, ys, sizeof(double) * m);
        memcpy(amp, as, sizeof(double) * m);
    }
    free(xs);
    free(ys);
    free(as);
    return rc;
}

int sasnav_tank_record(const sasnav_tank_params *p, int ping, float *passband,
                       sasnav_ping_pose *truth)
{
    int rc = sasnav_tank_check(p);
    if (rc) return rc;
    if (ping < 0 || ping >= p->n_pings)
        return sasnav_set_error(SASNAV_ERR_ARG, "tank: ping %d outside 0..%d", ping, p->n_pings - 1);
    if (!passband) return sasnav_set_error(SASNAV_ERR_ARG, "tank: output is NULL");
    int ns = sasnav_tank_n_samples(p), nc = sasnav_tank_n_chirp(p);
    sasnav_ping_pose *poses = malloc(sizeof *poses * p->n_pings);
    double *xs = NULL, *ys = NULL, *as = NULL, *acc = malloc(sizeof(double) * ns);
    int m = 0;
    if (!poses || !acc) {
        rc = sasnav_set_error(SASNAV_ERR_NOMEM, "tank: out of memory");
        goto done;
    }
    if ((rc = sasnav_tank_poses(p, NULL, poses))) goto done;
    if ((rc = tank_scene(p, &xs, &ys, &as, &m))) goto done;
    sasnav_ping_pose pose = poses[ping];
    if (truth) *truth = pose;

    const double fs = p->sample_rate, c = p->sound_speed, len = (nc - 1) / fs, h = p->array_height;
    /* element patterns at the centre frequency: sinc(D/lambda0 x the
     * direction's component along the array axis) */
    const double a_el = p->directivity ? p->element_length * 0.5 * (p->chirp.f_start + p->chirp.f_end) / c : 0.0;
    const double ca = cos(pose.array.theta), sa = sin(pose.array.theta);
    const double ct = cos(pose.tx.theta), st = sin(pose.tx.theta);
    sasnav_rng rng;
    sasnav_rng_seed(&rng, p->seed * 0x9e3779b97f4a7c15ULL + 0x6e6f697365ULL + (uint64_t)ping);
    for (int l = 0; l < p->n_rx; l++) {
        double u = (l - 0.5 * (p->n_rx - 1)) * p->rx_spacing;
        double rx = pose.array.x + u * cos(pose.array.theta);
        double ry = pose.array.y + u * sin(pose.array.theta);
        for (int n = 0; n < ns; n++) acc[n] = 0.0;
        for (int i = 0; i < m; i++) {
            double rt = sqrt((xs[i] - pose.tx.x) * (xs[i] - pose.tx.x) +
                             (ys[i] - pose.tx.y) * (ys[i] - pose.tx.y) + h * h);
            double rr = sqrt((xs[i] - rx) * (xs[i] - rx) + (ys[i] - ry) * (ys[i] - ry) + h * h);
            double att = 1.0;
            if (p->attenuation == SASNAV_ATTEN_SPHERICAL) att = 1.0 / (rt * rr);
            else if (p->attenuation == SASNAV_ATTEN_EXPLODING) att = 1.0 / sqrt(rt + rr);
            double dir = 1.0;
            if (a_el > 0) {
                dir = sinc_pi(a_el * ((xs[i] - pose.tx.x) * ct + (ys[i] - pose.tx.y) * st) / rt) *
                      sinc_pi(a_el * ((xs[i] - rx) * ca + (ys[i] - ry) * sa) / rr);
            }
            double a = p->gain * as[i] * att * dir, tau = (rt + rr) / c;
            long n0 = (long)ceil(tau * fs), n1 = (long)floor((tau + len) * fs);
            if (n0 < 0) n0 = 0;
            if (n1 > ns - 1) n1 = ns - 1;
            for (long n = n0; n <= n1; n++) acc[n] += a * chirp_at(&p->chirp, len, n / fs - tau);
        }
        float *out = passband + (size_t)l * ns;
        for (int n = 0; n < ns; n++)
            out[n] = (float)(acc[n] + p->noise_std * sasnav_rng_normal(&rng));
    }
done:
    free(poses);
    free(xs);
    free(ys);
    free(as);
    free(acc);
    return rc;
}
