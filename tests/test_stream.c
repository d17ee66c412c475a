/* Survey scale (docs/survey.md): streamed runs (sasnav_run_open) give the
 * same pings, images and navigations as runs read whole; backprojection in
 * tiles and bands of rows gives the same bits as one pass over the grid;
 * the parts of a distributed navigation (sasnav_navigate_part) recombine
 * into the same bits as one sasnav_navigate; a corrupt ping is an error
 * that names it, when it is read. */
#include "sasnav/error.h"
#include "sasnav/image.h"
#include "sasnav/io.h"
#include "sasnav/navigate.h"
#include "sasnav/sim.h"
#include "testutil.h"

#include <hdf5.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static sasnav_run *simulate(int n_pings, uint64_t seed)
{
    sasnav_scenario sc;
    if (sasnav_scenario_preset("paper-trajectory", &sc)) return NULL;
    sasnav_scenario_seed(&sc, seed);
    sc.traj.n_pings = n_pings;
    sc.traj.x_start = -0.5 * (n_pings - 1) * sc.traj.ping_spacing;
    sc.snr_db = 30;
    sasnav_run *run = NULL;
    int rc = sasnav_simulate(&sc, NULL, NULL, &run);
    CHECK(rc == 0, "simulation failed: %s", sasnav_last_error());
    return rc ? NULL : run;
}

/* Streamed and whole runs hold the same pings, navigation and constants. */
static void test_open_matches_read(const char *path, const sasnav_run *mem)
{
    sasnav_run *st = NULL;
    CHECK_OK(sasnav_run_open(path, &st));
    if (!st) return;
    CHECK(st->raw == NULL && st->source.read, "a streamed run holds no samples");
    CHECK(sasnav_run_ping(st, 0) == NULL, "sasnav_run_ping of a streamed run is NULL");
    CHECK(st->n_pings == mem->n_pings && st->array.n_rx == mem->array.n_rx &&
              st->win.n_samples == mem->win.n_samples,
          "shape");
    CHECK(!memcmp(st->nav, mem->nav, sizeof *st->nav * (size_t)st->n_pings), "navigation");
    CHECK(st->truth && !memcmp(st->truth, mem->truth, sizeof *st->truth * (size_t)st->n_pings), "truth");
    CHECK(st->tx_lag == mem->tx_lag && st->range_of_interest == mem->range_of_interest, "constants");
    CHECK_OK(sasnav_run_check(st));
    size_t n = sasnav_run_ping_size(st);
    sasnav_cfloat *buf = malloc(sizeof *buf * n);
    /* In a shuffled order: the source seeks. */
    for (int k = 0; k < st->n_pings; k++) {
        int p = (5 * k + 3) % st->n_pings;
        const sasnav_cfloat *got = NULL;
        CHECK_OK(sasnav_run_get_ping(st, p, buf, &got));
        CHECK(got == buf && !memcmp(buf, sasnav_run_ping(mem, p), sizeof *buf * n), "ping %d differs", p);
    }
    const sasnav_cfloat *got = NULL;
    CHECK(sasnav_run_get_ping(st, st->n_pings, buf, &got) == SASNAV_ERR_ARG && !got, "ping out of range");
    CHECK(sasnav_run_get_ping(st, 0, NULL, &got) == SASNAV_ERR_ARG, "a streamed ping needs a buffer");
    /* A subset of a streamed run is an in-memory run with the same pings. */
    int pick[2] = {3, 1}, chan[2] = {5, 2};
    sasnav_run *sub = NULL;
    CHECK_OK(sasnav_run_subset(st, pick, 2, chan, 2, &sub));
    if (sub) {
        size_t ns = (size_t)st->win.n_samples;
        for (int i = 0; i < 2; i++)
            for (int l = 0; l < 2; l++)
                CHECK(!memcmp(sasnav_run_ping(sub, i) + l * ns, sasnav_run_ping(mem, pick[i]) + chan[l] * ns,
                              sizeof *buf * ns),
                      "subset ping %d channel %d", i, l);
    }
    sasnav_run_free(sub);
    free(buf);
    sasnav_run_free(st);
}

/* Backprojection: streamed = in memory; bands of rows = the whole grid;
 * a grid of several tiles (over SASNAV_BACKPROJECT_TILE_PAIRS pairs) = the
 * same rows made as separate calls. */
