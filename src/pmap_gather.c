/* heliodon — contribution photon map lookups: per-source k nearest
 * neighbours through the page cache, density estimates, direction bins,
 * one-bounce final gather. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/material.h"
#include "heliodon/rng.h"
#include "scatter.h"
#include "heliodon/trace.h"
#include "pmap_internal.h"

void hd_pmap_lookup_opts_init(hd_pmap_lookup_opts *o)
{
    memset(o, 0, sizeof *o);
    o->k = 50;
    o->normal_tol = 0.9;
    o->kernel = HD_PMAP_KERNEL_FLAT;
}

/* a neighbour: squared distance, flux, incident direction, flags, and its
 * offset along the lookup normal (non-zero when the lookup point lies off
 * the photons' surface, e.g. a sensor 1 cm above the floor) */
typedef struct nb { float d2; float w[3]; float h; uint16_t dir; uint8_t fl; } nb;

struct hd_pmap_lookup {
    hd_pmap *m;
    hd_pmap_lookup_opts o;
    nb *heap;                 /* max-heap (nb_less order), size k */
    uint32_t nh;
    /* warm start: the previous query of this lookup object (same source and
     * same normal: its k photons lie within r_prev + |p - p_prev| of p) */
    int warm;
    uint32_t wsrc;
    float wp[3], wn[3];
    double wr;
    /* group lookups: candidate photons of a group of points, points (float) */
    struct cand *cand;
    size_t ncand, capcand;
    float *gp;
    size_t capgp;
    double *gr;               /* per source: largest k-th distance of its previous group (0: none) */
    uint64_t gmiss;           /* points looked up alone (ball outside the collected one) */
    struct sref *sel;
    size_t capsel;
    float *cx, *cy, *cz;      /* candidates' coordinates (structure of arrays, capcand) */
    uint16_t *cbin;           /* distance bins of the selected ones */
    float *fd;                /* filtered candidates of one point: squared distance, index */
    uint32_t *fj;
    size_t capsoa;

    double rsum;              /* k-th distances of full lookups (mean radius) */
    uint64_t rcount;
};

/* candidate of a group lookup: photon position and neighbour payload */
/* the disc correction of estimate() is limited to a disc of 1/20 of the
 * search sphere's cross-section (offsets beyond ~97 % of r) */
#define PM_DISC_MAXH2 0.95

/* squared radius of the disc the neighbours lie in: r2 less their mean
 * squared offset along the normal (sum_h2 over n), limited as above */
static inline double disc_r2(double r2, double sum_h2, size_t n)
{
    double hh = sum_h2 / (double)n;
    return r2 - (hh > PM_DISC_MAXH2 * r2 ? PM_DISC_MAXH2 * r2 : hh);
}

typedef struct cand { float w[3]; uint16_t dir; uint8_t fl; } cand;   /* payload; positions in cx, cy, cz */

hd_status hd_pmap_lookup_create(hd_pmap *m, const hd_pmap_lookup_opts *o, hd_pmap_lookup **out)
{
    *out = NULL;
    if (o->k < 2) return hd_fail(HD_ERR_RANGE, "photon lookups need at least 2 neighbours (got %u)", o->k);
    if (o->k > 10000000) return hd_fail(HD_ERR_RANGE, "%u neighbours per source: too many", o->k);
    hd_pmap_lookup *l = hd_calloc(1, sizeof *l);
    if (!l) return HD_ERR_NOMEM;
    l->m = m;
    l->o = *o;
    l->heap = hd_malloc_array(o->k, sizeof *l->heap);
    l->gr = hd_calloc(m->info.nsources ? m->info.nsources : 1, sizeof *l->gr);
    if (!l->heap || !l->gr) { hd_pmap_lookup_free(l); return HD_ERR_NOMEM; }
    *out = l;
    return HD_OK;
}

uint64_t hd_pmap_lookup_misses(const hd_pmap_lookup *l)
{
    return l->gmiss;
}

double hd_pmap_lookup_radius(hd_pmap_lookup *l, int reset)
{
    double r = l->rcount ? l->rsum / (double)l->rcount : 0;
    if (reset) { l->rsum = 0; l->rcount = 0; }
    return r;
}

void hd_pmap_lookup_free(hd_pmap_lookup *l)
{
    if (!l) return;
    free(l->heap);
    free(l->gr);
    free(l->cand);
    free(l->gp);
    free(l->sel);
    free(l->cx);
    free(l->cy);
    free(l->cz);
    free(l->cbin);
    free(l->fd);
    free(l->fj);
    free(l);
}

static inline float box_d2(const float *lo, const float *hi, const float p[3])
{
    float d = 0, v;
    v = p[0] < lo[0] ? lo[0] - p[0] : p[0] > hi[0] ? p[0] - hi[0] : 0; d += v * v;
    v = p[1] < lo[1] ? lo[1] - p[1] : p[1] > hi[1] ? p[1] - hi[1] : 0; d += v * v;
    v = p[2] < lo[2] ? lo[2] - p[2] : p[2] > hi[2] ? p[2] - hi[2] : 0; d += v * v;
    return d;
}

/* Total order of neighbours: distance, then content.  The k nearest under
 * a total order are one set whatever order the photons are offered in (or
 * how many far ones a search bound prunes), so lookups do not depend on the
 * traversal, the cache or the previous query. */
static inline int nb_less(const nb *a, const nb *b)
{
    if (a->d2 != b->d2) return a->d2 < b->d2;
    for (int k = 0; k < 3; k++) if (a->w[k] != b->w[k]) return a->w[k] < b->w[k];
    if (a->dir != b->dir) return a->dir < b->dir;
    return a->fl < b->fl;
}

/* Insert into the bounded max-heap; returns the new bound (heap top when full). */
static float heap_push(hd_pmap_lookup *l, const nb *e, float rmax2)
{
    uint32_t k = l->o.k;
    nb *h = l->heap;
    if (l->nh < k) {
        uint32_t i = l->nh++;
        while (i > 0) {
            uint32_t par = (i - 1) / 2;
            if (!nb_less(&h[par], e)) break;
            h[i] = h[par];
            i = par;
        }
        h[i] = *e;
        return l->nh == k ? h[0].d2 : rmax2;
    }
    if (!nb_less(e, &h[0])) return h[0].d2;
    uint32_t i = 0;
    for (;;) {
        uint32_t a = 2 * i + 1, b = a + 1, c = i;
        const nb *dc = e;
        if (a < k && nb_less(dc, &h[a])) { c = a; dc = &h[a]; }
        if (b < k && nb_less(dc, &h[b])) { c = b; }
        if (c == i) break;
        h[i] = h[c];
        i = c;
    }
    h[i] = *e;
    return h[0].d2;
}

/* normal cone of a node compatible with the lookup normal? */
static inline int cone_ok(const pm_node *N, const float n[3], float tol)
{
    float cf = N->ax[0] * n[0] + N->ax[1] * n[1] + N->ax[2] * n[2];
    if (cf >= N->cmin) return 1;   /* lookup normal inside the cone */
    float sf2 = 1 - cf * cf;
    float sf = sf2 > 0 ? sqrtf(sf2) : 0;
    return cf * N->cmin + sf * N->smin >= tol - 1e-6f;
}

/* every normal of the node's cone compatible with n (dot >= tol): the
 * smallest dot over the cone, cos(angle to the axis + half angle), with a
 * margin for float rounding */
