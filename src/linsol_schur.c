/* linsol_schur.c: Schur-reduced solve of the Newton systems of the
 * first-order particle ODE, factored by CHOLMOD (numerics.md 3.3).
 *
 * Equations (linsol_schur.h): J = [ 0 I ; M^-1 K  M^-1 D ],
 *     (I - gamma J) [dx; dv] = [r1; r2]
 *  => S dv = M r2 + gamma K r1,  dx = r1 + gamma dv,
 *     S = M - gamma D - gamma^2 K                                  (S.1)
 * (Baraff & Witkin 1998, eq. 18, with the first-order right-hand side of
 * SUNDIALS' Newton iteration in place of their single linearised step.)
 *
 * What is factored.  CHOLMOD needs a symmetric matrix: S is assembled from
 * the symmetric parts (K + K^T)/2 and (D + D^T)/2.  For the model they
 * differ from K and D only by the velocity-dependent dashpot term
 * dK_bb = -c/l [e (P u)^T + (u.e) P] (model.c), which is small; the exact,
 * unsymmetric J is kept in J*v so GMRES absorbs the difference.
 *
 * Indefinite S.  The geometric stiffness of a compressed spring,
 * k (1 - L/l) (I - u u^T) with l < L, and the concave parts of the bend and
 * shear energies make K indefinite away from equilibrium, so S can lose
 * definiteness when gamma^2 |K| outgrows M (large steps in a transient).
 * Choices (docs/integrators.md, "Linear solvers"):
 *   1. supernodal LL^T (BLAS-3, the fast path) of the exact symmetric S;
 *   2. if CHOLMOD reports CHOLMOD_NOT_POSDEF: simplicial LDL^T of the same
 *      S and the same fill-reducing ordering (no pivoting; exact for an
 *      indefinite but nonsingular S whose leading minors do not vanish);
 *   3. if that also fails (a zero or non-finite pivot, or a reciprocal
 *      condition estimate below SCHUR_RCOND_MIN), return 1: the integrator
 *      treats it as a recoverable setup failure and retries with a smaller
 *      step, and S -> M (SPD) as gamma -> 0.
 * Choi & Ko's clamp max(0, 1 - L/l) (2002) was not used: it needs the
 * element Hessians from the model (only the assembled K is available),
 * it does nothing for the bend and shear terms, and it turns an exact
 * preconditioner into an approximate one (more GMRES iterations).
 *
 * References: Baraff & Witkin, "Large steps in cloth simulation",
 * SIGGRAPH 1998; Chen, Davis, Hager & Rajamanickam, "Algorithm 887:
 * CHOLMOD", ACM TOMS 35 (2008); Choi & Ko, "Stable but responsive cloth",
 * SIGGRAPH 2002; numerics.md 3.3.
 */
#include "drape/linsol_schur.h"

#include <dlfcn.h>
#include <math.h>
#include <string.h>

#include <cholmod.h>

#include "drape/alloc.h"
#include "drape/integrator.h"

/* Below this reciprocal condition estimate (CHOLMOD's cheap diagonal
 * estimate) a factorisation is treated as failed. */
#define SCHUR_RCOND_MIN 1e-14

/* Supernode amalgamation (cholmod_common nrelax[]; zrelax[] stays at
 * CHOLMOD's 0.8, 0.1, 0.05).  CHOLMOD merges a child supernode into its
 * parent when the merged one has at most nrelax[0] columns, or at most
 * nrelax[1] (nrelax[2]) columns and at most zrelax[1] (zrelax[2]) of its
 * entries are explicit zeros.  CHOLMOD's 4, 16, 48 leave the lattice's
 * Schur matrix in many small supernodes, and each costs a BLAS call and an
 * OpenMP region (a futex system call in libgomp even when one thread
 * runs).  Measured with `drape bench --kernels` (schur_factor_ms, one
 * thread, same machine; three interleaved runs at 31 x 31 and 100 x 100,
 * two at 200 x 200): 31 x 31 5.7-6.2 ms -> 3.9-4.6 ms, 100 x 100 113-118 ->
 * 97-103 ms, 200 x 200 953-961 -> 889-917 ms, with the solve unchanged
 * within noise (0.25-0.26 ms at 31 x 31); 32, 128, 512 was slower than
 * this at 31 x 31 and 100 x 100
 * (docs/performance.md, "Fewer supernodes"). */
