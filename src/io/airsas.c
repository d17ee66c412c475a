/* AirSAS recordings: reading a directory of CSV files, and turning a
 * recording into a sasnav run (airsas.h). The CSV files are simple numeric
 * tables (no quoting); each is read whole and parsed with strtod, every field
 * checked to be a complete, finite number. */
#include "sasnav/airsas.h"
#include "sasnav/error.h"
#include "sasnav/geometry.h"
#include "io/textfile.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define MAX_FILE_BYTES (64L << 20)
#define MAX_PINGS 100000
#define MAX_SAMPLES (1 << 22)
#define MAX_CHANNELS 64

/* ------------------------------------------------------------ text files */

/* Next line of *cursor (NUL-terminated in place, "\r\n" or "\n"); NULL at the
 * end. */
static char *next_line(char **cursor)
{
    char *s = *cursor;
    if (!s || !*s) return NULL;
    char *nl = strchr(s, '\n');
    if (nl) {
        *nl = '\0';
        *cursor = nl + 1;
    } else {
        *cursor = s + strlen(s);
    }
    size_t len = strlen(s);
    if (len && s[len - 1] == '\r') s[len - 1] = '\0';
    return s;
}

static int blank(const char *s)
{
    for (; *s; s++)
        if (*s != ' ' && *s != '\t') return 0;
    return 1;
}

/* One complete finite number from s (surrounding blanks allowed) up to `end`
 * (exclusive, or the NUL). Returns 0 on success. */
static int parse_number(const char *s, const char *end, double *v)
{
    while (s < end && (*s == ' ' || *s == '\t')) s++;
    if (s == end) return -1;
    char *stop = NULL;
    errno = 0;
    double x = strtod(s, &stop);
    if (stop == s || errno == ERANGE || !isfinite(x) || stop > end) return -1;
    while (stop < end && (*stop == ' ' || *stop == '\t')) stop++;
    if (stop != end) return -1;
    *v = x;
    return 0;
}

/* Splits a line at commas and parses up to `max` numbers; returns the number
 * of fields, or -(field index + 1) when a field is not a number. */
static int parse_row(const char *line, double *vals, int max)
{
    int n = 0;
    const char *s = line;
    for (;;) {
        const char *comma = strchr(s, ',');
        const char *end = comma ? comma : s + strlen(s);
        double v;
        if (parse_number(s, end, &v)) return -(n + 1);
        if (n < max) vals[n] = v;
        n++;
        if (!comma) return n;
        s = comma + 1;
    }
}

/* ------------------------------------------------------ metadata files */

static int read_coordinates(const char *dir, sasnav_airsas *r)
{
    char path[4096];
    int rc = sasnav_path_join(path, sizeof path, dir, "Coordinates.csv");
    char *text = NULL;
    if (!rc) rc = sasnav_text_read(path, MAX_FILE_BYTES, SASNAV_ERR_FORMAT, &text, NULL);
    if (rc) return rc;
    int cap = 512, n = 0, line_no = 0;
    r->angle_deg = malloc(sizeof(double) * cap);
    r->height_mm = malloc(sizeof(double) * cap);
    r->temperature = malloc(sizeof(double) * cap);
    char *cursor = text, *line;
    while (!rc && (line = next_line(&cursor))) {
        line_no++;
        if (blank(line)) continue;
        double v[5];
        int k = parse_row(line, v, 5);
        if (k < 0 && line_no == 1) continue; /* the header */
        if (k < 0) {
            rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s line %d: field %d is not a number", path,
                                  line_no, -k);
        } else if (k < 4 || k > 5) {
            rc = sasnav_set_error(SASNAV_ERR_FORMAT,
                                  "%s line %d: %d columns, expected 5 (flight, angle, height, "
                                  "temperature, waveform)",
                                  path, line_no, k);
        } else if (v[0] != n + 1) {
            rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s line %d: flight %g, expected %d", path,
                                  line_no, v[0], n + 1);
        } else if (n >= MAX_PINGS) {
            rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s: more than %d flights", path, MAX_PINGS);
        } else {
            if (n == cap) {
                cap *= 2;
                double *a = realloc(r->angle_deg, sizeof(double) * cap);
                if (a) r->angle_deg = a;
                double *h = realloc(r->height_mm, sizeof(double) * cap);
                if (h) r->height_mm = h;
                double *t = realloc(r->temperature, sizeof(double) * cap);
                if (t) r->temperature = t;
                if (!a || !h || !t) rc = sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
            }
            if (!rc && (!r->angle_deg || !r->height_mm || !r->temperature))
                rc = sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
            if (!rc) {
                r->angle_deg[n] = v[1];
                r->height_mm[n] = v[2];
                r->temperature[n] = v[3];
                n++;
            }
        }
    }
    free(text);
    if (!rc && n == 0) rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s lists no flight", path);
    for (int p = 0; !rc && p < n; p++)
        if (r->temperature[p] < -100 || r->temperature[p] > 100)
            rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s: flight %d has temperature %g deg C", path,
                                  p + 1, r->temperature[p]);
    r->n_pings = n;
    return rc;
}

