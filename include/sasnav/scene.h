/* sasnav -- scenes: lists of point scatterers used to simulate raw data.
 * Simulated scatterers are placed off the reconstruction grid (no inverse
 * crime). Every random draw takes a seed.
 *
 * Threads: no shared state, no OpenMP. The random generator's state lives in
 * the caller's sasnav_rng: one generator per thread. Distinct calls may run
 * concurrently; scenes may be shared read-only. */
#ifndef SASNAV_SCENE_H
#define SASNAV_SCENE_H

#include <stdint.h>

#include "sasnav/model.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    int n;
    double *x, *y;          /* m */
    sasnav_cfloat *amp;     /* complex reflectivity of each scatterer */
} sasnav_scene;

/* Parameters of the paper's scene: sand ripples (complex circular Gaussian
 * speckle whose amplitude is modulated by ripples) plus a bright disc. */
typedef struct {
    double x_min, x_max, y_min, y_max; /* m, extent of the speckle field */
    double density;          /* scatterers per square metre (default 2e4) */
    double ripple_period;    /* m, ripple wavelength (default 0.15) */
    double ripple_angle;     /* rad, ripple crest direction from +x (default 0.3) */
    double ripple_depth;     /* 0..1 modulation depth (default 0.6) */
    double background;       /* rms amplitude of the background (default 1) */
    double disc_x, disc_y;   /* m, disc centre */
    double disc_radius;      /* m (default 0.2: 40 cm diameter); 0 = no disc */
    double disc_amplitude;   /* rms amplitude inside the disc (default 4) */
    uint64_t seed;
} sasnav_ripple_params;

void sasnav_ripple_default(sasnav_ripple_params *params);

/* Random scene of the paper (speckle + ripples + disc). */
int sasnav_scene_ripples(const sasnav_ripple_params *params, sasnav_scene **scene);

/* Scene of n point targets (arrays copied). */
/* A survey seabed (the "survey" preset, docs/config.md): over the
 * rectangle of `p` (density, background, ripple period/angle/depth and seed
 * used; the disc ignored), zones about 40 m long along track of sand
 * (speckle at 0.5 background), rippled sand (speckle modulated as the
 * ripple scene) and mud (0.2); rocks (one per 150 m^2: 40 bright
 * scatterers within 0.2-0.8 m); and every 25 m along track a man-made
 * target at a random range: a sphere (one point 30 times the speckle's
 * scatterer scale) or a 2 m x 0.5 m cylinder (its two edges as coherent
 * lines of scatterers 8 times that scale). The
 * targets' centres are written to targets_x/y (up to max_targets; NULL
 * for none) and their number to *n_targets. Seeded: the same seed, the
 * same scene. */
int sasnav_scene_survey(const sasnav_ripple_params *p, int max_targets, double *targets_x,
                        double *targets_y, int *n_targets, sasnav_scene **scene);

int sasnav_scene_points(int n, const double *x, const double *y, const sasnav_cfloat *amp,
                        sasnav_scene **scene);

/* Scene from an image on a grid: one scatterer per pixel with the pixel's
 * value, jittered by +-jitter * pixel size (seeded). */
int sasnav_scene_from_image(double x0, double y0, double dx, double dy, int nx, int ny,
                            const sasnav_cfloat *image, double jitter, uint64_t seed,
                            sasnav_scene **scene);

void sasnav_scene_free(sasnav_scene *scene);

/* Small seeded random generator (splitmix64 + xoshiro256**) used by every
 * random draw in the library, so that results are reproducible. */
typedef struct {
    uint64_t s[4];
} sasnav_rng;

void sasnav_rng_seed(sasnav_rng *rng, uint64_t seed);
uint64_t sasnav_rng_next(sasnav_rng *rng);
double sasnav_rng_uniform(sasnav_rng *rng);  /* [0, 1) */
double sasnav_rng_normal(sasnav_rng *rng);   /* N(0, 1) */

#ifdef __cplusplus
}
#endif
#endif
