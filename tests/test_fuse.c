/* The joint resolution and the smoother of sasnav_navigate
 * (src/trajectory/fuse.c) against constructed truths and a direct dense
 * solution:
 *   - a run of 8 pairs whose true motion errors vary smoothly; each pair
 *     offers the right candidate and one a phase-centre slip away (d of
 *     surge, d / R of yaw); on pairs 3 and 5 the slipped candidate has the
 *     lower eta (the per-pair best is wrong). The motion model alone picks
 *     the right candidates where the slip is large against the run's
 *     smoothness, and the aiding picks them whatever eta says;
 *   - the smoother equals the dense normal-equations solution of the same
 *     least squares (no Huber downweighting active), pulls an outlier
 *     estimate onto the aiding (Huber), and bridges a pair without an
 *     estimate from the aiding. */
#include "sasnav/error.h"
#include "testutil.h"
#include "trajectory/fuse.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define N 8

static double comp(sasnav_pose p, int k) { return k == 0 ? p.x : k == 1 ? p.y : p.theta; }

static void test_choose(void)
{
    const double d = 0.025, R = 10.0;
    sasnav_pose truth[N];
    for (int j = 0; j < N; j++)
        truth[j] = (sasnav_pose){2e-3 * sin(0.3 * j), 1e-3 * cos(0.2 * j), 1e-3 * sin(0.25 * j)};
    fuse_option pool[N][2];
    fuse_option *opts[N];
    int nopt[N], choice[N];
    for (int j = 0; j < N; j++) {
        sasnav_pose slip = {truth[j].x + d, truth[j].y, truth[j].theta - d / R};
        int wrong_best = j == 3 || j == 5;
        pool[j][0] = (fuse_option){slip, wrong_best ? 0.30 : 0.45, 1};
        pool[j][1] = (fuse_option){truth[j], wrong_best ? 0.31 : 0.30, 0};
        opts[j] = pool[j];
        nopt[j] = 2;
    }
    sasnav_pose a[N], sa[N];
    for (int j = 0; j < N; j++) {
        a[j] = (sasnav_pose){0, 0, 0};
        sa[j] = (sasnav_pose){INFINITY, INFINITY, INFINITY};
    }
    /* Each pair alone (no motion model coupling worth the name, no
     * aiding): the lower eta wins, wrong on pairs 3 and 5. */
    sasnav_pose loose = {1e3, 1e3, 1e3};
    CHECK_OK(fuse_choose(N, opts, nopt, a, sa, loose, 20.0, choice));
    CHECK(choice[3] == 0 && choice[5] == 0 && choice[2] == 1, "alone: choices %d %d %d", choice[2],
          choice[3], choice[5]);
    /* Motion model of 5 mm / 5e-4 rad per pair: a 25 mm, 2.5e-3 rad jump
     * costs 25 + 12.5 nats, ln(0.31 / 0.30) * 20 = 0.66 nats: the right
     * candidates everywhere. */
    sasnav_pose motion = {5e-3, 5e-3, 5e-4};
    CHECK_OK(fuse_choose(N, opts, nopt, a, sa, motion, 20.0, choice));
    int all = 1;
    for (int j = 0; j < N; j++) all &= choice[j] == 1;
    CHECK(all, "motion model: a slipped candidate was chosen");
    /* Aiding alone (a gyro of 1e-6 rad, a DVL of 0.3 mm), no motion model:
     * the right candidates even where eta prefers the slip strongly. */
    for (int j = 0; j < N; j++) {
        a[j] = (sasnav_pose){truth[j].x + 2e-4, truth[j].y, truth[j].theta + 1e-6};
        sa[j] = (sasnav_pose){3e-4, 3e-4, 1e-6};
        pool[j][0].eta = 0.2;
    }
    CHECK_OK(fuse_choose(N, opts, nopt, a, sa, loose, 20.0, choice));
    all = 1;
    for (int j = 0; j < N; j++) all &= choice[j] == 1;
    CHECK(all, "aiding: a slipped candidate was chosen");
    /* Costs that overflow (an aiding value far out against a tiny sigma)
     * still leave a choice of an existing option for every pair: before,
     * a pair after one whose every cost was infinite got option -1. */
    a[2] = (sasnav_pose){1e300, 0, 0};
    sa[2] = (sasnav_pose){1e-300, 1e-3, 1e-3};
    for (int j = 0; j < N; j++) choice[j] = -7;
    CHECK_OK(fuse_choose(N, opts, nopt, a, sa, motion, 20.0, choice));
    int in_range = 1;
    for (int j = 0; j < N; j++) in_range &= choice[j] >= 0 && choice[j] < nopt[j];
    CHECK(in_range, "infinite costs: choices %d %d %d %d out of range", choice[1], choice[2], choice[3],
          choice[4]);
}

