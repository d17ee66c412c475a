/* Trajectories from ping-pair displacements: composition, EPCA ping poses,
 * least-squares combination of redundant links (Gauss-Newton on SE(2)),
 * alignment to the track, and errors against the truth. */
#include "sasnav/trajectory.h"
#include "sasnav/error.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static int pose_finite(sasnav_pose a) { return isfinite(a.x) && isfinite(a.y) && isfinite(a.theta); }

int sasnav_traj_compose(sasnav_pose first, const sasnav_pose *displacements, int n,
                        sasnav_pose *centroids)
{
    if (n < 1) return sasnav_set_error(SASNAV_ERR_ARG, "trajectory needs >= 1 ping, got %d", n);
    if (!centroids || (n > 1 && !displacements))
        return sasnav_set_error(SASNAV_ERR_ARG, "trajectory: NULL array");
    if (!pose_finite(first)) return sasnav_set_error(SASNAV_ERR_ARG, "first pose is not finite");
    for (int i = 0; i + 1 < n; i++)
        if (!pose_finite(displacements[i]))
            return sasnav_set_error(SASNAV_ERR_ARG, "displacement %d is not finite", i);
    centroids[0] = first;
    for (int i = 0; i + 1 < n; i++) centroids[i + 1] = sasnav_pose_compose(centroids[i], displacements[i]);
    return SASNAV_OK;
}

int sasnav_traj_displacements(const sasnav_pose *centroids, int n, sasnav_pose *displacements)
{
    if (!centroids || !displacements) return sasnav_set_error(SASNAV_ERR_ARG, "trajectory: NULL array");
    if (n < 2) return sasnav_set_error(SASNAV_ERR_ARG, "displacements need >= 2 pings, got %d", n);
    for (int i = 0; i + 1 < n; i++)
        displacements[i] = sasnav_pose_between(centroids[i], centroids[i + 1]);
    return SASNAV_OK;
}

int sasnav_traj_ping_poses(const sasnav_pose *centroids, int n, double tx_lag, double dtheta_tx,
                           sasnav_ping_pose *pings)
{
    if (!centroids || !pings) return sasnav_set_error(SASNAV_ERR_ARG, "trajectory: NULL array");
    if (n < 1) return sasnav_set_error(SASNAV_ERR_ARG, "trajectory needs >= 1 ping, got %d", n);
    if (!isfinite(tx_lag) || !isfinite(dtheta_tx))
        return sasnav_set_error(SASNAV_ERR_ARG, "Tx lag and Tx yaw offset must be finite");
    sasnav_ping_pose local = sasnav_epca_local(tx_lag, dtheta_tx);
    for (int i = 0; i < n; i++) pings[i] = sasnav_ping_place(centroids[i], &local);
    return SASNAV_OK;
}

int sasnav_traj_centroids(const sasnav_ping_pose *pings, int n, sasnav_pose *centroids)
{
    if (!centroids || !pings) return sasnav_set_error(SASNAV_ERR_ARG, "trajectory: NULL array");
    if (n < 1) return sasnav_set_error(SASNAV_ERR_ARG, "trajectory needs >= 1 ping, got %d", n);
    for (int i = 0; i < n; i++) centroids[i] = sasnav_ping_centroid(&pings[i]);
    return SASNAV_OK;
}

/* ---- Least-squares combination ------------------------------------------ */

void sasnav_traj_solve_default_opts(sasnav_traj_solve_opts *opts)
{
    if (!opts) return;
    opts->max_iterations = 20;
    opts->tolerance = 1e-10;
}

/* Symmetric positive definite band matrix of order n and half-bandwidth w,
 * upper band stored row by row: a[i * (w + 1) + (j - i)] = A(i, j), j in
 * [i, i + w]. */
typedef struct {
    int n, w;
    double *a;
} band_matrix;

static double *band_at(band_matrix *m, int i, int j) { return &m->a[(size_t)i * (m->w + 1) + (j - i)]; }

/* In-place Cholesky A = U^T U (U upper, same band). Returns -1 when a pivot
 * is not positive relative to the original diagonal (singular system). */
static int band_cholesky(band_matrix *m)
{
    int n = m->n, w = m->w;
    for (int i = 0; i < n; i++) {
        int jmax = i + w < n - 1 ? i + w : n - 1;
        for (int j = i; j <= jmax; j++) {
            double sum = *band_at(m, i, j);
            int k0 = j - w > 0 ? j - w : 0;
            for (int k = k0; k < i; k++) sum -= *band_at(m, k, i) * *band_at(m, k, j);
            if (j == i) {
                if (!(sum > 1e-13 * fabs(*band_at(m, i, i))) || !(sum > 0)) return -1;
                *band_at(m, i, i) = sqrt(sum);
            } else {
                *band_at(m, i, j) = sum / *band_at(m, i, i);
            }
        }
    }
    return 0;
}

