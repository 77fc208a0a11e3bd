/* cli_run.c: `drape run [SCENE.yaml] [options]`: load a scene and its
 * fabric, build the lattice and model, integrate, measure, and print one
 * JSON object (or a CSV header and row) on stdout.  Frames (OBJ, HDF5 +
 * XDMF) are written only with --out DIR.  Progress goes to stderr only when
 * it is a terminal.  Keys of the result are a contract (issue 3).
 *
 * Interruption and resume (issue 7; docs/reliability.md): SIGINT and
 * SIGTERM set a flag (the handler does nothing else) that the driver polls
 * at every output point and every right-hand side evaluation checks; the
 * run then ends at the last output point with status interrupted,
 * writes DIR/drape.h5 with the state, velocities, time and run options
 * (group /run), and exits with 128 + the signal.  A second signal ends
 * drape at once (the handler is reset to the default on entry).
 * `drape run --resume DIR` reads that file back and continues.  A run that
 * fails for any other reason than a numerical fault leaves nothing of its
 * own in DIR (its frames are removed, a directory it created too). */
#include <errno.h>
#include <getopt.h>
#include <limits.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli.h"
#include "cli_io.h"
#include "drape/alloc.h"
#include "drape/diagnose.h"
#include "drape/drape.h"
#include "drape/equilibrium.h"
#include "drape/fabric.h"
#include "drape/lattice.h"
#include "drape/model.h"
#include "drape/output.h"
#include "drape/scene.h"
#include "drape/sim.h"
#include "drape/units.h"
#include "drape/yamldoc.h"

#define DEFAULT_SCENE "scenes/cusick.yaml"

static const char run_usage[] =
    "Usage: drape run [SCENE.yaml] [OPTIONS]\n"
    "       drape run --resume DIR [--format json|csv] [-q]\n"
    "\n"
    "Run a scene (default " DEFAULT_SCENE ") and print one JSON object on\n"
    "stdout with the result in SI units (keys: fabric, scene, integrator,\n"
    "energy_form, rtol, atol, spacing_m, particles, free_particles, status,\n"
    "t_end_s, dc, nodes, r_min_m, r_max_m, tip_angle_deg, bending_length_m,\n"
    "flexural_rigidity_Nm, energy_J{kinetic,stretch,bend,shear,gravity},\n"
    "max_strain, wall_s, steps, rhs_evals, jac_evals, lin_setups, nonlin_iters,\n"
    "err_test_fails, conv_fails, and more: mass_kg, areas, max_speed_m_s (at the\n"
    "end), mean_speed_m_s (largest particle speed averaged over the last\n"
    "equilibrium check interval: what the equilibrium test compares), the static\n"
    "solver's keys, linear_solver, lin_iters, lin_factors, integrator_switches\n"
    "(auto: changes between cvode-bdf and arkode-erk), max_order (cvode-bdf,\n"
    "auto); null where the scene does not produce one).  status is\n"
    "equilibrium, t_max, failed or interrupted.\n"
    "\n"
    "Options (override the scene file):\n"
    "  --fabric FILE            fabric file instead of the scene's\n"
    "  --integrator NAME        auto, arkode-imex, arkode-dirk, arkode-erk,\n"
    "                           cvode-bdf, gsl-msbdf, gsl-rk8pd\n"
    "  --rtol X, --atol X       tolerances (atol on positions, m)\n"
    "  --spacing LEN            lattice spacing, e.g. 5mm or '0.5 cm'\n"
    "  --energy-form FORM       consistent or seed\n"
    "  --t-max T                end time, e.g. 3s\n"
    "  --method METHOD          dynamic (default): integrate the equations of\n"
    "                           motion in time; static: minimise the potential\n"
    "                           energy directly (pseudo-transient continuation,\n"
    "                           Newton, Hessian check; docs/equilibrium.md): only\n"
    "                           the final state, no transient frames\n"
    "  --linear-solver NAME     auto (default), klu, schur or schur-direct\n"
    "                           (docs/integrators.md, \"Linear solvers\")\n"
    "  --max-order N            highest BDF order of cvode-bdf (also inside auto),\n"
    "                           1 to 5 (scene: solver.max_order, default 2); 1 is\n"
    "                           backward Euler, which damps fast vibrations and is\n"
    "                           the cheapest at loose tolerances\n"
    "  --max-steps N            give up (status failed) after N integrator steps\n"
    "                           between two output points (default 1000000)\n"
    "  --strain-limit X         stop (status failed) when a stretch edge's strain\n"
    "                           exceeds X, e.g. 0.2 = 20 % (scene: end.strain_limit,\n"
    "                           default 0.2)\n"
    "  --out DIR                write frames (OBJ, drape.h5 + drape.xmf) into DIR\n"
    "  --resume DIR             continue a run that was interrupted (SIGINT, SIGTERM)\n"
    "                           from DIR/drape.h5, with the options stored there\n"
    "  --format json|csv        result format on stdout (default json)\n"
    "  -q, --quiet              no progress on stderr\n"
    "  -h, --help               show this help\n"
    "\n"
    "SIGINT or SIGTERM stops a dynamic run within one model evaluation; it ends\n"
    "at the last output point (frame or equilibrium check) with status\n"
    "interrupted, the frames so far and DIR/drape.h5 kept for --resume; a second\n"
    "signal ends drape at once.\n"
    "\n"
    "Exit status: 0 equilibrium or t_max, 1 invalid input, 2 bad command line,\n"
    "3 I/O error, 4 the run failed (numerical), 5 out of memory, 130 interrupted\n"
    "by SIGINT, 143 interrupted by SIGTERM.\n";

/* ---- result fields ----------------------------------------------------- */

const char *const drape_cli_run_keys[] = {
    "fabric", "scene", "integrator", "energy_form", "rtol", "atol", "spacing_m",
    "particles", "free_particles", "status", "t_end_s", "dc", "nodes", "r_min_m",
    "r_max_m", "tip_angle_deg", "bending_length_m", "flexural_rigidity_Nm",
    "energy_J_kinetic", "energy_J_stretch", "energy_J_bend", "energy_J_shear",
    "energy_J_gravity", "max_strain", "wall_s", "steps", "rhs_evals", "jac_evals",
    "lin_setups", "nonlin_iters", "err_test_fails", "conv_fails", "mass_kg",
    "area_nominal_m2", "area_mesh_m2", "max_speed_m_s", "method", "iterations",
    "factorizations", "certified", "min_pivot_N_m", "omega_min_rad_s",
    "max_force_rel", "linear_solver", "lin_iters", "lin_factors", "mean_speed_m_s",
    "integrator_switches", "max_order", NULL};

