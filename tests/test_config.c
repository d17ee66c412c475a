/* Scenario configuration files: the examples load with the values they
 * state, bad files are refused with the key and the file named, and
 * write -> load reproduces the scenario. */
#include "sasnav/config.h"
#include "sasnav/error.h"
#include "testutil.h"

#include <dirent.h>
#include <locale.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static char source_dir[1024];

static void find_source_dir(void)
{
    const char *env = getenv("SASNAV_SOURCE");
    if (env && env[0]) {
        snprintf(source_dir, sizeof source_dir, "%s", env);
        return;
    }
    /* __FILE__ is .../tests/test_config.c in a CMake build. */
    snprintf(source_dir, sizeof source_dir, "%s", __FILE__);
    char *slash = strrchr(source_dir, '/');
    if (slash) *slash = '\0';
    slash = strrchr(source_dir, '/');
    if (slash)
        *slash = '\0';
    else
        snprintf(source_dir, sizeof source_dir, "..");
}

static void example_path(const char *name, char *out, size_t size)
{
    snprintf(out, size, "%s/examples/%s", source_dir, name);
}

static void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    if (!f) {
        fprintf(stderr, "cannot write %s\n", path);
        exit(2);
    }
    fputs(text, f);
    fclose(f);
}

static int near(double a, double b, double rel)
{
    if (isinf(a) || isinf(b)) return a == b;
    return fabs(a - b) <= rel * fmax(1.0, fmax(fabs(a), fabs(b)));
}

static void base_scenario(const char *preset, sasnav_scenario *sc)
{
    memset(sc, 0, sizeof *sc);
    CHECK_OK(sasnav_scenario_preset(preset, sc));
}

/* ---- the examples ---- */

static void test_example_pair(void)
{
    char path[1200];
    sasnav_scenario sc;
    base_scenario("paper-trajectory", &sc); /* the file's preset replaces it */
    example_path("paper-pair.yaml", path, sizeof path);
    CHECK_OK(sasnav_config_load(path, &sc));
    CHECK(strcmp(sc.name, "paper-pair") == 0, "name %s", sc.name);
    CHECK(sc.sys.sound_speed == 1500 && sc.sys.f0 == 300e3 && sc.sys.bandwidth == 30e3 &&
              sc.sys.sample_rate == 60e3,
          "system %g %g %g %g", sc.sys.sound_speed, sc.sys.f0, sc.sys.bandwidth,
          sc.sys.sample_rate);
    CHECK(sc.sys.taper == SASNAV_TAPER_NONE && sc.sys.attenuation == SASNAV_ATTEN_EXPLODING &&
              sc.sys.beam_pattern == 1,
          "system enums");
    CHECK(sc.array.n_rx == 16, "n_rx %d", sc.array.n_rx);
    /* Uniform array of 16 receivers 5 cm apart around the midpoint. */
    CHECK(near(sc.array.rx_u[0], -0.375, 1e-14) && near(sc.array.rx_u[15], 0.375, 1e-14),
          "rx_u %g..%g", sc.array.rx_u[0], sc.array.rx_u[15]);
    CHECK(sc.array.rx_length == 0.05 && sc.array.tx_length == 0.05, "lengths");
    CHECK(sc.range_min == 8.8 && sc.range_max == 11.6 && sc.range_of_interest == 10.0, "swath");
    CHECK(sc.traj.n_pings == 2 && sc.traj.ping_spacing == 0.20 && sc.traj.x_start == -0.10 &&
              sc.traj.tx_lag == 0.10 && sc.traj.true_bistatic == 0,
          "trajectory");
    CHECK(sc.traj.has_pair_error == 1 && sc.traj.pair_q == 1 && sc.traj.pair_error.x == -0.0345 &&
              sc.traj.pair_error.y == 0.0217 && sc.traj.pair_error.theta == 0.0410,
          "pair error %d q=%d (%g, %g, %g)", sc.traj.has_pair_error, sc.traj.pair_q,
          sc.traj.pair_error.x, sc.traj.pair_error.y, sc.traj.pair_error.theta);
    CHECK(sc.scene_kind == SASNAV_SCENE_RIPPLES && sc.ripples.x_min == -1.6 &&
              sc.ripples.x_max == 1.6 && sc.ripples.disc_radius == 0.2 && sc.ripples.disc_y == 10.0,
          "scene");
    CHECK(sc.snr_db == 30, "snr %g", sc.snr_db);
    CHECK(sc.image_grid.nx == 81 && sc.image_grid.ny == 129 &&
              near(sc.image_grid.dx, 0.0125, 1e-12) && near(sc.image_grid.dy, 0.0125, 1e-12) &&
              sc.image_grid.x0 == -0.5 && sc.image_grid.y0 == 9.2,
          "image grid %d x %d, %g %g", sc.image_grid.nx, sc.image_grid.ny, sc.image_grid.dx,
          sc.image_grid.dy);
}

