/* Fast factorised backprojection (FFBP; Ulander, Hellsten & Stenstrom,
 * IEEE Trans. AES 39(3), 2003), for the bistatic multi-receiver pings of
 * sasnav (image.h, docs/survey.md "FFBP").
 *
 * A subaperture (consecutive pings) has a local polar frame: origin at the
 * mean PCA centroid of its pings, axis along their mean heading, range rho
 * (horizontal) and direction cosine u = along / rho on the imaged side.
 * Its image f (the sum of its pings' adjoints) is stored demodulated,
 *   g(rho, u) = f exp(-j k sqrt(rho^2 + h^2)),  k = 4 pi f0 / c,
 * which is band-limited: along rho by the pulse (|k_rho| <= 2 pi B / c)
 * widened by the drift of the residual delay with range (the sensors'
 * offsets squared over 2 rho^2: a long subaperture at short range), and
 * along u by the spread of the subaperture's sensors about its origin
 * (spatial frequencies (f0 + f) s / c for along-track sensor-offset sums s):
 * a short subaperture needs few samples in u, a long one many, over the
 * same region. The recursion:
 *   - leaves: a group of LEAF_CHANNELS channels of one ping (the tree runs
 *     over the (ping, channel) items in order), by the exact adjoint
 *     operator (sasnav_op, its points replaced per leaf) on the leaf's
 *     polar grid, then demodulated;
 *   - a node: its two halves' polar images interpolated (6-tap Kaiser-sinc
 *     in rho and u) at its own polar samples, each remodulated by the phase
 *     of its own reference delay and demodulated by the node's;
 *   - the tile: the largest nodes whose polar grids hold fewer samples than
 *     the tile has pixels are interpolated onto the pixels and summed.
 * The top grids cover the tile, each child grid its parent's whole grid,
 * each widened by its own interpolation reach (4 samples), so every
 * sample an interpolation uses is right.
 * Where the polar frame does not suit (the rectangle reaching the track's
 * line, or within 18 degrees of end-fire), the node is split, down to the
 * direct operator on the pixels. The error against direct backprojection is
 * the interpolations' (about -50 dB each at the default oversampling 2);
 * measured in docs/survey.md. */
#include "sasnav/error.h"
#include "sasnav/image.h"
#include "backproject_internal.h"

#include <complex.h>
#include <limits.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#define TAPS 6
#define HALF 3
#define WSTEPS 4096  /* tabulated fractional positions (nearest: < -65 dB) */
#define UNSUITED 1000 /* internal: the polar frame does not suit this node */
#define U_LIMIT 0.95  /* |u| above this: too close to end-fire */
/* The leaves' time-interpolation tolerance: 1e-3 (-60 dB, the operator's
 * error is about a fifth of it) is well below the polar interpolations'
 * error and halves the kernel width of the default 1e-6. */
#define LEAF_TOLERANCE 1e-3
/* Channels per leaf: a leaf's polar grid needs u samples in proportion to
 * its aperture, so its cost grows as the square of its channels, while
 * each halving adds a merge level; 8 was the fastest of 4, 8, 16 and 32
 * on a 32-channel survey tile (docs/survey.md). */
#define LEAF_CHANNELS 32

typedef struct {
    double cx, cy, ca, sa; /* origin, heading (cos, sin) */
    int side;              /* +1: the region lies at positive across-track */
    double rho0, drho, u0, du;
    int nrho, nu;
} polar;

typedef struct {
    const sasnav_run *run;
    const sasnav_ping_pose *nav;
    const sasnav_op_opts *oo;
    const int *pings;
    double xa, xb, ya, yb; /* the tile's pixel centres */
    int c0, r0, w, h;
    const sasnav_grid *grid;
    double os, k, h2, umax;
    int nrx, nthreads;
    int cur_ping;          /* the ping held in cur (-1: none) */
    const sasnav_cfloat *cur;
    sasnav_cfloat *scratch; /* one ping's samples, for direct() */
    float *wtab;           /* (WSTEPS + 1) x TAPS weights */
    sasnav_cfloat *ping_buf, *tile;
    sasnav_op *tile_op;    /* the pixels' direct operator, made when needed */
    int group;             /* channels per leaf */
    sasnav_op *leaf_op[SASNAV_MAX_RX]; /* the leaves' operators, one per channel
                                          group (points replaced per leaf) */
    sasnav_op_opts leaf_oo; /* its options: tolerance at most LEAF_TOLERANCE */
    long *step, steps;
    sasnav_ping_progress_fn progress;
    void *user;
} ffbp_ctx;

