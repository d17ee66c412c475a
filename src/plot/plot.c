/* Pictures: PNG figures through PLplot's cairo driver ("pngcairo").
 *
 * Every call opens its own PLplot stream (plmkstrm ... plend1) and restores
 * the caller's current stream afterwards, so the calls do not disturb each
 * other. PLplot's global abort handler is replaced by a silent one for the
 * duration of a call (messages are collected through plsError instead).
 *
 * Output goes to "<path>.tmp-XXXXXX", created here with mkstemp before
 * PLplot sees the name (PLplot's own file opening retries, prompts on stdin
 * and finally calls exit() when it cannot open a file, so it must never be
 * given a name it cannot open), and is renamed onto <path> only when the
 * picture is complete. Everything that would make PLplot call plexit() (no
 * such device, unopenable file) is checked before plinit().
 */
#include "sasnav/plot.h"
#include "sasnav/error.h"
#include "sasnav/io.h"

#include <plplot/plplot.h>

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define PLOT_DEVICE "pngcairo"
#define PLOT_DPI 100.0
#define PLOT_TEXT_MAX 512

/* cmap0 (discrete colours): 0 background, 1 foreground, 2 light grid grey,
 * 3 marker grey, then ten line colours (the widely used "category 10"
 * palette, distinguishable in print and by most colour-blind readers). */
enum { COL_BG = 0, COL_FG = 1, COL_GRID = 2, COL_MARK = 3, COL_LINE0 = 4, N_LINE_COLOURS = 10 };

static const PLINT cmap0_r[] = {255, 0, 225, 90, 31, 255, 44, 214, 148, 140, 227, 127, 188, 23};
static const PLINT cmap0_g[] = {255, 0, 225, 90, 119, 127, 160, 39, 103, 86, 119, 127, 189, 190};
static const PLINT cmap0_b[] = {255, 0, 225, 90, 180, 14, 44, 40, 189, 75, 194, 127, 34, 207};

/* Continuous colour map (cmap1): viridis, a perceptually uniform map that
 * reads correctly in grey scale; eleven control points at 0, 0.1, ..., 1,
 * linearly interpolated in RGB by PLplot. */
static const double viridis_r[] = {68, 72, 65, 53, 42, 33, 34, 68, 122, 189, 253};
static const double viridis_g[] = {1, 36, 68, 95, 120, 145, 168, 191, 209, 223, 231};
static const double viridis_b[] = {84, 117, 135, 141, 142, 140, 132, 112, 81, 38, 37};

/* ---- one plotting session: temporary file + private PLplot stream ---- */

typedef struct {
    char tmp[4096];
    PLINT prev_stream;
    PLINT errcode;
    char errmsg[1024];
    int open; /* 1 once the stream exists (plend1 due) */
} plot_session;

static void silent_abort(PLCHAR_VECTOR message) { (void)message; }

static int device_available(void)
{
    enum { MAX_DEVICES = 128 };
    const char *menus[MAX_DEVICES], *names[MAX_DEVICES];
    const char **pm = menus, **pn = names;
    int n = MAX_DEVICES;
    plgDevs(&pm, &pn, &n);
    for (int i = 0; i < n; i++)
        if (names[i] && strcmp(names[i], PLOT_DEVICE) == 0) return 1;
    return 0;
}

/* Creates the temporary output file next to `path`. */
static int make_temp(const char *path, char *tmp, size_t size)
{
    if (!path || !path[0]) return sasnav_set_error(SASNAV_ERR_ARG, "plot: output path is empty");
    int len = snprintf(tmp, size, "%s.tmp-XXXXXX", path);
    if (len < 0 || (size_t)len >= size)
        return sasnav_set_error(SASNAV_ERR_ARG, "plot: output path too long: %s", path);
    int fd = mkstemp(tmp);
    if (fd < 0)
        return sasnav_set_error(SASNAV_ERR_IO, "%s: cannot create output file: %s", path,
                                strerror(errno));
    (void)fchmod(fd, 0644);
    close(fd);
    return SASNAV_OK;
}

