/* check_output.c: OBJ frames and drape.h5/drape.xmf, read back.
 *
 * A small hand-built lattice (5 x 4 grid with one corner point removed)
 * is written and parsed back: OBJ positions against the documented axis
 * map (x, z, -y) to print precision, normals of a tilted flat sheet against
 * the analytic normal, texture coordinates against (x0 - xmin)/(xmax -
 * xmin); HDF5 datasets bit for bit through the HDF5 API; no temporary file
 * may remain. */
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <hdf5.h>

#include "drape/alloc.h"
#include "drape/output.h"
#include "testutil.h"

#define NI 5
#define NJ 4
#define SIG 0.01

/* 5 x 4 points at spacing 1 cm from (0.1, -0.2), point (4, 3) removed:
 * 19 particles, 4 x 3 - 1 = 11 quads; particles with i == 0 fixed. */
static drape_lattice *tl_small(void)
{
    drape_lattice *L = drape_calloc(1, sizeof *L);
    ck_assert_ptr_nonnull(L);
    L->sigma = SIG;
    L->ni = NI;
    L->nj = NJ;
    L->grid = drape_calloc(NI * NJ, sizeof *L->grid);
    L->gi = drape_calloc(NI * NJ, sizeof *L->gi);
    L->gj = drape_calloc(NI * NJ, sizeof *L->gj);
    L->x0 = drape_calloc(3 * NI * NJ, sizeof *L->x0);
    L->fixed = drape_calloc(NI * NJ, 1);
    for (int j = 0; j < NJ; j++)
        for (int i = 0; i < NI; i++) {
            if (i == NI - 1 && j == NJ - 1) {
                L->grid[j * NI + i] = -1;
                continue;
            }
            int id = L->n++;
            L->grid[j * NI + i] = id;
            L->gi[id] = i;
            L->gj[id] = j;
            L->x0[3 * id] = 0.1 + i * SIG;
            L->x0[3 * id + 1] = -0.2 + j * SIG;
            L->x0[3 * id + 2] = 0.0;
            L->fixed[id] = i == 0;
        }
    L->area_nominal = 0.04 * 0.03;
    return L;
}

static void tl_free(drape_lattice *L)
{
    drape_free(L->grid);
    drape_free(L->gi);
    drape_free(L->gj);
    drape_free(L->x0);
    drape_free(L->fixed);
    drape_free(L);
}

/* A fresh directory under the scratch directory. */
static const char *subdir(const char *name)
{
    static char p[4][512];
    static int slot;
    char *s = p[slot++ % 4];
    snprintf(s, 512, "%s/%s", tu_scratch_dir(), name);
    ck_assert_msg(mkdir(s, 0700) == 0 || errno == EEXIST, "mkdir %s", s);
    return s;
}

/* Number of directory entries whose name contains `part`. */
static int count_entries(const char *dir, const char *part)
{
    DIR *d = opendir(dir);
    ck_assert_ptr_nonnull(d);
    int c = 0;
    struct dirent *e;
    while ((e = readdir(d)))
        if (strstr(e->d_name, part)) c++;
    closedir(d);
    return c;
}

static char *slurp(const char *path)
{
    FILE *f = fopen(path, "rb");
    ck_assert_msg(f != NULL, "cannot open %s", path);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *buf = malloc((size_t)n + 1);
    ck_assert(fread(buf, 1, (size_t)n, f) == (size_t)n);
    buf[n] = 0;
    fclose(f);
    return buf;
}

static int count_str(const char *s, const char *pat)
{
    int c = 0;
    for (const char *p = strstr(s, pat); p; p = strstr(p + 1, pat)) c++;
    return c;
}

/* ---------------------------------------------------------------- OBJ */

typedef struct obj_data {
    int nv, nvt, nvn, nf;
    double v[64][3], vt[64][2], vn[64][3];
    int f[64][4];
    double t;
} obj_data;