#define SCHUR_NRELAX_0 16
#define SCHUR_NRELAX_1 64
#define SCHUR_NRELAX_2 256

/* Threads.  Debian's CHOLMOD runs OpenMP regions with a fixed
 * num_threads(4) clause and calls the pthread OpenBLAS; on this project's
 * problem sizes both cost more than they gain (Cusick-size supernodes are
 * small, and the triangular solves are level-2 BLAS): single-threaded, runs of
 * the 101 x 101 and 21 x 21 hang lattices took 0.55-0.6 of the default
 * wall time (docs/integrators.md).  omp_set_num_threads(1) does not
 * override a num_threads clause; max-active-levels 0 does.  Every CHOLMOD call below is therefore bracketed by
 * "one thread" settings that are restored afterwards, so nothing else in
 * the process (GSL's dense LU on OpenBLAS) is affected.  The two library
 * functions are looked up at run time (POSIX dlsym on the global scope):
 * drape links neither libgomp nor the OpenBLAS symbols by name. */
typedef void (*set_int_fn)(int);
typedef int (*get_int_fn)(void);

typedef struct thread_ctl {
    set_int_fn blas_set, omp_set_levels;
    get_int_fn blas_get, omp_get_levels;
    int blas_saved, omp_saved;
} thread_ctl;

typedef char drape_check_sslong[sizeof(SuiteSparse_long) == sizeof(int64_t) ? 1 : -1];

struct drape_schur {
    const drape_pattern *P;
    int64_t n;          /* 3 nf */
    double *mass;       /* n: mass of the particle owning each coordinate */
    double *invm;       /* n */
    int64_t nl;         /* entries of the lower triangle of P */
    int64_t *map_a;     /* nl: slot of (i, j) in P */
    int64_t *map_b;     /* nl: slot of (j, i) in P */
    cholmod_common c;
    int have_c;
    int no_ldl;         /* 1: no LDL^T fallback (drape_schur_ldl_fallback) */
    cholmod_sparse *A;  /* S, lower triangle (stype -1) */
    cholmod_factor *Lll;  /* supernodal LL^T */
    cholmod_factor *Lldl; /* simplicial LDL^T (lazy) */
    cholmod_factor *cur;  /* the factor of the last successful call, or NULL */
    cholmod_dense *B, *X, *Y, *E;
    double gamma_f;
    drape_schur_stats st;
    thread_ctl th;
};

/* Function pointer from a data pointer (dlsym's documented POSIX use). */
static void *lookup(void *h, const char *name)
{
    return h ? dlsym(h, name) : NULL;
}

static void threads_init(thread_ctl *t)
{
    void *h = dlopen(NULL, RTLD_LAZY);
    void *p;
    memset(t, 0, sizeof *t);
    if ((p = lookup(h, "openblas_set_num_threads"))) memcpy(&t->blas_set, &p, sizeof p);
    if ((p = lookup(h, "openblas_get_num_threads"))) memcpy(&t->blas_get, &p, sizeof p);
    if ((p = lookup(h, "omp_set_max_active_levels"))) memcpy(&t->omp_set_levels, &p, sizeof p);
    if ((p = lookup(h, "omp_get_max_active_levels"))) memcpy(&t->omp_get_levels, &p, sizeof p);
    if (h) dlclose(h);
}

static void threads_single(thread_ctl *t)
{
    if (t->blas_set && t->blas_get) {
        t->blas_saved = t->blas_get();
        if (t->blas_saved != 1) t->blas_set(1);
    }
    if (t->omp_set_levels && t->omp_get_levels) {
        t->omp_saved = t->omp_get_levels();
        if (t->omp_saved != 0) t->omp_set_levels(0); /* every region inactive */
    }
}

static void threads_restore(thread_ctl *t)
{
    if (t->blas_set && t->blas_get && t->blas_saved != 1) t->blas_set(t->blas_saved);
    if (t->omp_set_levels && t->omp_get_levels && t->omp_saved != 0)
        t->omp_set_levels(t->omp_saved);
}

/* ---- names of the integrator option (integrator.h) ------------------------- */