/* Dense reference: the normal equations of
 * sum w_m (e - m)^2 + w_a (e - a)^2 + w_s (e_{j+1} - e_j)^2 + prior e^2,
 * solved by Gaussian elimination. */
static void dense_solve(int n, const double *wm, const double *m, const double *wa, const double *a,
                        double ws, double *e)
{
    double A[N][N + 1];
    memset(A, 0, sizeof A);
    for (int j = 0; j < n; j++) {
        A[j][j] += 1.0 + wm[j] + wa[j];
        A[j][n] = wm[j] * m[j] + wa[j] * a[j];
        if (j + 1 < n) {
            A[j][j] += ws;
            A[j + 1][j + 1] += ws;
            A[j][j + 1] -= ws;
            A[j + 1][j] -= ws;
        }
    }
    for (int c = 0; c < n; c++)
        for (int r = c + 1; r < n; r++) {
            double f = A[r][c] / A[c][c];
            for (int k = c; k <= n; k++) A[r][k] -= f * A[c][k];
        }
    for (int r = n - 1; r >= 0; r--) {
        double s = A[r][n];
        for (int k = r + 1; k < n; k++) s -= A[r][k] * e[k];
        e[r] = s / A[r][r];
    }
}

static void test_smooth(void)
{
    sasnav_pose m[N], sm[N], a[N], sa[N], e[N];
    for (int j = 0; j < N; j++) {
        m[j] = (sasnav_pose){1e-3 * j, 2e-5 * (j % 3), 1e-4 * cos(j)};
        sm[j] = (sasnav_pose){1e-3, 2e-5, 5e-5};
        a[j] = (sasnav_pose){m[j].x + 2e-4, m[j].y - 1e-4, m[j].theta + 3e-5};
        sa[j] = (sasnav_pose){5e-4, 3e-4, 2e-5};
    }
    sasnav_pose motion = {1e-2, 1e-2, 1e-2};
    /* Huber off (threshold 0): plain weighted least squares. */
    CHECK_OK(fuse_smooth(N, m, sm, a, sa, motion, 0.0, e));
    for (int k = 0; k < 3; k++) {
        double wm[N], mm[N], wa[N], aa[N], ref[N];
        for (int j = 0; j < N; j++) {
            wm[j] = 1.0 / (comp(sm[j], k) * comp(sm[j], k));
            wa[j] = 1.0 / (comp(sa[j], k) * comp(sa[j], k));
            mm[j] = comp(m[j], k);
            aa[j] = comp(a[j], k);
        }
        double ws = 1.0 / (comp(motion, k) * comp(motion, k));
        dense_solve(N, wm, mm, wa, aa, ws, ref);
        double worst = 0;
        for (int j = 0; j < N; j++) {
            double scale = fabs(ref[j]) > 1e-12 ? fabs(ref[j]) : 1e-12;
            double rel = fabs(comp(e[j], k) - ref[j]) / scale;
            if (rel > worst) worst = rel;
        }
        /* Thomas algorithm against Gaussian elimination: round-off only. */
        CHECK(worst < 1e-9, "component %d: smoother differs from the dense solution by %.2e", k, worst);
    }
    /* An outlier (a 25 mm surge slip) with a DVL of 0.5 mm: Huber weights
     * pull the fused value onto the aiding (within 2 mm), not halfway. */
    m[4].x += 0.025;
    CHECK_OK(fuse_smooth(N, m, sm, a, sa, motion, 3.0, e));
    CHECK(fabs(e[4].x - a[4].x) < 2e-3, "outlier kept: fused %.2f mm, aiding %.2f mm", 1e3 * e[4].x,
          1e3 * a[4].x);
    /* A pair without estimate is bridged by the aiding. */
    sm[2] = (sasnav_pose){INFINITY, INFINITY, INFINITY};
    CHECK_OK(fuse_smooth(N, m, sm, a, sa, motion, 3.0, e));
    CHECK(fabs(e[2].y - a[2].y) < 1e-6 && fabs(e[2].theta - a[2].theta) < 1e-7,
          "bridged pair: fused sway %.4f mm (aiding %.4f)", 1e3 * e[2].y, 1e3 * a[2].y);
}

