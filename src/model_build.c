/* model_build.c: construction of a particle model (model.h): the sparse
 * patterns of K, D and the first-order J made of full 3x3 blocks, every
 * element's block slots, the segment cache, and drape_model_new / free.
 * The storage scheme is described at the top of model.c; the evaluation
 * of energies, forces and Jacobians is there too. */
#include "drape/model.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "drape/alloc.h"
#include "drape/units.h"
#include "model_impl.h"

/* ------------------------------------------------------------ patterns */

static int cmp_int(const void *a, const void *b)
{
    int x = *(const int *)a, y = *(const int *)b;
    return (x > y) - (x < y);
}

/* Append the block pairs (column = free id of particle j, row = of i) of
 * an element of np particles to pc/pr. */
static void push_pairs(const drape_lattice *L, const int *ids, int np,
                       int *pc, int *pr, int64_t *n)
{
    for (int i = 0; i < np; i++) {
        for (int j = 0; j < np; j++) {
            int fi = L->free_id[ids[i]], fj = L->free_id[ids[j]];
            if (fi < 0 || fj < 0) continue;
            pc[*n] = fj;
            pr[*n] = fi;
            (*n)++;
        }
    }
}

/* Block CSC (nf block columns) of the elements selected, with every
 * diagonal block.  Allocates *bcol (nf + 1) and *brow. */
static int build_blocks(const drape_lattice *L, int edges, int hinges,
                        int corners, int cells, int64_t **bcol, int **brow)
{
    int nf = L->n_free;
    int64_t cap = (int64_t)nf + (edges ? 4 * (int64_t)L->n_edges : 0) +
                  (hinges ? 9 * (int64_t)L->n_hinges : 0) +
                  (corners ? 9 * (int64_t)L->n_corners : 0) +
                  (cells ? 16 * (int64_t)L->n_cells : 0);
    int64_t n = 0, *cnt = NULL;
    int *pc = NULL, *pr = NULL, *rows = NULL;
    int ids[3];
    int rc = -1;

    *bcol = NULL;
    *brow = NULL;
    pc = drape_malloc(sizeof(int) * (size_t)cap);
    pr = drape_malloc(sizeof(int) * (size_t)cap);
    rows = drape_malloc(sizeof(int) * (size_t)cap);
    cnt = drape_calloc((size_t)nf + 1, sizeof(int64_t));
    if (!pc || !pr || !rows || !cnt) goto out;

    for (int q = 0; q < nf; q++) {
        pc[n] = q;
        pr[n] = q;
        n++;
    }
    if (edges)
        for (int e = 0; e < L->n_edges; e++) {
            ids[0] = L->edges[e].a; ids[1] = L->edges[e].b;
            push_pairs(L, ids, 2, pc, pr, &n);
        }
    if (hinges)
        for (int h = 0; h < L->n_hinges; h++) {
            ids[0] = L->hinges[h].prev; ids[1] = L->hinges[h].mid;
            ids[2] = L->hinges[h].next;
            push_pairs(L, ids, 3, pc, pr, &n);
        }
    if (corners)
        for (int c = 0; c < L->n_corners; c++) {
            ids[0] = L->corners[c].mid; ids[1] = L->corners[c].warp;
            ids[2] = L->corners[c].weft;
            push_pairs(L, ids, 3, pc, pr, &n);
        }
    if (cells)
        for (int c = 0; c < L->n_cells; c++) push_pairs(L, L->cells[c].p, 4, pc, pr, &n);
    /* counting sort by column */
    for (int64_t k = 0; k < n; k++) cnt[pc[k] + 1]++;
    for (int q = 0; q < nf; q++) cnt[q + 1] += cnt[q];
    for (int64_t k = 0; k < n; k++) rows[cnt[pc[k]]++] = pr[k];
    for (int q = nf; q > 0; q--) cnt[q] = cnt[q - 1];
    cnt[0] = 0;
    /* sort and deduplicate each column in place, compacting */
    int64_t w = 0;
    for (int q = 0; q < nf; q++) {
        int64_t b = cnt[q], e = cnt[q + 1];
        qsort(rows + b, (size_t)(e - b), sizeof(int), cmp_int);
        cnt[q] = w;
        for (int64_t k = b; k < e; k++)
            if (k == b || rows[k] != rows[k - 1]) rows[w++] = rows[k];
    }
    cnt[nf] = w;
    *brow = drape_malloc(sizeof(int) * (size_t)(w > 0 ? w : 1));
    if (!*brow) goto out;
    memcpy(*brow, rows, sizeof(int) * (size_t)w);
    *bcol = cnt;
    cnt = NULL;
    rc = 0;
out:
    drape_free(pc);
    drape_free(pr);
    drape_free(rows);
    drape_free(cnt);
    return rc;
}