static double bessel_i0(double x)
{
    double sum = 1, term = 1, q = x * x / 4;
    for (int k = 1; k < 60; k++) {
        term *= q / ((double)k * k);
        sum += term;
        if (term < 1e-17 * sum) break;
    }
    return sum;
}

/* The Kaiser window's beta that minimises the interpolation error of a
 * signal oversampled `os` times (fitted on band-limited noise, 6 taps):
 * -29, -40, -48, -53, -64, -69 dB at 1.25, 1.5, 1.75, 2, 3, 4. */
static double kaiser_beta(double os)
{
    static const double o[6] = {1.25, 1.5, 1.75, 2.0, 3.0, 4.0}, b[6] = {2.0, 3.5, 4.0, 5.0, 6.5, 7.0};
    if (os <= o[0]) return b[0];
    for (int i = 1; i < 6; i++)
        if (os <= o[i]) return b[i - 1] + (b[i] - b[i - 1]) * (os - o[i - 1]) / (o[i] - o[i - 1]);
    return b[5];
}

/* wtab[k * TAPS + t]: the weight of sample floor(a) - HALF + 1 + t for a
 * fractional part k / WSTEPS: sinc times a Kaiser window of HALF samples. */
static void make_weights(float *wtab, double os)
{
    double beta = kaiser_beta(os), norm = bessel_i0(beta);
    for (int k = 0; k <= WSTEPS; k++)
        for (int t = 0; t < TAPS; t++) {
            double x = fabs((double)k / WSTEPS + HALF - 1 - t);
            double q = x / HALF, win = q < 1 ? bessel_i0(beta * sqrt(1 - q * q)) / norm : 0;
            double sinc = x == 0 ? 1.0 : sin(M_PI * x) / (M_PI * x);
            wtab[k * TAPS + t] = (float)(sinc * win);
        }
}

/* exp(j ph) for a phase of any size: reduced in double, then float. */
static inline sasnav_cfloat phasor(double ph)
{
    ph -= 2 * M_PI * rint(ph * (0.5 / M_PI));
    float f = (float)ph;
    return cosf(f) + I * sinf(f);
}

static void polar_point(const polar *g, double rho, double u, double *x, double *y)
{
    double along = rho * u, across = g->side * rho * sqrt(fmax(0.0, 1 - u * u));
    *x = g->cx + along * g->ca - across * g->sa;
    *y = g->cy + along * g->sa + across * g->ca;
}

/* Polar coordinates of (x, y) in g's frame; 0 when on the other side. */
static int to_polar(const polar *g, double x, double y, double *rho, double *u)
{
    double dx = x - g->cx, dy = y - g->cy;
    double along = dx * g->ca + dy * g->sa, across = -dx * g->sa + dy * g->ca;
    *rho = sqrt(dx * dx + dy * dy);
    if (!(g->side * across > 0) || !(*rho > 0)) return 0;
    *u = along / *rho;
    return 1;
}

/* g's value at (rho, u) by separable 6-tap interpolation (samples outside
 * the grid count as zero). */
