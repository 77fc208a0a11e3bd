/* cli_run.c: one run of `drape run` (its command line: cli_run_args.c):
 * load a scene and its fabric, build the lattice and model, integrate or
 * solve, measure, and print one JSON object (or a CSV header and row) on
 * stdout.  Frames (OBJ, HDF5 + XDMF) are written only with --out DIR.
 * Progress goes to stderr only when it is a terminal.  Keys of the result
 * are a contract.
 *
 * Interruption and resume (docs/reliability.md): SIGINT and
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
#include <limits.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli.h"
#include "cli_data.h"
#include "cli_io.h"
#include "cli_resume.h"
#include "cli_result.h"
#include "cli_run.h"
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

/* A fall that gains more than this fraction of the energy it dissipates
 * (energy_gain_J against energy_total_start_J - energy_total_end_J) is
 * warned about: measured gains are either zero or of the order of the
 * whole dissipated energy (docs/ensemble.md, "Energy gained by the
 * fixed-step fall"). */
#define DRAPE_CLI_GAIN_WARN 1e-2

/* ---- result keys --------------------------------------------------------- */

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
    "integrator_switches", "max_order",
    /* repeated specimens (cli_specimens.c) and the fall method */
    "cpu_s", "dc_sd", "dc_ci95", "dc_mode", "nodes_hist", "specimens",
    "specimens_failed", "seed", "fall_time_s", "fall_step_s",
    /* the animate method's step; the energy balance of dynamic runs */
    "step_s", "substeps", "energy_total_start_J", "energy_total_end_J",
    "energy_max_rise_J", "max_strain_peak", "energy_rescales",
    /* the energy terms the model was built with, joined by `+`
     * (bias only where the fabric gives a bias curve) */
    "terms",
    /* when the fall ended (it goes on while the cloth swings) */
    "fall_end_s",
    /* the fall's error control (--fall-tol), and its steps */
    "fall_tol_m", "fall_steps",
    /* the shear damping (damping.shear, --damping-shear) */
    "damping_shear_s",
    /* energy the fall's integrator created, and whether the fall was redone */
    "energy_gain_J", "fall_redone",
    /* the fall's fold phase at half its step */
    "fall_fold_time_s", "fall_fold_step_s",
    /* a refused longer step of the fall tried again */
    "fall_retry_s", "fall_refused",
    /* a fall ended because it kept gaining energy */
    "fall_pumped",
    /* where a redone fall was taken up again */
    "fall_redo_from_s",
    /* the perturbation that ran (docs/model.md 2): its form, RMS height (field)
     * or half range (particle), and the field's band of wavelengths */
    "perturbation_kind", "perturbation_amplitude_m", "perturbation_lambda_min_m",
    "perturbation_lambda_max_m",
    /* --convergence (cli_convergence.c): the same specimens at a spacing
     * sqrt(2) coarser; null without it */
    "spacing_coarse_m", "dc_spacing_delta", "dc_spacing_delta_ci95", "nodes_spacing_p", NULL};

int drape_cli_run_nkeys(void)
{
    int n = 0;
    while (drape_cli_run_keys[n]) n++;
    return n;
}

/* ---- observers ------------------------------------------------------------ */

typedef struct run_ctx {
    drape_model *model;
    drape_obj *obj;
    drape_h5 *h5;
    int frame;
    int progress; /* print progress on stderr */
    double t_max;
    int has_eq;      /* the run ends at equilibrium: speed below eq_speed */
    double eq_speed; /* m/s */
    /* the energy balance over the output points (dynamic runs): total
     * E = kinetic + potential (gravity included); no work is done on the
     * cloth (supports are fixed), so E should never rise */
    int n_energy;
    double e_start, e_prev, e_end, e_max_rise, strain_peak;
} run_ctx;

static void energy_balance(run_ctx *c, const drape_sim_event *ev)
{
    drape_energies E;
    const drape_lattice *L = drape_model_lattice(c->model);
    if (drape_model_energy(c->model, ev->x, &E) != 0) return;
    double e = drape_sim_kinetic_energy(L, ev->v) + E.stretch + E.bend + E.shear + E.gravity;
    double strain = drape_model_max_strain(c->model, ev->x);
    if (c->n_energy == 0) {
        c->e_start = e;
        c->e_max_rise = -INFINITY;
        c->strain_peak = strain;
    } else {
        if (e - c->e_prev > c->e_max_rise) c->e_max_rise = e - c->e_prev;
        if (strain > c->strain_peak) c->strain_peak = strain;
    }
    c->e_prev = c->e_end = e;
    c->n_energy++;
}

