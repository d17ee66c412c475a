/* Structure-aware HDF5 generator of the fuzz_{run,nav,image}_h5 harnesses.
 *
 * The fuzz input is not a file: it is a stream of decisions (one byte each,
 * see h5g_u8) that drive the writing of a structurally valid HDF5 file
 * through the HDF5 API, with the groups, datasets and attributes of the
 * sasnav format (docs/format.md) but fuzzed types, shapes, layouts, values,
 * and missing or extra members. A byte 0 (or the end of the input) always
 * means "as sasnav writes it": the empty input gives a valid file, and each
 * byte moves one decision away from it. What this fuzzes is sasnav's own
 * validation (src/io/h5.c, h5_util.c), not HDF5's parser (fuzz_run_h5_raw
 * does that). */
#ifndef SASNAV_FUZZ_H5GEN_H
#define SASNAV_FUZZ_H5GEN_H

#include <hdf5.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    const uint8_t *p;
    size_t n;
} h5g;

static unsigned h5g_u8(h5g *g)
{
    if (!g->n) return 0;
    g->n--;
    return *g->p++;
}

static unsigned h5g_u16(h5g *g)
{
    unsigned a = h5g_u8(g);
    return a | h5g_u8(g) << 8;
}

/* A value: mostly the default, else one of the troublesome ones. */
static double h5g_value(h5g *g, double dflt)
{
    unsigned c = h5g_u8(g);
    if (c == 0) return dflt;
    switch (c % 20) {
    case 0: return NAN;
    case 1: return INFINITY;
    case 2: return -INFINITY;
    case 3: return 0.0;
    case 4: return -dflt;
    case 5: return 1e308;
    case 6: return -1e308;
    case 7: return 4.9e-324;
    case 8: return dflt * 1e6;
    case 9: return dflt * 1e-6;
    case 10: {
        uint64_t u = 0;
        for (int k = 0; k < 8; k++) u |= (uint64_t)h5g_u8(g) << (8 * k);
        double d;
        memcpy(&d, &u, sizeof d);
        return d;
    }
    case 11: return 2147483648.0;
    case 12: return -1.0;
    case 13: return dflt * (1 + 1e-9);
    case 14: return 1e-300;
    case 15: return (double)(int)(h5g_u8(g)) - 128;
    case 16: return 3e38; /* beyond float after rounding? close to FLT_MAX */
    case 17: return 1e39; /* overflows float32 */
    case 18: return -0.0;
    default: return dflt + (double)(h5g_u8(g)) * 0.01;
    }
}

/* --- attributes ------------------------------------------------------------ */

enum { A_DOUBLE, A_INT, A_STRING };

/* Writes attribute `name` of `loc`, as sasnav does (byte 0) or missing,
 * with another type class, shape or width. */
