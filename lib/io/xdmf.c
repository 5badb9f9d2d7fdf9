/*
 * xdmf.c -- the frames of a run file described in XDMF, so that ParaView
 * opens them in place, as a time series, with no copy of the data.
 *
 * The description is XDMF 2 (an XML file; ParaView's "XDMF Reader") of a
 * temporal collection: one uniform grid per complete frame, at the frame's
 * time, of N points as one Polyvertex topology.  The points are the
 * current positions y = x + u, an XDMF Function "$0 + $1" of the reference
 * positions /particles/position and the frame's displacement; the point
 * data are the frame's displacement and velocity (vectors), damage (and
 * damage_run, strain_energy_density, von_mises and the stress tensor when
 * the frame holds them), and material and id from /particles.  Every array
 * is an HDF DataItem naming its dataset in the run file ("run.h5:/frames/
 * 00000100/damage"), with the dataset's own type and shape, read here from
 * the file rather than assumed.  Frames a killed run left incomplete are
 * not listed (pd_list_frames).
 */
#include <stdlib.h>
#include <string.h>

#include "io/h5util.h"
#include "io/pending.h"

/* The form of dataset `path`: rank, dimensions, and its numbers as XDMF
 * names them (NumberType, Precision); *present = 0 when there is none. */
typedef struct {
    int present;
    int rank;
    hsize_t dims[3];
    const char *type; /* "Float", "Int" or "UInt" */
    size_t size;      /* bytes per number          */
} ds_form;

static pd_status dataset_form(const pd_file *f, const char *path, ds_form *d)
{
    memset(d, 0, sizeof *d);
    if (!pd_h5_has_link(f->fid, path))
        return PD_OK;
    hid_t ds = H5Dopen2(f->fid, path, H5P_DEFAULT);
    hid_t sp = ds >= 0 ? H5Dget_space(ds) : -1;
    hid_t ty = ds >= 0 ? H5Dget_type(ds) : -1;
    pd_status s = PD_OK;
    int rank = sp >= 0 ? H5Sget_simple_extent_ndims(sp) : -1;
    H5T_class_t cls = ty >= 0 ? H5Tget_class(ty) : H5T_NO_CLASS;
    if (rank < 1 || rank > 3 || (cls != H5T_FLOAT && cls != H5T_INTEGER))
        s = pd_fail(PD_ERR_FORMAT, "'%s': %s is not a numeric dataset of rank 1 to 3", f->name,
                    path);
    else {
        H5Sget_simple_extent_dims(sp, d->dims, NULL);
        d->present = 1;
        d->rank = rank;
        d->size = H5Tget_size(ty);
        d->type = cls == H5T_FLOAT           ? "Float"
                  : H5Tget_sign(ty) == H5T_SGN_NONE ? "UInt"
                                                    : "Int";
    }
    if (ty >= 0)
        H5Tclose(ty);
    if (sp >= 0)
        H5Sclose(sp);
    if (ds >= 0)
        H5Dclose(ds);
    return s;
}

/* One HDF DataItem of dataset `path` of the run file `h5ref`. */
static void data_item(FILE *fp, const char *indent, const char *h5ref, const char *path,
                      const ds_form *d)
{
    fprintf(fp, "%s<DataItem Format=\"HDF\" NumberType=\"%s\" Precision=\"%zu\" Dimensions=\"",
            indent, d->type, d->size);
    for (int r = 0; r < d->rank; r++)
        fprintf(fp, "%s%llu", r ? " " : "", (unsigned long long)d->dims[r]);
    fprintf(fp, "\">");
    pd_xml_escaped(fp, h5ref);
    fprintf(fp, ":%s</DataItem>\n", path);
}

/* A point-data attribute of dataset `path` when the file has it (one row
 * a particle; 1, 3 or 9 numbers a row: a scalar, a vector, a tensor);
 * nothing when it has not. */
static pd_status attribute(FILE *fp, const pd_file *f, const char *h5ref, const char *path,
                           const char *name, int64_t n)
{
    ds_form d;
    pd_status s = dataset_form(f, path, &d);
    if (s != PD_OK || !d.present)
        return s;
    if ((int64_t)d.dims[0] != n)
        return pd_fail(PD_ERR_FORMAT, "'%s': %s has %llu rows, not one a particle (%lld)",
                       f->name, path, (unsigned long long)d.dims[0], (long long)n);
    hsize_t comp = 1;
    for (int r = 1; r < d.rank; r++)
        comp *= d.dims[r];
    const char *kind = comp == 1 ? "Scalar" : comp == 3 ? "Vector" : comp == 9 ? "Tensor" : NULL;
    if (kind == NULL)
        return pd_fail(PD_ERR_FORMAT, "'%s': %s has %llu components a particle", f->name, path,
                       (unsigned long long)comp);
    fprintf(fp, "    <Attribute Name=\"%s\" AttributeType=\"%s\" Center=\"Node\">\n", name, kind);
    data_item(fp, "     ", h5ref, path, &d);
    fprintf(fp, "    </Attribute>\n");
    return PD_OK;
}

