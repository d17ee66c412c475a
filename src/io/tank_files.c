/* The tank experiment's files (include/sasnav/tank.h): a simulated
 * recording written as WAV/CSV files, and such a directory (simulated or
 * recorded) read into a run through the ingest chain. */
#include "sasnav/tank.h"

#include "sasnav/error.h"
#include "sasnav/ingest.h"
#include "sasnav/io.h"
#include "io/textfile.h"

#include <errno.h>
#include <math.h>
#include <sndfile.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* ------------------------------------------------------------- writing */

/* Writes n_frames x n_ch samples (channel-major input) to `path` via a
 * temporary file renamed into place. */
static int write_wav(const char *path, const float *data, int n_ch, int n_frames, double fs)
{
    int rc0 = sasnav_output_check(path);
    if (rc0) return rc0;
    char tmp[4200];
    int k = snprintf(tmp, sizeof tmp, "%s.tmp%ld", path, (long)getpid());
    if (k < 0 || (size_t)k >= sizeof tmp) return sasnav_set_error(SASNAV_ERR_ARG, "path too long: %s", path);
    float *frames = malloc(sizeof(float) * (size_t)n_ch * n_frames);
    if (!frames) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory writing %s", path);
    for (int n = 0; n < n_frames; n++)
        for (int l = 0; l < n_ch; l++) frames[(size_t)n * n_ch + l] = data[(size_t)l * n_frames + n];
    SF_INFO info;
    memset(&info, 0, sizeof info);
    info.samplerate = (int)lround(fs);
    info.channels = n_ch;
    info.format = SF_FORMAT_WAV | SF_FORMAT_FLOAT;
    sigset_t held;
    sasnav_partial_hold(&held);
    SNDFILE *f = sf_open(tmp, SFM_WRITE, &info);
    int slot = f ? sasnav_partial_add(tmp) : -1;
    sasnav_partial_release(&held);
    if (!f) {
        free(frames);
        return sasnav_set_error(SASNAV_ERR_IO, "cannot create %s: %s", tmp, sf_strerror(NULL));
    }
    sf_count_t w = sf_writef_float(f, frames, n_frames);
    free(frames);
    int close_rc = sf_close(f);
    int rc = SASNAV_OK;
    if (w != n_frames || close_rc != 0) {
        unlink(tmp);
        rc = sasnav_set_error(SASNAV_ERR_IO, "cannot write %s (%lld of %d frames)", tmp,
                              (long long)w, n_frames);
    } else if (rename(tmp, path)) {
        int e = errno;
        unlink(tmp);
        rc = sasnav_set_error(SASNAV_ERR_IO, "cannot rename %s to %s: %s", tmp, path, strerror(e));
    }
    sasnav_partial_remove(slot);
    return rc;
}

static int write_poses_csv(const char *path, const sasnav_ping_pose *poses, int n)
{
    sasnav_text_out out;
    int rc = sasnav_text_open(&out, path);
    if (rc) return rc;
    fprintf(out.f, "ping,x,y,yaw\n");
    for (int i = 0; i < n; i++)
        fprintf(out.f, "%d,%.9f,%.9f,%.9e\n", i, poses[i].array.x, poses[i].array.y,
                poses[i].array.theta);
    return sasnav_text_commit(&out);
}

