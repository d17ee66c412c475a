/* In-memory runs: allocation, access to a ping's channels, validation. */
#include "sasnav/run.h"
#include "sasnav/error.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* Number of samples of a run, with overflow check (0 on overflow). */
static size_t run_sample_count(int n_pings, int n_rx, int n_samples)
{
    size_t n = (size_t)n_pings;
    if ((size_t)n_rx > SIZE_MAX / n) return 0;
    n *= (size_t)n_rx;
    if ((size_t)n_samples > SIZE_MAX / sizeof(sasnav_cfloat) / n) return 0;
    return n * (size_t)n_samples;
}

static int window_check(const sasnav_window *win)
{
    if (!win) return sasnav_set_error(SASNAV_ERR_ARG, "window is NULL");
    if (win->n_samples < 1)
        return sasnav_set_error(SASNAV_ERR_ARG, "window needs >= 1 sample, got %d",
                                win->n_samples);
    if (!isfinite(win->t0))
        return sasnav_set_error(SASNAV_ERR_ARG, "window start t0 is not finite");
    return SASNAV_OK;
}

int sasnav_run_alloc(const sasnav_system *sys, const sasnav_array *array,
                     const sasnav_window *win, int n_pings, int with_truth, sasnav_run **run)
{
    if (!run) return sasnav_set_error(SASNAV_ERR_ARG, "run output pointer is NULL");
    *run = NULL;
    if (!sys) return sasnav_set_error(SASNAV_ERR_ARG, "system is NULL");
    int rc = sasnav_system_check(sys);
    if (rc) return rc;
    rc = sasnav_array_check(array);
    if (rc) return rc;
    rc = window_check(win);
    if (rc) return rc;
    if (n_pings < 1) return sasnav_set_error(SASNAV_ERR_ARG, "run needs >= 1 ping, got %d", n_pings);
    size_t n = run_sample_count(n_pings, array->n_rx, win->n_samples);
    if (n == 0)
        return sasnav_set_error(SASNAV_ERR_ARG, "run of %d pings x %d channels x %d samples is too large",
                                n_pings, array->n_rx, win->n_samples);

    sasnav_run *r = calloc(1, sizeof *r);
    if (!r) return sasnav_set_error(SASNAV_ERR_NOMEM, "cannot allocate a run");
    r->sys = *sys;
    r->array = *array;
    r->win = *win;
    r->n_pings = n_pings;
    r->raw = calloc(n, sizeof *r->raw);
    r->nav = calloc((size_t)n_pings, sizeof *r->nav);
    if (with_truth) r->truth = calloc((size_t)n_pings, sizeof *r->truth);
    if (!r->raw || !r->nav || (with_truth && !r->truth)) {
        sasnav_run_free(r);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "cannot allocate a run of %zu samples", n);
    }
    *run = r;
    return SASNAV_OK;
}

int sasnav_run_alloc_streamed(const sasnav_system *sys, const sasnav_array *array,
                              const sasnav_window *win, int n_pings, int with_truth,
                              const sasnav_ping_source *source, sasnav_run **run)
{
    int rc = SASNAV_OK;
    if (!run) rc = sasnav_set_error(SASNAV_ERR_ARG, "run output pointer is NULL");
    else *run = NULL;
    if (!rc && (!source || !source->read))
        rc = sasnav_set_error(SASNAV_ERR_ARG, "a streamed run needs a ping source");
    if (!rc && !sys) rc = sasnav_set_error(SASNAV_ERR_ARG, "system is NULL");
    if (!rc) rc = sasnav_system_check(sys);
    if (!rc) rc = sasnav_array_check(array);
    if (!rc) rc = window_check(win);
    if (!rc && n_pings < 1) rc = sasnav_set_error(SASNAV_ERR_ARG, "run needs >= 1 ping, got %d", n_pings);
    if (!rc && run_sample_count(1, array->n_rx, win->n_samples) == 0)
        rc = sasnav_set_error(SASNAV_ERR_ARG, "pings of %d channels x %d samples are too large",
                              array->n_rx, win->n_samples);
    sasnav_run *r = rc ? NULL : calloc(1, sizeof *r);
    if (!rc && !r) rc = sasnav_set_error(SASNAV_ERR_NOMEM, "cannot allocate a run");
    if (rc) {
        if (source && source->close) source->close(source->ctx);
        return rc;
    }
    r->sys = *sys;
    r->array = *array;
    r->win = *win;
    r->n_pings = n_pings;
    r->source = *source;
    r->nav = calloc((size_t)n_pings, sizeof *r->nav);
    if (with_truth) r->truth = calloc((size_t)n_pings, sizeof *r->truth);
    if (!r->nav || (with_truth && !r->truth)) {
        sasnav_run_free(r);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "cannot allocate the navigation of %d pings", n_pings);
    }
    *run = r;
    return SASNAV_OK;
}

