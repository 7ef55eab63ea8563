/* heliodon — minimum-cost transportation problem by the network simplex
 * method (transport.h).  Nodes 0..na-1 are the sources, na..na+nb-1 the
 * sinks; the basis is a spanning tree of na+nb-1 source-sink arcs, kept
 * as a list of arcs and re-rooted at node 0 after every pivot (parent,
 * depth and potentials by a breadth-first walk: O(na+nb) per pivot, small
 * next to the pricing for the sizes of lobe sets). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "transport.h"

typedef struct tp_arc { int i, j; double x; } tp_arc;   /* source i, sink j (0-based), flow */

typedef struct tp_pair { double c; int i, j; } tp_pair;

static int cmp_tp_pair(const void *pa, const void *pb)
{
    const tp_pair *p = pa, *q = pb;
    if (p->c != q->c) return p->c < q->c ? -1 : 1;
    if (p->i != q->i) return p->i - q->i;
    return p->j - q->j;
}

typedef struct tp_tree {
    int n, na, nb;
    tp_arc *arc;             /* n-1 basic arcs */
    int *deg, *adj;          /* CSR adjacency: arc indices per node */
    int *parent, *parc, *depth, *queue;
    double *pot;
} tp_tree;

/* parent, parc (arc to the parent), depth and potentials from the arcs */
static void tp_rebuild(tp_tree *t, const double *c)
{
    int n = t->n, na = t->na, nb = t->nb;
    memset(t->deg, 0, (size_t)(n + 1) * sizeof(int));
    for (int k = 0; k < n - 1; k++) {
        t->deg[t->arc[k].i + 1]++;
        t->deg[na + t->arc[k].j + 1]++;
    }
    for (int k = 0; k < n; k++) t->deg[k + 1] += t->deg[k];
    int *fill = t->queue;    /* borrowed as the fill pointers */
    for (int k = 0; k < n; k++) fill[k] = t->deg[k];
    for (int k = 0; k < n - 1; k++) {
        t->adj[fill[t->arc[k].i]++] = k;
        t->adj[fill[na + t->arc[k].j]++] = k;
    }
    for (int k = 0; k < n; k++) t->parent[k] = -2;
    int head = 0, tail = 0;
    t->queue[tail++] = 0;
    t->parent[0] = -1;
    t->parc[0] = -1;
    t->depth[0] = 0;
    t->pot[0] = 0;
    while (head < tail) {
        int x = t->queue[head++];
        for (int q = t->deg[x]; q < t->deg[x + 1]; q++) {
            const tp_arc *e = &t->arc[t->adj[q]];
            int y = x < na ? na + e->j : e->i;
            if (t->parent[y] != -2) continue;
            t->parent[y] = x;
            t->parc[y] = t->adj[q];
            t->depth[y] = t->depth[x] + 1;
            t->pot[y] = c[(size_t)e->i * nb + e->j] - t->pot[x];
            t->queue[tail++] = y;
        }
    }
}

