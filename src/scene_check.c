/* scene_check.c: what a loaded scene's geometry implies (scene.h): sizes
 * that must fit together (support or table inside the specimen, overhang
 * shorter than the strip, a spacing the specimen can hold), the lattice
 * it will build and the memory that takes, pins inside it, and the fall
 * method's time scale.  Errors name the scene file, line and key of the
 * value at fault (drape_scene_pos).  scene.c reads the file key by key.
 *
 * Lattice size (used for pins and the memory estimate; it must agree with
 * the lattice builder, docs/model.md section 2): a side of length W at spacing s
 * holds floor(W/s + 1e-9) + 1 particles (the 1e-9 absorbs rounding in W/s,
 * e.g. 0.30/0.01 = 29.999999999999996); a circle of diameter d is centred on
 * a lattice point and holds about pi (d / 2s)^2 particles.
 *
 * Memory estimate (drape_scene_memory_bytes; docs/scenes.md, "Memory"):
 * the peak resident memory of one run, measured with getrusage's
 * ru_maxrss on the hang scene from 254 to 184 000 free particles for
 * every method, integrator and linear solver, is bounded by
 *     bytes = B0 + n (a + c log2 n)                               (M.1)
 * with n the lattice's particle count.  B0 = 32 MiB is the process itself
 * (the libraries: 27-29 MiB at 254 particles).  The linear part a holds
 * the model (state, masses, elements), the sparse Jacobian K and D (a
 * particle couples to about 21 others through bending hinges: ~190
 * nonzeros of 8 + 4 bytes in each, twice in the first-order system), the
 * integrator's vectors and the assembled Schur matrix; the n log2 n part
 * is the fill-in of CHOLMOD's supernodal Cholesky factor of the 3 nf x
 * 3 nf Schur matrix (or the static solver's Hessian) under a
 * nested-dissection-like ordering of the planar lattice (George 1973:
 * O(n log n) nonzeros for a 2-D grid).  Measured per particle above B0:
 * 15.7 KiB at 959, 21 KiB at 22 800 particles, rising by about
 * 1.2 KiB per doubling.  KLU's LU of the 6 nf first-order Jacobian
 * (--linear-solver klu, AMD ordering, no nested dissection) fills faster:
 *     bytes = B0 + n (a_klu + c_klu sqrt n)                        (M.2)
 * (21.6 KiB per particle at 959, 36.9 KiB at 5774; O(n^1.5) fill, the
 * AMD bound for a 2-D grid).  A flat 2 KiB per particle would be 10-25
 * times too low (hang at 0.3 mm: 2 GiB estimated, 21 GB resident).  Scenes above 8 GiB or 20
 * million particles are refused before anything is allocated.
 */
#include "drape/scene.h"

#include <math.h>
#include <stdio.h>

#include "drape/perturbation.h"
#include "drape/units.h"

/* Lattice counting slack and memory limits (see the header comment). */
#define SCENE_GRID_EPS 1e-9
#define SCENE_PI 3.14159265358979323846
#define SCENE_MAX_BYTES (8.0 * 1024.0 * 1024.0 * 1024.0)
/* (M.1) and (M.2), bytes (see the header comment and docs/scenes.md). */
#define SCENE_MEM_BASE (32.0 * 1024.0 * 1024.0)
#define SCENE_MEM_LINEAR (6.0 * 1024.0)
#define SCENE_MEM_FILL_LOG2 (1.25 * 1024.0)
#define SCENE_MEM_KLU_LINEAR (12.0 * 1024.0)
#define SCENE_MEM_KLU_FILL_SQRT (0.45 * 1024.0)
#define SCENE_MAX_PARTICLES 2.0e7

/* A length in SI, formatted in a readable unit ("18 cm", "2.5 mm"). */
static const char *fmt_len(double m, char *buf, size_t n)
{
    double a = fabs(m);
    if (a >= 1.0 || a == 0.0)
        snprintf(buf, n, "%.4g m", m);
    else if (a >= 1e-2)
        snprintf(buf, n, "%.4g cm", m * 1e2);
    else if (a >= 1e-3)
        snprintf(buf, n, "%.4g mm", m * 1e3);
    else
        snprintf(buf, n, "%.4g um", m * 1e6);
    return buf;
}

/* ------------------------------------------------------------------ */
/* Checks across keys (also run by drape_scene_check_with_fabric)      */

