/*
 * h5util.c -- checked HDF5 attribute and dataset access for libpd.  Every
 * read checks class, size and shape against the documented form before it
 * allocates, and refuses sizes larger than the machine's memory.
 */
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "base/comm.h"
#include "io/h5util.h"

int pd_h5_has_attr(hid_t loc, const char *name)
{
    return H5Aexists(loc, name) > 0;
}

int pd_h5_has_link(hid_t loc, const char *path)
{
    /* check each component, as H5Lexists requires */
    char buf[512];
    if (strlen(path) >= sizeof buf)
        return 0;
    strcpy(buf, path);
    for (char *p = buf + 1; ; p++) {
        if (*p == '/' || *p == '\0') {
            char c = *p;
            *p = '\0';
            if (H5Lexists(loc, buf, H5P_DEFAULT) <= 0)
                return 0;
            if (c == '\0')
                return 1;
            *p = c;
        }
    }
}

static hid_t open_attr(hid_t loc, const char *name)
{
    if (!pd_h5_has_attr(loc, name))
        return H5I_INVALID_HID;
    return H5Aopen(loc, name, H5P_DEFAULT);
}

pd_status pd_h5_read_attr_string(hid_t loc, const char *name, char **out)
{
    hid_t a = open_attr(loc, name);
    if (a < 0)
        return pd_fail(PD_ERR_FORMAT, "missing attribute '%s'", name);
    hid_t t = H5Aget_type(a);
    hid_t sp = H5Aget_space(a);
    pd_status s = PD_OK;
    if (H5Tget_class(t) != H5T_STRING || H5Sget_simple_extent_npoints(sp) != 1) {
        s = pd_fail(PD_ERR_FORMAT, "attribute '%s' is not a string", name);
    } else if (H5Tis_variable_str(t) > 0) {
        hid_t mt = H5Tcopy(H5T_C_S1);
        H5Tset_size(mt, H5T_VARIABLE);
        H5Tset_cset(mt, H5Tget_cset(t));
        char *v = NULL;
        if (H5Aread(a, mt, &v) < 0 || v == NULL)
            s = pd_fail(PD_ERR_FORMAT, "cannot read attribute '%s'", name);
        else {
            *out = strdup(v);
            H5free_memory(v);
        }
        H5Tclose(mt);
    } else {
        size_t len = H5Tget_size(t);
        char *v = calloc(len + 1, 1);
        hid_t mt = H5Tcopy(H5T_C_S1);
        H5Tset_size(mt, len + 1);
        H5Tset_cset(mt, H5Tget_cset(t));
        if (v == NULL || H5Aread(a, mt, v) < 0) {
            free(v);
            s = pd_fail(PD_ERR_FORMAT, "cannot read attribute '%s'", name);
        } else
            *out = v;
        H5Tclose(mt);
    }
    H5Sclose(sp);
    H5Tclose(t);
    H5Aclose(a);
    return s;
}

static pd_status read_attr_scalar(hid_t loc, const char *name, H5T_class_t cls, hid_t mt,
                                  void *out)
{
    hid_t a = open_attr(loc, name);
    if (a < 0)
        return pd_fail(PD_ERR_FORMAT, "missing attribute '%s'", name);
    hid_t t = H5Aget_type(a);
    hid_t sp = H5Aget_space(a);
    pd_status s = PD_OK;
    H5T_class_t c = H5Tget_class(t);
    int ok = (c == cls || (cls == H5T_FLOAT && c == H5T_INTEGER));
    if (!ok || H5Sget_simple_extent_npoints(sp) != 1)
        s = pd_fail(PD_ERR_FORMAT, "attribute '%s' has the wrong type or shape", name);
    else if (H5Aread(a, mt, out) < 0)
        s = pd_fail(PD_ERR_FORMAT, "cannot read attribute '%s'", name);
    H5Sclose(sp);
    H5Tclose(t);
    H5Aclose(a);
    return s;
}