int drape_cli_run_nkeys(void)
{
    int n = 0;
    while (drape_cli_run_keys[n]) n++;
    return n;
}

/* 1 if the fields are exactly drape_cli_run_keys, in order ('.' as '_'). */


typedef struct field {
    const char *key;
    const char *text; /* string value, or NULL */
    double value;     /* number; NaN prints null */
    int is_int;
} field;

#define MAX_FIELDS 64

typedef struct result_fields {
    field f[MAX_FIELDS];
    int n;
} result_fields;

static int fields_match_keys(const result_fields *r)
{
    if (r->n != drape_cli_run_nkeys()) return 0;
    for (int i = 0; i < r->n; i++) {
        const char *a = r->f[i].key, *b = drape_cli_run_keys[i];
        for (; *a && *b; a++, b++)
            if (*a != *b && !(*a == '.' && *b == '_')) return 0;
        if (*a || *b) return 0;
    }
    return 1;
}

static void add_num(result_fields *r, const char *key, double v)
{
    r->f[r->n++] = (field){key, NULL, v, 0};
}
static void add_int(result_fields *r, const char *key, double v)
{
    r->f[r->n++] = (field){key, NULL, v, 1};
}
static void add_str(result_fields *r, const char *key, const char *s)
{
    r->f[r->n++] = (field){key, s, 0.0, 0};
}

static void json_string(FILE *out, const char *s)
{
    fputc('"', out);
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        if (c == '"' || c == '\\') fprintf(out, "\\%c", c);
        else if (c < 0x20) fprintf(out, "\\u%04x", c);
        else fputc(c, out);
    }
    fputc('"', out);
}

static void print_value(FILE *out, const field *f, int json)
{
    if (f->text) {
        if (json) json_string(out, f->text);
        else drape_cli_csv_put(out, f->text);
    } else if (!isfinite(f->value) || (f->is_int && f->value < 0)) {
        fputs(json ? "null" : "", out);
    } else if (f->is_int) {
        fprintf(out, "%.0f", f->value);
    } else {
        fprintf(out, "%.10g", f->value);
    }
}

/* Keys "energy_J.kinetic" are nested in JSON and flattened with '_' in CSV. */
static void print_json(FILE *out, const result_fields *r)
{
    fputc('{', out);
    const char *group = NULL;
    size_t glen = 0;
    for (int i = 0; i < r->n; i++) {
        const char *k = r->f[i].key, *dot = strchr(k, '.');
        if (group && (!dot || (size_t)(dot - k) != glen || strncmp(k, group, glen) != 0)) {
            fputc('}', out);
            group = NULL;
        }
        if (i) fputs(", ", out);
        if (dot && !group) {
            group = k;
            glen = (size_t)(dot - k);
            fprintf(out, "\"%.*s\": {", (int)glen, k);
        }
        fprintf(out, "\"%s\": ", dot ? dot + 1 : k);
        print_value(out, &r->f[i], 1);
    }
    if (group) fputc('}', out);
    fputs("}\n", out);
}

static void print_csv(FILE *out, const result_fields *r)
{
    for (int i = 0; i < r->n; i++) {
        if (i) fputc(',', out);
        for (const char *k = r->f[i].key; *k; k++) fputc(*k == '.' ? '_' : *k, out);
    }
    fputc('\n', out);
    for (int i = 0; i < r->n; i++) {
        if (i) fputc(',', out);
        print_value(out, &r->f[i], 0);
    }
    fputc('\n', out);
}

/* ---- observers ------------------------------------------------------------ */

typedef struct run_ctx {
    drape_model *model;
    drape_obj *obj;
    drape_h5 *h5;
    int frame;
    int progress; /* print progress on stderr */
    double t_max;
} run_ctx;

static int observe(void *ctx, const drape_sim_event *ev, drape_error *err)
{
    run_ctx *c = ctx;
    if (c->progress) {
        fprintf(stderr, "\rdrape: t = %8.4f s of %g s, %ld steps, max speed %.3g m/s ",
                ev->t, c->t_max, ev->steps, ev->max_speed);
        if (ev->what & DRAPE_SIM_AT_END) fputc('\n', stderr);
    }
    if (!(ev->what & (DRAPE_SIM_AT_START | DRAPE_SIM_AT_FRAME | DRAPE_SIM_AT_END)))
        return 0;
    if (c->obj && drape_obj_frame(c->obj, c->frame, ev->t, ev->x, err) != 0) return -1;
    if (c->h5) {
        drape_energies E;
        double ke = drape_sim_kinetic_energy(drape_model_lattice(c->model), ev->v);
        if (drape_model_energy(c->model, ev->x, &E) != 0) {
            E.stretch = E.bend = E.shear = E.gravity = NAN;
        }
        if (drape_h5_frame(c->h5, ev->t, ev->x, ev->v, ke, &E, err) != 0) return -1;
    }
    c->frame++;
    return 0;
}

/* ---- option parsing ------------------------------------------------------- */

static int usage_error(const char *fmt, const char *a, const char *b)
{
    fputs("drape: ", stderr);
    fprintf(stderr, fmt, a, b);
    fputs("\nTry `drape run --help'.\n", stderr);
    return drape_error_exit_status(DRAPE_E_USAGE);
}

static int parse_quantity(const char *opt, const char *text, drape_dim dim,
                          double *v)
{
    char why[256];
    if (drape_units_parse(text, dim, v, why, sizeof why) != 0) {
        usage_error("%s: %s", opt, why);
        return -1;
    }
    return 0;
}

/* ---- interruption ------------------------------------------------------------ */

/* The signal that asked the run to stop, 0 = none.  The handler only sets
 * it; SA_RESETHAND makes a second signal take its default action. */
