/* integrator_sundials.c: the SUNDIALS 6.4.1 backends cvode-bdf, arkode-imex,
 * arkode-dirk and arkode-erk.
 *
 * Problem (integrator.h, MODEL.md 4): y' = F(y), y = [x_free; v_free],
 *     F(y) = [ v ; M^-1 f(x, v) ],   J = [ 0 I ; M^-1 K  M^-1 D ].
 *
 * cvode-bdf   CVODE, BDF orders 1..max_order (default 2: BDF orders 3-5
 *             are only A(alpha)-stable and lose on oscillatory stiffness,
 *             numerics.md 1.4 and 6.6), Newton with KLU on the exact
 *             sparse J.
 * arkode-imex ARKStep additive RK ARK4(3)6L[2]SA (Kennedy & Carpenter
 *             2003), implicit part
 *                 F_I = [ v ; M^-1 (f_stretch + f_edge + f_shear) ]
 *             and explicit part F_E = [ 0 ; M^-1 (f_bend + f_gravity +
 *             f_air) ] (numerics.md 3.4: x' = v belongs in F_I); KLU on
 *             dF_I/dy; Lagrange interpolant for dense output (stiff);
 *             stage predictor = maximum-order interpolant (see below).
 * arkode-dirk ARKStep fully implicit, ESDIRK4(3)6L[2]SA (Kennedy & Carpenter
 *             2016), L-stable and stiffly accurate; KLU on the exact J.
 * arkode-erk  ERKStep, Dormand-Prince 5(4) (explicit baseline).
 *
 * SUNDIALS traps handled here (numerics.md section 6): the first-order
 * pattern stores the diagonal (SUNMatScaleAddI_Sparse is O(N^2) otherwise);
 * the Jacobian callback receives SUNDIALS' clone of the matrix, whose index
 * arrays are not set, so it writes colptr/rowind every call (same pattern
 * every call, so KLU's symbolic analysis stays valid); sparse matrices have
 * no difference-quotient Jacobian, so the callback is mandatory; the
 * default mxstep of 500 is raised; SUNDIALS' own error printing is replaced
 * by a handler that keeps the last message for drape_error.
 *
 * References: Hindmarsh et al., "SUNDIALS: Suite of nonlinear and
 * differential/algebraic equation solvers", ACM TOMS 31 (2005); Reynolds et
 * al., ARKODE user guide v5.4.1; Kennedy & Carpenter, Appl. Numer. Math. 44
 * (2003) and NASA TM-2016-219173; Dormand & Prince, J. Comput. Appl. Math.
 * 6 (1980).
 */
#include "drape/integrator.h"

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
#include <sunmatrix/sunmatrix_sparse.h>

#include "drape/alloc.h"

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
#define IMEX_IMPLICIT_PARTS (DRAPE_PART_STRETCH | DRAPE_PART_EDGE | DRAPE_PART_SHEAR)

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

static int jac_cb(sunrealtype t, N_Vector y, N_Vector fy, SUNMatrix J, void *ud,
                  N_Vector t1, N_Vector t2, N_Vector t3)
{
    sun_state *s = ud;
    const drape_pattern *p = s->ode->pattern;
    (void)t; (void)fy; (void)t1; (void)t2; (void)t3;
    if (SUNSparseMatrix_NNZ(J) < p->nnz) return -1;
    memcpy(SUNSparseMatrix_IndexPointers(J), p->colptr,
           sizeof(sunindextype) * (size_t)(p->n + 1));
    memcpy(SUNSparseMatrix_IndexValues(J), p->rowind,
           sizeof(sunindextype) * (size_t)p->nnz);
    unsigned parts = s->kind == SK_IMEX ? s->parts_i : s->ode->parts;
    return drape_ode_jacobian(s->ode, parts, 1, N_VGetArrayPointer(y),
                              SUNSparseMatrix_Data(J));
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

static const char *hint(int cat)
{
    switch (cat) {
    case H_WORK:
        return "the step limit was reached: the problem is too stiff for this "
               "integrator or rtol too tight; use cvode-bdf or arkode-dirk, "
               "loosen rtol, or add damping";
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
                    s->msg, s->msg[0] ? ")" : "", hint(category(s->kind, flag)));
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
    memcpy(N_VGetArrayPointer(s->y), y0, sizeof(double) * (size_t)n);
    memcpy(N_VGetArrayPointer(s->atol), ode->atol, sizeof(double) * (size_t)n);

    if (kind != SK_ERK) {
        const drape_pattern *p = ode->pattern;
        s->A = SUNSparseMatrix(n, n, (sunindextype)p->nnz, CSC_MAT, s->ctx);
        if (!s->A) goto nomem;
        memcpy(SUNSparseMatrix_IndexPointers(s->A), p->colptr,
               sizeof(sunindextype) * (size_t)(p->n + 1));
        memcpy(SUNSparseMatrix_IndexValues(s->A), p->rowind,
               sizeof(sunindextype) * (size_t)p->nnz);
        memset(SUNSparseMatrix_Data(s->A), 0, sizeof(double) * (size_t)p->nnz);
        s->LS = SUNLinSol_KLU(s->y, s->A, s->ctx);
        if (!s->LS) goto nomem;
        /* AMD: never worse than the COLAMD default here (numerics.md 3.3). */
        TRY(SUNLinSol_KLUSetOrdering(s->LS, 0));
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
        TRY(CVodeSetJacFn(s->mem, jac_cb));
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
        TRY(ARKStepSetJacFn(s->mem, jac_cb));
        TRY(ARKStepSetPredictorMethod(s->mem, ARK_IMPLICIT_PREDICTOR));
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
    r->rhs_evals = s->ode->n_rhs;
    r->jac_evals = s->ode->n_jac;
    switch (s->kind) {
    case SK_CVODE:
        if (CVodeGetNumSteps(m, &v) == 0) r->steps = v;
        if (CVodeGetNumLinSolvSetups(m, &v) == 0) r->lin_setups = v;
        if (CVodeGetNumNonlinSolvIters(m, &v) == 0) r->nonlin_iters = v;
        if (CVodeGetNumErrTestFails(m, &v) == 0) r->err_test_fails = v;
        if (CVodeGetNumStepSolveFails(m, &v) == 0) r->conv_fails = v;
        break;
    case SK_IMEX:
    case SK_DIRK:
        if (ARKStepGetNumSteps(m, &v) == 0) r->steps = v;
        if (ARKStepGetNumLinSolvSetups(m, &v) == 0) r->lin_setups = v;
        if (ARKStepGetNumNonlinSolvIters(m, &v) == 0) r->nonlin_iters = v;
        if (ARKStepGetNumErrTestFails(m, &v) == 0) r->err_test_fails = v;
        if (ARKStepGetNumStepSolveFails(m, &v) == 0) r->conv_fails = v;
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