int drape_linsol_parse(const char *name, int *out)
{
    if (!name) return -1;
    if (strcmp(name, "auto") == 0) *out = DRAPE_LINSOL_AUTO;
    else if (strcmp(name, "klu") == 0) *out = DRAPE_LINSOL_KLU;
    else if (strcmp(name, "schur") == 0) *out = DRAPE_LINSOL_SCHUR;
    else if (strcmp(name, "schur-direct") == 0) *out = DRAPE_LINSOL_SCHUR_DIRECT;
    else return -1;
    return 0;
}

const char *drape_linsol_name(int linsol)
{
    switch (linsol) {
    case DRAPE_LINSOL_AUTO: return "auto";
    case DRAPE_LINSOL_KLU: return "klu";
    case DRAPE_LINSOL_SCHUR: return "schur";
    case DRAPE_LINSOL_SCHUR_DIRECT: return "schur-direct";
    default: return "none";
    }
}

/* ---- set-up ------------------------------------------------------------------ */

/* Slot of row r in column j of P, or -1 (rows sorted within a column). */
static int64_t find_slot(const drape_pattern *P, int64_t r, int64_t j)
{
    int64_t lo = P->colptr[j], hi = P->colptr[j + 1] - 1;
    while (lo <= hi) {
        int64_t mid = lo + (hi - lo) / 2, q = P->rowind[mid];
        if (q == r) return mid;
        if (q < r) lo = mid + 1;
        else hi = mid - 1;
    }
    return -1;
}

void drape_schur_free(drape_schur *s)
{
    if (!s) return;
    if (s->have_c) {
        cholmod_l_free_factor(&s->Lll, &s->c);
        cholmod_l_free_factor(&s->Lldl, &s->c);
        cholmod_l_free_sparse(&s->A, &s->c);
        cholmod_l_free_dense(&s->B, &s->c);
        cholmod_l_free_dense(&s->X, &s->c);
        cholmod_l_free_dense(&s->Y, &s->c);
        cholmod_l_free_dense(&s->E, &s->c);
        cholmod_l_finish(&s->c);
    }
    drape_free(s->mass);
    drape_free(s->invm);
    drape_free(s->map_a);
    drape_free(s->map_b);
    drape_free(s);
}

