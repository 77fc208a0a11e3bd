/* fit.c: piecewise polynomial Kawabata fits (docs/model.md 3.4).
 *
 * y(x) = sum_k c_k x^k on [from, to) for each piece, extended as an odd
 * function y(-x) = -y(x) (docs/model.md 3.2: M(-K) = -M(K); 3.3: F(-g) = -F(g)).
 * W(x) = integral_0^|x| y(s) ds is even and exact: piece by piece,
 * integral_a^b sum c_k s^k ds = sum c_k (b^{k+1} - a^{k+1}) / (k + 1).
 * Polynomials are evaluated by Horner's rule.
 */
#include "drape/fit.h"

#include <math.h>
#include <string.h>

/* Index of the piece containing x >= 0 (the last one beyond its start). */
static int piece_of(const drape_fit *f, double x)
{
    int i = 0;
    while (i + 1 < f->n && x >= f->p[i + 1].from) i++;
    return i;
}

static double poly(const drape_fit_piece *p, double x)
{
    double y = 0.0;
    for (int k = p->ncoef - 1; k >= 0; k--) y = y * x + p->c[k];
    return y;
}

static double poly_d1(const drape_fit_piece *p, double x)
{
    double y = 0.0;
    for (int k = p->ncoef - 1; k >= 1; k--) y = y * x + k * p->c[k];
    return y;
}

double drape_fit_piece_value(const drape_fit_piece *p, double x)
{
    return poly(p, x);
}

double drape_fit_piece_slope(const drape_fit_piece *p, double x)
{
    return poly_d1(p, x);
}

static double poly_d2(const drape_fit_piece *p, double x)
{
    double y = 0.0;
    for (int k = p->ncoef - 1; k >= 2; k--) y = y * x + (double)k * (k - 1) * p->c[k];
    return y;
}

/* Antiderivative P(x) = sum c_k x^{k+1} / (k + 1), P(0) = 0. */
static double poly_int(const drape_fit_piece *p, double x)
{
    double y = 0.0;
    for (int k = p->ncoef - 1; k >= 0; k--) y = y * x + p->c[k] / (k + 1);
    return y * x;
}

void drape_fit_prepare(drape_fit *f)
{
    double w = 0.0;
    for (int i = 0; i < f->n; i++) {
        f->w0[i] = w;
        if (i + 1 < f->n) {
            const drape_fit_piece *p = &f->p[i];
            w += poly_int(p, f->p[i + 1].from) - poly_int(p, p->from);
        }
    }
}

double drape_fit_value(const drape_fit *f, double x)
{
    double a = fabs(x);
    double y = poly(&f->p[piece_of(f, a)], a);
    return x < 0 ? -y : y;
}

double drape_fit_slope(const drape_fit *f, double x)
{
    double a = fabs(x);
    return poly_d1(&f->p[piece_of(f, a)], a);
}

double drape_fit_slope2(const drape_fit *f, double x)
{
    double a = fabs(x);
    double y = poly_d2(&f->p[piece_of(f, a)], a);
    return x < 0 ? -y : y;
}

double drape_fit_integral(const drape_fit *f, double x)
{
    double a = fabs(x);
    int i = piece_of(f, a);
    const drape_fit_piece *p = &f->p[i];
    return f->w0[i] + poly_int(p, a) - poly_int(p, p->from);
}

double drape_fit_value_over_x(const drape_fit *f, double x)
{
    double a = fabs(x);
    int i = piece_of(f, a);
    const drape_fit_piece *p = &f->p[i];
    if (i == 0 && p->c[0] == 0.0) {
        /* exact division: (sum_{k>=1} c_k a^k) / a = sum_{k>=1} c_k a^{k-1} */
        double y = 0.0;
        for (int k = p->ncoef - 1; k >= 1; k--) y = y * a + p->c[k];
        return y;
    }
    if (a == 0.0) return poly_d1(p, 0.0);
    return poly(p, a) / a;
}

void drape_fit_scale(drape_fit *f, double xs, double ys)
{
    for (int i = 0; i < f->n; i++) {
        drape_fit_piece *p = &f->p[i];
        p->from *= xs;
        if (!isinf(p->to)) p->to *= xs;
        double s = ys;
        for (int k = 0; k < p->ncoef; k++) {
            p->c[k] *= s;
            s /= xs;
        }
    }
    drape_fit_prepare(f);
}

int drape_fit_mean(const drape_fit *a, const drape_fit *b, drape_fit *out)
{
    /* merged knots: every piece start of a or b */
    double knots[2 * DRAPE_FIT_MAX_PIECES];
    int nk = 0, ia = 0, ib = 0;
    while (ia < a->n || ib < b->n) {
        double ka = ia < a->n ? a->p[ia].from : INFINITY;
        double kb = ib < b->n ? b->p[ib].from : INFINITY;
        double k = ka < kb ? ka : kb;
        if (ka == k) ia++;
        if (kb == k) ib++;
        knots[nk++] = k;
    }
    if (nk > DRAPE_FIT_MAX_PIECES) return -1;
    drape_fit r;
    memset(&r, 0, sizeof r);
    r.n = nk;
    for (int i = 0; i < nk; i++) {
        drape_fit_piece *p = &r.p[i];
        p->from = knots[i];
        p->to = i + 1 < nk ? knots[i + 1] : INFINITY;
        const drape_fit_piece *pa = &a->p[piece_of(a, p->from)];
        const drape_fit_piece *pb = &b->p[piece_of(b, p->from)];
        p->ncoef = pa->ncoef > pb->ncoef ? pa->ncoef : pb->ncoef;
        for (int k = 0; k < p->ncoef; k++) {
            double ca = k < pa->ncoef ? pa->c[k] : 0.0;
            double cb = k < pb->ncoef ? pb->c[k] : 0.0;
            p->c[k] = 0.5 * (ca + cb);
        }
    }
    drape_fit_prepare(&r);
    *out = r;
    return 0;
}

void drape_fit_knot_jumps(const drape_fit *f, double *value_jump,
                          double *slope_jump)
{
    double vj = 0.0, sj = 0.0;
    for (int i = 1; i < f->n; i++) {
        double x = f->p[i].from;
        double dv = fabs(poly(&f->p[i], x) - poly(&f->p[i - 1], x));
        double ds = fabs(poly_d1(&f->p[i], x) - poly_d1(&f->p[i - 1], x));
        if (dv > vj) vj = dv;
        if (ds > sj) sj = ds;
    }
    if (value_jump) *value_jump = vj;
    if (slope_jump) *slope_jump = sj;
}
