/* model.c: energies, forces and the exact sparse Jacobian of a particle
 * lattice (MODEL.md sections 3 and 4; seed eqs. 1, 10, 11, 14, 16-18).
 *
 * Energies (MODEL 3; w = element weight, sigma = spacing):
 *   stretch edge   E = 1/2 k_dir w (l - sigma)^2                   (seed 1)
 *   bend hinge     a = x_mid - x_prev, b = x_next - x_mid,
 *                  psi = atan2(|a x b|, a.b)            (0 = flat, MODEL 3.2)
 *                  l = length sigma (lattice.h: 1/2 at a cantilever clamp)
 *       consistent K = psi/l,   E = w sigma^2 Wb(K), Wb = int_0^K M
 *       seed       K = 2 psi/l, E = w M(K) K sigma^2 / 2       (seed 10, 11)
 *   shear corner   a = x_warp - x_mid, b = x_weft - x_mid,
 *                  alpha = atan2(|a x b|, a.b), gamma = pi/2 - alpha
 *                        = atan2(a.b, |a x b|)                  (MODEL 3.3)
 *       consistent E = w sigma^2/4 Ws(|gamma|), Ws = int_0^g F
 *       seed       E = w sigma^2/4 F(|gamma|) |gamma|               (seed 14)
 *   gravity        E = sum_i m_i g z_i                          (MODEL 3.5)
 * Dissipation (MODEL 3.6):
 *   air drag       f_i = -c_air m_i v_i
 *   edge dashpot   f_b = -c_edge ((v_b - v_a).e) e, f_a = -f_b, e = unit(x_b - x_a)
 *
 * Forces are the exact negative gradient.  K = df/dx and D = df/dv are
 * exact, including the x-dependence of the dashpot direction e
 * (dK_bb = -c/l [e (P u)^T + (u.e) P], P = I - e e^T, u = v_b - v_a).
 *
 * Angle derivatives (numerics.md 4.2, re-derived and checked by finite
 * differences in tests/check_model.c): with E = g(psi), unit edges
 * ah, bh, c = cos psi, s = sin psi, n = ah x bh, w_a = n x ah, w_b = bh x n,
 * r = g'/s and p = g'' - r c:
 *   dE/da = -r w_a/|a|,  dE/db = -r w_b/|b|
 *   H_aa = [p wa^ wa^T + r c (I - ah ah^T) + r (ah w_a^T + w_a ah^T)]/|a|^2
 *   H_bb = same with b
 *   H_ab = [p wa^ wb^T - r ((I - bh bh^T) - ah w_b^T)]/(|a||b|),  H_ba = H_ab^T
 * (wa^ = w_a/|w_a|, 0 at s = 0).  For bending r = [g'/psi][psi/sin psi]:
 * g'/psi is an exact polynomial division (drape_fit_value_over_x) and
 * psi/sin psi uses its series below 1e-3, so forces and K are finite and
 * continuous at the flat state.  A hinge with s < 1e-12 and c < 0 (folded),
 * a shear corner with s < 1e-12 (edges parallel) or an edge shorter than
 * 1e-12 sigma makes an evaluation return 1 with all outputs zero.
 *
 * Jacobian storage: one CSC pattern over the 3 n_free free coordinates,
 * made of full 3x3 blocks (every block coupled by a built element, plus
 * every diagonal block).  Within a block column all three scalar columns
 * have the same rows, so entry (3p+r, 3q+c) of block (p, q) sits at
 * slot(p, q) + c * colstride[q] + r; each element stores the slots of its
 * blocks, computed once in drape_model_new.
 *
 * References: Chen & Xu 2000 (seed); Breen, House & Wozny 1994;
 * Baraff & Witkin 1998 (spring Hessian); numerics.md 3.2, 4.2, 4.3.
 */
#include "drape/model.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "drape/alloc.h"
#include "drape/units.h"

/* An edge shorter than this fraction of sigma has no direction. */
#define MODEL_LEN_TINY 1e-12
/* |sin| of a hinge or corner angle below this is degenerate (numerics 4.3). */
#define MODEL_SIN_TINY 1e-12
/* Below this psi, psi/sin(psi) = 1 + psi^2/6 + 7 psi^4/360 (error < 1e-19). */
#define MODEL_SERIES_PSI 1e-3

#define PARTS_CONSERVATIVE (DRAPE_PART_STRETCH | DRAPE_PART_BEND | DRAPE_PART_SHEAR)
#define PARTS_DISSIPATIVE (DRAPE_PART_AIR | DRAPE_PART_EDGE)
#define PARTS_SEGMENTS (PARTS_CONSERVATIVE | DRAPE_PART_EDGE)

struct drape_model {
    const drape_lattice *L;
    drape_fabric F;
    drape_model_opts o;
    unsigned parts;
    int nf;            /* free particles */
    int64_t N;         /* 3 nf */
    drape_pattern pat; /* K, D */
    drape_pattern pat1; /* first-order J */
    int64_t *colstride; /* nf: rows per scalar column of block column q */
    int64_t *dslot;     /* nf: slot of the diagonal block */
    int64_t *eslot;     /* 4 per edge (aa, ab, ba, bb), -1 if not free */
    int64_t *hslot;     /* 9 per hinge (prev, mid, next)^2 */
    int64_t *cslot;     /* 9 per corner (mid, warp, weft)^2 */
    int64_t *kmap;      /* nnz(K): position of M^-1 K entry in J */
    int64_t *dmap;      /* nnz(K): position of M^-1 D entry in J, or -1 */
    int64_t *jid;       /* N: position of the identity entry (j, N + j) */
    double *invm_row;   /* N: 1/m of the particle owning a free coordinate */
    double *Kw, *Dw;    /* nnz(K) workspaces */
    double *rowsum;     /* N */
    /* Segment cache: every neighbour pair an element uses, oriented from
     * its lower particle id a to the higher b (d = x_b - x_a).  eval()
     * measures each segment once, not once per element that shares it
     * (an interior particle's two segments serve 14 element edges).  An
     * element's edge vector is +d or -d of one segment: ref = 2 s + flip. */
    int nseg;
    int *seg_ab;          /* 2 per segment: a, b */
    int *eref;            /* 1 per edge (x_b - x_a) */
    int *href;            /* 2 per hinge (x_mid - x_prev, x_next - x_mid) */
    int *cref;            /* 2 per corner (x_warp - x_mid, x_weft - x_mid) */
    double *seg_d;        /* 3 per segment: d */
    double *seg_l;        /* |d| */
    double *seg_u;        /* 3 per segment: d * (1 / |d|) */
    unsigned char *seg_bad; /* 1: shorter than MODEL_LEN_TINY sigma or not finite */
};

/* ---------------------------------------------------------------- vectors */