/* Opens a private stream writing a width x height pixel PNG. */
static int session_begin(plot_session *s, const char *path, int width, int height)
{
    memset(s, 0, sizeof *s);
    if (!device_available())
        return sasnav_set_error(SASNAV_ERR_UNSUPPORTED,
                                "plot: PLplot device '%s' is not installed (plplot-driver-cairo)",
                                PLOT_DEVICE);
    int rc = sasnav_output_check(path);
    if (!rc) rc = make_temp(path, s->tmp, sizeof s->tmp);
    if (rc) return rc;

    PLINT stream = -1;
    plgstrm(&s->prev_stream);
    plmkstrm(&stream);
    if (stream < 0) {
        unlink(s->tmp);
        plsstrm(s->prev_stream);
        return sasnav_set_error(SASNAV_ERR_INTERNAL, "plot: no free PLplot stream");
    }
    s->open = 1;
    plsError(&s->errcode, s->errmsg);
    plsabort(silent_abort);
    plsdev(PLOT_DEVICE);
    plsfnam(s->tmp);
    plspage(PLOT_DPI, PLOT_DPI, width, height, 0, 0);
    plscmap0(cmap0_r, cmap0_g, cmap0_b, (PLINT)(sizeof cmap0_r / sizeof cmap0_r[0]));
    plinit();
    if (s->errcode) return SASNAV_ERR_INTERNAL;
    pladv(0);
    plfont(1);
    plschr(0.0, 1.0);
    /* Plain decimal tick labels up to 7 digits, no "(x10^k)" side labels,
     * which PLplot places outside the page margins. */
    plsxax(7, 0);
    plsyax(7, 0);
    return SASNAV_OK;
}

/* Ends the stream; on success (status 0) renames the file onto `path`,
 * otherwise removes it. Returns the final status. */
static int session_end(plot_session *s, const char *path, int status)
{
    if (s->open) {
        plend1();
        plsstrm(s->prev_stream);
        plsabort(NULL);
        s->open = 0;
        if (status == SASNAV_OK && s->errcode)
            status = sasnav_set_error(SASNAV_ERR_INTERNAL, "plot: PLplot error: %s", s->errmsg);
        else if (status == SASNAV_ERR_INTERNAL && s->errcode)
            status = sasnav_set_error(SASNAV_ERR_INTERNAL, "plot: PLplot error: %s", s->errmsg);
    }
    if (!s->tmp[0]) return status;
    if (status == SASNAV_OK) {
        /* The cairo driver does not report write failures: check that a PNG
         * signature reached the file. */
        static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
        unsigned char head[8] = {0};
        FILE *f = fopen(s->tmp, "rb");
        size_t got = f ? fread(head, 1, sizeof head, f) : 0;
        if (f) fclose(f);
        if (got != sizeof head || memcmp(head, sig, sizeof sig) != 0)
            status = sasnav_set_error(SASNAV_ERR_IO, "%s: the PNG could not be written", path);
    }
    if (status == SASNAV_OK && rename(s->tmp, path) != 0)
        status = sasnav_set_error(SASNAV_ERR_IO, "%s: cannot rename output into place: %s", path,
                                  strerror(errno));
    if (status != SASNAV_OK) unlink(s->tmp);
    s->tmp[0] = '\0';
    return status;
}

/* ---- helpers ---- */

/* Copies user text for PLplot, whose escape character is '#': a literal '#'
 * is written "##". UTF-8 passes through (cairo renders it). */
static const char *plot_text(const char *in, char *out, size_t size)
{
    size_t j = 0;
    if (!in) in = "";
    for (size_t i = 0; in[i] && j + 2 < size; i++) {
        if (in[i] == '#') out[j++] = '#';
        out[j++] = in[i];
    }
    out[j] = '\0';
    return out;
}

static void set_viridis(void)
{
    enum { N = sizeof viridis_r / sizeof viridis_r[0] };
    PLFLT pos[N], r[N], g[N], b[N];
    for (int i = 0; i < N; i++) {
        pos[i] = (PLFLT)i / (N - 1);
        r[i] = viridis_r[i] / 255.0;
        g[i] = viridis_g[i] / 255.0;
        b[i] = viridis_b[i] / 255.0;
    }
    plscmap1n(256);
    plscmap1l(1, N, pos, r, g, b, NULL);
}