hd_status hd_transport_solve(int na, int nb, const double *a, const double *b, const double *c,
                             double *flow, double *u, double *v, long *npivots)
{
    if (npivots) *npivots = 0;
    if (na <= 0 || nb <= 0) return HD_OK;
    size_t np = (size_t)na * nb;
    int n = na + nb;
    tp_tree t = {.n = n, .na = na, .nb = nb};
    tp_pair *pp = hd_malloc_array(np, sizeof *pp);
    double *ra = hd_malloc_array((size_t)na, sizeof(double)), *rb = hd_malloc_array((size_t)nb, sizeof(double));
    int *uf = hd_malloc_array((size_t)n, sizeof(int));
    t.arc = hd_malloc_array((size_t)n, sizeof *t.arc);
    t.deg = hd_malloc_array((size_t)n + 1, sizeof(int));
    t.adj = hd_malloc_array((size_t)2 * n, sizeof(int));
    t.parent = hd_malloc_array((size_t)n, sizeof(int));
    t.parc = hd_malloc_array((size_t)n, sizeof(int));
    t.depth = hd_malloc_array((size_t)n, sizeof(int));
    t.queue = hd_malloc_array((size_t)n + 1, sizeof(int));
    t.pot = hd_malloc_array((size_t)n, sizeof(double));
    int *path = hd_malloc_array((size_t)n + 1, sizeof(int));
    hd_status st = HD_OK;
    if (!pp || !ra || !rb || !uf || !t.arc || !t.deg || !t.adj || !t.parent || !t.parc || !t.depth ||
        !t.queue || !t.pot || !path) {
        st = HD_ERR_NOMEM;
        goto done;
    }
    /* balance: demands scaled to the supplies' total */
    double sa = 0, sb = 0, cmax = 0;
    for (int i = 0; i < na; i++) sa += ra[i] = a[i] > 0 ? a[i] : 0;
    for (int j = 0; j < nb; j++) sb += rb[j] = b[j] > 0 ? b[j] : 0;
    if (sb > 0)
        for (int j = 0; j < nb; j++) rb[j] *= sa / sb;
    for (size_t q = 0; q < np; q++) {
        pp[q].c = c[q];
        pp[q].i = (int)(q / (size_t)nb);
        pp[q].j = (int)(q % (size_t)nb);
        if (fabs(c[q]) > cmax) cmax = fabs(c[q]);
    }
    qsort(pp, np, sizeof *pp, cmp_tp_pair);
    /* initial basis: the greedy least-cost plan (a forest: every component
     * keeps at most one node with supply or demand left), completed to a
     * spanning tree by the cheapest zero-flow arcs between components */
    for (int k = 0; k < n; k++) uf[k] = k;
    int nar = 0;
    double dust = 1e-13 * (sa > 0 ? sa : 1);
    for (size_t q = 0; q < np && nar < n - 1; q++) {
        int i = pp[q].i, j = pp[q].j;
        if (ra[i] <= 0 || rb[j] <= 0) continue;
        double amt = ra[i] < rb[j] ? ra[i] : rb[j];
        if (ra[i] - amt <= dust) ra[i] = 0; else ra[i] -= amt;
        if (rb[j] - amt <= dust) rb[j] = 0; else rb[j] -= amt;
        t.arc[nar++] = (tp_arc){i, j, amt};
        uf[hd_uf_find(uf, i)] = hd_uf_find(uf, na + j);
    }
    for (size_t q = 0; q < np && nar < n - 1; q++) {
        int i = pp[q].i, j = pp[q].j;
        int ri = hd_uf_find(uf, i), rj = hd_uf_find(uf, na + j);
        if (ri == rj) continue;
        t.arc[nar++] = (tp_arc){i, j, 0};
        uf[ri] = rj;
    }
    free(pp);
    pp = NULL;
    /* pivots */
    double tol = 1e-10 * (cmax > 0 ? cmax : 1);
    size_t block = (size_t)sqrt((double)np);
    if (block < 32) block = 32;
    if (block > np) block = np;
    size_t pos = 0;
    long piv = 0, limit = 200L * n + 100000L;
    for (;;) {
        tp_rebuild(&t, c);
        /* entering arc: the most negative reduced cost of the first block
         * (scanned cyclically from where the last search stopped) that has one */
        double best = -tol;
        size_t bq = np, seen = 0;
        while (seen < np) {
            size_t e = seen + block < np ? block : np - seen;
            int i = (int)(pos / (size_t)nb), j = (int)(pos % (size_t)nb);
            for (size_t k = 0; k < e; k++) {
                double rc = c[pos] - t.pot[i] - t.pot[na + j];
                if (rc < best) { best = rc; bq = pos; }
                if (++pos == np) { pos = 0; i = 0; j = 0; }
                else if (++j == nb) { j = 0; i++; }
            }
            seen += e;
            if (bq < np) break;
        }
        if (bq == np) break;                 /* optimal */
        if (piv >= limit) { st = HD_ERR_RANGE; break; }
        piv++;
        int ei = (int)(bq / (size_t)nb), ej = (int)(bq % (size_t)nb);
        /* the cycle: entering arc ei -> ej, then the tree path from sink ej
         * up to the apex and down to source ei.  On the sink's side an arc
         * whose lower node is a sink is traversed backwards (its flow
         * decreases), on the source's side one whose lower node is a source. */
        int x = ei, y = na + ej;
        int nx = 0, ny = 0;              /* path[0..nx-1]: nodes below the apex on ei's side;
                                          * path[n - ny .. n-1]: on ej's side */
        while (t.depth[x] > t.depth[y]) { path[nx++] = x; x = t.parent[x]; }
        while (t.depth[y] > t.depth[x]) { path[n - ++ny] = y; y = t.parent[y]; }
        while (x != y) {
            path[nx++] = x; x = t.parent[x];
            path[n - ++ny] = y; y = t.parent[y];
        }
        double theta = HUGE_VAL;
        int leave = -1, lside = 0;
        /* strongly-feasible rule: of the blocking arcs, the last one met
         * going round the cycle from the apex in the entering arc's
         * direction: the one nearest the apex on the sink's side, else
         * the one nearest ei on the source's side */
        for (int k = 0; k < nx; k++)
            if (path[k] < na) {
                double f = t.arc[t.parc[path[k]]].x;
                if (f < theta) { theta = f; leave = path[k]; lside = 0; }
            }
        for (int k = n - 1; k >= n - ny; k--)     /* from ej upwards */
            if (path[k] >= na) {
                double f = t.arc[t.parc[path[k]]].x;
                if (f <= theta) { theta = f; leave = path[k]; lside = 1; }
            }
        (void)lside;
        if (leave < 0) { st = HD_ERR_INTERNAL; break; }
        for (int k = 0; k < nx; k++) t.arc[t.parc[path[k]]].x += path[k] < na ? -theta : theta;
        for (int k = n - ny; k < n; k++) t.arc[t.parc[path[k]]].x += path[k] >= na ? -theta : theta;
        int la = t.parc[leave];
        t.arc[la] = (tp_arc){ei, ej, theta};
    }
    if (npivots) *npivots = piv;
    if (st == HD_OK || st == HD_ERR_RANGE) {
        memset(flow, 0, np * sizeof(double));
        for (int k = 0; k < n - 1; k++) flow[(size_t)t.arc[k].i * nb + t.arc[k].j] += t.arc[k].x;
        if (u)
            for (int i = 0; i < na; i++) u[i] = t.pot[i];
        if (v)
            for (int j = 0; j < nb; j++) v[j] = t.pot[na + j];
    }
done:
    free(pp); free(ra); free(rb); free(uf); free(t.arc); free(t.deg); free(t.adj); free(t.parent);
    free(t.parc); free(t.depth); free(t.queue); free(t.pot); free(path);
    return st;
}