static void test_example_trajectory(void)
{
    char path[1200];
    sasnav_scenario sc;
    base_scenario("paper-pair", &sc);
    example_path("paper-trajectory.yaml", path, sizeof path);
    CHECK_OK(sasnav_config_load(path, &sc));
    CHECK(strcmp(sc.name, "paper-trajectory") == 0, "name %s", sc.name);
    CHECK(sc.traj.n_pings == 16 && sc.traj.ping_spacing == 0.20 && sc.traj.speed == 2.0 &&
              sc.traj.x_start == -1.5,
          "track");
    CHECK(sc.traj.surge_rms == 0.01 && sc.traj.sway_rms == 0.01 && sc.traj.yaw_rms == 0.01 &&
              sc.traj.smooth_length == 1.0 && sc.traj.seed == 7,
          "motion errors");
    CHECK(sc.traj.true_bistatic == 1 && sc.traj.tx_lag == 0.10, "bistatic");
    /* paper-pair's pair error was replaced by the preset, and `none` kept it off. */
    CHECK(sc.traj.has_pair_error == 0, "pair_error: none");
    CHECK(sc.ripples.x_min == -2.6 && sc.ripples.x_max == 2.6 && sc.ripples.density == 1e4 &&
              sc.ripples.ripple_period == 0.15 && sc.ripples.ripple_angle == 0.3 &&
              sc.ripples.ripple_depth == 0.6 && sc.ripples.seed == 1,
          "ripples");
    CHECK(sc.snr_db == 30 && sc.noise_seed == 11, "noise");
    CHECK(sc.image_grid.nx == 321 && near(sc.image_grid.dx, 0.0125, 1e-12), "grid nx %d dx %g",
          sc.image_grid.nx, sc.image_grid.dx);
}

static void test_example_point(void)
{
    char path[1200];
    sasnav_scenario sc;
    base_scenario("paper-trajectory", &sc);
    example_path("point-target.yaml", path, sizeof path);
    CHECK_OK(sasnav_config_load(path, &sc));
    CHECK(strcmp(sc.name, "point-target") == 0, "name %s", sc.name);
    CHECK(sc.scene_kind == SASNAV_SCENE_POINTS, "kind %d", (int)sc.scene_kind);
    CHECK(sc.n_targets == 1 && sc.target_x[0] == 0.013 && sc.target_y[0] == 10.007 &&
              sc.target_amp[0] == 1.0,
          "target %d (%g, %g, %g)", sc.n_targets, sc.target_x[0], sc.target_y[0], sc.target_amp[0]);
    CHECK(isinf(sc.snr_db) && sc.snr_db > 0, "snr %g", sc.snr_db);
    CHECK(sc.traj.n_pings == 17 && sc.traj.x_start == -1.6 && sc.traj.surge_rms == 0, "track");
    CHECK(sc.range_min == 9.3 && sc.range_max == 10.8, "swath");
    CHECK(sc.image_grid.nx == 121 && near(sc.image_grid.dx, 0.0025, 1e-12), "grid");
}

/* ---- bad files ---- */

/* Loads `text` from a file and expects `status` with every string of
 * `needles` (NULL-terminated) in the message; *sc must be unchanged. */
