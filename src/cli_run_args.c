/* cli_run_args.c: the command line of `drape run`: its --help, the
 * options parsed and checked (a bad value exits 2 naming the option), the
 * default scene and the data directories, then the run as asked: resumed
 * from a checkpoint (cli_run.c), or one specimen or an ensemble
 * (cli_specimens.c).  The run itself is cli_run.c. */
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli.h"
#include "cli_data.h"
#include "cli_io.h"
#include "cli_run.h"
#include "drape/error.h"
#include "drape/integrator.h"
#include "drape/scene.h"
#include "drape/units.h"

#define DEFAULT_SCENE "scenes/cusick.yaml"

static const char run_usage[] =
    "Usage: drape run [SCENE.yaml] [OPTIONS]\n"
    "       drape run --resume DIR [--format json|csv|text] [-q] [-j N]\n"
    "\n"
    "Run a scene (default " DEFAULT_SCENE ") and print one JSON object on\n"
    "stdout with the result in SI units (keys: fabric, scene, integrator,\n"
    "energy_form, rtol, atol, spacing_m, particles, free_particles, status,\n"
    "t_end_s, dc, nodes, r_min_m, r_max_m, tip_angle_deg, bending_length_m,\n"
    "flexural_rigidity_Nm, energy_J{kinetic,stretch,bend,shear,gravity},\n"
    "max_strain, wall_s, steps, rhs_evals, jac_evals, lin_setups, nonlin_iters,\n"
    "err_test_fails, conv_fails, and more: mass_kg, area_nominal_m2,\n"
    "area_mesh_m2, max_speed_m_s (at the end), mean_speed_m_s (largest particle\n"
    "speed averaged over the last equilibrium check interval: what the\n"
    "equilibrium test compares), the static solver's (iterations,\n"
    "factorizations, certified, min_pivot_N_m, omega_min_rad_s,\n"
    "max_force_rel), linear_solver, lin_iters, lin_factors, integrator_switches\n"
    "(auto: changes between cvode-bdf and arkode-erk), max_order (cvode-bdf,\n"
    "auto), method, the fall's (fall_time_s, fall_step_s, fall_end_s,\n"
    "fall_steps, fall_tol_m, fall_fold_time_s, fall_fold_step_s, fall_retry_s,\n"
    "fall_refused, fall_redone, fall_pumped, fall_redo_from_s), step_s and\n"
    "substeps (animate), the energy balance (energy_total_start_J,\n"
    "energy_total_end_J, energy_max_rise_J, energy_gain_J, energy_rescales),\n"
    "max_strain_peak, terms, damping_shear_s, the perturbation\n"
    "(perturbation_kind field or particle, perturbation_amplitude_m,\n"
    "perturbation_lambda_min_m, perturbation_lambda_max_m); null where the\n"
    "scene does not produce one; docs/outputs.md), and with --convergence\n"
    "spacing_coarse_m, dc_spacing_delta, dc_spacing_delta_ci95 and\n"
    "nodes_spacing_p (below).  status is equilibrium,\n"
    "t_max, failed or interrupted.\n"
    "\n"
    "Repeated specimens (scene key `specimens: N`, or --specimens N): a drape\n"
    "test of N specimens that differ only in the perturbation seed (specimen k\n"
    "= 0..N-1 uses seed + k), run in N child processes, -j at a time.  Then dc\n"
    "is the mean DC, nodes the most frequent node count, and the result adds\n"
    "dc_sd (sample standard deviation), dc_ci95 (half-width of the 95 %\n"
    "interval of the mean, Student t), dc_mode (mean DC of the specimens with\n"
    "the modal node count), nodes_hist ({\"3\": 2, \"4\": 6}; CSV 3:2;4:6),\n"
    "specimens (one object per specimen: seed, status, dc, nodes, r_min_m,\n"
    "r_max_m, cpu_s; CSV: the count), specimens_failed, seed (the first), cpu_s\n"
    "(CPU seconds, child processes included); counters are summed over the\n"
    "specimens, energies and radii averaged (docs/ensemble.md).  The shipped\n"
    "Cusick scene asks for 12, the table scene for 10.\n"
    "\n"
    "Options (override the scene file):\n"
    "  --fabric FILE            fabric file instead of the scene's\n"
    "  --integrator NAME        auto, arkode-imex, arkode-dirk, arkode-erk,\n"
    "                           cvode-bdf, gsl-msbdf, gsl-rk8pd, animate\n"
    "  --rtol X, --atol X       tolerances (atol on positions, m)\n"
    "  --spacing LEN            lattice spacing, e.g. 5mm or '0.5 cm'\n"
    "  --energy-form FORM       consistent or seed\n"
    "  --t-max T                end time, e.g. 3s\n"
    "  --method METHOD          fall (the default where the scene ends at\n"
    "                           equilibrium): a short damped fall with a fixed\n"
    "                           large step, then the static solver (1-2 s per\n"
    "                           specimen on the Cusick test at 1 cm, about 10 s\n"
    "                           on the larger table scene; how its ensembles\n"
    "                           compare with the dynamic ones: docs/ensemble.md);\n"
    "                           dynamic (the\n"
    "                           default otherwise): integrate the equations of\n"
    "                           motion in time; static: minimise the potential\n"
    "                           energy directly (pseudo-transient continuation,\n"
    "                           Newton, Hessian check; docs/equilibrium.md): only\n"
    "                           the final state, no transient frames; animate:\n"
    "                           frames for renderers at graphics speed, a fixed\n"
    "                           step (the frame interval / --substeps), backward\n"
    "                           Euler by a few Newton iterations on one or two\n"
    "                           sparse factorisations (after Baraff & Witkin\n"
    "                           1998), first order, the energy never rising, no\n"
    "                           error control (docs/animate.md)\n"
    "  --substeps N             animate: steps per frame interval (scene:\n"
    "                           solver.substeps; default: the fewest that keep\n"
    "                           the step at most 1/30 s; the frame interval is\n"
    "                           output.frames.every, or 1/30 s)\n"
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
    "                           default 0.2; static and fall: the rest state's)\n"
    "  --fall-time T, --fall-step T  the fall method's least duration and its\n"
    "                           fixed step\n"
    "                           (scene: solver.fall_time, fall_step; default\n"
    "                           10 and 1/32 pendulum times sqrt(h/g) of the free\n"
    "                           length h: 0.78 s and 2.4 ms for the Cusick test)\n"
    "  --fall-fold-time T       the first part of the fall, while the folds\n"
    "                           form, at half the fall step (scene:\n"
    "                           solver.fall_fold_time; default half the fall\n"
    "                           time; 0 = none); result keys fall_fold_time_s,\n"
    "                           fall_fold_step_s\n"
    "  --fall-retry T           a longer step of the fall refused for raising\n"
    "                           its total energy is tried again T later, once\n"
    "                           (scene: solver.fall_retry; default 0 = never:\n"
    "                           it saves steps on falls refused by chance and\n"
    "                           costs steps where the longer step pumps, as on\n"
    "                           the 1 cm table; docs/ensemble.md); result keys\n"
    "                           fall_retry_s, fall_refused\n"
    "  --fall-swing X           the fall goes on past --fall-time while the\n"
    "                           cloth still swings, at twice the fall step: while\n"
    "                           its kinetic energy over the last fifth of the fall\n"
    "                           time exceeds X of its peak, up to 4 fall times\n"
    "                           (scene: solver.fall_swing; default 0.02, on the\n"
    "                           table scene 0; 0 = stop at the fall time); result\n"
    "                           key fall_end_s\n"
    "  --fall-tol L             the fall's step chosen by its error instead: the\n"
    "                           largest particle's position error per step at\n"
    "                           most L (e.g. 10um; from --fall-step/4 within\n"
    "                           [/64, x8]), a step that gains energy redone\n"
    "                           shorter (docs/ensemble.md; scene:\n"
    "                           solver.fall_tol; default 0 = the fixed step);\n"
    "                           result key fall_tol_m\n"
    "  --damping-shear T        the fabric's internal shear damping (fabric:\n"
    "                           damping.shear, default 0.5 ms; a scene's\n"
    "                           damping.shear replaces it, and this both; 0 =\n"
    "                           off): a viscous shear force per length T x G0 x\n"
    "                           the shear rate, G0 the flat fabric's shear\n"
    "                           rigidity (docs/model.md 3.6);\n"
    "                           result key damping_shear_s\n"
    "  --specimens N            repeated specimens (scene: specimens, default 1)\n"
    "  -j, --jobs N             specimens run at a time (default 0: one per core)\n"
    "  --seed N                 perturbation seed (of the first specimen)\n"
    "  --convergence            is the spacing fine enough?  Run the same\n"
    "                           specimens first at a spacing sqrt(2) coarser, and\n"
    "                           add spacing_coarse_m, dc_spacing_delta (mean DC\n"
    "                           here minus there), dc_spacing_delta_ci95 (its 95 %\n"
    "                           half-width, Welch) and nodes_spacing_p (the node\n"
    "                           histograms' exact test): converged where |delta|\n"
    "                           < 0.01 and p >= 0.05 (docs/convergence.md); not\n"
    "                           with --out\n"
    "  --terms LIST             energy terms, comma-separated: stretch, bend, shear,\n"
    "                           gravity, bias (scene: model.terms; default all;\n"
    "                           bias, the twist that makes a fabric's measured bias\n"
    "                           curve, acts only where the fabric gives one:\n"
    "                           docs/model.md, \"Bias bending\")\n"
    "  --out DIR                write frames (OBJ, drape.h5 + drape.xmf) into DIR;\n"
    "                           with N > 1 specimens DIR/specimen-001/...; Cusick\n"
    "                           and table scenes: DIR/shadow.svg and shadow.png, the\n"
    "                           top view of every specimen's shadow with the nodes\n"
    "                           and the DC\n"
    "  --resume DIR             continue a run that was interrupted (SIGINT, SIGTERM)\n"
    "                           from DIR/drape.h5, with the options stored there;\n"
    "                           an ensemble's DIR (with --out DIR): from\n"
    "                           DIR/ensemble.json, its finished specimens kept\n"
    "  --format json|csv|text   result format on stdout: JSON (the default\n"
    "                           when stdout is not a terminal), CSV, or a few\n"
    "                           lines for a person (the default on a terminal)\n"
    "  -q, --quiet              no progress on stderr\n"
    "  -h, --help               show this help\n"
    "\n"
    "SIGINT or SIGTERM stops a dynamic run within one model evaluation; it ends\n"
    "at the last output point (frame or equilibrium check) with status\n"
    "interrupted, the frames so far and DIR/drape.h5 kept for --resume; a second\n"
    "signal ends drape at once.\n"
    "\n"
    "An ensemble stops on SIGINT or SIGTERM as its specimens do.  With --out DIR\n"
    "it keeps DIR/ensemble.json and each finished specimen's result, and\n"
    "--resume DIR continues it: finished specimens are not run again, an\n"
    "interrupted dynamic specimen continues from its checkpoint, the others run\n"
    "from the start; refused when the scene or fabric file changed (exit 1),\n"
    "when the ensemble finished (2) or its manifest is missing or damaged (3)\n"
    "(docs/ensemble.md).  Without --out an ensemble cannot be resumed.\n"
    "\n"
    "Exit status: 0 equilibrium or t_max (an ensemble: at least one specimen;\n"
    "failed ones are counted in specimens_failed and named on stderr), 1 invalid\n"
    "input, 2 bad command line, 3 I/O error, 4 the run failed (numerical; an\n"
    "ensemble: every specimen), 5 out of memory, 130 interrupted by SIGINT, 143\n"
    "interrupted by SIGTERM.\n";


