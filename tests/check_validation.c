/* check_validation.c: drape against physics nobody here wrote (issue 5,
 * docs/validation.md).
 *
 * References (tests/elastica.c, independent of the library):
 *   - the heavy cantilever elastica (inextensible, M = B K, own weight),
 *     solved by shooting; itself checked against its small-Gamma
 *     expansion, derived by hand (t = s / L, Gamma = W g L^3 / B):
 *         theta = Gamma (1 - (1 - t)^3) / 6 + O(Gamma^3)
 *         drop / L  = Gamma / 8 - Gamma^3 / 640 + O(Gamma^5)      (V1)
 *         reach / L = 1 - Gamma^2 / 112 + O(Gamma^4)               (V2)
 *         drop / reach = Gamma / 8 - Gamma^3 / 2240 + O(Gamma^5)   (V3)
 *         M(0) L / B = Gamma / 2 - Gamma^3 / 320 + O(Gamma^5)      (V4)
 *     (Gamma / 8 is Euler-Bernoulli's w L^4 / (8 B)), against the global
 *     moment balance M(0) = integral_0^L w x(s) ds (V5), which the shooting
 *     never uses, and against ASTM D1388's rule (Peirce 1930): at a chord
 *     angle of 41.5 deg the bending length is half the overhang;
 *   - the elastic catenary (Irvine 1981) in closed form, checked against
 *     the common catenary (k -> infinity);
 *   - the fabric's own input curves (Kawabata round trip): uniform bending
 *     K or shear gamma of a patch, the moment (force) recovered from the
 *     model's forces by virtual work, dE/dK = -sum_i f_i . dx_i/dK; and a
 *     simulated pure-bending test (clamps on an arc, the clamp's couple);
 *   - the hanging chain: Bernoulli's frequencies (z_n / 2) sqrt(g / L) and
 *     the lumped chain's own (Sturm bisection), against frequencies fitted
 *     (sums of sinusoids, variable projection) to the time series that the
 *     run wrote to drape.h5 and the test reads back with the HDF5 C API;
 *   - conservation of energy: a bound derived from the integrator's local
 *     error test (energy_steps), tolerance proportionality, and no energy
 *     gain with dissipation;
 *   - the Cusick DC at several spacings and both energy forms (static
 *     minima; here mostly a record of multistability, docs/validation.md).
 *
 * Simulations use the dynamic driver (drape_sim_run, cvode-bdf, rtol 1e-7)
 * with air drag near critical for the slowest mode, and check that the end
 * state is in equilibrium (|f_i| <= 1e-4 m_i g, or 1e-4 of the bending
 * force scale without gravity) before comparing.
 *
 * Fast cases: about 7 s of CPU in all.
 *
 * Set DRAPE_VALIDATE_OUT=<file> to add the "full" case, which writes the
 * markdown tables of docs/validation.md to <file> (scripts/validate.sh).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <time.h>

#include <gsl/gsl_sf_bessel.h>
#include <hdf5.h>

#include "drape/alloc.h"
#include "drape/drape.h"
#include "drape/equilibrium.h"
#include "drape/error.h"
#include "drape/fabric.h"
#include "drape/integrator.h"
#include "drape/lattice.h"
#include "drape/model.h"
#include "drape/output.h"
#include "drape/scene.h"
#include "drape/sim.h"
#include "drape/units.h"
#include "elastica.h"
#include "testutil.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define V_W 0.2          /* kg/m^2: areal density of every test fabric */
#define V_L 0.1          /* m: cantilever overhang */
#define V_K 1e4          /* N/m: tensile stiffness (stiff: strain ~ 2e-5) */
#define V_RTOL 1e-7      /* integrator tolerance */
#define V_ATOL_REL 1e-7  /* atol on positions, in units of the specimen size */
#define V_EQ_FORCE 1e-4  /* settled: |f_i| <= V_EQ_FORCE m_i g */

static FILE *vout; /* the tables' file, DRAPE_VALIDATE_OUT */

static double wall_now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* ---- set-up ------------------------------------------------------------- */

/* A fabric with one-piece linear bending M = B K in both directions, linear
 * shear (unused by strips), weight V_W, stiffness k: written as YAML and
 * loaded, so the units path is exercised too. */
static void fabric_linear(drape_fabric *F, double B, double k)
{
    char text[1024];
    snprintf(text, sizeof text,
             "fabric: linear-elastica\n"
             "weight: %.17g kg/m^2\n"
             "tensile_stiffness: %.17g N/m\n"
             "bending:\n"
             "  units: {curvature: 1/m, moment: N.m/m}\n"
             "  warp: [{from: 0, poly: [0, %.17g]}]\n"
             "  weft: [{from: 0, poly: [0, %.17g]}]\n"
             "shear:\n"
             "  units: {angle: rad, force: N/m}\n"
             "  curve: [{from: 0, poly: [0, 1]}]\n",
             V_W, k, B, B);
    drape_error err;
    drape_error_clear(&err);
    const char *path = tu_write_file("linear.yaml", text);
    ck_assert_msg(drape_fabric_load(path, F, &err, NULL, NULL) == 0, "fabric: %s",
                  err.msg);
    ck_assert_close_rel(drape_fabric_bending_rigidity(F, DRAPE_WARP), B, 1e-14);
    ck_assert_close_rel(F->weight, V_W, 1e-15);
}

/* Largest |f_i| / (m_i g) over free particles, conservative parts; with
 * fscale > 0, |f_i| / fscale instead. */
static double max_force_rel(drape_model *m, const drape_lattice *L, const double *x,
                            double fscale)
{
    double *f = drape_malloc(sizeof(double) * 3 * (size_t)L->n), worst = 0.0;
    ck_assert_ptr_nonnull(f);
    unsigned parts = drape_model_parts(m) &
                     (DRAPE_PART_STRETCH | DRAPE_PART_BEND | DRAPE_PART_SHEAR |
                      DRAPE_PART_GRAVITY);
    ck_assert_int_eq(drape_model_forces(m, parts, x, NULL, f), 0);
    for (int p = 0; p < L->n; p++) {
        if (L->fixed[p]) continue;
        double r = sqrt(f[3 * p] * f[3 * p] + f[3 * p + 1] * f[3 * p + 1] +
                        f[3 * p + 2] * f[3 * p + 2]) /
                   (fscale > 0.0 ? fscale : L->mass[p] * DRAPE_G_STANDARD);
        if (r > worst) worst = r;
    }
    drape_free(f);
    return worst;
}

/* Run m to equilibrium with cvode-bdf: air drag already in the model,
 * omega the slowest mode (rad/s), size the specimen's size (m); the end
 * state must have |f_i| <= V_EQ_FORCE fscale (fscale 0: m_i g).  Returns
 * the final state (caller frees with drape_sim_result_free). */
static void settle(drape_model *m, double omega, double size, double fscale,
                   drape_sim_result *r)
{
    drape_sim_opts o;
    drape_sim_opts_default(&o);
    snprintf(o.integrator, sizeof o.integrator, "cvode-bdf");
    o.rtol = V_RTOL;
    o.atol = V_ATOL_REL * size;
    o.has_equilibrium = 1;
    o.eq_speed = V_ATOL_REL * size * omega; /* position error ~ speed / omega */
    o.eq_window = 2.0 * M_PI / omega;
    o.t_max = 400.0 / omega;
    drape_error err;
    drape_error_clear(&err);
    int rc = drape_sim_run(m, &o, NULL, NULL, r, &err);
    ck_assert_msg(rc == 0, "sim: %s", err.msg);
    ck_assert_msg(r->status == DRAPE_SIM_EQUILIBRIUM, "not settled by %g s", o.t_max);
    const drape_lattice *L = drape_model_lattice(m);
    double fr = max_force_rel(m, L, r->x, fscale);
    if (vout) fflush(vout);
    ck_assert_msg(fr <= V_EQ_FORCE, "end state not in equilibrium: |f| = %g x scale", fr);
}

/* ---- cantilever ---------------------------------------------------------- */

typedef struct cant_run {
    double gamma;
    int np;             /* particles along the overhang (spacings) */
    double k;           /* N/m */
    double reach, drop; /* tip, over L */
    double ratio;       /* drop / reach */
    double chord_deg;   /* drape_cantilever_measure's tip angle */
    double c_peirce;    /* its Peirce bending length, over L */
    double shape_err;   /* max distance to the elastica at the same s, over L */
    double max_strain;
    long steps;
    double wall_s;
    elastica_solution ref;
} cant_run;

/* Strip of overhang V_L, np spacings over the edge, two behind it (the
 * clamped part), one particle across (width sigma / 2), linear bending with
 * Gamma = W g L^3 / B, stiffness k, air drag 2 omega_1 (omega_1 =
 * 1.875^2 sqrt(B / (W L^4)), the first bending mode: critical for it).
 * whole_clamp = 1 undoes the lattice's clamp correction (docs/lattice.md):
 * the hinge on the platform edge gets its whole vertex length and area. */
static void cantilever_run(double gamma, int np, double k, int whole_clamp, cant_run *out)
{
    const double L = V_L, g = DRAPE_G_STANDARD, B = V_W * g * L * L * L / gamma;
    const double sig = L / np, omega = 1.875104 * 1.875104 * sqrt(B / (V_W * L * L * L * L));
    drape_fabric F;
    fabric_linear(&F, B, k);
    drape_scene s;
    memset(&s, 0, sizeof s);
    s.kind = DRAPE_SCENE_CANTILEVER;
    s.shape = DRAPE_SHAPE_STRIP;
    s.strip_dir = DRAPE_WARP;
    s.overhang = L;
    s.length = L + 2.0 * sig;
    s.width = 0.5 * sig;
    s.spacing = sig;
    s.terms = DRAPE_TERM_STRETCH | DRAPE_TERM_BEND | DRAPE_TERM_GRAVITY;
    s.energy_form = DRAPE_FORM_CONSISTENT;
    s.damping_air = 2.0 * omega;
    drape_error err;
    drape_error_clear(&err);
    drape_lattice *La = drape_lattice_new(&s, &F, &err);
    ck_assert_msg(La != NULL, "lattice: %s", err.msg);
    ck_assert_int_eq(La->n_free, np);
    int clamp_hinges = 0;
    for (int h = 0; h < La->n_hinges; h++) {
        drape_hinge *H = &La->hinges[h];
        if (La->x0[3 * H->mid] != 0.0) continue;
        ck_assert_close_rel(H->length, 0.5, 1e-15);
        clamp_hinges++;
        if (whole_clamp) {
            H->weight *= 2.0;
            H->length = 1.0;
        }
    }
    ck_assert_int_eq(clamp_hinges, 1);
    drape_model_opts mo;
    drape_model_opts_from_scene(&s, &mo);
    drape_model *m = drape_model_new(La, &F, &mo, &err);
    ck_assert_msg(m != NULL, "model: %s", err.msg);

    drape_sim_result r;
    double t0 = wall_now();
    settle(m, omega, L, 0.0, &r);
    out->wall_s = wall_now() - t0;

    drape_cantilever c;
    ck_assert_int_eq(drape_cantilever_measure(La, r.x, V_W, g, &c, &err), 0);
    ck_assert_close_rel(c.overhang_m, L, 1e-12);
    ck_assert_int_eq(elastica_solve(gamma, &out->ref), 0);
    out->gamma = gamma;
    out->np = np;
    out->k = k;
    out->reach = c.tip_m[0] / L;
    out->drop = -c.tip_m[2] / L;
    out->ratio = out->drop / out->reach;
    out->chord_deg = c.tip_angle_deg;
    out->c_peirce = c.bending_length_m / L;
    out->max_strain = r.max_strain;
    out->steps = r.stats.steps;

    /* shape: the particle at rest x = j sigma sits at s = j sigma */
    enum { NMAX = 1024 };
    static double ex[NMAX + 1], ed[NMAX + 1];
    ck_assert_int_le(np, NMAX);
    ck_assert_int_eq(elastica_shape(gamma, np + 1, ex, ed), 0);
    out->shape_err = 0.0;
    for (int p = 0; p < La->n; p++) {
        double x0 = La->x0[3 * p];
        if (x0 < -0.5 * sig) continue;
        int j = (int)lround(x0 / sig);
        double dx = r.x[3 * p] / L - ex[j], dz = -r.x[3 * p + 2] / L - ed[j];
        out->shape_err = fmax(out->shape_err, hypot(dx, dz));
    }
    drape_sim_result_free(&r);
    drape_model_free(m);
    drape_lattice_free(La);
}

static double rel_err(double obs, double ref) { return obs / ref - 1.0; }

/* ---- catenary ------------------------------------------------------------ */

typedef struct cat_run {
    int nseg;           /* segments between the pins */
    double k, span_frac;
    double sag, t_end;  /* m, N/m per unit width */
    double shape_err;   /* max distance to the reference at the same s, m */
    long steps;
    double wall_s;
    catenary_solution ref;
} cat_run;

/* A strip of length l0 (one particle across, width sigma / 2), pinned at its
 * two end particles; the right pin moved toward the left one so that the
 * span is span_frac * l0; stretch and gravity only (no bending at all).
 * Air drag near critical for the slowest (string) mode, edge dashpots for
 * the stretch waves; neither moves the equilibrium.
 * The end tension is the support reaction: the force of the first edge on
 * the pinned particle plus that particle's weight (the part of the strip the
 * pin carries directly), per unit width. */
