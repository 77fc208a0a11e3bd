/* check_drape.c: the observers of drape.h against hand computations.
 *
 * Lattices are built by hand here (the lattice builder is tested
 * elsewhere): a grid of ni x nj points at spacing sigma, a keep predicate,
 * a fixed predicate.  Expected areas come from counting cells, from
 * inclusion-exclusion, or from an independent exact union of axis-aligned
 * rectangles by coordinate compression. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "drape/alloc.h"
#include "drape/drape.h"
#include "testutil.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

typedef int (*tl_pred)(double x, double y, const double *par);

/* Grid point (i, j) at (ox + i sigma, oy + j sigma), kept if keep says so
 * (NULL: all), fixed if fix says so (NULL: none).  If swap, i runs along y
 * and j along x (a warp strip). */
static drape_lattice *tl_new(int ni, int nj, double sigma, double ox, double oy,
                             int swap, tl_pred keep, tl_pred fix, const double *par)
{
    drape_lattice *L = drape_calloc(1, sizeof *L);
    ck_assert_ptr_nonnull(L);
    L->sigma = sigma;
    L->ni = ni;
    L->nj = nj;
    L->grid = drape_calloc((size_t)(ni * nj), sizeof *L->grid);
    L->gi = drape_calloc((size_t)(ni * nj), sizeof *L->gi);
    L->gj = drape_calloc((size_t)(ni * nj), sizeof *L->gj);
    L->x0 = drape_calloc((size_t)(3 * ni * nj), sizeof *L->x0);
    L->fixed = drape_calloc((size_t)(ni * nj), 1);
    ck_assert(L->grid && L->gi && L->gj && L->x0 && L->fixed);
    for (int j = 0; j < nj; j++)
        for (int i = 0; i < ni; i++) {
            double a = ox + i * sigma, b = oy + j * sigma;
            double x = swap ? b : a, y = swap ? a : b;
            if (keep && !keep(x, y, par)) {
                L->grid[j * ni + i] = -1;
                continue;
            }
            int id = L->n++;
            L->grid[j * ni + i] = id;
            L->gi[id] = i;
            L->gj[id] = j;
            L->x0[3 * id] = x;
            L->x0[3 * id + 1] = y;
            L->fixed[id] = fix ? (unsigned char)fix(x, y, par) : 0;
        }
    return L;
}

static void tl_free(drape_lattice *L)
{
    if (!L) return;
    drape_free(L->grid);
    drape_free(L->gi);
    drape_free(L->gj);
    drape_free(L->x0);
    drape_free(L->fixed);
    drape_free(L);
}

/* par[0] = specimen radius, par[1] = disk radius, par[2] = tolerance */
static int in_circle(double x, double y, const double *par)
{
    return x * x + y * y <= par[0] * par[0] + par[2];
}
static int in_disk(double x, double y, const double *par)
{
    return x * x + y * y <= par[1] * par[1] + par[2];
}
/* par[3] = half side of a square disk */
static int in_square(double x, double y, const double *par)
{
    return fabs(x) <= par[3] + par[2] && fabs(y) <= par[3] + par[2];
}
static int on_platform(double x, double y, const double *par)
{
    (void)y;
    return x <= par[2];
}

static drape_lattice *tl_circle(double R, double Rd, double sigma)
{
    static double par[4];
    par[0] = R; par[1] = Rd; par[2] = 1e-9 * sigma * sigma; par[3] = 0;
    int h = (int)floor(R / sigma + 1e-9);
    return tl_new(2 * h + 1, 2 * h + 1, sigma, -h * sigma, -h * sigma, 0, in_circle,
                  in_disk, par);
}

static double *tl_copy_x0(const drape_lattice *L)
{
    double *x = drape_malloc(sizeof *x * (size_t)(3 * L->n));
    ck_assert_ptr_nonnull(x);
    memcpy(x, L->x0, sizeof *x * (size_t)(3 * L->n));
    return x;
}

/* Cells of L with all four corners kept (counted independently). */
static int tl_cells(const drape_lattice *L, int fixed_only)
{
    int c = 0;
    for (int j = 0; j + 1 < L->nj; j++)
        for (int i = 0; i + 1 < L->ni; i++) {
            int id[4] = {L->grid[j * L->ni + i], L->grid[j * L->ni + i + 1],
                         L->grid[(j + 1) * L->ni + i], L->grid[(j + 1) * L->ni + i + 1]};
            int ok = 1;
            for (int k = 0; k < 4; k++)
                if (id[k] < 0 || (fixed_only && !L->fixed[id[k]])) ok = 0;
            c += ok;
        }
    return c;
}

/* ------------------------------------------------------------------ DC */

