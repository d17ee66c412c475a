/* Virtual arrays of consecutive pings and navigation by their motion. See
 * virtual.h for the contract and docs/navigation.md, "Virtual arrays". */
#include "sasnav/virtual.h"
#include "sasnav/error.h"
#include "core/clock.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

sasnav_pose sasnav_channels_centroid(const sasnav_array *array, const sasnav_ping_pose *channels)
{
    double sx = 0, sy = 0, sc = 0, ss = 0;
    int n = array->n_rx;
    for (int l = 0; l < n; l++) {
        double xr, yr;
        sasnav_pose_apply(channels[l].array, array->rx_u[l], 0.0, &xr, &yr);
        sx += 0.5 * (xr + channels[l].tx.x);
        sy += 0.5 * (yr + channels[l].tx.y);
        sc += cos(channels[l].array.theta);
        ss += sin(channels[l].array.theta);
    }
    sasnav_pose c = {sx / n, sy / n, atan2(ss, sc)};
    return c;
}

int sasnav_virtual_array(const sasnav_array *array, int k, sasnav_array *out)
{
    if (!array || !out) return sasnav_set_error(SASNAV_ERR_ARG, "virtual array: NULL argument");
    int rc = sasnav_array_check(array);
    if (rc) return rc;
    if (k < 1 || (long)k * array->n_rx > SASNAV_MAX_RX)
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "virtual array: %d pings of %d channels make more than %d channels",
                                k, array->n_rx, SASNAV_MAX_RX);
    int pick[SASNAV_MAX_RX];
    for (int j = 0; j < k; j++)
        for (int l = 0; l < array->n_rx; l++) pick[j * array->n_rx + l] = l;
    return sasnav_array_select(array, pick, k * array->n_rx, out);
}

/* sasnav_virtual_layout with the run's channel offsets (NULL: none). */
static int layout_with_offsets(const sasnav_array *array, const sasnav_ping_pose *offset,
                               const sasnav_ping_pose *poses, int k, int align,
                               sasnav_ping_pose *local, sasnav_pose *centroid, double *turn)
{
    if (turn) *turn = 0.0;
    if (!array || !poses || !local || !centroid)
        return sasnav_set_error(SASNAV_ERR_ARG, "virtual layout: NULL argument");
    sasnav_array v;
    int rc = sasnav_virtual_array(array, k, &v);
    if (rc) return rc;
    int n = array->n_rx;
    for (int j = 0; j < k; j++) {
        const sasnav_ping_pose *p = &poses[j];
        if (!isfinite(p->tx.x) || !isfinite(p->tx.y) || !isfinite(p->tx.theta) ||
            !isfinite(p->array.x) || !isfinite(p->array.y) || !isfinite(p->array.theta))
            return sasnav_set_error(SASNAV_ERR_ARG, "virtual layout: pose of ping %d is not finite", j);
        if (offset) sasnav_channel_poses(p, offset, n, &local[j * n]);
        else
            for (int l = 0; l < n; l++) local[j * n + l] = *p;
    }
    sasnav_pose c = sasnav_channels_centroid(&v, local);
    for (int i = 0; i < v.n_rx; i++) {
        local[i].tx = sasnav_pose_between(c, local[i].tx);
        local[i].array = sasnav_pose_between(c, local[i].array);
    }
    if (align && k >= 2) {
        /* The pings' positions (each ping's array reference, channel 0) in
         * the centroid's frame, whose x axis is the pings' mean heading:
         * their principal axis should be that axis (no crab). Turn the
         * positions about the centroid by the axis's angle (mod pi); the
         * headings stay. */
        double mx = 0, my = 0, sxx = 0, syy = 0, sxy = 0;
        for (int j = 0; j < k; j++) {
            mx += local[(size_t)j * n].array.x / k;
            my += local[(size_t)j * n].array.y / k;
        }
        for (int j = 0; j < k; j++) {
            double dx = local[(size_t)j * n].array.x - mx, dy = local[(size_t)j * n].array.y - my;
            sxx += dx * dx;
            syy += dy * dy;
            sxy += dx * dy;
        }
        double phi = 0.5 * atan2(2.0 * sxy, sxx - syy);
        double cs = cos(phi), sn = sin(phi);
        if (turn) *turn = -phi;
        for (int i = 0; i < v.n_rx; i++) {
            sasnav_pose *q[2] = {&local[i].tx, &local[i].array};
            for (int t = 0; t < 2; t++) {
                double x = q[t]->x, y = q[t]->y;
                q[t]->x = cs * x + sn * y;
                q[t]->y = -sn * x + cs * y;
            }
        }
    }
    *centroid = c;
    return SASNAV_OK;
}

