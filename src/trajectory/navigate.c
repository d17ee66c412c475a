/* Navigation of a whole run: ping-pair estimates -> trajectory (paper
 * Section IV-C). See navigate.h for the contract. */
#include "sasnav/navigate.h"
#include "sasnav/error.h"
#include "sasnav/trajectory.h"
#include "core/clock.h"
#include "core/hash.h"
#include "trajectory/fuse.h"
#include "trajectory/pair_store.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void sasnav_navigate_default_opts(sasnav_navigate_opts *opts)
{
    if (!opts) return;
    memset(opts, 0, sizeof *opts);
    opts->method = SASNAV_METHOD_SUBSPACE;
    opts->long_baselines = 0;
    sasnav_pair_default_opts(&opts->pair);
    sasnav_dpca_default_opts(&opts->dpca);
    opts->link_sigma = (sasnav_pose){1e-3, 2e-5, 5e-5};
    opts->long_sigma = (sasnav_pose){2e-3, 4e-5, 1e-4};
    opts->link_eta = 0.2;
    opts->align = 1;
    opts->resolve = 1;
    opts->use_aiding = 1;
    opts->motion_sigma = (sasnav_pose){0.01, 0.01, 0.01};
    opts->eta_weight = 20.0;
    opts->aiding_gate = 5.0;
    opts->eta_outlier = 1.6;
    opts->speed_lags = 1;
    opts->aiding_bias_sigma = (sasnav_pose){4e-4, 4e-4, 0};
    opts->tx_yaw = 1;
    opts->nthreads = 0;
    opts->progress = NULL;
    opts->progress_user = NULL;
}

void sasnav_navigation_free(sasnav_navigation *nav)
{
    if (!nav) return;
    free(nav->pairs);
    if (nav->packed) {
        pair_store_free(nav->packed);
        free(nav->packed);
    }
    free(nav->centroids);
    free(nav->nav);
    free(nav->truth_centroids);
    free(nav->anchored);
    free(nav->cumulative);
    free(nav->differential);
    free(nav->formal_sigma);
    memset(nav, 0, sizeof *nav);
}

int sasnav_navigation_pair(const sasnav_navigation *nav, int j, sasnav_navigate_pair *np)
{
    if (!nav || !np) return sasnav_set_error(SASNAV_ERR_ARG, "navigation pair: NULL argument");
    if (j < 0 || j >= nav->n_pairs)
        return sasnav_set_error(SASNAV_ERR_ARG, "navigation pair %d does not exist (%d pairs)", j, nav->n_pairs);
    if (nav->pairs) *np = nav->pairs[j];
    else if (nav->packed) pair_store_get(nav->packed, j, np);
    else return sasnav_set_error(SASNAV_ERR_ARG, "navigation pair: the navigation holds no pairs");
    return SASNAV_OK;
}

static sasnav_pose pose_sub(sasnav_pose a, sasnav_pose b)
{
    return (sasnav_pose){a.x - b.x, a.y - b.y, sasnav_wrap_angle(a.theta - b.theta)};
}

static int sigma_ok(sasnav_pose s)
{
    return s.x > 0 && s.y > 0 && s.theta > 0 && isfinite(s.x) && isfinite(s.y) && isfinite(s.theta);
}

/* Along-axis positions of a ping's phase centres in its centroid frame:
 * u_l / 2 (EPCA model, one transmitter), or (Tx_l + Rx_l) / 2 of ping
 * 0's channels where the run has channel offsets. */
static void phase_centres(const sasnav_run *run, double *pc)
{
    if (!run->channel_offset) {
        for (int l = 0; l < run->array.n_rx; l++) pc[l] = 0.5 * run->array.rx_u[l];
        return;
    }
    sasnav_ping_pose ch[SASNAV_MAX_RX];
    sasnav_run_channel_poses(run, &run->nav[0], ch);
    sasnav_pose c = sasnav_ping_centroid(&run->nav[0]);
    for (int l = 0; l < run->array.n_rx; l++) {
        double rx, ry;
        sasnav_pose_apply(ch[l].array, run->array.rx_u[l], 0.0, &rx, &ry);
        sasnav_pose t = sasnav_pose_between(c, ch[l].tx), r = sasnav_pose_between(c, (sasnav_pose){rx, ry, 0});
        pc[l] = 0.5 * (t.x + r.x);
    }
}

/* Mean spacing of the sorted phase centres (0 for one). */
static double phase_centre_spacing(const double *pc, int n)
{
    double lo = INFINITY, hi = -INFINITY;
    for (int l = 0; l < n; l++) {
        lo = fmin(lo, pc[l]);
        hi = fmax(hi, pc[l]);
    }
    return n > 1 ? (hi - lo) / (n - 1) : 0.0;
}

/* Number of ping q's phase centres that nominally fall on ping p's, for an
 * along-track nominal displacement `along` (pc: phase_centres). */
static int overlapping_phase_centres(const double *pc, int n, double along)
{
    double lo = INFINITY, hi = -INFINITY;
    for (int l = 0; l < n; l++) {
        double v = pc[l];
        if (v < lo) lo = v;
        if (v > hi) hi = v;
    }
    const double tol = 1e-6;
    int k = 0;
    for (int l = 0; l < n; l++) {
        double v = along + pc[l];
        if (v >= lo - tol && v <= hi + tol) k++;
    }
    return k;
}

/* Codes that mean the navigation cannot go on (not a property of one pair;
 * unsupported: e.g. --gpu without a usable device). */
static int fatal_code(int rc)
{
    return rc == SASNAV_ERR_NOMEM || rc == SASNAV_ERR_FFT || rc == SASNAV_ERR_INTERNAL ||
           rc == SASNAV_ERR_UNSUPPORTED;
}

typedef struct {
    const sasnav_run *run;
    const sasnav_navigate_opts *opts;
    sasnav_pair **estimators; /* subspace: one per worker thread, reused */
    int n_workers;            /* threads over pairs (1: the operators use the threads) */
    double t0;
    double pc_spacing;        /* m, the array's phase-centre spacing */
    double *lags;             /* per-ping EPCA Tx-array offsets (m), or NULL:
                                 run->tx_lag for every ping */
    double *tx_yaw;           /* runs with channel offsets and a gyro: each
                                 ping's transmitter yaw relative to its
                                 array (sasnav_run_tx_yaw), or NULL */
    const sasnav_pair_record **done; /* opts->done sorted by key (NULL: none) */
    int n_done;
    uint64_t digest;          /* options_digest: the seed of every pair key */
    int part, n_parts;        /* sasnav_navigate_part: estimate pairs j with
                                 j % n_parts == part only (n_parts 1: all) */
    uint64_t *keys;           /* per output pair: its key (part mode), or NULL */
    sasnav_cfloat *bufs;      /* streamed runs: two pings per worker, or NULL */
    pair_store pairs;         /* the pairs while the navigation runs, packed */
    int two_pass;             /* opts.speed_lags 2: the first pass without the
                                 final stage (sasnav_pair_estimate_first),
                                 the offsets, then the final stages */
    double *post_buf;         /* the smoother's last system (9 x pairs), or NULL */
    fuse_posterior post;      /* ... its arrays (resolve_pairs) */
} nav_ctx;

/* Pair j, unpacked / packed again (pair_store.h). */
static void get_pair(const nav_ctx *ctx, int j, sasnav_navigate_pair *np) { pair_store_get(&ctx->pairs, j, np); }
static int put_pair(nav_ctx *ctx, int j, const sasnav_navigate_pair *np) { return pair_store_put(&ctx->pairs, j, np); }

/* Pings p and q of the run: pointers into it (in-memory run) or read into
 * worker t's buffers (streamed run: only the pings in flight are held). */
static int load_pair(const nav_ctx *ctx, int t, int p, int q, const sasnav_cfloat **dp,
                     const sasnav_cfloat **dq)
{
    size_t n = sasnav_run_ping_size(ctx->run);
    sasnav_cfloat *b = ctx->bufs ? ctx->bufs + 2 * (size_t)t * n : NULL;
    int rc = sasnav_run_get_ping(ctx->run, p, b, dp);
    if (!rc) rc = sasnav_run_get_ping(ctx->run, q, b ? b + n : NULL, dq);
    return rc;
}

/* The estimator's data: pair (p, q) through worker t's buffers, with the
 * per-ping offsets when in use. */
static int set_pair_data(const nav_ctx *ctx, int t, sasnav_pair *est, int p, int q, sasnav_pose nominal)
{
    const sasnav_cfloat *dp, *dq;
    int rc = load_pair(ctx, t, p, q, &dp, &dq);
    if (rc) return rc;
    return ctx->lags && !ctx->run->channel_offset
               ? sasnav_pair_set_data_lags(est, dp, dq, nominal, ctx->lags[p], ctx->lags[q])
               : sasnav_pair_set_data_run(est, ctx->run, p, q, dp, dq, nominal, ctx->tx_yaw);
}

static uint64_t hash_ints(uint64_t h, const int *v, int n)
{
    for (int j = 0; j < n; j++) {
        int64_t x = v[j];
        h = sasnav_hash_bytes(h, &x, sizeof x);
    }
    return h;
}

/* Digest of everything in the options and the array that a pair's first
 * estimate depends on (field by field: no padding bytes; thread counts
 * left out, they do not change the bits). */
