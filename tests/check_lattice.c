/* check_lattice.c: tests of the particle lattice (src/lattice.c).
 *
 * Expected values come from hand counts (grid sizes, clamped columns),
 * direct integer loops (lattice points in a disc), closed-form areas
 * (rectangles, the unit-disc identity m = W (pi - 1) / 4), conservation
 * (masses sum to W x area) and independent point sampling of the specimen
 * (areas of the circle's cells, edge rectangles and quarter cells).
 */
#include <check.h>
#include <math.h>
#include <string.h>

#include "drape/alloc.h"
#include "drape/lattice.h"
#include "drape/perturbation.h"
#include "testutil.h"

#define PI 3.14159265358979323846
#define WEIGHT 0.1 /* kg/m^2 */

static drape_fabric fab;

static const drape_fabric *fabric(void)
{
    memset(&fab, 0, sizeof fab);
    fab.weight = WEIGHT;
    fab.k[0] = fab.k[1] = 1000.0;
    return &fab;
}

static void base(drape_scene *s, drape_scene_kind kind, double spacing)
{
    memset(s, 0, sizeof *s);
    strcpy(s->path, "scenes/test.yaml");
    s->kind = kind;
    s->spacing = spacing;
    s->terms = DRAPE_TERM_ALL;
    s->support_diameter = 0.18;
}

static void rect(drape_scene *s, drape_scene_kind kind, double w, double h,
                 double spacing)
{
    base(s, kind, spacing);
    s->shape = DRAPE_SHAPE_RECTANGLE;
    s->width = w;
    s->height = h;
}

static void circle(drape_scene *s, double d, double spacing)
{
    base(s, DRAPE_SCENE_CUSICK, spacing);
    s->shape = DRAPE_SHAPE_CIRCLE;
    s->diameter = d;
}

static void strip(drape_scene *s, double len, double w, double overhang,
                  double spacing, drape_dir dir)
{
    base(s, DRAPE_SCENE_CANTILEVER, spacing);
    s->shape = DRAPE_SHAPE_STRIP;
    s->length = len;
    s->width = w;
    s->overhang = overhang;
    s->strip_dir = dir;
    s->terms = DRAPE_TERM_STRETCH | DRAPE_TERM_BEND | DRAPE_TERM_GRAVITY;
}

static drape_lattice *build(const drape_scene *s)
{
    drape_error err;
    drape_error_clear(&err);
    drape_lattice *L = drape_lattice_new(s, fabric(), &err);
    ck_assert_msg(L != NULL, "lattice_new failed: %s", err.msg);
    ck_assert_int_eq(drape_lattice_check(L), 0);
    long ni, nj, n;
    ck_assert_int_eq(drape_lattice_estimate(s, &ni, &nj, &n), 0);
    ck_assert_int_eq(ni, L->ni);
    ck_assert_int_eq(nj, L->nj);
    ck_assert_int_eq(n, L->n);
    return L;
}

static int count_fixed(const drape_lattice *L)
{
    int c = 0;
    for (int p = 0; p < L->n; p++) c += L->fixed[p];
    return c;
}

/* sum of weight * sigma^2 over edges (or hinges) of direction d */
static double edge_area(const drape_lattice *L, drape_dir d)
{
    double a = 0.0;
    for (int e = 0; e < L->n_edges; e++)
        if (L->edges[e].dir == d) a += L->edges[e].weight;
    return a * L->sigma * L->sigma;
}

static double hinge_area(const drape_lattice *L, drape_dir d)
{
    double a = 0.0;
    for (int h = 0; h < L->n_hinges; h++)
        if (L->hinges[h].dir == d) a += L->hinges[h].weight;
    return a * L->sigma * L->sigma;
}

static double corner_area(const drape_lattice *L)
{
    double a = 0.0;
    for (int c = 0; c < L->n_corners; c++) a += L->corners[c].weight;
    return a * L->sigma * L->sigma / 4.0;
}

static int at(const drape_lattice *L, int i, int j)
{
    if (i < 0 || j < 0 || i >= L->ni || j >= L->nj) return -1;
    return L->grid[j * L->ni + i];
}

/* ---- rectangle ---------------------------------------------------------- */