static double dot3(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void cross3(const double *a, const double *b, double *c)
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

static double norm3(const double *a) { return sqrt(dot3(a, a)); }

static void sub3(const double *a, const double *b, double *c)
{
    c[0] = a[0] - b[0];
    c[1] = a[1] - b[1];
    c[2] = a[2] - b[2];
}

/* ------------------------------------------------------- angle geometry */

/* The angle between edges a and b and what its derivatives need. */
typedef struct angle_geo {
    double la, lb;         /* |a|, |b| */
    double ah[3], bh[3];   /* unit edges */
    double wa[3], wb[3];   /* n x ah, bh x n (|w| = s) */
    double ua[3], ub[3];   /* w / s, 0 when s = 0 */
    double s, c;           /* |ah x bh|, ah . bh */
    double sn, cn;         /* sin, cos of the angle (s, c normalised) */
    double angle;          /* atan2(s, c) in [0, pi] */
} angle_geo;

/* Only what `need` asks for beyond the edges, s, c, sn, cn and w is
 * computed: GEO_ANGLE the angle (one atan2), GEO_HESS the unit vectors ua,
 * ub of the Hessian (the force path needs neither). */
enum { GEO_ANGLE = 1, GEO_HESS = 2 };

/* The rest of G from the unit edges ah, bh. */
static void angle_geo_finish(unsigned need, angle_geo *G)
{
    double n[3], h;
    cross3(G->ah, G->bh, n);
    G->s = norm3(n);
    G->c = dot3(G->ah, G->bh);
    cross3(n, G->ah, G->wa);
    cross3(G->bh, n, G->wb);
    if (need & GEO_HESS) {
        double is = G->s > 0.0 ? 1.0 / G->s : 0.0;
        for (int k = 0; k < 3; k++) {
            G->ua[k] = G->wa[k] * is;
            G->ub[k] = G->wb[k] * is;
        }
    }
    G->angle = (need & GEO_ANGLE) ? atan2(G->s, G->c) : 0.0;
    /* s and c are components of unit vectors, so s^2 + c^2 is about 1 and
     * cannot overflow or underflow: sqrt is exact enough, hypot is slow. */
    h = sqrt(G->s * G->s + G->c * G->c);
    G->sn = G->s / h;
    G->cn = G->c / h;
}

/* Fill G for the edges of segment refs ra, rb (the segment cache of the
 * current evaluation; the same operations as measuring a and b afresh, so
 * the same bits).  Returns 1 if either segment is degenerate, else 0. */
static int angle_geo_set(const drape_model *m, int ra, int rb, unsigned need,
                         angle_geo *G)
{
    int sa = ra >> 1, sb = rb >> 1;
    if (m->seg_bad[sa] || m->seg_bad[sb]) return 1;
    double fa = (ra & 1) ? -1.0 : 1.0, fb = (rb & 1) ? -1.0 : 1.0;
    const double *ua = m->seg_u + 3 * (int64_t)sa, *ub = m->seg_u + 3 * (int64_t)sb;
    G->la = m->seg_l[sa];
    G->lb = m->seg_l[sb];
    for (int k = 0; k < 3; k++) {
        G->ah[k] = fa * ua[k];  /* exact: a sign change */
        G->bh[k] = fb * ub[k];
    }
    angle_geo_finish(need, G);
    return 0;
}

/* Gradient of g(angle) with respect to a and b, given r = g'/sin. */
static void angle_grad(const angle_geo *G, double r, double *ga, double *gb)
{
    for (int k = 0; k < 3; k++) {
        ga[k] = -r * G->wa[k] / G->la;
        gb[k] = -r * G->wb[k] / G->lb;
    }
}

/* Hessian blocks of g(angle) with respect to (a, b), numerics 4.2.
 * Products of two vector components are formed first so that Haa and Hbb
 * come out exactly symmetric. */
static void angle_hess(const angle_geo *G, double r, double p,
                       double Haa[3][3], double Hab[3][3], double Hbb[3][3])
{
    double ia2 = 1.0 / (G->la * G->la), ib2 = 1.0 / (G->lb * G->lb);
    double iab = 1.0 / (G->la * G->lb);
    double rc = r * G->cn;
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            double d = i == j ? 1.0 : 0.0;
            Haa[i][j] = (p * (G->ua[i] * G->ua[j]) +
                         rc * (d - G->ah[i] * G->ah[j]) +
                         r * (G->ah[i] * G->wa[j] + G->wa[i] * G->ah[j])) * ia2;
            Hbb[i][j] = (p * (G->ub[i] * G->ub[j]) +
                         rc * (d - G->bh[i] * G->bh[j]) +
                         r * (G->bh[i] * G->wb[j] + G->wb[i] * G->bh[j])) * ib2;
            Hab[i][j] = (p * (G->ua[i] * G->ub[j]) -
                         r * ((d - G->bh[i] * G->bh[j]) - G->ah[i] * G->wb[j])) * iab;
        }
    }
}

/* Local force (9) and df/dx (9x9, NULL to skip) of a three-particle
 * element whose energy depends on the angle between a = sum_i ca[i] x_i and
 * b = sum_i cb[i] x_i. */
static void angle_local(const angle_geo *G, const double ca[3],
                        const double cb[3], double r, double p, double *fl,
                        double Jl[9][9])
{
    double ga[3], gb[3];
    angle_grad(G, r, ga, gb);
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++)
            fl[3 * i + k] = -(ca[i] * ga[k] + cb[i] * gb[k]);
    if (!Jl) return;
    double Haa[3][3], Hab[3][3], Hbb[3][3];
    angle_hess(G, r, p, Haa, Hab, Hbb);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            for (int u = 0; u < 3; u++)
                for (int v = 0; v < 3; v++)
                    Jl[3 * i + u][3 * j + v] =
                        -(ca[i] * ca[j] * Haa[u][v] +
                          (ca[i] * cb[j] * Hab[u][v] + cb[i] * ca[j] * Hab[v][u]) +
                          cb[i] * cb[j] * Hbb[u][v]);
}

/* ------------------------------------------------------- energy functions */

/* Bending: energy of hinge h at turning angle psi >= 0 when gop is NULL;
 * otherwise g'(psi)/psi and g''(psi) (and 0 is returned: the force path
 * does not pay for the energy).  The hinge spreads psi over
 * l = length sigma (lattice.h; length 0 means 1):
 *   consistent K = psi/l,   E = w sigma^2 Wb(K),       g'/psi = w sigma^2 M(K)/K / l^2,
 *                                                       g''    = w sigma^2 M'(K) / l^2
 *   seed       K = 2 psi/l, E = w sigma^2 M(K) K / 2,  g'/psi = 2 w sigma^2 (M' + M/K) / l^2,
 *                                                       g''    = 2 w sigma^2 (M'' K + 2 M') / l^2
 * M(K)/K is the exact polynomial division drape_fit_value_over_x. */
