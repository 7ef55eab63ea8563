/* heliodon — rcontrib -ap: the photon gather estimator of the rcontrib
 * driver (rcdriver.h).  Per ray, the photon lookups of every tracked
 * light-source modifier (-ab < 0: at the primary hit; -ab >= 0: one final
 * gather bounce with -ad rays), binned per modifier and, through the bin
 * function, by the photon's incident direction. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "heliodon/material.h"
#include "heliodon/parallel.h"
#include "pmprimary.h"
#include "heliodon/pmap.h"
#include "heliodon/rcmerge.h"
#include "heliodon/rng.h"
#include "heliodon/trace.h"
#include "pmap_internal.h"
#include "rcdriver.h"

/* ---- per-modifier source lists and bins ---- */
typedef struct rcmod {
    uint32_t *src;
    int nsrc;
} rcmod;

typedef struct binctx { const hd_binfn *b; } binctx;
static int binfn_cb(void *ctx, uint32_t src, hd_vec3 from)
{
    (void)src;
    const binctx *bc = ctx;
    int b = hd_binfn_eval(bc->b, from, 0.5, 0.5);
    return b >= 0 && b < bc->b->nbins ? b : -1;
}

/* -stats: the gather's work, counted per worker */
typedef struct pmcount {
    uint64_t rays, points;    /* primary rays traced, lookup points they found */
    uint64_t lookups;         /* irradiance estimates (point x source) */
    uint64_t groups;          /* group lookups (-ab < 0, modifiers without bins) */
    uint64_t gathers;         /* final gathers (-ab >= 0: point x source, -ad rays each) */
    uint64_t analytic;        /* records with analytic terms (-apd) */
} pmcount;

typedef struct rcjob {
    const hd_contrib *c;
    const hd_rcontrib_opts *o;
    const hd_rc_pmap_opts *po;
    hd_pmap *m;
    rcmod *mods;
    hd_pmap_lookup **lk;      /* per worker */
    double **tmp;             /* per worker, 3 * max bins */
    const hd_vec3 *org, *dir;
    uint64_t rec0;            /* global record index of the first record of the batch */
    int per;
    size_t rlen;
    double *out;
    /* value (record u, column c) at out + u * us + c * cs: record-major
     * (us = rlen, cs = 3), or column-major for pictures at -ab < 0 (us = 3,
     * cs = 3 x batch: a source's column is written contiguously) */
    size_t us, cs;
    /* column-major pictures: each worker zeroes its modifiers' columns and,
     * once they are complete, encodes them into the spool block (stream
     * colstream[col]) */
    hd_rc_out *os;
    const int *colstream;
    double **colbuf;          /* per worker: 3 x batch doubles per bin of one modifier */
    /* source-major -ab < 0 */
    hd_pmprim *gpp;           /* primary hit of every ray of the batch */
    size_t nrec;              /* records in the batch */
    /* coherent groups of lookup points (same normal, nearby): point ids
     * (ray index * HD_PMPRIM_PTS + point) in group order, group starts */
    uint32_t *gid;
    size_t *gstart, ngroups;
    size_t *gord;             /* groups in the Morton order of their first points (across normals) */
    hd_vec3 *gpt, *gn;        /* lookup points in group order, normal of each group */
    uint8_t *pnpt, *pnana;    /* per ray: lookup points, analytic records */
    double *pf;               /* per point id: the weight f[3] of its irradiance */
    double **gval;            /* per worker: 3 values per point id */
    pmcount *cnt;             /* per worker */
} rcjob;

/* Analytic part (pmap_primary.c) of source S for the ray resolved in pp,
 * added to the source's direction bin. */
static void add_analytic(const rcjob *j, const hd_cmod *cm, binctx *bc, uint32_t s, const hd_pmap_source *S,
                         const hd_pmprim *pp, double *rec, size_t cs, size_t col0)
{
    if (!pp->nana || !j->po->exact_direct) return;
    double d[3] = {0, 0, 0};
    if (!hd_pmprim_direct(j->c->ts, pp, S->dir, S->half_angle, j->c->o.ss, d)) return;
    int b = cm->bin.kind == HD_BIN_CONST ? 0 : binfn_cb(bc, s, S->dir);
    if (b < 0) return;
    for (int q = 0; q < 3; q++) {
        double v = d[q];
        if (j->c->vflag) v *= S->radiance[q];
        rec[cs * (col0 + (size_t)b) + q] += v;
    }
}

/* The terms v[3] of one lookup point with weight f[3] (per channel) added
 * into col[3], times the source's radiance with -V. */