START_TEST(test_rect_counts_masses)
{
    drape_scene s;
    rect(&s, DRAPE_SCENE_HANG, 0.30, 0.30, 0.01);
    drape_lattice *L = build(&s);
    ck_assert_int_eq(L->ni, 31);
    ck_assert_int_eq(L->nj, 31);
    ck_assert_int_eq(L->n, 961);
    ck_assert_int_eq(L->n_free, 961);
    /* all neighbours: 2 * 30 * 31 edges, 2 * 29 * 31 hinges, 4 per cell */
    ck_assert_int_eq(L->n_edges, 1860);
    ck_assert_int_eq(L->n_hinges, 1798);
    ck_assert_int_eq(L->n_corners, 3600);
    double m = WEIGHT * 1e-4; /* a full cell */
    ck_assert_close_rel(L->mass[at(L, 0, 0)], m / 4, 1e-12);
    ck_assert_close_rel(L->mass[at(L, 30, 30)], m / 4, 1e-12);
    ck_assert_close_rel(L->mass[at(L, 0, 7)], m / 2, 1e-12);
    ck_assert_close_rel(L->mass[at(L, 12, 30)], m / 2, 1e-12);
    ck_assert_close_rel(L->mass[at(L, 15, 15)], m, 1e-12);
    ck_assert_close_rel(L->mass_total, WEIGHT * 0.09, 1e-12);
    ck_assert_close_rel(L->area_nominal, 0.09, 1e-14);
    /* world placement: centred, i along +x, j along +y */
    const double *x = L->x0 + 3 * at(L, 0, 0);
    ck_assert_close_abs(x[0], -0.15, 1e-15);
    ck_assert_close_abs(x[1], -0.15, 1e-15);
    x = L->x0 + 3 * at(L, 30, 0);
    ck_assert_close_abs(x[0], 0.15, 1e-15);
    x = L->x0 + 3 * at(L, 15, 15);
    ck_assert_close_abs(x[0], 0.0, 1e-15);
    ck_assert_close_abs(x[1], 0.0, 1e-15);
    for (int e = 0; e < L->n_edges; e++) {
        const drape_edge *E = &L->edges[e];
        double dx = L->x0[3 * E->b] - L->x0[3 * E->a];
        int along_x = fabs(dx) > 0.5 * L->sigma;
        ck_assert_int_eq(E->dir, along_x ? DRAPE_WEFT : DRAPE_WARP);
        /* boundary rows carry half the width */
        int row = E->dir == DRAPE_WEFT ? L->gj[E->a] : L->gi[E->a];
        int nrow = E->dir == DRAPE_WEFT ? L->nj : L->ni;
        double w = (row == 0 || row == nrow - 1) ? 0.5 : 1.0;
        ck_assert_close_rel(E->weight, w, 1e-12);
    }
    drape_lattice_free(L);
}
END_TEST

/* Uniform stretch/bend/shear identities on rectangles at several spacings
 * that divide the sides: each direction's edges represent the whole area,
 * hinges the area less one spacing along their direction, corners the whole
 * area (four quarter cells per cell). */
START_TEST(test_rect_identities)
{
    static const double sp[] = {0.03, 0.02, 0.01, 0.005, 0.0025};
    for (size_t k = 0; k < sizeof sp / sizeof sp[0]; k++) {
        drape_scene s;
        rect(&s, DRAPE_SCENE_HANG, 0.30, 0.24, sp[k]);
        drape_lattice *L = build(&s);
        double A = 0.30 * 0.24, h = sp[k];
        ck_assert_close_rel(edge_area(L, DRAPE_WEFT), A, 1e-10);
        ck_assert_close_rel(edge_area(L, DRAPE_WARP), A, 1e-10);
        ck_assert_close_rel(hinge_area(L, DRAPE_WEFT), (0.30 - h) * 0.24, 1e-10);
        ck_assert_close_rel(hinge_area(L, DRAPE_WARP), 0.30 * (0.24 - h), 1e-10);
        ck_assert_close_rel(corner_area(L), A, 1e-10);
        ck_assert_close_rel(L->mass_total, WEIGHT * A, 1e-10);
        drape_lattice_free(L);
    }
}
END_TEST

/* Width 30.5 cm at 1 cm: 31 columns over 30 cm, centred, a 0.25 cm margin
 * on each side carried by the boundary columns. */
START_TEST(test_rect_nonmultiple)
{
    drape_scene s;
    rect(&s, DRAPE_SCENE_HANG, 0.305, 0.30, 0.01);
    drape_lattice *L = build(&s);
    ck_assert_int_eq(L->ni, 31);
    ck_assert_int_eq(L->nj, 31);
    ck_assert_close_abs(L->x0[3 * at(L, 0, 0)], -0.15, 1e-15);
    double m = WEIGHT * 1e-4;
    ck_assert_close_rel(L->mass[at(L, 0, 0)], 0.75 * 0.5 * m, 1e-9);
    ck_assert_close_rel(L->mass[at(L, 30, 9)], 0.75 * m, 1e-9);
    ck_assert_close_rel(L->mass[at(L, 9, 30)], 0.5 * m, 1e-9);
    ck_assert_close_rel(L->mass_total, WEIGHT * 0.305 * 0.30, 1e-10);
    /* edges along x cover the lattice's 30 cm, those along y all 30.5 cm */
    ck_assert_close_rel(edge_area(L, DRAPE_WEFT), 0.30 * 0.30, 1e-10);
    ck_assert_close_rel(edge_area(L, DRAPE_WARP), 0.305 * 0.30, 1e-10);
    for (int h = 0; h < L->n_hinges; h++)
        if (L->hinges[h].dir == DRAPE_WARP && L->gi[L->hinges[h].mid] == 0)
            ck_assert_close_rel(L->hinges[h].weight, 0.75, 1e-9);
    /* masses at several non-multiple sizes and spacings */
    static const double dims[][3] = {{0.305, 0.30, 0.01}, {0.30, 0.30, 0.007},
                                     {0.50, 0.333, 0.02}, {0.1, 0.1, 0.03}};
    for (size_t k = 0; k < 4; k++) {
        drape_scene t;
        rect(&t, DRAPE_SCENE_HANG, dims[k][0], dims[k][1], dims[k][2]);
        drape_lattice *M = build(&t);
        ck_assert_int_eq(M->ni, (int)floor(dims[k][0] / dims[k][2] + 1e-9) + 1);
        ck_assert_close_rel(M->mass_total, WEIGHT * dims[k][0] * dims[k][1], 1e-10);
        drape_lattice_free(M);
    }
    drape_lattice_free(L);
}
END_TEST

