/* scene.h: what to simulate, loaded from a scene YAML file.
 *
 * Scenes (docs/model.md section 5): cusick, hang, table, cantilever.  See
 * the files in scenes/ and docs/scenes.md for every key, its unit and
 * default.
 * All quantities are stored in SI.  The fabric path is resolved relative to
 * the directory of the scene file.
 */
#ifndef DRAPE_SCENE_H
#define DRAPE_SCENE_H

#include "drape/error.h"
#include "drape/fabric.h"

#define DRAPE_SCENE_MAX_PINS 64
#define DRAPE_INTEGRATOR_NAME_MAX 32

typedef enum drape_scene_kind {
    DRAPE_SCENE_CUSICK,
    DRAPE_SCENE_HANG,
    DRAPE_SCENE_TABLE,
    DRAPE_SCENE_CANTILEVER
} drape_scene_kind;

typedef enum drape_shape {
    DRAPE_SHAPE_RECTANGLE,
    DRAPE_SHAPE_CIRCLE,
    DRAPE_SHAPE_STRIP
} drape_shape;

typedef enum drape_energy_form {
    DRAPE_FORM_CONSISTENT, /* docs/model.md 3.2/3.3 default */
    DRAPE_FORM_SEED        /* the paper as printed */
} drape_energy_form;

/* Energy terms (bit mask). */
enum {
    DRAPE_TERM_STRETCH = 1u << 0,
    DRAPE_TERM_BEND = 1u << 1,
    DRAPE_TERM_SHEAR = 1u << 2,
    DRAPE_TERM_GRAVITY = 1u << 3,
    DRAPE_TERM_BIAS = 1u << 4,  /* twist cells: built only where
                                   the fabric gives bending.bias, and with
                                   bend */
    DRAPE_TERM_ALL = 0x1fu
};

/* How a run finds its result (solver.method, --method). */
typedef enum drape_method {
    DRAPE_METHOD_DEFAULT, /* not given: fall for scenes that end at
                             equilibrium, dynamic for the others */
    DRAPE_METHOD_DYNAMIC, /* the equations of motion in time (integrator) */
    DRAPE_METHOD_STATIC,  /* minimise E_pot from the flat state (equilibrium.h) */
    DRAPE_METHOD_FALL,    /* a short damped large-step fall, then the static
                             solver (equilibrium.h, dyn_time; docs/ensemble.md) */
    DRAPE_METHOD_ANIMATE  /* the equations of motion at a fixed step tied to
                             the frame rate (integrator "animate";
                             docs/animate.md) */
} drape_method;

/* "default", "dynamic", "static", "fall", "animate", NULL */
/* Names of the DRAPE_TERM_* bits, in bit order (NULL-terminated). */
extern const char *const drape_term_names[];
/* A comma-separated list of term names (`--terms`) into a DRAPE_TERM_*
 * mask.  0, or -1 for an unknown name or an empty list. */
int drape_scene_terms_parse(const char *list, unsigned *terms);
extern const char *const drape_method_names[];

/* Repeated specimens (docs/model.md 6): at most this many per run. */
#define DRAPE_SCENE_SPECIMENS_MAX 1000
#define DRAPE_SCENE_SPECIMENS_MAX_TEXT "1000"
/* The largest perturbation seed (scene and --seed), and of seed + k over an
 * ensemble's specimens: 2^53 - 1, the largest integer a JSON number (a
 * double) holds exactly. */
#define DRAPE_SCENE_SEED_MAX 9007199254740991UL
#define DRAPE_SCENE_SEED_MAX_TEXT "2^53 - 1 (9007199254740991)"

/* perturbation.kind (docs/model.md section 2): the smooth random height field
 * of perturbation.h, or amplitude * U(-1, 1) on each free particle. */
typedef enum drape_perturb_kind {
    DRAPE_PERTURB_FIELD = 0,
    DRAPE_PERTURB_PARTICLE = 1
} drape_perturb_kind;
extern const char *const drape_perturb_kind_names[]; /* "field", "particle", NULL */

typedef enum drape_table_shape { DRAPE_TABLE_SQUARE, DRAPE_TABLE_ROUND } drape_table_shape;

/* Where a key was written in the scene file (1-based; 0 if unknown or
 * defaulted), kept so that errors found after loading
 * (drape_scene_check_with_fabric) can point at the key. */
typedef struct drape_scene_pos {
    int line, column;
} drape_scene_pos;
/* The line of a value given on the command line instead (--spacing): its
 * errors name the option and are usage errors (exit 2). */
#define DRAPE_SCENE_POS_COMMAND_LINE (-1)