START_TEST(test_dc_undeformed_rect)
{
    /* 11 x 7 points, sigma 1 cm, centred; square disk of half side 1 cm */
    static const double par[4] = {0, 0, 1e-12, 0.01};
    drape_lattice *L = tl_new(11, 7, 0.01, -0.05, -0.03, 0, NULL, in_square, par);
    L->area_nominal = 0.1 * 0.06;
    drape_shadow s;
    drape_error err;
    drape_error_clear(&err);
    ck_assert_int_eq(drape_shadow_measure(L, L->x0, &s, &err), 0);
    ck_assert_close_rel(s.a_specimen_mesh_m2, 0.10 * 0.06, 1e-12);
    ck_assert_close_rel(s.a_disk_m2, 0.02 * 0.02, 1e-12);
    ck_assert_close_abs(s.dc, 1.0, 1e-12);
    ck_assert_close_rel(s.a_specimen_nominal_m2, 0.006, 1e-15);
    /* rays from the origin: a 10 x 6 cm rectangle */
    ck_assert_close_rel(s.r_max_m, sqrt(0.05 * 0.05 + 0.03 * 0.03), 1e-12);
    ck_assert_close_rel(s.r_min_m, 0.03, 1e-12);
    tl_free(L);
}
END_TEST

START_TEST(test_dc_undeformed_circle)
{
    const double sig[] = {0.02, 0.01, 0.005};
    for (int k = 0; k < 3; k++) {
        drape_lattice *L = tl_circle(0.15, 0.09, sig[k]);
        drape_shadow s;
        drape_error err;
        drape_error_clear(&err);
        ck_assert_int_eq(drape_shadow_measure(L, L->x0, &s, &err), 0);
        ck_assert_close_rel(s.a_specimen_mesh_m2, tl_cells(L, 0) * sig[k] * sig[k], 1e-12);
        ck_assert_close_rel(s.a_disk_m2, tl_cells(L, 1) * sig[k] * sig[k], 1e-12);
        ck_assert_close_abs(s.dc, 1.0, 1e-12);
        /* the staircase edge is not a fold */
        ck_assert_msg(s.nodes == 0, "sigma %g: %d nodes", sig[k], s.nodes);
        ck_assert(s.r_max_m <= 0.15 + 1e-12 && s.r_max_m > 0.15 - sig[k]);
        ck_assert(s.r_min_m > 0.15 - 2 * sig[k]);
        /* deformed copy gives a different DC: the test can fail */
        double *x = tl_copy_x0(L);
        for (int i = 0; i < L->n; i++)
            if (!L->fixed[i]) { x[3 * i] *= 0.9; x[3 * i + 1] *= 0.9; }
        ck_assert_int_eq(drape_shadow_measure(L, x, &s, &err), 0);
        ck_assert(s.dc < 0.99);
        drape_free(x);
        tl_free(L);
    }
}
END_TEST

/* Square disk: every free particle clamped horizontally onto the disk's
 * square and lowered by its distance: the shadow is the disk's, DC = 0. */
START_TEST(test_dc_zero_square)
{
    static const double par[4] = {0, 0, 1e-12, 0.04};
    drape_lattice *L = tl_new(21, 21, 0.01, -0.1, -0.1, 0, NULL, in_square, par);
    double *x = tl_copy_x0(L);
    for (int i = 0; i < L->n; i++) {
        if (L->fixed[i]) continue;
        double a = x[3 * i], b = x[3 * i + 1];
        double ca = fmax(-0.04, fmin(0.04, a)), cb = fmax(-0.04, fmin(0.04, b));
        x[3 * i] = ca;
        x[3 * i + 1] = cb;
        x[3 * i + 2] = -hypot(a - ca, b - cb);
    }
    drape_shadow s;
    drape_error err;
    drape_error_clear(&err);
    ck_assert_int_eq(drape_shadow_measure(L, x, &s, &err), 0);
    ck_assert_close_rel(s.a_disk_m2, 0.08 * 0.08, 1e-12);
    ck_assert_close_rel(s.a_shadow_m2, 0.08 * 0.08, 1e-12);
    ck_assert_close_abs(s.dc, 0.0, 1e-12);
    drape_free(x);
    tl_free(L);
}
END_TEST

/* Circle: free particles moved onto the disk edge along their radial line,
 * hanging down.  The shadow lies inside the disk's circle and contains the
 * disk's staircase: 0 <= DC <= (pi Rd^2 - A_disk) / (A_spec - A_disk). */
