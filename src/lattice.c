/* lattice.c: the particle lattice of a specimen (docs/model.md sections 2, 3, 5).
 *
 * What it builds (see lattice.h for the world placement and docs/lattice.md
 * for the full description):
 *
 *   - the grid: one particle per lattice point (i, j) at spacing sigma that
 *     lies in the specimen (rectangle, circle centred on a lattice point,
 *     strip with a particle exactly on the platform edge x = 0);
 *   - lumped masses (docs/model.md 2):  m_p = W * (A(C_p & S) + lumped),       (L1)
 *     C_p the sigma x sigma cell centred on p, S the specimen, and
 *     "lumped" the area A(C_q & S) of every lattice point q that is not a
 *     particle, given in equal shares to the particle(s) nearest to q.  The
 *     cells of all lattice points tile the plane, so sum m_p = W * A(S)
 *     up to rounding;
 *   - element weights (docs/model.md 3), each the fraction of a full element's area
 *     that lies inside the specimen:
 *       edge   w_e = A(R_e & S) / sigma^2,  R_e: sigma (along) x sigma
 *              (across) rectangle centred on the edge's midpoint;     (L2)
 *       hinge  w_h = A(C_mid & S) / sigma^2 * lambda, length lambda = 1/2
 *              for the along-strip hinge at the last clamped particle of a
 *              cantilever, 1 otherwise (docs/model.md 5): that hinge stands for
 *              [0, sigma/2] only, so its area and the length its turning
 *              angle is spread over are both halved; the model uses
 *              K = psi / (lambda sigma).  Halving the weight alone (K still
 *              psi / sigma) makes the spring softer instead of stiffer and
 *              the tip drop first-order wrong (docs/lattice.md);     (L3)
 *       corner w_c = A(Q_c & S) / (sigma^2 / 4), Q_c the sigma/2 x sigma/2
 *              quarter cell between mid and its two neighbours;       (L4)
 *       cell   w_q = A(Q & S) / sigma^2, Q the square (i, j)-(i+1, j+1)
 *              whose four corners are particles; built only with the
 *              bias term and a fabric with a bias curve;   (L5)
 *   - a strip cut at an angle to the yarns: the rectangle
 *     rotated in the grid, areas by polygon clipping (rot_area); hinges at
 *     the platform edge keep the part of their interval beyond it (L3'),
 *     and the areas of missing hinges and cells along the staircase edges
 *     are lumped onto the nearest ones (L6; weights may exceed 1);
 *   - the fixed set (clamps of each scene kind, pins) and free numbering;
 *   - the optional perturbation of free particles (docs/model.md 2): the
 *     smooth random height field of perturbation.h sampled at each rest
 *     position (x, y), z += w(x, y) h(x, y), w the Cusick scene's taper
 *     (r - r_support) / (r_specimen - r_support) clipped at 0 and 1
 *     elsewhere; or (kind: particle) z += a * U(-1, 1) in id order.
 *
 * Geometry is done in grid-index units (sigma = 1): the cell of (i, j) is
 * [i - 1/2, i + 1/2] x [j - 1/2, j + 1/2] and the specimen is an axis-aligned
 * rectangle or a disc in the same units, so every area above is either a
 * product of interval overlaps (exact) or a disc-rectangle intersection
 * computed in closed form (disc_rect_area below).
 */
#include "drape/lattice.h"

#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "drape/alloc.h"
#include "drape/perturbation.h"

/* Snap tolerance (relative, in grid-index units): a dimension within 1e-9
 * spacings of a multiple of sigma counts as that multiple, and a point
 * within 1e-9 (relative) of a specimen/clamp boundary counts as on it.
 * Protects the counts against rounding of inputs like 0.3 / 0.01. */
static const double SNAP = 1e-9;

/* Largest grid (bounding box, points) accepted: every id, and 4x the
 * particle count (corners), must fit an int, with margin. */
static const long MAX_GRID_POINTS = INT_MAX / 8;

/* Part of the clamp hinge's vertex interval [-sigma/2, sigma/2] that
 * overhangs the platform edge x = 0 (docs/model.md 5). */
static const double CLAMP_HINGE_FRACTION = 0.5;

/* Smallest such fraction of an oblique strip's hinge whose whole vertex
 * interval lies on the platform: a hinge 1 / 0.05 = 20 times
 * stiffer than a free one, which holds its yarn straight. */
static const double CLAMP_HINGE_MIN = 0.05;

/* Geometry of a scene in grid-index units. */
typedef struct geom {
    int ni, nj;
    int disc;             /* 1: specimen is the disc |(i,j) - (ci,cj)| <= r */
    double r;             /* disc radius, index units */
    double lo[2], hi[2];  /* rectangle specimen, index units ([0]: i) */
    double ci, cj;        /* grid index of the world origin */
    int swap;             /* 1 (warp strip): x = (j - cj) s, y = -(i - ci) s */
    int rot;              /* 1 (oblique strip): the world position is
                             x = ((i - ci) rs + (j - cj) rc) s,
                             y = (-(i - ci) rc + (j - cj) rs) s, and lo/hi
                             bound the strip in those rotated index units */
    double rs, rc;        /* sin and cos of the strip's angle from the warp */
} geom;

/* ---- areas ----------------------------------------------------------- */

/* P(x) = integral_0^x sqrt(r^2 - t^2) dt = (x sqrt(r^2 - x^2)
 * + r^2 asin(x / r)) / 2 for 0 <= x <= r. */