static inline int cone_all(const pm_node *N, const float n[3], float tol)
{
    float cf = N->ax[0] * n[0] + N->ax[1] * n[1] + N->ax[2] * n[2];
    if (N->cmin <= 0 || cf <= 0) return 0;   /* both angles below 90 degrees: the formula holds */
    float sf2 = 1 - cf * cf;
    float sf = sf2 > 0 ? sqrtf(sf2) : 0;
    return cf * N->cmin - sf * N->smin >= tol + 1e-4f;
}

/* squared distance from p to the farthest point of a box */
static inline float box_maxd2(const float *lo, const float *hi, const float p[3])
{
    float d = 0;
    for (int k = 0; k < 3; k++) {
        float a = p[k] - lo[k], b = hi[k] - p[k], v = a > b ? a : b;
        d += v * v;
    }
    return d;
}

typedef struct stk { uint32_t node, b, e; float d2; } stk;

/* A tree walk's two children ca (records [b, m)) and cb ([m, e)) at squared
 * distances da, db, those admitted (oka, okb) pushed so that the nearer is
 * visited first (ties: left first). */
static inline int push_children(stk *st, int sp, uint32_t ca, uint32_t cb, uint32_t b, uint32_t m, uint32_t e,
                                float da, float db, int oka, int okb)
{
    if (oka && okb) {
        if (da <= db) { st[sp++] = (stk){cb, m, e, db}; st[sp++] = (stk){ca, b, m, da}; }
        else { st[sp++] = (stk){ca, b, m, da}; st[sp++] = (stk){cb, m, e, db}; }
    } else if (oka) st[sp++] = (stk){ca, b, m, da};
    else if (okb) st[sp++] = (stk){cb, m, e, db};
    return sp;
}
#define PM_STACK 128

/* Scan one decoded page (kd-tree, nearest child first); returns the bound. */
static float scan_page(hd_pmap_lookup *l, const pm_page *pg, const float p[3], const float n[3], float tol,
                       float rmax2, float bound)
{
    if (!pg->count) return bound;
    stk st[PM_STACK];
    int sp = 0;
    float d0 = box_d2(pg->node[0].lo, pg->node[0].hi, p);
    if (d0 > bound || !cone_ok(&pg->node[0], n, tol)) return bound;
    st[sp++] = (stk){0, 0, pg->count, d0};
    while (sp > 0) {
        stk t = st[--sp];
        if (t.d2 > bound) continue;
        if (t.e - t.b <= PM_LEAF) {
            /* every normal of the leaf compatible: no per-photon test */
            int alln = cone_all(&pg->node[t.node], n, tol);
            uint32_t lastc = UINT32_MAX;
            float qn[3] = {0, 0, 0};
            for (uint32_t i = t.b; i < t.e; i++) {
                const float *q = pg->pos + 3 * i;
                float dx = q[0] - p[0], dy = q[1] - p[1], dz = q[2] - p[2];
                float d2 = dx * dx + dy * dy + dz * dz;
                if (d2 > bound) continue;
                if (!alln) {
                    if (pg->ncode[i] != lastc) { pm_nrm_decode(pg->ncode[i], qn); lastc = pg->ncode[i]; }
                    if (qn[0] * n[0] + qn[1] * n[1] + qn[2] * n[2] < tol) continue;
                }
                nb e2;
                e2.d2 = d2;
                e2.h = dx * n[0] + dy * n[1] + dz * n[2];
                pm_rgbe_decode(pg->wcode[i], e2.w);
                e2.dir = pg->dir[i];
                e2.fl = pg->flags[i];
                bound = heap_push(l, &e2, rmax2);
            }
            continue;
        }
        uint32_t m = pm_tree_split(t.b, t.e, PM_LEAF), ca = 2 * t.node + 1, cb = ca + 1;
        const pm_node *A = &pg->node[ca], *B = &pg->node[cb];
        float da = box_d2(A->lo, A->hi, p), db = box_d2(B->lo, B->hi, p);
        int oka = da <= bound && cone_ok(A, n, tol), okb = db <= bound && cone_ok(B, n, tol);
        /* sp + 2 <= PM_STACK: at most 2 entries per level, depth <= 22 (pages hold <= 2^24 photons) */
        sp = push_children(st, sp, ca, cb, t.b, m, t.e, da, db, oka, okb);
    }
    return bound;
}

/* Search the pages [first, first + np) of one source through their page
 * tree (nearest page box first). */
static hd_status scan_range(hd_pmap_lookup *l, uint64_t first, uint64_t np, const pm_box *tree, const float p[3],
                            const float n[3], float tol, float rmax2, float *bound)
{
    hd_pmap *m = l->m;
    stk st[PM_STACK];
    int sp = 0;
    float d0 = box_d2(tree[0].lo, tree[0].hi, p);
    if (d0 > *bound) return HD_OK;
    st[sp++] = (stk){0, 0, (uint32_t)np, d0};
    while (sp > 0) {
        stk t = st[--sp];
        if (t.d2 > *bound) continue;
        if (t.e - t.b == 1) {
            const pm_page *pg;
            uint64_t pi = first + t.b;
            hd_status s = pm_page_get(m, pi, &pg);
            if (s) return s;
            *bound = scan_page(l, pg, p, n, tol, rmax2, *bound);
            pm_page_release(m, pi);
            continue;
        }
        uint32_t mm = pm_tree_split(t.b, t.e, 1), ca = 2 * t.node + 1, cb = ca + 1;
        float da = box_d2(tree[ca].lo, tree[ca].hi, p), db = box_d2(tree[cb].lo, tree[cb].hi, p);
        int oka = da <= *bound, okb = db <= *bound;
        if (sp + 2 > PM_STACK) return hd_fail(HD_ERR_INTERNAL, "photon page tree too deep");
        sp = push_children(st, sp, ca, cb, t.b, mm, t.e, da, db, oka, okb);
    }
    return HD_OK;
}

/* Collect the k nearest compatible photons of source s.  The photons
 * offered to the heap and their order depend only on the map and the
 * query, never on what the page cache holds.  bound0: a squared distance
 * within which at least k compatible photons are known to lie (the search
 * starts with it; HUGE_VALF if none is known). */
static hd_status knn_b(hd_pmap_lookup *l, uint32_t s, hd_vec3 p, hd_vec3 n, float bound0)
{
    hd_pmap *m = l->m;
    const hd_pmap_source *S = &m->src[s];
    l->nh = 0;
    float rmax2 = l->o.max_radius > 0 ? (float)(l->o.max_radius * l->o.max_radius) : HUGE_VALF;
    float bound = rmax2 < bound0 ? rmax2 : bound0;
    float pf[3] = {(float)p.x, (float)p.y, (float)p.z}, nf[3] = {(float)n.x, (float)n.y, (float)n.z};
    float tol = (float)l->o.normal_tol;
    if (l->warm && l->wsrc == s && l->wn[0] == nf[0] && l->wn[1] == nf[1] && l->wn[2] == nf[2]) {
        double dx = pf[0] - l->wp[0], dy = pf[1] - l->wp[1], dz = pf[2] - l->wp[2];
        double r = (l->wr + sqrt(dx * dx + dy * dy + dz * dz)) * (1 + 1e-5) + 1e-6;
        if (r * r < bound) bound = (float)(r * r);
    }
    /* bound now holds at least k compatible photons (or is the -am limit):
     * the search never needs to look beyond it, also while the heap fills */
    float cap = bound;
    uint64_t nind = m->src_nind[s];
    hd_status st;
    if (nind && (st = scan_range(l, S->first_page, nind, m->ptree + m->src_tree[2 * s], pf, nf, tol, cap, &bound)))
        return st;
    if (!l->o.direct_scene && S->npages > nind &&
        (st = scan_range(l, S->first_page + nind, S->npages - nind, m->ptree + m->src_tree[2 * s + 1], pf, nf, tol,
                         cap, &bound)))
        return st;
    l->warm = l->nh == l->o.k;
    if (l->warm) {
        l->rsum += sqrt((double)l->heap[0].d2);
        l->rcount++;
        l->wsrc = s;
        memcpy(l->wp, pf, sizeof pf);
        memcpy(l->wn, nf, sizeof nf);
        l->wr = sqrt((double)l->heap[0].d2);
    }
    return HD_OK;
}