static uint64_t options_digest(const sasnav_run *run, const sasnav_navigate_opts *o)
{
    uint64_t h = SASNAV_HASH_INIT;
    const sasnav_array *a = &run->array;
    h = hash_ints(h, &a->n_rx, 1);
    h = sasnav_hash_doubles(h, a->rx_u, a->n_rx);
    const double ad[4] = {a->rx_length, a->tx_length, a->rx_height, a->tx_height};
    h = sasnav_hash_doubles(h, ad, 4);
    for (int l = 0; a->per_channel && l < a->n_rx; l++) {
        const double z[4] = {a->size[l].rx_length, a->size[l].tx_length, a->size[l].rx_height,
                             a->size[l].tx_height};
        h = sasnav_hash_doubles(h, z, 4);
    }
    const int mi[1] = {(int)o->method};
    h = hash_ints(h, mi, 1);
    if (o->method == SASNAV_METHOD_SUBSPACE) {
        const sasnav_pair_opts *po = &o->pair;
        const int pi[9] = {po->k, po->i, po->coarse_k, po->coarse_i, (int)po->norm, po->fix_yaw,
                           po->global_stage, po->max_evaluations, po->op.pad_samples};
        h = hash_ints(h, pi, 9);
        /* the search's grid (keys of earlier versions were made with the
         * full-pixel search, SASNAV_SEARCH_FINE, and stay theirs) */
        const int gr[1] = {po->search_grid};
        if (po->search_grid != SASNAV_SEARCH_FINE) h = hash_ints(h, gr, 1);
        const double pd[31] = {po->tikhonov, po->range_extent, po->cross_extent, po->pixel,
                               po->coarse_pixel, po->blur, po->blur_cross, po->prior.x, po->prior.y,
                               po->prior.theta, po->box.x, po->box.y, po->box.theta, po->yaw_sigma,
                               po->surge_sigma, po->grid_step.x, po->grid_step.y, po->grid_step.theta,
                               po->error_extent, po->error_taper, po->min_overlap,
                               po->verdict_eta_max, po->verdict_margin_min, po->op.tolerance,
                               po->op.oversampling, po->verdict_coincidence, po->verdict_margin_compact, po->verdict_contrast, po->joint_coverage_min, po->equalise, 0};
        h = sasnav_hash_doubles(h, pd, 31);
        /* the final stage's criterion and the joint misfit's settings (the
         * verdict's contrast gate, the coverage rule and the equalising length
         * are in pd above); keys of
         * earlier versions, which left them out, were made with the
         * defaults and stay theirs */
        sasnav_pair_opts def;
        sasnav_pair_default_opts(&def);
        if (po->final_criterion != def.final_criterion || po->joint_k != def.joint_k ||
            po->joint_mu != def.joint_mu || po->joint_shift_max != def.joint_shift_max ||
            po->joint_contrast_max != def.joint_contrast_max || po->joint_eta_ratio != def.joint_eta_ratio) {
            const double fd[6] = {(double)po->final_criterion, (double)po->joint_k, po->joint_mu,
                                  po->joint_shift_max, po->joint_contrast_max, po->joint_eta_ratio};
            h = sasnav_hash_doubles(h, fd, 6);
        }
        /* GPU estimates agree with the CPU's to float rounding, not to the
         * bit: a checkpoint of one is not resumed by the other (CPU keys
         * are those of earlier versions) */
        const int gi[1] = {po->gpu};
        if (po->gpu) h = hash_ints(h, gi, 1);
    } else if (o->method == SASNAV_METHOD_DPCA) {
        const sasnav_dpca_opts *d = &o->dpca;
        const int di[4] = {d->upsampling, d->use_phase, d->unwrap, d->bistatic_correction};
        h = hash_ints(h, di, 4);
        const double dd[4] = {d->range, d->half_width, d->max_sway, d->min_coherence};
        h = sasnav_hash_doubles(h, dd, 4);
    }
    return h;
}

/* Content key of pair (p, q): navigate.h, sasnav_pair_record. */
static uint64_t pair_key(const nav_ctx *ctx, int p, int q, const sasnav_cfloat *dp,
                         const sasnav_cfloat *dq)
{
    const sasnav_run *run = ctx->run;
    size_t n = (size_t)run->array.n_rx * (size_t)run->win.n_samples;
    uint64_t h = ctx->digest;
    int head[6] = {(int)ctx->opts->method, run->array.n_rx, run->win.n_samples, run->sys.beam_pattern,
                   (int)run->sys.taper, (int)run->sys.attenuation};
    h = sasnav_hash_bytes(h, head, sizeof head);
    if (ctx->opts->method == SASNAV_METHOD_DPCA) {
        /* DPCA's nominal step is (q - p) ping spacings, not the poses'. */
        const int steps = q - p;
        h = sasnav_hash_bytes(h, &steps, sizeof steps);
        h = sasnav_hash_double(h, run->ping_spacing);
    }
    const double sys[6] = {run->sys.sound_speed, run->sys.f0, run->sys.bandwidth,
                           run->sys.sample_rate, run->win.t0, run->range_of_interest};
    for (int j = 0; j < 6; j++) h = sasnav_hash_double(h, sys[j]);
    const int pings[2] = {p, q};
    const sasnav_cfloat *data[2] = {dp, dq};
    for (int k = 0; k < 2; k++) {
        int i = pings[k];
        h = sasnav_hash_words(h, data[k], n * sizeof(sasnav_cfloat));
        h = sasnav_hash_ping_poses(h, &run->nav[i], 1);
        h = sasnav_hash_double(h, ctx->lags ? ctx->lags[i] : run->tx_lag);
        if (ctx->tx_yaw) h = sasnav_hash_double(h, ctx->tx_yaw[i]);
    }
    if (run->channel_offset) h = sasnav_hash_ping_poses(h, run->channel_offset, run->array.n_rx);
    return h ? h : 1; /* 0 means "no key" in the progress report */
}

static int record_cmp(const void *a, const void *b)
{
    uint64_t x = (*(const sasnav_pair_record *const *)a)->key;
    uint64_t y = (*(const sasnav_pair_record *const *)b)->key;
    return x < y ? -1 : x > y;
}

/* The record of `key` in ctx->done, or NULL. */
static const sasnav_pair_record *find_record(const nav_ctx *ctx, uint64_t key)
{
    int lo = 0, hi = ctx->n_done - 1;
    while (lo <= hi) {
        int mid = lo + (hi - lo) / 2;
        uint64_t k = ctx->done[mid]->key;
        if (k == key) return ctx->done[mid];
        if (k < key) lo = mid + 1;
        else hi = mid - 1;
    }
    return NULL;
}

static int take_result(const nav_ctx *ctx, sasnav_navigate_pair *np, int rc);

/* A result given back by the caller (records, a reused navigation) is
 * read with its candidate count within the array (found by review). */
static void clamp_candidates(sasnav_pair_result *r)
{
    if (r->n_candidates < 0) r->n_candidates = 0;
    if (r->n_candidates > SASNAV_PAIR_MAX_CANDIDATES) r->n_candidates = SASNAV_PAIR_MAX_CANDIDATES;
    if (r->chosen >= r->n_candidates) r->chosen = r->n_candidates - 1;
}

/* Estimates pair (p, q) into *np (or takes it from ctx->done: *resumed
 * = 1). Returns a fatal code, else SASNAV_OK with np->status telling how
 * the pair went. *key: the pair's content key. */
static int estimate_pair(nav_ctx *ctx, int t, int j, int p, int q, sasnav_navigate_pair *np,
                         uint64_t *key, int *resumed)
{
    sasnav_pair *estimator = ctx->estimators ? ctx->estimators[t] : NULL;
    const sasnav_run *run = ctx->run;
    memset(np, 0, sizeof *np);
    np->p = p;
    np->q = q;
    np->nominal = sasnav_ping_displacement(&run->nav[p], &run->nav[q]);
    if (run->truth) {
        sasnav_pose d = sasnav_ping_displacement(&run->truth[p], &run->truth[q]);
        np->truth = pose_sub(d, np->nominal);
    }
    const sasnav_cfloat *dp, *dq;
    int rc = load_pair(ctx, t, p, q, &dp, &dq); /* a ping that cannot be read stops the run */
    if (rc) return rc;
    *key = pair_key(ctx, p, q, dp, dq);
    *resumed = 0;
    const sasnav_pair_record *rec = ctx->n_done > 0 ? find_record(ctx, *key) : NULL;
    if (rec) {
        np->result = rec->result;
        clamp_candidates(&np->result);
        np->status = rec->status;
        np->first_result = np->result;
        np->first_status = np->status;
        if (run->truth) np->error = pose_sub(np->result.error, np->truth);
        *resumed = 1;
        return SASNAV_OK;
    }
    const sasnav_navigation *reuse = ctx->opts->reuse;
    if (reuse) {
        /* The earlier estimate of the same pair: at the same place in the
         * output order when the runs are the same, else searched. */
        sasnav_navigate_pair old;
        int found = j < reuse->n_pairs && !sasnav_navigation_pair(reuse, j, &old) && old.p == p && old.q == q;
        for (int i = 0; i < reuse->n_pairs && !found; i++)
            found = !sasnav_navigation_pair(reuse, i, &old) && old.p == p && old.q == q;
        if (!found) return sasnav_set_error(SASNAV_ERR_ARG, "navigate: the reused navigation has no pair %d-%d", p, q);
        np->result = old.first_result;
        clamp_candidates(&np->result);
        np->status = old.first_status;
        np->first_result = np->result;
        np->first_status = np->status;
        if (run->truth) np->error = pose_sub(np->result.error, np->truth);
        return SASNAV_OK;
    }
    if (ctx->opts->method == SASNAV_METHOD_AIDING) {
        rc = SASNAV_OK; /* (the verdict: resolve_pairs, from the aiding) */
        np->result.status = SASNAV_OK;
        np->result.verdict = SASNAV_VERDICT_OK;
        np->result.displacement = np->nominal;
        np->result.margin = INFINITY;
    } else if (ctx->opts->method == SASNAV_METHOD_DPCA) {
        sasnav_dpca_opts o = ctx->opts->dpca;
        o.nthreads = ctx->opts->nthreads;
        if (run->raw) {
            rc = sasnav_dpca_estimate(run, p, q, &o, &np->result, NULL);
        } else {
            /* A streamed run: the two pings (in worker t's buffers, one
             * after the other) as a two-ping run; DPCA reads only them and
             * the run's constants (its nominal step: 1 x (q - p) spacings). */
            sasnav_run two = *run;
            sasnav_ping_pose nav2[2] = {run->nav[p], run->nav[q]};
            two.raw = (sasnav_cfloat *)dp;
            two.n_pings = 2;
            two.nav = nav2;
            two.truth = NULL;
            two.aiding = NULL;
            memset(&two.source, 0, sizeof two.source);
            two.ping_spacing = run->ping_spacing * (double)(q - p);
            rc = sasnav_dpca_estimate(&two, 0, 1, &o, &np->result, NULL);
        }
    } else {
        double t0 = sasnav_now_seconds();
        rc = ctx->lags && !run->channel_offset
                 ? sasnav_pair_set_data_lags(estimator, dp, dq, np->nominal, ctx->lags[p], ctx->lags[q])
                 : sasnav_pair_set_data_run(estimator, run, p, q, dp, dq, np->nominal, ctx->tx_yaw);
        if (!rc) rc = ctx->two_pass ? sasnav_pair_estimate_first(estimator, &np->result)
                                    : sasnav_pair_estimate(estimator, &np->result);
        if (rc) np->result.seconds = sasnav_now_seconds() - t0;
    }
    return take_result(ctx, np, rc);
}

/* Pair np's estimate after the estimator returned rc: fatal codes are
 * returned; otherwise an estimate that failed (or found no overlap)
 * becomes the nominal displacement, flagged. */
