/* Fast factorised backprojection (sasnav_ffbp_tile, docs/survey.md)
 * against direct backprojection (sasnav_backproject_tile, the slow exact
 * reference) on point targets: the image error in dB, each target's peak
 * pixel and its -3 dB widths along track and in range; the fallback to the
 * direct operator where polar grids do not suit; the same bits for any
 * thread count; and sasnav_op_set_points against fresh operators. */
#include "sasnav/error.h"
#include "sasnav/image.h"
#include "sasnav/op.h"
#include "sasnav/run.h"
#include "sasnav/scene.h"
#include "sasnav/sim.h"
#include "testutil.h"

#include <complex.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define NT 3
static const double TX[NT] = {-0.61, 0.013, 0.47}, TY[NT] = {9.62, 10.007, 10.31};

/* The paper's system over 3 point targets, a straight 41-ping track (8 m)
 * whose every ping sees them: 41 x 16 = 656 (ping, channel) pairs per
 * pixel, enough for a tree of 6 levels. */
static sasnav_run *point_run(void)
{
    sasnav_scenario sc;
    if (sasnav_scenario_preset("point", &sc)) return NULL;
    sc.traj.n_pings = 41;
    sc.traj.x_start = -4.0;
    sc.n_targets = NT;
    for (int i = 0; i < NT; i++) {
        sc.target_x[i] = TX[i];
        sc.target_y[i] = TY[i];
        sc.target_amp[i] = 1.0;
    }
    sc.range_min = 9.0;
    sc.range_max = 11.0;
    sasnav_run *run = NULL;
    int rc = sasnav_simulate(&sc, NULL, NULL, &run);
    CHECK(rc == 0, "simulation failed: %s", sasnav_last_error());
    return rc ? NULL : run;
}

/* -3 dB width (m) of |img| through pixel (iy, ix) along x (dir 0) or y (1),
 * by linear interpolation of the crossings of peak / sqrt(2). */
static double width_3db(const sasnav_grid *g, const sasnav_cfloat *img, int iy, int ix, int dir)
{
    double peak = cabsf(img[(size_t)iy * g->nx + ix]), half = peak / sqrt(2.0), w = 0;
    for (int side = -1; side <= 1; side += 2) {
        int k = 0;
        double prev = peak, cur = peak;
        for (k = 1; k < 200; k++) {
            int jx = dir == 0 ? ix + side * k : ix, jy = dir == 1 ? iy + side * k : iy;
            if (jx < 0 || jx >= g->nx || jy < 0 || jy >= g->ny) return NAN;
            cur = cabsf(img[(size_t)jy * g->nx + jx]);
            if (cur < half) break;
            prev = cur;
        }
        double frac = (prev - half) / (prev - cur);
        w += (k - 1 + frac) * (dir == 0 ? g->dx : g->dy);
    }
    return w;
}

static double rel_error_db(const sasnav_cfloat *ref, const sasnav_cfloat *x, size_t n)
{
    double e = 0, r = 0;
    for (size_t i = 0; i < n; i++) {
        sasnav_cfloat d = x[i] - ref[i];
        e += crealf(d) * crealf(d) + cimagf(d) * cimagf(d);
        r += crealf(ref[i]) * crealf(ref[i]) + cimagf(ref[i]) * cimagf(ref[i]);
    }
    return 10 * log10(e / r);
}

/* Direct backprojection (the reference) and FFBP of `run` with `nav` on
 * the whole grid, one thread each: *d and *f (free both). */
static void direct_and_ffbp(const sasnav_run *run, const sasnav_ping_pose *nav, const sasnav_grid *g,
                            sasnav_cfloat **d, sasnav_cfloat **f)
{
    size_t n = (size_t)g->nx * g->ny;
    *d = malloc(sizeof **d * n);
    *f = malloc(sizeof **f * n);
    sasnav_op_opts oo;
    sasnav_op_default_opts(&oo);
    oo.nthreads = 1;
    CHECK_OK(sasnav_backproject_tile(run, nav, g, 0, g->nx, 0, g->ny, &oo, *d, NULL, NULL));
    CHECK_OK(sasnav_ffbp_tile(run, nav, g, 0, g->nx, 0, g->ny, &oo, NULL, *f, NULL, NULL));
}

