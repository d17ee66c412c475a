/* The tank experiment of SPEC 4: passband simulator and WAV recording
 * reader (include/sasnav/tank.h). */
#include "sasnav/tank.h"

#include "sasnav/error.h"
#include "sasnav/scene.h"
#include "io/textfile.h"

#include <errno.h>
#include <math.h>
#include <sndfile.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

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

/* ------------------------------------------------------------- writing */

static int join(char *buf, size_t size, const char *dir, const char *name)
{
    int k = snprintf(buf, size, "%s/%s", dir, name);
    if (k < 0 || (size_t)k >= size)
        return sasnav_set_error(SASNAV_ERR_ARG, "path too long: %s/%s", dir, name);
    return SASNAV_OK;
}

/* Writes n_frames x n_ch samples (channel-major input) to `path` via a
 * temporary file renamed into place. */
static int write_wav(const char *path, const float *data, int n_ch, int n_frames, double fs)
{
    char tmp[4200];
    int k = snprintf(tmp, sizeof tmp, "%s.tmp%ld", path, (long)getpid());
    if (k < 0 || (size_t)k >= sizeof tmp) return sasnav_set_error(SASNAV_ERR_ARG, "path too long: %s", path);
    float *frames = malloc(sizeof(float) * (size_t)n_ch * n_frames);
    if (!frames) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory writing %s", path);
    for (int n = 0; n < n_frames; n++)
        for (int l = 0; l < n_ch; l++) frames[(size_t)n * n_ch + l] = data[(size_t)l * n_frames + n];
    SF_INFO info;
    memset(&info, 0, sizeof info);
    info.samplerate = (int)lround(fs);
    info.channels = n_ch;
    info.format = SF_FORMAT_WAV | SF_FORMAT_FLOAT;
    SNDFILE *f = sf_open(tmp, SFM_WRITE, &info);
    if (!f) {
        free(frames);
        return sasnav_set_error(SASNAV_ERR_IO, "cannot create %s: %s", tmp, sf_strerror(NULL));
    }
    sf_count_t w = sf_writef_float(f, frames, n_frames);
    free(frames);
    int close_rc = sf_close(f);
    if (w != n_frames || close_rc != 0) {
        unlink(tmp);
        return sasnav_set_error(SASNAV_ERR_IO, "cannot write %s (%lld of %d frames)", tmp,
                                (long long)w, n_frames);
    }
    if (rename(tmp, path)) {
        int e = errno;
        unlink(tmp);
        return sasnav_set_error(SASNAV_ERR_IO, "cannot rename %s to %s: %s", tmp, path, strerror(e));
    }
    return SASNAV_OK;
}

static int write_poses_csv(const char *path, const sasnav_ping_pose *poses, int n)
{
    char tmp[4200];
    int k = snprintf(tmp, sizeof tmp, "%s.tmp%ld", path, (long)getpid());
    if (k < 0 || (size_t)k >= sizeof tmp) return sasnav_set_error(SASNAV_ERR_ARG, "path too long: %s", path);
    FILE *f = fopen(tmp, "w");
    if (!f) return sasnav_set_error(SASNAV_ERR_IO, "cannot create %s: %s", tmp, strerror(errno));
    fprintf(f, "ping,x,y,yaw\n");
    for (int i = 0; i < n; i++)
        fprintf(f, "%d,%.9f,%.9f,%.9e\n", i, poses[i].array.x, poses[i].array.y,
                poses[i].array.theta);
    int bad = ferror(f);
    if (fclose(f) || bad) {
        unlink(tmp);
        return sasnav_set_error(SASNAV_ERR_IO, "cannot write %s", tmp);
    }
    if (rename(tmp, path)) {
        int e = errno;
        unlink(tmp);
        return sasnav_set_error(SASNAV_ERR_IO, "cannot rename %s to %s: %s", tmp, path, strerror(e));
    }
    return SASNAV_OK;
}

