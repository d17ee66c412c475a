/* The ping operator T and its adjoint T^H (paper eq. acop, SPEC 2; op.h).
 *
 * Per channel l, (T rho)_l(t_m) = sum_n p(t_m - tau_ln) G_ln rho_n is computed
 * as a NUFFT (Barnett et al. 2019; cf. Fessler & Sutton 2003, cited by the
 * paper):
 *
 *   1. spread: fine[j] = sum_n G_ln rho_n phi((j h - s_ln) / (w h / 2)),
 *      s_ln = tau_ln - (t0 - pad dt), on a periodic fine grid of Lf samples,
 *      spacing h = Mp dt / Lf (the period Mp dt of the coarse grid);
 *   2. F = FFT_Lf(fine) = (1/h) phihat(f_k) sum_n c_n exp(-j 2 pi f_k s_n)
 *      (Poisson summation, up to the kernel's aliasing error);
 *   3. X_k = F[k mod Lf] w(f_k) / (W phihat_eff(f_k)), phihat_eff = phihat / h,
 *      for the band |k| <= K (sasnav_band_kmax), 0 elsewhere;
 *   4. x = IFFT_Mp(X) (unnormalised): x[m] = sum_n c_n p(m dt - s_n), the
 *      periodic band-limited pulse of sasnav_pulse_direct; output samples
 *      m = pad .. pad + n_samples - 1.
 *
 * T^H applies the transposed steps in reverse order (zero-padded data ->
 * FFT_Mp -> same real weights -> embed in fine spectrum -> IFFT_Lf ->
 * interpolate with the same kernel taps -> conj(G)), so it is the exact
 * adjoint up to float rounding.
 *
 * Storage (filled by set_geometry): for every (channel, point) pair the first
 * fine-grid index (int32), `wpad` kernel taps (float, zero beyond the kernel
 * width; evaluated from polynomial fits of the kernel, kernel.h, instead of
 * w exp/sqrt calls) and G (complex float). Pairs are stored in blocks of
 * BLOCK points: pair (l, n) at ((n / BLOCK) * n_rx + l) * BLOCK + n % BLOCK,
 * so that a channel's points are contiguous within a block and a block's
 * channels are adjacent: the forward (each thread a range of channels, block
 * by block) and the adjoint interpolation (block by block, all channels) both
 * read the pair data as sequential streams.
 *
 * Threads: FFTW plans are made in create only (inside a named critical
 * section, since the FFTW planner is not re-entrant) and run with the
 * new-array execute functions on per-thread buffers of the same alignment.
 * Loops are scheduled dynamically (a thread that loses its core to another
 * process does not hold the others up); every output is still computed by one
 * thread in a fixed order, so results do not depend on the schedule.
 */
#include "sasnav/op.h"
#include "sasnav/error.h"
#include "operators/op_view.h"
#include "operators/op_team.h"
#include "signal/kernel.h"

#include <fftw3.h>
#include <math.h>
#include <omp.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* The per-pair loops of set_geometry compute every quantity for every pair
 * and then select (dropped pairs, beam patterns); GCC will not vectorise such
 * loops while it must assume that floating-point operations trap (its default
 * -ftrapping-math), because it moves operations into the selected branches.
 * Nothing here relies on FP exceptions. (-fno-math-errno cannot be set this
 * way, hence sqrt_nr below.) */
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC optimize("no-trapping-math")
#endif

/* The hot loops are compiled twice, for baseline x86-64 (SSE2) and for
 * x86-64-v3 (AVX2 + FMA), and the loader picks the version the CPU supports
 * (GCC function multi-versioning; bench_op: about 1.6x on the adjoint),
 * unless the whole build already targets AVX2 (SASNAV_NATIVE). The versions
 * may differ in the last bits (FMA contraction), never with the thread count. */
#ifndef HOT_LOOP /* -DHOT_LOOP= builds the baseline version only (tests) */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(__AVX2__)
#define HOT_LOOP __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define HOT_LOOP
#endif
#endif

#define BLOCK OP_BLOCK  /* points per block of the pair layout (64) */
#define MAX_SAMPLES (1 << 26)  /* window samples (keeps every index in int) */
#define MIN_SENSOR_DISTANCE 1e-9

/* FFT buffers are handled as interleaved (re, im) floats: fftwf_complex is
 * float _Complex here because <complex.h> is included before <fftw3.h>. */
typedef struct {
    float *fine;           /* 2 lf: FFT buffer of the fine grid */
    float *coarse;         /* 2 mp: FFT buffer of the coarse grid */
} op_work;

/* An open run of the spreading loop (see DEFINE_SPREAD). */
typedef struct {
    float re[SASNAV_KERNEL_MAX_WIDTH], im[SASNAV_KERNEL_MAX_WIDTH];
    int32_t first;
} spread_run;

typedef void (*spread_fn)(const sasnav_op *op, int l, int b, const sasnav_cfloat *rho, float *re,
                          float *im, spread_run *run);
typedef void (*interp_fn)(const sasnav_op *op, int block, sasnav_cfloat *rho, int accumulate);
typedef void (*spread2_fn)(const sasnav_op *op, int l, int b, const sasnav_cfloat *rho0,
                           const sasnav_cfloat *rho1, spread_run *run0, spread_run *run1);
typedef void (*interp2_fn)(const sasnav_op *op, int block, sasnav_cfloat *rho0, sasnav_cfloat *rho1);
typedef void (*taps_fn)(const sasnav_op *op, int count, const float *t, const float *keep,
                        float *taps);

struct sasnav_op {
    sasnav_system sys;
    sasnav_array array;
    sasnav_window win;
    int n_points, n_rx, n_samples, nthreads;
    double *x, *y;          /* the points, as given */
    double *tx_range;       /* per point: |z_n - z_t| (scratch of set_geometry) */
    double *tx_gain;        /* per point: Tx beam pattern */

    /* Grids. */
    int pad, mp, lf, ext;   /* coarse offset, coarse and fine lengths, fine extension */
    double dt, h, period, grid_start; /* grid_start = t0 - pad dt */
    sasnav_kernel kernel;
    int wpad;               /* taps stored per pair: width rounded up to 4 */
    int kmax;
    float *spectral;        /* 2 kmax + 1 real weights w(f_k) / (W phihat_eff(f_k)) */

    /* Per-pair geometry. */
    int n_blocks;
    size_t n_pairs;
    int32_t *index;         /* first fine index of the kernel, in [0, lf - w] */
    float *taps;            /* wpad kernel weights per pair */
    float *green;           /* G as (re, im) */
    long n_dropped;
    int have_geometry;
    unsigned long serial;   /* of the geometry held (op_view.h) */
    int cap_points;         /* points the per-pair storage holds */

    /* FFT plans and work buffers. */
    fftwf_plan fine_fwd, fine_bwd, coarse_fwd, coarse_bwd;
    op_work *work;          /* one per thread */
    float *adj2_re, *adj2_im; /* a second set, for the second image of the team
                                 applications (op_team.h; allocated by
                                 op_team_prepare) */
    float *adj_re, *adj_im; /* n_rx split fine grids (lf + ext each): spread by T,
                               interpolated by T^H */
    spread_fn spread;
    spread2_fn spread2;
    interp_fn interp;
    interp2_fn interp2;
    taps_fn taps_eval;
    int tap_degree;
    float *tap_coef;        /* (tap_degree + 1) x wpad polynomial coefficients */
};

/* ------------------------------------------------------------------------ */
/* Hot loops, generated for a compile-time tap count W (4, 8, 12, 16) so that
 * the compiler unrolls and vectorises the tap loop. */

/* fine[index + j] += taps[j] * G rho over the points of channel l in block b.
 * Consecutive points with the same first index (long runs along x on grids,
 * where the delay changes slowly) are summed in registers and added to the
 * grid once: adding every point straight into memory makes each update wait
 * for the previous, overlapping store (store-to-load forwarding). The open
 * run is carried from block to block in `run` (flushed by spread_flush). */
static void spread_flush(spread_run *run, int wpad, float *re, float *im)
{
    for (int j = 0; j < wpad; j++) {
        re[run->first + j] += run->re[j];
        im[run->first + j] += run->im[j];
        run->re[j] = run->im[j] = 0.0f;
    }
}

#define DEFINE_SPREAD(W)                                                                   \
    HOT_LOOP static void spread_##W(const sasnav_op *op, int l, int b,                     \
                                    const sasnav_cfloat *rho, float *restrict re,          \
                                    float *restrict im, spread_run *run)                   \
    {                                                                                      \
        const float *rho_f = (const float *)rho;                                           \
        int n0 = b * BLOCK;                                                                \
        int count = op->n_points - n0 < BLOCK ? op->n_points - n0 : BLOCK;                 \
        size_t q0 = ((size_t)b * (size_t)op->n_rx + (size_t)l) * BLOCK;                    \
        const int32_t *restrict index = op->index + q0;                                    \
        const float *restrict green = op->green + 2 * q0;                                  \
        const float *restrict taps = op->taps + q0 * W;                                    \
        /* G rho of the block's points first, in a loop across points that   \
         * vectorises (inside the run loop it was a scalar complex product     \
         * per pair and the loop's largest cost: bench_op 1.14-1.21x forward). */ \
        float c_r[BLOCK], c_i[BLOCK];                                                      \
        _Pragma("omp simd") for (int k = 0; k < count; k++)                                \
        {                                                                                  \
            float gr = green[2 * k], gi = green[2 * k + 1];                                \
            float rr = rho_f[2 * (n0 + k)], ri = rho_f[2 * (n0 + k) + 1];                  \
            c_r[k] = gr * rr - gi * ri;                                                    \
            c_i[k] = gr * ri + gi * rr;                                                    \
        }                                                                                  \
        float acc_r[W], acc_i[W];                                                          \
        for (int j = 0; j < W; j++) {                                                      \
            acc_r[j] = run->re[j];                                                         \
            acc_i[j] = run->im[j];                                                         \
        }                                                                                  \
        int32_t first = run->first;                                                        \
        for (int i = 0; i < count; i++) {                                                  \
            if (index[i] != first) {                                                       \
                _Pragma("omp simd") for (int j = 0; j < W; j++)                            \
                {                                                                          \
                    re[first + j] += acc_r[j];                                             \
                    im[first + j] += acc_i[j];                                             \
                    acc_r[j] = acc_i[j] = 0.0f;                                            \
                }                                                                          \
                first = index[i];                                                          \
            }                                                                              \
            float cr = c_r[i], ci = c_i[i];                                                \
            const float *restrict t = taps + (size_t)i * W;                                \
            _Pragma("omp simd") for (int j = 0; j < W; j++)                                \
            {                                                                              \
                acc_r[j] += t[j] * cr;                                                     \
                acc_i[j] += t[j] * ci;                                                     \
            }                                                                              \
        }                                                                                  \
        for (int j = 0; j < W; j++) {                                                      \
            run->re[j] = acc_r[j];                                                         \
            run->im[j] = acc_i[j];                                                         \
        }                                                                                  \
        run->first = first;                                                                \
    }