static void test_points(const sasnav_run *run)
{
    sasnav_grid g;
    /* 1.5 m x 1.0 m at 5 mm (below the 2.5 cm resolutions: widths resolved);
     * under sanitizers (20x slower) at 1 cm. */
#ifdef SASNAV_TEST_SANITIZED
    CHECK_OK(sasnav_grid_make(-0.75, 0.75, 151, 9.5, 10.5, 101, &g));
#else
    CHECK_OK(sasnav_grid_make(-0.75, 0.75, 301, 9.5, 10.5, 201, &g));
#endif
    size_t n = (size_t)g.nx * g.ny;
    sasnav_cfloat *d, *f, *f2 = malloc(sizeof *f2 * n);
    direct_and_ffbp(run, run->truth, &g, &d, &f);
    /* The interpolations' error: -52 dB each (6-tap Kaiser-sinc at 2x
     * oversampling), summed over the tree's levels; measured about -50 dB
     * here. -35 dB leaves room for float rounding and other scenes, and
     * still fails for any geometric or phase error (a 1 mm shift of one
     * level is about -20 dB at 300 kHz). */
    double err = rel_error_db(d, f, n);
    CHECK(err < -35.0, "FFBP error against direct backprojection %.1f dB (want < -35)", err);
    for (int t = 0; t < NT; t++) {
        /* The peak pixel of each target, within 5 cm of it. */
        int cx = (int)lround((TX[t] - g.x0) / g.dx), cy = (int)lround((TY[t] - g.y0) / g.dy);
        int bd[2] = {cx, cy}, bf[2] = {cx, cy};
        double md = 0, mf = 0;
        for (int iy = cy - 10; iy <= cy + 10; iy++)
            for (int ix = cx - 10; ix <= cx + 10; ix++) {
                double a = cabsf(d[(size_t)iy * g.nx + ix]), b = cabsf(f[(size_t)iy * g.nx + ix]);
                if (a > md) md = a, bd[0] = ix, bd[1] = iy;
                if (b > mf) mf = b, bf[0] = ix, bf[1] = iy;
            }
        CHECK(bd[0] == bf[0] && bd[1] == bf[1], "target %d: peak at (%d, %d) direct, (%d, %d) FFBP", t,
              bd[0], bd[1], bf[0], bf[1]);
        CHECK(fabs(mf / md - 1) < 0.05, "target %d: peak %.4g direct, %.4g FFBP", t, md, mf);
        for (int dir = 0; dir < 2; dir++) {
            double wd = width_3db(&g, d, bd[1], bd[0], dir), wf = width_3db(&g, f, bf[1], bf[0], dir);
            /* The acceptance: -3 dB widths within 5 %. */
            CHECK(isfinite(wd) && isfinite(wf) && fabs(wf / wd - 1) < 0.05,
                  "target %d: -3 dB width %s %.4g m direct, %.4g m FFBP", t, dir ? "in range" : "along track",
                  wd, wf);
        }
    }
#ifndef SASNAV_TEST_SANITIZED
    /* The same bits with two threads (fixed-order sums). */
    sasnav_op_opts oo;
    sasnav_op_default_opts(&oo);
    oo.nthreads = 2;
    CHECK_OK(sasnav_ffbp_tile(run, run->truth, &g, 0, g.nx, 0, g.ny, &oo, NULL, f2, NULL, NULL));
    CHECK(!memcmp(f, f2, sizeof *f * n), "FFBP differs between 1 and 2 threads");
#endif
    /* A sub-rectangle is the same computation on its own tile. */
    free(d);
    free(f);
    free(f2);
}

/* Speckle seen by a long subaperture at short range (paper-trajectory
 * system, 48 pings over 9.4 m at 10 m): the residual delay drifts with range
 * there, which the range sampling must follow (without that term this
 * case measured -28 dB; with it -44 dB). */
static void test_speckle(void)
{
    sasnav_scenario sc;
    CHECK_OK(sasnav_scenario_preset("paper-trajectory", &sc));
    sc.traj.n_pings = 48;
    sc.traj.x_start = -4.7;
    sc.ripples.x_min = -6;
    sc.ripples.x_max = 6;
    sasnav_run *run = NULL;
    CHECK_OK(sasnav_simulate(&sc, NULL, NULL, &run));
    if (!run) return;
    sasnav_grid g;
#ifdef SASNAV_TEST_SANITIZED
    CHECK_OK(sasnav_grid_make(-0.8, 0.8, 161, 9.4, 10.6, 121, &g));
#else
    /* A 1024 x 513 FFBP tile: subapertures of several metres. */
    CHECK_OK(sasnav_grid_make(-1.6, 1.6, 1025, 9.2, 10.8, 513, &g));
#endif
    size_t n = (size_t)g.nx * g.ny;
    sasnav_cfloat *d, *f;
    direct_and_ffbp(run, run->nav, &g, &d, &f);
    double err = rel_error_db(d, f, n);
    CHECK(err < -35.0, "FFBP error on speckle %.1f dB (want < -35)", err);
    if (getenv("SASNAV_TEST_VERBOSE")) fprintf(stderr, "speckle: %.1f dB\n", err);
    free(d);
    free(f);
    sasnav_run_free(run);
}