int sasnav_virtual_layout(const sasnav_array *array, const sasnav_ping_pose *poses, int k,
                          sasnav_ping_pose *local, sasnav_pose *centroid)
{
    return layout_with_offsets(array, NULL, poses, k, 0, local, centroid, NULL);
}

void sasnav_virtual_default_opts(sasnav_virtual_opts *opts)
{
    if (!opts) return;
    memset(opts, 0, sizeof *opts);
    opts->k = 4;
    opts->stride = 0;
    opts->interleave = 1;
    sasnav_pair_default_opts(&opts->pair);
    /* The yaw of a group of omnidirectional pings shows only through its
     * channels' positions: held at the input navigation's (a gyro's). */
    opts->pair.fix_yaw = 1;
    /* The coarse criteria (k, i = 2, 1) of the global and level-1 stages
     * pull disjoint virtual pings onto each other (phase-centre
     * coincidence: docs/navigation.md, "Virtual arrays"); the full ones do
     * not, and these layouts are small. */
    opts->pair.coarse_k = opts->pair.k;
    opts->pair.coarse_i = opts->pair.i;
    /* The coincidence rule of the verdict was measured on uniform arrays
     * (the tank, docs/estimator.md "Verdict"), not on virtual arrays:
     * off, their verdict is the margin's (pair.verdict_coincidence turns
     * it on; it then tests the groups' own phase centres). */
    opts->pair.verdict_coincidence = 0.0;
    /* The equalised search was measured on the paper system's seabeds
     * (docs/estimator.md, "An equalised search"), not on virtual arrays:
     * off (their steps as before it). */
    opts->pair.equalise = 0.0;
    opts->iterations = 2;
    opts->nthreads = 0;
}

void sasnav_virtual_navigation_free(sasnav_virtual_navigation *nav)
{
    if (!nav) return;
    free(nav->pairs);
    free(nav->centroid_in);
    free(nav->centroid);
    free(nav->layout_turn);
    free(nav->nav);
    memset(nav, 0, sizeof *nav);
}

/* The data of the virtual ping made of pings first + m j, j < k (channel
 * j * n_rx + l = channel l of ping first + m j). */
static int virtual_data(const sasnav_run *run, int first, int k, int m, sasnav_cfloat *out)
{
    size_t per = sasnav_run_ping_size(run);
    for (int j = 0; j < k; j++) {
        const sasnav_cfloat *ping = NULL;
        int rc = sasnav_run_get_ping(run, (first + m * j) % run->n_pings, out + (size_t)j * per, &ping);
        if (rc) return rc;
        if (ping != out + (size_t)j * per) memcpy(out + (size_t)j * per, ping, per * sizeof *out);
    }
    return SASNAV_OK;
}

typedef struct {
    const sasnav_run *run;
    const sasnav_virtual_opts *o;
    sasnav_array varray;
    int k, stride, m, n_groups, n_pairs, nv;
    int closed;                   /* the track closes: pairs wrap round */
    sasnav_ping_pose *layout_in;  /* n_groups * nv: local channel poses */
} vctx;

/* One pair (groups g and g + 1) with the thread's estimator. */
static int estimate_pair(const vctx *c, sasnav_pair *est, sasnav_cfloat *dp, sasnav_cfloat *dq,
                         int g, sasnav_virtual_pair *vp)
{
    int h = (g + 1) % c->n_groups; /* the closed loop's last pair wraps round to group 0 */
    int fp = g * c->stride, fq = h * c->stride;
    int rc = virtual_data(c->run, fp, c->k, c->m, dp);
    if (!rc) rc = virtual_data(c->run, fq, c->k, c->m, dq);
    if (!rc)
        rc = sasnav_pair_set_data_channels(est, dp, dq, vp->nominal, c->layout_in + (size_t)g * c->nv,
                                           c->layout_in + (size_t)h * c->nv);
    if (!rc) rc = sasnav_pair_estimate(est, &vp->est);
    if (rc) rc = sasnav_prefix_error(rc, "virtual pings at pings %d and %d", fp, fq);
    return rc;
}

/* Layout and centroid of the group of pings first + m j, j < k, with
 * poses from `nav`; gather: k scratch poses. */
