/* model.c: energies, forces and the exact sparse Jacobian of a particle
 * lattice (docs/model.md sections 3 and 4; seed eqs. 1, 10, 11, 14, 16-18).
 *
 * Energies (docs/model.md 3; w = element weight, sigma = spacing):
 *   stretch edge   E = 1/2 k_dir w (l - sigma)^2                   (seed 1)
 *   bend hinge     a = x_mid - x_prev, b = x_next - x_mid,
 *                  psi = atan2(|a x b|, a.b)            (0 = flat, docs/model.md 3.2)
 *                  l = length sigma (lattice.h: 1/2 at a cantilever clamp)
 *       consistent K = psi/l,   E = w sigma^2 Wb(K), Wb = int_0^K M
 *       seed       K = 2 psi/l, E = w M(K) K sigma^2 / 2       (seed 10, 11)
 *   shear corner   a = x_warp - x_mid, b = x_weft - x_mid,
 *                  alpha = atan2(|a x b|, a.b), gamma = pi/2 - alpha
 *                        = atan2(a.b, |a x b|)                  (docs/model.md 3.3)
 *       consistent E = w sigma^2/4 Ws(|gamma|), Ws = int_0^g F
 *       seed       E = w sigma^2/4 F(|gamma|) |gamma|               (seed 14)
 *   gravity        E = sum_i m_i g z_i                          (docs/model.md 3.5)
 * Dissipation (docs/model.md 3.6):
 *   air drag       f_i = -c_air m_i v_i
 *   edge dashpot   f_b = -c_edge ((v_b - v_a).e) e, f_a = -f_b, e = unit(x_b - x_a)
 *   shear damping  f = -beta q F'(0) (dgamma/dt) grad gamma per corner
 *                  (docs/model.md 3.6: the fabric's internal damping, on by
 *                  default, beta from fabric, scene or command line)
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
 */#include "drape/model.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "drape/alloc.h"
#include "drape/units.h"
#include "model_impl.h"

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

/* df/dx of an angle element is, in 3x3 blocks (i, j),
 *     -((aa Haa + (ab Hab + ba Hab^T)) + bb Hbb),
 * with aa = ca_i ca_j, ab = ca_i cb_j, ba = cb_i ca_j, bb = cb_i cb_j, all in
 * {-1, 0, 1}.  The two functions below are that formula written out for the
 * hinge's and the corner's coefficients: the terms with a zero coefficient
 * left out (adding an exact zero changes at most the sign of a zero sum),
 * the others added with their signs in the formula's order (a product by
 * +-1 is exact), so the numbers are those of the product form at a third
 * of its work, which had been the element kernels' largest cost
 * (docs/performance.md, "The angle elements' blocks written out").  A =
 * Haa[u][v], B = Hab[u][v], Bt = Hab[v][u], C = Hbb[u][v]. */
static void angle_jac_hinge(double Haa[3][3], double Hab[3][3], double Hbb[3][3],
                            double Jl[9][9])
{
    /* ca = (-1, 1, 0), cb = (0, -1, 1) */
    for (int u = 0; u < 3; u++)
        for (int v = 0; v < 3; v++) {
            double A = Haa[u][v], B = Hab[u][v], Bt = Hab[v][u], C = Hbb[u][v];
            Jl[u][v] = -A;
            Jl[u][3 + v] = -(-A + B);
            Jl[u][6 + v] = B;
            Jl[3 + u][v] = -(-A + Bt);
            Jl[3 + u][3 + v] = -((A + (-B - Bt)) + C);
            Jl[3 + u][6 + v] = -(B - C);
            Jl[6 + u][v] = Bt;
            Jl[6 + u][3 + v] = -(Bt - C);
            Jl[6 + u][6 + v] = -C;
        }
}

static void angle_jac_corner(double Haa[3][3], double Hab[3][3], double Hbb[3][3],
                             double Jl[9][9])
{
    /* ca = (-1, 1, 0), cb = (-1, 0, 1) */
    for (int u = 0; u < 3; u++)
        for (int v = 0; v < 3; v++) {
            double A = Haa[u][v], B = Hab[u][v], Bt = Hab[v][u], C = Hbb[u][v];
            Jl[u][v] = -((A + (B + Bt)) + C);
            Jl[u][3 + v] = -(-A - Bt);
            Jl[u][6 + v] = -(-B - C);
            Jl[3 + u][v] = -(-A - B);
            Jl[3 + u][3 + v] = -A;
            Jl[3 + u][6 + v] = -B;
            Jl[6 + u][v] = -(-Bt - C);
            Jl[6 + u][3 + v] = -Bt;
            Jl[6 + u][6 + v] = -C;
        }
}

