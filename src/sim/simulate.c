/* Raw-data simulator: the ping operator applied to an off-grid scatterer
 * scene with the true sensor poses, plus seeded complex white noise. */
#include "sasnav/error.h"
#include "sasnav/sim.h"

#include <math.h>
#include <stdlib.h>

static int simulate_raw(const sasnav_scenario *sc, const sasnav_scene *scene,
                        const sasnav_ping_pose *truth, sasnav_run *run,
                        const sasnav_op_opts *opts, sasnav_ping_progress_fn progress, void *user);

int sasnav_simulate_raw(const sasnav_scenario *sc, const sasnav_scene *scene,
                        const sasnav_ping_pose *truth, sasnav_run *run,
                        const sasnav_op_opts *opts)
{
    return simulate_raw(sc, scene, truth, run, opts, NULL, NULL);
}

static int simulate_raw(const sasnav_scenario *sc, const sasnav_scene *scene,
                        const sasnav_ping_pose *truth, sasnav_run *run,
                        const sasnav_op_opts *opts, sasnav_ping_progress_fn progress, void *user)
{
    if (!sc || !scene || !truth || !run || !run->raw)
        return sasnav_set_error(SASNAV_ERR_ARG, "NULL simulation argument");
    if (scene->n < 1) return sasnav_set_error(SASNAV_ERR_ARG, "empty scene");
    sasnav_op *op = NULL;
    int rc = sasnav_op_create(&run->sys, &run->array, &run->win, scene->n, scene->x, scene->y,
                              opts, &op);
    if (rc) return rc;
    for (int p = 0; p < run->n_pings && !rc; p++) {
        rc = sasnav_op_set_geometry(op, &truth[p]);
        if (!rc) rc = sasnav_op_forward(op, scene->amp, sasnav_run_ping(run, p));
        if (!rc && progress) progress(p + 1, run->n_pings, user);
    }
    sasnav_op_destroy(op);
    if (rc) return rc;
    if (isinf(sc->snr_db) && sc->snr_db > 0) return SASNAV_OK;

    size_t total = (size_t)run->n_pings * run->array.n_rx * run->win.n_samples;
    double power = 0;
    for (size_t i = 0; i < total; i++) {
        float re = crealf(run->raw[i]), im = cimagf(run->raw[i]);
        power += (double)re * re + (double)im * im;
    }
    power /= (double)total;
    if (!(power > 0))
        return sasnav_set_error(SASNAV_ERR_GEOMETRY,
                                "simulated echoes are all zero: the scene is outside the window or beam");
    double sigma = sqrt(power / pow(10.0, sc->snr_db / 10.0) / 2.0);
    sasnav_rng rng;
    sasnav_rng_seed(&rng, sc->noise_seed);
    for (size_t i = 0; i < total; i++) {
        double nr = sasnav_rng_normal(&rng), ni = sasnav_rng_normal(&rng);
        run->raw[i] += (float)(sigma * nr) + I * (float)(sigma * ni);
    }
    return SASNAV_OK;
}

static int scenario_scene(const sasnav_scenario *sc, sasnav_scene **scene)
{
    if (sc->scene_kind == SASNAV_SCENE_RIPPLES) return sasnav_scene_ripples(&sc->ripples, scene);
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

int sasnav_simulate_progress(const sasnav_scenario *sc, const sasnav_scene *scene,
                             const sasnav_op_opts *opts, sasnav_run **out,
                             sasnav_ping_progress_fn progress, void *user)
{
    if (!sc || !out) return sasnav_set_error(SASNAV_ERR_ARG, "NULL simulation argument");
    *out = NULL;
    int rc = sasnav_scenario_check(sc);
    if (rc) return rc;
    sasnav_window win;
    rc = sasnav_window_for_ranges(&sc->sys, sc->range_min, sc->range_max, 8, &win);
    if (rc) return rc;
    sasnav_run *run = NULL;
    rc = sasnav_run_alloc(&sc->sys, &sc->array, &win, sc->traj.n_pings, 1, &run);
    if (rc) return rc;
    run->ping_spacing = sc->traj.ping_spacing;
    run->speed = sc->traj.speed;
    run->tx_lag = sc->traj.tx_lag;
    run->range_of_interest = sc->range_of_interest;
    rc = sasnav_trajectory_nominal(&sc->traj, run->nav);
    if (!rc) rc = sasnav_trajectory_true(&sc->traj, run->truth);
    sasnav_scene *own = NULL;
    if (!rc && !scene) {
        rc = scenario_scene(sc, &own);
        scene = own;
    }
    if (!rc) rc = simulate_raw(sc, scene, run->truth, run, opts, progress, user);
    if (!rc && sc->aiding.enabled) rc = sasnav_simulate_aiding(&sc->aiding, sc->traj.speed, run);
    sasnav_scene_free(own);
    if (rc) {
        sasnav_run_free(run);
        return rc;
    }
    *out = run;
    return SASNAV_OK;
}