static volatile sig_atomic_t stop_signal;

static void on_stop_signal(int sig)
{
    stop_signal = sig;
}

typedef struct saved_signals {
    struct sigaction old_int, old_term;
    int installed;
} saved_signals;

/* Catch SIGINT and SIGTERM (a signal ignored at start, as in a background
 * job, stays ignored).  SA_RESTART: reads and writes are not cut short. */
static void catch_signals(saved_signals *sv)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_stop_signal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESTART | SA_RESETHAND;
    stop_signal = 0;
    sigaction(SIGINT, NULL, &sv->old_int);
    sigaction(SIGTERM, NULL, &sv->old_term);
    if (sv->old_int.sa_handler != SIG_IGN) sigaction(SIGINT, &sa, NULL);
    if (sv->old_term.sa_handler != SIG_IGN) sigaction(SIGTERM, &sa, NULL);
    sv->installed = 1;
}

static void restore_signals(saved_signals *sv)
{
    if (!sv->installed) return;
    sigaction(SIGINT, &sv->old_int, NULL);
    sigaction(SIGTERM, &sv->old_term, NULL);
    sv->installed = 0;
}

/* 128 + the signal, as shells report a process killed by it. */
static int interrupted_status(int sig)
{
    return 128 + (sig > 0 ? sig : SIGINT);
}

static const char *signal_name(int sig)
{
    return sig == SIGTERM ? "SIGTERM" : sig == SIGINT ? "SIGINT" : "a signal";
}

/* ---- resume ------------------------------------------------------------------ */

#define RUN_RESUME_FORMAT 1 /* /run attribute resume_format */

/* Everything --resume takes from DIR/drape.h5. */
typedef struct resume_info {
    drape_h5_checkpoint ck;
    char h5_path[4200];
    char scene_path[DRAPE_ERROR_FILE_MAX], fabric_path[DRAPE_ERROR_FILE_MAX];
    char integrator[DRAPE_INTEGRATOR_NAME_MAX], form[32], linsol[32];
    double rtol, atol, spacing, t_max, strain_limit, below_since;
    long max_steps;
    int max_order;   /* 0: the scene's (files written before --max-order) */
    int frames;      /* frames written before (OBJ and HDF5 numbering) */
    int had_h5;      /* the scene writes drape.h5 (else it is a checkpoint only) */
    drape_diag_ref ref;
} resume_info;

static const char *ck_text(const drape_h5_checkpoint *c, const char *key)
{
    const drape_kv *kv = drape_kv_find(c->run, c->n_run, key);
    return kv && kv->text ? kv->text : NULL;
}

static double ck_num(const drape_h5_checkpoint *c, const char *key)
{
    const drape_kv *kv = drape_kv_find(c->run, c->n_run, key);
    return kv && !kv->text ? kv->value : NAN;
}

/* A stored text must be the file's current text (the run continues on the
 * same inputs). */
static int same_input(const char *path, const char *stored, const char *what,
                      const char *h5, drape_error *err)
{
    drape_error e2;
    drape_error_clear(&e2);
    if (!stored)
        return drape_error_set(err, DRAPE_E_IO, h5, 0, 0, NULL,
                               "--resume: the %s text is not stored in the file", what);
    char *now = drape_cli_read_file(path, DRAPE_YDOC_MAX_BYTES, NULL, &e2);
    if (!now) {
        *err = e2;
        return -1;
    }
    int same = strcmp(now, stored) == 0;
    drape_free(now);
    if (!same)
        return drape_error_set(err, DRAPE_E_INPUT, path, 0, 0, NULL,
                               "--resume: this %s file changed since the run was interrupted "
                               "(%s keeps the old text as attribute %s_yaml); restore it, or "
                               "start a new run", what, h5, what);
    return 0;
}

static int resume_load(const char *dir, resume_info *ri, drape_error *err)
{
    drape_h5_checkpoint *c = &ri->ck;
    snprintf(ri->h5_path, sizeof ri->h5_path, "%s/drape.h5", dir);
    if (drape_h5_checkpoint_read(ri->h5_path, c, err) != 0) {
        if (access(ri->h5_path, F_OK) != 0) {
            drape_error_clear(err);
            return drape_error_set(err, DRAPE_E_IO, ri->h5_path, 0, 0, NULL,
                                   "--resume: no such file (a run interrupted with --out DIR "
                                   "leaves it there)");
        }
        return -1;
    }
    const drape_kv *st = drape_kv_find(c->stats, c->n_stats, "status");
    const char *status = st && st->text ? st->text : "";
    if (strcmp(status, "interrupted") != 0)
        return drape_error_set(err, DRAPE_E_USAGE, ri->h5_path, 0, 0, NULL,
                               "--resume: the run ended with status %s, not interrupted: "
                               "nothing to resume", status[0] ? status : "(none)");
    const char *sp = ck_text(c, "scene_path"), *fp = ck_text(c, "fabric_path");
    const char *in = ck_text(c, "integrator"), *fo = ck_text(c, "energy_form");
    const char *ls = ck_text(c, "linear_solver");
    if (ck_num(c, "resume_format") != RUN_RESUME_FORMAT || !sp || !fp || !in || !fo || !ls)
        return drape_error_set(err, DRAPE_E_IO, ri->h5_path, 0, 0, NULL,
                               "--resume: no usable /run group (written by another version "
                               "of drape?)");
    if (strlen(sp) >= sizeof ri->scene_path || strlen(fp) >= sizeof ri->fabric_path)
        return drape_error_set(err, DRAPE_E_IO, ri->h5_path, 0, 0, NULL,
                               "--resume: stored input paths too long");
    snprintf(ri->scene_path, sizeof ri->scene_path, "%s", sp);
    snprintf(ri->fabric_path, sizeof ri->fabric_path, "%s", fp);
    snprintf(ri->integrator, sizeof ri->integrator, "%s", in);
    snprintf(ri->form, sizeof ri->form, "%s", fo);
    snprintf(ri->linsol, sizeof ri->linsol, "%s", ls);
    ri->rtol = ck_num(c, "rtol");
    ri->atol = ck_num(c, "atol");
    ri->spacing = ck_num(c, "spacing_m");
    ri->t_max = ck_num(c, "t_max_s");
    ri->strain_limit = ck_num(c, "strain_limit");
    ri->below_since = ck_num(c, "eq_below_since_s");
    double ms = ck_num(c, "max_steps"), fr = ck_num(c, "frames"), h5 = ck_num(c, "hdf5");
    ri->ref.valid = ck_num(c, "energy_ref_valid") == 1.0;
    ri->ref.energy_J = ck_num(c, "energy_ref_J");
    ri->ref.scale_J = ck_num(c, "energy_scale_J");
    ri->ref.kinetic_J = ck_num(c, "energy_ref_kinetic_J");
    ri->ref.E.stretch = ck_num(c, "energy_ref_stretch_J");
    ri->ref.E.bend = ck_num(c, "energy_ref_bend_J");
    ri->ref.E.shear = ck_num(c, "energy_ref_shear_J");
    ri->ref.E.gravity = ck_num(c, "energy_ref_gravity_J");
    if (!(ri->rtol > 0) || !(ri->atol > 0) || !(ri->spacing > 0) || !(ri->t_max > 0) ||
        !(ri->strain_limit > 0) || !(ms >= 0) || !(fr >= 0 && fr < INT_MAX) ||
        !(h5 == 0 || h5 == 1) || isnan(ri->below_since) ||
        (ri->ref.valid && !(isfinite(ri->ref.energy_J) && ri->ref.scale_J > 0)))
        return drape_error_set(err, DRAPE_E_IO, ri->h5_path, 0, 0, NULL,
                               "--resume: missing or invalid values in /run");
    ri->max_steps = (long)ms;
    double mo = ck_num(c, "max_order");
    ri->max_order = mo >= 1 && mo <= 5 ? (int)mo : 0;
    ri->frames = (int)fr;
    ri->had_h5 = h5 == 1;
    if (same_input(ri->scene_path, c->scene_yaml, "scene", ri->h5_path, err) != 0 ||
        same_input(ri->fabric_path, c->fabric_yaml, "fabric", ri->h5_path, err) != 0)
        return -1;
    return 0;
}

