/* cli_bench.c: `drape bench`: work-precision measurements of the
 * integrators on one scene (docs/performance.md; numerics.md section 5):
 * its options, the sweep over integrators and tolerances (animate: over
 * its fixed steps) after the reference pair, and the CSV.  Each point runs
 * in a child process (cli_bench_point.c); `drape bench --kernels` is in
 * cli_bench_kernels.c.  Only this file, main.c and the other cli_*.c
 * print. */
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "cli.h"
#include "cli_bench.h"
#include "cli_data.h"
#include "cli_io.h"
#include "cli_run.h"
#include "drape/alloc.h"
#include "drape/drape.h"
#include "drape/fabric.h"
#include "drape/integrator.h"
#include "drape/lattice.h"
#include "drape/model.h"
#include "drape/scene.h"
#include "drape/sim.h"
#include "drape/units.h"

#define BENCH_DEFAULT_SCENE "scenes/cusick.yaml"
#define BENCH_KERNEL_SCENE "scenes/hang.yaml"
#define BENCH_REPEAT_BELOW_S 2.0      /* runs longer than this are not repeated */
#define BENCH_DEFAULT_RTOLS "1e-3:1e-8:2"
#define BENCH_DEFAULT_REF "arkode-erk,gsl-rk8pd"
#define BENCH_DEFAULT_REF_RTOL 1e-10
#define BENCH_DEFAULT_ATOL_SCALE 1e-3 /* m: atol = rtol * 1 mm */
#define BENCH_DEFAULT_SAMPLES 10
#define BENCH_ANIMATE_STEPS 6         /* animate: the sample interval / 2^k, k < 6 */
#define BENCH_DEFAULT_REPEAT 3
#define BENCH_DEFAULT_MAX_WALL 300.0  /* s per run */
#define BENCH_DEFAULT_SIZES "10,20,50,100,200"

static const char bench_usage[] =
    "Usage: drape bench [SCENE.yaml] [OPTIONS]\n"
    "       drape bench --kernels [SCENE.yaml] [--sizes N,N,...] [--out DIR]\n"
    "\n"
    "Work-precision benchmark (docs/performance.md): run the scene (default\n"
    BENCH_DEFAULT_SCENE ") with each integrator at each tolerance up to\n"
    "--t-end, and measure time, solver counters and the error against a\n"
    "reference solution.  The reference is the first --ref integrator at\n"
    "--ref-rtol; the second one is run the same way and its error against the\n"
    "first (rows `ref-check`) says how far the reference can be trusted.\n"
    "Equilibrium detection is off: every run integrates [0, t_end].\n"
    "\n"
    "Tolerances: atol = rtol * --atol-scale on positions (m); velocities get\n"
    "atol / T, T = sqrt(L / g) (docs/integrators.md, \"Tolerances\").\n"
    "\n"
    "Errors (all relative, dimensionless):\n"
    "  err_pos_rel      max over the K sample times t_k = k t_end / K and over\n"
    "                   particles of |x - x_ref|, divided by the specimen size\n"
    "                   size_m (largest extent of the rest lattice)\n"
    "  err_pos_rms_rel  the same with the RMS over particles\n"
    "  err_final_rel    max over particles of |x - x_ref| at t_end / size_m\n"
    "  err_final_v_rel  max over particles of |v - v_ref| at t_end / sqrt(g size_m)\n"
    "  err_dc           |DC - DC_ref| at t_end (cusick and table scenes only)\n"
    "\n"
    "Options:\n"
    "  --fabric FILE           fabric file instead of the scene's\n"
    "  --spacing LEN           lattice spacing, e.g. 5mm\n"
    "  --integrators A,B,...   integrators to sweep (default: cvode-bdf,\n"
    "                          arkode-imex, arkode-dirk, arkode-erk, gsl-msbdf,\n"
    "                          gsl-rk8pd and animate; auto only when listed)\n"
    "  --rtols LIST            comma-separated values, or HI:LO:N = N per decade\n"
    "                          from HI down to LO (default " BENCH_DEFAULT_RTOLS ");\n"
    "                          each value in (0, 1) as run's --rtol reads it\n"
    "  --steps LIST            the animate method's fixed steps, which it sweeps\n"
    "                          instead of tolerances, e.g. 10ms,5ms (default: the\n"
    "                          sample interval t_end / K divided by 1, 2, 4, ..., 32)\n"
    "  --atol-scale LEN        atol = rtol * LEN (default 1 mm)\n"
    "  --linear-solver NAME    auto (default), klu, schur or schur-direct\n"
    "  --max-order N           highest BDF order of cvode-bdf (also inside auto),\n"
    "                          1 to 5 (default: the scene's solver.max_order, else 2)\n"
    "  --t-end T               horizon (default: the scene's t_max)\n"
    "  --samples K             sample times for err_pos_rel (default 10)\n"
    "  --repeat N              time a point as the minimum of N runs; runs\n"
    "                          longer than 2 s are not repeated (default 3)\n"
    "  --max-wall S            stop a run after S s of wall time and record it as\n"
    "                          timeout; tighter tolerances of that integrator are\n"
    "                          then skipped (default 300; 0 = no limit)\n"
    "  --ref A,B               reference pair (default " BENCH_DEFAULT_REF ")\n"
    "  --ref-rtol X[,Y]        tolerance of the reference A [and of B] (default\n"
    "                          1e-10 for both)\n"
    "  --ref-max-wall S        time limit of each reference run (default 0 = none)\n"
    "  --out DIR               write DIR/NAME.csv (replaced after every point)\n"
    "                          instead of the CSV on stdout\n"
    "  --name NAME             file name stem (default: the scene file's, or\n"
    "                          `kernels' with --kernels)\n"
    "  --kernels               time one force evaluation (RHS), K and D, the\n"
    "                          first-order J and one CHOLMOD factorisation of\n"
    "                          S = M - gamma D - gamma^2 K on square lattices of\n"
    "                          the scene (default " BENCH_KERNEL_SCENE ") with N x N\n"
    "                          particles at its spacing; CPU time, minimum of 5\n"
    "                          batches\n"
    "  --sizes N,N,...         lattice sides for --kernels (default " BENCH_DEFAULT_SIZES ")\n"
    "  -q, --quiet             no progress on stderr (progress is printed only when\n"
    "                          stderr is a terminal)\n"
    "  -h, --help              show this help\n"
    "\n"
    "CSV columns: role (ref, ref-check, sweep), scene, fabric, particles,\n"
    "free_particles, size_m, t_end_s, samples, integrator, default (1 for\n"
    "`auto', the default integrator), linear_solver, rtol, atol_m, status (ok,\n"
    "failed, timeout, skipped), wall_s (minimum over repeats, integrator set-up\n"
    "and stepping), cpu_s (minimum, the run's process CPU time), repeats,\n"
    "steps, rhs_evals, jac_evals, lin_setups, lin_factors, nonlin_iters,\n"
    "err_test_fails, conv_fails, err_pos_rel, err_pos_rms_rel, err_final_rel,\n"
    "err_final_v_rel, dc, dc_ref, err_dc, nodes, message, max_order (cvode-bdf\n"
    "and auto), step_s (animate: its rtol and atol_m are empty).  Empty = not\n"
    "available.\n"
    "--kernels columns: side, particles, free_particles, nnz_K, rhs_ms, jac_ms\n"
    "(K and D), jac_first_order_ms, schur_factor_ms, rhs_us_per_free,\n"
    "jac_us_per_free, schur_solve_ms (one solve with that factor).\n"
    "\n"
    "Exit status: 0 done (failed or timed-out points are data, not errors),\n"
    "1 invalid input, 2 bad command line, 3 I/O error, 4 the reference run\n"
    "failed, 5 out of memory.\n";