/* rho[n] (+)= sum_l conj(G_ln) sum_j taps[j] fine_l[index + j] for the points
 * of one block. The per-tap partial sums of every point are kept in W lanes
 * over all channels and reduced once per point, channels in increasing order.
 * Two loop orders, with identical results:
 * - interp_points_W (point outer, channel inner): the lanes stay in
 *   registers, but every point's channels make one chain of additions and
 *   3 x n_rx interleaved streams of pair data; best only on small grids
 *   whose pair data sit in L2 (40 x 40: about 8 % faster);
 * - interp_stream_W (channel outer): the block's pair data are read as one
 *   sequential stream, the lanes go through L1 and consecutive pairs do not
 *   wait on each other; bench_op 1e-3, one thread: 1.18x faster on 64 x 64,
 *   1.38x on 80 x 128, 1.40x on 129 x 129 (the estimator's levels 1-2),
 *   2x on 256 x 256 (docs/estimator.md, "The adjoint's loop order").
 * sasnav_op_create picks one from the size of the pair data (STREAM_BYTES). */
#ifndef STREAM_BYTES
#define STREAM_BYTES (1u << 20)
#endif

static void store_point(sasnav_cfloat *rho, int n, float sr, float si, int accumulate)
{
    float *rho_f = (float *)rho;
    if (accumulate) {
        rho_f[2 * n] += sr;
        rho_f[2 * n + 1] += si;
    } else {
        rho_f[2 * n] = sr;
        rho_f[2 * n + 1] = si;
    }
}

/* Four consecutive points of one channel into the sums of n = 1 or 2 images
 * at once (interp_stream_W, interp2_W): lanes (point, tap), 4 W of them,
 * each with the operations of the one-point loops in the same order, so the
 * same bits. For W = 4 in 16-float vectors (GCC's vector extensions: one
 * AVX-512 register per sum where the target has them, two or four narrower
 * ones elsewhere); the four points' fine samples come from one 16-sample
 * window per grid and a permutation. `sasnav pair --threads 1` 1.10x
 * faster than one point at a time; what was tried beside it:
 * docs/estimator.md, "Four points at a time in the interpolation". */
typedef float v16sf __attribute__((vector_size(64)));
typedef float v8sf __attribute__((vector_size(32)));
typedef float v4sf __attribute__((vector_size(16)));

/* v = the 4 floats at p + x[0], then at p + x[1], p + x[2], p + x[3]. */
#define LOAD_FOUR(v, p, x)                                                                 \
    do {                                                                                   \
        v4sf f0_, f1_, f2_, f3_;                                                           \
        memcpy(&f0_, (p) + (x)[0], sizeof f0_);                                            \
        memcpy(&f1_, (p) + (x)[1], sizeof f1_);                                            \
        memcpy(&f2_, (p) + (x)[2], sizeof f2_);                                            \
        memcpy(&f3_, (p) + (x)[3], sizeof f3_);                                            \
        v8sf lo_ = __builtin_shufflevector(f0_, f1_, 0, 1, 2, 3, 4, 5, 6, 7);              \
        v8sf hi_ = __builtin_shufflevector(f2_, f3_, 0, 1, 2, 3, 4, 5, 6, 7);              \
        (v) = __builtin_shufflevector(lo_, hi_, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12,  \
                                      13, 14, 15);                                         \
    } while (0)

#define ADD_TO(p, d)                                                                       \
    do {                                                                                   \
        v16sf s_;                                                                          \
        memcpy(&s_, (p), sizeof s_);                                                       \
        s_ += (d);                                                                         \
        memcpy((p), &s_, sizeof s_);                                                       \
    } while (0)

typedef int32_t v16si __attribute__((vector_size(64)));
typedef int32_t v8si __attribute__((vector_size(32)));
typedef int32_t v4si __attribute__((vector_size(16)));

/* The fine grids end with READ_PAD floats of padding (fine_grids): the
 * window of 16 floats read at the smallest of four indices stays inside. */
#define READ_PAD 16

#if defined(__clang__) || (defined(__GNUC__) && __GNUC__ >= 12)
#define VECTOR_FOUR 1 /* __builtin_shufflevector: GCC 12, clang */
#else
#define VECTOR_FOUR 0
#endif

#if VECTOR_FOUR
/* fine: the 2n split grids (re, im of each image) of the channel; sum: the
 * 2n sums (re, im of each image) of the four points, 4 W floats each. */
static inline __attribute__((always_inline)) void
interp_four_4(int n, const float *restrict t, const float *restrict g, const int32_t *x,
              const float *const *fine, float *const *sum)
{
    v8sf g8;
    v16sf T, F[4];
    memcpy(&g8, g, sizeof g8); /* (re, im) of G for the four points */
    memcpy(&T, t, sizeof T);
    v16sf GR = __builtin_shufflevector(g8, g8, 0, 0, 0, 0, 2, 2, 2, 2, 4, 4, 4, 4, 6, 6, 6, 6);
    v16sf GI = __builtin_shufflevector(g8, g8, 1, 1, 1, 1, 3, 3, 3, 3, 5, 5, 5, 5, 7, 7, 7, 7);
    v16sf A = T * GR, C = T * GI;
    int32_t lo = x[0], hi = x[0];
    for (int k = 1; k < 4; k++) {
        lo = x[k] < lo ? x[k] : lo;
        hi = x[k] > hi ? x[k] : hi;
    }
    if (hi - lo <= 12) {
        /* Neighbouring points (almost always): one window of 16 fine
         * samples per grid, the lanes picked from it by a permutation. */
        v4si x4;
        memcpy(&x4, x, sizeof x4);
        x4 -= lo;
        /* widened in two steps: in one, GCC 12 went through the stack */
        v8si x8 = __builtin_shufflevector(x4, x4, 0, 1, 2, 3, 4, 5, 6, 7);
        v16si sel = __builtin_shufflevector(x8, x8, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2, 3, 3, 3, 3);
        sel += (v16si){0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3};
        for (int k = 0; k < 2 * n; k++) {
            v16sf w;
            memcpy(&w, fine[k] + lo, sizeof w);
#if defined(__clang__) /* no variable shuffle builtin: lane by lane (the fuzz builds) */
            for (int m = 0; m < 16; m++) F[k][m] = w[sel[m]];
#else
            F[k] = __builtin_shuffle(w, sel);
#endif
        }
    } else {
        for (int k = 0; k < 2 * n; k++) LOAD_FOUR(F[k], fine[k], x);
    }
    for (int m = 0; m < n; m++) {
        ADD_TO(sum[2 * m], A * F[2 * m] + C * F[2 * m + 1]);
        ADD_TO(sum[2 * m + 1], A * F[2 * m + 1] - C * F[2 * m]);
    }
}
#endif /* VECTOR_FOUR */

/* Other tap counts (not the estimator's), and W = 4 where the compiler has
 * no __builtin_shufflevector: the same lanes in a plain loop. */
#define DEFINE_INTERP_FOUR(W)                                                              \
    static inline void interp_four_##W(int n, const float *restrict t_,                    \
                                       const float *restrict g_, const int32_t *x_,        \
                                       const float *const *fine_, float *const *sum_)      \
    {                                                                                      \
        for (int m = 0; m < 4 * W; m++) {                                                  \
            int k_ = m / W, j_ = m % W;                                                    \
            float a_ = t_[m] * g_[2 * k_], c_ = t_[m] * g_[2 * k_ + 1];                    \
            for (int e = 0; e < n; e++) {                                                  \
                float fr_ = fine_[2 * e][x_[k_] + j_], fi_ = fine_[2 * e + 1][x_[k_] + j_]; \
                sum_[2 * e][m] += a_ * fr_ + c_ * fi_;                                     \
                sum_[2 * e + 1][m] += a_ * fi_ - c_ * fr_;                                 \
            }                                                                              \
        }                                                                                  \
    }
#if !VECTOR_FOUR
DEFINE_INTERP_FOUR(4)
#endif
DEFINE_INTERP_FOUR(8)
DEFINE_INTERP_FOUR(12)
DEFINE_INTERP_FOUR(16)

#define INTERP_PAIR(W, ar, ai)                                                             \
    do {                                                                                   \
        const float *restrict t_ = op->taps + q * W;                                       \
        const float *restrict fr_ = op->adj_re + (size_t)l * stride + op->index[q];        \
        const float *restrict fi_ = op->adj_im + (size_t)l * stride + op->index[q];        \
        float gr_ = op->green[2 * q], gi_ = op->green[2 * q + 1];                          \
        _Pragma("omp simd") for (int j = 0; j < W; j++)                                    \
        {                                                                                  \
            float a_ = t_[j] * gr_, c_ = t_[j] * gi_;                                      \
            ar[j] += a_ * fr_[j] + c_ * fi_[j];                                            \
            ai[j] += a_ * fi_[j] - c_ * fr_[j];                                            \
        }                                                                                  \
    } while (0)

