/* scene.c: load and validate a scene file (MODEL.md sections 5 and 6).
 *
 * A scene names what to simulate: the kind of test (cusick, hang, table,
 * cantilever), the fabric file, the specimen, the lattice spacing sigma,
 * the energy terms and form (MODEL.md 3), dissipation (MODEL.md 3.6), the
 * integrator and its tolerances, the end condition (MODEL.md 6) and the
 * outputs.  docs/scenes.md lists every key, its unit, default and the
 * scenes that allow it.
 *
 * Every quantity is a unit string converted once to SI by drape_units_parse
 * and checked against its dimension.  Every error carries the scene file,
 * the 1-based line and column of the offending key or value, and its key
 * path ("end.equilibrium.speed", "pins[1]").
 *
 * What the geometry implies (lattice size, memory, consistency of
 * sizes, the fall time scale) is in scene_check.c.
 */
#include "drape/scene.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "drape/units.h"
#include "drape/yamldoc.h"

const char *const drape_integrator_names[] = {
    "auto", "arkode-imex", "arkode-dirk", "arkode-erk",
    "cvode-bdf", "gsl-msbdf", "gsl-rk8pd", "animate", NULL};

/* Defaults (docs/scenes.md). */
#define SCENE_CUSICK_DIAMETER 0.30  /* m, Cusick specimen (BS 5058) */
#define SCENE_CUSICK_SUPPORT 0.18   /* m, Cusick support disk */
#define SCENE_RTOL 1e-4
#define SCENE_ATOL 1e-7
#define SCENE_EQ_SPEED 1e-4         /* m/s, MODEL.md 6 */
#define SCENE_EQ_WINDOW 0.2         /* s */
#define SCENE_MAX_ORDER_MAX 5       /* BDF methods stop at order 5 */
#define SCENE_STRAIN_LIMIT 0.2      /* end.strain_limit (diagnose.h, docs/scenes.md) */

#define PATH_MAX_KEY DRAPE_ERROR_KEY_MAX

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

/* ------------------------------------------------------------------ */
/* Small helpers                                                        */

typedef struct scene_ctx {
    const drape_ydoc *doc;
    drape_error *err;
    unsigned flags; /* DRAPE_SCENE_LOAD_* */
} scene_ctx;

static const char *node_kind(const drape_ynode *n)
{
    if (!n) return "nothing";
    switch (n->type) {
    case DRAPE_YNODE_MAPPING: return "a mapping";
    case DRAPE_YNODE_SEQUENCE: return "a sequence";
    default: return "a scalar";
    }
}

static void key_path(char *out, size_t n, const char *parent, const char *key)
{
    if (parent && parent[0])
        snprintf(out, n, "%s.%s", parent, key);
    else
        snprintf(out, n, "%s", key);
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

/* Error at the position of the idx-th key of map. */
static int key_error(const scene_ctx *c, const drape_ynode *map, size_t idx,
                     const char *path, drape_error_kind kind,
                     const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 6, 7)))
#endif
    ;

static int key_error(const scene_ctx *c, const drape_ynode *map, size_t idx,
                     const char *path, drape_error_kind kind,
                     const char *fmt, ...)
{
    char msg[DRAPE_ERROR_MSG_MAX];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return drape_error_set(c->err, kind, c->doc->path, map->key_line[idx],
                           map->key_column[idx], path, "%s", msg);
}

static int is_in(const char *s, const char *const *list)
{
    for (size_t i = 0; list[i]; i++)
        if (strcmp(s, list[i]) == 0) return 1;
    return 0;
}

/* "a, b, c" into buf. */
static const char *name_list(const char *const *names, char *buf, size_t n)
{
    size_t k = 0;
    buf[0] = 0;
    for (size_t i = 0; names[i]; i++) {
        int r = snprintf(buf + k, n - k, "%s%s", i ? ", " : "", names[i]);
        if (r < 0 || (size_t)r >= n - k) break;
        k += (size_t)r;
    }
    return buf;
}

static int want_map(const scene_ctx *c, const drape_ynode *n, const char *path)
{
    if (n->type == DRAPE_YNODE_MAPPING) return 0;
    return drape_ynode_error(c->err, c->doc, n, path, DRAPE_E_INPUT,
                             "expected a mapping ({key: value, ...}), got %s",
                             node_kind(n));
}

/* Required key: its value, or an error at the mapping that lacks it. */
static const drape_ynode *need(const scene_ctx *c, const drape_ynode *map,
                               const char *parent, const char *key,
                               const char *example)
{
    const drape_ynode *v = drape_ynode_get(map, key, NULL);
    if (!v) {
        char path[PATH_MAX_KEY];
        key_path(path, sizeof path, parent, key);
        drape_ynode_error(c->err, c->doc, map, path, DRAPE_E_INPUT,
                          "missing required key `%s` (for example `%s`)", key,
                          example);
    }
    return v;
}


