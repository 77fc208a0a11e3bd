/* cli_bench_kernels.c: `drape bench --kernels` (docs/performance.md): the
 * CPU cost of one force evaluation, one K and D, one first-order J, one
 * CHOLMOD factorisation of S = M - gamma D - gamma^2 K and one solve with
 * it, on square lattices of a scene, at a fixed state off the flat one.
 * The work-precision sweep is in cli_bench.c. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "cli_bench.h"
#include "cli_io.h"
#include "drape/alloc.h"
#include "drape/lattice.h"
#include "drape/linsol_schur.h"
#include "drape/model.h"

#define BENCH_KERNEL_MIN_BATCH_S 0.05 /* s of CPU per timed batch */
#define BENCH_KERNEL_BATCHES 5
#define BENCH_KERNEL_GAMMA 1e-4       /* s, gamma of the timed Schur factorisation */

static const char *const kernel_columns[] = {
    "side", "particles", "free_particles", "nnz_K", "rhs_ms", "jac_ms",
    "jac_first_order_ms", "schur_factor_ms", "rhs_us_per_free", "jac_us_per_free",
    "schur_solve_ms", NULL};

enum { K_RHS, K_JAC, K_JAC1, K_SCHUR, K_SOLVE, K_COUNT };

typedef struct kernel_ctx {
    drape_model *m;
    const double *x, *v;
    double *f, *K, *D, *J;
    drape_schur *schur;
    const double *r; /* 6 nf: right-hand side of the Newton system */
    double *z;       /* 6 nf: its solution */
} kernel_ctx;

static int kernel_call(kernel_ctx *c, int which, drape_error *err)
{
    switch (which) {
    case K_RHS: return drape_model_forces(c->m, DRAPE_PART_ALL, c->x, c->v, c->f);
    case K_JAC: return drape_model_jacobian(c->m, DRAPE_PART_ALL, c->x, c->v, c->K, c->D);
    case K_JAC1:
        return drape_model_jacobian_first_order(c->m, DRAPE_PART_ALL, 1, c->x, c->v, c->J);
    case K_SCHUR: return drape_schur_factor(c->schur, c->K, c->D, BENCH_KERNEL_GAMMA, err);
    default: return drape_schur_solve(c->schur, c->K, BENCH_KERNEL_GAMMA, c->r, c->z);
    }
}

/* CPU seconds per call: minimum over BENCH_KERNEL_BATCHES batches of at
 * least BENCH_KERNEL_MIN_BATCH_S each (after one warm-up call). */
static double kernel_time(kernel_ctx *c, int which, drape_error *err)
{
    if (kernel_call(c, which, err) != 0) return NAN;
    double best = INFINITY;
    for (int bt = 0; bt < BENCH_KERNEL_BATCHES; bt++) {
        long calls = 0;
        double t0 = drape_cli_bench_cpu_now(), t;
        do {
            if (kernel_call(c, which, err) != 0) return NAN;
            calls++;
            t = drape_cli_bench_cpu_now() - t0;
        } while (t < BENCH_KERNEL_MIN_BATCH_S);
        if (t / (double)calls < best) best = t / (double)calls;
    }
    return best;
}

