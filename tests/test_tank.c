/* Tank simulator and WAV recording reader (include/sasnav/tank.h):
 * - SPEC 4 defaults; poses (jump, yaw, determinism);
 * - 2 pings written as a recording directory, read back through the ingest
 *   chain into a run: shapes, system, navigation and truth, and the strongest
 *   compressed echo at a reflector's range;
 * - noise-free, Hann-tapered ingest of the recording against the baseband
 *   operator (sasnav_op, the model the estimators use) with the true poses
 *   and the simulator's scatterers: one complex scale ~1, small residual
 *   (conventions of SPEC 2 carried through the WAV path);
 * - refusals: wrong channel count, empty file, sample-rate mismatch, clipped
 *   record, missing ping file. */
#include "sasnav/error.h"
#include "sasnav/op.h"
#include "sasnav/io.h"
#include "sasnav/tank.h"
#include "testutil.h"

#include <complex.h>
#include <math.h>
#include <sndfile.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static int write_test_wav(const char *path, int n_ch, int n_frames, int rate, double value, int clip)
{
    SF_INFO info;
    memset(&info, 0, sizeof info);
    info.samplerate = rate;
    info.channels = n_ch;
    info.format = SF_FORMAT_WAV | SF_FORMAT_FLOAT;
    SNDFILE *f = sf_open(path, SFM_WRITE, &info);
    if (!f) return -1;
    float *buf = calloc((size_t)n_ch * (n_frames > 0 ? n_frames : 1), sizeof(float));
    for (int n = 0; n < n_frames; n++)
        for (int l = 0; l < n_ch; l++) {
            double v = value * sin(0.6 * n + l);
            if (clip && v > 0.5 * value) v = 0.5 * value; /* saturated converter */
            buf[(size_t)n * n_ch + l] = (float)v;
        }
    if (n_frames > 0) sf_writef_float(f, buf, n_frames);
    free(buf);
    return sf_close(f);
}

/* Ingest (Hann taper) of a noise-free 2-ping recording vs sasnav_op. */
static void test_against_operator(const sasnav_tank_params *p0, const char *dir)
{
    sasnav_tank_params p = *p0;
    p.noise_std = 0.0;
    CHECK_OK(sasnav_tank_write_dir(&p, dir));
    sasnav_tank_read_opts o;
    sasnav_tank_default_read_opts(&o);
    o.taper = SASNAV_TAPER_HANN;
    sasnav_run *run = NULL;
    CHECK_OK(sasnav_tank_read_dir(dir, &o, &run));
    if (!run) return;
    int m = p.n_reflectors + p.n_clutter, ns = run->win.n_samples, nr = run->array.n_rx;
    double *x = malloc(sizeof(double) * m), *y = malloc(sizeof(double) * m);
    double *amp = malloc(sizeof(double) * m);
    sasnav_cfloat *rho = malloc(sizeof *rho * m), *phi = malloc(sizeof *phi * (size_t)nr * ns);
    CHECK_OK(sasnav_tank_scene(&p, x, y, amp));
    for (int i = 0; i < m; i++) rho[i] = (float)(p.gain * amp[i]);
    sasnav_op *op = NULL;
    CHECK_OK(sasnav_op_create(&run->sys, &run->array, &run->win, m, x, y, NULL, &op));
    for (int k = 0; op && k < run->n_pings; k++) {
        CHECK_OK(sasnav_op_set_geometry(op, &run->truth[k]));
        CHECK_OK(sasnav_op_forward(op, rho, phi));
        CHECK(sasnav_op_n_dropped(op) == 0, "ping %d: echoes outside the operator grid", k);
        const sasnav_cfloat *z = sasnav_run_ping(run, k);
        double complex num = 0;
        double den = 0, zz = 0, res = 0;
        for (size_t i = 0; i < (size_t)nr * ns; i++) {
            num += conj((double complex)phi[i]) * z[i];
            den += cabs(phi[i]) * cabs(phi[i]);
            zz += cabs(z[i]) * cabs(z[i]);
        }
        double complex a = num / den;
        for (size_t i = 0; i < (size_t)nr * ns; i++) {
            double complex d = z[i] - a * phi[i];
            res += creal(d) * creal(d) + cimag(d) * cimag(d);
        }
        double err = sqrt(res / zz);
        printf("  ping %d vs sasnav_op: relative error %.2e, scale %.5f %+.5fj\n", k, err,
               creal(a), cimag(a));
        CHECK(err < 5e-3, "ping %d: relative error %g vs the operator", k, err);
        CHECK(cabs(a - 1.0) < 1e-2, "ping %d: scale %g%+gj is not 1", k, creal(a), cimag(a));
    }
    sasnav_op_destroy(op);
    sasnav_run_free(run);
    free(x);
    free(y);
    free(amp);
    free(rho);
    free(phi);
}

/* sasnav_tank_ingest_dir (written ping by ping) gives the file of
 * sasnav_tank_read_dir's run: samples, navigation, truth and constants
 * read back equal, and the header it reports is the run's. */