/* ---- the plan Radiance 6.1's pabopto2bsdf makes (transport.h) ----
 *
 * A transportation simplex on the cost table: Russell's approximation for
 * the starting basis, then pivots on the non-basic cell of most negative
 * reduced cost until none is below -1e-6 x the largest cost or the
 * objective stops falling.  Every choice below (scan orders, strict
 * comparisons, the slot a new basic cell takes, which basic cells reach
 * the output) follows the behaviour of Radiance's plans, which the trees
 * made from them depend on; docs/design/measured.md. */

#define RP_EPS 1e-6
#define RP_BIG 1e20

typedef struct rp_slot { int i, j; double x; } rp_slot;

typedef struct rp_state {
    int n1, n2, nslot;
    const double *c;         /* n1 x n2 (with the dummy row or column) */
    rp_slot *slot;           /* n1 + n2 slots; one is free at any time */
    unsigned char *basic;    /* n1 x n2 flags */
    int *rs, *rl, *cs, *cl;  /* slots by row / column (CSR, rebuilt per pivot) */
    int *qn, *qs, *prev;     /* search queue: node, slot used to reach it, queue index of its parent */
    double *u, *v;           /* duals of rows and columns */
} rp_state;

/* row/column lists of the basic slots (free slot excluded) */
static void rp_lists(rp_state *s, int free_slot)
{
    memset(s->rs, 0, (size_t)(s->n1 + 1) * sizeof(int));
    memset(s->cs, 0, (size_t)(s->n2 + 1) * sizeof(int));
    for (int k = 0; k < s->nslot; k++) {
        if (k == free_slot || s->slot[k].i < 0) continue;
        s->rs[s->slot[k].i + 1]++;
        s->cs[s->slot[k].j + 1]++;
    }
    for (int k = 0; k < s->n1; k++) s->rs[k + 1] += s->rs[k];
    for (int k = 0; k < s->n2; k++) s->cs[k + 1] += s->cs[k];
    int *fr = s->qn, *fc = s->qs;     /* borrowed fill pointers */
    memcpy(fr, s->rs, (size_t)s->n1 * sizeof(int));
    memcpy(fc, s->cs, (size_t)s->n2 * sizeof(int));
    for (int k = 0; k < s->nslot; k++) {
        if (k == free_slot || s->slot[k].i < 0) continue;
        s->rl[fr[s->slot[k].i]++] = k;
        s->cl[fc[s->slot[k].j]++] = k;
    }
}

