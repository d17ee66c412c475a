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
#include "sasnav/trajectory.h"
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

/* Inverts the k x k matrix a (row-major, in place) by Gauss-Jordan with
 * partial pivoting. */
static void invert(int k, double *a)
{
    double *w = calloc((size_t)(k * 2 * k), sizeof *w);
    for (int r = 0; r < k; r++) {
        for (int c = 0; c < k; c++) w[r * 2 * k + c] = a[r * k + c];
        w[r * 2 * k + k + r] = 1.0;
    }
    for (int c = 0; c < k; c++) {
        int piv = c;
        for (int r = c + 1; r < k; r++)
            if (fabs(w[r * 2 * k + c]) > fabs(w[piv * 2 * k + c])) piv = r;
        for (int t = 0; t < 2 * k; t++) {
            double x = w[c * 2 * k + t];
            w[c * 2 * k + t] = w[piv * 2 * k + t];
            w[piv * 2 * k + t] = x;
        }
        double f = w[c * 2 * k + c];
        for (int t = 0; t < 2 * k; t++) w[c * 2 * k + t] /= f;
        for (int r = 0; r < k; r++) {
            if (r == c) continue;
            double g = w[r * 2 * k + c];
            for (int t = 0; t < 2 * k; t++) w[r * 2 * k + t] -= g * w[c * 2 * k + t];
        }
    }
    for (int r = 0; r < k; r++)
        for (int c = 0; c < k; c++) a[r * k + c] = w[r * 2 * k + k + c];
    free(w);
}

enum { M = 12 };

/* One case of test_pose_sigma: returns the worst relative difference to the
 * dense reference and writes the fast form's final deviations. With
 * `huber` > 0 and `outlier` an estimate 20 of its deviations off the
 * aiding in yaw: the smoother down-weights it, and the reference takes
 * the Huber weights from the smoother's final e (the weights of its last
 * solve agree with them to the loop's 1e-3 change test). */
static double pose_sigma_case(double huber, int outlier, sasnav_pose *final_sigma)
{
    sasnav_pose m[M], sm[M], a[M], sa[M], e[M], nom[M], disp[M], poses[M + 1], sigma[M + 1];
    for (int j = 0; j < M; j++) {
        m[j] = (sasnav_pose){1e-3 * sin(0.7 * j), 2e-5 * cos(0.3 * j), 5e-5 * sin(0.5 * j)};
        sm[j] = (sasnav_pose){1e-3 * (1.0 + 0.3 * (j % 3)), 2e-5, 5e-5 * (1.0 + 0.5 * (j % 2))};
        a[j] = (sasnav_pose){0.9e-3 * sin(0.7 * j), 1e-5, 1e-5 * j};
        sa[j] = (sasnav_pose){5e-4, 1e-3, 2e-4};
        nom[j] = (sasnav_pose){0.2, 0.004 * (j % 3), 0.01 - 0.002 * j};
    }
    sm[5] = (sasnav_pose){INFINITY, INFINITY, INFINITY}; /* a bridged step */
    sa[7].theta = INFINITY;                             /* no gyro there */
    if (outlier) m[3].theta += 20 * sm[3].theta;
    sasnav_pose motion = {1e-3, 5e-5, 1e-4}, bs = {4e-4, 4e-4, 0};
    double buf[9 * M];
    fuse_posterior post;
    for (int k = 0; k < 3; k++) {
        post.d[k] = buf + 3 * k * M;
        post.off[k] = buf + (3 * k + 1) * M;
        post.yu[k] = buf + (3 * k + 2) * M;
    }
    CHECK_OK(fuse_smooth_post(M, m, sm, a, sa, motion, huber, bs, e, NULL, &post));
    CHECK(post.denom[0] > 0 && post.denom[1] > 0 && post.denom[2] == 0, "bias terms %g %g %g", post.denom[0],
          post.denom[1], post.denom[2]);
    for (int j = 0; j < M; j++)
        disp[j] = (sasnav_pose){nom[j].x + e[j].x, nom[j].y + e[j].y, nom[j].theta + e[j].theta};
    sasnav_pose first = {1.0, -2.0, 0.3};
    CHECK_OK(sasnav_traj_compose(first, disp, M + 1, poses));
    /* The poses far from the origin (world coordinates of a survey: UTM
     * metres): the standard deviations depend on differences only. */
    sasnav_pose far[M + 1];
    for (int i = 0; i <= M; i++) far[i] = (sasnav_pose){poses[i].x + 4.5e5, poses[i].y + 6.1e6, poses[i].theta};
    CHECK_OK(fuse_pose_sigma(M, &post, far, sigma));
    /* Dense posterior covariance per component. */
    static double cov[3][M][M];
    for (int k = 0; k < 3; k++) {
        int nb = comp(bs, k) > 0 ? 1 : 0, K = M + nb;
        double *info = calloc((size_t)(K * K), sizeof *info);
        double wm = 1.0 / (comp(motion, k) * comp(motion, k));
        for (int j = 0; j < M; j++) {
            double s1 = comp(sm[j], k), s2 = comp(sa[j], k);
            double w1 = isfinite(s1) ? 1.0 / (s1 * s1) : 0.0, w2 = isfinite(s2) ? 1.0 / (s2 * s2) : 0.0;
            if (huber > 0 && isfinite(s1)) {
                double r = fabs(comp(m[j], k) - comp(e[j], k)) / s1;
                if (r > huber) w1 *= huber / r;
            }
            info[j * K + j] += 1.0 + w1 + w2; /* the smoother's prior of 1 (m, rad) */
            if (j + 1 < M) {
                info[j * K + j] += wm;
                info[(j + 1) * K + j + 1] += wm;
                info[j * K + j + 1] -= wm;
                info[(j + 1) * K + j] -= wm;
            }
            if (nb) {
                info[j * K + M] += w2;
                info[M * K + j] += w2;
                info[M * K + M] += w2;
            }
        }
        if (nb) info[M * K + M] += 1.0 / (comp(bs, k) * comp(bs, k));
        invert(K, info);
        for (int i = 0; i < M; i++)
            for (int j = 0; j < M; j++) cov[k][i][j] = info[i * K + j];
        free(info);
    }
    /* Numerical derivatives of every pose with respect to every step. */
    const double h = 1e-6;
    static double J[M + 1][3][3][M]; /* [ping][output][component][step] */
    for (int k = 0; k < 3; k++)
        for (int j = 0; j < M; j++) {
            sasnav_pose dp[M], dm[M], pp[M + 1], pm[M + 1];
            memcpy(dp, disp, sizeof dp);
            memcpy(dm, disp, sizeof dm);
            if (k == 0) dp[j].x += h, dm[j].x -= h;
            else if (k == 1) dp[j].y += h, dm[j].y -= h;
            else dp[j].theta += h, dm[j].theta -= h;
            sasnav_traj_compose(first, dp, M + 1, pp);
            sasnav_traj_compose(first, dm, M + 1, pm);
            for (int i = 0; i <= M; i++) {
                J[i][0][k][j] = (pp[i].x - pm[i].x) / (2 * h);
                J[i][1][k][j] = (pp[i].y - pm[i].y) / (2 * h);
                J[i][2][k][j] = (pp[i].theta - pm[i].theta) / (2 * h);
            }
        }
    double worst = 0;
    for (int i = 0; i <= M; i++)
        for (int out = 0; out < 3; out++) {
            double v = 0;
            for (int k = 0; k < 3; k++)
                for (int r = 0; r < M; r++)
                    for (int c = 0; c < M; c++) v += J[i][out][k][r] * cov[k][r][c] * J[i][out][k][c];
            double ref = sqrt(v), got = comp(sigma[i], out);
            double rel = i == 0 ? fabs(got) : fabs(got - ref) / ref;
            if (rel > worst) worst = rel;
        }
    *final_sigma = sigma[M];
    return worst;
}