/* The fields of a frame ParaView is shown, in this order: the frame's own
 * (displacement is the grid's too), then the particles'. */
static const char *const frame_fields[] = {"displacement", "velocity", "damage", "damage_run",
                                           "strain_energy_density", "von_mises", "stress"};
static const char *const particle_fields[] = {"material", "id"};

static pd_status write_frame(FILE *fp, const pd_file *f, const char *h5ref, const char *frame,
                             int64_t n, const ds_form *pos)
{
    pd_frame_info fi;
    pd_status s = pd_read_frame_info(f, frame, &fi);
    char path[256];
    ds_form disp;
    if (s == PD_OK && snprintf(path, sizeof path, "/frames/%s/displacement", frame) >= (int)sizeof path)
        s = pd_fail(PD_ERR_FORMAT, "'%s': frame name '%s' too long", f->name, frame);
    if (s == PD_OK && (s = dataset_form(f, path, &disp)) == PD_OK &&
        !(disp.present && disp.rank == 2 && (int64_t)disp.dims[0] == n && disp.dims[1] == 3))
        s = pd_fail(PD_ERR_FORMAT, "'%s': frame %s has no displacement of %lld x 3", f->name,
                    frame, (long long)n);
    if (s != PD_OK)
        return s;
    fprintf(fp, "   <Grid Name=\"particles\" GridType=\"Uniform\">\n"
                "    <Time Value=\"%.17g\"/>\n"
                "    <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"%lld\" "
                "NodesPerElement=\"1\"/>\n"
                "    <Geometry GeometryType=\"XYZ\">\n"
                "     <DataItem ItemType=\"Function\" Function=\"$0 + $1\" Dimensions=\"%lld 3\">\n",
            fi.time, (long long)n, (long long)n);
    data_item(fp, "      ", h5ref, "/particles/position", pos);
    data_item(fp, "      ", h5ref, path, &disp);
    fprintf(fp, "     </DataItem>\n"
                "    </Geometry>\n");
    for (size_t k = 0; k < sizeof frame_fields / sizeof *frame_fields && s == PD_OK; k++) {
        snprintf(path, sizeof path, "/frames/%s/%s", frame, frame_fields[k]);
        s = attribute(fp, f, h5ref, path, frame_fields[k], n);
    }
    for (size_t k = 0; k < sizeof particle_fields / sizeof *particle_fields && s == PD_OK; k++) {
        snprintf(path, sizeof path, "/particles/%s", particle_fields[k]);
        s = attribute(fp, f, h5ref, path, particle_fields[k], n);
    }
    fprintf(fp, "   </Grid>\n");
    return s;
}

pd_status pd_xdmf_write(const pd_file *f, const char *h5ref, const char *path,
                        int64_t *nframes)
{
    *nframes = 0;
    if (h5ref == NULL || h5ref[0] == '\0' || strchr(h5ref, ':') != NULL)
        return pd_fail(PD_ERR_INVALID, "the run file's name for XDMF must be a path without ':'");
    ds_form pos;
    pd_status s = dataset_form(f, "/particles/position", &pos);
    if (s == PD_OK && !(pos.present && pos.rank == 2 && pos.dims[1] == 3))
        s = pd_fail(PD_ERR_FORMAT, "'%s' has no /particles/position of N x 3", f->name);
    int64_t nf = 0;
    char **frames = NULL;
    if (s == PD_OK)
        s = pd_list_frames(f, &nf, &frames);
    if (s != PD_OK)
        return s;
    const int64_t n = (int64_t)pos.dims[0];
    pd_pending out;
    if ((s = pd_pending_open(path, &out)) == PD_OK) {
        fprintf(out.fp, "<?xml version=\"1.0\" ?>\n"
                        "<!-- the frames of a pd run file, read in place: open with ParaView's "
                        "XDMF Reader -->\n"
                        "<Xdmf Version=\"2.0\">\n"
                        " <Domain>\n"
                        "  <Grid Name=\"run\" GridType=\"Collection\" CollectionType=\"Temporal\">\n");
        for (int64_t k = 0; k < nf && s == PD_OK; k++)
            s = write_frame(out.fp, f, h5ref, frames[k], n, &pos);
        fprintf(out.fp, "  </Grid>\n"
                        " </Domain>\n"
                        "</Xdmf>\n");
        s = pd_pending_close(&out, s);
    }
    pd_frames_free_list(nf, frames);
    if (s == PD_OK)
        *nframes = nf;
    return s;
}