static int observe(void *ctx, const drape_sim_event *ev, drape_error *err)
{
    run_ctx *c = ctx;
    energy_balance(c, ev);
    if (c->progress) {
        /* what is left: the speed still to lose, or the simulated time */
        if (c->has_eq)
            fprintf(stderr,
                    "\rdrape: t = %.4f s, %ld steps, max speed %.2e m/s, at rest below %.0e m/s"
                    " (stops by t = %g s) ",
                    ev->t, ev->steps, ev->max_speed, c->eq_speed, c->t_max);
        else
            fprintf(stderr, "\rdrape: t = %.4f s, %ld steps, %.4g s left to t = %g s ", ev->t,
                    ev->steps, c->t_max - ev->t, c->t_max);
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
 * job, stays ignored).  SA_RESTART: reads and writes are not cut short.
 * An ensemble's specimen (child), or a run of `drape batch` (which sets
 * DRAPE_SIGNAL_FORWARDED in its runs' environment), keeps the handler for
 * a second signal: Ctrl-C, `timeout`, systemd or Slurm signal the whole
 * process group or tree and the parent forwards the signal once more, so
 * such a run sees it twice; only a top-level run takes a second signal as
 * the user's "stop now". */
static void catch_signals(saved_signals *sv, int reset)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_stop_signal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESTART | (reset ? SA_RESETHAND : 0);
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

/* The fabric loader's warnings, but those about the bias curve only when
 * the run uses it (ctx: the scene's DRAPE_TERM_* mask): a library run in
 * the seed's model (--terms without bias) is not told about a term it
 * leaves out.  `drape check` prints them all. */
/* A number of the checkpoint's /stats (the interrupted run's result):
 * NAN where it is missing, text or not finite. */
static double ck_stat(const resume_info *ri, const char *key)
{
    const drape_kv *kv = drape_kv_find(ri->ck.stats, ri->ck.n_stats, key);
    return kv && !kv->text && isfinite(kv->value) ? kv->value : NAN;
}

static void fabric_warn(void *ctx, const drape_error *w)
{
    unsigned terms = *(const unsigned *)ctx;
    if (!(terms & DRAPE_TERM_BIAS) && strncmp(w->key, "bending.bias", 12) == 0) return;
    drape_cli_warn(NULL, w);
}

void drape_cli_run_remove_stale(const char *dir)
{
    drape_cli_remove_stale_tmp(dir, "frame_[0-9][0-9][0-9][0-9][0-9][0-9].obj",
                               DRAPE_CLI_TMP_PID_FIRST);
    drape_cli_remove_stale_tmp(dir, "drape.h5", DRAPE_CLI_TMP_PID_FIRST);
    drape_cli_remove_stale_tmp(dir, "drape.xmf", DRAPE_CLI_TMP_PID_FIRST);
}

/* ---- methods ----------------------------------------------------------------- */

/* The fall method's numbers (time 0: the static method). */
typedef struct fall_params {
    double time, step;           /* s: least duration, fixed step */
    double fold_time, fold_step; /* s: the fold phase (0, 0: none) */
    double swing;                /* fraction of the peak kinetic energy */
    double retry;                /* s: a refused longer step tried again */
    double tol;                  /* m: > 0 error-controlled (--fall-tol) */
} fall_params;

/* The static method: minimise E_pot from the initial state and present the
 * result as a run (status equilibrium or failed, no time, no integrator
 * statistics).  Frames: the final state only.  Returns 1 on success. */
static int run_static(drape_model *m, const drape_fabric *f, const fall_params *fp, run_ctx *rc,
                      double strain_limit, drape_sim_result *res,
                      drape_equilibrium_result *er, drape_error *err)
{
    const drape_lattice *L = drape_model_lattice(m);
    drape_equilibrium_opts eo;
    drape_equilibrium_opts_from_fabric(&eo, f);
    double fall_time = fp->time, fall_tol = fp->tol;
    eo.dyn_time = fall_time; /* the fall method: damped large-step dynamics first */
    eo.dyn_dt = fp->step;
    eo.dyn_time_fold = fp->fold_time; /* the first part at a shorter step */
    eo.dyn_dt_fold = fp->fold_step;
    eo.dyn_ke_frac = fp->swing; /* and on while the cloth still swings */
    eo.dyn_time_max = DRAPE_FALL_TIME_MAX * fall_time;
    eo.dyn_dt_swing = DRAPE_FALL_SWING_STEP * fp->step; /* at a longer step */
    eo.dyn_retry = fp->retry; /* a longer step refused is tried again */
    eo.dyn_tol = fall_tol; /* or the step chosen by its error (--fall-tol) */
    /* a fixed-step fall that gains energy falls again, error-controlled */
    eo.dyn_redo_tol = fall_tol > 0.0 ? 0.0 : DRAPE_FALL_REDO_TOL;
    /* after a fall a limp cloth can still be far from rest: the settling
     * may need more than the static method's iterations (measured: a
     * ponte-roma specimen, 704) */
    if (fall_time > 0.0) eo.max_iters = DRAPE_FALL_MAX_ITERS;
    eo.stop = &stop_signal;
    snprintf(res->integrator, sizeof res->integrator, "%s", fall_time > 0.0 ? "fall" : "static");
    res->status = DRAPE_SIM_FAILED;
    res->t_end_s = NAN;
    /* no integrator: every counter "not available" (-1), printed as null */
    res->stats.steps = res->stats.rhs_evals = res->stats.jac_evals = -1;
    res->stats.lin_setups = res->stats.nonlin_iters = res->stats.err_test_fails = -1;
    res->stats.conv_fails = res->stats.lin_iters = res->stats.lin_factors = -1;
    res->stats.switches = -1;
    res->stats.energy_rescales = -1;
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
    /* the fall: a certified minimum whose residual stalled at the roundoff
     * floor just above the tolerance is at rest (measured at 0.5 cm: 1.09e-8
     * against 1e-8 x weight) */
    int at_floor = fall_time > 0.0 && er->status == DRAPE_EQ_STALLED && er->certified == 1 &&
                   er->max_force_rel <= DRAPE_FALL_FLOOR * eo.tol;
    if (er->status != DRAPE_EQ_CONVERGED && !at_floor) {
        drape_error_set(err, DRAPE_E_NUMERIC, NULL, 0, 0, NULL,
                        "static equilibrium not reached (%s after %d iterations, largest "
                        "residual force %.3g x particle weight); hint: try --method dynamic",
                        drape_equilibrium_status_name(er->status), er->iterations,
                        er->max_force_rel);
        return 0;
    }
    /* the strain limit (end.strain_limit, --strain-limit) holds for the
     * rest state the solver found, as for every state of a dynamic run */
    if (strain_limit > 0.0 && res->max_strain > strain_limit) {
        drape_error_set(err, DRAPE_E_NUMERIC, NULL, 0, 0, NULL,
                        "the rest state's largest strain %.4g exceeds the strain limit %.4g "
                        "(end.strain_limit, --strain-limit)", res->max_strain, strain_limit);
        return 0;
    }
    res->status = DRAPE_SIM_EQUILIBRIUM;
    drape_sim_event ev = {DRAPE_SIM_AT_END, 0.0, res->x, res->v, er->iterations, 0.0};
    if ((rc->obj || rc->h5) && observe(rc, &ev, err) != 0) return 0;
    return 1;
}

int drape_cli_run_one(const run_args *ra, run_child *child)
{
    const char *scene_path = ra->scene_path, *fabric_path = ra->fabric_path;
    const char *integrator = ra->integrator, *form = ra->form, *out_dir = ra->out_dir;
    const char *resume_dir = ra->resume_dir;
    double rtol = ra->rtol, atol = ra->atol, spacing = ra->spacing, t_max = ra->t_max;
    double strain_limit = ra->strain_limit;
    long max_steps = ra->max_steps;
    int max_order = ra->max_order, linsol = ra->linsol, csv = ra->csv, quiet = ra->quiet;
    int method = ra->method;
    double cpu0 = drape_cli_cpu_s();
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
    catch_signals(&sigs, child == NULL && !getenv("DRAPE_SIGNAL_FORWARDED"));

    if (resume_dir) {
        ri = drape_calloc(1, sizeof *ri);
        if (!ri) goto nomem;
        if (drape_cli_resume_load(resume_dir, ri, &err) != 0) goto fail;
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
                               &err, resume_dir || ra->no_warnings ? NULL : drape_cli_warn, NULL) != 0)
        goto fail;
    if (fabric_path &&
        (size_t)snprintf(s.fabric_path, sizeof s.fabric_path, "%s", fabric_path) >= sizeof s.fabric_path) {
        drape_error_set(&err, DRAPE_E_IO, fabric_path, 0, 0, NULL, "path too long");
        goto fail;
    }
    if (integrator) snprintf(s.integrator, sizeof s.integrator, "%s", integrator);
    if (rtol > 0) s.rtol = rtol;
    if (atol > 0) s.atol = atol;
    if (spacing > 0) {
        s.spacing = spacing;
        if (!resume_dir) s.at_spacing.line = DRAPE_SCENE_POS_COMMAND_LINE;
    }
    if (t_max > 0) s.t_max = t_max;
    if (strain_limit > 0) s.strain_limit = strain_limit;
    if (max_order > 0) s.max_order = max_order;
    if (form) s.energy_form = strcmp(form, "seed") == 0 ? DRAPE_FORM_SEED : DRAPE_FORM_CONSISTENT;
    if (ra->has_seed) s.perturb_seed = ra->seed;
    if (ra->fall_time > 0) s.fall_time = ra->fall_time;
    if (ra->fall_step > 0) s.fall_step = ra->fall_step;
    if (ra->fall_swing >= 0) s.fall_swing = ra->fall_swing;
    if (ra->fall_tol >= 0) s.fall_tol = ra->fall_tol;
    if (ra->fall_fold_time >= 0) s.fall_fold_time = ra->fall_fold_time;
    if (ra->fall_retry >= 0) s.fall_retry = ra->fall_retry;
    if (ra->damping_shear >= 0) s.damping_shear = ra->damping_shear;
    if (ri && ri->damping_shear >= 0) s.damping_shear = ri->damping_shear; /* what ran */
    if (ra->substeps > 0) s.substeps = ra->substeps;
    if (ra->terms) s.terms = ra->terms;
    if (ri && ri->terms >= 1.0 && ri->terms <= (double)DRAPE_TERM_ALL) /* what ran */
        s.terms = (unsigned)ri->terms;
    /* the seed that ran (--seed included), not the scene's; a checkpoint
     * that did not store it: unknown, reported null */
    int seed_known = !ri || !isnan(ri->seed);
    if (ri && seed_known) s.perturb_seed = (unsigned long)ri->seed;
    /* an oblique strip is a staircase of the lattice: without shear its
     * cells turn freely (docs/scenes.md); allowed, as docs/validation.md
     * runs it on purpose, but said */
    if (s.shape == DRAPE_SHAPE_STRIP && s.strip_angle > 0.0 && s.strip_angle < 90.0 &&
        !(s.terms & DRAPE_TERM_SHEAR) && !ra->no_warnings && !resume_dir) {
        drape_error w;
        drape_error_clear(&w);
        drape_error_set(&w, DRAPE_E_INPUT, scene_path, 0, 0, "specimen.direction",
                        "a strip at %g deg to the warp without the shear term: its staircase "
                        "of lattice cells shears freely (docs/scenes.md)", s.strip_angle);
        drape_cli_warn(NULL, &w);
    }
    if (ri && ri->fixed_step > 0.0) { /* animate's step (its --substeps) */
        double frame;
        drape_scene_animate_step(&s, &frame, NULL);
        s.substeps = (int)lround(frame / ri->fixed_step);
    }
    /* --resume continues a dynamic run (only those are interrupted with a
     * checkpoint); otherwise --method, the scene's solver.method, and the
     * default: the fall method where the scene asks for an equilibrium */
    if (resume_dir) method = DRAPE_METHOD_DYNAMIC;
    if (method == DRAPE_METHOD_DEFAULT) method = s.method;
    if (method == DRAPE_METHOD_DEFAULT)
        method = s.has_equilibrium ? DRAPE_METHOD_FALL : DRAPE_METHOD_DYNAMIC;
    /* animate: the dynamic run with the fixed-step integrator */
    if (method == DRAPE_METHOD_ANIMATE) snprintf(s.integrator, sizeof s.integrator, "animate");
    int method_static = method == DRAPE_METHOD_STATIC || method == DRAPE_METHOD_FALL;
    fall_params fp = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
    if (method == DRAPE_METHOD_FALL) {
        drape_scene_fall_params(&s, &fp.time, &fp.step);
        fp.tol = s.fall_tol;
        /* the fold phase belongs to the fixed step */
        if (!(fp.tol > 0.0)) {
            drape_scene_fall_fold(&s, fp.time, fp.step, &fp.fold_time, &fp.fold_step);
            fp.retry = s.fall_retry; /* so is the retry */
        }
    }
    fp.swing = drape_scene_fall_swing(&s);
    double fall_time = fp.time, fall_step = fp.step;

    if (drape_fabric_load(s.fabric_path, &f, &err,
                          resume_dir || ra->no_warnings ? NULL : fabric_warn, &s.terms) != 0)
        goto fail;
    /* the internal shear damping: the fabric's unless the scene or
     * --damping-shear gives one; from here on s holds what runs */
    s.damping_shear = drape_scene_damping_shear(&s, &f);
    if (drape_scene_check_with_fabric(&s, &f, &err) != 0) goto fail;
    /* KLU's fill grows faster than CHOLMOD's (docs/scenes.md, "Memory") */
    if (linsol == DRAPE_LINSOL_KLU && method == DRAPE_METHOD_DYNAMIC &&
        drape_scene_check_memory(&s, DRAPE_SCENE_MEM_KLU, &err) != 0)
        goto fail;
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
    /* the static solver measures its residual in particle weights */
    if (method_static && !(drape_model_parts(m) & DRAPE_PART_GRAVITY)) {
        drape_error_set(&err, DRAPE_E_INPUT, NULL, 0, 0, "terms",
                        "the %s method settles the cloth under its weight: the energy terms "
                        "must include gravity", method == DRAPE_METHOD_FALL ? "fall" : "static");
        goto fail;
    }
    if (ra->check_only) goto out;

    if (out_dir && !(s.has_frames && s.out_obj) && !s.out_hdf5 && !ra->no_warnings &&
        s.kind != DRAPE_SCENE_CUSICK && s.kind != DRAPE_SCENE_TABLE) {
        drape_error w;
        drape_error_clear(&w);
        drape_error_set(&w, DRAPE_E_INPUT, scene_path, 0, 0, "output",
                        "--out: the scene asks for no frames and no drape.h5 (e.g. `output: "
                        "{frames: {every: 0.1 s, obj: true}, hdf5: true}`): %s gets only the "
                        "checkpoint of an interrupted dynamic run", out_dir);
        drape_cli_warn(NULL, &w);
    }
    if (out_dir) {
        if (drape_cli_ensure_dir(out_dir, &created_dir, &err) != 0) goto fail;
        /* one writer at a time (a specimen's directory is its ensemble's);
         * held, DIR has no live writer: a killed run's temporaries go */
        int held = 0;
        if (!child && !ra->check_only && drape_cli_lock_dir(out_dir, &held, &err) != 0) goto fail;
        if (held) {
            drape_cli_run_remove_stale(out_dir);
            drape_cli_remove_stale_tmp(out_dir, "shadow.svg", DRAPE_CLI_TMP_PID_LAST);
            drape_cli_remove_stale_tmp(out_dir, "shadow.png", DRAPE_CLI_TMP_PID_LAST);
        }
        /* a single run in an ensemble's directory: DIR is this run's now
         * (its shadow.svg replaces the ensemble's), and --resume DIR is
         * its (docs/outputs.md) */
        if (!child && !resume_dir && !ra->check_only) {
            char man[4200];
            snprintf(man, sizeof man, "%s/" DRAPE_ENSEMBLE_MANIFEST, out_dir);
            unlink(man);
            if (held)
                drape_cli_remove_stale_tmp(out_dir, DRAPE_ENSEMBLE_MANIFEST,
                                           DRAPE_CLI_TMP_PID_LAST);
        }
        if (!child && (s.kind == DRAPE_SCENE_CUSICK || s.kind == DRAPE_SCENE_TABLE) &&
            (drape_cli_check_target(out_dir, "shadow.svg", &err) != 0 ||
             drape_cli_check_target(out_dir, "shadow.png", &err) != 0))
            goto fail;
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
    rc.has_eq = s.has_equilibrium;
    rc.eq_speed = s.eq_speed;
    rc.frame = ri ? ri->frames : 0;
    if (ri) { /* the energy balance covers the whole run, as the counters do */
        double e0 = ck_stat(ri, "energy_total_start_J"), e1 = ck_stat(ri, "energy_total_end_J");
        double emr = ck_stat(ri, "energy_max_rise_J"), sp = ck_stat(ri, "max_strain_peak");
        if (isfinite(e0) && isfinite(e1)) {
            rc.n_energy = 1;
            rc.e_start = e0;
            rc.e_prev = rc.e_end = e1;
            rc.e_max_rise = isfinite(emr) ? emr : -INFINITY;
            rc.strain_peak = isfinite(sp) ? sp : 0.0;
        }
    }

    if (method_static) {
        sim_ok = run_static(m, &f, &fp, &rc, s.strain_limit, &res, &er, &err);
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
        so.observe_progress = 1; /* the energy balance at every output point */
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
        sim_ok = drape_sim_run(m, &so, observe, &rc,
                               &res, &err) == 0;
        interrupted = sim_ok && res.status == DRAPE_SIM_INTERRUPTED;
        if (ri) { /* one run: the counters and time of both parts */
            drape_cli_resume_add_previous(&ri->ck, "steps", &res.stats.steps);
            drape_cli_resume_add_previous(&ri->ck, "rhs_evals", &res.stats.rhs_evals);
            drape_cli_resume_add_previous(&ri->ck, "jac_evals", &res.stats.jac_evals);
            drape_cli_resume_add_previous(&ri->ck, "lin_setups", &res.stats.lin_setups);
            drape_cli_resume_add_previous(&ri->ck, "nonlin_iters", &res.stats.nonlin_iters);
            drape_cli_resume_add_previous(&ri->ck, "err_test_fails", &res.stats.err_test_fails);
            drape_cli_resume_add_previous(&ri->ck, "conv_fails", &res.stats.conv_fails);
            drape_cli_resume_add_previous(&ri->ck, "lin_iters", &res.stats.lin_iters);
            drape_cli_resume_add_previous(&ri->ck, "lin_factors", &res.stats.lin_factors);
            drape_cli_resume_add_previous(&ri->ck, "integrator_switches", &res.stats.switches);
            double w = ck_stat(ri, "wall_s");
            if (w >= 0) res.wall_s += w;
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

    drape_cli_result r;
    memset(&r, 0, sizeof r);
    drape_cli_result_str(&r, "fabric", f.name);
    drape_cli_result_str(&r, "scene", drape_scene_kind_name(s.kind));
    drape_cli_result_str(&r, "integrator", res.integrator[0] ? res.integrator : s.integrator);
    drape_cli_result_str(&r, "energy_form", drape_energy_form_name(s.energy_form));
    drape_cli_result_num(&r, "rtol", s.rtol);
    drape_cli_result_num(&r, "atol", s.atol);
    drape_cli_result_num(&r, "spacing_m", s.spacing);
    drape_cli_result_int(&r, "particles", L->n);
    drape_cli_result_int(&r, "free_particles", L->n_free);
    drape_cli_result_str(&r, "status", drape_sim_status_name(res.status));
    drape_cli_result_num(&r, "t_end_s", res.t_end_s);
    drape_cli_result_num(&r, "dc", have_dc ? sh.dc : NAN);
    drape_cli_result_int(&r, "nodes", have_dc ? sh.nodes : NAN);
    drape_cli_result_num(&r, "r_min_m", have_dc ? sh.r_min_m : NAN);
    drape_cli_result_num(&r, "r_max_m", have_dc ? sh.r_max_m : NAN);
    drape_cli_result_num(&r, "tip_angle_deg", have_cant ? cant.tip_angle_deg : NAN);
    drape_cli_result_num(&r, "bending_length_m", have_cant ? cant.bending_length_m : NAN);
    drape_cli_result_num(&r, "flexural_rigidity_Nm", have_cant ? cant.flexural_rigidity_Nm : NAN);
    drape_cli_result_num(&r, "energy_J.kinetic", have_state ? res.kinetic_J : NAN);
    drape_cli_result_num(&r, "energy_J.stretch", have_state ? res.energy.stretch : NAN);
    drape_cli_result_num(&r, "energy_J.bend", have_state ? res.energy.bend : NAN);
    drape_cli_result_num(&r, "energy_J.shear", have_state ? res.energy.shear : NAN);
    drape_cli_result_num(&r, "energy_J.gravity", have_state ? res.energy.gravity : NAN);
    drape_cli_result_num(&r, "max_strain", have_state ? res.max_strain : NAN);
    drape_cli_result_num(&r, "wall_s", res.wall_s);
    drape_cli_result_int(&r, "steps", res.stats.steps);
    drape_cli_result_int(&r, "rhs_evals", res.stats.rhs_evals);
    drape_cli_result_int(&r, "jac_evals", res.stats.jac_evals);
    drape_cli_result_int(&r, "lin_setups", res.stats.lin_setups);
    drape_cli_result_int(&r, "nonlin_iters", res.stats.nonlin_iters);
    drape_cli_result_int(&r, "err_test_fails", res.stats.err_test_fails);
    drape_cli_result_int(&r, "conv_fails", res.stats.conv_fails);
    drape_cli_result_num(&r, "mass_kg", L->mass_total);
    drape_cli_result_num(&r, "area_nominal_m2", L->area_nominal);
    drape_cli_result_num(&r, "area_mesh_m2", have_dc ? sh.a_specimen_mesh_m2 : NAN);
    drape_cli_result_num(&r, "max_speed_m_s", have_state || !sim_ok ? res.max_speed : NAN);
    drape_cli_result_str(&r, "method", drape_method_names[method]);
    /* static method only (null for dynamic runs) */
    drape_cli_result_int(&r, "iterations", method_static ? er.iterations : NAN);
    drape_cli_result_int(&r, "factorizations", method_static ? er.factorizations : NAN);
    if (method_static && er.certified >= 0) drape_cli_result_str(&r, "certified", er.certified ? "minimum" : "saddle");
    else drape_cli_result_num(&r, "certified", NAN);
    drape_cli_result_num(&r, "min_pivot_N_m", method_static ? er.min_pivot : NAN);
    drape_cli_result_num(&r, "omega_min_rad_s", method_static ? er.omega_min : NAN);
    drape_cli_result_num(&r, "max_force_rel", method_static ? er.max_force_rel : NAN);
    drape_cli_result_str(&r, "linear_solver", method_static ? "cholmod"
                                 : res.stats.linsol > 0 ? drape_linsol_name(res.stats.linsol)
                                                        : "none");
    drape_cli_result_int(&r, "lin_iters", res.stats.lin_iters);
    drape_cli_result_int(&r, "lin_factors", res.stats.lin_factors);
    /* the speed the equilibrium test used: largest particle speed averaged
     * over the last check interval (sim.h); null without checks */
    drape_cli_result_num(&r, "mean_speed_m_s", method_static ? NAN : res.check_speed);
    /* auto only (-1, null, for the others): changes between cvode-bdf and arkode-erk */
    drape_cli_result_int(&r, "integrator_switches", res.stats.switches);
    /* cvode-bdf's highest order (alone or inside auto); null for the others */
    {
        int bdf = method_static ? 0
                                : drape_integrator_bdf_order(res.integrator[0] ? res.integrator
                                                                               : s.integrator,
                                                             s.max_order);
        drape_cli_result_int(&r, "max_order", bdf > 0 ? bdf : NAN);
    }
    /* the ensemble's keys; for one specimen, its own */
    drape_cli_specimen one;
    memset(&one, 0, sizeof one);
    one.seed = s.perturb_seed;
    one.seed_unknown = !seed_known;
    snprintf(one.status, sizeof one.status, "%s", drape_sim_status_name(res.status));
    one.dc = have_dc ? sh.dc : NAN;
    one.nodes = have_dc ? sh.nodes : -1;
    one.r_min_m = have_dc ? sh.r_min_m : NAN;
    one.r_max_m = have_dc ? sh.r_max_m : NAN;
    /* a resumed run's CPU time counts the time before it, as wall_s does */
    double cpu_prev = ri ? ck_stat(ri, "cpu_s") : 0.0;
    if (!(cpu_prev >= 0)) cpu_prev = 0.0;
    one.cpu_s = drape_cli_cpu_s() - cpu0 + cpu_prev;
    drape_cli_result_num(&r, "cpu_s", drape_cli_cpu_s() + cpu_prev);
    drape_cli_result_num(&r, "dc_sd", NAN);
    drape_cli_result_num(&r, "dc_ci95", NAN);
    drape_cli_result_num(&r, "dc_mode", one.dc);
    if (have_dc && sh.nodes >= 0)
        r.hist[sh.nodes > DRAPE_ENSEMBLE_MAX_NODES ? DRAPE_ENSEMBLE_MAX_NODES : sh.nodes] = 1;
    drape_cli_result_hist(&r, "nodes_hist");
    r.spec = &one;
    r.n_spec = 1;
    drape_cli_result_specimens(&r, "specimens");
    drape_cli_result_int(&r, "specimens_failed", res.status == DRAPE_SIM_FAILED ? 1 : 0);
    drape_cli_result_int(&r, "seed", seed_known ? (double)s.perturb_seed : NAN);
    drape_cli_result_num(&r, "fall_time_s", method == DRAPE_METHOD_FALL ? fall_time : NAN);
    drape_cli_result_num(&r, "fall_step_s", method == DRAPE_METHOD_FALL ? fall_step : NAN);
    {
        int animate = !method_static && strcmp(s.integrator, "animate") == 0, nsub = 0;
        double step = drape_scene_animate_step(&s, NULL, &nsub);
        drape_cli_result_num(&r, "step_s", animate ? step : NAN);
        drape_cli_result_int(&r, "substeps", animate ? nsub : NAN);
        /* the energy balance: a dynamic run's over its output points, the
         * fall's over its steps */
        int bal = !method_static && rc.n_energy > 0;
        double e_start = NAN, e_end = NAN, e_rise = NAN;
        if (bal) {
            e_start = rc.e_start;
            e_end = rc.e_end;
            if (rc.n_energy > 1) e_rise = rc.e_max_rise;
        } else if (method == DRAPE_METHOD_FALL && sim_ok) {
            e_start = er.dyn_e_start;
            e_end = er.dyn_e_end;
            e_rise = er.dyn_e_max_rise;
        }
        drape_cli_result_num(&r, "energy_total_start_J", e_start);
        drape_cli_result_num(&r, "energy_total_end_J", e_end);
        drape_cli_result_num(&r, "energy_max_rise_J", e_rise);
        drape_cli_result_num(&r, "max_strain_peak", bal ? rc.strain_peak : NAN);
        drape_cli_result_int(&r, "energy_rescales", animate ? res.stats.energy_rescales : NAN);
    }
    char terms[96] = "";
    for (int k = 0; drape_term_names[k]; k++) {
        unsigned bit = 1u << k;
        if (!(s.terms & bit) || (bit == DRAPE_TERM_BIAS && L->n_cells == 0)) continue;
        size_t len = strlen(terms);
        snprintf(terms + len, sizeof terms - len, "%s%s", len ? "+" : "", drape_term_names[k]);
    }
    drape_cli_result_str(&r, "terms", terms);
    drape_cli_result_num(&r, "fall_end_s", method == DRAPE_METHOD_FALL && sim_ok ? er.dyn_end : NAN);
    drape_cli_result_num(&r, "fall_tol_m",
                         method == DRAPE_METHOD_FALL && s.fall_tol > 0.0 ? s.fall_tol : NAN);
    drape_cli_result_int(&r, "fall_steps", method == DRAPE_METHOD_FALL && sim_ok ? er.dyn_steps : NAN);
    drape_cli_result_num(&r, "damping_shear_s", s.damping_shear);
    {
        /* energy that the fall's integrator created: its total energy
         * above its value at the start (the model only dissipates) */
        int fall = method == DRAPE_METHOD_FALL && sim_ok && isfinite(er.dyn_e_max);
        double gain = fall ? fmax(0.0, er.dyn_e_max - er.dyn_e_start) : NAN;
        drape_cli_result_num(&r, "energy_gain_J", gain);
        drape_cli_result_int(&r, "fall_redone", fall ? er.dyn_redone : NAN);
        double lost = fall ? er.dyn_e_start - er.dyn_e_end : NAN;
        if (fall && gain > DRAPE_CLI_GAIN_WARN * fabs(lost)) {
            drape_error w;
            drape_error_clear(&w);
            drape_error_set(&w, DRAPE_E_NUMERIC, NULL, 0, 0, NULL,
                            "the fall gained energy: its total energy rose %.3g J above its "
                            "value at the start and ended %+.3g J from it; the model only "
                            "dissipates, so the integrator created that energy, and this rest "
                            "state may not be one that the physical fall reaches "
                            "(docs/ensemble.md, \"Energy gained by the fixed-step fall\")",
                            gain, -lost);
            drape_cli_warn(NULL, &w);
        }
    }
    /* a rest state that the certification calls a saddle: stationary but
     * not stable, so no physical drape stays there; kept (the result says
     * "certified": "saddle", exit 0 as before), and said, by every
     * specimen of an ensemble that ends there.  On a scene with
     * a zero mode (a cloth hung from one pin) the label is roundoff's:
     * docs/equilibrium.md, "Zero modes" */
    if (method_static && have_state && res.status == DRAPE_SIM_EQUILIBRIUM && er.certified == 0) {
        drape_error w;
        drape_error_clear(&w);
        drape_error_set(&w, DRAPE_E_NUMERIC, NULL, 0, 0, NULL,
                        "the rest state found is a saddle point, not a stable drape "
                        "(\"certified\": \"saddle\": its Hessian is not positive definite); a "
                        "real cloth would not stay there, unless the scene has a free rigid "
                        "motion, where the label is roundoff's (docs/equilibrium.md, "
                        "\"Zero modes\"); hint: --method dynamic");
        drape_cli_warn(NULL, &w);
    }
    drape_cli_result_num(&r, "fall_fold_time_s", fp.fold_time > 0.0 ? fp.fold_time : NAN);
    drape_cli_result_num(&r, "fall_fold_step_s", fp.fold_time > 0.0 ? fp.fold_step : NAN);
    drape_cli_result_num(&r, "fall_retry_s", fp.retry > 0.0 ? fp.retry : NAN);
    drape_cli_result_int(&r, "fall_refused",
                         method == DRAPE_METHOD_FALL && sim_ok ? er.dyn_refused : NAN);
    drape_cli_result_int(&r, "fall_pumped",
                         method == DRAPE_METHOD_FALL && sim_ok ? er.dyn_pumped : NAN);
    drape_cli_result_num(&r, "fall_redo_from_s",
                         method == DRAPE_METHOD_FALL && sim_ok ? er.dyn_redo_from : NAN);
    {
        int field = s.has_perturbation && s.perturb_kind == DRAPE_PERTURB_FIELD;
        double lo = NAN, hi = NAN;
        int modes;
        if (field) drape_scene_perturbation_band(&s, &lo, &hi, &modes);
        drape_cli_result_str(&r, "perturbation_kind",
                             s.has_perturbation ? drape_perturb_kind_names[s.perturb_kind] : NULL);
        drape_cli_result_num(&r, "perturbation_amplitude_m",
                             s.has_perturbation ? s.perturb_amplitude : NAN);
        drape_cli_result_num(&r, "perturbation_lambda_min_m", lo);
        drape_cli_result_num(&r, "perturbation_lambda_max_m", hi);
    }
    {
        /* this specimen as an ensemble of one, against the coarse one */
        drape_ensemble_stats one_st;
        double one_dc = one.dc;
        int one_nodes = one.nodes;
        drape_ensemble_stats_compute(&one_dc, &one_nodes, 1, &one_st);
        drape_cli_convergence_keys(&r, ra->coarse, &one_st);
    }
    if (!drape_cli_result_check_keys(&r)) {
        drape_error_set(&err, DRAPE_E_INTERNAL, NULL, 0, 0, NULL,
                        "result fields differ from drape_cli_run_keys");
        goto fail;
    }

    /* An interrupted dynamic run with --out always leaves DIR/drape.h5 (a
     * checkpoint without frames when the scene writes no HDF5). */
    if (interrupted && !method_static && out_dir && !rc.h5) {
        rc.h5 = drape_h5_open(out_dir, L, &err);
        if (!rc.h5) goto fail;
    }
    if (rc.h5) {
        drape_kv kv[DRAPE_CLI_RESULT_MAX + 2];
        int nkv = 0;
        for (int i = 0; i < r.n; i++) {
            const drape_cli_field *fl = &r.f[i];
            if (fl->type == DRAPE_CLI_F_HIST || fl->type == DRAPE_CLI_F_SPECIMENS) continue;
            kv[nkv++] = (drape_kv){fl->key, fl->type == DRAPE_CLI_F_STR && !fl->is_null_text
                                                ? fl->text : NULL,
                                   fl->type == DRAPE_CLI_F_STR ? NAN : fl->value};
        }
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
            drape_cli_run_kv_fill(rk, scene_path, &s, &so, &res, rc.frame, stop_signal,
                                  seed_known ? (double)s.perturb_seed : NAN);
            if (ra->ensemble_id) /* an ensemble's specimen: whose (added) */
                rk->kv[rk->n++] = (drape_kv){"ensemble_id", ra->ensemble_id, 0.0};
            fin.run = rk->kv;
            fin.n_run = rk->n;
        }
        drape_h5 *h = rc.h5;
        rc.h5 = NULL;
        if (drape_h5_finish(h, &fin, &err) != 0) goto fail;
        rc.h5 = h; /* complete; put in place after the picture (below) */
    }
    /* the picture of one specimen (as for an ensemble), before the result
     * is printed: a run that cannot write it prints no result */
    if (!child && out_dir && have_dc &&
        (s.kind == DRAPE_SCENE_CUSICK || s.kind == DRAPE_SCENE_TABLE)) {
        int na = 0;
        const double *rad = drape_dc_outline(dc, &na);
        drape_svg_specimen sv = {one.seed, one.dc, one.nodes, sh.centre_m[0], sh.centre_m[1],
                                 rad, na, sh.node_threshold_m, one.seed_unknown};
        if (drape_cli_write_shadow(out_dir, &s, &sv, 1, &r, &err) != 0) goto fail;
    }
    /* drape.h5 and drape.xmf are renamed into place only now, so that a
     * picture that cannot be written leaves neither */
    if (rc.h5) {
        drape_h5 *h = rc.h5;
        rc.h5 = NULL;
        if (drape_h5_commit(h, &err) != 0) goto fail;
    }
    /* a resumed run that finished: the checkpoint-only file has served
     * (removed only now: a run that failed above can be resumed again) */
    if (ri && !ri->had_h5 && !interrupted && !s.out_hdf5) {
        char p[4300];
        unlink(ri->h5_path);
        snprintf(p, sizeof p, "%s/drape.xmf", out_dir);
        unlink(p);
    }
    /* the frames stay; until here a failure (closing drape.h5, writing
     * shadow.svg) removes them.  Those of an earlier, longer run in the
     * same directory go, once this run is complete (an interrupted one
     * may be resumed over them: its own frames are all below rc.frame) */
    if (rc.obj && sim_ok && !interrupted && drape_obj_written(rc.obj) > 0) {
        int gone = drape_obj_remove_stale(rc.obj, rc.frame);
        if (gone > 0 && !ra->no_warnings)
            fprintf(stderr, "drape: %s: removed %d frame%s of an earlier run (from "
                    "frame_%06d.obj)\n", out_dir, gone, gone == 1 ? "" : "s", rc.frame);
    }
    if (rc.obj) { drape_obj_free(rc.obj); rc.obj = NULL; }
    if (created_dir && !interrupted) rmdir(out_dir); /* only if nothing was written */
    if (child) {
        drape_cli_result_write(child->out, &r);
        if (have_dc) {
            int na = 0;
            const double *rad = drape_dc_outline(dc, &na);
            fprintf(child->out, "@shadow\t%.9g %.9g %d %.9g", sh.centre_m[0], sh.centre_m[1], na,
                    sh.node_threshold_m);
            for (int k = 0; k < na; k++) fprintf(child->out, " %.6g", rad[k]);
            fputc('\n', child->out);
        }
    } else if (csv) {
        drape_cli_result_print_csv(stdout, &r);
    } else if (ra->text) {
        drape_cli_result_print_text(stdout, &r);
    } else if (drape_cli_result_print_json(stdout, &r) != 0) {
        goto nomem;
    }
    /* ferror too: a write that failed inside fprintf (a result longer than
     * the stream's buffer) left nothing for fflush to fail on */
    FILE *res_out = child ? child->out : stdout;
    if (fflush(res_out) != 0 || ferror(res_out)) {
        drape_error_set(&err, DRAPE_E_IO, "<stdout>", 0, 0, NULL, "cannot write the result");
        goto fail;
    }
    if (interrupted) {
        int sig = stop_signal;
        if (rc.progress) fputc('\n', stderr); /* end the progress line */
        if (child)
            ; /* a specimen: the ensemble reports it (and how to resume it) */
        else if (method_static)
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
    /* a failed run leaves nothing of its own behind */
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
