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
    "Run 'sasnav COMMAND --help' for the options of a command.\n";

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

int main(int argc, char **argv)
{
    cli_install_signal_handlers();
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
        if (!strcmp(argv[1], commands[i].name)) return commands[i].run(argc - 1, argv + 1);
    fprintf(stderr, "sasnav: unknown command '%s'\n\n%s", argv[1], usage);
    return 2;
}