static sasnav_cfloat interp(const ffbp_ctx *cx, const polar *g, const sasnav_cfloat *v, double rho,
                            double u)
{
    double a = (rho - g->rho0) / g->drho, b = (u - g->u0) / g->du;
    if (!(a > -HALF && a < g->nrho + HALF && b > -HALF && b < g->nu + HALF)) return 0;
    double fa = floor(a), fb = floor(b);
    int ia = (int)fa, ib = (int)fb;
    const float *wa = cx->wtab + (size_t)lrint((a - fa) * WSTEPS) * TAPS;
    const float *wb = cx->wtab + (size_t)lrint((b - fb) * WSTEPS) * TAPS;
    float re = 0, im = 0;
    int i0 = ia - HALF + 1, j0 = ib - HALF + 1;
    if (i0 >= 0 && i0 + TAPS <= g->nrho && j0 >= 0 && j0 + TAPS <= g->nu) {
        /* Inside: no bounds checks (the common case). */
        /* Rows weighted in rho first (12 interleaved floats per row: a
         * vectorisable loop), then the u weights. */
        const float *base = (const float *)(v + (size_t)i0 * (size_t)g->nu + (size_t)j0);
        float acc[2 * TAPS] = {0};
        for (int t = 0; t < TAPS; t++) {
            const float *row = base + 2 * (size_t)t * (size_t)g->nu;
            float w = wa[t];
            for (int k = 0; k < 2 * TAPS; k++) acc[k] += w * row[k];
        }
        for (int s2 = 0; s2 < TAPS; s2++) {
            re += wb[s2] * acc[2 * s2];
            im += wb[s2] * acc[2 * s2 + 1];
        }
        return re + I * im;
    }
    for (int t = 0; t < TAPS; t++) {
        int i = i0 + t;
        if (i < 0 || i >= g->nrho) continue;
        const sasnav_cfloat *row = v + (size_t)i * (size_t)g->nu;
        float rr = 0, ri = 0;
        for (int s2 = 0; s2 < TAPS; s2++) {
            int j = j0 + s2;
            if (j < 0 || j >= g->nu) continue;
            rr += wb[s2] * crealf(row[j]);
            ri += wb[s2] * cimagf(row[j]);
        }
        re += wa[t] * rr;
        im += wa[t] * ri;
    }
    return re + I * im;
}

/* Item i: channel i % nrx of ping pings[i / nrx]; its transmitter and
 * receiver positions. */
static void item_sensors(const ffbp_ctx *cx, int i, double *tx, double *ty, double *rx, double *ry,
                         double *theta)
{
    const sasnav_ping_pose *p = &cx->nav[cx->pings[i / cx->nrx]];
    double u = cx->run->array.rx_u[i % cx->nrx];
    sasnav_ping_pose ch;
    if (cx->run->channel_offset) { /* the channel's own poses */
        sasnav_channel_poses(p, &cx->run->channel_offset[i % cx->nrx], 1, &ch);
        p = &ch;
    }
    *tx = p->tx.x;
    *ty = p->tx.y;
    *rx = p->array.x + u * cos(p->array.theta);
    *ry = p->array.y + u * sin(p->array.theta);
    *theta = p->array.theta;
}

/* Polar coordinates of any point (the side ignored: for bounding boxes). */
static void to_polar_any(const polar *g, double x, double y, double *rho, double *u)
{
    double dx = x - g->cx, dy = y - g->cy;
    *rho = hypot(dx, dy);
    *u = *rho > 0 ? (dx * g->ca + dy * g->sa) / *rho : 0.0;
}

/* The polar grid of items [a, b): over the tile (parent NULL: the grid
 * that is interpolated onto the pixels) or over the parent's whole grid,
 * widened by the interpolation's reach in its own samples. */
/* The largest tx_height^2 + rx_height^2 over the channels. */
static double max_height2(const sasnav_array *array)
{
    double m = 0.0;
    for (int l = 0; l < (array->per_channel ? array->n_rx : 1); l++) {
        sasnav_channel_size z = sasnav_array_channel_size(array, l);
        double h = z.tx_height * z.tx_height + z.rx_height * z.rx_height;
        if (h > m) m = h;
    }
    return m;
}