/* Solves U^T U x = b in place (b becomes x). */
static void band_solve(band_matrix *m, double *b)
{
    int n = m->n, w = m->w;
    for (int i = 0; i < n; i++) {
        int k0 = i - w > 0 ? i - w : 0;
        double s = b[i];
        for (int k = k0; k < i; k++) s -= *band_at(m, k, i) * b[k];
        b[i] = s / *band_at(m, i, i);
    }
    for (int i = n - 1; i >= 0; i--) {
        int jmax = i + w < n - 1 ? i + w : n - 1;
        double s = b[i];
        for (int j = i + 1; j <= jmax; j++) s -= *band_at(m, i, j) * b[j];
        b[i] = s / *band_at(m, i, i);
    }
}

static int links_check(int n, const sasnav_traj_link *links, int n_links, int *max_baseline)
{
    *max_baseline = 0;
    for (int k = 0; k < n_links; k++) {
        const sasnav_traj_link *l = &links[k];
        if (l->p < 0 || l->q < 0 || l->p >= n || l->q >= n || l->p == l->q)
            return sasnav_set_error(SASNAV_ERR_ARG, "link %d joins pings %d and %d (need distinct, 0..%d)",
                                    k, l->p, l->q, n - 1);
        if (!pose_finite(l->displacement))
            return sasnav_set_error(SASNAV_ERR_ARG, "link %d displacement is not finite", k);
        if (!(l->sigma.x > 0) || !(l->sigma.y > 0) || !(l->sigma.theta > 0) || !pose_finite(l->sigma))
            return sasnav_set_error(SASNAV_ERR_ARG, "link %d needs finite sigmas > 0", k);
        int b = abs(l->q - l->p);
        if (b > *max_baseline) *max_baseline = b;
    }
    return SASNAV_OK;
}

/* Initial poses: ping q placed by its first-listed link to an earlier ping. */
static int initial_poses(int n, sasnav_pose first, const sasnav_traj_link *links, int n_links,
                         sasnav_pose *x)
{
    x[0] = first;
    for (int q = 1; q < n; q++) {
        int found = 0;
        for (int k = 0; k < n_links && !found; k++) {
            const sasnav_traj_link *l = &links[k];
            if (l->q == q && l->p < q) {
                x[q] = sasnav_pose_compose(x[l->p], l->displacement);
                found = 1;
            } else if (l->p == q && l->q < q) {
                x[q] = sasnav_pose_compose(x[l->q], sasnav_pose_inverse(l->displacement));
                found = 1;
            }
        }
        if (!found)
            return sasnav_set_error(SASNAV_ERR_ARG,
                                    "trajectory: ping %d has no link to an earlier ping", q);
    }
    return SASNAV_OK;
}

/* Adds one link's weighted residual and Jacobian to the normal equations
 * H d = -g over the unknowns (poses 1..n-1, 3 each); returns its cost. */
static double accumulate_link(const sasnav_traj_link *l, const sasnav_pose *x, band_matrix *h,
                              double *g)
{
    sasnav_pose xp = x[l->p], xq = x[l->q];
    double c = cos(xp.theta), s = sin(xp.theta);
    double dx = xq.x - xp.x, dy = xq.y - xp.y;
    double e[3] = {c * dx + s * dy - l->displacement.x, -s * dx + c * dy - l->displacement.y,
                   sasnav_wrap_angle(xq.theta - xp.theta - l->displacement.theta)};
    /* Jacobian rows (3) over the 6 parameters (xp, yp, thp, xq, yq, thq). */
    double jac[3][6] = {{-c, -s, -s * dx + c * dy, c, s, 0},
                        {s, -c, -c * dx - s * dy, -s, c, 0},
                        {0, 0, -1, 0, 0, 1}};
    double wgt[3] = {1.0 / l->sigma.x, 1.0 / l->sigma.y, 1.0 / l->sigma.theta};
    int idx[6];
    for (int a = 0; a < 3; a++) {
        idx[a] = l->p > 0 ? 3 * (l->p - 1) + a : -1;
        idx[3 + a] = l->q > 0 ? 3 * (l->q - 1) + a : -1;
    }
    double cost = 0;
    for (int r = 0; r < 3; r++) {
        double er = wgt[r] * e[r];
        cost += er * er;
        for (int a = 0; a < 6; a++) {
            if (idx[a] < 0 || jac[r][a] == 0) continue;
            double ja = wgt[r] * jac[r][a];
            g[idx[a]] += ja * er;
            for (int b = 0; b < 6; b++) {
                if (idx[b] < idx[a] || jac[r][b] == 0) continue;
                *band_at(h, idx[a], idx[b]) += ja * wgt[r] * jac[r][b];
            }
        }
    }
    return cost;
}