drape_schur *drape_schur_new(const drape_pattern *P, const double *inv_mass,
                             drape_error *err)
{
    drape_schur *s = drape_calloc(1, sizeof *s);
    if (!s) goto nomem;
    s->P = P;
    s->n = P->n;
    threads_init(&s->th);
    int64_t n = P->n;
    size_t nn = (size_t)(n > 0 ? n : 1);
    s->mass = drape_malloc(sizeof(double) * nn);
    s->invm = drape_malloc(sizeof(double) * nn);
    if (!s->mass || !s->invm) goto nomem;
    for (int64_t i = 0; i < n; i++) {
        s->invm[i] = inv_mass[i / 3];
        s->mass[i] = 1.0 / inv_mass[i / 3];
    }
    s->nl = 0;
    for (int64_t j = 0; j < n; j++)
        for (int64_t k = P->colptr[j]; k < P->colptr[j + 1]; k++)
            if (P->rowind[k] >= j) s->nl++;
    s->map_a = drape_malloc(sizeof(int64_t) * (size_t)(s->nl ? s->nl : 1));
    s->map_b = drape_malloc(sizeof(int64_t) * (size_t)(s->nl ? s->nl : 1));
    if (!s->map_a || !s->map_b) goto nomem;

    cholmod_l_start(&s->c);
    s->have_c = 1;
    s->c.print = 0;                      /* library code never prints */
    s->c.quick_return_if_not_posdef = 1; /* a failed LL^T costs less */
    s->c.final_ll = 0;                   /* simplicial stays LDL^T */
    s->c.nrelax[0] = SCHUR_NRELAX_0;
    s->c.nrelax[1] = SCHUR_NRELAX_1;
    s->c.nrelax[2] = SCHUR_NRELAX_2;
    s->A = cholmod_l_allocate_sparse((size_t)n, (size_t)n, (size_t)s->nl, 1, 1, -1,
                                     CHOLMOD_REAL, &s->c);
    s->B = cholmod_l_allocate_dense((size_t)n, 1, (size_t)n, CHOLMOD_REAL, &s->c);
    if (!s->A || !s->B) goto nomem;
    SuiteSparse_long *Ap = s->A->p, *Ai = s->A->i;
    double *Ax = s->A->x;
    int64_t q = 0;
    for (int64_t j = 0; j < n; j++) {
        Ap[j] = q;
        int has_diag = 0;
        for (int64_t k = P->colptr[j]; k < P->colptr[j + 1]; k++) {
            int64_t i = P->rowind[k];
            if (i < j) continue;
            int64_t t = find_slot(P, j, i);
            if (t < 0) {
                drape_error_set(err, DRAPE_E_INTERNAL, NULL, 0, 0, NULL,
                                "schur: the Jacobian pattern is not structurally "
                                "symmetric (entry %ld, %ld)", (long)i, (long)j);
                drape_schur_free(s);
                return NULL;
            }
            if (i == j) has_diag = 1;
            s->map_a[q] = k;
            s->map_b[q] = t;
            Ai[q] = i;
            Ax[q] = i == j ? s->mass[i] : 0.0;
            q++;
        }
        if (!has_diag) {
            drape_error_set(err, DRAPE_E_INTERNAL, NULL, 0, 0, NULL,
                            "schur: the Jacobian pattern lacks diagonal entry %ld",
                            (long)j);
            drape_schur_free(s);
            return NULL;
        }
    }
    Ap[n] = q;

    /* Symbolic analysis once (AMD, or METIS when CHOLMOD finds AMD poor). */
    s->c.supernodal = CHOLMOD_SUPERNODAL;
    threads_single(&s->th);
    s->Lll = cholmod_l_analyze(s->A, &s->c);
    threads_restore(&s->th);
    if (!s->Lll || s->c.status < CHOLMOD_OK) goto nomem;
    return s;

nomem:
    drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL,
                    "schur: out of memory setting up CHOLMOD for %ld unknowns",
                    (long)P->n);
    drape_schur_free(s);
    return NULL;
}

/* ---- factorisation ------------------------------------------------------------- */

static int factor_ok(drape_schur *s, cholmod_factor *L)
{
    if (s->c.status != CHOLMOD_OK || L->minor < L->n) return 0;
    double rc = cholmod_l_rcond(L, &s->c);
    return rc >= SCHUR_RCOND_MIN && isfinite(rc);
}

static int factor_numeric(drape_schur *s, double gamma);

int drape_schur_factor(drape_schur *s, const double *K, const double *D,
                       double gamma, drape_error *err)
{
    const int64_t n = s->n;
    const SuiteSparse_long *Ap = s->A->p, *Ai = s->A->i;
    double *Ax = s->A->x;
    double g2 = gamma * gamma;
    double bad = 0.0;
    s->cur = NULL;
    s->gamma_f = 0.0;
    for (int64_t j = 0; j < n; j++) {
        for (SuiteSparse_long q = Ap[j]; q < Ap[j + 1]; q++) {
            int64_t a = s->map_a[q], b = s->map_b[q];
            double v = -0.5 * g2 * (K[a] + K[b]);
            if (D) v -= 0.5 * gamma * (D[a] + D[b]);
            if (Ai[q] == j) v += s->mass[j];
            Ax[q] = v;
            bad += v * 0.0; /* NaN if any value is not finite */
        }
    }
    if (isnan(bad)) {
        s->st.failures++;
        return 1;
    }

    threads_single(&s->th);
    int rc = factor_numeric(s, gamma);
    threads_restore(&s->th);
    if (rc < 0)
        drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL,
                        "schur: CHOLMOD ran out of memory factoring %ld unknowns",
                        (long)n);
    return rc;
}

