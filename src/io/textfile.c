/* Atomic text outputs (textfile.h). */
#include "io/textfile.h"

#include "sasnav/error.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

int sasnav_text_open(sasnav_text_out *out, const char *path)
{
    out->f = NULL;
    out->tmp[0] = '\0';
    if (!path || !*path) return sasnav_set_error(SASNAV_ERR_ARG, "empty output path");
    int len = snprintf(out->tmp, sizeof out->tmp, "%s.tmp-XXXXXX", path);
    if (len < 0 || (size_t)len >= sizeof out->tmp || strlen(path) >= sizeof out->path)
        return sasnav_set_error(SASNAV_ERR_ARG, "%s: path too long", path);
    strcpy(out->path, path);
    int fd = mkstemp(out->tmp);
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
        return sasnav_set_error(SASNAV_ERR_IO, "%s: write error", out->path);
    }
    if (rename(out->tmp, out->path) != 0) {
        int e = errno;
        unlink(out->tmp);
        return sasnav_set_error(SASNAV_ERR_IO, "%s: cannot rename into place: %s", out->path,
                                strerror(e));
    }
    return 0;
}

void sasnav_text_abort(sasnav_text_out *out)
{
    if (out->f) fclose(out->f);
    out->f = NULL;
    if (out->tmp[0]) unlink(out->tmp);
}