static inline void add_point(const rcjob *j, const hd_pmap_source *S, const double *v, const double *f, double *col)
{
    for (int q = 0; q < 3; q++) {
        double x = v[q] * f[q];
        if (j->c->vflag) x *= S->radiance[q];
        col[q] += x;
    }
}

/* -ab >= 0: coefficients of the ray resolved in pp into rec: the final
 * gather's irradiance at each lookup point (scaled by its weight per
 * channel) in the bin of the source's direction, plus the analytic terms. */
static hd_status gather_ray(rcjob *j, int w, const hd_pmprim *pp, hd_rng *rng, double *rec)
{
    const hd_contrib *c = j->c;
    for (int mi = 0; mi < c->nmods; mi++) {
        const hd_cmod *cm = &c->mods[mi];
        binctx bc = {&cm->bin};
        for (int k = 0; k < j->mods[mi].nsrc; k++) {
            uint32_t s = j->mods[mi].src[k];
            const hd_pmap_source *S = hd_pmap_get_source(j->m, s);
            int b = binfn_cb(&bc, s, S->dir);
            for (int t = 0; t < pp->npt; t++) {
                double e[3];
                hd_status st = hd_pmap_final_gather(j->lk[w], c->ts, s, pp->pt[t].p, pp->pt[t].n, c->o.ad, rng, e);
                if (st) return st;
                if (b >= 0) add_point(j, S, e, pp->pt[t].f, rec + 3 * ((size_t)cm->first + (size_t)b));
            }
            j->cnt[w].gathers += (uint64_t)pp->npt;
            if (pp->nana && j->po->exact_direct) j->cnt[w].analytic++;
            add_analytic(j, cm, &bc, s, S, pp, rec, 3, (size_t)cm->first);
        }
    }
    return HD_OK;
}

/* The primary hit of a ray (pmap_primary.c): the -I point, or the diffuse
 * lookups behind glass / mirrors (f = scale x path weight, x rho_d / pi for
 * radiance) and the analytic records (specular highlights, BSDF data, rays
 * escaping towards a source).  -apd- (Radiance's behaviour) follows glass
 * transmission only. */
static int resolve_ray(const rcjob *j, hd_vec3 org, hd_vec3 dir, double scale, hd_pmprim *pp)
{
    int depth = j->po->exact_direct ? 2 : 0;
    return hd_pmap_primary(j->c->ts, org, dir, j->o->irrad, scale, depth, 1e-4, pp);
}

static hd_status trace_ray(void *ctx, int w, hd_vec3 org, hd_vec3 dir, hd_rng *rng, double scale, double *rec)
{
    rcjob *j = ctx;
    hd_pmprim pp;
    j->cnt[w].rays++;
    if (!resolve_ray(j, org, dir, scale, &pp)) return HD_OK;
    j->cnt[w].points += (uint64_t)pp.npt;
    return gather_ray(j, w, &pp, rng, rec);
}

/* -ab < 0, source-major: first the lookup points of a batch, then for each
 * source all records (the pages of one source stay in the cache; per record
 * the columns receive their terms in the same order as gather_point). */
static hd_status rc_points(void *ctx, size_t b, size_t e, size_t ci, int w)
{
    (void)ci;
    rcjob *j = ctx;
    for (size_t u = b; u < e; u++) {
        if (!j->colstream) memset(j->out + u * j->rlen, 0, j->rlen * sizeof(double));   /* record-major only */
        for (int k = 0; k < j->per; k++) {
            size_t idx = u * (size_t)j->per + (size_t)k;
            const hd_pmprim *pp = &j->gpp[idx];
            resolve_ray(j, j->org[idx], j->dir[idx], 1.0 / j->per, &j->gpp[idx]);
            j->cnt[w].rays++;
            j->cnt[w].points += (uint64_t)pp->npt;
            if (j->pf) {   /* compact copies for the per-source accumulation */
                j->pnpt[idx] = (uint8_t)pp->npt;
                j->pnana[idx] = (uint8_t)(pp->nana > 0);
                for (int t = 0; t < pp->npt; t++) memcpy(j->pf + 3 * (idx * HD_PMPRIM_PTS + (size_t)t), pp->pt[t].f, 3 * sizeof(double));
            }
        }
    }
    return HD_OK;
}

/* All records of the batch for source src of modifier mi (worker w).  A
 * modifier without bins takes its points' irradiances from group lookups
 * of the coherent groups, made first; with bins each point is looked up
 * alone.  The records receive their terms in the same order either way. */