/* Walk the basis tree from column node `col` (nodes: rows 0..n1-1,
 * columns n1..n1+n2-1).  With stop_row < 0 every node is reached and the
 * duals are set (column 0's dual is 0 when col = 0); otherwise the walk
 * stops at row stop_row and returns its queue index (-1 if unreachable). */
static int rp_walk(rp_state *s, int col, int stop_row)
{
    int n1 = s->n1, n2 = s->n2, head = 0, tail = 0;
    s->qn[tail] = n1 + col; s->qs[tail] = -1; s->prev[tail] = -1; tail++;
    if (stop_row < 0) s->v[col] = 0;
    while (head < tail) {
        int q = head++, x = s->qn[q];
        int b, e;
        const int *lst;
        if (x >= n1) { b = s->cs[x - n1]; e = s->cs[x - n1 + 1]; lst = s->cl; }
        else { b = s->rs[x]; e = s->rs[x + 1]; lst = s->rl; }
        for (int p = b; p < e; p++) {
            int k = lst[p];
            if (k == s->qs[q]) continue;
            const rp_slot *sl = &s->slot[k];
            int y = x >= n1 ? sl->i : n1 + sl->j;
            if (stop_row < 0) {
                if (y < n1) s->u[y] = s->c[(size_t)sl->i * n2 + sl->j] - s->v[sl->j];
                else s->v[y - n1] = s->c[(size_t)sl->i * n2 + sl->j] - s->u[sl->i];
            }
            s->qn[tail] = y; s->qs[tail] = k; s->prev[tail] = q; tail++;
            if (y == stop_row) return tail - 1;
            if (tail >= n1 + n2) return stop_row < 0 ? 0 : -1;   /* not a tree: cannot happen */
        }
    }
    return stop_row < 0 ? 0 : -1;
}

/* Russell's starting basis: repeatedly the open cell with the least
 * c_ij - U_i - V_j (U, V: the largest cost left in the row, column)
 * ships what it can and closes its row or column. */
