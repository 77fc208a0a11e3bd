/* cli_bench_point.c: one point of `drape bench` (cli_bench.c): a run in a
 * forked child, so that a slow point can be stopped at --max-wall
 * (SIGKILL; recorded as `timeout`) and an allocation failure (gsl-msbdf's
 * dense matrices) ends only that point.  The child inherits the model and
 * the reference samples, integrates with drape_sim_run (observer at the
 * sample times), computes its errors against the reference and its DC,
 * and writes one fixed-size record (plus the samples, for the reference)
 * into a pipe. */
#include <errno.h>
#include <math.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "cli_bench.h"
#include "cli_io.h"
#include "drape/alloc.h"
#include "drape/drape.h"
#include "drape/sim.h"
#include "drape/units.h"

static double mono_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Split a comma-separated list in place: up to max items. -1 if too many
 * or an item is empty. */
/* ---- errors against the reference ------------------------------------------ */

/* Positions of sample k (1..K) in a K x 3n array. */
static const double *sample_at(const bench *b, const double *xs, int k)
{
    return xs + (size_t)(k - 1) * b->n3;
}

static void compute_errors(const bench *b, const double *xs, const double *v_end,
                           bench_point *p)
{
    const drape_lattice *L = b->L;
    double emax = 0.0, erms = 0.0, efin = 0.0, evfin = 0.0;
    for (int k = 1; k <= b->samples; k++) {
        const double *a = sample_at(b, xs, k), *r = sample_at(b, b->ref_x, k);
        double mx = 0.0, ss = 0.0;
        for (int i = 0; i < L->n; i++) {
            double dx = a[3 * i] - r[3 * i], dy = a[3 * i + 1] - r[3 * i + 1],
                   dz = a[3 * i + 2] - r[3 * i + 2];
            double d2 = dx * dx + dy * dy + dz * dz;
            ss += d2;
            if (d2 > mx) mx = d2;
        }
        mx = sqrt(mx);
        double rms = L->n > 0 ? sqrt(ss / L->n) : 0.0;
        if (mx > emax) emax = mx;
        if (rms > erms) erms = rms;
        if (k == b->samples) efin = mx;
    }
    for (int i = 0; i < L->n; i++) {
        double dx = v_end[3 * i] - b->ref_v[3 * i], dy = v_end[3 * i + 1] - b->ref_v[3 * i + 1],
               dz = v_end[3 * i + 2] - b->ref_v[3 * i + 2];
        double d = sqrt(dx * dx + dy * dy + dz * dz);
        if (d > evfin) evfin = d;
    }
    p->err_pos = emax / b->size;
    p->err_pos_rms = erms / b->size;
    p->err_final = efin / b->size;
    p->err_final_v = evfin / sqrt(DRAPE_G_STANDARD * b->size);
}

/* ---- one run, in a child ------------------------------------------------------ */

typedef struct sample_ctx {
    const bench *b;
    double dt;
    double *xs;   /* K x 3n */
    int got;      /* samples stored */
} sample_ctx;

static int sample_observer(void *ctx, const drape_sim_event *ev, drape_error *err)
{
    (void)err;
    sample_ctx *c = ctx;
    if (!(ev->what & DRAPE_SIM_AT_FRAME)) return 0;
    long k = lround(ev->t / c->dt);
    if (k < 1 || k > c->b->samples) return 0;
    memcpy(c->xs + (size_t)(k - 1) * c->b->n3, ev->x, sizeof(double) * c->b->n3);
    c->got++;
    return 0;
}

static int write_all(int fd, const void *buf, size_t n)
{
    const char *p = buf;
    while (n > 0) {
        ssize_t w = write(fd, p, n);
        if (w < 0) {
            if (errno == EINTR) continue;
            return -1;
        }
        p += w;
        n -= (size_t)w;
    }
    return 0;
}

static void point_error(bench_point *p, const drape_error *e)
{
    char buf[sizeof p->msg];
    p->status = PT_FAILED;
    p->err_kind = e->kind;
    snprintf(p->msg, sizeof p->msg, "%s", drape_error_format(e, buf, sizeof buf));
}

/* The child's work: integrate, measure, write the record (and, with
 * want_samples, the K samples and the final velocities) to fd. */
