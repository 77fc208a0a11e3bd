/* model_impl.h: the particle model's private state, shared by the
 * evaluation (model.c) and its construction: patterns, slots and the
 * segment cache (model_build.c).  Not part of the library's interface. */
#ifndef DRAPE_MODEL_IMPL_H
#define DRAPE_MODEL_IMPL_H

#include <stdint.h>

#include "drape/model.h"

/* An edge shorter than this fraction of sigma has no direction. */
#define MODEL_LEN_TINY 1e-12
/* |sin| of a hinge or corner angle below this is degenerate (numerics 4.3). */
#define MODEL_SIN_TINY 1e-12
/* Below this psi, psi/sin(psi) = 1 + psi^2/6 + 7 psi^4/360 (error < 1e-19). */
#define MODEL_SERIES_PSI 1e-3

#define PARTS_CONSERVATIVE (DRAPE_PART_STRETCH | DRAPE_PART_BEND | DRAPE_PART_SHEAR)
#define PARTS_SEGMENTS (PARTS_CONSERVATIVE | DRAPE_PART_EDGE | DRAPE_PART_SHEAR_DAMPING)

struct drape_model {
    const drape_lattice *L;
    drape_fabric F;
    drape_model_opts o;
    unsigned parts;
    double shear_g0;   /* max(F'(0), 0) of the mean shear curve, N/m/rad (shear damping) */
    int nf;            /* free particles */
    int64_t N;         /* 3 nf */
    drape_pattern pat; /* K, D */
    drape_pattern pat1; /* first-order J */
    int64_t *colstride; /* nf: rows per scalar column of block column q */
    int64_t *dslot;     /* nf: slot of the diagonal block */
    int64_t *eslot;     /* 4 per edge (aa, ab, ba, bb), -1 if not free */
    int64_t *hslot;     /* 9 per hinge (prev, mid, next)^2 */
    int64_t *cslot;     /* 9 per corner (mid, warp, weft)^2 */
    int64_t *qslot;     /* 16 per twist cell (p0..p3)^2 */
    int use_cells;      /* twist cells evaluated with DRAPE_PART_BEND */
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

#endif /* DRAPE_MODEL_IMPL_H */