int sasnav_traj_solve(int n, sasnav_pose first, const sasnav_traj_link *links, int n_links,
                      const sasnav_traj_solve_opts *opts, sasnav_pose *centroids, int *iterations)
{
    if (iterations) *iterations = 0;
    if (!centroids || (n_links > 0 && !links))
        return sasnav_set_error(SASNAV_ERR_ARG, "trajectory: NULL array");
    if (n < 1) return sasnav_set_error(SASNAV_ERR_ARG, "trajectory needs >= 1 ping, got %d", n);
    if (n_links < 0) return sasnav_set_error(SASNAV_ERR_ARG, "negative number of links");
    if (!pose_finite(first)) return sasnav_set_error(SASNAV_ERR_ARG, "first pose is not finite");
    sasnav_traj_solve_opts o;
    if (opts) o = *opts;
    else sasnav_traj_solve_default_opts(&o);
    if (o.max_iterations < 1 || !(o.tolerance >= 0))
        return sasnav_set_error(SASNAV_ERR_ARG, "solve needs max_iterations >= 1 and tolerance >= 0");
    int max_baseline;
    int rc = links_check(n, links, n_links, &max_baseline);
    if (rc) return rc;
    rc = initial_poses(n, first, links, n_links, centroids);
    if (rc || n == 1) return rc;

    int nu = 3 * (n - 1), w = 3 * max_baseline + 2;
    if (w > nu - 1) w = nu - 1;
    band_matrix h = {nu, w, calloc((size_t)nu * (w + 1), sizeof(double))};
    double *g = calloc((size_t)nu, sizeof *g);
    if (!h.a || !g) {
        free(h.a);
        free(g);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "trajectory: out of memory for %d poses", n);
    }
    int done = 0;
    for (int it = 0; it < o.max_iterations && !done; it++) {
        memset(h.a, 0, sizeof(double) * (size_t)nu * (w + 1));
        memset(g, 0, sizeof(double) * (size_t)nu);
        for (int k = 0; k < n_links; k++) accumulate_link(&links[k], centroids, &h, g);
        if (band_cholesky(&h)) {
            rc = sasnav_set_error(SASNAV_ERR_GEOMETRY,
                                  "trajectory: singular normal equations (poses not constrained)");
            done = 1;
            break;
        }
        band_solve(&h, g); /* g = H^-1 g; the step is -g */
        double step = 0;
        for (int i = 1; i < n; i++) {
            const double *d = &g[3 * (i - 1)];
            centroids[i].x -= d[0];
            centroids[i].y -= d[1];
            centroids[i].theta = sasnav_wrap_angle(centroids[i].theta - d[2]);
            for (int a = 0; a < 3; a++)
                if (fabs(d[a]) > step) step = fabs(d[a]);
        }
        if (iterations) *iterations = it + 1;
        if (!isfinite(step)) {
            rc = sasnav_set_error(SASNAV_ERR_NOT_CONVERGED, "trajectory: Gauss-Newton diverged");
            done = 1;
        } else if (step <= o.tolerance) {
            done = 1;
        }
    }
    if (!done)
        rc = sasnav_set_error(SASNAV_ERR_NOT_CONVERGED, "trajectory: no convergence in %d iterations",
                              o.max_iterations);
    free(h.a);
    free(g);
    return rc;
}

/* ---- Alignment and errors ---------------------------------------------- */

int sasnav_traj_track_angle(const sasnav_pose *centroids, int n, double *angle)
{
    if (!centroids || !angle) return sasnav_set_error(SASNAV_ERR_ARG, "trajectory: NULL argument");
    if (n < 2) return sasnav_set_error(SASNAV_ERR_ARG, "track angle needs >= 2 pings, got %d", n);
    double mx = 0, my = 0;
    for (int i = 0; i < n; i++) {
        if (!pose_finite(centroids[i]))
            return sasnav_set_error(SASNAV_ERR_ARG, "centroid %d is not finite", i);
        mx += centroids[i].x;
        my += centroids[i].y;
    }
    mx /= n;
    my /= n;
    double sxx = 0, syy = 0, sxy = 0;
    for (int i = 0; i < n; i++) {
        double dx = centroids[i].x - mx, dy = centroids[i].y - my;
        sxx += dx * dx;
        syy += dy * dy;
        sxy += dx * dy;
    }
    if (!(sxx + syy > 0))
        return sasnav_set_error(SASNAV_ERR_GEOMETRY, "track angle: all centroids coincide");
    /* Principal axis of the scatter matrix (total least-squares line). */
    double a = 0.5 * atan2(2.0 * sxy, sxx - syy);
    double ex = centroids[n - 1].x - centroids[0].x, ey = centroids[n - 1].y - centroids[0].y;
    if (cos(a) * ex + sin(a) * ey < 0) a += M_PI;
    *angle = sasnav_wrap_angle(a);
    return SASNAV_OK;
}