sasnav_cfloat *sasnav_run_ping(const sasnav_run *run, int p)
{
    if (!run || !run->raw || p < 0 || p >= run->n_pings) return NULL;
    return run->raw + (size_t)p * (size_t)run->array.n_rx * (size_t)run->win.n_samples;
}

size_t sasnav_run_ping_size(const sasnav_run *run)
{
    return run ? (size_t)run->array.n_rx * (size_t)run->win.n_samples : 0;
}

int sasnav_run_get_ping(const sasnav_run *run, int p, sasnav_cfloat *buf,
                        const sasnav_cfloat **ping)
{
    if (!run || !ping) return sasnav_set_error(SASNAV_ERR_ARG, "NULL run or ping pointer");
    *ping = NULL;
    if (p < 0 || p >= run->n_pings)
        return sasnav_set_error(SASNAV_ERR_ARG, "ping %d outside 0..%d", p, run->n_pings - 1);
    if (run->raw) {
        *ping = sasnav_run_ping(run, p);
        return SASNAV_OK;
    }
    if (!run->source.read || !buf)
        return sasnav_set_error(SASNAV_ERR_ARG, "run has no samples (no raw data, no source or no buffer)");
    int rc;
#pragma omp critical(sasnav_ping_source)
    rc = run->source.read(run->source.ctx, p, buf);
    if (rc) return rc;
    *ping = buf;
    return SASNAV_OK;
}

void sasnav_aiding_free(sasnav_aiding *a)
{
    if (!a) return;
    free(a->time);
    free(a->yaw_rate);
    free(a->yaw_rate_sigma);
    free(a->velocity);
    free(a->velocity_sigma);
    free(a);
}

int sasnav_run_alloc_aiding(sasnav_run *run, int with_yaw_rate, int with_velocity)
{
    if (!run || run->n_pings < 1) return sasnav_set_error(SASNAV_ERR_ARG, "aiding needs a run");
    size_t n = (size_t)run->n_pings;
    sasnav_aiding *a = calloc(1, sizeof *a);
    if (!a) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    a->time = calloc(n, sizeof(double));
    int bad = !a->time;
    if (with_yaw_rate) {
        a->yaw_rate = calloc(n, sizeof(double));
        a->yaw_rate_sigma = malloc(n * sizeof(double));
        bad |= !a->yaw_rate || !a->yaw_rate_sigma;
        for (size_t p = 0; !bad && p < n; p++) a->yaw_rate_sigma[p] = INFINITY;
    }
    if (with_velocity) {
        a->velocity = calloc(2 * n, sizeof(double));
        a->velocity_sigma = malloc(2 * n * sizeof(double));
        bad |= !a->velocity || !a->velocity_sigma;
        for (size_t p = 0; !bad && p < 2 * n; p++) a->velocity_sigma[p] = INFINITY;
    }
    if (bad) {
        sasnav_aiding_free(a);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    }
    sasnav_aiding_free(run->aiding);
    run->aiding = a;
    return SASNAV_OK;
}

