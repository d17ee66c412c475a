/* Whole-file text reads, path joins and atomic text outputs (textfile.h). */
#include "io/textfile.h"

#include "sasnav/error.h"
#include "sasnav/io.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

int sasnav_text_open(sasnav_text_out *out, const char *path)
{
    out->f = NULL;
    out->tmp[0] = '\0';
    out->partial = -1;
    if (!path || !*path) return sasnav_set_error(SASNAV_ERR_ARG, "empty output path");
    int rc0 = sasnav_output_check(path);
    if (rc0) return rc0;
    int len = snprintf(out->tmp, sizeof out->tmp, "%s.tmp-XXXXXX", path);
    if (len < 0 || (size_t)len >= sizeof out->tmp || strlen(path) >= sizeof out->path)
        return sasnav_set_error(SASNAV_ERR_ARG, "%s: path too long", path);
    strcpy(out->path, path);
    sigset_t held;
    sasnav_partial_hold(&held);
    int fd = mkstemp(out->tmp);
    if (fd >= 0) out->partial = sasnav_partial_add(out->tmp);
    sasnav_partial_release(&held);
    if (fd < 0) {
        int e = errno;
        out->tmp[0] = '\0';
        return sasnav_set_error(SASNAV_ERR_IO, "%s: cannot create: %s", path, strerror(e));
    }
    (void)fchmod(fd, 0644);
    out->f = fdopen(fd, "w");
    if (!out->f) {
        close(fd);
        unlink(out->tmp);
        out->tmp[0] = '\0';
        return sasnav_set_error(SASNAV_ERR_IO, "%s: cannot open for writing", path);
    }
    return 0;
}

int sasnav_text_commit(sasnav_text_out *out)
{
    if (!out->f) return sasnav_set_error(SASNAV_ERR_ARG, "output not open");
    int bad = ferror(out->f);
    bad |= fflush(out->f) != 0;
    bad |= fclose(out->f) != 0;
    out->f = NULL;
    if (bad) {
        unlink(out->tmp);
        sasnav_partial_remove(out->partial);
        return sasnav_set_error(SASNAV_ERR_IO, "%s: write error", out->path);
    }
    if (rename(out->tmp, out->path) != 0) {
        int e = errno;
        unlink(out->tmp);
        sasnav_partial_remove(out->partial);
        return sasnav_set_error(SASNAV_ERR_IO, "%s: cannot rename into place: %s", out->path,
                                strerror(e));
    }
    sasnav_partial_remove(out->partial);
    return 0;
}

void sasnav_text_abort(sasnav_text_out *out)
{
    if (out->f) fclose(out->f);
    out->f = NULL;
    if (out->tmp[0]) unlink(out->tmp);
    sasnav_partial_remove(out->partial);
}

int sasnav_open_regular(const char *path)
{
    /* O_NONBLOCK: opening a FIFO without a writer returns at once (a
     * blocking open waits for ever, found by review); then refused */
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        sasnav_set_error(SASNAV_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
        return -1;
    }
    struct stat st;
    int flags = fcntl(fd, F_GETFL);
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode) || flags < 0 ||
        fcntl(fd, F_SETFL, flags & ~O_NONBLOCK) < 0) {
        close(fd);
        sasnav_set_error(SASNAV_ERR_IO, "%s: not a regular file", path);
        return -1;
    }
    return fd;
}

FILE *sasnav_fopen_regular(const char *path)
{
    int fd = sasnav_open_regular(path);
    if (fd < 0) return NULL;
    FILE *f = fdopen(fd, "rb");
    if (!f) {
        sasnav_set_error(SASNAV_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
        close(fd);
    }
    return f;
}

int sasnav_text_read(const char *path, long max_bytes, int bad_content, char **text, size_t *len)
{
    *text = NULL;
    if (len) *len = 0;
    FILE *f = sasnav_fopen_regular(path);
    if (!f) return SASNAV_ERR_IO;
    struct stat st;
    if (fstat(fileno(f), &st) != 0) {
        fclose(f);
        return sasnav_set_error(SASNAV_ERR_IO, "%s: not a regular file", path);
    }
    if (st.st_size > max_bytes) {
        fclose(f);
        return sasnav_set_error(bad_content, "%s: too large (%lld bytes, at most %ld)", path,
                                (long long)st.st_size, max_bytes);
    }
    char *buf = malloc((size_t)st.st_size + 1);
    if (!buf) {
        fclose(f);
        return sasnav_set_error(SASNAV_ERR_NOMEM, "%s: out of memory", path);
    }
    size_t n = fread(buf, 1, (size_t)st.st_size, f);
    int bad = ferror(f);
    fclose(f);
    if (bad) {
        free(buf);
        return sasnav_set_error(SASNAV_ERR_IO, "%s: read error", path);
    }
    buf[n] = '\0';
    if (memchr(buf, '\0', n)) {
        free(buf);
        return sasnav_set_error(bad_content, "%s: not a text file (NUL byte)", path);
    }
    *text = buf;
    if (len) *len = n;
    return SASNAV_OK;
}

int sasnav_path_join(char *out, size_t size, const char *dir, const char *name)
{
    int k = snprintf(out, size, "%s/%s", dir, name);
    if (k < 0 || (size_t)k >= size)
        return sasnav_set_error(SASNAV_ERR_ARG, "path too long: %s/%s", dir, name);
    return SASNAV_OK;
}