/* Scalar CSC of a block CSC: every block is a full 3x3. */
static int expand_blocks(int nf, const int64_t *bcol, const int *brow,
                         drape_pattern *P)
{
    int64_t N = 3 * (int64_t)nf, nnz = 9 * bcol[nf];
    P->n = N;
    P->nnz = nnz;
    P->colptr = drape_malloc(sizeof(int64_t) * (size_t)(N + 1));
    P->rowind = drape_malloc(sizeof(int64_t) * (size_t)(nnz > 0 ? nnz : 1));
    if (!P->colptr || !P->rowind) return -1;
    int64_t k = 0;
    for (int q = 0; q < nf; q++) {
        for (int c = 0; c < 3; c++) {
            P->colptr[3 * q + c] = k;
            for (int64_t t = bcol[q]; t < bcol[q + 1]; t++)
                for (int r = 0; r < 3; r++) P->rowind[k++] = 3 * (int64_t)brow[t] + r;
        }
    }
    P->colptr[N] = k;
    return 0;
}

/* Position t of block row p in block column q, or -1. */
static int64_t find_block(const int64_t *bcol, const int *brow, int q, int p)
{
    int64_t lo = bcol[q], hi = bcol[q + 1];
    while (lo < hi) {
        int64_t mid = lo + (hi - lo) / 2;
        if (brow[mid] < p) lo = mid + 1;
        else hi = mid;
    }
    return lo < bcol[q + 1] && brow[lo] == p ? lo : -1;
}

/* Slot of block (row particle i, column particle j) in the scalar pattern
 * expanded from the block pattern, or -1 if either is fixed. */
static int64_t block_slot(const drape_lattice *L, const int64_t *bcol,
                          const int *brow, int i, int j)
{
    int p = L->free_id[i], q = L->free_id[j];
    if (p < 0 || q < 0) return -1;
    int64_t t = find_block(bcol, brow, q, p);
    if (t < 0) return -1; /* cannot happen: every pair was pushed */
    return 9 * bcol[q] + 3 * (t - bcol[q]);
}

static int64_t *element_slots(const drape_lattice *L, const int64_t *bcol,
                              const int *brow, int nel, int np,
                              void (*ids_of)(const drape_lattice *, int, int *))
{
    int64_t *s = drape_malloc(sizeof(int64_t) * (size_t)(nel > 0 ? np * np * (int64_t)nel : 1));
    int ids[4];
    if (!s) return NULL;
    for (int e = 0; e < nel; e++) {
        ids_of(L, e, ids);
        for (int i = 0; i < np; i++)
            for (int j = 0; j < np; j++)
                s[(int64_t)np * np * e + np * i + j] = block_slot(L, bcol, brow, ids[i], ids[j]);
    }
    return s;
}

static void edge_ids(const drape_lattice *L, int e, int *ids)
{
    ids[0] = L->edges[e].a;
    ids[1] = L->edges[e].b;
}

static void cell_ids(const drape_lattice *L, int c, int *ids)
{
    memcpy(ids, L->cells[c].p, sizeof L->cells[c].p);
}

static void hinge_ids(const drape_lattice *L, int h, int *ids)
{
    ids[0] = L->hinges[h].prev;
    ids[1] = L->hinges[h].mid;
    ids[2] = L->hinges[h].next;
}

static void corner_ids(const drape_lattice *L, int c, int *ids)
{
    ids[0] = L->corners[c].mid;
    ids[1] = L->corners[c].warp;
    ids[2] = L->corners[c].weft;
}

