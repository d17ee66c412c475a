/* sasnav tank: the tank experiment of SPEC 4 as passband WAV recordings. */
#include "cli.h"

#include <omp.h>
#include "sasnav/tank.h"

#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>

int cmd_tank(int argc, char **argv);

static const char *help =
    "usage: sasnav tank -o DIR [--seed N] [--omni] [--clutter STD] [--plate-range R]\n"
    "                  [--noise STD]\n"
    "\n"
    "Simulates the tank experiment of SPEC 4 (8 Rx of 5 cm spaced 5 cm, Tx at\n"
    "the array midpoint, 32 pings at 2.5 cm steps with stepping errors, a surge\n"
    "jump between pings 11 and 12 and a constant yaw of 1.27e-2 rad; 4 point\n"
    "reflectors and weak clutter on a plate 1.5 m away; LFM 90-120 kHz, 3 ms,\n"
    "c = 1480 m/s) and writes what the experiment records:\n"
    "  DIR/ping_000.wav ..  8-channel 32-bit float WAV at 1 MHz (real passband,\n"
    "                       sample 0 at transmission)\n"
    "  DIR/chirp.wav        the transmitted chirp (mono)\n"
    "  DIR/positions.csv    ping,x,y,yaw: nominal plotter positions\n"
    "  DIR/truth.csv        ping,x,y,yaw: true poses\n"
    "  DIR/array.csv        rx_spacing,element_length,directivity (read by ingest)\n"
    "Turn it into a run with\n"
    "  sasnav ingest --wav DIR -o run.h5\n"
    "\n"
    "  --seed N    seed of the stepping errors, clutter and noise (default 1)\n"
    "  --omni      omnidirectional elements (default: the 5 cm elements'\n"
    "              line-aperture patterns at 105 kHz)\n"
    "  --clutter STD      amplitude std of the plate's 200 point scatterers\n"
    "                     (its texture; default 0.02 against reflectors of 1)\n"
    "  --plate-range R    range of the plate centre (m, default 1.5); the\n"
    "                     reflectors keep their place on the plate\n"
    "  --noise STD        white noise std per passband sample (default 1e-3)\n"
    "  --threads N OpenMP threads (default: all cores)\n"
    "  -o DIR      output directory (created if missing)\n";

int cmd_tank(int argc, char **argv)
{
    static const struct option longopts[] = {{"seed", required_argument, 0, 's'},
                                              {"omni", no_argument, 0, 'O'},
                                              {"clutter", required_argument, 0, 'c'},
                                              {"plate-range", required_argument, 0, 'r'},
                                              {"noise", required_argument, 0, 'n'},
                                              {"output", required_argument, 0, 'o'},
                                              {"help", no_argument, 0, 'h'},
                                              {"threads", required_argument, 0, 'N'},
                                              {0, 0, 0, 0}};
    const char *output = NULL;
    sasnav_tank_params p;
    sasnav_tank_default(&p);
    long v;
    double d;
    int opt;
    optind = 1;
    while ((opt = getopt_long(argc, argv, "s:o:h", longopts, NULL)) != -1) {
        switch (opt) {
        case 's':
            if (cli_parse_int(optarg, 0, 0x7fffffffL, &v))
                return cli_usage("tank", "--seed needs a non-negative integer");
            p.seed = (uint64_t)v;
            break;
        case 'O': p.directivity = 0; break;
        case 'c':
            if (cli_parse_double(optarg, &d) || !(d >= 0))
                return cli_usage("tank", "--clutter needs a non-negative amplitude std");
            p.clutter_std = d;
            break;
        case 'r':
            if (cli_parse_double(optarg, &d) || !(d > p.plate_radius) || !(d < p.range_max - p.plate_radius))
                return cli_usage("tank", "--plate-range needs a range keeping the plate in %g..%g m",
                                p.plate_radius, p.range_max);
            for (int i = 0; i < p.n_reflectors; i++) p.refl_y[i] += d - p.plate_y;
            p.plate_y = d;
            break;
        case 'n':
            if (cli_parse_double(optarg, &d) || !(d >= 0))
                return cli_usage("tank", "--noise needs a non-negative std");
            p.noise_std = d;
            break;
        case 'o': output = optarg; break;
        case 'N': {
            long threads;
            if (cli_parse_int(optarg, 0, 1024, &threads))
                return cli_usage("tank", "--threads needs an integer 0..1024");
            if (threads > 0) omp_set_num_threads((int)threads);
            break;
        }
        case 'h': fputs(help, stdout); return 0;
        default: return cli_bad_option("tank", argv, longopts);
        }
    }
    if (optind < argc) return cli_usage("tank", "unexpected argument '%s'", argv[optind]);
    if (!output) return cli_usage("tank", "an output directory is required (-o DIR)");
    int rc = sasnav_tank_write_dir(&p, output);
    if (rc) return cli_fail("tank", rc, "cannot write the recording to %s", output);
    fprintf(stderr, "sasnav tank: %d pings x %d channels x %d samples at %g kHz -> %s\n",
            p.n_pings, p.n_rx, sasnav_tank_n_samples(&p), p.sample_rate / 1e3, output);
    return 0;
}