static hd_status knn(hd_pmap_lookup *l, uint32_t s, hd_vec3 p, hd_vec3 n)
{
    return knn_b(l, s, p, n, HUGE_VALF);
}

static int through_glass(const hd_tscene *ts, hd_vec3 org, hd_vec3 d, double eps, double trans[3], hd_hit *h);

/* Exact direct irradiance (unit radiance) from source S at p, normal n,
 * through glass: a shadow ray to the disk centre. */
static void direct_term(const hd_tscene *ts, const hd_pmap_source *S, hd_vec3 p, hd_vec3 n, double out[3])
{
    out[0] = out[1] = out[2] = 0;
    double c = hd_vdot(n, S->dir);
    if (c <= 0) return;
    double T[3];
    hd_hit h;
    if (!through_glass(ts, p, S->dir, hd_tscene_eps(ts), T, &h)) return;
    double omega = 2 * HD_PI * (1 - cos(S->half_angle));
    for (int k = 0; k < 3; k++) out[k] = omega * c * T[k];
}

/* Density estimate from the neighbours in l->heap (l->nh of them), added
 * into out (per bin with a bin function). */
static void estimate(hd_pmap_lookup *l, const hd_pmap_source *S, uint32_t s, double *out, hd_pmap_binfn binfn,
                     void *binctx, unsigned need, int sorted)
{
    if (l->nh < 2) return;
    /* sum in the neighbours' total order (the heap's layout depends on the
     * order photons were offered; group lookups hand them in sorted) */
    nb *h = l->heap;
    for (uint32_t i = 1; i < l->nh && !sorted; i++) {
        if (!nb_less(&h[i], &h[i - 1])) continue;
        nb t = h[i];
        uint32_t q = i;
        while (q > 0 && nb_less(&t, &h[q - 1])) { h[q] = h[q - 1]; q--; }
        h[q] = t;
    }
    double r2;
    int skip_far;
    if (l->nh == l->o.k || !(l->o.max_radius > 0)) { r2 = (double)h[l->nh - 1].d2; skip_far = 1; }   /* the farthest */
    else { r2 = l->o.max_radius * l->o.max_radius; skip_far = 0; }
    if (!(r2 > 0)) return;
    /* The k nearest photons of a point at height hh above a plane of photons
     * lie in a disc of radius^2 r2 - hh^2, not r2: divide by that disc's
     * area (hh^2 = mean squared offset along the normal; ~1e-9 of r2 for
     * points on the photons' surface, where nothing changes).  Without this
     * a sensor 1 cm above the floor reads far too low once the photon count
     * makes r comparable to 1 cm (measured: -36 % with 10^9 photons, k 21). */
    double hh = 0;
    for (uint32_t i = 0; i < l->nh; i++) hh += (double)l->heap[i].h * l->heap[i].h;
    double r2d = disc_r2(r2, hh, l->nh);
    double norm = S->flux / (HD_PI * r2d);
    for (uint32_t i = 0; i < l->nh; i++) {
        const nb *e = &l->heap[i];
        double kw;
        if (skip_far && i == l->nh - 1) continue;   /* the farthest defines r */
        if ((e->fl & need) != need) continue;
        if (l->o.kernel == HD_PMAP_KERNEL_EPAN) {
            double u = ((double)e->d2 - (double)e->h * e->h) / r2d;
            kw = u < 1 ? 2.0 * (1.0 - u) : 0;
        }
        else kw = 1.0;
        double f = norm * kw;
        if (binfn) {
            int b = binfn(binctx, s, hd_vneg(hd_pmap_oct_decode(e->dir)));
            if (b < 0) continue;
            out[3 * b] += f * e->w[0];
            out[3 * b + 1] += f * e->w[1];
            out[3 * b + 2] += f * e->w[2];
        } else {
            out[0] += f * e->w[0];
            out[1] += f * e->w[1];
            out[2] += f * e->w[2];
        }
    }
}

/* exact direct term of source S at p into out (bin of the source direction) */
static void add_direct(hd_pmap_lookup *l, const hd_pmap_source *S, uint32_t s, hd_vec3 p, hd_vec3 n, double *out,
                       hd_pmap_binfn binfn, void *binctx)
{
    double dt[3];
    direct_term(l->o.direct_scene, S, p, n, dt);
    if (dt[0] > 0 || dt[1] > 0 || dt[2] > 0) {
        int b = binfn ? binfn(binctx, s, S->dir) : 0;
        if (b >= 0) for (int k = 0; k < 3; k++) out[3 * b + k] += dt[k];
    }
}

/* hd_pmap_irradiance with a known search bound (knn_b) */
static hd_status irradiance_b(hd_pmap_lookup *l, uint32_t s, hd_vec3 p, hd_vec3 n, double *out, hd_pmap_binfn binfn,
                              void *binctx, float bound0)
{
    hd_pmap *m = l->m;
    if (s >= m->info.nsources) return hd_fail(HD_ERR_RANGE, "source %u out of range", s);
    if (!binfn) out[0] = out[1] = out[2] = 0;
    const hd_pmap_source *S = &m->src[s];
    if (!S->npages) return HD_OK;
    if (l->o.direct_scene) add_direct(l, S, s, p, n, out, binfn, binctx);
    hd_status st = knn_b(l, s, p, n, bound0);
    if (st) return st;
    estimate(l, S, s, out, binfn, binctx, 0, 0);
    return HD_OK;
}

hd_status hd_pmap_irradiance(hd_pmap_lookup *l, uint32_t s, hd_vec3 p, hd_vec3 n, double *out,
                             hd_pmap_binfn binfn, void *binctx)
{
    return irradiance_b(l, s, p, n, out, binfn, binctx, HUGE_VALF);
}

/* ---- group lookups ----
 * Points sharing one normal (pixels of one surface): every compatible
 * photon within a radius R of a central point q is collected in one
 * traversal; each point then takes its k nearest from those candidates
 * (same float distances, same total order).  R comes from the previous
 * group of the same source (or, for the first, from the k nearest of q:
 * r_p <= r_q + |p - q| since the same photons are compatible with the same
 * normal).  A point's result is used only if its k-th-neighbour ball (or
 * its -am ball when it has fewer than k) lies inside the collected ball;
 * otherwise it is looked up alone — so results equal hd_pmap_irradiance. */

#define GMARGIN 1e-4
#ifndef GTF
#define GTF 0.5
#endif
#ifndef GRFAC
#define GRFAC 1.15
#endif

