/* Checkpoint files (checkpoint.h): records survive a reopen bit for bit; a
 * torn last record (a process killed in the middle of a write) or a
 * corrupted one is dropped with everything after it and the file cut
 * there; another job's, another layout's or a foreign file is refused and
 * left untouched; a second opener is refused while the first holds it; a
 * write that fails (file-size limit: a full disk) leaves whole records;
 * close with remove deletes the file. */
#include "sasnav/checkpoint.h"
#include "sasnav/error.h"
#include "testutil.h"

#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

static sasnav_pair_record make_record(int j)
{
    sasnav_pair_record r;
    memset(&r, 0, sizeof r);
    r.key = 0x9e3779b97f4a7c15ull * (uint64_t)(j + 1);
    r.p = j;
    r.q = j + 1;
    r.status = j % 2 ? SASNAV_ERR_NOT_CONVERGED : SASNAV_OK;
    r.result.error = (sasnav_pose){1e-3 * j, -2e-5 * j, 3e-4 / (j + 1)};
    r.result.eta = 0.1 + j;
    r.result.n_candidates = j % 4;
    r.result.margin = j == 2 ? INFINITY : 1.5;
    return r;
}

static long file_size(const char *path)
{
    struct stat st;
    return stat(path, &st) ? -1 : (long)st.st_size;
}

static int exists(const char *path) { return access(path, F_OK) == 0; }

static int equal_records(const sasnav_pair_record *a, int n)
{
    for (int j = 0; j < n; j++) {
        sasnav_pair_record r = make_record(j);
        if (memcmp(&a[j], &r, sizeof r)) return 0;
    }
    return 1;
}

/* Opens path for `job`, expecting `want` records equal to make_record's;
 * closes it (kept). */
static void reopen_expect(const char *path, const char *job, int want, const char *what)
{
    sasnav_checkpoint *ck = NULL;
    sasnav_pair_record *r = NULL;
    int n = -1;
    CHECK_OK(sasnav_checkpoint_open(path, job, &ck, &r, &n));
    CHECK(n == want && (n == 0 || equal_records(r, n)), "%s: %d records read back (want %d)", what, n, want);
    CHECK(sasnav_checkpoint_count(ck) == n, "%s: count %d", what, sasnav_checkpoint_count(ck));
    free(r);
    CHECK_OK(sasnav_checkpoint_close(ck, 0));
}