static int take_result(const nav_ctx *ctx, sasnav_navigate_pair *np, int rc)
{
    const sasnav_run *run = ctx->run;
    if (fatal_code(rc)) return rc;
    if (!rc && np->result.status == SASNAV_ERR_NO_OVERLAP) rc = SASNAV_ERR_NO_OVERLAP;
    if (rc) {
        /* No usable estimate: nominal displacement, flagged. */
        double seconds = np->result.seconds;
        memset(&np->result, 0, sizeof np->result);
        np->result.status = rc;
        /* not "ok" (0): passes that read the first verdict must skip it */
        np->result.verdict = rc == SASNAV_ERR_NO_OVERLAP ? SASNAV_VERDICT_NO_OVERLAP : SASNAV_VERDICT_FAILED;
        np->result.displacement = np->nominal;
        np->result.seconds = seconds;
        np->status = rc;
    } else {
        np->status = np->result.status;
    }
    if (run->truth) np->error = pose_sub(np->result.error, np->truth);
    np->first_result = np->result;
    np->first_status = np->status;
    return SASNAV_OK;
}

static void report(nav_ctx *ctx, int done, int total, const sasnav_navigate_pair *np,
                   uint64_t key, int resumed)
{
    if (!ctx->opts->progress) return;
    sasnav_navigate_progress pr = {done, total, np ? np->p : -1, np ? np->q : -1,
                                   np ? np->status : SASNAV_OK, np ? &np->result : NULL,
                                   sasnav_now_seconds() - ctx->t0, key, resumed};
    ctx->opts->progress(&pr, ctx->opts->progress_user);
}

static int check_input(const sasnav_run *run, const sasnav_navigate_opts *o)
{
    if (!run) return sasnav_set_error(SASNAV_ERR_ARG, "navigate: NULL run");
    int rc = sasnav_run_check(run);
    if (rc) return rc;
    if (run->n_pings < 2)
        return sasnav_set_error(SASNAV_ERR_ARG, "navigate: the run needs at least 2 pings (has %d)",
                                run->n_pings);
    if (o->method != SASNAV_METHOD_SUBSPACE && o->method != SASNAV_METHOD_DPCA &&
        o->method != SASNAV_METHOD_AIDING)
        return sasnav_set_error(SASNAV_ERR_ARG, "navigate: unknown method %d", (int)o->method);
    if (o->method == SASNAV_METHOD_DPCA && run->channel_offset)
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "navigate: DPCA pairs the receivers of one transmitter; this run's channels "
                                "have transmitters of their own (use the subspace method)");
    if (o->method == SASNAV_METHOD_AIDING && (!run->aiding || !o->use_aiding || !o->resolve))
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "navigate: navigation by aiding alone needs a run with aiding "
                                "measurements (and aiding and resolution enabled)");
    if (o->method == SASNAV_METHOD_AIDING && (!run->aiding->yaw_rate || !run->aiding->velocity))
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "navigate: navigation by aiding alone needs a gyro (yaw rate) and a DVL "
                                "(velocity); this run's aiding has no %s (the subspace method uses what "
                                "there is)",
                                run->aiding->yaw_rate   ? "velocity"
                                : run->aiding->velocity ? "yaw rate"
                                                        : "yaw rate or velocity");
    if (o->method == SASNAV_METHOD_AIDING && o->long_baselines)
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "navigate: navigation by aiding alone has no long baselines (the aiding "
                                "measures consecutive pings' steps only)");
    if (!(o->aiding_bias_sigma.x >= 0) || !(o->aiding_bias_sigma.y >= 0) ||
        !(o->aiding_bias_sigma.theta >= 0) ||
        !isfinite(o->aiding_bias_sigma.x + o->aiding_bias_sigma.y + o->aiding_bias_sigma.theta))
        return sasnav_set_error(SASNAV_ERR_ARG, "navigate: aiding bias standard deviations must be finite and >= 0");
    if (o->speed_lags < 0 || o->speed_lags > 2)
        return sasnav_set_error(SASNAV_ERR_ARG, "navigate: speed_lags must be 0, 1 or 2");
    if (o->tx_yaw < 0 || o->tx_yaw > 2) return sasnav_set_error(SASNAV_ERR_ARG, "navigate: tx_yaw must be 0, 1 or 2");
    if (o->reuse && (o->reuse->method != o->method || o->reuse->n_pings != run->n_pings ||
                     (!o->reuse->pairs && !o->reuse->packed)))
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "navigate: the navigation to reuse is of another method or run");
    if (o->n_done < 0 || (o->n_done > 0 && !o->done))
        return sasnav_set_error(SASNAV_ERR_ARG, "navigate: %d earlier pairs given without records", o->n_done);
    if (!sigma_ok(o->link_sigma) || !sigma_ok(o->long_sigma))
        return sasnav_set_error(SASNAV_ERR_ARG, "navigate: link standard deviations must be > 0");
    if (!(o->link_eta >= 0)) /* (NaN too; +inf is off) */
        return sasnav_set_error(SASNAV_ERR_ARG, "navigate: link_eta must be >= 0 (0 or +inf: off)");
    if (o->nthreads < 0) return sasnav_set_error(SASNAV_ERR_ARG, "navigate: nthreads < 0");
    if (o->resolve && (!sigma_ok(o->motion_sigma) || !(o->eta_weight >= 0) ||
                       !isfinite(o->eta_weight) || !(o->aiding_gate > 0)))
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "navigate: motion standard deviations must be > 0, the eta weight "
                                ">= 0 and the aiding gate > 0");
    if (!(o->eta_outlier > 1)) /* (NaN too) */
        return sasnav_set_error(SASNAV_ERR_ARG, "navigate: the eta outlier factor must be > 1 (+inf: off)");
    if (o->method == SASNAV_METHOD_SUBSPACE && !(run->range_of_interest > 0))
        return sasnav_set_error(SASNAV_ERR_ARG, "navigate: the run has no range of interest");
    if (!(run->tx_lag >= 0) || !isfinite(run->tx_lag))
        return sasnav_set_error(SASNAV_ERR_ARG, "navigate: the run's Tx-array offset is invalid");
    return SASNAV_OK;
}

/* Whether the pairs' own speed-scaled offsets are wanted (opts.speed_lags
 * 2, subspace, no DVL to take them from, one Tx per ping, no reused
 * navigation): then the first pass stops before the final stage, and the
 * final stages run once the offsets are known (docs/navigation.md, "Two
 * passes"). */
static int two_pass_mode(const sasnav_run *run, const sasnav_navigate_opts *o)
{
    int dvl = run->aiding && run->aiding->velocity && o->use_aiding;
    return o->speed_lags == 2 && o->method == SASNAV_METHOD_SUBSPACE && !dvl && !o->reuse && !run->channel_offset;
}

/* Estimates all pairs into ctx->pairs (allocated). */
static int estimate_all(nav_ctx *ctx, sasnav_navigation *out)
{
    const sasnav_run *run = ctx->run;
    int n = run->n_pings;
    int n_long = ctx->opts->long_baselines ? n - 2 : 0;
    if (n_long < 0) n_long = 0;
    /* Decide which long baselines can be estimated at all. */
    int total = n - 1;
    char *use_long = calloc((size_t)(n_long > 0 ? n_long : 1), 1);
    if (!use_long) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    double pc[SASNAV_MAX_RX];
    phase_centres(run, pc);
    for (int p = 0; p < n_long; p++) {
        sasnav_pose nom = sasnav_ping_displacement(&run->nav[p], &run->nav[p + 2]);
        if (overlapping_phase_centres(pc, run->array.n_rx, nom.x) >= 2) {
            use_long[p] = 1;
            total++;
        } else {
            out->n_skipped++;
        }
    }
    if (pair_store_init(&ctx->pairs, total)) {
        free(use_long);
        return SASNAV_ERR_NOMEM;
    }
    /* The pairs in their output order: consecutive pairs, then the long
     * baselines. */
    int *pq = malloc(sizeof(int) * 2 * (size_t)total);
    int *codes = calloc((size_t)total, sizeof(int));
    if (!pq || !codes) {
        free(pq);
        free(codes);
        free(use_long);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    }
    int k = 0;
    for (int p = 0; p + 1 < n; p++, k++) {
        pq[2 * k] = p;
        pq[2 * k + 1] = p + 1;
    }
    for (int p = 0; p < n_long; p++)
        if (use_long[p]) {
            pq[2 * k] = p;
            pq[2 * k + 1] = p + 2;
            k++;
        }
    /* The pairs this call estimates: all, or those of its part. */
    int *mine = malloc(sizeof(int) * (size_t)total);
    if (!mine) {
        free(pq);
        free(codes);
        free(use_long);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    }
    int n_mine = 0;
    for (int j = 0; j < total; j++)
        if (j % ctx->n_parts == ctx->part) mine[n_mine++] = j;
    report(ctx, 0, n_mine, NULL, 0, 0);
    double t_est = sasnav_now_seconds();
    /* Independent pairs run concurrently, one estimator per thread; each
     * pair's result depends on its own data only (the operators sum in a
     * fixed order whatever their thread count), so the output is the same
     * bits whatever the number of threads. A fatal error stops the
     * remaining pairs; the message of the first in the output order is
     * kept. */
    int done = 0, stop = 0, first_failed = total;
    char message[256] = "";
#pragma omp parallel for schedule(dynamic, 1) num_threads(ctx->n_workers) if (ctx->n_workers > 1)
    for (int m = 0; m < n_mine; m++) {
        int j = mine[m];
        int skip;
#pragma omp atomic read
        skip = stop;
        if (skip) continue;
        int t = ctx->n_workers > 1 ? omp_get_thread_num() : 0;
        uint64_t key = 0;
        int resumed = 0;
        sasnav_navigate_pair np;
        int rc = estimate_pair(ctx, t, j, pq[2 * j], pq[2 * j + 1], &np, &key, &resumed);
        if (!rc) rc = put_pair(ctx, j, &np);
        if (ctx->keys) ctx->keys[j] = key;
        codes[j] = rc;
        if (rc) {
#pragma omp critical(sasnav_navigate_failure)
            if (j < first_failed) {
                first_failed = j;
                snprintf(message, sizeof message, "%s", sasnav_last_error());
            }
#pragma omp atomic write
            stop = 1;
        } else {
#pragma omp critical(sasnav_navigate_progress)
            {
                done++;
                report(ctx, done, n_mine, &np, key, resumed);
            }
        }
    }
    out->seconds_estimation = sasnav_now_seconds() - t_est;
    out->pairs_per_second = out->seconds_estimation > 0 ? n_mine / out->seconds_estimation : 0.0;
    free(mine);
    int rc = first_failed < total ? sasnav_set_error(codes[first_failed], "%s", message) : SASNAV_OK;
    free(pq);
    free(codes);
    free(use_long);
    out->n_pairs = k;
    for (int j = 0; j < k; j++) {
        sasnav_navigate_pair np;
        get_pair(ctx, j, &np);
        int st = np.status;
        if (st != SASNAV_OK && st != SASNAV_ERR_NOT_CONVERGED) out->n_failed++;
        out->seconds_pairs += np.result.seconds;
    }
    out->seconds_per_pair = k > 0 ? out->seconds_pairs / k : 0.0;
    return rc;
}