/* ------------------------------------------------------------------ */
/* Scalars                                                              */

static int want_scalar(const scene_ctx *c, const drape_ynode *n,
                       const char *path, const char *expected)
{
    if (n->type == DRAPE_YNODE_SCALAR) return 0;
    return drape_ynode_error(c->err, c->doc, n, path, DRAPE_E_INPUT,
                             "expected %s, got %s", expected, node_kind(n));
}

/* Sign requirement of a quantity. */
enum { Q_ANY, Q_POSITIVE, Q_NONNEGATIVE };

/* Parse a quantity of dimension dim; noun names it in messages
 * ("length", "time", ...). */
static int parse_quantity(const scene_ctx *c, const drape_ynode *n,
                          const char *path, drape_dim dim, const char *noun,
                          int sign, double *out)
{
    char expected[96], why[384];
    double v;
    snprintf(expected, sizeof expected, "a %s%s",
             sign == Q_POSITIVE ? "positive " :
             sign == Q_NONNEGATIVE ? "non-negative " : "", noun);
    if (want_scalar(c, n, path, expected)) return -1;
    if (drape_units_parse(n->scalar, dim, &v, why, sizeof why) != 0) {
        if (strncmp(why, "expected", 8) == 0)
            return drape_ynode_error(c->err, c->doc, n, path, DRAPE_E_INPUT,
                                     "%s", why);
        return drape_ynode_error(c->err, c->doc, n, path, DRAPE_E_INPUT,
                                 "expected %s, got \"%s\": %s", expected,
                                 n->scalar, why);
    }
    if (!isfinite(v) || (sign == Q_POSITIVE && !(v > 0.0)) ||
        (sign == Q_NONNEGATIVE && !(v >= 0.0)))
        return drape_ynode_error(c->err, c->doc, n, path, DRAPE_E_INPUT,
                                 "expected %s, got \"%s\"", expected,
                                 n->scalar);
    *out = v;
    return 0;
}

/* Optional quantity under key: leaves *out alone when absent. */
static int opt_quantity(const scene_ctx *c, const drape_ynode *map,
                        const char *parent, const char *key, drape_dim dim,
                        const char *noun, int sign, double *out,
                        const drape_ynode **node)
{
    char path[PATH_MAX_KEY];
    const drape_ynode *v = drape_ynode_get(map, key, NULL);
    if (node) *node = v;
    if (!v) return 0;
    key_path(path, sizeof path, parent, key);
    return parse_quantity(c, v, path, dim, noun, sign, out);
}

static int req_quantity(const scene_ctx *c, const drape_ynode *map,
                        const char *parent, const char *key, drape_dim dim,
                        const char *noun, int sign, const char *example,
                        double *out, const drape_ynode **node)
{
    const drape_ynode *v = need(c, map, parent, key, example);
    if (!v) return -1;
    return opt_quantity(c, map, parent, key, dim, noun, sign, out, node);
}

/* One of names[]; *idx its index.  Suggests the nearest name. */
static int parse_enum(const scene_ctx *c, const drape_ynode *n,
                      const char *path, const char *const *names, int *idx)
{
    char list[256], expected[300];
    name_list(names, list, sizeof list);
    snprintf(expected, sizeof expected, "one of %s", list);
    if (want_scalar(c, n, path, expected)) return -1;
    for (int i = 0; names[i]; i++)
        if (strcmp(n->scalar, names[i]) == 0) {
            *idx = i;
            return 0;
        }
    size_t best = (size_t)-1, limit = strlen(n->scalar) / 2;
    int bi = -1;
    if (limit < 2) limit = 2;
    for (int i = 0; names[i]; i++) {
        size_t d = drape_levenshtein(n->scalar, names[i]);
        if (d < best) {
            best = d;
            bi = i;
        }
    }
    /* a unique name that starts with the text ("cvode" -> "cvode-bdf") */
    if (n->scalar[0] && !(bi >= 0 && best <= limit)) {
        int hits = 0;
        for (int i = 0; names[i]; i++)
            if (strncmp(names[i], n->scalar, strlen(n->scalar)) == 0) {
                hits++;
                bi = i;
            }
        if (hits == 1) best = 0;
    }
    if (bi >= 0 && best <= limit)
        return drape_ynode_error(c->err, c->doc, n, path, DRAPE_E_INPUT,
                                 "expected %s, got \"%s\" (did you mean "
                                 "`%s`?)", expected, n->scalar, names[bi]);
    return drape_ynode_error(c->err, c->doc, n, path, DRAPE_E_INPUT,
                             "expected %s, got \"%s\"", expected, n->scalar);
}

