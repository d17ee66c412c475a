/* The acoustic system and the receiver array: defaults and checks (model.h,
 * geometry.h). In the core because every layer, the run included, checks
 * what it is given against them. */
#include "sasnav/model.h"
#include "sasnav/geometry.h"
#include "sasnav/error.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

void sasnav_system_default(sasnav_system *sys)
{
    if (!sys) return;
    sys->sound_speed = 1500.0;
    sys->f0 = 300e3;
    sys->bandwidth = 30e3;
    sys->sample_rate = 60e3;
    sys->taper = SASNAV_TAPER_NONE;
    sys->attenuation = SASNAV_ATTEN_EXPLODING;
    sys->beam_pattern = 1;
}

static int check_positive(double v, const char *what)
{
    if (!isfinite(v) || !(v > 0.0))
        return sasnav_set_error(SASNAV_ERR_ARG, "system: %s must be finite and > 0, got %g",
                                what, v);
    return SASNAV_OK;
}

int sasnav_system_check(const sasnav_system *sys)
{
    if (!sys) return sasnav_set_error(SASNAV_ERR_ARG, "system description is NULL");
    int rc = check_positive(sys->sound_speed, "sound_speed");
    if (!rc) rc = check_positive(sys->f0, "f0");
    if (!rc) rc = check_positive(sys->bandwidth, "bandwidth");
    if (!rc) rc = check_positive(sys->sample_rate, "sample_rate");
    if (rc) return rc;
    if (sys->sound_speed < SASNAV_SOUND_SPEED_MIN || sys->sound_speed > SASNAV_SOUND_SPEED_MAX)
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "system: sound_speed %g m/s is outside the physically possible "
                                "%g..%g m/s",
                                sys->sound_speed, SASNAV_SOUND_SPEED_MIN, SASNAV_SOUND_SPEED_MAX);
    if (sys->f0 < SASNAV_F0_MIN || sys->f0 > SASNAV_F0_MAX)
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "system: f0 %g Hz is outside the plausible %g..%g Hz", sys->f0,
                                SASNAV_F0_MIN, SASNAV_F0_MAX);
    if (sys->sample_rate > SASNAV_SAMPLE_RATE_MAX)
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "system: sample_rate %g Hz is above the plausible %g Hz",
                                sys->sample_rate, SASNAV_SAMPLE_RATE_MAX);
    if (sys->sample_rate < sys->bandwidth)
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "system: sample_rate %g Hz is below the bandwidth %g Hz "
                                "(complex sampling needs fs >= B)",
                                sys->sample_rate, sys->bandwidth);
    if (!(sys->f0 > 0.5 * sys->bandwidth))
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "system: f0 %g Hz must exceed half the bandwidth (%g Hz)", sys->f0,
                                0.5 * sys->bandwidth);
    if (sys->taper != SASNAV_TAPER_NONE && sys->taper != SASNAV_TAPER_HANN &&
        sys->taper != SASNAV_TAPER_HAMMING)
        return sasnav_set_error(SASNAV_ERR_ARG, "system: unknown taper %d", (int)sys->taper);
    if (sys->attenuation != SASNAV_ATTEN_EXPLODING && sys->attenuation != SASNAV_ATTEN_SPHERICAL &&
        sys->attenuation != SASNAV_ATTEN_NONE)
        return sasnav_set_error(SASNAV_ERR_ARG, "system: unknown attenuation model %d",
                                (int)sys->attenuation);
    if (sys->beam_pattern != 0 && sys->beam_pattern != 1)
        return sasnav_set_error(SASNAV_ERR_ARG, "system: beam_pattern must be 0 or 1, got %d",
                                sys->beam_pattern);
    return SASNAV_OK;
}

/* Checks one set of sizes; `who` names it in the message ("array",
 * "array: channel 3"). */
static int check_size(sasnav_channel_size z, const char *who)
{
    if (!isfinite(z.rx_length) || z.rx_length < 0 || !isfinite(z.tx_length) || z.tx_length < 0)
        return sasnav_set_error(SASNAV_ERR_ARG, "%s: element lengths must be finite and >= 0", who);
    if (z.rx_length > SASNAV_SIZE_MAX_M || z.tx_length > SASNAV_SIZE_MAX_M)
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "%s: element lengths rx_length %g m, tx_length %g m: above the "
                                "plausible %g m",
                                who, z.rx_length, z.tx_length, SASNAV_SIZE_MAX_M);
    if (!isfinite(z.rx_height) || !isfinite(z.tx_height))
        return sasnav_set_error(SASNAV_ERR_ARG, "%s: sensor heights must be finite", who);
    if (fabs(z.rx_height) > SASNAV_HEIGHT_MAX_M || fabs(z.tx_height) > SASNAV_HEIGHT_MAX_M)
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "%s: heights rx_height %g m, tx_height %g m: beyond the "
                                "plausible +-%g m",
                                who, z.rx_height, z.tx_height, SASNAV_HEIGHT_MAX_M);
    return SASNAV_OK;
}

static sasnav_channel_size array_size(const sasnav_array *a)
{
    sasnav_channel_size z = {a->rx_length, a->tx_length, a->rx_height, a->tx_height};
    return z;
}

sasnav_channel_size sasnav_array_channel_size(const sasnav_array *array, int l)
{
    return array->per_channel ? array->size[l] : array_size(array);
}

static int check_sizes(int n, const sasnav_channel_size *sizes)
{
    for (int l = 0; l < n; l++) {
        char who[48];
        snprintf(who, sizeof who, "array: channel %d", l);
        int rc = check_size(sizes[l], who);
        if (rc) return rc;
    }
    return SASNAV_OK;
}