/* A float attribute of exactly n values. */
pd_status pd_h5_read_attr_doubles(hid_t loc, const char *name, double *out, int n)
{
    hid_t a = open_attr(loc, name);
    if (a < 0)
        return pd_fail(PD_ERR_FORMAT, "missing attribute '%s'", name);
    hid_t t = H5Aget_type(a);
    hid_t sp = H5Aget_space(a);
    pd_status s = PD_OK;
    if (H5Tget_class(t) != H5T_FLOAT || H5Sget_simple_extent_npoints(sp) != n)
        s = pd_fail(PD_ERR_FORMAT, "attribute '%s' has the wrong type or shape", name);
    else if (H5Aread(a, H5T_NATIVE_DOUBLE, out) < 0)
        s = pd_fail(PD_ERR_FORMAT, "cannot read attribute '%s'", name);
    H5Sclose(sp);
    H5Tclose(t);
    H5Aclose(a);
    return s;
}

pd_status pd_h5_read_attr_int(hid_t loc, const char *name, int64_t *out)
{
    return read_attr_scalar(loc, name, H5T_INTEGER, H5T_NATIVE_INT64, out);
}

pd_status pd_h5_read_attr_double(hid_t loc, const char *name, double *out)
{
    return read_attr_scalar(loc, name, H5T_FLOAT, H5T_NATIVE_DOUBLE, out);
}

static pd_status write_attr(hid_t loc, const char *name, hid_t type, hid_t space, const void *v)
{
    if (pd_h5_has_attr(loc, name))
        H5Adelete(loc, name);
    hid_t a = H5Acreate2(loc, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
    pd_status s = PD_OK;
    if (a < 0 || H5Awrite(a, type, v) < 0)
        s = pd_fail(PD_ERR_IO, "cannot write attribute '%s'", name);
    if (a >= 0)
        H5Aclose(a);
    return s;
}

pd_status pd_h5_write_attr_string(hid_t loc, const char *name, const char *value)
{
    hid_t t = H5Tcopy(H5T_C_S1);
    H5Tset_size(t, H5T_VARIABLE);
    H5Tset_cset(t, H5T_CSET_UTF8);
    hid_t sp = H5Screate(H5S_SCALAR);
    pd_status s = write_attr(loc, name, t, sp, &value);
    H5Sclose(sp);
    H5Tclose(t);
    return s;
}

pd_status pd_h5_write_attr_int(hid_t loc, const char *name, int64_t value)
{
    hid_t sp = H5Screate(H5S_SCALAR);
    pd_status s = write_attr(loc, name, H5T_NATIVE_INT64, sp, &value);
    H5Sclose(sp);
    return s;
}

pd_status pd_h5_write_attr_doubles(hid_t loc, const char *name, const double *v, int n)
{
    hsize_t dim = (hsize_t)n;
    hid_t sp = n == 1 ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, &dim, NULL);
    pd_status s = write_attr(loc, name, H5T_NATIVE_DOUBLE, sp, v);
    H5Sclose(sp);
    return s;
}

pd_status pd_h5_update_attr(hid_t loc, const char *name, hid_t memtype, const void *value)
{
    hid_t a = H5Aopen(loc, name, H5P_DEFAULT);
    pd_status s = PD_OK;
    if (a < 0 || H5Awrite(a, memtype, value) < 0)
        s = pd_fail(PD_ERR_IO, "cannot write attribute '%s'", name);
    if (a >= 0)
        H5Aclose(a);
    return s;
}

/* Is loc's file written by every MPI rank at once (parallel HDF5)? */
static int parallel_file(hid_t loc)
{
#ifdef H5_HAVE_PARALLEL
    hid_t fid = H5Iget_file_id(loc);
    hid_t fapl = fid >= 0 ? H5Fget_access_plist(fid) : H5I_INVALID_HID;
    const int mpio = fapl >= 0 && H5Pget_driver(fapl) == H5FD_MPIO;
    if (fapl >= 0)
        H5Pclose(fapl);
    if (fid >= 0)
        H5Fclose(fid); /* the identifier, not the file */
    return mpio;
#else
    (void)loc;
    return 0;
#endif
}

int pd_h5_writes_whole(hid_t loc)
{
    return !parallel_file(loc) || pd_comm_rank() == 0;
}