static int parse_bool(const scene_ctx *c, const drape_ynode *n,
                      const char *path, int *out)
{
    static const char *const t[] = {"true", "True", "TRUE", NULL};
    static const char *const f[] = {"false", "False", "FALSE", NULL};
    if (want_scalar(c, n, path, "true or false")) return -1;
    if (!n->quoted && is_in(n->scalar, t)) {
        *out = 1;
        return 0;
    }
    if (!n->quoted && is_in(n->scalar, f)) {
        *out = 0;
        return 0;
    }
    return drape_ynode_error(c->err, c->doc, n, path, DRAPE_E_INPUT,
                             "expected true or false, got %s\"%s\"",
                             n->quoted ? "the quoted string " : "", n->scalar);
}

/* An integer written in decimal ("-1", "30"), within [lo, hi]. */
static int parse_long(const scene_ctx *c, const drape_ynode *n,
                      const char *path, const char *expected, long lo,
                      long hi, long *out)
{
    if (want_scalar(c, n, path, expected)) return -1;
    const char *s = n->scalar;
    size_t i = (s[0] == '-' || s[0] == '+') ? 1 : 0;
    int ok = s[i] != 0;
    for (; s[i]; i++)
        if (s[i] < '0' || s[i] > '9') ok = 0;
    long v = 0;
    if (ok) {
        char *end;
        errno = 0;
        v = strtol(s, &end, 10);
        if (errno == ERANGE || *end) ok = 0;
    }
    if (!ok || v < lo || v > hi)
        return drape_ynode_error(c->err, c->doc, n, path, DRAPE_E_INPUT,
                                 "expected %s, got \"%s\"", expected, s);
    *out = v;
    return 0;
}

/* ------------------------------------------------------------------ */
/* Keys that exist, but not here                                        */

typedef struct key_owner {
    const char *key;
    const char *owner; /* "cantilever scenes", "circle specimens" */
} key_owner;

/* For each key of map that is not in allowed[] but is listed in owners[],
 * report where it belongs.  `here` describes the mapping ("a cusick scene").
 * Other keys are left to drape_ynode_check_keys. */
static int check_misplaced(const scene_ctx *c, const drape_ynode *map,
                           const char *parent, const char *const *allowed,
                           const key_owner *owners, const char *here)
{
    for (size_t i = 0; i < map->n; i++) {
        if (is_in(map->keys[i], allowed)) continue;
        for (const key_owner *o = owners; o->key; o++) {
            if (strcmp(o->key, map->keys[i]) != 0) continue;
            char path[PATH_MAX_KEY];
            key_path(path, sizeof path, parent, map->keys[i]);
            return key_error(c, map, i, path, DRAPE_E_INPUT,
                             "`%s` is only allowed in %s, not in %s",
                             map->keys[i], o->owner, here);
        }
    }
    return drape_ynode_check_keys(c->doc, map, parent, allowed, c->err);
}

/* ------------------------------------------------------------------ */
/* Sections                                                             */

