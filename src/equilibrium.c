/* equilibrium.c: the static drape by energy minimisation (equilibrium.h;
 * numerics.md 3.7; docs/model.md 3, 4, 6).
 *
 * Unknowns: the 3 nf free coordinates y.  E(y) = E_pot (docs/model.md 3: stretch,
 * bend, shear, gravity), F = -grad E = the conservative force (docs/model.md 4),
 * H = Hess E = -K (K = dF/dy from drape_model_jacobian, exact and
 * symmetric; unclamped: compressed springs, concave fit pieces and buckling
 * make it indefinite away from a minimum), M = lumped masses (diagonal).
 *
 * (E1) pseudo-transient continuation (PTC): a backward Euler step of
 *      M y'' = F started from rest, velocity discarded after the step
 *      (fully damped implicit dynamics), linearised:
 *          (M / dt^2 + Hc) dy = F(y),   y <- y + alpha dy
 *      Hc = H with compressed springs clamped (E8) when the fabric's k is
 *      given, else H.  If M/dt^2 + Hc is not positive definite (LL^T
 *      fails), dt <- dt/2.  For small dt the step is dt^2 M^-1 F (the
 *      physical fall); as dt grows it becomes Newton's method.  lambda =
 *      1/dt^2 is a Levenberg-Marquardt shift with the mass matrix as
 *      metric, so the iteration cannot jump across the basin the way
 *      undamped Newton from the flat state can (numerics 3.7 pitfall 1).
 * (E2) switched evolution relaxation (Mulder & van Leer 1985; Kelley &
 *      Keyes 1998) on the mass-weighted residual r = ||M^-1 F||_2, after a
 *      full step (alpha = 1):
 *          dt_{k+1} = dt_k * clamp(r_{k-1} / r_k, g_min, g_max)
 *      g_min > 1 keeps dt growing while the residual is flat (the cloth is
 *      still falling: gravity unbalanced); after a shortened step
 *      dt_{k+1} = dt_k sqrt(alpha) (the step of a small dt is ~ dt^2).
 * (E3) line search: Armijo, E(y + alpha dy) <= E(y) - c alpha F.dy, alpha
 *      = 1, 1/2, ... (DRAPE_EQ_LS_PTC halvings in PTC, DRAPE_EQ_LS_MAX in
 *      Newton).  dy is a descent direction whenever the matrix is positive
 *      definite.  Once dt > dt_newton: Newton, H dy = F with the exact H;
 *      if H is not positive definite, Hc (modified Newton, kept for
 *      DRAPE_EQ_EXACT_RETRY iterations before H is tried again); if neither
 *      factorises or the line search fails, back to PTC at dt_newton/4.
 * (E4) convergence: |F_i| <= tol * w_i for every free particle i
 *      (w_i = m_i g, the particle's weight, or force_ref).
 * (E5) eps_E = DRAPE_EQ_EPS_E * sum of |energy terms|: E is a sum of
 *      O(n) terms and its rounding error is about that big; a step whose
 *      energy change is within it is accepted only if it lowers
 *      ||M^-1 F||.  A full Newton step that changes E by less than eps_E
 *      without lowering the residual means the roundoff floor: stop
 *      (status stalled).
 * (E6) certification: LL^T of the exact H at the solution (no shift, no
 *      clamping).  Success <=> H positive definite <=> strict local
 *      minimum.  min pivot d_min = min_i L_ii^2 (N/m): every pivot of a
 *      symmetric positive definite matrix is >= lambda_min(H), so d_min is
 *      an upper bound on lambda_min, not a lower one.  The physical margin
 *      is the lowest natural frequency omega_min^2 = lambda_min(M^-1 H),
 *      from inverse iteration v <- H^-1 M v with the Rayleigh quotient
 *          rho(v) = v^T M u / u^T M u,  u = H^-1 M v
 *      (= u^T H u / u^T M u, an upper bound on lambda_min).
 * (E8) clamping (Choi & Ko 2002; numerics 3.2): a spring of stiffness k w
 *      shorter than sigma has the negative transverse stiffness
 *      k w (1 - sigma/l)(I - u u^T); Hc drops it.  Compressed springs are
 *      everywhere in a drape (the hem must shorten to fall), and their
 *      negative curvature otherwise forces lambda >> the slow modes'
 *      stiffness: measured 234 -> 88 iterations on the Cusick scene.
 * (E9) optional damped dynamics before (E1): the fall, equilibrium_fall.c.
 *
 * CHOLMOD: the matrices are formed in the model's CSC pattern (full, both
 * triangles, diagonal stored), of which the lower triangle is read.
 * cholmod_l_analyze finds the fill-reducing order once (a supernodal
 * LL^T factor with CHOLMOD's own amalgamation); the lower triangle that
 * CHOLMOD factorises is laid out in that order once (work_order), so
 * that cholmod_l_factorize (numeric only, per iteration) need not permute
 * and transpose it; cholmod_l_solve2 with its
 * workspaces kept.  Nothing is allocated inside the loop but what
 * CHOLMOD's factorisation allocates itself.
 *
 * References: C. T. Kelley and D. E. Keyes, "Convergence analysis of
 * pseudo-transient continuation", SIAM J. Numer. Anal. 35 (1998) 508-523;
 * W. A. Mulder and B. van Leer, J. Comput. Phys. 59 (1985) 232-246 (SER);
 * J. Nocedal and S. J. Wright, Numerical Optimization, 2nd ed. (2006),
 * sections 3.1-3.4 (line search, Hessian modification);
 * Y. Chen, T. A. Davis, W. W. Hager, S. Rajamanickam, "Algorithm 887:
 * CHOLMOD", ACM TOMS 35 (2008); numerics.md 3.2, 3.3, 3.7.
 */
