/* sasnav ingest --wav DIR: a tank-style WAV recording directory -> a run. */
#include "cli.h"
#include "sasnav/io.h"
#include "sasnav/tank.h"

#include <stdio.h>
#include <unistd.h>

int cmd_ingest_wav(const char *dir, int decimation, double range, const char *output);

static int truth_csv_exists(const char *dir)
{
    char path[4096];
    return snprintf(path, sizeof path, "%s/truth.csv", dir) < (int)sizeof path && access(path, F_OK) == 0;
}

/* Reads DIR (ping_NNN.wav, chirp.wav, positions.csv, truth.csv if present;
 * see include/sasnav/tank.h), runs the ingest chain (f0 105 kHz, B 30 kHz,
 * decimation `decimation`, or 33 when < 1; range of interest `range`, or
 * 1.5 m when not > 0) and writes the run to `output`.
 * Returns 0 or 1 (message printed), like the other commands. */
int cmd_ingest_wav(const char *dir, int decimation, double range, const char *output)
{
    if (!dir) return cli_usage("ingest", "an input directory is required (--wav DIR)");
    if (!output) return cli_usage("ingest", "an output file is required (-o run.h5)");
    sasnav_tank_read_opts o;
    sasnav_tank_default_read_opts(&o);
    if (decimation >= 1) o.decimation = decimation;
    if (range > 0) o.range_of_interest = range;
    sasnav_run info;
    int rc = sasnav_tank_ingest_dir(dir, &o, output, &info); /* ping by ping */
    if (rc) return cli_fail("ingest", rc, "cannot ingest the WAV recording %s", dir);
    fprintf(stderr,
            "sasnav ingest: %d pings x %d channels x %d samples (fs %g kHz, f0 %g kHz, "
            "B %g kHz, c %.1f m/s, truth %s) -> %s\n",
            info.n_pings, info.array.n_rx, info.win.n_samples, info.sys.sample_rate / 1e3,
            info.sys.f0 / 1e3, info.sys.bandwidth / 1e3, info.sys.sound_speed,
            truth_csv_exists(dir) ? "yes" : "no", output);
    return 0;
}
