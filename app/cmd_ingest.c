/* sasnav ingest: real recordings -> a run file (baseband, pulse-compressed). */
#include "cli.h"

#include <omp.h>
#include "sasnav/airsas.h"
#include "sasnav/io.h"

#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *help =
    "usage: sasnav ingest --airsas DIR [--background DIR] [options] -o run.h5\n"
    "\n"
    "Reads an AirSAS circular SAS recording (Flight-*.csv, Coordinates.csv,\n"
    "SysParams.csv, WaveformParams.csv), subtracts the empty-scene recording,\n"
    "removes the mean room response, pulse-compresses with the recorded LFM,\n"
    "demodulates to baseband and writes a run (docs/format.md) with the\n"
    "nominal circular navigation; image it with\n"
    "  sasnav image run.h5 --grid -0.3,0.3,400,-0.3,0.3,400 -o img.h5 --png img.png\n"
    "\n"
    "  --airsas DIR        recording directory\n"
    "  --wav DIR           tank-style recordings: ping_NNN.wav (multichannel,\n"
    "                      passband), chirp.wav, positions.csv [, truth.csv,\n"
    "                      array.csv] (as written by 'sasnav simulate --preset\n"
    "                      tank'); decimation default 33\n"
    "  --range R           (--wav) range of interest: centre of the estimation\n"
    "                      and image grids (m, default 1.5, the tank's plate)\n"
    "  --background DIR    empty-scene recording, subtracted ping by ping\n"
    "  --mic N             microphone (column) 1 or 2, or both: one ping of two\n"
    "                      channels, each at its microphone's height (default 1)\n"
    "  --first N           first ping, 0-based (default 0)\n"
    "  --stride K          keep every K-th ping (default 1)\n"
    "  --pings N           keep at most N pings (default: all)\n"
    "  --decimation D      baseband decimation of the records (default 4: 25 kHz)\n"
    "  --matched           plain matched filter instead of compression to the\n"
    "                      model pulse (flat spectrum over the band)\n"
    "  --taper T           pulse spectrum taper: none, hann, hamming (default none)\n"
    "  --f0 HZ             carrier (default: centre of the chirp sweep)\n"
    "  --bandwidth HZ      band (default: the chirp sweep width)\n"
    "  --no-room           keep the mean room response\n"
    "  --radius M          sensor circle radius (default 0.85)\n"
    "  --clip-run N        refuse records with N equal samples at their extreme\n"
    "                      value (default 3; 0: no check)\n"
    "  --threads N         OpenMP threads (default: all cores)\n"
    "  -o FILE             output run file (HDF5)\n";

static int parse_taper(const char *s, sasnav_taper *t)
{
    if (!strcmp(s, "none")) *t = SASNAV_TAPER_NONE;
    else if (!strcmp(s, "hann")) *t = SASNAV_TAPER_HANN;
    else if (!strcmp(s, "hamming")) *t = SASNAV_TAPER_HAMMING;
    else return -1;
    return 0;
}

/* The streamed run's destination: a run writer opened on the header. */
typedef struct {
    const char *path;
    sasnav_run_writer *writer;
    sasnav_run header; /* a copy, its nav owned here */
    sasnav_ping_pose *nav;
    int write_failed;
} ingest_out;

static int out_begin(void *ctx, const sasnav_run *hdr)
{
    ingest_out *w = ctx;
    w->header = *hdr;
    w->nav = malloc(sizeof *w->nav * (size_t)hdr->n_pings);
    if (!w->nav) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    memcpy(w->nav, hdr->nav, sizeof *w->nav * (size_t)hdr->n_pings);
    w->header.nav = w->nav;
    int rc = sasnav_run_writer_open(w->path, &w->header, &w->writer);
    if (rc) w->write_failed = 1;
    return rc;
}

static int out_ping(void *ctx, int k, const sasnav_cfloat *samples)
{
    ingest_out *w = ctx;
    int rc = sasnav_run_writer_put(w->writer, k, samples);
    if (rc) w->write_failed = 1;
    return rc;
}