static int pos_error(drape_error *err, const drape_scene *s,
                     drape_scene_pos p, const char *key,
                     drape_error_kind kind, const char *msg)
{
    if (p.line == DRAPE_SCENE_POS_COMMAND_LINE) { /* an option's value */
        char opt[64];
        snprintf(opt, sizeof opt, "--%s", key);
        return drape_error_set(err, kind == DRAPE_E_INPUT ? DRAPE_E_USAGE : kind, NULL, 0, 0,
                               opt, "%s", msg);
    }
    return drape_error_set(err, kind, s->path, p.line, p.column, key, "%s",
                           msg);
}

/* Particles along a side of length w at spacing sp (docs/model.md 2). */
static double grid_count(double w, double sp)
{
    return floor(w / sp + SCENE_GRID_EPS) + 1.0;
}

/* Bounding grid (ni along the weft, nj along the warp) and particle count
 * estimate, in double so absurd spacings do not overflow. */
static void grid_size(const drape_scene *s, double *ni, double *nj,
                      double *np)
{
    double sp = s->spacing;
    switch (s->shape) {
    case DRAPE_SHAPE_RECTANGLE:
        *ni = grid_count(s->width, sp);
        *nj = grid_count(s->height, sp);
        *np = *ni * *nj;
        break;
    case DRAPE_SHAPE_STRIP:
        if (s->strip_oblique) { /* the rotated rectangle's bounding box */
            double a = s->strip_angle * SCENE_PI / 180.0;
            double sa = fabs(sin(a)), ca = fabs(cos(a));
            *ni = floor((s->length * sa + s->width * ca) / sp) + 3.0;
            *nj = floor((s->length * ca + s->width * sa) / sp) + 3.0;
            *np = s->length * s->width / (sp * sp) + 2.0 * (s->length + s->width) / sp;
        } else if (s->strip_dir == DRAPE_WARP) {
            *ni = grid_count(s->width, sp);
            *nj = grid_count(s->length, sp);
        } else {
            *ni = grid_count(s->length, sp);
            *nj = grid_count(s->width, sp);
        }
        *np = *ni * *nj;
        break;
    default: {
        double r = 0.5 * s->diameter / sp;
        *ni = *nj = 2.0 * floor(r + SCENE_GRID_EPS) + 1.0;
        *np = SCENE_PI * r * r;
        break;
    }
    }
}

int drape_scene_check_geometry(const drape_scene *s, drape_error *err)
{
    static const drape_shape want[] = {DRAPE_SHAPE_CIRCLE,
                                       DRAPE_SHAPE_RECTANGLE,
                                       DRAPE_SHAPE_RECTANGLE,
                                       DRAPE_SHAPE_STRIP};
    char msg[DRAPE_ERROR_MSG_MAX], a[32], b[32], d[32];
    double sp = s->spacing, lim;
    const char *what;

    if ((int)s->kind < 0 || (int)s->kind > (int)DRAPE_SCENE_CANTILEVER ||
        s->shape != want[s->kind])
        return pos_error(err, s, s->at_specimen, "specimen.shape",
                         DRAPE_E_INPUT,
                         "the specimen's shape does not suit the scene");
    if (!(isfinite(sp) && sp > 0.0)) {
        snprintf(msg, sizeof msg, "expected a positive length, got %g m", sp);
        return pos_error(err, s, s->at_spacing, "spacing", DRAPE_E_INPUT, msg);
    }
    /* At least two particles across every dimension (a circle: three
     * across its diameter). */
    switch (s->shape) {
    case DRAPE_SHAPE_RECTANGLE:
        lim = fmin(s->width, s->height);
        what = s->width <= s->height ? "width" : "height";
        break;
    case DRAPE_SHAPE_STRIP:
        lim = fmin(s->width, s->length);
        what = s->width <= s->length ? "width" : "length";
        break;
    default:
        lim = 0.5 * s->diameter;
        what = "radius";
        break;
    }
    if (sp > lim * (1.0 + SCENE_GRID_EPS)) {
        snprintf(msg, sizeof msg,
                 "expected a spacing at most the specimen's %s (%s), got %s",
                 what, fmt_len(lim, a, sizeof a), fmt_len(sp, b, sizeof b));
        return pos_error(err, s, s->at_spacing, "spacing", DRAPE_E_INPUT, msg);
    }
    switch (s->kind) {
    case DRAPE_SCENE_CUSICK:
        if (!(s->support_diameter < s->diameter)) {
            snprintf(msg, sizeof msg,
                     "expected a support diameter smaller than the "
                     "specimen's diameter (%s), got %s",
                     fmt_len(s->diameter, a, sizeof a),
                     fmt_len(s->support_diameter, b, sizeof b));
            return pos_error(err, s, s->at_support, "support.diameter",
                             DRAPE_E_INPUT, msg);
        }
        break;
    case DRAPE_SCENE_TABLE:
        if (!(s->table_size < s->width && s->table_size < s->height)) {
            snprintf(msg, sizeof msg,
                     "expected a table smaller than the specimen (%s x %s) "
                     "on both sides, got %s %s",
                     fmt_len(s->width, a, sizeof a),
                     fmt_len(s->height, b, sizeof b),
                     s->table_shape == DRAPE_TABLE_SQUARE ? "side"
                                                          : "diameter",
                     fmt_len(s->table_size, d, sizeof d));
            return pos_error(err, s, s->at_table,
                             s->table_shape == DRAPE_TABLE_SQUARE
                                 ? "table.side"
                                 : "table.diameter",
                             DRAPE_E_INPUT, msg);
        }
        break;
    case DRAPE_SCENE_CANTILEVER:
        if (!(s->overhang < s->length)) {
            snprintf(msg, sizeof msg,
                     "expected an overhang shorter than the strip's length "
                     "(%s), got %s",
                     fmt_len(s->length, a, sizeof a),
                     fmt_len(s->overhang, b, sizeof b));
            return pos_error(err, s, s->at_overhang, "overhang",
                             DRAPE_E_INPUT, msg);
        }
        break;
    default:
        break;
    }
    return 0;
}

