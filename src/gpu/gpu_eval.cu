/* The estimator's error evaluation on a CUDA GPU (gpu_eval.h).
 *
 * The operator T of src/operators/op.c, step by step (per channel l):
 *   forward  spread (gather: each fine-grid sample sums the pairs whose
 *            kernel covers it, the pairs sorted by first fine index, in
 *            point order within an index) -> FFT_Lf -> band |k| <= K times
 *            the spectral weights into the coarse spectrum -> IFFT_Mp ->
 *            the window's samples;
 *   adjoint  zero-padded samples -> FFT_Mp -> weights into the fine
 *            spectrum -> IFFT_Lf -> interpolation per point over the
 *            channels -> conj(G).
 * CGLS (src/operators/cgls.c) keeps its scalars on the device (no host
 * round trip per iteration); the norms are summed in double, in a fixed
 * order. Every launch is checked; memory is plain cudaMalloc. */
#include <cub/cub.cuh>
#include <cuda_runtime.h>
#include <cufft.h>

#include <limits.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sasnav/error.h"
#include "gpu/gpu_eval.h"

/* The pair layout's block of points is 64 here (pair_of, k_spread, k_geometry). */
static_assert(OP_BLOCK == 64, "gpu_eval.cu assumes blocks of 64 points");

#define NRED 120  /* blocks of a norm's first pass (fixed: same sums every run) */
#define RTH 256   /* threads per block */

#define CK(call)                                                                          \
    do {                                                                                  \
        cudaError_t e_ = (call);                                                          \
        if (e_ != cudaSuccess)                                                            \
            return sasnav_set_error(SASNAV_ERR_INTERNAL, "GPU: %s failed: %s", #call,     \
                                    cudaGetErrorString(e_));                              \
    } while (0)
#define CKFFT(call)                                                                       \
    do {                                                                                  \
        cufftResult e_ = (call);                                                          \
        if (e_ != CUFFT_SUCCESS)                                                          \
            return sasnav_set_error(SASNAV_ERR_FFT, "GPU: %s failed (cuFFT error %d)", #call, \
                                    (int)e_);                                             \
    } while (0)
#define CKLAUNCH() CK(cudaGetLastError())

typedef struct {
    unsigned long serial; /* of the geometry held; 0: none */
    int32_t *index;
    float *taps;
    float2 *green;
    int *start; /* n_rx x (lf + 1): pairs of channel l with first index i at
                   order[l][start[l][i] .. start[l][i + 1]) */
    int *order; /* n_rx x n_points: pair numbers (point order within an index) */
} dev_op;

typedef struct {
    double gamma, gamma0;
    float alpha, beta;
    int stop;
} cgls_scalars;

typedef struct {
    cudaStream_t st;
    cufftHandle fine_plan, coarse_plan;
    int have_fine_plan, have_coarse_plan;
    float2 *fine, *coarse;     /* n_rx x lf, n_rx x mp */
    float2 *s, *p, *psi, *tmp; /* n_points */
    float2 *r, *q, *dtmp;      /* n_rx x n_samples */
    double *partial, *partial2;
    cgls_scalars *sc;
} chain_ws;

/* set_geometry's constants (op_geometry_consts without pointers). */
typedef struct {
    double inv_c, inv_h, two_f0, start, half, u_max, v_max;
    double att_exploding, att_spherical, att_none;
    int tap_degree;
} geom_consts;

#define N_GRAPHS 2
typedef struct {
    cudaGraphExec_t exec;
    int have, k, i;
    double lambda;
    unsigned long used; /* graph_clock at the last launch */
} eval_graph;

struct gpu_ctx {
    int np, n_rx, ns, pad, mp, lf, ext, wpad, kmax, n_blocks;
    /* Device-side geometry (gpu_set_points, gpu_place). */
    int have_points, points_ready; /* have_points: set_points succeeded;
                                      points_ready: its buffers exist */
    geom_consts gk;
    double *px, *py;
    float *tap_coef;
    op_channel_geometry *chan;
    int *keys_in, *keys_out, *vals_in, *counts, *sums, *near;
    int *h_near; /* pinned */
    void *sort_temp;
    size_t sort_bytes;
    size_t n_pairs, nd;
    float *spectral;
    dev_op op[2];
    chain_ws ws[2];
    float2 *rho_q, *data_q;
    /* Pinned host staging of gpu_eval's transfers (data_q, rho_p in; rho_q,
     * psi_p, psi_q out): copies from pageable memory go through the
     * driver's own staging, which serialises concurrent estimators. */
    float2 *h_in, *h_out;
    int *h_start, *h_order, *h_cursor;
    cudaEvent_t ev, ev_join;
    int have_ev, have_ev_join;
    /* The evaluation as one CUDA graph (captured at the first evaluation
     * of a (k, i, lambda); replayed after: one launch instead of ~4,700).
     * Two are kept (levels 1 and 2 share a context and alternate); a third
     * (k, i, lambda) replaces the one used least recently. */
    eval_graph graphs[N_GRAPHS];
    unsigned long graph_clock;
    int no_graph;
    char name[256];
};

static void free_points(gpu_ctx *g);

/* ------------------------------------------------------------------------ */
/* Kernels. */

__device__ __forceinline__ size_t pair_of(int n, int l, int n_rx)
{
    return ((size_t)(n / 64) * (size_t)n_rx + (size_t)l) * 64 + (size_t)(n % 64);
}

/* fine[l][j] = sum over the pairs covering j (and j + lf, the periodic
 * extension) of taps * G * rho. One warp per fine-grid sample: the pairs
 * whose first index lies in [pos - wpad + 1, pos] are contiguous in the
 * channel's sorted list; each lane sums every 32nd of them, then the lanes
 * are summed by a fixed shuffle tree (the same order every run). Block:
 * SPREAD_WARPS warps; grid (ceil(lf / SPREAD_WARPS), n_rx). */
#define SPREAD_WARPS 8
__global__ void k_spread(int np, int n_rx, int lf, int ext, int wpad, const int *start,
                         const int *order, const int32_t *index, const float *taps,
                         const float2 *green, const float2 *rho, float2 *fine)
{
    int lane = threadIdx.x & 31, wid = threadIdx.x >> 5;
    int j = blockIdx.x * SPREAD_WARPS + wid, l = blockIdx.y;
    if (j >= lf) return; /* uniform over the warp */
    const int *st = start + (size_t)l * (size_t)(lf + 1);
    const int *ord = order + (size_t)l * (size_t)np;
    int per_block = 64 * n_rx;
    float ar = 0.0f, ai = 0.0f;
    for (int w = 0; w < 2; w++) {
        if (w == 1 && j >= ext) break;
        int pos = w == 0 ? j : j + lf;
        int lo = pos - wpad + 1, hi = pos;
        if (lo < 0) lo = 0;
        if (hi > lf - 1) hi = lf - 1;
        if (lo > hi) continue;
        int e1 = st[hi + 1];
        for (int e = st[lo] + lane; e < e1; e += 32) {
            int q = ord[e];
            int n = (q / per_block) * 64 + (q & 63);
            float t = taps[(size_t)q * (size_t)wpad + (size_t)(pos - index[q])];
            float2 g = green[q], x = rho[n];
            float cr = g.x * x.x - g.y * x.y, ci = g.x * x.y + g.y * x.x;
            ar += t * cr;
            ai += t * ci;
        }
    }
    for (int off = 16; off > 0; off >>= 1) {
        ar += __shfl_down_sync(0xffffffffu, ar, off);
        ai += __shfl_down_sync(0xffffffffu, ai, off);
    }
    if (lane == 0) fine[(size_t)l * lf + j] = make_float2(ar, ai);
}