static double bend_g(const drape_model *m, const drape_hinge *h, double psi,
                     double *gop, double *g2)
{
    const drape_fit *M = &m->F.bend[h->dir];
    double sg = m->L->sigma, wt = h->weight;
    double l = (h->length > 0.0 ? h->length : 1.0) * sg;
    double q = wt * sg * sg / (l * l);
    if (m->o.form == DRAPE_FORM_SEED) {
        double K = 2.0 * psi / l;
        if (gop) {
            double d1 = drape_fit_slope(M, K);
            *gop = 2.0 * q * (d1 + drape_fit_value_over_x(M, K));
            *g2 = 2.0 * q * (drape_fit_slope2(M, K) * K + 2.0 * d1);
            return 0.0;
        }
        return wt * drape_fit_value(M, K) * K * sg * sg / 2.0;
    }
    double K = psi / l;
    if (gop) {
        *gop = q * drape_fit_value_over_x(M, K);
        *g2 = q * drape_fit_slope(M, K);
        return 0.0;
    }
    return wt * sg * sg * drape_fit_integral(M, K);
}

/* Shear: energy of a corner of weight wt at shear angle gamma when d1 is
 * NULL; otherwise dE/dgamma and d2E/dgamma2 (and 0 is returned). */
static double shear_g(const drape_model *m, double wt, double gamma,
                      double *d1, double *d2)
{
    const drape_fit *F = &m->F.shear_mean;
    double q = wt * m->L->sigma * m->L->sigma / 4.0;
    if (m->o.form == DRAPE_FORM_SEED) {
        double v = drape_fit_value(F, gamma);
        if (d1) {
            double s1 = drape_fit_slope(F, gamma);
            *d1 = q * (s1 * gamma + v);
            *d2 = q * (drape_fit_slope2(F, gamma) * gamma + 2.0 * s1);
            return 0.0;
        }
        return q * v * gamma;
    }
    if (d1) {
        *d1 = q * drape_fit_value(F, gamma);
        *d2 = q * drape_fit_slope(F, gamma);
        return 0.0;
    }
    return q * drape_fit_integral(F, gamma);
}

/* ------------------------------------------------------- element kernels */

static const double HINGE_CA[3] = {-1.0, 1.0, 0.0}; /* a = x_mid - x_prev */
static const double HINGE_CB[3] = {0.0, -1.0, 1.0}; /* b = x_next - x_mid */
static const double CORNER_CA[3] = {-1.0, 1.0, 0.0}; /* a = x_warp - x_mid */
static const double CORNER_CB[3] = {-1.0, 0.0, 1.0}; /* b = x_weft - x_mid */

/* Edge vector of segment ref into d; 1 if the segment is degenerate. */
static int seg_edge(const drape_model *m, int ref, double *d)
{
    int s = ref >> 1;
    const double *sd = m->seg_d + 3 * (int64_t)s;
    double f = (ref & 1) ? -1.0 : 1.0;
    if (m->seg_bad[s]) return 1;
    for (int k = 0; k < 3; k++) d[k] = f * sd[k];
    return 0;
}

/* Stretch edge: local force (a, b) and df/dx.  Returns 1 if degenerate. */
static int kern_stretch(const drape_model *m, const drape_edge *e, int ref,
                        double *fl, double Jl[9][9])
{
    double d[3], u[3], sg = m->L->sigma;
    if (seg_edge(m, ref, d)) return 1;
    double l = m->seg_l[ref >> 1];
    double kw = m->F.k[e->dir] * e->weight;
    for (int k = 0; k < 3; k++) u[k] = d[k] / l;
    double t = kw * (l - sg);
    for (int k = 0; k < 3; k++) {
        fl[3 + k] = -t * u[k];
        fl[k] = t * u[k];
    }
    if (!Jl) return 0;
    double g = 1.0 - sg / l;
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            double d_ij = i == j ? 1.0 : 0.0, uu = u[i] * u[j];
            double h = kw * (uu + g * (d_ij - uu));
            Jl[i][j] = -h;
            Jl[3 + i][3 + j] = -h;
            Jl[i][3 + j] = h;
            Jl[3 + i][j] = h;
        }
    }
    return 0;
}

/* Edge dashpot: local force, df/dx (Jl) and df/dv (Dl), either may be NULL.
 * v NULL means zero velocities. */
static int kern_dashpot(const drape_model *m, const drape_edge *e, int ref,
                        const double *v, double *fl, double Jl[9][9],
                        double Dl[9][9])
{
    double d[3], u[3] = {0.0, 0.0, 0.0}, dv[3] = {0.0, 0.0, 0.0};
    double c = m->o.c_edge;
    if (seg_edge(m, ref, d)) return 1;
    double l = m->seg_l[ref >> 1];
    for (int k = 0; k < 3; k++) u[k] = d[k] / l;
    if (v) sub3(v + 3 * e->b, v + 3 * e->a, dv);
    double w = dot3(dv, u);
    for (int k = 0; k < 3; k++) {
        fl[3 + k] = -c * w * u[k];
        fl[k] = c * w * u[k];
    }
    if (Jl) {
        double pu[3];
        for (int k = 0; k < 3; k++) pu[k] = dv[k] - w * u[k];
        for (int i = 0; i < 3; i++) {
            for (int j = 0; j < 3; j++) {
                double P = (i == j ? 1.0 : 0.0) - u[i] * u[j];
                double A = -c / l * (u[i] * pu[j] + w * P);
                Jl[3 + i][3 + j] = A;
                Jl[i][j] = A;
                Jl[i][3 + j] = -A;
                Jl[3 + i][j] = -A;
            }
        }
    }
    if (Dl) {
        for (int i = 0; i < 3; i++) {
            for (int j = 0; j < 3; j++) {
                double q = c * (u[i] * u[j]);
                Dl[i][j] = -q;
                Dl[3 + i][3 + j] = -q;
                Dl[i][3 + j] = q;
                Dl[3 + i][j] = q;
            }
        }
    }
    return 0;
}

/* Bending hinge: particles (prev, mid, next). */
static int kern_bend(const drape_model *m, const drape_hinge *h,
                     const int *ref, double *fl, double Jl[9][9])
{
    double gop, g2, ratio;
    angle_geo G;
    if (angle_geo_set(m, ref[0], ref[1], GEO_ANGLE | (Jl ? GEO_HESS : 0u), &G))
        return 1;
    if (G.s < MODEL_SIN_TINY && G.c < 0.0) return 1;
    double psi = G.angle;
    bend_g(m, h, psi, &gop, &g2);
    if (psi < MODEL_SERIES_PSI) {
        double p2 = psi * psi;
        ratio = 1.0 + p2 / 6.0 + 7.0 * p2 * p2 / 360.0;
    } else {
        ratio = psi / G.sn;
    }
    double r = gop * ratio;
    double p = g2 - r * G.cn;
    angle_local(&G, HINGE_CA, HINGE_CB, r, p, fl, Jl);
    return 0;
}

/* Shear corner: particles (mid, warp, weft).  g(alpha) = E(pi/2 - alpha),
 * so g' = -dE/dgamma and g'' = d2E/dgamma2. */
