/* scene.c: load and validate a scene file (docs/model.md sections 5 and 6).
 *
 * A scene names what to simulate: the kind of test (cusick, hang, table,
 * cantilever), the fabric file, the specimen, the lattice spacing sigma,
 * the energy terms and form (docs/model.md 3), dissipation (docs/model.md 3.6), the
 * integrator and its tolerances, the end condition (docs/model.md 6) and the
 * outputs.  docs/scenes.md lists every key, its unit, default and the
 * scenes that allow it.
 *
 * Every quantity is a unit string converted once to SI by drape_units_parse
 * and checked against its dimension.  Every error carries the scene file,
 * the 1-based line and column of the offending key or value, and its key
 * path ("end.equilibrium.speed", "pins[1]").
 *
 * What the geometry implies (lattice size, memory, consistency of
 * sizes, the fall time scale) is in scene_check.c; reading typed values
 * with their errors, in yread.c.
 */
#include "drape/scene.h"

#include <errno.h>
#include <ctype.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "drape/perturbation.h"
#include "drape/units.h"
#include "drape/yamldoc.h"
#include "yread.h"

const char *const drape_integrator_names[] = {
    "auto", "arkode-imex", "arkode-dirk", "arkode-erk",
    "cvode-bdf", "gsl-msbdf", "gsl-rk8pd", "animate", NULL};

/* Defaults (docs/scenes.md). */
#define SCENE_CUSICK_DIAMETER 0.30  /* m, Cusick specimen (BS 5058) */
#define SCENE_CUSICK_SUPPORT 0.18   /* m, Cusick support disk */
#define SCENE_RTOL 1e-4
#define SCENE_ATOL 1e-7
#define SCENE_EQ_SPEED 1e-4         /* m/s, docs/model.md 6 */
#define SCENE_EQ_WINDOW 0.2         /* s */
#define SCENE_MAX_ORDER_MAX 5       /* BDF methods stop at order 5 */
#define SCENE_STRAIN_LIMIT 0.2      /* end.strain_limit (diagnose.h, docs/scenes.md) */

static const char *const kind_names[] = {"cusick", "hang", "table",
                                         "cantilever", NULL};
static const char *const shape_names[] = {"rectangle", "circle", "strip",
                                          NULL};
static const char *const form_names[] = {"consistent", "seed", NULL};

/* drape_method order */
const char *const drape_method_names[] = {"default", "dynamic", "static", "fall", "animate", NULL};
const char *const drape_term_names[] = {"stretch", "bend", "shear", "gravity", "bias",
                                        NULL};
int drape_scene_terms_parse(const char *list, unsigned *terms)
{
    char buf[256], *save = NULL;
    unsigned m = 0;
    if ((size_t)snprintf(buf, sizeof buf, "%s", list) >= sizeof buf) return -1;
    for (char *t = strtok_r(buf, ",", &save); t; t = strtok_r(NULL, ",", &save)) {
        int k = 0;
        while (drape_term_names[k] && strcmp(drape_term_names[k], t) != 0) k++;
        if (!drape_term_names[k]) return -1;
        m |= 1u << k;
    }
    if (!m) return -1;
    *terms = m;
    return 0;
}

static const char *const table_shape_names[] = {"square", "round", NULL};

const char *drape_scene_kind_name(drape_scene_kind k)
{
    if ((int)k < 0 || (int)k > (int)DRAPE_SCENE_CANTILEVER) return "unknown";
    return kind_names[k];
}

const char *drape_energy_form_name(drape_energy_form f)
{
    if ((int)f < 0 || (int)f > (int)DRAPE_FORM_SEED) return "unknown";
    return form_names[f];
}

static drape_scene_pos node_pos(const drape_ynode *n)
{
    drape_scene_pos p = {0, 0};
    if (n) {
        p.line = n->line;
        p.column = n->column;
    }
    return p;
}

/* ------------------------------------------------------------------ */
/* Sections                                                             */