/* coarse[l][kc] = spectral * fine[l][kf] in the band, 0 elsewhere. */
__global__ void k_fine_to_coarse(int lf, int mp, int kmax, const float *spectral,
                                 const float2 *fine, float2 *coarse)
{
    int kc = blockIdx.x * blockDim.x + threadIdx.x, l = blockIdx.y;
    if (kc >= mp) return;
    float2 v = make_float2(0.0f, 0.0f);
    int k = kc <= kmax ? kc : kc >= mp - kmax ? kc - mp : INT_MIN;
    if (k != INT_MIN) {
        int kf = k < 0 ? k + lf : k;
        float r = spectral[k + kmax];
        float2 f = fine[(size_t)l * lf + kf];
        v = make_float2(r * f.x, r * f.y);
    }
    coarse[(size_t)l * mp + kc] = v;
}

/* fine[l][kf] = spectral * coarse[l][kc] in the band, 0 elsewhere. */
__global__ void k_coarse_to_fine(int lf, int mp, int kmax, const float *spectral,
                                 const float2 *coarse, float2 *fine)
{
    int kf = blockIdx.x * blockDim.x + threadIdx.x, l = blockIdx.y;
    if (kf >= lf) return;
    float2 v = make_float2(0.0f, 0.0f);
    int k = kf <= kmax ? kf : kf >= lf - kmax ? kf - lf : INT_MIN;
    if (k != INT_MIN) {
        int kc = k < 0 ? k + mp : k;
        float r = spectral[k + kmax];
        float2 c = coarse[(size_t)l * mp + kc];
        v = make_float2(r * c.x, r * c.y);
    }
    fine[(size_t)l * lf + kf] = v;
}

__global__ void k_crop(int mp, int pad, int ns, const float2 *coarse, float2 *data)
{
    int m = blockIdx.x * blockDim.x + threadIdx.x, l = blockIdx.y;
    if (m >= ns) return;
    data[(size_t)l * ns + m] = coarse[(size_t)l * mp + pad + m];
}

__global__ void k_pad(int mp, int pad, int ns, const float2 *data, float2 *coarse)
{
    int m = blockIdx.x * blockDim.x + threadIdx.x, l = blockIdx.y;
    if (m >= mp) return;
    int s = m - pad;
    coarse[(size_t)l * mp + m] = s >= 0 && s < ns ? data[(size_t)l * ns + s] : make_float2(0.0f, 0.0f);
}

/* rho[n] = sum_l conj(G_ln) sum_j taps_j fine_l[index + j]. Block: 32
 * points (lanes: consecutive pairs of a channel, coalesced) x INTERP_WARPS
 * warps (warp w: channels w, w + INTERP_WARPS, ...); the warps' sums are
 * added in warp order. Grid: ceil(np / 32). */
#define INTERP_WARPS 16
__global__ void k_interp(int np, int n_rx, int lf, int wpad, const int32_t *index,
                         const float *taps, const float2 *green, const float2 *fine, float2 *rho)
{
    __shared__ float2 part[INTERP_WARPS][32];
    int lane = threadIdx.x & 31, wid = threadIdx.x >> 5;
    int n = blockIdx.x * 32 + lane;
    float ar = 0.0f, ai = 0.0f;
    if (n < np) {
        for (int l = wid; l < n_rx; l += INTERP_WARPS) {
            size_t q = pair_of(n, l, n_rx);
            int i0 = index[q];
            const float *t = taps + q * (size_t)wpad;
            const float2 *f = fine + (size_t)l * lf;
            float sr = 0.0f, si = 0.0f;
            for (int j = 0; j < wpad; j++) {
                int pos = i0 + j;
                if (pos >= lf) pos -= lf;
                float2 v = f[pos];
                sr += t[j] * v.x;
                si += t[j] * v.y;
            }
            float2 g = green[q];
            ar += g.x * sr + g.y * si;
            ai += g.x * si - g.y * sr;
        }
    }
    part[wid][lane] = make_float2(ar, ai);
    __syncthreads();
    if (wid == 0 && n < np) {
        float sr = 0.0f, si = 0.0f;
        for (int w = 0; w < INTERP_WARPS; w++) {
            sr += part[w][lane].x;
            si += part[w][lane].y;
        }
        rho[n] = make_float2(sr, si);
    }
}

/* sin(pi a) / (pi a), 1 near a = 0 (op.c's sinc_pi). */
__device__ __forceinline__ double sinc_pi_dev(double a)
{
    double s, c;
    sincospi(a, &s, &c);
    double pa = 3.141592653589793 * a;
    return fabs(pa) < 1e-8 ? 1.0 : s / pa;
}

/* The pairs of point n and channel l from the channel's geometry: op.c's
 * setup_tx and setup_block, the same formulas in double (taps by Horner in
 * float, as taps_W), and the sort keys of the spread's lists: key l (lf + 1)
 * + first index, value the pair number; counts[l (lf + 1) + index + 1] += 1.
 * Grid: (ceil(np / RTH), n_rx). */