/* Rows [row0, row0 + rows) of dataset d (of its first dimension, all of
 * the others) from data; on a parallel file every rank at once, each its
 * own rows (none: rows 0). */
static herr_t write_part(hid_t d, hid_t memtype, const void *data, int64_t row0, int64_t rows)
{
    hid_t fs = H5Dget_space(d);
    hsize_t dims[H5S_MAX_RANK], start[H5S_MAX_RANK] = {0};
    const int rank = fs >= 0 ? H5Sget_simple_extent_dims(fs, dims, NULL) : -1;
    if (rank < 1) {
        if (fs >= 0)
            H5Sclose(fs);
        return -1;
    }
    start[0] = (hsize_t)row0;
    dims[0] = (hsize_t)rows;
    hsize_t one = 1;
    hid_t ms = rows > 0 ? H5Screate_simple(rank, dims, NULL) : H5Screate_simple(1, &one, NULL);
    if (rows > 0)
        H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, NULL, dims, NULL);
    else {
        H5Sselect_none(fs);
        H5Sselect_none(ms);
    }
    hid_t x = H5P_DEFAULT;
#ifdef H5_HAVE_PARALLEL
    if (parallel_file(d)) {
        x = H5Pcreate(H5P_DATASET_XFER);
        H5Pset_dxpl_mpio(x, H5FD_MPIO_COLLECTIVE);
    }
#endif
    static const double none;
    const herr_t e = H5Dwrite(d, memtype, ms, fs, x, data ? data : (const void *)&none);
    if (x != H5P_DEFAULT)
        H5Pclose(x);
    H5Sclose(ms);
    H5Sclose(fs);
    return e;
}

/* All of dataset d from data: on a parallel file rank 0's, with every
 * rank taking part. */
static herr_t write_whole(hid_t d, hid_t memtype, const void *data)
{
    if (!parallel_file(d))
        return H5Dwrite(d, memtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, data);
    hid_t fs = H5Dget_space(d);
    hsize_t dims[H5S_MAX_RANK];
    const int rank = fs >= 0 ? H5Sget_simple_extent_dims(fs, dims, NULL) : -1;
    if (fs >= 0)
        H5Sclose(fs);
    if (rank < 1)
        return -1;
    return write_part(d, memtype, data, 0, pd_comm_rank() == 0 ? (int64_t)dims[0] : 0);
}

pd_status pd_h5_write_into(hid_t loc, const char *name, hid_t memtype, const void *data)
{
    hid_t d = H5Dopen2(loc, name, H5P_DEFAULT);
    pd_status s = PD_OK;
    if (d < 0 || write_whole(d, memtype, data) < 0)
        s = pd_fail(PD_ERR_IO, "cannot write dataset '%s' (disk full?)", name);
    if (d >= 0)
        H5Dclose(d);
    return s;
}

pd_status pd_h5_write_rows(hid_t loc, const char *name, hid_t memtype, const void *data,
                           int64_t row0, int64_t rows)
{
    hid_t d = H5Dopen2(loc, name, H5P_DEFAULT);
    pd_status s = PD_OK;
    if (d < 0 || write_part(d, memtype, data, row0, rows) < 0)
        s = pd_fail(PD_ERR_IO, "cannot write dataset '%s' (disk full?)", name);
    if (d >= 0)
        H5Dclose(d);
    return s;
}

pd_status pd_h5_reserve_data(hid_t loc, const char *name, hid_t filetype, int rank,
                             const hsize_t *dims)
{
    hid_t sp = H5Screate_simple(rank, dims, NULL);
    hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
    H5Pset_obj_track_times(dcpl, 0);
    H5Pset_alloc_time(dcpl, H5D_ALLOC_TIME_EARLY);
    H5Pset_fill_time(dcpl, H5D_FILL_TIME_NEVER);
    hid_t d = H5Dcreate2(loc, name, filetype, sp, H5P_DEFAULT, dcpl, H5P_DEFAULT);
    H5Pclose(dcpl);
    H5Sclose(sp);
    if (d < 0)
        return pd_fail(PD_ERR_IO, "cannot create dataset '%s' (disk full?)", name);
    H5Dclose(d);
    return PD_OK;
}

