/* sasnav -- scenarios, trajectories and the raw-data simulator.
 *
 * Threads: no shared state (every random draw comes from the scenario's
 * seeds): distinct calls may run concurrently, scenarios and scenes shared
 * read-only. sasnav_simulate and sasnav_simulate_raw make an operator with
 * opts (OpenMP with opts->nthreads, 0 = omp_get_max_threads(); FFTW
 * planning: op.h); the rest is serial. */
#ifndef SASNAV_SIM_H
#define SASNAV_SIM_H

#include <stdint.h>

#include "sasnav/image.h"
#include "sasnav/run.h"
#include "sasnav/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

#define SASNAV_MAX_TARGETS 64

typedef enum {
    SASNAV_SCENE_RIPPLES = 0, /* paper scene: speckle + ripples + disc */
    SASNAV_SCENE_POINTS = 1,  /* point targets listed in the scenario */
    SASNAV_SCENE_FILE = 2,    /* image file (HDF5 image layout) */
    SASNAV_SCENE_SURVEY = 3   /* survey seabed (sasnav_scene_survey) over the
                                 ripple parameters' rectangle */
} sasnav_scene_kind;

/* Trajectory model: a nominal straight track along +x at y = 0 (or a
 * circle, circle_radius) and smooth random motion errors (surge, sway, yaw)
 * of the vehicle in its own frame, plus optionally an explicit error of
 * ping `pair_q` relative to ping `pair_q - 1`. */
typedef struct {
    int n_pings;
    double ping_spacing;     /* m, nominal (default 0.20) */
    double speed;            /* m/s (default 2) */
    double x_start;          /* m, centroid x of the first ping */
    double surge_rms;        /* m, rms of the smooth surge error of the path */
    double sway_rms;         /* m */
    double yaw_rms;          /* rad */
    double smooth_length;    /* m, correlation length of the errors (default 1.0) */
    int has_pair_error;      /* apply pair_error to ping pair (pair_q-1, pair_q) */
    int pair_q;
    sasnav_pose pair_error;  /* surge, sway, yaw of ping pair_q relative to pair_q-1 */
    double tx_lag;           /* m, Tx-array offset from motion (EPCA model) */
    double circle_radius;    /* m: 0 = the straight track along +x (default);
                                > 0: a circle of that radius about the
                                origin, run counter-clockwise so that +y
                                (the look direction) points at its centre;
                                arc length s from (0, -R) heading +x
                                (a turntable's circular SAS, AirSAS) */
    int true_bistatic;       /* 1: true Tx/array poses sampled on the path at
                                transmission / reception (different yaw);
                                0: exact EPCA geometry around each centroid */
    uint64_t seed;
} sasnav_trajectory_params;

/* Aiding sensors of a simulated run (docs/config.md, "aiding"): a gyro
 * (or INS heading) and a DVL, measuring each ping interval of the TRUE
 * PCA-centroid trajectory (sasnav_aiding in run.h) with the error model
 *   gyro: mean yaw rate + b_g + n,  b_g ~ N(0, gyro_bias) per run,
 *         n ~ N(0, gyro_arw / sqrt(dt)) per interval (angle random walk);
 *   DVL:  (1 + s) v + b_v + n,      s ~ N(0, dvl_scale) per run,
 *         b_v ~ N(0, dvl_bias) per run and component,
 *         n ~ N(0, dvl_noise) per interval and component.
 * The standard deviations written with the measurements combine the terms
 * (sqrt(arw^2 / dt + bias^2); sqrt(noise^2 + bias^2 + (scale v)^2)). The
 * defaults are a navigation-grade INS and a 600 kHz DVL (docs/config.md
 * gives the datasheets). */
typedef struct {
    int enabled;             /* 1: write aiding measurements (default 0) */
    int gyro, dvl;           /* sensors present (default 1, 1) */
    double gyro_arw;         /* rad/sqrt(s) (default 0.002 deg/sqrt(h)) */
    double gyro_bias;        /* rad/s (default 0.003 deg/h) */
    double dvl_noise;        /* m/s per ping interval (default 0.003) */
    double dvl_bias;         /* m/s (default 0.001) */
    double dvl_scale;        /* relative (default 0.002) */
    uint64_t seed;           /* error draws (default 13) */
} sasnav_aiding_params;

/* Fills the defaults above (enabled = 0). */
void sasnav_aiding_default(sasnav_aiding_params *ap);

/* Writes run->aiding from run->truth with the error model of `ap` (ping
 * epochs p * ping_spacing / speed). Errors: no truth, bad parameters. */
int sasnav_simulate_aiding(const sasnav_aiding_params *ap, double speed, sasnav_run *run);

/* A complete simulated scenario (what a config file or a preset describes). */
typedef struct {
    char name[64];
    sasnav_system sys;
    sasnav_array array;
    double range_min, range_max;   /* m, swath (sets the sample window) */
    double range_of_interest;      /* m, mid-range */
    sasnav_trajectory_params traj;
    sasnav_scene_kind scene_kind;
    sasnav_ripple_params ripples;
    int n_targets;
    double target_x[SASNAV_MAX_TARGETS], target_y[SASNAV_MAX_TARGETS];
    double target_amp[SASNAV_MAX_TARGETS];
    char scene_file[512];
    double snr_db;                 /* additive noise; +inf = noise-free */
    uint64_t noise_seed;
    sasnav_aiding_params aiding;   /* aiding sensors (off unless enabled) */
    sasnav_grid image_grid;        /* default grid for imaging */
    int n_channel_tx;              /* 0: one transmitter (the common case);
                                      else array.n_rx: channel l transmits
                                      from its own transmitter, at
                                      channel_tx_u[l] along the ping's
                                      transmitter axis (a head with several
                                      transmitters; the run gets
                                      channel_offset, file format 2) */
    double channel_tx_u[SASNAV_MAX_RX]; /* m */
} sasnav_scenario;