#include "drape/equilibrium.h"

#include <float.h>
#include <math.h>
#include <string.h>
#include <time.h>

#include <cholmod.h>

#include "drape/alloc.h"
#include "equilibrium_impl.h"

/* (E5): energy noise, in units of the sum of |terms|. */
#define DRAPE_EQ_EPS_E (1e3 * DBL_EPSILON)
/* (E3): line-search halvings before a step is refused: Newton (then PTC
 * takes over), PTC (then dt is halved), and Armijo's constant. */
#define DRAPE_EQ_LS_MAX 8
#define DRAPE_EQ_LS_PTC 2
#define DRAPE_EQ_ARMIJO 1e-4
/* (E3): Newton iterations that use Hc after the exact H failed to
 * factorise, before the exact H is tried again. */
#define DRAPE_EQ_EXACT_RETRY 3
/* (E1): dt below dt0 times this means the iteration has collapsed. */
#define DRAPE_EQ_DT_COLLAPSE 1e-8
/* (E6): inverse iteration stops when rho changes by less than this. */
#define DRAPE_EQ_EIG_RTOL 1e-8

/* CHOLMOD factorises supernodally at every size, with its own default
 * amalgamation (nrelax 4, 16, 48; zrelax 0.8, 0.1, 0.05).  drape's
 * executable runs CHOLMOD's OpenMP regions in the calling thread (main.c,
 * GOMP_parallel), so a supernode costs no futex call, and coarser
 * supernodes (nrelax 8, 32, 128; zrelax 0.5, 0.2) or a simplicial
 * factorisation of small systems cost more in extra zeros than they save:
 * CPU per factorisation of the fall, the mean over a specimen (seed 1),
 * coarse / default settings, three runs interleaved (docs/performance.md,
 * "The fall's factorisation with CHOLMOD's own supernodes"): Cusick 3 cm (156 unknowns) 0.042 / 0.028 ms, 2 cm (324)
 * 0.130-0.131 / 0.074-0.079 ms, 1 cm (1368) 0.62-0.64 / 0.50-0.54 ms,
 * table 2 cm (1800) 0.99-1.02 / 0.82-0.84 ms, table 1 cm 7.7-9.4 /
 * 5.9-8.2 ms. */
#define PARTS_POT (DRAPE_PART_STRETCH | DRAPE_PART_BEND | DRAPE_PART_SHEAR | \
                   DRAPE_PART_GRAVITY)

void drape_equilibrium_opts_default(drape_equilibrium_opts *o)
{
    memset(o, 0, sizeof *o);
    o->tol = 1e-8;
    o->max_iters = 500;
    o->dt0 = 0.0;
    o->dt_growth_max = 4.0;
    o->dt_growth_min = 1.5;
    o->dt_newton = 0.0;
    o->certify = 1;
    o->eig_iters = 40;
    o->force_ref = 0.0;
    o->trace = NULL;
    o->trace_ctx = NULL;
    o->stop = NULL;
}

void drape_equilibrium_opts_from_fabric(drape_equilibrium_opts *o, const drape_fabric *f)
{
    drape_equilibrium_opts_default(o);
    o->clamp_k[DRAPE_WEFT] = f->k[DRAPE_WEFT];
    o->clamp_k[DRAPE_WARP] = f->k[DRAPE_WARP];
}

const char *drape_equilibrium_status_name(drape_equilibrium_status s)
{
    switch (s) {
    case DRAPE_EQ_CONVERGED: return "converged";
    case DRAPE_EQ_MAX_ITERS: return "max_iters";
    case DRAPE_EQ_STALLED: return "stalled";
    case DRAPE_EQ_INTERRUPTED: return "interrupted";
    case DRAPE_EQ_DYN_ONLY: return "dyn_only";
    }
    return "stalled";
}

void drape_equilibrium_result_free(drape_equilibrium_result *r)
{
    if (!r) return;
    drape_free(r->x);
    r->x = NULL;
}

/* ------------------------------------------------------------ workspace */


