/* lattice_check.c: questions asked of a built lattice (lattice.h): its
 * invariants (drape_lattice_check: ids in range, weights in (0, 1], lumped
 * ones up to 64, neighbours one lattice step apart, masses and numbering
 * consistent; used by the model's constructor and by the tests on every
 * lattice they build) and its extent (drape_lattice_extent). */
#include "drape/lattice.h"

#include <math.h>

/* ---- invariants -------------------------------------------------------- */

static int bad_id(const drape_lattice *L, int p) { return p < 0 || p >= L->n; }

static int bad_weight(double w) { return !(w > 0.0 && w <= 1.0); }
/* hinges and cells of an oblique strip may carry lumped edge area (L6) */
static int bad_lumped_weight(double w) { return !(w > 0.0 && w <= 64.0); }

/* 1 unless q is the neighbour of p at step (di, dj) in the grid and at
 * distance sigma in the rest state. */
static int bad_neighbour(const drape_lattice *L, int p, int q, int di, int dj)
{
    if (bad_id(L, p) || bad_id(L, q)) return 1;
    if (L->gi[q] - L->gi[p] != di || L->gj[q] - L->gj[p] != dj) return 1;
    double d2 = 0.0;
    for (int k = 0; k < 3; k++) {
        double d = L->x0[3 * q + k] - L->x0[3 * p + k];
        d2 += d * d;
    }
    return fabs(sqrt(d2) - L->sigma) > 1e-9 * L->sigma;
}

double drape_lattice_extent(const drape_lattice *L)
{
    double ext = 0.0;
    for (int c = 0; c < 3; c++) {
        double lo = INFINITY, hi = -INFINITY;
        for (int i = 0; i < L->n; i++) {
            double q = L->x0[3 * i + c];
            if (q < lo) lo = q;
            if (q > hi) hi = q;
        }
        if (L->n > 0 && hi - lo > ext) ext = hi - lo;
    }
    return ext > 0.0 ? ext : L->sigma;
}

int drape_lattice_check(const drape_lattice *L)
{
    int bad = 0;
    if (!L) return 1;
    if (!(L->sigma > 0.0) || L->ni < 1 || L->nj < 1 || L->n < 1) return 1;
    if (!L->grid || !L->gi || !L->gj || !L->x0 || !L->xinit || !L->mass
        || !L->fixed || !L->free_id || (L->n_free > 0 && !L->free_to_id))
        return 1;

    /* grid <-> particles */
    int count = 0;
    for (long k = 0; k < (long)L->ni * L->nj; k++) {
        int p = L->grid[k];
        if (p < -1 || p >= L->n) bad++;
        else if (p >= 0) {
            count++;
            if ((long)L->gj[p] * L->ni + L->gi[p] != k) bad++;
        }
    }
    if (count != L->n) bad++;

    /* per particle */
    int nfree = 0;
    double msum = 0.0;
    for (int p = 0; p < L->n; p++) {
        if (L->gi[p] < 0 || L->gi[p] >= L->ni || L->gj[p] < 0
            || L->gj[p] >= L->nj)
            bad++;
        if (!(L->mass[p] > 0.0) || !isfinite(L->mass[p])) bad++;
        msum += L->mass[p];
        for (int k = 0; k < 3; k++)
            if (!isfinite(L->x0[3 * p + k]) || !isfinite(L->xinit[3 * p + k]))
                bad++;
        if (L->x0[3 * p + 2] != 0.0) bad++;
        if (L->fixed[p] > 1) bad++;
        if (L->fixed[p]) {
            if (L->free_id[p] != -1) bad++;
            for (int k = 0; k < 3; k++)
                if (L->xinit[3 * p + k] != L->x0[3 * p + k]) bad++;
        } else {
            int f = L->free_id[p];
            if (f != nfree || f >= L->n_free || L->free_to_id[f] != p) bad++;
            nfree++;
            if (L->xinit[3 * p] != L->x0[3 * p]
                || L->xinit[3 * p + 1] != L->x0[3 * p + 1])
                bad++;
        }
    }
    if (nfree != L->n_free) bad++;
    if (fabs(msum - L->mass_total) > 1e-12 * fabs(msum)) bad++;

    /* elements */
    if (L->n_edges < 0 || L->n_hinges < 0 || L->n_corners < 0) return bad + 1;
    if ((L->n_edges && !L->edges) || (L->n_hinges && !L->hinges)
        || (L->n_corners && !L->corners))
        return bad + 1;
    for (int e = 0; e < L->n_edges; e++) {
        const drape_edge *E = &L->edges[e];
        int d = E->dir == DRAPE_WARP;
        if (E->a >= E->b) bad++;
        if (bad_neighbour(L, E->a, E->b, !d, d)) { bad++; continue; }
        if (bad_weight(E->weight)) bad++;
        if (L->fixed[E->a] && L->fixed[E->b]) bad++;
    }
    for (int h = 0; h < L->n_hinges; h++) {
        const drape_hinge *H = &L->hinges[h];
        int d = H->dir == DRAPE_WARP;
        if (bad_neighbour(L, H->prev, H->mid, !d, d)
            || bad_neighbour(L, H->mid, H->next, !d, d)) {
            bad++;
            continue;
        }
        /* length 0 stands for 1 (lattice.h) */
        if (bad_lumped_weight(H->weight) || (H->length != 0.0 && bad_weight(H->length)))
            bad++;
        if (L->fixed[H->prev] && L->fixed[H->mid] && L->fixed[H->next]) bad++;
    }
    for (int c = 0; c < L->n_corners; c++) {
        const drape_corner *C = &L->corners[c];
        if (bad_id(L, C->mid) || bad_id(L, C->warp) || bad_id(L, C->weft)) {
            bad++;
            continue;
        }
        int dj = L->gj[C->warp] - L->gj[C->mid];
        int di = L->gi[C->weft] - L->gi[C->mid];
        if ((dj != 1 && dj != -1) || (di != 1 && di != -1)
            || bad_neighbour(L, C->mid, C->warp, 0, dj)
            || bad_neighbour(L, C->mid, C->weft, di, 0)) {
            bad++;
            continue;
        }
        if (bad_weight(C->weight)) bad++;
        if (L->fixed[C->mid] && L->fixed[C->warp] && L->fixed[C->weft]) bad++;
    }
    if (L->n_cells < 0 || (L->n_cells && !L->cells)) return bad + 1;
    for (int c = 0; c < L->n_cells; c++) {
        const drape_cell *Q = &L->cells[c];
        int nfix = 0;
        if (bad_id(L, Q->p[0]) || bad_id(L, Q->p[1]) || bad_id(L, Q->p[2]) ||
            bad_id(L, Q->p[3])) {
            bad++;
            continue;
        }
        if (bad_neighbour(L, Q->p[0], Q->p[1], 1, 0) || bad_neighbour(L, Q->p[1], Q->p[2], 0, 1) ||
            bad_neighbour(L, Q->p[3], Q->p[2], 1, 0) || bad_neighbour(L, Q->p[0], Q->p[3], 0, 1))
            bad++;
        if (bad_lumped_weight(Q->weight)) bad++;
        for (int k = 0; k < 4; k++) nfix += L->fixed[Q->p[k]];
        if (nfix == 4) bad++;
    }
    return bad;
}
