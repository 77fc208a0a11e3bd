/* linsol_schur.h: the Schur-reduced solve of the Newton systems of the
 * first-order particle ODE (numerics.md 3.3; Baraff & Witkin 1998).
 *
 * With y = [x; v] (3 nf each), J = [ 0 I ; M^-1 K  M^-1 D ], K = df/dx and
 * D = df/dv (3 nf square, the model's pattern, drape_model_pattern), the
 * Newton system of an implicit step is
 *     (I - gamma J) [dx; dv] = [r1; r2]
 * and eliminating dx gives
 *     S dv = M r2 + gamma K r1,   dx = r1 + gamma dv,
 *     S = M - gamma D - gamma^2 K                                  (S.1)
 * S is 3 nf square and symmetric for conservative forces and symmetric
 * dampers; it is symmetric positive definite near any stable equilibrium
 * (-K positive definite there, -D positive semidefinite).
 *
 * A drape_schur factors the symmetric part of S(gamma_f) with CHOLMOD
 * (symbolic analysis once, numeric factorisation per call of
 * drape_schur_factor) and applies it as the preconditioner of GMRES
 * (drape_schur_solve); drape_schur_jtimes is the exact product J v with the
 * same K and D.  The pattern is fixed at creation.  No function allocates
 * after drape_schur_new except CHOLMOD's first factorisation and the lazily
 * created LDL^T fallback (linsol_schur.c).
 */
#ifndef DRAPE_LINSOL_SCHUR_H
#define DRAPE_LINSOL_SCHUR_H

#include "drape/error.h"
#include "drape/model.h"

typedef struct drape_schur drape_schur;

/* Counters since creation. */
typedef struct drape_schur_stats {
    long factorizations; /* successful drape_schur_factor calls */
    long ldl_fallbacks;  /* of these, by LDL^T because LL^T found S indefinite */
    long failures;       /* drape_schur_factor calls that returned 1 */
} drape_schur_stats;

/* New solver for the 3 nf square pattern P (borrowed: must outlive it;
 * structurally symmetric, diagonal stored) and inv_mass (nf entries,
 * 1 / m of each free particle, copied).  NULL with err set (E_NOMEM, or
 * E_INTERNAL for a pattern that is not structurally symmetric). */
drape_schur *drape_schur_new(const drape_pattern *P, const double *inv_mass,
                             drape_error *err);
void drape_schur_free(drape_schur *s);

/* Assemble S(gamma) of (S.1) from the symmetric parts of K and D (values
 * in P; D may be NULL for D = 0) and factor it.  Returns 0, 1 when S could
 * not be factored (indefinite and singular, or not finite: the caller
 * should retry with a smaller step), -1 with err set (out of memory). */
int drape_schur_factor(drape_schur *s, const double *K, const double *D,
                       double gamma, drape_error *err);

/* on = 0: drape_schur_factor returns 1 where LL^T finds S indefinite,
 * without trying the (slow, simplicial) LDL^T: for a caller that shifts
 * S to positive definite instead (integrator_animate.c).  Default 1. */
void drape_schur_ldl_fallback(drape_schur *s, int on);

/* z = P^-1 r for P = I - gamma J: the block elimination above with K
 * (values in P) and the current gamma, S from the last factorisation
 * (exact when gamma equals its gamma and K, D are symmetric).  r, z have
 * 6 nf entries and may alias.  Returns 0, or 1 if nothing is factored. */
int drape_schur_solve(drape_schur *s, const double *K, double gamma,
                      const double *r, double *z);

/* Jv = J v = [ v2 ; M^-1 (K v1 + D v2) ] (6 nf); D may be NULL. */
void drape_schur_jtimes(const drape_schur *s, const double *K,
                        const double *D, const double *v, double *Jv);

/* gamma of the current factorisation (0 when nothing is factored). */
double drape_schur_gamma(const drape_schur *s);
void drape_schur_get_stats(const drape_schur *s, drape_schur_stats *st);

#endif /* DRAPE_LINSOL_SCHUR_H */
