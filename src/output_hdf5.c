/* output_hdf5.c: drape.h5 and its XDMF sidecar drape.xmf (output.h;
 * docs/outputs.md).
 *
 * One HDF5 dataset per frame (/steps/NNNNNN/positions): ParaView 5.11's
 * XDMF reader shows nothing for a HyperSlab into one [frames][n][3] array,
 * and does not load VTKHDF time series (STYLE.md), so every frame is its
 * own dataset and drape.xmf lists them in a temporal collection, referring
 * to drape.h5 by a path relative to itself.  Times and energies are kept in
 * memory and written at close; the file is written as drape.h5.PID.tmp
 * and renamed on a successful close, so an aborted run leaves no drape.h5.
 * Library errors: automatic printing is switched off (H5Eset_auto2) and the
 * innermost message of HDF5's error stack goes into the drape_error.
 */
#include "drape/output.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <hdf5.h>

#include "drape/alloc.h"
#include "drape/drape.h"

#define H5_BASE "drape.h5"
#define XMF_BASE "drape.xmf"
#define N_ENERGY 5

static const char *const energy_names[N_ENERGY] = {"kinetic", "stretch", "bend", "shear",
                                                   "gravity"};

struct drape_h5 {
    const drape_lattice *L;
    char *dir;
    char *path, *tmp;         /* DIR/drape.h5 and its temporary name */
    char *xmf, *xmf_tmp;      /* DIR/drape.xmf and its temporary name */
    hid_t file, steps;
    int n_quads;
    int nf, cap;
    double *times;            /* nf */
    double *en;               /* N_ENERGY per frame */
    unsigned char *has_v;     /* per frame: velocities written */
};

/* ----------------------------------------------------------- errors */

/* The innermost description, first line only (HDF5's can span several
 * lines with a time stamp and buffer addresses). */
static herr_t walk_cb(unsigned n, const H5E_error2_t *e, void *data)
{
    char *buf = data;
    if (n == 0 && e && e->desc) {
        /* a system call's failure: "file write failed: time = <ctime(), which
         * ends in a newline>, filename = ..., errno = 28, error message =
         * 'No space left on device', ...": keep the what and the reason */
        const char *m = strstr(e->desc, "error message = '");
        if (m) {
            m += strlen("error message = '");
            int wl = (int)strcspn(e->desc, ":\r\n"), ml = (int)strcspn(m, "'");
            snprintf(buf, 256, "%.*s: %.*s", wl, e->desc, ml, m);
        } else {
            snprintf(buf, 256, "%s", e->desc);
            buf[strcspn(buf, "\r\n")] = 0;
        }
    }
    return 0;
}

/* Record an E_IO error for h's file with HDF5's innermost message. */
static int h5_fail(const char *path, drape_error *err, const char *what)
{
    char msg[256] = "";
    H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, walk_cb, msg);
    H5Eclear2(H5E_DEFAULT);
    return drape_error_set(err, DRAPE_E_IO, path, 0, 0, NULL, "HDF5: %s%s%s", what,
                           msg[0] ? ": " : "", msg);
}

/* Close an HDF5 id on a failure path.  Every HDF5 call clears the error
 * stack when it starts, so a plain close would lose the failure's message
 * (a full disk's "No space left on device") before h5_fail reads it: the
 * stack is set aside and put back around the close. */
static void close_keep_error(herr_t (*close_id)(hid_t), hid_t id)
{
    hid_t es = H5Eget_current_stack();
    (void)close_id(id);
    if (es >= 0) H5Eset_current_stack(es);
}

/* ----------------------------------------------------------- helpers */

static char *join(const char *dir, const char *base, const char *suffix)
{
    size_t len = strlen(dir) + strlen(base) + (suffix ? strlen(suffix) : 0) + 32;
    char *p = drape_malloc(len);
    if (!p) return NULL;
    if (suffix)
        snprintf(p, len, "%s/%s.%ld%s", dir, base, (long)getpid(), suffix);
    else
        snprintf(p, len, "%s/%s", dir, base);
    return p;
}

/* Write a dataset of the given rank and dims; returns it open (caller
 * closes) or a negative id. */