const char *sasnav_resolution_name(int resolution)
{
    switch (resolution) {
    case SASNAV_RESOLVED_NONE: return "kept";
    case SASNAV_RESOLVED_CANDIDATE: return "candidate";
    case SASNAV_RESOLVED_REESTIMATED: return "re-estimated";
    case SASNAV_RESOLVED_BRIDGED: return "bridged";
    default: return "unknown";
    }
}

static int usable(const sasnav_navigate_pair *np)
{
    return np->status == SASNAV_OK || np->status == SASNAV_ERR_NOT_CONVERGED;
}

/* Half a slip: half a phase-centre spacing of surge, its yaw at the
 * range of interest (x and theta; y unused). */
static sasnav_pose half_slip(const nav_ctx *ctx)
{
    double d = ctx->pc_spacing, r = ctx->run->range_of_interest > 0 ? ctx->run->range_of_interest : 1.0;
    return (sasnav_pose){0.5 * d, 0.0, 0.5 * d / r};
}

/* Whether an estimate u agrees with the aiding v (standard deviations sa)
 * in surge and yaw, the directions of a phase-centre slip: within half a
 * slip (d / 2 of surge, d / (2 R) of yaw, d the phase-centre spacing, R
 * the range of interest) plus `gate` standard deviations of the aiding.
 * Half a slip is above the estimator's own spread (surge ~1 mm, yaw ~2e-4
 * rad on extended scenes, up to 7e-4 rad on a point target) and a slip
 * exceeds it on both axes. Components without aiding always agree. */
static int agrees(const nav_ctx *ctx, sasnav_pose u, sasnav_pose v, sasnav_pose sa)
{
    double gate = ctx->opts->aiding_gate;
    sasnav_pose h = half_slip(ctx);
    if (isfinite(sa.x) && fabs(u.x - v.x) > h.x + gate * sa.x) return 0;
    if (isfinite(sa.theta) && fabs(u.theta - v.theta) > h.theta + gate * sa.theta) return 0;
    return 1;
}

/* The aiding can settle a pair's ambiguity (or confirm an estimate
 * without verdict) only where its own gate, gate x sigma, is narrower than
 * half a slip in surge and in yaw: a coarser aiding "agrees" with a
 * slipped candidate as well (found by review). */
static int aiding_settles(const nav_ctx *ctx, sasnav_pose sa)
{
    double gate = ctx->opts->aiding_gate;
    sasnav_pose h = half_slip(ctx);
    return isfinite(sa.x) && isfinite(sa.theta) && gate * sa.x < h.x && gate * sa.theta < h.theta;
}

/* Makes a new estimate r of the pair its result: the new values, the
 * first estimate's candidates, ambiguity and margin (what the data
 * offered), time and cost added. */
static void adopt_estimate(sasnav_navigate_pair *np, sasnav_pair_result *r)
{
    sasnav_pair_result_carry(&np->result, r);
    np->result = *r;
}

/* A new estimate of pair j from `start` (subspace only), kept when its eta
 * is lower than the present one's (or the present one failed) and, with
 * aiding, it agrees with the aiding. Returns a fatal code or OK; *taken
 * tells whether it replaced the result. */
static int reestimate(nav_ctx *ctx, sasnav_navigate_pair *np, sasnav_pose start, sasnav_pose a,
                      sasnav_pose sa, int require_lower, int *taken)
{
    *taken = 0;
    if (!ctx->estimators) return SASNAV_OK;
    sasnav_pair *est = ctx->estimators[0];
    sasnav_pair_result r;
    int rc = set_pair_data(ctx, 0, est, np->p, np->q, np->nominal);
    if (!rc) rc = sasnav_pair_estimate_from(est, start, &r);
    if (fatal_code(rc)) return rc;
    if (rc || r.status == SASNAV_ERR_NO_OVERLAP) return SASNAV_OK;
    /* With aiding, a new estimate may be up to the verdict's margin worse
     * in eta than the first (the data could not tell the two apart: that
     * is what the aiding is for); without, it must be lower. The margin
     * is verdict_margin_min on every scene, also where a compact one's
     * verdict asks verdict_margin_compact: the stricter choice here. */
    double tol = isfinite(sa.x + sa.theta) ? ctx->opts->pair.verdict_margin_min : 1.0;
    int better = !usable(np) || !require_lower || r.eta < tol * np->result.eta;
    if (!better || !agrees(ctx, r.error, a, sa)) return SASNAV_OK;
    adopt_estimate(np, &r);
    np->status = r.status;
    *taken = 1;
    return SASNAV_OK;
}

/* The graver of two verdicts (sasnav_verdict_rank). */
static int worse(int a, int b) { return sasnav_verdict_rank(a) >= sasnav_verdict_rank(b) ? a : b; }

/* An estimate the motion model may lean on: ok, or a method's without
 * verdict (DPCA) that nothing contradicts. */
static int leanable(const sasnav_navigate_pair *np)
{
    return (np->verdict == SASNAV_VERDICT_OK || np->verdict == SASNAV_VERDICT_UNCHECKED) &&
           np->resolution != SASNAV_RESOLVED_BRIDGED;
}

/* A pair at a phase-centre coincidence on a compact scene: its surge
 * deviation in the smoother over an "ok" pair's. On 1,416 simulated tank
 * pairs (docs/validation.md, "Flagged pairs") the surge errors of such
 * pairs were 1.28 mm median / 5.52 mm p95 against 0.46 / 1.93 mm for the
 * "ok" ones: about 3-4x; the slip factor (25) would hand their surge to
 * the motion model, which a plotter's steps defeat. */
#define COINCIDENCE_SURGE_FACTOR 4.0

/* A pair whose verdict `verdict` is "ambiguous" only for its own estimate
 * sitting at a phase-centre coincidence on a compact scene: its candidates
 * were told apart (margin), and nothing of the resolution replaced or
 * doubted the estimate. No slip is in doubt: its sway and yaw are an ok
 * pair's, its surge is drawn towards the coincidence. */
static int coincidence_only(const nav_ctx *ctx, int verdict, const sasnav_navigate_pair *np)
{
    /* (a coincidence is flagged on compact scenes only, whose margin
     * minimum is verdict_margin_compact where that is larger) */
    const sasnav_pair_opts *po = &ctx->opts->pair;
    double need = po->verdict_margin_compact > po->verdict_margin_min ? po->verdict_margin_compact
                                                                     : po->verdict_margin_min;
    return verdict == SASNAV_VERDICT_AMBIGUOUS && np->result.coincidence && np->result.margin >= need &&
           np->resolution == SASNAV_RESOLVED_NONE;
}

/* An estimate's standard deviations scaled by its final eta
 * (opts.link_eta): (eta / link_eta)^2 above link_eta (an infinite eta:
 * infinite), 1 below or where eta is NaN; only in the components that
 * the pair's aiding measures (finite sa): elsewhere the motion model is
 * a loose bridge, and an ok pair should stay its own estimate
 * (docs/navigation.md, "Standard deviations that grow with eta"). */
static sasnav_pose eta_scaled(const nav_ctx *ctx, sasnav_pose s, double eta, sasnav_pose sa)
{
    double e0 = ctx->opts->link_eta;
    if (e0 > 0 && isfinite(e0) && eta > e0) {
        double f = (eta / e0) * (eta / e0);
        if (isfinite(sa.x)) s.x *= f;
        if (isfinite(sa.y)) s.y *= f;
        if (isfinite(sa.theta)) s.theta *= f;
    }
    return s;
}

/* Standard deviations of a pair's estimate in the smoother, given the
 * standard deviations of its aiding (+inf where none). */
static sasnav_pose estimate_sigma(const nav_ctx *ctx, const sasnav_navigate_pair *np, sasnav_pose sa)
{
    if (ctx->opts->method == SASNAV_METHOD_AIDING) return (sasnav_pose){INFINITY, INFINITY, INFINITY};
    if (np->resolution == SASNAV_RESOLVED_BRIDGED || !usable(np) ||
        np->verdict == SASNAV_VERDICT_FAILED || np->verdict == SASNAV_VERDICT_NO_OVERLAP)
        return (sasnav_pose){INFINITY, INFINITY, INFINITY};
    sasnav_pose s = eta_scaled(ctx, ctx->opts->link_sigma, np->result.eta, sa);
    if (np->verdict == SASNAV_VERDICT_AMBIGUOUS && !coincidence_only(ctx, np->verdict, np)) {
        /* The surge-yaw slip direction is in doubt; sway is not. (A pair
         * the resolution re-estimated or moved to another candidate stays
         * here even at a coincidence: its slip is what is in doubt.) */
        s.x *= 25.0;
        s.theta *= 25.0;
    } else if (np->result.coincidence) {
        /* At a phase-centre coincidence on a compact scene, whatever its
         * verdict: the surge is drawn towards the coincidence
         * (docs/navigation.md, "Pairs at a phase-centre coincidence"). An
         * aiding that agrees within its gate (half a spacing and more)
         * cannot tell that pull from the truth, so its "ok" does not
         * restore the surge's weight. */
        s.x *= COINCIDENCE_SURGE_FACTOR;
    }
    return s;
}

/* Motion-model prediction of pair j: the mean of the nearest usable
 * estimates before and after it (either alone at the run's ends). */
static sasnav_pose motion_prediction(const nav_ctx *ctx, int n, int j)
{
    int lo = -1, hi = -1;
    sasnav_navigate_pair np, lo_np, hi_np;
    for (int i = j - 1; i >= 0 && lo < 0; i--) {
        get_pair(ctx, i, &lo_np);
        if (leanable(&lo_np)) lo = i;
    }
    for (int i = j + 1; i < n && hi < 0; i++) {
        get_pair(ctx, i, &hi_np);
        if (leanable(&hi_np)) hi = i;
    }
    get_pair(ctx, j, &np);
    if (lo < 0 && hi < 0) return np.result.error;
    if (lo < 0) return hi_np.result.error;
    if (hi < 0) return lo_np.result.error;
    sasnav_pose a = lo_np.result.error, b = hi_np.result.error;
    double t = (double)(j - lo) / (double)(hi - lo);
    return (sasnav_pose){a.x + t * (b.x - a.x), a.y + t * (b.y - a.y), a.theta + t * (b.theta - a.theta)};
}

/* Fewest usable estimates for a run's median eta (opts.eta_outlier). */
#define ETA_OUTLIER_MIN_PAIRS 6

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Whether a pair takes part in the eta-outlier rule: a usable estimate
 * whose verdict is "ok" or "ambiguous" (not failed), with a finite eta, on
 * a speckle-like scene for the verdict (neither p's image nor q's compact:
 * the compact-scene rules did not apply). Read before the resolution,
 * where result is the first estimate (first_result). */