/* Counters of the interrupted part are added to the resumed part's. */
static void add_previous(const drape_h5_checkpoint *c, const char *key, long *v)
{
    const drape_kv *kv = drape_kv_find(c->stats, c->n_stats, key);
    if (kv && !kv->text && kv->value >= 0 && *v >= 0) *v += (long)kv->value;
}

/* The static method: minimise E_pot from the initial state and present the
 * result as a run (status equilibrium or failed, no time, no integrator
 * statistics).  Frames: the final state only.  Returns 1 on success. */
static int run_static(drape_model *m, const drape_fabric *f, run_ctx *rc,
                      drape_sim_result *res, drape_equilibrium_result *er,
                      drape_error *err)
{
    const drape_lattice *L = drape_model_lattice(m);
    drape_equilibrium_opts eo;
    drape_equilibrium_opts_from_fabric(&eo, f);
    eo.stop = &stop_signal;
    snprintf(res->integrator, sizeof res->integrator, "static");
    res->status = DRAPE_SIM_FAILED;
    res->t_end_s = NAN;
    /* no integrator: every counter "not available" (-1), printed as null */
    res->stats.steps = res->stats.rhs_evals = res->stats.jac_evals = -1;
    res->stats.lin_setups = res->stats.nonlin_iters = res->stats.err_test_fails = -1;
    res->stats.conv_fails = res->stats.lin_iters = res->stats.lin_factors = -1;
    res->stats.switches = -1;
    res->max_speed = NAN;
    if (drape_equilibrium_solve(m, L->xinit, &eo, er, err) != 0) return 0;
    res->wall_s = er->wall_s;
    res->x = er->x;
    er->x = NULL;
    res->v = drape_calloc((size_t)3 * (size_t)L->n, sizeof(double));
    if (!res->v) {
        drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL, "out of memory");
        return 0;
    }
    res->energy = er->energy;
    res->kinetic_J = 0.0;
    res->max_strain = er->max_strain;
    res->max_speed = 0.0;
    if (er->status == DRAPE_EQ_INTERRUPTED) return 1; /* the caller reports it */
    if (er->status != DRAPE_EQ_CONVERGED) {
        drape_error_set(err, DRAPE_E_NUMERIC, NULL, 0, 0, NULL,
                        "static equilibrium not reached (%s after %d iterations, largest "
                        "residual force %.3g x particle weight); hint: try --method dynamic",
                        drape_equilibrium_status_name(er->status), er->iterations,
                        er->max_force_rel);
        return 0;
    }
    res->status = DRAPE_SIM_EQUILIBRIUM;
    drape_sim_event ev = {DRAPE_SIM_AT_END, 0.0, res->x, res->v, er->iterations, 0.0};
    if ((rc->obj || rc->h5) && observe(rc, &ev, err) != 0) return 0;
    return 1;
}

/* The run's options and resume state for /run (strings point into s,
 * res, or static text; nums into the caller's array). */
typedef struct run_kv {
    drape_kv kv[32];
    int n;
    char scene_abs[PATH_MAX + DRAPE_ERROR_FILE_MAX], fabric_abs[PATH_MAX + DRAPE_ERROR_FILE_MAX];
} run_kv;

static void kv_num(run_kv *k, const char *key, double v)
{
    k->kv[k->n++] = (drape_kv){key, NULL, v};
}

static void kv_str(run_kv *k, const char *key, const char *text)
{
    k->kv[k->n++] = (drape_kv){key, text, 0.0};
}

/* path made absolute against the working directory (kept as given when
 * that fails), so that --resume works from anywhere. */
static void abs_path(const char *path, char *out, size_t n)
{
    char cwd[PATH_MAX];
    if (path[0] != '/' && getcwd(cwd, sizeof cwd)) {
        int r = snprintf(out, n, "%s/%s", cwd, path);
        if (r >= 0 && (size_t)r < n) return;
    }
    snprintf(out, n, "%s", path);
}

