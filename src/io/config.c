/* Scenario configuration files: YAML read with libfyaml, written as
 * commented YAML (layout and keys in docs/config.md).
 *
 * One table (config_keys below) names every key with its section, type,
 * admissible range, the struct field it sets and a short comment; the reader
 * and the writer both walk it, so the two cannot drift apart.
 *
 * Numbers are parsed and printed in the "C" locale (uselocale, per thread),
 * so a decimal comma locale cannot change what a file means.
 */
#include "sasnav/config.h"
#include "sasnav/error.h"
#include "sasnav/geometry.h"
#include "sasnav/image.h"
#include "io/textfile.h"

#include <libfyaml.h>

#include <errno.h>
#include <inttypes.h>
#include <locale.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#define CONFIG_MAX_BYTES (1 << 20) /* a scenario file is a few kB */
#define VALUE_MAX 600              /* longest scalar accepted (scene file path + slack) */

/* ---- the key table ---- */

typedef enum {
    V_REAL,       /* finite double with a range rule */
    V_INT,        /* int in [imin, imax] */
    V_SEED,       /* uint64_t */
    V_BOOL,       /* int 0/1 */
    V_STRING,     /* char[size] */
    V_TAPER,      /* sasnav_taper */
    V_ATTEN,      /* sasnav_attenuation */
    V_SCENE_KIND, /* sasnav_scene_kind */
    V_SNR,        /* double, finite or +inf */
    V_POSITIONS,  /* array.rx_positions: sequence of reals */
    V_TX_POSITIONS, /* array.tx_positions: sequence of reals, one per channel */
    V_SIZES,      /* array.rx_heights etc.: sequence of reals, one per channel;
                     imin = the member of sasnav_channel_size (0..3) */
    V_TARGETS,    /* scene.targets: sequence of [x, y, amp] */
    V_PAIR        /* trajectory.pair_error: mapping or none */
} value_kind;

typedef enum { R_ANY, R_POS, R_NONNEG, R_UNIT } real_rule;

/* Where a key's value lives: in the scenario itself, or in one of the
 * staging structs that are turned into the scenario's array / image grid /
 * pair error once the whole file has been read. */
typedef enum { B_SC, B_ARRAY, B_IMAGE, B_PAIR } value_base;

typedef struct {
    int n_rx;
    double rx_spacing;
    double rx_length, tx_length, rx_height, tx_height;
    int n_positions;
    double positions[SASNAV_MAX_RX];
    int n_size[4]; /* per-channel lists: rx_lengths, tx_lengths, rx_heights, tx_heights */
    double size_list[4][SASNAV_MAX_RX];
    int set_n_rx, set_spacing, set_positions, touched;
} array_stage;

typedef struct {
    double x_min, x_max, y_min, y_max;
    int nx, ny;
    int touched;
} image_stage;

typedef struct {
    int ping;
    double surge, sway, yaw;
} pair_stage;

typedef struct {
    const char *section; /* NULL: top level */
    const char *name;
    value_kind kind;
    value_base base;
    size_t offset;
    real_rule rule;
    long imin, imax; /* V_INT range; V_STRING: buffer size in imax */
    const char *comment;
} key_spec;

#define SC(member) B_SC, offsetof(sasnav_scenario, member)
#define AR(member) B_ARRAY, offsetof(array_stage, member)
#define IM(member) B_IMAGE, offsetof(image_stage, member)
#define PE(member) B_PAIR, offsetof(pair_stage, member)