#define DEFINE_INTERP(W)                                                                   \
    HOT_LOOP static void interp_points_##W(const sasnav_op *op, int b, sasnav_cfloat *rho, \
                                           int accumulate)                                 \
    {                                                                                      \
        int n0 = b * BLOCK;                                                                \
        int count = op->n_points - n0 < BLOCK ? op->n_points - n0 : BLOCK;                 \
        size_t stride = (size_t)op->lf + (size_t)op->ext;                                  \
        for (int i = 0; i < count; i++) {                                                  \
            float ar[W], ai[W];                                                            \
            for (int j = 0; j < W; j++) ar[j] = ai[j] = 0.0f;                              \
            for (int l = 0; l < op->n_rx; l++) {                                           \
                size_t q = ((size_t)b * (size_t)op->n_rx + (size_t)l) * BLOCK + (size_t)i; \
                INTERP_PAIR(W, ar, ai);                                                    \
            }                                                                              \
            float sr = 0.0f, si = 0.0f;                                                    \
            for (int j = 0; j < W; j++) {                                                  \
                sr += ar[j];                                                               \
                si += ai[j];                                                               \
            }                                                                              \
            store_point(rho, n0 + i, sr, si, accumulate);                                  \
        }                                                                                  \
    }                                                                                      \
    HOT_LOOP static void interp_stream_##W(const sasnav_op *op, int b, sasnav_cfloat *rho, \
                                           int accumulate)                                 \
    {                                                                                      \
        int n0 = b * BLOCK;                                                                \
        int count = op->n_points - n0 < BLOCK ? op->n_points - n0 : BLOCK;                 \
        size_t stride = (size_t)op->lf + (size_t)op->ext;                                  \
        float acc_r[BLOCK][W], acc_i[BLOCK][W];                                            \
        for (int i = 0; i < count; i++)                                                    \
            for (int j = 0; j < W; j++) acc_r[i][j] = acc_i[i][j] = 0.0f;                  \
        for (int l = 0; l < op->n_rx; l++) {                                               \
            size_t q0 = ((size_t)b * (size_t)op->n_rx + (size_t)l) * BLOCK;                \
            const float *fine_[2] = {op->adj_re + (size_t)l * stride,                      \
                                     op->adj_im + (size_t)l * stride};                     \
            int i = 0;                                                                     \
            for (; i + 4 <= count; i += 4) {                                               \
                float *sum_[2] = {&acc_r[i][0], &acc_i[i][0]};                             \
                interp_four_##W(1, op->taps + (q0 + (size_t)i) * W,                        \
                                op->green + 2 * (q0 + (size_t)i), op->index + q0 + (size_t)i, \
                                fine_, sum_);                                              \
            }                                                                              \
            for (; i < count; i++) {                                                       \
                size_t q = q0 + (size_t)i;                                                 \
                INTERP_PAIR(W, acc_r[i], acc_i[i]);                                        \
            }                                                                              \
        }                                                                                  \
        for (int i = 0; i < count; i++) {                                                  \
            float sr = 0.0f, si = 0.0f;                                                    \
            for (int j = 0; j < W; j++) {                                                  \
                sr += acc_r[i][j];                                                         \
                si += acc_i[i][j];                                                         \
            }                                                                              \
            store_point(rho, n0 + i, sr, si, accumulate);                                  \
        }                                                                                  \
    }

/* Kernel taps from the fractional offsets t (Horner on the fitted
 * polynomials, kernel.h), zeroed for dropped pairs (keep = 0). */
#define DEFINE_TAPS(W)                                                                     \
    HOT_LOOP static void taps_##W(const sasnav_op *op, int count, const float *t, const float *keep, \
                         float *restrict taps)                                             \
    {                                                                                      \
        const float *restrict coef = op->tap_coef;                                         \
        int p = op->tap_degree;                                                            \
        for (int i = 0; i < count; i++) {                                                  \
            float acc[W];                                                                  \
            for (int j = 0; j < W; j++) acc[j] = coef[p * W + j];                          \
            for (int k = p - 1; k >= 0; k--) {                                             \
                _Pragma("omp simd") for (int j = 0; j < W; j++) acc[j] =                   \
                    acc[j] * t[i] + coef[k * W + j];                                       \
            }                                                                              \
            for (int j = 0; j < W; j++) taps[(size_t)i * W + j] = acc[j] * keep[i];        \
        }                                                                                  \
    }
DEFINE_TAPS(4)
DEFINE_TAPS(8)
DEFINE_TAPS(12)
DEFINE_TAPS(16)

DEFINE_SPREAD(4)
DEFINE_SPREAD(8)
DEFINE_SPREAD(12)
DEFINE_SPREAD(16)
DEFINE_INTERP(4)
DEFINE_INTERP(8)
DEFINE_INTERP(12)
DEFINE_INTERP(16)

/* Two images through the same pair data (op_team.h): the loops above with a
 * second set of sums. The shared work (the pair data read, the runs found,
 * the taps loaded) is done once; each image's sums are the same operations
 * in the same order as spread_W / interp_stream_W on it alone, so each
 * result is the same bits as one image's. bench: two images of a 129 x 129
 * grid spread in 1.57x the time of one instead of 2x. */
#define DEFINE_SPREAD2(W)                                                                  \
    HOT_LOOP static void spread2_##W(const sasnav_op *op, int l, int b,                    \
                                     const sasnav_cfloat *rho0, const sasnav_cfloat *rho1, \
                                     spread_run *run0, spread_run *run1)                   \
    {                                                                                      \
        const float *r0 = (const float *)rho0, *r1 = (const float *)rho1;                  \
        int n0 = b * BLOCK;                                                                \
        int count = op->n_points - n0 < BLOCK ? op->n_points - n0 : BLOCK;                 \
        size_t q0 = ((size_t)b * (size_t)op->n_rx + (size_t)l) * BLOCK;                    \
        size_t stride = (size_t)op->lf + (size_t)op->ext;                                  \
        float *restrict re0 = op->adj_re + (size_t)l * stride;                             \
        float *restrict im0 = op->adj_im + (size_t)l * stride;                             \
        float *restrict re1 = op->adj2_re + (size_t)l * stride;                            \
        float *restrict im1 = op->adj2_im + (size_t)l * stride;                            \
        const int32_t *restrict index = op->index + q0;                                    \
        const float *restrict green = op->green + 2 * q0;                                  \
        const float *restrict taps = op->taps + q0 * W;                                    \
        float c_r[BLOCK], c_i[BLOCK], d_r[BLOCK], d_i[BLOCK];                              \
        _Pragma("omp simd") for (int k = 0; k < count; k++)                                \
        {                                                                                  \
            float gr = green[2 * k], gi = green[2 * k + 1];                                \
            float rr = r0[2 * (n0 + k)], ri = r0[2 * (n0 + k) + 1];                        \
            c_r[k] = gr * rr - gi * ri;                                                    \
            c_i[k] = gr * ri + gi * rr;                                                    \
            float sr = r1[2 * (n0 + k)], si = r1[2 * (n0 + k) + 1];                        \
            d_r[k] = gr * sr - gi * si;                                                    \
            d_i[k] = gr * si + gi * sr;                                                    \
        }                                                                                  \
        float a_r[W], a_i[W], b_r[W], b_i[W];                                              \
        for (int j = 0; j < W; j++) {                                                      \
            a_r[j] = run0->re[j];                                                          \
            a_i[j] = run0->im[j];                                                          \
            b_r[j] = run1->re[j];                                                          \
            b_i[j] = run1->im[j];                                                          \
        }                                                                                  \
        int32_t first = run0->first;                                                       \
        for (int i = 0; i < count; i++) {                                                  \
            if (index[i] != first) {                                                       \
                _Pragma("omp simd") for (int j = 0; j < W; j++)                            \
                {                                                                          \
                    re0[first + j] += a_r[j];                                              \
                    im0[first + j] += a_i[j];                                              \
                    re1[first + j] += b_r[j];                                              \
                    im1[first + j] += b_i[j];                                              \
                    a_r[j] = a_i[j] = b_r[j] = b_i[j] = 0.0f;                              \
                }                                                                          \
                first = index[i];                                                          \
            }                                                                              \
            float cr = c_r[i], ci = c_i[i], dr = d_r[i], di = d_i[i];                      \
            const float *restrict t = taps + (size_t)i * W;                                \
            _Pragma("omp simd") for (int j = 0; j < W; j++)                                \
            {                                                                              \
                a_r[j] += t[j] * cr;                                                       \
                a_i[j] += t[j] * ci;                                                       \
                b_r[j] += t[j] * dr;                                                       \
                b_i[j] += t[j] * di;                                                       \
            }                                                                              \
        }                                                                                  \
        for (int j = 0; j < W; j++) {                                                      \
            run0->re[j] = a_r[j];                                                          \
            run0->im[j] = a_i[j];                                                          \
            run1->re[j] = b_r[j];                                                          \
            run1->im[j] = b_i[j];                                                          \
        }                                                                                  \
        run0->first = run1->first = first;                                                 \
    }

#define DEFINE_INTERP2(W)                                                                  \
    HOT_LOOP static void interp2_##W(const sasnav_op *op, int b, sasnav_cfloat *rho0,      \
                                     sasnav_cfloat *rho1)                                  \
    {                                                                                      \
        int n0 = b * BLOCK;                                                                \
        int count = op->n_points - n0 < BLOCK ? op->n_points - n0 : BLOCK;                 \
        size_t stride = (size_t)op->lf + (size_t)op->ext;                                  \
        float a_r[BLOCK][W], a_i[BLOCK][W], b_r[BLOCK][W], b_i[BLOCK][W];                  \
        for (int i = 0; i < count; i++)                                                    \
            for (int j = 0; j < W; j++) a_r[i][j] = a_i[i][j] = b_r[i][j] = b_i[i][j] = 0.0f; \
        for (int l = 0; l < op->n_rx; l++) {                                               \
            size_t q0 = ((size_t)b * (size_t)op->n_rx + (size_t)l) * BLOCK;                \
            const float *fine_[4] = {op->adj_re + (size_t)l * stride,                      \
                                     op->adj_im + (size_t)l * stride,                      \
                                     op->adj2_re + (size_t)l * stride,                     \
                                     op->adj2_im + (size_t)l * stride};                    \
            int i = 0;                                                                     \
            for (; i + 4 <= count; i += 4) {                                               \
                float *sum_[4] = {&a_r[i][0], &a_i[i][0], &b_r[i][0], &b_i[i][0]};         \
                interp_four_##W(2, op->taps + (q0 + (size_t)i) * W,                        \
                                op->green + 2 * (q0 + (size_t)i), op->index + q0 + (size_t)i, \
                                fine_, sum_);                                              \
            }                                                                              \
            for (; i < count; i++) {                                                       \
                size_t q = q0 + (size_t)i;                                                 \
                const float *restrict t_ = op->taps + q * W;                               \
                size_t o_ = (size_t)l * stride + (size_t)op->index[q];                     \
                const float *restrict fr_ = op->adj_re + o_, *restrict fi_ = op->adj_im + o_; \
                const float *restrict gr_ = op->adj2_re + o_, *restrict gi_ = op->adj2_im + o_; \
                float g_r = op->green[2 * q], g_i = op->green[2 * q + 1];                  \
                _Pragma("omp simd") for (int j = 0; j < W; j++)                            \
                {                                                                          \
                    float a_ = t_[j] * g_r, c_ = t_[j] * g_i;                              \
                    a_r[i][j] += a_ * fr_[j] + c_ * fi_[j];                                \
                    a_i[i][j] += a_ * fi_[j] - c_ * fr_[j];                                \
                    b_r[i][j] += a_ * gr_[j] + c_ * gi_[j];                                \
                    b_i[i][j] += a_ * gi_[j] - c_ * gr_[j];                                \
                }                                                                          \
            }                                                                              \
        }                                                                                  \
        for (int i = 0; i < count; i++) {                                                  \
            float sr = 0.0f, si = 0.0f, ur = 0.0f, ui = 0.0f;                              \
            for (int j = 0; j < W; j++) {                                                  \
                sr += a_r[i][j];                                                           \
                si += a_i[i][j];                                                           \
                ur += b_r[i][j];                                                           \
                ui += b_i[i][j];                                                           \
            }                                                                              \
            store_point(rho0, n0 + i, sr, si, 0);                                          \
            store_point(rho1, n0 + i, ur, ui, 0);                                          \
        }                                                                                  \
    }
