/* cli_specimens.c: repeated specimens (docs/model.md 6; docs/ensemble.md).
 *
 * A drape test of N specimens is a loop over single runs above the single
 * run: specimen k = 0 .. N-1 is the scene with perturbation seed
 * seed + k, run by drape_cli_run_one in a child process (fork, no exec),
 * at most -j at a time.  A child sends its result fields and its shadow's
 * sampled outline through a pipe (cli_result.h's line format); the parent
 * collects them, reads each child's CPU time from wait4, computes the
 * statistics (ensemble.h), prints one result and draws DIR/shadow.svg.
 *
 * The ensemble's keys: dc is the mean DC, nodes the modal node count,
 * dc_sd, dc_ci95, dc_mode, nodes_hist, specimens (one object per
 * specimen), specimens_failed, cpu_s (this process and its children).
 * Other keys combine the specimens' values by the rule in key_rules:
 * the same for all (inputs), mean (geometry, energies), largest (times,
 * strains, residuals), smallest (certification margins) or sum (solver
 * counters).  Failed specimens are counted and left out of every
 * statistic; the run fails (exit 4) only when none produced a result.
 * SIGINT/SIGTERM: no new specimen starts, the running ones stop at their
 * next evaluation (they are sent the signal too), the result says
 * status interrupted and exits 128 + the signal.  A signal that comes
 * when every specimen has finished (before the last is reaped) stops
 * nothing: the ensemble ends as it would have.
 *
 * With --out DIR the ensemble keeps a record there (cli_specimens.h,
 * cli_specimens_record.c): its manifest, written before the first
 * specimen starts, and each finished specimen's result as it comes in.
 * `drape run --resume DIR` continues it through this same driver: the
 * stored specimens are read back, not run; a dynamic specimen that was
 * interrupted continues from its checkpoint (DIR/specimen-NNN/drape.h5,
 * the single run's --resume); the others run from the start.  Without
 * --out an ensemble cannot be resumed.
 */
#include "cli_run.h"

#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "cli.h"
#include "cli_io.h"
#include "cli_specimens.h"
#include "drape/alloc.h"
#include "drape/ensemble.h"
#include "drape/fabric.h"

double drape_cli_cpu_s(void)
{
    struct rusage a, b;
    getrusage(RUSAGE_SELF, &a);
    getrusage(RUSAGE_CHILDREN, &b);
    return (double)(a.ru_utime.tv_sec + a.ru_stime.tv_sec + b.ru_utime.tv_sec +
                    b.ru_stime.tv_sec) +
           1e-6 * (double)(a.ru_utime.tv_usec + a.ru_stime.tv_usec + b.ru_utime.tv_usec +
                           b.ru_stime.tv_usec);
}

/* ---- how the specimens' values combine ------------------------------------ */

enum { R_SAME, R_MEAN, R_MAX, R_MIN, R_SUM, R_OWN };

typedef struct key_rule {
    const char *key;
    int rule;
} key_rule;

/* Keys not listed are R_SAME (the value of the first specimen with a
 * result: the inputs and the lattice). */
static const key_rule key_rules[] = {
    {"status", R_OWN}, {"t_end_s", R_MAX}, {"dc", R_OWN}, {"nodes", R_OWN},
    {"r_min_m", R_MEAN}, {"r_max_m", R_MEAN}, {"tip_angle_deg", R_MEAN},
    {"bending_length_m", R_MEAN}, {"flexural_rigidity_Nm", R_MEAN},
    {"energy_J_kinetic", R_MEAN}, {"energy_J_stretch", R_MEAN}, {"energy_J_bend", R_MEAN},
    {"energy_J_shear", R_MEAN}, {"energy_J_gravity", R_MEAN}, {"max_strain", R_MAX},
    {"wall_s", R_OWN}, {"steps", R_SUM}, {"rhs_evals", R_SUM}, {"jac_evals", R_SUM},
    {"lin_setups", R_SUM}, {"nonlin_iters", R_SUM}, {"err_test_fails", R_SUM},
    {"conv_fails", R_SUM}, {"max_speed_m_s", R_MAX}, {"iterations", R_SUM},
    {"factorizations", R_SUM}, {"certified", R_OWN}, {"min_pivot_N_m", R_MIN},
    {"omega_min_rad_s", R_MIN}, {"max_force_rel", R_MAX}, {"lin_iters", R_SUM},
    {"lin_factors", R_SUM}, {"mean_speed_m_s", R_MAX}, {"integrator_switches", R_SUM},
    {"cpu_s", R_OWN}, {"dc_sd", R_OWN}, {"dc_ci95", R_OWN}, {"dc_mode", R_OWN},
    {"nodes_hist", R_OWN}, {"specimens", R_OWN}, {"specimens_failed", R_OWN},
    {"seed", R_OWN}, {"energy_total_start_J", R_MEAN}, {"energy_total_end_J", R_MEAN},
    {"energy_max_rise_J", R_MAX}, {"max_strain_peak", R_MAX}, {"energy_rescales", R_SUM},
    {"fall_end_s", R_MAX}, {"fall_steps", R_SUM}, {"energy_gain_J", R_MAX},
    {"fall_redone", R_SUM}, {"fall_refused", R_SUM},
    {"fall_pumped", R_SUM}, {"fall_redo_from_s", R_MIN}, {NULL, 0}};

static int rule_of(const char *key)
{
    for (int i = 0; key_rules[i].key; i++)
        if (strcmp(key_rules[i].key, key) == 0) return key_rules[i].rule;
    return R_SAME;
}

/* ---- one child ------------------------------------------------------------- */

