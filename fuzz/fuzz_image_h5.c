/* fuzz_image_h5: sasnav_image_read on structure-aware generated image
 * files (h5gen.h). Contract: SASNAV_OK with a grid that passes
 * sasnav_grid_check and finite pixels, or SASNAV_ERR_FORMAT / IO / NOMEM
 * with a message and nothing allocated. */
#include "fuzz_common.h"
#include "h5gen.h"
#include "sasnav/io.h"

static double fill_img(size_t i, const hsize_t *dims, int rank) { return cos(0.11 * (double)i); }
static double fill_x(size_t i, const hsize_t *dims, int rank) { return -1.0 + 0.01 * (double)i; }
static double fill_y(size_t i, const hsize_t *dims, int rank) { return 9.5 + 0.02 * (double)i; }

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    h5g_init();
    h5g g = {data, size};
    const char *path = fz_path("image.h5");
    hid_t f = h5g_create(&g, path);
    h5g_root(&g, f, "sasnav-image");
    hsize_t ny = 1 + (h5g_u8(&g) + 7) % 40, nx = 1 + (h5g_u8(&g) + 11) % 40;
    hsize_t di[2] = {ny, nx}, dx[1] = {nx}, dy[1] = {ny};
    h5g_dataset(&g, f, "/image", D_COMPLEX, 2, di, fill_img);
    hid_t im = H5Oopen(f, "/image", H5P_DEFAULT);
    if (im >= 0) {
        unsigned with = h5g_u8(&g);
        if (!(with & 1)) {
            h5g_attr(&g, im, "x0", A_DOUBLE, -1.0, NULL);
            h5g_attr(&g, im, "dx", A_DOUBLE, 0.01, NULL);
            h5g_attr(&g, im, "y0", A_DOUBLE, 9.5, NULL);
            h5g_attr(&g, im, "dy", A_DOUBLE, 0.02, NULL);
        }
        H5Oclose(im);
    }
    h5g_dataset(&g, f, "/x", D_REAL, 1, dx, fill_x);
    h5g_dataset(&g, f, "/y", D_REAL, 1, dy, fill_y);
    h5g_extras(&g, f);
    H5Fclose(f);

    sasnav_grid grid;
    sasnav_cfloat *img = NULL;
    int rc = sasnav_image_read(path, &grid, &img);
    static const int allowed[] = {SASNAV_ERR_FORMAT, SASNAV_ERR_IO, SASNAV_ERR_NOMEM, 0};
    fz_check_rc("sasnav_image_read", rc, allowed);
    if (rc == SASNAV_OK) {
        if (!img || sasnav_grid_check(&grid) != SASNAV_OK) abort();
        const float *v = (const float *)img;
        for (size_t k = 0; k < 2 * (size_t)grid.nx * (size_t)grid.ny; k++)
            if (!isfinite(v[k])) abort();
    } else if (img) {
        abort();
    }
    free(img);
    return 0;
}