DEFINE_SPREAD2(4)
DEFINE_SPREAD2(8)
DEFINE_SPREAD2(12)
DEFINE_SPREAD2(16)
DEFINE_INTERP2(4)
DEFINE_INTERP2(8)
DEFINE_INTERP2(12)
DEFINE_INTERP2(16)

/* Four channels side by side (W = 4, the estimator's kernel; forward_group).
 * spread_W and spread2_W add every pair of a run into the same accumulators,
 * so each addition waits for the previous one (perf: the loop's samples sit
 * on its four chained multiply-adds). Here channels l .. l + 3 advance in
 * one loop, four independent chains per image. Each channel gets the
 * operations of spread_W / spread2_W in the same order (G rho by the same
 * expression, the run flushed where the index changes, then taps x G rho
 * added): the same bits. n = 1 or 2 images (run1 unused for n = 1).
 * `sasnav pair pair.h5`, 5-6 alternating runs: 1.05x with one thread, 1.04x
 * with two (docs/estimator.md, "Four channels side by side"). Tried beside
 * it: the four channels in the lanes of 16-float vectors (one operation per
 * four pairs) is 1.6x slower: the runs of four channels end at a quarter
 * of the points, and every end costs a spill of the vectors. */
static inline __attribute__((always_inline)) void
spread_four_body(const sasnav_op *op, int n, int l, int b, const sasnav_cfloat *const *rho,
                 spread_run *run0, spread_run *run1)
{
    enum { W = 4 };
    int n0 = b * BLOCK;
    int count = op->n_points - n0 < BLOCK ? op->n_points - n0 : BLOCK;
    size_t stride = (size_t)op->lf + (size_t)op->ext;
    spread_run *run[2] = {run0, run1}; /* [image]: the runs of channels l .. l + 3 */
    float *re[2][4], *im[2][4];        /* [image][channel]: fine grids */
    const int32_t *idx[4];
    const float *tap[4];
    float cr[2][4][BLOCK], ci[2][4][BLOCK]; /* [image][channel][point]: G rho */
    for (int c = 0; c < 4; c++) {
        size_t q0 = ((size_t)b * (size_t)op->n_rx + (size_t)(l + c)) * BLOCK;
        idx[c] = op->index + q0;
        tap[c] = op->taps + q0 * W;
        re[0][c] = op->adj_re + (size_t)(l + c) * stride;
        im[0][c] = op->adj_im + (size_t)(l + c) * stride;
        re[1][c] = op->adj2_re + (size_t)(l + c) * stride;
        im[1][c] = op->adj2_im + (size_t)(l + c) * stride;
        const float *green = op->green + 2 * q0;
        for (int m = 0; m < n; m++) {
            const float *r = (const float *)rho[m];
            float *restrict pr = cr[m][c], *restrict pi = ci[m][c];
            _Pragma("omp simd") for (int k = 0; k < count; k++)
            {
                float gr = green[2 * k], gi = green[2 * k + 1];
                float rr = r[2 * (n0 + k)], ri = r[2 * (n0 + k) + 1];
                pr[k] = gr * rr - gi * ri;
                pi[k] = gr * ri + gi * rr;
            }
        }
    }
    v4sf ar[2][4], ai[2][4]; /* [image][channel]: the open runs' sums */
    int32_t first[4];
    for (int m = 0; m < n; m++)
        for (int c = 0; c < 4; c++) {
            memcpy(&ar[m][c], run[m][c].re, sizeof ar[m][c]);
            memcpy(&ai[m][c], run[m][c].im, sizeof ai[m][c]);
        }
    for (int c = 0; c < 4; c++) first[c] = run0[c].first;
    for (int i = 0; i < count; i++) {
        for (int c = 0; c < 4; c++) {
            if (idx[c][i] != first[c]) {
                for (int m = 0; m < n; m++) {
                    v4sf g;
                    memcpy(&g, re[m][c] + first[c], sizeof g);
                    g += ar[m][c];
                    memcpy(re[m][c] + first[c], &g, sizeof g);
                    memcpy(&g, im[m][c] + first[c], sizeof g);
                    g += ai[m][c];
                    memcpy(im[m][c] + first[c], &g, sizeof g);
                    ar[m][c] = ai[m][c] = (v4sf){0.0f, 0.0f, 0.0f, 0.0f};
                }
                first[c] = idx[c][i];
            }
            v4sf t;
            memcpy(&t, tap[c] + W * i, sizeof t);
            for (int m = 0; m < n; m++) {
                ar[m][c] += t * cr[m][c][i];
                ai[m][c] += t * ci[m][c][i];
            }
        }
    }
    for (int m = 0; m < n; m++)
        for (int c = 0; c < 4; c++) {
            memcpy(run[m][c].re, &ar[m][c], sizeof ar[m][c]);
            memcpy(run[m][c].im, &ai[m][c], sizeof ai[m][c]);
            run[m][c].first = first[c];
        }
}

HOT_LOOP static void spread_four1_4(const sasnav_op *op, int l, int b,
                                    const sasnav_cfloat *const *rho, spread_run *run0)
{
    spread_four_body(op, 1, l, b, rho, run0, run0);
}

HOT_LOOP static void spread_four2_4(const sasnav_op *op, int l, int b,
                                    const sasnav_cfloat *const *rho, spread_run *run0,
                                    spread_run *run1)
{
    spread_four_body(op, 2, l, b, rho, run0, run1);
}

/* ------------------------------------------------------------------------ */
/* Options and sizes. */

void sasnav_op_default_opts(sasnav_op_opts *opts)
{
    if (!opts) return;
    opts->tolerance = 1e-6;
    opts->oversampling = 2.0;
    opts->pad_samples = -1;
    opts->nthreads = 0;
}

static int check_opts(const sasnav_op_opts *o)
{
    if (!isfinite(o->tolerance) || !(o->tolerance >= 1e-12) || !(o->tolerance < 1.0))
        return sasnav_set_error(SASNAV_ERR_ARG, "op: tolerance must be in [1e-12, 1), got %g",
                                o->tolerance);
    if (!isfinite(o->oversampling) || !(o->oversampling >= 1.25) || !(o->oversampling <= 8.0))
        return sasnav_set_error(SASNAV_ERR_ARG, "op: oversampling must be in [1.25, 8], got %g",
                                o->oversampling);
    if (o->pad_samples < -1 || o->pad_samples > MAX_SAMPLES)
        return sasnav_set_error(SASNAV_ERR_ARG, "op: pad_samples must be -1 (auto) or 0..%d, got %d",
                                MAX_SAMPLES, o->pad_samples);
    if (o->nthreads < 0 || o->nthreads > 4096)
        return sasnav_set_error(SASNAV_ERR_ARG, "op: nthreads must be 0 (default) or 1..4096, got %d",
                                o->nthreads);
    return SASNAV_OK;
}

/* Smallest even n' >= n whose only prime factors are 2, 3, 5, 7 (fast FFTW
 * sizes). */
static int fast_even_size(long n)
{
    if (n < 2) n = 2;
    if (n % 2) n++;
    for (;; n += 2) {
        long m = n;
        static const int primes[4] = {2, 3, 5, 7};
        for (int i = 0; i < 4; i++)
            while (m % primes[i] == 0) m /= primes[i];
        if (m == 1) return (int)n;
    }
}

static int check_points(int n_points, const double *x, const double *y)
{
    if (n_points < 1) return sasnav_set_error(SASNAV_ERR_ARG, "op: need >= 1 point, got %d", n_points);
    if (!x || !y) return sasnav_set_error(SASNAV_ERR_ARG, "op: point coordinates are NULL");
    for (int n = 0; n < n_points; n++)
        if (!isfinite(x[n]) || !isfinite(y[n]))
            return sasnav_set_error(SASNAV_ERR_ARG, "op: point %d has non-finite coordinates", n);
    return SASNAV_OK;
}

/* Grid sizes: coarse Mp >= n_samples + 2 pad, fine Lf >= sigma Mp. */
static int setup_grids(sasnav_op *op, const sasnav_op_opts *o)
{
    int n = op->n_samples;
    op->pad = o->pad_samples >= 0 ? o->pad_samples : (int)ceil(0.1 * n) + 16;
    long need = (long)n + 2L * op->pad;
    if (need > MAX_SAMPLES)
        return sasnav_set_error(SASNAV_ERR_ARG, "op: window plus padding (%ld samples) too long", need);
    op->mp = fast_even_size(need);
    op->lf = fast_even_size((long)ceil(o->oversampling * op->mp - 1e-9));
    op->dt = 1.0 / op->sys.sample_rate;
    op->period = op->mp / op->sys.sample_rate;
    op->h = op->period / op->lf;
    op->grid_start = op->win.t0 - op->pad * op->dt;
    int rc = sasnav_kernel_choose(o->tolerance, o->oversampling, &op->kernel);
    if (rc) return rc;
    op->wpad = (op->kernel.width + 3) / 4 * 4;
    op->ext = op->wpad;
    if (op->lf <= 2 * op->kernel.width)
        return sasnav_set_error(SASNAV_ERR_ARG, "op: window too short for the kernel");
    return SASNAV_OK;
}

/* Spectral weights r_k = w(f_k) / (W phihat_eff(f_k)), |k| <= K, where
 * phihat_eff(f) = (1/h) int phi(t / (w h / 2)) exp(-j 2 pi f t) dt
 *              = (w / 2) F(pi f w h),  F = sasnav_kernel_transform. */
static int setup_spectrum(sasnav_op *op)
{
    op->kmax = sasnav_band_kmax(&op->sys, op->period);
    if (op->kmax < 0) return sasnav_set_error(SASNAV_ERR_INTERNAL, "op: bad pulse band");
    int nk = op->kmax + 1;
    double *xi = malloc(2 * (size_t)nk * sizeof *xi);
    op->spectral = malloc((2 * (size_t)op->kmax + 1) * sizeof *op->spectral);
    if (!xi || !op->spectral) {
        free(xi);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "op: out of memory (spectrum)");
    }
    double *ft = xi + nk;
    double w = op->kernel.width;
    for (int k = 0; k < nk; k++) xi[k] = M_PI * (k / op->period) * w * op->h;
    int rc = sasnav_kernel_transform(&op->kernel, 0, nk, xi, ft);
    double norm = 0.0;
    for (int k = -op->kmax; k <= op->kmax && !rc; k++) norm += sasnav_pulse_weight(&op->sys, k / op->period);
    if (!rc && !(norm > 0.0))
        rc = sasnav_set_error(SASNAV_ERR_ARG, "op: the pulse band holds no frequency of the grid");
    for (int k = -op->kmax; k <= op->kmax && !rc; k++) {
        double phihat = 0.5 * w * ft[abs(k)];
        if (!(phihat > 1e-30)) {
            rc = sasnav_set_error(SASNAV_ERR_INTERNAL, "op: kernel transform vanishes in band");
            break;
        }
        op->spectral[k + op->kmax] = (float)(sasnav_pulse_weight(&op->sys, k / op->period) / (norm * phihat));
    }
    free(xi);
    return rc;
}