static double circ_prim(double x, double r)
{
    double q = x / r;
    if (q > 1.0) q = 1.0;
    return 0.5 * (x * sqrt(fmax(r * r - x * x, 0.0)) + r * r * asin(q));
}

/* g(a, b) = area of {0 <= X <= a, 0 <= Y <= b, X^2 + Y^2 <= r^2}, a, b >= 0.
 * Derivation: clip a, b to r (the disc ends there).  If the corner (a, b)
 * is inside the disc the whole rectangle is: g = a b.  Otherwise the arc
 * Y = sqrt(r^2 - X^2) crosses Y = b at X = xc = sqrt(r^2 - b^2) < a, and
 *   g = int_0^a min(b, sqrt(r^2 - X^2)) dX = b xc + P(a) - P(xc). */
static double quad_area(double a, double b, double r)
{
    if (a > r) a = r;
    if (b > r) b = r;
    if (a * a + b * b <= r * r) return a * b;
    double xc = sqrt(fmax(r * r - b * b, 0.0));
    return b * xc + circ_prim(a, r) - circ_prim(xc, r);
}

/* G(x, y) = oriented integral_0^x integral_0^y 1_disc dY dX.  The disc is
 * symmetric in X and Y, so G(x, y) = sgn(x) sgn(y) g(|x|, |y|). */
static double quad_signed(double x, double y, double r)
{
    double v = quad_area(fabs(x), fabs(y), r);
    return ((x < 0) != (y < 0)) ? -v : v;
}

/* Area of [x0, x1] x [y0, y1] inside the disc of radius r centred at the
 * origin (x0 <= x1, y0 <= y1): inclusion-exclusion on G,
 *   A = G(x1, y1) - G(x0, y1) - G(x1, y0) + G(x0, y0). */
static double disc_rect_area(double x0, double x1, double y0, double y1,
                             double r)
{
    double a = quad_signed(x1, y1, r) - quad_signed(x0, y1, r)
             - quad_signed(x1, y0, r) + quad_signed(x0, y0, r);
    double full = (x1 - x0) * (y1 - y0);
    if (a < 0.0) a = 0.0;
    if (a > full) a = full;
    return a;
}

static double overlap(double a0, double a1, double b0, double b1)
{
    double lo = a0 > b0 ? a0 : b0, hi = a1 < b1 ? a1 : b1;
    return hi > lo ? hi - lo : 0.0;
}

/* Rotated index units of a grid point (oblique strip). */
static void rot_xy(const geom *g, double i, double j, double *X, double *Y)
{
    double u = i - g->ci, v = j - g->cj;
    *X = u * g->rs + v * g->rc;
    *Y = -u * g->rc + v * g->rs;
}

/* Clip the convex polygon P (n points, x/y pairs) to the half-plane
 * s * (coord k) <= s * c (k = 0: X, 1: Y); returns the new count (<= n + 1). */
static int clip_half(const double *P, int n, int k, double c, double s, double *Q)
{
    int m = 0;
    for (int a = 0; a < n; a++) {
        const double *p = P + 2 * a, *q = P + 2 * ((a + 1) % n);
        double dp = s * (p[k] - c), dq = s * (q[k] - c);
        if (dp <= 0.0) { Q[2 * m] = p[0]; Q[2 * m + 1] = p[1]; m++; }
        if ((dp < 0.0 && dq > 0.0) || (dp > 0.0 && dq < 0.0)) {
            double t = dp / (dp - dq);
            Q[2 * m] = p[0] + t * (q[0] - p[0]);
            Q[2 * m + 1] = p[1] + t * (q[1] - p[1]);
            m++;
        }
    }
    return m;
}

/* Area (index units) of the grid rectangle [x0, x1] x [y0, y1] inside the
 * oblique strip, and, with free_only, only its part beyond the platform
 * edge X > 0: the grid rectangle rotated into the strip's frame, clipped
 * by the strip's sides (Sutherland-Hodgman on a convex polygon), area by
 * the shoelace formula. */
static double rot_area(const geom *g, double x0, double x1, double y0, double y1,
                       int free_only)
{
    double P[2][2 * 10];
    rot_xy(g, x0, y0, &P[0][0], &P[0][1]);
    rot_xy(g, x1, y0, &P[0][2], &P[0][3]);
    rot_xy(g, x1, y1, &P[0][4], &P[0][5]);
    rot_xy(g, x0, y1, &P[0][6], &P[0][7]);
    int n = 4, cur = 0;
    const double lim[5][3] = {{0, g->hi[0], 1.0}, {0, g->lo[0], -1.0}, {1, g->hi[1], 1.0},
                              {1, g->lo[1], -1.0}, {0, 0.0, -1.0}};
    for (int k = 0; k < (free_only ? 5 : 4) && n > 0; k++) {
        n = clip_half(P[cur], n, (int)lim[k][0], lim[k][1], lim[k][2], P[1 - cur]);
        cur = 1 - cur;
    }
    double a = 0.0;
    for (int k = 0; k < n; k++) {
        const double *p = P[cur] + 2 * k, *q = P[cur] + 2 * ((k + 1) % n);
        a += p[0] * q[1] - q[0] * p[1];
    }
    return 0.5 * fabs(a);
}

/* Area (index units) of the rectangle spanned by (x0, y0), (x1, y1) (any
 * order) inside the specimen. */
