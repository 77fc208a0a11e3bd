/* fabric.h: a fabric's mechanical description, loaded from YAML.
 *
 * File format: see fabrics/cotton-breen.yaml and docs/fabrics.md.  Two ways
 * to give bending and shear:
 *   - piecewise fits (`bending: {units, warp, weft}`, `shear: {units, warp,
 *     weft}` or a single `shear` curve), docs/model.md 3.4;
 *   - KES-F summary values per direction (`kes:` block: B, 2HB, G, 2HG, ...),
 *     turned into piecewise fits by the construction in docs/fabrics.md.
 * Everything is stored in SI (docs/model.md section 1).
 */
#ifndef DRAPE_FABRIC_H
#define DRAPE_FABRIC_H

#include "drape/error.h"
#include "drape/fit.h"

#define DRAPE_FABRIC_NAME_MAX 128
#define DRAPE_FABRIC_TEXT_MAX 4096

/* The internal shear damping beta of a fabric whose file gives none
 * (`damping: {shear: T}`), s: docs/model.md 3.6.  A viscous shear stress
 * beta G0 dgamma/dt, G0 the slope of the mean shear curve at zero shear. */
#define DRAPE_FABRIC_DAMPING_SHEAR 0.5e-3

/* Material directions.  The lattice's i axis runs along the weft, j along
 * the warp (docs/model.md section 2). */
typedef enum drape_dir { DRAPE_WEFT = 0, DRAPE_WARP = 1 } drape_dir;

typedef struct drape_fabric {
    char name[DRAPE_FABRIC_NAME_MAX];          /* `fabric:` */
    char description[DRAPE_FABRIC_TEXT_MAX];   /* optional */
    char source[DRAPE_FABRIC_TEXT_MAX];        /* optional `source:` text */
    char path[DRAPE_ERROR_FILE_MAX];           /* file it came from */
    double weight;        /* areal density W, kg/m^2 */
    double k[2];          /* tensile stiffness per unit width, N/m, [DRAPE_WEFT], [DRAPE_WARP] */
    drape_fit bend[2];    /* M(K): K in 1/m, M in N.m/m, per direction */
    drape_fit bend_bias;  /* M(K) of a strip cut at 45 degrees (optional
                             `bending.bias`); valid if has_bias */
    int has_bias;
    drape_fit shear[2];   /* F(gamma): gamma in rad, F in N/m, per direction
                             (both equal when the file gives one curve) */
    drape_fit shear_mean; /* (shear[0] + shear[1]) / 2, used by the model */
    int from_kes;         /* 1 if built from KES-F summary values */
    double damping_shear; /* internal shear damping beta, s (`damping:
                             {shear: T}`; DRAPE_FABRIC_DAMPING_SHEAR when
                             absent; 0 = none), docs/model.md 3.6 */
} drape_fabric;

/* Load a fabric file.  Returns 0 and fills *f, or -1 and fills err with
 * file, line, column and key path.  Warnings (e.g. a slope jump at a knot)
 * go to warn(warn_ctx, ...); warn may be NULL.  Does not keep any pointer
 * into the file; nothing to free. */
int drape_fabric_load(const char *path, drape_fabric *f, drape_error *err,
                      drape_warn_fn warn, void *warn_ctx);

/* Initial (K -> 0) slopes, used for stiffness bounds and summaries:
 * bending rigidity B = dM/dK(0) (N.m) and shear rigidity G = dF/dgamma(0)
 * (N/m per rad). */
double drape_fabric_bending_rigidity(const drape_fabric *f, drape_dir d);
double drape_fabric_shear_rigidity(const drape_fabric *f);

/* The twist energy density Wt(tau) of a fabric with a bias curve (tau the
 * twist curvature kappa_xy, 1/m; J/m^2), chosen so that cylindrical
 * bending at 45 degrees stores the measured bias energy:
 *     Wt(tau) = Wb_bias(2 tau) - Wb_weft(tau) - Wb_warp(tau)
 * (docs/model.md, "Bias bending").  Even in tau.  Returns Wt and, if not
 * NULL, *d1 = Wt'(tau) and *d2 = Wt''(tau).  0 without a bias curve. */
double drape_fabric_twist_energy(const drape_fabric *f, double tau, double *d1,
                                 double *d2);

#endif /* DRAPE_FABRIC_H */
