/* SE(2) poses, centroids, displacements and trajectories (SPEC 1). */
#include "sasnav/error.h"
#include "sasnav/geometry.h"
#include "sasnav/scene.h"
#include "sasnav/sim.h"
#include "testutil.h"

#include <math.h>

/* Poses are composed in double precision: round trips hold to ~1e-15 m for
 * metre-scale poses; 1e-12 leaves room for a few rounding steps. */
#define TOL 1e-12

static int pose_close(sasnav_pose a, sasnav_pose b, double tol)
{
    return fabs(a.x - b.x) <= tol && fabs(a.y - b.y) <= tol &&
           fabs(sasnav_wrap_angle(a.theta - b.theta)) <= tol;
}

int main(void)
{
    sasnav_rng rng;
    sasnav_rng_seed(&rng, 42);
    for (int t = 0; t < 1000; t++) {
        sasnav_pose a = {4 * sasnav_rng_normal(&rng), 4 * sasnav_rng_normal(&rng), 3 * sasnav_rng_normal(&rng)};
        sasnav_pose b = {4 * sasnav_rng_normal(&rng), 4 * sasnav_rng_normal(&rng), 3 * sasnav_rng_normal(&rng)};
        sasnav_pose c = {sasnav_rng_normal(&rng), sasnav_rng_normal(&rng), sasnav_rng_normal(&rng)};
        sasnav_pose id = {0, 0, 0};
        CHECK(pose_close(sasnav_pose_compose(a, sasnav_pose_inverse(a)), id, TOL), "a * a^-1 != id");
        CHECK(pose_close(sasnav_pose_compose(sasnav_pose_inverse(a), a), id, TOL), "a^-1 * a != id");
        CHECK(pose_close(sasnav_pose_compose(a, sasnav_pose_between(a, b)), b, TOL), "a * (a^-1 b) != b");
        /* associativity */
        CHECK(pose_close(sasnav_pose_compose(sasnav_pose_compose(a, b), c),
                         sasnav_pose_compose(a, sasnav_pose_compose(b, c)), 1e-11), "not associative");
        /* composition moves points consistently */
        double px = sasnav_rng_normal(&rng), py = sasnav_rng_normal(&rng), x1, y1, x2, y2, xm, ym;
        sasnav_pose_apply(b, px, py, &xm, &ym);
        sasnav_pose_apply(a, xm, ym, &x1, &y1);
        sasnav_pose_apply(sasnav_pose_compose(a, b), px, py, &x2, &y2);
        CHECK(fabs(x1 - x2) < 1e-11 && fabs(y1 - y2) < 1e-11, "apply(a*b) != apply(a) apply(b)");
    }
    /* Wrap */
    CHECK(fabs(sasnav_wrap_angle(3 * M_PI) - M_PI) < 1e-12, "wrap 3pi");
    CHECK(fabs(sasnav_wrap_angle(-M_PI / 2 - 2 * M_PI) + M_PI / 2) < 1e-12, "wrap -5pi/2");

    /* Centroid: SPEC 1 ((x_a + x_t)/2, (y_a + y_t)/2, theta_r). */
    sasnav_ping_pose ping = {{1.0, 2.0, 0.3}, {1.2, 2.4, 0.1}};
    sasnav_pose c = sasnav_ping_centroid(&ping);
    CHECK(fabs(c.x - 1.1) < TOL && fabs(c.y - 2.2) < TOL && fabs(c.theta - 0.1) < TOL,
          "centroid (%g %g %g)", c.x, c.y, c.theta);
    /* local then place round trip */
    sasnav_ping_pose local = sasnav_ping_local(&ping);
    sasnav_ping_pose back = sasnav_ping_place(c, &local);
    CHECK(pose_close(back.tx, ping.tx, TOL) && pose_close(back.array, ping.array, TOL), "local/place");
    CHECK(fabs(local.array.theta) < TOL && fabs(local.tx.theta - 0.2) < TOL, "local yaw");
    /* EPCA geometry has its centroid at the origin and the array ahead */
    sasnav_ping_pose e = sasnav_epca_local(0.10, 0.0);
    sasnav_pose ec = sasnav_ping_centroid(&e);
    CHECK(pose_close(ec, (sasnav_pose){0, 0, 0}, TOL), "EPCA centroid not at origin");
    CHECK(fabs(e.array.x - e.tx.x - 0.10) < TOL, "EPCA lag");
    CHECK(fabs(sasnav_motion_tx_lag(2.0, 37.5, 1500.0) - 0.10) < TOL, "motion lag 2 m/s at 37.5 m");

    /* Displacement is the pose of q's centroid in p's frame. */
    sasnav_pose cp = {3.0, -1.0, 0.4}, d = {0.2 - 0.0345, 0.0217, 0.041};
    sasnav_ping_pose pp = sasnav_ping_place(cp, &e);
    sasnav_ping_pose pq = sasnav_ping_place(sasnav_pose_compose(cp, d), &e);
    CHECK(pose_close(sasnav_ping_displacement(&pp, &pq), d, TOL), "displacement");

    /* Trajectories: the explicit pair error is recovered exactly, with
     * exact EPCA and with true bistatic geometry. */
    sasnav_scenario sc;
    CHECK_OK(sasnav_scenario_preset("paper-pair", &sc));
    sasnav_ping_pose truth[2], nom[2];
    CHECK_OK(sasnav_trajectory_true(&sc.traj, truth));
    CHECK_OK(sasnav_trajectory_nominal(&sc.traj, nom));
    sasnav_pose dn = sasnav_ping_displacement(&nom[0], &nom[1]);
    CHECK(pose_close(dn, (sasnav_pose){0.2, 0, 0}, TOL), "nominal displacement");
    sasnav_pose dt = sasnav_ping_displacement(&truth[0], &truth[1]);
    CHECK(pose_close(dt, (sasnav_pose){0.2 - 0.0345, 0.0217, 0.041}, TOL), "pair error (%g %g %g)",
          dt.x, dt.y, dt.theta);
    CHECK_OK(sasnav_scenario_preset("paper-trajectory", &sc));
    sasnav_ping_pose tr[16], tr2[16];
    CHECK_OK(sasnav_trajectory_true(&sc.traj, tr));
    CHECK_OK(sasnav_trajectory_true(&sc.traj, tr2));
    int same = 1;
    for (int p = 0; p < 16; p++) same &= pose_close(tr[p].tx, tr2[p].tx, 0) && pose_close(tr[p].array, tr2[p].array, 0);
    CHECK(same, "trajectory not reproducible with the same seed");
    /* true bistatic: Tx and array yaw differ, their distance ~ tx_lag */
    double lag = hypot(tr[5].array.x - tr[5].tx.x, tr[5].array.y - tr[5].tx.y);
    CHECK(fabs(lag - 0.10) < 5e-3, "Tx-array distance %g", lag);
    CHECK(fabs(tr[5].array.theta - tr[5].tx.theta) > 0, "Tx and array yaw should differ");
    /* Bad inputs */
    sasnav_array arr;
    CHECK(sasnav_array_uniform(&arr, 0, 0.05, 0.05, 0.05) == SASNAV_ERR_ARG, "zero elements accepted");
    CHECK(sasnav_array_uniform(&arr, 4, NAN, 0.05, 0.05) == SASNAV_ERR_ARG, "NaN spacing accepted");
    sc.range_min = -1;
    CHECK(sasnav_scenario_check(&sc) == SASNAV_ERR_GEOMETRY, "negative range accepted");
    return test_summary("test_geometry");
}