/* The trajectory's formal standard deviations (fuse_pose_sigma, O(n)
 * prefix sums of the factored system) against a slow direct reference:
 * each component's posterior covariance from the dense inverse of the
 * smoother's information matrix (the bias unknown included, then
 * marginalised by taking the block), carried through numerical
 * derivatives of the composed poses. Weights that couple the steps
 * strongly (a motion model as tight as the estimates, a bridged step
 * without an estimate, the aiding's bias in surge and sway), so that the
 * tails and the bias term of the fast form matter; the poses handed to
 * it 6e6 m from the origin. Tolerance: 1e-6 relative (central
 * differences of step 1e-6 on poses of order 1); with Huber weights
 * 1e-3 (the reference's weights from the final e, within the loop's
 * 1e-3 of those solved with), and the down-weighting must show: the
 * final yaw deviation grows by more than 20 x that (a fast form with the
 * first pass's unit weights would miss the reference by that much). */
static void test_pose_sigma(void)
{
    sasnav_pose plain, robust;
    double worst = pose_sigma_case(0.0, 0, &plain);
    printf("pose sigma: final %.4g m, %.4g m, %.4g rad; worst relative difference to the dense one %.2e\n",
           plain.x, plain.y, plain.theta, worst);
    CHECK(worst < 1e-6, "formal standard deviations differ from the dense reference by %.2e", worst);
    worst = pose_sigma_case(3.0, 1, &robust);
    sasnav_pose outl;
    pose_sigma_case(0.0, 1, &outl);
    double grew = robust.theta / outl.theta - 1.0;
    printf("pose sigma with an outlier down-weighted: final yaw %.4g rad (%.4g without Huber), worst "
           "relative difference %.2e\n",
           robust.theta, outl.theta, worst);
    CHECK(worst < 1e-3, "with Huber weights: differ from the dense reference by %.2e", worst);
    CHECK(grew > 0.02, "the down-weighted outlier did not widen the yaw deviation (%.3g)", grew);
}

int main(void)
{
    test_choose();
    test_smooth();
    test_bias();
    test_pose_sigma();
    return test_summary("test_fuse");
}
