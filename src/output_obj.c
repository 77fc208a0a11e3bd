/* output_obj.c: Wavefront OBJ frames (output.h; docs/outputs.md).
 *
 * Axes: renderers (Blender's importer by default) expect Y up, drape has
 * z up, so a point (x, y, z) is written as
 *     (X, Y, Z) = (x, z, -y),                                            (1)
 * a proper rotation (-90 deg about x): handedness and face winding are
 * kept, and a face that turns counter-clockwise seen from +z (drape_quads_new
 * orders them so at rest) faces +Y.
 * Texture coordinates come from the rest lattice:
 *     u = (x0 - xmin) / (xmax - xmin),  v = (y0 - ymin) / (ymax - ymin). (2)
 * Vertex normals are the normalised sums of the vector areas of the quads
 * around a vertex,
 *     N_quad = 1/2 (c - a) x (d - b)                                     (3)
 * (exact for a planar quad, the mean of the two triangulations otherwise),
 * so larger faces weigh more; a vertex with no face or a zero sum gets the
 * rest normal (0, 1, 0) in OBJ axes.
 */
#include "drape/output.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "drape/alloc.h"
#include "drape/drape.h"

#define OBJ_NAME_MAX 256

struct drape_obj {
    const drape_lattice *L;
    char *dir;
    char fabric[OBJ_NAME_MAX], scene[OBJ_NAME_MAX];
    int n_quads;
    int *quads;   /* 4 per quad */
    double *uv;   /* 2n */
    double *nrm;  /* 3n workspace */
    char **written; /* paths of the files this handle wrote (drape_obj_discard) */
    int n_written, cap_written;
};

/* Copy a name for a one-line comment: control characters become spaces. */
static void copy_name(char *dst, const char *src)
{
    size_t k = 0;
    if (!src) src = "";
    for (; src[k] && k + 1 < OBJ_NAME_MAX; k++)
        dst[k] = (unsigned char)src[k] < 0x20 ? ' ' : src[k];
    dst[k] = 0;
}

static int check_dir(const char *dir, drape_error *err)
{
    struct stat st;
    if (stat(dir, &st) != 0)
        return drape_error_set(err, DRAPE_E_IO, dir, 0, 0, NULL,
                               "output directory: %s", strerror(errno));
    if (!S_ISDIR(st.st_mode))
        return drape_error_set(err, DRAPE_E_IO, dir, 0, 0, NULL,
                               "output directory: not a directory");
    if (access(dir, W_OK | X_OK) != 0)
        return drape_error_set(err, DRAPE_E_IO, dir, 0, 0, NULL,
                               "output directory: cannot write into it: %s", strerror(errno));
    return 0;
}

void drape_obj_free(drape_obj *o)
{
    if (!o) return;
    for (int k = 0; k < o->n_written; k++) drape_free(o->written[k]);
    drape_free(o->written);
    drape_free(o->dir);
    drape_free(o->quads);
    drape_free(o->uv);
    drape_free(o->nrm);
    drape_free(o);
}

drape_obj *drape_obj_new(const char *dir, const drape_lattice *L,
                         const char *fabric, const char *scene,
                         drape_error *err)
{
    drape_obj *o = NULL;
    if (check_dir(dir, err)) return NULL;
    o = drape_calloc(1, sizeof *o);
    if (!o) goto nomem;
    o->L = L;
    copy_name(o->fabric, fabric);
    copy_name(o->scene, scene);
    o->dir = drape_strdup(dir);
    if (!o->dir) goto nomem;
    o->quads = drape_quads_new(L, &o->n_quads, err);
    if (!o->quads) goto fail;
    o->uv = drape_malloc(sizeof *o->uv * (size_t)(2 * L->n + 1));
    o->nrm = drape_malloc(sizeof *o->nrm * (size_t)(3 * L->n + 1));
    if (!o->uv || !o->nrm) goto nomem;
    double lo[2] = {0, 0}, hi[2] = {0, 0};
    for (int i = 0; i < L->n; i++)
        for (int c = 0; c < 2; c++) {
            double v = L->x0[3 * i + c];
            if (i == 0 || v < lo[c]) lo[c] = v;
            if (i == 0 || v > hi[c]) hi[c] = v;
        }
    for (int i = 0; i < L->n; i++)
        for (int c = 0; c < 2; c++)
            o->uv[2 * i + c] = hi[c] > lo[c] ? (L->x0[3 * i + c] - lo[c]) / (hi[c] - lo[c]) : 0.0;
    return o;
nomem:
    drape_error_set(err, DRAPE_E_NOMEM, dir, 0, 0, NULL, "OBJ output: out of memory");
fail:
    drape_obj_free(o);
    return NULL;
}

