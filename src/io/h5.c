/* HDF5 files of runs, navigation and images (layout: docs/format.md).
 * The checked low-level access is in h5_util.c; this file maps the
 * library's structures onto the layout and validates what it reads. */
#include "sasnav/io.h"
#include "sasnav/checkpoint.h"

#include "io/h5_util.h"
#include "sasnav/error.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define UNITS_POSE "m, m, rad"

static const char *const RUN_FORMATS[] = {"sasnav-run"};
static const char *const IMAGE_FORMATS[] = {"sasnav-image"};
/* Navigation can be read from a navigation file or from a run. */
static const char *const NAV_FORMATS[] = {"sasnav-nav", "sasnav-run"};

static int floats_finite(const float *v, size_t n, size_t *bad)
{
    for (size_t k = 0; k < n; k++)
        if (!isfinite(v[k])) {
            *bad = k;
            return 0;
        }
    return 1;
}

/* --- navigation: <group>/tx and <group>/array, [n_pings][3] (x, y, theta) */

static int poses_finite(int n, const sasnav_ping_pose *poses)
{
    for (int p = 0; p < n; p++) {
        const sasnav_pose *q[2] = {&poses[p].tx, &poses[p].array};
        for (int k = 0; k < 2; k++)
            if (!isfinite(q[k]->x) || !isfinite(q[k]->y) || !isfinite(q[k]->theta)) return 0;
    }
    return 1;
}

static int poses_write(h5_ctx *c, const char *group, int n, const sasnav_ping_pose *poses)
{
    char name[32];
    double *buf = malloc((size_t)n * 3 * sizeof *buf);
    if (!buf) return h5_fail(c, SASNAV_ERR_NOMEM, "cannot allocate %d poses", n);
    int rc = h5_create_group(c, group);
    hsize_t dims[2] = {(hsize_t)n, 3};
    for (int which = 0; which < 2 && !rc; which++) {
        for (int p = 0; p < n; p++) {
            sasnav_pose q = which == 0 ? poses[p].tx : poses[p].array;
            buf[3 * p] = q.x;
            buf[3 * p + 1] = q.y;
            buf[3 * p + 2] = q.theta;
        }
        snprintf(name, sizeof name, "%s/%s", group, which == 0 ? "tx" : "array");
        rc = h5_write_dataset(c, name, H5_REAL, 2, dims, NULL, buf, UNITS_POSE);
    }
    free(buf);
    return rc;
}

/* Number of pings of a navigation group (rows of <group>/tx). */
static int poses_count(h5_ctx *c, const char *group, int *n)
{
    char name[32];
    snprintf(name, sizeof name, "%s/tx", group);
    hsize_t dims[2];
    hid_t dset;
    int rc = h5_open_dataset(c, name, H5_REAL, 2, dims, &dset);
    if (rc) return rc;
    H5Dclose(dset);
    if (dims[1] != 3)
        return h5_fail(c, SASNAV_ERR_FORMAT, "%s has %llu columns, expected 3 (x, y, theta)", name,
                       (unsigned long long)dims[1]);
    *n = (int)dims[0];
    return SASNAV_OK;
}

static int poses_read(h5_ctx *c, const char *group, int n, sasnav_ping_pose *poses)
{
    char name[32];
    double *buf = malloc((size_t)n * 3 * sizeof *buf);
    if (!buf) return h5_fail(c, SASNAV_ERR_NOMEM, "cannot allocate %d poses", n);
    hsize_t dims[2] = {(hsize_t)n, 3};
    int rc = SASNAV_OK;
    for (int which = 0; which < 2 && !rc; which++) {
        snprintf(name, sizeof name, "%s/%s", group, which == 0 ? "tx" : "array");
        rc = h5_read_dataset_dims(c, name, H5_REAL, 2, dims, buf);
        for (int p = 0; p < n && !rc; p++) {
            sasnav_pose q = {buf[3 * p], buf[3 * p + 1], buf[3 * p + 2]};
            if (!isfinite(q.x) || !isfinite(q.y) || !isfinite(q.theta))
                rc = h5_fail(c, SASNAV_ERR_FORMAT, "%s: pose of %s %d is not finite", name,
                             strcmp(group, "/channels") ? "ping" : "channel", p);
            else if (which == 0)
                poses[p].tx = q;
            else
                poses[p].array = q;
        }
    }
    free(buf);
    return rc;
}

/* --- runs ----------------------------------------------------------------- */

static int system_write(h5_ctx *c, const sasnav_run *run)
{
    const char *g = "/system";
    const sasnav_system *s = &run->sys;
    int rc = h5_create_group(c, g);
    if (!rc) rc = h5_write_attr_double(c, g, "sound_speed", s->sound_speed);
    if (!rc) rc = h5_write_attr_double(c, g, "f0", s->f0);
    if (!rc) rc = h5_write_attr_double(c, g, "bandwidth", s->bandwidth);
    if (!rc) rc = h5_write_attr_double(c, g, "sample_rate", s->sample_rate);
    if (!rc) rc = h5_write_attr_int(c, g, "taper", (int)s->taper);
    if (!rc) rc = h5_write_attr_int(c, g, "attenuation", (int)s->attenuation);
    if (!rc) rc = h5_write_attr_int(c, g, "beam_pattern", s->beam_pattern);
    if (!rc) rc = h5_write_attr_double(c, g, "t0", run->win.t0);
    if (!rc) rc = h5_write_attr_double(c, g, "ping_spacing", run->ping_spacing);
    if (!rc) rc = h5_write_attr_double(c, g, "speed", run->speed);
    if (!rc) rc = h5_write_attr_double(c, g, "tx_lag", run->tx_lag);
    if (!rc) rc = h5_write_attr_double(c, g, "range_of_interest", run->range_of_interest);
    return rc;
}

static int array_write(h5_ctx *c, const sasnav_array *a)
{
    const char *g = "/array";
    hsize_t dims[1] = {(hsize_t)a->n_rx};
    int rc = h5_create_group(c, g);
    if (!rc) rc = h5_write_dataset(c, "/array/rx_u", H5_REAL, 1, dims, NULL, a->rx_u, "m");
    if (!rc) rc = h5_write_attr_double(c, g, "rx_length", a->rx_length);
    if (!rc) rc = h5_write_attr_double(c, g, "tx_length", a->tx_length);
    if (!rc) rc = h5_write_attr_double(c, g, "rx_height", a->rx_height);
    if (!rc) rc = h5_write_attr_double(c, g, "tx_height", a->tx_height);
    if (!rc && a->per_channel) {
        double z[4 * SASNAV_MAX_RX];
        for (int l = 0; l < a->n_rx; l++) {
            z[4 * l] = a->size[l].rx_length;
            z[4 * l + 1] = a->size[l].tx_length;
            z[4 * l + 2] = a->size[l].rx_height;
            z[4 * l + 3] = a->size[l].tx_height;
        }
        hsize_t d2[2] = {(hsize_t)a->n_rx, 4};
        rc = h5_write_dataset(c, "/array/sizes", H5_REAL, 2, d2, NULL, z, "m");
    }
    return rc;
}

