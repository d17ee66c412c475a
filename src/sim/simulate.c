/* Raw-data simulator: the ping operator applied to an off-grid scatterer
 * scene with the true sensor poses, plus seeded complex white noise.
 *
 * One code path for runs in memory (sasnav_simulate) and runs streamed to
 * a sink (sasnav_simulate_stream, e.g. a file written ping by ping): the
 * pings are made one at a time and handed to a sink (for the in-memory run,
 * a copy into run->raw); the noise, scaled by the run's mean signal power,
 * is added in a second pass over the pings in order, with one random stream:
 * the same bits either way.
 *
 * Long scenes (a survey): a ping can only reach the scatterers within
 * c t_last / 2 of its sensors (t_last: the operator's last kept delay), so
 * when the scene is much longer than that reach, each ping simulates the
 * scatterers of its own along-track band (scene sorted by x once) instead
 * of the whole scene: the cost is linear in the run's length. A band holds
 * every scatterer the ping's operator would keep, but the operator then
 * sums them in another order than over the whole scene, so the bits differ
 * in the last place from a whole-scene simulation: the band is used only
 * when the scene spans more than SELECT_FACTOR times its width, never for
 * the built-in presets (a few metres). */
#include "sasnav/error.h"
#include "sasnav/sim.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define SELECT_FACTOR 4.0

/* Scatterers sorted by x (ties by index: deterministic). */
typedef struct {
    double *x, *y;
    sasnav_cfloat *amp;
    int n;
} sorted_scene;

static const sasnav_scene *sort_scene_of;
static int by_x(const void *a, const void *b)
{
    int i = *(const int *)a, j = *(const int *)b;
    double xi = sort_scene_of->x[i], xj = sort_scene_of->x[j];
    return xi < xj ? -1 : xi > xj ? 1 : (i > j) - (i < j);
}

static int sort_scene(const sasnav_scene *scene, sorted_scene *s)
{
    memset(s, 0, sizeof *s);
    int *idx = malloc(sizeof(int) * (size_t)scene->n);
    s->x = malloc(sizeof(double) * (size_t)scene->n);
    s->y = malloc(sizeof(double) * (size_t)scene->n);
    s->amp = malloc(sizeof(sasnav_cfloat) * (size_t)scene->n);
    if (!idx || !s->x || !s->y || !s->amp) {
        free(idx);
        free(s->x);
        free(s->y);
        free(s->amp);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory sorting %d scatterers", scene->n);
    }
    for (int i = 0; i < scene->n; i++) idx[i] = i;
    /* qsort is not re-entrant with a context; the simulator holds the
     * pointer only for this call, inside a critical section. */
#pragma omp critical(sasnav_sort_scene)
    {
        sort_scene_of = scene;
        qsort(idx, (size_t)scene->n, sizeof(int), by_x);
        sort_scene_of = NULL;
    }
    for (int k = 0; k < scene->n; k++) {
        s->x[k] = scene->x[idx[k]];
        s->y[k] = scene->y[idx[k]];
        s->amp[k] = scene->amp[idx[k]];
    }
    s->n = scene->n;
    free(idx);
    return SASNAV_OK;
}

/* First k with s->x[k] >= v. */
static int lower_bound(const sorted_scene *s, double v)
{
    int lo = 0, hi = s->n;
    while (lo < hi) {
        int mid = lo + (hi - lo) / 2;
        if (s->x[mid] < v) lo = mid + 1;
        else hi = mid;
    }
    return lo;
}

/* Radius of the disc around the array's reference point that holds every
 * sensor of the ping. */
static double sensor_radius(const sasnav_run *run, const sasnav_ping_pose *pose)
{
    const sasnav_array *a = &run->array;
    double r = hypot(pose->tx.x - pose->array.x, pose->tx.y - pose->array.y);
    for (int l = 0; l < a->n_rx; l++)
        if (fabs(a->rx_u[l]) > r) r = fabs(a->rx_u[l]);
    return r + sasnav_channel_offset_radius(run->channel_offset, a->n_rx);
}

typedef int (*put_fn)(void *ctx, int p, const sasnav_cfloat *samples);
typedef int (*get_fn)(void *ctx, int p, sasnav_cfloat *samples);

struct sasnav_simulator {
    const sasnav_run *run;    /* the header: shapes, truth */
    const sasnav_scene *scene;
    sasnav_op_opts opts;
    sasnav_op *op;            /* whole-scene operator (no band selection) */
    int select;               /* 1: each ping simulates its along-track band */
    sorted_scene sorted;
    double reach;             /* m: c t_last / 2 */
};