START_TEST(test_dc_circle_hanging)
{
    const double R = 0.15, Rd = 0.09, sigma = 0.01;
    drape_lattice *L = tl_circle(R, Rd, sigma);
    double *x = tl_copy_x0(L);
    for (int i = 0; i < L->n; i++) {
        if (L->fixed[i]) continue;
        double r = hypot(x[3 * i], x[3 * i + 1]);
        x[3 * i] *= Rd / r;
        x[3 * i + 1] *= Rd / r;
        x[3 * i + 2] = -(r - Rd);
    }
    drape_shadow s;
    drape_error err;
    drape_error_clear(&err);
    ck_assert_int_eq(drape_shadow_measure(L, x, &s, &err), 0);
    double bound = (M_PI * Rd * Rd - s.a_disk_m2) / (s.a_specimen_mesh_m2 - s.a_disk_m2);
    ck_assert_msg(s.dc >= -1e-12 && s.dc <= bound, "dc %.17g, bound %.17g", s.dc, bound);
    ck_assert_msg(bound < 0.1, "bound %g", bound);
    ck_assert(s.r_max_m <= Rd + 1e-12);
    drape_free(x);
    tl_free(L);
}
END_TEST

/* Exact union of axis-aligned rectangles by coordinate compression. */
static double rect_union(const double *r, int n)
{
    double xs[128], ys[128];
    int nx = 0, ny = 0;
    for (int k = 0; k < n; k++) {
        xs[nx++] = r[4 * k]; xs[nx++] = r[4 * k + 2];
        ys[ny++] = r[4 * k + 1]; ys[ny++] = r[4 * k + 3];
    }
    for (int a = 0; a < nx; a++)
        for (int b = a + 1; b < nx; b++) {
            if (xs[b] < xs[a]) { double t = xs[a]; xs[a] = xs[b]; xs[b] = t; }
            if (ys[b] < ys[a]) { double t = ys[a]; ys[a] = ys[b]; ys[b] = t; }
        }
    double area = 0.0;
    for (int a = 0; a + 1 < nx; a++)
        for (int b = 0; b + 1 < ny; b++) {
            double cx = 0.5 * (xs[a] + xs[a + 1]), cy = 0.5 * (ys[b] + ys[b + 1]);
            for (int k = 0; k < n; k++)
                if (cx > r[4 * k] && cx < r[4 * k + 2] && cy > r[4 * k + 1] && cy < r[4 * k + 3]) {
                    area += (xs[a + 1] - xs[a]) * (ys[b + 1] - ys[b]);
                    break;
                }
        }
    return area;
}

/* rectangle k -> 2 triangles, rotated by angle phi about the origin */
static void rects_to_tris(const double *r, int n, double phi, double *t)
{
    double c = cos(phi), s = sin(phi);
    for (int k = 0; k < n; k++) {
        double p[8] = {r[4 * k], r[4 * k + 1], r[4 * k + 2], r[4 * k + 1],
                       r[4 * k + 2], r[4 * k + 3], r[4 * k], r[4 * k + 3]};
        const int ix[6] = {0, 1, 2, 0, 2, 3};
        for (int m = 0; m < 6; m++) {
            double X = p[2 * ix[m]], Y = p[2 * ix[m] + 1];
            t[12 * k + 2 * m] = c * X - s * Y;
            t[12 * k + 2 * m + 1] = s * X + c * Y;
        }
    }
}

START_TEST(test_union_nonconvex)
{
    /* [0,2]^2, [1,3]^2, [1,3]x[-1,1]: 12 - 1 - 1 = 10 (non-convex) */
    const double r3[12] = {0, 0, 2, 2, 1, 1, 3, 3, 1, -1, 3, 1};
    double t[12 * 40], area;
    drape_error err;
    drape_error_clear(&err);
    rects_to_tris(r3, 3, 0.0, t);
    ck_assert_int_eq(drape_union_area(NULL, t, 6, &area, &err), 0);
    ck_assert_close_rel(area, 10.0, 1e-12);
    ck_assert_close_rel(rect_union(r3, 3), 10.0, 1e-15);
    /* a triangle poking out of the union: + 1/2 (apex (4, 0.5) on [3,..]) */
    double t4[6 * 7];
    memcpy(t4, t, sizeof(double) * 36);
    const double extra[6] = {3, 0, 4, 0.5, 3, 1};
    memcpy(t4 + 36, extra, sizeof extra);
    ck_assert_int_eq(drape_union_area(NULL, t4, 7, &area, &err), 0);
    ck_assert_close_rel(area, 10.5, 1e-12);

    /* 40 random rectangles, rotated: against coordinate compression */
    srand(12345);
    double r[160];
    for (int k = 0; k < 40; k++) {
        double x = rand() / (double)RAND_MAX * 0.3, y = rand() / (double)RAND_MAX * 0.3;
        double w = 0.005 + rand() / (double)RAND_MAX * 0.1;
        double h = 0.005 + rand() / (double)RAND_MAX * 0.1;
        r[4 * k] = x; r[4 * k + 1] = y; r[4 * k + 2] = x + w; r[4 * k + 3] = y + h;
    }
    double exact = rect_union(r, 40);
    rects_to_tris(r, 40, 0.7, t);
    ck_assert_int_eq(drape_union_area(NULL, t, 80, &area, &err), 0);
    ck_assert_close_rel(area, exact, 1e-9);
    /* degenerate triangles are skipped, not errors */
    const double deg[12] = {0, 0, 1, 1, 2, 2, 0, 0, 0, 0, 1, 0};
    ck_assert_int_eq(drape_union_area(NULL, deg, 2, &area, &err), 0);
    ck_assert_close_abs(area, 0.0, 0.0);
}
END_TEST