static double clock_s(clockid_t id)
{
    struct timespec ts;
    clock_gettime(id, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double energy_sum(const drape_energies *E)
{
    return E->stretch + E->bend + E->shear + E->gravity;
}

static double energy_abs(const drape_energies *E)
{
    return fabs(E->stretch) + fabs(E->bend) + fabs(E->shear) + fabs(E->gravity);
}

/* E_pot at x; 1 if the model cannot evaluate it (folded) or it is not
 * finite. */
static int eval_energy(eq_work *w, const double *x, drape_energies *E)
{
    w->r->energy_evals++;
    if (drape_model_energy(w->m, x, E) != 0) return 1;
    return isfinite(energy_sum(E)) ? 0 : 1;
}

static int eval_forces(eq_work *w, const double *x, double *f)
{
    w->r->force_evals++;
    return drape_model_forces(w->m, w->parts, x, NULL, f) != 0;
}

/* max_i |F_i| / w_i over free particles. */
static double force_rel(const eq_work *w, const double *f)
{
    double mx = 0.0;
    for (int p = 0; p < w->nf; p++) {
        const double *fi = f + 3 * (long)w->L->free_to_id[p];
        double a = sqrt(fi[0] * fi[0] + fi[1] * fi[1] + fi[2] * fi[2]) / w->wref[p];
        if (!(a <= mx)) mx = a; /* NaN propagates */
    }
    return mx;
}

/* ||M^-1 F||_2 over free coordinates (E2). */
static double accel_norm(const eq_work *w, const double *f)
{
    double s = 0.0;
    for (int p = 0; p < w->nf; p++) {
        const double *fi = f + 3 * (long)w->L->free_to_id[p];
        double im = 1.0 / w->mrow[3 * p];
        s += (fi[0] * fi[0] + fi[1] * fi[1] + fi[2] * fi[2]) * im * im;
    }
    return sqrt(s);
}

/* A = -(K + Kc) + lambda M, Kc only if clamp (the lower triangle is what
 * CHOLMOD reads). */
static void assemble(eq_work *w, double lambda, int clamp)
{
    double *ax = w->ax;
    if (clamp && w->Kc)
        for (long k = 0; k < w->pat->nnz; k++) ax[k] = -w->K[k] - w->Kc[k];
    else
        for (long k = 0; k < w->pat->nnz; k++) ax[k] = -w->K[k];
    if (lambda > 0.0)
        for (long j = 0; j < w->N; j++) ax[w->dpos[j]] += lambda * w->mrow[j];
}

/* Numeric factorisation of A.  1: positive definite, 0: not, -1: error. */
int eq_factorize(eq_work *w, drape_error *err)
{
    w->r->factorizations++;
    double *apx = w->A->x;
    const long *src = w->asrc;
    long anz = ((const long *)w->A->p)[w->N];
    for (long k = 0; k < anz; k++) apx[k] = w->ax[src[k]];
    int ok = cholmod_l_factorize(w->A, w->LF, &w->c);
    if (w->c.status == CHOLMOD_NOT_POSDEF) return 0;
    if (w->c.status == CHOLMOD_OUT_OF_MEMORY) { /* not the matrix's fault */
        drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL,
                        "out of memory in the equilibrium solver's factorisation "
                        "(%ld unknowns)", w->N);
        return -1;
    }
    if (!ok || w->c.status < CHOLMOD_OK) {
        drape_error_set(err, DRAPE_E_NUMERIC, NULL, 0, 0, NULL,
                        "equilibrium: CHOLMOD factorisation failed (status %d)",
                        w->c.status);
        return -1;
    }
    /* a supernodal factor is LL^T: a negative pivot stops it */
    return w->LF->minor == (size_t)w->N ? 1 : 0;
}

/* dy = A^-1 rhs (N numbers). */
int eq_solve(eq_work *w, const double *rhs, double *out, drape_error *err)
{
    double *b = w->B->x;
    for (long k = 0; k < w->N; k++) b[k] = rhs[w->perm[k]];
    if (!cholmod_l_solve2(CHOLMOD_A, w->LF, w->B, NULL, &w->X, NULL, &w->Y, &w->E,
                          &w->c)) {
        if (w->c.status == CHOLMOD_OUT_OF_MEMORY)
            return drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL,
                                   "out of memory in the equilibrium solver's solve "
                                   "(%ld unknowns)", w->N);
        return drape_error_set(err, DRAPE_E_NUMERIC, NULL, 0, 0, NULL,
                               "equilibrium: CHOLMOD solve failed (status %d)",
                               w->c.status);
    }
    const double *xs = w->X->x;
    for (long k = 0; k < w->N; k++) out[w->perm[k]] = xs[k];
    return 0;
}

/* Free coordinates of a full force array into rhs (N). */
static void gather(const eq_work *w, const double *full, double *free_part)
{
    for (int p = 0; p < w->nf; p++) {
        const double *s = full + 3 * (long)w->L->free_to_id[p];
        free_part[3 * p] = s[0];
        free_part[3 * p + 1] = s[1];
        free_part[3 * p + 2] = s[2];
    }
}

/* xt = x + alpha dy on free particles (fixed ones copied); returns the
 * largest particle displacement. */
static double trial_point(const eq_work *w, const double *x, double alpha,
                          double *xt)
{
    double mx = 0.0;
    memcpy(xt, x, sizeof(double) * 3 * (size_t)w->L->n);
    for (int p = 0; p < w->nf; p++) {
        double *t = xt + 3 * (long)w->L->free_to_id[p];
        double d2 = 0.0;
        for (int c = 0; c < 3; c++) {
            double d = alpha * w->dy[3 * p + c];
            t[c] += d;
            d2 += d * d;
        }
        if (d2 > mx) mx = d2;
    }
    return sqrt(mx);
}

/* Smallest pivot L_ii^2 of the supernodal LL^T factor. */
static double min_pivot(const cholmod_factor *F)
{
    double mn = INFINITY;
    const double *x = F->x;
    const long *super = F->super, *pi = F->pi, *px = F->px;
    for (size_t s = 0; s < F->nsuper; s++) {
        long k1 = super[s], k2 = super[s + 1];
        long nsrow = pi[s + 1] - pi[s];
        for (long j = 0; j < k2 - k1; j++) {
            double d = x[px[s] + j * nsrow + j];
            d = d * d;
            if (d < mn) mn = d;
        }
    }
    return mn;
}

/* Lowest eigenvalue of H v = lambda M v by inverse iteration with the
 * factor of H in w->LF (E6).  Returns the Rayleigh quotient. */