static hd_status source_records(rcjob *j, int w, int mi, uint32_t src)
{
    const hd_cmod *cm = &j->c->mods[mi];
    int grouped = cm->bin.kind == HD_BIN_CONST;
    int nb = grouped ? 1 : cm->bin.nbins;
    binctx bc = {&cm->bin};
    const hd_pmap_source *S = hd_pmap_get_source(j->m, src);
    pmcount *k = &j->cnt[w];
    /* columns: the modifier's own buffer (column-major pictures) or out */
    double *ob = j->colstream ? j->colbuf[w] : j->out;
    size_t cf = j->colstream ? 0 : (size_t)cm->first;
    double *gv = j->gval[w];
    for (size_t gi = 0; grouped && gi < j->ngroups; gi++) {
        size_t g = j->gord[gi], b = j->gstart[g], e = j->gstart[g + 1];
        double *gout = gv + 3 * j->nrec * (size_t)j->per * HD_PMPRIM_PTS;   /* scratch after the ids */
        hd_status st = hd_pmap_irradiance_group(j->lk[w], src, j->gpt + b, e - b, j->gn[g], gout);
        if (st) return st;
        for (size_t i = b; i < e; i++) memcpy(gv + 3 * (size_t)j->gid[i], gout + 3 * (i - b), 3 * sizeof(double));
        k->groups++;
        k->lookups += e - b;
    }
    for (size_t u = 0; u < j->nrec; u++) {
        double *rec = ob + u * j->us;
        for (int r = 0; r < j->per; r++) {
            size_t idx = u * (size_t)j->per + (size_t)r;
            for (int t = 0; t < j->pnpt[idx]; t++) {
                size_t id = idx * HD_PMPRIM_PTS + (size_t)t;
                const double *v = gv + 3 * id;
                if (!grouped) {
                    v = j->tmp[w];
                    memset(j->tmp[w], 0, sizeof(double) * 3 * (size_t)nb);
                    hd_status st = hd_pmap_irradiance(j->lk[w], src, j->gpp[idx].pt[t].p, j->gpp[idx].pt[t].n,
                                                      j->tmp[w], binfn_cb, &bc);
                    if (st) return st;
                    k->lookups++;
                }
                for (int bb = 0; bb < nb; bb++) add_point(j, S, v + 3 * bb, j->pf + 3 * id, rec + j->cs * (cf + (size_t)bb));
            }
            if (j->pnana[idx]) {
                add_analytic(j, cm, &bc, src, S, &j->gpp[idx], rec, j->cs, cf);
                if (j->po->exact_direct) k->analytic++;
            }
        }
    }
    return HD_OK;
}

/* ---- coherent groups of lookup points ----
 * The batch's lookup points sorted by (normal, Morton code of the
 * position); a group is a run with the same normal in one cell of about
 * the search radius, at most GROUP_MAX points.  Groups only change which
 * photons one traversal collects, never a result. */
#ifndef GROUP_MAX
#define GROUP_MAX 64
#endif
#ifndef GCELLF
#define GCELLF 2.5    /* group extent: GCELLF x the mean k-th distance (h-gather3: 1.0 -> 1.75, -7 % instructions;
                       * session 5, with the cheap AVX-512 per-point filter: 1.75 -> 2.5, -7 % CPU at 256^2) */
#endif

typedef struct gkey { uint32_t nb[3]; uint32_t id; uint64_t key; } gkey;

static int gkey_cmp(const void *a, const void *b)
{
    const gkey *x = a, *y = b;
    for (int k = 0; k < 3; k++) if (x->nb[k] != y->nb[k]) return x->nb[k] < y->nb[k] ? -1 : 1;
    if (x->key != y->key) return x->key < y->key ? -1 : 1;
    return x->id < y->id ? -1 : x->id > y->id;
}

static uint32_t fbits(double v)
{
    float f = (float)v;
    uint32_t u;
    memcpy(&u, &f, 4);
    return u;
}

/* The Morton code of p quantised to 21 bits per axis in the map's bounding cube: the groups' order
 * and the driver's locality keys. */
static uint64_t point_key(const hd_pmap_info *I, hd_vec3 p)
{
    double sc = 2097152.0 / I->size;
    double v[3] = {(p.x - I->org.x) * sc, (p.y - I->org.y) * sc, (p.z - I->org.z) * sc};
    uint32_t q[3];
    for (int k = 0; k < 3; k++) q[k] = v[k] < 0 ? 0 : v[k] > 2097151 ? 2097151 : (uint32_t)v[k];
    return hd_pmap_morton(q[0], q[1], q[2]);
}