static int parse_fabric(const drape_yread *c, const drape_ynode *root, drape_scene *s)
{
    size_t idx;
    const drape_ynode *v =
        drape_yread_need(c, root, "", "fabric", "fabric: ../fabrics/cotton-breen.yaml");
    if (!v) return -1;
    drape_ynode_get(root, "fabric", &idx);
    if (drape_yread_want_scalar(c, v, "fabric", "a file name")) return -1;
    if (v->scalar[0] == 0)
        return drape_yread_error(c, v, "fabric", DRAPE_E_INPUT,
                                 "expected a file name, got an empty value");
    const char *dir = c->doc->dir ? c->doc->dir : ".";
    int r;
    size_t nd = strlen(dir);
    if (v->scalar[0] == '/' || strcmp(dir, ".") == 0 || nd == 0)
        r = snprintf(s->fabric_path, sizeof s->fabric_path, "%s", v->scalar);
    else
        r = snprintf(s->fabric_path, sizeof s->fabric_path, "%s%s%s", dir,
                     dir[nd - 1] == '/' ? "" : "/", v->scalar);
    if (r < 0 || (size_t)r >= sizeof s->fabric_path)
        return drape_yread_error(c, v, "fabric", DRAPE_E_INPUT,
                                 "fabric path too long (more than %d bytes)",
                                 DRAPE_ERROR_FILE_MAX - 1);
    struct stat st;
    /* the caller names another fabric (--fabric): the scene's own drape_yread_need not
     * exist */
    if (c->flags & DRAPE_SCENE_LOAD_FABRIC_OVERRIDDEN) return 0;
    if (stat(s->fabric_path, &st) != 0) {
        int e = errno;
        if (e == ENOENT || e == ENOTDIR)
            return drape_yread_key_error(c, root, idx, "fabric", DRAPE_E_IO,
                                         "fabric file `%s` not found (resolved to %s)", v->scalar,
                                         s->fabric_path);
        return drape_yread_key_error(c, root, idx, "fabric", DRAPE_E_IO,
                                     "fabric file `%s` cannot be read (resolved to %s): "
                                     "%s",
                                     v->scalar, s->fabric_path, strerror(e));
    }
    if (S_ISDIR(st.st_mode))
        return drape_yread_key_error(c, root, idx, "fabric", DRAPE_E_IO,
                                     "fabric file `%s` is a directory (resolved to %s)", v->scalar,
                                     s->fabric_path);
    return 0;
}

/* specimen.direction of a strip: warp, weft, bias (45 degrees) or an
 * angle from the warp in [0, 90] degrees (a plain number is degrees; a
 * quantity may say deg or rad).  0 and 90 are the warp and weft strips. */
static int parse_direction(const drape_yread *c, const drape_ynode *v, drape_scene *s)
{
    const char *path = "specimen.direction";
    if (drape_yread_want_scalar(c, v, path,
                                "warp, weft, bias or an angle from the warp in degrees"))
        return -1;
    double deg;
    char *end;
    if (strcmp(v->scalar, "bias") == 0) {
        deg = 45.0;
    } else if (strcmp(v->scalar, "warp") == 0 || strcmp(v->scalar, "weft") == 0) {
        deg = strcmp(v->scalar, "warp") == 0 ? 0.0 : 90.0;
    } else {
        /* a plain decimal is degrees (no hex, inf or nan: strtod takes
         * "0x2D" as 45) */
        int plain = v->scalar[0] != 0;
        for (const char *p = v->scalar; *p && plain; p++)
            if (!strchr("0123456789.eE+-", *p)) plain = 0;
        int range = 0;
        deg = plain ? drape_units_strtod(v->scalar, &end, &range) : 0.0;
        if (plain && end != v->scalar && !*end && range)
            return drape_yread_error(c, v, path, DRAPE_E_INPUT,
                                     "number out of range: \"%s\"", v->scalar);
        if (!plain || end == v->scalar || *end) { /* a quantity with an angle unit */
            double rad;
            char why[160];
            if (drape_units_parse(v->scalar, DRAPE_DIM_NONE, &rad, why, sizeof why) != 0)
                return drape_yread_error(c, v, path, DRAPE_E_INPUT,
                                         "expected warp, weft, bias or an angle from the warp "
                                         "(22.5, 22.5 deg), got \"%s\"", v->scalar);
            deg = rad * 180.0 / 3.14159265358979323846;
        }
    }
    if (!(deg >= 0.0 && deg <= 90.0))
        return drape_yread_error(c, v, path, DRAPE_E_INPUT,
                                 "the strip's angle from the warp must be in [0, 90] degrees "
                                 "(the fabric is symmetric about its yarns), got \"%s\"",
                                 v->scalar);
    s->strip_oblique = 0;
    s->strip_angle = deg;
    if (deg == 0.0) s->strip_dir = DRAPE_WARP;
    else if (deg == 90.0) s->strip_dir = DRAPE_WEFT;
    else s->strip_oblique = 1;
    return 0;
}