static void vertex_normals(drape_obj *o, const double *x)
{
    const int n = o->L->n;
    memset(o->nrm, 0, sizeof *o->nrm * (size_t)(3 * n));
    for (int k = 0; k < o->n_quads; k++) {
        const int *q = o->quads + 4 * k;
        const double *a = x + 3 * q[0], *b = x + 3 * q[1];
        const double *c = x + 3 * q[2], *d = x + 3 * q[3];
        double p[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double r[3] = {d[0] - b[0], d[1] - b[1], d[2] - b[2]};
        double nq[3] = {0.5 * (p[1] * r[2] - p[2] * r[1]), 0.5 * (p[2] * r[0] - p[0] * r[2]),
                        0.5 * (p[0] * r[1] - p[1] * r[0])};
        for (int m = 0; m < 4; m++)
            for (int e = 0; e < 3; e++) o->nrm[3 * q[m] + e] += nq[e];
    }
    for (int i = 0; i < n; i++) {
        double *v = o->nrm + 3 * i;
        double s = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        if (s > 0.0 && isfinite(s)) {
            v[0] /= s; v[1] /= s; v[2] /= s;
        } else {
            v[0] = 0.0; v[1] = 0.0; v[2] = 1.0;
        }
    }
}

void drape_obj_discard(drape_obj *o)
{
    if (!o) return;
    for (int k = 0; k < o->n_written; k++) unlink(o->written[k]);
    drape_obj_free(o);
}

/* DIR/frame_NNNNNN.obj of frame k, newly allocated (NULL: no memory). */
static char *frame_path(const drape_obj *o, int k)
{
    size_t len = strlen(o->dir) + 32;
    char *path = drape_malloc(len);
    if (path) snprintf(path, len, "%s/frame_%06d.obj", o->dir, k);
    return path;
}

int drape_obj_remove_stale(drape_obj *o, int first)
{
    if (!o) return 0;
    int n = 0;
    for (int k = first; k >= 0 && k < 1000000; k++) {
        char *path = frame_path(o, k);
        if (!path) break;
        int gone = unlink(path) == 0;
        drape_free(path);
        if (!gone) break; /* the frames are numbered 0, 1, ... */
        n++;
    }
    return n;
}

int drape_obj_written(const drape_obj *o)
{
    return o ? o->n_written : 0;
}

/* Remember a path for drape_obj_discard (once per path). */
static int remember(drape_obj *o, const char *path)
{
    for (int k = o->n_written - 1; k >= 0; k--)
        if (strcmp(o->written[k], path) == 0) return 0;
    if (o->n_written == o->cap_written) {
        int cap = o->cap_written ? 2 * o->cap_written : 64;
        char **w = drape_realloc(o->written, sizeof *w * (size_t)cap);
        if (!w) return -1;
        o->written = w;
        o->cap_written = cap;
    }
    if (!(o->written[o->n_written] = drape_strdup(path))) return -1;
    o->n_written++;
    return 0;
}

int drape_obj_write(drape_obj *o, const char *path, double t_s,
                    const double *x, drape_error *err)
{
    const drape_lattice *L = o->L;
    char *tmp = NULL;
    FILE *f = NULL;
    int fd = -1, rc = -1, written = 0;
    for (int i = 0; i < 3 * L->n; i++)
        if (!isfinite(x[i]))
            return drape_error_set(err, DRAPE_E_NUMERIC, path, 0, 0, NULL,
                                   "OBJ frame at t = %g s: particle %d has a "
                                   "non-finite position", t_s, i / 3);
    size_t len = strlen(path) + 32;
    tmp = drape_malloc(len);
    if (!tmp) {
        drape_error_set(err, DRAPE_E_NOMEM, path, 0, 0, NULL, "out of memory");
        goto out;
    }
    snprintf(tmp, len, "%s.%ld.tmp", path, (long)getpid());
    /* never write through a stale temporary or a symlink */
    unlink(tmp);
    fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW, 0666);
    if (fd >= 0) written = 1;
    if (fd < 0 || !(f = fdopen(fd, "w"))) {
        drape_error_set(err, DRAPE_E_IO, path, 0, 0, NULL, "cannot create %s: %s",
                        tmp, strerror(errno));
        goto out;
    }
    fd = -1; /* owned by f */
    vertex_normals(o, x);
    fprintf(f, "# drape frame, t_s = %.17g\n", t_s);
    fprintf(f, "# units: m; axes: OBJ (X, Y, Z) = drape (x, z, -y), Y up\n");
    fprintf(f, "# fabric: %s\n# scene: %s\n", o->fabric, o->scene);
    fprintf(f, "# particles: %d, quads: %d\n", L->n, o->n_quads);
    fprintf(f, "o drape\n");
    for (int i = 0; i < L->n; i++) {
        const double *p = x + 3 * i;
        fprintf(f, "v %.9g %.9g %.9g\n", p[0], p[2], -p[1] + 0.0);
    }
    for (int i = 0; i < L->n; i++)
        fprintf(f, "vt %.9g %.9g\n", o->uv[2 * i], o->uv[2 * i + 1]);
    for (int i = 0; i < L->n; i++) {
        const double *nv = o->nrm + 3 * i;
        fprintf(f, "vn %.7g %.7g %.7g\n", nv[0], nv[2], -nv[1] + 0.0);
    }
    for (int k = 0; k < o->n_quads; k++) {
        const int *q = o->quads + 4 * k;
        fprintf(f, "f %d/%d/%d %d/%d/%d %d/%d/%d %d/%d/%d\n", q[0] + 1, q[0] + 1,
                q[0] + 1, q[1] + 1, q[1] + 1, q[1] + 1, q[2] + 1, q[2] + 1, q[2] + 1,
                q[3] + 1, q[3] + 1, q[3] + 1);
    }
    if (fflush(f) != 0 || ferror(f) || fsync(fileno(f)) != 0) {
        drape_error_set(err, DRAPE_E_IO, path, 0, 0, NULL, "cannot write %s: %s", tmp,
                        strerror(errno));
        goto out;
    }
    int cr = fclose(f);
    f = NULL;
    if (cr != 0) {
        drape_error_set(err, DRAPE_E_IO, path, 0, 0, NULL, "cannot write %s: %s", tmp,
                        strerror(errno));
        goto out;
    }
    if (rename(tmp, path) != 0) {
        drape_error_set(err, DRAPE_E_IO, path, 0, 0, NULL, "cannot rename %s: %s", tmp,
                        strerror(errno));
        goto out;
    }
    written = 0;
    if (remember(o, path) != 0) { /* a file drape_obj_discard would not know */
        unlink(path);
        drape_error_set(err, DRAPE_E_NOMEM, path, 0, 0, NULL, "out of memory");
        goto out;
    }
    rc = 0;
out:
    if (f) fclose(f);
    if (fd >= 0) close(fd);
    if (written && tmp) unlink(tmp);
    drape_free(tmp);
    return rc;
}

int drape_obj_frame(drape_obj *o, int frame, double t_s, const double *x,
                    drape_error *err)
{
    char *path = frame_path(o, frame);
    if (!path)
        return drape_error_set(err, DRAPE_E_NOMEM, o->dir, 0, 0, NULL, "out of memory");
    int rc = drape_obj_write(o, path, t_s, x, err);
    drape_free(path);
    return rc;
}