static void fill_run_kv(run_kv *k, const char *scene_path, const drape_scene *s,
                        const drape_sim_opts *so, const drape_sim_result *res, int frames)
{
    k->n = 0;
    abs_path(scene_path, k->scene_abs, sizeof k->scene_abs);
    abs_path(s->fabric_path, k->fabric_abs, sizeof k->fabric_abs);
    kv_num(k, "resume_format", RUN_RESUME_FORMAT);
    kv_str(k, "method", "dynamic");
    kv_str(k, "scene_path", k->scene_abs);
    kv_str(k, "fabric_path", k->fabric_abs);
    kv_str(k, "integrator", so->integrator);
    kv_num(k, "rtol", so->rtol);
    kv_num(k, "atol", so->atol);
    kv_num(k, "spacing_m", s->spacing);
    kv_str(k, "energy_form", drape_energy_form_name(s->energy_form));
    kv_num(k, "t_max_s", so->t_max);
    kv_num(k, "strain_limit", so->strain_limit);
    kv_num(k, "max_steps", (double)so->max_steps);
    kv_num(k, "max_order", (double)so->max_order);
    kv_str(k, "linear_solver", drape_linsol_name(so->linsol));
    kv_num(k, "frames", frames);
    kv_num(k, "hdf5", s->out_hdf5 ? 1.0 : 0.0);
    kv_num(k, "eq_below_since_s", res->eq_below_since);
    kv_num(k, "energy_ref_valid", res->diag_ref.valid ? 1.0 : 0.0);
    kv_num(k, "energy_ref_J", res->diag_ref.energy_J);
    kv_num(k, "energy_scale_J", res->diag_ref.scale_J);
    kv_num(k, "energy_ref_kinetic_J", res->diag_ref.kinetic_J);
    kv_num(k, "energy_ref_stretch_J", res->diag_ref.E.stretch);
    kv_num(k, "energy_ref_bend_J", res->diag_ref.E.bend);
    kv_num(k, "energy_ref_shear_J", res->diag_ref.E.shear);
    kv_num(k, "energy_ref_gravity_J", res->diag_ref.E.gravity);
    kv_num(k, "signal", stop_signal);
}