static void child_run(const bench *b, const char *integrator, double rtol,
                      int want_samples, int fd)
{
    bench_point p;
    memset(&p, 0, sizeof p);
    p.status = PT_OK;
    p.nodes = -1;
    p.err_pos = p.err_pos_rms = p.err_final = p.err_final_v = p.dc = NAN;
    snprintf(p.integrator, sizeof p.integrator, "%s", integrator);
    int animate = strcmp(integrator, "animate") == 0;
    p.rtol = animate ? NAN : rtol;
    p.atol = animate ? NAN : rtol * b->atol_scale;
    p.step = animate ? b->anim_step : NAN;
    p.repeats = 1;
    drape_error err;
    drape_error_clear(&err);
    drape_sim_result r;
    memset(&r, 0, sizeof r);
    sample_ctx sc = {b, b->t_end / b->samples, NULL, 0};
    sc.xs = drape_malloc(sizeof(double) * b->n3 * (size_t)b->samples);
    if (!sc.xs) {
        drape_error_set(&err, DRAPE_E_NOMEM, NULL, 0, 0, NULL, "out of memory for the samples");
        point_error(&p, &err);
        goto send;
    }
    drape_sim_opts so;
    drape_sim_opts_from_scene(&b->s, &so);
    snprintf(so.integrator, sizeof so.integrator, "%s", integrator);
    if (animate) {
        so.fixed_step = b->anim_step; /* no tolerances */
    } else {
        so.rtol = rtol;
        so.atol = p.atol;
    }
    so.t_max = b->t_end;
    so.has_equilibrium = 0;
    so.frame_every = sc.dt;
    so.linsol = b->linsol;
    so.observe_progress = 0;
    double c0 = drape_cli_bench_cpu_now();
    int rc = drape_sim_run(b->m, &so, sample_observer, &sc, &r, &err);
    p.cpu_s = drape_cli_bench_cpu_now() - c0;
    p.wall_s = r.wall_s;
    p.stats = r.stats;
    if (r.integrator[0]) snprintf(p.integrator, sizeof p.integrator, "%s", r.integrator);
    if (rc != 0) {
        point_error(&p, &err);
        goto send;
    }
    if (sc.got != b->samples) {
        drape_error_set(&err, DRAPE_E_INTERNAL, NULL, 0, 0, NULL,
                        "bench: %d of %d sample times seen", sc.got, b->samples);
        point_error(&p, &err);
        goto send;
    }
    if (b->ref_x) compute_errors(b, sc.xs, r.v, &p);
    if (b->has_dc) {
        drape_shadow sh;
        drape_error e2;
        drape_error_clear(&e2);
        if (drape_shadow_measure(b->L, r.x, &sh, &e2) == 0) {
            p.dc = sh.dc;
            p.nodes = sh.nodes;
        } else {
            snprintf(p.msg, sizeof p.msg, "DC: %s", e2.msg);
        }
    }
send:
    if (write_all(fd, &p, sizeof p) == 0 && want_samples && p.status == PT_OK) {
        if (write_all(fd, sc.xs, sizeof(double) * b->n3 * (size_t)b->samples) == 0)
            write_all(fd, r.v, sizeof(double) * b->n3);
    }
    drape_free(sc.xs);
    drape_sim_result_free(&r);
}

/* Read n bytes from fd before the deadline (monotonic s; <= 0: none).
 * 0 done, 1 timeout, -1 end of file or error. */
static int read_until(int fd, void *buf, size_t n, double deadline)
{
    char *p = buf;
    while (n > 0) {
        int ms = -1;
        if (deadline > 0) {
            double left = deadline - mono_now();
            if (left <= 0) return 1;
            ms = left > 1e6 ? 1000000000 : (int)ceil(left * 1000.0);
        }
        struct pollfd pf = {fd, POLLIN, 0};
        int pr = poll(&pf, 1, ms);
        if (pr < 0) {
            if (errno == EINTR) continue;
            return -1;
        }
        if (pr == 0) return 1;
        ssize_t got = read(fd, p, n);
        if (got < 0) {
            if (errno == EINTR) continue;
            return -1;
        }
        if (got == 0) return -1;
        p += got;
        n -= (size_t)got;
    }
    return 0;
}

/* Run one point in a child with a wall-time limit (0 = none).  With xs/v
 * non-NULL, receive the samples too.  Returns 0, or -1 if the child could
 * not be started (err set). */
int drape_cli_bench_point(const bench *b, const char *integrator, double rtol, double limit,
                     double *xs, double *v, bench_point *p, drape_error *err)
{
    int fd;
    pid_t pid = drape_cli_fork_pipe(&fd);
    if (pid < 0)
        return drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL, "pipe or fork: %s",
                               strerror(errno));
    if (pid == 0) {
        child_run(b, integrator, rtol, xs != NULL, fd);
        close(fd);
        _exit(0);
    }
    double deadline = limit > 0 ? mono_now() + limit : 0.0;
    int rr = read_until(fd, p, sizeof *p, deadline);
    if (rr == 0 && p->status == PT_OK && xs) {
        rr = read_until(fd, xs, sizeof(double) * b->n3 * (size_t)b->samples, deadline);
        if (rr == 0) rr = read_until(fd, v, sizeof(double) * b->n3, deadline);
    }
    close(fd);
    /* a point whose own wall time is over the limit is a timeout too: a
     * run faster than the scheduler can finish in the child before the
     * parent starts its clock (seen with --max-wall 1e-6 on a loaded
     * machine) */
    if (rr == 0 && limit > 0 && p->status == PT_OK && !(p->wall_s <= limit)) rr = 1;
    if (rr == 1) kill(pid, SIGKILL);
    int wst = 0;
    while (waitpid(pid, &wst, 0) < 0 && errno == EINTR) {}
    if (rr != 0) {
        memset(p, 0, sizeof *p);
        snprintf(p->integrator, sizeof p->integrator, "%s", integrator);
        int animate = strcmp(integrator, "animate") == 0;
        p->rtol = animate ? NAN : rtol;
        p->atol = animate ? NAN : rtol * b->atol_scale;
        p->step = animate ? b->anim_step : NAN;
        p->nodes = -1;
        p->err_pos = p->err_pos_rms = p->err_final = p->err_final_v = p->dc = NAN;
        p->wall_s = p->cpu_s = NAN;
        p->stats.steps = p->stats.rhs_evals = p->stats.jac_evals = -1;
        p->stats.lin_setups = p->stats.lin_factors = p->stats.nonlin_iters = -1;
        p->stats.err_test_fails = p->stats.conv_fails = -1;
        if (rr == 1) {
            p->status = PT_TIMEOUT;
            p->wall_s = limit;
            snprintf(p->msg, sizeof p->msg, "stopped after %g s of wall time (--max-wall)", limit);
        } else {
            p->status = PT_FAILED;
            p->err_kind = DRAPE_E_INTERNAL;
            if (WIFSIGNALED(wst))
                snprintf(p->msg, sizeof p->msg, "the run was killed by signal %d%s",
                         WTERMSIG(wst), WTERMSIG(wst) == SIGKILL ? " (out of memory?)" : "");
            else
                snprintf(p->msg, sizeof p->msg, "the run ended without a result");
        }
    }
    return 0;
}