/* Faces moved anywhere: two overlapping squares and a bow-tie cell. */
START_TEST(test_dc_lattice_overlaps)
{
    /* grid 8 x 2: cells at columns 0-1, 3-4, 6-7 (columns 2, 5 removed) */
    drape_lattice *L = tl_new(8, 2, 1.0, 0, 0, 0, NULL, NULL, NULL);
    int drop[] = {2, 5};
    int n = 0;
    for (int j = 0; j < 2; j++)
        for (int i = 0; i < 8; i++) {
            int skip = (i == drop[0] || i == drop[1]);
            L->grid[j * 8 + i] = skip ? -1 : n;
            if (!skip) {
                L->gi[n] = i; L->gj[n] = j;
                L->x0[3 * n] = i; L->x0[3 * n + 1] = j; L->x0[3 * n + 2] = 0;
                n++;
            }
        }
    L->n = n;
    int nq = 0;
    drape_error err;
    drape_error_clear(&err);
    int *q = drape_quads_new(L, &nq, &err);
    ck_assert_int_eq(nq, 3);
    drape_free(q);
    double x[3 * 12] = {0};
    /* cell A corners (0,0) (1,0) (0,1) (1,1) in grid order -> square [0,2]^2 */
#define P(i, j, X, Y) do { int id_ = L->grid[(j) * 8 + (i)]; x[3 * id_] = (X); x[3 * id_ + 1] = (Y); x[3*id_+2] = (i) * 0.1; } while (0)
    P(0, 0, 0, 0); P(1, 0, 2, 0); P(1, 1, 2, 2); P(0, 1, 0, 2);
    /* cell B: [1,3]^2 */
    P(3, 0, 1, 1); P(4, 0, 3, 1); P(4, 1, 3, 3); P(3, 1, 1, 3);
    /* cell C: bow-tie a=(10,0) b=(11,0) c=(10,1) d=(11,1): the hourglass
     * of two triangles about (10.5, 0.5), area 1/4 each */
    P(6, 0, 10, 0); P(7, 0, 11, 0); P(7, 1, 10, 1); P(6, 1, 11, 1);
#undef P
    drape_shadow s;
    ck_assert_int_eq(drape_shadow_measure(L, x, &s, &err), 0);
    ck_assert_close_rel(s.a_shadow_m2, 4 + 4 - 1 + 0.5, 1e-12);
    ck_assert_close_rel(s.a_specimen_mesh_m2, 3.0, 1e-12);
    ck_assert_close_abs(s.a_disk_m2, 0.0, 0.0);
    ck_assert_close_rel(s.dc, 7.5 / 3.0, 1e-12);
    /* non-finite positions are an error */
    x[4] = NAN;
    ck_assert_int_eq(drape_shadow_measure(L, x, &s, &err), -1);
    ck_assert_int_eq(err.kind, DRAPE_E_NUMERIC);
    tl_free(L);
}
END_TEST

/* The far exit t >= 0 of the ray c + t u from triangle tri (6 numbers), or
 * -1 if the ray misses it: the ray's parameter interval inside each of the
 * three half-planes, intersected (independent of GEOS). */
static double ray_exit(double cx, double cy, double ux, double uy, const double *tri)
{
    double o = (tri[2] - tri[0]) * (tri[5] - tri[1]) - (tri[3] - tri[1]) * (tri[4] - tri[0]);
    double sg = o > 0 ? 1.0 : -1.0, lo = 0.0, hi = INFINITY;
    for (int k = 0; k < 3; k++) {
        const double *a = tri + 2 * k, *b = tri + 2 * ((k + 1) % 3);
        double ex = b[0] - a[0], ey = b[1] - a[1];
        double f0 = sg * (ex * (cy - a[1]) - ey * (cx - a[0])); /* inside: f0 + t f1 >= 0 */
        double f1 = sg * (ex * uy - ey * ux);
        if (f1 == 0.0) {
            if (f0 < 0.0) return -1.0;
            continue;
        }
        double t = -f0 / f1;
        if (f1 > 0.0) lo = t > lo ? t : lo;
        else hi = t < hi ? t : hi;
    }
    return lo <= hi ? hi : -1.0;
}

