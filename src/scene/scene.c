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

/* Seabed zones of the survey scene along track. */
#define ZONE_LENGTH 40.0   /* m */
#define ROCK_AREA 150.0    /* m^2 per rock */
#define ROCK_POINTS 40
#define TARGET_SPACING 25.0 /* m along track */
#define CYL_POINTS 21      /* per edge line, 10 cm apart */

int sasnav_scene_survey(const sasnav_ripple_params *p, int max_targets, double *targets_x,
                        double *targets_y, int *n_targets, sasnav_scene **scene)
{
    if (!p || !scene) return sasnav_set_error(SASNAV_ERR_ARG, "NULL argument");
    if (n_targets) *n_targets = 0;
    double w = p->x_max - p->x_min, h = p->y_max - p->y_min;
    if (!(w > 0) || !(h > 0) || !isfinite(w) || !isfinite(h))
        return sasnav_set_error(SASNAV_ERR_ARG, "scene extent must be a non-empty rectangle");
    if (!(p->density > 0) || !isfinite(p->density) || !(p->ripple_period > 0) ||
        !isfinite(p->ripple_angle) || !(p->ripple_depth >= 0 && p->ripple_depth <= 1) ||
        !(p->background >= 0) || !isfinite(p->background))
        return sasnav_set_error(SASNAV_ERR_ARG, "invalid survey scene parameters");
    /* Counts in double first: a huge extent must be refused, not overflow
     * a cast into a negative count (a heap overflow, found by review). */
    double area = w * h, n_bg = area * p->density;
    double rocks = floor(area / ROCK_AREA), tgs = floor(w / TARGET_SPACING);
    double count = n_bg + rocks * ROCK_POINTS + tgs * 2 * CYL_POINTS;
    if (!(count <= 5e7))
        return sasnav_set_error(SASNAV_ERR_ARG, "scene would hold %.3g scatterers (max 5e7)", count);
    long n_rocks = (long)rocks, n_tg = (long)tgs;
    int rc = scene_alloc((int)ceil(count) + 1, scene);
    if (rc) return rc;
    sasnav_scene *s = *scene;
    sasnav_rng rng;
    sasnav_rng_seed(&rng, p->seed);
    /* Zone kinds: 0 sand, 1 ripples, 2 mud, drawn per zone. */
    int n_zones = (int)ceil(w / ZONE_LENGTH) + 1;
    unsigned char *zone = malloc((size_t)n_zones);
    if (!zone) {
        sasnav_scene_free(s);
        *scene = NULL;
        return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    }
    for (int z = 0; z < n_zones; z++) zone[z] = (unsigned char)(sasnav_rng_next(&rng) % 3);
    double ca = cos(p->ripple_angle), sa = sin(p->ripple_angle);
    double scale = p->background / sqrt(2.0 * p->density * 1e-4);
    int n = 0;
    long nb = lround(n_bg);
    for (long i = 0; i < nb; i++) {
        double x = p->x_min + w * sasnav_rng_uniform(&rng);
        double y = p->y_min + h * sasnav_rng_uniform(&rng);
        double re = sasnav_rng_normal(&rng), im = sasnav_rng_normal(&rng);
        int z = (int)((x - p->x_min) / ZONE_LENGTH);
        double m = zone[z] == 0 ? 0.5 : zone[z] == 2 ? 0.2
                 : 1.0 + p->ripple_depth * sin(2.0 * M_PI * (-x * sa + y * ca) / p->ripple_period);
        s->x[n] = x;
        s->y[n] = y;
        s->amp[n++] = (float)(m * scale * re) + I * (float)(m * scale * im);
    }
    free(zone);
    for (long r = 0; r < n_rocks; r++) {
        double cx = p->x_min + w * sasnav_rng_uniform(&rng), cy = p->y_min + h * sasnav_rng_uniform(&rng);
        double rad = 0.2 + 0.6 * sasnav_rng_uniform(&rng);
        for (int k = 0; k < ROCK_POINTS; k++) {
            double a = 2 * M_PI * sasnav_rng_uniform(&rng), d = rad * sqrt(sasnav_rng_uniform(&rng));
            double ph = 2 * M_PI * sasnav_rng_uniform(&rng);
            s->x[n] = cx + d * cos(a);
            s->y[n] = cy + d * sin(a);
            s->amp[n++] = (float)(4 * scale * cos(ph)) + I * (float)(4 * scale * sin(ph));
        }
    }
    int nt = 0;
    for (long t = 0; t < n_tg; t++) {
        double cx = p->x_min + (t + 0.5) * TARGET_SPACING;
        double cy = p->y_min + 0.15 * h + 0.7 * h * sasnav_rng_uniform(&rng);
        int kind = (int)(sasnav_rng_next(&rng) % 2);
        double yaw = M_PI * sasnav_rng_uniform(&rng);
        if (kind == 0) {
            /* Sphere: one bright point. */
            s->x[n] = cx;
            s->y[n] = cy;
            s->amp[n++] = (float)(30 * scale);
        } else {
            /* Cylinder, 2 m x 0.5 m: its two edges, coherent lines. */
            for (int e = -1; e <= 1; e += 2)
                for (int k = 0; k < CYL_POINTS; k++) {
                    double a = -1.0 + 2.0 * k / (CYL_POINTS - 1), b = 0.25 * e;
                    s->x[n] = cx + a * cos(yaw) - b * sin(yaw);
                    s->y[n] = cy + a * sin(yaw) + b * cos(yaw);
                    s->amp[n++] = (float)(8 * scale);
                }
        }
        if (targets_x && targets_y && nt < max_targets) {
            targets_x[nt] = cx;
            targets_y[nt] = cy;
        }
        nt++;
    }
    if (n_targets) *n_targets = nt < max_targets ? nt : max_targets;
    s->n = n;
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