typedef struct {
    const char *key;
    double *dst;
    int required;
} sys_key;

static int read_sysparams(const char *dir, sasnav_airsas *r)
{
    char path[4096];
    int rc = sasnav_path_join(path, sizeof path, dir, "SysParams.csv");
    char *text = NULL;
    if (!rc) rc = sasnav_text_read(path, MAX_FILE_BYTES, SASNAV_ERR_FORMAT, &text, NULL);
    if (rc) return rc;
    const sys_key keys[] = {
        {"Speaker x", &r->speaker[0], 1}, {"Speaker y", &r->speaker[1], 1},
        {"Speaker z", &r->speaker[2], 1}, {"Mic1 x", &r->mic[0][0], 1},
        {"Mic1 y", &r->mic[0][1], 1},     {"Mic1 z", &r->mic[0][2], 1},
        {"Mic2 x", &r->mic[1][0], 0},     {"Mic2 y", &r->mic[1][1], 0},
        {"Mic2 z", &r->mic[1][2], 0},     {"Center x", &r->center[0], 1},
        {"Center y", &r->center[1], 1},   {"Center z", &r->center[2], 1},
        {"Fs", &r->sample_rate, 1},       {"Group Delay", &r->group_delay, 1},
    };
    enum { NKEYS = sizeof keys / sizeof keys[0] };
    int found[NKEYS] = {0}, line_no = 0;
    char *cursor = text, *line;
    while (!rc && (line = next_line(&cursor))) {
        line_no++;
        char *comma = strchr(line, ',');
        if (!comma) continue;
        *comma = '\0';
        char *key = line;
        while (*key == ' ') key++;
        size_t kl = strlen(key);
        while (kl && key[kl - 1] == ' ') key[--kl] = '\0';
        for (int k = 0; k < NKEYS; k++) {
            if (strcmp(key, keys[k].key)) continue;
            double v;
            if (found[k])
                rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s line %d: '%s' given twice", path,
                                      line_no, key);
            else if (parse_number(comma + 1, comma + 1 + strlen(comma + 1), &v))
                rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s line %d: '%s' is not a number", path,
                                      line_no, key);
            else {
                *keys[k].dst = v;
                found[k] = 1;
            }
        }
    }
    free(text);
    for (int k = 0; !rc && k < NKEYS; k++)
        if (keys[k].required && !found[k])
            rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s: missing '%s'", path, keys[k].key);
    if (rc) return rc;
    r->has_mic2 = found[6] && found[7] && found[8];
    if (!(r->sample_rate > 0) || r->sample_rate > 1e9)
        return sasnav_set_error(SASNAV_ERR_FORMAT, "%s: Fs %g Hz is not a sampling rate", path,
                                r->sample_rate);
    if (r->group_delay < -1e6 || r->group_delay > 1e6)
        return sasnav_set_error(SASNAV_ERR_FORMAT, "%s: Group Delay %g samples is out of range",
                                path, r->group_delay);
    return SASNAV_OK;
}

/* A token "<number><unit>", e.g. "3.00E+4Hz". */
static int parse_with_unit(const char *token, const char *unit, double *v)
{
    size_t n = strlen(token), u = strlen(unit);
    if (n <= u || strcmp(token + n - u, unit)) return -1;
    return parse_number(token, token + n - u, v);
}