hid_t pd_h5_create_group(hid_t loc, const char *name)
{
    hid_t gcpl = H5Pcreate(H5P_GROUP_CREATE);
    H5Pset_obj_track_times(gcpl, 0);
    hid_t g = H5Gcreate2(loc, name, H5P_DEFAULT, gcpl, H5P_DEFAULT);
    H5Pclose(gcpl);
    return g;
}

pd_status pd_h5_write_data(hid_t loc, const char *name, hid_t filetype, hid_t memtype, int rank,
                           const hsize_t *dims, const void *data)
{
    hid_t sp = H5Screate_simple(rank, dims, NULL);
    /* no modification times: the same input gives the same bytes */
    hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
    H5Pset_obj_track_times(dcpl, 0);
    hid_t d = H5Dcreate2(loc, name, filetype, sp, H5P_DEFAULT, dcpl, H5P_DEFAULT);
    H5Pclose(dcpl);
    pd_status s = PD_OK;
    hsize_t total = 1;
    for (int r = 0; r < rank; r++)
        total *= dims[r];
    if (d < 0 || (total > 0 && write_whole(d, memtype, data) < 0))
        s = pd_fail(PD_ERR_IO, "cannot write dataset '%s' (disk full?)", name);
    if (d >= 0)
        H5Dclose(d);
    H5Sclose(sp);
    return s;
}

static const char *class_name(H5T_class_t c, size_t size)
{
    if (c == H5T_FLOAT)
        return size == 8 ? "float64" : "float32";
    if (c == H5T_INTEGER)
        return size == 8 ? "int64" : size == 4 ? "int32" : size == 1 ? "uint8" : "integer";
    return "non-numeric";
}

/* Open dataset `name` (*d, its space *sp; *rank) checked against the
 * form's class, size and rank; on failure nothing is left open. */
static pd_status open_checked(hid_t loc, const char *file, const char *name,
                              const pd_h5_form *form, hid_t *d, hid_t *sp, int *rank)
{
    if (!pd_h5_has_link(loc, name))
        return pd_fail(PD_ERR_FORMAT, "'%s' has no dataset '%s'", file, name);
    if ((*d = H5Dopen2(loc, name, H5P_DEFAULT)) < 0)
        return pd_fail(PD_ERR_FORMAT, "'%s': '%s' is not a dataset", file, name);
    hid_t t = H5Dget_type(*d);
    *sp = H5Dget_space(*d);
    *rank = H5Sget_simple_extent_ndims(*sp);
    const H5T_class_t cls = H5Tget_class(t);
    const size_t size = H5Tget_size(t);
    H5Tclose(t);
    pd_status s = PD_OK;
    if (cls != form->cls || size != form->size)
        s = pd_fail(PD_ERR_FORMAT, "'%s': dataset '%s' is %s, expected %s", file, name,
                    class_name(cls, size), class_name(form->cls, form->size));
    else if (*rank != form->rank)
        s = pd_fail(PD_ERR_FORMAT, "'%s': dataset '%s' has rank %d, expected %d", file, name,
                    *rank, form->rank);
    if (s != PD_OK) {
        H5Sclose(*sp);
        H5Dclose(*d);
    }
    return s;
}

pd_status pd_h5_read_data(hid_t loc, const char *file, const char *name, const pd_h5_form *form,
                          hid_t memtype, size_t elsize, void **buf, hsize_t *dims_out)
{
    hid_t d, sp;
    int rank;
    pd_status s = open_checked(loc, file, name, form, &d, &sp, &rank);
    if (s != PD_OK)
        return s;
    hsize_t dims[8] = {0};
    H5Sget_simple_extent_dims(sp, dims, NULL);
    double total = 1;
    for (int r = 0; r < rank; r++) {
        if (form->dims[r] != 0 && dims[r] != form->dims[r]) {
            s = pd_fail(PD_ERR_FORMAT,
                        "'%s': dataset '%s' has %llu entries along axis %d, expected %llu",
                        file, name, (unsigned long long)dims[r], r,
                        (unsigned long long)form->dims[r]);
            break;
        }
        total *= (double)dims[r];
    }
    if (s == PD_OK && total * (double)elsize > pd_memory_bytes())
        s = pd_fail(PD_ERR_NOMEM, "'%s': dataset '%s' declares %.3g bytes, more than memory",
                    file, name, total * (double)elsize);
    if (s == PD_OK) {
        void *b = *buf ? *buf : malloc(total > 0 ? (size_t)total * elsize : 1);
        if (b == NULL)
            s = pd_fail(PD_ERR_NOMEM, "out of memory reading '%s'", name);
        else if (total > 0 && H5Dread(d, memtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, b) < 0) {
            if (b != *buf)
                free(b);
            s = pd_fail(PD_ERR_FORMAT, "'%s': cannot read dataset '%s'", file, name);
        } else {
            *buf = b;
            if (dims_out)
                for (int r = 0; r < rank; r++)
                    dims_out[r] = dims[r];
        }
    }
    H5Sclose(sp);
    H5Dclose(d);
    return s;
}