__global__ void k_geometry(int np, int n_rx, int lf, int wpad, geom_consts k, const double *px,
                           const double *py, const op_channel_geometry *chan,
                           const float *coef, int32_t *index, float *taps, float2 *green, int *keys,
                           int *vals, int *counts, int *near)
{
    int n = blockIdx.x * blockDim.x + threadIdx.x, l = blockIdx.y;
    if (n >= np) return;
    const op_channel_geometry g = chan[l];
    const double min2 = 1e-18; /* op.c's MIN_SENSOR_DISTANCE squared */
    double x = px[n], y = py[n];
    double dxt = x - g.tx_x, dyt = y - g.tx_y;
    double r2t = dxt * dxt + dyt * dyt + g.tx_height * g.tx_height;
    int bad = !(r2t >= min2);
    double r_t = sqrt(r2t);
    double gain_tx = sinc_pi_dev(g.tx_aperture * (dxt * g.tx_cos + dyt * g.tx_sin) / (r_t + 1e-300));
    double xr = g.ar_x + g.rx_u * g.ar_cos, yr = g.ar_y + g.rx_u * g.ar_sin;
    double dx = x - xr, dy = y - yr;
    double r2 = dx * dx + dy * dy + g.rx_height * g.rx_height;
    bad |= !(r2 >= min2);
    double r_r = sqrt(r2), r_safe = r_r + 1e-300;
    double tau = (r_t + r_r) * k.inv_c;
    double u = (tau - k.start) * k.inv_h;
    int in = (u >= k.half) && (u <= k.u_max);
    double v = u - k.half;
    v = v > 0.0 ? v : 0.0;
    v = v < k.v_max ? v : k.v_max;
    double i0 = (double)(int)v;
    i0 += i0 < v ? 1.0 : 0.0;
    int idx = in ? (int)i0 : 0;
    float t = (float)(2.0 * (i0 - v) - 1.0), keep = in ? 1.0f : 0.0f;
    double pattern = sinc_pi_dev(g.rx_aperture * (dx * g.ar_cos + dy * g.ar_sin) / r_safe);
    double loss = k.att_exploding / sqrt(r_t + r_safe) + k.att_spherical / (r_t * r_safe) + k.att_none;
    double alpha = in ? gain_tx * pattern * loss : 0.0;
    double cycles = in ? k.two_f0 * tau : 0.0;
    double sn, cs;
    sincospi(cycles, &sn, &cs);
    size_t q = pair_of(n, l, n_rx);
    index[q] = idx;
    green[q] = make_float2((float)(alpha * cs), (float)(-alpha * sn));
    for (int j = 0; j < wpad; j++) {
        float acc = coef[k.tap_degree * wpad + j];
        for (int d = k.tap_degree - 1; d >= 0; d--) acc = acc * t + coef[d * wpad + j];
        taps[q * (size_t)wpad + j] = acc * keep;
    }
    keys[(size_t)l * np + n] = l * (lf + 1) + idx;
    vals[(size_t)l * np + n] = (int)q;
    atomicAdd(&counts[(size_t)l * (lf + 1) + idx + 1], 1);
    if (bad) atomicOr(near, 1);
}

/* start[l][i] = (inclusive sum of the counts up to (l, i)) - l np. */
__global__ void k_starts(int n, int lf, int np, const int *sums, int *start)
{
    int i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= n) return;
    start[i] = sums[i] - (i / (lf + 1)) * np;
}

/* First pass of ||v||^2: NRED partial sums in double. */
__global__ void k_norm2(const float2 *v, size_t n, double *partial)
{
    __shared__ double sh[RTH];
    double s = 0.0;
    for (size_t i = (size_t)blockIdx.x * RTH + threadIdx.x; i < n; i += (size_t)NRED * RTH) {
        double a = v[i].x, b = v[i].y;
        s += a * a + b * b;
    }
    sh[threadIdx.x] = s;
    __syncthreads();
    for (int w = RTH / 2; w > 0; w >>= 1) {
        if (threadIdx.x < w) sh[threadIdx.x] += sh[threadIdx.x + w];
        __syncthreads();
    }
    if (threadIdx.x == 0) partial[blockIdx.x] = sh[0];
}

__device__ double sum_partial(const double *p)
{
    double s = 0.0;
    for (int i = 0; i < NRED; i++) s += p[i];
    return s;
}

__global__ void k_cgls_init(const double *partial, cgls_scalars *sc)
{
    sc->gamma = sc->gamma0 = sum_partial(partial);
    sc->alpha = sc->beta = 0.0f;
    sc->stop = 0;
}

/* alpha = gamma / delta, delta = ||T p||^2 + lambda ||p||^2; stops (alpha =
 * 0 and no further update) where sasnav_cgls breaks off. */
__global__ void k_cgls_alpha(const double *partial_q, const double *partial_p, double lambda,
                             cgls_scalars *sc)
{
    double delta = sum_partial(partial_q);
    if (partial_p) delta += lambda * sum_partial(partial_p);
    if (sc->stop || !(sc->gamma > 1e-12 * sc->gamma0) || !(delta > 0.0)) {
        sc->stop = 1;
        sc->alpha = 0.0f;
    } else {
        sc->alpha = (float)(sc->gamma / delta);
    }
}

__global__ void k_cgls_beta(const double *partial, cgls_scalars *sc)
{
    if (sc->stop) return;
    double gnew = sum_partial(partial);
    sc->beta = (float)(gnew / sc->gamma);
    sc->gamma = gnew;
}

/* y += sign alpha x (sign +1 or -1), skipped once stopped. */
__global__ void k_axpy(float2 *y, const float2 *x, size_t n, float sign, const cgls_scalars *sc)
{
    if (sc->stop) return;
    size_t i = (size_t)blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= n) return;
    float a = sign * sc->alpha;
    y[i].x += a * x[i].x;
    y[i].y += a * x[i].y;
}

/* p = s + beta p, skipped once stopped. */
__global__ void k_update_p(float2 *p, const float2 *s, size_t n, const cgls_scalars *sc)
{
    if (sc->stop) return;
    size_t i = (size_t)blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= n) return;
    float b = sc->beta;
    p[i].x = s[i].x + b * p[i].x;
    p[i].y = s[i].y + b * p[i].y;
}

/* s -= lambda x (Tikhonov), skipped once stopped. */
__global__ void k_sub_scaled(float2 *s, const float2 *x, size_t n, float lambda,
                             const cgls_scalars *sc)
{
    if (sc->stop) return;
    size_t i = (size_t)blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= n) return;
    s[i].x -= lambda * x[i].x;
    s[i].y -= lambda * x[i].y;
}

/* ------------------------------------------------------------------------ */
/* Operator applications and CGLS on a chain's stream (device arrays). */

static unsigned blocks_of(size_t n) { return (unsigned)((n + RTH - 1) / RTH); }

static int forward(gpu_ctx *g, int which, chain_ws *w, const float2 *x, float2 *out)
{
    const dev_op *o = &g->op[which];
    k_spread<<<dim3((unsigned)((g->lf + SPREAD_WARPS - 1) / SPREAD_WARPS), g->n_rx), 32 * SPREAD_WARPS, 0,
               w->st>>>(g->np, g->n_rx, g->lf, g->ext, g->wpad, o->start, o->order, o->index, o->taps,
                        o->green, x, w->fine);
    CKLAUNCH();
    CKFFT(cufftExecC2C(w->fine_plan, (cufftComplex *)w->fine, (cufftComplex *)w->fine, CUFFT_FORWARD));
    k_fine_to_coarse<<<dim3(blocks_of((size_t)g->mp), g->n_rx), RTH, 0, w->st>>>(
        g->lf, g->mp, g->kmax, g->spectral, w->fine, w->coarse);
    CKLAUNCH();
    CKFFT(cufftExecC2C(w->coarse_plan, (cufftComplex *)w->coarse, (cufftComplex *)w->coarse,
                       CUFFT_INVERSE));
    k_crop<<<dim3(blocks_of((size_t)g->ns), g->n_rx), RTH, 0, w->st>>>(g->mp, g->pad, g->ns,
                                                                        w->coarse, out);
    CKLAUNCH();
    return SASNAV_OK;
}

