/* fuzz_run_h5_raw: the input bytes are the file. sasnav_run_read and
 * sasnav_nav_read on it. This mostly exercises HDF5's own parser (which has
 * known faults in 1.10.8 on files without checksums: docs/fuzzing.md);
 * crashes whose top frames are in libhdf5 are HDF5's. */
#include "fuzz_common.h"
#include "sasnav/io.h"

#include <hdf5.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static int init;
    if (!init) {
        init = 1;
        H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    }
    const char *path = fz_path("raw.h5");
    fz_write(path, data, size);
    static const int allowed[] = {SASNAV_ERR_FORMAT, SASNAV_ERR_IO, SASNAV_ERR_NOMEM, 0};
    sasnav_run *run = NULL;
    int rc = sasnav_run_read(path, &run);
    fz_check_rc("sasnav_run_read", rc, allowed);
    if (rc == SASNAV_OK && sasnav_run_check(run) != SASNAV_OK) abort();
    sasnav_run_free(run);
    int n = 0;
    sasnav_ping_pose *nav = NULL, *truth = NULL;
    rc = sasnav_nav_read(path, &n, &nav, &truth);
    fz_check_rc("sasnav_nav_read", rc, allowed);
    free(nav);
    free(truth);
    return 0;
}