/* Column names of the CSV (the contract, --help and docs/performance.md). */
static const char *const bench_columns[] = {
    "role", "scene", "fabric", "particles", "free_particles", "size_m", "t_end_s",
    "samples", "integrator", "default", "linear_solver", "rtol", "atol_m", "status",
    "wall_s", "cpu_s", "repeats", "steps", "rhs_evals", "jac_evals", "lin_setups",
    "lin_factors", "nonlin_iters", "err_test_fails", "conv_fails", "err_pos_rel",
    "err_pos_rms_rel", "err_final_rel", "err_final_v_rel", "dc", "dc_ref", "err_dc",
    "nodes", "message", "max_order", "step_s", NULL};

/* Name of a pt_status. */
const char *drape_cli_bench_status_name(int s)
{
    switch (s) {
    case PT_OK: return "ok";
    case PT_FAILED: return "failed";
    case PT_TIMEOUT: return "timeout";
    default: return "skipped";
    }
}

/* ---- small helpers -------------------------------------------------------- */

static int bench_usage_error(const char *fmt, const char *a)
{
    fputs("drape: ", stderr);
    fprintf(stderr, fmt, a);
    fputs("\nTry `drape bench --help'.\n", stderr);
    return drape_error_exit_status(DRAPE_E_USAGE);
}

static int bench_quantity(const char *opt, const char *text, drape_dim dim, double *v)
{
    char why[256];
    if (drape_units_parse(text, dim, v, why, sizeof why) != 0) {
        fprintf(stderr, "drape: %s: %s\nTry `drape bench --help'.\n", opt, why);
        return -1;
    }
    return 0;
}

double drape_cli_bench_cpu_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int split_list(char *text, char **items, int max)
{
    int n = 0;
    for (char *p = text;;) {
        char *c = strchr(p, ',');
        if (c) *c = 0;
        if (!*p || n == max) return -1;
        items[n++] = p;
        if (!c) break;
        p = c + 1;
    }
    return n;
}

/* --rtols: "a,b,c" or "HI:LO:N", each value read as run's --rtol
 * (drape_cli_rtol_parse).  Values sorted from loose to tight.  The count,
 * or -1 with why naming --rtols. */