static int kern_shear(const drape_model *m, const drape_corner *cn,
                      const int *ref, double *fl, double Jl[9][9])
{
    double d1, d2;
    angle_geo G;
    if (angle_geo_set(m, ref[0], ref[1], Jl ? GEO_HESS : 0u, &G))
        return 1;
    if (G.s < MODEL_SIN_TINY) return 1;
    double gamma = atan2(G.c, G.s);
    shear_g(m, cn->weight, gamma, &d1, &d2);
    double r = -d1 / G.sn;
    double p = d2 - r * G.cn;
    angle_local(&G, CORNER_CA, CORNER_CB, r, p, fl, Jl);
    return 0;
}

/* ------------------------------------------------------------- scatter */

static void add_forces(double *f, const int *ids, int np, const double *fl)
{
    for (int i = 0; i < np; i++)
        for (int k = 0; k < 3; k++) f[3 * ids[i] + k] += fl[3 * i + k];
}

/* Add local blocks Jl (np particles) into the CSC values V through the
 * element's slots (np*np, -1 where a particle is fixed). */
static void add_blocks(const drape_model *m, const int64_t *slots,
                       const int *ids, int np, double Jl[9][9], double *V)
{
    for (int i = 0; i < np; i++) {
        for (int j = 0; j < np; j++) {
            int64_t s = slots[np * i + j];
            if (s < 0) continue;
            int64_t st = m->colstride[m->L->free_id[ids[j]]];
            for (int c = 0; c < 3; c++)
                for (int r = 0; r < 3; r++)
                    V[s + c * st + r] += Jl[3 * i + r][3 * j + c];
        }
    }
}

/* Fill the segment cache for positions x. */
static void measure_segments(drape_model *m, const double *x)
{
    double lmin = MODEL_LEN_TINY * m->L->sigma;
    for (int s = 0; s < m->nseg; s++) {
        double *d = m->seg_d + 3 * (int64_t)s, *u = m->seg_u + 3 * (int64_t)s;
        const int *ab = m->seg_ab + 2 * (int64_t)s;
        sub3(x + 3 * (int64_t)ab[1], x + 3 * (int64_t)ab[0], d);
        double l = norm3(d);
        m->seg_l[s] = l;
        m->seg_bad[s] = !(l > lmin) || !isfinite(l);
        double il = 1.0 / l;
        for (int k = 0; k < 3; k++) u[k] = d[k] * il;
    }
}

static int all_finite(const double *a, int64_t n)
{
    double acc = 0.0;
    for (int64_t i = 0; i < n; i++) acc += a[i] * 0.0;
    return acc == 0.0; /* NaN or inf anywhere makes acc NaN */
}

/* f (3n), K, D (nnz) for the selected parts; any output may be NULL. */
static int eval(drape_model *m, unsigned parts, const double *x,
                const double *v, double *f, double *K, double *D)
{
    const drape_lattice *L = m->L;
    int64_t nnz = m->pat.nnz;
    double fl[9], Jl[9][9], Dl[9][9];
    int ids[3];
    int rc = 0;

    parts &= m->parts;
    if (parts & PARTS_SEGMENTS) measure_segments(m, x);
    if (f) memset(f, 0, sizeof(double) * 3 * (size_t)L->n);
    if (K) memset(K, 0, sizeof(double) * (size_t)nnz);
    if (D) memset(D, 0, sizeof(double) * (size_t)nnz);

    if (parts & DRAPE_PART_STRETCH) {
        for (int e = 0; e < L->n_edges && !rc; e++) {
            const drape_edge *E = &L->edges[e];
            if (kern_stretch(m, E, m->eref[e], fl, K ? Jl : NULL)) { rc = 1; break; }
            ids[0] = E->a; ids[1] = E->b;
            if (f) add_forces(f, ids, 2, fl);
            if (K) add_blocks(m, m->eslot + 4 * (int64_t)e, ids, 2, Jl, K);
        }
    }
    if (!rc && (parts & DRAPE_PART_EDGE)) {
        for (int e = 0; e < L->n_edges; e++) {
            const drape_edge *E = &L->edges[e];
            if (kern_dashpot(m, E, m->eref[e], v, fl, K ? Jl : NULL, D ? Dl : NULL)) {
                rc = 1;
                break;
            }
            ids[0] = E->a; ids[1] = E->b;
            if (f) add_forces(f, ids, 2, fl);
            if (K) add_blocks(m, m->eslot + 4 * (int64_t)e, ids, 2, Jl, K);
            if (D) add_blocks(m, m->eslot + 4 * (int64_t)e, ids, 2, Dl, D);
        }
    }
    if (!rc && (parts & DRAPE_PART_BEND)) {
        for (int h = 0; h < L->n_hinges; h++) {
            const drape_hinge *H = &L->hinges[h];
            if (kern_bend(m, H, m->href + 2 * (int64_t)h, fl, K ? Jl : NULL)) { rc = 1; break; }
            ids[0] = H->prev; ids[1] = H->mid; ids[2] = H->next;
            if (f) add_forces(f, ids, 3, fl);
            if (K) add_blocks(m, m->hslot + 9 * (int64_t)h, ids, 3, Jl, K);
        }
    }
    if (!rc && (parts & DRAPE_PART_SHEAR)) {
        for (int c = 0; c < L->n_corners; c++) {
            const drape_corner *C = &L->corners[c];
            if (kern_shear(m, C, m->cref + 2 * (int64_t)c, fl, K ? Jl : NULL)) { rc = 1; break; }
            ids[0] = C->mid; ids[1] = C->warp; ids[2] = C->weft;
            if (f) add_forces(f, ids, 3, fl);
            if (K) add_blocks(m, m->cslot + 9 * (int64_t)c, ids, 3, Jl, K);
        }
    }
    if (!rc && f && (parts & DRAPE_PART_GRAVITY)) {
        for (int i = 0; i < L->n; i++) f[3 * i + 2] -= L->mass[i] * m->o.g;
    }
    if (!rc && (parts & DRAPE_PART_AIR)) {
        double ca = m->o.c_air;
        if (f && v)
            for (int i = 0; i < L->n; i++)
                for (int k = 0; k < 3; k++)
                    f[3 * i + k] -= ca * L->mass[i] * v[3 * i + k];
        if (D)
            for (int q = 0; q < m->nf; q++) {
                double mq = L->mass[L->free_to_id[q]];
                for (int k = 0; k < 3; k++)
                    D[m->dslot[q] + k * m->colstride[q] + k] -= ca * mq;
            }
    }
    if (!rc) {
        if ((f && !all_finite(f, 3 * (int64_t)L->n)) ||
            (K && !all_finite(K, nnz)) || (D && !all_finite(D, nnz)))
            rc = 1;
    }
    if (rc) {
        if (f) memset(f, 0, sizeof(double) * 3 * (size_t)L->n);
        if (K) memset(K, 0, sizeof(double) * (size_t)nnz);
        if (D) memset(D, 0, sizeof(double) * (size_t)nnz);
    }
    return rc;
}

