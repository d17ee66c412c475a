/* fuzz_run_h5: sasnav_run_read on structure-aware generated run files
 * (h5gen.h: the input drives the writing of a run file with fuzzed types,
 * shapes, values and members; /channels, /array/sizes and format
 * version 2 on option bits). Contract: SASNAV_OK with a run that passes
 * sasnav_run_check, or SASNAV_ERR_FORMAT / IO / NOMEM with a message. */
#include "fuzz_common.h"
#include "h5gen.h"
#include "sasnav/io.h"

static double fill_raw(size_t i, const hsize_t *dims, int rank) { return sin(0.37 * (double)i); }
static double fill_rx(size_t i, const hsize_t *dims, int rank)
{
    return ((double)i - 0.5 * ((double)dims[0] - 1)) * 0.05;
}
static double fill_nav(size_t i, const hsize_t *dims, int rank)
{
    return i % 3 == 0 ? -1.0 + 0.2 * (double)(i / 3) : 0.0;
}
static double fill_nav_array(size_t i, const hsize_t *dims, int rank)
{
    return i % 3 == 0 ? -0.9 + 0.2 * (double)(i / 3) : 0.0;
}
static double fill_time(size_t i, const hsize_t *dims, int rank) { return 0.1 * (double)i; }
static double fill_zero(size_t i, const hsize_t *dims, int rank) { return 0.0; }
static double fill_sigma(size_t i, const hsize_t *dims, int rank) { return 1e-3; }
static double fill_size(size_t i, const hsize_t *dims, int rank) { return 0.01 * (double)(i % 4 + 1); }
static double fill_vel(size_t i, const hsize_t *dims, int rank) { return i % 2 == 0 ? 2.0 : 0.0; }

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    h5g_init();
    h5g g = {data, size};
    const char *path = fz_path("run.h5");
    hid_t f = h5g_create(&g, path);
    h5g_root(&g, f, "sasnav-run");
    hsize_t np = 1 + (h5g_u8(&g) + 2) % 8, nrx = 1 + (h5g_u8(&g) + 3) % 6, ns = 1 + (h5g_u8(&g) + 40) % 64;
    hsize_t d3[3] = {np, nrx, ns}, d1[1] = {nrx}, dn[2] = {np, 3}, dp[1] = {np}, dv[2] = {np, 2};
    h5g_dataset(&g, f, "/raw", D_COMPLEX, 3, d3, fill_raw);
    h5g_group(f, "/system");
    static const char *const sys[] = {"sound_speed", "f0", "bandwidth", "sample_rate", "taper",
                                      "attenuation", "beam_pattern", "t0", "ping_spacing", "speed",
                                      "tx_lag", "range_of_interest"};
    static const double sysv[] = {1500, 300000, 30000, 60000, 0, 0, 1, 0.0122667, 0.2, 2, 0.1, 10};
    hid_t s = H5Gopen2(f, "/system", H5P_DEFAULT);
    for (int k = 0; k < 12; k++)
        if (s >= 0) h5g_attr(&g, s, sys[k], (k >= 4 && k <= 6) ? A_INT : A_DOUBLE, sysv[k], NULL);
    if (s >= 0) H5Gclose(s);
    h5g_group(f, "/array");
    h5g_dataset(&g, f, "/array/rx_u", D_REAL, 1, d1, fill_rx);
    hid_t a = H5Gopen2(f, "/array", H5P_DEFAULT);
    static const char *const arr[] = {"rx_length", "tx_length", "rx_height", "tx_height"};
    static const double arrv[] = {0.05, 0.05, 0, 0};
    for (int k = 0; k < 4; k++)
        if (a >= 0) h5g_attr(&g, a, arr[k], A_DOUBLE, arrv[k], NULL);
    if (a >= 0) H5Gclose(a);
    h5g_group(f, "/nav");
    h5g_dataset(&g, f, "/nav/tx", D_REAL, 2, dn, fill_nav);
    h5g_dataset(&g, f, "/nav/array", D_REAL, 2, dn, fill_nav_array);
    unsigned opt = h5g_u8(&g);
    if (opt & 1) {
        h5g_group(f, "/truth");
        h5g_dataset(&g, f, "/truth/tx", D_REAL, 2, dn, fill_nav);
        h5g_dataset(&g, f, "/truth/array", D_REAL, 2, dn, fill_nav_array);
    }
    if (opt & 2) {
        h5g_group(f, "/aiding");
        h5g_dataset(&g, f, "/aiding/time", D_REAL, 1, dp, fill_time);
        if (opt & 4) {
            h5g_dataset(&g, f, "/aiding/yaw_rate", D_REAL, 1, dp, fill_zero);
            h5g_dataset(&g, f, "/aiding/yaw_rate_sigma", D_REAL, 1, dp, fill_sigma);
        }
        if (opt & 8) {
            h5g_dataset(&g, f, "/aiding/velocity", D_REAL, 2, dv, fill_vel);
            h5g_dataset(&g, f, "/aiding/velocity_sigma", D_REAL, 2, dv, fill_sigma);
        }
    }
    if (opt & 48) { /* format version 2: per-channel offsets and / or sizes */
        H5Adelete(f, "format_version");
        h5g_attr(&g, f, "format_version", A_INT, 2, NULL);
    }
    if (opt & 16) {
        hsize_t dc[2] = {nrx, 3};
        h5g_group(f, "/channels");
        h5g_dataset(&g, f, "/channels/tx", D_REAL, 2, dc, fill_zero);
        h5g_dataset(&g, f, "/channels/array", D_REAL, 2, dc, fill_zero);
    }
    if (opt & 32) {
        hsize_t ds[2] = {nrx, 4};
        h5g_dataset(&g, f, "/array/sizes", D_REAL, 2, ds, fill_size);
    }
    h5g_extras(&g, f);
    H5Fclose(f);

    sasnav_run *run = NULL;
    int rc = sasnav_run_read(path, &run);
    static const int allowed[] = {SASNAV_ERR_FORMAT, SASNAV_ERR_IO, SASNAV_ERR_NOMEM, 0};
    fz_check_rc("sasnav_run_read", rc, allowed);
    if (rc == SASNAV_OK) {
        if (!run || sasnav_run_check(run) != SASNAV_OK) {
            fprintf(stderr, "sasnav_run_read: OK but the run is invalid: %s\n", sasnav_last_error());
            abort();
        }
    } else if (run) {
        fprintf(stderr, "sasnav_run_read: error but *run set\n");
        abort();
    }
    sasnav_run_free(run);
    return 0;
}