int sasnav_traj_align(sasnav_pose *centroids, int n, double *angle)
{
    double a;
    int rc = sasnav_traj_track_angle(centroids, n, &a);
    if (rc) return rc;
    /* Rigid rotation by -a about the first centroid. */
    sasnav_pose pivot = {centroids[0].x, centroids[0].y, 0.0};
    sasnav_pose rot = {0.0, 0.0, -a};
    sasnav_pose to_pivot = sasnav_pose_inverse(pivot);
    for (int i = 0; i < n; i++) {
        sasnav_pose local = sasnav_pose_compose(to_pivot, centroids[i]);
        centroids[i] = sasnav_pose_compose(pivot, sasnav_pose_compose(rot, local));
    }
    if (angle) *angle = a;
    return SASNAV_OK;
}

int sasnav_traj_errors(const sasnav_pose *estimated, const sasnav_pose *truth, int n,
                       double track_angle, sasnav_pose *cumulative, sasnav_pose *differential)
{
    if (!estimated || !truth) return sasnav_set_error(SASNAV_ERR_ARG, "trajectory: NULL array");
    if (n < 1) return sasnav_set_error(SASNAV_ERR_ARG, "trajectory needs >= 1 ping, got %d", n);
    if (!isfinite(track_angle)) return sasnav_set_error(SASNAV_ERR_ARG, "track angle is not finite");
    double c = cos(track_angle), s = sin(track_angle);
    for (int i = 0; i < n; i++) {
        if (cumulative) {
            double dx = estimated[i].x - truth[i].x, dy = estimated[i].y - truth[i].y;
            cumulative[i] = (sasnav_pose){c * dx + s * dy, -s * dx + c * dy,
                                          sasnav_wrap_angle(estimated[i].theta - truth[i].theta)};
        }
        if (differential) {
            if (i == 0) {
                differential[0] = (sasnav_pose){0, 0, 0};
                continue;
            }
            sasnav_pose de = sasnav_pose_between(estimated[i - 1], estimated[i]);
            sasnav_pose dt = sasnav_pose_between(truth[i - 1], truth[i]);
            differential[i] = (sasnav_pose){de.x - dt.x, de.y - dt.y,
                                            sasnav_wrap_angle(de.theta - dt.theta)};
        }
    }
    return SASNAV_OK;
}

sasnav_pose sasnav_traj_rigid_fit(const sasnav_pose *a, const sasnav_pose *b, int n)
{
    if (n < 1 || !a || !b) return (sasnav_pose){0, 0, 0};
    double ax = 0, ay = 0, bx = 0, by = 0;
    for (int i = 0; i < n; i++) {
        ax += a[i].x;
        ay += a[i].y;
        bx += b[i].x;
        by += b[i].y;
    }
    ax /= n;
    ay /= n;
    bx /= n;
    by /= n;
    double sdot = 0, scross = 0;
    for (int i = 0; i < n; i++) {
        double px = a[i].x - ax, py = a[i].y - ay, qx = b[i].x - bx, qy = b[i].y - by;
        sdot += px * qx + py * qy;
        scross += px * qy - py * qx;
    }
    double phi = (sdot == 0 && scross == 0) ? 0.0 : atan2(scross, sdot);
    double c = cos(phi), s = sin(phi);
    return (sasnav_pose){bx - (c * ax - s * ay), by - (s * ax + c * ay), phi};
}

int sasnav_traj_rms_rigid(const sasnav_ping_pose *nav, const sasnav_ping_pose *truth, int n,
                          double *surge_rms, double *sway_rms)
{
    if (!nav || !truth || n < 1 || !surge_rms || !sway_rms)
        return sasnav_set_error(SASNAV_ERR_ARG, "rms_rigid: NULL argument or n < 1");
    sasnav_pose *a = malloc(sizeof *a * n), *t = malloc(sizeof *t * n);
    int rc = a && t ? SASNAV_OK : sasnav_set_error(SASNAV_ERR_NOMEM, "rms_rigid: out of memory");
    if (!rc) rc = sasnav_traj_centroids(nav, n, a);
    if (!rc) rc = sasnav_traj_centroids(truth, n, t);
    if (!rc) {
        sasnav_pose m = sasnav_traj_rigid_fit(a, t, n);
        double ex = 0, ey = 0;
        for (int p = 0; p < n; p++) {
            sasnav_pose e = sasnav_pose_compose(m, a[p]);
            ex += (e.x - t[p].x) * (e.x - t[p].x);
            ey += (e.y - t[p].y) * (e.y - t[p].y);
        }
        *surge_rms = sqrt(ex / n);
        *sway_rms = sqrt(ey / n);
    }
    free(a);
    free(t);
    return rc;
}