static void catenary_run(double l0, int nseg, double k, double span_frac, cat_run *out)
{
    const double sig = l0 / nseg, g = DRAPE_G_STANDARD, w = V_W * g;
    drape_fabric F;
    fabric_linear(&F, 1e-6, k);
    drape_scene s;
    memset(&s, 0, sizeof s);
    s.kind = DRAPE_SCENE_HANG;
    s.shape = DRAPE_SHAPE_RECTANGLE;
    s.width = l0;
    s.height = 0.5 * sig;
    s.spacing = sig;
    s.n_pins = 2;
    s.pins[0][0] = 0;  s.pins[0][1] = 0;
    s.pins[1][0] = -1; s.pins[1][1] = 0;
    s.terms = DRAPE_TERM_STRETCH | DRAPE_TERM_GRAVITY;
    s.energy_form = DRAPE_FORM_CONSISTENT;
    ck_assert_int_eq(catenary_solve(w, k, l0, span_frac * l0, &out->ref), 0);
    /* slowest mode: the antisymmetric string mode, wave speed sqrt(H / W) */
    double omega = 2.0 * M_PI / l0 * sqrt(out->ref.h / V_W);
    s.damping_air = 2.0 * omega;
    /* edge dashpots critical for one edge (stiffness k / 2, masses
     * W sigma^2 / 2 on the half-width row): the stretch waves of the
     * compressed start die at once (without them cvode-bdf needs ~1.5
     * million steps to resolve them at k = 1e4 N/m) */
    s.damping_edge = sig * sqrt(k * V_W);
    drape_error err;
    drape_error_clear(&err);
    drape_lattice *La = drape_lattice_new(&s, &F, &err);
    ck_assert_msg(La != NULL, "lattice: %s", err.msg);
    ck_assert_int_eq(La->n, nseg + 1);
    ck_assert_int_eq(La->n_free, nseg - 1);
    int left = La->grid[0], right = La->grid[nseg], mid = La->grid[nseg / 2];
    ck_assert(La->fixed[left] && La->fixed[right]);
    ck_assert_close_rel(La->x0[3 * right] - La->x0[3 * left], l0, 1e-12);
    /* move the right pin in; free particles start on the straight line */
    double x_left = La->xinit[3 * left];
    for (int p = 0; p < La->n; p++)
        La->xinit[3 * p] = x_left + span_frac * (La->x0[3 * p] - x_left);
    drape_model_opts mo;
    drape_model_opts_from_scene(&s, &mo);
    drape_model *m = drape_model_new(La, &F, &mo, &err);
    ck_assert_msg(m != NULL, "model: %s", err.msg);

    drape_sim_result r;
    double t0 = wall_now();
    settle(m, omega, l0, 0.0, &r);
    out->wall_s = wall_now() - t0;
    out->steps = r.stats.steps;
    out->nseg = nseg;
    out->k = k;
    out->span_frac = span_frac;
    out->sag = La->xinit[3 * left + 2] - r.x[3 * mid + 2];

    double *f = drape_malloc(sizeof(double) * 3 * (size_t)La->n);
    ck_assert_ptr_nonnull(f);
    ck_assert_int_eq(drape_model_forces(m, DRAPE_PART_STRETCH | DRAPE_PART_GRAVITY, r.x,
                                        NULL, f), 0);
    /* per unit width: the lattice row stands for a width sigma / 2 */
    double width = 0.5 * sig;
    double tl = sqrt(f[3 * left] * f[3 * left] + f[3 * left + 2] * f[3 * left + 2]) / width;
    double tr = sqrt(f[3 * right] * f[3 * right] + f[3 * right + 2] * f[3 * right + 2]) / width;
    ck_assert_close_rel(tl, tr, 1e-6); /* symmetry */
    out->t_end = 0.5 * (tl + tr);
    drape_free(f);

    out->shape_err = 0.0;
    for (int p = 0; p < La->n; p++) {
        double sp = La->x0[3 * p] - La->x0[3 * left], xr, dr;
        catenary_point(&out->ref, sp, &xr, &dr);
        double dx = (r.x[3 * p] - x_left) - xr, dz = (La->xinit[3 * left + 2] - r.x[3 * p + 2]) - dr;
        out->shape_err = fmax(out->shape_err, hypot(dx, dz));
    }
    drape_sim_result_free(&r);
    drape_model_free(m);
    drape_lattice_free(La);
}


/* ---- hanging chain ------------------------------------------------------- */

#define V_CHAIN_L 0.3    /* m: chain length */
#define V_CHAIN_A 3e-4   /* m: each mode's lateral amplitude at the free end (1e-3 L) */
#define V_CHAIN_DT 5e-3  /* s: frame interval (50 frames per period of mode 3) */

typedef struct chain_run {
    int nseg;
    double k, rtol;
    double omega[3];    /* fitted from the HDF5 frames, rad/s */
    double disc[3];     /* the lumped chain's own (elastica.h), rad/s */
    double cont[3];     /* the continuum's (z_n / 2) sqrt(g / L), rad/s */
    double resid;       /* relative residual of the three-sine fit */
    double static_force; /* largest |f_i| / m_i g at the analytic static state */
    long steps;
    double cpu_s;
    int frames;
} chain_run;

typedef struct h5_sink {
    drape_h5 *h;
    drape_model *m;
    const drape_lattice *L;
} h5_sink;

/* Observer: every frame into drape.h5, as `drape run --out` writes it. */
static int h5_sink_frame(void *ctx, const drape_sim_event *ev, drape_error *err)
{
    h5_sink *s = ctx;
    if (!(ev->what & DRAPE_SIM_AT_FRAME)) return 0;
    drape_energies E;
    if (drape_model_energy(s->m, ev->x, &E) != 0) return -1;
    return drape_h5_frame(s->h, ev->t, ev->x, ev->v, drape_sim_kinetic_energy(s->L, ev->v), &E,
                          err);
}

/* Read a 1-D or 2-D f64 dataset of drape.h5 (HDF5 C API, independent of the
 * writer): *rows x cols values into a new array. */
static double *h5_read(hid_t f, const char *name, int *rows, int cols)
{
    hid_t d = H5Dopen2(f, name, H5P_DEFAULT);
    ck_assert_msg(d >= 0, "no dataset %s", name);
    hid_t sp = H5Dget_space(d);
    hsize_t dims[2] = {0, 1};
    int rank = H5Sget_simple_extent_ndims(sp);
    ck_assert(rank == (cols > 1 ? 2 : 1));
    H5Sget_simple_extent_dims(sp, dims, NULL);
    ck_assert_int_eq((int)dims[1], cols);
    double *a = drape_malloc(sizeof(double) * (size_t)(dims[0] * (hsize_t)cols + 1));
    ck_assert_ptr_nonnull(a);
    ck_assert(H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, a) >= 0);
    H5Sclose(sp);
    H5Dclose(d);
    *rows = (int)dims[0];
    return a;
}

/* The hanging chain (issue 5 item 2): a strip of length V_CHAIN_L and nseg
 * segments, one particle across (width sigma / 2), pinned at its first
 * particle; stretch and gravity only (no bending at all), stiffness k; no
 * dissipation.  It starts in its static equilibrium, computed here
 * (hanging straight down, segment j stretched by the weight below it,
 * chain_discrete), displaced sideways (x) by V_CHAIN_A times the sum of the
 * first three continuum mode shapes J0(z_n sqrt(y / L)) (y up from the free
 * end), at rest.  The run writes a frame every V_CHAIN_DT to drape.h5
 * through the library's writer; the lateral displacements of all free
 * particles are read back from /steps/NNNNNN/positions with the HDF5 API
 * and fitted with three common frequencies (sines_fit, started from the
 * periodogram peaks of the free end's motion). */
static int chain_max_order = 5; /* cvode-bdf; table_chain also tries 2 */
static double chain_atol = 1e-6 * V_CHAIN_A; /* m; table_chain also tries 1e-7 m */
static void chain_run_once(int nseg, double k, const char *integrator, double rtol,
                           double t_rec, chain_run *out)
{
    const double L = V_CHAIN_L, sig = L / nseg, g = DRAPE_G_STANDARD, w = 0.5 * sig;
    memset(out, 0, sizeof *out);
    out->nseg = nseg;
    out->k = k;
    out->rtol = rtol;
    drape_fabric F;
    fabric_linear(&F, 1e-6, k);
    drape_scene s;
    memset(&s, 0, sizeof s);
    s.kind = DRAPE_SCENE_HANG;
    s.shape = DRAPE_SHAPE_RECTANGLE;
    s.width = L;
    s.height = w;
    s.spacing = sig;
    s.n_pins = 1;
    s.terms = DRAPE_TERM_STRETCH | DRAPE_TERM_GRAVITY;
    s.energy_form = DRAPE_FORM_CONSISTENT;
    drape_error err;
    drape_error_clear(&err);
    drape_lattice *La = drape_lattice_new(&s, &F, &err);
    ck_assert_msg(La != NULL, "lattice: %s", err.msg);
    ck_assert_int_eq(La->n, nseg + 1);
    ck_assert_int_eq(La->n_free, nseg);
    ck_assert_int_eq(La->nj, 1);
    /* the lumping the reference assumes: W sigma w per particle, half at
     * the free end; edges of half width (boundary row) */
    for (int i = 1; i <= nseg; i++)
        ck_assert_close_rel(La->mass[La->grid[i]], V_W * sig * w * (i == nseg ? 0.5 : 1.0), 1e-12);
    for (int e = 0; e < La->n_edges; e++) ck_assert_close_rel(La->edges[e].weight, 0.5, 1e-15);

    double seg[4096];
    ck_assert_int_le(nseg, 4096);
    ck_assert_int_eq(chain_discrete(nseg, L, V_W, g, k, 3, out->disc, seg), 0);
    for (int n = 0; n < 3; n++) out->cont[n] = chain_omega_continuous(n + 1, g, L);
    const int top = La->grid[0];
    const double x_top = La->xinit[3 * top], y_top = La->xinit[3 * top + 1],
                 z_top = La->xinit[3 * top + 2];
    double *xs = drape_malloc(sizeof(double) * 3 * (size_t)La->n);
    ck_assert_ptr_nonnull(xs);
    double z = z_top;
    for (int i = 0; i <= nseg; i++) {
        int p = La->grid[i];
        if (i > 0) z -= seg[i - 1];
        xs[3 * p] = x_top;
        xs[3 * p + 1] = y_top;
        xs[3 * p + 2] = z;
    }
    drape_model_opts mo;
    drape_model_opts_from_scene(&s, &mo);
    drape_model *m = drape_model_new(La, &F, &mo, &err);
    ck_assert_msg(m != NULL, "model: %s", err.msg);
    out->static_force = max_force_rel(m, La, xs, 0.0);
    for (int i = 0; i <= nseg; i++) {
        int p = La->grid[i];
        double y = L - i * sig, u = 0.0;
        for (int n = 1; n <= 3; n++) u += gsl_sf_bessel_J0(chain_j0_zero(n) * sqrt(y / L));
        for (int c = 0; c < 3; c++) La->xinit[3 * p + c] = xs[3 * p + c];
        if (i > 0) La->xinit[3 * p] += V_CHAIN_A * u;
    }

    drape_sim_opts o;
    drape_sim_opts_default(&o);
    snprintf(o.integrator, sizeof o.integrator, "%s", integrator);
    o.rtol = rtol;
    o.atol = chain_atol;
    o.t_max = t_rec;
    o.frame_every = V_CHAIN_DT;
    if (strcmp(integrator, "cvode-bdf") == 0) o.max_order = chain_max_order;
    h5_sink sink = {NULL, m, La};
    sink.h = drape_h5_open(tu_scratch_dir(), La, &err);
    ck_assert_msg(sink.h != NULL, "h5: %s", err.msg);
    drape_sim_result r;
    clock_t c0 = clock();
    int rc = drape_sim_run(m, &o, h5_sink_frame, &sink, &r, &err);
    out->cpu_s = (double)(clock() - c0) / CLOCKS_PER_SEC;
    ck_assert_msg(rc == 0, "sim: %s", err.msg);
    ck_assert(r.status == DRAPE_SIM_T_MAX);
    out->steps = r.stats.steps;
    ck_assert_msg(drape_h5_close(sink.h, NULL, &err) == 0, "h5: %s", err.msg);
    drape_sim_result_free(&r);

    /* read the time series back */
    char path[600];
    snprintf(path, sizeof path, "%s/drape.h5", tu_scratch_dir());
    hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    ck_assert_msg(f >= 0, "cannot open %s", path);
    int nt, rows;
    double *t = h5_read(f, "/times", &nt, 1);
    out->frames = nt;
    ck_assert_int_ge(nt, 100);
    double *u = drape_malloc(sizeof(double) * (size_t)nseg * (size_t)nt);
    ck_assert_ptr_nonnull(u);
    for (int q = 0; q < nt; q++) {
        char name[64];
        snprintf(name, sizeof name, "/steps/%06d/positions", q);
        double *x = h5_read(f, name, &rows, 3);
        ck_assert_int_eq(rows, La->n);
        ck_assert_close_rel(t[q], q * V_CHAIN_DT, 1e-9);
        for (int i = 1; i <= nseg; i++) {
            int p = La->grid[i];
            u[(size_t)(i - 1) * (size_t)nt + (size_t)q] = x[3 * p] - xs[3 * p];
        }
        drape_free(x);
    }
    H5Fclose(f);

    /* starting values: periodogram of the free end, up to the Nyquist
     * frequency, at a tenth of the record's resolution */
    double guess[3];
    int np = sines_peaks(t, u + (size_t)(nseg - 1) * (size_t)nt, nt, M_PI / V_CHAIN_DT,
                         0.1 * 2.0 * M_PI / t[nt - 1], 3, guess);
    ck_assert_int_eq(np, 3);
    ck_assert_int_eq(sines_fit(t, u, nseg, nt, 3, guess, out->omega, &out->resid), 0);
    drape_free(t);
    drape_free(u);
    drape_free(xs);
    drape_model_free(m);
    drape_lattice_free(La);
}