static int kernels_one(const drape_scene *s0, const drape_fabric *f, int side, FILE *o,
                       int progress_on, drape_error *err)
{
    drape_scene s = *s0;
    drape_lattice *L = NULL;
    drape_model *m = NULL;
    drape_schur *schur = NULL;
    double *x = NULL, *v = NULL, *fv = NULL, *K = NULL, *D = NULL, *J = NULL, *im = NULL;
    double *r = NULL, *z = NULL;
    int rc = -1;
    s.shape = DRAPE_SHAPE_RECTANGLE;
    s.width = s.height = (side - 1) * s.spacing;
    if (drape_scene_check_with_fabric(&s, f, err) != 0) goto out;
    L = drape_lattice_new(&s, f, err);
    if (!L) goto out;
    drape_model_opts mo;
    drape_model_opts_from_scene(&s, &mo);
    m = drape_model_new(L, f, &mo, err);
    if (!m) goto out;
    size_t n3 = 3 * (size_t)L->n;
    const drape_pattern *P = drape_model_pattern(m);
    const drape_pattern *P1 = drape_model_pattern_first_order(m);
    x = drape_malloc(sizeof(double) * n3);
    v = drape_malloc(sizeof(double) * n3);
    fv = drape_malloc(sizeof(double) * n3);
    K = drape_malloc(sizeof(double) * (size_t)(P->nnz ? P->nnz : 1));
    D = drape_malloc(sizeof(double) * (size_t)(P->nnz ? P->nnz : 1));
    J = drape_malloc(sizeof(double) * (size_t)(P1->nnz ? P1->nnz : 1));
    im = drape_malloc(sizeof(double) * (size_t)(L->n_free ? L->n_free : 1));
    size_t n6 = 6 * (size_t)(L->n_free ? L->n_free : 1);
    r = drape_malloc(sizeof(double) * n6);
    z = drape_malloc(sizeof(double) * n6);
    if (!x || !v || !fv || !K || !D || !J || !im || !r || !z) {
        drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL, "out of memory");
        goto out;
    }
    /* a deterministic state off the flat rest state: smooth waves of 2 % of
     * the spacing in z and 0.5 % in-plane, small velocities */
    for (int i = 0; i < L->n; i++) {
        double gi = L->gi[i], gj = L->gj[i];
        double a = 0.02 * s.spacing, w = 0.5 * sin(0.37 * gi + 0.11) * cos(0.23 * gj + 0.7);
        x[3 * i] = L->xinit[3 * i] + 0.25 * a * sin(0.51 * gj + 0.3);
        x[3 * i + 1] = L->xinit[3 * i + 1] + 0.25 * a * cos(0.43 * gi);
        x[3 * i + 2] = L->xinit[3 * i + 2] + a * w;
        v[3 * i] = 1e-3 * w;
        v[3 * i + 1] = -1e-3 * w;
        v[3 * i + 2] = 1e-2 * w;
        if (L->free_id[i] >= 0) im[L->free_id[i]] = 1.0 / L->mass[i];
    }
    for (size_t k = 0; k < n6; k++) r[k] = 1e-6 * sin(0.7 * (double)k + 0.2);
    schur = drape_schur_new(P, im, err);
    if (!schur) goto out;
    kernel_ctx c = {m, x, v, fv, K, D, J, schur, r, z};
    double t[K_COUNT];
    for (int k = 0; k < K_COUNT; k++) {
        if (k == K_SCHUR && kernel_call(&c, K_JAC, err) != 0) {
            drape_error_set(err, DRAPE_E_NUMERIC, NULL, 0, 0, NULL, "Jacobian failed");
            goto out;
        }
        t[k] = kernel_time(&c, k, err);
        if (!isfinite(t[k])) {
            drape_error_set(err, DRAPE_E_NUMERIC, NULL, 0, 0, NULL,
                            "kernel %d failed on the %d x %d lattice", k, side, side);
            goto out;
        }
    }
    fprintf(o, "%d,%d,%d,%ld,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g\n", side, L->n, L->n_free,
            (long)P->nnz, 1e3 * t[K_RHS], 1e3 * t[K_JAC], 1e3 * t[K_JAC1], 1e3 * t[K_SCHUR],
            1e6 * t[K_RHS] / L->n_free, 1e6 * t[K_JAC] / L->n_free, 1e3 * t[K_SOLVE]);
    if (progress_on)
        fprintf(stderr, "drape: bench kernels %d x %d: rhs %.3g ms, jac %.3g ms, schur %.3g ms, "
                "solve %.3g ms\n", side, side, 1e3 * t[K_RHS], 1e3 * t[K_JAC], 1e3 * t[K_SCHUR],
                1e3 * t[K_SOLVE]);
    rc = 0;
out:
    drape_schur_free(schur);
    drape_free(x);
    drape_free(v);
    drape_free(fv);
    drape_free(K);
    drape_free(D);
    drape_free(J);
    drape_free(im);
    drape_free(r);
    drape_free(z);
    drape_model_free(m);
    drape_lattice_free(L);
    return rc;
}

int drape_cli_bench_kernels(const drape_scene *s, const drape_fabric *f, const int *sizes,
                            int n_sizes, const char *out_dir, const char *name, int progress_on,
                            drape_error *err)
{
    drape_cli_afile a;
    FILE *o = stdout;
    char path[4096];
    if (out_dir) {
        if (drape_cli_ensure_dir(out_dir, NULL, err) != 0) return -1;
        snprintf(path, sizeof path, "%s/%s.csv", out_dir, name ? name : "kernels");
        if (drape_cli_afile_open(&a, path, err) != 0) return -1;
        o = a.f;
    }
    drape_cli_bench_header(o, kernel_columns);
    for (int i = 0; i < n_sizes; i++) {
        if (kernels_one(s, f, sizes[i], o, progress_on, err) != 0) {
            if (out_dir) drape_cli_afile_abort(&a);
            return -1;
        }
        if (!out_dir) fflush(stdout);
    }
    if (out_dir) return drape_cli_afile_commit(&a, err);
    if (fflush(stdout) != 0)
        return drape_error_set(err, DRAPE_E_IO, "<stdout>", 0, 0, NULL, "cannot write the CSV");
    return 0;
}