static double spec_area(const geom *g, double x0, double x1, double y0,
                        double y1)
{
    double t;
    if (x0 > x1) { t = x0; x0 = x1; x1 = t; }
    if (y0 > y1) { t = y0; y0 = y1; y1 = t; }
    if (g->rot) return rot_area(g, x0, x1, y0, y1, 0);
    if (g->disc)
        return disc_rect_area(x0 - g->ci, x1 - g->ci, y0 - g->cj, y1 - g->cj,
                              g->r);
    return overlap(x0, x1, g->lo[0], g->hi[0])
         * overlap(y0, y1, g->lo[1], g->hi[1]);
}

/* The part of the grid rectangle that can bend and twist: inside the
 * specimen and, on an oblique cantilever strip, beyond the platform edge
 * (on the platform nothing bends; L5, L6). */
static double free_area(const geom *g, const drape_scene *s, double x0, double x1,
                        double y0, double y1)
{
    if (g->rot) return rot_area(g, x0, x1, y0, y1, s->kind == DRAPE_SCENE_CANTILEVER);
    return spec_area(g, x0, x1, y0, y1);
}

static double cell_area(const geom *g, int i, int j)
{
    return spec_area(g, i - 0.5, i + 0.5, j - 0.5, j + 0.5);
}

/* Weight in (0, 1]: a fraction of a full area. */
static double frac(double area, double full)
{
    double w = area / full;
    return w > 1.0 ? 1.0 : w;
}

/* ---- geometry ---------------------------------------------------------- */

/* Number of lattice points on a side of length `len` (metres): the lattice
 * covers floor(len / s) spacings.  -1 if absurd. */
static long side_points(double len, double s)
{
    double v = len / s;
    if (!isfinite(v) || v < 0.0 || v > (double)MAX_GRID_POINTS) return -1;
    return (long)floor(v + SNAP) + 1;
}

static int is_kept(const geom *g, int i, int j)
{
    if (i < 0 || j < 0 || i >= g->ni || j >= g->nj) return 0;
    if (g->rot) {
        double X, Y, e = SNAP * (1.0 + fabs(g->lo[0]) + fabs(g->hi[0]));
        rot_xy(g, i, j, &X, &Y);
        return X >= g->lo[0] - e && X <= g->hi[0] + e && Y >= g->lo[1] - e &&
               Y <= g->hi[1] + e;
    }
    if (!g->disc) return 1;
    double di = i - g->ci, dj = j - g->cj, rr = g->r * (1.0 + SNAP);
    return di * di + dj * dj <= rr * rr;
}

static int pos_ok(double v) { return isfinite(v) && v > 0.0; }

/* Fill g from the scene.  Returns 0; -1 for invalid input (E_INPUT);
 * -2 for a lattice too large (E_NOMEM).  err may be NULL.  No allocation. */
static int geom_init(const drape_scene *s, geom *g, drape_error *err)
{
    const char *file = s->path;
    double sp = s->spacing;
    long ni = 0, nj = 0;

    memset(g, 0, sizeof *g);
    if (!pos_ok(sp))
        return drape_error_set(err, DRAPE_E_INPUT, file, 0, 0, "spacing",
                               "lattice spacing must be positive, got %g", sp);
    switch (s->shape) {
    case DRAPE_SHAPE_RECTANGLE:
        if (!pos_ok(s->width) || !pos_ok(s->height))
            return drape_error_set(err, DRAPE_E_INPUT, file, 0, 0, "specimen",
                                   "rectangle needs positive width and height");
        ni = side_points(s->width, sp);
        nj = side_points(s->height, sp);
        if (ni < 0 || nj < 0) break;
        g->ci = 0.5 * (double)(ni - 1);
        g->cj = 0.5 * (double)(nj - 1);
        g->lo[0] = g->ci - 0.5 * s->width / sp;
        g->hi[0] = g->ci + 0.5 * s->width / sp;
        g->lo[1] = g->cj - 0.5 * s->height / sp;
        g->hi[1] = g->cj + 0.5 * s->height / sp;
        break;
    case DRAPE_SHAPE_CIRCLE: {
        if (!pos_ok(s->diameter))
            return drape_error_set(err, DRAPE_E_INPUT, file, 0, 0,
                                   "specimen.diameter",
                                   "circle needs a positive diameter");
        long m = side_points(0.5 * s->diameter, sp);
        if (m < 0) break;
        m -= 1;
        ni = nj = 2 * m + 1;
        g->disc = 1;
        g->r = 0.5 * s->diameter / sp;
        g->ci = g->cj = (double)m;
        break;
    }
    case DRAPE_SHAPE_STRIP: {
        double len = s->length, ov = s->overhang;
        if (!pos_ok(len) || !pos_ok(s->width))
            return drape_error_set(err, DRAPE_E_INPUT, file, 0, 0, "specimen",
                                   "strip needs positive length and width");
        if (!isfinite(ov) || ov < 0.0 || ov > len * (1.0 + SNAP))
            return drape_error_set(err, DRAPE_E_INPUT, file, 0, 0, "overhang",
                                   "overhang %g m outside [0, length %g m]",
                                   ov, len);
        double back = len - ov; /* clamped length, x in [-back, 0] */
        if (back < 0.0) back = 0.0;
        long nb = side_points(back, sp) - 1;  /* points at x < 0 */
        long nf = side_points(ov, sp) - 1;    /* points at x > 0 */
        long nw = side_points(s->width, sp);
        if (nb < 0 || nf < 0 || nw < 0) { ni = -1; break; }
        long nlen = nb + nf + 1;
        double c_len = (double)nb, c_w = 0.5 * (double)(nw - 1);
        double lo_len = c_len - back / sp, hi_len = c_len + ov / sp;
        double lo_w = c_w - 0.5 * s->width / sp, hi_w = c_w + 0.5 * s->width / sp;
        if (s->strip_oblique) { /* the rotated rectangle */
            double a = s->strip_angle * 3.14159265358979323846 / 180.0;
            g->rot = 1;
            g->rs = sin(a);
            g->rc = cos(a);
            g->lo[0] = -back / sp; g->hi[0] = ov / sp;
            g->lo[1] = -0.5 * s->width / sp; g->hi[1] = 0.5 * s->width / sp;
            double umin = INFINITY, umax = -INFINITY, vmin = INFINITY, vmax = -INFINITY;
            for (int k = 0; k < 4; k++) {
                double X = k & 1 ? g->hi[0] : g->lo[0], Y = k & 2 ? g->hi[1] : g->lo[1];
                double u = X * g->rs - Y * g->rc, v = X * g->rc + Y * g->rs;
                umin = fmin(umin, u); umax = fmax(umax, u);
                vmin = fmin(vmin, v); vmax = fmax(vmax, v);
            }
            if (!(umax - umin < (double)MAX_GRID_POINTS && vmax - vmin < (double)MAX_GRID_POINTS)) {
                ni = -1;
                break;
            }
            double i0 = floor(umin - SNAP), j0 = floor(vmin - SNAP);
            g->ci = -i0;
            g->cj = -j0;
            ni = (long)(ceil(umax + SNAP) - i0) + 1;
            nj = (long)(ceil(vmax + SNAP) - j0) + 1;
            break;
        }
        if (s->strip_dir == DRAPE_WARP) { /* j along +x, i along -y */
            g->swap = 1;
            ni = nw; nj = nlen;
            g->ci = c_w; g->cj = c_len;
            g->lo[0] = lo_w; g->hi[0] = hi_w;
            g->lo[1] = lo_len; g->hi[1] = hi_len;
        } else {                          /* i along +x, j along +y */
            ni = nlen; nj = nw;
            g->ci = c_len; g->cj = c_w;
            g->lo[0] = lo_len; g->hi[0] = hi_len;
            g->lo[1] = lo_w; g->hi[1] = hi_w;
        }
        break;
    }
    default:
        return drape_error_set(err, DRAPE_E_INPUT, file, 0, 0, "specimen.shape",
                               "unknown specimen shape %d", (int)s->shape);
    }
    if (ni < 1 || nj < 1 || ni > MAX_GRID_POINTS / nj) {
        drape_error_set(err, DRAPE_E_NOMEM, file, 0, 0, "spacing",
                        "lattice too large for spacing %g m (more than %ld "
                        "grid points)", sp, MAX_GRID_POINTS);
        return -2;
    }
    g->ni = (int)ni;
    g->nj = (int)nj;
    return 0;
}