static const key_spec config_keys[] = {
    {NULL, "name", V_STRING, SC(name), R_ANY, 0, sizeof(((sasnav_scenario *)0)->name),
     "free text, names the scenario in outputs"},

    {"system", "sound_speed", V_REAL, SC(sys.sound_speed), R_POS, 0, 0, "m/s"},
    {"system", "f0", V_REAL, SC(sys.f0), R_POS, 0, 0, "Hz, carrier (centre) frequency"},
    {"system", "bandwidth", V_REAL, SC(sys.bandwidth), R_POS, 0, 0, "Hz, compressed pulse band"},
    {"system", "sample_rate", V_REAL, SC(sys.sample_rate), R_POS, 0, 0,
     "Hz, complex baseband rate (>= bandwidth)"},
    {"system", "taper", V_TAPER, SC(sys.taper), R_ANY, 0, 0, "none | hann | hamming"},
    {"system", "attenuation", V_ATTEN, SC(sys.attenuation), R_ANY, 0, 0,
     "exploding | spherical | none"},
    {"system", "beam_pattern", V_BOOL, SC(sys.beam_pattern), R_ANY, 0, 0,
     "true: sinc line-aperture patterns"},

    {"array", "n_rx", V_INT, AR(n_rx), R_ANY, 1, SASNAV_MAX_RX, "receivers"},
    {"array", "rx_spacing", V_REAL, AR(rx_spacing), R_NONNEG, 0, 0, "m, uniform receiver spacing"},
    {"array", "rx_positions", V_POSITIONS, AR(positions), R_ANY, 0, 0,
     "m, explicit receiver positions (non-uniform arrays)"},
    {"array", "tx_positions", V_TX_POSITIONS, SC(channel_tx_u), R_ANY, 0, 0,
     "m, per-channel transmitters along the Tx axis ([] = one Tx)"},
    {"array", "rx_length", V_REAL, AR(rx_length), R_NONNEG, 0, 0,
     "m, receiver aperture (0 = omni)"},
    {"array", "tx_length", V_REAL, AR(tx_length), R_NONNEG, 0, 0,
     "m, transmitter aperture (0 = omni)"},
    {"array", "rx_height", V_REAL, AR(rx_height), R_NONNEG, 0, 0, "m above the scene plane"},
    {"array", "tx_height", V_REAL, AR(tx_height), R_NONNEG, 0, 0, "m above the scene plane"},
    {"array", "rx_lengths", V_SIZES, AR(size_list), R_NONNEG, 0, 0,
     "m, per-channel receiver apertures ([] = rx_length for all)"},
    {"array", "tx_lengths", V_SIZES, AR(size_list), R_NONNEG, 1, 0,
     "m, per-channel transmitter apertures ([] = tx_length)"},
    {"array", "rx_heights", V_SIZES, AR(size_list), R_NONNEG, 2, 0,
     "m, per-channel receiver heights ([] = rx_height)"},
    {"array", "tx_heights", V_SIZES, AR(size_list), R_NONNEG, 3, 0,
     "m, per-channel transmitter heights ([] = tx_height)"},

    {"swath", "range_min", V_REAL, SC(range_min), R_POS, 0, 0, "m"},
    {"swath", "range_max", V_REAL, SC(range_max), R_POS, 0, 0, "m"},
    {"swath", "range_of_interest", V_REAL, SC(range_of_interest), R_POS, 0, 0, "m, mid-range"},

    {"trajectory", "n_pings", V_INT, SC(traj.n_pings), R_ANY, 1, 100000, "pings"},
    {"trajectory", "ping_spacing", V_REAL, SC(traj.ping_spacing), R_POS, 0, 0, "m, nominal"},
    {"trajectory", "speed", V_REAL, SC(traj.speed), R_POS, 0, 0, "m/s"},
    {"trajectory", "x_start", V_REAL, SC(traj.x_start), R_ANY, 0, 0, "m, centroid x of ping 0"},
    {"trajectory", "surge_rms", V_REAL, SC(traj.surge_rms), R_NONNEG, 0, 0, "m, smooth error"},
    {"trajectory", "sway_rms", V_REAL, SC(traj.sway_rms), R_NONNEG, 0, 0, "m, smooth error"},
    {"trajectory", "yaw_rms", V_REAL, SC(traj.yaw_rms), R_NONNEG, 0, 0, "rad, smooth error"},
    {"trajectory", "smooth_length", V_REAL, SC(traj.smooth_length), R_POS, 0, 0,
     "m, correlation length of the errors"},
    {"trajectory", "tx_lag", V_REAL, SC(traj.tx_lag), R_NONNEG, 0, 0,
     "m, Tx-array offset (EPCA); not derived from speed"},
    {"trajectory", "circle_radius", V_REAL, SC(traj.circle_radius), R_NONNEG, 0, 0,
     "m, 0 = straight track; > 0: circle about the origin (turntable)"},
    {"trajectory", "true_bistatic", V_BOOL, SC(traj.true_bistatic), R_ANY, 0, 0,
     "true: Tx/array poses sampled on the path"},
    {"trajectory", "seed", V_SEED, SC(traj.seed), R_ANY, 0, 0, "random motion errors"},
    {"trajectory", "pair_error", V_PAIR, SC(traj.pair_error), R_ANY, 0, 0,
     "none, or error of ping `ping` relative to ping-1"},

    {"trajectory.pair_error", "ping", V_INT, PE(ping), R_ANY, 1, 100000, "q (>= 1)"},
    {"trajectory.pair_error", "surge", V_REAL, PE(surge), R_ANY, 0, 0, "m"},
    {"trajectory.pair_error", "sway", V_REAL, PE(sway), R_ANY, 0, 0, "m"},
    {"trajectory.pair_error", "yaw", V_REAL, PE(yaw), R_ANY, 0, 0, "rad"},

    {"scene", "kind", V_SCENE_KIND, SC(scene_kind), R_ANY, 0, 0, "ripples | points | file | survey"},
    {"scene", "file", V_STRING, SC(scene_file), R_ANY, 0,
     sizeof(((sasnav_scenario *)0)->scene_file), "HDF5 image (kind: file)"},
    {"scene", "x_min", V_REAL, SC(ripples.x_min), R_ANY, 0, 0, "m, speckle field extent"},
    {"scene", "x_max", V_REAL, SC(ripples.x_max), R_ANY, 0, 0, "m"},
    {"scene", "y_min", V_REAL, SC(ripples.y_min), R_ANY, 0, 0, "m"},
    {"scene", "y_max", V_REAL, SC(ripples.y_max), R_ANY, 0, 0, "m"},
    {"scene", "density", V_REAL, SC(ripples.density), R_POS, 0, 0, "scatterers per m^2"},
    {"scene", "ripple_period", V_REAL, SC(ripples.ripple_period), R_POS, 0, 0, "m"},
    {"scene", "ripple_angle", V_REAL, SC(ripples.ripple_angle), R_ANY, 0, 0,
     "rad, crest direction from +x"},
    {"scene", "ripple_depth", V_REAL, SC(ripples.ripple_depth), R_UNIT, 0, 0, "0..1 modulation"},
    {"scene", "background", V_REAL, SC(ripples.background), R_NONNEG, 0, 0, "rms amplitude"},
    {"scene", "disc_x", V_REAL, SC(ripples.disc_x), R_ANY, 0, 0, "m, disc centre"},
    {"scene", "disc_y", V_REAL, SC(ripples.disc_y), R_ANY, 0, 0, "m"},
    {"scene", "disc_radius", V_REAL, SC(ripples.disc_radius), R_NONNEG, 0, 0, "m (0 = no disc)"},
    {"scene", "disc_amplitude", V_REAL, SC(ripples.disc_amplitude), R_NONNEG, 0, 0,
     "rms amplitude inside the disc"},
    {"scene", "seed", V_SEED, SC(ripples.seed), R_ANY, 0, 0, "speckle draw"},
    {"scene", "targets", V_TARGETS, SC(target_x), R_ANY, 0, 0,
     "[x m, y m, amplitude] (kind: points)"},

    {"noise", "snr_db", V_SNR, SC(snr_db), R_ANY, 0, 0, "dB, or inf for noise-free data"},
    {"noise", "seed", V_SEED, SC(noise_seed), R_ANY, 0, 0, "noise draw"},

    {"aiding", "enabled", V_BOOL, SC(aiding.enabled), R_ANY, 0, 0,
     "write gyro / DVL measurements of the true trajectory"},
    {"aiding", "gyro", V_BOOL, SC(aiding.gyro), R_ANY, 0, 0, "a gyro (yaw rate) is present"},
    {"aiding", "dvl", V_BOOL, SC(aiding.dvl), R_ANY, 0, 0, "a DVL (velocity) is present"},
    {"aiding", "gyro_arw", V_REAL, SC(aiding.gyro_arw), R_NONNEG, 0, 0,
     "rad/sqrt(s), angle random walk"},
    {"aiding", "gyro_bias", V_REAL, SC(aiding.gyro_bias), R_NONNEG, 0, 0, "rad/s, rate bias (1 sigma)"},
    {"aiding", "dvl_noise", V_REAL, SC(aiding.dvl_noise), R_NONNEG, 0, 0,
     "m/s, velocity noise per ping interval"},
    {"aiding", "dvl_bias", V_REAL, SC(aiding.dvl_bias), R_NONNEG, 0, 0, "m/s, velocity bias (1 sigma)"},
    {"aiding", "dvl_scale", V_REAL, SC(aiding.dvl_scale), R_NONNEG, 0, 0,
     "scale-factor error (1 sigma, relative)"},
    {"aiding", "seed", V_SEED, SC(aiding.seed), R_ANY, 0, 0, "aiding error draws"},

    {"image", "x_min", V_REAL, IM(x_min), R_ANY, 0, 0, "m, first pixel centre"},
    {"image", "x_max", V_REAL, IM(x_max), R_ANY, 0, 0, "m, last pixel centre"},
    {"image", "nx", V_INT, IM(nx), R_ANY, 1, 1000000, "pixels along track"},
    {"image", "y_min", V_REAL, IM(y_min), R_ANY, 0, 0, "m"},
    {"image", "y_max", V_REAL, IM(y_max), R_ANY, 0, 0, "m"},
    {"image", "ny", V_INT, IM(ny), R_ANY, 1, 1000000, "pixels along range"},
};

#define N_KEYS ((int)(sizeof config_keys / sizeof config_keys[0]))

/* Sections in the order they are written. */
static const char *const sections[] = {"system", "array", "swath", "trajectory",
                                       "scene",  "noise", "aiding", "image"};
#define N_SECTIONS ((int)(sizeof sections / sizeof sections[0]))

static const char *const taper_names[] = {"none", "hann", "hamming"};
static const char *const atten_names[] = {"exploding", "spherical", "none"};
static const char *const kind_names[] = {"ripples", "points", "file", "survey"};

/* ---- C-locale scope for number formatting ---- */

