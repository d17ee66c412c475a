/* Trajectories from displacements (trajectory.h): composition round trips,
 * least-squares combination of redundant links, alignment to the track,
 * cumulative/differential errors. */
#include "sasnav/error.h"
#include "sasnav/scene.h"
#include "sasnav/sim.h"
#include "sasnav/trajectory.h"
#include "testutil.h"

#include <math.h>
#include <string.h>

#define N_PINGS 16
/* Composition is double precision: a chain of 16 metre-scale poses keeps
 * ~1e-15 m per step; 1e-12 leaves room for the rounding of 16 steps. */
#define TOL 1e-12

static int pose_close(sasnav_pose a, sasnav_pose b, double tol)
{
    return fabs(a.x - b.x) <= tol && fabs(a.y - b.y) <= tol &&
           fabs(sasnav_wrap_angle(a.theta - b.theta)) <= tol;
}

/* A wiggly track along +x: 20 cm steps with surge, sway and yaw errors of
 * a few mm / mrad (seeded). */
static void random_track(sasnav_rng *rng, int n, sasnav_pose *c)
{
    for (int i = 0; i < n; i++) {
        c[i].x = -1.5 + 0.2 * i + 0.005 * sasnav_rng_normal(rng);
        c[i].y = 0.003 * sasnav_rng_normal(rng);
        c[i].theta = 0.01 * sasnav_rng_normal(rng);
    }
}

static void test_round_trip(void)
{
    sasnav_rng rng;
    sasnav_rng_seed(&rng, 3);
    sasnav_pose truth[N_PINGS], disp[N_PINGS - 1], back[N_PINGS];
    random_track(&rng, N_PINGS, truth);
    CHECK_OK(sasnav_traj_displacements(truth, N_PINGS, disp));
    CHECK_OK(sasnav_traj_compose(truth[0], disp, N_PINGS, back));
    int ok = 1;
    for (int i = 0; i < N_PINGS; i++) ok &= pose_close(back[i], truth[i], TOL);
    CHECK(ok, "compose(displacements(truth)) != truth");

    /* EPCA ping poses keep the centroids (and the lag). */
    sasnav_ping_pose pings[N_PINGS];
    CHECK_OK(sasnav_traj_ping_poses(truth, N_PINGS, 0.10, 0.0, pings));
    CHECK_OK(sasnav_traj_centroids(pings, N_PINGS, back));
    ok = 1;
    for (int i = 0; i < N_PINGS; i++) {
        ok &= pose_close(back[i], truth[i], TOL);
        sasnav_pose a = sasnav_pose_between(pings[i].tx, pings[i].array);
        ok &= fabs(a.x - 0.10) < TOL && fabs(a.y) < TOL;
    }
    CHECK(ok, "EPCA ping poses lose the centroid or the 10 cm lag");

    /* The simulator's true trajectory (EPCA geometry at the erroneous
     * centroids) is recovered from its own displacements. */
    sasnav_scenario sc;
    CHECK_OK(sasnav_scenario_preset("paper-trajectory", &sc));
    sc.traj.true_bistatic = 0;
    sasnav_ping_pose sim[N_PINGS];
    CHECK_OK(sasnav_trajectory_true(&sc.traj, sim));
    sasnav_pose sc_c[N_PINGS], sc_back[N_PINGS];
    CHECK_OK(sasnav_traj_centroids(sim, N_PINGS, sc_c));
    CHECK_OK(sasnav_traj_displacements(sc_c, N_PINGS, disp));
    CHECK_OK(sasnav_traj_compose(sc_c[0], disp, N_PINGS, sc_back));
    sasnav_ping_pose sim_back[N_PINGS];
    CHECK_OK(sasnav_traj_ping_poses(sc_back, N_PINGS, sc.traj.tx_lag, 0.0, sim_back));
    ok = 1;
    for (int i = 0; i < N_PINGS; i++)
        ok &= pose_close(sim_back[i].tx, sim[i].tx, TOL) && pose_close(sim_back[i].array, sim[i].array, TOL);
    CHECK(ok, "simulated ping poses not recovered from their displacements");
}

/* Links (p, p+1) and, when `skip`, (p, p+2), from the true centroids plus
 * seeded Gaussian noise of std `sigma` per component. */