/* First-order pattern: x columns [diag; N + K rows], v columns
 * [identity; N + D rows] with D rows = the blocks of the edge dashpots and
 * of the shear-damped corners + diagonal blocks when either is built, else
 * the diagonal alone. */
static int build_first_order(drape_model *m, const int64_t *dcol, const int *drow)
{
    const drape_pattern *P = &m->pat;
    drape_pattern *J = &m->pat1;
    int64_t N = m->N, nnz = 0, k = 0;
    int blocks = dcol != NULL; /* D has off-diagonal blocks */

    for (int64_t j = 0; j < N; j++) {
        nnz += 1 + (P->colptr[j + 1] - P->colptr[j]);
        nnz += 1 + (blocks ? 3 * (dcol[j / 3 + 1] - dcol[j / 3]) : 1);
    }
    J->n = 2 * N;
    J->nnz = nnz;
    J->colptr = drape_malloc(sizeof(int64_t) * (size_t)(2 * N + 1));
    J->rowind = drape_malloc(sizeof(int64_t) * (size_t)(nnz > 0 ? nnz : 1));
    m->kmap = drape_malloc(sizeof(int64_t) * (size_t)(P->nnz > 0 ? P->nnz : 1));
    m->dmap = drape_malloc(sizeof(int64_t) * (size_t)(P->nnz > 0 ? P->nnz : 1));
    m->jid = drape_malloc(sizeof(int64_t) * (size_t)(N > 0 ? N : 1));
    if (!J->colptr || !J->rowind || !m->kmap || !m->dmap || !m->jid) return -1;
    for (int64_t j = 0; j < N; j++) {
        J->colptr[j] = k;
        J->rowind[k++] = j;
        for (int64_t t = P->colptr[j]; t < P->colptr[j + 1]; t++) {
            m->kmap[t] = k;
            J->rowind[k++] = N + P->rowind[t];
        }
    }
    for (int64_t j = 0; j < N; j++) {
        int64_t start = k;
        J->colptr[N + j] = k;
        m->jid[j] = k;
        J->rowind[k++] = j;
        if (blocks) {
            int q = (int)(j / 3);
            for (int64_t t = dcol[q]; t < dcol[q + 1]; t++)
                for (int r = 0; r < 3; r++) J->rowind[k++] = N + 3 * (int64_t)drow[t] + r;
        } else {
            J->rowind[k++] = N + j;
        }
        /* map each K-pattern entry of column j to its D position, if any */
        for (int64_t t = P->colptr[j]; t < P->colptr[j + 1]; t++) {
            int64_t row = N + P->rowind[t], lo = start + 1, hi = k;
            while (lo < hi) {
                int64_t mid = lo + (hi - lo) / 2;
                if (J->rowind[mid] < row) lo = mid + 1;
                else hi = mid;
            }
            m->dmap[t] = lo < k && J->rowind[lo] == row ? lo : -1;
        }
    }
    J->colptr[2 * N] = k;
    return 0;
}

static int cmp_i64(const void *a, const void *b)
{
    int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
    return (x > y) - (x < y);
}

/* Segment ref of the edge vector x_to - x_from (keys: sorted lo * n + hi). */
static int seg_ref(const int64_t *keys, int nseg, int n, int from, int to)
{
    int lo = from < to ? from : to, hi = from < to ? to : from;
    int64_t key = (int64_t)lo * n + hi;
    const int64_t *k = bsearch(&key, keys, (size_t)nseg, sizeof *keys, cmp_i64);
    return 2 * (int)(k - keys) + (to == hi ? 0 : 1);
}