static void parse_obj(const char *path, obj_data *o)
{
    memset(o, 0, sizeof *o);
    o->t = NAN;
    FILE *f = fopen(path, "r");
    ck_assert_msg(f != NULL, "cannot open %s", path);
    char line[512];
    while (fgets(line, sizeof line, f)) {
        if (!strncmp(line, "v ", 2)) {
            ck_assert(sscanf(line + 2, "%lf %lf %lf", &o->v[o->nv][0], &o->v[o->nv][1],
                             &o->v[o->nv][2]) == 3);
            o->nv++;
        } else if (!strncmp(line, "vt ", 3)) {
            ck_assert(sscanf(line + 3, "%lf %lf", &o->vt[o->nvt][0], &o->vt[o->nvt][1]) == 2);
            o->nvt++;
        } else if (!strncmp(line, "vn ", 3)) {
            ck_assert(sscanf(line + 3, "%lf %lf %lf", &o->vn[o->nvn][0], &o->vn[o->nvn][1],
                             &o->vn[o->nvn][2]) == 3);
            o->nvn++;
        } else if (!strncmp(line, "f ", 2)) {
            int a[12];
            ck_assert(sscanf(line + 2, "%d/%d/%d %d/%d/%d %d/%d/%d %d/%d/%d", &a[0], &a[1],
                             &a[2], &a[3], &a[4], &a[5], &a[6], &a[7], &a[8], &a[9], &a[10],
                             &a[11]) == 12);
            for (int k = 0; k < 4; k++) {
                ck_assert_int_eq(a[3 * k], a[3 * k + 1]);
                ck_assert_int_eq(a[3 * k], a[3 * k + 2]);
                o->f[o->nf][k] = a[3 * k];
            }
            o->nf++;
        } else if (!strncmp(line, "# drape frame, t_s = ", 21)) {
            o->t = strtod(line + 21, NULL);
        }
    }
    fclose(f);
}

START_TEST(test_obj_roundtrip)
{
    drape_lattice *L = tl_small();
    const char *dir = subdir("obj");
    drape_error err;
    drape_error_clear(&err);
    drape_obj *o = drape_obj_new(dir, L, "cotton\nbreen", "cusick", &err);
    ck_assert_ptr_nonnull(o);
    /* a flat sheet tilted by alpha about the x axis: y' = y cos a,
     * z = y sin a; its upward normal is (0, -sin a, cos a) */
    const double al = 0.3;
    double x[3 * 19];
    for (int i = 0; i < L->n; i++) {
        x[3 * i] = L->x0[3 * i];
        x[3 * i + 1] = L->x0[3 * i + 1] * cos(al);
        x[3 * i + 2] = L->x0[3 * i + 1] * sin(al);
    }
    ck_assert_int_eq(drape_obj_frame(o, 7, 0.35, x, &err), 0);
    char path[600];
    snprintf(path, sizeof path, "%s/frame_000007.obj", dir);
    obj_data d;
    parse_obj(path, &d);
    ck_assert_int_eq(d.nv, 19);
    ck_assert_int_eq(d.nvt, 19);
    ck_assert_int_eq(d.nvn, 19);
    ck_assert_int_eq(d.nf, 11);
    ck_assert_close_rel(d.t, 0.35, 1e-15);
    for (int i = 0; i < 19; i++) {
        /* OBJ (X, Y, Z) = (x, z, -y), 9 significant digits */
        ck_assert_close_abs(d.v[i][0], x[3 * i], 1e-9 * 0.3);
        ck_assert_close_abs(d.v[i][1], x[3 * i + 2], 1e-9 * 0.3);
        ck_assert_close_abs(d.v[i][2], -x[3 * i + 1], 1e-9 * 0.3);
        /* normal (0, -sin a, cos a) -> (0, cos a, sin a) */
        ck_assert_close_abs(d.vn[i][0], 0.0, 1e-6);
        ck_assert_close_abs(d.vn[i][1], cos(al), 1e-6);
        ck_assert_close_abs(d.vn[i][2], sin(al), 1e-6);
        /* u = i / 4, v = j / 3 */
        ck_assert_close_abs(d.vt[i][0], L->gi[i] / 4.0, 1e-9);
        ck_assert_close_abs(d.vt[i][1], L->gj[i] / 3.0, 1e-9);
    }
    /* faces: valid 1-based ids, counter-clockwise about +Y in OBJ axes
     * (seen from above: (Z, X) plane), i.e. vector area along +Y */
    for (int k = 0; k < d.nf; k++) {
        double ay = 0;
        for (int c = 0; c < 4; c++) {
            int a = d.f[k][c], b = d.f[k][(c + 1) % 4];
            ck_assert(a >= 1 && a <= 19);
            ay += d.v[a - 1][2] * d.v[b - 1][0] - d.v[a - 1][0] * d.v[b - 1][2];
        }
        ck_assert_close_rel(0.5 * ay, SIG * SIG * cos(al), 1e-6);
    }
    /* the header keeps names on one line */
    char *text = slurp(path);
    ck_assert_ptr_nonnull(strstr(text, "# fabric: cotton breen\n"));
    ck_assert_ptr_nonnull(strstr(text, "# scene: cusick\n"));
    free(text);
    ck_assert_int_eq(count_entries(dir, ".tmp"), 0);
    ck_assert_int_eq(count_entries(dir, "frame_"), 1);
    /* rewriting a frame replaces it */
    ck_assert_int_eq(drape_obj_frame(o, 7, 0.5, L->x0, &err), 0);
    parse_obj(path, &d);
    ck_assert_close_rel(d.t, 0.5, 1e-15);
    ck_assert_close_abs(d.v[18][1], 0.0, 0.0);
    drape_obj_free(o);
    tl_free(L);
}
END_TEST