static hd_status build_groups(rcjob *j, const hd_pmap_info *I, double cell)
{
    size_t nray = j->nrec * (size_t)j->per, npt = 0;
    for (size_t r = 0; r < nray; r++) npt += (size_t)j->gpp[r].npt;
    j->ngroups = 0;
    if (!npt) { j->gstart[0] = 0; return HD_OK; }
    gkey *g = hd_malloc_array(npt, sizeof *g);
    if (!g) return HD_ERR_NOMEM;
    size_t n = 0;
    for (size_t r = 0; r < nray; r++)
        for (int t = 0; t < j->gpp[r].npt; t++) {
            const hd_pmprim_point *pt = &j->gpp[r].pt[t];
            g[n].nb[0] = fbits(pt->n.x); g[n].nb[1] = fbits(pt->n.y); g[n].nb[2] = fbits(pt->n.z);
            g[n].id = (uint32_t)(r * HD_PMPRIM_PTS + (size_t)t);
            g[n].key = point_key(I, pt->p);
            n++;
        }
    qsort(g, n, sizeof *g, gkey_cmp);
    /* greedy in Morton order: a group ends at a new normal, at GROUP_MAX
     * points, or at a point farther than the cell size from its first */
    size_t ng = 0;
    hd_vec3 first = hd_v3(0, 0, 0);
    double c2 = cell * cell;
    for (size_t i = 0; i < n; i++) {
        hd_vec3 pi = j->gpp[g[i].id / HD_PMPRIM_PTS].pt[g[i].id % HD_PMPRIM_PTS].p;
        int cut = i == 0 || i - j->gstart[ng - 1] >= GROUP_MAX || memcmp(g[i].nb, g[i - 1].nb, sizeof g[i].nb);
        if (!cut) {
            hd_vec3 d = hd_vsub(pi, first);
            cut = hd_vdot(d, d) > c2;
        }
        if (cut) {
            j->gn[ng] = j->gpp[g[i].id / HD_PMPRIM_PTS].pt[g[i].id % HD_PMPRIM_PTS].n;
            j->gstart[ng++] = i;
            first = pi;
        }
        j->gid[i] = g[i].id;
        j->gpt[i] = pi;
    }
    j->gstart[ng] = n;
    j->ngroups = ng;
    /* the groups visited in the Morton order of their first points, not
     * normal by normal: with a cache smaller than a source's photons, a
     * pass per normal would decode a source's pages once per normal */
    gkey *go = hd_malloc_array(ng ? ng : 1, sizeof *go);
    if (!go) { free(g); return HD_ERR_NOMEM; }
    for (size_t q = 0; q < ng; q++) {
        memset(go[q].nb, 0, sizeof go[q].nb);
        go[q].key = g[j->gstart[q]].key;
        go[q].id = (uint32_t)q;
    }
    qsort(go, ng, sizeof *go, gkey_cmp);
    for (size_t q = 0; q < ng; q++) j->gord[q] = go[q].id;
    free(go);

    free(g);
    return HD_OK;
}

/* -ab < 0: workers take whole modifiers (their columns are disjoint), each
 * source for all records of the batch (the source's pages stay in the
 * cache, and one barrier per batch instead of one per source). */
static hd_status rc_mods(void *ctx, size_t b, size_t e, size_t ci, int w)
{
    (void)ci;
    rcjob *j = ctx;
    for (size_t mi = b; mi < e; mi++) {
        const hd_cmod *cm = &j->c->mods[mi];
        size_t c0 = (size_t)cm->first, nb = (size_t)(cm->bin.nbins > 0 ? cm->bin.nbins : 1);
        if (j->colstream)   /* the worker's column buffer (stays in cache from one modifier to the next) */
            for (size_t b2 = 0; b2 < nb; b2++) memset(j->colbuf[w] + b2 * j->cs, 0, 3 * j->nrec * sizeof(double));
        for (int k = 0; k < j->mods[mi].nsrc; k++) {
            uint32_t src = j->mods[mi].src[k];
            if (!hd_pmap_get_source(j->m, src)->npages) continue;
            hd_status st = source_records(j, w, (int)mi, src);
            if (st) return st;
        }
        if (j->colstream)
            for (size_t b2 = 0; b2 < nb; b2++)
                if (j->colstream[c0 + b2] >= 0)
                    hd_rc_out_encode(j->os, j->colstream[c0 + b2], j->colbuf[w] + b2 * j->cs, j->nrec, 3);
    }
    return HD_OK;
}