/* ---- parsing ------------------------------------------------------------ */

/* --resume DIR: DIR must be a directory (an E_IO error naming DIR, not
 * one naming a file inside it that is missing only because DIR is). */
static int resume_dir_check(const char *dir, drape_error *err)
{
    struct stat st;
    if (stat(dir, &st) != 0)
        return drape_error_set(err, DRAPE_E_IO, dir, 0, 0, NULL,
                               "--resume: cannot use this directory: %s (give the --out DIR "
                               "of the interrupted run)", strerror(errno));
    if (!S_ISDIR(st.st_mode))
        return drape_error_set(err, DRAPE_E_IO, dir, 0, 0, NULL,
                               "--resume: not a directory (give the --out DIR of the "
                               "interrupted run)");
    return 0;
}

static int usage_error(const char *fmt, const char *a, const char *b)
{
    fputs("drape: ", stderr);
    fprintf(stderr, fmt, a, b);
    fputs("\nTry `drape run --help'.\n", stderr);
    return drape_error_exit_status(DRAPE_E_USAGE);
}

/* A count from min to max ("-j 0" = one per core). */
static int parse_count(const char *text, int min, int max, int *out)
{
    char *end;
    errno = 0;
    long v = strtol(text, &end, 10);
    if (errno || end == text || *end || v < min || v > max) return -1;
    *out = (int)v;
    return 0;
}

