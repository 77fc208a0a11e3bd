/* drape.c: observers of a lattice state (docs/model.md section 6).
 *
 * Drape coefficient (Cusick; docs/model.md 6):
 *   DC = (A_shadow - A_disk) / (A_specimen - A_disk)                    (1)
 * A_shadow is the area of the union of the horizontal projections of the
 * mesh faces.  A face is a lattice quad a-b-c-d; its projection is taken as
 * the union of the four triangles (a,b,m) (b,c,m) (c,d,m) (d,a,m) about the
 * corner mean m, which is the quad itself when the projected quad is convex
 * (then the quad is handed to GEOS as one polygon: same region, fewer
 * polygons) and prefers neither diagonal when it is folded.  A_specimen and
 * A_disk use the same code at the rest positions, so the undeformed
 * specimen gives exactly DC = 1.  Triangles (and quads) whose doubled area
 * is below DRAPE_SLIVER times their largest squared edge are numerically
 * degenerate (edge-on faces) and skipped: the area they could hold is below
 * 1e-12 of a face's.  The union is GEOS's unary union (overlay NG) with a
 * fixed-precision retry on a 1 nm grid when the floating overlay fails.
 *
 * Shadow radius and nodes: rays from the centre c (mean rest position of
 * the fixed particles, or the origin) at theta_k = 2 pi k / N;
 *   r(theta) = max { t >= 0 : c + t (cos theta, sin theta) on an exterior
 *              ring of the union }                                       (2)
 * Nodes (folds) are local maxima of the outline, the samples r_k smoothed
 * by a circular Gaussian of standard deviation s sigma / mean(r) radians
 * (s = 1 by default), whose topographic prominence exceeds f * mean(r)
 * (f = 0.05).  A circle cut from a square lattice lies between the
 * circles of radius R - sqrt(2) sigma and R, and its mesh's edge is a
 * staircase: steps of one spacing near the diagonals, flats of up to
 * 2 sqrt(2 R sigma) near the axes, about 0.9 sigma deep (1.0-1.1 sigma of
 * prominence measured in r(theta) at 0.25-2 cm, R = 15 cm).  Unsmoothed,
 * a threshold that ignores them grows with sigma, so the same fold would
 * count at one spacing and not at another; smoothed, the flat specimen
 * has no node and smooth synthetic n-fold shadows give n at every spacing
 * from 2 cm (n <= 4), 1 cm (n <= 10) and 0.7 cm (n <= 12) to 0.25 cm
 * (tests/check_drape.c).
 *
 * Cantilever (Peirce 1930; ASTM D1388; docs/model.md 6):
 *   theta = atan2(-z_tip, x_tip)   (chord from the platform edge x = z = 0)
 *   c = l (cos(theta/2) / (8 tan theta))^(1/3)                           (3)
 *   G = W g c^3                                                         (4)
 * with l the overhang (rest x of the free end), W the areal density.
 *
 * References: F. T. Peirce, "The handle of cloth as a measurable quantity",
 * J. Textile Inst. 21 (1930) T377; G. E. Cusick, "The measurement of fabric
 * drape", J. Textile Inst. 59 (1968) 253; GEOS C API 3.11.
 */
#include "drape/drape.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#define GEOS_USE_ONLY_R_API
#include <geos_c.h>

#include "drape/alloc.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* A triangle or quad is degenerate when twice its area is below this
 * fraction of its largest squared edge length. */
#define DRAPE_SLIVER 1e-12
/* Grid (m) of the fixed-precision union used when the floating one fails. */
#define DRAPE_UNION_GRID 1e-9

struct drape_dc {
    const drape_lattice *L;
    drape_dc_opts opts;
    GEOSContextHandle_t ctx;
    char geos_msg[256];
    int n_quads;
    int *quads;            /* 4 n_quads particle ids */
    int n_disk;
    int *disk;             /* indices of all-fixed quads */
    GEOSGeometry **geoms;  /* workspace, 4 n_quads */
    double *radii;         /* n_angles, last measurement */
    double *outline;       /* n_angles: radii smoothed (nodes) */
    double *dir;           /* 2 n_angles: cos, sin of theta_k */
    int have_radii;
    double a_specimen, a_disk;
    double centre[2];
};