static int eta_rule_pair(const nav_ctx *ctx, const sasnav_navigate_pair *np)
{
    const sasnav_pair_result *r = &np->result;
    return usable(np) && (np->verdict == SASNAV_VERDICT_OK || np->verdict == SASNAV_VERDICT_AMBIGUOUS) &&
           r->eta > 0 && isfinite(r->eta) && sasnav_pair_result_contrast(r) <= ctx->opts->pair.verdict_contrast;
}

/* The eta-outlier rule (opts.eta_outlier): the median final eta of the
 * first n consecutive pairs that take part (eta_rule_pair), and each one
 * of them far above it marked, and made "ambiguous" if it was "ok" (its
 * first verdict too: the estimate is what is in doubt). Before the joint
 * choice, so that the motion model and the aiding may settle the pair;
 * also without the resolution (opts.resolve 0: the verdicts only). On the
 * paper-trajectory's speckle seabed the pairs of a run stayed within 1.4
 * times their run's median eta (825 pairs, 30 and 20 dB); on runs with a
 * seabed feature 20-28 dB above the rest (docs/validation.md, "An eta far
 * above the run's") slipped pairs that no contrast gate caught reached
 * 1.6-2.3 times it, as did some correct ones. Compact scenes have rules of their own (coincidence,
 * margin) and etas that spread further among correct pairs (the simulated
 * tank's): the rule leaves them out. */
static int flag_eta_outliers(nav_ctx *ctx, sasnav_navigation *out, int n)
{
    const sasnav_navigate_opts *o = ctx->opts;
    out->eta_median = NAN;
    out->n_eta_outliers = 0;
    if (o->method != SASNAV_METHOD_SUBSPACE || !isfinite(o->eta_outlier) || n < ETA_OUTLIER_MIN_PAIRS)
        return SASNAV_OK;
    double *eta = malloc(sizeof *eta * (size_t)n);
    if (!eta) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory in the joint resolution");
    sasnav_navigate_pair pair, *np = &pair;
    int m = 0;
    for (int j = 0; j < n; j++) {
        get_pair(ctx, j, np);
        if (eta_rule_pair(ctx, np)) eta[m++] = np->result.eta;
    }
    if (m < ETA_OUTLIER_MIN_PAIRS) {
        free(eta);
        return SASNAV_OK;
    }
    qsort(eta, (size_t)m, sizeof *eta, cmp_double);
    double med = m % 2 ? eta[m / 2] : 0.5 * (eta[m / 2 - 1] + eta[m / 2]);
    free(eta);
    out->eta_median = med;
    double line = o->eta_outlier * med;
    int rc = SASNAV_OK;
    for (int j = 0; j < n && !rc; j++) {
        get_pair(ctx, j, np);
        if (!eta_rule_pair(ctx, np) || !(np->result.eta > line)) continue;
        np->eta_outlier = 1;
        out->n_eta_outliers++;
        if (np->verdict == SASNAV_VERDICT_OK) np->verdict = np->first_verdict = SASNAV_VERDICT_AMBIGUOUS;
        rc = put_pair(ctx, j, np);
    }
    return rc;
}

/* Step 0 of navigate.h: joint choice, new estimates where needed, robust
 * smoother. Consecutive pairs only. */
static int resolve_pairs(nav_ctx *ctx, sasnav_navigation *out)
{
    const sasnav_run *run = ctx->run;
    const sasnav_navigate_opts *o = ctx->opts;
    int n = run->n_pings - 1;
    int rc = SASNAV_OK;
    sasnav_navigate_pair pair, *np = &pair;
    for (int j = 0; j < out->n_pairs && !rc; j++) {
        get_pair(ctx, j, np);
        np->first_verdict = np->verdict = usable(np) ? np->result.verdict
                                        : np->status == SASNAV_ERR_NO_OVERLAP ? SASNAV_VERDICT_NO_OVERLAP
                                                                               : SASNAV_VERDICT_FAILED;
        if (np->status == SASNAV_ERR_NOT_CONVERGED) np->verdict = np->first_verdict = SASNAV_VERDICT_FAILED;
        if (o->method == SASNAV_METHOD_AIDING) {
            /* Dead reckoning: the step is what the aiding measured over the
             * interval. Where the gyro or the DVL has no measurement there
             * (+inf), that component is the motion model's guess: the pair
             * is "failed", never "ok". (Here, not where the pair is made,
             * so that resumed and reused records are judged alike.) */
            sasnav_pose a, sa;
            fuse_aiding_error(run, np->p, np->q, np->nominal, 0.0, &a, &sa);
            np->verdict = np->first_verdict = isfinite(sa.x) && isfinite(sa.y) && isfinite(sa.theta)
                                                  ? SASNAV_VERDICT_OK
                                                  : SASNAV_VERDICT_FAILED;
        }
        np->fused = np->result.error;
        np->aiding = (sasnav_pose){0, 0, 0};
        np->aiding_sigma = (sasnav_pose){INFINITY, INFINITY, INFINITY};
        np->eta_outlier = 0;
        rc = put_pair(ctx, j, np);
    }
    if (!rc) rc = flag_eta_outliers(ctx, out, n < out->n_pairs ? n : out->n_pairs);
    if (rc || !o->resolve || n < 1) return rc;
    sasnav_pose *a = malloc(sizeof *a * (size_t)n), *sa = malloc(sizeof *sa * (size_t)n);
    sasnav_pose *m = malloc(sizeof *m * (size_t)n), *sm = malloc(sizeof *sm * (size_t)n);
    sasnav_pose *e = malloc(sizeof *e * (size_t)n);
    fuse_option *pool = NULL;
    fuse_option **opts = malloc(sizeof *opts * (size_t)n);
    int *nopt = malloc(sizeof(int) * (size_t)n), *choice = malloc(sizeof(int) * (size_t)n);
    if (!a || !sa || !m || !sm || !e || !opts || !nopt || !choice) {
        rc = sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory in the joint resolution");
        goto done;
    }
    int with_aiding = o->use_aiding && run->aiding != NULL;
    out->aiding_used = with_aiding;
    for (int j = 0; j < n && !rc; j++) {
        get_pair(ctx, j, np);
        a[j] = (sasnav_pose){0, 0, 0};
        sa[j] = (sasnav_pose){INFINITY, INFINITY, INFINITY};
        if (with_aiding) fuse_aiding_error(run, np->p, np->q, np->nominal, np->result.error.theta, &a[j], &sa[j]);
        np->aiding = a[j];
        np->aiding_sigma = sa[j];
        rc = put_pair(ctx, j, np);
    }
    if (rc) goto done;
    /* 1. The joint choice among each pair's distinct refined candidates
     * (the chosen one at its final-stage value). Pairs without a usable
     * estimate offer their nominal step (motion error 0) at no eta cost.
     * The options of all pairs in one pool, as many as they have. */
    size_t n_pool = 0;
    for (int j = 0; j < n; j++) {
        get_pair(ctx, j, np);
        const sasnav_pair_result *r = &np->result;
        nopt[j] = 0;
        if (usable(np))
            for (int k = 0; k < r->n_candidates; k++)
                if (r->candidates[k].refined && r->candidates[k].same_as < 0) nopt[j]++;
        if (nopt[j] == 0) nopt[j] = 1;
        n_pool += (size_t)nopt[j];
    }
    pool = malloc(sizeof *pool * n_pool);
    if (!pool) {
        rc = sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory in the joint resolution");
        goto done;
    }
    n_pool = 0;
    for (int j = 0; j < n; j++) {
        get_pair(ctx, j, np);
        const sasnav_pair_result *r = &np->result;
        opts[j] = pool + n_pool;
        n_pool += (size_t)nopt[j];
        nopt[j] = 0;
        if (!usable(np) || r->n_candidates == 0) {
            opts[j][0] = (fuse_option){usable(np) ? r->error : (sasnav_pose){0, 0, 0}, NAN, -1};
            nopt[j] = 1;
            continue;
        }
        for (int k = 0; k < r->n_candidates; k++) {
            const sasnav_pair_candidate *cd = &r->candidates[k];
            if (!cd->refined || cd->same_as >= 0) continue;
            opts[j][nopt[j]++] = (fuse_option){k == r->chosen ? r->error : cd->error, cd->eta, k};
        }
        if (nopt[j] == 0) opts[j][nopt[j]++] = (fuse_option){r->error, NAN, r->chosen};
    }
    rc = fuse_choose(n, opts, nopt, a, sa, o->motion_sigma, o->eta_weight, choice);
    if (rc) goto done;
    for (int j = 0; j < n && !rc; j++) {
        get_pair(ctx, j, np);
        const fuse_option *c = &opts[j][choice[j]];
        if (!usable(np) || c->candidate < 0 || c->candidate == np->result.chosen) continue;
        int taken = 0;
        rc = reestimate(ctx, np, c->e, a[j], sa[j], 0, &taken);
        if (!rc && taken) {
            np->resolution = SASNAV_RESOLVED_CANDIDATE;
            np->result.chosen = c->candidate;
            /* Only the aiding settles an ambiguity (below); the motion
             * model's choice stays as doubtful as the pair was. */
            np->verdict = worse(np->first_verdict, np->result.verdict);
            rc = put_pair(ctx, j, np);
        }
    }
    if (rc) goto done;
    /* 2. Failed pairs and pairs that disagree with the aiding: a new
     * estimate from the aiding's prediction (or the motion model's); where
     * that does not give an estimate that is better and agrees, the pair
     * is bridged. Estimates that agree with the aiding are confirmed. */
    for (int j = 0; j < n && !rc && o->method != SASNAV_METHOD_AIDING; j++) {
        get_pair(ctx, j, np);
        int ok_alone = usable(np) && np->verdict != SASNAV_VERDICT_FAILED &&
                       np->verdict != SASNAV_VERDICT_NO_OVERLAP;
        int agree = agrees(ctx, np->result.error, a[j], sa[j]);
        if (ok_alone && agree) {
            if (with_aiding && (np->verdict == SASNAV_VERDICT_AMBIGUOUS || np->verdict == SASNAV_VERDICT_UNCHECKED) &&
                aiding_settles(ctx, sa[j]))
                np->verdict = SASNAV_VERDICT_OK; /* the aiding settles the ambiguity, or
                                                    confirms an estimate without verdict */
            rc = put_pair(ctx, j, np);
            continue;
        }
        if (np->status == SASNAV_ERR_NO_OVERLAP && !with_aiding) continue;
        sasnav_pose start = np->result.error;
        if (with_aiding) {
            if (isfinite(sa[j].x)) start.x = a[j].x;
            if (isfinite(sa[j].y)) start.y = a[j].y;
            if (isfinite(sa[j].theta)) start.theta = a[j].theta;
        } else {
            start = motion_prediction(ctx, n, j);
        }
        int taken = 0;
        if (np->status != SASNAV_ERR_NO_OVERLAP) rc = reestimate(ctx, np, start, a[j], sa[j], ok_alone, &taken);
        if (rc) break;
        if (taken) {
            np->resolution = SASNAV_RESOLVED_REESTIMATED;
            /* Confirmed by the aiding (reestimate keeps only estimates that
             * agree with it), or a local estimate from the motion model's
             * prediction that no candidate competition has tested:
             * ambiguous at best. */
            /* (the aiding settles which candidate, not whether the data
             * fit: a new estimate that itself failed stays failed; found
             * by review, a failed pair came out "ok") */
            if (with_aiding && aiding_settles(ctx, sa[j]) &&
                (np->result.verdict == SASNAV_VERDICT_OK || np->result.verdict == SASNAV_VERDICT_AMBIGUOUS))
                np->verdict = SASNAV_VERDICT_OK;
            else
                np->verdict = worse(SASNAV_VERDICT_AMBIGUOUS, np->result.verdict);
        } else if (!ok_alone || !agree) {
            np->resolution = SASNAV_RESOLVED_BRIDGED;
        }
        if (!rc) rc = put_pair(ctx, j, np);
    }
    if (rc) goto done;
    /* 3. The robust smoother. */
    for (int j = 0; j < n; j++) {
        get_pair(ctx, j, np);
        m[j] = np->result.error;
        sm[j] = estimate_sigma(ctx, np, sa[j]);
    }
    free(ctx->post_buf);
    ctx->post_buf = malloc(sizeof(double) * 9 * (size_t)n);
    if (!ctx->post_buf) {
        rc = sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory in the trajectory smoother");
        goto done;
    }
    for (int k = 0; k < 3; k++) {
        ctx->post.d[k] = ctx->post_buf + (size_t)(3 * k) * (size_t)n;
        ctx->post.off[k] = ctx->post_buf + (size_t)(3 * k + 1) * (size_t)n;
        ctx->post.yu[k] = ctx->post_buf + (size_t)(3 * k + 2) * (size_t)n;
        ctx->post.denom[k] = 0.0;
    }
    rc = fuse_smooth_post(n, m, sm, a, sa, o->motion_sigma, 3.0,
                          with_aiding ? o->aiding_bias_sigma : (sasnav_pose){0, 0, 0}, e, NULL, &ctx->post);
    if (rc) goto done;
    for (int j = 0; j < n && !rc; j++) {
        get_pair(ctx, j, np);
        np->fused = e[j];
        np->result.displacement = (sasnav_pose){np->nominal.x + e[j].x, np->nominal.y + e[j].y,
                                                np->nominal.theta + e[j].theta};
        rc = put_pair(ctx, j, np);
    }
done:
    free(a);
    free(sa);
    free(m);
    free(sm);
    free(e);
    free(pool);
    free(opts);
    free(nopt);
    free(choice);
    return rc;
}