/* all compatible photons of one page within sqrt(R2) of q */
static hd_status collect_page(hd_pmap_lookup *l, const pm_page *pg, const float q[3], const float n[3], float tol,
                              float R2)
{
    if (!pg->count) return HD_OK;
    struct { uint32_t node, b, e; } stk2[PM_STACK];
    int sp = 0;
    if (box_d2(pg->node[0].lo, pg->node[0].hi, q) > R2 || !cone_ok(&pg->node[0], n, tol)) return HD_OK;
    stk2[sp].node = 0; stk2[sp].b = 0; stk2[sp].e = pg->count; sp++;
    while (sp > 0) {
        sp--;
        uint32_t node = stk2[sp].node, b = stk2[sp].b, e = stk2[sp].e;
        if (e - b <= PM_LEAF) {
            if (l->ncand + PM_LEAF + 16 > l->capcand) {   /* 16: padding to whole vectors */
                size_t nc = l->capcand ? 2 * l->capcand : 1024;
                cand *c = hd_realloc_array(l->cand, nc, sizeof *c);
                if (c) l->cand = c;
                float *a[3] = {hd_realloc_array(l->cx, nc, sizeof(float)), NULL, NULL};
                if (a[0]) l->cx = a[0];
                a[1] = hd_realloc_array(l->cy, nc, sizeof(float));
                if (a[1]) l->cy = a[1];
                a[2] = hd_realloc_array(l->cz, nc, sizeof(float));
                if (a[2]) l->cz = a[2];
                if (!c || !a[0] || !a[1] || !a[2]) return HD_ERR_NOMEM;
                l->capcand = nc;
            }
            /* every normal of the leaf compatible / the whole leaf box in
             * the ball (margins: float rounding) -> no per-photon test */
            const pm_node *L = &pg->node[node];
            int alln = cone_all(L, n, tol), allin = box_maxd2(L->lo, L->hi, q) <= R2 * (1 - 1e-5f);
            cand *cc = l->cand + l->ncand;
            float *CX = l->cx + l->ncand, *CY = l->cy + l->ncand, *CZ = l->cz + l->ncand;
            uint32_t pi[PM_LEAF];   /* the leaf's photons taken, then their payloads */
            size_t nc = 0;
            if (alln) {   /* the usual case: no branch per photon (room for a whole leaf) */
                for (uint32_t i = b; i < e; i++) {
                    const float *x = pg->pos + 3 * i;
                    float dx = x[0] - q[0], dy = x[1] - q[1], dz = x[2] - q[2];
                    float d2 = dx * dx + dy * dy + dz * dz;
                    CX[nc] = x[0];
                    CY[nc] = x[1];
                    CZ[nc] = x[2];
                    pi[nc] = i;
                    nc += (size_t)(allin | (d2 <= R2));
                }
            } else {
                uint32_t lastc = UINT32_MAX;
                float xn[3] = {0, 0, 0};
                for (uint32_t i = b; i < e; i++) {
                    const float *x = pg->pos + 3 * i;
                    if (!allin) {
                        float dx = x[0] - q[0], dy = x[1] - q[1], dz = x[2] - q[2];
                        float d2 = dx * dx + dy * dy + dz * dz;
                        if (d2 > R2) continue;
                    }
                    if (pg->ncode[i] != lastc) { pm_nrm_decode(pg->ncode[i], xn); lastc = pg->ncode[i]; }
                    if (xn[0] * n[0] + xn[1] * n[1] + xn[2] * n[2] < tol) continue;
                    CX[nc] = x[0];
                    CY[nc] = x[1];
                    CZ[nc] = x[2];
                    pi[nc++] = i;
                }
            }
            for (size_t t = 0; t < nc; t++) {
                uint32_t i = pi[t];
                cand *c = cc + t;
                pm_rgbe_decode(pg->wcode[i], c->w);
                c->dir = pg->dir[i];
                c->fl = pg->flags[i];
            }
            l->ncand += nc;
            continue;
        }
        uint32_t mid = pm_tree_split(b, e, PM_LEAF), ca = 2 * node + 1, cb = ca + 1;
        const pm_node *A = &pg->node[ca], *B = &pg->node[cb];
        if (box_d2(A->lo, A->hi, q) <= R2 && cone_ok(A, n, tol)) { stk2[sp].node = ca; stk2[sp].b = b; stk2[sp].e = mid; sp++; }
        if (box_d2(B->lo, B->hi, q) <= R2 && cone_ok(B, n, tol)) { stk2[sp].node = cb; stk2[sp].b = mid; stk2[sp].e = e; sp++; }
    }
    return HD_OK;
}

static hd_status collect_range(hd_pmap_lookup *l, uint64_t first, uint64_t np, const pm_box *tree, const float q[3],
                               const float n[3], float tol, float R2)
{
    hd_pmap *m = l->m;
    struct { uint32_t node, b, e; } st[PM_STACK];
    int sp = 0;
    if (box_d2(tree[0].lo, tree[0].hi, q) > R2) return HD_OK;
    st[sp].node = 0; st[sp].b = 0; st[sp].e = (uint32_t)np; sp++;
    while (sp > 0) {
        sp--;
        uint32_t node = st[sp].node, b = st[sp].b, e = st[sp].e;
        if (e - b == 1) {
            const pm_page *pg;
            uint64_t pi = first + b;
            hd_status s = pm_page_get(m, pi, &pg);
            if (s) return s;
            s = collect_page(l, pg, q, n, tol, R2);
            pm_page_release(m, pi);
            if (s) return s;
            continue;
        }
        uint32_t mid = pm_tree_split(b, e, 1), ca = 2 * node + 1, cb = ca + 1;
        if (sp + 2 > PM_STACK) return hd_fail(HD_ERR_INTERNAL, "photon page tree too deep");
        if (box_d2(tree[ca].lo, tree[ca].hi, q) <= R2) { st[sp].node = ca; st[sp].b = b; st[sp].e = mid; sp++; }
        if (box_d2(tree[cb].lo, tree[cb].hi, q) <= R2) { st[sp].node = cb; st[sp].b = mid; st[sp].e = e; sp++; }
    }
    return HD_OK;
}

/* selection reference: distance to the point, candidate index */
typedef struct sref { float d2; uint32_t j; } sref;

/* the neighbours' total order (as nb_less) */
static inline int sref_less(const sref *a, const sref *b, const cand *c)
{
    if (a->d2 != b->d2) return a->d2 < b->d2;
    const cand *x = &c[a->j], *y = &c[b->j];
    for (int k = 0; k < 3; k++) if (x->w[k] != y->w[k]) return x->w[k] < y->w[k];
    if (x->dir != y->dir) return x->dir < y->dir;
    return x->fl < y->fl;
}

#define NSBIN 256

/* ---- per-point selection kernels ----
 * filter: every candidate j < nc (arrays padded with far points to a
 * multiple of 16) with d2 <= fb, as squared distance D[] and index J[] in
 * candidate order (D, J hold nc + 16); returns how many.  d2 is the float
 * expression of the point-by-point search, (dx*dx + dy*dy) + dz*dz, each
 * lane a separate IEEE multiply and add (no fused multiply-add), so every
 * kernel gives the same values as the scalar code.
 * rank (AVX2, AVX-512): the nk smallest of na <= PM_RANK_MAX filtered
 * ones, sorted, into Z, by counting for each how many are smaller; 0 if
 * some squared distance among them occurs twice (the total order then needs
 * the content: the caller sorts generically).  Level 0 portable C (four-
 * float GCC vectors where available), 1 AVX2, 2 AVX-512F, the best the CPU
 * has (detected once); hd_pmap_set_kernel lowers it. */
#define PM_RANK_MAX 64
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__)) && !defined(PM_NOVEC)
#define PM_X86 1
#include <immintrin.h>
#else
#define PM_X86 0
#endif
#if defined(__GNUC__) && !defined(PM_NOVEC)
#define PM_VEC 1
typedef float v4f __attribute__((vector_size(16)));
#else
#define PM_VEC 0
#endif