START_TEST(test_obj_errors)
{
    drape_lattice *L = tl_small();
    drape_error err;
    drape_error_clear(&err);
    char missing[600];
    snprintf(missing, sizeof missing, "%s/no/such/dir", tu_scratch_dir());
    ck_assert_ptr_null(drape_obj_new(missing, L, NULL, NULL, &err));
    ck_assert_int_eq(err.kind, DRAPE_E_IO);
    ck_assert_str_eq(err.file, missing);
    const char *dir = subdir("objerr");
    drape_error_clear(&err);
    drape_obj *o = drape_obj_new(dir, L, NULL, NULL, &err);
    ck_assert_ptr_nonnull(o);
    double x[3 * 19];
    memcpy(x, L->x0, sizeof x);
    x[10] = NAN;
    ck_assert_int_eq(drape_obj_frame(o, 0, 0.0, x, &err), -1);
    ck_assert_int_eq(err.kind, DRAPE_E_NUMERIC);
    ck_assert_int_eq(count_entries(dir, "frame_"), 0);
    drape_obj_free(o);
    /* the allocation hook: every failure is reported, nothing leaks */
    int ok = 0;
    for (long k = 1; k < 20 && !ok; k++) {
        drape_error_clear(&err);
        drape_alloc_fail_at(k);
        o = drape_obj_new(dir, L, NULL, NULL, &err);
        drape_alloc_fail_at(0);
        if (o) {
            drape_obj_free(o);
            ok = 1;
        } else {
            ck_assert_int_eq(err.kind, DRAPE_E_NOMEM);
        }
    }
    ck_assert(ok);
    tl_free(L);
}
END_TEST

/* --------------------------------------------------------------- HDF5 */

static char *read_str_attr(hid_t loc, const char *name)
{
    hid_t a = H5Aopen(loc, name, H5P_DEFAULT);
    ck_assert_msg(a >= 0, "attribute %s missing", name);
    hid_t t = H5Aget_type(a); /* variable-length UTF-8 string */
    ck_assert(H5Tis_variable_str(t) > 0);
    char *s = NULL;
    ck_assert(H5Aread(a, t, &s) >= 0);
    char *copy = strdup(s);
    H5free_memory(s);
    H5Tclose(t);
    H5Aclose(a);
    return copy;
}

static double read_num_attr(hid_t loc, const char *obj, const char *name)
{
    double v = NAN;
    hid_t a = H5Aopen_by_name(loc, obj, name, H5P_DEFAULT, H5P_DEFAULT);
    ck_assert_msg(a >= 0, "attribute %s of %s missing", name, obj);
    ck_assert(H5Aread(a, H5T_NATIVE_DOUBLE, &v) >= 0);
    H5Aclose(a);
    return v;
}

/* Read a whole dataset of doubles (n numbers expected). */
static void read_doubles(hid_t f, const char *name, double *out, hsize_t n)
{
    hid_t ds = H5Dopen2(f, name, H5P_DEFAULT);
    ck_assert_msg(ds >= 0, "dataset %s missing", name);
    hid_t sp = H5Dget_space(ds);
    ck_assert_int_eq((long)H5Sget_simple_extent_npoints(sp), (long)n);
    H5Sclose(sp);
    if (n) ck_assert(H5Dread(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, out) >= 0);
    H5Dclose(ds);
}

