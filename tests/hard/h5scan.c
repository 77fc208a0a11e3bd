/* h5scan.c: read a drape.h5 (docs/outputs.md) for the hard-case suite
 * (scripts/check-hard.sh, docs/stability.md) and print, one record a line:
 *
 *   nonfinite_data PATH COUNT       a float dataset with NaN/inf values
 *   nonfinite_attr PATH NAME        a float attribute that is NaN/inf
 *   frame K T EKIN ESTRETCH EBEND ESHEAR EGRAV STRAIN PSI
 *   final STRAIN PSI
 *   geometry L D                    L: largest extent of the rest lattice
 *                                   (m); D: largest rest distance of a
 *                                   particle from its nearest fixed one
 *   summary FRAMES DATASETS ATTRS
 *
 * STRAIN is the largest |l - l0| / l0 over the lattice edges (warp and weft
 * neighbours), PSI the largest turning angle pi - atan2(|u x w|, u . w)
 * over the bending hinges (docs/model.md 3.1, 3.2), both computed here from the
 * positions and the grid indices, independently of drape's model code.
 * Exit status 0 if the file could be read (whatever it contains), 1 if not.
 * Built by scripts/check-hard.sh with the hdf5-serial flags; not part of
 * the drape binary. */
#include <hdf5.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    int n;          /* particles */
    int ni, nj;     /* grid extent */
    int *id;        /* ni * nj: particle at (i, j), or -1 */
    double *x0;     /* rest positions, 3n */
    long ndata, nattr;
} scan;

/* Read a whole float dataset (any shape) as doubles; NULL if it is not one. */
static double *read_doubles(hid_t loc, const char *name, hsize_t *count)
{
    hid_t ds = H5Dopen2(loc, name, H5P_DEFAULT);
    if (ds < 0) return NULL;
    double *buf = NULL;
    hid_t ty = H5Dget_type(ds), sp = H5Dget_space(ds);
    if (ty >= 0 && sp >= 0 && H5Tget_class(ty) == H5T_FLOAT) {
        hssize_t m = H5Sget_simple_extent_npoints(sp);
        if (m >= 0) {
            buf = malloc(sizeof *buf * (size_t)(m > 0 ? m : 1));
            if (buf && H5Dread(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) < 0) {
                free(buf);
                buf = NULL;
            }
            if (buf) *count = (hsize_t)m;
        }
    }
    if (sp >= 0) H5Sclose(sp);
    if (ty >= 0) H5Tclose(ty);
    H5Dclose(ds);
    return buf;
}

static herr_t attr_cb(hid_t obj, const char *name, const H5A_info_t *info, void *data)
{
    const char *path = data;
    (void)info;
    hid_t a = H5Aopen(obj, name, H5P_DEFAULT);
    if (a < 0) return 0;
    hid_t ty = H5Aget_type(a), sp = H5Aget_space(a);
    if (ty >= 0 && sp >= 0 && H5Tget_class(ty) == H5T_FLOAT) {
        hssize_t m = H5Sget_simple_extent_npoints(sp);
        double *v = m > 0 ? malloc(sizeof *v * (size_t)m) : NULL;
        if (v && H5Aread(a, H5T_NATIVE_DOUBLE, v) >= 0)
            for (hssize_t k = 0; k < m; k++)
                if (!isfinite(v[k])) {
                    printf("nonfinite_attr %s %s\n", path, name);
                    break;
                }
        free(v);
    }
    if (sp >= 0) H5Sclose(sp);
    if (ty >= 0) H5Tclose(ty);
    H5Aclose(a);
    return 0;
}

static void scan_attrs(hid_t loc, const char *name, const char *path, scan *s)
{
    hid_t o = H5Oopen(loc, name, H5P_DEFAULT);
    if (o < 0) return;
    hsize_t idx = 0;
    H5Aiterate2(o, H5_INDEX_NAME, H5_ITER_NATIVE, &idx, attr_cb, (void *)path);
    s->nattr++;
    H5Oclose(o);
}