typedef struct child {
    pid_t pid;
    int fd;              /* read end of its pipe */
    int k;               /* specimen index */
    char *buf;           /* what it sent */
    size_t len, cap;
    int done, exit_status;
    int started;         /* launched in this part of the ensemble */
    int stored;          /* its result read back from DIR (--resume) */
    int from_ck;         /* continues from its checkpoint (--resume) */
    double cpu_s;
    drape_cli_result res;
    int have_res;
    double *radii;       /* its shadow outline, n_radii samples */
    int n_radii;
    int shadow_whole;    /* its @shadow line was read whole */
    double cx, cy, thr;
} child;

static volatile sig_atomic_t ens_stop;

/* signals received: a second one stops the specimens at once (SIGKILL),
 * unless drape batch runs this ensemble (DRAPE_SIGNAL_FORWARDED: the
 * ensemble then gets each signal twice, from whoever signalled the
 * process tree and from the batch) */
static volatile sig_atomic_t ens_signals;

static void on_signal(int sig)
{
    ens_stop = sig;
    ens_signals++;
}

/* on_signal for SIGINT and SIGTERM, with sa_flags flags, where the caller
 * (old_int, old_term: their handlers before) did not ignore them */
static void catch_ens_signals(const struct sigaction *old_int, const struct sigaction *old_term,
                              int flags)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sa.sa_flags = flags;
    sigemptyset(&sa.sa_mask);
    if (old_int->sa_handler != SIG_IGN) sigaction(SIGINT, &sa, NULL);
    if (old_term->sa_handler != SIG_IGN) sigaction(SIGTERM, &sa, NULL);
}

/* Start specimen c->k (seed): a new run, or with from_ck the run
 * continued from its checkpoint in its directory.  id: the ensemble's
 * (with --out), stored in its checkpoint.  No specimen prints the
 * loaders' warnings: the input check before the specimens did. */
static int launch(const run_args *a, child *c, unsigned long seed, const char *out_dir,
                  const char *id, int from_ck)
{
    int fd;
    pid_t pid = drape_cli_fork_pipe(&fd);
    if (pid < 0) return -1;
    if (pid == 0) {
        signal(SIGINT, SIG_DFL);
        signal(SIGTERM, SIG_DFL);
        char ctx[96];
        snprintf(ctx, sizeof ctx, "specimen %d (seed %lu): ", c->k + 1, seed);
        drape_cli_set_error_context(ctx);
        run_args ca = *a;
        ca.has_seed = 1;
        ca.seed = seed;
        ca.quiet = 1;
        ca.specimens = 1;
        ca.no_warnings = 1; /* the input check before the specimens printed them */
        ca.ensemble_id = id;
        char dir[4200];
        if (out_dir) {
            snprintf(dir, sizeof dir, "%s/specimen-%03d", out_dir, c->k + 1);
            ca.out_dir = dir;
            if (from_ck) ca.resume_dir = dir; /* its options are stored there */
        }
        FILE *o = fdopen(fd, "w");
        int st = 70;
        if (o) {
            run_child ch = {o};
            st = drape_cli_run_one(&ca, &ch);
            if (fclose(o) != 0 && st == 0) st = 3;
        }
        fflush(stderr);
        _exit(st);
    }
    c->pid = pid;
    c->fd = fd;
    return 0;
}

/* Read everything the child sent (it has exited, so the pipe ends). */
static int drain(child *c)
{
    for (;;) {
        if (c->cap - c->len < 4096) {
            size_t cap = c->cap ? 2 * c->cap : 16384;
            char *b = drape_realloc(c->buf, cap);
            if (!b) return -1;
            c->buf = b;
            c->cap = cap;
        }
        ssize_t r = read(c->fd, c->buf + c->len, c->cap - c->len - 1);
        if (r < 0 && errno == EINTR) continue;
        if (r <= 0) break;
        c->len += (size_t)r;
    }
    if (c->buf) c->buf[c->len] = 0;
    close(c->fd);
    c->fd = -1;
    return 0;
}

/* The next number of the @shadow line at *p (advanced past it and the
 * blank after it); 0, or -1 (drape_cli_result_parse_num). */
static int shadow_num(const char **p, double *v)
{
    if (drape_cli_result_parse_num(*p, p, v) != 0) return -1;
    if (**p == ' ') (*p)++;
    return 0;
}

/* Split the "@shadow" line off and parse both parts: "@shadow\tcx cy n
 * threshold r_1 ... r_n\n", every number whole. */
static void parse_child(child *c)
{
    if (!c->buf) return;
    char *sh = strstr(c->buf, "@shadow\t");
    if (sh) {
        *sh = 0;
        const char *p = sh + 8;
        double cx, cy, nd, thr;
        if (shadow_num(&p, &cx) == 0 && shadow_num(&p, &cy) == 0 && shadow_num(&p, &nd) == 0 &&
            shadow_num(&p, &thr) == 0 && nd > 0 && nd < 100000 && nd == floor(nd) &&
            (c->radii = drape_calloc((size_t)nd, sizeof(double)))) {
            int n = (int)nd, k = 0;
            c->cx = cx;
            c->cy = cy;
            c->thr = thr;
            while (k < n && shadow_num(&p, &c->radii[k]) == 0) k++;
            c->n_radii = k == n ? n : 0;
            /* (the line ends after its last sample: not cut short) */
            c->shadow_whole = c->n_radii > 0 && *p == '\n';
        }
    }
    c->have_res = drape_cli_result_read(c->buf, &c->res) == 0 && c->res.n > 0;
    if (sh) *sh = '@'; /* the text whole again (it may be stored) */
}