/* Counts and truth comparisons after the resolution. */
static int pair_summary(nav_ctx *ctx, sasnav_navigation *out)
{
    out->n_flagged = out->n_resolved = 0;
    int rc = SASNAV_OK;
    for (int j = 0; j < out->n_pairs && !rc; j++) {
        sasnav_navigate_pair np;
        get_pair(ctx, j, &np);
        if (np.verdict != SASNAV_VERDICT_OK || np.resolution == SASNAV_RESOLVED_BRIDGED) out->n_flagged++;
        if (np.resolution != SASNAV_RESOLVED_NONE) out->n_resolved++;
        if (ctx->run->truth) {
            np.error = pose_sub(np.fused, np.truth);
            rc = put_pair(ctx, j, &np);
        }
    }
    return rc;
}

/* Per-ping Tx-array offsets scaled by the vehicle's speed at each ping
 * (the offset is speed x two-way delay): lag_p = tx_lag (1 + a_p), a_p the
 * relative speed excess. From the DVL (the mean of the two intervals
 * around the ping) when `from_dvl`, else from the consecutive pairs'
 * surge motion errors (their mean over the nominal step). */
static void speed_lags(const nav_ctx *ctx, int from_dvl, double *lags)
{
    const sasnav_run *run = ctx->run;
    int n = run->n_pings;
    const sasnav_aiding *ad = run->aiding;
    for (int p = 0; p < n; p++) {
        double a = 0;
        if (from_dvl) {
            double dt0 = p > 0 ? ad->time[p] - ad->time[p - 1] : 0;
            double dt1 = p + 1 < n ? ad->time[p + 1] - ad->time[p] : 0;
            double sum = 0, w = 0;
            /* (intervals without a measurement, sigma +inf, skipped: their
             * value is not a speed) */
            if (p > 0 && isfinite(ad->velocity_sigma[2 * p])) {
                sasnav_pose nom = sasnav_ping_displacement(&run->nav[p - 1], &run->nav[p]);
                sum += ad->velocity[2 * p] * dt0 / fabs(nom.x) - 1.0;
                w += 1;
            }
            if (p + 1 < n && isfinite(ad->velocity_sigma[2 * (p + 1)])) {
                sasnav_pose nom = sasnav_ping_displacement(&run->nav[p], &run->nav[p + 1]);
                sum += ad->velocity[2 * (p + 1)] * dt1 / fabs(nom.x) - 1.0;
                w += 1;
            }
            a = w > 0 ? sum / w : 0.0;
        } else {
            double sum = 0, w = 0;
            for (int j = p - 1; j <= p; j++) {
                if (j < 0 || j >= n - 1) continue;
                sasnav_navigate_pair np;
                get_pair(ctx, j, &np);
                /* (usable too: a record of an older version gave a failed
                 * pair the verdict 0, "ok") */
                if (np.first_verdict != SASNAV_VERDICT_OK || !usable(&np) || !(fabs(np.nominal.x) > 0)) continue;
                sum += np.result.error.x / fabs(np.nominal.x);
                w += 1;
            }
            a = w > 0 ? sum / w : 0.0;
        }
        if (!isfinite(a) || a < -0.5) a = 0; /* nonsense speeds: keep the nominal offset */
        lags[p] = run->tx_lag * (1.0 + a);
    }
}

/* The second pass of two_pass: every one of the n pairs (the long
 * baselines too) with a first estimate gets its
 * final stage from it, on its data set again with the speed-scaled
 * offsets (ctx->lags); its candidates and margin stay the first pass's.
 * Concurrent over pairs like the first pass. */
static int finish_pass(nav_ctx *ctx, int n)
{
    int stop = 0;
    int *codes = calloc((size_t)(n > 0 ? n : 1), sizeof(int));
    if (!codes) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    char message[256] = "";
#pragma omp parallel for schedule(dynamic, 1) num_threads(ctx->n_workers) if (ctx->n_workers > 1)
    for (int j = 0; j < n; j++) {
        int skip;
#pragma omp atomic read
        skip = stop;
        sasnav_navigate_pair pair, *np = &pair;
        get_pair(ctx, j, np);
        if (skip || !usable(np)) continue;
        int t = ctx->n_workers > 1 ? omp_get_thread_num() : 0;
        sasnav_pair *est = ctx->estimators[t];
        sasnav_pair_result first = np->result;
        double t0 = sasnav_now_seconds();
        int rc = set_pair_data(ctx, t, est, np->p, np->q, np->nominal);
        if (!rc) rc = sasnav_pair_finish(est, &first, &np->result);
        if (rc) np->result.seconds = first.seconds + sasnav_now_seconds() - t0;
        rc = take_result(ctx, np, rc);
        if (!rc) rc = put_pair(ctx, j, np);
        if (rc) {
            codes[j] = rc;
#pragma omp critical(sasnav_navigate_failure)
            if (!message[0]) snprintf(message, sizeof message, "%s", sasnav_last_error());
#pragma omp atomic write
            stop = 1;
        }
    }
    int rc = SASNAV_OK;
    for (int j = 0; j < n && !rc; j++)
        if (codes[j]) rc = sasnav_set_error(codes[j], "%s", message);
    free(codes);
    return rc;
}

/* The second pass of opts.speed_lags = 2 and of the transmitters' turn
 * from the pairs: every consecutive pair whose first estimate is ok is
 * estimated again from it with the new layouts or offsets (local stages
 * only); its candidates and margin stay the first pass's. With
 * retry_flagged, a consecutive pair whose first estimate was not ok
 * (other than for want of overlap) is estimated afresh (all stages) with
 * them, and the new estimate replaces it when it is ok: for the turn,
 * whose absence can itself make a pair ambiguous. Concurrent over pairs
 * like the first pass. */
static int second_pass(nav_ctx *ctx, int retry_flagged)
{
    int n = ctx->run->n_pings - 1, stop = 0;
    int *codes = calloc((size_t)(n > 0 ? n : 1), sizeof(int));
    if (!codes) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
#pragma omp parallel for schedule(dynamic, 1) num_threads(ctx->n_workers) if (ctx->n_workers > 1)
    for (int j = 0; j < n; j++) {
        int skip;
#pragma omp atomic read
        skip = stop;
        sasnav_navigate_pair pair, *np = &pair;
        get_pair(ctx, j, np);
        int again = np->first_verdict == SASNAV_VERDICT_OK && usable(np);
        int afresh = !again && retry_flagged && np->q == np->p + 1 && np->status != SASNAV_ERR_NO_OVERLAP &&
                     np->first_verdict != SASNAV_VERDICT_NO_OVERLAP;
        if (skip || (!again && !afresh)) continue;
        int t = ctx->n_workers > 1 ? omp_get_thread_num() : 0;
        sasnav_pair *est = ctx->estimators[t];
        sasnav_pair_result r;
        int rc = set_pair_data(ctx, t, est, np->p, np->q, np->nominal);
        if (!rc) rc = again ? sasnav_pair_estimate_from(est, np->result.error, &r) : sasnav_pair_estimate(est, &r);
        if (fatal_code(rc)) {
            codes[j] = rc;
#pragma omp atomic write
            stop = 1;
            continue;
        }
        if (rc || r.verdict != SASNAV_VERDICT_OK) continue; /* keep the first estimate */
        if (again) {
            /* judged again with the first estimate's margin (its own was
             * infinite): on a scene compact by the new estimate's
             * contrasts that margin may be short of the compact one, and
             * the pair is then flagged */
            sasnav_pair_result_carry(&np->result, &r);
            sasnav_pair_rejudge(est, &r);
            np->result = r;
        } else { /* its own candidates; the time and work of both */
            r.seconds += np->result.seconds;
            r.applications += np->result.applications;
            r.evaluations += np->result.evaluations;
            np->result = r;
            np->first_verdict = r.verdict;
        }
        np->status = r.status;
        np->first_result = r;
        np->first_status = r.status;
        rc = put_pair(ctx, j, np);
        if (rc) {
            codes[j] = rc;
#pragma omp atomic write
            stop = 1;
        }
    }
    int rc = SASNAV_OK;
    for (int j = 0; j < n && !rc; j++)
        if (codes[j]) rc = codes[j];
    free(codes);
    return rc;
}

