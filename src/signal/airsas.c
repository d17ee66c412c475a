/* AirSAS processing: a recording (read by src/io/airsas.c) turned into a
 * sasnav run through the ingest chain (airsas.h): room-echo removal, pulse
 * compression, demodulation, decimation and the turntable's circular poses.
 * No file access here. */
#include "sasnav/airsas.h"
#include "sasnav/error.h"
#include "sasnav/geometry.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------ processing */

void sasnav_airsas_default_opts(sasnav_airsas_opts *opts)
{
    if (!opts) return;
    memset(opts, 0, sizeof *opts);
    opts->radius = 0.85;
    opts->microphone = 1;
    opts->ping_stride = 1;
    opts->remove_room = 1;
    opts->decimation = 4;
    opts->compression = SASNAV_COMPRESS_MODEL;
    opts->taper = SASNAV_TAPER_NONE;
    opts->clip_run = 3;
}

int sasnav_airsas_remove_room(int n_pings, int n, float *ts)
{
    if (!ts || n_pings < 1 || n < 1)
        return sasnav_set_error(SASNAV_ERR_ARG, "room removal: need records (%d pings x %d samples)",
                                n_pings, n);
    double *cm = calloc((size_t)n, sizeof *cm);
    if (!cm) return sasnav_set_error(SASNAV_ERR_NOMEM, "room removal: out of memory");
    for (int p = 0; p < n_pings; p++)
        for (int m = 0; m < n; m++) cm[m] += ts[(size_t)p * n + m];
    for (int m = 0; m < n; m++) cm[m] /= n_pings;
    for (int p = 0; p < n_pings; p++) {
        float *x = ts + (size_t)p * n;
        for (int m = 0; m < n; m++) {
            /* arg of a real number: 0 for >= 0 (numpy's angle(0) = 0), pi below */
            double arg_cm = cm[m] < 0 ? M_PI : 0.0, arg_ts = x[m] < 0 ? M_PI : 0.0;
            double dang = sasnav_wrap_angle(arg_cm - arg_ts);
            double beta = 1.0 / (1.0 + dang * dang);
            double dmag = fabs(cm[m]) - fabs((double)x[m]);
            double alpha = 1.0 / (1.0 + dmag * dmag);
            double sign = x[m] < 0 ? -1.0 : 1.0; /* exp(j arg(ts)) */
            x[m] = (float)(x[m] - alpha * beta * fabs(cm[m]) * sign);
        }
    }
    free(cm);
    return SASNAV_OK;
}

static int opts_check(const sasnav_airsas *rec, const sasnav_airsas_opts *o)
{
    if (!isfinite(o->radius) || !(o->radius > 0))
        return sasnav_set_error(SASNAV_ERR_ARG, "airsas: radius must be > 0, got %g m", o->radius);
    if (o->microphone != 1 && o->microphone != 2)
        return sasnav_set_error(SASNAV_ERR_ARG, "airsas: microphone must be 1 or 2, got %d", o->microphone);
    if (o->microphone > rec->n_channels)
        return sasnav_set_error(SASNAV_ERR_ARG, "airsas: microphone %d asked, the flights have %d column(s)",
                                o->microphone, rec->n_channels);
    if (o->microphone == 2 && !rec->has_mic2)
        return sasnav_set_error(SASNAV_ERR_ARG, "airsas: SysParams.csv gives no Mic2 position");
    if (o->first_ping < 0 || o->first_ping >= rec->n_pings)
        return sasnav_set_error(SASNAV_ERR_ARG, "airsas: first ping %d outside 0..%d", o->first_ping,
                                rec->n_pings - 1);
    if (o->ping_stride < 1)
        return sasnav_set_error(SASNAV_ERR_ARG, "airsas: ping stride must be >= 1, got %d", o->ping_stride);
    if (o->max_pings < 0)
        return sasnav_set_error(SASNAV_ERR_ARG, "airsas: max_pings must be >= 0, got %d", o->max_pings);
    if (!isfinite(o->f0) || o->f0 < 0 || !isfinite(o->bandwidth) || o->bandwidth < 0)
        return sasnav_set_error(SASNAV_ERR_ARG, "airsas: f0 and bandwidth must be >= 0 (0: from the chirp)");
    for (int p = 1; p < rec->n_pings; p++)
        if (fabs(rec->height_mm[p] - rec->height_mm[0]) > 1e-6)
            return sasnav_set_error(SASNAV_ERR_ARG,
                                    "airsas: flight %d is at height %g mm, flight 1 at %g mm (one "
                                    "array height per run)",
                                    p + 1, rec->height_mm[p], rec->height_mm[0]);
    return SASNAV_OK;
}