int sasnav_tank_write_dir(const sasnav_tank_params *p, const char *dir)
{
    int rc = sasnav_tank_check(p);
    if (rc) return rc;
    if (!dir || !*dir) return sasnav_set_error(SASNAV_ERR_ARG, "tank: no output directory");
    if (mkdir(dir, 0777) && errno != EEXIST)
        return sasnav_set_error(SASNAV_ERR_IO, "cannot create %s: %s", dir, strerror(errno));
    struct stat st;
    if (stat(dir, &st) || !S_ISDIR(st.st_mode))
        return sasnav_set_error(SASNAV_ERR_IO, "%s is not a directory", dir);
    int ns = sasnav_tank_n_samples(p), nc = sasnav_tank_n_chirp(p);
    float *buf = malloc(sizeof(float) * (size_t)p->n_rx * ns);
    float *chirp = malloc(sizeof(float) * nc);
    sasnav_ping_pose *nom = malloc(sizeof *nom * p->n_pings), *tru = malloc(sizeof *tru * p->n_pings);
    char path[4096], name[64];
    if (!buf || !chirp || !nom || !tru) {
        rc = sasnav_set_error(SASNAV_ERR_NOMEM, "tank: out of memory");
        goto done;
    }
    if ((rc = sasnav_lfm_samples(&p->chirp, p->sample_rate, nc, chirp))) goto done;
    if ((rc = join(path, sizeof path, dir, "chirp.wav"))) goto done;
    if ((rc = write_wav(path, chirp, 1, nc, p->sample_rate))) goto done;
    if ((rc = sasnav_tank_poses(p, nom, tru))) goto done;
    for (int k = 0; k < p->n_pings; k++) {
        if ((rc = sasnav_tank_record(p, k, buf, NULL))) goto done;
        snprintf(name, sizeof name, "ping_%03d.wav", k);
        if ((rc = join(path, sizeof path, dir, name))) goto done;
        if ((rc = write_wav(path, buf, p->n_rx, ns, p->sample_rate))) goto done;
    }
    if ((rc = join(path, sizeof path, dir, "positions.csv"))) goto done;
    if ((rc = write_poses_csv(path, nom, p->n_pings))) goto done;
    if ((rc = join(path, sizeof path, dir, "truth.csv"))) goto done;
    if ((rc = write_poses_csv(path, tru, p->n_pings))) goto done;
    /* the sensor description the reader needs to model the recording */
    if ((rc = join(path, sizeof path, dir, "array.csv"))) goto done;
    sasnav_text_out ao;
    if ((rc = sasnav_text_open(&ao, path))) goto done;
    fprintf(ao.f, "rx_spacing,element_length,directivity\n%.9g,%.9g,%d\n", p->rx_spacing,
            p->element_length, p->directivity);
    rc = sasnav_text_commit(&ao);
done:
    free(buf);
    free(chirp);
    free(nom);
    free(tru);
    return rc;
}

/* ------------------------------------------------------------- reading */

void sasnav_tank_default_read_opts(sasnav_tank_read_opts *o)
{
    if (!o) return;
    memset(o, 0, sizeof *o);
    o->sound_speed = 1480.0;
    o->f0 = 105e3;
    o->bandwidth = 30e3;
    o->decimation = 33;
    o->taper = SASNAV_TAPER_NONE;
    o->compression = SASNAV_COMPRESS_MODEL;
    o->attenuation = SASNAV_ATTEN_SPHERICAL;
    o->clip_run = 3;
    o->rx_spacing = 0.05;
    o->element_length = 0.05;
    o->directivity = 1;
    o->range_of_interest = 1.5;
}

/* array.csv (optional): "rx_spacing,element_length,directivity" and one
 * line of values; overrides the options. */
static int read_array_csv(const char *path, sasnav_tank_read_opts *o)
{
    FILE *f = fopen(path, "r");
    if (!f) return sasnav_set_error(SASNAV_ERR_IO, "cannot open %s", path);
    char head[256];
    double sp, el;
    int dir, ok = fgets(head, sizeof head, f) != NULL &&
                  !strncmp(head, "rx_spacing,element_length,directivity", 37) &&
                  fscanf(f, "%lf,%lf,%d", &sp, &el, &dir) == 3;
    fclose(f);
    if (!ok || !isfinite(sp) || sp <= 0 || !isfinite(el) || el < 0 || (dir != 0 && dir != 1))
        return sasnav_set_error(SASNAV_ERR_FORMAT,
                                "%s: expected 'rx_spacing,element_length,directivity' and one line of "
                                "values (spacing > 0, length >= 0, directivity 0 or 1)",
                                path);
    o->rx_spacing = sp;
    o->element_length = el;
    o->directivity = dir;
    return SASNAV_OK;
}

