/* T^H is the adjoint of T (SPEC 5): |<T x, y> - <x, T^H y>| <= 1e-5 ||T x|| ||y||
 * on random x, y, for the paper-pair geometry, a rotated bistatic 3-D one and
 * a layout of channels with transmitters of their own (three pings of a
 * three-channel array as one virtual ping, sasnav_op_set_channels),
 * for every stored tap count and both adjoint loop orders (small and large
 * grids); results independent of the thread count; the
 * accumulating adjoint; and the operator's input checks.
 *
 * Why 1e-5: in exact arithmetic the two inner products are equal (T^H applies
 * the transposed steps of T with the same real weights). What remains is float
 * rounding: each output of T or T^H is a sum of O(10^2-10^4) float products
 * with relative rounding ~6e-8, which accumulates (randomly) to ~1e-7..1e-6 of
 * the norms; the double-precision inner products add nothing. A wrong
 * conjugation, a mismatched weight or an indexing slip gives differences of
 * order ||T x|| ||y|| / sqrt(#samples) ~ 1e-2 here, and the second check with
 * y = T x' (large inner products) catches even small mismatches in scale. */
#include "sasnav/error.h"
#include "sasnav/geometry.h"
#include "sasnav/model.h"
#include "sasnav/op.h"
#include "testutil.h"