/* Values finite, standard deviations > 0 or +inf. */
/* Plausible aiding (docs/format.md, "/aiding"): finite values, within
 * `max` in magnitude (a vehicle's speed, a turn rate) where measured;
 * standard deviations of at least SIGMA_MIN (or +inf: no measurement, its
 * value a placeholder). Finite but absurd values, or tiny sigmas, would
 * overflow the fusion's costs and weights; a large sigma only weighs
 * nothing. */
#define AIDING_SIGMA_MIN 1e-12
#define AIDING_YAW_RATE_MAX 10.0 /* rad/s */
#define AIDING_TIME_MAX 1e10     /* s: |time| (three centuries) */

static int aiding_values_check(const double *v, const double *sigma, size_t n, double max, const char *what)
{
    for (size_t k = 0; k < n; k++) {
        if (!isfinite(v[k]))
            return sasnav_set_error(SASNAV_ERR_ARG, "aiding %s entry %zu is not finite", what, k);
        if (!(sigma[k] >= AIDING_SIGMA_MIN))
            return sasnav_set_error(SASNAV_ERR_ARG,
                                    "aiding %s standard deviation %zu must be >= %g or inf (got %g)", what,
                                    k, AIDING_SIGMA_MIN, sigma[k]);
        if (isfinite(sigma[k]) && !(fabs(v[k]) <= max))
            return sasnav_set_error(SASNAV_ERR_ARG, "aiding %s entry %zu is %g, beyond +-%g", what, k, v[k], max);
    }
    return SASNAV_OK;
}

int sasnav_aiding_check(const sasnav_aiding *a, int n_pings)
{
    if (!a) return SASNAV_OK;
    if (n_pings < 1 || !a->time) return sasnav_set_error(SASNAV_ERR_ARG, "aiding has no ping times");
    for (int p = 0; p < n_pings; p++) {
        if (!(fabs(a->time[p]) <= AIDING_TIME_MAX))
            return sasnav_set_error(SASNAV_ERR_ARG, "aiding time of ping %d (%g s) is not finite or beyond +-%g s",
                                    p, a->time[p], AIDING_TIME_MAX);
        if (p > 0 && !(a->time[p] > a->time[p - 1]))
            return sasnav_set_error(SASNAV_ERR_ARG,
                                    "aiding times must increase (ping %d at %g s, ping %d at %g s)",
                                    p - 1, a->time[p - 1], p, a->time[p]);
    }
    if (!a->yaw_rate != !a->yaw_rate_sigma || !a->velocity != !a->velocity_sigma)
        return sasnav_set_error(SASNAV_ERR_ARG, "aiding values without standard deviations");
    int rc = SASNAV_OK;
    if (a->yaw_rate)
        rc = aiding_values_check(a->yaw_rate, a->yaw_rate_sigma, (size_t)n_pings, AIDING_YAW_RATE_MAX, "yaw rate");
    if (!rc && a->velocity)
        rc = aiding_values_check(a->velocity, a->velocity_sigma, 2 * (size_t)n_pings, SASNAV_SPEED_MAX,
                                 "velocity");
    return rc;
}

static int pose_finite(sasnav_pose a) { return isfinite(a.x) && isfinite(a.y) && isfinite(a.theta); }

static int pose_placed(sasnav_pose a)
{
    return fabs(a.x) <= SASNAV_POSITION_MAX_M && fabs(a.y) <= SASNAV_POSITION_MAX_M;
}