static int read_waveform(const char *dir, sasnav_airsas *r)
{
    char path[4096];
    int rc = sasnav_path_join(path, sizeof path, dir, "WaveformParams.csv");
    char *text = NULL;
    if (!rc) rc = sasnav_text_read(path, MAX_FILE_BYTES, SASNAV_ERR_FORMAT, &text, NULL);
    if (rc) return rc;
    char *cursor = text, *line = next_line(&cursor);
    while (line && blank(line)) line = next_line(&cursor);
    char *tok[8] = {0};
    int nt = 0;
    if (line) {
        char *comma = strchr(line, ',');
        if (comma) *comma = '\0'; /* only the first field holds the description */
        char *save = NULL;
        for (char *t = strtok_r(line, "_", &save); t && nt < 8; t = strtok_r(NULL, "_", &save))
            tok[nt++] = t;
    }
    /* LFM_<f start>Hz_<f end>Hz_<duration>s_<amplitude>V[_tukeywin_<ratio>] */
    double f1, f2, dur, volts = 0, ratio = 0;
    if (nt < 4 || strcmp(tok[0], "LFM") || parse_with_unit(tok[1], "Hz", &f1) ||
        parse_with_unit(tok[2], "Hz", &f2) || parse_with_unit(tok[3], "s", &dur) ||
        (nt >= 5 && parse_with_unit(tok[4], "V", &volts)))
        rc = sasnav_set_error(SASNAV_ERR_FORMAT,
                              "%s: expected LFM_<f>Hz_<f>Hz_<T>s_<A>V[_tukeywin_<r>], got '%s'",
                              path, line ? line : "");
    else if (nt == 6 || nt > 7 || (nt == 7 && strcmp(tok[5], "tukeywin")))
        rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s: unknown window '%s' (only tukeywin)", path,
                              nt >= 6 ? tok[5] : "");
    else if (nt == 7 && parse_number(tok[6], tok[6] + strlen(tok[6]), &ratio))
        rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s: Tukey ratio '%s' is not a number", path, tok[6]);
    free(text);
    if (rc) return rc;
    r->lfm.f_start = f1;
    r->lfm.f_end = f2;
    r->lfm.duration = dur;
    r->lfm.tukey = ratio;
    r->drive_volts = volts;
    if (!sasnav_lfm_length(&r->lfm, r->sample_rate))
        return sasnav_prefix_error(SASNAV_ERR_FORMAT, "%s", path);
    return SASNAV_OK;
}

/* -------------------------------------------------------------- flights */

/* Flight p of `dir` into dst[channel][sample] (NULL: allocate r->samples
 * for every ping on the first flight and write there). The first flight
 * read fixes r->n_channels and r->n_samples; the others must match. */
static int read_flight(const char *dir, int p, sasnav_airsas *r, double **rows, int *cap, float *dst)
{
    char name[64], path[4096];
    snprintf(name, sizeof name, "Flight-%06d.csv", p + 1);
    int rc = sasnav_path_join(path, sizeof path, dir, name);
    char *text = NULL;
    if (!rc) rc = sasnav_text_read(path, MAX_FILE_BYTES, SASNAV_ERR_FORMAT, &text, NULL);
    if (rc) return rc;
    int n = 0, line_no = 0;
    char *cursor = text, *line;
    while (!rc && (line = next_line(&cursor))) {
        line_no++;
        if (blank(line)) continue;
        double v[MAX_CHANNELS];
        int k = parse_row(line, v, MAX_CHANNELS);
        if (k < 0) {
            rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s line %d: field %d is not a number", path,
                                  line_no, -k);
        } else if (r->n_channels == 0 && (k < 1 || k > MAX_CHANNELS)) {
            rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s line %d: %d columns (1..%d allowed)", path,
                                  line_no, k, MAX_CHANNELS);
        } else if (r->n_channels && k != r->n_channels) {
            rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s line %d: %d columns, expected %d", path,
                                  line_no, k, r->n_channels);
        } else if (n >= MAX_SAMPLES) {
            rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s: more than %d rows", path, MAX_SAMPLES);
        } else {
            if (!r->n_channels) r->n_channels = k;
            if ((size_t)(n + 1) * r->n_channels > (size_t)*cap) {
                int c2 = *cap ? 2 * *cap : 4096;
                while ((size_t)c2 < (size_t)(n + 1) * r->n_channels) c2 *= 2;
                double *grown = realloc(*rows, sizeof(double) * (size_t)c2);
                if (!grown) {
                    rc = sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory reading %s", path);
                    break;
                }
                *rows = grown;
                *cap = c2;
            }
            memcpy(*rows + (size_t)n * r->n_channels, v, sizeof(double) * r->n_channels);
            n++;
        }
    }
    free(text);
    if (rc) return rc;
    if (n == 0) return sasnav_set_error(SASNAV_ERR_FORMAT, "%s holds no samples", path);
    if (r->n_samples == 0) {
        r->n_samples = n;
        if (!dst) {
            size_t total = (size_t)r->n_pings * r->n_channels * n;
            r->samples = malloc(sizeof(float) * total);
            if (!r->samples) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory for %zu samples", total);
        }
    } else if (n != r->n_samples) {
        return sasnav_set_error(SASNAV_ERR_FORMAT, "%s has %d rows, Flight-000001.csv has %d", path, n,
                                r->n_samples);
    }
    if (!dst) dst = r->samples + (size_t)p * r->n_channels * r->n_samples;
    /* transpose rows [sample][channel] into [channel][sample] */
    for (int c = 0; c < r->n_channels; c++)
        for (int m = 0; m < n; m++) dst[(size_t)c * n + m] = (float)(*rows)[(size_t)m * r->n_channels + c];
    return SASNAV_OK;
}