/* The joint aiding bias: the bordered system against a dense solve, and a
 * constructed run where the aiding carries a constant 0.4 mm per pair
 * (a DVL's scale error at a steady speed) and the estimates are unbiased
 * with 1 mm of noise: estimating the bias brings the summed (final) error
 * of the fused run well below what ignoring it leaves. */
static void test_bias(void)
{
    sasnav_pose m[N], sm[N], a[N], sa[N], e[N], bias;
    double truth[N];
    /* Deterministic "noise" of zero mean. */
    const double noise[N] = {0.9, -1.1, 0.4, -0.3, 1.2, -0.8, 0.1, -0.4};
    for (int j = 0; j < N; j++) {
        truth[j] = 1e-3 * sin(0.4 * j);
        m[j] = (sasnav_pose){truth[j] + 1e-3 * noise[j], 0, 0};
        sm[j] = (sasnav_pose){1e-3, INFINITY, INFINITY};
        a[j] = (sasnav_pose){truth[j] + 4e-4 + 1e-4 * noise[(j + 3) % N], 0, 0};
        sa[j] = (sasnav_pose){4.1e-4, INFINITY, INFINITY};
    }
    sasnav_pose motion = {1e-2, 1e-2, 1e-2}, bs = {4e-4, 0, 0};
    CHECK_OK(fuse_smooth_bias(N, m, sm, a, sa, motion, 0.0, bs, e, &bias));
    /* Dense reference with the extra unknown. */
    double A[N + 1][N + 2];
    memset(A, 0, sizeof A);
    double ws = 1.0 / (motion.x * motion.x), wm = 1e6, wa = 1.0 / (sa[0].x * sa[0].x);
    for (int j = 0; j < N; j++) {
        A[j][j] += 1.0 + wm + wa;
        A[j][N] += wa;
        A[N][j] += wa;
        A[N][N] += wa;
        A[j][N + 1] = wm * m[j].x + wa * a[j].x;
        A[N][N + 1] += wa * a[j].x;
        if (j + 1 < N) {
            A[j][j] += ws;
            A[j + 1][j + 1] += ws;
            A[j][j + 1] -= ws;
            A[j + 1][j] -= ws;
        }
    }
    A[N][N] += 1.0 / (bs.x * bs.x);
    for (int c = 0; c <= N; c++)
        for (int r = c + 1; r <= N; r++) {
            double f = A[r][c] / A[c][c];
            for (int k = c; k <= N + 1; k++) A[r][k] -= f * A[c][k];
        }
    double ref[N + 1];
    for (int r = N; r >= 0; r--) {
        double s = A[r][N + 1];
        for (int k = r + 1; k <= N; k++) s -= A[r][k] * ref[k];
        ref[r] = s / A[r][r];
    }
    double worst = fabs(bias.x - ref[N]) / fabs(ref[N]);
    for (int j = 0; j < N; j++) {
        double rel = fabs(e[j].x - ref[j]) / (fabs(ref[j]) > 1e-9 ? fabs(ref[j]) : 1e-9);
        if (rel > worst) worst = rel;
    }
    CHECK(worst < 1e-9, "bordered solve differs from the dense one by %.2e", worst);
    double sum_with = 0, sum_without = 0;
    for (int j = 0; j < N; j++) sum_with += e[j].x - truth[j];
    CHECK_OK(fuse_smooth(N, m, sm, a, sa, motion, 0.0, e));
    for (int j = 0; j < N; j++) sum_without += e[j].x - truth[j];
    printf("aiding bias: estimated %.3f mm (true 0.400); summed error %.3f mm with, %.3f mm without\n",
           1e3 * bias.x, 1e3 * sum_with, 1e3 * sum_without);
    CHECK(fabs(sum_with) < 0.5 * fabs(sum_without), "estimating the bias did not halve the summed error");
    CHECK(bias.x > 1e-4, "bias estimate %.3f mm", 1e3 * bias.x);
}

int main(void)
{
    test_choose();
    test_smooth();
    test_bias();
    return test_summary("test_fuse");
}