static int node_geometry(const ffbp_ctx *cx, int a, int b, const polar *parent, polar *g)
{
    const sasnav_run *run = cx->run;
    double mx = 0, my = 0, ms = 0, mc = 0;
    for (int i = a; i < b; i++) {
        double tx, ty, rx, ry, th;
        item_sensors(cx, i, &tx, &ty, &rx, &ry, &th);
        mx += 0.5 * (tx + rx);
        my += 0.5 * (ty + ry);
        ms += sin(th);
        mc += cos(th);
    }
    g->cx = mx / (b - a);
    g->cy = my / (b - a);
    double hd = atan2(ms, mc);
    g->ca = cos(hd);
    g->sa = sin(hd);
    /* The tile: all on one side of the axis, away from end-fire. */
    double X[2] = {cx->xa, cx->xb}, Y[2] = {cx->ya, cx->yb};
    int pos = 0, neg = 0;
    for (int i = 0; i < 2; i++)
        for (int j = 0; j < 2; j++) {
            double across = -(X[i] - g->cx) * g->sa + (Y[j] - g->cy) * g->ca;
            pos += across > 0;
            neg += across < 0;
        }
    if (pos != 4 && neg != 4) return UNSUITED;
    g->side = pos == 4 ? 1 : -1;
    /* Bounds from a region's boundary, 128 samples per edge: the tile, or
     * the parent's polar box. */
    double rmin = INFINITY, rmax = 0, umin = INFINITY, umax = -INFINITY, tumin = INFINITY, tumax = -INFINITY;
    const int ns = 128;
    double step = 0;
    for (int pass = 0; pass < (parent ? 2 : 1); pass++) {
        for (int e = 0; e < 4; e++)
            for (int k = 0; k <= ns; k++) {
                double x, y, rho, u, f = (double)k / ns;
                if (pass == 0) {
                    x = e == 0 || e == 2 ? X[0] + f * (X[1] - X[0]) : e == 1 ? X[1] : X[0];
                    y = e == 1 || e == 3 ? Y[0] + f * (Y[1] - Y[0]) : e == 0 ? Y[0] : Y[1];
                } else {
                    double r0 = parent->rho0, r1 = parent->rho0 + (parent->nrho - 1) * parent->drho;
                    double u0 = parent->u0, u1 = parent->u0 + (parent->nu - 1) * parent->du;
                    if (u0 < -1) u0 = -1;
                    if (u1 > 1) u1 = 1;
                    double pr = e == 0 || e == 2 ? r0 + f * (r1 - r0) : e == 1 ? r1 : r0;
                    double pu = e == 1 || e == 3 ? u0 + f * (u1 - u0) : e == 0 ? u0 : u1;
                    polar_point(parent, pr, pu, &x, &y);
                }
                to_polar_any(g, x, y, &rho, &u);
                if (pass == 0) {
                    if (u < tumin) tumin = u;
                    if (u > tumax) tumax = u;
                }
                if (pass == 0 && parent) continue;
                if (rho < rmin) rmin = rho;
                if (rho > rmax) rmax = rho;
                if (u < umin) umin = u;
                if (u > umax) umax = u;
            }
        /* Between boundary samples: a sample's spacing of slack. */
        if (pass == 0) step = hypot(X[1] - X[0], Y[1] - Y[0]) / ns;
        else {
            double r1 = parent->rho0 + (parent->nrho - 1) * parent->drho;
            step = fmax(parent->drho * parent->nrho, r1 * parent->du * parent->nu) / ns;
        }
    }
    rmin -= step;
    rmax += step;
    if (!(rmin > step)) return UNSUITED;
    umin -= step / rmin;
    umax += step / rmin;
    double uabs = fmax(fabs(tumin), fabs(tumax)) + step / rmin;
    if (uabs > cx->umax) return UNSUITED;
    /* The spread of the bistatic delays about the reference 2 rho / c, as
     * a function of u: along-track offset sums s = t_u + r_u (first
     * order), across sums v (through sqrt(1 - u^2)), and the second-order
     * term (|t|^2 + |r|^2) / (2 rho), whose u-derivative is at most
     * (|t|^2 + |r|^2) / rho. */
    double seff = 0, sr = 0;
    for (int i = a; i < b; i++) {
        double tx, ty, rx, ry, th;
        item_sensors(cx, i, &tx, &ty, &rx, &ry, &th);
        double tu = (tx - g->cx) * g->ca + (ty - g->cy) * g->sa;
        double tv = -(tx - g->cx) * g->sa + (ty - g->cy) * g->ca;
        double ru = (rx - g->cx) * g->ca + (ry - g->cy) * g->sa;
        double rv = -(rx - g->cx) * g->sa + (ry - g->cy) * g->ca;
        double e = fabs(tu + ru) + fabs(tv + rv) * uabs / sqrt(1 - uabs * uabs) +
                   (tu * tu + tv * tv + ru * ru + rv * rv) / rmin;
        if (e > seff) seff = e;
        /* Along rho the residual delay changes as 1 - cos of the angles
         * between the sensors' rays and the centre's: at most
         * (|t|^2 + |r|^2) / (2 rho^2) (times c), with the heights' part. */
        double hh = max_height2(&run->array);
        double er = (tu * tu + tv * tv + ru * ru + rv * rv + hh) / (2 * rmin * rmin);
        if (er > sr) sr = er;
    }
    /* The beam patterns (sinc of D u / lambda for each aperture D) widen
     * the spectrum by (D_t + D_r) / lambda. */
    if (run->sys.beam_pattern) seff += 0.5 * (run->array.tx_length + run->array.rx_length);
    double c = run->sys.sound_speed, fmax_hz = run->sys.f0 + 0.5 * run->sys.bandwidth;
    double wu = 2.0 * fmax_hz / c * seff;
    /* rho: the pulse's band (2B / c) widened by the residual's drift. */
    g->drho = 1.0 / ((2.0 * run->sys.bandwidth / c + 2.0 * fmax_hz / c * sr) * cx->os);
    /* At least 4 intervals over the region (envelope). */
    double du_max = (umax - umin) / 4 + 1e-9;
    g->du = wu > 0 ? 1.0 / (wu * cx->os) : du_max;
    if (g->du > du_max) g->du = du_max;
    /* Widened by the interpolation's reach in this grid's samples (taps
     * floor(a) - HALF + 1 .. floor(a) + HALF). */
    rmin -= HALF * g->drho;
    rmax += HALF * g->drho;
    umin -= HALF * g->du;
    umax += HALF * g->du;
    if (!(rmin > 0)) return UNSUITED;
    double nr = ceil((rmax - rmin) / g->drho) + 1, nu = ceil((umax - umin) / g->du) + 1;
    if (nr * nu > (double)INT_MAX / 2) return UNSUITED;
    g->nrho = (int)nr;
    g->nu = (int)nu;
    g->rho0 = rmin;
    g->u0 = umin;
    return 0;
}