int sasnav_array_set_sizes(sasnav_array *array, const sasnav_channel_size *sizes)
{
    if (!array) return sasnav_set_error(SASNAV_ERR_ARG, "array is NULL");
    if (!sizes) {
        array->per_channel = 0;
        memset(array->size, 0, sizeof array->size);
        return SASNAV_OK;
    }
    if (array->n_rx < 1 || array->n_rx > SASNAV_MAX_RX)
        return sasnav_set_error(SASNAV_ERR_ARG, "array needs 1..%d receivers, got %d",
                                SASNAV_MAX_RX, array->n_rx);
    int rc = check_sizes(array->n_rx, sizes);
    if (rc) return rc;
    double rl = 0, tl = 0, rh = 0, th = 0;
    for (int l = 0; l < array->n_rx; l++) {
        rl = fmax(rl, sizes[l].rx_length);
        tl = fmax(tl, sizes[l].tx_length);
        rh += sizes[l].rx_height;
        th += sizes[l].tx_height;
    }
    memset(array->size, 0, sizeof array->size);
    memcpy(array->size, sizes, (size_t)array->n_rx * sizeof *sizes);
    array->per_channel = 1;
    array->rx_length = rl;
    array->tx_length = tl;
    array->rx_height = rh / array->n_rx;
    array->tx_height = th / array->n_rx;
    return SASNAV_OK;
}

int sasnav_array_select(const sasnav_array *array, const int *pick, int n, sasnav_array *out)
{
    if (!array || !pick || !out) return sasnav_set_error(SASNAV_ERR_ARG, "array select: NULL argument");
    if (n < 1 || n > SASNAV_MAX_RX)
        return sasnav_set_error(SASNAV_ERR_ARG, "array select: %d channels (1..%d)", n, SASNAV_MAX_RX);
    for (int l = 0; l < n; l++)
        if (pick[l] < 0 || pick[l] >= array->n_rx)
            return sasnav_set_error(SASNAV_ERR_ARG, "array select: channel %d outside 0..%d", pick[l],
                                    array->n_rx - 1);
    sasnav_array a = *array;
    a.n_rx = n;
    memset(a.rx_u, 0, sizeof a.rx_u);
    memset(a.size, 0, sizeof a.size);
    for (int l = 0; l < n; l++) a.rx_u[l] = array->rx_u[pick[l]];
    if (array->per_channel) {
        sasnav_channel_size z[SASNAV_MAX_RX];
        for (int l = 0; l < n; l++) z[l] = array->size[pick[l]];
        int rc = sasnav_array_set_sizes(&a, z);
        if (rc) return rc;
    }
    *out = a;
    return SASNAV_OK;
}

double sasnav_array_min_rx_length(const sasnav_array *array)
{
    double m = 0.0;
    int n = array->per_channel ? array->n_rx : 1;
    for (int l = 0; l < n; l++) {
        double d = sasnav_array_channel_size(array, l).rx_length;
        if (d > 0 && (m == 0.0 || d < m)) m = d;
    }
    return m;
}

int sasnav_array_check(const sasnav_array *array)
{
    if (!array) return sasnav_set_error(SASNAV_ERR_ARG, "array description is NULL");
    if (array->n_rx < 1 || array->n_rx > SASNAV_MAX_RX)
        return sasnav_set_error(SASNAV_ERR_ARG, "array needs 1..%d receivers, got %d",
                                SASNAV_MAX_RX, array->n_rx);
    int rc = check_size(array_size(array), "array");
    if (rc) return rc;
    if (array->per_channel != 0 && array->per_channel != 1)
        return sasnav_set_error(SASNAV_ERR_ARG, "array: per_channel must be 0 or 1, got %d",
                                array->per_channel);
    if (array->per_channel) {
        rc = check_sizes(array->n_rx, array->size);
        if (rc) return rc;
    }
    for (int l = 0; l < array->n_rx; l++) {
        if (!isfinite(array->rx_u[l]))
            return sasnav_set_error(SASNAV_ERR_ARG, "receiver %d position is not finite", l);
        if (fabs(array->rx_u[l]) > SASNAV_SIZE_MAX_M)
            return sasnav_set_error(SASNAV_ERR_ARG,
                                    "array: rx_u[%d] = %g m is beyond the plausible +-%g m", l,
                                    array->rx_u[l], SASNAV_SIZE_MAX_M);
    }
    return SASNAV_OK;
}

int sasnav_array_uniform(sasnav_array *array, int n, double spacing, double length,
                         double tx_length)
{
    if (!array) return sasnav_set_error(SASNAV_ERR_ARG, "array is NULL");
    if (n < 1 || n > SASNAV_MAX_RX)
        return sasnav_set_error(SASNAV_ERR_ARG, "array needs 1..%d receivers, got %d",
                                SASNAV_MAX_RX, n);
    if (!(spacing > 0) || !isfinite(spacing))
        return sasnav_set_error(SASNAV_ERR_ARG, "receiver spacing must be > 0, got %g", spacing);
    sasnav_array a = {0};
    a.n_rx = n;
    for (int l = 0; l < n; l++) a.rx_u[l] = (l - 0.5 * (n - 1)) * spacing;
    a.rx_length = length;
    a.tx_length = tx_length;
    int rc = sasnav_array_check(&a);
    if (rc) return rc;
    *array = a;
    return SASNAV_OK;
}
