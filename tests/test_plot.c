/* PNG figures: files appear only on success, are valid PNGs with real
 * content, bad arguments are refused and failures leave nothing behind. */
#include "sasnav/error.h"
#include "sasnav/plot.h"
#include "testutil.h"

#include <complex.h>
#include <dirent.h>
#include <fcntl.h>
#include <math.h>
#include <png.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

typedef struct {
    int width, height;
    double variance; /* of the grey level (0..255) over all pixels */
    int n_colours;   /* distinct RGB values, capped at 4096 */
} png_stats;

/* Reads a PNG with libpng's simplified API; returns 0 on success. */
static int read_png(const char *path, png_stats *st)
{
    png_image img;
    memset(&img, 0, sizeof img);
    img.version = PNG_IMAGE_VERSION;
    if (!png_image_begin_read_from_file(&img, path)) return -1;
    img.format = PNG_FORMAT_RGB;
    size_t size = PNG_IMAGE_SIZE(img);
    unsigned char *px = malloc(size);
    if (!px || !png_image_finish_read(&img, NULL, px, 0, NULL)) {
        png_image_free(&img);
        free(px);
        return -1;
    }
    st->width = (int)img.width;
    st->height = (int)img.height;
    size_t n = (size_t)img.width * img.height;
    double sum = 0, sum2 = 0;
    enum { MAXC = 4096 };
    static unsigned int seen[MAXC];
    int n_seen = 0;
    for (size_t i = 0; i < n; i++) {
        const unsigned char *p = px + 3 * i;
        double grey = 0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2];
        sum += grey;
        sum2 += grey * grey;
        unsigned int rgb = (unsigned)p[0] << 16 | (unsigned)p[1] << 8 | p[2];
        int known = 0;
        for (int k = 0; k < n_seen && !known; k++) known = seen[k] == rgb;
        if (!known && n_seen < MAXC) seen[n_seen++] = rgb;
    }
    st->variance = sum2 / n - (sum / n) * (sum / n);
    st->n_colours = n_seen;
    free(px);
    return 0;
}

static int file_exists(const char *path)
{
    struct stat sb;
    return stat(path, &sb) == 0;
}

/* Number of entries of `dir` whose name contains ".tmp-". */
static int count_temp_files(const char *dir)
{
    DIR *d = opendir(dir);
    if (!d) return -1;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)))
        if (strstr(e->d_name, ".tmp-")) n++;
    closedir(d);
    return n;
}

/* A point target's sinc^2 response over weak speckle: 81 x 129 pixels. */
static sasnav_cfloat *make_image(sasnav_grid *grid)
{
    *grid = (sasnav_grid){-0.5, 9.2, 0.0125, 0.0125, 81, 129};
    sasnav_cfloat *img = malloc(sizeof *img * 81 * 129);
    unsigned int state = 12345;
    for (int iy = 0; iy < grid->ny; iy++)
        for (int ix = 0; ix < grid->nx; ix++) {
            double x = grid->x0 + ix * grid->dx, y = grid->y0 + iy * grid->dy;
            double u = (x - 0.1) / 0.025, v = (y - 10.2) / 0.025;
            double sx = fabs(u) < 1e-9 ? 1 : sin(M_PI * u) / (M_PI * u);
            double sy = fabs(v) < 1e-9 ? 1 : sin(M_PI * v) / (M_PI * v);
            state = state * 1103515245u + 12345u;
            double re = ((state >> 8) & 0xffff) / 65536.0 - 0.5;
            state = state * 1103515245u + 12345u;
            double im = ((state >> 8) & 0xffff) / 65536.0 - 0.5;
            img[iy * grid->nx + ix] = (float)(sx * sy) + 0.01f * (float)re + 0.01f * I * (float)im;
        }
    return img;
}

static void check_png(const char *path, int min_colours)
{
    png_stats st = {0};
    CHECK(file_exists(path), "%s was not written", path);
    CHECK(read_png(path, &st) == 0, "%s is not a readable PNG", path);
    CHECK(st.width > 0 && st.height > 0, "%s: empty picture %dx%d", path, st.width, st.height);
    /* A flat picture (e.g. only background) has zero variance; a figure
     * with axes, text and data has a lot. */
    CHECK(st.variance > 100.0, "%s: grey-level variance %g: picture looks flat", path, st.variance);
    CHECK(st.n_colours >= min_colours, "%s: only %d colours (expected >= %d)", path, st.n_colours,
          min_colours);
}