static void test_backprojection(const char *path, const sasnav_run *mem)
{
    sasnav_run *st = NULL;
    CHECK_OK(sasnav_run_open(path, &st));
    if (!st) return;
    sasnav_op_opts oo;
    sasnav_op_default_opts(&oo);
    oo.nthreads = 1;
#ifdef SASNAV_TEST_SANITIZED
    int nx = 81, ny = 41;
#else
    /* 641 x 451 pixels x 16 channels = 4.6 M pairs: two tiles. */
    int nx = 641, ny = 451;
#endif
    sasnav_grid g;
    CHECK_OK(sasnav_grid_make(-1.6, 1.6, nx, 9.2, 10.8, ny, &g));
    size_t np = (size_t)nx * (size_t)ny;
    sasnav_cfloat *a = malloc(sizeof *a * np), *b = malloc(sizeof *b * np);
    CHECK_OK(sasnav_backproject(mem, mem->truth, &g, &oo, a));
    CHECK_OK(sasnav_backproject(st, st->truth, &g, &oo, b));
    CHECK(!memcmp(a, b, sizeof *a * np), "streamed and in-memory backprojections differ");
    double energy = 0;
    for (size_t j = 0; j < np; j++) energy += crealf(a[j]) * crealf(a[j]) + cimagf(a[j]) * cimagf(a[j]);
    CHECK(energy > 0, "the image is empty (the comparison would be void)");
    /* Three uneven bands, each made alone. */
    int cut[4] = {0, ny / 3, ny / 3 + 1, ny};
    memset(b, 0, sizeof *b * np);
    for (int k = 0; k < 3; k++)
        CHECK_OK(sasnav_backproject_rows(st, st->truth, &g, cut[k], cut[k + 1], &oo, b + (size_t)cut[k] * nx,
                                         NULL, NULL));
    CHECK(!memcmp(a, b, sizeof *a * np), "bands of rows differ from the whole grid");
    sasnav_cfloat dummy;
    CHECK(sasnav_backproject_rows(st, st->truth, &g, 2, 2, &oo, &dummy, NULL, NULL) == SASNAV_ERR_ARG,
          "an empty band is refused");
    CHECK(sasnav_backproject_rows(st, st->truth, &g, 0, ny + 1, &oo, b, NULL, NULL) == SASNAV_ERR_ARG,
          "rows beyond the grid are refused");
    free(a);
    free(b);

    /* Culling: a grid reaching 40 m along track, three tiles wide; the
     * pings (within 1 m of x = 0, window up to ~11 m) cannot reach the
     * tiles beyond ~13 m, which are skipped. Reference: one operator over
     * every pixel and every ping, no tiles, no culling. */
    CHECK_OK(sasnav_grid_make(-1.6, 40.0, 1101, 9.5, 10.5, 21, &g));
    np = (size_t)g.nx * (size_t)g.ny;
    a = malloc(sizeof *a * np);
    b = malloc(sizeof *b * np);
    double *x = malloc(sizeof(double) * np), *y = malloc(sizeof(double) * np);
    sasnav_grid_points(&g, (sasnav_pose){0, 0, 0}, x, y);
    sasnav_op *op = NULL;
    CHECK_OK(sasnav_op_create(&mem->sys, &mem->array, &mem->win, (int)np, x, y, &oo, &op));
    memset(a, 0, sizeof *a * np);
    for (int p = 0; op && p < mem->n_pings; p++) {
        CHECK_OK(sasnav_op_set_geometry(op, &mem->truth[p]));
        CHECK_OK(sasnav_op_adjoint_add(op, sasnav_run_ping(mem, p), a));
    }
    sasnav_op_destroy(op);
    free(x);
    free(y);
    CHECK_OK(sasnav_backproject(st, st->truth, &g, &oo, b));
    CHECK(!memcmp(a, b, sizeof *a * np), "tiles with culling differ from one direct operator");
    int far_zero = 1, near_nonzero = 0;
    for (int iy = 0; iy < g.ny; iy++)
        for (int ix = 0; ix < g.nx; ix++) {
            double px = g.x0 + ix * g.dx, v = cabsf(b[(size_t)iy * g.nx + ix]);
            if (px > 20.0 && v != 0) far_zero = 0;
            if (px < 1.0 && v > 0) near_nonzero = 1;
        }
    CHECK(far_zero && near_nonzero, "the image is not zero far away / nonzero near the pings");
    free(a);
    free(b);
    sasnav_run_free(st);
}

