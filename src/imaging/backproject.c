/* Backprojection of a run (paper eq. bckprj): the sum over pings of the
 * adjoint ping operators, on a user grid, with given navigation. */
#include "sasnav/error.h"
#include "sasnav/image.h"

#include <complex.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

int sasnav_backproject(const sasnav_run *run, const sasnav_ping_pose *nav,
                       const sasnav_grid *grid, const sasnav_op_opts *opts,
                       sasnav_cfloat *image)
{
    return sasnav_backproject_progress(run, nav, grid, opts, image, NULL, NULL);
}

int sasnav_backproject_progress(const sasnav_run *run, const sasnav_ping_pose *nav,
                                const sasnav_grid *grid, const sasnav_op_opts *opts,
                                sasnav_cfloat *image, sasnav_ping_progress_fn progress, void *user)
{
    if (!run || !nav || !grid || !image)
        return sasnav_set_error(SASNAV_ERR_ARG, "NULL backprojection argument");
    int rc = sasnav_grid_check(grid);
    if (rc) return rc;
    size_t np = (size_t)grid->nx * grid->ny;
    double *x = malloc(sizeof(double) * np), *y = malloc(sizeof(double) * np);
    if (!x || !y) {
        free(x);
        free(y);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory for %zu pixels", np);
    }
    sasnav_pose identity = {0, 0, 0};
    sasnav_grid_points(grid, identity, x, y);
    sasnav_op *op = NULL;
    rc = sasnav_op_create(&run->sys, &run->array, &run->win, (int)np, x, y, opts, &op);
    free(x);
    free(y);
    if (rc) return rc;
    memset(image, 0, sizeof(sasnav_cfloat) * np);
    for (int p = 0; p < run->n_pings && !rc; p++) {
        rc = sasnav_op_set_geometry(op, &nav[p]);
        if (!rc) rc = sasnav_op_adjoint_add(op, sasnav_run_ping(run, p), image);
        if (!rc && progress) progress(p + 1, run->n_pings, user);
    }
    sasnav_op_destroy(op);
    return rc;
}

double sasnav_image_correlation(const sasnav_cfloat *a, const sasnav_cfloat *b,
                                const unsigned char *region, size_t n)
{
    if (!a || !b) return 0.0;
    double re = 0, im = 0, na = 0, nb = 0;
    for (size_t j = 0; j < n; j++) {
        if (region && !region[j]) continue;
        double ar = crealf(a[j]), ai = cimagf(a[j]), br = crealf(b[j]), bi = cimagf(b[j]);
        re += ar * br + ai * bi; /* conj(a) b */
        im += ar * bi - ai * br;
        na += ar * ar + ai * ai;
        nb += br * br + bi * bi;
    }
    return na > 0 && nb > 0 ? hypot(re, im) / sqrt(na * nb) : 0.0;
}