/* Format version of a run: 2 with channels of their own (poses or sizes). */
static int run_version(const sasnav_run *run)
{
    return run->channel_offset || run->array.per_channel ? 2 : 1;
}

/* --- aiding: /aiding/time, yaw_rate(+_sigma), velocity(+_sigma) ---------- */

static int aiding_write(h5_ctx *c, int n, const sasnav_aiding *a)
{
    hsize_t d1[1] = {(hsize_t)n}, d2[2] = {(hsize_t)n, 2};
    int rc = h5_create_group(c, "/aiding");
    if (!rc) rc = h5_write_dataset(c, "/aiding/time", H5_REAL, 1, d1, NULL, a->time, "s");
    if (!rc && a->yaw_rate) {
        rc = h5_write_dataset(c, "/aiding/yaw_rate", H5_REAL, 1, d1, NULL, a->yaw_rate, "rad/s");
        if (!rc)
            rc = h5_write_dataset(c, "/aiding/yaw_rate_sigma", H5_REAL, 1, d1, NULL,
                                  a->yaw_rate_sigma, "rad/s");
    }
    if (!rc && a->velocity) {
        rc = h5_write_dataset(c, "/aiding/velocity", H5_REAL, 2, d2, NULL, a->velocity, "m/s");
        if (!rc)
            rc = h5_write_dataset(c, "/aiding/velocity_sigma", H5_REAL, 2, d2, NULL,
                                  a->velocity_sigma, "m/s");
    }
    return rc;
}

/* Reads /aiding into run->aiding (absent: none). Shapes must match the
 * run's pings; values are checked by sasnav_aiding_check. */
static int aiding_read(h5_ctx *c, sasnav_run *run)
{
    if (!h5_exists(c, "/aiding")) return SASNAV_OK;
    int yaw = h5_exists(c, "/aiding/yaw_rate"), vel = h5_exists(c, "/aiding/velocity");
    if (yaw != h5_exists(c, "/aiding/yaw_rate_sigma"))
        return h5_fail(c, SASNAV_ERR_FORMAT, "/aiding/yaw_rate and yaw_rate_sigma come together");
    if (vel != h5_exists(c, "/aiding/velocity_sigma"))
        return h5_fail(c, SASNAV_ERR_FORMAT, "/aiding/velocity and velocity_sigma come together");
    int rc = sasnav_run_alloc_aiding(run, yaw, vel);
    if (rc) return h5_reframe(c, rc, "/aiding");
    sasnav_aiding *a = run->aiding;
    hsize_t d1[1] = {(hsize_t)run->n_pings}, d2[2] = {(hsize_t)run->n_pings, 2};
    rc = h5_read_dataset_dims(c, "/aiding/time", H5_REAL, 1, d1, a->time);
    if (!rc && yaw) rc = h5_read_dataset_dims(c, "/aiding/yaw_rate", H5_REAL, 1, d1, a->yaw_rate);
    if (!rc && yaw)
        rc = h5_read_dataset_dims(c, "/aiding/yaw_rate_sigma", H5_REAL, 1, d1, a->yaw_rate_sigma);
    if (!rc && vel) rc = h5_read_dataset_dims(c, "/aiding/velocity", H5_REAL, 2, d2, a->velocity);
    if (!rc && vel)
        rc = h5_read_dataset_dims(c, "/aiding/velocity_sigma", H5_REAL, 2, d2, a->velocity_sigma);
    if (!rc) {
        rc = sasnav_aiding_check(a, run->n_pings);
        if (rc) rc = h5_reframe(c, rc, "/aiding");
    }
    return rc;
}

/* Reads /channels (format version 2; absent: none) into run->channel_offset. */
static int channels_read(h5_ctx *c, sasnav_run *run)
{
    if (!h5_exists(c, "/channels")) return SASNAV_OK;
    if (c->version < 2)
        return h5_fail(c, SASNAV_ERR_FORMAT, "/channels needs format_version 2 (the file says %d)", c->version);
    int n = 0;
    int rc = poses_count(c, "/channels", &n);
    if (!rc && n != run->array.n_rx)
        rc = h5_fail(c, SASNAV_ERR_FORMAT, "/channels/tx has %d channels, /raw has %d", n, run->array.n_rx);
    sasnav_ping_pose off[SASNAV_MAX_RX];
    if (!rc) rc = poses_read(c, "/channels", n, off);
    if (!rc) {
        rc = sasnav_run_set_channel_offset(run, off);
        if (rc) rc = h5_reframe(c, rc, "/channels");
    }
    return rc;
}

int sasnav_run_write(const char *path, const sasnav_run *run)
{
    if (!path) return sasnav_set_error(SASNAV_ERR_ARG, "run file path is NULL");
    int rc = sasnav_run_check(run);
    if (rc) return rc;
    h5_ctx c;
    h5_begin(&c, path);
    rc = h5_create_tmp_version(&c, "sasnav-run", run_version(run));
    hsize_t dims[3] = {(hsize_t)run->n_pings, (hsize_t)run->array.n_rx, (hsize_t)run->win.n_samples};
    hsize_t ping_chunk[3] = {1, dims[1], dims[2]};
    if (!rc) rc = h5_write_dataset(&c, "/raw", H5_COMPLEX, 3, dims, ping_chunk, run->raw, "1");
    if (!rc) rc = system_write(&c, run);
    if (!rc) rc = array_write(&c, &run->array);
    if (!rc) rc = poses_write(&c, "/nav", run->n_pings, run->nav);
    if (!rc && run->truth) rc = poses_write(&c, "/truth", run->n_pings, run->truth);
    if (!rc && run->aiding) rc = aiding_write(&c, run->n_pings, run->aiding);
    if (!rc && run->channel_offset) rc = poses_write(&c, "/channels", run->array.n_rx, run->channel_offset);
    if (!rc) rc = h5_commit(&c);
    h5_end(&c);
    return rc;
}

static double *axis_values(double v0, double d, int n)
{
    double *v = malloc((size_t)n * sizeof *v);
    if (v)
        for (int k = 0; k < n; k++) v[k] = v0 + k * d;
    return v;
}

/* --- runs written ping by ping -------------------------------------------- */

struct sasnav_run_writer {
    h5_ctx c;
    char *path;
    hid_t raw;
    sasnav_run header; /* shapes only (sys, array, win, n_pings) */
    size_t per_ping;
    int version;       /* 2 when the header had channel offsets */
};