/* ------------------------------------------------------------------ faces */

int *drape_quads_new(const drape_lattice *L, int *n_quads, drape_error *err)
{
    int n = 0, k = 0, *q = NULL;
    *n_quads = 0;
    for (int j = 0; j + 1 < L->nj; j++)
        for (int i = 0; i + 1 < L->ni; i++)
            if (L->grid[j * L->ni + i] >= 0 && L->grid[j * L->ni + i + 1] >= 0 &&
                L->grid[(j + 1) * L->ni + i + 1] >= 0 && L->grid[(j + 1) * L->ni + i] >= 0)
                n++;
    q = drape_malloc(sizeof *q * (size_t)(4 * n + 1));
    if (!q) {
        drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL,
                        "out of memory for %d mesh faces", n);
        return NULL;
    }
    for (int j = 0; j + 1 < L->nj; j++)
        for (int i = 0; i + 1 < L->ni; i++) {
            int a = L->grid[j * L->ni + i], b = L->grid[j * L->ni + i + 1];
            int c = L->grid[(j + 1) * L->ni + i + 1], d = L->grid[(j + 1) * L->ni + i];
            if (a < 0 || b < 0 || c < 0 || d < 0) continue;
            /* orientation at rest: z of (c - a) x (d - b) */
            const double *pa = L->x0 + 3 * a, *pb = L->x0 + 3 * b;
            const double *pc = L->x0 + 3 * c, *pd = L->x0 + 3 * d;
            double nz = (pc[0] - pa[0]) * (pd[1] - pb[1]) - (pc[1] - pa[1]) * (pd[0] - pb[0]);
            if (nz >= 0) {
                q[4 * k] = a; q[4 * k + 1] = b; q[4 * k + 2] = c; q[4 * k + 3] = d;
            } else {
                q[4 * k] = a; q[4 * k + 1] = d; q[4 * k + 2] = c; q[4 * k + 3] = b;
            }
            k++;
        }
    *n_quads = n;
    return q;
}

/* ------------------------------------------------------------------- GEOS */

static void geos_error_handler(const char *message, void *userdata)
{
    char *buf = userdata;
    if (buf[0] == 0) snprintf(buf, 256, "%s", message);
}

static void geos_notice_handler(const char *message, void *userdata)
{
    (void)message;
    (void)userdata;
}

static GEOSContextHandle_t geos_new(char *msgbuf)
{
    GEOSContextHandle_t ctx = GEOS_init_r();
    if (!ctx) return NULL;
    msgbuf[0] = 0;
    GEOSContext_setErrorMessageHandler_r(ctx, geos_error_handler, msgbuf);
    GEOSContext_setNoticeMessageHandler_r(ctx, geos_notice_handler, NULL);
    return ctx;
}

static int geos_fail(drape_error *err, const char *what, const char *msg)
{
    return drape_error_set(err, DRAPE_E_NUMERIC, NULL, 0, 0, NULL,
                           "shadow: GEOS %s failed%s%s", what, msg[0] ? ": " : "",
                           msg);
}

/* Polygon from np points (x y pairs), closed here. NULL on failure. */
static GEOSGeometry *make_polygon(GEOSContextHandle_t ctx, const double *p, int np)
{
    GEOSCoordSequence *s = GEOSCoordSeq_create_r(ctx, (unsigned)np + 1, 2);
    if (!s) return NULL;
    for (int k = 0; k <= np; k++) {
        int kk = k % np;
        if (!GEOSCoordSeq_setXY_r(ctx, s, (unsigned)k, p[2 * kk], p[2 * kk + 1])) {
            GEOSCoordSeq_destroy_r(ctx, s);
            return NULL;
        }
    }
    GEOSGeometry *ring = GEOSGeom_createLinearRing_r(ctx, s); /* owns s */
    if (!ring) return NULL;
    return GEOSGeom_createPolygon_r(ctx, ring, NULL, 0);     /* owns ring */
}

static double cross2(double ax, double ay, double bx, double by)
{
    return ax * by - ay * bx;
}

static double sq2(double ax, double ay)
{
    return ax * ax + ay * ay;
}