static int grid_ok(const sasnav_grid *grid)
{
    if (!grid) return 0;
    if (grid->nx < 1 || grid->ny < 1) return 0;
    if (!(grid->dx > 0) || !(grid->dy > 0)) return 0;
    double span_x = grid->nx * grid->dx, span_y = grid->ny * grid->dy;
    return isfinite(grid->x0) && isfinite(grid->y0) && isfinite(span_x) && isfinite(span_y) &&
           (double)grid->nx * grid->ny <= 1e8;
}

/* Page geometry of a map. With `true_aspect` the data area has the true
 * metre aspect ratio of the grid unless that would be more extreme than 1:3
 * (then it is clamped); otherwise (axes in different units) it is 4:3. */
typedef struct {
    int width, height;         /* page, pixels */
    double vx0, vx1, vy0, vy1; /* viewport, normalised page coordinates */
} map_layout;

static map_layout layout_map(const sasnav_grid *grid, int true_aspect)
{
    const double left = 110, right = 170, bottom = 90, top = 70; /* margins, pixels */
    /* aspect = height / width of the data area */
    double aspect = true_aspect ? (grid->ny * grid->dy) / (grid->nx * grid->dx) : 0.75;
    if (aspect > 3.0) aspect = 3.0;
    if (aspect < 1.0 / 3.0) aspect = 1.0 / 3.0;
    double w = 760, h = w * aspect;
    if (h > 900) {
        h = 900;
        w = h / aspect;
    }
    if (h < 380) {
        h = 380;
        w = h / aspect;
        if (w > 1300) w = 1300;
    }
    map_layout L;
    L.width = (int)lround(left + w + right);
    L.height = (int)lround(bottom + h + top);
    L.vx0 = left / L.width;
    L.vx1 = (left + w) / L.width;
    L.vy0 = bottom / L.height;
    L.vy1 = (bottom + h) / L.height;
    return L;
}

/* Draws a field already scaled to [zmin, zmax] (idata[ix][iy]) as a map with
 * axes, labels, title and a colour bar labelled `bar_label`. */
static void draw_map(const sasnav_grid *grid, PLFLT **idata, double zmin, double zmax,
                     const map_layout *L, const char *title, const char *xlabel, const char *ylabel,
                     const char *bar_label)
{
    char t[PLOT_TEXT_MAX], xl[PLOT_TEXT_MAX], yl[PLOT_TEXT_MAX], bl[PLOT_TEXT_MAX];
    double xmin = grid->x0 - 0.5 * grid->dx, xmax = grid->x0 + (grid->nx - 0.5) * grid->dx;
    double ymin = grid->y0 - 0.5 * grid->dy, ymax = grid->y0 + (grid->ny - 0.5) * grid->dy;

    set_viridis();
    plvpor(L->vx0, L->vx1, L->vy0, L->vy1);
    plwind(xmin, xmax, ymin, ymax);
    /* plimage's extent is the outer edge of the pixels. */
    plimage((PLFLT_MATRIX)idata, grid->nx, grid->ny, xmin, xmax, ymin, ymax, zmin, zmax, xmin, xmax,
            ymin, ymax);
    plcol0(COL_FG);
    plwidth(1.0);
    plschr(0.0, 0.95);
    plbox("bcinst", 0.0, 0, "bcinstv", 0.0, 0);
    plschr(0.0, 1.05);
    plmtex("b", 3.0, 0.5, 0.5, plot_text(xlabel, xl, sizeof xl));
    plmtex("l", 4.6, 0.5, 0.5, plot_text(ylabel, yl, sizeof yl));
    plschr(0.0, 1.25);
    plmtex("t", 1.6, 0.5, 0.5, plot_text(title, t, sizeof t));

    /* Colour bar to the right of the viewport, full height; its label is
     * written separately above it (a colour-bar label would shift the bar
     * off the viewport's height). Offsets are in viewport units. */
    const double bar_gap = 0.03, bar_width = 0.035;
    PLFLT bar_w, bar_h;
    const char *axis_opts[1] = {"bcvtsm"};
    PLFLT ticks[1] = {0.0};
    PLINT sub_ticks[1] = {0};
    PLINT n_values[1] = {2};
    PLFLT range[2] = {zmin, zmax};
    const PLFLT *values[1] = {range};
    plschr(0.0, 0.95);
    plcolorbar(&bar_w, &bar_h, PL_COLORBAR_IMAGE,
               PL_POSITION_RIGHT | PL_POSITION_OUTSIDE | PL_POSITION_VIEWPORT, bar_gap, 0.0,
               bar_width, 1.0, COL_BG, COL_FG, 1, 0.0, 0.0, 0, 0.0, 0, NULL, NULL, 1, axis_opts,
               ticks, sub_ticks, n_values, values);
    if (bar_label && bar_label[0]) {
        plcol0(COL_FG);
        plmtex("t", 1.1, 1.0 + bar_gap + 0.5 * bar_width, 0.5, plot_text(bar_label, bl, sizeof bl));
    }
}

