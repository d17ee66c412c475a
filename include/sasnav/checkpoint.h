/* sasnav -- checkpoints of long jobs: the pair estimates finished so far,
 * kept in a file so that an interrupted navigation (`sasnav navigate`,
 * `sasnav validate`) resumes from them with the same result.
 *
 * A checkpoint is an append-only binary file (docs/format.md,
 * "Checkpoints"): a header naming the sasnav version, the record layout
 * and the job (a text from the caller: what the records depend on beyond
 * their keys), then one record per finished pair (sasnav_pair_record,
 * navigate.h) followed by its 64-bit checksum. Every record is flushed to
 * the operating system when appended, so a killed process (SIGINT,
 * SIGTERM, SIGKILL, out of memory) loses nothing it had finished; the file
 * is also synced to the disk at most once a second (a power cut may lose
 * the last second). A torn or corrupted record and everything after it
 * are dropped when the file is opened again. The records hold the
 * in-memory layout of this build: a checkpoint is for resuming on the
 * same installation, not an exchange format.
 *
 * While open, the file is locked (flock): a second process opening the
 * same checkpoint gets SASNAV_ERR_IO "in use by another process".
 *
 * Threads: one checkpoint per thread at a time; append from one thread at
 * a time (navigate's progress callback already is). Part of libsasnav
 * (file I/O), not of the core. */
#ifndef SASNAV_CHECKPOINT_H
#define SASNAV_CHECKPOINT_H

#include "sasnav/navigate.h"
#include "sasnav/refine.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct sasnav_checkpoint sasnav_checkpoint;

/* Opens the checkpoint `path` of the job described by `job` (any text,
 * at most 64 KiB; compared byte for byte). When the file exists it must be
 * a checkpoint of this sasnav version and record layout and of the same
 * job: its records up to the first torn or corrupt one are returned in
 * *records (*n_records entries; free() it; NULL when 0) and the file is
 * cut after them, so that appended records follow them. When it does not
 * exist, or is empty (a process killed before it wrote the header), it is
 * started with the header (created with mode 0644), *n_records = 0.
 * Errors: SASNAV_ERR_ARG (NULL arguments, job too long), SASNAV_ERR_IO
 * (cannot create, read, lock or write; in use by another process),
 * SASNAV_ERR_FORMAT (not a sasnav checkpoint, another version or layout,
 * another job: the message says which), SASNAV_ERR_NOMEM. On error
 * nothing is created and *ck is NULL. */
int sasnav_checkpoint_open(const char *path, const char *job, sasnav_checkpoint **ck,
                           sasnav_pair_record **records, int *n_records);

/* Appends one record (flushed; synced at most once a second).
 * SASNAV_ERR_IO with a message when it cannot be written (e.g. a full
 * disk); the file then keeps the records before it. */
int sasnav_checkpoint_append(sasnav_checkpoint *ck, const sasnav_pair_record *record);

/* Number of records in the file (read at open plus appended). */
int sasnav_checkpoint_count(const sasnav_checkpoint *ck);

/* Closes the checkpoint (safe on NULL); with `remove_file` = 1 also
 * deletes the file (the job is complete and its output written).
 * SASNAV_ERR_IO when the last records cannot be flushed or the file not
 * removed. */
int sasnav_checkpoint_close(sasnav_checkpoint *ck, int remove_file);

/* Refinement states (`sasnav refine --checkpoint`; refine.h): an HDF5
 * file of format "sasnav-refine-state" (docs/format.md, "Checkpoints"),
 * written to a temporary name and renamed (always whole), replaced after
 * every sweep. The reader checks the layout, the sasnav version that wrote
 * it (SASNAV_ERR_FORMAT for another) and finite values; whether the state
 * belongs to the run, navigation and options at hand is checked by
 * sasnav_refine (its digest). Free what was read with
 * sasnav_refine_state_free. Errors as io.h's readers and writers. */
int sasnav_refine_state_write(const char *path, const sasnav_refine_state *state);
int sasnav_refine_state_read(const char *path, sasnav_refine_state *state);

#ifdef __cplusplus
}
#endif
#endif