/* Parts of a navigation recombine into the same bits as one navigation. */
static int nav_equal(const sasnav_navigation *x, const sasnav_navigation *y)
{
    if (x->n_pairs != y->n_pairs || x->n_pings != y->n_pings) return 0;
    for (int j = 0; j < x->n_pairs; j++) {
        const sasnav_navigate_pair *a = &x->pairs[j], *b = &y->pairs[j];
        if (a->p != b->p || a->q != b->q || a->status != b->status || a->verdict != b->verdict ||
            memcmp(&a->fused, &b->fused, sizeof a->fused) ||
            memcmp(&a->result.error, &b->result.error, sizeof a->result.error))
            return 0;
    }
    return !memcmp(x->nav, y->nav, sizeof *x->nav * (size_t)x->n_pings);
}

static void count_resumed(const sasnav_navigate_progress *pr, void *user)
{
    int *c = user;
    if (pr->result) {
        c[0]++;
        c[1] += pr->resumed;
    }
}

static void test_parts(const char *path, int method)
{
    sasnav_run *st = NULL;
    CHECK_OK(sasnav_run_open(path, &st));
    if (!st) return;
    sasnav_navigate_opts o;
    sasnav_navigate_default_opts(&o);
    o.method = method;
    o.nthreads = 1;
    o.pair.k = 2; /* coarse: the equality, not the accuracy, is tested */
    o.pair.i = 1;
    o.long_baselines = method == SASNAV_METHOD_DPCA; /* consecutive and long pairs interleaved */
    sasnav_navigation whole;
    CHECK_OK(sasnav_navigate(st, &o, &whole));
    const int n_parts = 3;
    sasnav_pair_record *all = NULL;
    int n_all = 0;
    for (int part = 0; part < n_parts; part++) {
        sasnav_pair_record *r = NULL;
        int n = 0;
        CHECK_OK(sasnav_navigate_part(st, &o, part, n_parts, &r, &n));
        all = realloc(all, sizeof *all * (size_t)(n_all + n + 1));
        if (n) memcpy(all + n_all, r, sizeof *r * (size_t)n);
        n_all += n;
        free(r);
    }
    CHECK(n_all == whole.n_pairs, "the parts hold %d pairs, the navigation %d", n_all, whole.n_pairs);
    /* Recombined: no pair estimated again (each taken from a record). */
    int counts[2] = {0, 0};
    o.done = all;
    o.n_done = n_all;
    o.progress = count_resumed;
    o.progress_user = counts;
    sasnav_navigation joined;
    CHECK_OK(sasnav_navigate(st, &o, &joined));
    CHECK(counts[0] == n_all && counts[1] == n_all, "%d of %d pairs reported, %d resumed", counts[0], n_all,
          counts[1]);
    CHECK(nav_equal(&whole, &joined), "method %d: the recombined parts differ from one navigation", method);
    sasnav_pair_record *r = NULL;
    int n = 0;
    CHECK(sasnav_navigate_part(st, &o, 3, 3, &r, &n) == SASNAV_ERR_ARG && !r, "part 3 of 3 is refused");
    CHECK(sasnav_navigate_part(st, &o, 0, 0, &r, &n) == SASNAV_ERR_ARG, "0 parts are refused");
    sasnav_navigation_free(&whole);
    sasnav_navigation_free(&joined);
    free(all);
    sasnav_run_free(st);
}

/* A ping made non-finite in the file: opening refuses it up front (every
 * ping is checked once as it is opened), with the message of a whole read.
 * A source that fails when a ping is read later (a disk error) makes a
 * navigation and a backprojection stop with its message, no crash. */
static int failing_read(void *ctx, int p, sasnav_cfloat *out)
{
    const sasnav_run *mem = ctx;
    if (p == 2) return sasnav_set_error(SASNAV_ERR_IO, "disk error reading ping 2");
    memcpy(out, sasnav_run_ping(mem, p), sizeof *out * sasnav_run_ping_size(mem));
    return SASNAV_OK;
}