/* Polynomial coefficients of the kernel taps (kernel.h), float, lane-padded. */
static int setup_taps(sasnav_op *op)
{
    op->tap_degree = sasnav_kernel_taps_degree(&op->kernel);
    size_t n = (size_t)(op->tap_degree + 1) * (size_t)op->wpad;
    double *coef = malloc(n * sizeof *coef);
    op->tap_coef = malloc(n * sizeof *op->tap_coef);
    if (!coef || !op->tap_coef) {
        free(coef);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "op: out of memory (taps)");
    }
    int rc = sasnav_kernel_fit_taps(&op->kernel, op->tap_degree, op->wpad, coef);
    for (size_t i = 0; i < n; i++) op->tap_coef[i] = (float)coef[i];
    free(coef);
    return rc;
}

/* The per-point and per-pair arrays for op->n_points points. */
static int setup_point_storage(sasnav_op *op)
{
    size_t np = (size_t)op->n_points;
    op->n_blocks = (int)((np + BLOCK - 1) / BLOCK);
    op->n_pairs = (size_t)op->n_blocks * BLOCK * (size_t)op->n_rx;
    op->x = malloc(np * sizeof *op->x);
    op->y = malloc(np * sizeof *op->y);
    op->tx_range = malloc(np * sizeof *op->tx_range);
    op->tx_gain = malloc(np * sizeof *op->tx_gain);
    op->index = calloc(op->n_pairs, sizeof *op->index);
    op->taps = calloc(op->n_pairs * (size_t)op->wpad, sizeof *op->taps);
    op->green = calloc(2 * op->n_pairs, sizeof *op->green);
    op->cap_points = op->n_points;
    if (!op->x || !op->y || !op->tx_range || !op->tx_gain || !op->index || !op->taps || !op->green)
        return sasnav_set_error(SASNAV_ERR_NOMEM, "op: out of memory (%zu pairs)", op->n_pairs);
    return SASNAV_OK;
}

static void free_point_storage(sasnav_op *op)
{
    free(op->x);
    free(op->y);
    free(op->tx_range);
    free(op->tx_gain);
    free(op->index);
    free(op->taps);
    free(op->green);
    op->x = op->y = op->tx_range = op->tx_gain = NULL;
    op->index = NULL;
    op->taps = op->green = NULL;
    op->cap_points = 0;
}

/* n floats of split fine grids and READ_PAD zeros after them (read, never
 * used, by interp_four_4's windows). */
static float *fine_grids(size_t n)
{
    float *f = fftwf_malloc((n + READ_PAD) * sizeof(float));
    if (f) memset(f + n, 0, READ_PAD * sizeof(float));
    return f;
}

static int setup_storage(sasnav_op *op)
{
    int rc = setup_point_storage(op);
    if (rc) return rc;
    size_t fine = (size_t)op->lf + (size_t)op->ext;
    op->adj_re = fine_grids(op->n_rx * fine);
    op->adj_im = fine_grids(op->n_rx * fine);
    op->work = calloc((size_t)op->nthreads, sizeof *op->work);
    if (!op->adj_re || !op->adj_im || !op->work)
        return sasnav_set_error(SASNAV_ERR_NOMEM, "op: out of memory (%zu pairs)", op->n_pairs);
    for (int t = 0; t < op->nthreads; t++) {
        op_work *w = &op->work[t];
        w->fine = fftwf_malloc(2 * (size_t)op->lf * sizeof(float));
        w->coarse = fftwf_malloc(2 * (size_t)op->mp * sizeof(float));
        if (!w->fine || !w->coarse)
            return sasnav_set_error(SASNAV_ERR_NOMEM, "op: out of memory (work buffers)");
    }
    return SASNAV_OK;
}

/* All plans in place on thread 0's buffers; other buffers come from
 * fftwf_malloc too, so they have the alignment the plans assume. */
static int setup_plans(sasnav_op *op)
{
    fftwf_complex *fine = (fftwf_complex *)op->work[0].fine;
    fftwf_complex *coarse = (fftwf_complex *)op->work[0].coarse;
    int ok;
#pragma omp critical(sasnav_fftw_planner)
    {
        op->fine_fwd = fftwf_plan_dft_1d(op->lf, fine, fine, FFTW_FORWARD, FFTW_ESTIMATE);
        op->fine_bwd = fftwf_plan_dft_1d(op->lf, fine, fine, FFTW_BACKWARD, FFTW_ESTIMATE);
        op->coarse_fwd = fftwf_plan_dft_1d(op->mp, coarse, coarse, FFTW_FORWARD, FFTW_ESTIMATE);
        op->coarse_bwd = fftwf_plan_dft_1d(op->mp, coarse, coarse, FFTW_BACKWARD, FFTW_ESTIMATE);
        ok = op->fine_fwd && op->fine_bwd && op->coarse_fwd && op->coarse_bwd;
    }
    if (!ok) return sasnav_set_error(SASNAV_ERR_FFT, "op: FFTW could not plan sizes %d/%d", op->mp, op->lf);
    return SASNAV_OK;
}

static void select_kernels(sasnav_op *op)
{
    size_t bytes = op->n_pairs * (sizeof(int32_t) + 2 * sizeof(float) + op->wpad * sizeof(float));
    int stream = bytes > STREAM_BYTES;
    switch (op->wpad) {
    case 4:
        op->spread = spread_4;
        op->spread2 = spread2_4;
        op->interp2 = interp2_4;
        op->interp = stream ? interp_stream_4 : interp_points_4;
        op->taps_eval = taps_4;
        break;
    case 8:
        op->spread = spread_8;
        op->spread2 = spread2_8;
        op->interp2 = interp2_8;
        op->interp = stream ? interp_stream_8 : interp_points_8;
        op->taps_eval = taps_8;
        break;
    case 12:
        op->spread = spread_12;
        op->spread2 = spread2_12;
        op->interp2 = interp2_12;
        op->interp = stream ? interp_stream_12 : interp_points_12;
        op->taps_eval = taps_12;
        break;
    default:
        op->spread = spread_16;
        op->spread2 = spread2_16;
        op->interp2 = interp2_16;
        op->interp = stream ? interp_stream_16 : interp_points_16;
        op->taps_eval = taps_16;
        break;
    }
}

int sasnav_op_create(const sasnav_system *sys, const sasnav_array *array, const sasnav_window *win,
                     int n_points, const double *x, const double *y, const sasnav_op_opts *opts,
                     sasnav_op **out)
{
    if (!out) return sasnav_set_error(SASNAV_ERR_ARG, "op: output pointer is NULL");
    *out = NULL;
    int rc = sasnav_system_check(sys);
    if (!rc) rc = sasnav_array_check(array);
    if (rc) return rc;
    if (!win) return sasnav_set_error(SASNAV_ERR_ARG, "op: window is NULL");
    if (!isfinite(win->t0) || win->n_samples < 1 || win->n_samples > MAX_SAMPLES)
        return sasnav_set_error(SASNAV_ERR_ARG, "op: bad window (t0 %g s, %d samples)", win->t0,
                                win->n_samples);
    rc = check_points(n_points, x, y);
    if (rc) return rc;
    sasnav_op_opts o;
    if (opts)
        o = *opts;
    else
        sasnav_op_default_opts(&o);
    rc = check_opts(&o);
    if (rc) return rc;

    sasnav_op *op = calloc(1, sizeof *op);
    if (!op) return sasnav_set_error(SASNAV_ERR_NOMEM, "op: out of memory");
    op->sys = *sys;
    op->array = *array;
    op->win = *win;
    op->n_points = n_points;
    op->n_rx = array->n_rx;
    op->n_samples = win->n_samples;
    op->nthreads = o.nthreads > 0 ? o.nthreads : omp_get_max_threads();
    if (op->nthreads < 1) op->nthreads = 1;
    rc = setup_grids(op, &o);
    if (!rc) rc = setup_storage(op);
    if (!rc) rc = setup_spectrum(op);
    if (!rc) rc = setup_taps(op);
    if (!rc) rc = setup_plans(op);
    if (rc) {
        sasnav_op_destroy(op);
        return rc;
    }
    memcpy(op->x, x, (size_t)n_points * sizeof *x);
    memcpy(op->y, y, (size_t)n_points * sizeof *y);
    select_kernels(op);
    *out = op;
    return SASNAV_OK;
}

int sasnav_op_set_points(sasnav_op *op, int n_points, const double *x, const double *y)
{
    if (!op) return sasnav_set_error(SASNAV_ERR_ARG, "op: NULL operator");
    int rc = check_points(n_points, x, y);
    if (rc) return rc;
    op->have_geometry = 0;
    if (n_points > op->cap_points) {
        free_point_storage(op);
        op->n_points = n_points;
        rc = setup_point_storage(op);
        if (rc) {
            free_point_storage(op);
            op->n_points = 0;
            return rc;
        }
    }
    op->n_points = n_points;
    op->n_blocks = (n_points + BLOCK - 1) / BLOCK;
    op->n_pairs = (size_t)op->n_blocks * BLOCK * (size_t)op->n_rx;
    memcpy(op->x, x, (size_t)n_points * sizeof *x);
    memcpy(op->y, y, (size_t)n_points * sizeof *y);
    select_kernels(op);
    return SASNAV_OK;
}

void sasnav_op_destroy(sasnav_op *op)
{
    if (!op) return;
#pragma omp critical(sasnav_fftw_planner)
    {
        if (op->fine_fwd) fftwf_destroy_plan(op->fine_fwd);
        if (op->fine_bwd) fftwf_destroy_plan(op->fine_bwd);
        if (op->coarse_fwd) fftwf_destroy_plan(op->coarse_fwd);
        if (op->coarse_bwd) fftwf_destroy_plan(op->coarse_bwd);
    }
    if (op->work) {
        for (int t = 0; t < op->nthreads; t++) {
            fftwf_free(op->work[t].fine);
            fftwf_free(op->work[t].coarse);
        }
        free(op->work);
    }
    fftwf_free(op->adj_re);
    fftwf_free(op->adj_im);
    fftwf_free(op->adj2_re);
    fftwf_free(op->adj2_im);
    free_point_storage(op);
    free(op->spectral);
    free(op->tap_coef);
    free(op);
}