int cmd_ingest(int argc, char **argv)
{
    static const struct option longopts[] = {
        {"airsas", required_argument, 0, 'a'},     {"background", required_argument, 0, 'b'},
        {"mic", required_argument, 0, 'm'},        {"first", required_argument, 0, 'F'},
        {"stride", required_argument, 0, 's'},     {"pings", required_argument, 0, 'n'},
        {"decimation", required_argument, 0, 'D'}, {"matched", no_argument, 0, 'M'},
        {"taper", required_argument, 0, 'T'},      {"f0", required_argument, 0, 'f'},
        {"bandwidth", required_argument, 0, 'B'},  {"no-room", no_argument, 0, 'R'},
        {"radius", required_argument, 0, 'r'},     {"clip-run", required_argument, 0, 'c'},
        {"output", required_argument, 0, 'o'},     {"help", no_argument, 0, 'h'},
        {"threads", required_argument, 0, 'N'},
        {"wav", required_argument, 0, 'w'},        {"range", required_argument, 0, 'G'},
        {0, 0, 0, 0}};
    const char *dir = NULL, *bgdir = NULL, *output = NULL, *wavdir = NULL;
    int decimation_given = 0;
    double range = 0.0;
    sasnav_airsas_opts o;
    sasnav_airsas_default_opts(&o);
    long v;
    double d;
    int opt, n_airsas = 0;
    optind = 1;
    while ((opt = getopt_long(argc, argv, "o:h", longopts, NULL)) != -1) {
        /* options of the AirSAS ingest alone (refused with --wav, which
         * would ignore them) */
        if (strchr("abmFsnMTfBRrc", opt)) n_airsas++;
        switch (opt) {
        case 'a': dir = optarg; break;
        case 'b': bgdir = optarg; break;
        case 'm':
            if (!strcmp(optarg, "both"))
                v = 0;
            else if (cli_parse_int(optarg, 1, 2, &v))
                return cli_usage("ingest", "--mic needs 1, 2 or both");
            o.microphone = (int)v;
            break;
        case 'F':
            if (cli_parse_int(optarg, 0, 1000000, &v))
                return cli_usage("ingest", "--first needs a ping index >= 0");
            o.first_ping = (int)v;
            break;
        case 's':
            if (cli_parse_int(optarg, 1, 1000000, &v))
                return cli_usage("ingest", "--stride needs an integer >= 1");
            o.ping_stride = (int)v;
            break;
        case 'n':
            if (cli_parse_int(optarg, 1, 1000000, &v))
                return cli_usage("ingest", "--pings needs an integer >= 1");
            o.max_pings = (int)v;
            break;
        case 'D':
            if (cli_parse_int(optarg, 1, 1000000, &v))
                return cli_usage("ingest", "--decimation needs an integer >= 1");
            o.decimation = (int)v;
            decimation_given = 1;
            break;
        case 'w': wavdir = optarg; break;
        case 'G':
            if (cli_parse_double(optarg, &d) || !(d > 0))
                return cli_usage("ingest", "--range needs a range > 0 (m)");
            range = d;
            break;
        case 'M': o.compression = SASNAV_COMPRESS_MATCHED; break;
        case 'T':
            if (parse_taper(optarg, &o.taper))
                return cli_usage("ingest", "--taper needs none, hann or hamming");
            break;
        case 'f':
            if (cli_parse_double(optarg, &d) || !(d > 0))
                return cli_usage("ingest", "--f0 needs a frequency > 0 (Hz)");
            o.f0 = d;
            break;
        case 'B':
            if (cli_parse_double(optarg, &d) || !(d > 0))
                return cli_usage("ingest", "--bandwidth needs a frequency > 0 (Hz)");
            o.bandwidth = d;
            break;
        case 'R': o.remove_room = 0; break;
        case 'r':
            if (cli_parse_double(optarg, &d) || !(d > 0))
                return cli_usage("ingest", "--radius needs a length > 0 (m)");
            o.radius = d;
            break;
        case 'c':
            if (cli_parse_int(optarg, 0, 1000000, &v) || v == 1)
                return cli_usage("ingest", "--clip-run needs 0 (off) or an integer >= 2");
            o.clip_run = (int)v;
            break;
        case 'o': output = optarg; break;
        case 'N': {
            long threads;
            if (cli_parse_int(optarg, 0, 1024, &threads))
                return cli_usage("ingest", "--threads needs an integer 0..1024");
            if (threads > 0) omp_set_num_threads((int)threads);
            break;
        }
        case 'h': fputs(help, stdout); return 0;
        default: return cli_bad_option("ingest", argv, longopts);
        }
    }
    if (optind != argc)
        return cli_usage("ingest", "unexpected argument '%s' (inputs are given with --airsas)",
                        argv[optind]);
    if (wavdir) {
        if (n_airsas)
            return cli_usage("ingest", "--wav takes only --range, --decimation, --threads and -o (the "
                                       "other options are the AirSAS ingest's)");
        if (!output) return cli_usage("ingest", "an output file is required (-o run.h5)");
        return cmd_ingest_wav(wavdir, decimation_given ? o.decimation : 0, range, output);
    }
    if (!dir) return cli_usage("ingest", "an input is required (--airsas DIR or --wav DIR)");
    if (!output) return cli_usage("ingest", "an output file is required (-o run.h5)");

    /* Streamed: the flights stay in their files and are read one at a
     * time (twice: the room response is the mean of all flights), the run
     * written ping by ping (docs/ingest.md). */
    sasnav_airsas *rec = NULL, *bg = NULL;
    int rc = sasnav_airsas_open(dir, &rec);
    if (rc) return cli_fail("ingest", rc, "cannot read the AirSAS recording %s", dir);
    if (bgdir && (rc = sasnav_airsas_open(bgdir, &bg))) {
        sasnav_airsas_free(rec);
        return cli_fail("ingest", rc, "cannot read the background recording %s", bgdir);
    }
    ingest_out w;
    memset(&w, 0, sizeof w);
    w.path = output;
    sasnav_airsas_sink sink = {out_begin, out_ping, &w};
    rc = sasnav_airsas_stream(rec, bg, &o, &sink);
    int n_recorded = rec->n_pings;
    sasnav_airsas_free(rec);
    sasnav_airsas_free(bg);
    if (!rc && w.writer) {
        rc = sasnav_run_writer_finish(w.writer, &w.header);
        w.writer = NULL;
        if (rc) w.write_failed = 1;
    }
    if (w.writer) sasnav_run_writer_abort(w.writer);
    if (rc) {
        free(w.nav);
        return w.write_failed ? cli_fail("ingest", rc, "cannot write %s", output)
                              : cli_fail("ingest", rc, "cannot process %s", dir);
    }
    const sasnav_run *run = &w.header;
    char rx_heights[64];
    if (run->array.per_channel && run->array.n_rx == 2)
        snprintf(rx_heights, sizeof rx_heights, "Rx %.4f and %.4f", run->array.size[0].rx_height,
                 run->array.size[1].rx_height);
    else
        snprintf(rx_heights, sizeof rx_heights, "Rx %.4f", run->array.rx_height);
    fprintf(stderr,
            "sasnav ingest: %d of %d pings x %d channel(s) x %d samples (fs %g kHz, f0 %g kHz, "
            "B %g kHz, c %.2f m/s, t0 %.4f ms, heights Tx %.4f %s m) -> %s\n",
            run->n_pings, n_recorded, run->array.n_rx, run->win.n_samples, run->sys.sample_rate / 1e3,
            run->sys.f0 / 1e3, run->sys.bandwidth / 1e3, run->sys.sound_speed, run->win.t0 * 1e3,
            run->array.tx_height, rx_heights, output);
    free(w.nav);
    return 0;
}
