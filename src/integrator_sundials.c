/* integrator_sundials.c: the SUNDIALS 6.4.1 backends cvode-bdf, arkode-imex,
 * arkode-dirk and arkode-erk.
 *
 * Problem (integrator.h, docs/model.md 4): y' = F(y), y = [x_free; v_free],
 *     F(y) = [ v ; M^-1 f(x, v) ],   J = [ 0 I ; M^-1 K  M^-1 D ].
 *
 * cvode-bdf   CVODE, BDF orders 1..max_order (default 2: BDF orders 3-5
 *             are only A(alpha)-stable and lose on oscillatory stiffness,
 *             numerics.md 1.4 and 6.6), Newton on the exact sparse J.
 * arkode-imex ARKStep additive RK ARK4(3)6L[2]SA (Kennedy & Carpenter
 *             2003), implicit part
 *                 F_I = [ v ; M^-1 (f_stretch + f_edge + f_shear +
 *                                   f_shear_damping) ]
 *             and explicit part F_E = [ 0 ; M^-1 (f_bend + f_gravity +
 *             f_air) ] (numerics.md 3.4: x' = v belongs in F_I); Newton on
 *             dF_I/dy; Lagrange interpolant for dense output (stiff);
 *             stage predictor = maximum-order interpolant (see below).
 * arkode-dirk ARKStep fully implicit, ESDIRK4(3)6L[2]SA (Kennedy & Carpenter
 *             2016), L-stable and stiffly accurate; Newton on the exact J.
 * arkode-erk  ERKStep, Dormand-Prince 5(4) (explicit baseline).
 *
 * Newton linear solvers (option linsol, integrator.h; docs/integrators.md
 * "Linear solvers"), for the system (I - gamma J) z = r:
 *   klu          A = I - gamma J assembled here (CVodeSetLinSysFn /
 *                ARKStepSetLinSysFn) from a saved J, KLU with AMD ordering;
 *                the setup is skipped when J and gamma are unchanged;
 *   schur        SPGMR, left preconditioner = the Schur elimination
 *                S dv = M r2 + gamma K r1, dx = r1 + gamma dv,
 *                S = M - gamma D - gamma^2 K (numerics.md 3.3; CHOLMOD,
 *                linsol_schur.c), exact J*v with the same K, D;
 *   schur-direct the Schur elimination applied once, through a one-shot
 *                "iterative" SUNLinearSolver (no Krylov iteration).
 * In every case the Newton iteration is SUNDIALS' modified Newton: J from
 * the last evaluation, re-evaluated when SUNDIALS asks (!jok).
 *
 * SUNDIALS traps handled here (numerics.md section 6): the first-order
 * pattern stores the diagonal and A is built here (SUNMatScaleAddI_Sparse
 * is O(N^2) with a missing diagonal); A keeps one pattern, so KLU's
 * symbolic analysis stays valid; sparse matrices have no
 * difference-quotient Jacobian, so the linear-system callback is
 * mandatory; the default mxstep of 500 is raised; SUNDIALS' own error
 * printing is replaced by a handler that keeps the last message for
 * drape_error.  Debian's libsundials is compiled without optimisation, so
 * the hot vector operations are replaced by compiled kernels
 * (sundials_kernels.c).
 *
 * References: Hindmarsh et al., "SUNDIALS: Suite of nonlinear and
 * differential/algebraic equation solvers", ACM TOMS 31 (2005); Reynolds et
 * al., ARKODE user guide v5.4.1; Kennedy & Carpenter, Appl. Numer. Math. 44
 * (2003) and NASA TM-2016-219173; Dormand & Prince, J. Comput. Appl. Math.
 * 6 (1980); Baraff & Witkin, SIGGRAPH 1998 (the Schur reduction).
 */
#include "drape/integrator.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h> /* free() of the flag names SUNDIALS mallocs */
#include <string.h>

#include <arkode/arkode_arkstep.h>
#include <arkode/arkode_erkstep.h>
#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_config.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunlinsol/sunlinsol_spgmr.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include "drape/alloc.h"
#include "drape/linsol_schur.h"
#include "sundials_kernels.h"

#if SUNDIALS_VERSION_MAJOR >= 7
#error "drape targets the SUNDIALS 6.x API (numerics.md 1.9): port the error handler and context creation"
#endif

/* The model's pattern indices are int64_t; SUNDIALS' must match to memcpy. */
typedef char drape_check_sunindextype[sizeof(sunindextype) == sizeof(int64_t) ? 1 : -1];

typedef enum sun_kind { SK_CVODE, SK_IMEX, SK_DIRK, SK_ERK } sun_kind;

/* Newton's initial guess for each implicit stage: 1 = the maximum-order
 * interpolant of the last step.  With ARKODE's default trivial predictor
 * (0, the previous step's solution) Newton's three iterations kept failing
 * on the hang test scene and the step was convergence-limited: 2-3x more
 * steps and 5x the time (docs/integrators.md). */
#define ARK_IMPLICIT_PREDICTOR 1

/* Parts in the implicit partition of arkode-imex (numerics.md 3.4). */
#define IMEX_IMPLICIT_PARTS \
    (DRAPE_PART_STRETCH | DRAPE_PART_EDGE | DRAPE_PART_SHEAR | DRAPE_PART_SHEAR_DAMPING)

/* arkode-imex: Newton's stopping test, as a fraction of the local error
 * test (ARKStepSetNonlinConvCoef; SUNDIALS' default is 0.1). */
#define IMEX_NLS_CONV_COEF 0.01