/* The segment cache's pairs and each element's refs (struct drape_model). */
static int build_segments(drape_model *m, int edges, int hinges, int corners)
{
    const drape_lattice *L = m->L;
    int64_t n = L->n, cap = 0, nk = 0;
    if (edges) cap += L->n_edges;
    if (hinges) cap += 2 * (int64_t)L->n_hinges;
    if (corners) cap += 2 * (int64_t)L->n_corners;
    int64_t *keys = drape_malloc(sizeof *keys * (size_t)(cap > 0 ? cap : 1));
    if (!keys) return -1;
#define SEG_KEY(p, q) ((p) < (q) ? (int64_t)(p) * n + (q) : (int64_t)(q) * n + (p))
    if (edges)
        for (int e = 0; e < L->n_edges; e++) keys[nk++] = SEG_KEY(L->edges[e].a, L->edges[e].b);
    if (hinges)
        for (int h = 0; h < L->n_hinges; h++) {
            const drape_hinge *H = &L->hinges[h];
            keys[nk++] = SEG_KEY(H->prev, H->mid);
            keys[nk++] = SEG_KEY(H->mid, H->next);
        }
    if (corners)
        for (int c = 0; c < L->n_corners; c++) {
            const drape_corner *C = &L->corners[c];
            keys[nk++] = SEG_KEY(C->mid, C->warp);
            keys[nk++] = SEG_KEY(C->mid, C->weft);
        }
#undef SEG_KEY
    if (nk > 0) qsort(keys, (size_t)nk, sizeof *keys, cmp_i64);
    int64_t ns = 0;
    for (int64_t k = 0; k < nk; k++)
        if (ns == 0 || keys[k] != keys[ns - 1]) keys[ns++] = keys[k];
    size_t z = (size_t)(ns > 0 ? ns : 1);
    m->nseg = (int)ns;
    m->seg_ab = drape_malloc(sizeof(int) * 2 * z);
    m->seg_d = drape_malloc(sizeof(double) * 3 * z);
    m->seg_u = drape_malloc(sizeof(double) * 3 * z);
    m->seg_l = drape_malloc(sizeof(double) * z);
    m->seg_bad = drape_malloc(z);
    if (edges) m->eref = drape_malloc(sizeof(int) * (size_t)(L->n_edges > 0 ? L->n_edges : 1));
    if (hinges) m->href = drape_malloc(sizeof(int) * 2 * (size_t)(L->n_hinges > 0 ? L->n_hinges : 1));
    if (corners) m->cref = drape_malloc(sizeof(int) * 2 * (size_t)(L->n_corners > 0 ? L->n_corners : 1));
    if (!m->seg_ab || !m->seg_d || !m->seg_u || !m->seg_l || !m->seg_bad ||
        (edges && !m->eref) || (hinges && !m->href) || (corners && !m->cref)) {
        drape_free(keys);
        return -1;
    }
    for (int64_t s = 0; s < ns; s++) {
        m->seg_ab[2 * s] = (int)(keys[s] / n);
        m->seg_ab[2 * s + 1] = (int)(keys[s] % n);
    }
    int nsi = (int)ns, ni = (int)n;
    if (edges)
        for (int e = 0; e < L->n_edges; e++)
            m->eref[e] = seg_ref(keys, nsi, ni, L->edges[e].a, L->edges[e].b);
    if (hinges)
        for (int h = 0; h < L->n_hinges; h++) {
            const drape_hinge *H = &L->hinges[h];
            m->href[2 * h] = seg_ref(keys, nsi, ni, H->prev, H->mid);
            m->href[2 * h + 1] = seg_ref(keys, nsi, ni, H->mid, H->next);
        }
    if (corners)
        for (int c = 0; c < L->n_corners; c++) {
            const drape_corner *C = &L->corners[c];
            m->cref[2 * c] = seg_ref(keys, nsi, ni, C->mid, C->warp);
            m->cref[2 * c + 1] = seg_ref(keys, nsi, ni, C->mid, C->weft);
        }
    drape_free(keys);
    return 0;
}