static const double HINGE_CA[3] = {-1.0, 1.0, 0.0}; /* a = x_mid - x_prev */
static const double HINGE_CB[3] = {0.0, -1.0, 1.0}; /* b = x_next - x_mid */
static const double CORNER_CA[3] = {-1.0, 1.0, 0.0}; /* a = x_warp - x_mid */
static const double CORNER_CB[3] = {-1.0, 0.0, 1.0}; /* b = x_weft - x_mid */

/* Local force (9) and df/dx (9x9, NULL to skip) of a hinge (corner 0) or a
 * corner (corner 1): an element whose energy depends on the angle between
 * a = sum_i ca[i] x_i and b = sum_i cb[i] x_i. */
static void angle_local(const angle_geo *G, int corner, double r, double p, double *fl,
                        double Jl[9][9])
{
    const double *ca = corner ? CORNER_CA : HINGE_CA, *cb = corner ? CORNER_CB : HINGE_CB;
    double ga[3], gb[3];
    angle_grad(G, r, ga, gb);
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++)
            fl[3 * i + k] = -(ca[i] * ga[k] + cb[i] * gb[k]);
    if (!Jl) return;
    double Haa[3][3], Hab[3][3], Hbb[3][3];
    angle_hess(G, r, p, Haa, Hab, Hbb);
    if (corner)
        angle_jac_corner(Haa, Hab, Hbb, Jl);
    else
        angle_jac_hinge(Haa, Hab, Hbb, Jl);
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
    angle_local(&G, 0, r, p, fl, Jl);
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
    angle_local(&G, 1, r, p, fl, Jl);
    return 0;
}

/* Shear damping of a corner (docs/model.md 3.6): the
 * dissipation function R = 1/2 kd (dgamma/dt)^2 with kd = beta q G0,
 * q = w sigma^2 / 4, G0 = F'(0) the initial slope of the fabric's mean
 * shear curve (the flat fabric's shear rigidity; clamped at 0), beta =
 * o.beta_shear: Rayleigh damping proportional to the flat state's shear
 * stiffness, constant per corner, so that it is smooth in x (a tangent
 * F'(gamma) would make K jump where F'' does, at gamma = 0 and at the
 * fit's knots).  With g = grad gamma (9 local coordinates, mid, warp,
 * weft), H = hess gamma and s = g . v:
 *     f = -kd s g,  D = df/dv = -kd g g^T,  K = df/dx = -kd (g (H v)^T + s H),
 * f . v = -kd s^2 <= 0.  gamma = pi/2 - alpha is the angle function
 * g(alpha) with g' = -1 and g'' = 0 (r = -1/sin, p = cos/sin), whose force
 * and df/dx angle_local gives as -g and -H.  v NULL means zero
 * velocities. */
static int kern_shear_damp(const drape_model *m, const drape_corner *cn, const int *ref,
                           const int *ids, const double *v, double *fl, double Jl[9][9],
                           double Dl[9][9])
{
    angle_geo G;
    double g[9], H[9][9], Hv[9] = {0.0}, s = 0.0;
    if (angle_geo_set(m, ref[0], ref[1], Jl ? GEO_HESS : 0u, &G)) return 1;
    if (G.s < MODEL_SIN_TINY) return 1;
    double kd = m->o.beta_shear * m->shear_g0 * cn->weight * m->L->sigma * m->L->sigma / 4.0;
    angle_local(&G, 1, -1.0 / G.sn, G.cn / G.sn, g, Jl ? H : NULL);
    for (int a = 0; a < 9; a++) {
        g[a] = -g[a];
        if (v) s += g[a] * v[3 * ids[a / 3] + a % 3];
    }
    for (int a = 0; a < 9; a++) fl[a] = -kd * s * g[a];
    if (Dl)
        for (int a = 0; a < 9; a++)
            for (int b = 0; b < 9; b++) Dl[a][b] = -kd * (g[a] * g[b]);
    if (Jl) {
        for (int a = 0; a < 9; a++)
            for (int b = 0; b < 9; b++) {
                H[a][b] = -H[a][b];
                if (v) Hv[a] += H[a][b] * v[3 * ids[b / 3] + b % 3];
            }
        for (int a = 0; a < 9; a++)
            for (int b = 0; b < 9; b++)
                Jl[a][b] = -kd * (g[a] * Hv[b] + s * H[a][b]);
    }
    return 0;
}