/* ---- energy ---------------------------------------------------------------
 * Without dissipation the exact flow conserves E = E_kin + E_pot, so along
 * the numerical solution y_0, y_1, ... (steps of the integrator)
 *     E(y_k) - E(y_0) = sum_{j<k} [E(y_{j+1}) - E(phi_h(y_j))]
 * exactly (phi_h the exact flow over step j: E(phi_h(y_j)) = E(y_j)), and
 * y_{j+1} - phi_h(y_j) = le_j is step j's local error.  CVODE accepts a
 * step when its local error estimate has weighted RMS norm <= 1, weights
 * w_i = rtol |y_i| + atol_i; so, to first order in le_j (Cauchy-Schwarz on
 * grad E . le = sum (g_i w_i)(le_i / w_i), N = 6 n_free unknowns),
 *     |E(y_k) - E(y_0)| <= B_k = sum_{j<k} sqrt(N) || g(y_j) o w(y_j) ||_2,
 * g = grad E = (-f_conservative, m v).  B is linear in the tolerances.  It
 * is a worst case (every step's error aligned with grad E, all of one
 * sign), so the observed error sits far below it (docs/validation.md).
 * With dissipation the exact flow only loses energy, E(phi_h(y_j)) <=
 * E(y_j), so E(y_{j+1}) - E(y_j) <= sqrt(N) ||g o w|| step by step. */

typedef struct energy_run {
    double rtol;
    long steps;
    double dev;      /* max_k |E_k - E_0| (undamped) */
    double rise;     /* max_k (E_{k+1} - E_k) / b_k, the worst step against its bound (damped) */
    double bound;    /* B at the end, J */
    double worst;    /* max_k |E_k - E_0| / B_k (undamped) */
    double scale;    /* largest kinetic energy, J */
    double e0, e_end;
} energy_run;

#define V_ENERGY_TSCALE 0.1 /* s: atol_v = atol / T (integrator.h), fixed here */

static void load_scene_file(const char *rel, drape_scene *s, drape_fabric *F)
{
    drape_error err;
    drape_error_clear(&err);
    ck_assert_msg(drape_scene_load(tu_src(rel), s, &err, NULL, NULL) == 0, "scene: %s", err.msg);
    ck_assert_msg(drape_fabric_load(s->fabric_path, F, &err, NULL, NULL) == 0, "fabric: %s",
                  err.msg);
}

/* The lattice (*L) and model of a loaded scene and fabric. */
static drape_model *scene_model(const drape_scene *s, const drape_fabric *F, drape_lattice **L)
{
    drape_error err;
    drape_error_clear(&err);
    *L = drape_lattice_new(s, F, &err);
    ck_assert_msg(*L != NULL, "lattice: %s", err.msg);
    drape_model_opts mo;
    drape_model_opts_from_scene(s, &mo);
    drape_model *m = drape_model_new(*L, F, &mo, &err);
    ck_assert_msg(m != NULL, "model: %s", err.msg);
    return m;
}

/* Total energy of the full state (x, v). */
static double total_energy(drape_model *m, const drape_lattice *L, const double *x,
                           const double *v)
{
    drape_energies e;
    ck_assert_int_eq(drape_model_energy(m, x, &e), 0);
    return drape_sim_kinetic_energy(L, v) + e.stretch + e.bend + e.shear + e.gravity;
}

/* sqrt(N) || g o w ||_2 at (x, v): one step's share of the bound. */
static double energy_step_bound(drape_model *m, const drape_lattice *L, const double *x,
                                const double *v, double *f, double rtol, double atol)
{
    unsigned cons = drape_model_parts(m) & (DRAPE_PART_STRETCH | DRAPE_PART_BEND |
                                            DRAPE_PART_SHEAR | DRAPE_PART_GRAVITY);
    ck_assert_int_eq(drape_model_forces(m, cons, x, NULL, f), 0);
    double s2 = 0.0;
    for (int p = 0; p < L->n; p++) {
        if (L->fixed[p]) continue;
        for (int c = 0; c < 3; c++) {
            double gx = f[3 * p + c] * (rtol * fabs(x[3 * p + c]) + atol);
            double gv = L->mass[p] * v[3 * p + c] *
                        (rtol * fabs(v[3 * p + c]) + atol / V_ENERGY_TSCALE);
            s2 += gx * gx + gv * gv;
        }
    }
    return sqrt(6.0 * L->n_free * s2);
}

/* Step the scene's model with cvode-bdf one internal step at a time to
 * t_end (rtol, atol = rtol x 1 cm), air drag `air` (1/s) instead of the
 * scene's damping; every step checked against the bound above. */
static void energy_steps(const char *rel, double air, double rtol, double t_end,
                         energy_run *out)
{
    drape_scene s;
    drape_fabric F;
    load_scene_file(rel, &s, &F);
    s.damping_air = air;
    s.damping_edge = 0.0;
    drape_lattice *L;
    drape_model *m = scene_model(&s, &F, &L);
    drape_error err;
    drape_error_clear(&err);
    drape_integrator_opts io;
    drape_integrator_opts_default(&io);
    io.rtol = rtol;
    io.atol = 1e-2 * rtol;
    io.t_scale = V_ENERGY_TSCALE;
    io.t_stop = t_end;
    drape_integrator *I = drape_integrator_new(m, "cvode-bdf", &io, &err);
    ck_assert_msg(I != NULL, "integrator: %s", err.msg);
    size_t n3 = 3 * (size_t)L->n;
    double *x = drape_malloc(sizeof(double) * n3), *v = drape_malloc(sizeof(double) * n3),
           *f = drape_malloc(sizeof(double) * n3);
    ck_assert(x && v && f);
    memset(out, 0, sizeof *out);
    out->rtol = rtol;
    drape_integrator_state(I, x, v);
    double E = total_energy(m, L, x, v), B = 0.0;
    out->e0 = E;
    for (;;) {
        double b = energy_step_bound(m, L, x, v, f, rtol, io.atol);
        ck_assert_msg(drape_integrator_step_to(I, t_end, DRAPE_STEP_ONE, &err) == 0,
                      "step: %s", err.msg);
        drape_integrator_state(I, x, v);
        double En = total_energy(m, L, x, v), ke = drape_sim_kinetic_energy(L, v);
        B += b;
        out->scale = fmax(out->scale, ke);
        out->dev = fmax(out->dev, fabs(En - out->e0));
        out->worst = fmax(out->worst, fabs(En - out->e0) / B);
        out->rise = fmax(out->rise, (En - E) / b);
        E = En;
        if (drape_integrator_time(I) >= t_end * (1 - 1e-12)) break;
    }
    drape_integrator_stats st;
    drape_integrator_get_stats(I, &st);
    out->steps = st.steps;
    out->bound = B;
    out->e_end = E;
    drape_free(x);
    drape_free(v);
    drape_free(f);
    drape_integrator_free(I);
    drape_model_free(m);
    drape_lattice_free(L);
}


/* ---- Cusick spacing study ------------------------------------------------
 * The default Cusick scene (scenes/cusick.yaml, cotton-breen) solved by the
 * static equilibrium solver (docs/equilibrium.md; what `drape run --method
 * static` does: same scene, same options, same minimum), at a spacing and
 * energy form, from the scene's flat start with the perturbation seed
 * `seed` (-1: no perturbation), or from a solution `from` on another
 * lattice: its displacement field x - x0, bilinearly interpolated in the
 * rest plane at this lattice's particles, so a minimum found on a fine
 * lattice can be followed to coarser ones. */

typedef struct cusick_sol {
    drape_lattice *L;
    double *x;           /* 3n: the minimum */
    double spacing, dc, energy, omega_min, cpu_s;
    int nodes, certified, converged, iterations;
} cusick_sol;

static void cusick_free(cusick_sol *c)
{
    drape_free(c->x);
    drape_lattice_free(c->L);
    memset(c, 0, sizeof *c);
}

static void interpolate_from(const cusick_sol *from, drape_lattice *L)
{
    const drape_lattice *Lf = from->L;
    const double sf = Lf->sigma;
    /* grid index of the rest point (0, 0) */
    double ic = Lf->gi[0] - Lf->x0[0] / sf, jc = Lf->gj[0] - Lf->x0[1] / sf;
    for (int p = 0; p < L->n; p++) {
        if (L->fixed[p]) continue;
        double fi = L->x0[3 * p] / sf + ic, fj = L->x0[3 * p + 1] / sf + jc;
        int i0 = (int)floor(fi + 1e-9), j0 = (int)floor(fj + 1e-9);
        double a = fmax(fi - i0, 0.0), b = fmax(fj - j0, 0.0), u[3] = {0, 0, 0}, wsum = 0.0;
        if (a < 1e-9) a = 0.0;
        if (b < 1e-9) b = 0.0;
        for (int di = 0; di < 2; di++)
            for (int dj = 0; dj < 2; dj++) {
                double w = (di ? a : 1 - a) * (dj ? b : 1 - b);
                int ii = i0 + di, jj = j0 + dj;
                if (w == 0.0 || ii < 0 || jj < 0 || ii >= Lf->ni || jj >= Lf->nj) continue;
                int q = Lf->grid[jj * Lf->ni + ii];
                if (q < 0) continue; /* outside the fine circle: renormalise */
                for (int c = 0; c < 3; c++) u[c] += w * (from->x[3 * q + c] - Lf->x0[3 * q + c]);
                wsum += w;
            }
        ck_assert_msg(wsum > 0.0, "no fine particle near (%g, %g)", L->x0[3 * p], L->x0[3 * p + 1]);
        for (int c = 0; c < 3; c++) L->xinit[3 * p + c] = L->x0[3 * p + c] + u[c] / wsum;
    }
}

static void cusick_static(const drape_scene *base, const drape_fabric *F, double spacing,
                          drape_energy_form form, long seed, const cusick_sol *from,
                          cusick_sol *out)
{
    drape_scene s = *base;
    s.spacing = spacing;
    s.energy_form = form;
    s.has_perturbation = seed >= 0 && !from;
    s.perturb_seed = seed >= 0 ? (unsigned long)seed : 0;
    drape_error err;
    drape_error_clear(&err);
    memset(out, 0, sizeof *out);
    out->spacing = spacing;
    out->L = drape_lattice_new(&s, F, &err);
    ck_assert_msg(out->L != NULL, "lattice: %s", err.msg);
    if (from) interpolate_from(from, out->L);
    drape_model_opts mo;
    drape_model_opts_from_scene(&s, &mo);
    drape_model *m = drape_model_new(out->L, F, &mo, &err);
    ck_assert_msg(m != NULL, "model: %s", err.msg);
    drape_equilibrium_opts eo;
    drape_equilibrium_opts_from_fabric(&eo, F);
    drape_equilibrium_result r;
    ck_assert_msg(drape_equilibrium_solve(m, out->L->xinit, &eo, &r, &err) == 0, "static: %s",
                  err.msg);
    out->converged = r.status == DRAPE_EQ_CONVERGED;
    out->certified = r.certified == 1;
    out->energy = r.energy_J;
    out->omega_min = r.omega_min;
    out->iterations = r.iterations;
    out->cpu_s = r.cpu_s;
    size_t n3 = 3 * (size_t)out->L->n;
    out->x = drape_malloc(sizeof(double) * n3);
    ck_assert_ptr_nonnull(out->x);
    memcpy(out->x, r.x, sizeof(double) * n3);
    drape_equilibrium_result_free(&r);
    drape_shadow sh;
    ck_assert_msg(drape_shadow_measure(out->L, out->x, &sh, &err) == 0, "dc: %s", err.msg);
    out->dc = sh.dc;
    out->nodes = sh.nodes;
    drape_model_free(m);
}

/* Order p and limit of D(h) = D* + C h^p from three spacings h1 > h2 > h3
 * (any ratios): (D1 - D2) / (D2 - D3) = (h1^p - h2^p) / (h2^p - h3^p),
 * which rises monotonically in p; returns 0, or -1 when the differences
 * change sign or p falls outside (0.05, 12) (no power law). */
