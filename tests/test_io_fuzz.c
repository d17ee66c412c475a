/* Robustness of the HDF5 readers against damaged files (fuzz-style).
 *
 * Valid files are damaged by seeded random mutations (bit flips, random
 * bytes, zero/0xFF runs, truncation, deleted ranges, combinations) and read
 * back. Contract: a reader returns either SASNAV_OK with a valid object
 * (sasnav_run_check passes) or SASNAV_ERR_FORMAT / SASNAV_ERR_IO with a
 * message; it never crashes, hangs, leaks or returns another code.
 *
 * Each variant is read in a forked child with an alarm, so a crash or a
 * hang is reported with the variant that caused it (kept in the test
 * directory as fuzz-fail-*.h5 to reproduce) instead of killing the test.
 * Under ASan/UBSan a memory error or a leak in the child (non-zero exit) is
 * a failure too.
 *
 * Bases: files written by sasnav (checksummed metadata, Fletcher-32 data)
 * and a run written with HDF5's oldest defaults (no checksums at all, as
 * h5py or MATLAB may write), which exercises HDF5's own parsers much harder
 * (with fixed-length strings: see write_legacy_run).
 *
 * HDF5 1.10.8 itself has memory errors and an endless loop on some damaged
 * files without checksums (attribute-message decoding, global heap). For the
 * unchecksummed base only, a crash, hang or sanitizer report whose first
 * frame outside libc/sanitizers is inside libhdf5 is reported as a known
 * HDF5 fault and does not fail the test (SASNAV_FUZZ_STRICT=1: it does);
 * for files written by sasnav every such event is a failure.
 *
 * Environment: SASNAV_FUZZ_VARIANTS (per base, default 250),
 * SASNAV_FUZZ_SEED (default 1), SASNAV_FUZZ_NOFORK=1 (in-process, to debug),
 * SASNAV_FUZZ_STRICT=1 (HDF5 faults fail the test for every base). */
#include "sasnav/error.h"
#include "sasnav/io.h"
#include "testutil.h"

#include <ctype.h>
#include <errno.h>
#include <execinfo.h>
#include <hdf5.h>
#include <signal.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

/* Sanitizer settings, used only by -fsanitize builds (SASNAV_SANITIZE).
 * HDF5 1.10.8 itself leaks a metadata-cache entry when a checksum or a
 * decoding check fails while loading an object header (reproducible with
 * HDF5 calls alone: H5Fopen, H5Aexists_by_name, H5Fclose on such a file),
 * and then reports "infinite loop closing library" at exit. Those leaks,
 * allocated under H5C_protect, are suppressed; leaks of sasnav's own memory
 * or of HDF5 identifiers it forgets to close (types, spaces, property lists,
 * allocated outside the metadata cache) are still reported. Full unwinding
 * is needed because libhdf5 has no frame pointers. */
const char *__asan_default_options(void);
const char *__asan_default_options(void)
{
    /* A corrupt size makes HDF5 ask for terabytes: get NULL (which HDF5
     * handles) as in a normal build, instead of an ASan abort. */
    return "fast_unwind_on_malloc=0:allocator_may_return_null=1";
}
const char *__lsan_default_suppressions(void);
const char *__lsan_default_suppressions(void) { return "leak:H5C_protect\n"; }

#define CHILD_OK 0
#define CHILD_CONTRACT 10 /* the reader broke its contract (wrong code, bad object) */
#define CHILD_ACCEPTED 11 /* read succeeded with a valid object (not an error) */
#define TIMEOUT_S 20      /* per variant; ASan builds are slow, HDF5 reads take ms */