static size_t filter_c(const float *restrict CX, const float *restrict CY, const float *restrict CZ, size_t nc,
                       const float p[3], float fb, float *restrict D, uint32_t *restrict J)
{
    const float px = p[0], py = p[1], pz = p[2];
    size_t na = 0;
#if PM_VEC
    v4f vx = {px, px, px, px}, vy = {py, py, py, py}, vz = {pz, pz, pz, pz};
    for (uint32_t j = 0; j < (uint32_t)nc; j += 4) {
        v4f cx, cy, cz;
        memcpy(&cx, CX + j, sizeof cx);
        memcpy(&cy, CY + j, sizeof cy);
        memcpy(&cz, CZ + j, sizeof cz);
        v4f dx = cx - vx, dy = cy - vy, dz = cz - vz;
        v4f d2 = dx * dx + dy * dy + dz * dz;
        float t[4];
        memcpy(t, &d2, sizeof t);
        D[na] = t[0]; J[na] = j; na += t[0] <= fb;
        D[na] = t[1]; J[na] = j + 1; na += t[1] <= fb;
        D[na] = t[2]; J[na] = j + 2; na += t[2] <= fb;
        D[na] = t[3]; J[na] = j + 3; na += t[3] <= fb;
    }
#else
    for (uint32_t j = 0; j < (uint32_t)nc; j++) {
        float dx = CX[j] - px, dy = CY[j] - py, dz = CZ[j] - pz;
        float d2 = dx * dx + dy * dy + dz * dz;
        D[na] = d2;
        J[na] = j;
        na += d2 <= fb;
    }
#endif
    return na;
}

#if PM_X86
/* The ranks R (#{m : D_m < D_i}) of the na filtered ones -> Z[R_i] for the
 * nk smallest.  Without ties the ranks below nk are 0..nk-1 once each; a
 * tie gives equal ranks, so more than nk of them below nk or a smaller
 * rank sum: 0 (the caller sorts generically). */
static int rank_place(const float *D, const uint32_t *J, const uint32_t *R, size_t na, size_t nk, sref *Z)
{
    size_t cnt = 0;
    unsigned long long sum = 0;
    for (size_t i = 0; i < na; i++) {
        size_t ok = R[i] < nk;
        cnt += ok;
        sum += ok ? R[i] : 0;
    }
    if (cnt != nk || sum != (unsigned long long)nk * (nk - 1) / 2) return 0;
    for (size_t i = 0; i < na; i++) {
        size_t q = R[i] < nk ? R[i] : nk;   /* Z[nk]: discard slot */
        Z[q].d2 = D[i];
        Z[q].j = J[i];
    }
    return 1;
}

__attribute__((target("avx512f"))) static size_t filter_avx512(const float *restrict CX, const float *restrict CY,
                                                               const float *restrict CZ, size_t nc, const float p[3],
                                                               float fb, float *restrict D, uint32_t *restrict J)
{
    __m512 vx = _mm512_set1_ps(p[0]), vy = _mm512_set1_ps(p[1]), vz = _mm512_set1_ps(p[2]), vb = _mm512_set1_ps(fb);
    __m512i idx = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15), step = _mm512_set1_epi32(16);
    size_t na = 0;
    for (size_t j = 0; j < nc; j += 16) {
        __m512 dx = _mm512_sub_ps(_mm512_loadu_ps(CX + j), vx);
        __m512 dy = _mm512_sub_ps(_mm512_loadu_ps(CY + j), vy);
        __m512 dz = _mm512_sub_ps(_mm512_loadu_ps(CZ + j), vz);
        __m512 d2 = _mm512_add_ps(_mm512_add_ps(_mm512_mul_ps(dx, dx), _mm512_mul_ps(dy, dy)), _mm512_mul_ps(dz, dz));
        __mmask16 m = _mm512_cmp_ps_mask(d2, vb, _CMP_LE_OQ);
        /* compress in registers, store whole vectors (D, J have 16 spare) */
        _mm512_storeu_ps(D + na, _mm512_maskz_compress_ps(m, d2));
        _mm512_storeu_si512((void *)(J + na), _mm512_maskz_compress_epi32(m, idx));
        na += (size_t)__builtin_popcount((unsigned)m);
        idx = _mm512_add_epi32(idx, step);
    }
    return na;
}

/* ranks r_i = #{m : D_m < D_i}, 16 lanes per vector, NV vectors: for each
 * m one broadcast and NV compare + masked add (no mask-to-integer moves) */
__attribute__((target("avx512f"), always_inline)) static inline void ranks_nv(const float *D, size_t na,
                                                                            const __m512 *v, __m512i *r,
                                                                            const size_t NV)
{
    const __m512i one = _mm512_set1_epi32(1);
    for (size_t m = 0; m < na; m++) {
        __m512 b = _mm512_set1_ps(D[m]);
        for (size_t t = 0; t < NV; t++) r[t] = _mm512_mask_add_epi32(r[t], _mm512_cmp_ps_mask(b, v[t], _CMP_LT_OQ), r[t], one);
    }
}

__attribute__((target("avx512f"))) static int rank_avx512(const float *D, const uint32_t *J, size_t na, size_t nk,
                                                          sref *Z)
{
    __m512 v[PM_RANK_MAX / 16];
    __m512i r[PM_RANK_MAX / 16];
    __mmask16 ok[PM_RANK_MAX / 16];
    size_t nv = (na + 15) / 16;
    for (size_t t = 0; t < nv; t++) {
        size_t left = na - 16 * t;
        ok[t] = left >= 16 ? (__mmask16)0xFFFF : (__mmask16)((1u << left) - 1);
        v[t] = _mm512_maskz_loadu_ps(ok[t], D + 16 * t);
        r[t] = _mm512_setzero_si512();
    }
    switch (nv) {
    case 1: ranks_nv(D, na, v, r, 1); break;
    case 2: ranks_nv(D, na, v, r, 2); break;
    case 3: ranks_nv(D, na, v, r, 3); break;
    default: ranks_nv(D, na, v, r, 4); break;
    }
    uint32_t R[PM_RANK_MAX];
    for (size_t t = 0; t < nv; t++) _mm512_storeu_si512((void *)(R + 16 * t), r[t]);
    return rank_place(D, J, R, na, nk, Z);
}
#endif

#if PM_X86
/* AVX2 (8 lanes): the same filter, compacted through a table of lane
 * permutations (AVX2 has no compress); the same ranks, counted by
 * subtracting the all-ones lanes of the comparisons. */
static uint32_t perm8[256][8];   /* lane indices of the set bits of m, in order */
static pthread_once_t perm8_once = PTHREAD_ONCE_INIT;
static void perm8_init(void)
{
    for (int m = 0; m < 256; m++) {
        int c = 0;
        for (int b = 0; b < 8; b++) if (m >> b & 1) perm8[m][c++] = (uint32_t)b;
        while (c < 8) perm8[m][c++] = 0;
    }
}

