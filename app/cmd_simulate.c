/* sasnav simulate: a run from a preset and/or a config file. */
#include "cli.h"
#include "sasnav/config.h"
#include "sasnav/io.h"
#include "sasnav/sim.h"

#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *help =
    "usage: sasnav simulate --preset NAME [--config FILE] [--seed N] [--snr DB]\n"
    "                       [--error SURGE,SWAY,YAW] [--aiding] [--threads N] -o run.h5\n"
    "       sasnav simulate --preset tank [--seed N] [--omni] -o DIR\n"
    "\n"
    "Simulates baseband pulse-compressed echoes of a scenario from scatterers\n"
    "placed off any image grid, with the true sensor poses, and writes them with\n"
    "the nominal and true navigation (docs/format.md).\n"
    "\n"
    "  --preset NAME    paper-pair | paper-trajectory | point (default\n"
    "                   paper-trajectory), or tank: the tank experiment as the\n"
    "                   recordings a user would have (multichannel passband WAV\n"
    "                   per ping, chirp, positions; 'sasnav tank --help'),\n"
    "                   written into the directory -o DIR\n"
    "  --config FILE    YAML scenario overriding the preset (docs/config.md)\n"
    "  --seed N         seed of the scene, trajectory and noise draws\n"
    "  --snr DB         signal-to-noise ratio in dB ('inf' = noise-free)\n"
    "  --error S,W,Y    motion error of ping 2 relative to ping 1: surge (m),\n"
    "                   sway (m), yaw (rad)\n"
    "  --aiding         also write gyro and DVL measurements of the true\n"
    "                   trajectory (navigation-grade INS and 600 kHz DVL error\n"
    "                   models; the config's 'aiding' section sets them;\n"
    "                   docs/config.md), which 'sasnav navigate' fuses\n"
    "  --threads N      OpenMP threads (default: all cores)\n"
    "  -o FILE          output run file (HDF5)\n";

static int writer_put(void *ctx, int p, const sasnav_cfloat *samples)
{
    return sasnav_run_writer_put(ctx, p, samples);
}

static int writer_get(void *ctx, int p, sasnav_cfloat *samples)
{
    return sasnav_run_writer_get(ctx, p, samples);
}

