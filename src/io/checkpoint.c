/* Checkpoints of long jobs (checkpoint.h; layout in docs/format.md,
 * "Checkpoints"). */
#define _GNU_SOURCE
#include "sasnav/checkpoint.h"
#include "core/clock.h"
#include "core/hash.h"
#include "sasnav/error.h"
#include "sasnav/version.h"

#include <errno.h>
#include <fcntl.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#define MAGIC "SASNAVCK"
#define FORMAT_VERSION 1u
#define MAX_JOB 65536
#define RECORD_SIZE ((uint32_t)sizeof(sasnav_pair_record))
#define SYNC_INTERVAL 1.0 /* s between fdatasync calls */

struct sasnav_checkpoint {
    int fd;
    int n_records;
    double last_sync;
    char path[4096];
};

/* The header of this build and job: magic, format version, record size,
 * version text length and text, job length and text, checksum of all
 * that. */
static unsigned char *make_header(const char *job, size_t *len)
{
    const char *ver = sasnav_version();
    uint32_t lv = (uint32_t)strlen(ver), lj = (uint32_t)strlen(job);
    size_t n = 8 + 4 + 4 + 4 + lv + 4 + lj + 8;
    unsigned char *h = malloc(n), *w = h;
    if (!h) return NULL;
    const uint32_t fv = FORMAT_VERSION, rs = RECORD_SIZE;
    memcpy(w, MAGIC, 8), w += 8;
    memcpy(w, &fv, 4), w += 4;
    memcpy(w, &rs, 4), w += 4;
    memcpy(w, &lv, 4), w += 4;
    memcpy(w, ver, lv), w += lv;
    memcpy(w, &lj, 4), w += 4;
    memcpy(w, job, lj), w += lj;
    uint64_t sum = sasnav_hash_bytes(SASNAV_HASH_INIT, h, (size_t)(w - h));
    memcpy(w, &sum, 8);
    *len = n;
    return h;
}

static int write_all(int fd, const void *buf, size_t n)
{
    const unsigned char *b = buf;
    while (n > 0) {
        ssize_t k = write(fd, b, n);
        if (k < 0 && errno == EINTR) continue;
        if (k <= 0) return -1;
        b += k;
        n -= (size_t)k;
    }
    return 0;
}

/* Reads the whole open file into *buf (*len bytes). */
static int read_all(int fd, const char *path, unsigned char **buf, size_t *len)
{
    struct stat st;
    if (fstat(fd, &st) || !S_ISREG(st.st_mode))
        return sasnav_set_error(SASNAV_ERR_IO, "checkpoint %s: not a regular file", path);
    size_t n = (size_t)st.st_size;
    /* The magic before the whole file: any file named by mistake (a run
     * of tens of GB) is refused without reading it into memory (found by
     * review). An empty or short file goes on to parse's message. */
    char magic[8];
    ssize_t got8 = n >= 8 ? pread(fd, magic, 8, 0) : 0;
    if (n >= 8 && got8 != 8)
        return sasnav_set_error(SASNAV_ERR_IO, "cannot read checkpoint %s: %s", path,
                                got8 < 0 ? strerror(errno) : "shorter than its size");
    if (n >= 8 && memcmp(magic, MAGIC, 8))
        return sasnav_set_error(SASNAV_ERR_FORMAT, "%s is not a sasnav checkpoint (give another "
                                "--checkpoint file, or remove it)", path);
    unsigned char *b = malloc(n + 1);
    if (!b) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory reading checkpoint %s", path);
    size_t got = 0;
    errno = 0;
    while (got < n) {
        ssize_t k = pread(fd, b + got, n - got, (off_t)got);
        if (k < 0 && errno == EINTR) continue;
        if (k <= 0) break;
        got += (size_t)k;
    }
    if (got != n) {
        int e = errno;
        free(b);
        return sasnav_set_error(SASNAV_ERR_IO, "cannot read checkpoint %s: %s", path,
                                e ? strerror(e) : "shorter than its size");
    }
    *buf = b;
    *len = n;
    return SASNAV_OK;
}

/* Checks the header of an existing checkpoint against ours and returns
 * the valid records. */