static void h5g_attr(h5g *g, hid_t loc, const char *name, int kind, double dflt, const char *sdflt)
{
    unsigned how = h5g_u8(g) % 14;
    if (how == 1) return; /* missing */
    hid_t space = H5I_INVALID_HID, type = H5I_INVALID_HID, mem = H5I_INVALID_HID;
    hsize_t two[1] = {2};
    if (how == 2)
        space = H5Screate_simple(1, two, NULL);
    else if (how == 3)
        space = H5Screate(H5S_NULL);
    else
        space = H5Screate(H5S_SCALAR);
    double v = kind == A_STRING ? 0 : h5g_value(g, dflt);
    double dv[2] = {v, v};
    int iv[2];
    long long lv[2];
    int str = kind == A_STRING;
    if (how == 4) str = !str; /* wrong class */
    if (str) {
        char buf[96];
        const char *s = sdflt ? sdflt : "x";
        unsigned sv = h5g_u8(g) % 6;
        if (sv == 1) s = "";
        else if (sv == 2) s = "sasnav-nav";
        else if (sv == 3) s = "sasnav-run";
        else if (sv == 4) s = "sasnav-image";
        else if (sv == 5) s = "sasnav-run-but-much-longer-than-the-reader-buffer-of-sixty-four-bytes!";
        snprintf(buf, sizeof buf, "%s", s);
        if (how == 5) { /* variable-length string */
            type = H5Tcopy(H5T_C_S1);
            H5Tset_size(type, H5T_VARIABLE);
            const char *pv[2] = {buf, buf};
            hid_t a = H5Acreate2(loc, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
            if (a >= 0) {
                H5Awrite(a, type, pv);
                H5Aclose(a);
            }
        } else {
            type = H5Tcopy(H5T_C_S1);
            size_t len = strlen(buf) + 1;
            if (how == 6) len = strlen(buf) ? strlen(buf) : 1; /* no terminator */
            H5Tset_size(type, len);
            if (how == 7) H5Tset_strpad(type, H5T_STR_SPACEPAD);
            char fixed[2][80];
            memset(fixed, ' ', sizeof fixed);
            memcpy(fixed[0], buf, strlen(buf) + 1 < len ? strlen(buf) + 1 : len);
            memcpy(fixed[1], fixed[0], len);
            char packed[160];
            memcpy(packed, fixed[0], len);
            memcpy(packed + len, fixed[1], len);
            hid_t a = H5Acreate2(loc, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
            if (a >= 0) {
                H5Awrite(a, type, packed);
                H5Aclose(a);
            }
        }
    } else {
        int asint = kind == A_INT;
        if (how == 8) asint = !asint;
        if (asint) {
            unsigned w = how == 9 ? h5g_u8(g) % 6 : 0;
            hid_t ft[6] = {H5T_STD_I32LE, H5T_STD_I64LE, H5T_STD_U8LE, H5T_STD_I16BE, H5T_STD_U64LE,
                           H5T_STD_I8LE};
            type = H5Tcopy(ft[w]);
            if (how == 10) {
                mem = H5Tcopy(H5T_NATIVE_LLONG);
                lv[0] = lv[1] = (long long)((unsigned long long)h5g_u8(g) << (h5g_u8(g) % 63));
                hid_t a = H5Acreate2(loc, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
                if (a >= 0) {
                    H5Awrite(a, mem, lv);
                    H5Aclose(a);
                }
            } else {
                mem = H5Tcopy(H5T_NATIVE_INT);
                iv[0] = iv[1] = (v >= -2e9 && v <= 2e9) ? (int)v : 7;
                hid_t a = H5Acreate2(loc, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
                if (a >= 0) {
                    H5Awrite(a, mem, iv);
                    H5Aclose(a);
                }
            }
        } else {
            unsigned w = how == 9 ? h5g_u8(g) % 3 : 0;
            hid_t ft[3] = {H5T_IEEE_F64LE, H5T_IEEE_F32LE, H5T_IEEE_F64BE};
            type = H5Tcopy(ft[w]);
            mem = H5Tcopy(H5T_NATIVE_DOUBLE);
            hid_t a = H5Acreate2(loc, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
            if (a >= 0) {
                H5Awrite(a, mem, dv);
                H5Aclose(a);
            }
        }
    }
    if (mem >= 0) H5Tclose(mem);
    if (type >= 0) H5Tclose(type);
    if (space >= 0) H5Sclose(space);
}

/* --- datasets ------------------------------------------------------------- */

enum { D_REAL, D_COMPLEX };

/* Fills n default values of a dataset (row-major over dims). */
typedef double (*h5g_fill_fn)(size_t index, const hsize_t *dims, int rank);

static hid_t h5g_complex_type(hid_t member, int swapped, int extra)
{
    size_t m = H5Tget_size(member);
    hid_t t = H5Tcreate(H5T_COMPOUND, (extra ? 3 : 2) * m);
    H5Tinsert(t, swapped ? "i" : "r", 0, member);
    H5Tinsert(t, swapped ? "r" : "i", m, member);
    if (extra) H5Tinsert(t, "z", 2 * m, member);
    return t;
}

/* Writes dataset `path` (parent groups must exist) of the given kind and
 * default shape, with default values from fill(). */
static void h5g_dataset(h5g *g, hid_t file, const char *path, int kind, int rank, const hsize_t *dims0,
                        h5g_fill_fn fill)
{
    unsigned what = h5g_u8(g) % 12;
    if (what == 1) return; /* missing */
    if (what == 2) {       /* a group where a dataset should be */
        hid_t gr = H5Gcreate2(file, path, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
        if (gr >= 0) H5Gclose(gr);
        return;
    }
    if (what == 3) { /* dangling soft link */
        H5Lcreate_soft("/nowhere", file, path, H5P_DEFAULT, H5P_DEFAULT);
        return;
    }
    if (what == 4) { /* soft link to the root (a group) or to itself */
        H5Lcreate_soft(h5g_u8(g) & 1 ? "/" : path, file, path, H5P_DEFAULT, H5P_DEFAULT);
        return;
    }
    if (what == 5) { /* external link to a missing file */
        H5Lcreate_external("missing.h5", "/x", file, path, H5P_DEFAULT, H5P_DEFAULT);
        return;
    }
    /* shape */
    int r = rank;
    hsize_t dims[4] = {0}, maxdims[4];
    for (int k = 0; k < rank; k++) dims[k] = dims0[k];
    unsigned sh = h5g_u8(g) % 8;
    if (sh == 1 && r < 4) dims[r++] = 1;
    else if (sh == 2 && r > 1) r--;
    else if (sh == 3) dims[h5g_u8(g) % r] = h5g_u8(g) % 9;
    else if (sh == 4) dims[h5g_u8(g) % r] = 0;
    else if (sh == 5) dims[h5g_u8(g) % r] += 1;
    else if (sh == 6) dims[h5g_u8(g) % r] = (hsize_t)1 << (20 + h5g_u8(g) % 24); /* huge, never written */
    size_t npts = 1;
    int huge = 0;
    for (int k = 0; k < r; k++) {
        if (dims[k] > (1u << 16)) huge = 1;
        npts *= dims[k] ? dims[k] : 1;
        maxdims[k] = dims[k];
    }
    if (huge) npts = 0;
    unsigned sp = h5g_u8(g) % 10;
    hid_t space;
    if (sp == 1)
        space = H5Screate(H5S_SCALAR), npts = 1;
    else if (sp == 2)
        space = H5Screate(H5S_NULL), npts = 0;
    else {
        if (sp == 3)
            for (int k = 0; k < r; k++) maxdims[k] = H5S_UNLIMITED;
        space = H5Screate_simple(r, dims, maxdims);
    }
    /* type */
    unsigned ty = h5g_u8(g) % 16;
    hid_t ftype, mtype;
    int convertible = 1;
    if (kind == D_REAL) {
        mtype = H5Tcopy(H5T_NATIVE_DOUBLE);
        switch (ty) {
        case 1: ftype = H5Tcopy(H5T_IEEE_F32LE); break;
        case 2: ftype = H5Tcopy(H5T_STD_I32LE); break;
        case 3: ftype = H5Tcopy(H5T_IEEE_F64BE); break;
        case 4: ftype = h5g_complex_type(H5T_IEEE_F32LE, 0, 0); convertible = 0; break;
        case 5: ftype = H5Tcopy(H5T_C_S1); H5Tset_size(ftype, 8); convertible = 0; break;
        case 6: { /* a float with a tiny exponent: 16-bit "half" */
            ftype = H5Tcopy(H5T_IEEE_F32LE);
            H5Tset_fields(ftype, 15, 10, 5, 0, 10);
            H5Tset_precision(ftype, 16);
            H5Tset_size(ftype, 2);
            H5Tset_ebias(ftype, 15);
            break;
        }
        case 7: { hsize_t two = 2; ftype = H5Tarray_create2(H5T_IEEE_F64LE, 1, &two); convertible = 0; break; }
        default: ftype = H5Tcopy(H5T_IEEE_F64LE);
        }
    } else {
        mtype = h5g_complex_type(H5T_NATIVE_FLOAT, 0, 0);
        switch (ty) {
        case 1: ftype = h5g_complex_type(H5T_IEEE_F64LE, 0, 0); break;
        case 2: ftype = h5g_complex_type(H5T_IEEE_F32LE, 1, 0); break;
        case 3: ftype = h5g_complex_type(H5T_IEEE_F32BE, 0, 0); break;
        case 4: ftype = h5g_complex_type(H5T_IEEE_F32LE, 0, 1); convertible = 0; break;
        case 5: ftype = H5Tcopy(H5T_IEEE_F64LE); convertible = 0; break;
        case 6: ftype = h5g_complex_type(H5T_STD_I32LE, 0, 0); convertible = 0; break;
        case 7: { /* only "r" */
            ftype = H5Tcreate(H5T_COMPOUND, 4);
            H5Tinsert(ftype, "r", 0, H5T_IEEE_F32LE);
            convertible = 0;
            break;
        }
        case 8: { /* "r" and "q" */
            ftype = H5Tcreate(H5T_COMPOUND, 8);
            H5Tinsert(ftype, "r", 0, H5T_IEEE_F32LE);
            H5Tinsert(ftype, "q", 4, H5T_IEEE_F32LE);
            convertible = 0;
            break;
        }
        case 9: { /* members with padding between them */
            ftype = H5Tcreate(H5T_COMPOUND, 16);
            H5Tinsert(ftype, "r", 0, H5T_IEEE_F32LE);
            H5Tinsert(ftype, "i", 8, H5T_IEEE_F32LE);
            break;
        }
        default: ftype = h5g_complex_type(H5T_IEEE_F32LE, 0, 0);
        }
    }
    /* layout */
    unsigned lay = h5g_u8(g) % 10;
    hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
    int write = 1;
    size_t fsize = H5Tget_size(ftype);
    int chunked = lay == 0 || lay == 3 || lay == 4 || lay == 6 || lay == 7 || sp == 3 || huge;
    if (lay == 2 && !huge && npts * fsize < 30000 && sp != 3) {
        H5Pset_layout(dcpl, H5D_COMPACT);
        chunked = 0;
    } else if (chunked && sp != 1 && sp != 2) {
        hsize_t ch[4];
        for (int k = 0; k < r; k++) ch[k] = dims[k] ? (dims[k] < 64 ? dims[k] : 64) : 1;
        if (lay == 7)
            for (int k = 0; k < r; k++) ch[k] = 1;
        H5Pset_chunk(dcpl, r, ch);
        if (lay == 0) H5Pset_fletcher32(dcpl);
        if (lay == 3 || lay == 6) H5Pset_deflate(dcpl, 1);
        if (lay == 4) H5Pset_shuffle(dcpl);
    }
    if (lay == 5 || lay == 8 || huge) write = 0; /* storage never allocated */
    if (lay == 8) {
        double nanv = NAN;
        if (kind == D_REAL && H5Tget_class(ftype) == H5T_FLOAT) H5Pset_fill_value(dcpl, H5T_NATIVE_DOUBLE, &nanv);
    }
    hid_t d = H5Dcreate2(file, path, ftype, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
    if (d >= 0 && write && npts) {
        unsigned vals = h5g_u8(g);
        if (convertible) {
            size_t ncomp = kind == D_COMPLEX ? 2 : 1;
            size_t nv = npts * ncomp;
            void *buf = malloc(kind == D_COMPLEX ? nv * sizeof(float) : nv * sizeof(double));
            if (!buf) abort();
            for (size_t i = 0; i < nv; i++) {
                double v = fill ? fill(i / ncomp, dims, r) : 0.0;
                if (kind == D_COMPLEX && i % 2) v = 0.5 * v;
                if (kind == D_COMPLEX) ((float *)buf)[i] = (float)v;
                else ((double *)buf)[i] = v;
            }
            /* poison up to 7 entries */
            for (unsigned k = 0; k < (vals & 7); k++) {
                size_t at = h5g_u16(g) % nv;
                double v = h5g_value(g, 1.0);
                if (kind == D_COMPLEX) ((float *)buf)[at] = (float)v;
                else ((double *)buf)[at] = v;
            }
            if (vals & 8) { /* write one element only (partial data) */
                hid_t fs = H5Dget_space(d);
                hsize_t one[4] = {1, 1, 1, 1}, zero[4] = {0};
                if (sp == 0 || sp == 3) {
                    H5Sselect_hyperslab(fs, H5S_SELECT_SET, zero, NULL, one, NULL);
                    hid_t ms = H5Screate_simple(1, one, NULL);
                    H5Dwrite(d, mtype, ms, fs, H5P_DEFAULT, buf);
                    H5Sclose(ms);
                }
                H5Sclose(fs);
            } else {
                H5Dwrite(d, mtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf);
            }
            free(buf);
        } else if (H5Tget_class(ftype) != H5T_VLEN) {
            size_t nb = npts * fsize;
            uint8_t *buf = calloc(nb ? nb : 1, 1);
            if (!buf) abort();
            for (size_t i = 0; i < nb && g->n; i++) buf[i] = (uint8_t)h5g_u8(g);
            H5Dwrite(d, ftype, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf);
            free(buf);
        }
        if (vals & 16) h5g_attr(g, d, "units", A_STRING, 0, "m");
    }
    if (d >= 0) H5Dclose(d);
    H5Pclose(dcpl);
    H5Tclose(ftype);
    H5Tclose(mtype);
    H5Sclose(space);
}

static void h5g_group(hid_t file, const char *path)
{
    hid_t gr = H5Gcreate2(file, path, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (gr >= 0) H5Gclose(gr);
}

/* Creates the file: a byte picks the oldest (no checksums) or newest
 * format. */
static hid_t h5g_create(h5g *g, const char *path)
{
    hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
    if (h5g_u8(g) & 1) H5Pset_libver_bounds(fapl, H5F_LIBVER_LATEST, H5F_LIBVER_LATEST);
    hid_t f = H5Fcreate(path, H5F_ACC_TRUNC, H5P_DEFAULT, fapl);
    H5Pclose(fapl);
    if (f < 0) abort();
    return f;
}

/* Root attributes: format (the given name by default), format_version. */
static void h5g_root(h5g *g, hid_t file, const char *format)
{
    h5g_attr(g, file, "format", A_STRING, 0, format);
    h5g_attr(g, file, "format_version", A_INT, 1, NULL);
    h5g_attr(g, file, "created_by", A_STRING, 0, "sasnav-fuzz");
}

/* Extra members: up to 3 objects anywhere, some with the names the reader
 * looks for. */
static void h5g_extras(h5g *g, hid_t file)
{
    static const char *const names[] = {"/extra", "/nav/extra", "/system/x", "/image/x", "/aiding/x",
                                        "/truth", "/aiding", "/x", "/y", "/raw", "/nav", "/truth/tx"};
    unsigned n = h5g_u8(g) % 4;
    for (unsigned k = 0; k < n; k++) {
        const char *nm = names[h5g_u8(g) % (sizeof names / sizeof names[0])];
        if (h5g_u8(g) & 1)
            h5g_group(file, nm);
        else {
            hsize_t d[1] = {3};
            h5g_dataset(g, file, nm, D_REAL, 1, d, NULL);
        }
    }
}

static void h5g_init(void)
{
    static int done;
    if (done) return;
    done = 1;
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
}

#endif