/* Each transmitter's turn between transmission and reception from the
 * consecutive pairs' first estimates (opts.tx_yaw without a gyro): the
 * track's turn per metre, each ok pair's estimated yaw over its nominal
 * step length, interpolated as the gyro's rates are
 * (sasnav_tx_yaw_from_rates) with distance along the track for time and
 * the distance travelled between transmission and reception (tx_lag;
 * without it, speed x the two-way delay at the range of interest) for
 * the interval. *used: the pairs that gave a rate (0: no turn known,
 * tx_yaw untouched; also where two pings' nominal poses coincide). */
static int pairs_tx_yaw(const nav_ctx *ctx, int n_pairs, double *tx_yaw, int *used)
{
    const sasnav_run *run = ctx->run;
    int n = run->n_pings;
    *used = 0;
    double range = run->range_of_interest > 0 ? run->range_of_interest : ctx->opts->pair.range;
    double interval = run->tx_lag > 0 ? run->tx_lag : run->speed * 2.0 * range / run->sys.sound_speed;
    if (!(interval > 0) || !isfinite(interval) || n < 2) return SASNAV_OK;
    double *s = malloc(sizeof(double) * 2 * (size_t)n);
    unsigned char *valid = calloc((size_t)n, 1);
    if (!s || !valid) {
        free(s);
        free(valid);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    }
    double *rate = s + n;
    s[0] = rate[0] = 0.0;
    for (int p = 1; p < n; p++) {
        sasnav_pose d = sasnav_ping_displacement(&run->nav[p - 1], &run->nav[p]);
        s[p] = s[p - 1] + hypot(d.x, d.y);
        rate[p] = 0.0;
    }
    for (int j = 0; j < n_pairs; j++) {
        sasnav_navigate_pair np;
        get_pair(ctx, j, &np);
        double len = np.q == np.p + 1 ? s[np.q] - s[np.p] : 0.0;
        if (np.first_verdict != SASNAV_VERDICT_OK || !usable(&np) || !(len > 0)) continue;
        rate[np.q] = np.result.displacement.theta / len;
        valid[np.q] = isfinite(rate[np.q]) != 0;
        *used += valid[np.q];
    }
    for (int p = 1; p < n && *used; p++)
        if (!(s[p] > s[p - 1])) *used = 0; /* pings at one place: no distance to interpolate on */
    int rc = *used ? sasnav_tx_yaw_from_rates(n, s, rate, valid, interval, tx_yaw) : SASNAV_OK;
    free(s);
    free(valid);
    return rc;
}

/* Centroids from the pair displacements: the chain, or the least squares
 * over all links when long baselines were estimated. */
static int solve_centroids(const nav_ctx *ctx, sasnav_navigation *out, sasnav_pose first)
{
    int n = out->n_pings, n_chain = n - 1;
    if (out->n_pairs == n_chain) {
        sasnav_pose *disp = malloc(sizeof *disp * (size_t)n_chain);
        if (!disp) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
        for (int j = 0; j < n_chain; j++) {
            sasnav_navigate_pair np;
            get_pair(ctx, j, &np);
            disp[j] = np.result.displacement;
        }
        int rc = sasnav_traj_compose(first, disp, n, out->centroids);
        free(disp);
        return rc;
    }
    sasnav_traj_link *links = malloc(sizeof *links * (size_t)out->n_pairs);
    if (!links) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    for (int j = 0; j < out->n_pairs; j++) {
        sasnav_navigate_pair pair, *np = &pair;
        get_pair(ctx, j, np);
        /* (fixed standard deviations here: the consecutive pairs carry
         * their fused values already, weighed by link_eta in the
         * smoother; the long baselines' weights by eta are not measured) */
        sasnav_pose s = np->q - np->p == 1 ? ctx->opts->link_sigma : ctx->opts->long_sigma;
        if (np->status != SASNAV_OK && np->status != SASNAV_ERR_NOT_CONVERGED) {
            /* A failed pair stands in with its nominal displacement, so that
             * every ping stays reached, but weighs (almost) nothing. */
            s = (sasnav_pose){1e4 * s.x, 1e4 * s.y, 1e4 * s.theta};
        }
        links[j] = (sasnav_traj_link){np->p, np->q, np->result.displacement, s};
    }
    int rc = sasnav_traj_solve(n, first, links, out->n_pairs, NULL, out->centroids,
                               &out->lsq_iterations);
    free(links);
    return rc;
}

/* Truth-dependent outputs: the true centroids in the estimate's frame, the
 * estimate in the truth's frame, cumulative and differential errors. */
static int compare_with_truth(const nav_ctx *ctx, sasnav_navigation *out)
{
    const sasnav_run *run = ctx->run;
    int n = out->n_pings;
    size_t np = (size_t)n;
    out->truth_centroids = malloc(sizeof(sasnav_pose) * np);
    out->anchored = malloc(sizeof(sasnav_ping_pose) * np);
    out->cumulative = malloc(sizeof(sasnav_pose) * np);
    out->differential = malloc(sizeof(sasnav_pose) * np);
    sasnav_pose *true_c = malloc(sizeof(sasnav_pose) * np);
    sasnav_pose *moved = malloc(sizeof(sasnav_pose) * np);
    if (!out->truth_centroids || !out->anchored || !out->cumulative || !out->differential ||
        !true_c || !moved) {
        free(true_c);
        free(moved);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    }
    out->has_truth = 1;
    int rc = sasnav_traj_centroids(run->truth, n, true_c);
    /* Gauge: the rigid motion taking the true first centroid onto the
     * estimated one (and its inverse for the anchored estimate). */
    sasnav_pose to_est = sasnav_pose_compose(out->centroids[0], sasnav_pose_inverse(true_c[0]));
    sasnav_pose to_true = sasnav_pose_inverse(to_est);
    for (int i = 0; i < n; i++) {
        out->truth_centroids[i] = sasnav_pose_compose(to_est, true_c[i]);
        moved[i] = sasnav_pose_compose(to_true, out->centroids[i]);
    }
    if (!rc) rc = sasnav_traj_ping_poses(moved, n, run->tx_lag, 0.0, out->anchored);
    if (!rc)
        rc = sasnav_traj_errors(out->centroids, out->truth_centroids, n, 0.0, out->cumulative,
                                out->differential);
    free(true_c);
    free(moved);
    if (rc) return rc;
    out->cumulative[0] = (sasnav_pose){0, 0, 0}; /* exact by construction; drop rounding */
    sasnav_pose sc = {0, 0, 0}, sd = {0, 0, 0};
    for (int i = 0; i < n; i++) {
        sc.x += out->cumulative[i].x * out->cumulative[i].x;
        sc.y += out->cumulative[i].y * out->cumulative[i].y;
        sc.theta += out->cumulative[i].theta * out->cumulative[i].theta;
        sd.x += out->differential[i].x * out->differential[i].x;
        sd.y += out->differential[i].y * out->differential[i].y;
        sd.theta += out->differential[i].theta * out->differential[i].theta;
    }
    out->rms_cumulative = (sasnav_pose){sqrt(sc.x / n), sqrt(sc.y / n), sqrt(sc.theta / n)};
    int nd = n - 1;
    out->rms_differential = (sasnav_pose){sqrt(sd.x / nd), sqrt(sd.y / nd), sqrt(sd.theta / nd)};
    return SASNAV_OK;
}

/* Before a second pass: each pair's first verdict is its present one
 * (second_pass re-estimates the pairs whose first verdict is ok). */
static int keep_first_verdicts(nav_ctx *ctx, int n_pairs)
{
    int rc = SASNAV_OK;
    for (int j = 0; j < n_pairs && !rc; j++) {
        sasnav_navigate_pair np;
        get_pair(ctx, j, &np);
        np.first_verdict = np.result.verdict;
        rc = put_pair(ctx, j, &np);
    }
    return rc;
}