/* ---- construction ------------------------------------------------------ */

static int grid_at(const drape_lattice *L, int i, int j)
{
    if (i < 0 || j < 0 || i >= L->ni || j >= L->nj) return -1;
    return L->grid[(size_t)j * (size_t)L->ni + (size_t)i];
}

/* Masses (L1).  Every lattice point q of the grid grown by one ring (cells
 * beyond it cannot meet the specimen: the kept points reach to within one
 * spacing of its boundary) contributes W * A(C_q & S): to itself if kept,
 * else in equal shares to the kept particle(s) nearest to q (ties split;
 * searched among the 8 neighbours, which are nearer than any other point,
 * else over all particles). */
static void lump_masses(drape_lattice *L, const geom *g, double W)
{
    double s2 = L->sigma * L->sigma;
    for (int j = -1; j <= L->nj; j++) {
        for (int i = -1; i <= L->ni; i++) {
            double a = cell_area(g, i, j);
            if (a <= 0.0) continue;
            int p = grid_at(L, i, j);
            if (p >= 0) { L->mass[p] += W * a * s2; continue; }
            int best = INT_MAX, cnt = 0;
            for (int pass = 0; pass < 2; pass++) {
                for (int dj = -1; dj <= 1; dj++)
                    for (int di = -1; di <= 1; di++) {
                        int q = grid_at(L, i + di, j + dj);
                        if (q < 0 || (di == 0 && dj == 0)) continue;
                        int d2 = di * di + dj * dj;
                        if (pass == 0 && d2 < best) best = d2;
                        if (pass == 1 && d2 == best) cnt++;
                    }
            }
            if (cnt > 0) {
                for (int dj = -1; dj <= 1; dj++)
                    for (int di = -1; di <= 1; di++) {
                        int q = grid_at(L, i + di, j + dj);
                        if (q < 0 || (di == 0 && dj == 0)) continue;
                        if (di * di + dj * dj == best)
                            L->mass[q] += W * a * s2 / cnt;
                    }
                continue;
            }
            /* no neighbour kept (only with sigma comparable to the
             * specimen): brute-force nearest particles */
            long bestl = LONG_MAX;
            for (int q = 0; q < L->n; q++) {
                long di = L->gi[q] - i, dj = L->gj[q] - j;
                long d2 = di * di + dj * dj;
                if (d2 < bestl) { bestl = d2; cnt = 1; }
                else if (d2 == bestl) cnt++;
            }
            for (int q = 0; q < L->n; q++) {
                long di = L->gi[q] - i, dj = L->gj[q] - j;
                if (di * di + dj * dj == bestl) L->mass[q] += W * a * s2 / cnt;
            }
        }
    }
}