/* Reads a whole WAV into channel-major samples. */
static int read_wav(const char *path, int *n_ch, int *n_frames, int *rate, float **data)
{
    *data = NULL;
    SF_INFO info;
    memset(&info, 0, sizeof info);
    SNDFILE *f = sf_open(path, SFM_READ, &info);
    if (!f) {
        struct stat st;
        if (stat(path, &st))
            return sasnav_set_error(SASNAV_ERR_IO, "cannot open %s: %s", path, strerror(errno));
        return sasnav_set_error(SASNAV_ERR_FORMAT, "%s is not a readable sound file: %s", path,
                                sf_strerror(NULL));
    }
    int rc = SASNAV_OK;
    if (info.frames <= 0)
        rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s is empty (no samples)", path);
    else if (info.channels < 1 || info.channels > SASNAV_MAX_RX)
        rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s has %d channels (1..%d supported)", path,
                              info.channels, SASNAV_MAX_RX);
    else if (info.frames > 100000000 / info.channels)
        rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s is too long (%lld frames)", path,
                              (long long)info.frames);
    else if (info.samplerate <= 0)
        rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s has sample rate %d", path, info.samplerate);
    float *frames = NULL, *out = NULL;
    if (!rc) {
        frames = malloc(sizeof(float) * (size_t)info.channels * info.frames);
        out = malloc(sizeof(float) * (size_t)info.channels * info.frames);
        if (!frames || !out) rc = sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory reading %s", path);
    }
    if (!rc) {
        sf_count_t got = sf_readf_float(f, frames, info.frames);
        if (got != info.frames)
            rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s: read %lld of %lld frames (truncated?)", path,
                                  (long long)got, (long long)info.frames);
    }
    sf_close(f);
    if (!rc) {
        int nf = (int)info.frames, nch = info.channels;
        for (int n = 0; n < nf; n++)
            for (int l = 0; l < nch; l++) out[(size_t)l * nf + n] = frames[(size_t)n * nch + l];
        *n_ch = nch;
        *n_frames = nf;
        *rate = info.samplerate;
        *data = out;
        out = NULL;
    }
    free(frames);
    free(out);
    return rc;
}

/* Reads "ping,x,y,yaw" rows 0..n-1 into poses (Tx = array). *n = 0 and
 * SASNAV_ERR_IO when the file is missing. */
static int read_poses_csv(const char *path, sasnav_ping_pose **poses, int *n)
{
    *poses = NULL;
    *n = 0;
    FILE *f = fopen(path, "r");
    if (!f) return sasnav_set_error(SASNAV_ERR_IO, "cannot open %s: %s", path, strerror(errno));
    char line[512];
    int cap = 0, rc = SASNAV_OK, lineno = 0;
    sasnav_ping_pose *v = NULL;
    while (fgets(line, sizeof line, f)) {
        lineno++;
        char *s = line;
        while (*s == ' ' || *s == '\t') s++;
        if (*s == '\n' || *s == '\r' || *s == '\0' || *s == '#') continue;
        if (lineno == 1 && !strncmp(s, "ping", 4)) continue; /* header */
        int k;
        double x, y, yaw;
        char extra;
        if (sscanf(s, "%d ,%lf ,%lf ,%lf %c", &k, &x, &y, &yaw, &extra) != 4 || !isfinite(x) ||
            !isfinite(y) || !isfinite(yaw)) {
            rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s line %d: expected 'ping,x,y,yaw'", path,
                                  lineno);
            break;
        }
        if (k != *n) {
            rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s line %d: ping %d, expected %d", path,
                                  lineno, k, *n);
            break;
        }
        if (*n >= 1000000) {
            rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s: too many pings", path);
            break;
        }
        if (*n == cap) {
            cap = cap ? 2 * cap : 64;
            sasnav_ping_pose *t = realloc(v, sizeof *v * cap);
            if (!t) {
                rc = sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory reading %s", path);
                break;
            }
            v = t;
        }
        sasnav_pose q = {x, y, yaw};
        v[*n].tx = q;
        v[*n].array = q;
        (*n)++;
    }
    fclose(f);
    if (!rc && *n == 0) rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s lists no ping", path);
    if (rc) {
        free(v);
        *n = 0;
        return rc;
    }
    *poses = v;
    return SASNAV_OK;
}

