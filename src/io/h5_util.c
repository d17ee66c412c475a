/* Private HDF5 helpers: checked attribute/dataset access, error messages
 * naming the file and the object, and atomic writes (temporary + rename). */
#include "io/h5_util.h"
#include "io/textfile.h"

#include "sasnav/error.h"
#include "sasnav/io.h"
#include "sasnav/model.h"

#include <errno.h>
#include <pthread.h>
#include <fcntl.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#define H5_VERSION_AT_LEAST(maj, min, rel)                                              \
    (H5_VERS_MAJOR > (maj) || (H5_VERS_MAJOR == (maj) && H5_VERS_MINOR > (min)) ||    \
     (H5_VERS_MAJOR == (maj) && H5_VERS_MINOR == (min) && H5_VERS_RELEASE >= (rel)))

/* H5Pset_file_locking exists from 1.10.7 and 1.12.1 on. */
#if (H5_VERS_MAJOR == 1 && H5_VERS_MINOR == 10 && H5_VERS_RELEASE >= 7) ||              \
    (H5_VERS_MAJOR == 1 && H5_VERS_MINOR == 12 && H5_VERS_RELEASE >= 1) ||              \
    (H5_VERS_MAJOR == 1 && H5_VERS_MINOR >= 13) || H5_VERS_MAJOR > 1
#define SASNAV_H5_HAVE_FILE_LOCKING 1
#endif

/* Largest chunk written (bytes); HDF5 allows 4 GiB, the chunk cache is
 * 1 MiB by default, whole-dataset reads bypass it either way. */
#define CHUNK_BYTES_MAX ((size_t)64 << 20)
/* Datasets up to this size (bytes) without a chunk request are stored in
 * their object header (compact layout, covered by its checksum); HDF5 caps
 * compact data at 64 KiB. */
#define COMPACT_BYTES_MAX ((size_t)16 << 10)
/* A compressed dataset (written by another tool) may expand at most this
 * much: bounds the memory a corrupt or hostile file can make us allocate. */
#define EXPANSION_MAX 1024.0

static void close_id(hid_t *id, herr_t (*closer)(hid_t))
{
    if (*id >= 0) closer(*id);
    *id = H5I_INVALID_HID;
}

/* --- errors ------------------------------------------------------------- */

/* HDF5 1.10.8 crashes in its exit handler (H5F__close_cb from
 * H5_term_library) after an H5Fclose that failed, e.g. on a full disk or a
 * file-size limit. Every file sasnav opens it also closes, so the handler
 * has nothing to do for us: it is switched off before the first HDF5 call
 * (H5dont_atexit fails harmlessly when another user of the library in the
 * process called HDF5 first). */
static pthread_once_t atexit_once = PTHREAD_ONCE_INIT;
static void no_atexit(void)
{
    (void)H5dont_atexit();
}

void h5_begin(h5_ctx *c, const char *path)
{
    pthread_once(&atexit_once, no_atexit);
    c->path = path ? path : "(null)";
    c->tmp_path = NULL;
    c->partial = -1;
    c->file = H5I_INVALID_HID;
    c->saved_func = NULL;
    c->saved_data = NULL;
    H5Eget_auto2(H5E_DEFAULT, &c->saved_func, &c->saved_data);
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
}

void h5_end(h5_ctx *c)
{
    close_id(&c->file, H5Fclose);
    if (c->tmp_path) {
        unlink(c->tmp_path);
        free(c->tmp_path);
        c->tmp_path = NULL;
    }
    sasnav_partial_remove(c->partial);
    c->partial = -1;
    H5Eclear2(H5E_DEFAULT);
    H5Eset_auto2(H5E_DEFAULT, c->saved_func, c->saved_data);
}

static int vfail(h5_ctx *c, int status, const char *detail, const char *fmt, va_list ap)
{
    char what[384];
    vsnprintf(what, sizeof what, fmt, ap);
    if (detail && detail[0])
        return sasnav_set_error(status, "%s: %s (HDF5: %s)", c->path, what, detail);
    return sasnav_set_error(status, "%s: %s", c->path, what);
}

int h5_fail(h5_ctx *c, int status, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int rc = vfail(c, status, NULL, fmt, ap);
    va_end(ap);
    return rc;
}

typedef struct {
    char desc[160];
    int locked; /* the file is locked by another process */
} h5_detail;

/* Keeps the innermost (first, walking upward) error of the HDF5 stack. */
static herr_t detail_walk(unsigned n, const H5E_error2_t *err, void *data)
{
    h5_detail *d = data;
    if (err->min_num == H5E_CANTLOCKFILE) d->locked = 1;
    if (n == 0 && err->desc) {
        /* a system error's description is a multi-line record ("file write
         * failed: time = ..., errno = 27, error message = 'File too large',
         * ..."): keep the system's message alone */
        const char *m = strstr(err->desc, "error message = '");
        if (m) {
            m += strlen("error message = '");
            size_t len = strcspn(m, "'");
            if (len >= sizeof d->desc) len = sizeof d->desc - 1;
            memcpy(d->desc, m, len);
            d->desc[len] = '\0';
        } else {
            snprintf(d->desc, sizeof d->desc, "%s", err->desc);
        }
        for (char *q = d->desc; *q; q++)
            if (*q == '\n' || *q == '\r') *q = ' ';
    }
    return 0;
}

