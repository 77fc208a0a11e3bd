/* lattice-turn: is a fold state of the Cusick test as good with its folds
 * turned? (docs/convergence.md, "Where the nodes sit")
 *
 * usage: lattice-turn SCENE FABRIC SEED SOURCE_SPACING_M SPACING_M...
 *
 * One specimen (SEED) falls to rest by the fall method at SOURCE_SPACING_M.
 * Its rest state, a displacement field of the specimen (bilinear between
 * the particles, renormalised over the kept corners at the free edge),
 * is then put on the lattice of each SPACING_M as it is, turned by 10
 * degrees and turned by 45 degrees about the support's axis, and each is
 * relaxed by the static solver.  For a fabric that is isotropic (the
 * study fabric isotropic-plate) the continuum has the turned states as
 * rest states of the same energy; on the lattice they need not be.
 * Printed per spacing and turn: the rest energy, the phase of the rim's
 * four-fold component (0: crests on the lattice axes, 45: on the
 * diagonals) and its amplitude (relative to the mean radius), whether the
 * solver certified a minimum.  The 10-degree turn is the control: it
 * puts the same interpolation error into the state as 45 degrees does. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "drape/equilibrium.h"
#include "drape/fabric.h"
#include "drape/lattice.h"
#include "drape/model.h"
#include "drape/scene.h"

#define PI 3.14159265358979323846

/* the phase (deg in [0, 90)) of the cos 4 theta component of the rim's
 * horizontal radius, and its amplitude relative to the mean */
static void fold_phase(const drape_lattice *L, const double *x, double R, double *ph, double *amp)
{
    enum { NB = 72 };
    double sum[NB] = {0}; int cnt[NB] = {0};
    for (int i = 0; i < L->n; i++) {
        double r0 = hypot(L->x0[3*i], L->x0[3*i+1]);
        if (r0 < R - 1.5 * L->sigma) continue;
        double th = atan2(L->x0[3*i+1], L->x0[3*i]);
        int b = (int)floor((th + PI) / (2 * PI) * NB) % NB;
        sum[b] += hypot(x[3*i], x[3*i+1]) / r0; cnt[b]++;
    }
    double c = 0, s = 0, m = 0; int n = 0;
    for (int b = 0; b < NB; b++) {
        if (!cnt[b]) continue;
        double th = -PI + (b + 0.5) * 2 * PI / NB, r = sum[b] / cnt[b];
        c += r * cos(4*th); s += r * sin(4*th); m += r; n++;
    }
    *ph = fmod(atan2(s, c) / 4 * 180 / PI + 90, 90);
    *amp = 2 * hypot(c, s) / m;
}

static int grid(const drape_lattice *L, int i, int j)
{
    if (i < 0 || j < 0 || i >= L->ni || j >= L->nj) return -1;
    return L->grid[j * L->ni + i];
}

/* displacement X(u) - u at material point (u, v), bilinear over the kept
 * corners of its cell (weights renormalised where corners are missing) */
static void disp_at(const drape_lattice *L, const double *X, double u, double v, double *d)
{
    int m = (L->ni - 1) / 2;
    double fi = u / L->sigma + m, fj = v / L->sigma + m;
    int i0 = (int)floor(fi), j0 = (int)floor(fj);
    double a = fi - i0, b = fj - j0, wsum = 0;
    d[0] = d[1] = d[2] = 0;
    for (int di = 0; di < 2; di++)
        for (int dj = 0; dj < 2; dj++) {
            int p = grid(L, i0 + di, j0 + dj);
            if (p < 0) continue;
            double w = (di ? a : 1 - a) * (dj ? b : 1 - b) + 1e-12;
            for (int k = 0; k < 3; k++) d[k] += w * (X[3*p+k] - L->x0[3*p+k]);
            wsum += w;
        }
    if (wsum > 0) { for (int k = 0; k < 3; k++) d[k] /= wsum; return; }
    /* nearest particle */
    double best = 1e9; int bp = 0;
    for (int p = 0; p < L->n; p++) {
        double dd = hypot(L->x0[3*p] - u, L->x0[3*p+1] - v);
        if (dd < best) { best = dd; bp = p; }
    }
    for (int k = 0; k < 3; k++) d[k] = X[3*bp+k] - L->x0[3*bp+k];
}