__attribute__((target("avx2"))) static size_t filter_avx2(const float *restrict CX, const float *restrict CY,
                                                          const float *restrict CZ, size_t nc, const float p[3],
                                                          float fb, float *restrict D, uint32_t *restrict J)
{
    __m256 vx = _mm256_set1_ps(p[0]), vy = _mm256_set1_ps(p[1]), vz = _mm256_set1_ps(p[2]), vb = _mm256_set1_ps(fb);
    __m256i idx = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7), step = _mm256_set1_epi32(8);
    size_t na = 0;
    for (size_t j = 0; j < nc; j += 8) {
        __m256 dx = _mm256_sub_ps(_mm256_loadu_ps(CX + j), vx);
        __m256 dy = _mm256_sub_ps(_mm256_loadu_ps(CY + j), vy);
        __m256 dz = _mm256_sub_ps(_mm256_loadu_ps(CZ + j), vz);
        __m256 d2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)), _mm256_mul_ps(dz, dz));
        unsigned m = (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(d2, vb, _CMP_LE_OQ));
        __m256i pm = _mm256_loadu_si256((const __m256i *)(const void *)perm8[m]);
        _mm256_storeu_ps(D + na, _mm256_permutevar8x32_ps(d2, pm));
        _mm256_storeu_si256((__m256i *)(void *)(J + na), _mm256_permutevar8x32_epi32(idx, pm));
        na += (size_t)__builtin_popcount(m);
        idx = _mm256_add_epi32(idx, step);
    }
    return na;
}

__attribute__((target("avx2"), always_inline)) static inline void ranks8_nv(const float *D, size_t na, const __m256 *v,
                                                                          __m256i *r, const size_t NV)
{
    for (size_t m = 0; m < na; m++) {
        __m256 b = _mm256_set1_ps(D[m]);
        for (size_t t = 0; t < NV; t++)
            r[t] = _mm256_sub_epi32(r[t], _mm256_castps_si256(_mm256_cmp_ps(b, v[t], _CMP_LT_OQ)));
    }
}

__attribute__((target("avx2"))) static int rank_avx2(float *D, const uint32_t *J, size_t na, size_t nk, sref *Z)
{
    __m256 v[PM_RANK_MAX / 8];
    __m256i r[PM_RANK_MAX / 8];
    size_t nv = (na + 7) / 8;
    for (size_t i = na; i < 8 * nv; i++) D[i] = HUGE_VALF;   /* padding lanes (D has 16 spare) */
    for (size_t t = 0; t < nv; t++) {
        v[t] = _mm256_loadu_ps(D + 8 * t);
        r[t] = _mm256_setzero_si256();
    }
    switch (nv) {
    case 1: ranks8_nv(D, na, v, r, 1); break;
    case 2: ranks8_nv(D, na, v, r, 2); break;
    case 3: ranks8_nv(D, na, v, r, 3); break;
    case 4: ranks8_nv(D, na, v, r, 4); break;
    case 5: ranks8_nv(D, na, v, r, 5); break;
    case 6: ranks8_nv(D, na, v, r, 6); break;
    case 7: ranks8_nv(D, na, v, r, 7); break;
    default: ranks8_nv(D, na, v, r, 8); break;
    }
    uint32_t R[PM_RANK_MAX];
    for (size_t t = 0; t < nv; t++) _mm256_storeu_si256((__m256i *)(void *)(R + 8 * t), r[t]);
    return rank_place(D, J, R, na, nk, Z);
}
#endif

static int kernel_max = -1, kernel_use = -1;

static pthread_once_t kernel_once = PTHREAD_ONCE_INIT;
static void kernel_detect(void)
{
    int mx = 0;
#if PM_X86
    mx = hd_cpu_level();
    pthread_once(&perm8_once, perm8_init);
#endif
    __atomic_store_n(&kernel_max, mx, __ATOMIC_RELAXED);
    int u = -1;
    (void)__atomic_compare_exchange_n(&kernel_use, &u, mx, 0, __ATOMIC_RELAXED, __ATOMIC_RELAXED);
}

int hd_pmap_set_kernel(int level)
{
    pthread_once(&kernel_once, kernel_detect);
    int mx = __atomic_load_n(&kernel_max, __ATOMIC_RELAXED);
    int u = level < 0 || level > mx ? mx : level;
    __atomic_store_n(&kernel_use, u, __ATOMIC_RELAXED);
    return u;
}

static inline int pm_kernel(void)
{
    pthread_once(&kernel_once, kernel_detect);
    return __atomic_load_n(&kernel_use, __ATOMIC_RELAXED);
}

/* estimate() for the nk neighbours Z (sorted in the total order) of a
 * group point pp: the same expressions in the same order, read straight
 * from the candidates */
static void estimate_sel(const hd_pmap_lookup *l, const hd_pmap_source *S, const cand *cd, const float *CX,
                         const float *CY, const float *CZ, const sref *Z, size_t nk,
                         const float pp[3], const float nf[3], double *out)
{
    if (nk < 2) return;
    double r2;
    int skip_far;
    if (nk == l->o.k || !(l->o.max_radius > 0)) { r2 = (double)Z[nk - 1].d2; skip_far = 1; }
    else { r2 = l->o.max_radius * l->o.max_radius; skip_far = 0; }
    if (!(r2 > 0)) return;
    double hh = 0;
    for (size_t i = 0; i < nk; i++) {
        uint32_t j = Z[i].j;
        float dx = CX[j] - pp[0], dy = CY[j] - pp[1], dz = CZ[j] - pp[2];
        float h = dx * nf[0] + dy * nf[1] + dz * nf[2];
        hh += (double)h * h;
    }
    double r2d = disc_r2(r2, hh, nk);
    double norm = S->flux / (HD_PI * r2d);
    size_t nsum = skip_far ? nk - 1 : nk;   /* the farthest defines r */
    if (l->o.kernel == HD_PMAP_KERNEL_EPAN) {
        for (size_t i = 0; i < nsum; i++) {
            uint32_t j = Z[i].j;
            const cand *c = &cd[j];
            float dx = CX[j] - pp[0], dy = CY[j] - pp[1], dz = CZ[j] - pp[2];
            float h = dx * nf[0] + dy * nf[1] + dz * nf[2];
            double u = ((double)Z[i].d2 - (double)h * h) / r2d;
            double kw = u < 1 ? 2.0 * (1.0 - u) : 0;
            double f = norm * kw;
            out[0] += f * c->w[0];
            out[1] += f * c->w[1];
            out[2] += f * c->w[2];
        }
    } else {
        double f = norm * 1.0;
        for (size_t i = 0; i < nsum; i++) {
            const float *w = cd[Z[i].j].w;
            out[0] += f * w[0];
            out[1] += f * w[1];
            out[2] += f * w[2];
        }
    }
}

