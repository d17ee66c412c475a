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
    "  --preset NAME    paper-pair | paper-trajectory | point | survey | circular\n"
    "                   (default paper-trajectory; survey: a 300 kHz survey\n"
    "                   SAS over a 100 m varied seabed; circular: a simulated\n"
    "                   AirSAS, one channel on a 0.85 m circle; docs/config.md),\n"
    "                   or tank: the\n"
    "                   tank experiment as the recordings a user would have\n"
    "                   (multichannel passband WAV per ping, chirp, positions;\n"
    "                   'sasnav tank --help'), written into the directory -o DIR\n"
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
    "  -o FILE          output run file (HDF5)\n"
    "\n"
    "The run is written ping by ping (memory: the scene and one ping).\n"
    "'mpirun -np N sasnav simulate ...' spreads the pings over N processes;\n"
    "rank 0 writes the same file as one process, bit for bit (docs/survey.md).\n";

static int writer_put(void *ctx, int p, const sasnav_cfloat *samples)
{
    return sasnav_run_writer_put(ctx, p, samples);
}

static int writer_get(void *ctx, int p, sasnav_cfloat *samples)
{
    return sasnav_run_writer_get(ctx, p, samples);
}

/* `mpirun -np N sasnav simulate`: rank r makes the pings p with p % N == r
 * (noise-free) and sends them to rank 0, which writes them in ping order,
 * sums their power in that order, then adds the noise (one random stream,
 * as one process does) and the aiding: the same file as one process, bit
 * for bit. Takes the scene (freed). Returns the CLI status. */
static int simulate_distributed(const sasnav_scenario *sc, sasnav_scene *scene, const sasnav_op_opts *oo,
                                const char *output)
{
    int ranks = cli_mpi_size(), rank = cli_mpi_rank(), rank0_failed = 0;
    sasnav_run *head = NULL;
    sasnav_simulator *sim = NULL;
    sasnav_run_writer *w = NULL;
    int rc = sasnav_scenario_header(sc, &head);
    if (!rc && !scene) rc = sasnav_scenario_scene(sc, &scene);
    if (!rc) rc = sasnav_simulator_create(head, scene, oo, &sim);
    size_t per_ping = head ? sasnav_run_ping_size(head) : 1;
    sasnav_cfloat *buf = rc ? NULL : malloc(sizeof *buf * per_ping);
    if (!rc && !buf) rc = sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory for a ping");
    if (!rc && rank == 0) rc = sasnav_run_writer_open(output, head, &w);
    if (cli_mpi_any(rc != 0, &rank0_failed)) {
        if (rc && (rank == 0 || !rank0_failed)) cli_fail("simulate", rc, "simulation failed");
        sasnav_run_writer_abort(w);
        sasnav_simulator_destroy(sim);
        sasnav_scene_free(scene);
        sasnav_run_free(head);
        free(buf);
        return CLI_FAILURE;
    }
    cli_progress prog;
    cli_progress_init(&prog, "simulate", "pings");
    double power = 0;
    int n = head->n_pings;
    for (int p = 0; p < n && !rc; p++) {
        int owner = p % ranks;
        if (owner == rank) {
            rc = sasnav_simulator_ping(sim, p, buf);
            if (rc) cli_fail("simulate", rc, "simulation failed");
            if (rank != 0) {
                int st = rc;
                cli_mpi_send(0, &st, sizeof st);
                if (!rc) cli_mpi_send(0, buf, sizeof *buf * per_ping);
                continue;
            }
        } else if (rank == 0) {
            int st = 0;
            cli_mpi_recv(owner, &st, sizeof st);
            if (st) {
                rc = st;
                fprintf(stderr, "sasnav simulate: rank %d failed (above): %s not written\n", owner, output);
                break;
            }
            cli_mpi_recv(owner, buf, sizeof *buf * per_ping);
        } else {
            continue;
        }
        /* rank 0 */
        power = sasnav_ping_power(buf, per_ping, power);
        rc = sasnav_run_writer_put(w, p, buf);
        if (rc) cli_fail("simulate", rc, "cannot write %s", output);
        else cli_progress_update(&prog, p + 1, n);
    }
    cli_progress_end(&prog);
    sasnav_simulator_destroy(sim);
    sasnav_scene_free(scene);
    free(buf);
    if (rank != 0) {
        sasnav_run_free(head);
        return rc ? CLI_FAILURE : 0;
    }
    if (!rc) {
        sasnav_ping_sink sink = {writer_put, writer_get, w};
        rc = sasnav_simulate_noise(sc, head, power / ((double)per_ping * (double)n), &sink);
        if (!rc && sc->aiding.enabled) rc = sasnav_simulate_aiding(&sc->aiding, sc->traj.speed, head);
        if (rc) cli_fail("simulate", rc, "simulation failed");
    }
    if (rc) {
        sasnav_run_writer_abort(w);
        sasnav_run_free(head);
        cli_mpi_abort(CLI_FAILURE); /* the others may wait on a send */
        return CLI_FAILURE;
    }
    rc = sasnav_run_writer_finish(w, head);
    int rx = head->array.n_rx, ns = head->win.n_samples;
    sasnav_run_free(head);
    if (rc) return cli_fail("simulate", rc, "cannot write %s", output);
    fprintf(stderr, "sasnav simulate: %s: %d pings x %d channels x %d samples%s -> %s (%d processes)\n",
            sc->name, n, rx, ns, sc->aiding.enabled ? " + aiding" : "", output, ranks);
    return 0;
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
    if (!strcmp(preset, "tank") && cli_mpi_size() > 1)
        return cli_usage("simulate", "--preset tank runs in one process, not in the %d of mpirun", cli_mpi_size());
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
    if (cli_mpi_size() > 1) return simulate_distributed(&sc, scene, &oo, output);
    /* Streamed: each ping is written as it is made (memory: the scene and
     * one ping, whatever the run's length). */
    sasnav_run *shape = NULL; /* shapes, window, channel offsets (the format version) */
    rc = sasnav_scenario_header(&sc, &shape);
    sasnav_run_writer *w = NULL;
    if (!rc) rc = sasnav_run_writer_open(output, shape, &w);
    sasnav_run_free(shape);
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