static herr_t link_cb(hid_t g, const char *name, const H5L_info_t *info, void *data)
{
    scan *s = data;
    char path[512];
    (void)info;
    snprintf(path, sizeof path, "/%s", name);
    scan_attrs(g, name, path, s);
    hsize_t m = 0;
    double *v = read_doubles(g, name, &m);
    if (v) {
        long bad = 0;
        for (hsize_t k = 0; k < m; k++)
            if (!isfinite(v[k])) bad++;
        if (bad) printf("nonfinite_data %s %ld\n", path, bad);
        s->ndata++;
        free(v);
    }
    return 0;
}

static int read_ints(hid_t f, const char *name, int *buf)
{
    hid_t ds = H5Dopen2(f, name, H5P_DEFAULT);
    if (ds < 0) return -1;
    herr_t r = H5Dread(ds, H5T_NATIVE_INT, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf);
    H5Dclose(ds);
    return r < 0 ? -1 : 0;
}

static double dist(const double *a, const double *b)
{
    double d0 = a[0] - b[0], d1 = a[1] - b[1], d2 = a[2] - b[2];
    return sqrt(d0 * d0 + d1 * d1 + d2 * d2);
}

static int at(const scan *s, int i, int j)
{
    if (i < 0 || j < 0 || i >= s->ni || j >= s->nj) return -1;
    return s->id[j * s->ni + i];
}