static int parse_fabric(const scene_ctx *c, const drape_ynode *root,
                        drape_scene *s)
{
    size_t idx;
    const drape_ynode *v = need(c, root, "", "fabric",
                                "fabric: ../fabrics/cotton-breen.yaml");
    if (!v) return -1;
    drape_ynode_get(root, "fabric", &idx);
    if (want_scalar(c, v, "fabric", "a file name")) return -1;
    if (v->scalar[0] == 0)
        return drape_ynode_error(c->err, c->doc, v, "fabric", DRAPE_E_INPUT,
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
        return drape_ynode_error(c->err, c->doc, v, "fabric", DRAPE_E_INPUT,
                                 "fabric path too long (more than %d bytes)",
                                 DRAPE_ERROR_FILE_MAX - 1);
    struct stat st;
    /* the caller names another fabric (--fabric): the scene's own need not
     * exist */
    if (c->flags & DRAPE_SCENE_LOAD_FABRIC_OVERRIDDEN) return 0;
    if (stat(s->fabric_path, &st) != 0) {
        int e = errno;
        if (e == ENOENT || e == ENOTDIR)
            return key_error(c, root, idx, "fabric", DRAPE_E_IO,
                             "fabric file `%s` not found (resolved to %s)",
                             v->scalar, s->fabric_path);
        return key_error(c, root, idx, "fabric", DRAPE_E_IO,
                         "fabric file `%s` cannot be read (resolved to %s): "
                         "%s", v->scalar, s->fabric_path, strerror(e));
    }
    if (S_ISDIR(st.st_mode))
        return key_error(c, root, idx, "fabric", DRAPE_E_IO,
                         "fabric file `%s` is a directory (resolved to %s)",
                         v->scalar, s->fabric_path);
    return 0;
}

/* specimen.direction of a strip: warp, weft, bias (45 degrees) or an
 * angle from the warp in [0, 90] degrees (a plain number is degrees; a
 * quantity may say deg or rad).  0 and 90 are the warp and weft strips. */
static int parse_direction(const scene_ctx *c, const drape_ynode *v, drape_scene *s)
{
    const char *path = "specimen.direction";
    if (want_scalar(c, v, path, "warp, weft, bias or an angle from the warp in degrees"))
        return -1;
    double deg;
    char *end;
    if (strcmp(v->scalar, "bias") == 0) {
        deg = 45.0;
    } else if (strcmp(v->scalar, "warp") == 0 || strcmp(v->scalar, "weft") == 0) {
        deg = strcmp(v->scalar, "warp") == 0 ? 0.0 : 90.0;
    } else {
        deg = strtod(v->scalar, &end);
        if (end == v->scalar || *end) { /* a quantity with an angle unit */
            double rad;
            char why[160];
            if (drape_units_parse(v->scalar, DRAPE_DIM_NONE, &rad, why, sizeof why) != 0)
                return drape_ynode_error(c->err, c->doc, v, path, DRAPE_E_INPUT,
                                         "expected warp, weft, bias or an angle from the warp "
                                         "(22.5, 22.5 deg), got \"%s\"", v->scalar);
            deg = rad * 180.0 / 3.14159265358979323846;
        }
    }
    if (!(deg >= 0.0 && deg <= 90.0))
        return drape_ynode_error(c->err, c->doc, v, path, DRAPE_E_INPUT,
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

static int parse_specimen(const scene_ctx *c, const drape_ynode *root,
                          drape_scene *s)
{
    static const char *const all[] = {"shape", "width", "height", "diameter",
                                      "length", "direction", NULL};
    static const char *const rect[] = {"shape", "width", "height", NULL};
    static const char *const circ[] = {"shape", "diameter", NULL};
    static const char *const strip[] = {"shape", "length", "width",
                                        "direction", NULL};
    static const char *const *const keys_of[] = {rect, circ, strip};
    static const key_owner owners[] = {
        {"width", "rectangle and strip specimens"},
        {"height", "rectangle specimens"},
        {"diameter", "circle specimens"},
        {"length", "strip specimens"},
        {"direction", "strip specimens"},
        {NULL, NULL}};
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
        need(c, root, "", "specimen",
             s->kind == DRAPE_SCENE_CANTILEVER
                 ? "specimen: {shape: strip, length: 20 cm, width: 2.5 cm}"
                 : "specimen: {shape: rectangle, width: 30 cm, height: "
                   "30 cm}");
        return -1;
    }
    s->at_specimen = node_pos(m);
    if (want_map(c, m, "specimen")) return -1;
    if (drape_ynode_check_keys(c->doc, m, "specimen", all, c->err)) return -1;
    if ((v = drape_ynode_get(m, "shape", NULL)) != NULL) {
        int k;
        if (parse_enum(c, v, "specimen.shape", shape_names, &k)) return -1;
        if ((drape_shape)k != want[s->kind])
            return drape_ynode_error(
                c->err, c->doc, v, "specimen.shape", DRAPE_E_INPUT,
                "expected %s (a %s scene needs a %s specimen), got \"%s\"",
                shape_names[want[s->kind]], kind_names[s->kind],
                shape_names[want[s->kind]], v->scalar);
        s->shape = (drape_shape)k;
    }
    snprintf(here, sizeof here, "a %s specimen", shape_names[s->shape]);
    if (check_misplaced(c, m, "specimen", keys_of[s->shape], owners, here))
        return -1;

    switch (s->shape) {
    case DRAPE_SHAPE_RECTANGLE:
        if (req_quantity(c, m, "specimen", "width", DRAPE_DIM_LENGTH,
                         "length", Q_POSITIVE, "width: 30 cm", &s->width,
                         NULL) ||
            req_quantity(c, m, "specimen", "height", DRAPE_DIM_LENGTH,
                         "length", Q_POSITIVE, "height: 30 cm", &s->height,
                         NULL))
            return -1;
        break;
    case DRAPE_SHAPE_CIRCLE:
        s->diameter = SCENE_CUSICK_DIAMETER;
        if (opt_quantity(c, m, "specimen", "diameter", DRAPE_DIM_LENGTH,
                         "length", Q_POSITIVE, &s->diameter, &v))
            return -1;
        if (v) s->at_specimen = node_pos(v);
        break;
    case DRAPE_SHAPE_STRIP:
        s->strip_dir = DRAPE_WARP;
        if (req_quantity(c, m, "specimen", "length", DRAPE_DIM_LENGTH,
                         "length", Q_POSITIVE, "length: 20 cm", &s->length,
                         NULL) ||
            req_quantity(c, m, "specimen", "width", DRAPE_DIM_LENGTH,
                         "length", Q_POSITIVE, "width: 2.5 cm", &s->width,
                         NULL))
            return -1;
        if ((v = drape_ynode_get(m, "direction", NULL)) != NULL &&
            parse_direction(c, v, s))
            return -1;
        break;
    }
    return 0;
}

static int parse_support(const scene_ctx *c, const drape_ynode *root,
                         drape_scene *s)
{
    static const char *const keys[] = {"diameter", NULL};
    const drape_ynode *m = drape_ynode_get(root, "support", NULL), *v;
    s->support_diameter = SCENE_CUSICK_SUPPORT;
    s->at_support = s->at_specimen;
    if (!m) return 0;
    s->at_support = node_pos(m);
    if (want_map(c, m, "support") ||
        drape_ynode_check_keys(c->doc, m, "support", keys, c->err) ||
        opt_quantity(c, m, "support", "diameter", DRAPE_DIM_LENGTH, "length",
                     Q_POSITIVE, &s->support_diameter, &v))
        return -1;
    if (v) s->at_support = node_pos(v);
    return 0;
}

static int parse_table(const scene_ctx *c, const drape_ynode *root,
                       drape_scene *s)
{
    static const char *const all[] = {"shape", "side", "diameter", NULL};
    static const char *const square[] = {"shape", "side", NULL};
    static const char *const round[] = {"shape", "diameter", NULL};
    static const key_owner owners[] = {{"side", "square tables"},
                                       {"diameter", "round tables"},
                                       {NULL, NULL}};
    const drape_ynode *m = need(c, root, "", "table",
                                "table: {shape: square, side: 36 cm}"), *v;
    int k = DRAPE_TABLE_SQUARE;
    if (!m) return -1;
    if (want_map(c, m, "table") ||
        drape_ynode_check_keys(c->doc, m, "table", all, c->err))
        return -1;
    if ((v = drape_ynode_get(m, "shape", NULL)) != NULL &&
        parse_enum(c, v, "table.shape", table_shape_names, &k))
        return -1;
    s->table_shape = (drape_table_shape)k;
    if (check_misplaced(c, m, "table", k == DRAPE_TABLE_SQUARE ? square : round,
                        owners, k == DRAPE_TABLE_SQUARE ? "a square table"
                                                        : "a round table"))
        return -1;
    if (req_quantity(c, m, "table", k == DRAPE_TABLE_SQUARE ? "side" : "diameter",
                     DRAPE_DIM_LENGTH, "length", Q_POSITIVE,
                     k == DRAPE_TABLE_SQUARE ? "side: 36 cm" : "diameter: 36 cm",
                     &s->table_size, &v))
        return -1;
    s->at_table = node_pos(v);
    return 0;
}

static int parse_perturbation(const scene_ctx *c, const drape_ynode *root,
                              drape_scene *s)
{
    static const char *const keys[] = {"amplitude", "seed", NULL};
    const drape_ynode *m = drape_ynode_get(root, "perturbation", NULL), *v;
    if (!m) return 0;
    if (want_map(c, m, "perturbation") ||
        drape_ynode_check_keys(c->doc, m, "perturbation", keys, c->err) ||
        req_quantity(c, m, "perturbation", "amplitude", DRAPE_DIM_LENGTH,
                     "length", Q_NONNEGATIVE, "amplitude: 0.1 mm",
                     &s->perturb_amplitude, NULL))
        return -1;
    s->has_perturbation = 1;
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
            if (errno == ERANGE) big = 1;
            if (big || *end) ok = 0;
        }
        if (!ok) {
            if (want_scalar(c, v, "perturbation.seed",
                            "a non-negative integer"))
                return -1;
            return drape_ynode_error(c->err, c->doc, v, "perturbation.seed",
                                     DRAPE_E_INPUT,
                                     "expected a non-negative integer%s, got "
                                     "\"%s\"", big ? " (this one is too "
                                     "large)" : "", t);
        }
    }
    return 0;
}