static int lowest_mode(eq_work *w, int iters, double *lam, drape_error *err)
{
    long N = w->N;
    /* deterministic start with every component present (no symmetry) */
    unsigned long s = 88172645463325252ul;
    for (long j = 0; j < N; j++) {
        s ^= s << 13; s ^= s >> 7; s ^= s << 17;
        w->v[j] = (double)(s % 2000001ul) / 1e6 - 1.0 + 1e-3;
    }
    double rho = NAN, prev = NAN;
    for (int it = 0; it < iters; it++) {
        for (long j = 0; j < N; j++) w->u[j] = w->mrow[j] * w->v[j];
        if (eq_solve(w, w->u, w->u, err) != 0) return -1;
        double num = 0.0, den = 0.0;
        for (long j = 0; j < N; j++) {
            num += w->v[j] * w->mrow[j] * w->u[j];
            den += w->u[j] * w->mrow[j] * w->u[j];
        }
        if (!(den > 0.0)) break;
        rho = num / den;
        double sc = 1.0 / sqrt(den);
        for (long j = 0; j < N; j++) w->v[j] = w->u[j] * sc;
        if (it > 0 && fabs(rho - prev) <= DRAPE_EQ_EIG_RTOL * fabs(rho)) break;
        prev = rho;
    }
    *lam = rho;
    return 0;
}

/* The slot of entry (i, j) of the model's symmetric pattern (slot k) or of
 * its mirror (j, i), whichever is in the lower triangle (i >= j): the
 * triangle that the matrices are read from, as before CHOLMOD's input was
 * laid out in its own order (the two agree where the model's matrix is
 * symmetric to the last bit). */
static int64_t lower_slot(const drape_pattern *P, int64_t i, int64_t j, int64_t k)
{
    if (i >= j) return k;
    for (int64_t q = P->colptr[i]; q < P->colptr[i + 1]; q++)
        if (P->rowind[q] == j) return q;
    return k; /* not reached: the pattern is symmetric */
}

/* CHOLMOD's order for the model's pattern, and the matrix it factorises.
 * cholmod_l_factorize transposes a matrix that it must permute (twice for
 * a lower triangle, supernodal), every call: measured 10.6 % of the CPU
 * of one default specimen (perf, docs/performance.md).  So the fill-reducing order is
 * found once (cholmod_l_analyze of the pattern: AMD and the elimination
 * tree's postorder), the triangle that CHOLMOD's supernodal factorisation
 * reads without a transpose (the lower one) is laid out in that order, and
 * it is analysed again in its natural order: the same factor, no
 * transposes.  w->asrc maps its entries to the model's slots, w->perm its
 * rows (eq_factorize, eq_solve).  Returns 0, 1 (out of memory) or -1
 * (err set). */
static int work_order(eq_work *w, drape_error *err)
{
    const drape_pattern *P = w->pat;
    long N = w->N;
    size_t nnz = (size_t)P->nnz;
    cholmod_sparse *S = cholmod_l_allocate_sparse((size_t)N, (size_t)N, nnz, 1, 1, -1,
                                                 CHOLMOD_REAL, &w->c);
    w->perm = drape_malloc(sizeof(long) * (size_t)N);
    long *pinv = drape_malloc(sizeof(long) * (size_t)N);
    if (!S || !w->perm || !pinv) goto nomem;
    long *sp = S->p, *si = S->i;
    for (long j = 0; j <= N; j++) sp[j] = (long)P->colptr[j];
    for (int64_t k = 0; k < P->nnz; k++) si[k] = (long)P->rowind[k];
    memset(S->x, 0, sizeof(double) * nnz); /* the analysis reads the pattern */
    cholmod_factor *F = cholmod_l_analyze(S, &w->c);
    cholmod_l_free_sparse(&S, &w->c);
    if (!F) {
        drape_free(pinv);
        if (w->c.status == CHOLMOD_OUT_OF_MEMORY) return 1;
        return drape_error_set(err, DRAPE_E_NUMERIC, NULL, 0, 0, NULL,
                               "equilibrium: CHOLMOD analysis failed (status %d)",
                               w->c.status);
    }
    memcpy(w->perm, F->Perm, sizeof(long) * (size_t)N);
    cholmod_l_free_factor(&F, &w->c);
    for (long k = 0; k < N; k++) pinv[w->perm[k]] = k;
    /* the triangle of P ax P^T, column by column (new column J is old
     * column perm[J]), rows sorted */
    size_t anz = 0;
    for (long j = 0; j < N; j++)
        for (int64_t k = P->colptr[j]; k < P->colptr[j + 1]; k++) {
            long I = pinv[P->rowind[k]], J = pinv[j];
            if (I >= J) anz++;
        }
    w->A = cholmod_l_allocate_sparse((size_t)N, (size_t)N, anz, 1, 1, -1,
                                     CHOLMOD_REAL, &w->c);
    w->asrc = drape_malloc(sizeof(long) * (anz > 0 ? anz : 1));
    if (!w->A || !w->asrc) goto nomem;
    long *ap = w->A->p, *ai = w->A->i, q = 0;
    for (long J = 0; J < N; J++) {
        long j = w->perm[J];
        ap[J] = q;
        for (int64_t k = P->colptr[j]; k < P->colptr[j + 1]; k++) {
            long I = pinv[P->rowind[k]];
            if (I < J) continue;
            long t = q++; /* insertion by row */
            while (t > ap[J] && ai[t - 1] > I) {
                ai[t] = ai[t - 1];
                w->asrc[t] = w->asrc[t - 1];
                t--;
            }
            ai[t] = I;
            w->asrc[t] = (long)lower_slot(P, P->rowind[k], j, k);
        }
    }
    ap[N] = q;
    memset(w->A->x, 0, sizeof(double) * (anz > 0 ? anz : 1));
    drape_free(pinv);
    pinv = NULL;
    w->c.nmethods = 1;
    w->c.method[0].ordering = CHOLMOD_NATURAL;
    w->c.postorder = 0;
    w->LF = cholmod_l_analyze(w->A, &w->c);
    if (!w->LF) {
        if (w->c.status == CHOLMOD_OUT_OF_MEMORY) return 1;
        return drape_error_set(err, DRAPE_E_NUMERIC, NULL, 0, 0, NULL,
                               "equilibrium: CHOLMOD analysis failed (status %d)",
                               w->c.status);
    }
    return 0;
nomem:
    cholmod_l_free_sparse(&S, &w->c);
    drape_free(pinv);
    return 1;
}