START_TEST(test_hang_pins)
{
    drape_scene s;
    rect(&s, DRAPE_SCENE_HANG, 0.30, 0.30, 0.01);
    s.n_pins = 2;
    s.pins[0][0] = 0;  s.pins[0][1] = -1;
    s.pins[1][0] = -1; s.pins[1][1] = -1;
    drape_lattice *L = build(&s);
    ck_assert_int_eq(count_fixed(L), 2);
    ck_assert_int_eq(L->n_free, 959);
    int a = at(L, 0, 30), b = at(L, 30, 30);
    ck_assert(L->fixed[a] && L->fixed[b]);
    ck_assert_close_abs(L->x0[3 * a], -0.15, 1e-15);
    ck_assert_close_abs(L->x0[3 * a + 1], 0.15, 1e-15);
    ck_assert_close_abs(L->x0[3 * b], 0.15, 1e-15);
    ck_assert_int_eq(L->free_id[a], -1);
    drape_lattice_free(L);

    /* -31 is the first column; pins combine with nothing else in hang */
    s.n_pins = 1;
    s.pins[0][0] = -31; s.pins[0][1] = 0;
    L = build(&s);
    ck_assert(L->fixed[at(L, 0, 0)]);
    ck_assert_int_eq(count_fixed(L), 1);
    drape_lattice_free(L);

    static const int badpins[][2] = {{31, 0}, {0, -32}, {-32, 3}, {5, 31}};
    for (int k = 0; k < 4; k++) {
        drape_error err;
        drape_error_clear(&err);
        s.n_pins = 2;
        s.pins[0][0] = 0; s.pins[0][1] = 0;
        s.pins[1][0] = badpins[k][0]; s.pins[1][1] = badpins[k][1];
        L = drape_lattice_new(&s, fabric(), &err);
        ck_assert_ptr_eq(L, NULL);
        ck_assert_int_eq(err.kind, DRAPE_E_INPUT);
        ck_assert_str_eq(err.key, "pins[1]");
        ck_assert_str_eq(err.file, "scenes/test.yaml");
    }
}
END_TEST

START_TEST(test_table)
{
    drape_scene s;
    rect(&s, DRAPE_SCENE_TABLE, 0.60, 0.60, 0.01);
    s.table_shape = DRAPE_TABLE_SQUARE;
    s.table_size = 0.36;
    drape_lattice *L = build(&s);
    ck_assert_int_eq(L->n, 61 * 61);
    ck_assert_int_eq(count_fixed(L), 37 * 37);
    /* edges: all 2 * 60 * 61 less the 2 * 36 * 37 inside the clamped block */
    ck_assert_int_eq(L->n_edges, 2 * 60 * 61 - 2 * 36 * 37);
    /* hinges: 2 * 59 * 61 less those with 3 clamped particles: 2 * 35 * 37 */
    ck_assert_int_eq(L->n_hinges, 2 * 59 * 61 - 2 * 35 * 37);
    drape_lattice_free(L);

    s.table_shape = DRAPE_TABLE_ROUND;
    L = build(&s);
    int expect = 0;
    for (int j = -30; j <= 30; j++)
        for (int i = -30; i <= 30; i++) expect += i * i + j * j <= 18 * 18;
    ck_assert_int_eq(count_fixed(L), expect);
    drape_lattice_free(L);
}
END_TEST

/* ---- circle ------------------------------------------------------------- */

START_TEST(test_circle_counts)
{
    drape_scene s;
    circle(&s, 0.30, 0.01);
    drape_lattice *L = build(&s);
    int n = 0, nfix = 0;
    for (int j = -15; j <= 15; j++)
        for (int i = -15; i <= 15; i++) {
            n += i * i + j * j <= 225;
            nfix += i * i + j * j <= 81;
        }
    ck_assert_int_eq(L->ni, 31);
    ck_assert_int_eq(L->n, n);
    ck_assert_int_eq(count_fixed(L), nfix);
    ck_assert_int_eq(L->n_free, n - nfix);
    int c = at(L, 15, 15);
    ck_assert(c >= 0);
    ck_assert_close_abs(L->x0[3 * c], 0.0, 1e-15);
    ck_assert_close_abs(L->x0[3 * c + 1], 0.0, 1e-15);
    ck_assert(at(L, 30, 15) >= 0);  /* (15, 0) cm: on the circle, kept */
    ck_assert(at(L, 30, 16) < 0);
    ck_assert_close_rel(L->area_nominal, PI * 0.15 * 0.15, 1e-14);
    drape_lattice_free(L);
}
END_TEST

/* Circle of diameter 2 sigma: particles at the centre and at the four
 * points (+-1, 0), (0, +-1) on the circle.  The centre cell lies inside
 * (corner at 0.71 < 1); the four diagonal cells' parts go half and half to
 * their two axial neighbours, so by symmetry each axial particle carries
 * W (pi - 1) / 4 sigma^2. */
START_TEST(test_circle_hand_masses)
{
    drape_scene s;
    circle(&s, 0.02, 0.01);
    drape_lattice *L = build(&s);
    ck_assert_int_eq(L->n, 5);
    double m = WEIGHT * 1e-4;
    ck_assert_close_rel(L->mass[at(L, 1, 1)], m, 1e-13);
    ck_assert_close_rel(L->mass[at(L, 2, 1)], m * (PI - 1) / 4, 1e-12);
    ck_assert_close_rel(L->mass[at(L, 1, 0)], m * (PI - 1) / 4, 1e-12);
    ck_assert_close_rel(L->mass_total, WEIGHT * PI * 1e-4, 1e-12);
    drape_lattice_free(L);
}
END_TEST