/* Where items [a, b) split in two: at a ping boundary, or within one
 * ping at a boundary of the leaves' channel groups. */
static int split(const ffbp_ctx *cx, int a, int b)
{
    int pa = a / cx->nrx, pb = b / cx->nrx;
    if (pb - pa >= 2) return (pa + (pb - pa) / 2) * cx->nrx;
    int base = pa * cx->nrx, ga = (a - base) / cx->group, gb = (b - base + cx->group - 1) / cx->group;
    int mid = base + (ga + (gb - ga) / 2) * cx->group;
    return mid < b ? mid : b;
}

static void step_done(ffbp_ctx *cx)
{
    ++*cx->step;
    if (cx->progress)
        cx->progress((int)(*cx->step < INT_MAX ? *cx->step : INT_MAX),
                     (int)(cx->steps < INT_MAX ? cx->steps : INT_MAX), cx->user);
}

/* The samples of the ping holding item i (read once per ping). */
static int item_ping(ffbp_ctx *cx, int i, const sasnav_cfloat **samples)
{
    int p = cx->pings[i / cx->nrx];
    if (cx->cur_ping != p) {
        cx->cur_ping = -1;
        int rc = sasnav_run_get_ping(cx->run, p, cx->ping_buf, &cx->cur);
        if (rc) return rc;
        cx->cur_ping = p;
    }
    *samples = cx->cur;
    return 0;
}

/* The demodulated polar image of pings [a, b) over the tile widened by
 * `margin`: *g and *out (allocated; free with free()). */
static int build_polar(ffbp_ctx *cx, int a, int b, const polar *parent, polar *g, sasnav_cfloat **out);