/* ------------------------------------------------------------------------ */
/* Geometry (set_geometry). Written as plain arithmetic (no libm calls in the
 * per-pair loops) so that the compiler vectorises them. */

/* Nearest integer of |v| < 2^51 by the "magic number" trick (exact under
 * IEEE round-to-nearest; vectorises, unlike rint/floor in baseline x86-64, and
 * has no undefined float-to-int conversion for huge or non-finite v). */
#ifdef __FAST_MATH__
#error "op.c needs IEEE semantics (round_nearest); do not build it with -ffast-math"
#endif
static inline double round_nearest(double v)
{
    const double magic = 6755399441055744.0; /* 1.5 * 2^52 */
    return (v + magic) - magic;
}

/* sin(pi v) and cos(pi v): v = k + r with k the nearest integer, |r| <= 1/2;
 * Taylor polynomials of sin(pi r) (to degree 17) and cos(pi r) (to degree
 * 18), truncation below 5e-14 at |r| = 1/2; the sign (-1)^k. */
static inline void sincospi(double v, double *s, double *c)
{
    double k = round_nearest(v);
    double x = M_PI * (v - k), x2 = x * x;
    /* sin(x) = x (1 - x^2/3! + x^4/5! - ... + x^16/17!) */
    double sn = 1.0 / 355687428096000.0;   /* 1/17! */
    sn = sn * x2 - 1.0 / 1307674368000.0;  /* 1/15! */
    sn = sn * x2 + 1.0 / 6227020800.0;     /* 1/13! */
    sn = sn * x2 - 1.0 / 39916800.0;       /* 1/11! */
    sn = sn * x2 + 1.0 / 362880.0;         /* 1/9! */
    sn = sn * x2 - 1.0 / 5040.0;
    sn = sn * x2 + 1.0 / 120.0;
    sn = sn * x2 - 1.0 / 6.0;
    sn = (sn * x2 + 1.0) * x;
    /* cos(x) = 1 - x^2/2! + x^4/4! - ... + x^18/18! */
    double cs = -1.0 / 6402373705728000.0; /* 1/18! */
    cs = cs * x2 + 1.0 / 20922789888000.0; /* 1/16! */
    cs = cs * x2 - 1.0 / 87178291200.0;    /* 1/14! */
    cs = cs * x2 + 1.0 / 479001600.0;      /* 1/12! */
    cs = cs * x2 - 1.0 / 3628800.0;        /* 1/10! */
    cs = cs * x2 + 1.0 / 40320.0;
    cs = cs * x2 - 1.0 / 720.0;
    cs = cs * x2 + 1.0 / 24.0;
    cs = cs * x2 - 0.5;
    cs = cs * x2 + 1.0;
    double odd = k - 2.0 * round_nearest(0.5 * k); /* -1, 0 or 1 */
    double sign = odd != 0.0 ? -1.0 : 1.0;
    *s = sign * sn;
    *c = sign * cs;
}

/* Line-aperture pattern sinc(a) = sin(pi a) / (pi a), a = D sin(phi) / lambda,
 * sin(phi) = (unit vector element -> point) . (element axis). Written without
 * a branch on the result: q is used in both cases so that the compiler
 * cannot move the division into a branch. */
static inline double sinc_pi(double a)
{
    double s, c;
    sincospi(a, &s, &c);
    double pa = M_PI * a;
    double small = fabs(pa) < 1e-8 ? 1.0 : 0.0;
    double q = s / (small != 0.0 ? 1.0 : pa);
    return q * (1.0 - small) + small;
}

/* sqrt without errno handling (libm's sqrt keeps a branch for x < 0 that
 * stops vectorisation): Newton iterations on 1/sqrt(x) from a bit-level first
 * guess (error < 3.5 %, then 2e-3, 4e-6, 3e-11), and one correction of
 * x * y. Within 1 ulp of sqrt for every positive normal double (tested over
 * 1e-12 .. 1e12); sqrt_nr(0) = 0; NaN for inf or NaN. */
static inline double sqrt_nr(double x)
{
    uint64_t bits;
    memcpy(&bits, &x, sizeof bits);
    bits = 0x5FE6EB50C7B537A9ull - (bits >> 1);
    double y;
    memcpy(&y, &bits, sizeof y);
    double hx = 0.5 * x;
    y = y * (1.5 - hx * y * y);
    y = y * (1.5 - hx * y * y);
    y = y * (1.5 - hx * y * y);
    double r = x * y;
    return r + 0.5 * y * (x - r * r);
}

/* Spreading loss (SPEC 2) as c_exploding / sqrt(r_t + r_r) + c_spherical /
 * (r_t r_r) + c_none, with one coefficient 1 and the others 0. */
typedef struct {
    double exploding, spherical, none;
} attenuation_coefs;

static attenuation_coefs attenuation_model(sasnav_attenuation model)
{
    attenuation_coefs a = {0.0, 0.0, 0.0};
    if (model == SASNAV_ATTEN_SPHERICAL)
        a.spherical = 1.0;
    else if (model == SASNAV_ATTEN_NONE)
        a.none = 1.0;
    else
        a.exploding = 1.0;
    return a;
}

static int check_pose(sasnav_pose p)
{
    return isfinite(p.x) && isfinite(p.y) && isfinite(p.theta);
}

/* What set_geometry needs of one ping. */
typedef struct {
    double tx_x, tx_y, tx_cos, tx_sin, tx_aperture; /* aperture = D_t / lambda (0: omni) */
    double ar_x, ar_y, ar_cos, ar_sin, rx_aperture;
    double tx_height, rx_height;
} ping_geometry;

/* Tx range and pattern of points [n0, n1). Returns how many are closer than
 * MIN_SENSOR_DISTANCE to the Tx. */
HOT_LOOP static int setup_tx(sasnav_op *op, const ping_geometry *g, int n0, int n1)
{
    const double *restrict x = op->x, *restrict y = op->y;
    double *restrict range = op->tx_range, *restrict gain = op->tx_gain;
    double hz2 = g->tx_height * g->tx_height;
    const double min2 = MIN_SENSOR_DISTANCE * MIN_SENSOR_DISTANCE;
    int bad = 0;
#pragma omp simd reduction(+ : bad)
    for (int n = n0; n < n1; n++) {
        double dx = x[n] - g->tx_x, dy = y[n] - g->tx_y;
        double r2 = dx * dx + dy * dy + hz2;
        bad += !(r2 >= min2);
        double r = sqrt_nr(r2);
        range[n] = r;
        gain[n] = sinc_pi(g->tx_aperture * (dx * g->tx_cos + dy * g->tx_sin) / (r + 1e-300));
    }
    return bad;
}

/* Pairs of channel l and block b: delay (double), first fine index, kernel
 * offset, G. Returns the number of dropped pairs; *bad counts points closer
 * than MIN_SENSOR_DISTANCE to the receiver. Every quantity is computed for
 * every pair and dropped pairs are then zeroed by selects (vectorisable);
 * their values may be garbage (even NaN for absurd coordinates), never their
 * stored results. */
HOT_LOOP static long setup_block(sasnav_op *op, const ping_geometry *g, int l, int b, int *bad)
{
    int n0 = b * BLOCK, count = op->n_points - n0 < BLOCK ? op->n_points - n0 : BLOCK;
    size_t q0 = ((size_t)b * (size_t)op->n_rx + (size_t)l) * BLOCK;
    const double *restrict x = op->x + n0, *restrict y = op->y + n0;
    const double *restrict r_tx = op->tx_range + n0, *restrict gain_tx = op->tx_gain + n0;
    int32_t *restrict index = op->index + q0;
    float *restrict green = op->green + 2 * q0;
    float t[BLOCK], keep[BLOCK];
    double u_rx = op->array.rx_u[l];
    double xr = g->ar_x + u_rx * g->ar_cos, yr = g->ar_y + u_rx * g->ar_sin;
    double ar_cos = g->ar_cos, ar_sin = g->ar_sin, aperture = g->rx_aperture;
    double hz2 = g->rx_height * g->rx_height;
    const double min2 = MIN_SENSOR_DISTANCE * MIN_SENSOR_DISTANCE;
    double inv_c = 1.0 / op->sys.sound_speed, inv_h = 1.0 / op->h, two_f0 = 2.0 * op->sys.f0;
    double start = op->grid_start, half = 0.5 * op->kernel.width, u_max = op->lf - half;
    double v_max = u_max - half;
    attenuation_coefs att = attenuation_model(op->sys.attenuation);
    long dropped = 0;
    int near = 0;
#pragma omp simd reduction(+ : dropped, near)
    for (int i = 0; i < count; i++) {
        double dx = x[i] - xr, dy = y[i] - yr;
        double r2 = dx * dx + dy * dy + hz2;
        near += !(r2 >= min2);
        double r_r = sqrt_nr(r2), r_t = r_tx[i];
        double r_safe = r_r + 1e-300;
        double tau = (r_t + r_r) * inv_c;
        double u = (tau - start) * inv_h; /* fine-grid coordinate */
        int in = (u >= half) & (u <= u_max);
        dropped += !in;
        /* Kernel covers i0 .. i0 + w - 1, i0 = ceil(u - w/2) in [0, lf - w];
         * v is clamped so that the conversion is defined for any u. */
        double v = u - half;
        v = v > 0.0 ? v : 0.0;
        v = v < v_max ? v : v_max;
        double i0 = (double)(int32_t)v;
        i0 += i0 < v ? 1.0 : 0.0;
        index[i] = in ? (int32_t)i0 : 0;
        t[i] = (float)(2.0 * (i0 - v) - 1.0);
        keep[i] = in ? 1.0f : 0.0f;
        double pattern = sinc_pi(aperture * (dx * ar_cos + dy * ar_sin) / r_safe);
        double loss = att.exploding / sqrt_nr(r_t + r_safe) + att.spherical / (r_t * r_safe) +
                      att.none;
        double alpha = gain_tx[i] * pattern * loss;
        alpha = u >= half ? alpha : 0.0;
        alpha = u <= u_max ? alpha : 0.0;
        /* G = alpha exp(-j 2 pi f0 tau) = alpha (cos(pi 2 f0 tau) - j sin(...));
         * 2 f0 tau (~8000 at 10 m) is reduced in double inside sincospi. */
        double cycles = two_f0 * tau;
        cycles = u >= half ? cycles : 0.0;
        cycles = u <= u_max ? cycles : 0.0;
        double sn, cs;
        sincospi(cycles, &sn, &cs);
        green[2 * i] = (float)(alpha * cs);
        green[2 * i + 1] = (float)(-alpha * sn);
    }
    op->taps_eval(op, count, t, keep, op->taps + q0 * (size_t)op->wpad);
    *bad += near;
    return dropped;
}

