/* cli_resume.h: what `drape run --resume DIR` reads back from DIR/drape.h5
 * (the /run group written when a run is interrupted), and the /run group
 * itself (docs/reliability.md).  Private to src/cli_*.c. */
#ifndef DRAPE_CLI_RESUME_H
#define DRAPE_CLI_RESUME_H

#include <limits.h>

#include "drape/diagnose.h"
#include "drape/error.h"
#include "drape/output.h"
#include "drape/scene.h"
#include "drape/sim.h"

#define RUN_RESUME_FORMAT 1 /* /run attribute resume_format */

/* Everything --resume takes from DIR/drape.h5. */
typedef struct resume_info {
    drape_h5_checkpoint ck;
    char h5_path[4200];
    char scene_path[DRAPE_ERROR_FILE_MAX], fabric_path[DRAPE_ERROR_FILE_MAX];
    char integrator[DRAPE_INTEGRATOR_NAME_MAX], form[32], linsol[32];
    double rtol, atol, spacing, t_max, strain_limit, below_since;
    double fixed_step;  /* animate's step, s; NaN when not stored (older files) */
    double terms;       /* the DRAPE_TERM_* mask run (--terms); NaN when not
                           stored (older files: the scene's) */
    double damping_shear; /* s, the shear damping run (--damping-shear); NaN
                             when not stored (older files: the scene's) */
    double seed;        /* the perturbation seed run (--seed included); NaN
                           when not stored (older files, or a run resumed
                           from one: unknown, reported null) */
    long max_steps;
    int max_order;   /* 0: the scene's (files written before --max-order) */
    int frames;      /* frames written before (OBJ and HDF5 numbering) */
    int had_h5;      /* the scene writes drape.h5 (else it is a checkpoint only) */
    drape_diag_ref ref;
} resume_info;

/* Read DIR/drape.h5 into *ri (caller frees ri->ck with
 * drape_h5_checkpoint_free): the run must have ended interrupted, and its
 * scene and fabric files must still hold the stored texts. */
int drape_cli_resume_load(const char *dir, resume_info *ri, drape_error *err);

/* Counters of the interrupted part are added to the resumed part's. */
void drape_cli_resume_add_previous(const drape_h5_checkpoint *c, const char *key, long *v);

/* The run's options and resume state for /run (strings point into s,
 * res, or static text; nums into the caller's array). */
typedef struct run_kv {
    drape_kv kv[34]; /* (the caller may add ensemble_id) */
    int n;
    char scene_abs[PATH_MAX + DRAPE_ERROR_FILE_MAX], fabric_abs[PATH_MAX + DRAPE_ERROR_FILE_MAX];
} run_kv;

/* Fill k with the run's options and resume state (signal: the one that
 * stopped the run, 0 = none; seed: the perturbation seed run, NaN when
 * unknown). */
void drape_cli_run_kv_fill(run_kv *k, const char *scene_path, const drape_scene *s,
                           const drape_sim_opts *so, const drape_sim_result *res, int frames,
                           int signal, double seed);

#endif /* DRAPE_CLI_RESUME_H */