/* ------------------------------------------------------------- public */

void drape_model_opts_from_scene(const drape_scene *s, drape_model_opts *o)
{
    o->terms = s->terms;
    o->form = s->energy_form;
    o->c_air = s->damping_air;
    o->c_edge = s->damping_edge;
    o->g = DRAPE_G_STANDARD;
}

const drape_lattice *drape_model_lattice(const drape_model *m) { return m->L; }

unsigned drape_model_parts(const drape_model *m) { return m->parts; }

const drape_pattern *drape_model_pattern(const drape_model *m) { return &m->pat; }

const drape_pattern *drape_model_pattern_first_order(const drape_model *m)
{
    return &m->pat1;
}

int drape_model_energy(drape_model *m, const double *x, drape_energies *E)
{
    const drape_lattice *L = m->L;
    double sg = L->sigma, lmin = MODEL_LEN_TINY * sg;
    int rc = 0;
    memset(E, 0, sizeof *E);
    if (m->parts & DRAPE_PART_STRETCH) {
        for (int e = 0; e < L->n_edges; e++) {
            const drape_edge *ed = &L->edges[e];
            double d[3];
            sub3(x + 3 * ed->b, x + 3 * ed->a, d);
            double l = norm3(d);
            if (!(l > lmin)) rc = 1;
            E->stretch += 0.5 * m->F.k[ed->dir] * ed->weight * (l - sg) * (l - sg);
        }
    }
    if (m->parts & DRAPE_PART_BEND) {
        for (int h = 0; h < L->n_hinges; h++) {
            const drape_hinge *H = &L->hinges[h];
            double a[3], b[3], n[3];
            sub3(x + 3 * H->mid, x + 3 * H->prev, a);
            sub3(x + 3 * H->next, x + 3 * H->mid, b);
            double la = norm3(a), lb = norm3(b);
            if (!(la > lmin) || !(lb > lmin)) { rc = 1; continue; }
            cross3(a, b, n);
            double s = norm3(n) / (la * lb), c = dot3(a, b) / (la * lb);
            if (s < MODEL_SIN_TINY && c < 0.0) rc = 1;
            E->bend += bend_g(m, H, atan2(s, c), NULL, NULL);
        }
    }
    if (m->parts & DRAPE_PART_SHEAR) {
        for (int k = 0; k < L->n_corners; k++) {
            const drape_corner *C = &L->corners[k];
            double a[3], b[3], n[3];
            sub3(x + 3 * C->warp, x + 3 * C->mid, a);
            sub3(x + 3 * C->weft, x + 3 * C->mid, b);
            double la = norm3(a), lb = norm3(b);
            if (!(la > lmin) || !(lb > lmin)) { rc = 1; continue; }
            cross3(a, b, n);
            double s = norm3(n) / (la * lb), c = dot3(a, b) / (la * lb);
            if (s < MODEL_SIN_TINY) rc = 1;
            E->shear += shear_g(m, C->weight, atan2(c, s), NULL, NULL);
        }
    }
    if (m->parts & DRAPE_PART_GRAVITY) {
        for (int i = 0; i < L->n; i++) E->gravity += L->mass[i] * m->o.g * x[3 * i + 2];
    }
    if (!isfinite(E->stretch + E->bend + E->shear + E->gravity)) {
        memset(E, 0, sizeof *E);
        rc = 1;
    }
    return rc;
}

int drape_model_forces(drape_model *m, unsigned parts, const double *x,
                       const double *v, double *f)
{
    return eval(m, parts, x, v, f, NULL, NULL);
}

int drape_model_jacobian(drape_model *m, unsigned parts, const double *x,
                         const double *v, double *K, double *D)
{
    return eval(m, parts, x, v, NULL, K, D);
}

int drape_model_jacobian_first_order(drape_model *m, unsigned parts,
                                     int include_kinematic, const double *x,
                                     const double *v, double *J)
{
    const drape_pattern *P = &m->pat;
    int want_d = (parts & m->parts & PARTS_DISSIPATIVE) != 0;
    int rc = eval(m, parts, x, v, NULL, m->Kw, want_d ? m->Dw : NULL);
    memset(J, 0, sizeof(double) * (size_t)m->pat1.nnz);
    if (rc) return rc;
    for (int64_t j = 0; j < m->N; j++) {
        if (include_kinematic) J[m->jid[j]] = 1.0;
        for (int64_t k = P->colptr[j]; k < P->colptr[j + 1]; k++) {
            double im = m->invm_row[P->rowind[k]];
            J[m->kmap[k]] = m->Kw[k] * im;
            if (want_d && m->dmap[k] >= 0) J[m->dmap[k]] = m->Dw[k] * im;
        }
    }
    return 0;
}

int drape_model_omega_bound(drape_model *m, unsigned parts, const double *x,
                            double *omega)
{
    const drape_pattern *P = &m->pat;
    double best = 0.0;
    *omega = 0.0;
    parts &= PARTS_CONSERVATIVE;
    int rc = eval(m, parts, x, NULL, NULL, m->Kw, NULL);
    if (rc) return rc;
    memset(m->rowsum, 0, sizeof(double) * (size_t)m->N);
    for (int64_t k = 0; k < P->nnz; k++) m->rowsum[P->rowind[k]] += fabs(m->Kw[k]);
    for (int64_t i = 0; i < m->N; i++) {
        double q = m->rowsum[i] * m->invm_row[i];
        if (q > best) best = q;
    }
    *omega = sqrt(best);
    return 0;
}

double drape_model_max_strain(const drape_model *m, const double *x)
{
    const drape_lattice *L = m->L;
    double best = 0.0;
    for (int e = 0; e < L->n_edges; e++) {
        double d[3];
        sub3(x + 3 * L->edges[e].b, x + 3 * L->edges[e].a, d);
        double st = fabs(norm3(d) - L->sigma) / L->sigma;
        if (st > best || isnan(st)) best = st;
    }
    return best;
}

/* ------------------------------------------------------------ patterns */

static int cmp_int(const void *a, const void *b)
{
    int x = *(const int *)a, y = *(const int *)b;
    return (x > y) - (x < y);
}

/* Append the block pairs (column = free id of particle j, row = of i) of
 * an element of np particles to pc/pr. */
static void push_pairs(const drape_lattice *L, const int *ids, int np,
                       int *pc, int *pr, int64_t *n)
{
    for (int i = 0; i < np; i++) {
        for (int j = 0; j < np; j++) {
            int fi = L->free_id[ids[i]], fj = L->free_id[ids[j]];
            if (fi < 0 || fj < 0) continue;
            pc[*n] = fj;
            pr[*n] = fi;
            (*n)++;
        }
    }
}

/* Block CSC (nf block columns) of the elements selected, with every
 * diagonal block.  Allocates *bcol (nf + 1) and *brow. */