/* Krylov subspace of SPGMR with the Schur preconditioner.  With S factored
 * at the current gamma one iteration is exact; between setups gamma moves by
 * up to 20-30 %: measured 0.96-1.04 iterations per Newton iteration
 * (docs/integrators.md), so 5 is ample. */
#define SCHUR_MAXL 5

typedef struct sun_state {
    sun_kind kind;
    const char *name;
    drape_ode *ode;
    unsigned parts_i, parts_e; /* arkode-imex partitions */
    SUNContext ctx;
    int have_ctx;
    void *mem;
    N_Vector y, atol, yd;
    SUNMatrix A;
    SUNLinearSolver LS;
    int linsol;          /* DRAPE_LINSOL_KLU, _SCHUR or _SCHUR_DIRECT; 0 for arkode-erk */
    unsigned jparts;     /* parts in the Newton Jacobian */
    int have_d;          /* jparts has a dissipative part (D != 0) */
    drape_schur *schur;  /* linsol schur, schur-direct */
    double *K, *D;       /* linsol schur: K, D of the last Jacobian (model pattern) */
    double *J;           /* linsol klu: first-order J of the last evaluation */
    int64_t *jdiag;      /* linsol klu: slot of each diagonal entry of J */
    double gamma_a;      /* linsol klu: gamma of the values in A (0 = none) */
    int a_same;          /* linsol klu: the last klu_linsys left A unchanged */
    long n_reuse;        /* setups that kept the previous factorisation */
    int jac_valid;       /* K, D hold a Jacobian */
    drape_error serr;    /* first error inside the preconditioner */
    long max_steps;
    double t_stop;
    char msg[256]; /* last message from SUNDIALS' error handler */
} sun_state;

/* ---- callbacks -------------------------------------------------------------- */

static int rhs_all(sunrealtype t, N_Vector y, N_Vector ydot, void *ud)
{
    sun_state *s = ud;
    (void)t;
    return drape_ode_rhs(s->ode, s->ode->parts, 1, N_VGetArrayPointer(y),
                         N_VGetArrayPointer(ydot));
}

static int rhs_impl(sunrealtype t, N_Vector y, N_Vector ydot, void *ud)
{
    sun_state *s = ud;
    (void)t;
    return drape_ode_rhs(s->ode, s->parts_i, 1, N_VGetArrayPointer(y),
                         N_VGetArrayPointer(ydot));
}

static int rhs_expl(sunrealtype t, N_Vector y, N_Vector ydot, void *ud)
{
    sun_state *s = ud;
    (void)t;
    return drape_ode_rhs(s->ode, s->parts_e, 0, N_VGetArrayPointer(y),
                         N_VGetArrayPointer(ydot));
}

/* ---- linsol klu: the Newton matrix built here ------------------------------
 * A = I - gamma J from drape's own copy of J (same values as SUNDIALS'
 * default SUNMatCopy + SUNMatScaleAddI, which Debian ships unoptimised);
 * J is re-evaluated only when SUNDIALS asks (!jok).  A keeps the pattern it
 * was created with, so KLU's symbolic analysis and pivot order stay valid
 * (SUNLinSol_KLU analyses once, then only klu_l_refactor: numerics.md 6.2). */
static int klu_linsys(sun_state *s, N_Vector y, SUNMatrix A, sunbooleantype jok,
                      sunbooleantype *jcur, sunrealtype gamma)
{
    const drape_pattern *p = s->ode->pattern;
    *jcur = SUNFALSE;
    /* Same Jacobian and same gamma: A is unchanged, and kluwrap_setup skips
     * the refactorisation. */
    s->a_same = jok && s->jac_valid && gamma == s->gamma_a;
    if (s->a_same) return 0;
    s->gamma_a = 0.0;
    if (!jok || !s->jac_valid) {
        s->jac_valid = 0;
        if (drape_ode_jacobian(s->ode, s->jparts, 1, N_VGetArrayPointer(y), s->J) != 0)
            return 1;
        s->jac_valid = 1;
        *jcur = SUNTRUE;
    }
    double *a = SUNSparseMatrix_Data(A);
    const double *J = s->J;
    for (int64_t k = 0; k < p->nnz; k++) a[k] = -gamma * J[k];
    for (int64_t j = 0; j < p->n; j++) a[s->jdiag[j]] += 1.0;
    s->gamma_a = gamma;
    return 0;
}

/* A direct linear solver that forwards to SUNLinSol_KLU but skips its
 * setup (klu_l_refactor) when klu_linsys left A unchanged.  SUNLinSol_KLU
 * analyses and factors on its first setup and only refactors afterwards. */
typedef struct kluwrap_content {
    SUNLinearSolver inner;
    sun_state *s;
} kluwrap_content;

#define KW(LS) ((kluwrap_content *)(LS)->content)

static SUNLinearSolver_Type kluwrap_gettype(SUNLinearSolver LS)
{
    (void)LS;
    return SUNLINEARSOLVER_DIRECT;
}

static SUNLinearSolver_ID kluwrap_getid(SUNLinearSolver LS)
{
    (void)LS;
    return SUNLINEARSOLVER_CUSTOM;
}

static int kluwrap_initialize(SUNLinearSolver LS)
{
    return SUNLinSolInitialize(KW(LS)->inner);
}

static int kluwrap_setup(SUNLinearSolver LS, SUNMatrix A)
{
    sun_state *s = KW(LS)->s;
    if (s->a_same) {
        s->n_reuse++;
        return SUNLS_SUCCESS;
    }
    int rc = SUNLinSolSetup(KW(LS)->inner, A);
    if (rc != SUNLS_SUCCESS) s->gamma_a = 0.0; /* never reuse a failed factor */
    return rc;
}

