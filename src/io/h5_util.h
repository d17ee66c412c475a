/* Private helpers of the HDF5 layer (src/io): error reporting with the file
 * named, checked reads of attributes and datasets, and the write-to-a-temporary
 * -then-rename protocol. The layout itself is in docs/format.md.
 *
 * Every helper returns SASNAV_OK or an error code after recording a message
 * "<path>: <what>" with sasnav_set_error. Not thread-safe (serial HDF5). */
#ifndef SASNAV_IO_H5_UTIL_H
#define SASNAV_IO_H5_UTIL_H

#include <hdf5.h>
#include <stddef.h>

/* Written to the root attribute `created_by`. */
#define SASNAV_H5_CREATED_BY "sasnav 0.1.0"
#define SASNAV_H5_FORMAT_VERSION 1     /* written unless a run needs more */
#define SASNAV_H5_FORMAT_VERSION_MAX 2 /* read: 1 .. this (2: run files with /channels) */

/* Whole-file state of one read or write call. */
typedef struct {
    const char *path;   /* the file as named by the caller (messages) */
    char *tmp_path;     /* writers: the temporary file, NULL once renamed */
    int partial;        /* its slot among the outputs in progress */
    hid_t file;         /* open file or H5I_INVALID_HID */
    H5E_auto2_t saved_func; /* HDF5 automatic error printing, restored at the end */
    void *saved_data;
    int version;        /* readers: the file's format_version */
} h5_ctx;

/* Silences HDF5's error printing for the duration of the call. */
void h5_begin(h5_ctx *c, const char *path);
/* Closes the file if open, removes a leftover temporary file, restores
 * HDF5's error printing. Safe to call once after h5_begin on every path. */
void h5_end(h5_ctx *c);

/* Records "path: message" and returns status. */
int h5_fail(h5_ctx *c, int status, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
/* Same, appending the innermost HDF5 error description, then clears it. */
int h5_fail_lib(h5_ctx *c, int status, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
/* Re-labels the current last error (from a validation function) as a
 * format error "path: where: <message>"; NOMEM is passed through. */
int h5_reframe(h5_ctx *c, int status, const char *where);

/* --- reading ------------------------------------------------------------ */

/* Opens c->path read-only: SASNAV_ERR_IO if the file is missing, a directory
 * or unreadable, SASNAV_ERR_FORMAT if it is not (a valid) HDF5 file. Then
 * checks the root attributes `format` (one of the n accepted names) and
 * `format_version`. */
int h5_open_read(h5_ctx *c, const char *const *formats, int n_formats);

/* 1 if the object `name` (absolute path) exists, checking each component. */
int h5_exists(h5_ctx *c, const char *name);

/* 1 if object `obj` exists and has an attribute `name`. */
int h5_attr_exists(h5_ctx *c, const char *obj, const char *name);

/* Scalar attributes of object `obj` (absolute path). A double accepts any
 * integer or float type, an int any integer type. Missing, non-scalar or
 * wrong-class attributes are format errors. */
int h5_read_attr_double(h5_ctx *c, const char *obj, const char *name, double *value);
int h5_read_attr_int(h5_ctx *c, const char *obj, const char *name, int *value);
/* Fixed- or variable-length string; must fit in size - 1 bytes. */
int h5_read_attr_string(h5_ctx *c, const char *obj, const char *name, char *buf, size_t size);

/* Dataset kinds: real (float class, read as double) or complex (compound of
 * exactly two float members "r" and "i", read as float pairs). */
enum { H5_REAL = 0, H5_COMPLEX = 1 };

/* Opens dataset `name`, checks its kind and rank, returns its dims (each in
 * 1..INT_MAX), and checks that the file stores as much data as they need
 * (so that callers may allocate for them). */
int h5_open_dataset(h5_ctx *c, const char *name, int kind, int rank, hsize_t *dims, hid_t *dset);
/* Reads the whole dataset (opened by h5_open_dataset) into buf (double or
 * sasnav_cfloat). */
int h5_read_dataset(h5_ctx *c, hid_t dset, const char *name, int kind, void *buf);
/* Convenience: open, check dims equal `dims`, read, close. */
/* Reads rows first .. first + count - 1 (along the first dimension) of an
 * open dataset into buf. */
int h5_read_rows(h5_ctx *c, hid_t dset, const char *name, int kind, hsize_t first, hsize_t count,
                 void *buf);
int h5_read_dataset_dims(h5_ctx *c, const char *name, int kind, int rank, const hsize_t *dims,
                         void *buf);

/* --- writing ------------------------------------------------------------ */

/* Creates "<path>.tmp-XXXXXX" next to path and opens it as a new HDF5 file,
 * writing the root attributes (format, format_version, created_by). */
int h5_create_tmp(h5_ctx *c, const char *format);
/* The same with a given format_version (1 .. SASNAV_H5_FORMAT_VERSION_MAX). */
int h5_create_tmp_version(h5_ctx *c, const char *format, int version);
/* Closes the file, flushes it to disk and renames it onto c->path. */
int h5_commit(h5_ctx *c);

int h5_create_group(h5_ctx *c, const char *name);
int h5_write_attr_double(h5_ctx *c, const char *obj, const char *name, double value);
int h5_write_attr_int(h5_ctx *c, const char *obj, const char *name, int value);
int h5_write_attr_string(h5_ctx *c, const char *obj, const char *name, const char *value);
/* Writes a chunked dataset with Fletcher-32 checksums and a `units` string
 * attribute (if not NULL). Real data: float64 from double; complex: {r, i}
 * float32. chunk_hint: chunk shape, or NULL for the whole dataset (both
 * capped at 64 MiB per chunk). */
/* Creates dataset `name` (storage as h5_write_dataset) without data, for
 * block writes; *dset to be closed by the caller (H5Dclose). */
int h5_create_dataset(h5_ctx *c, const char *name, int kind, int rank, const hsize_t *dims,
                      const hsize_t *chunk_hint, const char *units, hid_t *dset);
/* Writes the block start[k] .. start[k] + count[k] - 1 of an open dataset. */
int h5_write_block(h5_ctx *c, hid_t dset, const char *name, int kind, int rank, const hsize_t *start,
                   const hsize_t *count, const void *data);
int h5_write_dataset(h5_ctx *c, const char *name, int kind, int rank, const hsize_t *dims,
                     const hsize_t *chunk_hint, const void *data, const char *units);

#endif