static int group_layout(const vctx *c, const sasnav_ping_pose *nav, int first, int align,
                        sasnav_ping_pose *gather, sasnav_ping_pose *local, sasnav_pose *centroid,
                        double *turn)
{
    for (int j = 0; j < c->k; j++) gather[j] = nav[(first + c->m * j) % c->run->n_pings];
    return layout_with_offsets(&c->run->array, c->run->channel_offset, gather, c->k, align, local,
                               centroid, turn);
}

/* p moved by c along its normal (its yaw + 90 degrees). */
static sasnav_pose moved_across(sasnav_pose p, double c)
{
    return (sasnav_pose){p.x - sin(p.theta) * c, p.y + cos(p.theta) * c, p.theta};
}

/* along_input: the groups' input centroids moved along their normals
 * only. With X_g = C_g + c_g n_g (C_g the input centroid, n_g its normal),
 * the step from g to h = g + 1 read in g's frame has the sway (X_h - X_g)
 * . n_g = nominal sway + c_h cos(yaw_h - yaw_g) - c_g; setting it to the
 * used step's sway chains c from c_0 = 0. Closed: c should come back to 0
 * after the last step; its end value is spread evenly over the groups, as
 * the pose chain spreads its misclosure. The yaws stay the input's. */
static void across_only(const vctx *c, sasnav_virtual_navigation *out)
{
    int ng = c->n_groups;
    double cg = 0.0, end = 0.0;
    out->centroid[0] = out->centroid_in[0];
    for (int g = 0; g < c->n_pairs; g++) {
        int h = (g + 1) % ng;
        const sasnav_virtual_pair *vp = &out->pairs[g];
        double cos_turn = cos(sasnav_wrap_angle(out->centroid_in[h].theta - out->centroid_in[g].theta));
        cg = (vp->step.y - vp->nominal.y + cg) / cos_turn;
        if (h == 0) end = cg; /* the closed loop's way back to group 0 */
        else out->centroid[h] = moved_across(out->centroid_in[h], cg);
    }
    if (c->closed) {
        out->misclosure = moved_across((sasnav_pose){0.0, 0.0, out->centroid_in[0].theta}, end);
        out->misclosure.theta = 0.0;
        for (int g = 1; g < ng; g++) out->centroid[g] = moved_across(out->centroid[g], -(double)g / ng * end);
    }
}

/* turn_exposure: the largest position error that a turn of every step by
 * turn_mean (a crab, a heading bias) leaves in the chained centroids.
 * Chained poses: the chain turned about group 0, so |turn_mean| times the
 * largest distance of a centroid from group 0's (the track's length on a
 * straight track; at most the diameter on a closed circle, whose chain
 * still closes). along_input: every step's sway grows by turn_mean times
 * its length, so c_g by turn_mean times the length chained to g; a closed
 * loop's spread takes out the part proportional to g. */
static void turn_exposure(const vctx *c, sasnav_virtual_navigation *out)
{
    int ng = c->n_groups;
    double worst = 0.0;
    if (c->o->along_input) {
        double total = 0.0, run_len = 0.0;
        for (int g = 0; g < c->n_pairs; g++) total += hypot(out->pairs[g].step.x, out->pairs[g].step.y);
        for (int g = 0; g < ng; g++) {
            double e = run_len - (c->closed ? (double)g / ng * total : 0.0);
            worst = fmax(worst, fabs(e));
            if (g < c->n_pairs) run_len += hypot(out->pairs[g].step.x, out->pairs[g].step.y);
        }
    } else {
        for (int g = 1; g < ng; g++)
            worst = fmax(worst, hypot(out->centroid[g].x - out->centroid[0].x,
                                      out->centroid[g].y - out->centroid[0].y));
    }
    out->turn_exposure = fabs(out->turn_mean) * worst;
}

/* One pass over the pairs with `nav` as the input navigation: layouts,
 * nominal and true displacements, the estimates (opts->nthreads at once),
 * and the chained centroids (centroid[0] = centroid_in[0]). */