static int adjoint(gpu_ctx *g, int which, chain_ws *w, const float2 *d, float2 *out)
{
    const dev_op *o = &g->op[which];
    k_pad<<<dim3(blocks_of((size_t)g->mp), g->n_rx), RTH, 0, w->st>>>(g->mp, g->pad, g->ns, d,
                                                                       w->coarse);
    CKLAUNCH();
    CKFFT(cufftExecC2C(w->coarse_plan, (cufftComplex *)w->coarse, (cufftComplex *)w->coarse,
                       CUFFT_FORWARD));
    k_coarse_to_fine<<<dim3(blocks_of((size_t)g->lf), g->n_rx), RTH, 0, w->st>>>(
        g->lf, g->mp, g->kmax, g->spectral, w->coarse, w->fine);
    CKLAUNCH();
    CKFFT(cufftExecC2C(w->fine_plan, (cufftComplex *)w->fine, (cufftComplex *)w->fine, CUFFT_INVERSE));
    k_interp<<<(unsigned)((g->np + 31) / 32), 32 * INTERP_WARPS, 0, w->st>>>(
        g->np, g->n_rx, g->lf, g->wpad, o->index, o->taps, o->green, w->fine, out);
    CKLAUNCH();
    return SASNAV_OK;
}

static int norm2(chain_ws *w, const float2 *v, size_t n, double *partial)
{
    k_norm2<<<NRED, RTH, 0, w->st>>>(v, n, partial);
    CKLAUNCH();
    return SASNAV_OK;
}

/* x = T^+ d by k iterations (sasnav_cgls, same recurrences). */
static int cgls(gpu_ctx *g, int which, chain_ws *w, const float2 *d, int k, double tikhonov,
                float2 *x)
{
    size_t np = (size_t)g->np, nd = g->nd;
    int rc;
    CK(cudaMemsetAsync(x, 0, np * sizeof(float2), w->st));
    if (k == 0) return SASNAV_OK;
    CK(cudaMemcpyAsync(w->r, d, nd * sizeof(float2), cudaMemcpyDeviceToDevice, w->st));
    if ((rc = adjoint(g, which, w, w->r, w->s))) return rc;
    CK(cudaMemcpyAsync(w->p, w->s, np * sizeof(float2), cudaMemcpyDeviceToDevice, w->st));
    if ((rc = norm2(w, w->s, np, w->partial))) return rc;
    k_cgls_init<<<1, 1, 0, w->st>>>(w->partial, w->sc);
    CKLAUNCH();
    for (int it = 0; it < k; it++) {
        if ((rc = forward(g, which, w, w->p, w->q))) return rc;
        if ((rc = norm2(w, w->q, nd, w->partial))) return rc;
        if (tikhonov > 0 && (rc = norm2(w, w->p, np, w->partial2))) return rc;
        k_cgls_alpha<<<1, 1, 0, w->st>>>(w->partial, tikhonov > 0 ? w->partial2 : NULL, tikhonov,
                                         w->sc);
        CKLAUNCH();
        k_axpy<<<blocks_of(np), RTH, 0, w->st>>>(x, w->p, np, 1.0f, w->sc);
        CKLAUNCH();
        if (it == k - 1) break; /* the next direction would not be used */
        k_axpy<<<blocks_of(nd), RTH, 0, w->st>>>(w->r, w->q, nd, -1.0f, w->sc);
        CKLAUNCH();
        if ((rc = adjoint(g, which, w, w->r, w->s))) return rc;
        if (tikhonov > 0) {
            k_sub_scaled<<<blocks_of(np), RTH, 0, w->st>>>(w->s, x, np, (float)tikhonov, w->sc);
            CKLAUNCH();
        }
        if ((rc = norm2(w, w->s, np, w->partial))) return rc;
        k_cgls_beta<<<1, 1, 0, w->st>>>(w->partial, w->sc);
        CKLAUNCH();
        k_update_p<<<blocks_of(np), RTH, 0, w->st>>>(w->p, w->s, np, w->sc);
        CKLAUNCH();
    }
    return SASNAV_OK;
}

/* out = Q x = T^+ (T x). */
static int project(gpu_ctx *g, int which, chain_ws *w, const float2 *x, float2 *out, int k,
                   double tikhonov)
{
    int rc = forward(g, which, w, x, w->dtmp);
    if (rc) return rc;
    return cgls(g, which, w, w->dtmp, k, tikhonov, out);
}

/* ------------------------------------------------------------------------ */
/* Context. */

static int use_graphs = 1; /* gpu_use_graphs */

extern "C" void gpu_use_graphs(int on) { use_graphs = on != 0; }

static void free_op(dev_op *o)
{
    cudaFree(o->index);
    cudaFree(o->taps);
    cudaFree(o->green);
    cudaFree(o->start);
    cudaFree(o->order);
    memset(o, 0, sizeof *o);
}

static void free_ws(chain_ws *w)
{
    if (w->have_fine_plan) cufftDestroy(w->fine_plan);
    if (w->have_coarse_plan) cufftDestroy(w->coarse_plan);
    if (w->st) cudaStreamDestroy(w->st);
    cudaFree(w->fine);
    cudaFree(w->coarse);
    cudaFree(w->s);
    cudaFree(w->p);
    cudaFree(w->psi);
    cudaFree(w->tmp);
    cudaFree(w->r);
    cudaFree(w->q);
    cudaFree(w->dtmp);
    cudaFree(w->partial);
    cudaFree(w->partial2);
    cudaFree(w->sc);
    memset(w, 0, sizeof *w);
}

extern "C" void gpu_destroy(gpu_ctx *g)
{
    if (!g) return;
    for (int c = 0; c < 2; c++) {
        free_op(&g->op[c]);
        free_ws(&g->ws[c]);
    }
    free_points(g);
    cudaFree(g->tap_coef);
    cudaFree(g->spectral);
    cudaFree(g->rho_q);
    if (g->h_in) cudaFreeHost(g->h_in);
    if (g->h_out) cudaFreeHost(g->h_out);
    cudaFree(g->data_q);
    for (int j = 0; j < N_GRAPHS; j++)
        if (g->graphs[j].have) cudaGraphExecDestroy(g->graphs[j].exec);
    if (g->have_ev) cudaEventDestroy(g->ev);
    if (g->have_ev_join) cudaEventDestroy(g->ev_join);
    free(g->h_start);
    free(g->h_order);
    free(g->h_cursor);
    free(g);
}