static int observed_order(const double h[3], const double d[3], double *p, double *lim)
{
    double r = (d[0] - d[1]) / (d[1] - d[2]);
    if (!(r > 0.0) || !isfinite(r)) return -1;
    double lo = 0.05, hi = 12.0;
    double flo = (pow(h[0], lo) - pow(h[1], lo)) / (pow(h[1], lo) - pow(h[2], lo)) - r;
    double fhi = (pow(h[0], hi) - pow(h[1], hi)) / (pow(h[1], hi) - pow(h[2], hi)) - r;
    if (!(flo < 0.0 && fhi > 0.0)) return -1;
    for (int it = 0; it < 200; it++) {
        double mid = 0.5 * (lo + hi);
        double f = (pow(h[0], mid) - pow(h[1], mid)) / (pow(h[1], mid) - pow(h[2], mid)) - r;
        if (f < 0.0) lo = mid;
        else hi = mid;
    }
    *p = 0.5 * (lo + hi);
    *lim = d[2] - (d[1] - d[2]) * pow(h[2], *p) / (pow(h[1], *p) - pow(h[2], *p));
    return 0;
}

/* ---- Kawabata round trip ------------------------------------------------- */

typedef struct patch {
    drape_fabric F;
    drape_scene s;
    drape_lattice *L;
    drape_model *m;
    double *x, *dx, *f;
} patch;

/* A 2 cm x 2 cm patch at 2 mm of fabric F (copied), only the term `term`,
 * energy form `form`, nothing fixed. */
static void patch_new(patch *P, const drape_fabric *F, unsigned term, drape_energy_form form)
{
    memset(P, 0, sizeof *P);
    drape_error err;
    drape_error_clear(&err);
    P->F = *F;
    P->s.kind = DRAPE_SCENE_HANG;
    P->s.shape = DRAPE_SHAPE_RECTANGLE;
    P->s.width = 0.02;
    P->s.height = 0.02;
    P->s.spacing = 0.002;
    P->s.terms = term;
    P->s.energy_form = form;
    P->L = drape_lattice_new(&P->s, &P->F, &err);
    ck_assert_msg(P->L != NULL, "lattice: %s", err.msg);
    drape_model_opts mo;
    drape_model_opts_from_scene(&P->s, &mo);
    P->m = drape_model_new(P->L, &P->F, &mo, &err);
    ck_assert_msg(P->m != NULL, "model: %s", err.msg);
    size_t n3 = 3 * (size_t)P->L->n;
    P->x = drape_malloc(sizeof(double) * n3);
    P->dx = drape_malloc(sizeof(double) * n3);
    P->f = drape_malloc(sizeof(double) * n3);
    ck_assert(P->x && P->dx && P->f);
}

static void patch_free(patch *P)
{
    drape_free(P->x);
    drape_free(P->dx);
    drape_free(P->f);
    drape_model_free(P->m);
    drape_lattice_free(P->L);
}

/* -sum f . dx over all particles (the patch is free: no fixed particles) */
static double virtual_work(patch *P, unsigned part)
{
    ck_assert_int_eq(drape_model_forces(P->m, part, P->x, NULL, P->f), 0);
    double dw = 0.0;
    for (int q = 0; q < 3 * P->L->n; q++) dw -= P->f[q] * P->dx[q];
    return dw;
}

/* Uniform bending of the `dir` lattice lines to curvature K (1/m): along the
 * bent direction the particles lie on a polygon of chord sigma turning by
 * K sigma at every particle (so every hinge has psi = K sigma exactly and
 * no edge stretches); dx = d x / dK analytically.  Returns the moment per
 * unit width recovered from the model, (dE/dK) / sum(weight sigma^2). */
static double patch_bend_moment(patch *P, drape_dir dir, double K)
{
    const drape_lattice *L = P->L;
    const double sig = L->sigma, h = 0.5 * K * sig;
    const double rho = sig / (2.0 * sin(h)), drho = -sig * sig * cos(h) / (4.0 * sin(h) * sin(h));
    int axis = dir == DRAPE_WEFT ? 0 : 1; /* weft lines run along x (i) */
    double mid = axis == 0 ? 0.5 * (L->ni - 1) : 0.5 * (L->nj - 1);
    for (int p = 0; p < L->n; p++) {
        double u = (axis == 0 ? L->gi[p] : L->gj[p]) - mid, ph = u * K * sig;
        for (int c = 0; c < 3; c++) { P->x[3 * p + c] = L->x0[3 * p + c]; P->dx[3 * p + c] = 0.0; }
        P->x[3 * p + axis] = rho * sin(ph);
        P->x[3 * p + 2] = rho * (1.0 - cos(ph));
        P->dx[3 * p + axis] = drho * sin(ph) + rho * cos(ph) * u * sig;
        P->dx[3 * p + 2] = drho * (1.0 - cos(ph)) + rho * sin(ph) * u * sig;
    }
    double area = 0.0;
    for (int k = 0; k < L->n_hinges; k++)
        if (L->hinges[k].dir == dir) area += L->hinges[k].weight * sig * sig;
    return virtual_work(P, DRAPE_PART_BEND) / area;
}

/* Uniform shear gamma (rad): particle (i, j) at (i sigma + j sigma sin g,
 * j sigma cos g): every edge keeps its length, every corner turns by
 * +-gamma.  Returns (dE/dgamma) / sum(weight sigma^2 / 4). */
static double patch_shear_force(patch *P, double gm)
{
    const drape_lattice *L = P->L;
    const double sig = L->sigma;
    for (int p = 0; p < L->n; p++) {
        double i = L->gi[p], j = L->gj[p];
        P->x[3 * p] = sig * (i + j * sin(gm));
        P->x[3 * p + 1] = sig * j * cos(gm);
        P->x[3 * p + 2] = 0.0;
        P->dx[3 * p] = sig * j * cos(gm);
        P->dx[3 * p + 1] = -sig * j * sin(gm);
        P->dx[3 * p + 2] = 0.0;
    }
    double area = 0.0;
    for (int k = 0; k < L->n_corners; k++) area += L->corners[k].weight * sig * sig / 4.0;
    return virtual_work(P, DRAPE_PART_SHEAR) / area;
}

/* Simulated pure bending (KES-FB2 style): a strip of free length 1 cm at
 * 1 mm, one particle across (width sigma / 2), bending along `dir`; its two
 * end particles at each end are clamped on the arc of curvature K (every
 * turning angle K sigma), the free ones start on that arc with a bump of
 * 0.05 sigma and settle (cvode-bdf, air drag critical for the first
 * clamped-clamped mode, stretch and bending only, no gravity).  Measured:
 * the curvature of the settled strip from its positions, K_sim = mean
 * psi / sigma over the free particles (and the spread), and the moment per
 * unit width the strip exerts on the left clamp, from the model's forces on
 * the two clamped particles: the couple sum (x_p - x_0) x f_p about the
 * bending axis, over the width.  The net force on the clamp (which pure
 * bending makes zero) is returned too, over M / sigma. */
typedef struct bend_run {
    double K_sim, K_spread, M_sim, M_fit, net_force;
    long steps;
} bend_run;

static void bend_simulated(const drape_fabric *F, drape_dir dir, double K, bend_run *out)
{
    const double sig = 0.001, lb = 0.012; /* 13 particles: 2 + 9 free + 2 */
    const int n = 13, along = dir == DRAPE_WEFT ? 0 : 1;
    drape_scene s;
    memset(&s, 0, sizeof s);
    s.kind = DRAPE_SCENE_HANG;
    s.shape = DRAPE_SHAPE_RECTANGLE;
    s.width = along == 0 ? lb : 0.5 * sig;
    s.height = along == 0 ? 0.5 * sig : lb;
    s.spacing = sig;
    s.n_pins = 4;
    const int ends[4] = {0, 1, -2, -1};
    for (int k = 0; k < 4; k++) {
        s.pins[k][along] = ends[k];
        s.pins[k][1 - along] = 0;
    }
    s.terms = DRAPE_TERM_STRETCH | DRAPE_TERM_BEND;
    s.energy_form = DRAPE_FORM_CONSISTENT;
    double B = drape_fit_slope(&F->bend[dir], K), Mk = drape_fit_value(&F->bend[dir], K);
    double lf = (n - 3) * sig; /* between the inner clamped particles */
    double omega = 22.373 * sqrt(B / (F->weight * lf * lf * lf * lf));
    s.damping_air = 2.0 * omega;
    drape_error err;
    drape_error_clear(&err);
    drape_lattice *L = drape_lattice_new(&s, F, &err);
    ck_assert_msg(L != NULL, "lattice: %s", err.msg);
    ck_assert_int_eq(L->n, n);
    ck_assert_int_eq(L->n_free, n - 4);
    const double h = 0.5 * K * sig, rho = sig / (2.0 * sin(h)), mid = 0.5 * (n - 1);
    int id[13];
    for (int p = 0; p < n; p++) {
        int u = along == 0 ? L->gi[p] : L->gj[p];
        id[u] = p;
        double ph = (u - mid) * K * sig, *x = L->xinit + 3 * p;
        x[along] = rho * sin(ph);
        x[1 - along] = 0.0;
        x[2] = rho * (1.0 - cos(ph));
        if (!L->fixed[p]) x[2] += 0.05 * sig * sin(M_PI * (u - 1) / (n - 3));
    }
    drape_model_opts mo;
    drape_model_opts_from_scene(&s, &mo);
    drape_model *m = drape_model_new(L, F, &mo, &err);
    ck_assert_msg(m != NULL, "model: %s", err.msg);
    drape_sim_result r;
    /* force scale: the moment over a spacing, times the width */
    double width = 0.5 * sig, fscale = Mk * width / sig;
    settle(m, omega, lb, fscale, &r);
    out->steps = r.stats.steps;

    double ks = 0.0, kmin = INFINITY, kmax = -INFINITY;
    for (int u = 2; u <= n - 3; u++) {
        const double *a = r.x + 3 * id[u - 1], *b = r.x + 3 * id[u], *c = r.x + 3 * id[u + 1];
        double e1[3], e2[3], cr[3];
        for (int q = 0; q < 3; q++) { e1[q] = a[q] - b[q]; e2[q] = c[q] - b[q]; }
        cr[0] = e1[1] * e2[2] - e1[2] * e2[1];
        cr[1] = e1[2] * e2[0] - e1[0] * e2[2];
        cr[2] = e1[0] * e2[1] - e1[1] * e2[0];
        double th = atan2(sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]),
                          e1[0] * e2[0] + e1[1] * e2[1] + e1[2] * e2[2]);
        double k = (M_PI - th) / sig;
        ks += k;
        kmin = fmin(kmin, k);
        kmax = fmax(kmax, k);
    }
    out->K_sim = ks / (n - 4);
    out->K_spread = (kmax - kmin) / out->K_sim;
    out->M_fit = drape_fit_value(&F->bend[dir], out->K_sim);

    double *f = drape_malloc(sizeof(double) * 3 * (size_t)n);
    ck_assert_ptr_nonnull(f);
    ck_assert_int_eq(drape_model_forces(m, DRAPE_PART_STRETCH | DRAPE_PART_BEND, r.x, NULL, f), 0);
    /* couple about the axis across the strip: for a weft strip (x, z) the
     * y component of r x f is r_z f_x - r_x f_z; for a warp strip (y, z)
     * the x component is r_y f_z - r_z f_y */
    const double *x0 = r.x + 3 * id[0];
    double cpl = 0.0, net[3] = {0.0, 0.0, 0.0};
    for (int u = 0; u < 2; u++) {
        const double *x = r.x + 3 * id[u], *fp = f + 3 * id[u];
        double rv[3] = {x[0] - x0[0], x[1] - x0[1], x[2] - x0[2]};
        cpl += along == 0 ? rv[2] * fp[0] - rv[0] * fp[2] : rv[1] * fp[2] - rv[2] * fp[1];
        for (int q = 0; q < 3; q++) net[q] += fp[q];
    }
    out->M_sim = fabs(cpl) / width;
    out->net_force = sqrt(net[0] * net[0] + net[1] * net[1] + net[2] * net[2]) / fscale;
    drape_free(f);
    drape_sim_result_free(&r);
    drape_model_free(m);
    drape_lattice_free(L);
}

/* KES-F ranges: K up to 2.5 1/cm, gamma up to 0.13 rad (Breen's fits);
 * points on both sides of every knot of cotton-breen. */
static const double kawabata_K[] = {10, 30, 39, 41, 49, 51, 100, 200, 251, 253};
static const double kawabata_g[] = {0.002, 0.005, 0.0087, 0.0088, 0.02, 0.05, 0.1, 0.13};
#define N_KAW_K ((int)(sizeof kawabata_K / sizeof kawabata_K[0]))
#define N_KAW_G ((int)(sizeof kawabata_g / sizeof kawabata_g[0]))

/* ========================================================================= */

