/* sasnav ingest --wav DIR: a tank-style WAV recording directory -> a run. */
#include "cli.h"
#include "sasnav/io.h"
#include "sasnav/tank.h"

#include <stdio.h>

int cmd_ingest_wav(const char *dir, int decimation, double range, const char *output);

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
    sasnav_run *run = NULL;
    int rc = sasnav_tank_read_dir(dir, &o, &run);
    if (rc) return cli_fail("ingest", rc, "cannot ingest the WAV recording %s", dir);
    rc = sasnav_run_write(output, run);
    if (rc) {
        sasnav_run_free(run);
        return cli_fail("ingest", rc, "cannot write %s", output);
    }
    fprintf(stderr,
            "sasnav ingest: %d pings x %d channels x %d samples (fs %g kHz, f0 %g kHz, "
            "B %g kHz, c %.1f m/s, truth %s) -> %s\n",
            run->n_pings, run->array.n_rx, run->win.n_samples, run->sys.sample_rate / 1e3,
            run->sys.f0 / 1e3, run->sys.bandwidth / 1e3, run->sys.sound_speed,
            run->truth ? "yes" : "no", output);
    sasnav_run_free(run);
    return 0;
}
