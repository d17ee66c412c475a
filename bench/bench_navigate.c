/* Throughput and accuracy of `sasnav navigate` (subspace estimator) on
 * paper-trajectory runs (16 pings, 15 pairs).
 *
 * usage: bench_navigate [--seeds S0 N] [--snr DB|inf] [--threads T1,T2,...]
 *                       [--gpu | --gpu-copy]
 *
 * For each of N seeds from S0 (the `sasnav simulate --seed` convention:
 * scene 3s+1, trajectory 3s+2, noise 3s+3), simulates the run once and
 * navigates it once per thread count (default 1 and 2). Prints per run and
 * thread count: wall time of the pair estimates, pairs per second, seconds
 * per pair, how many pairs ran at a time, the final cumulative sway error
 * (the paper's figure of merit, bound lambda/25) and whether the pair
 * estimates are bit-identical to those of the first thread count, and where
 * the pairs' time goes (their estimates' stage seconds summed over the
 * pairs; "rest": a pair's wall time outside its stages). Then the
 * peak resident memory (ru_maxrss). --gpu: the evaluations on a CUDA GPU
 * (builds with -DSASNAV_CUDA=ON: docs/estimator.md, "GPU"); --gpu-copy: the
 * same with q's pairs computed on the CPU and copied (the slower variant). */
#include "sasnav/error.h"
#include "sasnav/navigate.h"
#include "sasnav/sim.h"
#include "bench_util.h"
#ifdef SASNAV_HAVE_CUDA
#include "gpu/gpu_eval.h"
#endif

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

#define MAX_T 8

static int same_pairs(const sasnav_navigation *a, const sasnav_navigation *b)
{
    if (a->n_pairs != b->n_pairs) return 0;
    for (int j = 0; j < a->n_pairs; j++) {
        const sasnav_pair_result *x = &a->pairs[j].result, *y = &b->pairs[j].result;
        if (memcmp(&x->error, &y->error, sizeof x->error) || x->eta != y->eta || x->zeta != y->zeta ||
            a->pairs[j].status != b->pairs[j].status)
            return 0;
    }
    return 1;
}

int main(int argc, char **argv)
{
    long s0 = 101, ns = 1;
    double snr = 30.0;
    int threads[MAX_T] = {1, 2}, nt = 2, gpu = 0;
    for (int a = 1; a < argc; a++) {
        if (bench_seed_option(argc, argv, &a, &s0, &ns, &snr)) continue;
        if (!strcmp(argv[a], "--threads") && a + 1 < argc) {
            nt = 0;
            for (char *p = argv[++a]; *p && nt < MAX_T;) {
                threads[nt++] = (int)strtol(p, &p, 10);
                if (*p == ',') p++;
            }
        } else if (!strcmp(argv[a], "--gpu")) {
            gpu = 1;
        } else if (!strcmp(argv[a], "--gpu-copy")) {
            gpu = 2;
        } else {
            fprintf(stderr, "usage: bench_navigate [--seeds S0 N] [--snr DB|inf] [--threads T1,T2,...] "
                            "[--gpu | --gpu-copy]\n");
            return 2;
        }
    }
    if (ns < 1 || nt < 1) return 2;
#ifdef SASNAV_HAVE_CUDA
    gpu_use_device_geometry(gpu != 2);
#endif
    const double lambda = 1500.0 / 300e3;
    printf("paper-trajectory, SNR %g dB, seeds %ld..%ld%s\n", snr, s0, s0 + ns - 1,
           gpu == 1 ? ", evaluations on the GPU" : gpu == 2 ? ", evaluations on the GPU (pairs copied)" : "");
    printf("%6s %8s %10s %10s %10s %8s %14s %10s\n", "seed", "threads", "pairs_s", "pairs/s", "s/pair",
           "at once", "final sway mm", "identical");
    int bad = 0;
    for (long s = s0; s < s0 + ns; s++) {
        sasnav_run *run = bench_trajectory_run(s, snr, 0);
        if (!run) return 1;
        sasnav_navigation first;
        memset(&first, 0, sizeof first);
        for (int t = 0; t < nt; t++) {
            sasnav_navigate_opts no;
            sasnav_navigate_default_opts(&no);
            no.nthreads = threads[t];
            no.pair.gpu = gpu != 0;
            sasnav_navigation nav;
            if (sasnav_navigate(run, &no, &nav)) {
                fprintf(stderr, "navigate: %s\n", sasnav_last_error());
                sasnav_run_free(run);
                return 1;
            }
            double sway = nav.has_truth ? nav.cumulative[nav.n_pings - 1].y : NAN;
            int same = t == 0 ? 1 : same_pairs(&first, &nav);
            bad += !same;
            printf("%6ld %8d %10.2f %10.3f %10.3f %8d %+14.4f %10s%s\n", s, threads[t],
                   nav.seconds_estimation, nav.pairs_per_second, nav.seconds_per_pair,
                   nav.threads_over_pairs, 1e3 * sway, t == 0 ? "-" : same ? "yes" : "NO",
                   fabs(sway) > lambda / 25 ? "  (over lambda/25)" : "");
            double st[5] = {0, 0, 0, 0, 0};
            for (int j = 0; j < nav.n_pairs; j++) {
                const sasnav_pair_result *r = &nav.pairs[j].result;
                st[0] += r->seconds_global;
                st[1] += r->seconds_zeta;
                st[2] += r->seconds_eta;
                st[3] += r->seconds_final;
                st[4] += r->seconds - r->seconds_global - r->seconds_zeta - r->seconds_eta - r->seconds_final;
            }
            printf("       pairs' seconds summed: global %.2f, zeta %.2f, eta %.2f, final %.2f, rest %.2f\n", st[0],
                   st[1], st[2], st[3], st[4]);
            fflush(stdout);
            if (t == 0) first = nav;
            else sasnav_navigation_free(&nav);
        }
        sasnav_navigation_free(&first);
        sasnav_run_free(run);
    }
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    printf("peak memory %.1f MiB; runs whose pair estimates changed with the thread count: %d\n",
           ru.ru_maxrss / 1024.0, bad);
    return bad ? 1 : 0;
}
