/* diagnose.c: numerical faults of a state (diagnose.h; docs/reliability.md).
 *
 * Strain of a stretch edge (a, b) at positions x (the definition of
 * drape_model_max_strain, docs/model.md 3.1):
 *     eps = | |x_b - x_a| - sigma | / sigma                               (1)
 * Total energy (docs/model.md 3, 4):
 *     E = 1/2 sum m_i |v_i|^2 + E_stretch + E_bend + E_shear + E_gravity  (2)
 * With fixed particles at rest and only dissipative non-conservative
 * forces (air drag -c m v, edge dashpots, docs/model.md 3.6), dE/dt <= 0, so
 *     E(t) - E(0) > gain x scale                                          (3)
 * can only be a numerical blow-up; scale = M g L + sum |E_k(0)|.
 */
#include "drape/diagnose.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "drape/alloc.h"
#include "drape/units.h"

static double kinetic(const drape_lattice *L, const double *v)
{
    double e = 0.0;
    if (!v) return 0.0;
    for (int i = 0; i < L->n; i++) {
        const double *q = v + 3 * i;
        e += 0.5 * L->mass[i] * (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
    }
    return e;
}

static double total(const drape_energies *E, double kin)
{
    return kin + E->stretch + E->bend + E->shear + E->gravity;
}

void drape_diag_ref_init(drape_model *m, const double *x, const double *v,
                         drape_diag_ref *ref)
{
    const drape_lattice *L = drape_model_lattice(m);
    memset(ref, 0, sizeof *ref);
    if (drape_model_energy(m, x, &ref->E) != 0) return; /* folded: no check */
    ref->kinetic_J = kinetic(L, v);
    ref->energy_J = total(&ref->E, ref->kinetic_J);
    double ext = 0.0;
    for (int c = 0; c < 3; c++) {
        double lo = 0.0, hi = 0.0;
        for (int i = 0; i < L->n; i++) {
            double q = L->x0[3 * i + c];
            if (i == 0 || q < lo) lo = q;
            if (i == 0 || q > hi) hi = q;
        }
        if (hi - lo > ext) ext = hi - lo;
    }
    double mgl = (drape_model_parts(m) & DRAPE_PART_GRAVITY)
                     ? L->mass_total * DRAPE_G_STANDARD * ext : 0.0;
    ref->scale_J = mgl + fabs(ref->kinetic_J) + fabs(ref->E.stretch) +
                   fabs(ref->E.bend) + fabs(ref->E.shear) + fabs(ref->E.gravity);
    ref->valid = isfinite(ref->energy_J) && isfinite(ref->scale_J) && ref->scale_J > 0.0;
}

static void locate(const drape_lattice *L, int id, int *i, int *j)
{
    *i = id >= 0 ? L->gi[id] : -1;
    *j = id >= 0 ? L->gj[id] : -1;
}

static void clear(drape_diagnosis *d, double t)
{
    memset(d, 0, sizeof *d);
    d->kind = DRAPE_DIAG_NONE;
    d->t = t;
    d->term = "";
    d->particle = d->i = d->j = -1;
    d->other = d->oi = d->oj = -1;
    d->component = -1;
}

/* Most strained stretch edge (1); *edge = -1 when there is none. */
static double max_strain(const drape_lattice *L, const double *x, int *edge)
{
    double worst = 0.0;
    *edge = -1;
    for (int k = 0; k < L->n_edges; k++) {
        const double *a = x + 3 * L->edges[k].a, *b = x + 3 * L->edges[k].b;
        double d0 = b[0] - a[0], d1 = b[1] - a[1], d2 = b[2] - a[2];
        double eps = fabs(sqrt(d0 * d0 + d1 * d1 + d2 * d2) - L->sigma) / L->sigma;
        if (*edge < 0 || eps > worst) {
            worst = eps;
            *edge = k;
        }
    }
    return worst;
}

static void set_edge(const drape_lattice *L, int k, drape_diagnosis *d)
{
    if (k < 0) return;
    d->particle = L->edges[k].a;
    d->other = L->edges[k].b;
    locate(L, d->particle, &d->i, &d->j);
    locate(L, d->other, &d->oi, &d->oj);
}

/* Particle with the largest force of one part (allocates a workspace). */
static int largest_force(drape_model *m, unsigned part, const double *x)
{
    const drape_lattice *L = drape_model_lattice(m);
    double *f = drape_malloc(sizeof(double) * (size_t)(3 * L->n + 1));
    int best = -1;
    double fmax = -1.0;
    if (!f) return -1;
    drape_model_forces(m, part, x, NULL, f); /* 1 (folded): f still finite */
    for (int i = 0; i < L->n; i++) {
        if (L->fixed[i]) continue;
        const double *q = f + 3 * i;
        double a = q[0] * q[0] + q[1] * q[1] + q[2] * q[2];
        if (!isfinite(a)) a = INFINITY;
        if (a > fmax) {
            fmax = a;
            best = i;
        }
    }
    drape_free(f);
    return best;
}

/* The first conservative part whose force is not finite at x (x finite). */
static const char *nonfinite_part(drape_model *m, const double *x)
{
    static const struct { unsigned part; const char *name; } parts[] = {
        {DRAPE_PART_STRETCH, "stretch"}, {DRAPE_PART_BEND, "bend"},
        {DRAPE_PART_SHEAR, "shear"}, {DRAPE_PART_GRAVITY, "gravity"}};
    const drape_lattice *L = drape_model_lattice(m);
    unsigned have = drape_model_parts(m);
    double *f = drape_malloc(sizeof(double) * (size_t)(3 * L->n + 1));
    const char *hit = NULL;
    if (!f) return NULL;
    for (size_t k = 0; k < sizeof parts / sizeof parts[0] && !hit; k++) {
        if (!(have & parts[k].part)) continue;
        drape_model_forces(m, parts[k].part, x, NULL, f);
        for (int i = 0; i < 3 * L->n && !hit; i++)
            if (!isfinite(f[i])) hit = parts[k].name;
    }
    drape_free(f);
    return hit;
}

static int check_finite(drape_model *m, const double *x, const double *v,
                        drape_diagnosis *d)
{
    const drape_lattice *L = drape_model_lattice(m);
    const double *arr[2] = {x, v};
    for (int w = 0; w < 2; w++) {
        if (!arr[w]) continue;
        for (int k = 0; k < 3 * L->n; k++) {
            if (isfinite(arr[w][k])) continue;
            d->kind = DRAPE_DIAG_NONFINITE;
            d->term = w == 0 ? "position" : "velocity";
            d->particle = k / 3;
            d->component = k % 3;
            d->value = arr[w][k];
            locate(L, d->particle, &d->i, &d->j);
            if (w == 1) { /* positions finite: which force is not? */
                const char *p = nonfinite_part(m, x);
                if (p) d->term = p;
            }
            return 1;
        }
    }
    return 0;
}

int drape_diagnose(drape_model *m, double t, const double *x, const double *v,
                   double strain_limit, double energy_gain,
                   const drape_diag_ref *ref, drape_diagnosis *d)
{
    const drape_lattice *L = drape_model_lattice(m);
    int edge;
    clear(d, t);
    if (check_finite(m, x, v, d)) return 1;

    double eps = max_strain(L, x, &edge);
    if (strain_limit > 0.0 && edge >= 0 && eps > strain_limit) {
        d->kind = DRAPE_DIAG_STRAIN;
        d->term = "stretch";
        d->value = eps;
        d->limit = strain_limit;
        set_edge(L, edge, d);
        return 1;
    }

    drape_energies E;
    if (!(energy_gain > 0.0) || !ref || !ref->valid) return 0;
    if (drape_model_energy(m, x, &E) != 0) return 0; /* folded: the solver's business */
    double kin = kinetic(L, v);
    double gain = total(&E, kin) - ref->energy_J, lim = energy_gain * ref->scale_J;
    if (!(gain > lim)) return 0;
    d->kind = DRAPE_DIAG_ENERGY;
    d->value = gain;
    d->limit = lim;
    /* the term that grew most */
    const double rise[5] = {kin - ref->kinetic_J, E.stretch - ref->E.stretch,
                            E.bend - ref->E.bend, E.shear - ref->E.shear,
                            E.gravity - ref->E.gravity};
    static const char *const names[5] = {"kinetic", "stretch", "bend", "shear", "gravity"};
    static const unsigned part[5] = {0, DRAPE_PART_STRETCH, DRAPE_PART_BEND,
                                     DRAPE_PART_SHEAR, DRAPE_PART_GRAVITY};
    int w = 0;
    for (int k = 1; k < 5; k++)
        if (rise[k] > rise[w]) w = k;
    d->term = names[w];
    if (w == 0 && v) { /* the fastest particle */
        double s2 = -1.0;
        for (int i = 0; i < L->n; i++) {
            const double *q = v + 3 * i;
            double a = q[0] * q[0] + q[1] * q[1] + q[2] * q[2];
            if (a > s2) {
                s2 = a;
                d->particle = i;
            }
        }
        locate(L, d->particle, &d->i, &d->j);
    } else if (w == 1) {
        set_edge(L, edge, d);
    } else if (w > 1) {
        d->particle = largest_force(m, part[w], x);
        locate(L, d->particle, &d->i, &d->j);
    }
    return 1;
}

static void particle_text(char *buf, size_t n, int id, int i, int j)
{
    if (id < 0) snprintf(buf, n, "an unknown particle");
    else snprintf(buf, n, "particle %d (i %d, j %d)", id, i, j);
}

char *drape_diagnosis_format(const drape_diagnosis *d, char *buf, size_t n)
{
    static const char *const axis[3] = {"x", "y", "z"};
    char p[64], q[64];
    if (!buf || n == 0) return buf;
    particle_text(p, sizeof p, d->particle, d->i, d->j);
    particle_text(q, sizeof q, d->other, d->oi, d->oj);
    switch (d->kind) {
    case DRAPE_DIAG_NONFINITE: {
        int state = strcmp(d->term, "position") == 0 || strcmp(d->term, "velocity") == 0;
        snprintf(buf, n, "non-finite %s (%s = %g) of %s at t = %.9g s%s%s%s",
                 strcmp(d->term, "position") == 0 ? "position" : "velocity",
                 d->component >= 0 && d->component < 3 ? axis[d->component] : "?",
                 d->value, p, d->t, state ? "" : "; the ", state ? "" : d->term,
                 state ? "" : " force is not finite there");
        break;
    }
    case DRAPE_DIAG_STRAIN:
        snprintf(buf, n, "strain %.4g of the stretch edge between %s and %s exceeds the "
                 "limit %.4g at t = %.9g s", d->value, p, q, d->limit, d->t);
        break;
    case DRAPE_DIAG_ENERGY:
        if (d->other >= 0)
            snprintf(buf, n, "energy blow-up at t = %.9g s: the total energy rose by %.4g J "
                     "(limit %.4g J), most in the %s term, at the edge between %s and %s",
                     d->t, d->value, d->limit, d->term, p, q);
        else
            snprintf(buf, n, "energy blow-up at t = %.9g s: the total energy rose by %.4g J "
                     "(limit %.4g J), most in the %s term, largest at %s",
                     d->t, d->value, d->limit, d->term, p);
        break;
    default:
        snprintf(buf, n, "no numerical fault at t = %.9g s", d->t);
        break;
    }
    return buf;
}
