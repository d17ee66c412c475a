/* Text outputs (configs, CSV tables, reports) written under a temporary name
 * "<path>.tmp-XXXXXX" in the target's directory and renamed onto the target
 * only when everything was written: a failure never leaves a half-written
 * file. Private to the library and the CLI. */
#ifndef SASNAV_TEXTFILE_H
#define SASNAV_TEXTFILE_H

#include <stdio.h>

typedef struct {
    FILE *f;         /* write here between open and commit */
    char tmp[4096];
    char path[4096];
} sasnav_text_out;

/* Creates the temporary file (mode 0644). SASNAV_ERR_IO / SASNAV_ERR_ARG
 * with a message on failure (nothing left behind). */
int sasnav_text_open(sasnav_text_out *out, const char *path);

/* Flushes, closes and renames onto the target; on any error removes the
 * temporary file and returns SASNAV_ERR_IO with a message. */
int sasnav_text_commit(sasnav_text_out *out);

/* Closes and removes the temporary file (after a failure of the caller). */
void sasnav_text_abort(sasnav_text_out *out);

#endif