/* Clamps of the scene kind (world coordinates). */
static int clamped_by_kind(const drape_scene *s, const double *x)
{
    double sp = s->spacing;
    switch (s->kind) {
    case DRAPE_SCENE_CUSICK: {
        double r = 0.5 * s->support_diameter * (1.0 + SNAP);
        return x[0] * x[0] + x[1] * x[1] <= r * r;
    }
    case DRAPE_SCENE_TABLE: {
        double h = 0.5 * s->table_size * (1.0 + SNAP);
        if (s->table_shape == DRAPE_TABLE_ROUND)
            return x[0] * x[0] + x[1] * x[1] <= h * h;
        return fabs(x[0]) <= h && fabs(x[1]) <= h;
    }
    case DRAPE_SCENE_CANTILEVER:
        return x[0] <= SNAP * sp;
    case DRAPE_SCENE_HANG:
    default:
        return 0;
    }
}

/* Pins: (i, j) with negative values counting from the end. */
static int apply_pins(drape_lattice *L, const drape_scene *s,
                      drape_error *err)
{
    for (int k = 0; k < s->n_pins && k < DRAPE_SCENE_MAX_PINS; k++) {
        int i = s->pins[k][0], j = s->pins[k][1];
        int ii = i < 0 ? L->ni + i : i, jj = j < 0 ? L->nj + j : j;
        char key[32];
        snprintf(key, sizeof key, "pins[%d]", k);
        if (ii < 0 || jj < 0 || ii >= L->ni || jj >= L->nj)
            return drape_error_set(err, DRAPE_E_INPUT, s->path, 0, 0, key,
                                   "pin (%d, %d) is outside the %d x %d "
                                   "lattice (i in [-%d, %d], j in [-%d, %d])",
                                   i, j, L->ni, L->nj, L->ni, L->ni - 1,
                                   L->nj, L->nj - 1);
        int p = grid_at(L, ii, jj);
        if (p < 0)
            return drape_error_set(err, DRAPE_E_INPUT, s->path, 0, 0, key,
                                   "pin (%d, %d) is a lattice point outside "
                                   "the specimen", i, j);
        L->fixed[p] = 1;
    }
    return 0;
}

/* The hinge of direction d that the area of lattice point (i, j) goes to
 * (L6): the nearest one along the same yarn within 3 spacings, else the
 * nearest in the plane.  A clamp hinge (L3') takes area too: its K =
 * psi / (length sigma) is the curvature of the strip just beyond the
 * edge, where that area lies; but not one held at CLAMP_HINGE_MIN, whose
 * interval lies on the platform (a stiff hinge that keeps the yarn
 * straight, not a piece of bending fabric).  -1 if there is none. */
static int takes_area(const drape_hinge *H)
{
    return H->length <= 0.0 || H->length > CLAMP_HINGE_MIN;
}

static int nearest_hinge(const drape_lattice *L, const int *hid, int i, int j, int d)
{
    static const int step[2][2] = {{1, 0}, {0, 1}};
    for (int r = 1; r <= 3; r++)
        for (int sg = -1; sg <= 1; sg += 2) {
            int ii = i + sg * r * step[d][0], jj = j + sg * r * step[d][1];
            if (grid_at(L, ii, jj) < 0) continue;
            int h = hid[2 * ((long)jj * L->ni + ii) + d];
            if (h >= 0 && takes_area(&L->hinges[h])) return h;
        }
    int best = -1;
    long best_d2 = LONG_MAX;
    for (int h = 0; h < L->n_hinges; h++) {
        const drape_hinge *H = &L->hinges[h];
        if ((int)H->dir != d || !takes_area(H)) continue;
        long di = L->gi[H->mid] - i, dj = L->gj[H->mid] - j, d2 = di * di + dj * dj;
        if (d2 < best_d2) best_d2 = d2, best = h;
    }
    return best;
}

/* Oblique strip (L6): along a staircase edge some particles lack
 * a neighbour in a yarn direction, so they carry no hinge in it, and some
 * squares inside the strip lack a corner, so there is no twist cell: that
 * area would bend and twist with no stiffness, a band about sigma wide
 * along each free edge.  Each such area (the particle's cell inside the
 * strip; the square's part inside the strip) is added to the weight of the
 * nearest element of the same family along the same yarn (hinges) or
 * next to it (cells), as masses are lumped (L1).  Weights may then exceed
 * 1. */
