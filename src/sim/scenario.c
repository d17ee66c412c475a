/* Built-in scenarios (SPEC 4) and scenario validation. */
#include "sasnav/error.h"
#include "sasnav/sim.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* m: |x|, |y| of a simulated scene's corners (a survey line of 100 km) */
#define SCENE_EXTENT_MAX 1e5

static void base_paper(sasnav_scenario *sc)
{
    memset(sc, 0, sizeof *sc);
    sasnav_system_default(&sc->sys);
    /* 16 Rx and 1 Tx, all 5 cm long, Rx spacing 5 cm (SPEC 4 paper-pair). */
    sasnav_array_uniform(&sc->array, 16, 0.05, 0.05, 0.05);
    sc->range_min = 8.8;
    sc->range_max = 11.6;
    sc->range_of_interest = 10.0;
    sasnav_trajectory_params *t = &sc->traj;
    t->ping_spacing = 0.20;
    t->speed = 2.0;
    t->smooth_length = 1.0;
    t->tx_lag = 0.10; /* the paper's virtual 10 cm Tx-array offset */
    t->seed = 7;
    sc->scene_kind = SASNAV_SCENE_RIPPLES;
    sasnav_ripple_default(&sc->ripples);
    sc->snr_db = 30.0;
    sc->noise_seed = 11;
    sasnav_aiding_default(&sc->aiding);
}

