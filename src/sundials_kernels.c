/* sundials_kernels.c: compiled serial vector kernels for the SUNDIALS
 * backends (integrator_sundials.c).
 *
 * Debian 12's libsundials 6.4.1 is built without optimisation (its
 * N_VWSqrSumLocal_Serial keeps every operand on the stack: 21 instructions
 * per element), and every solver vector is an NVECTOR_SERIAL clone of the
 * state vector.  These replacements of the hot operations compute the same
 * expressions in the same order (no reassociation: -std=c99 keeps FP
 * contraction off), so results are unchanged, except kv_linearsum with
 * a = +-b: a x + b y where NVECTOR_SERIAL computes a (x +- y), which rounds
 * differently (arkode-dirk's results depend on it; docs/integrators.md,
 * "Debian's libsundials"); they are installed on the
 * state vector before the solver clones it (N_VClone copies the ops
 * table).  The fused operations (N_VLinearCombination, N_VScaleAddMulti,
 * N_VDotProdMulti), which NVECTOR_SERIAL leaves off by default, save whole
 * passes in the BDF and RK updates. */
#include "sundials_kernels.h"

#include <math.h>
#include <string.h>

#define VD(v) NV_DATA_S(v)
#define VN(v) NV_LENGTH_S(v)

static void kv_linearsum(sunrealtype a, N_Vector x, sunrealtype b, N_Vector y, N_Vector z)
{
    const sunrealtype *xd = VD(x), *yd = VD(y);
    sunrealtype *zd = VD(z);
    sunindextype n = VN(x);
    if (a == 1.0 && b == 1.0)
        for (sunindextype i = 0; i < n; i++) zd[i] = xd[i] + yd[i];
    else if (a == 1.0 && b == -1.0)
        for (sunindextype i = 0; i < n; i++) zd[i] = xd[i] - yd[i];
    else if (a == 1.0)
        for (sunindextype i = 0; i < n; i++) zd[i] = xd[i] + b * yd[i];
    else if (b == 1.0)
        for (sunindextype i = 0; i < n; i++) zd[i] = a * xd[i] + yd[i];
    else
        for (sunindextype i = 0; i < n; i++) zd[i] = a * xd[i] + b * yd[i];
}

static void kv_const(sunrealtype c, N_Vector z)
{
    sunrealtype *zd = VD(z);
    for (sunindextype i = 0, n = VN(z); i < n; i++) zd[i] = c;
}

static void kv_prod(N_Vector x, N_Vector y, N_Vector z)
{
    const sunrealtype *xd = VD(x), *yd = VD(y);
    sunrealtype *zd = VD(z);
    for (sunindextype i = 0, n = VN(x); i < n; i++) zd[i] = xd[i] * yd[i];
}

static void kv_div(N_Vector x, N_Vector y, N_Vector z)
{
    const sunrealtype *xd = VD(x), *yd = VD(y);
    sunrealtype *zd = VD(z);
    for (sunindextype i = 0, n = VN(x); i < n; i++) zd[i] = xd[i] / yd[i];
}

static void kv_scale(sunrealtype c, N_Vector x, N_Vector z)
{
    const sunrealtype *xd = VD(x);
    sunrealtype *zd = VD(z);
    sunindextype n = VN(x);
    if (c == 1.0) {
        if (xd != zd) memcpy(zd, xd, sizeof(sunrealtype) * (size_t)n);
    } else if (c == -1.0) {
        for (sunindextype i = 0; i < n; i++) zd[i] = -xd[i];
    } else {
        for (sunindextype i = 0; i < n; i++) zd[i] = c * xd[i];
    }
}

static void kv_abs(N_Vector x, N_Vector z)
{
    const sunrealtype *xd = VD(x);
    sunrealtype *zd = VD(z);
    for (sunindextype i = 0, n = VN(x); i < n; i++) zd[i] = fabs(xd[i]);
}

static void kv_inv(N_Vector x, N_Vector z)
{
    const sunrealtype *xd = VD(x);
    sunrealtype *zd = VD(z);
    for (sunindextype i = 0, n = VN(x); i < n; i++) zd[i] = 1.0 / xd[i];
}

static void kv_addconst(N_Vector x, sunrealtype b, N_Vector z)
{
    const sunrealtype *xd = VD(x);
    sunrealtype *zd = VD(z);
    for (sunindextype i = 0, n = VN(x); i < n; i++) zd[i] = xd[i] + b;
}

static sunrealtype kv_dotprod(N_Vector x, N_Vector y)
{
    const sunrealtype *xd = VD(x), *yd = VD(y);
    sunrealtype sum = 0.0;
    for (sunindextype i = 0, n = VN(x); i < n; i++) sum += xd[i] * yd[i];
    return sum;
}

static sunrealtype kv_maxnorm(N_Vector x)
{
    const sunrealtype *xd = VD(x);
    sunrealtype m = 0.0;
    for (sunindextype i = 0, n = VN(x); i < n; i++)
        if (fabs(xd[i]) > m) m = fabs(xd[i]);
    return m;
}

static sunrealtype kv_wsqrsum(N_Vector x, N_Vector w)
{
    const sunrealtype *xd = VD(x), *wd = VD(w);
    sunrealtype sum = 0.0;
    for (sunindextype i = 0, n = VN(x); i < n; i++) {
        sunrealtype p = xd[i] * wd[i];
        sum += p * p;
    }
    return sum;
}