static h5_detail lib_detail(void)
{
    h5_detail d = {"", 0};
    H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, detail_walk, &d);
    H5Eclear2(H5E_DEFAULT);
    return d;
}

int h5_fail_lib(h5_ctx *c, int status, const char *fmt, ...)
{
    h5_detail d = lib_detail();
    va_list ap;
    va_start(ap, fmt);
    int rc = vfail(c, status, d.desc, fmt, ap);
    va_end(ap);
    return rc;
}

int h5_reframe(h5_ctx *c, int status, const char *where)
{
    if (status == SASNAV_ERR_NOMEM) return status;
    char msg[512];
    snprintf(msg, sizeof msg, "%s", sasnav_last_error());
    return h5_fail(c, SASNAV_ERR_FORMAT, "%s: %s", where, msg);
}

/* --- opening ------------------------------------------------------------ */

static hid_t file_access_plist(int for_writing)
{
    hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
    if (fapl < 0) return fapl;
    /* Closing the file closes every object still open in it. */
    H5Pset_fclose_degree(fapl, H5F_CLOSE_STRONG);
#ifdef SASNAV_H5_HAVE_FILE_LOCKING
    /* Lock where the file system can, do not fail where it cannot (NFS). */
    H5Pset_file_locking(fapl, 1, 1);
#endif
    if (for_writing) {
        /* The 1.8 object formats: readable by HDF5 >= 1.8 (MATLAB, h5py,
         * netCDF-4 tools) and with checksummed superblock and object
         * headers, so that most metadata corruption is detected. */
        H5Pset_libver_bounds(fapl, H5F_LIBVER_V18, H5F_LIBVER_V18);
    } else {
        /* A small metadata cache. Its size counts the entries' size on
         * disk; a chunk-index node of a run's /raw takes ~5x that in
         * memory (17 kB for 3.4 kB), so the default 2 MB cache held ~6 MB
         * of index nodes once the open-time storage check had visited
         * them all (a 20,000-ping run; docs/survey.md). 256 kB still holds
         * the root and the path to any ping (~80 entries). */
        H5AC_cache_config_t mdc;
        memset(&mdc, 0, sizeof mdc);
        mdc.version = H5AC__CURR_CACHE_CONFIG_VERSION;
        if (H5Pget_mdc_config(fapl, &mdc) >= 0) {
            mdc.set_initial_size = 1;
            mdc.initial_size = 1 << 18;
            mdc.max_size = 1 << 18;
            mdc.min_size = 1 << 16;
            H5Pset_mdc_config(fapl, &mdc);
        }
    }
    return fapl;
}

static int is_hdf5(const char *path)
{
#if H5_VERSION_AT_LEAST(1, 12, 0)
    return H5Fis_accessible(path, H5P_DEFAULT) > 0;
#else
    return H5Fis_hdf5(path) > 0;
#endif
}

/* H5Lvisit: stops (1) at the first link that is neither hard nor soft,
 * its name into data (256 bytes). */
static herr_t link_outside(hid_t group, const char *name, const H5L_info_t *info, void *data)
{
    (void)group;
    if (info->type == H5L_TYPE_HARD || info->type == H5L_TYPE_SOFT) return 0;
    snprintf((char *)data, 256, "%s", name);
    return 1;
}

int h5_open_read(h5_ctx *c, const char *const *formats, int n_formats)
{
    struct stat st;
    if (stat(c->path, &st) != 0) return h5_fail(c, SASNAV_ERR_IO, "cannot open: %s", strerror(errno));
    if (S_ISDIR(st.st_mode)) return h5_fail(c, SASNAV_ERR_IO, "cannot open: is a directory");
    if (!S_ISREG(st.st_mode)) return h5_fail(c, SASNAV_ERR_IO, "cannot open: not a regular file");
    int fd = open(c->path, O_RDONLY | O_CLOEXEC);
    if (fd < 0) return h5_fail(c, SASNAV_ERR_IO, "cannot open: %s", strerror(errno));
    close(fd);
    if (!is_hdf5(c->path)) {
        H5Eclear2(H5E_DEFAULT);
        return h5_fail(c, SASNAV_ERR_FORMAT, "not an HDF5 file");
    }
    hid_t fapl = file_access_plist(0);
    if (fapl < 0) return h5_fail_lib(c, SASNAV_ERR_INTERNAL, "cannot create a file access list");
    c->file = H5Fopen(c->path, H5F_ACC_RDONLY, fapl);
    h5_detail d = lib_detail(); /* before the next HDF5 call clears it */
    H5Pclose(fapl);
    if (c->file < 0) {
        if (d.locked)
            return h5_fail(c, SASNAV_ERR_IO, "file is locked by another process (HDF5: %s)", d.desc);
        return h5_fail(c, SASNAV_ERR_FORMAT, "corrupt or truncated HDF5 file (HDF5: %s)", d.desc);
    }

    char format[64];
    int rc = h5_read_attr_string(c, "/", "format", format, sizeof format);
    if (rc) return rc;
    int known = 0;
    for (int k = 0; k < n_formats; k++)
        if (strcmp(format, formats[k]) == 0) known = 1;
    if (!known)
        return h5_fail(c, SASNAV_ERR_FORMAT, "root attribute 'format' is \"%s\", expected \"%s\"",
                       format, formats[0]);
    /* Links out of the file (external, user-defined) are refused: reading
     * through one opens another file, or blocks for ever on a FIFO (found
     * by review). Hard and soft links stay within this file. */
    char outside[256] = "";
    herr_t visited = H5Lvisit(c->file, H5_INDEX_NAME, H5_ITER_NATIVE, link_outside, outside);
    if (visited > 0)
        return h5_fail(c, SASNAV_ERR_FORMAT, "/%s is a link out of the file (external links are not supported)",
                       outside);
    if (visited < 0) return h5_fail_lib(c, SASNAV_ERR_FORMAT, "corrupt HDF5 file: its links cannot be listed");
    int version;
    rc = h5_read_attr_int(c, "/", "format_version", &version);
    if (rc) return rc;
    if (version < 1 || version > SASNAV_H5_FORMAT_VERSION_MAX)
        return h5_fail(c, SASNAV_ERR_FORMAT, "format_version %d is not supported (this library reads 1 to %d)",
                       version, SASNAV_H5_FORMAT_VERSION_MAX);
    c->version = version;
    return SASNAV_OK;
}