typedef struct drape_scene {
    char path[DRAPE_ERROR_FILE_MAX];        /* the scene file */
    char fabric_path[DRAPE_ERROR_FILE_MAX]; /* resolved against the scene's directory */
    drape_scene_kind kind;

    /* specimen */
    drape_shape shape;
    double width;     /* rectangle: along x (weft), m; strip: across, m */
    double height;    /* rectangle: along y (warp), m */
    double diameter;  /* circle, m */
    double length;    /* strip, m */
    drape_dir strip_dir; /* strip: material direction of its length */
    int strip_oblique;   /* strip cut at an angle to the yarns */
    double strip_angle;  /* with strip_oblique: angle of its length from the
                            warp, degrees, in (0, 90) (`bias` = 45) */

    double support_diameter;       /* cusick, m (default 0.18) */
    drape_table_shape table_shape; /* table */
    double table_size;             /* table: side (square) or diameter (round), m */
    double overhang;               /* cantilever, m */
    double spacing;                /* lattice spacing sigma, m */

    int has_perturbation;
    drape_perturb_kind perturb_kind; /* perturbation.kind (default field) */
    double perturb_amplitude;      /* m: the field's RMS height; the
                                      particle form's half range */
    unsigned long perturb_seed;
    double perturb_lambda_min;     /* m, field: shortest wavelength; 0 =
                                      DRAPE_FIELD_LAMBDA_MIN */
    double perturb_lambda_max;     /* m, field: longest wavelength; 0 = the
                                      specimen's largest dimension */
    int perturb_modes;             /* field: plane waves; 0 = DRAPE_FIELD_MODES */

    int n_pins;
    int pins[DRAPE_SCENE_MAX_PINS][2]; /* (i, j); negative counts from the end */

    drape_energy_form energy_form;
    unsigned terms;                /* DRAPE_TERM_* mask */

    double damping_air;            /* 1/s, 0 = off */
    double damping_edge;           /* N.s/m, 0 = off */
    double damping_shear;          /* s, 0 = off: the internal shear damping
                                      (docs/model.md 3.6); < 0
                                      (DRAPE_SCENE_DAMPING_SHEAR_FABRIC, the
                                      loader's default) = the fabric's, see
                                      drape_scene_damping_shear */

    char integrator[DRAPE_INTEGRATOR_NAME_MAX]; /* default "auto" */
    double rtol, atol;             /* defaults 1e-4, 1e-7 */
    int max_order;                 /* solver.max_order (1-5), 0 = integrator's default */
    drape_method method;           /* solver.method; DEFAULT when not given */
    double fall_time, fall_step;   /* solver.fall_time, fall_step, s; 0 = the
                                      fall method's defaults */
    double fall_swing;             /* solver.fall_swing: the
                                      fall goes on past fall_time while the
                                      kinetic energy exceeds this fraction of
                                      its peak; < 0 = the scene's default
                                      (DRAPE_FALL_SWING, the table
                                      DRAPE_FALL_SWING_TABLE), 0 = off */
    double fall_fold_time;         /* solver.fall_fold_time, s: the first part of the fall,
                                      while the folds form, at half the fall
                                      step; < 0 = DRAPE_FALL_FOLD_TIME of the
                                      fall time, 0 = none */
    double fall_retry;             /* solver.fall_retry, s: a longer step of the fall
                                      refused for raising its total energy
                                      is tried again this long after, once
                                      (drape_equilibrium_opts.dyn_retry);
                                      0 = never (default: on the table at 1
                                      cm the retried steps kept a third of
                                      the specimens swinging to the longest
                                      fall, docs/ensemble.md, "Trying the
                                      longer step again") */
    double fall_tol;               /* solver.fall_tol, m: > 0:
                                      the fall's step is chosen by its error
                                      in position (drape_equilibrium_opts.
                                      dyn_tol); 0 = the fixed fall_step */
    int substeps;                  /* solver.substeps: animate steps per frame
                                      interval; 0 = DRAPE_ANIMATE_SUBSTEPS */
    int specimens;                 /* specimens: repeated specimens with seeds
                                      seed, seed + 1, ... (default 1) */

    int has_equilibrium;
    double eq_speed;               /* m/s (default 1e-4) */
    double eq_window;              /* s (default 0.2) */
    double t_max;                  /* s */
    double strain_limit;           /* end.strain_limit: a run whose largest stretch
                                      strain exceeds it stops (failed); default
                                      0.2 (docs/scenes.md) */

    int has_frames;
    double frame_every;            /* s */
    int out_obj, out_hdf5;

    /* Source positions of the values checked by
     * drape_scene_check_with_fabric (spacing, the pins key, support.diameter,
     * the table size, overhang, the specimen's size). */
    drape_scene_pos at_spacing, at_pins, at_support, at_table, at_overhang,
        at_specimen;
} drape_scene;

