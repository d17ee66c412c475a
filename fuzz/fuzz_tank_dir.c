/* fuzz_tank_dir: sasnav_tank_read_dir (default options) on a recording
 * directory unpacked from the input (container: fuzz_common.h; file
 * indices below). Contract: SASNAV_OK with a run that passes
 * sasnav_run_check, or SASNAV_ERR_IO / FORMAT / ARG / NOMEM / FFT with a
 * message. */
#include "fuzz_common.h"
#include "sasnav/tank.h"

static const char *const names[] = {
    "positions.csv", /* 0 */
    "truth.csv",     /* 1 */
    "chirp.wav",     /* 2 */
    "array.csv",     /* 3 */
    "ping_000.wav",  /* 4 */
    "ping_001.wav",  /* 5 */
    "ping_002.wav",  /* 6 */
};

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_unpack(data, size, names, (int)(sizeof names / sizeof names[0]));
    sasnav_tank_read_opts o;
    sasnav_tank_default_read_opts(&o);
    sasnav_run *run = NULL;
    int rc = sasnav_tank_read_dir(fz_scratch(), &o, &run);
    static const int allowed[] = {SASNAV_ERR_IO, SASNAV_ERR_FORMAT, SASNAV_ERR_ARG,
                                  SASNAV_ERR_NOMEM, SASNAV_ERR_FFT, 0};
    fz_check_rc("sasnav_tank_read_dir", rc, allowed);
    if (rc == SASNAV_OK && (!run || sasnav_run_check(run))) {
        fprintf(stderr, "tank read OK but the run is invalid: %s\n", sasnav_last_error());
        abort();
    }
    if (rc != SASNAV_OK && run) abort();
    sasnav_run_free(run);
    return 0;
}