/* Column-major copy for PLplot: idata[ix][iy]. */
static PLFLT **alloc_columns(int nx, int ny, PLFLT **block)
{
    PLFLT **cols = malloc((size_t)nx * sizeof *cols);
    *block = malloc((size_t)nx * (size_t)ny * sizeof **block);
    if (!cols || !*block) {
        free(cols);
        free(*block);
        *block = NULL;
        return NULL;
    }
    for (int ix = 0; ix < nx; ix++) cols[ix] = *block + (size_t)ix * ny;
    return cols;
}

/* ---- public functions ---- */

int sasnav_plot_image_db(const char *png_path, const sasnav_grid *grid, const sasnav_cfloat *image,
                         double dynamic_range_db, const char *title)
{
    if (!png_path || !image)
        return sasnav_set_error(SASNAV_ERR_ARG, "plot_image_db: NULL argument");
    if (!grid_ok(grid))
        return sasnav_set_error(SASNAV_ERR_ARG, "plot_image_db: invalid image grid");
    if (!(dynamic_range_db > 0) || !isfinite(dynamic_range_db))
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "plot_image_db: dynamic range must be finite and > 0 dB, got %g",
                                dynamic_range_db);
    const int nx = grid->nx, ny = grid->ny;
    const double floor_db = -dynamic_range_db;

    double peak = 0.0;
    for (size_t n = 0; n < (size_t)nx * ny; n++) {
        double a = cabs((double complex)image[n]);
        if (isfinite(a) && a > peak) peak = a;
    }
    PLFLT *block;
    PLFLT **cols = alloc_columns(nx, ny, &block);
    if (!cols) return sasnav_set_error(SASNAV_ERR_NOMEM, "plot_image_db: out of memory");
    /* dB re the peak, clipped to the floor; non-finite pixels and an
     * all-zero image sit on the floor. */
    for (int iy = 0; iy < ny; iy++)
        for (int ix = 0; ix < nx; ix++) {
            double a = cabs((double complex)image[(size_t)iy * nx + ix]);
            double db = floor_db;
            if (peak > 0 && isfinite(a) && a > 0) db = 20.0 * log10(a / peak);
            if (!(db > floor_db)) db = floor_db;
            if (db > 0) db = 0;
            cols[ix][iy] = db;
        }

    map_layout L = layout_map(grid, 1);
    plot_session s;
    int rc = session_begin(&s, png_path, L.width, L.height);
    if (rc == SASNAV_OK)
        draw_map(grid, cols, floor_db, 0.0, &L, title, "along-track x (m)", "range y (m)", "dB");
    rc = session_end(&s, png_path, rc);
    free(cols);
    free(block);
    return rc;
}