static int parse_rtols(const char *text, double *out, int max, char *why, size_t nwhy)
{
    char buf[512];
    int n = 0;
    if (strlen(text) >= sizeof buf) return snprintf(why, nwhy, "--rtols: list too long"), -1;
    snprintf(buf, sizeof buf, "%s", text);
    char *c1 = strchr(buf, ':');
    if (c1) {
        char *c2 = strchr(c1 + 1, ':'), *end;
        double hi, lo;
        if (!c2) goto bad_range;
        *c1 = *c2 = 0;
        if (drape_cli_rtol_parse("--rtols", buf, &hi, why, nwhy) ||
            drape_cli_rtol_parse("--rtols", c1 + 1, &lo, why, nwhy))
            return -1;
        errno = 0;
        long per = strtol(c2 + 1, &end, 10);
        if (errno || end == c2 + 1 || *end || per < 1 || per > 8 || !(lo <= hi)) goto bad_range;
        double decades = log10(hi / lo);
        long k_max = (long)floor(decades * (double)per + 1e-9);
        for (long k = 0; k <= k_max; k++) {
            if (n == max) return snprintf(why, nwhy, "--rtols: more than %d values", max), -1;
            double e = log10(hi) - (double)k / (double)per;
            double v = pow(10.0, e);
            /* keep three significant digits so names print cleanly */
            char t[32];
            snprintf(t, sizeof t, "%.3g", v);
            out[n++] = strtod(t, NULL);
        }
    } else {
        char *items[BENCH_MAX_LIST];
        int k = split_list(buf, items, BENCH_MAX_LIST < max ? BENCH_MAX_LIST : max);
        if (k < 0) goto bad_range;
        for (int i = 0; i < k; i++)
            if (drape_cli_rtol_parse("--rtols", items[i], &out[n++], why, nwhy)) return -1;
    }
    /* loose to tight */
    for (int i = 1; i < n; i++)
        for (int j = i; j > 0 && out[j] > out[j - 1]; j--) {
            double t = out[j];
            out[j] = out[j - 1];
            out[j - 1] = t;
        }
    return n;
bad_range:
    snprintf(why, nwhy, "--rtols: expected values in (0, 1) as a,b,c or HI:LO:N "
             "(LO <= HI, N from 1 to 8 per decade), got `%s'", text);
    return -1;
}

/* --ref-rtol: "X" or "X,Y", each read as run's --rtol. */
static int parse_ref_rtol(const char *text, double ref_rtol[2], char *why, size_t nwhy)
{
    char buf[256], *items[3];
    if (strlen(text) >= sizeof buf) return snprintf(why, nwhy, "--ref-rtol: too long"), -1;
    snprintf(buf, sizeof buf, "%s", text);
    int k = split_list(buf, items, 2);
    if (k < 1) return snprintf(why, nwhy, "--ref-rtol: expected X or X,Y, got `%s'", text), -1;
    for (int i = 0; i < k; i++)
        if (drape_cli_rtol_parse("--ref-rtol", items[i], &ref_rtol[i], why, nwhy)) return -1;
    if (k == 1) ref_rtol[1] = ref_rtol[0];
    return 0;
}

static int integrator_known(const char *name)
{
    for (int i = 0; drape_integrator_names[i]; i++)
        if (strcmp(drape_integrator_names[i], name) == 0) return 1;
    return 0;
}

/* ---- output ------------------------------------------------------------------------ */

static void put_num(FILE *o, double v)
{
    if (isfinite(v)) fprintf(o, "%.6g", v);
}
static void put_count(FILE *o, long v)
{
    if (v >= 0) fprintf(o, "%ld", v);
}

void drape_cli_bench_header(FILE *o, const char *const *cols)
{
    for (int i = 0; cols[i]; i++) fprintf(o, "%s%s", i ? "," : "", cols[i]);
    fputc('\n', o);
}