/* ---- the estimator ---- */
typedef struct pmest {
    rcjob j;
    const hd_pmap_info *I;
    hd_pmap_lookup_opts lo;
    int nth, maxbins;
    size_t batch, batch_big; /* records per batch: the first batch, and once the page cache proved too small */
    uint64_t evict0;          /* page evictions before the first batch */
    double gcell;             /* group extent: GCELLF x the mean k-th distance of the previous batch */
} pmest;

/* ---- locality keys (the driver's coherent order, -ab < 0) ----
 * Per record the Morton code of its first lookup point in the map's
 * bounding cube (as the groups), UINT64_MAX for records without one. */
typedef struct keyjob { rcjob *j; const hd_pmap_info *I; const hd_vec3 *org, *dir; int per; uint64_t *key; } keyjob;

static hd_status key_units(void *ctx, size_t b, size_t e, size_t ci, int w)
{
    (void)ci; (void)w;
    const keyjob *kj = ctx;
    for (size_t u = b; u < e; u++) {
        kj->key[u] = UINT64_MAX;
        for (int k = 0; k < kj->per; k++) {
            size_t idx = u * (size_t)kj->per + (size_t)k;
            hd_pmprim pp;
            if (!resolve_ray(kj->j, kj->org[idx], kj->dir[idx], 1.0 / kj->per, &pp) || !pp.npt) continue;
            kj->key[u] = point_key(kj->I, pp.pt[0].p);
            break;
        }
    }
    return HD_OK;
}

static hd_status pm_keys(void *ctx, const hd_vec3 *org, const hd_vec3 *dir, size_t nrec, int per, uint64_t *key)
{
    pmest *e = ctx;
    keyjob kj = {&e->j, e->I, org, dir, per, key};
    return hd_parallel_for(nrec, 256, e->nth, key_units, &kj);
}

/* The arrays sized by the batch (pm_batch_alloc) */
static void pm_batch_free(pmest *e)
{
    rcjob *j = &e->j;
    int nth = e->nth;
    for (int w = 0; j->colbuf && w < nth; w++) free(j->colbuf[w]);
    free(j->colbuf);
    for (int w = 0; j->gval && w < nth; w++) free(j->gval[w]);
    free(j->gval);
    free(j->gpp);
    free(j->gid);
    free(j->gstart);
    free(j->gord);
    free(j->gpt);
    free(j->gn);
    free(j->pnpt);
    free(j->pnana);
    free(j->pf);
    j->colbuf = NULL;
    j->gval = NULL;
    j->gpp = NULL;
    j->gid = NULL;
    j->gstart = j->gord = NULL;
    j->gpt = j->gn = NULL;
    j->pnpt = j->pnana = NULL;
    j->pf = NULL;
}

static void pm_free(void *ctx)
{
    pmest *e = ctx;
    if (!e) return;
    rcjob *j = &e->j;
    int nth = e->nth;
    pm_batch_free(e);
    free(j->cnt);
    for (int w = 0; j->lk && w < nth; w++) hd_pmap_lookup_free(j->lk[w]);
    for (int w = 0; j->tmp && w < nth; w++) free(j->tmp[w]);
    free(j->lk);
    free(j->tmp);
    for (int mi = 0; j->mods && mi < j->c->nmods; mi++) free(j->mods[mi].src);
    free(j->mods);
    if (j->m) hd_pmap_close(j->m);
    free(e);
}

/* -ab < 0, first batch: the mean k-th distance at up to 64 of its points
 * for the first source with photons */
static hd_status probe_cell(pmest *e)
{
    rcjob *j = &e->j;
    const hd_contrib *c = j->c;
    uint32_t ps = UINT32_MAX;
    for (int mi = 0; mi < c->nmods && ps == UINT32_MAX; mi++)
        for (int q = 0; q < j->mods[mi].nsrc; q++)
            if (hd_pmap_get_source(j->m, j->mods[mi].src[q])->npages) { ps = j->mods[mi].src[q]; break; }
    size_t nray = j->nrec * (size_t)j->per, stepr = nray / 64 + 1;
    double e3[3];
    for (size_t r = 0; ps != UINT32_MAX && r < nray; r += stepr)
        if (j->gpp[r].npt) {
            hd_status st = hd_pmap_irradiance(j->lk[0], ps, j->gpp[r].pt[0].p, j->gpp[r].pt[0].n, e3, NULL, NULL);
            if (st) return st;
        }
    e->gcell = GCELLF * hd_pmap_lookup_radius(j->lk[0], 1);
    if (!(e->gcell > 0)) e->gcell = 0.1 * e->lo.max_radius;
    return HD_OK;
}