/* par[1]: disk radius, par[2]: tolerance, par[4]: the disk's centre x */
static int in_disk_offset(double x, double y, const double *par)
{
    return (x - par[4]) * (x - par[4]) + y * y <= par[1] * par[1] + par[2];
}

/* r(theta) on shadows that are not star-shaped about the centre (a
 * swirl: rays leave and re-enter it), on overlapping folds, and about a
 * centre off the specimen's middle, against each ray cast through every
 * face's four triangles about its corner mean (drape.c's faces) and the
 * farthest exit taken: the farthest point of the union along the ray, which
 * is on its exterior ring.  r_min, r_max (exact: the farthest exterior
 * vertex) and the centre follow. */
START_TEST(test_dc_rays_independent)
{
    static double par[5];
    const double R = 0.15, sigma = 0.01;
    for (int c = 0; c < 4; c++) {
        par[0] = R; par[1] = 0.05; par[2] = 1e-9 * sigma * sigma; par[3] = 0.0;
        par[4] = c == 3 ? 0.04 : 0.0; /* an offset support disk: the rays' centre moves */
        int h = (int)floor(R / sigma + 1e-9);
        drape_lattice *L = tl_new(2 * h + 1, 2 * h + 1, sigma, -h * sigma, -h * sigma, 0,
                                  in_circle, in_disk_offset, par);
        double *x = tl_copy_x0(L);
        for (int i = 0; i < L->n; i++) {
            double X = L->x0[3 * i], Y = L->x0[3 * i + 1], r = hypot(X, Y), ph = atan2(Y, X);
            if (c == 0 || c == 3) { /* swirl: the angle turns with r^2 (1.7 turns at the hem) */
                double a = 25.0 * r * r / R;
                X = r * cos(ph + a);
                Y = r * sin(ph + a);
            } else { /* seven folds pushed sideways over each other, with ripples */
                double f = r > 0.05 ? 0.7 : 1.0, d = r > 0.05 ? 0.6 * (r - 0.05) * sin(7 * ph) : 0;
                double nx = c == 2 ? 0.004 * sin(50 * X) : 0.0, ny = c == 2 ? 0.004 * cos(40 * Y) : 0.0;
                X = f * r * cos(ph) - d * sin(ph) + nx;
                Y = f * r * sin(ph) + d * cos(ph) + ny;
            }
            x[3 * i] = X;
            x[3 * i + 1] = Y;
            x[3 * i + 2] = -0.01 * r;
        }
        drape_error err;
        drape_error_clear(&err);
        drape_dc *d = drape_dc_new(L, NULL, &err);
        ck_assert_ptr_nonnull(d);
        drape_shadow sh;
        ck_assert_int_eq(drape_dc_measure(d, x, &sh, &err), 0);
        ck_assert_close_abs(sh.centre_m[0], par[4], 1e-12);
        ck_assert_close_abs(sh.centre_m[1], 0.0, 1e-12);
        int na = 0, nq = 0;
        const double *rad = drape_dc_radii(d, &na);
        int *q = drape_quads_new(L, &nq, &err);
        ck_assert(rad && na >= 8 && q && nq > 0);
        double rmin = INFINITY, vmax = 0.0;
        for (int a = 0; a < na; a++) {
            double th = 2.0 * M_PI * a / na, ux = cos(th), uy = sin(th), best = 0.0;
            int exits = 0;
            for (int k = 0; k < nq; k++) {
                double p[8], mx = 0.0, my = 0.0;
                for (int v = 0; v < 4; v++) {
                    p[2 * v] = x[3 * q[4 * k + v]];
                    p[2 * v + 1] = x[3 * q[4 * k + v] + 1];
                    mx += p[2 * v] / 4;
                    my += p[2 * v + 1] / 4;
                }
                for (int v = 0; v < 4; v++) {
                    int w = (v + 1) % 4;
                    double tri[6] = {p[2 * v], p[2 * v + 1], p[2 * w], p[2 * w + 1], mx, my};
                    double o = (tri[2] - tri[0]) * (tri[5] - tri[1]) - (tri[3] - tri[1]) * (tri[4] - tri[0]);
                    if (fabs(o) < 1e-14) continue;
                    double t = ray_exit(sh.centre_m[0], sh.centre_m[1], ux, uy, tri);
                    exits += t >= 0.0;
                    if (t > best) best = t;
                }
            }
            ck_assert_msg(fabs(best - rad[a]) <= 1e-12, "case %d ray %d: r %.15g, cast %.15g", c, a,
                          rad[a], best);
            rmin = fmin(rmin, best);
            ck_assert_msg(exits > 0, "case %d ray %d meets no face", c, a);
        }
        for (int i = 0; i < L->n; i++)
            vmax = fmax(vmax, hypot(x[3 * i] - sh.centre_m[0], x[3 * i + 1] - sh.centre_m[1]));
        ck_assert_close_abs(sh.r_min_m, rmin, 1e-12);
        ck_assert_msg(sh.r_max_m <= vmax + 1e-12 && sh.r_max_m >= rmin, "case %d r_max %g", c,
                      sh.r_max_m);
        drape_free(q);
        drape_free(x);
        drape_dc_free(d);
        tl_free(L);
    }
}
END_TEST

