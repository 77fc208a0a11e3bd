/* lattice.h: the particle lattice of a specimen (docs/model.md sections 2, 3, 5).
 *
 * One particle per warp/weft crossing at spacing sigma.  Grid index (i, j):
 * i counts along the weft, j along the warp.  The lattice lists the model's
 * elements (stretch edges, bending hinges, shear corners), each with the
 * weight (fraction of a full interior element's width/area) it carries, so
 * that uniform deformation stores exactly the per-area energy times the
 * specimen area.  Lumped masses sum to W x specimen area.  Clamped and
 * pinned particles are `fixed` and are not unknowns of the integrator.
 *
 * World placement (rest state, z = 0 plane, before perturbation):
 *   rectangle: centred at the origin, i along +x, j along +y;
 *   circle:    centre particle at the origin, i along +x, j along +y;
 *   strip:     the strip's length along +x, its clamped end at
 *              x = -(length - overhang), the platform edge at x = 0, its width
 *              along y centred on 0; a warp strip has j along +x, a weft
 *              strip has i along +x.
 * docs/lattice.md documents the weights and the mass lumping.
 */
#ifndef DRAPE_LATTICE_H
#define DRAPE_LATTICE_H

#include <stddef.h>

#include "drape/error.h"
#include "drape/fabric.h"
#include "drape/scene.h"

/* Stretch edge between neighbours a and b (a < b as particle ids). */
typedef struct drape_edge {
    int a, b;
    drape_dir dir;  /* DRAPE_WARP if a and b are warp neighbours */
    double weight;  /* width fraction: 1 interior, 1/2 in a boundary row */
} drape_edge;

/* Bending hinge at `mid` with neighbours prev and next along `dir`. */
typedef struct drape_hinge {
    int prev, mid, next;
    drape_dir dir;
    double weight;  /* area fraction of the hinge's sigma x sigma patch */
    double length;  /* (added) fraction of sigma over which the hinge's turning
                       angle psi is spread: 1, or 1/2 for the hinge at a
                       cantilever's last clamped particle (docs/model.md 5).  The
                       model takes K = psi / (length sigma) (seed form:
                       2 psi / (length sigma)) and E = weight sigma^2 Wb(K);
                       weight already includes the factor `length`.
                       0 (a hinge built by hand without it) means 1. */
} drape_hinge;

/* Shear corner at `mid` between its warp neighbour `warp` and weft
 * neighbour `weft`. */
typedef struct drape_corner {
    int mid, warp, weft;
    double weight;  /* area fraction of the quarter cell, 1 when whole */
} drape_corner;

/* Twist cell (the `bias` term): the lattice square with lower
 * left corner p[0] = (i, j) and, counter-clockwise, p[1] = (i+1, j),
 * p[2] = (i+1, j+1), p[3] = (i, j+1). */
typedef struct drape_cell {
    int p[4];
    double weight;  /* area fraction of the square inside the specimen */
} drape_cell;

typedef struct drape_lattice {
    double sigma;          /* spacing, m */
    int ni, nj;            /* bounding grid size */
    int n;                 /* number of particles */
    int *grid;             /* ni*nj: particle id at grid[j*ni + i], or -1 */
    int *gi, *gj;          /* per particle: grid index */
    double *x0;            /* 3n: rest positions, m */
    double *xinit;         /* 3n: initial positions (rest + perturbation), m */
    double *mass;          /* n: lumped masses, kg */
    unsigned char *fixed;  /* n: 1 if clamped or pinned */
    int n_free;            /* number of free particles */
    int *free_id;          /* n: index among free particles, or -1 */
    int *free_to_id;       /* n_free: particle id of each free particle */

    int n_edges;   drape_edge *edges;
    int n_hinges;  drape_hinge *hinges;
    int n_corners; drape_corner *corners;
    int n_cells;   drape_cell *cells;   /* only with the bias term */

    double area_nominal;   /* specimen area from its dimensions, m^2 */
    double mass_total;     /* sum of masses, kg */
} drape_lattice;

/* Build the lattice of scene s for fabric f (uses W for masses).  Elements
 * all of whose particles are fixed are left out (they store a constant
 * energy).  Returns a new lattice (caller frees with drape_lattice_free) or
 * NULL with err set (E_NOMEM, or E_INPUT for a pin outside the lattice). */
drape_lattice *drape_lattice_new(const drape_scene *s, const drape_fabric *f,
                                 drape_error *err);
void drape_lattice_free(drape_lattice *L);

/* Grid dimensions and particle count the scene would need, without
 * allocating (for the memory estimate).  Returns 0, or -1 if absurd. */
int drape_lattice_estimate(const drape_scene *s, long *ni, long *nj,
                           long *n_particles);

/* Largest extent of the rest lattice (x0) along x, y or z, m; sigma for a
 * single particle.  The length scale of tolerances and energy checks. */
double drape_lattice_extent(const drape_lattice *L);

/* Number of violated invariants (ids in range, neighbours at distance
 * sigma in the rest state, weights in (0, 1], masses > 0, free ids
 * consistent, ...); 0 means consistent. */
int drape_lattice_check(const drape_lattice *L);

#endif /* DRAPE_LATTICE_H */