static int parse_specimen(const drape_yread *c, const drape_ynode *root, drape_scene *s)
{
    static const char *const all[] = {"shape", "width", "height", "diameter",
                                      "length", "direction", NULL};
    static const char *const rect[] = {"shape", "width", "height", NULL};
    static const char *const circ[] = {"shape", "diameter", NULL};
    static const char *const strip[] = {"shape", "length", "width",
                                        "direction", NULL};
    static const char *const *const keys_of[] = {rect, circ, strip};
    static const drape_yread_owner owners[] = {
        {"width", "rectangle and strip specimens"}, {"height", "rectangle specimens"},
        {"diameter", "circle specimens"},           {"length", "strip specimens"},
        {"direction", "strip specimens"},           {NULL, NULL}};
    static const drape_shape want[] = {DRAPE_SHAPE_CIRCLE,
                                       DRAPE_SHAPE_RECTANGLE,
                                       DRAPE_SHAPE_RECTANGLE,
                                       DRAPE_SHAPE_STRIP};
    const drape_ynode *m = drape_ynode_get(root, "specimen", NULL), *v;
    char here[64];

    s->shape = want[s->kind];
    if (!m) {
        if (s->kind == DRAPE_SCENE_CUSICK) {
            s->diameter = SCENE_CUSICK_DIAMETER;
            return 0;
        }
        drape_yread_need(c, root, "", "specimen",
                         s->kind == DRAPE_SCENE_CANTILEVER
                             ? "specimen: {shape: strip, length: 20 cm, width: 2.5 cm}"
                             : "specimen: {shape: rectangle, width: 30 cm, height: "
                               "30 cm}");
        return -1;
    }
    s->at_specimen = node_pos(m);
    if (drape_yread_want_map(c, m, "specimen")) return -1;
    if (drape_ynode_check_keys(c->doc, m, "specimen", all, c->err)) return -1;
    if ((v = drape_ynode_get(m, "shape", NULL)) != NULL) {
        int k;
        if (drape_yread_enum(c, v, "specimen.shape", shape_names, &k)) return -1;
        if ((drape_shape)k != want[s->kind])
            return drape_ynode_error(
                c->err, c->doc, v, "specimen.shape", DRAPE_E_INPUT,
                "expected %s (a %s scene needs a %s specimen), got \"%s\"",
                shape_names[want[s->kind]], kind_names[s->kind],
                shape_names[want[s->kind]], v->scalar);
        s->shape = (drape_shape)k;
    }
    snprintf(here, sizeof here, "a %s specimen", shape_names[s->shape]);
    if (drape_yread_misplaced(c, m, "specimen", keys_of[s->shape], owners, here)) return -1;

    switch (s->shape) {
    case DRAPE_SHAPE_RECTANGLE:
        if (drape_yread_req_quantity(c, m, "specimen", "width", DRAPE_DIM_LENGTH, "length",
                                     DRAPE_YREAD_POSITIVE, "width: 30 cm", &s->width, NULL) ||
            drape_yread_req_quantity(c, m, "specimen", "height", DRAPE_DIM_LENGTH, "length",
                                     DRAPE_YREAD_POSITIVE, "height: 30 cm", &s->height, NULL))
            return -1;
        break;
    case DRAPE_SHAPE_CIRCLE:
        s->diameter = SCENE_CUSICK_DIAMETER;
        if (drape_yread_opt_quantity(c, m, "specimen", "diameter", DRAPE_DIM_LENGTH, "length",
                                     DRAPE_YREAD_POSITIVE, &s->diameter, &v))
            return -1;
        if (v) s->at_specimen = node_pos(v);
        break;
    case DRAPE_SHAPE_STRIP:
        s->strip_dir = DRAPE_WARP;
        if (drape_yread_req_quantity(c, m, "specimen", "length", DRAPE_DIM_LENGTH, "length",
                                     DRAPE_YREAD_POSITIVE, "length: 20 cm", &s->length, NULL) ||
            drape_yread_req_quantity(c, m, "specimen", "width", DRAPE_DIM_LENGTH, "length",
                                     DRAPE_YREAD_POSITIVE, "width: 2.5 cm", &s->width, NULL))
            return -1;
        if ((v = drape_ynode_get(m, "direction", NULL)) != NULL &&
            parse_direction(c, v, s))
            return -1;
        break;
    }
    return 0;
}

static int parse_support(const drape_yread *c, const drape_ynode *root, drape_scene *s)
{
    static const char *const keys[] = {"diameter", NULL};
    const drape_ynode *m = drape_ynode_get(root, "support", NULL), *v;
    s->support_diameter = SCENE_CUSICK_SUPPORT;
    s->at_support = s->at_specimen;
    if (!m) return 0;
    s->at_support = node_pos(m);
    if (drape_yread_want_map(c, m, "support") ||
        drape_ynode_check_keys(c->doc, m, "support", keys, c->err) ||
        drape_yread_opt_quantity(c, m, "support", "diameter", DRAPE_DIM_LENGTH, "length",
                                 DRAPE_YREAD_POSITIVE, &s->support_diameter, &v))
        return -1;
    if (v) s->at_support = node_pos(v);
    return 0;
}

static int parse_table(const drape_yread *c, const drape_ynode *root, drape_scene *s)
{
    static const char *const all[] = {"shape", "side", "diameter", NULL};
    static const char *const square[] = {"shape", "side", NULL};
    static const char *const round[] = {"shape", "diameter", NULL};
    static const drape_yread_owner owners[] = {
        {"side", "square tables"}, {"diameter", "round tables"}, {NULL, NULL}};
    const drape_ynode *m = drape_yread_need(c, root, "", "table",
                                            "table: {shape: square, side: 36 cm}"),
                      *v;
    int k = DRAPE_TABLE_SQUARE;
    if (!m) return -1;
    if (drape_yread_want_map(c, m, "table") ||
        drape_ynode_check_keys(c->doc, m, "table", all, c->err))
        return -1;
    if ((v = drape_ynode_get(m, "shape", NULL)) != NULL &&
        drape_yread_enum(c, v, "table.shape", table_shape_names, &k))
        return -1;
    s->table_shape = (drape_table_shape)k;
    if (drape_yread_misplaced(c, m, "table", k == DRAPE_TABLE_SQUARE ? square : round, owners,
                              k == DRAPE_TABLE_SQUARE ? "a square table" : "a round table"))
        return -1;
    if (drape_yread_req_quantity(c, m, "table", k == DRAPE_TABLE_SQUARE ? "side" : "diameter",
                                 DRAPE_DIM_LENGTH, "length", DRAPE_YREAD_POSITIVE,
                                 k == DRAPE_TABLE_SQUARE ? "side: 36 cm" : "diameter: 36 cm",
                                 &s->table_size, &v))
        return -1;
    s->at_table = node_pos(v);
    return 0;
}