START_TEST(test_quads_orientation)
{
    /* warp-strip layout: i along y, j along x */
    drape_lattice *L = tl_new(3, 5, 0.01, 0, 0, 1, NULL, NULL, NULL);
    int nq = 0;
    drape_error err;
    drape_error_clear(&err);
    int *q = drape_quads_new(L, &nq, &err);
    ck_assert_int_eq(nq, 2 * 4);
    for (int k = 0; k < nq; k++) {
        double a2 = 0;
        for (int c = 0; c < 4; c++) {
            const double *p = L->x0 + 3 * q[4 * k + c], *r = L->x0 + 3 * q[4 * k + (c + 1) % 4];
            a2 += p[0] * r[1] - p[1] * r[0];
        }
        ck_assert_close_rel(0.5 * a2, 1e-4, 1e-12); /* +sigma^2: CCW from +z */
    }
    drape_free(q);
    tl_free(L);
}
END_TEST

START_TEST(test_dc_alloc_failures)
{
    drape_lattice *L = tl_circle(0.05, 0.02, 0.01);
    drape_error err;
    int ok = 0;
    for (long k = 1; k < 30 && !ok; k++) {
        drape_error_clear(&err);
        drape_alloc_fail_at(k);
        drape_dc *d = drape_dc_new(L, NULL, &err);
        drape_alloc_fail_at(0);
        if (d) {
            drape_shadow s;
            ck_assert_int_eq(drape_dc_measure(d, L->x0, &s, &err), 0);
            ck_assert_close_abs(s.dc, 1.0, 1e-12);
            ck_assert_ptr_nonnull(drape_dc_radii(d, NULL));
            drape_dc_free(d);
            ok = 1;
        } else {
            ck_assert_int_eq(err.kind, DRAPE_E_NOMEM);
        }
    }
    ck_assert(ok);
    /* bad options */
    drape_dc_opts o;
    drape_dc_opts_default(&o);
    o.n_angles = 4;
    drape_error_clear(&err);
    ck_assert_ptr_null(drape_dc_new(L, &o, &err));
    ck_assert_int_eq(err.kind, DRAPE_E_INPUT);
    tl_free(L);
}
END_TEST

/* ---------------------------------------------------------------- nodes */

START_TEST(test_nodes_samples)
{
    double r[360];
    const int ks[] = {5, 7, 9};
    for (int m = 0; m < 3; m++) {
        int k = ks[m];
        for (int a = 0; a < 360; a++) {
            double th = 2 * M_PI * a / 360;
            /* phase shift so no peak sits on sample 0; a small ripple */
            r[a] = 0.15 * (1 + 0.2 * cos(k * th + 0.3)) + 0.002 * sin(60 * th);
        }
        ck_assert_int_eq(drape_nodes_count(r, 360, 0.05 * 0.15), k);
        /* the ripple alone is counted when the threshold is 0 */
        ck_assert_int_gt(drape_nodes_count(r, 360, 0.0), k);
    }
    for (int a = 0; a < 360; a++) r[a] = 0.1;
    ck_assert_int_eq(drape_nodes_count(r, 360, 0.0), 0);
    /* hand example: peaks 5 (global: prominence 5) and 4 (prominence 4-3) */
    const double h[8] = {0, 5, 3, 4, 0, 0, 0, 0};
    ck_assert_int_eq(drape_nodes_count(h, 8, 0.5), 2);
    ck_assert_int_eq(drape_nodes_count(h, 8, 1.5), 1);
    ck_assert_int_eq(drape_nodes_count(h, 8, 4.9), 1);
    ck_assert_int_eq(drape_nodes_count(h, 8, 5.0), 0);
    /* twin peaks of equal height with a shallow dip: one node, not two */
    const double tw[8] = {0, 5, 4.5, 5, 0, 0, 3, 0};
    ck_assert_int_eq(drape_nodes_count(tw, 8, 1.0), 2);
    ck_assert_int_eq(drape_nodes_count(tw, 8, 0.4), 3);
    /* exactly k-fold symmetric samples: every peak has prominence 2 */
    for (int a = 0; a < 360; a++) r[a] = cos(6 * 2 * M_PI * a / 360);
    ck_assert_int_eq(drape_nodes_count(r, 360, 1.9), 6);
    /* a plateau peak wrapping round the end counts once */
    const double p[8] = {2, 2, 1, 0, 0, 0, 1, 2};
    ck_assert_int_eq(drape_nodes_count(p, 8, 0.5), 1);
}
END_TEST