/* An opened recording's flight reader (sasnav_airsas_open). */
typedef struct {
    char *dir;
    sasnav_airsas *rec;
    double *rows;
    int cap;
} flight_reader;

static int read_flight_on_demand(void *ctx, int p, float *out)
{
    flight_reader *f = ctx;
    if (p < 0 || p >= f->rec->n_pings)
        return sasnav_set_error(SASNAV_ERR_ARG, "airsas: flight %d outside 1..%d", p + 1, f->rec->n_pings);
    return read_flight(f->dir, p, f->rec, &f->rows, &f->cap, out);
}

static void close_flights(void *ctx)
{
    flight_reader *f = ctx;
    if (!f) return;
    free(f->dir);
    free(f->rows);
    free(f);
}

void sasnav_airsas_free(sasnav_airsas *rec)
{
    if (!rec) return;
    if (rec->close_flights) rec->close_flights(rec->flight_ctx);
    free(rec->samples);
    free(rec->angle_deg);
    free(rec->height_mm);
    free(rec->temperature);
    free(rec);
}

/* sasnav_airsas_read (streamed = 0) or sasnav_airsas_open (1: the first
 * flight read for the shape only, the others left for read_flight). */
static int airsas_load(const char *dir, int streamed, sasnav_airsas **rec)
{
    if (!rec) return sasnav_set_error(SASNAV_ERR_ARG, "airsas: output pointer is NULL");
    *rec = NULL;
    if (!dir || !*dir) return sasnav_set_error(SASNAV_ERR_ARG, "airsas: no directory given");
    struct stat st;
    if (stat(dir, &st) != 0)
        return sasnav_set_error(SASNAV_ERR_IO, "cannot open %s: %s", dir, strerror(errno));
    if (!S_ISDIR(st.st_mode)) return sasnav_set_error(SASNAV_ERR_IO, "%s is not a directory", dir);
    sasnav_airsas *r = calloc(1, sizeof *r);
    if (!r) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    int rc = read_coordinates(dir, r);
    if (!rc) rc = read_sysparams(dir, r);
    if (!rc) rc = read_waveform(dir, r);
    double *rows = NULL;
    int cap = 0;
    if (!streamed) {
        for (int p = 0; !rc && p < r->n_pings; p++) rc = read_flight(dir, p, r, &rows, &cap, NULL);
        free(rows);
    } else if (!rc) {
        flight_reader *f = calloc(1, sizeof *f);
        if (f) f->dir = strdup(dir);
        if (!f || !f->dir) {
            free(f);
            rc = sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
        } else {
            f->rec = r;
            r->read_flight = read_flight_on_demand;
            r->close_flights = close_flights;
            r->flight_ctx = f;
            /* The shape, from the first flight, read as if the recording
             * had one ping (its samples allocated for that ping only, then
             * dropped: the flights are read again when used). */
            int n_pings = r->n_pings;
            r->n_pings = 1;
            rc = read_flight(dir, 0, r, &f->rows, &f->cap, NULL);
            r->n_pings = n_pings;
            free(r->samples);
            r->samples = NULL;
        }
    }
    if (rc) {
        sasnav_airsas_free(r);
        return rc;
    }
    *rec = r;
    return SASNAV_OK;
}

int sasnav_airsas_read(const char *dir, sasnav_airsas **rec) { return airsas_load(dir, 0, rec); }

int sasnav_airsas_open(const char *dir, sasnav_airsas **rec) { return airsas_load(dir, 1, rec); }