int sasnav_run_writer_open(const char *path, const sasnav_run *header, sasnav_run_writer **out)
{
    if (!out) return sasnav_set_error(SASNAV_ERR_ARG, "run writer output pointer is NULL");
    *out = NULL;
    if (!path || !header) return sasnav_set_error(SASNAV_ERR_ARG, "run writer needs a path and a header");
    int rc = sasnav_system_check(&header->sys);
    if (!rc) rc = sasnav_array_check(&header->array);
    if (rc) return rc;
    if (header->n_pings < 1 || header->win.n_samples < 1)
        return sasnav_set_error(SASNAV_ERR_ARG, "run writer needs >= 1 ping and >= 1 sample");
    sasnav_run_writer *w = calloc(1, sizeof *w);
    char *copy = w ? strdup(path) : NULL;
    if (!w || !copy) {
        free(w);
        free(copy);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    }
    w->path = copy;
    w->raw = H5I_INVALID_HID;
    w->header = *header;
    w->header.raw = NULL;
    w->header.nav = w->header.truth = NULL;
    w->header.aiding = NULL;
    w->version = run_version(header);
    w->header.channel_offset = NULL;
    memset(&w->header.source, 0, sizeof w->header.source);
    w->per_ping = (size_t)header->array.n_rx * (size_t)header->win.n_samples;
    h5_begin(&w->c, w->path);
    rc = h5_create_tmp_version(&w->c, "sasnav-run", w->version);
    hsize_t dims[3] = {(hsize_t)header->n_pings, (hsize_t)header->array.n_rx,
                       (hsize_t)header->win.n_samples};
    hsize_t chunk[3] = {1, dims[1], dims[2]};
    if (!rc) rc = h5_create_dataset(&w->c, "/raw", H5_COMPLEX, 3, dims, chunk, "1", &w->raw);
    if (rc) {
        sasnav_run_writer_abort(w);
        return rc;
    }
    *out = w;
    return SASNAV_OK;
}

int sasnav_run_writer_put(sasnav_run_writer *w, int p, const sasnav_cfloat *samples)
{
    if (!w || !samples || p < 0 || p >= w->header.n_pings)
        return sasnav_set_error(SASNAV_ERR_ARG, "run writer: bad ping %d", p);
    size_t bad;
    if (!floats_finite((const float *)samples, 2 * w->per_ping, &bad))
        return sasnav_set_error(SASNAV_ERR_ARG, "ping %d to write: sample %zu of channel %zu is not finite", p,
                                bad / 2 % (size_t)w->header.win.n_samples,
                                bad / 2 / (size_t)w->header.win.n_samples);
    hsize_t start[3] = {(hsize_t)p, 0, 0},
            count[3] = {1, (hsize_t)w->header.array.n_rx, (hsize_t)w->header.win.n_samples};
    return h5_write_block(&w->c, w->raw, "/raw", H5_COMPLEX, 3, start, count, samples);
}

int sasnav_run_writer_get(sasnav_run_writer *w, int p, sasnav_cfloat *samples)
{
    if (!w || !samples || p < 0 || p >= w->header.n_pings)
        return sasnav_set_error(SASNAV_ERR_ARG, "run writer: bad ping %d", p);
    return h5_read_rows(&w->c, w->raw, "/raw", H5_COMPLEX, (hsize_t)p, 1, samples);
}

int sasnav_run_writer_finish(sasnav_run_writer *w, const sasnav_run *run)
{
    if (!w) return sasnav_set_error(SASNAV_ERR_ARG, "run writer is NULL");
    int rc = run ? SASNAV_OK : sasnav_set_error(SASNAV_ERR_ARG, "run writer: no run to finish with");
    if (!rc && (run->n_pings != w->header.n_pings || run->array.n_rx != w->header.array.n_rx ||
                run->win.n_samples != w->header.win.n_samples))
        rc = sasnav_set_error(SASNAV_ERR_ARG, "run writer: the run's shape differs from the one opened");
    if (!rc && run_version(run) != w->version)
        rc = sasnav_set_error(SASNAV_ERR_ARG, "run writer: channel offsets and per-channel sizes must be "
                                              "given when the writer is opened (they set the format version)");
    if (!rc) rc = sasnav_run_check_header(run);
    if (!rc) {
        H5Dclose(w->raw);
        w->raw = H5I_INVALID_HID;
        rc = system_write(&w->c, run);
    }
    if (!rc) rc = array_write(&w->c, &run->array);
    if (!rc) rc = poses_write(&w->c, "/nav", run->n_pings, run->nav);
    if (!rc && run->truth) rc = poses_write(&w->c, "/truth", run->n_pings, run->truth);
    if (!rc && run->aiding) rc = aiding_write(&w->c, run->n_pings, run->aiding);
    if (!rc && run->channel_offset)
        rc = poses_write(&w->c, "/channels", run->array.n_rx, run->channel_offset);
    if (!rc) rc = h5_commit(&w->c);
    sasnav_run_writer_abort(w); /* frees; after a commit nothing is left to remove */
    return rc;
}

void sasnav_run_writer_abort(sasnav_run_writer *w)
{
    if (!w) return;
    if (w->raw >= 0) H5Dclose(w->raw);
    h5_end(&w->c); /* closes the file, removes the temporary one if any */
    free(w->path);
    free(w);
}

/* --- images written tile by tile ------------------------------------------- */

struct sasnav_image_writer {
    h5_ctx c;
    char *path;
    hid_t image;
    sasnav_grid grid;
};

int sasnav_image_writer_open(const char *path, const sasnav_grid *grid, int tile_cols, int tile_rows,
                             sasnav_image_writer **out)
{
    if (!out) return sasnav_set_error(SASNAV_ERR_ARG, "image writer output pointer is NULL");
    *out = NULL;
    if (!path) return sasnav_set_error(SASNAV_ERR_ARG, "image writer needs a path");
    int rc = sasnav_grid_check(grid);
    if (rc) return rc;
    sasnav_image_writer *w = calloc(1, sizeof *w);
    char *copy = w ? strdup(path) : NULL;
    double *x = axis_values(grid->x0, grid->dx, grid->nx), *y = axis_values(grid->y0, grid->dy, grid->ny);
    if (!w || !copy || !x || !y) {
        free(w);
        free(copy);
        free(x);
        free(y);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    }
    w->path = copy;
    w->image = H5I_INVALID_HID;
    w->grid = *grid;
    h5_begin(&w->c, w->path);
    hsize_t dims[2] = {(hsize_t)grid->ny, (hsize_t)grid->nx};
    hsize_t chunk[2] = {(hsize_t)(tile_rows > 0 && tile_rows < grid->ny ? tile_rows : grid->ny),
                        (hsize_t)(tile_cols > 0 && tile_cols < grid->nx ? tile_cols : grid->nx)};
    rc = h5_create_tmp(&w->c, "sasnav-image");
    if (!rc) rc = h5_create_dataset(&w->c, "/image", H5_COMPLEX, 2, dims, chunk, "1", &w->image);
    if (!rc) rc = h5_write_attr_double(&w->c, "/image", "x0", grid->x0);
    if (!rc) rc = h5_write_attr_double(&w->c, "/image", "dx", grid->dx);
    if (!rc) rc = h5_write_attr_double(&w->c, "/image", "y0", grid->y0);
    if (!rc) rc = h5_write_attr_double(&w->c, "/image", "dy", grid->dy);
    if (!rc) rc = h5_write_dataset(&w->c, "/x", H5_REAL, 1, &dims[1], NULL, x, "m");
    if (!rc) rc = h5_write_dataset(&w->c, "/y", H5_REAL, 1, &dims[0], NULL, y, "m");
    free(x);
    free(y);
    if (rc) {
        sasnav_image_writer_abort(w);
        return rc;
    }
    *out = w;
    return SASNAV_OK;
}

