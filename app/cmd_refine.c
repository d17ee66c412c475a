/* sasnav refine: multi-ping data-domain refinement of a navigation. */
#include "cli.h"

#include "sasnav/checkpoint.h"
#include "sasnav/io.h"
#include "sasnav/refine.h"
#include "sasnav/run.h"
#include "sasnav/trajectory.h"

#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* --checkpoint: the state after every sweep, written whole (temporary
 * file and rename). */
typedef struct {
    const char *path; /* NULL: no checkpoint */
    int failed;
    cli_progress progress;
    int sweeps;
} refine_ckpt;

static void save_state(const sasnav_refine_state *st, void *user)
{
    refine_ckpt *k = user;
    cli_progress_update(&k->progress, st->sweeps_done, k->sweeps);
    if (k->failed || !k->path) return;
    if (sasnav_refine_state_write(k->path, st)) {
        k->failed = 1;
        fprintf(stderr, "sasnav refine: warning: %s; going on without checkpointing\n", sasnav_last_error());
    }
}

/* Progress over windows (runs longer than --window). */
static void window_done(int done, int total, const sasnav_refine_report *w, void *user)
{
    (void)w;
    refine_ckpt *k = user;
    cli_progress_update(&k->progress, done, total);
}

static const char *help =
    "usage: sasnav refine run.h5 nav.h5 -o refined.h5 [--grid X0,X1,NX,Y0,Y1,NY]\n"
    "                     [--sweeps N] [--surge-range M] [--sway-range M] [--sparsity EPS]\n"
    "                     [--window N] [--threads N] [--checkpoint FILE]\n"
    "\n"
    "Refines a navigation (the output of 'sasnav navigate', or any navigation\n"
    "file of the run's pings) with all pings together: for each ping in turn,\n"
    "a least-squares scene is fitted to the other pings' data, and the ping is\n"
    "moved along and across its array axis to best predict its own data from\n"
    "that scene (docs/navigation.md, 'Multi-ping refinement'). The common move\n"
    "of all pings is removed (not observable). The start must be within the\n"
    "search ranges of the truth (sway within about a quarter wavelength).\n"
    "Where the run holds the truth, prints the rms surge and sway errors\n"
    "before and after (after the rigid motion that best fits the centroids\n"
    "onto the true ones). The refinement is for scenes of a few strong\n"
    "scatterers (the tank); where the scenes explain the pings poorly (mean\n"
    "misfit above 0.3: an extended, speckle-like seabed) a warning says that\n"
    "its result is unreliable.\n"
    "\n"
    "  --grid ...        scene grid (default: the nominal track's extent x range\n"
    "                    of interest +-0.35 m, 5 mm pixels); it must hold the\n"
    "                    scene's echoes and sample their band\n"
    "  --sweeps N        sweeps over the pings at most (default 8)\n"
    "  --sparsity EPS    reweighted damping of the scene, pixel i by\n"
    "                    1 / (|s_i|^2 / mean |s|^2 + EPS) (default 0.01: a\n"
    "                    scene of few strong scatterers; 0: uniform damping)\n"
    "  --surge-range M   half-width of the surge search, m (default 0.012)\n"
    "  --sway-range M    half-width of the sway search, m (default 0.0015)\n"
    "  --window N        runs longer than N pings are refined in windows of N\n"
    "                    pings, half overlapping, joined into one navigation;\n"
    "                    memory and time per ping are those of one window\n"
    "                    (default 64; 0: the whole run at once)\n"
    "  --threads N       OpenMP threads (default: all cores)\n"
    "  --checkpoint FILE  keep the refinement's state in FILE after every sweep;\n"
    "                    the same command run again after an interruption\n"
    "                    resumes from it with the same result (docs/cli.md).\n"
    "                    FILE is removed once -o is written (runs of one window)\n"
    "  -o FILE           output navigation (HDF5, with the run's truth if any)\n";