static int kluwrap_solve(SUNLinearSolver LS, SUNMatrix A, N_Vector x, N_Vector b,
                         sunrealtype tol)
{
    return SUNLinSolSolve(KW(LS)->inner, A, x, b, tol);
}

static sunindextype kluwrap_lastflag(SUNLinearSolver LS)
{
    return SUNLinSolLastFlag(KW(LS)->inner);
}

static int kluwrap_free(SUNLinearSolver LS)
{
    if (!LS) return SUNLS_SUCCESS;
    if (LS->content) {
        if (KW(LS)->inner) SUNLinSolFree(KW(LS)->inner);
        drape_free(LS->content);
        LS->content = NULL;
    }
    SUNLinSolFreeEmpty(LS);
    return SUNLS_SUCCESS;
}

/* Takes ownership of inner (freed on failure too). */
static SUNLinearSolver kluwrap_new(SUNLinearSolver inner, sun_state *s)
{
    SUNLinearSolver LS = SUNLinSolNewEmpty(s->ctx);
    if (!LS || !(LS->content = drape_calloc(1, sizeof(kluwrap_content)))) {
        if (LS) SUNLinSolFreeEmpty(LS);
        SUNLinSolFree(inner);
        return NULL;
    }
    KW(LS)->inner = inner;
    KW(LS)->s = s;
    LS->ops->gettype = kluwrap_gettype;
    LS->ops->getid = kluwrap_getid;
    LS->ops->initialize = kluwrap_initialize;
    LS->ops->setup = kluwrap_setup;
    LS->ops->solve = kluwrap_solve;
    LS->ops->lastflag = kluwrap_lastflag;
    LS->ops->free = kluwrap_free;
    return LS;
}

static int linsys_cv(sunrealtype t, N_Vector y, N_Vector fy, SUNMatrix A,
                     sunbooleantype jok, sunbooleantype *jcur, sunrealtype gamma,
                     void *ud, N_Vector t1, N_Vector t2, N_Vector t3)
{
    (void)t; (void)fy; (void)t1; (void)t2; (void)t3;
    return klu_linsys(ud, y, A, jok, jcur, gamma);
}

static int linsys_ark(sunrealtype t, N_Vector y, N_Vector fy, SUNMatrix A,
                      SUNMatrix M, sunbooleantype jok, sunbooleantype *jcur,
                      sunrealtype gamma, void *ud, N_Vector t1, N_Vector t2,
                      N_Vector t3)
{
    (void)t; (void)fy; (void)M; (void)t1; (void)t2; (void)t3;
    return klu_linsys(ud, y, A, jok, jcur, gamma);
}

/* ---- linsol schur: preconditioner and J*v (numerics.md 3.3) ---------------- */

/* Same signature as ARKLsPrecSetupFn.  New K, D when SUNDIALS asks for a
 * fresh Jacobian (!jok); S(gamma) refactored unless K, D and gamma are
 * those of the current factor. */
static int psetup_cb(sunrealtype t, N_Vector y, N_Vector fy, sunbooleantype jok,
                     sunbooleantype *jcur, sunrealtype gamma, void *ud)
{
    sun_state *s = ud;
    (void)t; (void)fy;
    *jcur = SUNFALSE;
    /* Same Jacobian and same gamma (CVODE keeps h for many steps and still
     * calls the setup every 20): S is unchanged, keep its factor. */
    if (jok && s->jac_valid && gamma == drape_schur_gamma(s->schur)) {
        s->n_reuse++;
        return 0;
    }
    if (!jok || !s->jac_valid) {
        drape_ode *o = s->ode;
        s->jac_valid = 0;
        o->n_jac++;
        drape_ode_scatter(o, N_VGetArrayPointer(y));
        if (drape_model_jacobian(o->model, s->jparts, o->x, o->v, s->K,
                                 s->have_d ? s->D : NULL) != 0)
            return 1;
        s->jac_valid = 1;
        *jcur = SUNTRUE;
    }
    int rc = drape_schur_factor(s->schur, s->K, s->have_d ? s->D : NULL, gamma, &s->serr);
    return rc < 0 ? -1 : rc;
}

/* Same signature as ARKLsPrecSolveFn: z = (I - gamma J)^-1 r by the Schur
 * elimination (exact up to the gamma of the last setup). */
static int psolve_cb(sunrealtype t, N_Vector y, N_Vector fy, N_Vector r,
                     N_Vector z, sunrealtype gamma, sunrealtype delta, int lr,
                     void *ud)
{
    sun_state *s = ud;
    (void)t; (void)y; (void)fy; (void)delta; (void)lr;
    return drape_schur_solve(s->schur, s->K, gamma, N_VGetArrayPointer(r),
                             N_VGetArrayPointer(z));
}

/* Same signature as ARKLsJacTimesVecFn.  J v with the K, D of the last
 * Jacobian evaluation: the same (modified) Newton matrix the KLU path
 * factors, so both paths take the same Newton iterates up to the GMRES
 * tolerance. */
static int jtimes_cb(N_Vector v, N_Vector Jv, sunrealtype t, N_Vector y,
                     N_Vector fy, void *ud, N_Vector tmp)
{
    sun_state *s = ud;
    (void)t; (void)y; (void)fy; (void)tmp;
    if (!s->jac_valid) return 1;
    drape_schur_jtimes(s->schur, s->K, s->have_d ? s->D : NULL,
                       N_VGetArrayPointer(v), N_VGetArrayPointer(Jv));
    return 0;
}

/* ---- linsol schur-direct: a one-shot "iterative" linear solver --------------
 * SUNDIALS' iterative-solver interface with no iteration: Solve applies the
 * preconditioner once (z = P^-1 r, the Schur elimination), Setup calls the
 * preconditioner setup.  The Newton iteration then is the same modified
 * Newton iteration as with KLU, with S(gamma of the last setup). */