START_TEST(test_h5_roundtrip)
{
    drape_lattice *L = tl_small();
    const char *dir = subdir("h5");
    drape_error err;
    drape_error_clear(&err);
    drape_h5 *h = drape_h5_open(dir, L, &err);
    ck_assert_ptr_nonnull(h);
    double x[3][3 * 19], v[3 * 19];
    srand(7);
    for (int f = 0; f < 3; f++)
        for (int i = 0; i < 3 * 19; i++) x[f][i] = L->x0[i] + 1e-3 * rand() / RAND_MAX - 5e-4 * f;
    for (int i = 0; i < 3 * 19; i++) v[i] = 0.1 * rand() / RAND_MAX;
    const double t[3] = {0.0, 0.05, 0.1};
    for (int f = 0; f < 3; f++) {
        drape_energies E = {1.0 + f, 2.0 + f, 3.0 + f, -4.0 - f};
        ck_assert_int_eq(drape_h5_frame(h, t[f], x[f], f == 1 ? NULL : v, 0.5 * f, &E, &err), 0);
    }
    ck_assert_int_eq(drape_h5_frames(h), 3);
    /* nothing but temporary files before the close */
    ck_assert_int_eq(count_entries(dir, "drape.h5"), 1);
    ck_assert_int_eq(count_entries(dir, ".tmp"), 1);
    const drape_kv stats[] = {{"steps", NULL, 123}, {"integrator", "arkode-imex", 0},
                              {"wall_s", NULL, 1.25}};
    const char *fab = "fabric: cotton\nweight: 20 mg/cm^2 # \"quoted\" & <tags>\n";
    const char *scn = "scene: cusick\n";
    drape_h5_final fin = {0.1, x[2], v, stats, 3, fab, scn, NULL, 0};
    ck_assert_int_eq(drape_h5_close(h, &fin, &err), 0);
    ck_assert_int_eq(count_entries(dir, ".tmp"), 0);

    char path[600];
    snprintf(path, sizeof path, "%s/drape.h5", dir);
    hid_t F = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    ck_assert(F >= 0);
    double buf[3 * 19];
    for (int f = 0; f < 3; f++) {
        char name[64];
        snprintf(name, sizeof name, "/steps/%06d/positions", f);
        read_doubles(F, name, buf, 3 * 19);
        ck_assert(memcmp(buf, x[f], sizeof buf) == 0);
        ck_assert(read_num_attr(F, name, "time_s") == t[f]);
        snprintf(name, sizeof name, "/steps/%06d/velocities", f);
        ck_assert_int_eq(H5Lexists(F, name, H5P_DEFAULT) > 0, f != 1);
    }
    read_doubles(F, "/steps/000002/velocities", buf, 3 * 19);
    ck_assert(memcmp(buf, v, sizeof buf) == 0);
    double tt[3], e[3];
    read_doubles(F, "/times", tt, 3);
    ck_assert(memcmp(tt, t, sizeof tt) == 0);
    read_doubles(F, "/energies/kinetic", e, 3);
    ck_assert(e[0] == 0.0 && e[1] == 0.5 && e[2] == 1.0);
    read_doubles(F, "/energies/gravity", e, 3);
    ck_assert(e[0] == -4.0 && e[1] == -5.0 && e[2] == -6.0);
    read_doubles(F, "/energies/shear", e, 3);
    ck_assert(e[2] == 5.0);
    read_doubles(F, "/final/positions", buf, 3 * 19);
    ck_assert(memcmp(buf, x[2], sizeof buf) == 0);
    read_doubles(F, "/mesh/rest_positions", buf, 3 * 19);
    ck_assert(memcmp(buf, L->x0, sizeof buf) == 0);
    ck_assert(read_num_attr(F, "/mesh", "sigma_m") == SIG);
    /* quads: 11 of them, corners at sigma from their neighbours */
    int q[11][4];
    hid_t ds = H5Dopen2(F, "/mesh/quads", H5P_DEFAULT);
    hid_t sp = H5Dget_space(ds);
    ck_assert_int_eq((int)H5Sget_simple_extent_npoints(sp), 44);
    H5Sclose(sp);
    ck_assert(H5Dread(ds, H5T_NATIVE_INT, H5S_ALL, H5S_ALL, H5P_DEFAULT, q) >= 0);
    H5Dclose(ds);
    for (int k = 0; k < 11; k++)
        for (int c = 0; c < 4; c++) {
            int a = q[k][c], b = q[k][(c + 1) % 4];
            ck_assert(a >= 0 && a < 19);
            double dx = L->x0[3 * a] - L->x0[3 * b], dy = L->x0[3 * a + 1] - L->x0[3 * b + 1];
            ck_assert_close_rel(hypot(dx, dy), SIG, 1e-9);
        }
    ck_assert(read_num_attr(F, "/stats", "steps") == 123);
    ck_assert(read_num_attr(F, "/stats", "wall_s") == 1.25);
    hid_t g = H5Gopen2(F, "/stats", H5P_DEFAULT);
    char *s = read_str_attr(g, "integrator");
    ck_assert_str_eq(s, "arkode-imex");
    free(s);
    H5Gclose(g);
    s = read_str_attr(F, "fabric_yaml");
    ck_assert_str_eq(s, fab);
    free(s);
    s = read_str_attr(F, "scene_yaml");
    ck_assert_str_eq(s, scn);
    free(s);
    H5Fclose(F);

    /* the sidecar: one grid per frame, relative paths, balanced tags */
    snprintf(path, sizeof path, "%s/drape.xmf", dir);
    char *xmf = slurp(path);
    ck_assert_ptr_nonnull(strstr(xmf, "CollectionType=\"Temporal\""));
    ck_assert_int_eq(count_str(xmf, "<Grid Name=\"step_"), 3);
    ck_assert_int_eq(count_str(xmf, "<Grid "), count_str(xmf, "</Grid>"));
    ck_assert_int_eq(count_str(xmf, "<DataItem "), count_str(xmf, "</DataItem>"));
    ck_assert_int_eq(count_str(xmf, "TopologyType=\"Quadrilateral\" NumberOfElements=\"11\""), 3);
    ck_assert_int_eq(count_str(xmf, ">drape.h5:/mesh/quads</DataItem>"), 3);
    ck_assert_ptr_nonnull(strstr(xmf, ">drape.h5:/steps/000002/positions</DataItem>"));
    ck_assert_ptr_nonnull(strstr(xmf, ">drape.h5:/steps/000000/velocities</DataItem>"));
    ck_assert_ptr_null(strstr(xmf, "/steps/000001/velocities"));
    ck_assert_ptr_nonnull(strstr(xmf, "<Time Value=\"0.050000000000000003\"/>"));
    ck_assert_ptr_nonnull(strstr(xmf, "Dimensions=\"19 3\""));
    ck_assert_ptr_null(strstr(xmf, dir)); /* no absolute path */
    free(xmf);
    tl_free(L);
}
END_TEST

