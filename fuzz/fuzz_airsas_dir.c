/* fuzz_airsas_dir: sasnav_airsas_read on an AirSAS directory unpacked from
 * the input (container: fuzz_common.h; file indices below), then, for a
 * recording it accepts, sasnav_airsas_to_run with the default options (what
 * `sasnav ingest` does). Contract: read: SASNAV_OK or SASNAV_ERR_IO /
 * FORMAT / NOMEM; to_run: SASNAV_OK with a valid run or SASNAV_ERR_ARG /
 * NOMEM / FFT; always with a message. */
#include "fuzz_common.h"
#include "sasnav/airsas.h"

static const char *const names[] = {
    "Coordinates.csv",    /* 0 */
    "SysParams.csv",      /* 1 */
    "WaveformParams.csv", /* 2 */
    "Flight-000001.csv",  /* 3 */
    "Flight-000002.csv",  /* 4 */
    "Flight-000003.csv",  /* 5 */
};

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_unpack(data, size, names, (int)(sizeof names / sizeof names[0]));
    sasnav_airsas *rec = NULL;
    int rc = sasnav_airsas_read(fz_scratch(), &rec);
    static const int allowed[] = {SASNAV_ERR_IO, SASNAV_ERR_FORMAT, SASNAV_ERR_NOMEM, 0};
    fz_check_rc("sasnav_airsas_read", rc, allowed);
    if (rc != SASNAV_OK) {
        if (rec) abort();
        return 0;
    }
    if (!rec || rec->n_pings < 1 || rec->n_samples < 1 || rec->n_channels < 1 || !rec->samples) abort();
    sasnav_airsas_opts o;
    sasnav_airsas_default_opts(&o);
    sasnav_run *run = NULL;
    rc = sasnav_airsas_to_run(rec, NULL, &o, &run);
    static const int allowed_run[] = {SASNAV_ERR_ARG, SASNAV_ERR_NOMEM, SASNAV_ERR_FFT, 0};
    fz_check_rc("sasnav_airsas_to_run", rc, allowed_run);
    if (rc == SASNAV_OK && (!run || sasnav_run_check(run))) {
        fprintf(stderr, "airsas run invalid: %s\n", sasnav_last_error());
        abort();
    }
    sasnav_run_free(run);
    sasnav_airsas_free(rec);
    return 0;
}
