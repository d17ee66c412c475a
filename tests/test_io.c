/* HDF5 files (src/io, docs/format.md) and the run/grid containers:
 * - bit-exact round trips of runs, navigation and images;
 * - every kind of malformed input gives the documented error code and a
 *   message (files are made malformed with the HDF5 C API);
 * - writers never leave a partial file or a temporary behind;
 * - files are readable by h5py as complex64 (skipped without python3/h5py);
 * - grid helpers and run containers. */
#include "sasnav/error.h"
#include "sasnav/image.h"
#include "sasnav/io.h"
#include "testutil.h"

#include <dirent.h>
#include <hdf5.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* --- helpers ------------------------------------------------------------- */

static uint64_t rng_state;
static void rng_seed(uint64_t s) { rng_state = s ^ 0x9E3779B97F4A7C15ull; }
static uint64_t rng_next(void) /* splitmix64 */
{
    uint64_t z = (rng_state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}
static double rng_uniform(double a, double b) { return a + (b - a) * (double)(rng_next() >> 11) / 9007199254740992.0; }

static char *tmp_file(const char *name)
{
    static char buf[8][512];
    static int k;
    char *p = buf[k++ % 8];
    snprintf(p, 512, "%s/%s", test_tmpdir(), name);
    return p;
}

#define SAME_BITS(a, b) (memcmp(&(a), &(b), sizeof(a)) == 0)

/* Datatypes the test itself holds open (counted by H5Fget_obj_count). */
static ssize_t test_open_types;

/* No HDF5 object may stay open after a library call. */
static void check_no_open_objects(const char *where)
{
    ssize_t n = H5Fget_obj_count(H5F_OBJ_ALL, H5F_OBJ_ALL) - test_open_types;
    CHECK(n == 0, "%s: %zd HDF5 objects left open", where, n);
}

/* Expects status `want` and a non-empty message. */
#define CHECK_FAILS(expr, want)                                                                  \
    do {                                                                                         \
        sasnav_clear_error();                                                                    \
        int rc_ = (expr);                                                                        \
        CHECK(rc_ == (want), "%s returned %d, expected %d (%s)", #expr, rc_, (want), sasnav_last_error()); \
        CHECK(sasnav_last_error()[0] != '\0', "%s: empty error message", #expr);                \
        if (rc_ == (want)) printf("  ok (%s): %s\n", sasnav_strerror(rc_), sasnav_last_error()); \
        check_no_open_objects(#expr);                                                            \
    } while (0)

static void random_pose(sasnav_pose *p)
{
    p->x = rng_uniform(-100, 100);
    p->y = rng_uniform(-5, 5);
    p->theta = rng_uniform(-0.3, 0.3);
}

/* Random pings anywhere in +-100 m, each transmitter within a metre of its
 * array (the plausibility check refuses more than 100 m apart). */
static void random_poses(sasnav_ping_pose *poses, int n)
{
    for (int p = 0; p < n; p++) {
        random_pose(&poses[p].array);
        poses[p].tx = poses[p].array;
        poses[p].tx.x += rng_uniform(-1, 1);
        poses[p].tx.y += rng_uniform(-0.5, 0.5);
        poses[p].tx.theta += rng_uniform(-0.01, 0.01);
    }
}

/* A run with random contents (seeded), with or without ground truth. */
static sasnav_run *random_run(uint64_t seed, int n_pings, int n_rx, int n_samples, int with_truth)
{
    rng_seed(seed);
    sasnav_system sys;
    sasnav_system_default(&sys);
    sys.sound_speed = rng_uniform(1400, 1600);
    sys.f0 = rng_uniform(1e5, 4e5);
    sys.bandwidth = rng_uniform(1e4, 4e4);
    sys.sample_rate = sys.bandwidth * rng_uniform(1, 3);
    sys.taper = SASNAV_TAPER_HANN;
    sys.attenuation = SASNAV_ATTEN_SPHERICAL;
    sys.beam_pattern = 0;
    sasnav_array array;
    if (sasnav_array_uniform(&array, n_rx, rng_uniform(0.01, 0.1), rng_uniform(0, 0.1),
                             rng_uniform(0, 0.1)))
        return NULL;
    array.rx_height = rng_uniform(0, 2);
    array.tx_height = rng_uniform(0, 2);
    sasnav_window win = {rng_uniform(0.001, 0.02), n_samples};
    sasnav_run *run = NULL;
    if (sasnav_run_alloc(&sys, &array, &win, n_pings, with_truth, &run)) return NULL;
    size_t n = (size_t)n_pings * n_rx * n_samples;
    for (size_t k = 0; k < n; k++)
        run->raw[k] = (float)rng_uniform(-1e3, 1e3) + I * (float)rng_uniform(-1e-3, 1e-3);
    random_poses(run->nav, n_pings);
    if (with_truth) random_poses(run->truth, n_pings);
    run->ping_spacing = rng_uniform(0.1, 0.3);
    run->speed = rng_uniform(0, 3);
    run->tx_lag = rng_uniform(-0.2, 0.2);
    run->range_of_interest = rng_uniform(1, 50);
    return run;
}

/* Field-by-field, bit-exact comparison (structs have padding). */
static int runs_identical(const sasnav_run *a, const sasnav_run *b)
{
    int same = SAME_BITS(a->sys.sound_speed, b->sys.sound_speed) && SAME_BITS(a->sys.f0, b->sys.f0) &&
               SAME_BITS(a->sys.bandwidth, b->sys.bandwidth) &&
               SAME_BITS(a->sys.sample_rate, b->sys.sample_rate) && a->sys.taper == b->sys.taper &&
               a->sys.attenuation == b->sys.attenuation && a->sys.beam_pattern == b->sys.beam_pattern;
    same = same && a->array.n_rx == b->array.n_rx &&
           memcmp(a->array.rx_u, b->array.rx_u, a->array.n_rx * sizeof(double)) == 0 &&
           SAME_BITS(a->array.rx_length, b->array.rx_length) &&
           SAME_BITS(a->array.tx_length, b->array.tx_length) &&
           SAME_BITS(a->array.rx_height, b->array.rx_height) &&
           SAME_BITS(a->array.tx_height, b->array.tx_height) &&
           a->array.per_channel == b->array.per_channel;
    for (int l = 0; same && a->array.per_channel && l < a->array.n_rx; l++)
        same = SAME_BITS(a->array.size[l].rx_length, b->array.size[l].rx_length) &&
               SAME_BITS(a->array.size[l].tx_length, b->array.size[l].tx_length) &&
               SAME_BITS(a->array.size[l].rx_height, b->array.size[l].rx_height) &&
               SAME_BITS(a->array.size[l].tx_height, b->array.size[l].tx_height);
    same = same && SAME_BITS(a->win.t0, b->win.t0) && a->win.n_samples == b->win.n_samples &&
           a->n_pings == b->n_pings;
    same = same && SAME_BITS(a->ping_spacing, b->ping_spacing) && SAME_BITS(a->speed, b->speed) &&
           SAME_BITS(a->tx_lag, b->tx_lag) && SAME_BITS(a->range_of_interest, b->range_of_interest);
    if (!same) return 0;
    size_t n = (size_t)a->n_pings * a->array.n_rx * a->win.n_samples;
    if (memcmp(a->raw, b->raw, n * sizeof *a->raw) != 0) return 0;
    if (memcmp(a->nav, b->nav, a->n_pings * sizeof *a->nav) != 0) return 0;
    if (!a->truth != !b->truth) return 0;
    if (a->truth && memcmp(a->truth, b->truth, a->n_pings * sizeof *a->truth) != 0) return 0;
    if (!a->channel_offset != !b->channel_offset) return 0;
    if (a->channel_offset &&
        memcmp(a->channel_offset, b->channel_offset, a->array.n_rx * sizeof *a->channel_offset) != 0)
        return 0;
    return 1;
}

/* Entries of the test directory whose name contains `part`. */
static int dir_count(const char *dir, const char *part)
{
    DIR *d = opendir(dir);
    if (!d) return -1;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)))
        if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..") && strstr(e->d_name, part)) n++;
    closedir(d);
    return n;
}

static int copy_prefix(const char *from, const char *to, double fraction)
{
    FILE *in = fopen(from, "rb");
    if (!in) return -1;
    fseek(in, 0, SEEK_END);
    long size = ftell(in);
    rewind(in);
    long keep = (long)(size * fraction);
    char *buf = malloc(size > 0 ? (size_t)size : 1);
    size_t got = fread(buf, 1, (size_t)size, in);
    fclose(in);
    FILE *out = fopen(to, "wb");
    if (!out || got != (size_t)size) {
        free(buf);
        if (out) fclose(out);
        return -1;
    }
    fwrite(buf, 1, (size_t)keep, out);
    fclose(out);
    free(buf);
    return 0;
}

static int write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    if (!f) return -1;
    fputs(text, f);
    fclose(f);
    return 0;
}

/* --- round trips ------------------------------------------------------------ */