typedef struct {
    locale_t c_locale, previous;
} c_numeric;

static void c_numeric_enter(c_numeric *c)
{
    c->c_locale = newlocale(LC_NUMERIC_MASK, "C", (locale_t)0);
    c->previous = c->c_locale ? uselocale(c->c_locale) : (locale_t)0;
}

static void c_numeric_leave(c_numeric *c)
{
    if (c->c_locale) {
        uselocale(c->previous);
        freelocale(c->c_locale);
    }
}

/* ---- the loader ---- */

typedef struct {
    const char *path;
    sasnav_scenario sc; /* working copy, written back only on success */
    array_stage array;
    image_stage image;
    pair_stage pair;
    int pair_seen;     /* pair_error given as a mapping */
    int pair_ping_set; /* ... with a ping */
    char key[160];     /* dotted name of the key being read */
} loader;

static int node_line(struct fy_node *node)
{
    struct fy_token *token = node ? fy_node_get_scalar_token(node) : NULL;
    const struct fy_mark *mark = token ? fy_token_start_mark(token) : NULL;
    return mark ? mark->line + 1 : 0;
}

/* Records "path:line: key: message" as a SASNAV_ERR_CONFIG error. */
static int fail(const loader *L, int line, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

static int fail(const loader *L, int line, const char *fmt, ...)
{
    char message[400];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(message, sizeof message, fmt, ap);
    va_end(ap);
    char where[32] = "";
    if (line > 0) snprintf(where, sizeof where, ":%d", line);
    if (L->key[0])
        return sasnav_set_error(SASNAV_ERR_CONFIG, "%s%s: %s: %s", L->path, where, L->key, message);
    return sasnav_set_error(SASNAV_ERR_CONFIG, "%s%s: %s", L->path, where, message);
}

/* Value text for messages: quoted, shortened. */
static const char *shown(const char *text, char *out, size_t size)
{
    size_t n = strlen(text);
    if (n + 1 <= size && n <= 40) return memcpy(out, text, n + 1);
    snprintf(out, size, "%.37s...", text);
    return out;
}

static const char *node_kind_name(struct fy_node *node)
{
    switch (fy_node_get_type(node)) {
    case FYNT_MAPPING: return "a mapping";
    case FYNT_SEQUENCE: return "a sequence";
    default: return "a scalar";
    }
}

static int is_null_scalar(const char *text, int quoted)
{
    return !quoted && (!text[0] || !strcmp(text, "~") || !strcmp(text, "null") ||
                       !strcmp(text, "Null") || !strcmp(text, "NULL"));
}

/* Copies a scalar value into buf. *quoted tells whether it was quoted
 * (then it is a string, never a number). Null values are refused unless
 * allow_null (then *is_null is set). */
static int scalar_value(const loader *L, struct fy_node *value, int line, char *buf, size_t size,
                        int *quoted, int allow_null, int *is_null)
{
    *quoted = 0;
    if (is_null) *is_null = 0;
    buf[0] = '\0';
    if (value && fy_node_get_style(value) == FYNS_ALIAS)
        return fail(L, line, "aliases (*name) are not supported");
    if (value && !fy_node_is_scalar(value))
        return fail(L, line, "expected a single value, got %s", node_kind_name(value));
    size_t len = 0;
    const char *text = value ? fy_node_get_scalar(value, &len) : "";
    if (!text) text = "";
    if (len >= size) return fail(L, line, "value too long (%zu characters)", len);
    memcpy(buf, text, len);
    buf[len] = '\0';
    if (memchr(text, '\0', len)) return fail(L, line, "value contains a NUL character");
    enum fy_node_style style = value ? fy_node_get_style(value) : FYNS_PLAIN;
    *quoted = style == FYNS_SINGLE_QUOTED || style == FYNS_DOUBLE_QUOTED || style == FYNS_LITERAL ||
              style == FYNS_FOLDED;
    if (is_null_scalar(buf, *quoted)) {
        if (allow_null) {
            *is_null = 1;
            return SASNAV_OK;
        }
        return fail(L, line, "missing value");
    }
    return SASNAV_OK;
}

static int parse_double_text(const char *text, double *out)
{
    if (!text[0] || text[0] == ' ') return 0;
    char *end;
    errno = 0;
    double v = strtod(text, &end);
    if (*end != '\0') return 0;
    *out = v;
    return 1;
}

static int read_real(const loader *L, struct fy_node *node, int line, real_rule rule, double *out)
{
    char text[VALUE_MAX], tmp[48];
    int quoted, rc = scalar_value(L, node, line, text, sizeof text, &quoted, 0, NULL);
    if (rc) return rc;
    double v;
    if (quoted)
        return fail(L, line, "expected a finite number, got the quoted string '%s'",
                    shown(text, tmp, sizeof tmp));
    if (!parse_double_text(text, &v) || !isfinite(v))
        return fail(L, line, "expected a finite number, got '%s'", shown(text, tmp, sizeof tmp));
    if (rule == R_POS && !(v > 0)) return fail(L, line, "must be > 0, got %g", v);
    if (rule == R_NONNEG && !(v >= 0)) return fail(L, line, "must be >= 0, got %g", v);
    if (rule == R_UNIT && !(v >= 0 && v <= 1)) return fail(L, line, "must be in [0, 1], got %g", v);
    *out = v;
    return SASNAV_OK;
}

static int read_int(const loader *L, struct fy_node *node, int line, long imin, long imax, int *out)
{
    char text[VALUE_MAX], tmp[48];
    int quoted, rc = scalar_value(L, node, line, text, sizeof text, &quoted, 0, NULL);
    if (rc) return rc;
    char *end = text;
    errno = 0;
    int digits =
        !quoted && ((text[0] >= '0' && text[0] <= '9') ||
                    ((text[0] == '-' || text[0] == '+') && text[1] >= '0' && text[1] <= '9'));
    long v = digits ? strtol(text, &end, 10) : 0;
    if (!digits || *end != '\0' || errno == ERANGE)
        return fail(L, line, "expected an integer, got '%s'", shown(text, tmp, sizeof tmp));
    if (v < imin) return fail(L, line, "must be >= %ld, got %ld", imin, v);
    if (v > imax) return fail(L, line, "must be <= %ld, got %ld", imax, v);
    *out = (int)v;
    return SASNAV_OK;
}

static int read_seed(const loader *L, struct fy_node *node, int line, uint64_t *out)
{
    char text[VALUE_MAX], tmp[48];
    int quoted, rc = scalar_value(L, node, line, text, sizeof text, &quoted, 0, NULL);
    if (rc) return rc;
    char *end = text;
    errno = 0;
    unsigned long long v = 0;
    int ok = !quoted && text[0] >= '0' && text[0] <= '9';
    if (ok) v = strtoull(text, &end, 10);
    if (!ok || *end != '\0' || errno == ERANGE)
        return fail(L, line, "expected a seed (an integer 0..%" PRIu64 "), got '%s'", UINT64_MAX,
                    shown(text, tmp, sizeof tmp));
    *out = (uint64_t)v;
    return SASNAV_OK;
}

static int read_bool(const loader *L, struct fy_node *node, int line, int *out)
{
    char text[VALUE_MAX], tmp[48];
    int quoted, rc = scalar_value(L, node, line, text, sizeof text, &quoted, 0, NULL);
    if (rc) return rc;
    if (!quoted && (!strcmp(text, "true") || !strcmp(text, "True") || !strcmp(text, "TRUE"))) {
        *out = 1;
        return SASNAV_OK;
    }
    if (!quoted && (!strcmp(text, "false") || !strcmp(text, "False") || !strcmp(text, "FALSE"))) {
        *out = 0;
        return SASNAV_OK;
    }
    return fail(L, line, "expected true or false, got '%s'", shown(text, tmp, sizeof tmp));
}

static int read_choice(const loader *L, struct fy_node *node, int line, const char *const *names,
                       int n_names, int *out)
{
    char text[VALUE_MAX], tmp[48];
    int quoted, rc = scalar_value(L, node, line, text, sizeof text, &quoted, 0, NULL);
    if (rc) return rc;
    for (int i = 0; i < n_names; i++)
        if (!strcmp(text, names[i])) {
            *out = i;
            return SASNAV_OK;
        }
    char list[160] = "";
    for (int i = 0; i < n_names; i++) {
        strncat(list, names[i], sizeof list - strlen(list) - 1);
        if (i + 1 < n_names) strncat(list, ", ", sizeof list - strlen(list) - 1);
    }
    return fail(L, line, "expected one of %s; got '%s'", list, shown(text, tmp, sizeof tmp));
}

static int read_string(const loader *L, struct fy_node *node, int line, char *out, size_t size)
{
    char text[VALUE_MAX];
    int quoted, is_null, rc = scalar_value(L, node, line, text, sizeof text, &quoted, 1, &is_null);
    if (rc) return rc;
    if (is_null) text[0] = '\0';
    if (strlen(text) >= size)
        return fail(L, line, "too long (%zu characters, at most %zu)", strlen(text), size - 1);
    memcpy(out, text, strlen(text) + 1);
    return SASNAV_OK;
}

static int is_inf_text(const char *t)
{
    if (*t == '+') t++;
    if (*t == '.') t++;
    return !strcasecmp(t, "inf") || !strcasecmp(t, "infinity");
}

static int read_snr(const loader *L, struct fy_node *node, int line, double *out)
{
    char text[VALUE_MAX], tmp[48];
    int quoted, rc = scalar_value(L, node, line, text, sizeof text, &quoted, 0, NULL);
    if (rc) return rc;
    double v;
    if (is_inf_text(text)) {
        *out = INFINITY;
        return SASNAV_OK;
    }
    if (quoted || !parse_double_text(text, &v) || !isfinite(v))
        return fail(L, line, "expected a finite number of dB or inf, got '%s'",
                    shown(text, tmp, sizeof tmp));
    *out = v;
    return SASNAV_OK;
}

/* Element `i` of a sequence as a real; the message names key[i]. */
static int read_real_item(loader *L, struct fy_node *item, int line, const char *suffix,
                          double *out)
{
    size_t base = strlen(L->key);
    strncat(L->key, suffix, sizeof L->key - base - 1);
    int item_line = node_line(item);
    int rc = read_real(L, item, item_line ? item_line : line, R_ANY, out);
    L->key[base] = '\0';
    return rc;
}

/* A sequence of at most SASNAV_MAX_RX reals into out[], its length into *n. */
static int read_real_list(loader *L, struct fy_node *node, int line, double *out, int *n)
{
    void *iter = NULL;
    struct fy_node *item;
    int i = 0;
    while ((item = fy_node_sequence_iterate(node, &iter))) {
        char suffix[24];
        snprintf(suffix, sizeof suffix, "[%d]", i);
        int rc = read_real_item(L, item, line, suffix, &out[i]);
        if (rc) return rc;
        i++;
    }
    *n = i;
    return SASNAV_OK;
}

static int read_positions(loader *L, struct fy_node *node, int line)
{
    if (!node || !fy_node_is_sequence(node))
        return fail(L, line, "expected a sequence of positions [u0, u1, ...] in metres");
    int n = fy_node_sequence_item_count(node);
    if (n < 1 || n > SASNAV_MAX_RX)
        return fail(L, line, "needs 1..%d positions, got %d", SASNAV_MAX_RX, n);
    int rc = read_real_list(L, node, line, L->array.positions, &L->array.n_positions);
    if (!rc) L->array.set_positions = 1;
    return rc;
}

static int read_tx_positions(loader *L, struct fy_node *node, int line)
{
    if (!node || !fy_node_is_sequence(node))
        return fail(L, line, "expected a sequence of transmitter positions [u0, u1, ...] in metres, one per channel");
    int n = fy_node_sequence_item_count(node);
    if (n > SASNAV_MAX_RX) return fail(L, line, "needs 0..%d positions, got %d", SASNAV_MAX_RX, n);
    return read_real_list(L, node, line, L->sc.channel_tx_u, &L->sc.n_channel_tx);
}

static int read_sizes(loader *L, const key_spec *k, struct fy_node *node, int line)
{
    if (!node || !fy_node_is_sequence(node))
        return fail(L, line, "expected a sequence of reals [v0, v1, ...] in metres, one per channel");
    int n = fy_node_sequence_item_count(node);
    if (n > SASNAV_MAX_RX) return fail(L, line, "needs 0..%d values, got %d", SASNAV_MAX_RX, n);
    return read_real_list(L, node, line, L->array.size_list[k->imin], &L->array.n_size[k->imin]);
}

static int read_targets(loader *L, struct fy_node *node, int line)
{
    if (!node || !fy_node_is_sequence(node))
        return fail(L, line, "expected a sequence of [x, y, amplitude] triples");
    int n = fy_node_sequence_item_count(node);
    if (n > SASNAV_MAX_TARGETS)
        return fail(L, line, "at most %d targets, got %d", SASNAV_MAX_TARGETS, n);
    void *iter = NULL;
    struct fy_node *item;
    int i = 0;
    while ((item = fy_node_sequence_iterate(node, &iter))) {
        int item_line = node_line(item) ? node_line(item) : line;
        if (!fy_node_is_sequence(item) || fy_node_sequence_item_count(item) != 3) {
            size_t base = strlen(L->key);
            snprintf(L->key + base, sizeof L->key - base, "[%d]", i);
            return fail(L, item_line, "expected [x, y, amplitude]");
        }
        double v[3];
        for (int k = 0; k < 3; k++) {
            char suffix[32];
            snprintf(suffix, sizeof suffix, "[%d][%d]", i, k);
            int rc =
                read_real_item(L, fy_node_sequence_get_by_index(item, k), item_line, suffix, &v[k]);
            if (rc) return rc;
        }
        L->sc.target_x[i] = v[0];
        L->sc.target_y[i] = v[1];
        L->sc.target_amp[i] = v[2];
        i++;
    }
    L->sc.n_targets = n;
    return SASNAV_OK;
}

static int read_section(loader *L, const char *section, struct fy_node *map, int line);

static int read_pair(loader *L, struct fy_node *node, int line)
{
    if (node && fy_node_is_mapping(node)) {
        L->pair_seen = 1;
        return read_section(L, "trajectory.pair_error", node, line);
    }
    char text[VALUE_MAX], tmp[48];
    int quoted, is_null, rc = scalar_value(L, node, line, text, sizeof text, &quoted, 1, &is_null);
    if (rc) return rc;
    if (is_null || (!quoted && (!strcmp(text, "none") || !strcmp(text, "false")))) {
        L->sc.traj.has_pair_error = 0;
        L->pair_seen = 0;
        return SASNAV_OK;
    }
    return fail(L, line, "expected none or {ping: q, surge: m, sway: m, yaw: rad}, got '%s'",
                shown(text, tmp, sizeof tmp));
}

static void *field_address(loader *L, const key_spec *k)
{
    switch (k->base) {
    case B_SC: return (char *)&L->sc + k->offset;
    case B_ARRAY: return (char *)&L->array + k->offset;
    case B_IMAGE: return (char *)&L->image + k->offset;
    case B_PAIR: return (char *)&L->pair + k->offset;
    }
    return NULL;
}

static int read_value(loader *L, const key_spec *k, struct fy_node *value, int line)
{
    void *field = field_address(L, k);
    int choice = 0, rc;
    if (value && fy_node_get_style(value) == FYNS_ALIAS)
        return fail(L, line, "aliases (*name) are not supported");
    switch (k->kind) {
    case V_REAL: return read_real(L, value, line, k->rule, field);
    case V_INT: return read_int(L, value, line, k->imin, k->imax, field);
    case V_SEED: return read_seed(L, value, line, field);
    case V_BOOL: return read_bool(L, value, line, field);
    case V_STRING: return read_string(L, value, line, field, (size_t)k->imax);
    case V_SNR: return read_snr(L, value, line, field);
    case V_TAPER:
        rc = read_choice(L, value, line, taper_names, 3, &choice);
        if (!rc) *(sasnav_taper *)field = (sasnav_taper)choice;
        return rc;
    case V_ATTEN:
        rc = read_choice(L, value, line, atten_names, 3, &choice);
        if (!rc) *(sasnav_attenuation *)field = (sasnav_attenuation)choice;
        return rc;
    case V_SCENE_KIND:
        rc = read_choice(L, value, line, kind_names, 4, &choice);
        if (!rc) *(sasnav_scene_kind *)field = (sasnav_scene_kind)choice;
        return rc;
    case V_POSITIONS: return read_positions(L, value, line);
    case V_TX_POSITIONS: return read_tx_positions(L, value, line);
    case V_SIZES: return read_sizes(L, k, value, line);
    case V_TARGETS: return read_targets(L, value, line);
    case V_PAIR: return read_pair(L, value, line);
    }
    return fail(L, line, "internal: unhandled key kind");
}

static const key_spec *find_key(const char *section, const char *name)
{
    for (int i = 0; i < N_KEYS; i++) {
        const key_spec *k = &config_keys[i];
        int same_section = section ? (k->section && !strcmp(k->section, section)) : !k->section;
        if (same_section && !strcmp(k->name, name)) return k;
    }
    return NULL;
}

static void known_keys(const char *section, char *out, size_t size)
{
    out[0] = '\0';
    for (int i = 0; i < N_KEYS; i++) {
        const key_spec *k = &config_keys[i];
        if (!k->section || strcmp(k->section, section)) continue;
        if (out[0]) strncat(out, ", ", size - strlen(out) - 1);
        strncat(out, k->name, size - strlen(out) - 1);
    }
}

/* Reads the key of a pair into buf (plain text only). */
static int pair_key(loader *L, struct fy_node_pair *pair, char *buf, size_t size, int *line)
{
    struct fy_node *key = fy_node_pair_key(pair);
    *line = node_line(key);
    if (!key || !fy_node_is_scalar(key) || fy_node_get_style(key) == FYNS_ALIAS)
        return fail(L, *line, "keys must be plain names");
    size_t len = 0;
    const char *text = fy_node_get_scalar(key, &len);
    if (!text || len == 0 || len >= size || memchr(text, '\0', len))
        return fail(L, *line, "invalid key");
    memcpy(buf, text, len);
    buf[len] = '\0';
    return SASNAV_OK;
}

static void mark_touched(loader *L, const key_spec *k)
{
    if (k->base == B_ARRAY) {
        L->array.touched = 1;
        if (!strcmp(k->name, "n_rx")) L->array.set_n_rx = 1;
        if (!strcmp(k->name, "rx_spacing")) L->array.set_spacing = 1;
    } else if (k->base == B_IMAGE) {
        L->image.touched = 1;
    } else if (k->base == B_PAIR && !strcmp(k->name, "ping")) {
        L->pair_ping_set = 1;
    }
}

static int read_section(loader *L, const char *section, struct fy_node *map, int line)
{
    size_t base = strlen(L->key);
    if (!map || !fy_node_is_mapping(map)) {
        if (map && fy_node_get_style(map) == FYNS_ALIAS)
            return fail(L, line, "aliases (*name) are not supported");
        return fail(L, line, "expected a mapping of keys (section '%s')", section);
    }
    void *iter = NULL;
    struct fy_node_pair *pair;
    while ((pair = fy_node_mapping_iterate(map, &iter))) {
        char name[96], known[600];
        int key_line, rc = pair_key(L, pair, name, sizeof name, &key_line);
        if (rc) return rc;
        snprintf(L->key + base, sizeof L->key - base, "%s%s", base ? "." : "", name);
        const key_spec *k = find_key(section, name);
        if (!k) {
            known_keys(section, known, sizeof known);
            return fail(L, key_line, "unknown key (known in %s: %s)", section, known);
        }
        rc = read_value(L, k, fy_node_pair_value(pair), key_line);
        if (rc) return rc;
        mark_touched(L, k);
        L->key[base] = '\0';
    }
    return SASNAV_OK;
}

/* ---- staging: array, image grid, pair error ---- */

static int array_is_uniform(const sasnav_array *a, double *spacing)
{
    int n = a->n_rx;
    double s = n > 1 ? (a->rx_u[n - 1] - a->rx_u[0]) / (n - 1) : 0.0;
    *spacing = s;
    double tol = 1e-12 * fmax(1.0, fabs(s) * n);
    for (int l = 0; l < n; l++)
        if (fabs(a->rx_u[l] - (l - 0.5 * (n - 1)) * s) > tol) return 0;
    return 1;
}

static void stage_from_scenario(loader *L)
{
    const sasnav_array *a = &L->sc.array;
    memset(&L->array, 0, sizeof L->array);
    L->array.n_rx = a->n_rx;
    array_is_uniform(a, &L->array.rx_spacing);
    L->array.rx_length = a->rx_length;
    L->array.tx_length = a->tx_length;
    L->array.rx_height = a->rx_height;
    L->array.tx_height = a->tx_height;
    for (int l = 0; a->per_channel && l < a->n_rx; l++) {
        L->array.size_list[0][l] = a->size[l].rx_length;
        L->array.size_list[1][l] = a->size[l].tx_length;
        L->array.size_list[2][l] = a->size[l].rx_height;
        L->array.size_list[3][l] = a->size[l].tx_height;
    }
    for (int i = 0; i < 4; i++) L->array.n_size[i] = a->per_channel ? a->n_rx : 0;

    const sasnav_grid *g = &L->sc.image_grid;
    memset(&L->image, 0, sizeof L->image);
    L->image.x_min = g->x0;
    L->image.x_max = g->x0 + (g->nx - 1) * g->dx;
    L->image.nx = g->nx;
    L->image.y_min = g->y0;
    L->image.y_max = g->y0 + (g->ny - 1) * g->dy;
    L->image.ny = g->ny;

    const sasnav_trajectory_params *t = &L->sc.traj;
    L->pair.ping = t->pair_q;
    L->pair.surge = t->has_pair_error ? t->pair_error.x : 0.0;
    L->pair.sway = t->has_pair_error ? t->pair_error.y : 0.0;
    L->pair.yaw = t->has_pair_error ? t->pair_error.theta : 0.0;
    L->pair_seen = 0;
    L->pair_ping_set = 0;
}

static int apply_array(loader *L)
{
    array_stage *s = &L->array;
    sasnav_array a = L->sc.array;
    int rc = SASNAV_OK;
    L->key[0] = '\0';
    if (!s->touched) return SASNAV_OK;
    if (s->set_positions) {
        if (s->set_spacing)
            return fail(L, 0, "array.rx_spacing and array.rx_positions cannot both be given");
        if (s->set_n_rx && s->n_rx != s->n_positions)
            return fail(L, 0, "array.n_rx (%d) differs from the number of array.rx_positions (%d)",
                        s->n_rx, s->n_positions);
        a.n_rx = s->n_positions;
        memset(a.rx_u, 0, sizeof a.rx_u);
        memcpy(a.rx_u, s->positions, sizeof(double) * (size_t)s->n_positions);
    } else if (s->set_n_rx || s->set_spacing) {
        if (s->n_rx > 1 && !(s->rx_spacing > 0))
            return fail(L, 0, "array.rx_spacing must be > 0 with %d receivers", s->n_rx);
        rc = sasnav_array_uniform(&a, s->n_rx, s->n_rx > 1 ? s->rx_spacing : 1.0, s->rx_length,
                                  s->tx_length);
        if (rc) return fail(L, 0, "array: %s", sasnav_last_error());
    }
    a.rx_length = s->rx_length;
    a.tx_length = s->tx_length;
    a.rx_height = s->rx_height;
    a.tx_height = s->tx_height;
    sasnav_array_set_sizes(&a, NULL);
    if (s->n_size[0] || s->n_size[1] || s->n_size[2] || s->n_size[3]) {
        static const char *names[4] = {"rx_lengths", "tx_lengths", "rx_heights", "tx_heights"};
        const double scalar[4] = {s->rx_length, s->tx_length, s->rx_height, s->tx_height};
        sasnav_channel_size z[SASNAV_MAX_RX];
        double v[4][SASNAV_MAX_RX];
        for (int i = 0; i < 4; i++) {
            if (s->n_size[i] && s->n_size[i] != a.n_rx)
                return fail(L, 0, "array.%s has %d values for %d channels", names[i], s->n_size[i],
                            a.n_rx);
            for (int l = 0; l < a.n_rx; l++) v[i][l] = s->n_size[i] ? s->size_list[i][l] : scalar[i];
        }
        for (int l = 0; l < a.n_rx; l++) {
            sasnav_channel_size zl = {v[0][l], v[1][l], v[2][l], v[3][l]};
            z[l] = zl;
        }
        rc = sasnav_array_set_sizes(&a, z);
        if (rc) return fail(L, 0, "%s", sasnav_last_error());
    }
    rc = sasnav_array_check(&a);
    if (rc) return fail(L, 0, "array: %s", sasnav_last_error());
    L->sc.array = a;
    return SASNAV_OK;
}

static int apply_image(loader *L)
{
    image_stage *s = &L->image;
    L->key[0] = '\0';
    if (!s->touched) return SASNAV_OK;
    sasnav_grid grid;
    int rc = sasnav_grid_make(s->x_min, s->x_max, s->nx, s->y_min, s->y_max, s->ny, &grid);
    if (rc) return fail(L, 0, "image: %s", sasnav_last_error());
    L->sc.image_grid = grid;
    return SASNAV_OK;
}

static int apply_pair(loader *L)
{
    L->key[0] = '\0';
    if (!L->pair_seen) return SASNAV_OK;
    sasnav_trajectory_params *t = &L->sc.traj;
    if (!L->pair_ping_set && !t->has_pair_error)
        return fail(L, 0, "trajectory.pair_error needs a ping (q >= 1)");
    t->has_pair_error = 1;
    t->pair_q = L->pair.ping;
    t->pair_error.x = L->pair.surge;
    t->pair_error.y = L->pair.sway;
    t->pair_error.theta = L->pair.yaw;
    return SASNAV_OK;
}

/* Checks between keys, with the keys named, before the library's own
 * scenario check. */
static int cross_check(loader *L)
{
    const sasnav_scenario *sc = &L->sc;
    L->key[0] = '\0';
    if (!(sc->range_min < sc->range_max))
        return fail(L, 0, "swath.range_min (%g) must be < swath.range_max (%g)", sc->range_min,
                    sc->range_max);
    if (!(sc->sys.sample_rate >= sc->sys.bandwidth))
        return fail(L, 0, "system.sample_rate (%g) must be >= system.bandwidth (%g)",
                    sc->sys.sample_rate, sc->sys.bandwidth);
    if (sc->traj.has_pair_error && sc->traj.pair_q >= sc->traj.n_pings)
        return fail(L, 0, "trajectory.pair_error.ping (%d) must be < trajectory.n_pings (%d)",
                    sc->traj.pair_q, sc->traj.n_pings);
    if (sc->scene_kind == SASNAV_SCENE_POINTS && sc->n_targets < 1)
        return fail(L, 0, "scene.kind is points but scene.targets is empty");
    if (sc->scene_kind == SASNAV_SCENE_FILE && !sc->scene_file[0])
        return fail(L, 0, "scene.kind is file but scene.file is not given");
    if ((sc->scene_kind == SASNAV_SCENE_RIPPLES || sc->scene_kind == SASNAV_SCENE_SURVEY) &&
        !(sc->ripples.x_min < sc->ripples.x_max && sc->ripples.y_min < sc->ripples.y_max))
        return fail(L, 0, "scene.x_min < scene.x_max and scene.y_min < scene.y_max are required");
    return SASNAV_OK;
}

/* ---- reading the file ---- */

static void diag_discard(struct fy_diag *diag, void *user, const char *buf, size_t len)
{
    (void)diag, (void)user, (void)buf, (void)len;
}

/* Offset of the first byte that is not valid UTF-8 (overlong forms,
 * surrogates and code points past U+10FFFF included), or len when all is.
 * Checked before libfyaml sees the text: libfyaml 0.8 loops forever on some
 * invalid UTF-8 (e.g. the two bytes "%\xf3": fuzz_config, docs/fuzzing.md). */
static size_t utf8_invalid_at(const unsigned char *s, size_t len)
{
    size_t i = 0;
    while (i < len) {
        unsigned c = s[i];
        size_t n = c < 0x80 ? 0 : (c & 0xE0) == 0xC0 ? 1 : (c & 0xF0) == 0xE0 ? 2 : (c & 0xF8) == 0xF0 ? 3 : 9;
        if (n == 9 || c == 0xC0 || c == 0xC1 || c > 0xF4 || n >= len - i) return i;
        unsigned long cp = n == 0 ? c : n == 1 ? (c & 0x1F) : n == 2 ? (c & 0x0F) : (c & 0x07);
        for (size_t k = 1; k <= n; k++) {
            if ((s[i + k] & 0xC0) != 0x80) return i;
            cp = cp << 6 | (s[i + k] & 0x3F);
        }
        if ((n == 2 && cp < 0x800) || (n == 3 && (cp < 0x10000 || cp > 0x10FFFF)) ||
            (cp >= 0xD800 && cp <= 0xDFFF))
            return i;
        i += n + 1;
    }
    return len;
}

/* Parses text into a document; NULL document with SASNAV_OK means an empty
 * stream (no keys). */
static int parse_yaml(const char *path, const char *text, size_t len, struct fy_document **doc)
{
    struct fy_diag_cfg dcfg;
    fy_diag_cfg_default(&dcfg);
    dcfg.fp = NULL;
    dcfg.output_fn = diag_discard;
    dcfg.colorize = false;
    struct fy_diag *diag = fy_diag_create(&dcfg);
    if (!diag)
        return sasnav_set_error(SASNAV_ERR_NOMEM, "%s: cannot create YAML diagnostics", path);
    fy_diag_set_collect_errors(diag, true);
    struct fy_parse_cfg pcfg;
    memset(&pcfg, 0, sizeof pcfg);
    pcfg.flags = FYPCF_QUIET | FYPCF_JSON_NONE;
    pcfg.diag = diag;
    *doc = fy_document_build_from_string(&pcfg, text, len);
    int rc = SASNAV_OK;
    void *iter = NULL;
    struct fy_diag_error *err = fy_diag_errors_iterate(diag, &iter);
    if (err) {
        rc = sasnav_set_error(SASNAV_ERR_CONFIG, "%s:%d:%d: YAML syntax error: %s", path, err->line,
                              err->column, err->msg ? err->msg : "unknown");
    } else if (*doc && fy_diag_got_error(diag)) {
        rc = sasnav_set_error(SASNAV_ERR_CONFIG, "%s: YAML syntax error", path);
    }
    if (rc && *doc) {
        fy_document_destroy(*doc);
        *doc = NULL;
    }
    fy_diag_destroy(diag);
    return rc;
}

/* Finds top-level `preset` and applies it to the working copy. */
static int apply_preset(loader *L, struct fy_node *root)
{
    void *iter = NULL;
    struct fy_node_pair *pair;
    while ((pair = fy_node_mapping_iterate(root, &iter))) {
        char name[96];
        int line, rc = pair_key(L, pair, name, sizeof name, &line);
        if (rc) return rc;
        if (strcmp(name, "preset")) continue;
        char preset[64];
        snprintf(L->key, sizeof L->key, "preset");
        rc = read_string(L, fy_node_pair_value(pair), line, preset, sizeof preset);
        if (rc) return rc;
        if (sasnav_scenario_preset(preset, &L->sc) != SASNAV_OK)
            return fail(L, line, "%s", sasnav_last_error());
        L->key[0] = '\0';
    }
    return SASNAV_OK;
}

static int read_top(loader *L, struct fy_node *root)
{
    if (!fy_node_is_mapping(root))
        return fail(L, node_line(root),
                    "the file must be a mapping of sections (system:, array:, ...)");
    int rc = apply_preset(L, root);
    if (rc) return rc;
    stage_from_scenario(L);
    void *iter = NULL;
    struct fy_node_pair *pair;
    while ((pair = fy_node_mapping_iterate(root, &iter))) {
        char name[96];
        int line;
        rc = pair_key(L, pair, name, sizeof name, &line);
        if (rc) return rc;
        snprintf(L->key, sizeof L->key, "%s", name);
        struct fy_node *value = fy_node_pair_value(pair);
        if (!strcmp(name, "preset")) {
            rc = SASNAV_OK;
        } else if (find_key(NULL, name)) {
            rc = read_value(L, find_key(NULL, name), value, line);
        } else {
            int known = 0;
            for (int s = 0; s < N_SECTIONS; s++)
                if (!strcmp(name, sections[s])) known = 1;
            if (!known)
                return fail(L, line,
                            "unknown key (known: preset, name, system, array, swath, "
                            "trajectory, scene, noise, aiding, image)");
            rc = read_section(L, name, value, line);
        }
        if (rc) return rc;
        L->key[0] = '\0';
    }
    return SASNAV_OK;
}

int sasnav_config_load(const char *path, sasnav_scenario *sc)
{
    if (!path || !sc) return sasnav_set_error(SASNAV_ERR_ARG, "config_load: NULL argument");
    char *text = NULL;
    size_t len = 0;
    int rc = sasnav_text_read(path, CONFIG_MAX_BYTES, SASNAV_ERR_CONFIG, &text, &len);
    if (rc) return rc;
    size_t bad = utf8_invalid_at((const unsigned char *)text, len);
    if (bad < len) {
        free(text);
        return sasnav_set_error(SASNAV_ERR_CONFIG, "%s: not UTF-8 text (byte %zu)", path, bad);
    }

    loader *L = calloc(1, sizeof *L);
    if (!L) {
        free(text);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "config_load: out of memory");
    }
    L->path = path;
    L->sc = *sc;
    c_numeric locale;
    c_numeric_enter(&locale);
    struct fy_document *doc = NULL;
    rc = parse_yaml(path, text, len, &doc);
    struct fy_node *root = doc ? fy_document_root(doc) : NULL;
    if (!rc && root) rc = read_top(L, root);
    if (!rc && root) rc = apply_array(L);
    if (!rc && root) rc = apply_image(L);
    if (!rc && root) rc = apply_pair(L);
    if (!rc) rc = cross_check(L);
    if (!rc && sasnav_scenario_check(&L->sc) != SASNAV_OK)
        rc = sasnav_prefix_error(SASNAV_ERR_CONFIG, "%s: invalid scenario", path);
    if (!rc) *sc = L->sc;
    c_numeric_leave(&locale);
    if (doc) fy_document_destroy(doc);
    free(text);
    free(L);
    return rc;
}