int sasnav_poses_check(const sasnav_ping_pose *poses, int n, const char *what)
{
    if (!what) what = "pose";
    if (n < 0 || (n > 0 && !poses)) return sasnav_set_error(SASNAV_ERR_ARG, "%s: NULL or negative count", what);
    for (int p = 0; p < n; p++) {
        if (!pose_finite(poses[p].tx) || !pose_finite(poses[p].array))
            return sasnav_set_error(SASNAV_ERR_ARG, "%s of ping %d is not finite", what, p);
        if (!pose_placed(poses[p].tx) || !pose_placed(poses[p].array))
            return sasnav_set_error(SASNAV_ERR_ARG,
                                    "%s of ping %d: position (%g, %g) m is beyond +-%g m", what,
                                    p, poses[p].array.x, poses[p].array.y, SASNAV_POSITION_MAX_M);
        double sep = hypot(poses[p].tx.x - poses[p].array.x, poses[p].tx.y - poses[p].array.y);
        if (sep > SASNAV_SIZE_MAX_M)
            return sasnav_set_error(SASNAV_ERR_ARG,
                                    "%s of ping %d: transmitter %g m from the array (plausible: "
                                    "at most %g m)",
                                    what, p, sep, SASNAV_SIZE_MAX_M);
    }
    return SASNAV_OK;
}

static int offset_check(const sasnav_ping_pose *offset, int n)
{
    for (int l = 0; l < n; l++) {
        if (!pose_finite(offset[l].tx) || !pose_finite(offset[l].array))
            return sasnav_set_error(SASNAV_ERR_ARG, "offset of channel %d is not finite", l);
        double r = sasnav_channel_offset_radius(&offset[l], 1);
        if (r > SASNAV_SIZE_MAX_M)
            return sasnav_set_error(SASNAV_ERR_ARG,
                                    "offset of channel %d: %g m from its ping (plausible: at most %g m)",
                                    l, r, SASNAV_SIZE_MAX_M);
    }
    return SASNAV_OK;
}

int sasnav_run_set_channel_offset(sasnav_run *run, const sasnav_ping_pose *offset)
{
    if (!run) return sasnav_set_error(SASNAV_ERR_ARG, "channel offsets need a run");
    sasnav_ping_pose *copy = NULL;
    int n = run->array.n_rx;
    if (offset) {
        if (n < 1 || n > SASNAV_MAX_RX)
            return sasnav_set_error(SASNAV_ERR_ARG, "channel offsets for %d channels", n);
        int rc = offset_check(offset, n);
        if (rc) return rc;
        copy = malloc(sizeof *copy * (size_t)n);
        if (!copy) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
        memcpy(copy, offset, sizeof *copy * (size_t)n);
    }
    free(run->channel_offset);
    run->channel_offset = copy;
    return SASNAV_OK;
}

void sasnav_run_channel_poses(const sasnav_run *run, const sasnav_ping_pose *ping, sasnav_ping_pose *out)
{
    if (run->channel_offset) {
        sasnav_channel_poses(ping, run->channel_offset, run->array.n_rx, out);
        return;
    }
    for (int l = 0; l < run->array.n_rx; l++) out[l] = *ping;
}

static int run_check(const sasnav_run *run, int samples);

int sasnav_run_check(const sasnav_run *run) { return run_check(run, 1); }

int sasnav_run_check_header(const sasnav_run *run) { return run_check(run, 0); }