static int one_pass(vctx *c, const sasnav_ping_pose *nav, sasnav_virtual_navigation *out)
{
    const sasnav_run *run = c->run;
    const sasnav_virtual_opts *opts = c->o;
    int ng = c->n_groups, rc = SASNAV_OK;
    sasnav_ping_pose *scratch = malloc(sizeof *scratch * (size_t)(c->nv + c->k));
    if (!scratch) return sasnav_set_error(SASNAV_ERR_NOMEM, "virtual arrays: out of memory");
    sasnav_ping_pose *gather = scratch + c->nv;
    for (int g = 0; g < ng && !rc; g++)
        rc = group_layout(c, nav, g * c->stride, c->o->align_heading, gather,
                          c->layout_in + (size_t)g * c->nv, &out->centroid_in[g], &out->layout_turn[g]);
    for (int g = 0; g < c->n_pairs && !rc; g++) {
        sasnav_virtual_pair *vp = &out->pairs[g];
        int h = (g + 1) % ng;
        /* along_input reads each step's sway across the next group's
         * normal, 1 / cos of the turn between them: refused past 60 degrees */
        double turn = sasnav_wrap_angle(out->centroid_in[h].theta - out->centroid_in[g].theta);
        if (opts->along_input && !(cos(turn) >= 0.5)) {
            rc = sasnav_set_error(SASNAV_ERR_ARG,
                                  "virtual arrays: along-track from the input: the groups at pings %d "
                                  "and %d turn by %.1f degrees (at most 60: fewer pings between "
                                  "groups)",
                                  g * c->stride, h * c->stride, fabs(turn) * 180.0 / M_PI);
            break;
        }
        memset(vp, 0, sizeof *vp);
        vp->first_p = g * c->stride;
        vp->first_q = h * c->stride;
        vp->nominal = sasnav_pose_between(out->centroid_in[g], out->centroid_in[h]);
        vp->truth = (sasnav_pose){NAN, NAN, NAN};
        if (run->truth) {
            sasnav_pose cp, cq;
            rc = group_layout(c, run->truth, vp->first_p, 0, gather, scratch, &cp, NULL);
            if (!rc) rc = group_layout(c, run->truth, vp->first_q, 0, gather, scratch, &cq, NULL);
            if (!rc) vp->truth = sasnav_pose_between(cp, cq);
        }
    }
    free(scratch);
    if (rc) return rc;

    int nthreads = opts->nthreads > 0 ? opts->nthreads : omp_get_max_threads();
    if (nthreads > c->n_pairs) nthreads = c->n_pairs;
    int failed = 0, fail_rc = SASNAV_OK;
    char fail_msg[512] = "";
#pragma omp parallel num_threads(nthreads)
    {
        sasnav_pair_opts po = opts->pair;
        po.nthreads = 1;
        sasnav_pair *est = NULL;
        size_t nd = sasnav_run_ping_size(run) * (size_t)c->k;
        sasnav_cfloat *dp = malloc(nd * sizeof *dp), *dq = malloc(nd * sizeof *dq);
        int trc = dp && dq ? sasnav_pair_create(&run->sys, &c->varray, &run->win, &po, &est)
                           : sasnav_set_error(SASNAV_ERR_NOMEM, "virtual arrays: out of memory");
#pragma omp for schedule(dynamic, 1)
        for (int g = 0; g < c->n_pairs; g++) {
            int stop;
#pragma omp atomic read
            stop = failed;
            if (stop) continue;
            if (!trc) trc = estimate_pair(c, est, dp, dq, g, &out->pairs[g]);
            if (trc) {
#pragma omp critical(sasnav_virtual_failure)
                if (!failed) {
                    failed = 1;
                    fail_rc = trc;
                    snprintf(fail_msg, sizeof fail_msg, "%s", sasnav_last_error());
                }
            }
        }
        sasnav_pair_destroy(est);
        free(dp);
        free(dq);
    }
    if (failed) return sasnav_set_error(fail_rc, "%s", fail_msg);
    /* A step whose estimate is not "ok" (ambiguous, failed, no overlap)
     * is not trusted: the chain takes the input navigation's step there. */
    out->n_fallback = 0;
    double len_in = 0, len_est = 0;
    for (int g = 0; g < c->n_pairs; g++) {
        sasnav_virtual_pair *vp = &out->pairs[g];
        vp->used = vp->est.verdict == SASNAV_VERDICT_OK;
        vp->step = vp->used ? vp->est.displacement : vp->nominal;
        out->n_fallback += !vp->used;
        if (vp->used) {
            len_in += hypot(vp->nominal.x, vp->nominal.y);
            len_est += hypot(vp->step.x, vp->step.y);
        }
    }
    /* keep_length: the used steps' length from the input navigation. */
    out->length_scale = opts->keep_length && len_est > 0 && len_in > 0 ? len_in / len_est : 1.0;
    for (int g = 0; g < c->n_pairs && out->length_scale != 1.0; g++) {
        sasnav_virtual_pair *vp = &out->pairs[g];
        if (!vp->used) continue;
        vp->step.x *= out->length_scale;
        vp->step.y *= out->length_scale;
    }
    /* align_heading: how far the layouts were turned; their mean is what a
     * crab or a heading bias would contribute (the steps turned alike). */
    out->turn_mean = out->turn_rms = out->turn_exposure = 0.0;
    if (opts->align_heading) {
        for (int g = 0; g < ng; g++) {
            out->turn_mean += out->layout_turn[g] / ng;
            out->turn_rms += out->layout_turn[g] * out->layout_turn[g] / ng;
        }
        out->turn_rms = sqrt(out->turn_rms);
    }
    if (opts->along_input) {
        across_only(c, out);
        if (opts->align_heading) turn_exposure(c, out);
        return SASNAV_OK;
    }
    out->centroid[0] = out->centroid_in[0];
    for (int g = 0; g + 1 < ng; g++)
        out->centroid[g + 1] = sasnav_pose_compose(out->centroid[g], out->pairs[g].step);
    if (c->closed) {
        /* The loop's last step should land on group 0: spread the
         * misclosure evenly over the n steps (least squares with equal
         * weights on the world-frame steps; yaw likewise). */
        sasnav_pose end = sasnav_pose_compose(out->centroid[ng - 1], out->pairs[ng - 1].step);
        double ex = end.x - out->centroid[0].x, ey = end.y - out->centroid[0].y;
        double et = sasnav_wrap_angle(end.theta - out->centroid[0].theta);
        out->misclosure = (sasnav_pose){ex, ey, et};
        for (int g = 1; g < ng; g++) {
            double f = (double)g / ng;
            out->centroid[g].x -= f * ex;
            out->centroid[g].y -= f * ey;
            out->centroid[g].theta = sasnav_wrap_angle(out->centroid[g].theta - f * et);
        }
    }
    if (opts->align_heading) turn_exposure(c, out);
    return SASNAV_OK;
}