static int parse_pins(const scene_ctx *c, const drape_ynode *root,
                      drape_scene *s)
{
    size_t idx;
    const drape_ynode *m = need(c, root, "", "pins", "pins: [[0, -1], [-1, -1]]");
    char path[PATH_MAX_KEY];
    if (!m) return -1;
    drape_ynode_get(root, "pins", &idx);
    s->at_pins.line = root->key_line[idx];
    s->at_pins.column = root->key_column[idx];
    if (m->type != DRAPE_YNODE_SEQUENCE)
        return drape_ynode_error(c->err, c->doc, m, "pins", DRAPE_E_INPUT,
                                 "expected a sequence of [i, j] pairs, got %s",
                                 node_kind(m));
    if (m->n == 0)
        return drape_ynode_error(c->err, c->doc, m, "pins", DRAPE_E_INPUT,
                                 "expected at least one [i, j] pair, got an "
                                 "empty sequence");
    if (m->n > DRAPE_SCENE_MAX_PINS)
        return drape_ynode_error(c->err, c->doc, m, "pins", DRAPE_E_INPUT,
                                 "expected at most %d pins, got %zu",
                                 DRAPE_SCENE_MAX_PINS, m->n);
    for (size_t k = 0; k < m->n; k++) {
        const drape_ynode *p = m->items[k];
        snprintf(path, sizeof path, "pins[%zu]", k);
        if (p->type != DRAPE_YNODE_SEQUENCE || p->n != 2)
            return drape_ynode_error(
                c->err, c->doc, p, path, DRAPE_E_INPUT,
                "expected an [i, j] pair of lattice indices, got %s%s",
                p->type == DRAPE_YNODE_SEQUENCE ? "a sequence of length "
                                                : node_kind(p),
                p->type == DRAPE_YNODE_SEQUENCE
                    ? (p->n == 1 ? "1" : p->n == 0 ? "0" : "more than 2")
                    : "");
        for (int d = 0; d < 2; d++) {
            char ipath[PATH_MAX_KEY];
            long v;
            snprintf(ipath, sizeof ipath, "pins[%zu][%d]", k, d);
            if (parse_long(c, p->items[d], ipath,
                           "an integer lattice index (-1 is the last)",
                           -1000000000L, 1000000000L, &v))
                return -1;
            s->pins[k][d] = (int)v;
        }
    }
    s->n_pins = (int)m->n;
    return 0;
}

