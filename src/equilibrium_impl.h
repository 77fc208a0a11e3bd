/* equilibrium_impl.h: the equilibrium solver's private workspace, shared
 * by the static solver (equilibrium.c: pseudo-transient continuation,
 * Newton, certification) and the fall before it (equilibrium_fall.c: the
 * damped implicit dynamics, E9).  Not part of the library's interface. */
#ifndef DRAPE_EQUILIBRIUM_IMPL_H
#define DRAPE_EQUILIBRIUM_IMPL_H

#include <cholmod.h>

#include "drape/equilibrium.h"
#include "drape/lattice.h"
#include "drape/model.h"

/* The workspace of one solve: the model's pattern and matrices, the
 * CHOLMOD factor of A (analysed once), the buffers of both stages. */
typedef struct eq_work {
    drape_model *m;
    const drape_lattice *L;
    unsigned parts;        /* conservative parts the model has */
    int nf;
    long N;                /* 3 nf */
    const drape_pattern *pat;
    double *K;             /* nnz: K = dF/dy */
    double *Kc;            /* nnz: clamp correction (E8), added to K when asked */
    long *dpos;            /* N: slot of the diagonal entry of each column */
    double *mrow;          /* N: mass of the coordinate's particle */
    double *wref;          /* nf: reference force of each free particle */
    double *xt, *xz;       /* 3n: trial positions; xz: scratch of the dynamics */
    double *f, *ft, *fz;   /* 3n: forces at x and xt; fz: scratch of the dynamics */
    double *dy;            /* N: step */
    double *rhs, *rch;     /* N: F(y) (free part); right side of the dynamics */
    double *v, *u;         /* N: inverse iteration */
    double *D, *vel, *fd;  /* damped dynamics: nnz, 3n, 3n */
    double kclamp[2];      /* N/m per direction; 0 = no clamping */
    double *ax;            /* nnz: the matrix to factorise, in the model's
                              pattern (both triangles; eq_factorize reads
                              the lower one) */
    cholmod_common c;
    int c_started;
    cholmod_sparse *A;     /* one triangle of P ax P^T, which CHOLMOD
                              factorises without transposing it */
    long *perm;            /* N: row k of A is row perm[k] of ax */
    long *asrc;            /* A's nnz: the slot of ax each entry of A takes */
    cholmod_factor *LF;    /* of A, in its own (natural) order */
    cholmod_dense *B, *X, *Y, *E;
    drape_equilibrium_result *r;
} eq_work;

/* Numeric factorisation of the matrix in w->ax.  1: positive definite,
 * 0: not, -1: error (err set). */
int eq_factorize(eq_work *w, drape_error *err);
/* out = A^-1 rhs (N numbers; out may be rhs).  0, or -1 with err set. */
int eq_solve(eq_work *w, const double *rhs, double *out, drape_error *err);

/* A state of a fall, from which another fall can go on: the fixed-step
 * fall records the one of its lowest total energy, where a second fall
 * under error control takes over (equilibrium_fall.c). */
typedef struct eq_fall_state {
    double *x, *v;      /* 3n each, the caller's buffers */
    double t;           /* s since the fall began */
    double e_start;     /* J: total energy at the fall's start */
    double e_max, e_max_rise, dt_min, dt_max; /* the fall's record up to t */
    double ke_peak;     /* J: the largest kinetic energy up to t */
    double ke_win;      /* J: the largest over the swing criterion's window
                           that ends at t */
    int steps;          /* steps up to t */
    int refused;        /* steps refused up to t (dyn_refused) */
} eq_fall_state;

/* (E9) The fall: damped implicit dynamics of x (3n, updated in place)
 * from rest (from NULL) or from the state *from (x must hold from->x),
 * for o->dyn_time, then on while the cloth swings (up to T_max); fills
 * w->r's dyn_* fields; with low given, records there the state of the
 * lowest total energy.  Returns 0, 1 (folded or too small a step),
 * 2 (stop raised), 3 (see equilibrium_fall.c) or -1 (err set). */
int eq_fall(eq_work *w, double *x, const drape_equilibrium_opts *o, double T_max,
            const eq_fall_state *from, eq_fall_state *low, drape_error *err);

#endif