static void test_run_round_trip(void)
{
    for (int with_truth = 0; with_truth <= 1; with_truth++) {
        sasnav_run *run = random_run(100 + with_truth, 5, 7, 37, with_truth), *back = NULL;
        CHECK(run != NULL, "random run: %s", sasnav_last_error());
        if (!run) continue;
        const char *path = tmp_file(with_truth ? "run_truth.h5" : "run.h5");
        CHECK_OK(sasnav_run_write(path, run));
        check_no_open_objects("run_write");
        CHECK_OK(sasnav_run_read(path, &back));
        check_no_open_objects("run_read");
        CHECK(back && runs_identical(run, back), "run round trip (truth %d) is not bit-exact", with_truth);
        /* Overwriting an existing file works and leaves no temporary. */
        run->raw[3] += 1.0f;
        CHECK_OK(sasnav_run_write(path, run));
        sasnav_run_free(back);
        back = NULL;
        CHECK_OK(sasnav_run_read(path, &back));
        CHECK(back && runs_identical(run, back), "overwritten run differs");
        CHECK(dir_count(test_tmpdir(), ".tmp-") == 0, "temporary files left behind");
        /* The navigation of a run file can be read on its own. */
        int n = 0;
        sasnav_ping_pose *nav = NULL, *truth = NULL;
        CHECK_OK(sasnav_nav_read(path, &n, &nav, &truth));
        CHECK(n == run->n_pings && nav && memcmp(nav, run->nav, n * sizeof *nav) == 0,
              "navigation read from a run file differs");
        CHECK(with_truth ? (truth && memcmp(truth, run->truth, n * sizeof *truth) == 0) : truth == NULL,
              "truth read from a run file is wrong");
        free(nav);
        free(truth);
        sasnav_run_free(back);
        sasnav_run_free(run);
    }
}

static void test_nav_round_trip(void)
{
    rng_seed(7);
    enum { N = 11 };
    sasnav_ping_pose nav[N], truth[N];
    random_poses(nav, N);
    random_poses(truth, N);
    const char *path = tmp_file("nav.h5");
    for (int with_truth = 0; with_truth <= 1; with_truth++) {
        CHECK_OK(sasnav_nav_write(path, N, nav, with_truth ? truth : NULL));
        int n = 0;
        sasnav_ping_pose *rn = NULL, *rt = NULL;
        CHECK_OK(sasnav_nav_read(path, &n, &rn, &rt));
        check_no_open_objects("nav_read");
        CHECK(n == N && rn && memcmp(rn, nav, sizeof nav) == 0, "nav round trip differs");
        if (with_truth)
            CHECK(rt && memcmp(rt, truth, sizeof truth) == 0, "truth round trip differs");
        else
            CHECK(rt == NULL, "truth should be NULL when absent");
        free(rn);
        free(rt);
        /* truth == NULL: not read. */
        rn = NULL;
        CHECK_OK(sasnav_nav_read(path, &n, &rn, NULL));
        CHECK(rn && memcmp(rn, nav, sizeof nav) == 0, "nav read without truth differs");
        free(rn);
    }
    /* An implausible pose (finite, 1e300 m away) is refused by the reader,
     * as in a run (before, `image --nav` cast it into a grid size). */
    {
        hid_t f = H5Fopen(path, H5F_ACC_RDWR, H5P_DEFAULT);
        hid_t d = H5Dopen2(f, "/nav/array", H5P_DEFAULT);
        double v[N * 3];
        H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v);
        v[3 * 4] = 1e300;
        H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v);
        H5Dclose(d);
        H5Fclose(f);
        int n = 0;
        sasnav_ping_pose *rn = NULL, *rt = NULL;
        CHECK_FAILS(sasnav_nav_read(path, &n, &rn, &rt), SASNAV_ERR_FORMAT);
        CHECK(rn == NULL && strstr(sasnav_last_error(), "ping 4") != NULL, "implausible nav: '%s'",
              sasnav_last_error());
    }
    /* Standard deviations (/nav_sigma): a bit-exact round trip; none in a
     * file written without them; refused when negative or not finite, on
     * writing and (a file edited after) on reading; a shape other than
     * /nav's refused. */
    {
        sasnav_pose sg[N];
        for (int i = 0; i < N; i++) sg[i] = (sasnav_pose){1e-3 * i, 3e-5 * i * i, 2e-5 * i};
        const char *sp = tmp_file("nav_sigma.h5");
        CHECK_OK(sasnav_nav_write_sigma(sp, N, nav, truth, sg));
        int n = 0;
        sasnav_pose *rs = NULL;
        CHECK_OK(sasnav_nav_read_sigma(sp, &n, &rs));
        check_no_open_objects("nav_read_sigma");
        CHECK(n == N && rs && memcmp(rs, sg, sizeof sg) == 0, "standard deviations round trip differs");
        free(rs);
        sasnav_ping_pose *rn = NULL;
        CHECK_OK(sasnav_nav_read(sp, &n, &rn, NULL)); /* the rest of the file as before */
        CHECK(rn && memcmp(rn, nav, sizeof nav) == 0, "nav beside standard deviations differs");
        free(rn);
        rs = (sasnav_pose *)1;
        const char *plain = tmp_file("nav_plain.h5");
        CHECK_OK(sasnav_nav_write(plain, N, nav, NULL));
        CHECK_OK(sasnav_nav_read_sigma(plain, &n, &rs)); /* written without */
        CHECK(rs == NULL && n == N, "a file without /nav_sigma: %p, %d pings", (void *)rs, n);
        sg[3].y = -1e-6;
        CHECK_FAILS(sasnav_nav_write_sigma(tmp_file("nav_bad.h5"), N, nav, NULL, sg), SASNAV_ERR_ARG);
        sg[3].y = NAN;
        CHECK_FAILS(sasnav_nav_write_sigma(tmp_file("nav_bad.h5"), N, nav, NULL, sg), SASNAV_ERR_ARG);
        CHECK(dir_count(test_tmpdir(), "nav_bad") == 0, "a refused write left a file");
        hid_t f = H5Fopen(sp, H5F_ACC_RDWR, H5P_DEFAULT);
        hid_t d = H5Dopen2(f, "/nav_sigma", H5P_DEFAULT);
        double v[N * 3];
        H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v);
        v[3 * 5 + 1] = -2e-5;
        H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v);
        H5Dclose(d);
        H5Fclose(f);
        rs = NULL;
        CHECK_FAILS(sasnav_nav_read_sigma(sp, &n, &rs), SASNAV_ERR_FORMAT);
        CHECK(rs == NULL && n == 0 && strstr(sasnav_last_error(), "nav_sigma") != NULL,
              "negative standard deviation read: '%s'", sasnav_last_error());
        /* /nav_sigma of another length than /nav */
        f = H5Fopen(sp, H5F_ACC_RDWR, H5P_DEFAULT);
        H5Ldelete(f, "/nav_sigma", H5P_DEFAULT);
        hsize_t dims[2] = {N - 1, 3};
        hid_t space = H5Screate_simple(2, dims, NULL);
        d = H5Dcreate2(f, "/nav_sigma", H5T_NATIVE_DOUBLE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
        for (int i = 0; i < N * 3; i++) v[i] = 1e-3;
        H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v);
        H5Dclose(d);
        H5Sclose(space);
        H5Fclose(f);
        CHECK_FAILS(sasnav_nav_read_sigma(sp, &n, &rs), SASNAV_ERR_FORMAT);
        CHECK(rs == NULL && n == 0, "standard deviations of the wrong shape read");
        /* a navigation that sasnav_nav_read refuses (/nav/array a row
         * short) is refused here too, /nav_sigma or not */
        const char *sq = tmp_file("nav_sigma2.h5");
        CHECK_OK(sasnav_nav_write_sigma(sq, N, nav, NULL, (sasnav_pose[N]){{0, 0, 0}}));
        f = H5Fopen(sq, H5F_ACC_RDWR, H5P_DEFAULT);
        H5Ldelete(f, "/nav/array", H5P_DEFAULT);
        space = H5Screate_simple(2, dims, NULL); /* dims: N - 1 rows */
        d = H5Dcreate2(f, "/nav/array", H5T_NATIVE_DOUBLE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
        H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v);
        H5Dclose(d);
        H5Sclose(space);
        H5Fclose(f);
        sasnav_ping_pose *rn2 = NULL;
        CHECK_FAILS(sasnav_nav_read(sq, &n, &rn2, NULL), SASNAV_ERR_FORMAT);
        CHECK_FAILS(sasnav_nav_read_sigma(sq, &n, &rs), SASNAV_ERR_FORMAT);
        CHECK(rs == NULL && n == 0, "a broken navigation's standard deviations read");
    }
    /* A nav file is not a run. */
    sasnav_run *run = (sasnav_run *)1;
    CHECK_FAILS(sasnav_run_read(path, &run), SASNAV_ERR_FORMAT);
    CHECK(run == NULL, "run pointer not cleared on failure");
}

static void test_image_round_trip(void)
{
    rng_seed(11);
    sasnav_grid grids[3];
    CHECK_OK(sasnav_grid_make(-0.37, 0.61, 13, 9.1, 10.3, 6, &grids[0]));
    grids[0].x0 += 1e-9; /* origin not on the axis formula's grid */
    CHECK_OK(sasnav_grid_make(2.0, 2.0, 1, -1.0, 1.0, 5, &grids[1]));
    CHECK_OK(sasnav_grid_make(0.5, 0.5, 1, 3.0, 3.0, 1, &grids[2]));
    for (int k = 0; k < 3; k++) {
        const sasnav_grid *g = &grids[k];
        size_t n = (size_t)g->nx * g->ny;
        sasnav_cfloat *img = malloc(n * sizeof *img), *back = NULL;
        for (size_t i = 0; i < n; i++) img[i] = (float)rng_uniform(-1, 1) + I * (float)rng_uniform(-1e6, 1e6);
        const char *path = tmp_file("image.h5");
        CHECK_OK(sasnav_image_write(path, g, img));
        sasnav_grid gb;
        memset(&gb, 0xA5, sizeof gb);
        CHECK_OK(sasnav_image_read(path, &gb, &back));
        check_no_open_objects("image_read");
        CHECK(back && memcmp(back, img, n * sizeof *img) == 0, "image %d pixels differ", k);
        CHECK(gb.nx == g->nx && gb.ny == g->ny && SAME_BITS(gb.x0, g->x0) && SAME_BITS(gb.y0, g->y0) &&
                  SAME_BITS(gb.dx, g->dx) && SAME_BITS(gb.dy, g->dy),
              "image %d grid differs", k);
        free(back);
        free(img);
    }
}