static int parse_model(const scene_ctx *c, const drape_ynode *root,
                       drape_scene *s)
{
    static const char *const keys[] = {"energy_form", "terms", NULL};
    const drape_ynode *m = drape_ynode_get(root, "model", NULL), *v;
    s->energy_form = DRAPE_FORM_CONSISTENT;
    s->terms = DRAPE_TERM_ALL;
    if (!m) return 0;
    if (want_map(c, m, "model") ||
        drape_ynode_check_keys(c->doc, m, "model", keys, c->err))
        return -1;
    if ((v = drape_ynode_get(m, "energy_form", NULL)) != NULL) {
        int k;
        if (parse_enum(c, v, "model.energy_form", form_names, &k)) return -1;
        s->energy_form = (drape_energy_form)k;
    }
    if ((v = drape_ynode_get(m, "terms", NULL)) != NULL) {
        char list[128];
        name_list(drape_term_names, list, sizeof list);
        if (v->type != DRAPE_YNODE_SEQUENCE || v->n == 0)
            return drape_ynode_error(
                c->err, c->doc, v, "model.terms", DRAPE_E_INPUT,
                "expected a non-empty sequence of terms (%s), got %s", list,
                v->type == DRAPE_YNODE_SEQUENCE ? "an empty sequence"
                                                : node_kind(v));
        s->terms = 0;
        for (size_t k = 0; k < v->n; k++) {
            char path[PATH_MAX_KEY];
            int t;
            snprintf(path, sizeof path, "model.terms[%zu]", k);
            if (parse_enum(c, v->items[k], path, drape_term_names, &t)) return -1;
            if (s->terms & (1u << t))
                return drape_ynode_error(c->err, c->doc, v->items[k], path,
                                         DRAPE_E_INPUT,
                                         "term `%s` is listed twice",
                                         drape_term_names[t]);
            s->terms |= 1u << t;
        }
    }
    return 0;
}

static int parse_damping(const scene_ctx *c, const drape_ynode *root,
                         drape_scene *s)
{
    static const char *const keys[] = {"air", "edge", NULL};
    const drape_ynode *m = drape_ynode_get(root, "damping", NULL);
    if (!m) return 0;
    if (want_map(c, m, "damping") ||
        drape_ynode_check_keys(c->doc, m, "damping", keys, c->err) ||
        opt_quantity(c, m, "damping", "air", DRAPE_DIM_RATE, "rate (1/s)",
                     Q_NONNEGATIVE, &s->damping_air, NULL) ||
        opt_quantity(c, m, "damping", "edge", DRAPE_DIM_DAMPING,
                     "damping coefficient (N.s/m)", Q_NONNEGATIVE,
                     &s->damping_edge, NULL))
        return -1;
    return 0;
}

/* A tolerance: a plain number in (0, 1). */
static int parse_tol(const scene_ctx *c, const drape_ynode *m,
                     const char *key, double *out)
{
    char path[PATH_MAX_KEY];
    const drape_ynode *v = drape_ynode_get(m, key, NULL);
    double t = 0.0;
    if (!v) return 0;
    key_path(path, sizeof path, "solver", key);
    if (parse_quantity(c, v, path, DRAPE_DIM_NONE, "number in (0, 1)", Q_ANY,
                       &t))
        return -1;
    if (!(t > 0.0 && t < 1.0))
        return drape_ynode_error(c->err, c->doc, v, path, DRAPE_E_INPUT,
                                 "expected a number in (0, 1), got \"%s\"",
                                 v->scalar);
    *out = t;
    return 0;
}