static int background_check(const sasnav_airsas *rec, const sasnav_airsas *bg)
{
    if (bg->n_pings != rec->n_pings || bg->n_samples != rec->n_samples ||
        bg->n_channels != rec->n_channels)
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "airsas: the background has %d pings x %d samples x %d channels, "
                                "the recording %d x %d x %d",
                                bg->n_pings, bg->n_samples, bg->n_channels, rec->n_pings,
                                rec->n_samples, rec->n_channels);
    if (bg->sample_rate != rec->sample_rate)
        return sasnav_set_error(SASNAV_ERR_ARG, "airsas: the background is sampled at %g Hz, the recording at %g Hz",
                                bg->sample_rate, rec->sample_rate);
    return SASNAV_OK;
}

/* Raw records of one microphone, minus the background: ts[p * n + m]. The
 * raw records (and the background's) are checked by the ingest plan first
 * (finite, not clipped). */
static int gather_records(const sasnav_airsas *rec, const sasnav_airsas *bg, int mic,
                          const sasnav_ingest *check, float **out)
{
    size_t n = (size_t)rec->n_samples;
    float *ts = malloc(sizeof(float) * n * (size_t)rec->n_pings);
    if (!ts) return sasnav_set_error(SASNAV_ERR_NOMEM, "airsas: out of memory");
    for (int p = 0; p < rec->n_pings; p++) {
        const float *x = rec->samples + ((size_t)p * rec->n_channels + mic) * n;
        const float *b = bg ? bg->samples + ((size_t)p * bg->n_channels + mic) * n : NULL;
        int rc = sasnav_ingest_check_record(check, 1, x);
        const char *which = "";
        if (!rc && b) {
            rc = sasnav_ingest_check_record(check, 1, b);
            which = " (background)";
        }
        if (rc) {
            free(ts);
            return sasnav_prefix_error(rc, "airsas: flight %d%s", p + 1, which);
        }
        for (size_t m = 0; m < n; m++) ts[(size_t)p * n + m] = b ? x[m] - b[m] : x[m];
    }
    *out = ts;
    return SASNAV_OK;
}

static int make_plan(const sasnav_airsas *rec, const sasnav_airsas_opts *o, sasnav_ingest **plan)
{
    int nc = sasnav_lfm_length(&rec->lfm, rec->sample_rate);
    if (nc < 1) return SASNAV_ERR_ARG;
    float *chirp = malloc(sizeof(float) * (size_t)nc);
    if (!chirp) return sasnav_set_error(SASNAV_ERR_NOMEM, "airsas: out of memory");
    int rc = sasnav_lfm_samples(&rec->lfm, rec->sample_rate, nc, chirp);
    sasnav_ingest_opts io;
    sasnav_ingest_default_opts(&io);
    io.sample_rate = rec->sample_rate;
    io.t_start = -rec->group_delay / rec->sample_rate;
    io.f0 = o->f0 > 0 ? o->f0 : 0.5 * (rec->lfm.f_start + rec->lfm.f_end);
    io.bandwidth = o->bandwidth > 0 ? o->bandwidth : fabs(rec->lfm.f_end - rec->lfm.f_start);
    io.decimation = o->decimation;
    io.compression = o->compression;
    io.taper = o->taper;
    io.clip_run = o->clip_run;
    if (!rc) rc = sasnav_ingest_create(&io, rec->n_samples, chirp, nc, plan);
    free(chirp);
    return rc;
}