const char *const drape_perturb_kind_names[] = {"field", "particle", NULL};

static int parse_perturbation(const drape_yread *c, const drape_ynode *root, drape_scene *s)
{
    static const char *const keys[] = {"amplitude", "seed", "kind", "lambda_min",
                                       "lambda_max", "modes", NULL};
    static const char *const field_keys[] = {"lambda_min", "lambda_max", "modes"};
    const drape_ynode *m = drape_ynode_get(root, "perturbation", NULL), *v, *vmin = NULL;
    if (!m) return 0;
    if (drape_yread_want_map(c, m, "perturbation") ||
        drape_ynode_check_keys(c->doc, m, "perturbation", keys, c->err) ||
        drape_yread_req_quantity(c, m, "perturbation", "amplitude", DRAPE_DIM_LENGTH, "length",
                                 DRAPE_YREAD_NONNEGATIVE, "amplitude: 0.1 mm",
                                 &s->perturb_amplitude, NULL))
        return -1;
    s->has_perturbation = 1;
    if ((v = drape_ynode_get(m, "kind", NULL)) != NULL) {
        int k;
        if (drape_yread_enum(c, v, "perturbation.kind", drape_perturb_kind_names, &k)) return -1;
        s->perturb_kind = (drape_perturb_kind)k;
    }
    if (s->perturb_kind == DRAPE_PERTURB_PARTICLE)
        for (size_t k = 0; k < sizeof field_keys / sizeof *field_keys; k++)
            if ((v = drape_ynode_get(m, field_keys[k], NULL)) != NULL) {
                char path[DRAPE_YREAD_PATH_MAX];
                drape_yread_path(path, sizeof path, "perturbation", field_keys[k]);
                return drape_yread_error(c, v, path, DRAPE_E_INPUT,
                                         "`%s` belongs to the smooth field (kind: field); "
                                         "the particle form has only amplitude and seed",
                                         field_keys[k]);
            }
    if (drape_yread_opt_quantity(c, m, "perturbation", "lambda_min", DRAPE_DIM_LENGTH,
                                 "length", DRAPE_YREAD_POSITIVE, &s->perturb_lambda_min,
                                 &vmin) ||
        drape_yread_opt_quantity(c, m, "perturbation", "lambda_max", DRAPE_DIM_LENGTH,
                                 "length", DRAPE_YREAD_POSITIVE, &s->perturb_lambda_max, &v))
        return -1;
    if (vmin && v && s->perturb_lambda_max < s->perturb_lambda_min)
        return drape_yread_error(c, v, "perturbation.lambda_max", DRAPE_E_INPUT,
                                 "the longest wavelength (%g m) is shorter than lambda_min "
                                 "(%g m)", s->perturb_lambda_max, s->perturb_lambda_min);
    if (!vmin && v && s->perturb_lambda_max < DRAPE_FIELD_LAMBDA_MIN)
        return drape_yread_error(c, v, "perturbation.lambda_max", DRAPE_E_INPUT,
                                 "the longest wavelength (%g m) is shorter than the default "
                                 "lambda_min (%g m): give lambda_min too",
                                 s->perturb_lambda_max, DRAPE_FIELD_LAMBDA_MIN);
    if ((v = drape_ynode_get(m, "modes", NULL)) != NULL) {
        long nm;
        if (drape_yread_long(c, v, "perturbation.modes", "an integer from 1 to 1024", 1,
                             DRAPE_FIELD_MODES_MAX, &nm))
            return -1;
        s->perturb_modes = (int)nm;
    }
    if ((v = drape_ynode_get(m, "seed", NULL)) != NULL) {
        const char *t = v->type == DRAPE_YNODE_SCALAR ? v->scalar : "";
        int ok = v->type == DRAPE_YNODE_SCALAR && t[0] != 0;
        for (size_t i = 0; ok && t[i]; i++)
            if (t[i] < '0' || t[i] > '9') ok = 0;
        int big = 0;
        if (ok) {
            char *end;
            errno = 0;
            s->perturb_seed = strtoul(t, &end, 10);
            if (errno == ERANGE || s->perturb_seed > DRAPE_SCENE_SEED_MAX) big = 1;
            if (big || *end) ok = 0;
        }
        if (!ok) {
            if (drape_yread_want_scalar(c, v, "perturbation.seed", "a non-negative integer"))
                return -1;
            return drape_yread_error(c, v, "perturbation.seed",
                                     DRAPE_E_INPUT,
                                     "expected a non-negative integer%s, got "
                                     "\"%s\"", big ? " up to "
                                     DRAPE_SCENE_SEED_MAX_TEXT : "", t);
        }
    }
    return 0;
}