/* Twist cell (docs/model.md, "Bias bending").  With the cell's
 * corners P0 = (i, j), P1 = (i+1, j), P2 = (i+1, j+1), P3 = (i, j+1):
 *     a  = P0 - P1 + P2 - P3   (its non-planarity: sigma^2 x_xy for a
 *                               surface x(u, v); zero for any cylinder
 *                               whose axis is along a lattice direction)
 *     e1 = P2 - P0, e2 = P3 - P1 (the diagonals), c = e1 x e2,
 *     r  = a . c / g,  g = sqrt(c . c + eps^2)   (r = a . n, n the unit
 *                               normal; eps = 1e-6 sigma^2 keeps r smooth
 *                               where the diagonals become parallel)
 *     tau = r / sigma^2 (the twist curvature kappa_xy), E = w sigma^2 Wt(tau).
 * z = (a, e1, e2) is linear in the 12 coordinates, with the coefficients
 * below; gradient and Hessian are formed in z and mapped back. */
static const double CELL_CZ[3][4] = {{1.0, -1.0, 1.0, -1.0},  /* a */
                                     {-1.0, 0.0, 1.0, 0.0},   /* e1 */
                                     {0.0, -1.0, 0.0, 1.0}};  /* e2 */

/* M = [v]x, the matrix with M w = v x w. */
static void skew3(const double *v, double sgn, double M[3][3])
{
    M[0][0] = 0.0;          M[0][1] = -sgn * v[2]; M[0][2] = sgn * v[1];
    M[1][0] = sgn * v[2];   M[1][1] = 0.0;         M[1][2] = -sgn * v[0];
    M[2][0] = -sgn * v[1];  M[2][1] = sgn * v[0];  M[2][2] = 0.0;
}

/* tau of the cell at x, and (if gz != NULL) the gradient of r in z (9),
 * and (if Hz != NULL) its Hessian (9x9). */
static double cell_twist(const drape_model *m, const drape_cell *q, const double *x,
                         double gz[9], double Hz[9][9])
{
    double z[3][3], c[3];
    const double *P[4];
    double sg = m->L->sigma, eps = 1e-6 * sg * sg;
    for (int k = 0; k < 4; k++) P[k] = x + 3 * (int64_t)q->p[k];
    for (int u = 0; u < 3; u++)
        for (int d = 0; d < 3; d++) {
            double v = 0.0;
            for (int k = 0; k < 4; k++) v += CELL_CZ[u][k] * P[k][d];
            z[u][d] = v;
        }
    const double *a = z[0], *e1 = z[1], *e2 = z[2];
    cross3(e1, e2, c);
    double g = sqrt(dot3(c, c) + eps * eps), f = dot3(a, c), r = f / g;
    if (!gz) return r / (sg * sg);
    /* gradients of f and g in z */
    double gf[9], gg[9], t[3];
    for (int d = 0; d < 3; d++) gf[d] = c[d];
    cross3(e2, a, t);
    for (int d = 0; d < 3; d++) gf[3 + d] = t[d];
    cross3(a, e1, t);
    for (int d = 0; d < 3; d++) gf[6 + d] = t[d];
    double ch[3] = {c[0] / g, c[1] / g, c[2] / g};
    for (int d = 0; d < 3; d++) gg[d] = 0.0;
    cross3(e2, ch, t); /* d|c|/de1 = e2 x c/g */
    for (int d = 0; d < 3; d++) gg[3 + d] = t[d];
    cross3(ch, e1, t); /* d|c|/de2 = c/g x e1 */
    for (int d = 0; d < 3; d++) gg[6 + d] = t[d];
    for (int k = 0; k < 9; k++) gz[k] = (gf[k] - r * gg[k]) / g;
    if (!Hz) return r / (sg * sg);
    /* Hessian of f (trilinear a . (e1 x e2)) */
    double Hf[9][9], Hg[9][9], S[3][3];
    memset(Hf, 0, sizeof Hf);
    memset(Hg, 0, sizeof Hg);
    skew3(e2, -1.0, S); /* d c / d e1 = -[e2]x */
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) { Hf[i][3 + j] = S[i][j]; Hf[3 + j][i] = S[i][j]; }
    skew3(e1, 1.0, S);  /* d c / d e2 = [e1]x */
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) { Hf[i][6 + j] = S[i][j]; Hf[6 + j][i] = S[i][j]; }
    skew3(a, -1.0, S);  /* d (e2 x a) / d e2 = -[a]x */
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) { Hf[3 + i][6 + j] = S[i][j]; Hf[6 + j][3 + i] = S[i][j]; }
    /* Hessian of g = sqrt(c.c + eps^2) in (e1, e2): Jc^T (I - ch ch^T) Jc / g
     * plus ch . d2c, with Jc = [-[e2]x, [e1]x] */
    double Jc[3][6];
    skew3(e2, -1.0, S);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) Jc[i][j] = S[i][j];
    skew3(e1, 1.0, S);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) Jc[i][3 + j] = S[i][j];
    double PJ[3][6];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 6; j++) {
            double v = 0.0;
            for (int k = 0; k < 3; k++)
                v += ((i == k ? 1.0 : 0.0) - ch[i] * ch[k]) * Jc[k][j];
            PJ[i][j] = v;
        }
    for (int i = 0; i < 6; i++)
        for (int j = 0; j < 6; j++) {
            double v = 0.0;
            for (int k = 0; k < 3; k++) v += Jc[k][i] * PJ[k][j];
            Hg[3 + i][3 + j] = v / g;
        }
    skew3(ch, -1.0, S); /* d2 (w . e1 x e2) / de1 de2 = -[w]x */
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            Hg[3 + i][6 + j] += S[i][j];
            Hg[6 + j][3 + i] += S[i][j];
        }
    for (int i = 0; i < 9; i++)
        for (int j = 0; j < 9; j++)
            Hz[i][j] = (Hf[i][j] - (gf[i] * gg[j] + gg[i] * gf[j]) / g +
                        2.0 * r * gg[i] * gg[j] / g - r * Hg[i][j]) / g;
    return r / (sg * sg);
}