int sasnav_scenario_preset(const char *name, sasnav_scenario *sc)
{
    if (!name || !sc) return sasnav_set_error(SASNAV_ERR_ARG, "NULL preset argument");
    if (strcmp(name, "paper-pair") == 0) {
        /* Pings 8 and 9 of the paper facing the disc; motion error of ping 9
         * relative to ping 8: surge -3.45 cm, sway 2.17 cm, yaw 4.10e-2 rad. */
        base_paper(sc);
        sc->traj.n_pings = 2;
        sc->traj.x_start = -0.10;
        sc->traj.has_pair_error = 1;
        sc->traj.pair_q = 1;
        sc->traj.pair_error = (sasnav_pose){-0.0345, 0.0217, 4.10e-2};
        sc->traj.true_bistatic = 0;
        sc->ripples.x_min = -1.6;
        sc->ripples.x_max = 1.6;
        sasnav_grid_make(-0.5, 0.5, 81, 9.2, 10.8, 129, &sc->image_grid);
    } else if (strcmp(name, "paper-trajectory") == 0) {
        /* 16 pings along a 3 m path at 2 m/s with smooth random errors; raw
         * data from the true, different Tx and array poses. */
        base_paper(sc);
        sc->traj.n_pings = 16;
        sc->traj.x_start = -1.5;
        sc->traj.surge_rms = 0.01;
        sc->traj.sway_rms = 0.01;
        sc->traj.yaw_rms = 0.01;
        sc->traj.true_bistatic = 1;
        sc->ripples.x_min = -2.6;
        sc->ripples.x_max = 2.6;
        sasnav_grid_make(-2.0, 2.0, 321, 9.2, 10.8, 129, &sc->image_grid);
    } else if (strcmp(name, "point") == 0) {
        /* One point target in paper-pair geometry seen by a 17-ping straight
         * aperture: resolution and focusing checks. */
        base_paper(sc);
        sc->traj.n_pings = 17;
        sc->traj.x_start = -1.6;
        sc->scene_kind = SASNAV_SCENE_POINTS;
        sc->n_targets = 1;
        sc->target_x[0] = 0.013;
        sc->target_y[0] = 10.007;
        sc->target_amp[0] = 1.0;
        sc->snr_db = INFINITY;
        sc->range_min = 9.3;
        sc->range_max = 10.8;
        sasnav_grid_make(-0.15, 0.15, 121, 9.85, 10.15, 121, &sc->image_grid);
    } else if (strcmp(name, "circular") == 0) {
        /* A simulated AirSAS (Penn State ARL's in-air circular SAS,
         * ../shared/data/airsas: docs/navigation.md, "Virtual arrays"): one
         * omnidirectional speaker and one microphone sharing x, y, 0.258 m
         * and 0.220 m above the scene plane, an LFM of 10-30 kHz in air
         * (c = 343 m/s), pings every degree of a 0.85 m circle about the
         * scene centre (360 pings, 14.8 mm apart). The smooth motion errors
         * (a few millimetres over metres of arc) stand for a navigation
         * drift: the run's nominal circle is the "input navigation" whose
         * error virtual-array navigation must remove. */
        memset(sc, 0, sizeof *sc);
        sasnav_system_default(&sc->sys);
        sc->sys.sound_speed = 343.0;
        sc->sys.f0 = 20e3;
        sc->sys.bandwidth = 20e3;
        sc->sys.sample_rate = 25e3;
        sc->sys.attenuation = SASNAV_ATTEN_NONE;
        sc->sys.beam_pattern = 0;
        memset(&sc->array, 0, sizeof sc->array);
        sc->array.n_rx = 1; /* at the array's origin, with the Tx */
        sc->array.tx_height = 0.2575;
        sc->array.rx_height = 0.2195;
        sc->range_min = 0.45;
        sc->range_max = 1.30;
        sc->range_of_interest = 0.85;
        sasnav_trajectory_params *t = &sc->traj;
        t->circle_radius = 0.85;
        t->ping_spacing = 0.85 * M_PI / 180.0;
        t->n_pings = 360;
        t->speed = 0.1;
        t->x_start = 0.0;
        t->surge_rms = 0.003;
        t->sway_rms = 0.003;
        t->yaw_rms = 0.0; /* an omnidirectional SISO ping has no yaw of its own */
        t->smooth_length = 1.5;
        t->tx_lag = 0.0;
        t->true_bistatic = 0;
        t->seed = 7;
        sc->scene_kind = SASNAV_SCENE_RIPPLES;
        sasnav_ripple_default(&sc->ripples);
        sc->ripples.x_min = -0.12;
        sc->ripples.x_max = 0.12;
        sc->ripples.y_min = -0.12;
        sc->ripples.y_max = 0.12;
        sc->ripples.ripple_period = 0.08;
        sc->ripples.disc_x = 0.08;
        sc->ripples.disc_y = -0.05;
        sc->ripples.disc_radius = 0.05;
        sc->snr_db = 30.0;
        sc->noise_seed = 11;
        sasnav_aiding_default(&sc->aiding);
        sasnav_grid_make(-0.3, 0.3, 151, -0.3, 0.3, 151, &sc->image_grid);
    } else if (strcmp(name, "survey") == 0) {
        /* A 300 kHz survey SAS in the class of NATO CMRE's MUSCLE (300 kHz,
         * 60 kHz band: docs/config.md "survey" for the sources and what is
         * assumed), 32 receivers of 5 cm (1.6 m) and a 5 cm transmitter 10 m
         * above the seabed, imaging 25-120 m; the ping interval is the
         * two-way time to the far range (0.16 s), 0.32 m at 2 m/s. 300
         * pings (96 m) over a varied seabed (sasnav_scene_survey) with
         * smooth motion errors of a few centimetres over tens of metres. */
        memset(sc, 0, sizeof *sc);
        sasnav_system_default(&sc->sys);
        sc->sys.f0 = 300e3;
        sc->sys.bandwidth = 60e3;
        sc->sys.sample_rate = 75e3;
        sasnav_array_uniform(&sc->array, 32, 0.05, 0.05, 0.05);
        sc->array.rx_height = 10.0;
        sc->array.tx_height = 10.0;
        sc->range_min = 25.0;
        sc->range_max = 120.0;
        sc->range_of_interest = 70.0;
        sasnav_trajectory_params *t = &sc->traj;
        t->speed = 2.0;
        t->ping_spacing = t->speed * 2.0 * sc->range_max / sc->sys.sound_speed;
        t->n_pings = 300;
        t->x_start = 0.0;
        t->surge_rms = 0.03;
        t->sway_rms = 0.03;
        t->yaw_rms = 0.003;
        t->smooth_length = 10.0;
        t->tx_lag = sasnav_motion_tx_lag(t->speed, sc->range_of_interest, sc->sys.sound_speed);
        t->true_bistatic = 1;
        t->seed = 7;
        sc->scene_kind = SASNAV_SCENE_SURVEY;
        sasnav_ripple_default(&sc->ripples);
        double x_end = t->x_start + (t->n_pings - 1) * t->ping_spacing;
        sc->ripples.x_min = t->x_start - 10.0;
        sc->ripples.x_max = x_end + 10.0;
        sc->ripples.y_min = 26.0;
        sc->ripples.y_max = 118.0;
        sc->ripples.density = 20.0;
        sc->ripples.ripple_period = 0.5;
        sc->ripples.disc_radius = 0.0;
        sc->snr_db = 30.0;
        sc->noise_seed = 11;
        sasnav_aiding_default(&sc->aiding);
        /* A 10 m x 10 m patch at mid-swath, 1 cm pixels (the image's
         * Nyquist spacing: 1.25 cm in range, 2.5 cm along track). */
        sasnav_grid_make(43.0, 53.0, 1001, 65.0, 75.0, 1001, &sc->image_grid);
    } else {
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "unknown preset '%s' (known: paper-pair, paper-trajectory, point, "
                                "circular, survey)",
                                name);
    }
    snprintf(sc->name, sizeof sc->name, "%s", name);
    return SASNAV_OK;
}