static int navigate(nav_ctx *ctx, sasnav_navigation *out)
{
    const sasnav_run *run = ctx->run;
    int n = run->n_pings;
    out->centroids = malloc(sizeof(sasnav_pose) * (size_t)n);
    out->nav = malloc(sizeof(sasnav_ping_pose) * (size_t)n);
    if (!out->centroids || !out->nav) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    const sasnav_navigate_opts *o = ctx->opts;
    int dvl = run->aiding && run->aiding->velocity && o->use_aiding;
    /* (channel layouts take their Tx-array offsets from the navigation:
     * speed-scaled offsets do not apply to them) */
    if (o->speed_lags && o->method == SASNAV_METHOD_SUBSPACE && dvl && !run->channel_offset) {
        ctx->lags = malloc(sizeof(double) * (size_t)n);
        if (!ctx->lags) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
        speed_lags(ctx, 1, ctx->lags);
    }
    if (run->channel_offset && run->aiding && run->aiding->yaw_rate && o->use_aiding && o->tx_yaw == 1 &&
        o->method == SASNAV_METHOD_SUBSPACE) {
        ctx->tx_yaw = malloc(sizeof(double) * (size_t)n);
        if (!ctx->tx_yaw) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
        double range = run->range_of_interest > 0 ? run->range_of_interest : o->pair.range; /* as the estimators' */
        int r = sasnav_run_tx_yaw(run, range, ctx->tx_yaw);
        if (r) return r;
    }
    out->gyro_tx_yaw = ctx->tx_yaw != NULL;
    int rc = estimate_all(ctx, out);
    if (rc || ctx->n_parts > 1 || ctx->keys) return rc; /* a part: first estimates only */
    if (run->channel_offset && o->tx_yaw && !ctx->tx_yaw && o->method == SASNAV_METHOD_SUBSPACE && !o->reuse) {
        /* No gyro: the turn between transmission and reception from the
         * pairs' own yaw estimates, then the ok pairs again. */
        rc = keep_first_verdicts(ctx, out->n_pairs);
        if (rc) return rc;
        ctx->tx_yaw = malloc(sizeof(double) * (size_t)n);
        if (!ctx->tx_yaw) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
        int used = 0;
        rc = pairs_tx_yaw(ctx, out->n_pairs, ctx->tx_yaw, &used);
        if (rc) return rc;
        if (used) {
            rc = second_pass(ctx, 1);
            if (rc) return rc;
            out->pairs_tx_yaw = 1;
        } else {
            free(ctx->tx_yaw);
            ctx->tx_yaw = NULL;
        }
    }
    if (o->speed_lags == 2 && o->method == SASNAV_METHOD_SUBSPACE && !ctx->lags && !o->reuse &&
        !run->channel_offset) {
        rc = keep_first_verdicts(ctx, out->n_pairs);
        if (rc) return rc;
        ctx->lags = malloc(sizeof(double) * (size_t)n);
        if (!ctx->lags) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
        speed_lags(ctx, 0, ctx->lags);
        double t = sasnav_now_seconds();
        rc = ctx->two_pass ? finish_pass(ctx, out->n_pairs) : second_pass(ctx, 0);
        if (rc) return rc;
        if (ctx->two_pass) {
            /* the estimation's figures over both passes */
            out->seconds_estimation += sasnav_now_seconds() - t;
            out->pairs_per_second = out->seconds_estimation > 0 ? out->n_pairs / out->seconds_estimation : 0.0;
            out->seconds_pairs = 0;
            for (int j = 0; j < out->n_pairs; j++) {
                sasnav_navigate_pair np;
                get_pair(ctx, j, &np);
                out->seconds_pairs += np.result.seconds;
            }
            out->seconds_per_pair = out->n_pairs > 0 ? out->seconds_pairs / out->n_pairs : 0.0;
        }
    }
    rc = resolve_pairs(ctx, out);
    if (!rc) rc = pair_summary(ctx, out);
    if (rc) return rc;
    sasnav_pose first = sasnav_ping_centroid(&run->nav[0]);
    rc = solve_centroids(ctx, out, first);
    if (rc) return rc;
    if (ctx->opts->align) {
        rc = sasnav_traj_align(out->centroids, n, &out->track_angle);
        if (rc) return rc;
    }
    if (ctx->post_buf && out->n_pairs == n - 1 && o->method != SASNAV_METHOD_DPCA) {
        /* The smoother's posterior carried through the chain (with long
         * baselines the least squares re-weighs the links: not here; DPCA
         * takes the surge as nominal, which link_sigma's 1 mm a pair
         * would call measured: not there either). */
        out->formal_sigma = malloc(sizeof(sasnav_pose) * (size_t)n);
        if (!out->formal_sigma) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
        rc = fuse_pose_sigma(n - 1, &ctx->post, out->centroids, out->formal_sigma);
        if (rc) return rc;
        for (int i = 0; i < n && out->formal_sigma; i++)
            if (!isfinite(out->formal_sigma[i].x) || !isfinite(out->formal_sigma[i].y) ||
                !isfinite(out->formal_sigma[i].theta)) {
                /* (an overflow on absurd inputs: none rather than a value
                 * the navigation file would refuse; found by review) */
                free(out->formal_sigma);
                out->formal_sigma = NULL;
            }
    }
    rc = sasnav_traj_ping_poses(out->centroids, n, run->tx_lag, 0.0, out->nav);
    if (rc) return rc;
    if (run->truth) rc = compare_with_truth(ctx, out);
    return rc;
}

/* The pairs into the output: unpacked into out->pairs, or kept packed
 * (opts.compact_pairs; ctx->pairs is then emptied). */
static int hand_out_pairs(nav_ctx *ctx, sasnav_navigation *out)
{
    /* failed pairs counted as they end (a second pass may rescue a pair or
     * fail one: the first pass's count went stale; found by review) */
    out->n_failed = 0;
    for (int j = 0; j < out->n_pairs; j++) {
        sasnav_navigate_pair np;
        get_pair(ctx, j, &np);
        out->n_failed += !usable(&np);
    }
    if (ctx->opts->compact_pairs) {
        pair_store *s = malloc(sizeof *s);
        if (!s) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
        *s = ctx->pairs;
        memset(&ctx->pairs, 0, sizeof ctx->pairs);
        out->packed = s;
        return SASNAV_OK;
    }
    out->pairs = malloc(sizeof *out->pairs * (size_t)(out->n_pairs > 0 ? out->n_pairs : 1));
    if (!out->pairs) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    for (int j = 0; j < out->n_pairs; j++) get_pair(ctx, j, &out->pairs[j]);
    return SASNAV_OK;
}

/* sasnav_navigate, or with keys != NULL the first estimates of one part
 * (sasnav_navigate_part), their keys in keys[] (one per output pair). */
static int navigate_run(const sasnav_run *run, const sasnav_navigate_opts *opts,
                        sasnav_navigation *out, int part, int n_parts, uint64_t **keys)
{
    if (!out) return sasnav_set_error(SASNAV_ERR_ARG, "navigate: NULL output");
    memset(out, 0, sizeof *out);
    sasnav_navigate_opts defaults;
    if (!opts) {
        sasnav_navigate_default_opts(&defaults);
        opts = &defaults;
    }
    int rc = check_input(run, opts);
    if (rc) return rc;
    nav_ctx ctx = {run, opts, NULL, 1, sasnav_now_seconds(),
                   run->array.n_rx > 1 ? 0.5 * fabs(run->array.rx_u[1] - run->array.rx_u[0]) : 0.025,
                   NULL, NULL, NULL, 0, 0, part, n_parts, NULL, NULL, {0, NULL, NULL}, 0,
                   NULL, {{NULL}, {NULL}, {NULL}, {0}}};
    ctx.two_pass = two_pass_mode(run, opts);
    ctx.digest = options_digest(run, opts);
    if (ctx.two_pass) {
        /* first estimates without the final stage: not those of one pass */
        const int marker[1] = {2};
        ctx.digest = hash_ints(ctx.digest, marker, 1);
    }
    if (run->channel_offset) { /* the layout's phase-centre spacing */
        double pc[SASNAV_MAX_RX];
        phase_centres(run, pc);
        double d = phase_centre_spacing(pc, run->array.n_rx);
        if (d > 0) ctx.pc_spacing = d;
    }
    if (keys) {
        ctx.keys = calloc((size_t)(2 * run->n_pings), sizeof *ctx.keys);
        if (!ctx.keys) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    }
    out->method = opts->method;
    out->n_pings = run->n_pings;
    /* Threads: over pairs when there are several pairs (one estimator, or
     * DPCA, per thread, their operators on one thread each); with one
     * thread or one pair, inside the operators. */
    int threads = opts->nthreads > 0 ? opts->nthreads : omp_get_max_threads();
    int n_pairs_max = 2 * run->n_pings;
    ctx.n_workers = threads < n_pairs_max ? threads : n_pairs_max;
    if (ctx.n_workers < 1 || run->n_pings < 3) ctx.n_workers = 1;
    out->threads_over_pairs = ctx.n_workers;
    sasnav_navigate_opts inner = *opts;
    if (ctx.n_workers > 1) {
        inner.nthreads = 1;
        ctx.opts = &inner;
    }
    if (!run->raw) {
        ctx.bufs = malloc(sizeof *ctx.bufs * 2 * (size_t)ctx.n_workers * sasnav_run_ping_size(run));
        if (!ctx.bufs) rc = sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory for the pings in flight");
    }
    if (!rc && opts->method == SASNAV_METHOD_SUBSPACE) {
        sasnav_pair_opts po = opts->pair;
        po.range = run->range_of_interest;
        po.tx_lag = run->tx_lag;
        po.nthreads = ctx.n_workers > 1 ? 1 : opts->nthreads;
        ctx.estimators = calloc((size_t)ctx.n_workers, sizeof *ctx.estimators);
        if (!ctx.estimators) rc = sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory"); /* freed below */
        for (int t = 0; t < ctx.n_workers && !rc; t++)
            rc = sasnav_pair_create(&run->sys, &run->array, &run->win, &po, &ctx.estimators[t]);
    }
    if (!rc && opts->n_done > 0) {
        ctx.done = malloc(sizeof *ctx.done * (size_t)opts->n_done);
        if (!ctx.done) rc = sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
        else {
            for (int j = 0; j < opts->n_done; j++) ctx.done[j] = &opts->done[j];
            qsort(ctx.done, (size_t)opts->n_done, sizeof *ctx.done, record_cmp);
            ctx.n_done = opts->n_done;
        }
    }
    if (!rc) rc = navigate(&ctx, out);
    if (!rc) rc = hand_out_pairs(&ctx, out);
    pair_store_free(&ctx.pairs);
    free(ctx.done);
    free(ctx.bufs);
    if (ctx.estimators)
        for (int t = 0; t < ctx.n_workers; t++) sasnav_pair_destroy(ctx.estimators[t]);
    free(ctx.estimators);
    free(ctx.lags);
    free(ctx.tx_yaw);
    free(ctx.post_buf);
    out->seconds = sasnav_now_seconds() - ctx.t0;
    if (keys) *keys = ctx.keys;
    if (rc) {
        if (keys) {
            free(ctx.keys);
            *keys = NULL;
        }
        /* Keep the message of the failure across the frees. */
        sasnav_navigation_free(out);
        return rc;
    }
    return SASNAV_OK;
}

int sasnav_navigate(const sasnav_run *run, const sasnav_navigate_opts *opts,
                    sasnav_navigation *out)
{
    return navigate_run(run, opts, out, 0, 1, NULL);
}

int sasnav_navigate_part(const sasnav_run *run, const sasnav_navigate_opts *opts, int part,
                         int n_parts, sasnav_pair_record **records, int *n_records)
{
    if (!records || !n_records) return sasnav_set_error(SASNAV_ERR_ARG, "navigate: NULL records");
    *records = NULL;
    *n_records = 0;
    if (n_parts < 1 || part < 0 || part >= n_parts)
        return sasnav_set_error(SASNAV_ERR_ARG, "navigate: part %d of %d does not exist", part, n_parts);
    sasnav_navigation nav;
    uint64_t *keys = NULL;
    int rc = navigate_run(run, opts, &nav, part, n_parts, &keys);
    if (rc) return rc;
    sasnav_pair_record *r = malloc(sizeof *r * (size_t)(nav.n_pairs > 0 ? nav.n_pairs : 1));
    if (!r) {
        free(keys);
        sasnav_navigation_free(&nav);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    }
    int n = 0;
    for (int j = part; j < nav.n_pairs; j += n_parts) {
        sasnav_navigate_pair np;
        sasnav_navigation_pair(&nav, j, &np);
        memset(&r[n], 0, sizeof r[n]);
        r[n].key = keys[j];
        r[n].p = np.p;
        r[n].q = np.q;
        r[n].status = np.first_status;
        r[n].result = np.first_result;
        n++;
    }
    free(keys);
    sasnav_navigation_free(&nav);
    *records = r;
    *n_records = n;
    return SASNAV_OK;
}