/* A quantity of dimension dim (SI); why set if it does not parse. */
static int quantity(const char *name, const char *text, drape_dim dim, double *v,
                    char *why, size_t n)
{
    char w[256];
    if (drape_units_parse(text, dim, v, w, sizeof w) == 0) return 0;
    snprintf(why, n, "%s: %s", name, w);
    return -1;
}

int drape_cli_rtol_parse(const char *name, const char *text, double *v, char *why, size_t n)
{
    if (quantity(name, text, DRAPE_DIM_NONE, v, why, n)) return -1;
    if (!(*v > 0 && *v < 1)) {
        snprintf(why, n, "%s: must be in (0, 1), got %s", name, text);
        return -1;
    }
    return 0;
}

#define IS(opt) (strcmp(name, opt) == 0)
#define WHY(...) (snprintf(why, n, __VA_ARGS__), -1)

int drape_cli_run_option(run_args *ra, const char *name, const char *text, char *why, size_t n)
{
    double v;
    if (IS("--integrator")) {
        for (int i = 0; drape_integrator_names[i]; i++)
            if (strcmp(drape_integrator_names[i], text) == 0) return ra->integrator = text, 0;
        return WHY("--integrator: unknown integrator `%s'; see `drape run --help'", text);
    }
    if (IS("--energy-form")) {
        if (strcmp(text, "consistent") && strcmp(text, "seed"))
            return WHY("--energy-form: expected consistent or seed, got `%s'", text);
        return ra->form = text, 0;
    }
    if (IS("--rtol")) {
        if (drape_cli_rtol_parse(name, text, &v, why, n)) return -1;
        return ra->rtol = v, 0;
    }
    if (IS("--atol") || IS("--spacing")) {
        if (quantity(name, text, DRAPE_DIM_LENGTH, &v, why, n)) return -1;
        if (!(v > 0)) return WHY("%s: must be positive, got %s", name, text);
        *(IS("--atol") ? &ra->atol : &ra->spacing) = v;
        return 0;
    }
    if (IS("--t-max") || IS("--fall-time") || IS("--fall-step")) {
        if (quantity(name, text, DRAPE_DIM_TIME, &v, why, n)) return -1;
        if (!(v > 0)) return WHY("%s: must be positive, got %s", name, text);
        *(IS("--t-max") ? &ra->t_max : IS("--fall-time") ? &ra->fall_time : &ra->fall_step) = v;
        return 0;
    }
    if (IS("--strain-limit")) {
        if (quantity(name, text, DRAPE_DIM_NONE, &v, why, n)) return -1;
        if (!(v > 0) || !isfinite(v))
            return WHY("--strain-limit: must be a positive number, got %s", text);
        return ra->strain_limit = v, 0;
    }
    if (IS("--fall-tol")) {
        if (quantity(name, text, DRAPE_DIM_LENGTH, &v, why, n)) return -1;
        if (!(v >= 0)) return WHY("--fall-tol: must not be negative, got %s", text);
        return ra->fall_tol = v, 0;
    }
    if (IS("--fall-fold-time") || IS("--fall-retry") || IS("--damping-shear")) {
        if (quantity(name, text, DRAPE_DIM_TIME, &v, why, n)) return -1;
        if (!(v >= 0) || !isfinite(v)) return WHY("%s: must be a time >= 0, got %s", name, text);
        *(IS("--fall-fold-time") ? &ra->fall_fold_time
          : IS("--fall-retry")   ? &ra->fall_retry
                                 : &ra->damping_shear) = v;
        return 0;
    }
    if (IS("--fall-swing")) {
        char *end;
        int range;
        v = drape_units_strtod(text, &end, &range);
        if (*end || end == text || !(v >= 0.0 && v < 1.0) || range)
            return WHY("--fall-swing: expected a fraction in [0, 1), got `%s'", text);
        return ra->fall_swing = v, 0;
    }
    if (IS("--method")) {
        for (int k = 1; drape_method_names[k]; k++)
            if (strcmp(text, drape_method_names[k]) == 0) return ra->method = k, 0;
        return WHY("--method: expected fall, dynamic, static or animate, got `%s'", text);
    }
    if (IS("--linear-solver")) {
        if (drape_linsol_parse(text, &ra->linsol) != 0)
            return WHY("--linear-solver: expected auto, klu, schur or schur-direct, got `%s'", text);
        return 0;
    }
    if (IS("--terms")) {
        if (drape_scene_terms_parse(text, &ra->terms) != 0)
            return WHY("--terms: expected a comma-separated list of stretch, bend, "
                       "shear, gravity, bias, got `%s'", text);
        return 0;
    }
    if (IS("--max-order")) {
        if (drape_max_order_parse(text, &ra->max_order) != 0)
            return WHY("--max-order: expected an integer from 1 to 5, got `%s'", text);
        return 0;
    }
    if (IS("--max-steps")) {
        char *end;
        errno = 0;
        long m = strtol(text, &end, 10);
        if (errno || *end || end == text || m <= 0)
            return WHY("--max-steps: expected a positive integer, got `%s'", text);
        return ra->max_steps = m, 0;
    }
    if (IS("--specimens")) {
        if (parse_count(text, 1, DRAPE_SCENE_SPECIMENS_MAX, &ra->specimens) != 0)
            return WHY("--specimens: expected an integer from 1 to %s, got `%s'",
                       DRAPE_SCENE_SPECIMENS_MAX_TEXT, text);
        return 0;
    }
    if (IS("--substeps")) {
        if (parse_count(text, 1, DRAPE_ANIMATE_SUBSTEPS_MAX, &ra->substeps) != 0)
            return WHY("--substeps: expected an integer from 1 to %d, got `%s'",
                       DRAPE_ANIMATE_SUBSTEPS_MAX, text);
        return 0;
    }
    if (IS("--seed")) {
        char *end;
        errno = 0;
        unsigned long u = strtoul(text, &end, 10);
        if (errno || *end || text[0] == '-' || text[0] == 0 || u > DRAPE_SCENE_SEED_MAX)
            return WHY("--seed: expected a non-negative integer up to "
                       DRAPE_SCENE_SEED_MAX_TEXT ", got `%s'", text);
        ra->has_seed = 1;
        ra->seed = u;
        return 0;
    }
    return WHY("%s: not an option of drape run", name);
}