/* 1 if the triangle p (6 numbers) is too thin to count. */
static int tri_degenerate(const double *p)
{
    double e1x = p[2] - p[0], e1y = p[3] - p[1];
    double e2x = p[4] - p[0], e2y = p[5] - p[1];
    double e3x = p[4] - p[2], e3y = p[5] - p[3];
    double a2 = fabs(cross2(e1x, e1y, e2x, e2y));
    double m = sq2(e1x, e1y);
    if (sq2(e2x, e2y) > m) m = sq2(e2x, e2y);
    if (sq2(e3x, e3y) > m) m = sq2(e3x, e3y);
    return !(a2 > DRAPE_SLIVER * m);
}

/* Append the polygon(s) of projected quad p (8 numbers) to g; returns the
 * new count, or -1 on a GEOS failure. */
static int add_quad(GEOSContextHandle_t ctx, const double *p, GEOSGeometry **g,
                    int ng)
{
    double c[4], m2 = 0.0;
    int pos = 0, neg = 0;
    for (int k = 0; k < 4; k++) {
        const double *a = p + 2 * k, *b = p + 2 * ((k + 1) % 4), *e = p + 2 * ((k + 2) % 4);
        c[k] = cross2(b[0] - a[0], b[1] - a[1], e[0] - b[0], e[1] - b[1]);
        if (sq2(b[0] - a[0], b[1] - a[1]) > m2) m2 = sq2(b[0] - a[0], b[1] - a[1]);
    }
    for (int k = 0; k < 4; k++) {
        if (c[k] > DRAPE_SLIVER * m2) pos++;
        else if (c[k] < -DRAPE_SLIVER * m2) neg++;
    }
    if (pos == 4 || neg == 4) { /* strictly convex: the quad itself */
        GEOSGeometry *q = make_polygon(ctx, p, 4);
        if (!q) return -1;
        g[ng++] = q;
        return ng;
    }
    double mx = 0.25 * (p[0] + p[2] + p[4] + p[6]);
    double my = 0.25 * (p[1] + p[3] + p[5] + p[7]);
    for (int k = 0; k < 4; k++) {
        int k1 = (k + 1) % 4;
        double t[6] = {p[2 * k], p[2 * k + 1], p[2 * k1], p[2 * k1 + 1], mx, my};
        if (tri_degenerate(t)) continue;
        GEOSGeometry *q = make_polygon(ctx, t, 3);
        if (!q) return -1;
        g[ng++] = q;
    }
    return ng;
}

/* Union of the ng polygons g (consumed).  Returns the union (caller
 * destroys) or NULL with err set. */
static GEOSGeometry *union_of(GEOSContextHandle_t ctx, char *msg, GEOSGeometry **g,
                              int ng, drape_error *err)
{
    GEOSGeometry *col = GEOSGeom_createCollection_r(ctx, GEOS_GEOMETRYCOLLECTION, g,
                                                    (unsigned)ng);
    if (!col) {
        for (int k = 0; k < ng; k++) GEOSGeom_destroy_r(ctx, g[k]);
        geos_fail(err, "collection", msg);
        return NULL;
    }
    GEOSGeometry *u = GEOSUnaryUnion_r(ctx, col);
    if (!u) {
        char first[256];
        snprintf(first, sizeof first, "%s", msg);
        msg[0] = 0;
        u = GEOSUnaryUnionPrec_r(ctx, col, DRAPE_UNION_GRID);
        if (!u) {
            char both[600];
            snprintf(both, sizeof both, "%s; with a %g m grid: %s", first,
                     DRAPE_UNION_GRID, msg);
            geos_fail(err, "union", both);
        }
    }
    GEOSGeom_destroy_r(ctx, col);
    return u;
}

static int area_of(GEOSContextHandle_t ctx, char *msg, const GEOSGeometry *u,
                   double *area, drape_error *err)
{
    if (!GEOSArea_r(ctx, u, area)) return geos_fail(err, "area", msg);
    return 0;
}

/* Union of the projections of quads idx[0..nq) (all quads when idx is
 * NULL) at positions x.  Returns the union or NULL with err set. */