/* A circle lattice stretched to r = rho (1 + 0.2 cos(k phi)): k nodes. */
START_TEST(test_nodes_lattice)
{
    const int ks[] = {5, 7, 9};
    for (int m = 0; m < 3; m++) {
        drape_lattice *L = tl_circle(0.15, 0.09, 0.005);
        double *x = tl_copy_x0(L);
        for (int i = 0; i < L->n; i++) {
            double phi = atan2(x[3 * i + 1], x[3 * i]);
            double f = 1 + 0.2 * cos(ks[m] * phi + 0.1);
            x[3 * i] *= f;
            x[3 * i + 1] *= f;
        }
        drape_shadow s;
        drape_error err;
        drape_error_clear(&err);
        ck_assert_int_eq(drape_shadow_measure(L, x, &s, &err), 0);
        ck_assert_int_eq(s.nodes, ks[m]);
        ck_assert(fabs(s.r_max_m - 0.18) < 0.005 * 1.2);
        ck_assert(fabs(s.r_min_m - 0.12) < 0.005 * 1.2);
        drape_free(x);
        tl_free(L);
    }
}
END_TEST

/* The outline's smoothing: a constant stays, cos(m theta) is scaled by the
 * continuous Gaussian's transfer exp(-(m sd)^2 / 2). */
START_TEST(test_outline_smooth)
{
    enum { N = 360 };
    double r[N], o[N];
    for (int k = 0; k < N; k++) r[k] = 0.12;
    drape_outline_smooth(r, N, 0.05, o);
    for (int k = 0; k < N; k++) ck_assert(fabs(o[k] - 0.12) < 1e-15);
    const double sds[] = {0.02, 0.05, 0.1};
    for (int a = 0; a < 3; a++)
        for (int m = 1; m <= 12; m++) {
            for (int k = 0; k < N; k++) r[k] = cos(m * 2 * M_PI * k / N);
            drape_outline_smooth(r, N, sds[a], o);
            double want = exp(-0.5 * m * m * sds[a] * sds[a]), worst = 0;
            for (int k = 0; k < N; k++) worst = fmax(worst, fabs(o[k] - want * r[k]));
            ck_assert_msg(worst < 1e-3, "sd %g, m %d: off by %g", sds[a], m, worst);
        }
    drape_outline_smooth(r, N, 0.0, o);
    for (int k = 0; k < N; k++) ck_assert(o[k] == r[k]);
}
END_TEST

/* Nodes count folds, not the lattice (docs/model.md 6): the 30 cm specimen on
 * its 18 cm support, built here on square lattices of 2 to 0.25 cm, has no
 * node flat, and n when its skirt is pulled in to rho = 9 cm + (r - 9 cm)
 * c(phi), c = 0.45 + 0.12 cos(n phi + 0.3 + 0.4 sin phi) (n folds at
 * irregular angles, each 1.4 cm deep: the stairs of the hem are carried
 * into the shadow), for n up to 4 at 2 cm, 10 at 1 cm (11 folds 6 cm
 * apart, six spacings, give 10) and 12 from 0.7 cm on. */