static int check_lattice(const drape_lattice *L)
{
    int n = L->n;
    if (!(L->sigma > 0.0) || n < 0 || L->n_free < 0 || L->n_free > n) return -1;
    for (int e = 0; e < L->n_edges; e++) {
        const drape_edge *E = &L->edges[e];
        if (E->a < 0 || E->a >= n || E->b < 0 || E->b >= n || E->a == E->b ||
            (E->dir != DRAPE_WARP && E->dir != DRAPE_WEFT))
            return -1;
    }
    for (int h = 0; h < L->n_hinges; h++) {
        const drape_hinge *H = &L->hinges[h];
        if (H->prev < 0 || H->prev >= n || H->mid < 0 || H->mid >= n ||
            H->next < 0 || H->next >= n ||
            (H->dir != DRAPE_WARP && H->dir != DRAPE_WEFT))
            return -1;
    }
    for (int c = 0; c < L->n_corners; c++) {
        const drape_corner *C = &L->corners[c];
        if (C->mid < 0 || C->mid >= n || C->warp < 0 || C->warp >= n ||
            C->weft < 0 || C->weft >= n)
            return -1;
    }
    for (int q = 0; q < L->n_free; q++) {
        int id = L->free_to_id[q];
        if (id < 0 || id >= n || L->free_id[id] != q || !(L->mass[id] > 0.0))
            return -1;
    }
    return 0;
}

void drape_model_diagonal_slots(const drape_model *m, long *slots)
{
    for (int q = 0; q < m->nf; q++)
        for (int c = 0; c < 3; c++)
            slots[3 * q + c] = (long)(m->dslot[q] + c * m->colstride[q] + c);
}