/* --- malformed files ------------------------------------------------------------ */

/* A valid run file to damage, re-created for every case. */
static const char *fresh_run_file(const char *name, int with_truth)
{
    sasnav_run *run = random_run(5, 4, 3, 16, with_truth);
    const char *path = tmp_file(name);
    CHECK(run && sasnav_run_write(path, run) == 0, "cannot write %s: %s", path, sasnav_last_error());
    sasnav_run_free(run);
    return path;
}

static hid_t open_rw(const char *path)
{
    hid_t f = H5Fopen(path, H5F_ACC_RDWR, H5P_DEFAULT);
    CHECK(f >= 0, "cannot reopen %s", path);
    return f;
}

static void make_dataset(hid_t loc, const char *name, hid_t type, int rank, const hsize_t *dims,
                         const void *data)
{
    hid_t space = H5Screate_simple(rank, dims, NULL);
    hid_t d = H5Dcreate2(loc, name, type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    CHECK(d >= 0, "cannot create %s", name);
    if (data) CHECK(H5Dwrite(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) >= 0, "cannot write %s", name);
    H5Dclose(d);
    H5Sclose(space);
}

static void replace_dataset(hid_t f, const char *name, hid_t type, int rank, const hsize_t *dims,
                            const void *data)
{
    CHECK(H5Ldelete(f, name, H5P_DEFAULT) >= 0, "cannot delete %s", name);
    make_dataset(f, name, type, rank, dims, data);
}

/* Overwrites an attribute. (H5Awrite on an attribute from H5Aopen_by_name
 * with a path fails in HDF5 1.10.8: open the object first.) */
static void set_attr(hid_t f, const char *obj, const char *name, hid_t type, const void *v)
{
    hid_t o = H5Oopen(f, obj, H5P_DEFAULT);
    hid_t a = H5Aopen(o, name, H5P_DEFAULT);
    CHECK(a >= 0 && H5Awrite(a, type, v) >= 0, "cannot set %s %s", obj, name);
    H5Aclose(a);
    H5Oclose(o);
}

static void set_attr_double(hid_t f, const char *obj, const char *name, double v)
{
    set_attr(f, obj, name, H5T_NATIVE_DOUBLE, &v);
}

static void set_attr_int(hid_t f, const char *obj, const char *name, int v)
{
    set_attr(f, obj, name, H5T_NATIVE_INT, &v);
}

/* Replaces a root string attribute with a variable-length (h5py-style) one. */
static void set_attr_vlen_string(hid_t f, const char *name, const char *v)
{
    H5Adelete(f, name);
    hid_t t = H5Tcopy(H5T_C_S1);
    H5Tset_size(t, H5T_VARIABLE);
    H5Tset_cset(t, H5T_CSET_UTF8);
    hid_t s = H5Screate(H5S_SCALAR);
    hid_t a = H5Acreate2(f, name, t, s, H5P_DEFAULT, H5P_DEFAULT);
    CHECK(a >= 0 && H5Awrite(a, t, &v) >= 0, "cannot write vlen attribute %s", name);
    H5Aclose(a);
    H5Sclose(s);
    H5Tclose(t);
}

static hid_t complex_type(hid_t member, size_t size, const char *r, const char *i)
{
    hid_t t = H5Tcreate(H5T_COMPOUND, 2 * size);
    H5Tinsert(t, r, 0, member);
    H5Tinsert(t, i, size, member);
    return t;
}

/* Writes one value into dataset `name` at element `index` (flat). */
static void poke(hid_t f, const char *name, hid_t memtype, hsize_t index, int rank, const void *value)
{
    hid_t d = H5Dopen2(f, name, H5P_DEFAULT);
    hid_t fs = H5Dget_space(d);
    hsize_t dims[4], coord[4];
    H5Sget_simple_extent_dims(fs, dims, NULL);
    for (int k = rank - 1; k >= 0; k--) {
        coord[k] = index % dims[k];
        index /= dims[k];
    }
    H5Sselect_elements(fs, H5S_SELECT_SET, 1, coord);
    hsize_t one = 1;
    hid_t ms = H5Screate_simple(1, &one, NULL);
    CHECK(H5Dwrite(d, memtype, ms, fs, H5P_DEFAULT, value) >= 0, "cannot poke %s", name);
    H5Sclose(ms);
    H5Sclose(fs);
    H5Dclose(d);
}

/* Aiding measurements (docs/format.md, "/aiding"): a bit-exact round trip
 * of both sensors and of the gyro alone, +inf standard deviations kept,
 * and bad aiding refused with a message naming it: NaN, a wrong length, a
 * negative or zero standard deviation, times that do not increase, values
 * without their standard deviations. */
static int aiding_identical(const sasnav_aiding *a, const sasnav_aiding *b, int n)
{
    if (!a || !b) return 0;
    if (memcmp(a->time, b->time, sizeof(double) * n)) return 0;
    if (!a->yaw_rate != !b->yaw_rate || !a->velocity != !b->velocity) return 0;
    if (a->yaw_rate && (memcmp(a->yaw_rate, b->yaw_rate, sizeof(double) * n) ||
                        memcmp(a->yaw_rate_sigma, b->yaw_rate_sigma, sizeof(double) * n)))
        return 0;
    if (a->velocity && (memcmp(a->velocity, b->velocity, sizeof(double) * 2 * n) ||
                        memcmp(a->velocity_sigma, b->velocity_sigma, sizeof(double) * 2 * n)))
        return 0;
    return 1;
}

static void test_aiding(void)
{
    for (int dvl = 1; dvl >= 0; dvl--) {
        sasnav_run *run = random_run(300 + dvl, 6, 3, 16, 1), *back = NULL;
        if (!run) continue;
        CHECK_OK(sasnav_run_alloc_aiding(run, 1, dvl));
        sasnav_aiding *a = run->aiding;
        for (int p = 0; a && p < run->n_pings; p++) {
            a->time[p] = 0.1 * p + rng_uniform(0, 1e-3);
            a->yaw_rate[p] = rng_uniform(-0.025, 0.025);
            a->yaw_rate_sigma[p] = rng_uniform(1e-6, 2e-6);
            for (int k = 0; dvl && k < 2; k++) {
                a->velocity[2 * p + k] = k == 0 ? rng_uniform(2.0, 2.01) : rng_uniform(0, 0.02);
                a->velocity_sigma[2 * p + k] = p == 2 ? INFINITY : 3e-3;
            }
        }
        const char *path = tmp_file(dvl ? "aiding.h5" : "aiding-gyro.h5");
        CHECK_OK(sasnav_run_write(path, run));
        CHECK_OK(sasnav_run_read(path, &back));
        CHECK(back && runs_identical(run, back) && aiding_identical(run->aiding, back->aiding, run->n_pings),
              "aiding round trip (DVL %d) is not bit-exact", dvl);
        sasnav_run_free(back);
        sasnav_run_free(run);
    }
    /* Bad aiding in a file. */
    sasnav_run *run = random_run(310, 6, 3, 16, 1), *back = NULL;
    if (!run) return;
    CHECK_OK(sasnav_run_alloc_aiding(run, 1, 1));
    for (int p = 0; p < run->n_pings; p++) {
        run->aiding->time[p] = 0.1 * p;
        run->aiding->yaw_rate_sigma[p] = 1e-6;
        run->aiding->velocity_sigma[2 * p] = run->aiding->velocity_sigma[2 * p + 1] = 3e-3;
    }
    const char *good = tmp_file("aiding-good.h5");
    CHECK_OK(sasnav_run_write(good, run));
    struct {
        const char *name, *dataset, *expect;
        int kind; /* 0 poke NaN, 1 short dataset, 2 negative sigma, 3 zero sigma, 4 times, 5 drop sigma,
                     6 absurd value, 7 tiny sigma (both finite: they overflowed the fusion's costs) */
    } cases[] = {{"aiding-nan.h5", "/aiding/yaw_rate", "not finite", 0},
                 {"aiding-short.h5", "/aiding/velocity", "/aiding/velocity", 1},
                 {"aiding-negative.h5", "/aiding/yaw_rate_sigma", "standard deviation", 2},
                 {"aiding-zero.h5", "/aiding/velocity_sigma", "standard deviation", 3},
                 {"aiding-time.h5", "/aiding/time", "must increase", 4},
                 {"aiding-nosigma.h5", "/aiding/yaw_rate_sigma", "come together", 5},
                 {"aiding-huge.h5", "/aiding/yaw_rate", "beyond", 6},
                 {"aiding-tiny.h5", "/aiding/velocity_sigma", "standard deviation", 7}};
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        const char *path = tmp_file(cases[c].name);
        CHECK_OK(sasnav_run_write(path, run));
        hid_t f = open_rw(path);
        double v;
        switch (cases[c].kind) {
        case 0: v = NAN; poke(f, cases[c].dataset, H5T_NATIVE_DOUBLE, 3, 1, &v); break;
        case 1: {
            hsize_t d[2] = {(hsize_t)run->n_pings - 1, 2};
            double zeros[12] = {0};
            replace_dataset(f, cases[c].dataset, H5T_NATIVE_DOUBLE, 2, d, zeros);
            break;
        }
        case 2: v = -1e-6; poke(f, cases[c].dataset, H5T_NATIVE_DOUBLE, 2, 1, &v); break;
        case 3: v = 0.0; poke(f, cases[c].dataset, H5T_NATIVE_DOUBLE, 5, 2, &v); break;
        case 4: v = 0.1; poke(f, cases[c].dataset, H5T_NATIVE_DOUBLE, 3, 1, &v); break;
        case 5: H5Ldelete(f, cases[c].dataset, H5P_DEFAULT); break;
        case 6: v = 1e300; poke(f, cases[c].dataset, H5T_NATIVE_DOUBLE, 2, 1, &v); break;
        case 7: v = 1e-300; poke(f, cases[c].dataset, H5T_NATIVE_DOUBLE, 3, 2, &v); break;
        }
        H5Fclose(f);
        CHECK_FAILS(sasnav_run_read(path, &back), SASNAV_ERR_FORMAT);
        CHECK(strstr(sasnav_last_error(), cases[c].expect) != NULL && strstr(sasnav_last_error(), "aiding"),
              "%s: message '%s' does not say '%s'", cases[c].name, sasnav_last_error(), cases[c].expect);
        CHECK(back == NULL, "%s: run returned", cases[c].name);
    }
    /* In memory: sasnav_run_check refuses the same. */
    run->aiding->velocity[1] = NAN;
    CHECK(sasnav_run_check(run) == SASNAV_ERR_ARG, "NaN velocity accepted in memory");
    sasnav_run_free(run);
}

