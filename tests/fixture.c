/* fixture.c: the small hang scene of fixture.h. */
#include "fixture.h"

#include <string.h>

#include "testutil.h"

void tf_build(tf_scene *t, double c_air, double c_edge)
{
    drape_error err;
    drape_error_clear(&err);
    memset(t, 0, sizeof *t);
    ck_assert_msg(drape_fabric_load(tu_src("fabrics/cotton-breen.yaml"), &t->fab, &err,
                                    NULL, NULL) == 0, "fabric: %s", err.msg);
    drape_scene *s = &t->sc;
    s->kind = DRAPE_SCENE_HANG;
    s->shape = DRAPE_SHAPE_RECTANGLE;
    s->width = TF_SIDE;
    s->height = TF_SIDE;
    s->spacing = TF_SPACING;
    s->n_pins = 2;
    s->pins[0][0] = 0;  s->pins[0][1] = -1;
    s->pins[1][0] = -1; s->pins[1][1] = -1;
    s->terms = DRAPE_TERM_ALL;
    s->energy_form = DRAPE_FORM_CONSISTENT;
    s->damping_air = c_air;
    s->damping_edge = c_edge;
    t->L = drape_lattice_new(s, &t->fab, &err);
    ck_assert_msg(t->L != NULL, "lattice: %s", err.msg);
    ck_assert_int_eq(t->L->n_free, 34);
    drape_model_opts mo;
    drape_model_opts_from_scene(s, &mo);
    t->m = drape_model_new(t->L, &t->fab, &mo, &err);
    ck_assert_msg(t->m != NULL, "model: %s", err.msg);
}

void tf_free(tf_scene *t)
{
    drape_model_free(t->m);
    drape_lattice_free(t->L);
}