/* Serial numbers of the geometries set by any operator (op_view.h). */
static atomic_ulong geometry_serial;

/* Index of the first point within MIN_SENSOR_DISTANCE of (sx, sy, height). */
static int find_near_point(const sasnav_op *op, double sx, double sy, double height)
{
    for (int n = 0; n < op->n_points; n++) {
        double dx = op->x[n] - sx, dy = op->y[n] - sy;
        if (!(sqrt(dx * dx + dy * dy + height * height) >= MIN_SENSOR_DISTANCE)) return n;
    }
    return 0;
}

static int geometry_error(const sasnav_op *op, const ping_geometry *g, int per_channel)
{
    for (int l = 0; l < op->n_rx; l++) {
        const ping_geometry *gl = &g[per_channel ? l : 0];
        if (l == 0 || per_channel) {
            int n = find_near_point(op, gl->tx_x, gl->tx_y, gl->tx_height);
            double dx = op->x[n] - gl->tx_x, dy = op->y[n] - gl->tx_y, h = gl->tx_height;
            if (!(sqrt(dx * dx + dy * dy + h * h) >= MIN_SENSOR_DISTANCE))
                return sasnav_set_error(SASNAV_ERR_GEOMETRY,
                                        "op: point %d (%g, %g) coincides with the Tx of channel %d",
                                        n, op->x[n], op->y[n], l);
        }
        double u = op->array.rx_u[l];
        double xr = gl->ar_x + u * gl->ar_cos, yr = gl->ar_y + u * gl->ar_sin;
        int n = find_near_point(op, xr, yr, gl->rx_height);
        double dx = op->x[n] - xr, dy = op->y[n] - yr, h = gl->rx_height;
        if (!(sqrt(dx * dx + dy * dy + h * h) >= MIN_SENSOR_DISTANCE))
            return sasnav_set_error(SASNAV_ERR_GEOMETRY,
                                    "op: point %d (%g, %g) coincides with receiver %d", n,
                                    op->x[n], op->y[n], l);
    }
    return sasnav_set_error(SASNAV_ERR_GEOMETRY, "op: a point coincides with a sensor");
}

/* Channel l's geometry (its sizes: sasnav_array_channel_size). */
static ping_geometry make_geometry(const sasnav_op *op, const sasnav_ping_pose *ping, int l)
{
    double lambda = sasnav_wavelength(&op->sys);
    int beams = op->sys.beam_pattern;
    sasnav_channel_size z = sasnav_array_channel_size(&op->array, l);
    ping_geometry g = {ping->tx.x, ping->tx.y, cos(ping->tx.theta), sin(ping->tx.theta),
                       beams ? z.tx_length / lambda : 0.0,
                       ping->array.x, ping->array.y, cos(ping->array.theta),
                       sin(ping->array.theta), beams ? z.rx_length / lambda : 0.0,
                       z.tx_height, z.rx_height};
    return g;
}

/* Whether two channels' transmitters give the same Tx range and pattern. */
static int same_tx(const ping_geometry *a, const ping_geometry *b)
{
    return a->tx_x == b->tx_x && a->tx_y == b->tx_y && a->tx_cos == b->tx_cos &&
           a->tx_sin == b->tx_sin && a->tx_aperture == b->tx_aperture &&
           a->tx_height == b->tx_height;
}

/* Geometry of every channel: poses[0] for all (one Tx, N Rx), or poses[l]
 * for channel l (per_channel); each channel with its sizes when the array
 * has sizes per channel. Channels are set up in runs of consecutive
 * channels that share a transmitter (pose, length and height): the Tx
 * range and pattern of each point are computed once per run (the one-Tx
 * case is one run). */
static int apply_geometry(sasnav_op *op, const sasnav_ping_pose *poses, int per_channel)
{
    int n_pose = per_channel ? op->n_rx : 1;
    for (int c = 0; c < n_pose; c++)
        if (!check_pose(poses[c].tx) || !check_pose(poses[c].array))
            return per_channel ? sasnav_set_error(SASNAV_ERR_ARG,
                                                  "op: pose of channel %d is not finite", c)
                               : sasnav_set_error(SASNAV_ERR_ARG, "op: ping pose is not finite");
    op->have_geometry = 0;
    per_channel = per_channel || op->array.per_channel;
    int n_geom = per_channel ? op->n_rx : 1;
    ping_geometry g[SASNAV_MAX_RX];
    for (int c = 0; c < n_geom; c++) g[c] = make_geometry(op, &poses[n_pose > 1 ? c : 0], c);
    long dropped = 0;
    for (int l0 = 0, l1; l0 < op->n_rx; l0 = l1) {
        l1 = op->n_rx;
        if (per_channel)
            for (l1 = l0 + 1; l1 < op->n_rx && same_tx(&g[l1], &g[l0]); l1++) {}
        int bad = 0, nl = l1 - l0, n_tasks = op->n_blocks * nl;
        const ping_geometry *gt = &g[per_channel ? l0 : 0];
#pragma omp parallel num_threads(op->nthreads) reduction(+ : dropped, bad)
        {
#pragma omp for schedule(dynamic, 4)
            for (int b = 0; b < op->n_blocks; b++) {
                int n0 = b * BLOCK, n1 = n0 + BLOCK < op->n_points ? n0 + BLOCK : op->n_points;
                bad += setup_tx(op, gt, n0, n1);
            }
#pragma omp for schedule(dynamic, 4)
            for (int task = 0; task < n_tasks; task++) {
                int l = l0 + task % nl;
                dropped += setup_block(op, &g[per_channel ? l : 0], l, task / nl, &bad);
            }
        }
        if (bad) return geometry_error(op, g, per_channel);
    }
    op->n_dropped = dropped;
    op->have_geometry = 1;
    op->serial = atomic_fetch_add(&geometry_serial, 1) + 1;
    return SASNAV_OK;
}

int sasnav_op_set_geometry(sasnav_op *op, const sasnav_ping_pose *ping)
{
    if (!op || !ping) return sasnav_set_error(SASNAV_ERR_ARG, "op: set_geometry with NULL argument");
    return apply_geometry(op, ping, 0);
}

int sasnav_op_set_channels(sasnav_op *op, const sasnav_ping_pose *channels)
{
    if (!op || !channels)
        return sasnav_set_error(SASNAV_ERR_ARG, "op: set_channels with NULL argument");
    return apply_geometry(op, channels, 1);
}

int sasnav_op_set_ping(sasnav_op *op, const sasnav_ping_pose *ping, const sasnav_ping_pose *offset)
{
    if (!op || !ping) return sasnav_set_error(SASNAV_ERR_ARG, "op: set_ping with NULL argument");
    if (!offset) return apply_geometry(op, ping, 0);
    sasnav_ping_pose ch[SASNAV_MAX_RX];
    sasnav_channel_poses(ping, offset, op->n_rx, ch);
    return apply_geometry(op, ch, 1);
}

/* ------------------------------------------------------------------------ */
/* Forward and adjoint. */

static void fft(fftwf_plan plan, float *buf)
{
    fftwf_execute_dft(plan, (fftwf_complex *)buf, (fftwf_complex *)buf);
}

/* Steps 2-4 for channel l, from its spread fine grid (re, im). */
static void forward_finish(const sasnav_op *op, float *restrict re, float *restrict im,
                           sasnav_cfloat *out, op_work *w)
{
    int lf = op->lf, mp = op->mp, ext = op->ext, kmax = op->kmax;
    float *restrict ff = w->fine, *restrict fc = w->coarse;
    for (int j = 0; j < ext; j++) { /* periodic wrap of the extension */
        re[j] += re[lf + j];
        im[j] += im[lf + j];
    }
    for (int j = 0; j < lf; j++) {
        ff[2 * j] = re[j];
        ff[2 * j + 1] = im[j];
    }
    fft(op->fine_fwd, ff);
    memset(fc, 0, 2 * (size_t)mp * sizeof(float));
    for (int k = -kmax; k <= kmax; k++) {
        int kf = k < 0 ? k + lf : k, kc = k < 0 ? k + mp : k;
        float r = op->spectral[k + kmax];
        fc[2 * kc] = r * ff[2 * kf];
        fc[2 * kc + 1] = r * ff[2 * kf + 1];
    }
    fft(op->coarse_bwd, fc);
    memcpy(out, fc + 2 * op->pad, (size_t)op->n_samples * sizeof(sasnav_cfloat));
}

/* Channels [l0, l1): spread block by block, so that the group's pair data
 * (adjacent in the layout) are read as one sequential stream, into the
 * per-channel grids op->adj_re/adj_im (free while T runs), then finish each
 * channel. (One channel at a time reads 2.8 kB pieces 45 kB apart, which the
 * prefetchers follow badly: 256 x 256 grids ran 2x slower.) With four taps,
 * four channels at a time (spread_four1_4, spread_four2_4). Each channel's
 * grid is summed in point order whatever the grouping, so results do not
 * depend on it. n = 2: a second image at once, into op->adj2_re/adj2_im
 * (spread2_W; op_team.h). */
static void forward_group(const sasnav_op *op, int n, int l0, int l1,
                          const sasnav_cfloat *const *rho, sasnav_cfloat *const *data, op_work *w)
{
    size_t fine = (size_t)op->lf + (size_t)op->ext;
    float *re[2] = {op->adj_re, op->adj2_re}, *im[2] = {op->adj_im, op->adj2_im};
    spread_run run[2][SASNAV_MAX_RX];
    for (int c = 0; c < n; c++) {
        memset(run[c], 0, (size_t)(l1 - l0) * sizeof run[c][0]);
        for (int l = l0; l < l1; l++) {
            memset(re[c] + (size_t)l * fine, 0, fine * sizeof(float));
            memset(im[c] + (size_t)l * fine, 0, fine * sizeof(float));
        }
    }
    for (int b = 0; b < op->n_blocks; b++) {
        int l = l0;
        if (op->wpad == 4)
            for (; l + 4 <= l1; l += 4) {
                if (n == 2)
                    spread_four2_4(op, l, b, rho, &run[0][l - l0], &run[1][l - l0]);
                else
                    spread_four1_4(op, l, b, rho, &run[0][l - l0]);
            }
        for (; l < l1; l++) {
            if (n == 2)
                op->spread2(op, l, b, rho[0], rho[1], &run[0][l - l0], &run[1][l - l0]);
            else
                op->spread(op, l, b, rho[0], re[0] + (size_t)l * fine, im[0] + (size_t)l * fine,
                           &run[0][l - l0]);
        }
    }
    for (int l = l0; l < l1; l++)
        for (int c = 0; c < n; c++) {
            float *gr = re[c] + (size_t)l * fine, *gi = im[c] + (size_t)l * fine;
            spread_flush(&run[c][l - l0], op->wpad, gr, gi);
            forward_finish(op, gr, gi, data[c] + (size_t)l * (size_t)op->n_samples, w);
        }
}