static int file_version(const char *path)
{
    int v = -1;
    hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    hid_t a = f >= 0 ? H5Aopen(f, "format_version", H5P_DEFAULT) : -1;
    if (a >= 0) {
        H5Aread(a, H5T_NATIVE_INT, &v);
        H5Aclose(a);
    }
    if (f >= 0) H5Fclose(f);
    return v;
}

/* Format version 2: per-channel offsets (/channels) round-trip bit for bit
 * through the whole-run and ping-by-ping writers and both readers; a run
 * without them is still written as version 1; version-1 files with
 * /channels, wrong shapes and non-finite offsets are refused. */
static void test_channels(void)
{
    sasnav_run *run = random_run(320, 5, 4, 16, 1), *back = NULL;
    if (!run) return;
    const char *v1 = tmp_file("channels-v1.h5");
    CHECK_OK(sasnav_run_write(v1, run));
    CHECK(file_version(v1) == 1, "a run without channel offsets written as version %d", file_version(v1));
    CHECK_OK(sasnav_run_read(v1, &back));
    CHECK(back && back->channel_offset == NULL, "a version-1 file read with channel offsets");
    sasnav_run_free(back);
    back = NULL;

    sasnav_ping_pose off[4];
    for (int l = 0; l < 4; l++) {
        off[l].tx = (sasnav_pose){rng_uniform(-0.3, 0.3), rng_uniform(-0.05, 0.05), rng_uniform(-0.1, 0.1)};
        off[l].array = (sasnav_pose){rng_uniform(-0.1, 0.1), rng_uniform(-0.05, 0.05), rng_uniform(-0.1, 0.1)};
    }
    CHECK_OK(sasnav_run_set_channel_offset(run, off));
    const char *v2 = tmp_file("channels-v2.h5");
    CHECK_OK(sasnav_run_write(v2, run));
    CHECK(file_version(v2) == 2, "a run with channel offsets written as version %d", file_version(v2));
    CHECK_OK(sasnav_run_read(v2, &back));
    CHECK(back && runs_identical(run, back), "channel offsets: round trip is not bit-exact");
    sasnav_run_free(back);
    back = NULL;
    CHECK_OK(sasnav_run_open(v2, &back)); /* streamed: the same header */
    CHECK(back && back->channel_offset &&
              memcmp(back->channel_offset, off, sizeof off) == 0,
          "channel offsets: streamed open lost them");
    sasnav_run_free(back);
    back = NULL;

    /* Ping by ping: the writer takes the version from its header. */
    const char *w2 = tmp_file("channels-writer.h5");
    sasnav_run_writer *w = NULL;
    CHECK_OK(sasnav_run_writer_open(w2, run, &w));
    for (int p = 0; w && p < run->n_pings; p++) CHECK_OK(sasnav_run_writer_put(w, p, sasnav_run_ping(run, p)));
    if (w) CHECK_OK(sasnav_run_writer_finish(w, run));
    CHECK_OK(sasnav_run_read(w2, &back));
    CHECK(back && runs_identical(run, back) && file_version(w2) == 2, "channel offsets: writer round trip");
    sasnav_run_free(back);
    back = NULL;
    sasnav_run plain = *run; /* opened without offsets, finished with them */
    plain.channel_offset = NULL;
    w = NULL;
    CHECK_OK(sasnav_run_writer_open(tmp_file("channels-mismatch.h5"), &plain, &w));
    for (int p = 0; w && p < run->n_pings; p++) CHECK_OK(sasnav_run_writer_put(w, p, sasnav_run_ping(run, p)));
    if (w) CHECK_FAILS(sasnav_run_writer_finish(w, run), SASNAV_ERR_ARG);
    CHECK(dir_count(test_tmpdir(), "channels-mismatch") == 0, "a refused writer left a file");

    /* A subset keeps the offsets of the channels it keeps. */
    int pings[2] = {3, 1}, chans[2] = {2, 0};
    sasnav_run *sub = NULL;
    CHECK_OK(sasnav_run_subset(run, pings, 2, chans, 2, &sub));
    CHECK(sub && sub->channel_offset && memcmp(&sub->channel_offset[0], &off[2], sizeof off[0]) == 0 &&
              memcmp(&sub->channel_offset[1], &off[0], sizeof off[0]) == 0,
          "subset: channel offsets not carried");
    sasnav_run_free(sub);

    /* Bad offsets in memory and in files. */
    sasnav_ping_pose bad[4];
    memcpy(bad, off, sizeof bad);
    bad[1].array.theta = NAN;
    CHECK_FAILS(sasnav_run_set_channel_offset(run, bad), SASNAV_ERR_ARG);
    bad[1].array.theta = 0;
    bad[2].tx.x = 1e6;
    CHECK_FAILS(sasnav_run_set_channel_offset(run, bad), SASNAV_ERR_ARG);
    struct {
        const char *name, *expect;
        int kind; /* 0 version 1 with /channels, 1 NaN, 2 wrong count, 3 one dataset missing */
    } cases[] = {{"channels-badversion.h5", "format_version 2", 0},
                 {"channels-nan.h5", "not finite", 1},
                 {"channels-count.h5", "channels", 2},
                 {"channels-missing.h5", "/channels/array", 3}};
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        const char *path = tmp_file(cases[c].name);
        CHECK_OK(sasnav_run_write(path, run));
        hid_t f = open_rw(path);
        double v = NAN;
        switch (cases[c].kind) {
        case 0: set_attr_int(f, "/", "format_version", 1); break;
        case 1: poke(f, "/channels/tx", H5T_NATIVE_DOUBLE, 5, 2, &v); break;
        case 2: {
            hsize_t d[2] = {3, 3};
            double zeros[9] = {0};
            replace_dataset(f, "/channels/tx", H5T_NATIVE_DOUBLE, 2, d, zeros);
            replace_dataset(f, "/channels/array", H5T_NATIVE_DOUBLE, 2, d, zeros);
            break;
        }
        case 3: H5Ldelete(f, "/channels/array", H5P_DEFAULT); break;
        }
        H5Fclose(f);
        CHECK_FAILS(sasnav_run_read(path, &back), SASNAV_ERR_FORMAT);
        CHECK(strstr(sasnav_last_error(), cases[c].expect) != NULL,
              "%s: message '%s' does not say '%s'", cases[c].name, sasnav_last_error(), cases[c].expect);
        CHECK(back == NULL, "%s: run returned", cases[c].name);
        check_no_open_objects(cases[c].name);
    }
    sasnav_run_free(run);
}

/* Per-channel sizes (/array/sizes, format version 2): round trip bit for
 * bit through both writers and both readers, kept by subsets; the
 * array-wide values follow the channels (largest lengths, mean heights);
 * a version-1 file with /array/sizes, NaN, a negative length and a wrong
 * shape are refused with the dataset named. */