static int build_blocks(const drape_lattice *L, int edges, int hinges,
                        int corners, int64_t **bcol, int **brow)
{
    int nf = L->n_free;
    int64_t cap = (int64_t)nf + (edges ? 4 * (int64_t)L->n_edges : 0) +
                  (hinges ? 9 * (int64_t)L->n_hinges : 0) +
                  (corners ? 9 * (int64_t)L->n_corners : 0);
    int64_t n = 0, *cnt = NULL;
    int *pc = NULL, *pr = NULL, *rows = NULL;
    int ids[3];
    int rc = -1;

    *bcol = NULL;
    *brow = NULL;
    pc = drape_malloc(sizeof(int) * (size_t)cap);
    pr = drape_malloc(sizeof(int) * (size_t)cap);
    rows = drape_malloc(sizeof(int) * (size_t)cap);
    cnt = drape_calloc((size_t)nf + 1, sizeof(int64_t));
    if (!pc || !pr || !rows || !cnt) goto out;

    for (int q = 0; q < nf; q++) {
        pc[n] = q;
        pr[n] = q;
        n++;
    }
    if (edges)
        for (int e = 0; e < L->n_edges; e++) {
            ids[0] = L->edges[e].a; ids[1] = L->edges[e].b;
            push_pairs(L, ids, 2, pc, pr, &n);
        }
    if (hinges)
        for (int h = 0; h < L->n_hinges; h++) {
            ids[0] = L->hinges[h].prev; ids[1] = L->hinges[h].mid;
            ids[2] = L->hinges[h].next;
            push_pairs(L, ids, 3, pc, pr, &n);
        }
    if (corners)
        for (int c = 0; c < L->n_corners; c++) {
            ids[0] = L->corners[c].mid; ids[1] = L->corners[c].warp;
            ids[2] = L->corners[c].weft;
            push_pairs(L, ids, 3, pc, pr, &n);
        }
    /* counting sort by column */
    for (int64_t k = 0; k < n; k++) cnt[pc[k] + 1]++;
    for (int q = 0; q < nf; q++) cnt[q + 1] += cnt[q];
    for (int64_t k = 0; k < n; k++) rows[cnt[pc[k]]++] = pr[k];
    for (int q = nf; q > 0; q--) cnt[q] = cnt[q - 1];
    cnt[0] = 0;
    /* sort and deduplicate each column in place, compacting */
    int64_t w = 0;
    for (int q = 0; q < nf; q++) {
        int64_t b = cnt[q], e = cnt[q + 1];
        qsort(rows + b, (size_t)(e - b), sizeof(int), cmp_int);
        cnt[q] = w;
        for (int64_t k = b; k < e; k++)
            if (k == b || rows[k] != rows[k - 1]) rows[w++] = rows[k];
    }
    cnt[nf] = w;
    *brow = drape_malloc(sizeof(int) * (size_t)(w > 0 ? w : 1));
    if (!*brow) goto out;
    memcpy(*brow, rows, sizeof(int) * (size_t)w);
    *bcol = cnt;
    cnt = NULL;
    rc = 0;
out:
    drape_free(pc);
    drape_free(pr);
    drape_free(rows);
    drape_free(cnt);
    return rc;
}

/* Scalar CSC of a block CSC: every block is a full 3x3. */
static int expand_blocks(int nf, const int64_t *bcol, const int *brow,
                         drape_pattern *P)
{
    int64_t N = 3 * (int64_t)nf, nnz = 9 * bcol[nf];
    P->n = N;
    P->nnz = nnz;
    P->colptr = drape_malloc(sizeof(int64_t) * (size_t)(N + 1));
    P->rowind = drape_malloc(sizeof(int64_t) * (size_t)(nnz > 0 ? nnz : 1));
    if (!P->colptr || !P->rowind) return -1;
    int64_t k = 0;
    for (int q = 0; q < nf; q++) {
        for (int c = 0; c < 3; c++) {
            P->colptr[3 * q + c] = k;
            for (int64_t t = bcol[q]; t < bcol[q + 1]; t++)
                for (int r = 0; r < 3; r++) P->rowind[k++] = 3 * (int64_t)brow[t] + r;
        }
    }
    P->colptr[N] = k;
    return 0;
}

/* Position t of block row p in block column q, or -1. */
static int64_t find_block(const int64_t *bcol, const int *brow, int q, int p)
{
    int64_t lo = bcol[q], hi = bcol[q + 1];
    while (lo < hi) {
        int64_t mid = lo + (hi - lo) / 2;
        if (brow[mid] < p) lo = mid + 1;
        else hi = mid;
    }
    return lo < bcol[q + 1] && brow[lo] == p ? lo : -1;
}

/* Slot of block (row particle i, column particle j) in the scalar pattern
 * expanded from the block pattern, or -1 if either is fixed. */
static int64_t block_slot(const drape_lattice *L, const int64_t *bcol,
                          const int *brow, int i, int j)
{
    int p = L->free_id[i], q = L->free_id[j];
    if (p < 0 || q < 0) return -1;
    int64_t t = find_block(bcol, brow, q, p);
    if (t < 0) return -1; /* cannot happen: every pair was pushed */
    return 9 * bcol[q] + 3 * (t - bcol[q]);
}

static int64_t *element_slots(const drape_lattice *L, const int64_t *bcol,
                              const int *brow, int nel, int np,
                              void (*ids_of)(const drape_lattice *, int, int *))
{
    int64_t *s = drape_malloc(sizeof(int64_t) * (size_t)(nel > 0 ? np * np * (int64_t)nel : 1));
    int ids[3];
    if (!s) return NULL;
    for (int e = 0; e < nel; e++) {
        ids_of(L, e, ids);
        for (int i = 0; i < np; i++)
            for (int j = 0; j < np; j++)
                s[(int64_t)np * np * e + np * i + j] = block_slot(L, bcol, brow, ids[i], ids[j]);
    }
    return s;
}

static void edge_ids(const drape_lattice *L, int e, int *ids)
{
    ids[0] = L->edges[e].a;
    ids[1] = L->edges[e].b;
}

static void hinge_ids(const drape_lattice *L, int h, int *ids)
{
    ids[0] = L->hinges[h].prev;
    ids[1] = L->hinges[h].mid;
    ids[2] = L->hinges[h].next;
}

static void corner_ids(const drape_lattice *L, int c, int *ids)
{
    ids[0] = L->corners[c].mid;
    ids[1] = L->corners[c].warp;
    ids[2] = L->corners[c].weft;
}

/* First-order pattern: x columns [diag; N + K rows], v columns
 * [identity; N + D rows] with D rows = edge blocks + diagonal blocks when
 * edge dashpots are built, else the diagonal alone. */