int h5_exists(h5_ctx *c, const char *name)
{
    char buf[256];
    size_t n = strlen(name);
    if (n == 0 || n >= sizeof buf || name[0] != '/') return 0;
    if (n == 1) return 1; /* the root group */
    memcpy(buf, name, n + 1);
    for (size_t k = 1; k <= n; k++) {
        if (buf[k] != '/' && buf[k] != '\0') continue;
        char saved = buf[k];
        buf[k] = '\0';
        htri_t e = H5Lexists(c->file, buf, H5P_DEFAULT);
        if (e > 0) e = H5Oexists_by_name(c->file, buf, H5P_DEFAULT);
        buf[k] = saved;
        if (e <= 0) {
            H5Eclear2(H5E_DEFAULT);
            return 0;
        }
    }
    return 1;
}

/* --- attributes --------------------------------------------------------- */

static const char *class_name(H5T_class_t cls)
{
    switch (cls) {
    case H5T_INTEGER: return "integer";
    case H5T_FLOAT: return "float";
    case H5T_STRING: return "string";
    case H5T_COMPOUND: return "compound";
    case H5T_ARRAY: return "array";
    case H5T_ENUM: return "enum";
    case H5T_VLEN: return "variable-length";
    default: return "other";
    }
}

int h5_attr_exists(h5_ctx *c, const char *obj, const char *name)
{
    if (!h5_exists(c, obj)) return 0;
    htri_t e = H5Aexists_by_name(c->file, obj, name, H5P_DEFAULT);
    H5Eclear2(H5E_DEFAULT);
    return e > 0;
}

/* Opens a single-valued attribute and returns it with its type. */
static int attr_open(h5_ctx *c, const char *obj, const char *name, hid_t *attr, hid_t *type)
{
    *attr = *type = H5I_INVALID_HID;
    if (!h5_exists(c, obj)) return h5_fail(c, SASNAV_ERR_FORMAT, "missing group %s", obj);
    htri_t e = H5Aexists_by_name(c->file, obj, name, H5P_DEFAULT);
    if (e < 0) return h5_fail_lib(c, SASNAV_ERR_FORMAT, "cannot look up attribute '%s' of %s", name, obj);
    if (e == 0) return h5_fail(c, SASNAV_ERR_FORMAT, "missing attribute '%s' of %s", name, obj);
    *attr = H5Aopen_by_name(c->file, obj, name, H5P_DEFAULT, H5P_DEFAULT);
    if (*attr < 0) return h5_fail_lib(c, SASNAV_ERR_FORMAT, "cannot open attribute '%s' of %s", name, obj);
    hid_t space = H5Aget_space(*attr);
    H5S_class_t sc = space >= 0 ? H5Sget_simple_extent_type(space) : H5S_NO_CLASS;
    hssize_t np = space >= 0 ? H5Sget_simple_extent_npoints(space) : -1;
    close_id(&space, H5Sclose);
    if (!(sc == H5S_SCALAR || (sc == H5S_SIMPLE && np == 1))) {
        close_id(attr, H5Aclose);
        return h5_fail(c, SASNAV_ERR_FORMAT, "attribute '%s' of %s is not a single value", name, obj);
    }
    *type = H5Aget_type(*attr);
    if (*type < 0) {
        int rc = h5_fail_lib(c, SASNAV_ERR_FORMAT, "attribute '%s' of %s has no readable type", name, obj);
        close_id(attr, H5Aclose);
        return rc;
    }
    return SASNAV_OK;
}