int cmd_refine(int argc, char **argv)
{
    static const struct option longopts[] = {
        {"grid", required_argument, 0, 'g'},        {"sweeps", required_argument, 0, 's'},
        {"surge-range", required_argument, 0, 'u'}, {"sway-range", required_argument, 0, 'v'},
        {"threads", required_argument, 0, 't'},     {"output", required_argument, 0, 'o'},
        {"sparsity", required_argument, 0, 'e'},    {"help", no_argument, 0, 'h'},
        {"checkpoint", required_argument, 0, 'C'},  {"window", required_argument, 0, 'w'},
        {0, 0, 0, 0}};
    sasnav_refine_opts ro;
    sasnav_refine_default_opts(&ro);
    const char *output = NULL, *checkpoint = NULL;
    long sweeps = ro.sweeps, threads = 0, window = 64;
    int opt;
    optind = 1;
    while ((opt = getopt_long(argc, argv, "o:h", longopts, NULL)) != -1) {
        switch (opt) {
        case 'g': if (cli_parse_grid(optarg, &ro.grid)) return cli_usage("refine", "--grid: %s", sasnav_last_error()); break;
        case 's':
            if (cli_parse_int(optarg, 1, SASNAV_REFINE_MAX_SWEEPS, &sweeps))
                return cli_usage("refine", "--sweeps needs 1..%d", SASNAV_REFINE_MAX_SWEEPS);
            break;
        case 'u':
            if (cli_parse_double(optarg, &ro.surge_range) || !(ro.surge_range > 0 && ro.surge_range <= 1))
                return cli_usage("refine", "--surge-range needs a half-width in (0, 1] m");
            break;
        case 'v':
            if (cli_parse_double(optarg, &ro.sway_range) || !(ro.sway_range > 0 && ro.sway_range <= 1))
                return cli_usage("refine", "--sway-range needs a half-width in (0, 1] m");
            break;
        case 'e':
            if (cli_parse_double(optarg, &ro.sparsity) || !(ro.sparsity >= 0 && ro.sparsity <= 1e6))
                return cli_usage("refine", "--sparsity needs a number in [0, 1e6]");
            break;
        case 't': if (cli_parse_int(optarg, 0, 1024, &threads)) return cli_usage("refine", "--threads needs 0..1024"); break;
        case 'w':
            if (cli_parse_int(optarg, 0, 1000000, &window) || (window > 0 && window < 3))
                return cli_usage("refine", "--window needs 0 (the whole run) or a number of pings >= 3");
            break;
        case 'o': output = optarg; break;
        case 'C': checkpoint = optarg; break;
        case 'h': fputs(help, stdout); return 0;
        default: return cli_bad_option("refine", argv, longopts);
        }
    }
    if (optind != argc - 2) return cli_usage("refine", "a run file and a navigation file are required");
    if (!output) return cli_usage("refine", "an output file is required (-o FILE)");
    if (checkpoint && cli_same_file(checkpoint, output))
        return cli_usage("refine", "--checkpoint and -o name the same file (%s)", output);
    ro.sweeps = (int)sweeps;
    ro.nthreads = (int)threads;
    const char *run_path = argv[optind], *nav_path = argv[optind + 1];
    sasnav_run *run = NULL;
    int rc = sasnav_run_open(run_path, &run); /* streamed: read a window at a time */
    if (rc) return cli_fail("refine", rc, "cannot read %s", run_path);
    int n = 0;
    sasnav_ping_pose *nav = NULL;
    rc = sasnav_nav_read(nav_path, &n, &nav, NULL);
    if (rc) {
        sasnav_run_free(run);
        return cli_fail("refine", rc, "cannot read %s", nav_path);
    }
    if (n != run->n_pings) {
        sasnav_run_free(run);
        free(nav);
        return cli_fail("refine", 0, "%s has %d pings, %s has %d", nav_path, n, run_path, run->n_pings);
    }
    int windowed = window > 0 && window < n;
    if (checkpoint && windowed) {
        sasnav_run_free(run);
        free(nav);
        return cli_usage("refine", "--checkpoint works on runs of one window: %s has %d pings, --window is %ld "
                                   "(use --window 0 to refine it whole)", run_path, n, window);
    }
    sasnav_refine_state resume;
    memset(&resume, 0, sizeof resume);
    refine_ckpt ck = {checkpoint, 0, {0}, ro.sweeps};
    cli_progress_init(&ck.progress, "refine", windowed ? "windows" : "sweeps");
    if (!windowed) {
        ro.sweep_done = save_state;
        ro.sweep_user = &ck;
    }
    if (checkpoint) {
        if (access(checkpoint, F_OK) == 0) {
            rc = sasnav_refine_state_read(checkpoint, &resume);
            if (rc) {
                sasnav_run_free(run);
                free(nav);
                return cli_fail("refine", rc, "cannot use checkpoint %s", checkpoint);
            }
            ro.resume = &resume;
            fprintf(stderr, "sasnav refine: resuming from %s (%d sweeps done before)\n", checkpoint,
                    resume.sweeps_done);
        }
    }
    sasnav_ping_pose *out = malloc(sizeof *out * n);
    sasnav_refine_report rep;
    rc = out ? sasnav_refine_windows(run, nav, windowed ? (int)window : 0, &ro, out, &rep,
                                     windowed ? window_done : NULL, &ck)
             : sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    int refined = !rc, rc_lib = rc;
    cli_progress_end(&ck.progress);
    if (!rc) rc = sasnav_nav_write(output, n, out, run->truth);
    sasnav_refine_state_free(&resume);
    if (rc) {
        sasnav_run_free(run);
        free(nav);
        free(out);
        rc = refined ? cli_fail("refine", rc, "cannot write %s", output)
                     : cli_fail("refine", rc, "refinement of %s failed", nav_path);
        if (checkpoint && !refined && ro.resume && rc_lib == SASNAV_ERR_ARG)
            fprintf(stderr, "sasnav refine: remove %s to start again\n", checkpoint);
        else if (checkpoint && !ck.failed && access(checkpoint, F_OK) == 0)
            fprintf(stderr, "sasnav refine: state kept in %s: run the same command again to resume\n", checkpoint);
        return rc;
    }
    if (checkpoint && unlink(checkpoint) && access(checkpoint, F_OK) == 0)
        fprintf(stderr, "sasnav refine: warning: cannot remove checkpoint %s\n", checkpoint);
    for (int s = 0; s < rep.sweeps; s++)
        printf("sweep %d: mean misfit %.5f -> %.5f, rms move %.3f mm\n", s + 1, rep.misfit[s], rep.misfit[s + 1],
               1e3 * rep.rms_move[s]);
    printf("common move removed: %+.3f mm along, %+.3f mm across\n", 1e3 * rep.mean_move_surge,
           1e3 * rep.mean_move_sway);
    if (run->truth) {
        double a0, b0, a1, b1;
        if (!sasnav_traj_rms_rigid(nav, run->truth, run->n_pings, &a0, &b0) &&
            !sasnav_traj_rms_rigid(out, run->truth, run->n_pings, &a1, &b1))
            printf("rms error vs the truth (best rigid fit): surge %.3f -> %.3f mm, sway %.3f -> %.3f mm\n",
                   1e3 * a0, 1e3 * a1, 1e3 * b0, 1e3 * b1);
    }
    if (rep.unreliable)
        fprintf(stderr,
                "sasnav refine: warning: the scenes explain the pings poorly (mean misfit %.3f > %.1f): the "
                "refinement needs a scene of a few strong scatterers and is unreliable on this run; "
                "the input navigation is likely better\n",
                rep.misfit[0], SASNAV_REFINE_MISFIT_MAX);
    if (windowed)
        fprintf(stderr, "sasnav refine: %d pings in windows of %ld, at most %d sweeps, %.1f s -> %s\n", n, window,
                rep.sweeps, rep.seconds, output);
    else
        fprintf(stderr, "sasnav refine: %d pings, %d sweeps, %.1f s -> %s\n", n, rep.sweeps, rep.seconds, output);
    sasnav_run_free(run);
    free(nav);
    free(out);
    return 0;
}
