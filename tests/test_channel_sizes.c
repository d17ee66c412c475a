/* Channels of their own sizes (sasnav_array.per_channel: each channel's
 * transmitter and receiver apertures and heights; docs/model.md "Channel
 * layouts", format version 2 /array/sizes).
 *
 * 1. The operator against one-channel operators: channel l of an operator
 *    whose channels have sizes of their own is the operator of a head made
 *    of channel l alone with those sizes as the array's (the one-size code
 *    path, tested against first principles by test_op_point / test_nufft).
 *    Forward: channel by channel; adjoint: the sum of the one-channel
 *    adjoints. Both use the same arithmetic, so the tolerance is float
 *    rounding (1e-6 relative; measured 0). The same operator with the
 *    array's mean heights for every channel differs by O(1): the test can
 *    fail.
 * 2. Adjointness <T x, y> = <x, T^H y> to 1e-5 relative (float sums of
 *    ~10^4 terms).
 * 3. The simulated echo of a point target against first principles, with
 *    receivers at two heights (0.4 m and 1.6 m) and the transmitter at 1 m:
 *    for every channel of every ping the sample nearest the two-way delay
 *    tau = (sqrt(d_t^2 + h_t^2) + sqrt(d_r^2 + h_l^2)) / c (computed here)
 *    has the phase -2 pi f0 tau to 1e-3 rad (test_channels' tolerance:
 *    interpolation 1e-6 and float samples give 1e-5 rad; 1 micron of path
 *    is 1.3e-3 rad). With one height for all receivers (their mean) the
 *    phases are off by radians.
 * 4. Focus: the backprojected image of that run (true poses) peaks within
 *    1 mm of the target; made as if every receiver sat at the mean height
 *    it loses most of its peak; FFBP matches the direct sum (-30 dB, as
 *    test_channels asks).
 * 5. Virtual arrays and subsets carry the sizes; config lists. */
#include "sasnav/config.h"
#include "sasnav/error.h"
#include "sasnav/geometry.h"
#include "sasnav/image.h"
#include "sasnav/op.h"
#include "sasnav/run.h"
#include "sasnav/sim.h"
#include "sasnav/virtual.h"
#include "testutil.h"