int sasnav_scenario_check(const sasnav_scenario *sc)
{
    if (!sc) return sasnav_set_error(SASNAV_ERR_ARG, "scenario is NULL");
    int rc = sasnav_system_check(&sc->sys);
    if (rc) return rc;
    rc = sasnav_array_check(&sc->array);
    if (rc) return rc;
    if (sc->n_channel_tx != 0 && sc->n_channel_tx != sc->array.n_rx)
        return sasnav_set_error(SASNAV_ERR_ARG, "%d channel transmitter positions for %d channels",
                                sc->n_channel_tx, sc->array.n_rx);
    for (int l = 0; l < sc->n_channel_tx; l++)
        if (!isfinite(sc->channel_tx_u[l]) || fabs(sc->channel_tx_u[l]) > SASNAV_SIZE_MAX_M)
            return sasnav_set_error(SASNAV_ERR_ARG,
                                    "channel %d's transmitter position %g m is not finite or beyond +-%g m", l,
                                    sc->channel_tx_u[l], SASNAV_SIZE_MAX_M);
    if (!isfinite(sc->range_min) || !isfinite(sc->range_max) || !(sc->range_min > 0) ||
        !(sc->range_max > sc->range_min))
        return sasnav_set_error(SASNAV_ERR_GEOMETRY,
                                "swath must satisfy 0 < range_min < range_max (got %g..%g m)",
                                sc->range_min, sc->range_max);
    if (!(sc->range_of_interest > 0) || !isfinite(sc->range_of_interest))
        return sasnav_set_error(SASNAV_ERR_GEOMETRY, "range of interest must be > 0");
    const sasnav_trajectory_params *t = &sc->traj;
    if (t->n_pings < 1 || t->n_pings > 100000)
        return sasnav_set_error(SASNAV_ERR_ARG, "number of pings must be 1..100000 (got %d)",
                                t->n_pings);
    if (!(t->ping_spacing > 0) || !isfinite(t->ping_spacing) || !(t->speed > 0) ||
        !isfinite(t->speed))
        return sasnav_set_error(SASNAV_ERR_ARG, "ping spacing and speed must be > 0");
    if (!isfinite(t->x_start) || !(t->tx_lag >= 0) || !isfinite(t->tx_lag) ||
        !(t->surge_rms >= 0) || !(t->sway_rms >= 0) || !(t->yaw_rms >= 0) ||
        !isfinite(t->surge_rms + t->sway_rms + t->yaw_rms) || !(t->smooth_length > 0) ||
        !(t->circle_radius >= 0) || !isfinite(t->circle_radius))
        return sasnav_set_error(SASNAV_ERR_ARG, "trajectory error parameters must be finite, >= 0");
    if (t->has_pair_error &&
        (t->pair_q < 1 || t->pair_q >= t->n_pings || !isfinite(t->pair_error.x) ||
         !isfinite(t->pair_error.y) || !isfinite(t->pair_error.theta)))
        return sasnav_set_error(SASNAV_ERR_ARG, "pair error must be finite and name ping 1..%d",
                                t->n_pings - 1);
    if (isnan(sc->snr_db)) return sasnav_set_error(SASNAV_ERR_ARG, "SNR is NaN");
    const sasnav_aiding_params *ap = &sc->aiding;
    if (ap->enabled &&
        (!(ap->gyro_arw >= 0) || !(ap->gyro_bias >= 0) || !(ap->dvl_noise >= 0) ||
         !(ap->dvl_bias >= 0) || !(ap->dvl_scale >= 0) ||
         !isfinite(ap->gyro_arw + ap->gyro_bias + ap->dvl_noise + ap->dvl_bias + ap->dvl_scale)))
        return sasnav_set_error(SASNAV_ERR_ARG, "aiding error parameters must be finite and >= 0");
    if (sc->scene_kind == SASNAV_SCENE_POINTS) {
        if (sc->n_targets < 1 || sc->n_targets > SASNAV_MAX_TARGETS)
            return sasnav_set_error(SASNAV_ERR_ARG, "point scene needs 1..%d targets",
                                    SASNAV_MAX_TARGETS);
        for (int i = 0; i < sc->n_targets; i++)
            if (!isfinite(sc->target_x[i]) || !isfinite(sc->target_y[i]) ||
                !isfinite(sc->target_amp[i]))
                return sasnav_set_error(SASNAV_ERR_ARG, "target %d is not finite", i);
    } else if (sc->scene_kind == SASNAV_SCENE_RIPPLES || sc->scene_kind == SASNAV_SCENE_SURVEY) {
        const sasnav_ripple_params *r = &sc->ripples;
        if (!(r->x_max > r->x_min) || !(r->y_max > r->y_min) || !(r->density > 0) ||
            !isfinite(r->x_min + r->x_max + r->y_min + r->y_max + r->density))
            return sasnav_set_error(SASNAV_ERR_ARG, "ripple scene extent/density invalid");
        double big = fmax(fmax(fabs(r->x_min), fabs(r->x_max)), fmax(fabs(r->y_min), fabs(r->y_max)));
        if (!(big <= SCENE_EXTENT_MAX))
            return sasnav_set_error(SASNAV_ERR_ARG, "scene corners must lie within +-%g m (got %g m)",
                                    SCENE_EXTENT_MAX, big);
        if (sc->traj.circle_radius > 0) {
            double ax = fmax(fabs(r->x_min), fabs(r->x_max)), ay = fmax(fabs(r->y_min), fabs(r->y_max));
            if (!(hypot(ax, ay) < sc->traj.circle_radius))
                return sasnav_set_error(SASNAV_ERR_GEOMETRY,
                                        "scene must lie inside the %g m circle of the track",
                                        sc->traj.circle_radius);
        } else if (!(r->y_min > 0)) {
            return sasnav_set_error(SASNAV_ERR_GEOMETRY, "scene must lie in front of the track (y > 0)");
        }
    } else if (sc->scene_kind == SASNAV_SCENE_FILE) {
        if (!sc->scene_file[0]) return sasnav_set_error(SASNAV_ERR_ARG, "scene file not named");
    } else {
        return sasnav_set_error(SASNAV_ERR_ARG, "unknown scene kind %d", (int)sc->scene_kind);
    }
    return sasnav_grid_check(&sc->image_grid);
}

void sasnav_scenario_seed(sasnav_scenario *sc, uint64_t seed)
{
    if (!sc) return;
    sc->ripples.seed = seed * 3 + 1;
    sc->traj.seed = seed * 3 + 2;
    sc->noise_seed = seed * 3 + 3;
    sc->aiding.seed = seed * 3 + 4;
}