int sasnav_image_writer_put(sasnav_image_writer *w, int col0, int col1, int row0, int row1,
                            const sasnav_cfloat *tile)
{
    if (!w || !tile || col0 < 0 || row0 < 0 || col1 > w->grid.nx || row1 > w->grid.ny || col0 >= col1 ||
        row0 >= row1)
        return sasnav_set_error(SASNAV_ERR_ARG, "image writer: block %d..%d x %d..%d outside the grid", col0,
                                col1 - 1, row0, row1 - 1);
    size_t bad, n = (size_t)(col1 - col0) * (size_t)(row1 - row0);
    if (!floats_finite((const float *)tile, 2 * n, &bad))
        return sasnav_set_error(SASNAV_ERR_ARG, "image pixel (%zu, %zu) is not finite",
                                row0 + bad / 2 / (size_t)(col1 - col0), col0 + bad / 2 % (size_t)(col1 - col0));
    hsize_t start[2] = {(hsize_t)row0, (hsize_t)col0}, count[2] = {(hsize_t)(row1 - row0), (hsize_t)(col1 - col0)};
    return h5_write_block(&w->c, w->image, "/image", H5_COMPLEX, 2, start, count, tile);
}

int sasnav_image_writer_finish(sasnav_image_writer *w)
{
    if (!w) return sasnav_set_error(SASNAV_ERR_ARG, "image writer is NULL");
    H5Dclose(w->image);
    w->image = H5I_INVALID_HID;
    int rc = h5_commit(&w->c);
    sasnav_image_writer_abort(w);
    return rc;
}

void sasnav_image_writer_abort(sasnav_image_writer *w)
{
    if (!w) return;
    if (w->image >= 0) H5Dclose(w->image);
    h5_end(&w->c);
    free(w->path);
    free(w);
}

/* An integer attribute that must lie in [lo, hi]. */
static int attr_int_range(h5_ctx *c, const char *obj, const char *name, int lo, int hi, int *value)
{
    int rc = h5_read_attr_int(c, obj, name, value);
    if (rc) return rc;
    if (*value < lo || *value > hi)
        return h5_fail(c, SASNAV_ERR_FORMAT, "attribute '%s' of %s is %d, expected %d..%d", name, obj,
                       *value, lo, hi);
    return SASNAV_OK;
}

/* Reads /system into the run header (everything but sizes and arrays). */
static int system_read(h5_ctx *c, sasnav_run *h)
{
    const char *g = "/system";
    sasnav_system *s = &h->sys;
    int taper = 0, atten = 0;
    int rc = h5_read_attr_double(c, g, "sound_speed", &s->sound_speed);
    if (!rc) rc = h5_read_attr_double(c, g, "f0", &s->f0);
    if (!rc) rc = h5_read_attr_double(c, g, "bandwidth", &s->bandwidth);
    if (!rc) rc = h5_read_attr_double(c, g, "sample_rate", &s->sample_rate);
    if (!rc) rc = attr_int_range(c, g, "taper", SASNAV_TAPER_NONE, SASNAV_TAPER_HAMMING, &taper);
    if (!rc) rc = attr_int_range(c, g, "attenuation", SASNAV_ATTEN_EXPLODING, SASNAV_ATTEN_NONE, &atten);
    if (!rc) rc = attr_int_range(c, g, "beam_pattern", 0, 1, &s->beam_pattern);
    if (!rc) rc = h5_read_attr_double(c, g, "t0", &h->win.t0);
    if (!rc) rc = h5_read_attr_double(c, g, "ping_spacing", &h->ping_spacing);
    if (!rc) rc = h5_read_attr_double(c, g, "speed", &h->speed);
    if (!rc) rc = h5_read_attr_double(c, g, "tx_lag", &h->tx_lag);
    if (!rc) rc = h5_read_attr_double(c, g, "range_of_interest", &h->range_of_interest);
    if (rc) return rc;
    s->taper = (sasnav_taper)taper;
    s->attenuation = (sasnav_attenuation)atten;
    rc = sasnav_system_check(s);
    if (rc) return h5_reframe(c, rc, g);
    return SASNAV_OK;
}

static int array_read(h5_ctx *c, int n_rx, sasnav_array *a)
{
    const char *g = "/array";
    memset(a, 0, sizeof *a);
    if (n_rx > SASNAV_MAX_RX)
        return h5_fail(c, SASNAV_ERR_FORMAT, "/raw has %d channels, at most %d are supported", n_rx,
                       SASNAV_MAX_RX);
    a->n_rx = n_rx;
    hsize_t dims[1] = {(hsize_t)n_rx};
    int rc = h5_read_dataset_dims(c, "/array/rx_u", H5_REAL, 1, dims, a->rx_u);
    if (!rc) rc = h5_read_attr_double(c, g, "rx_length", &a->rx_length);
    if (!rc) rc = h5_read_attr_double(c, g, "tx_length", &a->tx_length);
    if (!rc) rc = h5_read_attr_double(c, g, "rx_height", &a->rx_height);
    if (!rc) rc = h5_read_attr_double(c, g, "tx_height", &a->tx_height);
    if (rc) return rc;
    if (h5_exists(c, "/array/sizes")) {
        if (c->version < 2)
            return h5_fail(c, SASNAV_ERR_FORMAT, "/array/sizes needs format_version 2 (the file says %d)",
                           c->version);
        double z[4 * SASNAV_MAX_RX];
        hsize_t d2[2] = {(hsize_t)n_rx, 4};
        rc = h5_read_dataset_dims(c, "/array/sizes", H5_REAL, 2, d2, z);
        if (rc) return rc;
        sasnav_channel_size sz[SASNAV_MAX_RX];
        for (int l = 0; l < n_rx; l++) {
            sasnav_channel_size zl = {z[4 * l], z[4 * l + 1], z[4 * l + 2], z[4 * l + 3]};
            sz[l] = zl;
        }
        rc = sasnav_array_set_sizes(a, sz);
        if (rc) return h5_reframe(c, rc, "/array/sizes");
    }
    rc = sasnav_array_check(a);
    if (rc) return h5_reframe(c, rc, g);
    return SASNAV_OK;
}