typedef struct oneshot_content {
    void *pdata;
    SUNPSetupFn pset;
    SUNPSolveFn psol;
    long last_flag;
} oneshot_content;

static SUNLinearSolver_Type oneshot_gettype(SUNLinearSolver LS)
{
    (void)LS;
    return SUNLINEARSOLVER_ITERATIVE;
}

static SUNLinearSolver_ID oneshot_getid(SUNLinearSolver LS)
{
    (void)LS;
    return SUNLINEARSOLVER_CUSTOM;
}

static int oneshot_setatimes(SUNLinearSolver LS, void *ad, SUNATimesFn at)
{
    (void)LS; (void)ad; (void)at;
    return SUNLS_SUCCESS;
}

static int oneshot_setprec(SUNLinearSolver LS, void *pd, SUNPSetupFn ps, SUNPSolveFn pv)
{
    oneshot_content *c = LS->content;
    c->pdata = pd;
    c->pset = ps;
    c->psol = pv;
    return SUNLS_SUCCESS;
}

static int oneshot_setscaling(SUNLinearSolver LS, N_Vector s1, N_Vector s2)
{
    (void)LS; (void)s1; (void)s2;
    return SUNLS_SUCCESS;
}

static int oneshot_setzeroguess(SUNLinearSolver LS, sunbooleantype z)
{
    (void)LS; (void)z;
    return SUNLS_SUCCESS;
}

static int oneshot_initialize(SUNLinearSolver LS)
{
    (void)LS;
    return SUNLS_SUCCESS;
}

static int oneshot_setup(SUNLinearSolver LS, SUNMatrix A)
{
    oneshot_content *c = LS->content;
    (void)A;
    int rc = c->pset ? c->pset(c->pdata) : 0;
    c->last_flag = rc == 0 ? SUNLS_SUCCESS : rc > 0 ? SUNLS_PSET_FAIL_REC : SUNLS_PSET_FAIL_UNREC;
    return (int)c->last_flag;
}

static int oneshot_solve(SUNLinearSolver LS, SUNMatrix A, N_Vector x, N_Vector b,
                         sunrealtype tol)
{
    oneshot_content *c = LS->content;
    (void)A;
    int rc = c->psol ? c->psol(c->pdata, b, x, tol, SUN_PREC_LEFT) : -1;
    c->last_flag = rc == 0 ? SUNLS_SUCCESS : rc > 0 ? SUNLS_PSOLVE_FAIL_REC : SUNLS_PSOLVE_FAIL_UNREC;
    return (int)c->last_flag;
}

static int oneshot_numiters(SUNLinearSolver LS)
{
    (void)LS;
    return 1;
}

static sunrealtype oneshot_resnorm(SUNLinearSolver LS)
{
    (void)LS;
    return 0.0;
}

static sunindextype oneshot_lastflag(SUNLinearSolver LS)
{
    return ((oneshot_content *)LS->content)->last_flag;
}

static int oneshot_free(SUNLinearSolver LS)
{
    if (!LS) return SUNLS_SUCCESS;
    drape_free(LS->content);
    LS->content = NULL;
    SUNLinSolFreeEmpty(LS);
    return SUNLS_SUCCESS;
}

static SUNLinearSolver oneshot_new(SUNContext ctx)
{
    SUNLinearSolver LS = SUNLinSolNewEmpty(ctx);
    if (!LS) return NULL;
    LS->content = drape_calloc(1, sizeof(oneshot_content));
    if (!LS->content) {
        SUNLinSolFreeEmpty(LS);
        return NULL;
    }
    LS->ops->gettype = oneshot_gettype;
    LS->ops->getid = oneshot_getid;
    LS->ops->setatimes = oneshot_setatimes;
    LS->ops->setpreconditioner = oneshot_setprec;
    LS->ops->setscalingvectors = oneshot_setscaling;
    LS->ops->setzeroguess = oneshot_setzeroguess;
    LS->ops->initialize = oneshot_initialize;
    LS->ops->setup = oneshot_setup;
    LS->ops->solve = oneshot_solve;
    LS->ops->numiters = oneshot_numiters;
    LS->ops->resnorm = oneshot_resnorm;
    LS->ops->lastflag = oneshot_lastflag;
    LS->ops->free = oneshot_free;
    return LS;
}

static void err_handler(int code, const char *module, const char *function,
                        char *msg, void *ud)
{
    sun_state *s = ud;
    (void)code; (void)module;
    snprintf(s->msg, sizeof s->msg, "%s: %s", function ? function : "?",
             msg ? msg : "");
}

/* ---- error messages ---------------------------------------------------------- */

enum { H_WORK, H_ACC, H_ERR, H_CONV, H_LS, H_RHS, H_OTHER };

static int category(sun_kind k, int flag)
{
    if (k == SK_CVODE) {
        switch (flag) {
        case CV_TOO_MUCH_WORK: return H_WORK;
        case CV_TOO_MUCH_ACC: return H_ACC;
        case CV_ERR_FAILURE: return H_ERR;
        case CV_CONV_FAILURE: case CV_NLS_FAIL: case CV_NLS_SETUP_FAIL: return H_CONV;
        case CV_LSETUP_FAIL: case CV_LSOLVE_FAIL: return H_LS;
        case CV_RHSFUNC_FAIL: case CV_FIRST_RHSFUNC_ERR: case CV_REPTD_RHSFUNC_ERR:
        case CV_UNREC_RHSFUNC_ERR: return H_RHS;
        default: return H_OTHER;
        }
    }
    switch (flag) {
    case ARK_TOO_MUCH_WORK: return H_WORK;
    case ARK_TOO_MUCH_ACC: return H_ACC;
    case ARK_ERR_FAILURE: return H_ERR;
    case ARK_CONV_FAILURE: case ARK_NLS_SETUP_FAIL: case ARK_NLS_OP_ERR: return H_CONV;
    case ARK_LSETUP_FAIL: case ARK_LSOLVE_FAIL: return H_LS;
    case ARK_RHSFUNC_FAIL: case ARK_FIRST_RHSFUNC_ERR: case ARK_REPTD_RHSFUNC_ERR:
    case ARK_UNREC_RHSFUNC_ERR: return H_RHS;
    default: return H_OTHER;
    }
}