static void write_row(FILE *o, const bench *b, const bench_point *p)
{
    const drape_lattice *L = b->L;
    const drape_integrator_stats *st = &p->stats;
    int implicit = st->linsol > 0;
    fprintf(o, "%s,", p->role);
    drape_cli_csv_put(o, drape_scene_kind_name(b->s.kind));
    fputc(',', o);
    drape_cli_csv_put(o, b->f.name);
    fprintf(o, ",%d,%d,", L->n, L->n_free);
    put_num(o, b->size);
    fputc(',', o);
    put_num(o, b->t_end);
    fprintf(o, ",%d,%s,%d,%s,", b->samples, p->integrator,
            strcmp(p->integrator, b->default_name) == 0,
            implicit ? drape_linsol_name(st->linsol) : "none");
    put_num(o, p->rtol);
    fputc(',', o);
    put_num(o, p->atol);
    fprintf(o, ",%s,", drape_cli_bench_status_name(p->status));
    put_num(o, p->wall_s);
    fputc(',', o);
    put_num(o, p->cpu_s);
    fputc(',', o);
    if (p->status == PT_OK) fprintf(o, "%d", p->repeats);
    const long c[8] = {st->steps, st->rhs_evals, st->jac_evals, st->lin_setups,
                       st->lin_factors, st->nonlin_iters, st->err_test_fails, st->conv_fails};
    for (int i = 0; i < 8; i++) {
        fputc(',', o);
        if (p->status != PT_SKIPPED) put_count(o, c[i]);
    }
    const double e[4] = {p->err_pos, p->err_pos_rms, p->err_final, p->err_final_v};
    for (int i = 0; i < 4; i++) {
        fputc(',', o);
        put_num(o, e[i]);
    }
    fputc(',', o);
    put_num(o, p->dc);
    fputc(',', o);
    if (b->has_dc) put_num(o, b->ref_dc);
    fputc(',', o);
    if (isfinite(p->dc) && isfinite(b->ref_dc) && strcmp(p->role, "ref") != 0)
        put_num(o, fabs(p->dc - b->ref_dc));
    fputc(',', o);
    if (p->nodes >= 0) fprintf(o, "%d", p->nodes);
    fputc(',', o);
    drape_cli_csv_put(o, p->msg);
    fputc(',', o);
    int bdf = drape_integrator_bdf_order(p->integrator, b->s.max_order);
    if (bdf > 0) fprintf(o, "%d", bdf);
    fputc(',', o);
    put_num(o, p->step);
    fputc('\n', o);
}

/* Rewrite DIR/NAME.csv with every row so far (atomic replacement). */
static int flush_csv(bench *b, drape_error *err)
{
    if (!b->out_dir) return 0;
    drape_cli_afile a;
    if (drape_cli_afile_open(&a, b->csv_path, err) != 0) return -1;
    drape_cli_bench_header(a.f, bench_columns);
    for (int i = 0; i < b->n_rows; i++) write_row(a.f, b, &b->rows[i]);
    return drape_cli_afile_commit(&a, err);
}

static int add_row(bench *b, const bench_point *p, drape_error *err)
{
    if (b->n_rows == b->cap_rows) {
        int cap = b->cap_rows ? 2 * b->cap_rows : 64;
        bench_point *nr = drape_realloc(b->rows, sizeof *nr * (size_t)cap);
        if (!nr) return drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL, "out of memory");
        b->rows = nr;
        b->cap_rows = cap;
    }
    b->rows[b->n_rows++] = *p;
    if (!b->out_dir) {
        write_row(stdout, b, p);
        if (fflush(stdout) != 0)
            return drape_error_set(err, DRAPE_E_IO, "<stdout>", 0, 0, NULL, "cannot write the CSV");
        return 0;
    }
    return flush_csv(b, err);
}

static void progress(const bench *b, const bench_point *p)
{
    if (!b->progress) return;
    if (isfinite(p->step))
        fprintf(stderr, "drape: bench %-9s %-11s step %-8.3g %-7s", p->role, p->integrator,
                p->step, drape_cli_bench_status_name(p->status));
    else
        fprintf(stderr, "drape: bench %-9s %-11s rtol %-8.3g %-7s", p->role, p->integrator,
                p->rtol, drape_cli_bench_status_name(p->status));
    if (p->status == PT_OK)
        fprintf(stderr, " wall %.3g s, cpu %.3g s, err_pos %.3g", p->wall_s, p->cpu_s, p->err_pos);
    else if (p->msg[0])
        fprintf(stderr, " %.120s", p->msg);
    fputc('\n', stderr);
}

/* File name stem: --name, or the scene file's base name without .yaml/.yml. */
static void csv_path(bench *b, const char *name, const char *fallback)
{
    char stem[256];
    if (name) {
        snprintf(stem, sizeof stem, "%s", name);
    } else {
        const char *base = strrchr(fallback, '/');
        base = base ? base + 1 : fallback;
        snprintf(stem, sizeof stem, "%.200s", base); /* a file name: long ones shortened */
        char *dot = strrchr(stem, '.');
        if (dot && (strcmp(dot, ".yaml") == 0 || strcmp(dot, ".yml") == 0)) *dot = 0;
    }
    snprintf(b->csv_path, sizeof b->csv_path, "%s/%s.csv", b->out_dir, stem);
}

/* ---- the sweep ------------------------------------------------------------------- */