static hd_status pm_run(void *ctx, const hd_rc_batch *b)
{
    pmest *e = ctx;
    rcjob *j = &e->j;
    j->org = b->org;
    j->dir = b->dir;
    j->rec0 = b->rec0;
    j->per = b->per;
    j->rlen = b->rlen;
    j->out = b->out;
    j->os = b->os;
    j->colstream = b->colstream;
    j->nrec = b->nrec;
    int nth = e->nth;
    hd_status st;
    if (j->c->o.ab >= 0) return hd_rc_per_ray(b, j->c->o.seed, nth, 8, trace_ray, j);
    if ((st = hd_parallel_for(b->nrec, 8, nth, rc_points, j))) return st;
    if (!(e->gcell > 0) && (st = probe_cell(e))) return st;
    if ((st = build_groups(j, e->I, e->gcell))) return st;
    if ((st = hd_parallel_for((size_t)j->c->nmods, 1, nth, rc_mods, j))) return st;
    double rs = 0, rn = 0;   /* next batch's group cell from this batch's radii */
    for (int w = 0; w < nth; w++) {
        double r = hd_pmap_lookup_radius(j->lk[w], 0);
        if (r > 0) { rs += r; rn += 1; }
        hd_pmap_lookup_radius(j->lk[w], 1);
    }
    if (rn > 0) e->gcell = GCELLF * rs / rn;
    return HD_OK;
}

/* -stats: the counts of every worker, the points group lookups searched
 * alone, the page cache's reads */
static void pm_stats(void *ctx, FILE *f)
{
    const pmest *e = ctx;
    const rcjob *j = &e->j;
    pmcount t = {0};
    uint64_t alone = 0, reads = 0, peak = 0;
    for (int w = 0; w < e->nth; w++) {
        const pmcount *k = &j->cnt[w];
        t.rays += k->rays;
        t.points += k->points;
        t.lookups += k->lookups;
        t.groups += k->groups;
        t.gathers += k->gathers;
        t.analytic += k->analytic;
        alone += hd_pmap_lookup_misses(j->lk[w]);
    }
    hd_pmap_cache_stats(j->m, &reads, &peak);
    fprintf(f, "%s: stats: photon gather (-ap %s, %u neighbours): %llu rays, %llu lookup points", hd_progname(),
            j->po->file, e->lo.k, (unsigned long long)t.rays, (unsigned long long)t.points);
    if (j->c->o.ab >= 0)
        fprintf(f, "; %llu final gathers of %d rays", (unsigned long long)t.gathers, j->c->o.ad);
    else
        fprintf(f, "; %llu irradiance lookups (%llu group lookups, %llu points searched alone)",
                (unsigned long long)t.lookups, (unsigned long long)t.groups, (unsigned long long)alone);
    fprintf(f, "; %llu records with analytic terms; %llu page reads, page cache peak %llu kB\n",
            (unsigned long long)t.analytic, (unsigned long long)reads, (unsigned long long)(peak + 1023) / 1024);
}

/* Records per batch within HD_PMAP_RC_BATCH_BYTES (or $HELIODON_RC_BATCH_MB): per record the driver's
 * rays and spool block (up to 12 bytes a column) and, at -ab < 0, the
 * primary hits, lookup points, groups and values of every worker and the
 * picture columns (-fc) or the record (otherwise); no more than nout
 * records when the run's size is known. */
size_t hd_pmap_rc_batch(const hd_contrib *c, const hd_rcontrib_opts *o, int nth, int maxbins, uint64_t nout)
{
    size_t per = (size_t)(o->accum > 0 ? o->accum : 1), nc = (size_t)c->ncols, pts = per * HD_PMPRIM_PTS;
    size_t b = per * (2 * sizeof(hd_vec3) + sizeof(hd_pmprim)) + 12 * nc;
    if (c->o.ab < 0) {
        b += pts * (sizeof(uint32_t) + 2 * sizeof(size_t) + 2 * sizeof(hd_vec3) + 3 * sizeof(double)) + 2 * per;
        b += (size_t)nth * pts * 3 * sizeof(double);
    }
    b += o->fout == 'c' && c->o.ab < 0 ? (size_t)nth * 3 * sizeof(double) * (size_t)maxbins : 3 * nc * sizeof(double);
    const char *ev = getenv("HELIODON_RC_BATCH_MB");   /* rcontrib.1: the budget in MB */
    double mb = ev && *ev ? atof(ev) : 0;
    size_t budget = mb > 0 && mb < 1e6 ? (size_t)(mb * 1048576.0) : HD_PMAP_RC_BATCH_BYTES;
    size_t batch = budget / b;
    if (o->accum > 0 && nout > 0 && batch > nout) batch = (size_t)nout;
    if (batch > (size_t)1 << 24) batch = (size_t)1 << 24;   /* point ids stay 32-bit */
    return batch < 16 ? 16 : batch;
}