static void expect_bad(const char *dir, const char *label, const char *text, int status,
                       const char *const *needles)
{
    char path[600];
    snprintf(path, sizeof path, "%s/%s.yaml", dir, label);
    write_text(path, text);
    sasnav_scenario sc, before;
    base_scenario("paper-pair", &sc);
    before = sc;
    int rc = sasnav_config_load(path, &sc);
    const char *msg = sasnav_last_error();
    CHECK(rc == status, "%s: expected %d, got %d (%s)", label, status, rc, msg);
    for (int i = 0; needles && needles[i]; i++)
        CHECK(strstr(msg, needles[i]) != NULL, "%s: message '%s' lacks '%s'", label, msg,
              needles[i]);
    CHECK(strstr(msg, label) != NULL, "%s: message '%s' does not name the file", label, msg);
    CHECK(memcmp(&sc, &before, sizeof sc) == 0, "%s: scenario modified by a failed load", label);
}

#define NEEDLES(...) ((const char *const[]){__VA_ARGS__, NULL})

static void test_bad_files(const char *dir)
{
    const int E = SASNAV_ERR_CONFIG;
    /* Non-finite numbers, in every spelling. */
    expect_bad(dir, "nan", "system:\n  f0: .nan\n", E, NEEDLES("system.f0", "finite", ":2"));
    expect_bad(dir, "nan2", "scene:\n  disc_x: NaN\n", E, NEEDLES("scene.disc_x", "finite"));
    expect_bad(dir, "inf", "swath:\n  range_max: .inf\n", E, NEEDLES("swath.range_max"));
    expect_bad(dir, "inf2", "swath:\n  range_max: inf\n", E, NEEDLES("swath.range_max"));
    expect_bad(dir, "notnum", "system:\n  f0: abc\n", E, NEEDLES("system.f0", "'abc'"));
    expect_bad(dir, "quoted", "system:\n  f0: '300e3'\n", E, NEEDLES("system.f0", "quoted"));
    expect_bad(dir, "snrnan", "noise:\n  snr_db: .nan\n", E, NEEDLES("noise.snr_db"));
    /* Unknown keys and sections. */
    expect_bad(dir, "unknown", "system:\n  f00: 1\n", E,
               NEEDLES("system.f00", "unknown key", "f0"));
    expect_bad(dir, "section", "sytem:\n  f0: 1\n", E, NEEDLES("sytem", "unknown key"));
    expect_bad(dir, "nested", "trajectory:\n  pair_error: {ping: 1, roll: 0.1}\n", E,
               NEEDLES("trajectory.pair_error.roll"));
    /* Ranges and counts. */
    expect_bad(dir, "negrange", "swath:\n  range_min: -1\n", E, NEEDLES("swath.range_min", "> 0"));
    expect_bad(dir, "swapped", "swath:\n  range_min: 12\n  range_max: 9\n", E,
               NEEDLES("swath.range_min", "swath.range_max"));
    expect_bad(dir, "zerorx", "array:\n  n_rx: 0\n", E, NEEDLES("array.n_rx", ">= 1"));
    expect_bad(dir, "manyrx", "array:\n  n_rx: 129\n", E, NEEDLES("array.n_rx", "<= 128"));
    expect_bad(dir, "fracrx", "array:\n  n_rx: 16.5\n", E, NEEDLES("array.n_rx", "integer"));
    expect_bad(dir, "negpings", "trajectory:\n  n_pings: -3\n", E, NEEDLES("trajectory.n_pings"));
    expect_bad(dir, "negseed", "noise:\n  seed: -1\n", E, NEEDLES("noise.seed"));
    expect_bad(dir, "depth", "scene:\n  ripple_depth: 1.5\n", E, NEEDLES("scene.ripple_depth"));
    expect_bad(dir, "pairq", "trajectory:\n  pair_error: {ping: 2}\n", E,
               NEEDLES("trajectory.pair_error.ping", "trajectory.n_pings"));
    expect_bad(dir, "gridn", "image:\n  nx: 0\n", E, NEEDLES("image.nx"));
    expect_bad(dir, "gridrange", "image:\n  x_min: 1\n  x_max: 0\n", E, NEEDLES("image"));
    expect_bad(dir, "spacing", "array:\n  rx_spacing: 0\n", E, NEEDLES("array.rx_spacing"));
    expect_bad(dir, "rxboth", "array:\n  rx_spacing: 0.05\n  rx_positions: [0, 0.1]\n", E,
               NEEDLES("array.rx_spacing", "array.rx_positions"));
    /* Wrong types and shapes. */
    expect_bad(dir, "enum", "system:\n  taper: kaiser\n", E, NEEDLES("system.taper", "hann"));
    expect_bad(dir, "bool", "system:\n  beam_pattern: yes please\n", E,
               NEEDLES("system.beam_pattern", "true or false"));
    expect_bad(dir, "scalarsec", "system: 3\n", E, NEEDLES("system", "mapping"));
    expect_bad(dir, "mapvalue", "array:\n  n_rx: {a: 1}\n", E, NEEDLES("array.n_rx", "mapping"));
    expect_bad(dir, "empty", "system:\n  f0:\n", E, NEEDLES("system.f0", "missing"));
    expect_bad(dir, "target2", "scene:\n  kind: points\n  targets: [[1, 2]]\n", E,
               NEEDLES("scene.targets[0]", "[x, y, amplitude]"));
    expect_bad(dir, "targetnan", "scene:\n  targets: [[1, 2, .nan]]\n", E,
               NEEDLES("scene.targets[0][2]"));
    expect_bad(dir, "notargets", "scene:\n  kind: points\n  targets: []\n", E,
               NEEDLES("scene.targets"));
    expect_bad(dir, "toplist", "- 1\n- 2\n", E, NEEDLES("mapping"));
    expect_bad(dir, "alias", "swath:\n  range_min: &r 9\n  range_of_interest: *r\n", E,
               NEEDLES("swath.range_of_interest", "alias"));
    expect_bad(dir, "preset", "preset: paper-pear\n", E, NEEDLES("preset", "paper-pear"));
    /* YAML syntax errors carry the line. */
    expect_bad(dir, "syntax", "system:\n  f0: [1, 2\n", E, NEEDLES("syntax", ":3:"));
    expect_bad(dir, "tabs", "system:\n\tf0: 1\n", E, NEEDLES("syntax"));
    expect_bad(dir, "dupkey", "system:\n  f0: 1\n  f0: 2\n", E, NEEDLES("duplicate"));

    /* Too many targets. */
    char text[4096] = "scene:\n  targets:\n";
    for (int i = 0; i < SASNAV_MAX_TARGETS + 1; i++) strcat(text, "    - [0, 10, 1]\n");
    expect_bad(dir, "manytargets", text, E, NEEDLES("scene.targets", "at most"));

    /* A missing file is an I/O error. */
    char path[600];
    sasnav_scenario sc;
    base_scenario("paper-pair", &sc);
    snprintf(path, sizeof path, "%s/does-not-exist.yaml", dir);
    CHECK(sasnav_config_load(path, &sc) == SASNAV_ERR_IO, "missing file: %s", sasnav_last_error());
    CHECK(strstr(sasnav_last_error(), "does-not-exist.yaml") != NULL, "message names the file");
    CHECK(sasnav_config_load(dir, &sc) == SASNAV_ERR_IO, "a directory is not a config");
    CHECK(sasnav_config_load(NULL, &sc) == SASNAV_ERR_ARG, "NULL path");
    CHECK(sasnav_config_load(path, NULL) == SASNAV_ERR_ARG, "NULL scenario");
}