static int parse(const char *path, const unsigned char *b, size_t n, const unsigned char *ours,
                 size_t ours_len, sasnav_pair_record **records, int *n_records, size_t *end)
{
    if (n < 8 || memcmp(b, MAGIC, 8))
        return sasnav_set_error(SASNAV_ERR_FORMAT, "%s is not a sasnav checkpoint (give another "
                                "--checkpoint file, or remove it)", path);
    /* The version text and the job of the file, for the message. */
    uint32_t fv = 0, rs = 0, lv = 0, lj = 0;
    if (n >= 20) {
        memcpy(&fv, b + 8, 4);
        memcpy(&rs, b + 12, 4);
        memcpy(&lv, b + 16, 4);
    }
    if (n < 20 || fv != FORMAT_VERSION || lv > 256 || n < 20 + (size_t)lv + 4)
        return sasnav_set_error(SASNAV_ERR_FORMAT, "checkpoint %s: unknown format or truncated header", path);
    memcpy(&lj, b + 20 + lv, 4);
    size_t hlen = 20 + (size_t)lv + 4 + (size_t)lj + 8;
    if (lj > MAX_JOB || n < hlen)
        return sasnav_set_error(SASNAV_ERR_FORMAT, "checkpoint %s: truncated header", path);
    uint64_t sum;
    memcpy(&sum, b + hlen - 8, 8);
    if (sum != sasnav_hash_bytes(SASNAV_HASH_INIT, b, hlen - 8))
        return sasnav_set_error(SASNAV_ERR_FORMAT, "checkpoint %s: corrupt header", path);
    const char *ver = sasnav_version();
    if (lv != strlen(ver) || memcmp(b + 20, ver, lv) || rs != RECORD_SIZE)
        return sasnav_set_error(SASNAV_ERR_FORMAT,
                                "checkpoint %s was written by sasnav %.*s (record size %u), this is %s "
                                "(%u): remove it to start again",
                                path, (int)lv, (const char *)(b + 20), rs, ver, RECORD_SIZE);
    if (hlen != ours_len || memcmp(b, ours, hlen))
        return sasnav_set_error(SASNAV_ERR_FORMAT,
                                "checkpoint %s belongs to another job (other input or options): "
                                "remove it, or give another --checkpoint file", path);
    size_t rec = RECORD_SIZE + 8, k = (n - hlen) / rec, valid = 0;
    sasnav_pair_record *r = k > 0 ? malloc(k * sizeof *r) : NULL;
    if (k > 0 && !r) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory reading checkpoint %s", path);
    for (size_t j = 0; j < k; j++) {
        const unsigned char *p = b + hlen + j * rec;
        memcpy(&sum, p + RECORD_SIZE, 8);
        if (sum != sasnav_hash_bytes(SASNAV_HASH_INIT, p, RECORD_SIZE)) break; /* torn or corrupt */
        memcpy(&r[valid++], p, RECORD_SIZE);
    }
    if (valid == 0) {
        free(r);
        r = NULL;
    }
    *records = r;
    *n_records = (int)valid;
    *end = hlen + valid * rec;
    return SASNAV_OK;
}