/* Reads /raw into the allocated run and checks every sample. */
static int raw_read(h5_ctx *c, hid_t dset, sasnav_run *run)
{
    int rc = h5_read_dataset(c, dset, "/raw", H5_COMPLEX, run->raw);
    if (rc) return rc;
    size_t per_channel = (size_t)run->win.n_samples, per_ping = per_channel * (size_t)run->array.n_rx;
    size_t bad;
    if (!floats_finite((const float *)run->raw, 2 * per_ping * (size_t)run->n_pings, &bad)) {
        bad /= 2;
        return h5_fail(c, SASNAV_ERR_FORMAT, "/raw: sample %zu of channel %zu of ping %zu is not finite",
                       bad % per_channel, (bad % per_ping) / per_channel, bad / per_ping);
    }
    return SASNAV_OK;
}

/* A streamed run's source: the open file and its /raw dataset. */
typedef struct {
    char *path;
    hid_t file, raw;
    size_t per_ping, per_channel;
} run_stream;

static void stream_close(void *ctx)
{
    run_stream *st = ctx;
    if (!st) return;
    if (st->raw >= 0) H5Dclose(st->raw);
    if (st->file >= 0) H5Fclose(st->file);
    free(st->path);
    free(st);
}

static int stream_read(void *ctx, int p, sasnav_cfloat *out)
{
    run_stream *st = ctx;
    h5_ctx c;
    h5_begin(&c, st->path); /* messages name the file; c.file stays unset */
    int rc = h5_read_rows(&c, st->raw, "/raw", H5_COMPLEX, (hsize_t)p, 1, out);
    size_t bad;
    if (!rc && !floats_finite((const float *)out, 2 * st->per_ping, &bad)) {
        bad /= 2;
        rc = h5_fail(&c, SASNAV_ERR_FORMAT, "/raw: sample %zu of channel %zu of ping %d is not finite",
                     bad % st->per_channel, bad / st->per_channel, p);
    }
    h5_end(&c);
    return rc;
}

/* Everything after the file is open; *out is set only on success. With
 * `streamed`, the samples are left in the file and the run reads them
 * through a run_stream that takes over c->file. */
static int run_read_open(h5_ctx *c, int streamed, sasnav_run **out)
{
    sasnav_run h;
    memset(&h, 0, sizeof h);
    hsize_t dims[3];
    hid_t raw;
    int rc = system_read(c, &h);
    if (rc) return rc;
    rc = h5_open_dataset(c, "/raw", H5_COMPLEX, 3, dims, &raw);
    if (rc) return rc;
    h.n_pings = (int)dims[0];
    h.win.n_samples = (int)dims[2];
    rc = array_read(c, (int)dims[1], &h.array);
    int nav_pings = 0, with_truth = h5_exists(c, "/truth");
    if (!rc) rc = poses_count(c, "/nav", &nav_pings);
    if (!rc && nav_pings != h.n_pings)
        rc = h5_fail(c, SASNAV_ERR_FORMAT, "/nav/tx has %d pings, /raw has %d", nav_pings, h.n_pings);

    sasnav_run *run = NULL;
    if (!rc && streamed) {
        run_stream *st = calloc(1, sizeof *st);
        char *path = st ? strdup(c->path) : NULL;
        if (!st || !path) {
            free(st);
            rc = sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
        } else {
            st->path = path;
            st->raw = raw;
            st->file = c->file;
            st->per_channel = (size_t)h.win.n_samples;
            st->per_ping = st->per_channel * (size_t)h.array.n_rx;
            raw = H5I_INVALID_HID;
            c->file = H5I_INVALID_HID; /* the source owns the file now */
            sasnav_ping_source src = {stream_read, stream_close, st};
            rc = sasnav_run_alloc_streamed(&h.sys, &h.array, &h.win, h.n_pings, with_truth, &src, &run);
            if (rc) rc = h5_reframe(c, rc, "/raw");
            else c->file = st->file; /* borrowed for the reads below */
            /* Every ping read once and checked now, one at a time: a
             * corrupt or non-finite sample is refused up front, as by
             * sasnav_run_read, not hours into a survey's processing. */
            sasnav_cfloat *buf = rc ? NULL : malloc(sizeof *buf * st->per_ping);
            if (!rc && !buf) rc = sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory for a ping");
            for (int p = 0; !rc && p < h.n_pings; p++) {
                rc = h5_read_rows(c, st->raw, "/raw", H5_COMPLEX, (hsize_t)p, 1, buf);
                size_t bad;
                if (!rc && !floats_finite((const float *)buf, 2 * st->per_ping, &bad)) {
                    bad /= 2;
                    rc = h5_fail(c, SASNAV_ERR_FORMAT, "/raw: sample %zu of channel %zu of ping %d is not finite",
                                 bad % st->per_channel, bad / st->per_channel, p);
                }
            }
            free(buf);
        }
    } else if (!rc) {
        rc = sasnav_run_alloc(&h.sys, &h.array, &h.win, h.n_pings, with_truth, &run);
        if (rc) rc = h5_reframe(c, rc, "/raw");
        if (!rc) rc = raw_read(c, raw, run);
    }
    if (raw >= 0) H5Dclose(raw);
    if (!rc) rc = poses_read(c, "/nav", run->n_pings, run->nav);
    if (!rc && with_truth) rc = poses_read(c, "/truth", run->n_pings, run->truth);
    if (!rc) rc = aiding_read(c, run);
    if (!rc) rc = channels_read(c, run);
    if (!rc) {
        run->ping_spacing = h.ping_spacing;
        run->speed = h.speed;
        run->tx_lag = h.tx_lag;
        run->range_of_interest = h.range_of_interest;
        rc = sasnav_run_check(run);
        if (rc) rc = h5_reframe(c, rc, "run");
    }
    if (streamed && run) c->file = H5I_INVALID_HID; /* the run's source closes it */
    if (rc) {
        sasnav_run_free(run);
        return rc;
    }
    *out = run;
    return SASNAV_OK;
}

static int run_load(const char *path, int streamed, sasnav_run **run)
{
    if (!run) return sasnav_set_error(SASNAV_ERR_ARG, "run output pointer is NULL");
    *run = NULL;
    if (!path) return sasnav_set_error(SASNAV_ERR_ARG, "run file path is NULL");
    h5_ctx c;
    h5_begin(&c, path);
    int rc = h5_open_read(&c, RUN_FORMATS, 1);
    if (!rc) rc = run_read_open(&c, streamed, run);
    h5_end(&c);
    return rc;
}

int sasnav_run_read(const char *path, sasnav_run **run) { return run_load(path, 0, run); }

int sasnav_run_open(const char *path, sasnav_run **run) { return run_load(path, 1, run); }

/* --- navigation files ------------------------------------------------------ */

/* /nav_sigma is written from and read into sasnav_pose rows directly. */
_Static_assert(sizeof(sasnav_pose) == 3 * sizeof(double), "sasnav_pose is three doubles");

/* Standard deviations: n rows of three finite values >= 0. */
static int sigma_ok(int n, const sasnav_pose *sigma)
{
    for (int p = 0; p < n; p++)
        if (!(sigma[p].x >= 0) || !(sigma[p].y >= 0) || !(sigma[p].theta >= 0) || !isfinite(sigma[p].x) ||
            !isfinite(sigma[p].y) || !isfinite(sigma[p].theta))
            return 0;
    return 1;
}