START_TEST(test_elastica_small_gamma)
{
    /* (V1)-(V4); the remainders, measured at Gamma = 0.03 .. 0.3, scale as
     * the next power: 3.48e-5 Gamma^5 (drop), 1.79e-4 Gamma^4 (reach),
     * 8.4e-6 Gamma^5 (ratio), 5.99e-5 Gamma^5 (clamp moment) */
    const double gs[] = {1e-3, 1e-2, 0.1, 0.2};
    for (int k = 0; k < 4; k++) {
        double G = gs[k], G3 = G * G * G, G5 = G3 * G * G;
        elastica_solution e;
        ck_assert_int_eq(elastica_solve(G, &e), 0);
        ck_assert_close_abs(e.tip_drop, G / 8 - G3 / 640, 5e-5 * G5 + 1e-13);
        ck_assert_close_abs(e.tip_x, 1 - G * G / 112, 3e-4 * G * G * G * G + 1e-13);
        ck_assert_close_abs(e.ratio, G / 8 - G3 / 2240, 1.3e-5 * G5 + 1e-13);
        ck_assert_close_abs(e.mu0, G / 2 - G3 / 320, 9e-5 * G5 + 1e-13);
    }
    /* a leading term alone is not enough at Gamma = 0.2: the series matter */
    elastica_solution e;
    ck_assert_int_eq(elastica_solve(0.2, &e), 0);
    ck_assert(fabs(e.tip_drop - 0.2 / 8) > 1e-6);
    /* outside the range */
    ck_assert_int_eq(elastica_solve(0.0, &e), -1);
    ck_assert_int_eq(elastica_solve(1e5, &e), -1);
}
END_TEST

START_TEST(test_elastica_moment_balance)
{
    /* (V5) M(0) L / B = Gamma int_0^1 x(t) dt, Simpson on 2001 points */
    enum { N = 2001 };
    static double x[N], d[N];
    const double gs[] = {1, 8, 30, 100};
    for (int k = 0; k < 4; k++) {
        elastica_solution e;
        ck_assert_int_eq(elastica_solve(gs[k], &e), 0);
        ck_assert_int_eq(elastica_shape(gs[k], N, x, d), 0);
        double sum = x[0] + x[N - 1];
        for (int i = 1; i < N - 1; i++) sum += (i % 2 ? 4.0 : 2.0) * x[i];
        double integral = sum / (3.0 * (N - 1));
        ck_assert_close_rel(e.mu0, gs[k] * integral, 1e-9);
        ck_assert_close_rel(x[N - 1], e.tip_x, 1e-10);
        ck_assert_close_rel(d[N - 1], e.tip_drop, 1e-10);
        /* the physical branch: slope below the vertical, monotone */
        ck_assert(e.tip_slope < 0.5 * M_PI && e.tip_slope > 0.0);
        for (int i = 1; i < N; i++) ck_assert(d[i] >= d[i - 1] && x[i] >= x[i - 1]);
    }
}
END_TEST

START_TEST(test_elastica_astm_rule)
{
    /* ASTM D1388: at a chord of 41.5 deg the bending length
     * c = (B / (W g))^(1/3) = L Gamma^(-1/3) is half the overhang */
    double G;
    ck_assert_int_eq(elastica_gamma_for_chord(41.5 * M_PI / 180, &G), 0);
    ck_assert_close_rel(cbrt(1.0 / G), 0.5, 1e-3);
    elastica_solution e;
    ck_assert_int_eq(elastica_solve(G, &e), 0);
    ck_assert_close_rel(e.chord, 41.5 * M_PI / 180, 1e-9);
    /* Peirce's closed form by hand: cos(20.75 deg) = 0.935135,
     * 8 tan(41.5 deg) = 7.077800, ratio 0.132122, cube root 0.509321 */
    ck_assert_close_rel(elastica_peirce_c_over_l(41.5 * M_PI / 180), 0.509321, 1e-5);
}
END_TEST

START_TEST(test_catenary_reference)
{
    /* k -> infinity: the common catenary, l0 = 2a sinh(l / 2a), sag =
     * a (cosh(l / 2a) - 1); a found here by bisection, independently */
    const double w = 2.0, l0 = 1.0, l = 0.8;
    double lo = 0.01, hi = 100.0;
    for (int it = 0; it < 200; it++) {
        double a = 0.5 * (lo + hi);
        if (2 * a * sinh(l / (2 * a)) > l0) lo = a; else hi = a;
    }
    double a = 0.5 * (lo + hi);
    catenary_solution c;
    ck_assert_int_eq(catenary_solve(w, 1e15, l0, l, &c), 0);
    ck_assert_close_rel(c.h, w * a, 1e-9);
    ck_assert_close_rel(c.sag, a * (cosh(l / (2 * a)) - 1), 1e-9);
    ck_assert_close_rel(c.t_end, w * a * cosh(l / (2 * a)), 1e-9);
    /* the right support is where the span says; the shape is symmetric */
    double x, d;
    catenary_point(&c, l0, &x, &d);
    ck_assert_close_rel(x, l, 1e-12);
    ck_assert_close_abs(d, 0.0, 1e-12);
    /* elastic, small sag: parabola, H = w l^2 / (8 sag), and the cable's
     * stretched length (from the mean strain) equals the parabola's arc
     * length l (1 + 8/3 (sag/l)^2) to O((sag/l)^4) */
    ck_assert_int_eq(catenary_solve(2.0, 1e4, 1.0, 1.0, &c), 0);
    ck_assert(c.sag > 0.01 && c.sag < 0.05);
    ck_assert_close_rel(c.h, 2.0 / (8 * c.sag), 1e-3);
    ck_assert_close_rel(c.h / 1e4, 8.0 / 3.0 * c.sag * c.sag, 1e-2);
}
END_TEST

START_TEST(test_cantilever_elastica)
{
    /* issue 5: drop/reach within 0.5 % at 40 particles, Gamma 0.1 .. 100 */
    const double gs[] = {0.1, 8, 100};
    for (int k = 0; k < 3; k++) {
        cant_run c;
        cantilever_run(gs[k], 40, V_K, 0, &c);
        double e = rel_err(c.ratio, c.ref.ratio);
        ck_assert_msg(fabs(e) < 5e-3, "Gamma %g: drop/reach %.10g, elastica %.10g (%.3g %%)",
                      gs[k], c.ratio, c.ref.ratio, 100 * e);
        ck_assert_msg(c.shape_err < 2e-3, "Gamma %g: shape off by %g L", gs[k], c.shape_err);
        ck_assert(c.max_strain < 1e-3);
    }
}
END_TEST

START_TEST(test_cantilever_convergence)
{
    /* second order in sigma (docs/model.md 5), and Richardson's extrapolation from
     * 20 and 40 particles lands on the elastica */
    cant_run c10, c20, c40;
    cantilever_run(8, 10, V_K, 0, &c10);
    cantilever_run(8, 20, V_K, 0, &c20);
    cantilever_run(8, 40, V_K, 0, &c40);
    double e10 = rel_err(c10.ratio, c10.ref.ratio), e20 = rel_err(c20.ratio, c20.ref.ratio),
           e40 = rel_err(c40.ratio, c40.ref.ratio);
    double p1 = log2(e10 / e20), p2 = log2(e20 / e40);
    ck_assert_msg(fabs(p1 - 2) < 0.15 && fabs(p2 - 2) < 0.15,
                  "errors %g %g %g: orders %g %g", e10, e20, e40, p1, p2);
    double rich = (4 * c40.ratio - c20.ratio) / 3;
    ck_assert_close_rel(rich, c40.ref.ratio, 5e-5);
    /* and the test sees the clamp: without the correction the strip is
     * about sigma/2 too long, an error of first order (~ 4 % here) */
    cant_run w40;
    cantilever_run(8, 40, V_K, 1, &w40);
    double ew = rel_err(w40.ratio, w40.ref.ratio);
    ck_assert_msg(ew > 0.02 && ew < 0.06, "whole clamp hinge: error %g", ew);
}
END_TEST

START_TEST(test_cantilever_astm)
{
    /* Gamma = 8: c = L / 2 exactly; ASTM reads 41.5 deg there */
    cant_run c;
    cantilever_run(8, 40, V_K, 0, &c);
    ck_assert_msg(fabs(c.chord_deg - 41.5) < 0.05, "chord %.4f deg", c.chord_deg);
    /* drape's reading (Peirce's formula) at that chord: the formula's
     * own value, 1.9 % above the true c = L/2 (docs/validation.md) */
    ck_assert_close_rel(c.c_peirce, elastica_peirce_c_over_l(c.chord_deg * M_PI / 180), 1e-12);
    ck_assert(c.c_peirce > 0.5 * 1.015 && c.c_peirce < 0.5 * 1.025);
}
END_TEST

START_TEST(test_catenary)
{
    /* issue 5: sag and end tension within 0.5 %: pins at the rest distance
     * (the cable must stretch to sag; k = 10 N/m: strain ~ 5 %), and the
     * right pin moved in to 80 % of the length with stiff k = 1e4 N/m */
    const double ks[2] = {10.0, V_K}, fr[2] = {1.0, 0.8};
    for (int c = 0; c < 2; c++) {
        cat_run r;
        catenary_run(0.3, 30, ks[c], fr[c], &r);
        ck_assert_msg(fabs(rel_err(r.sag, r.ref.sag)) < 5e-3, "k %g span %g: sag %.8g, ref %.8g",
                      ks[c], fr[c], r.sag, r.ref.sag);
        ck_assert_msg(fabs(rel_err(r.t_end, r.ref.t_end)) < 5e-3,
                      "k %g span %g: end tension %.8g, ref %.8g", ks[c], fr[c], r.t_end,
                      r.ref.t_end);
        ck_assert(r.shape_err < 5e-3 * r.ref.sag);
    }
}
END_TEST

static void load_fabric(const char *rel, drape_fabric *F)
{
    drape_error err;
    drape_error_clear(&err);
    ck_assert_msg(drape_fabric_load(tu_src(rel), F, &err, NULL, NULL) == 0, "fabric: %s",
                  err.msg);
}

START_TEST(test_kawabata_round_trip)
{
    /* the consistent form carries exactly the fit's moment and force
     * (docs/model.md 3.2, 3.3); issue 5 asks for 1 %, the form promises rounding */
    drape_fabric F;
    load_fabric("fabrics/cotton-breen.yaml", &F);
    patch P;
    patch_new(&P, &F, DRAPE_TERM_BEND, DRAPE_FORM_CONSISTENT);
    for (int d = 0; d < 2; d++)
        for (int k = 0; k < N_KAW_K; k++) {
            double K = kawabata_K[k];
            double Ms = patch_bend_moment(&P, (drape_dir)d, K);
            ck_assert_close_rel(Ms, drape_fit_value(&F.bend[d], K), 1e-8);
        }
    patch_free(&P);
    patch_new(&P, &F, DRAPE_TERM_SHEAR, DRAPE_FORM_CONSISTENT);
    for (int k = 0; k < N_KAW_G; k++) {
        double g = kawabata_g[k], Fs = patch_shear_force(&P, g);
        ck_assert_close_rel(Fs, drape_fit_value(&F.shear_mean, g), 1e-8);
        /* the model's isotropic mean lies between the input curves */
        double f0 = drape_fit_value(&F.shear[0], g), f1 = drape_fit_value(&F.shear[1], g);
        ck_assert(Fs >= fmin(f0, f1) * (1 - 1e-12) && Fs <= fmax(f0, f1) * (1 + 1e-12));
    }
    patch_free(&P);
    /* simulated: clamps on an arc, the strip settles, the clamp's couple */
    const double Ks[] = {30, 200};
    for (int d = 0; d < 2; d++)
        for (int k = 0; k < 2; k++) {
            bend_run b;
            bend_simulated(&F, (drape_dir)d, Ks[k], &b);
            /* measured: 1e-8 (the issue asks for 1 %) */
            ck_assert_close_rel(b.K_sim, Ks[k], 1e-6);
            ck_assert(b.K_spread < 1e-6);
            ck_assert_msg(fabs(rel_err(b.M_sim, b.M_fit)) < 1e-6, "dir %d K %g: M %.8g, fit %.8g",
                          d, Ks[k], b.M_sim, b.M_fit);
            ck_assert(b.net_force < 1e-5);
        }
    /* the seed form (eqs. 10, 11) does not round-trip: with K = psi / sigma
     * it stores sigma^2 K M(2K) per hinge; linear M = B K gives a moment
     * d/dK (2 B K^2) = 4 B K */
    fabric_linear(&F, 1e-5, V_K);
    patch_new(&P, &F, DRAPE_TERM_BEND, DRAPE_FORM_SEED);
    for (int d = 0; d < 2; d++)
        for (int k = 0; k < N_KAW_K; k++) {
            double K = kawabata_K[k];
            ck_assert_close_rel(patch_bend_moment(&P, (drape_dir)d, K), 4e-5 * K, 1e-8);
        }
    patch_free(&P);
}
END_TEST