static int run_sweep(bench *b, char **integ, int n_integ, const double *rtols, int n_rtols,
                     char **ref, const double *ref_rtol, drape_error *err)
{
    bench_point p;
    /* the reference */
    b->ref_x = drape_malloc(sizeof(double) * b->n3 * (size_t)b->samples);
    b->ref_v = drape_malloc(sizeof(double) * (b->n3 ? b->n3 : 1));
    if (!b->ref_x || !b->ref_v)
        return drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL,
                               "out of memory for the reference samples");
    double *rx = b->ref_x;
    b->ref_x = NULL; /* the reference child computes no errors */
    if (drape_cli_bench_point(b, ref[0], ref_rtol[0], b->ref_max_wall, rx, b->ref_v, &p, err) != 0) {
        b->ref_x = rx;
        return -1;
    }
    b->ref_x = rx;
    snprintf(p.role, sizeof p.role, "ref");
    b->ref_dc = p.dc;
    if (p.status == PT_OK) p.err_pos = p.err_pos_rms = p.err_final = p.err_final_v = 0.0;
    progress(b, &p);
    if (add_row(b, &p, err) != 0) return -1;
    if (p.status != PT_OK)
        return drape_error_set(err, p.status == PT_FAILED && p.err_kind == DRAPE_E_NOMEM
                                        ? DRAPE_E_NOMEM : DRAPE_E_NUMERIC,
                               NULL, 0, 0, NULL, "reference run %s at rtol %g: %s: %s", ref[0],
                               ref_rtol[0], drape_cli_bench_status_name(p.status), p.msg);
    /* the second reference, measured against the first */
    if (drape_cli_bench_point(b, ref[1], ref_rtol[1], b->ref_max_wall, NULL, NULL, &p, err) != 0) return -1;
    snprintf(p.role, sizeof p.role, "ref-check");
    progress(b, &p);
    if (add_row(b, &p, err) != 0) return -1;
    double agree = p.status == PT_OK ? p.err_pos : NAN;
    if (!isfinite(agree))
        fprintf(stderr, "drape: warning: the reference check %s did not finish (%s); the "
                        "reference is not confirmed\n", ref[1], drape_cli_bench_status_name(p.status));

    double smallest = INFINITY;
    for (int ii = 0; ii < n_integ; ii++) {
        int skip = 0;
        /* animate sweeps its fixed step (--steps) instead of a tolerance */
        int animate = strcmp(integ[ii], "animate") == 0;
        int n_points = animate ? b->n_steps : n_rtols;
        for (int k = 0; k < n_points; k++) {
            double rtol_k = animate ? NAN : rtols[k];
            if (animate) b->anim_step = b->steps[k];
            if (skip) {
                memset(&p, 0, sizeof p);
                snprintf(p.integrator, sizeof p.integrator, "%s", integ[ii]);
                if (strcmp(integ[ii], "auto") == 0)
                    snprintf(p.integrator, sizeof p.integrator, "%s", b->default_name);
                p.rtol = rtol_k;
                p.atol = rtol_k * b->atol_scale;
                p.step = animate ? b->anim_step : NAN;
                p.status = PT_SKIPPED;
                p.nodes = -1;
                p.err_pos = p.err_pos_rms = p.err_final = p.err_final_v = p.dc = NAN;
                p.wall_s = p.cpu_s = NAN;
                snprintf(p.msg, sizeof p.msg, "a looser tolerance already timed out or ran out of memory");
            } else {
                if (drape_cli_bench_point(b, integ[ii], rtol_k, b->max_wall, NULL, NULL, &p, err) != 0)
                    return -1;
                for (int rep = 1; rep < b->repeat && p.status == PT_OK &&
                                  p.wall_s < BENCH_REPEAT_BELOW_S; rep++) {
                    bench_point q;
                    if (drape_cli_bench_point(b, integ[ii], rtol_k, b->max_wall, NULL, NULL, &q, err) != 0)
                        return -1;
                    if (q.status != PT_OK) break;
                    if (q.wall_s < p.wall_s) p.wall_s = q.wall_s;
                    if (q.cpu_s < p.cpu_s) p.cpu_s = q.cpu_s;
                    p.repeats++;
                }
                if (p.status == PT_TIMEOUT ||
                    (p.status == PT_FAILED && p.err_kind == DRAPE_E_NOMEM))
                    skip = 1;
                if (p.status == PT_OK && p.err_pos > 0 && p.err_pos < smallest)
                    smallest = p.err_pos;
            }
            snprintf(p.role, sizeof p.role, "sweep");
            progress(b, &p);
            if (add_row(b, &p, err) != 0) return -1;
        }
    }
    if (isfinite(agree) && isfinite(smallest) && agree > 0.01 * smallest)
        fprintf(stderr, "drape: warning: the reference pair agrees to %.3g (err_pos_rel), more "
                        "than 1/100 of the smallest error measured (%.3g); tighten --ref-rtol\n",
                agree, smallest);
    return 0;
}

/* ---- entry ---------------------------------------------------------------------------- */