/* The demodulated polar image of items [a, b) on the grid g (node_geometry's). */
static int fill_polar(ffbp_ctx *cx, int a, int b, const polar *g, sasnav_cfloat **out)
{
    *out = NULL;
    int rc = 0;
    size_t n = (size_t)g->nrho * (size_t)g->nu;
    sasnav_cfloat *v = calloc(n, sizeof *v);
    if (!v) return sasnav_set_error(SASNAV_ERR_NOMEM, "FFBP: out of memory for a %d x %d polar image", g->nrho, g->nu);
    if (b - a <= cx->group) {
        /* A leaf: one group of channels of one ping (see split()),
         * exactly, by the adjoint operator on the leaf's polar samples. */
        double *x = malloc(sizeof(double) * n), *y = malloc(sizeof(double) * n);
        if (!x || !y) {
            free(x);
            free(y);
            free(v);
            return sasnav_set_error(SASNAV_ERR_NOMEM, "FFBP: out of memory for a leaf of %zu points", n);
        }
        for (int i = 0; i < g->nrho; i++)
            for (int j = 0; j < g->nu; j++) {
                size_t q = (size_t)i * (size_t)g->nu + (size_t)j;
                polar_point(g, g->rho0 + i * g->drho, g->u0 + j * g->du, &x[q], &y[q]);
            }
        const sasnav_cfloat *ping = NULL;
        int l0 = a % cx->nrx, gi = l0 / cx->group;
        sasnav_op **op = &cx->leaf_op[gi];
        if (!*op) {
            sasnav_array sub;
            int pick[SASNAV_MAX_RX];
            for (int l = 0; l < b - a; l++) pick[l] = l0 + l;
            rc = sasnav_array_select(&cx->run->array, pick, b - a, &sub);
            if (!rc) rc = sasnav_op_create(&cx->run->sys, &sub, &cx->run->win, (int)n, x, y, &cx->leaf_oo, op);
        } else {
            rc = sasnav_op_set_points(*op, (int)n, x, y);
        }
        free(x);
        free(y);
        if (!rc) rc = item_ping(cx, a, &ping);
        if (!rc)
            rc = sasnav_op_set_ping(*op, &cx->nav[cx->pings[a / cx->nrx]],
                                    cx->run->channel_offset ? cx->run->channel_offset + l0 : NULL);
        if (!rc) rc = sasnav_op_adjoint(*op, ping + (size_t)l0 * (size_t)cx->run->win.n_samples, v);
        if (rc) {
            free(v);
            return rc;
        }
        for (int i = 0; i < g->nrho; i++) {
            double rho = g->rho0 + i * g->drho;
            sasnav_cfloat rot = conjf(phasor(cx->k * sqrt(rho * rho + cx->h2)));
            for (int j = 0; j < g->nu; j++) v[(size_t)i * (size_t)g->nu + (size_t)j] *= rot;
        }
        if (b % cx->nrx == 0) step_done(cx);
        *out = v;
        return 0;
    }
    int mid = split(cx, a, b);
    for (int half = 0; half < 2 && !rc; half++) {
        polar gc;
        sasnav_cfloat *vc = NULL;
        rc = half == 0 ? build_polar(cx, a, mid, g, &gc, &vc) : build_polar(cx, mid, b, g, &gc, &vc);
        if (rc) break;
        const polar *G = g;
#pragma omp parallel for num_threads(cx->nthreads) schedule(static)
        for (int i = 0; i < G->nrho; i++) {
            double rho = G->rho0 + i * G->drho;
            double ref = sqrt(rho * rho + cx->h2);
            for (int j = 0; j < G->nu; j++) {
                double x, y, rc_, uc;
                polar_point(G, rho, G->u0 + j * G->du, &x, &y);
                if (!to_polar(&gc, x, y, &rc_, &uc)) continue;
                sasnav_cfloat val = interp(cx, &gc, vc, rc_, uc);
                if (val == 0) continue;
                v[(size_t)i * (size_t)G->nu + (size_t)j] += val * phasor(cx->k * (sqrt(rc_ * rc_ + cx->h2) - ref));
            }
        }
        free(vc);
    }
    if (rc) {
        free(v);
        return rc;
    }
    *out = v;
    return 0;
}

static int build_polar(ffbp_ctx *cx, int a, int b, const polar *parent, polar *g, sasnav_cfloat **out)
{
    *out = NULL;
    int rc = node_geometry(cx, a, b, parent, g);
    return rc ? rc : fill_polar(cx, a, b, g, out);
}

/* Items [a, b) by the direct operator on the tile's pixels (a ping's
 * other channels given zeros). */
static int direct(ffbp_ctx *cx, int a, int b)
{
    size_t ns = (size_t)cx->run->win.n_samples;
    if (!cx->tile_op) {
        size_t np = (size_t)cx->w * (size_t)cx->h;
        double *x = malloc(sizeof(double) * np), *y = malloc(sizeof(double) * np);
        if (!x || !y) {
            free(x);
            free(y);
            return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory for a tile of %zu pixels", np);
        }
        sasnav_bp_tile_points(cx->grid, cx->c0, cx->r0, cx->w, cx->h, x, y);
        int rc = sasnav_op_create(&cx->run->sys, &cx->run->array, &cx->run->win, (int)np, x, y, cx->oo,
                                  &cx->tile_op);
        free(x);
        free(y);
        if (rc) return rc;
    }
    int rc = 0;
    for (int i = a; i < b && !rc;) {
        int pi = i / cx->nrx, l0 = i % cx->nrx, l1 = cx->nrx;
        if ((pi + 1) * cx->nrx > b) l1 = b - pi * cx->nrx;
        const sasnav_cfloat *ping = NULL;
        rc = item_ping(cx, i, &ping);
        if (!rc && (l0 > 0 || l1 < cx->nrx)) {
            memset(cx->scratch, 0, sizeof *cx->scratch * ns * (size_t)cx->nrx);
            memcpy(cx->scratch + (size_t)l0 * ns, ping + (size_t)l0 * ns, sizeof *ping * ns * (size_t)(l1 - l0));
            ping = cx->scratch;
        }
        if (!rc) rc = sasnav_op_set_ping(cx->tile_op, &cx->nav[cx->pings[pi]], cx->run->channel_offset);
        if (!rc) rc = sasnav_op_adjoint_add(cx->tile_op, ping, cx->tile);
        if (!rc && l1 == cx->nrx) step_done(cx);
        i = pi * cx->nrx + l1;
    }
    return rc;
}