int drape_cli_run(int argc, char **argv)
{
    enum { O_FABRIC = 1000, O_INTEGRATOR, O_RTOL, O_ATOL, O_SPACING, O_FORM,
           O_TMAX, O_OUT, O_FORMAT, O_MAXSTEPS, O_METHOD, O_LINSOL, O_RESUME,
           O_STRAIN, O_MAXORDER };
    static const struct option opts[] = {
        {"fabric", required_argument, NULL, O_FABRIC},
        {"integrator", required_argument, NULL, O_INTEGRATOR},
        {"rtol", required_argument, NULL, O_RTOL},
        {"atol", required_argument, NULL, O_ATOL},
        {"spacing", required_argument, NULL, O_SPACING},
        {"energy-form", required_argument, NULL, O_FORM},
        {"t-max", required_argument, NULL, O_TMAX},
        {"out", required_argument, NULL, O_OUT},
        {"max-steps", required_argument, NULL, O_MAXSTEPS},
        {"max-order", required_argument, NULL, O_MAXORDER},
        {"method", required_argument, NULL, O_METHOD},
        {"linear-solver", required_argument, NULL, O_LINSOL},
        {"strain-limit", required_argument, NULL, O_STRAIN},
        {"resume", required_argument, NULL, O_RESUME},
        {"format", required_argument, NULL, O_FORMAT},
        {"quiet", no_argument, NULL, 'q'},
        {"help", no_argument, NULL, 'h'},
        {NULL, 0, NULL, 0}};
    const char *fabric_path = NULL, *integrator = NULL, *form = NULL, *out_dir = NULL;
    const char *resume_dir = NULL, *run_opt = NULL;
    double rtol = 0, atol = 0, spacing = 0, t_max = 0, strain_limit = 0;
    int csv = 0, quiet = 0, c;
    long max_steps = 0;
    int max_order = 0;
    int method_static = 0, linsol = 0;
    while ((c = getopt_long(argc, argv, "qh", opts, NULL)) != -1) {
        switch (c) {
        case O_FABRIC: fabric_path = optarg; break;
        case O_INTEGRATOR: integrator = optarg; break;
        case O_RTOL:
            if (parse_quantity("--rtol", optarg, DRAPE_DIM_NONE, &rtol)) return 2;
            if (!(rtol > 0 && rtol < 1)) return usage_error("--rtol: must be in (0, 1), got %s%s", optarg, "");
            break;
        case O_ATOL:
            if (parse_quantity("--atol", optarg, DRAPE_DIM_LENGTH, &atol)) return 2;
            if (!(atol > 0)) return usage_error("--atol: must be positive, got %s%s", optarg, "");
            break;
        case O_SPACING:
            if (parse_quantity("--spacing", optarg, DRAPE_DIM_LENGTH, &spacing)) return 2;
            if (!(spacing > 0)) return usage_error("--spacing: must be positive, got %s%s", optarg, "");
            break;
        case O_FORM: form = optarg; break;
        case O_TMAX:
            if (parse_quantity("--t-max", optarg, DRAPE_DIM_TIME, &t_max)) return 2;
            if (!(t_max > 0)) return usage_error("--t-max: must be positive, got %s%s", optarg, "");
            break;
        case O_STRAIN:
            if (parse_quantity("--strain-limit", optarg, DRAPE_DIM_NONE, &strain_limit)) return 2;
            if (!(strain_limit > 0) || !isfinite(strain_limit))
                return usage_error("--strain-limit: must be a positive number, got %s%s", optarg, "");
            break;
        case O_OUT: out_dir = optarg; break;
        case O_RESUME: resume_dir = optarg; break;
        case O_LINSOL:
            if (drape_linsol_parse(optarg, &linsol) != 0)
                return usage_error("--linear-solver: expected auto, klu, schur or schur-direct, got `%s'%s", optarg, "");
            break;
        case O_METHOD:
            if (strcmp(optarg, "dynamic") == 0) method_static = 0;
            else if (strcmp(optarg, "static") == 0) method_static = 1;
            else return usage_error("--method: expected dynamic or static, got `%s'%s", optarg, "");
            break;
        case O_MAXSTEPS: {
            char *end;
            errno = 0;
            max_steps = strtol(optarg, &end, 10);
            if (errno || *end || max_steps <= 0)
                return usage_error("--max-steps: expected a positive integer, got `%s'%s", optarg, "");
            break;
        }
        case O_MAXORDER:
            if (drape_max_order_parse(optarg, &max_order) != 0)
                return usage_error("--max-order: expected an integer from 1 to 5, got `%s'%s", optarg, "");
            break;
        case O_FORMAT:
            if (strcmp(optarg, "json") == 0) csv = 0;
            else if (strcmp(optarg, "csv") == 0) csv = 1;
            else return usage_error("--format: expected json or csv, got `%s'%s", optarg, "");
            break;
        case 'q': quiet = 1; break;
        case 'h': fputs(run_usage, stdout); return 0;
        default:
            fputs("Try `drape run --help'.\n", stderr);
            return drape_error_exit_status(DRAPE_E_USAGE);
        }
        if (c != O_RESUME && c != O_FORMAT && c != 'q') run_opt = argv[optind - 1];
    }
    if (argc - optind > 1) return usage_error("run: one scene at a time, got `%s' and `%s'", argv[optind], argv[optind + 1]);
    if (resume_dir && optind < argc)
        return usage_error("--resume: no scene file with it (the run's is stored in %s/drape.h5), got `%s'",
                           resume_dir, argv[optind]);
    if (resume_dir && run_opt)
        return usage_error("--resume: only --format and -q go with it (the run's options are "
                           "stored in %s/drape.h5), got `%s'", resume_dir, run_opt);
    const char *scene_path = optind < argc ? argv[optind] : DEFAULT_SCENE;
    if (integrator) {
        int ok = 0;
        for (int i = 0; drape_integrator_names[i]; i++)
            ok |= strcmp(drape_integrator_names[i], integrator) == 0;
        if (!ok) return usage_error("--integrator: unknown integrator `%s'%s; see `drape run --help'", integrator, "");
    }
    if (form && strcmp(form, "consistent") && strcmp(form, "seed"))
        return usage_error("--energy-form: expected consistent or seed, got `%s'%s", form, "");

    drape_error err;
    drape_error_clear(&err);
    drape_scene s;
    drape_fabric f;
    drape_lattice *L = NULL;
    drape_model *m = NULL;
    drape_dc *dc = NULL;
    run_ctx rc;
    memset(&rc, 0, sizeof rc);
    drape_sim_result res;
    memset(&res, 0, sizeof res);
    drape_equilibrium_result er;
    memset(&er, 0, sizeof er);
    resume_info *ri = NULL;
    run_kv *rk = NULL;
    saved_signals sigs;
    memset(&sigs, 0, sizeof sigs);
    char *fabric_text = NULL, *scene_text = NULL;
    int status = 0, sim_ok = 0, created_dir = 0, interrupted = 0;
    drape_sim_opts so;
    drape_sim_opts_default(&so);

    /* from here on SIGINT and SIGTERM are polled, not fatal */
    catch_signals(&sigs);

    if (resume_dir) {
        ri = drape_calloc(1, sizeof *ri);
        if (!ri) goto nomem;
        if (resume_load(resume_dir, ri, &err) != 0) goto fail;
        scene_path = ri->scene_path;
        fabric_path = ri->fabric_path;
        integrator = ri->integrator;
        rtol = ri->rtol;
        atol = ri->atol;
        spacing = ri->spacing;
        t_max = ri->t_max;
        strain_limit = ri->strain_limit;
        form = ri->form;
        max_steps = ri->max_steps;
        max_order = ri->max_order;
        if (drape_linsol_parse(ri->linsol, &linsol) != 0) linsol = 0;
        out_dir = resume_dir;
    }

    if (drape_scene_load_flags(scene_path, fabric_path ? DRAPE_SCENE_LOAD_FABRIC_OVERRIDDEN : 0u, &s,
                               &err, resume_dir ? NULL : drape_cli_warn, NULL) != 0)
        goto fail;
    if (fabric_path) snprintf(s.fabric_path, sizeof s.fabric_path, "%s", fabric_path);
    if (integrator) snprintf(s.integrator, sizeof s.integrator, "%s", integrator);
    if (rtol > 0) s.rtol = rtol;
    if (atol > 0) s.atol = atol;
    if (spacing > 0) s.spacing = spacing;
    if (t_max > 0) s.t_max = t_max;
    if (strain_limit > 0) s.strain_limit = strain_limit;
    if (max_order > 0) s.max_order = max_order;
    if (form) s.energy_form = strcmp(form, "seed") == 0 ? DRAPE_FORM_SEED : DRAPE_FORM_CONSISTENT;

    if (drape_fabric_load(s.fabric_path, &f, &err, resume_dir ? NULL : drape_cli_warn, NULL) != 0)
        goto fail;
    if (drape_scene_check_with_fabric(&s, &f, &err) != 0) goto fail;
    L = drape_lattice_new(&s, &f, &err);
    if (!L) goto fail;
    if (ri && ri->ck.n != L->n) {
        drape_error_set(&err, DRAPE_E_IO, ri->h5_path, 0, 0, NULL,
                        "--resume: the stored state has %d particles, the scene's lattice %d",
                        ri->ck.n, L->n);
        goto fail;
    }
    drape_model_opts mo;
    drape_model_opts_from_scene(&s, &mo);
    m = drape_model_new(L, &f, &mo, &err);
    if (!m) goto fail;

    if (out_dir) {
        if (drape_cli_ensure_dir(out_dir, &created_dir, &err) != 0) goto fail;
        if (s.has_frames && s.out_obj) {
            rc.obj = drape_obj_new(out_dir, L, f.name, drape_scene_kind_name(s.kind), &err);
            if (!rc.obj) goto fail;
        }
        if (s.out_hdf5) {
            rc.h5 = drape_h5_open(out_dir, L, &err);
            if (!rc.h5) goto fail;
            if (ri && ri->had_h5 && drape_h5_copy_frames(rc.h5, ri->h5_path, &err) != 0) goto fail;
        }
    }
    rc.model = m;
    rc.progress = !quiet && isatty(STDERR_FILENO);
    rc.t_max = s.t_max;
    rc.frame = ri ? ri->frames : 0;

    if (method_static) {
        sim_ok = run_static(m, &f, &rc, &res, &er, &err);
        if (stop_signal) { /* the solve stops at its next iteration */
            interrupted = 1;
            res.status = DRAPE_SIM_INTERRUPTED;
            drape_obj_discard(rc.obj);
            drape_h5_discard(rc.h5);
            rc.obj = NULL;
            rc.h5 = NULL;
            if (created_dir) rmdir(out_dir);
        }
    } else {
        drape_sim_opts_from_scene(&s, &so);
        so.observe_progress = rc.progress;
        if (max_steps > 0) so.max_steps = max_steps;
        so.linsol = linsol;
        so.stop = &stop_signal;
        if (ri) {
            so.t0 = ri->ck.t_s;
            so.x0 = ri->ck.x;
            so.v0 = ri->ck.v;
            so.eq_below_since = ri->below_since;
            so.diag_ref = &ri->ref;
        }
        sim_ok = drape_sim_run(m, &so, (rc.obj || rc.h5 || rc.progress) ? observe : NULL, &rc,
                               &res, &err) == 0;
        interrupted = sim_ok && res.status == DRAPE_SIM_INTERRUPTED;
        if (ri) { /* one run: the counters and time of both parts */
            add_previous(&ri->ck, "steps", &res.stats.steps);
            add_previous(&ri->ck, "rhs_evals", &res.stats.rhs_evals);
            add_previous(&ri->ck, "jac_evals", &res.stats.jac_evals);
            add_previous(&ri->ck, "lin_setups", &res.stats.lin_setups);
            add_previous(&ri->ck, "nonlin_iters", &res.stats.nonlin_iters);
            add_previous(&ri->ck, "err_test_fails", &res.stats.err_test_fails);
            add_previous(&ri->ck, "conv_fails", &res.stats.conv_fails);
            add_previous(&ri->ck, "lin_iters", &res.stats.lin_iters);
            add_previous(&ri->ck, "lin_factors", &res.stats.lin_factors);
            add_previous(&ri->ck, "integrator_switches", &res.stats.switches);
            const drape_kv *w = drape_kv_find(ri->ck.stats, ri->ck.n_stats, "wall_s");
            if (w && !w->text && w->value >= 0) res.wall_s += w->value;
        }
    }
    if (!sim_ok && err.kind != DRAPE_E_NUMERIC && !interrupted) goto fail; /* I/O or input: no result */
    if (!sim_ok && !interrupted) {
        drape_cli_print_error(&err);
        status = drape_error_exit_status(err.kind);
    }
    int have_state = sim_ok && !(method_static && interrupted);

    /* measurements on the final state */
    drape_shadow sh;
    int have_dc = 0, have_cant = 0;
    drape_cantilever cant;
    if (have_state && (s.kind == DRAPE_SCENE_CUSICK || s.kind == DRAPE_SCENE_TABLE)) {
        drape_error e2;
        drape_error_clear(&e2);
        dc = drape_dc_new(L, NULL, &e2);
        if (dc && drape_dc_measure(dc, res.x, &sh, &e2) == 0) have_dc = 1;
        else drape_cli_print_error(&e2);
    }
    if (have_state && s.kind == DRAPE_SCENE_CANTILEVER) {
        drape_error e2;
        drape_error_clear(&e2);
        if (drape_cantilever_measure(L, res.x, f.weight, DRAPE_G_STANDARD, &cant, &e2) == 0)
            have_cant = 1;
        else drape_cli_print_error(&e2);
    }

    result_fields r;
    r.n = 0;
    add_str(&r, "fabric", f.name);
    add_str(&r, "scene", drape_scene_kind_name(s.kind));
    add_str(&r, "integrator", res.integrator[0] ? res.integrator : s.integrator);
    add_str(&r, "energy_form", drape_energy_form_name(s.energy_form));
    add_num(&r, "rtol", s.rtol);
    add_num(&r, "atol", s.atol);
    add_num(&r, "spacing_m", s.spacing);
    add_int(&r, "particles", L->n);
    add_int(&r, "free_particles", L->n_free);
    add_str(&r, "status", drape_sim_status_name(res.status));
    add_num(&r, "t_end_s", res.t_end_s);
    add_num(&r, "dc", have_dc ? sh.dc : NAN);
    add_int(&r, "nodes", have_dc ? sh.nodes : NAN);
    add_num(&r, "r_min_m", have_dc ? sh.r_min_m : NAN);
    add_num(&r, "r_max_m", have_dc ? sh.r_max_m : NAN);
    add_num(&r, "tip_angle_deg", have_cant ? cant.tip_angle_deg : NAN);
    add_num(&r, "bending_length_m", have_cant ? cant.bending_length_m : NAN);
    add_num(&r, "flexural_rigidity_Nm", have_cant ? cant.flexural_rigidity_Nm : NAN);
    add_num(&r, "energy_J.kinetic", have_state ? res.kinetic_J : NAN);
    add_num(&r, "energy_J.stretch", have_state ? res.energy.stretch : NAN);
    add_num(&r, "energy_J.bend", have_state ? res.energy.bend : NAN);
    add_num(&r, "energy_J.shear", have_state ? res.energy.shear : NAN);
    add_num(&r, "energy_J.gravity", have_state ? res.energy.gravity : NAN);
    add_num(&r, "max_strain", have_state ? res.max_strain : NAN);
    add_num(&r, "wall_s", res.wall_s);
    add_int(&r, "steps", res.stats.steps);
    add_int(&r, "rhs_evals", res.stats.rhs_evals);
    add_int(&r, "jac_evals", res.stats.jac_evals);
    add_int(&r, "lin_setups", res.stats.lin_setups);
    add_int(&r, "nonlin_iters", res.stats.nonlin_iters);
    add_int(&r, "err_test_fails", res.stats.err_test_fails);
    add_int(&r, "conv_fails", res.stats.conv_fails);
    add_num(&r, "mass_kg", L->mass_total);
    add_num(&r, "area_nominal_m2", L->area_nominal);
    add_num(&r, "area_mesh_m2", have_dc ? sh.a_specimen_mesh_m2 : NAN);
    add_num(&r, "max_speed_m_s", have_state || !sim_ok ? res.max_speed : NAN);
    add_str(&r, "method", method_static ? "static" : "dynamic");
    /* static method only (null for dynamic runs) */
    add_int(&r, "iterations", method_static ? er.iterations : NAN);
    add_int(&r, "factorizations", method_static ? er.factorizations : NAN);
    if (method_static && er.certified >= 0) add_str(&r, "certified", er.certified ? "minimum" : "saddle");
    else add_num(&r, "certified", NAN);
    add_num(&r, "min_pivot_N_m", method_static ? er.min_pivot : NAN);
    add_num(&r, "omega_min_rad_s", method_static ? er.omega_min : NAN);
    add_num(&r, "max_force_rel", method_static ? er.max_force_rel : NAN);
    add_str(&r, "linear_solver", method_static ? "cholmod"
                                 : res.stats.linsol > 0 ? drape_linsol_name(res.stats.linsol)
                                                        : "none");
    add_int(&r, "lin_iters", res.stats.lin_iters);
    add_int(&r, "lin_factors", res.stats.lin_factors);
    /* the speed the equilibrium test used: largest particle speed averaged
     * over the last check interval (sim.h); null without checks */
    add_num(&r, "mean_speed_m_s", method_static ? NAN : res.check_speed);
    /* auto only (-1, null, for the others): changes between cvode-bdf and arkode-erk */
    add_int(&r, "integrator_switches", res.stats.switches);
    /* cvode-bdf's highest order (alone or inside auto); null for the others */
    {
        int bdf = method_static ? 0
                                : drape_integrator_bdf_order(res.integrator[0] ? res.integrator
                                                                               : s.integrator,
                                                             s.max_order);
        add_int(&r, "max_order", bdf > 0 ? bdf : NAN);
    }
    if (!fields_match_keys(&r)) {
        drape_error_set(&err, DRAPE_E_INTERNAL, NULL, 0, 0, NULL,
                        "result fields differ from drape_cli_run_keys");
        goto fail;
    }

    if (rc.obj) { drape_obj_free(rc.obj); rc.obj = NULL; } /* the frames stay */
    /* An interrupted dynamic run with --out always leaves DIR/drape.h5 (a
     * checkpoint without frames when the scene writes no HDF5). */
    if (interrupted && !method_static && out_dir && !rc.h5) {
        rc.h5 = drape_h5_open(out_dir, L, &err);
        if (!rc.h5) goto fail;
    }
    if (rc.h5) {
        drape_kv kv[MAX_FIELDS + 2];
        int nkv = 0;
        for (int i = 0; i < r.n; i++)
            kv[nkv++] = (drape_kv){r.f[i].key, r.f[i].text, r.f[i].value};
        char diag[DRAPE_ERROR_MSG_MAX + 600];
        if (!sim_ok && err.kind != DRAPE_OK)
            kv[nkv++] = (drape_kv){"error", drape_error_format(&err, diag, sizeof diag), 0.0};
        /* the inputs as attributes; they were just read, so a failure here
         * (NULL) only leaves the attribute out (and a resume impossible) */
        fabric_text = drape_cli_read_file(s.fabric_path, DRAPE_YDOC_MAX_BYTES, NULL, NULL);
        scene_text = drape_cli_read_file(scene_path, DRAPE_YDOC_MAX_BYTES, NULL, NULL);
        drape_h5_final fin = {res.t_end_s, res.x, res.v, kv, nkv, fabric_text, scene_text,
                              NULL, 0};
        if (!method_static) {
            if (!(rk = drape_calloc(1, sizeof *rk))) goto nomem;
            fill_run_kv(rk, scene_path, &s, &so, &res, rc.frame);
            fin.run = rk->kv;
            fin.n_run = rk->n;
        }
        drape_h5 *h = rc.h5;
        rc.h5 = NULL;
        if (drape_h5_close(h, &fin, &err) != 0) goto fail;
    }
    /* a resumed run that finished: the checkpoint-only file has served */
    if (ri && !ri->had_h5 && !interrupted && !s.out_hdf5) {
        char p[4300];
        unlink(ri->h5_path);
        snprintf(p, sizeof p, "%s/drape.xmf", out_dir);
        unlink(p);
    }
    if (csv) print_csv(stdout, &r);
    else print_json(stdout, &r);
    if (fflush(stdout) != 0) {
        drape_error_set(&err, DRAPE_E_IO, "<stdout>", 0, 0, NULL, "cannot write the result");
        goto fail;
    }
    if (interrupted) {
        int sig = stop_signal;
        if (rc.progress) fputc('\n', stderr); /* end the progress line */
        if (method_static)
            fprintf(stderr, "drape: run interrupted by %s during the static solve; nothing "
                    "written\n", signal_name(sig));
        else if (out_dir)
            fprintf(stderr, "drape: run interrupted by %s at t = %.9g s; continue with "
                    "`drape run --resume %s`\n", signal_name(sig), res.t_end_s, out_dir);
        else
            fprintf(stderr, "drape: run interrupted by %s at t = %.9g s (no --out DIR: "
                    "nothing to resume from)\n", signal_name(sig), res.t_end_s);
        status = interrupted_status(sig);
    }
    goto out;
nomem:
    drape_error_set(&err, DRAPE_E_NOMEM, NULL, 0, 0, NULL, "out of memory");
fail:
    drape_cli_print_error(&err);
    status = drape_error_exit_status(err.kind);
    /* a failed run leaves nothing of its own behind (issue 7) */
    drape_obj_discard(rc.obj);
    rc.obj = NULL;
    drape_h5_discard(rc.h5);
    rc.h5 = NULL;
    if (created_dir) rmdir(out_dir); /* only if empty */
out:
    restore_signals(&sigs);
    drape_obj_free(rc.obj);
    drape_h5_discard(rc.h5);
    drape_dc_free(dc);
    drape_sim_result_free(&res);
    drape_equilibrium_result_free(&er);
    drape_model_free(m);
    drape_lattice_free(L);
    drape_free(fabric_text);
    drape_free(scene_text);
    drape_free(rk);
    if (ri) drape_h5_checkpoint_free(&ri->ck);
    drape_free(ri);
    return status;
}