/* scene.damping_shear when neither the scene nor the command line gives
 * one: the fabric's own (drape_fabric.damping_shear). */
#define DRAPE_SCENE_DAMPING_SHEAR_FABRIC (-1.0)

/* The internal shear damping beta (s) a run of scene s on fabric f uses:
 * the scene's (a scene key or --damping-shear) when it gives one (>= 0),
 * else the fabric's.  f may be NULL (then 0 where the scene gives none). */
double drape_scene_damping_shear(const drape_scene *s, const drape_fabric *f);

/* The band of the perturbation field a run of s draws: lambda_min,
 * lambda_max (m) and the number of plane waves, each the scene's or its
 * default (the longest: the specimen's largest dimension, and never
 * shorter than the shortest). */
void drape_scene_perturbation_band(const drape_scene *s, double *lambda_min,
                                   double *lambda_max, int *modes);

/* Known integrator names, NULL-terminated (for validation and --help). */
extern const char *const drape_integrator_names[];

/* Load a scene file (does not load the fabric).  Returns 0 and fills *s, or
 * -1 and fills err with file, line, column, key path.  warn may be NULL. */
int drape_scene_load(const char *path, drape_scene *s, drape_error *err,
                     drape_warn_fn warn, void *warn_ctx);

/* Flags of drape_scene_load_flags. */
enum {
    /* the caller will use another fabric (--fabric): the scene's `fabric`
     * key is still required and resolved into fabric_path, but the file
     * need not exist */
    DRAPE_SCENE_LOAD_FABRIC_OVERRIDDEN = 1u << 0
};
/* drape_scene_load with flags (0 = drape_scene_load). */
int drape_scene_load_flags(const char *path, unsigned flags, drape_scene *s,
                           drape_error *err, drape_warn_fn warn, void *warn_ctx);

/* Checks across keys that need no fabric (scene_check.c): the shape the
 * kind needs, a spacing the specimen can hold, support or table inside
 * the specimen, overhang shorter than the strip.  drape_scene_load runs
 * them; errors name the scene file and key. */
int drape_scene_check_geometry(const drape_scene *s, drape_error *err);

/* Checks that need both files: support or table larger than the specimen,
 * overhang longer than the strip, pins outside the lattice, a lattice that
 * would not fit in memory (estimated before allocating).  Errors name the
 * scene file and key. */
int drape_scene_check_with_fabric(const drape_scene *s, const drape_fabric *f,
                                  drape_error *err);

/* The linear solvers whose memory the estimate tells apart: CHOLMOD's
 * (every method's default: the Schur system of the dynamic and animate
 * runs, the static solver's Hessian) and KLU's LU of the first-order
 * Jacobian (--linear-solver klu), whose fill grows faster. */
typedef enum drape_scene_mem_solver {
    DRAPE_SCENE_MEM_CHOLMOD = 0,
    DRAPE_SCENE_MEM_KLU = 1
} drape_scene_mem_solver;

/* Estimated peak resident memory of one run (one process) of the scene,
 * in bytes, before anything is allocated (scene_check.c, docs/scenes.md,
 * "Memory"): an upper bound, over every method and integrator, of the
 * measured peak RSS, for the particle count n of the lattice:
 *     bytes = B0 + n (a + c log2 n)          (CHOLMOD: nested-dissection fill)
 *     bytes = B0 + n (a_klu + c_klu sqrt n)  (KLU: AMD fill of the 6 nf system)
 * The count is the scene's (ni x nj, pi (d/2s)^2 for a circle). */
double drape_scene_memory_bytes(const drape_scene *s, drape_scene_mem_solver solver);

/* Refuse (DRAPE_E_NOMEM at the spacing key, exit 5) a scene whose
 * estimated memory with this solver (drape_scene_memory_bytes) is above
 * 8 GiB or whose lattice has over 20 million particles.
 * drape_scene_check_with_fabric runs it with DRAPE_SCENE_MEM_CHOLMOD;
 * drape run again with KLU when --linear-solver klu is given. */
int drape_scene_check_memory(const drape_scene *s, drape_scene_mem_solver solver,
                             drape_error *err);