/* The arrays of batches of up to `batch` records (freed first). */
static hd_status pm_batch_alloc(pmest *e, size_t batch)
{
    rcjob *j = &e->j;
    const hd_contrib *c = j->c;
    int nth = e->nth, per = j->o->accum > 0 ? j->o->accum : 1;
    pm_batch_free(e);
    e->batch = batch;
    size_t nray = batch * (size_t)per;
    j->gpp = hd_malloc_array(nray, sizeof *j->gpp);
    if (!j->gpp) return HD_ERR_NOMEM;
    pm_prefault(j->gpp, nray * sizeof *j->gpp);   /* written in full by every batch */
    j->us = 3 * (size_t)c->ncols;
    j->cs = 3;
    if (c->o.ab < 0) {
        size_t nid = nray * HD_PMPRIM_PTS;
        j->gid = hd_malloc_array(nid, sizeof *j->gid);
        j->gstart = hd_malloc_array(nid + 1, sizeof *j->gstart);
        j->gord = hd_malloc_array(nid + 1, sizeof *j->gord);
        j->gpt = hd_malloc_array(nid, sizeof *j->gpt);
        j->gn = hd_malloc_array(nid, sizeof *j->gn);
        j->pnpt = hd_malloc(nray);
        j->pnana = hd_malloc(nray);
        j->pf = hd_malloc_array(nid, 3 * sizeof(double));
        j->gval = hd_calloc((size_t)nth, sizeof *j->gval);
        if (!j->gid || !j->gstart || !j->gord || !j->gpt || !j->gn || !j->pnpt || !j->pnana || !j->pf || !j->gval)
            return HD_ERR_NOMEM;
        for (int w = 0; w < nth; w++)
            if (!(j->gval[w] = hd_malloc_array(nid + GROUP_MAX, 3 * sizeof(double)))) return HD_ERR_NOMEM;
        if (j->o->fout == 'c') {   /* column-major pictures: no record buffer */
            j->us = 3;
            j->cs = 3 * batch;
            j->colbuf = hd_calloc((size_t)nth, sizeof *j->colbuf);
            if (!j->colbuf) return HD_ERR_NOMEM;
            for (int w = 0; w < nth; w++)
                if (!(j->colbuf[w] = hd_malloc_array(3 * batch * (size_t)e->maxbins, sizeof(double)))) return HD_ERR_NOMEM;
        }
    }
    return HD_OK;
}

/* -ab < 0, after the first batch: whether the page cache evicted pages in
 * it (the pages of all sources near one batch's points do not fit: each
 * later batch would decode its pages again); then the driver's batches grow
 * to batch_big, here reallocated. */
static int pm_evicted(void *ctx)
{
    const pmest *e = ctx;
    return hd_pmap_cache_evictions(e->j.m) > e->evict0;
}

static hd_status pm_grow(void *ctx)
{
    pmest *e = ctx;
    return pm_batch_alloc(e, e->batch_big);
}

