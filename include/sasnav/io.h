/* sasnav -- HDF5 files (layout in docs/format.md).
 *
 * This layer is separate from the numerical core: only the CLI and tools
 * call it. Every writer writes to "<path>.tmp-XXXXXX" in the same directory
 * and renames it onto `path` only on success, so a failure never leaves a
 * half-written output file. Readers validate every dataset's type and shape
 * and every value (finite navigation, positive sizes) and return
 * SASNAV_ERR_IO (missing/unreadable file) or SASNAV_ERR_FORMAT (corrupt,
 * truncated, wrong shape, missing dataset) with a message naming the problem.
 * HDF5's own error printing is silenced (and restored on return).
 *
 * Threads: treat as not thread-safe: call these from one thread at a time,
 * never alongside other HDF5 use in the process. Each call swaps the
 * default HDF5 error handler (H5Eset_auto2, src/io/h5_util.c h5_begin /
 * h5_end). Only a thread-safe HDF5 build (H5_HAVE_THREADSAFE; Debian 12's
 * libhdf5 1.10.8 is one) serialises HDF5 calls itself; sasnav neither checks
 * for one nor is tested that way. sasnav_remove_partial_outputs is
 * async-signal-safe and may run from any thread (atomic slots).
 */
#ifndef SASNAV_IO_H
#define SASNAV_IO_H

#include "sasnav/image.h"
#include "sasnav/run.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Raw-data run: /raw, /nav/{tx,array}, /truth/{tx,array} (if known), system
 * attributes. */
int sasnav_run_write(const char *path, const sasnav_run *run);
int sasnav_run_read(const char *path, sasnav_run **run);

/* Opens a run file for streaming: everything is read and checked as by
 * sasnav_run_read, the samples one ping at a time (a corrupt or
 * non-finite sample is refused here, up front, with the same message), but
 * not kept: the pings are read again when used (sasnav_run_get_ping: one
 * HDF5 chunk each, checked again). Memory: the run's navigation, truth and
 * aiding (tens of bytes per ping) and one ping, not its samples. The file
 * stays open until sasnav_run_free. */
int sasnav_run_open(const char *path, sasnav_run **run);

/* Navigation only (e.g. the output of `sasnav navigate`): /nav/tx,
 * /nav/array [ping][3] and optionally /truth/tx, /truth/array. */
int sasnav_nav_write(const char *path, int n_pings, const sasnav_ping_pose *nav,
                     const sasnav_ping_pose *truth);
/* Reads /nav (allocated, n_pings returned); truth may be NULL (not read) and
 * *truth is set to NULL when the file has none. */
int sasnav_nav_read(const char *path, int *n_pings, sasnav_ping_pose **nav,
                    sasnav_ping_pose **truth);

/* sasnav_nav_write with the navigation's standard deviations as well:
 * /nav_sigma [ping][3] (sasnav_navigation.formal_sigma: along, across the
 * track (m), yaw (rad) of each PCA centroid relative to the first); sigma
 * may be NULL (none written). SASNAV_ERR_ARG also for a value that is not
 * finite or is negative. */
int sasnav_nav_write_sigma(const char *path, int n_pings, const sasnav_ping_pose *nav,
                           const sasnav_ping_pose *truth, const sasnav_pose *sigma);
/* Reads /nav_sigma of a navigation (or run) file: *sigma allocated with
 * *n_pings rows (those of /nav), or NULL when the file has none (then
 * *n_pings is still /nav's). SASNAV_ERR_IO / SASNAV_ERR_FORMAT as
 * sasnav_nav_read, also for a /nav_sigma whose shape is not /nav's or
 * whose values are not finite and >= 0; SASNAV_ERR_ARG, SASNAV_ERR_NOMEM. */
int sasnav_nav_read_sigma(const char *path, int *n_pings, sasnav_pose **sigma);

/* Complex image: /image [ny][nx] compound {r, i} float32, /x [nx], /y [ny]. */
int sasnav_image_write(const char *path, const sasnav_grid *grid, const sasnav_cfloat *image);

/* An image file written block by block (a survey's image is made in tiles
 * and need not be held whole): the same file as sasnav_image_write once
 * every pixel has been put (pixels never put are undefined). open creates
 * a temporary file beside `path` (tile_cols x tile_rows: the HDF5 chunk
 * shape, 0 = the whole grid, capped); put writes the block of columns
 * col0 .. col1 - 1 and rows row0 .. row1 - 1 (row-major, finite values);
 * finish renames the file into place and frees the writer; abort removes
 * it and frees. Not thread-safe (serial HDF5). */
typedef struct sasnav_image_writer sasnav_image_writer;
int sasnav_image_writer_open(const char *path, const sasnav_grid *grid, int tile_cols, int tile_rows,
                             sasnav_image_writer **writer);
int sasnav_image_writer_put(sasnav_image_writer *writer, int col0, int col1, int row0, int row1,
                            const sasnav_cfloat *block);
int sasnav_image_writer_finish(sasnav_image_writer *writer);
void sasnav_image_writer_abort(sasnav_image_writer *writer);

/* A run file written ping by ping (a long simulation need not be held
 * whole): open with the run's shape (sys, array, win, n_pings of
 * `header`; its samples and navigation are not used), put each ping's
 * samples (any order; get reads one back), then finish with the run's
 * header (navigation, truth, aiding, constants; raw may be NULL): the same
 * file as sasnav_run_write. finish and abort free the writer. */
typedef struct sasnav_run_writer sasnav_run_writer;
int sasnav_run_writer_open(const char *path, const sasnav_run *header, sasnav_run_writer **writer);
int sasnav_run_writer_put(sasnav_run_writer *writer, int p, const sasnav_cfloat *samples);
int sasnav_run_writer_get(sasnav_run_writer *writer, int p, sasnav_cfloat *samples);
int sasnav_run_writer_finish(sasnav_run_writer *writer, const sasnav_run *header);
void sasnav_run_writer_abort(sasnav_run_writer *writer);
/* Allocates *image (nx * ny values); free with free(). */
int sasnav_image_read(const char *path, sasnav_grid *grid, sasnav_cfloat **image);

/* Every file the I/O layer writes (HDF5, text, WAV) goes to a temporary
 * name next to its target ("<target>.tmp-XXXXXX") that is renamed onto the
 * target only when complete: a failure never leaves a half-written file and
 * keeps the previous one. This removes the temporary files of the writes in
 * progress; it is async-signal-safe, for a SIGINT / SIGTERM handler that
 * then ends the process (the sasnav tool installs one). */
void sasnav_remove_partial_outputs(void);

/* Whether `path` may be written that way: SASNAV_OK when it does not exist
 * or is a regular file; SASNAV_ERR_IO (message naming it) when it is a
 * device, a directory, a pipe or a socket, which the rename would replace
 * (e.g. -o /dev/null). Every writer calls it first. */
int sasnav_output_check(const char *path);

#ifdef __cplusplus
}
#endif
#endif