static int build_first_order(drape_model *m, const int64_t *dcol, const int *drow)
{
    const drape_pattern *P = &m->pat;
    drape_pattern *J = &m->pat1;
    int64_t N = m->N, nnz = 0, k = 0;
    int edge = dcol != NULL;

    for (int64_t j = 0; j < N; j++) {
        nnz += 1 + (P->colptr[j + 1] - P->colptr[j]);
        nnz += 1 + (edge ? 3 * (dcol[j / 3 + 1] - dcol[j / 3]) : 1);
    }
    J->n = 2 * N;
    J->nnz = nnz;
    J->colptr = drape_malloc(sizeof(int64_t) * (size_t)(2 * N + 1));
    J->rowind = drape_malloc(sizeof(int64_t) * (size_t)(nnz > 0 ? nnz : 1));
    m->kmap = drape_malloc(sizeof(int64_t) * (size_t)(P->nnz > 0 ? P->nnz : 1));
    m->dmap = drape_malloc(sizeof(int64_t) * (size_t)(P->nnz > 0 ? P->nnz : 1));
    m->jid = drape_malloc(sizeof(int64_t) * (size_t)(N > 0 ? N : 1));
    if (!J->colptr || !J->rowind || !m->kmap || !m->dmap || !m->jid) return -1;
    for (int64_t j = 0; j < N; j++) {
        J->colptr[j] = k;
        J->rowind[k++] = j;
        for (int64_t t = P->colptr[j]; t < P->colptr[j + 1]; t++) {
            m->kmap[t] = k;
            J->rowind[k++] = N + P->rowind[t];
        }
    }
    for (int64_t j = 0; j < N; j++) {
        int64_t start = k;
        J->colptr[N + j] = k;
        m->jid[j] = k;
        J->rowind[k++] = j;
        if (edge) {
            int q = (int)(j / 3);
            for (int64_t t = dcol[q]; t < dcol[q + 1]; t++)
                for (int r = 0; r < 3; r++) J->rowind[k++] = N + 3 * (int64_t)drow[t] + r;
        } else {
            J->rowind[k++] = N + j;
        }
        /* map each K-pattern entry of column j to its D position, if any */
        for (int64_t t = P->colptr[j]; t < P->colptr[j + 1]; t++) {
            int64_t row = N + P->rowind[t], lo = start + 1, hi = k;
            while (lo < hi) {
                int64_t mid = lo + (hi - lo) / 2;
                if (J->rowind[mid] < row) lo = mid + 1;
                else hi = mid;
            }
            m->dmap[t] = lo < k && J->rowind[lo] == row ? lo : -1;
        }
    }
    J->colptr[2 * N] = k;
    return 0;
}

static int cmp_i64(const void *a, const void *b)
{
    int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
    return (x > y) - (x < y);
}

/* Segment ref of the edge vector x_to - x_from (keys: sorted lo * n + hi). */
static int seg_ref(const int64_t *keys, int nseg, int n, int from, int to)
{
    int lo = from < to ? from : to, hi = from < to ? to : from;
    int64_t key = (int64_t)lo * n + hi;
    const int64_t *k = bsearch(&key, keys, (size_t)nseg, sizeof *keys, cmp_i64);
    return 2 * (int)(k - keys) + (to == hi ? 0 : 1);
}

/* The segment cache's pairs and each element's refs (struct drape_model). */
static int build_segments(drape_model *m, int edges, int hinges, int corners)
{
    const drape_lattice *L = m->L;
    int64_t n = L->n, cap = 0, nk = 0;
    if (edges) cap += L->n_edges;
    if (hinges) cap += 2 * (int64_t)L->n_hinges;
    if (corners) cap += 2 * (int64_t)L->n_corners;
    int64_t *keys = drape_malloc(sizeof *keys * (size_t)(cap > 0 ? cap : 1));
    if (!keys) return -1;
#define SEG_KEY(p, q) ((p) < (q) ? (int64_t)(p) * n + (q) : (int64_t)(q) * n + (p))
    if (edges)
        for (int e = 0; e < L->n_edges; e++) keys[nk++] = SEG_KEY(L->edges[e].a, L->edges[e].b);
    if (hinges)
        for (int h = 0; h < L->n_hinges; h++) {
            const drape_hinge *H = &L->hinges[h];
            keys[nk++] = SEG_KEY(H->prev, H->mid);
            keys[nk++] = SEG_KEY(H->mid, H->next);
        }
    if (corners)
        for (int c = 0; c < L->n_corners; c++) {
            const drape_corner *C = &L->corners[c];
            keys[nk++] = SEG_KEY(C->mid, C->warp);
            keys[nk++] = SEG_KEY(C->mid, C->weft);
        }
#undef SEG_KEY
    if (nk > 0) qsort(keys, (size_t)nk, sizeof *keys, cmp_i64);
    int64_t ns = 0;
    for (int64_t k = 0; k < nk; k++)
        if (ns == 0 || keys[k] != keys[ns - 1]) keys[ns++] = keys[k];
    size_t z = (size_t)(ns > 0 ? ns : 1);
    m->nseg = (int)ns;
    m->seg_ab = drape_malloc(sizeof(int) * 2 * z);
    m->seg_d = drape_malloc(sizeof(double) * 3 * z);
    m->seg_u = drape_malloc(sizeof(double) * 3 * z);
    m->seg_l = drape_malloc(sizeof(double) * z);
    m->seg_bad = drape_malloc(z);
    if (edges) m->eref = drape_malloc(sizeof(int) * (size_t)(L->n_edges > 0 ? L->n_edges : 1));
    if (hinges) m->href = drape_malloc(sizeof(int) * 2 * (size_t)(L->n_hinges > 0 ? L->n_hinges : 1));
    if (corners) m->cref = drape_malloc(sizeof(int) * 2 * (size_t)(L->n_corners > 0 ? L->n_corners : 1));
    if (!m->seg_ab || !m->seg_d || !m->seg_u || !m->seg_l || !m->seg_bad ||
        (edges && !m->eref) || (hinges && !m->href) || (corners && !m->cref)) {
        drape_free(keys);
        return -1;
    }
    for (int64_t s = 0; s < ns; s++) {
        m->seg_ab[2 * s] = (int)(keys[s] / n);
        m->seg_ab[2 * s + 1] = (int)(keys[s] % n);
    }
    int nsi = (int)ns, ni = (int)n;
    if (edges)
        for (int e = 0; e < L->n_edges; e++)
            m->eref[e] = seg_ref(keys, nsi, ni, L->edges[e].a, L->edges[e].b);
    if (hinges)
        for (int h = 0; h < L->n_hinges; h++) {
            const drape_hinge *H = &L->hinges[h];
            m->href[2 * h] = seg_ref(keys, nsi, ni, H->prev, H->mid);
            m->href[2 * h + 1] = seg_ref(keys, nsi, ni, H->mid, H->next);
        }
    if (corners)
        for (int c = 0; c < L->n_corners; c++) {
            const drape_corner *C = &L->corners[c];
            m->cref[2 * c] = seg_ref(keys, nsi, ni, C->mid, C->warp);
            m->cref[2 * c + 1] = seg_ref(keys, nsi, ni, C->mid, C->weft);
        }
    drape_free(keys);
    return 0;
}