static GEOSGeometry *shadow_of(drape_dc *d, const double *x, const int *idx, int nq,
                               drape_error *err)
{
    int ng = 0;
    d->geos_msg[0] = 0;
    for (int k = 0; k < nq; k++) {
        const int *q = d->quads + 4 * (idx ? idx[k] : k);
        double p[8];
        for (int c = 0; c < 4; c++) {
            p[2 * c] = x[3 * q[c]];
            p[2 * c + 1] = x[3 * q[c] + 1];
        }
        int r = add_quad(d->ctx, p, d->geoms, ng);
        if (r < 0) {
            for (int m = 0; m < ng; m++) GEOSGeom_destroy_r(d->ctx, d->geoms[m]);
            geos_fail(err, "polygon", d->geos_msg);
            return NULL;
        }
        ng = r;
    }
    return union_of(d->ctx, d->geos_msg, d->geoms, ng, err);
}

/* --------------------------------------------------------------- handle */

void drape_dc_opts_default(drape_dc_opts *o)
{
    o->n_angles = DRAPE_SHADOW_ANGLES;
    o->node_prominence = DRAPE_NODE_PROMINENCE;
    o->node_sigmas = DRAPE_NODE_SIGMAS;
    o->outline_sigmas = DRAPE_OUTLINE_SIGMAS;
}

void drape_dc_free(drape_dc *d)
{
    if (!d) return;
    if (d->ctx) GEOS_finish_r(d->ctx);
    drape_free(d->quads);
    drape_free(d->disk);
    drape_free(d->geoms);
    drape_free(d->radii);
    drape_free(d->outline);
    drape_free(d->dir);
    drape_free(d);
}

drape_dc *drape_dc_new(const drape_lattice *L, const drape_dc_opts *opts,
                       drape_error *err)
{
    drape_dc *d = drape_calloc(1, sizeof *d);
    GEOSGeometry *u = NULL;
    if (!d) goto nomem;
    d->L = L;
    if (opts) d->opts = *opts;
    else drape_dc_opts_default(&d->opts);
    if (d->opts.n_angles < 8 || !(d->opts.node_prominence >= 0.0) ||
        !(d->opts.node_sigmas >= 0.0) || !(d->opts.outline_sigmas >= 0.0) ||
        !isfinite(d->opts.outline_sigmas)) {
        drape_error_set(err, DRAPE_E_INPUT, NULL, 0, 0, NULL,
                        "shadow: need at least 8 rays, prominences >= 0 and a finite "
                        "smoothing >= 0 (got %d, %g, %g, %g)", d->opts.n_angles,
                        d->opts.node_prominence, d->opts.node_sigmas,
                        d->opts.outline_sigmas);
        goto fail;
    }
    d->quads = drape_quads_new(L, &d->n_quads, err);
    if (!d->quads) goto fail;
    d->disk = drape_malloc(sizeof *d->disk * (size_t)(d->n_quads + 1));
    d->geoms = drape_malloc(sizeof *d->geoms * (size_t)(4 * d->n_quads + 1));
    d->radii = drape_malloc(sizeof *d->radii * (size_t)d->opts.n_angles);
    d->outline = drape_malloc(sizeof *d->outline * (size_t)d->opts.n_angles);
    d->dir = drape_malloc(sizeof *d->dir * (size_t)(2 * d->opts.n_angles));
    if (!d->disk || !d->geoms || !d->radii || !d->outline || !d->dir) goto nomem;
    for (int a = 0; a < d->opts.n_angles; a++) {
        double th = 2.0 * M_PI * a / d->opts.n_angles;
        d->dir[2 * a] = cos(th);
        d->dir[2 * a + 1] = sin(th);
    }
    for (int k = 0; k < d->n_quads; k++) {
        const int *q = d->quads + 4 * k;
        if (L->fixed[q[0]] && L->fixed[q[1]] && L->fixed[q[2]] && L->fixed[q[3]])
            d->disk[d->n_disk++] = k;
    }
    int nfix = 0;
    for (int i = 0; i < L->n; i++)
        if (L->fixed[i]) {
            d->centre[0] += L->x0[3 * i];
            d->centre[1] += L->x0[3 * i + 1];
            nfix++;
        }
    if (nfix > 0) {
        d->centre[0] /= nfix;
        d->centre[1] /= nfix;
    }
    d->ctx = geos_new(d->geos_msg);
    if (!d->ctx) {
        drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL,
                        "shadow: cannot create a GEOS context");
        goto fail;
    }
    u = shadow_of(d, L->x0, NULL, d->n_quads, err);
    if (!u || area_of(d->ctx, d->geos_msg, u, &d->a_specimen, err)) goto fail;
    GEOSGeom_destroy_r(d->ctx, u);
    u = shadow_of(d, L->x0, d->disk, d->n_disk, err);
    if (!u || area_of(d->ctx, d->geos_msg, u, &d->a_disk, err)) goto fail;
    GEOSGeom_destroy_r(d->ctx, u);
    return d;