/* The corrected navigation: group g's correction D_g = centroid[g] *
 * inverse(centroid_in[g]) (a rigid move), interpolated linearly in ping
 * index between the groups' middle pings (x, y, yaw components; constant
 * before the first and after the last), applied to each ping of `nav`.
 * Interpolation rather than moving each group as a block: the pings of a
 * group then follow the slope between its neighbours, so the next pass's
 * layouts carry the tilt and stretch that the input navigation had wrong
 * inside the groups (measured: docs/navigation.md, "Virtual arrays"). */
static void apply_corrections(const vctx *c, const sasnav_ping_pose *nav,
                              const sasnav_virtual_navigation *v, sasnav_ping_pose *out)
{
    int ng = c->n_groups;
    double half = 0.5 * c->m * (c->k - 1);
    for (int i = 0; i < c->run->n_pings; i++) {
        double u = ((double)i - half) / c->stride; /* group coordinate */
        int g = (int)floor(u);
        double w = u - g;
        if (c->closed) {
            g = ((g % ng) + ng) % ng; /* round the loop */
        } else if (g < 0) {
            g = 0;
            w = 0;
        } else if (g >= ng - 1) {
            g = ng - 1;
            w = 0;
        }
        int h = (g + 1) % ng;
        sasnav_pose d0 = sasnav_pose_compose(v->centroid[g], sasnav_pose_inverse(v->centroid_in[g]));
        sasnav_pose d = d0;
        if (w > 0) {
            sasnav_pose d1 = sasnav_pose_compose(v->centroid[h], sasnav_pose_inverse(v->centroid_in[h]));
            d.x = (1 - w) * d0.x + w * d1.x;
            d.y = (1 - w) * d0.y + w * d1.y;
            d.theta = d0.theta + w * sasnav_wrap_angle(d1.theta - d0.theta);
        }
        out[i].tx = sasnav_pose_compose(d, nav[i].tx);
        out[i].array = sasnav_pose_compose(d, nav[i].array);
    }
}