/* ---- accepted variants ---- */

static void test_good_variants(const char *dir)
{
    char path[600];
    sasnav_scenario sc, before;

    /* Empty and comment-only files change nothing. */
    snprintf(path, sizeof path, "%s/empty.yaml", dir);
    write_text(path, "");
    base_scenario("paper-pair", &sc);
    before = sc;
    CHECK_OK(sasnav_config_load(path, &sc));
    CHECK(memcmp(&sc, &before, sizeof sc) == 0, "empty file changed the scenario");
    write_text(path, "# nothing but a comment\n");
    CHECK_OK(sasnav_config_load(path, &sc));
    CHECK(memcmp(&sc, &before, sizeof sc) == 0, "comment-only file changed the scenario");

    /* snr_db spellings of infinity; overrides without a preset key apply
     * on top of the caller's scenario. */
    const char *infs[] = {"inf", ".inf", "+inf", ".Inf", "\"inf\"", "Infinity"};
    for (int i = 0; i < 6; i++) {
        char text[80];
        snprintf(text, sizeof text, "noise:\n  snr_db: %s\n", infs[i]);
        write_text(path, text);
        base_scenario("paper-pair", &sc);
        CHECK_OK(sasnav_config_load(path, &sc));
        CHECK(isinf(sc.snr_db) && sc.snr_db > 0, "snr_db: %s gave %g", infs[i], sc.snr_db);
        CHECK(sc.traj.n_pings == 2, "preset values kept");
    }

    /* Only lengths changed: receiver positions stay; heights are kept when
     * the array is rebuilt from n_rx. */
    write_text(path, "array:\n  rx_height: 0.5\n  n_rx: 8\n  tx_length: 0\n");
    base_scenario("paper-pair", &sc);
    CHECK_OK(sasnav_config_load(path, &sc));
    CHECK(sc.array.n_rx == 8 && near(sc.array.rx_u[0], -0.175, 1e-14) &&
              sc.array.rx_height == 0.5 && sc.array.tx_length == 0 && sc.array.rx_length == 0.05,
          "array rebuilt: n=%d u0=%g h=%g", sc.array.n_rx, sc.array.rx_u[0], sc.array.rx_height);

    /* Non-uniform array through rx_positions. */
    write_text(path, "array:\n  rx_positions: [-0.1, 0.0, 0.05, 0.3]\n");
    base_scenario("paper-pair", &sc);
    CHECK_OK(sasnav_config_load(path, &sc));
    CHECK(sc.array.n_rx == 4 && sc.array.rx_u[2] == 0.05 && sc.array.rx_u[3] == 0.3,
          "rx_positions");

    /* pair_error: none switches the preset's error off; flow mappings work. */
    write_text(path, "trajectory: {pair_error: none, n_pings: 5}\n");
    base_scenario("paper-pair", &sc);
    CHECK_OK(sasnav_config_load(path, &sc));
    CHECK(sc.traj.has_pair_error == 0 && sc.traj.n_pings == 5, "pair_error none");
}