START_TEST(test_circle_mass_sums)
{
    /* includes 2 cm on the 30 cm circle and spacings where R / sigma has a
     * fractional part > 1/2 (cells outside the grid's box meet the disc) */
    static const double sp[] = {0.01, 0.02, 0.007, 0.04, 0.035, 0.0025, 0.11};
    for (size_t k = 0; k < sizeof sp / sizeof sp[0]; k++) {
        drape_scene s;
        circle(&s, 0.30, sp[k]);
        s.support_diameter = 0.0;
        drape_lattice *L = build(&s);
        ck_assert_close_rel(L->mass_total, WEIGHT * PI * 0.0225, 1e-3);
        ck_assert_close_rel(L->mass_total, WEIGHT * PI * 0.0225, 1e-10);
        drape_lattice_free(L);
    }
}
END_TEST

/* Point sampling (independent of the analytic disc-rectangle area) of the
 * disc r = R / sigma in index units around the centre (c, c): an nsub x
 * nsub midpoint grid per cell of every lattice point. */
typedef struct sampled {
    double cell_kept;      /* area of kept particles' cells in the disc */
    double edge[2];        /* area of the edge rectangles of existing edges */
    double corner;         /* area of quarter cells of existing corners */
} sampled;

static sampled sample_disc(const drape_lattice *L, double r, int nsub)
{
    sampled S = {0, {0, 0}, 0};
    int c = (L->ni - 1) / 2;
    double h = 1.0 / nsub, da = h * h;
    for (int j = -1; j <= L->nj; j++)
        for (int i = -1; i <= L->ni; i++)
            for (int b = 0; b < nsub; b++)
                for (int a = 0; a < nsub; a++) {
                    double x = i - 0.5 + (a + 0.5) * h;
                    double y = j - 0.5 + (b + 0.5) * h;
                    double dx = x - c, dy = y - c;
                    if (dx * dx + dy * dy > r * r) continue;
                    int p = at(L, i, j);
                    if (p < 0) continue;
                    S.cell_kept += da;
                    /* quarter cell of p towards the sample */
                    int qi = x > i ? 1 : -1, qj = y > j ? 1 : -1;
                    if (at(L, i + qi, j) >= 0 && at(L, i, j + qj) >= 0)
                        S.corner += da;
                    /* weft edge rectangle [i', i'+1] x [j - 1/2, j + 1/2] */
                    int i0 = x > i ? i : i - 1;
                    if (at(L, i0, j) >= 0 && at(L, i0 + 1, j) >= 0)
                        S.edge[DRAPE_WEFT] += da;
                    int j0 = y > j ? j : j - 1;
                    if (at(L, i, j0) >= 0 && at(L, i, j0 + 1) >= 0)
                        S.edge[DRAPE_WARP] += da;
                }
    return S;
}

START_TEST(test_circle_weights_sampled)
{
    static const double sp[] = {0.01, 0.02};
    for (size_t k = 0; k < 2; k++) {
        drape_scene s;
        circle(&s, 0.30, sp[k]);
        s.support_diameter = 0.0;
        drape_lattice *L = build(&s);
        double r = 0.15 / sp[k], s2 = sp[k] * sp[k];
        sampled S = sample_disc(L, r, 64);
        double disc = PI * r * r;
        /* every sample of the disc lies in some kept particle's cell or is
         * lumped: the kept cells hold the disc less the lumped remainder */
        ck_assert(S.cell_kept <= disc * (1 + 1e-3));
        ck_assert_close_rel(edge_area(L, DRAPE_WEFT) / s2, S.edge[DRAPE_WEFT], 2e-3);
        ck_assert_close_rel(edge_area(L, DRAPE_WARP) / s2, S.edge[DRAPE_WARP], 2e-3);
        ck_assert_close_rel(corner_area(L) / s2, S.corner, 2e-3);
        /* the edges of a circle miss a boundary strip: within a few % */
        ck_assert_close_rel(edge_area(L, DRAPE_WEFT) / s2, disc, 0.05 * sp[k] / 0.01);
        ck_assert_close_rel(edge_area(L, DRAPE_WARP) / s2, disc, 0.05 * sp[k] / 0.01);
        /* each particle: at least its own cell's part, at most that plus
         * its non-kept neighbours' cells */
        for (int p = 0; p < L->n; p++) {
            int i = L->gi[p], j = L->gj[p], c = (L->ni - 1) / 2;
            double own = 0, extra = 0;
            int nsub = 64;
            double h = 1.0 / nsub;
            for (int dj = -1; dj <= 1; dj++)
                for (int di = -1; di <= 1; di++) {
                    int kept = at(L, i + di, j + dj) >= 0;
                    if (kept && (di || dj)) continue;
                    double a = 0;
                    for (int bb = 0; bb < nsub; bb++)
                        for (int aa = 0; aa < nsub; aa++) {
                            double x = i + di - 0.5 + (aa + 0.5) * h - c;
                            double y = j + dj - 0.5 + (bb + 0.5) * h - c;
                            if (x * x + y * y <= r * r) a += h * h;
                        }
                    if (di == 0 && dj == 0) own = a; else extra += a;
                }
            double m = L->mass[p] / (WEIGHT * s2);
            ck_assert_msg(m >= own - 0.02 && m <= own + extra + 0.02,
                          "particle %d: m = %g, own %g, extra %g", p, m, own,
                          extra);
        }
        drape_lattice_free(L);
    }
}
END_TEST

/* ---- strip / cantilever -------------------------------------------------- */