nomem:
    drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL,
                    "shadow: out of memory");
fail:
    if (d && u) GEOSGeom_destroy_r(d->ctx, u);
    drape_dc_free(d);
    return NULL;
}

const double *drape_dc_radii(const drape_dc *d, int *n_angles)
{
    if (n_angles) *n_angles = d->opts.n_angles;
    return d->have_radii ? d->radii : NULL;
}

const double *drape_dc_outline(const drape_dc *d, int *n_angles)
{
    if (n_angles) *n_angles = d->opts.n_angles;
    return d->have_radii ? d->outline : NULL;
}

void drape_outline_smooth(const double *r, int n, double sd_rad, double *out)
{
    double s = sd_rad * n / (2.0 * M_PI); /* in samples */
    int w = (int)ceil(4.0 * s);
    if (!(s > 0.0) || n < 1) {
        for (int k = 0; k < n; k++) out[k] = r[k];
        return;
    }
    if (w > n / 2) w = n / 2;
    for (int k = 0; k < n; k++) {
        double sum = 0.0, wsum = 0.0;
        for (int j = -w; j <= w; j++) {
            if (n % 2 == 0 && j == w && w == n / 2) break; /* one sample once */
            double g = exp(-0.5 * (j / s) * (j / s));
            sum += g * r[((k + j) % n + n) % n];
            wsum += g;
        }
        out[k] = sum / wsum;
    }
}

/* ---------------------------------------------------------------- radius */

/* Fold the exterior rings of polygonal geometry g into r(theta) and rmax. */
static int rays_from(drape_dc *d, const GEOSGeometry *g, double *rmax,
                     drape_error *err)
{
    GEOSContextHandle_t ctx = d->ctx;
    int type = GEOSGeomTypeId_r(ctx, g);
    if (type == GEOS_MULTIPOLYGON || type == GEOS_GEOMETRYCOLLECTION) {
        int n = GEOSGetNumGeometries_r(ctx, g);
        for (int k = 0; k < n; k++)
            if (rays_from(d, GEOSGetGeometryN_r(ctx, g, k), rmax, err)) return -1;
        return 0;
    }
    if (type != GEOS_POLYGON || GEOSisEmpty_r(ctx, g)) return 0;
    const GEOSGeometry *ring = GEOSGetExteriorRing_r(ctx, g);
    const GEOSCoordSequence *s = ring ? GEOSGeom_getCoordSeq_r(ctx, ring) : NULL;
    unsigned np = 0;
    if (!s || !GEOSCoordSeq_getSize_r(ctx, s, &np)) return geos_fail(err, "ring", d->geos_msg);
    const double cx = d->centre[0], cy = d->centre[1];
    const int na = d->opts.n_angles;
    double px = 0, py = 0;
    for (unsigned k = 0; k < np; k++) {
        double qx, qy;
        if (!GEOSCoordSeq_getXY_r(ctx, s, k, &qx, &qy)) return geos_fail(err, "ring", d->geos_msg);
        qx -= cx;
        qy -= cy;
        double rq = sqrt(sq2(qx, qy));
        if (rq > *rmax) *rmax = rq;
        if (k > 0) {
            /* segment p -> q against every ray: c + t u = p + s e, with
             * t = (p x e) / (u x e), s = (p x u) / (u x e) */
            double ex = qx - px, ey = qy - py;
            double tol = 1e-12;
            for (int a = 0; a < na; a++) {
                double ux = d->dir[2 * a], uy = d->dir[2 * a + 1];
                double den = cross2(ux, uy, ex, ey);
                if (den == 0.0) continue;
                double t = cross2(px, py, ex, ey) / den;
                double sp = cross2(px, py, ux, uy) / den;
                if (t >= 0.0 && sp >= -tol && sp <= 1.0 + tol && t > d->radii[a])
                    d->radii[a] = t;
            }
        }
        px = qx;
        py = qy;
    }
    return 0;
}

