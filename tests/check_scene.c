/* check_scene.c: scene files (scene.h).
 *
 * The four example scenes are loaded and compared with hand conversions of
 * their text (1 cm = 0.01 m, 0.1 mm = 1e-4 m, 1/30 s, ...).  Then every
 * class of bad input, each asserting the error kind, line, column and key
 * path; positions are counted by hand from the YAML text in the test.  The
 * lattice sizes used by the pin and memory checks are worked out by hand:
 * a 30 cm side at 1 cm holds 30/1 + 1 = 31 particles. */
#include "drape/scene.h"

#include "drape/alloc.h"

#include <glob.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <unistd.h>

#include "testutil.h"

Suite *scene_suite(void);

static char fabric_abs[4096]; /* absolute path of the cotton fabric */

static int file_exists(const char *p)
{
    struct stat st;
    return stat(p, &st) == 0 && S_ISREG(st.st_mode);
}


static void setup(void)
{
    char cwd[2048];
    ck_assert_ptr_nonnull(getcwd(cwd, sizeof cwd));
    snprintf(fabric_abs, sizeof fabric_abs, "%s/%s", cwd,
             tu_src("fabrics/cotton-breen.yaml"));
    ck_assert_msg(file_exists(fabric_abs), "no fabric at %s", fabric_abs);
}

/* Write text with "@F" replaced by the fabric's absolute path. */
static const char *write_scene(const char *name, const char *text)
{
    static char buf[16384];
    size_t k = 0;
    for (const char *t = text; *t && k + 1 < sizeof buf; t++) {
        if (t[0] == '@' && t[1] == 'F') {
            k += (size_t)snprintf(buf + k, sizeof buf - k, "%s", fabric_abs);
            t++;
        } else {
            buf[k++] = *t;
        }
    }
    buf[k] = 0;
    return tu_write_file(name, buf);
}

static int load_text(const char *text, drape_scene *s, drape_error *e)
{
    const char *path = write_scene("scene.yaml", text);
    drape_error_clear(e);
    return drape_scene_load(path, s, e, NULL, NULL);
}

/* Loading text must fail with kind at line:col (col 0: not checked), key
 * path `key`, and a message containing `needle` (NULL: not checked). */
static void expect_error(const char *text, drape_error_kind kind, int line,
                         int col, const char *key, const char *needle)
{
    drape_scene s;
    drape_error e;
    char buf[1024];
    int rc = load_text(text, &s, &e);
    drape_error_format(&e, buf, sizeof buf);
    ck_assert_msg(rc == -1, "accepted:\n%s", text);
    ck_assert_msg(e.kind == kind, "kind %d, expected %d: %s", (int)e.kind,
                  (int)kind, buf);
    ck_assert_msg(e.line == line, "line %d, expected %d: %s", e.line, line,
                  buf);
    if (col)
        ck_assert_msg(e.column == col, "column %d, expected %d: %s", e.column,
                      col, buf);
    ck_assert_msg(strcmp(e.key, key) == 0, "key `%s`, expected `%s`: %s",
                  e.key, key, buf);
    if (needle)
        ck_assert_msg(strstr(e.msg, needle) != NULL,
                      "message lacks \"%s\": %s", needle, buf);
    ck_assert_msg(strstr(e.file, "scene.yaml") != NULL, "file: %s", buf);
}

/* ---------------------------------------------------- the example scenes */

static void load_example(const char *name, drape_scene *s)
{
    drape_error e;
    drape_fabric f;
    char buf[1024];
    memset(&f, 0, sizeof f);
    drape_error_clear(&e);
    int rc = drape_scene_load(tu_src(name), s, &e, NULL, NULL);
    ck_assert_msg(rc == 0, "%s: %s", name,
                  drape_error_format(&e, buf, sizeof buf));
    ck_assert_str_eq(s->path, tu_src(name));
    ck_assert_msg(file_exists(s->fabric_path), "fabric_path %s",
                  s->fabric_path);
    ck_assert_str_eq(s->fabric_path, "../scenes/../fabrics/cotton-breen.yaml");
    rc = drape_scene_check_with_fabric(s, &f, &e);
    ck_assert_msg(rc == 0, "%s: %s", name,
                  drape_error_format(&e, buf, sizeof buf));
}

START_TEST(test_cusick)
{
    drape_scene s;
    load_example("scenes/cusick.yaml", &s);
    ck_assert_int_eq(s.kind, DRAPE_SCENE_CUSICK);
    ck_assert_int_eq(s.shape, DRAPE_SHAPE_CIRCLE);
    ck_assert_close_rel(s.diameter, 0.30, 1e-12);         /* 30 cm */
    ck_assert_close_rel(s.support_diameter, 0.18, 1e-12); /* 18 cm */
    ck_assert_close_rel(s.spacing, 0.01, 1e-12);          /* 1 cm */
    ck_assert_int_eq(s.has_perturbation, 1);
    ck_assert_close_rel(s.perturb_amplitude, 1e-4, 1e-12); /* 0.1 mm */
    ck_assert_uint_eq(s.perturb_seed, 1);
    ck_assert_int_eq(s.n_pins, 0);
    ck_assert_int_eq(s.energy_form, DRAPE_FORM_CONSISTENT);
    ck_assert_uint_eq(s.terms, 1u | 2u | 4u | 8u | 16u); /* the shipped list adds bias */
    ck_assert_close_rel(s.damping_air, 2.0, 1e-12);   /* 2 1/s */
    ck_assert_close_rel(s.damping_edge, 0.02, 1e-12); /* 0.02 N.s/m */
    ck_assert_str_eq(s.integrator, "arkode-imex");
    ck_assert_close_rel(s.rtol, 1e-4, 1e-12);
    ck_assert_close_rel(s.atol, 1e-7, 1e-12);
    ck_assert_int_eq(s.max_order, 0);
    ck_assert_int_eq(s.has_equilibrium, 1);
    ck_assert_close_rel(s.eq_speed, 1e-4, 1e-12);
    ck_assert_close_rel(s.eq_window, 0.2, 1e-12);
    ck_assert_close_rel(s.t_max, 20.0, 1e-12);
    ck_assert_int_eq(s.has_frames, 1);
    ck_assert_close_rel(s.frame_every, 0.05, 1e-12);
    ck_assert_int_eq(s.out_obj, 1);
    ck_assert_int_eq(s.out_hdf5, 1);
    /* spacing: 1 cm is on line 6, value at column 10 */
    ck_assert_int_eq(s.at_spacing.line, 6);
    ck_assert_int_eq(s.at_spacing.column, 10);
}
END_TEST

START_TEST(test_hang)
{
    drape_scene s;
    load_example("scenes/hang.yaml", &s);
    ck_assert_int_eq(s.kind, DRAPE_SCENE_HANG);
    ck_assert_int_eq(s.shape, DRAPE_SHAPE_RECTANGLE);
    ck_assert_close_rel(s.width, 0.30, 1e-12);
    ck_assert_close_rel(s.height, 0.30, 1e-12);
    ck_assert_close_rel(s.spacing, 0.01, 1e-12);
    ck_assert_int_eq(s.n_pins, 2);
    ck_assert_int_eq(s.pins[0][0], 0);
    ck_assert_int_eq(s.pins[0][1], -1);
    ck_assert_int_eq(s.pins[1][0], -1);
    ck_assert_int_eq(s.pins[1][1], -1);
    ck_assert_int_eq(s.has_perturbation, 0);
    ck_assert_uint_eq(s.terms, DRAPE_TERM_ALL); /* the shipped list adds bias (issue 18) */
    ck_assert_close_rel(s.damping_air, 0.5, 1e-12);
    ck_assert(s.damping_edge == 0.0);
    ck_assert_str_eq(s.integrator, "cvode-bdf");
    ck_assert_close_rel(s.rtol, 1e-5, 1e-12);
    ck_assert_close_rel(s.atol, 1e-8, 1e-12);
    ck_assert_int_eq(s.has_equilibrium, 0);
    ck_assert_close_rel(s.t_max, 3.0, 1e-12);
    ck_assert_int_eq(s.has_frames, 1);
    ck_assert_close_rel(s.frame_every, 1.0 / 30.0, 1e-12); /* "1/30 s" */
    ck_assert_int_eq(s.out_obj, 1);
    ck_assert_int_eq(s.out_hdf5, 1);
    ck_assert_int_eq(s.at_pins.line, 7); /* `pins:` key, line 7 column 1 */
    ck_assert_int_eq(s.at_pins.column, 1);
}
END_TEST