START_TEST(test_strip_warp)
{
    drape_scene s;
    strip(&s, 0.20, 0.025, 0.06, 0.0025, DRAPE_WARP);
    drape_lattice *L = build(&s);
    ck_assert_int_eq(L->ni, 11);
    ck_assert_int_eq(L->nj, 81);
    ck_assert_int_eq(L->n, 891);
    ck_assert_int_eq(count_fixed(L), 57 * 11);
    ck_assert_int_eq(L->n_free, 24 * 11);
    int at_edge = 0;
    double xmin = 1, xmax = -1, ymin = 1, ymax = -1;
    for (int p = 0; p < L->n; p++) {
        const double *x = L->x0 + 3 * p;
        ck_assert_int_eq(L->fixed[p], x[0] <= 0.0);
        at_edge += x[0] == 0.0;
        xmin = fmin(xmin, x[0]); xmax = fmax(xmax, x[0]);
        ymin = fmin(ymin, x[1]); ymax = fmax(ymax, x[1]);
    }
    ck_assert_int_eq(at_edge, 11);
    ck_assert_close_abs(xmin, -0.14, 1e-14);
    ck_assert_close_abs(xmax, 0.06, 1e-14);
    ck_assert_close_abs(ymin, -0.0125, 1e-14);
    ck_assert_close_abs(ymax, 0.0125, 1e-14);
    /* j along +x (warp along the length), frame right-handed */
    int p = at(L, 3, 60);
    ck_assert_close_abs(L->x0[3 * at(L, 3, 61)] - L->x0[3 * p], 0.0025, 1e-15);
    double ax = L->x0[3 * at(L, 4, 60)] - L->x0[3 * p];
    double ay = L->x0[3 * at(L, 4, 60) + 1] - L->x0[3 * p + 1];
    double bx = L->x0[3 * at(L, 3, 61)] - L->x0[3 * p];
    double by = L->x0[3 * at(L, 3, 61) + 1] - L->x0[3 * p + 1];
    ck_assert(ax * by - ay * bx > 0.0);
    for (int e = 0; e < L->n_edges; e++) {
        const drape_edge *E = &L->edges[e];
        int along = fabs(L->x0[3 * E->b] - L->x0[3 * E->a]) > 0.5 * L->sigma;
        ck_assert_int_eq(E->dir, along ? DRAPE_WARP : DRAPE_WEFT);
    }
    /* elements: no shear; warp edges from x = 0 on (24 x 11), weft edges in
     * the 24 free columns (24 x 10); warp hinges at x = 0 .. 5.75 cm
     * (24 x 11), weft hinges in free columns (24 x 9) */
    ck_assert_int_eq(L->n_corners, 0);
    ck_assert_int_eq(L->n_edges, 24 * 11 + 24 * 10);
    ck_assert_int_eq(L->n_hinges, 24 * 11 + 24 * 9);
    /* the clamp hinge counts its overhanging half: along-strip hinges
     * represent 23.5 spacings of length times the width */
    ck_assert_close_rel(hinge_area(L, DRAPE_WARP), 23.5 * 0.0025 * 0.025, 1e-10);
    for (int h = 0; h < L->n_hinges; h++) {
        const drape_hinge *H = &L->hinges[h];
        if (H->dir != DRAPE_WARP) continue;
        int row = L->gi[H->mid];
        double w = (row == 0 || row == 10) ? 0.5 : 1.0;
        double len = 1.0;
        if (L->x0[3 * H->mid] == 0.0) { w *= 0.5; len = 0.5; }
        ck_assert_close_rel(H->weight, w, 1e-12);
        ck_assert_close_rel(H->length, len, 1e-15);
    }
    ck_assert_close_rel(L->mass_total, WEIGHT * 0.20 * 0.025, 1e-10);
    ck_assert_close_rel(L->area_nominal, 0.20 * 0.025, 1e-14);
    drape_lattice_free(L);
}
END_TEST

START_TEST(test_strip_weft_and_nonmultiple)
{
    drape_scene s;
    strip(&s, 0.20, 0.025, 0.06, 0.0025, DRAPE_WEFT);
    drape_lattice *L = build(&s);
    ck_assert_int_eq(L->ni, 81);
    ck_assert_int_eq(L->nj, 11);
    ck_assert_close_abs(L->x0[3 * at(L, 1, 0)] - L->x0[3 * at(L, 0, 0)], 0.0025, 1e-15);
    ck_assert_close_abs(L->x0[3 * at(L, 0, 0)], -0.14, 1e-14);
    ck_assert_close_abs(L->x0[3 * at(L, 56, 5)], 0.0, 0.0);
    ck_assert_int_eq(count_fixed(L), 57 * 11);
    ck_assert_close_rel(hinge_area(L, DRAPE_WEFT), 23.5 * 0.0025 * 0.025, 1e-10);
    drape_lattice_free(L);

    /* 20 cm, 6.1 cm over at 1 cm: 13 points behind the edge, 6 beyond; the
     * 0.9 cm end pieces go to the end particles */
    strip(&s, 0.20, 0.025, 0.061, 0.01, DRAPE_WARP);
    L = build(&s);
    ck_assert_int_eq(L->nj, 20);
    ck_assert_int_eq(L->ni, 3);
    ck_assert_int_eq(count_fixed(L), 14 * 3);
    ck_assert_close_rel(L->mass_total, WEIGHT * 0.20 * 0.025, 1e-10);
    /* back end: its cell plus x in [-13.9, -13.5] cm, the cell of the
     * dropped point x = -14 cm, lumped onto it */
    ck_assert_close_rel(L->mass[at(L, 1, 0)], WEIGHT * 1e-4 * 1.4, 1e-9);
    ck_assert_close_rel(L->mass[at(L, 1, 19)], WEIGHT * 1e-4 * 0.6, 1e-9);
    int zero = 0;
    for (int p = 0; p < L->n; p++) zero += L->x0[3 * p] == 0.0;
    ck_assert_int_eq(zero, 3);
    drape_lattice_free(L);
}
END_TEST

