#define _XOPEN_SOURCE 700 /* nftw */
#include "testutil.h"

#include "sasnav/error.h"

#include "sasnav/image.h"
#include "sasnav/op.h"

#include <complex.h>
#include <ftw.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int test_failures = 0;
int test_checks = 0;

static char tmpdir[256];

static int remove_entry(const char *path, const struct stat *sb, int flag, struct FTW *ftw)
{
    (void)sb;
    (void)flag;
    (void)ftw;
    return remove(path) ? -1 : 0;
}

/* The test's directory goes after a clean run; it stays, and is named, after
 * a failure or when SASNAV_KEEP_TMP is set. */
static void cleanup_tmpdir(void)
{
    if (!tmpdir[0]) return;
    if (test_failures || getenv("SASNAV_KEEP_TMP")) {
        printf("files kept in %s\n", tmpdir);
        return;
    }
    if (nftw(tmpdir, remove_entry, 16, FTW_DEPTH | FTW_PHYS)) perror(tmpdir);
    tmpdir[0] = 0;
}

int test_summary(const char *name)
{
    cleanup_tmpdir();
    printf("%s: %d checks, %d failures\n", name, test_checks, test_failures);
    if (test_checks == 0) {
        printf("%s: no checks ran\n", name);
        return 1;
    }
    return test_failures ? 1 : 0;
}

const char *test_tmpdir(void)
{
    if (!tmpdir[0]) {
        const char *base = getenv("TMPDIR");
        snprintf(tmpdir, sizeof tmpdir, "%s/sasnav-test-XXXXXX", base ? base : "/tmp");
        if (!mkdtemp(tmpdir)) {
            perror("mkdtemp");
            exit(2);
        }
    }
    return tmpdir;
}

sasnav_run *test_tank_run(const sasnav_tank_params *p)
{
    char dir[1024];
    snprintf(dir, sizeof dir, "%s/rec", test_tmpdir());
    CHECK_OK(sasnav_tank_write_dir(p, dir));
    sasnav_tank_read_opts ro;
    sasnav_tank_default_read_opts(&ro);
    sasnav_run *run = NULL;
    CHECK_OK(sasnav_tank_read_dir(dir, &ro, &run));
    return run;
}

sasnav_run *test_tank_short_run(int n_pings, int jump_ping)
{
    sasnav_tank_params p;
    sasnav_tank_default(&p);
    p.n_pings = n_pings;
    p.jump_ping = jump_ping;
    p.x_start = -0.5 * (p.n_pings - 1) * p.step;
    p.n_clutter = 50;
    return test_tank_run(&p);
}

double test_image_peak(const sasnav_grid *g, const sasnav_cfloat *img, double *px, double *py)
{
    int best = 0;
    for (int i = 1; i < g->nx * g->ny; i++)
        if (cabsf(img[i]) > cabsf(img[best])) best = i;
    int ix = best % g->nx, iy = best / g->nx;
    *px = g->x0 + ix * g->dx;
    *py = g->y0 + iy * g->dy;
    if (ix > 0 && ix < g->nx - 1) {
        double a = cabsf(img[best - 1]), b = cabsf(img[best]), c = cabsf(img[best + 1]);
        double den = a - 2.0 * b + c;
        if (den != 0.0) *px += g->dx * 0.5 * (a - c) / den;
    }
    if (iy > 0 && iy < g->ny - 1) {
        double a = cabsf(img[best - g->nx]), b = cabsf(img[best]), c = cabsf(img[best + g->nx]);
        double den = a - 2.0 * b + c;
        if (den != 0.0) *py += g->dy * 0.5 * (a - c) / den;
    }
    return cabsf(img[best]);
}

double test_backproject_ffbp(sasnav_run *run, const sasnav_ping_pose *nav, const sasnav_grid *g,
                             sasnav_cfloat *img)
{
    size_t n = (size_t)g->nx * g->ny;
    sasnav_cfloat *fb = malloc(sizeof *fb * n);
    CHECK(fb != NULL, "out of memory");
    if (!fb) return 0.0;
    sasnav_op_opts oo;
    sasnav_op_default_opts(&oo);
    oo.nthreads = 1;
    CHECK_OK(sasnav_backproject(run, nav, g, &oo, img));
    CHECK_OK(sasnav_ffbp_tile(run, nav, g, 0, g->nx, 0, g->ny, &oo, NULL, fb, NULL, NULL));
    double e = 0, r = 0;
    for (size_t i = 0; i < n; i++) {
        e += pow(cabsf(fb[i] - img[i]), 2);
        r += pow(cabsf(img[i]), 2);
    }
    free(fb);
    return r > 0 ? 10 * log10(e / r) : 0.0;
}
