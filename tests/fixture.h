/* fixture.h: a small hang scene shared by the integrator and linear-solver
 * suites: a 10 cm cotton-breen square at 2 cm (6 x 6 particles), pinned at
 * the two corners of its last row, all four energy terms. */
#ifndef DRAPE_TEST_FIXTURE_H
#define DRAPE_TEST_FIXTURE_H

#include "drape/fabric.h"
#include "drape/lattice.h"
#include "drape/model.h"
#include "drape/scene.h"

#define TF_SIDE 0.10    /* m: 6 x 6 particles at 2 cm */
#define TF_SPACING 0.02 /* m */

typedef struct tf_scene {
    drape_fabric fab;
    drape_scene sc;
    drape_lattice *L;
    drape_model *m;
} tf_scene;

/* Build the scene with air drag c_air (1/s) and edge dashpots c_edge
 * (N.s/m); fails the calling test on any error.  Free with tf_free. */
void tf_build(tf_scene *t, double c_air, double c_edge);
void tf_free(tf_scene *t);

#endif