static int lump_edge_areas(drape_lattice *L, const geom *g, const drape_scene *s)
{
    int *hid = drape_calloc((size_t)L->ni * L->nj * 2, sizeof(int));
    int *qid = drape_calloc((size_t)L->ni * L->nj, sizeof(int));
    if (!hid || !qid) { drape_free(hid); drape_free(qid); return -1; }
    for (long k = 0; k < 2L * L->ni * L->nj; k++) hid[k] = -1;
    for (long k = 0; k < (long)L->ni * L->nj; k++) qid[k] = -1;
    for (int h = 0; h < L->n_hinges; h++) {
        const drape_hinge *H = &L->hinges[h];
        hid[2 * ((long)L->gj[H->mid] * L->ni + L->gi[H->mid]) + H->dir] = h;
    }
    for (int c = 0; c < L->n_cells; c++) {
        int p = L->cells[c].p[0];
        qid[(long)L->gj[p] * L->ni + L->gi[p]] = c;
    }
    /* every lattice point, particle or not, whose cell reaches into the
     * strip beyond the platform edge (only that part: on the platform
     * nothing bends) and has no hinge in direction d */
    for (int j = -1; j <= L->nj && L->n_hinges > 0; j++)
        for (int i = -1; i <= L->ni; i++) {
            int p = grid_at(L, i, j);
            double a = free_area(g, s, i - 0.5, i + 0.5, j - 0.5, j + 0.5);
            if (a <= SNAP) continue;
            for (int d = 0; d < 2; d++) {
                if (p >= 0 && hid[2 * ((long)j * L->ni + i) + d] >= 0) continue;
                int h = nearest_hinge(L, hid, i, j, d);
                if (h >= 0) L->hinges[h].weight += a; /* weight: area / sigma^2 */
            }
        }
    if (L->n_cells > 0) {
        for (int j = -1; j < L->nj; j++)
            for (int i = -1; i < L->ni; i++) {
                if (i >= 0 && j >= 0 && qid[(long)j * L->ni + i] >= 0) continue;
                double a = free_area(g, s, i, i + 1.0, j, j + 1.0);
                if (a <= SNAP) continue;
                /* the nearest cell: rings of growing radius, nearest first */
                int done = 0;
                for (int r = 1; r <= 3 && !done; r++)
                    for (int d2 = 1; d2 <= 2 * r * r && !done; d2++)
                        for (int dj = -r; dj <= r && !done; dj++)
                            for (int di = -r; di <= r && !done; di++) {
                                if (di * di + dj * dj != d2) continue;
                                int ii = i + di, jj = j + dj;
                                if (ii < 0 || jj < 0 || ii >= L->ni || jj >= L->nj) continue;
                                int c = qid[(long)jj * L->ni + ii];
                                if (c >= 0) { L->cells[c].weight += a; done = 1; }
                            }
            }
    }
    drape_free(hid);
    drape_free(qid);
    return 0;
}

/* Elements (L2-L6).  With fill = 0 only counts; with fill = 1 stores into
 * the arrays (already sized by the counting pass).  -1: out of memory. */
static int build_elements(drape_lattice *L, const geom *g,
                           const drape_scene *s, const drape_fabric *f,
                           int want_cells, int fill)
{
    int want_edges = (s->terms & DRAPE_TERM_STRETCH) || s->damping_edge > 0.0;
    int want_hinges = (s->terms & DRAPE_TERM_BEND) != 0;
    int want_corners = (s->terms & DRAPE_TERM_SHEAR) || drape_scene_damping_shear(s, f) > 0.0;
    int ne = 0, nh = 0, nc = 0, nq = 0;
    /* direction d: DRAPE_WEFT steps i, DRAPE_WARP steps j */
    static const int step[2][2] = {{1, 0}, {0, 1}};
    static const int quad[4][2] = {{1, 1}, {-1, 1}, {-1, -1}, {1, -1}};

    for (int p = 0; p < L->n; p++) {
        int i = L->gi[p], j = L->gj[p];
        for (int d = 0; d < 2 && want_edges; d++) {
            int q = grid_at(L, i + step[d][0], j + step[d][1]);
            if (q < 0 || (L->fixed[p] && L->fixed[q])) continue;
            if (fill) {
                drape_edge *e = &L->edges[ne];
                e->a = p; e->b = q; e->dir = (drape_dir)d;
                /* sigma along the edge, sigma across, centred on its middle */
                double mi = i + 0.5 * step[d][0], mj = j + 0.5 * step[d][1];
                e->weight = frac(spec_area(g, mi - 0.5, mi + 0.5,
                                           mj - 0.5, mj + 0.5), 1.0);
            }
            ne++;
        }
        for (int d = 0; d < 2 && want_hinges; d++) {
            int a = grid_at(L, i - step[d][0], j - step[d][1]);
            int b = grid_at(L, i + step[d][0], j + step[d][1]);
            if (a < 0 || b < 0) continue;
            int nfix = L->fixed[a] + L->fixed[p] + L->fixed[b];
            if (nfix == 3) continue;
            if (fill) {
                drape_hinge *h = &L->hinges[nh];
                h->prev = a; h->mid = p; h->next = b; h->dir = (drape_dir)d;
                h->weight = frac(cell_area(g, i, j), 1.0);
                h->length = 1.0;
                /* cantilever clamp (docs/model.md 5, L3): the hinge at the last
                 * clamped particle, along the strip, stands for its
                 * overhanging half [0, sigma/2] only: half the area, and
                 * its turning psi is spread over sigma/2 (K = 2 psi/sigma) */
                if (s->kind == DRAPE_SCENE_CANTILEVER && !g->rot && L->fixed[p]
                    && L->fixed[a] != L->fixed[b]
                    && fabs(L->x0[3 * a] - L->x0[3 * b]) > L->sigma) {
                    h->weight *= CLAMP_HINGE_FRACTION;
                    h->length = CLAMP_HINGE_FRACTION;
                }
                /* oblique strip (L3'): the same rule for yarns
                 * that cross the platform edge x = 0 at an angle: the
                 * hinge stands for the part of its vertex interval
                 * [-sigma/2, sigma/2] (along its yarn) beyond the edge,
                 * lambda = (x_p + sigma |g| / 2) / (sigma |g|) in [0, 1],
                 * g = dx/ds along the yarn; an interval wholly on the
                 * platform keeps CLAMP_HINGE_MIN (a stiff hinge: the yarn
                 * stays straight up to the edge) */
                if (s->kind == DRAPE_SCENE_CANTILEVER && g->rot &&
                    (L->fixed[a] || L->fixed[p] || L->fixed[b])) {
                    double gx = fabs(L->x0[3 * b] - L->x0[3 * a]) / (2.0 * L->sigma);
                    double lam = gx > 1e-12
                                     ? (L->x0[3 * p] + 0.5 * L->sigma * gx) / (L->sigma * gx)
                                     : 1.0;
                    if (lam > 1.0) lam = 1.0;
                    if (lam < CLAMP_HINGE_MIN) lam = CLAMP_HINGE_MIN;
                    h->weight *= lam;
                    h->length = lam;
                }
            }
            nh++;
        }
        for (int c = 0; c < 4 && want_corners; c++) {
            int wf = grid_at(L, i + quad[c][0], j);
            int wp = grid_at(L, i, j + quad[c][1]);
            if (wf < 0 || wp < 0) continue;
            if (L->fixed[p] && L->fixed[wf] && L->fixed[wp]) continue;
            if (fill) {
                drape_corner *k = &L->corners[nc];
                k->mid = p; k->warp = wp; k->weft = wf;
                k->weight = frac(spec_area(g, i, i + 0.5 * quad[c][0],
                                           j, j + 0.5 * quad[c][1]), 0.25);
            }
            nc++;
        }
        if (want_cells) { /* (L5) the square (i, j)-(i+1, j+1) */
            int q[4] = {p, grid_at(L, i + 1, j), grid_at(L, i + 1, j + 1),
                        grid_at(L, i, j + 1)};
            if (q[1] < 0 || q[2] < 0 || q[3] < 0) continue;
            if (L->fixed[q[0]] && L->fixed[q[1]] && L->fixed[q[2]] && L->fixed[q[3]])
                continue;
            double wq = frac(free_area(g, s, i, i + 1.0, j, j + 1.0), 1.0);
            if (!(wq > SNAP)) continue;
            if (fill) {
                drape_cell *k = &L->cells[nq];
                memcpy(k->p, q, sizeof q);
                k->weight = wq;
            }
            nq++;
        }
    }
    L->n_edges = ne;
    L->n_hinges = nh;
    L->n_corners = nc;
    L->n_cells = nq;
    if (fill && g->rot) return lump_edge_areas(L, g, s);
    return 0;
}