/* Prominent peaks of circular samples: see drape.h. */
int drape_nodes_count(const double *r, int n, double min_prominence)
{
    return drape_nodes_find(r, n, min_prominence, NULL, 0);
}

int drape_nodes_find(const double *r, int n, double min_prominence, int *peaks,
                     int max_peaks)
{
    if (n < 3) return 0;
    int m0 = 0;
    for (int k = 1; k < n; k++)
        if (r[k] < r[m0]) m0 = k;
    const double rmin = r[m0];
#define A(k) r[(m0 + (k)) % n]
    int count = 0;
    int k = 1;
    while (k < n) {
        int e = k;
        while (e + 1 < n && A(e + 1) == A(k)) e++;
        double h = A(k);
        double next = A((e + 1) % n);
        if (A(k - 1) < h && next < h) {
            /* walk left from k-1 and right from e+1 to the nearest higher
             * sample, keeping the lowest value met; equal heights are
             * ordered by index so that one of twin peaks is the higher */
            double lo_l = h, lo_r = h;
            int found = 0, len = e - k + 1;
            for (int s = 1; s <= n - len; s++) {
                int j = ((k - s) % n + n) % n;
                double v = A(j);
                if (v > h || (v == h && j > k)) { found = 1; break; }
                if (v < lo_l) lo_l = v;
            }
            for (int s = 1; found && s <= n - len; s++) {
                int j = (e + s) % n;
                double v = A(j);
                if (v > h || (v == h && j > k)) break;
                if (v < lo_r) lo_r = v;
            }
            double prom = found ? h - (lo_l > lo_r ? lo_l : lo_r) : h - rmin;
            if (prom > min_prominence) {
                if (peaks && count < max_peaks) peaks[count] = (m0 + (k + e) / 2) % n;
                count++;
            }
        }
        k = e + 1;
    }
#undef A
    return count;
}

int drape_dc_measure(drape_dc *d, const double *x, drape_shadow *out,
                     drape_error *err)
{
    const drape_lattice *L = d->L;
    GEOSGeometry *u = NULL;
    int rc = -1;
    memset(out, 0, sizeof *out);
    for (int i = 0; i < 3 * L->n; i++)
        if (!isfinite(x[i])) {
            drape_error_set(err, DRAPE_E_NUMERIC, NULL, 0, 0, NULL,
                            "shadow: particle %d has a non-finite position", i / 3);
            goto out;
        }
    u = shadow_of(d, x, NULL, d->n_quads, err);
    if (!u || area_of(d->ctx, d->geos_msg, u, &out->a_shadow_m2, err)) goto out;
    out->a_specimen_mesh_m2 = d->a_specimen;
    out->a_disk_m2 = d->a_disk;
    out->a_specimen_nominal_m2 = L->area_nominal;
    out->dc = d->a_specimen > d->a_disk
                  ? (out->a_shadow_m2 - d->a_disk) / (d->a_specimen - d->a_disk)
                  : NAN;
    out->centre_m[0] = d->centre[0];
    out->centre_m[1] = d->centre[1];

    const int na = d->opts.n_angles;
    double rmax = 0.0, sum = 0.0, rmin;
    for (int a = 0; a < na; a++) d->radii[a] = 0.0;
    if (rays_from(d, u, &rmax, err)) goto out;
    d->have_radii = 1;
    rmin = d->radii[0];
    for (int a = 0; a < na; a++) {
        sum += d->radii[a];
        if (d->radii[a] < rmin) rmin = d->radii[a];
    }
    out->r_mean_m = sum / na;
    out->r_min_m = rmin;
    out->r_max_m = rmax;
    double thr = d->opts.node_prominence * out->r_mean_m;
    if (d->opts.node_sigmas * L->sigma > thr) thr = d->opts.node_sigmas * L->sigma;
    out->node_threshold_m = thr;
    drape_outline_smooth(d->radii, na,
                         out->r_mean_m > 0.0 ? d->opts.outline_sigmas * L->sigma / out->r_mean_m
                                             : 0.0,
                         d->outline);
    out->nodes = drape_nodes_count(d->outline, na, thr);
    rc = 0;
out:
    if (u) GEOSGeom_destroy_r(d->ctx, u);
    return rc;
}