static int work_init(eq_work *w, drape_model *m, drape_error *err)
{
    const drape_lattice *L = drape_model_lattice(m);
    w->m = m;
    w->L = L;
    w->parts = drape_model_parts(m) & PARTS_POT;
    w->nf = L->n_free;
    w->N = 3 * (long)L->n_free;
    w->pat = drape_model_pattern(m);
    size_t N1 = (size_t)(w->N > 0 ? w->N : 1);
    size_t n3 = 3 * (size_t)(L->n > 0 ? L->n : 1);
    size_t nnz = (size_t)(w->pat->nnz > 0 ? w->pat->nnz : 1);
    w->K = drape_malloc(sizeof(double) * nnz);
    w->ax = drape_calloc(nnz, sizeof(double));
    w->dpos = drape_malloc(sizeof(long) * N1);
    w->mrow = drape_malloc(sizeof(double) * N1);
    w->wref = drape_malloc(sizeof(double) * (size_t)(w->nf > 0 ? w->nf : 1));
    w->xt = drape_malloc(sizeof(double) * n3);
    w->xz = drape_malloc(sizeof(double) * n3);
    w->f = drape_malloc(sizeof(double) * n3);
    w->ft = drape_malloc(sizeof(double) * n3);
    w->fz = drape_malloc(sizeof(double) * n3);
    w->dy = drape_malloc(sizeof(double) * N1);
    w->D = drape_malloc(sizeof(double) * nnz);
    w->vel = drape_calloc(n3, sizeof(double));
    w->fd = drape_malloc(sizeof(double) * n3);
    w->rhs = drape_malloc(sizeof(double) * N1);
    w->rch = drape_malloc(sizeof(double) * N1);
    w->v = drape_malloc(sizeof(double) * N1);
    w->u = drape_malloc(sizeof(double) * N1);
    if (!w->K || !w->ax || !w->dpos || !w->mrow || !w->wref || !w->xt || !w->xz || !w->f || !w->ft || !w->fz ||
        !w->dy || !w->D || !w->vel || !w->fd || !w->rhs || !w->rch || !w->v || !w->u)
        goto nomem;
    for (int p = 0; p < w->nf; p++)
        for (int c = 0; c < 3; c++) w->mrow[3 * p + c] = L->mass[L->free_to_id[p]];
    drape_model_diagonal_slots(m, w->dpos);
    if (w->kclamp[0] > 0.0 || w->kclamp[1] > 0.0) { /* (E8): model.h */
        w->Kc = drape_malloc(sizeof(double) * nnz);
        if (!w->Kc) goto nomem;
    }
    if (w->N == 0) return 0;

    cholmod_l_start(&w->c);
    w->c_started = 1;
    w->c.print = 0;              /* library code never prints */
    w->c.error_handler = NULL;
    w->c.quick_return_if_not_posdef = 1;
    w->c.final_ll = 1;           /* LL^T, which fails when not PD */
    w->c.supernodal = CHOLMOD_SUPERNODAL; /* its own amalgamation: above */
    w->B = cholmod_l_allocate_dense((size_t)w->N, 1, (size_t)w->N, CHOLMOD_REAL, &w->c);
    if (!w->B) goto nomem;
    int rc = work_order(w, err);
    if (rc != 0) {
        if (rc == 1) goto nomem;
        return -1;
    }
    return 0;
nomem:
    return drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL,
                           "out of memory in the equilibrium solver (%ld unknowns)",
                           w->N);
}

static void work_free(eq_work *w)
{
    if (w->c_started) {
        cholmod_l_free_factor(&w->LF, &w->c);
        cholmod_l_free_sparse(&w->A, &w->c);
        cholmod_l_free_dense(&w->B, &w->c);
        cholmod_l_free_dense(&w->X, &w->c);
        cholmod_l_free_dense(&w->Y, &w->c);
        cholmod_l_free_dense(&w->E, &w->c);
        cholmod_l_finish(&w->c);
    }
    drape_free(w->K);
    drape_free(w->ax);
    drape_free(w->perm);
    drape_free(w->asrc);
    drape_free(w->dpos);
    drape_free(w->mrow);
    drape_free(w->wref);
    drape_free(w->xt);
    drape_free(w->xz);
    drape_free(w->f);
    drape_free(w->ft);
    drape_free(w->fz);
    drape_free(w->Kc);
    drape_free(w->dy);
    drape_free(w->D);
    drape_free(w->vel);
    drape_free(w->fd);
    drape_free(w->rhs);
    drape_free(w->rch);
    drape_free(w->v);
    drape_free(w->u);
}

/* The iterate x may live in a trial buffer after the swaps of the loop:
 * copy it into r->x and give r->x's buffer back to the workspace. */