int sasnav_simulator_create(const sasnav_run *header, const sasnav_scene *scene, const sasnav_op_opts *opts,
                            sasnav_simulator **out)
{
    if (!out) return sasnav_set_error(SASNAV_ERR_ARG, "NULL simulator output");
    *out = NULL;
    if (!header || !scene || !header->truth) return sasnav_set_error(SASNAV_ERR_ARG, "NULL simulation argument");
    if (scene->n < 1) return sasnav_set_error(SASNAV_ERR_ARG, "empty scene");
    sasnav_simulator *sim = calloc(1, sizeof *sim);
    if (!sim) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    sim->run = header;
    sim->scene = scene;
    if (opts) sim->opts = *opts;
    else sasnav_op_default_opts(&sim->opts);
    const sasnav_run *run = header;
    int rc = sasnav_op_create(&run->sys, &run->array, &run->win, scene->n, scene->x, scene->y, &sim->opts,
                              &sim->op);
    if (rc) {
        free(sim);
        return rc;
    }
    double t_first, t_last;
    sasnav_op_delay_span(sim->op, &t_first, &t_last);
    sim->reach = 0.5 * run->sys.sound_speed * t_last;
    double xmin = INFINITY, xmax = -INFINITY;
    for (int i = 0; i < scene->n; i++) {
        if (scene->x[i] < xmin) xmin = scene->x[i];
        if (scene->x[i] > xmax) xmax = scene->x[i];
    }
    sim->select = xmax - xmin > SELECT_FACTOR * 2.0 * (sim->reach + sensor_radius(run, &run->truth[0]));
    if (sim->select) {
        sasnav_op_destroy(sim->op);
        sim->op = NULL;
        rc = sort_scene(scene, &sim->sorted);
        if (rc) {
            free(sim);
            return rc;
        }
    }
    *out = sim;
    return SASNAV_OK;
}

int sasnav_simulator_ping(sasnav_simulator *sim, int p, sasnav_cfloat *out)
{
    if (!sim || !out || p < 0 || p >= sim->run->n_pings)
        return sasnav_set_error(SASNAV_ERR_ARG, "simulator: bad ping %d", p);
    const sasnav_run *run = sim->run;
    const sasnav_ping_pose *pose = &run->truth[p];
    if (!sim->select) {
        int rc = sasnav_op_set_ping(sim->op, pose, run->channel_offset);
        return rc ? rc : sasnav_op_forward(sim->op, sim->scene->amp, out);
    }
    double band = sim->reach + sensor_radius(run, pose) + 1e-6;
    int k0 = lower_bound(&sim->sorted, pose->array.x - band);
    int k1 = lower_bound(&sim->sorted, pose->array.x + band);
    if (k1 <= k0) {
        memset(out, 0, sizeof *out * sasnav_run_ping_size(run));
        return SASNAV_OK;
    }
    sasnav_op *op = NULL;
    int rc = sasnav_op_create(&run->sys, &run->array, &run->win, k1 - k0, sim->sorted.x + k0, sim->sorted.y + k0,
                              &sim->opts, &op);
    if (!rc) rc = sasnav_op_set_ping(op, pose, run->channel_offset);
    if (!rc) rc = sasnav_op_forward(op, sim->sorted.amp + k0, out);
    sasnav_op_destroy(op);
    return rc;
}

void sasnav_simulator_destroy(sasnav_simulator *sim)
{
    if (!sim) return;
    sasnav_op_destroy(sim->op);
    free(sim->sorted.x);
    free(sim->sorted.y);
    free(sim->sorted.amp);
    free(sim);
}

double sasnav_ping_power(const sasnav_cfloat *samples, size_t n, double acc)
{
    for (size_t i = 0; i < n; i++) {
        float re = crealf(samples[i]), im = cimagf(samples[i]);
        acc += (double)re * re + (double)im * im;
    }
    return acc;
}

/* The pings of `run` (shape, truth) simulated into the sink; *power_out:
 * mean signal power over all samples. */
static int simulate_pings(const sasnav_scene *scene, const sasnav_run *run, const sasnav_op_opts *opts,
                          put_fn put, void *ctx, double *power_out, sasnav_ping_progress_fn progress, void *user)
{
    size_t per_ping = sasnav_run_ping_size(run);
    sasnav_cfloat *buf = malloc(sizeof *buf * per_ping);
    if (!buf) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory for a ping");
    sasnav_simulator *sim = NULL;
    int rc = sasnav_simulator_create(run, scene, opts, &sim);
    double power = 0;
    for (int p = 0; p < run->n_pings && !rc; p++) {
        rc = sasnav_simulator_ping(sim, p, buf);
        if (!rc) power = sasnav_ping_power(buf, per_ping, power);
        if (!rc) rc = put(ctx, p, buf);
        if (!rc && progress) progress(p + 1, run->n_pings, user);
    }
    sasnav_simulator_destroy(sim);
    free(buf);
    *power_out = power / ((double)per_ping * (double)run->n_pings);
    return rc;
}