int sasnav_nav_write(const char *path, int n_pings, const sasnav_ping_pose *nav,
                     const sasnav_ping_pose *truth)
{
    return sasnav_nav_write_sigma(path, n_pings, nav, truth, NULL);
}

int sasnav_nav_write_sigma(const char *path, int n_pings, const sasnav_ping_pose *nav,
                           const sasnav_ping_pose *truth, const sasnav_pose *sigma)
{
    if (!path || !nav || n_pings < 1)
        return sasnav_set_error(SASNAV_ERR_ARG, "navigation write needs a path and >= 1 pose");
    if (!poses_finite(n_pings, nav) || (truth && !poses_finite(n_pings, truth)))
        return sasnav_set_error(SASNAV_ERR_ARG, "navigation to write is not finite");
    if (sigma && !sigma_ok(n_pings, sigma))
        return sasnav_set_error(SASNAV_ERR_ARG, "standard deviations to write are not finite and >= 0");
    h5_ctx c;
    h5_begin(&c, path);
    int rc = h5_create_tmp(&c, "sasnav-nav");
    if (!rc) rc = poses_write(&c, "/nav", n_pings, nav);
    if (!rc && truth) rc = poses_write(&c, "/truth", n_pings, truth);
    if (!rc && sigma) {
        hsize_t dims[2] = {(hsize_t)n_pings, 3};
        /* (sasnav_pose is three doubles: x, y, theta) */
        rc = h5_write_dataset(&c, "/nav_sigma", H5_REAL, 2, dims, NULL, sigma, UNITS_POSE);
    }
    if (!rc) rc = h5_commit(&c);
    h5_end(&c);
    return rc;
}

static int nav_read_open(h5_ctx *c, int *n_pings, sasnav_ping_pose **nav, sasnav_ping_pose **truth)
{
    int n = 0;
    int rc = poses_count(c, "/nav", &n);
    if (rc) return rc;
    int with_truth = truth && h5_exists(c, "/truth");
    sasnav_ping_pose *pn = calloc((size_t)n, sizeof *pn);
    sasnav_ping_pose *pt = with_truth ? calloc((size_t)n, sizeof *pt) : NULL;
    if (!pn || (with_truth && !pt)) rc = h5_fail(c, SASNAV_ERR_NOMEM, "cannot allocate %d poses", n);
    if (!rc) rc = poses_read(c, "/nav", n, pn);
    if (!rc && with_truth) rc = poses_read(c, "/truth", n, pt);
    /* the runs' plausibility (a position of 1e300 m read, then cast into
     * a grid size, was undefined behaviour; found by review) */
    char why[256];
    if (!rc && (sasnav_poses_check(pn, n, "navigation") || (with_truth && sasnav_poses_check(pt, n, "true pose")))) {
        snprintf(why, sizeof why, "%s", sasnav_last_error()); /* h5_fail rewrites that buffer */
        rc = h5_fail(c, SASNAV_ERR_FORMAT, "%s", why);
    }
    if (rc) {
        free(pn);
        free(pt);
        return rc;
    }
    *n_pings = n;
    *nav = pn;
    if (truth) *truth = pt;
    return SASNAV_OK;
}

int sasnav_nav_read_sigma(const char *path, int *n_pings, sasnav_pose **sigma)
{
    if (sigma) *sigma = NULL;
    if (n_pings) *n_pings = 0;
    if (!path || !n_pings || !sigma)
        return sasnav_set_error(SASNAV_ERR_ARG, "standard deviations read needs a path and output pointers");
    h5_ctx c;
    h5_begin(&c, path);
    int rc = h5_open_read(&c, NAV_FORMATS, 2), n = 0;
    sasnav_ping_pose *pn = NULL;
    /* the navigation checked as sasnav_nav_read checks it (found by
     * review: counting /nav/tx's rows alone let a file through that the
     * navigation reader refuses) */
    if (!rc) rc = nav_read_open(&c, &n, &pn, NULL);
    free(pn);
    sasnav_pose *s = NULL;
    if (!rc && n >= 1 && h5_exists(&c, "/nav_sigma")) {
        s = malloc(sizeof *s * (size_t)n);
        hsize_t dims[2] = {(hsize_t)n, 3};
        if (!s) rc = h5_fail(&c, SASNAV_ERR_NOMEM, "cannot allocate %d standard deviations", n);
        if (!rc) rc = h5_read_dataset_dims(&c, "/nav_sigma", H5_REAL, 2, dims, s);
        if (!rc && !sigma_ok(n, s))
            rc = h5_fail(&c, SASNAV_ERR_FORMAT, "/nav_sigma: a standard deviation is not finite and >= 0");
    }
    h5_end(&c);
    if (rc) {
        free(s);
        return rc;
    }
    *n_pings = n;
    *sigma = s;
    return SASNAV_OK;
}

int sasnav_nav_read(const char *path, int *n_pings, sasnav_ping_pose **nav, sasnav_ping_pose **truth)
{
    if (truth) *truth = NULL;
    if (nav) *nav = NULL;
    if (n_pings) *n_pings = 0;
    if (!path || !n_pings || !nav)
        return sasnav_set_error(SASNAV_ERR_ARG, "navigation read needs a path and output pointers");
    h5_ctx c;
    h5_begin(&c, path);
    int rc = h5_open_read(&c, NAV_FORMATS, 2);
    if (!rc) rc = nav_read_open(&c, n_pings, nav, truth);
    h5_end(&c);
    return rc;
}

/* --- images ------------------------------------------------------------------ */


int sasnav_image_write(const char *path, const sasnav_grid *grid, const sasnav_cfloat *image)
{
    if (!path || !image) return sasnav_set_error(SASNAV_ERR_ARG, "image write needs a path and an image");
    int rc = sasnav_grid_check(grid);
    if (rc) return rc;
    size_t bad, n = (size_t)grid->nx * (size_t)grid->ny;
    if (!floats_finite((const float *)image, 2 * n, &bad))
        return sasnav_set_error(SASNAV_ERR_ARG, "image pixel (%zu, %zu) is not finite",
                                bad / 2 / (size_t)grid->nx, bad / 2 % (size_t)grid->nx);
    double *x = axis_values(grid->x0, grid->dx, grid->nx);
    double *y = axis_values(grid->y0, grid->dy, grid->ny);
    h5_ctx c;
    h5_begin(&c, path);
    if (!x || !y) rc = h5_fail(&c, SASNAV_ERR_NOMEM, "cannot allocate the image axes");
    hsize_t dims[2] = {(hsize_t)grid->ny, (hsize_t)grid->nx};
    if (!rc) rc = h5_create_tmp(&c, "sasnav-image");
    if (!rc) rc = h5_write_dataset(&c, "/image", H5_COMPLEX, 2, dims, NULL, image, "1");
    if (!rc) rc = h5_write_attr_double(&c, "/image", "x0", grid->x0);
    if (!rc) rc = h5_write_attr_double(&c, "/image", "dx", grid->dx);
    if (!rc) rc = h5_write_attr_double(&c, "/image", "y0", grid->y0);
    if (!rc) rc = h5_write_attr_double(&c, "/image", "dy", grid->dy);
    if (!rc) rc = h5_write_dataset(&c, "/x", H5_REAL, 1, &dims[1], NULL, x, "m");
    if (!rc) rc = h5_write_dataset(&c, "/y", H5_REAL, 1, &dims[0], NULL, y, "m");
    if (!rc) rc = h5_commit(&c);
    h5_end(&c);
    free(x);
    free(y);
    return rc;
}