static int parse_pins(const drape_yread *c, const drape_ynode *root, drape_scene *s)
{
    size_t idx;
    const drape_ynode *m = drape_yread_need(c, root, "", "pins", "pins: [[0, -1], [-1, -1]]");
    char path[DRAPE_YREAD_PATH_MAX];
    if (!m) return -1;
    drape_ynode_get(root, "pins", &idx);
    s->at_pins.line = root->key_line[idx];
    s->at_pins.column = root->key_column[idx];
    if (m->type != DRAPE_YNODE_SEQUENCE)
        return drape_yread_error(c, m, "pins", DRAPE_E_INPUT,
                                 "expected a sequence of [i, j] pairs, got %s",
                                 drape_yread_kind(m));
    if (m->n == 0)
        return drape_yread_error(c, m, "pins", DRAPE_E_INPUT,
                                 "expected at least one [i, j] pair, got an "
                                 "empty sequence");
    if (m->n > DRAPE_SCENE_MAX_PINS)
        return drape_yread_error(c, m, "pins", DRAPE_E_INPUT,
                                 "expected at most %d pins, got %zu",
                                 DRAPE_SCENE_MAX_PINS, m->n);
    for (size_t k = 0; k < m->n; k++) {
        const drape_ynode *p = m->items[k];
        snprintf(path, sizeof path, "pins[%zu]", k);
        if (p->type != DRAPE_YNODE_SEQUENCE || p->n != 2)
            return drape_yread_error(c, p, path, DRAPE_E_INPUT,
                                     "expected an [i, j] pair of lattice indices, got %s%s",
                                     p->type == DRAPE_YNODE_SEQUENCE ? "a sequence of length "
                                                                     : drape_yread_kind(p),
                                     p->type == DRAPE_YNODE_SEQUENCE ? (p->n == 1   ? "1"
                                                                        : p->n == 0 ? "0"
                                                                                    : "more than 2")
                                                                     : "");
        for (int d = 0; d < 2; d++) {
            char ipath[DRAPE_YREAD_PATH_MAX];
            long v;
            snprintf(ipath, sizeof ipath, "pins[%zu][%d]", k, d);
            if (drape_yread_long(c, p->items[d], ipath, "an integer lattice index (-1 is the last)",
                                 -1000000000L, 1000000000L, &v))
                return -1;
            s->pins[k][d] = (int)v;
        }
    }
    s->n_pins = (int)m->n;
    return 0;
}

static int parse_model(const drape_yread *c, const drape_ynode *root, drape_scene *s)
{
    static const char *const keys[] = {"energy_form", "terms", NULL};
    const drape_ynode *m = drape_ynode_get(root, "model", NULL), *v;
    s->energy_form = DRAPE_FORM_CONSISTENT;
    s->terms = DRAPE_TERM_ALL;
    if (!m) return 0;
    if (drape_yread_want_map(c, m, "model") ||
        drape_ynode_check_keys(c->doc, m, "model", keys, c->err))
        return -1;
    if ((v = drape_ynode_get(m, "energy_form", NULL)) != NULL) {
        int k;
        if (drape_yread_enum(c, v, "model.energy_form", form_names, &k)) return -1;
        s->energy_form = (drape_energy_form)k;
    }
    if ((v = drape_ynode_get(m, "terms", NULL)) != NULL) {
        char list[128];
        drape_yread_name_list(drape_term_names, list, sizeof list);
        if (v->type != DRAPE_YNODE_SEQUENCE || v->n == 0)
            return drape_yread_error(c, v, "model.terms", DRAPE_E_INPUT,
                                     "expected a non-empty sequence of terms (%s), got %s", list,
                                     v->type == DRAPE_YNODE_SEQUENCE ? "an empty sequence"
                                                                     : drape_yread_kind(v));
        s->terms = 0;
        for (size_t k = 0; k < v->n; k++) {
            char path[DRAPE_YREAD_PATH_MAX];
            int t;
            snprintf(path, sizeof path, "model.terms[%zu]", k);
            if (drape_yread_enum(c, v->items[k], path, drape_term_names, &t)) return -1;
            if (s->terms & (1u << t))
                return drape_yread_error(c, v->items[k], path,
                                         DRAPE_E_INPUT,
                                         "term `%s` is listed twice",
                                         drape_term_names[t]);
            s->terms |= 1u << t;
        }
    }
    return 0;
}

static int parse_damping(const drape_yread *c, const drape_ynode *root, drape_scene *s)
{
    static const char *const keys[] = {"air", "edge", "shear", NULL};
    const drape_ynode *m = drape_ynode_get(root, "damping", NULL);
    s->damping_shear = DRAPE_SCENE_DAMPING_SHEAR_FABRIC;
    if (!m) return 0;
    if (drape_yread_want_map(c, m, "damping") ||
        drape_ynode_check_keys(c->doc, m, "damping", keys, c->err) ||
        drape_yread_opt_quantity(c, m, "damping", "air", DRAPE_DIM_RATE, "rate (1/s)",
                                 DRAPE_YREAD_NONNEGATIVE, &s->damping_air, NULL) ||
        drape_yread_opt_quantity(c, m, "damping", "edge", DRAPE_DIM_DAMPING,
                                 "damping coefficient (N.s/m)", DRAPE_YREAD_NONNEGATIVE,
                                 &s->damping_edge, NULL) ||
        drape_yread_opt_quantity(c, m, "damping", "shear", DRAPE_DIM_TIME,
                                 "time (s)",
                                 DRAPE_YREAD_NONNEGATIVE, &s->damping_shear, NULL))
        return -1;
    return 0;
}