/* The fall method's time and step (solver.fall_time, fall_step, or their
 * defaults from the scene's geometry; docs/ensemble.md):
 *     t_fall = DRAPE_FALL_TIME_FACTOR sqrt(h / g),
 *     h_step = DRAPE_FALL_STEP_FACTOR sqrt(h / g),
 * h the length that hangs free (Cusick: (D - d)/2; table: the longest
 * overhang; cantilever: the overhang; hang: the specimen's height), so
 * that scenes of another size fall for the same number of pendulum
 * times of their skirt. */
#define DRAPE_FALL_TIME_FACTOR 10.0
#define DRAPE_FALL_STEP_FACTOR 0.03125
/* The fall does not end while the cloth still swings: past t_fall it goes
 * on while the largest kinetic energy over the last t_fall / 5 exceeds
 * DRAPE_FALL_SWING of its peak, up to DRAPE_FALL_TIME_MAX t_fall
 * (docs/ensemble.md, "The swing criterion"). */
#define DRAPE_FALL_SWING 0.02
/* The table scene's fall ends at t_fall: there the
 * swing's longer step is refused (it pumps energy into the hem compressed
 * over the table's edges), so the swing ran at the fold step, a quarter
 * to a third of a specimen's CPU, and changed no statistic that was
 * measured (cotton at 1 cm, 32 specimens, and at 2 cm; the limp
 * polyester tablecloth at 1 cm, 16: the ensembles with and without it
 * indistinguishable; docs/ensemble.md, "The table's fall without the
 * swing"). */
#define DRAPE_FALL_SWING_TABLE 0.0
#define DRAPE_FALL_TIME_MAX 4.0
/* Past t_fall the folds have formed and the skirt swings at its pendulum
 * frequency: the step is DRAPE_FALL_SWING_STEP h_step there (about 100
 * steps per pendulum period; docs/ensemble.md, "The step of the swing"). */
#define DRAPE_FALL_SWING_STEP 2.0
/* m: a fixed-step fall whose total energy climbs above its value at the
 * start (its linearly implicit step pumped energy into the folds: the
 * model only dissipates) is done again with its step chosen by its error
 * at this tolerance (--fall-tol; exact Jacobian, rising steps refused):
 * docs/ensemble.md, "Energy gained by the fixed-step fall".  30 um is the
 * tolerance at which the error-controlled fall was measured against the
 * accurate ensembles. */
#define DRAPE_FALL_REDO_TOL 30e-6
/* Iterations of the static solver after the fall (the static method keeps
 * its 500; docs/ensemble.md). */
#define DRAPE_FALL_MAX_ITERS 2000
/* After the fall a certified minimum whose residual stalls (roundoff) below
 * this multiple of the static tolerance counts as the rest state. */
#define DRAPE_FALL_FLOOR 100.0
void drape_scene_fall_params(const drape_scene *s, double *time_s, double *step_s);
/* While the folds form the fall takes half its step: the first
 * DRAPE_FALL_FOLD_TIME t_fall (or solver.fall_fold_time) at
 * DRAPE_FALL_FOLD_STEP h_step.  At the fall step alone its linearly
 * implicit BDF2 lets too many specimens fold into more nodes (cotton:
 * mean DC 0.004 low over 128 specimens) and pumps energy into a few
 * (docs/ensemble.md, "The fold phase"). */
#define DRAPE_FALL_FOLD_TIME 0.5
#define DRAPE_FALL_FOLD_STEP 0.5
/* The fold phase's time and step for a fall of time_s, step_s: 0 and 0
 * when there is none. */
void drape_scene_fall_fold(const drape_scene *s, double time_s, double step_s,
                           double *fold_time_s, double *fold_step_s);

/* The fall's swing fraction (solver.fall_swing or DRAPE_FALL_SWING). */
double drape_scene_fall_swing(const drape_scene *s);

/* The animate method's fixed step (docs/animate.md): the frame interval
 * (output.frames.every, or DRAPE_ANIMATE_FRAME when the scene writes no
 * frames: 30 frames per second) divided by solver.substeps; by default the
 * fewest steps per frame that keep the step at most DRAPE_ANIMATE_FRAME
 * (1 at 30 frames per second, 3 for frames every 0.1 s).  *frame_s and
 * *substeps may be NULL. */
#define DRAPE_ANIMATE_FRAME (1.0 / 30.0)
#define DRAPE_ANIMATE_SUBSTEPS_MAX 10000
double drape_scene_animate_step(const drape_scene *s, double *frame_s, int *substeps);

/* Names for output. */
const char *drape_scene_kind_name(drape_scene_kind k);
const char *drape_energy_form_name(drape_energy_form f);

#endif /* DRAPE_SCENE_H */
