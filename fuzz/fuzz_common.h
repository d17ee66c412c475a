/* Shared helpers of the libFuzzer harnesses (docs/fuzzing.md).
 *
 *  - a private scratch directory in /dev/shm (tmpfs: no disk traffic),
 *    created on first use and removed at exit (or by a later harness, when
 *    this one crashed); readers take paths, so every
 *    input is written there first;
 *  - the multi-file container of the directory readers (fuzz_tank_dir,
 *    fuzz_airsas_dir): records until the input ends, each
 *        u8  file index (modulo the harness's number of file names)
 *        u16 length, little-endian (clamped to the bytes left)
 *        length bytes of content
 *    a later record for the same index replaces the earlier one; a file
 *    without a record does not exist;
 *  - the reader contract: SASNAV_OK, or one of the codes the reader
 *    documents, with a non-empty message. Anything else aborts (a crash
 *    for libFuzzer, so the input is kept). */
#ifndef SASNAV_FUZZ_COMMON_H
#define SASNAV_FUZZ_COMMON_H

#include "sasnav/error.h"

#include <dirent.h>
#include <errno.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* Sanitizer defaults for every harness (a corrupt size may make HDF5 or
 * libsndfile ask for terabytes: they handle NULL, as in a normal build).
 * HDF5 1.10.8 leaks a metadata-cache entry when an object header fails its
 * checks (tests/test_io_fuzz.c): that leak is HDF5's, not ours. Full
 * unwinding on malloc: libhdf5 has no frame pointers, and the suppression
 * needs the H5C_protect frame. libfyaml 0.8 leaks the chunk array of its
 * atom iterator when a scalar holds more escapes than its eight startup
 * slots (a single-quoted key of many '' pairs; upstream libfyaml issue
 * 233, fixed after 0.8): the frame fy_atom_format_text, under
 * fy_node_get_scalar (docs/fuzzing.md). */
const char *__asan_default_options(void);
const char *__asan_default_options(void) { return "allocator_may_return_null=1:detect_leaks=1:fast_unwind_on_malloc=0"; }
const char *__lsan_default_suppressions(void);
const char *__lsan_default_suppressions(void) { return "leak:H5C_protect\nleak:H5FL_\nleak:fy_atom_format_text\n"; }

static char fz_dir[64];

static inline void fz_rmdir(const char *dir)
{
    DIR *d = opendir(dir);
    if (d) {
        struct dirent *e;
        char p[1024];
        while ((e = readdir(d))) {
            if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
            snprintf(p, sizeof p, "%s/%s", dir, e->d_name);
            unlink(p);
        }
        closedir(d);
    }
    rmdir(dir);
}

static inline void fz_cleanup(void)
{
    if (fz_dir[0]) fz_rmdir(fz_dir);
}

/* The scratch directory "/dev/shm/sasnav-fuzz-<pid>" (or /tmp). A harness
 * that crashes or is killed (timeouts, fork mode) cannot clean up: the
 * directories of processes that no longer exist are removed here. */
static inline const char *fz_scratch(void)
{
    if (!fz_dir[0]) {
        const char *base = access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp";
        DIR *d = opendir(base);
        struct dirent *e;
        while (d && (e = readdir(d))) {
            long pid;
            char stale[512], end;
            if (sscanf(e->d_name, "sasnav-fuzz-%ld%c", &pid, &end) != 1 || pid <= 0) continue;
            if (kill((pid_t)pid, 0) == 0 || errno != ESRCH) continue;
            snprintf(stale, sizeof stale, "%s/%s", base, e->d_name);
            fz_rmdir(stale);
        }
        if (d) closedir(d);
        snprintf(fz_dir, sizeof fz_dir, "%s/sasnav-fuzz-%ld", base, (long)getpid());
        if (mkdir(fz_dir, 0700) != 0 && errno != EEXIST) abort();
        atexit(fz_cleanup);
    }
    return fz_dir;
}

/* Path of `name` in the scratch directory (static buffer). */
static inline const char *fz_path(const char *name)
{
    static char p[256];
    snprintf(p, sizeof p, "%s/%s", fz_scratch(), name);
    return p;
}

static inline void fz_write(const char *path, const uint8_t *data, size_t size)
{
    FILE *f = fopen(path, "wb");
    if (!f) abort();
    if (size && fwrite(data, 1, size, f) != size) abort();
    if (fclose(f)) abort();
}

/* Empties the scratch directory (the directory readers' input). */
static inline void fz_clear(void)
{
    const char *dir = fz_scratch();
    DIR *d = opendir(dir);
    if (!d) abort();
    struct dirent *e;
    char p[512];
    while ((e = readdir(d))) {
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
        snprintf(p, sizeof p, "%s/%s", dir, e->d_name);
        unlink(p);
    }
    closedir(d);
}

/* Unpacks the container (see above) into the scratch directory, after
 * emptying it. names[n] are the file names the indices map to. */
static inline void fz_unpack(const uint8_t *data, size_t size, const char *const *names, int n)
{
    fz_clear();
    const uint8_t *start[256] = {0};
    size_t len[256] = {0};
    int present[256] = {0};
    size_t pos = 0;
    while (pos < size) {
        int idx = data[pos++] % n;
        size_t l = 0;
        if (pos < size) l = data[pos++];
        if (pos < size) l |= (size_t)data[pos++] << 8;
        if (l > size - pos) l = size - pos;
        start[idx] = data + pos;
        len[idx] = l;
        present[idx] = 1;
        pos += l;
    }
    for (int k = 0; k < n; k++)
        if (present[k]) fz_write(fz_path(names[k]), start[k], len[k]);
}

/* Aborts unless rc is SASNAV_OK or one of the allowed codes (terminated by
 * 0) with a message. SASNAV_FUZZ_VERBOSE=1 prints every result. */
static inline void fz_check_rc(const char *what, int rc, const int *allowed)
{
    if (getenv("SASNAV_FUZZ_VERBOSE")) /* to see what a seed reaches */
        fprintf(stderr, "%s: %d %s\n", what, rc, rc ? sasnav_last_error() : "OK");
    if (rc == SASNAV_OK) return;
    for (const int *a = allowed; *a; a++)
        if (rc == *a) {
            const char *m = sasnav_last_error();
            if (!m || !m[0]) {
                fprintf(stderr, "%s: error %d without a message\n", what, rc);
                abort();
            }
            return;
        }
    fprintf(stderr, "%s: contract broken: returned %d (%s): %s\n", what, rc, sasnav_strerror(rc),
            sasnav_last_error());
    abort();
}

#endif