drape_model *drape_model_new(const drape_lattice *L, const drape_fabric *F,
                             const drape_model_opts *o, drape_error *err)
{
    drape_model *m = NULL;
    int64_t *bcol = NULL, *dcol = NULL;
    int *brow = NULL, *drow = NULL;

    if (!L || !F || !o) {
        drape_error_set(err, DRAPE_E_INTERNAL, NULL, 0, 0, NULL,
                        "drape_model_new: NULL argument");
        return NULL;
    }
    if (check_lattice(L)) {
        drape_error_set(err, DRAPE_E_INTERNAL, NULL, 0, 0, NULL,
                        "drape_model_new: inconsistent lattice (ids, sigma or masses)");
        return NULL;
    }
    if (!(o->c_air >= 0.0) || !(o->c_edge >= 0.0) ||
        !(o->beta_shear >= 0.0 || o->beta_shear == DRAPE_SCENE_DAMPING_SHEAR_FABRIC) ||
        !(F->damping_shear >= 0.0) ||
        !isfinite(o->c_air) || !isfinite(o->c_edge) || !isfinite(o->beta_shear) ||
        !isfinite(F->damping_shear) ||
        !isfinite(o->g)) {
        drape_error_set(err, DRAPE_E_INPUT, NULL, 0, 0, NULL,
                        "damping and gravity must be finite and >= 0 (c_air %g, c_edge %g, "
                        "beta_shear %g, g %g)",
                        o->c_air, o->c_edge, o->beta_shear, o->g);
        return NULL;
    }
    m = drape_calloc(1, sizeof *m);
    if (!m) goto nomem;
    m->L = L;
    m->F = *F;
    m->o = *o;
    if (m->o.beta_shear < 0.0) m->o.beta_shear = F->damping_shear; /* the fabric's */
    m->parts = o->terms & (DRAPE_PART_STRETCH | DRAPE_PART_BEND |
                           DRAPE_PART_SHEAR | DRAPE_PART_GRAVITY);
    if (o->c_air > 0.0) m->parts |= DRAPE_PART_AIR;
    if (o->c_edge > 0.0) m->parts |= DRAPE_PART_EDGE;
    /* shear damping acts on the lattice's shear corners (built when the
     * scene has the shear term or sets damping.shear) */
    if (m->o.beta_shear > 0.0 && L->n_corners > 0) m->parts |= DRAPE_PART_SHEAR_DAMPING;
    m->shear_g0 = fmax(drape_fit_slope(&m->F.shear_mean, 0.0), 0.0);
    m->nf = L->n_free;
    m->N = 3 * (int64_t)L->n_free;

    int use_edges = (m->parts & (DRAPE_PART_STRETCH | DRAPE_PART_EDGE)) != 0;
    int use_hinges = (m->parts & DRAPE_PART_BEND) != 0;
    int use_corners = (m->parts & (DRAPE_PART_SHEAR | DRAPE_PART_SHEAR_DAMPING)) != 0;
    /* twist cells belong to bending */
    int use_cells = use_hinges && L->n_cells > 0 && m->F.has_bias;
    m->use_cells = use_cells;
    if (build_blocks(L, use_edges, use_hinges, use_corners, use_cells, &bcol, &brow))
        goto nomem;
    if (expand_blocks(m->nf, bcol, brow, &m->pat)) goto nomem;

    m->colstride = drape_malloc(sizeof(int64_t) * (size_t)(m->nf > 0 ? m->nf : 1));
    m->dslot = drape_malloc(sizeof(int64_t) * (size_t)(m->nf > 0 ? m->nf : 1));
    m->invm_row = drape_malloc(sizeof(double) * (size_t)(m->N > 0 ? m->N : 1));
    m->rowsum = drape_malloc(sizeof(double) * (size_t)(m->N > 0 ? m->N : 1));
    m->Kw = drape_malloc(sizeof(double) * (size_t)(m->pat.nnz > 0 ? m->pat.nnz : 1));
    m->Dw = drape_malloc(sizeof(double) * (size_t)(m->pat.nnz > 0 ? m->pat.nnz : 1));
    if (!m->colstride || !m->dslot || !m->invm_row || !m->rowsum || !m->Kw || !m->Dw)
        goto nomem;
    for (int q = 0; q < m->nf; q++) {
        int id = L->free_to_id[q];
        m->colstride[q] = 3 * (bcol[q + 1] - bcol[q]);
        m->dslot[q] = block_slot(L, bcol, brow, id, id);
        for (int k = 0; k < 3; k++) m->invm_row[3 * q + k] = 1.0 / L->mass[id];
    }
    if (use_edges) {
        m->eslot = element_slots(L, bcol, brow, L->n_edges, 2, edge_ids);
        if (!m->eslot) goto nomem;
    }
    if (use_hinges) {
        m->hslot = element_slots(L, bcol, brow, L->n_hinges, 3, hinge_ids);
        if (!m->hslot) goto nomem;
    }
    if (use_corners) {
        m->cslot = element_slots(L, bcol, brow, L->n_corners, 3, corner_ids);
        if (!m->cslot) goto nomem;
    }
    if (use_cells) {
        m->qslot = element_slots(L, bcol, brow, L->n_cells, 4, cell_ids);
        if (!m->qslot) goto nomem;
    }
    if (build_segments(m, use_edges, use_hinges, use_corners)) goto nomem;
    if (m->parts & (DRAPE_PART_EDGE | DRAPE_PART_SHEAR_DAMPING)) {
        if (build_blocks(L, (m->parts & DRAPE_PART_EDGE) != 0, 0,
                         (m->parts & DRAPE_PART_SHEAR_DAMPING) != 0, 0, &dcol, &drow))
            goto nomem;
    }
    if (build_first_order(m, dcol, drow)) goto nomem;
    goto out;

nomem:
    drape_error_set(err, DRAPE_E_NOMEM, NULL, 0, 0, NULL,
                    "out of memory building the model of %d particles",
                    L->n);
    drape_model_free(m);
    m = NULL;
out:
    drape_free(bcol);
    drape_free(brow);
    drape_free(dcol);
    drape_free(drow);
    return m;
}

void drape_model_free(drape_model *m)
{
    if (!m) return;
    drape_free(m->pat.colptr);
    drape_free(m->pat.rowind);
    drape_free(m->pat1.colptr);
    drape_free(m->pat1.rowind);
    drape_free(m->colstride);
    drape_free(m->dslot);
    drape_free(m->eslot);
    drape_free(m->hslot);
    drape_free(m->cslot);
    drape_free(m->qslot);
    drape_free(m->kmap);
    drape_free(m->dmap);
    drape_free(m->jid);
    drape_free(m->invm_row);
    drape_free(m->Kw);
    drape_free(m->Dw);
    drape_free(m->rowsum);
    drape_free(m->seg_ab);
    drape_free(m->eref);
    drape_free(m->href);
    drape_free(m->cref);
    drape_free(m->seg_d);
    drape_free(m->seg_u);
    drape_free(m->seg_l);
    drape_free(m->seg_bad);
    drape_free(m);
}