static int parse_solver(const scene_ctx *c, const drape_ynode *root,
                        drape_scene *s)
{
    static const char *const keys[] = {"integrator", "rtol", "atol",
                                       "max_order", "method", "fall_time",
                                       "fall_step", "substeps", "fall_swing", NULL};
    const drape_ynode *m = drape_ynode_get(root, "solver", NULL), *v;
    snprintf(s->integrator, sizeof s->integrator, "%s", "auto");
    s->rtol = SCENE_RTOL;
    s->atol = SCENE_ATOL;
    s->fall_swing = -1.0; /* DRAPE_FALL_SWING */
    if (!m) return 0;
    if (want_map(c, m, "solver") ||
        drape_ynode_check_keys(c->doc, m, "solver", keys, c->err))
        return -1;
    if ((v = drape_ynode_get(m, "integrator", NULL)) != NULL) {
        int k;
        if (parse_enum(c, v, "solver.integrator", drape_integrator_names, &k))
            return -1;
        snprintf(s->integrator, sizeof s->integrator, "%s",
                 drape_integrator_names[k]);
    }
    if (parse_tol(c, m, "rtol", &s->rtol) || parse_tol(c, m, "atol", &s->atol))
        return -1;
    if ((v = drape_ynode_get(m, "max_order", NULL)) != NULL) {
        long k;
        if (parse_long(c, v, "solver.max_order", "an integer from 1 to 5", 1,
                       SCENE_MAX_ORDER_MAX, &k))
            return -1;
        s->max_order = (int)k;
    }
    if ((v = drape_ynode_get(m, "method", NULL)) != NULL) {
        int k;
        /* "default" is what an absent key means, not a value to write */
        if (parse_enum(c, v, "solver.method", drape_method_names + 1, &k))
            return -1;
        s->method = (drape_method)(k + 1);
    }
    if ((v = drape_ynode_get(m, "fall_time", NULL)) != NULL &&
        parse_quantity(c, v, "solver.fall_time", DRAPE_DIM_TIME, "time",
                       Q_POSITIVE, &s->fall_time))
        return -1;
    if ((v = drape_ynode_get(m, "fall_step", NULL)) != NULL &&
        parse_quantity(c, v, "solver.fall_step", DRAPE_DIM_TIME, "time",
                       Q_POSITIVE, &s->fall_step))
        return -1;
    if ((v = drape_ynode_get(m, "fall_swing", NULL)) != NULL) {
        if (parse_quantity(c, v, "solver.fall_swing", DRAPE_DIM_NONE,
                           "fraction of the peak kinetic energy", Q_NONNEGATIVE,
                           &s->fall_swing))
            return -1;
        if (!(s->fall_swing < 1.0))
            return drape_ynode_error(c->err, c->doc, v, "solver.fall_swing", DRAPE_E_INPUT,
                                     "expected a fraction in [0, 1), got \"%s\"", v->scalar);
    }
    if ((v = drape_ynode_get(m, "substeps", NULL)) != NULL) {
        long k;
        if (parse_long(c, v, "solver.substeps", "an integer from 1 to "
                       "10000", 1, DRAPE_ANIMATE_SUBSTEPS_MAX, &k))
            return -1;
        s->substeps = (int)k;
    }
    return 0;
}

static int parse_end(const scene_ctx *c, const drape_ynode *root,
                     drape_scene *s)
{
    static const char *const keys[] = {"equilibrium", "t_max", "strain_limit", NULL};
    static const char *const eq_keys[] = {"speed", "window", NULL};
    const drape_ynode *m = need(c, root, "", "end", "end: {t_max: 20 s}");
    const drape_ynode *eq, *win = NULL;
    if (!m) return -1;
    s->eq_speed = SCENE_EQ_SPEED;
    s->eq_window = SCENE_EQ_WINDOW;
    s->strain_limit = SCENE_STRAIN_LIMIT;
    if (want_map(c, m, "end") ||
        drape_ynode_check_keys(c->doc, m, "end", keys, c->err))
        return -1;
    if ((eq = drape_ynode_get(m, "equilibrium", NULL)) != NULL) {
        if (want_map(c, eq, "end.equilibrium") ||
            drape_ynode_check_keys(c->doc, eq, "end.equilibrium", eq_keys,
                                   c->err) ||
            opt_quantity(c, eq, "end.equilibrium", "speed", DRAPE_DIM_SPEED,
                         "speed", Q_POSITIVE, &s->eq_speed, NULL) ||
            opt_quantity(c, eq, "end.equilibrium", "window", DRAPE_DIM_TIME,
                         "time", Q_POSITIVE, &s->eq_window, &win))
            return -1;
        s->has_equilibrium = 1;
    }
    if (req_quantity(c, m, "end", "t_max", DRAPE_DIM_TIME, "time", Q_POSITIVE,
                     "t_max: 20 s", &s->t_max, NULL) ||
        opt_quantity(c, m, "end", "strain_limit", DRAPE_DIM_NONE,
                     "strain (a fraction: 0.2 = 20 %)", Q_POSITIVE,
                     &s->strain_limit, NULL))
        return -1;
    if (s->has_equilibrium && !(s->eq_window < s->t_max)) {
        char a[32], b[32];
        snprintf(a, sizeof a, "%g s", s->eq_window);
        snprintf(b, sizeof b, "%g s", s->t_max);
        return drape_ynode_error(c->err, c->doc, win ? win : eq,
                                 "end.equilibrium.window", DRAPE_E_INPUT,
                                 "expected a window shorter than t_max (%s), "
                                 "got %s", b, a);
    }
    return 0;
}