static void test_image_db(const char *dir)
{
    char path[512];
    sasnav_grid grid;
    sasnav_cfloat *img = make_image(&grid);
    snprintf(path, sizeof path, "%s/image.png", dir);
    CHECK_OK(sasnav_plot_image_db(path, &grid, img, 40.0, "point target (# 1), 40 dB"));
    /* The colour map spreads over many colours. */
    check_png(path, 64);
    CHECK(count_temp_files(dir) == 0, "temporary files left in %s", dir);

    /* NaN and infinite pixels are drawn at the floor, not refused. */
    img[10] = NAN;
    img[20] = INFINITY;
    snprintf(path, sizeof path, "%s/image-nan.png", dir);
    CHECK_OK(sasnav_plot_image_db(path, &grid, img, 30.0, "with NaN"));
    check_png(path, 16);

    /* An all-zero image plots the floor without dividing by zero. */
    memset(img, 0, sizeof *img * 81 * 129);
    snprintf(path, sizeof path, "%s/image-zero.png", dir);
    CHECK_OK(sasnav_plot_image_db(path, &grid, img, 30.0, "all zero"));
    check_png(path, 2);

    /* Bad arguments. */
    CHECK(sasnav_plot_image_db(path, NULL, img, 30.0, "t") == SASNAV_ERR_ARG, "NULL grid");
    CHECK(sasnav_plot_image_db(path, &grid, NULL, 30.0, "t") == SASNAV_ERR_ARG, "NULL image");
    CHECK(sasnav_plot_image_db(path, &grid, img, 0.0, "t") == SASNAV_ERR_ARG, "zero range");
    CHECK(sasnav_plot_image_db(path, &grid, img, NAN, "t") == SASNAV_ERR_ARG, "NaN range");
    sasnav_grid bad = grid;
    bad.dx = -1;
    CHECK(sasnav_plot_image_db(path, &bad, img, 30.0, "t") == SASNAV_ERR_ARG, "negative dx");
    bad = grid;
    bad.nx = 0;
    CHECK(sasnav_plot_image_db(path, &bad, img, 30.0, "t") == SASNAV_ERR_ARG, "nx = 0");
    free(img);
}

static void test_lines(const char *dir)
{
    char path[512];
    enum { N = 200 };
    double x[N], y0[N], y1[N], y2[N];
    for (int i = 0; i < N; i++) {
        x[i] = -0.1 + 0.2 * i / (N - 1);
        y0[i] = 0.02 + (x[i] - 0.02) * (x[i] - 0.02);
        y1[i] = 0.05 + 0.5 * fabs(x[i] + 0.03);
        y2[i] = i == 50 ? NAN : 0.01 + 0.3 * x[i] * x[i] + 0.002 * sin(200 * x[i]);
    }
    const double *xs[3] = {x, x, x}, *ys[3] = {y0, y1, y2};
    const int ns[3] = {N, N, N};
    const char *labels[3] = {"zeta (blurred)", "zeta", NULL};
    sasnav_line_plot p = {"cost along surge",
                          "surge error (m)",
                          "normalised error",
                          3,
                          ns,
                          xs,
                          ys,
                          labels,
                          0,
                          0.02,
                          NAN};
    snprintf(path, sizeof path, "%s/lines.png", dir);
    CHECK_OK(sasnav_plot_lines(path, &p));
    check_png(path, 4);

    p.log_y = 1;
    p.vline2 = -0.03;
    snprintf(path, sizeof path, "%s/lines-log.png", dir);
    CHECK_OK(sasnav_plot_lines(path, &p));
    check_png(path, 4);

    /* Nothing plottable on a log axis. */
    double neg[2] = {-1, 0}, xx[2] = {0, 1};
    const double *xn[1] = {xx}, *yn[1] = {neg};
    const int nn[1] = {2};
    sasnav_line_plot q = {"t", "x", "y", 1, nn, xn, yn, NULL, 1, NAN, NAN};
    CHECK(sasnav_plot_lines(path, &q) == SASNAV_ERR_ARG, "log axis with y <= 0 only");
    CHECK(sasnav_plot_lines(path, NULL) == SASNAV_ERR_ARG, "NULL plot");
    q.n_series = 0;
    CHECK(sasnav_plot_lines(path, &q) == SASNAV_ERR_ARG, "no series");
}

