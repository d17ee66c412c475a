/* Text files of the I/O layer. Reading: a whole regular text file into
 * memory; paths joined with a length check. Writing: text outputs (configs, CSV tables, reports) written under a temporary name
 * "<path>.tmp-XXXXXX" in the target's directory and renamed onto the target
 * only when everything was written: a failure never leaves a half-written
 * file. Private to the library and the CLI. */
#ifndef SASNAV_TEXTFILE_H
#define SASNAV_TEXTFILE_H

#include <signal.h>
#include <stdio.h>

typedef struct {
    FILE *f;         /* write here between open and commit */
    char tmp[4096];
    char path[4096];
    int partial;     /* slot of tmp among the outputs in progress */
} sasnav_text_out;

/* Opens a regular file for reading: never blocks (a FIFO or a device
 * given as an input is refused, "not a regular file", not waited on).
 * NULL and SASNAV_ERR_IO with a message naming the path on failure. */
FILE *sasnav_fopen_regular(const char *path);
/* The same as a descriptor (-1 on failure). */
int sasnav_open_regular(const char *path);

/* Creates the temporary file (mode 0644). SASNAV_ERR_IO / SASNAV_ERR_ARG
 * with a message on failure (nothing left behind). */
int sasnav_text_open(sasnav_text_out *out, const char *path);

/* Flushes, closes and renames onto the target; on any error removes the
 * temporary file and returns SASNAV_ERR_IO with a message. */
int sasnav_text_commit(sasnav_text_out *out);

/* Closes and removes the temporary file (after a failure of the caller). */
void sasnav_text_abort(sasnav_text_out *out);

/* Outputs in progress (src/io/partial.c): a temporary file is registered
 * when created (the slot returned, -1 when none is free) and unregistered
 * when renamed or removed; sasnav_remove_partial_outputs (io.h) removes the
 * registered ones from a signal handler. */
int sasnav_partial_add(const char *tmp_path);
void sasnav_partial_remove(int slot);
/* Signals held between creating a temporary file and registering it (so a
 * handler never misses one): hold, create, add, release. */
void sasnav_partial_hold(sigset_t *old);
void sasnav_partial_release(const sigset_t *old);

/* Reads the whole regular file `path` (at most max_bytes bytes) into a
 * NUL-terminated buffer (*text, to free(); *len bytes, may be NULL).
 * SASNAV_ERR_IO (missing, unreadable, not a regular file), `bad_content`
 * (the caller's code, e.g. SASNAV_ERR_CONFIG, for a file over max_bytes or
 * holding a NUL byte) or SASNAV_ERR_NOMEM, with a message naming the file. */
int sasnav_text_read(const char *path, long max_bytes, int bad_content, char **text, size_t *len);

/* out = dir + "/" + name; SASNAV_ERR_ARG when it does not fit in size. */
int sasnav_path_join(char *out, size_t size, const char *dir, const char *name);

#endif
