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

static int uf_find(int *uf, int k)
{
    while (uf[k] != k) { uf[k] = uf[uf[k]]; k = uf[k]; }
    return k;
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
        uf[uf_find(uf, i)] = uf_find(uf, na + j);
    }
    for (size_t q = 0; q < np && nar < n - 1; q++) {
        int i = pp[q].i, j = pp[q].j;
        int ri = uf_find(uf, i), rj = uf_find(uf, na + j);
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