int sasnav_plot_map(const char *png_path, const sasnav_grid *grid, const double *f,
                    const char *title, const char *xlabel, const char *ylabel)
{
    if (!png_path || !f) return sasnav_set_error(SASNAV_ERR_ARG, "plot_map: NULL argument");
    if (!grid_ok(grid)) return sasnav_set_error(SASNAV_ERR_ARG, "plot_map: invalid grid");
    const int nx = grid->nx, ny = grid->ny;
    double lo = INFINITY, hi = -INFINITY;
    for (size_t n = 0; n < (size_t)nx * ny; n++)
        if (isfinite(f[n])) {
            if (f[n] < lo) lo = f[n];
            if (f[n] > hi) hi = f[n];
        }
    if (!(lo <= hi)) lo = hi = 0.0; /* nothing finite: a flat map */
    if (hi - lo <= 1e-12 * fmax(fabs(lo), fabs(hi))) {
        /* Constant field: open the scale around the value. */
        double pad = fabs(lo) > 0 ? 0.05 * fabs(lo) : 0.5;
        lo -= pad;
        hi += pad;
    }
    PLFLT *block;
    PLFLT **cols = alloc_columns(nx, ny, &block);
    if (!cols) return sasnav_set_error(SASNAV_ERR_NOMEM, "plot_map: out of memory");
    for (int iy = 0; iy < ny; iy++)
        for (int ix = 0; ix < nx; ix++) {
            double v = f[(size_t)iy * nx + ix];
            cols[ix][iy] = isfinite(v) ? v : lo; /* non-finite samples at the bottom */
        }

    /* Default labels mean scene coordinates in metres: keep the true shape.
     * Caller-named axes may be in different units (surge vs yaw). */
    map_layout L = layout_map(grid, !xlabel && !ylabel);
    plot_session s;
    int rc = session_begin(&s, png_path, L.width, L.height);
    if (rc == SASNAV_OK)
        draw_map(grid, cols, lo, hi, &L, title, xlabel ? xlabel : "along-track x (m)",
                 ylabel ? ylabel : "range y (m)", "");
    rc = session_end(&s, png_path, rc);
    free(cols);
    free(block);
    return rc;
}

/* ---- line plots ---- */

typedef struct {
    double xmin, xmax, ymin, ymax; /* y in log10 units when log_y */
} line_range;

static double plot_y(const sasnav_line_plot *p, double y)
{
    if (!p->log_y) return y;
    return y > 0 ? log10(y) : NAN;
}

static int line_ranges(const sasnav_line_plot *p, line_range *r)
{
    r->xmin = r->ymin = INFINITY;
    r->xmax = r->ymax = -INFINITY;
    for (int s = 0; s < p->n_series; s++)
        for (int i = 0; i < p->n[s]; i++) {
            double x = p->x[s][i], y = plot_y(p, p->y[s][i]);
            if (!isfinite(x) || !isfinite(y)) continue;
            r->xmin = fmin(r->xmin, x);
            r->xmax = fmax(r->xmax, x);
            r->ymin = fmin(r->ymin, y);
            r->ymax = fmax(r->ymax, y);
        }
    if (!(r->xmin <= r->xmax)) return 0;
    if (isfinite(p->vline)) r->xmin = fmin(r->xmin, p->vline), r->xmax = fmax(r->xmax, p->vline);
    if (isfinite(p->vline2)) r->xmin = fmin(r->xmin, p->vline2), r->xmax = fmax(r->xmax, p->vline2);
    if (r->xmax - r->xmin <= 1e-12 * fmax(fabs(r->xmin), fabs(r->xmax))) {
        double pad = r->xmin != 0 ? 0.05 * fabs(r->xmin) : 0.5;
        r->xmin -= pad;
        r->xmax += pad;
    }
    if (p->log_y) {
        /* Whole decades, at least one, so that the axis has labelled ticks. */
        r->ymin = floor(r->ymin);
        r->ymax = ceil(r->ymax);
        if (r->ymax <= r->ymin) r->ymax = r->ymin + 1;
    } else {
        if (r->ymax - r->ymin <= 1e-12 * fmax(fabs(r->ymin), fabs(r->ymax))) {
            double pad = r->ymin != 0 ? 0.05 * fabs(r->ymin) : 0.5;
            r->ymin -= pad;
            r->ymax += pad;
        } else {
            double pad = 0.05 * (r->ymax - r->ymin);
            r->ymin -= pad;
            r->ymax += pad;
        }
    }
    return 1;
}

