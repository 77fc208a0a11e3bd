/* lattice-anisotropy: how much the lattice's bending energy prefers folds
 * along its diagonals to folds along its axes (docs/convergence.md, "Where
 * the nodes sit").
 *
 * usage: lattice-anisotropy SCENE FABRIC SPACING_M...
 *        (make bench-anisotropy runs the shipped Cusick scene with the
 *        isotropic study fabric)
 *
 * The specimen of the Cusick SCENE is put, by hand, into a smooth skirt:
 * flat on the support, then a generator that turns down by
 * beta (1 - exp(-s / ell)) at the distance s beyond the support's edge,
 * and on it four folds, a displacement normal to the skirt of
 * amp (s / (R - r_support))^2 cos(4 (theta - theta0)).  For a fabric that
 * is isotropic in bending (warp, weft and bias curves alike) the continuum
 * energy of that shape does not depend on theta0; the lattice's does.  For
 * each spacing it prints the bending energy (hinges and twist cells,
 * drape_model_energy) with the folds' crests on the lattice axes
 * (theta0 = 0) and on its diagonals (theta0 = 45 degrees), their
 * relative difference, and how much of it lies inside and outside a band
 * of 2 cm along the free edge (elements counted by their centre's rest
 * radius).  The defaults (beta 0.2 rad, ell 1.5 cm, amp 5 mm) keep the
 * shape close to an isometry of the flat specimen, so that the hinges'
 * curvatures are those of a bent, not a stretched, sheet; environment
 * variables AMP (m), BETA (rad) and ELL (m) change them. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "drape/fabric.h"
#include "drape/lattice.h"
#include "drape/model.h"
#include "drape/scene.h"

#define PI 3.14159265358979323846

static double RS, RR, BETA = 0.2, ELL = 0.015, AMP = 0.005;
#define NF 4

static double env(const char *name, double dflt)
{
    const char *v = getenv(name);
    return v && *v ? atof(v) : dflt;
}

/* the skirt at the rest point (X, Y), folds turned by th0, into p */
static void shape(double X, double Y, double th0, double *p)
{
    double rho = hypot(X, Y), th = atan2(Y, X);
    if (rho <= RS) {
        p[0] = X;
        p[1] = Y;
        p[2] = 0.0;
        return;
    }
    double s = rho - RS, r = RS, z = 0.0, h = s / 400.0;
    for (int k = 0; k < 400; k++) { /* the generator, midpoint rule */
        double phi = BETA * (1.0 - exp(-(k + 0.5) * h / ELL));
        r += h * cos(phi);
        z -= h * sin(phi);
    }
    double phi = BETA * (1.0 - exp(-s / ELL)), q = s / (RR - RS);
    double w = AMP * q * q * cos(NF * (th - th0));
    r += w * sin(phi);
    z += w * cos(phi);
    p[0] = r * cos(th);
    p[1] = r * sin(th);
    p[2] = z;
}

/* the bending energy, J, of the elements in region 0 (all), 1 (centre
 * inside R - band) or 2 (in the band) */
static double bend_energy(const drape_scene *sc, const drape_fabric *f, int region,
                          double band, double th0)
{
    drape_error err;
    drape_lattice *L = drape_lattice_new(sc, f, &err);
    if (!L) {
        fprintf(stderr, "lattice-anisotropy: %s\n", err.msg);
        exit(1);
    }
    for (int i = 0; region && i < L->n_hinges; i++) {
        const double *c = L->x0 + 3 * L->hinges[i].mid;
        if ((hypot(c[0], c[1]) < RR - band) != (region == 1)) L->hinges[i].weight = 0.0;
    }
    for (int i = 0; region && i < L->n_cells; i++) {
        double cx = 0.0, cy = 0.0;
        for (int k = 0; k < 4; k++) {
            cx += 0.25 * L->x0[3 * L->cells[i].p[k]];
            cy += 0.25 * L->x0[3 * L->cells[i].p[k] + 1];
        }
        if ((hypot(cx, cy) < RR - band) != (region == 1)) L->cells[i].weight = 0.0;
    }
    drape_model_opts o;
    drape_model_opts_from_scene(sc, &o);
    o.beta_shear = 0.0;
    drape_model *m = drape_model_new(L, f, &o, &err);
    double *x = malloc(sizeof *x * 3 * (size_t)L->n);
    if (!m || !x) {
        fprintf(stderr, "lattice-anisotropy: %s\n", m ? "out of memory" : err.msg);
        exit(1);
    }
    for (int i = 0; i < L->n; i++) shape(L->x0[3 * i], L->x0[3 * i + 1], th0, x + 3 * i);
    drape_energies E;
    if (drape_model_energy(m, x, &E) != 0) {
        fprintf(stderr, "lattice-anisotropy: a folded element\n");
        exit(1);
    }
    free(x);
    drape_model_free(m);
    drape_lattice_free(L);
    return E.bend;
}

int main(int argc, char **argv)
{
    drape_scene sc;
    drape_fabric f;
    drape_error err;
    if (argc < 4) {
        fputs("usage: lattice-anisotropy SCENE FABRIC SPACING_M...\n", stderr);
        return 2;
    }
    AMP = env("AMP", AMP);
    BETA = env("BETA", BETA);
    ELL = env("ELL", ELL);
    if (drape_scene_load_flags(argv[1], DRAPE_SCENE_LOAD_FABRIC_OVERRIDDEN, &sc, &err, NULL,
                               NULL) != 0 ||
        drape_fabric_load(argv[2], &f, &err, NULL, NULL) != 0) {
        fprintf(stderr, "lattice-anisotropy: %s:%d: %s: %s\n", err.file, err.line, err.key,
                err.msg);
        return 1;
    }
    if (sc.kind != DRAPE_SCENE_CUSICK) {
        fputs("lattice-anisotropy: expected a Cusick scene\n", stderr);
        return 2;
    }
    RS = 0.5 * sc.support_diameter;
    RR = 0.5 * sc.diameter;
    const double band = 0.02, th45 = PI / 4.0;
    printf("# %d folds, amplitude %g m, skirt angle %g rad over %g m; bending energy (mJ) "
           "with the crests on the axes (E_axes) and on the diagonals (E_diag)\n",
           NF, AMP, BETA, ELL);
    printf("%-10s %-12s %-12s %-10s %-12s %-12s\n", "spacing_m", "E_axes_mJ", "E_diag_mJ",
           "diag/axes-1", "of_it_inner", "of_it_edge_2cm");
    for (int a = 3; a < argc; a++) {
        sc.spacing = atof(argv[a]);
        double e[3][2];
        for (int r = 0; r < 3; r++) {
            e[r][0] = bend_energy(&sc, &f, r, band, 0.0);
            e[r][1] = bend_energy(&sc, &f, r, band, th45);
        }
        printf("%-10.5g %-12.6g %-12.6g %-+10.4f %-+12.4f %-+12.4f\n", sc.spacing,
               1e3 * e[0][0], 1e3 * e[0][1], e[0][1] / e[0][0] - 1.0,
               (e[1][1] - e[1][0]) / e[0][0], (e[2][1] - e[2][0]) / e[0][0]);
    }
    return 0;
}