START_TEST(test_chain_reference)
{
    /* the zeros of J0 against GSL's */
    for (int n = 1; n <= 5; n++) {
        ck_assert_close_rel(chain_j0_zero(n), gsl_sf_bessel_zero_J0((unsigned)n), 1e-14);
        ck_assert(fabs(gsl_sf_bessel_J0(chain_j0_zero(n))) < 1e-14);
    }
    /* two segments by hand (per unit width, sigma = L / 2, lambda =
     * omega^2 sigma / g): masses W sigma (1, 1/2), segment stiffnesses
     * T / sigma = W g (3/2, 1/2), so det([2 - l, -1/2; -1/2, (1 - l) / 2])
     * = 0, l^2 - 3 l + 3/2 = 0, l = (3 -+ sqrt 3) / 2 */
    double om[2];
    ck_assert_int_eq(chain_discrete(2, 1.0, 0.2, 9.0, 0.0, 2, om, NULL), 0);
    ck_assert_close_rel(om[0] * om[0] * 0.5 / 9.0, (3 - sqrt(3)) / 2, 1e-13);
    ck_assert_close_rel(om[1] * om[1] * 0.5 / 9.0, (3 + sqrt(3)) / 2, 1e-13);
    /* the lumped inextensible chain converges to Bernoulli's frequencies
     * at second order in sigma (errors quarter per halving) */
    double e[3][3];
    const int ns[3] = {40, 80, 160};
    for (int j = 0; j < 3; j++) {
        double w[3];
        ck_assert_int_eq(chain_discrete(ns[j], 0.3, 0.2, DRAPE_G_STANDARD, 0.0, 3, w, NULL), 0);
        for (int n = 0; n < 3; n++)
            e[j][n] = w[n] / chain_omega_continuous(n + 1, DRAPE_G_STANDARD, 0.3) - 1.0;
    }
    for (int n = 0; n < 3; n++) {
        ck_assert(e[0][n] < 0.0 && e[1][n] < 0.0 && e[2][n] < 0.0);
        ck_assert_msg(fabs(log2(e[1][n] / e[2][n]) - 2.0) < 0.1, "mode %d: errors %g %g", n + 1,
                      e[1][n], e[2][n]);
    }
    /* stretch lengthens the chain: lower frequencies, by about eps / 2 */
    double wk[3], w0[3];
    ck_assert_int_eq(chain_discrete(80, 0.3, 0.2, DRAPE_G_STANDARD, 1e2, 3, wk, NULL), 0);
    ck_assert_int_eq(chain_discrete(80, 0.3, 0.2, DRAPE_G_STANDARD, 0.0, 3, w0, NULL), 0);
    double eps_top = 0.2 * DRAPE_G_STANDARD * 0.3 / 1e2;
    ck_assert(wk[0] < w0[0] && w0[0] - wk[0] < 0.5 * eps_top * w0[0]);
}
END_TEST

START_TEST(test_chain_frequencies)
{
    /* issue 5 item 2: the first three frequencies from the HDF5 time series
     * within 0.5 % of (z_n / 2) sqrt(g / L); 80 segments (the lumped chain
     * is then 0.25 % low in mode 3), k = 1e3 N/m (stretch lowers them by
     * 1.6e-4); and the run reproduces the lumped chain's own frequencies
     * (measured to 1.2e-5: the fit's bias from the weakly excited modes 4+) */
    chain_run c;
    chain_run_once(80, 1e3, "gsl-rk8pd", 1e-9, 3.0, &c);
    ck_assert(c.static_force < 1e-8);
    ck_assert_msg(c.resid < 1e-2, "fit residual %g", c.resid);
    for (int n = 0; n < 3; n++) {
        ck_assert_msg(fabs(c.omega[n] / c.cont[n] - 1) < 5e-3, "mode %d: %.8g rad/s, continuum %.8g",
                      n + 1, c.omega[n], c.cont[n]);
        ck_assert_msg(fabs(c.omega[n] / c.disc[n] - 1) < 1e-4, "mode %d: %.8g rad/s, lumped %.8g",
                      n + 1, c.omega[n], c.disc[n]);
    }
}
END_TEST

START_TEST(test_energy_conservation)
{
    /* issue 5 item 4, short: 0.3 s of the 10 cm hang scene, every step
     * within the bound derived above energy_steps */
    const char *scene = "tests/data/validation/hang-energy.yaml";
    energy_run a, b, d;
    energy_steps(scene, 0.0, 1e-5, 0.3, &a);
    energy_steps(scene, 0.0, 1e-7, 0.3, &b);
    ck_assert(a.scale > 1e-4); /* it falls: E_kin reaches ~1e-3 J */
    ck_assert_msg(a.worst <= 1.0, "rtol 1e-5: |E - E0| reached %g of the bound", a.worst);
    ck_assert_msg(b.worst <= 1.0, "rtol 1e-7: |E - E0| reached %g of the bound", b.worst);
    /* tolerance proportionality: with error-per-step control a method of
     * order q >= 1 has global errors ~ tol^(q / (q + 1)), so 100 x tighter
     * tolerances cut the drift at least 10 x; asked: 5 x (measured 60 x) */
    ck_assert_msg(b.dev * 5.0 <= a.dev, "drift %g at rtol 1e-5, %g at 1e-7", a.dev, b.dev);
    /* with air drag the energy never increases (step by step, within each
     * step's share of the bound), and the drag visibly dissipates */
    energy_steps(scene, 0.5, 1e-5, 0.3, &d);
    ck_assert_msg(d.rise <= 1.0, "a step raised E by %g of its bound", d.rise);
    ck_assert(d.e_end < d.e0 - 0.05 * d.scale);
}
END_TEST

START_TEST(test_cusick_static)
{
    /* issue 5 item 5, fast part: the default Cusick scene at 2 cm has one
     * certified minimum whatever the perturbation seed; the seed form's
     * bending is 2.3-3.4 times stiffer (Table 8), so it drapes less: higher
     * DC, at 2 and 1 cm */
    drape_scene base;
    drape_fabric F;
    load_scene_file("scenes/cusick.yaml", &base, &F);
    double dc_cons[2] = {0, 0}, dc_seed[2] = {0, 0};
    for (int seed = 1; seed <= 3; seed++) {
        cusick_sol a, b;
        cusick_static(&base, &F, 0.02, DRAPE_FORM_CONSISTENT, seed, NULL, &a);
        cusick_static(&base, &F, 0.02, DRAPE_FORM_SEED, seed, NULL, &b);
        ck_assert(a.converged && a.certified && b.converged && b.certified);
        if (seed > 1) {
            ck_assert_close_abs(a.dc, dc_cons[0], 1e-3);
            ck_assert_close_abs(b.dc, dc_seed[0], 1e-3);
        }
        dc_cons[0] = a.dc;
        dc_seed[0] = b.dc;
        cusick_free(&a);
        cusick_free(&b);
    }
    cusick_sol a, b;
    cusick_static(&base, &F, 0.01, DRAPE_FORM_CONSISTENT, 1, NULL, &a);
    cusick_static(&base, &F, 0.01, DRAPE_FORM_SEED, 1, NULL, &b);
    ck_assert(a.converged && a.certified && b.converged && b.certified);
    dc_cons[1] = a.dc;
    dc_seed[1] = b.dc;
    cusick_free(&a);
    cusick_free(&b);
    for (int k = 0; k < 2; k++)
        ck_assert_msg(dc_seed[k] > dc_cons[k] + 0.05, "spacing %d: DC seed %g, consistent %g", k,
                      dc_seed[k], dc_cons[k]);
}
END_TEST

/* ---- full tables (DRAPE_VALIDATE_OUT) ------------------------------------
 * Markdown for docs/validation.md; every number below is computed here.
 * The table tests also assert the bounds, so `make validate` fails
 * when the sweep does. */

static void table_elastica(void)
{
    const double gs[] = {0.01, 0.1, 0.5, 1, 2, 5, 8, 10, 20, 50, 100, 200, 400};
    fprintf(vout, "\n### Table 1. The reference heavy elastica\n\n"
                  "| Gamma | M(0) L/B | reach/L | drop/L | drop/reach | chord (deg) | tip slope (deg) | (drop - series)/Gamma^5 |\n"
                  "|---|---|---|---|---|---|---|---|\n");
    for (int k = 0; k < (int)(sizeof gs / sizeof gs[0]); k++) {
        elastica_solution e;
        ck_assert_int_eq(elastica_solve(gs[k], &e), 0);
        double G = gs[k];
        char rem[32] = "-";
        if (G <= 0.5)
            snprintf(rem, sizeof rem, "%.3e", (e.tip_drop - (G / 8 - G * G * G / 640)) / pow(G, 5));
        fprintf(vout, "| %g | %.8f | %.8f | %.8f | %.8f | %.4f | %.4f | %s |\n", G, e.mu0,
                e.tip_x, e.tip_drop, e.ratio, e.chord * 180 / M_PI,
                e.tip_slope * 180 / M_PI, rem);
    }
}

static void table_cantilever(void)
{
    const double gs[] = {0.1, 0.2, 0.5, 1, 2, 5, 8, 10, 20, 50, 100};
    fprintf(vout, "\n### Table 2. drape against the elastica, 40 particles over the edge\n\n"
                  "| Gamma | drop/reach drape | drop/reach elastica | error | chord drape (deg) | chord elastica (deg) | shape error / L | max strain | steps | wall (s) |\n"
                  "|---|---|---|---|---|---|---|---|---|---|\n");
    for (int k = 0; k < (int)(sizeof gs / sizeof gs[0]); k++) {
        cant_run c;
        cantilever_run(gs[k], 40, V_K, 0, &c);
        double e = rel_err(c.ratio, c.ref.ratio);
        fprintf(vout, "| %g | %.7f | %.7f | %+.3f %% | %.3f | %.3f | %.1e | %.1e | %ld | %.2f |\n",
                gs[k], c.ratio, c.ref.ratio, 100 * e, c.chord_deg, c.ref.chord * 180 / M_PI,
                c.shape_err, c.max_strain, c.steps, c.wall_s);
        ck_assert_msg(fabs(e) < 5e-3, "Gamma %g: %g", gs[k], e);
    }
}

static void table_convergence(void)
{
    const double gs[] = {0.1, 1, 8, 100};
    const int nps[] = {10, 20, 40, 80};
    for (int variant = 0; variant < 2; variant++) {
        if (variant == 0)
            fprintf(vout, "\n### Table 3. Spacing convergence of drop/reach (clamp hinge: its overhanging half)\n\n");
        else
            fprintf(vout, "\n### Table 4. The same with the clamp hinge given its whole vertex length (no correction)\n\n");
        fprintf(vout, "| Gamma | 10 | 20 | 40 | 80 | orders | Richardson 40/80 |\n"
                      "|---|---|---|---|---|---|---|\n");
        for (int k = 0; k < 4; k++) {
            double e[4], r[4];
            for (int j = 0; j < 4; j++) {
                cant_run c;
                cantilever_run(gs[k], nps[j], V_K, variant, &c);
                r[j] = c.ratio;
                e[j] = rel_err(c.ratio, c.ref.ratio);
            }
            elastica_solution ref;
            ck_assert_int_eq(elastica_solve(gs[k], &ref), 0);
            double p = variant == 0 ? 2.0 : 1.0;
            double rich = (pow(2, p) * r[3] - r[2]) / (pow(2, p) - 1);
            fprintf(vout, "| %g | %+.4f %% | %+.4f %% | %+.4f %% | %+.4f %% | %.2f, %.2f, %.2f | %+.1e |\n",
                    gs[k], 100 * e[0], 100 * e[1], 100 * e[2], 100 * e[3], log2(e[0] / e[1]),
                    log2(e[1] / e[2]), log2(e[2] / e[3]), rel_err(rich, ref.ratio));
            if (variant == 0) ck_assert(fabs(log2(e[2] / e[3]) - 2) < 0.2);
        }
    }
}

static void table_stiffness(void)
{
    /* k = 1e6 N/m: the spring forces' share of atol (k sigma-weighted
     * 1e-8 m) exceeds the residual check 1e-4 m g; it would need atol
     * 1e-11 m */
    const double ks[] = {1e2, 1e3, 1e4, 1e5};
    fprintf(vout, "\n### Table 5. Stretch stiffness, Gamma = 8, 40 particles\n\n"
                  "| k (N/m) | max strain | drop/reach error | steps | wall (s) |\n|---|---|---|---|---|\n");
    for (int k = 0; k < 4; k++) {
        cant_run c;
        cantilever_run(8, 40, ks[k], 0, &c);
        fprintf(vout, "| %g | %.1e | %+.4f %% | %ld | %.2f |\n", ks[k], c.max_strain,
                100 * rel_err(c.ratio, c.ref.ratio), c.steps, c.wall_s);
    }
}

static void table_peirce(void)
{
    const double th[] = {5, 10, 20, 30, 40, 41.5, 45, 50, 60, 70, 80};
    fprintf(vout, "\n### Table 6. Bending length from the chord angle: exact elastica vs Peirce's f(theta)\n\n"
                  "| chord (deg) | Gamma (exact) | c/L exact = Gamma^(-1/3) | c/L Peirce | Peirce error in c | in B = W g c^3 |\n"
                  "|---|---|---|---|---|---|\n");
    for (int k = 0; k < (int)(sizeof th / sizeof th[0]); k++) {
        double G, t = th[k] * M_PI / 180;
        ck_assert_int_eq(elastica_gamma_for_chord(t, &G), 0);
        double ce = cbrt(1 / G), cp = elastica_peirce_c_over_l(t);
        fprintf(vout, "| %g | %.5f | %.5f | %.5f | %+.2f %% | %+.2f %% |\n", th[k], G, ce, cp,
                100 * rel_err(cp, ce), 100 * rel_err(cp * cp * cp, ce * ce * ce));
    }
    cant_run c;
    cantilever_run(8, 40, V_K, 0, &c);
    fprintf(vout, "\ndrape at Gamma = 8 (c = L/2 exactly), 40 particles: chord %.3f deg "
                  "(ASTM D1388 reads c = L/2 at 41.5 deg), Peirce's formula on that chord "
                  "c = %.5f L (%+.2f %%).\n", c.chord_deg, c.c_peirce,
            100 * rel_err(c.c_peirce, 0.5));
}