int sasnav_tank_write_dir(const sasnav_tank_params *p, const char *dir)
{
    int rc = sasnav_tank_check(p);
    if (rc) return rc;
    if (!dir || !*dir) return sasnav_set_error(SASNAV_ERR_ARG, "tank: no output directory");
    if (mkdir(dir, 0777) && errno != EEXIST)
        return sasnav_set_error(SASNAV_ERR_IO, "cannot create %s: %s", dir, strerror(errno));
    struct stat st;
    if (stat(dir, &st) || !S_ISDIR(st.st_mode))
        return sasnav_set_error(SASNAV_ERR_IO, "%s is not a directory", dir);
    int ns = sasnav_tank_n_samples(p), nc = sasnav_tank_n_chirp(p);
    float *buf = malloc(sizeof(float) * (size_t)p->n_rx * ns);
    float *chirp = malloc(sizeof(float) * nc);
    sasnav_ping_pose *nom = malloc(sizeof *nom * p->n_pings), *tru = malloc(sizeof *tru * p->n_pings);
    char path[4096], name[64];
    if (!buf || !chirp || !nom || !tru) {
        rc = sasnav_set_error(SASNAV_ERR_NOMEM, "tank: out of memory");
        goto done;
    }
    if ((rc = sasnav_lfm_samples(&p->chirp, p->sample_rate, nc, chirp))) goto done;
    if ((rc = sasnav_path_join(path, sizeof path, dir, "chirp.wav"))) goto done;
    if ((rc = write_wav(path, chirp, 1, nc, p->sample_rate))) goto done;
    if ((rc = sasnav_tank_poses(p, nom, tru))) goto done;
    for (int k = 0; k < p->n_pings; k++) {
        if ((rc = sasnav_tank_record(p, k, buf, NULL))) goto done;
        snprintf(name, sizeof name, "ping_%03d.wav", k);
        if ((rc = sasnav_path_join(path, sizeof path, dir, name))) goto done;
        if ((rc = write_wav(path, buf, p->n_rx, ns, p->sample_rate))) goto done;
    }
    if ((rc = sasnav_path_join(path, sizeof path, dir, "positions.csv"))) goto done;
    if ((rc = write_poses_csv(path, nom, p->n_pings))) goto done;
    if ((rc = sasnav_path_join(path, sizeof path, dir, "truth.csv"))) goto done;
    if ((rc = write_poses_csv(path, tru, p->n_pings))) goto done;
    /* the sensor description the reader needs to model the recording */
    if ((rc = sasnav_path_join(path, sizeof path, dir, "array.csv"))) goto done;
    sasnav_text_out ao;
    if ((rc = sasnav_text_open(&ao, path))) goto done;
    fprintf(ao.f, "rx_spacing,element_length,directivity\n%.9g,%.9g,%d\n", p->rx_spacing,
            p->element_length, p->directivity);
    rc = sasnav_text_commit(&ao);
done:
    free(buf);
    free(chirp);
    free(nom);
    free(tru);
    return rc;
}

/* ------------------------------------------------------------- reading */

void sasnav_tank_default_read_opts(sasnav_tank_read_opts *o)
{
    if (!o) return;
    memset(o, 0, sizeof *o);
    o->sound_speed = 1480.0;
    o->f0 = 105e3;
    o->bandwidth = 30e3;
    o->decimation = 33;
    o->taper = SASNAV_TAPER_NONE;
    o->compression = SASNAV_COMPRESS_MODEL;
    o->attenuation = SASNAV_ATTEN_SPHERICAL;
    o->clip_run = 3;
    o->rx_spacing = 0.05;
    o->element_length = 0.05;
    o->directivity = 1;
    o->range_of_interest = 1.5;
}

/* array.csv (optional): "rx_spacing,element_length,directivity" and one
 * line of values; overrides the options. */
static int read_array_csv(const char *path, sasnav_tank_read_opts *o)
{
    FILE *f = sasnav_fopen_regular(path);
    if (!f) return SASNAV_ERR_IO;
    char head[256];
    double sp, el;
    int dir, ok = fgets(head, sizeof head, f) != NULL &&
                  !strncmp(head, "rx_spacing,element_length,directivity", 37) &&
                  fscanf(f, "%lf,%lf,%d", &sp, &el, &dir) == 3;
    fclose(f);
    if (!ok || !isfinite(sp) || sp <= 0 || !isfinite(el) || el < 0 || (dir != 0 && dir != 1))
        return sasnav_set_error(SASNAV_ERR_FORMAT,
                                "%s: expected 'rx_spacing,element_length,directivity' and one line of "
                                "values (spacing > 0, length >= 0, directivity 0 or 1)",
                                path);
    o->rx_spacing = sp;
    o->element_length = el;
    o->directivity = dir;
    return SASNAV_OK;
}