/* Small-deflection cantilever on the lattice's own weights, lengths and
 * masses (linear M = B K): the hinge energy weight sigma^2 B K^2 / 2 with
 * K = (z_prev - 2 z_mid + z_next) / (length sigma^2) and gravity on the
 * masses give a linear system for the centre row's free heights.  The tip
 * must converge at second order to the clamped Euler-Bernoulli beam,
 * z_tip = -W g l^4 / (8 B) (uniform load, clamp at x = 0). */
static double cantilever_tip(double sp)
{
    enum { NMAX = 64 };
    static double A[NMAX][NMAX], b[NMAX], z[NMAX];
    const double B = 1e-5, g = 9.80665;
    drape_scene s;
    strip(&s, 0.20, 0.01, 0.06, sp, DRAPE_WARP);
    s.terms = DRAPE_TERM_BEND | DRAPE_TERM_GRAVITY;
    drape_lattice *L = build(&s);
    int row = (L->ni - 1) / 2, idx[4096], n = 0;
    ck_assert_int_le(L->n, 4096);
    for (int p = 0; p < L->n; p++)
        idx[p] = (L->gi[p] == row && !L->fixed[p]) ? n++ : -1;
    ck_assert_int_le(n, NMAX);
    memset(A, 0, sizeof A);
    for (int p = 0; p < L->n; p++)
        if (idx[p] >= 0) b[idx[p]] = -L->mass[p] * g;
    for (int h = 0; h < L->n_hinges; h++) {
        const drape_hinge *H = &L->hinges[h];
        if (H->dir != DRAPE_WARP || L->gi[H->mid] != row) continue;
        int id[3] = {H->prev, H->mid, H->next};
        double d[3] = {1, -2, 1};
        double c = H->weight * B / (sp * sp * H->length * H->length);
        for (int u = 0; u < 3; u++)
            for (int v = 0; v < 3; v++)
                if (idx[id[u]] >= 0 && idx[id[v]] >= 0)
                    A[idx[id[u]]][idx[id[v]]] += c * d[u] * d[v];
    }
    for (int k = 0; k < n; k++)          /* Gauss, SPD: no pivoting */
        for (int i = k + 1; i < n; i++) {
            double m = A[i][k] / A[k][k];
            for (int j = k; j < n; j++) A[i][j] -= m * A[k][j];
            b[i] -= m * b[k];
        }
    for (int i = n - 1; i >= 0; i--) {
        double r = b[i];
        for (int j = i + 1; j < n; j++) r -= A[i][j] * z[j];
        z[i] = r / A[i][i];
    }
    double tip = 0.0;
    for (int p = 0; p < L->n; p++)
        if (idx[p] >= 0 && fabs(L->x0[3 * p] - 0.06) < 1e-9) tip = z[idx[p]];
    drape_lattice_free(L);
    return tip;
}

START_TEST(test_cantilever_clamp_convergence)
{
    double exact = -WEIGHT * 9.80665 * pow(0.06, 4) / (8 * 1e-5);
    double e1 = cantilever_tip(0.005) / exact - 1;
    double e2 = cantilever_tip(0.0025) / exact - 1;
    double e3 = cantilever_tip(0.00125) / exact - 1;
    ck_assert_msg(fabs(e2) < 3e-3, "tip error at 24 particles %g", e2);
    ck_assert_msg(fabs(e1 / e2 - 4) < 0.2 && fabs(e2 / e3 - 4) < 0.2,
                  "errors %g %g %g: not second order", e1, e2, e3);
}
END_TEST

/* ---- elements, terms, perturbation ---------------------------------------- */

START_TEST(test_terms_select_elements)
{
    drape_scene s;
    rect(&s, DRAPE_SCENE_HANG, 0.10, 0.10, 0.01);
    s.terms = DRAPE_TERM_BEND | DRAPE_TERM_GRAVITY;
    drape_lattice *L = build(&s);
    ck_assert_int_eq(L->n_edges, 0);
    ck_assert_int_eq(L->n_corners, 0);
    ck_assert_int_eq(L->n_hinges, 2 * 9 * 11);
    drape_lattice_free(L);
    s.damping_edge = 0.02; /* dashpots need the edges */
    L = build(&s);
    ck_assert_int_eq(L->n_edges, 2 * 10 * 11);
    drape_lattice_free(L);
    s.terms = DRAPE_TERM_SHEAR;
    s.damping_edge = 0.0;
    L = build(&s);
    ck_assert_int_eq(L->n_edges, 0);
    ck_assert_int_eq(L->n_hinges, 0);
    ck_assert_int_eq(L->n_corners, 400);
    drape_lattice_free(L);
    s.terms = DRAPE_TERM_BEND | DRAPE_TERM_GRAVITY;
    s.damping_shear = 5e-4; /* shear damping needs the corners */
    L = build(&s);
    ck_assert_int_eq(L->n_edges, 0);
    ck_assert_int_eq(L->n_corners, 400);
    drape_lattice_free(L);
}
END_TEST

