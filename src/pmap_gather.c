/* heliodon — contribution photon map lookups: per-source k nearest
 * neighbours through the page cache, density estimates, direction bins,
 * one-bounce final gather. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/material.h"
#include "heliodon/rng.h"
#include "heliodon/trace.h"
#include "pmap_internal.h"

void hd_pmap_lookup_opts_init(hd_pmap_lookup_opts *o)
{
    memset(o, 0, sizeof *o);
    o->k = 50;
    o->normal_tol = 0.9;
    o->kernel = HD_PMAP_KERNEL_FLAT;
}

typedef struct nb { double d2; float w[3]; uint16_t dir; } nb;

struct hd_pmap_lookup {
    hd_pmap *m;
    hd_pmap_lookup_opts o;
    nb *heap;                 /* max-heap on d2, size k */
    uint32_t nh;
    double *pd2;              /* candidate page distances */
    uint64_t *pidx;
    size_t pcap;
};

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
    uint64_t maxp = 1;
    for (uint32_t s = 0; s < m->info.nsources; s++) if (m->src[s].npages > maxp) maxp = m->src[s].npages;
    l->pcap = (size_t)maxp;
    l->pd2 = hd_malloc_array(l->pcap, sizeof *l->pd2);
    l->pidx = hd_malloc_array(l->pcap, sizeof *l->pidx);
    if (!l->heap || !l->pd2 || !l->pidx) { hd_pmap_lookup_free(l); return HD_ERR_NOMEM; }
    *out = l;
    return HD_OK;
}

void hd_pmap_lookup_free(hd_pmap_lookup *l)
{
    if (!l) return;
    free(l->heap);
    free(l->pd2);
    free(l->pidx);
    free(l);
}

static double box_d2(const float *lo, const float *hi, hd_vec3 p)
{
    double d = 0, v;
    v = p.x < lo[0] ? lo[0] - p.x : p.x > hi[0] ? p.x - hi[0] : 0; d += v * v;
    v = p.y < lo[1] ? lo[1] - p.y : p.y > hi[1] ? p.y - hi[1] : 0; d += v * v;
    v = p.z < lo[2] ? lo[2] - p.z : p.z > hi[2] ? p.z - hi[2] : 0; d += v * v;
    return d;
}

static void heap_push(hd_pmap_lookup *l, const nb *e)
{
    uint32_t k = l->o.k;
    nb *h = l->heap;
    if (l->nh < k) {
        uint32_t i = l->nh++;
        while (i > 0) {
            uint32_t par = (i - 1) / 2;
            if (h[par].d2 > e->d2 || (h[par].d2 == e->d2)) break;
            h[i] = h[par];
            i = par;
        }
        h[i] = *e;
        return;
    }
    if (e->d2 >= h[0].d2) return;
    uint32_t i = 0;
    for (;;) {
        uint32_t a = 2 * i + 1, b = a + 1, c = i;
        double dc = e->d2;
        if (a < k && h[a].d2 > dc) { c = a; dc = h[a].d2; }
        if (b < k && h[b].d2 > dc) { c = b; }
        if (c == i) break;
        h[i] = h[c];
        i = c;
    }
    h[i] = *e;
}