/* A tolerance: a plain number in (0, 1). */
static int parse_tol(const drape_yread *c, const drape_ynode *m, const char *key, double *out)
{
    char path[DRAPE_YREAD_PATH_MAX];
    const drape_ynode *v = drape_ynode_get(m, key, NULL);
    double t = 0.0;
    if (!v) return 0;
    drape_yread_path(path, sizeof path, "solver", key);
    /* no unit: the parser takes angles as dimensionless ("5 deg" was
     * 0.087), and atol's units are those of the state (m and m/s) */
    for (const char *q = v->type == DRAPE_YNODE_SCALAR ? v->scalar : ""; *q; q++)
        if (isalpha((unsigned char)*q) && *q != 'e' && *q != 'E')
            return drape_yread_error(c, v, path, DRAPE_E_INPUT,
                                     "a tolerance is a plain number without a unit (atol "
                                     "is in m and m/s), got \"%s\"", v->scalar);
    if (drape_yread_quantity(c, v, path, DRAPE_DIM_NONE, "number in (0, 1)", DRAPE_YREAD_ANY, &t))
        return -1;
    if (!(t > 0.0 && t < 1.0))
        return drape_yread_error(c, v, path, DRAPE_E_INPUT,
                                 "expected a number in (0, 1), got \"%s\"",
                                 v->scalar);
    *out = t;
    return 0;
}

static int parse_solver(const drape_yread *c, const drape_ynode *root, drape_scene *s)
{
    static const char *const keys[] = {"integrator", "rtol", "atol",
                                       "max_order", "method", "fall_time",
                                       "fall_step", "substeps", "fall_swing", "fall_tol",
                                       "fall_fold_time", "fall_retry", NULL};
    const drape_ynode *m = drape_ynode_get(root, "solver", NULL), *v;
    snprintf(s->integrator, sizeof s->integrator, "%s", "auto");
    s->rtol = SCENE_RTOL;
    s->atol = SCENE_ATOL;
    s->fall_swing = -1.0; /* the scene's default: drape_scene_fall_swing */
    s->fall_fold_time = -1.0; /* DRAPE_FALL_FOLD_TIME of the fall time */
    if (!m) return 0;
    if (drape_yread_want_map(c, m, "solver") ||
        drape_ynode_check_keys(c->doc, m, "solver", keys, c->err))
        return -1;
    if ((v = drape_ynode_get(m, "integrator", NULL)) != NULL) {
        int k;
        if (drape_yread_enum(c, v, "solver.integrator", drape_integrator_names, &k)) return -1;
        snprintf(s->integrator, sizeof s->integrator, "%s",
                 drape_integrator_names[k]);
    }
    if (parse_tol(c, m, "rtol", &s->rtol) || parse_tol(c, m, "atol", &s->atol))
        return -1;
    if ((v = drape_ynode_get(m, "max_order", NULL)) != NULL) {
        long k;
        if (drape_yread_long(c, v, "solver.max_order", "an integer from 1 to 5", 1,
                             SCENE_MAX_ORDER_MAX, &k))
            return -1;
        s->max_order = (int)k;
    }
    if ((v = drape_ynode_get(m, "method", NULL)) != NULL) {
        int k;
        /* "default" is what an absent key means, not a value to write */
        if (drape_yread_enum(c, v, "solver.method", drape_method_names + 1, &k)) return -1;
        s->method = (drape_method)(k + 1);
    }
    if ((v = drape_ynode_get(m, "fall_time", NULL)) != NULL &&
        drape_yread_quantity(c, v, "solver.fall_time", DRAPE_DIM_TIME, "time", DRAPE_YREAD_POSITIVE,
                             &s->fall_time))
        return -1;
    if ((v = drape_ynode_get(m, "fall_step", NULL)) != NULL &&
        drape_yread_quantity(c, v, "solver.fall_step", DRAPE_DIM_TIME, "time", DRAPE_YREAD_POSITIVE,
                             &s->fall_step))
        return -1;
    if ((v = drape_ynode_get(m, "fall_fold_time", NULL)) != NULL &&
        drape_yread_quantity(c, v, "solver.fall_fold_time", DRAPE_DIM_TIME, "time",
                             DRAPE_YREAD_NONNEGATIVE, &s->fall_fold_time))
        return -1;
    if ((v = drape_ynode_get(m, "fall_retry", NULL)) != NULL &&
        drape_yread_quantity(c, v, "solver.fall_retry", DRAPE_DIM_TIME, "time",
                             DRAPE_YREAD_NONNEGATIVE, &s->fall_retry))
        return -1;
    if ((v = drape_ynode_get(m, "fall_tol", NULL)) != NULL &&
        drape_yread_quantity(c, v, "solver.fall_tol", DRAPE_DIM_LENGTH, "length",
                             DRAPE_YREAD_NONNEGATIVE, &s->fall_tol))
        return -1;
    if ((v = drape_ynode_get(m, "fall_swing", NULL)) != NULL) {
        if (drape_yread_quantity(c, v, "solver.fall_swing", DRAPE_DIM_NONE,
                                 "fraction of the peak kinetic energy", DRAPE_YREAD_NONNEGATIVE,
                                 &s->fall_swing))
            return -1;
        if (!(s->fall_swing < 1.0))
            return drape_yread_error(c, v, "solver.fall_swing", DRAPE_E_INPUT,
                                     "expected a fraction in [0, 1), got \"%s\"", v->scalar);
    }
    if ((v = drape_ynode_get(m, "substeps", NULL)) != NULL) {
        long k;
        if (drape_yread_long(c, v, "solver.substeps",
                             "an integer from 1 to "
                             "10000",
                             1, DRAPE_ANIMATE_SUBSTEPS_MAX, &k))
            return -1;
        s->substeps = (int)k;
    }
    return 0;
}

