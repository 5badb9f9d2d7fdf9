/*
 * h5util.h -- internal helpers of libpd for HDF5 attributes and datasets.
 * Not installed; the public interface is pd.h.
 */
#ifndef PD_H5UTIL_H
#define PD_H5UTIL_H

#include <hdf5.h>

#include "pd.h"

struct pd_file {
    hid_t fid;
    char *name;           /* for messages                          */
    char *path;           /* final path (NULL for stdout)          */
    char *tmp;            /* temporary path being written          */
    unsigned char *image; /* stdin or update image kept alive      */
    int to_stdout;
    int readonly;
    int published;        /* renamed to `path` while still open    */
    int version;          /* pd_format_version: the file's, or this
                             pd's for a file it makes             */
    struct pd_series_plan *series; /* the rows of /series still to
                                      write (series_io.c), or NULL     */
    int ranks;            /* >1: every MPI rank writes it (parallel
                             HDF5), rank 0 renames it               */
};

void pd_series_plan_free(struct pd_series_plan *plan);

int pd_h5_has_attr(hid_t loc, const char *name);
int pd_h5_has_link(hid_t loc, const char *path);
pd_status pd_h5_read_attr_string(hid_t loc, const char *name, char **out);
pd_status pd_h5_read_attr_int(hid_t loc, const char *name, int64_t *out);
pd_status pd_h5_read_attr_double(hid_t loc, const char *name, double *out);
pd_status pd_h5_read_attr_doubles(hid_t loc, const char *name, double *out, int n);
pd_status pd_h5_write_attr_string(hid_t loc, const char *name, const char *value);
pd_status pd_h5_write_attr_int(hid_t loc, const char *name, int64_t value);
pd_status pd_h5_write_attr_doubles(hid_t loc, const char *name, const double *v, int n);
/* Write an existing attribute in place (no change to the file's layout). */
pd_status pd_h5_update_attr(hid_t loc, const char *name, hid_t memtype, const void *value);
/* Write a whole existing dataset in place.  On a file every MPI rank
 * writes at once (parallel HDF5, pd_file_create_ranks) every rank calls
 * it, and rank 0's data are written. */
pd_status pd_h5_write_into(hid_t loc, const char *name, hid_t memtype, const void *data);
/* Write rows [row0, row0 + rows) of an existing dataset (of its first
 * dimension, all of the others) from data, in place.  On a parallel file
 * every rank calls it at once (collective), each with its own rows, which
 * may be none. */
pd_status pd_h5_write_rows(hid_t loc, const char *name, hid_t memtype, const void *data,
                           int64_t row0, int64_t rows);
/* 1 when this process writes the whole of datasets of loc's file: always,
 * but on a parallel file, where rank 0 does. */
int pd_h5_writes_whole(hid_t loc);
/* A dataset with its storage allocated now, to be written in place later. */
pd_status pd_h5_reserve_data(hid_t loc, const char *name, hid_t filetype, int rank,
                             const hsize_t *dims);
/* A group without modification times (reproducible bytes). */
hid_t pd_h5_create_group(hid_t loc, const char *name);
pd_status pd_h5_write_data(hid_t loc, const char *name, hid_t filetype, hid_t memtype, int rank,
                           const hsize_t *dims, const void *data);

/* The expected form of a dataset: class (H5T_FLOAT/H5T_INTEGER), size in
 * bytes, rank and dimensions (0 = any). */
typedef struct {
    H5T_class_t cls;
    size_t size;
    int rank;
    hsize_t dims[2];
} pd_h5_form;

/* Read a whole dataset after checking its form: into *buf when it is not
 * NULL (then every dimension of the form must be fixed), else into a new
 * allocation returned in *buf.  Integers out of the memory type's range are
 * clipped by HDF5, so callers range-check what they read. */
pd_status pd_h5_read_data(hid_t loc, const char *file, const char *name, const pd_h5_form *form,
                          hid_t memtype, size_t elsize, void **buf, hsize_t *dims);
/* Read rows [row0, row0 + rows) of a dataset of the form's class, size and
 * rank (1 or 2; fixed dimensions checked) into buf (that many rows of
 * memtype): a piece of a body on MPI ranks reads only its rows. */
/* The rows of a dataset of the form's class, size and rank (1 or 2; a
 * fixed second dimension checked), before any is read. */
pd_status pd_h5_rows(hid_t loc, const char *file, const char *name, const pd_h5_form *form,
                     int64_t *rows);
pd_status pd_h5_read_rows(hid_t loc, const char *file, const char *name, const pd_h5_form *form,
                          hid_t memtype, void *buf, int64_t row0, int64_t rows);

#endif