#include <complex.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static uint64_t rng_state = 12345;
static double uniform(void)
{
    uint64_t z = (rng_state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return (z >> 11) * (1.0 / 9007199254740992.0);
}
static double gauss(void)
{
    double u = uniform(), v = uniform();
    return sqrt(-2.0 * log(u + 1e-300)) * cos(2.0 * M_PI * v);
}
static void random_vector(sasnav_cfloat *v, size_t n)
{
    for (size_t i = 0; i < n; i++) v[i] = (float)gauss() + I * (float)gauss();
}

/* <a, b> = sum a_i conj(b_i), in double. */
static double complex dot(const sasnav_cfloat *a, const sasnav_cfloat *b, size_t n)
{
    double complex s = 0.0;
    for (size_t i = 0; i < n; i++) s += (double complex)a[i] * conj((double complex)b[i]);
    return s;
}
static double norm2(const sasnav_cfloat *a, size_t n) { return sqrt(creal(dot(a, a, n))); }

typedef struct {
    const char *name;
    sasnav_system sys;
    sasnav_array array;
    sasnav_window win;
    sasnav_ping_pose ping;
    sasnav_ping_pose chan[SASNAV_MAX_RX]; /* per-channel poses when per_channel */
    int per_channel;
    int np;
    double *x, *y;
} setup;

/* A grid nx x ny of spacing d centred on (cx, cy) rotated by `angle`, plus
 * `n_far` points far outside the window (their pairs are dropped). */
static void make_points(setup *s, int nx, int ny, double d, double cx, double cy, double angle,
                        int n_far)
{
    s->np = nx * ny + n_far;
    s->x = malloc((size_t)s->np * sizeof *s->x);
    s->y = malloc((size_t)s->np * sizeof *s->y);
    double c = cos(angle), sn = sin(angle);
    for (int j = 0; j < ny; j++)
        for (int i = 0; i < nx; i++) {
            double u = (i - 0.5 * (nx - 1)) * d, v = (j - 0.5 * (ny - 1)) * d;
            s->x[j * nx + i] = cx + c * u - sn * v;
            s->y[j * nx + i] = cy + sn * u + c * v;
        }
    for (int k = 0; k < n_far; k++) {
        s->x[nx * ny + k] = cx + 0.1 * k;
        s->y[nx * ny + k] = cy + 5.0 + k;
    }
}

static void paper_pair(setup *s)
{
    s->name = "paper pair";
    sasnav_system_default(&s->sys);
    sasnav_array_uniform(&s->array, 16, 0.05, 0.05, 0.05);
    sasnav_ping_pose local = sasnav_epca_local(0.10, 0.0);
    sasnav_pose centroid = {0.0, 0.0, 0.0};
    s->ping = sasnav_ping_place(centroid, &local);
    sasnav_window_for_ranges(&s->sys, 9.6, 10.4, 8, &s->win);
    make_points(s, 40, 48, 0.0125, 0.0, 10.0, 0.0, 5);
}

/* A grid large enough (160 x 160 points x 16 channels, 18 MB of pair data)
 * for the operator to use its streaming adjoint loop (op.c, STREAM_BYTES). */
static void paper_pair_large(setup *s)
{
    paper_pair(s);
    free(s->x);
    free(s->y);
    s->name = "paper pair 160^2";
    sasnav_window_for_ranges(&s->sys, 8.9, 11.2, 8, &s->win);
    make_points(s, 160, 160, 0.0125, 0.0, 10.0, 0.0, 0);
}

/* Rotated bistatic geometry: array yaw 0.3, Tx yaw 0.22 and displaced
 * sideways, sensors 0.5 / 0.8 m above the plane, spherical spreading, Hann
 * taper, an irregular array. */
static void rotated_bistatic(setup *s)
{
    s->name = "rotated bistatic";
    sasnav_system_default(&s->sys);
    s->sys.attenuation = SASNAV_ATTEN_SPHERICAL;
    s->sys.taper = SASNAV_TAPER_HANN;
    sasnav_array_uniform(&s->array, 7, 0.06, 0.04, 0.08);
    s->array.rx_u[3] += 0.013;
    s->array.rx_height = 0.5;
    s->array.tx_height = 0.8;
    sasnav_pose tx = {0.9, -0.55, 0.22}, arr = {1.1, -0.45, 0.3};
    s->ping.tx = tx;
    s->ping.array = arr;
    sasnav_window_for_ranges(&s->sys, 7.5, 8.7, 4, &s->win);
    /* Boresight of yaw 0.3 is (-sin 0.3, cos 0.3). */
    make_points(s, 33, 29, 0.02, 1.0 - 8.0 * sin(0.3), -0.5 + 8.0 * cos(0.3), 0.3, 3);
}

/* Channels as Tx-Rx pairs: three pings of a 3-channel bistatic array along
 * a curved path (yaw and Tx pose changing from ping to ping), heights, as
 * one 9-channel virtual ping. */
static void channel_layout(setup *s)
{
    rotated_bistatic(s);
    s->name = "channel layout";
    sasnav_array a;
    sasnav_array_uniform(&a, 3, 0.06, 0.04, 0.08);
    a.rx_height = 0.5;
    a.tx_height = 0.8;
    s->array = a;
    s->array.n_rx = 9;
    for (int j = 0; j < 3; j++)
        for (int l = 0; l < 3; l++) {
            s->array.rx_u[3 * j + l] = a.rx_u[l];
            sasnav_pose tx = {0.9 + 0.07 * j, -0.55 + 0.004 * j * j, 0.22 + 0.01 * j};
            sasnav_pose arr = {1.1 + 0.07 * j, -0.45 + 0.003 * j * j, 0.3 + 0.012 * j};
            s->chan[3 * j + l].tx = tx;
            s->chan[3 * j + l].array = arr;
        }
    s->per_channel = 1;
}

static void free_setup(setup *s)
{
    free(s->x);
    free(s->y);
}

static sasnav_op *make_op(const setup *s, double tol, double sigma, int nthreads)
{
    sasnav_op_opts o;
    sasnav_op_default_opts(&o);
    o.tolerance = tol;
    o.oversampling = sigma;
    o.nthreads = nthreads;
    sasnav_op *op = NULL;
    CHECK_OK(sasnav_op_create(&s->sys, &s->array, &s->win, s->np, s->x, s->y, &o, &op));
    if (op) CHECK_OK(s->per_channel ? sasnav_op_set_channels(op, s->chan)
                                     : sasnav_op_set_geometry(op, &s->ping));
    return op;
}

static void check_adjoint(const setup *s, double tol, double sigma)
{
    sasnav_op *op = make_op(s, tol, sigma, 0);
    if (!op) return;
    size_t np = (size_t)s->np, nd = (size_t)s->array.n_rx * (size_t)s->win.n_samples;
    sasnav_cfloat *x = malloc(np * sizeof *x), *tx = malloc(nd * sizeof *tx);
    sasnav_cfloat *y = malloc(nd * sizeof *y), *thy = malloc(np * sizeof *thy);
    random_vector(x, np);
    random_vector(y, nd);
    CHECK_OK(sasnav_op_forward(op, x, tx));
    CHECK_OK(sasnav_op_adjoint(op, y, thy));
    double scale = norm2(tx, nd) * norm2(y, nd);
    double diff = cabs(dot(tx, y, nd) - dot(x, thy, np));
    printf("  %-17s tol %.0e sigma %.2f w %2d: |<Tx,y> - <x,T^H y>| / (|Tx||y|) = %.2e "
           "(dropped %ld)\n",
           s->name, tol, sigma, sasnav_op_kernel_width(op), diff / scale, sasnav_op_n_dropped(op));
    CHECK(scale > 0.0, "%s: T x is not zero", s->name);
    CHECK(diff <= 1e-5 * scale, "%s tol %g: adjoint mismatch %g", s->name, tol, diff / scale);
    /* y correlated with the range of T: <T x, T x2> is of the order of the
     * norms, so a relative scale error of 1e-5 in T^H would show. */
    sasnav_cfloat *x2 = malloc(np * sizeof *x2);
    random_vector(x2, np);
    for (size_t i = 0; i < np; i++) x2[i] = 0.5f * x2[i] + x[i];
    CHECK_OK(sasnav_op_forward(op, x2, y));
    CHECK_OK(sasnav_op_adjoint(op, y, thy));
    double complex a = dot(tx, y, nd), b = dot(x, thy, np);
    CHECK(cabs(a - b) <= 1e-5 * norm2(tx, nd) * norm2(y, nd) && cabs(a - b) <= 1e-5 * cabs(a),
          "%s: correlated inner products %g%+gi vs %g%+gi", s->name, creal(a), cimag(a), creal(b),
          cimag(b));
    free(x);
    free(x2);
    free(tx);
    free(y);
    free(thy);
    sasnav_op_destroy(op);
}

/* nthreads 1 and 2 give the same numbers: every output is computed by one
 * thread in a fixed order, so they are expected bitwise equal (checked to
 * 1e-6 of the norm; identity is reported). */
static void check_threads(const setup *s)
{
    sasnav_op *op1 = make_op(s, 1e-6, 2.0, 1), *op2 = make_op(s, 1e-6, 2.0, 2);
    if (!op1 || !op2) return;
    size_t np = (size_t)s->np, nd = (size_t)s->array.n_rx * (size_t)s->win.n_samples;
    sasnav_cfloat *x = malloc(np * sizeof *x), *d1 = malloc(nd * sizeof *d1);
    sasnav_cfloat *d2 = malloc(nd * sizeof *d2), *r1 = malloc(np * sizeof *r1);
    sasnav_cfloat *r2 = malloc(np * sizeof *r2);
    random_vector(x, np);
    CHECK_OK(sasnav_op_forward(op1, x, d1));
    CHECK_OK(sasnav_op_forward(op2, x, d2));
    CHECK_OK(sasnav_op_adjoint(op1, d1, r1));
    CHECK_OK(sasnav_op_adjoint(op2, d1, r2));
    double ed = 0.0, er = 0.0;
    for (size_t i = 0; i < nd; i++) ed = fmax(ed, cabsf(d1[i] - d2[i]));
    for (size_t i = 0; i < np; i++) er = fmax(er, cabsf(r1[i] - r2[i]));
    int same = !memcmp(d1, d2, nd * sizeof *d1) && !memcmp(r1, r2, np * sizeof *r1);
    printf("  %-17s 1 vs 2 threads: max diff forward %.1e adjoint %.1e (%s)\n", s->name, ed, er,
           same ? "bitwise identical" : "not bitwise identical");
    CHECK(ed <= 1e-6 * norm2(d1, nd) && er <= 1e-6 * norm2(r1, np), "%s: threads differ", s->name);
    /* adjoint_add accumulates: r2 = r1 + T^H d1 = 2 r1 (exact in float). */
    memcpy(r2, r1, np * sizeof *r1);
    CHECK_OK(sasnav_op_adjoint_add(op2, d1, r2));
    int twice = 1;
    for (size_t i = 0; i < np; i++) twice &= r2[i] == 2.0f * r1[i];
    CHECK(twice, "%s: adjoint_add accumulates", s->name);
    free(x);
    free(d1);
    free(d2);
    free(r1);
    free(r2);
    sasnav_op_destroy(op1);
    sasnav_op_destroy(op2);
}

/* Every channel with the ping's pose: set_channels gives set_geometry's
 * numbers bit for bit (the one-Tx case is one run of channels); a channel
 * moved changes that channel's data only. */
static void check_channels_match(const setup *s)
{
    sasnav_op *a = make_op(s, 1e-6, 2.0, 0), *b = make_op(s, 1e-6, 2.0, 0);
    if (!a || !b) return;
    sasnav_ping_pose ch[SASNAV_MAX_RX];
    for (int l = 0; l < s->array.n_rx; l++) ch[l] = s->ping;
    CHECK_OK(sasnav_op_set_channels(b, ch));
    size_t np = (size_t)s->np, ns = (size_t)s->win.n_samples, nd = (size_t)s->array.n_rx * ns;
    sasnav_cfloat *x = malloc(np * sizeof *x), *da = malloc(nd * sizeof *da);
    sasnav_cfloat *db = malloc(nd * sizeof *db), *ra = malloc(np * sizeof *ra);
    sasnav_cfloat *rb = malloc(np * sizeof *rb);
    random_vector(x, np);
    CHECK_OK(sasnav_op_forward(a, x, da));
    CHECK_OK(sasnav_op_forward(b, x, db));
    CHECK_OK(sasnav_op_adjoint(a, da, ra));
    CHECK_OK(sasnav_op_adjoint(b, da, rb));
    CHECK(!memcmp(da, db, nd * sizeof *da) && !memcmp(ra, rb, np * sizeof *ra),
          "%s: set_channels with the ping's pose = set_geometry, bit for bit", s->name);
    /* Channel 2's transmitter 5 cm away: only channel 2 changes. */
    ch[2].tx.x += 0.05;
    CHECK_OK(sasnav_op_set_channels(b, ch));
    CHECK_OK(sasnav_op_forward(b, x, db));
    int others_same = 1;
    double moved = 0;
    for (int l = 0; l < s->array.n_rx; l++)
        for (size_t m = 0; m < ns; m++) {
            size_t i = (size_t)l * ns + m;
            if (l == 2) moved = fmax(moved, cabsf(da[i] - db[i]));
            else others_same &= da[i] == db[i];
        }
    CHECK(others_same && moved > 1e-3 * norm2(da, nd) / sqrt((double)nd),
          "%s: one channel's Tx moved changes that channel alone (change %g)", s->name, moved);
    free(x);
    free(da);
    free(db);
    free(ra);
    free(rb);
    sasnav_op_destroy(a);
    sasnav_op_destroy(b);
}

static void check_bad_inputs(void)
{
    sasnav_system sys;
    sasnav_system_default(&sys);
    sasnav_array array;
    sasnav_array_uniform(&array, 4, 0.05, 0.05, 0.05);
    sasnav_window win;
    sasnav_window_for_ranges(&sys, 9.0, 11.0, 8, &win);
    double x[2] = {0.0, 0.1}, y[2] = {10.0, 10.0};
    sasnav_op *op = (sasnav_op *)&op; /* must be reset to NULL on failure */
    CHECK(sasnav_op_create(NULL, &array, &win, 2, x, y, NULL, &op) == SASNAV_ERR_ARG && !op,
          "NULL system");
    CHECK(sasnav_op_create(&sys, NULL, &win, 2, x, y, NULL, &op) == SASNAV_ERR_ARG, "NULL array");
    CHECK(sasnav_op_create(&sys, &array, NULL, 2, x, y, NULL, &op) == SASNAV_ERR_ARG, "NULL window");
    CHECK(sasnav_op_create(&sys, &array, &win, 0, x, y, NULL, &op) == SASNAV_ERR_ARG, "0 points");
    CHECK(sasnav_op_create(&sys, &array, &win, 2, NULL, y, NULL, &op) == SASNAV_ERR_ARG, "NULL x");
    CHECK(sasnav_op_create(&sys, &array, &win, 2, x, y, NULL, NULL) == SASNAV_ERR_ARG, "NULL out");
    y[1] = NAN;
    CHECK(sasnav_op_create(&sys, &array, &win, 2, x, y, NULL, &op) == SASNAV_ERR_ARG, "NaN point");
    y[1] = INFINITY;
    CHECK(sasnav_op_create(&sys, &array, &win, 2, x, y, NULL, &op) == SASNAV_ERR_ARG, "inf point");
    y[1] = 10.0;
    sasnav_window bad_win = {NAN, 10};
    CHECK(sasnav_op_create(&sys, &array, &bad_win, 2, x, y, NULL, &op) == SASNAV_ERR_ARG, "NaN t0");
    bad_win.t0 = 0.0;
    bad_win.n_samples = 0;
    CHECK(sasnav_op_create(&sys, &array, &bad_win, 2, x, y, NULL, &op) == SASNAV_ERR_ARG,
          "0 samples");
    sasnav_op_opts o;
    sasnav_op_default_opts(&o);
    o.tolerance = 0.0;
    CHECK(sasnav_op_create(&sys, &array, &win, 2, x, y, &o, &op) == SASNAV_ERR_ARG, "tol 0");
    sasnav_op_default_opts(&o);
    o.oversampling = 1.0;
    CHECK(sasnav_op_create(&sys, &array, &win, 2, x, y, &o, &op) == SASNAV_ERR_ARG, "sigma 1");
    sasnav_op_default_opts(&o);
    o.nthreads = -1;
    CHECK(sasnav_op_create(&sys, &array, &win, 2, x, y, &o, &op) == SASNAV_ERR_ARG, "nthreads -1");
    sasnav_array bad_array = array;
    bad_array.n_rx = 0;
    CHECK(sasnav_op_create(&sys, &bad_array, &win, 2, x, y, NULL, &op) == SASNAV_ERR_ARG, "0 Rx");

    CHECK_OK(sasnav_op_create(&sys, &array, &win, 2, x, y, NULL, &op));
    sasnav_cfloat rho[2] = {1, 1}, data[4 * 400];
    CHECK(sasnav_op_n_samples(op) <= 400, "window size");
    CHECK(sasnav_op_forward(op, rho, data) == SASNAV_ERR_ARG, "forward before set_geometry");
    sasnav_ping_pose ping = {{0, 0, 0}, {0, 0, 0}};
    ping.array.theta = NAN;
    CHECK(sasnav_op_set_geometry(op, &ping) == SASNAV_ERR_ARG, "NaN pose");
    CHECK(sasnav_op_set_geometry(op, NULL) == SASNAV_ERR_ARG, "NULL pose");
    CHECK(sasnav_op_set_channels(op, NULL) == SASNAV_ERR_ARG, "NULL channel poses");
    sasnav_ping_pose chans[4] = {{{0, 0, 0}, {0, 0, 0}}, {{0, 0, 0}, {0, 0, 0}},
                                 {{0, 0, 0}, {0, 0, 0}}, {{0, 0, 0}, {0, 0, 0}}};
    chans[3].tx.y = NAN;
    CHECK(sasnav_op_set_channels(op, chans) == SASNAV_ERR_ARG &&
              strstr(sasnav_last_error(), "channel 3"),
          "NaN pose of channel 3: %s", sasnav_last_error());
    chans[3].tx = (sasnav_pose){0.0, 10.0, 0.0}; /* channel 3's Tx on point 0 */
    CHECK(sasnav_op_set_channels(op, chans) == SASNAV_ERR_GEOMETRY &&
              strstr(sasnav_last_error(), "Tx of channel 3"),
          "point on channel 3's Tx: %s", sasnav_last_error());
    /* A point on a receiver (Rx 3 at u = +0.075) and on the Tx. */
    sasnav_ping_pose on_rx = {{0, 0, 0}, {0.1 - 0.075, 10.0, 0.0}};
    CHECK(sasnav_op_set_geometry(op, &on_rx) == SASNAV_ERR_GEOMETRY, "point on a receiver: %s",
          sasnav_last_error());
    CHECK(sasnav_op_forward(op, rho, data) == SASNAV_ERR_ARG, "failed geometry is not used");
    sasnav_ping_pose on_tx = {{0.0, 10.0, 0.0}, {0, 0, 0}};
    CHECK(sasnav_op_set_geometry(op, &on_tx) == SASNAV_ERR_GEOMETRY, "point on the Tx");
    ping.array.theta = 0.0;
    CHECK_OK(sasnav_op_set_geometry(op, &ping));
    CHECK(sasnav_op_forward(op, NULL, data) == SASNAV_ERR_ARG, "NULL rho");
    CHECK(sasnav_op_adjoint(op, data, NULL) == SASNAV_ERR_ARG, "NULL image");
    CHECK(sasnav_op_n_points(op) == 2 && sasnav_op_n_rx(op) == 4, "sizes");
    CHECK(sasnav_op_period(op) >= sasnav_op_n_samples(op) / sys.sample_rate, "period covers window");
    sasnav_op_destroy(op);
    sasnav_op_destroy(NULL);
}

int main(void)
{
    setup s[4];
    memset(s, 0, sizeof s);
    paper_pair(&s[0]);
    rotated_bistatic(&s[1]);
    paper_pair_large(&s[2]);
    channel_layout(&s[3]);
    /* Tolerances covering every stored tap count (4, 8, 12, 16) and three
     * oversampling factors. */
    static const double tols[4] = {1e-3, 1e-6, 1e-9, 1e-12};
    for (int k = 0; k < 2; k++) {
        for (int t = 0; t < 4; t++) check_adjoint(&s[k], tols[t], 2.0);
        check_adjoint(&s[k], 1e-6, 1.25);
        check_adjoint(&s[k], 1e-4, 3.0);
        check_threads(&s[k]);
    }
    /* 1e-3: four taps, the estimator's, whose streaming adjoint takes four
     * points at a time in vectors (op.c, interp_four_4) */
    check_adjoint(&s[2], 1e-3, 2.0);
    check_adjoint(&s[2], 1e-6, 2.0);
    check_adjoint(&s[2], 1e-9, 2.0);
    check_threads(&s[2]);
    for (int t = 0; t < 4; t++) check_adjoint(&s[3], tols[t], 2.0);
    check_threads(&s[3]);
    check_channels_match(&s[0]);
    check_channels_match(&s[1]);
    check_bad_inputs();
    for (int k = 0; k < 4; k++) free_setup(&s[k]);
    return test_summary("test_op_adjoint");
}