/* The circle: ping p at a = 90 - angle degrees, yaw a + 90 degrees. */
static sasnav_ping_pose circle_pose(double radius, double angle_deg)
{
    double a = (90.0 - angle_deg) * M_PI / 180.0;
    sasnav_pose pose = {radius * cos(a), radius * sin(a), sasnav_wrap_angle(a + 0.5 * M_PI)};
    sasnav_ping_pose ping = {pose, pose};
    return ping;
}

int sasnav_airsas_to_run(const sasnav_airsas *rec, const sasnav_airsas *background,
                         const sasnav_airsas_opts *opts, sasnav_run **run)
{
    if (!run) return sasnav_set_error(SASNAV_ERR_ARG, "airsas: run output pointer is NULL");
    *run = NULL;
    if (!rec || !rec->samples) return sasnav_set_error(SASNAV_ERR_ARG, "airsas: no recording");
    sasnav_airsas_opts o;
    if (opts)
        o = *opts;
    else
        sasnav_airsas_default_opts(&o);
    int rc = opts_check(rec, &o);
    if (!rc && background) rc = background_check(rec, background);
    if (rc) return rc;

    /* Kept pings. */
    int n_keep = (rec->n_pings - 1 - o.first_ping) / o.ping_stride + 1;
    if (o.max_pings > 0 && n_keep > o.max_pings) n_keep = o.max_pings;

    sasnav_ingest *plan = NULL;
    rc = make_plan(rec, &o, &plan);
    if (rc) return rc;
    float *ts = NULL;
    rc = gather_records(rec, background, o.microphone - 1, plan, &ts);
    if (!rc && o.remove_room) rc = sasnav_airsas_remove_room(rec->n_pings, rec->n_samples, ts);

    sasnav_system sys;
    sasnav_system_default(&sys);
    double t_mean = 0;
    for (int p = 0; p < rec->n_pings; p++) t_mean += rec->temperature[p];
    t_mean /= rec->n_pings;
    sys.sound_speed = 331.4 + 0.6 * t_mean;
    sys.attenuation = SASNAV_ATTEN_NONE;
    sys.beam_pattern = 0;
    sasnav_array array;
    memset(&array, 0, sizeof array);
    array.n_rx = 1;
    double h = rec->height_mm[0] / 1000.0 - rec->center[2];
    array.tx_height = rec->speaker[2] + h;
    array.rx_height = rec->mic[o.microphone - 1][2] + h;
    sasnav_window win;
    sasnav_run *r = NULL;
    if (!rc) rc = sasnav_ingest_system(plan, &sys);
    if (!rc) rc = sasnav_ingest_window(plan, &win);
    if (!rc) rc = sasnav_run_alloc(&sys, &array, &win, n_keep, 0, &r);
    for (int k = 0; !rc && k < n_keep; k++) {
        int p = o.first_ping + k * o.ping_stride;
        rc = sasnav_ingest_execute(plan, 1, ts + (size_t)p * rec->n_samples, sasnav_run_ping(r, k));
        if (rc) rc = sasnav_prefix_error(rc, "airsas: flight %d", p + 1);
        r->nav[k] = circle_pose(o.radius, rec->angle_deg[p]);
    }
    free(ts);
    sasnav_ingest_destroy(plan);
    if (rc) {
        sasnav_run_free(r);
        return rc;
    }
    double step = n_keep > 1 ? fabs(rec->angle_deg[o.first_ping + o.ping_stride] -
                                    rec->angle_deg[o.first_ping])
                             : 0.0;
    r->ping_spacing = o.radius * step * M_PI / 180.0;
    r->speed = 0;
    r->tx_lag = 0;
    r->range_of_interest = o.radius;
    /* the recording's numbers may still make an invalid run (a Group Delay
     * that puts the whole window before t = 0, an angle step that overflows
     * ping_spacing): found by fuzz_airsas_dir, docs/fuzzing.md */
    rc = sasnav_run_check(r);
    if (rc) {
        sasnav_run_free(r);
        return sasnav_prefix_error(rc, "airsas");
    }
    *run = r;
    return SASNAV_OK;
}