static sunrealtype kv_wrmsnorm(N_Vector x, N_Vector w)
{
    return sqrt(kv_wsqrsum(x, w) / (sunrealtype)VN(x));
}

static sunrealtype kv_wsqrsummask(N_Vector x, N_Vector w, N_Vector id)
{
    const sunrealtype *xd = VD(x), *wd = VD(w), *idd = VD(id);
    sunrealtype sum = 0.0;
    for (sunindextype i = 0, n = VN(x); i < n; i++) {
        if (idd[i] > 0.0) {
            sunrealtype p = xd[i] * wd[i];
            sum += p * p;
        }
    }
    return sum;
}

static sunrealtype kv_wrmsnormmask(N_Vector x, N_Vector w, N_Vector id)
{
    return sqrt(kv_wsqrsummask(x, w, id) / (sunrealtype)VN(x));
}

static sunrealtype kv_wl2norm(N_Vector x, N_Vector w)
{
    return sqrt(kv_wsqrsum(x, w));
}

static sunrealtype kv_l1norm(N_Vector x)
{
    const sunrealtype *xd = VD(x);
    sunrealtype sum = 0.0;
    for (sunindextype i = 0, n = VN(x); i < n; i++) sum += fabs(xd[i]);
    return sum;
}

static void kv_compare(sunrealtype c, N_Vector x, N_Vector z)
{
    const sunrealtype *xd = VD(x);
    sunrealtype *zd = VD(z);
    for (sunindextype i = 0, n = VN(x); i < n; i++) zd[i] = fabs(xd[i]) >= c ? 1.0 : 0.0;
}

static sunbooleantype kv_invtest(N_Vector x, N_Vector z)
{
    const sunrealtype *xd = VD(x);
    sunrealtype *zd = VD(z);
    sunbooleantype ok = SUNTRUE;
    for (sunindextype i = 0, n = VN(x); i < n; i++) {
        if (xd[i] == 0.0) ok = SUNFALSE;
        else zd[i] = 1.0 / xd[i];
    }
    return ok;
}

/* z = sum_k c_k X_k; z may be X_0. */
static int kv_linearcombination(int nv, sunrealtype *c, N_Vector *X, N_Vector z)
{
    sunrealtype *zd = VD(z);
    sunindextype n = VN(z);
    if (nv < 1) return -1;
    if (nv == 1) {
        kv_scale(c[0], X[0], z);
        return 0;
    }
    if (nv == 2) {
        kv_linearsum(c[0], X[0], c[1], X[1], z);
        return 0;
    }
    /* first two, then accumulate the rest (same order as a loop of sums) */
    const sunrealtype *x0 = VD(X[0]), *x1 = VD(X[1]);
    for (sunindextype i = 0; i < n; i++) zd[i] = c[0] * x0[i] + c[1] * x1[i];
    for (int k = 2; k < nv; k++) {
        const sunrealtype *xk = VD(X[k]);
        sunrealtype ck = c[k];
        for (sunindextype i = 0; i < n; i++) zd[i] += ck * xk[i];
    }
    return 0;
}

/* Z_k = a_k x + Y_k; Z_k may be Y_k. */
static int kv_scaleaddmulti(int nv, sunrealtype *a, N_Vector x, N_Vector *Y, N_Vector *Z)
{
    const sunrealtype *xd = VD(x);
    sunindextype n = VN(x);
    for (int k = 0; k < nv; k++) {
        const sunrealtype *yd = VD(Y[k]);
        sunrealtype *zd = VD(Z[k]), ak = a[k];
        for (sunindextype i = 0; i < n; i++) zd[i] = ak * xd[i] + yd[i];
    }
    return 0;
}

static int kv_dotprodmulti(int nv, N_Vector x, N_Vector *Y, sunrealtype *d)
{
    for (int k = 0; k < nv; k++) d[k] = kv_dotprod(x, Y[k]);
    return 0;
}

void drape_sundials_install_kernels(N_Vector v)
{
    N_Vector_Ops o = v->ops;
    o->nvlinearsum = kv_linearsum;
    o->nvconst = kv_const;
    o->nvprod = kv_prod;
    o->nvdiv = kv_div;
    o->nvscale = kv_scale;
    o->nvabs = kv_abs;
    o->nvinv = kv_inv;
    o->nvaddconst = kv_addconst;
    o->nvdotprod = kv_dotprod;
    o->nvmaxnorm = kv_maxnorm;
    o->nvwrmsnorm = kv_wrmsnorm;
    o->nvwrmsnormmask = kv_wrmsnormmask;
    o->nvwl2norm = kv_wl2norm;
    o->nvl1norm = kv_l1norm;
    o->nvcompare = kv_compare;
    o->nvinvtest = kv_invtest;
    o->nvlinearcombination = kv_linearcombination;
    o->nvscaleaddmulti = kv_scaleaddmulti;
    o->nvdotprodmulti = kv_dotprodmulti;
    o->nvdotprodlocal = kv_dotprod;
    o->nvmaxnormlocal = kv_maxnorm;
    o->nvl1normlocal = kv_l1norm;
    o->nvinvtestlocal = kv_invtest;
    o->nvwsqrsumlocal = kv_wsqrsum;
    o->nvwsqrsummasklocal = kv_wsqrsummask;
}