int cmd_simulate(int argc, char **argv)
{
    static const struct option longopts[] = {
        {"preset", required_argument, 0, 'p'}, {"config", required_argument, 0, 'c'},
        {"seed", required_argument, 0, 's'},   {"snr", required_argument, 0, 'n'},
        {"error", required_argument, 0, 'e'},  {"threads", required_argument, 0, 't'},
        {"output", required_argument, 0, 'o'}, {"help", no_argument, 0, 'h'},
        {"omni", no_argument, 0, 'O'},         {"aiding", no_argument, 0, 'A'},
        {0, 0, 0, 0}};
    const char *preset = "paper-trajectory", *config = NULL, *seed = NULL, *snr = NULL,
               *error = NULL, *output = NULL;
    long threads = 0;
    int opt, omni = 0, aiding = 0;
    optind = 1;
    while ((opt = getopt_long(argc, argv, "p:c:s:n:e:t:o:h", longopts, NULL)) != -1) {
        switch (opt) {
        case 'p': preset = optarg; break;
        case 'c': config = optarg; break;
        case 's': seed = optarg; break;
        case 'n': snr = optarg; break;
        case 'e': error = optarg; break;
        case 't':
            if (cli_parse_int(optarg, 0, 1024, &threads))
                return cli_usage("simulate", "--threads needs an integer 0..1024");
            break;
        case 'o': output = optarg; break;
        case 'O': omni = 1; break;
        case 'A': aiding = 1; break;
        case 'h': fputs(help, stdout); return 0;
        default: return cli_bad_option("simulate", argv, longopts);
        }
    }
    if (optind < argc) return cli_usage("simulate", "unexpected argument '%s'", argv[optind]);
    if (!output) return cli_usage("simulate", "an output file is required (-o run.h5)");
    if (omni && strcmp(preset, "tank")) return cli_usage("simulate", "--omni applies to --preset tank only");
    if (!strcmp(preset, "tank")) {
        if (config || snr || error || aiding)
            return cli_usage("simulate", "--preset tank takes only --seed, --omni and -o DIR");
        char *args[7] = {"tank", "-o", (char *)output, NULL, NULL, NULL, NULL};
        int na = 3;
        if (seed) {
            args[na++] = "--seed";
            args[na++] = (char *)seed;
        }
        if (omni) args[na++] = "--omni";
        return cmd_tank(na, args);
    }

    sasnav_scenario sc;
    int rc = sasnav_scenario_preset(preset, &sc);
    if (rc) return cli_usage("simulate", "--preset needs paper-pair, paper-trajectory, point or tank (got '%s')", preset);
    if (config && (rc = sasnav_config_load(config, &sc)))
        return cli_fail("simulate", rc, "invalid configuration");
    if (seed) {
        long s;
        if (cli_parse_int(seed, 0, 0x7fffffffL, &s))
            return cli_usage("simulate", "--seed needs a non-negative integer");
        sasnav_scenario_seed(&sc, (uint64_t)s);
    }
    if (aiding) sc.aiding.enabled = 1;
    if (snr) {
        double v;
        if (!strcmp(snr, "inf")) sc.snr_db = INFINITY;
        else if (cli_parse_double(snr, &v)) return cli_usage("simulate", "--snr needs a number or 'inf'");
        else sc.snr_db = v;
    }
    if (error) {
        double e[3];
        if (cli_parse_doubles(error, 3, e))
            return cli_usage("simulate", "--error needs SURGE,SWAY,YAW (three finite numbers)");
        if (sc.traj.n_pings < 2) return cli_usage("simulate", "--error needs at least two pings");
        sc.traj.has_pair_error = 1;
        sc.traj.pair_q = 1;
        sc.traj.pair_error = (sasnav_pose){e[0], e[1], e[2]};
    }
    rc = sasnav_scenario_check(&sc);
    if (rc) return cli_fail("simulate", rc, "scenario");

    sasnav_scene *scene = NULL;
    if (sc.scene_kind == SASNAV_SCENE_FILE) {
        sasnav_grid g;
        sasnav_cfloat *img = NULL;
        rc = sasnav_image_read(sc.scene_file, &g, &img);
        if (rc) return cli_fail("simulate", rc, "scene file %s", sc.scene_file);
        rc = sasnav_scene_from_image(g.x0, g.y0, g.dx, g.dy, g.nx, g.ny, img, 0.3, sc.ripples.seed,
                                     &scene);
        free(img);
        if (rc) return cli_fail("simulate", rc, "scene file %s", sc.scene_file);
    }
    sasnav_op_opts oo;
    sasnav_op_default_opts(&oo);
    oo.nthreads = (int)threads;
    /* Streamed: each ping is written as it is made (memory: the scene and
     * one ping, whatever the run's length). */
    sasnav_window win;
    rc = sasnav_window_for_ranges(&sc.sys, sc.range_min, sc.range_max, 8, &win);
    sasnav_run shape;
    memset(&shape, 0, sizeof shape);
    shape.sys = sc.sys;
    shape.array = sc.array;
    shape.win = win;
    shape.n_pings = sc.traj.n_pings;
    sasnav_run_writer *w = NULL;
    if (!rc) rc = sasnav_run_writer_open(output, &shape, &w);
    if (rc) {
        sasnav_scene_free(scene);
        return cli_fail("simulate", rc, "cannot write %s", output);
    }
    sasnav_ping_sink sink = {writer_put, writer_get, w};
    sasnav_run *run = NULL;
    cli_progress prog;
    cli_progress_init(&prog, "simulate", "pings");
    rc = sasnav_simulate_stream(&sc, scene, &oo, &sink, &run, cli_ping_progress, &prog);
    cli_progress_end(&prog);
    sasnav_scene_free(scene);
    if (rc) {
        sasnav_run_writer_abort(w);
        return cli_fail("simulate", rc, "simulation failed");
    }
    rc = sasnav_run_writer_finish(w, run);
    int pings = run->n_pings, rx = run->array.n_rx, ns = run->win.n_samples;
    sasnav_run_free(run);
    if (rc) return cli_fail("simulate", rc, "cannot write %s", output);
    fprintf(stderr, "sasnav simulate: %s: %d pings x %d channels x %d samples%s -> %s\n", sc.name,
            pings, rx, ns, sc.aiding.enabled ? " + aiding" : "", output);
    return 0;
}