/* Built-in presets: "paper-pair", "paper-trajectory", "point" (one point
 * target in paper-pair geometry), "survey" (a 300 kHz survey SAS over a
 * 100 m varied seabed at 25-120 m range; docs/config.md). Returns SASNAV_ERR_ARG for unknown names. */
int sasnav_scenario_preset(const char *name, sasnav_scenario *sc);

/* Seeds every random draw of a scenario from one number S (what
 * `sasnav simulate --seed S` does): scene 3S + 1, trajectory errors 3S + 2,
 * noise 3S + 3, aiding errors 3S + 4. */
void sasnav_scenario_seed(sasnav_scenario *sc, uint64_t seed);

/* Validates a scenario (positive sizes, finite values, sensible ranges). */
int sasnav_scenario_check(const sasnav_scenario *sc);

/* Nominal ping poses (straight track, EPCA geometry, no error). */
int sasnav_trajectory_nominal(const sasnav_trajectory_params *tp, sasnav_ping_pose *poses);

/* True ping poses: nominal plus the smooth random errors (seeded) plus the
 * explicit pair error. */
int sasnav_trajectory_true(const sasnav_trajectory_params *tp, sasnav_ping_pose *poses);

/* Simulates the raw data of a scenario for the given true poses into run->raw
 * (using a scene whose scatterers are off any reconstruction grid), adding
 * complex white Gaussian noise at sc->snr_db (per-run signal power / noise
 * power, seeded by sc->noise_seed). */
int sasnav_simulate_raw(const sasnav_scenario *sc, const sasnav_scene *scene,
                        const sasnav_ping_pose *truth, sasnav_run *run,
                        const sasnav_op_opts *opts);

/* Complete simulation: scene, trajectories, raw data, and the aiding
 * measurements when sc->aiding.enabled. Sets run->nav to the
 * nominal poses and run->truth to the true ones. `scene` may be NULL: the
 * scene is then built from the scenario (ripples or point targets); a
 * SASNAV_SCENE_FILE scenario needs the caller to load the scene and pass it. */
int sasnav_simulate(const sasnav_scenario *sc, const sasnav_scene *scene,
                    const sasnav_op_opts *opts, sasnav_run **run);

/* The same with a progress callback over the simulated pings (may be
 * NULL; sasnav_ping_progress_fn: image.h). */
int sasnav_simulate_progress(const sasnav_scenario *sc, const sasnav_scene *scene,
                             const sasnav_op_opts *opts, sasnav_run **run,
                             sasnav_ping_progress_fn progress, void *user);

/* Where sasnav_simulate_stream puts the pings (e.g. a run file written
 * ping by ping: sasnav_run_writer, io.h). put() receives ping p's samples
 * (n_rx * n_samples values); get() reads back what was put. Both return
 * SASNAV_OK or an error code (message set). */
typedef struct {
    int (*put)(void *ctx, int p, const sasnav_cfloat *samples);
    int (*get)(void *ctx, int p, sasnav_cfloat *samples);
    void *ctx;
} sasnav_ping_sink;

/* sasnav_simulate_progress without holding the run: each ping goes to
 * sink->put as it is made (noise-free); with a finite SNR each is then read
 * back (get), given its noise and put again (the noise's scale is the
 * run's mean signal power, known only after the last ping). The samples
 * are the same bits as sasnav_simulate's. Memory: the scene and one ping.
 * *header receives the run without samples (raw NULL: navigation, truth,
 * aiding, constants; for sasnav_run_writer_finish; free with
 * sasnav_run_free). A scene much longer than a ping's reach (a survey) is
 * simulated band by band along track (src/sim/simulate.c): the cost grows
 * linearly with the run's length. */
int sasnav_simulate_stream(const sasnav_scenario *sc, const sasnav_scene *scene,
                           const sasnav_op_opts *opts, const sasnav_ping_sink *sink,
                           sasnav_run **header, sasnav_ping_progress_fn progress, void *user);

/* The pieces of sasnav_simulate_stream, for callers that spread the pings
 * over processes (`mpirun sasnav simulate`): the same bits when the pings'
 * power is summed in ping order and the noise added by one caller.
 * sasnav_scenario_header: the run of a scenario without samples
 * (navigation, truth, constants; free with sasnav_run_free).
 * sasnav_scenario_scene: the scenario's own scene (ripples or points).
 * sasnav_simulator_*: noise-free pings of a header's true poses from a
 * scene (which both must outlive the simulator); ping p needs no other
 * ping (any order, any process). sasnav_ping_power: acc + sum |s|^2 over n
 * samples, in order (the mean power is its total over all pings in ping
 * order / samples). sasnav_simulate_noise: the second pass (get, add noise
 * of `mean_power` at the scenario's SNR, put; every ping in order). */
typedef struct sasnav_simulator sasnav_simulator;
int sasnav_scenario_header(const sasnav_scenario *sc, sasnav_run **header);
int sasnav_scenario_scene(const sasnav_scenario *sc, sasnav_scene **scene);
int sasnav_simulator_create(const sasnav_run *header, const sasnav_scene *scene, const sasnav_op_opts *opts,
                            sasnav_simulator **sim);
int sasnav_simulator_ping(sasnav_simulator *sim, int p, sasnav_cfloat *out);
void sasnav_simulator_destroy(sasnav_simulator *sim);
double sasnav_ping_power(const sasnav_cfloat *samples, size_t n, double acc);
int sasnav_simulate_noise(const sasnav_scenario *sc, const sasnav_run *header, double mean_power,
                          const sasnav_ping_sink *sink);

#ifdef __cplusplus
}
#endif
#endif