static void rp_russell(rp_state *s, double *S, double *D, double maxw)
{
    int n1 = s->n1, n2 = s->n2;
    const double *c = s->c;
    double *U = s->u, *V = s->v;
    double *dl = hd_malloc_array((size_t)n1 * n2, sizeof(double));
    int *rown = hd_malloc_array((size_t)n1 + 1, sizeof(int)), *coln = hd_malloc_array((size_t)n2 + 1, sizeof(int));
    if (!dl || !rown || !coln) { free(dl); free(rown); free(coln); s->nslot = -1; return; }
    for (int i = 0; i < n1; i++) U[i] = 0;
    for (int j = 0; j < n2; j++) V[j] = 0;
    for (int i = 0; i < n1; i++)
        for (int j = 0; j < n2; j++) {
            double x = c[(size_t)i * n2 + j];
            if (x > U[i]) U[i] = x;
            if (x > V[j]) V[j] = x;
        }
    for (int i = 0; i < n1; i++)
        for (int j = 0; j < n2; j++) dl[(size_t)i * n2 + j] = c[(size_t)i * n2 + j] - U[i] - V[j];
    /* open rows and columns in ascending order (compacted arrays) */
    int nr = n1, nc = n2, ns = 0;
    for (int i = 0; i < n1; i++) rown[i] = i;
    for (int j = 0; j < n2; j++) coln[j] = j;
    while (nr > 0 && nc > 0) {
        double low = RP_BIG;
        int li = -1, lj = -1, pi = 0, pj = 0;
        for (int a = 0; a < nr; a++) {
            const double *drow = dl + (size_t)rown[a] * n2;
            for (int b = 0; b < nc; b++)
                if (drow[coln[b]] < low) { low = drow[coln[b]]; li = rown[a]; lj = coln[b]; pi = a; pj = b; }
        }
        if (li < 0) { li = rown[0]; lj = coln[0]; pi = pj = 0; }
        double amt;
        if (D[lj] - S[li] > maxw * RP_EPS || (fabs(S[li] - D[lj]) < maxw * RP_EPS && nr > 1)) {
            memmove(rown + pi, rown + pi + 1, (size_t)(nr - pi - 1) * sizeof(int));
            nr--;
            for (int b = 0; b < nc; b++) {           /* columns whose largest cost was in row li */
                int j = coln[b];
                if (V[j] != c[(size_t)li * n2 + j]) continue;
                V[j] = 0;
                for (int a = 0; a < nr; a++)
                    if (c[(size_t)rown[a] * n2 + j] > V[j]) V[j] = c[(size_t)rown[a] * n2 + j];
                for (int a = 0; a < nr; a++)
                    dl[(size_t)rown[a] * n2 + j] = c[(size_t)rown[a] * n2 + j] - U[rown[a]] - V[j];
            }
            amt = S[li];
        } else {
            memmove(coln + pj, coln + pj + 1, (size_t)(nc - pj - 1) * sizeof(int));
            nc--;
            for (int a = 0; a < nr; a++) {           /* rows whose largest cost was in column lj */
                int i = rown[a];
                if (U[i] != c[(size_t)i * n2 + lj]) continue;
                U[i] = 0;
                for (int b = 0; b < nc; b++)
                    if (c[(size_t)i * n2 + coln[b]] > U[i]) U[i] = c[(size_t)i * n2 + coln[b]];
                for (int b = 0; b < nc; b++)
                    dl[(size_t)i * n2 + coln[b]] = c[(size_t)i * n2 + coln[b]] - U[i] - V[coln[b]];
            }
            amt = D[lj];
        }
        S[li] -= amt;
        D[lj] -= amt;
        s->basic[(size_t)li * n2 + lj] = 1;
        s->slot[ns++] = (rp_slot){li, lj, amt};
    }
    for (int k = ns; k < n1 + n2; k++) s->slot[k] = (rp_slot){-1, -1, 0};
    free(dl); free(rown); free(coln);
}