START_TEST(test_h5_discard_and_errors)
{
    drape_lattice *L = tl_small();
    const char *dir = subdir("h5discard");
    drape_error err;
    drape_error_clear(&err);
    drape_h5 *h = drape_h5_open(dir, L, &err);
    ck_assert_ptr_nonnull(h);
    ck_assert_int_eq(drape_h5_frame(h, 0.0, L->x0, NULL, 0.0, NULL, &err), 0);
    double x[3 * 19];
    memcpy(x, L->x0, sizeof x);
    x[5] = INFINITY;
    ck_assert_int_eq(drape_h5_frame(h, 0.1, x, NULL, 0.0, NULL, &err), -1);
    ck_assert_int_eq(err.kind, DRAPE_E_NUMERIC);
    drape_h5_discard(h);
    ck_assert_int_eq(count_entries(dir, "drape"), 0);
    drape_h5_discard(NULL);

    char missing[600];
    snprintf(missing, sizeof missing, "%s/missing", tu_scratch_dir());
    drape_error_clear(&err);
    ck_assert_ptr_null(drape_h5_open(missing, L, &err));
    ck_assert_int_eq(err.kind, DRAPE_E_IO);
    ck_assert_str_eq(err.file, missing);

    /* no frames: empty /times, the sidecar shows the rest mesh */
    dir = subdir("h5empty");
    drape_error_clear(&err);
    h = drape_h5_open(dir, L, &err);
    ck_assert_ptr_nonnull(h);
    ck_assert_int_eq(drape_h5_close(h, NULL, &err), 0);
    char path[600];
    snprintf(path, sizeof path, "%s/drape.h5", dir);
    hid_t F = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    ck_assert(F >= 0);
    read_doubles(F, "/times", NULL, 0);
    ck_assert(H5Aexists(F, "fabric_yaml") == 0);
    H5Fclose(F);
    snprintf(path, sizeof path, "%s/drape.xmf", dir);
    char *xmf = slurp(path);
    ck_assert_ptr_nonnull(strstr(xmf, "drape.h5:/mesh/rest_positions"));
    free(xmf);
    ck_assert_int_eq(count_entries(dir, ".tmp"), 0);
    tl_free(L);
}
END_TEST