static void test_channel_sizes(void)
{
    sasnav_run *run = random_run(321, 5, 3, 16, 1), *back = NULL;
    if (!run) return;
    sasnav_channel_size z[3] = {{0.05, 0.02, 0.30, 0.25}, {0.0, 0.02, 0.20, 0.25}, {0.04, 0.03, 0.25, 0.26}};
    CHECK_OK(sasnav_array_set_sizes(&run->array, z));
    CHECK(run->array.per_channel == 1 && run->array.rx_length == 0.05 && run->array.tx_length == 0.03 &&
              fabs(run->array.rx_height - 0.25) < 1e-15 && fabs(run->array.tx_height - 0.76 / 3) < 1e-15,
          "array-wide values are not the channels' largest lengths and mean heights");
    CHECK(sasnav_array_min_rx_length(&run->array) == 0.04, "smallest nonzero rx length %g",
          sasnav_array_min_rx_length(&run->array));
    const char *path = tmp_file("sizes-v2.h5");
    CHECK_OK(sasnav_run_write(path, run));
    CHECK(file_version(path) == 2, "per-channel sizes written as version %d", file_version(path));
    CHECK_OK(sasnav_run_read(path, &back));
    CHECK(back && runs_identical(run, back), "per-channel sizes: round trip is not bit-exact");
    sasnav_run_free(back);
    back = NULL;
    CHECK_OK(sasnav_run_open(path, &back));
    CHECK(back && back->array.per_channel && memcmp(back->array.size, z, sizeof z) == 0,
          "per-channel sizes: streamed open lost them");
    sasnav_run_free(back);
    back = NULL;
    const char *w2 = tmp_file("sizes-writer.h5");
    sasnav_run_writer *w = NULL;
    CHECK_OK(sasnav_run_writer_open(w2, run, &w));
    for (int p = 0; w && p < run->n_pings; p++) CHECK_OK(sasnav_run_writer_put(w, p, sasnav_run_ping(run, p)));
    if (w) CHECK_OK(sasnav_run_writer_finish(w, run));
    CHECK_OK(sasnav_run_read(w2, &back));
    CHECK(back && runs_identical(run, back) && file_version(w2) == 2, "per-channel sizes: writer round trip");
    sasnav_run_free(back);
    back = NULL;

    int pings[2] = {3, 1}, chans[2] = {2, 1};
    sasnav_run *sub = NULL;
    CHECK_OK(sasnav_run_subset(run, pings, 2, chans, 2, &sub));
    CHECK(sub && sub->array.per_channel && memcmp(&sub->array.size[0], &z[2], sizeof z[0]) == 0 &&
              memcmp(&sub->array.size[1], &z[1], sizeof z[0]) == 0 && sub->array.rx_length == 0.04,
          "subset: per-channel sizes not carried");
    sasnav_run_free(sub);

    sasnav_channel_size bad[3];
    memcpy(bad, z, sizeof bad);
    bad[1].rx_height = NAN;
    sasnav_array before = run->array;
    CHECK_FAILS(sasnav_array_set_sizes(&run->array, bad), SASNAV_ERR_ARG);
    CHECK(strstr(sasnav_last_error(), "channel 1") != NULL, "message '%s' does not name the channel",
          sasnav_last_error());
    CHECK(memcmp(&before, &run->array, sizeof before) == 0, "a refused set_sizes changed the array");
    bad[1].rx_height = 0.2;
    bad[2].tx_length = -0.01;
    CHECK_FAILS(sasnav_array_set_sizes(&run->array, bad), SASNAV_ERR_ARG);
    struct {
        const char *name, *expect;
        int kind; /* 0 version 1, 1 NaN, 2 negative length, 3 wrong shape */
    } cases[] = {{"sizes-badversion.h5", "format_version 2", 0},
                 {"sizes-nan.h5", "finite", 1},
                 {"sizes-negative.h5", ">= 0", 2},
                 {"sizes-shape.h5", "/array/sizes", 3}};
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        const char *p = tmp_file(cases[c].name);
        CHECK_OK(sasnav_run_write(p, run));
        hid_t f = open_rw(p);
        double v = NAN;
        switch (cases[c].kind) {
        case 0: set_attr_int(f, "/", "format_version", 1); break;
        case 1: poke(f, "/array/sizes", H5T_NATIVE_DOUBLE, 6, 2, &v); break;
        case 2: v = -0.05; poke(f, "/array/sizes", H5T_NATIVE_DOUBLE, 4, 2, &v); break;
        case 3: {
            hsize_t d[2] = {2, 4};
            double zeros[8] = {0};
            replace_dataset(f, "/array/sizes", H5T_NATIVE_DOUBLE, 2, d, zeros);
            break;
        }
        }
        H5Fclose(f);
        CHECK_FAILS(sasnav_run_read(p, &back), SASNAV_ERR_FORMAT);
        CHECK(strstr(sasnav_last_error(), cases[c].expect) != NULL,
              "%s: message '%s' does not say '%s'", cases[c].name, sasnav_last_error(), cases[c].expect);
        CHECK(back == NULL, "%s: run returned", cases[c].name);
        check_no_open_objects(cases[c].name);
    }
    sasnav_run_free(run);
}

/* Replaces /raw of the run file at `path` by a chunked one (a chunk per
 * ping) of n_pings x 3 x 16 samples, deflated when `deflate`, of which
 * only ping 0 (`ping0`, 3 x 16 complex) is written. */