/* Twist cell energy (fl == NULL), or force (12) and df/dx (12x12). */
static double kern_twist(const drape_model *m, const drape_cell *q, const double *x,
                         double *fl, double Jl[12][12])
{
    double sg = m->L->sigma, w = q->weight;
    double gz[9], Hz[9][9], d1, d2;
    if (!fl) {
        double tau = cell_twist(m, q, x, NULL, NULL);
        return w * sg * sg * drape_fabric_twist_energy(&m->F, tau, NULL, NULL);
    }
    double tau = cell_twist(m, q, x, gz, Jl ? Hz : NULL);
    drape_fabric_twist_energy(&m->F, tau, &d1, &d2);
    /* E(z) = w sg^2 Wt(r / sg^2): dE/dz = w Wt' gz,
     * d2E/dz2 = w (Wt'' gz gz^T / sg^2 + Wt' Hz) */
    double Ez[9];
    for (int k = 0; k < 9; k++) Ez[k] = w * d1 * gz[k];
    for (int i = 0; i < 4; i++)
        for (int d = 0; d < 3; d++) {
            double v = 0.0;
            for (int u = 0; u < 3; u++) v += CELL_CZ[u][i] * Ez[3 * u + d];
            fl[3 * i + d] = -v;
        }
    if (!Jl) return 0.0;
    double Hzz[9][9];
    for (int i = 0; i < 9; i++)
        for (int j = 0; j < 9; j++)
            Hzz[i][j] = w * (d2 * gz[i] * gz[j] / (sg * sg) + d1 * Hz[i][j]);
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            for (int di = 0; di < 3; di++)
                for (int dj = 0; dj < 3; dj++) {
                    double v = 0.0;
                    for (int u = 0; u < 3; u++) {
                        if (CELL_CZ[u][i] == 0.0) continue;
                        for (int t = 0; t < 3; t++)
                            v += CELL_CZ[u][i] * CELL_CZ[t][j] * Hzz[3 * u + di][3 * t + dj];
                    }
                    Jl[3 * i + di][3 * j + dj] = -v;
                }
    return 0.0;
}

/* ------------------------------------------------------------- scatter */

static void add_forces(double *f, const int *ids, int np, const double *fl)
{
    for (int i = 0; i < np; i++)
        for (int k = 0; k < 3; k++) f[3 * ids[i] + k] += fl[3 * i + k];
}

/* Add local blocks Jl (np particles) into the CSC values V through the
 * element's slots (np*np, -1 where a particle is fixed). */
static void add_blocks_ld(const drape_model *m, const int64_t *slots,
                          const int *ids, int np, const double *Jl, int ld, double *V)
{
    int64_t st[4]; /* column strides of the element's particles (np <= 4) */
    for (int j = 0; j < np; j++) {
        int fid = m->L->free_id[ids[j]];
        st[j] = fid >= 0 ? m->colstride[fid] : 0; /* fixed: no slot uses it */
    }
    for (int i = 0; i < np; i++) {
        for (int j = 0; j < np; j++) {
            int64_t s = slots[np * i + j];
            if (s < 0) continue;
            const double *J = Jl + 3 * i * ld + 3 * j;
            double *W = V + s;
            for (int c = 0; c < 3; c++, W += st[j])
                for (int r = 0; r < 3; r++) W[r] += J[r * ld + c];
        }
    }
}