#undef IS
#undef WHY

void drape_cli_run_args_init(run_args *ra)
{
    memset(ra, 0, sizeof *ra);
    ra->method = DRAPE_METHOD_DEFAULT;
    ra->fall_swing = -1.0;
    ra->fall_tol = -1.0;
    ra->fall_fold_time = -1.0;
    ra->fall_retry = -1.0;
    ra->damping_shear = -1.0;
    ra->jobs = 0; /* one per core */
}

static int same_text(const char *a, const char *b)
{
    return a == b || (a && b && strcmp(a, b) == 0);
}

int drape_cli_run_option_same(const char *name, const char *a, const char *b)
{
    run_args x, y;
    char why[512];
    memset(&x, 0, sizeof x);
    memset(&y, 0, sizeof y);
    if (drape_cli_run_option(&x, name, a, why, sizeof why) != 0 ||
        drape_cli_run_option(&y, name, b, why, sizeof why) != 0)
        return 0;
    /* every field drape_cli_run_option sets (the others stay 0 in both);
     * field by field, not memcmp: integrator and form point into the two
     * texts.  An option added to drape_cli_run_option belongs here too */
    return same_text(x.integrator, y.integrator) && same_text(x.form, y.form) &&
           x.rtol == y.rtol && x.atol == y.atol && x.spacing == y.spacing &&
           x.t_max == y.t_max && x.strain_limit == y.strain_limit &&
           x.max_steps == y.max_steps && x.max_order == y.max_order && x.linsol == y.linsol &&
           x.method == y.method && x.has_seed == y.has_seed && x.seed == y.seed &&
           x.fall_time == y.fall_time && x.fall_step == y.fall_step &&
           x.fall_swing == y.fall_swing && x.fall_tol == y.fall_tol &&
           x.fall_fold_time == y.fall_fold_time && x.fall_retry == y.fall_retry &&
           x.damping_shear == y.damping_shear && x.substeps == y.substeps &&
           x.terms == y.terms && x.specimens == y.specimens;
}