static void test_corrupt_ping(const char *path, const sasnav_run *mem)
{
    hid_t f = H5Fopen(path, H5F_ACC_RDWR, H5P_DEFAULT);
    hid_t d = H5Dopen2(f, "/raw", H5P_DEFAULT);
    hid_t fs = H5Dget_space(d);
    hsize_t start[3] = {2, 3, 10}, count[3] = {1, 1, 1};
    H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, NULL, count, NULL);
    hid_t ms = H5Screate_simple(3, count, NULL);
    hid_t t = H5Tcreate(H5T_COMPOUND, 2 * sizeof(float));
    H5Tinsert(t, "r", 0, H5T_NATIVE_FLOAT);
    H5Tinsert(t, "i", sizeof(float), H5T_NATIVE_FLOAT);
    float v[2] = {NAN, 0};
    CHECK(H5Dwrite(d, t, ms, fs, H5P_DEFAULT, v) >= 0, "could not corrupt the file");
    H5Tclose(t);
    H5Sclose(ms);
    H5Sclose(fs);
    H5Dclose(d);
    H5Fclose(f);

    sasnav_run *st = NULL;
    int rc = sasnav_run_open(path, &st);
    CHECK(rc == SASNAV_ERR_FORMAT && !st && strstr(sasnav_last_error(), "ping 2") &&
              strstr(sasnav_last_error(), "channel 3") && strstr(sasnav_last_error(), path),
          "corrupt ping at open: %d %s", rc, sasnav_last_error());
    char open_msg[512];
    snprintf(open_msg, sizeof open_msg, "%s", sasnav_last_error());
    sasnav_run *whole = NULL;
    CHECK(sasnav_run_read(path, &whole) == SASNAV_ERR_FORMAT && !whole, "the whole read refuses it too");
    CHECK(!strcmp(open_msg, sasnav_last_error()), "different messages: '%s' and '%s'", open_msg,
          sasnav_last_error());

    sasnav_ping_source src = {failing_read, NULL, (void *)mem};
    CHECK_OK(sasnav_run_alloc_streamed(&mem->sys, &mem->array, &mem->win, mem->n_pings, 0, &src, &st));
    if (!st) return;
    memcpy(st->nav, mem->nav, sizeof *st->nav * (size_t)mem->n_pings);
    st->ping_spacing = mem->ping_spacing;
    st->tx_lag = mem->tx_lag;
    st->range_of_interest = mem->range_of_interest;
    st->speed = mem->speed;
    sasnav_navigate_opts o;
    sasnav_navigate_default_opts(&o);
    o.method = SASNAV_METHOD_DPCA;
    sasnav_navigation nav;
    rc = sasnav_navigate(st, &o, &nav);
    CHECK(rc == SASNAV_ERR_IO && strstr(sasnav_last_error(), "disk error reading ping 2"),
          "navigate over a failing source: %d %s", rc, sasnav_last_error());
    sasnav_grid g;
    CHECK_OK(sasnav_grid_make(-0.5, 0.5, 11, 9.5, 10.5, 11, &g));
    sasnav_cfloat img[121];
    rc = sasnav_backproject(st, st->nav, &g, NULL, img);
    CHECK(rc == SASNAV_ERR_IO && strstr(sasnav_last_error(), "ping 2"), "backproject over a failing source: %d %s", rc,
          sasnav_last_error());
    sasnav_run_free(st);
}

/* A scene far longer than a ping's reach is simulated band by band along
 * track (src/sim/simulate.c): against one operator over the whole scene,
 * the pings agree to float rounding (the bands sum the same scatterers in
 * another order), and the streamed simulation writes the same bits as the
 * in-memory one. */