START_TEST(test_table)
{
    drape_scene s;
    load_example("scenes/table.yaml", &s);
    ck_assert_int_eq(s.kind, DRAPE_SCENE_TABLE);
    ck_assert_int_eq(s.shape, DRAPE_SHAPE_RECTANGLE);
    ck_assert_close_rel(s.width, 0.60, 1e-12);
    ck_assert_close_rel(s.height, 0.60, 1e-12);
    ck_assert_int_eq(s.table_shape, DRAPE_TABLE_SQUARE);
    ck_assert_close_rel(s.table_size, 0.36, 1e-12);
    ck_assert_close_rel(s.perturb_amplitude, 1e-4, 1e-12);
    ck_assert_uint_eq(s.perturb_seed, 7);
    /* defaults: no model block */
    ck_assert_int_eq(s.energy_form, DRAPE_FORM_CONSISTENT);
    ck_assert_uint_eq(s.terms, DRAPE_TERM_ALL);
    ck_assert_str_eq(s.integrator, "arkode-imex");
    ck_assert_close_rel(s.frame_every, 0.1, 1e-12);
    ck_assert_int_eq(s.out_obj, 1);
    ck_assert_int_eq(s.out_hdf5, 0); /* not given */
}
END_TEST

START_TEST(test_cantilever)
{
    drape_scene s;
    load_example("scenes/cantilever.yaml", &s);
    ck_assert_int_eq(s.kind, DRAPE_SCENE_CANTILEVER);
    ck_assert_int_eq(s.shape, DRAPE_SHAPE_STRIP);
    ck_assert_close_rel(s.length, 0.20, 1e-12);
    ck_assert_close_rel(s.width, 0.025, 1e-12);
    ck_assert_int_eq(s.strip_dir, DRAPE_WARP);
    ck_assert_close_rel(s.overhang, 0.06, 1e-12);
    ck_assert_close_rel(s.spacing, 0.0025, 1e-12); /* 0.25 cm */
    ck_assert_uint_eq(s.terms, DRAPE_TERM_STRETCH | DRAPE_TERM_BEND |
                                   DRAPE_TERM_GRAVITY | DRAPE_TERM_BIAS);
    ck_assert_close_rel(s.damping_air, 5.0, 1e-12);
    ck_assert_str_eq(s.integrator, "cvode-bdf");
    ck_assert_close_rel(s.rtol, 1e-6, 1e-12);
    ck_assert_close_rel(s.atol, 1e-9, 1e-12);
    ck_assert_close_rel(s.eq_speed, 1e-5, 1e-12);
    ck_assert_close_rel(s.eq_window, 0.2, 1e-12);
    ck_assert_close_rel(s.t_max, 20.0, 1e-12);
    ck_assert_int_eq(s.has_frames, 0);
    ck_assert_int_eq(s.out_obj, 0);
    ck_assert_int_eq(s.out_hdf5, 0);
}
END_TEST

START_TEST(test_names)
{
    ck_assert_str_eq(drape_scene_kind_name(DRAPE_SCENE_CUSICK), "cusick");
    ck_assert_str_eq(drape_scene_kind_name(DRAPE_SCENE_HANG), "hang");
    ck_assert_str_eq(drape_scene_kind_name(DRAPE_SCENE_TABLE), "table");
    ck_assert_str_eq(drape_scene_kind_name(DRAPE_SCENE_CANTILEVER),
                     "cantilever");
    ck_assert_str_eq(drape_scene_kind_name((drape_scene_kind)42), "unknown");
    ck_assert_str_eq(drape_energy_form_name(DRAPE_FORM_CONSISTENT),
                     "consistent");
    ck_assert_str_eq(drape_energy_form_name(DRAPE_FORM_SEED), "seed");
    int n = 0;
    while (drape_integrator_names[n]) n++;
    ck_assert_int_eq(n, 8);
    ck_assert_str_eq(drape_integrator_names[0], "auto");
    ck_assert_str_eq(drape_integrator_names[7], "animate");
}
END_TEST

/* ----------------------------------------------------- defaults, options */