static void add_blocks(const drape_model *m, const int64_t *slots,
                       const int *ids, int np, double Jl[9][9], double *V)
{
    add_blocks_ld(m, slots, ids, np, &Jl[0][0], 9, V);
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

/* 1 if every a[i] is finite: NaN or inf anywhere makes a sum of a[i] * 0
 * NaN.  Four sums, so that the additions do not wait on one another (one
 * chain of dependent additions was the largest part of eval's own time in
 * `perf annotate`; sim.c keeps its own check of states). */
static int all_finite(const double *a, int64_t n)
{
    double acc[4] = {0.0, 0.0, 0.0, 0.0};
    int64_t i = 0;
    for (; i + 4 <= n; i += 4)
        for (int k = 0; k < 4; k++) acc[k] += a[i + k] * 0.0;
    for (; i < n; i++) acc[0] += a[i] * 0.0;
    return (acc[0] + acc[1]) + (acc[2] + acc[3]) == 0.0;
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
        for (int c = 0; m->use_cells && !rc && c < L->n_cells; c++) {
            const drape_cell *Q = &L->cells[c];
            double fq[12], Jq[12][12];
            kern_twist(m, Q, x, fq, K ? Jq : NULL);
            if (f) add_forces(f, Q->p, 4, fq);
            if (K) add_blocks_ld(m, m->qslot + 16 * (int64_t)c, Q->p, 4, &Jq[0][0], 12, K);
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
    if (!rc && (parts & DRAPE_PART_SHEAR_DAMPING)) {
        for (int c = 0; c < L->n_corners; c++) {
            const drape_corner *C = &L->corners[c];
            ids[0] = C->mid; ids[1] = C->warp; ids[2] = C->weft;
            if (kern_shear_damp(m, C, m->cref + 2 * (int64_t)c, ids, v, fl, K ? Jl : NULL,
                                D ? Dl : NULL)) {
                rc = 1;
                break;
            }
            if (f) add_forces(f, ids, 3, fl);
            if (K) add_blocks(m, m->cslot + 9 * (int64_t)c, ids, 3, Jl, K);
            if (D) add_blocks(m, m->cslot + 9 * (int64_t)c, ids, 3, Dl, D);
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
    o->beta_shear = s->damping_shear;
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
        for (int c = 0; m->use_cells && c < L->n_cells; c++)
            E->bend += kern_twist(m, &L->cells[c], x, NULL, NULL);
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

int drape_model_eval(drape_model *m, unsigned parts, const double *x,
                     const double *v, double *f, double *K, double *D)
{
    return eval(m, parts, x, v, f, K, D);
}

int drape_model_jacobian_first_order(drape_model *m, unsigned parts,
                                     int include_kinematic, const double *x,
                                     const double *v, double *J)
{
    const drape_pattern *P = &m->pat;
    int want_d = (parts & m->parts & DRAPE_PARTS_DAMPING) != 0;
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

void drape_model_compression_clamp(const drape_model *m, const double *x,
                                   const double kclamp[2], double *Kc)
{
    const drape_lattice *L = m->L;
    memset(Kc, 0, sizeof(double) * (size_t)m->pat.nnz);
    if (!m->eslot) return;
    double sg = L->sigma;
    for (int e = 0; e < L->n_edges; e++) {
        const drape_edge *ed = &L->edges[e];
        double d[3];
        sub3(x + 3 * ed->b, x + 3 * ed->a, d);
        double l = norm3(d);
        if (!(l < sg) || !(l > 0.0)) continue;
        double kd = kclamp ? kclamp[ed->dir] : m->F.k[ed->dir];
        double c = kd * ed->weight * (sg / l - 1.0), Jl[9][9];
        for (int k = 0; k < 3; k++) d[k] /= l;
        for (int r = 0; r < 3; r++)
            for (int q = 0; q < 3; q++) {
                double p = c * ((r == q ? 1.0 : 0.0) - d[r] * d[q]);
                Jl[r][q] = Jl[3 + r][3 + q] = -p; /* aa, bb */
                Jl[r][3 + q] = Jl[3 + r][q] = p;  /* ab, ba */
            }
        const int ids[2] = {ed->a, ed->b};
        add_blocks(m, m->eslot + 4 * (int64_t)e, ids, 2, Jl, Kc);
    }
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