/* Second pass: complex white noise at sc->snr_db of the mean power, one
 * random stream over the pings in order. */
static int add_noise(const sasnav_scenario *sc, const sasnav_run *run, double power, put_fn put,
                     get_fn get, void *ctx)
{
    if (isinf(sc->snr_db) && sc->snr_db > 0) return SASNAV_OK;
    if (!(power > 0))
        return sasnav_set_error(SASNAV_ERR_GEOMETRY,
                                "simulated echoes are all zero: the scene is outside the window or beam");
    double sigma = sqrt(power / pow(10.0, sc->snr_db / 10.0) / 2.0);
    size_t per_ping = (size_t)run->array.n_rx * (size_t)run->win.n_samples;
    sasnav_cfloat *buf = malloc(sizeof *buf * per_ping);
    if (!buf) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory for a ping");
    sasnav_rng rng;
    sasnav_rng_seed(&rng, sc->noise_seed);
    int rc = SASNAV_OK;
    for (int p = 0; p < run->n_pings && !rc; p++) {
        rc = get(ctx, p, buf);
        for (size_t i = 0; !rc && i < per_ping; i++) {
            double nr = sasnav_rng_normal(&rng), ni = sasnav_rng_normal(&rng);
            buf[i] += (float)(sigma * nr) + I * (float)(sigma * ni);
        }
        if (!rc) rc = put(ctx, p, buf);
    }
    free(buf);
    return rc;
}

int sasnav_simulate_noise(const sasnav_scenario *sc, const sasnav_run *header, double mean_power,
                          const sasnav_ping_sink *sink)
{
    if (!sc || !header || !sink || !sink->put || !sink->get)
        return sasnav_set_error(SASNAV_ERR_ARG, "NULL simulation argument");
    return add_noise(sc, header, mean_power, sink->put, sink->get, sink->ctx);
}

/* The in-memory sink: run->raw. */
static int mem_put(void *ctx, int p, const sasnav_cfloat *samples)
{
    sasnav_run *run = ctx;
    memcpy(sasnav_run_ping(run, p), samples, sizeof *samples * sasnav_run_ping_size(run));
    return SASNAV_OK;
}

static int mem_get(void *ctx, int p, sasnav_cfloat *samples)
{
    sasnav_run *run = ctx;
    memcpy(samples, sasnav_run_ping(run, p), sizeof *samples * sasnav_run_ping_size(run));
    return SASNAV_OK;
}

int sasnav_simulate_raw(const sasnav_scenario *sc, const sasnav_scene *scene,
                        const sasnav_ping_pose *truth, sasnav_run *run,
                        const sasnav_op_opts *opts)
{
    if (!sc || !scene || !truth || !run || !run->raw)
        return sasnav_set_error(SASNAV_ERR_ARG, "NULL simulation argument");
    if (scene->n < 1) return sasnav_set_error(SASNAV_ERR_ARG, "empty scene");
    double power = 0;
    /* The poses to simulate with, in the run's truth slot for the call. */
    sasnav_run view = *run;
    view.truth = (sasnav_ping_pose *)truth;
    int rc = simulate_pings(scene, &view, opts, mem_put, run, &power, NULL, NULL);
    if (!rc) rc = add_noise(sc, run, power, mem_put, mem_get, run);
    return rc;
}

int sasnav_scenario_scene(const sasnav_scenario *sc, sasnav_scene **scene)
{
    if (!sc || !scene) return sasnav_set_error(SASNAV_ERR_ARG, "NULL scene argument");
    if (sc->scene_kind == SASNAV_SCENE_RIPPLES) return sasnav_scene_ripples(&sc->ripples, scene);
    if (sc->scene_kind == SASNAV_SCENE_SURVEY)
        return sasnav_scene_survey(&sc->ripples, 0, NULL, NULL, NULL, scene);
    if (sc->scene_kind == SASNAV_SCENE_POINTS) {
        sasnav_cfloat amp[SASNAV_MAX_TARGETS];
        for (int i = 0; i < sc->n_targets; i++) amp[i] = (float)sc->target_amp[i];
        return sasnav_scene_points(sc->n_targets, sc->target_x, sc->target_y, amp, scene);
    }
    return sasnav_set_error(SASNAV_ERR_ARG, "scene from a file must be loaded by the caller");
}

int sasnav_simulate(const sasnav_scenario *sc, const sasnav_scene *scene,
                    const sasnav_op_opts *opts, sasnav_run **out)
{
    return sasnav_simulate_progress(sc, scene, opts, out, NULL, NULL);
}

/* The run's header (navigation, truth, constants; samples only when
 * with_raw) for scenario sc. */