int sasnav_tank_read_dir(const char *dir, const sasnav_tank_read_opts *o_in, sasnav_run **run)
{
    if (!run) return sasnav_set_error(SASNAV_ERR_ARG, "tank: run output is NULL");
    *run = NULL;
    if (!dir || !o_in) return sasnav_set_error(SASNAV_ERR_ARG, "tank: NULL directory or options");
    sasnav_tank_read_opts oc = *o_in;
    const sasnav_tank_read_opts *o = &oc;
    if (!isfinite(o->sound_speed) || o->sound_speed <= 0 || !isfinite(o->range_of_interest) ||
        o->range_of_interest <= 0)
        return sasnav_set_error(SASNAV_ERR_ARG, "tank: bad sound speed or range of interest");
    char path[4096];
    sasnav_ping_pose *nav = NULL, *truth = NULL;
    float *chirp = NULL, *rec = NULL;
    sasnav_ingest *plan = NULL;
    sasnav_run *r = NULL;
    int n_pings = 0, n_truth = 0, rc;

    if ((rc = join(path, sizeof path, dir, "array.csv"))) return rc;
    if (access(path, F_OK) == 0 && (rc = read_array_csv(path, &oc))) return rc;
    if ((rc = join(path, sizeof path, dir, "positions.csv"))) return rc;
    if ((rc = read_poses_csv(path, &nav, &n_pings))) return rc;
    if ((rc = join(path, sizeof path, dir, "truth.csv"))) goto done;
    if (access(path, F_OK) == 0) {
        if ((rc = read_poses_csv(path, &truth, &n_truth))) goto done;
        if (n_truth != n_pings) {
            rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s lists %d pings, positions.csv %d", path,
                                  n_truth, n_pings);
            goto done;
        }
    }

    int nch_c, nc, rate_c;
    if ((rc = join(path, sizeof path, dir, "chirp.wav"))) goto done;
    if ((rc = read_wav(path, &nch_c, &nc, &rate_c, &chirp))) goto done;
    if (nch_c != 1) {
        rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s has %d channels, the chirp must be mono", path,
                              nch_c);
        goto done;
    }

    int n_rx = 0, n_in = 0;
    for (int k = 0; k < n_pings; k++) {
        char name[64];
        snprintf(name, sizeof name, "ping_%03d.wav", k);
        if ((rc = join(path, sizeof path, dir, name))) goto done;
        int nch, nf, rate;
        free(rec);
        rec = NULL;
        if ((rc = read_wav(path, &nch, &nf, &rate, &rec))) goto done;
        if (rate != rate_c) {
            rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s: sample rate %d Hz, chirp.wav %d Hz", path,
                                  rate, rate_c);
            goto done;
        }
        if (k == 0) {
            n_rx = nch;
            n_in = nf;
            sasnav_ingest_opts io;
            sasnav_ingest_default_opts(&io);
            io.sample_rate = rate;
            io.t_start = 0.0;
            io.f0 = o->f0;
            io.bandwidth = o->bandwidth;
            io.decimation = o->decimation;
            io.compression = o->compression;
            io.taper = o->taper;
            io.clip_run = o->clip_run;
            if ((rc = sasnav_ingest_create(&io, n_in, chirp, nc, &plan))) goto done;
            sasnav_system sys;
            sasnav_system_default(&sys);
            if ((rc = sasnav_ingest_system(plan, &sys))) goto done;
            sys.sound_speed = o->sound_speed;
            sys.attenuation = o->attenuation;
            sys.beam_pattern = o->directivity ? 1 : 0;
            sasnav_array a;
            if ((rc = sasnav_array_uniform(&a, n_rx, o->rx_spacing, o->element_length,
                                           o->element_length)))
                goto done;
            sasnav_window win;
            if ((rc = sasnav_ingest_window(plan, &win))) goto done;
            if ((rc = sasnav_run_alloc(&sys, &a, &win, n_pings, truth != NULL, &r))) goto done;
        } else if (nch != n_rx) {
            rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s has %d channels, ping_000.wav %d", path,
                                  nch, n_rx);
            goto done;
        } else if (nf != n_in) {
            rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s has %d samples per channel, ping_000.wav %d",
                                  path, nf, n_in);
            goto done;
        }
        if (sasnav_ingest_check_record(plan, n_rx, rec)) {
            char why[512];
            snprintf(why, sizeof why, "%s", sasnav_last_error());
            rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s: %s", path, why);
            goto done;
        }
        if ((rc = sasnav_ingest_execute(plan, n_rx, rec, sasnav_run_ping(r, k)))) goto done;
    }
    memcpy(r->nav, nav, sizeof *nav * n_pings);
    if (truth) memcpy(r->truth, truth, sizeof *truth * n_pings);
    r->ping_spacing = n_pings > 1 ? fabs(nav[n_pings - 1].array.x - nav[0].array.x) / (n_pings - 1)
                                  : 0.0;
    r->speed = 0.0;
    r->tx_lag = 0.0;
    r->range_of_interest = o->range_of_interest;
    rc = sasnav_run_check(r);
done:
    if (rc) sasnav_run_free(r);
    else *run = r;
    sasnav_ingest_destroy(plan);
    free(nav);
    free(truth);
    free(chirp);
    free(rec);
    return rc;
}