/* Reads a whole WAV into channel-major samples. */
static int read_wav(const char *path, int *n_ch, int *n_frames, int *rate, float **data)
{
    *data = NULL;
    SF_INFO info;
    memset(&info, 0, sizeof info);
    int fd = sasnav_open_regular(path);
    if (fd < 0) return SASNAV_ERR_IO;
    SNDFILE *f = sf_open_fd(fd, SFM_READ, &info, 1); /* closes fd */
    if (!f)
        return sasnav_set_error(SASNAV_ERR_FORMAT, "%s is not a readable sound file: %s", path,
                                sf_strerror(NULL));
    int rc = SASNAV_OK;
    if (info.frames <= 0)
        rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s is empty (no samples)", path);
    else if (info.channels < 1 || info.channels > SASNAV_MAX_RX)
        rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s has %d channels (1..%d supported)", path,
                              info.channels, SASNAV_MAX_RX);
    else if (info.frames > 100000000 / info.channels)
        rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s is too long (%lld frames)", path,
                              (long long)info.frames);
    else if (info.samplerate <= 0)
        rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s has sample rate %d", path, info.samplerate);
    float *frames = NULL, *out = NULL;
    if (!rc) {
        frames = malloc(sizeof(float) * (size_t)info.channels * info.frames);
        out = malloc(sizeof(float) * (size_t)info.channels * info.frames);
        if (!frames || !out) rc = sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory reading %s", path);
    }
    if (!rc) {
        sf_count_t got = sf_readf_float(f, frames, info.frames);
        if (got != info.frames)
            rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s: read %lld of %lld frames (truncated?)", path,
                                  (long long)got, (long long)info.frames);
    }
    sf_close(f);
    if (!rc) {
        int nf = (int)info.frames, nch = info.channels;
        for (int n = 0; n < nf; n++)
            for (int l = 0; l < nch; l++) out[(size_t)l * nf + n] = frames[(size_t)n * nch + l];
        *n_ch = nch;
        *n_frames = nf;
        *rate = info.samplerate;
        *data = out;
        out = NULL;
    }
    free(frames);
    free(out);
    return rc;
}

/* Reads "ping,x,y,yaw" rows 0..n-1 into poses (Tx = array). *n = 0 and
 * SASNAV_ERR_IO when the file is missing. */
static int read_poses_csv(const char *path, sasnav_ping_pose **poses, int *n)
{
    *poses = NULL;
    *n = 0;
    FILE *f = sasnav_fopen_regular(path);
    if (!f) return SASNAV_ERR_IO;
    char line[512];
    int cap = 0, rc = SASNAV_OK, lineno = 0;
    sasnav_ping_pose *v = NULL;
    while (fgets(line, sizeof line, f)) {
        lineno++;
        char *s = line;
        while (*s == ' ' || *s == '\t') s++;
        if (*s == '\n' || *s == '\r' || *s == '\0' || *s == '#') continue;
        if (lineno == 1 && !strncmp(s, "ping", 4)) continue; /* header */
        int k;
        double x, y, yaw;
        char extra;
        if (sscanf(s, "%d ,%lf ,%lf ,%lf %c", &k, &x, &y, &yaw, &extra) != 4 || !isfinite(x) ||
            !isfinite(y) || !isfinite(yaw)) {
            rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s line %d: expected 'ping,x,y,yaw'", path,
                                  lineno);
            break;
        }
        if (k != *n) {
            rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s line %d: ping %d, expected %d", path,
                                  lineno, k, *n);
            break;
        }
        if (*n >= 1000000) {
            rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s: too many pings", path);
            break;
        }
        if (*n == cap) {
            cap = cap ? 2 * cap : 64;
            sasnav_ping_pose *t = realloc(v, sizeof *v * cap);
            if (!t) {
                rc = sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory reading %s", path);
                break;
            }
            v = t;
        }
        sasnav_pose q = {x, y, yaw};
        v[*n].tx = q;
        v[*n].array = q;
        (*n)++;
    }
    fclose(f);
    if (!rc && *n == 0) rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s lists no ping", path);
    if (rc) {
        free(v);
        *n = 0;
        return rc;
    }
    *poses = v;
    return SASNAV_OK;
}