static hid_t put_data(hid_t loc, const char *name, hid_t ftype, hid_t mtype, int rank,
                      const hsize_t *dims, const void *data)
{
    hid_t sp = H5Screate_simple(rank, dims, NULL);
    if (sp < 0) return -1;
    hid_t ds = H5Dcreate2(loc, name, ftype, sp, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (ds < 0) {
        close_keep_error(H5Sclose, sp);
        return -1;
    }
    H5Sclose(sp);
    hsize_t total = 1;
    for (int k = 0; k < rank; k++) total *= dims[k];
    if (total > 0 && H5Dwrite(ds, mtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0) {
        close_keep_error(H5Dclose, ds);
        return -1;
    }
    return ds;
}

static int put_data_closed(hid_t loc, const char *name, hid_t ftype, hid_t mtype, int rank,
                           const hsize_t *dims, const void *data)
{
    hid_t ds = put_data(loc, name, ftype, mtype, rank, dims, data);
    if (ds < 0) return -1;
    return H5Dclose(ds) < 0 ? -1 : 0;
}

static int attr_double(hid_t loc, const char *name, double v)
{
    hid_t sp = H5Screate(H5S_SCALAR);
    if (sp < 0) return -1;
    hid_t a = H5Acreate2(loc, name, H5T_IEEE_F64LE, sp, H5P_DEFAULT, H5P_DEFAULT);
    if (a < 0) {
        close_keep_error(H5Sclose, sp);
        return -1;
    }
    H5Sclose(sp);
    if (H5Awrite(a, H5T_NATIVE_DOUBLE, &v) < 0) {
        close_keep_error(H5Aclose, a);
        return -1;
    }
    return H5Aclose(a) < 0 ? -1 : 0;
}

/* Variable-length UTF-8 string attribute. */
static int attr_string(hid_t loc, const char *name, const char *text)
{
    hid_t t = H5Tcopy(H5T_C_S1);
    if (t < 0) return -1;
    int rc = -1;
    hid_t sp = -1, a = -1;
    if (H5Tset_size(t, H5T_VARIABLE) < 0 || H5Tset_cset(t, H5T_CSET_UTF8) < 0) goto out;
    sp = H5Screate(H5S_SCALAR);
    if (sp < 0) goto out;
    a = H5Acreate2(loc, name, t, sp, H5P_DEFAULT, H5P_DEFAULT);
    if (a < 0) goto out;
    if (H5Awrite(a, t, &text) < 0) goto out;
    rc = 0;
out:
    if (rc < 0) { /* keep the failure's message for h5_fail */
        if (a >= 0) close_keep_error(H5Aclose, a);
        if (sp >= 0) close_keep_error(H5Sclose, sp);
        close_keep_error(H5Tclose, t);
        return rc;
    }
    if (H5Aclose(a) < 0) rc = -1;
    H5Sclose(sp);
    H5Tclose(t);
    return rc;
}

/* Group NAME under loc with one attribute per key (text or number); keys
 * that are NULL or empty are skipped.  0 or -1. */
static int put_kv_group(hid_t loc, const char *name, const drape_kv *kv, int n)
{
    hid_t g = H5Gcreate2(loc, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (g < 0) return -1;
    int rc = 0;
    for (int k = 0; k < n && rc == 0; k++) {
        if (!kv[k].key || !kv[k].key[0]) continue;
        rc = kv[k].text ? attr_string(g, kv[k].key, kv[k].text)
                        : attr_double(g, kv[k].key, kv[k].value);
    }
    if (rc < 0) {
        close_keep_error(H5Gclose, g);
        return -1;
    }
    return H5Gclose(g) < 0 ? -1 : 0;
}

static int attr_units(hid_t loc, const char *units)
{
    return attr_string(loc, "units", units);
}

/* ----------------------------------------------------------- open */

static void h5_free(drape_h5 *h)
{
    if (!h) return;
    drape_free(h->dir);
    drape_free(h->path);
    drape_free(h->tmp);
    drape_free(h->xmf);
    drape_free(h->xmf_tmp);
    drape_free(h->times);
    drape_free(h->en);
    drape_free(h->has_v);
    drape_free(h);
}

/* Close the HDF5 handles (errors ignored: used on failure paths). */
static void h5_close_ids(drape_h5 *h)
{
    if (h->steps >= 0) H5Gclose(h->steps);
    if (h->file >= 0) H5Fclose(h->file);
    h->steps = h->file = -1;
}

void drape_h5_discard(drape_h5 *h)
{
    if (!h) return;
    h5_close_ids(h);
    if (h->tmp) unlink(h->tmp);
    if (h->xmf_tmp) unlink(h->xmf_tmp);
    h5_free(h);
}

static int write_mesh(drape_h5 *h, drape_error *err)
{
    const drape_lattice *L = h->L;
    int rc = -1, *quads = NULL, *ij = NULL;
    hid_t g = -1, ds = -1;
    quads = drape_quads_new(L, &h->n_quads, err);
    if (!quads) goto out;
    ij = drape_malloc(sizeof *ij * (size_t)(2 * L->n + 1));
    if (!ij) {
        drape_error_set(err, DRAPE_E_NOMEM, h->path, 0, 0, NULL, "out of memory");
        goto out;
    }
    for (int i = 0; i < L->n; i++) {
        ij[2 * i] = L->gi[i];
        ij[2 * i + 1] = L->gj[i];
    }
    g = H5Gcreate2(h->file, "mesh", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (g < 0) goto h5err;
    hsize_t d3[2] = {(hsize_t)L->n, 3}, dq[2] = {(hsize_t)h->n_quads, 4};
    hsize_t d1[1] = {(hsize_t)L->n}, d2[2] = {(hsize_t)L->n, 2};
    ds = put_data(g, "rest_positions", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 2, d3, L->x0);
    if (ds < 0 || attr_units(ds, "m") < 0 || H5Dclose(ds) < 0) goto h5err;
    ds = -1;
    if (put_data_closed(g, "quads", H5T_STD_I32LE, H5T_NATIVE_INT, 2, dq, quads) < 0 ||
        put_data_closed(g, "fixed", H5T_STD_U8LE, H5T_NATIVE_UCHAR, 1, d1, L->fixed) < 0 ||
        put_data_closed(g, "grid_ij", H5T_STD_I32LE, H5T_NATIVE_INT, 2, d2, ij) < 0 ||
        attr_double(g, "sigma_m", L->sigma) < 0 ||
        attr_double(g, "area_nominal_m2", L->area_nominal) < 0)
        goto h5err;
    rc = 0;
    goto out;
h5err:
    h5_fail(h->path, err, "cannot write /mesh");
out:
    if (ds >= 0) H5Dclose(ds);
    if (g >= 0) H5Gclose(g);
    drape_free(quads);
    drape_free(ij);
    return rc;
}

drape_h5 *drape_h5_open(const char *dir, const drape_lattice *L, drape_error *err)
{
    struct stat st;
    drape_h5 *h = NULL;
    /* HDF5 1.10.8 crashes in its exit handler (H5F__close_cb) when an
     * H5Fclose failed earlier, e.g. on a full disk; drape closes its files
     * itself, so the handler is not installed (effective only before the
     * library's first initialisation; later calls fail harmlessly). */
    (void)H5dont_atexit();
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    if (stat(dir, &st) != 0) {
        drape_error_set(err, DRAPE_E_IO, dir, 0, 0, NULL, "output directory: %s",
                        strerror(errno));
        return NULL;
    }
    if (!S_ISDIR(st.st_mode)) {
        drape_error_set(err, DRAPE_E_IO, dir, 0, 0, NULL,
                        "output directory: not a directory");
        return NULL;
    }
    h = drape_calloc(1, sizeof *h);
    if (!h) goto nomem;
    h->file = h->steps = -1;
    h->L = L;
    h->dir = drape_strdup(dir);
    h->path = join(dir, H5_BASE, NULL);
    h->tmp = join(dir, H5_BASE, ".tmp");
    h->xmf = join(dir, XMF_BASE, NULL);
    h->xmf_tmp = join(dir, XMF_BASE, ".tmp");
    if (!h->dir || !h->path || !h->tmp || !h->xmf || !h->xmf_tmp) goto nomem;
    /* the files renamed into place at the end: refuse a directory in the
     * way now, not after the run */
    for (int k = 0; k < 2; k++) {
        const char *p = k ? h->xmf : h->path;
        if (lstat(p, &st) == 0 && S_ISDIR(st.st_mode)) {
            drape_error_set(err, DRAPE_E_IO, p, 0, 0, NULL,
                            "a directory is in the way of the output file");
            goto fail;
        }
    }
    /* never write through a stale temporary or a symlink (EXCL) */
    unlink(h->tmp);
    unlink(h->xmf_tmp);
    /* the 1.8 file format or later: its object headers, heaps and B-trees
     * carry checksums, so a damaged checkpoint is refused by --resume
     * instead of being read (HDF5 1.10's reader of the default, earlier
     * format crashed on a damaged local heap) */
    hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
    if (fapl >= 0 && H5Pset_libver_bounds(fapl, H5F_LIBVER_V18, H5F_LIBVER_LATEST) >= 0)
        h->file = H5Fcreate(h->tmp, H5F_ACC_EXCL, H5P_DEFAULT, fapl);
    if (fapl >= 0) H5Pclose(fapl);
    if (h->file < 0) {
        h5_fail(h->path, err, "cannot create the file");
        goto fail;
    }
    if (attr_string(h->file, "creator", "drape") < 0 ||
        attr_string(h->file, "format", "drape-h5 1") < 0 ||
        attr_string(h->file, "units", "SI: m, s, kg, J; z up") < 0) {
        h5_fail(h->path, err, "cannot write root attributes");
        goto fail;
    }
    if (write_mesh(h, err)) goto fail;
    h->steps = H5Gcreate2(h->file, "steps", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (h->steps < 0) {
        h5_fail(h->path, err, "cannot create /steps");
        goto fail;
    }
    return h;
nomem:
    drape_error_set(err, DRAPE_E_NOMEM, dir, 0, 0, NULL, "HDF5 output: out of memory");
fail:
    drape_h5_discard(h);
    return NULL;
}

/* ----------------------------------------------------------- frames */

int drape_h5_frames(const drape_h5 *h)
{
    return h->nf;
}

static int grow(drape_h5 *h)
{
    if (h->nf < h->cap) return 0;
    int cap = h->cap ? 2 * h->cap : 64;
    double *t = drape_realloc(h->times, sizeof *t * (size_t)cap);
    if (!t) return -1;
    h->times = t;
    double *e = drape_realloc(h->en, sizeof *e * (size_t)(N_ENERGY * cap));
    if (!e) return -1;
    h->en = e;
    unsigned char *v = drape_realloc(h->has_v, (size_t)cap);
    if (!v) return -1;
    h->has_v = v;
    h->cap = cap;
    return 0;
}

/* positions (and velocities) + time_s into an open group */
static int put_state(hid_t g, double t_s, const double *x, const double *v, int n)
{
    hsize_t d3[2] = {(hsize_t)n, 3};
    hid_t ds = put_data(g, "positions", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 2, d3, x);
    if (ds < 0) return -1;
    if (attr_double(ds, "time_s", t_s) < 0 || attr_units(ds, "m") < 0) {
        close_keep_error(H5Dclose, ds);
        return -1;
    }
    int rc = H5Dclose(ds) < 0 ? -1 : 0;
    if (rc == 0 && v) {
        ds = put_data(g, "velocities", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 2, d3, v);
        if (ds < 0) return -1;
        if (attr_units(ds, "m/s") < 0) {
            close_keep_error(H5Dclose, ds);
            return -1;
        }
        if (H5Dclose(ds) < 0) rc = -1;
    }
    if (rc == 0 && attr_double(g, "time_s", t_s) < 0) rc = -1;
    return rc;
}

static int check_finite(const char *path, const double *a, int n, double t_s, const char *what,
                        drape_error *err)
{
    for (int i = 0; a && i < 3 * n; i++)
        if (!isfinite(a[i]))
            return drape_error_set(err, DRAPE_E_NUMERIC, path, 0, 0, NULL,
                                   "frame at t = %g s: particle %d has a non-finite %s",
                                   t_s, i / 3, what);
    return 0;
}

int drape_h5_frame(drape_h5 *h, double t_s, const double *x, const double *v,
                   double kinetic_J, const drape_energies *E, drape_error *err)
{
    const int n = h->L->n;
    if (check_finite(h->path, x, n, t_s, "position", err) ||
        check_finite(h->path, v, n, t_s, "velocity", err))
        return -1;
    if (grow(h))
        return drape_error_set(err, DRAPE_E_NOMEM, h->path, 0, 0, NULL, "out of memory");
    char name[32];
    snprintf(name, sizeof name, "%06d", h->nf);
    hid_t g = H5Gcreate2(h->steps, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (g < 0) return h5_fail(h->path, err, "cannot create a frame group");
    int rc = put_state(g, t_s, x, v, n);
    if (rc) close_keep_error(H5Gclose, g);
    else if (H5Gclose(g) < 0) rc = -1;
    if (rc) {
        char what[64];
        snprintf(what, sizeof what, "cannot write /steps/%s", name);
        return h5_fail(h->path, err, what);
    }
    h->times[h->nf] = t_s;
    double *e = h->en + N_ENERGY * h->nf;
    e[0] = kinetic_J;
    e[1] = E ? E->stretch : NAN;
    e[2] = E ? E->bend : NAN;
    e[3] = E ? E->shear : NAN;
    e[4] = E ? E->gravity : NAN;
    h->has_v[h->nf] = v != NULL;
    h->nf++;
    return 0;
}

/* ----------------------------------------------------------- close */

static int write_series(drape_h5 *h, drape_error *err)
{
    hsize_t d1[1] = {(hsize_t)h->nf};
    hid_t ds = -1, g = -1;
    double *col = NULL;
    int rc = -1;
    ds = put_data(h->file, "times", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 1, d1, h->times);
    if (ds < 0 || attr_units(ds, "s") < 0) goto h5err;
    H5Dclose(ds);
    ds = -1;
    col = drape_malloc(sizeof *col * (size_t)(h->nf + 1));
    if (!col) {
        drape_error_set(err, DRAPE_E_NOMEM, h->path, 0, 0, NULL, "out of memory");
        goto out;
    }
    g = H5Gcreate2(h->file, "energies", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (g < 0) goto h5err;
    for (int k = 0; k < N_ENERGY; k++) {
        for (int f = 0; f < h->nf; f++) col[f] = h->en[N_ENERGY * f + k];
        ds = put_data(g, energy_names[k], H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 1, d1, col);
        if (ds < 0 || attr_units(ds, "J") < 0) goto h5err;
        H5Dclose(ds);
        ds = -1;
    }
    rc = 0;
    goto out;
h5err:
    h5_fail(h->path, err, "cannot write /times or /energies");
out:
    if (ds >= 0) H5Dclose(ds);
    if (g >= 0) H5Gclose(g);
    drape_free(col);
    return rc;
}

static int write_final(drape_h5 *h, const drape_h5_final *fin, drape_error *err)
{
    hid_t g = -1;
    int rc = -1;
    if (fin->x) {
        if (check_finite(h->path, fin->x, h->L->n, fin->t_s, "position", err) ||
            check_finite(h->path, fin->v, h->L->n, fin->t_s, "velocity", err))
            return -1;
        g = H5Gcreate2(h->file, "final", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
        if (g < 0 || put_state(g, fin->t_s, fin->x, fin->v, h->L->n) < 0) goto h5err;
        H5Gclose(g);
        g = -1;
    }
    if (fin->n_stats > 0 && fin->stats &&
        put_kv_group(h->file, "stats", fin->stats, fin->n_stats) < 0)
        goto h5err;
    if (fin->n_run > 0 && fin->run && put_kv_group(h->file, "run", fin->run, fin->n_run) < 0)
        goto h5err;
    if ((fin->fabric_yaml && attr_string(h->file, "fabric_yaml", fin->fabric_yaml) < 0) ||
        (fin->scene_yaml && attr_string(h->file, "scene_yaml", fin->scene_yaml) < 0))
        goto h5err;
    rc = 0;
    goto out;
h5err:
    h5_fail(h->path, err, "cannot write the final state or statistics");
out:
    if (g >= 0) H5Gclose(g);
    return rc;
}

/* Flush a closed file's data to disk (best effort). */
static void sync_path(const char *path)
{
    int fd = open(path, O_RDONLY);
    if (fd >= 0) {
        if (fsync(fd) != 0) { /* best effort */ }
        close(fd);
    }
}

/* Write s escaped for an XML attribute or text. */
static void xml_escaped(FILE *f, const char *s)
{
    for (; *s; s++) {
        switch (*s) {
        case '&': fputs("&amp;", f); break;
        case '<': fputs("&lt;", f); break;
        case '>': fputs("&gt;", f); break;
        case '"': fputs("&quot;", f); break;
        case '\'': fputs("&apos;", f); break;
        default: fputc(*s, f);
        }
    }
}

static void xmf_item(FILE *f, const char *dims, const char *type, int prec, const char *dset)
{
    fprintf(f, "          <DataItem Dimensions=\"%s\" NumberType=\"%s\" Precision=\"%d\" "
               "Format=\"HDF\">", dims, type, prec);
    xml_escaped(f, H5_BASE);
    fprintf(f, ":%s</DataItem>\n", dset);
}

static void xmf_grid(const drape_h5 *h, FILE *f, const char *name, double t,
                     const char *positions, const char *velocities)
{
    const int n = h->L->n;
    char dn3[64], dq[64], dn[32];
    snprintf(dn3, sizeof dn3, "%d 3", n);
    snprintf(dq, sizeof dq, "%d 4", h->n_quads);
    snprintf(dn, sizeof dn, "%d", n);
    fprintf(f, "      <Grid Name=\"%s\" GridType=\"Uniform\">\n", name);
    fprintf(f, "        <Time Value=\"%.17g\"/>\n", t);
    if (h->n_quads > 0) {
        fprintf(f, "        <Topology TopologyType=\"Quadrilateral\" NumberOfElements=\"%d\">\n",
                h->n_quads);
        xmf_item(f, dq, "Int", 4, "/mesh/quads");
        fprintf(f, "        </Topology>\n");
    } else {
        fprintf(f, "        <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"%d\" "
                   "NodesPerElement=\"1\"/>\n", n);
    }
    fprintf(f, "        <Geometry GeometryType=\"XYZ\">\n");
    xmf_item(f, dn3, "Float", 8, positions);
    fprintf(f, "        </Geometry>\n");
    if (velocities) {
        fprintf(f, "        <Attribute Name=\"velocity\" AttributeType=\"Vector\" Center=\"Node\">\n");
        xmf_item(f, dn3, "Float", 8, velocities);
        fprintf(f, "        </Attribute>\n");
    }
    fprintf(f, "        <Attribute Name=\"fixed\" AttributeType=\"Scalar\" Center=\"Node\">\n");
    xmf_item(f, dn, "UChar", 1, "/mesh/fixed");
    fprintf(f, "        </Attribute>\n");
    fprintf(f, "      </Grid>\n");
}

static int write_xmf(drape_h5 *h, drape_error *err)
{
    int fd = open(h->xmf_tmp, O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW, 0666);
    FILE *f = fd >= 0 ? fdopen(fd, "w") : NULL;
    if (!f && fd >= 0) close(fd);
    if (!f)
        return drape_error_set(err, DRAPE_E_IO, h->xmf, 0, 0, NULL, "cannot create %s: %s",
                               h->xmf_tmp, strerror(errno));
    fprintf(f, "<?xml version=\"1.0\" ?>\n<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n");
    fprintf(f, "<Xdmf Version=\"2.0\">\n  <Domain>\n");
    fprintf(f, "    <Grid Name=\"drape\" GridType=\"Collection\" CollectionType=\"Temporal\">\n");
    if (h->nf == 0) {
        xmf_grid(h, f, "rest", 0.0, "/mesh/rest_positions", NULL);
    }
    for (int k = 0; k < h->nf; k++) {
        char name[32], pos[64], vel[64];
        snprintf(name, sizeof name, "step_%06d", k);
        snprintf(pos, sizeof pos, "/steps/%06d/positions", k);
        snprintf(vel, sizeof vel, "/steps/%06d/velocities", k);
        xmf_grid(h, f, name, h->times[k], pos, h->has_v[k] ? vel : NULL);
    }
    fprintf(f, "    </Grid>\n  </Domain>\n</Xdmf>\n");
    int bad = fflush(f) != 0 || ferror(f) || fsync(fileno(f)) != 0;
    int e = errno;
    if (fclose(f) != 0 && !bad) {
        bad = 1;
        e = errno;
    }
    if (bad)
        return drape_error_set(err, DRAPE_E_IO, h->xmf, 0, 0, NULL, "cannot write %s: %s",
                               h->xmf_tmp, strerror(e));
    return 0;
}

int drape_h5_finish(drape_h5 *h, const drape_h5_final *fin, drape_error *err)
{
    if (!h) return 0;
    if (write_series(h, err) || (fin && write_final(h, fin, err))) goto fail;
    if (H5Gclose(h->steps) < 0) {
        h->steps = -1;
        h5_fail(h->path, err, "cannot close /steps");
        goto fail;
    }
    h->steps = -1;
    if (H5Fclose(h->file) < 0) {
        h->file = -1;
        h5_fail(h->path, err, "cannot close the file");
        goto fail;
    }
    h->file = -1;
    sync_path(h->tmp);
    if (write_xmf(h, err)) goto fail;
    return 0;
fail:
    drape_h5_discard(h);
    return -1;
}

int drape_h5_commit(drape_h5 *h, drape_error *err)
{
    if (!h) return 0;
    if (rename(h->tmp, h->path) != 0) {
        drape_error_set(err, DRAPE_E_IO, h->path, 0, 0, NULL, "cannot rename %s: %s", h->tmp,
                        strerror(errno));
        goto fail;
    }
    if (rename(h->xmf_tmp, h->xmf) != 0) {
        drape_error_set(err, DRAPE_E_IO, h->xmf, 0, 0, NULL, "cannot rename %s: %s",
                        h->xmf_tmp, strerror(errno));
        goto fail;
    }
    h5_free(h);
    return 0;
fail:
    drape_h5_discard(h);
    return -1;
}

int drape_h5_close(drape_h5 *h, const drape_h5_final *fin, drape_error *err)
{
    if (drape_h5_finish(h, fin, err) != 0) return -1;
    return drape_h5_commit(h, err);
}

/* ----------------------------------------------------------- reading */

const drape_kv *drape_kv_find(const drape_kv *kv, int n, const char *key)
{
    for (int k = 0; kv && k < n; k++)
        if (kv[k].key && strcmp(kv[k].key, key) == 0) return kv + k;
    return NULL;
}

static void kv_free(drape_kv *kv, int n)
{
    for (int k = 0; kv && k < n; k++) {
        drape_free((char *)kv[k].key);
        drape_free((char *)kv[k].text);
    }
    drape_free(kv);
}

void drape_h5_checkpoint_free(drape_h5_checkpoint *c)
{
    if (!c) return;
    drape_free(c->x);
    drape_free(c->v);
    kv_free(c->run, c->n_run);
    kv_free(c->stats, c->n_stats);
    drape_free(c->fabric_yaml);
    drape_free(c->scene_yaml);
    memset(c, 0, sizeof *c);
}

/* A string attribute (variable or fixed length, any character set) as a
 * new string, or NULL. */
static char *read_string_attr(hid_t a)
{
    hid_t t = H5Aget_type(a);
    char *out = NULL;
    if (t < 0) return NULL;
    htri_t var = H5Tis_variable_str(t);
    if (var > 0) {
        char *raw = NULL;
        if (H5Aread(a, t, &raw) >= 0 && raw) {
            out = drape_strdup(raw);
            H5free_memory(raw);
        }
    } else if (var == 0) {
        size_t n = H5Tget_size(t);
        if (n > 0 && n < ((size_t)1 << 30) && (out = drape_calloc(n + 1, 1)) != NULL &&
            H5Aread(a, t, out) < 0) {
            drape_free(out);
            out = NULL;
        }
    }
    H5Tclose(t);
    return out;
}

/* Attributes of a group (strings and numbers) into a new array. */
static int read_attrs(hid_t file, const char *group, drape_kv **out, int *nout)
{
    *out = NULL;
    *nout = 0;
    if (H5Lexists(file, group, H5P_DEFAULT) <= 0) return 0;
    hid_t g = H5Gopen2(file, group, H5P_DEFAULT);
    if (g < 0) return -1;
    H5O_info_t info;
    int rc = -1;
    if (H5Oget_info2(g, &info, H5O_INFO_NUM_ATTRS) < 0) goto out;
    int n = (int)info.num_attrs;
    drape_kv *kv = drape_calloc((size_t)n + 1, sizeof *kv);
    if (!kv) goto out;
    *out = kv;
    for (int k = 0; k < n; k++) {
        hid_t a = H5Aopen_by_idx(g, ".", H5_INDEX_NAME, H5_ITER_INC, (hsize_t)k, H5P_DEFAULT,
                                 H5P_DEFAULT);
        if (a < 0) goto out;
        char name[256];
        ssize_t len = H5Aget_name(a, sizeof name, name);
        hid_t t = H5Aget_type(a);
        int ok = len > 0 && t >= 0;
        if (ok && H5Tget_class(t) == H5T_STRING) {
            kv[*nout].text = read_string_attr(a);
            ok = kv[*nout].text != NULL;
        } else if (ok) {
            double v = NAN;
            ok = H5Aread(a, H5T_NATIVE_DOUBLE, &v) >= 0;
            kv[*nout].value = v;
        }
        if (t >= 0) H5Tclose(t);
        H5Aclose(a);
        if (!ok) goto out;
        if (!(kv[*nout].key = drape_strdup(name))) goto out;
        (*nout)++;
    }
    rc = 0;
out:
    H5Gclose(g);
    return rc;
}

static char *read_root_string(hid_t file, const char *name)
{
    if (H5Aexists(file, name) <= 0) return NULL;
    hid_t a = H5Aopen(file, name, H5P_DEFAULT);
    if (a < 0) return NULL;
    char *s = read_string_attr(a);
    H5Aclose(a);
    return s;
}

/* An [n][3] f64 dataset into a new array; *n its rows (-1 on failure). */
static double *read_n3(hid_t loc, const char *name, int *n)
{
    double *buf = NULL;
    *n = -1;
    hid_t ds = H5Dopen2(loc, name, H5P_DEFAULT);
    if (ds < 0) return NULL;
    hid_t sp = H5Dget_space(ds);
    hsize_t dims[2] = {0, 0};
    if (sp >= 0 && H5Sget_simple_extent_ndims(sp) == 2 &&
        H5Sget_simple_extent_dims(sp, dims, NULL) == 2 && dims[1] == 3 && dims[0] < (1u << 30)) {
        buf = drape_malloc(sizeof(double) * (size_t)(3 * dims[0] + 1));
        if (buf && (dims[0] == 0 ||
                    H5Dread(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) >= 0)) {
            *n = (int)dims[0];
        } else {
            drape_free(buf);
            buf = NULL;
        }
    }
    if (sp >= 0) H5Sclose(sp);
    H5Dclose(ds);
    return buf;
}

/* A 1-D f64 dataset of exactly n entries into buf. */
static int read_1d(hid_t loc, const char *name, double *buf, int n)
{
    hid_t ds = H5Dopen2(loc, name, H5P_DEFAULT);
    if (ds < 0) return -1;
    hid_t sp = H5Dget_space(ds);
    hsize_t dims[1] = {0};
    int rc = -1;
    if (sp >= 0 && H5Sget_simple_extent_ndims(sp) == 1 &&
        H5Sget_simple_extent_dims(sp, dims, NULL) == 1 && dims[0] == (hsize_t)n &&
        (n == 0 || H5Dread(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) >= 0))
        rc = 0;
    if (sp >= 0) H5Sclose(sp);
    H5Dclose(ds);
    return rc;
}

static int count_1d(hid_t loc, const char *name)
{
    hid_t ds = H5Dopen2(loc, name, H5P_DEFAULT);
    if (ds < 0) return -1;
    hid_t sp = H5Dget_space(ds);
    hsize_t dims[1] = {0};
    int n = -1;
    if (sp >= 0 && H5Sget_simple_extent_ndims(sp) == 1 &&
        H5Sget_simple_extent_dims(sp, dims, NULL) == 1 && dims[0] < (1u << 30))
        n = (int)dims[0];
    if (sp >= 0) H5Sclose(sp);
    H5Dclose(ds);
    return n;
}

static hid_t open_readonly(const char *path, drape_error *err)
{
    (void)H5dont_atexit();
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    if (access(path, R_OK) != 0) {
        drape_error_set(err, DRAPE_E_IO, path, 0, 0, NULL, "cannot open: %s", strerror(errno));
        return -1;
    }
    hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    if (f < 0) h5_fail(path, err, "cannot open the file");
    return f;
}

int drape_h5_checkpoint_read(const char *path, drape_h5_checkpoint *c, drape_error *err)
{
    int rc = -1, nv = -1;
    hid_t g = -1;
    memset(c, 0, sizeof *c);
    hid_t f = open_readonly(path, err);
    if (f < 0) return -1;
    if (H5Lexists(f, "final", H5P_DEFAULT) <= 0) {
        drape_error_set(err, DRAPE_E_IO, path, 0, 0, NULL, "no /final state in the file");
        goto out;
    }
    g = H5Gopen2(f, "final", H5P_DEFAULT);
    if (g < 0) goto h5err;
    c->x = read_n3(g, "positions", &c->n);
    c->v = read_n3(g, "velocities", &nv);
    if (!c->x || !c->v || nv != c->n) {
        drape_error_set(err, DRAPE_E_IO, path, 0, 0, NULL,
                        "/final/positions and /final/velocities unreadable or of different sizes");
        goto out;
    }
    hid_t a = H5Aopen(g, "time_s", H5P_DEFAULT);
    if (a < 0) goto h5err;
    herr_t r = H5Aread(a, H5T_NATIVE_DOUBLE, &c->t_s);
    H5Aclose(a);
    if (r < 0) goto h5err;
    c->frames = H5Lexists(f, "times", H5P_DEFAULT) > 0 ? count_1d(f, "times") : 0;
    if (c->frames < 0) goto h5err;
    if (read_attrs(f, "run", &c->run, &c->n_run) != 0 ||
        read_attrs(f, "stats", &c->stats, &c->n_stats) != 0)
        goto h5err;
    c->fabric_yaml = read_root_string(f, "fabric_yaml");
    c->scene_yaml = read_root_string(f, "scene_yaml");
    rc = 0;
    goto out;
h5err:
    h5_fail(path, err, "cannot read the final state or attributes");
out:
    if (g >= 0) H5Gclose(g);
    H5Fclose(f);
    return rc;
}

int drape_h5_copy_frames(drape_h5 *h, const char *path, drape_error *err)
{
    const int n = h->L->n;
    int rc = -1, nf = 0;
    double *times = NULL, *en = NULL, *x = NULL, *v = NULL;
    hid_t f = open_readonly(path, err);
    if (f < 0) return -1;
    if (H5Lexists(f, "times", H5P_DEFAULT) <= 0) { /* no frames */
        rc = 0;
        goto out;
    }
    nf = count_1d(f, "times");
    if (nf < 0) goto h5err;
    times = drape_malloc(sizeof(double) * (size_t)(nf + 1));
    en = drape_malloc(sizeof(double) * (size_t)(N_ENERGY * nf + 1));
    if (!times || !en) goto nomem;
    if (read_1d(f, "times", times, nf) != 0) goto h5err;
    for (int k = 0; k < N_ENERGY; k++) {
        char name[64];
        double *col = drape_malloc(sizeof(double) * (size_t)(nf + 1));
        if (!col) goto nomem;
        snprintf(name, sizeof name, "energies/%s", energy_names[k]);
        int r = read_1d(f, name, col, nf);
        for (int i = 0; i < nf; i++) en[N_ENERGY * i + k] = r == 0 ? col[i] : NAN;
        drape_free(col);
    }
    for (int i = 0; i < nf; i++) {
        char name[64];
        int nx = -1, nv = -1;
        snprintf(name, sizeof name, "steps/%06d/positions", i);
        x = read_n3(f, name, &nx);
        snprintf(name, sizeof name, "steps/%06d/velocities", i);
        v = H5Lexists(f, name, H5P_DEFAULT) > 0 ? read_n3(f, name, &nv) : NULL;
        if (!x || nx != n || (v && nv != n)) {
            drape_error_set(err, DRAPE_E_IO, path, 0, 0, NULL,
                            "frame %d: /steps/%06d unreadable or not %d particles", i, i, n);
            goto out;
        }
        const double *e = en + N_ENERGY * i;
        drape_energies E = {e[1], e[2], e[3], e[4]};
        if (drape_h5_frame(h, times[i], x, v, e[0], &E, err) != 0) goto out;
        drape_free(x);
        drape_free(v);
        x = v = NULL;
    }
    rc = 0;
    goto out;
nomem:
    drape_error_set(err, DRAPE_E_NOMEM, path, 0, 0, NULL, "out of memory");
    goto out;
h5err:
    h5_fail(path, err, "cannot read the frames");
out:
    drape_free(times);
    drape_free(en);
    drape_free(x);
    drape_free(v);
    H5Fclose(f);
    return rc;
}