/* ---- the ensemble's result ---------------------------------------------------- */

/* The status a specimen reported ("failed" when it reported nothing). */
static const char *spec_status(const child *c)
{
    const drape_cli_field *f =
        c->have_res ? drape_cli_result_find(&c->res, "status") : NULL;
    return f && f->type == DRAPE_CLI_F_STR ? f->text : "failed";
}

/* 1 if the specimen produced a result (equilibrium or t_max). */
static int spec_ok(const child *c)
{
    const char *s = spec_status(c);
    return strcmp(s, "equilibrium") == 0 || strcmp(s, "t_max") == 0;
}

static void combine(drape_cli_result *out, const char *key, const drape_cli_field *proto,
                    child *ch, int n, int rule)
{
    double acc = NAN;
    int cnt = 0;
    for (int k = 0; k < n; k++) {
        if (!spec_ok(&ch[k])) continue;
        double v = drape_cli_result_get(&ch[k].res, key);
        if (!isfinite(v) || (proto->type == DRAPE_CLI_F_INT && v < 0)) continue;
        if (cnt == 0) acc = v;
        else if (rule == R_MEAN || rule == R_SUM) acc += v;
        else if (rule == R_MAX && v > acc) acc = v;
        else if (rule == R_MIN && v < acc) acc = v;
        cnt++;
    }
    if (rule == R_MEAN && cnt > 0) acc /= cnt;
    if (proto->type == DRAPE_CLI_F_INT) drape_cli_result_int(out, key, acc);
    else drape_cli_result_num(out, key, acc);
}

/* What the parent knows of the run itself, for the keys that no specimen
 * reported when none finished (interrupted or all failed). */
typedef struct ens_ident {
    const char *fabric, *scene;
    double spacing_m;
} ens_ident;

static void build_result(drape_cli_result *r, child *ch, int n, const child *first,
                         const drape_ensemble_stats *st, int n_failed, int interrupted,
                         double wall_s, double cpu_prev, unsigned long seed0,
                         drape_cli_specimen *spec, const ens_ident *id,
                         const run_coarse *coarse)
{
    memset(r, 0, sizeof *r);
    int all_eq = 1, n_ok = 0, all_min = 1, any_cert = 0;
    for (int k = 0; k < n; k++) {
        if (!spec_ok(&ch[k])) continue;
        n_ok++;
        if (strcmp(spec_status(&ch[k]), "equilibrium") != 0) all_eq = 0;
        const drape_cli_field *c = drape_cli_result_find(&ch[k].res, "certified");
        if (c && c->type == DRAPE_CLI_F_STR && !c->is_null_text) {
            any_cert = 1;
            if (strcmp(c->text, "minimum") != 0) all_min = 0;
        }
    }
    for (int i = 0; drape_cli_run_keys[i]; i++) {
        const char *key = drape_cli_run_keys[i];
        /* the nested JSON name of energy_J_* */
        char jkey[48];
        if (strncmp(key, "energy_J_", 9) == 0) snprintf(jkey, sizeof jkey, "energy_J.%s", key + 9);
        else snprintf(jkey, sizeof jkey, "%s", key);
        const drape_cli_field *proto =
            first ? drape_cli_result_find(&first->res, key) : NULL;
        int rule = rule_of(key);
        if (strcmp(key, "spacing_coarse_m") == 0) {
            drape_cli_convergence_keys(r, coarse, st); /* and the three after it */
        } else if (strcmp(key, "dc_spacing_delta") == 0 ||
                   strcmp(key, "dc_spacing_delta_ci95") == 0 ||
                   strcmp(key, "nodes_spacing_p") == 0) {
            continue;
        } else if (strcmp(key, "status") == 0) {
            drape_cli_result_str(r, jkey, interrupted ? "interrupted"
                                          : n_ok == 0  ? "failed"
                                          : all_eq     ? "equilibrium"
                                                       : "t_max");
        } else if (strcmp(key, "dc") == 0) {
            drape_cli_result_num(r, jkey, st->dc_mean);
        } else if (strcmp(key, "nodes") == 0) {
            drape_cli_result_int(r, jkey, st->nodes_mode);
        } else if (strcmp(key, "wall_s") == 0) {
            drape_cli_result_num(r, jkey, wall_s);
        } else if (strcmp(key, "certified") == 0) {
            drape_cli_result_str(r, jkey, !any_cert ? NULL : all_min ? "minimum" : "saddle");
        } else if (strcmp(key, "cpu_s") == 0) {
            drape_cli_result_num(r, jkey, drape_cli_cpu_s() + cpu_prev);
        } else if (strcmp(key, "dc_sd") == 0) {
            drape_cli_result_num(r, jkey, st->dc_sd);
        } else if (strcmp(key, "dc_ci95") == 0) {
            drape_cli_result_num(r, jkey, st->dc_ci95);
        } else if (strcmp(key, "dc_mode") == 0) {
            drape_cli_result_num(r, jkey, st->dc_mode);
        } else if (strcmp(key, "nodes_hist") == 0) {
            memcpy(r->hist, st->hist, sizeof r->hist);
            drape_cli_result_hist(r, jkey);
        } else if (strcmp(key, "specimens") == 0) {
            r->spec = spec;
            r->n_spec = n;
            drape_cli_result_specimens(r, jkey);
        } else if (strcmp(key, "specimens_failed") == 0) {
            drape_cli_result_int(r, jkey, n_failed);
        } else if (strcmp(key, "seed") == 0) {
            drape_cli_result_int(r, jkey, (double)seed0);
        } else if (!proto && strcmp(key, "fabric") == 0) {
            drape_cli_result_str(r, jkey, id->fabric);
        } else if (!proto && strcmp(key, "scene") == 0) {
            drape_cli_result_str(r, jkey, id->scene);
        } else if (!proto && strcmp(key, "spacing_m") == 0) {
            drape_cli_result_num(r, jkey, id->spacing_m);
        } else if (!proto) {
            drape_cli_result_num(r, jkey, NAN);
        } else if (rule == R_SAME || proto->type == DRAPE_CLI_F_STR) {
            if (proto->type == DRAPE_CLI_F_STR)
                drape_cli_result_str(r, jkey, proto->is_null_text ? NULL : proto->text);
            else if (proto->type == DRAPE_CLI_F_INT)
                drape_cli_result_int(r, jkey, proto->value);
            else
                drape_cli_result_num(r, jkey, proto->value);
        } else {
            combine(r, jkey, proto, ch, n, rule);
        }
    }
}

