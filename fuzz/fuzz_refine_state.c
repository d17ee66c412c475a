/* fuzz_refine_state: the input bytes are a refinement state file
 * (`sasnav refine --checkpoint`, HDF5 format "sasnav-refine-state"):
 * sasnav_refine_state_read. Raw bytes, like fuzz_run_h5_raw: mostly HDF5's
 * own parser. Contract: a documented code; an accepted state is whole,
 * finite, with positive weights and damping. */
#include "fuzz_common.h"
#include "sasnav/checkpoint.h"

#include <complex.h>
#include <hdf5.h>
#include <math.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static int init;
    if (!init) {
        init = 1;
        H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    }
    const char *path = fz_path("state.h5");
    fz_write(path, data, size);
    static const int allowed[] = {SASNAV_ERR_FORMAT, SASNAV_ERR_IO, SASNAV_ERR_NOMEM, 0};
    sasnav_refine_state st;
    int rc = sasnav_refine_state_read(path, &st);
    fz_check_rc("sasnav_refine_state_read", rc, allowed);
    if (rc == SASNAV_OK) {
        if (st.n_pings < 3 || st.n_pixels < 1 || !st.poses || !st.move_u || !st.move_v || !st.scene ||
            !st.weights || !(st.mu > 0) || st.report.sweeps != st.sweeps_done)
            abort();
        for (int i = 0; i < st.n_pixels; i++)
            if (!(st.weights[i] > 0) || !isfinite(crealf(st.scene[i])) || !isfinite(cimagf(st.scene[i]))) abort();
    } else if (st.poses || st.scene || st.weights) {
        abort();
    }
    sasnav_refine_state_free(&st);
    return 0;
}