/* A grid across the track's line: no polar frame suits, every ping goes
 * through the direct operator on the tile: the same bits as direct. */
static void test_fallback(const sasnav_run *run)
{
    sasnav_grid g;
    CHECK_OK(sasnav_grid_make(-0.3013, 0.3013, 41, -0.4007, 0.4007, 33, &g));
    size_t n = (size_t)g.nx * g.ny;
    sasnav_cfloat *d, *f;
    sasnav_run r = *run;
    r.array.rx_height = r.array.tx_height = 1.0; /* no pixel on a sensor */
    direct_and_ffbp(&r, r.truth, &g, &d, &f);
    sasnav_op_opts oo;
    sasnav_op_default_opts(&oo);
    CHECK(!memcmp(d, f, sizeof *d * n), "the fallback is the direct operator");
    sasnav_ffbp_opts fo;
    sasnav_ffbp_default_opts(&fo);
    fo.oversampling = 1.0;
    CHECK(sasnav_ffbp_tile(&r, r.truth, &g, 0, g.nx, 0, g.ny, &oo, &fo, f, NULL, NULL) == SASNAV_ERR_ARG,
          "oversampling below 1.25 is refused");
    fo.oversampling = NAN;
    CHECK(sasnav_ffbp_tile(&r, r.truth, &g, 0, g.nx, 0, g.ny, &oo, &fo, f, NULL, NULL) == SASNAV_ERR_ARG,
          "NaN oversampling is refused");
    CHECK(sasnav_ffbp_tile(&r, r.truth, &g, 0, g.nx + 1, 0, g.ny, &oo, NULL, f, NULL, NULL) == SASNAV_ERR_ARG,
          "pixels outside the grid are refused");
    free(d);
    free(f);
}

/* sasnav_op_set_points: the same adjoint as a fresh operator on the new
 * points, shrinking and growing. */
static void test_set_points(const sasnav_run *run)
{
    int sizes[3] = {500, 120, 2000};
    double *x = malloc(sizeof(double) * 2000), *y = malloc(sizeof(double) * 2000);
    sasnav_cfloat *a = malloc(sizeof *a * 2000), *b = malloc(sizeof *b * 2000);
    sasnav_op *reused = NULL;
    for (int k = 0; k < 3; k++) {
        int n = sizes[k];
        for (int i = 0; i < n; i++) {
            x[i] = -0.5 + 1.0 * i / n + 0.01 * k;
            y[i] = 9.6 + 0.8 * ((i * 37) % n) / n;
        }
        sasnav_op *fresh = NULL;
        CHECK_OK(sasnav_op_create(&run->sys, &run->array, &run->win, n, x, y, NULL, &fresh));
        if (!reused)
            CHECK_OK(sasnav_op_create(&run->sys, &run->array, &run->win, n, x, y, NULL, &reused));
        else
            CHECK_OK(sasnav_op_set_points(reused, n, x, y));
        CHECK(sasnav_op_n_points(reused) == n, "point count after set_points");
        CHECK_OK(sasnav_op_set_geometry(fresh, &run->truth[3]));
        CHECK_OK(sasnav_op_set_geometry(reused, &run->truth[3]));
        CHECK_OK(sasnav_op_adjoint(fresh, sasnav_run_ping(run, 3), a));
        CHECK_OK(sasnav_op_adjoint(reused, sasnav_run_ping(run, 3), b));
        CHECK(!memcmp(a, b, sizeof *a * (size_t)n), "set_points (%d points) differs from a fresh operator", n);
        sasnav_op_destroy(fresh);
    }
    x[0] = NAN;
    CHECK(sasnav_op_set_points(reused, 10, x, y) == SASNAV_ERR_ARG, "non-finite points are refused");
    sasnav_op_destroy(reused);
    free(x);
    free(y);
    free(a);
    free(b);
}

/* The survey preset and its seabed: consistent timing, seeded scenes,
 * content within the extent, bad parameters refused, a two-ping run. */