static int make_ws(gpu_ctx *g, chain_ws *w)
{
    size_t np = (size_t)g->np, nd = g->nd;
    /* Non-blocking: no implicit synchronisation with the legacy default
     * stream, which another thread may use while a graph is captured here. */
    CK(cudaStreamCreateWithFlags(&w->st, cudaStreamNonBlocking));
    int n_lf = g->lf, n_mp = g->mp;
    CKFFT(cufftPlanMany(&w->fine_plan, 1, &n_lf, NULL, 1, g->lf, NULL, 1, g->lf, CUFFT_C2C, g->n_rx));
    w->have_fine_plan = 1;
    CKFFT(cufftPlanMany(&w->coarse_plan, 1, &n_mp, NULL, 1, g->mp, NULL, 1, g->mp, CUFFT_C2C, g->n_rx));
    w->have_coarse_plan = 1;
    CKFFT(cufftSetStream(w->fine_plan, w->st));
    CKFFT(cufftSetStream(w->coarse_plan, w->st));
    CK(cudaMalloc((void **)&w->fine, (size_t)g->n_rx * g->lf * sizeof(float2)));
    CK(cudaMalloc((void **)&w->coarse, (size_t)g->n_rx * g->mp * sizeof(float2)));
    CK(cudaMalloc((void **)&w->s, np * sizeof(float2)));
    CK(cudaMalloc((void **)&w->p, np * sizeof(float2)));
    CK(cudaMalloc((void **)&w->psi, np * sizeof(float2)));
    CK(cudaMalloc((void **)&w->tmp, np * sizeof(float2)));
    CK(cudaMalloc((void **)&w->r, nd * sizeof(float2)));
    CK(cudaMalloc((void **)&w->q, nd * sizeof(float2)));
    CK(cudaMalloc((void **)&w->dtmp, nd * sizeof(float2)));
    CK(cudaMalloc((void **)&w->partial, NRED * sizeof(double)));
    CK(cudaMalloc((void **)&w->partial2, NRED * sizeof(double)));
    CK(cudaMalloc((void **)&w->sc, sizeof(cgls_scalars)));
    return SASNAV_OK;
}

__global__ void k_probe(void) {}

extern "C" int gpu_check_device(void)
{
    int count = 0;
    cudaError_t e = cudaGetDeviceCount(&count);
    if (e != cudaSuccess || count < 1) {
        cudaGetLastError(); /* clear the error state */
        return sasnav_set_error(SASNAV_ERR_UNSUPPORTED, "GPU: no usable CUDA device (%s)",
                                e != cudaSuccess ? cudaGetErrorString(e) : "none found");
    }
    /* code for this device's architecture? (a build for compute capability
     * 9.0 only cannot launch on an older GPU: CMAKE_CUDA_ARCHITECTURES) */
    k_probe<<<1, 1>>>();
    e = cudaGetLastError();
    if (e != cudaSuccess) {
        int dev = 0, major = 0, minor = 0;
        cudaGetDevice(&dev);
        cudaDeviceGetAttribute(&major, cudaDevAttrComputeCapabilityMajor, dev);
        cudaDeviceGetAttribute(&minor, cudaDevAttrComputeCapabilityMinor, dev);
        return sasnav_set_error(SASNAV_ERR_UNSUPPORTED,
                                "GPU: cannot run on device %d (compute capability %d.%d): %s; "
                                "configure with -DCMAKE_CUDA_ARCHITECTURES for it",
                                dev, major, minor, cudaGetErrorString(e));
    }
    return SASNAV_OK;
}

static int create(const op_view *v, gpu_ctx *g)
{
    int rc = gpu_check_device();
    if (rc) return rc;
    cudaDeviceProp prop;
    CK(cudaGetDeviceProperties(&prop, 0));
    snprintf(g->name, sizeof g->name, "%s", prop.name);
    g->np = v->n_points;
    g->n_rx = v->n_rx;
    g->ns = v->n_samples;
    g->pad = v->pad;
    g->mp = v->mp;
    g->lf = v->lf;
    g->ext = v->ext;
    g->wpad = v->wpad;
    g->kmax = v->kmax;
    g->n_blocks = v->n_blocks;
    g->n_pairs = v->n_pairs;
    g->nd = (size_t)v->n_rx * (size_t)v->n_samples;
    if (2 * g->kmax + 1 > g->mp || g->ext > g->lf || g->pad + g->ns > g->mp || g->n_pairs > INT_MAX ||
        (size_t)g->n_rx * (size_t)(g->lf + 1) > INT_MAX || (size_t)g->n_rx * (size_t)g->np > INT_MAX)
        return sasnav_set_error(SASNAV_ERR_UNSUPPORTED, "GPU: operator grids out of range");
    CK(cudaMalloc((void **)&g->spectral, (2 * (size_t)g->kmax + 1) * sizeof(float)));
    g->no_graph = !use_graphs;
    CK(cudaMalloc((void **)&g->rho_q, (size_t)g->np * sizeof(float2)));
    CK(cudaMallocHost((void **)&g->h_in, (g->nd + (size_t)g->np) * sizeof(float2)));
    CK(cudaMallocHost((void **)&g->h_out, 3 * (size_t)g->np * sizeof(float2)));
    CK(cudaMalloc((void **)&g->data_q, g->nd * sizeof(float2)));
    CK(cudaEventCreateWithFlags(&g->ev, cudaEventDisableTiming));
    g->have_ev = 1;
    CK(cudaEventCreateWithFlags(&g->ev_join, cudaEventDisableTiming));
    g->have_ev_join = 1;
    g->h_start = (int *)malloc((size_t)g->n_rx * (size_t)(g->lf + 1) * sizeof(int));
    g->h_order = (int *)malloc((size_t)g->n_rx * (size_t)g->np * sizeof(int));
    g->h_cursor = (int *)malloc((size_t)(g->lf + 1) * sizeof(int));
    if (!g->h_start || !g->h_order || !g->h_cursor)
        return sasnav_set_error(SASNAV_ERR_NOMEM, "GPU: out of memory (host staging)");
    for (int c = 0; c < 2; c++) {
        dev_op *o = &g->op[c];
        CK(cudaMalloc((void **)&o->index, g->n_pairs * sizeof(int32_t)));
        CK(cudaMalloc((void **)&o->taps, g->n_pairs * (size_t)g->wpad * sizeof(float)));
        CK(cudaMalloc((void **)&o->green, g->n_pairs * sizeof(float2)));
        CK(cudaMalloc((void **)&o->start, (size_t)g->n_rx * (size_t)(g->lf + 1) * sizeof(int)));
        CK(cudaMalloc((void **)&o->order, (size_t)g->n_rx * (size_t)g->np * sizeof(int)));
        int rc = make_ws(g, &g->ws[c]);
        if (rc) return rc;
    }
    /* on a work stream (non-blocking: they would not wait for the legacy
     * stream), synchronised */
    CK(cudaMemcpyAsync(g->spectral, v->spectral, (2 * (size_t)g->kmax + 1) * sizeof(float),
                       cudaMemcpyHostToDevice, g->ws[0].st));
    CK(cudaStreamSynchronize(g->ws[0].st));
    return SASNAV_OK;
}

