/* Small statistics helpers shared by the bench programs. */
#ifndef SASNAV_BENCH_STATS_H
#define SASNAV_BENCH_STATS_H

#include <math.h>
#include <stdlib.h>

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* Percentile (0..100) of n values by linear interpolation (sorts v). */
static double percentile(double *v, int n, double pc)
{
    if (n < 1) return NAN;
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    double r = pc / 100.0 * (n - 1);
    int i = (int)floor(r);
    if (i >= n - 1) return v[n - 1];
    return v[i] + (r - i) * (v[i + 1] - v[i]);
}

#endif