/* drape_obj_discard removes exactly the frames its handle wrote: not an
 * earlier file of the directory (issue 7: a failed run leaves nothing of
 * its own). */
START_TEST(test_obj_discard)
{
    drape_lattice *L = tl_small();
    const char *dir = subdir("objdiscard");
    char keep[600];
    snprintf(keep, sizeof keep, "%s/frame_000099.obj", dir);
    FILE *k = fopen(keep, "w");
    ck_assert_ptr_nonnull(k);
    fputs("# not drape's\n", k);
    fclose(k);
    drape_error err;
    drape_error_clear(&err);
    drape_obj *o = drape_obj_new(dir, L, "f", "s", &err);
    ck_assert_ptr_nonnull(o);
    for (int f = 0; f < 3; f++) ck_assert_int_eq(drape_obj_frame(o, f, 0.1 * f, L->x0, &err), 0);
    ck_assert_int_eq(drape_obj_frame(o, 2, 0.2, L->x0, &err), 0); /* rewritten: once */
    ck_assert_int_eq(drape_obj_written(o), 3);
    ck_assert_int_eq(count_entries(dir, "frame_"), 4);
    drape_obj_discard(o);
    ck_assert_int_eq(count_entries(dir, "frame_"), 1);
    ck_assert_int_eq(access(keep, F_OK), 0);
    drape_obj_discard(NULL);
    /* free keeps them */
    drape_error_clear(&err);
    o = drape_obj_new(dir, L, "f", "s", &err);
    ck_assert_ptr_nonnull(o);
    ck_assert_int_eq(drape_obj_frame(o, 0, 0.0, L->x0, &err), 0);
    drape_obj_free(o);
    ck_assert_int_eq(count_entries(dir, "frame_"), 2);
    tl_free(L);
}
END_TEST

/* What --resume reads back: /final, /run and /stats attributes, the input
 * texts; and the frames of an earlier file copied in front of new ones. */