static int parse_end(const drape_yread *c, const drape_ynode *root, drape_scene *s)
{
    static const char *const keys[] = {"equilibrium", "t_max", "strain_limit", NULL};
    static const char *const eq_keys[] = {"speed", "window", NULL};
    const drape_ynode *m = drape_yread_need(c, root, "", "end", "end: {t_max: 20 s}");
    const drape_ynode *eq, *win = NULL;
    if (!m) return -1;
    s->eq_speed = SCENE_EQ_SPEED;
    s->eq_window = SCENE_EQ_WINDOW;
    s->strain_limit = SCENE_STRAIN_LIMIT;
    if (drape_yread_want_map(c, m, "end") || drape_ynode_check_keys(c->doc, m, "end", keys, c->err))
        return -1;
    if ((eq = drape_ynode_get(m, "equilibrium", NULL)) != NULL) {
        if (drape_yread_want_map(c, eq, "end.equilibrium") ||
            drape_ynode_check_keys(c->doc, eq, "end.equilibrium", eq_keys, c->err) ||
            drape_yread_opt_quantity(c, eq, "end.equilibrium", "speed", DRAPE_DIM_SPEED, "speed",
                                     DRAPE_YREAD_POSITIVE, &s->eq_speed, NULL) ||
            drape_yread_opt_quantity(c, eq, "end.equilibrium", "window", DRAPE_DIM_TIME, "time",
                                     DRAPE_YREAD_POSITIVE, &s->eq_window, &win))
            return -1;
        s->has_equilibrium = 1;
    }
    if (drape_yread_req_quantity(c, m, "end", "t_max", DRAPE_DIM_TIME, "time", DRAPE_YREAD_POSITIVE,
                                 "t_max: 20 s", &s->t_max, NULL) ||
        drape_yread_opt_quantity(c, m, "end", "strain_limit", DRAPE_DIM_NONE,
                                 "strain (a fraction: 0.2 = 20 %)", DRAPE_YREAD_POSITIVE,
                                 &s->strain_limit, NULL))
        return -1;
    if (s->has_equilibrium && !(s->eq_window < s->t_max)) {
        char a[32], b[32];
        snprintf(a, sizeof a, "%g s", s->eq_window);
        snprintf(b, sizeof b, "%g s", s->t_max);
        return drape_yread_error(c, win ? win : eq,
                                 "end.equilibrium.window", DRAPE_E_INPUT,
                                 "expected a window shorter than t_max (%s), "
                                 "got %s", b, a);
    }
    return 0;
}

static int parse_output(const drape_yread *c, const drape_ynode *root, drape_scene *s)
{
    static const char *const keys[] = {"frames", "hdf5", NULL};
    static const char *const fr_keys[] = {"every", "obj", NULL};
    const drape_ynode *m = drape_ynode_get(root, "output", NULL), *v;
    if (!m) return 0;
    if (drape_yread_want_map(c, m, "output") ||
        drape_ynode_check_keys(c->doc, m, "output", keys, c->err))
        return -1;
    if ((v = drape_ynode_get(m, "frames", NULL)) != NULL) {
        const drape_ynode *o;
        if (drape_yread_want_map(c, v, "output.frames") ||
            drape_ynode_check_keys(c->doc, v, "output.frames", fr_keys, c->err) ||
            drape_yread_req_quantity(c, v, "output.frames", "every", DRAPE_DIM_TIME, "time",
                                     DRAPE_YREAD_POSITIVE, "every: 0.05 s", &s->frame_every, NULL))
            return -1;
        if ((o = drape_ynode_get(v, "obj", NULL)) != NULL &&
            drape_yread_bool(c, o, "output.frames.obj", &s->out_obj))
            return -1;
        s->has_frames = 1;
    }
    if ((v = drape_ynode_get(m, "hdf5", NULL)) != NULL &&
        drape_yread_bool(c, v, "output.hdf5", &s->out_hdf5))
        return -1;
    return 0;
}