/* open_checked, and the dataset's rank (1 or 2) and its fixed dimensions
 * checked: dims its extent. */
static pd_status open_rows(hid_t loc, const char *file, const char *name, const pd_h5_form *form,
                           hid_t *d, hid_t *fs, int *rank, hsize_t dims[2])
{
    pd_status s = open_checked(loc, file, name, form, d, fs, rank);
    if (s != PD_OK)
        return s;
    dims[0] = 0;
    dims[1] = 1;
    if (*rank < 1 || *rank > 2)
        s = pd_fail(PD_ERR_FORMAT, "'%s': dataset '%s' has rank %d, expected 1 or 2", file, name,
                    *rank);
    else if (H5Sget_simple_extent_dims(*fs, dims, NULL) < 0)
        s = pd_fail(PD_ERR_FORMAT, "'%s': cannot read dataset '%s'", file, name);
    for (int r = 0; r < *rank && s == PD_OK; r++)
        if (form->dims[r] != 0 && dims[r] != form->dims[r])
            s = pd_fail(PD_ERR_FORMAT,
                        "'%s': dataset '%s' has %llu entries along axis %d, expected %llu",
                        file, name, (unsigned long long)dims[r], r,
                        (unsigned long long)form->dims[r]);
    if (s != PD_OK) {
        H5Sclose(*fs);
        H5Dclose(*d);
    }
    return s;
}

pd_status pd_h5_rows(hid_t loc, const char *file, const char *name, const pd_h5_form *form,
                     int64_t *rows)
{
    hid_t d, fs;
    int rank;
    hsize_t dims[2];
    *rows = 0;
    pd_status s = open_rows(loc, file, name, form, &d, &fs, &rank, dims);
    if (s != PD_OK)
        return s;
    *rows = (int64_t)dims[0];
    H5Sclose(fs);
    H5Dclose(d);
    return PD_OK;
}

pd_status pd_h5_read_rows(hid_t loc, const char *file, const char *name, const pd_h5_form *form,
                          hid_t memtype, void *buf, int64_t row0, int64_t rows)
{
    hid_t d, fs;
    int rank;
    hsize_t dims[2];
    pd_status s = open_rows(loc, file, name, form, &d, &fs, &rank, dims);
    if (s != PD_OK)
        return s;
    if (row0 < 0 || rows < 0 || (uint64_t)(row0 + rows) > (uint64_t)dims[0])
        s = pd_fail(PD_ERR_FORMAT, "'%s': dataset '%s' has %llu entries, rows up to %lld wanted",
                    file, name, (unsigned long long)dims[0], (long long)(row0 + rows));
    if (s == PD_OK && rows > 0) {
        hsize_t start[2] = {(hsize_t)row0, 0}, count[2] = {(hsize_t)rows, dims[1]};
        hid_t ms = H5Screate_simple(rank, count, NULL);
        if (H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, NULL, count, NULL) < 0 ||
            H5Dread(d, memtype, ms, fs, H5P_DEFAULT, buf) < 0)
            s = pd_fail(PD_ERR_FORMAT, "'%s': cannot read dataset '%s'", file, name);
        H5Sclose(ms);
    }
    H5Sclose(fs);
    H5Dclose(d);
    return s;
}