/* Reads a numeric attribute converted to `memtype` after checking its class. */
static int attr_read_number(h5_ctx *c, const char *obj, const char *name, hid_t memtype,
                            int allow_float, void *value)
{
    hid_t attr, type;
    int rc = attr_open(c, obj, name, &attr, &type);
    if (rc) return rc;
    H5T_class_t cls = H5Tget_class(type);
    if (!(cls == H5T_INTEGER || (allow_float && cls == H5T_FLOAT))) {
        rc = h5_fail(c, SASNAV_ERR_FORMAT, "attribute '%s' of %s is a %s, expected %s", name, obj,
                     class_name(cls), allow_float ? "number" : "integer");
    } else if (H5Aread(attr, memtype, value) < 0) {
        rc = h5_fail_lib(c, SASNAV_ERR_FORMAT, "cannot read attribute '%s' of %s", name, obj);
    }
    close_id(&type, H5Tclose);
    close_id(&attr, H5Aclose);
    return rc;
}

int h5_read_attr_double(h5_ctx *c, const char *obj, const char *name, double *value)
{
    int rc = attr_read_number(c, obj, name, H5T_NATIVE_DOUBLE, 1, value);
    if (rc) return rc;
    if (!isfinite(*value))
        return h5_fail(c, SASNAV_ERR_FORMAT, "attribute '%s' of %s is not finite", name, obj);
    return SASNAV_OK;
}

int h5_read_attr_int(h5_ctx *c, const char *obj, const char *name, int *value)
{
    return attr_read_number(c, obj, name, H5T_NATIVE_INT, 0, value);
}

int h5_read_attr_string(h5_ctx *c, const char *obj, const char *name, char *buf, size_t size)
{
    hid_t attr, type, mem = H5I_INVALID_HID;
    int rc = attr_open(c, obj, name, &attr, &type);
    if (rc) return rc;
    memset(buf, 0, size);
    if (H5Tget_class(type) != H5T_STRING) {
        rc = h5_fail(c, SASNAV_ERR_FORMAT, "attribute '%s' of %s is a %s, expected a string", name, obj,
                     class_name(H5Tget_class(type)));
        goto done;
    }
    mem = H5Tcopy(H5T_C_S1);
    H5Tset_cset(mem, H5Tget_cset(type)); /* HDF5 does not convert character sets */
    if (H5Tis_variable_str(type) > 0) {
        char *s = NULL;
        H5Tset_size(mem, H5T_VARIABLE);
        if (H5Aread(attr, mem, &s) < 0 || !s) {
            rc = h5_fail_lib(c, SASNAV_ERR_FORMAT, "cannot read attribute '%s' of %s", name, obj);
        } else if (strlen(s) >= size) {
            rc = h5_fail(c, SASNAV_ERR_FORMAT, "attribute '%s' of %s is too long", name, obj);
        } else {
            memcpy(buf, s, strlen(s) + 1);
        }
        if (s) H5free_memory(s);
    } else {
        size_t n = H5Tget_size(type);
        if (n == 0 || n >= size) {
            rc = h5_fail(c, SASNAV_ERR_FORMAT, "attribute '%s' of %s is too long", name, obj);
            goto done;
        }
        H5Tset_size(mem, n + 1);
        H5Tset_strpad(mem, H5T_STR_NULLTERM);
        if (H5Aread(attr, mem, buf) < 0)
            rc = h5_fail_lib(c, SASNAV_ERR_FORMAT, "cannot read attribute '%s' of %s", name, obj);
        buf[size - 1] = '\0';
    }
done:
    close_id(&mem, H5Tclose);
    close_id(&type, H5Tclose);
    close_id(&attr, H5Aclose);
    return rc;
}

/* --- datasets ----------------------------------------------------------- */

/* Memory (native) or file (little-endian) type of a kind of dataset. */
static hid_t kind_type(int kind, int file)
{
    if (kind == H5_REAL) return H5Tcopy(file ? H5T_IEEE_F64LE : H5T_NATIVE_DOUBLE);
    hid_t member = file ? H5T_IEEE_F32LE : H5T_NATIVE_FLOAT;
    hid_t t = H5Tcreate(H5T_COMPOUND, sizeof(sasnav_cfloat));
    if (t < 0) return t;
    if (H5Tinsert(t, "r", 0, member) < 0 || H5Tinsert(t, "i", sizeof(float), member) < 0) {
        H5Tclose(t);
        return H5I_INVALID_HID;
    }
    return t;
}

static int type_check(h5_ctx *c, const char *name, int kind, hid_t type)
{
    H5T_class_t cls = H5Tget_class(type);
    if (kind == H5_REAL) {
        if (cls != H5T_FLOAT)
            return h5_fail(c, SASNAV_ERR_FORMAT, "%s is a %s dataset, expected float", name,
                           class_name(cls));
        return SASNAV_OK;
    }
    if (cls != H5T_COMPOUND)
        return h5_fail(c, SASNAV_ERR_FORMAT, "%s is a %s dataset, expected a compound {r, i} (complex)",
                       name, class_name(cls));
    int nm = H5Tget_nmembers(type);
    int ir = H5Tget_member_index(type, "r");
    int ii = H5Tget_member_index(type, "i");
    H5Eclear2(H5E_DEFAULT);
    if (nm != 2 || ir < 0 || ii < 0 || H5Tget_member_class(type, (unsigned)ir) != H5T_FLOAT ||
        H5Tget_member_class(type, (unsigned)ii) != H5T_FLOAT)
        return h5_fail(c, SASNAV_ERR_FORMAT,
                       "%s must be a compound of exactly two float members \"r\" and \"i\"", name);
    return SASNAV_OK;
}