/* ---- the writer ---- */

/* Shortest decimal that reads back to exactly the same double. */
static void format_real(double v, char *out, size_t size)
{
    if (isinf(v)) {
        snprintf(out, size, v > 0 ? "inf" : "-inf");
        return;
    }
    for (int digits = 6; digits <= 17; digits++) {
        snprintf(out, size, "%.*g", digits, v);
        if (strtod(out, NULL) == v) return;
    }
}

/* YAML double-quoted string (escapes for quote, backslash and control
 * characters; UTF-8 passes through). */
static void quote_string(const char *s, char *out, size_t size)
{
    size_t j = 0;
    out[j++] = '"';
    for (const unsigned char *p = (const unsigned char *)s; *p && j + 6 < size; p++) {
        if (*p == '"' || *p == '\\') {
            out[j++] = '\\';
            out[j++] = (char)*p;
        } else if (*p < 0x20 || *p == 0x7f) {
            j += (size_t)snprintf(out + j, size - j, "\\x%02x", *p);
        } else {
            out[j++] = (char)*p;
        }
    }
    out[j++] = '"';
    out[j] = '\0';
}

typedef struct {
    const sasnav_scenario *sc;
    array_stage array;
    image_stage image;
    pair_stage pair;
    int uniform;
} writer;

static const void *writer_field(const writer *w, const key_spec *k)
{
    switch (k->base) {
    case B_SC: return (const char *)w->sc + k->offset;
    case B_ARRAY: return (const char *)&w->array + k->offset;
    case B_IMAGE: return (const char *)&w->image + k->offset;
    case B_PAIR: return (const char *)&w->pair + k->offset;
    }
    return NULL;
}