static hd_status pm_setup(pmest *e, const hd_contrib *c, const hd_rcontrib_opts *o)
{
    rcjob *j = &e->j;
    const hd_rc_pmap_opts *po = &o->pm;
    hd_status st = hd_pmap_open(&j->m, po->file, po->cache);
    if (st) return st;
    const hd_pmap_info *I = e->I = hd_pmap_get_info(j->m);
    if (!(j->mods = hd_calloc((size_t)c->nmods, sizeof *j->mods))) return HD_ERR_NOMEM;
    e->maxbins = 1;
    for (int mi = 0; mi < c->nmods; mi++) {
        j->mods[mi].src = hd_calloc(I->nsources ? I->nsources : 1, sizeof(uint32_t));
        if (!j->mods[mi].src) return HD_ERR_NOMEM;
        for (uint32_t s = 0; s < I->nsources; s++)
            if (!strcmp(hd_pmap_get_source(j->m, s)->modifier, c->mods[mi].name)) j->mods[mi].src[j->mods[mi].nsrc++] = s;
        if (!j->mods[mi].nsrc)
            return hd_fail(HD_ERR_USAGE, "%s: modifier %s is not a light source of the photon map", po->file,
                           c->mods[mi].name);
        if (c->mods[mi].bin.nbins > e->maxbins) e->maxbins = c->mods[mi].bin.nbins;
    }
    double bw = po->bw > 0 ? po->bw : 40;
    if (!(po->bw > 0)) hd_warn("-ap %s: no bandwidth given, using 40", po->file);
    if (po->bw2 > 0) hd_warn("-ap second bandwidth %g ignored: heliodon uses per-source neighbours", po->bw2);
    if (po->ac > 0) hd_warn("-ac %g ignored: the page size is fixed when the map is built (mkpmap -apZ)", po->ac);
    hd_pmap_lookup_opts_init(&e->lo);
    /* the bandwidth is shared by the map's sources that stored photons, whichever of them this run
     * asks for (-M), as Radiance's lookup shares it: a source's DC does not depend on the others
     * in the run, so a run split by modifiers gives the pictures of the whole run */
    uint32_t nactive = 0;
    for (uint32_t s = 0; s < I->nsources; s++)
        if (hd_pmap_get_source(j->m, s)->stored) nactive++;
    uint32_t k = (uint32_t)ceil(bw / (nactive ? nactive : 1));
    e->lo.k = k < 2 ? 2 : k;
    /* default search limit: 0.5 % of the photon map's extent (lookups far
     * from any photon of a source, e.g. on the distant ground, would
     * otherwise scan every page of that source) */
    e->lo.max_radius = po->am > 0 ? po->am : 0.005 * I->size;
    e->lo.direct_scene = po->exact_direct ? c->ts : NULL;
    int nth = e->nth;
    j->lk = hd_calloc((size_t)nth, sizeof *j->lk);
    j->tmp = hd_calloc((size_t)nth, sizeof *j->tmp);
    j->cnt = hd_calloc((size_t)nth, sizeof *j->cnt);
    if (!j->lk || !j->tmp || !j->cnt) return HD_ERR_NOMEM;
    for (int w = 0; w < nth; w++) {
        if ((st = hd_pmap_lookup_create(j->m, &e->lo, &j->lk[w]))) return st;
        j->tmp[w] = hd_malloc_array((size_t)e->maxbins * 3, sizeof(double));
        if (!j->tmp[w]) return HD_ERR_NOMEM;
    }
    /* rays in batches of up to 16384 records (fewer when records are long, so that
     * the batch stays within ~64 MB); when the first batch shows that the page
     * cache cannot hold the pages of all sources near one batch's points (every
     * batch would decode them again), batches as large as the memory budget
     * allows (hd_pmap_rc_batch) */
    size_t rlen = 3 * (size_t)c->ncols, batch = (size_t)(8u << 20) / (rlen ? rlen : 1);
    if (batch > 16384) batch = 16384;
    if (batch < 16) batch = 16;
    uint64_t nout = o->ranged ? o->rec_count : hd_rcontrib_nrecords(o);
    e->batch_big = c->o.ab < 0 ? hd_pmap_rc_batch(c, o, nth, e->maxbins, nout) : 0;
    if (e->batch_big && batch > e->batch_big) batch = e->batch_big;   /* a smaller HELIODON_RC_BATCH_MB */
    if ((st = pm_batch_alloc(e, batch))) return st;
    e->evict0 = hd_pmap_cache_evictions(j->m);
    return HD_OK;
}

hd_status hd_pmap_rc_estimator(const hd_contrib *c, const hd_rcontrib_opts *o, hd_rc_estimator *est)
{
    pmest *e = hd_calloc(1, sizeof *e);
    if (!e) return HD_ERR_NOMEM;
    e->j.c = c;
    e->j.o = o;
    e->j.po = &o->pm;
    e->nth = hd_resolve_threads(o->nthreads);
    hd_status st = pm_setup(e, c, o);
    if (st) { pm_free(e); return st; }
    est->ctx = e;
    est->c0_per = 1;
    est->batch = e->batch;
    est->batch_big = e->batch_big;
    est->colmajor = e->j.colbuf != NULL;
    est->run = pm_run;
    est->keys = c->o.ab < 0 ? pm_keys : NULL;
    est->evicted = c->o.ab < 0 ? pm_evicted : NULL;
    est->grow = pm_grow;
    est->free = pm_free;
    est->stats = pm_stats;
    return HD_OK;
}