static void table_catenary(void)
{
    const double ks[] = {10, V_K, V_K}, fr[] = {1.0, 1.0, 0.8};
    const int ns[] = {10, 20, 40, 80};
    fprintf(vout, "\n### Table 7. Catenary, 30 cm strip pinned at both ends, W = 0.2 kg/m^2, no bending\n\n"
                  "| k (N/m) | span / length | segments | sag (mm) | sag error | end tension (N/m) | tension error | shape error / sag | steps | wall (s) |\n"
                  "|---|---|---|---|---|---|---|---|---|---|\n");
    for (int c = 0; c < 3; c++)
        for (int j = 0; j < 4; j++) {
            cat_run r;
            catenary_run(0.3, ns[j], ks[c], fr[c], &r);
            fprintf(vout, "| %g | %g | %d | %.4f (ref %.4f) | %+.4f %% | %.5f (ref %.5f) | %+.4f %% | %.1e | %ld | %.2f |\n",
                    ks[c], fr[c], ns[j], 1e3 * r.sag, 1e3 * r.ref.sag,
                    100 * rel_err(r.sag, r.ref.sag), r.t_end, r.ref.t_end,
                    100 * rel_err(r.t_end, r.ref.t_end), r.shape_err / r.ref.sag, r.steps,
                    r.wall_s);
        }
}

static void table_kawabata(void)
{
    drape_fabric F;
    load_fabric("fabrics/cotton-breen.yaml", &F);
    patch Pc, Ps;
    patch_new(&Pc, &F, DRAPE_TERM_BEND, DRAPE_FORM_CONSISTENT);
    patch_new(&Ps, &F, DRAPE_TERM_BEND, DRAPE_FORM_SEED);
    fprintf(vout, "\n### Table 8. Kawabata round trip, bending (cotton-breen, 2 x 2 cm patch at 2 mm)\n\n"
                  "| K (1/cm) | warp M input (gf.cm/cm) | consistent | simulated | seed / input | weft M input | consistent | simulated | seed / input |\n"
                  "|---|---|---|---|---|---|---|---|---|\n");
    const double gfcm = 9.80665e-3; /* N.m/m per gf.cm/cm */
    for (int k = 0; k < N_KAW_K; k++) {
        double K = kawabata_K[k];
        fprintf(vout, "| %.2f ", K / 100);
        for (int d = 1; d >= 0; d--) {
            double Min = drape_fit_value(&F.bend[d], K);
            double Mc = patch_bend_moment(&Pc, (drape_dir)d, K);
            double Ms = patch_bend_moment(&Ps, (drape_dir)d, K);
            bend_run b;
            bend_simulated(&F, (drape_dir)d, K, &b);
            fprintf(vout, "| %.5f | %+.1e | %+.1e | %.3f ", Min / gfcm, rel_err(Mc, Min),
                    rel_err(b.M_sim, b.M_fit), Ms / Min);
            ck_assert(fabs(rel_err(b.M_sim, b.M_fit)) < 1e-2);
        }
        fprintf(vout, "|\n");
    }
    patch_free(&Pc);
    patch_free(&Ps);
    patch_new(&Pc, &F, DRAPE_TERM_SHEAR, DRAPE_FORM_CONSISTENT);
    patch_new(&Ps, &F, DRAPE_TERM_SHEAR, DRAPE_FORM_SEED);
    fprintf(vout, "\n### Table 9. Kawabata round trip, shear (the model uses the mean of warp and weft)\n\n"
                  "| gamma (rad) | F mean input (gf/cm) | consistent | seed / input | warp vs mean | weft vs mean |\n"
                  "|---|---|---|---|---|---|\n");
    for (int k = 0; k < N_KAW_G; k++) {
        double g = kawabata_g[k], Fin = drape_fit_value(&F.shear_mean, g);
        double Fc = patch_shear_force(&Pc, g), Fs = patch_shear_force(&Ps, g);
        fprintf(vout, "| %.4f | %.4f | %+.1e | %.3f | %+.2f %% | %+.2f %% |\n", g,
                Fin / 0.980665, rel_err(Fc, Fin), Fs / Fin,
                100 * rel_err(drape_fit_value(&F.shear[DRAPE_WARP], g), Fin),
                100 * rel_err(drape_fit_value(&F.shear[DRAPE_WEFT], g), Fin));
        ck_assert(fabs(rel_err(Fc, Fin)) < 1e-8);
    }
    patch_free(&Pc);
    patch_free(&Ps);
}


static void table_chain(void)
{
    typedef struct { int n; double k; const char *integ; double rtol, atol; int order; } row;
    const double a0 = 1e-6 * V_CHAIN_A;
    const row rows[] = {{20, 1e3, "gsl-rk8pd", 1e-9, a0, 0},  {40, 1e3, "gsl-rk8pd", 1e-9, a0, 0},
                        {80, 1e3, "gsl-rk8pd", 1e-9, a0, 0},  {160, 1e3, "gsl-rk8pd", 1e-9, a0, 0},
                        {320, 1e3, "gsl-rk8pd", 1e-9, a0, 0}, {160, 1e2, "gsl-rk8pd", 1e-9, a0, 0},
                        {160, 1e4, "gsl-rk8pd", 1e-9, a0, 0}, {80, 1e3, "cvode-bdf", 1e-9, a0, 5},
                        {80, 1e3, "cvode-bdf", 1e-4, a0, 2},  {80, 1e3, "cvode-bdf", 1e-4, 1e-7, 2}};
    const int nrows = (int)(sizeof rows / sizeof rows[0]);
    fprintf(vout, "\n### Table 10. Hanging chain, L = %g cm: frequencies fitted to the HDF5 time series (3 s, frames every %g ms)\n\n"
                  "Continuum omega_n = (z_n / 2) sqrt(g / L) = %.6f, %.6f, %.6f rad/s. "
                  "`lumped chain`: the discrete chain's own frequencies (elastica.c), with the same k.\n\n"
                  "| segments | k (N/m) | integrator, rtol, atol (max order) | omega_1 fit (rad/s) | vs continuum | omega_2 fit | vs continuum | omega_3 fit | vs continuum | fit vs lumped chain (max) | lumped chain vs continuum (mode 1, 2, 3) | fit residual | steps | CPU s |\n"
                  "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
            100 * V_CHAIN_L, 1e3 * V_CHAIN_DT,
            chain_omega_continuous(1, DRAPE_G_STANDARD, V_CHAIN_L),
            chain_omega_continuous(2, DRAPE_G_STANDARD, V_CHAIN_L),
            chain_omega_continuous(3, DRAPE_G_STANDARD, V_CHAIN_L));
    double disc_err[5][3]; /* rows 0-4: fit error with the stretch shift taken out */
    for (int r = 0; r < nrows; r++) {
        chain_run c;
        chain_max_order = rows[r].order;
        chain_atol = rows[r].atol;
        chain_run_once(rows[r].n, rows[r].k, rows[r].integ, rows[r].rtol, 3.0, &c);
        double fd = 0.0, inext[3];
        ck_assert_int_eq(chain_discrete(rows[r].n, V_CHAIN_L, V_W, DRAPE_G_STANDARD, 0.0, 3,
                                        inext, NULL), 0);
        fprintf(vout, "| %d | %g | %s, %g, %.0e m%s%s%s ", rows[r].n, rows[r].k, rows[r].integ,
                rows[r].rtol, rows[r].atol, rows[r].order ? " (" : "",
                rows[r].order ? (rows[r].order == 5 ? "5" : "2") : "", rows[r].order ? ")" : "");
        for (int n = 0; n < 3; n++) {
            double e = c.omega[n] / c.cont[n] - 1;
            fd = fmax(fd, fabs(c.omega[n] / c.disc[n] - 1));
            if (r < 5) disc_err[r][n] = c.omega[n] / (c.cont[n] * c.disc[n] / inext[n]) - 1;
            fprintf(vout, "| %.7f | %+.4f %% ", c.omega[n], 100 * e);
            if (rows[r].atol <= a0 && rows[r].n >= 80) ck_assert(fabs(e) < 5e-3);
        }
        fprintf(vout, "| %.1e | %+.4f, %+.4f, %+.4f %% | %.1e | %ld | %.1f |\n", fd,
                100 * (c.disc[0] / c.cont[0] - 1), 100 * (c.disc[1] / c.cont[1] - 1),
                100 * (c.disc[2] / c.cont[2] - 1), c.resid, c.steps, c.cpu_s);
        if (rows[r].atol <= a0) ck_assert(fd < 1e-4);
    }
    chain_max_order = 5;
    chain_atol = a0;
    fprintf(vout, "\nObserved orders in the spacing (k = 1e3 N/m, 20-40-80-160-320 segments) of the "
                  "fitted frequencies' error against the continuum, with the stretch shift "
                  "(lumped chain at k over lumped chain at k = infinity, -1.7e-4 for mode 1) "
                  "taken out: ");
    for (int n = 0; n < 3; n++) {
        fprintf(vout, "%smode %d: ", n ? "; " : "", n + 1);
        for (int r = 0; r < 4; r++)
            fprintf(vout, "%s%.2f", r ? ", " : "", log2(disc_err[r][n] / disc_err[r + 1][n]));
    }
    fprintf(vout, ".\n");
}

/* ---- energy over 10 s with `drape run` ---- */

typedef struct h5_energy {
    int nf, n;
    double *t, *e;      /* frames; total energy per frame */
    double *ke;
    double stretch_end; /* stretch energy of the last frame, J */
    double b_mean;      /* mean over frames of sqrt(N) ||g o w|| */
} h5_energy;

/* Run `drape run SCENE --rtol R --atol A --out DIR` and read the frames'
 * energies (/energies/...) and states (/steps/...) from DIR/drape.h5. */
static void energy_drape_run(const char *rel, const char *integrator, double rtol, long *steps,
                             double *cpu, h5_energy *h)
{
    char dir[600], args[1400], out[8192], errb[4096];
    snprintf(dir, sizeof dir, "%s/energy", tu_scratch_dir());
    mkdir(dir, 0700);
    snprintf(args, sizeof args, "run %s --integrator %s --rtol %g --atol %g --out %s -q",
             tu_src(rel), integrator, rtol, 1e-2 * rtol, dir);
    struct rusage r0, r1;
    getrusage(RUSAGE_CHILDREN, &r0);
    int st = tu_run_drape(args, out, sizeof out, errb, sizeof errb);
    getrusage(RUSAGE_CHILDREN, &r1);
    *cpu = (double)(r1.ru_utime.tv_sec - r0.ru_utime.tv_sec) +
           1e-6 * (double)(r1.ru_utime.tv_usec - r0.ru_utime.tv_usec);
    ck_assert_msg(st == 0, "drape %s: %d %s", args, st, errb);
    const char *ps = strstr(out, "\"steps\": ");
    ck_assert_ptr_nonnull(ps);
    *steps = atol(ps + 9);

    char path[700];
    snprintf(path, sizeof path, "%s/drape.h5", dir);
    hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    ck_assert_msg(f >= 0, "cannot open %s", path);
    const char *names[5] = {"/energies/kinetic", "/energies/stretch", "/energies/bend",
                            "/energies/shear", "/energies/gravity"};
    int nf;
    h->t = h5_read(f, "/times", &h->nf, 1);
    h->e = drape_calloc((size_t)h->nf, sizeof(double));
    ck_assert_ptr_nonnull(h->e);
    for (int k = 0; k < 5; k++) {
        double *a = h5_read(f, names[k], &nf, 1);
        ck_assert_int_eq(nf, h->nf);
        for (int q = 0; q < nf; q++) h->e[q] += a[q];
        if (k == 1) h->stretch_end = a[nf - 1];
        if (k == 0) h->ke = a;
        else drape_free(a);
    }
    /* the bound's per-step share at every frame, with the scene's model */
    drape_scene s;
    drape_fabric F;
    load_scene_file(rel, &s, &F);
    drape_lattice *L;
    drape_model *m = scene_model(&s, &F, &L);
    int rows;
    double *x0 = h5_read(f, "/mesh/rest_positions", &rows, 3), ext = 0.0;
    ck_assert_int_eq(rows, L->n);
    for (int c = 0; c < 3; c++) { /* integrator.h: T = sqrt(extent / g) */
        double lo = INFINITY, hi = -INFINITY;
        for (int q = 0; q < rows; q++) {
            lo = fmin(lo, x0[3 * q + c]);
            hi = fmax(hi, x0[3 * q + c]);
        }
        ext = fmax(ext, hi - lo);
    }
    drape_free(x0);
    double T = sqrt(ext / DRAPE_G_STANDARD), *fv = drape_malloc(sizeof(double) * 3 * (size_t)L->n);
    ck_assert_ptr_nonnull(fv);
    h->b_mean = 0.0;
    unsigned cons = drape_model_parts(m) & (DRAPE_PART_STRETCH | DRAPE_PART_BEND |
                                            DRAPE_PART_SHEAR | DRAPE_PART_GRAVITY);
    for (int q = 0; q < h->nf; q++) {
        char name[64];
        snprintf(name, sizeof name, "/steps/%06d/positions", q);
        double *x = h5_read(f, name, &rows, 3);
        snprintf(name, sizeof name, "/steps/%06d/velocities", q);
        double *v = h5_read(f, name, &rows, 3);
        ck_assert_int_eq(drape_model_forces(m, cons, x, NULL, fv), 0);
        double s2 = 0.0, atol = 1e-2 * rtol;
        for (int p = 0; p < L->n; p++) {
            if (L->fixed[p]) continue;
            for (int c = 0; c < 3; c++) {
                double gx = fv[3 * p + c] * (rtol * fabs(x[3 * p + c]) + atol);
                double gv = L->mass[p] * v[3 * p + c] * (rtol * fabs(v[3 * p + c]) + atol / T);
                s2 += gx * gx + gv * gv;
            }
        }
        h->b_mean += sqrt(6.0 * L->n_free * s2) / h->nf;
        drape_free(x);
        drape_free(v);
    }
    H5Fclose(f);
    drape_free(fv);
    drape_model_free(m);
    drape_lattice_free(L);
}