/* Draws series s, broken at non-finite points. */
static void draw_series(const sasnav_line_plot *p, int s, PLFLT *bx, PLFLT *by)
{
    int k = 0;
    for (int i = 0; i <= p->n[s]; i++) {
        double x = i < p->n[s] ? p->x[s][i] : NAN;
        double y = i < p->n[s] ? plot_y(p, p->y[s][i]) : NAN;
        if (isfinite(x) && isfinite(y)) {
            bx[k] = x;
            by[k] = y;
            k++;
            continue;
        }
        if (k == 1)
            plpoin(1, bx, by, 1);
        else if (k > 1)
            plline(k, bx, by);
        k = 0;
    }
}

static int check_lines(const sasnav_line_plot *p, int *max_n)
{
    if (!p) return sasnav_set_error(SASNAV_ERR_ARG, "plot_lines: NULL plot description");
    if (p->n_series < 1 || p->n_series > 10000 || !p->n || !p->x || !p->y)
        return sasnav_set_error(SASNAV_ERR_ARG, "plot_lines: needs 1 or more series with n, x, y");
    *max_n = 0;
    for (int s = 0; s < p->n_series; s++) {
        if (p->n[s] < 0)
            return sasnav_set_error(SASNAV_ERR_ARG, "plot_lines: series %d has n < 0", s);
        if (p->n[s] > 0 && (!p->x[s] || !p->y[s]))
            return sasnav_set_error(SASNAV_ERR_ARG, "plot_lines: series %d has NULL data", s);
        if (p->n[s] > *max_n) *max_n = p->n[s];
    }
    return SASNAV_OK;
}

/* Picks the inside corner of the viewport (top-right, top-left,
 * bottom-right, bottom-left) whose legend-sized region covers the fewest
 * data points. */
static PLINT legend_corner(const sasnav_line_plot *p, const line_range *r, int n_entries)
{
    static const PLINT corners[4] = {
        PL_POSITION_TOP | PL_POSITION_RIGHT, PL_POSITION_TOP | PL_POSITION_LEFT,
        PL_POSITION_BOTTOM | PL_POSITION_RIGHT, PL_POSITION_BOTTOM | PL_POSITION_LEFT};
    const double box_w = 0.40, box_h = fmin(0.9, 0.05 + 0.065 * n_entries);
    long count[4] = {0, 0, 0, 0};
    for (int s = 0; s < p->n_series; s++)
        for (int i = 0; i < p->n[s]; i++) {
            double x = p->x[s][i], y = plot_y(p, p->y[s][i]);
            if (!isfinite(x) || !isfinite(y)) continue;
            double u = (x - r->xmin) / (r->xmax - r->xmin), v = (y - r->ymin) / (r->ymax - r->ymin);
            int right = u > 1 - box_w, left = u<box_w, top = v> 1 - box_h, bottom = v < box_h;
            count[0] += top && right;
            count[1] += top && left;
            count[2] += bottom && right;
            count[3] += bottom && left;
        }
    int best = 0;
    for (int c = 1; c < 4; c++)
        if (count[c] < count[best]) best = c;
    return corners[best];
}