/* Writes "indent key: value" and the comment aligned at column 44. */
static void write_line(FILE *f, int indent, const char *name, const char *value,
                       const char *comment)
{
    int n = fprintf(f, "%*s%s: %s", indent, "", name, value);
    if (comment) fprintf(f, "%*s# %s", n < 44 ? 44 - n : 1, "", comment);
    fputc('\n', f);
}

static void write_key(FILE *f, const writer *w, const key_spec *k, int indent)
{
    const void *field = writer_field(w, k);
    const sasnav_scenario *sc = w->sc;
    char value[4 * VALUE_MAX + 8];
    switch (k->kind) {
    case V_REAL:
    case V_SNR: format_real(*(const double *)field, value, sizeof value); break;
    case V_INT: snprintf(value, sizeof value, "%d", *(const int *)field); break;
    case V_SEED: snprintf(value, sizeof value, "%" PRIu64, *(const uint64_t *)field); break;
    case V_BOOL: snprintf(value, sizeof value, "%s", *(const int *)field ? "true" : "false"); break;
    case V_TAPER: snprintf(value, sizeof value, "%s", taper_names[sc->sys.taper]); break;
    case V_ATTEN: snprintf(value, sizeof value, "%s", atten_names[sc->sys.attenuation]); break;
    case V_SCENE_KIND: snprintf(value, sizeof value, "%s", kind_names[sc->scene_kind]); break;
    case V_STRING: quote_string((const char *)field, value, sizeof value); break;
    case V_POSITIONS:
        if (w->uniform) return;
        fprintf(f, "%*s%s: [", indent, "", k->name);
        for (int l = 0; l < sc->array.n_rx; l++) {
            format_real(sc->array.rx_u[l], value, sizeof value);
            fprintf(f, "%s%s", l ? ", " : "", value);
        }
        fprintf(f, "]  # %s\n", k->comment);
        return;
    case V_SIZES:
        fprintf(f, "%*s%s: [", indent, "", k->name);
        for (int l = 0; sc->array.per_channel && l < sc->array.n_rx; l++) {
            const sasnav_channel_size *z = &sc->array.size[l];
            const double m[4] = {z->rx_length, z->tx_length, z->rx_height, z->tx_height};
            format_real(m[k->imin], value, sizeof value);
            fprintf(f, "%s%s", l ? ", " : "", value);
        }
        fprintf(f, "]  # %s\n", k->comment);
        return;
    case V_TX_POSITIONS:
        fprintf(f, "%*s%s: [", indent, "", k->name);
        for (int l = 0; l < sc->n_channel_tx; l++) {
            format_real(sc->channel_tx_u[l], value, sizeof value);
            fprintf(f, "%s%s", l ? ", " : "", value);
        }
        fprintf(f, "]  # %s\n", k->comment);
        return;
    case V_TARGETS:
        if (sc->n_targets == 0) {
            write_line(f, indent, k->name, "[]", k->comment);
            return;
        }
        write_line(f, indent, k->name, "", k->comment);
        for (int i = 0; i < sc->n_targets && i < SASNAV_MAX_TARGETS; i++) {
            char x[40], y[40], a[40];
            format_real(sc->target_x[i], x, sizeof x);
            format_real(sc->target_y[i], y, sizeof y);
            format_real(sc->target_amp[i], a, sizeof a);
            fprintf(f, "%*s  - [%s, %s, %s]\n", indent, "", x, y, a);
        }
        return;
    case V_PAIR:
        if (!sc->traj.has_pair_error) {
            write_line(f, indent, k->name, "none", k->comment);
            return;
        }
        write_line(f, indent, k->name, "", k->comment);
        for (int i = 0; i < N_KEYS; i++)
            if (config_keys[i].section && !strcmp(config_keys[i].section, "trajectory.pair_error"))
                write_key(f, w, &config_keys[i], indent + 2);
        return;
    }
    if (k->base == B_ARRAY && !strcmp(k->name, "rx_spacing") && !w->uniform) return;
    write_line(f, indent, k->name, value, k->comment);
}

