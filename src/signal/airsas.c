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

/* The room removal of one record x (n samples) with the mean cm. */
static void remove_room_record(int n, const double *cm, float *x)
{
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
    for (int p = 0; p < n_pings; p++) remove_room_record(n, cm, ts + (size_t)p * n);
    free(cm);
    return SASNAV_OK;
}

static int opts_check(const sasnav_airsas *rec, const sasnav_airsas_opts *o)
{
    if (!isfinite(o->radius) || !(o->radius > 0))
        return sasnav_set_error(SASNAV_ERR_ARG, "airsas: radius must be > 0, got %g m", o->radius);
    if (o->microphone < 0 || o->microphone > 2)
        return sasnav_set_error(SASNAV_ERR_ARG, "airsas: microphone must be 1, 2 or 0 (both), got %d",
                                o->microphone);
    if ((o->microphone == 0 ? 2 : o->microphone) > rec->n_channels)
        return sasnav_set_error(SASNAV_ERR_ARG, "airsas: microphone %s asked, the flights have %d column(s)",
                                o->microphone == 0 ? "1 and 2" : o->microphone == 1 ? "1" : "2",
                                rec->n_channels);
    if (o->microphone != 1 && !rec->has_mic2)
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

/* Scratch of one flight of a recording and of its background, for
 * recordings opened with sasnav_airsas_open (NULL for one read whole). */
typedef struct {
    float *rec, *bg;
} flight_scratch;

/* The raw record of microphone `mic` (index) of flight p, minus the
 * background's, into ts (n_samples values). The raw records (and the
 * background's) are checked by the ingest plan first (finite, not
 * clipped). `again`: the scratch already holds flight p (a second
 * microphone of the same flight), not read a second time. */
static int flight_record(const sasnav_airsas *rec, const sasnav_airsas *bg, int p, int mic, int again,
                         const sasnav_ingest *check, const flight_scratch *scratch, float *ts)
{
    size_t n = (size_t)rec->n_samples;
    const float *x, *b = NULL;
    int rc = SASNAV_OK;
    if (rec->samples) {
        x = rec->samples + ((size_t)p * rec->n_channels + mic) * n;
    } else {
        if (!again) rc = rec->read_flight(rec->flight_ctx, p, scratch->rec);
        x = scratch->rec + (size_t)mic * n;
    }
    if (!rc && bg) {
        if (bg->samples) {
            b = bg->samples + ((size_t)p * bg->n_channels + mic) * n;
        } else {
            if (!again) rc = bg->read_flight(bg->flight_ctx, p, scratch->bg);
            b = scratch->bg + (size_t)mic * n;
        }
    }
    if (rc) return rc;
    rc = sasnav_ingest_check_record(check, 1, x);
    const char *which = "";
    if (!rc && b) {
        rc = sasnav_ingest_check_record(check, 1, b);
        which = " (background)";
    }
    if (rc) return sasnav_prefix_error(rc, "airsas: flight %d%s", p + 1, which);
    for (size_t m = 0; m < n; m++) ts[m] = b ? x[m] - b[m] : x[m];
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

static int has_flights(const sasnav_airsas *r) { return r->samples || r->read_flight; }

int sasnav_airsas_stream(const sasnav_airsas *rec, const sasnav_airsas *background,
                         const sasnav_airsas_opts *opts, const sasnav_airsas_sink *sink)
{
    if (!sink || !sink->begin || !sink->ping) return sasnav_set_error(SASNAV_ERR_ARG, "airsas: no sink");
    if (!rec || !has_flights(rec)) return sasnav_set_error(SASNAV_ERR_ARG, "airsas: no recording");
    if (background && !has_flights(background))
        return sasnav_set_error(SASNAV_ERR_ARG, "airsas: the background holds no flights");
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
    size_t n = (size_t)rec->n_samples, flight = n * (size_t)rec->n_channels;
    /* the microphones used: channel c of the run is microphone mics[c] */
    int n_mic = o.microphone == 0 ? 2 : 1;
    int mics[2] = {o.microphone == 0 ? 0 : o.microphone - 1, 1};
    flight_scratch scratch = {NULL, NULL};
    float *ts = malloc(sizeof(float) * n);
    double *cm = calloc(n * (size_t)n_mic, sizeof *cm);
    sasnav_ping_pose *nav = malloc(sizeof *nav * (size_t)n_keep);
    if (!rec->samples) scratch.rec = malloc(sizeof(float) * flight);
    if (background && !background->samples) scratch.bg = malloc(sizeof(float) * flight);
    sasnav_cfloat *out = NULL;
    if (!ts || !cm || !nav || (!rec->samples && !scratch.rec) || (background && !background->samples && !scratch.bg))
        rc = sasnav_set_error(SASNAV_ERR_NOMEM, "airsas: out of memory");

    /* Pass 1 over every flight of the recording (kept or not): the records
     * checked, and their mean (the room response). */
    for (int p = 0; !rc && p < rec->n_pings; p++)
        for (int c = 0; !rc && c < n_mic; c++) {
            rc = flight_record(rec, background, p, mics[c], c > 0, plan, &scratch, ts);
            for (size_t m = 0; !rc && o.remove_room && m < n; m++) cm[c * n + m] += ts[m];
        }
    for (size_t m = 0; !rc && o.remove_room && m < n * (size_t)n_mic; m++) cm[m] /= rec->n_pings;

    /* The run's header. */
    sasnav_run hdr;
    memset(&hdr, 0, sizeof hdr);
    sasnav_system_default(&hdr.sys);
    double t_mean = 0;
    for (int p = 0; p < rec->n_pings; p++) t_mean += rec->temperature[p];
    t_mean /= rec->n_pings;
    hdr.sys.sound_speed = 331.4 + 0.6 * t_mean;
    hdr.sys.attenuation = SASNAV_ATTEN_NONE;
    hdr.sys.beam_pattern = 0;
    hdr.array.n_rx = n_mic;
    double h = rec->height_mm[0] / 1000.0 - rec->center[2];
    hdr.array.tx_height = rec->speaker[2] + h;
    hdr.array.rx_height = rec->mic[mics[0]][2] + h;
    if (n_mic == 2) { /* both at the array's origin, each at its own height */
        sasnav_channel_size z[2];
        for (int c = 0; c < 2; c++) {
            sasnav_channel_size zc = {0.0, 0.0, rec->mic[mics[c]][2] + h, hdr.array.tx_height};
            z[c] = zc;
        }
        if (!rc) rc = sasnav_array_set_sizes(&hdr.array, z);
    }
    if (!rc) rc = sasnav_ingest_system(plan, &hdr.sys);
    if (!rc) rc = sasnav_ingest_window(plan, &hdr.win);
    if (!rc) {
        hdr.n_pings = n_keep;
        hdr.nav = nav;
        for (int k = 0; k < n_keep; k++) nav[k] = circle_pose(o.radius, rec->angle_deg[o.first_ping + k * o.ping_stride]);
        double step = n_keep > 1 ? fabs(rec->angle_deg[o.first_ping + o.ping_stride] - rec->angle_deg[o.first_ping])
                                 : 0.0;
        hdr.ping_spacing = o.radius * step * M_PI / 180.0;
        hdr.speed = 0;
        hdr.tx_lag = 0;
        hdr.range_of_interest = o.radius;
        /* the recording's numbers may still make an invalid run (a Group
         * Delay that puts the whole window before t = 0, an angle step that
         * overflows ping_spacing): found by fuzz_airsas_dir, docs/fuzzing.md */
        rc = sasnav_run_check_header(&hdr);
        if (rc) rc = sasnav_prefix_error(rc, "airsas");
    }
    if (!rc) {
        out = malloc(sizeof *out * (size_t)hdr.win.n_samples * (size_t)n_mic);
        if (!out) rc = sasnav_set_error(SASNAV_ERR_NOMEM, "airsas: out of memory");
    }
    if (!rc) rc = sink->begin(sink->ctx, &hdr);

    /* Pass 2: each kept flight, its room response removed, through the
     * ingest chain. */
    for (int k = 0; !rc && k < n_keep; k++) {
        int p = o.first_ping + k * o.ping_stride;
        for (int c = 0; !rc && c < n_mic; c++) {
            rc = flight_record(rec, background, p, mics[c], c > 0, plan, &scratch, ts);
            if (!rc && o.remove_room) remove_room_record((int)n, cm + c * n, ts);
            if (!rc) {
                rc = sasnav_ingest_execute(plan, 1, ts, out + (size_t)c * (size_t)hdr.win.n_samples);
                if (rc) rc = sasnav_prefix_error(rc, "airsas: flight %d", p + 1);
            }
        }
        if (!rc) rc = sink->ping(sink->ctx, k, out);
    }
    free(out);
    free(ts);
    free(cm);
    free(nav);
    free(scratch.rec);
    free(scratch.bg);
    sasnav_ingest_destroy(plan);
    return rc;
}

/* sasnav_airsas_to_run's sink: the run in memory. */
static int run_begin(void *ctx, const sasnav_run *hdr)
{
    sasnav_run **r = ctx;
    int rc = sasnav_run_alloc(&hdr->sys, &hdr->array, &hdr->win, hdr->n_pings, 0, r);
    if (rc) return rc;
    memcpy((*r)->nav, hdr->nav, sizeof *hdr->nav * (size_t)hdr->n_pings);
    (*r)->ping_spacing = hdr->ping_spacing;
    (*r)->speed = hdr->speed;
    (*r)->tx_lag = hdr->tx_lag;
    (*r)->range_of_interest = hdr->range_of_interest;
    return SASNAV_OK;
}

static int run_ping(void *ctx, int k, const sasnav_cfloat *samples)
{
    sasnav_run *r = *(sasnav_run **)ctx;
    memcpy(sasnav_run_ping(r, k), samples, sizeof *samples * sasnav_run_ping_size(r));
    return SASNAV_OK;
}

int sasnav_airsas_to_run(const sasnav_airsas *rec, const sasnav_airsas *background,
                         const sasnav_airsas_opts *opts, sasnav_run **run)
{
    if (!run) return sasnav_set_error(SASNAV_ERR_ARG, "airsas: run output pointer is NULL");
    *run = NULL;
    sasnav_run *r = NULL;
    sasnav_airsas_sink sink = {run_begin, run_ping, &r};
    int rc = sasnav_airsas_stream(rec, background, opts, &sink);
    if (!rc) {
        rc = sasnav_run_check(r);
        if (rc) rc = sasnav_prefix_error(rc, "airsas");
    }
    if (rc) {
        sasnav_run_free(r);
        return rc;
    }
    *run = r;
    return SASNAV_OK;
}