int drape_cli_write_shadow(const char *dir, const drape_scene *s,
                           const drape_svg_specimen *sp, int n,
                           const drape_cli_result *r, drape_error *err)
{
    char path[4200], title[512];
    snprintf(path, sizeof path, "%s/shadow.svg", dir);
    const drape_cli_field *fab = drape_cli_result_find(r, "fabric");
    const drape_cli_field *meth = drape_cli_result_find(r, "method");
    snprintf(title, sizeof title, "%s, %s, %s, spacing %g cm",
             fab && fab->type == DRAPE_CLI_F_STR ? fab->text : "",
             drape_scene_kind_name(s->kind),
             meth && meth->type == DRAPE_CLI_F_STR ? meth->text : "", 100.0 * s->spacing);
    drape_svg_scene sc;
    memset(&sc, 0, sizeof sc);
    sc.title = title;
    sc.table = s->kind == DRAPE_SCENE_TABLE;
    sc.specimen_d_m = s->diameter;
    sc.support_d_m = s->support_diameter;
    sc.width_m = s->width;
    sc.height_m = s->height;
    sc.table_round = s->table_shape == DRAPE_TABLE_ROUND;
    sc.table_size_m = s->table_size;
    sc.dc_mean = drape_cli_result_get(r, "dc");
    sc.dc_ci95 = drape_cli_result_get(r, "dc_ci95");
    double nf = drape_cli_result_get(r, "specimens_failed");
    sc.n_failed = isfinite(nf) ? (int)nf : 0;
    sc.hist = r->hist;
    sc.hist_n = DRAPE_ENSEMBLE_MAX_NODES + 1;
    /* drawn once into memory, then written as shadow.svg and rendered
     * into shadow.png; both complete before either is renamed into place */
    char *svg = NULL;
    size_t len = 0;
    FILE *mem = open_memstream(&svg, &len);
    if (!mem) return drape_error_set(err, DRAPE_E_NOMEM, path, 0, 0, NULL, "out of memory");
    int bad = drape_svg_shadow_write(mem, &sc, sp, n) != 0;
    if (fclose(mem) != 0 || bad) {
        free(svg);
        return drape_error_set(err, DRAPE_E_NOMEM, path, 0, 0, NULL, "out of memory");
    }
    int rc = -1;
    drape_cli_afile as, ap;
    int as_open = 0, ap_open = 0;
    if (drape_cli_afile_open(&as, path, err) != 0) goto out;
    as_open = 1;
    if (fwrite(svg, 1, len, as.f) != len || fflush(as.f) != 0) {
        drape_error_set(err, DRAPE_E_IO, path, 0, 0, NULL, "cannot write: %s", strerror(errno));
        goto out;
    }
    snprintf(path, sizeof path, "%s/shadow.png", dir);
    if (drape_cli_afile_open(&ap, path, err) != 0) goto out;
    ap_open = 1;
    if (drape_png_from_svg(svg, len, ap.f, path, err) != 0) goto out;
    as_open = 0;
    if (drape_cli_afile_commit(&as, err) != 0) goto out;
    ap_open = 0;
    if (drape_cli_afile_commit(&ap, err) != 0) goto out;
    rc = 0;
out:
    if (as_open) drape_cli_afile_abort(&as);
    if (ap_open) drape_cli_afile_abort(&ap);
    free(svg);
    return rc;
}

/* ---- the record in DIR (--out) ------------------------------------------------- */

/* 1 if a specimen's result is whole: every key a specimen sends
 * (drape_cli_run_keys but the ensemble's own nodes_hist and specimens),
 * its status a text, and with a DC its shadow's outline.  A result.txt
 * cut short or edited is not (read back, it would count as a failed
 * specimen, or give the ensemble's result nulls). */
static int complete(const child *c)
{
    if (!c->have_res) return 0;
    for (int i = 0; drape_cli_run_keys[i]; i++) {
        const char *key = drape_cli_run_keys[i];
        if (strcmp(key, "nodes_hist") != 0 && strcmp(key, "specimens") != 0 &&
            !drape_cli_result_find(&c->res, key))
            return 0;
    }
    const drape_cli_field *st = drape_cli_result_find(&c->res, "status");
    if (st->type != DRAPE_CLI_F_STR || st->is_null_text) return 0;
    return !isfinite(drape_cli_result_get(&c->res, "dc")) || c->shadow_whole;
}

/* A specimen whose result is kept: it is not run again by --resume (a
 * numerical failure is deterministic; an error without a result, an
 * interruption, are not kept). */
static int spec_done(const child *c)
{
    return complete(c) && (spec_ok(c) || strcmp(spec_status(c), "failed") == 0);
}