static int scenario_header(const sasnav_scenario *sc, int with_raw, sasnav_run **out)
{
    if (!out) return sasnav_set_error(SASNAV_ERR_ARG, "NULL header output");
    *out = NULL;
    if (!sc) return sasnav_set_error(SASNAV_ERR_ARG, "NULL scenario");
    int rc = sasnav_scenario_check(sc);
    if (rc) return rc;
    sasnav_window win;
    rc = sasnav_window_for_ranges(&sc->sys, sc->range_min, sc->range_max, 8, &win);
    if (rc) return rc;
    sasnav_run *run = NULL;
    if (with_raw) {
        rc = sasnav_run_alloc(&sc->sys, &sc->array, &win, sc->traj.n_pings, 1, &run);
    } else {
        /* A header: a streamed run whose source is never read. */
        run = calloc(1, sizeof *run);
        if (!run) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
        run->sys = sc->sys;
        run->array = sc->array;
        run->win = win;
        run->n_pings = sc->traj.n_pings;
        run->nav = calloc((size_t)run->n_pings, sizeof *run->nav);
        run->truth = calloc((size_t)run->n_pings, sizeof *run->truth);
        if (!run->nav || !run->truth) {
            sasnav_run_free(run);
            return sasnav_set_error(SASNAV_ERR_NOMEM, "cannot allocate the navigation of %d pings",
                                    sc->traj.n_pings);
        }
    }
    if (rc) return rc;
    if (sc->n_channel_tx) {
        sasnav_ping_pose off[SASNAV_MAX_RX];
        memset(off, 0, sizeof off);
        for (int l = 0; l < sc->n_channel_tx; l++) off[l].tx.x = sc->channel_tx_u[l];
        rc = sasnav_run_set_channel_offset(run, off);
        if (rc) {
            sasnav_run_free(run);
            return rc;
        }
    }
    run->ping_spacing = sc->traj.ping_spacing;
    run->speed = sc->traj.speed;
    run->tx_lag = sc->traj.tx_lag;
    run->range_of_interest = sc->range_of_interest;
    rc = sasnav_trajectory_nominal(&sc->traj, run->nav);
    if (!rc) rc = sasnav_trajectory_true(&sc->traj, run->truth);
    if (rc) {
        sasnav_run_free(run);
        return rc;
    }
    *out = run;
    return SASNAV_OK;
}

/* Scene (the scenario's unless given), pings, noise and aiding of `run`
 * (its header made by scenario_header) into the sink. */
static int simulate_into(const sasnav_scenario *sc, const sasnav_scene *scene, const sasnav_op_opts *opts,
                         sasnav_run *run, put_fn put, get_fn get, void *ctx,
                         sasnav_ping_progress_fn progress, void *user)
{
    sasnav_scene *own = NULL;
    int rc = SASNAV_OK;
    if (!scene) {
        rc = sasnav_scenario_scene(sc, &own);
        scene = own;
    }
    double power = 0;
    if (!rc && scene->n < 1) rc = sasnav_set_error(SASNAV_ERR_ARG, "empty scene");
    if (!rc) rc = simulate_pings(scene, run, opts, put, ctx, &power, progress, user);
    if (!rc) rc = add_noise(sc, run, power, put, get, ctx);
    if (!rc && sc->aiding.enabled) rc = sasnav_simulate_aiding(&sc->aiding, sc->traj.speed, run);
    sasnav_scene_free(own);
    return rc;
}

int sasnav_scenario_header(const sasnav_scenario *sc, sasnav_run **header)
{
    return scenario_header(sc, 0, header);
}

int sasnav_simulate_progress(const sasnav_scenario *sc, const sasnav_scene *scene,
                             const sasnav_op_opts *opts, sasnav_run **out,
                             sasnav_ping_progress_fn progress, void *user)
{
    if (!sc || !out) return sasnav_set_error(SASNAV_ERR_ARG, "NULL simulation argument");
    *out = NULL;
    sasnav_run *run = NULL;
    int rc = scenario_header(sc, 1, &run);
    if (!rc) rc = simulate_into(sc, scene, opts, run, mem_put, mem_get, run, progress, user);
    if (rc) {
        sasnav_run_free(run);
        return rc;
    }
    *out = run;
    return SASNAV_OK;
}

int sasnav_simulate_stream(const sasnav_scenario *sc, const sasnav_scene *scene,
                           const sasnav_op_opts *opts, const sasnav_ping_sink *sink,
                           sasnav_run **header, sasnav_ping_progress_fn progress, void *user)
{
    if (!sc || !sink || !sink->put || !sink->get || !header)
        return sasnav_set_error(SASNAV_ERR_ARG, "NULL simulation argument");
    *header = NULL;
    sasnav_run *run = NULL;
    int rc = scenario_header(sc, 0, &run);
    if (!rc) rc = simulate_into(sc, scene, opts, run, sink->put, sink->get, sink->ctx, progress, user);
    if (rc) {
        sasnav_run_free(run);
        return rc;
    }
    *header = run;
    return SASNAV_OK;
}