hd_status hd_transport_radiance(int na, int nb, const double *a, const double *b, const double *c,
                                double *flow, long *npivots)
{
    if (npivots) *npivots = 0;
    if (na <= 0 || nb <= 0) return HD_OK;
    double ssum = 0, dsum = 0;
    for (int i = 0; i < na; i++) ssum += a[i];
    for (int j = 0; j < nb; j++) dsum += b[j];
    for (int i = 0; i < na; i++) if (a[i] < 0) return HD_ERR_RANGE;
    for (int j = 0; j < nb; j++) if (b[j] < 0) return HD_ERR_RANGE;
    double diff = ssum - dsum;
    int n1 = na, n2 = nb;
    if (fabs(diff) > RP_EPS * ssum) {        /* a dummy row or column takes the difference at no cost */
        if (diff < 0) n1++;
        else n2++;
    }
    double maxw = ssum > dsum ? ssum : dsum;
    size_t ncell = (size_t)n1 * n2;
    rp_state s = {.n1 = n1, .n2 = n2, .nslot = n1 + n2};
    double *cc = hd_malloc_array(ncell, sizeof(double));
    double *S = hd_malloc_array((size_t)n1, sizeof(double)), *D = hd_malloc_array((size_t)n2, sizeof(double));
    s.slot = hd_malloc_array((size_t)(n1 + n2), sizeof(rp_slot));
    s.basic = hd_calloc(ncell, 1);
    s.rs = hd_malloc_array((size_t)n1 + 1, sizeof(int));
    s.cs = hd_malloc_array((size_t)n2 + 1, sizeof(int));
    s.rl = hd_malloc_array((size_t)(n1 + n2), sizeof(int));
    s.cl = hd_malloc_array((size_t)(n1 + n2), sizeof(int));
    s.qn = hd_malloc_array((size_t)(n1 + n2 + 1), sizeof(int));
    s.qs = hd_malloc_array((size_t)(n1 + n2 + 1), sizeof(int));
    s.prev = hd_malloc_array((size_t)(n1 + n2 + 1), sizeof(int));
    s.u = hd_malloc_array((size_t)n1, sizeof(double));
    s.v = hd_malloc_array((size_t)n2, sizeof(double));
    double *rmin = hd_malloc_array((size_t)n1, sizeof(double)), *uo = hd_malloc_array((size_t)n1, sizeof(double));
    double *vo = hd_malloc_array((size_t)n2, sizeof(double));
    int *rarg = hd_malloc_array((size_t)n1, sizeof(int)), *chcol = hd_malloc_array((size_t)n2, sizeof(int));
    hd_status st = HD_OK;
    if (!cc || !S || !D || !s.slot || !s.basic || !s.rs || !s.cs || !s.rl || !s.cl || !s.qn || !s.qs ||
        !s.prev || !s.u || !s.v || !rmin || !uo || !vo || !rarg || !chcol) {
        st = HD_ERR_NOMEM;
        goto done;
    }
    double maxc = 0;
    for (int i = 0; i < n1; i++)
        for (int j = 0; j < n2; j++) {
            double x = (i < na && j < nb) ? c[(size_t)i * nb + j] : 0;
            if (x < 0) { st = HD_ERR_RANGE; goto done; }
            cc[(size_t)i * n2 + j] = x;
            if (x > maxc) maxc = x;
        }
    s.c = cc;
    for (int i = 0; i < na; i++) S[i] = a[i];
    if (n1 > na) S[na] = -diff;
    for (int j = 0; j < nb; j++) D[j] = b[j];
    if (n2 > nb) D[nb] = diff;
    rp_russell(&s, S, D, maxw);
    if (s.nslot < 0) { st = HD_ERR_NOMEM; goto done; }
    for (int k = 0; k < n1; k++) s.u[k] = 0;
    for (int k = 0; k < n2; k++) s.v[k] = 0;
    int fslot = n1 + n2 - 1;               /* the slot the next entering cell takes */
    int lasti[2] = {-1, -1};               /* rows whose basic cells changed in the last pivot */
    double obj = RP_BIG, oldobj;
    long piv = 0, limit = 1000L * (n1 + n2) + 100000L;
    for (;;) {
        oldobj = obj;
        obj = 0;
        for (int k = 0; k < n1 + n2; k++)
            if (k != fslot && s.slot[k].i >= 0) obj += cc[(size_t)s.slot[k].i * n2 + s.slot[k].j] * s.slot[k].x;
        rp_lists(&s, fslot);
        rp_walk(&s, 0, -1);
        /* pricing: the least reduced cost of every row (first column on ties)
         * is kept between pivots; a row is rescanned when its dual changed or
         * its basic cells did, otherwise only the columns whose dual changed
         * are looked at.  The values are those of a full scan, bit for bit. */
        int nch = 0;
        for (int j = 0; j < n2; j++)
            if (piv == 0 || s.v[j] != vo[j]) { vo[j] = s.v[j]; chcol[nch++] = j; }
        for (int i = 0; i < n1; i++) {
            int full = piv == 0 || s.u[i] != uo[i] || i == lasti[0] || i == lasti[1];
            uo[i] = s.u[i];
            const double *crow = cc + (size_t)i * n2;
            const unsigned char *brow = s.basic + (size_t)i * n2;
            double ui = s.u[i];
            if (!full)
                for (int q = 0; q < nch && !full; q++) {
                    int j = chcol[q];
                    double rc = crow[j] - ui - s.v[j];
                    if (j == rarg[i]) {
                        if (brow[j] || rc > rmin[i]) full = 1;
                        else rmin[i] = rc;
                    } else if (!brow[j] && (rc < rmin[i] || (rc == rmin[i] && j < rarg[i]))) {
                        rmin[i] = rc;
                        rarg[i] = j;
                    }
                }
            if (full) {
                double m = HUGE_VAL;
                int a = -1;
                for (int j = 0; j < n2; j++) {
                    double rc = crow[j] - ui - s.v[j];
                    if (rc < m && !brow[j]) { m = rc; a = j; }
                }
                rmin[i] = m;
                rarg[i] = a;
            }
        }
        double low = 0;
        int li = 0, lj = 0;
        for (int i = 0; i < n1; i++)
            if (rmin[i] < low) { low = rmin[i]; li = i; lj = rarg[i]; }
        if (low >= -RP_EPS * maxc || oldobj - obj < 0) break;
        if (piv >= limit) { st = HD_ERR_RANGE; break; }
        /* the cycle: entering cell, then the tree path from its column to its row */
        int end = rp_walk(&s, lj, li);
        if (end < 0) { st = HD_ERR_INTERNAL; break; }
        /* cells on the path, from the entering row's end back to the column:
         * the 1st, 3rd, ... lose flow, the others gain it */
        double theta = RP_BIG;
        int leave = -1, pos = 0;
        for (int q = end; s.prev[q] >= 0; q = s.prev[q], pos++)
            if (!(pos & 1) && s.slot[s.qs[q]].x < theta) { theta = s.slot[s.qs[q]].x; leave = s.qs[q]; }
        if (leave < 0) { st = HD_ERR_INTERNAL; break; }
        pos = 0;
        for (int q = end; s.prev[q] >= 0; q = s.prev[q], pos++) s.slot[s.qs[q]].x += (pos & 1) ? theta : -theta;
        s.slot[fslot] = (rp_slot){li, lj, theta};
        s.basic[(size_t)li * n2 + lj] = 1;
        s.basic[(size_t)s.slot[leave].i * n2 + s.slot[leave].j] = 0;
        lasti[0] = li;
        lasti[1] = s.slot[leave].i;
        fslot = leave;
        piv++;
    }
    if (npivots) *npivots = piv;
    if (st == HD_OK || st == HD_ERR_RANGE) {
        /* Radiance's output leaves out the cell in the last slot unless that slot is free */
        memset(flow, 0, (size_t)na * nb * sizeof(double));
        for (int k = 0; k < n1 + n2 - 1; k++) {
            const rp_slot *sl = &s.slot[k];
            if (k == fslot || sl->i < 0 || sl->i >= na || sl->j >= nb || sl->x == 0) continue;
            if (!s.basic[(size_t)sl->i * n2 + sl->j]) continue;
            flow[(size_t)sl->i * nb + sl->j] = sl->x;
        }
    }
done:
    free(cc); free(S); free(D); free(s.slot); free(s.basic); free(s.rs); free(s.cs); free(s.rl); free(s.cl);
    free(s.qn); free(s.qs); free(s.prev); free(s.u); free(s.v);
    free(rmin); free(uo); free(vo); free(rarg); free(chcol);
    return st;
}