/* --resume: the specimens of m read back (c->stored), or marked to
 * continue from their checkpoints (c->from_ck).  Returns how many were
 * read back. */
static int read_back(const ens_record *m, child *ch, int n)
{
    int n_stored = 0;
    for (int k = 0; k < n; k++) {
        child *c = &ch[k];
        int ex = 0;
        double cpu = 0.0;
        char *text = drape_cli_ens_result_load(m, k, &ex, &cpu);
        if (text) {
            c->buf = text;
            c->len = strlen(text);
            c->cap = c->len + 1;
            parse_child(c);
            if (spec_done(c)) {
                c->stored = c->done = 1;
                c->exit_status = ex;
                c->cpu_s = cpu;
                n_stored++;
                continue;
            }
            fprintf(stderr, "drape: %s/specimen-%03d/" ENS_RESULT ": warning: not a result "
                    "that can be used; the specimen runs again\n", m->dir, k + 1);
            drape_free(c->buf);
            drape_free(c->radii);
            c->buf = NULL;
            c->radii = NULL;
            c->len = c->cap = 0;
            c->n_radii = c->have_res = c->shadow_whole = 0;
        }
        c->from_ck = drape_cli_ens_checkpoint(m, k, &c->cpu_s);
    }
    return n_stored;
}

/* The temporaries of DIR's files and of specimens 1..n's result.txt
 * (NAME.tmp.PID, cli_io.h), frames, drape.h5 and drape.xmf (NAME.PID.tmp,
 * drape_cli_run_remove_stale) that a part killed outright left, in DIR
 * (a single run killed there) and in the specimens' directories: removed
 * once DIR is held (no other drape writes there then). */
static void remove_stale(const char *dir, int n)
{
    drape_cli_remove_stale_tmp(dir, DRAPE_ENSEMBLE_MANIFEST, DRAPE_CLI_TMP_PID_LAST);
    drape_cli_remove_stale_tmp(dir, "shadow.svg", DRAPE_CLI_TMP_PID_LAST);
    drape_cli_remove_stale_tmp(dir, "shadow.png", DRAPE_CLI_TMP_PID_LAST);
    drape_cli_run_remove_stale(dir);
    for (int k = 0; k < n; k++) {
        char sd[4200];
        snprintf(sd, sizeof sd, "%s/specimen-%03d", dir, k + 1);
        drape_cli_remove_stale_tmp(sd, ENS_RESULT, DRAPE_CLI_TMP_PID_LAST);
        drape_cli_run_remove_stale(sd);
    }
}

/* ---- driver ------------------------------------------------------------------- */

int drape_cli_specimens_run(const run_args *a)
{
    return drape_cli_specimens_drive(a, NULL);
}