extern "C" int gpu_create(const op_view *shape, gpu_ctx **out)
{
    if (!shape || !out) return sasnav_set_error(SASNAV_ERR_ARG, "GPU: NULL argument");
    *out = NULL;
    gpu_ctx *g = (gpu_ctx *)calloc(1, sizeof *g);
    if (!g) return sasnav_set_error(SASNAV_ERR_NOMEM, "GPU: out of memory");
    int rc = create(shape, g);
    if (rc) {
        gpu_destroy(g);
        return rc;
    }
    *out = g;
    return SASNAV_OK;
}

static int same_shape(const gpu_ctx *g, const op_view *v)
{
    return v->n_points == g->np && v->n_rx == g->n_rx && v->n_samples == g->ns && v->pad == g->pad &&
           v->mp == g->mp && v->lf == g->lf && v->ext == g->ext && v->wpad == g->wpad &&
           v->kmax == g->kmax && v->n_pairs == g->n_pairs;
}

extern "C" int gpu_fits(const gpu_ctx *g, const op_view *v) { return g && v && same_shape(g, v); }

extern "C" int gpu_set_op(gpu_ctx *g, int which, const op_view *v)
{
    if (!g || !v || which < 0 || which > 1) return sasnav_set_error(SASNAV_ERR_ARG, "GPU: bad set_op arguments");
    if (!same_shape(g, v)) return sasnav_set_error(SASNAV_ERR_ARG, "GPU: operator of another shape");
    dev_op *o = &g->op[which];
    if (v->serial != 0 && o->serial == v->serial) return SASNAV_OK;
    o->serial = 0;
    /* Pairs of each channel sorted by first fine index (counting sort,
     * stable: point order within an index). Indices lie in [0, lf - w]. */
    int lf = g->lf, np = g->np, n_rx = g->n_rx;
    for (int l = 0; l < n_rx; l++) {
        int *st = g->h_start + (size_t)l * (size_t)(lf + 1);
        int *ord = g->h_order + (size_t)l * (size_t)np;
        memset(st, 0, (size_t)(lf + 1) * sizeof(int));
        for (int n = 0; n < np; n++) {
            size_t q = ((size_t)(n / 64) * (size_t)n_rx + (size_t)l) * 64 + (size_t)(n % 64);
            int idx = v->index[q];
            if (idx < 0 || idx >= lf) return sasnav_set_error(SASNAV_ERR_INTERNAL, "GPU: fine index out of range");
            st[idx + 1]++;
        }
        for (int i = 1; i <= lf; i++) st[i] += st[i - 1];
        memcpy(g->h_cursor, st, (size_t)(lf + 1) * sizeof(int));
        for (int n = 0; n < np; n++) {
            size_t q = ((size_t)(n / 64) * (size_t)n_rx + (size_t)l) * 64 + (size_t)(n % 64);
            ord[g->h_cursor[v->index[q]]++] = (int)q;
        }
    }
    cudaStream_t st = g->ws[0].st; /* (both streams are idle between calls) */
    CK(cudaMemcpyAsync(o->index, v->index, g->n_pairs * sizeof(int32_t), cudaMemcpyHostToDevice, st));
    CK(cudaMemcpyAsync(o->taps, v->taps, g->n_pairs * (size_t)g->wpad * sizeof(float),
                       cudaMemcpyHostToDevice, st));
    CK(cudaMemcpyAsync(o->green, v->green, g->n_pairs * sizeof(float2), cudaMemcpyHostToDevice, st));
    CK(cudaMemcpyAsync(o->start, g->h_start, (size_t)n_rx * (size_t)(lf + 1) * sizeof(int),
                       cudaMemcpyHostToDevice, st));
    CK(cudaMemcpyAsync(o->order, g->h_order, (size_t)n_rx * (size_t)np * sizeof(int),
                       cudaMemcpyHostToDevice, st));
    CK(cudaStreamSynchronize(st));
    o->serial = v->serial;
    return SASNAV_OK;
}

static int have_op(const gpu_ctx *g, int which)
{
    if (which < 0 || which > 1 || !g->op[which].serial)
        return sasnav_set_error(SASNAV_ERR_ARG, "GPU: operator %d has no geometry", which);
    return SASNAV_OK;
}

extern "C" int gpu_apply(gpu_ctx *g, int which, int adj, const float *x, float *out)
{
    if (!g || !x || !out) return sasnav_set_error(SASNAV_ERR_ARG, "GPU: NULL argument");
    int rc = have_op(g, which);
    if (rc) return rc;
    chain_ws *w = &g->ws[0];
    size_t nin = adj ? g->nd : (size_t)g->np, nout = adj ? (size_t)g->np : g->nd;
    float2 *din = adj ? w->r : w->s, *dout = adj ? w->s : w->q;
    CK(cudaMemcpyAsync(din, x, nin * sizeof(float2), cudaMemcpyHostToDevice, w->st));
    rc = adj ? adjoint(g, which, w, din, dout) : forward(g, which, w, din, dout);
    if (rc) return rc;
    CK(cudaMemcpyAsync(out, dout, nout * sizeof(float2), cudaMemcpyDeviceToHost, w->st));
    CK(cudaStreamSynchronize(w->st));
    return SASNAV_OK;
}

extern "C" int gpu_cgls(gpu_ctx *g, int which, const float *data, int k, double tikhonov,
                               float *x)
{
    if (!g || !data || !x || k < 0 || !(tikhonov >= 0))
        return sasnav_set_error(SASNAV_ERR_ARG, "GPU: bad CGLS arguments");
    int rc = have_op(g, which);
    if (rc) return rc;
    chain_ws *w = &g->ws[0];
    CK(cudaMemcpyAsync(g->data_q, data, g->nd * sizeof(float2), cudaMemcpyHostToDevice, w->st));
    if ((rc = cgls(g, which, w, g->data_q, k, tikhonov, g->rho_q))) return rc;
    CK(cudaMemcpyAsync(x, g->rho_q, (size_t)g->np * sizeof(float2), cudaMemcpyDeviceToHost, w->st));
    CK(cudaStreamSynchronize(w->st));
    return SASNAV_OK;
}

/* The evaluation's device work, from w0->psi = rho_p and g->data_q; ends
 * on stream 0 (stream 1 joined back), with rho_q in g->rho_q, psi_p in
 * ws[0].psi and psi_q in ws[1].psi. */