static int parse_output(const scene_ctx *c, const drape_ynode *root,
                        drape_scene *s)
{
    static const char *const keys[] = {"frames", "hdf5", NULL};
    static const char *const fr_keys[] = {"every", "obj", NULL};
    const drape_ynode *m = drape_ynode_get(root, "output", NULL), *v;
    if (!m) return 0;
    if (want_map(c, m, "output") ||
        drape_ynode_check_keys(c->doc, m, "output", keys, c->err))
        return -1;
    if ((v = drape_ynode_get(m, "frames", NULL)) != NULL) {
        const drape_ynode *o;
        if (want_map(c, v, "output.frames") ||
            drape_ynode_check_keys(c->doc, v, "output.frames", fr_keys,
                                   c->err) ||
            req_quantity(c, v, "output.frames", "every", DRAPE_DIM_TIME,
                         "time", Q_POSITIVE, "every: 0.05 s", &s->frame_every,
                         NULL))
            return -1;
        if ((o = drape_ynode_get(v, "obj", NULL)) != NULL &&
            parse_bool(c, o, "output.frames.obj", &s->out_obj))
            return -1;
        s->has_frames = 1;
    }
    if ((v = drape_ynode_get(m, "hdf5", NULL)) != NULL &&
        parse_bool(c, v, "output.hdf5", &s->out_hdf5))
        return -1;
    return 0;
}

/* ------------------------------------------------------------------ */
/* Public                                                               */

static int parse_scene(const scene_ctx *c, drape_scene *s)
{
    static const char *const all[] = {
        "scene", "fabric", "description", "specimen", "spacing",
        "perturbation", "model", "damping", "solver", "end", "output",
        "specimens", "support", "table", "overhang", "pins", NULL};
    static const key_owner owners[] = {{"support", "cusick scenes"},
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

    if (want_map(c, root, "")) return -1;
    if (drape_ynode_check_keys(c->doc, root, "", all, c->err)) return -1;
    if (!(v = need(c, root, "", "scene", "scene: cusick")) ||
        parse_enum(c, v, "scene", kind_names, &k))
        return -1;
    s->kind = (drape_scene_kind)k;
    for (n = 0; common[n]; n++) allowed[n] = common[n];
    allowed[n++] = own[k];
    allowed[n] = NULL;
    snprintf(here, sizeof here, "a %s scene", kind_names[k]);
    if (check_misplaced(c, root, "", allowed, owners, here)) return -1;

    if (parse_fabric(c, root, s)) return -1;
    if ((v = drape_ynode_get(root, "description", NULL)) != NULL &&
        want_scalar(c, v, "description", "a text"))
        return -1;
    if (parse_specimen(c, root, s)) return -1;
    if (req_quantity(c, root, "", "spacing", DRAPE_DIM_LENGTH, "length",
                     Q_POSITIVE, "spacing: 1 cm", &s->spacing, &v))
        return -1;
    s->at_spacing = node_pos(v);
    s->specimens = 1;
    if ((v = drape_ynode_get(root, "specimens", NULL)) != NULL) {
        long nsp;
        if (parse_long(c, v, "specimens", "an integer from 1 to "
                       DRAPE_SCENE_SPECIMENS_MAX_TEXT, 1,
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
        if (req_quantity(c, root, "", "overhang", DRAPE_DIM_LENGTH, "length",
                         Q_POSITIVE, "overhang: 6 cm", &s->overhang, &v))
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
    (void)warn;
    (void)warn_ctx;

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
    scene_ctx c = {doc, err, flags};
    if (parse_scene(&c, s) != 0) goto out;
    if (drape_scene_check_geometry(s, err) != 0) goto out;
    rc = 0;
out:
    drape_ydoc_free(doc);
    return rc;
}