static void test_survey(void)
{
    sasnav_scenario sc;
    CHECK_OK(sasnav_scenario_preset("survey", &sc));
    CHECK_OK(sasnav_scenario_check(&sc));
    /* The ping interval is the two-way time to the far range. */
    double pri = sc.traj.ping_spacing / sc.traj.speed;
    CHECK(fabs(pri - 2 * sc.range_max / sc.sys.sound_speed) < 1e-12, "ping interval %g s", pri);
    double array = sc.array.rx_u[sc.array.n_rx - 1] - sc.array.rx_u[0] + 0.05;
    CHECK(sc.traj.ping_spacing < array / 2, "ping spacing %g m under half the %g m array", sc.traj.ping_spacing,
          array);
    sasnav_ripple_params rp = sc.ripples;
    rp.x_min = 0;
    rp.x_max = 60;
    sasnav_scene *a = NULL, *b = NULL, *c = NULL;
    double tx[8], ty[8];
    int nt = 0;
    CHECK_OK(sasnav_scene_survey(&rp, 8, tx, ty, &nt, &a));
    CHECK_OK(sasnav_scene_survey(&rp, 0, NULL, NULL, NULL, &b));
    rp.seed += 1;
    CHECK_OK(sasnav_scene_survey(&rp, 0, NULL, NULL, NULL, &c));
    if (a && b && c) {
        CHECK(nt == 2, "targets every 25 m: %d in 60 m", nt);
        CHECK(a->n == b->n && !memcmp(a->x, b->x, sizeof(double) * (size_t)a->n) &&
                  !memcmp(a->amp, b->amp, sizeof *a->amp * (size_t)a->n),
              "the same seed gives the same scene");
        CHECK(a->n != c->n || memcmp(a->x, c->x, sizeof(double) * (size_t)a->n), "another seed, another scene");
        double area = 60 * (rp.y_max - rp.y_min);
        CHECK(a->n >= area * rp.density, "%d scatterers for %g m^2 at %g/m^2", a->n, area, rp.density);
        int outside = 0;
        for (int i = 0; i < a->n; i++)
            /* Rocks reach 0.8 m and cylinders 1.03 m beyond their centres. */
            outside += a->x[i] < rp.x_min - 1.1 || a->x[i] > rp.x_max + 1.1 || a->y[i] < rp.y_min - 1.1 ||
                       a->y[i] > rp.y_max + 1.1 || !isfinite(crealf(a->amp[i]));
        CHECK(outside == 0, "%d scatterers outside the seabed", outside);
        for (int t = 0; t < nt; t++)
            CHECK(tx[t] > rp.x_min && tx[t] < rp.x_max && ty[t] > rp.y_min && ty[t] < rp.y_max, "target %d", t);
    }
    sasnav_scene_free(a);
    sasnav_scene_free(b);
    sasnav_scene_free(c);
    rp.density = 0;
    CHECK(sasnav_scene_survey(&rp, 0, NULL, NULL, NULL, &a) == SASNAV_ERR_ARG, "zero density is refused");
    rp.density = 20;
    rp.ripple_depth = 2;
    CHECK(sasnav_scene_survey(&rp, 0, NULL, NULL, NULL, &a) == SASNAV_ERR_ARG, "ripple depth 2 is refused");
    /* A huge extent at a tiny density: the rock count once overflowed a
     * long into a negative total that passed the size check (a heap
     * overflow under ASan); refused, nothing allocated. */
    sasnav_ripple_params huge = sc.ripples;
    huge.x_min = 0;
    huge.x_max = 1e10;
    huge.y_min = 1;
    huge.y_max = 1e12;
    huge.density = 1e-30;
    a = NULL;
    CHECK(sasnav_scene_survey(&huge, 0, NULL, NULL, NULL, &a) == SASNAV_ERR_ARG && a == NULL,
          "a 1e10 x 1e12 m survey scene accepted");
    /* Two pings over a short stretch of seabed. */
    sc.traj.n_pings = 2;
    sc.ripples.x_max = 10;
    sasnav_run *run = NULL;
    CHECK_OK(sasnav_simulate(&sc, NULL, NULL, &run));
    if (run) {
        CHECK(run->array.n_rx == 32 && run->n_pings == 2, "survey run shape");
        CHECK_OK(sasnav_run_check(run));
    }
    sasnav_run_free(run);
}

int main(void)
{
    test_survey();
    sasnav_run *run = point_run();
    if (!run) return test_summary("test_ffbp");
    test_points(run);
    test_fallback(run);
    test_speckle();
    test_set_points(run);
    sasnav_run_free(run);
    return test_summary("test_ffbp");
}