static int make_links(sasnav_rng *rng, const sasnav_pose *truth, int n, int skip, sasnav_pose sigma,
                      double noise, sasnav_traj_link *links)
{
    int k = 0;
    for (int b = 1; b <= (skip ? 2 : 1); b++)
        for (int p = 0; p + b < n; p++) {
            sasnav_pose d = sasnav_pose_between(truth[p], truth[p + b]);
            d.x += noise * sigma.x * sasnav_rng_normal(rng);
            d.y += noise * sigma.y * sasnav_rng_normal(rng);
            d.theta += noise * sigma.theta * sasnav_rng_normal(rng);
            links[k++] = (sasnav_traj_link){p, p + b, d, sigma};
        }
    return k;
}

static void test_least_squares(void)
{
    sasnav_rng rng;
    sasnav_rng_seed(&rng, 11);
    sasnav_pose truth[N_PINGS], est[N_PINGS], chain[N_PINGS], disp[N_PINGS - 1];
    sasnav_traj_link links[2 * N_PINGS];
    /* Link noise like a pair estimator's: surge weak (1 mm), sway strong
     * (20 um), yaw 1e-4 rad. */
    sasnav_pose sigma = {1e-3, 2e-5, 1e-4};
    int iters = 0;

    /* Consistent (noise-free) redundant links: the truth, exactly. */
    random_track(&rng, N_PINGS, truth);
    int nl = make_links(&rng, truth, N_PINGS, 1, sigma, 0.0, links);
    CHECK_OK(sasnav_traj_solve(N_PINGS, truth[0], links, nl, NULL, est, &iters));
    int ok = 1;
    for (int i = 0; i < N_PINGS; i++) ok &= pose_close(est[i], truth[i], 1e-11);
    CHECK(ok, "noise-free redundant links do not give the truth");

    /* Chain only: the solve is the composition (one Gauss-Newton step of
     * zero length). */
    nl = make_links(&rng, truth, N_PINGS, 0, sigma, 1.0, links);
    for (int i = 0; i < nl; i++) disp[i] = links[i].displacement;
    CHECK_OK(sasnav_traj_compose(truth[0], disp, N_PINGS, chain));
    CHECK_OK(sasnav_traj_solve(N_PINGS, truth[0], links, nl, NULL, est, &iters));
    ok = 1;
    for (int i = 0; i < N_PINGS; i++) ok &= pose_close(est[i], chain[i], TOL);
    CHECK(ok && iters == 1, "chain-only solve differs from the composition (%d iterations)", iters);

    /* Redundant noisy links: over 200 seeded trials the mean squared error of
     * the poses (all pings) must drop against the chain alone. For yaw (a
     * linear problem) the variance of ping i is the effective resistance
     * from ping 0 to ping i of a network of unit resistors on the links:
     * i for the chain; with the (p, p+2) links about 0.2 i (per unit length
     * the chain conducts 1 and the two interleaved skip chains 2 each), so
     * the expected ratio is about 0.2, and sway/surge follow through the
     * lever arm. Measured 0.17-0.22; the threshold 0.5 only asks for a clear
     * gain and leaves room for the 200-trial sampling error. */
    double se_chain[3] = {0}, se_ls[3] = {0};
    int trials = 200, fails = 0;
    for (int t = 0; t < trials; t++) {
        random_track(&rng, N_PINGS, truth);
        nl = make_links(&rng, truth, N_PINGS, 1, sigma, 1.0, links);
        for (int i = 0; i < N_PINGS - 1; i++) disp[i] = links[i].displacement;
        sasnav_traj_compose(truth[0], disp, N_PINGS, chain);
        if (sasnav_traj_solve(N_PINGS, truth[0], links, nl, NULL, est, &iters)) fails++;
        sasnav_pose ec[N_PINGS], el[N_PINGS];
        sasnav_traj_errors(chain, truth, N_PINGS, 0.0, ec, NULL);
        sasnav_traj_errors(est, truth, N_PINGS, 0.0, el, NULL);
        for (int i = 1; i < N_PINGS; i++) {
            se_chain[0] += ec[i].x * ec[i].x;
            se_chain[1] += ec[i].y * ec[i].y;
            se_chain[2] += ec[i].theta * ec[i].theta;
            se_ls[0] += el[i].x * el[i].x;
            se_ls[1] += el[i].y * el[i].y;
            se_ls[2] += el[i].theta * el[i].theta;
        }
    }
    CHECK(fails == 0, "%d least-squares solves failed", fails);
    const char *name[3] = {"surge", "sway", "yaw"};
    for (int a = 0; a < 3; a++) {
        double ratio = se_ls[a] / se_chain[a];
        printf("  LS vs chain, %s: rms %.3g -> %.3g (variance ratio %.3f)\n", name[a],
               sqrt(se_chain[a] / (trials * (N_PINGS - 1))), sqrt(se_ls[a] / (trials * (N_PINGS - 1))),
               ratio);
        CHECK(ratio < 0.5, "%s: redundant links do not reduce the error (ratio %.3f)", name[a], ratio);
    }

    /* Bad input. */
    sasnav_traj_link bad = links[0];
    bad.sigma.y = 0;
    CHECK(sasnav_traj_solve(N_PINGS, truth[0], &bad, 1, NULL, est, NULL) == SASNAV_ERR_ARG,
          "zero sigma accepted");
    CHECK(sasnav_traj_solve(N_PINGS, truth[0], links, 1, NULL, est, NULL) == SASNAV_ERR_ARG,
          "unreached pings accepted");
    bad = links[0];
    bad.q = N_PINGS;
    CHECK(sasnav_traj_solve(N_PINGS, truth[0], &bad, 1, NULL, est, NULL) == SASNAV_ERR_ARG,
          "link outside the run accepted");
    CHECK(sasnav_traj_compose(truth[0], NULL, 0, est) == SASNAV_ERR_ARG, "n = 0 accepted");
}