int main(void)
{
    char path[4096], foreign[4096], nodir[4096];
    snprintf(path, sizeof path, "%s/ck.bin", test_tmpdir());
    snprintf(foreign, sizeof foreign, "%s/foreign.bin", test_tmpdir());
    snprintf(nodir, sizeof nodir, "%s/no/such/dir/ck.bin", test_tmpdir());
    unlink(path);
    const long rec = (long)sizeof(sasnav_pair_record) + 8;
    const char *job = "sasnav test";

    /* New file: the header only; 4 records appended and read back. */
    sasnav_checkpoint *ck = NULL;
    sasnav_pair_record *r = NULL;
    int n = -1;
    CHECK_OK(sasnav_checkpoint_open(path, job, &ck, &r, &n));
    CHECK(ck && n == 0 && r == NULL, "new checkpoint: %d records", n);
    long header = file_size(path);
    CHECK(header > 16, "header of %ld bytes", header);
    for (int j = 0; j < 4 && ck; j++) {
        sasnav_pair_record x = make_record(j);
        CHECK_OK(sasnav_checkpoint_append(ck, &x));
    }
    /* While open: a second opener is refused (a second process resuming
     * the same job at the same time would append to it twice). */
    sasnav_checkpoint *ck2 = NULL;
    CHECK(sasnav_checkpoint_open(path, job, &ck2, &r, &n) == SASNAV_ERR_IO && !ck2 &&
              strstr(sasnav_last_error(), "in use"),
          "a checkpoint open twice: %s", sasnav_last_error());
    CHECK_OK(sasnav_checkpoint_close(ck, 0));
    CHECK(file_size(path) == header + 4 * rec, "size %ld, want %ld", file_size(path), header + 4 * rec);
    reopen_expect(path, job, 4, "reopened");

    /* A torn last record (killed during its write): 3 kept, file cut. */
    CHECK(truncate(path, header + 4 * rec - 5) == 0, "truncate");
    reopen_expect(path, job, 3, "torn record");
    CHECK(file_size(path) == header + 3 * rec, "torn record not cut: size %ld", file_size(path));

    /* Appending after the cut continues the record sequence. */
    CHECK_OK(sasnav_checkpoint_open(path, job, &ck, &r, &n));
    free(r);
    {
        sasnav_pair_record x = make_record(3);
        CHECK_OK(sasnav_checkpoint_append(ck, &x));
    }
    CHECK_OK(sasnav_checkpoint_close(ck, 0));
    reopen_expect(path, job, 4, "appended after the cut");

    /* One flipped bit in record 2: records 0 and 1 kept. */
    {
        FILE *f = fopen(path, "r+b");
        CHECK(f != NULL, "cannot open %s", path);
        if (f) {
            long at = header + 2 * rec + 17;
            fseek(f, at, SEEK_SET);
            int c = fgetc(f);
            fseek(f, at, SEEK_SET);
            fputc(c ^ 0x10, f);
            fclose(f);
        }
    }
    reopen_expect(path, job, 2, "corrupted record");

    /* Another job: refused, the file untouched. */
    long size = file_size(path);
    CHECK(sasnav_checkpoint_open(path, "sasnav other", &ck, &r, &n) == SASNAV_ERR_FORMAT && !ck &&
              strstr(sasnav_last_error(), "another job"),
          "another job's checkpoint: %s", sasnav_last_error());
    CHECK(file_size(path) == size, "a refused checkpoint was changed");

    /* A foreign file, an empty file, a corrupt header: refused. */
    {
        FILE *f = fopen(foreign, "wb");
        if (f) {
            fputs("x,y,z\n1,2,3\n", f);
            fclose(f);
        }
        CHECK(sasnav_checkpoint_open(foreign, job, &ck, &r, &n) == SASNAV_ERR_FORMAT &&
                  strstr(sasnav_last_error(), "not a sasnav checkpoint"),
              "a CSV file as checkpoint: %s", sasnav_last_error());
        /* An empty file (killed before the header): started again. */
        f = fopen(foreign, "wb");
        if (f) fclose(f);
        CHECK_OK(sasnav_checkpoint_open(foreign, job, &ck, &r, &n));
        CHECK(n == 0 && file_size(foreign) == header, "an empty checkpoint: %d records, size %ld", n,
              file_size(foreign));
        CHECK_OK(sasnav_checkpoint_close(ck, 0));
        /* The header of path with one byte of the job changed. */
        FILE *g = fopen(path, "rb");
        f = fopen(foreign, "wb");
        if (f && g) {
            char buf[4096];
            size_t k = fread(buf, 1, sizeof buf, g);
            if (k > 40) buf[header - 10] ^= 1;
            fwrite(buf, 1, k, f);
        }
        if (f) fclose(f);
        if (g) fclose(g);
        CHECK(sasnav_checkpoint_open(foreign, job, &ck, &r, &n) == SASNAV_ERR_FORMAT,
              "a corrupt header accepted");
    }

    /* A directory that does not exist: an I/O error, nothing created. */
    CHECK(sasnav_checkpoint_open(nodir, job, &ck, &r, &n) == SASNAV_ERR_IO && !ck,
          "missing directory: %s", sasnav_last_error());
    CHECK(sasnav_checkpoint_open(NULL, job, &ck, &r, &n) == SASNAV_ERR_ARG, "NULL path accepted");

    /* A write that fails (a file-size limit, as a full disk): error, and
     * the file holds whole records only. In a child: the limit is for the
     * process. */
    unlink(path);
    pid_t pid = fork();
    if (pid == 0) {
        signal(SIGXFSZ, SIG_IGN);
        sasnav_checkpoint *c = NULL;
        sasnav_pair_record *rr = NULL;
        int nn = 0;
        if (sasnav_checkpoint_open(path, job, &c, &rr, &nn)) _exit(3);
        struct rlimit lim = {(rlim_t)(file_size(path) + 2 * rec + rec / 2), RLIM_INFINITY};
        lim.rlim_max = lim.rlim_cur;
        if (setrlimit(RLIMIT_FSIZE, &lim)) _exit(4);
        int ok = 0, failed = 0;
        for (int j = 0; j < 4; j++) {
            sasnav_pair_record x = make_record(j);
            if (sasnav_checkpoint_append(c, &x)) failed++;
            else ok++;
        }
        sasnav_checkpoint_close(c, 0);
        _exit(ok == 2 && failed == 2 ? 0 : 5);
    }
    int st = 0;
    waitpid(pid, &st, 0);
    CHECK(WIFEXITED(st) && WEXITSTATUS(st) == 0, "file-size limit: child status %d", st);
    CHECK(file_size(path) == header + 2 * rec, "after failed writes: size %ld, want %ld", file_size(path),
          header + 2 * rec);
    reopen_expect(path, job, 2, "after failed writes");

    /* Close with remove: gone. */
    CHECK_OK(sasnav_checkpoint_open(path, job, &ck, &r, &n));
    free(r);
    CHECK_OK(sasnav_checkpoint_close(ck, 1));
    CHECK(!exists(path), "checkpoint not removed");
    CHECK_OK(sasnav_checkpoint_close(NULL, 1));
    unlink(foreign);
    return test_summary("test_checkpoint");
}