static int enqueue_eval(gpu_ctx *g, int k, int i, double tikhonov)
{
    size_t np = (size_t)g->np;
    chain_ws *w0 = &g->ws[0], *w1 = &g->ws[1];
    int rc;
    /* rho_q = T_q^+ phi_q on stream 0; psi_q's chain starts from it. */
    if ((rc = cgls(g, 1, w0, g->data_q, k, tikhonov, g->rho_q))) return rc;
    CK(cudaMemcpyAsync(w1->psi, g->rho_q, np * sizeof(float2), cudaMemcpyDeviceToDevice, w0->st));
    CK(cudaEventRecord(g->ev, w0->st));
    CK(cudaStreamWaitEvent(w1->st, g->ev, 0));
    /* chain 0: psi_p, first Q_q; chain 1: psi_q, first Q_p (the chains of
     * pair.c's project_chains); issued step by step so that both streams
     * have work. */
    for (int s = 0; s < 2 * i; s++) {
        for (int c = 0; c < 2; c++) {
            chain_ws *w = &g->ws[c];
            int which = (s % 2 == 0) == (c == 0) ? 1 : 0;
            const float2 *in = s % 2 == 0 ? w->psi : w->tmp;
            float2 *out = s % 2 == 0 ? w->tmp : w->psi;
            if ((rc = project(g, which, w, in, out, k, tikhonov))) return rc;
        }
    }
    CK(cudaEventRecord(g->ev_join, w1->st));
    CK(cudaStreamWaitEvent(w0->st, g->ev_join, 0));
    return SASNAV_OK;
}

/* Captures enqueue_eval into *exec (stream capture of stream 0, which
 * forks stream 1 and joins it back). */
static int capture(gpu_ctx *g, int k, int i, double tikhonov, cudaGraphExec_t *exec)
{
    cudaStream_t st = g->ws[0].st;
    CK(cudaStreamBeginCapture(st, cudaStreamCaptureModeThreadLocal));
    int rc = enqueue_eval(g, k, i, tikhonov);
    cudaGraph_t graph = NULL;
    cudaError_t e = cudaStreamEndCapture(st, &graph);
    if (rc) {
        if (graph) cudaGraphDestroy(graph);
        return rc;
    }
    if (e != cudaSuccess)
        return sasnav_set_error(SASNAV_ERR_INTERNAL, "GPU: graph capture failed: %s", cudaGetErrorString(e));
    e = cudaGraphInstantiate(exec, graph, 0);
    cudaGraphDestroy(graph);
    if (e != cudaSuccess)
        return sasnav_set_error(SASNAV_ERR_INTERNAL, "GPU: graph instantiation failed: %s",
                                cudaGetErrorString(e));
    return SASNAV_OK;
}

/* The evaluation from the staged inputs (g->h_in) to the staged outputs
 * (g->h_out), stream 0 synchronised at the end. */
static int eval_staged(gpu_ctx *g, int k, int i, double tikhonov)
{
    size_t np = (size_t)g->np;
    chain_ws *w0 = &g->ws[0], *w1 = &g->ws[1];
    int rc;
    CK(cudaMemcpyAsync(g->data_q, g->h_in, g->nd * sizeof(float2), cudaMemcpyHostToDevice, w0->st));
    CK(cudaMemcpyAsync(w0->psi, g->h_in + g->nd, np * sizeof(float2), cudaMemcpyHostToDevice, w0->st));
    eval_graph *eg = NULL;
    if (!g->no_graph) {
        for (int j = 0; j < N_GRAPHS && !eg; j++)
            if (g->graphs[j].have && g->graphs[j].k == k && g->graphs[j].i == i &&
                g->graphs[j].lambda == tikhonov)
                eg = &g->graphs[j];
        if (!eg) {
            eg = &g->graphs[0]; /* an empty slot, else the least recently used */
            for (int j = 1; j < N_GRAPHS && eg->have; j++)
                if (!g->graphs[j].have || g->graphs[j].used < eg->used) eg = &g->graphs[j];
            if (eg->have) cudaGraphExecDestroy(eg->exec);
            eg->have = 0;
            if (capture(g, k, i, tikhonov, &eg->exec) == SASNAV_OK) {
                *eg = (eval_graph){eg->exec, 1, k, i, tikhonov, 0};
            } else {
                eg = NULL;
                g->no_graph = 1; /* not capturable here: the same work, launched one by one */
                cudaGetLastError();
            }
        }
    }
    if (eg) {
        eg->used = ++g->graph_clock;
        CK(cudaGraphLaunch(eg->exec, w0->st));
    } else if ((rc = enqueue_eval(g, k, i, tikhonov))) {
        return rc;
    }
    CK(cudaMemcpyAsync(g->h_out, g->rho_q, np * sizeof(float2), cudaMemcpyDeviceToHost, w0->st));
    CK(cudaMemcpyAsync(g->h_out + np, w0->psi, np * sizeof(float2), cudaMemcpyDeviceToHost, w0->st));
    CK(cudaMemcpyAsync(g->h_out + 2 * np, w1->psi, np * sizeof(float2), cudaMemcpyDeviceToHost, w0->st));
    CK(cudaStreamSynchronize(w0->st));
    return SASNAV_OK;
}

extern "C" int gpu_eval(gpu_ctx *g, const float *data_q, const float *rho_p, int k, int i,
                               double tikhonov, float *rho_q, float *psi_p, float *psi_q)
{
    if (!g || !data_q || !rho_p || !rho_q || !psi_p || !psi_q || k < 0 || i < 0 || !(tikhonov >= 0))
        return sasnav_set_error(SASNAV_ERR_ARG, "GPU: bad evaluation arguments");
    int rc = have_op(g, 0);
    if (!rc) rc = have_op(g, 1);
    if (rc) return rc;
    size_t np = (size_t)g->np;
    memcpy(g->h_in, data_q, g->nd * sizeof(float2));
    memcpy(g->h_in + g->nd, rho_p, np * sizeof(float2));
    if ((rc = eval_staged(g, k, i, tikhonov))) {
        /* no copy may still use the staging buffers when the next call
         * fills them */
        cudaStreamSynchronize(g->ws[0].st);
        cudaStreamSynchronize(g->ws[1].st);
        return rc;
    }
    memcpy(rho_q, g->h_out, np * sizeof(float2));
    memcpy(psi_p, g->h_out + np, np * sizeof(float2));
    memcpy(psi_q, g->h_out + 2 * np, np * sizeof(float2));
    return SASNAV_OK;
}

static int use_device_geometry = 1; /* gpu_use_device_geometry */

extern "C" void gpu_use_device_geometry(int on) { use_device_geometry = on != 0; }
extern "C" int gpu_device_geometry(void) { return use_device_geometry; }

/* A serial no operator holds: the pairs were computed on the device. */
#define DEVICE_PLACED ((unsigned long)-1)

/* Bits of the sort keys l (lf + 1) + index < n_rx (lf + 1). */
static int key_bits(const gpu_ctx *g)
{
    int nc = g->n_rx * (g->lf + 1), bits = 1;
    while (bits < 31 && (1 << bits) < nc) bits++;
    return bits;
}

