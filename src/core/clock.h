/* Wall-clock seconds for the timings the library reports (monotonic clock).
 * Private to the library and the CLI. */
#ifndef SASNAV_CLOCK_H
#define SASNAV_CLOCK_H

#include <time.h>

static inline double sasnav_now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

#endif