/* Rigid rotation of a trajectory by `angle` about its first centroid. */
static void rotate(sasnav_pose *c, int n, double angle)
{
    sasnav_pose pivot = {c[0].x, c[0].y, 0};
    for (int i = 0; i < n; i++) {
        double dx = c[i].x - pivot.x, dy = c[i].y - pivot.y;
        c[i].x = pivot.x + cos(angle) * dx - sin(angle) * dy;
        c[i].y = pivot.y + sin(angle) * dx + cos(angle) * dy;
        c[i].theta += angle;
    }
}

static void test_alignment(void)
{
    /* The paper's tank run was tilted by 1.27e-2 rad (Sec. V-D). */
    const double angle = 1.27e-2;
    sasnav_pose straight[N_PINGS], wiggly[N_PINGS], copy[N_PINGS];
    for (int i = 0; i < N_PINGS; i++) straight[i] = (sasnav_pose){0.025 * i, 0.0, 0.0};
    rotate(straight, N_PINGS, angle);
    double a = 0;
    CHECK_OK(sasnav_traj_align(straight, N_PINGS, &a));
    CHECK(fabs(a - angle) < 1e-13, "straight track: angle %.15g, expected %.15g", a, angle);
    int ok = 1;
    for (int i = 0; i < N_PINGS; i++)
        ok &= pose_close(straight[i], (sasnav_pose){0.025 * i, 0.0, 0.0}, 1e-13);
    CHECK(ok, "aligned straight track is not back on +x with zero yaw");

    /* A wiggly track: the principal axis rotates with the track, so the
     * fitted angle changes by exactly the applied rotation, and after
     * alignment the fitted angle is zero. */
    sasnav_rng rng;
    sasnav_rng_seed(&rng, 5);
    random_track(&rng, N_PINGS, wiggly);
    double a0 = 0, a1 = 0, a2 = 1;
    CHECK_OK(sasnav_traj_track_angle(wiggly, N_PINGS, &a0));
    memcpy(copy, wiggly, sizeof copy);
    rotate(copy, N_PINGS, angle);
    CHECK_OK(sasnav_traj_align(copy, N_PINGS, &a1));
    CHECK(fabs(a1 - a0 - angle) < 1e-12, "rotation not recovered: %.15g vs %.15g", a1 - a0, angle);
    CHECK_OK(sasnav_traj_track_angle(copy, N_PINGS, &a2));
    CHECK(fabs(a2) < 1e-12, "aligned track still at %.3g rad", a2);
    /* Yaw follows the rigid rotation: theta_aligned = theta + angle - a1. */
    ok = 1;
    for (int i = 0; i < N_PINGS; i++)
        ok &= fabs(sasnav_wrap_angle(copy[i].theta - (wiggly[i].theta + angle - a1))) < 1e-12;
    CHECK(ok, "aligned yaws are not the rotated yaws");
    /* A track running towards -x is oriented first -> last. */
    sasnav_pose back[3] = {{0, 0, 0}, {-1, 0.01, 0}, {-2, 0.02, 0}};
    CHECK_OK(sasnav_traj_track_angle(back, 3, &a));
    CHECK(fabs(a - atan2(0.01, -1)) < 1e-12, "backwards track angle %g", a);
}