int drape_cli_run(int argc, char **argv)
{
    /* the options that set a value of the run: drape_cli_run_option */
    enum { O_FABRIC = 1000, O_OUT, O_FORMAT, O_RESUME, O_VALUE, O_CONVERGENCE };
    static const struct option opts[] = {
        {"fabric", required_argument, NULL, O_FABRIC},
        {"integrator", required_argument, NULL, O_VALUE},
        {"rtol", required_argument, NULL, O_VALUE},
        {"atol", required_argument, NULL, O_VALUE},
        {"spacing", required_argument, NULL, O_VALUE},
        {"energy-form", required_argument, NULL, O_VALUE},
        {"t-max", required_argument, NULL, O_VALUE},
        {"out", required_argument, NULL, O_OUT},
        {"max-steps", required_argument, NULL, O_VALUE},
        {"max-order", required_argument, NULL, O_VALUE},
        {"method", required_argument, NULL, O_VALUE},
        {"linear-solver", required_argument, NULL, O_VALUE},
        {"strain-limit", required_argument, NULL, O_VALUE},
        {"resume", required_argument, NULL, O_RESUME},
        {"specimens", required_argument, NULL, O_VALUE},
        {"jobs", required_argument, NULL, 'j'},
        {"seed", required_argument, NULL, O_VALUE},
        {"terms", required_argument, NULL, O_VALUE},
        {"fall-swing", required_argument, NULL, O_VALUE},
        {"fall-tol", required_argument, NULL, O_VALUE},
        {"fall-fold-time", required_argument, NULL, O_VALUE},
        {"fall-retry", required_argument, NULL, O_VALUE},
        {"damping-shear", required_argument, NULL, O_VALUE},
        {"fall-time", required_argument, NULL, O_VALUE},
        {"fall-step", required_argument, NULL, O_VALUE},
        {"substeps", required_argument, NULL, O_VALUE},
        {"format", required_argument, NULL, O_FORMAT},
        {"convergence", no_argument, NULL, O_CONVERGENCE},
        {"quiet", no_argument, NULL, 'q'},
        {"help", no_argument, NULL, 'h'},
        {NULL, 0, NULL, 0}};
    const char *fabric_path = NULL, *out_dir = NULL, *resume_dir = NULL, *run_opt = NULL;
    int fmt = -1, quiet = 0, c, li; /* 0 json, 1 csv, 2 text; -1 not given */
    run_args ra;
    drape_cli_run_args_init(&ra);
    if ((c = drape_cli_args_unambiguous(argc, argv, "qhj:", opts, "drape run")) != 0) return c;
    while ((c = getopt_long(argc, argv, "qhj:", opts, &li)) != -1) {
        switch (c) {
        case O_FABRIC: fabric_path = optarg; break;
        case O_OUT:
        case O_RESUME:
            if (!*optarg)
                return usage_error("%s: expected a directory, got an empty name%s",
                                   c == O_OUT ? "--out" : "--resume", "");
            if (c == O_OUT) out_dir = optarg;
            else resume_dir = optarg;
            break;
        case O_VALUE: {
            char name[32], why[512];
            snprintf(name, sizeof name, "--%s", opts[li].name);
            if (drape_cli_run_option(&ra, name, optarg, why, sizeof why) != 0)
                return usage_error("%s%s", why, "");
            /* as given, for an ensemble's manifest (the last of a
             * repeated option, as it is the one that counts) */
            int g = 0;
            while (g < ra.n_given && strcmp(ra.given_name[g], opts[li].name) != 0) g++;
            if (g == RUN_GIVEN_MAX) return usage_error("run: too many options%s%s", "", "");
            ra.given_name[g] = opts[li].name;
            ra.given_text[g] = optarg;
            if (g == ra.n_given) ra.n_given++;
            break;
        }
        case 'j':
            if (parse_count(optarg, 0, 4096, &ra.jobs) != 0)
                return usage_error("-j: expected a number of processes from 0 (one per core) to %s, got `%s'",
                                   "4096", optarg);
            break;
        case O_FORMAT:
            if (strcmp(optarg, "json") == 0) fmt = 0;
            else if (strcmp(optarg, "csv") == 0) fmt = 1;
            else if (strcmp(optarg, "text") == 0) fmt = 2;
            else return usage_error("--format: expected json, csv or text, got `%s'%s", optarg, "");
            break;
        case O_CONVERGENCE: ra.convergence = 1; break;
        case 'q': quiet = 1; break;
        case 'h': fputs(run_usage, stdout); return 0;
        default:
            fputs("Try `drape run --help'.\n", stderr);
            return drape_error_exit_status(DRAPE_E_USAGE);
        }
        if (c != O_RESUME && c != O_FORMAT && c != 'q' && c != 'j') /* the option, not its value */
            run_opt = optarg && optarg == argv[optind - 1] && optind >= 2 ? argv[optind - 2]
                                                                       : argv[optind - 1];
    }
    if (argc - optind > 1) return usage_error("run: one scene at a time, got `%s' and `%s'", argv[optind], argv[optind + 1]);
    if (resume_dir && optind < argc)
        return usage_error("--resume: no scene file with it (the run's is stored in %s: drape.h5, "
                           "or ensemble.json for an ensemble), got `%s'",
                           resume_dir, argv[optind]);
    if (resume_dir && run_opt)
        return usage_error("--resume: only --format, -q and -j go with it (the run's options are "
                           "stored in %s: drape.h5, or ensemble.json for an ensemble), got `%s'",
                           resume_dir, run_opt);
    /* the default scene and paths not found here: the data directories
     * (cli_data.h; a resumed run's paths are stored absolute) */
    char scene_buf[4096], fabric_buf[4096];
    const char *scene_path = optind < argc ? argv[optind] : DEFAULT_SCENE;
    if (!resume_dir) {
        drape_error derr;
        drape_error_clear(&derr);
        if (drape_cli_data_find(scene_path, scene_buf, sizeof scene_buf, &derr) != 0 ||
            (fabric_path && drape_cli_data_find(fabric_path, fabric_buf, sizeof fabric_buf, &derr) != 0)) {
            drape_cli_print_error(&derr);
            return drape_error_exit_status(derr.kind);
        }
        scene_path = scene_buf;
        if (fabric_path) fabric_path = fabric_buf;
    }
    ra.scene_path = scene_path;
    ra.fabric_path = fabric_path;
    ra.out_dir = out_dir;
    ra.resume_dir = resume_dir;
    /* a person at a terminal reads the summary; a pipe gets JSON */
    if (fmt < 0) fmt = isatty(STDOUT_FILENO) ? 2 : 0;
    ra.csv = fmt == 1;
    ra.text = fmt == 2;
    ra.quiet = quiet;
    if (resume_dir) {
        drape_error derr;
        drape_error_clear(&derr);
        if (resume_dir_check(resume_dir, &derr) != 0) {
            drape_cli_print_error(&derr);
            return drape_error_exit_status(derr.kind);
        }
        /* an ensemble's directory has its manifest (docs/ensemble.md); a
         * single run's, its checkpoint DIR/drape.h5 */
        char manifest[4200];
        snprintf(manifest, sizeof manifest, "%s/" DRAPE_ENSEMBLE_MANIFEST, resume_dir);
        char h5[4200], first[4200];
        snprintf(h5, sizeof h5, "%s/drape.h5", resume_dir);
        snprintf(first, sizeof first, "%s/specimen-001", resume_dir);
        if (access(manifest, F_OK) == 0 || (access(h5, F_OK) != 0 && access(first, F_OK) == 0))
            return drape_cli_specimens_resume(&ra); /* (refused without a manifest) */
        return drape_cli_run_one(&ra, NULL);
    }
    if (ra.convergence && out_dir)
        return usage_error("--convergence: not with --out (run the coarser spacing as an "
                           "ensemble of its own with --out to keep it: docs/convergence.md)%s%s",
                           "", "");
    return ra.convergence ? drape_cli_convergence_run(&ra) : drape_cli_specimens_run(&ra);
}