/* The perturbation's taper w(x, y) (docs/model.md 2): in the Cusick scene
 * (r - r_support) / (r_specimen - r_support), clipped at 0, so the field
 * vanishes at the support's edge; 1 elsewhere. */
static double taper(const drape_scene *s, const double *x)
{
    if (s->kind != DRAPE_SCENE_CUSICK || !(s->diameter > s->support_diameter)) return 1.0;
    double r = hypot(x[0], x[1]);
    double w = (r - 0.5 * s->support_diameter) / (0.5 * (s->diameter - s->support_diameter));
    return w > 0.0 ? w : 0.0;
}

/* Raise the free particles by the scene's perturbation (docs/model.md 2,
 * perturbation.h): the smooth field, tapered, sampled at each rest
 * position; or amplitude * U(-1, 1) per particle in id order. */
static int perturb(drape_lattice *L, const drape_scene *s, drape_error *err)
{
    drape_rng g;
    if (s->perturb_kind == DRAPE_PERTURB_PARTICLE) {
        drape_rng_seed(&g, (uint64_t)s->perturb_seed);
        for (int p = 0; p < L->n; p++)
            if (!L->fixed[p])
                L->xinit[3 * p + 2] += s->perturb_amplitude * drape_rng_uniform_pm1(&g);
        return 0;
    }
    double lo, hi;
    int modes;
    drape_scene_perturbation_band(s, &lo, &hi, &modes);
    drape_field *f = drape_malloc(sizeof *f);
    if (!f)
        return drape_error_set(err, DRAPE_E_NOMEM, s->path, 0, 0, NULL,
                               "out of memory building the lattice");
    if (drape_field_draw(f, (uint64_t)s->perturb_seed, modes, lo, hi, s->perturb_amplitude)) {
        drape_free(f);
        return drape_error_set(err, DRAPE_E_INPUT, s->path, 0, 0, "perturbation",
                               "the perturbation field's band is out of range (lambda_min "
                               "%g m, lambda_max %g m, %d modes, amplitude %g m)",
                               lo, hi, modes, s->perturb_amplitude);
    }
    for (int p = 0; p < L->n; p++) {
        const double *x = L->x0 + 3 * p;
        if (!L->fixed[p])
            L->xinit[3 * p + 2] += taper(s, x) * drape_field_height(f, x[0], x[1]);
    }
    drape_free(f);
    return 0;
}

static double nominal_area(const drape_scene *s)
{
    switch (s->shape) {
    case DRAPE_SHAPE_RECTANGLE: return s->width * s->height;
    case DRAPE_SHAPE_CIRCLE:
        return 0.25 * 3.14159265358979323846 * s->diameter * s->diameter;
    case DRAPE_SHAPE_STRIP: return s->length * s->width;
    default: return 0.0;
    }
}