/* ------------------------------------------------------------------ */
/* Public                                                               */

static int parse_scene(const drape_yread *c, drape_scene *s)
{
    static const char *const all[] = {
        "scene", "fabric", "description", "specimen", "spacing",
        "perturbation", "model", "damping", "solver", "end", "output",
        "specimens", "support", "table", "overhang", "pins", NULL};
    static const drape_yread_owner owners[] = {{"support", "cusick scenes"},
                                               {"table", "table scenes"},
                                               {"overhang", "cantilever scenes"},
                                               {"pins", "hang scenes"},
                                               {NULL, NULL}};
    /* Root keys allowed per kind: the common ones plus its own. */
    static const char *const common[] = {
        "scene", "fabric", "description", "specimen", "spacing",
        "perturbation", "model", "damping", "solver", "end", "output",
        "specimens", NULL};
    static const char *const own[] = {"support", "pins", "table", "overhang"};
    const char *allowed[16];
    const drape_ynode *root = c->doc->root, *v;
    char here[64];
    size_t n = 0;
    int k;

    if (drape_yread_want_map(c, root, "")) return -1;
    if (drape_ynode_check_keys(c->doc, root, "", all, c->err)) return -1;
    if (!(v = drape_yread_need(c, root, "", "scene", "scene: cusick")) ||
        drape_yread_enum(c, v, "scene", kind_names, &k))
        return -1;
    s->kind = (drape_scene_kind)k;
    for (n = 0; common[n]; n++) allowed[n] = common[n];
    allowed[n++] = own[k];
    allowed[n] = NULL;
    snprintf(here, sizeof here, "a %s scene", kind_names[k]);
    if (drape_yread_misplaced(c, root, "", allowed, owners, here)) return -1;

    if (parse_fabric(c, root, s)) return -1;
    if ((v = drape_ynode_get(root, "description", NULL)) != NULL &&
        drape_yread_want_scalar(c, v, "description", "a text"))
        return -1;
    if (parse_specimen(c, root, s)) return -1;
    if (drape_yread_req_quantity(c, root, "", "spacing", DRAPE_DIM_LENGTH, "length",
                                 DRAPE_YREAD_POSITIVE, "spacing: 1 cm", &s->spacing, &v))
        return -1;
    s->at_spacing = node_pos(v);
    s->specimens = 1;
    if ((v = drape_ynode_get(root, "specimens", NULL)) != NULL) {
        long nsp;
        if (drape_yread_long(c, v, "specimens",
                             "an integer from 1 to " DRAPE_SCENE_SPECIMENS_MAX_TEXT, 1,
                             DRAPE_SCENE_SPECIMENS_MAX, &nsp))
            return -1;
        s->specimens = (int)nsp;
    }
    switch (s->kind) {
    case DRAPE_SCENE_CUSICK:
        if (parse_support(c, root, s)) return -1;
        break;
    case DRAPE_SCENE_TABLE:
        if (parse_table(c, root, s)) return -1;
        break;
    case DRAPE_SCENE_CANTILEVER:
        if (drape_yread_req_quantity(c, root, "", "overhang", DRAPE_DIM_LENGTH, "length",
                                     DRAPE_YREAD_POSITIVE, "overhang: 6 cm", &s->overhang, &v))
            return -1;
        s->at_overhang = node_pos(v);
        break;
    case DRAPE_SCENE_HANG:
        if (parse_pins(c, root, s)) return -1;
        break;
    }
    if (parse_perturbation(c, root, s) || parse_model(c, root, s) ||
        parse_damping(c, root, s) || parse_solver(c, root, s) ||
        parse_end(c, root, s) || parse_output(c, root, s))
        return -1;
    return 0;
}


int drape_scene_load(const char *path, drape_scene *s, drape_error *err,
                     drape_warn_fn warn, void *warn_ctx)
{
    return drape_scene_load_flags(path, 0u, s, err, warn, warn_ctx);
}

int drape_scene_load_flags(const char *path, unsigned flags, drape_scene *s,
                           drape_error *err, drape_warn_fn warn, void *warn_ctx)
{
    drape_ydoc *doc = NULL;
    int rc = -1;

    if (!path || !s)
        return drape_error_set(err, DRAPE_E_INTERNAL, NULL, 0, 0, NULL,
                               "drape_scene_load: NULL argument");
    memset(s, 0, sizeof *s);
    if (strlen(path) >= sizeof s->path)
        return drape_error_set(err, DRAPE_E_IO, NULL, 0, 0, NULL,
                               "scene path too long (more than %d bytes)",
                               DRAPE_ERROR_FILE_MAX - 1);
    snprintf(s->path, sizeof s->path, "%s", path);
    doc = drape_ydoc_load(path, err);
    if (!doc) goto out;
    drape_yread c = {doc, err, flags, warn, warn_ctx};
    if (parse_scene(&c, s) != 0) goto out;
    if (drape_scene_check_geometry(s, err) != 0) goto out;
    rc = 0;
out:
    drape_ydoc_free(doc);
    return rc;
}