static void test_errors(void)
{
    sasnav_pose truth[4] = {{0, 0, 0}, {0.2, 0, 0}, {0.4, 0, 0}, {0.6, 0, 0}};
    sasnav_pose est[4];
    memcpy(est, truth, sizeof est);
    est[2].y += 1e-3; /* 1 mm sway error at ping 2 only */
    sasnav_pose cum[4], dif[4];
    CHECK_OK(sasnav_traj_errors(est, truth, 4, 0.0, cum, dif));
    CHECK(fabs(cum[2].y - 1e-3) < 1e-15 && fabs(cum[1].y) < 1e-15 && fabs(cum[3].y) < 1e-15,
          "cumulative sway");
    CHECK(fabs(dif[2].y - 1e-3) < 1e-15 && fabs(dif[3].y + 1e-3) < 1e-15 && dif[0].y == 0,
          "differential sway %g %g", dif[2].y, dif[3].y);
    /* In a rotated track frame the same error reads the same. */
    const double angle = 0.3;
    rotate(truth, 4, angle);
    rotate(est, 4, angle);
    CHECK_OK(sasnav_traj_errors(est, truth, 4, angle, cum, dif));
    CHECK(fabs(cum[2].y - 1e-3) < 1e-14 && fabs(cum[2].x) < 1e-14, "rotated cumulative (%g, %g)",
          cum[2].x, cum[2].y);
    CHECK(fabs(dif[2].y - 1e-3) < 1e-14, "rotated differential %g", dif[2].y);
}

/* The rigid fit recovers a known motion exactly (points not collinear) and
 * the least-squares one with noise against a direct search over the angle. */
static void test_rigid_fit(void)
{
    enum { N = 9 };
    sasnav_pose a[N], b[N];
    sasnav_pose m = {0.3, -1.2, 0.4};
    for (int i = 0; i < N; i++) {
        a[i] = (sasnav_pose){0.1 * i, 0.02 * i * i, 0.0};
        b[i] = sasnav_pose_compose(m, a[i]);
    }
    sasnav_pose f = sasnav_traj_rigid_fit(a, b, N);
    CHECK(fabs(f.x - m.x) < 1e-12 && fabs(f.y - m.y) < 1e-12 && fabs(f.theta - m.theta) < 1e-12,
          "rigid fit (%g, %g, %g)", f.x, f.y, f.theta);
    for (int i = 0; i < N; i++) {
        b[i].x += 1e-3 * sin(3.1 * i);
        b[i].y += 1e-3 * cos(1.7 * i);
    }
    f = sasnav_traj_rigid_fit(a, b, N);
    /* direct: for each angle the best translation is the centroid difference */
    double best = HUGE_VAL, best_phi = 0;
    for (int k = -2000; k <= 2000; k++) {
        double phi = m.theta + 1e-6 * k, c = cos(phi), s = sin(phi), tx = 0, ty = 0, e = 0;
        for (int i = 0; i < N; i++) {
            tx += (b[i].x - (c * a[i].x - s * a[i].y)) / N;
            ty += (b[i].y - (s * a[i].x + c * a[i].y)) / N;
        }
        for (int i = 0; i < N; i++) {
            double ex = c * a[i].x - s * a[i].y + tx - b[i].x, ey = s * a[i].x + c * a[i].y + ty - b[i].y;
            e += ex * ex + ey * ey;
        }
        if (e < best) {
            best = e;
            best_phi = phi;
        }
    }
    CHECK(fabs(f.theta - best_phi) < 2e-6, "noisy rigid fit angle %.8f vs direct %.8f", f.theta, best_phi);
    sasnav_pose z = sasnav_traj_rigid_fit(a, b, 0);
    CHECK(z.x == 0 && z.y == 0 && z.theta == 0, "empty fit is not the identity");
}

int main(void)
{
    test_rigid_fit();
    test_round_trip();
    test_least_squares();
    test_alignment();
    test_errors();
    return test_summary("test_trajectory");
}