/* Adds pings [a, b) to the tile: through the largest polar images smaller
 * than the tile, or directly. */
static int accumulate(ffbp_ctx *cx, int a, int b);

/* Items [a, b) in two halves, or a single ping by the direct operator. */
static int accumulate_split(ffbp_ctx *cx, int a, int b)
{
    if (b - a <= cx->nrx) return direct(cx, a, b);
    int mid = split(cx, a, b);
    int rc = accumulate(cx, a, mid);
    return rc ? rc : accumulate(cx, mid, b);
}

static int accumulate(ffbp_ctx *cx, int a, int b)
{
    size_t npix = (size_t)cx->w * (size_t)cx->h;
    polar g;
    int rc = node_geometry(cx, a, b, NULL, &g);
    if (rc && rc != UNSUITED) return rc;
    if (rc == UNSUITED || (double)g.nrho * g.nu > (double)npix) return accumulate_split(cx, a, b);
    sasnav_cfloat *v = NULL;
    long step0 = *cx->step;
    rc = fill_polar(cx, a, b, &g, &v);
    if (rc == UNSUITED) {
        /* A level below did not suit: redo these pings split (the steps
         * already counted are counted again). */
        *cx->step = step0;
        return accumulate_split(cx, a, b);
    }
    if (rc) return rc;
#pragma omp parallel for num_threads(cx->nthreads) schedule(static)
    for (int iy = 0; iy < cx->h; iy++) {
        double y = cx->grid->y0 + (cx->r0 + iy) * cx->grid->dy;
        for (int ix = 0; ix < cx->w; ix++) {
            double x = cx->grid->x0 + (cx->c0 + ix) * cx->grid->dx, rho, u;
            if (!to_polar(&g, x, y, &rho, &u)) continue;
            sasnav_cfloat val = interp(cx, &g, v, rho, u);
            cx->tile[(size_t)iy * (size_t)cx->w + (size_t)ix] += val * phasor(cx->k * sqrt(rho * rho + cx->h2));
        }
    }
    free(v);
    return 0;
}

void sasnav_ffbp_default_opts(sasnav_ffbp_opts *opts)
{
    if (!opts) return;
    opts->oversampling = 2.0;
}

