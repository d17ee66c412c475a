/* Scenes: point scatterers for the simulator (SPEC 4: the paper's sand
 * ripples plus a 40 cm disc; point targets; a scene from an image). */
#include "sasnav/error.h"
#include "sasnav/scene.h"

#include <math.h>
#include <stdlib.h>

static int scene_alloc(int n, sasnav_scene **out)
{
    sasnav_scene *s = calloc(1, sizeof *s);
    if (!s) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory for a scene");
    s->n = n;
    s->x = malloc(sizeof(double) * (size_t)(n > 0 ? n : 1));
    s->y = malloc(sizeof(double) * (size_t)(n > 0 ? n : 1));
    s->amp = malloc(sizeof(sasnav_cfloat) * (size_t)(n > 0 ? n : 1));
    if (!s->x || !s->y || !s->amp) {
        sasnav_scene_free(s);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory for %d scatterers", n);
    }
    *out = s;
    return SASNAV_OK;
}

void sasnav_scene_free(sasnav_scene *scene)
{
    if (!scene) return;
    free(scene->x);
    free(scene->y);
    free(scene->amp);
    free(scene);
}

void sasnav_ripple_default(sasnav_ripple_params *p)
{
    p->x_min = -1.5;
    p->x_max = 1.5;
    p->y_min = 9.0;
    p->y_max = 11.0;
    p->density = 1e4;
    p->ripple_period = 0.15;
    p->ripple_angle = 0.3;
    p->ripple_depth = 0.6;
    p->background = 1.0;
    p->disc_x = 0.0;
    p->disc_y = 10.0;
    p->disc_radius = 0.2;
    p->disc_amplitude = 4.0;
    p->seed = 1;
}

int sasnav_scene_ripples(const sasnav_ripple_params *p, sasnav_scene **scene)
{
    if (!p || !scene) return sasnav_set_error(SASNAV_ERR_ARG, "NULL argument");
    double w = p->x_max - p->x_min, h = p->y_max - p->y_min;
    if (!(w > 0) || !(h > 0) || !isfinite(w) || !isfinite(h))
        return sasnav_set_error(SASNAV_ERR_ARG, "scene extent must be a non-empty rectangle");
    if (!(p->density > 0) || !isfinite(p->density) || !(p->ripple_period > 0) ||
        !isfinite(p->ripple_angle) || !(p->ripple_depth >= 0 && p->ripple_depth <= 1) ||
        !(p->background >= 0) || !(p->disc_radius >= 0) || !isfinite(p->disc_amplitude) ||
        !isfinite(p->disc_x) || !isfinite(p->disc_y))
        return sasnav_set_error(SASNAV_ERR_ARG, "invalid ripple scene parameters");
    double count = w * h * p->density;
    if (count > 5e7)
        return sasnav_set_error(SASNAV_ERR_ARG, "scene would hold %.3g scatterers (max 5e7)", count);
    int n = (int)lround(count);
    if (n < 1) n = 1;
    int rc = scene_alloc(n, scene);
    if (rc) return rc;
    sasnav_scene *s = *scene;
    sasnav_rng rng;
    sasnav_rng_seed(&rng, p->seed);
    double ca = cos(p->ripple_angle), sa = sin(p->ripple_angle);
    /* Circular complex Gaussian speckle of unit variance per scatterer,
     * normalised so that the mean power per square metre is independent of
     * the density. */
    double scale = 1.0 / sqrt(2.0 * p->density * 1e-4);
    for (int i = 0; i < n; i++) {
        double x = p->x_min + w * sasnav_rng_uniform(&rng);
        double y = p->y_min + h * sasnav_rng_uniform(&rng);
        double re = sasnav_rng_normal(&rng), im = sasnav_rng_normal(&rng);
        double d = -x * sa + y * ca; /* distance across the ripple crests */
        double m = p->background * (1.0 + p->ripple_depth * sin(2.0 * M_PI * d / p->ripple_period));
        double r2 = (x - p->disc_x) * (x - p->disc_x) + (y - p->disc_y) * (y - p->disc_y);
        if (p->disc_radius > 0 && r2 <= p->disc_radius * p->disc_radius) m = p->disc_amplitude;
        s->x[i] = x;
        s->y[i] = y;
        s->amp[i] = (float)(m * scale * re) + I * (float)(m * scale * im);
    }
    return SASNAV_OK;
}

int sasnav_scene_points(int n, const double *x, const double *y, const sasnav_cfloat *amp,
                        sasnav_scene **scene)
{
    if (n < 1 || !x || !y || !amp || !scene)
        return sasnav_set_error(SASNAV_ERR_ARG, "a point scene needs n >= 1 targets");
    for (int i = 0; i < n; i++)
        if (!isfinite(x[i]) || !isfinite(y[i]) || !isfinite(crealf(amp[i])) ||
            !isfinite(cimagf(amp[i])))
            return sasnav_set_error(SASNAV_ERR_ARG, "point target %d is not finite", i);
    int rc = scene_alloc(n, scene);
    if (rc) return rc;
    for (int i = 0; i < n; i++) {
        (*scene)->x[i] = x[i];
        (*scene)->y[i] = y[i];
        (*scene)->amp[i] = amp[i];
    }
    return SASNAV_OK;
}

int sasnav_scene_from_image(double x0, double y0, double dx, double dy, int nx, int ny,
                            const sasnav_cfloat *image, double jitter, uint64_t seed,
                            sasnav_scene **scene)
{
    if (!image || !scene || nx < 1 || ny < 1 || !(dx > 0) || !(dy > 0) || !isfinite(x0) ||
        !isfinite(y0) || !(jitter >= 0 && jitter <= 0.5))
        return sasnav_set_error(SASNAV_ERR_ARG, "invalid image scene arguments");
    int rc = scene_alloc(nx * ny, scene);
    if (rc) return rc;
    sasnav_rng rng;
    sasnav_rng_seed(&rng, seed);
    for (int iy = 0; iy < ny; iy++)
        for (int ix = 0; ix < nx; ix++) {
            int n = iy * nx + ix;
            double jx = (2.0 * sasnav_rng_uniform(&rng) - 1.0) * jitter * dx;
            double jy = (2.0 * sasnav_rng_uniform(&rng) - 1.0) * jitter * dy;
            (*scene)->x[n] = x0 + ix * dx + jx;
            (*scene)->y[n] = y0 + iy * dy + jy;
            sasnav_cfloat a = image[n];
            if (!isfinite(crealf(a)) || !isfinite(cimagf(a))) {
                sasnav_scene_free(*scene);
                *scene = NULL;
                return sasnav_set_error(SASNAV_ERR_ARG, "scene image pixel (%d, %d) is not finite", iy, ix);
            }
            (*scene)->amp[n] = a;
        }
    return SASNAV_OK;
}