static void test_map(const char *dir)
{
    char path[512];
    sasnav_grid grid = {-0.05, -0.04, 0.001, 0.002, 101, 41};
    double *f = malloc(sizeof *f * 101 * 41);
    for (int iy = 0; iy < grid.ny; iy++)
        for (int ix = 0; ix < grid.nx; ix++) {
            double u = grid.x0 + ix * grid.dx, v = grid.y0 + iy * grid.dy;
            f[iy * grid.nx + ix] = hypot(u - 0.01, 3 * (v + 0.01));
        }
    f[7] = NAN;
    snprintf(path, sizeof path, "%s/map.png", dir);
    CHECK_OK(sasnav_plot_map(path, &grid, f, "zeta(surge, yaw)", "surge (m)", "yaw (rad)"));
    check_png(path, 64);
    /* Constant field. */
    for (int n = 0; n < 101 * 41; n++) f[n] = 3.0;
    snprintf(path, sizeof path, "%s/map-flat.png", dir);
    CHECK_OK(sasnav_plot_map(path, &grid, f, "flat", NULL, NULL));
    check_png(path, 2);
    free(f);
}

/* Failures leave no file behind: a missing directory, and a target that
 * cannot be replaced (a directory of that name) after the picture is drawn. */
static void test_cleanup_on_failure(const char *dir)
{
    char path[600], sub[512];
    sasnav_grid grid;
    sasnav_cfloat *img = make_image(&grid);
    snprintf(path, sizeof path, "%s/no-such-dir/image.png", dir);
    CHECK(sasnav_plot_image_db(path, &grid, img, 40.0, "x") == SASNAV_ERR_IO,
          "missing directory must give SASNAV_ERR_IO");
    CHECK(strstr(sasnav_last_error(), "no-such-dir") != NULL, "message names the path: %s",
          sasnav_last_error());
    CHECK(!file_exists(path), "file appeared in a missing directory");

    snprintf(sub, sizeof sub, "%s/fail", dir);
    CHECK(mkdir(sub, 0755) == 0, "mkdir %s", sub);
    snprintf(path, sizeof path, "%s/target.png", sub);
    CHECK(mkdir(path, 0755) == 0, "mkdir %s", path);
    CHECK(sasnav_plot_image_db(path, &grid, img, 40.0, "x") == SASNAV_ERR_IO,
          "a directory in the way must give SASNAV_ERR_IO");
    CHECK(count_temp_files(sub) == 0, "temporary file left behind in %s", sub);
    rmdir(path);
    rmdir(sub);
    free(img);
}

/* The library prints nothing: PLplot's messages are silenced. */
static void test_quiet(const char *dir)
{
    char path[512], log[512];
    snprintf(log, sizeof log, "%s/stderr.txt", dir);
    fflush(stderr);
    int saved = dup(2);
    int fd = open(log, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (saved < 0 || fd < 0) return;
    dup2(fd, 2);
    close(fd);
    sasnav_grid grid;
    sasnav_cfloat *img = make_image(&grid);
    snprintf(path, sizeof path, "%s/quiet.png", dir);
    int rc = sasnav_plot_image_db(path, &grid, img, 40.0, "quiet");
    double x[2] = {0, 1}, y[2] = {1, 2};
    const double *xs[1] = {x}, *ys[1] = {y};
    const int ns[1] = {2};
    sasnav_line_plot p = {"t", "x", "y", 1, ns, xs, ys, NULL, 0, NAN, NAN};
    int rc2 = sasnav_plot_lines(path, &p);
    int rc3 = sasnav_plot_image_db("/nonexistent-dir/x.png", &grid, img, 40.0, "quiet");
    fflush(stderr);
    dup2(saved, 2);
    close(saved);
    free(img);
    CHECK(rc == 0 && rc2 == 0 && rc3 == SASNAV_ERR_IO, "plots: %d %d %d", rc, rc2, rc3);
    struct stat sb;
    CHECK(stat(log, &sb) == 0 && sb.st_size == 0, "library wrote %lld bytes to stderr",
          (long long)sb.st_size);
    unlink(log);
}

int main(void)
{
    const char *dir = test_tmpdir();
    test_image_db(dir);
    test_lines(dir);
    test_map(dir);
    test_cleanup_on_failure(dir);
    test_quiet(dir);
    return test_summary("test_plot");
}