static void test_ingest_to_file(const char *dir)
{
    char path[1200];
    snprintf(path, sizeof path, "%s/streamed.h5", dir);
    sasnav_tank_read_opts o;
    sasnav_tank_default_read_opts(&o);
    sasnav_run *a = NULL, *b = NULL, info;
    CHECK_OK(sasnav_tank_read_dir(dir, &o, &a));
    CHECK_OK(sasnav_tank_ingest_dir(dir, &o, path, &info));
    CHECK_OK(sasnav_run_read(path, &b));
    if (a && b) {
        size_t ns = sasnav_run_ping_size(a) * (size_t)a->n_pings;
        CHECK(b->n_pings == a->n_pings && sasnav_run_ping_size(b) == sasnav_run_ping_size(a) &&
                  !memcmp(a->raw, b->raw, sizeof *a->raw * ns) &&
                  !memcmp(a->nav, b->nav, sizeof *a->nav * (size_t)a->n_pings) && b->truth &&
                  !memcmp(a->truth, b->truth, sizeof *a->truth * (size_t)a->n_pings) &&
                  a->ping_spacing == b->ping_spacing && a->range_of_interest == b->range_of_interest &&
                  test_same_system(&a->sys, &b->sys),
              "the run written ping by ping differs from the one read whole");
        CHECK(info.n_pings == a->n_pings && info.array.n_rx == a->array.n_rx &&
                  info.win.n_samples == a->win.n_samples && info.raw == NULL && info.nav == NULL,
              "header: %d pings x %d channels x %d samples", info.n_pings, info.array.n_rx, info.win.n_samples);
    }
    sasnav_run_free(a);
    sasnav_run_free(b);
}

static void expect_refusal(const char *dir, const char *what, const char *needle)
{
    sasnav_tank_read_opts o;
    sasnav_tank_default_read_opts(&o);
    sasnav_run *run = NULL;
    int rc = sasnav_tank_read_dir(dir, &o, &run);
    CHECK(rc != 0 && run == NULL, "%s: accepted", what);
    CHECK(rc == SASNAV_ERR_FORMAT || rc == SASNAV_ERR_IO, "%s: code %d", what, rc);
    CHECK(strstr(sasnav_last_error(), needle) != NULL, "%s: message '%s' lacks '%s'", what,
          sasnav_last_error(), needle);
    printf("  %s refused: %s\n", what, sasnav_last_error());
    sasnav_run_free(run);
}