int drape_cli_specimens_drive(const run_args *a, ens_record *rm)
{
    drape_error err;
    drape_error_clear(&err);
    drape_scene s;
    const char *scene_path = a->scene_path;
    const int resuming = rm != NULL;
    /* the scene once here, for N and the seed; each child loads it again
     * (and prints its warnings) */
    if (drape_scene_load_flags(scene_path, a->fabric_path ? DRAPE_SCENE_LOAD_FABRIC_OVERRIDDEN : 0u,
                               &s, &err, NULL, NULL) != 0) {
        drape_cli_print_error(&err);
        return drape_error_exit_status(err.kind);
    }
    int n = a->specimens > 0 ? a->specimens : s.specimens;
    if (n <= 1) return drape_cli_run_one(a, NULL);
    /* the input once, here, as one specimen would check it (the fabric,
     * the options, the lattice and the model): an input error is then
     * reported once, with its own exit status, not by every specimen */
    {
        run_args ca = *a;
        ca.check_only = 1;
        ca.specimens = 1;
        ca.quiet = 1;
        /* the input's warnings once, here, not as a specimen's */
        ca.no_warnings = a->no_warnings || resuming;
        int cst = drape_cli_run_one(&ca, NULL);
        if (cst != 0) return cst;
    }
    const char *fabric_path = a->fabric_path ? a->fabric_path : s.fabric_path;
    /* the fabric's name for a result that no specimen finished (it loaded
     * above, so an error here is out of memory at most) */
    char fabric_name[DRAPE_FABRIC_NAME_MAX] = "";
    {
        drape_fabric *f = drape_malloc(sizeof *f);
        drape_error ferr;
        drape_error_clear(&ferr);
        if (f && drape_fabric_load(fabric_path, f, &ferr, NULL, NULL) == 0)
            memcpy(fabric_name, f->name, sizeof fabric_name);
        drape_free(f);
    }

    unsigned long seed0 = a->has_seed ? a->seed : s.perturb_seed;
    if (seed0 > DRAPE_SCENE_SEED_MAX - (unsigned long)(n - 1)) {
        fprintf(stderr, "drape: run: the seeds of %d specimens from %lu go past "
                DRAPE_SCENE_SEED_MAX_TEXT ": give a smaller --seed\n", n, seed0);
        return drape_error_exit_status(DRAPE_E_USAGE);
    }
    if (a->has_seed) s.perturb_seed = a->seed;
    if (a->spacing > 0) s.spacing = a->spacing;
    int jobs = a->jobs;
    if (jobs <= 0) {
        long ncpu = sysconf(_SC_NPROCESSORS_ONLN);
        jobs = ncpu > 0 ? (int)ncpu : 1;
    }
    if (jobs > n) jobs = n;
    int progress = !a->quiet && isatty(STDERR_FILENO);
    int status = 0, created_dir = 0, n_running = 0, n_done = 0, next = 0;
    int n_stored = 0, n_kept = 0; /* read back; stored in this part */
    double cpu_prev = 0.0, wall_prev = 0.0; /* of the parts before (--resume) */
    ens_record own;
    memset(&own, 0, sizeof own);
    ens_record *m = rm;
    /* the handlers of SIGINT and SIGTERM while the specimens run and the
     * result is written (restored at the end: a signal while the summary
     * is written is held, not a kill that leaves it half done) */
    struct sigaction old_int, old_term;
    int handlers_set = 0;
    child *ch = drape_calloc((size_t)n, sizeof *ch);
    drape_cli_specimen *spec = drape_calloc((size_t)n, sizeof *spec);
    drape_svg_specimen *sv = drape_calloc((size_t)n, sizeof *sv);
    drape_cli_result *r = drape_calloc(1, sizeof *r);
    double *dcs = drape_calloc((size_t)n, sizeof(double));
    int *nodes = drape_calloc((size_t)n, sizeof(int));
    if (!ch || !spec || !sv || !r || !dcs || !nodes) {
        drape_error_set(&err, DRAPE_E_NOMEM, NULL, 0, 0, NULL, "out of memory");
        goto fail;
    }
    for (int k = 0; k < n; k++) {
        ch[k].k = k;
        ch[k].fd = -1;
    }
    if (resuming) {
        if (m->n != n || m->seed0 != seed0) { /* (the manifest sets both) */
            drape_error_set(&err, DRAPE_E_INTERNAL, m->path, 0, 0, NULL,
                            "--resume: %d specimens from seed %lu, the manifest says %d from %lu",
                            n, seed0, m->n, m->seed0);
            goto fail;
        }
        n_done = n_stored = read_back(m, ch, n);
        /* as a finished single run is refused: the result was printed */
        if (n_stored == n && strcmp(m->status, "running") != 0 &&
            strcmp(m->status, "interrupted") != 0) {
            drape_error_set(&err, DRAPE_E_USAGE, m->path, 0, 0, NULL,
                            "--resume: the ensemble ended with status %s and every specimen's "
                            "result is stored: nothing to resume", m->status);
            goto fail;
        }
        /* the time of the parts before; at least that of the specimens
         * kept and of the checkpoints continued (their time so far: a
         * part killed outright did not record its own) */
        double cpu_kept = 0.0;
        for (int k = 0; k < n; k++)
            if ((ch[k].stored || ch[k].from_ck) && ch[k].cpu_s > 0) cpu_kept += ch[k].cpu_s;
        cpu_prev = m->cpu_s > cpu_kept ? m->cpu_s : cpu_kept;
        wall_prev = m->wall_s;
    }
    int held = 0;
    if (a->out_dir && (drape_cli_ensure_dir(a->out_dir, &created_dir, &err) != 0 ||
                       drape_cli_lock_dir(a->out_dir, &held, &err) != 0))
        goto fail;
    if (held) remove_stale(a->out_dir, n);
    if (a->out_dir && !a->no_warnings && !resuming) { /* an earlier, larger ensemble's specimens */
        char sd[4200];
        struct stat sst;
        int k = n + 1;
        for (; k < 1000; k++) {
            snprintf(sd, sizeof sd, "%s/specimen-%03d", a->out_dir, k);
            if (stat(sd, &sst) != 0) break;
        }
        if (k == n + 2)
            fprintf(stderr, "drape: %s: warning: specimen-%03d is of an earlier ensemble "
                    "(this one has %d specimens, and shadow.svg shows only them)\n",
                    a->out_dir, n + 1, n);
        else if (k > n + 2)
            fprintf(stderr, "drape: %s: warning: specimen-%03d to specimen-%03d are of an "
                    "earlier ensemble (this one has %d specimens, and shadow.svg shows only "
                    "them)\n", a->out_dir, n + 1, k - 1, n);
    }
    if (a->out_dir && (s.kind == DRAPE_SCENE_CUSICK || s.kind == DRAPE_SCENE_TABLE) &&
        (drape_cli_check_target(a->out_dir, "shadow.svg", &err) != 0 ||
         drape_cli_check_target(a->out_dir, "shadow.png", &err) != 0))
        goto fail;
    /* a new ensemble's manifest, before any specimen starts (results an
     * earlier ensemble stored here are not this one's) */
    if (a->out_dir && !resuming) {
        if (drape_cli_ens_record_new(&own, a->out_dir, a, fabric_path, n, seed0, &err) != 0)
            goto fail;
        m = &own;
        for (int k = 0; k < n; k++) drape_cli_ens_result_remove(m, k);
        if (drape_cli_ens_record_write(m, &err) != 0) goto fail;
    }

    ens_stop = 0;
    ens_signals = 0;
    const int hard_at = getenv("DRAPE_SIGNAL_FORWARDED") ? 3 : 2;
    sigaction(SIGINT, NULL, &old_int);
    sigaction(SIGTERM, NULL, &old_term);
    /* no SA_RESTART: waitpid below returns EINTR, to pass a signal on */
    catch_ens_signals(&old_int, &old_term, 0);
    handlers_set = 1;

    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    int forwarded = 0, hard = 0;
    for (;;) {
        while (next < n && ch[next].stored) next++;
        if (n_running == 0 && (next >= n || ens_stop)) break;
        while (!ens_stop && next < n && n_running < jobs) {
            child *c = &ch[next];
            if (launch(a, c, seed0 + (unsigned long)next, a->out_dir, m ? m->id : NULL,
                       c->from_ck) != 0) {
                drape_error_set(&err, DRAPE_E_IO, NULL, 0, 0, NULL,
                                "cannot start a process for specimen %d: %s", next + 1,
                                strerror(errno));
                ens_stop = -1;
                break;
            }
            c->started = 1;
            n_running++;
            next++;
            while (next < n && ch[next].stored) next++;
        }
        if (n_running == 0) break;
        if (ens_stop > 0 && !forwarded) {
            /* a signal sent to this process alone (kill PID) reaches the
             * children too; from a terminal they had it already */
            for (int k = 0; k < n; k++)
                if (ch[k].started && !ch[k].done) kill(ch[k].pid, (int)ens_stop);
            forwarded = 1;
        }
        if (ens_signals >= hard_at && !hard) { /* the user's "stop now" */
            for (int k = 0; k < n; k++)
                if (ch[k].started && !ch[k].done) kill(ch[k].pid, SIGKILL);
            hard = 1;
        }
        /* a child's CPU time: what RUSAGE_CHILDREN gains when it is
         * waited for (wait4 is not POSIX) */
        int ws;
        struct rusage ru0, ru;
        getrusage(RUSAGE_CHILDREN, &ru0);
        pid_t pid = waitpid(-1, &ws, 0);
        getrusage(RUSAGE_CHILDREN, &ru);
        if (pid < 0) {
            if (errno == EINTR) continue;
            break;
        }
        for (int k = 0; k < n; k++) {
            child *c = &ch[k];
            if (!c->started || c->pid != pid || c->done) continue;
            c->done = 1;
            c->exit_status = WIFEXITED(ws) ? WEXITSTATUS(ws) : 128 + WTERMSIG(ws);
            /* (a continued specimen: its time before, from its checkpoint) */
            c->cpu_s += (double)(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec -
                                 ru0.ru_utime.tv_sec - ru0.ru_stime.tv_sec) +
                        1e-6 * (double)(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec -
                                        ru0.ru_utime.tv_usec - ru0.ru_stime.tv_usec);
            if (drain(c) != 0) {
                drape_error_set(&err, DRAPE_E_NOMEM, NULL, 0, 0, NULL, "out of memory");
                ens_stop = -1;
            }
            parse_child(c);
            if (c->exit_status == 0 && !c->have_res)
                fprintf(stderr, "drape: specimen %d (seed %lu): its result could not be read "
                        "(internal error)\n", k + 1, seed0 + (unsigned long)k);
            /* kept for --resume as it comes in; a result that cannot be
             * stored only costs that specimen's run again */
            if (m && spec_done(c)) {
                drape_error se;
                drape_error_clear(&se);
                if (drape_cli_ens_result_store(m, k, c->exit_status, c->cpu_s, c->buf, c->len,
                                               &se) == 0)
                    n_kept++;
                else
                    drape_cli_print_error(&se);
            }
            n_running--;
            n_done++;
            if (progress) {
                /* what is left, at this part's pace so far */
                struct timespec tn;
                clock_gettime(CLOCK_MONOTONIC, &tn);
                double el = (double)(tn.tv_sec - t0.tv_sec) + 1e-9 * (double)(tn.tv_nsec - t0.tv_nsec);
                int left = n - n_done, ran = n_done - n_stored; /* ran >= 1 here */
                fprintf(stderr, "\rdrape: specimen %d of %d done (seed %lu: %s), %d running, %d left",
                        n_done, n, seed0 + (unsigned long)k, spec_status(c), n_running, left);
                if (left > 0 && ran > 0) fprintf(stderr, ", about %.0f s to go ", el * left / ran);
                else fputc(' ', stderr);
            }
        }
    }
    if (progress) fputc('\n', stderr);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    /* what stopped the specimens, if anything: a signal from here on (while
     * the result is written, the handlers still set) changes nothing */
    const int stop_sig = (int)ens_stop;
    /* and a write of the result that such a signal interrupts goes on
     * (SA_RESTART: a blocked write to a full pipe returned EINTR, "cannot
     * write the result") */
    catch_ens_signals(&old_int, &old_term, SA_RESTART);
    if (stop_sig < 0) goto fail;

    /* interrupted: a specimen is (not started, or stopped by the signal);
     * a signal that came after every specimen finished (before the last
     * was reaped) interrupted nothing */
    int n_failed = 0, n_ok = 0, interrupted = 0;
    const child *first = NULL;
    for (int k = 0; k < n; k++) {
        child *c = &ch[k];
        drape_cli_specimen *p = &spec[k];
        int ran = c->started || c->stored;
        p->seed = seed0 + (unsigned long)k;
        /* not started, or stopped by the signal before it reported */
        const char *stx = !ran || (stop_sig > 0 && !c->have_res && c->exit_status >= 128)
                              ? "interrupted" : spec_status(c);
        snprintf(p->status, sizeof p->status, "%.15s", stx);
        int ok = ran && spec_ok(c);
        if (strcmp(p->status, "interrupted") == 0) interrupted = 1;
        if (!ok && strcmp(p->status, "interrupted") != 0) {
            n_failed++;
            snprintf(p->status, sizeof p->status, "failed");
        }
        p->dc = ok ? drape_cli_result_get(&c->res, "dc") : NAN;
        double nd = ok ? drape_cli_result_get(&c->res, "nodes") : NAN;
        p->nodes = isfinite(nd) ? (int)nd : -1;
        p->r_min_m = ok ? drape_cli_result_get(&c->res, "r_min_m") : NAN;
        p->r_max_m = ok ? drape_cli_result_get(&c->res, "r_max_m") : NAN;
        p->cpu_s = ran ? c->cpu_s : NAN;
        dcs[k] = p->dc;
        nodes[k] = p->nodes;
        if (ok && !first) first = c;
        n_ok += ok;
        sv[k] = (drape_svg_specimen){p->seed, p->dc, p->nodes, c->cx, c->cy,
                                     ok ? c->radii : NULL, ok ? c->n_radii : 0, c->thr,
                                     p->seed_unknown};
    }
    /* the inputs (integrator, lattice, options) from any specimen that
     * reported, also when none succeeded (failed, interrupted) */
    const child *proto = first;
    for (int k = 0; !proto && k < n; k++)
        if (ch[k].have_res) proto = &ch[k];
    drape_ensemble_stats st;
    drape_ensemble_stats_compute(dcs, nodes, n, &st);
    /* every specimen failed in the same way that is not numerical (an
     * output directory it cannot write, no memory): that error, its exit
     * status and no result, as for one specimen (and no record: there is
     * nothing to resume) */
    if (n_failed == n && !interrupted) {
        int common = ch[0].exit_status;
        for (int k = 1; k < n; k++)
            if (ch[k].exit_status != common) common = -1;
        if (common > 0 && common < 128 && common != drape_error_exit_status(DRAPE_E_NUMERIC)) {
            fprintf(stderr, "drape: every specimen failed (exit status %d)\n", common);
            status = common;
            if (m && !resuming && n_kept == 0) unlink(m->path);
            if (created_dir) rmdir(a->out_dir); /* only if empty */
            goto out;
        }
    }
    double wall = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    ens_ident id = {fabric_name[0] ? fabric_name : NULL, drape_scene_kind_name(s.kind),
                    s.spacing};
    build_result(r, ch, n, proto, &st, n_failed, interrupted, wall + wall_prev, cpu_prev,
                 seed0, spec, &id, a->coarse);
    if (!drape_cli_result_check_keys(r)) {
        drape_error_set(&err, DRAPE_E_INTERNAL, NULL, 0, 0, NULL,
                        "ensemble result fields differ from drape_cli_run_keys");
        goto fail;
    }
    if (a->out_dir && first && !interrupted &&
        (s.kind == DRAPE_SCENE_CUSICK || s.kind == DRAPE_SCENE_TABLE) &&
        drape_cli_write_shadow(a->out_dir, &s, sv, n, r, &err) != 0)
        goto fail;
    if (a->csv) drape_cli_result_print_csv(stdout, r);
    else if (a->text) drape_cli_result_print_text(stdout, r);
    else if (drape_cli_result_print_json(stdout, r) != 0) {
        drape_error_set(&err, DRAPE_E_NOMEM, NULL, 0, 0, NULL, "out of memory");
        goto fail;
    }
    /* ferror too: a write that failed inside fprintf (the specimens array
     * passes the stream's buffer) left nothing for fflush to fail on */
    if (fflush(stdout) != 0 || ferror(stdout)) {
        drape_error_set(&err, DRAPE_E_IO, "<stdout>", 0, 0, NULL, "cannot write the result");
        goto fail;
    }
    /* the end of this part in the manifest: its status (a finished
     * ensemble is not resumed), the time of every part so far */
    if (m) {
        const drape_cli_field *sf = drape_cli_result_find(r, "status");
        drape_error me;
        drape_error_clear(&me);
        if (drape_cli_ens_record_end(m, sf && sf->type == DRAPE_CLI_F_STR ? sf->text : "failed",
                                     drape_cli_result_get(r, "cpu_s"), wall + wall_prev,
                                     &me) != 0)
            drape_cli_print_error(&me);
    }
    if (interrupted) {
        int sig = stop_sig > 0 ? stop_sig : SIGINT;
        if (a->out_dir)
            fprintf(stderr, "drape: interrupted by %s with %d of %d specimens finished; "
                    "continue with `drape run --resume %s`\n",
                    sig == SIGTERM ? "SIGTERM" : "SIGINT", n_ok, n, a->out_dir);
        else
            fprintf(stderr, "drape: interrupted by %s with %d of %d specimens finished (an "
                    "ensemble without --out DIR is not resumable: run it again)\n",
                    sig == SIGTERM ? "SIGTERM" : "SIGINT", n_ok, n);
        status = 128 + sig;
    } else if (n_failed == n) { /* (a hang or cantilever has no DC: st.n is 0) */
        fprintf(stderr, "drape: every specimen failed\n");
        status = drape_error_exit_status(DRAPE_E_NUMERIC);
        if (created_dir) rmdir(a->out_dir); /* only if empty */
    } else if (n_failed) {
        fprintf(stderr, "drape: warning: %d of %d specimens failed; the statistics use the "
                "other %d\n", n_failed, n, n_ok);
    }
    goto out;
fail:
    drape_cli_print_error(&err);
    status = drape_error_exit_status(err.kind);
    for (int k = 0; ch && k < n; k++)
        if (ch[k].started && !ch[k].done) kill(ch[k].pid, SIGTERM);
    while (n_running > 0 && wait(NULL) > 0) n_running--;
    /* a new ensemble that kept nothing leaves no manifest */
    if (m && !resuming && n_kept == 0) unlink(m->path);
    if (created_dir) rmdir(a->out_dir); /* only if empty */
out:
    if (handlers_set) {
        sigaction(SIGINT, &old_int, NULL);
        sigaction(SIGTERM, &old_term, NULL);
    }
    for (int k = 0; ch && k < n; k++) {
        if (ch[k].fd >= 0) close(ch[k].fd);
        drape_free(ch[k].buf);
        drape_free(ch[k].radii);
    }
    drape_cli_ens_record_free(&own);
    drape_free(ch);
    drape_free(spec);
    drape_free(sv);
    drape_free(r);
    drape_free(dcs);
    drape_free(nodes);
    return status;
}