static void write_config(FILE *f, const writer *w)
{
    fputs("# sasnav scenario configuration (written by sasnav_config_write).\n"
          "# SI units: m, s, Hz, rad. Every key is optional when the file is loaded:\n"
          "# missing keys keep the values of the preset (top-level `preset:`) or of\n"
          "# the caller's default. Keys are documented in docs/config.md.\n",
          f);
    for (int i = 0; i < N_KEYS; i++)
        if (!config_keys[i].section) write_key(f, w, &config_keys[i], 0);
    for (int s = 0; s < N_SECTIONS; s++) {
        fprintf(f, "\n%s:\n", sections[s]);
        for (int i = 0; i < N_KEYS; i++)
            if (config_keys[i].section && !strcmp(config_keys[i].section, sections[s]))
                write_key(f, w, &config_keys[i], 2);
    }
}

int sasnav_config_write(const char *path, const sasnav_scenario *sc)
{
    if (!path || !sc) return sasnav_set_error(SASNAV_ERR_ARG, "config_write: NULL argument");
    if (!path[0]) return sasnav_set_error(SASNAV_ERR_ARG, "config_write: empty path");
    if (sc->array.n_rx < 1 || sc->array.n_rx > SASNAV_MAX_RX || sc->n_targets < 0 ||
        sc->n_targets > SASNAV_MAX_TARGETS)
        return sasnav_set_error(SASNAV_ERR_ARG, "config_write: scenario sizes out of range");
    if ((int)sc->sys.taper < 0 || (int)sc->sys.taper > 2 || (int)sc->sys.attenuation < 0 ||
        (int)sc->sys.attenuation > 2 || (int)sc->scene_kind < 0 || (int)sc->scene_kind > 2)
        return sasnav_set_error(SASNAV_ERR_ARG,
                                "config_write: unknown taper, attenuation or scene kind");

    writer w;
    memset(&w, 0, sizeof w);
    w.sc = sc;
    loader *tmp_loader = calloc(1, sizeof *tmp_loader);
    if (!tmp_loader) return sasnav_set_error(SASNAV_ERR_NOMEM, "config_write: out of memory");
    tmp_loader->sc = *sc;
    stage_from_scenario(tmp_loader);
    w.array = tmp_loader->array;
    w.image = tmp_loader->image;
    w.pair = tmp_loader->pair;
    free(tmp_loader);
    double spacing;
    w.uniform = array_is_uniform(&sc->array, &spacing);

    sasnav_text_out out;
    int rc = sasnav_text_open(&out, path);
    if (rc) return rc;
    c_numeric locale;
    c_numeric_enter(&locale);
    write_config(out.f, &w);
    c_numeric_leave(&locale);
    return sasnav_text_commit(&out);
}