int sasnav_ffbp_tile(const sasnav_run *run, const sasnav_ping_pose *nav, const sasnav_grid *grid,
                     int col0, int col1, int row0, int row1, const sasnav_op_opts *opts,
                     const sasnav_ffbp_opts *fopts, sasnav_cfloat *image,
                     sasnav_ping_progress_fn progress, void *user)
{
    int rc = sasnav_bp_check_args(run, nav, grid, col0, col1, row0, row1, image);
    if (rc) return rc;
    sasnav_ffbp_opts fo;
    sasnav_ffbp_default_opts(&fo);
    if (fopts) fo = *fopts;
    if (!(fo.oversampling >= 1.25 && fo.oversampling <= 4))
        return sasnav_set_error(SASNAV_ERR_ARG, "FFBP oversampling must be within 1.25..4 (got %g)",
                                fo.oversampling);
    ffbp_ctx *cx = calloc(1, sizeof *cx);
    int *pings = malloc(sizeof(int) * (size_t)run->n_pings);
    if (!cx || !pings) {
        free(cx);
        free(pings);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    }
    cx->run = run;
    cx->nav = nav;
    cx->oo = opts;
    cx->grid = grid;
    cx->pings = pings;
    cx->os = fo.oversampling;
    cx->nrx = run->array.n_rx;
    cx->group = cx->nrx < LEAF_CHANNELS ? cx->nrx : LEAF_CHANNELS;
    if (opts)
        cx->leaf_oo = *opts;
    else
        sasnav_op_default_opts(&cx->leaf_oo);
    if (cx->leaf_oo.tolerance < LEAF_TOLERANCE) cx->leaf_oo.tolerance = LEAF_TOLERANCE;
    cx->cur_ping = -1;
    cx->umax = U_LIMIT;
    cx->k = 4.0 * M_PI * run->sys.f0 / run->sys.sound_speed;
    double hm = 0.5 * (run->array.tx_height + run->array.rx_height);
    cx->h2 = hm * hm;
    cx->nthreads = opts && opts->nthreads > 0 ? opts->nthreads : omp_get_max_threads();
    cx->progress = progress;
    cx->user = user;
    cx->wtab = malloc(sizeof(float) * (WSTEPS + 1) * TAPS);
    if (!cx->wtab) {
        free(cx);
        free(pings);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    }
    make_weights(cx->wtab, cx->os);
    /* The delays an operator keeps (the same for every operator of this
     * run and options). */
    double t_first = 0, t_last = 0;
    {
        double px = grid->x0, py = grid->y0;
        sasnav_op *probe = NULL;
        rc = sasnav_op_create(&run->sys, &run->array, &run->win, 1, &px, &py, opts, &probe);
        if (!rc) sasnav_op_delay_span(probe, &t_first, &t_last);
        sasnav_op_destroy(probe);
    }
    int tw, th;
    sasnav_bp_tile_size_pairs(run, SASNAV_FFBP_TILE_PAIRS, col1 - col0, row1 - row0, &tw, &th);
    long ntx = (col1 - col0 + tw - 1) / tw, nty = (row1 - row0 + th - 1) / th, step = 0;
    cx->step = &step;
    cx->steps = ntx * nty * run->n_pings;
    if (!rc) {
        cx->ping_buf = malloc(sizeof *cx->ping_buf * sasnav_run_ping_size(run));
        cx->scratch = malloc(sizeof *cx->scratch * sasnav_run_ping_size(run));
        if (!cx->ping_buf || !cx->scratch) rc = sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory for a ping");
    }
    size_t stride = (size_t)(col1 - col0);
    for (int r0 = row0; r0 < row1 && !rc; r0 += th)
        for (int c0 = col0; c0 < col1 && !rc; c0 += tw) {
            int r1 = r0 + th < row1 ? r0 + th : row1, c1 = c0 + tw < col1 ? c0 + tw : col1;
            cx->c0 = c0;
            cx->r0 = r0;
            cx->w = c1 - c0;
            cx->h = r1 - r0;
            cx->xa = grid->x0 + c0 * grid->dx;
            cx->xb = grid->x0 + (c1 - 1) * grid->dx;
            cx->ya = grid->y0 + r0 * grid->dy;
            cx->yb = grid->y0 + (r1 - 1) * grid->dy;
            int n = 0;
            for (int p = 0; p < run->n_pings; p++)
                if (sasnav_bp_ping_reaches(run, &nav[p], cx->xa, cx->xb, cx->ya, cx->yb, t_last)) pings[n++] = p;
            long base = step;
            cx->tile = calloc((size_t)cx->w * (size_t)cx->h, sizeof *cx->tile);
            if (!cx->tile) rc = sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory for a tile");
            if (!rc && n > 0) rc = accumulate(cx, 0, n * cx->nrx);
            sasnav_op_destroy(cx->tile_op);
            cx->tile_op = NULL;
            for (int iy = 0; iy < cx->h && !rc; iy++)
                memcpy(image + (size_t)(r0 - row0 + iy) * stride + (size_t)(c0 - col0),
                       cx->tile + (size_t)iy * (size_t)cx->w, sizeof *cx->tile * (size_t)cx->w);
            free(cx->tile);
            cx->tile = NULL;
            step = base + run->n_pings;
            if (!rc && progress)
                progress((int)(step < INT_MAX ? step : INT_MAX), (int)(cx->steps < INT_MAX ? cx->steps : INT_MAX), user);
        }
    for (int gi = 0; gi < SASNAV_MAX_RX; gi++) sasnav_op_destroy(cx->leaf_op[gi]);
    free(cx->ping_buf);
    free(cx->scratch);
    free(cx->wtab);
    free(pings);
    free(cx);
    return rc;
}