static void opts(const drape_scene *sc, const drape_fabric *f, drape_equilibrium_opts *eo, int fall)
{
    drape_equilibrium_opts_from_fabric(eo, f);
    eo->eig_iters = 0;
    if (!fall) { eo->max_iters = DRAPE_FALL_MAX_ITERS; return; }
    double T, h, Tf, hf;
    drape_scene_fall_params(sc, &T, &h);
    drape_scene_fall_fold(sc, T, h, &Tf, &hf);
    eo->dyn_time = T; eo->dyn_dt = h; eo->dyn_time_fold = Tf; eo->dyn_dt_fold = hf;
    eo->dyn_ke_frac = drape_scene_fall_swing(sc);
    eo->dyn_time_max = DRAPE_FALL_TIME_MAX * T;
    eo->dyn_dt_swing = DRAPE_FALL_SWING_STEP * h;
    eo->dyn_retry = sc->fall_retry;
    eo->dyn_redo_tol = DRAPE_FALL_REDO_TOL;
    eo->max_iters = DRAPE_FALL_MAX_ITERS;
}

int main(int argc, char **argv)
{
    drape_scene sc; drape_fabric f; drape_error err;
    if (argc < 6) { fprintf(stderr, "usage: rot scene fabric seed fine_spacing coarse_spacing...\n"); return 2; }
    if (drape_scene_load_flags(argv[1], DRAPE_SCENE_LOAD_FABRIC_OVERRIDDEN, &sc, &err, NULL, NULL) ||
        drape_fabric_load(argv[2], &f, &err, NULL, NULL)) { fprintf(stderr, "%s\n", err.msg); return 1; }
    double R = 0.5 * sc.diameter;
    sc.perturb_seed = (unsigned long)atol(argv[3]);
    sc.spacing = atof(argv[4]);
    drape_lattice *Lf = drape_lattice_new(&sc, &f, &err);
    drape_model_opts mo; drape_model_opts_from_scene(&sc, &mo);
    drape_model *mf = drape_model_new(Lf, &f, &mo, &err);
    drape_equilibrium_opts eo; drape_equilibrium_result rf;
    opts(&sc, &f, &eo, 1);
    if (drape_equilibrium_solve(mf, Lf->xinit, &eo, &rf, &err) != 0) { fprintf(stderr, "%s\n", err.msg); return 1; }
    double ph, am;
    fold_phase(Lf, rf.x, R, &ph, &am);
    printf("# source: seed %s at %s m: E %.7g J, fold phase %.1f deg (0 axes, 45 diagonals), amp %.4f, certified %d\n",
           argv[3], argv[4], rf.energy_J, ph, am, rf.certified);
    printf("%-8s %-6s %-13s %-7s %-7s %-5s %-9s\n", "spacing", "turn", "E_J", "phase", "amp", "cert", "iters");
    for (int a = 5; a < argc; a++) {
        sc.spacing = atof(argv[a]);
        drape_lattice *L = drape_lattice_new(&sc, &f, &err);
        drape_model *m = drape_model_new(L, &f, &mo, &err);
        double E[3]; static const double turns[3] = {0, 10, 45};
        for (int t = 0; t < 3; t++) {
            double ang = turns[t] * PI / 180, c = cos(ang), s = sin(ang);
            double *x = malloc(sizeof(double) * 3 * L->n);
            for (int p = 0; p < L->n; p++) {
                double u = L->x0[3*p], v = L->x0[3*p+1];
                if (L->fixed[p]) { memcpy(x + 3*p, L->x0 + 3*p, 3 * sizeof(double)); continue; }
                double ub = c*u + s*v, vb = -s*u + c*v, d[3];
                disp_at(Lf, rf.x, ub, vb, d);
                double X = ub + d[0], Y = vb + d[1];
                x[3*p] = c*X - s*Y; x[3*p+1] = s*X + c*Y; x[3*p+2] = d[2];
            }
            drape_equilibrium_result r;
            opts(&sc, &f, &eo, 0);
            if (drape_equilibrium_solve(m, x, &eo, &r, &err) != 0) { fprintf(stderr, "%s\n", err.msg); return 1; }
            fold_phase(L, r.x, R, &ph, &am);
            E[t] = r.energy_J;
            printf("%-8s %-6s %-13.7g %-7.1f %-7.4f %-5d %-9d %s\n", argv[a], t == 2 ? "45" : t ? "10" : "0", r.energy_J, ph, am,
                   r.certified, r.iterations, drape_equilibrium_status_name(r.status));
            fflush(stdout);
            drape_equilibrium_result_free(&r);
            free(x);
        }
        printf("%-8s E(turned 10) - E(as fallen) = %+.4g J (%+.4f of |E|); E(turned 45) - E(as fallen) = %+.4g J (%+.4f)\n", argv[a],
               E[1] - E[0], (E[1] - E[0]) / fabs(E[0]), E[2] - E[0], (E[2] - E[0]) / fabs(E[0]));
        drape_model_free(m); drape_lattice_free(L);
    }
    return 0;
}
