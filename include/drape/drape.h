/* drape.h: observers of a lattice state (docs/model.md section 6): the drape
 * coefficient and the shadow of a draped specimen, the cantilever's tip
 * angle and Peirce bending length, and the lattice's quad faces.
 *
 * Every function here only reads the lattice and a position array x (3n
 * numbers, all particles in particle-id order, m); none changes them.
 * docs/outputs.md documents the definitions and thresholds.
 */
#ifndef DRAPE_DRAPE_H
#define DRAPE_DRAPE_H

#include "drape/error.h"
#include "drape/lattice.h"

/* ---- faces --------------------------------------------------------------
 * The mesh faces are the lattice quads (i,j)-(i+1,j)-(i+1,j+1)-(i,j+1) whose
 * four corners are all kept.  drape_quads_new returns them as 4 particle
 * ids per quad, ordered so that every quad turns counter-clockwise seen
 * from +z in the rest state (its normal points up), in grid order (j, then
 * i).  *n_quads gets the count (may be 0; then a non-NULL empty array is
 * returned).  Caller frees with drape_free.  NULL with err set (E_NOMEM). */
int *drape_quads_new(const drape_lattice *L, int *n_quads, drape_error *err);

/* ---- drape coefficient and shadow --------------------------------------
 *
 *   DC = (A_shadow - A_disk) / (A_specimen - A_disk)            (docs/model.md 6)
 *
 * A_shadow: area of the union of the horizontal projections of all faces at
 * positions x.  Each quad is split into four triangles about the mean of
 * its corners (no diagonal is preferred), so a flat convex quad projects to
 * itself.  A_specimen: the same at the rest positions x0.  A_disk: the same
 * for the faces whose four corners are all fixed, at x0.  The union is
 * computed by GEOS (reentrant C API). */
#define DRAPE_SHADOW_ANGLES 360        /* rays for r(theta) */
#define DRAPE_NODE_PROMINENCE 0.05     /* fraction of the mean radius */
#define DRAPE_NODE_SIGMAS 0.0          /* multiple of the spacing sigma */
#define DRAPE_OUTLINE_SIGMAS 1.0       /* the outline's smoothing, spacings */

/* Nodes are counted on the shadow's outline: r(theta) smoothed by a
 * circular Gaussian whose standard deviation is outline_sigmas spacings
 * of arc at the mean radius (drape_outline_smooth).  That removes the
 * stairs that the lattice cuts into a circle (their period along the edge
 * is one or two spacings) and keeps every fold the lattice can form (a
 * fold spans several spacings).  A node is a maximum of the outline whose
 * prominence exceeds node_prominence * mean(r), a physical size the same
 * at every spacing, and node_sigmas * sigma (0 by default).  Checked on
 * the flat specimen and on smooth synthetic shadows at 2 to 0.25 cm
 * (tests/check_drape.c, docs/outputs.md). */
typedef struct drape_dc_opts {
    int n_angles;           /* rays sampling the shadow's radius, >= 8 */
    double node_prominence; /* fraction of the mean radius, >= 0 */
    double node_sigmas;     /* multiple of sigma, >= 0 */
    double outline_sigmas;  /* the outline's smoothing, spacings, >= 0 */
} drape_dc_opts;

/* Defaults: DRAPE_SHADOW_ANGLES, DRAPE_NODE_PROMINENCE, DRAPE_NODE_SIGMAS,
 * DRAPE_OUTLINE_SIGMAS. */
void drape_dc_opts_default(drape_dc_opts *o);

typedef struct drape_shadow {
    double a_shadow_m2;           /* union of the projected faces at x */
    double a_specimen_mesh_m2;    /* the same at rest (x0) */
    double a_disk_m2;             /* union of all-fixed faces at rest */
    double a_specimen_nominal_m2; /* L->area_nominal */
    double dc;                    /* NaN when A_specimen == A_disk */
    int nodes;                    /* folds: prominent maxima of r(theta) */
    double r_min_m, r_max_m;      /* shadow's outer radius, min and max */
    double r_mean_m;              /* mean of the sampled r(theta) */
    double centre_m[2];           /* centre of the rays (x, y) */
    double node_threshold_m;      /* the prominence a node must exceed, m */
} drape_shadow;

typedef struct drape_dc drape_dc;