/* ---- write -> load ---- */

static void compare_scenarios(const char *label, const sasnav_scenario *a, const sasnav_scenario *b)
{
    /* Exact for every value that is written as-is (shortest round-trip
     * decimal); 1e-12 relative where the file stores a derived quantity:
     * receiver positions (from a spacing) and the grid (from its extent). */
    const double rel = 1e-12;
    CHECK(strcmp(a->name, b->name) == 0, "%s: name '%s' vs '%s'", label, a->name, b->name);
    CHECK(test_same_system(&a->sys, &b->sys), "%s: system differs", label);
    CHECK(a->array.n_rx == b->array.n_rx, "%s: n_rx", label);
    for (int l = 0; l < a->array.n_rx && l < SASNAV_MAX_RX; l++)
        CHECK(near(a->array.rx_u[l], b->array.rx_u[l], rel), "%s: rx_u[%d] %.17g vs %.17g", label,
              l, a->array.rx_u[l], b->array.rx_u[l]);
    CHECK(a->array.rx_length == b->array.rx_length && a->array.tx_length == b->array.tx_length &&
              a->array.rx_height == b->array.rx_height && a->array.tx_height == b->array.tx_height,
          "%s: array sizes", label);
    CHECK(a->range_min == b->range_min && a->range_max == b->range_max &&
              a->range_of_interest == b->range_of_interest,
          "%s: swath", label);
    const sasnav_trajectory_params *ta = &a->traj, *tb = &b->traj;
    CHECK(ta->n_pings == tb->n_pings && ta->ping_spacing == tb->ping_spacing &&
              ta->speed == tb->speed && ta->x_start == tb->x_start &&
              ta->surge_rms == tb->surge_rms && ta->sway_rms == tb->sway_rms &&
              ta->yaw_rms == tb->yaw_rms && ta->smooth_length == tb->smooth_length &&
              ta->tx_lag == tb->tx_lag && ta->true_bistatic == tb->true_bistatic &&
              ta->seed == tb->seed,
          "%s: trajectory", label);
    CHECK(ta->has_pair_error == tb->has_pair_error, "%s: has_pair_error", label);
    if (ta->has_pair_error)
        CHECK(ta->pair_q == tb->pair_q && ta->pair_error.x == tb->pair_error.x &&
                  ta->pair_error.y == tb->pair_error.y &&
                  ta->pair_error.theta == tb->pair_error.theta,
              "%s: pair error", label);
    CHECK(a->scene_kind == b->scene_kind, "%s: scene kind", label);
    CHECK(memcmp(&a->ripples, &b->ripples, sizeof a->ripples) == 0, "%s: ripple parameters", label);
    CHECK(a->n_targets == b->n_targets, "%s: n_targets", label);
    for (int i = 0; i < a->n_targets && i < SASNAV_MAX_TARGETS; i++)
        CHECK(a->target_x[i] == b->target_x[i] && a->target_y[i] == b->target_y[i] &&
                  a->target_amp[i] == b->target_amp[i],
              "%s: target %d", label, i);
    CHECK(strcmp(a->scene_file, b->scene_file) == 0, "%s: scene file", label);
    CHECK(a->n_channel_tx == b->n_channel_tx, "%s: %d vs %d channel transmitters", label, a->n_channel_tx,
          b->n_channel_tx);
    for (int l = 0; l < a->n_channel_tx && l < SASNAV_MAX_RX; l++)
        CHECK(a->channel_tx_u[l] == b->channel_tx_u[l], "%s: channel %d's transmitter", label, l);
    CHECK(a->snr_db == b->snr_db && a->noise_seed == b->noise_seed, "%s: noise %g vs %g", label,
          a->snr_db, b->snr_db);
    const sasnav_grid *ga = &a->image_grid, *gb = &b->image_grid;
    CHECK(ga->nx == gb->nx && ga->ny == gb->ny && ga->x0 == gb->x0 && ga->y0 == gb->y0 &&
              near(ga->dx, gb->dx, rel) && near(ga->dy, gb->dy, rel),
          "%s: image grid (%.17g, %.17g) vs (%.17g, %.17g)", label, ga->dx, ga->dy, gb->dx, gb->dy);
}