START_TEST(test_h5_checkpoint_and_copy)
{
    drape_lattice *L = tl_small();
    const char *dir = subdir("h5ck");
    drape_error err;
    drape_error_clear(&err);
    drape_h5 *h = drape_h5_open(dir, L, &err);
    ck_assert_ptr_nonnull(h);
    double x[2][3 * 19], v[3 * 19];
    for (int i = 0; i < 3 * 19; i++) {
        x[0][i] = L->x0[i];
        x[1][i] = L->x0[i] - 1e-3 * (i % 7);
        v[i] = 0.01 * (i % 5) - 0.02;
    }
    drape_energies E0 = {1, 2, 3, -4}, E1 = {5, 6, 7, -8};
    ck_assert_int_eq(drape_h5_frame(h, 0.0, x[0], v, 0.5, &E0, &err), 0);
    ck_assert_int_eq(drape_h5_frame(h, 0.05, x[1], NULL, 0.25, &E1, &err), 0);
    const drape_kv stats[] = {{"status", "interrupted", 0}, {"steps", NULL, 42}};
    const drape_kv run[] = {{"integrator", "cvode-bdf", 0}, {"rtol", NULL, 1e-5},
                            {"eq_below_since_s", NULL, -1}};
    drape_h5_final fin = {0.07, x[1], v, stats, 2, "fabric: f\n", "scene: hang\n", run, 3};
    ck_assert_int_eq(drape_h5_close(h, &fin, &err), 0);

    char path[600];
    snprintf(path, sizeof path, "%s/drape.h5", dir);
    drape_h5_checkpoint c;
    ck_assert_msg(drape_h5_checkpoint_read(path, &c, &err) == 0, "%s", err.msg);
    ck_assert_int_eq(c.n, 19);
    ck_assert_int_eq(c.frames, 2);
    ck_assert(c.t_s == 0.07);
    for (int i = 0; i < 3 * 19; i++) ck_assert(c.x[i] == x[1][i] && c.v[i] == v[i]);
    ck_assert_str_eq(drape_kv_find(c.stats, c.n_stats, "status")->text, "interrupted");
    ck_assert(drape_kv_find(c.stats, c.n_stats, "steps")->value == 42);
    ck_assert_str_eq(drape_kv_find(c.run, c.n_run, "integrator")->text, "cvode-bdf");
    ck_assert(drape_kv_find(c.run, c.n_run, "rtol")->value == 1e-5);
    ck_assert(drape_kv_find(c.run, c.n_run, "eq_below_since_s")->value == -1);
    ck_assert_ptr_null(drape_kv_find(c.run, c.n_run, "nope"));
    ck_assert_str_eq(c.fabric_yaml, "fabric: f\n");
    ck_assert_str_eq(c.scene_yaml, "scene: hang\n");
    drape_h5_checkpoint_free(&c);

    /* a new file in another directory: the two old frames, then one more */
    const char *dir2 = subdir("h5ck2");
    drape_error_clear(&err);
    h = drape_h5_open(dir2, L, &err);
    ck_assert_ptr_nonnull(h);
    ck_assert_msg(drape_h5_copy_frames(h, path, &err) == 0, "%s", err.msg);
    ck_assert_int_eq(drape_h5_frames(h), 2);
    ck_assert_int_eq(drape_h5_frame(h, 0.1, x[0], v, 0.125, &E0, &err), 0);
    ck_assert_int_eq(drape_h5_close(h, NULL, &err), 0);
    snprintf(path, sizeof path, "%s/drape.h5", dir2);
    hid_t F = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    ck_assert(F >= 0);
    double t[3], ke[3], grav[3], p1[3 * 19];
    read_doubles(F, "/times", t, 3);
    read_doubles(F, "/energies/kinetic", ke, 3);
    read_doubles(F, "/energies/gravity", grav, 3);
    read_doubles(F, "/steps/000001/positions", p1, 3 * 19);
    ck_assert(t[0] == 0.0 && t[1] == 0.05 && t[2] == 0.1);
    ck_assert(ke[0] == 0.5 && ke[1] == 0.25 && ke[2] == 0.125);
    ck_assert(grav[0] == -4 && grav[1] == -8 && grav[2] == -4);
    for (int i = 0; i < 3 * 19; i++) ck_assert(p1[i] == x[1][i]);
    ck_assert(H5Lexists(F, "/steps/000000/velocities", H5P_DEFAULT) > 0);
    ck_assert(H5Lexists(F, "/steps/000001/velocities", H5P_DEFAULT) == 0);
    H5Fclose(F);

    /* errors: no file; a file without /final */
    snprintf(path, sizeof path, "%s/none.h5", dir2);
    drape_error_clear(&err);
    ck_assert_int_eq(drape_h5_checkpoint_read(path, &c, &err), -1);
    ck_assert_int_eq(err.kind, DRAPE_E_IO);
    drape_h5_checkpoint_free(&c);
    const char *dir3 = subdir("h5ck3");
    drape_error_clear(&err);
    h = drape_h5_open(dir3, L, &err);
    ck_assert_ptr_nonnull(h);
    ck_assert_int_eq(drape_h5_close(h, NULL, &err), 0);
    snprintf(path, sizeof path, "%s/drape.h5", dir3);
    ck_assert_int_eq(drape_h5_checkpoint_read(path, &c, &err), -1);
    ck_assert_msg(strstr(err.msg, "/final") != NULL, "%s", err.msg);
    drape_h5_checkpoint_free(&c);
    tl_free(L);
}
END_TEST

Suite *output_suite(void);
Suite *output_suite(void)
{
    Suite *s = suite_create("output");
    TCase *tc = tcase_create("files");
    tcase_set_timeout(tc, 60);
    tcase_add_test(tc, test_obj_roundtrip);
    tcase_add_test(tc, test_obj_errors);
    tcase_add_test(tc, test_h5_roundtrip);
    tcase_add_test(tc, test_h5_discard_and_errors);
    tcase_add_test(tc, test_obj_discard);
    tcase_add_test(tc, test_h5_checkpoint_and_copy);
    suite_add_tcase(s, tc);
    return s;
}