/* Collect the k nearest compatible photons of source s. */
static hd_status knn(hd_pmap_lookup *l, uint32_t s, hd_vec3 p, hd_vec3 n)
{
    hd_pmap *m = l->m;
    const hd_pmap_source *S = &m->src[s];
    l->nh = 0;
    double rmax2 = l->o.max_radius > 0 ? l->o.max_radius * l->o.max_radius : HUGE_VAL;
    size_t nc = 0;
    for (uint64_t i = 0; i < S->npages; i++) {
        uint64_t pg = S->first_page + i;
        double d2 = box_d2(m->pages[pg].lo, m->pages[pg].hi, p);
        if (d2 > rmax2) continue;
        /* insertion into a sorted list (ties by page index: deterministic) */
        size_t j = nc++;
        while (j > 0 && (l->pd2[j - 1] > d2)) { l->pd2[j] = l->pd2[j - 1]; l->pidx[j] = l->pidx[j - 1]; j--; }
        l->pd2[j] = d2;
        l->pidx[j] = pg;
    }
    float nx = (float)n.x, ny = (float)n.y, nz = (float)n.z, tol = (float)l->o.normal_tol;
    int skipdirect = l->o.direct_scene != NULL;
    for (size_t c = 0; c < nc; c++) {
        double bound = l->nh == l->o.k ? l->heap[0].d2 : rmax2;
        if (l->pd2[c] >= bound) break;
        const pm_page *pg;
        hd_status st = pm_page_get(m, l->pidx[c], &pg);
        if (st) return st;
        for (uint32_t b = 0; b < pg->nblocks; b++) {
            bound = l->nh == l->o.k ? l->heap[0].d2 : rmax2;
            if (box_d2(pg->blo + 3 * b, pg->bhi + 3 * b, p) >= bound) continue;
            uint32_t e = (b + 1) * PM_BLOCK < pg->count ? (b + 1) * PM_BLOCK : pg->count;
            for (uint32_t i = b * PM_BLOCK; i < e; i++) {
                const float *q = pg->pos + 3 * i, *qn = pg->nrm + 3 * i;
                if (qn[0] * nx + qn[1] * ny + qn[2] * nz < tol) continue;
                if (skipdirect && (pg->flags[i] & PM_F_DIRECT)) continue;
                double dx = q[0] - p.x, dy = q[1] - p.y, dz = q[2] - p.z;
                double d2 = dx * dx + dy * dy + dz * dz;
                if (d2 >= rmax2) continue;
                if (l->nh == l->o.k && d2 >= l->heap[0].d2) continue;
                nb e2;
                e2.d2 = d2;
                memcpy(e2.w, pg->w + 3 * i, sizeof e2.w);
                e2.dir = pg->dir[i];
                heap_push(l, &e2);
            }
        }
        pm_page_release(m, l->pidx[c]);
    }
    return HD_OK;
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

hd_status hd_pmap_irradiance(hd_pmap_lookup *l, uint32_t s, hd_vec3 p, hd_vec3 n, double *out,
                             hd_pmap_binfn binfn, void *binctx)
{
    hd_pmap *m = l->m;
    if (s >= m->info.nsources) return hd_fail(HD_ERR_RANGE, "source %u out of range", s);
    if (!binfn) out[0] = out[1] = out[2] = 0;
    const hd_pmap_source *S = &m->src[s];
    if (!S->npages) return HD_OK;
    if (l->o.direct_scene) {
        double dt[3];
        direct_term(l->o.direct_scene, S, p, n, dt);
        if (dt[0] > 0 || dt[1] > 0 || dt[2] > 0) {
            int b = binfn ? binfn(binctx, s, S->dir) : 0;
            if (b >= 0) for (int k = 0; k < 3; k++) out[3 * b + k] += dt[k];
        }
    }
    hd_status st = knn(l, s, p, n);
    if (st) return st;
    if (l->nh < 2) return HD_OK;
    double r2;
    int skip_far;
    if (l->nh == l->o.k || !(l->o.max_radius > 0)) { r2 = l->heap[0].d2; skip_far = 1; }
    else { r2 = l->o.max_radius * l->o.max_radius; skip_far = 0; }
    if (!(r2 > 0)) return HD_OK;
    /* the heap's layout depends only on the order photons were offered
     * (pages by distance, then file order): the same for any cache size */
    double norm = S->flux / (HD_PI * r2);
    for (uint32_t i = 0; i < l->nh; i++) {
        const nb *e = &l->heap[i];
        double kw;
        if (skip_far && i == 0) continue;   /* heap top = farthest (defines r) */
        if (l->o.kernel == HD_PMAP_KERNEL_EPAN) kw = 2.0 * (1.0 - e->d2 / r2);
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