/* Checks the storage of a dataset: no external files or virtual layout, and
 * as many bytes stored as its shape needs (allowing for compression). */
static int storage_check(h5_ctx *c, hid_t dset, const char *name)
{
    int rc = SASNAV_OK;
    hid_t dcpl = H5Dget_create_plist(dset);
    hid_t type = H5Dget_type(dset);
    hid_t space = H5Dget_space(dset);
    if (dcpl < 0 || type < 0 || space < 0) {
        rc = h5_fail_lib(c, SASNAV_ERR_FORMAT, "cannot inspect dataset %s", name);
        goto done;
    }
    H5D_layout_t layout = H5Pget_layout(dcpl);
    if (layout != H5D_CONTIGUOUS && layout != H5D_CHUNKED && layout != H5D_COMPACT) {
        rc = h5_fail(c, SASNAV_ERR_FORMAT, "%s has an unsupported storage layout", name);
        goto done;
    }
    if (H5Pget_external_count(dcpl) != 0) {
        rc = h5_fail(c, SASNAV_ERR_FORMAT, "%s refers to external files (not supported)", name);
        goto done;
    }
    int compressed = 0, nf = H5Pget_nfilters(dcpl);
    for (int k = 0; k < nf; k++) {
        unsigned flags = 0, config = 0;
        size_t ncd = 0;
        char fname[64];
        H5Z_filter_t f = H5Pget_filter2(dcpl, (unsigned)k, &flags, &ncd, NULL, sizeof fname, fname, &config);
        if (f != H5Z_FILTER_FLETCHER32 && f != H5Z_FILTER_SHUFFLE) compressed = 1;
    }
    double expected = (double)H5Sget_simple_extent_npoints(space) * (double)H5Tget_size(type);
    double stored = (double)H5Dget_storage_size(dset);
    if (stored <= 0 || (!compressed && stored < expected) || (compressed && expected > EXPANSION_MAX * stored)) {
        rc = h5_fail(c, SASNAV_ERR_FORMAT,
                     "%s: file stores %.0f bytes for %.0f bytes of data (truncated or incomplete)", name,
                     stored, expected);
        goto done;
    }
#if H5_VERSION_AT_LEAST(1, 10, 5) /* H5Dget_num_chunks */
    if (layout == H5D_CHUNKED) {
        /* Every chunk written: a compressed dataset of which a writer
         * stored only some chunks passes the size test above, and its
         * missing chunks would read as the fill value (found by review).
         * Where the count cannot be had, the test is skipped, not the
         * file refused. */
        int rank = H5Sget_simple_extent_ndims(space);
        hsize_t dims[H5S_MAX_RANK], chunk[H5S_MAX_RANK], have = 0;
        double need = 1;
        if (rank >= 1 && rank <= H5S_MAX_RANK && H5Sget_simple_extent_dims(space, dims, NULL) >= 0 &&
            H5Pget_chunk(dcpl, rank, chunk) == rank && H5Dget_num_chunks(dset, space, &have) >= 0) {
            for (int k = 0; k < rank; k++) need *= chunk[k] > 0 ? ceil((double)dims[k] / (double)chunk[k]) : 0;
            if ((double)have < need)
                rc = h5_fail(c, SASNAV_ERR_FORMAT,
                             "%s: %.0f of its %.0f chunks written (truncated or incomplete)", name,
                             (double)have, need);
        }
    }
#endif
done:
    H5Eclear2(H5E_DEFAULT);
    close_id(&space, H5Sclose);
    close_id(&type, H5Tclose);
    close_id(&dcpl, H5Pclose);
    return rc;
}

int h5_open_dataset(h5_ctx *c, const char *name, int kind, int rank, hsize_t *dims, hid_t *dset)
{
    *dset = H5I_INVALID_HID;
    if (!h5_exists(c, name)) return h5_fail(c, SASNAV_ERR_FORMAT, "missing dataset %s", name);
    hid_t d = H5Dopen2(c->file, name, H5P_DEFAULT);
    if (d < 0) return h5_fail_lib(c, SASNAV_ERR_FORMAT, "%s is not a readable dataset", name);
    hid_t type = H5Dget_type(d);
    int rc = type < 0 ? h5_fail_lib(c, SASNAV_ERR_FORMAT, "%s has no readable type", name)
                      : type_check(c, name, kind, type);
    close_id(&type, H5Tclose);
    if (rc) {
        H5Dclose(d);
        return rc;
    }
    hid_t space = H5Dget_space(d);
    if (space < 0 || H5Sget_simple_extent_type(space) != H5S_SIMPLE) {
        rc = h5_fail_lib(c, SASNAV_ERR_FORMAT, "%s is not a simple array", name);
    } else {
        int nd = H5Sget_simple_extent_ndims(space);
        if (nd != rank) {
            rc = h5_fail(c, SASNAV_ERR_FORMAT, "%s has rank %d, expected %d", name, nd, rank);
        } else if (H5Sget_simple_extent_dims(space, dims, NULL) < 0) {
            rc = h5_fail_lib(c, SASNAV_ERR_FORMAT, "cannot read the shape of %s", name);
        } else {
            for (int k = 0; k < rank && !rc; k++)
                if (dims[k] < 1 || dims[k] > INT32_MAX)
                    rc = h5_fail(c, SASNAV_ERR_FORMAT, "%s has dimension %d of size %llu", name, k,
                                 (unsigned long long)dims[k]);
        }
    }
    close_id(&space, H5Sclose);
    /* Before anyone allocates memory for the shape it claims. */
    if (!rc) rc = storage_check(c, d, name);
    if (rc) {
        H5Dclose(d);
        return rc;
    }
    *dset = d;
    return SASNAV_OK;
}