static double *iterate_home(eq_work *w, double *x)
{
    double *rx = w->r->x;
    if (x == rx) return rx;
    memcpy(rx, x, sizeof(double) * 3 * (size_t)w->L->n);
    if (w->xt == rx) w->xt = x;
    else w->xz = x;
    return rx;
}

static void trace(const drape_equilibrium_opts *o, int iter, int newton, double dt,
                  int posdef, int accepted, double alpha, double E, double frel,
                  double step)
{
    if (!o->trace) return;
    drape_equilibrium_iter it = {iter, newton, dt, posdef, accepted, alpha, E, frel, step};
    o->trace(o->trace_ctx, &it);
}

/* After a refused iteration (E1, E3): PTC halves dt; a refused Newton
 * step goes back to PTC at dt_newton / 4. */
static void refuse(int *newton, double *dt, double dt_newton)
{
    if (*newton) {
        *newton = 0;
        *dt = dt_newton / 4.0;
    } else {
        *dt *= 0.5;
    }
}

/* ------------------------------------------------------------------ solve */

int drape_equilibrium_solve(drape_model *m, const double *x0,
                            const drape_equilibrium_opts *opts,
                            drape_equilibrium_result *r, drape_error *err)
{
    double t_start = clock_s(CLOCK_MONOTONIC);
    double c_start = clock_s(CLOCK_PROCESS_CPUTIME_ID);
    drape_equilibrium_opts o;
    if (opts) o = *opts;
    else drape_equilibrium_opts_default(&o);
    memset(r, 0, sizeof *r);
    r->status = DRAPE_EQ_STALLED;
    r->certified = -1;
    r->not_posdef_column = -1;
    r->min_pivot = NAN;
    r->omega_min = NAN;
    r->max_force_rel = NAN;
    r->energy_J = NAN;
    r->dyn_e_start = r->dyn_e_end = r->dyn_e_max_rise = r->dyn_e_max = NAN;
    r->dyn_redo_from = NAN;

    eq_work w;
    memset(&w, 0, sizeof w);
    double *x = NULL; /* the iterate: r->x or one of the trial buffers */
    w.r = r;
    w.kclamp[0] = o.clamp_k[0];
    w.kclamp[1] = o.clamp_k[1];
    int rc = -1;
    const drape_lattice *L = drape_model_lattice(m);

    if (!(o.tol > 0.0) || o.max_iters < 1 || !(o.clamp_k[0] >= 0.0) ||
        !(o.clamp_k[1] >= 0.0) || !isfinite(o.clamp_k[0]) || !isfinite(o.clamp_k[1]) ||
        !(o.dyn_time >= 0.0) || !isfinite(o.dyn_time) ||
        (o.dyn_time > 0.0 && !(o.dyn_dt > 0.0 && isfinite(o.dyn_dt))) || !(o.dt0 >= 0.0) ||
        !(o.dyn_time_fold >= 0.0) || !isfinite(o.dyn_time_fold) ||
        (o.dyn_time_fold > 0.0 && !(o.dyn_dt_fold > 0.0 && isfinite(o.dyn_dt_fold))) ||
        !(o.dyn_ke_frac >= 0.0 && o.dyn_ke_frac < 1.0) ||
        !(o.dyn_time_max >= 0.0) || !isfinite(o.dyn_time_max) ||
        !(o.dyn_dt_swing >= 0.0) || !isfinite(o.dyn_dt_swing) ||
        !(o.dyn_retry >= 0.0) || !isfinite(o.dyn_retry) ||
        !(o.dyn_tol >= 0.0) || !isfinite(o.dyn_tol) ||
        !(o.dyn_redo_tol >= 0.0) || !isfinite(o.dyn_redo_tol) ||
        !(o.dt_growth_max >= 1.0) || !(o.dt_growth_min >= 1.0) ||
        o.dt_growth_min > o.dt_growth_max || !(o.dt_newton >= 0.0) ||
        o.eig_iters < 0 || !(o.force_ref >= 0.0) || !isfinite(o.force_ref) ||
        !isfinite(o.dt0) || !isfinite(o.dt_newton)) {
        return drape_error_set(err, DRAPE_E_INPUT, NULL, 0, 0, NULL,
                               "equilibrium: bad options (tol %g, max_iters %d, dt0 %g, "
                               "growth %g..%g, dt_newton %g, eig_iters %d, force_ref %g)",
                               o.tol, o.max_iters, o.dt0, o.dt_growth_min,
                               o.dt_growth_max, o.dt_newton, o.eig_iters, o.force_ref);
    }
    r->x = drape_malloc(sizeof(double) * 3 * (size_t)(L->n > 0 ? L->n : 1));
    if (!r->x) {
        return drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL,
                               "out of memory in the equilibrium solver");
    }
    memcpy(r->x, x0, sizeof(double) * 3 * (size_t)L->n);
    for (long k = 0; k < 3 * (long)L->n; k++) {
        if (!isfinite(x0[k])) {
            drape_error_set(err, DRAPE_E_NUMERIC, NULL, 0, 0, NULL,
                            "equilibrium: non-finite start position %ld", k);
            goto out;
        }
    }
    x = r->x;
    if (work_init(&w, m, err) != 0) goto out;

    /* reference forces w_i: the weight from the gravity part, or force_ref */
    double g = 0.0;
    if (w.parts & DRAPE_PART_GRAVITY) {
        drape_model_forces(m, DRAPE_PART_GRAVITY, x, NULL, w.f);
        for (int p = 0; p < w.nf; p++) {
            int id = L->free_to_id[p];
            double gi = -w.f[3 * id + 2] / L->mass[id];
            if (gi > g) g = gi;
        }
    }
    double msum = 0.0, wsum = 0.0;
    for (int p = 0; p < w.nf; p++) {
        double mi = L->mass[L->free_to_id[p]];
        w.wref[p] = o.force_ref > 0.0 ? o.force_ref : mi * g;
        msum += mi;
        wsum += w.wref[p];
        if (!(w.wref[p] > 0.0)) {
            drape_error_set(err, DRAPE_E_INPUT, NULL, 0, 0, NULL,
                            "equilibrium: no gravity in the model: give force_ref");
            goto out;
        }
    }

    drape_energies Ec, Et;
    if (eval_energy(&w, x, &Ec) != 0 || eval_forces(&w, x, w.f) != 0) {
        drape_error_set(err, DRAPE_E_NUMERIC, NULL, 0, 0, NULL,
                        "equilibrium: the start state cannot be evaluated (folded hinge "
                        "or corner, or zero-length edge)");
        goto out;
    }
    if (w.nf == 0) { /* nothing moves: at rest, a minimum (an empty Hessian) */
        int dyn_only = o.dyn_time > 0.0 && o.dyn_only;
        r->status = dyn_only ? DRAPE_EQ_DYN_ONLY : DRAPE_EQ_CONVERGED;
        r->max_force_rel = 0.0;
        r->certified = o.certify && !dyn_only ? 1 : -1; /* -1: not checked */
        rc = 0;
        goto done;
    }

    if (o.dyn_time > 0.0) {
        double tmax = o.dyn_time_max > 0.0 ? o.dyn_time_max : 4.0 * o.dyn_time;
        /* the state of the lowest total energy, kept for a second fall
         * (dyn_redo_tol) */
        size_t n3 = 3 * (size_t)L->n;
        int redo = o.dyn_redo_tol > 0.0 && !(o.dyn_tol > 0.0);
        eq_fall_state low;
        memset(&low, 0, sizeof low);
        if (redo) {
            low.x = drape_malloc(sizeof(double) * 2 * n3);
            if (!low.x) {
                drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL, "out of memory");
                goto out;
            }
            low.v = low.x + n3;
        }
        int rcd = eq_fall(&w, x, &o, tmax, NULL, redo ? &low : NULL, err);
        /* it gained energy: on from its lowest, error-controlled.  Against
         * a second fall from the flat start, from the lowest state the
         * table's three pumping specimens of 32 at 1 cm cost 15-20 CPU s
         * instead of 31-42, with the same histogram and mean within 0.001
         * (docs/ensemble.md, "Energy gained by the fixed-step fall") */
        if (rcd == 3) {
            drape_equilibrium_opts o2 = o;
            o2.dyn_tol = o.dyn_redo_tol;
            memcpy(x, low.x, sizeof(double) * n3);
            r->dyn_redone = 1;
            r->dyn_redo_from = low.t;
            rcd = eq_fall(&w, x, &o2, tmax, &low, NULL, err);
        }
        drape_free(low.x);
        if (rcd < 0) goto out;
        if (rcd == 1 || eval_energy(&w, x, &Ec) != 0 || eval_forces(&w, x, w.f) != 0) {
            drape_error_set(err, DRAPE_E_NUMERIC, NULL, 0, 0, NULL,
                            "equilibrium: the damped dynamics failed (folded hinge or "
                            "corner, or zero-length edge)");
            goto out;
        }
        if (rcd == 2) { /* stopped: report the state reached, not certified */
            r->status = DRAPE_EQ_INTERRUPTED;
            rc = 0;
            goto done;
        }
        if (o.dyn_only) { /* the state after the dynamics, no minimisation */
            x = iterate_home(&w, x);
            r->status = DRAPE_EQ_DYN_ONLY;
            rc = 0;
            goto done;
        }
    }
    /* time scale T = sqrt(sigma / g) (sqrt(sigma m / w) with force_ref) */
    double T = sqrt(L->sigma * msum / wsum);
    double dt0 = o.dt0 > 0.0 ? o.dt0 : DRAPE_EQ_DT0_FACTOR * T;
    double dt_newton = o.dt_newton > 0.0 ? o.dt_newton : DRAPE_EQ_DT_NEWTON_FACTOR * T;
    double dt = dt0;
    int newton = dt >= dt_newton;
    double E = energy_sum(&Ec);
    double frel = force_rel(&w, w.f);
    double anorm = accel_norm(&w, w.f);
    int have_jac = 0, skip_exact = 0;
    double *rhs = w.rhs;

    r->status = DRAPE_EQ_MAX_ITERS;
    while (1) {
        if (frel <= o.tol) {
            r->status = DRAPE_EQ_CONVERGED;
            break;
        }
        if (o.stop && *o.stop) {
            r->status = DRAPE_EQ_INTERRUPTED;
            break;
        }
        if (r->iterations >= o.max_iters) break;
        if (dt < DRAPE_EQ_DT_COLLAPSE * dt0) {
            r->status = DRAPE_EQ_STALLED;
            break;
        }
        if (!have_jac) {
            r->jacobian_evals++;
            if (drape_model_jacobian(m, w.parts, x, NULL, w.K, NULL) != 0) {
                drape_error_set(err, DRAPE_E_NUMERIC, NULL, 0, 0, NULL,
                                "equilibrium: Hessian not defined (folded hinge or corner)");
                goto out;
            }
            have_jac = 1;
            if (w.Kc) drape_model_compression_clamp(w.m, x, w.kclamp, w.Kc);
            gather(&w, w.f, rhs);
        }
        r->iterations++;
        /* PTC: clamped + shift; Newton: exact, else clamped (modified
         * Newton), else back to PTC */
        int use_clamp = !newton || (w.Kc && skip_exact > 0);
        if (skip_exact > 0) skip_exact--;
        assemble(&w, newton ? 0.0 : 1.0 / (dt * dt), use_clamp);
        int pd = eq_factorize(&w, err);
        if (pd == 0 && newton && !use_clamp && w.Kc) {
            skip_exact = DRAPE_EQ_EXACT_RETRY; /* modified Newton for a while */
            assemble(&w, 0.0, 1);
            pd = eq_factorize(&w, err);
        }
        if (pd < 0) goto out;
        if (pd == 0) {
            int was_newton = newton;
            r->rejected++;
            refuse(&newton, &dt, dt_newton);
            trace(&o, r->iterations, was_newton, was_newton ? INFINITY : dt, 0, 0, 0.0, E,
                  frel, 0.0);
            continue;
        }
        if (eq_solve(&w, rhs, w.dy, err) != 0) goto out;

        /* line search (E3): Armijo on E along dy, at most DRAPE_EQ_LS_MAX
         * halvings (Newton) or DRAPE_EQ_LS_PTC (PTC) */
        double eps_E = DRAPE_EQ_EPS_E * energy_abs(&Ec);
        double Fs = 0.0;
        for (long j = 0; j < w.N; j++) Fs += rhs[j] * w.dy[j];
        double alpha = 1.0, step = 0.0, an = anorm, Enew = E;
        int accepted = 0, noise = 0;
        int ls_max = newton ? DRAPE_EQ_LS_MAX : DRAPE_EQ_LS_PTC;
        for (int ls = 0; ls <= ls_max; ls++, alpha *= 0.5) {
            step = trial_point(&w, x, alpha, w.xt);
            if (eval_energy(&w, w.xt, &Et) != 0) continue;
            Enew = energy_sum(&Et);
            int armijo = Enew <= E - DRAPE_EQ_ARMIJO * alpha * Fs && Enew < E - eps_E;
            if (!armijo && Enew > E + eps_E) continue;
            if (eval_forces(&w, w.xt, w.ft) != 0) continue;
            an = accel_norm(&w, w.ft);
            if (!armijo && !(an < anorm)) { /* within rounding: need less residual */
                if (ls == 0 && newton) noise = 1;
                continue;
            }
            accepted = 1;
            break;
        }
        if (accepted) {
            if (!newton) {
                if (alpha < 1.0) dt *= sqrt(alpha); /* too long: shorten */
                else { /* SER (E2) */
                    double ratio = an > 0.0 ? anorm / an : o.dt_growth_max;
                    if (ratio < o.dt_growth_min) ratio = o.dt_growth_min;
                    if (ratio > o.dt_growth_max) ratio = o.dt_growth_max;
                    dt *= ratio;
                }
            }
            double *tmp = x; x = w.xt; w.xt = tmp;
            tmp = w.f; w.f = w.ft; w.ft = tmp;
            Ec = Et;
            E = Enew;
            anorm = an;
            frel = force_rel(&w, w.f);
            have_jac = 0;
        }
        int was_newton = newton;
        if (accepted) {
            if (newton) r->newton_steps++;
            else r->ptc_steps++;
            if (!newton && dt >= dt_newton) newton = 1;
        } else {
            r->rejected++;
            refuse(&newton, &dt, dt_newton);
        }
        trace(&o, r->iterations, was_newton, was_newton ? INFINITY : dt, 1, accepted, alpha,
              E, frel, step);
        /* a full Newton step whose energy change is within rounding and
         * that does not lower the residual: the roundoff floor (E5) */
        if (!accepted && noise) {
            r->status = DRAPE_EQ_STALLED;
            break;
        }
    }

    x = iterate_home(&w, x);

    /* certification (E6): the exact Hessian at x */
    if (o.certify && r->status != DRAPE_EQ_INTERRUPTED) {
        r->jacobian_evals++;
        if (drape_model_jacobian(m, w.parts, x, NULL, w.K, NULL) != 0) {
            r->certified = 0;
        } else {
            assemble(&w, 0.0, 0);
            int pd = eq_factorize(&w, err);
            if (pd < 0) goto out;
            if (pd == 1) {
                r->certified = 1;
                r->min_pivot = min_pivot(w.LF);
                if (o.eig_iters > 0) {
                    double lam;
                    if (lowest_mode(&w, o.eig_iters, &lam, err) != 0) goto out;
                    r->omega_min = lam > 0.0 ? sqrt(lam) : NAN;
                }
            } else {
                r->certified = 0;
                r->not_posdef_column = (long)w.LF->minor;
            }
        }
    }
    rc = 0;

done:
    r->energy = Ec;
    r->energy_J = energy_sum(&Ec);
    r->max_force_rel = force_rel(&w, w.f);
    r->max_strain = drape_model_max_strain(m, r->x);
out:
    if (x) iterate_home(&w, x);
    work_free(&w);
    r->wall_s = clock_s(CLOCK_MONOTONIC) - t_start;
    r->cpu_s = clock_s(CLOCK_PROCESS_CPUTIME_ID) - c_start;
    return rc;
}