int drape_cli_bench(int argc, char **argv)
{
    enum { O_FABRIC = 1000, O_SPACING, O_INTEG, O_RTOLS, O_ATOL_SCALE, O_LINSOL, O_TEND,
           O_SAMPLES, O_REPEAT, O_MAXWALL, O_REF, O_REFRTOL, O_REFMAXWALL, O_OUT, O_NAME,
           O_KERNELS, O_SIZES, O_MAXORDER, O_STEPS };
    static const struct option opts[] = {
        {"fabric", required_argument, NULL, O_FABRIC},
        {"spacing", required_argument, NULL, O_SPACING},
        {"integrators", required_argument, NULL, O_INTEG},
        {"rtols", required_argument, NULL, O_RTOLS},
        {"atol-scale", required_argument, NULL, O_ATOL_SCALE},
        {"linear-solver", required_argument, NULL, O_LINSOL},
        {"t-end", required_argument, NULL, O_TEND},
        {"samples", required_argument, NULL, O_SAMPLES},
        {"repeat", required_argument, NULL, O_REPEAT},
        {"max-wall", required_argument, NULL, O_MAXWALL},
        {"ref", required_argument, NULL, O_REF},
        {"ref-rtol", required_argument, NULL, O_REFRTOL},
        {"ref-max-wall", required_argument, NULL, O_REFMAXWALL},
        {"out", required_argument, NULL, O_OUT},
        {"name", required_argument, NULL, O_NAME},
        {"kernels", no_argument, NULL, O_KERNELS},
        {"sizes", required_argument, NULL, O_SIZES},
        {"max-order", required_argument, NULL, O_MAXORDER},
        {"steps", required_argument, NULL, O_STEPS},
        {"quiet", no_argument, NULL, 'q'},
        {"help", no_argument, NULL, 'h'},
        {NULL, 0, NULL, 0}};
    static char integ_buf[512], ref_buf[128], sizes_buf[512], steps_buf[512];
    const char *steps_text = NULL;
    const char *fabric_path = NULL, *out_dir = NULL, *name = NULL;
    const char *integ_text = NULL, *ref_text = BENCH_DEFAULT_REF, *sizes_text = BENCH_DEFAULT_SIZES;
    const char *rtols_text = BENCH_DEFAULT_RTOLS;
    double spacing = 0, t_end = 0, atol_scale = BENCH_DEFAULT_ATOL_SCALE;
    double max_wall = BENCH_DEFAULT_MAX_WALL, ref_max_wall = 0;
    double ref_rtol[2] = {BENCH_DEFAULT_REF_RTOL, BENCH_DEFAULT_REF_RTOL};
    long samples = BENCH_DEFAULT_SAMPLES, repeat = BENCH_DEFAULT_REPEAT;
    int max_order = 0;
    int linsol = 0, quiet = 0, kernels = 0, c;
    char *end;
    if ((c = drape_cli_args_unambiguous(argc, argv, "qh", opts, "drape bench")) != 0) return c;
    while ((c = getopt_long(argc, argv, "qh", opts, NULL)) != -1) {
        switch (c) {
        case O_FABRIC: fabric_path = optarg; break;
        case O_SPACING:
            if (bench_quantity("--spacing", optarg, DRAPE_DIM_LENGTH, &spacing)) return 2;
            if (!(spacing > 0)) return bench_usage_error("--spacing: must be positive, got %s", optarg);
            break;
        case O_INTEG: integ_text = optarg; break;
        case O_RTOLS: rtols_text = optarg; break;
        case O_STEPS: steps_text = optarg; break;
        case O_ATOL_SCALE:
            if (bench_quantity("--atol-scale", optarg, DRAPE_DIM_LENGTH, &atol_scale)) return 2;
            if (!(atol_scale > 0)) return bench_usage_error("--atol-scale: must be positive, got %s", optarg);
            break;
        case O_LINSOL:
            if (drape_linsol_parse(optarg, &linsol) != 0)
                return bench_usage_error("--linear-solver: expected auto, klu, schur or schur-direct, got `%s'", optarg);
            break;
        case O_TEND:
            if (bench_quantity("--t-end", optarg, DRAPE_DIM_TIME, &t_end)) return 2;
            if (!(t_end > 0) || !isfinite(t_end)) return bench_usage_error("--t-end: must be positive, got %s", optarg);
            break;
        case O_SAMPLES:
            errno = 0;
            samples = strtol(optarg, &end, 10);
            if (errno || *end || samples < 1 || samples > 10000)
                return bench_usage_error("--samples: expected an integer in 1..10000, got `%s'", optarg);
            break;
        case O_MAXORDER:
            if (drape_max_order_parse(optarg, &max_order) != 0)
                return bench_usage_error("--max-order: expected an integer from 1 to 5, got `%s'", optarg);
            break;
        case O_REPEAT:
            errno = 0;
            repeat = strtol(optarg, &end, 10);
            if (errno || *end || repeat < 1 || repeat > 1000)
                return bench_usage_error("--repeat: expected an integer in 1..1000, got `%s'", optarg);
            break;
        case O_MAXWALL:
        case O_REFMAXWALL: {
            double w;
            if (bench_quantity(c == O_MAXWALL ? "--max-wall" : "--ref-max-wall", optarg,
                               DRAPE_DIM_TIME, &w)) return 2;
            if (!(w >= 0) || !isfinite(w))
                return bench_usage_error(c == O_MAXWALL ? "--max-wall: must be a time >= 0, got %s"
                                                        : "--ref-max-wall: must be a time >= 0, got %s",
                                         optarg);
            if (c == O_MAXWALL) max_wall = w;
            else ref_max_wall = w;
            break;
        }
        case O_REF: ref_text = optarg; break;
        case O_REFRTOL: {
            char why[512];
            if (parse_ref_rtol(optarg, ref_rtol, why, sizeof why) != 0)
                return bench_usage_error("%s", why);
            break;
        }
        case O_OUT:
            if (!*optarg)
                return bench_usage_error("%s", "--out: expected a directory, got an empty name");
            out_dir = optarg;
            break;
        case O_NAME:
            if (!*optarg || strchr(optarg, '/'))
                return bench_usage_error("--name: expected a file name stem, got `%s'", optarg);
            name = optarg;
            break;
        case O_KERNELS: kernels = 1; break;
        case O_SIZES: sizes_text = optarg; break;
        case 'q': quiet = 1; break;
        case 'h': fputs(bench_usage, stdout); return 0;
        default:
            fputs("Try `drape bench --help'.\n", stderr);
            return drape_error_exit_status(DRAPE_E_USAGE);
        }
    }
    if (argc - optind > 1)
        return bench_usage_error("bench: one scene at a time, got `%s' and more", argv[optind]);

    /* lists */
    char *integ[BENCH_MAX_LIST], *ref[BENCH_MAX_LIST];
    int n_integ = 0, n_ref;
    if (integ_text) {
        if (strlen(integ_text) >= sizeof integ_buf)
            return bench_usage_error("--integrators: list too long%s", "");
        snprintf(integ_buf, sizeof integ_buf, "%s", integ_text);
        n_integ = split_list(integ_buf, integ, BENCH_MAX_LIST);
        if (n_integ < 1) return bench_usage_error("--integrators: bad list `%s'", integ_text);
    } else {
        const drape_integrator_type *const *all = drape_integrator_types();
        for (; all[n_integ] && n_integ < BENCH_MAX_LIST; n_integ++)
            integ[n_integ] = (char *)all[n_integ]->name;
    }
    for (int i = 0; i < n_integ; i++)
        if (!integrator_known(integ[i]))
            return bench_usage_error("--integrators: unknown integrator `%s'; see `drape run --help'", integ[i]);
    if (strlen(ref_text) >= sizeof ref_buf) return bench_usage_error("--ref: list too long%s", "");
    snprintf(ref_buf, sizeof ref_buf, "%s", ref_text);
    n_ref = split_list(ref_buf, ref, BENCH_MAX_LIST);
    if (n_ref != 2) return bench_usage_error("--ref: expected two integrators A,B, got `%s'", ref_text);
    for (int i = 0; i < 2; i++)
        if (!integrator_known(ref[i]) || strcmp(ref[i], "auto") == 0)
            return bench_usage_error("--ref: unknown integrator `%s'", ref[i]);
    if (strcmp(ref[0], ref[1]) == 0)
        return bench_usage_error("--ref: the two reference integrators must differ, got `%s' twice", ref[0]);
    double steps[BENCH_MAX_LIST];
    int n_steps = 0;
    if (steps_text) { /* animate's steps: times with units, e.g. 10ms,5ms */
        if (strlen(steps_text) >= sizeof steps_buf) return bench_usage_error("--steps: list too long%s", "");
        snprintf(steps_buf, sizeof steps_buf, "%s", steps_text);
        char *items[BENCH_MAX_LIST];
        n_steps = split_list(steps_buf, items, BENCH_MAX_LIST);
        if (n_steps < 1) return bench_usage_error("--steps: bad list `%s'", steps_text);
        for (int i = 0; i < n_steps; i++) {
            if (bench_quantity("--steps", items[i], DRAPE_DIM_TIME, &steps[i])) return 2;
            if (!(steps[i] > 0) || !isfinite(steps[i]))
                return bench_usage_error("--steps: must be positive, got %s", items[i]);
        }
    }
    double rtols[BENCH_MAX_LIST];
    char rtols_why[512];
    int n_rtols = parse_rtols(rtols_text, rtols, BENCH_MAX_LIST, rtols_why, sizeof rtols_why);
    if (n_rtols < 1) return bench_usage_error("%s", rtols_why);
    int sizes[BENCH_MAX_LIST], n_sizes = 0;
    {
        if (strlen(sizes_text) >= sizeof sizes_buf) return bench_usage_error("--sizes: list too long%s", "");
        snprintf(sizes_buf, sizeof sizes_buf, "%s", sizes_text);
        char *items[BENCH_MAX_LIST];
        n_sizes = split_list(sizes_buf, items, BENCH_MAX_LIST);
        if (n_sizes < 1) return bench_usage_error("--sizes: bad list `%s'", sizes_text);
        for (int i = 0; i < n_sizes; i++) {
            long v = strtol(items[i], &end, 10);
            if (*end || v < 2 || v > 2000)
                return bench_usage_error("--sizes: expected integers in 2..2000, got `%s'", items[i]);
            sizes[i] = (int)v;
        }
    }

    const char *scene_path = optind < argc ? argv[optind]
                             : kernels ? BENCH_KERNEL_SCENE : BENCH_DEFAULT_SCENE;
    drape_error err;
    drape_error_clear(&err);
    char scene_buf[4096], fabric_buf[4096]; /* cli_data.h */
    if (drape_cli_data_find(scene_path, scene_buf, sizeof scene_buf, &err) != 0 ||
        (fabric_path && drape_cli_data_find(fabric_path, fabric_buf, sizeof fabric_buf, &err) != 0)) {
        drape_cli_print_error(&err);
        return drape_error_exit_status(err.kind);
    }
    scene_path = scene_buf;
    if (fabric_path) fabric_path = fabric_buf;
    bench b;
    memset(&b, 0, sizeof b);
    b.scene_path = scene_path;
    b.progress = !quiet && isatty(STDERR_FILENO);
    b.ref_dc = NAN;
    int status = 0;

    if (drape_scene_load_flags(scene_path, fabric_path ? DRAPE_SCENE_LOAD_FABRIC_OVERRIDDEN : 0u, &b.s,
                               &err, drape_cli_warn, NULL) != 0) goto fail;
    if (fabric_path &&
        (size_t)snprintf(b.s.fabric_path, sizeof b.s.fabric_path, "%s", fabric_path) >= sizeof b.s.fabric_path) {
        drape_error_set(&err, DRAPE_E_IO, fabric_path, 0, 0, NULL, "path too long");
        goto fail;
    }
    if (spacing > 0) b.s.spacing = spacing;
    if (max_order > 0) b.s.max_order = max_order;
    if (drape_fabric_load(b.s.fabric_path, &b.f, &err, drape_cli_warn, NULL) != 0) goto fail;
    b.s.damping_shear = drape_scene_damping_shear(&b.s, &b.f); /* the fabric's unless the scene's */

    if (kernels) {
        if (b.s.kind != DRAPE_SCENE_HANG) {
            drape_error_set(&err, DRAPE_E_INPUT, scene_path, 0, 0, "scene",
                            "--kernels needs a hang scene (square lattices), got %s",
                            drape_scene_kind_name(b.s.kind));
            goto fail;
        }
        if (drape_cli_bench_kernels(&b.s, &b.f, sizes, n_sizes, out_dir, name, b.progress, &err) != 0)
            goto fail;
        goto out;
    }

    if (drape_scene_check_with_fabric(&b.s, &b.f, &err) != 0) goto fail;
    b.L = drape_lattice_new(&b.s, &b.f, &err);
    if (!b.L) goto fail;
    drape_model_opts mo;
    drape_model_opts_from_scene(&b.s, &mo);
    b.m = drape_model_new(b.L, &b.f, &mo, &err);
    if (!b.m) goto fail;
    b.n3 = 3 * (size_t)b.L->n;
    {
        double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
        for (int i = 0; i < b.L->n; i++)
            for (int d = 0; d < 2; d++) {
                lo[d] = fmin(lo[d], b.L->x0[3 * i + d]);
                hi[d] = fmax(hi[d], b.L->x0[3 * i + d]);
            }
        b.size = fmax(hi[0] - lo[0], hi[1] - lo[1]);
        if (!(b.size > 0)) b.size = b.s.spacing;
    }
    b.t_end = t_end > 0 ? t_end : b.s.t_max;
    b.samples = (int)samples;
    /* animate's steps: given, or the sample interval / 2^k, k = 0..5 (each
     * divides the interval, so the samples fall on the step grid) */
    b.n_steps = n_steps > 0 ? n_steps : BENCH_ANIMATE_STEPS;
    for (int i = 0; i < b.n_steps; i++)
        b.steps[i] = n_steps > 0 ? steps[i] : b.t_end / b.samples / (double)(1 << i);
    b.atol_scale = atol_scale;
    b.linsol = linsol;
    b.repeat = (int)repeat;
    b.max_wall = max_wall;
    b.ref_max_wall = ref_max_wall;
    b.has_dc = b.s.kind == DRAPE_SCENE_CUSICK || b.s.kind == DRAPE_SCENE_TABLE;
    {
        /* the default integrator's name (`auto', its own backend) */
        drape_integrator_opts io;
        drape_integrator_opts_default(&io);
        io.t_stop = b.t_end;
        drape_integrator *I = drape_integrator_new(b.m, "auto", &io, &err);
        if (!I) goto fail;
        snprintf(b.default_name, sizeof b.default_name, "%s", drape_integrator_name(I));
        drape_integrator_free(I);
    }
    b.out_dir = out_dir;
    if (out_dir) {
        if (drape_cli_ensure_dir(out_dir, NULL, &err) != 0) goto fail;
        csv_path(&b, name, scene_path);
    } else {
        drape_cli_bench_header(stdout, bench_columns);
    }
    if (run_sweep(&b, integ, n_integ, rtols, n_rtols, ref, ref_rtol, &err) != 0) goto fail;
    if (out_dir && b.progress) fprintf(stderr, "drape: bench: wrote %s\n", b.csv_path);
    goto out;
fail:
    drape_cli_print_error(&err);
    status = drape_error_exit_status(err.kind);
out:
    drape_free(b.rows);
    drape_free(b.ref_x);
    drape_free(b.ref_v);
    drape_model_free(b.m);
    drape_lattice_free(b.L);
    return status;
}