static const char *hint(sun_kind k, int cat)
{
    switch (cat) {
    case H_WORK:
        if (k == SK_ERK)
            return "the step limit was reached: the problem is too stiff for an "
                   "explicit integrator; use arkode-dirk or cvode-bdf, loosen "
                   "rtol, or add damping";
        return "the step limit was reached: rtol is too tight for this run's "
               "length or the stiff modes are undamped; loosen rtol, raise "
               "--max-steps, add edge damping, or try another implicit "
               "integrator (arkode-dirk, cvode-bdf)";
    case H_ACC:
        return "the tolerance asks for more than double precision: loosen rtol/atol";
    case H_ERR:
        return "the error test failed repeatedly with a collapsing step: loosen "
               "rtol, add damping, or check the fabric's fits for kinks";
    case H_CONV:
        return "Newton's iteration did not converge even at small steps: check "
               "the fabric's stiffness values, add edge damping, or try another "
               "integrator";
    case H_LS:
        return "the sparse linear solve failed (singular Newton matrix): "
               "coincident particles or an extreme stiffness";
    case H_RHS:
        return "the model could not be evaluated (a hinge or shear corner folded "
               "back onto itself, or a non-finite force): add damping, tighten "
               "rtol, or check the fabric";
    default:
        return "internal solver error";
    }
}

static int fail(sun_state *s, int flag, double t, const char *during,
                drape_error *err)
{
    char *fname = s->kind == SK_CVODE  ? CVodeGetReturnFlagName(flag)
                  : s->kind == SK_ERK ? ERKStepGetReturnFlagName(flag)
                                      : ARKStepGetReturnFlagName(flag);
    drape_error_set(err, DRAPE_E_NUMERIC, NULL, 0, 0, NULL,
                    "%s failed at t = %.9g s%s%s: %s%s%s%s; hint: %s", s->name, t,
                    during ? " in " : "", during ? during : "",
                    fname ? fname : "unknown flag", s->msg[0] ? " (" : "",
                    s->msg, s->msg[0] ? ")" : "", hint(s->kind, category(s->kind, flag)));
    free(fname); /* malloc'd by SUNDIALS 6.x */
    return -1;
}

/* ---- alloc / free -------------------------------------------------------------- */

static void sun_free(void *st)
{
    sun_state *s = st;
    if (!s) return;
    if (s->mem) {
        if (s->kind == SK_CVODE) CVodeFree(&s->mem);
        else if (s->kind == SK_ERK) ERKStepFree(&s->mem);
        else ARKStepFree(&s->mem);
    }
    if (s->LS) SUNLinSolFree(s->LS);
    drape_schur_free(s->schur);
    drape_free(s->K);
    drape_free(s->D);
    drape_free(s->J);
    drape_free(s->jdiag);
    if (s->A) SUNMatDestroy(s->A);
    if (s->y) N_VDestroy(s->y);
    if (s->atol) N_VDestroy(s->atol);
    if (s->yd) N_VDestroy(s->yd);
    if (s->have_ctx) SUNContext_Free(&s->ctx);
    drape_free(s);
}