int main(void)
{
    sasnav_tank_params p;
    sasnav_tank_default(&p);
    CHECK_OK(sasnav_tank_check(&p));
    CHECK(p.n_rx == 8 && p.n_pings == 32 && fabs(p.step - 0.025) < 1e-12, "defaults");
    CHECK(sasnav_tank_n_chirp(&p) == 3000, "chirp of %d samples", sasnav_tank_n_chirp(&p));
    int ns = sasnav_tank_n_samples(&p);
    CHECK(ns >= (int)(1e6 * (2 * 3.0 / 1480 + 3e-3)), "record of %d samples too short", ns);

    /* full-length poses: the jump between pings 11 and 12, constant yaw */
    sasnav_ping_pose nom[32], tru[32];
    CHECK_OK(sasnav_tank_poses(&p, nom, tru));
    double d_jump = tru[12].array.x - tru[11].array.x;
    CHECK(fabs(d_jump - (0.025 + 0.017)) < 0.01, "jump step %g", d_jump);
    for (int k = 0; k < 32; k++) {
        CHECK(fabs(tru[k].array.theta - 1.27e-2) < 1e-15, "yaw of ping %d", k);
        CHECK(fabs(nom[k].array.x - (p.x_start + k * 0.025)) < 1e-12, "nominal x of ping %d", k);
        if (k > 0 && k != 12) {
            double s = tru[k].array.x - tru[k - 1].array.x;
            CHECK(fabs(s - 0.025) < 0.01, "step %d is %g", k, s);
        }
    }

    /* a 2-ping recording */
    p.n_pings = 2;
    p.n_clutter = 40;
    p.x_start = -0.0125;
    const char *tmp = test_tmpdir();
    char dir[1024], path[1200];
    snprintf(dir, sizeof dir, "%s/rec", tmp);
    CHECK_OK(sasnav_tank_write_dir(&p, dir));

    /* determinism of the synthesis */
    float *a = malloc(sizeof(float) * 8 * ns), *b = malloc(sizeof(float) * 8 * ns);
    sasnav_ping_pose t1;
    CHECK_OK(sasnav_tank_record(&p, 1, a, &t1));
    CHECK_OK(sasnav_tank_record(&p, 1, b, NULL));
    CHECK(memcmp(a, b, sizeof(float) * 8 * ns) == 0, "ping synthesis is not deterministic");
    float peak = 0;
    for (int i = 0; i < 8 * ns; i++) peak = fmaxf(peak, fabsf(a[i]));
    CHECK(peak > 0.05f && peak < 1.0f, "passband peak %g outside (0.05, 1)", peak);
    free(a);
    free(b);

    sasnav_tank_read_opts o;
    sasnav_tank_default_read_opts(&o);
    sasnav_run *run = NULL;
    CHECK_OK(sasnav_tank_read_dir(dir, &o, &run));
    if (run) {
        int nout = (ns + 32) / 33;
        CHECK(run->n_pings == 2 && run->array.n_rx == 8, "shape %d pings x %d rx", run->n_pings,
              run->array.n_rx);
        CHECK(run->win.n_samples == nout, "n_samples %d, expected %d", run->win.n_samples, nout);
        CHECK(fabs(run->sys.f0 - 105e3) < 1e-6 && fabs(run->sys.bandwidth - 30e3) < 1e-6,
              "band %g %g", run->sys.f0, run->sys.bandwidth);
        CHECK(fabs(run->sys.sample_rate - 1e6 / 33) < 1e-6, "fs %g", run->sys.sample_rate);
        CHECK(run->sys.sound_speed == 1480.0 && run->tx_lag == 0.0 &&
                  run->range_of_interest == 1.5,
              "system/run fields");
        CHECK(fabs(run->ping_spacing - 0.025) < 1e-9, "ping spacing %g", run->ping_spacing);
        CHECK(run->truth != NULL, "truth.csv not read");
        CHECK(fabs(run->nav[1].array.x - 0.0125) < 1e-9 && run->nav[1].array.theta == 0.0,
              "nominal nav");
        if (run->truth) {
            CHECK(fabs(run->truth[1].array.x - t1.array.x) < 1e-8 &&
                      fabs(run->truth[1].array.y - t1.array.y) < 1e-8 &&
                      fabs(run->truth[1].array.theta - t1.array.theta) < 1e-10,
                  "truth of ping 1 (%g %g %g) vs (%g %g %g)", run->truth[1].array.x,
                  run->truth[1].array.y, run->truth[1].array.theta, t1.array.x, t1.array.y,
                  t1.array.theta);
        }
        /* strongest echo of every channel of ping 0 at a reflector range
         * (rows at y = 1.4 and 1.6, x = +-0.1 -> ~1.404 / ~1.603 m) */
        double dr = 1480.0 / (2.0 * run->sys.sample_rate); /* 2.44 cm per sample */
        for (int l = 0; l < 8; l++) {
            const sasnav_cfloat *z = sasnav_run_ping(run, 0) + (size_t)l * run->win.n_samples;
            int best = 0;
            for (int m = 1; m < run->win.n_samples; m++)
                if (cabsf(z[m]) > cabsf(z[best])) best = m;
            double r = 0.5 * 1480.0 * (run->win.t0 + best / run->sys.sample_rate);
            double e = fmin(fabs(r - 1.404), fabs(r - 1.603));
            CHECK(e < 1.5 * dr, "channel %d: peak at %.3f m", l, r);
            if (l == 0) printf("  channel 0: compressed peak |z| %.3f at %.3f m\n", cabsf(z[best]), r);
        }
        sasnav_run_free(run);
    }

    char dir2[1100];
    snprintf(dir2, sizeof dir2, "%s/clean", tmp);
    test_against_operator(&p, dir2);
    test_ingest_to_file(dir2);

    /* refusals, each on ping_001.wav */
    snprintf(path, sizeof path, "%s/ping_001.wav", dir);
    CHECK(write_test_wav(path, 7, ns, 1000000, 0.1, 0) == 0, "cannot write a test WAV");
    expect_refusal(dir, "wrong channel count", "channels");
    CHECK(write_test_wav(path, 8, 0, 1000000, 0.1, 0) == 0, "cannot write a test WAV");
    expect_refusal(dir, "empty WAV", "empty");
    CHECK(write_test_wav(path, 8, ns, 500000, 0.1, 0) == 0, "cannot write a test WAV");
    expect_refusal(dir, "sample-rate mismatch", "sample rate");
    CHECK(write_test_wav(path, 8, ns - 5, 1000000, 0.1, 0) == 0, "cannot write a test WAV");
    expect_refusal(dir, "length mismatch", "samples per channel");
    CHECK(write_test_wav(path, 8, ns, 1000000, 0.5, 1) == 0, "cannot write a test WAV");
    expect_refusal(dir, "clipped record", "clip");
    remove(path);
    expect_refusal(dir, "missing ping", "ping_001.wav");
    /* Written ping by ping: a refusal leaves no file. */
    {
        char out[1200];
        snprintf(out, sizeof out, "%s/refused.h5", tmp);
        sasnav_tank_read_opts o;
        sasnav_tank_default_read_opts(&o);
        CHECK(sasnav_tank_ingest_dir(dir, &o, out, NULL) != 0 && access(out, F_OK) != 0,
              "a refused recording left %s", out);
    }

    return test_summary("test_tank");
}