static int run_check(const sasnav_run *run, int samples)
{
    if (!run) return sasnav_set_error(SASNAV_ERR_ARG, "run is NULL");
    int rc = sasnav_system_check(&run->sys);
    if (rc) return rc;
    rc = sasnav_array_check(&run->array);
    if (rc) return rc;
    rc = window_check(&run->win);
    if (rc) return rc;
    if (run->n_pings < 1)
        return sasnav_set_error(SASNAV_ERR_ARG, "run needs >= 1 ping, got %d", run->n_pings);
    size_t n = run_sample_count(run->n_pings, run->array.n_rx, run->win.n_samples);
    if (n == 0) return sasnav_set_error(SASNAV_ERR_ARG, "run dimensions overflow");
    if ((samples && !run->raw && !run->source.read) || !run->nav)
        return sasnav_set_error(SASNAV_ERR_ARG, "run data or navigation is NULL");
    if (!isfinite(run->ping_spacing) || !isfinite(run->tx_lag))
        return sasnav_set_error(SASNAV_ERR_ARG, "ping spacing and Tx lag must be finite");
    if (fabs(run->ping_spacing) > SASNAV_SIZE_MAX_M || fabs(run->tx_lag) > SASNAV_SIZE_MAX_M)
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "ping_spacing %g m, tx_lag %g m: beyond the plausible +-%g m",
                                run->ping_spacing, run->tx_lag, SASNAV_SIZE_MAX_M);
    if (!isfinite(run->speed) || run->speed < 0 || run->speed > SASNAV_SPEED_MAX)
        return sasnav_set_error(SASNAV_ERR_ARG, "speed %g m/s is outside the plausible 0..%g m/s",
                                run->speed, SASNAV_SPEED_MAX);
    if (!isfinite(run->range_of_interest) || run->range_of_interest < 0 ||
        run->range_of_interest > SASNAV_RANGE_MAX_M)
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "range_of_interest %g m is outside the plausible 0..%g m",
                                run->range_of_interest, SASNAV_RANGE_MAX_M);
    double t_end = run->win.t0 + run->win.n_samples / run->sys.sample_rate;
    if (!(t_end > 0) || 0.5 * run->sys.sound_speed * t_end > SASNAV_RANGE_MAX_M)
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "sample window t0 %g s + %d samples at %g Hz ends at range %g m "
                                "(plausible: 0..%g m)",
                                run->win.t0, run->win.n_samples, run->sys.sample_rate,
                                0.5 * run->sys.sound_speed * t_end, SASNAV_RANGE_MAX_M);
    rc = sasnav_poses_check(run->nav, run->n_pings, "navigation");
    if (rc) return rc;
    if (run->truth) {
        rc = sasnav_poses_check(run->truth, run->n_pings, "true pose");
        if (rc) return rc;
    }
    rc = sasnav_aiding_check(run->aiding, run->n_pings);
    if (rc) return rc;
    if (run->channel_offset) {
        rc = offset_check(run->channel_offset, run->array.n_rx);
        if (rc) return rc;
    }
    const float *v = (const float *)run->raw; /* C11 6.2.5: complex = float[2] */
    for (size_t k = 0; samples && v && k < 2 * n; k++)
        if (!isfinite(v[k])) {
            size_t s = k / 2, per_ping = n / (size_t)run->n_pings;
            return sasnav_set_error(SASNAV_ERR_ARG,
                                    "raw sample %zu of channel %zu of ping %zu is not finite",
                                    s % (size_t)run->win.n_samples,
                                    (s % per_ping) / (size_t)run->win.n_samples, s / per_ping);
        }
    return SASNAV_OK;
}

void sasnav_run_free(sasnav_run *run)
{
    if (!run) return;
    free(run->raw);
    if (run->source.close) run->source.close(run->source.ctx);
    free(run->nav);
    free(run->truth);
    sasnav_aiding_free(run->aiding);
    free(run->channel_offset);
    free(run);
}