/* Run a SUNDIALS setter; on a negative flag record which and fail. */
#define TRY(call)                                                             \
    do {                                                                      \
        int f_ = (call);                                                      \
        if (f_ < 0) { flag = f_; what = #call; goto setup_failed; }           \
    } while (0)

static void *sun_alloc(sun_kind kind, const char *name, drape_ode *ode,
                       const drape_integrator_opts *o, double t0,
                       const double *y0, drape_error *err)
{
    sun_state *s = drape_calloc(1, sizeof *s);
    int flag = 0;
    const char *what = NULL;
    if (!s) goto nomem;
    s->kind = kind;
    s->name = name;
    s->ode = ode;
    s->parts_i = IMEX_IMPLICIT_PARTS & ode->parts;
    s->parts_e = ode->parts & ~IMEX_IMPLICIT_PARTS;
    s->max_steps = o->max_steps > 0 ? o->max_steps : DRAPE_INTEGRATOR_MAX_STEPS_DEFAULT;
    s->t_stop = o->t_stop;
    if (SUNContext_Create(NULL, &s->ctx) != 0) goto nomem;
    s->have_ctx = 1;
    sunindextype n = (sunindextype)ode->dim;
    s->y = N_VNew_Serial(n, s->ctx);
    s->atol = N_VNew_Serial(n, s->ctx);
    s->yd = N_VNew_Serial(n, s->ctx);
    if (!s->y || !s->atol || !s->yd) goto nomem;
    drape_sundials_install_kernels(s->y);
    drape_sundials_install_kernels(s->atol);
    drape_sundials_install_kernels(s->yd);
    memcpy(N_VGetArrayPointer(s->y), y0, sizeof(double) * (size_t)n);
    memcpy(N_VGetArrayPointer(s->atol), ode->atol, sizeof(double) * (size_t)n);

    if (kind != SK_ERK) {
        s->jparts = kind == SK_IMEX ? s->parts_i : ode->parts;
        s->have_d = (s->jparts & DRAPE_PARTS_DAMPING) != 0;
        s->linsol = o->linsol;
        if (s->linsol == DRAPE_LINSOL_AUTO)
            s->linsol = ode->nf3 >= DRAPE_LINSOL_SCHUR_MIN_NF3 ? DRAPE_LINSOL_SCHUR_DIRECT
                                                               : DRAPE_LINSOL_KLU;
        if (s->linsol != DRAPE_LINSOL_KLU && s->linsol != DRAPE_LINSOL_SCHUR &&
            s->linsol != DRAPE_LINSOL_SCHUR_DIRECT) {
            drape_error_set(err, DRAPE_E_INPUT, NULL, 0, 0, "solver.linear_solver",
                            "unknown linear solver %d (auto, klu, schur or schur-direct)",
                            o->linsol);
            sun_free(s);
            return NULL;
        }
    }
    if (kind != SK_ERK && s->linsol != DRAPE_LINSOL_KLU) {
        const drape_pattern *P = drape_model_pattern(ode->model);
        size_t nnz = (size_t)(P->nnz > 0 ? P->nnz : 1);
        s->K = drape_calloc(nnz, sizeof(double));
        s->D = drape_calloc(nnz, sizeof(double));
        if (!s->K || !s->D) goto nomem;
        s->schur = drape_schur_new(P, ode->inv_mass, err);
        if (!s->schur) {
            sun_free(s);
            return NULL;
        }
        s->LS = s->linsol == DRAPE_LINSOL_SCHUR
                    ? SUNLinSol_SPGMR(s->y, SUN_PREC_LEFT, SCHUR_MAXL, s->ctx)
                    : oneshot_new(s->ctx);
        if (!s->LS) goto nomem;
    } else if (kind != SK_ERK) {
        const drape_pattern *p = ode->pattern;
        s->A = SUNSparseMatrix(n, n, (sunindextype)p->nnz, CSC_MAT, s->ctx);
        if (!s->A) goto nomem;
        memcpy(SUNSparseMatrix_IndexPointers(s->A), p->colptr,
               sizeof(sunindextype) * (size_t)(p->n + 1));
        memcpy(SUNSparseMatrix_IndexValues(s->A), p->rowind,
               sizeof(sunindextype) * (size_t)p->nnz);
        memset(SUNSparseMatrix_Data(s->A), 0, sizeof(double) * (size_t)p->nnz);
        s->J = drape_calloc((size_t)(p->nnz > 0 ? p->nnz : 1), sizeof(double));
        s->jdiag = drape_malloc(sizeof(int64_t) * (size_t)(p->n > 0 ? p->n : 1));
        if (!s->J || !s->jdiag) goto nomem;
        for (int64_t j = 0; j < p->n; j++) {
            s->jdiag[j] = -1;
            for (int64_t k = p->colptr[j]; k < p->colptr[j + 1]; k++)
                if (p->rowind[k] == j) s->jdiag[j] = k;
            if (s->jdiag[j] < 0) {
                drape_error_set(err, DRAPE_E_INTERNAL, NULL, 0, 0, NULL,
                                "%s: the first-order pattern lacks diagonal entry %ld",
                                name, (long)j);
                sun_free(s);
                return NULL;
            }
        }
        SUNLinearSolver klu = SUNLinSol_KLU(s->y, s->A, s->ctx);
        if (!klu) goto nomem;
        /* AMD: never worse than the COLAMD default here (numerics.md 3.3). */
        if (SUNLinSol_KLUSetOrdering(klu, 0) != 0) {
            SUNLinSolFree(klu);
            goto nomem;
        }
        s->LS = kluwrap_new(klu, s);
        if (!s->LS) goto nomem;
    }

    switch (kind) {
    case SK_CVODE:
        s->mem = CVodeCreate(CV_BDF, s->ctx);
        if (!s->mem) goto nomem;
        TRY(CVodeSetErrHandlerFn(s->mem, err_handler, s));
        TRY(CVodeInit(s->mem, rhs_all, t0, s->y));
        TRY(CVodeSetUserData(s->mem, s));
        TRY(CVodeSVtolerances(s->mem, o->rtol, s->atol));
        TRY(CVodeSetMaxNumSteps(s->mem, s->max_steps));
        TRY(CVodeSetMaxOrd(s->mem, o->max_order > 0 ? o->max_order
                                                    : DRAPE_INTEGRATOR_MAX_ORDER_DEFAULT));
        TRY(CVodeSetLinearSolver(s->mem, s->LS, s->A));
        if (s->schur) {
            TRY(CVodeSetPreconditioner(s->mem, psetup_cb, psolve_cb));
            TRY(CVodeSetJacTimes(s->mem, NULL, jtimes_cb));
        } else {
            TRY(CVodeSetLinSysFn(s->mem, linsys_cv));
        }
        if (o->t_stop > 0.0) TRY(CVodeSetStopTime(s->mem, o->t_stop));
        if (o->h_init > 0.0) TRY(CVodeSetInitStep(s->mem, o->h_init));
        break;
    case SK_IMEX:
    case SK_DIRK:
        s->mem = kind == SK_IMEX ? ARKStepCreate(rhs_expl, rhs_impl, t0, s->y, s->ctx)
                                 : ARKStepCreate(NULL, rhs_all, t0, s->y, s->ctx);
        if (!s->mem) goto nomem;
        TRY(ARKStepSetErrHandlerFn(s->mem, err_handler, s));
        TRY(ARKStepSetUserData(s->mem, s));
        if (kind == SK_IMEX)
            TRY(ARKStepSetTableNum(s->mem, ARKODE_ARK436L2SA_DIRK_6_3_4,
                                   ARKODE_ARK436L2SA_ERK_6_3_4));
        else
            TRY(ARKStepSetTableNum(s->mem, ARKODE_ESDIRK436L2SA_6_3_4, ARKODE_ERK_NONE));
        TRY(ARKStepSVtolerances(s->mem, o->rtol, s->atol));
        TRY(ARKStepSetMaxNumSteps(s->mem, s->max_steps));
        TRY(ARKStepSetInterpolantType(s->mem, ARK_INTERP_LAGRANGE));
        TRY(ARKStepSetLinearSolver(s->mem, s->LS, s->A));
        if (s->schur) {
            TRY(ARKStepSetPreconditioner(s->mem, psetup_cb, psolve_cb));
            TRY(ARKStepSetJacTimes(s->mem, NULL, jtimes_cb));
        } else {
            TRY(ARKStepSetLinSysFn(s->mem, linsys_ark));
        }
        TRY(ARKStepSetPredictorMethod(s->mem, ARK_IMPLICIT_PREDICTOR));
        /* arkode-dirk: f_I at a solved stage from Newton's correction,
         * (z_i - a_i) / gamma, instead of one more evaluation: 27-31 % fewer
         * right-hand sides, same error on the hang test scene.  Not for
         * arkode-imex, whose error grew 20x with it (docs/integrators.md,
         * "Options and defaults"). */
        if (kind == SK_DIRK) TRY(ARKStepSetDeduceImplicitRhs(s->mem, SUNTRUE));
        /* arkode-imex evaluates f_I again at each solved stage, so the
         * Newton error of the stage (allowed up to 0.1 of the error test by
         * default) comes back multiplied by the stiffness of the stretch:
         * on a limp folded strip the stretch energy grew 1e4-fold and the
         * total energy rose; at k = 1e6 N/m the steps shrank 64-fold.
         * Newton to 0.01 of the error test removes both, with the same
         * error at equal rtol on the hang scene (docs/integrators.md,
         * "arkode-imex and the Newton tolerance"). */
        if (kind == SK_IMEX) TRY(ARKStepSetNonlinConvCoef(s->mem, IMEX_NLS_CONV_COEF));
        if (o->t_stop > 0.0) TRY(ARKStepSetStopTime(s->mem, o->t_stop));
        if (o->h_init > 0.0) TRY(ARKStepSetInitStep(s->mem, o->h_init));
        break;
    case SK_ERK:
        s->mem = ERKStepCreate(rhs_all, t0, s->y, s->ctx);
        if (!s->mem) goto nomem;
        TRY(ERKStepSetErrHandlerFn(s->mem, err_handler, s));
        TRY(ERKStepSetUserData(s->mem, s));
        TRY(ERKStepSetTableNum(s->mem, ARKODE_DORMAND_PRINCE_7_4_5));
        TRY(ERKStepSVtolerances(s->mem, o->rtol, s->atol));
        TRY(ERKStepSetMaxNumSteps(s->mem, s->max_steps));
        if (o->t_stop > 0.0) TRY(ERKStepSetStopTime(s->mem, o->t_stop));
        if (o->h_init > 0.0) TRY(ERKStepSetInitStep(s->mem, o->h_init));
        break;
    }
    return s;

nomem:
    drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL,
                    "%s: out of memory setting up %ld unknowns", name, ode->dim);
    sun_free(s);
    return NULL;
setup_failed:
    fail(s, flag, t0, what, err);
    sun_free(s);
    return NULL;
}