static void raw_first_ping_only(const char *path, hid_t c32, hsize_t n_pings, int deflate, const float *ping0)
{
    hid_t f = open_rw(path);
    H5Ldelete(f, "/raw", H5P_DEFAULT);
    hsize_t dims[3] = {n_pings, 3, 16}, chunk[3] = {1, 3, 16}, start[3] = {0, 0, 0};
    hid_t space = H5Screate_simple(3, dims, NULL), dcpl = H5Pcreate(H5P_DATASET_CREATE);
    H5Pset_chunk(dcpl, 3, chunk);
    if (deflate) H5Pset_deflate(dcpl, 6);
    hid_t dset = H5Dcreate2(f, "/raw", c32, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
    hid_t mspace = H5Screate_simple(3, chunk, NULL);
    H5Sselect_hyperslab(space, H5S_SELECT_SET, start, NULL, chunk, NULL);
    CHECK(H5Dwrite(dset, c32, mspace, space, H5P_DEFAULT, ping0) >= 0, "cannot write one ping");
    H5Sclose(mspace);
    H5Dclose(dset);
    H5Pclose(dcpl);
    H5Sclose(space);
    H5Fclose(f);
}

static void test_bad_run_files(void)
{
    sasnav_run *run = NULL;
    const char *path;
    hid_t f;
    printf("bad inputs:\n");

    CHECK_FAILS(sasnav_run_read(tmp_file("does-not-exist.h5"), &run), SASNAV_ERR_IO);
    CHECK_FAILS(sasnav_run_read(test_tmpdir(), &run), SASNAV_ERR_IO);
    path = tmp_file("text.h5");
    write_text(path, "this is not an HDF5 file\n");
    CHECK_FAILS(sasnav_run_read(path, &run), SASNAV_ERR_FORMAT);
    path = tmp_file("empty.h5");
    write_text(path, "");
    CHECK_FAILS(sasnav_run_read(path, &run), SASNAV_ERR_FORMAT);
    path = fresh_run_file("half.h5", 1);
    CHECK(copy_prefix(path, tmp_file("half-cut.h5"), 0.5) == 0, "cannot truncate");
    CHECK_FAILS(sasnav_run_read(tmp_file("half-cut.h5"), &run), SASNAV_ERR_FORMAT);
    CHECK(copy_prefix(path, tmp_file("almost.h5"), 0.98) == 0, "cannot truncate");
    CHECK_FAILS(sasnav_run_read(tmp_file("almost.h5"), &run), SASNAV_ERR_FORMAT);

    /* /raw missing */
    path = fresh_run_file("noraw.h5", 0);
    f = open_rw(path);
    H5Ldelete(f, "/raw", H5P_DEFAULT);
    H5Fclose(f);
    CHECK_FAILS(sasnav_run_read(path, &run), SASNAV_ERR_FORMAT);
    CHECK(strstr(sasnav_last_error(), "/raw") != NULL, "message should name /raw");

    /* /raw of the wrong rank (complex, 2-D) */
    path = fresh_run_file("rank.h5", 0);
    f = open_rw(path);
    hid_t c32 = complex_type(H5T_NATIVE_FLOAT, 4, "r", "i");
    test_open_types++;
    hsize_t d2[2] = {4, 48};
    replace_dataset(f, "/raw", c32, 2, d2, NULL);
    H5Fclose(f);
    CHECK_FAILS(sasnav_run_read(path, &run), SASNAV_ERR_FORMAT);
    CHECK(strstr(sasnav_last_error(), "rank") != NULL, "message should mention the rank");

    /* /raw not compound (float32) */
    hsize_t d3[3] = {4, 3, 16};
    float *zeros = calloc(3 * 4 * 3 * 16, sizeof(float)); /* up to 3 members */
    path = fresh_run_file("real.h5", 0);
    f = open_rw(path);
    replace_dataset(f, "/raw", H5T_NATIVE_FLOAT, 3, d3, zeros);
    H5Fclose(f);
    CHECK_FAILS(sasnav_run_read(path, &run), SASNAV_ERR_FORMAT);

    /* compound with the wrong member names */
    path = fresh_run_file("members.h5", 0);
    f = open_rw(path);
    hid_t bad = complex_type(H5T_NATIVE_FLOAT, 4, "re", "im");
    replace_dataset(f, "/raw", bad, 3, d3, zeros);
    H5Tclose(bad);
    H5Fclose(f);
    CHECK_FAILS(sasnav_run_read(path, &run), SASNAV_ERR_FORMAT);

    /* a third member, or integer members */
    path = fresh_run_file("members3.h5", 0);
    f = open_rw(path);
    hid_t c3 = H5Tcreate(H5T_COMPOUND, 12);
    H5Tinsert(c3, "r", 0, H5T_NATIVE_FLOAT);
    H5Tinsert(c3, "i", 4, H5T_NATIVE_FLOAT);
    H5Tinsert(c3, "w", 8, H5T_NATIVE_FLOAT);
    replace_dataset(f, "/raw", c3, 3, d3, zeros);
    H5Tclose(c3);
    H5Fclose(f);
    CHECK_FAILS(sasnav_run_read(path, &run), SASNAV_ERR_FORMAT);
    path = fresh_run_file("intmembers.h5", 0);
    f = open_rw(path);
    hid_t ci = complex_type(H5T_NATIVE_INT, 4, "r", "i");
    replace_dataset(f, "/raw", ci, 3, d3, zeros);
    H5Tclose(ci);
    H5Fclose(f);
    CHECK_FAILS(sasnav_run_read(path, &run), SASNAV_ERR_FORMAT);

    /* compound with float64 members is accepted and converted */
    path = fresh_run_file("f64.h5", 0);
    sasnav_run *ref = NULL;
    CHECK_OK(sasnav_run_read(path, &ref));
    f = open_rw(path);
    hid_t c64 = complex_type(H5T_NATIVE_DOUBLE, 8, "i", "r"); /* members in the other order */
    double *wide = malloc(2 * 4 * 3 * 16 * sizeof *wide);
    for (int k = 0; ref && k < 4 * 3 * 16; k++) { /* order (i, r) in the file */
        wide[2 * k] = cimagf(ref->raw[k]);
        wide[2 * k + 1] = crealf(ref->raw[k]);
    }
    replace_dataset(f, "/raw", c64, 3, d3, wide);
    H5Tclose(c64);
    H5Fclose(f);
    CHECK_OK(sasnav_run_read(path, &run));
    CHECK(run && ref && runs_identical(run, ref), "float64 {i, r} raw not converted exactly");
    sasnav_run_free(run);
    run = NULL;

    /* /raw claiming a million pings with one ping stored: rejected before
     * anything is allocated for it */
    path = fresh_run_file("sparse.h5", 0);
    raw_first_ping_only(path, c32, 1000000, 0, zeros);
    CHECK_FAILS(sasnav_run_read(path, &run), SASNAV_ERR_FORMAT);
    CHECK(strstr(sasnav_last_error(), "incomplete") != NULL, "message should say the data is incomplete");
    /* /raw compressed, chunk by ping, only ping 0 written (a writer that
     * died): the storage is within the compression's bounds, but chunks
     * are missing; their samples would read as zeros */
    path = fresh_run_file("partial-gzip.h5", 0);
    {
        float one[2 * 3 * 16];
        for (int k = 0; k < 2 * 3 * 16; k++) one[k] = 0.25f * (float)(k % 7) - 0.5f;
        raw_first_ping_only(path, c32, 4, 1, one);
    }
    CHECK_FAILS(sasnav_run_read(path, &run), SASNAV_ERR_FORMAT);
    CHECK(strstr(sasnav_last_error(), "chunks written") != NULL, "partial compressed /raw: '%s'",
          sasnav_last_error());
    /* a link out of the file (another file, or a FIFO that would block the
     * reader for ever): refused at open */
    path = fresh_run_file("external.h5", 0);
    f = open_rw(path);
    CHECK(H5Lcreate_external("elsewhere.h5", "/truth", f, "/truth_link", H5P_DEFAULT, H5P_DEFAULT) >= 0,
          "cannot make an external link");
    H5Fclose(f);
    CHECK_FAILS(sasnav_run_read(path, &run), SASNAV_ERR_FORMAT);
    CHECK(strstr(sasnav_last_error(), "external") != NULL, "external link: '%s'", sasnav_last_error());
    /* a dataset created but never written */
    path = fresh_run_file("unwritten.h5", 0);
    f = open_rw(path);
    hsize_t dn4[2] = {4, 3};
    replace_dataset(f, "/nav/tx", H5T_NATIVE_DOUBLE, 2, dn4, NULL);
    H5Fclose(f);
    CHECK_FAILS(sasnav_run_read(path, &run), SASNAV_ERR_FORMAT);

    /* NaN in raw samples */
    path = fresh_run_file("nanraw.h5", 0);
    f = open_rw(path);
    float nanpair[2] = {0.0f, NAN};
    poke(f, "/raw", c32, 77, 3, nanpair);
    H5Fclose(f);
    CHECK_FAILS(sasnav_run_read(path, &run), SASNAV_ERR_FORMAT);
    CHECK(strstr(sasnav_last_error(), "ping 1") != NULL, "message should locate the sample");

    /* nav with a wrong number of pings */
    path = fresh_run_file("navpings.h5", 1);
    f = open_rw(path);
    hsize_t dn[2] = {3, 3};
    double nav9[9] = {0};
    replace_dataset(f, "/nav/tx", H5T_NATIVE_DOUBLE, 2, dn, nav9);
    H5Fclose(f);
    CHECK_FAILS(sasnav_run_read(path, &run), SASNAV_ERR_FORMAT);
    CHECK(strstr(sasnav_last_error(), "/nav/tx") != NULL, "message should name /nav/tx");

    /* /nav/array disagreeing with /nav/tx */
    path = fresh_run_file("navarray.h5", 0);
    f = open_rw(path);
    replace_dataset(f, "/nav/array", H5T_NATIVE_DOUBLE, 2, dn, nav9);
    H5Fclose(f);
    CHECK_FAILS(sasnav_run_read(path, &run), SASNAV_ERR_FORMAT);

    /* truth with the wrong shape */
    path = fresh_run_file("truthshape.h5", 1);
    f = open_rw(path);
    hsize_t dt[2] = {4, 2};
    replace_dataset(f, "/truth/array", H5T_NATIVE_DOUBLE, 2, dt, nav9);
    H5Fclose(f);
    CHECK_FAILS(sasnav_run_read(path, &run), SASNAV_ERR_FORMAT);

    /* NaN in navigation (and in truth) */
    const char *nav_sets[2] = {"/nav/array", "/truth/tx"};
    for (int k = 0; k < 2; k++) {
        path = fresh_run_file("nannav.h5", 1);
        f = open_rw(path);
        double nan = NAN;
        poke(f, nav_sets[k], H5T_NATIVE_DOUBLE, 7, 2, &nan);
        H5Fclose(f);
        CHECK_FAILS(sasnav_run_read(path, &run), SASNAV_ERR_FORMAT);
        CHECK(strstr(sasnav_last_error(), nav_sets[k]) != NULL, "message should name %s", nav_sets[k]);
        int n;
        sasnav_ping_pose *nav = NULL, *truth = NULL;
        CHECK_FAILS(sasnav_nav_read(path, &n, &nav, &truth), SASNAV_ERR_FORMAT);
        CHECK(nav == NULL && truth == NULL, "outputs not cleared on failure");
    }

    /* rx_u length disagreeing with /raw */
    path = fresh_run_file("rxu.h5", 0);
    f = open_rw(path);
    hsize_t d1 = 5;
    double rxu[5] = {0, 1, 2, 3, 4};
    replace_dataset(f, "/array/rx_u", H5T_NATIVE_DOUBLE, 1, &d1, rxu);
    H5Fclose(f);
    CHECK_FAILS(sasnav_run_read(path, &run), SASNAV_ERR_FORMAT);
    CHECK(strstr(sasnav_last_error(), "rx_u") != NULL, "message should name rx_u");

    /* a missing system attribute */
    path = fresh_run_file("noattr.h5", 0);
    f = open_rw(path);
    H5Adelete_by_name(f, "/system", "f0", H5P_DEFAULT);
    H5Fclose(f);
    CHECK_FAILS(sasnav_run_read(path, &run), SASNAV_ERR_FORMAT);
    CHECK(strstr(sasnav_last_error(), "f0") != NULL, "message should name f0");

    /* invalid system values */
    path = fresh_run_file("fs.h5", 0);
    f = open_rw(path);
    set_attr_double(f, "/system", "sample_rate", 10.0);
    H5Fclose(f);
    CHECK_FAILS(sasnav_run_read(path, &run), SASNAV_ERR_FORMAT);
    path = fresh_run_file("inf.h5", 0);
    f = open_rw(path);
    set_attr_double(f, "/system", "speed", INFINITY);
    H5Fclose(f);
    CHECK_FAILS(sasnav_run_read(path, &run), SASNAV_ERR_FORMAT);
    path = fresh_run_file("taper.h5", 0);
    f = open_rw(path);
    set_attr_int(f, "/system", "taper", 7);
    H5Fclose(f);
    CHECK_FAILS(sasnav_run_read(path, &run), SASNAV_ERR_FORMAT);

    /* a string where a number belongs */
    path = fresh_run_file("strattr.h5", 0);
    f = open_rw(path);
    hid_t g = H5Gopen2(f, "/array", H5P_DEFAULT);
    set_attr_vlen_string(g, "rx_length", "5 cm");
    H5Gclose(g);
    H5Fclose(f);
    CHECK_FAILS(sasnav_run_read(path, &run), SASNAV_ERR_FORMAT);

    /* wrong format name, unsupported version; h5py-style strings accepted */
    path = fresh_run_file("format.h5", 0);
    f = open_rw(path);
    set_attr_vlen_string(f, "format", "sasnav-image");
    H5Fclose(f);
    CHECK_FAILS(sasnav_run_read(path, &run), SASNAV_ERR_FORMAT);
    path = fresh_run_file("version.h5", 0);
    f = open_rw(path);
    set_attr_int(f, "/", "format_version", 3);
    H5Fclose(f);
    CHECK_FAILS(sasnav_run_read(path, &run), SASNAV_ERR_FORMAT);
    path = fresh_run_file("vlen.h5", 0);
    f = open_rw(path);
    set_attr_vlen_string(f, "format", "sasnav-run");
    H5Fclose(f);
    CHECK_OK(sasnav_run_read(path, &run));
    sasnav_run_free(run);
    run = NULL;

    /* a plain HDF5 file without our attributes */
    path = tmp_file("plain.h5");
    f = H5Fcreate(path, H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    make_dataset(f, "/raw", c32, 3, d3, zeros);
    H5Fclose(f);
    CHECK_FAILS(sasnav_run_read(path, &run), SASNAV_ERR_FORMAT);

    CHECK(run == NULL, "run pointer set after failures");
    H5Tclose(c32);
    test_open_types--;
    free(zeros);
    free(wide);
    sasnav_run_free(ref);
}

/* Physically impossible values in an otherwise well-formed run file: each
 * refused with SASNAV_ERR_FORMAT and a message naming the file and the
 * value (docs/format.md, "Plausibility"). */
static void test_implausible_runs(void)
{
    printf("implausible runs:\n");
    static const struct {
        const char *obj, *attr;
        double value;
        const char *says;
    } cases[] = {
        {"/system", "sound_speed", 15.0, "sound_speed"},      /* nothing carries sound so slowly */
        {"/system", "sound_speed", 15000.0, "sound_speed"},   /* nor so fast (steel: 5900) */
        {"/system", "f0", 50.0, "f0"},                        /* below the band's use for imaging */
        {"/system", "f0", 1e9, "f0"},
        {"/system", "sample_rate", 1e12, "sample_rate"},
        {"/system", "speed", 1000.0, "speed"},               /* 2000 kn */
        {"/system", "ping_spacing", 1e4, "ping_spacing"},
        {"/system", "range_of_interest", 1e7, "range_of_interest"},
        {"/system", "t0", 200.0, "window"},                   /* 150 km of travel before sample 0 */
        {"/array", "rx_height", -1e5, "heights"},
        {"/array", "rx_length", 500.0, "element lengths"},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        char name[64];
        snprintf(name, sizeof name, "implausible-%zu.h5", k);
        const char *path = fresh_run_file(name, 0);
        hid_t f = open_rw(path);
        set_attr_double(f, cases[k].obj, cases[k].attr, cases[k].value);
        H5Fclose(f);
        sasnav_run *run = NULL;
        CHECK_FAILS(sasnav_run_read(path, &run), SASNAV_ERR_FORMAT);
        CHECK(strstr(sasnav_last_error(), name) && strstr(sasnav_last_error(), cases[k].says),
              "%s %s = %g: the message should name the file and %s: %s", cases[k].obj,
              cases[k].attr, cases[k].value, cases[k].says, sasnav_last_error());
        sasnav_run_free(run);
    }
    /* a receiver 1 km from the array's centre, a transmitter 200 m from its array */
    const char *path = fresh_run_file("implausible-rx.h5", 0);
    hid_t f = open_rw(path);
    double far = 1000.0;
    poke(f, "/array/rx_u", H5T_NATIVE_DOUBLE, 1, 1, &far);
    H5Fclose(f);
    sasnav_run *run = NULL;
    CHECK_FAILS(sasnav_run_read(path, &run), SASNAV_ERR_FORMAT);
    CHECK(strstr(sasnav_last_error(), "rx_u[1]") != NULL, "message names rx_u[1]: %s",
          sasnav_last_error());
    path = fresh_run_file("implausible-tx.h5", 0);
    f = open_rw(path);
    double tx_x = 200.0;
    poke(f, "/nav/tx", H5T_NATIVE_DOUBLE, 3 * 2, 2, &tx_x); /* ping 2, x */
    H5Fclose(f);
    CHECK_FAILS(sasnav_run_read(path, &run), SASNAV_ERR_FORMAT);
    CHECK(strstr(sasnav_last_error(), "ping 2") && strstr(sasnav_last_error(), "transmitter"),
          "message names ping 2's transmitter: %s", sasnav_last_error());
}

static void test_bad_image_files(void)
{
    sasnav_grid grid, gb;
    CHECK_OK(sasnav_grid_make(0, 1, 4, 10, 11, 3, &grid));
    sasnav_cfloat img[12] = {0};
    sasnav_cfloat *back = NULL;
    const char *path = tmp_file("badimage.h5");
    hsize_t d4 = 4;
    double x[4] = {0, 0.25, 0.6, 1.0};

    /* /x of the wrong length */
    CHECK_OK(sasnav_image_write(path, &grid, img));
    hid_t f = open_rw(path);
    hsize_t d3 = 3;
    replace_dataset(f, "/x", H5T_NATIVE_DOUBLE, 1, &d3, x);
    H5Fclose(f);
    CHECK_FAILS(sasnav_image_read(path, &gb, &back), SASNAV_ERR_FORMAT);
    /* /x disagreeing with the grid attributes */
    CHECK_OK(sasnav_image_write(path, &grid, img));
    f = open_rw(path);
    replace_dataset(f, "/x", H5T_NATIVE_DOUBLE, 1, &d4, x);
    H5Fclose(f);
    CHECK_FAILS(sasnav_image_read(path, &gb, &back), SASNAV_ERR_FORMAT);
    /* without attributes, the grid comes from uniform /x, /y ... */
    CHECK_OK(sasnav_image_write(path, &grid, img));
    f = open_rw(path);
    const char *attrs[4] = {"x0", "dx", "y0", "dy"};
    for (int k = 0; k < 4; k++) H5Adelete_by_name(f, "/image", attrs[k], H5P_DEFAULT);
    H5Fclose(f);
    CHECK_OK(sasnav_image_read(path, &gb, &back));
    CHECK(back && gb.nx == 4 && gb.ny == 3 && fabs(gb.dx - 1.0 / 3) < 1e-15 && gb.y0 == 10.0,
          "grid from coordinates is wrong");
    free(back);
    back = NULL;
    /* ... and non-uniform /x is rejected */
    f = open_rw(path);
    replace_dataset(f, "/x", H5T_NATIVE_DOUBLE, 1, &d4, x);
    H5Fclose(f);
    CHECK_FAILS(sasnav_image_read(path, &gb, &back), SASNAV_ERR_FORMAT);
    /* NaN pixel */
    CHECK_OK(sasnav_image_write(path, &grid, img));
    f = open_rw(path);
    hid_t c32 = complex_type(H5T_NATIVE_FLOAT, 4, "r", "i");
    float nanpair[2] = {NAN, 0};
    poke(f, "/image", c32, 5, 2, nanpair);
    H5Tclose(c32);
    H5Fclose(f);
    CHECK_FAILS(sasnav_image_read(path, &gb, &back), SASNAV_ERR_FORMAT);
    /* a run is not an image */
    CHECK_FAILS(sasnav_image_read(fresh_run_file("notimage.h5", 0), &gb, &back), SASNAV_ERR_FORMAT);
    CHECK(back == NULL, "image pointer set after failure");
}

/* --- writers -------------------------------------------------------------------- */

static void test_writers_fail_cleanly(void)
{
    sasnav_run *run = random_run(9, 2, 2, 8, 1);
    sasnav_grid grid;
    CHECK_OK(sasnav_grid_make(0, 1, 2, 0, 1, 2, &grid));
    sasnav_cfloat img[4] = {1, 2, 3, 4};
    const char *dir = test_tmpdir();
    int before = dir_count(dir, "");
    printf("writer failures:\n");

    /* A directory that does not exist. */
    CHECK_FAILS(sasnav_run_write(tmp_file("no-such-dir/run.h5"), run), SASNAV_ERR_IO);
    CHECK_FAILS(sasnav_nav_write(tmp_file("no-such-dir/nav.h5"), run->n_pings, run->nav, NULL),
                SASNAV_ERR_IO);
    CHECK_FAILS(sasnav_image_write(tmp_file("no-such-dir/image.h5"), &grid, img), SASNAV_ERR_IO);
    CHECK(dir_count(dir, "") == before, "files appeared in %s", dir);
    CHECK(dir_count(dir, "no-such-dir") == 0, "directory appeared");

    /* The target is a non-empty directory: everything is written, the final
     * rename fails, the temporary file must go. */
    const char *target = tmp_file("occupied");
    mkdir(target, 0755);
    write_text(tmp_file("occupied/keep"), "x");
    before = dir_count(dir, "");
    CHECK_FAILS(sasnav_run_write(target, run), SASNAV_ERR_IO);
    CHECK_FAILS(sasnav_image_write(target, &grid, img), SASNAV_ERR_IO);
    CHECK(dir_count(dir, "") == before && dir_count(dir, ".tmp-") == 0, "temporary file left behind");

    /* The target is a pipe (as /dev/null is a device): refused before
     * anything is written; renaming onto it would replace it by a file. */
    const char *fifo = tmp_file("a-fifo");
    CHECK(mkfifo(fifo, 0644) == 0, "cannot make a FIFO");
    CHECK_FAILS(sasnav_run_write(fifo, run), SASNAV_ERR_IO);
    CHECK_FAILS(sasnav_nav_write(fifo, run->n_pings, run->nav, NULL), SASNAV_ERR_IO);
    CHECK_FAILS(sasnav_image_write(fifo, &grid, img), SASNAV_ERR_IO);
    CHECK(strstr(sasnav_last_error(), "not a regular file") != NULL, "message: %s", sasnav_last_error());
    struct stat fst;
    CHECK(stat(fifo, &fst) == 0 && S_ISFIFO(fst.st_mode), "the FIFO was replaced");
    unlink(fifo);

    /* Invalid data: nothing is created, an existing file is kept. */
    const char *path = tmp_file("kept.h5");
    CHECK_OK(sasnav_run_write(path, run));
    before = dir_count(dir, "");
    double saved = run->nav[1].array.y;
    run->nav[1].array.y = NAN;
    CHECK_FAILS(sasnav_run_write(path, run), SASNAV_ERR_ARG);
    CHECK_FAILS(sasnav_nav_write(path, run->n_pings, run->nav, NULL), SASNAV_ERR_ARG);
    run->nav[1].array.y = saved;
    img[2] = NAN;
    CHECK_FAILS(sasnav_image_write(path, &grid, img), SASNAV_ERR_ARG);
    sasnav_run *back = NULL;
    CHECK_OK(sasnav_run_read(path, &back));
    CHECK(back && runs_identical(run, back), "existing file changed by a failed write");
    CHECK(dir_count(dir, "") == before, "failed writes changed the directory");
    sasnav_run_free(back);

    /* An unwritable directory (meaningless as root, who may write anyway). */
    if (geteuid() != 0) {
        const char *ro = tmp_file("readonly");
        mkdir(ro, 0555);
        CHECK_FAILS(sasnav_run_write(tmp_file("readonly/run.h5"), run), SASNAV_ERR_IO);
        CHECK(dir_count(ro, "") == 0, "file created in a read-only directory");
    } else {
        printf("  SKIP read-only directory check (running as root)\n");
    }
    sasnav_run_free(run);
}

/* --- h5py ----------------------------------------------------------------------- */

/* A Python interpreter with h5py and numpy: $SASNAV_PYTHON, python3 on the
 * PATH, or the system's (a virtualenv's python3 may lack h5py). */
static const char *python_with_h5py(void)
{
    static const char *candidates[] = {NULL, "python3", "/usr/bin/python3"};
    candidates[0] = getenv("SASNAV_PYTHON");
    for (int k = 0; k < 3; k++) {
        char cmd[512];
        if (!candidates[k] || strchr(candidates[k], '\'')) continue;
        snprintf(cmd, sizeof cmd, "'%s' -c 'import h5py, numpy' >/dev/null 2>&1", candidates[k]);
        if (system(cmd) == 0) return candidates[k];
    }
    return NULL;
}

static void test_h5py(void)
{
    const char *python = python_with_h5py();
    if (!python) {
        printf("SKIP h5py check: no python3 with h5py and numpy\n");
        return;
    }
    /* Values the script can recompute exactly. */
    sasnav_grid grid;
    CHECK_OK(sasnav_grid_make(-1, 1, 5, 2, 3, 3, &grid));
    sasnav_cfloat img[15];
    for (int iy = 0; iy < 3; iy++)
        for (int ix = 0; ix < 5; ix++) img[iy * 5 + ix] = (ix + 0.25f) + I * (iy - 0.5f * ix);
    const char *ipath = tmp_file("py_image.h5");
    CHECK_OK(sasnav_image_write(ipath, &grid, img));
    sasnav_run *run = random_run(3, 2, 3, 4, 0);
    for (int p = 0; p < 2; p++)
        for (int l = 0; l < 3; l++)
            for (int m = 0; m < 4; m++) run->raw[(p * 3 + l) * 4 + m] = (100 * p + 10 * l + m) - I * 0.5f * m;
    const char *rpath = tmp_file("py_run.h5");
    CHECK_OK(sasnav_run_write(rpath, run));

    char cmd[2048];
    snprintf(cmd, sizeof cmd,
             "'%s' -c '\n"
             "import h5py, numpy as np, sys\n"
             "f = h5py.File(sys.argv[1], \"r\")\n"
             "a = f[\"image\"][...]\n"
             "iy, ix = np.mgrid[0:3, 0:5]\n"
             "want = ((ix + 0.25) + 1j * (iy - 0.5 * ix)).astype(np.complex64)\n"
             "assert a.dtype == np.complex64, a.dtype\n"
             "assert a.shape == (3, 5), a.shape\n"
             "assert (a == want).all(), a\n"
             "assert f.attrs[\"format\"] == b\"sasnav-image\", f.attrs[\"format\"]\n"
             "assert int(f.attrs[\"format_version\"]) == 1\n"
             "assert np.allclose(f[\"x\"][...], np.linspace(-1, 1, 5)) and f[\"x\"].dtype == np.float64\n"
             "g = h5py.File(sys.argv[2], \"r\")\n"
             "r = g[\"raw\"][...]\n"
             "p, l, m = np.mgrid[0:2, 0:3, 0:4]\n"
             "assert r.dtype == np.complex64 and r.shape == (2, 3, 4), (r.dtype, r.shape)\n"
             "assert (r == (100 * p + 10 * l + m - 0.5j * m)).all(), r\n"
             "assert g[\"nav/tx\"].shape == (2, 3) and g[\"nav/tx\"].dtype == np.float64\n"
             "assert g[\"nav/tx\"].attrs[\"units\"] == b\"m, m, rad\"\n"
             "assert g[\"system\"].attrs[\"beam_pattern\"] == 0\n"
             "assert \"truth\" not in g\n"
             "' '%s' '%s'",
             python, ipath, rpath);
    int status = system(cmd);
    CHECK(status == 0, "h5py could not read the files as expected (status %d)", status);
    if (status == 0) printf("h5py reads /image and /raw as complex64 with the expected values\n");
    sasnav_run_free(run);
}

/* --- containers ------------------------------------------------------------------ */

static void test_grid(void)
{
    sasnav_grid g;
    CHECK_OK(sasnav_grid_make(-1, 2, 4, 5, 6, 3, &g));
    CHECK(g.x0 == -1 && g.dx == 1 && g.y0 == 5 && g.dy == 0.5 && g.nx == 4 && g.ny == 3, "grid_make");
    double x[12], y[12];
    sasnav_pose identity = {0, 0, 0};
    sasnav_grid_points(&g, identity, x, y);
    CHECK(x[0] == -1 && y[0] == 5 && x[3] == 2 && y[3] == 5 && x[4] == -1 && y[4] == 5.5 && x[11] == 2 &&
              y[11] == 6,
          "grid_points order: n = iy * nx + ix");
    /* A quarter turn about (10, 20): local (px, py) -> (10 - py, 20 + px). */
    sasnav_pose frame = {10, 20, M_PI / 2};
    sasnav_grid_points(&g, frame, x, y);
    double err = 0;
    for (int iy = 0; iy < 3; iy++)
        for (int ix = 0; ix < 4; ix++) {
            int n = iy * 4 + ix;
            err = fmax(err, fabs(x[n] - (10 - (5 + 0.5 * iy))) + fabs(y[n] - (20 + (-1 + ix))));
        }
    CHECK(err < 1e-12, "grid_points frame transform error %g", err); /* rounding of cos(pi/2) */
    CHECK_OK(sasnav_grid_make(3, 3, 1, 0, 2, 5, &g));
    CHECK(g.dx == g.dy && g.dy == 0.5, "single-pixel axis takes the other spacing");
    CHECK_FAILS(sasnav_grid_make(1, 0, 4, 0, 1, 4, &g), SASNAV_ERR_ARG);
    CHECK_FAILS(sasnav_grid_make(0, 1, 1, 0, 1, 4, &g), SASNAV_ERR_ARG);
    CHECK_FAILS(sasnav_grid_make(0, 1, 0, 0, 1, 4, &g), SASNAV_ERR_ARG);
    CHECK_FAILS(sasnav_grid_make(0, NAN, 3, 0, 1, 4, &g), SASNAV_ERR_ARG);
    CHECK_FAILS(sasnav_grid_make(0, 1, 100000, 0, 1, 100000, &g), SASNAV_ERR_ARG);
    sasnav_grid z = {0, 0, 0, 1, 2, 2};
    CHECK_FAILS(sasnav_grid_check(&z), SASNAV_ERR_ARG);
}

static void test_run_container(void)
{
    sasnav_run *run = random_run(1, 3, 4, 5, 0);
    CHECK(run && run->truth == NULL, "alloc without truth");
    if (!run) return;
    CHECK_OK(sasnav_run_check(run));
    CHECK(sasnav_run_ping(run, 0) == run->raw && sasnav_run_ping(run, 2) == run->raw + 2 * 4 * 5,
          "ping pointers");
    CHECK(sasnav_run_ping(run, 3) == NULL && sasnav_run_ping(run, -1) == NULL, "out-of-range ping");
    run->raw[17] = NAN;
    CHECK_FAILS(sasnav_run_check(run), SASNAV_ERR_ARG);
    run->raw[17] = 0;
    run->speed = -1;
    CHECK_FAILS(sasnav_run_check(run), SASNAV_ERR_ARG);
    run->speed = 1;
    run->nav[2].tx.theta = INFINITY;
    CHECK_FAILS(sasnav_run_check(run), SASNAV_ERR_ARG);
    sasnav_run *r2 = NULL;
    sasnav_window win = {0, 0};
    CHECK_FAILS(sasnav_run_alloc(&run->sys, &run->array, &win, 2, 0, &r2), SASNAV_ERR_ARG);
    win.n_samples = 4;
    CHECK_FAILS(sasnav_run_alloc(&run->sys, &run->array, &win, 0, 0, &r2), SASNAV_ERR_ARG);
    win.n_samples = 1 << 30;
    CHECK_FAILS(sasnav_run_alloc(&run->sys, &run->array, &win, 1 << 30, 0, &r2), SASNAV_ERR_ARG);
    CHECK(r2 == NULL, "failed alloc set the run");
    sasnav_run_free(run);
    sasnav_run_free(NULL);
}

int main(void)
{
    test_aiding();
    test_channels();
    test_channel_sizes();
    test_grid();
    test_run_container();
    test_run_round_trip();
    test_nav_round_trip();
    test_image_round_trip();
    test_bad_run_files();
    test_implausible_runs();
    test_bad_image_files();
    test_writers_fail_cleanly();
    test_h5py();
    check_no_open_objects("end");
    return test_summary("test_io");
}
