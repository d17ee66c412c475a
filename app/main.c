/* sasnav: synthetic aperture sonar micronavigation and imaging, command line. */
#include "cli.h"
#include "sasnav/version.h"

#include <stdio.h>
#include <string.h>

static const char *usage =
    "usage: sasnav COMMAND [options]\n"
    "\n"
    "Synthetic aperture sonar micronavigation (Caporale & Petillot subspace\n"
    "intersection) and imaging.\n"
    "\n"
    "commands:\n"
    "  simulate   simulate a run (presets paper-pair, paper-trajectory, point)\n"
    "  image      backproject a run into an image (HDF5 and PNG)\n"
    "  pair       estimate the motion error between two pings\n"
    "  cuts       error-function cuts and maps around a point (CSV + PNG)\n"
    "  ingest     real recordings (AirSAS, WAV) to a run: pulse compression, baseband\n"
    "  tank       simulate the paper's tank experiment as passband WAV recordings\n"
    "  navigate   estimate the trajectory of a whole run (subspace or DPCA)\n"
    "  refine     refine a navigation with all pings together (data-domain fit)\n"
    "  demo       paper-trajectory end to end: navigation, images, report\n"
    "  validate   the tank experiment's validation (K sub-sampled runs, SISO/SIMO)\n"
    "\n"
    "options:\n"
    "  --help     this text\n"
    "  --version  the version of sasnav\n"
    "\n"
    "Run 'sasnav COMMAND --help' for the options of a command. Every command\n"
    "that computes takes --threads N. Exit status: 0 success, 1 a failure\n"
    "(missing or corrupt input, a computation or a write that failed), 2 a\n"
    "usage error (unknown or malformed option, missing argument).\n";

typedef struct {
    const char *name;
    int (*run)(int, char **);
} command;

static const command commands[] = {
    {"simulate", cmd_simulate},
    {"image", cmd_image},
    {"pair", cmd_pair},
    {"cuts", cmd_cuts},
    {"ingest", cmd_ingest},
    {"navigate", cmd_navigate},
    {"refine", cmd_refine},
    {"demo", cmd_demo},
    {"tank", cmd_tank},
    {"validate", cmd_validate},
};

/* Commands that split their work over the ranks of an MPI job. */
static int runs_distributed(const char *name)
{
    return !strcmp(name, "navigate") || !strcmp(name, "image") || !strcmp(name, "simulate");
}

static int run_command(int argc, char **argv);

int main(int argc, char **argv)
{
    if (cli_mpi_init(&argc, &argv)) return CLI_FAILURE;
    int rc = run_command(argc, argv);
    cli_mpi_finalize();
    return rc;
}

static int run_command(int argc, char **argv)
{
    cli_install_signal_handlers();
    opterr = 0; /* the commands report bad options themselves (cli_bad_option) */
    if (argc < 2) {
        fputs(usage, stderr);
        return 2;
    }
    if (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h") || !strcmp(argv[1], "help")) {
        fputs(usage, stdout);
        return 0;
    }
    if (!strcmp(argv[1], "--version")) {
        printf("sasnav %s\n", sasnav_version());
        return 0;
    }
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
        if (!strcmp(argv[1], commands[i].name)) {
            if (cli_mpi_size() > 1 && !runs_distributed(argv[1]))
                return cli_usage(argv[1], "runs as one process: of the commands, simulate, navigate and "
                                          "image split their work over the %d processes of mpirun",
                                 cli_mpi_size());
            return commands[i].run(argc - 1, argv + 1);
        }
    const char *names[sizeof commands / sizeof commands[0]];
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++) names[i] = commands[i].name;
    const char *near = cli_nearest(argv[1], names, (int)(sizeof names / sizeof names[0]));
    if (near)
        fprintf(stderr, "sasnav: unknown command '%s' (did you mean '%s'?)\n", argv[1], near);
    else
        fprintf(stderr, "sasnav: unknown command '%s'\n", argv[1]);
    fputs("run 'sasnav --help' for the commands\n", stderr);
    return CLI_USAGE;
}