void drape_scene_fall_params(const drape_scene *s, double *time_s, double *step_s)
{
    double h;
    switch (s->kind) {
    case DRAPE_SCENE_CUSICK: h = 0.5 * (s->diameter - s->support_diameter); break;
    case DRAPE_SCENE_TABLE: {
        double w = s->shape == DRAPE_SHAPE_CIRCLE ? s->diameter : s->width;
        double l = s->shape == DRAPE_SHAPE_CIRCLE ? s->diameter : s->height;
        h = 0.5 * ((w > l ? w : l) - s->table_size);
        break;
    }
    case DRAPE_SCENE_CANTILEVER: h = s->overhang; break;
    default: h = s->shape == DRAPE_SHAPE_CIRCLE ? s->diameter : s->height; break;
    }
    if (!(h > 0.0)) h = s->spacing;
    double tau = sqrt(h / DRAPE_G_STANDARD);
    *time_s = s->fall_time > 0.0 ? s->fall_time : DRAPE_FALL_TIME_FACTOR * tau;
    *step_s = s->fall_step > 0.0 ? s->fall_step : DRAPE_FALL_STEP_FACTOR * tau;
}

void drape_scene_fall_fold(const drape_scene *s, double time_s, double step_s,
                           double *fold_time_s, double *fold_step_s)
{
    double t = s->fall_fold_time >= 0.0 ? s->fall_fold_time : DRAPE_FALL_FOLD_TIME * time_s;
    if (t > time_s) t = time_s;
    *fold_time_s = t > 0.0 ? t : 0.0;
    *fold_step_s = t > 0.0 ? DRAPE_FALL_FOLD_STEP * step_s : 0.0;
}

double drape_scene_fall_swing(const drape_scene *s)
{
    if (s->fall_swing >= 0.0) return s->fall_swing;
    return s->kind == DRAPE_SCENE_TABLE ? DRAPE_FALL_SWING_TABLE : DRAPE_FALL_SWING;
}

void drape_scene_perturbation_band(const drape_scene *s, double *lambda_min,
                                   double *lambda_max, int *modes)
{
    double lo = s->perturb_lambda_min > 0.0 ? s->perturb_lambda_min : DRAPE_FIELD_LAMBDA_MIN;
    double hi = s->perturb_lambda_max;
    if (!(hi > 0.0)) {
        switch (s->shape) {
        case DRAPE_SHAPE_CIRCLE: hi = s->diameter; break;
        case DRAPE_SHAPE_RECTANGLE: hi = fmax(s->width, s->height); break;
        case DRAPE_SHAPE_STRIP: hi = fmax(s->length, s->width); break;
        default: hi = lo; break;
        }
        if (!(hi >= lo)) hi = lo; /* a specimen smaller than the shortest wave */
    }
    *lambda_min = lo;
    *lambda_max = hi;
    *modes = s->perturb_modes > 0 ? s->perturb_modes : DRAPE_FIELD_MODES;
}