drape_lattice *drape_lattice_new(const drape_scene *s, const drape_fabric *f,
                                 drape_error *err)
{
    drape_lattice *L = NULL;
    geom g;
    int rc = -1;

    if (!s || !f) {
        drape_error_set(err, DRAPE_E_INTERNAL, NULL, 0, 0, NULL,
                        "drape_lattice_new: NULL scene or fabric");
        return NULL;
    }
    if (geom_init(s, &g, err) != 0) return NULL;

    L = drape_calloc(1, sizeof *L);
    if (!L) goto nomem;
    L->sigma = s->spacing;
    L->ni = g.ni;
    L->nj = g.nj;
    size_t ngrid = (size_t)g.ni * (size_t)g.nj;
    L->grid = drape_calloc(ngrid, sizeof *L->grid);
    if (!L->grid) goto nomem;
    int n = 0;
    for (int j = 0; j < g.nj; j++)
        for (int i = 0; i < g.ni; i++)
            L->grid[(size_t)j * g.ni + i] = is_kept(&g, i, j) ? n++ : -1;
    L->n = n;

    size_t un = (size_t)n;
    L->gi = drape_calloc(un, sizeof *L->gi);
    L->gj = drape_calloc(un, sizeof *L->gj);
    L->x0 = drape_calloc(3 * un, sizeof *L->x0);
    L->xinit = drape_calloc(3 * un, sizeof *L->xinit);
    L->mass = drape_calloc(un, sizeof *L->mass);
    L->fixed = drape_calloc(un, sizeof *L->fixed);
    L->free_id = drape_calloc(un, sizeof *L->free_id);
    if (!L->gi || !L->gj || !L->x0 || !L->xinit || !L->mass || !L->fixed
        || !L->free_id)
        goto nomem;

    /* positions and kind clamps */
    for (int j = 0; j < g.nj; j++) {
        for (int i = 0; i < g.ni; i++) {
            int p = grid_at(L, i, j);
            if (p < 0) continue;
            double *x = L->x0 + 3 * p;
            L->gi[p] = i;
            L->gj[p] = j;
            if (g.rot) {
                rot_xy(&g, i, j, &x[0], &x[1]);
                x[0] *= L->sigma;
                x[1] *= L->sigma;
            } else if (g.swap) {
                x[0] = (j - g.cj) * L->sigma;
                x[1] = -(i - g.ci) * L->sigma;
            } else {
                x[0] = (i - g.ci) * L->sigma;
                x[1] = (j - g.cj) * L->sigma;
            }
            x[2] = 0.0;
            L->fixed[p] = (unsigned char)clamped_by_kind(s, x);
        }
    }
    if (apply_pins(L, s, err) != 0) goto out;

    lump_masses(L, &g, f->weight);
    L->mass_total = 0.0;
    for (int p = 0; p < n; p++) L->mass_total += L->mass[p];
    L->area_nominal = nominal_area(s);

    /* free numbering */
    L->n_free = 0;
    for (int p = 0; p < n; p++)
        L->free_id[p] = L->fixed[p] ? -1 : L->n_free++;
    L->free_to_id = drape_calloc((size_t)L->n_free, sizeof *L->free_to_id);
    if (!L->free_to_id) goto nomem;
    for (int p = 0; p < n; p++)
        if (L->free_id[p] >= 0) L->free_to_id[L->free_id[p]] = p;

    /* initial state: rest + perturbation of free particles, in id order */
    memcpy(L->xinit, L->x0, 3 * un * sizeof *L->x0);
    if (s->has_perturbation && perturb(L, s, err) != 0) goto out;

    /* elements: count, allocate, fill.  Twist cells only where the bias
     * term is asked for (by default it is), with bend, the fabric gives a
     * bias curve (without one, `bias` leaves the seed's model) and the
     * energy form is the consistent one (the twist energy is calibrated
     * against the consistent hinges; the seed form's hinges are 4 times
     * stiffer, so `seed` runs the seed's model) */
    int want_cells = (s->terms & DRAPE_TERM_BIAS) && (s->terms & DRAPE_TERM_BEND) &&
                     f->has_bias && s->energy_form == DRAPE_FORM_CONSISTENT;
    build_elements(L, &g, s, f, want_cells, 0);
    if (L->n_edges > 0) {
        L->edges = drape_calloc((size_t)L->n_edges, sizeof *L->edges);
        if (!L->edges) goto nomem;
    }
    if (L->n_hinges > 0) {
        L->hinges = drape_calloc((size_t)L->n_hinges, sizeof *L->hinges);
        if (!L->hinges) goto nomem;
    }
    if (L->n_corners > 0) {
        L->corners = drape_calloc((size_t)L->n_corners, sizeof *L->corners);
        if (!L->corners) goto nomem;
    }
    if (L->n_cells > 0) {
        L->cells = drape_calloc((size_t)L->n_cells, sizeof *L->cells);
        if (!L->cells) goto nomem;
    }
    if (build_elements(L, &g, s, f, want_cells, 1) != 0) goto nomem;
    rc = 0;
    goto out;

nomem:
    drape_error_set(err, DRAPE_E_NOMEM, s->path, 0, 0, NULL,
                    "out of memory building the lattice");
out:
    if (rc != 0) {
        drape_lattice_free(L);
        L = NULL;
    }
    return L;
}

void drape_lattice_free(drape_lattice *L)
{
    if (!L) return;
    drape_free(L->grid);
    drape_free(L->gi);
    drape_free(L->gj);
    drape_free(L->x0);
    drape_free(L->xinit);
    drape_free(L->mass);
    drape_free(L->fixed);
    drape_free(L->free_id);
    drape_free(L->free_to_id);
    drape_free(L->edges);
    drape_free(L->hinges);
    drape_free(L->corners);
    drape_free(L->cells);
    drape_free(L);
}

int drape_lattice_estimate(const drape_scene *s, long *ni, long *nj,
                           long *n_particles)
{
    geom g;
    if (!s || geom_init(s, &g, NULL) != 0) return -1;
    long n = 0;
    if (g.disc || g.rot) {
        for (int j = 0; j < g.nj; j++)
            for (int i = 0; i < g.ni; i++) n += is_kept(&g, i, j);
    } else {
        n = (long)g.ni * g.nj;
    }
    if (ni) *ni = g.ni;
    if (nj) *nj = g.nj;
    if (n_particles) *n_particles = n;
    return 0;
}