int h5_read_dataset(h5_ctx *c, hid_t dset, const char *name, int kind, void *buf)
{
    int rc = SASNAV_OK;
    hid_t mem = kind_type(kind, 0);
    if (mem < 0) return h5_fail_lib(c, SASNAV_ERR_INTERNAL, "cannot build the memory type of %s", name);
    if (H5Dread(dset, mem, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) < 0)
        rc = h5_fail_lib(c, SASNAV_ERR_FORMAT, "cannot read %s (corrupt data)", name);
    H5Tclose(mem);
    return rc;
}

int h5_read_rows(h5_ctx *c, hid_t dset, const char *name, int kind, hsize_t first, hsize_t count,
                 void *buf)
{
    int rc = SASNAV_OK;
    hsize_t dims[8], start[8] = {0}, n[8];
    hid_t mem = kind_type(kind, 0), fspace = H5Dget_space(dset), mspace = H5I_INVALID_HID;
    int rank = fspace >= 0 ? H5Sget_simple_extent_ndims(fspace) : -1;
    if (mem < 0 || fspace < 0 || rank < 1 || rank > 8 ||
        H5Sget_simple_extent_dims(fspace, dims, NULL) < 0)
        rc = h5_fail_lib(c, SASNAV_ERR_FORMAT, "cannot read the shape of %s", name);
    if (!rc && first + count > dims[0])
        rc = h5_fail(c, SASNAV_ERR_FORMAT, "%s has %llu rows, rows %llu..%llu asked for", name,
                     (unsigned long long)dims[0], (unsigned long long)first,
                     (unsigned long long)(first + count - 1));
    if (!rc) {
        for (int k = 0; k < rank; k++) n[k] = dims[k];
        start[0] = first;
        n[0] = count;
        mspace = H5Screate_simple(rank, n, NULL);
        if (mspace < 0 || H5Sselect_hyperslab(fspace, H5S_SELECT_SET, start, NULL, n, NULL) < 0)
            rc = h5_fail_lib(c, SASNAV_ERR_INTERNAL, "cannot select rows of %s", name);
    }
    if (!rc && H5Dread(dset, mem, mspace, fspace, H5P_DEFAULT, buf) < 0)
        rc = h5_fail_lib(c, SASNAV_ERR_FORMAT, "cannot read rows %llu..%llu of %s (corrupt data)",
                         (unsigned long long)first, (unsigned long long)(first + count - 1), name);
    if (mspace >= 0) H5Sclose(mspace);
    if (fspace >= 0) H5Sclose(fspace);
    if (mem >= 0) H5Tclose(mem);
    return rc;
}

int h5_read_dataset_dims(h5_ctx *c, const char *name, int kind, int rank, const hsize_t *dims,
                         void *buf)
{
    hsize_t got[8];
    hid_t dset;
    int rc = h5_open_dataset(c, name, kind, rank, got, &dset);
    if (rc) return rc;
    for (int k = 0; k < rank && !rc; k++)
        if (got[k] != dims[k])
            rc = h5_fail(c, SASNAV_ERR_FORMAT, "%s has dimension %d of size %llu, expected %llu", name, k,
                         (unsigned long long)got[k], (unsigned long long)dims[k]);
    if (!rc) rc = h5_read_dataset(c, dset, name, kind, buf);
    H5Dclose(dset);
    return rc;
}

/* --- writing ------------------------------------------------------------ */