static uint64_t rng_state;
static uint64_t rng_next(void) /* splitmix64 */
{
    uint64_t z = (rng_state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}
static size_t rng_below(size_t n) { return n ? (size_t)(rng_next() % n) : 0; }

typedef struct {
    unsigned char *data;
    size_t size;
} blob;

static int blob_load(const char *path, blob *b)
{
    FILE *f = fopen(path, "rb");
    if (!f) return -1;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    rewind(f);
    b->data = malloc(n > 0 ? (size_t)n : 1);
    b->size = fread(b->data, 1, (size_t)n, f);
    fclose(f);
    return b->size == (size_t)n ? 0 : -1;
}

static int blob_save(const char *path, const blob *b)
{
    FILE *f = fopen(path, "wb");
    if (!f) return -1;
    size_t n = fwrite(b->data, 1, b->size, f);
    return (fclose(f) == 0 && n == b->size) ? 0 : -1;
}

enum { MUT_BITS, MUT_BYTES, MUT_HEAD, MUT_RUN, MUT_TRUNCATE, MUT_DELETE, MUT_MIXED, MUT_COUNT };
static const char *mutation_name[MUT_COUNT] = {"bit flips", "random bytes", "header bytes", "byte run",
                                               "truncation", "deleted range", "mixed"};

/* Applies mutation `kind` in place (size may shrink). */
static void mutate(blob *b, int kind)
{
    size_t n = b->size;
    switch (kind) {
    case MUT_BITS:
        for (int k = 1 + (int)rng_below(8); k > 0; k--) b->data[rng_below(n)] ^= (unsigned char)(1u << rng_below(8));
        break;
    case MUT_BYTES:
        for (int k = 1 + (int)rng_below(16); k > 0; k--) b->data[rng_below(n)] = (unsigned char)rng_next();
        break;
    case MUT_HEAD: /* superblock and root object header live in the first KB */
        for (int k = 1 + (int)rng_below(4); k > 0; k--)
            b->data[rng_below(n < 1024 ? n : 1024)] = (unsigned char)rng_next();
        break;
    case MUT_RUN: {
        size_t len = 1 + rng_below(64), at = rng_below(n);
        unsigned char v = rng_below(2) ? 0xFF : 0x00;
        for (size_t k = at; k < at + len && k < n; k++) b->data[k] = v;
        break;
    }
    case MUT_TRUNCATE:
        b->size = rng_below(n);
        break;
    case MUT_DELETE: {
        size_t at = rng_below(n), len = 1 + rng_below(256);
        if (at + len > n) len = n - at;
        memmove(b->data + at, b->data + at + len, n - at - len);
        b->size = n - len;
        break;
    }
    default:
        mutate(b, MUT_BITS);
        mutate(b, MUT_RUN);
        if (rng_below(2)) mutate(b, MUT_TRUNCATE);
        break;
    }
}

typedef enum { READ_RUN, READ_NAV, READ_IMAGE } reader_kind;

/* Reads `path` with one reader and checks the contract: CHILD_ACCEPTED,
 * CHILD_OK (clean rejection) or CHILD_CONTRACT. */
static int read_and_check(reader_kind kind, const char *path)
{
    sasnav_clear_error();
    int rc;
    int valid = 1;
    if (kind == READ_RUN) {
        sasnav_run *run = NULL;
        rc = sasnav_run_read(path, &run);
        if (rc == 0) valid = run && sasnav_run_check(run) == 0;
        else valid = run == NULL;
        sasnav_run_free(run);
    } else if (kind == READ_NAV) {
        int n = -1;
        sasnav_ping_pose *nav = NULL, *truth = NULL;
        rc = sasnav_nav_read(path, &n, &nav, &truth);
        if (rc == 0) valid = nav && n >= 1;
        else valid = !nav && !truth;
        free(nav);
        free(truth);
    } else {
        sasnav_grid grid;
        sasnav_cfloat *image = NULL;
        rc = sasnav_image_read(path, &grid, &image);
        if (rc == 0) valid = image && sasnav_grid_check(&grid) == 0;
        else valid = image == NULL;
        free(image);
    }
    ssize_t open_objects = H5Fget_obj_count(H5F_OBJ_ALL, H5F_OBJ_ALL);
    if (open_objects != 0) {
        fprintf(stderr, "  %s: %zd HDF5 objects left open (status %d)\n", path, open_objects, rc);
        return CHILD_CONTRACT;
    }
    if (rc != 0 && rc != SASNAV_ERR_FORMAT && rc != SASNAV_ERR_IO) {
        fprintf(stderr, "  %s: unexpected status %d (%s)\n", path, rc, sasnav_last_error());
        return CHILD_CONTRACT;
    }
    if (rc != 0 && sasnav_last_error()[0] == '\0') {
        fprintf(stderr, "  %s: error %d without a message\n", path, rc);
        return CHILD_CONTRACT;
    }
    if (!valid) {
        fprintf(stderr, "  %s: status %d but inconsistent outputs\n", path, rc);
        return CHILD_CONTRACT;
    }
    return rc == 0 ? CHILD_ACCEPTED : CHILD_OK;
}

static const char *child_log_path(void)
{
    static char path[512];
    snprintf(path, sizeof path, "%s/fuzz-child.log", test_tmpdir());
    return path;
}

static void print_child_log(void)
{
    FILE *f = fopen(child_log_path(), "r");
    if (!f) return;
    char line[512];
    int n = 0;
    while (fgets(line, sizeof line, f) && n++ < 40) fprintf(stderr, "    | %s", line);
    fclose(f);
}

/* In the child: a backtrace on a fatal signal or the timeout, to tell
 * faults inside HDF5 from ours (sanitizer builds print their own). */
static void fault_handler(int sig)
{
    void *frames[64];
    int n = backtrace(frames, 64);
    char msg[64];
    int len = snprintf(msg, sizeof msg, "fatal signal %d, backtrace:\n", sig);
    if (write(2, msg, (size_t)len) < 0) _exit(CHILD_CONTRACT);
    if (n > 2) backtrace_symbols_fd(frames + 2, n - 2, 2); /* skip handler, trampoline */
    signal(sig, SIG_DFL);
    raise(sig);
}

static void install_fault_handlers(void)
{
    void *warm[2];
    backtrace(warm, 2); /* loads the unwinder now, not in the handler */
    int sigs[] = {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGALRM};
    for (size_t k = 0; k < sizeof sigs / sizeof *sigs; k++) signal(sigs[k], fault_handler);
}

static int frame_in_runtime(const char *line)
{
    static const char *runtime[] = {"libsanitizer", "libasan", "libubsan", "liblsan", "libc.so",
                                    "sysdeps", "libgcc", "ld-linux", "linux-vdso"};
    for (size_t k = 0; k < sizeof runtime / sizeof *runtime; k++)
        if (strstr(line, runtime[k])) return 1;
    return 0;
}

/* 1 when the child's log holds at least one stack and every stack's first
 * frame outside libc and the sanitizers is in libhdf5. UBSan reports (our
 * code only is instrumented) and logs without stacks count as ours. */
static int fault_in_hdf5(void)
{
    FILE *f = fopen(child_log_path(), "r");
    if (!f) return 0;
    char line[1024];
    int stacks = 0, in_hdf5 = 0, in_stack = 0, decided = 0;
    while (fgets(line, sizeof line, f)) {
        if (strstr(line, "runtime error")) {
            fclose(f);
            return 0;
        }
        /* Sanitizer frames: "    #3 0x... in f file"; glibc backtrace_symbols:
         * "module(function+0x..)[0x...]". */
        const char *p = line + strspn(line, " \t");
        int frame = (p[0] == '#' && isdigit((unsigned char)p[1]) && strstr(p, " 0x")) || strstr(line, ")[0x");
        if (!frame) {
            in_stack = 0;
            continue;
        }
        if (!in_stack) {
            in_stack = 1;
            decided = 0;
            stacks++;
        }
        if (decided || frame_in_runtime(line)) continue;
        decided = 1;
        if (strstr(line, "libhdf5")) in_hdf5++;
    }
    fclose(f);
    return stacks > 0 && in_hdf5 == stacks;
}

/* Runs read_and_check in a child with a time limit. Returns the child's
 * code, or -signal when it was killed (SIGALRM: hang). */
static int run_isolated(reader_kind kind, const char *path, int nofork)
{
    if (nofork) return read_and_check(kind, path);
    fflush(stdout);
    fflush(stderr);
    pid_t pid = fork();
    if (pid < 0) {
        perror("fork");
        return -1000;
    }
    if (pid == 0) {
        /* HDF5 and the sanitizers write to stderr: keep it for failures. */
        if (!freopen(child_log_path(), "w", stderr)) _exit(CHILD_CONTRACT);
        install_fault_handlers();
        alarm(TIMEOUT_S);
        exit(read_and_check(kind, path)); /* exit: sanitizers' leak check runs */
    }
    int status;
    while (waitpid(pid, &status, 0) < 0)
        if (errno != EINTR) return -1001;
    return WIFSIGNALED(status) ? -WTERMSIG(status) : WEXITSTATUS(status);
}

typedef struct {
    const char *name;
    reader_kind kind;
    int tolerate_hdf5_faults; /* unchecksummed base: see the header comment */
    blob base;
} base_file;

static int fuzz_base(base_file *b, int variants, uint64_t seed0, int nofork, int strict)
{
    int accepted = 0, rejected = 0, failures = 0, hdf5_faults = 0;
    int by_kind[MUT_COUNT][2] = {{0}};
    char path[512];
    snprintf(path, sizeof path, "%s/fuzz-%s.h5", test_tmpdir(), b->name);
    for (int v = 0; v < variants; v++) {
        uint64_t seed = seed0 * 1000003u + (uint64_t)v;
        rng_state = seed;
        int kind = (int)rng_below(MUT_COUNT);
        blob m = {malloc(b->base.size), b->base.size};
        memcpy(m.data, b->base.data, b->base.size);
        mutate(&m, kind);
        CHECK(blob_save(path, &m) == 0, "cannot write %s", path);
        int r = run_isolated(b->kind, path, nofork);
        if (r == CHILD_ACCEPTED) {
            accepted++;
            by_kind[kind][0]++;
        } else if (r == CHILD_OK) {
            rejected++;
            by_kind[kind][1]++;
        } else {
            char keep[600];
            snprintf(keep, sizeof keep, "%s/fuzz-fail-%s-%d.h5", test_tmpdir(), b->name, v);
            blob_save(keep, &m);
            const char *what = r < 0 ? (r == -SIGALRM ? "hang, killed by signal" : "crash, signal")
                                     : "child exit";
            int known = !nofork && r != CHILD_CONTRACT && b->tolerate_hdf5_faults && !strict &&
                        fault_in_hdf5();
            if (known) {
                hdf5_faults++;
                printf("  known HDF5 fault (not counted): %s variant %d (seed %llu, %s): %s %d in "
                       "libhdf5; kept as %s\n",
                       b->name, v, (unsigned long long)seed, mutation_name[kind], what, r < 0 ? -r : r,
                       keep);
            } else {
                failures++;
                print_child_log();
                CHECK(0, "%s variant %d (seed %llu, %s): %s %d; kept as %s", b->name, v,
                      (unsigned long long)seed, mutation_name[kind], what, r < 0 ? -r : r, keep);
            }
        }
        free(m.data);
    }
    printf("%-12s %4d variants: %4d rejected cleanly, %4d accepted as valid, %d failures, "
           "%d known HDF5 faults\n",
           b->name, variants, rejected, accepted, failures, hdf5_faults);
    for (int k = 0; k < MUT_COUNT; k++)
        printf("    %-14s rejected %4d accepted %4d\n", mutation_name[k], by_kind[k][1], by_kind[k][0]);
    /* The mutations must actually damage files: most variants are rejected. */
    CHECK(rejected > (variants - hdf5_faults) / 2, "%s: only %d of %d variants rejected: mutations too weak?", b->name,
          rejected, variants);
    return failures;
}

/* --- base files ------------------------------------------------------------ */

static sasnav_run *small_run(void)
{
    sasnav_system sys;
    sasnav_system_default(&sys);
    sasnav_array array;
    sasnav_window win = {0.012, 8};
    sasnav_run *run = NULL;
    if (sasnav_array_uniform(&array, 2, 0.05, 0.05, 0.05) ||
        sasnav_run_alloc(&sys, &array, &win, 3, 1, &run))
        return NULL;
    rng_state = 42;
    for (int k = 0; k < 3 * 2 * 8; k++)
        run->raw[k] = (float)(rng_next() % 1000) - 500 + I * (float)(rng_next() % 100);
    for (int p = 0; p < 3; p++) {
        sasnav_pose a = {0.2 * p, 0.001 * p, 0.01 * p}, t = {0.2 * p - 0.1, 0.0, 0.0};
        run->nav[p].array = run->truth[p].array = a;
        run->nav[p].tx = run->truth[p].tx = t;
    }
    run->ping_spacing = 0.2;
    run->speed = 2;
    run->tx_lag = 0.1;
    run->range_of_interest = 10;
    return run;
}

static void put_attr(hid_t loc, const char *name, hid_t type, const void *value)
{
    hid_t s = H5Screate(H5S_SCALAR);
    hid_t a = H5Acreate2(loc, name, type, s, H5P_DEFAULT, H5P_DEFAULT);
    H5Awrite(a, type, value);
    H5Aclose(a);
    H5Sclose(s);
}

static void put_dataset(hid_t loc, const char *name, hid_t type, int rank, const hsize_t *dims,
                        const void *data)
{
    hid_t s = H5Screate_simple(rank, dims, NULL);
    hid_t d = H5Dcreate2(loc, name, type, s, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    H5Dwrite(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data);
    H5Dclose(d);
    H5Sclose(s);
}

/* The same run as HDF5's defaults write it: superblock v0, v1 object
 * headers, symbol-table groups, contiguous data, vlen strings, float64
 * complex members: nothing is checksummed. */
static int write_legacy_run(const char *path, const sasnav_run *run)
{
    hid_t f = H5Fcreate(path, H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    if (f < 0) return -1;
    /* Fixed-length string (as MATLAB writes it). A variable-length one (h5py)
     * lives in the global heap, whose parser in HDF5 1.10.8 loops forever on
     * a free-space object of size 0: a damaged unchecksummed file can hang
     * any reader of it; see docs/format.md. */
    hid_t str = H5Tcopy(H5T_C_S1);
    H5Tset_size(str, 11);
    const char *format = "sasnav-run";
    put_attr(f, "format", str, format);
    int version = 1;
    put_attr(f, "format_version", H5T_NATIVE_INT, &version);
    hid_t c64 = H5Tcreate(H5T_COMPOUND, 16);
    H5Tinsert(c64, "r", 0, H5T_NATIVE_DOUBLE);
    H5Tinsert(c64, "i", 8, H5T_NATIVE_DOUBLE);
    size_t n = (size_t)run->n_pings * run->array.n_rx * run->win.n_samples;
    double *wide = malloc(2 * n * sizeof *wide);
    for (size_t k = 0; k < n; k++) {
        wide[2 * k] = crealf(run->raw[k]);
        wide[2 * k + 1] = cimagf(run->raw[k]);
    }
    hsize_t d3[3] = {(hsize_t)run->n_pings, (hsize_t)run->array.n_rx, (hsize_t)run->win.n_samples};
    put_dataset(f, "raw", c64, 3, d3, wide);
    free(wide);
    hid_t g = H5Gcreate2(f, "system", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    const char *dn[] = {"sound_speed", "f0", "bandwidth", "sample_rate", "t0", "ping_spacing", "speed",
                        "tx_lag", "range_of_interest"};
    double dv[] = {run->sys.sound_speed, run->sys.f0, run->sys.bandwidth, run->sys.sample_rate, run->win.t0,
                   run->ping_spacing, run->speed, run->tx_lag, run->range_of_interest};
    for (int k = 0; k < 9; k++) put_attr(g, dn[k], H5T_NATIVE_DOUBLE, &dv[k]);
    int iv[3] = {(int)run->sys.taper, (int)run->sys.attenuation, run->sys.beam_pattern};
    put_attr(g, "taper", H5T_NATIVE_INT, &iv[0]);
    put_attr(g, "attenuation", H5T_NATIVE_INT, &iv[1]);
    put_attr(g, "beam_pattern", H5T_NATIVE_INT, &iv[2]);
    H5Gclose(g);
    g = H5Gcreate2(f, "array", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    hsize_t d1 = (hsize_t)run->array.n_rx;
    put_dataset(g, "rx_u", H5T_NATIVE_DOUBLE, 1, &d1, run->array.rx_u);
    put_attr(g, "rx_length", H5T_NATIVE_DOUBLE, &run->array.rx_length);
    put_attr(g, "tx_length", H5T_NATIVE_DOUBLE, &run->array.tx_length);
    put_attr(g, "rx_height", H5T_NATIVE_DOUBLE, &run->array.rx_height);
    put_attr(g, "tx_height", H5T_NATIVE_DOUBLE, &run->array.tx_height);
    H5Gclose(g);
    const char *groups[2] = {"nav", "truth"};
    const sasnav_ping_pose *poses[2] = {run->nav, run->truth};
    for (int k = 0; k < 2; k++) {
        g = H5Gcreate2(f, groups[k], H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
        hsize_t d2[2] = {(hsize_t)run->n_pings, 3};
        double buf[2][64 * 3];
        for (int p = 0; p < run->n_pings && p < 64; p++) {
            const sasnav_pose *q[2] = {&poses[k][p].tx, &poses[k][p].array};
            for (int w = 0; w < 2; w++) {
                buf[w][3 * p] = q[w]->x;
                buf[w][3 * p + 1] = q[w]->y;
                buf[w][3 * p + 2] = q[w]->theta;
            }
        }
        put_dataset(g, "tx", H5T_NATIVE_DOUBLE, 2, d2, buf[0]);
        put_dataset(g, "array", H5T_NATIVE_DOUBLE, 2, d2, buf[1]);
        H5Gclose(g);
    }
    H5Tclose(c64);
    H5Tclose(str);
    return H5Fclose(f) < 0 ? -1 : 0;
}

static int make_bases(base_file *bases)
{
    sasnav_run *run = small_run();
    CHECK(run != NULL, "small run: %s", sasnav_last_error());
    if (!run) return 0;
    char path[512];
    int n = 0;

    snprintf(path, sizeof path, "%s/base-run.h5", test_tmpdir());
    CHECK_OK(sasnav_run_write(path, run));
    bases[n++] = (base_file){"run", READ_RUN, 0, {0}};
    CHECK(blob_load(path, &bases[n - 1].base) == 0, "cannot load %s", path);

    snprintf(path, sizeof path, "%s/base-legacy.h5", test_tmpdir());
    CHECK(write_legacy_run(path, run) == 0, "cannot write %s", path);
    sasnav_run *back = NULL;
    CHECK_OK(sasnav_run_read(path, &back)); /* the undamaged base is valid */
    CHECK(back && memcmp(back->raw, run->raw, 48 * sizeof *run->raw) == 0, "legacy base reads wrong");
    sasnav_run_free(back);
    bases[n++] = (base_file){"legacy-run", READ_RUN, 1, {0}};
    CHECK(blob_load(path, &bases[n - 1].base) == 0, "cannot load %s", path);

    snprintf(path, sizeof path, "%s/base-nav.h5", test_tmpdir());
    CHECK_OK(sasnav_nav_write(path, run->n_pings, run->nav, run->truth));
    bases[n++] = (base_file){"nav", READ_NAV, 0, {0}};
    CHECK(blob_load(path, &bases[n - 1].base) == 0, "cannot load %s", path);

    sasnav_grid grid;
    sasnav_cfloat image[6 * 4];
    for (int k = 0; k < 24; k++) image[k] = k - 0.5f * I * k;
    CHECK_OK(sasnav_grid_make(-0.3, 0.3, 6, 9.5, 10.5, 4, &grid));
    snprintf(path, sizeof path, "%s/base-image.h5", test_tmpdir());
    CHECK_OK(sasnav_image_write(path, &grid, image));
    bases[n++] = (base_file){"image", READ_IMAGE, 0, {0}};
    CHECK(blob_load(path, &bases[n - 1].base) == 0, "cannot load %s", path);

    sasnav_run_free(run);
    return n;
}

int main(void)
{
    const char *env = getenv("SASNAV_FUZZ_VARIANTS");
    int variants = env ? atoi(env) : 250;
    env = getenv("SASNAV_FUZZ_SEED");
    uint64_t seed = env ? strtoull(env, NULL, 10) : 1;
    env = getenv("SASNAV_FUZZ_NOFORK");
    int nofork = env && env[0] == '1';
    env = getenv("SASNAV_FUZZ_STRICT");
    int strict = env && env[0] == '1';
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL); /* the test's own HDF5 calls */
    /* No HDF5 free lists: freed blocks go back to malloc, so a leak report
     * shows where the block was really allocated (not an earlier owner). */
    H5set_free_list_limits(0, 0, 0, 0, 0, 0);

    base_file bases[4];
    int n = make_bases(bases);
    for (int k = 0; k < n; k++)
        CHECK(run_isolated(bases[k].kind, "/nonexistent/sasnav-fuzz.h5", nofork) == CHILD_OK,
              "missing file not rejected cleanly");
    time_t start = time(NULL);
    for (int k = 0; k < n; k++) {
        /* The undamaged base is accepted. */
        char path[512];
        snprintf(path, sizeof path, "%s/fuzz-%s.h5", test_tmpdir(), bases[k].name);
        CHECK(blob_save(path, &bases[k].base) == 0 && run_isolated(bases[k].kind, path, nofork) == CHILD_ACCEPTED,
              "undamaged %s base not accepted", bases[k].name);
        fuzz_base(&bases[k], bases[k].kind == READ_RUN ? variants : variants / 2, seed + (uint64_t)k, nofork,
                  strict);
        free(bases[k].base.data);
    }
    printf("fuzzing took %ld s\n", (long)(time(NULL) - start));
    return test_summary("test_io_fuzz");
}
