/* Minimal test helpers: CHECK macros that report file:line and count
 * failures; a test returns test_summary() from main. */
#ifndef SASNAV_TESTUTIL_H
#define SASNAV_TESTUTIL_H

#include <stdio.h>

#include "sasnav/image.h"
#include "sasnav/tank.h"

extern int test_failures;
extern int test_checks;

#define CHECK(cond, ...)                                                         \
    do {                                                                         \
        test_checks++;                                                           \
        if (!(cond)) {                                                           \
            test_failures++;                                                     \
            fprintf(stderr, "%s:%d: CHECK failed: %s: ", __FILE__, __LINE__, #cond); \
            fprintf(stderr, __VA_ARGS__);                                        \
            fprintf(stderr, "\n");                                               \
        }                                                                        \
    } while (0)

#define CHECK_OK(expr)                                                           \
    do {                                                                         \
        int rc_ = (expr);                                                        \
        CHECK(rc_ == 0, "%s returned %d (%s)", #expr, rc_, sasnav_last_error()); \
    } while (0)

/* Prints a summary and returns the process exit status (0 = pass); removes
 * test_tmpdir() after a clean run (kept after a failure or with
 * SASNAV_KEEP_TMP set). */
int test_summary(const char *name);

/* A fresh temporary directory for the test's files (created, mkdtemp). */
const char *test_tmpdir(void);

/* The tank recording of `p` written as WAV files under test_tmpdir()/rec
 * and read back through the ingest chain with the default read options
 * (CHECKs each step; NULL on failure). Free with sasnav_run_free. */
sasnav_run *test_tank_run(const sasnav_tank_params *p);

/* A short tank run through test_tank_run: the default tank with n_pings
 * centred on the plate, the surge jump before ping jump_ping and 50 clutter
 * points (a lighter scene for quick tests). */
sasnav_run *test_tank_short_run(int n_pings, int jump_ping);

/* |image| peak of a grid image: its value, and its sub-pixel position
 * (parabolic fit through the peak and its neighbours along x and y). */
double test_image_peak(const sasnav_grid *g, const sasnav_cfloat *img, double *px, double *py);

/* Direct backprojection of `run` with poses `nav` on `g` (one thread) into
 * img, and FFBP of the same into a scratch image: FFBP's error against the
 * direct sum in dB (10 log10 of the squared-error ratio; 0 on failure,
 * counted). */
double test_backproject_ffbp(sasnav_run *run, const sasnav_ping_pose *nav, const sasnav_grid *g,
                             sasnav_cfloat *img);

/* Field-by-field equality of two systems (memcmp would compare the
 * struct's padding bytes, which copies need not keep). */
static inline int test_same_system(const sasnav_system *a, const sasnav_system *b)
{
    return a->sound_speed == b->sound_speed && a->f0 == b->f0 && a->bandwidth == b->bandwidth &&
           a->sample_rate == b->sample_rate && a->taper == b->taper &&
           a->attenuation == b->attenuation && a->beam_pattern == b->beam_pattern;
}

/* Final-stage estimator iterations for the tests that run whole searches:
 * coarse ones keep the sanitized build inside its time budget. */
#ifdef SASNAV_TEST_SANITIZED
#define EST_K 2
#define EST_I 1
#else
#define EST_K 8
#define EST_I 8
#endif

#endif