/* Random letters for temporary names (not security relevant: O_EXCL). */
static uint64_t tmp_random(void)
{
    static _Thread_local uint64_t counter;
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    uint64_t z = (uint64_t)ts.tv_nsec ^ ((uint64_t)ts.tv_sec << 30) ^ ((uint64_t)getpid() << 16) ^
                 (uint64_t)(uintptr_t)&counter ^ (++counter * 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull; /* splitmix64 finaliser */
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/* Creates an empty "<path>.tmp-XXXXXX" with O_EXCL (mode 0666 & ~umask). */
static int tmp_create(h5_ctx *c)
{
    int rc0 = sasnav_output_check(c->path); /* its message names the file */
    if (rc0) return rc0;
    static const char letters[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789";
    size_t n = strlen(c->path) + 16;
    char *tmp = malloc(n);
    if (!tmp) return h5_fail(c, SASNAV_ERR_NOMEM, "cannot allocate a file name");
    for (int attempt = 0; attempt < 100; attempt++) {
        uint64_t r = tmp_random();
        char suffix[7];
        for (int k = 0; k < 6; k++, r /= 62) suffix[k] = letters[r % 62];
        suffix[6] = '\0';
        snprintf(tmp, n, "%s.tmp-%s", c->path, suffix);
        sigset_t held;
        sasnav_partial_hold(&held);
        int fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        if (fd >= 0) c->partial = sasnav_partial_add(tmp);
        sasnav_partial_release(&held);
        if (fd >= 0) {
            close(fd);
            c->tmp_path = tmp;
            return SASNAV_OK;
        }
        if (errno != EEXIST) {
            int e = errno;
            free(tmp);
            return h5_fail(c, SASNAV_ERR_IO, "cannot create a temporary file next to it: %s", strerror(e));
        }
    }
    free(tmp);
    return h5_fail(c, SASNAV_ERR_IO, "cannot create a unique temporary file next to it");
}

int h5_create_tmp(h5_ctx *c, const char *format)
{
    return h5_create_tmp_version(c, format, SASNAV_H5_FORMAT_VERSION);
}

int h5_create_tmp_version(h5_ctx *c, const char *format, int version)
{
    int rc = tmp_create(c);
    if (rc) return rc;
    hid_t fapl = file_access_plist(1);
    if (fapl < 0) return h5_fail_lib(c, SASNAV_ERR_INTERNAL, "cannot create a file access list");
    c->file = H5Fcreate(c->tmp_path, H5F_ACC_TRUNC, H5P_DEFAULT, fapl);
    if (c->file < 0) rc = h5_fail_lib(c, SASNAV_ERR_IO, "cannot create %s", c->tmp_path);
    H5Pclose(fapl);
    if (rc) return rc;
    rc = h5_write_attr_string(c, "/", "format", format);
    if (!rc) rc = h5_write_attr_int(c, "/", "format_version", version);
    if (!rc) rc = h5_write_attr_string(c, "/", "created_by", SASNAV_H5_CREATED_BY);
    return rc;
}

int h5_commit(h5_ctx *c)
{
    herr_t e = H5Fclose(c->file);
    c->file = H5I_INVALID_HID;
    if (e < 0) return h5_fail_lib(c, SASNAV_ERR_IO, "cannot finish writing %s", c->tmp_path);
    /* Data on disk before the rename makes it visible. */
    int fd = open(c->tmp_path, O_RDONLY | O_CLOEXEC);
    if (fd < 0 || fsync(fd) != 0) {
        int err = errno;
        if (fd >= 0) close(fd);
        return h5_fail(c, SASNAV_ERR_IO, "cannot flush %s: %s", c->tmp_path, strerror(err));
    }
    close(fd);
    if (rename(c->tmp_path, c->path) != 0)
        return h5_fail(c, SASNAV_ERR_IO, "cannot rename %s onto it: %s", c->tmp_path, strerror(errno));
    free(c->tmp_path);
    c->tmp_path = NULL;
    sasnav_partial_remove(c->partial);
    c->partial = -1;
    return SASNAV_OK;
}

int h5_create_group(h5_ctx *c, const char *name)
{
    /* Attributes stay in the (checksummed) object header up to 32 of them,
     * not in a separate heap from 9 on as by default. */
    hid_t gcpl = H5Pcreate(H5P_GROUP_CREATE);
    if (gcpl < 0 || H5Pset_attr_phase_change(gcpl, 32, 24) < 0) {
        close_id(&gcpl, H5Pclose);
        return h5_fail_lib(c, SASNAV_ERR_INTERNAL, "cannot describe group %s", name);
    }
    hid_t g = H5Gcreate2(c->file, name, H5P_DEFAULT, gcpl, H5P_DEFAULT);
    int rc = g < 0 ? h5_fail_lib(c, SASNAV_ERR_IO, "cannot create group %s", name) : SASNAV_OK;
    close_id(&g, H5Gclose);
    H5Pclose(gcpl);
    return rc;
}

static int attr_write(h5_ctx *c, const char *obj, const char *name, hid_t ftype, hid_t mtype,
                      const void *value)
{
    int rc = SASNAV_OK;
    hid_t space = H5Screate(H5S_SCALAR);
    hid_t attr = space < 0 ? H5I_INVALID_HID
                           : H5Acreate_by_name(c->file, obj, name, ftype, space, H5P_DEFAULT,
                                               H5P_DEFAULT, H5P_DEFAULT);
    if (attr < 0 || H5Awrite(attr, mtype, value) < 0)
        rc = h5_fail_lib(c, SASNAV_ERR_IO, "cannot write attribute '%s' of %s", name, obj);
    close_id(&attr, H5Aclose);
    close_id(&space, H5Sclose);
    return rc;
}

int h5_write_attr_double(h5_ctx *c, const char *obj, const char *name, double value)
{
    return attr_write(c, obj, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &value);
}

int h5_write_attr_int(h5_ctx *c, const char *obj, const char *name, int value)
{
    return attr_write(c, obj, name, H5T_STD_I32LE, H5T_NATIVE_INT, &value);
}

int h5_write_attr_string(h5_ctx *c, const char *obj, const char *name, const char *value)
{
    /* Fixed-length, NUL-terminated ASCII (h5py: numpy bytes; MATLAB: char). */
    hid_t type = H5Tcopy(H5T_C_S1);
    if (type < 0 || H5Tset_size(type, strlen(value) + 1) < 0 || H5Tset_strpad(type, H5T_STR_NULLTERM) < 0) {
        close_id(&type, H5Tclose);
        return h5_fail_lib(c, SASNAV_ERR_INTERNAL, "cannot build a string type");
    }
    int rc = attr_write(c, obj, name, type, type, value);
    H5Tclose(type);
    return rc;
}

/* Chunk shape: the given one (or the whole dataset), halved along its
 * leading dimensions until it holds at most CHUNK_BYTES_MAX. */
static void chunk_shape(int rank, const hsize_t *dims, size_t elem, hsize_t *chunk)
{
    for (int k = 0; k < rank; k++) chunk[k] = dims[k];
    for (;;) {
        double bytes = (double)elem;
        for (int k = 0; k < rank; k++) bytes *= (double)chunk[k];
        if (bytes <= (double)CHUNK_BYTES_MAX) return;
        int k = 0;
        while (k < rank - 1 && chunk[k] == 1) k++;
        if (chunk[k] == 1) return;
        chunk[k] = (chunk[k] + 1) / 2;
    }
}

int h5_create_dataset(h5_ctx *c, const char *name, int kind, int rank, const hsize_t *dims,
                      const hsize_t *chunk_hint, const char *units, hid_t *out)
{
    int rc = SASNAV_OK;
    *out = H5I_INVALID_HID;
    hsize_t chunk[8];
    hid_t ftype = kind_type(kind, 1);
    hid_t space = H5Screate_simple(rank, dims, NULL);
    hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE), dset = H5I_INVALID_HID;
    if (ftype < 0 || space < 0 || dcpl < 0) {
        rc = h5_fail_lib(c, SASNAV_ERR_INTERNAL, "cannot describe dataset %s", name);
        goto done;
    }
    /* Small datasets: compact. Others: the requested chunk (per ping for
     * /raw) or the whole dataset, capped in size, each chunk with a
     * Fletcher-32 checksum. Either way corrupted data are detected. */
    double bytes = (double)H5Tget_size(ftype);
    for (int k = 0; k < rank; k++) bytes *= (double)dims[k];
    herr_t e;
    if (!chunk_hint && bytes <= (double)COMPACT_BYTES_MAX) {
        e = H5Pset_layout(dcpl, H5D_COMPACT);
    } else {
        chunk_shape(rank, chunk_hint ? chunk_hint : dims, H5Tget_size(ftype), chunk);
        e = H5Pset_chunk(dcpl, rank, chunk);
        if (e >= 0) e = H5Pset_fletcher32(dcpl);
    }
    if (e < 0 || H5Pset_fill_time(dcpl, H5D_FILL_TIME_NEVER) < 0) {
        rc = h5_fail_lib(c, SASNAV_ERR_INTERNAL, "cannot set the storage of dataset %s", name);
        goto done;
    }
    dset = H5Dcreate2(c->file, name, ftype, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
    if (dset < 0) {
        rc = h5_fail_lib(c, SASNAV_ERR_IO, "cannot create dataset %s", name);
        goto done;
    }
    if (units) rc = h5_write_attr_string(c, name, "units", units);
    if (!rc) {
        *out = dset;
        dset = H5I_INVALID_HID;
    }
done:
    close_id(&dset, H5Dclose);
    close_id(&dcpl, H5Pclose);
    close_id(&space, H5Sclose);
    close_id(&ftype, H5Tclose);
    return rc;
}

int h5_write_block(h5_ctx *c, hid_t dset, const char *name, int kind, int rank, const hsize_t *start,
                   const hsize_t *count, const void *data)
{
    int rc = SASNAV_OK;
    hid_t mtype = kind_type(kind, 0), fspace = H5Dget_space(dset);
    hid_t mspace = H5Screate_simple(rank, count, NULL);
    if (mtype < 0 || fspace < 0 || mspace < 0 ||
        H5Sselect_hyperslab(fspace, H5S_SELECT_SET, start, NULL, count, NULL) < 0)
        rc = h5_fail_lib(c, SASNAV_ERR_INTERNAL, "cannot select a block of %s", name);
    else if (H5Dwrite(dset, mtype, mspace, fspace, H5P_DEFAULT, data) < 0)
        rc = h5_fail_lib(c, SASNAV_ERR_IO, "cannot write a block of %s", name);
    close_id(&mspace, H5Sclose);
    close_id(&fspace, H5Sclose);
    close_id(&mtype, H5Tclose);
    return rc;
}

int h5_write_dataset(h5_ctx *c, const char *name, int kind, int rank, const hsize_t *dims,
                     const hsize_t *chunk_hint, const void *data, const char *units)
{
    hid_t dset;
    int rc = h5_create_dataset(c, name, kind, rank, dims, chunk_hint, NULL, &dset);
    if (rc) return rc;
    hid_t mtype = kind_type(kind, 0);
    if (mtype < 0 || H5Dwrite(dset, mtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0)
        rc = h5_fail_lib(c, SASNAV_ERR_IO, "cannot write dataset %s", name);
    close_id(&mtype, H5Tclose);
    close_id(&dset, H5Dclose);
    if (!rc && units) rc = h5_write_attr_string(c, name, "units", units);
    return rc;
}
