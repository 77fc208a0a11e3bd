/* cli_bench.h: `drape bench`, private to its three files: the
 * work-precision sweep, its options and CSV (cli_bench.c), one measured
 * point in a child process (cli_bench_point.c) and --kernels
 * (cli_bench_kernels.c). */
#ifndef DRAPE_CLI_BENCH_H
#define DRAPE_CLI_BENCH_H

#include <stdio.h>

#include "drape/error.h"
#include "drape/fabric.h"
#include "drape/integrator.h"
#include "drape/lattice.h"
#include "drape/model.h"
#include "drape/scene.h"

#define BENCH_MAX_LIST 64

typedef enum pt_status { PT_OK, PT_FAILED, PT_TIMEOUT, PT_SKIPPED } pt_status;

/* One measured point: a fixed-size record, also the child -> parent message. */
typedef struct bench_point {
    char role[16];
    int status;     /* pt_status */
    int err_kind;   /* drape_error_kind of a failure */
    char integrator[DRAPE_INTEGRATOR_NAME_MAX];
    double rtol, atol;
    double step;    /* animate: its fixed step, s; NaN for the others */
    double wall_s, cpu_s;
    int repeats;
    drape_integrator_stats stats;
    double err_pos, err_pos_rms, err_final, err_final_v;
    double dc;
    int nodes;      /* -1 = none */
    char msg[DRAPE_ERROR_MSG_MAX + DRAPE_ERROR_FILE_MAX];
} bench_point;

typedef struct bench {
    const char *scene_path;
    drape_scene s;
    drape_fabric f;
    drape_lattice *L;
    drape_model *m;
    size_t n3;
    double size;      /* m: largest extent of the rest lattice */
    double t_end;     /* s */
    int samples;      /* K */
    double atol_scale;
    int linsol;
    int repeat;
    double max_wall, ref_max_wall;
    int has_dc;
    char default_name[DRAPE_INTEGRATOR_NAME_MAX];
    double *ref_x;    /* K x 3n: reference positions at t_k, k = 1..K */
    double *ref_v;    /* 3n: reference velocities at t_end */
    double ref_dc;
    double steps[BENCH_MAX_LIST]; /* animate's steps, s (--steps) */
    int n_steps;
    double anim_step; /* the step of the animate point being run */
    int progress;
    /* output */
    bench_point *rows;
    int n_rows, cap_rows;
    const char *out_dir;
    char csv_path[4096];
} bench;

/* "ok", "failed", "timeout", "skipped". */
const char *drape_cli_bench_status_name(int s);

/* Run one point (integrator at rtol, or animate at b->anim_step) in a
 * forked child with a wall-time limit (0 = none), its errors measured
 * against b->ref_x when set (cli_bench_point.c).  With xs/v non-NULL,
 * receive the samples too (the reference run).  Returns 0 (p filled,
 * whatever its status), or -1 with err set if the child could not run. */
int drape_cli_bench_point(const bench *b, const char *integrator, double rtol, double limit,
                          double *xs, double *v, bench_point *p, drape_error *err);

/* CPU seconds of this process. */
double drape_cli_bench_cpu_now(void);
/* One CSV header line from a NULL-terminated list of column names. */
void drape_cli_bench_header(FILE *o, const char *const *cols);
/* --kernels: one CSV row per lattice side into DIR/NAME.csv (NAME default
 * "kernels"; atomically replaced) or stdout. */
int drape_cli_bench_kernels(const drape_scene *s, const drape_fabric *f, const int *sizes,
                            int n_sizes, const char *out_dir, const char *name, int progress_on,
                            drape_error *err);

#endif /* DRAPE_CLI_BENCH_H */