static void round_trip(const char *dir, const char *label, const sasnav_scenario *sc)
{
    char path[600];
    snprintf(path, sizeof path, "%s/rt-%s.yaml", dir, label);
    CHECK_OK(sasnav_config_write(path, sc));
    /* Load onto an empty scenario: every key must be in the file. */
    sasnav_scenario back;
    memset(&back, 0, sizeof back);
    CHECK_OK(sasnav_config_load(path, &back));
    compare_scenarios(label, sc, &back);
    /* And onto a different preset. */
    base_scenario("point", &back);
    CHECK_OK(sasnav_config_load(path, &back));
    compare_scenarios(label, sc, &back);
}

static void test_round_trip(const char *dir)
{
    const char *presets[] = {"paper-pair", "paper-trajectory", "point"};
    sasnav_scenario sc;
    for (int i = 0; i < 3; i++) {
        base_scenario(presets[i], &sc);
        round_trip(dir, presets[i], &sc);
    }

    /* Everything away from the presets: awkward values, a non-uniform
     * array, many targets, extreme seeds, a name that needs escaping. */
    base_scenario("paper-pair", &sc);
    snprintf(sc.name, sizeof sc.name, "odd \"name\" # with \\ and: colon");
    sc.sys.taper = SASNAV_TAPER_HAMMING;
    sc.sys.attenuation = SASNAV_ATTEN_SPHERICAL;
    sc.sys.beam_pattern = 0;
    sc.sys.f0 = 1.0 / 3.0 * 1e6;
    sc.array.n_rx = 5;
    double u[5] = {-0.2, -0.1, 0.0, 0.15, 0.31};
    memcpy(sc.array.rx_u, u, sizeof u);
    sc.array.rx_height = 0.7;
    sc.array.tx_height = 0.1 + 0.2;
    sc.n_channel_tx = 5; /* channels with transmitters of their own */
    double tu[5] = {-0.2, 1.0 / 3.0, 0.0, 0.15, -1e-3};
    memcpy(sc.channel_tx_u, tu, sizeof tu);
    sc.traj.pair_q = 1;
    sc.traj.pair_error = (sasnav_pose){1e-300, -2.5e-5, 0.1};
    sc.traj.seed = UINT64_MAX;
    sc.traj.x_start = -0.0;
    sc.scene_kind = SASNAV_SCENE_POINTS;
    sc.n_targets = SASNAV_MAX_TARGETS;
    for (int i = 0; i < sc.n_targets; i++) {
        sc.target_x[i] = 0.01 * i - 0.3;
        sc.target_y[i] = 9.5 + 0.017 * i;
        sc.target_amp[i] = i % 2 ? -1.5 : 0.1 * i;
    }
    snprintf(sc.scene_file, sizeof sc.scene_file, "dir with space/scene:1.h5");
    sc.snr_db = INFINITY;
    sc.noise_seed = 0;
    CHECK_OK(sasnav_grid_make(-0.123456789, 0.987654321, 97, 9.0, 9.0, 1, &sc.image_grid));
    CHECK_OK(sasnav_scenario_check(&sc));
    round_trip(dir, "odd", &sc);

    /* One receiver (no spacing) and a file scene. */
    base_scenario("paper-pair", &sc);
    CHECK_OK(sasnav_array_uniform(&sc.array, 1, 0.05, 0.02, 0.03));
    sc.scene_kind = SASNAV_SCENE_FILE;
    snprintf(sc.scene_file, sizeof sc.scene_file, "scene.h5");
    sc.traj.has_pair_error = 0;
    round_trip(dir, "single", &sc);

    /* Writing into a missing directory fails and leaves nothing. */
    char path[600];
    snprintf(path, sizeof path, "%s/no-such-dir/x.yaml", dir);
    CHECK(sasnav_config_write(path, &sc) == SASNAV_ERR_IO, "write into a missing directory");
    CHECK(sasnav_config_write(NULL, &sc) == SASNAV_ERR_ARG, "NULL path");
    DIR *d = opendir(dir);
    int temps = 0;
    struct dirent *e;
    while (d && (e = readdir(d)))
        if (strstr(e->d_name, ".tmp-")) temps++;
    if (d) closedir(d);
    CHECK(temps == 0, "%d temporary files left", temps);
}