START_TEST(test_perturbation)
{
    drape_scene s;
    circle(&s, 0.30, 0.01);
    s.has_perturbation = 1;
    s.perturb_kind = DRAPE_PERTURB_PARTICLE;
    s.perturb_amplitude = 1e-4;
    s.perturb_seed = 1;
    drape_lattice *A = build(&s);
    drape_lattice *B = build(&s);
    s.perturb_seed = 2;
    drape_lattice *C = build(&s);
    int same_ab = 1, diff_ac = 0;
    double sum = 0, sum2 = 0;
    for (int p = 0; p < A->n; p++) {
        double z = A->xinit[3 * p + 2];
        if (A->fixed[p]) {
            ck_assert(z == 0.0 && C->xinit[3 * p + 2] == 0.0);
            continue;
        }
        ck_assert(fabs(z) <= 1e-4);
        ck_assert(fabs(C->xinit[3 * p + 2]) <= 1e-4);
        same_ab &= z == B->xinit[3 * p + 2];
        diff_ac += z != C->xinit[3 * p + 2];
        sum += z / 1e-4;
        sum2 += (z / 1e-4) * (z / 1e-4);
        ck_assert(A->xinit[3 * p] == A->x0[3 * p]);
    }
    int nf = A->n_free;
    ck_assert(same_ab);
    ck_assert_int_eq(diff_ac, nf);
    /* U(-1, 1): mean 0 (sd 1/sqrt(3 nf)), mean square 1/3 (sd sqrt(4/45/nf)) */
    ck_assert_msg(fabs(sum / nf) < 5.0 / sqrt(3.0 * nf), "mean %g", sum / nf);
    ck_assert_msg(fabs(sum2 / nf - 1.0 / 3.0) < 5.0 * sqrt(4.0 / 45.0 / nf),
                  "mean square %g", sum2 / nf);
    drape_lattice_free(A);
    drape_lattice_free(B);
    drape_lattice_free(C);

    s.has_perturbation = 0;
    A = build(&s);
    for (int k = 0; k < 3 * A->n; k++) ck_assert(A->xinit[k] == A->x0[k]);
    drape_lattice_free(A);
}
END_TEST

/* The smooth field (docs/model.md 2) belongs to the specimen: the Cusick
 * specimen at 1 cm and at 0.5 cm (every 1 cm lattice point is one of the
 * 0.5 cm lattice) has the same height at the same material point; the
 * height is the taper (r - r_support) / (r_specimen - r_support) times the
 * field drawn with the seed and the scene's band, sampled at the rest
 * position about the specimen's centre; a rectangle (hang) has no taper. */
START_TEST(test_perturbation_field_spacing)
{
    static drape_field F;
    drape_scene s;
    const double A = 1e-4, R = 0.15, Rs = 0.09;
    circle(&s, 2 * R, 0.01);
    s.support_diameter = 2 * Rs;
    s.has_perturbation = 1;
    s.perturb_amplitude = A;
    s.perturb_seed = 5;
    drape_lattice *C = build(&s);
    s.spacing = 0.005;
    drape_lattice *Fn = build(&s);
    double lo, hi;
    int modes;
    drape_scene_perturbation_band(&s, &lo, &hi, &modes);
    ck_assert(lo == 0.02 && hi == 2 * R && modes == 64); /* the model's (docs/model.md) defaults */
    ck_assert_int_eq(drape_field_draw(&F, 5, 64, 0.02, 2 * R, A), 0);
    int shared = 0, raised = 0;
    double zmax = 0.0;
    for (int p = 0; p < C->n; p++) {
        const double *x = C->x0 + 3 * p;
        double z = C->xinit[3 * p + 2], r = hypot(x[0], x[1]);
        int q = -1;
        for (int k = 0; k < Fn->n && q < 0; k++)
            if (fabs(Fn->x0[3 * k] - x[0]) < 1e-9 && fabs(Fn->x0[3 * k + 1] - x[1]) < 1e-9) q = k;
        ck_assert_msg(q >= 0, "1 cm particle at (%g, %g) not on the 0.5 cm lattice", x[0], x[1]);
        shared++;
        ck_assert(C->fixed[p] == Fn->fixed[q]);
        ck_assert_msg(fabs(z - Fn->xinit[3 * q + 2]) <= 1e-12 * A,
                      "at (%g, %g): %.17g at 1 cm, %.17g at 0.5 cm", x[0], x[1], z,
                      Fn->xinit[3 * q + 2]);
        double w = r > Rs ? (r - Rs) / (R - Rs) : 0.0;
        double want = C->fixed[p] ? 0.0 : w * drape_field_height(&F, x[0], x[1]);
        ck_assert_msg(fabs(z - want) <= 1e-12 * A, "at (%g, %g): %.17g, expected %.17g", x[0],
                      x[1], z, want);
        raised += z != 0.0;
        zmax = fmax(zmax, fabs(z));
    }
    ck_assert_int_eq(shared, C->n);
    ck_assert_int_gt(raised, C->n_free / 2);
    ck_assert(zmax > 0.5 * A && zmax < A * sqrt(128.0));
    drape_lattice_free(C);
    drape_lattice_free(Fn);
    /* a rectangle: no taper, the band's default top its larger side;
     * another seed, another field */
    rect(&s, DRAPE_SCENE_HANG, 0.30, 0.20, 0.02);
    s.n_pins = 1;
    s.pins[0][0] = 0;
    s.pins[0][1] = -1;
    s.has_perturbation = 1;
    s.perturb_amplitude = A;
    s.perturb_seed = 6;
    s.perturb_lambda_min = 0.03;
    s.perturb_modes = 10;
    drape_lattice *H = build(&s);
    drape_scene_perturbation_band(&s, &lo, &hi, &modes);
    ck_assert(lo == 0.03 && hi == 0.30 && modes == 10);
    ck_assert_int_eq(drape_field_draw(&F, 6, 10, 0.03, 0.30, A), 0);
    for (int p = 0; p < H->n; p++) {
        const double *x = H->x0 + 3 * p;
        double want = H->fixed[p] ? 0.0 : drape_field_height(&F, x[0], x[1]);
        ck_assert(fabs(H->xinit[3 * p + 2] - want) <= 1e-12 * A);
        ck_assert(H->xinit[3 * p] == x[0] && H->xinit[3 * p + 1] == x[1]);
    }
    drape_lattice_free(H);
}
END_TEST