static void h5_energy_free(h5_energy *h)
{
    drape_free(h->t);
    drape_free(h->e);
    drape_free(h->ke);
}

static void table_energy(void)
{
    const char *rel = "tests/data/validation/hang-energy.yaml";
    const double rtols[] = {1e-3, 1e-4, 1e-5, 1e-6, 1e-6};
    const char *integ[] = {"cvode-bdf", "cvode-bdf", "cvode-bdf", "cvode-bdf", "gsl-rk8pd"};
    const int nr = (int)(sizeof rtols / sizeof rtols[0]);
    fprintf(vout, "\n### Table 11. Energy over 10 s, `drape run %s --integrator I --rtol R --atol R x 1 cm` (no dissipation)\n\n"
                  "scale = the largest kinetic energy of the run; B = steps x the frames' mean of sqrt(N) |g o w| (an estimate of the bound, whose sum runs over the steps; derived for CVODE's error test only).\n\n"
                  "| integrator | rtol | steps | max abs(E - E(0)) / scale | (E(10 s) - E(0)) / scale | B / scale | max abs(E - E(0)) / B | stretch energy at 10 s / scale | scale (J) | CPU s |\n"
                  "|---|---|---|---|---|---|---|---|---|---|\n", rel);
    for (int r = 0; r < nr; r++) {
        long steps;
        double cpu;
        h5_energy h;
        energy_drape_run(rel, integ[r], rtols[r], &steps, &cpu, &h);
        double scale = 0.0, dev = 0.0;
        for (int q = 0; q < h.nf; q++) {
            scale = fmax(scale, h.ke[q]);
            dev = fmax(dev, fabs(h.e[q] - h.e[0]));
        }
        ck_assert_close_rel(h.t[h.nf - 1], 10.0, 1e-9);
        int bdf = strcmp(integ[r], "cvode-bdf") == 0;
        double B = (double)steps * h.b_mean;
        fprintf(vout, "| %s | %g | %ld | %.2e | %+.2e | ", integ[r], rtols[r], steps, dev / scale,
                (h.e[h.nf - 1] - h.e[0]) / scale);
        if (bdf) fprintf(vout, "%.2e | %.1e ", B / scale, dev / B);
        else fprintf(vout, "- | - ");
        fprintf(vout, "| %.1e | %.3e | %.1f |\n", h.stretch_end / scale, scale, cpu);
        fflush(vout);
        if (bdf) ck_assert(dev <= B); /* the bound is CVODE's error test's */
        h5_energy_free(&h);
    }
    const char *reld = "tests/data/validation/hang-energy-damped.yaml";
    long steps;
    double cpu;
    h5_energy h;
    energy_drape_run(reld, "cvode-bdf", 1e-5, &steps, &cpu, &h);
    double rise = -INFINITY, scale = 0.0;
    for (int q = 0; q < h.nf; q++) scale = fmax(scale, h.ke[q]);
    for (int q = 1; q < h.nf; q++) rise = fmax(rise, h.e[q] - h.e[q - 1]);
    fprintf(vout, "\nWith air drag 0.5 1/s (`%s`, rtol 1e-5, %ld steps, %.1f s CPU): "
                  "the largest change of E between consecutive frames is %+.2e of the scale "
                  "(never an increase), and E(10 s) - E(0) = %+.3f of it.\n",
            reld, steps, cpu, rise / scale, (h.e[h.nf - 1] - h.e[0]) / scale);
    ck_assert(rise <= 0.0);
    h5_energy_free(&h);
}

/* ---- Cusick ---- */

static const double cus_h[4] = {0.02, 0.01, 0.0075, 0.005};
#define CUS_SEEDS 8

static void table_cusick(void)
{
    drape_scene base;
    drape_fabric F;
    load_scene_file("scenes/cusick.yaml", &base, &F);
    const char *forms[2] = {"consistent", "seed"};
    fprintf(vout, "\n### Table 12. Cusick DC (`scenes/cusick.yaml`), static minima from %d perturbation seeds\n\n"
                  "Each entry: DC (nodes) of a distinct certified minimum and how many seeds (1-%d, amplitude 0.1 mm) reached it; `flat`: the unperturbed start.\n\n"
                  "| form | spacing (cm) | free particles | minima: DC (nodes) x seeds | DC range | flat start | CPU s per solve |\n"
                  "|---|---|---|---|---|---|---|\n", CUS_SEEDS, CUS_SEEDS);
    cusick_sol fine[2][CUS_SEEDS];
    for (int fm = 0; fm < 2; fm++)
        for (int k = 0; k < 4; k++) {
            double dcs[CUS_SEEDS], es[CUS_SEEDS], cpu = 0.0, lo = INFINITY, hi = -INFINITY;
            int nodes[CUS_SEEDS], nfree = 0;
            for (int sd = 0; sd < CUS_SEEDS; sd++) {
                cusick_sol c;
                cusick_static(&base, &F, cus_h[k], (drape_energy_form)fm, sd + 1, NULL, &c);
                ck_assert_msg(c.converged && c.certified, "%s %g cm seed %d: not a certified minimum",
                              forms[fm], 100 * cus_h[k], sd + 1);
                dcs[sd] = c.dc;
                es[sd] = c.energy;
                nodes[sd] = c.nodes;
                cpu += c.cpu_s / CUS_SEEDS;
                nfree = c.L->n_free;
                lo = fmin(lo, c.dc);
                hi = fmax(hi, c.dc);
                if (k == 3) fine[fm][sd] = c;
                else cusick_free(&c);
            }
            cusick_sol flat;
            cusick_static(&base, &F, cus_h[k], (drape_energy_form)fm, -1, NULL, &flat);
            fprintf(vout, "| %s | %g | %d | ", forms[fm], 100 * cus_h[k], nfree);
            int done[CUS_SEEDS] = {0};
            for (int a = 0; a < CUS_SEEDS; a++) {
                if (done[a]) continue;
                int cnt = 0;
                for (int b = a; b < CUS_SEEDS; b++)
                    if (!done[b] && fabs(es[b] - es[a]) <= 1e-7 * fabs(es[a]) &&
                        fabs(dcs[b] - dcs[a]) < 1e-4) {
                        done[b] = 1;
                        cnt++;
                    }
                fprintf(vout, "%.4f (%d) x %d; ", dcs[a], nodes[a], cnt);
            }
            fprintf(vout, "| %.4f - %.4f | %.4f (%d)%s | %.2f |\n", lo, hi, flat.dc, flat.nodes,
                    !flat.converged ? ", not converged" : flat.certified ? "" : ", saddle", cpu);
            fflush(vout);
            cusick_free(&flat);
        }

    /* follow minima found at 0.5 cm to the coarser lattices */
    fprintf(vout, "\n### Table 13. Minima found at 0.5 cm followed to coarser lattices (interpolated start, then the static solver)\n\n"
                  "| form | start (seed at 0.5 cm) | 2 cm | 1 cm | 0.75 cm | 0.5 cm | 0.25 cm | observed order from 1, 0.75, 0.5 cm | from 0.75, 0.5, 0.25 cm |\n"
                  "|---|---|---|---|---|---|---|---|---|\n");
    for (int fm = 0; fm < 2; fm++) {
        int used[CUS_SEEDS] = {0};
        for (int a = 0; a < CUS_SEEDS; a++) {
            /* one representative per distinct minimum */
            int dup = 0;
            for (int b = 0; b < a; b++)
                if (used[b] && fabs(fine[fm][b].energy - fine[fm][a].energy) <=
                                   1e-7 * fabs(fine[fm][a].energy))
                    dup = 1;
            if (dup) continue;
            used[a] = 1;
            double d[4];
            int nd[4];
            fprintf(vout, "| %s | seed %d |", forms[fm], a + 1);
            for (int k = 0; k < 3; k++) {
                cusick_sol c;
                cusick_static(&base, &F, cus_h[k], (drape_energy_form)fm, -1, &fine[fm][a], &c);
                d[k] = c.dc;
                nd[k] = c.converged ? c.nodes : -1;
                fprintf(vout, " %.4f (%d)%s |", c.dc, c.nodes,
                        !c.converged ? " not converged" : c.certified ? "" : " saddle");
                cusick_free(&c);
            }
            d[3] = fine[fm][a].dc;
            nd[3] = fine[fm][a].nodes;
            fprintf(vout, " %.4f (%d) |", d[3], nd[3]);
            /* a minimum that keeps its node count from 1 to 0.5 cm is also
             * followed to 0.25 cm (about 20 s) */
            int same = nd[1] == nd[3] && nd[2] == nd[3];
            double d4[3] = {d[2], d[3], 0.0};
            int nd4 = -1;
            if (same) {
                cusick_sol c;
                cusick_static(&base, &F, 0.0025, (drape_energy_form)fm, -1, &fine[fm][a], &c);
                d4[2] = c.dc;
                nd4 = c.nodes;
                fprintf(vout, " %.4f (%d)%s |", c.dc, c.nodes,
                        c.certified ? (c.converged ? "" : " stalled, certified") : " not certified");
                cusick_free(&c);
            } else {
                fprintf(vout, " - |");
            }
            double p, lim;
            if (same && observed_order(cus_h + 1, d + 1, &p, &lim) == 0)
                fprintf(vout, " %.2f (limit %.4f) |", p, lim);
            else
                fprintf(vout, " - (%s) |",
                        nd[1] < 0 || nd[2] < 0 ? "not converged"
                        : same ? "no power law" : "node counts differ");
            const double h4[3] = {0.0075, 0.005, 0.0025};
            if (same && nd4 == nd[3] && observed_order(h4, d4, &p, &lim) == 0)
                fprintf(vout, " %.2f (limit %.4f) |\n", p, lim);
            else
                fprintf(vout, " %s |\n", !same ? "-" : nd4 != nd[3] ? "- (node counts differ)"
                                                                    : "- (no power law)");
            fflush(vout);
        }
        for (int sd = 0; sd < CUS_SEEDS; sd++) cusick_free(&fine[fm][sd]);
    }
}

START_TEST(test_full_tables)
{
    const char *path = getenv("DRAPE_VALIDATE_OUT");
    ck_assert_ptr_nonnull(path);
    vout = fopen(path, "w");
    ck_assert_msg(vout != NULL, "cannot write %s", path);
    double t0 = wall_now();
    table_elastica();
    table_cantilever();
    table_convergence();
    table_stiffness();
    table_peirce();
    table_catenary();
    table_kawabata();
    table_chain();
    table_energy();
    table_cusick();
    fprintf(vout, "\n(tables computed in %.0f s)\n", wall_now() - t0);
    fclose(vout);
    vout = NULL;
}
END_TEST

Suite *validation_suite(void);
Suite *validation_suite(void)
{
    Suite *s = suite_create("validation");
    TCase *tr = tcase_create("references");
    tcase_set_timeout(tr, 60);
    tcase_add_test(tr, test_elastica_small_gamma);
    tcase_add_test(tr, test_elastica_moment_balance);
    tcase_add_test(tr, test_elastica_astm_rule);
    tcase_add_test(tr, test_catenary_reference);
    suite_add_tcase(s, tr);
    TCase *tc = tcase_create("cantilever");
    tcase_set_timeout(tc, 60);
    tcase_add_test(tc, test_cantilever_elastica);
    tcase_add_test(tc, test_cantilever_convergence);
    tcase_add_test(tc, test_cantilever_astm);
    suite_add_tcase(s, tc);
    TCase *tk = tcase_create("catenary_kawabata");
    tcase_set_timeout(tk, 60);
    tcase_add_test(tk, test_catenary);
    tcase_add_test(tk, test_kawabata_round_trip);
    suite_add_tcase(s, tk);
    TCase *td = tcase_create("dynamics");
    tcase_set_timeout(td, 60);
    tcase_add_test(td, test_chain_reference);
    tcase_add_test(td, test_chain_frequencies);
    tcase_add_test(td, test_energy_conservation);
    tcase_add_test(td, test_cusick_static);
    suite_add_tcase(s, td);
    if (getenv("DRAPE_VALIDATE_OUT")) {
        TCase *tf = tcase_create("full");
        tcase_set_timeout(tf, 7200);
        tcase_add_test(tf, test_full_tables);
        suite_add_tcase(s, tf);
    }
    return s;
}