/* One image axis: origin and spacing from the attributes of /image when
 * present (exact round trip), else from the coordinates; the coordinates must
 * be uniform either way. *d = 0 for a single pixel without a spacing. */
static int axis_read(h5_ctx *c, const char *name, const char *a0, const char *ad, int n, double *v0,
                     double *d)
{
    double *v = malloc((size_t)n * sizeof *v);
    if (!v) return h5_fail(c, SASNAV_ERR_NOMEM, "cannot allocate %s", name);
    hsize_t dims[1] = {(hsize_t)n};
    int rc = h5_read_dataset_dims(c, name, H5_REAL, 1, dims, v);
    for (int k = 0; k < n && !rc; k++)
        if (!isfinite(v[k])) rc = h5_fail(c, SASNAV_ERR_FORMAT, "%s[%d] is not finite", name, k);
    if (!rc && h5_attr_exists(c, "/image", a0)) {
        rc = h5_read_attr_double(c, "/image", a0, v0);
        if (!rc) rc = h5_read_attr_double(c, "/image", ad, d);
    } else if (!rc) {
        *v0 = v[0];
        *d = n > 1 ? (v[n - 1] - v[0]) / (n - 1) : 0.0;
    }
    if (!rc && n > 1 && !(*d > 0))
        rc = h5_fail(c, SASNAV_ERR_FORMAT, "%s is not increasing", name);
    /* Tolerance: rounding of v0 + k d, relative to the spacing and values. */
    for (int k = 0; k < n && !rc; k++)
        if (fabs(v[k] - (*v0 + k * *d)) > 1e-6 * *d + 1e-12 * fabs(v[k]))
            rc = h5_fail(c, SASNAV_ERR_FORMAT, "%s is not uniformly spaced (or disagrees with /image %s, %s)",
                         name, a0, ad);
    free(v);
    return rc;
}

static int image_read_open(h5_ctx *c, sasnav_grid *grid, sasnav_cfloat **image)
{
    hsize_t dims[2];
    hid_t dset;
    int rc = h5_open_dataset(c, "/image", H5_COMPLEX, 2, dims, &dset);
    if (rc) return rc;
    sasnav_grid g = {0, 0, 0, 0, (int)dims[1], (int)dims[0]};
    rc = axis_read(c, "/x", "x0", "dx", g.nx, &g.x0, &g.dx);
    if (!rc) rc = axis_read(c, "/y", "y0", "dy", g.ny, &g.y0, &g.dy);
    if (!rc) {
        /* Single-pixel axes without spacing: as sasnav_grid_make. */
        if (g.dx == 0.0) g.dx = g.dy > 0.0 ? g.dy : 1.0;
        if (g.dy == 0.0) g.dy = g.dx;
        rc = sasnav_grid_check(&g);
        if (rc) rc = h5_reframe(c, rc, "/image");
    }
    sasnav_cfloat *img = NULL;
    size_t n = (size_t)g.nx * (size_t)g.ny, bad;
    if (!rc) {
        img = malloc(n * sizeof *img);
        if (!img) rc = h5_fail(c, SASNAV_ERR_NOMEM, "cannot allocate a %d x %d image", g.ny, g.nx);
    }
    if (!rc) rc = h5_read_dataset(c, dset, "/image", H5_COMPLEX, img);
    if (!rc && !floats_finite((const float *)img, 2 * n, &bad))
        rc = h5_fail(c, SASNAV_ERR_FORMAT, "/image: pixel (%zu, %zu) is not finite", bad / 2 / (size_t)g.nx,
                     bad / 2 % (size_t)g.nx);
    H5Dclose(dset);
    if (rc) {
        free(img);
        return rc;
    }
    *grid = g;
    *image = img;
    return SASNAV_OK;
}

int sasnav_image_read(const char *path, sasnav_grid *grid, sasnav_cfloat **image)
{
    if (image) *image = NULL;
    if (!path || !grid || !image)
        return sasnav_set_error(SASNAV_ERR_ARG, "image read needs a path, a grid and an image pointer");
    h5_ctx c;
    h5_begin(&c, path);
    int rc = h5_open_read(&c, IMAGE_FORMATS, 1);
    if (!rc) rc = image_read_open(&c, grid, image);
    h5_end(&c);
    return rc;
}

/* --- refinement states (checkpoint.h) ------------------------------------- */

static const char *const REFINE_STATE_FORMATS[] = {"sasnav-refine-state"};

int sasnav_refine_state_write(const char *path, const sasnav_refine_state *st)
{
    if (!path || !st || st->n_pings < 3 || st->n_pixels < 1 || !st->poses || !st->move_u || !st->move_v ||
        !st->scene || !st->weights)
        return sasnav_set_error(SASNAV_ERR_ARG, "refinement state write needs a path and a whole state");
    size_t np = (size_t)st->n_pixels;
    double *w = malloc(sizeof *w * np);
    if (!w) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    for (size_t i = 0; i < np; i++) w[i] = st->weights[i];
    char digest[17];
    snprintf(digest, sizeof digest, "%016llx", (unsigned long long)st->digest);
    h5_ctx c;
    h5_begin(&c, path);
    int rc = h5_create_tmp(&c, "sasnav-refine-state");
    hsize_t dn[1] = {(hsize_t)st->n_pings}, dp[1] = {(hsize_t)np};
    hsize_t dm[1] = {SASNAV_REFINE_MAX_SWEEPS + 1}, dr[1] = {SASNAV_REFINE_MAX_SWEEPS};
    const sasnav_refine_report *r = &st->report;
    if (!rc) rc = h5_write_attr_string(&c, "/", "digest", digest);
    if (!rc) rc = h5_write_attr_int(&c, "/", "sweeps_done", st->sweeps_done);
    if (!rc) rc = h5_write_attr_int(&c, "/", "finished", st->finished);
    if (!rc) rc = h5_write_attr_double(&c, "/", "mu", st->mu);
    if (!rc) rc = poses_write(&c, "/poses", st->n_pings, st->poses);
    if (!rc) rc = h5_write_dataset(&c, "/move_u", H5_REAL, 1, dn, NULL, st->move_u, "m");
    if (!rc) rc = h5_write_dataset(&c, "/move_v", H5_REAL, 1, dn, NULL, st->move_v, "m");
    if (!rc) rc = h5_write_dataset(&c, "/scene", H5_COMPLEX, 1, dp, NULL, st->scene, NULL);
    if (!rc) rc = h5_write_dataset(&c, "/weights", H5_REAL, 1, dp, NULL, w, NULL);
    if (!rc) rc = h5_create_group(&c, "/report");
    if (!rc) rc = h5_write_attr_int(&c, "/report", "sweeps", r->sweeps);
    if (!rc) rc = h5_write_attr_int(&c, "/report", "undone", r->undone);
    if (!rc) rc = h5_write_attr_double(&c, "/report", "seconds", r->seconds);
    if (!rc) rc = h5_write_dataset(&c, "/report/misfit", H5_REAL, 1, dm, NULL, r->misfit, NULL);
    if (!rc) rc = h5_write_dataset(&c, "/report/rms_move", H5_REAL, 1, dr, NULL, r->rms_move, "m");
    if (!rc) rc = h5_commit(&c);
    h5_end(&c);
    free(w);
    return rc;
}