START_TEST(test_defaults)
{
    drape_scene s;
    drape_error e;
    ck_assert_int_eq(load_text("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                               "end: {t_max: 5 s}\n", &s, &e), 0);
    ck_assert_int_eq(s.shape, DRAPE_SHAPE_CIRCLE);
    ck_assert_close_rel(s.diameter, 0.30, 1e-12);
    ck_assert_close_rel(s.support_diameter, 0.18, 1e-12);
    ck_assert_int_eq(s.has_perturbation, 0);
    ck_assert_int_eq(s.energy_form, DRAPE_FORM_CONSISTENT);
    ck_assert_uint_eq(s.terms, 31u); /* all five, bias included (issue 18) */
    ck_assert(s.damping_air == 0.0 && s.damping_edge == 0.0);
    ck_assert(s.damping_shear == DRAPE_SCENE_DAMPING_SHEAR_FABRIC); /* the fabric's */
    ck_assert_str_eq(s.integrator, "auto");
    ck_assert_close_rel(s.rtol, 1e-4, 1e-12);
    ck_assert_close_rel(s.atol, 1e-7, 1e-12);
    ck_assert_int_eq(s.has_equilibrium, 0);
    ck_assert_close_rel(s.eq_speed, 1e-4, 1e-12);
    ck_assert_close_rel(s.eq_window, 0.2, 1e-12);
    ck_assert_int_eq(s.has_frames, 0);
    ck_assert_int_eq(s.out_obj + s.out_hdf5, 0);
    ck_assert_str_eq(s.fabric_path, fabric_abs); /* absolute stays as is */

    /* empty equilibrium block: on, with the defaults */
    ck_assert_int_eq(load_text("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                               "end: {equilibrium: {}, t_max: 5 s}\n"
                               "output: {frames: {every: 100 ms}}\n",
                               &s, &e), 0);
    ck_assert_int_eq(s.has_equilibrium, 1);
    ck_assert_close_rel(s.eq_speed, 1e-4, 1e-12);
    ck_assert_int_eq(s.has_frames, 1);
    ck_assert_close_rel(s.frame_every, 0.1, 1e-12);
    ck_assert_int_eq(s.out_obj, 0);
}
END_TEST

/* end.strain_limit (issue 7): optional, default 0.2, a positive number. */
START_TEST(test_strain_limit)
{
    drape_scene s;
    drape_error e;
    ck_assert_int_eq(load_text("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                               "end: {t_max: 5 s}\n", &s, &e), 0);
    ck_assert_close_rel(s.strain_limit, 0.2, 1e-15);
    ck_assert_int_eq(load_text("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                               "end: {t_max: 5 s, strain_limit: 0.05}\n", &s, &e), 0);
    ck_assert_close_rel(s.strain_limit, 0.05, 1e-15);
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "end:\n  t_max: 5 s\n  strain_limit: -0.1\n",
                 DRAPE_E_INPUT, 6, 17, "end.strain_limit", NULL);
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "end:\n  t_max: 5 s\n  strain_limit: 5 cm\n",
                 DRAPE_E_INPUT, 6, 17, "end.strain_limit", NULL);
    /* every shipped scene loads unchanged and gets the default */
    const char *names[] = {"scenes/cusick.yaml", "scenes/hang.yaml", "scenes/table.yaml",
                           "scenes/cantilever.yaml"};
    for (int k = 0; k < 4; k++) {
        drape_error_clear(&e);
        ck_assert_int_eq(drape_scene_load(tu_src(names[k]), &s, &e, NULL, NULL), 0);
        ck_assert_close_rel(s.strain_limit, 0.2, 1e-15);
    }
}
END_TEST

START_TEST(test_options)
{
    drape_scene s;
    drape_error e;
    char buf[1024];
    int rc = load_text(
        "scene: cantilever\nfabric: @F\n"
        "description: a weft strip\n"
        "specimen: {shape: strip, length: 150 mm, width: 0.02, "
        "direction: weft}\n"
        "overhang: 0.5 dm\n" /* no dm: must fail; replaced below */
        "spacing: 5 mm\nend: {t_max: 1 min}\n", &s, &e);
    ck_assert_int_eq(rc, -1); /* "dm" is not a unit */
    rc = load_text(
        "scene: cantilever\nfabric: @F\n"
        "description: a weft strip\n"
        "specimen: {shape: strip, length: 150 mm, width: 0.02, "
        "direction: weft}\n"
        "overhang: 50 mm\n"
        "spacing: 5 mm\n"
        "perturbation: {amplitude: 0 m}\n"
        "model: {energy_form: seed, terms: [gravity, bend]}\n"
        "damping: {edge: 1 N.s/m, shear: 0.5 ms}\n"
        "solver: {integrator: gsl-msbdf, max_order: 3, rtol: 1/1000}\n"
        "end: {t_max: 1 min, equilibrium: {speed: 1 mm/s, window: 500 ms}}\n"
        "output: {hdf5: false, frames: {every: 1/25 s, obj: false}}\n",
        &s, &e);
    ck_assert_msg(rc == 0, "%s", drape_error_format(&e, buf, sizeof buf));
    ck_assert_int_eq(s.strip_dir, DRAPE_WEFT);
    ck_assert_close_rel(s.length, 0.15, 1e-12);
    ck_assert_close_rel(s.width, 0.02, 1e-12); /* bare number: SI */
    ck_assert_close_rel(s.overhang, 0.05, 1e-12);
    ck_assert_close_rel(s.spacing, 0.005, 1e-12);
    ck_assert_int_eq(s.has_perturbation, 1);
    ck_assert(s.perturb_amplitude == 0.0);
    ck_assert_uint_eq(s.perturb_seed, 0);
    ck_assert_int_eq(s.perturb_kind, DRAPE_PERTURB_FIELD); /* docs/model.md 2's default */
    ck_assert(s.perturb_lambda_min == 0.0 && s.perturb_lambda_max == 0.0 && s.perturb_modes == 0);
    ck_assert_int_eq(s.energy_form, DRAPE_FORM_SEED);
    ck_assert_uint_eq(s.terms, DRAPE_TERM_GRAVITY | DRAPE_TERM_BEND);
    ck_assert_close_rel(s.damping_edge, 1.0, 1e-12);
    ck_assert_close_rel(s.damping_shear, 5e-4, 1e-12); /* 0.5 ms */
    ck_assert_str_eq(s.integrator, "gsl-msbdf");
    ck_assert_int_eq(s.max_order, 3);
    ck_assert_close_rel(s.rtol, 1e-3, 1e-12);
    ck_assert_close_rel(s.t_max, 60.0, 1e-12);
    ck_assert_close_rel(s.eq_speed, 1e-3, 1e-12);
    ck_assert_close_rel(s.eq_window, 0.5, 1e-12);
    ck_assert_close_rel(s.frame_every, 0.04, 1e-12);

    /* every integrator name is accepted */
    for (int i = 0; drape_integrator_names[i]; i++) {
        char text[512];
        snprintf(text, sizeof text,
                 "scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "solver: {integrator: %s}\nend: {t_max: 5 s}\n",
                 drape_integrator_names[i]);
        ck_assert_int_eq(load_text(text, &s, &e), 0);
        ck_assert_str_eq(s.integrator, drape_integrator_names[i]);
    }

    /* round table */
    rc = load_text("scene: table\nfabric: @F\n"
                   "specimen: {shape: rectangle, width: 1 m, height: 80 cm}\n"
                   "table: {shape: round, diameter: 70 cm}\n"
                   "spacing: 2 cm\nend: {t_max: 5 s}\n", &s, &e);
    ck_assert_msg(rc == 0, "%s", drape_error_format(&e, buf, sizeof buf));
    ck_assert_int_eq(s.table_shape, DRAPE_TABLE_ROUND);
    ck_assert_close_rel(s.table_size, 0.70, 1e-12);
}
END_TEST

START_TEST(test_fabric_relative)
{
    drape_scene s;
    drape_error e;
    char expect[1024], buf[1024];
    tu_write_file("myfabric.yaml", "fabric: dummy\n");
    const char *p = tu_write_file("rel.yaml",
                                  "scene: cusick\nfabric: myfabric.yaml\n"
                                  "spacing: 2 cm\nend: {t_max: 5 s}\n");
    drape_error_clear(&e);
    int rc = drape_scene_load(p, &s, &e, NULL, NULL);
    ck_assert_msg(rc == 0, "%s", drape_error_format(&e, buf, sizeof buf));
    snprintf(expect, sizeof expect, "%s/myfabric.yaml", tu_scratch_dir());
    ck_assert_str_eq(s.fabric_path, expect);
    ck_assert(file_exists(s.fabric_path));
}
END_TEST

/* A scene whose own fabric file is missing: an error naming the key when
 * the scene's fabric is to be used, fine when the caller overrides it
 * (drape run --fabric, drape batch). */
START_TEST(test_fabric_overridden)
{
    drape_scene s;
    drape_error e;
    char buf[1024];
    const char *p = tu_write_file("nofab.yaml",
                                  "scene: cusick\nfabric: no-such-fabric.yaml\n"
                                  "spacing: 2 cm\nend: {t_max: 5 s}\n");
    drape_error_clear(&e);
    ck_assert_int_eq(drape_scene_load(p, &s, &e, NULL, NULL), -1);
    ck_assert_int_eq(e.kind, DRAPE_E_IO);
    ck_assert_str_eq(e.key, "fabric");
    ck_assert_int_eq(e.line, 2);
    drape_error_clear(&e);
    int rc = drape_scene_load_flags(p, DRAPE_SCENE_LOAD_FABRIC_OVERRIDDEN, &s, &e, NULL, NULL);
    ck_assert_msg(rc == 0, "%s", drape_error_format(&e, buf, sizeof buf));
    ck_assert_int_eq(s.kind, DRAPE_SCENE_CUSICK);
    ck_assert(strstr(s.fabric_path, "no-such-fabric.yaml") != NULL);
}
END_TEST

/* ------------------------------------------------------------ bad input */

START_TEST(test_bad_fabric_missing)
{
    drape_scene s;
    drape_error e;
    const char *p = tu_write_file("nofab.yaml",
                                  "# comment\nscene: cusick\n"
                                  "fabric: ../fabrics/x.yaml\n"
                                  "spacing: 2 cm\nend: {t_max: 5 s}\n");
    drape_error_clear(&e);
    ck_assert_int_eq(drape_scene_load(p, &s, &e, NULL, NULL), -1);
    ck_assert_int_eq(e.kind, DRAPE_E_IO);
    ck_assert_int_eq(e.line, 3);
    ck_assert_int_eq(e.column, 1);
    ck_assert_str_eq(e.key, "fabric");
    ck_assert_ptr_nonnull(strstr(e.msg, "fabric file `../fabrics/x.yaml` not "
                                        "found (resolved to "));
    ck_assert_ptr_nonnull(strstr(e.msg, "/../fabrics/x.yaml)"));
    /* a directory is not a fabric file */
    expect_error("scene: cusick\nfabric: /\nspacing: 2 cm\nend: {t_max: 5 s}\n",
                 DRAPE_E_IO, 2, 1, "fabric", "directory");
    /* the scene file itself */
    drape_error_clear(&e);
    ck_assert_int_eq(drape_scene_load("no/such/scene.yaml", &s, &e, NULL,
                                      NULL), -1);
    ck_assert_int_eq(e.kind, DRAPE_E_IO);
}
END_TEST

START_TEST(test_bad_keys)
{
    /* unknown key with a suggestion */
    expect_error("scene: cusick\nfabric: @F\nspaceing: 2 cm\n"
                 "end: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 3, 1, "spaceing", "did you mean `spacing`");
    /* nested: end: {t_mx: ...}, key at column 7 */
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "end: {t_mx: 5 s}\n",
                 DRAPE_E_INPUT, 4, 7, "end.t_mx", "did you mean `t_max`");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "end:\n  equilibrium:\n    sped: 1 mm/s\n  t_max: 5 s\n",
                 DRAPE_E_INPUT, 6, 5, "end.equilibrium.sped", "`speed`");
    /* a key of another scene kind */
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\noverhang: 6 cm\n"
                 "end: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 1, "overhang", "cantilever scenes");
    expect_error("scene: table\nfabric: @F\n"
                 "specimen: {width: 60 cm, height: 60 cm}\n"
                 "table: {side: 30 cm}\nsupport: {diameter: 18 cm}\n"
                 "spacing: 2 cm\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 5, 1, "support", "cusick scenes");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "pins: [[0, 0]]\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 1, "pins", "hang scenes");
    /* a key of another specimen shape / table shape */
    expect_error("scene: hang\nfabric: @F\n"
                 "specimen:\n  width: 30 cm\n  height: 30 cm\n"
                 "  diameter: 30 cm\n"
                 "spacing: 2 cm\npins: [[0, 0]]\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 6, 3, "specimen.diameter", "circle");
    expect_error("scene: table\nfabric: @F\n"
                 "specimen: {width: 60 cm, height: 60 cm}\n"
                 "table: {shape: round, side: 30 cm}\n"
                 "spacing: 2 cm\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 23, "table.side", "square tables");

    /* missing required keys: reported at the mapping that lacks them */
    expect_error("fabric: @F\nspacing: 2 cm\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 1, 1, "scene", "missing required key");
    expect_error("scene: cusick\nspacing: 2 cm\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 1, 1, "fabric", "missing required key");
    expect_error("scene: cusick\nfabric: @F\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 1, 1, "spacing", "missing required key");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n",
                 DRAPE_E_INPUT, 1, 1, "end", "missing required key");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "end: {equilibrium: {}}\n",
                 DRAPE_E_INPUT, 4, 6, "end.t_max", "missing required key");
    expect_error("scene: hang\nfabric: @F\n"
                 "specimen: {width: 30 cm, height: 30 cm}\n"
                 "spacing: 2 cm\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 1, 1, "pins", "missing required key");
    expect_error("scene: hang\nfabric: @F\n"
                 "spacing: 2 cm\npins: [[0, 0]]\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 1, 1, "specimen", "missing required key");
    expect_error("scene: hang\nfabric: @F\nspecimen: {width: 30 cm}\n"
                 "spacing: 2 cm\npins: [[0, 0]]\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 3, 11, "specimen.height",
                 "missing required key");
    expect_error("scene: cantilever\nfabric: @F\n"
                 "specimen: {length: 20 cm, width: 2 cm}\n"
                 "spacing: 5 mm\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 1, 1, "overhang", "missing required key");
    expect_error("scene: table\nfabric: @F\n"
                 "specimen: {width: 60 cm, height: 60 cm}\n"
                 "spacing: 2 cm\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 1, 1, "table", "missing required key");
    expect_error("scene: table\nfabric: @F\n"
                 "specimen: {width: 60 cm, height: 60 cm}\n"
                 "table: {shape: round}\n"
                 "spacing: 2 cm\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 8, "table.diameter", "missing required");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "end: {t_max: 5 s}\noutput: {frames: {obj: true}}\n",
                 DRAPE_E_INPUT, 5, 18, "output.frames.every",
                 "missing required key");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "perturbation: {seed: 3}\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 15, "perturbation.amplitude",
                 "missing required key");
}
END_TEST

START_TEST(test_bad_types)
{
    {   /* the top level must be a mapping (yamldoc or scene.c says so) */
        drape_scene s;
        drape_error e;
        ck_assert_int_eq(load_text("- scene: cusick\n", &s, &e), -1);
        ck_assert(e.kind == DRAPE_E_INPUT || e.kind == DRAPE_E_SYNTAX);
        ck_assert_int_eq(e.line, 1);
    }
    expect_error("scene: cusick\nfabric: @F\nspecimen: 30 cm\n"
                 "spacing: 2 cm\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 3, 11, "specimen",
                 "expected a mapping ({key: value, ...}), got a scalar");
    /* the scalar is quoted back; an empty value is named as such */
    expect_error("scene: cusick\nfabric: @F\nspecimen: 30 cm\n"
                 "spacing: 2 cm\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 3, 11, "specimen", "got a scalar (\"30 cm\")");
    expect_error("scene: cusick\nfabric: @F\nspecimen:\n"
                 "spacing: 2 cm\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 3, 0, "specimen",
                 "expected a mapping ({key: value, ...}), got an empty value");
    expect_error("scene: cusick\nfabric: @F\nspacing: [1 cm, 2 cm]\n"
                 "end: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 3, 10, "spacing",
                 "expected a positive length, got a sequence");
    expect_error("scene: [cusick]\nfabric: @F\nspacing: 2 cm\n"
                 "end: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 1, 8, "scene", "got a sequence");
    expect_error("scene: cusick\nfabric: {a: b}\nspacing: 2 cm\n"
                 "end: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 2, 9, "fabric", "expected a file name");
    expect_error("scene: hang\nfabric: @F\n"
                 "specimen: {width: 30 cm, height: 30 cm}\n"
                 "spacing: 2 cm\npins: 3\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 5, 7, "pins",
                 "expected a sequence of [i, j] pairs, got a scalar");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "model: {terms: stretch}\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 16, "model.terms", "got a scalar");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "end: 5 s\n",
                 DRAPE_E_INPUT, 4, 6, "end", "expected a mapping");
    expect_error("scene: cusick\nfabric: @F\ndescription: {a: 1}\n"
                 "spacing: 2 cm\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 3, 14, "description", "expected a text");
}
END_TEST

START_TEST(test_bad_units)
{
    /* unknown unit */
    expect_error("scene: cusick\nfabric: @F\nspacing: 1 furlong\n"
                 "end: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 3, 10, "spacing", "unknown unit");
    /* wrong dimension */
    expect_error("scene: cusick\nfabric: @F\nspacing: 1 s\n"
                 "end: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 3, 10, "spacing", "expected a length");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "end: {t_max: 20 m}\n",
                 DRAPE_E_INPUT, 4, 14, "end.t_max", "expected a time");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "damping: {air: 2 N.s/m}\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 16, "damping.air", "expected a rate");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "damping: {edge: 2 1/s}\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 17, "damping.edge",
                 "expected a damping coefficient");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "damping: {shear: 2 1/s}\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 18, "damping.shear", "expected a time");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "end: {equilibrium: {speed: 1 mm}, t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 28, "end.equilibrium.speed",
                 "expected a speed");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "solver: {rtol: 1e-4 m}\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 16, "solver.rtol", "plain number without a unit");
    /* an angle is dimensionless to the unit parser: it passed as 0.087 */
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "solver: {rtol: 5 deg}\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 16, "solver.rtol", "plain number without a unit");
    /* not a number */
    expect_error("scene: cusick\nfabric: @F\nspacing: two cm\n"
                 "end: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 3, 10, "spacing", "not a number");
    expect_error("scene: cusick\nfabric: @F\nspacing:\n"
                 "end: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 3, 0, "spacing", "empty");
}
END_TEST

START_TEST(test_bad_ranges)
{
    /* non-positive, non-finite physical values */
    expect_error("scene: cusick\nfabric: @F\nspacing: 0 cm\n"
                 "end: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 3, 10, "spacing",
                 "expected a positive length, got \"0 cm\"");
    expect_error("scene: cusick\nfabric: @F\nspacing: -1 cm\n"
                 "end: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 3, 10, "spacing", "positive");
    expect_error("scene: cusick\nfabric: @F\nspacing: 1e999 m\n"
                 "end: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 3, 10, "spacing", "range");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "end: {t_max: 0 s}\n",
                 DRAPE_E_INPUT, 4, 14, "end.t_max", "positive time");
    expect_error("scene: cusick\nfabric: @F\n"
                 "specimen: {diameter: -30 cm}\nspacing: 2 cm\n"
                 "end: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 3, 22, "specimen.diameter", "positive");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "support: {diameter: 0 cm}\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 21, "support.diameter", "positive");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "end: {equilibrium: {window: 0 s}, t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 29, "end.equilibrium.window", "positive");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "end: {equilibrium: {window: 5 s}, t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 29, "end.equilibrium.window",
                 "shorter than t_max");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "output: {frames: {every: 0 s}}\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 26, "output.frames.every", "positive");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "perturbation: {amplitude: -1 mm}\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 27, "perturbation.amplitude",
                 "non-negative");
    /* a value that underflows is refused, not read as 0 */
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "perturbation: {amplitude: 1e-400 m}\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 27, "perturbation.amplitude",
                 "number out of range");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "damping: {edge: 1e-310 N.s/m}\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 17, "damping.edge", "number out of range");
    /* tolerances in (0, 1) */
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "solver: {rtol: 1.5}\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 16, "solver.rtol", "(0, 1)");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "solver: {fall_fold_time: -1 s}\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 26, "solver.fall_fold_time", NULL);
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "solver: {atol: 0}\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 16, "solver.atol", "(0, 1)");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "solver: {atol: 1}\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 16, "solver.atol", "(0, 1)");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "solver: {max_order: 6}\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 21, "solver.max_order", "1 to 5");
    /* negative damping; zero is allowed (off) */
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "damping: {air: -1 1/s}\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 16, "damping.air", "non-negative");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "damping: {air: 0 1/s, edge: -0.1 N.s/m}\n"
                 "end: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 29, "damping.edge", "non-negative");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "damping: {shear: -1 ms}\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 18, "damping.shear", "non-negative");
    /* the perturbation's form and band */
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "perturbation: {amplitude: 1 mm, kind: noise}\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 39, "perturbation.kind", "field");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "perturbation: {amplitude: 1 mm, kind: particle, lambda_min: 1 cm}\n"
                 "end: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 61, "perturbation.lambda_min", "belongs to the smooth field");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "perturbation: {amplitude: 1 mm, lambda_min: 4 cm, lambda_max: 3 cm}\n"
                 "end: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 63, "perturbation.lambda_max", "shorter than lambda_min");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "perturbation: {amplitude: 1 mm, lambda_max: 1 cm}\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 45, "perturbation.lambda_max", "give lambda_min too");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "perturbation: {amplitude: 1 mm, lambda_min: 0 cm}\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 45, "perturbation.lambda_min", "positive");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "perturbation: {amplitude: 1 mm, modes: 0}\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 40, "perturbation.modes", "1 to 1024");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "perturbation: {amplitude: 1 mm, modes: 1025}\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 40, "perturbation.modes", "1 to 1024");
    /* seeds */
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "perturbation: {amplitude: 1 mm, seed: -1}\n"
                 "end: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 39, "perturbation.seed",
                 "non-negative integer");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "perturbation: {amplitude: 1 mm, seed: 1.5}\n"
                 "end: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 39, "perturbation.seed",
                 "non-negative integer");
}
END_TEST

/* The perturbation's keys (docs/model.md 2): the form, the band, the modes. */
START_TEST(test_perturbation_keys)
{
    drape_scene s;
    drape_error e;
    char buf[1200];
    int rc = load_text("scene: cusick\nfabric: @F\nspacing: 1 cm\n"
                       "perturbation: {amplitude: 0.2 mm, seed: 4, lambda_min: 3 cm, "
                       "lambda_max: 0.2 m, modes: 128}\nend: {t_max: 5 s}\n", &s, &e);
    ck_assert_msg(rc == 0, "%s", drape_error_format(&e, buf, sizeof buf));
    ck_assert_int_eq(s.perturb_kind, DRAPE_PERTURB_FIELD);
    ck_assert_close_rel(s.perturb_amplitude, 2e-4, 1e-12);
    ck_assert_close_rel(s.perturb_lambda_min, 0.03, 1e-12);
    ck_assert_close_rel(s.perturb_lambda_max, 0.2, 1e-12);
    ck_assert_int_eq(s.perturb_modes, 128);
    double lo, hi;
    int m;
    drape_scene_perturbation_band(&s, &lo, &hi, &m);
    ck_assert(lo == s.perturb_lambda_min && hi == s.perturb_lambda_max && m == 128);
    rc = load_text("scene: cusick\nfabric: @F\nspacing: 1 cm\n"
                   "perturbation: {amplitude: 0.1 mm, kind: particle}\nend: {t_max: 5 s}\n",
                   &s, &e);
    ck_assert_msg(rc == 0, "%s", drape_error_format(&e, buf, sizeof buf));
    ck_assert_int_eq(s.perturb_kind, DRAPE_PERTURB_PARTICLE);
    /* the default band: 2 cm up to the specimen's largest dimension, and
     * no shorter than lambda_min on a small specimen */
    rc = load_text("scene: cusick\nfabric: @F\nspacing: 1 cm\n"
                   "specimen: {shape: circle, diameter: 25 cm}\nsupport: {diameter: 10 cm}\n"
                   "perturbation: {amplitude: 0.1 mm}\nend: {t_max: 5 s}\n", &s, &e);
    ck_assert_msg(rc == 0, "%s", drape_error_format(&e, buf, sizeof buf));
    drape_scene_perturbation_band(&s, &lo, &hi, &m);
    ck_assert(lo == 0.02 && fabs(hi - 0.25) < 1e-15 && m == 64);
    s.diameter = 0.015;
    drape_scene_perturbation_band(&s, &lo, &hi, &m);
    ck_assert(lo == 0.02 && hi == 0.02);
}
END_TEST

START_TEST(test_bad_names)
{
    expect_error("scene: cusik\nfabric: @F\nspacing: 2 cm\n"
                 "end: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 1, 8, "scene", "did you mean `cusick`");
    expect_error("scene: drop\nfabric: @F\nspacing: 2 cm\n"
                 "end: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 1, 8, "scene",
                 "expected one of cusick, hang, table, cantilever");
    expect_error("scene: cusick\nfabric: @F\nspecimen: {shape: disc}\n"
                 "spacing: 2 cm\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 3, 19, "specimen.shape",
                 "rectangle, circle, strip");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "solver: {integrator: cvode}\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 22, "solver.integrator",
                 "did you mean `cvode-bdf`");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "model: {terms: [stretch, bending]}\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 26, "model.terms[1]",
                 "did you mean `bend`");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "model: {terms: [bend, gravity, bend]}\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 32, "model.terms[2]", "listed twice");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "model: {terms: []}\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 16, "model.terms", "empty");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "model: {energy_form: paper}\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 22, "model.energy_form",
                 "consistent, seed");
    expect_error("scene: table\nfabric: @F\n"
                 "specimen: {width: 60 cm, height: 60 cm}\n"
                 "table: {shape: oval, diameter: 30 cm}\n"
                 "spacing: 2 cm\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 16, "table.shape", "square, round");
    /* bias and angles are accepted since issue 18 (tests/check_bias.c) */
    expect_error("scene: cantilever\nfabric: @F\n"
                 "specimen: {length: 20 cm, width: 2 cm, direction: diagonal}\n"
                 "overhang: 6 cm\nspacing: 5 mm\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 3, 51, "specimen.direction", "warp, weft, bias or an angle");
    /* a plain number is degrees; strtod's hex ("0x2D" = 45) is not */
    expect_error("scene: cantilever\nfabric: @F\n"
                 "specimen: {length: 20 cm, width: 2 cm, direction: 0x2D}\n"
                 "overhang: 6 cm\nspacing: 5 mm\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 3, 51, "specimen.direction", NULL);
    /* nor does an angle that underflows read as the warp */
    expect_error("scene: cantilever\nfabric: @F\n"
                 "specimen: {length: 20 cm, width: 2 cm, direction: 1e-400}\n"
                 "overhang: 6 cm\nspacing: 5 mm\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 3, 51, "specimen.direction", "out of range");
    /* shape must suit the scene */
    expect_error("scene: cusick\nfabric: @F\n"
                 "specimen: {shape: rectangle, width: 30 cm, height: 30 cm}\n"
                 "spacing: 2 cm\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 3, 19, "specimen.shape",
                 "cusick scene needs a circle");
    expect_error("scene: cantilever\nfabric: @F\n"
                 "specimen: {shape: rectangle, width: 30 cm, height: 30 cm}\n"
                 "overhang: 6 cm\nspacing: 2 cm\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 3, 19, "specimen.shape", "strip");
    expect_error("scene: hang\nfabric: @F\n"
                 "specimen: {shape: circle, diameter: 30 cm}\n"
                 "spacing: 2 cm\npins: [[0, 0]]\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 3, 19, "specimen.shape", "rectangle");
    /* booleans are true or false */
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "end: {t_max: 5 s}\noutput: {hdf5: yes}\n",
                 DRAPE_E_INPUT, 5, 16, "output.hdf5",
                 "expected true or false, got \"yes\"");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                 "end: {t_max: 5 s}\noutput: {hdf5: \"true\"}\n",
                 DRAPE_E_INPUT, 5, 16, "output.hdf5", "quoted");
    expect_error("scene: cusick\nfabric: @F\nspacing: 2 cm\nend: {t_max: 5 s}\n"
                 "output: {frames: {every: 1 s, obj: 1}}\n",
                 DRAPE_E_INPUT, 5, 36, "output.frames.obj",
                 "expected true or false");
}
END_TEST

START_TEST(test_bad_pins_syntax)
{
    const char *head = "scene: hang\nfabric: @F\n"
                       "specimen: {width: 30 cm, height: 30 cm}\n"
                       "spacing: 1 cm\nend: {t_max: 5 s}\n";
    char text[8192];
    snprintf(text, sizeof text, "%spins: [[0, -1], [3]]\n", head);
    expect_error(text, DRAPE_E_INPUT, 6, 17, "pins[1]", "[i, j] pair");
    snprintf(text, sizeof text, "%spins: [[0, -1], [3, 1.5]]\n", head);
    expect_error(text, DRAPE_E_INPUT, 6, 21, "pins[1][1]", "integer");
    snprintf(text, sizeof text, "%spins: []\n", head);
    expect_error(text, DRAPE_E_INPUT, 6, 7, "pins", "at least one");
    /* 65 pins: one more than DRAPE_SCENE_MAX_PINS = 64 */
    size_t k = (size_t)snprintf(text, sizeof text, "%spins: [", head);
    for (int i = 0; i < 65; i++)
        k += (size_t)snprintf(text + k, sizeof text - k, "%s[%d, 0]",
                              i ? ", " : "", i % 31);
    snprintf(text + k, sizeof text - k, "]\n");
    expect_error(text, DRAPE_E_INPUT, 6, 7, "pins", "at most 64");
}
END_TEST

START_TEST(test_bad_geometry)
{
    /* support as large as the specimen */
    expect_error("scene: cusick\nfabric: @F\n"
                 "specimen: {diameter: 30 cm}\nsupport: {diameter: 30 cm}\n"
                 "spacing: 2 cm\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 21, "support.diameter",
                 "smaller than the specimen's diameter (30 cm), got 30 cm");
    /* the default support (18 cm) and a 15 cm specimen: at the diameter */
    expect_error("scene: cusick\nfabric: @F\n"
                 "specimen: {diameter: 15 cm}\n"
                 "spacing: 1 cm\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 3, 22, "support.diameter", "got 18 cm");
    /* table larger than the specimen on one side (60 x 40 cm, side 50) */
    expect_error("scene: table\nfabric: @F\n"
                 "specimen: {width: 60 cm, height: 40 cm}\n"
                 "table: {side: 50 cm}\n"
                 "spacing: 2 cm\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 15, "table.side", "both sides");
    expect_error("scene: table\nfabric: @F\n"
                 "specimen: {width: 40 cm, height: 60 cm}\n"
                 "table: {shape: round, diameter: 40 cm}\n"
                 "spacing: 2 cm\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 33, "table.diameter", "smaller");
    /* overhang as long as the strip */
    expect_error("scene: cantilever\nfabric: @F\n"
                 "specimen: {length: 20 cm, width: 2 cm}\n"
                 "overhang: 200 mm\nspacing: 5 mm\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 11, "overhang", "shorter than the strip");
    /* spacing larger than the specimen */
    expect_error("scene: hang\nfabric: @F\n"
                 "specimen: {width: 30 cm, height: 20 cm}\n"
                 "spacing: 25 cm\npins: [[0, 0]]\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 4, 10, "spacing", "height (20 cm)");
    expect_error("scene: cantilever\nfabric: @F\n"
                 "specimen: {length: 20 cm, width: 2 cm}\n"
                 "overhang: 6 cm\nspacing: 3 cm\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 5, 10, "spacing", "width (2 cm)");
    /* a circle needs spacing <= radius (three particles across) */
    expect_error("scene: cusick\nfabric: @F\n"
                 "specimen: {diameter: 30 cm}\nsupport: {diameter: 10 cm}\n"
                 "spacing: 16 cm\nend: {t_max: 5 s}\n",
                 DRAPE_E_INPUT, 5, 10, "spacing", "radius (15 cm)");
    /* spacing equal to the radius is allowed */
    drape_scene s;
    drape_error e;
    ck_assert_int_eq(load_text("scene: cusick\nfabric: @F\n"
                               "support: {diameter: 10 cm}\n"
                               "spacing: 15 cm\nend: {t_max: 5 s}\n",
                               &s, &e), 0);
}
END_TEST

/* ---------------------------------------------- drape_scene_check_with_fabric */

static void load_ok(const char *text, drape_scene *s)
{
    drape_error e;
    char buf[1024];
    int rc = load_text(text, s, &e);
    ck_assert_msg(rc == 0, "%s", drape_error_format(&e, buf, sizeof buf));
}

static const char *hang_with_pins(const char *pins)
{
    static char text[1024];
    snprintf(text, sizeof text,
             "scene: hang\nfabric: @F\n"
             "specimen: {width: 30 cm, height: 20 cm}\n"
             "spacing: 1 cm\n"
             "pins: %s\n"
             "end: {t_max: 5 s}\n", pins);
    return text;
}

START_TEST(test_pins_in_lattice)
{
    /* 30 cm x 20 cm at 1 cm: 31 x 21 particles; i in -31..30, j in -21..20 */
    static const char *const ok[] = {"[[0, 0]]", "[[30, 20]]", "[[-31, -21]]",
                                     "[[-1, -1], [0, -1]]", NULL};
    static const char *const bad[] = {"[[31, 0]]", "[[0, 21]]", "[[-32, 0]]",
                                      "[[0, 0], [0, -22]]", NULL};
    drape_scene s;
    drape_error e;
    drape_fabric f;
    char buf[1024];
    memset(&f, 0, sizeof f);
    for (int i = 0; ok[i]; i++) {
        load_ok(hang_with_pins(ok[i]), &s);
        drape_error_clear(&e);
        ck_assert_msg(drape_scene_check_with_fabric(&s, &f, &e) == 0,
                      "%s: %s", ok[i], drape_error_format(&e, buf, sizeof buf));
    }
    for (int i = 0; bad[i]; i++) {
        load_ok(hang_with_pins(bad[i]), &s);
        drape_error_clear(&e);
        ck_assert_msg(drape_scene_check_with_fabric(&s, &f, &e) == -1,
                      "accepted %s", bad[i]);
        drape_error_format(&e, buf, sizeof buf);
        ck_assert_int_eq(e.kind, DRAPE_E_INPUT);
        ck_assert_int_eq(e.line, 5); /* the `pins` key */
        ck_assert_int_eq(e.column, 1);
        ck_assert_msg(strstr(e.msg, "31 x 21 lattice") != NULL, "%s", buf);
        ck_assert_str_eq(e.key, i == 3 ? "pins[1]" : "pins[0]");
        ck_assert_msg(strstr(e.file, "scene.yaml") != NULL, "%s", buf);
    }
    load_ok(hang_with_pins("[[31, 0]]"), &s);
    drape_error_clear(&e);
    drape_scene_check_with_fabric(&s, &f, &e);
    ck_assert_msg(strstr(e.msg, "pin [31, 0]") != NULL, "%s", e.msg);

    /* 29 cm at 1 cm: 29/1 + 1 = 30 particles, although 0.29 / 0.01 is
     * 28.999999999999996 in floating point. */
    load_ok("scene: hang\nfabric: @F\n"
            "specimen: {width: 29 cm, height: 0.29 m}\nspacing: 1 cm\n"
            "pins: [[29, 29], [-30, -30]]\nend: {t_max: 5 s}\n", &s);
    drape_error_clear(&e);
    ck_assert_msg(drape_scene_check_with_fabric(&s, &f, &e) == 0, "%s",
                  drape_error_format(&e, buf, sizeof buf));
    load_ok("scene: hang\nfabric: @F\n"
            "specimen: {width: 29 cm, height: 0.29 m}\nspacing: 1 cm\n"
            "pins: [[0, 0], [0, 30]]\nend: {t_max: 5 s}\n", &s);
    drape_error_clear(&e);
    ck_assert_int_eq(drape_scene_check_with_fabric(&s, &f, &e), -1);
    ck_assert_msg(strstr(e.msg, "30 x 30 lattice") != NULL, "%s", e.msg);
    ck_assert_str_eq(e.key, "pins[1]");
}
END_TEST

START_TEST(test_memory_estimate)
{
    drape_scene s;
    drape_error e;
    drape_fabric f;
    char buf[1024];
    memset(&f, 0, sizeof f);

    /* Cusick at 1 um: pi (0.15 / 1e-6)^2 = 7.07e10 particles */
    load_ok("scene: cusick\nfabric: @F\nspacing: 1 um\nend: {t_max: 5 s}\n",
            &s);
    drape_error_clear(&e);
    ck_assert_int_eq(drape_scene_check_with_fabric(&s, &f, &e), -1);
    drape_error_format(&e, buf, sizeof buf);
    ck_assert_int_eq(e.kind, DRAPE_E_NOMEM);
    ck_assert_int_eq(e.line, 3);
    ck_assert_int_eq(e.column, 10);
    ck_assert_str_eq(e.key, "spacing");
    ck_assert_msg(strstr(e.msg, "spacing 1 um gives ~7.1e+10 particles") !=
                      NULL, "%s", buf);

    /* (M.1), B0 + n (6 KiB + 1.25 KiB log2 n), B0 = 32 MiB: a 50 cm x 50 cm
     * cloth at 1 mm, 501^2 = 251001 particles, log2 n = 17.937:
     * 33554432 + 251001 x (6144 + 1280 x 17.937) = 7.34e9 B, under
     * 8 GiB = 8.59e9 B: accepted. */
    load_ok("scene: table\nfabric: @F\n"
            "specimen: {width: 50 cm, height: 50 cm}\ntable: {side: 30 cm}\n"
            "spacing: 1 mm\nend: {t_max: 5 s}\n", &s);
    drape_error_clear(&e);
    ck_assert_msg(drape_scene_check_with_fabric(&s, &f, &e) == 0, "%s",
                  drape_error_format(&e, buf, sizeof buf));
    /* 55 cm: 551^2 = 303601, log2 n = 18.212: 8.98e9 B > 8 GiB: refused,
     * at the spacing on line 5.  (At the flat 2 KiB per particle of drape
     * 6fe1cdc and before, 2 m x 2 m at 1 mm, 4.0 million particles, was
     * accepted.) */
    load_ok("scene: table\nfabric: @F\n"
            "specimen: {width: 55 cm, height: 55 cm}\ntable: {side: 30 cm}\n"
            "spacing: 1 mm\nend: {t_max: 5 s}\n", &s);
    drape_error_clear(&e);
    ck_assert_int_eq(drape_scene_check_with_fabric(&s, &f, &e), -1);
    ck_assert_int_eq(e.kind, DRAPE_E_NOMEM);
    ck_assert_int_eq(e.line, 5);
    ck_assert_str_eq(e.key, "spacing");
    ck_assert_msg(strstr(e.msg, "~3e+05 particles") != NULL, "%s", e.msg);
    ck_assert_msg(strstr(e.msg, "~8.36 GiB") != NULL, "%s", e.msg);
    /* the review's case: hang (30 cm) at 0.3 mm, 1001^2 particles, was
     * estimated at 2 GiB and grew past 21 GB: now refused */
    load_ok("scene: hang\nfabric: @F\n"
            "specimen: {width: 30 cm, height: 30 cm}\n"
            "spacing: 0.3 mm\npins: [[0, -1], [-1, -1]]\nend: {t_max: 3 s}\n", &s);
    drape_error_clear(&e);
    ck_assert_int_eq(drape_scene_check_with_fabric(&s, &f, &e), -1);
    ck_assert_int_eq(e.kind, DRAPE_E_NOMEM);

    /* A spacing changed after loading (as a --spacing option would) is
     * checked again: 50 cm is larger than the 20 cm height. */
    load_ok(hang_with_pins("[[0, 0]]"), &s);
    s.spacing = 0.5;
    drape_error_clear(&e);
    ck_assert_int_eq(drape_scene_check_with_fabric(&s, &f, &e), -1);
    ck_assert_int_eq(e.kind, DRAPE_E_INPUT);
    ck_assert_int_eq(e.line, 4);
    ck_assert_str_eq(e.key, "spacing");
}
END_TEST

/* Every allocation failure while loading ends in E_NOMEM, never a crash or
 * a half-filled success. */
START_TEST(test_alloc_failures)
{
    drape_scene s;
    drape_error e;
    char buf[1024];
    int done = 0;
    for (long n = 1; n < 100000 && !done; n++) {
        drape_error_clear(&e);
        drape_alloc_fail_at(n);
        int rc = drape_scene_load(tu_src("scenes/cusick.yaml"), &s, &e, NULL,
                                  NULL);
        drape_alloc_fail_at(0);
        if (rc == 0) {
            done = 1;
            ck_assert_close_rel(s.spacing, 0.01, 1e-12);
        } else {
            ck_assert_msg(e.kind == DRAPE_E_NOMEM, "fail at %ld: %s", n,
                          drape_error_format(&e, buf, sizeof buf));
        }
    }
    ck_assert(done);
}
END_TEST

/* ---------------------------------------------------- tests/bad/scene-*.yaml */

/* Each file's first line reads "# expect LINE KEY: what is wrong". */
START_TEST(test_bad_files)
{
    glob_t g;
    char buf[1024];
    int n = 0;
    ck_assert_int_eq(glob("bad/scene-*.yaml", 0, NULL, &g), 0);
    for (size_t k = 0; k < g.gl_pathc; k++) {
        const char *p = g.gl_pathv[k];
        FILE *fp = fopen(p, "r");
        char first[512], key[128];
        int line;
        ck_assert_ptr_nonnull(fp);
        ck_assert_ptr_nonnull(fgets(first, sizeof first, fp));
        fclose(fp);
        ck_assert_msg(sscanf(first, "# expect %d %127[^:]:", &line, key) == 2,
                      "%s: first line must be \"# expect LINE KEY: ...\"", p);
        drape_scene s;
        drape_error e;
        drape_fabric f;
        memset(&f, 0, sizeof f);
        drape_error_clear(&e);
        int rc = drape_scene_load(p, &s, &e, NULL, NULL);
        if (rc == 0) rc = drape_scene_check_with_fabric(&s, &f, &e);
        drape_error_format(&e, buf, sizeof buf);
        ck_assert_msg(rc == -1, "%s accepted", p);
        ck_assert_msg(e.line == line && strcmp(e.key, key) == 0,
                      "%s: expected line %d key %s, got %s", p, line, key,
                      buf);
        ck_assert_str_eq(e.file, p);
        n++;
    }
    globfree(&g);
    ck_assert_int_ge(n, 8);
}
END_TEST

/* The fall method's time scale: the pendulum time sqrt(h / g) of the free
 * length h (Cusick (D - d)/2 = 6 cm, table (60 - 36)/2 = 12 cm), 10 of
 * them for the fall and 1/32 of one per step; the scene's keys win.  The
 * fold phase: the first half of the fall at half the step, or
 * solver.fall_fold_time (0: none; at most the fall time). */
START_TEST(test_fall_params)
{
    drape_scene s;
    double t, h;
    load_example("scenes/cusick.yaml", &s);
    ck_assert_int_eq(s.specimens, 12);
    ck_assert_int_eq(s.method, DRAPE_METHOD_DEFAULT);
    drape_scene_fall_params(&s, &t, &h);
    ck_assert_close_rel(t, 10.0 * sqrt(0.06 / 9.80665), 1e-12);
    ck_assert_close_rel(h, sqrt(0.06 / 9.80665) / 32.0, 1e-12);
    double tf, hf;
    drape_scene_fall_fold(&s, t, h, &tf, &hf);
    ck_assert_close_rel(tf, 5.0 * sqrt(0.06 / 9.80665), 1e-12);
    ck_assert_close_rel(hf, sqrt(0.06 / 9.80665) / 64.0, 1e-12);
    s.fall_fold_time = 0.0;
    drape_scene_fall_fold(&s, t, h, &tf, &hf);
    ck_assert(tf == 0.0 && hf == 0.0);
    s.fall_fold_time = 2.0; /* longer than the fall: all of it */
    drape_scene_fall_fold(&s, t, h, &tf, &hf);
    ck_assert(tf == t && hf == 0.5 * h);
    drape_error e;
    ck_assert_int_eq(load_text("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                               "solver: {fall_fold_time: 0.1 s}\nend: {t_max: 5 s}\n", &s, &e), 0);
    ck_assert_double_eq_tol(s.fall_fold_time, 0.1, 1e-15);
    /* the swing past the fall time: on by default, off on the table
     * (DRAPE_FALL_SWING_TABLE), the scene's own value either way */
    load_example("scenes/cusick.yaml", &s);
    ck_assert_double_eq(drape_scene_fall_swing(&s), 0.02);
    ck_assert_int_eq(load_text("scene: cusick\nfabric: @F\nspacing: 2 cm\n"
                               "solver: {fall_swing: 0}\nend: {t_max: 5 s}\n", &s, &e), 0);
    ck_assert_double_eq(drape_scene_fall_swing(&s), 0.0);
    load_example("scenes/table.yaml", &s);
    ck_assert_double_eq(drape_scene_fall_swing(&s), 0.0);
    s.fall_swing = 0.05;
    ck_assert_double_eq(drape_scene_fall_swing(&s), 0.05);
    load_example("scenes/table.yaml", &s);
    ck_assert_int_eq(s.specimens, 10);
    drape_scene_fall_params(&s, &t, &h);
    ck_assert_close_rel(t, 10.0 * sqrt(0.12 / 9.80665), 1e-12);
    s.fall_time = 0.3;
    s.fall_step = 0.004;
    drape_scene_fall_params(&s, &t, &h);
    ck_assert_double_eq(t, 0.3);
    ck_assert_double_eq(h, 0.004);
    load_example("scenes/hang.yaml", &s);
    ck_assert_int_eq(s.specimens, 1); /* no key: one specimen */
}
END_TEST

/* ------------------------------------------- memory estimate vs real runs */

/* Run `drape run scenes/hang.yaml --spacing SPACING -q ARGS...` (at most
 * 8 ARGS, NULL-terminated) as a child and return its peak resident memory
 * in bytes as the kernel counted it (ru_maxrss, KiB on Linux);
 * *status gets its exit status.  The run is meant to pass the memory check
 * and reach its first factorisations, where its memory peaks (docs/scenes.md,
 * "Memory"); exit status 4 (a --max-steps limit) is accepted. */
static double child_peak_rss(const char *spacing, const char *const extra[], int *status)
{
    const char *args[16];
    int k = 0;
    args[k++] = "run";
    args[k++] = tu_src("scenes/hang.yaml");
    args[k++] = "--spacing";
    args[k++] = spacing;
    args[k++] = "-q";
    for (int i = 0; extra[i] && k < 15; i++) args[k++] = extra[i];
    args[k] = NULL;
    /* getrusage(RUSAGE_CHILDREN) is the largest over every reaped child:
     * an intermediate process of its own per run keeps runs apart (wait4
     * is not POSIX) */
    int fd[2];
    long rep[2] = {-1, 0}; /* exit status (-1: killed), ru_maxrss KiB */
    ck_assert_int_eq(pipe(fd), 0);
    pid_t mid = fork();
    ck_assert_msg(mid >= 0, "fork failed");
    if (mid == 0) {
        close(fd[0]);
        pid_t pid = tu_spawn_drape(args, NULL, NULL, 0);
        int st = 0;
        struct rusage ru;
        long r[2] = {-1, 0};
        if (waitpid(pid, &st, 0) == pid && WIFEXITED(st)) r[0] = WEXITSTATUS(st);
        if (getrusage(RUSAGE_CHILDREN, &ru) == 0) r[1] = ru.ru_maxrss;
        _exit(write(fd[1], r, sizeof r) == (ssize_t)sizeof r ? 0 : 1);
    }
    close(fd[1]);
    ssize_t got = read(fd[0], rep, sizeof rep);
    close(fd[0]);
    int st = 0;
    ck_assert_msg(waitpid(mid, &st, 0) == mid && WIFEXITED(st) && WEXITSTATUS(st) == 0 &&
                      got == (ssize_t)sizeof rep,
                  "could not measure drape run --spacing %s", spacing);
    ck_assert_msg(rep[0] >= 0, "drape run --spacing %s was killed", spacing);
    *status = (int)rep[0];
    return (double)rep[1] * 1024.0;
}

/* The estimate of the hang scene at a spacing (the test's own loading of
 * the shipped scene, as drape run does before it allocates). */
static double hang_estimate(double spacing, drape_scene_mem_solver solver)
{
    drape_scene s;
    drape_error e;
    char buf[1024];
    drape_error_clear(&e);
    ck_assert_msg(drape_scene_load(tu_src("scenes/hang.yaml"), &s, &e, NULL, NULL) == 0, "%s",
                  drape_error_format(&e, buf, sizeof buf));
    s.spacing = spacing;
    return drape_scene_memory_bytes(&s, solver);
}

/* The estimate must bound the peak RSS the kernel measured for a real run
 * (the review's case: hang at 0.3 mm estimated at 2 GiB grew past 21 GB),
 * and not by more than a factor 2 (an estimate that refuses runs that fit
 * is no better).  Cheap sizes, the methods whose peaks differ most:
 * dynamic cvode-bdf (the scene's, at two sizes: the estimate's growth
 * with the fill-in) and auto (CVODE and ARKODE both allocated), animate
 * and static on CHOLMOD; dynamic with KLU against the KLU estimate.  Before the fix (a flat 2 KiB per particle) the 4 mm
 * estimate was 11.3 MiB against a measured 125 MiB. */
START_TEST(test_memory_estimate_bounds_rss)
{
    static const struct {
        const char *spacing;
        double spacing_m;
        drape_scene_mem_solver solver;
        const char *args[8];
    } runs[] = {
        {"4mm", 0.004, DRAPE_SCENE_MEM_CHOLMOD, {"--max-steps", "3", NULL}},
        {"3mm", 0.003, DRAPE_SCENE_MEM_CHOLMOD, {"--max-steps", "3", NULL}},
        {"4mm", 0.004, DRAPE_SCENE_MEM_CHOLMOD, {"--max-steps", "3", "--integrator", "auto", NULL}},
        {"4mm", 0.004, DRAPE_SCENE_MEM_CHOLMOD, {"--method", "animate", "--t-max", "0.07s", NULL}},
        {"1cm", 0.01, DRAPE_SCENE_MEM_CHOLMOD, {"--method", "static", NULL}},
        {"7mm", 0.007, DRAPE_SCENE_MEM_KLU,
         {"--max-steps", "3", "--linear-solver", "klu", NULL}},
    };
    /* not under the sanitizers or memcheck (scripts/asan.sh and
     * scripts/valgrind.sh set DRAPE_TEST_SKIP_RSS): an instrumented drape
     * keeps shadow memory and a quarantine, and a child forked by a test
     * under memcheck carries memcheck's resident memory into its
     * ru_maxrss through the exec; neither is a run's */
    if (getenv("DRAPE_TEST_SKIP_RSS")) {
        fprintf(stderr, "note: test_memory_estimate_bounds_rss skipped (DRAPE_TEST_SKIP_RSS)\n");
        return;
    }
    for (size_t i = 0; i < sizeof runs / sizeof runs[0]; i++) {
        int status = -1;
        double rss = child_peak_rss(runs[i].spacing, runs[i].args, &status);
        double est = hang_estimate(runs[i].spacing_m, runs[i].solver);
        ck_assert_msg(status == 0 || status == 4, "hang --spacing %s %s: exit %d",
                      runs[i].spacing, runs[i].args[1], status);
        ck_assert_msg(rss > 0.0, "no ru_maxrss");
        ck_assert_msg(est >= rss,
                      "hang --spacing %s %s %s: estimate %.17g B below the measured peak RSS "
                      "%.17g B",
                      runs[i].spacing, runs[i].args[0], runs[i].args[1], est, rss);
        ck_assert_msg(est <= 2.0 * rss,
                      "hang --spacing %s %s %s: estimate %.17g B above twice the measured "
                      "peak RSS %.17g B",
                      runs[i].spacing, runs[i].args[0], runs[i].args[1], est, rss);
    }
}
END_TEST

Suite *scene_suite(void)
{
    Suite *s = suite_create("scene");
    TCase *tc = tcase_create("examples");
    tcase_add_checked_fixture(tc, setup, NULL);
    tcase_add_test(tc, test_cusick);
    tcase_add_test(tc, test_perturbation_keys);
    tcase_add_test(tc, test_hang);
    tcase_add_test(tc, test_table);
    tcase_add_test(tc, test_cantilever);
    tcase_add_test(tc, test_names);
    tcase_add_test(tc, test_defaults);
    tcase_add_test(tc, test_fall_params);
    tcase_add_test(tc, test_options);
    tcase_add_test(tc, test_strain_limit);
    tcase_add_test(tc, test_fabric_relative);
    tcase_add_test(tc, test_fabric_overridden);
    tcase_add_test(tc, test_alloc_failures);
    suite_add_tcase(s, tc);

    tc = tcase_create("bad");
    tcase_add_checked_fixture(tc, setup, NULL);
    tcase_add_test(tc, test_bad_fabric_missing);
    tcase_add_test(tc, test_bad_keys);
    tcase_add_test(tc, test_bad_types);
    tcase_add_test(tc, test_bad_units);
    tcase_add_test(tc, test_bad_ranges);
    tcase_add_test(tc, test_bad_names);
    tcase_add_test(tc, test_bad_pins_syntax);
    tcase_add_test(tc, test_bad_geometry);
    tcase_add_test(tc, test_bad_files);
    suite_add_tcase(s, tc);

    tc = tcase_create("with_fabric");
    tcase_add_checked_fixture(tc, setup, NULL);
    tcase_add_test(tc, test_pins_in_lattice);
    tcase_add_test(tc, test_memory_estimate);
    suite_add_tcase(s, tc);

    /* child runs of drape (a few seconds each) */
    tc = tcase_create("memory");
    tcase_set_timeout(tc, 60);
    tcase_add_test(tc, test_memory_estimate_bounds_rss);
    suite_add_tcase(s, tc);
    return s;
}