int sasnav_checkpoint_open(const char *path, const char *job, sasnav_checkpoint **ck,
                           sasnav_pair_record **records, int *n_records)
{
    if (ck) *ck = NULL;
    if (records) *records = NULL;
    if (n_records) *n_records = 0;
    if (!path || !job || !ck || !records || !n_records)
        return sasnav_set_error(SASNAV_ERR_ARG, "checkpoint: NULL argument");
    if (strlen(job) > MAX_JOB) return sasnav_set_error(SASNAV_ERR_ARG, "checkpoint: job text too long");
    if (strlen(path) >= sizeof ((sasnav_checkpoint *)0)->path)
        return sasnav_set_error(SASNAV_ERR_ARG, "checkpoint: path too long");
    size_t hlen;
    unsigned char *header = make_header(job, &hlen);
    if (!header) return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    sasnav_checkpoint *c = calloc(1, sizeof *c);
    if (!c) {
        free(header);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "out of memory");
    }
    strcpy(c->path, path);
    int created = 0, rc = SASNAV_OK;
    int fd = open(path, O_RDWR | O_CLOEXEC);
    if (fd < 0 && errno == ENOENT) {
        fd = open(path, O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
        created = fd >= 0;
    }
    if (fd < 0) {
        rc = sasnav_set_error(SASNAV_ERR_IO, "cannot open checkpoint %s: %s", path, strerror(errno));
        goto fail;
    }
    if (flock(fd, LOCK_EX | LOCK_NB)) {
        rc = errno == EWOULDBLOCK
                 ? sasnav_set_error(SASNAV_ERR_IO, "checkpoint %s is in use by another process", path)
                 : sasnav_set_error(SASNAV_ERR_IO, "cannot lock checkpoint %s: %s", path, strerror(errno));
        goto fail;
    }
    /* An empty file: one this function created and was killed before it
     * wrote the header (nothing to lose): started again. */
    struct stat st;
    if (!created && fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && st.st_size == 0) created = 2;
    if (created) {
        if (write_all(fd, header, hlen) || fdatasync(fd)) {
            rc = sasnav_set_error(SASNAV_ERR_IO, "cannot write checkpoint %s: %s", path, strerror(errno));
            goto fail;
        }
    } else {
        unsigned char *b = NULL;
        size_t n = 0, end = 0;
        rc = read_all(fd, path, &b, &n);
        if (!rc) rc = parse(path, b, n, header, hlen, records, n_records, &end);
        free(b);
        if (rc) goto fail;
        if (end != n && ftruncate(fd, (off_t)end)) {
            rc = sasnav_set_error(SASNAV_ERR_IO, "cannot cut checkpoint %s: %s", path, strerror(errno));
            free(*records);
            *records = NULL;
            *n_records = 0;
            goto fail;
        }
    }
    if (lseek(fd, 0, SEEK_END) < 0) {
        rc = sasnav_set_error(SASNAV_ERR_IO, "cannot seek in checkpoint %s: %s", path, strerror(errno));
        free(*records);
        *records = NULL;
        *n_records = 0;
        goto fail;
    }
    free(header);
    c->fd = fd;
    c->n_records = *n_records;
    c->last_sync = sasnav_now_seconds();
    *ck = c;
    return SASNAV_OK;
fail:
    if (fd >= 0) {
        if (created == 1) unlink(path);
        else if (created == 2 && ftruncate(fd, 0)) { /* leave it empty as it was */
        }
        close(fd);
    }
    free(header);
    free(c);
    return rc;
}

int sasnav_checkpoint_append(sasnav_checkpoint *ck, const sasnav_pair_record *record)
{
    if (!ck || !record) return sasnav_set_error(SASNAV_ERR_ARG, "checkpoint: NULL argument");
    unsigned char buf[sizeof(sasnav_pair_record) + 8];
    memcpy(buf, record, RECORD_SIZE);
    uint64_t sum = sasnav_hash_bytes(SASNAV_HASH_INIT, buf, RECORD_SIZE);
    memcpy(buf + RECORD_SIZE, &sum, 8);
    off_t at = lseek(ck->fd, 0, SEEK_CUR);
    if (write_all(ck->fd, buf, sizeof buf)) {
        int e = errno;
        /* Keep the file a whole number of records. */
        if (at >= 0 && ftruncate(ck->fd, at) == 0) (void)lseek(ck->fd, at, SEEK_SET);
        return sasnav_set_error(SASNAV_ERR_IO, "cannot write checkpoint %s: %s", ck->path, strerror(e));
    }
    ck->n_records++;
    double now = sasnav_now_seconds();
    if (now - ck->last_sync >= SYNC_INTERVAL) {
        ck->last_sync = now;
        if (fdatasync(ck->fd))
            return sasnav_set_error(SASNAV_ERR_IO, "cannot sync checkpoint %s: %s", ck->path, strerror(errno));
    }
    return SASNAV_OK;
}

int sasnav_checkpoint_count(const sasnav_checkpoint *ck) { return ck ? ck->n_records : 0; }

int sasnav_checkpoint_close(sasnav_checkpoint *ck, int remove_file)
{
    if (!ck) return SASNAV_OK;
    int rc = SASNAV_OK;
    if (remove_file) {
        if (unlink(ck->path) && errno != ENOENT)
            rc = sasnav_set_error(SASNAV_ERR_IO, "cannot remove checkpoint %s: %s", ck->path, strerror(errno));
    } else if (fdatasync(ck->fd)) {
        rc = sasnav_set_error(SASNAV_ERR_IO, "cannot sync checkpoint %s: %s", ck->path, strerror(errno));
    }
    close(ck->fd); /* releases the lock */
    free(ck);
    return rc;
}