double drape_scene_damping_shear(const drape_scene *s, const drape_fabric *f)
{
    if (s->damping_shear >= 0.0) return s->damping_shear;
    return f ? f->damping_shear : 0.0;
}

double drape_scene_animate_step(const drape_scene *s, double *frame_s, int *substeps)
{
    double frame = s->has_frames && s->frame_every > 0.0 ? s->frame_every : DRAPE_ANIMATE_FRAME;
    int n = s->substeps;
    if (n <= 0) {
        double q = ceil(frame / DRAPE_ANIMATE_FRAME - 1e-9);
        n = q < 1.0 ? 1 : q > DRAPE_ANIMATE_SUBSTEPS_MAX ? DRAPE_ANIMATE_SUBSTEPS_MAX : (int)q;
    }
    if (frame_s) *frame_s = frame;
    if (substeps) *substeps = n;
    return frame / n;
}

double drape_scene_memory_bytes(const drape_scene *s, drape_scene_mem_solver solver)
{
    double ni, nj, n;
    grid_size(s, &ni, &nj, &n);
    if (n < 2.0) n = 2.0;
    if (solver == DRAPE_SCENE_MEM_KLU)
        return SCENE_MEM_BASE + n * (SCENE_MEM_KLU_LINEAR + SCENE_MEM_KLU_FILL_SQRT * sqrt(n));
    return SCENE_MEM_BASE + n * (SCENE_MEM_LINEAR + SCENE_MEM_FILL_LOG2 * log2(n));
}

int drape_scene_check_memory(const drape_scene *s, drape_scene_mem_solver solver,
                             drape_error *err)
{
    char msg[DRAPE_ERROR_MSG_MAX], a[32];
    double ni, nj, np, bytes;
    const double gib = 1024.0 * 1024.0 * 1024.0;

    /* Memory, estimated in double before anything is allocated. */
    grid_size(s, &ni, &nj, &np);
    bytes = drape_scene_memory_bytes(s, solver);
    if (np > SCENE_MAX_PARTICLES || bytes > SCENE_MAX_BYTES) {
        snprintf(msg, sizeof msg,
                 "spacing %s gives ~%.2g particles, ~%.3g GiB at ~%.0f KiB "
                 "per particle%s; the limit is %.0f million particles and "
                 "%.0f GiB",
                 fmt_len(s->spacing, a, sizeof a), np, bytes / gib,
                 bytes / (np > 1.0 ? np : 1.0) / 1024.0,
                 solver == DRAPE_SCENE_MEM_KLU ? " with --linear-solver klu" : "",
                 SCENE_MAX_PARTICLES / 1e6, SCENE_MAX_BYTES / gib);
        return pos_error(err, s, s->at_spacing, "spacing", DRAPE_E_NOMEM,
                         msg);
    }
    return 0;
}

int drape_scene_check_with_fabric(const drape_scene *s, const drape_fabric *f,
                                  drape_error *err)
{
    char msg[DRAPE_ERROR_MSG_MAX];
    double ni, nj, np;

    if (!s || !f)
        return drape_error_set(err, DRAPE_E_INTERNAL, NULL, 0, 0, NULL,
                               "drape_scene_check_with_fabric: NULL argument");
    if (drape_scene_check_geometry(s, err)) return -1;
    if (drape_scene_check_memory(s, DRAPE_SCENE_MEM_CHOLMOD, err)) return -1;
    grid_size(s, &ni, &nj, &np);

    /* Pins inside the bounding grid; -1 is the last index. */
    if (s->n_pins < 0 || s->n_pins > DRAPE_SCENE_MAX_PINS)
        return drape_error_set(err, DRAPE_E_INTERNAL, s->path, 0, 0, "pins",
                               "n_pins = %d out of range", s->n_pins);
    for (int k = 0; k < s->n_pins; k++) {
        int i = s->pins[k][0], j = s->pins[k][1];
        long li = (long)ni, lj = (long)nj;
        if (i < -li || i >= li || j < -lj || j >= lj) {
            char key[32];
            snprintf(key, sizeof key, "pins[%d]", k);
            snprintf(msg, sizeof msg,
                     "pin [%d, %d] is outside the %ld x %ld lattice (i in "
                     "%ld..%ld along the width, j in %ld..%ld along the "
                     "height; -1 is the last)",
                     i, j, li, lj, -li, li - 1, -lj, lj - 1);
            return pos_error(err, s, s->at_pins, key, DRAPE_E_INPUT, msg);
        }
    }
    return 0;
}