int sasnav_run_subset(const sasnav_run *run, const int *pings, int n_pings, const int *channels,
                      int n_channels, sasnav_run **out)
{
    if (!out) return sasnav_set_error(SASNAV_ERR_ARG, "subset output pointer is NULL");
    *out = NULL;
    if (!run || !pings || n_pings < 1)
        return sasnav_set_error(SASNAV_ERR_ARG, "subset needs a run and at least one ping");
    int nc = channels ? n_channels : run->array.n_rx;
    if (nc < 1 || nc > run->array.n_rx)
        return sasnav_set_error(SASNAV_ERR_ARG, "subset of %d channels from %d", nc, run->array.n_rx);
    for (int i = 0; i < n_pings; i++)
        if (pings[i] < 0 || pings[i] >= run->n_pings)
            return sasnav_set_error(SASNAV_ERR_ARG, "subset ping %d outside 0..%d", pings[i],
                                    run->n_pings - 1);
    for (int l = 0; channels && l < nc; l++)
        if (channels[l] < 0 || channels[l] >= run->array.n_rx)
            return sasnav_set_error(SASNAV_ERR_ARG, "subset channel %d outside 0..%d", channels[l],
                                    run->array.n_rx - 1);
    int pick[SASNAV_MAX_RX];
    for (int l = 0; l < nc; l++) pick[l] = channels ? channels[l] : l;
    sasnav_array a;
    int rc = sasnav_array_select(&run->array, pick, nc, &a);
    if (rc) return rc;
    sasnav_run *r = NULL;
    rc = sasnav_run_alloc(&run->sys, &a, &run->win, n_pings, run->truth != NULL, &r);
    if (rc) return rc;
    size_t ns = (size_t)run->win.n_samples;
    sasnav_cfloat *tmp = NULL; /* a streamed ping whose channels are picked */
    for (int i = 0; i < n_pings; i++) {
        sasnav_cfloat *dst = sasnav_run_ping(r, i);
        const sasnav_cfloat *src = NULL;
        if (run->raw) src = sasnav_run_ping(run, pings[i]);
        else if (!channels) rc = sasnav_run_get_ping(run, pings[i], dst, &src); /* read in place */
        else {
            if (!tmp) tmp = malloc(sizeof *tmp * sasnav_run_ping_size(run));
            rc = tmp ? sasnav_run_get_ping(run, pings[i], tmp, &src)
                     : sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
        }
        if (rc) {
            free(tmp);
            sasnav_run_free(r);
            return rc;
        }
        for (int l = 0; src != dst && l < nc; l++)
            memcpy(dst + (size_t)l * ns, src + (size_t)(channels ? channels[l] : l) * ns,
                   sizeof(sasnav_cfloat) * ns);
        r->nav[i] = run->nav[pings[i]];
        if (run->truth) r->truth[i] = run->truth[pings[i]];
    }
    free(tmp);
    r->ping_spacing = n_pings > 1 ? run->ping_spacing * fabs((double)(pings[n_pings - 1] - pings[0])) /
                                        (n_pings - 1)
                                  : run->ping_spacing;
    r->speed = run->speed;
    r->tx_lag = run->tx_lag;
    r->range_of_interest = run->range_of_interest;
    if (run->channel_offset) {
        sasnav_ping_pose off[SASNAV_MAX_RX];
        for (int l = 0; l < nc; l++) off[l] = run->channel_offset[channels ? channels[l] : l];
        rc = sasnav_run_set_channel_offset(r, off);
        if (rc) {
            sasnav_run_free(r);
            return rc;
        }
    }
    int consecutive = run->aiding != NULL;
    for (int i = 1; i < n_pings && consecutive; i++) consecutive = pings[i] == pings[i - 1] + 1;
    if (consecutive) {
        const sasnav_aiding *ai = run->aiding;
        rc = sasnav_run_alloc_aiding(r, ai->yaw_rate != NULL, ai->velocity != NULL);
        if (rc) {
            sasnav_run_free(r);
            return rc;
        }
        for (int i = 0; i < n_pings; i++) {
            int p = pings[i];
            r->aiding->time[i] = ai->time[p];
            if (ai->yaw_rate) {
                r->aiding->yaw_rate[i] = ai->yaw_rate[p];
                r->aiding->yaw_rate_sigma[i] = ai->yaw_rate_sigma[p];
            }
            for (int k = 0; ai->velocity && k < 2; k++) {
                r->aiding->velocity[2 * i + k] = ai->velocity[2 * p + k];
                r->aiding->velocity_sigma[2 * i + k] = ai->velocity_sigma[2 * p + k];
            }
        }
    }
    *out = r;
    return SASNAV_OK;
}