static void draw_legend(const sasnav_line_plot *p, const line_range *r)
{
    if (!p->labels) return;
    int n = 0;
    for (int s = 0; s < p->n_series; s++)
        if (p->labels[s]) n++;
    if (n == 0) return;
    PLINT *opt = calloc((size_t)n, sizeof *opt), *text_col = calloc((size_t)n, sizeof *text_col);
    PLINT *line_col = calloc((size_t)n, sizeof *line_col),
          *line_sty = calloc((size_t)n, sizeof *line_sty);
    PLFLT *line_w = calloc((size_t)n, sizeof *line_w);
    char **text = calloc((size_t)n, sizeof *text);
    char *store = calloc((size_t)n, PLOT_TEXT_MAX);
    if (opt && text_col && line_col && line_sty && line_w && text && store) {
        int k = 0;
        for (int s = 0; s < p->n_series; s++) {
            if (!p->labels[s]) continue;
            opt[k] = PL_LEGEND_LINE;
            text_col[k] = COL_FG;
            line_col[k] = COL_LINE0 + s % N_LINE_COLOURS;
            line_sty[k] = 1;
            line_w[k] = 2.0;
            text[k] = store + (size_t)k * PLOT_TEXT_MAX;
            plot_text(p->labels[s], text[k], PLOT_TEXT_MAX);
            k++;
        }
        PLFLT w, h;
        plschr(0.0, 0.9);
        pllegend(&w, &h, PL_LEGEND_BACKGROUND | PL_LEGEND_BOUNDING_BOX,
                 legend_corner(p, r, n) | PL_POSITION_INSIDE | PL_POSITION_VIEWPORT, 0.02, 0.03,
                 0.07, COL_BG, COL_GRID, 1, 0, 0, n, opt, 0.8, 1.0, 2.0, 0.0, text_col,
                 (PLCHAR_MATRIX)text, NULL, NULL, NULL, NULL, line_col, line_sty, line_w, NULL,
                 NULL, NULL, NULL);
    }
    free(opt);
    free(text_col);
    free(line_col);
    free(line_sty);
    free(line_w);
    free(text);
    free(store);
}

int sasnav_plot_lines(const char *png_path, const sasnav_line_plot *p)
{
    if (!png_path) return sasnav_set_error(SASNAV_ERR_ARG, "plot_lines: NULL path");
    int max_n = 0;
    int rc = check_lines(p, &max_n);
    if (rc) return rc;
    line_range r;
    if (!line_ranges(p, &r))
        return sasnav_set_error(SASNAV_ERR_ARG, "plot_lines: no finite point to plot%s",
                                p->log_y ? " (log axis needs y > 0)" : "");
    PLFLT *bx = malloc(((size_t)max_n + 1) * sizeof *bx);
    PLFLT *by = malloc(((size_t)max_n + 1) * sizeof *by);
    if (!bx || !by) {
        free(bx);
        free(by);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "plot_lines: out of memory");
    }

    const int width = 1000, height = 650;
    plot_session s;
    rc = session_begin(&s, png_path, width, height);
    if (rc == SASNAV_OK) {
        char t[PLOT_TEXT_MAX], xl[PLOT_TEXT_MAX], yl[PLOT_TEXT_MAX];
        const char *yopt_grid = p->log_y ? "gl" : "g";
        const char *yopt_axis = p->log_y ? "bcinstvl" : "bcinstv";
        plvpor(110.0 / width, 1.0 - 40.0 / width, 80.0 / height, 1.0 - 60.0 / height);
        plwind(r.xmin, r.xmax, r.ymin, r.ymax);
        plcol0(COL_GRID);
        plwidth(1.0);
        plbox("g", 0.0, 0, yopt_grid, 0.0, 0);
        if (isfinite(p->vline) || isfinite(p->vline2)) {
            plcol0(COL_MARK);
            pllsty(2);
            plwidth(1.5);
            if (isfinite(p->vline)) pljoin(p->vline, r.ymin, p->vline, r.ymax);
            if (isfinite(p->vline2)) pljoin(p->vline2, r.ymin, p->vline2, r.ymax);
            pllsty(1);
        }
        plwidth(2.0);
        for (int k = 0; k < p->n_series; k++) {
            plcol0(COL_LINE0 + k % N_LINE_COLOURS);
            draw_series(p, k, bx, by);
        }
        plcol0(COL_FG);
        plwidth(1.0);
        plschr(0.0, 0.95);
        plbox("bcinst", 0.0, 0, yopt_axis, 0.0, 0);
        plschr(0.0, 1.05);
        plmtex("b", 3.0, 0.5, 0.5, plot_text(p->xlabel, xl, sizeof xl));
        plmtex("l", 5.0, 0.5, 0.5, plot_text(p->ylabel, yl, sizeof yl));
        plschr(0.0, 1.25);
        plmtex("t", 1.6, 0.5, 0.5, plot_text(p->title, t, sizeof t));
        draw_legend(p, &r);
    }
    rc = session_end(&s, png_path, rc);
    free(bx);
    free(by);
    return rc;
}