static void *cvode_alloc(drape_ode *ode, const drape_integrator_opts *o,
                         double t0, const double *y0, drape_error *err)
{
    return sun_alloc(SK_CVODE, "cvode-bdf", ode, o, t0, y0, err);
}

static void *imex_alloc(drape_ode *ode, const drape_integrator_opts *o,
                        double t0, const double *y0, drape_error *err)
{
    return sun_alloc(SK_IMEX, "arkode-imex", ode, o, t0, y0, err);
}

static void *dirk_alloc(drape_ode *ode, const drape_integrator_opts *o,
                        double t0, const double *y0, drape_error *err)
{
    return sun_alloc(SK_DIRK, "arkode-dirk", ode, o, t0, y0, err);
}

static void *erk_alloc(drape_ode *ode, const drape_integrator_opts *o,
                       double t0, const double *y0, drape_error *err)
{
    return sun_alloc(SK_ERK, "arkode-erk", ode, o, t0, y0, err);
}

/* ---- operations ------------------------------------------------------------------ */

static int sun_reinit(void *st, double t0, const double *y0, drape_error *err)
{
    sun_state *s = st;
    int flag = 0;
    s->msg[0] = 0;
    s->jac_valid = 0;
    s->gamma_a = 0.0;
    s->n_reuse = 0;
    memcpy(N_VGetArrayPointer(s->y), y0, sizeof(double) * (size_t)s->ode->dim);
    switch (s->kind) {
    case SK_CVODE:
        flag = CVodeReInit(s->mem, t0, s->y);
        if (flag >= 0 && s->t_stop > 0.0) flag = CVodeSetStopTime(s->mem, s->t_stop);
        break;
    case SK_IMEX:
        flag = ARKStepReInit(s->mem, rhs_expl, rhs_impl, t0, s->y);
        if (flag >= 0 && s->t_stop > 0.0) flag = ARKStepSetStopTime(s->mem, s->t_stop);
        break;
    case SK_DIRK:
        flag = ARKStepReInit(s->mem, NULL, rhs_all, t0, s->y);
        if (flag >= 0 && s->t_stop > 0.0) flag = ARKStepSetStopTime(s->mem, s->t_stop);
        break;
    case SK_ERK:
        flag = ERKStepReInit(s->mem, rhs_all, t0, s->y);
        if (flag >= 0 && s->t_stop > 0.0) flag = ERKStepSetStopTime(s->mem, s->t_stop);
        break;
    }
    if (flag < 0) return fail(s, flag, t0, "restart", err);
    return 0;
}

