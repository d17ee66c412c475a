/* fuzz_nav_h5: sasnav_nav_read and sasnav_nav_read_sigma on
 * structure-aware generated navigation files (h5gen.h). Contract: SASNAV_OK
 * with n >= 1 finite poses (and standard deviations finite and >= 0, or
 * none), or SASNAV_ERR_FORMAT / IO / NOMEM with a message and nothing
 * allocated. */
#include "fuzz_common.h"
#include "h5gen.h"
#include "sasnav/io.h"

static double fill_nav(size_t i, const hsize_t *dims, int rank)
{
    return i % 3 == 0 ? -1.0 + 0.2 * (double)(i / 3) : 0.0;
}
static double fill_nav_array(size_t i, const hsize_t *dims, int rank)
{
    return i % 3 == 0 ? -0.9 + 0.2 * (double)(i / 3) : (i % 3 == 2 ? 0.01 : 0.0);
}
static double fill_sigma(size_t i, const hsize_t *dims, int rank) { return 1e-4 * (double)(i % 7); }

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    h5g_init();
    h5g g = {data, size};
    const char *path = fz_path("nav.h5");
    hid_t f = h5g_create(&g, path);
    h5g_root(&g, f, h5g_u8(&g) & 1 ? "sasnav-run" : "sasnav-nav");
    hsize_t np = 1 + (h5g_u8(&g) + 4) % 16, dn[2] = {np, 3};
    h5g_group(f, "/nav");
    h5g_dataset(&g, f, "/nav/tx", D_REAL, 2, dn, fill_nav);
    h5g_dataset(&g, f, "/nav/array", D_REAL, 2, dn, fill_nav_array);
    unsigned opt = h5g_u8(&g);
    if (opt & 1) {
        h5g_group(f, "/truth");
        h5g_dataset(&g, f, "/truth/tx", D_REAL, 2, dn, fill_nav);
        h5g_dataset(&g, f, "/truth/array", D_REAL, 2, dn, fill_nav_array);
    }
    if (opt & 4) h5g_dataset(&g, f, "/nav_sigma", D_REAL, 2, dn, fill_sigma);
    h5g_extras(&g, f);
    H5Fclose(f);

    int n = -1;
    sasnav_ping_pose *nav = NULL, *truth = NULL;
    int want_truth = !(opt & 2);
    int rc = sasnav_nav_read(path, &n, &nav, want_truth ? &truth : NULL);
    static const int allowed[] = {SASNAV_ERR_FORMAT, SASNAV_ERR_IO, SASNAV_ERR_NOMEM, 0};
    fz_check_rc("sasnav_nav_read", rc, allowed);
    if (rc == SASNAV_OK) {
        if (n < 1 || !nav) abort();
        for (int p = 0; p < n; p++) {
            const sasnav_ping_pose *q[2] = {&nav[p], truth ? &truth[p] : &nav[p]};
            for (int k = 0; k < 2; k++)
                if (!isfinite(q[k]->tx.x) || !isfinite(q[k]->tx.y) || !isfinite(q[k]->tx.theta) ||
                    !isfinite(q[k]->array.x) || !isfinite(q[k]->array.y) || !isfinite(q[k]->array.theta))
                    abort();
        }
    } else if (nav || truth || n != 0) {
        fprintf(stderr, "sasnav_nav_read: error but outputs set\n");
        abort();
    }
    free(nav);
    free(truth);
    sasnav_pose *sigma = NULL;
    n = -1;
    rc = sasnav_nav_read_sigma(path, &n, &sigma);
    fz_check_rc("sasnav_nav_read_sigma", rc, allowed);
    if (rc == SASNAV_OK) {
        if (n < 1) abort();
        for (int p = 0; sigma && p < n; p++)
            if (!(sigma[p].x >= 0 && sigma[p].y >= 0 && sigma[p].theta >= 0) || !isfinite(sigma[p].x) ||
                !isfinite(sigma[p].y) || !isfinite(sigma[p].theta))
                abort();
    } else if (sigma || n != 0) {
        fprintf(stderr, "sasnav_nav_read_sigma: error but outputs set\n");
        abort();
    }
    free(sigma);
    return 0;
}
