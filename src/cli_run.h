/* cli_run.h: `drape run` between its files: the options of one run
 * (cli_run_args.c), the single specimen (cli_run.c), the ensemble of repeated
 * specimens over child processes and its picture (cli_specimens.c).
 * Private to src/cli_*.c. */
#ifndef DRAPE_CLI_RUN_H
#define DRAPE_CLI_RUN_H

#include <stdio.h>

#include "cli_result.h"
#include "drape/ensemble.h"
#include "drape/error.h"
#include "drape/output.h"
#include "drape/scene.h"

/* An ensemble's manifest in its --out DIR (cli_specimens_record.c) */
#define DRAPE_ENSEMBLE_MANIFEST "ensemble.json"

#define RUN_GIVEN_MAX 48 /* more than the options of drape_cli_run_option */

/* The command line of `drape run`, parsed (0 / NULL = not given: the
 * scene's value). */
typedef struct run_args {
    const char *scene_path, *fabric_path, *integrator, *form, *out_dir, *resume_dir;
    double rtol, atol, spacing, t_max, strain_limit;
    long max_steps;
    int max_order, linsol, method; /* method: drape_method */
    int csv, quiet;
    int text;                 /* --format text (the default on a terminal) */
    int has_seed;
    unsigned long seed;       /* --seed: perturbation.seed */
    double fall_time, fall_step; /* s */
    double fall_swing;        /* --fall-swing; < 0 = the scene's */
    double fall_tol;          /* --fall-tol, m; < 0 = the scene's */
    double fall_fold_time;    /* --fall-fold-time, s; < 0 = the scene's */
    double fall_retry;        /* --fall-retry, s; < 0 = the scene's */
    double damping_shear;     /* --damping-shear, s; < 0 = the scene's */
    int substeps;             /* --substeps (animate); 0 = the scene's */
    unsigned terms;           /* --terms: DRAPE_TERM_* mask; 0 = the scene's */
    int specimens;            /* --specimens; 0 = the scene's */
    int jobs;                 /* -j: processes at once; 0 = one per core */
    int no_warnings;          /* the loaders' warnings are not printed (an
                                 ensemble's specimens after the first) */
    int check_only;           /* load, check and build the model, then stop
                                 (an ensemble checks its input once before
                                 it starts its specimens) */
    const char *ensemble_id;  /* an ensemble's specimen with --out: its
                                 ensemble's id, stored in the checkpoint's
                                 /run (a resumed ensemble continues only its
                                 own specimens' checkpoints) */
    /* the options drape_cli_run_option took, as given on the command line
     * (long name without dashes, text; the last of a repeated option): an
     * ensemble records them in its manifest (cli_specimens_record.c) */
    const char *given_name[RUN_GIVEN_MAX], *given_text[RUN_GIVEN_MAX];
    int n_given;
    int convergence;          /* --convergence: the same specimens also at a
                                 spacing sqrt(2) coarser (cli_convergence.c) */
    const struct run_coarse *coarse; /* that ensemble's statistics, for the
                                 result's dc_spacing_* keys; NULL: none */
} run_args;

/* The ensemble that --convergence ran at the coarser spacing. */
typedef struct run_coarse {
    double spacing_m;
    drape_ensemble_stats st;
} run_coarse;

/* The result keys of --convergence from the coarse ensemble c and this
 * run's statistics st (NaN where c is NULL): spacing_coarse_m,
 * dc_spacing_delta (this mean - the coarse one), dc_spacing_delta_ci95
 * (Welch), nodes_spacing_p (exact test of the node histograms). */
void drape_cli_convergence_keys(drape_cli_result *r, const run_coarse *c,
                                const drape_ensemble_stats *st);

/* drape run --convergence: the coarse ensemble, then this one. */
int drape_cli_convergence_run(const run_args *a);

/* Every field not given: 0, NULL, or the "the scene's" value. */
void drape_cli_run_args_init(run_args *ra);

/* Set the value of one of `drape run`'s options in ra, checked as run
 * checks it: name with its dashes ("--rtol"), text as given (units
 * allowed where the option takes a quantity).  Every option but --fabric,
 * --out, --resume, --format, -j, -q and -h; `drape batch` checks the
 * options it passes on to its runs with it.  0, or -1 with why set
 * ("--rtol: must be in (0, 1), got 2"). */
int drape_cli_run_option(run_args *ra, const char *name, const char *text, char *why, size_t n);

/* A relative tolerance as `drape run --rtol` reads it: a dimensionless
 * quantity (drape_units_parse: decimal, exponent or fraction "1/1000"; no
 * hex, inf or nan; out of the normal doubles refused) in (0, 1).  Shared
 * by bench's --rtols and --ref-rtol, so that they take what run takes.
 * 0 and *v, or -1 with why naming the option name ("--rtols: must be in
 * (0, 1), got 2"). */
int drape_cli_rtol_parse(const char *name, const char *text, double *v, char *why, size_t n);

/* 1 if texts a and b of option name (as drape_cli_run_option takes them)
 * both parse and set the same value: `--spacing 5mm` and `0.5cm`,
 * `--rtol 1e-4` and `0.0001`, `--terms bend,stretch` and `stretch,bend`.
 * Values are compared exactly (bit for bit), so that runs given either
 * text are the same runs; 0 otherwise (or if either does not parse). */
int drape_cli_run_option_same(const char *name, const char *a, const char *b);

/* In an ensemble's child process: where the result goes instead of stdout
 * (drape_cli_result_write lines and an "@shadow" line). */
typedef struct run_child {
    FILE *out;
} run_child;

/* Remove the temporaries of a run's files in DIR (output.h's NAME.PID.tmp
 * of frame_NNNNNN.obj, drape.h5 and drape.xmf) that a run killed outright
 * (SIGKILL) left, and no other file.  Only for a DIR this process holds
 * (drape_cli_lock_dir, drape_cli_remove_stale_tmp). */
void drape_cli_run_remove_stale(const char *dir);

/* One specimen: load, build, run, measure, write frames, print the result
 * (child NULL) or send it to the parent.  Returns the exit status.  With
 * a->check_only: load, check and build only (the error printed, nothing
 * on stdout, no file written). */
int drape_cli_run_one(const run_args *a, run_child *child);

/* The run as the scene and options ask: one specimen in this process, or
 * N specimens in child processes (seeds seed + k), -j at a time, and
 * their statistics.  Returns the exit status. */
int drape_cli_specimens_run(const run_args *a);

/* `drape run --resume DIR` of an ensemble's directory (DIR/ensemble.json,
 * cli_specimens_record.c): the ensemble continued, a->csv, a->quiet and
 * a->jobs as given now.  Returns the exit status. */
int drape_cli_specimens_resume(const run_args *a);

/* Write DIR/shadow.svg: the top view of the specimens' shadows (scene s,
 * n specimens), with the result r's statistics in its legend. */
int drape_cli_write_shadow(const char *dir, const drape_scene *s,
                           const drape_svg_specimen *sp, int n,
                           const drape_cli_result *r, drape_error *err);

/* CPU seconds of this process and its waited-for children. */
double drape_cli_cpu_s(void);

#endif /* DRAPE_CLI_RUN_H */