/* sasnav_tank_read_dir (out_path NULL: the run in memory, *run) or
 * sasnav_tank_ingest_dir (each ping written to out_path as it is made; the
 * header in *info). */
static int tank_ingest(const char *dir, const sasnav_tank_read_opts *o_in, const char *out_path,
                       sasnav_run **run, sasnav_run *info)
{
    if (!dir || !o_in) return sasnav_set_error(SASNAV_ERR_ARG, "tank: NULL directory or options");
    sasnav_tank_read_opts oc = *o_in;
    const sasnav_tank_read_opts *o = &oc;
    if (!isfinite(o->sound_speed) || o->sound_speed <= 0 || !isfinite(o->range_of_interest) ||
        o->range_of_interest <= 0)
        return sasnav_set_error(SASNAV_ERR_ARG, "tank: bad sound speed or range of interest");
    char path[4096];
    sasnav_ping_pose *nav = NULL, *truth = NULL;
    float *chirp = NULL, *rec = NULL;
    sasnav_ingest *plan = NULL;
    sasnav_run *r = NULL, hdr;
    sasnav_run_writer *writer = NULL;
    int n_pings = 0, n_truth = 0, rc;
    memset(&hdr, 0, sizeof hdr);

    if ((rc = sasnav_path_join(path, sizeof path, dir, "array.csv"))) return rc;
    if (access(path, F_OK) == 0 && (rc = read_array_csv(path, &oc))) return rc;
    if ((rc = sasnav_path_join(path, sizeof path, dir, "positions.csv"))) return rc;
    if ((rc = read_poses_csv(path, &nav, &n_pings))) return rc;
    if ((rc = sasnav_path_join(path, sizeof path, dir, "truth.csv"))) goto done;
    if (access(path, F_OK) == 0) {
        if ((rc = read_poses_csv(path, &truth, &n_truth))) goto done;
        if (n_truth != n_pings) {
            rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s lists %d pings, positions.csv %d", path,
                                  n_truth, n_pings);
            goto done;
        }
    }

    int nch_c, nc, rate_c;
    if ((rc = sasnav_path_join(path, sizeof path, dir, "chirp.wav"))) goto done;
    if ((rc = read_wav(path, &nch_c, &nc, &rate_c, &chirp))) goto done;
    if (nch_c != 1) {
        rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s has %d channels, the chirp must be mono", path,
                              nch_c);
        goto done;
    }

    int n_rx = 0, n_in = 0;
    for (int k = 0; k < n_pings; k++) {
        char name[64];
        snprintf(name, sizeof name, "ping_%03d.wav", k);
        if ((rc = sasnav_path_join(path, sizeof path, dir, name))) goto done;
        int nch, nf, rate;
        free(rec);
        rec = NULL;
        if ((rc = read_wav(path, &nch, &nf, &rate, &rec))) goto done;
        if (rate != rate_c) {
            rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s: sample rate %d Hz, chirp.wav %d Hz", path,
                                  rate, rate_c);
            goto done;
        }
        if (k == 0) {
            n_rx = nch;
            n_in = nf;
            sasnav_ingest_opts io;
            sasnav_ingest_default_opts(&io);
            io.sample_rate = rate;
            io.t_start = 0.0;
            io.f0 = o->f0;
            io.bandwidth = o->bandwidth;
            io.decimation = o->decimation;
            io.compression = o->compression;
            io.taper = o->taper;
            io.clip_run = o->clip_run;
            if ((rc = sasnav_ingest_create(&io, n_in, chirp, nc, &plan))) goto done;
            sasnav_system sys;
            sasnav_system_default(&sys);
            if ((rc = sasnav_ingest_system(plan, &sys))) goto done;
            sys.sound_speed = o->sound_speed;
            sys.attenuation = o->attenuation;
            sys.beam_pattern = o->directivity ? 1 : 0;
            sasnav_array a;
            if ((rc = sasnav_array_uniform(&a, n_rx, o->rx_spacing, o->element_length,
                                           o->element_length)))
                goto done;
            sasnav_window win;
            if ((rc = sasnav_ingest_window(plan, &win))) goto done;
            /* In memory: the whole run. Written: one ping's buffer, and the
             * writer opened on the run's shape. */
            if ((rc = sasnav_run_alloc(&sys, &a, &win, out_path ? 1 : n_pings, truth != NULL && !out_path, &r)))
                goto done;
            hdr = *r;
            hdr.n_pings = n_pings;
            hdr.raw = NULL;
            hdr.nav = nav;
            hdr.truth = truth;
            if (out_path && (rc = sasnav_run_writer_open(out_path, &hdr, &writer))) goto done;
        } else if (nch != n_rx) {
            rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s has %d channels, ping_000.wav %d", path,
                                  nch, n_rx);
            goto done;
        } else if (nf != n_in) {
            rc = sasnav_set_error(SASNAV_ERR_FORMAT, "%s has %d samples per channel, ping_000.wav %d",
                                  path, nf, n_in);
            goto done;
        }
        if (sasnav_ingest_check_record(plan, n_rx, rec)) {
            rc = sasnav_prefix_error(SASNAV_ERR_FORMAT, "%s", path);
            goto done;
        }
        if ((rc = sasnav_ingest_execute(plan, n_rx, rec, sasnav_run_ping(r, out_path ? 0 : k)))) goto done;
        if (out_path && (rc = sasnav_run_writer_put(writer, k, sasnav_run_ping(r, 0)))) goto done;
    }
    hdr.ping_spacing = n_pings > 1 ? fabs(nav[n_pings - 1].array.x - nav[0].array.x) / (n_pings - 1) : 0.0;
    hdr.speed = 0.0;
    hdr.tx_lag = 0.0;
    hdr.range_of_interest = o->range_of_interest;
    if (!out_path) {
        memcpy(r->nav, nav, sizeof *nav * n_pings);
        if (truth) memcpy(r->truth, truth, sizeof *truth * n_pings);
        r->ping_spacing = hdr.ping_spacing;
        r->speed = hdr.speed;
        r->tx_lag = hdr.tx_lag;
        r->range_of_interest = hdr.range_of_interest;
        rc = sasnav_run_check(r);
    } else {
        rc = sasnav_run_check_header(&hdr);
        if (!rc) {
            rc = sasnav_run_writer_finish(writer, &hdr);
            writer = NULL;
        }
        if (!rc && info) {
            *info = hdr;
            info->nav = info->truth = NULL;
        }
    }
done:
    if (writer) sasnav_run_writer_abort(writer);
    if (rc || out_path) sasnav_run_free(r);
    else *run = r;
    sasnav_ingest_destroy(plan);
    free(nav);
    free(truth);
    free(chirp);
    free(rec);
    return rc;
}

int sasnav_tank_read_dir(const char *dir, const sasnav_tank_read_opts *o, sasnav_run **run)
{
    if (!run) return sasnav_set_error(SASNAV_ERR_ARG, "tank: run output is NULL");
    *run = NULL;
    return tank_ingest(dir, o, NULL, run, NULL);
}

int sasnav_tank_ingest_dir(const char *dir, const sasnav_tank_read_opts *o, const char *path, sasnav_run *info)
{
    if (!path) return sasnav_set_error(SASNAV_ERR_ARG, "tank: no output file");
    if (info) memset(info, 0, sizeof *info);
    return tank_ingest(dir, o, path, NULL, info);
}