static void test_long_scene(void)
{
    sasnav_scenario sc;
    sasnav_scenario_preset("paper-trajectory", &sc);
    sc.traj.n_pings = 4;
    sc.traj.x_start = 60.0; /* the middle of the scene */
    sc.snr_db = INFINITY;
    int n = 6000;
    double *x = malloc(sizeof(double) * n), *y = malloc(sizeof(double) * n);
    sasnav_cfloat *amp = malloc(sizeof *amp * n);
    sasnav_rng rng;
    sasnav_rng_seed(&rng, 42);
    for (int i = 0; i < n; i++) {
        x[i] = -40.0 + 200.0 * sasnav_rng_uniform(&rng); /* 200 m: over 4 x twice the reach */
        y[i] = 9.2 + 1.6 * sasnav_rng_uniform(&rng);
        amp[i] = (float)sasnav_rng_normal(&rng) + I * (float)sasnav_rng_normal(&rng);
    }
    sasnav_scene *scene = NULL;
    CHECK_OK(sasnav_scene_points(n, x, y, amp, &scene));
    sasnav_op_opts oo;
    sasnav_op_default_opts(&oo);
    oo.nthreads = 1;
    sasnav_run *run = NULL;
    CHECK_OK(sasnav_simulate(&sc, scene, &oo, &run));
    sasnav_op *op = NULL;
    if (run) CHECK_OK(sasnav_op_create(&run->sys, &run->array, &run->win, n, x, y, &oo, &op));
    size_t per = run ? sasnav_run_ping_size(run) : 0;
    sasnav_cfloat *ref = malloc(sizeof *ref * (per ? per : 1));
    double worst = 0, energy = 0;
    for (int p = 0; op && p < run->n_pings; p++) {
        CHECK_OK(sasnav_op_set_geometry(op, &run->truth[p]));
        CHECK_OK(sasnav_op_forward(op, amp, ref));
        const sasnav_cfloat *got = sasnav_run_ping(run, p);
        double e = 0, d = 0;
        for (size_t i = 0; i < per; i++) {
            e += crealf(ref[i]) * crealf(ref[i]) + cimagf(ref[i]) * cimagf(ref[i]);
            double dr = crealf(ref[i]) - crealf(got[i]), di = cimagf(ref[i]) - cimagf(got[i]);
            d += dr * dr + di * di;
        }
        energy += e;
        if (e > 0 && sqrt(d / e) > worst) worst = sqrt(d / e);
    }
    /* float sums of ~1e3 terms in another order: ~1e-6 relative. */
    CHECK(energy > 0 && worst < 1e-5, "band-by-band simulation vs whole scene: relative error %g", worst);
    sasnav_op_destroy(op);
    free(ref);
    sasnav_run_free(run);
    sasnav_scene_free(scene);
    free(x);
    free(y);
    free(amp);
}

/* Streamed simulation into a file = the in-memory simulation written. */
static int sink_put(void *ctx, int p, const sasnav_cfloat *s) { return sasnav_run_writer_put(ctx, p, s); }
static int sink_get(void *ctx, int p, sasnav_cfloat *s) { return sasnav_run_writer_get(ctx, p, s); }

static int mem_sink_put(void *ctx, int p, const sasnav_cfloat *s)
{
    memcpy(sasnav_run_ping(ctx, p), s, sizeof *s * sasnav_run_ping_size(ctx));
    return SASNAV_OK;
}
static int mem_sink_get(void *ctx, int p, sasnav_cfloat *s)
{
    memcpy(s, sasnav_run_ping(ctx, p), sizeof *s * sasnav_run_ping_size(ctx));
    return SASNAV_OK;
}