/* Numbers mean the same in a decimal-comma locale. */
static void test_locale(const char *dir)
{
    const char *names[] = {"de_DE.UTF-8", "de_DE.utf8", "fr_FR.UTF-8", "fr_FR.utf8"};
    const char *found = NULL;
    for (int i = 0; i < 4 && !found; i++)
        if (setlocale(LC_NUMERIC, names[i])) found = names[i];
    if (!found) {
        printf("test_config: no decimal-comma locale installed, locale check skipped\n");
        return;
    }
    char path[600];
    snprintf(path, sizeof path, "%s/locale.yaml", dir);
    write_text(path, "array:\n  rx_spacing: 0.025\n");
    sasnav_scenario sc;
    base_scenario("paper-pair", &sc);
    CHECK_OK(sasnav_config_load(path, &sc));
    CHECK(near(sc.array.rx_u[1] - sc.array.rx_u[0], 0.025, 1e-12), "spacing under %s", found);
    round_trip(dir, "locale", &sc);
    setlocale(LC_NUMERIC, "C");
}

int main(void)
{
    find_source_dir();
    const char *dir = test_tmpdir();
    test_example_pair();
    test_example_trajectory();
    test_example_point();
    test_bad_files(dir);
    test_good_variants(dir);
    test_round_trip(dir);
    test_locale(dir);
    return test_summary("test_config");
}