hd_status hd_pmap_irradiance_group(hd_pmap_lookup *l, uint32_t s, const hd_vec3 *p, size_t np, hd_vec3 n,
                                   double *out)
{
    hd_pmap *m = l->m;
    if (s >= m->info.nsources) return hd_fail(HD_ERR_RANGE, "source %u out of range", s);
    for (size_t i = 0; i < 3 * np; i++) out[i] = 0;
    const hd_pmap_source *S = &m->src[s];
    if (!S->npages || !np) return HD_OK;
    if (np < 3 || !(l->o.max_radius > 0)) {
        for (size_t i = 0; i < np; i++) {
            hd_status st = hd_pmap_irradiance(l, s, p[i], n, out + 3 * i, NULL, NULL);
            if (st) return st;
        }
        return HD_OK;
    }
    if (np > l->capgp) {
        float *g = hd_realloc_array(l->gp, np, 3 * sizeof *g);
        if (!g) return HD_ERR_NOMEM;
        l->gp = g;
        l->capgp = np;
    }
    /* the centre point q: nearest to the centroid */
    double c[3] = {0, 0, 0};
    for (size_t i = 0; i < np; i++) {
        l->gp[3 * i] = (float)p[i].x; l->gp[3 * i + 1] = (float)p[i].y; l->gp[3 * i + 2] = (float)p[i].z;
        for (int k = 0; k < 3; k++) c[k] += l->gp[3 * i + k];
    }
    size_t qi = 0;
    double best = HUGE_VAL, amax = 0;
    for (size_t i = 0; i < np; i++) {
        double d = 0;
        for (int k = 0; k < 3; k++) {
            double v = l->gp[3 * i + k] - c[k] / (double)np;
            d += v * v;
            if (fabs(l->gp[3 * i + k]) > amax) amax = fabs(l->gp[3 * i + k]);
        }
        if (d < best) { best = d; qi = i; }
    }
    const float *q = l->gp + 3 * qi;
    double ext = 0;
    for (size_t i = 0; i < np; i++) {
        double d = 0;
        for (int k = 0; k < 3; k++) { double v = (double)l->gp[3 * i + k] - q[k]; d += v * v; }
        if (d > ext) ext = d;
    }
    ext = sqrt(ext);
    double abs_m = 1e-6 * (1 + amax);   /* absolute margin: float rounding of coordinates this large */
    float rmax2 = (float)(l->o.max_radius * l->o.max_radius);
    double rmax = sqrt((double)rmax2);
    hd_status st;
    /* collection radius R: guessed from the previous group of this source,
     * remembered per source across batches (every point checks that its
     * k-th neighbour ball lies inside, else it is looked up alone), or for
     * a source's first group bounded exactly by the k nearest of q */
    double R, rq = -1;
    if (l->gr[s] > 0) {
        R = GRFAC * l->gr[s] + ext;
    } else {
        if ((st = knn(l, s, p[qi], n))) return st;
        rq = l->nh == l->o.k ? sqrt((double)l->heap[0].d2) : rmax;
        R = rq + 2 * ext;
    }
    if (R > rmax + ext) R = rmax + ext;
    R = R * (1 + GMARGIN) + abs_m;
    float nf[3] = {(float)n.x, (float)n.y, (float)n.z}, tol = (float)l->o.normal_tol;
    l->ncand = 0;
    uint64_t nind = m->src_nind[s];
    float R2 = (float)(R * R);
    if (nind && (st = collect_range(l, S->first_page, nind, m->ptree + m->src_tree[2 * s], q, nf, tol, R2))) return st;
    if (!l->o.direct_scene && S->npages > nind &&
        (st = collect_range(l, S->first_page + nind, S->npages - nind, m->ptree + m->src_tree[2 * s + 1], q, nf, tol,
                            R2)))
        return st;
    size_t nc = l->ncand;
    if (nc + 4 > l->capsel) {
        sref *ss = hd_realloc_array(l->sel, nc + 4, sizeof *ss);
        if (!ss) return HD_ERR_NOMEM;
        l->sel = ss;
        l->capsel = nc + 4;
    }
    if (nc + 16 > l->capsoa) {
        size_t ncap = nc + nc / 2 + 64;
        uint16_t *bb = hd_realloc_array(l->cbin, ncap, sizeof(uint16_t));
        if (bb) l->cbin = bb;
        float *fd = hd_realloc_array(l->fd, ncap, sizeof(float));
        if (fd) l->fd = fd;
        uint32_t *jj = hd_realloc_array(l->fj, ncap, sizeof(uint32_t));
        if (jj) l->fj = jj;
        if (!fd || !bb || !jj) return HD_ERR_NOMEM;
        l->capsoa = ncap;
    }
    const cand *cd = l->cand;
    float *restrict CX = l->cx, *restrict CY = l->cy, *restrict CZ = l->cz;
    uint16_t *restrict BK = l->cbin;
    /* whole vectors: far points after the last (collect_page left room) */
    for (size_t j = nc; j < ((nc + 15) & ~(size_t)15); j++) CX[j] = CY[j] = CZ[j] = 1e30f;   /* d2 = inf */
    float *restrict FD = l->fd;
    uint32_t *restrict FJ = l->fj;
    sref *Bs = l->sel;
    const int kern = pm_kernel();
    (void)kern;   /* used only by the SIMD kernels (none off x86-64 or with PM_NOVEC) */
    double gmax = 0;
    uint32_t k = l->o.k;
    int pv = 0;   /* previous point verified: its k-th distance, position */
    double prv = 0;
    const float *ppv = NULL;
    for (size_t i = 0; i < np; i++) {
        double *o = out + 3 * i;
        const float *pp = l->gp + 3 * i;
        double dpq = 0;
        for (int kk = 0; kk < 3; kk++) { double v = (double)pp[kk] - q[kk]; dpq += v * v; }
        dpq = sqrt(dpq);
        /* only photons whose ball around p lies inside the collected one
         * can be verified: bound (R - |p - q|)^2, less a margin */
        double bp = (R - abs_m) / (1 + GMARGIN) - dpq;
        bp = (bp - abs_m) / (1 + GMARGIN);
        if (rq >= 0 && (rq + dpq) * (1 + GMARGIN) + abs_m < bp) bp = (rq + dpq) * (1 + GMARGIN) + abs_m;
        float bound = bp <= 0 ? 0 : bp * bp < (double)rmax2 ? (float)(bp * bp) : rmax2;
        /* every candidate within the bound, then the k smallest in the
         * neighbours' total order: counting sort by d2 into bins of
         * [0, bound], keep the bins that hold the k nearest, insertion-sort
         * those (nearly sorted already).  The distance and bin loop runs
         * over arrays (vectorised); d2 is the same float expression as in
         * the point-by-point search. */
        /* tighter filter from the previous point of the group (verified,
         * so its k nearest are candidates): they lie within r_prev +
         * |p - p_prev| of p, so p's k nearest do too (if fewer than k pass,
         * float rounding: filter again with the bound) */
        float fb = bound, fb1 = bound;
        int tight = 0;
        if (pv) {
            double dd = 0;
            for (int kk = 0; kk < 3; kk++) { double v = (double)pp[kk] - ppv[kk]; dd += v * v; }
            dd = sqrt(dd);
            double t = (prv + dd) * (1 + GMARGIN) + abs_m;
            if (t * t < (double)bound) { fb = fb1 = (float)(t * t); tight = 1; }
            /* any filter radius that passes at least k candidates keeps all
             * of p's k nearest: first try a guess nearer r_prev */
            double t2 = prv + GTF * dd;
            if (t2 * t2 < (double)fb) { fb = (float)(t2 * t2); tight = 2; }
        }
        size_t na;
    refilter:
#if PM_X86
        if (kern >= 2) na = filter_avx512(CX, CY, CZ, nc, pp, fb, FD, FJ);
        else if (kern == 1) na = filter_avx2(CX, CY, CZ, nc, pp, fb, FD, FJ);
        else
#endif
            na = filter_c(CX, CY, CZ, nc, pp, fb, FD, FJ);
        if (tight == 2 && na < k) { fb = fb1; tight = fb1 < bound; goto refilter; }
        if (tight && na < k) { fb = bound; tight = 0; goto refilter; }
        size_t nk = na < k ? na : k;
        const sref *Z = Bs;
        int done = 0;
        if (na <= 1) {
            if (na) { Bs[0].d2 = FD[0]; Bs[0].j = FJ[0]; }
            done = 1;
        }
#if PM_X86
        if (!done && kern >= 2 && na <= PM_RANK_MAX) done = rank_avx512(FD, FJ, na, nk, Bs);
        if (!done && kern == 1 && na <= PM_RANK_MAX) done = rank_avx2(FD, FJ, na, nk, Bs);
#endif
        if (!done) {
            uint32_t cnt[NSBIN + 1], nbin = na >= NSBIN ? NSBIN : (uint32_t)na;   /* ~1 bin per photon */
            memset(cnt, 0, (nbin + 1) * sizeof *cnt);
            float sc = fb > 0 ? (float)nbin / fb : 0;
            for (size_t a2 = 0; a2 < na; a2++) {
                uint32_t bk = (uint32_t)(FD[a2] * sc);
                bk = bk < nbin - 1 ? bk : nbin - 1;
                BK[a2] = (uint16_t)bk;
                cnt[bk + 1]++;
            }
            uint32_t lastb = 0, run = 0;   /* cnt[b] = start of bin b, up to the bin holding the k-th */
            for (;; lastb++) {
                run += cnt[lastb + 1];
                cnt[lastb + 1] = run;
                if (run >= nk) break;
            }
            size_t take = run;
            for (size_t a2 = 0; a2 < na; a2++) {
                uint32_t bk = BK[a2];
                uint32_t ok = bk <= lastb, pos = ok ? cnt[bk] : (uint32_t)take;   /* Bs[take]: discard slot */
                Bs[pos].d2 = FD[a2];
                Bs[pos].j = FJ[a2];
                cnt[bk] += ok;
            }
            for (size_t a2 = 1; a2 < take; a2++) {
                if (!sref_less(&Bs[a2], &Bs[a2 - 1], cd)) continue;
                sref t = Bs[a2];
                size_t qq = a2;
                while (qq > 0 && sref_less(&t, &Bs[qq - 1], cd)) { Bs[qq] = Bs[qq - 1]; qq--; }
                Bs[qq] = t;
            }
        }
        l->nh = 0;   /* the heap is not used by group lookups */
        /* exact only if the point's search ball lies within the collected one */
        double rp = nk == k ? sqrt((double)Z[k - 1].d2) : rmax;
        if (nk == k) {
            if (rp > gmax) gmax = rp;
            l->rsum += rp;
            l->rcount++;
        }
        if ((rp * (1 + GMARGIN) + abs_m + dpq) * (1 + GMARGIN) + abs_m > R) {
            /* its k nearest candidates bound the search: the k-th one's
             * squared distance is the same float expression as the point
             * search computes, and at least k photons lie within it */
            if ((st = irradiance_b(l, s, p[i], n, o, NULL, NULL, nk == k ? Z[k - 1].d2 : HUGE_VALF))) return st;
            l->gmiss++;
            pv = 0;
            continue;
        }
        pv = nk == k;   /* its k nearest are candidates: a filter for the next point */
        prv = pv ? rp : 0;
        ppv = pp;
        if (l->o.direct_scene) add_direct(l, S, s, p[i], n, o, NULL, NULL);
        estimate_sel(l, S, cd, CX, CY, CZ, Z, nk, pp, nf, o);   /* Z is sorted in the total order */
    }
    l->gr[s] = gmax;
    return HD_OK;
}