/* The buffers of the device-side geometry (gpu_set_points). */
static void free_points(gpu_ctx *g)
{
    cudaFree(g->px);
    cudaFree(g->py);
    cudaFree(g->chan);
    cudaFree(g->keys_in);
    cudaFree(g->keys_out);
    cudaFree(g->vals_in);
    cudaFree(g->counts);
    cudaFree(g->sums);
    cudaFree(g->near);
    cudaFree(g->sort_temp);
    if (g->h_near) cudaFreeHost(g->h_near);
    g->px = g->py = NULL;
    g->chan = NULL;
    g->keys_in = g->keys_out = g->vals_in = g->counts = g->sums = g->near = g->h_near = NULL;
    g->sort_temp = NULL;
    g->sort_bytes = 0;
    g->points_ready = g->have_points = 0;
}

static int alloc_points(gpu_ctx *g, size_t np, size_t n, size_t nc)
{
    CK(cudaMalloc((void **)&g->px, np * sizeof(double)));
    CK(cudaMalloc((void **)&g->py, np * sizeof(double)));
    CK(cudaMalloc((void **)&g->chan, (size_t)g->n_rx * sizeof(op_channel_geometry)));
    CK(cudaMalloc((void **)&g->keys_in, n * sizeof(int)));
    CK(cudaMalloc((void **)&g->keys_out, n * sizeof(int)));
    CK(cudaMalloc((void **)&g->vals_in, n * sizeof(int)));
    CK(cudaMalloc((void **)&g->counts, nc * sizeof(int)));
    CK(cudaMalloc((void **)&g->sums, nc * sizeof(int)));
    CK(cudaMalloc((void **)&g->near, sizeof(int)));
    CK(cudaMallocHost((void **)&g->h_near, sizeof(int)));
    size_t b1 = 0, b2 = 0;
    CK(cub::DeviceRadixSort::SortPairs(NULL, b1, g->keys_in, g->keys_out, g->vals_in, g->vals_in,
                                       (int)n, 0, key_bits(g)));
    CK(cub::DeviceScan::InclusiveSum(NULL, b2, g->counts, g->sums, (int)nc));
    g->sort_bytes = b1 > b2 ? b1 : b2;
    CK(cudaMalloc(&g->sort_temp, g->sort_bytes));
    g->points_ready = 1;
    return SASNAV_OK;
}

extern "C" int gpu_set_points(gpu_ctx *g, const op_geometry_consts *c)
{
    if (!g || !c || !c->x || !c->y || !c->tap_coef || c->tap_degree < 0)
        return sasnav_set_error(SASNAV_ERR_ARG, "GPU: bad set_points arguments");
    size_t np = (size_t)g->np, n = (size_t)g->n_rx * np, nc = (size_t)g->n_rx * (size_t)(g->lf + 1);
    size_t ncoef = (size_t)(c->tap_degree + 1) * (size_t)g->wpad;
    g->have_points = 0; /* until every copy below has succeeded */
    if (!g->points_ready) {
        /* all or nothing: a failure frees what was made, so that a later
         * call starts again from scratch */
        int rc = alloc_points(g, np, n, nc);
        if (rc) {
            free_points(g);
            return rc;
        }
    }
    /* pairs of the last block's missing points stay zero; the operators'
     * zeroed pairs are no geometry */
    g->op[0].serial = g->op[1].serial = 0;
    cudaStream_t st = g->ws[0].st;
    for (int c2 = 0; c2 < 2; c2++) {
        CK(cudaMemsetAsync(g->op[c2].index, 0, g->n_pairs * sizeof(int32_t), st));
        CK(cudaMemsetAsync(g->op[c2].taps, 0, g->n_pairs * (size_t)g->wpad * sizeof(float), st));
        CK(cudaMemsetAsync(g->op[c2].green, 0, g->n_pairs * sizeof(float2), st));
    }
    cudaFree(g->tap_coef);
    g->tap_coef = NULL;
    CK(cudaMalloc((void **)&g->tap_coef, ncoef * sizeof(float)));
    CK(cudaMemcpyAsync(g->tap_coef, c->tap_coef, ncoef * sizeof(float), cudaMemcpyHostToDevice, st));
    CK(cudaMemcpyAsync(g->px, c->x, np * sizeof(double), cudaMemcpyHostToDevice, st));
    CK(cudaMemcpyAsync(g->py, c->y, np * sizeof(double), cudaMemcpyHostToDevice, st));
    CK(cudaStreamSynchronize(st));
    g->gk = (geom_consts){c->inv_c, c->inv_h, c->two_f0, c->start, c->half, c->u_max, c->v_max,
                          c->att_exploding, c->att_spherical, c->att_none, c->tap_degree};
    g->have_points = 1;
    return SASNAV_OK;
}

extern "C" int gpu_place(gpu_ctx *g, int which, const op_channel_geometry *channels)
{
    if (!g || !channels || which < 0 || which > 1)
        return sasnav_set_error(SASNAV_ERR_ARG, "GPU: bad place arguments");
    if (!g->have_points) return sasnav_set_error(SASNAV_ERR_ARG, "GPU: place before set_points");
    dev_op *o = &g->op[which];
    o->serial = 0;
    cudaStream_t st = g->ws[0].st;
    int np = g->np, lf = g->lf;
    int n = g->n_rx * np, nc = g->n_rx * (lf + 1), end_bit = key_bits(g);
    CK(cudaMemcpyAsync(g->chan, channels, (size_t)g->n_rx * sizeof(op_channel_geometry),
                       cudaMemcpyHostToDevice, st));
    CK(cudaMemsetAsync(g->counts, 0, (size_t)nc * sizeof(int), st));
    CK(cudaMemsetAsync(g->near, 0, sizeof(int), st));
    k_geometry<<<dim3(blocks_of((size_t)np), g->n_rx), RTH, 0, st>>>(
        np, g->n_rx, lf, g->wpad, g->gk, g->px, g->py, g->chan, g->tap_coef, o->index, o->taps,
        o->green, g->keys_in, g->vals_in, g->counts, g->near);
    CKLAUNCH();
    /* the spread's lists: a stable sort keeps point order within an index */
    size_t bytes = g->sort_bytes;
    CK(cub::DeviceRadixSort::SortPairs(g->sort_temp, bytes, g->keys_in, g->keys_out, g->vals_in, o->order,
                                       n, 0, end_bit, st));
    bytes = g->sort_bytes;
    CK(cub::DeviceScan::InclusiveSum(g->sort_temp, bytes, g->counts, g->sums, nc, st));
    k_starts<<<blocks_of((size_t)nc), RTH, 0, st>>>(nc, lf, np, g->sums, o->start);
    CKLAUNCH();
    CK(cudaMemcpyAsync(g->h_near, g->near, sizeof(int), cudaMemcpyDeviceToHost, st));
    CK(cudaStreamSynchronize(st));
    if (*g->h_near)
        return sasnav_set_error(SASNAV_ERR_GEOMETRY, "op: a point coincides with a sensor");
    o->serial = DEVICE_PLACED;
    return SASNAV_OK;
}

extern "C" const char *gpu_name(const gpu_ctx *g) { return g ? g->name : ""; }