/* Prepare the measurement for lattice L (borrowed: must outlive the
 * handle): faces, a GEOS context, A_specimen and A_disk, the ray centre
 * (mean rest position of the fixed particles, or the origin when none is
 * fixed).  opts may be NULL (defaults).  Returns NULL with err set
 * (E_NOMEM, E_INPUT for bad options, E_NUMERIC if GEOS fails).  Caller
 * frees with drape_dc_free. */
drape_dc *drape_dc_new(const drape_lattice *L, const drape_dc_opts *opts,
                       drape_error *err);
void drape_dc_free(drape_dc *d);

/* Measure the shadow at positions x (3n, m).  Returns 0, or -1 with err
 * set: E_NUMERIC for a non-finite position or a GEOS failure (message
 * included).  r(theta), theta_k = 2 pi k / n_angles, is the largest
 * distance from the centre along the ray to the exterior boundary of the
 * union (0 where the ray misses it); r_max is exact (farthest exterior
 * vertex), r_min and r_mean are over the samples. */
int drape_dc_measure(drape_dc *d, const double *x, drape_shadow *out,
                     drape_error *err);

/* The last measurement's samples r(theta_k), n_angles of them (NULL before
 * the first measurement).  Owned by the handle. */
const double *drape_dc_radii(const drape_dc *d, int *n_angles);

/* The last measurement's outline: r(theta_k) smoothed as the nodes are
 * counted (drape_dc_opts), n_angles samples (NULL before the first
 * measurement).  Owned by the handle. */
const double *drape_dc_outline(const drape_dc *d, int *n_angles);

/* Smooth circular samples r[0..n) (theta_k = 2 pi k / n) with a circular
 * Gaussian of standard deviation sd_rad (radians) into out[0..n) (out !=
 * r); weights cut at 4 standard deviations and normalised, so a constant
 * stays constant.  sd_rad = 0 copies. */
void drape_outline_smooth(const double *r, int n, double sd_rad, double *out);

/* One-shot: drape_dc_new + drape_dc_measure + drape_dc_free. */
int drape_shadow_measure(const drape_lattice *L, const double *x,
                         drape_shadow *out, drape_error *err);

/* Area (m^2) of the union of n_tri triangles given as 6 numbers each
 * (x1 y1 x2 y2 x3 y3), with d's GEOS context (d may be NULL: a temporary
 * context is used).  Degenerate triangles are skipped.  Returns 0 or -1. */
int drape_union_area(drape_dc *d, const double *tri, int n_tri, double *area,
                     drape_error *err);

/* Number of nodes of circular samples r[0..n): local maxima (a plateau
 * counts once) whose topographic prominence exceeds (>) min_prominence.  The
 * prominence of a peak is its height above the higher of the two lowest
 * points met walking left and right from it to the nearest higher sample
 * (all the way round for the highest peak; of equal heights, the later
 * sample counts as higher, so one of twin peaks keeps the prominence).
 * Constant r: 0. */
int drape_nodes_count(const double *r, int n, double min_prominence);
/* The same, and the sample index of each node (the middle of a plateau)
 * in peaks[0..max_peaks) (peaks may be NULL); returns the count. */
int drape_nodes_find(const double *r, int n, double min_prominence, int *peaks,
                     int max_peaks);

/* ---- cantilever --------------------------------------------------------
 * The strip's length runs along +x; the platform edge is the line x = 0,
 * z = 0 (lattice.h).  The tip is the mean position of the particles of the
 * free end (rest x within sigma/2 of the largest rest x); l is their mean
 * rest x (the mesh overhang). */
typedef struct drape_cantilever {
    double overhang_m;           /* l */
    double tip_m[3];             /* mean current position of the tip */
    double tip_angle_deg;        /* theta: chord from the edge to the tip,
                                    below horizontal, atan2(-z, x) */
    double bending_length_m;     /* c, NaN unless 0 < theta < 90 deg */
    double flexural_rigidity_Nm; /* G = W g c^3, N.m (per unit width) */
} drape_cantilever;

/* weight_kg_m2 = W, g in m/s^2.  Returns 0, or -1 with err set (E_INPUT
 * for an empty lattice, E_NUMERIC for a non-finite position). */
int drape_cantilever_measure(const drape_lattice *L, const double *x,
                             double weight_kg_m2, double g,
                             drape_cantilever *out, drape_error *err);

/* Peirce: c = l (cos(theta/2) / (8 tan theta))^(1/3), theta in rad.
 * NaN unless 0 < theta < pi/2 and l > 0. */
double drape_peirce_bending_length(double l, double theta_rad);

#endif /* DRAPE_DRAPE_H */