static int sun_step_to(void *st, double t_out, drape_step_mode mode, double *t,
                       double *y, drape_error *err)
{
    sun_state *s = st;
    sunrealtype tret = *t;
    int flag = 0, one = mode == DRAPE_STEP_ONE;
    s->msg[0] = 0;
    drape_error_clear(&s->serr);
    switch (s->kind) {
    case SK_CVODE:
        flag = CVode(s->mem, t_out, s->y, &tret, one ? CV_ONE_STEP : CV_NORMAL);
        break;
    case SK_IMEX:
    case SK_DIRK:
        flag = ARKStepEvolve(s->mem, t_out, s->y, &tret, one ? ARK_ONE_STEP : ARK_NORMAL);
        break;
    case SK_ERK:
        flag = ERKStepEvolve(s->mem, t_out, s->y, &tret, one ? ARK_ONE_STEP : ARK_NORMAL);
        break;
    }
    *t = tret;
    memcpy(y, N_VGetArrayPointer(s->y), sizeof(double) * (size_t)s->ode->dim);
    if (flag < 0 && s->serr.kind != DRAPE_OK) { /* out of memory in CHOLMOD */
        *err = s->serr;
        return -1;
    }
    if (flag < 0) return fail(s, flag, tret, NULL, err);
    return 0;
}

static int sun_get_state(void *st, double t, double *y, drape_error *err)
{
    sun_state *s = st;
    int flag = 0;
    s->msg[0] = 0;
    switch (s->kind) {
    case SK_CVODE: flag = CVodeGetDky(s->mem, t, 0, s->yd); break;
    case SK_IMEX:
    case SK_DIRK: flag = ARKStepGetDky(s->mem, t, 0, s->yd); break;
    case SK_ERK: flag = ERKStepGetDky(s->mem, t, 0, s->yd); break;
    }
    if (flag < 0) return fail(s, flag, t, "dense output", err);
    memcpy(y, N_VGetArrayPointer(s->yd), sizeof(double) * (size_t)s->ode->dim);
    return 0;
}

static void sun_stats(const void *st, drape_integrator_stats *r)
{
    const sun_state *s = st;
    void *m = s->mem;
    long v;
    memset(r, 0, sizeof *r);
    r->switches = -1;
    r->energy_rescales = -1;
    r->rhs_evals = s->ode->n_rhs;
    r->jac_evals = s->ode->n_jac;
    r->linsol = s->linsol;
    switch (s->kind) {
    case SK_CVODE:
        if (CVodeGetNumSteps(m, &v) == 0) r->steps = v;
        if (CVodeGetNumLinSolvSetups(m, &v) == 0) r->lin_setups = v;
        r->lin_factors = r->lin_setups - s->n_reuse;
        if (CVodeGetNumNonlinSolvIters(m, &v) == 0) r->nonlin_iters = v;
        if (CVodeGetNumErrTestFails(m, &v) == 0) r->err_test_fails = v;
        if (CVodeGetNumStepSolveFails(m, &v) == 0) r->conv_fails = v;
        if (s->schur && CVodeGetNumLinIters(m, &v) == 0) r->lin_iters = v;
        break;
    case SK_IMEX:
    case SK_DIRK:
        if (ARKStepGetNumSteps(m, &v) == 0) r->steps = v;
        if (ARKStepGetNumLinSolvSetups(m, &v) == 0) r->lin_setups = v;
        r->lin_factors = r->lin_setups - s->n_reuse;
        if (ARKStepGetNumNonlinSolvIters(m, &v) == 0) r->nonlin_iters = v;
        if (ARKStepGetNumErrTestFails(m, &v) == 0) r->err_test_fails = v;
        if (ARKStepGetNumStepSolveFails(m, &v) == 0) r->conv_fails = v;
        if (s->schur && ARKStepGetNumLinIters(m, &v) == 0) r->lin_iters = v;
        break;
    case SK_ERK:
        if (ERKStepGetNumSteps(m, &v) == 0) r->steps = v;
        if (ERKStepGetNumErrTestFails(m, &v) == 0) r->err_test_fails = v;
        break;
    }
}

const drape_integrator_type drape_integrator_cvode_bdf = {
    "cvode-bdf", "CVODE BDF (max order 2 by default), KLU on the exact sparse Jacobian",
    cvode_alloc, sun_reinit, sun_step_to, sun_get_state, sun_stats, sun_free};

const drape_integrator_type drape_integrator_arkode_imex = {
    "arkode-imex",
    "ARKStep ARK436L2SA IMEX: implicit x'=v, stretch, edge dashpots, shear; explicit bend, gravity, air",
    imex_alloc, sun_reinit, sun_step_to, sun_get_state, sun_stats, sun_free};

const drape_integrator_type drape_integrator_arkode_dirk = {
    "arkode-dirk", "ARKStep ESDIRK436L2SA fully implicit (L-stable), KLU on the exact Jacobian",
    dirk_alloc, sun_reinit, sun_step_to, sun_get_state, sun_stats, sun_free};

const drape_integrator_type drape_integrator_arkode_erk = {
    "arkode-erk", "ERKStep Dormand-Prince 5(4), explicit adaptive",
    erk_alloc, sun_reinit, sun_step_to, sun_get_state, sun_stats, sun_free};