/* The numeric factorisation of s->A: 0, 1 (failed), -1 (out of memory). */
static int factor_numeric(drape_schur *s, double gamma)
{
    /* 1. supernodal LL^T */
    int ok = cholmod_l_factorize(s->A, s->Lll, &s->c);
    if (!ok && s->c.status == CHOLMOD_OUT_OF_MEMORY) goto nomem;
    if (ok && factor_ok(s, s->Lll)) {
        s->cur = s->Lll;
        s->gamma_f = gamma;
        s->st.factorizations++;
        return 0;
    }
    if (s->c.status != CHOLMOD_NOT_POSDEF && s->c.status != CHOLMOD_OK) {
        s->st.failures++;
        return 1;
    }

    if (s->no_ldl) { /* the caller shifts S instead (drape_schur_ldl_fallback) */
        s->st.failures++;
        return 1;
    }
    /* 2. simplicial LDL^T, same ordering (analysed on first use) */
    if (!s->Lldl) {
        int nm = s->c.nmethods, ord = s->c.method[0].ordering, pa = s->c.postorder;
        s->c.supernodal = CHOLMOD_SIMPLICIAL;
        s->c.nmethods = 1;
        s->c.method[0].ordering = CHOLMOD_GIVEN;
        s->c.postorder = 0;
        s->Lldl = cholmod_l_analyze_p(s->A, s->Lll->Perm, NULL, 0, &s->c);
        s->c.supernodal = CHOLMOD_SUPERNODAL;
        s->c.nmethods = nm;
        s->c.method[0].ordering = ord;
        s->c.postorder = pa;
        if (!s->Lldl) goto nomem;
    }
    ok = cholmod_l_factorize(s->A, s->Lldl, &s->c);
    if (!ok && s->c.status == CHOLMOD_OUT_OF_MEMORY) goto nomem;
    if (ok && factor_ok(s, s->Lldl)) {
        s->cur = s->Lldl;
        s->gamma_f = gamma;
        s->st.factorizations++;
        s->st.ldl_fallbacks++;
        return 0;
    }
    /* 3. give up on this gamma */
    s->st.failures++;
    return 1;

nomem:
    return -1;
}

void drape_schur_ldl_fallback(drape_schur *s, int on) { s->no_ldl = !on; }

/* ---- solve and product -------------------------------------------------------- */

int drape_schur_solve(drape_schur *s, const double *K, double gamma,
                      const double *r, double *z)
{
    const drape_pattern *P = s->P;
    const int64_t n = s->n;
    const double *r1 = r, *r2 = r + n;
    double *b = s->B->x;
    if (!s->cur) return 1;
    for (int64_t i = 0; i < n; i++) b[i] = s->mass[i] * r2[i];
    for (int64_t j = 0; j < n; j++) {
        double gx = gamma * r1[j];
        if (gx == 0.0) continue;
        for (int64_t k = P->colptr[j]; k < P->colptr[j + 1]; k++)
            b[P->rowind[k]] += K[k] * gx;
    }
    threads_single(&s->th);
    int ok = cholmod_l_solve2(CHOLMOD_A, s->cur, s->B, NULL, &s->X, NULL, &s->Y, &s->E,
                              &s->c);
    threads_restore(&s->th);
    if (!ok) return 1;
    const double *dv = s->X->x;
    for (int64_t i = 0; i < n; i++) {
        z[i] = r1[i] + gamma * dv[i];
        z[n + i] = dv[i];
    }
    return 0;
}

void drape_schur_jtimes(const drape_schur *s, const double *K, const double *D,
                        const double *v, double *Jv)
{
    const drape_pattern *P = s->P;
    const int64_t n = s->n;
    const double *v1 = v, *v2 = v + n;
    double *a = Jv + n;
    memcpy(Jv, v2, sizeof(double) * (size_t)n);
    memset(a, 0, sizeof(double) * (size_t)n);
    if (D) {
        for (int64_t j = 0; j < n; j++) {
            double x1 = v1[j], x2 = v2[j];
            for (int64_t k = P->colptr[j]; k < P->colptr[j + 1]; k++)
                a[P->rowind[k]] += K[k] * x1 + D[k] * x2;
        }
    } else {
        for (int64_t j = 0; j < n; j++) {
            double x1 = v1[j];
            for (int64_t k = P->colptr[j]; k < P->colptr[j + 1]; k++)
                a[P->rowind[k]] += K[k] * x1;
        }
    }
    for (int64_t i = 0; i < n; i++) a[i] *= s->invm[i];
}

double drape_schur_gamma(const drape_schur *s) { return s->gamma_f; }

void drape_schur_get_stats(const drape_schur *s, drape_schur_stats *st)
{
    *st = s->st;
}