#include <complex.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define CHECK_FAILS(expr, want)                                                                      \
    do {                                                                                             \
        int rc_ = (expr);                                                                            \
        CHECK(rc_ == (want), "%s returned %d, expected %d (%s)", #expr, rc_, (want), sasnav_last_error()); \
        if (rc_ == (want)) printf("  ok: %s\n", sasnav_last_error());                                \
    } while (0)

#define N_CH 4
static const double RX_H[N_CH] = {0.4, 1.6, 0.4, 1.6};
static const double RX_D[N_CH] = {0.05, 0.04, 0.05, 0.03};
#define TX_H 1.0

/* Four receivers spaced 5 cm, at two heights and of three lengths, one
 * 5 cm transmitter at 1 m. */
static void sized_head(sasnav_array *a)
{
    CHECK_OK(sasnav_array_uniform(a, N_CH, 0.05, 0.05, 0.05));
    sasnav_channel_size z[N_CH];
    for (int l = 0; l < N_CH; l++) {
        sasnav_channel_size zl = {RX_D[l], 0.05, RX_H[l], TX_H};
        z[l] = zl;
    }
    CHECK_OK(sasnav_array_set_sizes(a, z));
}

static double rel_diff(const sasnav_cfloat *a, const sasnav_cfloat *b, size_t n)
{
    double e = 0, r = 0;
    for (size_t i = 0; i < n; i++) {
        e += pow(cabs(a[i] - b[i]), 2);
        r += pow(cabs(b[i]), 2);
    }
    return r > 0 ? sqrt(e / r) : sqrt(e);
}

static void test_operator(void)
{
    sasnav_scenario sc;
    CHECK_OK(sasnav_scenario_preset("point", &sc));
    sasnav_array a;
    sized_head(&a);
    const int n = 300;
    double x[300], y[300];
    sasnav_cfloat rho[300], back[300], sum[300];
    uint64_t s = 12345;
    for (int i = 0; i < n; i++) {
        s = s * 6364136223846793005ull + 1442695040888963407ull;
        x[i] = -0.2 + 0.4 * (double)(s >> 11) / 9007199254740992.0;
        s = s * 6364136223846793005ull + 1442695040888963407ull;
        y[i] = 9.8 + 0.4 * (double)(s >> 11) / 9007199254740992.0;
        rho[i] = (float)cos(3.0 * i) + I * (float)sin(7.0 * i);
    }
    sasnav_window win = {2 * 9.5 / sc.sys.sound_speed, 0};
    win.n_samples = (int)(2 * 1.0 / sc.sys.sound_speed * sc.sys.sample_rate);
    sasnav_op_opts oo;
    sasnav_op_default_opts(&oo);
    oo.nthreads = 1;
    sasnav_ping_pose ping = {{-0.1, 0.0, 0.02}, {0.0, 0.003, 0.021}};
    sasnav_op *op = NULL;
    CHECK_OK(sasnav_op_create(&sc.sys, &a, &win, n, x, y, &oo, &op));
    if (!op) return;
    CHECK_OK(sasnav_op_set_geometry(op, &ping));
    size_t ns = (size_t)win.n_samples;
    sasnav_cfloat *data = malloc(sizeof *data * ns * N_CH), *one = malloc(sizeof *one * ns);
    sasnav_cfloat *probe = malloc(sizeof *probe * ns * N_CH);
    CHECK_OK(sasnav_op_forward(op, rho, data));
    for (size_t i = 0; i < ns * N_CH; i++) probe[i] = (float)sin(0.37 * i) + I * (float)cos(0.11 * i);
    CHECK_OK(sasnav_op_adjoint(op, probe, back));
    memset(sum, 0, sizeof sum);
    double worst_fwd = 0;
    for (int l = 0; l < N_CH; l++) {
        sasnav_array b;
        CHECK_OK(sasnav_array_uniform(&b, 1, 1.0, RX_D[l], 0.05));
        b.rx_u[0] = a.rx_u[l];
        b.rx_height = RX_H[l];
        b.tx_height = TX_H;
        sasnav_op *o1 = NULL;
        CHECK_OK(sasnav_op_create(&sc.sys, &b, &win, n, x, y, &oo, &o1));
        if (!o1) continue;
        CHECK_OK(sasnav_op_set_geometry(o1, &ping));
        CHECK_OK(sasnav_op_forward(o1, rho, one));
        double e = rel_diff(data + l * ns, one, ns);
        if (e > worst_fwd) worst_fwd = e;
        CHECK_OK(sasnav_op_adjoint_add(o1, probe + l * ns, sum));
        sasnav_op_destroy(o1);
    }
    double e_adj = rel_diff(back, sum, (size_t)n);
    /* The same head with one size for all (the mean heights, largest lengths). */
    sasnav_array m = a;
    CHECK_OK(sasnav_array_set_sizes(&m, NULL));
    sasnav_op *om = NULL;
    CHECK_OK(sasnav_op_create(&sc.sys, &m, &win, n, x, y, &oo, &om));
    double e_mean = 0;
    if (om) {
        CHECK_OK(sasnav_op_set_geometry(om, &ping));
        sasnav_cfloat *dm = malloc(sizeof *dm * ns * N_CH);
        CHECK_OK(sasnav_op_forward(om, rho, dm));
        e_mean = rel_diff(dm, data, ns * N_CH);
        free(dm);
        sasnav_op_destroy(om);
    }
    /* adjointness */
    double complex lhs = 0, rhs = 0;
    for (size_t i = 0; i < ns * N_CH; i++) lhs += data[i] * conj(probe[i]);
    for (int i = 0; i < n; i++) rhs += rho[i] * conj(back[i]);
    double e_dot = cabs(lhs - rhs) / cabs(lhs);
    printf("operator: forward vs one-channel operators %.1e, adjoint %.1e, <Tx,y> vs <x,T^H y> %.1e; "
           "one size for all: %.2f\n",
           worst_fwd, e_adj, e_dot, e_mean);
    CHECK(worst_fwd < 1e-6, "forward channel differs from its one-channel operator by %.2e", worst_fwd);
    CHECK(e_adj < 1e-6, "adjoint differs from the sum of one-channel adjoints by %.2e", e_adj);
    CHECK(e_dot < 1e-5, "adjointness %.2e", e_dot);
    CHECK(e_mean > 0.1, "per-channel sizes change nothing (%.2e): the test cannot fail", e_mean);
    free(data);
    free(one);
    free(probe);
    sasnav_op_destroy(op);
}

static sasnav_run *point_run(void)
{
    sasnav_scenario sc;
    CHECK_OK(sasnav_scenario_preset("point", &sc));
    sized_head(&sc.array);
    sasnav_run *run = NULL;
    CHECK_OK(sasnav_simulate(&sc, NULL, NULL, &run));
    CHECK(run && run->array.per_channel, "the simulated run lost its per-channel sizes");
    return run;
}

static void test_echo_phase(const sasnav_run *run, double px, double py)
{
    const double c = run->sys.sound_speed, f0 = run->sys.f0, fs = run->sys.sample_rate;
    double worst = 0, worst_mean = 0, hm = 0;
    for (int l = 0; l < N_CH; l++) hm += RX_H[l] / N_CH;
    int checked = 0;
    for (int p = 0; p < run->n_pings; p++) {
        const sasnav_ping_pose *t = &run->truth[p];
        const sasnav_cfloat *d = sasnav_run_ping(run, p);
        for (int l = 0; l < N_CH; l++) {
            double rxx = t->array.x + run->array.rx_u[l] * cos(t->array.theta);
            double rxy = t->array.y + run->array.rx_u[l] * sin(t->array.theta);
            double dr = hypot(px - rxx, py - rxy), dt = hypot(px - t->tx.x, py - t->tx.y);
            double rt = sqrt(dt * dt + TX_H * TX_H);
            double tau = (rt + sqrt(dr * dr + RX_H[l] * RX_H[l])) / c;
            double tau_mean = (rt + sqrt(dr * dr + hm * hm)) / c;
            /* inside the elements' first nulls (horizontal sin phi < lambda / D) */
            double s_rx = fabs((px - rxx) * cos(t->array.theta) + (py - rxy) * sin(t->array.theta)) / dr;
            double s_tx = fabs((px - t->tx.x) * cos(t->tx.theta) + (py - t->tx.y) * sin(t->tx.theta)) / dt;
            if (s_rx > 0.08 || s_tx > 0.08) continue;
            long m = lround((tau - run->win.t0) * fs);
            if (m < 0 || m >= run->win.n_samples) continue;
            sasnav_cfloat v = d[(size_t)l * run->win.n_samples + m];
            double got = carg(v);
            double e = fabs(remainder(got + 2 * M_PI * f0 * tau, 2 * M_PI));
            double e_mean = fabs(remainder(got + 2 * M_PI * f0 * tau_mean, 2 * M_PI));
            if (e > worst) worst = e;
            if (e_mean > worst_mean) worst_mean = e_mean;
            checked++;
        }
    }
    printf("echo phase: %d channel-pings, worst error %.2e rad (one mean height: %.2f rad)\n", checked,
           worst, worst_mean);
    CHECK(checked >= 24, "only %d channel-pings inside the beams", checked);
    CHECK(worst < 1e-3, "echo phase off by %.2e rad from the per-channel delay", worst);
    CHECK(worst_mean > 0.5, "the heights change nothing (%.2e rad): the test cannot fail", worst_mean);
}

static void test_focus(sasnav_run *run, double tx_, double ty_)
{
    sasnav_grid g;
    CHECK_OK(sasnav_grid_make(tx_ - 0.0407, tx_ + 0.0393, 41, ty_ - 0.0403, ty_ + 0.0397, 41, &g));
    size_t n = (size_t)g.nx * g.ny;
    sasnav_cfloat *img = malloc(sizeof *img * n), *mean = malloc(sizeof *mean * n);
    double ffbp_db = test_backproject_ffbp(run, run->truth, &g, img);
    sasnav_op_opts oo;
    sasnav_op_default_opts(&oo);
    oo.nthreads = 1;
    sasnav_array keep = run->array;
    CHECK_OK(sasnav_array_set_sizes(&run->array, NULL)); /* one size: the mean heights */
    CHECK_OK(sasnav_backproject(run, run->truth, &g, &oo, mean));
    run->array = keep;
    double x, y, xm, ym;
    double peak = test_image_peak(&g, img, &x, &y), peak_mean = test_image_peak(&g, mean, &xm, &ym);
    printf("focus: peak at (%+.2f, %+.2f) mm from the target; one-height image: peak %.3f of it, at "
           "(%+.1f, %+.1f) mm; FFBP vs direct %.1f dB\n",
           1e3 * (x - tx_), 1e3 * (y - ty_), peak_mean / peak, 1e3 * (xm - tx_), 1e3 * (ym - ty_), ffbp_db);
    CHECK(hypot(x - tx_, y - ty_) < 1e-3, "the image peaks %.2f mm from the target", 1e3 * hypot(x - tx_, y - ty_));
    CHECK(peak_mean < 0.7 * peak, "one height for all keeps %.3f of the peak", peak_mean / peak);
    CHECK(ffbp_db < -30, "FFBP with per-channel sizes %.1f dB from the direct sum", ffbp_db);
    free(img);
    free(mean);
}

static void test_carried(void)
{
    sasnav_array a, v;
    sized_head(&a);
    CHECK_OK(sasnav_virtual_array(&a, 3, &v));
    int ok = v.n_rx == 3 * N_CH && v.per_channel;
    for (int l = 0; ok && l < v.n_rx; l++)
        ok = memcmp(&v.size[l], &a.size[l % N_CH], sizeof v.size[l]) == 0 && v.rx_u[l] == a.rx_u[l % N_CH];
    CHECK(ok, "a virtual array does not repeat the channels' sizes");
    int pick[2] = {3, 0};
    sasnav_array s;
    CHECK_OK(sasnav_array_select(&a, pick, 2, &s));
    CHECK(s.n_rx == 2 && s.size[0].rx_length == RX_D[3] && s.size[1].rx_height == RX_H[0] &&
              s.rx_length == 0.05 && fabs(s.rx_height - 0.5 * (RX_H[3] + RX_H[0])) < 1e-15,
          "select: sizes or array-wide values wrong");
    pick[0] = N_CH;
    CHECK_FAILS(sasnav_array_select(&a, pick, 2, &s), SASNAV_ERR_ARG);

    /* Config: per-channel lists, a list of the wrong length refused. */
    const char *good = "array:\n  n_rx: 4\n  rx_spacing: 0.05\n  rx_length: 0.05\n  tx_height: 1.0\n"
                       "  rx_heights: [0.4, 1.6, 0.4, 1.6]\n  rx_lengths: [0.05, 0.04, 0.05, 0.03]\n";
    char path[1200];
    snprintf(path, sizeof path, "%s/sizes.yaml", test_tmpdir());
    FILE *f = fopen(path, "w");
    if (f) {
        fputs(good, f);
        fclose(f);
    }
    sasnav_scenario sc;
    CHECK_OK(sasnav_scenario_preset("point", &sc));
    CHECK_OK(sasnav_config_load(path, &sc));
    int same = sc.array.per_channel && sc.array.n_rx == N_CH;
    for (int l = 0; same && l < N_CH; l++)
        same = sc.array.size[l].rx_height == RX_H[l] && sc.array.size[l].rx_length == RX_D[l] &&
               sc.array.size[l].tx_height == TX_H && sc.array.size[l].tx_length == sc.array.tx_length;
    CHECK(same, "config: per-channel lists not applied");
    /* written and read back: the same sizes */
    char path2[1200];
    snprintf(path2, sizeof path2, "%s/sizes-out.yaml", test_tmpdir());
    CHECK_OK(sasnav_config_write(path2, &sc));
    sasnav_scenario sc2;
    CHECK_OK(sasnav_scenario_preset("paper-pair", &sc2));
    CHECK_OK(sasnav_config_load(path2, &sc2));
    CHECK(sc2.array.per_channel && memcmp(sc2.array.size, sc.array.size, sizeof sc.array.size) == 0,
          "config: per-channel sizes do not round-trip");
    f = fopen(path, "w");
    if (f) {
        fputs("array:\n  n_rx: 4\n  rx_spacing: 0.05\n  rx_heights: [0.4, 1.6]\n", f);
        fclose(f);
    }
    CHECK_OK(sasnav_scenario_preset("point", &sc));
    CHECK_FAILS(sasnav_config_load(path, &sc), SASNAV_ERR_CONFIG);
    CHECK(strstr(sasnav_last_error(), "rx_heights") != NULL, "message '%s' does not name the key",
          sasnav_last_error());
}

int main(void)
{
    test_operator();
    sasnav_run *run = point_run();
    if (run) {
        double x = 0.013, y = 10.007; /* the "point" preset's target */
        test_echo_phase(run, x, y);
        test_focus(run, x, y);
        sasnav_run_free(run);
    }
    test_carried();
    return test_summary("test_channel_sizes");
}