START_TEST(test_nodes_staircase)
{
    const double sps[] = {0.02, 0.01, 0.007, 0.005, 0.0035, 0.0025};
    for (int a = 0; a < 6; a++) {
        drape_lattice *L = tl_circle(0.15, 0.09, sps[a]);
        double *x = tl_copy_x0(L);
        drape_error err;
        drape_error_clear(&err);
        drape_dc *d = drape_dc_new(L, NULL, &err);
        ck_assert_msg(d != NULL, "%s", err.msg);
        drape_shadow sh;
        ck_assert_int_eq(drape_dc_measure(d, x, &sh, &err), 0);
        ck_assert_msg(sh.nodes == 0, "flat at %g m: %d nodes", sps[a], sh.nodes);
        int nmax = sps[a] > 0.015 ? 4 : sps[a] > 0.008 ? 10 : 12;
        for (int n = 2; n <= nmax; n++) {
            for (int i = 0; i < L->n; i++) {
                double X = L->x0[3 * i], Y = L->x0[3 * i + 1], r = hypot(X, Y);
                double phi = atan2(Y, X);
                double c = 0.45 + 0.12 * cos(n * phi + 0.3 + 0.4 * sin(phi));
                double rho = r > 0.09 ? 0.09 + (r - 0.09) * c : r;
                x[3 * i] = r > 0 ? rho * X / r : 0.0;
                x[3 * i + 1] = r > 0 ? rho * Y / r : 0.0;
            }
            ck_assert_int_eq(drape_dc_measure(d, x, &sh, &err), 0);
            ck_assert_msg(sh.nodes == n, "%d folds at %g m: %d nodes", n, sps[a], sh.nodes);
            int na;
            const double *ol = drape_dc_outline(d, &na);
            ck_assert_int_eq(drape_nodes_count(ol, na, sh.node_threshold_m), n);
        }
        drape_dc_free(d);
        drape_free(x);
        tl_free(L);
    }
}
END_TEST

/* ----------------------------------------------------------- cantilever */

START_TEST(test_cantilever)
{
    /* strip 10 cm long (4 cm on the platform, 6 cm overhang), 1 cm wide,
     * sigma 2.5 mm, warp layout (j along x) */
    static const double par[4] = {0, 0, 1e-12, 0};
    drape_lattice *L = tl_new(5, 41, 0.0025, -0.005, -0.04, 1, NULL, on_platform, par);
    const double angles[] = {41.5, 20.0, 70.0};
    for (int m = 0; m < 3; m++) {
        double al = angles[m] * M_PI / 180, *x = tl_copy_x0(L);
        for (int i = 0; i < L->n; i++)
            if (x[3 * i] > 0) { /* rotate the overhang down about the edge */
                double X = x[3 * i];
                x[3 * i] = X * cos(al);
                x[3 * i + 2] = -X * sin(al);
            }
        drape_cantilever c;
        drape_error err;
        drape_error_clear(&err);
        ck_assert_int_eq(drape_cantilever_measure(L, x, 0.15, 9.80665, &c, &err), 0);
        ck_assert_close_rel(c.overhang_m, 0.06, 1e-12);
        ck_assert_close_rel(c.tip_angle_deg, angles[m], 1e-12);
        ck_assert_close_abs(c.tip_m[1], 0.0, 1e-15);
        if (m == 0) {
            /* ASTM D1388: cos(20.75 deg) = 0.935135, tan(41.5 deg) = 0.884725,
             * (0.935135 / 7.077800)^(1/3) = 0.50928: c ~ l / 2 */
            ck_assert_close_rel(c.bending_length_m, 0.06 * 0.50928, 1e-4);
            ck_assert_close_rel(c.flexural_rigidity_Nm,
                                0.15 * 9.80665 * pow(0.06 * 0.50928, 3), 3e-4);
        }
        drape_free(x);
    }
    /* Peirce's formula outside (0, 90) deg is undefined */
    ck_assert(isnan(drape_peirce_bending_length(0.06, 0.0)));
    ck_assert(isnan(drape_peirce_bending_length(0.06, M_PI / 2)));
    ck_assert(isnan(drape_peirce_bending_length(0.06, 2.0)));
    ck_assert(!isnan(drape_peirce_bending_length(0.06, 1.0)));
    tl_free(L);
}
END_TEST

Suite *drape_suite(void);
Suite *drape_suite(void)
{
    Suite *s = suite_create("drape");
    TCase *tc = tcase_create("shadow");
    tcase_set_timeout(tc, 60);
    tcase_add_test(tc, test_dc_undeformed_rect);
    tcase_add_test(tc, test_dc_undeformed_circle);
    tcase_add_test(tc, test_dc_zero_square);
    tcase_add_test(tc, test_dc_circle_hanging);
    tcase_add_test(tc, test_union_nonconvex);
    tcase_add_test(tc, test_dc_lattice_overlaps);
    tcase_add_test(tc, test_dc_rays_independent);
    tcase_add_test(tc, test_quads_orientation);
    tcase_add_test(tc, test_dc_alloc_failures);
    tcase_add_test(tc, test_nodes_samples);
    tcase_add_test(tc, test_nodes_lattice);
    tcase_add_test(tc, test_outline_smooth);
    tcase_add_test(tc, test_nodes_staircase);
    suite_add_tcase(s, tc);
    TCase *tk = tcase_create("cantilever");
    tcase_set_timeout(tk, 60);
    tcase_add_test(tk, test_cantilever);
    suite_add_tcase(s, tk);
    return s;
}