START_TEST(test_check_detects_damage)
{
    drape_scene s;
    circle(&s, 0.10, 0.01);
    s.support_diameter = 0.04;
    drape_lattice *L = build(&s);
    ck_assert(L->n_free > 0 && L->n_edges > 3 && L->n_hinges > 5);
    double w = L->edges[3].weight;
    L->edges[3].weight = 0.0;
    ck_assert_int_gt(drape_lattice_check(L), 0);
    L->edges[3].weight = w;
    int b = L->hinges[5].next;
    L->hinges[5].next = L->hinges[5].prev;
    ck_assert_int_gt(drape_lattice_check(L), 0);
    L->hinges[5].next = b;
    double m = L->mass[2];
    L->mass[2] = -m;
    ck_assert_int_gt(drape_lattice_check(L), 0);
    L->mass[2] = m;
    int p = L->free_to_id[0];
    L->fixed[p] = 1; /* free numbering now inconsistent */
    ck_assert_int_gt(drape_lattice_check(L), 0);
    L->fixed[p] = 0;
    ck_assert_int_eq(drape_lattice_check(L), 0);
    drape_lattice_free(L);
}
END_TEST

START_TEST(test_bad_input)
{
    drape_scene s;
    drape_error err;
    long ni, nj, n;
    rect(&s, DRAPE_SCENE_HANG, 0.30, 0.30, 0.0);
    drape_error_clear(&err);
    ck_assert_ptr_eq(drape_lattice_new(&s, fabric(), &err), NULL);
    ck_assert_int_eq(err.kind, DRAPE_E_INPUT);
    ck_assert_int_eq(drape_lattice_estimate(&s, &ni, &nj, &n), -1);
    rect(&s, DRAPE_SCENE_HANG, 300.0, 300.0, 1e-6); /* 9e16 points */
    drape_error_clear(&err);
    ck_assert_ptr_eq(drape_lattice_new(&s, fabric(), &err), NULL);
    ck_assert_int_eq(err.kind, DRAPE_E_NOMEM);
    ck_assert_int_eq(drape_lattice_estimate(&s, &ni, &nj, &n), -1);
    strip(&s, 0.20, 0.025, 0.30, 0.01, DRAPE_WARP); /* overhang > length */
    drape_error_clear(&err);
    ck_assert_ptr_eq(drape_lattice_new(&s, fabric(), &err), NULL);
    ck_assert_int_eq(err.kind, DRAPE_E_INPUT);
    ck_assert_str_eq(err.key, "overhang");
}
END_TEST

/* Every allocation of the constructor fails in turn: NULL and E_NOMEM, no
 * crash; then it succeeds. */
static void alloc_walk(const drape_scene *s)
{
    for (long k = 1;; k++) {
        drape_error err;
        drape_error_clear(&err);
        drape_alloc_fail_at(k);
        drape_lattice *L = drape_lattice_new(s, fabric(), &err);
        drape_alloc_fail_at(0);
        if (L) {
            ck_assert_int_gt(k, 1);
            ck_assert_int_eq(drape_lattice_check(L), 0);
            drape_lattice_free(L);
            return;
        }
        ck_assert_int_eq(err.kind, DRAPE_E_NOMEM);
        ck_assert_msg(k < 100, "no success after %ld allocations", k);
    }
}

START_TEST(test_alloc_failures)
{
    drape_scene s;
    circle(&s, 0.30, 0.02);
    s.has_perturbation = 1;
    s.perturb_amplitude = 1e-4;
    alloc_walk(&s);
    rect(&s, DRAPE_SCENE_HANG, 0.30, 0.30, 0.03);
    s.n_pins = 1;
    s.pins[0][0] = -1; s.pins[0][1] = -1;
    alloc_walk(&s);
    strip(&s, 0.20, 0.025, 0.06, 0.01, DRAPE_WARP);
    alloc_walk(&s);
}
END_TEST

Suite *lattice_suite(void);
Suite *lattice_suite(void)
{
    Suite *su = suite_create("lattice");
    TCase *tc = tcase_create("lattice");
    tcase_set_timeout(tc, 60);
    tcase_add_test(tc, test_rect_counts_masses);
    tcase_add_test(tc, test_rect_identities);
    tcase_add_test(tc, test_rect_nonmultiple);
    tcase_add_test(tc, test_hang_pins);
    tcase_add_test(tc, test_table);
    tcase_add_test(tc, test_circle_counts);
    tcase_add_test(tc, test_circle_hand_masses);
    tcase_add_test(tc, test_circle_mass_sums);
    tcase_add_test(tc, test_circle_weights_sampled);
    tcase_add_test(tc, test_strip_warp);
    tcase_add_test(tc, test_strip_weft_and_nonmultiple);
    tcase_add_test(tc, test_cantilever_clamp_convergence);
    tcase_add_test(tc, test_terms_select_elements);
    tcase_add_test(tc, test_perturbation);
    tcase_add_test(tc, test_perturbation_field_spacing);
    tcase_add_test(tc, test_check_detects_damage);
    tcase_add_test(tc, test_bad_input);
    tcase_add_test(tc, test_alloc_failures);
    suite_add_tcase(su, tc);
    return su;
}