int sasnav_refine_state_read(const char *path, sasnav_refine_state *st)
{
    if (!path || !st) return sasnav_set_error(SASNAV_ERR_ARG, "refinement state read: NULL argument");
    memset(st, 0, sizeof *st);
    h5_ctx c;
    h5_begin(&c, path);
    int rc = h5_open_read(&c, REFINE_STATE_FORMATS, 1);
    char created[64] = "", digest[32] = "";
    if (!rc) rc = h5_read_attr_string(&c, "/", "created_by", created, sizeof created);
    if (!rc && strcmp(created, SASNAV_H5_CREATED_BY))
        rc = h5_fail(&c, SASNAV_ERR_FORMAT, "written by %s, this is %s: remove it to start again", created,
                     SASNAV_H5_CREATED_BY);
    if (!rc) rc = h5_read_attr_string(&c, "/", "digest", digest, sizeof digest);
    char *end = NULL;
    unsigned long long dg = rc ? 0 : strtoull(digest, &end, 16);
    if (!rc && (strlen(digest) != 16 || !end || *end))
        rc = h5_fail(&c, SASNAV_ERR_FORMAT, "attribute 'digest' is not 16 hex digits");
    st->digest = dg;
    if (!rc) rc = h5_read_attr_int(&c, "/", "sweeps_done", &st->sweeps_done);
    if (!rc) rc = h5_read_attr_int(&c, "/", "finished", &st->finished);
    if (!rc) rc = h5_read_attr_double(&c, "/", "mu", &st->mu);
    if (!rc && (st->sweeps_done < 0 || st->sweeps_done > SASNAV_REFINE_MAX_SWEEPS || st->finished < 0 ||
                st->finished > 1 || !(st->mu > 0) || !isfinite(st->mu)))
        rc = h5_fail(&c, SASNAV_ERR_FORMAT, "sweeps_done, finished or mu out of range");
    int n = 0;
    if (!rc) rc = poses_count(&c, "/poses", &n);
    if (!rc && n < 3) rc = h5_fail(&c, SASNAV_ERR_FORMAT, "/poses: fewer than 3 poses");
    hsize_t dims[1] = {0};
    hid_t ds = H5I_INVALID_HID;
    if (!rc) rc = h5_open_dataset(&c, "/scene", H5_COMPLEX, 1, dims, &ds);
    if (ds != H5I_INVALID_HID) H5Dclose(ds);
    if (!rc && dims[0] > (hsize_t)INT32_MAX) rc = h5_fail(&c, SASNAV_ERR_FORMAT, "/scene: too large");
    size_t np = (size_t)dims[0];
    double *w = NULL;
    if (!rc) {
        st->n_pings = n;
        st->n_pixels = (int)np;
        st->poses = malloc(sizeof *st->poses * n);
        st->move_u = malloc(sizeof(double) * n);
        st->move_v = malloc(sizeof(double) * n);
        st->scene = malloc(sizeof *st->scene * np);
        st->weights = malloc(sizeof *st->weights * np);
        w = malloc(sizeof *w * np);
        if (!st->poses || !st->move_u || !st->move_v || !st->scene || !st->weights || !w)
            rc = h5_fail(&c, SASNAV_ERR_NOMEM, "cannot allocate the state");
    }
    hsize_t dn[1] = {(hsize_t)n}, dm[1] = {SASNAV_REFINE_MAX_SWEEPS + 1}, dr[1] = {SASNAV_REFINE_MAX_SWEEPS};
    if (!rc) rc = poses_read(&c, "/poses", n, st->poses);
    if (!rc) rc = h5_read_dataset_dims(&c, "/move_u", H5_REAL, 1, dn, st->move_u);
    if (!rc) rc = h5_read_dataset_dims(&c, "/move_v", H5_REAL, 1, dn, st->move_v);
    if (!rc) rc = h5_read_dataset_dims(&c, "/scene", H5_COMPLEX, 1, dims, st->scene);
    if (!rc) rc = h5_read_dataset_dims(&c, "/weights", H5_REAL, 1, dims, w);
    sasnav_refine_report *r = &st->report;
    if (!rc) rc = h5_read_attr_int(&c, "/report", "sweeps", &r->sweeps);
    if (!rc) rc = h5_read_attr_int(&c, "/report", "undone", &r->undone);
    if (!rc) rc = h5_read_attr_double(&c, "/report", "seconds", &r->seconds);
    if (!rc) rc = h5_read_dataset_dims(&c, "/report/misfit", H5_REAL, 1, dm, r->misfit);
    if (!rc) rc = h5_read_dataset_dims(&c, "/report/rms_move", H5_REAL, 1, dr, r->rms_move);
    if (!rc && r->sweeps != st->sweeps_done)
        rc = h5_fail(&c, SASNAV_ERR_FORMAT, "report sweeps %d differ from sweeps_done %d", r->sweeps, st->sweeps_done);
    for (int p = 0; !rc && p < n; p++)
        if (!isfinite(st->move_u[p]) || !isfinite(st->move_v[p]))
            rc = h5_fail(&c, SASNAV_ERR_FORMAT, "/move_u, /move_v: non-finite value at ping %d", p);
    if (!rc && !poses_finite(n, st->poses)) rc = h5_fail(&c, SASNAV_ERR_FORMAT, "/poses: non-finite pose");
    size_t bad = 0;
    if (!rc && !floats_finite((const float *)st->scene, 2 * np, &bad))
        rc = h5_fail(&c, SASNAV_ERR_FORMAT, "/scene: non-finite value at %zu", bad / 2);
    for (size_t i = 0; !rc && i < np; i++) {
        st->weights[i] = (float)w[i];
        if (!(st->weights[i] > 0) || !isfinite(st->weights[i]))
            rc = h5_fail(&c, SASNAV_ERR_FORMAT, "/weights: value %g at %zu is not positive and finite", w[i], i);
    }
    h5_end(&c);
    free(w);
    if (rc) sasnav_refine_state_free(st);
    return rc;
}