/* The transposed steps of the forward operator up to the fine grid, which is left
 * (split, with its periodic extension) in op->adj_re/adj_im for channel l. */
static void adjoint_channel_to(const sasnav_op *op, int l, const sasnav_cfloat *data, op_work *w,
                               float *re_base, float *im_base)
{
    int lf = op->lf, mp = op->mp, ext = op->ext, kmax = op->kmax;
    size_t fine = (size_t)lf + (size_t)ext;
    float *restrict ff = w->fine, *restrict fc = w->coarse;
    memset(fc, 0, 2 * (size_t)mp * sizeof(float));
    memcpy(fc + 2 * op->pad, data, (size_t)op->n_samples * sizeof(sasnav_cfloat));
    fft(op->coarse_fwd, fc);
    memset(ff, 0, 2 * (size_t)lf * sizeof(float));
    for (int k = -kmax; k <= kmax; k++) {
        int kf = k < 0 ? k + lf : k, kc = k < 0 ? k + mp : k;
        float r = op->spectral[k + kmax];
        ff[2 * kf] = r * fc[2 * kc];
        ff[2 * kf + 1] = r * fc[2 * kc + 1];
    }
    fft(op->fine_bwd, ff);
    float *restrict re = re_base + (size_t)l * fine, *restrict im = im_base + (size_t)l * fine;
    for (int j = 0; j < lf; j++) {
        re[j] = ff[2 * j];
        im[j] = ff[2 * j + 1];
    }
    for (int j = 0; j < ext; j++) {
        re[lf + j] = re[j];
        im[lf + j] = im[j];
    }
}

static void adjoint_channel(const sasnav_op *op, int l, const sasnav_cfloat *data, op_work *w)
{
    adjoint_channel_to(op, l, data, w, op->adj_re, op->adj_im);
}

static int check_apply(const sasnav_op *op, const void *in, const void *out)
{
    if (!op || !in || !out) return sasnav_set_error(SASNAV_ERR_ARG, "op: NULL argument");
    if (!op->have_geometry)
        return sasnav_set_error(SASNAV_ERR_ARG, "op: sasnav_op_set_geometry has not succeeded");
    return SASNAV_OK;
}

int sasnav_op_forward(sasnav_op *op, const sasnav_cfloat *rho, sasnav_cfloat *data)
{
    int rc = check_apply(op, rho, data);
    if (rc) return rc;
    /* One group of adjacent channels per thread. */
    int size = (op->n_rx + op->nthreads - 1) / op->nthreads;
    int n_groups = (op->n_rx + size - 1) / size;
#pragma omp parallel for num_threads(op->nthreads) schedule(dynamic, 1)
    for (int g = 0; g < n_groups; g++) {
        int l0 = g * size, l1 = l0 + size < op->n_rx ? l0 + size : op->n_rx;
        forward_group(op, 1, l0, l1, &rho, &data, &op->work[omp_get_thread_num()]);
    }
    return SASNAV_OK;
}

static int adjoint(sasnav_op *op, const sasnav_cfloat *data, sasnav_cfloat *rho, int accumulate)
{
    int rc = check_apply(op, data, rho);
    if (rc) return rc;
#pragma omp parallel num_threads(op->nthreads)
    {
        op_work *w = &op->work[omp_get_thread_num()];
#pragma omp for schedule(dynamic, 1)
        for (int l = 0; l < op->n_rx; l++)
            adjoint_channel(op, l, data + (size_t)l * (size_t)op->n_samples, w);
#pragma omp for schedule(dynamic, 4)
        for (int b = 0; b < op->n_blocks; b++) op->interp(op, b, rho, accumulate);
    }
    return SASNAV_OK;
}

int sasnav_op_adjoint(sasnav_op *op, const sasnav_cfloat *data, sasnav_cfloat *rho)
{
    return adjoint(op, data, rho, 0);
}

int sasnav_op_adjoint_add(sasnav_op *op, const sasnav_cfloat *data, sasnav_cfloat *rho)
{
    return adjoint(op, data, rho, 1);
}

/* ------------------------------------------------------------------------ */
/* Team applications (op_team.h). */

int op_team_prepare(sasnav_op *op)
{
    if (!op) return sasnav_set_error(SASNAV_ERR_ARG, "op: NULL argument");
    if (!op->have_geometry)
        return sasnav_set_error(SASNAV_ERR_ARG, "op: sasnav_op_set_geometry has not succeeded");
    if (!op->adj2_re) {
        size_t n = (size_t)op->n_rx * ((size_t)op->lf + (size_t)op->ext);
        op->adj2_re = fine_grids(n);
        op->adj2_im = fine_grids(n);
        if (!op->adj2_re || !op->adj2_im) {
            fftwf_free(op->adj2_re);
            fftwf_free(op->adj2_im);
            op->adj2_re = op->adj2_im = NULL;
            return sasnav_set_error(SASNAV_ERR_NOMEM, "op: out of memory (second fine grids)");
        }
    }
    return SASNAV_OK;
}

int op_threads(const sasnav_op *op) { return op ? op->nthreads : 0; }

/* This thread's share [*a, *b) of n items: contiguous, in thread order. */
static void team_share(int n, int *a, int *b)
{
    int nt = omp_get_num_threads(), t = omp_get_thread_num();
    int size = (n + nt - 1) / nt;
    *a = t * size < n ? t * size : n;
    *b = *a + size < n ? *a + size : n;
}

void op_forward_team(const sasnav_op *op, int n, const sasnav_cfloat *const *rho,
                     sasnav_cfloat *const *data)
{
    int l0, l1;
    team_share(op->n_rx, &l0, &l1);
    if (l0 < l1) forward_group(op, n, l0, l1, rho, data, &op->work[omp_get_thread_num()]);
#pragma omp barrier
}

void op_adjoint_team(const sasnav_op *op, int n, const sasnav_cfloat *const *data,
                     sasnav_cfloat *const *rho)
{
    int a, b;
    op_work *w = &op->work[omp_get_thread_num()];
    team_share(op->n_rx, &a, &b);
    for (int l = a; l < b; l++) {
        size_t off = (size_t)l * (size_t)op->n_samples;
        adjoint_channel_to(op, l, data[0] + off, w, op->adj_re, op->adj_im);
        if (n == 2) adjoint_channel_to(op, l, data[1] + off, w, op->adj2_re, op->adj2_im);
    }
#pragma omp barrier
    team_share(op->n_blocks, &a, &b);
    for (int k = a; k < b; k++) {
        if (n == 1) op->interp(op, k, rho[0], 0);
        else op->interp2(op, k, rho[0], rho[1]);
    }
#pragma omp barrier
}

/* ------------------------------------------------------------------------ */
/* Accessors. */

int sasnav_op_n_points(const sasnav_op *op) { return op ? op->n_points : 0; }
int sasnav_op_n_rx(const sasnav_op *op) { return op ? op->n_rx : 0; }
int sasnav_op_n_samples(const sasnav_op *op) { return op ? op->n_samples : 0; }
double sasnav_op_period(const sasnav_op *op) { return op ? op->period : 0.0; }
long sasnav_op_n_dropped(const sasnav_op *op) { return op ? op->n_dropped : 0; }

void sasnav_op_delay_span(const sasnav_op *op, double *first, double *last)
{
    /* setup_block keeps u = (tau - grid_start) / h in [w/2, lf - w/2]. */
    double half = 0.5 * op->kernel.width;
    *first = op->grid_start + half * op->h;
    *last = op->grid_start + (op->lf - half) * op->h;
}
int op_view_get(const sasnav_op *op, op_view *v)
{
    if (!op || !v) return sasnav_set_error(SASNAV_ERR_ARG, "op view: NULL argument");
    if (!op->have_geometry)
        return sasnav_set_error(SASNAV_ERR_ARG, "op view: sasnav_op_set_geometry has not succeeded");
    *v = (op_view){op->n_points, op->n_rx, op->n_samples, op->pad, op->mp, op->lf,
                          op->ext, op->wpad, op->kmax, op->n_blocks, op->n_pairs, op->index,
                          op->taps, op->green, op->spectral, op->serial};
    return SASNAV_OK;
}

int op_channel_geometry_get(const sasnav_op *op, const sasnav_ping_pose *poses,
                                   int per_channel, op_channel_geometry *out)
{
    if (!op || !poses || !out) return sasnav_set_error(SASNAV_ERR_ARG, "op: NULL argument");
    int n_pose = per_channel ? op->n_rx : 1;
    for (int c = 0; c < n_pose; c++)
        if (!check_pose(poses[c].tx) || !check_pose(poses[c].array))
            return sasnav_set_error(SASNAV_ERR_ARG, "op: pose of channel %d is not finite", c);
    /* as apply_geometry: one geometry for all channels unless per channel */
    int own = per_channel || op->array.per_channel;
    for (int l = 0; l < op->n_rx; l++) {
        ping_geometry g = make_geometry(op, &poses[n_pose > 1 ? l : 0], own ? l : 0);
        out[l] = (op_channel_geometry){g.tx_x, g.tx_y, g.tx_cos, g.tx_sin, g.tx_aperture,
                                              g.ar_x, g.ar_y, g.ar_cos, g.ar_sin, g.rx_aperture,
                                              g.tx_height, g.rx_height, op->array.rx_u[l]};
    }
    return SASNAV_OK;
}

int op_geometry_consts_get(const sasnav_op *op, op_geometry_consts *out)
{
    if (!op || !out) return sasnav_set_error(SASNAV_ERR_ARG, "op: NULL argument");
    /* the constants of setup_block */
    double half = 0.5 * op->kernel.width, u_max = op->lf - half;
    attenuation_coefs att = attenuation_model(op->sys.attenuation);
    *out = (op_geometry_consts){op->x, op->y, 1.0 / op->sys.sound_speed, 1.0 / op->h,
                                       2.0 * op->sys.f0, op->grid_start, half, u_max,
                                       u_max - half, att.exploding, att.spherical, att.none,
                                       op->tap_degree, op->tap_coef};
    return SASNAV_OK;
}

int sasnav_op_kernel_width(const sasnav_op *op) { return op ? op->kernel.width : 0; }