int sasnav_navigate_virtual(const sasnav_run *run, const sasnav_virtual_opts *opts,
                            sasnav_virtual_navigation *out)
{
    if (!run || !opts || !out) return sasnav_set_error(SASNAV_ERR_ARG, "navigate_virtual: NULL argument");
    memset(out, 0, sizeof *out);
    double t0 = sasnav_now_seconds();
    int rc = sasnav_run_check_header(run);
    if (rc) return rc;
    vctx c;
    memset(&c, 0, sizeof c);
    c.run = run;
    c.o = opts;
    c.k = opts->k;
    c.m = opts->interleave;
    if (c.k < 1) return sasnav_set_error(SASNAV_ERR_ARG, "virtual arrays: k = %d must be >= 1", c.k);
    if (c.m < 1 || c.m > 1000)
        return sasnav_set_error(SASNAV_ERR_ARG, "virtual arrays: interleave = %d must be 1..1000", c.m);
    c.stride = opts->stride > 0 ? opts->stride : c.m > 1 ? 1 : opts->k;
    if (opts->iterations < 1 || opts->iterations > 20)
        return sasnav_set_error(SASNAV_ERR_ARG, "virtual arrays: iterations = %d must be 1..20",
                                opts->iterations);
    rc = sasnav_virtual_array(&run->array, c.k, &c.varray);
    if (rc) return rc;
    rc = sasnav_pair_opts_check(&opts->pair);
    if (rc) return rc;
    long span = (long)c.m * (c.k - 1) + 1; /* pings a group spans */
    c.closed = opts->closed != 0;
    if (c.closed) {
        /* Groups start every stride pings all round; the track must close:
         * the last ping within two nominal steps of the first. */
        double step = run->ping_spacing > 0 ? run->ping_spacing : 0.0;
        sasnav_pose a = sasnav_ping_centroid(&run->nav[0]);
        sasnav_pose b = sasnav_ping_centroid(&run->nav[run->n_pings - 1]);
        if (run->n_pings % c.stride || span > run->n_pings / 2 ||
            !(hypot(a.x - b.x, a.y - b.y) <= 2.0 * step))
            return sasnav_set_error(SASNAV_ERR_ARG,
                                    "virtual arrays: --closed needs a track whose last ping lies "
                                    "within two steps of its first (%.4g m apart, step %.4g m), "
                                    "a stride dividing the %d pings and groups spanning less than "
                                    "half of them",
                                    hypot(a.x - b.x, a.y - b.y), step, run->n_pings);
        c.n_groups = run->n_pings / c.stride;
    } else {
        c.n_groups = run->n_pings >= span ? (int)((run->n_pings - span) / c.stride + 1) : 0;
    }
    c.n_pairs = c.closed ? c.n_groups : c.n_groups - 1;
    if (c.n_groups < 2)
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "virtual arrays: %d pings make fewer than two groups of %d pings "
                                "(a ping every %d, a group every %d pings)",
                                run->n_pings, c.k, c.m, c.stride);
    c.nv = c.varray.n_rx;
    int ng = c.n_groups;
    out->n_pings = run->n_pings;
    out->k = c.k;
    out->stride = c.stride;
    out->interleave = c.m;
    out->n_groups = ng;
    out->n_pairs = c.n_pairs;
    out->closed = c.closed;
    out->align_heading = opts->align_heading != 0;
    out->along_input = opts->along_input != 0;
    out->pairs = calloc((size_t)ng, sizeof *out->pairs);
    out->centroid_in = calloc((size_t)ng, sizeof *out->centroid_in);
    out->centroid = calloc((size_t)ng, sizeof *out->centroid);
    out->layout_turn = calloc((size_t)ng, sizeof *out->layout_turn);
    out->nav = calloc((size_t)run->n_pings, sizeof *out->nav);
    sasnav_ping_pose *cur = malloc(sizeof *cur * (size_t)run->n_pings);
    c.layout_in = malloc(sizeof *c.layout_in * (size_t)ng * (size_t)c.nv);
    if (!out->pairs || !out->centroid_in || !out->centroid || !out->layout_turn || !out->nav ||
        !c.layout_in || !cur) {
        free(c.layout_in);
        free(cur);
        sasnav_virtual_navigation_free(out);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "virtual arrays: out of memory");
    }
    memcpy(cur, run->nav, sizeof *cur * (size_t)run->n_pings);
    for (int it = 0; it < opts->iterations && !rc; it++) {
        rc = one_pass(&c, cur, out);
        if (!rc) {
            apply_corrections(&c, cur, out, out->nav);
            memcpy(cur, out->nav, sizeof *cur * (size_t)run->n_pings);
        }
        out->iterations = it + 1;
    }
    free(c.layout_in);
    free(cur);
    if (rc) {
        sasnav_virtual_navigation_free(out);
        return rc;
    }
    out->seconds = sasnav_now_seconds() - t0;
    return SASNAV_OK;
}