/* Largest edge strain and hinge turning angle of the positions x (3n). */
static void measure(const scan *s, const double *x, double *strain, double *psi)
{
    const double pi = acos(-1.0);
    double es = 0.0, ps = 0.0;
    for (int j = 0; j < s->nj; j++)
        for (int i = 0; i < s->ni; i++) {
            int p = at(s, i, j);
            if (p < 0) continue;
            for (int dir = 0; dir < 2; dir++) {
                int di = dir == 0, dj = dir == 1;
                int q = at(s, i + di, j + dj), r = at(s, i - di, j - dj);
                if (q >= 0) {
                    double l0 = dist(s->x0 + 3 * p, s->x0 + 3 * q);
                    double e = fabs(dist(x + 3 * p, x + 3 * q) - l0) / l0;
                    if (!(e <= es)) es = e; /* NaN propagates */
                }
                if (q >= 0 && r >= 0) {
                    double u[3], w[3], c[3];
                    for (int k = 0; k < 3; k++) {
                        u[k] = x[3 * r + k] - x[3 * p + k];
                        w[k] = x[3 * q + k] - x[3 * p + k];
                    }
                    c[0] = u[1] * w[2] - u[2] * w[1];
                    c[1] = u[2] * w[0] - u[0] * w[2];
                    c[2] = u[0] * w[1] - u[1] * w[0];
                    double a = pi - atan2(sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]),
                                          u[0] * w[0] + u[1] * w[1] + u[2] * w[2]);
                    if (!(a <= ps)) ps = a;
                }
            }
        }
    *strain = es;
    *psi = ps;
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: h5scan drape.h5\n");
        return 1;
    }
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    hid_t f = H5Fopen(argv[1], H5F_ACC_RDONLY, H5P_DEFAULT);
    if (f < 0) {
        fprintf(stderr, "h5scan: cannot open %s\n", argv[1]);
        return 1;
    }
    scan s;
    memset(&s, 0, sizeof s);
    scan_attrs(f, ".", "/", &s);
    H5Lvisit(f, H5_INDEX_NAME, H5_ITER_NATIVE, link_cb, &s);

    hsize_t m = 0;
    s.x0 = read_doubles(f, "/mesh/rest_positions", &m);
    s.n = (int)(m / 3);
    int *ij = s.x0 ? malloc(sizeof *ij * 2 * (size_t)(s.n > 0 ? s.n : 1)) : NULL;
    if (!ij || read_ints(f, "/mesh/grid_ij", ij) != 0) {
        fprintf(stderr, "h5scan: %s: no /mesh/rest_positions or /mesh/grid_ij\n", argv[1]);
        return 1;
    }
    for (int p = 0; p < s.n; p++) {
        if (ij[2 * p] + 1 > s.ni) s.ni = ij[2 * p] + 1;
        if (ij[2 * p + 1] + 1 > s.nj) s.nj = ij[2 * p + 1] + 1;
    }
    s.id = malloc(sizeof *s.id * (size_t)s.ni * (size_t)s.nj);
    if (!s.id) return 1;
    for (int k = 0; k < s.ni * s.nj; k++) s.id[k] = -1;
    for (int p = 0; p < s.n; p++) s.id[ij[2 * p + 1] * s.ni + ij[2 * p]] = p;

    unsigned char *fixed = malloc((size_t)(s.n > 0 ? s.n : 1));
    hid_t dsf = H5Dopen2(f, "/mesh/fixed", H5P_DEFAULT);
    if (!fixed || dsf < 0 ||
        H5Dread(dsf, H5T_NATIVE_UCHAR, H5S_ALL, H5S_ALL, H5P_DEFAULT, fixed) < 0) {
        fprintf(stderr, "h5scan: %s: no /mesh/fixed\n", argv[1]);
        return 1;
    }
    H5Dclose(dsf);
    double ext = 0.0, dmax = 0.0;
    for (int k = 0; k < 3; k++) {
        double lo = INFINITY, hi = -INFINITY;
        for (int p = 0; p < s.n; p++) {
            if (s.x0[3 * p + k] < lo) lo = s.x0[3 * p + k];
            if (s.x0[3 * p + k] > hi) hi = s.x0[3 * p + k];
        }
        if (s.n > 0 && hi - lo > ext) ext = hi - lo;
    }
    for (int p = 0; p < s.n; p++) {
        double dmin = INFINITY;
        for (int q = 0; q < s.n; q++)
            if (fixed[q]) {
                double d = dist(s.x0 + 3 * p, s.x0 + 3 * q);
                if (d < dmin) dmin = d;
            }
        if (dmin > dmax) dmax = dmin;
    }
    printf("geometry %.17g %.17g\n", ext, dmax);
    free(fixed);

    hsize_t nt = 0;
    double *t = read_doubles(f, "/times", &nt);
    const char *en[5] = {"/energies/kinetic", "/energies/stretch", "/energies/bend",
                         "/energies/shear", "/energies/gravity"};
    double *e[5];
    for (int k = 0; k < 5; k++) {
        hsize_t c = 0;
        e[k] = read_doubles(f, en[k], &c);
        if (e[k] && c != nt) {
            free(e[k]);
            e[k] = NULL;
        }
    }
    for (hsize_t fr = 0; t && fr < nt; fr++) {
        char name[64];
        snprintf(name, sizeof name, "/steps/%06d/positions", (int)fr);
        hsize_t c = 0;
        double *x = read_doubles(f, name, &c);
        double strain = NAN, psi = NAN;
        if (x && (int)(c / 3) == s.n) measure(&s, x, &strain, &psi);
        free(x);
        printf("frame %d %.17g", (int)fr, t[fr]);
        for (int k = 0; k < 5; k++) printf(" %.17g", e[k] ? e[k][fr] : NAN);
        printf(" %.17g %.17g\n", strain, psi);
    }
    hsize_t c = 0;
    double *x = read_doubles(f, "/final/positions", &c);
    if (x && (int)(c / 3) == s.n) {
        double strain, psi;
        measure(&s, x, &strain, &psi);
        printf("final %.17g %.17g\n", strain, psi);
    }
    printf("summary %d %ld %ld\n", (int)nt, s.ndata, s.nattr);
    free(x);
    free(t);
    for (int k = 0; k < 5; k++) free(e[k]);
    free(s.id);
    free(ij);
    free(s.x0);
    H5Fclose(f);
    return 0;
}