static void test_stream_simulation(void)
{
    sasnav_scenario sc;
    sasnav_scenario_preset("paper-trajectory", &sc);
    sasnav_scenario_seed(&sc, 11);
    sc.traj.n_pings = 5;
    sc.snr_db = 20;
    sc.aiding.enabled = 1;
    sasnav_run *mem = NULL;
    CHECK_OK(sasnav_simulate(&sc, NULL, NULL, &mem));
    if (!mem) return;
    char a[1024], b[1024];
    snprintf(a, sizeof a, "%s/sim-mem.h5", test_tmpdir());
    snprintf(b, sizeof b, "%s/sim-stream.h5", test_tmpdir());
    CHECK_OK(sasnav_run_write(a, mem));
    sasnav_run_writer *w = NULL;
    CHECK_OK(sasnav_run_writer_open(b, mem, &w));
    sasnav_ping_sink sink = {sink_put, sink_get, w};
    sasnav_run *header = NULL;
    CHECK_OK(sasnav_simulate_stream(&sc, NULL, NULL, &sink, &header, NULL, NULL));
    if (header) CHECK_OK(sasnav_run_writer_finish(w, header));
    else sasnav_run_writer_abort(w);
    sasnav_run *back = NULL;
    CHECK_OK(sasnav_run_read(b, &back));
    if (back) {
        CHECK(!memcmp(back->raw, mem->raw, sizeof *back->raw * sasnav_run_ping_size(mem) * (size_t)mem->n_pings),
              "streamed simulation samples differ from the in-memory ones");
        CHECK(!memcmp(back->truth, mem->truth, sizeof *back->truth * (size_t)mem->n_pings), "truth");
        CHECK(back->aiding && !memcmp(back->aiding->velocity, mem->aiding->velocity,
                                      sizeof(double) * 2 * (size_t)mem->n_pings),
              "aiding");
    }
    /* The pieces a distributed simulation uses (pings made in any order,
     * power summed in ping order, noise added by one caller) give the same
     * samples. */
    sasnav_run *head = NULL, *pieces = NULL;
    sasnav_scene *scene = NULL;
    sasnav_simulator *sim = NULL;
    CHECK_OK(sasnav_scenario_header(&sc, &head));
    CHECK_OK(sasnav_scenario_scene(&sc, &scene));
    CHECK_OK(sasnav_run_alloc(&mem->sys, &mem->array, &mem->win, mem->n_pings, 1, &pieces));
    if (head && scene && pieces) CHECK_OK(sasnav_simulator_create(head, scene, NULL, &sim));
    if (sim) {
        size_t per = sasnav_run_ping_size(pieces);
        for (int k = 0; k < pieces->n_pings; k++) {
            int p = (3 * k + 2) % pieces->n_pings; /* 2, 0, 3, 1, 4 */
            CHECK_OK(sasnav_simulator_ping(sim, p, sasnav_run_ping(pieces, p)));
        }
        double power = 0;
        for (int p = 0; p < pieces->n_pings; p++) power = sasnav_ping_power(sasnav_run_ping(pieces, p), per, power);
        sasnav_ping_sink ms = {mem_sink_put, mem_sink_get, pieces};
        CHECK_OK(sasnav_simulate_noise(&sc, head, power / ((double)per * pieces->n_pings), &ms));
        CHECK(!memcmp(pieces->raw, mem->raw, sizeof *mem->raw * per * (size_t)mem->n_pings),
              "simulation by pieces differs from sasnav_simulate");
        CHECK(!memcmp(head->truth, mem->truth, sizeof *mem->truth * (size_t)mem->n_pings), "header truth");
    }
    sasnav_simulator_destroy(sim);
    sasnav_scene_free(scene);
    sasnav_run_free(pieces);
    sasnav_run_free(head);

    /* A writer that is abandoned leaves no file behind. */
    snprintf(b, sizeof b, "%s/abandoned.h5", test_tmpdir());
    w = NULL;
    CHECK_OK(sasnav_run_writer_open(b, mem, &w));
    sasnav_run_writer_abort(w);
    FILE *f = fopen(b, "rb");
    CHECK(!f, "an abandoned run file exists");
    if (f) fclose(f);
    sasnav_run_free(back);
    sasnav_run_free(header);
    sasnav_run_free(mem);
}

int main(void)
{
    test_long_scene();
    test_stream_simulation();
    sasnav_run *mem = simulate(6, 7);
    if (!mem) return test_summary("test_stream");
    char path[1024];
    snprintf(path, sizeof path, "%s/run.h5", test_tmpdir());
    CHECK_OK(sasnav_run_write(path, mem));
    test_open_matches_read(path, mem);
    test_backprojection(path, mem);
    test_parts(path, SASNAV_METHOD_DPCA);
#ifndef SASNAV_TEST_SANITIZED
    test_parts(path, SASNAV_METHOD_SUBSPACE);
#endif
    test_corrupt_ping(path, mem);
    sasnav_run *absent = NULL;
    snprintf(path, sizeof path, "%s/absent.h5", test_tmpdir());
    CHECK(sasnav_run_open(path, &absent) != SASNAV_OK && !absent, "a missing file is refused");
    sasnav_run_free(mem);
    return test_summary("test_stream");
}