/* Transmission of a shadow / gather ray through glass and invisible
 * surfaces until the first opaque hit; returns 0 if it hits something
 * opaque (hit in *h), 1 if it escapes (trans[3] = product). */
static int through_glass(const hd_tscene *ts, hd_vec3 org, hd_vec3 d, double eps, double trans[3], hd_hit *h)
{
    /* starts at org (tmin = eps) */
    trans[0] = trans[1] = trans[2] = 1;
    double tmin = eps;
    for (int guard = 0; guard < 100; guard++) {
        if (!hd_tscene_intersect(ts, org, d, tmin, 0, h)) return 1;
        const hd_surface *f = hd_tscene_surface(ts, h->surf);
        const hd_tmat *m = hd_tscene_material(ts, f->mat);
        while (m && m->type == HD_MAT_ILLUM) m = m->alt >= 0 ? hd_tscene_material(ts, m->alt) : NULL;
        hd_tmat mt;
        m = hd_scatter_hitmat(m, h, d, &mt);
        if (!m || m->type == HD_MAT_INVISIBLE) { org = h->p; continue; }
        if (m->type != HD_MAT_GLASS) return 0;
        double R[3], T[3];
        hd_glass_coeffs(m->color, m->rindex, fabs(hd_vdot(d, h->n)), R, T);
        for (int k = 0; k < 3; k++) trans[k] *= T[k];
        org = h->p;
    }
    return 0;
}

hd_status hd_pmap_final_gather(hd_pmap_lookup *l, const hd_tscene *ts, uint32_t s, hd_vec3 p, hd_vec3 n,
                               int nrays, hd_rng *rng, double out[3])
{
    hd_pmap *m = l->m;
    out[0] = out[1] = out[2] = 0;
    if (s >= m->info.nsources) return hd_fail(HD_ERR_RANGE, "source %u out of range", s);
    const hd_pmap_source *S = &m->src[s];
    double eps = hd_tscene_eps(ts);
    hd_vec3 a, b;
    hd_vbasis(n, &a, &b);
    /* direct: shadow ray to the source centre (solid angle of the disk) */
    direct_term(ts, S, p, n, out);
    /* caustics: light that reached p after specular or BSDF scattering
     * with no diffuse bounce (photons flagged caustic); the gather rays
     * below see only the diffuse reflection of the surfaces they hit, and
     * the shadow ray above only glass, so this part comes from the photons
     * at p: the caustic ones among p's k nearest, over the same disc */
    if (S->npages) {
        hd_status st = knn(l, s, p, n);
        if (st) return st;
        estimate(l, S, s, out, NULL, NULL, PM_F_CAUSTIC, 0);
    }
    if (nrays <= 0) return HD_OK;
    double acc[3] = {0, 0, 0};
    int g = (int)sqrt((double)nrays);
    if (g < 1) g = 1;
    for (int i = 0; i < nrays; i++) {
        int j = i % (g * g);
        double u1 = ((j % g) + hd_rng_uniform(rng)) / g, u2 = ((j / g) + hd_rng_uniform(rng)) / g;
        double r = sqrt(u1), phi = 2 * HD_PI * u2;
        hd_vec3 d = hd_vnorm(hd_vadd(hd_vadd(hd_vscale(a, r * cos(phi)), hd_vscale(b, r * sin(phi))),
                                     hd_vscale(n, sqrt(1 - u1 > 0 ? 1 - u1 : 0))));
        double T[3];
        hd_hit h;
        if (through_glass(ts, p, d, eps, T, &h)) continue;
        const hd_surface *f = hd_tscene_surface(ts, h.surf);
        const hd_tmat *mt = hd_tscene_material(ts, f->mat);
        while (mt && mt->type == HD_MAT_ILLUM) mt = mt->alt >= 0 ? hd_tscene_material(ts, mt->alt) : NULL;
        hd_tmat mtl;
        mt = hd_scatter_hitmat(mt, &h, d, &mtl);
        if (!mt || hd_tmat_emits(mt)) continue;
        if (mt->type != HD_MAT_PLASTIC && mt->type != HD_MAT_METAL && mt->type != HD_MAT_TRANS) continue;
        hd_vec3 nf = hd_vdot(d, h.n) < 0 ? h.n : hd_vneg(h.n);
        hd_nshade ns;
        hd_normal_coeffs(mt, fabs(hd_vdot(d, h.n)), &ns);
        double e[3];
        hd_status st = hd_pmap_irradiance(l, s, h.p, nf, e, NULL, NULL);
        if (st) return st;
        for (int k = 0; k < 3; k++) acc[k] += T[k] * ns.rdiff[k] * e[k];
    }
    for (int k = 0; k < 3; k++) out[k] += acc[k] / nrays;
    return HD_OK;
}