static int check_lattice(const drape_lattice *L)
{
    int n = L->n;
    if (!(L->sigma > 0.0) || n < 0 || L->n_free < 0 || L->n_free > n) return -1;
    for (int e = 0; e < L->n_edges; e++) {
        const drape_edge *E = &L->edges[e];
        if (E->a < 0 || E->a >= n || E->b < 0 || E->b >= n || E->a == E->b ||
            (E->dir != DRAPE_WARP && E->dir != DRAPE_WEFT))
            return -1;
    }
    for (int h = 0; h < L->n_hinges; h++) {
        const drape_hinge *H = &L->hinges[h];
        if (H->prev < 0 || H->prev >= n || H->mid < 0 || H->mid >= n ||
            H->next < 0 || H->next >= n ||
            (H->dir != DRAPE_WARP && H->dir != DRAPE_WEFT))
            return -1;
    }
    for (int c = 0; c < L->n_corners; c++) {
        const drape_corner *C = &L->corners[c];
        if (C->mid < 0 || C->mid >= n || C->warp < 0 || C->warp >= n ||
            C->weft < 0 || C->weft >= n)
            return -1;
    }
    for (int q = 0; q < L->n_free; q++) {
        int id = L->free_to_id[q];
        if (id < 0 || id >= n || L->free_id[id] != q || !(L->mass[id] > 0.0))
            return -1;
    }
    return 0;
}

drape_model *drape_model_new(const drape_lattice *L, const drape_fabric *F,
                             const drape_model_opts *o, drape_error *err)
{
    drape_model *m = NULL;
    int64_t *bcol = NULL, *dcol = NULL;
    int *brow = NULL, *drow = NULL;

    if (!L || !F || !o) {
        drape_error_set(err, DRAPE_E_INTERNAL, NULL, 0, 0, NULL,
                        "drape_model_new: NULL argument");
        return NULL;
    }
    if (check_lattice(L)) {
        drape_error_set(err, DRAPE_E_INTERNAL, NULL, 0, 0, NULL,
                        "drape_model_new: inconsistent lattice (ids, sigma or masses)");
        return NULL;
    }
    if (!(o->c_air >= 0.0) || !(o->c_edge >= 0.0) || !isfinite(o->c_air) ||
        !isfinite(o->c_edge) || !isfinite(o->g)) {
        drape_error_set(err, DRAPE_E_INPUT, NULL, 0, 0, NULL,
                        "damping and gravity must be finite and >= 0 (c_air %g, c_edge %g, g %g)",
                        o->c_air, o->c_edge, o->g);
        return NULL;
    }
    m = drape_calloc(1, sizeof *m);
    if (!m) goto nomem;
    m->L = L;
    m->F = *F;
    m->o = *o;
    m->parts = o->terms & (DRAPE_PART_STRETCH | DRAPE_PART_BEND |
                           DRAPE_PART_SHEAR | DRAPE_PART_GRAVITY);
    if (o->c_air > 0.0) m->parts |= DRAPE_PART_AIR;
    if (o->c_edge > 0.0) m->parts |= DRAPE_PART_EDGE;
    m->nf = L->n_free;
    m->N = 3 * (int64_t)L->n_free;

    int use_edges = (m->parts & (DRAPE_PART_STRETCH | DRAPE_PART_EDGE)) != 0;
    int use_hinges = (m->parts & DRAPE_PART_BEND) != 0;
    int use_corners = (m->parts & DRAPE_PART_SHEAR) != 0;
    if (build_blocks(L, use_edges, use_hinges, use_corners, &bcol, &brow)) goto nomem;
    if (expand_blocks(m->nf, bcol, brow, &m->pat)) goto nomem;

    m->colstride = drape_malloc(sizeof(int64_t) * (size_t)(m->nf > 0 ? m->nf : 1));
    m->dslot = drape_malloc(sizeof(int64_t) * (size_t)(m->nf > 0 ? m->nf : 1));
    m->invm_row = drape_malloc(sizeof(double) * (size_t)(m->N > 0 ? m->N : 1));
    m->rowsum = drape_malloc(sizeof(double) * (size_t)(m->N > 0 ? m->N : 1));
    m->Kw = drape_malloc(sizeof(double) * (size_t)(m->pat.nnz > 0 ? m->pat.nnz : 1));
    m->Dw = drape_malloc(sizeof(double) * (size_t)(m->pat.nnz > 0 ? m->pat.nnz : 1));
    if (!m->colstride || !m->dslot || !m->invm_row || !m->rowsum || !m->Kw || !m->Dw)
        goto nomem;
    for (int q = 0; q < m->nf; q++) {
        int id = L->free_to_id[q];
        m->colstride[q] = 3 * (bcol[q + 1] - bcol[q]);
        m->dslot[q] = block_slot(L, bcol, brow, id, id);
        for (int k = 0; k < 3; k++) m->invm_row[3 * q + k] = 1.0 / L->mass[id];
    }
    if (use_edges) {
        m->eslot = element_slots(L, bcol, brow, L->n_edges, 2, edge_ids);
        if (!m->eslot) goto nomem;
    }
    if (use_hinges) {
        m->hslot = element_slots(L, bcol, brow, L->n_hinges, 3, hinge_ids);
        if (!m->hslot) goto nomem;
    }
    if (use_corners) {
        m->cslot = element_slots(L, bcol, brow, L->n_corners, 3, corner_ids);
        if (!m->cslot) goto nomem;
    }
    if (build_segments(m, use_edges, use_hinges, use_corners)) goto nomem;
    if (m->parts & DRAPE_PART_EDGE) {
        if (build_blocks(L, 1, 0, 0, &dcol, &drow)) goto nomem;
    }
    if (build_first_order(m, dcol, drow)) goto nomem;
    goto out;

nomem:
    drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL,
                    "out of memory building the model of %d particles",
                    L->n);
    drape_model_free(m);
    m = NULL;
out:
    drape_free(bcol);
    drape_free(brow);
    drape_free(dcol);
    drape_free(drow);
    return m;
}

void drape_model_free(drape_model *m)
{
    if (!m) return;
    drape_free(m->pat.colptr);
    drape_free(m->pat.rowind);
    drape_free(m->pat1.colptr);
    drape_free(m->pat1.rowind);
    drape_free(m->colstride);
    drape_free(m->dslot);
    drape_free(m->eslot);
    drape_free(m->hslot);
    drape_free(m->cslot);
    drape_free(m->kmap);
    drape_free(m->dmap);
    drape_free(m->jid);
    drape_free(m->invm_row);
    drape_free(m->Kw);
    drape_free(m->Dw);
    drape_free(m->rowsum);
    drape_free(m->seg_ab);
    drape_free(m->eref);
    drape_free(m->href);
    drape_free(m->cref);
    drape_free(m->seg_d);
    drape_free(m->seg_u);
    drape_free(m->seg_l);
    drape_free(m->seg_bad);
    drape_free(m);
}