int drape_shadow_measure(const drape_lattice *L, const double *x,
                         drape_shadow *out, drape_error *err)
{
    drape_dc *d = drape_dc_new(L, NULL, err);
    if (!d) return -1;
    int rc = drape_dc_measure(d, x, out, err);
    drape_dc_free(d);
    return rc;
}

int drape_union_area(drape_dc *d, const double *tri, int n_tri, double *area,
                     drape_error *err)
{
    char own_msg[256];
    char *msg = d ? d->geos_msg : own_msg;
    GEOSContextHandle_t ctx = d ? d->ctx : geos_new(own_msg);
    GEOSGeometry **g = drape_malloc(sizeof *g * (size_t)(n_tri + 1));
    GEOSGeometry *u = NULL;
    int ng = 0, rc = -1;
    *area = 0.0;
    if (!ctx || !g) {
        drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL, "shadow: out of memory");
        goto out;
    }
    msg[0] = 0;
    for (int k = 0; k < n_tri; k++) {
        if (tri_degenerate(tri + 6 * k)) continue;
        g[ng] = make_polygon(ctx, tri + 6 * k, 3);
        if (!g[ng]) {
            for (int m = 0; m < ng; m++) GEOSGeom_destroy_r(ctx, g[m]);
            geos_fail(err, "polygon", msg);
            goto out;
        }
        ng++;
    }
    u = union_of(ctx, msg, g, ng, err);
    if (!u || area_of(ctx, msg, u, area, err)) goto out;
    rc = 0;
out:
    if (u) GEOSGeom_destroy_r(ctx, u);
    drape_free(g);
    if (!d && ctx) GEOS_finish_r(ctx);
    return rc;
}

/* ------------------------------------------------------------- cantilever */

double drape_peirce_bending_length(double l, double theta_rad)
{
    if (!(l > 0.0) || !(theta_rad > 0.0) || !(theta_rad < 0.5 * M_PI)) return NAN;
    return l * cbrt(cos(0.5 * theta_rad) / (8.0 * tan(theta_rad)));
}

int drape_cantilever_measure(const drape_lattice *L, const double *x,
                             double weight_kg_m2, double g,
                             drape_cantilever *out, drape_error *err)
{
    memset(out, 0, sizeof *out);
    if (L->n <= 0)
        return drape_error_set(err, DRAPE_E_INPUT, NULL, 0, 0, NULL,
                               "cantilever: empty lattice");
    double xmax = L->x0[0];
    for (int i = 1; i < L->n; i++)
        if (L->x0[3 * i] > xmax) xmax = L->x0[3 * i];
    double l = 0.0, tip[3] = {0, 0, 0};
    int m = 0;
    for (int i = 0; i < L->n; i++)
        if (L->x0[3 * i] >= xmax - 0.5 * L->sigma) {
            l += L->x0[3 * i];
            for (int c = 0; c < 3; c++) tip[c] += x[3 * i + c];
            m++;
        }
    l /= m;
    for (int c = 0; c < 3; c++) tip[c] /= m;
    if (!isfinite(tip[0]) || !isfinite(tip[1]) || !isfinite(tip[2]))
        return drape_error_set(err, DRAPE_E_NUMERIC, NULL, 0, 0, NULL,
                               "cantilever: non-finite tip position");
    double theta = atan2(-tip[2], tip[0]) + 0.0; /* no -0 */
    out->overhang_m = l;
    for (int c = 0; c < 3; c++) out->tip_m[c] = tip[c];
    out->tip_angle_deg = theta * 180.0 / M_PI;
    out->bending_length_m = drape_peirce_bending_length(l, theta);
    double c3 = out->bending_length_m;
    out->flexural_rigidity_Nm = weight_kg_m2 * g * c3 * c3 * c3;
    return 0;
}
